/* capdyn sweep (issue 9, docs/sweep.md): the summary is the same for any
 * number of worker processes (and, where built, MPI ranks), a failing
 * variant is recorded while the others complete, an interrupted sweep
 * resumes to the same summary, a variant's verdict is the one `capdyn run`
 * gives, and the TAKO-vs-Space region ordering.
 *
 * The sweeps here are small and short (a 5x5 grid of 0.08 s runs) so that
 * `make test` stays quick on a shared machine. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include <capdyn/verdict.h>
#include <hdf5.h>
#include "proc_util.h"
#include "h5_test_util.h"
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <dirent.h>

/* ---- comparing two summaries (everything but /timing) -------------------- */

/* The bytes of a dataset or attribute as text: strings one per line,
 * numbers by their raw bytes in hex. */
static char *values_of(hid_t obj, int is_attr)
{
    hid_t t = is_attr ? H5Aget_type(obj) : H5Dget_type(obj);
    hid_t s = is_attr ? H5Aget_space(obj) : H5Dget_space(obj);
    hssize_t n = H5Sget_simple_extent_npoints(s);
    size_t sz = H5Tget_size(t), len = 0, cap = 64, i;
    char *out = malloc(cap);
    cr_assert_not_null(out);
    out[0] = 0;
#define APPEND(str)                                                                                                \
    do {                                                                                                           \
        const char *a_ = (str);                                                                                    \
        size_t l_ = strlen(a_);                                                                                    \
        while (len + l_ + 2 > cap) out = realloc(out, cap *= 2);                                                   \
        memcpy(out + len, a_, l_ + 1);                                                                             \
        len += l_;                                                                                                 \
    } while (0)
    if (H5Tget_class(t) == H5T_STRING && H5Tis_variable_str(t) > 0) {
        char **v = calloc((size_t)n + 1, sizeof *v);
        cr_assert((is_attr ? H5Aread(obj, t, v) : H5Dread(obj, t, H5S_ALL, H5S_ALL, H5P_DEFAULT, v)) >= 0);
        for (i = 0; i < (size_t)n; i++) {
            APPEND(v[i] ? v[i] : "(null)");
            APPEND("\n");
            H5free_memory(v[i]);
        }
        free(v);
    } else {
        unsigned char *b = malloc(sz * (size_t)n + 1);
        char hx[4];
        cr_assert((is_attr ? H5Aread(obj, t, b) : H5Dread(obj, t, H5S_ALL, H5S_ALL, H5P_DEFAULT, b)) >= 0);
        for (i = 0; i < sz * (size_t)n; i++) {
            snprintf(hx, sizeof hx, "%02x", b[i]);
            APPEND(hx);
        }
        free(b);
    }
#undef APPEND
    H5Sclose(s);
    H5Tclose(t);
    return out;
}

typedef struct {
    hid_t other;
    const char *path_b;
    int count;
} cmp_ctx;

static herr_t cmp_attr(hid_t loc, const char *name, const H5A_info_t *info, void *op)
{
    cmp_ctx *c = op;
    hid_t a = H5Aopen(loc, name, H5P_DEFAULT), b;
    char *va, *vb;
    (void)info;
    cr_assert(H5Aexists(c->other, name) > 0, "attribute %s missing in %s", name, c->path_b);
    b = H5Aopen(c->other, name, H5P_DEFAULT);
    va = values_of(a, 1);
    vb = values_of(b, 1);
    cr_assert_str_eq(va, vb, "attribute %s differs", name);
    free(va);
    free(vb);
    H5Aclose(a);
    H5Aclose(b);
    c->count++;
    return 0;
}

static herr_t cmp_obj(hid_t loc, const char *name, const H5L_info_t *info, void *op)
{
    cmp_ctx *c = op;
    H5O_info_t oi;
    (void)info;
    if (!strcmp(name, "timing")) return 0; /* wall times: not deterministic */
    cr_assert(H5Lexists(c->other, name, H5P_DEFAULT) > 0, "%s missing in %s", name, c->path_b);
    H5Oget_info_by_name(loc, name, &oi, H5P_DEFAULT);
    if (oi.type == H5O_TYPE_GROUP) {
        hid_t ga = H5Gopen2(loc, name, H5P_DEFAULT), gb = H5Gopen2(c->other, name, H5P_DEFAULT);
        cmp_ctx sub = {gb, c->path_b, 0};
        H5Literate(ga, H5_INDEX_NAME, H5_ITER_INC, NULL, cmp_obj, &sub);
        c->count += sub.count;
        H5Gclose(ga);
        H5Gclose(gb);
    } else {
        hid_t da = H5Dopen2(loc, name, H5P_DEFAULT), db = H5Dopen2(c->other, name, H5P_DEFAULT);
        char *va = values_of(da, 0), *vb = values_of(db, 0);
        cr_assert_str_eq(va, vb, "dataset %s differs", name);
        free(va);
        free(vb);
        H5Dclose(da);
        H5Dclose(db);
        c->count++;
    }
    return 0;
}

/* Every dataset and root attribute of a equals b's, /timing excepted, and
 * both have the same number of objects. */
static void same_summary(const char *a, const char *b)
{
    hid_t fa = open_ro(a), fb = open_ro(b);
    cmp_ctx c1, c2;
    hsize_t na = 0, nb = 0;
    cr_assert(fa >= 0 && fb >= 0, "open %s and %s", a, b);
    c1.other = fb;
    c1.path_b = b;
    c1.count = 0;
    H5Literate(fa, H5_INDEX_NAME, H5_ITER_INC, NULL, cmp_obj, &c1);
    c2 = c1;
    c2.count = 0;
    H5Aiterate2(fa, H5_INDEX_NAME, H5_ITER_INC, NULL, cmp_attr, &c2);
    cr_assert_gt(c1.count, 15, "only %d datasets compared", c1.count);
    cr_assert_gt(c2.count, 10, "only %d attributes compared", c2.count);
    {
        H5G_info_t ga, gb;
        H5Gget_info(fa, &ga);
        H5Gget_info(fb, &gb);
        na = ga.nlinks;
        nb = gb.nlinks;
    }
    cr_assert_eq(na, nb, "%s has %llu objects, %s %llu", a, (unsigned long long)na, b, (unsigned long long)nb);
    H5Fclose(fa);
    H5Fclose(fb);
}

static long long ds_ll(hid_t f, const char *name, long i)
{
    long long v[4096];
    hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
    cr_assert(d >= 0, "dataset %s", name);
    cr_assert(H5Dread(d, H5T_NATIVE_LLONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) >= 0);
    H5Dclose(d);
    return v[i];
}
static double ds_d(hid_t f, const char *name, long i)
{
    double v[4096];
    hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
    cr_assert(d >= 0, "dataset %s", name);
    cr_assert(H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) >= 0);
    H5Dclose(d);
    return v[i];
}
static void ds_str(hid_t f, const char *name, long i, char *out, size_t n)
{
    char *v[4096];
    hid_t d = H5Dopen2(f, name, H5P_DEFAULT), t = H5Tcopy(H5T_C_S1);
    long k, cnt;
    H5Tset_size(t, H5T_VARIABLE);
    H5Tset_cset(t, H5T_CSET_UTF8);
    cr_assert(d >= 0, "dataset %s", name);
    {
        hid_t s = H5Dget_space(d);
        cnt = (long)H5Sget_simple_extent_npoints(s);
        H5Sclose(s);
    }
    cr_assert(H5Dread(d, t, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) >= 0);
    snprintf(out, n, "%s", v[i] ? v[i] : "");
    for (k = 0; k < cnt; k++) H5free_memory(v[k]);
    H5Tclose(t);
    H5Dclose(d);
}

#define SHORT "--set", "simulation.duration=0.08", "--set", "simulation.output_dt=0.01"
#define GRID5 "--vary", "target.object.position[0]=-0.004:0.004:5", "--vary", "target.object.position[1]=0.07:0.09:5"

/* argv[n..]: BIN sweep SCENARIO SHORT; returns the new n */
static int sweep_argv(char **argv, int n, const char *b, char *sc)
{
    argv[n++] = (char *)b;
    argv[n++] = "sweep";
    argv[n++] = sc;
    argv[n++] = "--set";
    argv[n++] = "simulation.duration=0.08";
    argv[n++] = "--set";
    argv[n++] = "simulation.output_dt=0.01";
    return n;
}

/* ---- tests ------------------------------------------------------------------ */

Test(sweep, grid_5x5_same_summary_serial_and_two_workers, .timeout = 240)
{
    char dir[256], sc[512], s1[512], s2[512], r[512], *out = NULL, *err = NULL, val[64];
    hid_t f, g;
    long i;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "tako_centred.toml");
    snprintf(s1, sizeof s1, "%s/j1.h5", dir);
    snprintf(s2, sizeof s2, "%s/j2.h5", dir);
    cr_assert_eq(capdyn(dir, &out, &err, "sweep", sc, SHORT, GRID5, "-j", "1", "-o", s1, NULL), 0, "%s", err);
    cr_assert(strstr(out, "25 of 25 variants run (0 failed)"), "%s", out);
    free(out);
    free(err);
    cr_assert_eq(capdyn(dir, &out, &err, "sweep", sc, SHORT, GRID5, "-j", "2", "-q", "-o", s2, NULL), 0, "%s", err);
    cr_assert_str_eq(out, "", "--quiet prints nothing: %s", out);
    free(out);
    free(err);
    same_summary(s1, s2);
    same_summary(s2, s1);

    f = open_ro(s1);
    cr_assert(f >= 0);
    cr_assert_eq(attr_ll(f, "n_variants"), 25);
    cr_assert_eq(attr_ll(f, "complete"), 1);
    cr_assert_eq(attr_ll(f, "n_failed"), 0);
    /* C order, the first key slowest: variant 7 = (x index 1, y index 2) */
    ds_str(f, "param_values", 7 * 2 + 0, val, sizeof val);
    cr_assert_str_eq(val, "-0.002");
    ds_str(f, "param_values", 7 * 2 + 1, val, sizeof val);
    cr_assert_str_eq(val, "0.08");
    for (i = 0; i < 25; i++) {
        cr_assert_eq(ds_ll(f, "status", i), 0, "variant %ld", i);
        cr_assert_eq(ds_d(f, "t_final", i), 0.08, "variant %ld ran to the end", i);
    }
    g = H5Gopen2(f, "timing", H5P_DEFAULT);
    cr_assert(g >= 0);
    cr_assert_eq(attr_ll(g, "jobs"), 1);
    H5Gclose(g);

    /* a variant is a normal run: capdyn run with the same overrides gives the
     * same figures of merit, exactly (variant 12: x = 0, y = 0.08) */
    snprintf(r, sizeof r, "%s/v12.h5", dir);
    cr_assert_eq(capdyn(dir, NULL, NULL, "run", sc, SHORT, "--set", "target.object.position[0]=0", "--set",
                        "target.object.position[1]=0.08", "-q", "-o", r, NULL),
                 0);
    {
        hid_t fr = open_ro(r);
        char v[64];
        cr_assert(fr >= 0);
        cr_assert_eq(attr_d(fr, "capture_peak_fn"), ds_d(f, "peak_fn", 12));
        cr_assert_eq(attr_d(fr, "t_final"), ds_d(f, "t_final", 12));
        cr_assert_eq(attr_ll(fr, "stats_nrhs"), ds_ll(f, "stats_rhs", 12));
        attr_s(fr, "capture_verdict", v, sizeof v);
        cr_assert_eq(ds_ll(f, "verdict", 12), !strcmp(v, "captured") ? 1 : !strcmp(v, "escaped") ? 2 : 0);
        H5Fclose(fr);
    }
    H5Fclose(f);
    rm_rf(dir);
}

Test(sweep, a_failing_variant_is_recorded_and_the_rest_complete, .timeout = 120)
{
    char dir[256], sc[512], s[512], *out = NULL, *err = NULL, why[600];
    hid_t f;
    long i;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "tako_centred.toml");
    snprintf(s, sizeof s, "%s/fail.h5", dir);
    /* variant 2's work budget is far below what the run needs (the loader
     * accepts it: at least 960 evaluations); variant 4's mass is refused */
    cr_assert_eq(capdyn(dir, &out, &err, "sweep", sc, SHORT, "--vary",
                        "simulation.max_rhs_evals=1e9,1e9,3000,1e9,1e9", "-j", "2", "-o", s, NULL),
                 0, "%s", err);
    cr_assert(strstr(out, "5 of 5 variants run (1 failed)"), "%s", out);
    cr_assert(strstr(out, "variant 2 failed: work budget spent:"), "%s", out);
    free(out);
    free(err);
    f = open_ro(s);
    cr_assert(f >= 0);
    cr_assert_eq(attr_ll(f, "n_failed"), 1);
    cr_assert_eq(attr_ll(f, "complete"), 1);
    for (i = 0; i < 5; i++) {
        ds_str(f, "failure", i, why, sizeof why);
        if (i == 2) {
            cr_assert_eq(ds_ll(f, "status", i), CD_EINTERRUPT);
            cr_assert(strstr(why, "more than simulation.max_rhs_evals = 3000"), "%s", why);
            cr_assert_lt(ds_d(f, "t_final", i), 0.08);
        } else {
            cr_assert_eq(ds_ll(f, "status", i), 0, "variant %ld: %s", i, why);
            cr_assert_str_eq(why, "");
            cr_assert_eq(ds_d(f, "t_final", i), 0.08);
        }
    }
    H5Fclose(f);

    /* a value the loader refuses, in a later variant: recorded with its message */
    cr_assert_eq(capdyn(dir, &out, &err, "sweep", sc, SHORT, "--vary", "target.object.mass=0.3,-1", "-j", "1", "-o",
                        s, NULL),
                 0, "%s", err);
    cr_assert(strstr(out, "variant 1 failed:") && strstr(out, "mass"), "%s", out);
    free(out);
    free(err);
    f = open_ro(s);
    cr_assert_eq(ds_ll(f, "status", 1), 1000);
    cr_assert_eq(ds_ll(f, "status", 0), 0);
    H5Fclose(f);
    rm_rf(dir);
}

Test(sweep, an_interrupted_sweep_resumes_to_the_same_summary, .timeout = 240)
{
    char dir[256], sc[512], full[512], part[512], *out = NULL, *err = NULL;
    char *argv[32];
    int n = 0, st;
    pid_t pid;
    hid_t f;
    long long nrun;
    const char *vary = "target.object.position[1]=0.07:0.09:8";
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "tako_centred.toml");
    snprintf(full, sizeof full, "%s/full.h5", dir);
    snprintf(part, sizeof part, "%s/part.h5", dir);
    cr_assert_eq(capdyn(dir, NULL, &err, "sweep", sc, SHORT, "--vary", vary, "-j", "2", "-q", "-o", full, NULL), 0,
                 "%s", err);
    free(err);

    n = sweep_argv(argv, n, bin(), sc);
    argv[n++] = "--vary";
    argv[n++] = (char *)vary;
    argv[n++] = "-j";
    argv[n++] = "1";
    argv[n++] = "-o";
    argv[n++] = part;
    argv[n] = NULL;
    pid = spawn(dir, argv, NULL);
    /* stop it once the first variants are done (each takes ~0.1 s) */
    sleep_s(0.5);
    kill(pid, SIGINT);
    st = wait_status(pid);
    f = open_ro(part);
    cr_assert(f >= 0, "the partial summary is readable");
    nrun = attr_ll(f, "n_run");
    if (st == 130) {
        cr_assert_eq(attr_ll(f, "complete"), 0);
        cr_assert_lt(nrun, 8);
        cr_assert_eq(ds_ll(f, "status", 7), -1, "the last variant is marked not run");
    } else {
        cr_assert_eq(st, 0, "exit status %d", st);
        cr_log_info("the sweep ended before SIGINT (a very fast machine): resume is a no-op");
    }
    H5Fclose(f);
    {
        char ep[600], *e;
        snprintf(ep, sizeof ep, "%s/err.txt", dir);
        e = slurp(ep);
        if (st == 130) cr_assert(e && strstr(e, "continue with --resume"), "%s", e ? e : "");
        free(e);
    }

    /* --resume with another sweep is refused; the same sweep completes */
    cr_assert_eq(capdyn(dir, NULL, &err, "sweep", sc, SHORT, "--vary", "target.object.position[1]=0.07:0.09:7",
                        "--resume", "-o", part, NULL),
                 1);
    cr_assert(strstr(err, "--resume:"), "%s", err);
    free(err);
    cr_assert_eq(capdyn(dir, &out, &err, "sweep", sc, SHORT, "--vary", vary, "-j", "2", "--resume", "-o", part, NULL),
                 0, "%s", err);
    cr_assert(strstr(out, "8 of 8 variants run"), "%s", out);
    free(out);
    free(err);
    same_summary(full, part);
    rm_rf(dir);
}

Test(sweep, bad_command_lines)
{
    char dir[256], sc[512], *err = NULL;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "tako_centred.toml");
    cr_assert_eq(capdyn(dir, NULL, &err, "sweep", sc, NULL), 2);
    cr_assert(strstr(err, "nothing to vary"), "%s", err);
    free(err);
    cr_assert_eq(capdyn(dir, NULL, &err, "sweep", sc, "--vary", "simulation.duration=1:2", NULL), 2);
    cr_assert(strstr(err, "expected A:B:N"), "%s", err);
    free(err);
    cr_assert_eq(capdyn(dir, NULL, &err, "sweep", sc, "--vary", "a=1,2", "--vary", "a=3,4", NULL), 2);
    cr_assert(strstr(err, "given twice"), "%s", err);
    free(err);
    cr_assert_eq(capdyn(dir, NULL, &err, "sweep", sc, "--vary", "a=1,,2", NULL), 2);
    cr_assert(strstr(err, "empty value"), "%s", err);
    free(err);
    /* a key the scenario does not have: the loader's message, nothing run */
    cr_assert_eq(capdyn(dir, NULL, &err, "sweep", sc, "--vary", "target.object.mas=1,2", NULL), 1);
    cr_assert(strstr(err, "target") && strstr(err, "(the first variant)"), "%s", err);
    free(err);
    rm_rf(dir);
}

Test(sweep, latin_hypercube_covers_every_stratum_once)
{
    char dir[256], sc[512], s[512], *err = NULL;
    hid_t f;
    int seen[10] = {0}, i;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "tako_centred.toml");
    snprintf(s, sizeof s, "%s/lhs.h5", dir);
    /* the runs are made as short as the loader allows: only the plan matters */
    cr_assert_eq(capdyn(dir, NULL, &err, "sweep", sc, "--set", "simulation.duration=0.002", "--set",
                        "simulation.output_dt=0.001", "--lhs", "10", "--seed", "7", "--vary",
                        "target.object.position[1]=0.07:0.09", "--vary", "target.object.mass=0.2:0.4", "-q", "-o", s,
                        NULL),
                 0, "%s", err);
    free(err);
    f = open_ro(s);
    cr_assert(f >= 0);
    for (i = 0; i < 10; i++) {
        double y, m2;
        double v[20];
        hid_t d = H5Dopen2(f, "param_numeric", H5P_DEFAULT);
        cr_assert(H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) >= 0);
        H5Dclose(d);
        y = v[2 * i];
        m2 = v[2 * i + 1];
        cr_assert(y >= 0.07 && y <= 0.09 && m2 >= 0.2 && m2 <= 0.4, "variant %d: %g %g", i, y, m2);
        seen[(int)((y - 0.07) / 0.002 * (1 - 1e-12))]++;
    }
    for (i = 0; i < 10; i++) cr_assert_eq(seen[i], 1, "stratum %d of y holds %d samples", i, seen[i]);
    H5Fclose(f);
    rm_rf(dir);
}

/* TAKO vs Space Gripper (issue 9; docs/sweep.md, "TAKO vs Space Gripper"):
 * the two scenarios, which share fingers, object, contact law and torque
 * scale, on a coarse grid of the same positions (x = -0.006, 0 m; y = 0.07,
 * 0.13, 0.19 m), as a regression of what the physics gives today. Issue 9
 * expected the Space Gripper's region to be the wider one, with off-centre
 * positions that it captures and TAKO loses; the simulation does not give
 * that (docs/sweep.md has the 5x8 map): both capture the cylinder wherever
 * its centre is between the fingers (y <= 0.17 m, the fingertips), both
 * squeeze it out when its centre is 2 cm beyond the tips (0.19 m), the same
 * verdict in every cell. This test fails as soon as that changes, in either
 * direction. Duration 3 s: the latest verdict of this grid is at 2.5 s (the
 * Space Gripper's grasp rocking after the clutch, at (-0.006, 0.13)). */
Test(sweep, tako_vs_space_region_on_a_coarse_grid, .timeout = 900)
{
    static const char *names[2] = {"tako_vs_space_region.toml", "tako_vs_space_region_space.toml"};
    /* verdicts in variant order: x = -0.006 (y 0.07, 0.11, 0.15), x = 0 (...) */
    static const int expect[2][6] = {{1, 1, 2, 1, 1, 2}, {1, 1, 2, 1, 1, 2}};
    char dir[256], sc[512], s[2][512], *err = NULL;
    long long ncap[2];
    double area[2];
    int g, i;
    make_tmpdir(dir, sizeof dir);
    for (g = 0; g < 2; g++) {
        hid_t f, rg, d;
        scen(sc, sizeof sc, names[g]);
        snprintf(s[g], sizeof s[g], "%s/region%d.h5", dir, g);
        cr_assert_eq(capdyn(dir, NULL, &err, "sweep", sc, "--set", "simulation.duration=3.0", "--vary",
                            "target.object.position[0]=-0.006:0:2", "--vary", "target.object.position[1]=0.07:0.19:3",
                            "--until-verdict", "--length", "0.15", "-j", "2", "-q", "-o", s[g], NULL),
                     0, "%s", err);
        free(err);
        f = open_ro(s[g]);
        cr_assert(f >= 0);
        for (i = 0; i < 6; i++) {
            cr_assert_eq(ds_ll(f, "status", i), 0, "%s variant %d", names[g], i);
            cr_assert_eq(ds_ll(f, "verdict", i), expect[g][i], "%s variant %d: verdict %lld, expected %d", names[g],
                         i, ds_ll(f, "verdict", i), expect[g][i]);
        }
        rg = H5Gopen2(f, "region", H5P_DEFAULT);
        cr_assert(rg >= 0, "a grid over two ranges has a region");
        d = H5Dopen2(rg, "captured", H5P_DEFAULT);
        cr_assert(H5Dread(d, H5T_NATIVE_LLONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, &ncap[g]) >= 0);
        H5Dclose(d);
        d = H5Dopen2(rg, "area", H5P_DEFAULT);
        cr_assert(H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, &area[g]) >= 0);
        H5Dclose(d);
        H5Gclose(rg);
        H5Fclose(f);
        /* the area is the captured cells x (0.006 m x 0.06 m) / (0.15 m)^2 */
        cr_assert_float_eq(area[g], (double)ncap[g] * 0.006 * 0.06 / (0.15 * 0.15), 1e-12);
    }
    /* the two regions (the verdicts above: no position that the Space
     * Gripper captures and TAKO loses, nor the reverse) */
    cr_assert_eq(ncap[0], 4);
    cr_assert_eq(ncap[1], 4);
    cr_assert_float_eq(area[0], area[1], 1e-15, "TAKO %g, Space Gripper %g", area[0], area[1]);
    rm_rf(dir);
}

/* The same comparison with a smaller cylinder (r 0.02 m, bench/region_settings.sh
 * "small"), at y = 0.11 m, centred and 2 cm off centre: the Space Gripper
 * captures it at both positions (at 0.37 and 0.41 s in the 8 s sweep), TAKO at
 * neither: its fingers close straight (the tips on their stops: the base's 4x
 * torque swings them) and meet tip to tip at 17 deg above the cylinder, which
 * then floats in the cage they close, touching nothing (no contact at the
 * end: not a grasp; it stays so to 8 s). The synchronised schedule curls the
 * Space Gripper's fingers around it before they meet. This is the one setting
 * of four where the paper's ordering shows (docs/sweep.md). Duration 1.5 s:
 * the Space Gripper's verdicts fall before 0.6 s. */
Test(sweep, a_small_cylinder_that_the_space_gripper_captures_and_tako_only_cages, .timeout = 600)
{
    static const char *names[2] = {"tako_vs_space_region.toml", "tako_vs_space_region_space.toml"};
    static const int expect[2] = {CD_VERDICT_UNRESOLVED, CD_VERDICT_CAPTURED};
    char dir[256], sc[512], out[512], *err = NULL;
    int g, i;
    make_tmpdir(dir, sizeof dir);
    for (g = 0; g < 2; g++) {
        hid_t f;
        scen(sc, sizeof sc, names[g]);
        snprintf(out, sizeof out, "%s/small%d.h5", dir, g);
        cr_assert_eq(capdyn(dir, NULL, &err, "sweep", sc, "--set", "simulation.duration=1.5", "--set",
                            "target.object.shape.radius=0.02", "--set", "target.object.inertia=[1.2e-4,1.2e-4,6e-5]",
                            "--set", "target.object.position[1]=0.11", "--vary", "target.object.position[0]=0,0.02",
                            "--until-verdict", "-j", "2", "-q", "-o", out, NULL),
                     0, "%s", err);
        free(err);
        err = NULL;
        f = open_ro(out);
        cr_assert(f >= 0);
        for (i = 0; i < 2; i++) {
            cr_assert_eq(ds_ll(f, "status", i), 0, "%s variant %d", names[g], i);
            cr_expect_eq(ds_ll(f, "verdict", i), expect[g], "%s x = %s: verdict %lld, expected %d", names[g],
                         i ? "0.02" : "0", ds_ll(f, "verdict", i), expect[g]);
            /* TAKO: no grip at the end (the grasp quality of no contacts is 0);
             * the Space Gripper: force closure */
            if (g == 0) cr_expect_eq(ds_d(f, "epsilon", i), 0.0, "TAKO x = %s: epsilon %g", i ? "0.02" : "0", ds_d(f, "epsilon", i));
            else cr_expect_gt(ds_d(f, "epsilon", i), 0.0, "Space x = %s: epsilon %g", i ? "0.02" : "0", ds_d(f, "epsilon", i));
        }
        H5Fclose(f);
    }
    rm_rf(dir);
}

/* issue 22: a caged variant's t_cage (the monitor's: the capture conditions
 * first held without force closure, docs/capture.md "Verdicts") is in the
 * summary and its text table, equal to the capdyn run of the same variant,
 * NaN for a captured one, and kept by --shard and --merge. The frictionless
 * Space Gripper wrap of tests/test_verdict.c (contact.mu = mu_max = 0) cages
 * at 0.672 s (Hunt-Crossley finger pairs; 0.547 s on the linear law); with
 * mu_max = 0.5 (the static coefficient; mu = 0) it is captured at 0.761 s. A kept run (--keep-runs) stores the peaks over steps
 * of the capdyn run. 1 s runs. */
Test(sweep, a_caged_variant_has_the_t_cage_of_capdyn_run_in_the_summary_table_and_merge, .timeout = 180)
{
    char dir[256], sc[512], full[512], sh[2][512], merged[512], run[512], keep[512], *out = NULL, *err = NULL, *line,
        *col, *save;
    double t_run, t0, t1;
    char verdict[32];
    hid_t f;
    int k, ncol, icage = -1, row;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "space_gripper_cylinder.toml");
    snprintf(full, sizeof full, "%s/full.h5", dir);
    snprintf(merged, sizeof merged, "%s/merged.h5", dir);
    snprintf(run, sizeof run, "%s/run.h5", dir);
#define CAGE_SETS "--set", "simulation.duration=1.0", "--set", "contact.mu=0.0", "--vary", "contact.mu_max=0.0,0.5"
    snprintf(keep, sizeof keep, "%s/keep", dir);
    cr_assert_eq(capdyn(dir, NULL, &err, "sweep", sc, CAGE_SETS, "-j", "1", "-q", "-o", full, "--keep-runs", keep, NULL),
                 0, "%s", err);
    free(err);
    for (k = 0; k < 2; k++) {
        char which[16];
        snprintf(sh[k], sizeof sh[k], "%s/shard%d.h5", dir, k + 1);
        snprintf(which, sizeof which, "%d/2", k + 1);
        cr_assert_eq(capdyn(dir, NULL, &err, "sweep", sc, CAGE_SETS, "--shard", which, "-q", "-o", sh[k], NULL), 0,
                     "%s", err);
        free(err);
    }
#undef CAGE_SETS
    cr_assert_eq(capdyn(dir, NULL, &err, "sweep", "--merge", sh[1], sh[0], "-o", merged, NULL), 0, "%s", err);
    free(err);
    cr_assert_eq(capdyn(dir, NULL, &err, "run", sc, "--set", "simulation.duration=1.0", "--set", "contact.mu=0.0",
                        "--set", "contact.mu_max=0.0", "-q", "-o", run, NULL),
                 0, "%s", err);
    free(err);
    f = open_ro(run);
    cr_assert(f >= 0);
    attr_s(f, "capture_verdict", verdict, sizeof verdict);
    t_run = attr_d(f, "capture_t");
    H5Fclose(f);
    cr_assert_str_eq(verdict, "caged");
    cr_expect(fabs(t_run - 0.672) < 1.5e-3, "capdyn run: caged at %.17g s", t_run);
    /* the kept run's file has the peaks over steps of capdyn run's (the same
     * run: bit for bit) */
    {
        static const char *const pk[6] = {"/contacts/fn_step_max", "/contacts/fn_step_body", "/contacts/fn_step_onset",
                                          "/contacts/ft_step_max", "/contacts/t_fn_step_body",
                                          "/contacts/t_fn_step_onset"};
        char kp[600];
        hid_t fk;
        snprintf(kp, sizeof kp, "%s/variant_000000.h5", keep);
        fk = open_ro(kp);
        f = open_ro(run);
        cr_assert(fk >= 0 && f >= 0, "%s", kp);
        for (k = 0; k < 6; k++) {
            size_t na, nb;
            double *va = read_all(f, pk[k], &na), *vb = read_all(fk, pk[k], &nb);
            cr_assert(na == nb && na > 0, "%s: %zu and %zu slots", pk[k], na, nb);
            cr_expect(memcmp(va, vb, na * sizeof *va) == 0, "%s differs between capdyn run and the kept run", pk[k]);
            free(va);
            free(vb);
        }
        H5Fclose(fk);
        H5Fclose(f);
    }

    f = open_ro(full);
    cr_assert(f >= 0);
    cr_assert_eq(attr_ll(f, "format_version"), 3);
    cr_expect_eq(ds_ll(f, "verdict", 0), CD_VERDICT_CAGED, "mu_max 0: verdict %lld", ds_ll(f, "verdict", 0));
    cr_expect_eq(ds_ll(f, "verdict", 1), CD_VERDICT_CAPTURED, "mu_max 0.5: verdict %lld", ds_ll(f, "verdict", 1));
    t0 = ds_d(f, "t_cage", 0);
    t1 = ds_d(f, "t_cage", 1);
    cr_expect(t0 == t_run, "t_cage %.17g s in the summary, capdyn run %.17g s", t0, t_run);
    cr_expect(isnan(ds_d(f, "t_capture", 0)), "the caged variant: t_capture %g", ds_d(f, "t_capture", 0));
    cr_expect(isnan(t1) && isfinite(ds_d(f, "t_capture", 1)), "the captured variant: t_cage %g, t_capture %g", t1,
              ds_d(f, "t_capture", 1));
    H5Fclose(f);
    f = open_ro(merged);
    cr_assert(f >= 0);
    cr_expect(ds_d(f, "t_cage", 0) == t_run && isnan(ds_d(f, "t_cage", 1)), "merged: t_cage %.17g, %g",
              ds_d(f, "t_cage", 0), ds_d(f, "t_cage", 1));
    H5Fclose(f);
    same_summary(full, merged);

    /* the text table: t_cage is the last column, named in the header */
    cr_assert_eq(capdyn(dir, &out, &err, "sweep", "--table", full, NULL), 0, "%s", err);
    free(err);
    row = 0;
    for (line = strtok_r(out, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
        char *s2, *tok[64];
        ncol = 0;
        for (col = strtok_r(line, " ", &s2); col && ncol < 64; col = strtok_r(NULL, " ", &s2)) tok[ncol++] = col;
        if (ncol > 1 && !strcmp(tok[0], "#") && !strcmp(tok[1], "index")) {
            cr_assert_str_eq(tok[ncol - 1], "t_cage", "the header ends with %s", tok[ncol - 1]);
            icage = ncol - 2; /* the rows have no leading '#' */
        } else if (ncol > 0 && tok[0][0] != '#') {
            double v;
            cr_assert(icage > 0 && ncol == icage + 1, "row %d: %d columns, t_cage at %d", row, ncol, icage);
            v = strtod(tok[icage], NULL);
            if (row == 0) cr_expect(v == t_run, "table row 0: t_cage '%s', capdyn run %.17g", tok[icage], t_run);
            else cr_expect_str_eq(tok[icage], "nan", "table row 1: t_cage '%s'", tok[icage]);
            row++;
        }
    }
    cr_expect_eq(row, 2, "%d rows in the table", row);
    free(out);
    rm_rf(dir);
}

/* Only where capdyn is built with MPI (make MPI=1 test sets CAPDYN_MPI_BIN):
 * the same 5x5 grid under `mpirun -n 2` (rank 0 hands out, rank 1 runs)
 * gives the summary of the serial sweep. */
Test(sweep, mpirun_two_ranks_gives_the_serial_summary, .timeout = 300)
{
    const char *mb = getenv("CAPDYN_MPI_BIN");
    char dir[256], sc[512], s1[512], sm[512], *err = NULL;
    /* spawn() splits each "K=V" in place: writable copies */
    char e1[] = "OMPI_ALLOW_RUN_AS_ROOT=1", e2[] = "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1", e3[] = "OMPI_MCA_btl=self,vader";
    char *argv[40], *env[4];
    int n = 0, st;
    hid_t f, g;
    env[0] = e1;
    env[1] = e2;
    env[2] = e3;
    env[3] = NULL;
    if (!mb || !*mb) cr_skip_test("capdyn is not built with MPI here ('make MPI=1 test' runs this test)");
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "tako_centred.toml");
    snprintf(s1, sizeof s1, "%s/serial.h5", dir);
    snprintf(sm, sizeof sm, "%s/mpi.h5", dir);
    cr_assert_eq(capdyn(dir, NULL, &err, "sweep", sc, SHORT, GRID5, "-j", "1", "-q", "-o", s1, NULL), 0, "%s", err);
    free(err);
    argv[n++] = "/usr/bin/env";
    argv[n++] = "mpirun";
    argv[n++] = "-n";
    argv[n++] = "2";
    argv[n++] = "--oversubscribe";
    n = sweep_argv(argv, n, mb, sc);
    argv[n++] = "--vary";
    argv[n++] = "target.object.position[0]=-0.004:0.004:5";
    argv[n++] = "--vary";
    argv[n++] = "target.object.position[1]=0.07:0.09:5";
    argv[n++] = "-q";
    argv[n++] = "-o";
    argv[n++] = sm;
    argv[n] = NULL;
    st = wait_status(spawn(dir, argv, env));
    if (st != 0) {
        char ep[600], *e;
        snprintf(ep, sizeof ep, "%s/err.txt", dir);
        e = slurp(ep);
        cr_assert_fail("mpirun exit status %d: %s", st, e ? e : "");
    }
    same_summary(s1, sm);
    f = open_ro(sm);
    g = H5Gopen2(f, "timing", H5P_DEFAULT);
    cr_assert_eq(attr_ll(g, "jobs"), 2, "the summary was written by rank 0 of 2");
    H5Gclose(g);
    H5Fclose(f);
    rm_rf(dir);
}

Test(sweep, resume_of_a_finished_sweep_changes_nothing, .timeout = 120)
{
    /* issue 24: --resume on a complete summary used to mark variant 0 not
     * run (status -1, complete 0) and exit 0. Now: exit 0, "3 of 3 variants
     * run", and the summary equal to the one before (all but /timing). */
    char dir[256], sc[512], s[512], before[512], *out = NULL, *err = NULL, *bytes;
    hid_t f;
    long i;
    FILE *fp;
    struct stat st;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "tako_centred.toml");
    snprintf(s, sizeof s, "%s/s.h5", dir);
    snprintf(before, sizeof before, "%s/before.h5", dir);
    cr_assert_eq(capdyn(dir, NULL, &err, "sweep", sc, SHORT, "--vary", "target.object.mass=0.3,0.4,0.5", "-q", "-o", s,
                        NULL),
                 0, "%s", err);
    free(err);
    cr_assert_eq(stat(s, &st), 0);
    bytes = malloc((size_t)st.st_size);
    fp = fopen(s, "rb");
    cr_assert(bytes && fp && fread(bytes, 1, (size_t)st.st_size, fp) == (size_t)st.st_size);
    fclose(fp);
    fp = fopen(before, "wb");
    cr_assert(fp && fwrite(bytes, 1, (size_t)st.st_size, fp) == (size_t)st.st_size);
    fclose(fp);
    free(bytes);
    for (i = 0; i < 2; i++) { /* twice, with one and with two workers */
        cr_assert_eq(capdyn(dir, &out, &err, "sweep", sc, SHORT, "--vary", "target.object.mass=0.3,0.4,0.5", "-j",
                            i ? "2" : "1", "--resume", "-o", s, NULL),
                     0, "%s", err);
        cr_assert(strstr(out, "3 of 3 variants run (0 failed), 0 in"), "%s", out);
        free(out);
        free(err);
    }
    f = open_ro(s);
    cr_assert(f >= 0);
    cr_assert_eq(attr_ll(f, "complete"), 1);
    cr_assert_eq(attr_ll(f, "n_run"), 3);
    for (i = 0; i < 3; i++) cr_assert_eq(ds_ll(f, "status", i), 0, "variant %ld", i);
    H5Fclose(f);
    same_summary(before, s);
    same_summary(s, before);
    rm_rf(dir);
}

Test(sweep, a_killed_sweep_leaves_a_readable_summary_and_resumes_to_the_same, .timeout = 240)
{
    /* SIGKILL (no chance to write) half a second into an 8-variant sweep:
     * the summary on disk is the last complete one (written before the
     * first variant, then at each 10 s checkpoint): --table reads it, every
     * row not yet written is "not run", and --resume, started while the
     * orphaned worker may still be finishing its variant (it must not hold
     * the summary's lock), completes it to the uninterrupted summary. */
    char dir[256], sc[512], full[512], part[512], *out = NULL, *err = NULL;
    char *argv[32];
    int n = 0, st;
    pid_t pid;
    const char *vary = "target.object.position[1]=0.07:0.09:8";
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "tako_centred.toml");
    snprintf(full, sizeof full, "%s/full.h5", dir);
    snprintf(part, sizeof part, "%s/part.h5", dir);
    cr_assert_eq(capdyn(dir, NULL, &err, "sweep", sc, SHORT, "--vary", vary, "-j", "2", "-q", "-o", full, NULL), 0,
                 "%s", err);
    free(err);
    n = sweep_argv(argv, n, bin(), sc);
    argv[n++] = "--vary";
    argv[n++] = (char *)vary;
    argv[n++] = "-j";
    argv[n++] = "1";
    argv[n++] = "-q";
    argv[n++] = "-o";
    argv[n++] = part;
    argv[n] = NULL;
    pid = spawn(dir, argv, NULL);
    sleep_s(0.5);
    kill(pid, SIGKILL);
    st = wait_status(pid);
    if (st != 128 + SIGKILL) cr_log_info("the sweep ended (%d) before SIGKILL: a very fast machine", st);
    cr_assert_eq(capdyn(dir, &out, &err, "sweep", "--table", part, NULL), 0, "the summary is readable: %s", err);
    cr_assert(strstr(out, ": 8 variants"), "%s", out);
    free(out);
    free(err);
    cr_assert_eq(capdyn(dir, &out, &err, "sweep", sc, SHORT, "--vary", vary, "-j", "2", "--resume", "-o", part, NULL),
                 0, "%s", err);
    cr_assert(strstr(out, "8 of 8 variants run"), "%s", out);
    free(out);
    free(err);
    same_summary(full, part);
    same_summary(part, full);
    rm_rf(dir);
}

/* the pid of the process whose environment has OMPI_COMM_WORLD_RANK=rank
 * and whose parent is ppid, or -1 */
static pid_t mpi_rank_pid(pid_t ppid, int rank)
{
    DIR *d = opendir("/proc");
    struct dirent *e;
    pid_t found = -1;
    char want[64];
    snprintf(want, sizeof want, "OMPI_COMM_WORLD_RANK=%d", rank);
    if (!d) return -1;
    while (found < 0 && (e = readdir(d)) != NULL) {
        char p[300], buf[65536];
        long pid = atol(e->d_name), pp = -1;
        FILE *f;
        size_t n, i;
        if (pid <= 0) continue;
        snprintf(p, sizeof p, "/proc/%ld/stat", pid);
        if (!(f = fopen(p, "r"))) continue;
        if (fscanf(f, "%*d (%*[^)]) %*c %ld", &pp) != 1) pp = -1;
        fclose(f);
        if (pp != (long)ppid) continue;
        snprintf(p, sizeof p, "/proc/%ld/environ", pid);
        if (!(f = fopen(p, "r"))) continue;
        n = fread(buf, 1, sizeof buf - 1, f);
        fclose(f);
        buf[n] = 0;
        for (i = 0; i < n; i += strlen(buf + i) + 1)
            if (!strcmp(buf + i, want)) found = (pid_t)pid;
    }
    closedir(d);
    return found;
}

Test(sweep, mpirun_with_a_rank_killed_then_resumed_gives_the_serial_summary, .timeout = 300)
{
    /* issue 24: three ranks; a worker rank (rank 1) is SIGKILLed a second
     * in. Open MPI then ends the job (rank 0 gets SIGTERM: it writes the
     * summary of what finished, or the last checkpoint stays), and a
     * serial --resume completes it to the summary of an uninterrupted
     * serial sweep. */
    const char *mb = getenv("CAPDYN_MPI_BIN");
    char dir[256], sc[512], s1[512], sm[512], *err = NULL, *out = NULL;
    char e1[] = "OMPI_ALLOW_RUN_AS_ROOT=1", e2[] = "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1", e3[] = "OMPI_MCA_btl=self,vader";
    char *argv[40], *env[4];
    int n = 0, st;
    pid_t pid, victim = -1;
    double t0;
    env[0] = e1;
    env[1] = e2;
    env[2] = e3;
    env[3] = NULL;
    if (!mb || !*mb) cr_skip_test("capdyn is not built with MPI here ('make MPI=1 test' runs this test)");
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "tako_centred.toml");
    snprintf(s1, sizeof s1, "%s/serial.h5", dir);
    snprintf(sm, sizeof sm, "%s/mpi.h5", dir);
    cr_assert_eq(capdyn(dir, NULL, &err, "sweep", sc, SHORT, GRID5, "-j", "2", "-q", "-o", s1, NULL), 0, "%s", err);
    free(err);
    argv[n++] = "/usr/bin/env";
    argv[n++] = "mpirun";
    argv[n++] = "-n";
    argv[n++] = "3";
    argv[n++] = "--oversubscribe";
    n = sweep_argv(argv, n, mb, sc);
    argv[n++] = "--vary";
    argv[n++] = "target.object.position[0]=-0.004:0.004:5";
    argv[n++] = "--vary";
    argv[n++] = "target.object.position[1]=0.07:0.09:5";
    argv[n++] = "-q";
    argv[n++] = "-o";
    argv[n++] = sm;
    argv[n] = NULL;
    pid = spawn(dir, argv, env);
    /* /usr/bin/env execs mpirun: its ranks are pid's children */
    for (t0 = now(); now() - t0 < 60 && victim < 0;) {
        struct stat st_;
        if (stat(sm, &st_) == 0) victim = mpi_rank_pid(pid, 1);
        if (victim < 0) sleep_s(0.05);
    }
    cr_assert_gt(victim, 0, "rank 1 found once the first summary is written");
    sleep_s(1.0);
    kill(victim, SIGKILL);
    st = wait_status(pid);
    if (st == 0) cr_log_info("mpirun ended before the kill took effect: resume is a no-op");
    else {
        hid_t f = open_ro(sm);
        cr_assert(f >= 0, "the summary after the kill is readable");
        cr_log_info("mpirun exit %d; %lld of 25 variants in the summary", st, attr_ll(f, "n_run"));
        cr_assert_lt(attr_ll(f, "n_run"), 25);
        H5Fclose(f);
    }
    cr_assert_eq(capdyn(dir, &out, &err, "sweep", sc, SHORT, GRID5, "-j", "2", "--resume", "-o", sm, NULL), 0, "%s",
                 err);
    cr_assert(strstr(out, "25 of 25 variants run"), "%s", out);
    free(out);
    free(err);
    same_summary(s1, sm);
    same_summary(sm, s1);
    rm_rf(dir);
}
