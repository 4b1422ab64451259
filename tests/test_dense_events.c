/* Dense output and the event log of a results file (src/sim/sampler.c).
 *
 * With simulation.sampling = "interpolate" (the default of auto and
 * ros34pw2) a sample inside a step is taken on the sampler's scratch data,
 * one at a step's end on the run's own. The results file must hold each
 * event once, in time order, as with samples that stop the steps: the
 * free-floating arm's schedule switches its three actuators' rows at
 * t = 1, 2, 3 and 4 s (12 events), on sample times. Before the fix the
 * scratch's empty log read as a reset and the events were written twice
 * (36, out of order). */
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <hdf5.h>

static const char *root(void)
{
    const char *r = getenv("CAPDYN_ROOT");
    return r && *r ? r : ".";
}

static const char *bin(void)
{
    const char *b = getenv("CAPDYN_BIN");
    return b && *b ? b : "build/capdyn";
}

/* runs the scenario with the given sampling, returns the event times (n of them) */
static int event_times(const char *sampling, double *t, int cap)
{
    char h5[] = "/tmp/capdyn_dense_events_XXXXXX", cmd[2048], line[512];
    int fd = mkstemp(h5), n = 0;
    FILE *p;
    cr_assert(fd >= 0);
    close(fd);
    snprintf(cmd, sizeof cmd,
             "%s run %s/scenarios/free_floating_arm.toml --set 'simulation.integrator=\"rk8pd\"' "
             "--set 'simulation.sampling=\"%s\"' -o %s -q >/dev/null 2>&1 && %s export %s events",
             bin(), root(), sampling, h5, bin(), h5);
    p = popen(cmd, "r");
    cr_assert_not_null(p);
    while (fgets(line, sizeof line, p))
        if (line[0] != '#' && n < cap) t[n++] = strtod(line, NULL);
    cr_assert_eq(pclose(p), 0, "%s", cmd);
    unlink(h5);
    return n;
}

Test(dense_events, interpolated_samples_write_each_event_once_in_time_order, .timeout = 120)
{
    double ts[64], ti[64];
    int ns = event_times("stop", ts, 64), ni = event_times("interpolate", ti, 64), i;
    cr_expect_eq(ns, 12, "stopped samples: %d events, 12 schedule switches expected", ns);
    cr_expect_eq(ni, ns, "interpolated samples: %d events, %d with stopped ones", ni, ns);
    for (i = 1; i < ni; i++) cr_expect_geq(ti[i], ti[i - 1], "event %d at %g s before event %d at %g s", i, ti[i], i - 1, ti[i - 1]);
    for (i = 0; i < ni && i < ns; i++) cr_expect_eq(ti[i], ts[i], "event %d at %.17g s vs %.17g s", i, ti[i], ts[i]);
}

/* The per-sample diagnostics (docs/results-format.md: nsteps, nrhs, nevents
 * "so far", step_size the last accepted step) of interpolated samples are the
 * run's, not the scratch data's: before the fix every sample inside a step
 * read 0 and only the last one held the counts. ros34pw2 on Fig. 5's closing
 * (0.2 s, 201 samples, about 10^4 steps): the counts never decrease, every
 * sample after the first holds at least one step, and the last equals the
 * file's closing statistics. */
static long long attr_i64(hid_t f, const char *name)
{
    long long v = -2;
    hid_t a = H5Aopen(f, name, H5P_DEFAULT);
    cr_assert(a >= 0, "attribute %s", name);
    H5Aread(a, H5T_NATIVE_LLONG, &v);
    H5Aclose(a);
    return v;
}

static long read_i64(hid_t f, const char *name, long long *v, long cap)
{
    hid_t ds = H5Dopen2(f, name, H5P_DEFAULT), sp;
    hsize_t n;
    cr_assert(ds >= 0, "dataset %s", name);
    sp = H5Dget_space(ds);
    H5Sget_simple_extent_dims(sp, &n, NULL);
    cr_assert_leq(n, (hsize_t)cap);
    H5Dread(ds, H5T_NATIVE_LLONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, v);
    H5Sclose(sp);
    H5Dclose(ds);
    return (long)n;
}

Test(dense_events, interpolated_samples_carry_the_runs_statistics, .timeout = 120)
{
    char h5[] = "/tmp/capdyn_dense_stats_XXXXXX", cmd[2048];
    int fd = mkstemp(h5);
    static long long ns[512], nr[512], ne[512];
    long n, i;
    hid_t f;
    cr_assert(fd >= 0);
    close(fd);
    snprintf(cmd, sizeof cmd,
             "%s run %s/scenarios/paper_fig5_envelope_grasp.toml --set 'simulation.integrator=\"ros34pw2\"' "
             "--set simulation.duration=0.2 -o %s -q >/dev/null 2>&1",
             bin(), root(), h5);
    cr_assert_eq(system(cmd), 0, "%s", cmd);
    f = H5Fopen(h5, H5F_ACC_RDONLY, H5P_DEFAULT);
    cr_assert(f >= 0);
    n = read_i64(f, "diagnostics/nsteps", ns, 512);
    cr_assert_eq(read_i64(f, "diagnostics/nrhs", nr, 512), n);
    cr_assert_eq(read_i64(f, "diagnostics/nevents", ne, 512), n);
    cr_assert_eq(n, 201, "samples: %ld", n);
    for (i = 1; i < n; i++) {
        cr_expect_geq(ns[i], 1, "sample %ld: nsteps %lld", i, ns[i]);
        cr_expect_geq(ns[i], ns[i - 1], "sample %ld: nsteps %lld after %lld", i, ns[i], ns[i - 1]);
        cr_expect_geq(nr[i], nr[i - 1], "sample %ld: nrhs %lld after %lld", i, nr[i], nr[i - 1]);
        cr_expect_geq(ne[i], ne[i - 1], "sample %ld: nevents %lld after %lld", i, ne[i], ne[i - 1]);
    }
    cr_expect_eq(ns[n - 1], attr_i64(f, "stats_nsteps"));
    cr_expect_eq(nr[n - 1], attr_i64(f, "stats_nrhs"));
    cr_expect_eq(ne[n - 1], attr_i64(f, "stats_nevents"));
    H5Fclose(f);
    unlink(h5);
}
