# Animated GIF of a capture, one frame per exported frame (plots/capture.sh):
#   gnuplot -c plots/capture_animation.gp GEOM.dat CPS.dat OUT.gif [TITLE]
geom = ARG1; cps = ARG2; out = ARG3
title = ARGC >= 4 ? ARG4 : "capture"
set terminal gif animate delay 8 size 800,640 font ",10"
set output out
set view equal xyz
set view 64, 24, 1.6
set xlabel "x [m]"; set ylabel "y [m]"; set zlabel "z [m]"
set palette defined (0 "grey60", 1 "forest-green", 2 "red")
set cbrange [0:2]
unset colorbox
n = int(system("grep -c '^# frame' ".cps))
do for [i=0:n-1] {
    tt = system(sprintf("awk 'BEGIN{n=-1} /^# frame/{n++} n==%d && !/^#/ && NF {print $8; exit}' %s", i, cps))
    set title sprintf("%s\nt = %s s", title, tt)
    splot geom index i every :::0::0 using 1:2:3 with linespoints lw 3 pt 7 ps 0.6 lc rgb "navy" notitle, \
          geom index i every :::1::1 using 1:2:3:4:5:6 with vectors nohead lc rgb "dark-orange" notitle, \
          cps index i using 5:6:7:4 with points pt 7 ps 0.5 palette notitle
}
