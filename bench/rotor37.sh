#!/usr/bin/env bash
# The NASA Rotor 37 blade benchmark of issue 25 (doc/benchmarks.md, "Rotor 37"): the
# forced-response curve with stability across the first mode of a real FE model that no one
# here wrote (61,098 DOFs, CalculiX deck in ../shared/models/rotor37), and the time of each
# phase. Release build.
#
#   bench/rotor37.sh [WORKDIR] [POINTS]    (default WORKDIR: a folder under /tmp, kept;
#                                           POINTS: 400, the curve's max_step = 130 / POINTS)
#
# The case: 1 N at node 1353 y (row 3854), 16 ground friction contacts along the tip chord
# (y rows of README's node list; mu = 1, normal load 0.01 N each: the tips slip at resonance
# and the peak about halves), stiffness-proportional damping beta = 2.04e-6 s, H = 15 odd
# harmonics, &sweep 1900 -> 2030 rad/s with stability, the default Craig-Bampton reduction
# and the default step control (no min_step). Units of the model: mm, t, s (N).
# The matrices are made once by the deck's make_matrices.sh (calculix-ccx, 1-2 minutes) and
# kept in WORKDIR; a second run of the script reuses them.
# Prints the phase table: wall time of the whole run, and from summary.nml reading the
# matrix files, the reduction, its error estimate (or the cache: a second run of the script
# finds out/reduction.cache and skips the three), the sweep and the stability's share, the
# number of points and the exit code.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
work=${1:-/tmp/stickslip-rotor37}
points=${2:-400}
deck="$root/../shared/models/rotor37"
mkdir -p "$work"
if [ ! -s "$work/blade_sti.mtx" ] || [ ! -s "$work/blade_mas.mtx" ]; then
    echo "making the matrices in $work (CalculiX)" >&2
    sh "$deck/make_matrices.sh" "$work" >&2
fi
fpm build --profile release >/dev/null
exe=$(fpm run --profile release --runner echo 2>/dev/null | tail -n 1)
case "$exe" in /*) ;; *) exe="$root/$exe" ;; esac
step=$(awk -v p="$points" 'BEGIN { printf "%.6g", 130.0 / p }')
cat > "$work/sweep.nml" <<EOF
! Rotor 37 blade (bench/rotor37.sh): 1 N at node 1353 y, 16 tip contacts in y
&system
  mass_file = 'blade_mas.mtx'
  stiffness_file = 'blade_sti.mtx'
  rayleigh_beta = 2.04e-6
/
&forcing omega = 1961.0, force_dof = 3854, force_amplitude = 1.0 /
&friction
  contact_dof = 2, 113, 13775, 116, 28097, 13781, 587, 28157, 125, 14261, 28190, 28193,
                14255, 7025, 27986, 569
  mu = 16*1.0
  normal_load = 16*0.01
/
&hbm harmonics = 15, odd_only = T /
&run method = 'sweep' /
&sweep start = 1900.0, stop = 2030.0, step = $step, max_step = $step, stability = T,
       resume = F, plot = F /
&output directory = 'out' /
EOF
cd "$work"
# a fresh output directory except the reduction cache (the second run's cache hit)
mkdir -p out
find out -mindepth 1 ! -name reduction.cache -delete
t0=$(date +%s.%N)
set +e
"$exe" sweep.nml > run.out 2> run.err
code=$?
set -e
t1=$(date +%s.%N)
get() { sed -n "s/^ *$1 = *//p" out/summary.nml 2>/dev/null | head -n 1; }
points_done=0
[ -s out/frc.csv ] && points_done=$(($(wc -l < out/frc.csv) - 1))
num() { v=$(get "$1"); echo "${v:-0}"; }
awk -v wall="$(echo "$t1 - $t0" | bc)" -v rd="$(num reduction_read_seconds)" \
    -v red="$(num reduction_seconds)" -v est="$(num reduction_error_seconds)" \
    -v cache="$(get reduction_cache)" -v cpu="$(num cpu_seconds)" \
    -v stab="$(num stability_cpu_seconds)" -v pts="$points_done" -v code="$code" 'BEGIN {
    printf "Rotor 37, %d points, exit %d, reduction cache %s\n", pts, code, cache
    printf "  reading the matrix files %8.1f s\n", rd
    printf "  reduction                %8.1f s\n", red
    printf "  error estimate           %8.1f s\n", est
    printf "  sweep without stability  %8.1f s CPU\n", cpu - stab
    printf "  stability                %8.1f s CPU (%.3f s per point)\n", stab, (pts > 0 ? stab / pts : 0)
    printf "  whole run                %8.1f s wall\n", wall
}'
grep -h "warning\|error" run.err | head -n 5 || true
