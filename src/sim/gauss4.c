/* rk4imp: capdyn's implicit 2-stage Gauss-Legendre Runge-Kutta stepper.
 *
 * Why capdyn's own: until now "rk4imp" was GSL's gsl_odeiv2_step_rk4imp,
 * the same method, whose Newton solve calls gsl_linalg_LU_decomp, and GSL
 * 2.7's LU allocates its pivot vector on every call: an allocation in every
 * step (and an abort when malloc fails), against the rule that no step
 * allocates. This one keeps every buffer in the data's workspace and uses
 * rosw.c's in-place LU.
 *
 * The method (Hairer & Wanner, Solving Ordinary Differential Equations II,
 * 2nd ed., Springer 1996, sec. IV.5, Table 5.1; Butcher 1964): s = 2,
 *   c = 1/2 -+ sqrt(3)/6,  A = [1/4, 1/4 - sqrt(3)/6; 1/4 + sqrt(3)/6, 1/4],
 *   b = (1/2, 1/2);
 * order 4, A-stable (|R(z)| <= 1 on Re z <= 0, R(-inf) = 1: not L-stable),
 * symmetric. The stage equations in Z_i = Y_i - y0,
 *   Z_i = h sum_j a_ij f(t + c_j h, y0 + Z_j),
 * are solved by the simplified Newton iteration of H&W sec. IV.8 (starting
 * from Z = 0):
 *   (I - h A (x) J) dZ = -Z + h (A (x) I) F(Z),   Z += dZ,
 * with one real 2na x 2na matrix on the active set (the unknowns outside it,
 * whose rows the Jacobian leaves out, take dZ = the residual: a fixed-point
 * step, exact for the open slots' deflections, whose derivative is 0). J is
 * rosw.c's (cd_rosw_jacobian): by default the structured model Jacobian on
 * the active set (simulation.jacobian = "model"), else forward differences
 * with opt.fd_eps; it is kept CD_ROSW_JAC_AGE steps, renewed after a restart
 * and after a Newton failure. J only steers the iteration: the converged
 * stages, and so the order, do not depend on it. The iteration stops when
 * its estimated remaining error eta |dZ| (eta = theta / (1 - theta), theta
 * the contraction |dZ_k| / |dZ_k-1|, the norm scaled by atol + rtol |y|) is
 * below CD_GAUSS4_KAPPA; it fails (GSL_FAILURE: GSL's evolve halves the
 * step and retries) when theta >= 0.99 (no contraction) or after
 * CD_GAUSS4_NEWTON_MAX iterations. A non-finite Newton increment (or one
 * so large that its scaled norm overflows) or solution is GSL_EBADFUNC, as
 * a non-finite stage of an explicit stepper: the driver retries with a
 * quarter of the step and stops with CD_ENUMERIC below h_min (integrator.c).
 * The solution is y1 = y0 + d1 Z1 + d2 Z2 with d = b^T A^-1 = (-sqrt 3, sqrt 3)
 * (H&W IV.8, (8.2b)): no evaluation of f, and the residual of a stiff
 * component is not amplified by h lambda.
 *
 * The error estimate is step doubling, as GSL's rk4imp: one step of h and
 * two of h/2 from the same start; the result is the two half steps', its
 * error (y_half - y_full) / (2^4 - 1) (Richardson, H&W I, sec. II.4), of
 * O(h^5), so order() returns 4 for GSL's standard control. A step so costs
 * three stage solves of 2 evaluations per Newton iteration (often 2-4
 * iterations), one evaluation for dydt_out (the exact f(t + h, y1), GSL's
 * evolve hands it back as the next dydt_in), two LU factorizations of
 * 2na x 2na (for h and h/2, kept while the step and the Jacobian are the
 * same), plus the Jacobian when it is renewed. */
#include "gauss4.h"

#include <float.h>
#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define S3 1.7320508075688772935 /* sqrt(3) */
static const double G_C[2] = {0.5 - S3 / 6.0, 0.5 + S3 / 6.0};
static const double G_A[2][2] = {{0.25, 0.25 - S3 / 6.0}, {0.25 + S3 / 6.0, 0.25}};
static const double G_D[2] = {-S3, S3}; /* b^T A^-1 */

static size_t buf_size(size_t n, size_t na2)
{
    return 16 + (2 * na2 * na2 + 15 * n + na2) * sizeof(double) + 2 * na2 * sizeof(int) + 16;
}

static void carve(cd_gauss4 *g, void *mem, size_t n, size_t na2)
{
    double *p = (double *)(void *)(((uintptr_t)mem + 15) & ~(uintptr_t)15);
    g->M[0] = p; p += na2 * na2;
    g->M[1] = p; p += na2 * na2;
    g->z1 = p; p += n; g->z2 = p; p += n; g->dz1 = p; p += n; g->dz2 = p; p += n;
    g->f1 = p; p += n; g->f2 = p; p += n; g->yt = p; p += n; g->ybig = p; p += n;
    g->ymid = p; p += n; g->f0 = p; p += n;
    g->za1 = p; p += n; g->za2 = p; p += n; g->zb1 = p; p += n; g->zb2 = p; p += n;
    g->r = p; p += na2;
    g->piv[0] = (int *)(void *)p;
    g->piv[1] = g->piv[0] + na2;
}

size_t cd_gauss4_size(const cd_model *m)
{
    size_t n = (size_t)(m->ny ? m->ny : 1), na2 = 2 * ((size_t)cd_rosw_na_max(m) + 1);
    return buf_size(n, na2);
}

void cd_gauss4_init(cd_gauss4 *g, cd_rosw *rw, const cd_model *m, void *mem)
{
    size_t n = (size_t)(m->ny ? m->ny : 1), na2 = 2 * ((size_t)cd_rosw_na_max(m) + 1);
    memset(g, 0, sizeof *g);
    g->rw = rw;
    g->ny = m->ny;
    g->na2_max = (int)na2;
    g->eta = 1.0;
    carve(g, mem, n, na2);
}

size_t cd_gauss4_size_plain(int ny)
{
    size_t n = (size_t)(ny > 0 ? ny : 1);
    return buf_size(n, 2 * n + 2);
}

void cd_gauss4_init_plain(cd_gauss4 *g, cd_rosw *rw, int ny, double rtol, double atol, void *mem)
{
    size_t n = (size_t)(ny > 0 ? ny : 1);
    memset(g, 0, sizeof *g);
    g->rw = rw;
    g->ny = ny;
    g->na2_max = (int)(2 * n + 2);
    g->rtol = rtol;
    g->atol = atol;
    g->eta = 1.0;
    carve(g, mem, n, 2 * n + 2);
}

/* The starting values of H&W IV.8 (8.5): the collocation polynomial w of a
 * solved step (w(0) = 0, w(c_i) = Z_i, in units of that step) through
 * (za1, za2), read at tau_i: z_i = base + w(tau_i) - w(tau0). base may be
 * NULL (0). */
static void predict(int n, const double *za1, const double *za2, const double *base, double tau0,
                    const double tau[2], double *z1, double *z2)
{
    const double c1 = G_C[0], c2 = G_C[1];
    double l1[3], l2[3], t3[3] = {tau0, tau[0], tau[1]};
    int i, c;
    for (i = 0; i < 3; i++) {
        l1[i] = t3[i] * (t3[i] - c2) / (c1 * (c1 - c2));
        l2[i] = t3[i] * (t3[i] - c1) / (c2 * (c2 - c1));
    }
    for (c = 0; c < n; c++) {
        double w0 = l1[0] * za1[c] + l2[0] * za2[c], b = base ? base[c] : 0.0;
        z1[c] = b + l1[1] * za1[c] + l2[1] * za2[c] - w0;
        z2[c] = b + l1[2] * za1[c] + l2[2] * za2[c] - w0;
    }
}

/* LU of I - h A (x) J on the active set into slot k */
static int factor(cd_gauss4 *g, int k, double h)
{
    const cd_rosw *w = g->rw;
    int na = w->na, n2 = 2 * na, bi, bj, a, c;
    double *M = g->M[k];
    for (bi = 0; bi < 2; bi++)
        for (bj = 0; bj < 2; bj++) {
            double s = -h * G_A[bi][bj];
            for (a = 0; a < na; a++) {
                double *row = M + (size_t)(bi * na + a) * (size_t)n2 + (size_t)bj * na;
                const double *Ja = w->J + (size_t)a * (size_t)na;
                for (c = 0; c < na; c++) row[c] = s * Ja[c];
                if (bi == bj) row[a] += 1.0;
            }
        }
    g->lu_h[k] = 0;
    if (n2 && cd_rosw_lu_decomp(M, n2, g->piv[k]) != 0) return GSL_FAILURE;
    g->lu_h[k] = h;
    return GSL_SUCCESS;
}

/* the scaled RMS norm of (dz1, dz2) */
static double znorm(const cd_gauss4 *g, const double *y0, int n)
{
    double acc = 0;
    int c;
    for (c = 0; c < n; c++) {
        double sc = g->atol + g->rtol * fabs(y0[c]), q;
        /* never ask below round-off: the increments stop at ~ eps |y| */
        if (sc < 1e4 * DBL_EPSILON * fabs(y0[c])) sc = 1e4 * DBL_EPSILON * fabs(y0[c]);
        q = g->dz1[c] / sc;
        acc += q * q;
        q = g->dz2[c] / sc;
        acc += q * q;
    }
    return n ? sqrt(acc / (2.0 * n)) : 0.0;
}

/* Solves the stage equations of one step (t, h) from y0 with LU slot k,
 * starting from the guess in z1, z2 (left there converged), and writes
 * y0 + d^T Z to y1. */
static int stage_solve(cd_gauss4 *g, int k, double t, double h, const double *y0, double *y1,
                       const gsl_odeiv2_system *sys)
{
    const cd_rosw *w = g->rw;
    int n = g->ny, na = w->na, it, a, c;
    double prev = 0, eta = pow(fmax(g->eta, DBL_EPSILON), 0.8), theta;
    for (it = 0; it < CD_GAUSS4_NEWTON_MAX; it++) {
        double dn;
        g->nnewton++;
        for (c = 0; c < n; c++) g->yt[c] = y0[c] + g->z1[c];
        if (GSL_ODEIV_FN_EVAL(sys, t + G_C[0] * h, g->yt, g->f1) != GSL_SUCCESS) return GSL_EBADFUNC;
        for (c = 0; c < n; c++) g->yt[c] = y0[c] + g->z2[c];
        if (GSL_ODEIV_FN_EVAL(sys, t + G_C[1] * h, g->yt, g->f2) != GSL_SUCCESS) return GSL_EBADFUNC;
        /* the residuals: the full correction of the unknowns outside the active set */
        for (c = 0; c < n; c++) {
            g->dz1[c] = -g->z1[c] + h * (G_A[0][0] * g->f1[c] + G_A[0][1] * g->f2[c]);
            g->dz2[c] = -g->z2[c] + h * (G_A[1][0] * g->f1[c] + G_A[1][1] * g->f2[c]);
        }
        if (na) {
            for (a = 0; a < na; a++) {
                g->r[a] = g->dz1[w->act[a]];
                g->r[na + a] = g->dz2[w->act[a]];
            }
            cd_rosw_lu_solve(g->M[k], 2 * na, g->piv[k], g->r);
            for (a = 0; a < na; a++) {
                g->dz1[w->act[a]] = g->r[a];
                g->dz2[w->act[a]] = g->r[na + a];
            }
        }
        dn = znorm(g, y0, n);
        /* a non-finite increment (or one beyond ~1e154 tolerances, whose
         * square overflows): a non-finite value inside the trial step, as an
         * explicit stepper's overflowing stage */
        if (!isfinite(dn)) return GSL_EBADFUNC;
        if (it > 0) {
            theta = prev > 0 ? dn / prev : 0.0;
            if (theta >= 0.99) return GSL_FAILURE;
            eta = theta / (1.0 - theta);
        }
        for (c = 0; c < n; c++) {
            g->z1[c] += g->dz1[c];
            g->z2[c] += g->dz2[c];
        }
        prev = dn;
        if (eta * dn <= CD_GAUSS4_KAPPA || dn == 0) {
            g->eta = eta;
            for (c = 0; c < n; c++) {
                y1[c] = y0[c] + G_D[0] * g->z1[c] + G_D[1] * g->z2[c];
                if (!isfinite(y1[c])) return GSL_EBADFUNC;
            }
            return GSL_SUCCESS;
        }
    }
    return GSL_FAILURE;
}

typedef struct {
    cd_gauss4 *g;
    int have_prev;
    double t_prev;
} gauss_state;

static void *gauss_alloc(size_t dim)
{
    gauss_state *s = (gauss_state *)calloc(1, sizeof *s);
    (void)dim;
    if (!s) GSL_ERROR_NULL("failed to allocate the Gauss stepper state", GSL_ENOMEM);
    return s;
}

/* the LU slot for the step h: 0 for the full step, 1 for the half */
static int ensure_lu(cd_gauss4 *g, int k, double h)
{
    if (g->lu_h[k] == h) return GSL_SUCCESS;
    return factor(g, k, h);
}

static int gauss_apply(void *vs, size_t dim, double t, double h, double y[], double yerr[], const double dydt_in[],
                       double dydt_out[], const gsl_odeiv2_system *sys)
{
    gauss_state *s = (gauss_state *)vs;
    cd_gauss4 *g = s->g;
    cd_rosw *w;
    int n = (int)dim, c, st, retry;
    double h2 = 0.5 * h;
    if (!g || n != g->ny) return GSL_EINVAL;
    w = g->rw;
    if (w->d) { /* the Newton tolerance: the run's */
        g->rtol = w->d->opt.rtol;
        g->atol = w->d->opt.atol;
    }
    retry = s->have_prev && s->t_prev == t;
    if (!w->jac_ok || w->jac_age >= CD_ROSW_JAC_AGE || (retry && g->renew && w->jac_t != t)) {
        const double *f0 = dydt_in;
        if (!f0) {
            if (GSL_ODEIV_FN_EVAL(sys, t, y, g->f0) != GSL_SUCCESS) return GSL_EBADFUNC;
            f0 = g->f0;
        }
        if (cd_rosw_jacobian(w, t, y, f0, sys) != GSL_SUCCESS) return GSL_EBADFUNC;
        g->lu_h[0] = g->lu_h[1] = 0;
    }
    s->have_prev = 1;
    s->t_prev = t;
    g->renew = 1; /* cleared when the step succeeds */
    if (ensure_lu(g, 0, h) != GSL_SUCCESS || ensure_lu(g, 1, h2) != GSL_SUCCESS) return GSL_FAILURE;
    /* two half steps, then the full one, all from y (kept until success);
     * each starts from the collocation polynomial of a step solved before */
    if (g->have_pred && g->t_next == t && g->h_pred > 0) {
        double tau[2] = {1.0 + G_C[0] * h2 / g->h_pred, 1.0 + G_C[1] * h2 / g->h_pred};
        predict(n, g->zb1, g->zb2, NULL, 1.0, tau, g->z1, g->z2);
    } else {
        memset(g->z1, 0, (size_t)n * sizeof(double));
        memset(g->z2, 0, (size_t)n * sizeof(double));
    }
    g->have_pred = 0;
    st = stage_solve(g, 1, t, h2, y, g->ymid, sys);
    if (st == GSL_SUCCESS) {
        const double tau[2] = {1.0 + G_C[0], 1.0 + G_C[1]};
        memcpy(g->za1, g->z1, (size_t)n * sizeof(double));
        memcpy(g->za2, g->z2, (size_t)n * sizeof(double));
        predict(n, g->za1, g->za2, NULL, 1.0, tau, g->z1, g->z2);
        st = stage_solve(g, 1, t + h2, h2, g->ymid, g->yt, sys);
    }
    if (st == GSL_SUCCESS) {
        /* the full step's stages at c_1 h (in the first half, tau = 2 c_1)
         * and c_2 h (in the second, tau = 2 c_2 - 1, on top of ymid - y) */
        const double ta[2] = {2.0 * G_C[0], 2.0 * G_C[0]}, tb[2] = {2.0 * G_C[1] - 1.0, 2.0 * G_C[1] - 1.0};
        memcpy(g->zb1, g->z1, (size_t)n * sizeof(double));
        memcpy(g->zb2, g->z2, (size_t)n * sizeof(double));
        for (c = 0; c < n; c++) g->f0[c] = g->ymid[c] - y[c];
        predict(n, g->za1, g->za2, NULL, 0.0, ta, g->z1, g->dz1);
        predict(n, g->zb1, g->zb2, g->f0, 0.0, tb, g->dz2, g->z2);
        memcpy(g->ymid, g->yt, (size_t)n * sizeof(double)); /* y after the two halves */
        st = stage_solve(g, 0, t, h, y, g->ybig, sys);
    }
    if (st != GSL_SUCCESS) {
        g->nfail++;
        g->eta = 1.0;
        return st;
    }
    for (c = 0; c < n; c++) {
        yerr[c] = (g->ymid[c] - g->ybig[c]) / 15.0;
        y[c] = g->ymid[c];
    }
    g->renew = 0;
    g->have_pred = 1;
    g->t_next = t + h;
    g->h_pred = h2;
    w->jac_age++;
    if (dydt_out && GSL_ODEIV_FN_EVAL(sys, t + h, y, dydt_out) != GSL_SUCCESS) return GSL_EBADFUNC;
    return GSL_SUCCESS;
}

static int gauss_set_driver(void *vs, const gsl_odeiv2_driver *d)
{
    (void)vs;
    (void)d;
    return GSL_SUCCESS;
}

static int gauss_reset(void *vs, size_t dim)
{
    gauss_state *s = (gauss_state *)vs;
    (void)dim;
    s->have_prev = 0;
    if (s->g) {
        cd_rosw_invalidate(s->g->rw);
        s->g->lu_h[0] = s->g->lu_h[1] = 0;
        s->g->eta = 1.0;
        s->g->renew = 0;
        s->g->have_pred = 0;
    }
    return GSL_SUCCESS;
}

static unsigned int gauss_order(void *vs)
{
    (void)vs;
    return 4u;
}

static void gauss_free(void *vs) { free(vs); }

static const gsl_odeiv2_step_type gauss_type = {"rk4imp", 1, 1, gauss_alloc, gauss_apply, gauss_set_driver,
                                                gauss_reset, gauss_order, gauss_free};
const gsl_odeiv2_step_type *cd_step_gauss4 = &gauss_type;

void cd_gauss4_bind(gsl_odeiv2_step *s, cd_gauss4 *g)
{
    gauss_state *st = (gauss_state *)s->state;
    st->g = g;
    st->have_prev = 0;
    g->lu_h[0] = g->lu_h[1] = 0;
    g->have_pred = 0;
}
