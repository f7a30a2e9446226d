# The SDF collision paper's Fig 5 from two --trace CSVs of the inclined-plane sample: the tracked (centre) vertex's
# height above the slope over time, the paper's method (faces) against the one it improves on (in-solve), with the
# thickness they rest at.
#   build/samples/inclined_plane --trace faces.csv
#   build/samples/inclined_plane --method in-solve --trace in_solve.csv
#   gnuplot -e "faces='faces.csv'; in_solve='in_solve.csv'; out='fig5.png'" samples/inclined_plane/fig5.gp
if (!exists("faces")) faces = "faces.csv"
if (!exists("in_solve")) in_solve = "in_solve.csv"
if (!exists("out")) out = "fig5.png"
if (!exists("thickness")) thickness = 0.005

set terminal pngcairo size 1200,700 font "sans,11"
set output out
set datafile separator ","
set datafile columnheaders
set multiplot layout 1,2 title "Tracked vertex height above the slope (50x80 cloth, 30 degrees, 10 substeps)"
set grid lc rgb "#dddddd"
set key top right box opaque
set xlabel "time (s)"
set ylabel "height (m)"
set title "whole run"
plot in_solve using 1:2 with lines lw 2 lc rgb "#1f77b4" title "in-solve (the previous method)", \
     faces using 1:2 with lines lw 2 dt 2 lc rgb "#d62728" title "faces (the paper's method)", \
     thickness with lines lc rgb "#555555" dt 3 title "thickness"
set title "after landing: height above the thickness (nm)"
set ylabel "height - thickness (nm)"
set xrange [0.6:*]
set format y "%g"
plot in_solve using 1:(($2 - thickness)*1e9) with lines lw 2 lc rgb "#1f77b4" title "in-solve (the previous method)", \
     faces using 1:(($2 - thickness)*1e9) with lines lw 2 dt 2 lc rgb "#d62728" title "faces (the paper's method)"
unset multiplot
