# The close-up of a capture animated (plots/capture.sh writes the inputs):
#   gnuplot -c plots/capture_animation.gp PREFIX OUT.gif TITLE "CLOSE-UP RANGES" FREF LREF TARGET
# PREFIX_a_edges.dat, PREFIX_a_cps.dat, PREFIX_a_forces.dat: `capdyn export
# edges|checkpoints|forces --frames 60 --frame TARGET`; one set of axes for
# every frame; force arrows: LREF metres stand for FREF newtons.
p = ARG1; out = ARG2; title = ARG3; cr = ARG4
fref = real(ARG5); lref = real(ARG6); target = ARG7
s = lref / fref
# arrows longer than a quarter of the close-up's width are drawn at that length
hc = (real(word(cr,2)) - real(word(cr,1))) / 4
cap(x, y, z) = (L = s * sqrt(x*x + y*y + z*z), L > hc ? hc / L : 1.0)
nice(x) = (e = 10**floor(log10(x)), f = x / e, (f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10) * e)
set terminal gif animate delay 10 size 800,700 font ",10"
set output out
set view equal xyz
set view 62, 28, 1.2
set palette defined (0 "grey60", 1 "forest-green", 2 "red")
set cbrange [0:2]
unset colorbox
set xyplane relative 0
set key noenhanced at screen 0.99, screen 0.88 right top vertical font ",9" box opaque
set xrange [word(cr,1):word(cr,2)]; set yrange [word(cr,3):word(cr,4)]; set zrange [word(cr,5):word(cr,6)]
set xtics nice((real(word(cr,2)) - real(word(cr,1))) / 3); set ytics nice((real(word(cr,4)) - real(word(cr,3))) / 3)
set ztics nice((real(word(cr,6)) - real(word(cr,5))) / 3)
set xlabel sprintf("x [m] (%s frame)", target) noenhanced; set ylabel "y [m]"; set zlabel "z [m]"
n = int(system(sprintf("grep -c '^# frame' '%s_a_edges.dat'", p)))
do for [i=0:n-1] {
    tt = real(system(sprintf("awk '/^# frame %d /{print $NF; exit}' '%s_a_edges.dat'", i, p)))
    set title sprintf("%s\nclose-up in the frame of %s, t = %.3f s", title, target, tt) noenhanced
    splot p."_a_edges_clip.dat" index i using 1:2:($4 == 1 ? $3 : NaN) with lines lc rgb "dark-orange" notitle, \
          "" index i using 1:2:($4 != 1 ? $3 : NaN) with lines lw 2 lc rgb "navy" notitle, \
          p."_a_cps.dat" index i using 5:6:7:4 with points pt 7 ps 0.7 palette notitle, \
          p."_a_forces.dat" index i using 1:2:($11 == 1 ? $3 : NaN):($4*s*cap($4,$5,$6)):($5*s*cap($4,$5,$6)):($6*s*cap($4,$5,$6)) with vectors filled head lw 2 lc rgb "red" notitle, \
          keyentry with vectors filled head lw 2 lc rgb "red" title sprintf("force on %s: %g mm = %g N", target, lref*1000, fref), \
          keyentry with points pt 7 lc rgb "grey60" title "open", \
          keyentry with points pt 7 lc rgb "forest-green" title "stick", \
          keyentry with points pt 7 lc rgb "red" title "slip"
}
