#!/usr/bin/env bash
# Regenerate the README figures: Figure 3 of the paper (examples/seed.nml, the three methods
# side by side) and the work-precision diagrams of examples/seed_study.nml and
# examples/chain4_study.nml, release build. Writes doc/*.png; the runs' files stay in out/.
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
echo "wrote doc/figure3.png doc/work_precision_seed.png doc/work_precision_chain4.png"
