# Splat Pareto plot: edge error against run time, every setting of
# tests/bench/splat.c, with the Pareto front. Called by run.sh as
#   gnuplot -e "dir='build/bench'; out='docs/bench'" tests/bench/splat.gp
set terminal pngcairo size 1000,700 font "sans,11"
set output out.'/splat_pareto.png'
set datafile separator ","
# (bottom left, where no setting lands: at the top right the key hid the
# bilinear baseline's label and the Pareto front's step)
set key inside left bottom box opaque font "sans,10"
set logscale x
set logscale y
set grid xtics ytics mxtics mytics lc rgb "#dddddd"
set xlabel "time: road grid build + splat, ms (median, log scale)"
set ylabel "edge error, m (SPEC mean edge displacement, log scale)"
set title "Splat on the city scene: accuracy against time (lower left is better)"
f = dir.'/splat.csv'
sel(g) = (strcol(1) eq g) ? $7 : NaN
plot dir.'/splat_pareto.csv' using 2:3 skip 1 with steps lw 2 lc rgb "#999999" title "Pareto front", \
     f using 6:(sel("default")) skip 1 with points pt 7 ps 2.0 lc rgb "black" title "default", \
     f using 6:(sel("distance")) skip 1 with linespoints pt 5 ps 1.3 lc rgb "#1f77b4" title "distance buffer, K = 4..32", \
     f using 6:(sel("dilate")) skip 1 with linespoints pt 4 ps 1.3 lc rgb "#ff7f0e" title "dilate buffer, K = 4..32", \
     f using 6:(sel("alpha-res")) skip 1 with points pt 9 ps 1.3 lc rgb "#2ca02c" title "alpha-res 8..64", \
     f using 6:(sel("transition")) skip 1 with points pt 11 ps 1.3 lc rgb "#9467bd" title "transition hard..16 px", \
     f using 6:(sel("texels")) skip 1 with linespoints pt 13 ps 1.3 lc rgb "#8c564b" title "texels per cell 1, 2, 4, 8", \
     f using 6:(sel("baseline")) skip 1 with points pt 3 ps 2.0 lc rgb "#d62728" title "baseline: 5 m cell buffer (nearest / bilinear)", \
     f using 6:(sel("edges")) skip 1 with points pt 15 ps 1.8 lc rgb "#17becf" title "analytic edges", \
     f using 6:(sel("edges")):2 skip 1 with labels offset 0,-1 font "sans,9" notitle, \
     f using 6:(sel("distance")):2 skip 1 with labels offset 0,-1 font "sans,9" notitle, \
     f using 6:(sel("dilate")):2 skip 1 with labels offset 0,1 font "sans,9" notitle, \
     f using 6:(sel("texels")):2 skip 1 with labels offset 1.5,0 font "sans,9" notitle, \
     f using 6:(sel("baseline")):2 skip 1 with labels offset 0,1 font "sans,9" notitle
