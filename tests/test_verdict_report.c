/* The names of the reported figures (issue 22, item 2): `capdyn run` prints
 * the peak normal force at the samples, over every step with onset
 * transients excluded, and the onset transient apart; `capdyn info` prints
 * the same lines from the file (the peaks over steps are stored at close),
 * and says "not stored in this file" for a file without them. Checked
 * against the closed form of a critically damped ball against a wall
 * (docs/cli.md, "Peak forces"). */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "proc_util.h"
#include "h5_test_util.h"

/* A ball of 1 kg at v0 = 1 m/s toward a fixed wall 5.5 mm away; linear law
 * K = 1e4 N/m, D = 200 N s/m: omega = sqrt(K/m) = 100 rad/s, critical
 * damping (zeta = D / (2 sqrt(m K)) = 1). In contact (s = t - 5.5 ms):
 *   x = v0 s e^(-w s),  xdot = v0 e^(-w s) (1 - w s),
 *   f = K x + D xdot = m v0 w e^(-w s) (2 - w s)
 * (-m xddot). At touch f jumps to D v0 = 200 N and then falls. The damper
 * term D xdot exceeds the elastic term K x until w s = 2/3: the onset
 * window; the physical peak after it is f(2/3 / w) = m v0 w (4/3) e^(-2/3)
 * = 68.4566 N; the samples (every 1 ms, s = 0.5, 1.5, .. ms) see at most
 * f(0.5 ms) = 100 e^(-0.05) 1.95 = 185.49 N. */
static const char *ball_toml =
    "title = \"test: critically damped ball against a wall\"\n"
    "[simulation]\n"
    "duration = 0.03\n"
    "gravity = [0.0, 0.0, 0.0]\n"
    "integrator = \"rk8pd\"\n"
    "rtol = 1e-10\n"
    "atol = 1e-12\n"
    "h_max = 1e-5\n"
    "output_dt = 1e-3\n"
    "[contact]\n"
    "K = 1e4\n"
    "D = 200.0\n"
    "mu_max = 0.5\n"
    "mu = 0.5\n"
    "[[system]]\n"
    "name = \"ball\"\n"
    "base = \"free\"\n"
    "mass = 1.0\n"
    "inertia = [0.004, 0.004, 0.004]\n"
    "position = [-0.1055, 0.0, 0.0]\n"
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

/* ball_toml written to DIR/ball.toml, its results path DIR/ball.h5 */
static void ball_files(const char *dir, char *toml, size_t ntoml, char *h5, size_t nh5)
{
    FILE *f;
    snprintf(toml, ntoml, "%s/ball.toml", dir);
    snprintf(h5, nh5, "%s/ball.h5", dir);
    f = fopen(toml, "w");
    cr_assert_not_null(f);
    fputs(ball_toml, f);
    fclose(f);
}

static double force(double s) { return s < 0 ? 0.0 : 100.0 * exp(-100.0 * s) * (2.0 - 100.0 * s); }

/* the number after "KEY  " at the start of a line of text (NaN if absent) */
static double after_key(const char *text, const char *key)
{
    const char *p = text;
    size_t n = strlen(key);
    while (p && *p) {
        if (!strncmp(p, key, n) && (p[n] == ' ')) return strtod(p + n, NULL);
        p = strchr(p, '\n');
        if (p) p++;
    }
    return NAN;
}

/* the time in " at t = T s" of the line that starts with key (NaN if absent) */
static double time_in(const char *text, const char *key)
{
    const char *p = text;
    size_t n = strlen(key);
    while (p && *p) {
        const char *e = strchr(p, '\n'), *a = strstr(p, " at t = ");
        if (!strncmp(p, key, n) && a && (!e || a < e)) return strtod(a + 8, NULL);
        p = e ? e + 1 : NULL;
    }
    return NAN;
}

Test(verdict_report, run_and_info_name_the_peak_at_samples_over_steps_and_the_onset_transient, .timeout = 60)
{
    char dir[64], toml[256], h5[256], *out = NULL, *err = NULL, *iout = NULL;
    double smp = 0, body, onset, s_run, s_info, ws = 2.0 / 3.0;
    int k;
    make_tmpdir(dir, sizeof dir);
    ball_files(dir, toml, sizeof toml, h5, sizeof h5);
    cr_assert_eq(capdyn(dir, &out, &err, "run", toml, "-o", h5, (char *)NULL), 0, "%s", err);
    for (k = 0; k <= 30; k++) {
        double fk = force(k * 1e-3 - 5.5e-3);
        if (fk > smp) smp = fk;
    }
    cr_assert_float_eq(smp, 100.0 * exp(-0.05) * 1.95, 1e-12);
    s_run = after_key(out, "peak fn at samples");
    body = after_key(out, "peak fn over steps");
    onset = after_key(out, "onset transient");
    cr_log_info("samples %g (closed form %g), over steps %g (%g), onset %g (%g)", s_run, smp, body, force(ws / 100.0),
                onset, 200.0);
    /* the samples: the closed form at s = 0.5 ms; printed with 6 significant
     * digits: 5e-6 relative, the integration (rk8pd, rtol 1e-10) adds less */
    cr_expect(fabs(s_run - smp) < 5e-6 * smp, "peak fn at samples %.9g, closed form %.9g\n%s", s_run, smp, out);
    /* over steps, onset excluded: f at the window's end w s = 2/3, reached by
     * the first step past it (h <= 1e-5 s: f falls by at most
     * |f'| h = 100^2 e^(-2/3) (3 - 2/3) 1e-5 = 0.12 N, 0.2 %) */
    cr_expect(body <= force(ws / 100.0) * (1 + 1e-9) && body > force(ws / 100.0) * 0.998,
              "peak fn over steps %.9g, closed form %.9g\n%s", body, force(ws / 100.0), out);
    /* the onset transient: D v0 = 200 N at touch, the first step inside the
     * window (events land within 1e-10 s past the touch) */
    cr_expect(onset <= 200.0 * (1 + 1e-9) && onset > 200.0 * 0.999, "onset transient %.9g, expected D v0 = 200 N\n%s",
              onset, out);
    cr_expect_not_null(strstr(out, "onset transients excluded"), "%s", out);
    /* when: the touch at t = 5.5 ms (gap 5.5 mm at 1 m/s) for the transient,
     * the window's end w s = 2/3 for the body, each reached by the first
     * step at or past it (h <= 1e-5 s) */
    {
        double tb = time_in(out, "peak fn over steps"), to = time_in(out, "onset transient");
        double tb0 = 5.5e-3 + ws / 100.0, to0 = 5.5e-3;
        cr_expect(tb >= tb0 - 1e-9 && tb <= tb0 + 1e-5 + 1e-9, "peak fn over steps at t = %.9g s, closed form %.9g s",
                  tb, tb0);
        cr_expect(to >= to0 - 1e-9 && to <= to0 + 1e-5 + 1e-9, "onset transient at t = %.9g s, the touch at %.9g s", to,
                  to0);
    }
    /* info reads the file: the samples, and the peaks over steps the run
     * stored at its end, under the same names and values */
    cr_assert_eq(capdyn(dir, &iout, &err, "info", h5, (char *)NULL), 0, "%s", err);
    s_info = after_key(iout, "peak fn at samples");
    cr_expect_eq(s_info, s_run, "info %.9g, run %.9g", s_info, s_run);
    cr_expect_eq(after_key(iout, "peak fn over steps"), body, "info %.9g, run %.9g\n%s",
                 after_key(iout, "peak fn over steps"), body, iout);
    cr_expect_eq(after_key(iout, "onset transient"), onset, "info %.9g, run %.9g\n%s", after_key(iout, "onset transient"),
                 onset, iout);
    cr_expect_eq(time_in(iout, "peak fn over steps"), time_in(out, "peak fn over steps"), "%s", iout);
    cr_expect_eq(time_in(iout, "onset transient"), time_in(out, "onset transient"), "%s", iout);
    cr_expect_null(strstr(iout, "max force"), "the old ambiguous header is gone:\n%s", iout);
    free(out);
    free(err);
    free(iout);
    rm_rf(dir);
}

/* The caged verdict in the texts: `capdyn run` and `capdyn info` of the
 * frictionless Space Gripper wrap (test_verdict.c: caged at 0.672 s, no force
 * closure), the sweep line counting it apart from captured, and the table's
 * verdict code 3. */
Test(verdict_report, run_info_and_sweep_name_the_cage, .timeout = 120)
{
    char dir[64], sc[512], h5[256], sw[256], *out = NULL, *err = NULL, *iout = NULL, *sout = NULL, *tab = NULL;
    const char *line = "capture     caged at t = 0.672 s\n";
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "space_gripper_cylinder.toml");
    snprintf(h5, sizeof h5, "%s/cage.h5", dir);
    snprintf(sw, sizeof sw, "%s/cage_sweep.h5", dir);
    cr_assert_eq(capdyn(dir, &out, &err, "run", sc, "--set", "contact.mu=0.0", "--set", "contact.mu_max=0.0", "--set",
                        "simulation.duration=1.0", "-o", h5, (char *)NULL),
                 0, "%s", err);
    cr_expect_not_null(strstr(out, line), "%s", out);
    cr_expect_not_null(strstr(out, "grasp quality epsilon 0 (no force closure)"), "%s", out);
    cr_assert_eq(capdyn(dir, &iout, &err, "info", h5, (char *)NULL), 0, "%s", err);
    cr_expect_not_null(strstr(iout, line), "%s", iout);
    cr_assert_eq(capdyn(dir, &sout, &err, "sweep", sc, "--set", "contact.mu=0.0", "--set", "simulation.duration=1.0",
                        "--vary", "contact.mu_max=0.0,0.0", "-j", "1", "-o", sw, (char *)NULL),
                 0, "%s", err);
    cr_expect_not_null(strstr(sout, "captured 0, caged 2, escaped 0, unresolved 0"), "%s", sout);
    cr_assert_eq(capdyn(dir, &tab, &err, "sweep", "--table", sw, (char *)NULL), 0, "%s", err);
    cr_expect_not_null(strstr(tab, "# verdict: 0 unresolved, 1 captured, 2 escaped, 3 caged, -1 none"), "%s", tab);
    cr_expect_not_null(strstr(tab, "\n0 0.0 0 3 0 "), "variant 0: verdict 3, status 0:\n%s", tab);
    free(out);
    free(err);
    free(iout);
    free(sout);
    free(tab);
    rm_rf(dir);
}

/* ---- the peaks over steps in the results file (issue 22, item 2) ---------- */

/* text without its "wall time" line (the one line of a run's summary that
 * differs from info's: the run's own wall time, info's at the last sample) */
static char *without_wall(const char *text)
{
    char *o = malloc(strlen(text) + 1), *q = o;
    const char *p = text;
    cr_assert_not_null(o);
    while (*p) {
        const char *e = strchr(p, '\n');
        size_t n = e ? (size_t)(e - p) + 1 : strlen(p);
        if (strncmp(p, "wall time ", 10) != 0) {
            memcpy(q, p, n);
            q += n;
        }
        p += n;
    }
    *q = 0;
    return o;
}

/* the line of text that starts with key (malloc'ed; NULL if none) */
static char *line_of(const char *text, const char *key)
{
    const char *p = text;
    size_t n = strlen(key);
    while (p && *p) {
        const char *e = strchr(p, '\n');
        if (!strncmp(p, key, n)) {
            size_t len = e ? (size_t)(e - p) : strlen(p);
            char *l = malloc(len + 1);
            memcpy(l, p, len);
            l[len] = 0;
            return l;
        }
        p = e ? e + 1 : NULL;
    }
    return NULL;
}

static void read_vec(hid_t f, const char *path, double *v, int n)
{
    hid_t d = H5Dopen2(f, path, H5P_DEFAULT), sp;
    hsize_t dim = 0;
    cr_assert(d >= 0, "dataset %s", path);
    sp = H5Dget_space(d);
    cr_assert_eq(H5Sget_simple_extent_dims(sp, &dim, NULL), 1, "%s is one-dimensional", path);
    cr_assert_eq((int)dim, n, "%s has %d elements, nslot %d", path, (int)dim, n);
    cr_assert(H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) >= 0);
    H5Sclose(sp);
    H5Dclose(d);
}

/* The frictionless Space Gripper wrap of tests/test_verdict.c (caged at
 * 0.672 s, 1 s): 100 slots; onset transients on the hand x cylinder pairs'
 * linear law, and the finger pairs' (Hunt-Crossley) impact forces. capdyn info
 * of its file prints every line of the run's summary, the contact table
 * with its over-steps columns and the peak lines included, except the wall
 * time; in the file each slot's fn_step_max is the larger of its body and
 * onset peaks (every step's force is in exactly one of the two). */
Test(verdict_report, info_prints_the_run_summary_line_for_line_with_the_peaks_over_steps, .timeout = 120)
{
    char dir[64], h5[256], sc[512], *out = NULL, *err = NULL, *iout = NULL, *a, *b;
    double *v;
    int nslot, k, nonset = 0;
    hid_t f;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "space_gripper_cylinder.toml");
    snprintf(h5, sizeof h5, "%s/cage.h5", dir);
    cr_assert_eq(capdyn(dir, &out, &err, "run", sc, "--set", "simulation.duration=1.0", "--set", "contact.mu=0.0",
                        "--set", "contact.mu_max=0.0", "-o", h5, (char *)NULL),
                 0, "%s", err);
    free(err);
    cr_assert_eq(capdyn(dir, &iout, &err, "info", h5, (char *)NULL), 0, "%s", err);
    a = without_wall(out);
    b = without_wall(iout);
    cr_expect_str_eq(b, a, "info and run differ:\n--- run\n%s\n--- info\n%s", a, b);
    cr_expect_not_null(strstr(b, "fn step [N]"), "the table's over-steps columns:\n%s", b);
    cr_expect_not_null(strstr(b, "\npeak fn over steps  "), "%s", b);
    cr_expect_not_null(strstr(b, "\nonset transient  "), "%s", b);
    cr_expect_not_null(strstr(b, "\npeak |ft| over steps  "), "%s", b);
    free(a);
    free(b);
    f = open_ro(h5);
    cr_assert(f >= 0);
    {
        hid_t gc = H5Gopen2(f, "contacts", H5P_DEFAULT);
        cr_assert(gc >= 0);
        nslot = (int)attr_ll(gc, "nslot");
        H5Gclose(gc);
    }
    cr_assert_gt(nslot, 0);
    v = malloc(sizeof(double) * 6 * (size_t)nslot);
    read_vec(f, "/contacts/fn_step_max", v, nslot);
    read_vec(f, "/contacts/fn_step_body", v + nslot, nslot);
    read_vec(f, "/contacts/fn_step_onset", v + 2 * nslot, nslot);
    read_vec(f, "/contacts/ft_step_max", v + 3 * nslot, nslot);
    read_vec(f, "/contacts/t_fn_step_body", v + 4 * nslot, nslot);
    read_vec(f, "/contacts/t_fn_step_onset", v + 5 * nslot, nslot);
    for (k = 0; k < nslot; k++) {
        double mx = v[k], bo = v[nslot + k], on = v[2 * nslot + k];
        cr_expect(mx == fmax(bo, on), "slot %d: fn_step_max %.17g, body %.17g, onset %.17g", k, mx, bo, on);
        cr_expect(v[3 * nslot + k] == 0.0, "slot %d: frictionless, |ft| over steps %g", k, v[3 * nslot + k]);
        nonset += on > 0;
        /* a time for each peak reached, inside the run; NaN for none */
        cr_expect(bo > 0 ? v[4 * nslot + k] > 0 && v[4 * nslot + k] <= 1.0 : isnan(v[4 * nslot + k]),
                  "slot %d: body %g at t = %g", k, bo, v[4 * nslot + k]);
        cr_expect(on > 0 ? v[5 * nslot + k] > 0 && v[5 * nslot + k] <= 1.0 : isnan(v[5 * nslot + k]),
                  "slot %d: onset %g at t = %g", k, on, v[5 * nslot + k]);
    }
    cr_expect_gt(nonset, 0, "no slot with an onset transient");
    H5Fclose(f);
    free(v);
    free(out);
    free(err);
    free(iout);
    rm_rf(dir);
}

/* A file without the peaks over steps, as written before they were stored
 * (the datasets deleted), and one whose run never closed it (NaN, as a
 * killed run leaves them): info opens both (exit 0), prints the peaks at
 * samples, and says why the peaks over steps are not there, in one line. */
Test(verdict_report, info_of_a_file_without_the_peaks_over_steps_says_they_are_not_stored, .timeout = 60)
{
    static const char *const names[6] = {"fn_step_max",  "fn_step_body",   "fn_step_onset",
                                         "ft_step_max",  "t_fn_step_body", "t_fn_step_onset"};
    char dir[64], toml[256], h5[256], *out = NULL, *err = NULL, *iout = NULL, *l;
    double nans[64];
    int k;
    hid_t f, g, d;
    make_tmpdir(dir, sizeof dir);
    ball_files(dir, toml, sizeof toml, h5, sizeof h5);
    cr_assert_eq(capdyn(dir, &out, &err, "run", toml, "-o", h5, "-q", (char *)NULL), 0, "%s", err);
    free(err);
    free(out);
    /* the run never closed it: NaN in one of them */
    for (k = 0; k < 64; k++) nans[k] = NAN;
    f = H5Fopen(h5, H5F_ACC_RDWR, H5P_DEFAULT);
    cr_assert(f >= 0);
    d = H5Dopen2(f, "/contacts/fn_step_body", H5P_DEFAULT);
    cr_assert(d >= 0);
    cr_assert(H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, nans) >= 0); /* nslot 1 */
    H5Dclose(d);
    H5Fclose(f);
    cr_assert_eq(capdyn(dir, &iout, &err, "info", h5, (char *)NULL), 0, "%s", err);
    free(err);
    l = line_of(iout, "peak fn over steps");
    cr_assert_not_null(l, "%s", iout);
    cr_expect_str_eq(l, "peak fn over steps  not stored in this file (its run did not close it: the peaks over steps "
                        "are written at the end of the run)");
    cr_expect_null(strstr(iout, "\nonset transient  "), "%s", iout);
    cr_expect_null(strstr(iout, "fn step [N]"), "%s", iout);
    cr_expect(after_key(iout, "peak fn at samples") > 0, "%s", iout);
    free(l);
    free(iout);
    /* an older file: no such datasets */
    f = H5Fopen(h5, H5F_ACC_RDWR, H5P_DEFAULT);
    cr_assert(f >= 0);
    g = H5Gopen2(f, "contacts", H5P_DEFAULT);
    for (k = 0; k < 6; k++) cr_assert(H5Ldelete(g, names[k], H5P_DEFAULT) >= 0, "delete %s", names[k]);
    H5Gclose(g);
    H5Fclose(f);
    cr_assert_eq(capdyn(dir, &iout, &err, "info", h5, (char *)NULL), 0, "%s", err);
    l = line_of(iout, "peak fn over steps");
    cr_assert_not_null(l, "%s", iout);
    cr_expect_str_eq(l, "peak fn over steps  not stored in this file (written by a capdyn from before the peaks over "
                        "steps were kept in results files; capdyn run prints them at its end)");
    cr_expect_null(strstr(iout, "\nonset transient  "), "%s", iout);
    cr_expect(after_key(iout, "peak fn at samples") > 0, "%s", iout);
    free(l);
    free(iout);
    free(err);
    rm_rf(dir);
}
