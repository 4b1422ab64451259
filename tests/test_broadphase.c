/* The broad phase of the contact evaluation (src/contact/contact.c,
 * docs/contact.md "Broad phase of open slots"): an open slot apart from its
 * shape (x < 0) is skipped after its geometry, its other outputs computed
 * on demand. It must never skip a slot the exact query finds touching, and
 * it must change no result: the derivative, every slot output and every
 * switching function are bit-identical to the full evaluation
 * (opt.broad_phase = 0), and so is a whole capture run. The integrator's
 * smallest switching function leaves out the open slots apart by more than
 * their check point's radius (cd_contact_switch_near): the same ones with
 * and without the broad phase, all with positive functions. */
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include <capdyn/io.h>
#include "scene_util.h"
#include "capture_util.h"
#include "../src/contact/contact.h"
#include <math.h>
#include <string.h>

static unsigned long long bp_rng = 0x9E3779B97F4A7C15ULL;
static double bp_urand(void)
{
    bp_rng ^= bp_rng << 13;
    bp_rng ^= bp_rng >> 7;
    bp_rng ^= bp_rng << 17;
    return (double)(bp_rng >> 11) / 9007199254740992.0;
}

/* rotation from a random unit quaternion */
static void rand_quat(double q[4])
{
    double n;
    do {
        int i;
        for (i = 0; i < 4; i++) q[i] = 2.0 * bp_urand() - 1.0;
        n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    } while (n < 0.1 || n > 1.0);
    q[0] /= n; q[1] /= n; q[2] /= n; q[3] /= n;
}

static void quat_to_R(const double q[4], double R[9])
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    R[0] = 1 - 2 * (y * y + z * z); R[1] = 2 * (x * y - w * z);     R[2] = 2 * (x * z + w * y);
    R[3] = 2 * (x * y + w * z);     R[4] = 1 - 2 * (x * x + z * z); R[5] = 2 * (y * z - w * x);
    R[6] = 2 * (x * z - w * y);     R[7] = 2 * (y * z + w * x);     R[8] = 1 - 2 * (x * x + y * y);
}

static int same(double a, double b) { return memcmp(&a, &b, sizeof a) == 0; }
static int same3(const double *a, const double *b) { return memcmp(a, b, 3 * sizeof *a) == 0; }

/* One shape of every type on a fixed ground, each at its own place and
 * orientation within 0.6 m of the origin (the plane below them all); a free
 * probe body carries 12 check points of radius 0 to 0.06 m; every check
 * point is paired with every shape. */
static cd_model *scene(int *probe_sys)
{
    cd_model *m = cd_model_create();
    cd_error e;
    cd_contact_law law = cd_contact_law_default();
    double verts[3 * 10], q[4], R[9], zero[3] = {0, 0, 0};
    int ground, probe, lid, i, sh;
    static const double pos[6][3] = {{0, 0, -0.5}, {0.3, 0, 0}, {-0.3, 0.1, 0}, {0, 0.35, 0.1}, {0, -0.3, 0.05},
                                     {0.25, 0.3, -0.2}};
    static const double size[6][3] = {{0, 0, 0}, {0.15, 0, 0}, {0.12, 0.08, 0.2}, {0.1, 0.15, 0}, {0.06, 0.12, 0},
                                      {0, 0, 0}};
    const cd_shape_type type[6] = {CD_SHAPE_PLANE, CD_SHAPE_SPHERE, CD_SHAPE_BOX, CD_SHAPE_CYLINDER, CD_SHAPE_CAPSULE,
                                   CD_SHAPE_CONVEX};
    ground = add_system(m, "ground", CD_BASE_FIXED, 1.0, 1.0, NULL, NULL, NULL);
    probe = add_system(m, "probe", CD_BASE_FREE, 1.0, 0.01, zero, NULL, NULL);
    for (i = 0; i < 10; i++) { /* an irregular hull of 10 points */
        verts[3 * i] = 0.15 * (2.0 * bp_urand() - 1.0);
        verts[3 * i + 1] = 0.1 * (2.0 * bp_urand() - 1.0);
        verts[3 * i + 2] = 0.12 * (2.0 * bp_urand() - 1.0);
    }
    law.mu_s = law.mu_k = 0.5;
    lid = cd_model_add_law(m, &law, &e);
    cr_assert(lid >= 0, "%s", e.msg);
    for (i = 0; i < 6; i++) {
        rand_quat(q);
        quat_to_R(q, R);
        sh = cd_model_add_shape(m, m->sys_body_adr[ground], type[i], pos[i], i == 0 ? NULL : R,
                                type[i] == CD_SHAPE_PLANE || type[i] == CD_SHAPE_CONVEX ? NULL : size[i],
                                type[i] == CD_SHAPE_CONVEX ? verts : NULL, type[i] == CD_SHAPE_CONVEX ? 10 : 0, &e);
        cr_assert(sh >= 0, "shape %d: %s", i, e.msg);
        cr_assert(cd_model_add_pair(m, probe, -1, sh, lid, &e) >= 0, "%s", e.msg);
    }
    for (i = 0; i < 12; i++) {
        double p[3] = {0.2 * (2.0 * bp_urand() - 1.0), 0.2 * (2.0 * bp_urand() - 1.0), 0.2 * (2.0 * bp_urand() - 1.0)};
        cr_assert(cd_model_add_checkpoint(m, m->sys_body_adr[probe], p, 0.06 * (i % 4) / 3.0, &e) >= 0, "%s", e.msg);
    }
    m->gravity[0] = m->gravity[1] = m->gravity[2] = 0;
    cr_assert_eq(cd_model_finalize(m, &e), CD_OK, "%s", e.msg);
    cr_assert_eq(m->nslot, 72);
    *probe_sys = probe;
    return m;
}

/* the probe at a random pose and velocity near the shapes */
static void random_state(const cd_model *m, cd_data *d, int probe)
{
    cd_sys_state s = cd_state_of(m, d, probe);
    int i;
    for (i = 0; i < 3; i++) {
        s.pos[i] = 0.5 * (2.0 * bp_urand() - 1.0);
        s.vel[i] = 2.0 * bp_urand() - 1.0;
        s.angvel[i] = 4.0 * (2.0 * bp_urand() - 1.0);
    }
    s.pos[2] -= 0.2;
    rand_quat(s.quat);
}

Test(broadphase, never_skips_a_touching_slot_and_changes_no_output)
{
    /* 3000 random poses of the probe (72 slots against a plane, sphere,
     * box, cylinder, capsule and hull), then 2000 of a random walk of small
     * moves (where the free spheres cached by the last evaluation certify
     * slots apart; each cached sphere is checked to be free: its centre is
     * at least its radius from the shape by the exact query), all slots
     * open but in poses 2000-2999: a slot the broad
     * phase skips must have x < 0 by the exact query (cd_shape_distance on
     * the check point, independent of the evaluation), i.e. every touching
     * slot is evaluated; and against the full evaluation of the same state
     * the derivative, every slot output (through cd_contact_slot_outputs)
     * and both switching functions are bit-identical. Then, with a third of
     * the slots closed (stick or slip), none of those is skipped either. */
    int probe, pose, k, nskip = 0, ntouch = 0, nfar_bound = 0, nleft = 0, nfree = 0, nnear = 0;
    cd_model *m = scene(&probe);
    cd_error e;
    cd_data *d1 = cd_data_create(m, 0, &e), *d0;
    cr_assert(d1, "%s", e.msg);
    d0 = cd_data_create(m, 0, &e);
    cr_assert(d0, "%s", e.msg);
    cr_assert_eq(d1->opt.broad_phase, 1, "on by default");
    d0->opt.broad_phase = 0;
    for (pose = 0; pose < 5000; pose++) {
        int closed = pose >= 2000 && pose < 3000;
        if (pose < 3000 || pose % 500 == 0) {
            random_state(m, d1, probe);
        } else {
            /* a random walk of small moves (<= 0.5 mm, 0.01 rad) from the last pose: the free
             * spheres of the last evaluation certify most apart slots (slot_free) */
            cd_sys_state st = cd_state_of(m, d1, probe);
            double dq[4], qn[4], nq;
            int i;
            for (i = 0; i < 3; i++) st.pos[i] += 1e-3 * (bp_urand() - 0.5);
            dq[0] = 1.0;
            for (i = 1; i < 4; i++) dq[i] = 5e-3 * (2.0 * bp_urand() - 1.0);
            qn[0] = st.quat[0] * dq[0] - st.quat[1] * dq[1] - st.quat[2] * dq[2] - st.quat[3] * dq[3];
            qn[1] = st.quat[0] * dq[1] + st.quat[1] * dq[0] + st.quat[2] * dq[3] - st.quat[3] * dq[2];
            qn[2] = st.quat[0] * dq[2] - st.quat[1] * dq[3] + st.quat[2] * dq[0] + st.quat[3] * dq[1];
            qn[3] = st.quat[0] * dq[3] + st.quat[1] * dq[2] - st.quat[2] * dq[1] + st.quat[3] * dq[0];
            nq = sqrt(qn[0] * qn[0] + qn[1] * qn[1] + qn[2] * qn[2] + qn[3] * qn[3]);
            for (i = 0; i < 4; i++) st.quat[i] = qn[i] / nq;
        }
        memcpy(d0->y, d1->y, (size_t)m->ny * sizeof(double));
        d0->t = d1->t;
        for (k = 0; k < m->nslot; k++) {
            int mode = closed && bp_urand() < 0.33 ? (bp_urand() < 0.5 ? CD_MODE_STICK : CD_MODE_SLIP) : CD_MODE_OPEN;
            d0->slot_mode[k] = d1->slot_mode[k] = mode;
            if (mode == CD_MODE_SLIP) {
                double dir[3] = {1, 0, 0};
                memcpy(d0->slot_dir + 3 * k, dir, sizeof dir);
                memcpy(d1->slot_dir + 3 * k, dir, sizeof dir);
            }
        }
        cr_assert_eq(cd_forward(m, d1), CD_OK);
        cr_assert_eq(cd_forward(m, d0), CD_OK);
        cr_assert(memcmp(d0->ydot, d1->ydot, (size_t)m->ny * sizeof(double)) == 0, "pose %d: ydot differs", pose);
        for (k = 0; k < m->nslot; k++) {
            int cp = m->slot_cp[k], sh = m->slot_shape[k];
            double pw[3], t[3], pl[3], dist, n[3], s[3], xt, x, xd, f, pt[3], nn[3], vt[3], g0[2], g1[2];
            const double *R = d1->shape_R + 9 * sh;
            cd_point_world(m, d1, m->cp_body[cp], m->cp_pos + 3 * cp, pw, NULL);
            t[0] = pw[0] - d1->shape_xw[3 * sh];
            t[1] = pw[1] - d1->shape_xw[3 * sh + 1];
            t[2] = pw[2] - d1->shape_xw[3 * sh + 2];
            pl[0] = R[0] * t[0] + R[3] * t[1] + R[6] * t[2];
            pl[1] = R[1] * t[0] + R[4] * t[1] + R[7] * t[2];
            pl[2] = R[2] * t[0] + R[5] * t[1] + R[8] * t[2];
            cr_assert_eq(cd_shape_distance(m, sh, pl, m->cp_radius[cp], &dist, n, s), 0);
            xt = m->cp_radius[cp] - dist;
            if (xt >= 0) {
                ntouch++;
                cr_assert_eq(d1->slot_far[k], 0, "pose %d slot %d: touching (x = %.3g m) but skipped", pose, k, xt);
            }
            if (d1->slot_mode[k] != CD_MODE_OPEN)
                cr_assert_eq(d1->slot_far[k], 0, "pose %d slot %d: closed but skipped", pose, k);
            if (d1->slot_far[k]) {
                nskip++;
                cr_assert_lt(xt, 0.0, "pose %d slot %d skipped with x = %.3g m", pose, k, xt);
                if (!same(d1->slot_x[k], xt)) nfar_bound++; /* x is a bound: the group's or a bounding sphere's */
            }
            cr_assert_eq(d0->slot_far[k], 0);
            cd_contact_slot_outputs(m, d1, k, &x, &xd, &f, pt, nn, vt);
            cr_assert(same(x, d0->slot_x[k]), "pose %d slot %d: x", pose, k);
            if (d1->slot_far[k]) /* in the data: x, or (a skipped group) an upper bound of the penetration */
                cr_assert(d1->slot_x[k] >= xt - 1e-12 && d1->slot_x[k] < 0, "pose %d slot %d: x %.17g, bound %.17g",
                          pose, k, xt, d1->slot_x[k]);
            else
                cr_assert(same(d1->slot_x[k], d0->slot_x[k]), "pose %d slot %d: x", pose, k);
            cr_assert(same(xd, d0->slot_xdot[k]) && same(f, d0->slot_fnraw[k]), "pose %d slot %d: xdot, f_raw", pose, k);
            cr_assert(same3(pt, d0->slot_point + 3 * k) && same3(nn, d0->slot_normal + 3 * k) &&
                      same3(vt, d0->slot_vt + 3 * k), "pose %d slot %d: point, normal, slip velocity", pose, k);
            cr_assert(same(d1->slot_fn[k], d0->slot_fn[k]) && same3(d1->slot_ft + 3 * k, d0->slot_ft + 3 * k),
                      "pose %d slot %d: forces", pose, k);
            if (d1->slot_free[4 * k + 3] > 0) { /* a cached free sphere is free */
                double fd, fn[3], fs[3];
                cr_assert_eq(cd_shape_distance(m, sh, d1->slot_free + 4 * k, 0.0, &fd, fn, fs), 0);
                cr_assert(fd >= d1->slot_free[4 * k + 3] - 1e-12, "pose %d slot %d: free sphere of radius %.17g, "
                          "its centre %.17g from the shape", pose, k, d1->slot_free[4 * k + 3], fd);
                if (pose >= 3000 && d1->slot_free[4 * k + 3] > m->cp_radius[cp]) nfree++;
            }
            cd_contact_switch(m, d1, k, 0, g1);
            cd_contact_switch(m, d0, k, 0, g0);
            cr_assert(same(g0[0], g1[0]) && same(g0[1], g1[1]), "pose %d slot %d: switching functions", pose, k);
            {
                /* the integrator's minimum leaves out exactly the open slots apart by more than r
                 * (their functions positive), the same with and without the broad phase, and
                 * takes the others' functions as they are */
                double h0[2], h1[2];
                int n1 = cd_contact_switch_near(m, d1, k, h1), n0 = cd_contact_switch_near(m, d0, k, h0);
                /* the rule on the full evaluation's x (a hull's plane bound beyond the margin: >= the
                 * true x), and, independent of it, never for a slot within r by the exact query */
                int apart = d0->slot_mode[k] == CD_MODE_OPEN && d0->slot_x[k] < -m->cp_radius[cp];
                cr_assert_eq(n1, n0, "pose %d slot %d: left out with the broad phase %d, without %d (x %.17g / %.17g, exact %.17g, r %g, far %d, shape %d)", pose, k, !n1, !n0, d1->slot_x[k], d0->slot_x[k], xt, m->cp_radius[cp], d1->slot_far[k], (int)m->shape_type[sh]);
                cr_assert_eq(n1, !apart, "pose %d slot %d: open %d, x = %.6g m, r = %g m: left out %d", pose, k,
                             d0->slot_mode[k] == CD_MODE_OPEN, d0->slot_x[k], m->cp_radius[cp], !n1);
                if (!(d1->slot_mode[k] == CD_MODE_OPEN && xt < -m->cp_radius[cp] * (1.0 - 1e-9)))
                    cr_assert_eq(n1, 1, "pose %d slot %d: x = %.6g m by the exact query, left out", pose, k, xt);
                if (!n1) {
                    nleft++;
                    cr_assert(g1[0] > 0 && g1[1] > 0, "pose %d slot %d: left out with g = (%g, %g)", pose, k, g1[0], g1[1]);
                } else {
                    cr_assert(same(h1[0], g1[0]) && same(h1[1], g1[1]) && same(h0[0], g0[0]) && same(h0[1], g0[1]),
                              "pose %d slot %d: kept, with other functions", pose, k);
                }
            }
        }
        {
            /* the groups' near spheres: each holds the exact distance at its centre, and where the
             * evaluation skips a group's query by it (the distance bound below R - 1e-6 m) the exact
             * query at the group's centre finds it not apart (dist <= R) */
            int g;
            for (g = 0; g < m->ngroup; g++) {
                const double *near = d1->group_near + 4 * g;
                int k0 = m->group_adr[g], sh = m->slot_shape[k0];
                double cw[3], t[3], cl[3], dist, n[3], s[3], mv, R0 = m->group_radius[g];
                const double *R = d1->shape_R + 9 * sh;
                if (!(near[3] < HUGE_VAL)) continue;
                cr_assert_eq(cd_shape_distance(m, sh, near, 0.0, &dist, n, s), 0);
                cr_assert(same(dist, near[3]), "pose %d group %d: near sphere %.17g, exact %.17g", pose, g, near[3], dist);
                cd_point_world(m, d1, m->cp_body[m->slot_cp[k0]], m->group_pos + 3 * g, cw, NULL);
                for (k = 0; k < 3; k++) t[k] = cw[k] - d1->shape_xw[3 * sh + k];
                cl[0] = R[0] * t[0] + R[3] * t[1] + R[6] * t[2];
                cl[1] = R[1] * t[0] + R[4] * t[1] + R[7] * t[2];
                cl[2] = R[2] * t[0] + R[5] * t[1] + R[8] * t[2];
                for (k = 0; k < 3; k++) t[k] = cl[k] - near[k];
                mv = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
                if (near[3] + mv < R0 - 1e-6 && mv > 0) {
                    nnear++;
                    cr_assert_eq(cd_shape_distance(m, sh, cl, 0.0, &dist, n, s), 0);
                    cr_assert(dist <= R0, "pose %d group %d: skippable by its near sphere, yet %.17g from the shape "
                              "(R %.17g)", pose, g, dist, R0);
                }
            }
        }
        if (pose % 100 == 0) { /* cd_contact_complete leaves every array as the full evaluation's */
            cd_contact_complete(m, d1);
            for (k = 0; k < m->nslot; k++) cr_assert_eq(d1->slot_far[k], 0);
            cr_assert(memcmp(d1->slot_xdot, d0->slot_xdot, (size_t)m->nslot * sizeof(double)) == 0);
            cr_assert(memcmp(d1->slot_point, d0->slot_point, (size_t)m->nslot * 3 * sizeof(double)) == 0);
            cr_assert(memcmp(d1->slot_normal, d0->slot_normal, (size_t)m->nslot * 3 * sizeof(double)) == 0);
            cr_assert(memcmp(d1->slot_vt, d0->slot_vt, (size_t)m->nslot * 3 * sizeof(double)) == 0);
            cr_assert(memcmp(d1->slot_fnraw, d0->slot_fnraw, (size_t)m->nslot * sizeof(double)) == 0);
            cr_assert(memcmp(d1->slot_x, d0->slot_x, (size_t)m->nslot * sizeof(double)) == 0);
        }
    }
    cr_log_info("5000 poses x 72 slots: %d touching, %d skipped (%d with a bound for x: by the group, a bounding "
                "sphere or a free sphere)",
                ntouch, nskip, nfar_bound);
    cr_expect_gt(ntouch, 1000, "the poses bring many check points into contact");
    cr_expect_gt(nskip, 50000, "most open slots are skipped");
    cr_log_info("%d free spheres larger than the check point in the random walk", nfree);
    cr_expect_gt(nfree, 10000, "the walk's evaluations cache free spheres");
    cr_expect_gt(nfar_bound, 1000, "many before their own exact query");
    cr_log_info("%d group centres within their near sphere's bound after a move (the group query skipped)", nnear);
    cr_expect_gt(nnear, 100, "the walk's evaluations use the groups' near spheres");
    cr_log_info("%d open slots left out of the smallest switching function (apart by more than r)", nleft);
    cr_expect_gt(nleft, 10000, "most open slots are apart by more than r");
    cd_data_free(d0);
    cd_data_free(d1);
    cd_model_free(m);
}

Test(broadphase, option_is_checked)
{
    cd_options o = cd_options_default();
    cd_error e;
    o.broad_phase = 2;
    cr_assert_eq(cd_options_check(&o, &e), CD_EINVAL);
    cr_expect_str_eq(e.msg, "option broad_phase must be 0 or 1, got 2");
}

/* One capture run to t_end with the broad phase on or off. */
typedef struct {
    cd_scenario *sc;
    cd_data *d;
    cd_ctrl *c;
    cd_monitor mon;
} bp_run;

static void capture_run(bp_run *r, const char *path, int broad_phase, double t_end)
{
    cd_error err;
    capture_open(path, NULL, 0, &r->sc, &r->d, &r->c, &r->mon);
    r->d->opt.broad_phase = broad_phase;
    while (r->d->t < t_end - 1e-12) {
        double tn = fmin(r->d->t + r->sc->output_dt, t_end);
        cr_assert_eq(cd_sim_advance(r->sc->model, r->d, tn, NULL, NULL, &err), CD_OK, "%s: %s", path, err.msg);
        cd_monitor_update(&r->mon, r->sc->model, r->d);
    }
}

Test(broadphase, capture_run_is_bit_identical_without_it, .timeout = 600)
{
    /* scenarios/capture_handrail_tumbling.toml (432 slots, 16 ever in
     * contact), its whole 4.5 s with its own settings (rk8pd, rtol 1e-9):
     * with and without the broad phase the same steps, evaluations and
     * events (time, kind, slot, x, forces: bit for bit), the same final
     * state and the same verdict at the same time. */
    const char *path = "scenarios/capture_handrail_tumbling.toml";
    bp_run a, b;
    long i, nev;
    const cd_model *m;
    capture_run(&a, path, 1, 4.5);
    capture_run(&b, path, 0, 4.5);
    m = a.sc->model;
    cr_assert_eq(m->nslot, 432);
    cr_expect_eq(a.d->stats.nsteps, b.d->stats.nsteps);
    cr_expect_eq(a.d->stats.nrhs, b.d->stats.nrhs);
    cr_expect_eq(a.d->stats.nrejected, b.d->stats.nrejected);
    cr_assert_eq(a.d->ev_count, b.d->ev_count);
    cr_assert_gt(a.d->ev_count, 10, "contact events happen");
    nev = a.d->ev_count < a.d->ev_cap ? a.d->ev_count : a.d->ev_cap;
    for (i = 0; i < nev; i++) {
        const cd_event *x = cd_data_event(a.d, i), *y = cd_data_event(b.d, i);
        cr_assert(same(x->t, y->t) && x->kind == y->kind && x->slot == y->slot && x->owner == y->owner &&
                      same(x->x, y->x) && same(x->fn, y->fn) && same(x->ft, y->ft),
                  "event %ld: %s slot %d at %.17g vs %s slot %d at %.17g", i, cd_event_kind_name(x->kind), x->slot, x->t,
                  cd_event_kind_name(y->kind), y->slot, y->t);
    }
    cr_assert(same(a.d->t, b.d->t));
    cr_expect(memcmp(a.d->y, b.d->y, (size_t)m->ny * sizeof(double)) == 0, "final state bit-identical");
    cr_expect(memcmp(a.d->slot_fn, b.d->slot_fn, (size_t)m->nslot * sizeof(double)) == 0, "final normal forces");
    cr_expect_eq(a.mon.verdict, CD_VERDICT_CAPTURED, "verdict %s", cd_verdict_name(a.mon.verdict));
    cr_expect_eq(a.mon.verdict, b.mon.verdict);
    cr_expect(same(a.mon.t_capture, b.mon.t_capture), "captured at %.17g vs %.17g s", a.mon.t_capture, b.mon.t_capture);
    cd_ctrl_free(a.c); cd_data_free(a.d); cd_scenario_free(a.sc);
    cd_ctrl_free(b.c); cd_data_free(b.d); cd_scenario_free(b.sc);
}
