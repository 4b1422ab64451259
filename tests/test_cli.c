/* The capdyn command end to end (issue 4): run -> HDF5 -> info/export ->
 * gnuplot, plus the failure paths (SIGKILL, signals, unwritable output, bad
 * arguments, integrator failure).
 *
 * Environment: CAPDYN_BIN the binary (default build/capdyn), CAPDYN_ROOT the
 * repository (default .), as `make test` sets them. Each test works in its
 * own temporary directory. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include <capdyn/io.h>
#include <hdf5.h>
#include <gsl/gsl_errno.h>
#include "../src/io/h5_util.h"
#include "h5_test_util.h"
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static const double PI = 3.14159265358979323846;

/* ---- helpers ---------------------------------------------------------------- */
#include "proc_util.h"


/* A ball of 1 kg and radius 0.1 m at 1 m/s toward a fixed wall (the plane
 * x = 0, outward normal -x), 5 mm away; an undamped linear contact K = 1e4
 * N/m, no gravity. Closed form (linear spring, D = 0): contact from t = 5 ms
 * for pi sqrt(m/K) = 31.4159 ms, then the ball leaves at exactly -1 m/s. */
static const char *ball_toml =
    "title = \"test: undamped ball against a wall\"\n"
    "[simulation]\n"
    "duration = 0.06\n"
    "gravity = [0.0, 0.0, 0.0]\n"
    "integrator = \"rk8pd\"\n"
    "rtol = 1e-11\n"
    "atol = 1e-13\n"
    "h_max = 1e-3\n"
    "output_dt = 1e-3\n"
    "[contact]\n"
    "K = 1e4\n"
    "D = 0.0\n"
    "mu_max = 0.5\n"
    "mu = 0.5\n"
    "[[system]]\n"
    "name = \"ball\"\n"
    "base = \"free\"\n"
    "mass = 1.0\n"
    "inertia = [0.004, 0.004, 0.004]\n"
    "position = [-0.105, 0.0, 0.0]\n"
    "velocity = [1.0, 0.0, 0.0]\n"
    "checkpoints = [[0.0, 0.0, 0.0, 0.1]]\n"
    "[[system]]\n"
    "name = \"wall\"\n"
    "base = \"fixed\"\n"
    "  [[system.shape]]\n"
    "  name = \"face\"\n"
    "  type = \"plane\"\n"
    "  normal = [-1.0, 0.0, 0.0]\n"
    "[[pair]]\n"
    "checkpoints = \"ball\"\n"
    "shape = \"wall/face\"\n";

static void write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    cr_assert_not_null(f, "%s", path);
    fputs(text, f);
    fclose(f);
}

/* Parses an export: the first line "# a b c" names the columns; every
 * other non-empty line that is not a comment must have that many tokens.
 * Returns the number of data rows (-1 on a bad row); *ncol the column count. */
static long parse_columns(const char *text, int *ncol)
{
    const char *p = text, *eol;
    long rows = 0;
    int first = 1;
    *ncol = 0;
    while (*p) {
        char line[8192];
        size_t n;
        int k = 0;
        char *tok, *save;
        eol = strchr(p, '\n');
        n = eol ? (size_t)(eol - p) : strlen(p);
        if (n >= sizeof line) n = sizeof line - 1;
        memcpy(line, p, n);
        line[n] = 0;
        p = eol ? eol + 1 : p + n;
        if (first) {
            cr_assert(line[0] == '#' && line[1] == ' ', "the first line is a '# ' header: '%s'", line);
            for (tok = strtok_r(line + 2, " ", &save); tok; tok = strtok_r(NULL, " ", &save)) (*ncol)++;
            first = 0;
            continue;
        }
        if (line[0] == '#' || line[0] == 0) continue;
        for (tok = strtok_r(line, " \t", &save); tok; tok = strtok_r(NULL, " \t", &save)) k++;
        if (k != *ncol) {
            cr_log_error("row %ld has %d columns, header %d", rows, k, *ncol);
            return -1;
        }
        rows++;
    }
    return rows;
}

/* ---- end to end ----------------------------------------------------------- */
Test(cli, run_reads_back_shapes_and_the_impact_rebound)
{
    /* The ball scenario above: 0.06 s at 1 ms = 61 samples. Physical figures
     * against the closed form of the undamped linear contact: onset at 5 ms
     * (1e-9 s: events are located to 1e-10 s), contact duration pi/100 s
     * (1e-8 relative), rebound velocity -1 m/s (1e-7 relative: rk8pd at
     * rtol 1e-11; energy is conserved by the undamped spring). */
    char dir[64], toml[256], h5[256], *out = NULL, *err = NULL, s[128];
    hid_t f, ds, ct;
    hsize_t d[3];
    size_t n;
    double *vel, *t;
    typedef struct { double t; int kind; } ev_t;
    ev_t ev[8];
    int rc;
    make_tmpdir(dir, sizeof dir);
    snprintf(toml, sizeof toml, "%s/ball.toml", dir);
    snprintf(h5, sizeof h5, "%s/ball.h5", dir);
    write_file(toml, ball_toml);
    rc = capdyn(dir, &out, &err, "run", toml, "-o", h5, (char *)NULL);
    cr_assert_eq(rc, 0, "exit %d, stderr: %s", rc, err);
    cr_expect(strstr(out, "status      ok") != NULL, "summary shows the status: %s", out);
    cr_expect(strstr(out, "onset 1") && strstr(out, "separation 1"), "events by kind in the summary: %s", out);
    cr_expect(strstr(out, "peak fn over steps") != NULL && strstr(out, "peak fn at samples") != NULL, "%s", out);
    cr_expect(strstr(out, "momentum") != NULL && strstr(out, "energy") != NULL);
    free(out);
    free(err);

    f = open_ro(h5);
    cr_assert(f >= 0, "the results file opens");
    cr_expect_eq(attr_ll(f, "committed_samples"), 61);
    cr_expect_eq(dims_of(f, "/time", d), 1);
    cr_expect_eq(d[0], 61);
    cr_expect_eq(dims_of(f, "/systems/ball/base_pos", d), 2);
    cr_expect(d[0] == 61 && d[1] == 3);
    cr_expect_eq(dims_of(f, "/systems/ball/base_quat", d), 2);
    cr_expect(d[1] == 4);
    cr_expect_eq(dims_of(f, "/systems/ball/body_x", d), 3);
    cr_expect(d[0] == 61 && d[1] == 1 && d[2] == 3);
    cr_expect_eq(dims_of(f, "/contacts/fn", d), 2);
    cr_expect(d[0] == 61 && d[1] == 1);
    cr_expect_eq(dims_of(f, "/contacts/ft", d), 3);
    cr_expect(d[0] == 61 && d[1] == 1 && d[2] == 3);
    cr_expect_eq(dims_of(f, "/diagnostics/kinetic_energy", d), 2);
    cr_expect(d[0] == 61 && d[1] == 2);
    attr_s(f, "title", s, sizeof s);
    cr_expect_str_eq(s, "test: undamped ball against a wall");
    attr_s(f, "capdyn_version", s, sizeof s);
    cr_expect_str_eq(s, cd_version());
    attr_s(f, "run_status", s, sizeof s);
    cr_expect_str_eq(s, cd_status_string(CD_OK));
    {
        char *txt;
        hid_t a = H5Aopen(f, "scenario_text", H5P_DEFAULT), ty = H5Aget_type(a), mt = H5Tcopy(ty);
        size_t sz = H5Tget_size(ty);
        H5Tset_size(mt, sz);
        txt = calloc(1, sz + 1);
        H5Aread(a, mt, txt);
        cr_expect(strstr(txt, "checkpoints = \"ball\"") != NULL, "the scenario text is stored");
        free(txt);
        H5Tclose(mt);
        H5Tclose(ty);
        H5Aclose(a);
    }
    /* events: onset then separation */
    ds = H5Dopen2(f, "/events", H5P_DEFAULT);
    dims_of(f, "/events", d);
    cr_assert_eq(d[0], 2, "one onset, one separation");
    {
        hid_t ft = H5Dget_type(ds), kt = H5Tget_member_type(ft, (unsigned)H5Tget_member_index(ft, "kind"));
        ct = H5Tcreate(H5T_COMPOUND, sizeof(ev_t));
        H5Tinsert(ct, "t", HOFFSET(ev_t, t), H5T_NATIVE_DOUBLE);
        H5Tinsert(ct, "kind", HOFFSET(ev_t, kind), kt);
        cr_assert(H5Dread(ds, ct, H5S_ALL, H5S_ALL, H5P_DEFAULT, ev) >= 0);
        H5Tclose(kt);
        H5Tclose(ft);
        H5Tclose(ct);
    }
    H5Dclose(ds);
    cr_expect_eq(ev[0].kind, CD_EV_ONSET);
    cr_expect_eq(ev[1].kind, CD_EV_SEPARATION);
    cr_expect_lt(fabs(ev[0].t - 0.005), 1e-9, "onset at %.12g s", ev[0].t);
    cr_expect_lt(fabs((ev[1].t - ev[0].t) - PI / 100.0) / (PI / 100.0), 1e-8, "contact lasted %.12g s, closed form %.12g s",
                 ev[1].t - ev[0].t, PI / 100.0);
    vel = read_all(f, "/systems/ball/base_vel", &n);
    t = read_all(f, "/time", &n);
    cr_assert_eq(n, 61);
    cr_expect_eq(t[60], 0.06);
    cr_expect_lt(fabs(vel[3 * 60] + 1.0), 1e-7, "rebound velocity %.12g m/s, closed form -1", vel[3 * 60]);
    cr_log_info("ball: onset %.12g s, contact %.12g s (exact %.12g), rebound %.12g m/s", ev[0].t, ev[1].t - ev[0].t,
                PI / 100.0, vel[3 * 60]);
    free(vel);
    free(t);
    H5Fclose(f);
    rm_rf(dir);
}

Test(cli, free_floating_arm_conserves_momentum_in_the_file)
{
    /* scenarios/free_floating_arm.toml: one free-floating system, internal
     * joint torques only, no gravity. The stored momentum stays at its start
     * value within 1e-10 of the scale sqrt(2 M T_max) (issue 2, test 3). */
    char dir[64], sc[512], h5[256], *out = NULL, *err = NULL;
    hid_t f;
    size_t n, nk, i;
    double *P, *ke, M = 0, Tmax = 0, dP = 0, P0[3];
    int rc, a;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "free_floating_arm.toml");
    snprintf(h5, sizeof h5, "%s/arm.h5", dir);
    rc = capdyn(dir, &out, &err, "run", sc, "-o", h5, "--quiet", (char *)NULL);
    cr_assert_eq(rc, 0, "exit %d: %s", rc, err);
    cr_expect_eq(out ? strlen(out) : 0, 0, "--quiet prints nothing on success: %s", out);
    free(out);
    free(err);
    f = open_ro(h5);
    cr_assert(f >= 0);
    {
        cd_error e;
        cd_scenario *s = cd_scenario_load(sc, NULL, 0, &e);
        cr_assert_not_null(s, "%s", e.msg);
        cr_assert_eq(s->model->nsys, 1);
        for (i = 0; i < (size_t)s->model->nbody; i++) M += s->model->body_mass[i];
        cd_scenario_free(s);
    }
    P = read_all(f, "/diagnostics/momentum", &n);
    ke = read_all(f, "/diagnostics/kinetic_energy", &nk);
    cr_assert_eq(n, 3 * nk);
    memcpy(P0, P, sizeof P0);
    for (i = 0; i < nk; i++) {
        double d3[3];
        if (ke[i] > Tmax) Tmax = ke[i];
        for (a = 0; a < 3; a++) d3[a] = P[3 * i + a] - P0[a];
        if (sqrt(d3[0] * d3[0] + d3[1] * d3[1] + d3[2] * d3[2]) > dP) dP = sqrt(d3[0] * d3[0] + d3[1] * d3[1] + d3[2] * d3[2]);
    }
    cr_assert_gt(Tmax, 0, "the arm moves");
    cr_expect_lt(dP, 1e-10 * sqrt(2 * M * Tmax), "|P - P0| = %.3e, scale %.3e", dP, sqrt(2 * M * Tmax));
    cr_log_info("free-floating arm: |P - P0| max %.3e kg m/s, scale sqrt(2 M T) %.3e", dP, sqrt(2 * M * Tmax));
    free(P);
    free(ke);
    H5Fclose(f);
    rm_rf(dir);
}

/* capdyn run of a shipped scenario (with one --set, or none) into a fresh
 * directory: its summary (stdout), the directory removed */
static char *summary_of(const char *scenario, const char *set)
{
    char dir[64], sc[512], h5[256], *out = NULL, *err = NULL;
    int rc;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, scenario);
    snprintf(h5, sizeof h5, "%s/run.h5", dir);
    rc = set ? capdyn(dir, &out, &err, "run", sc, "--set", set, "-o", h5, (char *)NULL)
             : capdyn(dir, &out, &err, "run", sc, "-o", h5, (char *)NULL);
    cr_assert_eq(rc, 0, "%s: exit %d: %s", scenario, rc, err);
    free(err);
    rm_rf(dir);
    return out;
}

Test(cli, the_summary_states_an_initial_overlap)
{
    /* scenarios/soft_wrap.toml starts with 16 check points of the fingers
     * inside the prism, the deepest 7.62 mm (slot 295, finger 1's second
     * link): the summary says so, with the deepest one. Fig. 3's scene starts
     * apart and then makes contact: no such line. */
    char *wrap = summary_of("soft_wrap.toml", "simulation.duration=0.001"), *fig3 = summary_of("paper_fig3_impact.toml", NULL);
    cr_expect(wrap && strstr(wrap, "initial overlap  16 check points inside their shapes at the first sample, t = 0 s") &&
                  strstr(wrap, "(deepest 7.62 mm: slot 295, hand/f1_l1 cp 79 -> object (convex))"),
              "%s", wrap);
    cr_expect(fig3 && strstr(fig3, "in contact at some time") && !strstr(fig3, "initial overlap"), "%s", fig3);
    free(wrap);
    free(fig3);
}

Test(cli, export_columns_parse)
{
    /* Every export of the ball run: a '# ' header, then rows with exactly
     * the header's number of columns; row counts from the file (61 samples,
     * 2 events, 1 slot); --every 10 keeps samples 0, 10, .., 60 = 7 rows. */
    char dir[64], toml[256], h5[256], *out = NULL;
    int ncol, rc;
    long rows;
    make_tmpdir(dir, sizeof dir);
    snprintf(toml, sizeof toml, "%s/ball.toml", dir);
    snprintf(h5, sizeof h5, "%s/ball.h5", dir);
    write_file(toml, ball_toml);
    cr_assert_eq(capdyn(dir, NULL, NULL, "run", toml, "-o", h5, "--quiet", (char *)NULL), 0);
#define EXPORT(expect_rows, expect_cols, ...)                                                           \
    do {                                                                                                  \
        rc = capdyn(dir, &out, NULL, "export", h5, __VA_ARGS__, (char *)NULL);                            \
        cr_assert_eq(rc, 0, "export " #__VA_ARGS__ " exit %d", rc);                                     \
        rows = parse_columns(out, &ncol);                                                                 \
        cr_expect_eq(rows, expect_rows, "export " #__VA_ARGS__ ": %ld rows", rows);                     \
        cr_expect_eq(ncol, expect_cols, "export " #__VA_ARGS__ ": %d columns", ncol);                   \
        free(out);                                                                                        \
    } while (0)
    EXPORT(61, 1, "time");
    EXPORT(7, 1, "time", "--every", "10");
    EXPORT(61, 14, "system", "ball");       /* t + 3 + 4 + 3 + 3, no joints */
    EXPORT(61, 8, "contacts");               /* t nopen nstick nslip fn_sum + 3 per slot */
    EXPORT(61, 8, "contacts", "--active");
    EXPORT(61, 19, "slot", "0");
    EXPORT(1, 10, "slots");
    EXPORT(2, 13, "events"); /* ... body_a body_b owner_kind owner */
    EXPORT(61, 22, "diagnostics");
    EXPORT(61, 22, "diagnostics", "ball");
    EXPORT(3, 10, "checkpoints", "--frames", "3");
#undef EXPORT
    /* outline: one frame per --at time, each a block of polylines */
    rc = capdyn(dir, &out, NULL, "export", h5, "outline", "--at", "0,end", (char *)NULL);
    cr_assert_eq(rc, 0);
    rows = parse_columns(out, &ncol);
    cr_expect_eq(ncol, 4);
    cr_expect_gt(rows, 4, "the wall is drawn (%ld rows)", rows);
    cr_expect(strstr(out, "# frame 1 sample 60 t 0.06") != NULL, "'end' is the last sample");
    free(out);
    rm_rf(dir);
}

/* ---- crash safety and signals ------------------------------------------------- */
/* A long run of the Fig. 5 scenario (100 s simulated, several seconds of wall
 * time) committing every 0.3 s of wall time (output every 10 ms, so the
 * 1024-row buffer never forces extra commits). */
static pid_t start_long_run(const char *dir, const char *h5)
{
    static char sc[512];
    char *argv[16];
    int n = 0;
    scen(sc, sizeof sc, "paper_fig5_envelope_grasp.toml");
    argv[n++] = (char *)bin();
    argv[n++] = (char *)"run";
    argv[n++] = sc;
    argv[n++] = (char *)"-o";
    argv[n++] = (char *)h5;
    argv[n++] = (char *)"--set";
    argv[n++] = (char *)"simulation.duration=100";
    argv[n++] = (char *)"--set";
    argv[n++] = (char *)"simulation.output_dt=0.01";
    argv[n++] = (char *)"--set";
    argv[n++] = (char *)"simulation.flush_every=0.3";
    argv[n] = NULL;
    return spawn(dir, argv, NULL);
}

/* Waits until the committed counter changes to a value > 0 (a commit just
 * finished); returns it. */
static long long wait_for_commit(const char *h5, pid_t pid)
{
    double t0 = now();
    long long c0 = -1, c;
    while (now() - t0 < 30.0) {
        int st;
        cr_assert_eq(waitpid(pid, &st, WNOHANG), 0, "the run ended early");
        c = peek_committed(h5);
        if (c > 0 && c0 >= 0 && c != c0) return c;
        if (c >= 0) c0 = c;
        sleep_s(0.01);
    }
    cr_assert_fail("no commit within 30 s");
    return -1;
}

Test(cli, sigkill_leaves_a_readable_file, .timeout = 60)
{
    /* Kill -9 a run 0.1 s after a commit (the next is due 0.3 s after it):
     * h5dump -H reads the file, capdyn info and export work and report only
     * the committed samples, whose times increase and stay below the end. */
    char dir[64], h5[256], *out = NULL, *err = NULL, cmd[600];
    pid_t pid;
    long long seen, c;
    hid_t f;
    hsize_t d[3];
    size_t n, i;
    double *t;
    int rc, ncol;
    make_tmpdir(dir, sizeof dir);
    snprintf(h5, sizeof h5, "%s/killed.h5", dir);
    pid = start_long_run(dir, h5);
    seen = wait_for_commit(h5, pid);
    sleep_s(0.1);
    cr_assert_eq(kill(pid, SIGKILL), 0);
    cr_assert_eq(wait_status(pid), 128 + SIGKILL);

    snprintf(cmd, sizeof cmd, "h5dump -H '%s' > '%s/h5dump.txt' 2>&1", h5, dir);
    rc = system(cmd);
    cr_expect_eq(rc, 0, "h5dump -H reads the killed file (status %d)", rc);
    f = open_ro(h5);
    cr_assert(f >= 0, "HDF5 opens the killed file");
    c = attr_ll(f, "committed_samples");
    cr_expect_geq(c, seen, "committed %lld >= the %lld seen before the kill", c, seen);
    dims_of(f, "/time", d);
    cr_expect_geq((long long)d[0], c, "rows on disk %llu >= committed %lld", (unsigned long long)d[0], c);
    t = read_all(f, "/time", &n);
    for (i = 1; i < (size_t)c; i++) cr_assert_gt(t[i], t[i - 1], "time increases at %zu", i);
    cr_expect_lt(t[c - 1], 100.0);
    {
        char s[64];
        attr_s(f, "run_status", s, sizeof s);
        cr_expect_str_eq(s, "running", "a killed run never wrote its final status");
    }
    free(t);
    H5Fclose(f);

    rc = capdyn(dir, &out, &err, "info", h5, (char *)NULL);
    cr_expect_eq(rc, 0, "capdyn info on the killed file: %s", err);
    cr_expect(out && strstr(out, "unfinished") != NULL, "info says the run did not finish: %s", out);
    free(out);
    free(err);
    rc = capdyn(dir, &out, NULL, "export", h5, "time", (char *)NULL);
    cr_expect_eq(rc, 0);
    cr_expect_eq(parse_columns(out, &ncol), c, "export gives the committed samples only");
    free(out);
    cr_log_info("SIGKILL: %lld samples committed, file readable", c);
    rm_rf(dir);
}

static void signal_stops_cleanly(int sig)
{
    /* SIGINT / SIGTERM: the run stops at the next step, appends its last
     * state, closes the file with status "interrupted" and exits 130. */
    char dir[64], h5[256], s[128], *err;
    pid_t pid;
    hid_t f;
    hsize_t d[3];
    size_t n;
    double *t, tf;
    int rc;
    make_tmpdir(dir, sizeof dir);
    snprintf(h5, sizeof h5, "%s/stopped.h5", dir);
    pid = start_long_run(dir, h5);
    wait_for_commit(h5, pid);
    cr_assert_eq(kill(pid, sig), 0);
    rc = wait_status(pid);
    snprintf(s, sizeof s, "%s/err.txt", dir);
    err = slurp(s);
    cr_expect_eq(rc, 130, "exit status %d; stderr: %s", rc, err);
    cr_expect(err && strstr(err, sig == SIGINT ? "SIGINT" : "SIGTERM"), "stderr names the signal: %s", err);
    free(err);
    f = open_ro(h5);
    cr_assert(f >= 0);
    attr_s(f, "run_status", s, sizeof s);
    cr_expect_str_eq(s, cd_status_string(CD_EINTERRUPT));
    dims_of(f, "/time", d);
    cr_expect_eq((long long)d[0], attr_ll(f, "committed_samples"), "a closed file has every row committed");
    t = read_all(f, "/time", &n);
    tf = attr_d(f, "t_final");
    cr_expect_eq(t[n - 1], tf, "the last sample is the state where it stopped (%.9g vs %.9g)", t[n - 1], tf);
    cr_expect_lt(tf, 100.0);
    free(t);
    H5Fclose(f);
    rm_rf(dir);
}

Test(cli, sigint_stops_cleanly, .timeout = 60) { signal_stops_cleanly(SIGINT); }
Test(cli, sigterm_stops_cleanly, .timeout = 60) { signal_stops_cleanly(SIGTERM); }

/* ---- failures ------------------------------------------------------------------- */
Test(cli, unwritable_output_fails_before_the_run)
{
    /* A 1000 s run into a directory that does not exist: exit 1 within 5 s
     * (a run would take minutes), the message names the path, nothing made. */
    char dir[64], sc[512], *err = NULL;
    const char *bad = "/nonexistent_capdyn_dir/sub/out.h5";
    double t0;
    int rc;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "paper_fig5_envelope_grasp.toml");
    t0 = now();
    rc = capdyn(dir, NULL, &err, "run", sc, "-o", bad, "--set", "simulation.duration=1000", (char *)NULL);
    cr_expect_eq(rc, 1, "exit %d", rc);
    cr_expect_lt(now() - t0, 5.0, "failed before running");
    cr_expect(err && strncmp(err, "capdyn: error: ", 15) == 0, "stderr: %s", err);
    cr_expect(err && strstr(err, bad) != NULL, "the message names the path: %s", err);
    cr_expect(err && strchr(err, '\n') == err + strlen(err) - 1, "one line: %s", err);
    cr_expect_neq(access(bad, F_OK), 0);
    free(err);
    /* a path whose parent is a regular file */
    {
        char badf[300];
        snprintf(badf, sizeof badf, "%s/err.txt/out.h5", dir);
        rc = capdyn(dir, NULL, &err, "run", sc, "-o", badf, (char *)NULL);
        cr_expect_eq(rc, 1);
        free(err);
    }
    rm_rf(dir);
}

Test(cli, integrator_failure_keeps_the_data)
{
    /* max_steps = 10 per sample interval: the Fig. 5 run fails with
     * CD_EMAXSTEPS once the contacts need more steps. Exit 1 with one
     * 'capdyn: error:' line; the file is closed with that status and keeps
     * the samples before the failure plus the last good state. */
    char dir[64], sc[512], h5[256], s[300], *err = NULL;
    hid_t f;
    hsize_t d[3];
    int rc;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "paper_fig5_envelope_grasp.toml");
    snprintf(h5, sizeof h5, "%s/fail.h5", dir);
    rc = capdyn(dir, NULL, &err, "run", sc, "-o", h5, "--quiet", "--set", "simulation.max_steps=10", "--set",
                "simulation.integrator=\"rk8pd\"", (char *)NULL);
    cr_expect_eq(rc, 1, "exit %d: %s", rc, err);
    cr_expect(err && strstr(err, "capdyn: error: run failed") != NULL, "stderr: %s", err);
    cr_expect(err && strstr(err, h5) != NULL, "stderr says where the data is: %s", err);
    free(err);
    f = open_ro(h5);
    cr_assert(f >= 0);
    attr_s(f, "run_status", s, sizeof s);
    cr_expect_str_eq(s, cd_status_string(CD_EMAXSTEPS));
    attr_s(f, "run_message", s, sizeof s);
    cr_expect(strstr(s, "max_steps") != NULL, "message: %s", s);
    dims_of(f, "/time", d);
    cr_expect_gt(d[0], 10, "samples before the failure are kept (%llu)", (unsigned long long)d[0]);
    cr_expect_lt(attr_d(f, "t_final"), 2.0);
    H5Fclose(f);
    rm_rf(dir);
}

/* ---- write failures (disk full) ------------------------------------------------------ */
/* "samples     N committed" of a `capdyn info` output (-1 if absent). */
static long info_samples(const char *out)
{
    const char *p = out ? strstr(out, "\nsamples ") : NULL;
    long n = -1;
    if (p && sscanf(p + 9, " %ld committed", &n) != 1) n = -1;
    return n;
}
/* The text after "status" of a `capdyn info` output, up to the end of the line. */
static void info_status(const char *out, char *buf, size_t len)
{
    const char *p = out ? strstr(out, "\nstatus ") : NULL;
    size_t n;
    buf[0] = 0;
    if (!p) return;
    p += 8;
    while (*p == ' ') p++;
    n = strcspn(p, "\n");
    if (n >= len) n = len - 1;
    memcpy(buf, p, n);
    buf[n] = 0;
}

static int h5clear(const char *path)
{
    char cmd[600];
    snprintf(cmd, sizeof cmd, "h5clear --increment=0 '%s' >/dev/null 2>&1", path);
    return system(cmd);
}

Test(cli, a_full_disk_stops_the_run_with_one_error_and_keeps_the_committed_samples, .timeout = 60)
{
    /* The review's repro (B3), made larger so that commits happen first: the
     * Fig. 3 impact over 4 s (40001 samples, a 7.8 MB file) under a 4 MiB
     * file size limit (POSIX sh: ulimit -f counts 512-byte blocks), SIGXFSZ
     * ignored as a full disk does not send it. Before the fix: exit 139
     * (segfault in HDF5's atexit clean-up), no message about the write, an
     * unreadable file claiming "ok" after h5clear. Now: exit 1 (not a
     * signal), one error line naming the file and the write that could not
     * be done, and a file (readable as is, and after h5clear --increment=0,
     * the documented recovery) whose committed samples are > 0, are exactly
     * those of an unlimited run (bit for bit) and whose status is not "ok". */
    char dir[64], sc[512], h5[256], ref[256], cmd[2048], st[600], *out = NULL, *err = NULL, errp[300];
    char *argv[4];
    hid_t f, fr;
    size_t n, nr, i;
    double *t, *tr, *ke, *ker;
    long ns;
    int rc, run_rc;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "paper_fig3_impact.toml");
    snprintf(h5, sizeof h5, "%s/full.h5", dir);
    snprintf(ref, sizeof ref, "%s/ref.h5", dir);
    rc = capdyn(dir, NULL, NULL, "run", sc, "-o", ref, "--quiet", "--set", "simulation.duration=4", (char *)NULL);
    cr_assert_eq(rc, 0, "the reference run");

    snprintf(cmd, sizeof cmd,
             "trap '' XFSZ; ulimit -f 8192 || exit 99; exec '%s' run '%s' -o '%s' --quiet --set simulation.duration=4",
             bin(), sc, h5);
    argv[0] = (char *)"/bin/sh";
    argv[1] = (char *)"-c";
    argv[2] = cmd;
    argv[3] = NULL;
    rc = run_rc = wait_status(spawn(dir, argv, NULL));
    snprintf(errp, sizeof errp, "%s/err.txt", dir);
    err = slurp(errp);
    cr_assert_neq(rc, 99, "ulimit -f failed");
    cr_expect_eq(rc, 1, "exit status %d (>= 128: killed by signal %d); stderr: %s", rc, rc - 128, err);
    cr_expect(err && strncmp(err, "capdyn: error: ", 15) == 0, "stderr: %s", err);
    cr_expect(err && strchr(err, '\n') == err + strlen(err) - 1, "one line: %s", err);
    cr_expect(err && strstr(err, h5) != NULL, "the message names the file: %s", err);
    cr_expect(err && (strstr(err, "file size limit") || strstr(err, "disk full") || strstr(err, "failed")),
              "the message says what could not be written: %s", err);
    free(err);

    /* readable as it is: the space check stopped before writing */
    rc = capdyn(dir, &out, &err, "info", h5, (char *)NULL);
    cr_expect_eq(rc, 0, "capdyn info without h5clear: %s", err);
    free(out);
    free(err);
    /* the documented recovery, harmless on a consistent file */
    cr_assert_eq(h5clear(h5), 0, "h5clear --increment=0");
    rc = capdyn(dir, &out, &err, "info", h5, (char *)NULL);
    cr_assert_eq(rc, 0, "capdyn info after h5clear: %s", err);
    ns = info_samples(out);
    info_status(out, st, sizeof st);
    cr_expect_gt(ns, 0, "samples committed before the disk was full: %s", out);
    cr_expect_lt(ns, 40001);
    cr_expect(strncmp(st, "ok", 2) != 0, "status is not ok: '%s'", st);
    cr_expect(strstr(st, "file size limit") || strstr(st, "failed") || strstr(st, "running"), "status: '%s'", st);
    free(out);
    free(err);

    f = open_ro(h5);
    fr = open_ro(ref);
    cr_assert(f >= 0 && fr >= 0);
    cr_expect_eq(attr_ll(f, "committed_samples"), ns);
    t = read_all(f, "/time", &n);
    tr = read_all(fr, "/time", &nr);
    ke = read_all(f, "/diagnostics/kinetic_energy", &n);
    ker = read_all(fr, "/diagnostics/kinetic_energy", &nr);
    cr_assert_geq(n, (size_t)ns);
    for (i = 0; i < (size_t)ns; i++) {
        cr_assert_eq(t[i], tr[i], "t[%zu] %.17g vs %.17g in the unlimited run", i, t[i], tr[i]);
        cr_assert_eq(ke[i], ker[i], "kinetic energy [%zu] %.17g vs %.17g", i, ke[i], ker[i]);
    }
    free(t);
    free(tr);
    free(ke);
    free(ker);
    H5Fclose(f);
    H5Fclose(fr);
    cr_log_info("file size limit 4 MiB: exit %d, %ld samples committed (t <= %.4g s), status '%.60s...'", run_rc, ns,
                (double)(ns - 1) * 1e-4, st);
    rm_rf(dir);
}

/* The child of the two tests below: runs the scenario sc through the library
 * writer (compressed or not), commits ncommit samples dt apart, lowers its
 * file size limit, soft and hard, to the file's size + 8 KiB (SIGXFSZ ignored: a write fails
 * with EFBIG), turns the space check off and goes on to 3 ncommit samples.
 * The flush must fail (CD_EIO, the message naming the file and the
 * committed samples), the close too, and H5close after it must not crash
 * (on a file left half closed in HDF5's id table). Exits 0, or the number
 * of the check that failed. */
static void quota_child(const char *sc, const char *h5, int no_compress, long ncommit, double dt, int no_fds)
{
    cd_error e;
    char want[32];
    cd_scenario *s = cd_scenario_load(sc, NULL, 0, &e);
    cd_data *d = s ? cd_data_create(s->model, s->event_capacity, &e) : NULL;
    cd_h5_writer *w;
    struct stat sb;
    struct rlimit rl;
    cd_status r = CD_OK;
    long k;
    if (!d) _exit(10);
    s->no_compress = no_compress;
    w = cd_h5_create(h5, s->model, s, &e);
    if (!w) _exit(10);
    for (k = 0; k < ncommit && r == CD_OK; k++) {
        if (k > 0) r = cd_sim_advance(s->model, d, (double)k * dt, NULL, NULL, &e);
        if (r == CD_OK) r = cd_h5_append(w, s->model, d, &e);
    }
    if (r != CD_OK || cd_h5_flush(w, &e) != CD_OK) _exit(11);
    if (stat(h5, &sb) != 0 || getrlimit(RLIMIT_FSIZE, &rl) != 0) _exit(12);
    signal(SIGXFSZ, SIG_IGN);
    rl.rlim_cur = rl.rlim_max = (rlim_t)sb.st_size + 8192; /* both, as `ulimit -f` sets them */
    if (setrlimit(RLIMIT_FSIZE, &rl) != 0) _exit(13);
    if (no_fds) { /* every descriptor the process may have is taken: open() fails from here on */
        if (getrlimit(RLIMIT_NOFILE, &rl) != 0) _exit(13);
        rl.rlim_cur = 256 < rl.rlim_max ? 256 : rl.rlim_max;
        if (setrlimit(RLIMIT_NOFILE, &rl) != 0) _exit(13);
        while (open("/dev/null", O_RDONLY) >= 0) {}
        if (errno != EMFILE) _exit(13);
    }
    cd_h5_writer_set_space_check(w, 0, 0);
    for (; k < 3 * ncommit && r == CD_OK; k++) {
        r = cd_sim_advance(s->model, d, (double)k * dt, NULL, NULL, &e);
        if (r == CD_OK) r = cd_h5_append(w, s->model, d, &e);
    }
    if (r == CD_OK) r = cd_h5_flush(w, &e);
    if (r != CD_EIO) _exit(14);
    snprintf(want, sizeof want, "%ld samples", ncommit);
    if (!strstr(e.msg, h5) || !strstr(e.msg, want)) _exit(15);
    if (cd_h5_close(w, s->model, d, CD_OK, "finished", &e) != CD_EIO) _exit(16);
    cd_data_free(d);
    cd_scenario_free(s);
    H5close();
    _exit(0);
}

/* Forks quota_child on the Fig. 3 scenario writing h5 and asserts that it
 * ran all its checks. */
static void run_quota_child(const char *h5, int no_compress, long ncommit, double dt, int no_fds)
{
    char sc[512];
    pid_t pid;
    int ws;
    scen(sc, sizeof sc, "paper_fig3_impact.toml");
    fflush(NULL);
    pid = fork();
    cr_assert(pid >= 0);
    if (pid == 0) quota_child(sc, h5, no_compress, ncommit, dt, no_fds);
    cr_assert_eq(waitpid(pid, &ws, 0), pid);
    cr_assert(WIFEXITED(ws) && WEXITSTATUS(ws) == 0, "the writing child: %s %d", WIFEXITED(ws) ? "exit" : "signal",
              WIFEXITED(ws) ? WEXITSTATUS(ws) : WTERMSIG(ws));
}

/* `capdyn info` reads h5 (exit 0) with ncommit committed samples and a
 * status that is not "ok", and /time holds them at the times they were
 * taken (k dt: cd_sim_advance stops exactly at its target time). */
static void expect_committed_samples(const char *dir, const char *h5, long ncommit, double dt)
{
    char st[600], *out = NULL, *err = NULL;
    int rc = capdyn(dir, &out, &err, "info", h5, (char *)NULL);
    long k;
    hid_t f;
    size_t n;
    double *t;
    cr_assert_eq(rc, 0, "capdyn info: %s", err);
    cr_expect_eq(info_samples(out), ncommit, "the committed samples: %s", out);
    info_status(out, st, sizeof st);
    cr_expect(strncmp(st, "ok", 2) != 0, "status is not ok: '%s'", st);
    free(out);
    free(err);
    f = open_ro(h5);
    cr_assert(f >= 0);
    t = read_all(f, "/time", &n);
    cr_assert_geq(n, (size_t)ncommit);
    for (k = 0; k < ncommit; k++) cr_assert_eq(t[k], (double)k * dt, "t[%ld] = %.17g", k, t[k]);
    free(t);
    H5Fclose(f);
}

Test(cli, info_names_a_truncated_file_and_h5clear_recovers_it, .timeout = 60)
{
    /* A write that fails where no check can foresee it (a disk quota): the
     * library writer with its space check off, in a child process whose
     * file size limit is lowered after 2000 committed samples of the Fig. 3
     * scenario. The file is then truncated (HDF5 recorded a larger end of
     * file than it could write). `capdyn info` says so and names the
     * recovery; after `h5clear --increment=0` it reads the 2000 committed
     * samples, at the times they were taken, and a status that is not "ok".
     * Uncompressed (simulation.compress = false): HDF5 writes the chunks
     * from its cache and fails there. The compressed writer writes its own
     * chunks (src/io/h5_pack.c) and leaves no truncated file:
     * a_failed_chunk_write_leaves_a_file_that_reads_as_committed. */
    char dir[64], h5[256], *out = NULL, *err = NULL, want[400];
    int rc;
    const long ncommit = 2000;
    const double dt = 1e-4;
    make_tmpdir(dir, sizeof dir);
    snprintf(h5, sizeof h5, "%s/quota.h5", dir);
    run_quota_child(h5, 1, ncommit, dt, 0);

    rc = capdyn(dir, &out, &err, "info", h5, (char *)NULL);
    cr_expect_eq(rc, 1, "exit %d", rc);
    snprintf(want, sizeof want, "'h5clear --increment=0 %s'", h5);
    cr_expect(err && strstr(err, "truncated") && strstr(err, want), "info names the damage and the recovery: %s", err);
    cr_expect(err && strchr(err, '\n') == err + strlen(err) - 1, "one line: %s", err);
    free(out);
    free(err);

    cr_assert_eq(h5clear(h5), 0, "h5clear --increment=0");
    expect_committed_samples(dir, h5, ncommit, dt); /* they are back */
    rc = capdyn(dir, &out, NULL, "export", h5, "time", (char *)NULL);
    cr_expect_eq(rc, 0);
    {
        int ncol;
        cr_expect_eq(parse_columns(out, &ncol), ncommit, "export gives the committed samples");
    }
    free(out);
    rm_rf(dir);
}

/* The compressed writer's chunk write refused by a file size limit after
 * 2000 committed samples (no_fds: with no descriptor left as well): the
 * file reads as committed without any recovery. */
static void committed_after_a_failed_chunk_write(int no_fds)
{
    char dir[64], h5[256];
    const long ncommit = 2000;
    const double dt = 1e-4;
    make_tmpdir(dir, sizeof dir);
    snprintf(h5, sizeof h5, "%s/quota.h5", dir);
    run_quota_child(h5, 0, ncommit, dt, no_fds);
    expect_committed_samples(dir, h5, ncommit, dt);
    rm_rf(dir);
}

Test(cli, a_failed_chunk_write_leaves_a_file_that_reads_as_committed, .timeout = 60)
{
    /* The same failure as above with the default, compressed writer, which
     * packs and writes its chunks itself (src/io/h5_pack.c): the refused
     * chunk write is reported (exit status CD_EIO, the message names the
     * file and the 2000 committed samples), the writer closes without
     * crashing (H5close after it), and the file reads as it was at its last
     * commit without any recovery: `capdyn info` exits 0 with the 2000
     * samples, at the times they were taken, and a status that is not "ok". */
    committed_after_a_failed_chunk_write(0);
}

Test(cli, a_failed_chunk_write_with_no_descriptor_left_reads_as_committed, .timeout = 60)
{
    /* The same failure when the process has no file descriptor left (its
     * limit reached before the refused write): the writer cannot open
     * anything at the close, yet its close must not flush into the file it
     * failed to write (src/io/h5.c, detach_file: the descriptor it points
     * the file at was opened when the writer was created). The checks are
     * those above: CD_EIO, no crash at H5close, and the 2000 committed
     * samples read back without any recovery. */
    committed_after_a_failed_chunk_write(1);
}

Test(cli, more_than_1e9_samples_is_refused)
{
    /* B5: output_dt = 1e-300 (or duration = 1e300) made the sample count
     * overflow a long: the run printed "status ok: finished at t = 0 s" and
     * exited 0. Now the loader refuses it (exit 1, one line naming the key
     * and its range) before any file is made. */
    char dir[64], sc[512], h5[256], *out = NULL, *err = NULL;
    int rc;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "paper_fig3_impact.toml");
    snprintf(h5, sizeof h5, "%s/never.h5", dir);
    rc = capdyn(dir, &out, &err, "run", sc, "-o", h5, "--set", "simulation.output_dt=1e-300", (char *)NULL);
    cr_expect_eq(rc, 1, "exit %d: %s", rc, out);
    cr_expect(err && strstr(err, "key 'simulation.output_dt': expected a value in [duration / 1e9, inf)"),
              "stderr: %s", err);
    cr_expect(err && strchr(err, '\n') == err + strlen(err) - 1, "one line: %s", err);
    cr_expect(!out || !strstr(out, "status"), "no summary: %s", out);
    cr_expect_neq(access(h5, F_OK), 0, "no file");
    free(out);
    free(err);
    rc = capdyn(dir, &out, &err, "run", sc, "-o", h5, "--set", "simulation.duration=1e300", (char *)NULL);
    cr_expect_eq(rc, 1, "exit %d: %s", rc, out);
    cr_expect(err && strstr(err, "paper_fig3_impact.toml:38:13: key 'simulation.output_dt'"), "stderr: %s", err);
    free(out);
    free(err);
    rc = capdyn(dir, NULL, &err, "check", sc, "--set", "simulation.output_dt=1e-300", (char *)NULL);
    cr_expect_eq(rc, 1, "check: exit %d", rc);
    free(err);
    rm_rf(dir);
}

Test(cli, a_signal_before_the_results_file_exists_stops_cleanly, .timeout = 30)
{
    /* R4: SIGINT was caught only after the results file was created, so one
     * arriving earlier killed the process with the file half made. A
     * SIGINT made pending (blocked, then raised) before exec is delivered
     * when capdyn run installs its handlers and unblocks the signal, before
     * the file exists: the run stops at once (exit 130) with a closed file
     * holding the t = 0 sample and status "interrupted". */
    char dir[64], sc[512], h5[256], s[128], errp[300], *err;
    char *argv[12];
    pid_t pid;
    hid_t f;
    int rc;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "paper_fig5_envelope_grasp.toml");
    snprintf(h5, sizeof h5, "%s/early.h5", dir);
    argv[0] = (char *)bin();
    argv[1] = (char *)"run";
    argv[2] = sc;
    argv[3] = (char *)"-o";
    argv[4] = h5;
    argv[5] = (char *)"--quiet";
    argv[6] = (char *)"--set";
    argv[7] = (char *)"simulation.duration=20";
    argv[8] = NULL;
    {
        sigset_t set, old;
        sigemptyset(&set);
        sigaddset(&set, SIGINT);
        cr_assert_eq(sigprocmask(SIG_BLOCK, &set, &old), 0);
        /* the child inherits the mask; it raises SIGINT itself before exec */
        fflush(NULL);
        pid = fork();
        cr_assert(pid >= 0);
        if (pid == 0) {
            int fe = open(strcat(strcpy(errp, dir), "/err.txt"), O_WRONLY | O_CREAT | O_TRUNC, 0644);
            if (fe >= 0) dup2(fe, 2);
            raise(SIGINT);
            execv(argv[0], argv);
            _exit(127);
        }
        sigprocmask(SIG_SETMASK, &old, NULL);
    }
    rc = wait_status(pid);
    snprintf(errp, sizeof errp, "%s/err.txt", dir);
    err = slurp(errp);
    cr_expect_eq(rc, 130, "exit %d; stderr: %s", rc, err);
    cr_expect(err && strstr(err, "SIGINT"), "stderr: %s", err);
    free(err);
    f = open_ro(h5);
    cr_assert(f >= 0, "the results file is closed and readable");
    attr_s(f, "run_status", s, sizeof s);
    cr_expect_str_eq(s, cd_status_string(CD_EINTERRUPT));
    cr_expect_eq(attr_ll(f, "committed_samples"), 1, "the t = 0 sample only");
    cr_expect_eq(attr_d(f, "t_final"), 0.0);
    H5Fclose(f);
    rm_rf(dir);
}

static int g_gsl_errors;
static void count_gsl_error(const char *reason, const char *file, int line, int gsl_errno)
{
    (void)reason; (void)file; (void)line; (void)gsl_errno;
    g_gsl_errors++;
}

Test(cli, the_library_leaves_the_gsl_error_handler_to_the_program)
{
    /* Only the capdyn program turns GSL's abort-on-error handler off
     * (src/cli/capdyn.c); the library never sets a handler. A program's own
     * handler is still in place after loading, simulating (0.05 s of the
     * Fig. 3 impact, through contact onset) and writing a results file. */
    char sc[512], h5[256];
    cd_error e;
    cd_scenario *s;
    cd_data *d;
    cd_h5_writer *w;
    gsl_error_handler_t *prev, *now_h;
    scen(sc, sizeof sc, "paper_fig3_impact.toml");
    snprintf(h5, sizeof h5, "/tmp/capdyn_cli_gsl_%ld.h5", (long)getpid());
    prev = gsl_set_error_handler(count_gsl_error);
    s = cd_scenario_load(sc, NULL, 0, &e);
    cr_assert_not_null(s, "%s", e.msg);
    d = cd_data_create(s->model, s->event_capacity, &e);
    cr_assert_not_null(d, "%s", e.msg);
    w = cd_h5_create(h5, s->model, s, &e);
    cr_assert_not_null(w, "%s", e.msg);
    cr_assert_eq(cd_sim_advance(s->model, d, 0.05, NULL, NULL, &e), CD_OK, "%s", e.msg);
    cr_assert_eq(cd_h5_append(w, s->model, d, &e), CD_OK, "%s", e.msg);
    cr_assert_eq(cd_h5_close(w, s->model, d, CD_OK, "", &e), CD_OK, "%s", e.msg);
    now_h = gsl_set_error_handler(prev);
    cr_expect(now_h == count_gsl_error, "the library replaced the program's GSL error handler");
    cr_expect_eq(g_gsl_errors, 0, "no GSL error in a healthy run");
    cr_expect_gt(d->ev_count, 0, "the run went through contact events");
    cd_data_free(d);
    cd_scenario_free(s);
    remove(h5);
}

Test(cli, bad_arguments_exit_2_runtime_errors_exit_1)
{
    /* Usage errors: exit 2 and one "capdyn: error:" line. Runtime errors
     * (missing files): exit 1. --help/--version: exit 0 on stdout. */
    char dir[64], *out = NULL, *err = NULL, sc[512], h5[256], toml[256];
    int rc;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "paper_fig3_impact.toml");
    snprintf(toml, sizeof toml, "%s/ball.toml", dir);
    snprintf(h5, sizeof h5, "%s/ball.h5", dir);
    write_file(toml, ball_toml);
    cr_assert_eq(capdyn(dir, NULL, NULL, "run", toml, "-o", h5, "--quiet", (char *)NULL), 0);
#define USAGE(...)                                                                           \
    do {                                                                                     \
        rc = capdyn(dir, NULL, &err, __VA_ARGS__, (char *)NULL);                            \
        cr_expect_eq(rc, 2, #__VA_ARGS__ ": exit %d", rc);                                   \
        cr_expect(err && strncmp(err, "capdyn: error: ", 15) == 0, #__VA_ARGS__ ": %s", err); \
        free(err);                                                                           \
    } while (0)
    rc = capdyn(dir, NULL, NULL, (char *)NULL);
    cr_expect_eq(rc, 2, "no command: exit %d", rc);
    USAGE("frobnicate");
    USAGE("--frobnicate");
    USAGE("run");
    USAGE("run", sc, "--bogus");
    USAGE("run", sc, "-o");
    USAGE("run", sc, "--set", "novalue");
    USAGE("run", sc, sc);
    USAGE("check");
    USAGE("info");
    USAGE("export", h5);
    USAGE("export", h5, "nonsense");
    USAGE("export", h5, "slot");
    USAGE("export", h5, "time", "--every", "0");
    USAGE("export", h5, "time", "--view", "xq");
    USAGE("export", h5, "outline", "--at", "zero");
#undef USAGE
    rc = capdyn(dir, &out, NULL, "--help", (char *)NULL);
    cr_expect_eq(rc, 0);
    cr_expect(out && strstr(out, "usage: capdyn") != NULL);
    free(out);
    rc = capdyn(dir, &out, NULL, "export", "--help", (char *)NULL);
    cr_expect_eq(rc, 0);
    cr_expect(out && strstr(out, "usage: capdyn export") != NULL);
    free(out);
    rc = capdyn(dir, &out, NULL, "--version", (char *)NULL);
    cr_expect_eq(rc, 0);
    {
        char want[64];
        snprintf(want, sizeof want, "capdyn %s\n", cd_version());
        cr_expect_str_eq(out, want);
    }
    free(out);
    rc = capdyn(dir, NULL, &err, "info", "/nonexistent/file.h5", (char *)NULL);
    cr_expect_eq(rc, 1, "missing results file: exit %d", rc);
    cr_expect(err && strstr(err, "/nonexistent/file.h5"), "%s", err);
    free(err);
    rc = capdyn(dir, NULL, &err, "info", toml, (char *)NULL);
    cr_expect_eq(rc, 1, "not an HDF5 file: exit %d", rc);
    free(err);
    rc = capdyn(dir, NULL, &err, "export", h5, "system", "nosuch", (char *)NULL);
    cr_expect_eq(rc, 1, "unknown system: exit %d", rc);
    free(err);
    rc = capdyn(dir, NULL, &err, "run", "/nonexistent/scenario.toml", (char *)NULL);
    cr_expect_eq(rc, 1, "missing scenario: exit %d", rc);
    free(err);
    rm_rf(dir);
}

/* capdyn check on NAME.toml made from the template fmt with the value bad:
 * exit 1, nothing on stdout, one line on stderr holding want; with the value
 * good: exit 0 (the control). */
static void check_refuses_then_accepts(const char *name, const char *fmt, const char *bad, const char *good,
                                       const char *want)
{
    char dir[64], toml[256], text[512], *out = NULL, *err = NULL;
    int rc;
    make_tmpdir(dir, sizeof dir);
    snprintf(toml, sizeof toml, "%s/%s", dir, name);
    snprintf(text, sizeof text, fmt, bad);
    write_file(toml, text);
    rc = capdyn(dir, &out, &err, "check", toml, (char *)NULL);
    cr_expect_eq(rc, 1, "exit %d: %s", rc, err);
    cr_expect(out && out[0] == 0, "stdout '%s'", out);
    cr_expect(err && strstr(err, want) && strchr(err, '\n') == err + strlen(err) - 1, "stderr '%s'", err);
    free(out);
    free(err);
    out = err = NULL;
    snprintf(text, sizeof text, fmt, good);
    write_file(toml, text);
    rc = capdyn(dir, &out, &err, "check", toml, (char *)NULL);
    cr_expect_eq(rc, 0, "exit %d: %s", rc, err);
    free(out);
    free(err);
    rm_rf(dir);
}

Test(cli, check_refuses_a_scenario_whose_first_evaluation_overflows)
{
    /* A constant motor torque of 1e308 N m passes every range check, but
     * the first evaluation of the dynamics overflows and a run stops at
     * t = 0 ("numerical failure"). capdyn check evaluates the initial state
     * and says so: exit 1, nothing on stdout, one line naming the file. A
     * torque of 1 N m passes (the control of the test). */
    check_refuses_then_accepts("arm.toml",
                               "[simulation]\nduration = 0.01\n\n[[system]]\nname = \"arm\"\nbase = \"fixed\"\n\n"
                               "[[system.link]]\nname = \"upper\"\nmass = 1.0\ninertia = [0.01, 0.01, 0.01]\n"
                               "actuator = { type = \"constant\", tau = %s }\n",
                               "1e308", "1.0", "arm.toml: the initial state (t = 0 s) gives a non-finite value");
}

Test(cli, check_refuses_a_scenario_whose_first_sample_overflows)
{
    /* A free body at 1e300 m/s: the evaluation is finite (no force depends
     * on the speed), but the kinetic energy m v^2 / 2 = 5e599 J overflows, and
     * a run stops at its first sample ("non-finite output"). capdyn check
     * computes the first sample's energy and momenta and names the system
     * and the quantity: exit 1, one line. 1e100 m/s (5e199 J) passes. */
    check_refuses_then_accepts("ball.toml",
                               "[simulation]\nduration = 0.01\n\n[[system]]\nname = \"ball\"\nmass = 1.0\n"
                               "inertia = [0.01, 0.01, 0.01]\nvelocity = [%s, 0, 0]\n",
                               "1e300", "1e100",
                               "ball.toml: system 'ball' at the initial state (t = 0 s) has a non-finite kinetic "
                               "energy, so a run would stop at its first sample");
}

Test(cli, check_prints_the_model_summary)
{
    /* capdyn check: exit 0 and an OK line whose counts are the model's
     * (cd_scenario_load of the same file); --set applies. */
    char dir[64], sc[512], want[128], *out = NULL;
    cd_error e;
    cd_scenario *s;
    int rc;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "paper_fig5_envelope_grasp.toml");
    s = cd_scenario_load(sc, NULL, 0, &e);
    cr_assert_not_null(s, "%s", e.msg);
    rc = capdyn(dir, &out, NULL, "check", sc, "--set", "simulation.duration=0.5", "--set",
                "simulation.integrator=\"rk8pd\"", (char *)NULL);
    cr_expect_eq(rc, 0);
    cr_expect(out && strstr(out, ": OK: ") != NULL, "%s", out);
    snprintf(want, sizeof want, "%d contact slots, state size %d; 0.5 s", s->model->nslot, s->model->ny);
    cr_expect(out && strstr(out, want) != NULL, "'%s' in '%s'", want, out);
    /* second and last line: the least work, 0.5 s / h_max 1e-3 s = 500 steps
     * of rk8pd (12 new evaluations each; the scenario's own "auto" counts
     * ros34pw2's 4), and the default budget */
    {
        const char *nl = out ? strchr(out, '\n') : NULL;
        cr_expect(nl && strcmp(nl + 1, "work: at least 500 steps and 6000 right-hand-side evaluations; budget: "
                                       "max_rhs_evals 1e+09, max_wall_time 3600 s\n") == 0,
                  "%s", out);
    }
    free(out);
    cd_scenario_free(s);
    rm_rf(dir);
}

/* ---- figures ---------------------------------------------------------------------- */
static long file_size(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

static int starts_with(const char *path, const char *magic, size_t n)
{
    char buf[16] = {0};
    FILE *f = fopen(path, "rb");
    size_t got;
    if (!f) return 0;
    got = fread(buf, 1, n, f);
    fclose(f);
    return got == n && memcmp(buf, magic, n) == 0;
}

Test(cli, figures_script_renders_nonempty_images, .timeout = 120)
{
    /* plots/figures.sh (what `make figures` runs) on shortened runs
     * (CAPDYN_RUN_ARGS sets the duration to 0.12 s): every figure exists,
     * PNGs carry the PNG signature and more than 5 kB, SVGs are SVG text,
     * the animation is a GIF. */
    static const char *pngs[] = {"fig3_force", "fig3_force_first_strike", "fig3_diagnostics", "fig5_force",
                                 "fig5_force_closing", "fig5_snapshots", "fig5_diagnostics"};
    char dir[64], script[512], figdir[300], p[400], env1[400], env2[320], env3[600];
    char *argv[3], *env[4];
    size_t i;
    int rc;
    make_tmpdir(dir, sizeof dir);
    snprintf(script, sizeof script, "%s/plots/figures.sh", root());
    snprintf(figdir, sizeof figdir, "%s/figures", dir);
    snprintf(env1, sizeof env1, "FIGURES_DIR=%s", figdir);
    snprintf(env2, sizeof env2, "CAPDYN_RUN_ARGS=--set simulation.duration=0.12");
    if (bin()[0] == '/') snprintf(env3, sizeof env3, "CAPDYN=%s", bin());
    else {
        char cwd[400];
        cr_assert_not_null(getcwd(cwd, sizeof cwd));
        snprintf(env3, sizeof env3, "CAPDYN=%s/%s", cwd, bin());
    }
    env[0] = env1;
    env[1] = env2;
    env[2] = env3;
    env[3] = NULL;
    argv[0] = (char *)"/bin/bash";
    argv[1] = script;
    argv[2] = NULL;
    rc = wait_status(spawn(dir, argv, env));
    if (rc != 0) {
        char ep[300], *err;
        snprintf(ep, sizeof ep, "%s/err.txt", dir);
        err = slurp(ep);
        cr_assert_fail("figures.sh exit %d: %s", rc, err);
    }
    for (i = 0; i < sizeof pngs / sizeof *pngs; i++) {
        snprintf(p, sizeof p, "%s/%s.png", figdir, pngs[i]);
        cr_expect(starts_with(p, "\x89PNG", 4), "%s is a PNG", p);
        cr_expect_gt(file_size(p), 5000, "%s: %ld bytes", p, file_size(p));
        snprintf(p, sizeof p, "%s/%s.svg", figdir, pngs[i]);
        {
            char *svg = slurp(p);
            cr_expect(svg && strstr(svg, "<svg") != NULL, "%s is SVG", p);
            free(svg);
        }
    }
    snprintf(p, sizeof p, "%s/fig5_grasp.gif", figdir);
    cr_expect(starts_with(p, "GIF89a", 6), "%s is a GIF", p);
    cr_expect_gt(file_size(p), 5000);
    rm_rf(dir);
}

Test(cli, interpolated_samples_match_stopped_ones_on_the_same_grid)
{
    /* simulation.sampling = "interpolate" (dense output, issue 11): the same
     * free-floating arm sampled every 1 ms for 2 s, with steps up to 10 ms
     * that no longer stop at the samples: the same sample times bit for bit,
     * the base position within 1e-9 m of the run that stops at every sample
     * (Hermite error over a 10 ms step of this slow motion, plus rtol 1e-10),
     * and at least 3x fewer steps. */
    char dir[64], sc[512], h5[2][256], *err = NULL;
    const char *mode[2] = {"simulation.sampling=\"stop\"", "simulation.sampling=\"interpolate\""};
    double *t[2], *p[2], worst = 0;
    long long steps[2];
    size_t n[2], np, i;
    int k, rc;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "free_floating_arm.toml");
    for (k = 0; k < 2; k++) {
        hid_t f;
        snprintf(h5[k], sizeof h5[k], "%s/arm%d.h5", dir, k);
        rc = capdyn(dir, NULL, &err, "run", sc, "-o", h5[k], "--quiet", "--set", "simulation.duration=2", "--set",
                    "simulation.output_dt=1e-3", "--set", mode[k], (char *)NULL);
        cr_assert_eq(rc, 0, "exit %d: %s", rc, err);
        free(err);
        f = open_ro(h5[k]);
        cr_assert(f >= 0);
        t[k] = read_all(f, "/time", &n[k]);
        p[k] = read_all(f, "/systems/robot/base_pos", &np);
        steps[k] = attr_ll(f, "stats_nsteps");
        H5Fclose(f);
    }
    cr_assert_eq(n[0], 2001);
    cr_assert_eq(n[1], n[0]);
    for (i = 0; i < n[0]; i++) cr_expect_eq(t[0][i], t[1][i], "sample %zu: %.17g vs %.17g", i, t[0][i], t[1][i]);
    for (i = 0; i < np; i++) worst = fmax(worst, fabs(p[0][i] - p[1][i]));
    cr_log_info("sampling stop: %lld steps, interpolate: %lld steps; base position differs by at most %.3g m", steps[0],
                steps[1], worst);
    cr_expect_leq(worst, 1e-9, "base position differs by %.3g m", worst);
    cr_expect_leq(3 * steps[1], steps[0], "steps: %lld interpolated vs %lld stopped", steps[1], steps[0]);
    for (k = 0; k < 2; k++) { free(t[k]); free(p[k]); }
    rm_rf(dir);
}

Test(cli, jacobian_count_is_recorded_for_the_stiff_stepper_only)
{
    /* stats_njac: ros34pw2 forms at least one Jacobian, each costing one
     * evaluation per active unknown (at least the block's 13 coordinates and
     * velocities), all counted in stats_nrhs; rk8pd forms none. */
    char dir[64], sc[512], h5[256], *err = NULL;
    const char *stp[2] = {"simulation.integrator=ros34pw2", "simulation.integrator=rk8pd"};
    int k, rc;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "block_on_slope.toml");
    for (k = 0; k < 2; k++) {
        hid_t f;
        long long nj, nf;
        snprintf(h5, sizeof h5, "%s/j%d.h5", dir, k);
        rc = capdyn(dir, NULL, &err, "run", sc, "-o", h5, "--quiet", "--set", "simulation.duration=0.5", "--set", stp[k],
                    (char *)NULL);
        cr_assert_eq(rc, 0, "exit %d: %s", rc, err);
        free(err);
        f = open_ro(h5);
        cr_assert(f >= 0);
        nj = attr_ll(f, "stats_njac");
        nf = attr_ll(f, "stats_nrhs");
        H5Fclose(f);
        if (k == 0) {
            cr_expect_geq(nj, 1, "ros34pw2: %lld Jacobians", nj);
            cr_expect_geq(nf, 13 * nj, "ros34pw2: %lld evaluations for %lld Jacobians", nf, nj);
        } else {
            cr_expect_eq(nj, 0, "rk8pd: %lld Jacobians", nj);
        }
    }
    rm_rf(dir);
}

/* Every dataset of a results file (H5Ovisit), for the comparison below. */
typedef struct {
    char name[64][128];
    int n;
} ds_list;

static herr_t list_ds(hid_t obj, const char *name, const H5O_info_t *info, void *op)
{
    ds_list *l = (ds_list *)op;
    (void)obj;
    if (info->type == H5O_TYPE_DATASET && l->n < 64) snprintf(l->name[l->n++], sizeof l->name[0], "/%s", name);
    return 0;
}

/* The bytes of dataset name of f in its native type (malloc'd), and their count. */
static unsigned char *read_bytes(hid_t f, const char *name, size_t *nb, int *nfilters)
{
    hid_t ds = H5Dopen2(f, name, H5P_DEFAULT), ft, mt, pl, sp;
    unsigned char *b = NULL;
    *nb = 0;
    *nfilters = -1;
    if (ds < 0) return NULL;
    ft = H5Dget_type(ds);
    mt = H5Tget_native_type(ft, H5T_DIR_ASCEND);
    sp = H5Dget_space(ds);
    *nb = (size_t)H5Sget_simple_extent_npoints(sp) * H5Tget_size(mt);
    H5Sclose(sp);
    b = calloc(*nb + 1, 1);
    if (b && H5Dread(ds, mt, H5S_ALL, H5S_ALL, H5P_DEFAULT, b) < 0) { free(b); b = NULL; }
    pl = H5Dget_create_plist(ds);
    *nfilters = H5Pget_nfilters(pl);
    H5Pclose(pl);
    H5Tclose(mt);
    H5Tclose(ft);
    H5Dclose(ds);
    return b;
}

Test(cli, uncompressed_results_hold_the_same_samples, .timeout = 120)
{
    /* simulation.compress = false (issue 11: HDF5 compression optional): the
     * sample series carry no filter. The default file's series are shuffled
     * and deflated, their chunks packed by capdyn itself (src/io/h5_pack.c:
     * byte planes deflated or stored by their entropy) and rewritten at every
     * commit while they fill: every dataset of the two files of the same run
     * (the Fig. 5 grasp, 0.3 s: 301 samples, contact series of 44 slots in
     * float64, int8 modes, int64 counters; a commit every few samples,
     * flush_every = 1 ms of wall time) must hold the same bytes, read by
     * HDF5's own filters, but the wall-clock time of each sample. (With a
     * commit every millisecond the compressed file is the larger one: a
     * rewritten chunk that grew takes new space, rule 2 of src/io/h5.c.) */
    char dir[64], sc[512], h5[2][256], *err = NULL;
    const char *opt[2] = {"simulation.compress=true", "simulation.compress=false"};
    static ds_list l[2];
    hid_t f[2];
    int k, i, rc, nseries = 0;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "paper_fig5_envelope_grasp.toml");
    for (k = 0; k < 2; k++) {
        snprintf(h5[k], sizeof h5[k], "%s/c%d.h5", dir, k);
        rc = capdyn(dir, NULL, &err, "run", sc, "-o", h5[k], "--quiet", "--set", "simulation.duration=0.3", "--set",
                    "simulation.flush_every=1e-3", "--set", opt[k], (char *)NULL);
        cr_assert_eq(rc, 0, "exit %d: %s", rc, err);
        free(err);
        f[k] = open_ro(h5[k]);
        cr_assert(f[k] >= 0);
        l[k].n = 0;
        cr_assert_geq(H5Ovisit(f[k], H5_INDEX_NAME, H5_ITER_NATIVE, list_ds, &l[k]), 0);
    }
    cr_assert_eq(l[0].n, l[1].n, "the same datasets");
    for (i = 0; i < l[0].n; i++) {
        size_t nb[2];
        int nf[2];
        unsigned char *b[2];
        cr_assert_str_eq(l[0].name[i], l[1].name[i]);
        for (k = 0; k < 2; k++) b[k] = read_bytes(f[k], l[0].name[i], &nb[k], &nf[k]);
        cr_assert(b[0] && b[1], "%s reads", l[0].name[i]);
        cr_expect_eq(nb[0], nb[1], "%s: %zu and %zu bytes", l[0].name[i], nb[0], nb[1]);
        if (nf[1] == 0 && nf[0] > 0) { /* a sample series */
            nseries++;
            cr_expect_eq(nf[0], strstr(l[0].name[i], "mode") ? 1 : 2, "%s: %d filters", l[0].name[i], nf[0]);
            if (!strstr(l[0].name[i], "wall_time"))
                cr_expect(nb[0] == nb[1] && memcmp(b[0], b[1], nb[0]) == 0, "%s: the same bytes", l[0].name[i]);
        }
        free(b[0]);
        free(b[1]);
    }
    cr_expect_geq(nseries, 20, "sample series compared: %d", nseries);
    H5Fclose(f[0]);
    H5Fclose(f[1]);
    rm_rf(dir);
}

/* An initial pose that overlaps (the region cylinder at x = 0.03 m, inside
 * the right finger): capdyn check warns once on stderr, naming the deepest
 * check point, both bodies and the depth (22.6 mm: the nearest check
 * point, radius 8 mm, on the finger's axis at x = 0.05 m, is 20.4 mm from the
 * cylinder's axis, radius 35 mm: 35 + 8 - 20.4), and
 * still exits 0 (it is physics, not an error); the scenario as shipped gets
 * no warning. */
Test(cli, an_overlapping_initial_pose_is_warned_about)
{
    char dir[256], sc[512], *out = NULL, *err = NULL;
    int rc;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "tako_vs_space_region.toml");
    rc = capdyn(dir, &out, &err, "check", sc, "--set", "target.object.position=[0.03,0.08,0]", (char *)NULL);
    cr_expect_eq(rc, 0, "%s", err);
    cr_expect(err && strstr(err, "warning") && strstr(err, "initial pose overlaps") && strstr(err, "'hand/f1_l0'") &&
                  strstr(err, "'object/object'") && strstr(err, "22.6 mm"),
              "stderr: %s", err ? err : "(none)");
    free(out);
    free(err);
    out = err = NULL;
    rc = capdyn(dir, &out, &err, "check", sc, (char *)NULL);
    cr_expect_eq(rc, 0);
    cr_expect(!err || !strstr(err, "warning"), "stderr: %s", err);
    free(out);
    free(err);
    rm_rf(dir);
}

/* the double of a dataset's element i (read as double) */
static double ds_elem(const char *path, const char *name, long i)
{
    hid_t f = open_ro(path), d;
    double v[64];
    cr_assert(f >= 0, "%s", path);
    d = H5Dopen2(f, name, H5P_DEFAULT);
    cr_assert(d >= 0 && H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) >= 0, "%s", name);
    H5Dclose(d);
    H5Fclose(f);
    return v[i];
}

Test(cli, numbers_print_in_the_shortest_form_that_reads_back, .timeout = 60)
{
    /* issue 27: `sweep --table` printed 0.059999999999999998 and `length
     * 0.14999999999999999`; `info` printed rtol 1.23456789e-9 as 1.23457e-09.
     * Now: 0.06, length 0.15, rtol 1.23456789e-09; every number of the
     * table reads back (strtod) as exactly the value in the summary, and
     * none has more than the 17 significant digits a double needs. */
    char dir[64], sc[512], s[600], r[600], *out = NULL, *err = NULL, *line, *save = NULL;
    long row = 0;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "tako_centred.toml");
    snprintf(s, sizeof s, "%s/s.h5", dir);
    snprintf(r, sizeof r, "%s/r.h5", dir);
    cr_assert_eq(capdyn(dir, NULL, &err, "sweep", sc, "--set", "simulation.duration=0.02", "--set",
                        "simulation.output_dt=0.01", "--vary", "target.object.position[0]=0.06,0.07", "--length", "0.15",
                        "-q", "-o", s, NULL),
                 0, "%s", err);
    free(err);
    cr_assert_eq(capdyn(dir, &out, &err, "sweep", "--table", s, NULL), 0, "%s", err);
    cr_expect(strstr(out, "# length 0.15 m "), "%s", out);
    for (line = strtok_r(out, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
        char tok[9][64];
        double want[9];
        int k;
        if (line[0] == '#') continue;
        cr_assert_eq(sscanf(line, "%*s %*s %63s %*s %*s %63s %63s %63s %63s %63s %63s %63s", tok[0], tok[1], tok[2],
                            tok[3], tok[4], tok[5], tok[6], tok[7]),
                     8, "%s", line);
        want[0] = ds_elem(s, "param_numeric", row) / 0.15;
        want[1] = ds_elem(s, "t_capture", row);
        want[2] = ds_elem(s, "t_escape", row);
        want[3] = ds_elem(s, "peak_fn", row);
        want[4] = ds_elem(s, "peak_tau", row);
        want[5] = ds_elem(s, "epsilon", row);
        want[6] = ds_elem(s, "fn_step_max", row);
        want[7] = ds_elem(s, "t_final", row);
        for (k = 0; k < 8; k++) {
            double v = strtod(tok[k], NULL);
            size_t digits = 0;
            const char *c;
            for (c = tok[k]; *c && *c != 'e'; c++) digits += *c >= '0' && *c <= '9';
            if (isnan(want[k])) cr_expect_str_eq(tok[k], "nan", "column %d: %s", k, line);
            else cr_expect_eq(v, want[k], "column %d: '%s' reads back as %.17g, the summary has %.17g", k, tok[k], v, want[k]);
            cr_expect_leq(digits, 18, "'%s': at most 17 significant digits", tok[k]);
        }
        cr_expect_str_eq(tok[7], "0.02", "t_final: %s", line);
        cr_expect(!strncmp(line, row ? "1 0.07 " : "0 0.06 ", 7), "the swept value as given: %s", line);
        row++;
    }
    cr_expect_eq(row, 2);
    free(out);
    free(err);
    cr_assert_eq(capdyn(dir, NULL, &err, "run", sc, "-q", "-o", r, "--set", "simulation.duration=0.02", "--set",
                        "simulation.rtol=1.23456789e-9", NULL),
                 0, "%s", err);
    free(err);
    cr_assert_eq(capdyn(dir, &out, &err, "info", r, NULL), 0, "%s", err);
    cr_expect(strstr(out, "rtol 1.23456789e-09, atol 1e-10"), "%s", out);
    free(out);
    free(err);
    rm_rf(dir);
}

/* issue 22 (a): a capture scenario without [capture] workspace gets a default
 * that covers the arm's reach: 1.5 x (the hand's reach + the arm's stretched
 * length from the first arm joint to the palm centre: 0.15 + 0.9 + 0.9 + 0.1
 * + 0.1 m of joint offsets + 0.12 m palm offset = 2.27 m), not 'escaped at
 * t = 0' (the target's CoM starts 1.12 m from the palm) */
Test(cli, a_capture_without_workspace_covers_the_arm_reach)
{
    char p[1024];
    const char *r = getenv("CAPDYN_ROOT");
    cd_error e;
    cd_scenario *sc;
    cd_data *d;
    cd_monitor mo;
    cd_monitor_opts op;
    snprintf(p, sizeof p, "%s/scenarios/capture_handrail_tumbling.toml", r ? r : ".");
    sc = cd_scenario_load(p, NULL, 0, &e);
    cr_assert(sc, "%s", e.msg);
    d = cd_data_create(sc->model, 0, &e);
    cr_assert(d, "%s", e.msg);
    op = cd_scenario_monitor_opts(sc);
    op.workspace = 0; /* what the loader leaves when the key is omitted */
    cr_assert_eq(cd_monitor_init(&mo, sc->model, d, &op, &e), CD_OK, "%s", e.msg);
    cr_expect(fabs(mo.opt.workspace - 1.5 * (mo.reach + 2.27)) < 1e-12, "workspace %.17g, reach %.17g", mo.opt.workspace,
              mo.reach);
    cd_monitor_update(&mo, sc->model, d);
    cr_expect(mo.offset_norm > 1.0 && mo.offset_norm < mo.opt.workspace, "offset %g, workspace %g", mo.offset_norm,
              mo.opt.workspace);
    cr_expect_eq(mo.verdict, CD_VERDICT_UNRESOLVED, "verdict %s at t = 0", cd_verdict_name(mo.verdict));
    cd_data_free(d);
    cd_scenario_free(sc);
}

/* issue 22 (a): an explicit workspace smaller than the target's start
 * distance is warned about by check (and run) */
Test(cli, a_target_outside_the_workspace_is_warned_about)
{
    char dir[256], sc[512], *out = NULL, *err = NULL;
    int rc;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "capture_handrail_tumbling.toml");
    rc = capdyn(dir, &out, &err, "check", sc, "--set", "capture.workspace=0.5", (char *)NULL);
    cr_expect_eq(rc, 0, "%s", err);
    cr_expect(err && strstr(err, "capdyn: warning: ") &&
                  strstr(err, ": the object 'target' starts 1.123 m from the palm centre, outside the capture workspace "
                              "([capture] workspace = 0.5 m): the verdict is 'escaped' at t = 0\n"),
              "stderr: %s", err ? err : "(none)");
    free(out);
    free(err);
    out = err = NULL;
    rc = capdyn(dir, &out, &err, "check", sc, (char *)NULL);
    cr_expect_eq(rc, 0);
    cr_expect(!err || !strstr(err, "workspace"), "stderr: %s", err);
    free(out);
    free(err);
    rm_rf(dir);
}

/* issue 22 (c): with [control] attitude control on (reaction-wheel torque on
 * the base, an external torque), the summary does not call the angular
 * momentum conserved; with it off it does; capdyn info, which cannot tell
 * from the file, says when it is */
Test(cli, attitude_control_is_not_called_momentum_conserving, .timeout = 120)
{
    char dir[256], sc[512], h5[600], *out = NULL, *err = NULL;
    int rc;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "capture_handrail_tumbling.toml");
    snprintf(h5, sizeof h5, "%s/a.h5", dir);
    rc = capdyn(dir, &out, &err, "run", sc, "-o", h5, "--set", "simulation.duration=0.2", (char *)NULL);
    cr_assert_eq(rc, 0, "%s", err);
    cr_expect(out && strstr(out, "\n            (linear expected to be conserved: free-floating systems, no gravity; angular "
                                 "not expected to be conserved: attitude control applies torque to the base)\n"),
              "stdout: %s", out ? out : "(none)");
    cr_expect(out && !strstr(out, "(expected to be conserved"), "stdout: %s", out);
    free(out);
    free(err);
    out = err = NULL;
    rc = capdyn(dir, &out, &err, "info", h5, (char *)NULL);
    cr_expect_eq(rc, 0, "%s", err);
    cr_expect(out && strstr(out, "(expected to be conserved: free-floating systems, no gravity; angular only if "
                                 "[control] attitude control was off: it applies torque to the base)\n"),
              "stdout: %s", out ? out : "(none)");
    free(out);
    free(err);
    out = err = NULL;
    rc = capdyn(dir, &out, &err, "run", sc, "-o", h5, "--set", "simulation.duration=0.2", "--set",
                "control.attitude.on=false", (char *)NULL);
    cr_assert_eq(rc, 0, "%s", err);
    cr_expect(out && strstr(out, "\n            (expected to be conserved: free-floating systems, no gravity)\n"),
              "stdout: %s", out ? out : "(none)");
    free(out);
    free(err);
    rm_rf(dir);
}

/* issue 22 (d): no energy drift relative to a kinetic energy near zero: a
 * ball at rest without gravity has T = 0 over the run; the summary gives the
 * absolute drift (0 J) and says why there is no relative one. The moving
 * ball still gets its relative figure. */
Test(cli, no_relative_energy_figure_against_a_kinetic_energy_near_zero)
{
    char dir[256], toml[512], h5[600], *out = NULL, *err = NULL;
    int rc;
    make_tmpdir(dir, sizeof dir);
    snprintf(toml, sizeof toml, "%s/ball.toml", dir);
    snprintf(h5, sizeof h5, "%s/ball.h5", dir);
    write_file(toml, ball_toml);
    rc = capdyn(dir, &out, &err, "run", toml, "-o", h5, "--set", "system.ball.velocity=[0.0, 0.0, 0.0]", (char *)NULL);
    cr_assert_eq(rc, 0, "exit %d, stderr: %s", rc, err);
    cr_expect(out && strstr(out, "energy      kinetic + gravitational: E(0) = 0 J, E(end) = 0 J, max |E - E(0)| = 0 J\n"
                                 "            (no relative figure: the largest kinetic energy, 0 J, is near zero, at most "
                                 "1e-9 of |E|; contact springs and actuator work are not in E)\n"),
              "stdout: %s", out ? out : "(none)");
    free(out);
    free(err);
    out = err = NULL;
    /* at rest against the wall under gravity g = 9.81 m/s^2 toward it, at
     * the spring's equilibrium (penetration m g / K = 9.81e-4 m): T stays at
     * round-off (about 1e-29 J) while E = -m g x = 0.971 J */
    rc = capdyn(dir, &out, &err, "run", toml, "-o", h5, "--set", "system.ball.velocity=[0.0, 0.0, 0.0]", "--set",
                "simulation.gravity=[9.81, 0.0, 0.0]", "--set", "system.ball.position=[-0.099019, 0.0, 0.0]", (char *)NULL);
    cr_assert_eq(rc, 0, "exit %d, stderr: %s", rc, err);
    {
        const char *p = out ? strstr(out, "(no relative figure: the largest kinetic energy, ") : NULL;
        double T = p ? strtod(p + strlen("(no relative figure: the largest kinetic energy, "), NULL) : NAN;
        cr_expect(p && strstr(out, "E(0) = 0.97137639 J") && T >= 0 && T < 1e-20 &&
                      strstr(p, " J, is near zero, at most 1e-9 of |E|; contact springs and actuator work are not in E)\n"),
                  "stdout: %s", out ? out : "(none)");
    }
    free(out);
    free(err);
    out = err = NULL;
    rc = capdyn(dir, &out, &err, "run", toml, "-o", h5, (char *)NULL);
    cr_assert_eq(rc, 0, "exit %d, stderr: %s", rc, err);
    cr_expect(out && strstr(out, " relative to the largest kinetic energy; contact springs") && !strstr(out, "no relative figure"),
              "stdout: %s", out ? out : "(none)");
    free(out);
    free(err);
    rm_rf(dir);
}

Test(cli, export_to_a_full_device_fails_with_one_line)
{
    /* every export writes through the reading child's temporary file; the
     * parent's copy to stdout must report a device that takes nothing
     * (/dev/full: ENOSPC). The contacts table fitted stdio's buffer and
     * exited 0 with nothing written. */
    static const char *what[] = {"events", "contacts", "system carrier"};
    char dir[64], sc[512], cmd[2048], *err;
    int i, rc;
    if (access("/dev/full", W_OK) != 0) cr_skip_test("no /dev/full here");
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "paper_fig3_impact.toml");
    snprintf(cmd, sizeof cmd, "%s run %s -o %s/r.h5 -q --set simulation.duration=0.05", bin(), sc, dir);
    cr_assert_eq(system(cmd), 0, "%s", cmd);
    for (i = 0; i < 3; i++) {
        snprintf(cmd, sizeof cmd, "%s export %s/r.h5 %s > /dev/full 2> %s/err.txt", bin(), dir, what[i], dir);
        rc = system(cmd);
        cr_expect(WIFEXITED(rc) && WEXITSTATUS(rc) == 1, "export %s to /dev/full: status %d", what[i], rc);
        snprintf(cmd, sizeof cmd, "%s/err.txt", dir);
        err = slurp(cmd);
        cr_expect(err && strstr(err, "capdyn: error: writing the output failed: No space left on device") != NULL,
                  "export %s: stderr '%s'", what[i], err ? err : "");
        free(err);
    }
    rm_rf(dir);
}
