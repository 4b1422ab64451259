/* The normal damping laws (issue 22): the paper's linear damper and the
 * Hunt-Crossley damper, against closed forms of a 1-DoF impact.
 *
 * Scene: a free ball (mass m, check point of radius r at its CoM) moving at
 * -v0 onto a fixed plane, no gravity, frictionless; x the penetration.
 *
 * Hunt-Crossley (Hunt & Crossley 1975), f = K x^p + D x^p xdot = K x^p (1 + u),
 * u = D xdot / K. With v = xdot, m v dv/dx = -K x^p (1 + u), so
 *   (m K / D^2) [u - ln(1 + u)] du-integrated = -x^(p+1)/(p+1) + const,
 * i.e. u - ln(1 + u) + (D^2/(m K)) x^(p+1)/(p+1) is conserved. At onset and at
 * separation x = 0, so the rebound u_out = -e u_in solves
 *   u_out - ln(1 + u_out) = u_in - ln(1 + u_in),   -1 < u_out < 0,
 * for every p and m: the exact restitution e(u_in), u_in = D v0 / K, which
 * falls with the impact speed (e = 1 - 2u/3 + 4u^2/9 + O(u^3): Hunt and
 * Crossley's D = 3 K (1 - e) / (2 v0) to first order). f >= 0 throughout
 * (1 + u > 0), so the contact ends at x = 0 with f = 0. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include "scene_util.h"
#include <math.h>
#include <string.h>

typedef ball_scene scene;

static cd_contact_law law_of(int damping, double K, double D, double p)
{
    cd_contact_law law = cd_contact_law_default();
    law.K = K;
    law.D = D;
    law.p = p;
    law.q = 1.0;
    law.damping = damping;
    law.Kt = 1e3;
    law.Dt = 0;
    law.mu_s = law.mu_k = 0;
    return law;
}

static scene ball(double mass, double r, double gap, double v0, const cd_contact_law *law)
{
    return ball_on_plane(mass, r, gap, v0, law, 1e-4);
}

static void scene_free(scene *sc) { ball_scene_free(sc); }

static void advance(scene *sc, double t)
{
    cd_error e;
    cr_assert_eq(cd_sim_advance(sc->m, sc->d, t, NULL, NULL, &e), CD_OK, "%s", e.msg);
}

/* the exact Hunt-Crossley restitution for u_in = D v0 / K (bisection on the first integral) */
static double hc_restitution(double u_in)
{
    double C = u_in - log1p(u_in), lo = -1.0 + 1e-300, hi = 0.0;
    int i;
    for (i = 0; i < 200; i++) {
        double mid = 0.5 * (lo + hi);
        if (mid - log1p(mid) > C) lo = mid;
        else hi = mid;
    }
    return -0.5 * (lo + hi) / u_in;
}

/* Restitution against impact speed, p = 1 and p = 1.5 (Hertz-like), three
 * speeds spanning u_in = 0.06 .. 0.9: the simulated e agrees with the exact
 * first integral to 1e-6 (relative; events to 1e-10 s, rtol 1e-12), e falls
 * with the speed, and e lies within 0.45 u^2 above Hunt and Crossley's
 * first-order 1 - 2u/3. The contact ends at x = 0 (|x| < 1e-9 m at the
 * separation event): no early separation as with the linear damper. */
Test(contact_law, hunt_crossley_restitution_against_impact_speed)
{
    const double ps[2] = {1.0, 1.5}, Ks[2] = {1e4, 1e6}, v0s[3] = {0.2, 1.0, 3.0};
    const double mass = 1.0, r = 0.05, gap = 1e-3;
    int i, j;
    for (i = 0; i < 2; i++) {
        /* D sized by Hunt and Crossley's rule for e = 0.8 at 1 m/s: D = 3 K (1 - e) / (2 v) */
        double K = Ks[i], D = 3.0 * K * (1.0 - 0.8) / 2.0, e_prev = 2.0;
        for (j = 0; j < 3; j++) {
            double v0 = v0s[j], u = D * v0 / K, e_exact = hc_restitution(u), e_sim;
            cd_contact_law law = law_of(CD_DAMP_HUNT_CROSSLEY, K, D, ps[i]);
            scene sc = ball(mass, r, gap, v0, &law);
            const cd_event *on, *sep;
            advance(&sc, gap / v0 + 0.5);
            cr_assert_eq(sc.d->ev_count, 2, "p %g v0 %g: onset + separation, got %ld events", ps[i], v0,
                         sc.d->ev_count);
            on = cd_data_event(sc.d, 0);
            sep = cd_data_event(sc.d, 1);
            cr_assert_eq(on->kind, CD_EV_ONSET);
            cr_assert_eq(sep->kind, CD_EV_SEPARATION);
            e_sim = cd_state_of(sc.m, sc.d, sc.ball).vel[2] / v0;
            cr_log_info("hunt-crossley p %.1f v0 %.1f (u %.3f): e %.12g, exact %.12g (rel %.1e), first order %.6g, "
                        "x at separation %.2e m",
                        ps[i], v0, u, e_sim, e_exact, fabs(e_sim - e_exact) / e_exact, 1.0 - 2.0 * u / 3.0, sep->x);
            cr_expect_lt(fabs(e_sim - e_exact) / e_exact, 1e-6, "p %g v0 %g: e %.12g, exact %.12g", ps[i], v0, e_sim,
                         e_exact);
            cr_expect_lt(e_exact, e_prev, "restitution falls with the impact speed");
            cr_expect(e_exact - (1.0 - 2.0 * u / 3.0) > 0 && e_exact - (1.0 - 2.0 * u / 3.0) < 0.45 * u * u,
                      "u %g: e %.9g against 1 - 2u/3 = %.9g", u, e_exact, 1.0 - 2.0 * u / 3.0);
            cr_expect_lt(fabs(sep->x), 1e-9, "separation at x = 0: x = %.3g m", sep->x);
            e_prev = e_exact;
            scene_free(&sc);
        }
    }
}

/* Force at onset and at separation, at delta = 1e-7 s inside the contact.
 * Hunt-Crossley, p = 1: x ~ v delta, so f ~ (K + D v) v delta: 1e-4 N here,
 * continuous (zero) at both ends; checked against that first-order value to
 * 1e-3. The linear law (paper eq. 3), unchanged: f ~ D v0 at onset, the jump. */
Test(contact_law, force_continuous_at_onset_and_separation)
{
    const double mass = 1.0, K = 1e4, D = 3000.0, r = 0.05, gap = 1e-3, v0 = 1.0, dt = 1e-7;
    cd_contact_law hc = law_of(CD_DAMP_HUNT_CROSSLEY, K, D, 1.0), lin = law_of(CD_DAMP_LINEAR, K, 100.0, 1.0);
    scene a = ball(mass, r, gap, v0, &hc), b, c;
    double t_on, t_sep, v_out, f_on, f_sep, want;
    advance(&a, gap / v0 + 0.5);
    cr_assert_eq(a.d->ev_count, 2);
    t_on = cd_data_event(a.d, 0)->t;
    t_sep = cd_data_event(a.d, 1)->t;
    v_out = cd_state_of(a.m, a.d, a.ball).vel[2];
    scene_free(&a);
    b = ball(mass, r, gap, v0, &hc);
    advance(&b, t_on + dt);
    f_on = b.d->slot_fn[0];
    want = (K + D * v0) * v0 * dt;
    cr_log_info("hunt-crossley: f %.6g N at onset + %g s (first order %.6g N)", f_on, dt, want);
    cr_expect_lt(fabs(f_on / want - 1.0), 1e-3, "onset: f %.9g N, first order %.9g N", f_on, want);
    advance(&b, t_sep - dt);
    f_sep = b.d->slot_fn[0];
    want = (K - D * v_out) * v_out * dt;
    cr_log_info("hunt-crossley: f %.6g N at separation - %g s (first order %.6g N)", f_sep, dt, want);
    cr_expect_lt(fabs(f_sep / want - 1.0), 1e-3, "separation: f %.9g N, first order %.9g N", f_sep, want);
    scene_free(&b);
    c = ball(mass, r, gap, v0, &lin);
    advance(&c, gap / v0 + dt);
    cr_expect_eq(c.d->slot_mode[0], CD_MODE_STICK, "closed");
    cr_expect_lt(fabs(c.d->slot_fn[0] / (100.0 * v0) - 1.0), 1e-3, "linear law: f %.9g N at onset, D v0 = %g N",
                 c.d->slot_fn[0], 100.0 * v0);
    scene_free(&c);
}

/* The model rejects an unknown damping law by name of the field. */
Test(contact_law, model_rejects_an_unknown_damping_law)
{
    cd_model *m = cd_model_create();
    cd_contact_law law = cd_contact_law_default();
    cd_error e;
    law.damping = 7;
    cr_expect_lt(cd_model_add_law(m, &law, &e), 0);
    cr_expect_str_eq(e.msg, "contact law: damping must be CD_DAMP_LINEAR (0) or CD_DAMP_HUNT_CROSSLEY (1), got 7");
    cd_model_free(m);
}
