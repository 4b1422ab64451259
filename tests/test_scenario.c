/* Tests of the TOML scenario loader (src/io/scenario.cpp, docs/scenario-format.md).
 *
 * Fixtures live in tests/data/scenarios/ and the shipped scenarios in
 * scenarios/, both found from $CAPDYN_ROOT (default "."; the Makefile runs
 * the tests from the repository root).
 *
 * - one test per rejection rule: the message names the file, the line and
 *   column, the key path and what was expected (asserted as substrings; the
 *   line:column values are those of the fixture files);
 * - a round trip of every documented key: all_keys.toml sets each key once and
 *   the resulting cd_model fields are compared numerically (values are either
 *   copied, so compared to 1e-15 relative, or computed from degrees/halves, so
 *   compared to 1e-12);
 * - include and --set semantics;
 * - every file in scenarios/ loads, and its stated geometry/parameters hold. */
#include <criterion/criterion.h>

#include "capdyn/io.h"
#include "capdyn/sim.h"

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* the actuator cd_model_set_actuator made for joint body b (CD_ACT_NONE: none) */
#define ACT_TYPE(m, b) ((m)->body_act[b] >= 0 ? (m)->act_type[(m)->body_act[b]] : CD_ACT_NONE)
#define ACT_PRM(m, b) ((m)->act_prm + 4 * (m)->body_act[b])

#define PI 3.14159265358979323846
#define DEG (PI / 180.0)

static const char *root_dir(void)
{
    const char *r = getenv("CAPDYN_ROOT");
    return (r && *r) ? r : ".";
}

static const char *fixture(const char *name)
{
    static char buf[4096];
    snprintf(buf, sizeof buf, "%s/tests/data/scenarios/%s", root_dir(), name);
    return buf;
}

static cd_scenario *load_ok(const char *name, const char *const *ov, int nov)
{
    cd_error err;
    cd_scenario *sc = cd_scenario_load(fixture(name), ov, nov, &err);
    cr_assert_not_null(sc, "%s should load, got: %s", name, err.msg);
    cr_assert_eq(err.status, CD_OK);
    return sc;
}

/* Loads a fixture that must fail with status st and a message containing
 * every string of subs (NULL-terminated). */
static void expect_fail_ov(const char *name, const char *const *ov, int nov, cd_status st, const char *const *subs)
{
    cd_error err;
    cd_scenario *sc;
    int i;
    memset(&err, 0, sizeof err);
    sc = cd_scenario_load(fixture(name), ov, nov, &err);
    cr_assert_null(sc, "%s should be rejected", name);
    cr_assert_eq(err.status, st, "%s: status %d, expected %d (%s)", name, err.status, st, err.msg);
    for (i = 0; subs[i]; i++)
        cr_assert(strstr(err.msg, subs[i]) != NULL, "%s: message lacks \"%s\":\n  %s", name, subs[i], err.msg);
}
static void expect_fail(const char *name, cd_status st, const char *const *subs)
{
    expect_fail_ov(name, NULL, 0, st, subs);
}

#define SUBS(...) ((const char *const[]){__VA_ARGS__, NULL})

/* relative comparison helpers */
static void near(double got, double want, double rtol, const char *what)
{
    double tol = rtol * (fabs(want) > 1 ? fabs(want) : 1.0);
    cr_assert(fabs(got - want) <= tol, "%s: got %.17g, want %.17g (tol %g)", what, got, want, tol);
}
static void near_n(const double *got, const double *want, int n, double rtol, const char *what)
{
    int i;
    char buf[128];
    for (i = 0; i < n; i++) {
        snprintf(buf, sizeof buf, "%s[%d]", what, i);
        near(got[i], want[i], rtol, buf);
    }
}

/* ==== rejection rules: one test each ====================================== */

Test(scenario_reject, unreadable_main_file)
{
    expect_fail("does_not_exist.toml", CD_EIO, SUBS("cannot read scenario file", "does_not_exist.toml", "No such file"));
}

Test(scenario_reject, toml_syntax_error)
{
    expect_fail("bad_syntax.toml", CD_EINVAL, SUBS("bad_syntax.toml:3:22: ", "TOML syntax error"));
}

Test(scenario_reject, unknown_key_with_suggestion)
{
    expect_fail("bad_unknown_key.toml", CD_EINVAL,
                SUBS("bad_unknown_key.toml:6:1: key 'system[0].mas': unknown key", "did you mean 'mass'?"));
}

Test(scenario_reject, unknown_top_level_table)
{
    expect_fail("bad_unknown_top.toml", CD_EINVAL,
                SUBS("bad_unknown_top.toml:3:2: key 'simulaton': unknown key", "did you mean 'simulation'?"));
}

Test(scenario_reject, wrong_type)
{
    expect_fail("bad_type.toml", CD_EINVAL,
                SUBS("bad_type.toml:2:12: key 'simulation.duration': expected a positive number, got 'long'"));
}

Test(scenario_reject, nan_literal)
{
    expect_fail("bad_nan.toml", CD_EINVAL,
                SUBS("bad_nan.toml:3:17: key 'simulation.gravity[1]': expected a finite number, got nan"));
}

Test(scenario_reject, inf_literal)
{
    expect_fail("bad_inf.toml", CD_EINVAL, SUBS("bad_inf.toml:6:8: key 'system[0].mass': expected a positive number, got inf"));
}

Test(scenario_reject, negative_link_mass)
{
    /* the exact form of issue 4 */
    expect_fail("bad_mass_negative.toml", CD_EINVAL,
                SUBS("bad_mass_negative.toml:18:10: key 'system[0].link[2].mass': expected a positive number, got -1"));
}

Test(scenario_reject, zero_mass)
{
    expect_fail("bad_mass_zero.toml", CD_EINVAL,
                SUBS("bad_mass_zero.toml:6:8: key 'system[0].mass': expected a positive number, got 0"));
}

Test(scenario_reject, inertia_not_positive_definite)
{
    /* [[1,2,0],[2,1,0],[0,0,1]] has eigenvalues 3, 1, -1 */
    expect_fail("bad_inertia_pd.toml", CD_EINVAL,
                SUBS("bad_inertia_pd.toml:7:11: key 'system[0].inertia': expected a positive definite inertia",
                     "(3, 1, -1)"));
}

Test(scenario_reject, inertia_triangle_inequality)
{
    /* 1 + 1 < 3: no mass distribution has these principal moments */
    expect_fail("bad_inertia_triangle.toml", CD_EINVAL,
                SUBS("bad_inertia_triangle.toml:7:11: key 'system[0].inertia'", "triangle inequality", "(1, 1, 3)"));
}

Test(scenario_reject, inertia_not_symmetric)
{
    expect_fail("bad_inertia_asym.toml", CD_EINVAL,
                SUBS("bad_inertia_asym.toml:7:11: key 'system[0].inertia': expected a symmetric inertia matrix"));
}

Test(scenario_reject, missing_required_key_in_table)
{
    /* located at the [simulation] header */
    expect_fail("bad_missing_duration.toml", CD_EINVAL,
                SUBS("bad_missing_duration.toml:1:1: key 'simulation.duration': missing required key",
                     "expected a positive number"));
}

Test(scenario_reject, missing_required_key_in_array_of_tables)
{
    expect_fail("bad_missing_mass.toml", CD_EINVAL,
                SUBS("bad_missing_mass.toml:4:1: key 'system[0].mass': missing required key"));
}

Test(scenario_reject, no_system_at_all)
{
    expect_fail("bad_no_system.toml", CD_EINVAL,
                SUBS("bad_no_system.toml:1:1: key 'system': missing required key", "[[system]] or [[target]]"));
}

Test(scenario_reject, unknown_parent)
{
    expect_fail("bad_parent.toml", CD_EINVAL,
                SUBS("bad_parent.toml:14:12: key 'system[0].link[1].parent'", "got 'uper'", "did you mean 'upper'?"));
}

Test(scenario_reject, unknown_shape_in_pair)
{
    expect_fail("bad_pair_shape.toml", CD_EINVAL,
                SUBS("bad_pair_shape.toml:19:9: key 'pair[0].shape'", "has no shape 'grond'", "did you mean 'ground'?"));
}

Test(scenario_reject, unknown_system_in_pair)
{
    expect_fail("bad_pair_system.toml", CD_EINVAL,
                SUBS("bad_pair_system.toml:18:15: key 'pair[0].checkpoints'", "no system 'bal'", "did you mean 'ball'?"));
}

Test(scenario_reject, pair_without_checkpoints)
{
    expect_fail("bad_no_checkpoints.toml", CD_EINVAL,
                SUBS("bad_no_checkpoints.toml:17:15: key 'pair[0].checkpoints'", "which has none"));
}

Test(scenario_reject, unknown_integrator)
{
    expect_fail("bad_integrator.toml", CD_EINVAL,
                SUBS("bad_integrator.toml:3:14: key 'simulation.integrator'", "got 'rk45'", "did you mean 'rkf45'?"));
}

Test(scenario_reject, missing_include_file)
{
    expect_fail("bad_include_missing.toml", CD_EIO,
                SUBS("bad_include_missing.toml:2:28: key 'include[1]': cannot read included file", "no_such_file.toml"));
}

Test(scenario_reject, include_of_a_device_does_not_hang, .timeout = 10)
{
    /* /dev/zero never ends: reading it hung the loader (and `capdyn check`).
     * Only regular files are read; the error names the include entry. A
     * hang is caught by the timeout. */
    expect_fail("bad_include_device.toml", CD_EIO,
                SUBS("bad_include_device.toml:2:28: key 'include[1]': cannot read included file '/dev/zero'",
                     "not a regular file (a character device)"));
}

Test(scenario_reject, include_of_a_directory)
{
    expect_fail("bad_include_dir.toml", CD_EIO,
                SUBS("bad_include_dir.toml:2:11: key 'include': cannot read included file", "not a regular file (a directory)"));
}

Test(scenario_reject, main_file_must_be_a_regular_file, .timeout = 10)
{
    cd_error err;
    cd_scenario *sc = cd_scenario_load("/dev/zero", NULL, 0, &err);
    cr_assert_null(sc);
    cr_expect_eq(err.status, CD_EIO);
    cr_expect(strstr(err.msg, "cannot read scenario file '/dev/zero': not a regular file (a character device)"),
              "message: %s", err.msg);
}

Test(scenario_reject, file_larger_than_16_MiB, .timeout = 10)
{
    /* A sparse 17 MiB file: refused from its size (stat), before reading. */
    char path[256], inc[512];
    FILE *f;
    cd_error err;
    cd_scenario *sc;
    snprintf(path, sizeof path, "/tmp/capdyn_test_scenario_big_%ld.toml", (long)getpid());
    f = fopen(path, "wb");
    cr_assert_not_null(f);
    cr_assert_eq(fseek(f, 17L << 20, SEEK_SET), 0);
    cr_assert_eq(fputc('\n', f), '\n');
    fclose(f);
    sc = cd_scenario_load(path, NULL, 0, &err);
    cr_expect_null(sc);
    cr_expect_eq(err.status, CD_EIO);
    cr_expect(strstr(err.msg, "more than the 16 MiB a scenario file may have") != NULL, "message: %s", err.msg);
    /* the same file as an include: located at the include entry */
    snprintf(inc, sizeof inc, "/tmp/capdyn_test_scenario_inc_%ld.toml", (long)getpid());
    f = fopen(inc, "w");
    cr_assert_not_null(f);
    fprintf(f, "include = \"%s\"\n", path);
    fclose(f);
    sc = cd_scenario_load(inc, NULL, 0, &err);
    cr_expect_null(sc);
    cr_expect(strstr(err.msg, ":1:11: key 'include': cannot read included file") &&
                  strstr(err.msg, "more than the 16 MiB"),
              "message: %s", err.msg);
    remove(path);
    remove(inc);
}

Test(scenario_reject, more_than_1e9_samples)
{
    /* duration / output_dt = 4e300 made (long)ceil(...) in the CLI undefined
     * (the run then "finished" at t = 0 with exit 0): the loader refuses
     * more than 1e9 samples, naming output_dt and its allowed range. */
    expect_fail("bad_output_dt_tiny.toml", CD_EINVAL,
                SUBS("bad_output_dt_tiny.toml:4:13: key 'simulation.output_dt': expected a value in [duration / 1e9, inf) "
                     "= [4e-09, inf) s", "got 1e-300"));
}

Test(scenario_reject, more_than_1e9_samples_from_an_override)
{
    /* minimal.toml: duration 4 s, output_dt duration / 1000 by default */
    const char *dur[] = {"simulation.duration=1e300", "simulation.output_dt=1e-4"};
    const char *dt[] = {"simulation.output_dt=1e-300"};
    expect_fail_ov("minimal.toml", dur, 2, CD_EINVAL,
                   SUBS("--set 'simulation.output_dt=1e-4': key 'simulation.output_dt': expected a value in "
                        "[duration / 1e9, inf) = [1e+291, inf) s"));
    expect_fail_ov("minimal.toml", dt, 1, CD_EINVAL,
                   SUBS("--set 'simulation.output_dt=1e-300': key 'simulation.output_dt'", "got 1e-300"));
    {
        /* 1e9 samples (to rounding: 4 / 4e-9 <= 1e9 in doubles) is allowed;
         * such a run needs >= 1.2e10 evaluations (1e9 steps of rk8pd), more
         * than the default work budget: lifted here (0 = no limit) */
        const char *ok[] = {"simulation.output_dt=4e-9", "simulation.max_rhs_evals=0"};
        cd_scenario *sc = load_ok("minimal.toml", ok, 2);
        cr_expect(fabs(sc->duration / sc->output_dt - 1e9) <= 1.0, "%.17g samples", sc->duration / sc->output_dt);
        cd_scenario_free(sc);
    }
}

Test(scenario_reject, include_cycle)
{
    /* a -> b -> a: reported where b includes a */
    expect_fail("cycle_a.toml", CD_EINVAL,
                SUBS("cycle_b.toml:1:12: key 'include[0]': include cycle:", "cycle_a.toml -> ", "cycle_b.toml -> "));
}

Test(scenario_reject, builder_error_is_located)
{
    /* self-contact is refused by cd_model_add_pair; its message comes back
     * prefixed with the position of the [[pair]] table */
    expect_fail("bad_self_contact.toml", CD_EINVAL,
                SUBS("bad_self_contact.toml:16:1: key 'pair[0]': ", "cannot touch its own shape"));
}

Test(scenario_reject, rpy_and_quaternion_together)
{
    expect_fail("bad_rpy_quat.toml", CD_EINVAL,
                SUBS("bad_rpy_quat.toml:9:1: key 'system[0].quaternion': give either rpy_deg or quaternion"));
}

Test(scenario_reject, radians_key_on_revolute_joint)
{
    expect_fail("bad_q0_revolute.toml", CD_EINVAL,
                SUBS("bad_q0_revolute.toml:13:3: key 'system[0].link[0].q0': does not apply to a revolute joint",
                     "q0_deg"));
}

Test(scenario_reject, mu_above_mu_max)
{
    expect_fail("bad_mu.toml", CD_EINVAL, SUBS("bad_mu.toml:6:6: key 'contact.mu': expected mu <= mu_max = 0.4, got 0.5"));
}

Test(scenario_reject, table_times_not_increasing)
{
    expect_fail("bad_table_time.toml", CD_EINVAL,
                SUBS("bad_table_time.toml:12:65: key 'system[0].link[0].actuator.table[2]'", "strictly increasing"));
}

Test(scenario_reject, gripper_mechanism_needs_its_fingers)
{
    /* a mechanism gripper builds its hand: the finger links must be given */
    expect_fail("bad_gripper.toml", CD_EINVAL,
                SUBS("bad_gripper.toml:4:1: key 'gripper.links': missing required key (expected an array of link lengths [m]"));
}

Test(scenario_reject, duplicate_system_name)
{
    expect_fail("bad_dup_name.toml", CD_EINVAL, SUBS("bad_dup_name.toml:10:8: key 'target[0].name'", "'ball' twice"));
}

Test(scenario_reject, wrong_vector_length)
{
    expect_fail("bad_vec_len.toml", CD_EINVAL,
                SUBS("bad_vec_len.toml:8:12: key 'system[0].position': expected an array of 3 numbers, got [1, 2]"));
}

Test(scenario_reject, size_key_of_another_shape_type)
{
    expect_fail("bad_shape_key.toml", CD_EINVAL,
                SUBS("bad_shape_key.toml:10:3: key 'system[0].shape[0].radius': does not apply to a box shape"));
}

Test(scenario_reject, initial_position_outside_limits)
{
    expect_fail("bad_limit.toml", CD_EINVAL,
                SUBS("bad_limit.toml:13:12: key 'system[0].link[0].q0_deg': expected an initial position within"));
}

Test(scenario_reject, velocity_on_fixed_base)
{
    expect_fail("bad_fixed_velocity.toml", CD_EINVAL,
                SUBS("bad_fixed_velocity.toml:7:1: key 'system[0].velocity': applies only to a free base"));
}

Test(scenario_reject, rule_and_explicit_stiffness)
{
    expect_fail("bad_rule_and_k.toml", CD_EINVAL, SUBS("bad_rule_and_k.toml:5:1: key 'contact.K'", "give one or the other"));
}

Test(scenario_reject, integer_key_given_a_fraction)
{
    expect_fail("bad_max_steps.toml", CD_EINVAL,
                SUBS("bad_max_steps.toml:3:13: key 'simulation.max_steps': expected an integer >= 1, got 2.5"));
}

Test(scenario_reject, override_unknown_key)
{
    const char *ov[] = {"simulation.duraton=3"};
    expect_fail_ov("minimal.toml", ov, 1, CD_EINVAL,
                   SUBS("--set 'simulation.duraton=3': key 'simulation.duraton': unknown key", "did you mean 'duration'?"));
}

Test(scenario_reject, override_bad_value)
{
    const char *ov[] = {"system.ball.mass=-2"};
    expect_fail_ov("minimal.toml", ov, 1, CD_EINVAL,
                   SUBS("--set 'system.ball.mass=-2': key 'system[0].mass': expected a positive number, got -2"));
}

Test(scenario_reject, override_unknown_element_name)
{
    const char *ov[] = {"system.bal.mass=2"};
    expect_fail_ov("minimal.toml", ov, 1, CD_EINVAL,
                   SUBS("--set 'system.bal.mass=2': key 'system': no element named 'bal'", "did you mean 'ball'?"));
}

Test(scenario_reject, override_index_out_of_range)
{
    const char *ov[] = {"system[3].mass=2"};
    expect_fail_ov("minimal.toml", ov, 1, CD_EINVAL, SUBS("--set 'system[3].mass=2'", "index [3] out of range"));
}

Test(scenario_reject, override_malformed)
{
    const char *ov1[] = {"simulation.duration"};
    const char *ov2[] = {"simulation.duration=[1,"};
    const char *ov3[] = {"include=[\"x.toml\"]"};
    expect_fail_ov("minimal.toml", ov1, 1, CD_EINVAL, SUBS("--set 'simulation.duration': expected KEY.PATH=VALUE"));
    expect_fail_ov("minimal.toml", ov2, 1, CD_EINVAL, SUBS("--set 'simulation.duration=[1,': cannot parse the value"));
    expect_fail_ov("minimal.toml", ov3, 1, CD_EINVAL, SUBS("'include' cannot be changed by --set"));
}

Test(scenario_reject, null_arguments_and_null_error)
{
    cd_error err;
    cr_assert_null(cd_scenario_load(NULL, NULL, 0, &err));
    cr_assert_eq(err.status, CD_EINVAL);
    /* err may be NULL: still no crash, still NULL */
    cr_assert_null(cd_scenario_load(fixture("bad_syntax.toml"), NULL, 0, NULL));
    cd_scenario_free(NULL);
}

/* ==== round trip of every key ============================================== */

Test(scenario_roundtrip, every_documented_key)
{
    cd_scenario *sc = load_ok("all_keys.toml", NULL, 0);
    const cd_model *m = sc->model;
    const double R1 = 1e-15, R2 = 1e-12;
    int arm, ground, stand, sat, b_l1, b_sl, b_l2, b_l3, b_l4;
    cr_assert(m->finalized);

    /* run settings */
    cr_assert_str_eq(sc->title, "all keys");
    near(sc->duration, 2.5, R1, "duration");
    near(sc->output_dt, 0.01, R1, "output_dt");
    near(sc->flush_every, 0.5, R1, "flush_every");
    cr_assert_eq(sc->event_capacity, 999);
    cr_assert_str_eq(sc->overrides, "");
    {
        /* text = the file's text */
        FILE *f = fopen(fixture("all_keys.toml"), "rb");
        static char buf[65536];
        size_t n;
        cr_assert_not_null(f);
        n = fread(buf, 1, sizeof buf - 1, f);
        buf[n] = 0;
        fclose(f);
        cr_assert_str_eq(sc->text, buf);
        cr_assert(strstr(sc->path, "all_keys.toml") != NULL);
    }

    /* [simulation] */
    {
        double g[3] = {0, 0, -9.81};
        near_n(m->gravity, g, 3, R1, "gravity");
    }
    cr_assert_eq(m->opt.stepper, CD_STEP_RKCK);
    near(m->opt.rtol, 1e-7, R1, "rtol");
    near(m->opt.atol, 1e-9, R1, "atol");
    near(m->opt.h_init, 2e-5, R1, "h_init");
    near(m->opt.h_max, 5e-3, R1, "h_max");
    near(m->opt.h_min, 1e-13, R1, "h_min");
    near(m->opt.h_fixed, 2e-4, R1, "h_fixed");
    cr_assert_eq(m->opt.max_steps, 123456L);
    near(m->opt.event_tol, 1e-9, R1, "event_tol");
    near(m->opt.dwell, 2e-7, R1, "dwell");
    near(m->opt.v_reg, 3e-6, R1, "v_reg");
    near(m->opt.fd_eps, 2e-7, R1, "fd_eps");

    /* systems: [[system]] in order, then [[target]] */
    cr_assert_eq(m->nsys, 4);
    arm = cd_model_system_id(m, "arm");
    ground = cd_model_system_id(m, "ground");
    stand = cd_model_system_id(m, "stand");
    sat = cd_model_system_id(m, "sat");
    cr_assert(arm == 0 && ground == 1 && stand == 2 && sat == 3);
    cr_assert_eq(m->sys_base_type[arm], CD_BASE_FREE);
    cr_assert_eq(m->sys_base_type[ground], CD_BASE_FIXED);
    cr_assert_eq(m->sys_base_type[stand], CD_BASE_FIXED);
    cr_assert_eq(m->sys_base_type[sat], CD_BASE_FREE);
    cr_assert_eq(m->nbody, 9); /* arm base + 5 links, ground, stand, sat */

    /* arm base: 6-number inertia, rpy yaw 90 deg, deg/s angular velocity */
    {
        double I[9] = {1.0, 0.1, -0.05, 0.1, 2.0, 0.02, -0.05, 0.02, 2.5};
        double pos[3] = {0.1, 0.2, 0.3}, vel[3] = {0.01, 0.02, 0.03}, w[3] = {0, 0, 10 * DEG};
        double q[4] = {cos(PI / 4), 0, 0, sin(PI / 4)};
        int b0 = m->sys_body_adr[arm];
        near(m->body_mass[b0], 10.0, R1, "arm mass");
        near_n(m->body_inertia + 9 * b0, I, 9, R1, "arm inertia");
        near_n(m->sys_pos0 + 3 * arm, pos, 3, R1, "arm position");
        near_n(m->sys_vel0 + 3 * arm, vel, 3, R1, "arm velocity");
        near_n(m->sys_angvel0 + 3 * arm, w, 3, R2, "arm angular_velocity_deg_s");
        near_n(m->sys_quat0 + 4 * arm, q, 4, R2, "arm rpy_deg -> quaternion");
    }
    /* fixed bases: defaults (1 kg, identity) and explicit mass/inertia/quaternion */
    {
        double I1[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, I2[9] = {1, 0, 0, 0, 2, 0, 0, 0, 2};
        double p[3] = {0, 0, -1}, q[4] = {0, 0, 0, 1};
        near(m->body_mass[m->sys_body_adr[ground]], 1.0, R1, "fixed default mass");
        near_n(m->body_inertia + 9 * m->sys_body_adr[ground], I1, 9, R1, "fixed default inertia");
        near_n(m->sys_pos0 + 3 * ground, p, 3, R1, "ground position");
        near(m->body_mass[m->sys_body_adr[stand]], 5.0, R1, "stand mass");
        near_n(m->body_inertia + 9 * m->sys_body_adr[stand], I2, 9, R1, "stand inertia");
        near_n(m->sys_quat0 + 4 * stand, q, 4, R1, "stand quaternion");
    }
    /* target sugar: free system, rad/s angular velocity, quaternion */
    {
        double I[9] = {100, 0, 0, 0, 150, 0, 0, 0, 200}, p[3] = {3, 0, 0}, v[3] = {-0.1, 0, 0};
        double w[3] = {0.1, 0.01, 0.1}, q[4] = {0, 1, 0, 0};
        int b = m->sys_body_adr[sat];
        near(m->body_mass[b], 500.0, R1, "sat mass");
        near_n(m->body_inertia + 9 * b, I, 9, R1, "sat inertia");
        near_n(m->sys_pos0 + 3 * sat, p, 3, R1, "sat position");
        near_n(m->sys_vel0 + 3 * sat, v, 3, R1, "sat velocity");
        near_n(m->sys_angvel0 + 3 * sat, w, 3, R1, "sat angular_velocity");
        near_n(m->sys_quat0 + 4 * sat, q, 4, R1, "sat quaternion");
    }

    /* links */
    b_l1 = cd_model_body_id(m, "arm/l1");
    b_sl = cd_model_body_id(m, "arm/slider");
    b_l2 = cd_model_body_id(m, "arm/l2");
    b_l3 = cd_model_body_id(m, "arm/l3");
    b_l4 = cd_model_body_id(m, "arm/l4");
    cr_assert(b_l1 == 1 && b_sl == 2 && b_l2 == 3 && b_l3 == 4 && b_l4 == 5);
    cr_assert_eq(m->body_parent[b_l1], 0);  /* default: the base */
    cr_assert_eq(m->body_parent[b_sl], 0);  /* parent = "base" */
    cr_assert_eq(m->body_parent[b_l2], b_l1);
    cr_assert_eq(m->body_parent[b_l3], b_l2); /* default: the previous link */
    cr_assert_eq(m->body_parent[b_l4], b_l3);
    cr_assert_eq(m->body_jnt_type[b_l1], CD_JOINT_REVOLUTE);
    cr_assert_eq(m->body_jnt_type[b_sl], CD_JOINT_PRISMATIC);
    cr_assert_eq(m->body_jnt_type[b_l2], CD_JOINT_REVOLUTE); /* default joint */
    {
        double ax1[3] = {0, 0, 1}, ax2[3] = {1, 0, 0}, o1[3] = {0.5, 0, 0}, o2[3] = {-0.5, 0, 0};
        double Rx90[9] = {1, 0, 0, 0, 0, -1, 0, 1, 0}; /* rpy_deg = [90, 0, 0] */
        double Ry90[9] = {0, 0, 1, 0, 1, 0, -1, 0, 0}; /* quaternion (cos 45, 0, sin 45, 0) */
        double Id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        double c1[3] = {0.25, 0, 0}, z3[3] = {0, 0, 0};
        double I1[9] = {0.01, 0, 0, 0, 0.05, 0, 0, 0, 0.05};
        near_n(m->body_axis + 3 * b_l1, ax1, 3, R1, "l1 axis (normalised)");
        near_n(m->body_axis + 3 * b_sl, ax2, 3, R1, "slider axis");
        near_n(m->body_axis + 3 * b_l2, ax1, 3, R1, "l2 default axis");
        near_n(m->body_jnt_pos + 3 * b_l1, o1, 3, R1, "l1 origin");
        near_n(m->body_jnt_pos + 3 * b_sl, o2, 3, R1, "slider origin");
        near_n(m->body_jnt_rot + 9 * b_l1, Rx90, 9, R2, "l1 rpy_deg");
        near_n(m->body_jnt_rot + 9 * b_sl, Ry90, 9, R2, "slider quaternion");
        near_n(m->body_jnt_rot + 9 * b_l2, Id, 9, R1, "l2 default rotation");
        near(m->body_mass[b_l1], 2.0, R1, "l1 mass");
        near_n(m->body_com + 3 * b_l1, c1, 3, R1, "l1 com");
        near_n(m->body_com + 3 * b_sl, z3, 3, R1, "slider default com");
        near_n(m->body_inertia + 9 * b_l1, I1, 9, R1, "l1 3x3 inertia");
        near(m->body_q0[b_l1], 30 * DEG, R2, "l1 q0_deg");
        near(m->body_qd0[b_l1], -5 * DEG, R2, "l1 qd0_deg_s");
        near(m->body_q0[b_sl], 0.05, R1, "slider q0");
        near(m->body_qd0[b_sl], 0.01, R1, "slider qd0");
        near(m->body_q0[b_l2], 0.0, R1, "l2 default q0");
    }
    /* actuators */
    cr_assert_eq(ACT_TYPE(m, b_l1), CD_ACT_TABLE);
    cr_assert_eq(m->act_tbl_n[m->body_act[b_l1]], 3);
    {
        double t[3] = {0, 1, 2}, v[3] = {0, 2, -1};
        near_n(m->tbl_t + m->act_tbl_adr[m->body_act[b_l1]], t, 3, R1, "table t");
        near_n(m->tbl_v + m->act_tbl_adr[m->body_act[b_l1]], v, 3, R1, "table tau");
    }
    cr_assert_eq(ACT_TYPE(m, b_sl), CD_ACT_PD);
    {
        double a[4] = {0.5, 100, 2, 0.1}; /* tau0, kp, kd, qref */
        double b[4] = {0.0, 5, 0.1, 45 * DEG};
        near_n(ACT_PRM(m, b_sl), a, 4, R1, "slider pd");
        cr_assert_eq(ACT_TYPE(m, b_l2), CD_ACT_PD);
        near_n(ACT_PRM(m, b_l2), b, 4, R2, "l2 pd (qref_deg)");
    }
    cr_assert_eq(ACT_TYPE(m, b_l3), CD_ACT_CONSTANT);
    near(ACT_PRM(m, b_l3)[0], 0.25, R1, "l3 tau");
    cr_assert_eq(ACT_TYPE(m, b_l4), CD_ACT_NONE);

    /* check points: arm base 1, l1 2, sat 1 */
    cr_assert_eq(m->ncp, 4);
    {
        double p0[3] = {0, 0, 0.5}, p1[3] = {0.5, 0, 0}, p2[3] = {0.25, 0, 0}, p3[3] = {0.6, 0, 0};
        cr_assert(m->cp_body[0] == 0 && m->cp_body[1] == b_l1 && m->cp_body[2] == b_l1 &&
                  m->cp_body[3] == m->sys_body_adr[sat]);
        near_n(m->cp_pos, p0, 3, R1, "cp0");
        near_n(m->cp_pos + 3, p1, 3, R1, "cp1");
        near_n(m->cp_pos + 6, p2, 3, R1, "cp2");
        near_n(m->cp_pos + 9, p3, 3, R1, "cp3");
        near(m->cp_radius[0], 0.01, R1, "r0");
        near(m->cp_radius[1], 0.02, R1, "r1");
        near(m->cp_radius[2], 0.03, R1, "r2");
        near(m->cp_radius[3], 0.0, R1, "r3");
    }

    /* shapes: hull, l1cap, wall, ball, post, rock, sat/shape */
    cr_assert_eq(m->nshape, 7);
    {
        double hull[3] = {0.5, 0.4, 0.3}, hp[3] = {0, 0, 0.1}, cap[3] = {0.03, 0.2, 0};
        double cyl[3] = {0.05, 0.5, 0}, Ry90[9] = {0, 0, 1, 0, 1, 0, -1, 0, 0};
        double wp[3] = {2, 0, 0}, bp[3] = {1, 0, 0};
        double verts[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
        double zcol[3];
        const double *Rw = m->shape_rot + 9 * 2;
        cr_assert_eq(m->shape_type[0], CD_SHAPE_BOX);
        cr_assert_eq(m->shape_body[0], 0);
        near_n(m->shape_size, hull, 3, R1, "box size -> half extents");
        near_n(m->shape_pos, hp, 3, R1, "hull position");
        cr_assert_eq(m->shape_type[1], CD_SHAPE_CAPSULE);
        cr_assert_eq(m->shape_body[1], b_l1);
        near_n(m->shape_size + 3, cap, 3, R1, "capsule radius, half length");
        near_n(m->shape_rot + 9, Ry90, 9, R2, "capsule rpy_deg");
        cr_assert_eq(m->shape_type[2], CD_SHAPE_PLANE);
        /* normal = the shape frame's z axis in the body frame: third column */
        zcol[0] = Rw[2]; zcol[1] = Rw[5]; zcol[2] = Rw[8];
        {
            double n[3] = {-1, 0, 0};
            near_n(zcol, n, 3, R2, "plane normal");
        }
        near_n(m->shape_pos + 6, wp, 3, R1, "wall position");
        cr_assert_eq(m->shape_type[3], CD_SHAPE_SPHERE);
        near(m->shape_size[9], 0.2, R1, "sphere radius");
        near_n(m->shape_pos + 9, bp, 3, R1, "ball position");
        cr_assert_eq(m->shape_type[4], CD_SHAPE_CYLINDER);
        near_n(m->shape_size + 12, cyl, 3, R1, "cylinder radius, half length");
        cr_assert_eq(m->shape_type[5], CD_SHAPE_CONVEX);
        cr_assert_eq(m->shape_vert_num[5], 4);
        near_n(m->vert + 3 * m->shape_vert_adr[5], verts, 12, R1, "vertices");
        cr_assert_eq(m->shape_type[6], CD_SHAPE_SPHERE);
        cr_assert_eq(m->shape_body[6], m->sys_body_adr[sat]);
        near(m->shape_size[18], 0.8, R1, "target sphere radius");
    }

    /* contact laws and pairs */
    cr_assert_eq(m->npair, 4);
    cr_assert_eq(m->nlaw, 4);
    {
        const cd_contact_law *L0 = &m->law[m->pair_law[0]], *L1 = &m->law[m->pair_law[1]];
        const cd_contact_law *L2 = &m->law[m->pair_law[2]], *L3 = &m->law[m->pair_law[3]];
        /* [contact] as given */
        double l0[8] = {2e4, 30, 1.5, 1.25, 1e4, 20, 0.6, 0.4};
        /* pair K only: the rest from [contact] (K_t given there, so kept) */
        double l1[8] = {5e4, 30, 1.5, 1.25, 1e4, 20, 0.6, 0.4};
        /* rule: K = 1000 x 20, D = 2 x 0.5 x sqrt(2e4 x 2) = 200; mu given, mu_max inherited */
        double l2[8] = {2e4, 200, 1.5, 1.25, 1e4, 20, 0.6, 0.3};
        double l3[8] = {3e4, 10, 1.2, 1.1, 9e3, 7, 0.9, 0.8};
        const cd_contact_law *Ls[4] = {L0, L1, L2, L3};
        const double *want[4] = {l0, l1, l2, l3};
        int i;
        for (i = 0; i < 4; i++) {
            double got[8] = {Ls[i]->K, Ls[i]->D, Ls[i]->p, Ls[i]->q, Ls[i]->Kt, Ls[i]->Dt, Ls[i]->mu_s, Ls[i]->mu_k};
            char what[32];
            snprintf(what, sizeof what, "pair %d law", i);
            near_n(got, want[i], 8, R2, what);
        }
    }
    cr_assert(m->pair_sys[0] == arm && m->pair_body[0] == -1 && m->pair_shape[0] == 2);
    cr_assert(m->pair_sys[1] == arm && m->pair_body[1] == b_l1 && m->pair_shape[1] == 6);
    cr_assert(m->pair_sys[2] == sat && m->pair_body[2] == -1 && m->pair_shape[2] == 3);
    cr_assert(m->pair_sys[3] == arm && m->pair_body[3] == 0 && m->pair_shape[3] == 6);
    /* slots: 3 arm cps x wall + 2 l1 cps x sat + 1 sat cp x ball + 1 base cp x sat */
    cr_assert_eq(m->nslot, 7);
    cd_scenario_free(sc);
}

Test(scenario_roundtrip, defaults)
{
    cd_scenario *sc = load_ok("minimal.toml", NULL, 0);
    const cd_model *m = sc->model;
    cd_options o = cd_options_default();
    /* title defaults to the file name's stem; output_dt to duration / 1000 */
    cr_assert_str_eq(sc->title, "minimal");
    near(sc->duration, 4.0, 1e-15, "duration");
    near(sc->output_dt, 4.0 / 1000, 1e-15, "default output_dt");
    near(sc->flush_every, 1.0, 1e-15, "default flush_every");
    cr_assert_eq(sc->event_capacity, 4096);
    cr_assert(m->gravity[0] == 0 && m->gravity[1] == 0 && m->gravity[2] == 0);
    cr_assert(m->opt.stepper == o.stepper && m->opt.rtol == o.rtol && m->opt.atol == o.atol &&
              m->opt.h_init == o.h_init && m->opt.h_max == o.h_max && m->opt.h_min == o.h_min &&
              m->opt.h_fixed == o.h_fixed && m->opt.max_steps == o.max_steps && m->opt.event_tol == o.event_tol &&
              m->opt.dwell == o.dwell && m->opt.v_reg == o.v_reg && m->opt.fd_eps == o.fd_eps);
    cr_assert_eq(m->sys_base_type[0], CD_BASE_FREE); /* base defaults to free */
    cr_assert_eq(m->sys_quat0[0], 1.0);
    cd_scenario_free(sc);
}

Test(scenario_roundtrip, contact_rule)
{
    cd_scenario *sc = load_ok("rule_contact.toml", NULL, 0);
    const cd_model *m = sc->model;
    /* cd_contact_law_from_rule(500, 40, 0.2, zeta = 1 default): K = 2e4, D = 2 sqrt(2e4 x 0.2) = 126.49 */
    double K = 2e4, D = 2.0 * sqrt(2e4 * 0.2);
    const cd_contact_law *L0 = &m->law[m->pair_law[0]], *L1 = &m->law[m->pair_law[1]];
    double g0[8] = {L0->K, L0->D, L0->p, L0->q, L0->Kt, L0->Dt, L0->mu_s, L0->mu_k};
    double w0[8] = {K, D, 1, 1, K, D, 0.7, 0.7}; /* K_t, D_t track K, D; mu follows mu_max */
    double g1[8] = {L1->K, L1->D, L1->p, L1->q, L1->Kt, L1->Dt, L1->mu_s, L1->mu_k};
    double w1[8] = {1e3, D, 1, 1, 1e3, D, 0.7, 0.7}; /* the pair's K; K_t still tracks K */
    near_n(g0, w0, 8, 1e-12, "[contact.rule] law");
    near_n(g1, w1, 8, 1e-12, "pair K over the rule");
    /* the second pair repeats the first's slots: the builder keeps one */
    cr_assert_eq(m->nslot, 1);
    cd_scenario_free(sc);
}

/* ==== include and --set ====================================================== */

Test(scenario_include, merge_order_and_arrays_by_name)
{
    cd_scenario *sc = load_ok("inc_child.toml", NULL, 0);
    const cd_model *m = sc->model;
    int arm = cd_model_system_id(m, "arm"), l3;
    cr_assert_str_eq(sc->title, "child");                     /* the including file wins */
    near(sc->duration, 3.0, 1e-15, "duration from the later include");
    near(m->opt.rtol, 1e-5, 1e-15, "rtol: sub/inc_extra beats inc_common");
    near(m->opt.atol, 1e-10, 1e-15, "atol: child beats inc_base");
    cr_assert_eq(m->nsys, 2);
    cr_assert(arm == 0 && cd_model_system_id(m, "ball") == 1); /* merged element keeps its place */
    near(m->body_mass[m->sys_body_adr[arm]], 20.0, 1e-15, "arm mass updated by name");
    near(m->body_inertia[9 * m->sys_body_adr[arm]], 1.0, 1e-15, "arm inertia inherited");
    cr_assert_eq(m->sys_nbody[arm], 4);                         /* base, l1, l2, l3 */
    near(m->body_mass[cd_model_body_id(m, "arm/l1")], 1.0, 1e-15, "l1 untouched");
    near(m->body_mass[cd_model_body_id(m, "arm/l2")], 3.0, 1e-15, "l2 updated by name");
    l3 = cd_model_body_id(m, "arm/l3");
    near(m->body_mass[l3], 0.5, 1e-15, "l3 appended");
    cr_assert_eq(m->body_parent[l3], cd_model_body_id(m, "arm/l2"));
    /* text: the main file first, then each include after a header line */
    cr_assert(strncmp(sc->text, "# include semantics", 19) == 0);
    cr_assert(strstr(sc->text, "# ---- included file: ") != NULL);
    cr_assert(strstr(sc->text, "inc_base.toml ----") && strstr(sc->text, "inc_common.toml ----") &&
              strstr(sc->text, "inc_extra.toml ----") && strstr(sc->text, "inc_leaf.toml ----"));
    cd_scenario_free(sc);
}

Test(scenario_include, contact_defaults_through_nested_includes)
{
    cd_scenario *sc;
    const cd_model *m;
    /* a pair makes the [contact] law visible: K from inc_common, mu_max from
     * sub/inc_leaf (resolved relative to sub/inc_extra.toml, not the CWD) */
    const char *ov[] = {"system.ball.checkpoints=[[0,0,0,0.1]]",
                        "system.arm.shape={name=\"plate\", type=\"box\", size=[1,1,1]}",
                        "pair=[{checkpoints=\"ball\", shape=\"arm/plate\"}]"};
    sc = load_ok("inc_child.toml", ov, 3);
    m = sc->model;
    cr_assert_eq(m->npair, 1);
    near(m->law[m->pair_law[0]].K, 1e4, 1e-15, "K from inc_common.toml");
    near(m->law[m->pair_law[0]].mu_s, 0.7, 1e-15, "mu_max from sub/inc_leaf.toml");
    cd_scenario_free(sc);
}

Test(scenario_override, set_by_name_index_and_new_keys)
{
    const char *ov[] = {"simulation.duration=5",
                        "system.arm.link[1].mass=4",       /* by name, then index: l2 */
                        "system[0].link.l1.mass = 1.5",    /* by index, then name; spaces allowed */
                        "simulation.integrator=rk4",       /* a bare word is a string */
                        "simulation.output_dt=0.5",        /* a key absent from the files */
                        "system.ball.position=[1, 2, 3]",
                        "simulation.gravity=[0,0,-1]",
                        "simulation.gravity[2]=-2"};       /* one element of a number array */
    cd_scenario *sc = load_ok("inc_child.toml", ov, 8);
    const cd_model *m = sc->model;
    double p[3] = {1, 2, 3};
    near(sc->duration, 5.0, 1e-15, "duration overridden after includes");
    near(m->body_mass[cd_model_body_id(m, "arm/l2")], 4.0, 1e-15, "link[1] mass");
    near(m->body_mass[cd_model_body_id(m, "arm/l1")], 1.5, 1e-15, "link l1 mass");
    cr_assert_eq(m->opt.stepper, CD_STEP_RK4_FIXED);
    near(sc->output_dt, 0.5, 1e-15, "new key");
    near_n(m->sys_pos0 + 3, p, 3, 1e-15, "ball position");
    near(m->gravity[2], -2.0, 1e-15, "gravity[2]");
    /* the overrides are kept, one per line */
    cr_assert_str_eq(sc->overrides,
                     "simulation.duration=5\nsystem.arm.link[1].mass=4\nsystem[0].link.l1.mass = 1.5\n"
                     "simulation.integrator=rk4\nsimulation.output_dt=0.5\nsystem.ball.position=[1, 2, 3]\n"
                     "simulation.gravity=[0,0,-1]\nsimulation.gravity[2]=-2\n");
    cd_scenario_free(sc);
}

Test(scenario_override, vector_components_and_the_only_element)
{
    /* minimal.toml has one [[system]] ("ball"): system.position is
     * system[0].position; .x .y .z are [0] [1] [2] of a number array */
    const char *ov[] = {"system.position=[1, 2, 3]", "system.position.y=5", "system.ball.position.z=-4"};
    const char *bad[] = {"system.position=[1, 2, 3]", "system.position.w=1"};
    cd_scenario *sc = load_ok("minimal.toml", ov, 3);
    double p[3] = {1, 5, -4};
    near_n(sc->model->sys_pos0, p, 3, 0.0, "position after .y and .z");
    cd_scenario_free(sc);
    expect_fail_ov("minimal.toml", bad, 2, CD_EINVAL,
                   SUBS("--set 'system.position.w=1': key 'system[0].position': no component 'w' (expected x, y, z"));
}

Test(scenario_override, a_component_of_a_key_the_file_lacks_is_named_as_such)
{
    /* minimal.toml has no gravity and no velocity: .x on them cannot pick a
     * component of anything; the message says so and names the whole
     * array to set (it said "got a table": the override's own {x = 1}) */
    const char *grav[] = {"simulation.gravity.x=1"};
    const char *vel[] = {"system.ball.velocity.y=2"};
    const char *scalar[] = {"simulation.duration.z=1"};
    expect_fail_ov("minimal.toml", grav, 1, CD_EINVAL,
                   SUBS("--set 'simulation.gravity.x=1': key 'simulation.gravity': expected an array of 3 numbers, got "
                        "only the component '.x' (--set named a component of a key the file does not have: set the "
                        "whole array instead, --set 'simulation.gravity=[x, y, z]')"));
    expect_fail_ov("minimal.toml", vel, 1, CD_EINVAL,
                   SUBS("key 'system[0].velocity': expected an array of 3 numbers, got only the component '.y' "));
    expect_fail_ov("minimal.toml", scalar, 1, CD_EINVAL,
                   SUBS("key 'simulation.duration': no component 'z': the value is 4, not an array of numbers"));
}

Test(scenario_override, later_override_wins)
{
    const char *ov[] = {"simulation.duration=5", "simulation.duration=7"};
    cd_scenario *sc = load_ok("minimal.toml", ov, 2);
    near(sc->duration, 7.0, 1e-15, "the last --set wins");
    cd_scenario_free(sc);
}

/* ==== the shipped scenarios ==================================================== */

Test(scenario_files, every_scenario_loads)
{
    char dir[4096], path[8192];
    DIR *d;
    struct dirent *e;
    int n = 0;
    snprintf(dir, sizeof dir, "%s/scenarios", root_dir());
    d = opendir(dir);
    cr_assert_not_null(d, "cannot open %s", dir);
    while ((e = readdir(d)) != NULL) {
        size_t len = strlen(e->d_name);
        cd_error err;
        cd_scenario *sc;
        if (len < 6 || strcmp(e->d_name + len - 5, ".toml") != 0) continue;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        sc = cd_scenario_load(path, NULL, 0, &err);
        cr_assert_not_null(sc, "%s: %s", e->d_name, err.msg);
        cr_assert(sc->model->finalized && strlen(sc->title) > 0 && sc->duration > 0);
        cd_scenario_free(sc);
        n++;
    }
    closedir(d);
    cr_assert_geq(n, 4, "expected at least the 4 paper/demo scenarios, found %d", n);
}

static cd_scenario *load_scenario(const char *name)
{
    char path[4096];
    cd_error err;
    cd_scenario *sc;
    snprintf(path, sizeof path, "%s/scenarios/%s", root_dir(), name);
    sc = cd_scenario_load(path, NULL, 0, &err);
    cr_assert_not_null(sc, "%s: %s", name, err.msg);
    return sc;
}

Test(scenario_files, fig5_geometry_is_the_benchmark_scene)
{
    cd_scenario *sc = load_scenario("paper_fig5_envelope_grasp.toml");
    const cd_model *m = sc->model;
    cd_error err;
    cd_data *d = cd_data_create(m, sc->event_capacity, &err);
    int hand = cd_model_system_id(m, "hand"), obj = cd_model_system_id(m, "object"), k;
    int l1 = cd_model_body_id(m, "hand/left1"), l2 = cd_model_body_id(m, "hand/left2");
    int r1 = cd_model_body_id(m, "hand/right1"), r2 = cd_model_body_id(m, "hand/right2");
    double tip[3] = {0, 0.07, 0}, pw[3], want[3];
    cr_assert_not_null(d, "%s", err.msg);
    cr_assert(hand >= 0 && obj >= 0 && l1 > 0 && l2 > 0 && r1 > 0 && r2 > 0);
    cr_assert_eq(m->sys_base_type[hand], CD_BASE_FIXED);
    cr_assert_eq(m->sys_base_type[obj], CD_BASE_FREE);
    near(m->body_mass[m->sys_body_adr[hand]], 2.0, 1e-15, "palm mass");
    near(m->body_mass[l1], 0.05, 1e-15, "link 1 mass");
    near(m->body_mass[l2], 0.04, 1e-15, "link 2 mass");
    near(m->body_mass[m->sys_body_adr[obj]], 0.3, 1e-15, "object mass");
    near(m->gravity[0] + m->gravity[1] + m->gravity[2], 0.0, 0, "no gravity");
    near(sc->duration, 2.0, 0, "2 s");
    cd_kinematics(m, d);
    /* fingertips at q = 0: bases (+-0.05, 0.02, 0) + 0.08 + 0.07 along +y (exact to 1e-15 m) */
    cd_point_world(m, d, l2, tip, pw, NULL);
    want[0] = -0.05; want[1] = 0.17; want[2] = 0;
    near_n(pw, want, 3, 1e-15, "left fingertip");
    cd_point_world(m, d, r2, tip, pw, NULL);
    want[0] = 0.05;
    near_n(pw, want, 3, 1e-15, "right fingertip");
    /* joint axes: -z left, +z right, so a positive torque closes both */
    cr_assert(d->body_axisw[3 * l1 + 2] == -1 && d->body_axisw[3 * l2 + 2] == -1);
    cr_assert(d->body_axisw[3 * r1 + 2] == 1 && d->body_axisw[3 * r2 + 2] == 1);
    cr_assert(ACT_TYPE(m, l1) == CD_ACT_CONSTANT && ACT_PRM(m, l1)[0] == 0.2);
    cr_assert(ACT_TYPE(m, l2) == CD_ACT_CONSTANT && ACT_PRM(m, l2)[0] == 0.1);
    cr_assert(ACT_TYPE(m, r1) == CD_ACT_CONSTANT && ACT_PRM(m, r1)[0] == 0.2);
    cr_assert(ACT_TYPE(m, r2) == CD_ACT_CONSTANT && ACT_PRM(m, r2)[0] == 0.1);
    {
        double c[3] = {0.005, 0.075, 0};
        near_n(m->sys_pos0 + 3 * obj, c, 3, 1e-15, "cylinder position");
    }
    /* friction and the stated contact law (rule: K = 1e4, D = 2 sqrt(1e4 x 0.3)) */
    near(m->law[0].K, 1e4, 1e-12, "K");
    near(m->law[0].D, 2 * sqrt(1e4 * 0.3), 1e-12, "D");
    cr_assert(m->law[0].mu_s == 0.5 && m->law[0].mu_k == 0.5);
    /* 15 check points per finger + 7 on the palm, all against the cylinder,
     * plus the left tip link's 7 against the right tip's capsule; none starts
     * in contact (the closest, the right finger, is ~2 mm off the cylinder) */
    cr_assert_eq(m->nslot, 44);
    cr_assert_eq(cd_forward(m, d), CD_OK);
    for (k = 0; k < m->nslot; k++) cr_assert_lt(d->slot_x[k], -1e-3, "slot %d starts at x = %g", k, d->slot_x[k]);
    cd_data_free(d);
    cd_scenario_free(sc);
}

Test(scenario_files, fig3_parameters_give_the_stated_time_scales)
{
    cd_scenario *sc = load_scenario("paper_fig3_impact.toml");
    const cd_model *m = sc->model;
    int front = cd_model_body_id(m, "carrier/front");
    double M = m->body_mass[m->sys_body_adr[0]], mf = m->body_mass[front];
    double Ka = m->body_spring[2 * front], Kb = m->law[0].K;
    cr_assert_eq(m->body_jnt_type[front], CD_JOINT_PRISMATIC);
    cr_assert_eq(ACT_TYPE(m, front), CD_ACT_NONE, "the rear spring is a passive joint spring, not an actuator");
    cr_assert_eq(m->body_damping[front], 0.5);
    /* slow phase ~ pi sqrt(M / K_a) ~ 0.2 s (the paper) within 2 % */
    near(PI * sqrt(M / Ka), 0.2, 0.004, "slow contact phase [s]"); /* 2 % of 0.2 s */
    cr_assert(M >= 50 * mf, "M >> m");
    /* the paper's rule: the stiff contact is 10..100 x the soft spring */
    cr_assert(Kb >= 10 * Ka && Kb <= 100 * Ka, "K_b / K_a = %g", Kb / Ka);
    /* the front face starts 1 mm from the wall and approaches at 0.1 m/s */
    {
        cd_error err;
        cd_data *d = cd_data_create(m, 0, &err);
        cr_assert_not_null(d);
        cr_assert_eq(cd_forward(m, d), CD_OK);
        near(d->slot_x[0], -1e-3, 1e-12, "initial gap [m]");
        cd_data_free(d);
    }
    cd_scenario_free(sc);
}

Test(scenario_files, tumbling_target_is_the_asymmetric_top)
{
    cd_scenario *sc = load_scenario("tumbling_target.toml");
    const cd_model *m = sc->model;
    int s = cd_model_system_id(m, "satellite"), b, sh;
    double I[9] = {100, 0, 0, 0, 150, 0, 0, 0, 200}, w[3] = {0.1, 0.01, 0.1};
    cr_assert_geq(s, 0);
    b = m->sys_body_adr[s];
    cr_assert_eq(m->sys_base_type[s], CD_BASE_FREE);
    near_n(m->body_inertia + 9 * b, I, 9, 1e-15, "satellite inertia");
    near_n(m->sys_angvel0 + 3 * s, w, 3, 1e-15, "omega0");
    /* the box's edges match the inertia: m (b^2 + c^2) / 12 = I_x etc. within 0.1 % */
    for (sh = 0; sh < m->nshape && m->shape_body[sh] != b; sh++) {}
    cr_assert_lt(sh, m->nshape);
    {
        const double *h = m->shape_size + 3 * sh; /* half extents */
        double a2 = 4 * h[0] * h[0], b2 = 4 * h[1] * h[1], c2 = 4 * h[2] * h[2], ms = m->body_mass[b];
        near(ms * (b2 + c2) / 12, 100, 1e-3, "I_x of the box");
        near(ms * (a2 + c2) / 12, 150, 1e-3, "I_y of the box");
        near(ms * (a2 + b2) / 12, 200, 1e-3, "I_z of the box");
    }
    cd_scenario_free(sc);
}

Test(scenario_files, free_floating_arm_has_no_gravity_nor_contact)
{
    cd_scenario *sc = load_scenario("free_floating_arm.toml");
    const cd_model *m = sc->model;
    int k;
    cr_assert(m->gravity[0] == 0 && m->gravity[1] == 0 && m->gravity[2] == 0);
    cr_assert_eq(m->nslot, 0);
    cr_assert_eq(m->sys_base_type[0], CD_BASE_FREE);
    cr_assert_eq(m->body_mass[0], 100.0);
    cr_assert_geq(m->sys_nbody[0] - 1, 2);
    for (k = 1; k < m->sys_nbody[0]; k++) cr_assert_eq(ACT_TYPE(m, k), CD_ACT_TABLE);
    cd_scenario_free(sc);
}
