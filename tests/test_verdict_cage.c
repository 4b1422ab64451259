/* The three-finger box cage of issue 22 item 3 (docs/grippers.md "Capture
 * verdict", scenarios/space_gripper_box_cage.toml): a three-finger Space
 * Gripper on an off-centre 40 mm box locks its fingertips tip to tip above
 * the box, only two fingers touch it, epsilon = 0: the verdict is caged, not
 * captured. Its counterparts with the same hand and law: the centred box,
 * touched by all three fingers, is captured with epsilon > 0; and the box
 * 0.1 mm off the mirror plane of the cage is captured too (the cage rests on
 * the symmetry of the placement). Each case through the loader, cd_sim_advance
 * and the monitor at every sample, as `capdyn run` does; about 1 s of wall
 * time each. */
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include <capdyn/io.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#define SCEN "scenarios/space_gripper_box_cage.toml"
#define NFINGER 3

typedef struct {
    cd_scenario *sc;
    cd_data *d;
    cd_monitor mon;
    int link[NFINGER][2]; /* body ids of hand/f<f>_l<j> */
    int palm;             /* the hand's base body */
} crun;

static void crun_open(crun *r, const char *const *ov, int nov)
{
    cd_error err;
    cd_monitor_opts mo;
    int f, j;
    memset(r, 0, sizeof *r);
    r->sc = cd_scenario_load(SCEN, ov, nov, &err);
    cr_assert_not_null(r->sc, "%s", err.msg);
    r->d = cd_data_create(r->sc->model, 0, &err);
    cr_assert_not_null(r->d, "%s", err.msg);
    mo = cd_scenario_monitor_opts(r->sc);
    cr_assert_eq(cd_monitor_init(&r->mon, r->sc->model, r->d, &mo, &err), CD_OK, "%s", err.msg);
    for (f = 0; f < NFINGER; f++)
        for (j = 0; j < 2; j++) {
            char name[32];
            snprintf(name, sizeof name, "hand/f%d_l%d", f, j);
            r->link[f][j] = cd_model_body_id(r->sc->model, name);
            cr_assert_geq(r->link[f][j], 0, "no body %s", name);
        }
    r->palm = r->sc->model->sys_body_adr[r->mon.opt.hand];
    cd_monitor_update(&r->mon, r->sc->model, r->d);
}

static void crun_to(crun *r, double t_end)
{
    cd_error err;
    double dt = r->sc->output_dt;
    while (r->d->t < t_end - 1e-12) {
        double tn = r->d->t + dt > t_end ? t_end : r->d->t + dt;
        cr_assert_eq(cd_sim_advance(r->sc->model, r->d, tn, NULL, NULL, &err), CD_OK, "%s", err.msg);
        cd_monitor_update(&r->mon, r->sc->model, r->d);
    }
}

static void crun_close(crun *r)
{
    cd_data_free(r->d);
    cd_scenario_free(r->sc);
}

/* finger of a body (0..2), -1 for the palm, the object or anything else */
static int finger_of(const crun *r, int body)
{
    int f, j;
    for (f = 0; f < NFINGER; f++)
        for (j = 0; j < 2; j++)
            if (r->link[f][j] == body) return f;
    return -1;
}

/* the object's closed contacts at the current state: bit f set if finger f
 * touches it; *palm = number of closed slots with the palm */
static unsigned object_fingers(const crun *r, int *palm)
{
    const cd_model *m = r->sc->model;
    unsigned mask = 0;
    int k, obj = r->mon.opt.object;
    *palm = 0;
    for (k = 0; k < m->nslot; k++) {
        int bc = m->cp_body[m->slot_cp[k]], bs = m->shape_body[m->slot_shape[k]];
        int other = m->body_sys[bc] == obj ? bs : m->body_sys[bs] == obj ? bc : -1;
        if (r->d->slot_mode[k] == CD_MODE_OPEN || other < 0) continue;
        if (other == r->palm) (*palm)++;
        else if (finger_of(r, other) >= 0) mask |= 1u << finger_of(r, other);
    }
    return mask;
}

/* closed slots whose check point is the fingertip of finger a (the tip
 * link's last check point, at the link's length) and whose shape is the tip
 * link of finger b != a */
static int tip_on_tip(const crun *r, int a, int b)
{
    const cd_model *m = r->sc->model;
    double tip_y = 0.04; /* links = [0.05, 0.04] in the scenario */
    int k, n = 0;
    for (k = 0; k < m->nslot; k++) {
        int cp = m->slot_cp[k];
        if (r->d->slot_mode[k] == CD_MODE_OPEN) continue;
        if (m->cp_body[cp] != r->link[a][1] || m->shape_body[m->slot_shape[k]] != r->link[b][1]) continue;
        if (fabs(m->cp_pos[3 * cp + 1] - tip_y) < 1e-12) n++;
    }
    return n;
}

/* The cage. Fingers 1 and 2 pinch the box's side faces x = -/+20 mm with one
 * base-link check point each, at opposite points; finger 0 passes over it and
 * its fingertip jams against the tip links of fingers 1 and 2. Two point
 * contacts cannot resist a torque about the line through them, so epsilon = 0
 * (exactly: the analysis finds no force closure). The contact set settles at
 * 0.148 s; caged after the 0.2 s dwell, at 0.348 s (measured with `capdyn
 * run`; the same with integrator "rk8pd"), and still caged at the end (1 s). */
Test(verdict_cage, three_fingers_on_an_off_centre_box_cage_it, .timeout = 120)
{
    crun r;
    int palm;
    unsigned touch;
    crun_open(&r, NULL, 0);
    crun_to(&r, 0.5);
    cr_expect_eq(r.mon.verdict, CD_VERDICT_CAGED, "verdict %s (epsilon %g, t_capture %g)",
                 cd_verdict_name(r.mon.verdict), r.mon.epsilon, r.mon.t_capture);
    cr_expect(isfinite(r.mon.t_cage) && fabs(r.mon.t_cage - 0.348) < 1.5e-3, "t_cage %g, measured 0.348 s",
              r.mon.t_cage);
    cr_expect(isnan(r.mon.t_capture), "never captured: t_capture %g", r.mon.t_capture);
    cr_expect_eq(r.mon.epsilon, 0.0, "epsilon at the judgement %g", r.mon.epsilon);
    crun_to(&r, r.sc->duration);
    cr_expect_eq(r.mon.verdict, CD_VERDICT_CAGED, "at the end: %s", cd_verdict_name(r.mon.verdict));
    cr_expect(r.mon.enclosed, "the box is enclosed at the end");
    touch = object_fingers(&r, &palm);
    cr_expect_eq(touch, (1u << 1) | (1u << 2), "fingers touching the box (bit per finger): 0x%x, expected 1 and 2 only",
                 touch);
    cr_expect_eq(palm, 0, "%d contacts with the palm", palm);
    cr_expect_eq(r.mon.n_stick + r.mon.n_slip, 2, "%d stick + %d slip contacts with the box, expected 2", r.mon.n_stick,
                 r.mon.n_slip);
    cr_expect(tip_on_tip(&r, 0, 1) >= 1 && tip_on_tip(&r, 0, 2) >= 1,
              "finger 0's tip on the tip links of fingers 1 (%d slots) and 2 (%d slots)", tip_on_tip(&r, 0, 1),
              tip_on_tip(&r, 0, 2));
    crun_close(&r);
}

/* The same hand on the centred box: all three fingers' base links touch it
 * (5 contacts, 2 each on fingers 1 and 2), force closure; captured at
 * 0.388 s with epsilon 0.0857 (capdyn run), never caged. */
Test(verdict_cage, the_centred_box_is_captured, .timeout = 120)
{
    static const char *const ov[] = {"target.object.position=[0.0, 0.045, 0.0]"};
    crun r;
    int palm;
    unsigned touch;
    crun_open(&r, ov, 1);
    crun_to(&r, 0.5);
    cr_expect_eq(r.mon.verdict, CD_VERDICT_CAPTURED, "verdict %s (epsilon %g, t_cage %g)",
                 cd_verdict_name(r.mon.verdict), r.mon.epsilon, r.mon.t_cage);
    cr_expect(fabs(r.mon.t_capture - 0.388) < 1.5e-3, "t_capture %g, measured 0.388 s", r.mon.t_capture);
    cr_expect_gt(r.mon.epsilon, 0.0, "epsilon at the verdict %g", r.mon.epsilon);
    cr_expect(isnan(r.mon.t_cage), "never caged: t_cage %g", r.mon.t_cage);
    touch = object_fingers(&r, &palm);
    cr_expect_eq(touch, 7u, "fingers touching the box (bit per finger): 0x%x, expected all three", touch);
    crun_close(&r);
}

/* The cage rests on the mirror symmetry of the placement (x = 0, the plane
 * between fingers 1 and 2). 0.1 mm off it, finger 2 touches the box about
 * 5 ms before finger 1 and turns it by about 3 deg onto more points of the
 * fingers and onto the palm: captured at 0.359 s with epsilon 0.17, never
 * caged. (Measured with capdyn run --set: 0.07 mm off the plane, or the box
 * turned 0.5 deg about the palm normal, is still caged; 0.1 mm or 1 deg is
 * captured.) */
Test(verdict_cage, the_box_off_the_mirror_plane_is_captured, .timeout = 120)
{
    static const char *const ov[] = {"target.object.position=[0.0001, 0.045, -0.01]"};
    crun r;
    int palm;
    unsigned touch;
    crun_open(&r, ov, 1);
    crun_to(&r, 0.5);
    cr_expect_eq(r.mon.verdict, CD_VERDICT_CAPTURED, "verdict %s (epsilon %g, t_cage %g)",
                 cd_verdict_name(r.mon.verdict), r.mon.epsilon, r.mon.t_cage);
    cr_expect(fabs(r.mon.t_capture - 0.359) < 1.5e-3, "t_capture %g, measured 0.359 s", r.mon.t_capture);
    cr_expect_gt(r.mon.epsilon, 0.0, "epsilon at the verdict %g", r.mon.epsilon);
    cr_expect(isnan(r.mon.t_cage), "never caged: t_cage %g", r.mon.t_cage);
    touch = object_fingers(&r, &palm);
    cr_expect(palm >= 1 && (touch & 6u) == 6u, "fingers 0x%x and %d palm contacts", touch, palm);
    crun_close(&r);
}
