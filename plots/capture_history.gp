# Time histories of a capture (plots/capture.sh writes the inputs):
#   gnuplot -c plots/capture_history.gp PREFIX OUT.png [TITLE]
# PREFIX_contacts.dat (capdyn export contacts), PREFIX_tau.dat (t, then the
# chaser's applied joint torques: arm joints first), PREFIX_chaser.dat
# (capdyn export system chaser), PREFIX_diag_{chaser,target,all}.dat
# (capdyn export diagnostics [SYSTEM]: px py pz in 6-8, lx ly lz in 10-12,
# angular momentum about each one's own CoM).
p = ARG1; out = ARG2
title = ARGC >= 3 ? ARG3 : "capture"
set terminal pngcairo size 1400,1000 font ",10"
set output out
set multiplot layout 3,2 title title
set grid
set xlabel "t [s]"
set key top left
set title "contact forces"; set ylabel "N"; set y2tics; set y2label "stick contacts"
plot p."_contacts.dat" using 1:5 with lines lw 2 title "sum of normal forces", \
     "" using 1:3 axes x1y2 with steps title "stick contacts (right axis)"
unset y2tics; unset y2label
set title "arm joint torques (controller)"; set ylabel "N m"
plot for [j=2:7] p."_tau.dat" using 1:j with lines title sprintf("joint %d", j-1)
set title "base attitude"; set ylabel "deg"; set y2tics; set y2label "deg/s"
plot p."_chaser.dat" using 1:(2*acos(abs($5) < 1 ? abs($5) : 1)*180/pi) with lines lw 2 title "rotation from t = 0", \
     "" using 1:(sqrt($12**2 + $13**2 + $14**2)*180/pi) axes x1y2 with lines title "rate [deg/s] (right axis)"
unset y2tics; unset y2label
set title "linear momentum"; set ylabel "kg m/s"
plot p."_diag_chaser.dat" using 1:7 with lines title "chaser p_y", p."_diag_target.dat" using 1:7 with lines title "target p_y", \
     p."_diag_all.dat" using 1:7 with lines lw 2 title "whole p_y", \
     p."_diag_chaser.dat" using 1:6 with lines dt 2 title "chaser p_x", p."_diag_target.dat" using 1:6 with lines dt 2 title "target p_x", \
     p."_diag_all.dat" using 1:6 with lines lw 2 dt 2 title "whole p_x"
set title "angular momentum (each about its own CoM)"; set ylabel "kg m^2/s"
plot p."_diag_chaser.dat" using 1:10 with lines title "chaser L_x", p."_diag_target.dat" using 1:10 with lines title "target L_x", \
     p."_diag_all.dat" using 1:10 with lines lw 2 title "whole L_x", \
     p."_diag_chaser.dat" using 1:12 with lines dt 2 title "chaser L_z", p."_diag_target.dat" using 1:12 with lines dt 2 title "target L_z", \
     p."_diag_all.dat" using 1:12 with lines lw 2 dt 2 title "whole L_z"
set title "momentum of the whole: change since t = 0"; set ylabel ""
set logscale y
plot p."_diag_all.dat" using 1:($9 > 0 ? $9 : 1e-18) with lines title "|P - P(0)| [kg m/s]", \
     "" using 1:($13 > 0 ? $13 : 1e-18) with lines title "|L - L(0)| [kg m^2/s] (wheels when on)"
unset multiplot
