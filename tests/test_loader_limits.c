/* The loader's input bounds (docs/reliability.md "## Input", issue 12):
 * whatever the file, cd_scenario_load ends, in bounded stack and time, with
 * a scenario or one located message. Every load here runs on a thread with a
 * 256 KiB stack (an embedder's thread; 1 MiB under ASan, whose frames are
 * larger), so a recursion per nesting level or per include would crash the
 * test. Each case is built in a temporary directory; messages are asserted
 * exactly (file:line:col, key, expected, got). */
#include "loader_util.h"

#include "capdyn/sim.h"

#include <math.h>

static const char *BALL = "[simulation]\nduration = 0.01\n\n[[system]]\nname = \"ball\"\nmass = 1.0\n"
                          "inertia = [0.1, 0.1, 0.1]\n";

/* expects path to fail with status st and exactly the message dir/ + msg */
static void expect_msg(const char *dir, const char *file, const char *const *ov, int nov, cd_status st,
                       const char *msg)
{
    char path[1024], want[2048];
    cd_error err;
    cd_scenario *sc;
    snprintf(path, sizeof path, "%s/%s", dir, file);
    sc = lu_load_small_stack(path, ov, nov, &err);
    cr_assert_null(sc, "%s should fail", file);
    cd_scenario_free(sc);
    cr_expect_eq(err.status, st, "status %d, message %s", err.status, err.msg);
    if (msg[0] == '-') snprintf(want, sizeof want, "%s", msg); /* an override: no file prefix */
    else snprintf(want, sizeof want, "%s/%s", dir, msg);
    cr_expect_str_eq(err.msg, want);
}

/* ---- includes ---- */

/* n files c0 -> c1 -> ... -> c(n-1), the last one the ball */
static void chain(const char *dir, int n)
{
    char name[64];
    int i;
    for (i = 0; i + 1 < n; i++) {
        snprintf(name, sizeof name, "c%d.toml", i);
        lu_write(dir, name, "include = [\"c%d.toml\"]\ntitle = \"c%d\"\n", i + 1, i);
    }
    snprintf(name, sizeof name, "c%d.toml", n - 1);
    lu_write(dir, name, "%s", BALL);
}

Test(loader_limits, include_chain_of_32_levels_loads_on_a_small_stack)
{
    char dir[64], path[1024];
    cd_error err;
    cd_scenario *sc;
    lu_tmpdir(dir, sizeof dir);
    chain(dir, 33); /* the main file and 32 levels of includes */
    snprintf(path, sizeof path, "%s/c0.toml", dir);
    sc = lu_load_small_stack(path, NULL, 0, &err);
    cr_assert_not_null(sc, "%s", err.msg);
    /* the main file's title wins over its includes' */
    cr_expect_str_eq(sc->title, "c0");
    cr_expect_eq(sc->model->nsys, 1);
    cd_scenario_free(sc);
    lu_rm_rf(dir);
}

Test(loader_limits, include_chain_deeper_than_32_is_refused_at_the_include)
{
    char dir[64];
    lu_tmpdir(dir, sizeof dir);
    chain(dir, 200);
    {
        char msg[1024];
        snprintf(msg, sizeof msg,
                 "c32.toml:1:12: key 'include[0]': expected includes nested at most 32 levels deep, got %s/c0.toml -> "
                 "%s/c1.toml -> ... -> %s/c32.toml -> %s/c33.toml",
                 dir, dir, dir, dir);
        expect_msg(dir, "c0.toml", NULL, 0, CD_EINVAL, msg);
    }
    lu_rm_rf(dir);
}

Test(loader_limits, each_file_including_the_next_twice_is_read_once, .timeout = 20)
{
    /* 30 levels of t(i) = include t(i+1) twice: 2^30 loads without the
     * cache of parsed files (the test would time out); with it each file is
     * read once, which the stored text shows (one header per included file) */
    char dir[64], path[1024], name[64];
    cd_error err;
    cd_scenario *sc;
    int i, headers = 0;
    const char *p;
    lu_tmpdir(dir, sizeof dir);
    for (i = 0; i < 30; i++) {
        snprintf(name, sizeof name, "t%d.toml", i);
        lu_write(dir, name, "include = [\"t%d.toml\", \"t%d.toml\"]\n", i + 1, i + 1);
    }
    lu_write(dir, "t30.toml", "%s", BALL);
    snprintf(path, sizeof path, "%s/t0.toml", dir);
    sc = lu_load_small_stack(path, NULL, 0, &err);
    cr_assert_not_null(sc, "%s", err.msg);
    for (p = sc->text; (p = strstr(p, "# ---- included file: ")) != NULL; p++) headers++;
    cr_expect_eq(headers, 30, "%d included texts stored", headers);
    cr_expect_eq(sc->model->nsys, 1);
    cd_scenario_free(sc);
    lu_rm_rf(dir);
}

Test(loader_limits, include_cycle_names_the_chain)
{
    char dir[64], msg[1024];
    lu_tmpdir(dir, sizeof dir);
    lu_write(dir, "a.toml", "include = [\"b.toml\"]\n%s", BALL);
    lu_write(dir, "b.toml", "\ninclude = \"a.toml\"\n");
    snprintf(msg, sizeof msg,
             "b.toml:2:11: key 'include': include cycle: %s/a.toml -> %s/b.toml -> %s/a.toml (expected a file that "
             "does not include itself)",
             dir, dir, dir);
    expect_msg(dir, "a.toml", NULL, 0, CD_EINVAL, msg);
    lu_rm_rf(dir);
}

Test(loader_limits, includes_together_bounded_to_64_MiB)
{
    /* five files of 15 MiB each (under the 16 MiB per file): the fifth
     * passes 64 MiB in all and is refused at its include entry */
    char dir[64], path[1024], msg[1024];
    int i;
    lu_tmpdir(dir, sizeof dir);
    for (i = 0; i < 5; i++) {
        FILE *f;
        long k;
        snprintf(path, sizeof path, "%s/big%d.toml", dir, i);
        f = fopen(path, "w");
        cr_assert_not_null(f);
        for (k = 0; k < 15L * 1024 * 1024 / 64; k++) fprintf(f, "%-63s\n", "# padding");
        fclose(f);
    }
    lu_write(dir, "main.toml", "include = [\"big0.toml\", \"big1.toml\", \"big2.toml\", \"big3.toml\", \"big4.toml\"]\n%s",
             BALL);
    snprintf(msg, sizeof msg,
             "main.toml:1:64: key 'include[4]': cannot read included file '%s/big4.toml': the scenario and its includes "
             "together exceed 64 MiB (78643368 bytes read)",
             dir);
    expect_msg(dir, "main.toml", NULL, 0, CD_EIO, msg);
    lu_rm_rf(dir);
}

/* ---- what reaches toml++ ---- */

/* writes BALL + a line made of n copies of unit, with head and tail around */
static void long_line(const char *dir, const char *name, const char *head, const char *unit, int n, const char *tail)
{
    char path[1024];
    FILE *f;
    int i;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    f = fopen(path, "w");
    cr_assert_not_null(f);
    fprintf(f, "%s%s", BALL, head);
    for (i = 0; i < n; i++) fputs(unit, f);
    fprintf(f, "%s\n", tail);
    fclose(f);
}

Test(loader_limits, dotted_key_of_20000_names_is_refused_before_the_parser)
{
    char dir[64];
    lu_tmpdir(dir, sizeof dir);
    long_line(dir, "key.toml", "a", ".a", 19999, " = 1");
    expect_msg(dir, "key.toml", NULL, 0, CD_EINVAL,
               "key.toml:8:1: key 'a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a...': expected a key or table header of at most 32 dotted names, got 20000");
    long_line(dir, "header.toml", "[a", ".a", 19999, "]");
    expect_msg(dir, "header.toml", NULL, 0, CD_EINVAL,
               "header.toml:8:2: key 'a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a...': expected a key or table header of at most 32 dotted names, got 20000");
    long_line(dir, "aot.toml", "[[\"a\"", ".'a'", 19999, "]]");
    expect_msg(dir, "aot.toml", NULL, 0, CD_EINVAL,
               "aot.toml:8:3: key '\"a\".'a'.'a'.'a'.'a'.'a'.'a'.'a'.'a'.'a'...': expected a key or table header of at most 32 dotted names, got 20000");
    /* 32 names pass the bound: the schema names the unknown key (in the
     * [[system]] table the file ends with) */
    long_line(dir, "ok.toml", "system.a", ".a", 30, " = 1");
    expect_msg(dir, "ok.toml", NULL, 0, CD_EINVAL,
               "ok.toml:8:1: key 'system[0].system': unknown key (expected one of: 'name', 'mass', 'inertia', 'position', "
               "'rpy_deg', 'quaternion', 'velocity', 'angular_velocity', 'angular_velocity_deg_s', 'checkpoints', "
               "'shape', 'prescribed_motion', 'base', 'link')");
    lu_rm_rf(dir);
}

Test(loader_limits, nesting_deeper_than_64_is_refused_before_the_parser)
{
    char dir[64];
    lu_tmpdir(dir, sizeof dir);
    /* x = [[[...]]] in the [[system]] table: x is at depth 3 (system, its
     * element, x), the 62nd bracket (column 66) opens depth 65 */
    long_line(dir, "arrays.toml", "x = ", "[", 20000, "");
    expect_msg(dir, "arrays.toml", NULL, 0, CD_EINVAL,
               "arrays.toml:8:66: expected values nested at most 64 levels deep (table header names, dotted key names, "
               "arrays and inline tables together), got deeper");
    /* each {a.b = adds two levels: the key of the 31st (column 216) reaches 65 */
    long_line(dir, "inline.toml", "x = ", "{a.b = ", 20000, "");
    expect_msg(dir, "inline.toml", NULL, 0, CD_EINVAL,
               "inline.toml:8:216: expected values nested at most 64 levels deep (table header names, dotted key "
               "names, arrays and inline tables together), got deeper");
    /* x = 63 nested arrays at the top (depth 1 + 63): within the bound,
     * toml++ and the schema take it */
    {
        char path[1024];
        FILE *f;
        int i;
        snprintf(path, sizeof path, "%s/deep_ok.toml", dir);
        f = fopen(path, "w");
        cr_assert_not_null(f);
        fputs("x = ", f);
        for (i = 0; i < 63; i++) fputc('[', f);
        for (i = 0; i < 63; i++) fputc(']', f);
        fprintf(f, "\n%s", BALL);
        fclose(f);
        expect_msg(dir, "deep_ok.toml", NULL, 0, CD_EINVAL,
                   "deep_ok.toml:1:1: key 'x': unknown key (expected one of: 'title', 'include', 'simulation', "
                   "'contact', 'system', 'target', 'pair', 'gripper', 'actuator', 'capture', 'control')");
    }
    lu_rm_rf(dir);
}

Test(loader_limits, brackets_in_strings_and_comments_do_not_count)
{
    /* 200 '[' and 200 dots inside strings and comments are text, not nesting */
    char dir[64], path[1024];
    cd_error err;
    cd_scenario *sc;
    FILE *f;
    int i;
    lu_tmpdir(dir, sizeof dir);
    snprintf(path, sizeof path, "%s/s.toml", dir);
    f = fopen(path, "w");
    cr_assert_not_null(f);
    fputs("title = \"", f);
    for (i = 0; i < 200; i++) fputs("[.", f);
    fputs("\"\n# ", f);
    for (i = 0; i < 200; i++) fputs("{a.", f);
    fputs("\n'''x'''\n", f); /* leave it as a syntax error after a literal string: not our business */
    fclose(f);
    sc = lu_load_small_stack(path, NULL, 0, &err);
    cr_assert_null(sc);
    cr_expect(strstr(err.msg, "s.toml:3:") && strstr(err.msg, "TOML syntax error"), "%s", err.msg);
    /* the same title in a valid file loads */
    f = fopen(path, "w");
    fputs("title = \"", f);
    for (i = 0; i < 200; i++) fputs("[.", f);
    fprintf(f, "\"\n%s", BALL);
    fclose(f);
    sc = lu_load_small_stack(path, NULL, 0, &err);
    cr_assert_not_null(sc, "%s", err.msg);
    cr_expect_eq(strlen(sc->title), 400u);
    cd_scenario_free(sc);
    lu_rm_rf(dir);
}

/* ---- overrides ---- */

Test(loader_limits, overrides_with_a_huge_index_a_long_path_or_a_deep_value)
{
    char dir[64];
    const char *big[] = {"system[99999999999999].mass=1"};
    const char *huge[] = {"system[99999999999999999999999999].mass=1"};
    const char *fits[] = {"system[999999999].mass=1"};
    static char longpath[256];
    const char *lp[] = {longpath};
    static char deep[512];
    const char *dv[] = {deep};
    int i;
    lu_tmpdir(dir, sizeof dir);
    lu_write(dir, "b.toml", "%s", BALL);
    expect_msg(dir, "b.toml", big, 1, CD_EINVAL,
               "--set 'system[99999999999999].mass=1': bad index [99999999999999] in key path "
               "'system[99999999999999].mass' (expected [N], 0 <= N < 10^9)");
    expect_msg(dir, "b.toml", huge, 1, CD_EINVAL,
               "--set 'system[99999999999999999999999999].mass=1': bad index [99999999999999999999999999] in key path "
               "'system[99999999999999999999999999].mass' (expected [N], 0 <= N < 10^9)");
    expect_msg(dir, "b.toml", fits, 1, CD_EINVAL,
               "--set 'system[999999999].mass=1': key 'system': index [999999999] out of range (the array has 1 "
               "elements)");
    strcpy(longpath, "a");
    for (i = 0; i < 40; i++) strcat(longpath, ".a");
    strcat(longpath, "=1");
    {
        char want[1024];
        snprintf(want, sizeof want, "--set '%s': expected a key path of at most 32 names, got 41", longpath);
        expect_msg(dir, "b.toml", lp, 1, CD_EINVAL, want);
    }
    strcpy(deep, "title=");
    for (i = 0; i < 100; i++) strcat(deep, "[");
    {
        char want[1024];
        snprintf(want, sizeof want,
                 "--set '%s': expected values nested at most 64 levels deep (table header names, dotted key names, "
                 "arrays and inline tables together), got deeper",
                 deep);
        expect_msg(dir, "b.toml", dv, 1, CD_EINVAL, want);
    }
    lu_rm_rf(dir);
}

/* ---- messages ---- */

Test(loader_limits, control_characters_are_escaped_in_messages)
{
    /* a name with a newline, an ESC sequence, a TAB and a C1 control (U+009B) */
    char dir[64];
    cd_error err;
    cd_scenario *sc;
    char path[1024];
    lu_tmpdir(dir, sizeof dir);
    lu_write(dir, "e.toml", "[simulation]\nduration = 1\n[[system]]\nname = \"a\\nb\\u001b[2J\\tc\\u009b\"\nmass = 1\n"
                            "inertia = [1, 1, 1]\n");
    snprintf(path, sizeof path, "%s/e.toml", dir);
    sc = lu_load_small_stack(path, NULL, 0, &err);
    cr_assert_null(sc);
    {
        char want[1024];
        snprintf(want, sizeof want,
                 "%s/e.toml:4:8: key 'system[0].name': expected a name made of letters, digits, '_' and '-', got "
                 "'a\\nb\\x1b[2J\\tc\\u009b'",
                 dir);
        cr_expect_str_eq(err.msg, want);
    }
    lu_rm_rf(dir);
}

Test(loader_limits, degenerate_hull_reported_at_its_key)
{
    char dir[64];
    lu_tmpdir(dir, sizeof dir);
    lu_write(dir, "h.toml", "%s\n[[system.shape]]\nname = \"flat\"\ntype = \"convex\"\n"
                            "vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0.5, 0.5, 0]]\n",
             BALL);
    expect_msg(dir, "h.toml", NULL, 0, CD_EINVAL,
               "h.toml:12:12: key 'system[0].shape[0].vertices': expected vertices spanning a volume (not all on one "
               "plane), got points on one plane (thickness 0 m for a size of 0.707106781186548 m)");
    lu_write(dir, "l.toml", "%s\n[[system.shape]]\nname = \"line\"\ntype = \"convex\"\n"
                            "vertices = [[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]]\n",
             BALL);
    expect_msg(dir, "l.toml", NULL, 0, CD_EINVAL,
               "l.toml:12:12: key 'system[0].shape[0].vertices': expected vertices spanning a volume (not all on one "
               "plane), got points on one line");
    lu_rm_rf(dir);
}

/* ---- the work of a run ---- */

Test(loader_limits, duration_1e300_is_refused_by_the_work_budget)
{
    char dir[64];
    const char *lift[] = {"simulation.max_rhs_evals=0", "simulation.output_dt=1e292"};
    char path[1024];
    cd_error err;
    cd_scenario *sc;
    lu_tmpdir(dir, sizeof dir);
    lu_write(dir, "long.toml", "[simulation]\nduration = 1e300\n[[system]]\nname = \"b\"\nmass = 1\ninertia = [1, 1, 1]\n");
    /* default auto, h_max 1e-2 s: 1e302 steps of at least 2 evaluations (its stiff stepper's, msbdf: a
     * Newton iteration and the end derivative) */
    expect_msg(dir, "long.toml", NULL, 0, CD_EINVAL,
               "long.toml:2:12: key 'simulation.duration': expected a run within max_rhs_evals = 1000000000 "
               "right-hand-side evaluations, got one needing at least 2e+302 (1e+302 steps of at most h_max = 0.01 "
               "s, 2 evaluations each, for duration = 1e+300 s); shorten the duration or raise "
               "simulation.max_rhs_evals");
    /* max_rhs_evals = 0 lifts the bound; the estimate is still reported */
    snprintf(path, sizeof path, "%s/long.toml", dir);
    sc = lu_load_small_stack(path, lift, 2, &err);
    cr_assert_not_null(sc, "%s", err.msg);
    cr_expect_eq(sc->max_rhs_evals, 0.0);
    cr_expect(fabs(sc->min_steps / 1e302 - 1) < 1e-12, "%g", sc->min_steps);
    cr_expect(fabs(sc->min_rhs_evals / 2e302 - 1) < 1e-12, "%g", sc->min_rhs_evals);
    cr_expect_eq(sc->max_wall_time, 3600.0);
    cd_scenario_free(sc);
    lu_rm_rf(dir);
}

Test(loader_limits, run_stops_when_its_evaluation_budget_is_spent, .timeout = 60)
{
    /* a ball falling for 100 s (rkf45, h_max 1e-3 s: >= 1e5 steps, 5e5
     * evaluations) with max_rhs_evals = 6e5: check accepts it, run stops
     * at the budget with exit status 1, the one error line saying so, and the
     * file keeps the samples */
    char dir[64], *out = NULL, *err = NULL;
    int rc;
    lu_tmpdir(dir, sizeof dir);
    lu_write(dir, "fall.toml", "[simulation]\nduration = 100\nintegrator = \"rkf45\"\nh_max = 1e-3\noutput_dt = 1\n"
                               "max_rhs_evals = 6e5\ngravity = [0, 0, -9.81]\n[[system]]\nname = \"b\"\nmass = 1\n"
                               "inertia = [1, 1, 1]\n");
    {
        const char *a[] = {"check", "fall.toml", NULL};
        rc = lu_capdyn(dir, &out, &err, a);
        cr_expect_eq(rc, 0, "%s", err);
        cr_expect(out && strstr(out, "\nwork: at least 100000 steps and 500000 right-hand-side evaluations; budget: "
                                     "max_rhs_evals 600000, max_wall_time 3600 s\n"),
                  "%s", out);
        free(out);
        free(err);
    }
    {
        const char *a[] = {"run", "fall.toml", "-o", "fall.h5", "-q", NULL};
        rc = lu_capdyn(dir, &out, &err, a);
        cr_expect_eq(rc, 1);
        cr_expect(err && strstr(err, "capdyn: error: run failed (interrupted): work budget spent: ") == err &&
                      strstr(err, " right-hand-side evaluations, more than simulation.max_rhs_evals = 600000, at t = ") &&
                      strchr(err, '\n') == err + strlen(err) - 1,
                  "%s", err);
        free(out);
        free(err);
    }
    lu_rm_rf(dir);
}

Test(loader_limits, a_run_whose_steps_collapse_stops_at_its_pace_not_after_its_budget, .timeout = 120)
{
    /* tumbling_target with a gravity of 1e19 m/s^2: every value passes the
     * loader, but the satellite's speed grows by 1e19 m/s every second and
     * the steps fall to ~1e-10 s, some 1e11 steps for the 20 s. With
     * max_wall_time = 20 s the pace check looks after 0.2 s (a hundredth of
     * the budget) and stops the run there, as the projection (some 1e5 s)
     * is far above 10 x 20 s, instead of after the 20 s the budget allows:
     * exit status 1, one error line naming the pace and the budget, the
     * samples so far kept */
    char dir[64], scen[1024], *out = NULL, *err = NULL;
    int rc;
    lu_tmpdir(dir, sizeof dir);
    snprintf(scen, sizeof scen, "%s/scenarios/tumbling_target.toml", lu_root());
    {
        const char *a[] = {"run", scen, "--set", "simulation.gravity=[0,0,1e19]", "--set",
                           "simulation.max_wall_time=20", "-o", "crawl.h5", "-q", NULL};
        rc = lu_capdyn(dir, &out, &err, a);
    }
    cr_expect_eq(rc, 1, "%s", err);
    cr_expect(err && strstr(err, "capdyn: error: run failed (interrupted): work budget: at its pace so far (t = ") == err &&
                  strstr(err, " more than 10 x simulation.max_wall_time = 20 s; stopped early (0 lifts the budget); "
                              "results up to t = ") &&
                  strstr(err, " kept in 'crawl.h5'\n") && strchr(err, '\n') == err + strlen(err) - 1,
              "%s", err);
    free(out);
    free(err);
    {
        /* the file holds the committed samples (t = 0 at least) */
        const char *a[] = {"info", "crawl.h5", NULL};
        rc = lu_capdyn(dir, &out, &err, a);
        cr_expect_eq(rc, 0, "%s", err);
        cr_expect(out && strstr(out, "status      interrupted: work budget: at its pace so far"), "%s", out);
        free(out);
        free(err);
    }
    lu_rm_rf(dir);
}

Test(loader_limits, a_file_included_again_and_again_is_bounded)
{
    /* b.toml holds 20 000 check points (100 000 values); main includes it
     * 200 times: 2e7 values to copy, refused at the include that passes 1e7 */
    char dir[64], path[1024], msg[1024];
    FILE *f;
    int i;
    lu_tmpdir(dir, sizeof dir);
    snprintf(path, sizeof path, "%s/b.toml", dir);
    f = fopen(path, "w");
    cr_assert_not_null(f);
    fputs("[[system]]\nname = \"ball\"\ncheckpoints = [", f);
    for (i = 0; i < 20000; i++) fputs("[0, 0, 0, 0],", f);
    fputs("]\n", f);
    fclose(f);
    snprintf(path, sizeof path, "%s/main.toml", dir);
    f = fopen(path, "w");
    cr_assert_not_null(f);
    fputs("include = [", f);
    for (i = 0; i < 200; i++) fputs("\"b.toml\", ", f);
    fprintf(f, "]\n%s", BALL);
    fclose(f);
    /* the first include is read, the next ones are copies of 100 005 values
     * each (20 000 rows of 1 + 4, the system table, its entries): the 100th
     * copy (include[100], column 12 + 10 * 100) passes 1e7 */
    snprintf(msg, sizeof msg,
             "main.toml:1:1012: key 'include[100]': expected includes that repeat at most 10^7 values in all, got more "
             "(file '%s/b.toml' included again and again)",
             dir);
    expect_msg(dir, "main.toml", NULL, 0, CD_EINVAL, msg);
    lu_rm_rf(dir);
}

Test(loader_limits, convex_vertices_bounded_per_shape_and_in_all)
{
    /* 17 convex shapes of 128 vertices: the 17th (its vertices on line
     * 8 + 3 + 4 * 16 = 75) passes 2048 in all */
    char dir[64], path[1024];
    FILE *f;
    int s, i;
    lu_tmpdir(dir, sizeof dir);
    snprintf(path, sizeof path, "%s/h.toml", dir);
    f = fopen(path, "w");
    cr_assert_not_null(f);
    fputs(BALL, f);
    for (s = 0; s < 17; s++) {
        fprintf(f, "[[system.shape]]\nname = \"h%d\"\ntype = \"convex\"\nvertices = [", s);
        for (i = 0; i < 128; i++) fprintf(f, "[%d, %d, %d], ", i % 4, (i / 4) % 4, i / 16);
        fputs("]\n", f);
    }
    fclose(f);
    expect_msg(dir, "h.toml", NULL, 0, CD_EINVAL,
               "h.toml:75:12: key 'system[0].shape[16].vertices': expected at most 2048 vertices in all convex shapes "
               "together, got 2176 with this one");
    lu_rm_rf(dir);
}
