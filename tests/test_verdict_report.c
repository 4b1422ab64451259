/* The names of the reported figures (issue 22, item 2): `capdyn run` prints
 * the peak normal force at the samples, over every step with onset
 * transients excluded, and the onset transient apart; `capdyn info` prints
 * the one at the samples only. Checked against the closed form of a
 * critically damped ball against a wall (docs/cli.md, "Peak forces"). */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "proc_util.h"

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

Test(verdict_report, run_and_info_name_the_peak_at_samples_over_steps_and_the_onset_transient, .timeout = 60)
{
    char dir[64], toml[256], h5[256], *out = NULL, *err = NULL, *iout = NULL;
    double smp = 0, body, onset, s_run, s_info, ws = 2.0 / 3.0;
    int k;
    FILE *f;
    make_tmpdir(dir, sizeof dir);
    snprintf(toml, sizeof toml, "%s/ball.toml", dir);
    snprintf(h5, sizeof h5, "%s/ball.h5", dir);
    f = fopen(toml, "w");
    cr_assert_not_null(f);
    fputs(ball_toml, f);
    fclose(f);
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
    /* info reads the file: the samples only, under the same name and value */
    cr_assert_eq(capdyn(dir, &iout, &err, "info", h5, (char *)NULL), 0, "%s", err);
    s_info = after_key(iout, "peak fn at samples");
    cr_expect_eq(s_info, s_run, "info %.9g, run %.9g", s_info, s_run);
    cr_expect_null(strstr(iout, "peak fn over steps"), "info has no steps to speak of:\n%s", iout);
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
