# Mesher plots from tests/bench/roam.c (roadsplat ROAM vs \\@mapbox/martini,
# same grids, same run). Called by run.sh as
#   gnuplot -e "dir='build/bench'; out='docs/bench'" tests/bench/roam.gp
set terminal pngcairo size 1300,480 font "sans,10"
set output out.'/roam.png'
set datafile separator ","
f = dir.'/roam.csv'
# one line per (DEM, mesher): grep the rows so that lines are not broken
src(d, m) = sprintf("< grep '^%s,%s,' '%s'", d, m, f)
set logscale xy
set format x "%g"
set format y "%g"
set grid xtics ytics mxtics mytics lc rgb "#dddddd"
set key top right box opaque font "sans,9"
set multiplot layout 1,3 title "1025^2 DEMs: roadsplat ROAM vs \\@mapbox/martini (medians, same run)"
set title "time against requested max error"
set xlabel "requested max error E, m"
set ylabel "build + mesh time, ms"
# (headroom over the slowest times for the key: without it the key hid
# martini's times; the other panels' keys sit bottom left)
set yrange [1:30000]
set ytics ("1" 1, "10" 10, "100" 100, "1000" 1000)
plot src("fractal", "roadsplat") using 3:9 with linespoints pt 7 lc rgb "#1f77b4" title "roadsplat, fractal", \
     src("realistic", "roadsplat") using 3:9 with linespoints pt 5 lc rgb "#1f77b4" dt 2 title "roadsplat, realistic", \
     src("fractal", "roadsplat_reused") using 3:9 with linespoints pt 7 lc rgb "#2ca02c" title "reused (set\\_dem), fractal", \
     src("realistic", "roadsplat_reused") using 3:9 with linespoints pt 5 lc rgb "#2ca02c" dt 2 title "reused (set\\_dem), realistic", \
     src("fractal", "martini") using 3:9 with linespoints pt 6 lc rgb "#d62728" title "martini, fractal", \
     src("realistic", "martini") using 3:9 with linespoints pt 4 lc rgb "#d62728" dt 2 title "martini, realistic"
set yrange [*:*]
set ytics auto
set title "triangles against measured max error"
set xlabel "true max vertical error over all samples, m"
set ylabel "triangles"
set key bottom left
plot src("fractal", "roadsplat") using 5:4 with linespoints pt 7 lc rgb "#1f77b4" title "roadsplat, fractal", \
     src("realistic", "roadsplat") using 5:4 with linespoints pt 5 lc rgb "#1f77b4" dt 2 title "roadsplat, realistic", \
     src("fractal", "martini") using 5:4 with linespoints pt 6 lc rgb "#d62728" title "martini, fractal", \
     src("realistic", "martini") using 5:4 with linespoints pt 4 lc rgb "#d62728" dt 2 title "martini, realistic"
set title "triangles against measured RMS error"
set xlabel "true RMS vertical error over all samples, m"
plot src("fractal", "roadsplat") using 6:4 with linespoints pt 7 lc rgb "#1f77b4" title "roadsplat, fractal", \
     src("realistic", "roadsplat") using 6:4 with linespoints pt 5 lc rgb "#1f77b4" dt 2 title "roadsplat, realistic", \
     src("fractal", "martini") using 6:4 with linespoints pt 6 lc rgb "#d62728" title "martini, fractal", \
     src("realistic", "martini") using 6:4 with linespoints pt 4 lc rgb "#d62728" dt 2 title "martini, realistic"
unset multiplot
