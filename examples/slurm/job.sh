#!/usr/bin/env bash
# One stickslip case per SLURM array task (examples/slurm/README.md):
#     python3 make_cases.py template.nml params.csv      # prints N, writes cases/case_001.nml ...
#     sbatch --array=1-N job.sh
#     python3 collect.py results > campaign.csv          # after the array finished
# Task i runs the i-th case file of cases/ in sorted order (case_001.nml, ...) with OMP_NUM_THREADS = the task's CPUs (a
# robustness or work-precision study inside a case uses them). The task's exit code is
# stickslip's: 0 ok, 1 input, 2 numerical or untrusted answer, 3 I/O; it is also written to
# status/<case>.exit (STATUS=dir to change), where collect.py finds the cases that failed.
#SBATCH --job-name=stickslip
#SBATCH --array=1-6
#SBATCH --cpus-per-task=1
#SBATCH --time=00:30:00
#SBATCH --output=stickslip_%A_%a.log
set -euo pipefail
: "${SLURM_ARRAY_TASK_ID:?run it with sbatch --array=1-N (or set SLURM_ARRAY_TASK_ID)}"
export OMP_NUM_THREADS="${SLURM_CPUS_PER_TASK:-1}"
cases="${CASES:-cases}"                 # folder of make_cases.py's output
stickslip="${STICKSLIP:-stickslip}"     # the program (fpm install puts it in PREFIX/bin)
status="${STATUS:-status}"              # folder of the exit codes, one file per case
case_file=$(find "$cases" -maxdepth 1 -name '*.nml' | LC_ALL=C sort | sed -n "${SLURM_ARRAY_TASK_ID}p")
[ -n "$case_file" ] || { echo "job.sh: no case number $SLURM_ARRAY_TASK_ID in $cases/" >&2; exit 1; }
mkdir -p "$status"
code=0
"$stickslip" --quiet "$case_file" || code=$?
name=$(basename "$case_file" .nml)
echo "$code" > "$status/$name.exit.tmp" && mv "$status/$name.exit.tmp" "$status/$name.exit"
exit "$code"
