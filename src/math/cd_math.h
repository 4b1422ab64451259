/* Small dense algebra used by every layer: 3-vectors, 3x3 matrices (row-major),
 * unit quaternions (scalar first: w, x, y, z) and 6-D spatial vectors.
 *
 * Spatial vectors follow Featherstone's Plucker convention in world coordinates:
 * a motion vector is [omega; v_O] (angular velocity, then the velocity of the body
 * point that coincides with the reference point O), a force vector is [n_O; f]
 * (moment about O, then force). All functions are static inline so that the core
 * has no link-time dependency beyond libm; none allocates. */
#ifndef CD_MATH_H
#define CD_MATH_H

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#define CD_PI 3.14159265358979323846

/* 1 if every a[i] (i < n) is finite. Exactly !isfinite over the array, by
 * the IEEE-754 bits: a double is Inf or NaN iff its 11 exponent bits are all
 * ones, and then (bits & EXP) + 2^52 carries into bit 63; for every finite
 * double it stays below 2^63. Branch-free integer work with four
 * accumulators: the per-evaluation checks of y and ydot (over 1 000 unknowns
 * with 432 contact slots) cost several times less than an isfinite loop. */
static inline int cd_all_finite(const double *a, int n)
{
    const uint64_t EXP = UINT64_C(0x7ff0000000000000), ONE = UINT64_C(1) << 52;
    uint64_t c0 = 0, c1 = 0, c2 = 0, c3 = 0, u0, u1, u2, u3;
    int i = 0;
    for (; i + 4 <= n; i += 4) {
        memcpy(&u0, a + i, 8); memcpy(&u1, a + i + 1, 8); memcpy(&u2, a + i + 2, 8); memcpy(&u3, a + i + 3, 8);
        c0 |= (u0 & EXP) + ONE; c1 |= (u1 & EXP) + ONE; c2 |= (u2 & EXP) + ONE; c3 |= (u3 & EXP) + ONE;
    }
    for (; i < n; i++) { memcpy(&u0, a + i, 8); c0 |= (u0 & EXP) + ONE; }
    return !((c0 | c1 | c2 | c3) >> 63);
}

/* ---- 3-vectors ---------------------------------------------------------- */
static inline void cd_v3_set(double r[3], double x, double y, double z) { r[0] = x; r[1] = y; r[2] = z; }
static inline void cd_v3_copy(double r[3], const double a[3]) { r[0] = a[0]; r[1] = a[1]; r[2] = a[2]; }
static inline void cd_v3_zero(double r[3]) { r[0] = r[1] = r[2] = 0.0; }
static inline void cd_v3_add(double r[3], const double a[3], const double b[3])
{ r[0] = a[0] + b[0]; r[1] = a[1] + b[1]; r[2] = a[2] + b[2]; }
static inline void cd_v3_sub(double r[3], const double a[3], const double b[3])
{ r[0] = a[0] - b[0]; r[1] = a[1] - b[1]; r[2] = a[2] - b[2]; }
static inline void cd_v3_scale(double r[3], const double a[3], double s)
{ r[0] = a[0] * s; r[1] = a[1] * s; r[2] = a[2] * s; }
/* r += s a */
static inline void cd_v3_axpy(double r[3], double s, const double a[3])
{ r[0] += s * a[0]; r[1] += s * a[1]; r[2] += s * a[2]; }
static inline double cd_v3_dot(const double a[3], const double b[3])
{ return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static inline double cd_v3_norm(const double a[3]) { return sqrt(cd_v3_dot(a, a)); }
/* r = a x b; r may alias neither a nor b */
static inline void cd_v3_cross(double r[3], const double a[3], const double b[3])
{
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
}
/* Normalises in place; returns the old norm (0 leaves a untouched). */
static inline double cd_v3_normalize(double a[3])
{
    double n = cd_v3_norm(a);
    if (n > 0.0) { a[0] /= n; a[1] /= n; a[2] /= n; }
    return n;
}
static inline int cd_v3_isfinite(const double a[3])
{ return isfinite(a[0]) && isfinite(a[1]) && isfinite(a[2]); }

/* ---- 3x3 matrices, row-major ------------------------------------------- */
static inline void cd_m3_identity(double R[9])
{ memset(R, 0, 9 * sizeof(double)); R[0] = R[4] = R[8] = 1.0; }
static inline void cd_m3_copy(double R[9], const double A[9]) { memcpy(R, A, 9 * sizeof(double)); }
/* r = A a */
static inline void cd_m3_mulv(double r[3], const double A[9], const double a[3])
{
    r[0] = A[0] * a[0] + A[1] * a[1] + A[2] * a[2];
    r[1] = A[3] * a[0] + A[4] * a[1] + A[5] * a[2];
    r[2] = A[6] * a[0] + A[7] * a[1] + A[8] * a[2];
}
/* r = A^T a */
static inline void cd_m3_tmulv(double r[3], const double A[9], const double a[3])
{
    r[0] = A[0] * a[0] + A[3] * a[1] + A[6] * a[2];
    r[1] = A[1] * a[0] + A[4] * a[1] + A[7] * a[2];
    r[2] = A[2] * a[0] + A[5] * a[1] + A[8] * a[2];
}
/* C = A B (C must not alias A or B) */
static inline void cd_m3_mul(double C[9], const double A[9], const double B[9])
{
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            C[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
}
/* C = A B A^T for symmetric B (inertia rotation); C must not alias A or B */
static inline void cd_m3_rotsym(double C[9], const double A[9], const double B[9])
{
    double T[9];
    int i, j;
    cd_m3_mul(T, A, B);
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            C[3 * i + j] = T[3 * i] * A[3 * j] + T[3 * i + 1] * A[3 * j + 1] + T[3 * i + 2] * A[3 * j + 2];
}
/* Rotation by angle th about the unit axis a (Rodrigues). */
static inline void cd_m3_axis_angle(double R[9], const double a[3], double th)
{
    double c = cos(th), s = sin(th), v = 1.0 - c;
    R[0] = c + a[0] * a[0] * v;        R[1] = a[0] * a[1] * v - a[2] * s; R[2] = a[0] * a[2] * v + a[1] * s;
    R[3] = a[1] * a[0] * v + a[2] * s; R[4] = c + a[1] * a[1] * v;        R[5] = a[1] * a[2] * v - a[0] * s;
    R[6] = a[2] * a[0] * v - a[1] * s; R[7] = a[2] * a[1] * v + a[0] * s; R[8] = c + a[2] * a[2] * v;
}
/* Rotation matrix from roll, pitch, yaw [rad]: R = Rz(yaw) Ry(pitch) Rx(roll)
 * (fixed axes X, then Y, then Z). SpaceDyn's rpy2dc(r,p,y)' is Rx Ry Rz =
 * cd_m3_from_rpy(-r,-p,-y)' -- not a plain transpose; see docs/dynamics.md. */
static inline void cd_m3_from_rpy(double R[9], double roll, double pitch, double yaw)
{
    double cr = cos(roll), sr = sin(roll), cp = cos(pitch), sp = sin(pitch);
    double cy = cos(yaw), sy = sin(yaw);
    R[0] = cy * cp; R[1] = cy * sp * sr - sy * cr; R[2] = cy * sp * cr + sy * sr;
    R[3] = sy * cp; R[4] = sy * sp * sr + cy * cr; R[5] = sy * sp * cr - cy * sr;
    R[6] = -sp;     R[7] = cp * sr;                R[8] = cp * cr;
}

/* ---- quaternions (w, x, y, z), active rotation body -> world ------------- */
/* q / |q| in place, for a q given by a user (any scale). Where |q|^2
 * overflows or underflows (components of 1e200 or 1e-200) it is formed after
 * scaling q by its largest component; otherwise directly, so that a q of
 * ordinary size gives the same bits as the plain division. Returns 0 and
 * leaves q as it was for a zero or non-finite q. */
static inline int cd_quat_normalize(double q[4])
{
    double n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], mx = 0, s[4];
    int i;
    if (!(isfinite(n2) && n2 >= DBL_MIN)) {
        for (i = 0; i < 4; i++)
            if (fabs(q[i]) > mx) mx = fabs(q[i]);
        if (!(mx > 0) || !isfinite(mx)) return 0;
        for (i = 0; i < 4; i++) s[i] = q[i] / mx;
        n2 = s[0] * s[0] + s[1] * s[1] + s[2] * s[2] + s[3] * s[3];
        for (i = 0; i < 4; i++) q[i] = s[i];
    }
    n2 = sqrt(n2);
    for (i = 0; i < 4; i++) q[i] /= n2;
    return 1;
}
static inline void cd_quat_to_m3(double R[9], const double qin[4])
{
    double n = sqrt(qin[0] * qin[0] + qin[1] * qin[1] + qin[2] * qin[2] + qin[3] * qin[3]);
    double w = qin[0] / n, x = qin[1] / n, y = qin[2] / n, z = qin[3] / n;
    R[0] = 1 - 2 * (y * y + z * z); R[1] = 2 * (x * y - w * z);     R[2] = 2 * (x * z + w * y);
    R[3] = 2 * (x * y + w * z);     R[4] = 1 - 2 * (x * x + z * z); R[5] = 2 * (y * z - w * x);
    R[6] = 2 * (x * z - w * y);     R[7] = 2 * (y * z + w * x);     R[8] = 1 - 2 * (x * x + y * y);
}
/* Quaternion of a proper rotation matrix (Shepperd's method), w >= 0. */
static inline void cd_m3_to_quat(double q[4], const double R[9])
{
    double tr = R[0] + R[4] + R[8], s;
    if (tr > 0) {
        s = 2.0 * sqrt(tr + 1.0);
        q[0] = 0.25 * s; q[1] = (R[7] - R[5]) / s; q[2] = (R[2] - R[6]) / s; q[3] = (R[3] - R[1]) / s;
    } else if (R[0] > R[4] && R[0] > R[8]) {
        s = 2.0 * sqrt(1.0 + R[0] - R[4] - R[8]);
        q[0] = (R[7] - R[5]) / s; q[1] = 0.25 * s; q[2] = (R[1] + R[3]) / s; q[3] = (R[2] + R[6]) / s;
    } else if (R[4] > R[8]) {
        s = 2.0 * sqrt(1.0 + R[4] - R[0] - R[8]);
        q[0] = (R[2] - R[6]) / s; q[1] = (R[1] + R[3]) / s; q[2] = 0.25 * s; q[3] = (R[5] + R[7]) / s;
    } else {
        s = 2.0 * sqrt(1.0 + R[8] - R[0] - R[4]);
        q[0] = (R[3] - R[1]) / s; q[1] = (R[2] + R[6]) / s; q[2] = (R[5] + R[7]) / s; q[3] = 0.25 * s;
    }
    if (q[0] < 0) { q[0] = -q[0]; q[1] = -q[1]; q[2] = -q[2]; q[3] = -q[3]; }
}
/* Time derivative of q for an angular velocity w given in WORLD coordinates:
 * qdot = 1/2 [0, w] (x) q. */
static inline void cd_quat_deriv_world(double qd[4], const double q[4], const double w[3])
{
    qd[0] = 0.5 * (-w[0] * q[1] - w[1] * q[2] - w[2] * q[3]);
    qd[1] = 0.5 * (w[0] * q[0] + w[1] * q[3] - w[2] * q[2]);
    qd[2] = 0.5 * (w[1] * q[0] + w[2] * q[1] - w[0] * q[3]);
    qd[3] = 0.5 * (w[2] * q[0] + w[0] * q[2] - w[1] * q[1]);
}

/* ---- small dense SPD solve --------------------------------------------------
 * In-place Cholesky H = L L^T (lower triangle of the row-major n x n H
 * overwritten by L) and the solve of H x = b in place. Why not GSL's
 * gsl_linalg_cholesky_decomp1: on a matrix that is not positive definite in
 * floating point it calls GSL's error handler, whose default aborts the
 * process, and the library must never abort nor change that process-wide
 * handler. Returns -1 (nothing solved) when a pivot is not positive, or is
 * below n eps times its diagonal entry (numerically singular). */
/* Number of entries of the increasing array t[0..n) that are <= x: the
 * index of the first time after x (binary search). Schedules, waypoints and
 * breakpoints are all found with it. */
static inline int cd_count_le(const double *t, int n, double x)
{
    int lo = 0, hi = n;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (t[mid] <= x) lo = mid + 1; else hi = mid;
    }
    return lo;
}

static inline int cd_chol_decomp(double *H, int n)
{
    int i, j, k;
    for (j = 0; j < n; j++) {
        double djj = H[j * n + j], piv = djj;
        for (k = 0; k < j; k++) piv -= H[j * n + k] * H[j * n + k];
        if (!(piv > (double)n * 2.220446049250313e-16 * fabs(djj))) return -1;
        piv = sqrt(piv);
        H[j * n + j] = piv;
        for (i = j + 1; i < n; i++) {
            double s = H[i * n + j];
            for (k = 0; k < j; k++) s -= H[i * n + k] * H[j * n + k];
            H[i * n + j] = s / piv;
        }
    }
    return 0;
}
static inline void cd_chol_solve(const double *L, int n, double *b)
{
    int i, k;
    for (i = 0; i < n; i++) { /* L y = b */
        double s = b[i];
        for (k = 0; k < i; k++) s -= L[i * n + k] * b[k];
        b[i] = s / L[i * n + i];
    }
    for (i = n - 1; i >= 0; i--) { /* L^T x = y */
        double s = b[i];
        for (k = i + 1; k < n; k++) s -= L[k * n + i] * b[k];
        b[i] = s / L[i * n + i];
    }
}

/* ---- spatial (6-D) algebra, Plucker coordinates about one point ---------- */
/* Motion cross motion: r = a x_m b  (a = [w; v]) */
static inline void cd_sv_crossm(double r[6], const double a[6], const double b[6])
{
    double t[3];
    cd_v3_cross(r, a, b);
    cd_v3_cross(r + 3, a, b + 3);
    cd_v3_cross(t, a + 3, b);
    cd_v3_add(r + 3, r + 3, t);
}
/* Motion cross force: r = a x_f f  (f = [n; f]) */
static inline void cd_sv_crossf(double r[6], const double a[6], const double f[6])
{
    double t[3];
    cd_v3_cross(r, a, f);
    cd_v3_cross(t, a + 3, f + 3);
    cd_v3_add(r, r, t);
    cd_v3_cross(r + 3, a, f + 3);
}
static inline double cd_sv_dot(const double a[6], const double b[6])
{ return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] + a[4] * b[4] + a[5] * b[5]; }

/* A rigid body's spatial inertia about the reference point, kept compactly as
 * mass m, first moment h = m c (c: CoM relative to the reference point) and the
 * rotational inertia Io about the reference point (symmetric 3x3). */
typedef struct { double m; double h[3]; double I[9]; } cd_rbi;

/* Build from mass, CoM offset c (world axes, relative to the reference point)
 * and inertia Ic about the CoM (world axes): Io = Ic + m (|c|^2 1 - c c^T). */
static inline void cd_rbi_make(cd_rbi *r, double m, const double c[3], const double Ic[9])
{
    double cc = cd_v3_dot(c, c);
    int i, j;
    r->m = m;
    cd_v3_scale(r->h, c, m);
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            r->I[3 * i + j] = Ic[3 * i + j] + m * ((i == j ? cc : 0.0) - c[i] * c[j]);
}
static inline void cd_rbi_add(cd_rbi *r, const cd_rbi *a)
{
    int i;
    r->m += a->m;
    for (i = 0; i < 3; i++) r->h[i] += a->h[i];
    for (i = 0; i < 9; i++) r->I[i] += a->I[i];
}
/* f = I v for a motion vector v = [w; u]: f = [Io w + h x u; m u - h x w] */
static inline void cd_rbi_mulv(double f[6], const cd_rbi *r, const double v[6])
{
    double t[3];
    cd_m3_mulv(f, r->I, v);
    cd_v3_cross(t, r->h, v + 3);
    cd_v3_add(f, f, t);
    cd_v3_cross(t, r->h, v);
    cd_v3_scale(f + 3, v + 3, r->m);
    cd_v3_sub(f + 3, f + 3, t);
}

#endif
