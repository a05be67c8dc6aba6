# Scaling plots (log-log) with the least-squares fits written by
# tests/bench/scaling.c into scaling_fit.gp. Called by run.sh as
#   gnuplot -e "dir='build/bench'; out='docs/bench'" tests/bench/scaling.gp
set terminal pngcairo size 1100,850 font "sans,10"
set output out.'/scaling.png'
set datafile separator ","
load dir.'/scaling_fit.gp'
f = dir.'/scaling.csv'
sel(s, col) = (strcol(1) eq s) ? column(col) : NaN
set logscale xy
set grid xtics ytics mxtics mytics lc rgb "#dddddd"
unset key
set format y "%g"
set format x "%g"
set ylabel "time, ms (median, log scale)"
set multiplot layout 2,2 title "Splat scaling. Blue circles: total (road grid + splat); red squares: road work (grid build); dashed: least-squares fits on log-log"
do for [k = 1:4] {
    s = word("map length count texels", k)
    xl = word("DEM_side_(samples,_5_m_cells,_constant_road_density) road_length_(m,_one_6_m_road,_513^2_map) road_count_(60_m_x_6_m_roads,_513^2_map) texels_per_cell_(city_scene)", k)
    set xlabel system("echo '".xl."' | tr _ ' '")
    ab = value("a_".s."_build"); bb = value("b_".s."_build")
    at = value("a_".s."_total"); bt = value("b_".s."_total")
    set xrange [word("70 70 0.7 0.7", k) + 0 : word("1200 5000 400 12", k) + 0]
    set title sprintf("%s: slope %.2f total, %.2f road work", s, at, ab)
    plot f using 2:(sel(s, 5)) skip 1 with points pt 7 ps 1.3 lc rgb "#1f77b4" title "total (grid + splat)", \
         exp(bt) * x**at with lines lc rgb "#1f77b4" dt 2 title sprintf("fit x^{%.2f}", at), \
         f using 2:(sel(s, 4)) skip 1 with points pt 5 ps 1.3 lc rgb "#d62728" title "road work (grid build)", \
         exp(bb) * x**ab with lines lc rgb "#d62728" dt 2 title sprintf("fit x^{%.2f}", ab)
}
unset multiplot
