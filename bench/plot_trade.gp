# Error against cost (log-log) of the trade study, one panel per scene error, with the Pareto front that
# bench/trade_study computed (trade_pareto_<panel>.csv). Rows whose axis the scene cannot feel (axis_applies 0:
# method and PGD on the hanging cloth, PGD on the plane) repeat the default's computation and are not drawn. Run by trade_study after it writes the CSVs, or:
#   gnuplot -e "dir='docs/trade'" bench/plot_trade.gp
if (!exists("dir")) dir = "docs/trade"
csv = dir . "/trade.csv"

set terminal pngcairo size 1600,1200 font "sans,10"
set output dir . "/trade.png"
set datafile separator ","
set datafile columnheaders
set datafile missing ""
set logscale xy
set format y "10^{%L}"
set format x "%g"
set grid xtics ytics mxtics mytics lc rgb "#dddddd"
set key top right box opaque font "sans,9" spacing 0.9
set xlabel "ms per frame (dt 1/60 s, 651 vertices, one thread)"

groups = "faces/float faces/double in-solve/float vertices/float faces/float/pgd<12"
gcolour(i) = word("#1f77b4 #9467bd #d62728 #2ca02c #ff7f0e", i)
gpoint(i) = int(word("7 5 9 11 13", i))

# panel name, scene, error column, title
names   = "hanging hanging_strain slope drop"
scenes  = "hanging hanging slope drop"
columns = "lowest_drop_err strain_max accel_err traj_rms_err"
titles  = "'hanging cloth: |lowest drop - reference| (m)' 'hanging cloth: max stretch strain' 'slope 30°, μ 0.3: |a - g(sin θ - μ cos θ)| (m/s²)' 'drop on a ball: trajectory RMS error vs reference (m)'"

# a positive error or nothing (log axes)
pos(x) = (x > 0) ? x : NaN

set multiplot layout 2,2 title "drape trade study: error against cost; Pareto front in black, labelled substeps x iterations" font "sans,13"
do for [p = 1:4] {
  sc = word(scenes, p)
  col = word(columns, p)
  set title word(titles, p)
  set ylabel col noenhanced
  if (sc eq "slope") { set key bottom right } else { set key top right }
  plot for [g = 1:words(groups)] csv \
         using ((strcol("scene") eq sc && strcol("role") eq "sweep" && column("axis_applies") == 1 && strcol("group") eq word(groups, g)) ? column("ms_per_frame") : NaN):(pos(column(col))) \
         with points pt gpoint(g) ps 1.3 lc rgb gcolour(g) title word(groups, g), \
       csv using ((strcol("scene") eq sc && strcol("role") eq "check") ? column("ms_per_frame") : NaN):(pos(column(col))) \
         with points pt 3 ps 2 lw 2 lc rgb "#444444" title "check: double, 500 substeps", \
       dir . "/trade_pareto_" . word(names, p) . ".csv" using "ms_per_frame":(pos(column("error"))) \
         with linespoints lw 2 pt 6 ps 2 lc rgb "black" title "Pareto front", \
       "" using "ms_per_frame":(pos(column("error"))):"label" with labels left offset 1,0.6 font "sans,8" tc rgb "black" notitle
}
unset multiplot
