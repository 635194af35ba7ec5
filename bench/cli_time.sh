#!/usr/bin/env bash
# Whole-process wall time of `stickslip examples/seed.nml` solved by the weighted residual alone
# (&run method = 'hbm'; the example runs all three methods), release build: median of N runs.
#
# Usage: bench/cli_time.sh [N] [BASELINE]     (N default 21)
#
# Runs, in turn so that the machine's noise falls on all alike:
#   - an empty Fortran program linked to the same libraries (the floor: process start and
#     dynamic linking),
#   - the CLI of this tree,
#   - with BASELINE (a commit), the CLI of that commit, built once under
#     build/cli-baseline-<commit>/ from `git archive` (bench/bench_cli.f90 is copied in).
# Then the breakdown of one run by bench_cli (read, solve, truncation estimate, hbm.csv,
# coefficients.csv; medians of N processes) for each build, and FFT planning and execution
# costs in a fresh process (bench_cli fft).
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-21}
baseline=${2:-}
root=$(pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

build_tree() {   # $1: tree; prints the paths of its CLI and bench_cli executables
    (cd "$1" && fpm build --profile release >/dev/null 2>&1 &&
        fpm run --profile release --runner echo 2>/dev/null | tail -n 1 &&
        fpm run --profile release --example bench_cli --runner echo 2>/dev/null | tail -n 1)
}

mapfile -t cur < <(build_tree "$root")
cur=("$root/${cur[0]}" "$root/${cur[1]}")
if [[ -n "$baseline" ]]; then
    sha=$(git rev-parse --short "$baseline")
    base_dir="$root/build/cli-baseline-$sha"
    if [[ ! -d "$base_dir" ]]; then
        mkdir -p "$base_dir"
        git archive "$sha" | tar -x -C "$base_dir"
        cp bench/bench_cli.f90 "$base_dir/bench/"
        if ! grep -q 'name = "bench_cli"' "$base_dir/fpm.toml"; then
            printf '\n[[example]]\nname = "bench_cli"\nsource-dir = "bench"\nmain = "bench_cli.f90"\n' \
                >> "$base_dir/fpm.toml"
        fi
    fi
    mapfile -t base < <(build_tree "$base_dir")
    base=("$base_dir/${base[0]}" "$base_dir/${base[1]}")
fi

# the floor: an empty program linked like the CLI (fpm.toml's link list, no --as-needed)
libs=$(sed -n 's/^link *= *\[\(.*\)\]/\1/p' fpm.toml | tr -d '",' )
printf 'program empty\nend program empty\n' > "$work/empty.f90"
gfortran -O2 "$work/empty.f90" -o "$work/empty" -Wl,--no-as-needed $(printf -- '-l%s ' $libs)

sed -e "s|directory *= *'[^']*'|directory = '$work/seed'|" -e "s|method *= *'all'|method = 'hbm'|" \
    examples/seed.nml > "$work/seed.nml"
mkdir -p "$work/parts"

now_us() { local t=${EPOCHREALTIME/./}; echo "$t"; }
declare -A times
labels=(empty current)
[[ -n "$baseline" ]] && labels+=(baseline)
for _ in $(seq "$n"); do
    for label in "${labels[@]}"; do
        case $label in
            empty) cmd=("$work/empty") ;;
            current) cmd=("${cur[0]}" --quiet "$work/seed.nml") ;;
            baseline) cmd=("${base[0]}" --quiet "$work/seed.nml") ;;
        esac
        t0=$(now_us)
        "${cmd[@]}"
        t1=$(now_us)
        times[$label]+="$(( t1 - t0 )) "
    done
done
median() { tr ' ' '\n' | grep -v '^$' | sort -n | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
ms() { awk -v us="$1" 'BEGIN {printf "%.2f", us/1000}'; }
echo "stickslip examples/seed.nml (method hbm), wall time, median of $n runs (release build, $(nproc) cores):"
for label in "${labels[@]}"; do
    m=$(echo "${times[$label]}" | median)
    eval "med_$label=$m"
    case $label in
        empty) echo "  empty program linked to the same libraries: $(ms "$m") ms" ;;
        current) echo "  this tree:                                 $(ms "$m") ms" ;;
        baseline) echo "  baseline $sha:                        $(ms "$m") ms" ;;
    esac
done
if [[ -n "$baseline" ]]; then
    awk -v b="$med_baseline" -v c="$med_current" -v e="$med_empty" 'BEGIN {
        printf "  baseline / this tree: %.2fx; above the floor: %.2f -> %.2f ms\n", b/c, (b-e)/1000, (c-e)/1000 }'
fi

# breakdown: one cold run per process, medians of each column
breakdown() {   # $1: bench_cli executable
    local rows=()
    for _ in $(seq "$n"); do
        rows+=("$("$1" parts "$work/seed.nml" "$work/parts")")
    done
    printf '%s\n' "${rows[@]}" | awk '
        { for (i = 2; i <= NF; i++) v[i, NR] = $i; nf = NF; nr = NR }
        END {
            split("read solve estimate hbm.csv coefficients.csv", name, " ")
            for (i = 2; i <= nf; i++) {
                for (r = 1; r <= nr; r++) {      # insertion sort (POSIX awk has no asort)
                    x = v[i, r]
                    for (j = r - 1; j >= 1 && col[j] > x; j--) col[j + 1] = col[j]
                    col[j + 1] = x
                }
                printf "  %s %.2f", name[i - 1], col[int((nr + 1) / 2)]
            }
            printf " (ms)\n"
        }'
}
echo "one run, by part (bench_cli parts; median of $n processes):"
echo "  this tree:"
breakdown "${cur[1]}"
if [[ -n "$baseline" ]]; then
    echo "  baseline $sha:"
    breakdown "${base[1]}"
fi
echo "FFT in a fresh process (bench_cli fft): first 1024-point set-up, 4096-point set-up,"
echo "a second 1024-point init, one 1024-point forward transform (median of 2001) [us]:"
echo "  this tree:     $("${cur[1]}" fft | cut -d' ' -f2-)"
if [[ -n "$baseline" ]]; then
    echo "  baseline $sha: $("${base[1]}" fft | cut -d' ' -f2-)"
fi
