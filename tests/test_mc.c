/* capdyn sweep --mc (issue 26, docs/sweep.md "Monte Carlo"): the sampled
 * moments of each dispersion against their exact values (5 sigma of the
 * estimator), physical inertia draws, draws that depend on (seed, variant)
 * only, shards merged equal to one run, resume of a half-done campaign, and
 * a Bernoulli case whose probability is known. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <hdf5.h>
#include "proc_util.h"
#include "h5_test_util.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NDRAW 20000
#define PI 3.14159265358979323846

/* the --plan table: rows x cols numbers (a TOML array's numbers expanded) */
typedef struct {
    double v[NDRAW][16];
    int ncol;
} table;

static void parse_plan(const char *out, table *t, long nrow)
{
    const char *p = strchr(out, '\n');
    long r = 0;
    cr_assert_not_null(p);
    p++;
    while (*p && r < nrow) {
        char *e;
        int c = 0;
        strtol(p, &e, 10); /* the variant */
        p = e;
        while (*p && *p != '\n') {
            if (*p == '\t' || *p == '[' || *p == ',' || *p == ' ' || *p == ']') {
                p++;
                continue;
            }
            cr_assert_lt(c, 16);
            t->v[r][c++] = strtod(p, &e);
            cr_assert(e != p, "a number in row %ld", r);
            p = e;
        }
        t->ncol = c;
        if (*p) p++;
        r++;
    }
    cr_assert_eq(r, nrow, "%ld plan rows, not %ld", r, nrow);
}

static void mean_var(const table *t, int c, double *m, double *v)
{
    long i;
    double s = 0, s2 = 0;
    for (i = 0; i < NDRAW; i++) s += t->v[i][c];
    *m = s / NDRAW;
    for (i = 0; i < NDRAW; i++) s2 += (t->v[i][c] - *m) * (t->v[i][c] - *m);
    *v = s2 / (NDRAW - 1);
}

/* the sample mean within 5 sigma of the mean's estimator (sd / sqrt(N)), the
 * sample variance within 5 sigma of the variance's estimator
 * (sqrt((mu4 - sigma^4) / N)) */
static void check(const char *what, double m, double v, double mean, double var, double mu4)
{
    double sm = 5 * sqrt(var / NDRAW), sv = 5 * sqrt((mu4 - var * var) / NDRAW);
    cr_log_info("%s: mean %.6g (exact %.6g, bound %.3g), variance %.6g (exact %.6g, bound %.3g)", what, m, mean, sm, v,
                var, sv);
    cr_assert_leq(fabs(m - mean), sm, "%s: mean %.6g, exact %.6g", what, m, mean);
    cr_assert_leq(fabs(v - var), sv, "%s: variance %.6g, exact %.6g", what, v, var);
}

static double phi(double x) { return exp(-0.5 * x * x) / sqrt(2 * PI); }
static double Phi(double x) { return 0.5 * erfc(-x / sqrt(2)); }

static table T;

Test(mc, each_dispersion_has_its_mean_and_variance_within_5_sigma, .timeout = 120)
{
    char dir[256], sc[512], n[32], *out = NULL, *err = NULL;
    double m, v;
    long i;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "tako_centred.toml");
    snprintf(n, sizeof n, "%d", NDRAW);
    cr_assert_eq(capdyn(dir, &out, &err, "sweep", sc, "--mc", n, "--seed", "11", "--plan", "--disperse",
                        "a=normal(1,0.5)", "--disperse", "b=normal(0,1,-1,2)", "--disperse", "c=uniform(2,5)",
                        "--disperse", "d=cone(0,0,2,30)", "--disperse", "e=rotation(1,0,0,0,90)", "--disperse",
                        "f=inertia(1,2,2.5,0.4)", NULL),
                 0, "%s", err);
    parse_plan(out, &T, NDRAW);
    cr_assert_eq(T.ncol, 1 + 1 + 1 + 3 + 4 + 3);
    /* normal(1, 0.5): mu4 = 3 sigma^4 */
    mean_var(&T, 0, &m, &v);
    check("normal(1,0.5)", m, v, 1, 0.25, 3 * 0.0625);
    /* normal(0,1) truncated to [-1, 2]: the truncated normal's moments */
    {
        double a = -1, b = 2, Z = Phi(b) - Phi(a), mu = (phi(a) - phi(b)) / Z;
        double var = 1 + (a * phi(a) - b * phi(b)) / Z - mu * mu;
        for (i = 0; i < NDRAW; i++) cr_assert(T.v[i][1] >= -1 && T.v[i][1] <= 2, "draw %ld: %g", i, T.v[i][1]);
        mean_var(&T, 1, &m, &v);
        /* mu4 bounded by the untruncated one (3): a looser, safe bound */
        check("normal(0,1,-1,2)", m, v, mu, var, 3);
    }
    /* uniform(2, 5): variance w^2/12, mu4 = w^4/80 */
    mean_var(&T, 2, &m, &v);
    check("uniform(2,5)", m, v, 3.5, 9.0 / 12, 81.0 / 80);
    /* cone: length 2, angle to z <= 30 deg, cos(theta) uniform in [cos 30, 1] */
    {
        table *c = &T;
        double ca = cos(30 * PI / 180), w = 1 - ca;
        static double ct[NDRAW];
        for (i = 0; i < NDRAW; i++) {
            double *x = c->v[i] + 3, r = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
            cr_assert_float_eq(r, 2, 1e-12, "cone draw %ld has length %.17g", i, r);
            ct[i] = x[2] / r;
            cr_assert_geq(ct[i], ca - 1e-12, "cone draw %ld is %.6g deg off the axis", i, acos(ct[i]) * 180 / PI);
        }
        for (i = 0; i < NDRAW; i++) c->v[i][0] = ct[i];
        mean_var(c, 0, &m, &v);
        check("cone: cos(theta)", m, v, 1 - w / 2, w * w / 12, w * w * w * w / 80);
        /* the azimuth: mean of x ~ 0 (variance of x: E[sin^2] / 2 * 4) */
        for (i = 0; i < NDRAW; i++) c->v[i][0] = c->v[i][3];
        mean_var(c, 0, &m, &v);
        cr_assert_leq(fabs(m), 5 * sqrt(v / NDRAW), "cone: mean x %.4g", m);
    }
    /* rotation: unit quaternions, angle 2 acos|w| uniform in [0, 90] deg */
    for (i = 0; i < NDRAW; i++) {
        double *q = T.v[i] + 6, nq = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        cr_assert_float_eq(nq, 1, 1e-12, "rotation draw %ld: |q| = %.17g", i, nq);
        T.v[i][0] = 2 * acos(fmin(1, fabs(q[0]))) * 180 / PI;
    }
    mean_var(&T, 0, &m, &v);
    check("rotation: angle [deg]", m, v, 45, 8100.0 / 12, 8100.0 * 8100.0 / 80);
    /* inertia, REL_SD 0.4 (many draws rejected): every draw physical */
    for (i = 0; i < NDRAW; i++) {
        double *I = T.v[i] + 10;
        cr_assert(I[0] > 0 && I[1] > 0 && I[2] > 0, "inertia draw %ld not positive", i);
        cr_assert(I[0] + I[1] >= I[2] && I[1] + I[2] >= I[0] && I[0] + I[2] >= I[1],
                  "inertia draw %ld [%g, %g, %g] breaks a triangle inequality", i, I[0], I[1], I[2]);
    }
    free(out);
    free(err);
    /* a variant's draws depend on (seed, its index) only: the first 3 of
     * --mc 3 are the first 3 of --mc NDRAW */
    {
        char *o2 = NULL, *l1, *l2;
        cr_assert_eq(capdyn(dir, &o2, NULL, "sweep", sc, "--mc", "3", "--seed", "11", "--plan", "--disperse",
                            "a=normal(1,0.5)", NULL),
                     0);
        cr_assert_eq(capdyn(dir, &out, NULL, "sweep", sc, "--mc", n, "--seed", "11", "--plan", "--disperse",
                            "a=normal(1,0.5)", NULL),
                     0);
        l1 = strstr(out, "\n2\t");
        l2 = strstr(o2, "\n2\t");
        cr_assert(l1 && l2);
        cr_assert_eq(strncmp(out, o2, (size_t)(strchr(l2 + 1, '\n') - o2)), 0, "%s", o2);
        free(o2);
        free(out);
    }
    rm_rf(dir);
}

Test(mc, bad_dispersions_are_refused_with_the_reason)
{
    char dir[256], sc[512], *err = NULL;
    static const char *cases[][2] = {
        {"k=gauss(0,1)", "--disperse k=gauss(0,1): unknown distribution 'gauss'"},
        {"k=normal(0,-1)", "--disperse k=normal(0,-1): the standard deviation SD must be >= 0"},
        {"k=uniform(2,1)", "--disperse k=uniform(2,1): LO must not exceed HI"},
        {"k=normal(0,1,2,3)", "the bounds must hold the mean"},
        {"k=inertia(1,1,3,0.1)", "obey A+B>=C"},
        {"k=uniform(1,nan)", "'nan' is not a finite number"},
    };
    size_t i;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "tako_centred.toml");
    for (i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        cr_assert_eq(capdyn(dir, NULL, &err, "sweep", sc, "--mc", "2", "--disperse", cases[i][0], NULL), 2, "%s",
                     cases[i][0]);
        cr_assert_not_null(strstr(err, cases[i][1]), "%s: %s", cases[i][0], err);
        free(err);
    }
    /* an unknown key: the loader's message on the first variant, exit 1 */
    cr_assert_eq(capdyn(dir, NULL, &err, "sweep", sc, "--mc", "2", "--disperse", "target.object.mas=uniform(1,2)",
                        "-o", "x.h5", NULL),
                 1);
    cr_assert_not_null(strstr(err, "'target[0].mas': unknown key (did you mean 'mass'?)"), "%s", err);
    free(err);
    cr_assert_eq(capdyn(dir, NULL, &err, "sweep", sc, "--mc", "2", NULL), 2);
    cr_assert_not_null(strstr(err, "--mc needs at least one --disperse"), "%s", err);
    free(err);
    rm_rf(dir);
}

static void checksum_of(const char *path, char *out, size_t n)
{
    hid_t f = open_ro(path), a, t;
    char *v = NULL;
    cr_assert(f >= 0, "open %s", path);
    a = H5Aopen(f, "checksum", H5P_DEFAULT);
    cr_assert(a >= 0, "%s: no checksum", path);
    t = H5Aget_type(a); /* a variable-length string */
    cr_assert(H5Aread(a, t, &v) >= 0 && v);
    snprintf(out, n, "%s", v);
    H5free_memory(v);
    H5Tclose(t);
    H5Aclose(a);
    H5Fclose(f);
}

#define MC_ARGS(sc)                                                                                                \
    "sweep", sc, "--set", "simulation.duration=0.08", "--set", "simulation.output_dt=0.01", "--vary",              \
        "target.object.position[0]=-0.002,0.002", "--mc", "3", "--disperse", "target.object.mass=uniform(0.2,0.4)",  \
        "--disperse", "target.object.inertia=inertia(1e-4,1e-4,1.5e-4,0.2)", "-j", "1", "-q"

/* The root checksum (FNV-1a over every attribute and dataset but /timing,
 * docs/sweep.md) of the shards merged equals the one-process run's, and so
 * do the per-cell probabilities. Shard 3/3 comes from the Slurm variables. */
Test(mc, shards_merged_equal_one_run_and_a_half_done_campaign_resumes_to_it, .timeout = 240)
{
    char dir[256], sc[512], one[512], s[3][512], m[512], half[512], c1[64], c2[64], *err = NULL;
    int k;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "tako_centred.toml");
    snprintf(one, sizeof one, "%s/one.h5", dir);
    cr_assert_eq(capdyn(dir, NULL, &err, MC_ARGS(sc), "-o", one, NULL), 0, "%s", err);
    free(err);
    for (k = 0; k < 3; k++) {
        char sh[16];
        snprintf(s[k], sizeof s[k], "%s/shard%d.h5", dir, k + 1);
        snprintf(sh, sizeof sh, "%d/3", k + 1);
        if (k < 2) {
            cr_assert_eq(capdyn(dir, NULL, &err, MC_ARGS(sc), "--shard", sh, "-o", s[k], NULL), 0, "%s", err);
            free(err);
        } else {
            char *argv[40] = {(char *)bin(), MC_ARGS(sc), "-o", s[k], NULL};
            char e1[] = "SLURM_ARRAY_TASK_ID=2", e2[] = "SLURM_ARRAY_TASK_COUNT=3"; /* spawn writes into them */
            char *env[] = {e1, e2, NULL};
            cr_assert_eq(wait_status(spawn(dir, argv, env)), 0);
        }
        {
            hid_t f = open_ro(s[k]);
            cr_assert_eq(attr_ll(f, "n_run"), 2, "shard %d ran %lld of 6", k + 1, attr_ll(f, "n_run"));
            cr_assert_eq(attr_ll(f, "complete"), 0);
            H5Fclose(f);
        }
    }
    snprintf(m, sizeof m, "%s/merged.h5", dir);
    cr_assert_eq(capdyn(dir, NULL, &err, "sweep", "--merge", s[2], s[0], s[1], "-o", m, NULL), 0, "%s", err);
    free(err);
    checksum_of(one, c1, sizeof c1);
    checksum_of(m, c2, sizeof c2);
    cr_assert_str_eq(c1, c2, "merged %s, one run %s", c2, c1);
    {
        hid_t f = open_ro(m);
        cr_assert_eq(attr_ll(f, "complete"), 1);
        H5Fclose(f);
    }
    /* a shard given twice is refused */
    cr_assert_eq(capdyn(dir, NULL, &err, "sweep", "--merge", s[0], s[0], "-o", m, NULL), 1);
    cr_assert_not_null(strstr(err, "is in two shards"), "%s", err);
    free(err);
    /* mid-campaign: shard 1/3 continued with --resume on one process */
    snprintf(half, sizeof half, "%s/half.h5", dir);
    cr_assert_eq(capdyn(dir, NULL, &err, MC_ARGS(sc), "--shard", "1/3", "-o", half, NULL), 0, "%s", err);
    free(err);
    cr_assert_eq(capdyn(dir, NULL, &err, MC_ARGS(sc), "--resume", "-o", half, NULL), 0, "%s", err);
    free(err);
    checksum_of(half, c2, sizeof c2);
    cr_assert_str_eq(c1, c2, "resumed %s, one run %s", c2, c1);
    rm_rf(dir);
}

/* A Bernoulli case with a known threshold: tako_centred captures its
 * cylinder at T_c (3.001 s since the bristle law, 3.337 s before; measured
 * here by one nominal run); a run whose duration d is dispersed
 * uniform(2.7, 3.4) ends captured iff d >= T_c (every other input is the
 * nominal run's), so P = (3.4 - T_c) / 0.7 (0.57: the interval holds T_c
 * well inside, so both outcomes are drawn). Each
 * variant's verdict is checked against its drawn d (d within one output
 * step of T_c excepted), and P must lie in the sweep's Wilson 95 % interval
 * of /mc (N = 40 draws, seed 1: deterministic). */
Test(mc, a_dispersed_duration_gives_the_analytic_capture_probability, .timeout = 900)
{
    char dir[256], sc[512], s[512], *out = NULL, *err = NULL, *p;
    double tc, P, lo, hi, pc, d[40 * 2];
    long long verdict[40];
    hid_t f;
    int i;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "tako_centred.toml");
    cr_assert_eq(capdyn(dir, &out, &err, "run", sc, "-o", "nominal.h5", NULL), 0, "%s", err);
    p = strstr(out, "captured at t = ");
    cr_assert_not_null(p, "%s", out);
    tc = strtod(p + strlen("captured at t = "), NULL);
    cr_assert(tc > 2.8 && tc < 3.3, "T_c = %g", tc);
    free(out);
    free(err);
    snprintf(s, sizeof s, "%s/bern.h5", dir);
    cr_assert_eq(capdyn(dir, NULL, &err, "sweep", sc, "--mc", "40", "--disperse", "simulation.duration=uniform(2.7,3.4)",
                        "-j", "2", "-q", "-o", s, NULL),
                 0, "%s", err);
    free(err);
    f = open_ro(s);
    {
        hid_t ds = H5Dopen2(f, "param_numeric", H5P_DEFAULT);
        cr_assert(H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, d) >= 0);
        H5Dclose(ds);
        ds = H5Dopen2(f, "verdict", H5P_DEFAULT);
        cr_assert(H5Dread(ds, H5T_NATIVE_LLONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, verdict) >= 0);
        H5Dclose(ds);
    }
    for (i = 0; i < 40; i++)
        if (fabs(d[i] - tc) > 1e-3)
            cr_assert_eq(verdict[i] == 1, d[i] >= tc, "variant %d: duration %.6f, T_c %.3f, verdict %lld", i, d[i], tc,
                         verdict[i]);
    {
        size_t n;
        double *v = read_all(f, "mc/p_capture", &n);
        pc = v[0];
        free(v);
        v = read_all(f, "mc/p_low", &n);
        lo = v[0];
        free(v);
        v = read_all(f, "mc/p_high", &n);
        hi = v[0];
        free(v);
    }
    H5Fclose(f);
    P = (3.4 - tc) / 0.7;
    cr_log_info("T_c %.3f s: analytic P %.4f; sampled %.4f, Wilson 95 %% [%.4f, %.4f]", tc, P, pc, lo, hi);
    cr_assert(lo <= P && P <= hi, "analytic %.4f outside [%.4f, %.4f]", P, lo, hi);
    /* the interval is Wilson's score interval of the count (z = 1.959964) */
    {
        int k = 0;
        double z = 1.959963984540054, n = 40, ph, c, h;
        for (i = 0; i < 40; i++) k += verdict[i] == 1;
        ph = k / n;
        cr_assert_float_eq(pc, ph, 1e-15);
        c = (ph + z * z / (2 * n)) / (1 + z * z / n);
        h = z * sqrt(ph * (1 - ph) / n + z * z / (4 * n * n)) / (1 + z * z / n);
        cr_assert_float_eq(lo, c - h, 1e-12);
        cr_assert_float_eq(hi, c + h, 1e-12);
    }
    rm_rf(dir);
}
