# The SDF collision paper's Fig 5 from two --trace CSVs of the inclined-plane sample: the tracked (centre) vertex's
# height above the slope over time, the improved method against the baseline, with the thickness they rest at.
#   build/samples/inclined_plane --trace improved.csv
#   build/samples/inclined_plane --method baseline --trace baseline.csv
#   gnuplot -e "improved='improved.csv'; baseline='baseline.csv'; out='fig5.png'" samples/inclined_plane/fig5.gp
if (!exists("improved")) improved = "improved.csv"
if (!exists("baseline")) baseline = "baseline.csv"
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
plot baseline using 1:2 with lines lw 2 lc rgb "#1f77b4" title "baseline (collide inside the solve)", \
     improved using 1:2 with lines lw 2 dt 2 lc rgb "#d62728" title "improved (paper 002)", \
     thickness with lines lc rgb "#555555" dt 3 title "thickness"
set title "after landing: height above the thickness (nm)"
set ylabel "height - thickness (nm)"
set xrange [0.6:*]
set format y "%g"
plot baseline using 1:(($2 - thickness)*1e9) with lines lw 2 lc rgb "#1f77b4" title "baseline", \
     improved using 1:(($2 - thickness)*1e9) with lines lw 2 dt 2 lc rgb "#d62728" title "improved"
unset multiplot
