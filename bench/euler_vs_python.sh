#!/usr/bin/env bash
# Implicit Euler on the seed case, 1000 steps per period, from rest until periodic
# (examples/seed_euler.nml with steps_per_period = 1000, tol 1e-8): the whole
# `stickslip` process (release build; read, integrate, write euler.csv and the summary)
# against the plain Python stepper of bench/euler_python.py (same scheme), side by side.
# Prints the medians (N CLI runs, P Python runs), the ratio, and checks that both found
# the periodic state after the same number of periods.
# Usage: bench/euler_vs_python.sh [N [P]]   (defaults 11 and 3)
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-11}
p=${2:-3}
fpm build --profile release >/dev/null
exe=$(fpm run --profile release --runner echo 2>/dev/null | tail -n 1)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
sed -e "s|directory *= *'[^']*'|directory = '$out/seed'|" \
    -e "s|steps_per_period *= *[0-9]*|steps_per_period = 1000|" \
    examples/seed_euler.nml > "$out/seed.nml"
median() { sort -g | sed -n "$(( ($1 + 1) / 2 ))p"; }
cli=()
for _ in $(seq "$n"); do
    t0=$(date +%s%N)
    "$exe" --quiet "$out/seed.nml"
    t1=$(date +%s%N)
    cli+=("$(( (t1 - t0) / 1000 ))")
done
cli_us=$(printf '%s\n' "${cli[@]}" | median "$n")
periods=$(sed -n 's/^ *periods *= *\([0-9]*\).*/\1/p' "$out/seed/summary.nml" | head -n 1)
step_s=$(sed -n 's/^ *euler_seconds *= *\([-0-9.Ee+]*\).*/\1/p' "$out/seed/summary.nml" | head -n 1)
py=()
py_step=()
for _ in $(seq "$p"); do
    t0=$(date +%s%N)
    line=$(python3 bench/euler_python.py 1000 1e-8)
    line=${line%%$'\n'*}
    t1=$(date +%s%N)
    py+=("$(( (t1 - t0) / 1000 ))")
    py_step+=("$(echo "$line" | awk '{print $6}')")
    py_periods=$(echo "$line" | awk '{print $2}')
done
py_us=$(printf '%s\n' "${py[@]}" | median "$p")
py_step_s=$(printf '%s\n' "${py_step[@]}" | median "$p")
awk -v c="$cli_us" -v q="$py_us" -v s="$step_s" -v qs="$py_step_s" -v n="$n" -v p="$p" \
    -v per="$periods" -v pper="$py_periods" -v cores="$(getconf _NPROCESSORS_ONLN)" 'BEGIN {
    printf "seed, 1000 steps per period, from rest until periodic (%s periods; Python: %s)\n", per, pper
    printf "  stickslip (whole process, release build): %8.1f ms  median of %d (stepping %.1f ms, last run)\n", c / 1000, n, s * 1000
    printf "  plain Python stepper (whole process):     %8.1f ms  median of %d (stepping %.1f ms)\n", q / 1000, p, qs * 1000
    printf "  ratio Python / stickslip: %.1fx whole process, %.1fx stepping alone (%d cores)\n", q / c, qs / s, cores
}'
if [ "$periods" != "$py_periods" ]; then
    echo "MISMATCH: stickslip needed $periods periods, Python $py_periods" >&2
    exit 1
fi
