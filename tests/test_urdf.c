/* URDF import (src/io/urdf.cpp, docs/urdf.md; issue 25): the mapping onto
 * capdyn's model (fixed joints merged, the base frame at the root's CoM,
 * check points, overrides by joint name), the capture chaser imported from
 * URDF equal to the TOML one, and the refusals with the element and its
 * line. The dynamics against Pinocchio are in
 * python/tests/test_urdf_pinocchio.py; bad_inputs 95-99 cover five more
 * refusals through the CLI. */
#include "loader_util.h"

#include "capdyn/sim.h"

#include <math.h>

/* a scenario text (URDF paths absolute, from CAPDYN_ROOT) loaded; NULL with
 * err filled on failure */
static cd_scenario *load_urdf_text(const char *text, cd_error *err)
{
    char dir[512], path[600];
    cd_scenario *sc;
    lu_tmpdir(dir, sizeof dir);
    lu_write(dir, "s.toml", "%s", text);
    snprintf(path, sizeof path, "%s/s.toml", dir);
    sc = cd_scenario_load(path, NULL, 0, err);
    lu_rm_rf(dir);
    return sc;
}

static char *urdf_path(const char *name)
{
    static char buf[4][1024];
    static int k;
    k = (k + 1) % 4;
    snprintf(buf[k], sizeof buf[k], "%s/tests/urdf/%s", lu_root(), name);
    return buf[k];
}

static cd_scenario *load_system(const char *urdf, const char *extra, cd_error *err)
{
    char text[4096];
    snprintf(text, sizeof text,
             "[simulation]\nduration = 0.1\ngravity = [0.0, 0.0, 0.0]\n\n[[system]]\nname = \"robot\"\nurdf = \"%s\"\n%s",
             urdf_path(urdf), extra ? extra : "");
    return load_urdf_text(text, err);
}

/* the message after the scenario's location prefix "FILE:L:C: key 'system[0].urdf': " */
static const char *after_key(const char *msg)
{
    const char *p = strstr(msg, "key 'system[0].urdf': ");
    return p ? p + strlen("key 'system[0].urdf': ") : msg;
}

static int close_rel(double a, double b, double tol) { return fabs(a - b) <= tol * fmax(1.0, fmax(fabs(a), fabs(b))); }

Test(urdf, capture_chaser_from_urdf_equals_the_toml_chaser)
{
    char p1[1024], p2[1024];
    cd_error err;
    cd_scenario *a, *b;
    const cd_model *ma, *mb;
    int i, k;
    snprintf(p1, sizeof p1, "%s/scenarios/capture_handrail_tumbling.toml", lu_root());
    snprintf(p2, sizeof p2, "%s/scenarios/capture_urdf_arm.toml", lu_root());
    a = cd_scenario_load(p1, NULL, 0, &err);
    cr_assert_not_null(a, "%s", err.msg);
    b = cd_scenario_load(p2, NULL, 0, &err); /* its urdf path is relative to the scenario file */
    cr_assert_not_null(b, "%s", err.msg);
    ma = a->model;
    mb = b->model;
    cr_assert_eq(ma->nbody, mb->nbody);
    cr_assert_eq(ma->ncp, mb->ncp);
    cr_assert_eq(ma->nshape, mb->nshape);
    cr_assert_eq(ma->nslot, mb->nslot);
    cr_assert_eq(ma->nlim, mb->nlim);
    cr_assert_eq(ma->ny, mb->ny);
    for (i = 0; i < ma->nbody; i++) {
        cr_expect_eq(ma->body_parent[i], mb->body_parent[i], "body %d", i);
        cr_expect_eq(ma->body_jnt_type[i], mb->body_jnt_type[i], "body %d", i);
        cr_expect(close_rel(ma->body_mass[i], mb->body_mass[i], 1e-15), "body %d mass", i);
        cr_expect(close_rel(ma->body_q0[i], mb->body_q0[i], 1e-15), "body %d q0 %g %g", i, ma->body_q0[i], mb->body_q0[i]);
        for (k = 0; k < 3; k++) {
            cr_expect(close_rel(ma->body_jnt_pos[3 * i + k], mb->body_jnt_pos[3 * i + k], 1e-15), "body %d joint pos", i);
            cr_expect(close_rel(ma->body_axis[3 * i + k], mb->body_axis[3 * i + k], 1e-15), "body %d axis", i);
            cr_expect(close_rel(ma->body_com[3 * i + k], mb->body_com[3 * i + k], 1e-15), "body %d com", i);
        }
        for (k = 0; k < 9; k++) {
            cr_expect(close_rel(ma->body_inertia[9 * i + k], mb->body_inertia[9 * i + k], 1e-15), "body %d inertia", i);
            cr_expect(close_rel(ma->body_jnt_rot[9 * i + k], mb->body_jnt_rot[9 * i + k], 1e-15), "body %d rot", i);
        }
        for (k = 0; k < 2; k++)
            cr_expect(close_rel(ma->body_limit[6 * i + k], mb->body_limit[6 * i + k], 1e-15), "body %d limit", i);
    }
    cr_expect_str_eq(a->imported, "");
    cr_expect(strstr(b->imported, "body upper_arm        joint upper_arm_joint    revolute   <- shoulder_yaw   mass 25 kg, "
                                  "limits [-2.96706, 2.96706] rad\n") != NULL, "%s", b->imported);
    cd_scenario_free(a);
    cd_scenario_free(b);
}

Test(urdf, fixed_joints_merge_mass_and_shapes_into_the_parent)
{
    cd_error err;
    cd_scenario *sc = load_system("hand.urdf", NULL, &err);
    const cd_model *m;
    double total = 0.0;
    int i, mesh = -1;
    cr_assert_not_null(sc, "%s", err.msg);
    m = sc->model;
    /* palm + 3 fingers x 2 moving links; mounts, pads, tool frame merged */
    cr_assert_eq(m->nbody, 7);
    for (i = 0; i < m->nbody; i++) total += m->body_mass[i];
    /* the URDF's masses: palm 1.5, per finger mount 0.05, l1 0.05, l2 0.03, pad 0.01 */
    cr_expect(fabs(total - (1.5 + 3 * (0.05 + 0.05 + 0.03 + 0.01))) <= 1e-12, "total %.17g", total);
    cr_expect(fabs(m->body_mass[0] - 1.65) <= 1e-12, "palm %.17g", m->body_mass[0]);
    cr_expect(fabs(m->body_mass[2] - 0.04) <= 1e-12, "f0_l2 + pad %.17g", m->body_mass[2]);
    /* shapes: the palm's mesh, 2 cylinders and the pad's sphere per finger */
    cr_assert_eq(m->nshape, 10);
    for (i = 0; i < m->nshape; i++)
        if (m->shape_type[i] == CD_SHAPE_CONVEX) mesh = i;
    cr_assert_geq(mesh, 0);
    cr_expect_eq(m->shape_vert_num[mesh], 8, "a box mesh hulls to its 8 corners");
    cr_expect_str_eq(sc->warnings, "");
    cd_scenario_free(sc);
}

Test(urdf, base_frame_is_the_root_com_and_inertia_is_rotated)
{
    cd_error err;
    cd_scenario *sc = load_system("arm7.urdf", "position = [0.1, 0.2, 0.3]\n", &err);
    const cd_model *m;
    const double *I;
    double tr;
    cr_assert_not_null(sc, "%s", err.msg);
    m = sc->model;
    /* the root link's <inertial> origin (0.05, -0.02, 0.03), identity pose */
    cr_expect(fabs(m->sys_pos0[0] - 0.15) <= 1e-15 && fabs(m->sys_pos0[1] - 0.18) <= 1e-15 && fabs(m->sys_pos0[2] - 0.33) <= 1e-15,
              "base CoM (%g, %g, %g)", m->sys_pos0[0], m->sys_pos0[1], m->sys_pos0[2]);
    /* the link on the base: its joint origin (0.4, 0, 0.25) from the root frame, so from the CoM */
    cr_expect(fabs(m->body_jnt_pos[3] - 0.35) <= 1e-15 && fabs(m->body_jnt_pos[4] - 0.02) <= 1e-15 &&
              fabs(m->body_jnt_pos[5] - 0.22) <= 1e-15);
    /* the inertial's rpy turns the inertia: trace and symmetry kept, products appear */
    I = m->body_inertia;
    tr = I[0] + I[4] + I[8];
    cr_expect(fabs(tr - 45.0) <= 1e-12, "trace %.17g", tr);
    cr_expect(fabs(I[1] - I[3]) <= 1e-15 && fabs(I[2] - I[6]) <= 1e-15 && fabs(I[5] - I[7]) <= 1e-15);
    cr_expect(fabs(I[1] - 0.5) > 0.1, "ixy %.6g: the rotation moved it", I[1]);
    /* limits -> stops: 6 limited joints (j4 is continuous) */
    cr_expect_eq(m->nlim, 6);
    cd_scenario_free(sc);
    sc = load_system("arm7.urdf", "ignore_limits = true\n", &err);
    cr_assert_not_null(sc, "%s", err.msg);
    cr_expect_eq(sc->model->nlim, 0);
    cr_expect(strstr(sc->imported, "link1            joint j1") && strstr(sc->imported, "limits ignored"), "%s", sc->imported);
    cd_scenario_free(sc);
}

Test(urdf, joint_overrides_by_name)
{
    cd_error err;
    cd_scenario *sc = load_system("arm7.urdf",
                                  "\n[[system.joint]]\nname = \"j2\"\nq0_deg = 30.0\nspring = { stiffness = 5.0 }\n"
                                  "\n[[system.joint]]\nname = \"j5\"\nq0 = 0.05\nlimit = [-0.05, 0.1]\n"
                                  "actuator = { type = \"constant\", tau = 1.0 }\n",
                                  &err);
    const cd_model *m;
    int b2, b5;
    cr_assert_not_null(sc, "%s", err.msg);
    m = sc->model;
    b2 = cd_model_body_id(m, "robot/link2");
    b5 = cd_model_body_id(m, "robot/link5");
    cr_assert(b2 > 0 && b5 > 0);
    cr_expect(fabs(m->body_q0[b2] - 30.0 * M_PI / 180.0) <= 1e-15);
    cr_expect_eq(m->body_spring[2 * b2], 5.0);
    cr_expect_eq(m->body_lim_id[b2] >= 0, 1, "the URDF limit stays a stop");
    cr_expect(fabs(m->body_limit[6 * b2 + 1] - 2.0) <= 1e-15, "upper %.17g", m->body_limit[6 * b2 + 1]);
    cr_expect_eq(m->body_q0[b5], 0.05);
    cr_expect_eq(m->body_limit[6 * b5], -0.05);
    cr_expect_eq(m->body_limit[6 * b5 + 1], 0.1);
    cr_expect_eq(m->nu, 1);
    cd_scenario_free(sc);

    sc = load_system("arm7.urdf", "\n[[system.joint]]\nname = \"j9\"\nq0_deg = 1.0\n", &err);
    cr_assert_null(sc);
    cr_expect(strstr(err.msg, ":10:8: key 'system[0].joint[0].name': expected the name of a joint of '") &&
                  strstr(err.msg, "arm7.urdf', got 'j9'"), "%s", err.msg);
    sc = load_system("arm7.urdf", "\n[[system.joint]]\nname = \"flange_mount\"\nspring = { stiffness = 1.0 }\n", &err);
    cr_assert_null(sc);
    cr_expect(strstr(err.msg, "key 'system[0].joint[0].name': expected a moving joint, got 'flange_mount' (a fixed joint: "
                              "its link is merged into its parent)"), "%s", err.msg);
    sc = load_system("arm7.urdf", "\n[[system.joint]]\nname = \"j1\"\nq0_deg = 170.0\n", &err);
    cr_assert_null(sc);
    cr_expect(strstr(err.msg, "arm7.urdf:26: <joint name=\"j1\">: initial position 2.96706 outside its <limit> [-2.9, 2.9]"), "%s", err.msg);
}

Test(urdf, checkpoints_along_links_every_spacing)
{
    cd_error err;
    cd_scenario *sc = load_system("chaser.urdf", "checkpoint_spacing = 0.1\ncheckpoint_radius = 0.01\n", &err);
    const cd_model *m;
    int b, i, n = 0, last = -1;
    cr_assert_not_null(sc, "%s", err.msg);
    m = sc->model;
    b = cd_model_body_id(m, "robot/upper_arm");
    /* upper_arm: joint to the forearm's joint 0.9 m along x: 9 intervals, 10 points */
    for (i = 0; i < m->ncp; i++)
        if (m->cp_body[i] == b) {
            cr_expect(fabs(m->cp_pos[3 * i] - 0.1 * n) <= 1e-15 && m->cp_pos[3 * i + 1] == 0.0 && m->cp_radius[i] == 0.01,
                      "point %d at x = %.17g", n, m->cp_pos[3 * i]);
            n++;
            last = i;
        }
    cr_expect_eq(n, 10);
    cr_expect(last >= 0 && fabs(m->cp_pos[3 * last] - 0.9) <= 1e-15);
    /* wrist_roll (no child): to twice its CoM, 0.16 m: 2 intervals, 3 points; base: none */
    b = cd_model_body_id(m, "robot/wrist_roll");
    for (i = 0, n = 0; i < m->ncp; i++) n += m->cp_body[i] == b;
    cr_expect_eq(n, 3);
    for (i = 0, n = 0; i < m->ncp; i++) n += m->cp_body[i] == m->sys_body_adr[0];
    cr_expect_eq(n, 0);
    cd_scenario_free(sc);
}

Test(urdf, refused_elements_name_the_element_and_its_line)
{
    static const struct {
        const char *file, *want;
    } cases[] = {
        {"bad/floating.urdf", "floating.urdf:18: <joint name=\"j1\">: type 'floating' is refused (capdyn imports revolute, "
                              "continuous, prismatic and fixed joints; a free root is [[system]] base = \"free\")"},
        {"bad/mimic.urdf", "mimic.urdf:31: <joint name=\"j2\">: <mimic> is refused (a joint coupled to another; capdyn "
                           "joints are independent: couple them with an actuator's transmission instead)"},
        {"bad/missing_mesh.urdf", "missing_mesh.urdf:4: <link name=\"base\">: <collision> 1: cannot read mesh file '"},
        {"bad/cycle.urdf", "cycle.urdf:37: <joint name=\"j2\">: link 'a' already has the parent joint 'j0' (line 25): a "
                           "kinematic loop, refused (a capdyn system is a tree)"},
        {"bad/missing_inertial.urdf", "missing_inertial.urdf:11: <link name=\"l1\">: no <inertial> with a positive mass "
                                      "(on this moving link or a link fixed to it); capdyn bodies need a mass > 0"},
    };
    size_t i;
    for (i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        cd_error err;
        cd_scenario *sc = load_system(cases[i].file, NULL, &err);
        cr_expect_null(sc, "%s", cases[i].file);
        cd_scenario_free(sc);
        cr_expect(strstr(after_key(err.msg), cases[i].want) != NULL, "%s:\n  got  %s\n  want ...%s", cases[i].file,
                  err.msg, cases[i].want);
        cr_expect_eq(err.status, strstr(cases[i].file, "mesh") ? CD_EIO : CD_EINVAL, "%s", cases[i].file);
    }
}

Test(urdf, nonconvex_mesh_is_hulled_with_a_warning)
{
    cd_error err;
    cd_scenario *sc = load_system("bad/nonconvex_mesh.urdf", NULL, &err);
    const char *want = "nonconvex_mesh.urdf:4: <link name=\"base\">: <collision> 1: mesh 'star.obj' is not convex (2 of 8 "
                       "vertices inside its hull): replaced by its convex hull (6 vertices)\n";
    cr_assert_not_null(sc, "%s", err.msg);
    cr_expect(strlen(sc->warnings) > strlen(want) && strcmp(sc->warnings + strlen(sc->warnings) - strlen(want), want) == 0,
              "%s", sc->warnings);
    cr_assert_eq(sc->model->nshape, 1);
    cr_expect_eq(sc->model->shape_vert_num[0], 6, "the octahedron's tips");
    cd_scenario_free(sc);
}

Test(urdf, c_api_reads_builds_and_refuses)
{
    cd_error err;
    cd_urdf *u = cd_urdf_read(urdf_path("arm7.urdf"), &err);
    cd_model *m = cd_model_create();
    cd_urdf_opts o = cd_urdf_opts_default();
    int sys;
    cr_assert_not_null(u, "%s", err.msg);
    cr_expect_str_eq(cd_urdf_robot_name(u), "arm7");
    cr_expect_eq(cd_urdf_njoint(u), 8);
    o.fixed = 1;
    sys = cd_urdf_build(u, m, &o, &err);
    cr_assert_eq(sys, 0, "%s", err.msg);
    cr_expect_eq(m->sys_nbody[0], 8);
    cr_expect_eq(m->sys_base_type[0], CD_BASE_FIXED);
    cr_expect_eq(cd_urdf_joint_body(u, m, sys, "j7"), 7);
    cr_expect_eq(cd_urdf_joint_body(u, m, sys, "flange_mount"), -2);
    cr_expect_eq(cd_urdf_joint_body(u, m, sys, "nope"), -1);
    cr_expect_eq(cd_model_finalize(m, &err), CD_OK, "%s", err.msg);
    /* NULL arguments, the documented way (docs/embedding.md, "NULL arguments") */
    cr_expect_eq(cd_urdf_build(NULL, m, &o, &err), -1);
    cr_expect(err.status == CD_EINVAL && strstr(err.msg, "cd_urdf_build: the URDF is NULL"), "%s", err.msg);
    cr_expect_eq(cd_urdf_build(u, NULL, &o, NULL), -1);
    cr_expect_eq(cd_urdf_build(u, m, NULL, NULL), -1);
    cr_expect_null(cd_urdf_read(NULL, &err));
    cr_expect(err.status == CD_EINVAL && strstr(err.msg, "cd_urdf_read: the path is NULL"), "%s", err.msg);
    cr_expect_null(cd_urdf_warnings(NULL));
    cr_expect_null(cd_urdf_robot_name(NULL));
    cr_expect_null(cd_urdf_describe(NULL, m, 0));
    cr_expect_null(cd_urdf_describe(u, NULL, 0));
    cr_expect_eq(cd_urdf_njoint(NULL), 0);
    cr_expect_eq(cd_urdf_joint_index(NULL, "j1"), -1);
    cr_expect_eq(cd_urdf_joint_index(u, NULL), -1);
    cr_expect_eq(cd_urdf_joint_index(u, "j7"), 7);
    /* shapes: one <collision> per link, named after it; the flange's on link7 */
    cr_expect_eq(cd_urdf_nshape(u), 9);
    cr_expect_str_eq(cd_urdf_shape_name(u, 0), "base");
    cr_expect_str_eq(cd_urdf_shape_name(u, 7), "link7");
    cr_expect_str_eq(cd_urdf_shape_name(u, 8), "flange");
    cr_expect_null(cd_urdf_shape_name(u, 9));
    cr_expect_null(cd_urdf_shape_name(NULL, 0));
    cr_expect_eq(cd_urdf_nshape(NULL), 0);
    cr_expect_eq(cd_urdf_joint_body(NULL, m, 0, "j1"), -1);
    cr_expect_eq(cd_urdf_joint_body(u, NULL, 0, "j1"), -1);
    cd_model_free(m);
    cd_urdf_free(u);
    cd_urdf_free(NULL);
    cr_expect_null(cd_urdf_read("/nonexistent/x.urdf", &err));
    cr_expect_eq(err.status, CD_EIO);
    cr_expect_str_eq(err.msg, "/nonexistent/x.urdf: cannot read the URDF file: No such file or directory");
}

/* urdfdom's own error (it logs through console_bridge) comes back as the one
 * line of the CLI, with the line of the value it quotes: nothing else on stderr */
Test(urdf, urdfdom_errors_are_captured_into_one_line)
{
    char dir[512], *out = NULL, *errs = NULL;
    const char *args[] = {"check", "s.toml", NULL};
    int rc;
    lu_tmpdir(dir, sizeof dir);
    lu_write(dir, "s.toml", "[simulation]\nduration = 0.1\n\n[[system]]\nname = \"r\"\nurdf = \"%s\"\n",
             urdf_path("bad/mass_not_a_number.urdf"));
    rc = lu_capdyn(dir, &out, &errs, args);
    cr_expect_eq(rc, 1);
    cr_expect_str_eq(out, "");
    cr_expect(errs && strstr(errs, "mass_not_a_number.urdf:14: URDF parse error (urdfdom): Inertial: mass [abc] is not a float\n") &&
                  strchr(errs, '\n') == errs + strlen(errs) - 1,
              "%s", errs ? errs : "(null)");
    free(out);
    free(errs);
    lu_rm_rf(dir);
}

/* scenarios/capture_urdf_arm.toml runs its capture to the verdict of the
 * TOML chaser's run (capture_handrail_tumbling.toml: captured at 4.19 s; 4.17 s before the bristle slip law of docs/contact.md) */
Test(urdf, capture_with_the_urdf_chaser_is_captured, .timeout = 300)
{
    char dir[512], scen[1024], *out = NULL, *errs = NULL;
    const char *args[] = {"run", scen, "-o", "out.h5", NULL};
    int rc;
    snprintf(scen, sizeof scen, "%s/scenarios/capture_urdf_arm.toml", lu_root());
    lu_tmpdir(dir, sizeof dir);
    rc = lu_capdyn(dir, &out, &errs, args);
    cr_expect_eq(rc, 0, "%s", errs ? errs : "");
    cr_expect(out && strstr(out, "capture     captured at t = 4.19 s"), "%s", out ? out : "(null)");
    free(out);
    free(errs);
    lu_rm_rf(dir);
}

/* a [[pair]] names an imported shape "system/LINK" */
Test(urdf, pairs_name_imported_shapes_by_link)
{
    cd_error err;
    cd_scenario *sc = load_system("arm7.urdf",
                                  "\n[[system]]\nname = \"ball\"\nmass = 1.0\ninertia = [0.01, 0.01, 0.01]\n"
                                  "position = [2.0, 0.0, 0.0]\ncheckpoints = [[0.0, 0.0, 0.0, 0.05]]\n"
                                  "\n[[pair]]\ncheckpoints = \"ball\"\nshape = \"robot/link3\"\n"
                                  "\n[[pair]]\ncheckpoints = \"ball\"\nshape = \"robot/flange\"\n",
                                  &err);
    const cd_model *m;
    cr_assert_not_null(sc, "%s", err.msg);
    m = sc->model;
    cr_assert_eq(m->nslot, 2);
    cr_expect_eq(m->shape_body[m->slot_shape[0]], cd_model_body_id(m, "robot/link3"));
    cr_expect_eq(m->shape_body[m->slot_shape[1]], cd_model_body_id(m, "robot/link7"), "the flange is merged into link7");
    cr_expect_eq(m->shape_type[m->slot_shape[1]], CD_SHAPE_SPHERE);
    cd_scenario_free(sc);
}
