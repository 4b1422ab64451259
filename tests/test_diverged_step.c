/* A diverged explicit step is rejected (src/sim/integrator.c, diverged()).
 *
 * GSL's standard error test accepts a step when
 * |err_i| <= atol + rtol (|y1_i| + h |f(t1, y1)_i|). Far past an explicit
 * method's stability limit the stages grow like (h lambda)^s and f(t1, y1)
 * grows faster than y1 and the error estimate, so such a step passed: the
 * Fig. 5 grasp with h_max = 0.05 "accepted" a 4.7 ms rk8pd step that ended at
 * |y| ~ 1e109, and the run stopped with "event location failed".
 *
 * Two checks. The regression is the Fig. 5 case itself (the last test; it
 * fails without the check). The block below is the linear companion: a
 * first trial step ten times past rk8pd's stability limit, whose growth is
 * linear, so GSL's own test already rejects it; the closed form must hold
 * with the check in place for every explicit stepper and auto.
 *
 * The closed form: a 1 kg block resting on a plane (K = 1e6 N/m) in
 * stick, pushed along x at v0. The stick spring-damper (K_t = 1e6 N/m,
 * D_t = 2 sqrt(K_t m): critical) holds it, |K_t x| stays far inside the
 * cone, and its displacement is x(t) = v0 t exp(-w t), w = sqrt(K_t / m) =
 * 1e3 1/s. The first trial step is 0.05 s (h w = 50, ten times rk8pd's
 * stability limit). */
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include "scene_util.h"
#include <math.h>
#include <stdio.h>

static const double G = 9.81, V0 = 1e-3, W = 1e3;

static void block_run(cd_stepper stepper, double t_end, double *x, cd_status *st, long *nrej)
{
    cd_error e;
    cd_model *m = cd_model_create();
    cd_data *d;
    double mass = 1.0, K = 1e6, pos[3] = {0, 0, -mass * G / 1e6}, vel[3] = {V0, 0, 0};
    int ground, plane, blk, lid;
    cd_contact_law law = cd_contact_law_default();
    ground = add_system(m, "ground", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL);
    plane = add_plane(m, m->sys_body_adr[ground]);
    blk = add_system(m, "block", CD_BASE_FREE, mass, 1e6, pos, vel, NULL);
    add_point(m, m->sys_body_adr[blk]);
    law.K = K;
    law.D = 2.0 * sqrt(K * mass);
    law.Kt = W * W * mass;
    law.Dt = 2.0 * sqrt(law.Kt * mass);
    law.mu_s = law.mu_k = 0.5;
    lid = cd_model_add_law(m, &law, &e);
    cr_assert(lid >= 0, "%s", e.msg);
    cr_assert(cd_model_add_pair(m, blk, -1, plane, lid, &e) >= 0, "%s", e.msg);
    m->gravity[2] = -G;
    cr_assert(cd_model_finalize(m, &e) == CD_OK, "%s", e.msg);
    m->opt.stepper = stepper;
    m->opt.rtol = 1e-8;
    m->opt.atol = 1e-12;
    m->opt.h_init = 0.05;
    m->opt.h_max = 0.05;
    d = cd_data_create(m, 0, &e);
    cr_assert(d, "%s", e.msg);
    d->slot_mode[0] = CD_MODE_STICK;
    cr_assert_eq(cd_forward(m, d), CD_OK);
    *st = cd_sim_advance(m, d, t_end, NULL, NULL, &e);
    *x = cd_state_of(m, d, 1).pos[0];
    *nrej = d->stats.nrejected;
    cr_log_info("%s to %g s: status %d, x = %.6g m (closed form %.6g), %ld steps, %ld rejected, %ld evaluations",
                cd_stepper_name(stepper), t_end, (int)*st, *x, V0 * t_end * exp(-W * t_end), d->stats.nsteps,
                d->stats.nrejected, d->stats.nrhs);
    cd_data_free(d);
    cd_model_free(m);
}

/* The displacement against the closed form: within 1e-10 m (the slot
 * stays in stick: |K_t x| <= K_t v0 / (e w) = 0.37 N < mu m g = 4.9 N). */
static void check(cd_stepper stepper)
{
    static const double T[] = {2e-3, 0.01, 0.05, 0.5};
    size_t i;
    for (i = 0; i < sizeof T / sizeof *T; i++) {
        double x, xc = V0 * T[i] * exp(-W * T[i]);
        cd_status st;
        long nrej;
        block_run(stepper, T[i], &x, &st, &nrej);
        cr_assert_eq(st, CD_OK, "%s to %g s: status %d", cd_stepper_name(stepper), T[i], (int)st);
        cr_expect(fabs(x - xc) < 1e-10, "%s at %g s: x = %.6g m, closed form %.6g m", cd_stepper_name(stepper), T[i],
                  x, xc);
    }
}

Test(diverged_step, rk8pd_rejects_a_diverged_first_step) { check(CD_STEP_RK8PD); }
Test(diverged_step, rkf45_rejects_a_diverged_first_step) { check(CD_STEP_RKF45); }
Test(diverged_step, auto_rejects_a_diverged_first_step) { check(CD_STEP_AUTO); }

/* The case that found it: Fig. 5 with the bench's h_max = 0.05 s stopped at
 * 0.0287 s (the fingertips' first touch) with "event location failed". Now
 * it runs, and its state at 0.2 s agrees with an h_max = 1e-3 s run (the
 * scenario's own until 2026-11-28) to the tolerance's order (both rtol 1e-8). */
#include <capdyn/io.h>
static void fig5_to(const char *hmax, double t_end, double *q, cd_status *st)
{
    char ov[64];
    const char *ovp[1] = {ov};
    cd_error e;
    cd_scenario *sc;
    cd_data *d;
    int i;
    snprintf(ov, sizeof ov, "simulation.h_max=%s", hmax);
    sc = cd_scenario_load("scenarios/paper_fig5_envelope_grasp.toml", ovp, 1, &e);
    cr_assert(sc, "%s", e.msg);
    d = cd_data_create(sc->model, sc->event_capacity, &e);
    cr_assert(d, "%s", e.msg);
    *st = cd_sim_advance(sc->model, d, t_end, NULL, NULL, &e);
    if (*st != CD_OK) cr_log_info("h_max %s: %s", hmax, e.msg);
    for (i = 0; i < 4; i++) q[i] = cd_state_of(sc->model, d, 0).q[i];
    cd_data_free(d);
    cd_scenario_free(sc);
}

Test(diverged_step, fig5_with_large_h_max_runs_and_agrees)
{
    double qa[4], qb[4];
    cd_status sa, sb;
    int i;
    fig5_to("0.05", 0.2, qa, &sa);
    fig5_to("1e-3", 0.2, qb, &sb);
    cr_assert_eq(sa, CD_OK, "h_max 0.05: status %d", (int)sa);
    cr_assert_eq(sb, CD_OK, "h_max 1e-3: status %d", (int)sb);
    for (i = 0; i < 4; i++)
        cr_expect(fabs(qa[i] - qb[i]) < 1e-5, "joint %d: %.9g rad (h_max 0.05) vs %.9g rad (1e-3)", i, qa[i], qb[i]);
}
