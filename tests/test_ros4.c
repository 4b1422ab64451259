/* The order-4 linearly implicit stepper RODAS4 (src/sim/rosw.c, issue 18
 * item 2): its tableau checked against the published one (the row sums
 * rodas.f states), its measured order on a smooth problem with a known
 * solution, the order of its embedded estimate, its stability on a very stiff
 * linear problem, and the Fig. 5 grasp against a tight rk8pd run. The
 * model-free tests drive the GSL step type directly on a workspace without a
 * model (cd_rosw_init_plain) with the system's exact Jacobian and df/dt. */
#include "stepper_util.h"
#include "../src/sim/rosw.h"

#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    gsl_odeiv2_step *s;
    cd_rosw w;
    void *mem;
} plain;

static void plain_open(plain *P, const gsl_odeiv2_step_type *T, int n)
{
    P->mem = malloc(cd_rosw_size_plain(n));
    cr_assert(P->mem);
    cd_rosw_init_plain(&P->w, n, 1e-8, P->mem);
    P->s = gsl_odeiv2_step_alloc(T, (size_t)n);
    cr_assert(P->s);
    cd_rosw_bind(P->s, &P->w, 0);
}

static void plain_close(plain *P)
{
    gsl_odeiv2_step_free(P->s);
    free(P->mem);
}

/* fixed steps over [0, 2]: the max-norm global error at t = 2 */
static double global_error_sys(const gsl_odeiv2_step_type *T, int nsteps, gsl_odeiv2_system *sys)
{
    plain P;
    double y[2], err[2], u[2], h = 2.0 / nsteps, t = 0;
    int i;
    plain_open(&P, T, 2);
    exact(0, y);
    for (i = 0; i < nsteps; i++) {
        cr_assert_eq(gsl_odeiv2_step_apply(P.s, t, h, y, err, NULL, NULL, sys), GSL_SUCCESS);
        t = (i + 1) * h;
    }
    plain_close(&P);
    exact(2.0, u);
    return fmax(fabs(y[0] - u[0]), fabs(y[1] - u[1]));
}

/* ... on smooth_f with its exact Jacobian */
static double global_error(const gsl_odeiv2_step_type *T, int nsteps)
{
    gsl_odeiv2_system sys = {smooth_f, smooth_j, 2, NULL};
    return global_error_sys(T, nsteps, &sys);
}

/* The published tableau, converted: its row sums are rodas.f's nodes c_i and
 * gamma_i (the conversion's check), and it is the method GSL reports as of
 * order 4. */
Test(ros4, tableau_row_sums_match_rodas_f)
{
    /* rodas.f (METH = 1): C2..C4 = 0.386, 0.21, 0.63 (and 1, 1 for the two
     * last stages); D1..D4 = 0.25, -0.1043, 0.1035, -0.0362 (and 0, 0) */
    const double c_pub[6] = {0, 0.386, 0.21, 0.63, 1, 1}, g_pub[6] = {0.25, -0.1043, 0.1035, -0.0362, 0, 0};
    double c[6], g[6];
    int i, ns = cd_rosw_tableau_sums(cd_step_rodas4, c, g);
    gsl_odeiv2_step *s = gsl_odeiv2_step_alloc(cd_step_rodas4, 2);
    cr_assert_eq(ns, 6);
    for (i = 0; i < 6; i++) {
        cr_expect_leq(fabs(c[i] - c_pub[i]), 1e-14, "c_%d = %.17g, rodas.f %.17g", i + 1, c[i], c_pub[i]);
        cr_expect_leq(fabs(g[i] - g_pub[i]), 1e-14, "gamma_%d = %.17g, rodas.f %.17g", i + 1, g[i], g_pub[i]);
    }
    cr_assert(s);
    cr_expect_eq(gsl_odeiv2_step_order(s), 4u);
    cr_expect_str_eq(gsl_odeiv2_step_name(s), "rodas4");
    gsl_odeiv2_step_free(s);
}

/* Convergence with fixed steps h = 2/20 ... 2/320 and the exact Jacobian:
 * the global error falls by 2^4 per halving. Measured slopes (log2 of the
 * ratio): 4.22, 3.83, 3.91, 3.95 for rodas4 (errors 3.9e-8 ... 6.4e-13);
 * ros34pw2 on the same problem, the control that the test tells the orders
 * apart: 3.17 on the last halving. */
Test(ros4, global_error_is_of_order_4)
{
    int N[5] = {20, 40, 80, 160, 320}, i;
    double e[5], e3[5];
    for (i = 0; i < 5; i++) {
        e[i] = global_error(cd_step_rodas4, N[i]);
        e3[i] = global_error(cd_step_ros34pw2, N[i]);
    }
    for (i = 0; i + 1 < 5; i++) {
        double p = log2(e[i] / e[i + 1]), p3 = log2(e3[i] / e3[i + 1]);
        cr_log_info("N %d -> %d: rodas4 error %.3e -> %.3e, slope %.3f; ros34pw2 slope %.3f", N[i], N[i + 1], e[i],
                    e[i + 1], p, p3);
        cr_expect(p >= 3.7 && p <= 4.3, "rodas4: slope %.3f between N = %d and %d (errors %.3e, %.3e), expected 4 +- 0.3",
                  p, N[i], N[i + 1], e[i], e[i + 1]);
        if (i == 3) /* the control's error changes sign near N = 40: its asymptotic pair */
            cr_expect(p3 >= 2.7 && p3 <= 3.3, "ros34pw2 (control): slope %.3f, expected 3 +- 0.3", p3);
    }
    cr_expect_lt(e[4], 1e-9, "rodas4 at N = 320: error %.3e", e[4]);
}

/* A matrix that has nothing to do with the Jacobian of smooth_f (constant,
 * other signs and sizes) and no df/dt. */
static int wrong_j(double t, const double y[], double *J, double dfdt[], void *p)
{
    (void)t;
    (void)y;
    (void)p;
    J[0] = -3.0; J[1] = 0.7;
    J[2] = 1.9;  J[3] = 0.4;
    dfdt[0] = dfdt[1] = 0;
    return GSL_SUCCESS;
}

/* ros34pw2 is a W-method: its order 3 holds whatever matrix stands in for
 * the Jacobian, which is what lets capdyn keep a Jacobian over steps and
 * leave terms out of the structured one (rosw.c). Its stages are computed in
 * transformed unknowns (rosw.c, rosw_state), an exact rewriting for any
 * matrix; this checks that rewriting where an exact Jacobian would hide an
 * error that cancels only for it. With wrong_j the global error falls by 2^3
 * per halving (measured slopes 3.07, 3.04, 3.02, 3.01, errors 4.4e-5 ...
 * 9.8e-9); rodas4, a Rosenbrock method whose order needs the exact Jacobian,
 * is the control: with the same matrix its order drops (measured slopes 1.39,
 * 0.86, 0.77, 0.90). */
Test(ros4, ros34pw2_keeps_order_3_with_any_matrix)
{
    gsl_odeiv2_system sys = {smooth_f, wrong_j, 2, NULL};
    int N[5] = {40, 80, 160, 320, 640}, i;
    double e[5], e4[5];
    for (i = 0; i < 5; i++) {
        e[i] = global_error_sys(cd_step_ros34pw2, N[i], &sys);
        e4[i] = global_error_sys(cd_step_rodas4, N[i], &sys);
    }
    for (i = 0; i + 1 < 5; i++) {
        double p = log2(e[i] / e[i + 1]), p4 = log2(e4[i] / e4[i + 1]);
        cr_log_info("N %d -> %d: ros34pw2 error %.3e -> %.3e, slope %.3f; rodas4 slope %.3f", N[i], N[i + 1], e[i],
                    e[i + 1], p, p4);
        cr_expect(p >= 2.7 && p <= 3.3, "ros34pw2 with a wrong matrix: slope %.3f between N = %d and %d, expected 3 +- 0.3",
                  p, N[i], N[i + 1]);
        cr_expect(p4 < 2.5, "rodas4 (control) with a wrong matrix: slope %.3f, expected its order to drop", p4);
    }
}

/* The embedded estimate: for one step from t = 0.3 the estimate |y - yhat|
 * is the local error of the order-3 solution, O(h^4); the solution's own
 * local error is O(h^5). */
Test(ros4, embedded_estimate_is_of_order_3)
{
    gsl_odeiv2_system sys = {smooth_f, smooth_j, 2, NULL};
    double H[4] = {0.2, 0.1, 0.05, 0.025}, est[4], loc[4];
    int i;
    for (i = 0; i < 4; i++) {
        plain P;
        double y[2], err[2], u[2];
        plain_open(&P, cd_step_rodas4, 2);
        exact(0.3, y);
        cr_assert_eq(gsl_odeiv2_step_apply(P.s, 0.3, H[i], y, err, NULL, NULL, &sys), GSL_SUCCESS);
        exact(0.3 + H[i], u);
        est[i] = fmax(fabs(err[0]), fabs(err[1]));
        loc[i] = fmax(fabs(y[0] - u[0]), fabs(y[1] - u[1]));
        plain_close(&P);
    }
    for (i = 0; i + 1 < 4; i++) {
        double pe = log2(est[i] / est[i + 1]), pl = log2(loc[i] / loc[i + 1]);
        cr_log_info("h %.3g: estimate %.3e (slope %.3f), local error %.3e (slope %.3f)", H[i + 1], est[i + 1], pe,
                    loc[i + 1], pl);
        cr_expect(pe >= 3.6 && pe <= 4.4, "estimate slope %.3f at h %g, expected 4 +- 0.4", pe, H[i + 1]);
        cr_expect(pl >= 4.5, "local error slope %.3f at h %g, expected about 5", pl, H[i + 1]);
        cr_expect_gt(est[i + 1], loc[i + 1], "the estimate (%.3e) bounds the order-4 local error (%.3e)", est[i + 1],
                     loc[i + 1]);
    }
}

/* y' = lambda (y - cos t) - sin t, lambda = -1e6: y = cos t from y(0) = 1.
 * Steps of 0.1 (h lambda = -1e5) stay stable and accurate (measured error
 * 2.0e-9), and a start off the smooth solution (y(0) = 2) is damped in one
 * step (L-stability, R(-infinity) = 0: measured 8.8e-5 of the offset of 1
 * after the first step) and keeps decaying (the end error below 1e-8). */
static int stiff_cos_f(double t, const double y[], double f[], void *p)
{
    (void)p;
    f[0] = -1e6 * (y[0] - cos(t)) - sin(t);
    return GSL_SUCCESS;
}
static int stiff_cos_j(double t, const double y[], double *J, double dfdt[], void *p)
{
    (void)p;
    (void)y;
    J[0] = -1e6;
    dfdt[0] = -1e6 * sin(t) - cos(t);
    return GSL_SUCCESS;
}

Test(ros4, stiff_linear_problem_stable_at_large_steps)
{
    gsl_odeiv2_system sys = {stiff_cos_f, stiff_cos_j, 1, NULL};
    int start;
    for (start = 0; start < 2; start++) {
        plain P;
        double y = start ? 2.0 : 1.0, err, t = 0, h = 0.1, worst = 0, first = 0, last;
        int i;
        plain_open(&P, cd_step_rodas4, 1);
        for (i = 0; i < 20; i++) {
            cr_assert_eq(gsl_odeiv2_step_apply(P.s, t, h, &y, &err, NULL, NULL, &sys), GSL_SUCCESS);
            t = (i + 1) * h;
            if (i == 0) first = fabs(y - cos(t));
            if (fabs(y - cos(t)) > worst) worst = fabs(y - cos(t));
        }
        plain_close(&P);
        last = fabs(y - cos(t));
        cr_log_info("y(0) = %g: error after the first step %.3e, worst over 20 steps of 0.1 %.3e, at t = 2 %.3e",
                    start ? 2.0 : 1.0, first, worst, last);
        cr_expect_lt(last, 1e-8, "y(0) = %g: error %.3e at t = 2", start ? 2.0 : 1.0, last);
        cr_expect(isfinite(y), "y(2) = %g", y);
        cr_expect_lt(worst, start ? 1e-4 : 1e-6, "y(0) = %g: worst error %.3e", start ? 2.0 : 1.0, worst);
    }
}

/* A contact scenario: the Fig. 5 envelope grasp (2 s: closing, 44 contact
 * events, the rocking hold) with rodas4 at rtol 1e-8 and with rk8pd at rtol
 * 1e-12 (the tight reference): the same events (count and kinds), the same
 * final slot modes, and every generalized coordinate (the object's pose among
 * them) within 1e-6 (m, rad; measured 1.7e-10). Event location runs on rodas4's own
 * locator steps and the samples on the Hermite interpolant. */
Test(ros4, fig5_grasp_agrees_with_tight_rk8pd, .timeout = 600)
{
    static outcome o[2];
    double worst = 0;
    int i;
    run_fig5("simulation.integrator=\"rodas4\"", "simulation.rtol=1e-8", 2.0, &o[0]);
    run_fig5("simulation.integrator=\"rk8pd\"", "simulation.rtol=1e-12", 2.0, &o[1]);
    cr_assert_eq(o[0].nq, o[1].nq);
    for (i = 0; i < o[0].nq; i++)
        if (fabs(o[0].q[i] - o[1].q[i]) > worst) worst = fabs(o[0].q[i] - o[1].q[i]);
    cr_log_info("Fig. 5, 2 s: rodas4 %ld rhs, %ld Jacobians, %ld events; rk8pd %ld rhs, %ld events; worst coordinate "
                "difference %.3e",
                o[0].nrhs, o[0].njac, o[0].nev, o[1].nrhs, o[1].nev, worst);
    cr_expect_gt(o[0].nev, 10, "the grasp makes contact events (%ld)", o[0].nev);
    cr_expect_eq(o[0].nev, o[1].nev, "events: rodas4 %ld, rk8pd %ld", o[0].nev, o[1].nev);
    for (i = 0; i < 8; i++)
        cr_expect_eq(o[0].kinds[i], o[1].kinds[i], "events of kind %d: rodas4 %ld, rk8pd %ld", i, o[0].kinds[i],
                     o[1].kinds[i]);
    cr_expect_lt(worst, 1e-6, "coordinates differ by %.3e", worst);
    for (i = 0; i < o[0].ns; i++)
        cr_expect_eq(o[0].modes[i], o[1].modes[i], "slot %d: mode %d vs %d", i, o[0].modes[i], o[1].modes[i]);
    cr_expect_gt(o[0].njac, 0, "rodas4 formed its Jacobians");
}
