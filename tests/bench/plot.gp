# plot.gp - error against time for one accuracy axis, Pareto fronts marked.
#
# Called by tests/bench/run.sh once per tests/bench/out/acc_<axis>.dat
# (written by bench_accuracy):
#   gnuplot -e "datafile='...'; outfile='...'; axisname='...'; \
#               machine='...'; stamp='...'; cmd='...'" tests/bench/plot.gp
# Data columns: 1 cost (time per client frame incl. tick, ms; for codecs
# KiB per frame - run.sh passes the matching xlab), 2 tick ms,
# 3 frame ms, 4 height RMS (% of Hs), 5 normal RMS (deg), 6 SSIM, 7 label.
# Index 0: every setting; 1: height Pareto front; 2: normal Pareto front;
# 3: the shipped default.  Front points and the default are labelled
# (labelling every point makes clusters unreadable; the tables name them all).

if (!exists("datafile")) datafile = 'tests/bench/out/acc_grid.dat'
if (!exists("outfile")) outfile = 'tests/bench/out/acc_grid.png'
if (!exists("axisname")) axisname = 'grid'
if (!exists("machine")) machine = ''
if (!exists("stamp")) stamp = ''
if (!exists("cmd")) cmd = 'make bench'
if (!exists("xlab")) xlab = 'time per client frame, tick included (ms, median)'

set terminal pngcairo size 1500,640 font 'DejaVu Sans,10' noenhanced
set output outfile
set multiplot layout 1,2 title sprintf("Accuracy vs cost: %s\n%s | %s | reproduce: %s", axisname, machine, stamp, cmd) font ',11'

set logscale xy
set grid xtics ytics mxtics mytics lc rgb '#dddddd'
set key top right box opaque
set xlabel xlab
set format x '%g'
set format y '%g'

set ylabel 'height RMS error (% of Hs)'
plot datafile index 0 using 1:4 with points pt 7 ps 1.2 lc rgb '#4477aa' title 'setting', \
     '' index 1 using 1:4 with linespoints lw 2 pt 6 ps 2 lc rgb '#cc3311' title 'Pareto front', \
     '' index 1 using 1:4:7 with labels offset char 0.8,0.6 left font ',8' notitle, \
     '' index 3 using 1:4:7 with labels offset char 0.8,-0.8 left font ',8' notitle, \
     '' index 3 using 1:4 with points pt 3 ps 3.5 lw 2 lc rgb '#000000' title 'shipped default'

set ylabel 'normal angle RMS error (degrees)'
plot datafile index 0 using 1:5 with points pt 7 ps 1.2 lc rgb '#4477aa' title 'setting', \
     '' index 2 using 1:5 with linespoints lw 2 pt 6 ps 2 lc rgb '#cc3311' title 'Pareto front', \
     '' index 2 using 1:5:7 with labels offset char 0.8,0.6 left font ',8' notitle, \
     '' index 3 using 1:5:7 with labels offset char 0.8,-0.8 left font ',8' notitle, \
     '' index 3 using 1:5 with points pt 3 ps 3.5 lw 2 lc rgb '#000000' title 'shipped default'

unset multiplot
