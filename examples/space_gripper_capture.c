/* space_gripper_capture.c -- a Space Gripper catches a drifting cylinder,
 * built in C with the builders of <capdyn/build.h> (docs/embedding.md,
 * "Building a gripper in C"): the hand of scenarios/space_gripper_cylinder.toml,
 * the cylinder drifting into it at 30 mm/s, the fingers closing from 0.6 s.
 * What running it checks (exit status 1 otherwise): both fingers clutch
 * (the wire mechanism takes over), and at 4 s the cylinder is held: within
 * 1 mm/s of the fixed palm, its centre between the fingers. */
#include <capdyn/capdyn.h>

#include <math.h>
#include <stdio.h>

#define T_END 4.0   /* [s] */
#define V_HELD 1e-3 /* [m/s] */

int main(void)
{
    cd_model *m = cd_model_create();
    cd_data *d = NULL;
    cd_error err;
    cd_shape_desc cyl = cd_shape_desc_default();
    cd_target_desc tgt = cd_target_desc_default();
    cd_hand_desc h = cd_hand_desc_default(); /* a Space Gripper, two opposed fingers */
    cd_hand hand;
    /* the contact law of the paper's rule: 10x the 1e3 N/m pad, critical for 0.3 kg */
    cd_contact_law law = cd_contact_law_from_rule(1e3, 10, 0.3, 1.0, 0.5);
    int obj, f, clutched = 0, ok;
    const double *v;
    if (!m) return 1;
    m->opt.rtol = 1e-8;
    m->opt.atol = 1e-10;
    m->opt.h_max = 1e-3;
    /* the target: a 0.3 kg cylinder (r 35 mm, 60 mm long) drifting to the palm */
    cyl.type = CD_SHAPE_CYLINDER;
    cyl.radius = 0.035;
    cyl.length = 0.06;
    tgt.name = "object";
    tgt.mass = 0.3;
    tgt.inertia[0] = tgt.inertia[4] = 1.81875e-4;
    tgt.inertia[8] = 1.8375e-4;
    tgt.pos[0] = 0.005;
    tgt.pos[1] = 0.105;
    tgt.vel[1] = -0.03;
    tgt.shapes = &cyl;
    tgt.nshape = 1;
    /* the hand: links 80 and 70 mm, stops at straight, closing 110 deg in 1 s */
    h.link_length[1] = 0.07;
    h.link_mass[0] = 0.05;
    h.link_mass[1] = 0.04;
    h.joint_limited = 1;
    h.joint_upper[0] = h.joint_upper[1] = 3.14159265358979;
    h.close_angle = 110.0 * 3.14159265358979 / 180.0;
    h.close_start = 0.6;
    h.torque = 0.05;
    h.clutch_threshold = 0.25;
    h.torque_limit = 0.3;
    if ((obj = cd_build_target(m, &tgt, &err)) < 0 || cd_build_hand(m, &h, &hand, &err) < 0 ||
        cd_build_hand_drive(m, &h, &hand, &law, &obj, 1, &err) != CD_OK || cd_model_finalize(m, &err) != CD_OK ||
        !(d = cd_data_create(m, 1024, &err)) || cd_sim_advance(m, d, T_END, NULL, NULL, &err) != CD_OK) {
        fprintf(stderr, "space_gripper_capture: %s\n", err.msg);
        cd_data_free(d);
        cd_model_free(m);
        return 1;
    }
    for (f = 0; f < hand.nclutch; f++) clutched += d->finger_mode[hand.clutch[f]] != 0;
    v = d->body_v + 3 * m->sys_body_adr[obj];
    ok = clutched == 2 && sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) < V_HELD && fabs(d->body_x[3 * m->sys_body_adr[obj]]) < h.spacing / 2;
    printf("t = %g s: %d of 2 fingers clutched, object at (%.4f, %.4f) m, speed %.2e m/s: %s\n", d->t, clutched,
           d->body_x[3 * m->sys_body_adr[obj]], d->body_x[3 * m->sys_body_adr[obj] + 1], sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]),
           ok ? "held" : "NOT held");
    cd_data_free(d);
    cd_model_free(m);
    return ok ? 0 : 1;
}
