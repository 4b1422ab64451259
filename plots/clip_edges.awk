# Clips the polylines of `capdyn export edges` (x y z part body, frames
# separated by "# frame" lines) to a box: gnuplot's splot does not clip lines
# at the axis ranges, so a close-up would show the whole of a large target.
#   awk -v box="xlo xhi ylo yhi zlo zhi" -f plots/clip_edges.awk EDGES.dat
# Liang-Barsky per segment; a polyline leaving and re-entering the box is
# split (one blank line); every frame keeps a row (nan) so gnuplot's index
# counts frames.
function clip(x1, y1, z1, x2, y2, z2,   t0, t1, d, p, q, k, r) {
    t0 = 0; t1 = 1
    d[1] = x2 - x1; d[2] = y2 - y1; d[3] = z2 - z1
    p[1] = x1; p[2] = y1; p[3] = z1
    for (k = 1; k <= 3; k++) {
        if (d[k] == 0) { if (p[k] < lo[k] || p[k] > hi[k]) return 0; continue }
        q = (lo[k] - p[k]) / d[k]; r = (hi[k] - p[k]) / d[k]
        if (q > r) { tmp = q; q = r; r = tmp }
        if (q > t0) t0 = q
        if (r < t1) t1 = r
        if (t0 > t1) return 0
    }
    A[1] = x1 + t0 * d[1]; A[2] = y1 + t0 * d[2]; A[3] = z1 + t0 * d[3]
    B[1] = x1 + t1 * d[1]; B[2] = y1 + t1 * d[2]; B[3] = z1 + t1 * d[3]
    cin = t0 > 0; cout = t1 < 1
    return 1
}
BEGIN { split(box, b, " "); for (k = 1; k <= 3; k++) { lo[k] = b[2 * k - 1]; hi[k] = b[2 * k] }; nf = 0 }
/^# frame/ { if (nf++ > 0) printf "\n\n"; print; print "nan nan nan 1 -1"; have = 0; brk = 0; next }
/^#/ { if (nf == 0) print; next }
NF == 0 { have = 0; brk = 1; next }
{
    if (have && clip(px, py, pz, $1, $2, $3)) {
        if (brk || cin) print ""
        print A[1], A[2], A[3], $4, $5
        print B[1], B[2], B[3], $4, $5
        brk = cout
    } else if (have) brk = 1
    px = $1; py = $2; pz = $3; have = 1
}
