# Capture views of four instants (plots/capture.sh writes the inputs):
#   gnuplot -c plots/capture_snapshots.gp PREFIX OUT.png TITLE "WORLD RANGES" "CLOSE-UP RANGES" FREF LREF TARGET ["W,H"]
# PREFIX_w_edges.dat, PREFIX_w_cps.dat: `capdyn export edges|checkpoints --at
# T1,T2,T3,T4` (world frame); PREFIX_c_edges.dat, PREFIX_c_cps.dat,
# PREFIX_c_forces.dat: the same and `capdyn export forces` with --frame
# TARGET. RANGES: "xlo xhi ylo yhi zlo zhi" [m], one set per row of panels.
# Force arrows: LREF metres stand for FREF newtons (in the legend).
p = ARG1; out = ARG2; title = ARG3; wr = ARG4; cr = ARG5
fref = real(ARG6); lref = real(ARG7); target = ARG8
s = lref / fref
# arrows longer than a quarter of the close-up's width are drawn at that length
hc = (real(word(cr,2)) - real(word(cr,1))) / 4
cap(x, y, z) = (L = s * sqrt(x*x + y*y + z*z), L > hc ? hc / L : 1.0)
nice(x) = (e = 10**floor(log10(x)), f = x / e, (f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10) * e)
# optional ARG9 "W,H": a palette PNG of that size (gnuplot's gd terminal; small files, e.g. for docs/img/)
if (ARGC >= 9) { eval sprintf("set terminal png size %s font 'DejaVuSans,9'", ARG9) } else { set terminal pngcairo size 1800,1000 font ",10" }
set output out
set view equal xyz
set view 62, 28, 0.95
set palette defined (0 "grey60", 1 "forest-green", 2 "red")
set cbrange [0:2]
unset colorbox
set xyplane relative 0
set tics font ",8"
set key noenhanced font ",9" at screen 0.995, screen 0.9 right top box opaque
set multiplot title title noenhanced font ",13"
# row 1: the whole scene, world frame
set xrange [word(wr,1):word(wr,2)]; set yrange [word(wr,3):word(wr,4)]; set zrange [word(wr,5):word(wr,6)]
set xtics nice((real(word(wr,2)) - real(word(wr,1))) / 3); set ytics nice((real(word(wr,4)) - real(word(wr,3))) / 3)
set ztics nice((real(word(wr,6)) - real(word(wr,5))) / 3)
set xlabel "x [m]" offset 0,-0.5; set ylabel "y [m]" offset 0,-0.5; set zlabel "z [m]"
set size 0.21, 0.4
set view 62, 28, 1.7
do for [i=0:3] {
    set origin 0.21 * i, 0.54
    tt = real(system(sprintf("awk '/^# frame %d /{print $NF; exit}' '%s_w_edges.dat'", i, p)))
    set title sprintf("whole scene (world frame), t = %.3g s", tt)
    if (i == 0) {
        splot p."_w_edges.dat" index i using 1:2:($4 == 1 ? $3 : NaN) with lines lc rgb "dark-orange" notitle, \
              "" index i using 1:2:($4 != 1 ? $3 : NaN) with lines lw 2 lc rgb "navy" notitle, \
              p."_w_cps.dat" index i using 5:6:7:4 with points pt 7 ps 0.3 palette notitle, \
              keyentry with lines lc rgb "dark-orange" title "shapes (edges)", \
              keyentry with lines lw 2 lc rgb "navy" title "links (joint to joint)"
    } else {
        splot p."_w_edges.dat" index i using 1:2:($4 == 1 ? $3 : NaN) with lines lc rgb "dark-orange" notitle, \
              "" index i using 1:2:($4 != 1 ? $3 : NaN) with lines lw 2 lc rgb "navy" notitle, \
              p."_w_cps.dat" index i using 5:6:7:4 with points pt 7 ps 0.3 palette notitle
    }
}
# row 2: the close-up in the target's frame
set key at screen 0.995, screen 0.5
set xrange [word(cr,1):word(cr,2)]; set yrange [word(cr,3):word(cr,4)]; set zrange [word(cr,5):word(cr,6)]
set xtics nice((real(word(cr,2)) - real(word(cr,1))) / 3); set ytics nice((real(word(cr,4)) - real(word(cr,3))) / 3)
set ztics nice((real(word(cr,6)) - real(word(cr,5))) / 3)
set xlabel sprintf("x [m] (%s frame)", target) noenhanced; set ylabel "y [m]"; set zlabel "z [m]"
set size 0.21, 0.55
set view 62, 28, 1.45
do for [i=0:3] {
    set origin 0.21 * i, 0.0
    tt = real(system(sprintf("awk '/^# frame %d /{print $NF; exit}' '%s_c_edges.dat'", i, p)))
    set title sprintf("close-up, frame of %s, t = %.3g s", target, tt) noenhanced
    if (i == 0) {
        splot p."_c_edges_clip.dat" index i using 1:2:($4 == 1 ? $3 : NaN) with lines lc rgb "dark-orange" notitle, \
              "" index i using 1:2:($4 != 1 ? $3 : NaN) with lines lw 2 lc rgb "navy" notitle, \
              p."_c_cps.dat" index i using 5:6:7:4 with points pt 7 ps 0.7 palette notitle, \
              p."_c_forces.dat" index i using 1:2:($11 == 1 ? $3 : NaN):($4*s*cap($4,$5,$6)):($5*s*cap($4,$5,$6)):($6*s*cap($4,$5,$6)) with vectors filled head lw 2 lc rgb "red" notitle, \
              p."_c_forces.dat" index i using 1:2:($11 == 0 ? $3 : NaN):($4*s*cap($4,$5,$6)):($5*s*cap($4,$5,$6)):($6*s*cap($4,$5,$6)) with vectors filled head lw 1.5 lc rgb "purple" notitle, \
              keyentry with vectors filled head lw 2 lc rgb "red" title sprintf("force on %s: %g mm = %g N", target, lref*1000, fref), \
              keyentry with vectors filled head lw 1.5 lc rgb "purple" title "force within one system", \
              keyentry with points pt 7 ps 0.8 lc rgb "grey60" title "check point: open", \
              keyentry with points pt 7 ps 0.8 lc rgb "forest-green" title "check point: stick", \
              keyentry with points pt 7 ps 0.8 lc rgb "red" title "check point: slip"
    } else {
        splot p."_c_edges_clip.dat" index i using 1:2:($4 == 1 ? $3 : NaN) with lines lc rgb "dark-orange" notitle, \
              "" index i using 1:2:($4 != 1 ? $3 : NaN) with lines lw 2 lc rgb "navy" notitle, \
              p."_c_cps.dat" index i using 5:6:7:4 with points pt 7 ps 0.7 palette notitle, \
              p."_c_forces.dat" index i using 1:2:($11 == 1 ? $3 : NaN):($4*s*cap($4,$5,$6)):($5*s*cap($4,$5,$6)):($6*s*cap($4,$5,$6)) with vectors filled head lw 2 lc rgb "red" notitle, \
              p."_c_forces.dat" index i using 1:2:($11 == 0 ? $3 : NaN):($4*s*cap($4,$5,$6)):($5*s*cap($4,$5,$6)):($6*s*cap($4,$5,$6)) with vectors filled head lw 1.5 lc rgb "purple" notitle
    }
}
unset multiplot
