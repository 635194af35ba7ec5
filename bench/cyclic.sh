#!/usr/bin/env bash
# Cost per sweep point on one sector against the assembled disk (issue 27): the lumped
# 24-sector disk of examples/bladed_disk.nml (tip shrouds rubbing on the next blade, EO 3)
# swept over omega 1.5..4 without stability or truncation estimate, &cyclic model = 'sector'
# and 'disk', the two in turn N times (default 3), release build. Prints each run's points
# and CPU seconds (summary.nml), the medians per point and their ratio.
# Usage: bench/cyclic.sh [N]
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-3}
fpm build --profile release >/dev/null
exe=$(fpm run --profile release --runner echo 2>/dev/null | tail -n 1)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for model in sector disk; do
    sed -e "s|^&cyclic .*|\&cyclic   sectors = 24, engine_order = 3, left_dofs = 1, right_dofs = 3, next_dof = 2, model = '$model' /|" \
        -e "s|^&run .*|\&run method = 'sweep' /|" \
        -e "s|^&output .*|\&output directory = '$work/$model' /|" \
        examples/bladed_disk.nml > "$work/$model.nml"
    echo "&sweep start = 1.5, stop = 4.0, stability = .false., truncation = .false., plot = .false. /" \
        >> "$work/$model.nml"
done
value() { grep -m1 "^  $2 = " "$1/summary.nml" | sed 's/.*= *//'; }
declare -A per
for ((i = 1; i <= n; i++)); do
    for model in sector disk; do
        "$exe" "$work/$model.nml" >/dev/null 2>&1
        p=$(value "$work/$model" points)
        c=$(value "$work/$model" cpu_seconds)
        # (Fortran's E exponents: awk reads them, bc does not)
        ms_point=$(awk -v c="$c" -v p="$p" 'BEGIN { printf "%.6f", 1000 * c / p }')
        per[$model]+="$ms_point "
        printf 'run %d %-6s: %s points, %.3f s CPU, %.3f ms a point\n' "$i" "$model" "$p" \
            "$(awk -v c="$c" 'BEGIN { print c + 0 }')" "$ms_point"
    done
done
median() { printf '%s\n' $1 | sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }
ms=$(median "${per[sector]}")
md=$(median "${per[disk]}")
printf 'median per point: sector %.3f ms, disk %.3f ms, disk / sector %.0f\n' "$ms" "$md" \
    "$(awk -v a="$md" -v b="$ms" 'BEGIN { print a / b }')"
