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
