/* Impact validation of the normal contact law (issue 3, tests 1, 2 and 5).
 *
 * Scenes are built by code: a fixed "ground"/"wall" system (no links) carrying
 * a plane (half-space z <= 0, normal +z) and a free system that hits it with
 * a check point (a sphere of radius r). Penetration x = r - z_centre; the law
 * is f = K x^p + D xdot^q while the slot is closed (sim.h, contact.c). The
 * slot closes when x crosses 0 upward and opens when min(K x, f_raw) crosses
 * 0 downward: with damping that is where f_n = K x + D xdot reaches 0 (no
 * pull), before x returns to 0. Events are located to opt.event_tol = 1e-10 s,
 * so an onset -> separation interval from the event log is good to ~2e-10 s.
 * No gravity. Friction plays no part (the motion is along the normal: the
 * tangential velocity and the stick spring stay exactly 0). */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include "scene_util.h"
#include <gsl/gsl_integration.h>
#include <gsl/gsl_sf_gamma.h>
#include <math.h>
#include <string.h>
#include <time.h>

static const double PI = 3.14159265358979323846;

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}



/* normal law only: frictionless (mu_s = mu_k = 0 is accepted by the model;
 * K_t must be > 0 and is irrelevant here) */
static cd_contact_law normal_law(double K, double D, double p, double q)
{
    cd_contact_law law = cd_contact_law_default();
    law.K = K;
    law.D = D;
    law.p = p;
    law.q = q;
    law.Kt = 1e3;
    law.Dt = 0;
    law.mu_s = law.mu_k = 0;
    return law;
}

/* A ball (mass m, check point of radius r at its CoM) at height r + gap,
 * moving at -v0 toward the ground plane. */
typedef ball_scene scene;

static scene ball_scene_of(double mass, double r, double gap, double v0, const cd_contact_law *law)
{
    return ball_on_plane(mass, r, gap, v0, law, 1e-3 /* < 1/30 of every contact duration below */);
}

static void scene_free(scene *sc) { ball_scene_free(sc); }

/* Runs a single impact to t_end; returns onset and separation times and the
 * rebound velocity; asserts the event log holds exactly onset, separation. */
static void run_impact(scene *sc, double t_end, double *t_on, double *t_sep, double *v_out)
{
    cd_error e;
    const cd_event *e0, *e1;
    cd_sys_state x;
    cr_assert_eq(cd_sim_advance(sc->m, sc->d, t_end, NULL, NULL, &e), CD_OK, "%s", e.msg);
    cr_assert_eq(sc->d->ev_count, 2, "one impact: onset + separation, got %ld events", sc->d->ev_count);
    e0 = cd_data_event(sc->d, 0);
    e1 = cd_data_event(sc->d, 1);
    cr_assert_eq(e0->kind, CD_EV_ONSET);
    cr_assert_eq(e1->kind, CD_EV_SEPARATION);
    cr_assert_eq(sc->d->slot_mode[0], CD_MODE_OPEN);
    x = cd_state_of(sc->m, sc->d, sc->ball);
    /* the motion stays on the normal: no friction, no spin */
    cr_expect_eq(x.vel[0], 0.0);
    cr_expect_eq(x.vel[1], 0.0);
    cr_expect_eq(x.angvel[0] * x.angvel[0] + x.angvel[1] * x.angvel[1] + x.angvel[2] * x.angvel[2], 0.0);
    *t_on = e0->t;
    *t_sep = e1->t;
    *v_out = x.vel[2];
}

/* ---- test 1: linear spring-dashpot impact ------------------------------------
 * Closed form of the SAME model (separation at f_n = 0, not at x = 0).
 * With x the penetration, m x'' = -(K x + D x'), x(0) = 0, x'(0) = v0, and
 * wn = sqrt(K/m), zeta = D / (2 sqrt(K m)), wd = wn sqrt(1 - zeta^2):
 *   x(t)  = (v0/wd) e^{-zeta wn t} sin(wd t)
 *   x'(t) = v0 e^{-zeta wn t} [cos(wd t) - zeta/sqrt(1-zeta^2) sin(wd t)]
 * Write zeta = sin(b), sqrt(1 - zeta^2) = cos(b), phi = wd t. Then
 *   f_n/m = wn^2 x + 2 zeta wn x'
 *         = v0 wn e^{-zeta wn t} [(1 - 2 zeta^2) sin(phi) + 2 zeta sqrt(1-zeta^2) cos(phi)] / sqrt(1-zeta^2)
 *         = v0 wn e^{-zeta wn t} [cos(2b) sin(phi) + sin(2b) cos(phi)] / cos(b)
 *         = v0 wn e^{-zeta wn t} sin(phi + 2b) / cos(b),
 * so f_n = D v0 > 0 at onset and first returns to 0 at phi = pi - 2b:
 *   contact duration  t_c = (pi - 2 asin(zeta)) / wd = 2 acos(zeta) / wd.
 * Likewise x'(t) = v0 e^{-zeta wn t} cos(phi + b) / cos(b); at phi = pi - 2b,
 * cos(pi - b) = -cos(b), so x' = -v0 e^{-zeta wn t_c}: the ball leaves with
 *   e = v_out / v_in = exp(-zeta wn t_c) = exp(-2 zeta acos(zeta) / sqrt(1 - zeta^2)).
 * (x(t_c) = (v0/wd) e sin(2b) > 0: it leaves while still "penetrating", then
 * flies freely, so the slot stays open: K x + D x' < 0 from then on.) */
Test(contact_impact, linear_spring_dashpot_restitution_and_duration)
{
    const double zetas[3] = {0.05, 0.3, 0.7};
    const double mass = 1.0, K = 1e4, r = 0.05, gap = 0.01, v0 = 1.0;
    int i;
    for (i = 0; i < 3; i++) {
        double zeta = zetas[i], D = 2.0 * zeta * sqrt(K * mass);
        double wn = sqrt(K / mass), wd = wn * sqrt(1.0 - zeta * zeta);
        double tc_exact = 2.0 * acos(zeta) / wd, e_exact = exp(-zeta * wn * tc_exact);
        double t_on, t_sep, v_out, tc, e, err_tc, err_e;
        cd_contact_law law = normal_law(K, D, 1.0, 1.0);
        scene sc = ball_scene_of(mass, r, gap, v0, &law);
        run_impact(&sc, gap / v0 + 2.0 * tc_exact, &t_on, &t_sep, &v_out);
        tc = t_sep - t_on;
        e = v_out / v0;
        err_tc = fabs(tc - tc_exact) / tc_exact;
        err_e = fabs(e - e_exact) / e_exact;
        cr_log_info("linear zeta %.2f: t_c %.12g (exact %.12g, rel %.1e), e %.12g (exact %.12g, rel %.1e), nrhs %ld",
                    zeta, tc, tc_exact, err_tc, e, e_exact, err_e, sc.d->stats.nrhs);
        /* free flight to the plane: onset at gap / v0 (event_tol 1e-10 s) */
        cr_expect_leq(fabs(t_on - gap / v0), 1e-9, "onset at %.15g, expected %.15g", t_on, gap / v0);
        cr_expect_leq(err_tc, 1e-6, "zeta %.2f: contact duration %.12g s, exact %.12g s", zeta, tc, tc_exact);
        cr_expect_leq(err_e, 1e-6, "zeta %.2f: restitution %.12g, exact %.12g", zeta, e, e_exact);
        scene_free(&sc);
    }
}

/* The same closed form with the linearly implicit stepper (ros34pw2, order
 * 3): events are located by its own steps, the contact duration and the
 * restitution agree with the closed form to the same 1e-6 at rtol 1e-12. */
Test(contact_impact, linear_impact_with_the_stiff_stepper)
{
    const double mass = 1.0, K = 1e4, r = 0.05, gap = 0.01, v0 = 1.0, zeta = 0.3;
    double D = 2.0 * zeta * sqrt(K * mass), wn = sqrt(K / mass), wd = wn * sqrt(1.0 - zeta * zeta);
    double tc_exact = 2.0 * acos(zeta) / wd, e_exact = exp(-zeta * wn * tc_exact), t_on, t_sep, v_out;
    cd_contact_law law = normal_law(K, D, 1.0, 1.0);
    scene sc = ball_scene_of(mass, r, gap, v0, &law);
    cd_error e;
    cd_data_free(sc.d);
    sc.m->opt.stepper = CD_STEP_ROS34PW2;
    sc.d = cd_data_create(sc.m, 0, &e);
    cr_assert(sc.d, "%s", e.msg);
    run_impact(&sc, gap / v0 + 2.0 * tc_exact, &t_on, &t_sep, &v_out);
    cr_log_info("ros34pw2: t_c rel %.1e, e rel %.1e, %ld steps, %ld rhs, %ld Jacobians",
                fabs(t_sep - t_on - tc_exact) / tc_exact, fabs(v_out / v0 - e_exact) / e_exact, sc.d->stats.nsteps,
                sc.d->stats.nrhs, sc.d->stats.njac);
    cr_expect_leq(fabs(t_on - gap / v0), 1e-9, "onset at %.15g", t_on);
    cr_expect_leq(fabs(t_sep - t_on - tc_exact) / tc_exact, 1e-6, "contact duration %.12g s, exact %.12g s", t_sep - t_on,
                  tc_exact);
    cr_expect_leq(fabs(v_out / v0 - e_exact) / e_exact, 1e-6, "restitution %.12g, exact %.12g", v_out / v0, e_exact);
    cr_expect_gt(sc.d->stats.njac, 0, "the stepper formed its Jacobian");
    scene_free(&sc);
}

/* ---- test 2: Hertz impact ------------------------------------------------------
 * m x'' = -K x^{3/2} (D = 0). Energy: (1/2) m x'^2 + (2/5) K x^{5/2} = (1/2) m v0^2,
 * so x_max = (5 m v0^2 / (4 K))^{2/5} and, the motion being symmetric in time
 * (no damping: separation at x = 0 with x' = -v0),
 *   t_c = 2 int_0^{x_max} dx / sqrt(v0^2 - (4K/5m) x^{5/2})
 *       = 2 (x_max / v0) int_0^1 du / sqrt(1 - u^{5/2})        (u = x / x_max)
 *       = 2 (x_max / v0) (2/5) B(2/5, 1/2)                     (w = u^{5/2})
 *       = (4/5) sqrt(pi) Gamma(2/5) / Gamma(9/10) * (x_max / v0).
 * With x_max / v0 = (5/4)^{2/5} (m^2 / (K^2 v0))^{1/5}:
 *   t_c = C (m^2 / (K^2 v0))^{1/5},  C = (4/5) (5/4)^{2/5} sqrt(pi) Gamma(2/5) / Gamma(9/10)
 *       = 3.2180654597...
 * (2.9432 x_max / v0 is the classic form; issue 3's "3.2145" is 2.94 x 1.0934,
 * i.e. the rounded 2.94 -- the exact constant differs from it by 1.1e-3.)
 * Checked for three speeds, which also checks the v0^{-1/5} scaling. */
static double hertz_integrand(double u, void *params)
{
    (void)params;
    return 1.0 / sqrt(1.0 - pow(u, 2.5));
}

Test(contact_impact, hertz_contact_duration_and_energy)
{
    const double speeds[3] = {0.5, 1.0, 2.0};
    const double mass = 1.0, K = 1e6, r = 0.05, gap = 0.002;
    const double C = 0.8 * pow(1.25, 0.4) * sqrt(PI) * gsl_sf_gamma(0.4) / gsl_sf_gamma(0.9);
    int i;
    /* the Beta-function step checked by quadrature: int_0^1 du / sqrt(1 - u^{5/2})
     * (integrable singularity at u = 1, QAGS) = (2/5) B(2/5, 1/2) */
    {
        gsl_integration_workspace *w = gsl_integration_workspace_alloc(200);
        gsl_function fn;
        double I, abserr, B = 0.4 * gsl_sf_beta(0.4, 0.5);
        fn.function = hertz_integrand;
        fn.params = NULL;
        cr_assert(w);
        cr_assert_eq(gsl_integration_qags(&fn, 0.0, 1.0, 0.0, 1e-12, 200, w, &I, &abserr), 0);
        gsl_integration_workspace_free(w);
        cr_log_info("hertz: C = %.13g; quadrature %.15g vs (2/5) B(2/5,1/2) %.15g", C, I, B);
        cr_expect_leq(fabs(I - B), 1e-10, "quadrature %.15g vs (2/5) B(2/5, 1/2) = %.15g", I, B);
    }
    for (i = 0; i < 3; i++) {
        double v0 = speeds[i], tc_exact = C * pow(mass * mass / (K * K * v0), 0.2);
        double t_on, t_sep, v_out, tc, err_tc, err_E;
        cd_contact_law law = normal_law(K, 0.0, 1.5, 1.0);
        scene sc = ball_scene_of(mass, r, gap, v0, &law);
        run_impact(&sc, gap / v0 + 2.0 * tc_exact, &t_on, &t_sep, &v_out);
        tc = t_sep - t_on;
        err_tc = fabs(tc - tc_exact) / tc_exact;
        /* energy returned: (1/2) m v_out^2 against (1/2) m v_in^2 */
        err_E = fabs(v_out * v_out / (v0 * v0) - 1.0);
        cr_log_info("hertz v0 %.1f: t_c %.12g (exact %.12g, rel %.1e), energy ratio - 1 = %.1e, nrhs %ld",
                    v0, tc, tc_exact, err_tc, err_E, sc.d->stats.nrhs);
        cr_expect_leq(err_tc, 1e-5, "v0 %.1f: contact duration %.12g s, exact %.12g s", v0, tc, tc_exact);
        cr_expect_leq(err_E, 1e-8, "v0 %.1f: energy returned, relative error %.3e", v0, err_E);
        cr_expect_gt(v_out, 0.0);
        scene_free(&sc);
    }
}

/* ---- test 5: the paper's Figs. 2-3 ------------------------------------------------
 * A carrier of mass M (free base) holds a front mass m on a soft spring K_a:
 * m is a prismatic link along z (axis +z: q > 0 compresses the spring) with a
 * PD actuator kp = K_a, kd = 0, qref = 0 -- a pure spring; the dissipation is
 * in the contact. The check point (radius 0) is on m; the wall is the plane
 * z = 0 of a fixed system, contact stiffness K_b with a small damping ratio
 * zeta_b (relative to m). Everything moves at -v0 toward the wall.
 *
 * M = 10 kg, m = 0.1 kg, K_a = pi^2 M / 0.2^2 (= 2467 N/m, M-K_a half period
 * 0.2 s as in the paper), K_b = 1e6 N/m (400 K_a), zeta_b = 0.1, v0 = 1 m/s.
 *
 * What the event log shows (and what is compared):
 *  - First strike: event 0 (onset) -> event 1 (separation). Over ~1 ms the
 *    soft spring carries K_a/K_b = 0.25 % of the contact force and M is
 *    decoupled, so the strike is the linear spring-dashpot impact of m alone
 *    on K_b (m_eff = m): by test 1's closed form it lasts
 *    t_1 = 2 acos(zeta_b) / (w_b sqrt(1 - zeta_b^2)). The measured frequency
 *    w_meas = 2 acos(zeta_b) / (sqrt(1 - zeta_b^2) t_1) is compared with
 *    w_b = sqrt(K_b/m), 2 % (the neglected K_a and M motion shift it ~0.3 %).
 *    Its force peak, from the same closed form (max of sin(phi+2b)e^{..}:
 *    phi = pi/2 - 3b), is v0 sqrt(K_b m) exp(-(pi/2 - 3 asin zeta) zeta/sqrt(1-zeta^2));
 *    the sampled peak is compared with it, 2 %.
 *  - m rebounds (the spring is barely compressed), M keeps coming, m is
 *    pushed back to the wall: a few more strikes follow, each losing
 *    energy in the contact damper, until m stays on the wall (the re-strikes
 *    are as sharp as the first and, with M's spring now loaded, their peaks
 *    are higher: measured up to 348 N). From then on m
 *    is pinned and M oscillates on K_a (in series with K_b: +0.12 %) and the
 *    contact holds while the spring is compressed, i.e. for half an M-K_a
 *    period; when the spring is back at its free length the contact force
 *    reaches 0 and m leaves the wall with M.
 *  - The "slow contact phase" is therefore defined as first onset -> final
 *    separation (the last event; the run continues to 0.3 s to show that no
 *    contact recurs, with the carrier moving away). It is compared with
 *    pi sqrt(M/K_a) = 0.2 s, 2 %. The force peak of the last (persistent)
 *    contact is where M's kinetic energy is in the spring: K_a q_max =
 *    v0 sqrt(K_a M) (M loses ~1 % of its momentum in the strikes), compared
 *    on the samples, 2 %.
 *  - The force is sampled every 5e-5 s with cd_sim_advance and d->slot_fn[0];
 *    between the first separation and the second onset every sample is 0. */
typedef struct { cd_model *m; cd_data *d; int carrier, front; } fig3_scene;

static const double F3_M = 10.0, F3_m = 0.1, F3_KB = 1e6, F3_ZETA = 0.1, F3_V0 = 1.0;
static const double F3_GAP = 1.234e-3;

static fig3_scene fig3_build(void)
{
    fig3_scene f;
    cd_error e;
    cd_link_desc l = cd_link_desc_default();
    cd_actuator act;
    cd_contact_law law;
    double Ka = PI * PI * F3_M / (0.2 * 0.2), arm = 0.1, zero[3] = {0, 0, 0};
    double pos[3] = {0, 0, 0}, vel[3] = {0, 0, 0};
    int wall, plane, lid;
    f.m = cd_model_create();
    cr_assert(f.m);
    wall = add_system(f.m, "wall", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL);
    plane = add_plane(f.m, f.m->sys_body_adr[wall]);
    pos[2] = arm + F3_GAP;
    vel[2] = -F3_V0;
    f.carrier = add_system(f.m, "carrier", CD_BASE_FREE, F3_M, 0.1, pos, vel, NULL);
    l.name = "front";
    l.parent = f.m->sys_body_adr[f.carrier];
    l.type = CD_JOINT_PRISMATIC;
    l.pos[0] = l.pos[1] = 0;
    l.pos[2] = -arm;
    l.axis[0] = l.axis[1] = 0;
    l.axis[2] = 1;
    l.mass = F3_m;
    memset(l.com, 0, sizeof l.com);
    memset(l.inertia, 0, sizeof l.inertia);
    l.inertia[0] = l.inertia[4] = l.inertia[8] = 1e-4;
    l.q0 = l.qd0 = 0;
    f.front = cd_model_add_link(f.m, f.carrier, &l, &e);
    cr_assert(f.front >= 0, "%s", e.msg);
    memset(&act, 0, sizeof act);
    act.type = CD_ACT_PD;
    act.kp = Ka;
    act.kd = 0;
    act.qref = 0;
    cr_assert_eq(cd_model_set_actuator(f.m, f.front, &act, &e), CD_OK, "%s", e.msg);
    cr_assert(cd_model_add_checkpoint(f.m, f.front, zero, 0.0, &e) >= 0, "%s", e.msg);
    law = normal_law(F3_KB, 2.0 * F3_ZETA * sqrt(F3_KB * F3_m), 1.0, 1.0);
    lid = cd_model_add_law(f.m, &law, &e);
    cr_assert(lid >= 0, "%s", e.msg);
    cr_assert(cd_model_add_pair(f.m, f.carrier, f.front, plane, lid, &e) >= 0, "%s", e.msg);
    cr_assert_eq(cd_model_finalize(f.m, &e), CD_OK, "%s", e.msg);
    f.m->opt.rtol = 1e-10;
    f.m->opt.atol = 1e-12;
    /* h_max stays at its default (1e-2 s): the adaptive control resolves the
     * 1 ms strikes by itself, and every onset is caught since an open slot
     * exerts no force (the penetration keeps growing past the crossing) */
    f.d = cd_data_create(f.m, 0, &e);
    cr_assert(f.d, "%s", e.msg);
    return f;
}

Test(contact_impact, paper_fig3_first_strike_and_slow_phase)
{
    const double Ka = PI * PI * F3_M / (0.2 * 0.2), T_END = 0.3, DT = 5e-5;
    const double w_b = sqrt(F3_KB / F3_m), z = F3_ZETA, sq = sqrt(1.0 - z * z);
    const double T_slow = PI * sqrt(F3_M / Ka);
    const double f1_exact = F3_V0 * sqrt(F3_KB * F3_m) * exp(-(PI / 2 - 3.0 * asin(z)) * z / sq);
    const double f2_exact = F3_V0 * sqrt(Ka * F3_M);
    fig3_scene f = fig3_build();
    cd_error e;
    const cd_event *ev0, *ev1, *ev2, *evl, *evlo;
    static double samp_t[6000], samp_f[6000];
    double t0, wall_s, t1, w_meas, slow, f1max = 0, f2max = 0, gapmax = 0, t_final;
    long i, nsamp = (long)(T_END / DT + 0.5), ngap = 0, nrhs_sampled, n_on = 0;

    cr_assert_leq(nsamp, 6000);
    t0 = now_s();
    for (i = 1; i <= nsamp; i++) {
        cr_assert_eq(cd_sim_advance(f.m, f.d, i * DT, NULL, NULL, &e), CD_OK, "%s", e.msg);
        samp_t[i - 1] = f.d->t;
        samp_f[i - 1] = f.d->slot_fn[0];
    }
    wall_s = now_s() - t0;
    nrhs_sampled = f.d->stats.nrhs;

    cr_assert_geq(f.d->ev_count, 4, "at least a strike and the slow phase, got %ld events", f.d->ev_count);
    cr_assert_lt(f.d->ev_count, f.d->ev_cap, "the whole log is held");
    ev0 = cd_data_event(f.d, 0);
    ev1 = cd_data_event(f.d, 1);
    ev2 = cd_data_event(f.d, 2);
    evl = cd_data_event(f.d, f.d->ev_count - 1);
    for (i = 0; i < f.d->ev_count; i++) {
        const cd_event *ev = cd_data_event(f.d, i);
        cr_assert_eq(ev->kind, i % 2 == 0 ? CD_EV_ONSET : CD_EV_SEPARATION, "event %ld alternates", i);
        if (ev->kind == CD_EV_ONSET) n_on++;
    }
    cr_assert_eq(evl->kind, CD_EV_SEPARATION, "the run ends separated");
    evlo = cd_data_event(f.d, f.d->ev_count - 2);
    /* classify the samples by the event log: first strike, open gap after it,
     * the last (persistent) contact */
    for (i = 0; i < nsamp; i++) {
        if (samp_t[i] > ev0->t && samp_t[i] < ev1->t && samp_f[i] > f1max) f1max = samp_f[i];
        if (samp_t[i] > ev1->t && samp_t[i] < ev2->t) {
            ngap++;
            if (fabs(samp_f[i]) > gapmax) gapmax = fabs(samp_f[i]);
        }
        if (samp_t[i] > evlo->t && samp_t[i] < evl->t && samp_f[i] > f2max) f2max = samp_f[i];
    }
    cr_expect_eq(f.d->slot_mode[0], CD_MODE_OPEN);
    cr_expect_gt(cd_state_of(f.m, f.d, f.carrier).vel[2], 0.0, "the carrier moves away from the wall");
    cr_expect_lt(evl->t, T_END - 0.05, "nothing happens in the last 0.05 s");
    cr_expect_leq(fabs(ev0->t - F3_GAP / F3_V0), 1e-9, "first onset at gap / v0");

    /* first strike */
    t1 = ev1->t - ev0->t;
    w_meas = 2.0 * acos(z) / (sq * t1);
    /* slow contact phase */
    t_final = evl->t;
    slow = t_final - ev0->t;
    cr_log_info("fig3: %ld events (%ld strikes), first strike %.6e s: w_meas %.2f rad/s vs sqrt(K_b/m) %.2f "
                "(rel %.2e); slow phase %.6f s vs pi sqrt(M/K_a) %.6f (rel %.2e); last contact from %.6f s",
                f.d->ev_count, n_on, t1, w_meas, w_b, (w_meas - w_b) / w_b, slow, T_slow, (slow - T_slow) / T_slow,
                evlo->t);
    cr_log_info("fig3: strike peak %.2f N (exact %.2f, rel %.2e); slow peak %.2f N (v0 sqrt(K_a M) %.2f, rel %.2e)",
                f1max, f1_exact, (f1max - f1_exact) / f1_exact, f2max, f2_exact, (f2max - f2_exact) / f2_exact);
    cr_log_info("fig3: sampled run (%ld calls of cd_sim_advance): nrhs %ld, nsteps %ld, wall %.3f s",
                nsamp, nrhs_sampled, f.d->stats.nsteps, wall_s);
    cr_expect_leq(fabs(w_meas - w_b) / w_b, 0.02, "first-strike frequency %.2f rad/s vs sqrt(K_b/m) = %.2f",
                  w_meas, w_b);
    cr_expect_leq(fabs(slow - T_slow) / T_slow, 0.02, "slow contact phase %.6f s vs pi sqrt(M/K_a) = %.6f s",
                  slow, T_slow);
    /* two time scales: the strike is two orders of magnitude shorter */
    cr_expect_lt(t1, 0.01 * slow, "strike %.3e s vs slow phase %.3e s", t1, slow);
    /* the force profile */
    cr_expect_leq(fabs(f1max - f1_exact) / f1_exact, 0.02, "strike peak %.3f N vs %.3f N", f1max, f1_exact);
    cr_expect_leq(fabs(f2max - f2_exact) / f2_exact, 0.02, "slow peak %.3f N vs %.3f N", f2max, f2_exact);
    cr_expect_gt(ngap, 0, "samples fall in the open gap after the first strike (%.3e s)", ev2->t - ev1->t);
    cr_expect_eq(gapmax, 0.0, "no force while open");

    /* the same run in one call: the integrator's own cost, same event times */
    {
        fig3_scene g = fig3_build();
        double tw = now_s();
        cr_assert_eq(cd_sim_advance(g.m, g.d, T_END, NULL, NULL, &e), CD_OK, "%s", e.msg);
        tw = now_s() - tw;
        cr_log_info("fig3: single call to %.2f s: nrhs %ld, nsteps %ld, nrejected %ld, events %ld, wall %.3f s",
                    T_END, g.d->stats.nrhs, g.d->stats.nsteps, g.d->stats.nrejected, g.d->ev_count, tw);
        cr_expect_eq(g.d->ev_count, f.d->ev_count, "same number of events");
        if (g.d->ev_count == f.d->ev_count)
            cr_expect_leq(fabs(cd_data_event(g.d, g.d->ev_count - 1)->t - t_final), 1e-7,
                          "final separation %.12g vs %.12g s", cd_data_event(g.d, g.d->ev_count - 1)->t, t_final);
        cd_data_free(g.d);
        cd_model_free(g.m);
    }
    cd_data_free(f.d);
    cd_model_free(f.m);
}
