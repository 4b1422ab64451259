/* Grasp quality (docs/grasp-quality.md): the linearised friction cone's
 * under-estimate of epsilon and the Qhull cost versus the number of cone
 * edges m. `make bench-grasp`. Grasp: four frictional point contacts on a
 * sphere at the vertices of a regular tetrahedron, normals through the
 * centre (tests/test_grasp_quality.c, tetra_grasp), 3-D mode. The exact-cone
 * value is bracketed, not extrapolated: the 32-edge polygon of radius mu lies
 * inside the exact cone, the one of radius mu / cos(pi/32) contains it, so
 *   lo = eps_32(mu) <= eps_exact(mu) <= hi = eps_32(mu / cos(pi/32)),
 * and the under-estimate 1 - eps_m/eps_exact of m edges lies in
 * [1 - eps_m/lo, 1 - eps_m/hi] (printed as a range, times are wall clock).
 * Also prints the hand-computed cases of the tests with their errors. */
#define _POSIX_C_SOURCE 199309L /* clock_gettime */
#include <capdyn/analysis.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static double eps(double mu, int m, double *ms, int *nfacet)
{
    static const double v[4][3] = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
    const double c[3] = {0, 0, 0}, r = 0.15 / sqrt(3.0);
    cd_grasp_contact k[4];
    cd_grasp_options o = cd_grasp_options_default();
    cd_grasp_quality q;
    cd_error e;
    double t0;
    int i, a;
    memset(k, 0, sizeof k);
    for (i = 0; i < 4; i++) {
        for (a = 0; a < 3; a++) k[i].p[a] = r * v[i][a], k[i].n[a] = -v[i][a];
        k[i].mu = mu;
        k[i].t[0] = v[i][1], k[i].t[1] = -v[i][0];
    }
    o.cone_edges = m;
    t0 = now();
    if (cd_grasp_quality_eval(k, 4, c, &o, &q, &e) != CD_OK) {
        fprintf(stderr, "%s\n", e.msg);
        return NAN;
    }
    if (ms) *ms = 1e3 * (now() - t0);
    if (nfacet) *nfacet = q.nfacet;
    return q.epsilon;
}

static cd_grasp_contact pc(double px, double py, double nx, double ny, double mu)
{
    cd_grasp_contact k;
    memset(&k, 0, sizeof k);
    k.p[0] = px, k.p[1] = py, k.n[0] = nx, k.n[1] = ny, k.mu = mu;
    return k;
}

/* the hand-computed cases of tests/test_grasp_quality.c: value and error */
static void hand_cases(void)
{
    const double c[3] = {0, 0, 0}, s3 = sqrt(3.0), mus[] = {0.5, 1.0, 1.2, 1.6};
    cd_grasp_contact k[4] = {pc(0.5, 0.25, -1, 0, 0), pc(0.25, 0.5, 0, -1, 0), pc(-0.5, -0.25, 1, 0, 0),
                             pc(-0.25, -0.5, 0, 1, 0)};
    cd_grasp_options o = cd_grasp_options_default();
    cd_grasp_quality q;
    cd_error e;
    unsigned i;
    int j;
    o.mode = CD_GRASP_PLANAR;
    printf("# hand-computed cases: epsilon, hand value, difference\n");
    cd_grasp_quality_eval(k, 4, c, &o, &q, &e);
    printf("  square, rho auto       %.17f %.17f %+.2e\n", q.epsilon, 1.0 / 3.0, q.epsilon - 1.0 / 3.0);
    o.rho = 1.0;
    cd_grasp_quality_eval(k, 4, c, &o, &q, &e);
    printf("  square, rho 1          %.17f %.17f %+.2e\n", q.epsilon, 0.5 / sqrt(5.0), q.epsilon - 0.5 / sqrt(5.0));
    o.rho = 0.0;
    for (i = 0; i < sizeof mus / sizeof mus[0]; i++) {
        double mu = mus[i], h = fmin(mu, (1.0 + s3 * mu) / sqrt(7.0 - 2.0 * s3 * mu + 5.0 * mu * mu));
        for (j = 0; j < 3; j++) {
            double ph = 2.0 * acos(-1.0) * j / 3.0;
            k[j] = pc(0.2 * cos(ph), 0.2 * sin(ph), -cos(ph), -sin(ph), mu);
        }
        cd_grasp_quality_eval(k, 3, c, &o, &q, &e);
        printf("  disc 120 deg, mu %.1f   %.17f %.17f %+.2e\n", mu, q.epsilon, h, q.epsilon - h);
    }
    {
        /* 3-D frictionless cube, 12 contacts: epsilon = 1/sqrt(15) */
        cd_grasp_contact cube[12];
        cd_grasp_options o3 = cd_grasp_options_default();
        int ax, g, n = 0;
        memset(cube, 0, sizeof cube);
        for (ax = 0; ax < 3; ax++)
            for (g = -1; g <= 1; g += 2)
                for (j = -1; j <= 1; j += 2, n++) {
                    cube[n].p[ax] = 0.5 * g;
                    cube[n].p[(ax + 2) % 3] = 0.25 * j;
                    cube[n].n[ax] = -g;
                }
        cd_grasp_quality_eval(cube, 12, c, &o3, &q, &e);
        printf("  cube 3-D, frictionless %.17f %.17f %+.2e\n", q.epsilon, 1.0 / sqrt(15.0), q.epsilon - 1.0 / sqrt(15.0));
    }
    k[0] = pc(0.1, 0, -1, 0, 0.5);
    k[1] = pc(-0.1, 0, 1, 0, 0.5);
    cd_grasp_quality_eval(k, 2, c, &o, &q, &e);
    printf("  antipodal, mu 0.5      %.17f %.17f %+.2e\n", q.epsilon, 1.0 / 3.0, q.epsilon - 1.0 / 3.0);
}

int main(void)
{
    static const double mus[] = {0.2, 0.4, 0.8};
    static const int ms[] = {4, 8, 16, 32, 64};
    const double pi = acos(-1.0);
    unsigned i, j;
    hand_cases();
    printf("# tetrahedral 4-contact grasp, 3-D mode; exact eps in [lo, hi] = [eps_32(mu), eps_32(mu/cos(pi/32))]\n");
    printf("# %4s %4s %14s %22s %12s %8s %10s\n", "mu", "m", "epsilon", "under-estimate range", "1-cos(pi/m)",
           "facets", "time[ms]");
    for (i = 0; i < sizeof mus / sizeof mus[0]; i++) {
        double lo = eps(mus[i], 32, NULL, NULL), hi = eps(mus[i] / cos(pi / 32), 32, NULL, NULL);
        printf("# mu %.1f: eps_exact in [%.9f, %.9f]\n", mus[i], lo, hi);
        for (j = 0; j < sizeof ms / sizeof ms[0]; j++) {
            double t, e;
            int nf;
            e = eps(mus[i], ms[j], &t, &nf);
            printf("  %4.1f %4d %14.9f %10.4f..%-10.4f %12.4f %8d %10.2f\n", mus[i], ms[j], e, fmax(0.0, 1.0 - e / lo),
                   1.0 - e / hi, 1.0 - cos(pi / ms[j]), nf, t);
        }
    }
    return 0;
}
