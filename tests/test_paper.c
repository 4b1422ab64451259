/* The paper's scenarios, run from the shipped files (the TOML files in scenarios/), as
 * users run them: the outcomes the figures are meant to show.
 *
 * Fig. 3: the compliant mechanism hitting a wall. From the first onset to
 * the final separation the front mass stays at (or keeps returning to) the
 * wall for half a period of the carrier on the soft spring,
 * pi sqrt(M/K_a) = 0.1987 s with the file's M = 10 kg, K_a = 2500 N/m
 * (paper: about 0.2 s), within 2 %; the first strike is short: it lasts
 * about half a period of the front mass on the stiff contact,
 * pi sqrt(m/K_b) = 3.14 ms (m = 0.1 kg, K_b = 1e5 N/m), within 10 % (the
 * soft spring in parallel and the light damping shift it by a few %).
 *
 * Fig. 5, the benchmark file: after 2 s the cylinder is caged by the two
 * fingers and pressed on the palm: several contacts stick, on each finger and
 * on the palm, and the cylinder is nearly at rest relative to the (fixed)
 * palm (the benchmark's constant torques and undamped joints leave a slow
 * rocking of about 2 mm/s that decays with a time constant of ~0.7 s). Which
 * links touch it, and the wrapped file (both links on the cylinder, the
 * paper's envelope grasp): at the end of this file. */
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include <capdyn/io.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static cd_scenario *load(const char *name)
{
    char path[1024];
    const char *root = getenv("CAPDYN_ROOT");
    cd_error e;
    cd_scenario *sc;
    snprintf(path, sizeof path, "%s/scenarios/%s", root ? root : ".", name);
    sc = cd_scenario_load(path, NULL, 0, &e);
    cr_assert(sc, "%s", e.msg);
    return sc;
}

Test(paper, fig3_two_time_scales, .timeout = 60)
{
    cd_scenario *sc = load("paper_fig3_impact.toml");
    const cd_model *m = sc->model;
    cd_error e;
    cd_data *d = cd_data_create(m, 0, &e);
    double t_first_on = -1, t_first_off = -1, t_last_off = -1, slow, strike;
    long i;
    cr_assert(d, "%s", e.msg);
    cr_assert_eq(cd_sim_advance(m, d, sc->duration, NULL, NULL, &e), CD_OK, "%s", e.msg);
    for (i = 0; i < d->ev_count; i++) {
        const cd_event *ev = cd_data_event(d, i);
        if (ev->kind == CD_EV_ONSET && t_first_on < 0) t_first_on = ev->t;
        if (ev->kind == CD_EV_SEPARATION) {
            if (t_first_off < 0) t_first_off = ev->t;
            t_last_off = ev->t;
        }
    }
    cr_assert(t_first_on > 0 && t_last_off > t_first_on, "no contact");
    slow = t_last_off - t_first_on;
    strike = t_first_off - t_first_on;
    cr_log_info("fig3 file: %ld events, first strike %.3e s, contact phase %.6f s, nrhs %ld", d->ev_count, strike,
                slow, d->stats.nrhs);
    cr_expect_lt(fabs(slow - M_PI * sqrt(10.0 / 2500.0)) / (M_PI * sqrt(10.0 / 2500.0)), 0.02,
                 "contact phase %.6f s", slow);
    cr_expect_lt(fabs(strike - M_PI * sqrt(0.1 / 1e5)) / (M_PI * sqrt(0.1 / 1e5)), 0.10, "first strike %.3e s",
                 strike);
    cd_data_free(d);
    cd_scenario_free(sc);
}

Test(paper, fig5_envelope_grasp_holds_the_cylinder, .timeout = 120)
{
    cd_scenario *sc = load("paper_fig5_envelope_grasp.toml");
    const cd_model *m = sc->model;
    cd_error e;
    cd_data *d = cd_data_create(m, 0, &e);
    int hand = cd_model_system_id(m, "hand"), obj = cd_model_system_id(m, "object"), k;
    int nstick = 0, on_left = 0, on_right = 0, on_palm = 0;
    double speed, spin;
    cd_sys_state o;
    cr_assert(d, "%s", e.msg);
    cr_assert(hand >= 0 && obj >= 0);
    cr_assert_eq(cd_sim_advance(m, d, sc->duration, NULL, NULL, &e), CD_OK, "%s", e.msg);
    o = cd_state_of(m, d, obj);
    speed = sqrt(o.vel[0] * o.vel[0] + o.vel[1] * o.vel[1] + o.vel[2] * o.vel[2]);
    spin = sqrt(o.angvel[0] * o.angvel[0] + o.angvel[1] * o.angvel[1] + o.angvel[2] * o.angvel[2]);
    for (k = 0; k < m->nslot; k++) {
        int body = m->cp_body[m->slot_cp[k]];
        const char *bn = m->body_name[body];
        if (d->slot_mode[k] != CD_MODE_STICK || m->shape_body[m->slot_shape[k]] != m->sys_body_adr[obj]) continue;
        nstick++;
        if (strncmp(bn, "left", 4) == 0) on_left++;
        else if (strncmp(bn, "right", 5) == 0) on_right++;
        else if (body == m->sys_body_adr[hand]) on_palm++;
    }
    cr_log_info("fig5 file: cylinder at (%.4f %.4f) m, speed %.2e m/s, spin %.2e rad/s; %d sticking contacts on it "
                "(left %d, right %d, palm %d); %ld events, nrhs %ld",
                o.pos[0], o.pos[1], speed, spin, nstick, on_left, on_right, on_palm, d->ev_count, d->stats.nrhs);
    /* caged between the fingers and pressed on the palm (palm face y = 0.02, radius 0.035) */
    cr_expect_lt(fabs(o.pos[1] - (0.02 + 0.035)), 2e-3, "cylinder centre y = %.4f m", o.pos[1]);
    cr_expect_lt(fabs(o.pos[0]), 0.02, "cylinder centre x = %.4f m", o.pos[0]);
    cr_expect_lt(fabs(o.pos[2]), 1e-9, "planar: z = %g m", o.pos[2]);
    cr_expect_geq(nstick, 3, "sticking contacts on the cylinder: %d", nstick);
    cr_expect(on_left >= 1 && on_right >= 1 && on_palm >= 1, "left %d right %d palm %d", on_left, on_right, on_palm);
    cr_expect_lt(speed, 1e-2, "cylinder speed %.3e m/s", speed);
    cr_expect_lt(spin, 0.3, "cylinder spin %.3e rad/s", spin);
    cd_data_free(d);
    cd_scenario_free(sc);
}

/* ---- Fig. 5: which links touch the cylinder (issue 22) ------------------------------
 * After every accepted step (and every event) the bodies with a closed slot
 * against the object are marked, with the first time each touched; and the
 * first closing of a fingertip-on-fingertip slot. Body order in the files:
 * palm, left1, left2, right1, right2. */
typedef struct {
    int obj_body;
    double t_touch[5]; /* first contact of palm, left1, left2, right1, right2 with the object; -1 never */
    double t_tips;     /* first fingertip-on-fingertip contact; -1 never */
} touch_log;

static int touch_cb(const cd_model *m, cd_data *d, void *user)
{
    touch_log *L = (touch_log *)user;
    int k;
    for (k = 0; k < m->nslot; k++) {
        int a = m->cp_body[m->slot_cp[k]], b = m->shape_body[m->slot_shape[k]];
        if (d->slot_mode[k] == CD_MODE_OPEN) continue;
        if (b == L->obj_body && a < 5 && L->t_touch[a] < 0) L->t_touch[a] = d->t;
        if (b != L->obj_body && L->t_tips < 0) L->t_tips = d->t;
    }
    return 0;
}

static void run_touch(const char *file, touch_log *L, cd_data **dp, cd_scenario **scp)
{
    cd_scenario *sc = load(file);
    const cd_model *m = sc->model;
    cd_error e;
    cd_data *d = cd_data_create(m, 0, &e);
    int i, obj = cd_model_system_id(m, "object");
    cr_assert(d, "%s", e.msg);
    cr_assert(obj >= 0);
    cr_assert_eq(cd_model_body_id(m, "hand/left1"), 1);
    cr_assert_eq(cd_model_body_id(m, "hand/left2"), 2);
    cr_assert_eq(cd_model_body_id(m, "hand/right1"), 3);
    cr_assert_eq(cd_model_body_id(m, "hand/right2"), 4);
    L->obj_body = m->sys_body_adr[obj];
    for (i = 0; i < 5; i++) L->t_touch[i] = -1;
    L->t_tips = -1;
    cr_assert_eq(cd_sim_advance(m, d, sc->duration, touch_cb, L, &e), CD_OK, "%s", e.msg);
    cr_log_info("%s: first contact with the cylinder: palm %.4f, left1 %.4f, left2 %.4f, right1 %.4f, right2 %.4f s; "
                "tip on tip %.4f s (-1: never)", file, L->t_touch[0], L->t_touch[1], L->t_touch[2], L->t_touch[3],
                L->t_touch[4], L->t_tips);
    *dp = d;
    *scp = sc;
}

/* The body's slots against the object that stick at the end. */
static int sticking_on(const cd_model *m, const cd_data *d, int body, int obj_body)
{
    int k, n = 0;
    for (k = 0; k < m->nslot; k++)
        if (m->cp_body[m->slot_cp[k]] == body && m->shape_body[m->slot_shape[k]] == obj_body &&
            d->slot_mode[k] == CD_MODE_STICK)
            n++;
    return n;
}

/* The benchmark file, as it is (what its header now says): the fingertips
 * meet above the cylinder before the fingers reach it (t < 0.05 s), the tip
 * links touch it, the proximal links never do: a fingertip grasp. The tip
 * pair uses the Hunt-Crossley law (no onset spike). */
Test(paper, fig5_benchmark_is_a_fingertip_grasp, .timeout = 120)
{
    touch_log L;
    cd_data *d;
    cd_scenario *sc;
    int k, hc = 0;
    run_touch("paper_fig5_envelope_grasp.toml", &L, &d, &sc);
    for (k = 0; k < sc->model->nslot; k++)
        if (sc->model->shape_body[sc->model->slot_shape[k]] != L.obj_body)
            hc += sc->model->law[sc->model->slot_law[k]].damping == CD_DAMP_HUNT_CROSSLEY;
    cr_expect_gt(hc, 0, "the fingertip pair's slots use Hunt-Crossley");
    cr_expect(L.t_tips >= 0 && L.t_tips < 0.05, "tips meet at %.4f s", L.t_tips);
    cr_expect(L.t_tips < L.t_touch[2] && L.t_tips < L.t_touch[4], "before either tip link touches the cylinder");
    cr_expect(L.t_touch[2] >= 0 && L.t_touch[4] >= 0, "tip links touch the cylinder");
    cr_expect(L.t_touch[1] < 0 && L.t_touch[3] < 0, "proximal links never touch it: left1 %.4f right1 %.4f",
              L.t_touch[1], L.t_touch[3]);
    cd_data_free(d);
    cd_scenario_free(sc);
}

/* The wrapped file: the paper's envelope grasp. Every link touches the
 * cylinder, the proximal links first; the tips never meet; at the end both
 * links of each finger hold it in stick and it is nearly at rest. */
Test(paper, fig5_wrapped_both_links_hold_the_cylinder, .timeout = 120)
{
    touch_log L;
    cd_data *d;
    cd_scenario *sc;
    cd_sys_state o;
    int i, obj;
    double speed;
    run_touch("paper_fig5_envelope_grasp_wrapped.toml", &L, &d, &sc);
    for (i = 1; i < 5; i++) cr_expect_geq(L.t_touch[i], 0, "link body %d touches the cylinder", i);
    cr_expect(L.t_touch[1] < L.t_touch[2] && L.t_touch[3] < L.t_touch[4], "proximal links first");
    cr_expect_lt(L.t_tips, 0, "the fingertips never meet: %.4f", L.t_tips);
    for (i = 1; i < 5; i++)
        cr_expect_geq(sticking_on(sc->model, d, i, L.obj_body), 1, "link body %d holds the cylinder in stick at the end", i);
    obj = cd_model_system_id(sc->model, "object");
    o = cd_state_of(sc->model, d, obj);
    speed = sqrt(o.vel[0] * o.vel[0] + o.vel[1] * o.vel[1] + o.vel[2] * o.vel[2]);
    cr_log_info("wrapped: cylinder at (%.4f %.4f) m, speed %.2e m/s", o.pos[0], o.pos[1], speed);
    cr_expect_lt(speed, 1e-2, "cylinder nearly at rest: %.3e m/s", speed);
    cd_data_free(d);
    cd_scenario_free(sc);
}
