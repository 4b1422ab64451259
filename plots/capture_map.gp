# The capture-success map (docs/capture.md, "The capture map"): one cell per
# variant of a capdyn sweep over the aim error across the bar (first key,
# shown in mm) x the target's tumbling rate (second key, deg/s). Left: the
# verdict, each cell labelled with the peak contact force on the target [N]
# (a few newtons and more: the hand closed on the bar). Right: the time to
# capture (blank: not captured).
#
# With a Monte Carlo sweep (--mc N, several draws per cell; MODE "mc"):
# left the capture probability per cell (one colour scale, 0 to 1, cells
# labelled "captured/n"), right its Wilson 95 % interval (colour: the
# interval's width; cells labelled [low, high]; cells whose interval is
# wider than 0.3 hatched).
#
# usage: gnuplot -c plots/capture_map.gp MAP.dat OUT.(png|svg) "TITLE" [MODE]
#   MAP.dat   capdyn sweep --table SUMMARY.h5 (a grid over two keys)
#   MODE      verdict (default) | mc
# Table columns (two keys): 1 index, 2-3 values, 4-5 normalised values,
# 6 verdict, 7 status, 8 t_capture, 9 t_escape, 10 peak_fn, ...
# Monte Carlo table (two --vary keys): 1 cell, 2-3 values, 4 n,
# 5 n_captured, 6 n_caged, 7 n_failed, 8 p_capture, 9 p_low, 10 p_high, ...

if (ARGC < 3) { print "usage: gnuplot -c capture_map.gp MAP.dat OUT TITLE [verdict|mc]"; exit status 2 }
f = ARG1; out = ARG2; ttl = ARG3
mode = (ARGC >= 4) ? ARG4 : "verdict"

if (out[strlen(out)-3:] eq ".svg") {
    set terminal svg size 1100, 520 dynamic enhanced font "sans,11" background rgb "white"
} else {
    set terminal pngcairo size 1100, 520 enhanced font "sans,11"
}
set output out

# the cell size: the grid steps of both keys
stats f using ($2 * 1000) nooutput
x_lo = STATS_min; x_hi = STATS_max
stats f using 3 nooutput
y_lo = STATS_min; y_hi = STATS_max
stats f using 1 nooutput
nvar = STATS_records
stats f using ($3 == y_lo ? 1 : 0) nooutput
nx = STATS_sum
ny = nvar / nx
dx = nx > 1 ? (x_hi - x_lo) / (nx - 1) : 1
dy = ny > 1 ? (y_hi - y_lo) / (ny - 1) : 1
set xrange [x_lo - dx / 2 : x_hi + dx / 2]
set yrange [y_lo - dy / 2 : y_hi + dy / 2]

# readable ticks: at most about 6 per axis, at the grid's values
set xtics nomirror out
set ytics nomirror out
if (nx > 6) { set xtics x_lo, ceil((nx - 1) / 5.0) * dx }
if (ny > 6) { set ytics y_lo, ceil((ny - 1) / 5.0) * dy }
set bmargin 5

if (mode eq "mc") {
    set xlabel "aim error across the bar, control.misalign.position[0] [mm]"
    set ylabel "tumbling rate about the target's x [deg/s]"
    set key off
    set multiplot layout 1, 2 title ttl noenhanced
    set palette defined (0 "#d62728", 0.5 "#ffbf00", 1 "#2ca02c")
    set cbrange [0:1]
    set cblabel "capture probability" noenhanced
    set title "capture probability (cells: captured / draws)" noenhanced
    plot f using ($2 * 1000):3:(dx / 2):(dy / 2):8 with boxxyerror fs solid 0.9 noborder lc palette, \
         f using ($2 * 1000):3:(sprintf("%d/%d", $5, $4)) with labels font ",9"
    set palette rgbformulae 7,5,15 negative
    set cbrange [0:1]
    set cblabel "width of the Wilson 95 % interval" noenhanced
    set title "Wilson 95 % interval (cells: high over low)\n(hatched: wider than 0.3)" noenhanced
    plot f using ($2 * 1000):3:(dx / 2):(dy / 2):($10 - $9) with boxxyerror fs solid 0.9 noborder lc palette, \
         f using ($10 - $9 > 0.3 ? $2 * 1000 : 1 / 0):3:(dx / 2):(dy / 2) with boxxyerror fs pattern 4 transparent lc rgb "#404040", \
         f using ($2 * 1000):3:(sprintf("%.2f\n%.2f", $10, $9)) with labels font ",8" tc rgb "white"
    unset multiplot
    exit
}

# verdict colours: captured green, escaped red, unresolved amber, caged
# (verdict code 3: held but not captured) blue, failed dark grey, not run
# (an interrupted sweep) light grey
vcol(v, s) = (s == -1) ? 0xd0d0d0 : (s != 0) ? 0x505050 : (v == 1) ? 0x2ca02c : (v == 2) ? 0xd62728 : (v == 3) ? 0x1f77b4 : 0xffbf00
# (the force is read inside: a NaN argument would make the label "nan")
vlab(s) = (s == -1) ? "not run" : (s != 0) ? "failed" : sprintf("%.1f", column(10))

set xlabel "aim error across the bar, control.misalign.position[0] [mm]"
set ylabel "tumbling rate about the target's x [deg/s]"
set key off
set multiplot layout 1, 2 title ttl noenhanced

set title "verdict: green captured, red escaped, amber unresolved, blue caged\n(cells: peak fn on the target at samples [N])" noenhanced
unset colorbox
plot f using ($2 * 1000):3:(dx / 2):(dy / 2):(vcol($6, $7)) with boxxyerror fs solid 0.85 noborder lc rgb variable, \
     f using ($2 * 1000):3:(vlab($7)) with labels font ",9"

set title "time to capture [s] (blank: not captured)" noenhanced
set colorbox
set palette rgbformulae 33,13,10
set cblabel "t_capture [s]" noenhanced
plot f using ($2 * 1000):3:(dx / 2):(dy / 2):($7 == 0 && $6 == 1 ? $8 : 1 / 0) with boxxyerror fs solid 0.9 noborder lc palette, \
     f using ($2 * 1000):3:($7 == 0 && $6 == 1 ? sprintf("%.2f", $8) : "") with labels font ",9"
unset multiplot
