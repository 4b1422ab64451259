# 3-D snapshots of a capture (plots/capture.sh writes the inputs):
#   gnuplot -c plots/capture_snapshots.gp GEOM.dat CPS.dat OUT.png [TITLE]
# GEOM.dat: per frame (gnuplot index) the arm's joint origins, the target's
# box edges and bar (world x y z); CPS.dat: `capdyn export checkpoints --at`
# (x y z in columns 5-7, contact mode in 4: grey open, green stick, red slip).
geom = ARG1; cps = ARG2; out = ARG3
title = ARGC >= 4 ? ARG4 : "capture"
set terminal pngcairo size 1400,1100 font ",10"
set output out
set view equal xyz
set view 64, 24, 1.6
set xlabel "x [m]"; set ylabel "y [m]"; set zlabel "z [m]"
set palette defined (0 "grey60", 1 "forest-green", 2 "red")
set cbrange [0:2]
unset colorbox
set multiplot layout 2,2 title title
do for [i=0:3] {
    tt = system(sprintf("awk 'BEGIN{n=-1} /^# frame/{n++} n==%d && !/^#/ && NF {print $8; exit}' %s", i, cps))
    set title sprintf("t = %s s", tt)
    splot geom index i every :::0::0 using 1:2:3 with linespoints lw 3 pt 7 ps 0.6 lc rgb "navy" title "arm", \
          geom index i every :::1::1 using 1:2:3:4:5:6 with vectors nohead lc rgb "dark-orange" title "bus, target, handrail", \
          cps index i using 5:6:7:4 with points pt 7 ps 0.5 palette title "gripper"
}
unset multiplot
