/* Harness for the C snippets of docs/embedding.md that work on a model and
 * a data (tests/doctest/run.sh: <!-- doctest c embed_run -->). It builds a
 * small model, gives the snippet the names it takes as given (m, d, err,
 * act, base, tau_cmd, n, st, d_other, finger_act, grip_slot, chaser, wrist,
 * target_base, my_controller, handle, my_buffer), puts the snippet's
 * definitions at SNIP_DEFS and its statements in a block in main, then
 * steps the data 50 more times of 1 ms. It fails when the snippet's own
 * status `st` is not CD_OK or a later step fails or the time does not
 * advance by 50 ms (no event happens in the harness's first 0.1 s, so every
 * setting the guide shows must step).
 *
 * The model: a hand (free base, 1 kg) with one finger (a revolute link about
 * z, 0.5 m, driven by actuator 0 through d->ctrl[0]) whose tip check point
 * can touch a fixed wall (contact slot 0). HARNESS_NUSER user switches are
 * reserved (embed_user.c: 1). The stepper is RK4 with a fixed step, the
 * guide's control-loop setting. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <capdyn/capdyn.h>

#ifndef HARNESS_NUSER
#define HARNESS_NUSER 0
#endif

static double my_controller(const cd_model *m, const cd_data *d)
{
    return -2.0 * cd_joint_q(m, d, 1) - 0.5 * cd_joint_qd(m, d, 1);
}
static void handle(cd_status st, const cd_error *err)
{
    fprintf(stderr, "handle: %s: %s\n", cd_status_string(st), err->msg);
}
static double *my_buffer(size_t n)
{
    return malloc(n * sizeof(double));
}

static cd_model *build(cd_error *err)
{
    cd_model *m = cd_model_create();
    cd_system_desc hand = cd_system_desc_default(), wall = cd_system_desc_default();
    cd_link_desc finger = cd_link_desc_default();
    cd_actuator_desc motor = cd_actuator_desc_default();
    cd_contact_law law = cd_contact_law_from_rule(1e3, 10, 0.05, 1.0, 0.3);
    const double tip[3] = {0.5, 0, 0}, block_pos[3] = {0.45, 0.35, 0}, half[3] = {0.2, 0.1, 0.1};
    double ratio = 1.0;
    int hs, ws, fb, sh, lw;
    if (!m) return NULL;
    hand.name = "hand";
    wall.name = "wall";
    wall.type = CD_BASE_FIXED;
    if ((hs = cd_model_add_system(m, &hand, err)) < 0) goto fail;
    finger.name = "finger";
    finger.parent = m->sys_body_adr[hs];
    finger.mass = 0.1;
    finger.com[0] = 0.25;
    memset(finger.inertia, 0, sizeof finger.inertia);
    finger.inertia[0] = 1e-5; finger.inertia[4] = finger.inertia[8] = 0.1 * 0.25 / 12;
    if ((fb = cd_model_add_link(m, hs, &finger, err)) < 0) goto fail;
    if ((ws = cd_model_add_system(m, &wall, err)) < 0) goto fail;
    if (cd_model_add_checkpoint(m, fb, tip, 0.01, err) < 0) goto fail;
    sh = cd_model_add_shape(m, m->sys_body_adr[ws], CD_SHAPE_BOX, block_pos, NULL, half, NULL, 0, err);
    if (sh < 0 || (lw = cd_model_add_law(m, &law, err)) < 0 || cd_model_add_pair(m, hs, -1, sh, lw, err) < 0) goto fail;
    motor.name = "motor";
    motor.type = CD_ACT_NONE;
    motor.ntrn = 1;
    motor.trn_body = &fb;
    motor.trn_ratio = &ratio;
    if (cd_model_add_actuator(m, &motor, err) < 0) goto fail;
    if (HARNESS_NUSER > 0 && cd_model_set_user_switches(m, HARNESS_NUSER, err) != CD_OK) goto fail;
    m->opt.stepper = CD_STEP_RK4_FIXED;
    if (cd_model_finalize(m, err) != CD_OK) goto fail;
    return m;
fail:
    cd_model_free(m);
    return NULL;
}

#include SNIP_DEFS

int main(void)
{
    cd_error err;
    cd_model *m = build(&err);
    cd_data *d, *d_other;
    cd_status st = CD_OK;
    int act = 0, base = 0, finger_act = 0, grip_slot = 0, chaser = 0, wrist = 0, target_base = 0, k;
    double tau_cmd = 0.5, t0;
    long n = 100;
    if (!m) { fprintf(stderr, "harness: model: %s\n", err.msg); return 1; }
    d = cd_data_create(m, 0, &err);
    d_other = cd_data_create(m, 0, &err);
    if (!d || !d_other) { fprintf(stderr, "harness: data: %s\n", err.msg); return 1; }
    wrist = m->sys_body_adr[0] + 1;      /* the finger link: an arm joint before the palm */
    target_base = m->sys_body_adr[1];   /* the wall's body */
    (void)act; (void)base; (void)finger_act; (void)grip_slot; (void)chaser; (void)wrist; (void)target_base;
    (void)tau_cmd; (void)n; (void)my_controller; (void)handle; (void)my_buffer;
    {
#include SNIP_BODY
    }
    /* no event happens in the harness's first 0.1 s (the finger is 4 cm
     * from the wall, at rest): every documented setting must step */
    if (st != CD_OK) {
        fprintf(stderr, "harness: the snippet's last status: %s: %s\n", cd_status_string(st), err.msg);
        return 1;
    }
    t0 = d->t;
    for (k = 0; k < 50; k++)
        if ((st = cd_step(m, d, 1e-3, &err)) != CD_OK) {
            fprintf(stderr, "harness: step after the snippet: %s: %s\n", cd_status_string(st), err.msg);
            return 1;
        }
    if (!(fabs(d->t - (t0 + 0.05)) < 1e-12) || !isfinite(d->y[0])) {
        fprintf(stderr, "harness: 50 steps of 1 ms went from t = %g to %g s\n", t0, d->t);
        return 1;
    }
    printf("harness: t = %.6f s, %ld events\n", d->t, d->ev_count);
    cd_data_free(d_other);
    cd_data_free(d);
    cd_model_free(m);
    return 0;
}
