# Grasp snapshots: a planar view of the links (segments), shapes (outlines:
# the palm box, the target cylinder as a circle, capsule links) and the check
# points (circles of their radius, coloured by contact mode) at chosen times.
#
# usage: gnuplot -c plots/snapshots.gp OUTLINE.dat CHECKPOINTS.dat OUT.(png|svg) ["TITLE"] [COLUMNS]
#   OUTLINE.dat      capdyn export RESULTS.h5 outline --at T1,T2,...
#   CHECKPOINTS.dat  capdyn export RESULTS.h5 checkpoints --at T1,T2,...
#   COLUMNS          panels per row (default 2)
# Each frame is one block (gnuplot index); columns: outline u v part body,
# checkpoints u v r mode x y z t cp body (docs/cli.md).

if (ARGC < 3) { print "usage: gnuplot -c snapshots.gp OUTLINE.dat CHECKPOINTS.dat OUT.png|OUT.svg [TITLE] [COLUMNS]"; exit status 2 }
outline = ARG1
cps = ARG2
out = ARG3
ttl = (ARGC >= 4) ? ARG4 : "snapshots"
ncol = (ARGC >= 5) ? int(ARG5) : 2

stats outline using 1:2 nooutput
nframe = STATS_blocks
ulo = STATS_min_x; uhi = STATS_max_x; vlo = STATS_min_y; vhi = STATS_max_y
pad = 0.05 * ((uhi - ulo > vhi - vlo) ? (uhi - ulo) : (vhi - vlo))
nrow = (nframe + ncol - 1) / ncol

if (out[strlen(out)-3:] eq ".svg") {
    set terminal svg size 480*ncol, 480*nrow + 40 dynamic enhanced font "sans,10" background rgb "white"
} else {
    set terminal pngcairo size 480*ncol, 480*nrow + 40 enhanced font "sans,10"
}
set output out

# the time of frame i, from the export's "# frame I sample S t T" lines
frame_t(i) = real(system(sprintf("awk '$2 == \"frame\" && $3 == %d {print $7; exit}' '%s'", i, outline)))
view = system("grep -m1 '^# view' '".outline."' | awk '{print $3}'")
set xlabel view[1:1]." [m]"
set ylabel view[2:2]." [m]"
set size ratio -1
set xrange [ulo - pad : uhi + pad]
set yrange [vlo - pad : vhi + pad]
set grid lc rgb "#eeeeee"
set key off
set style fill transparent solid 0.5 border
# part 0 link, 1 shape outline, 2 base-to-joint segment; mode 0 open, 1 stick, 2 slip
partcolor(p) = (p == 0) ? 0x202020 : (p == 1) ? 0x3060c0 : 0x909090
partwidth(p) = (p == 0) ? 3 : 1.5
modecolor(m) = (m == 2) ? 0xe02020 : (m == 1) ? 0x20a020 : 0xb0b0b0

set multiplot layout nrow, ncol title ttl noenhanced
do for [i=0:nframe-1] {
    set title sprintf("t = %.4g s", frame_t(i))
    plot outline index i using 1:2:(partcolor($3)) with lines lw 2 lc rgb variable, \
         cps index i using 1:2:3:(modecolor($4)) with circles lc rgb variable
}
unset multiplot
