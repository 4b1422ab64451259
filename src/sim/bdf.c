/* msbdf: capdyn's variable-order (1-5), variable-step BDF stepper.
 *
 * Why capdyn's own: until now "msbdf" was GSL's gsl_odeiv2_step_msbdf,
 * whose Newton solve calls gsl_linalg_LU_decomp, and GSL 2.7's LU allocates
 * its pivot vector on every call: an allocation inside steps (and an abort
 * when malloc fails), against the rule that no step allocates. This one
 * keeps every buffer in the data's workspace and uses rosw.c's in-place LU.
 *
 * The method: the backward differentiation formulas in their variable-
 * coefficient form (Hairer, Norsett & Wanner, Solving ODEs I, 2nd ed., 1993,
 * sec. III.5, "variable step size BDF", eq. (5.18); Hairer & Wanner II, 2nd
 * ed., 1996, sec. V.1 for their stability; the same form as DASSL, Brenan,
 * Campbell & Petzold 1989, ch. 5). The step of order k from t_n to
 * t_{n+1} = t_n + h asks that the polynomial q of degree k through
 * y_{n+1}, y_n, ..., y_{n+1-k} (at their own, unequal times) satisfy
 *   q'(t_{n+1}) = f(t_{n+1}, y_{n+1}),  i.e.  sum_j alpha_j y_{n+1-j} = f,
 * alpha_j the derivatives at t_{n+1} of the Lagrange basis on those times,
 * alpha_0 = sum_{j=1..k} 1/H_j, H_j = t_{n+1} - t_{n+1-j}. With
 * gamma = 1/alpha_0 the equation Y - gamma f(Y) + gamma psi = 0 (psi the
 * history's part) is solved by the simplified Newton iteration with the
 * matrix I - gamma J on the active set (the unknowns outside it, whose rows
 * the Jacobian leaves out, take the residual as increment), J rosw.c's
 * (cd_rosw_jacobian: the structured model Jacobian, or forward differences
 * with simulation.jacobian = "fd"), kept CD_ROSW_JAC_AGE steps, renewed
 * after a restart and after a Newton failure; the LU is kept while gamma
 * changes by less than CD_BDF_GAMMA_TOL, and a Newton failure with an old
 * LU or Jacobian is retried once with the step's own, J renewed at (t, y)
 * (J and the LU only steer the
 * iteration: the converged Y, and so the order, do not depend on them). The
 * iteration starts from the predictor (below) and stops when its estimated
 * remaining error eta |dY| (eta = theta/(1 - theta), theta the contraction,
 * the norm scaled by atol + rtol |y|) is below CD_BDF_KAPPA; it fails
 * (GSL_FAILURE: GSL's evolve halves the step) when theta >= 0.99 or after
 * CD_BDF_NEWTON_MAX iterations. A non-finite f, increment or solution is
 * GSL_EBADFUNC, as in gauss4.c (the driver retries with a quarter of the
 * step, then stops with CD_ENUMERIC below h_min).
 *
 * The error estimate: the predictor is the polynomial through the k + 1
 * newest accepted points, extrapolated to t_{n+1} (after a restart, when
 * only y_n is known: y_n + h f_n). Its error is y^(k+1)/(k+1)! prod_{j=1..k+1}
 * H_j, the corrector's y^(k+1)/(k+1)! prod_{j=1..k} H_j / alpha_0, so
 *   err = (y_{n+1} - y_pred) / (H_{k+1} alpha_0),
 * which is the classical -h^2/2 y'' for k = 1 and -2/9 h^3 y''' for k = 2 at
 * constant steps; it is O(h^(k+1)), and order() returns the k of the last
 * step, so GSL's standard control picks the next step for it.
 *
 * The order: a restart begins at order 1 and the history grows by one point
 * per step. After each accepted step the errors the orders k-1, k and k+1
 * would make at the same step are estimated from the divided differences of
 * the newest points, E_q ~ |y[t_{n+1}, ..., t_{n-q}]| q! h^(q+1) / (1 + ... +
 * 1/q) (the constant-step error constant), and the order whose step
 * (1/E_q)^(1/(q+1)) is the largest is taken, lowering at once and raising
 * only after k + 1 steps at order k (the strategy of DASSL, Brenan et al.
 * sec. 5.2). Three error-test rejections in a row drop to order 1.
 * Zero-stability of variable steps: above order 1 a step more than
 * CD_BDF_RATIO_MAX = 1.5 times the last one is refused at once (GSL_FAILURE,
 * before any evaluation; evolve halves it and retries), so the step grows by
 * at most 1.5x per step (GSL's control would raise it by up to 5x when the
 * error is tiny). Variable-step BDF of order k >= 3 is zero-stable only for
 * step ratios near 1 (H&W I, sec. III.5; BDF2 up to 1 + sqrt 2, Grigorieff
 * 1983). Measured on the Fig. 5 grasp at rtol 1e-10 (tests/test_bdf.c): with
 * a limit of 2 the run made 50 events instead of rk8pd's 44 and its
 * coordinates differed by 1.4e-6; with 1.5, 44 events and 1.5e-9 (capping
 * the order at 3 with the limit 2 also gave 44, capping at 4 gave 48).
 * These refusals are counted in nratio (and by evolve as failed steps).
 *
 * Stability: BDF1 and BDF2 are L-stable (A-stable with R(-inf) = 0), BDF3-5
 * A(alpha)-stable with alpha = 86.0, 73.4, 51.8 degrees (H&W II, Table V.2.1):
 * stiff decays are damped, but lightly damped stiff oscillations (eigenvalues
 * near the imaginary axis) at orders 3-5 can be amplified: there the error
 * test rejects and the order falls.
 *
 * Communication with GSL's evolve: a step is applied once, and only the next
 * call tells whether evolve accepted it (a call at its end) or rejected it
 * (a call at its start with a smaller step); the history therefore holds
 * accepted points only, the newest being the state evolve passes in (after
 * capdyn's quaternion renormalisation). A call at any other time restarts
 * the history; so does reset() (events, breakpoints, snapshots: the
 * integrator's restarts).
 *
 * Event location (cd_bdf_trial): the integrator's locator asks for the
 * solution at t0 + tau inside an accepted step from t0; msbdf gives the BDF
 * step of that length from the same history (the step it would have taken),
 * its Newton iteration carried to CD_BDF_KAPPA_TRIAL so that the located
 * state is smooth in tau, the history untouched. The event then restarts the
 * history anyway.
 *
 * Cost per step: one evaluation per Newton iteration (often 1-3), one for
 * dydt_out (the exact f(t + h, y1), handed back by evolve as the next
 * dydt_in) unless the Newton iteration ended on the iterate it had just
 * evaluated (newton(): within kappa by the contraction bound), an LU only
 * when gamma moved by > 30% or J was renewed (of the velocities' block,
 * nU x nU, when J is the structured one: the reduction of rosw.c, exact for
 * the matrix I - gamma J; else of na x na), the Jacobian every
 * CD_ROSW_JAC_AGE steps. */
#include "bdf.h"
#include "../math/cd_math.h"

#include <float.h>
#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static size_t buf_size(size_t n, size_t na)
{
    return 16 + ((CD_BDF_NHIST + 6) * n + na * na + 3 * na) * sizeof(double) + na * sizeof(int) + 16;
}

static void carve(cd_bdf *g, void *mem, size_t n, size_t na)
{
    double *p = (double *)(void *)(((uintptr_t)mem + 15) & ~(uintptr_t)15);
    int j;
    for (j = 0; j < CD_BDF_NHIST; j++) { g->Y[j] = p; p += n; }
    g->yp = p; p += n; g->F = p; p += n; g->dY = p; p += n; g->f0 = p; p += n; g->psi = p; p += n;
    g->ypred = p; p += n;
    g->M = p; p += na * na;
    g->r = p; p += na;
    g->u = p; p += na;
    g->rpz = p; p += na;
    g->piv = (int *)(void *)p;
}

static void clear(cd_bdf *g)
{
    g->nh = 0;
    g->have_pend = 0;
    g->nrej = 0;
    g->k = g->k_next = g->k_used = 1;
    g->nk = 0;
    g->lu_gamma = 0;
    g->eta = 1.0;
    g->renew = 0;
}

size_t cd_bdf_size(const cd_model *m)
{
    size_t n = (size_t)(m->ny ? m->ny : 1), na = (size_t)cd_rosw_na_max(m) + 1;
    return buf_size(n, na);
}

void cd_bdf_init(cd_bdf *g, cd_rosw *rw, const cd_model *m, void *mem)
{
    size_t n = (size_t)(m->ny ? m->ny : 1), na = (size_t)cd_rosw_na_max(m) + 1;
    memset(g, 0, sizeof *g);
    g->rw = rw;
    g->ny = m->ny;
    g->na_max = (int)na;
    g->kmax = CD_BDF_KMAX;
    carve(g, mem, n, na);
    clear(g);
}

size_t cd_bdf_size_plain(int ny)
{
    size_t n = (size_t)(ny > 0 ? ny : 1);
    return buf_size(n, n + 1);
}

void cd_bdf_init_plain(cd_bdf *g, cd_rosw *rw, int ny, double rtol, double atol, void *mem)
{
    size_t n = (size_t)(ny > 0 ? ny : 1);
    memset(g, 0, sizeof *g);
    g->rw = rw;
    g->ny = ny;
    g->na_max = (int)(n + 1);
    g->rtol = rtol;
    g->atol = atol;
    g->kmax = CD_BDF_KMAX;
    carve(g, mem, n, n + 1);
    clear(g);
}

/* (t, y) becomes the newest accepted point; the oldest drops out when full */
static void push(cd_bdf *g, double t, const double *y)
{
    int j, last = g->nh < CD_BDF_NHIST ? g->nh : CD_BDF_NHIST - 1;
    double *oldest = g->Y[last];
    for (j = last; j > 0; j--) {
        g->Y[j] = g->Y[j - 1];
        g->th[j] = g->th[j - 1];
    }
    g->Y[0] = oldest;
    g->th[0] = t;
    memcpy(g->Y[0], y, (size_t)g->ny * sizeof(double));
    if (g->nh < CD_BDF_NHIST) g->nh++;
}

/* A restart of the history at (t, y): order 1, this point alone */
static void restart_history(cd_bdf *g, double t, const double *y)
{
    g->nh = 0;
    g->k = g->k_next = 1;
    g->nk = 0;
    g->nrej = 0;
    push(g, t, y);
}

void cd_bdf_seed(cd_bdf *g, double t, const double *y)
{
    push(g, t, y);
    g->have_pend = 0;
}

static double scale(const cd_bdf *g, double y)
{
    double sc = g->atol + g->rtol * fabs(y);
    /* never ask below round-off */
    if (sc < 1e4 * DBL_EPSILON * fabs(y)) sc = 1e4 * DBL_EPSILON * fabs(y);
    return sc > 0 ? sc : DBL_MIN;
}

/* LU of I - gamma J on the active set: of the velocities' block alone when
 * the Jacobian is the structured one (rosw.c, reduce(): the positions and
 * anchors move with the velocities, and (I - gamma J) x = r reduces to
 * them exactly), e.g. 14 unknowns instead of 39 on the Fig. 5 grasp */
static int factor(cd_bdf *g, double gamma)
{
    g->lu_gamma = 0;
    if (cd_rosw_factor_c(g->rw, gamma, g->M, g->piv) != 0) return GSL_FAILURE;
    g->lu_gamma = gamma;
    return GSL_SUCCESS;
}

/* Solves Y - gamma f(t1, Y) + psi = 0 (psi already times gamma) for Y,
 * starting from Y = yp; the result is left in yp. The
 * iteration converges at kappa; when it stalls (theta >= 0.99, or
 * CD_BDF_NEWTON_MAX iterations) after an iterate already met kappa_ok >=
 * kappa, that iterate is the result (cd_bdf_trial asks for kappa below
 * the round-off of a tight tolerance; the steps pass kappa_ok = kappa). */
static int newton(cd_bdf *g, double t1, double gamma, const gsl_odeiv2_system *sys, double kappa, double kappa_ok,
                  int *f_at_y)
{
    const cd_rosw *w = g->rw;
    int n = g->ny, na = w->na, it, a, c, met = 0;
    double prev = 0, eta = pow(fmax(g->eta, DBL_EPSILON), 0.8), theta;
    double *Y = g->yp;
    for (it = 0; it < CD_BDF_NEWTON_MAX; it++) {
        double acc = 0, dn;
        g->nnewton++;
        if (GSL_ODEIV_FN_EVAL(sys, t1, Y, g->F) != GSL_SUCCESS) return GSL_EBADFUNC;
        for (c = 0; c < n; c++) g->dY[c] = gamma * g->F[c] - g->psi[c] - Y[c];
        if (na) {
            for (a = 0; a < na; a++) g->r[a] = g->dY[w->act[a]];
            cd_rosw_solve_c(w, g->lu_gamma, g->M, g->piv, g->r, g->u, g->rpz);
            for (a = 0; a < na; a++) g->dY[w->act[a]] = g->r[a];
        }
        for (c = 0; c < n; c++) {
            double q = g->dY[c] / scale(g, g->Y[0][c]);
            acc += q * q;
        }
        dn = n ? sqrt(acc / n) : 0.0;
        if (!isfinite(dn)) return GSL_EBADFUNC;
        if (it > 0) {
            theta = prev > 0 ? dn / prev : 0.0;
            if (theta >= 0.99) return met ? GSL_SUCCESS : GSL_FAILURE;
            eta = theta / (1.0 - theta);
            /* the iterate just evaluated is itself within kappa of the
             * solution (its distance at most |dY| / (1 - theta) by the
             * contraction): it is the result, unmoved, and g->F is exactly
             * f(t1, Y), which the step hands back as its end derivative
             * instead of evaluating f once more */
            if (f_at_y && dn / (1.0 - theta) <= kappa) {
                g->eta = eta;
                if (!cd_all_finite(Y, n)) return GSL_EBADFUNC;
                *f_at_y = 1;
                return GSL_SUCCESS;
            }
        }
        for (c = 0; c < n; c++) Y[c] += g->dY[c];
        prev = dn;
        if (eta * dn <= kappa || dn == 0) {
            g->eta = eta;
            return cd_all_finite(Y, n) ? GSL_SUCCESS : GSL_EBADFUNC;
        }
        if (eta * dn <= kappa_ok) {
            if (!cd_all_finite(Y, n)) return GSL_EBADFUNC;
            met = 1;
        }
    }
    return met ? GSL_SUCCESS : GSL_FAILURE;
}

/* The order for the next step after an accepted step of order k and size h
 * ending at t1 with solution y1 (the history not yet including it). */
static int choose_order(const cd_bdf *g, int k, double h, double t1, const double *y1)
{
    double x[CD_BDF_NHIST + 1], E[CD_BDF_KMAX + 2], cqs[CD_BDF_KMAX + 2];
    /* the order may rise only after k + 1 steps at order k, and not past
     * kmax: otherwise E[k + 1] is not needed, nor the highest divided
     * difference (the lower ones are the same, bit for bit) */
    const int up = k < g->kmax && g->nk + 1 >= k + 1, qmax = up ? k + 1 : k;
    int m = g->nh < qmax + 1 ? g->nh : qmax + 1; /* history points used; m + 1 points in all */
    int q, c, i, j, kn = k;
    double best;
    x[0] = t1;
    for (j = 0; j < m; j++) x[j + 1] = g->th[j];
    double rdx[CD_BDF_NHIST + 1][CD_BDF_NHIST + 1];
    for (q = 0; q <= CD_BDF_KMAX + 1; q++) E[q] = -1;
    /* every order the loop below looks at gets at least the 0 of an unknown
     * whose points are all equal (skipped there: its divided differences are
     * exactly 0); most of a contact model's unknowns are such, the bristles
     * of the open slots */
    for (q = (k > 1 ? k - 1 : 1); q <= qmax && q <= CD_BDF_KMAX; q++)
        if (q + 1 <= m) E[q] = 0;
    /* the differences' denominators' reciprocals, 1 / (x_i - x_{i-j}), once
     * for every unknown (a product per difference, not a division: the
     * divisions made this the stepper's costliest function) */
    for (j = 1; j <= m; j++)
        for (i = m; i >= j; i--) rdx[i][j] = 1.0 / (x[i] - x[i - j]);
    /* and the error constants, q! h^(q+1) / (1 + ... + 1/q) */
    for (q = 1; q <= qmax && q <= CD_BDF_KMAX; q++) {
        double hq = 0;
        cqs[q] = h;
        for (i = 1; i <= q; i++) {
            cqs[q] *= i * h;
            hq += 1.0 / i;
        }
        cqs[q] /= hq;
    }
    for (c = 0; c < g->ny; c++) {
        double v[CD_BDF_NHIST + 1], rsc;
        int moved = 0;
        v[0] = y1[c];
        for (j = 0; j < m; j++) {
            v[j + 1] = g->Y[j][c];
            moved |= v[j + 1] != v[0];
        }
        if (!moved) continue;
        rsc = 1.0 / scale(g, y1[c]);
        /* Newton's divided differences in place: v[i] = y[x_0..x_i] */
        for (j = 1; j <= m; j++)
            for (i = m; i >= j; i--) v[i] = (v[i] - v[i - 1]) * rdx[i][j];
        for (q = (k > 1 ? k - 1 : 1); q <= qmax && q <= CD_BDF_KMAX; q++) {
            double e;
            if (q + 1 > m) continue; /* needs q + 2 points */
            e = fabs(v[q + 1]) * cqs[q] * rsc;
            if (e > E[q]) E[q] = e;
        }
    }
    if (E[k] < 0) return k;
    best = pow(fmax(E[k], 1e-300), -1.0 / (k + 1));
    if (k > 1 && E[k - 1] >= 0 && pow(fmax(E[k - 1], 1e-300), -1.0 / k) >= best) {
        kn = k - 1;
    } else if (up && E[k + 1] >= 0 &&
               pow(fmax(E[k + 1], 1e-300), -1.0 / (k + 2)) > best) {
        kn = k + 1;
    }
    return kn;
}

typedef struct {
    cd_bdf *g;
    int have_prev;
    double t_prev;
} bdf_state;

static void *bdf_alloc(size_t dim)
{
    bdf_state *s = (bdf_state *)calloc(1, sizeof *s);
    (void)dim;
    if (!s) GSL_ERROR_NULL("failed to allocate the BDF stepper state", GSL_ENOMEM);
    return s;
}

static int near(double a, double b, double h) { return fabs(a - b) <= 1e-6 * fabs(h); }

/* What GSL's evolve did with the pending step, as a call at t with step h
 * tells: accepted (t is its end), rejected by the error test (t is its
 * start), the same start again (a refused or failed step), or a restart
 * (anywhere else). bdf_apply acts on it; cd_bdf_step_limit predicts that. */
enum { PEND_ACCEPTED, PEND_REJECTED, PEND_SAME_START, PEND_RESTART };
static int pending_outcome(const cd_bdf *g, double t, double h)
{
    const double hp = g->t1p - g->t0p;
    if (g->have_pend && near(t, g->t1p, hp)) return PEND_ACCEPTED;
    if (g->have_pend && near(t, g->t0p, hp)) return PEND_REJECTED;
    if (g->nh > 0 && near(t, g->th[0], h)) return PEND_SAME_START;
    return PEND_RESTART;
}

double cd_bdf_step_limit(const cd_bdf *g, double t, double h)
{
    const int pend = pending_outcome(g, t, h);
    double last;
    int k, nh;
    switch (pend) {
    case PEND_ACCEPTED: /* pushed, then the order it chose */
        last = t - g->t0p;
        nh = g->nh < CD_BDF_NHIST ? g->nh + 1 : CD_BDF_NHIST;
        k = g->k_next;
        break;
    case PEND_REJECTED:
    case PEND_SAME_START:
        if (g->nh < 2) return h;
        last = g->th[0] - g->th[1];
        nh = g->nh;
        k = g->k;
        if (pend == PEND_REJECTED && g->nrej + 1 >= 3) k = 1;
        break;
    default:
        return h; /* a restart: order 1 */
    }
    if (g->kfix > 0) k = g->kfix;
    if (k > nh - 1) k = nh - 1 > 1 ? nh - 1 : 1;
    if (k <= 1 || last < CD_BDF_SLIVER * h) return h; /* no bound at order 1; after a sliver the history restarts */
    return h > CD_BDF_RATIO_MAX * last ? CD_BDF_RATIO_MAX * last : h;
}

/* The corrector of order k from the newest history point to t1: psi (the
 * history's part, times gamma) into g->psi; returns alpha0 (gamma =
 * 1/alpha0). The coefficients are on x_0 = t1, x_j = th[j-1] (times from t1). */
static double corrector(cd_bdf *g, int k, double t1)
{
    int n = g->ny, j, m, c;
    double alpha0 = 0, gamma;
    for (j = 1; j <= k; j++) alpha0 += 1.0 / (t1 - g->th[j - 1]);
    memset(g->psi, 0, (size_t)n * sizeof(double));
    for (j = 1; j <= k; j++) {
        double xj = g->th[j - 1] - t1, num = 1, den = xj, aj; /* den: (x_j - x_0) */
        for (m = 1; m <= k; m++) {
            if (m == j) continue;
            num *= -(g->th[m - 1] - t1);
            den *= xj - (g->th[m - 1] - t1);
        }
        aj = num / den;
        for (c = 0; c < n; c++) g->psi[c] += aj * g->Y[j - 1][c];
    }
    gamma = 1.0 / alpha0;
    for (c = 0; c < n; c++) g->psi[c] *= gamma;
    return alpha0;
}

/* The predictor: the polynomial through the k + 1 newest points at t1, into g->yp */
static void predict(cd_bdf *g, int k, double t1)
{
    int n = g->ny, j, m, c;
    memset(g->yp, 0, (size_t)n * sizeof(double));
    for (j = 0; j <= k; j++) {
        double L = 1;
        for (m = 0; m <= k; m++)
            if (m != j) L *= (t1 - g->th[m]) / (g->th[j] - g->th[m]);
        for (c = 0; c < n; c++) g->yp[c] += L * g->Y[j][c];
    }
}

static int bdf_apply(void *vs, size_t dim, double t, double h, double y[], double yerr[], const double dydt_in[],
                     double dydt_out[], const gsl_odeiv2_system *sys)
{
    bdf_state *s = (bdf_state *)vs;
    cd_bdf *g = s->g;
    cd_rosw *w;
    int n = (int)dim, c, k, st, retry, f_at_y = 0;
    double t1 = t + h, alpha0 = 0, gamma, C;
    const double *f0 = dydt_in;
    if (!g || n != g->ny || !(h > 0)) return GSL_EINVAL;
    w = g->rw;
    if (w->d) {
        g->rtol = w->d->opt.rtol;
        g->atol = w->d->opt.atol;
    }
    /* what evolve did with the last step */
    switch (pending_outcome(g, t, h)) {
    case PEND_ACCEPTED:
        if (g->k_used == g->k) g->nk++;
        push(g, t, y);
        g->nrej = 0;
        if (g->k_next != g->k) {
            g->k = g->k_next;
            g->nk = 0;
        }
        break;
    case PEND_REJECTED: /* by the error test */
        if (++g->nrej >= 3 && g->k > 1) {
            g->k = g->k_next = 1;
            g->nk = 0;
        }
        break;
    case PEND_RESTART:
        restart_history(g, t, y);
        break;
    default: /* the same start again */
        break;
    }
    g->have_pend = 0;
    memcpy(g->Y[0], y, (size_t)n * sizeof(double)); /* the state as evolve passes it */
    g->th[0] = t;
    /* the order of this step */
    k = g->kfix > 0 ? g->kfix : g->k;
    if (k > g->nh - 1) k = g->nh - 1 > 1 ? g->nh - 1 : 1;
    /* zero-stability of variable steps: a step more than CD_BDF_RATIO_MAX
     * times the last one above order 1 is refused without any evaluation
     * (evolve halves it) */
    if (g->nh >= 2 && k > 1 && h > CD_BDF_RATIO_MAX * (g->th[0] - g->th[1])) {
        if (!(g->th[0] - g->th[1] < CD_BDF_SLIVER * h)) {
            g->nratio++;
            return GSL_FAILURE;
        }
        /* the last step a sliver (an output time a few ulps after the one
         * before, a landing short by round-off): the 1.5x rule would hold
         * the steps near its length, below h_min. The history restarts at
         * this point, at order 1, whose zero-stability has no step-ratio
         * bound, as after an event. */
        restart_history(g, t, y);
        k = 1;
    }
    g->k_used = k;
    /* the Jacobian (as gauss4.c) */
    retry = s->have_prev && s->t_prev == t;
    if (!f0 && (g->nh == 1 || !w->jac_ok || w->jac_age >= CD_ROSW_JAC_AGE || (retry && g->renew && w->jac_t != t))) {
        if (GSL_ODEIV_FN_EVAL(sys, t, y, g->f0) != GSL_SUCCESS) return GSL_EBADFUNC;
        f0 = g->f0;
    }
    if (!w->jac_ok || w->jac_age >= CD_ROSW_JAC_AGE || (retry && g->renew && w->jac_t != t)) {
        if (cd_rosw_jacobian(w, t, y, f0, sys) != GSL_SUCCESS) return GSL_EBADFUNC;
        g->lu_gamma = 0;
    }
    s->have_prev = 1;
    s->t_prev = t;
    g->renew = 1; /* cleared when the step succeeds */
    alpha0 = corrector(g, k, t1);
    gamma = 1.0 / alpha0;
    /* the predictor and the error constant */
    if (g->nh == 1) {
        for (c = 0; c < n; c++) g->yp[c] = y[c] + h * f0[c];
        C = 2.0;
    } else {
        predict(g, k, t1);
        C = (t1 - g->th[k]) * alpha0;
    }
    memcpy(g->ypred, g->yp, (size_t)n * sizeof(double)); /* yp becomes Y */
    if (g->lu_gamma == 0 || fabs(gamma / g->lu_gamma - 1.0) > CD_BDF_GAMMA_TOL) {
        if (factor(g, gamma) != GSL_SUCCESS) {
            g->nfail++;
            return GSL_FAILURE;
        }
    }
    st = newton(g, t1, gamma, sys, CD_BDF_KAPPA, CD_BDF_KAPPA, &f_at_y);
    if (st == GSL_FAILURE && (g->lu_gamma != gamma || w->jac_t != t)) {
        /* an old matrix or Jacobian: once more with the step's own (CVODE's
         * recovery from a convergence failure) */
        memcpy(g->yp, g->ypred, (size_t)n * sizeof(double));
        g->eta = 1.0;
        st = GSL_SUCCESS;
        if (w->jac_t != t) {
            if (!f0) {
                if (GSL_ODEIV_FN_EVAL(sys, t, y, g->f0) != GSL_SUCCESS) return GSL_EBADFUNC;
                f0 = g->f0;
            }
            if (cd_rosw_jacobian(w, t, y, f0, sys) != GSL_SUCCESS) return GSL_EBADFUNC;
        }
        st = factor(g, gamma);
        if (st == GSL_SUCCESS) st = newton(g, t1, gamma, sys, CD_BDF_KAPPA, CD_BDF_KAPPA, &f_at_y);
    }
    if (st != GSL_SUCCESS) {
        g->nfail++;
        g->eta = 1.0;
        return st;
    }
    for (c = 0; c < n; c++) {
        yerr[c] = (g->yp[c] - g->ypred[c]) / C;
        y[c] = g->yp[c];
    }
    g->k_next = g->kfix > 0 ? g->kfix : choose_order(g, k, h, t1, y);
    g->renew = 0;
    g->have_pend = 1;
    g->t0p = t;
    g->t1p = t1;
    g->nsteps_k[k]++;
    w->jac_age++;
    if (dydt_out) {
        if (f_at_y) memcpy(dydt_out, g->F, (size_t)n * sizeof(double));
        else if (GSL_ODEIV_FN_EVAL(sys, t1, y, dydt_out) != GSL_SUCCESS) return GSL_EBADFUNC;
    }
    return GSL_SUCCESS;
}

int cd_bdf_trial(cd_bdf *g, const gsl_odeiv2_system *sys, double t0, double tau, double *y)
{
    int n = g->ny, k = g->k_used, st;
    double t1 = t0 + tau, gamma, eta_save = g->eta;
    if (!g->have_pend || g->nh < 1 || g->th[0] != t0 || !(tau > 0) || k < 1 || k > g->nh) {
        g->ntrial_fail++;
        return GSL_FAILURE;
    }
    gamma = 1.0 / corrector(g, k, t1);
    /* the predictor: the history's polynomial (y0 alone after a restart) */
    if (g->nh < k + 1) memcpy(g->yp, g->Y[0], (size_t)n * sizeof(double));
    else predict(g, k, t1);
    if ((g->lu_gamma == 0 || fabs(gamma / g->lu_gamma - 1.0) > CD_BDF_GAMMA_TOL) && factor(g, gamma) != GSL_SUCCESS) {
        g->ntrial_fail++;
        return GSL_FAILURE;
    }
    g->eta = 1.0;
    g->ntrial++;
    st = newton(g, t1, gamma, sys, CD_BDF_KAPPA_TRIAL, CD_BDF_KAPPA, NULL);
    g->eta = eta_save;
    if (st != GSL_SUCCESS) {
        g->ntrial_fail++;
        return st;
    }
    memcpy(y, g->yp, (size_t)n * sizeof(double));
    return GSL_SUCCESS;
}

static int bdf_set_driver(void *vs, const gsl_odeiv2_driver *d)
{
    (void)vs;
    (void)d;
    return GSL_SUCCESS;
}

static int bdf_reset(void *vs, size_t dim)
{
    bdf_state *s = (bdf_state *)vs;
    (void)dim;
    s->have_prev = 0;
    if (s->g) {
        cd_rosw_invalidate(s->g->rw);
        clear(s->g);
    }
    return GSL_SUCCESS;
}

static unsigned int bdf_order(void *vs)
{
    bdf_state *s = (bdf_state *)vs;
    return s->g ? (unsigned int)s->g->k_used : 1u;
}

static void bdf_free(void *vs) { free(vs); }

static const gsl_odeiv2_step_type bdf_type = {"msbdf", 1, 1, bdf_alloc, bdf_apply, bdf_set_driver,
                                              bdf_reset, bdf_order, bdf_free};
const gsl_odeiv2_step_type *cd_step_bdf = &bdf_type;

void cd_bdf_bind(gsl_odeiv2_step *s, cd_bdf *g)
{
    bdf_state *st = (bdf_state *)s->state;
    st->g = g;
    st->have_prev = 0;
    clear(g);
}
