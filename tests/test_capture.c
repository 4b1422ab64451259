/* Capture of a tumbling satellite by a free-flying robot (issue 10,
 * docs/capture.md): the built-in controller ([control]) and a gripper mounted
 * on the arm ([gripper] system/attach), run through the scenarios. */
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include <capdyn/io.h>

#include <math.h>
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
    cd_error err;
    cd_monitor_opts mo;
    memset(r, 0, sizeof *r);
    r->sc = cd_scenario_load(path, ov, nov, &err);
    cr_assert_not_null(r->sc, "%s", err.msg);
    cr_assert_not_null(r->sc->control, "%s has a [control] table", path);
    r->d = cd_data_create(r->sc->model, 0, &err);
    cr_assert_not_null(r->d, "%s", err.msg);
    r->c = cd_ctrl_create(r->sc->model, r->sc->control, &err);
    cr_assert_not_null(r->c, "%s", err.msg);
    cd_ctrl_install(r->c, r->d);
    mo = cd_scenario_monitor_opts(r->sc);
    cr_assert_eq(cd_monitor_init(&r->mon, r->sc->model, r->d, &mo, &err), CD_OK, "%s", err.msg);
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
 * largest momentum either body carries. */
Test(capture, momentum_of_chaser_and_target_is_conserved, .timeout = 300)
{
    const char *ov[] = {"control.attitude.on=false", "simulation.duration=3.4"};
    run_t r;
    const cd_model *m;
    double P0[3], L0[3], dP = 0, dL = 0, Pmax = 0, Lmax = 0;
    int s, k;
    long nev_contact = 0, i;
    run_open(&r, HANDRAIL, ov, 2);
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
        if (r.d->t == 0) { memcpy(P0, P, sizeof P0); memcpy(L0, L, sizeof L0); }
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
    }
    cr_expect(nev_contact >= 10 && cd_ctrl_phase_of(r.c, r.d) == CD_CTRL_HOLD, "contact events %ld, phase %d", nev_contact,
              cd_ctrl_phase_of(r.c, r.d));
    cr_expect(Pmax > 0.1 && Lmax > 1.0, "momenta exchanged: |P| %g, |L| %g", Pmax, Lmax);
    cr_expect(dP <= 1e-9 * Pmax, "linear momentum drift %g kg m/s, %g relative", dP, dP / Pmax);
    cr_expect(dL <= 1e-9 * Lmax, "angular momentum drift %g kg m^2/s, %g relative", dL, dL / Lmax);
    cr_log_info("capture momentum: |dP| %.3g (%.3g relative to %.4g), |dL| %.3g (%.3g relative to %.4g)", dP,
                dP / Pmax, Pmax, dL, dL / Lmax, Lmax);
    run_close(&r);
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
    refused("gripper.type=\"space\"", "key 'gripper.close.on': expected 'time' for a 'space' gripper");
    refused("control.fixture=\"target/nope\"", "key 'control.fixture': expected a shape \"system/shape\" of another system, got 'target/nope'");
    refused("gripper.finger_joint.q0_deg=[10.0]", "key 'gripper.finger_joint.q0_deg': expected 2 angles (one per finger link)");
    refused("control.start=\"later\"", "key 'control.start'");
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
    cd_scenario_free(sc);
}
