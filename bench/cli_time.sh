#!/usr/bin/env bash
# Whole-process wall time of `stickslip examples/seed.nml` solved by the weighted residual alone
# (&run method = 'hbm'; the example runs all three methods), release build: median of N runs.
# Usage: bench/cli_time.sh [N]   (default 21)
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-21}
fpm build --profile release >/dev/null
exe=$(fpm run --profile release --runner echo 2>/dev/null | tail -n 1)
out=$(mktemp -d)
sed -e "s|directory *= *'[^']*'|directory = '$out/seed'|" -e "s|method *= *'all'|method = 'hbm'|" \
    examples/seed.nml > "$out/seed.nml"
times=()
for _ in $(seq "$n"); do
    t0=$(date +%s%N)
    "$exe" --quiet "$out/seed.nml"
    t1=$(date +%s%N)
    times+=($(( (t1 - t0) / 1000 )))
done
med=$(printf '%s\n' "${times[@]}" | sort -n | sed -n "$(( (n + 1) / 2 ))p")
echo "stickslip examples/seed.nml (method hbm): median wall time $(( med / 1000 )).$(( (med % 1000) / 100 )) ms over $n runs (release build, $(nproc) cores)"
rm -rf "$out"
