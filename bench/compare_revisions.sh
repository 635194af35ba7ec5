#!/bin/sh
# Whole-process timings of benchmark programs in two revisions, run in turn (A B A B ...)
# on the same machine in the same script: the median CPU time [s] of each and the ratio
# A/B. A is this working tree, B a git revision built in a temporary worktree.
#
#   bench/compare_revisions.sh REV [RUNS] [BENCH ...]
#
# REV: the revision to compare against (e.g. 2ed6a59, the tree before issue 23);
# RUNS: runs of each program per revision (default 3, one warm-up run each not counted);
# BENCH: programs under bench/ (default bench_hbm bench_euler bench_frc bench_contacts).
# Both are built with `fpm build --profile release`. Needs git, fpm and /usr/bin/time.
set -eu
rev=${1:?usage: bench/compare_revisions.sh REV [RUNS] [BENCH ...]}
runs=${2:-3}
[ $# -ge 2 ] && shift 2 || shift 1
benches=${*:-bench_hbm bench_euler bench_frc bench_contacts}
here=$(cd "$(dirname "$0")/.." && pwd)
tmp=$(mktemp -d)
trap 'git -C "$here" worktree remove --force "$tmp/b" >/dev/null 2>&1 || true; rm -rf "$tmp"' EXIT
git -C "$here" worktree add --detach "$tmp/b" "$rev" >/dev/null 2>&1
for tree in "$here" "$tmp/b"; do
    (cd "$tree" && fpm build --profile release >/dev/null)
done
# the path of a built example program in a tree
prog() {
    find "$1/build" -path "*/example/$2" -type f | head -n 1
}
# CPU seconds (user + sys) of one run
cpu() {
    (cd "$1" && /usr/bin/time -f "%U %S" -o "$tmp/t" "$2" >/dev/null 2>&1)
    awk '{ print $1 + $2 }' "$tmp/t"
}
median() {
    sort -g | awk '{ a[NR] = $1 } END { print (NR % 2) ? a[(NR + 1)/2] : (a[NR/2] + a[NR/2 + 1])/2 }'
}
echo "A = $(git -C "$here" rev-parse --short HEAD) (working tree), B = $rev; $runs runs each, release profile"
printf '%-16s %10s %10s %8s\n' program "A cpu [s]" "B cpu [s]" A/B
for b in $benches; do
    pa=$(prog "$here" "$b")
    pb=$(prog "$tmp/b" "$b")
    if [ -z "$pa" ] || [ -z "$pb" ]; then
        echo "$b: not built in both revisions" >&2
        continue
    fi
    cpu "$here" "$pa" > /dev/null
    cpu "$tmp/b" "$pb" > /dev/null
    : > "$tmp/a.txt"
    : > "$tmp/b.txt"
    i=0
    while [ "$i" -lt "$runs" ]; do
        cpu "$here" "$pa" >> "$tmp/a.txt"
        cpu "$tmp/b" "$pb" >> "$tmp/b.txt"
        i=$((i + 1))
    done
    ma=$(median < "$tmp/a.txt")
    mb=$(median < "$tmp/b.txt")
    printf '%-16s %10.2f %10.2f %8.3f\n' "$b" "$ma" "$mb" "$(echo "$ma $mb" | awk '{ print $1/$2 }')"
done
