/* rk8pd: capdyn's explicit Prince-Dormand 8(7) stepper (src/sim/rk8.c).
 * Its tableau is checked three ways: the order conditions it must meet
 * (through order 2 exactly, and the measured global order 8 on a smooth
 * problem with a known solution), and a step bit for bit equal to GSL's
 * gsl_odeiv2_step_rk8pd, the same method, which capdyn used before. The
 * skipping of the open slots' anchors rests on one fact of the model, that
 * their derivative is exactly 0 at every state while the slot is open:
 * checked on random states of a capture scene, where a bound step is then
 * again bit for bit GSL's full step. That no step allocates is in
 * tests/test_invariants.c (no_allocation_in_steps_and_events). */
#include "stepper_util.h"
#include "../src/sim/rk8.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* one step of type T (unbound) of the smooth system from (t, y) */
static void step_of(const gsl_odeiv2_step_type *T, const gsl_odeiv2_system *sys, double t, double h,
                    const double *y0, double *y, double *yerr, double *dydt_out, int use_in)
{
    gsl_odeiv2_step *s = gsl_odeiv2_step_alloc(T, sys->dimension);
    double din[64];
    cr_assert(s && sys->dimension <= 64);
    memcpy(y, y0, sys->dimension * sizeof(double));
    if (use_in) cr_assert_eq(GSL_ODEIV_FN_EVAL(sys, t, y0, din), GSL_SUCCESS);
    cr_assert_eq(gsl_odeiv2_step_apply(s, t, h, y, yerr, use_in ? din : NULL, dydt_out, sys), GSL_SUCCESS);
    gsl_odeiv2_step_free(s);
}

/* The type GSL's evolve and control see: order 8, name rk8pd. */
Test(rk8, step_type_is_rk8pd_of_order_8)
{
    gsl_odeiv2_step *s = gsl_odeiv2_step_alloc(cd_step_rk8pd, 2);
    cr_assert(s);
    cr_expect_str_eq(gsl_odeiv2_step_name(s), "rk8pd");
    cr_expect_eq(gsl_odeiv2_step_order(s), 8u);
    gsl_odeiv2_step_free(s);
}

/* On the smooth nonlinear system, from several states and step sizes, with
 * and without dydt_in: the result, the error estimate and dydt_out equal
 * GSL's rk8pd bit for bit (the same tableau, the stage sums in the same
 * order, -ffp-contract=off). */
Test(rk8, one_step_is_gsls_rk8pd_bit_for_bit)
{
    gsl_odeiv2_system sys = {smooth_f, smooth_j, 2, NULL};
    double hs[4] = {1e-4, 1e-2, 0.1, 0.7};
    int i, j, use_in, nsame = 0;
    for (i = 0; i < 5; i++)
        for (j = 0; j < 4; j++)
            for (use_in = 0; use_in < 2; use_in++) {
                double t = 0.37 * i, y0[2] = {2.0 + sin(t) + 0.1 * i, exp(-0.5 * t) - 0.05 * i};
                double ya[2], yb[2], ea[2], eb[2], fa[2], fb[2];
                step_of(cd_step_rk8pd, &sys, t, hs[j], y0, ya, ea, fa, use_in);
                step_of(gsl_odeiv2_step_rk8pd, &sys, t, hs[j], y0, yb, eb, fb, use_in);
                cr_expect(memcmp(ya, yb, sizeof ya) == 0 && memcmp(ea, eb, sizeof ea) == 0 &&
                              memcmp(fa, fb, sizeof fa) == 0,
                          "t %g h %g: y (%.17g, %.17g) vs GSL (%.17g, %.17g), yerr (%.3e, %.3e) vs (%.3e, %.3e)", t,
                          hs[j], ya[0], ya[1], yb[0], yb[1], ea[0], ea[1], eb[0], eb[1]);
                nsame++;
            }
    cr_log_info("%d steps compared", nsame);
}

/* The local error of one step from the exact solution at t = 0.3 falls at
 * least as h^9 (order 8; the smooth system: u1 = 2 + sin t, u2 =
 * exp(-t/2)), its 7th-order estimate at least as h^8: measured, not taken
 * on trust from GSL. On this problem the slopes come down to 9 and 8 from
 * above (10.4 and 9.1 between h = 0.4 and 0.2: the next terms still count)
 * until round-off takes over near h = 0.05, so the test asks for more than
 * 8.5 and 7.5: a method of order 7 (a wrong coefficient) would show 8 and 7. */
Test(rk8, local_error_is_of_order_9_and_its_estimate_of_order_8)
{
    gsl_odeiv2_system sys = {smooth_f, smooth_j, 2, NULL};
    double H[3] = {0.4, 0.2, 0.1}, e[3], est[3], t0 = 0.3;
    int i;
    for (i = 0; i < 3; i++) {
        gsl_odeiv2_step *s = gsl_odeiv2_step_alloc(cd_step_rk8pd, 2);
        double y[2], yerr[2], u[2];
        cr_assert(s);
        exact(t0, y);
        cr_assert_eq(gsl_odeiv2_step_apply(s, t0, H[i], y, yerr, NULL, NULL, &sys), GSL_SUCCESS);
        exact(t0 + H[i], u);
        e[i] = fmax(fabs(y[0] - u[0]), fabs(y[1] - u[1]));
        est[i] = fmax(fabs(yerr[0]), fabs(yerr[1]));
        gsl_odeiv2_step_free(s);
    }
    for (i = 0; i + 1 < 3; i++) {
        double p = log2(e[i] / e[i + 1]), q = log2(est[i] / est[i + 1]);
        cr_log_info("h %g -> %g: error %.3e -> %.3e (slope %.3f), estimate %.3e -> %.3e (slope %.3f)", H[i],
                    H[i + 1], e[i], e[i + 1], p, est[i], est[i + 1], q);
        cr_expect(p > 8.5, "error slope %.3f between h = %g and %g (errors %.3e, %.3e), expected > 8.5", p, H[i],
                  H[i + 1], e[i], e[i + 1]);
        cr_expect(q > 7.5, "estimate slope %.3f between h = %g and %g, expected > 7.5", q, H[i], H[i + 1]);
    }
}

/* the model's right-hand side for GSL (the integrator's own is internal) */
typedef struct {
    const cd_model *m;
    cd_data *d;
} model_sys;

static int model_f(double t, const double y[], double f[], void *p)
{
    model_sys *M = (model_sys *)p;
    double *save = M->d->y, ts = M->d->t;
    cd_status st;
    M->d->y = (double *)y;
    M->d->t = t;
    st = cd_forward(M->m, M->d);
    M->d->y = save;
    M->d->t = ts;
    if (st != CD_OK) return GSL_EBADFUNC;
    memcpy(f, M->d->ydot, (size_t)M->m->ny * sizeof(double));
    return GSL_SUCCESS;
}

/* is y index i inside the runs? */
static int in_runs(int i, int nr, const int *lo, const int *hi)
{
    int r;
    for (r = 0; r < nr; r++)
        if (i >= lo[r] && i < hi[r]) return 1;
    return 0;
}

/* A capture scene (432 slots) 0.1 s in, with fingers on the target: the
 * bound stepper's runs hold every unknown but the open slots' anchors; at
 * 200 random states around it (positions, velocities and anchors perturbed,
 * so open slots may even penetrate) every skipped unknown's derivative is
 * exactly 0; and one bound step equals GSL's full rk8pd step bit for bit, y
 * and error estimate, over all 1350 unknowns. */
Test(rk8, bound_step_skips_exactly_the_open_anchors, .timeout = 300)
{
    char path[1024];
    cd_error e;
    cd_scenario *sc;
    cd_data *d;
    const cd_model *m;
    model_sys M;
    gsl_odeiv2_system sys;
    gsl_odeiv2_step *own, *ref;
    const int *lo, *hi;
    double *y0, *ya, *yb, *ea, *eb, *f, hs[3] = {1e-6, 1e-5, 1e-4};
    int nr, i, k, trial, nopen = 0, nclosed = 0, nskip, ny;
    unsigned seed = 12345u;
    snprintf(path, sizeof path, "%s/scenarios/capture_too_fast.toml", step_root());
    sc = cd_scenario_load(path, NULL, 0, &e);
    cr_assert(sc, "%s", e.msg);
    m = sc->model;
    d = cd_data_create(m, sc->event_capacity, &e);
    cr_assert(d, "%s", e.msg);
    cr_assert_eq(cd_sim_advance(m, d, 0.1, NULL, NULL, &e), CD_OK, "%s", e.msg);
    for (k = 0; k < m->nslot; k++) {
        if (d->slot_mode[k] == CD_MODE_OPEN) nopen++;
        else nclosed++;
    }
    cr_assert(nclosed > 0 && nopen > 0, "the scene has closed (%d) and open (%d) slots at 0.1 s", nclosed, nopen);
    ny = m->ny;
    M.m = m;
    M.d = d;
    sys.function = model_f;
    sys.jacobian = NULL;
    sys.dimension = (size_t)ny;
    sys.params = &M;
    own = gsl_odeiv2_step_alloc(cd_step_rk8pd, (size_t)ny);
    ref = gsl_odeiv2_step_alloc(gsl_odeiv2_step_rk8pd, (size_t)ny);
    cr_assert(own && ref);
    cd_rk8_bind(own, &m, d);
    nr = cd_rk8_runs(own, &lo, &hi);
    for (i = 0, nskip = 0; i < ny; i++) nskip += !in_runs(i, nr, lo, hi);
    cr_expect_eq(nskip, 3 * nopen, "skipped %d unknowns, expected 3 x %d open slots", nskip, nopen);
    for (k = 0; k < m->nslot; k++)
        cr_expect_eq(in_runs(m->ny_slot_adr + 3 * k, nr, lo, hi), d->slot_mode[k] != CD_MODE_OPEN, "slot %d", k);
    y0 = malloc((size_t)ny * sizeof(double));
    ya = malloc((size_t)ny * sizeof(double));
    yb = malloc((size_t)ny * sizeof(double));
    ea = malloc((size_t)ny * sizeof(double));
    eb = malloc((size_t)ny * sizeof(double));
    f = malloc((size_t)ny * sizeof(double));
    cr_assert(y0 && ya && yb && ea && eb && f);
    memcpy(y0, d->y, (size_t)ny * sizeof(double));
    for (trial = 0; trial < 200; trial++) {
        memcpy(ya, y0, (size_t)ny * sizeof(double));
        for (i = 0; i < ny; i++) { /* relative 1e-3 and absolute 1e-4 perturbations */
            double r1, r2;
            seed = seed * 1103515245u + 12345u; r1 = (double)(seed >> 8) / 16777216.0 - 0.5;
            seed = seed * 1103515245u + 12345u; r2 = (double)(seed >> 8) / 16777216.0 - 0.5;
            ya[i] += 2e-3 * r1 * ya[i] + 2e-4 * r2;
        }
        cr_assert_eq(model_f(d->t, ya, f, &M), GSL_SUCCESS, "trial %d evaluates", trial);
        for (i = 0; i < ny; i++)
            if (!in_runs(i, nr, lo, hi) && f[i] != 0.0) {
                cr_expect(0, "trial %d: skipped unknown %d (slot %d) has derivative %.3e", trial, i,
                          (i - m->ny_slot_adr) / 3, f[i]);
                break;
            }
    }
    for (k = 0; k < 3; k++) {
        memcpy(ya, y0, (size_t)ny * sizeof(double));
        memcpy(yb, y0, (size_t)ny * sizeof(double));
        memset(ea, 0xff, (size_t)ny * sizeof(double)); /* the skipped ones must be written (0) */
        cr_assert_eq(gsl_odeiv2_step_apply(own, d->t, hs[k], ya, ea, NULL, NULL, &sys), GSL_SUCCESS);
        cr_assert_eq(gsl_odeiv2_step_apply(ref, d->t, hs[k], yb, eb, NULL, NULL, &sys), GSL_SUCCESS);
        cr_expect(memcmp(ya, yb, (size_t)ny * sizeof(double)) == 0, "h %g: y differs from GSL's rk8pd", hs[k]);
        cr_expect(memcmp(ea, eb, (size_t)ny * sizeof(double)) == 0, "h %g: yerr differs from GSL's rk8pd", hs[k]);
    }
    free(y0); free(ya); free(yb); free(ea); free(eb); free(f);
    gsl_odeiv2_step_free(own);
    gsl_odeiv2_step_free(ref);
    cd_data_free(d);
    cd_scenario_free(sc);
}
