# Work-precision diagram of a study (&run method = 'study'): error against the exact
# reference vs CPU seconds, log-log, one curve per method (the weighted residual: one per
# quadrature sample count), for the displacement (max error, worst DOF) and the friction
# force (RMS error solid, max error dashed, worst contact). Converged runs only.
# Writes <dir>/work_precision.png.
#   gnuplot -e "dir='out/seed_study'" examples/work_precision.gp
if (!exists("dir")) dir = 'out/seed_study'
f = dir.'/study.csv'
rows(m) = sprintf("< awk -F, 'NR > 1 && $4 == \"T\" && %s' %s", m, f)
samples = system(sprintf("awk -F, 'NR > 1 && $1 == \"hbm\" {print $3}' %s | sort -un | tr '\\n' ' '", f))

set terminal pngcairo size 1400,600 enhanced font ',11'
set output dir.'/work_precision.png'
set datafile separator ','
set logscale xy
set format x '10^{%L}'
set format y '10^{%L}'
set grid lc rgb '#dddddd'
set key bottom left box opaque
set xlabel 'CPU time per solve [s]'
set multiplot layout 1,2 title sprintf("%s: work-precision (error relative to the reference amplitude)", dir) noenhanced

set title 'displacement: max error, worst DOF'
set ylabel 'max |x - x_{ref}| / max |x_{ref}|'
plot for [i=1:words(samples)] rows(sprintf("$1 == \"hbm\" && $3 == %s", word(samples, i))) \
         u 5:8 w lp lw 2 pt 7 ps 0.8 lc i t sprintf('weighted residual, %s samples', word(samples, i)).(i == 1 ? ' (H labelled)' : ''), \
     rows(sprintf("$1 == \"hbm\" && $3 == %s", word(samples, 1))) \
         u 5:8:(sprintf('%d', $2)) w labels offset 0.9,0.6 font ',8' tc lt 1 notitle, \
     rows('$1 == "euler"') u 5:8 w lp lw 2 pt 5 ps 0.8 lc rgb '#d1495b' dt 2 t 'implicit Euler (steps/period labelled)', \
     rows('$1 == "euler"') u 5:8:(sprintf('%d', $2)) w labels offset 0,-0.8 font ',8' tc rgb '#d1495b' notitle

set title 'friction force: RMS error (solid), max error (dashed), worst contact'
set ylabel '|r - r_{ref}| / max |r_{ref}|'
plot for [i=1:words(samples)] rows(sprintf("$1 == \"hbm\" && $3 == %s", word(samples, i))) \
         u 5:13 w lp lw 2 pt 7 ps 0.8 lc i t sprintf('weighted residual, %s samples', word(samples, i)), \
     for [i=1:words(samples)] rows(sprintf("$1 == \"hbm\" && $3 == %s", word(samples, i))) \
         u 5:10 w l lw 1 dt 2 lc i notitle, \
     rows('$1 == "euler"') u 5:13 w lp lw 2 pt 5 ps 0.8 lc rgb '#d1495b' t 'implicit Euler', \
     rows('$1 == "euler"') u 5:10 w l lw 1 dt 2 lc rgb '#d1495b' notitle
unset multiplot
