# Per-frame mesh time over the drive of tests/bench/roam.c (`roam OUTDIR
# drive`): rs_roam_update (frame-coherent) against rs_roam_frame (rebuilt
# from scratch) at the same views, thread CPU time. Called by run.sh as
#   gnuplot -e "dir='build/bench'; out='docs/bench'" tests/bench/roam_drive.gp
set terminal pngcairo size 1300,440 font "sans,10"
set output out.'/roam_drive.png'
set datafile separator ","
f = dir.'/roam_drive.csv'
src(s) = sprintf("< grep '^%s,' '%s'", s, f)
set grid xtics ytics lc rgb "#dddddd"
set key top right box opaque font "sans,9"
set xlabel "frame (1/3 m per frame)"
set multiplot layout 1,3 title "ROAM drive, 1280x720, 2 px: per-frame mesh time, update vs rebuild (same run)"
set logscale y
set format y "%g"
set ylabel "ms per frame (thread CPU)"
set title "1025^2 fractal (500 m relief)"
plot src("fractal") using 2:4 with lines lc rgb "#d62728" title "rebuild (rs\\_roam\\_frame)", \
     src("fractal") using 2:3 with lines lc rgb "#1f77b4" title "update (rs\\_roam\\_update)", \
     src("fractal-p16") using 2:4 with lines lc rgb "#ff9896" title "rebuild, 16-cell patches", \
     src("fractal-p16") using 2:3 with lines lc rgb "#9ecae1" title "update, 16-cell patches"
set title "city 400x350, 5 m cells"
plot src("city") using 2:4 with lines lc rgb "#d62728" title "rebuild (rs\\_roam\\_frame)", \
     src("city") using 2:3 with lines lc rgb "#1f77b4" title "update (rs\\_roam\\_update)", \
     src("city-p16") using 2:4 with lines lc rgb "#ff9896" title "rebuild, 16-cell patches", \
     src("city-p16") using 2:3 with lines lc rgb "#9ecae1" title "update, 16-cell patches"
unset logscale y
set title "triangles and split/merge operations per update"
set ylabel "triangles"
set y2label "operations"
set y2tics
set ytics nomirror
# (headroom over the curves for the key: at the bottom it hid the city's operations)
set key top right
stats src("fractal") using 6 name "TRI" nooutput
stats src("fractal") using ($2 > 0 ? $7 : 1/0) name "OPS" nooutput
set yrange [0:TRI_max * 1.45]
set y2range [0:OPS_max * 1.45]
# frame 0 builds the mesh from the base mesh (tens of thousands of splits): left out
plot src("fractal") using 2:6 with lines lc rgb "#d62728" title "fractal triangles, rebuild", \
     src("fractal") using 2:5 with lines lc rgb "#1f77b4" dt 2 title "fractal triangles, update", \
     src("fractal") using 2:($2 > 0 ? $7 : 1/0) axes x1y2 with lines lc rgb "#2ca02c" title "fractal operations (right axis)", \
     src("city") using 2:($2 > 0 ? $7 : 1/0) axes x1y2 with lines lc rgb "#ff7f0e" title "city operations (right axis)"
unset multiplot
