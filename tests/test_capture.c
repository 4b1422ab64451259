/* Capture of a tumbling satellite by a free-flying robot (issue 10,
 * docs/capture.md): the built-in controller ([control]) and a gripper mounted
 * on the arm ([gripper] system/attach), run through the scenarios. */
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include <capdyn/io.h>
#include "capture_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define HANDRAIL "scenarios/capture_handrail_tumbling.toml"

typedef struct {
    cd_scenario *sc;
    cd_data *d;
    cd_ctrl *c;
    cd_monitor mon;
} run_t;

static void run_open(run_t *r, const char *path, const char *const *ov, int nov)
{
    memset(r, 0, sizeof *r);
    capture_open(path, ov, nov, &r->sc, &r->d, &r->c, &r->mon);
}

static void run_close(run_t *r)
{
    cd_ctrl_free(r->c);
    cd_data_free(r->d);
    cd_scenario_free(r->sc);
}

/* advances to t, sample by sample (dt), updating the monitor as capdyn run does */
static void run_to(run_t *r, double t_end, double dt)
{
    cd_error err;
    while (r->d->t < t_end - 1e-12) {
        double tn = r->d->t + dt > t_end ? t_end : r->d->t + dt;
        cr_assert_eq(cd_sim_advance(r->sc->model, r->d, tn, NULL, NULL, &err), CD_OK, "%s", err.msg);
        cd_monitor_update(&r->mon, r->sc->model, r->d);
    }
}

static void verdict_of(const char *path, cd_verdict want)
{
    run_t r;
    run_open(&r, path, NULL, 0);
    run_to(&r, r.sc->duration, r.sc->output_dt);
    cr_expect_eq(r.mon.verdict, want, "%s: verdict %s, expected %s (t_capture %g, t_escape %g, v_rel %g, w_rel %g)",
                 path, cd_verdict_name(r.mon.verdict), cd_verdict_name(want), r.mon.t_capture, r.mon.t_escape,
                 r.mon.v_rel, r.mon.w_rel);
    if (want == CD_VERDICT_CAPTURED) /* captured after the trigger, by a grasp that held */
        cr_expect(cd_ctrl_phase_of(r.c, r.d) == CD_CTRL_HOLD && r.mon.t_capture > cd_ctrl_t_trigger(r.c),
                  "%s: phase %d, trigger at %g, capture at %g", path, cd_ctrl_phase_of(r.c, r.d),
                  cd_ctrl_t_trigger(r.c), r.mon.t_capture);
    else /* the arm never got the fixture into the hand */
        cr_expect(isnan(cd_ctrl_t_trigger(r.c)), "%s: the trigger fired at %g", path, cd_ctrl_t_trigger(r.c));
    run_close(&r);
}

Test(capture, handrail_tumbling_is_captured, .timeout = 300) { verdict_of(HANDRAIL, CD_VERDICT_CAPTURED); }
Test(capture, body_offset_with_misalignment_is_captured, .timeout = 300)
{
    verdict_of("scenarios/capture_body_offset.toml", CD_VERDICT_CAPTURED);
}
Test(capture, too_fast_target_escapes, .timeout = 300) { verdict_of("scenarios/capture_too_fast.toml", CD_VERDICT_ESCAPED); }

/* The whole system's linear momentum and angular momentum (about the world
 * origin) through approach, impacts, stick-slip and the grasp, with the
 * attitude control (the only external torque) off: conserved to 1e-9 of the
 * largest momentum either body carries. Returns the run's clutch events. */
static long momentum_through_capture(const char *const *ov, int nov, const char *what)
{
    run_t r;
    const cd_model *m;
    double P0[3], L0[3], dP = 0, dL = 0, Pmax = 0, Lmax = 0;
    int s, k, first = 1;
    long nev_contact = 0, nev_clutch = 0, i;
    run_open(&r, HANDRAIL, ov, nov);
    m = r.sc->model;
    for (;;) {
        double P[3] = {0, 0, 0}, L[3] = {0, 0, 0}, e[3];
        cd_kinematics(m, r.d);
        for (s = 0; s < m->nsys; s++) {
            double p[3], l[3];
            cd_momentum(m, r.d, s, NULL, p, NULL, l, NULL);
            for (k = 0; k < 3; k++) { P[k] += p[k]; L[k] += l[k]; }
            if (sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) > Pmax) Pmax = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
            if (sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]) > Lmax) Lmax = sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]);
        }
        if (first) { memcpy(P0, P, sizeof P0); memcpy(L0, L, sizeof L0); first = 0; } /* t = 0 */
        for (k = 0; k < 3; k++) e[k] = P[k] - P0[k];
        if (sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]) > dP) dP = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
        for (k = 0; k < 3; k++) e[k] = L[k] - L0[k];
        if (sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]) > dL) dL = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
        if (r.d->t >= r.sc->duration) break;
        run_to(&r, r.d->t + 0.01, 0.01);
    }
    /* the run went through the capture: contact onsets, stick-slip switches, the trigger and the hold */
    for (i = 0; i < (r.d->ev_count < r.d->ev_cap ? r.d->ev_count : r.d->ev_cap); i++) {
        const cd_event *ev = cd_data_event(r.d, i);
        if (ev->kind == CD_EV_ONSET || ev->kind == CD_EV_STICK_SLIP || ev->kind == CD_EV_SLIP_STICK) nev_contact++;
        if (ev->kind == CD_EV_CLUTCH) nev_clutch++;
    }
    cr_expect(nev_contact >= 10 && cd_ctrl_phase_of(r.c, r.d) == CD_CTRL_HOLD, "%s: contact events %ld, phase %d", what,
              nev_contact, cd_ctrl_phase_of(r.c, r.d));
    cr_expect(Pmax > 0.1 && Lmax > 1.0, "%s: momenta exchanged: |P| %g, |L| %g", what, Pmax, Lmax);
    cr_expect(dP <= 1e-9 * Pmax, "%s: linear momentum drift %g kg m/s, %g relative", what, dP, dP / Pmax);
    cr_expect(dL <= 1e-9 * Lmax, "%s: angular momentum drift %g kg m^2/s, %g relative", what, dL, dL / Lmax);
    cr_log_info("%s: momentum |dP| %.3g (%.3g relative to %.4g), |dL| %.3g (%.3g relative to %.4g); %ld contact and %ld "
                "clutch events", what, dP, dP / Pmax, Pmax, dL, dL / Lmax, Lmax, nev_contact, nev_clutch);
    run_close(&r);
    return nev_clutch;
}

Test(capture, momentum_of_chaser_and_target_is_conserved, .timeout = 300)
{
    const char *ov[] = {"control.attitude.on=false", "simulation.duration=3.4"};
    momentum_through_capture(ov, 2, "soft gripper");
}

/* The same with a Space Gripper closed by the trigger: its clutches release
 * on the bar (located events) during the capture. */
Test(capture, momentum_is_conserved_through_the_space_grippers_clutch_events, .timeout = 300)
{
    const char *ov[] = {"control.attitude.on=false", "simulation.duration=3.4", "gripper.type=\"space\"",
                        "gripper.clutch={ threshold = 0.5, wire_stiffness = 20.0, torque_limit = 1.0 }"};
    long nclutch = momentum_through_capture(ov, 4, "space gripper");
    cr_expect(nclutch >= 1, "%ld clutch events", nclutch);
}

/* A non-tumbling target at rest in the closed hand (fingers closed to
 * 0.4 mm of the bar, their release springs off), the controller holding
 * from the start, no grip torque: nothing may move. The impedance reference, the attitude law and
 * the resolved-rate path must not push: drift of the target relative to the
 * palm < 1e-9 m over 10 s. */
Test(capture, held_target_at_rest_does_not_drift, .timeout = 300)
{
    const char *ov[] = {"target[0].position=[4.0338, 0.0, -0.2]", "target[0].angular_velocity_deg_s=[0.0, 0.0, 0.0]",
                        "gripper.finger_joint.q0_deg=[16.0, -5.0]", "gripper.finger_joint.spring=0.0",
                        "control.start=\"hold\"", "gripper.torque=0.0", "simulation.duration=10.0"};
    run_t r;
    const cd_model *m;
    int ob, pb, k;
    double r0[3], drift = 0;
    run_open(&r, HANDRAIL, ov, 7);
    m = r.sc->model;
    ob = m->sys_body_adr[r.sc->capture_object];
    pb = r.sc->capture_palm;
    cd_kinematics(m, r.d);
    for (k = 0; k < 3; k++) r0[k] = r.d->body_c[3 * ob + k] - r.d->body_x[3 * pb + k];
    while (r.d->t < 10.0 - 1e-12) {
        double e[3];
        run_to(&r, r.d->t + 0.5, 0.5);
        cd_kinematics(m, r.d);
        for (k = 0; k < 3; k++) e[k] = r.d->body_c[3 * ob + k] - r.d->body_x[3 * pb + k] - r0[k];
        if (sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]) > drift) drift = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    }
    cr_expect(drift < 1e-9, "drift %g m over 10 s", drift);
    cr_expect(cd_ctrl_phase_of(r.c, r.d) == CD_CTRL_HOLD);
    run_close(&r);
}

/* The same hold with the gripper squeezing (its grip torque, 0.5 N m x
 * (4, 1), on through the controller's close command), started from the
 * static equilibrium of the squeezed grasp: the data is made without the
 * settle (without the grip torque nothing holds the fingers there), the
 * controller installed, then reset with opt.equilibrium_start so that its
 * torques are in the balance. Mirror-symmetric pairs (base joints 18.546
 * deg, tips -4.710 deg, about where they come to rest): no net force on the
 * target. Drift of the target relative to the palm < 1e-9 m over 10 s,
 * with the 12 contacts of the settle (3 per finger: two on the bar, one
 * finger tip on the other) closed and sticking throughout.
 * Two causes of creep were found on the way, both physical: (1) the
 * settle kept a contact closed that it had moved out of touch, pulling
 * (f_n = -0.75 N); it opened at the first step and the grasp crept 0.1 mm
 * to a new rest (fixed: the settle opens pulling contacts, src/sim/equilibrium.c);
 * (2) at the scenario's mu_max = 0.5 the settled grasp needs |f_t|/f_n =
 * 0.57 at each finger's first check point on the bar: it slips at once and
 * creeps 0.12 mm to a friction-limited rest. Here mu_max = 0.7: the grasp
 * is inside its friction cone. */
Test(capture, squeezed_target_at_rest_does_not_drift, .timeout = 300)
{
    const char *ov[] = {"target[0].position=[4.0338, 0.0, -0.2]", "target[0].angular_velocity_deg_s=[0.0, 0.0, 0.0]",
                        "gripper.finger_joint.q0_deg=[18.546, -4.710]", "control.start=\"hold\"",
                        "contact.mu_max=0.7", "simulation.duration=10.0"};
    run_t r;
    const cd_model *m;
    cd_error err;
    int ob, pb, k, s, nclosed = 0, nstick_min = 1 << 30;
    double r0[3], drift = 0;
    run_open(&r, HANDRAIL, ov, 6);
    m = r.sc->model;
    r.d->opt.equilibrium_start = 1;
    cr_assert_eq(cd_data_reset(m, r.d, &err), CD_OK, "%s", err.msg); /* the settle with the controller's torques */
    ob = m->sys_body_adr[r.sc->capture_object];
    pb = r.sc->capture_palm;
    cd_kinematics(m, r.d);
    for (k = 0; k < 3; k++) r0[k] = r.d->body_c[3 * ob + k] - r.d->body_x[3 * pb + k];
    for (s = 0; s < m->nslot; s++) nclosed += r.d->slot_mode[s] != CD_MODE_OPEN;
    cr_log_info("squeezed hold: %d contacts closed, settle residual %g after %d iterations", nclosed, r.d->stats.eq_residual,
                r.d->stats.eq_iterations);
    while (r.d->t < 10.0 - 1e-12) {
        double e[3];
        int nst = 0;
        run_to(&r, r.d->t + 0.5, 0.5);
        cd_kinematics(m, r.d);
        for (k = 0; k < 3; k++) e[k] = r.d->body_c[3 * ob + k] - r.d->body_x[3 * pb + k] - r0[k];
        if (sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]) > drift) drift = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
        for (s = 0; s < m->nslot; s++) nst += r.d->slot_mode[s] == CD_MODE_STICK;
        if (nst < nstick_min) nstick_min = nst;
    }
    cr_expect(nclosed == 12, "%d contacts closed at the start", nclosed);
    cr_expect(nstick_min == nclosed, "%d contacts closed at the start, as few as %d sticking later", nclosed, nstick_min);
    cr_expect(drift < 1e-9, "drift %g m over 10 s", drift);
    cr_log_info("squeezed hold: drift %.3g m over 10 s", drift);
    run_close(&r);
}

/* DETUMBLE (docs/capture.md): the target held in the squeezing hand (grip
 * torque on) turns at 1 deg/s about the palm's approach axis, through the
 * bar's centre, relative to the chaser at rest; the controller detumbles
 * from t = 0. Its moment about the approach axis is held at its limit
 * n_y = 0.7 N m while the rate is large, so the relative rate falls at
 * n_y / J, J = 116 + 410 * 0.2^2 = 132.4 kg m^2 the target's inertia about
 * that axis (0.303 deg/s^2): 0.697 deg/s at t = 1 s (within 0.02 deg/s;
 * the base's reaction and the grasp's compliance make the difference).
 * By t = 3 s the relative rate is below 0.15 deg/s (what is left is the
 * target rocking in the compliant grasp, all contacts sticking), every
 * arm torque within tau_max and the grasp carrying it: at least 8
 * contacts. */
Test(capture, detumbling_stops_the_held_target_at_the_grasp_limit, .timeout = 300)
{
    const char *ov[] = {"target[0].position=[4.0338, 0.0, -0.2]", "target[0].angular_velocity_deg_s=[1.0, 0.0, 0.0]",
                        "target[0].velocity=[0.0, 0.0034906585, 0.0]", "gripper.finger_joint.q0_deg=[16.0, -5.0]",
                        "control.start=\"hold\"", "control.detumble.on=true", "control.detumble.after=0.0",
                        "simulation.duration=3.0"};
    run_t r;
    const cd_model *m;
    cd_ctrl_merit f;
    double w1 = NAN, taumax = 0;
    int s, ncontact = 0, b;
    run_open(&r, HANDRAIL, ov, 8);
    m = r.sc->model;
    cd_kinematics(m, r.d);
    cd_ctrl_merit_init(&f, r.c, m, r.d);
    cr_expect(fabs(f.w_rel - 1.0 * M_PI / 180) < 1e-9, "initial relative rate %g deg/s", f.w_rel * 180 / M_PI);
    while (r.d->t < 3.0 - 1e-12) {
        run_to(&r, r.d->t + 0.05, 0.05);
        cd_kinematics(m, r.d);
        cd_ctrl_merit_update(&f, r.c, m, r.d);
        if (fabs(r.d->t - 1.0) < 1e-9) w1 = f.w_rel;
        for (b = r.sc->control->palm; b > m->sys_body_adr[r.sc->control->sys]; b = m->body_parent[b])
            if (fabs(r.d->qfrc_applied[m->body_dof[b]]) > taumax) taumax = fabs(r.d->qfrc_applied[m->body_dof[b]]);
    }
    for (s = 0; s < m->nslot; s++) ncontact += r.d->slot_mode[s] != CD_MODE_OPEN;
    cr_expect(cd_ctrl_phase_of(r.c, r.d) == CD_CTRL_DETUMBLE && cd_ctrl_t_detumble(r.c) < 1e-6, "phase %d from %g s",
              cd_ctrl_phase_of(r.c, r.d), cd_ctrl_t_detumble(r.c));
    cr_expect(fabs(w1 * 180 / M_PI - (1.0 - 0.7 / 132.4 * 180 / M_PI)) < 0.02, "relative rate at 1 s: %g deg/s, expected %g",
              w1 * 180 / M_PI, 1.0 - 0.7 / 132.4 * 180 / M_PI);
    cr_expect(f.w_rel * 180 / M_PI < 0.15, "relative rate at 3 s: %g deg/s", f.w_rel * 180 / M_PI);
    cr_expect(taumax <= r.sc->control->tau_max, "arm torque %g N m", taumax);
    /* the figure of merit capture_tau_arm_max: the same samples (and t = 0) */
    cr_expect(taumax > 0 && f.tau_arm_max >= taumax && f.tau_arm_max <= r.sc->control->tau_max,
              "merit arm torque %g N m, sampled %g N m", f.tau_arm_max, taumax);
    cr_expect(ncontact >= 8, "%d contacts carry the target", ncontact);
    cr_log_info("detumbling: relative rate 1 deg/s -> %.4f deg/s at 1 s, %.4f deg/s at 3 s; %d contacts", w1 * 180 / M_PI,
                f.w_rel * 180 / M_PI, ncontact);
    run_close(&r);
}

/* Checkpoint and rollback with the controller's memory (cd_ctrl_state_get /
 * _set next to cd_state_get / _set, docs/embedding.md): the handrail
 * capture is saved mid-approach (t = 2 s) and after the trigger (t = 2.8 s,
 * CLOSING: the trigger time that schedules HOLD is in the controller), run
 * on into HOLD (t = 3.4 s; HOLD at 3.14 s). Rolled back to 2 s in the same
 * data and controller, and restored at 2.8 s into a new data and a new
 * controller (as after a restart), the reruns end bit-identical (memcmp of
 * the state buffers). Restored without the controller's memory, the new
 * controller never reaches HOLD: the memory is needed. */
static void advance_to(run_t *r, double t_end)
{
    cd_error err;
    while (r->d->t < t_end - 1e-12) {
        double tn = r->d->t + 0.1 > t_end ? t_end : r->d->t + 0.1;
        cr_assert_eq(cd_sim_advance(r->sc->model, r->d, tn, NULL, NULL, &err), CD_OK, "%s", err.msg);
    }
}

Test(capture, checkpoint_with_the_controller_state_reruns_bit_identical, .timeout = 300)
{
    const char *ov[] = {"simulation.duration=3.4"};
    run_t r, r2;
    const cd_model *m;
    cd_error err;
    size_t n, nc;
    double *s_approach, *s_closing, *s_end, *s_rerun, *c_approach, *c_closing, bad[64];
    run_open(&r, HANDRAIL, ov, 1);
    m = r.sc->model;
    n = cd_state_size(m);
    nc = cd_ctrl_state_size(r.c);
    cr_assert(nc < 64);
    s_approach = malloc(4 * n * sizeof(double));
    c_approach = malloc(2 * nc * sizeof(double));
    cr_assert(s_approach && c_approach);
    s_closing = s_approach + n;
    s_end = s_closing + n;
    s_rerun = s_end + n;
    c_closing = c_approach + nc;
    advance_to(&r, 2.0);
    cr_assert_eq(cd_ctrl_phase_of(r.c, r.d), CD_CTRL_APPROACH);
    cd_state_get(m, r.d, s_approach);
    cd_ctrl_state_get(r.c, c_approach);
    advance_to(&r, 2.8);
    cr_assert_eq(cd_ctrl_phase_of(r.c, r.d), CD_CTRL_CLOSING, "phase %d at 2.8 s", cd_ctrl_phase_of(r.c, r.d));
    cd_state_get(m, r.d, s_closing);
    cd_ctrl_state_get(r.c, c_closing);
    advance_to(&r, 3.4);
    cr_assert_eq(cd_ctrl_phase_of(r.c, r.d), CD_CTRL_HOLD);
    cd_state_get(m, r.d, s_end);
    /* rollback to mid-approach, same data and controller */
    cr_assert_eq(cd_state_set(m, r.d, s_approach, &err), CD_OK, "%s", err.msg);
    cr_assert_eq(cd_ctrl_state_set(r.c, c_approach, &err), CD_OK, "%s", err.msg);
    cr_expect(isnan(cd_ctrl_t_trigger(r.c)), "the trigger time is rolled back");
    advance_to(&r, 2.8); /* the same stops as the first run: the integrator's steps end at each */
    advance_to(&r, 3.4);
    cd_state_get(m, r.d, s_rerun);
    cr_expect(memcmp(s_end, s_rerun, n * sizeof(double)) == 0, "rerun from the approach checkpoint differs");
    /* a new data and controller restored after the trigger */
    run_open(&r2, HANDRAIL, ov, 1);
    cr_assert_eq(cd_state_set(r2.sc->model, r2.d, s_closing, &err), CD_OK, "%s", err.msg);
    cr_assert_eq(cd_ctrl_state_set(r2.c, c_closing, &err), CD_OK, "%s", err.msg);
    advance_to(&r2, 3.4);
    cd_state_get(r2.sc->model, r2.d, s_rerun);
    cr_expect(memcmp(s_end, s_rerun, n * sizeof(double)) == 0, "restart from the closing checkpoint differs");
    cr_expect_eq(cd_ctrl_t_hold(r2.c), cd_ctrl_t_hold(r.c));
    run_close(&r2);
    /* the same without the controller's memory: the trigger time is lost, HOLD never comes */
    run_open(&r2, HANDRAIL, ov, 1);
    cr_assert_eq(cd_state_set(r2.sc->model, r2.d, s_closing, &err), CD_OK, "%s", err.msg);
    advance_to(&r2, 3.4);
    cr_expect_eq(cd_ctrl_phase_of(r2.c, r2.d), CD_CTRL_CLOSING, "phase %d without the controller's memory",
                 cd_ctrl_phase_of(r2.c, r2.d));
    /* a buffer that is not a controller state is refused, the controller unchanged */
    memset(bad, 0, sizeof bad);
    cr_expect_eq(cd_ctrl_state_set(r2.c, bad, &err), CD_EINVAL);
    cr_expect(strstr(err.msg, "control: not a state of this controller (expected 6 arm joints)") != NULL, "%s", err.msg);
    cr_expect(isnan(cd_ctrl_t_trigger(r2.c)));
    run_close(&r2);
    free(s_approach);
    free(c_approach);
    run_close(&r);
}

/* close.on = "trigger" for clutched fingers: a Space Gripper on the arm
 * (the handrail scenario with gripper.type = "space"; closing schedule 120
 * deg in 1 s). Before the trigger every finger's schedule angle is 0 (the
 * controller holds d->finger_t0 at +inf); 0.25 s after it the schedule is
 * a quarter of the way: theta = 0.25 s x 120 deg / 1 s = 30 deg (to 1e-9
 * rad), and finger_t0 is the trigger time. */
Test(capture, space_gripper_closes_on_the_trigger, .timeout = 300)
{
    const char *ov[] = {"gripper.type=\"space\"", "simulation.duration=3.0"};
    run_t r;
    const cd_model *m;
    double tt;
    int f;
    run_open(&r, HANDRAIL, ov, 2);
    m = r.sc->model;
    cr_assert(m->nfinger == 4 && r.sc->control->nclose_finger == 4, "%d fingers, %d closed on the trigger", m->nfinger,
              r.sc->control->nclose_finger);
    while (cd_ctrl_phase_of(r.c, r.d) == CD_CTRL_APPROACH && r.d->t < 3.0 - 1e-12) {
        advance_to(&r, r.d->t + 0.1);
        for (f = 0; f < m->nfinger && cd_ctrl_phase_of(r.c, r.d) == CD_CTRL_APPROACH; f++)
            cr_assert(r.d->finger_theta[f] == 0.0 && isinf(r.d->finger_t0[f]), "t %g: finger %d at %g rad before the trigger",
                      r.d->t, f, r.d->finger_theta[f]);
    }
    tt = cd_ctrl_t_trigger(r.c);
    cr_assert(tt > 2.0 && tt < 2.9, "trigger at %g s", tt);
    advance_to(&r, tt + 0.25);
    for (f = 0; f < m->nfinger; f++) {
        cr_expect(r.d->finger_t0[f] == tt, "finger %d: origin %g, trigger %g", f, r.d->finger_t0[f], tt);
        cr_expect(fabs(r.d->finger_theta[f] - 30.0 * M_PI / 180) < 1e-9, "finger %d: schedule %.12g rad", f,
                  r.d->finger_theta[f]);
    }
    run_close(&r);
}

/* Bad mounted-gripper and [control] inputs: one message naming the key and
 * what was expected. */
static void refused(const char *ov, const char *want)
{
    cd_error err;
    const char *a[1];
    cd_scenario *sc;
    a[0] = ov;
    sc = cd_scenario_load(HANDRAIL, a, 1, &err);
    cr_expect_null(sc, "--set %s was accepted", ov);
    cd_scenario_free(sc);
    cr_expect(err.status == CD_EINVAL && strstr(err.msg, want) != NULL, "--set %s: got '%s', expected '%s'", ov, err.msg,
              want);
}

Test(capture, bad_inputs_are_refused_with_the_key)
{
    refused("gripper.attach=\"upper_arm\"", "key 'gripper.attach': expected a link without child links (the fingers "
                                            "become its only branches), got 'upper_arm' (parent of 'forearm')");
    refused("gripper.attach=\"elbow\"", "key 'gripper.attach': expected 'base' or a link of system 'chaser', got 'elbow'");
    refused("gripper.palm.mass=2.0", "key 'gripper.palm.mass': does not apply to a gripper mounted on a link");
    refused("gripper.system=\"target\"", "key 'gripper.system': expected a [[system]] (the chaser), got the target 'target'");
    refused("gripper.close={on=\"trigger\", start=1.0}",
            "key 'gripper.close.start': does not apply with on = 'trigger'");
    refused("control.fixture=\"target/nope\"", "key 'control.fixture': expected a shape \"system/shape\" of another system, got 'target/nope'");
    refused("gripper.finger_joint.q0_deg=[10.0]", "key 'gripper.finger_joint.q0_deg': expected 2 angles (one per finger link)");
    refused("control.start=\"later\"", "key 'control.start'");
    refused("control.detumble.moment_max=[1.0, 0.0, 1.0]", "key 'control.detumble.moment_max");
    refused("control.detumble.base=\"hold\"", "key 'control.detumble.base'");
}

/* The controller's own checks (an embedder's configuration). */
Test(capture, controller_configuration_is_checked)
{
    cd_error err;
    cd_scenario *sc = cd_scenario_load(HANDRAIL, NULL, 0, &err);
    cd_ctrl_config c;
    cr_assert_not_null(sc, "%s", err.msg);
    c = *sc->control;
    c.sys = sc->capture_object; /* the target as chaser: no arm joint leads to the palm */
    cr_expect_null(cd_ctrl_create(sc->model, &c, &err));
    cr_expect(strstr(err.msg, "control: the palm (body") != NULL, "%s", err.msg);
    c = *sc->control;
    c.dls = 0;
    cr_expect_null(cd_ctrl_create(sc->model, &c, &err));
    cr_expect(strstr(err.msg, "out of range") != NULL, "%s", err.msg);
    c = *sc->control;
    c.user_switch0 = sc->model->nuser - 1;
    cr_expect_null(cd_ctrl_create(sc->model, &c, &err));
    cr_expect(strstr(err.msg, "needs user switches") != NULL, "%s", err.msg);
    c = *sc->control; /* detumbling needs a third user switch: the scenario's has it off */
    c.detumble = 1;
    cr_expect_null(cd_ctrl_create(sc->model, &c, &err));
    cr_expect(strstr(err.msg, "needs user switches 0 to 2 (the model has 2)") != NULL, "%s", err.msg);
    cd_scenario_free(sc);
}
