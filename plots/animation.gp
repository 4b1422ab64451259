# Animated GIF of a whole run (grasp snapshots frame by frame).
#
# usage: gnuplot -c plots/animation.gp OUTLINE.dat CHECKPOINTS.dat OUT.gif ["TITLE"] [DELAY]
#   OUTLINE.dat      capdyn export RESULTS.h5 outline --frames N
#   CHECKPOINTS.dat  capdyn export RESULTS.h5 checkpoints --frames N
#   DELAY            time between frames in 1/100 s (default 5)

if (ARGC < 3) { print "usage: gnuplot -c animation.gp OUTLINE.dat CHECKPOINTS.dat OUT.gif [TITLE] [DELAY]"; exit status 2 }
outline = ARG1
cps = ARG2
out = ARG3
ttl = (ARGC >= 4) ? ARG4 : ""
delay = (ARGC >= 5) ? int(ARG5) : 5

stats outline using 1:2 nooutput
nframe = STATS_blocks
ulo = STATS_min_x; uhi = STATS_max_x; vlo = STATS_min_y; vhi = STATS_max_y
pad = 0.05 * ((uhi - ulo > vhi - vlo) ? (uhi - ulo) : (vhi - vlo))

set terminal gif animate delay delay loop 0 size 560,560 optimize font "sans,10"
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
set style fill solid 0.5 border
partcolor(p) = (p == 0) ? 0x202020 : (p == 1) ? 0x3060c0 : 0x909090
modecolor(m) = (m == 2) ? 0xe02020 : (m == 1) ? 0x20a020 : 0xb0b0b0

do for [i=0:nframe-1] {
    set title sprintf("%s   t = %.3f s", ttl, frame_t(i)) noenhanced
    plot outline index i using 1:2:(partcolor($3)) with lines lw 2 lc rgb variable, \
         cps index i using 1:2:3:(modecolor($4)) with circles lc rgb variable
}
set output
