#!/usr/bin/env bash
# Whole-process wall time of a family of forced-response curves (examples/damper_family.nml:
# 10 normal loads) with OMP_NUM_THREADS = 1 and 2, the two run in turn N times (default 3)
# so that the machine's noise falls on both alike; release build. Prints each run and the
# medians, and the speed-up of the curves traced in parallel.
# Usage: bench/family.sh [N]
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-3}
fpm build --profile release >/dev/null
exe=$(fpm run --profile release --runner echo 2>/dev/null | tail -n 1)
one=()
two=()
run() {   # $1: threads; prints the wall seconds
    local t0 t1
    t0=$(date +%s.%N)
    OMP_NUM_THREADS=$1 "$exe" examples/damper_family.nml >/dev/null 2>&1 || true
    t1=$(date +%s.%N)
    echo "$t1 - $t0" | bc -l
}
for ((i = 1; i <= n; i++)); do
    a=$(run 1)
    b=$(run 2)
    one+=("$a")
    two+=("$b")
    printf 'run %d: 1 thread %.2f s, 2 threads %.2f s\n' "$i" "$a" "$b"
done
median() { printf '%s\n' "$@" | sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }
m1=$(median "${one[@]}")
m2=$(median "${two[@]}")
printf 'median: 1 thread %.2f s, 2 threads %.2f s, speed-up %.2f\n' "$m1" "$m2" \
    "$(echo "$m1 / $m2" | bc -l)"
