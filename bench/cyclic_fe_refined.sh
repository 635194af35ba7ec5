#!/usr/bin/env bash
# The CalculiX bladed-disk sector at FE sizes of 10^4 DOFs and more: make_sector.py
# --refine K (each cell of examples/calculix_sector's mesh split in K^3) writes the sector
# and its case (Craig-Bampton keeping the cyclic faces, each face by 12 interface modes,
# the platforms rubbing on the next sector's, a sweep of about 110 points across the axial
# family of nodal diameter 3); each case runs once with the reduction cache off, with and
# without the reduction's error estimate (&reduction error_estimate). Prints per K: DOFs,
# face DOFs, the generation's seconds (ccx and the script), and per run the wall time, the
# reduction's phases (stderr), reduction_seconds (reduction and interface modes),
# reduction_error_seconds (the estimate), the error per nodal diameter, points and CPU ms a
# point of the sweep. Needs ccx (calculix-ccx). Release build.
# Usage: bench/cyclic_fe_refined.sh [K ...]   (default: 1 2 3; K = 3 is 33k DOFs, about
#        1.5 min to generate and 1.5 min to run on the 2-core VM; K = 4, 76k DOFs, 4.5
#        and 5.5 min)
set -euo pipefail
cd "$(dirname "$0")/.."
refines=("$@")
[ ${#refines[@]} -eq 0 ] && refines=(1 2 3)
if ! command -v ccx >/dev/null; then
    echo "cyclic_fe_refined.sh: needs ccx (apt-get install calculix-ccx)" >&2
    exit 1
fi
fpm build --profile release >/dev/null
exe=$(fpm run --profile release --runner echo 2>/dev/null | tail -n 1)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
value() { grep -m1 "^  $2 = " "$1/summary.nml" | sed 's/.*= *//' || true; }
# a number in 3 digits, or '-' when the summary has none (not measured)
sci() { if [ -n "$1" ]; then awk -v x="$1" 'BEGIN { printf "%.2e", x }'; else echo -; fi; }
for k in "${refines[@]}"; do
    dir="$work/r$k"
    t0=$(date +%s.%N)
    python3 examples/calculix_sector/make_sector.py --refine "$k" --out "$dir" > "$dir.gen"
    t1=$(date +%s.%N)
    dofs=$(sed -n 's/.* \([0-9]*\) DOFs (K:.*/\1/p' "$dir.gen")
    pairs=$(sed -n 's/.*node pairs, \([0-9]*\) DOF pairs.*/\1/p' "$dir.gen")
    printf 'K = %d: %s DOFs, %s DOFs a face; generated in %.1f s\n' "$k" "$dofs" "$pairs" \
        "$(awk -v a="$t0" -v b="$t1" 'BEGIN { print b - a }')"
    for estimate in T F; do
        name="run_$estimate"
        settings="interface_modes = 12, cache = 'off', error_estimate = $estimate"
        sed -e "s|^  directory = .*|  directory = '$dir/$name'|" \
            -e "s|^  interface_modes = 12 .*|  $settings|" "$dir/case.nml" > "$dir/$name.nml"
        t0=$(date +%s.%N)
        "$exe" "$dir/$name.nml" > "$dir/$name.out" 2> "$dir/$name.err"
        t1=$(date +%s.%N)
        out="$dir/$name"
        points=$(value "$out" points)
        cpu=$(value "$out" cpu_seconds)
        printf '  error_estimate = %s: wall %.1f s; reduction %.1f s, estimate %.1f s (%s); ' \
            "$estimate" "$(awk -v a="$t0" -v b="$t1" 'BEGIN { print b - a }')" \
            "$(value "$out" reduction_seconds)" \
            "$(awk -v e="$(value "$out" reduction_error_seconds)" \
                'BEGIN { print (e < 0) ? 0 : e }')" \
            "$(value "$out" reduction_error_method | tr -d "'")"
        printf 'reduced %s DOFs; error nd3 %s, nd9 %s; %s points, %.2f ms a point\n' \
            "$(value "$out" reduction_interface_dof)" \
            "$(sci "$(value "$out" reduction_error_nd3)")" \
            "$(sci "$(value "$out" reduction_error_nd9)")" "$points" \
            "$(awk -v c="$cpu" -v p="$points" 'BEGIN { print 1000 * c / p }')"
        sed 's/^stickslip: /    /' "$dir/$name.err" | grep "reduction:" || true
    done
done
