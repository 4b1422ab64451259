# Graspable-region maps of two sweeps side by side (docs/sweep.md): each
# variant's cell on the swept plane coloured by its verdict, peak contact
# force or capture time, with the palm and fingers drawn at their initial
# pose; positions normalised by the total finger length.
#
# usage: gnuplot -c plots/region.gp A.dat B.dat OUTLINE.dat OUT.(png|svg) METRIC LENGTH "TITLE A" "TITLE B" "TITLE"
#   A.dat, B.dat   capdyn sweep --table SUMMARY.h5 (a grid over x and y, the first two keys)
#   OUTLINE.dat    capdyn export RUN.h5 outline --at 0 (one run of the scenario; body 0 is the object, not drawn)
#   METRIC         verdict | peak_fn | t_capture
#   LENGTH         [m] total finger length (positions / LENGTH)
# Table columns (two keys): 1 index, 2-3 values, 4-5 normalised values,
# 6 verdict, 7 status, 8 t_capture, 9 t_escape, 10 peak_fn, ...

if (ARGC < 9) { print "usage: gnuplot -c region.gp A.dat B.dat OUTLINE.dat OUT METRIC LENGTH TITLE_A TITLE_B TITLE"; exit status 2 }
fa = ARG1; fb = ARG2; outline = ARG3; out = ARG4; metric = ARG5; L = real(ARG6)
ta = ARG7; tb = ARG8; ttl = ARG9

if (out[strlen(out)-3:] eq ".svg") {
    set terminal svg size 1100, 560 dynamic enhanced font "sans,11" background rgb "white"
} else {
    set terminal pngcairo size 1100, 560 enhanced font "sans,11"
}
set output out

# the cell size: the grid steps of x and y (from A)
stats fa using 2 nooutput
nx_lo = STATS_min; nx_hi = STATS_max
stats fa using 3 nooutput
ny_lo = STATS_min; ny_hi = STATS_max
stats fa using 1 nooutput
nvar = STATS_records
# distinct x values: count rows with the first y value
stats fa using ($3 == ny_lo ? 1 : 0) nooutput
nx = STATS_sum
ny = nvar / nx
dx = nx > 1 ? (nx_hi - nx_lo) / (nx - 1) / L : 0.01
dy = ny > 1 ? (ny_hi - ny_lo) / (ny - 1) / L : 0.01

# verdict colours: captured green, escaped red, unresolved amber, caged
# (verdict code 3: held but not captured) blue, failed black
vcol(v, s) = (s != 0) ? 0x000000 : (v == 1) ? 0x2ca02c : (v == 2) ? 0xd62728 : (v == 3) ? 0x1f77b4 : 0xffbf00

# readable ticks: about 4 per axis at round steps of x / L and y / L, and
# the bottom margin kept for the legend line below the x label
nice(r) = (m = 10 ** floor(log10(r / 4)), f = r / 4 / m, (f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10) * m)
# the plotted range: the cells and the hand's outline
stats outline using ($1 / L) nooutput
xr = ((STATS_max > nx_hi / L ? STATS_max : nx_hi / L) - (STATS_min < nx_lo / L ? STATS_min : nx_lo / L)) + dx
stats outline using ($2 / L) nooutput
yr = ((STATS_max > ny_hi / L ? STATS_max : ny_hi / L) - (STATS_min < ny_lo / L ? STATS_min : ny_lo / L)) + dy
set xtics nice(xr) nomirror out
set ytics nice(yr) nomirror out
set bmargin 6

set size ratio -1
set xlabel "x / L (L = total finger length)"
set ylabel "y / L"
set multiplot layout 1, 2 title ttl noenhanced
set key off
if (metric eq "verdict") {
    unset colorbox
    set label 1 "green captured, red escaped, amber unresolved, blue caged, black failed" at screen 0.5, 0.025 center
} else {
    set colorbox
    set palette rgbformulae 33,13,10
    if (metric eq "peak_fn") { set cblabel "peak fn on the object at samples [N]" }
    if (metric eq "t_capture") { set cblabel "time to capture [s] (blank: not captured)" }
}
col = (metric eq "peak_fn") ? 10 : 8
# one colour scale for both panels (the same quantity): the range over both
# (a panel with no value, e.g. no capture for t_capture, leaves the scale to the other)
if (metric ne "verdict") {
    c_lo = 1e300; c_hi = -1e300
    undefine STATS_*
    stats fa using ($7 == 0 && (col == 10 || $6 == 1) ? column(col) : 1 / 0) nooutput
    if (exists("STATS_min")) { c_lo = STATS_min; c_hi = STATS_max }
    undefine STATS_*
    stats fb using ($7 == 0 && (col == 10 || $6 == 1) ? column(col) : 1 / 0) nooutput
    if (exists("STATS_min")) { c_lo = (STATS_min < c_lo) ? STATS_min : c_lo; c_hi = (STATS_max > c_hi) ? STATS_max : c_hi }
    if (c_lo < c_hi) { set cbrange [c_lo : c_hi] }
}

do for [p = 1:2] {
    f = (p == 1) ? fa : fb
    set title ((p == 1) ? ta : tb) noenhanced
    if (metric eq "verdict") {
        plot f using ($2 / L):($3 / L):(dx / 2):(dy / 2):(vcol($6, $7)) with boxxyerror fs solid 0.85 noborder lc rgb variable, \
             outline using ($1 / L):($3 == 0 ? $2 / L : 1 / 0) with lines lw 3 lc rgb "#303030", \
             outline using ($1 / L):($3 == 1 && $4 != 0 ? $2 / L : 1 / 0) with lines lw 1 lc rgb "#606060"
    } else {
        plot f using ($2 / L):($3 / L):(dx / 2):(dy / 2):($7 == 0 ? column(col) : 1 / 0) with boxxyerror fs solid 0.9 noborder lc palette, \
             outline using ($1 / L):($3 == 0 ? $2 / L : 1 / 0) with lines lw 3 lc rgb "#303030", \
             outline using ($1 / L):($3 == 1 && $4 != 0 ? $2 / L : 1 / 0) with lines lw 1 lc rgb "#606060"
    }
}
unset multiplot
