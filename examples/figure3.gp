# Figure 3 of Legrand & Pierre (2023) from a run with &run method = 'all':
# x1 and x2 vs t, v2 vs t, r vs t and r vs v2; weighted residual solid, implicit Euler
# dashed, exact reference dotted. Writes <dir>/figure3.png.
#   gnuplot -e "dir='out/seed'" examples/figure3.gp
# Optional: n (DOFs, default 2), a and b (the two DOFs drawn, default 1 and 2), c (contact,
# default 1), e.g. gnuplot -e "dir='out/chain4'; n=4; a=1; b=2; c=1" examples/figure3.gp
if (!exists("dir")) dir = 'out/seed'
if (!exists("n")) n = 2
if (!exists("a")) a = 1
if (!exists("b")) b = 2
if (!exists("c")) c = 1
hbm = dir.'/hbm.csv'
eul = dir.'/euler.csv'
ref = dir.'/reference.csv'
xa = 1 + a; xb = 1 + b; vb = 1 + n + b; rc = 1 + 2*n + c

set terminal pngcairo size 1400,1000 enhanced font ',11'
set output dir.'/figure3.png'
set datafile separator ','
set grid lc rgb '#dddddd'
set key top right box opaque samplen 3 noenhanced
set style line 1 lc rgb '#1f4e9a' lw 2.2 dt 1
set style line 2 lc rgb '#d1495b' lw 2.2 dt 2
set style line 3 lc rgb '#111111' lw 2.6 dt 3
set style line 4 lc rgb '#2a9d8f' lw 2.2 dt 1
set style line 5 lc rgb '#e9a23b' lw 2.2 dt 2
set multiplot layout 2,2 title sprintf("%s: weighted residual (solid), implicit Euler (dashed), exact reference (dotted)", dir) noenhanced

set title sprintf('displacements x%d (left axis) and x%d (right axis)', a, b)
set xlabel 't [s]'
set ylabel sprintf('x%d [m]', a)
set y2label sprintf('x%d [m]', b)
set ytics nomirror
set y2tics
plot hbm u 1:xa w l ls 1 t sprintf('x%d', a), eul u 1:xa w l ls 2 notitle, \
     ref u 1:xa w l ls 3 notitle, \
     hbm u 1:xb axes x1y2 w l ls 4 t sprintf('x%d', b), eul u 1:xb axes x1y2 w l ls 5 notitle, \
     ref u 1:xb axes x1y2 w l ls 3 notitle
unset y2label
unset y2tics
set ytics mirror

set title sprintf('velocity v%d', b)
set ylabel sprintf('v%d [m/s]', b)
plot hbm u 1:vb w l ls 1 t 'weighted residual', eul u 1:vb w l ls 2 t 'implicit Euler', \
     ref u 1:vb w l ls 3 t 'exact reference'

set title sprintf('friction force r%d', c)
set ylabel sprintf('r%d [N]', c)
plot hbm u 1:rc w l ls 1 t 'weighted residual', eul u 1:rc w l ls 2 t 'implicit Euler', \
     ref u 1:rc w l ls 3 t 'exact reference'

set title sprintf('friction force r%d vs slip velocity v%d', c, b)
set xlabel sprintf('v%d [m/s]', b)
plot hbm u vb:rc w l ls 1 t 'weighted residual', eul u vb:rc w l ls 2 t 'implicit Euler', \
     ref u vb:rc w l ls 3 t 'exact reference'
unset multiplot
