#!/usr/bin/env bash
# The CalculiX bladed-disk sector (examples/calculix_sector, 1662 DOFs, 24 sectors, EO 3,
# platforms rubbing on the next sector's): its Craig-Bampton reduction (no reduction cache,
# the error per nodal diameter measured) plus a sweep of about 400 points over the case's
# range (max_step 2.45 rad/s), stability off, twice: 'sector' keeps the cyclic faces' 144
# DOFs, 'sector12' describes each face by 12 interface modes (&reduction interface_modes,
# the example's setting); beside them the reduced
# CalculiX strip (examples/calculix_beam, one blade, contacts on the ground) swept likewise,
# for the cost per point. Release build, each run N times in turn (default 3); prints each
# run's wall time, reduction seconds, points and CPU seconds (summary.nml) and the medians.
# Usage: bench/cyclic_fe.sh [N]
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-3}
fpm build --profile release >/dev/null
exe=$(fpm run --profile release --runner echo 2>/dev/null | tail -n 1)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
root=$(pwd)
# a copy of a case: matrix files by absolute path, output in $work, no reduction cache, the
# sweep's step and stability replaced
copy() {
    local case=$1 name=$2 step=$3
    sed -e "s|_file = '|_file = '$root/$(dirname "$case")/|" \
        -e "s|directory = '[^']*'|directory = '$work/$name'|" \
        -e "s|^  max_step = .*|  max_step = $step|" \
        -e "s|stability = [TF]|stability = F|" \
        -e "/^&reduction/,/^\//d" "$case" > "$work/$name.nml"
    echo "&reduction method = 'craig-bampton', cache = 'off', interface_modes = $4 /" \
        >> "$work/$name.nml"
}
copy examples/calculix_sector/case.nml sector 2.45 0
copy examples/calculix_sector/case.nml sector12 2.45 12
# the strip's case: one &sweep line with max_step
sed -e "s|_file = '|_file = '$root/examples/calculix_beam/|" \
    -e "s|directory = '[^']*'|directory = '$work/strip'|" \
    -e "s|max_step = [0-9.]*|max_step = 0.375|" -e "s|stability = T|stability = F|" \
    examples/calculix_beam/case.nml > "$work/strip.nml"
echo "&reduction cache = 'off' /" >> "$work/strip.nml"
value() { grep -m1 "^  $2 = " "$1/summary.nml" | sed 's/.*= *//'; }
declare -A wall per red
for ((i = 1; i <= n; i++)); do
    for name in sector sector12 strip; do
        t0=$(date +%s.%N)
        "$exe" "$work/$name.nml" >/dev/null 2>&1
        t1=$(date +%s.%N)
        w=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.3f", b - a }')
        p=$(value "$work/$name" points)
        c=$(value "$work/$name" cpu_seconds)
        r=$(awk -v a="$(value "$work/$name" reduction_seconds)" \
                -v b="$(value "$work/$name" reduction_error_seconds)" \
                'BEGIN { printf "%.3f", a + b }')
        ms=$(awk -v c="$c" -v p="$p" 'BEGIN { printf "%.4f", 1000 * c / p }')
        wall[$name]+="$w "
        per[$name]+="$ms "
        red[$name]+="$r "
        printf 'run %d %-8s: wall %.2f s, reduction %.2f s, %s points, %.2f s CPU in the' \
            "$i" "$name" "$w" "$r" "$p" "$(awk -v c="$c" 'BEGIN { print c + 0 }')"
        printf ' sweep, %.2f ms a point\n' "$ms"
    done
done
median() { printf '%s\n' $1 | sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }
for name in sector sector12 strip; do
    printf 'median %-8s: wall %.2f s, reduction %.2f s, %.2f ms a point\n' "$name" \
        "$(median "${wall[$name]}")" "$(median "${red[$name]}")" "$(median "${per[$name]}")"
done
