#!/usr/bin/env bash
# Implicit Euler on the seed case, 1000 steps per period, from rest until periodic
# (examples/seed_euler.nml with steps_per_period = 1000, tol 1e-8): the whole
# `stickslip` process (release build; read, integrate, write euler.csv and the summary)
# against the plain Python stepper of bench/euler_python.py (same scheme), side by side.
# Prints the medians of wall time and of CPU time (task-clock: on a shared machine the
# fairer one) over N CLI runs and P Python runs, the ratios, the stepping time alone, and
# checks that both found the periodic state after the same number of periods.
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
# run CMD...: writes "wall_seconds cpu_seconds" of the process to $out/time (wall from the
# clock, CPU from perf stat's task-clock when perf works, else /usr/bin/time at 10 ms)
if perf stat -x, -e task-clock -o "$out/perf" true 2>/dev/null; then
    run() {
        local t0 t1
        t0=$(date +%s%N)
        perf stat -x, -e task-clock -o "$out/perf" "$@"
        t1=$(date +%s%N)
        awk -F, -v w="$(( t1 - t0 ))" '/task-clock/ {print w / 1e9, $1 / 1000, 0}' "$out/perf" > "$out/time"
    }
else
    run() { /usr/bin/time -o "$out/time" -f "%e %U %S" "$@"; }
fi
cli_wall=(); cli_cpu=()
for _ in $(seq "$n"); do
    # wall time of a bare run (perf's own start-up would count in a short process), then
    # the CPU time of a run under perf
    t0=$(date +%s%N)
    "$exe" --quiet "$out/seed.nml"
    t1=$(date +%s%N)
    cli_wall+=("$(awk -v w="$(( t1 - t0 ))" 'BEGIN {print w / 1e9}')")
    run "$exe" --quiet "$out/seed.nml"
    read -r e u s < "$out/time"
    cli_cpu+=("$(awk -v u="$u" -v s="$s" 'BEGIN {print u + s}')")
done
periods=$(sed -n 's/^ *periods *= *\([0-9]*\).*/\1/p' "$out/seed/summary.nml" | head -n 1)
step_s=$(sed -n 's/^ *euler_seconds *= *\([-0-9.Ee+]*\).*/\1/p' "$out/seed/summary.nml" | head -n 1)
py_wall=(); py_cpu=(); py_step=()
for _ in $(seq "$p"); do
    run python3 bench/euler_python.py 1000 1e-8 > "$out/py.txt"
    read -r e u s < "$out/time"
    py_wall+=("$e"); py_cpu+=("$(awk -v u="$u" -v s="$s" 'BEGIN {print u + s}')")
    line=$(head -n 1 "$out/py.txt")
    py_step+=("$(echo "$line" | awk '{print $6}')")
    py_periods=$(echo "$line" | awk '{print $2}')
done
cw=$(printf '%s\n' "${cli_wall[@]}" | median "$n")
cc=$(printf '%s\n' "${cli_cpu[@]}" | median "$n")
pw=$(printf '%s\n' "${py_wall[@]}" | median "$p")
pc=$(printf '%s\n' "${py_cpu[@]}" | median "$p")
ps=$(printf '%s\n' "${py_step[@]}" | median "$p")
awk -v cw="$cw" -v cc="$cc" -v pw="$pw" -v pc="$pc" -v s="$step_s" -v ps="$ps" -v n="$n" \
    -v p="$p" -v per="$periods" -v pper="$py_periods" \
    -v cores="$(getconf _NPROCESSORS_ONLN)" 'BEGIN {
    printf "seed, 1000 steps per period, from rest until periodic (%s periods; Python: %s)\n", per, pper
    printf "  stickslip (whole process, release build): wall %7.1f ms, CPU %7.1f ms  (median of %d; stepping %.1f ms wall, last run)\n", cw * 1000, cc * 1000, n, s * 1000
    printf "  plain Python stepper (whole process):     wall %7.1f ms, CPU %7.1f ms  (median of %d; stepping %.1f ms wall)\n", pw * 1000, pc * 1000, p, ps * 1000
    printf "  ratio Python / stickslip: %.1fx wall, %.1fx CPU, %.1fx stepping alone (%d cores)\n", pw / cw, pc / cc, ps / s, cores
}'
if [ "$periods" != "$py_periods" ]; then
    echo "MISMATCH: stickslip needed $periods periods, Python $py_periods" >&2
    exit 1
fi
