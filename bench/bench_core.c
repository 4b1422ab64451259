/* Core benchmarks (make bench): cost of one right-hand-side evaluation for
 * free-floating chains of growing size, and two contact validation cases of
 * issue 3 (right-hand-side evaluations and wall time). Wall times are medians
 * of repeated runs on this machine; rhs counts are exact and repeatable. */
#include <capdyn/capdyn.h>
#include "bench_chain.h"
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

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}
#include <stdlib.h>
static double median(double *v, int n) { qsort(v, (size_t)n, sizeof *v, cmp); return v[n / 2]; }

static void bench_rhs(void)
{
    int sizes[5] = {2, 7, 12, 20, 30}, k;
    printf("right-hand side (kinematics + CRBA + Cholesky + RNE), free-floating chain\n");
    printf("%8s %14s\n", "joints", "us/eval");
    for (k = 0; k < 5; k++) {
        cd_model *m = bench_chain(sizes[k], 1);
        cd_error e;
        cd_data *d = cd_data_create(m, 0, &e);
        double t[7];
        int r, i, reps = 20000 / sizes[k] + 200;
        for (r = 0; r < 7; r++) {
            double t0 = now();
            for (i = 0; i < reps; i++) cd_forward(m, d);
            t[r] = (now() - t0) / reps * 1e6;
        }
        printf("%8d %14.2f\n", sizes[k], median(t, 7));
        cd_data_free(d);
        cd_model_free(m);
    }
}

/* issue 3 validation case 3 (sliding block) and case 5 (Fig. 3 impact) */
static void bench_contact(void)
{
    const double G = 9.81;
    int r;
    double tw[5];
    long nrhs = 0, nev = 0;
    printf("\ncontact cases (rk8pd, rtol 1e-11, atol 1e-13)\n");
    for (r = 0; r < 5; r++) {
        cd_model *m = cd_model_create();
        cd_error e;
        cd_system_desc s = cd_system_desc_default();
        cd_contact_law law = cd_contact_law_default();
        double th = atan(0.55), z[3] = {0, 0, 0}, t0;
        int pl, lid;
        cd_data *d;
        s.type = CD_BASE_FIXED;
        cd_model_add_system(m, &s, &e);
        pl = cd_model_add_shape(m, 0, CD_SHAPE_PLANE, NULL, NULL, NULL, NULL, 0, &e);
        s = cd_system_desc_default();
        s.inertia[0] = s.inertia[4] = s.inertia[8] = 1e6;
        s.pos[2] = -G * cos(th) / 1e6;
        cd_model_add_system(m, &s, &e);
        cd_model_add_checkpoint(m, 1, z, 0, &e);
        law.K = law.Kt = 1e6;
        law.D = law.Dt = 2e3;
        law.mu_s = 0.5;
        law.mu_k = 0.4;
        lid = cd_model_add_law(m, &law, &e);
        cd_model_add_pair(m, 1, -1, pl, lid, &e);
        m->gravity[0] = G * sin(th);
        m->gravity[2] = -G * cos(th);
        cd_model_finalize(m, &e);
        m->opt.rtol = 1e-11; m->opt.atol = 1e-13; m->opt.h_max = 1e-3;
        d = cd_data_create(m, 0, &e);
        t0 = now();
        cd_sim_advance(m, d, 1.5, NULL, NULL, &e);
        tw[r] = now() - t0;
        nrhs = d->stats.nrhs;
        nev = d->stats.nevents;
        cd_data_free(d);
        cd_model_free(m);
    }
    printf("  case 3, block sliding down a 28.8 deg incline, 1.5 s: %ld rhs evals, %ld events, %.1f ms\n",
           nrhs, nev, 1e3 * median(tw, 5));
    for (r = 0; r < 5; r++) {
        /* Fig. 2-3: M = 10 kg free base, front mass m = 0.1 kg on a prismatic
         * spring K_a = pi^2 M / 0.2^2, wall contact K_b = 1e6 N/m */
        cd_model *m = cd_model_create();
        cd_error e;
        cd_system_desc s = cd_system_desc_default();
        cd_link_desc l = cd_link_desc_default();
        cd_contact_law law = cd_contact_law_default();
        cd_actuator a;
        double z[3] = {0, 0, 0}, pos[3] = {0, 0, 0}, rot[9] = {0, 0, -1, 0, 1, 0, 1, 0, 0}, t0;
        int pl, lid, front;
        cd_data *d;
        s.type = CD_BASE_FIXED;
        cd_model_add_system(m, &s, &e);
        pos[0] = 0.0;
        /* wall: plane whose outward normal is -x, at x = 0 */
        pl = cd_model_add_shape(m, 0, CD_SHAPE_PLANE, pos, rot, NULL, NULL, 0, &e);
        s = cd_system_desc_default();
        s.mass = 10;
        s.pos[0] = -0.2;
        s.vel[0] = 0.5;
        cd_model_add_system(m, &s, &e);
        l.parent = 1;
        l.type = CD_JOINT_PRISMATIC;
        l.axis[0] = 1; l.axis[2] = 0;
        l.pos[0] = 0.1;
        l.mass = 0.1;
        l.qd0 = 0;
        front = cd_model_add_link(m, 1, &l, &e);
        memset(&a, 0, sizeof a);
        a.type = CD_ACT_PD;
        a.kp = 9.869604401089358 * 10 / 0.04; /* pi^2 M / T^2, T = 0.2 s */
        a.kd = 1.0;
        cd_model_set_actuator(m, front, &a, &e);
        cd_model_add_checkpoint(m, front, z, 0.0, &e);
        law.K = 1e6;
        law.D = 2 * 0.1 * sqrt(1e6 * 0.1);
        law.Kt = 1e6;
        law.Dt = law.D;
        lid = cd_model_add_law(m, &law, &e);
        cd_model_add_pair(m, 1, -1, pl, lid, &e);
        cd_model_finalize(m, &e);
        m->opt.rtol = 1e-11; m->opt.atol = 1e-13;
        d = cd_data_create(m, 0, &e);
        t0 = now();
        cd_sim_advance(m, d, 0.6, NULL, NULL, &e);
        tw[r] = now() - t0;
        nrhs = d->stats.nrhs;
        nev = d->stats.nevents;
        cd_data_free(d);
        cd_model_free(m);
    }
    printf("  case 5, Fig. 2-3 compliant mechanism hitting a wall, 0.6 s: %ld rhs evals, %ld events, %.1f ms\n",
           nrhs, nev, 1e3 * median(tw, 5));
}

int main(void)
{
    printf("capdyn %s core benchmarks\n\n", cd_version());
    bench_rhs();
    bench_contact();
    return 0;
}
