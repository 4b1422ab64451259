/* msbdf: capdyn's variable-order variable-step BDF stepper (src/sim/bdf.c).
 * The measured order of each fixed order 1-5 at fixed steps on a smooth
 * problem with a known solution (started from exact values), the error of
 * the variable-order run under GSL's standard control falling with the
 * tolerance, stability on a very stiff linear problem at large steps, a
 * Newton failure that returns a failure after a bounded number of
 * iterations, the history's handling of a step GSL's evolve rejects, and the
 * Fig. 5 grasp against a tight rk8pd run. That no step allocates is in
 * tests/test_invariants.c (no_allocation_in_steps_and_events). The
 * model-free tests drive the GSL step type directly on a workspace without a
 * model (cd_rosw_init_plain + cd_bdf_init_plain). */
#include "stepper_util.h"
#include "../src/sim/bdf.h"

#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    gsl_odeiv2_step *s;
    cd_rosw w;
    cd_bdf g;
    void *mem, *gmem;
} plain;

static void plain_open(plain *P, int n, double tol)
{
    P->mem = malloc(cd_rosw_size_plain(n));
    P->gmem = malloc(cd_bdf_size_plain(n));
    cr_assert(P->mem && P->gmem);
    cd_rosw_init_plain(&P->w, n, 1e-8, P->mem);
    cd_bdf_init_plain(&P->g, &P->w, n, tol, tol, P->gmem);
    P->s = gsl_odeiv2_step_alloc(cd_step_bdf, (size_t)n);
    cr_assert(P->s);
    cd_bdf_bind(P->s, &P->g);
}

static void plain_close(plain *P)
{
    gsl_odeiv2_step_free(P->s);
    free(P->mem);
    free(P->gmem);
}

/* order k fixed, nsteps fixed steps over [0, 2] from the exact values at
 * t = -k h, ..., 0 (the startup): the max-norm global error at t = 2 */
static double global_error(int k, int nsteps, int exact_jac)
{
    gsl_odeiv2_system sys = {smooth_f, exact_jac ? smooth_j : NULL, 2, NULL};
    plain P;
    double y[2], err[2], u[2], h = 2.0 / nsteps, t = 0;
    int i;
    plain_open(&P, 2, 1e-13);
    P.g.kfix = k;
    for (i = k; i >= 0; i--) {
        exact(-i * h, u);
        cd_bdf_seed(&P.g, -i * h, u);
    }
    exact(0, y);
    for (i = 0; i < nsteps; i++) {
        cr_assert_eq(gsl_odeiv2_step_apply(P.s, t, h, y, err, NULL, NULL, &sys), GSL_SUCCESS, "k %d step %d of %d", k,
                     i, nsteps);
        cr_assert_eq(gsl_odeiv2_step_order(P.s), (unsigned)k, "k %d step %d: order %u", k, i,
                     gsl_odeiv2_step_order(P.s));
        t = (i + 1) * h;
    }
    plain_close(&P);
    exact(2.0, u);
    return fmax(fabs(y[0] - u[0]), fabs(y[1] - u[1]));
}

/* The type GSL's evolve and control see: name msbdf, order 1 at a start. */
Test(bdf, step_type_is_msbdf_starting_at_order_1)
{
    plain P;
    plain_open(&P, 2, 1e-8);
    cr_expect_eq(gsl_odeiv2_step_order(P.s), 1u);
    cr_expect_str_eq(gsl_odeiv2_step_name(P.s), "msbdf");
    plain_close(&P);
}

/* Convergence of each order k = 1..5 at fixed steps h = 2/N: the global
 * error falls by 2^k per halving (slope k +- 0.3), with the exact Jacobian
 * and with forward differences (the Jacobian only steers the Newton
 * iteration). N is chosen per order so that the errors stay well above the
 * Newton tolerance (1e-13) and round-off. */
Test(bdf, fixed_order_global_error_is_of_order_k)
{
    static const int N[5][4] = {{40, 80, 160, 320}, {40, 80, 160, 320}, {20, 40, 80, 160}, {40, 80, 160, 320},
                                {10, 20, 40, 80}};
    int k, i, j;
    for (k = 1; k <= 5; k++)
        for (j = 0; j < 2; j++) {
            double e[4];
            for (i = 0; i < 4; i++) e[i] = global_error(k, N[k - 1][i], j == 0);
            for (i = 0; i + 1 < 4; i++) {
                double p = log2(e[i] / e[i + 1]);
                cr_log_info("order %d, %s Jacobian, N %d -> %d: error %.3e -> %.3e, slope %.3f", k,
                            j == 0 ? "exact" : "difference", N[k - 1][i], N[k - 1][i + 1], e[i], e[i + 1], p);
                cr_expect(p >= k - 0.3 && p <= k + 0.3,
                          "order %d, %s Jacobian: slope %.3f between N = %d and %d (errors %.3e, %.3e)", k,
                          j == 0 ? "exact" : "difference", p, N[k - 1][i], N[k - 1][i + 1], e[i], e[i + 1]);
            }
        }
}

/* The variable-order run under GSL's standard control (the driver capdyn
 * uses: a_y = a_dydt = 1) from a cold start over [0, 4]: the global error
 * falls with the tolerance, and tight tolerances climb to high orders. */
Test(bdf, variable_order_error_falls_with_tolerance)
{
    gsl_odeiv2_system sys = {smooth_f, smooth_j, 2, NULL};
    double tol[4] = {1e-4, 1e-6, 1e-8, 1e-10}, e[4];
    int i, kmax_used[4];
    for (i = 0; i < 4; i++) {
        plain P;
        gsl_odeiv2_control *c = gsl_odeiv2_control_standard_new(tol[i], tol[i], 1.0, 1.0);
        gsl_odeiv2_evolve *ev = gsl_odeiv2_evolve_alloc(2);
        double y[2], u[2], t = 0, h = 1e-4;
        long nst = 0;
        int k;
        plain_open(&P, 2, tol[i]);
        exact(0, y);
        while (t < 4.0) {
            cr_assert_eq(gsl_odeiv2_evolve_apply(ev, c, P.s, &sys, &t, 4.0, &h, y), GSL_SUCCESS, "tol %g t %g", tol[i],
                         t);
            nst++;
        }
        exact(4.0, u);
        e[i] = fmax(fabs(y[0] - u[0]), fabs(y[1] - u[1]));
        kmax_used[i] = 0;
        for (k = 1; k <= CD_BDF_KMAX; k++)
            if (P.g.nsteps_k[k] > 0) kmax_used[i] = k;
        cr_log_info("tol %g: error %.3e, %ld steps (%lu rejected), steps at orders 1-5: %ld %ld %ld %ld %ld", tol[i],
                    e[i], nst, (unsigned long)ev->failed_steps, P.g.nsteps_k[1], P.g.nsteps_k[2], P.g.nsteps_k[3],
                    P.g.nsteps_k[4], P.g.nsteps_k[5]);
        cr_expect_lt(e[i], 100.0 * tol[i], "tol %g: error %.3e", tol[i], e[i]);
        if (i > 0) cr_expect_lt(e[i], 0.1 * e[i - 1], "tol %g: error %.3e after %.3e", tol[i], e[i], e[i - 1]);
        gsl_odeiv2_evolve_free(ev);
        gsl_odeiv2_control_free(c);
        plain_close(&P);
    }
    cr_expect_geq(kmax_used[3], 4, "at tol 1e-10 the highest order used is %d", kmax_used[3]);
}

/* The end derivative a step hands back (GSL's dydt_out, evolve's next
 * dydt_in; capdyn's switching functions and dense output read the data of
 * that evaluation) is f at the step's end, bit for bit, whether msbdf
 * evaluated it after the Newton iteration or the iteration ended on the
 * iterate it had just evaluated (within the Newton tolerance by the
 * contraction bound: no evaluation more). Counted: a step's evaluations are
 * its Newton iterations plus one, or its Newton iterations alone when the
 * evaluation was saved, which only a step of two or more iterations can do
 * (the first iterate is the predictor: measured 6 of 212 steps here, whose
 * Newton iteration mostly converges at once; on the Fig. 5 grasp, 12 s,
 * 14 816 -> 13 588 evaluations); the run ends within 100x the tolerance. */
typedef struct {
    long n;
    double t, y[2];
} calls;

static int counted_f(double t, const double y[], double f[], void *p)
{
    calls *c = (calls *)p;
    c->n++;
    c->t = t;
    c->y[0] = y[0];
    c->y[1] = y[1];
    return smooth_f(t, y, f, NULL);
}

Test(bdf, end_derivative_is_f_at_the_step_end)
{
    calls cnt = {0, 0, {0, 0}};
    gsl_odeiv2_system sys = {counted_f, smooth_j, 2, &cnt};
    plain P;
    double y[2], err[2], u[2], fin[2], fout[2], fx[2], t = 0, h = 1e-3;
    long nst = 0, saved = 0;
    int i;
    plain_open(&P, 2, 1e-8);
    exact(0, y);
    smooth_f(0, y, fin, NULL);
    for (i = 0; i < 400 && t < 4.0; i++) {
        long n0 = cnt.n, nn0 = P.g.nnewton;
        double hh = h;
        if (P.g.nh >= 2 && hh > 1.5 * (P.g.th[0] - P.g.th[1])) hh = 1.5 * (P.g.th[0] - P.g.th[1]);
        if (t + hh > 4.0) hh = 4.0 - t;
        cr_assert_eq(gsl_odeiv2_step_apply(P.s, t, hh, y, err, fin, fout, &sys), GSL_SUCCESS, "step %d at t %g", i, t);
        t += hh;
        nst++;
        smooth_f(t, y, fx, NULL);
        cr_assert(fout[0] == fx[0] && fout[1] == fx[1], "step %d to t %.6g: dydt_out (%.17g, %.17g), f (%.17g, %.17g)",
                  i, t, fout[0], fout[1], fx[0], fx[1]);
        cr_assert(cnt.t == t && cnt.y[0] == y[0] && cnt.y[1] == y[1],
                  "step %d: the last evaluation was not at the step's end state", i);
        if (cnt.n - n0 == P.g.nnewton - nn0) {
            saved++;
            cr_assert_geq(P.g.nnewton - nn0, 2, "step %d saved the end evaluation after %ld Newton iteration", i,
                          P.g.nnewton - nn0);
        } else cr_assert_eq(cnt.n - n0, P.g.nnewton - nn0 + 1, "step %d: %ld evaluations, %ld Newton iterations", i,
                          cnt.n - n0, P.g.nnewton - nn0);
        fin[0] = fout[0];
        fin[1] = fout[1];
        h = hh * 1.2; /* grow towards the error the tolerance allows; no rejection test here */
        if (h > 0.02) h = 0.02;
    }
    exact(t, u);
    cr_log_info("%ld steps to t = %g, %ld with the end evaluation saved; %ld evaluations, %ld Newton iterations", nst,
                t, saved, cnt.n, P.g.nnewton);
    cr_expect_gt(saved, 0, "none of %ld steps saved the end evaluation", nst);
    cr_expect_lt(fmax(fabs(y[0] - u[0]), fabs(y[1] - u[1])), 100 * 1e-8, "error %.3e at t = %g",
                 fmax(fabs(y[0] - u[0]), fabs(y[1] - u[1])), t);
    plain_close(&P);
}

/* y' = -1e6 (y - cos t): the solution from y(0) = A = l^2 / (1 + l^2),
 * l = 1e6, is y = A cos t + B sin t, B = l / (1 + l^2). Fixed steps of 0.1
 * and 0.05 (h lambda = -1e5, -5e4) over [0, 2] at each fixed order 1-5 (the
 * history built up from the cold start, order <= points known - 1): the
 * negative real axis is inside the stability region of every BDF order
 * (L-stable for 1-2, A(alpha) for 3-5, alpha >= 51.8 deg), so the solution
 * stays on the smooth one; from y(0) = 2 (an offset of ~1 on the stiff
 * mode) the offset is damped (R(-inf) = 0 for every BDF: it is gone once
 * y(0) has left the k points of the history, so the worst error is taken
 * from step k + 2 on). */
Test(bdf, stiff_linear_problem_stable_at_large_steps)
{
    gsl_odeiv2_system sys = {stiff_f, stiff_j, 1, NULL};
    int start, k, hk;
    for (k = 1; k <= 5; k++)
        for (start = 0; start < 2; start++)
            for (hk = 0; hk < 2; hk++) {
                plain P;
                double y = start ? 2.0 : stiff_exact(0), err, t = 0, h = hk ? 0.05 : 0.1, worst = 0;
                int i, ns = (int)lround(2.0 / h);
                plain_open(&P, 1, 1e-10);
                P.g.kfix = k;
                for (i = 0; i < ns; i++) {
                    cr_assert_eq(gsl_odeiv2_step_apply(P.s, t, h, &y, &err, NULL, NULL, &sys), GSL_SUCCESS,
                                 "k %d step %d", k, i);
                    t = (i + 1) * h;
                    if (i >= k + 1 && fabs(y - stiff_exact(t)) > worst) worst = fabs(y - stiff_exact(t));
                }
                plain_close(&P);
                cr_log_info("order %d, y(0) = %g, h %g: worst error after step k + 1 %.3e, at t = 2 %.3e", k,
                            start ? 2.0 : stiff_exact(0), h, worst, fabs(y - stiff_exact(t)));
                cr_expect(isfinite(y), "y(2) = %g", y);
                cr_expect_lt(fabs(y - stiff_exact(t)), 1e-5, "order %d, y(0) = %g, h %g: error at t = 2 %.3e", k,
                             start ? 2.0 : stiff_exact(0), h, fabs(y - stiff_exact(t)));
                cr_expect_lt(worst, 1e-4, "order %d, y(0) = %g, h %g: worst error %.3e", k,
                             start ? 2.0 : stiff_exact(0), h, worst);
            }
}

/* A Newton iteration that cannot converge: the stiff problem with a zero
 * "Jacobian" (a fixed-point iteration, contraction |h lambda| >> 1). The
 * step returns GSL_FAILURE (GSL's evolve then halves the step) after at most
 * CD_BDF_NEWTON_MAX iterations, and y is unchanged; at h = 1e-8 it
 * converges. */
Test(bdf, newton_failure_returns_failure_bounded)
{
    gsl_odeiv2_system sys = {stiff_f, zero_j, 1, NULL};
    plain P;
    double y = 1.0, err = 0;
    int st;
    plain_open(&P, 1, 1e-10);
    st = gsl_odeiv2_step_apply(P.s, 0.0, 0.1, &y, &err, NULL, NULL, &sys);
    cr_expect_eq(st, GSL_FAILURE, "status %d", st);
    cr_expect_eq(y, 1.0, "y changed to %.17g", y);
    cr_expect(P.g.nnewton >= 1 && P.g.nnewton <= CD_BDF_NEWTON_MAX, "%ld iterations", P.g.nnewton);
    cr_expect_eq(P.g.nfail, 1);
    st = gsl_odeiv2_step_apply(P.s, 0.0, 1e-8, &y, &err, NULL, NULL, &sys);
    cr_expect_eq(st, GSL_SUCCESS, "status %d", st);
    cr_expect_lt(fabs(y - stiff_exact(1e-8)), 1e-11, "y %.17g", y);
    plain_close(&P);
}

/* The history holds accepted points only: a step that evolve rejects (the
 * next call starts where it started) leaves no trace, and a call at an
 * unrelated time restarts at order 1. Order 2 from seeded exact values
 * 0.05 apart: a step of 0.07 "rejected", then two of 0.05 give what two
 * steps of 0.05 give without the rejected one. A step more than
 * CD_BDF_RATIO_MAX times the last is refused before any evaluation. */
Test(bdf, rejected_step_leaves_history_unchanged)
{
    gsl_odeiv2_system sys = {smooth_f, smooth_j, 2, NULL};
    double ya[2], yb[2], err[2], u[2];
    int r, i;
    for (r = 0; r < 2; r++) {
        plain P;
        double *y = r ? yb : ya;
        plain_open(&P, 2, 1e-12);
        P.g.kfix = 2;
        for (i = 2; i >= 0; i--) {
            exact(-i * 0.05, u);
            cd_bdf_seed(&P.g, -i * 0.05, u);
        }
        exact(0, y);
        if (r) {
            double ysave[2] = {y[0], y[1]};
            cr_assert_eq(gsl_odeiv2_step_apply(P.s, 0.0, 0.07, y, err, NULL, NULL, &sys), GSL_SUCCESS);
            y[0] = ysave[0]; /* what evolve does on rejection: restore, retry smaller */
            y[1] = ysave[1];
        }
        cr_assert_eq(gsl_odeiv2_step_apply(P.s, 0.0, 0.05, y, err, NULL, NULL, &sys), GSL_SUCCESS);
        cr_assert_eq(gsl_odeiv2_step_apply(P.s, 0.05, 0.05, y, err, NULL, NULL, &sys), GSL_SUCCESS);
        cr_expect_eq(gsl_odeiv2_step_order(P.s), 2u);
        cr_expect_eq(P.g.nh, 4, "history points %d", P.g.nh);
        if (r) { /* 0.1 after 0.05: refused, y untouched */
            double ys[2] = {y[0], y[1]};
            long nn = P.g.nnewton;
            cr_expect_eq(gsl_odeiv2_step_apply(P.s, 0.1, 0.1, y, err, NULL, NULL, &sys), GSL_FAILURE);
            cr_expect(y[0] == ys[0] && y[1] == ys[1] && P.g.nnewton == nn && P.g.nratio == 1);
        }
        /* a call elsewhere: a restart at order 1 */
        cr_assert_eq(gsl_odeiv2_step_apply(P.s, 5.0, 0.01, u, err, NULL, NULL, &sys), GSL_SUCCESS);
        cr_expect_eq(gsl_odeiv2_step_order(P.s), 1u);
        plain_close(&P);
    }
    /* the same within the Newton tolerance (1e-12: the rejected step leaves
     * another iteration matrix and contraction estimate, so the iterates
     * differ at that level; a rejected point kept in the history would move
     * the result by the step's error, ~1e-6) */
    cr_expect_lt(fabs(ya[0] - yb[0]), 1e-11, "%.17g vs %.17g", ya[0], yb[0]);
    cr_expect_lt(fabs(ya[1] - yb[1]), 1e-11, "%.17g vs %.17g", ya[1], yb[1]);
}

/* The Fig. 5 envelope grasp (2 s: closing, the contact events, the rocking
 * hold; h_max 0.05) with msbdf at rtol 1e-10 and rk8pd at rtol 1e-12 (the
 * tight reference): the same events (count and kinds), the same final slot
 * modes, every generalized coordinate within 1e-6 (m, rad). And msbdf at
 * rtol 3e-11, where its locator (rk8pd across msbdf's step, beyond rk8pd's
 * stability limit) used to land on a spurious stick-slip pair of 15 ns on a
 * contact 0.32 N inside its cone: with the locator's sub-steps
 * (docs/events.md section 6, step 4) the same events as the reference. */
#ifndef FIG5_T_END
#define FIG5_T_END 2.0
#endif

Test(bdf, fig5_grasp_agrees_with_tight_rk8pd, .timeout = 900)
{
    static outcome o[2];
    const double t_end = FIG5_T_END;
    double worst = 0;
    int i;
    run_fig5("simulation.integrator=\"msbdf\"", "simulation.rtol=1e-10", t_end, &o[0]);
    run_fig5("simulation.integrator=\"rk8pd\"", "simulation.rtol=1e-12", t_end, &o[1]);
    cr_assert_eq(o[0].nq, o[1].nq);
    for (i = 0; i < o[0].nq; i++)
        if (fabs(o[0].q[i] - o[1].q[i]) > worst) worst = fabs(o[0].q[i] - o[1].q[i]);
    cr_log_info("Fig. 5, %g s: msbdf (rtol 1e-10) %ld steps, %ld rhs, %ld Jacobians, %ld events; rk8pd %ld rhs, %ld "
                "events; worst coordinate difference %.3e",
                t_end, o[0].nsteps, o[0].nrhs, o[0].njac, o[0].nev, o[1].nrhs, o[1].nev, worst);
    cr_expect_gt(o[0].nev, 5, "the grasp makes contact events (%ld)", o[0].nev);
    cr_expect_eq(o[0].nev, o[1].nev, "events: msbdf %ld, rk8pd %ld", o[0].nev, o[1].nev);
    for (i = 0; i < 8; i++)
        cr_expect_eq(o[0].kinds[i], o[1].kinds[i], "events of kind %d: msbdf %ld, rk8pd %ld", i, o[0].kinds[i],
                     o[1].kinds[i]);
    cr_expect_lt(worst, 1e-6, "coordinates differ by %.3e", worst);
    for (i = 0; i < o[0].ns; i++)
        cr_expect_eq(o[0].modes[i], o[1].modes[i], "slot %d: mode %d vs %d", i, o[0].modes[i], o[1].modes[i]);
    cr_expect_gt(o[0].njac, 0, "msbdf formed its Jacobians");
    run_fig5("simulation.integrator=\"msbdf\"", "simulation.rtol=3e-11", t_end, &o[0]);
    cr_log_info("msbdf at rtol 3e-11: %ld events", o[0].nev);
    cr_expect_eq(o[0].nev, o[1].nev, "events: msbdf (rtol 3e-11) %ld, rk8pd %ld", o[0].nev, o[1].nev);
    for (i = 0; i < 8; i++)
        cr_expect_eq(o[0].kinds[i], o[1].kinds[i], "events of kind %d: msbdf (rtol 3e-11) %ld, rk8pd %ld", i,
                     o[0].kinds[i], o[1].kinds[i]);
}

/* An output time reached a few ulps after the last one (a caller's sample
 * grid, a landing that fell short by round-off) makes a sliver step of
 * ~1e-15 s. Above order 1 the step-ratio rule allowed the next step only
 * 1.5 times that sliver, so every later step was refused down to below h_min
 * and the run stopped with CD_ESTALL (seen on capture_handrail_tumbling at
 * 3.51 s with `capdyn run`). A sliver now restarts the history at order 1
 * (BDF1 is zero-stable at any step ratio): the run goes on and ends where the
 * run without the sliver ends, within the tolerance. */
Test(bdf, continues_after_a_sliver_step)
{
    static const char *ov[] = {"simulation.integrator=\"msbdf\"", "simulation.rtol=1e-9"};
    char path[1024];
    cd_error e;
    cd_scenario *sc;
    cd_data *d[2];
    const cd_model *m;
    double t1 = 0.5, worst = 0;
    int i, r;
    snprintf(path, sizeof path, "%s/scenarios/free_floating_arm.toml", step_root());
    sc = cd_scenario_load(path, ov, 2, &e);
    cr_assert(sc, "%s", e.msg);
    m = sc->model;
    for (r = 0; r < 2; r++) {
        d[r] = cd_data_create(m, sc->event_capacity, &e);
        cr_assert(d[r], "%s", e.msg);
        cr_assert_eq(cd_sim_advance(m, d[r], t1, NULL, NULL, &e), CD_OK, "%s", e.msg);
        cr_assert(d[r]->stats.h_last > 1e-6, "ordinary steps before the sliver (last %g s)", d[r]->stats.h_last);
        if (r == 1) {
            double ts = t1;
            for (i = 0; i < 8; i++) ts = nextafter(ts, 1.0); /* 8 ulps: 8.9e-16 s */
            cr_assert_eq(cd_sim_advance(m, d[r], ts, NULL, NULL, &e), CD_OK, "%s", e.msg);
            cr_assert_lt(d[r]->stats.h_last, 1e-14, "a sliver step (%g s)", d[r]->stats.h_last);
        }
        cr_assert_eq(cd_sim_advance(m, d[r], 1.0, NULL, NULL, &e), CD_OK, "run %d after %g s: %s", r, t1, e.msg);
    }
    for (i = 0; i < m->ny; i++)
        if (fabs(d[0]->y[i] - d[1]->y[i]) > worst) worst = fabs(d[0]->y[i] - d[1]->y[i]);
    cr_log_info("after a sliver step: %ld steps against %ld, largest difference of the state %.3e", d[1]->stats.nsteps,
                d[0]->stats.nsteps, worst);
    cr_expect_lt(worst, 1e-6, "the state after the sliver differs by %.3e", worst);
    for (r = 0; r < 2; r++) cd_data_free(d[r]);
    cd_scenario_free(sc);
}

/* cd_bdf_trial, the locator of events on msbdf's own solution: after a step
 * of order 3 from t = 0 (h = 0.05, history from exact values), a trial to
 * the step's end is that step's solution, and a trial to 0.03 is the BDF
 * step of that length over the same history (a second instance, stepped
 * there directly), both within the Newton tolerances (the step's 0.01, the
 * trial's 1e-4 of the scale 1e-12 (1 + |y|): differences of a few 1e-14).
 * The trials leave the history as it was: the next step, which accepts the
 * pending one, ends where it ends without them (within the same tolerance:
 * a trial may leave another iteration matrix). A trial from anywhere but the
 * pending step's start is refused. */
Test(bdf, trial_step_is_the_step_of_that_length)
{
    gsl_odeiv2_system sys = {smooth_f, smooth_j, 2, NULL};
    const double h = 0.05;
    double y1[2], yt[2], yr[2], yn[2], yb[2], err[2], u[2];
    plain P[3];
    int r, i;
    for (r = 0; r < 3; r++) {
        plain_open(&P[r], 2, 1e-12);
        P[r].g.kfix = 3;
        for (i = 3; i >= 0; i--) {
            exact(-i * h, u);
            cd_bdf_seed(&P[r].g, -i * h, u);
        }
    }
    exact(0, y1);
    memcpy(yn, y1, sizeof y1);
    memcpy(yr, y1, sizeof y1);
    cr_assert_eq(gsl_odeiv2_step_apply(P[0].s, 0.0, h, y1, err, NULL, NULL, &sys), GSL_SUCCESS);
    cr_assert_eq(gsl_odeiv2_step_apply(P[1].s, 0.0, h, yn, err, NULL, NULL, &sys), GSL_SUCCESS);
    cr_assert_eq(gsl_odeiv2_step_apply(P[2].s, 0.0, 0.03, yr, err, NULL, NULL, &sys), GSL_SUCCESS);
    /* to the step's end: the step */
    cr_assert_eq(cd_bdf_trial(&P[0].g, &sys, 0.0, h, yt), GSL_SUCCESS);
    for (i = 0; i < 2; i++)
        cr_expect_lt(fabs(yt[i] - y1[i]), 1e-13, "trial to h, component %d: %.17g, the step %.17g", i, yt[i], y1[i]);
    /* to 0.03: the BDF step of that length */
    cr_assert_eq(cd_bdf_trial(&P[0].g, &sys, 0.0, 0.03, yt), GSL_SUCCESS);
    for (i = 0; i < 2; i++)
        cr_expect_lt(fabs(yt[i] - yr[i]), 1e-13, "trial to 0.03, component %d: %.17g, a step of 0.03 %.17g", i, yt[i],
                     yr[i]);
    exact(0.03, u);
    cr_expect_gt(fabs(yt[0] - u[0]) + fabs(yt[1] - u[1]), 1e-15, "not the exact solution by accident");
    cr_expect_lt(fabs(yt[0] - u[0]) + fabs(yt[1] - u[1]), 1e-6, "trial to 0.03 off the solution by %.3e",
                 fabs(yt[0] - u[0]) + fabs(yt[1] - u[1]));
    /* elsewhere: refused, nothing computed */
    cr_expect_eq(cd_bdf_trial(&P[0].g, &sys, 0.01, 0.02, yt), GSL_FAILURE);
    /* the history as it was: the next step ends where it ends without the trials */
    memcpy(yb, y1, sizeof y1);
    cr_assert_eq(gsl_odeiv2_step_apply(P[0].s, h, h, yb, err, NULL, NULL, &sys), GSL_SUCCESS);
    cr_assert_eq(gsl_odeiv2_step_apply(P[1].s, h, h, yn, err, NULL, NULL, &sys), GSL_SUCCESS);
    cr_expect_eq(P[0].g.nh, P[1].g.nh, "history points %d and %d", P[0].g.nh, P[1].g.nh);
    for (i = 0; i < 2; i++)
        cr_expect_lt(fabs(yb[i] - yn[i]), 1e-13, "the step after the trials, component %d: %.17g, without %.17g", i,
                     yb[i], yn[i]);
    cr_expect_eq(P[0].g.ntrial, 2, "trials solved %ld", P[0].g.ntrial);
    cr_expect_eq(P[0].g.ntrial_fail, 1, "refused trials %ld", P[0].g.ntrial_fail);
    for (r = 0; r < 3; r++) plain_close(&P[r]);
}
