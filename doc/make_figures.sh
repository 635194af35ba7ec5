#!/usr/bin/env bash
# Regenerate the figures of doc/: Figure 3 of the paper (examples/seed.nml, the three methods
# side by side), the work-precision diagrams of examples/seed_study.nml and
# examples/chain4_study.nml, the forced-response curves of examples/seed_frc.nml and
# examples/designer_damper.nml and the
# robustness maps of examples/seed_robustness.nml, release build. Writes doc/*.png; the runs'
# files stay in out/.
set -euo pipefail
cd "$(dirname "$0")/.."
fpm build --profile release >/dev/null
run() { fpm run --profile release -- "$1"; }
run examples/seed.nml
gnuplot -e "dir='out/seed'" examples/figure3.gp
cp out/seed/figure3.png doc/figure3.png
for c in seed_study chain4_study; do
    run "examples/$c.nml"
    gnuplot -e "dir='out/$c'" examples/work_precision.gp
    cp "out/$c/work_precision.png" "doc/work_precision_${c%_study}.png"
done
run examples/seed_frc.nml
cp out/seed_frc/frc.png doc/frc_seed.png
run examples/designer_damper.nml
cp out/designer_damper/frc.png doc/frc_designer.png
run examples/seed_robustness.nml
cp out/seed_robustness/robustness_cold.png doc/robustness_cold.png
cp out/seed_robustness/robustness_warm.png doc/robustness_warm.png
# the convergence table of doc/convergence.md ("When the first attempt fails"): 14 cases and
# the impact case at H = 10..150 (about 1.5 min on 2 cores; iwan.nml is left out, see there)
fpm run --example bench_convergence --profile release -- \
    $(ls bench/convergence/*.nml | grep -v iwan) > doc/convergence_table.txt
echo "wrote doc/figure3.png doc/work_precision_seed.png doc/work_precision_chain4.png" \
     "doc/frc_seed.png doc/frc_designer.png doc/robustness_cold.png doc/robustness_warm.png" \
     "doc/convergence_table.txt"
