/* The builders of include/capdyn/build.h (src/builders/): each hand type and
 * each target type built in C gives the model the scenario loader makes of
 * the same thing written in TOML, entry for entry (every count and every
 * table of cd_model compared exactly, after cd_model_finalize); and a hand's
 * check points are bounded before they are made (issue 24). */
#include "loader_util.h"

#include "capdyn/build.h"
#include "capdyn/capdyn.h"

#include <math.h>
#include <time.h>

#define DEG (3.14159265358979323846 / 180.0) /* the loader's degree */

/* ---- the comparison ------------------------------------------------------- */

static int bad; /* differing entries of the current comparison */

static void cmp_d(const char *what, const double *a, const double *b, int n)
{
    int i;
    for (i = 0; i < n; i++)
        if (memcmp(&a[i], &b[i], sizeof(double)) != 0) {
            if (bad++ < 8) cr_log_error("%s[%d]: C %.17g, TOML %.17g", what, i, a[i], b[i]);
        }
}
static void cmp_i(const char *what, const int *a, const int *b, int n)
{
    int i;
    for (i = 0; i < n; i++)
        if (a[i] != b[i] && bad++ < 8) cr_log_error("%s[%d]: C %d, TOML %d", what, i, a[i], b[i]);
}
static void cmp_s(const char *what, char *const *a, char *const *b, int n)
{
    int i;
    for (i = 0; i < n; i++)
        if (strcmp(a[i] ? a[i] : "", b[i] ? b[i] : "") != 0 && bad++ < 8) cr_log_error("%s[%d]: C '%s', TOML '%s'", what, i, a[i], b[i]);
}
#define CI(f) cmp_i(#f, &a->f, &b->f, 1)
#define AD(f, n) cmp_d(#f, a->f, b->f, (n))
#define AI(f, n) cmp_i(#f, a->f, b->f, (n))

/* every count and table of two finalized models; returns the entries that differ */
static int model_diff(const cd_model *a, const cd_model *b)
{
    int k;
    bad = 0;
    CI(nsys); CI(nbody); CI(ncp); CI(nshape); CI(nvert); CI(nlaw); CI(npair); CI(nslot); CI(ntbl); CI(nu); CI(ntrn);
    CI(nlim); CI(nfric); CI(nuser); CI(nfinger); CI(npresc); CI(nsw); CI(nv); CI(ny); CI(ny_slot_adr); CI(ny_fric_adr);
    CI(nface); CI(nfjnt); CI(nbreak);
    if (bad) return bad; /* the tables' sizes differ */
    AD(gravity, 3);
    if (a->opt.stepper != b->opt.stepper) bad++;
    CI(opt.equilibrium_start);
    cmp_d("opt", &a->opt.rtol, &b->opt.rtol, 1); cmp_d("opt.atol", &a->opt.atol, &b->opt.atol, 1);
    cmp_d("opt.h_init", &a->opt.h_init, &b->opt.h_init, 1); cmp_d("opt.h_max", &a->opt.h_max, &b->opt.h_max, 1);
    cmp_d("opt.event_tol", &a->opt.event_tol, &b->opt.event_tol, 1); cmp_d("opt.dwell", &a->opt.dwell, &b->opt.dwell, 1);
    /* systems */
    cmp_s("sys_name", a->sys_name, b->sys_name, a->nsys);
    AI(sys_base_type, a->nsys); AI(sys_body_adr, a->nsys); AI(sys_nbody, a->nsys); AI(sys_ndof, a->nsys);
    AI(sys_v_adr, a->nsys); AI(sys_y_adr, a->nsys);
    AD(sys_pos0, 3 * a->nsys); AD(sys_quat0, 4 * a->nsys); AD(sys_vel0, 3 * a->nsys); AD(sys_angvel0, 3 * a->nsys);
    /* bodies and joints */
    cmp_s("body_name", a->body_name, b->body_name, a->nbody);
    AI(body_sys, a->nbody); AI(body_parent, a->nbody); AI(body_jnt_type, a->nbody); AI(body_dof, a->nbody);
    AD(body_jnt_pos, 3 * a->nbody); AD(body_jnt_rot, 9 * a->nbody); AD(body_axis, 3 * a->nbody); AD(body_mass, a->nbody);
    AD(body_com, 3 * a->nbody); AD(body_inertia, 9 * a->nbody); AD(body_q0, a->nbody); AD(body_qd0, a->nbody);
    AD(body_spring, 2 * a->nbody); AD(body_damping, a->nbody); AD(body_fric, 3 * a->nbody); AD(body_limit, 6 * a->nbody);
    AI(body_lim_id, a->nbody); AI(body_fric_id, a->nbody); AI(lim_body, a->nlim); AI(fric_body, a->nfric);
    AI(body_presc, a->nbody); AD(body_presc_prm, 6 * a->nbody); AI(body_wp_adr, a->nbody); AI(body_wp_n, a->nbody);
    /* actuators, clutched fingers, tables */
    cmp_s("act_name", a->act_name, b->act_name, a->nu);
    AI(act_type, a->nu); AD(act_prm, 4 * a->nu); AD(act_motor, 2 * a->nu); AI(act_tbl_adr, a->nu); AI(act_tbl_n, a->nu);
    AI(act_trn_adr, a->nu); AI(act_trn_n, a->nu); AI(trn_body, a->ntrn); AD(trn_ratio, a->ntrn); AI(body_act, a->nbody);
    cmp_s("finger_name", a->finger_name, b->finger_name, a->nfinger);
    AI(finger_type, a->nfinger); AI(finger_jnt_adr, a->nfinger); AI(finger_jnt_n, a->nfinger); AI(fjnt_body, a->nfjnt);
    AD(fjnt_sync, a->nfjnt); AD(fjnt_ratio, a->nfjnt); AD(finger_prm, 6 * a->nfinger); AI(finger_tbl_adr, a->nfinger);
    AI(finger_tbl_n, a->nfinger); AD(tbl_t, a->ntbl); AD(tbl_v, a->ntbl); AD(breaks, a->nbreak);
    /* check points, shapes, hulls */
    AI(cp_body, a->ncp); AD(cp_pos, 3 * a->ncp); AD(cp_radius, a->ncp);
    AI(shape_body, a->nshape); AI(shape_type, a->nshape); AD(shape_pos, 3 * a->nshape); AD(shape_rot, 9 * a->nshape);
    AD(shape_size, 3 * a->nshape); AD(shape_rbound, a->nshape); AI(shape_vert_adr, a->nshape); AI(shape_vert_num, a->nshape);
    AD(vert, 3 * a->nvert); AI(shape_face_adr, a->nshape); AI(shape_face_num, a->nshape); AI(face_vert, 3 * a->nface);
    AD(face_plane, 4 * a->nface);
    /* laws, pairs, slots */
    for (k = 0; k < a->nlaw; k++) {
        const cd_contact_law *x = &a->law[k], *y = &b->law[k];
        double lx[10] = {x->K, x->D, x->p, x->q, x->Kt, x->Dt, x->mu_s, x->mu_k, x->pt, x->qt};
        double ly[10] = {y->K, y->D, y->p, y->q, y->Kt, y->Dt, y->mu_s, y->mu_k, y->pt, y->qt};
        cmp_d("law", lx, ly, 10);
        cmp_i("law.pull", &x->pull, &y->pull, 1);
    }
    AI(pair_sys, a->npair); AI(pair_body, a->npair); AI(pair_shape, a->npair); AI(pair_law, a->npair);
    AI(slot_cp, a->nslot); AI(slot_shape, a->nslot); AI(slot_law, a->nslot);
    return bad;
}

/* the scenario text written to a temporary file and loaded */
static cd_scenario *load_text(const char *text)
{
    char dir[512], path[600];
    cd_error err;
    cd_scenario *sc;
    lu_tmpdir(dir, sizeof dir);
    lu_write(dir, "s.toml", "%s", text);
    snprintf(path, sizeof path, "%s/s.toml", dir);
    sc = cd_scenario_load(path, NULL, 0, &err);
    cr_assert_not_null(sc, "%s", err.msg);
    lu_rm_rf(dir);
    return sc;
}

/* ---- hands ---------------------------------------------------------------- */

static const char *TARGET_TOML =
    "[simulation]\nduration = 1.0\n\n"
    "[[target]]\nname = \"object\"\nmass = 0.3\ninertia = [1.0e-4, 2.0e-4, 3.0e-4]\nposition = [0.005, 0.075, 0.0]\n"
    "velocity = [0.01, -0.02, 0.0]\nangular_velocity = [0.1, 0.2, 0.3]\n"
    "shape = { type = \"cylinder\", radius = 0.035, length = 0.06 }\n\n";

/* the cylinder target of TARGET_TOML, in C */
static int c_target(cd_model *m)
{
    cd_shape_desc s = cd_shape_desc_default();
    cd_target_desc t = cd_target_desc_default();
    cd_error err;
    int id;
    s.type = CD_SHAPE_CYLINDER;
    s.radius = 0.035;
    s.length = 0.06;
    t.name = "object";
    t.mass = 0.3;
    t.inertia[0] = 1.0e-4; t.inertia[4] = 2.0e-4; t.inertia[8] = 3.0e-4;
    t.pos[0] = 0.005; t.pos[1] = 0.075;
    t.vel[0] = 0.01; t.vel[1] = -0.02;
    t.angvel[0] = 0.1; t.angvel[1] = 0.2; t.angvel[2] = 0.3;
    t.shapes = &s;
    t.nshape = 1;
    id = cd_build_target(m, &t, &err);
    cr_assert(id >= 0, "%s", err.msg);
    return id;
}

/* hand h (with the target first, as the loader orders them), finalized */
static cd_model *c_hand_model(const cd_hand_desc *h, cd_hand *hand)
{
    cd_model *m = cd_model_create();
    cd_contact_law law = cd_contact_law_default();
    cd_error err;
    int tgt;
    cr_assert_not_null(m);
    tgt = c_target(m);
    cr_assert(cd_build_hand(m, h, hand, &err) >= 0, "%s", err.msg);
    cr_assert_eq(cd_build_hand_drive(m, h, hand, &law, &tgt, 1, &err), CD_OK, "%s", err.msg);
    cr_assert_eq(cd_model_finalize(m, &err), CD_OK, "%s", err.msg);
    return m;
}

static const char *TYPE_NAME[] = {"soft", "tako", "space", "torque_switch"};
static const char *LAYOUT_NAME[] = {"two_opposed", "three_120", "two_pairs", "two_interleaved"};

/* every key of [gripper] given (the non-default values of full_desc) */
static void full_toml(char *buf, size_t n, cd_hand_type ty, cd_hand_layout lay)
{
    int clutched = ty == CD_HAND_SPACE || ty == CD_HAND_TORQUE_SWITCH;
    snprintf(buf, n,
             "%s[gripper]\ntype = \"%s\"\nhand = \"%s\"\nlinks = [0.08, 0.07, 0.05]\nmasses = [0.05, 0.04, 0.03]\n"
             "radius = 0.007\nspacing = 0.11\ncheckpoint_spacing = 0.01\n%s"
             "palm = { size = [0.12, 0.04, 0.05], mass = 1.5, position = [0.0, -0.01, 0.02] }\n"
             "close = { time = 0.8, angle_deg = 110.0, start = 0.1 }\nopen_at = 2.0\ntorque = 0.05\n"
             "ratios = [3.0, 2.0, 1.0]\nmotor = { stall_torque = 0.4, noload_speed = 3.0 }\n%s"
             "finger_joint = { spring = 0.01, damping = 0.001, limit_deg = [[0.0, 180.0], [-10.0, 170.0], [0.0, 90.0]], q0_deg = [5.0, 0.0, 10.0] }\n",
             TARGET_TOML, TYPE_NAME[ty], LAYOUT_NAME[lay],
             lay == CD_HAND_TWO_PAIRS ? "pair_offset = 0.03\n" : lay == CD_HAND_TWO_INTERLEAVED ? "pair_offset = 0.02\n" : "",
             clutched ? "clutch = { threshold = 0.25, wire_stiffness = 15.0, wire_damping = 0.02, torque_limit = 0.3 }\n" : "");
}

static cd_hand_desc full_desc(cd_hand_type ty, cd_hand_layout lay)
{
    cd_hand_desc h = cd_hand_desc_default();
    const double lo[3] = {0.0, -10.0, 0.0}, hi[3] = {180.0, 170.0, 90.0}, q0[3] = {5.0, 0.0, 10.0};
    int j;
    h.type = ty;
    h.layout = lay;
    h.nlink = 3;
    h.link_length[0] = 0.08; h.link_length[1] = 0.07; h.link_length[2] = 0.05;
    h.link_mass[0] = 0.05; h.link_mass[1] = 0.04; h.link_mass[2] = 0.03;
    h.radius = 0.007;
    h.spacing = 0.11;
    h.checkpoint_spacing = 0.01;
    if (lay == CD_HAND_TWO_PAIRS) h.pair_offset = 0.03;
    if (lay == CD_HAND_TWO_INTERLEAVED) h.pair_offset = 0.02;
    h.palm_size[2] = 0.05;
    h.palm_mass = 1.5;
    h.palm_pos[1] = -0.01; h.palm_pos[2] = 0.02;
    h.close_time = 0.8;
    h.close_angle = 110.0 * DEG;
    h.close_start = 0.1;
    h.open_at = 2.0;
    h.torque = 0.05;
    h.ratio[0] = 3.0; h.ratio[1] = 2.0; h.ratio[2] = 1.0;
    h.stall_torque = 0.4;
    h.noload_speed = 3.0;
    if (ty == CD_HAND_SPACE || ty == CD_HAND_TORQUE_SWITCH) {
        h.clutch_threshold = 0.25;
        h.wire_stiffness = 15.0;
        h.wire_damping = 0.02;
        h.torque_limit = 0.3;
    }
    h.joint_spring = 0.01;
    h.joint_damping = 0.001;
    h.joint_limited = 1;
    for (j = 0; j < 3; j++) {
        h.joint_lower[j] = lo[j] * DEG;
        h.joint_upper[j] = hi[j] * DEG;
        h.q0[j] = q0[j] * DEG;
    }
    return h;
}

/* the C hand against the TOML one; the C hand's own counts as a check that
 * the comparison is not between two empty models */
static void compare_hand(const char *toml, const cd_hand_desc *h, int nfinger, int nact, int nclutch)
{
    cd_scenario *sc = load_text(toml);
    cd_hand hand;
    cd_model *m = c_hand_model(h, &hand);
    cr_expect_eq(model_diff(m, sc->model), 0, "%d entries differ", bad);
    cr_expect_eq(hand.nfinger, nfinger);
    cr_expect_eq(m->nbody, 1 + 1 + nfinger * h->nlink, "target, palm and the finger links");
    cr_expect_eq(hand.nact, nact);
    cr_expect_eq(hand.nclutch, nclutch);
    cr_expect_eq(m->nfinger, nclutch);
    cr_expect(hand.ncp > 0 && hand.ncp == m->ncp, "%d check points", hand.ncp);
    cr_expect(m->nslot >= hand.ncp, "%d slots: every check point of the hand against the target (and other fingers)", m->nslot);
    cr_expect_eq(sc->capture_hand, hand.sys);
    cr_expect_eq(sc->capture_palm, hand.palm);
    cd_model_free(m);
    cd_scenario_free(sc);
}

Test(build, soft_hand_equals_the_toml_one)
{
    char t[4096];
    cd_hand_desc h = full_desc(CD_HAND_SOFT, CD_HAND_THREE_120);
    full_toml(t, sizeof t, CD_HAND_SOFT, CD_HAND_THREE_120);
    compare_hand(t, &h, 3, 3, 0);
}

Test(build, tako_hand_equals_the_toml_one)
{
    char t[4096];
    cd_hand_desc h = full_desc(CD_HAND_TAKO, CD_HAND_TWO_PAIRS);
    full_toml(t, sizeof t, CD_HAND_TAKO, CD_HAND_TWO_PAIRS);
    compare_hand(t, &h, 4, 1, 0);
}

Test(build, space_hand_equals_the_toml_one)
{
    char t[4096];
    cd_hand_desc h = full_desc(CD_HAND_SPACE, CD_HAND_TWO_OPPOSED);
    full_toml(t, sizeof t, CD_HAND_SPACE, CD_HAND_TWO_OPPOSED);
    compare_hand(t, &h, 2, 0, 2);
}

Test(build, torque_switch_hand_equals_the_toml_one)
{
    char t[4096];
    cd_hand_desc h = full_desc(CD_HAND_TORQUE_SWITCH, CD_HAND_TWO_INTERLEAVED);
    full_toml(t, sizeof t, CD_HAND_TORQUE_SWITCH, CD_HAND_TWO_INTERLEAVED);
    compare_hand(t, &h, 2, 0, 2);
}

/* the documented defaults are the loader's: only type and links given */
Test(build, default_description_equals_the_loaders_defaults)
{
    char t[2048];
    int ty;
    for (ty = 0; ty < CD_HAND_NTYPES; ty++) {
        cd_hand_desc h = cd_hand_desc_default();
        snprintf(t, sizeof t, "%s[gripper]\ntype = \"%s\"\nlinks = [0.08, 0.07]\n", TARGET_TOML, TYPE_NAME[ty]);
        h.type = (cd_hand_type)ty;
        h.link_length[1] = 0.07;
        compare_hand(t, &h, 2, ty == CD_HAND_SOFT ? 2 : ty == CD_HAND_TAKO ? 1 : 0, ty >= CD_HAND_SPACE ? 2 : 0);
    }
}

/* a hand mounted on the last link of a chaser (the fingers become that
 * link's branches) and closed by a controller's trigger */
Test(build, mounted_hand_equals_the_toml_one)
{
    static const char *toml =
        "[simulation]\nduration = 1.0\n\n"
        "[[system]]\nname = \"chaser\"\nmass = 100.0\ninertia = [10.0, 11.0, 12.0]\nposition = [0.0, -1.0, 0.0]\n"
        "[[system.link]]\nname = \"wrist\"\naxis = [0.0, 0.0, 1.0]\norigin = [0.0, 0.5, 0.0]\nmass = 2.0\n"
        "com = [0.0, 0.1, 0.0]\ninertia = [0.01, 0.02, 0.03]\n\n"
        "[gripper]\ntype = \"tako\"\nsystem = \"chaser\"\nattach = \"wrist\"\nlinks = [0.08, 0.07]\n"
        "palm = { position = [0.0, 0.2, 0.0] }\nclose = { on = \"trigger\" }\n\n"
        "[[target]]\nname = \"object\"\nmass = 0.3\ninertia = [1.0e-4, 2.0e-4, 3.0e-4]\nposition = [0.0, 0.0, 0.0]\n"
        "shape = { type = \"sphere\", radius = 0.03 }\n\n"
        "[control]\ntype = \"capture\"\nfixture = \"object/shape\"\n";
    cd_scenario *sc = load_text(toml);
    cd_model *m = cd_model_create();
    cd_system_desc sd = cd_system_desc_default();
    cd_link_desc ld = cd_link_desc_default();
    cd_target_desc td = cd_target_desc_default();
    cd_shape_desc s = cd_shape_desc_default();
    cd_hand_desc h = cd_hand_desc_default();
    cd_contact_law law = cd_contact_law_default();
    cd_hand hand;
    cd_error err;
    int chaser, wrist, tgt;
    sd.name = "chaser";
    sd.mass = 100.0;
    sd.inertia[0] = 10.0; sd.inertia[4] = 11.0; sd.inertia[8] = 12.0;
    sd.pos[1] = -1.0;
    chaser = cd_model_add_system(m, &sd, &err);
    cr_assert(chaser >= 0, "%s", err.msg);
    ld.name = "wrist";
    ld.parent = m->sys_body_adr[chaser];
    ld.pos[1] = 0.5;
    ld.mass = 2.0;
    ld.com[1] = 0.1;
    ld.inertia[0] = 0.01; ld.inertia[4] = 0.02; ld.inertia[8] = 0.03;
    wrist = cd_model_add_link(m, chaser, &ld, &err);
    cr_assert(wrist >= 0, "%s", err.msg);
    h.type = CD_HAND_TAKO;
    h.attach_body = wrist;
    h.link_length[1] = 0.07;
    h.palm_pos[1] = 0.2;
    h.close_on_trigger = 1;
    cr_assert(cd_build_hand(m, &h, &hand, &err) >= 0, "%s", err.msg);
    s.radius = 0.03;
    td.name = "object";
    td.mass = 0.3;
    td.inertia[0] = 1.0e-4; td.inertia[4] = 2.0e-4; td.inertia[8] = 3.0e-4;
    td.shapes = &s;
    td.nshape = 1;
    tgt = cd_build_target(m, &td, &err);
    cr_assert(tgt >= 0, "%s", err.msg);
    cr_assert_eq(cd_build_hand_drive(m, &h, &hand, &law, &tgt, 1, &err), CD_OK, "%s", err.msg);
    /* the loader's controller adds its user switches (2: detumble off) */
    cr_assert_eq(cd_model_set_user_switches(m, 2, &err), CD_OK, "%s", err.msg);
    cr_assert_eq(cd_model_finalize(m, &err), CD_OK, "%s", err.msg);
    cr_expect_eq(model_diff(m, sc->model), 0, "%d entries differ", bad);
    cr_expect_eq(hand.sys, chaser);
    cr_expect_eq(hand.palm, wrist);
    cr_expect_eq(m->act_type[hand.act[0]], CD_ACT_NONE, "closed by the trigger: u = ctrl");
    cr_assert_not_null(sc->control);
    cr_expect_eq(sc->control->nclose, 1);
    cr_expect_eq(sc->control->close_act[0], hand.act[0]);
    cr_expect_eq(sc->control->close_u[0], hand.act_close_u[0]);
    cd_model_free(m);
    cd_scenario_free(sc);
}

/* ---- targets -------------------------------------------------------------- */

static const double CUBE[24] = {-0.1, -0.1, -0.1, 0.1, -0.1, -0.1, -0.1, 0.1, -0.1, 0.1, 0.1, -0.1,
                                -0.1, -0.1, 0.1,  0.1, -0.1, 0.1,  -0.1, 0.1, 0.1,  0.12, 0.1, 0.1};

/* target shape kinds: the TOML `shape` value and the same in C */
struct tcase {
    const char *toml;
    int nshape;
    cd_shape_desc s[3];
};

static void target_case(struct tcase *c, int k)
{
    cd_shape_desc d = cd_shape_desc_default();
    /* shape frame rotated by the quaternion (0.5, 0.5, 0.5, 0.5): exact */
    const double R[9] = {0, 0, 1, 1, 0, 0, 0, 1, 0};
    memset(c, 0, sizeof *c);
    c->nshape = 1;
    d.pos[0] = 0.01; d.pos[1] = -0.02; d.pos[2] = 0.03;
    switch (k) {
    case 0:
        c->toml = "{ type = \"sphere\", radius = 0.04, position = [0.01, -0.02, 0.03] }";
        d.type = CD_SHAPE_SPHERE; d.radius = 0.04;
        break;
    case 1:
        c->toml = "{ type = \"box\", size = [0.1, 0.2, 0.3], position = [0.01, -0.02, 0.03], quaternion = [0.5, 0.5, 0.5, 0.5] }";
        d.type = CD_SHAPE_BOX; d.size[0] = 0.1; d.size[1] = 0.2; d.size[2] = 0.3;
        memcpy(d.rot, R, sizeof R);
        break;
    case 2:
        c->toml = "{ type = \"cylinder\", radius = 0.035, length = 0.24, position = [0.01, -0.02, 0.03] }";
        d.type = CD_SHAPE_CYLINDER; d.radius = 0.035; d.length = 0.24;
        break;
    case 3:
        c->toml = "{ type = \"capsule\", radius = 0.015, length = 0.3, position = [0.01, -0.02, 0.03] }";
        d.type = CD_SHAPE_CAPSULE; d.radius = 0.015; d.length = 0.3;
        break;
    case 4:
        c->toml = "{ type = \"convex\", position = [0.01, -0.02, 0.03], vertices = [[-0.1, -0.1, -0.1], [0.1, -0.1, -0.1], "
                  "[-0.1, 0.1, -0.1], [0.1, 0.1, -0.1], [-0.1, -0.1, 0.1], [0.1, -0.1, 0.1], [-0.1, 0.1, 0.1], [0.12, 0.1, 0.1]] }";
        d.type = CD_SHAPE_CONVEX; d.verts = CUBE; d.nvert = 8;
        break;
    case 5:
        c->toml = "{ type = \"handrail\", radius = 0.015, length = 0.5, height = 0.06, post = 0.025, position = [0.01, -0.02, 0.03], "
                  "quaternion = [0.5, 0.5, 0.5, 0.5] }";
        d.type = CD_SHAPE_HANDRAIL; d.radius = 0.015; d.length = 0.5; d.height = 0.06; d.post = 0.025;
        memcpy(d.rot, R, sizeof R);
        break;
    case 6: /* a docking fixture: a cylinder on a stand-off post */
        c->toml = "[{ name = \"dock\", type = \"cylinder\", radius = 0.035, length = 0.24, position = [-0.95, -0.3, 0.2] },"
                  " { name = \"dock_post\", type = \"box\", size = [0.15, 0.04, 0.04], position = [-0.875, -0.3, 0.2] }]";
        c->nshape = 2;
        d.type = CD_SHAPE_CYLINDER; d.radius = 0.035; d.length = 0.24;
        d.pos[0] = -0.95; d.pos[1] = -0.3; d.pos[2] = 0.2;
        c->s[1] = d;
        c->s[1].type = CD_SHAPE_BOX; c->s[1].size[0] = 0.15; c->s[1].size[1] = 0.04; c->s[1].size[2] = 0.04;
        c->s[1].pos[0] = -0.875;
        break;
    default: /* a body with two solar-array wings (thin boxes) */
        c->toml = "[{ name = \"body\", type = \"box\", size = [1.6, 1.4, 1.2] },"
                  " { name = \"wing0\", type = \"box\", size = [0.03, 2.0, 1.0], position = [0.0, 1.7, 0.0] },"
                  " { name = \"wing1\", type = \"box\", size = [0.03, 2.0, 1.0], position = [0.0, -1.7, 0.0] }]";
        c->nshape = 3;
        d.type = CD_SHAPE_BOX; d.size[0] = 1.6; d.size[1] = 1.4; d.size[2] = 1.2;
        d.pos[0] = d.pos[1] = d.pos[2] = 0;
        c->s[1] = d; c->s[1].size[0] = 0.03; c->s[1].size[1] = 2.0; c->s[1].size[2] = 1.0; c->s[1].pos[1] = 1.7;
        c->s[2] = c->s[1]; c->s[2].pos[1] = -1.7;
        break;
    }
    c->s[0] = d;
}

Test(build, each_target_type_equals_the_toml_one)
{
    int k;
    for (k = 0; k < 8; k++) {
        struct tcase c;
        char t[4096];
        cd_scenario *sc;
        cd_model *m = cd_model_create();
        cd_target_desc td = cd_target_desc_default();
        cd_hand_desc h = cd_hand_desc_default();
        cd_contact_law law = cd_contact_law_default();
        cd_hand hand;
        cd_error err;
        int tgt, i, nsh = 0;
        target_case(&c, k);
        /* tumbling: mass properties, pose, velocity and rate; the default hand pairs with it */
        snprintf(t, sizeof t,
                 "[simulation]\nduration = 1.0\n\n[[target]]\nname = \"sat\"\nmass = 410.0\n"
                 "inertia = [[116.0, 1.0, 0.0], [1.0, 137.0, 0.0], [0.0, 0.0, 154.0]]\nposition = [1.0, 2.0, 3.0]\n"
                 "quaternion = [0.9, 0.1, 0.3, 0.2]\nvelocity = [0.01, 0.0, -0.02]\nangular_velocity_deg_s = [3.0, 0.0, 1.0]\n"
                 "shape = %s\n\n[gripper]\ntype = \"space\"\nlinks = [0.08, 0.08]\n",
                 c.toml);
        sc = load_text(t);
        td.name = "sat";
        td.mass = 410.0;
        td.inertia[0] = 116.0; td.inertia[1] = td.inertia[3] = 1.0; td.inertia[4] = 137.0; td.inertia[8] = 154.0;
        td.pos[0] = 1.0; td.pos[1] = 2.0; td.pos[2] = 3.0;
        td.quat[0] = 0.9; td.quat[1] = 0.1; td.quat[2] = 0.3; td.quat[3] = 0.2;
        td.vel[0] = 0.01; td.vel[2] = -0.02;
        td.angvel[0] = 3.0 * DEG; td.angvel[2] = 1.0 * DEG;
        td.shapes = c.s;
        td.nshape = c.nshape;
        tgt = cd_build_target(m, &td, &err);
        cr_assert(tgt >= 0, "case %d: %s", k, err.msg);
        for (i = 0; i < c.nshape; i++) nsh += cd_shape_desc_count(&c.s[i]);
        cr_expect_eq(m->nshape, nsh, "case %d", k);
        cr_assert(cd_build_hand(m, &h, &hand, &err) >= 0, "%s", err.msg);
        cr_assert_eq(cd_build_hand_drive(m, &h, &hand, &law, &tgt, 1, &err), CD_OK, "%s", err.msg);
        cr_assert_eq(cd_model_finalize(m, &err), CD_OK, "case %d: %s", k, err.msg);
        cr_expect_eq(model_diff(m, sc->model), 0, "case %d (%s): %d entries differ", k, c.toml, bad);
        cd_model_free(m);
        cd_scenario_free(sc);
    }
}

/* the handrail's three parts: the bar's axis along the rail's x at its
 * height, the posts at its ends (exact geometry, not only the loader's) */
Test(build, handrail_is_a_bar_on_two_posts)
{
    cd_model *m = cd_model_create();
    cd_system_desc sd = cd_system_desc_default();
    cd_shape_desc s = cd_shape_desc_default();
    cd_error err;
    int sys, id;
    sys = cd_model_add_system(m, &sd, &err);
    s.type = CD_SHAPE_HANDRAIL;
    s.radius = 0.015; s.length = 0.5; s.height = 0.06; /* post: 2 radius */
    id = cd_build_shape(m, m->sys_body_adr[sys], &s, &err);
    cr_assert_eq(id, 0, "%s", err.msg);
    cr_assert_eq(m->nshape, 3);
    cr_expect_eq(m->shape_type[0], CD_SHAPE_CAPSULE);
    cr_expect_float_eq(m->shape_pos[2], 0.06, 1e-15);
    cr_expect_float_eq(m->shape_size[1], 0.25 - 0.015, 1e-15, "capsule half axis: the bar spans the length");
    cr_expect_float_eq(m->shape_rot[2], 1.0, 1e-15, "the capsule's axis (z) along the rail's x");
    cr_expect_eq(m->shape_type[1], CD_SHAPE_BOX);
    cr_expect_float_eq(m->shape_pos[3], -(0.25 - 0.015), 1e-15);
    cr_expect_float_eq(m->shape_pos[6], 0.25 - 0.015, 1e-15);
    cr_expect_float_eq(m->shape_size[5], 0.03, 1e-15, "post half height");
    /* too short for its posts, or a bar below its radius */
    s.length = 0.05;
    cr_expect_lt(cd_build_shape(m, 0, &s, &err), 0);
    cr_expect(strstr(err.msg, "posts") != NULL, "%s", err.msg);
    s.length = 0.5; s.height = 0.01;
    cr_expect_lt(cd_build_shape(m, 0, &s, &err), 0);
    cr_expect(strstr(err.msg, "radius") != NULL, "%s", err.msg);
    cd_model_free(m);
}

/* ---- bounds (issue 24) ---------------------------------------------------- */

/* a 1e-300 m radius (the check-point spacing's default), a tiny spacing or a
 * huge link is refused at once, before any check point is made */
Test(build, huge_checkpoint_counts_are_refused_before_allocating, .timeout = 10)
{
    cd_model *m = cd_model_create();
    cd_hand_desc h = cd_hand_desc_default();
    cd_hand hand;
    cd_error err;
    clock_t c0 = clock();
    h.radius = 1e-300;
    cr_expect_lt(cd_build_hand(m, &h, &hand, &err), 0);
    cr_expect_eq(err.status, CD_EINVAL);
    cr_expect(strstr(err.msg, "expected at most 100000") != NULL, "%s", err.msg);
    cr_expect_eq(m->nsys, 0, "nothing built");
    h = cd_hand_desc_default();
    h.link_length[0] = 1e6; /* 1.25e8 check points at 8 mm */
    cr_expect_lt(cd_build_hand(m, &h, &hand, &err), 0);
    cr_expect(strstr(err.msg, "check points") != NULL, "%s", err.msg);
    cr_expect_eq(m->ncp, 0);
    cr_expect_gt(cd_hand_checkpoint_count(&h), 1e8);
    cr_expect_lt((double)(clock() - c0) / CLOCKS_PER_SEC, 1.0, "refused without making them");
    /* the count of a normal hand is exact: 2 fingers x (10 + 10) + 11 on the palm */
    h = cd_hand_desc_default();
    cr_expect_eq(cd_hand_checkpoint_count(&h), 2 * (10 + 10) + 11);
    cr_assert(cd_build_hand(m, &h, &hand, &err) >= 0, "%s", err.msg);
    cr_expect_eq(hand.ncp, 2 * (10 + 10) + 11);
    cr_expect_eq(m->ncp, hand.ncp);
    cd_model_free(m);
}

/* a finger link shorter than the check-point spacing would pass through objects */
Test(build, a_link_without_check_points_is_refused)
{
    cd_model *m = cd_model_create();
    cd_hand_desc h = cd_hand_desc_default();
    cd_hand hand;
    cd_error err;
    h.checkpoint_spacing = 0.09; /* longer than the 0.08 m links */
    cr_expect_lt(cd_build_hand(m, &h, &hand, &err), 0);
    cr_expect(strstr(err.msg, "no check point") != NULL, "%s", err.msg);
    cr_expect_eq(m->nsys, 0);
    cd_model_free(m);
}

/* ---- the cost of a tumbling rate (issue 24) ------------------------------- */

/* a free box tumbling at w about (1, 0, 1)/sqrt 2 (principal: about x), nothing else */
static cd_model *spinning_box(double w, cd_stepper st, int principal)
{
    cd_model *m = cd_model_create();
    cd_target_desc t = cd_target_desc_default();
    cd_shape_desc s = cd_shape_desc_default();
    cd_error err;
    s.type = CD_SHAPE_BOX;
    t.mass = 500.0;
    t.inertia[0] = 100.0; t.inertia[4] = 150.0; t.inertia[8] = 200.0;
    if (principal) t.angvel[0] = w;
    else t.angvel[0] = t.angvel[2] = w / sqrt(2.0);
    t.shapes = &s;
    t.nshape = 1;
    cr_assert(cd_build_target(m, &t, &err) >= 0, "%s", err.msg);
    m->opt.stepper = st;
    cr_assert_eq(cd_model_finalize(m, &err), CD_OK, "%s", err.msg);
    return m;
}

/* the estimate is within a factor of 2 of the steps the stepper takes on a
 * tumbling box (torque-free rotation at 1000 rad/s for 0.05 s: 50 rad), and
 * 1 to 3 times them for a spin about a principal axis (steadier: larger steps) */
Test(build, spin_step_estimate_is_within_a_factor_of_two)
{
    const cd_stepper st[5] = {CD_STEP_RK8PD, CD_STEP_RKF45, CD_STEP_RKCK, CD_STEP_RK4IMP, CD_STEP_MSBDF};
    int i;
    for (i = 0; i < 5; i++) {
        cd_model *m = spinning_box(1000.0, st[i], 0), *p = spinning_box(1000.0, st[i], 1);
        cd_error err;
        cd_data *d = cd_data_create(m, 0, &err), *dp = cd_data_create(p, 0, &err);
        double w, est;
        cr_assert_not_null(d, "%s", err.msg);
        cr_assert_eq(cd_spin_steps(m, 0.05, &w, &est), 0);
        cr_expect_float_eq(w, 1000.0, 1e-9);
        cr_assert_eq(cd_sim_advance(m, d, 0.05, NULL, NULL, &err), CD_OK, "%s", err.msg);
        cr_expect(est > 0.5 * d->stats.nsteps && est < 2.0 * d->stats.nsteps, "%s: estimate %g, steps taken %ld",
                  cd_stepper_name(st[i]), est, d->stats.nsteps);
        cr_assert_not_null(dp);
        cr_assert_eq(cd_sim_advance(p, dp, 0.05, NULL, NULL, &err), CD_OK, "%s", err.msg);
        cr_expect(est >= 1.0 * dp->stats.nsteps && est < 3.0 * dp->stats.nsteps, "%s, principal axis: estimate %g, steps taken %ld",
                  cd_stepper_name(st[i]), est, dp->stats.nsteps);
        cd_data_free(d);
        cd_data_free(dp);
        cd_model_free(m);
        cd_model_free(p);
    }
    {   /* fixed steps: no estimate; at rest: none */
        cd_model *m = spinning_box(1000.0, CD_STEP_RK4_FIXED, 0), *r = spinning_box(0.0, CD_STEP_RK8PD, 0);
        cr_expect_eq(cd_spin_steps(m, 1.0, NULL, NULL), -1);
        cr_expect_eq(cd_spin_steps(r, 1.0, NULL, NULL), -1);
        cd_model_free(m);
        cd_model_free(r);
    }
}

/* `capdyn check` and `run` warn at 1e6 rad/s with the steps it will cost,
 * and go on (exit 0); a shipped tumbling scenario is not warned about */
Test(build, an_extreme_tumbling_rate_is_warned_about)
{
    char dir[512], shipped[1024], *out = NULL, *err = NULL;
    const char *check[] = {"check", "spin.toml", NULL};
    const char *run[] = {"run", "spin.toml", "-o", "spin.h5", "-q", "--set", "simulation.duration=0.05", "--set", "simulation.output_dt=0.05", NULL};
    const char *calm[] = {"check", shipped, NULL};
    int rc;
    lu_tmpdir(dir, sizeof dir);
    lu_write(dir, "spin.toml",
             "[simulation]\nduration = 1.0\n\n[[target]]\nname = \"sat\"\nmass = 500.0\ninertia = [100.0, 150.0, 200.0]\n"
             "angular_velocity = [1e6, 0.0, 0.0]\nshape = { type = \"box\", size = [1.7, 1.3, 0.8] }\n");
    rc = lu_capdyn(dir, &out, &err, check);
    cr_expect_eq(rc, 0, "%s", err);
    cr_expect(err && strstr(err, "warning: spin.toml: system 'sat' tumbles at 1e+06 rad/s") &&
                  strstr(err, "roughly 2.6e+06 integrator steps (auto at rtol 1e-09) for duration = 1 s"),
              "stderr: %s", err ? err : "(none)");
    free(out);
    free(err);
    rc = lu_capdyn(dir, &out, &err, run);
    cr_expect_eq(rc, 0, "%s", err);
    cr_expect(err && strstr(err, "tumbles at 1e+06 rad/s") && strstr(err, "roughly 1.3e+05 integrator steps"),
              "stderr (duration 0.05 s): %s", err ? err : "(none)");
    free(out);
    free(err);
    snprintf(shipped, sizeof shipped, "%s/scenarios/tumbling_target.toml", lu_root());
    if (shipped[0] != '/') { /* relative root: from the test's directory */
        char cwd[512];
        cr_assert_not_null(getcwd(cwd, sizeof cwd));
        snprintf(shipped, sizeof shipped, "%s/%s/scenarios/tumbling_target.toml", cwd, lu_root());
    }
    rc = lu_capdyn(dir, &out, &err, calm);
    cr_expect_eq(rc, 0, "%s", err);
    cr_expect(!err || !strstr(err, "warning"), "stderr: %s", err);
    free(out);
    free(err);
    lu_rm_rf(dir);
}

/* ---- a chaser: the shipped capture scenario, built in C ------------------- */

#include "../src/math/cd_math.h" /* cd_m3_from_rpy: the loader's rpy_deg */

/* scenarios/capture_handrail_tumbling.toml (the ETS-VII chaser and target,
 * a soft gripper of two finger pairs on the wrist, reaction wheels) built
 * with cd_build_chaser, cd_build_hand, cd_build_target: the same model,
 * entry for entry, and the same wheels in the controller's configuration */
Test(build, shipped_capture_scenario_equals_the_c_build)
{
    char path[1024];
    cd_error err;
    cd_scenario *sc;
    cd_model *m = cd_model_create();
    cd_chaser_desc c = cd_chaser_desc_default();
    cd_target_desc t = cd_target_desc_default();
    cd_hand_desc h = cd_hand_desc_default();
    cd_shape_desc bus = cd_shape_desc_default(), tshape[2];
    cd_link_desc arm[6];
    cd_joint_props jp[6];
    cd_contact_law law = cd_contact_law_default(), rule = cd_contact_law_from_rule(1e3, 10, 0.1, 1.0, 0.5);
    cd_ctrl_config cfg = cd_ctrl_config_default();
    cd_hand hand;
    /* name, axis, origin x, mass, com x, inertia diagonal, q0 [deg] */
    static const struct { const char *n; double ax[3], ox, mass, cx, I[3], q0; } L[6] = {
        {"shoulder_yaw", {0, 0, 1}, 1.0, 10.0, 0.075, {0.05, 0.05, 0.05}, 0},
        {"upper_arm", {0, 1, 0}, 0.15, 25.0, 0.45, {0.1, 1.69, 1.69}, -30.0},
        {"forearm", {0, 1, 0}, 0.9, 20.0, 0.45, {0.08, 1.35, 1.35}, 60.0},
        {"wrist_pitch", {0, 1, 0}, 0.9, 5.0, 0.05, {0.01, 0.01, 0.01}, -30.0},
        {"wrist_yaw", {0, 0, 1}, 0.1, 5.0, 0.05, {0.01, 0.01, 0.01}, 0},
        {"wrist_roll", {1, 0, 0}, 0.1, 6.0, 0.08, {0.02, 0.02, 0.02}, 0}};
    int chaser, tgt, i;
    snprintf(path, sizeof path, "%s/scenarios/capture_handrail_tumbling.toml", lu_root());
    sc = cd_scenario_load(path, NULL, 0, &err);
    cr_assert_not_null(sc, "%s", err.msg);
    m->opt.h_max = 1e-3; /* the [simulation] options are the scenario's, not the builders' */
    m->opt.stepper = CD_STEP_RK8PD;
    /* the chaser: a 2 m bus, the 6-joint arm with stops at +-170 deg, wheels of 1 N m */
    bus.type = CD_SHAPE_BOX;
    bus.size[0] = bus.size[1] = bus.size[2] = 2.0;
    for (i = 0; i < 6; i++) {
        arm[i] = cd_link_desc_default();
        arm[i].name = L[i].n;
        arm[i].parent = i - 1;
        memcpy(arm[i].axis, L[i].ax, sizeof arm[i].axis);
        arm[i].pos[0] = L[i].ox;
        arm[i].mass = L[i].mass;
        arm[i].com[0] = L[i].cx;
        memset(arm[i].inertia, 0, sizeof arm[i].inertia);
        arm[i].inertia[0] = L[i].I[0]; arm[i].inertia[4] = L[i].I[1]; arm[i].inertia[8] = L[i].I[2];
        arm[i].q0 = L[i].q0 * DEG;
        jp[i] = cd_joint_props_default();
        jp[i].limited = 1;
        jp[i].lower = -170.0 * DEG;
        jp[i].upper = 170.0 * DEG;
    }
    c.mass = 2540.0;
    c.inertia[0] = c.inertia[4] = c.inertia[8] = 1693.0;
    c.shapes = &bus;
    c.nshape = 1;
    c.arm = arm;
    c.arm_joint = jp;
    c.narm = 6;
    c.wheels = 1;
    c.wheel_kp = 2000.0; c.wheel_kd = 8000.0; c.wheel_torque = 1.0;
    chaser = cd_build_chaser(m, &c, &err);
    cr_assert(chaser >= 0, "%s", err.msg);
    /* the gripper on the wrist: two finger pairs, closed by the trigger */
    h.type = CD_HAND_SOFT;
    h.layout = CD_HAND_TWO_PAIRS;
    h.pair_offset = 0.06;
    h.attach_body = m->sys_body_adr[chaser] + 6;
    h.palm_size[2] = 0.16;
    h.palm_pos[0] = 0.12;
    cd_m3_from_rpy(h.palm_rot, 0.0 * DEG, 0.0 * DEG, -90.0 * DEG);
    h.link_length[1] = 0.07;
    h.link_mass[0] = 0.15; h.link_mass[1] = 0.1;
    h.checkpoint_spacing = 0.01;
    h.torque = 0.5;
    h.stall_torque = 0.5; h.noload_speed = 5.0;
    h.close_on_trigger = 1;
    h.joint_spring = 0.02; h.joint_damping = 0.005;
    h.joint_limited = 1;
    h.joint_lower[0] = h.joint_lower[1] = -5.0 * DEG;
    h.joint_upper[0] = h.joint_upper[1] = 120.0 * DEG;
    cr_assert(cd_build_hand(m, &h, &hand, &err) >= 0, "%s", err.msg);
    /* the 410 kg target tumbling at 3 deg/s, with its handrail */
    tshape[0] = cd_shape_desc_default();
    tshape[0].type = CD_SHAPE_BOX;
    tshape[0].size[0] = 1.6; tshape[0].size[1] = 1.4; tshape[0].size[2] = 1.2;
    tshape[1] = cd_shape_desc_default();
    tshape[1].type = CD_SHAPE_HANDRAIL;
    tshape[1].radius = 0.03; tshape[1].length = 0.3; tshape[1].height = 0.15; tshape[1].post = 0.06;
    tshape[1].pos[0] = -0.8; tshape[1].pos[2] = 0.2;
    cd_m3_from_rpy(tshape[1].rot, 0.0 * DEG, -90.0 * DEG, 0.0 * DEG);
    t.mass = 410.0;
    t.inertia[0] = 116.0; t.inertia[4] = 137.0; t.inertia[8] = 154.0;
    t.pos[0] = 4.1338; t.pos[1] = 0.005; t.pos[2] = -0.2;
    t.angvel[0] = 3.0 * DEG;
    t.shapes = tshape;
    t.nshape = 2;
    tgt = cd_build_target(m, &t, &err);
    cr_assert(tgt >= 0, "%s", err.msg);
    /* [contact]: the paper's rule, mu_max 0.5, mu 0.4 */
    law.K = rule.K; law.D = rule.D; law.Kt = law.K; law.Dt = law.D;
    law.mu_s = 0.5; law.mu_k = 0.4;
    {
        /* [gripper] finger_contact: Hunt-Crossley on the finger-on-finger
         * pairs (check points on a finger, the shape another finger of the
         * hand), K 1e4, D 7.37e4, D_t 63.25; the pairs against the target
         * keep [contact]'s law */
        cd_contact_law ff = law;
        int p0 = m->npair, p, lid, nff = 0;
        cr_assert_eq(cd_build_hand_drive(m, &h, &hand, &law, &tgt, 1, &err), CD_OK, "%s", err.msg);
        ff.damping = CD_DAMP_HUNT_CROSSLEY;
        ff.K = 1e4; ff.D = 7.37e4; ff.Kt = ff.K; ff.Dt = 63.25;
        lid = cd_model_add_law(m, &ff, &err);
        cr_assert(lid >= 0, "%s", err.msg);
        for (p = p0; p < m->npair; p++)
            if (m->pair_body[p] >= 0 && m->body_sys[m->shape_body[m->pair_shape[p]]] == hand.sys) {
                m->pair_law[p] = lid;
                nff++;
            }
        cr_assert_gt(nff, 0, "the two finger pairs can touch each other");
    }
    cr_assert_eq(cd_model_set_user_switches(m, 2, &err), CD_OK, "%s", err.msg); /* the controller's (detumble off) */
    cr_assert_eq(cd_model_finalize(m, &err), CD_OK, "%s", err.msg);
    cr_expect_eq(model_diff(m, sc->model), 0, "%d entries differ", bad);
    cr_expect_eq(m->nbody, 1 + 6 + 4 * 2 + 1, "bus, arm, four 2-link fingers, target");
    cr_expect_eq(m->nshape, 1 + 1 + 8 + 1 + 3, "bus, palm, finger capsules, target body, handrail");
    cd_chaser_wheels(&c, chaser, &cfg);
    cr_assert_not_null(sc->control);
    cr_expect_eq(sc->control->sys, cfg.sys);
    cr_expect_eq(sc->control->attitude, cfg.attitude);
    cr_expect_eq(sc->control->att_kp, cfg.att_kp);
    cr_expect_eq(sc->control->att_kd, cfg.att_kd);
    cr_expect_eq(sc->control->att_tau_max, cfg.att_tau_max);
    cr_expect_eq(sc->control->palm, hand.palm);
    cr_expect_eq(sc->control->nclose, hand.nact);
    cd_model_free(m);
    cd_scenario_free(sc);
}

/* issue 22 (b): a clutched hand whose coupling limit is not above the clutch
 * threshold is refused (the clutch load max_j tau_j is saturated at the
 * limit, so it would never reach the threshold and the clutch never fire) */
Test(build, a_clutch_torque_limit_below_the_threshold_is_refused)
{
    cd_model *m = cd_model_create();
    cd_hand_desc h = cd_hand_desc_default();
    cd_contact_law law = cd_contact_law_default();
    cd_hand hand;
    cd_error err;
    h.type = CD_HAND_SPACE;
    h.clutch_threshold = 0.05;
    h.torque_limit = 0.04;
    cr_assert(cd_build_hand(m, &h, &hand, &err) >= 0, "%s", err.msg);
    cr_expect_eq(cd_build_hand_drive(m, &h, &hand, &law, NULL, 0, &err), CD_EINVAL);
    cr_expect_str_eq(err.msg, "hand: the coupling torque limit 0.04 N m (torque_limit) must exceed the clutch threshold "
                              "0.05 N m, or the clutch never disengages");
    cd_model_free(m);
    /* the motor's stall torque is the limit when torque_limit is 0 */
    m = cd_model_create();
    h.torque_limit = 0;
    h.stall_torque = 0.05;
    cr_assert(cd_build_hand(m, &h, &hand, &err) >= 0, "%s", err.msg);
    cr_expect_eq(cd_build_hand_drive(m, &h, &hand, &law, NULL, 0, &err), CD_EINVAL);
    cr_expect_str_eq(err.msg, "hand: the coupling torque limit 0.05 N m (the motor's stall torque) must exceed the clutch "
                              "threshold 0.05 N m, or the clutch never disengages");
    cd_model_free(m);
    /* just above: accepted */
    m = cd_model_create();
    h.stall_torque = 0.051;
    cr_assert(cd_build_hand(m, &h, &hand, &err) >= 0, "%s", err.msg);
    cr_expect_eq(cd_build_hand_drive(m, &h, &hand, &law, NULL, 0, &err), CD_OK, "%s", err.msg);
    cd_model_free(m);
}
