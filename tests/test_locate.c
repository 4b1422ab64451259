/* Event location when the step's interpolant is off (src/sim/integrator.c,
 * locate and probe): a check point on a body spinning at a constant rate
 * meets a plane on a circle, so its approach is not a cubic and the cubic
 * Hermite interpolant of a long step (h_max 0.05 s) misplaces the crossing
 * by more than the 1e-10 s the events are located to. The certification by
 * the integrator's own step then fails on one end; the probe brackets the
 * crossing near that end instead of iterating over the rest of the step.
 * The onset must still land at the closed-form time, and the locator steps
 * stay few: with the bracket over the rest of the step (the code before the
 * probe, 831ed9f) rk8pd took 23 and 25 here at w = 10 and 30 rad/s. */
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include "scene_util.h"
#include "../src/sim/integ.h"

#include <math.h>

/* rotor of check-point radius r = 0.01 at 0.2 m from its spin axis (z),
 * spinning at w; the plane's solid is y >= 0.15: onset when
 * 0.2 sin(w t) + 0.01 = 0.15, t* = asin(0.7) / w.
 * hover: a second check point at the rotor's centre (on the spin axis: it
 * does not move), 5 mm from a second plane (y <= -0.015): within its
 * radius, so it stays in the smallest switching function with a small,
 * constant value, K * 5 mm = 50 N, while the rotating point's function
 * falls from ~1e3 N to about -K * 5 mm at the step's end. The minimum is
 * then one unit's function at the bracket's lower end and another's at its
 * upper end. */
typedef struct {
    double t_ev;   /* the first event */
    int kind;
    long nloc;     /* locator steps */
    long ninterp;  /* iterations on the interpolant */
    long nother;   /* events of other slots than 0 (the rotating point on the upper plane) */
    long ntrial, ntrial_fail; /* msbdf's own locator trials: solved, failed (cd_integ_locator_counts) */
} spin_out;

static spin_out spin_run(cd_stepper stepper, double w, int hover)
{
    cd_model *m = cd_model_create();
    cd_error e;
    cd_data *d;
    double Rs[9] = {1, 0, 0, 0, 0, -1, 0, 1, 0}, ps[3] = {0, 0.15, 0}, cp[3] = {0.2, 0, 0}, wv[3] = {0, 0, 0};
    double Rl[9] = {1, 0, 0, 0, 0, 1, 0, -1, 0}, pl[3] = {0, -0.015, 0}, c0[3] = {0, 0, 0};
    cd_contact_law law = cd_contact_law_default();
    int ground, rotor, sh, sh2, lid;
    long i;
    spin_out o;
    wv[2] = w;
    ground = add_system(m, "ground", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL);
    rotor = add_system(m, "rotor", CD_BASE_FREE, 1.0, 0.01, NULL, NULL, wv);
    sh = cd_model_add_shape(m, m->sys_body_adr[ground], CD_SHAPE_PLANE, ps, Rs, NULL, NULL, 0, &e);
    cr_assert(sh >= 0, "%s", e.msg);
    cr_assert(cd_model_add_checkpoint(m, m->sys_body_adr[rotor], cp, 0.01, &e) >= 0, "%s", e.msg);
    law.K = 1e4; law.D = 10; law.mu_s = law.mu_k = 0;
    lid = cd_model_add_law(m, &law, &e);
    cr_assert(lid >= 0, "%s", e.msg);
    cr_assert(cd_model_add_pair(m, rotor, -1, sh, lid, &e) >= 0, "%s", e.msg);
    if (hover) {
        sh2 = cd_model_add_shape(m, m->sys_body_adr[ground], CD_SHAPE_PLANE, pl, Rl, NULL, NULL, 0, &e);
        cr_assert(sh2 >= 0, "%s", e.msg);
        cr_assert(cd_model_add_checkpoint(m, m->sys_body_adr[rotor], c0, 0.01, &e) >= 0, "%s", e.msg);
        cr_assert(cd_model_add_pair(m, rotor, -1, sh2, lid, &e) >= 0, "%s", e.msg);
    }
    m->gravity[0] = m->gravity[1] = m->gravity[2] = 0;
    cr_assert_eq(cd_model_finalize(m, &e), CD_OK, "%s", e.msg);
    m->opt.stepper = stepper;
    m->opt.h_max = 0.05;
    m->opt.rtol = 1e-10;
    m->opt.atol = 1e-12;
    d = cd_data_create(m, 16, &e);
    cr_assert(d, "%s", e.msg);
    cr_assert_eq(cd_sim_advance(m, d, 1.05 * asin(0.7) / w, NULL, NULL, &e), CD_OK, "%s", e.msg);
    cr_assert_geq(d->ev_count, 1, "the check point reaches the plane");
    o.t_ev = cd_data_event(d, 0)->t;
    o.kind = cd_data_event(d, 0)->kind;
    o.nloc = d->stats.nlocate_steps;
    o.ninterp = d->stats.nlocate_interp;
    o.nother = 0;
    cd_integ_locator_counts(d, &o.ntrial, &o.ntrial_fail);
    for (i = 0; i < d->ev_count; i++)
        if (cd_data_event(d, i)->slot != 0) o.nother++; /* (mu = 0: the onset goes on to slip at once) */
    cd_data_free(d);
    cd_model_free(m);
    return o;
}

Test(locate, onset_on_a_circle_at_the_closed_form_time_with_few_locator_steps)
{
    /* the onset within 2e-10 s of t* (the 1e-10 s bracket plus the
     * integration's error at rtol 1e-10, ~1e-11 s at 1.4 m/s), in at most 8
     * locator steps (2 when both certifications hold; the old bracket over
     * the rest of the step took 23 and 25), at two spin rates and with
     * rk8pd, auto and msbdf (whose trials are its own steps, cd_bdf_trial) */
    const cd_stepper st[3] = {CD_STEP_RK8PD, CD_STEP_AUTO, CD_STEP_MSBDF};
    const double w[2] = {10.0, 30.0};
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 2; j++) {
            double ts = asin(0.7) / w[j];
            spin_out o = spin_run(st[i], w[j], 0);
            double t = o.t_ev;
            int kind = o.kind;
            long nloc = o.nloc;
            cr_log_info("%s, w = %g rad/s: onset at %.15g s (closed form %.15g, off by %.2e s), %ld locator steps",
                        cd_stepper_name(st[i]), w[j], t, ts, t - ts, nloc);
            cr_expect_eq(kind, CD_EV_ONSET);
            cr_expect_leq(fabs(t - ts), 2e-10, "%s, w %g: onset at %.15g s, closed form %.15g s", cd_stepper_name(st[i]),
                          w[j], t, ts);
            cr_expect_leq(nloc, 8, "%s, w %g: %ld locator steps", cd_stepper_name(st[i]), w[j], nloc);
            if (st[i] == CD_STEP_MSBDF) { /* its locator steps are its own trials, none fell back to rk8pd */
                cr_expect_eq(o.ntrial, nloc, "msbdf, w %g: %ld own trials for %ld locator steps", w[j], o.ntrial, nloc);
                cr_expect_eq(o.ntrial_fail, 0, "msbdf, w %g: %ld trials failed", w[j], o.ntrial_fail);
            }
        }
}

Test(locate, first_crossing_of_one_unit_under_another_units_minimum_in_few_iterations)
{
    /* The rotor with the hovering second check point (spin_run's hover):
     * the onset within 2e-10 s of t* as above, and the bracket on the
     * interpolant narrowed by the crossing unit's own secant (each unit's,
     * as SUNDIALS' rootfinding does), with the end game one tolerance from
     * an end instead of bisections: at most 12 iterations on the
     * interpolant. Measured: 10 and 6 (at w = 10 the first four are
     * bisections, the rotating point being farther than its radius from
     * the plane at the step's start, where it has no function value); the
     * secant of the minimum with bisections near the ends (before
     * 2026-11-27's change) took 31 and 29. */
    const double w[2] = {10.0, 30.0};
    int j;
    for (j = 0; j < 2; j++) {
        double ts = asin(0.7) / w[j];
        spin_out o = spin_run(CD_STEP_RK8PD, w[j], 1);
        double t = o.t_ev;
        long ninterp = o.ninterp, nloc = o.nloc, nother = o.nother;
        cr_log_info("w = %g rad/s: onset at %.15g s (closed form %.15g, off by %.2e s), %ld iterations on the "
                    "interpolant, %ld locator steps",
                    w[j], t, ts, t - ts, ninterp, nloc);
        cr_expect_eq(nother, 0, "only the rotating point touches, the upper plane");
        cr_expect_leq(fabs(t - ts), 2e-10, "w %g: onset at %.15g s, closed form %.15g s", w[j], t, ts);
        cr_expect_leq(ninterp, 12, "w %g: %ld iterations on the interpolant", w[j], ninterp);
        cr_expect_leq(nloc, 8, "w %g: %ld locator steps", w[j], nloc);
    }
}
