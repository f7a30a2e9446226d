# The SDF collision paper's Fig 5 from two --trace CSVs of the inclined-plane sample: the tracked (centre) vertex's
# height above the slope over time, the paper's method (faces) against the one it improves on (in-solve), with the
# thickness they rest at.
#   build/samples/inclined_plane --gap -0.05 --trace faces.csv
#   build/samples/inclined_plane --gap -0.05 --method in-solve --trace in_solve.csv
#   gnuplot -e "faces='faces.csv'; in_solve='in_solve.csv'; out='fig5.png'" samples/inclined_plane/fig5.gp
if (!exists("faces")) faces = "faces.csv"
if (!exists("in_solve")) in_solve = "in_solve.csv"
if (!exists("out")) out = "fig5.png"
if (!exists("thickness")) thickness = 0.005

set terminal pngcairo size 1200,700 font "sans,11"
set output out
set datafile separator ","
set datafile columnheaders
set multiplot layout 1,2 title "Tracked vertex height (50x80 cloth started 5 cm into a 30 degree slope, 10 substeps)"
set grid lc rgb "#dddddd"
set key top right box opaque
set xlabel "time (s)"
set ylabel "height (m)"
set title "whole run"
plot in_solve using 1:2 with lines lw 2 lc rgb "#1f77b4" title "in-solve (the previous method)", \
     faces using 1:2 with lines lw 2 dt 2 lc rgb "#d62728" title "faces (the paper's method)", \
     thickness with lines lc rgb "#555555" dt 3 title "thickness"
set title "after landing: distance from the thickness (log scale)"
set ylabel "|height - thickness| (m)"
set xrange [0.6:*]
set logscale y
set format y "10^{%L}"
# Exactly at the thickness reads as the CSV's last digit, 1e-8 m.
floor = 1e-8
plot in_solve using 1:(abs($2 - thickness) > floor ? abs($2 - thickness) : floor) with lines lw 2 lc rgb "#1f77b4" \
       title "in-solve (the previous method)", \
     faces using 1:(abs($2 - thickness) > floor ? abs($2 - thickness) : floor) with lines lw 2 dt 2 \
       lc rgb "#d62728" title "faces (the paper's method)"
unset multiplot
