/* The articulated-body forward dynamics (src/dynamics/aba.c) against the
 * composite-rigid-body path and against conservation laws:
 *
 *  1. 240 random trees (1-40 joints, free and fixed base, revolute and
 *     prismatic joints on random axes, random state, torques, base wrench,
 *     external wrenches on every body, random gravity): ABA and CRBA give the
 *     same accelerations to 1e-10 relative, and RNE of ABA's answer returns
 *     the applied generalized forces to 1e-10 relative;
 *  2. a free-floating 30-link chain with PD joint actuators (internal
 *     torques) integrated through the default path, which is ABA at 36 DoFs:
 *     linear and angular momentum about the CoM conserved to 1e-10 relative;
 *  3. no allocation in ABA calls nor in the integrated run;
 *  4. a base whose articulated inertia is singular is reported (CD_ENUMERIC),
 *     not turned into NaN. */
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "alloc_count.h"

/* splitmix64: a fixed, portable sequence for reproducible random trees */
static uint64_t aba_seed;
static double rnd(void)
{
    uint64_t z = (aba_seed += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}
static double between(double lo, double hi) { return lo + (hi - lo) * rnd(); }

/* a random rotation from a random unit quaternion (w, x, y, z) */
static void random_rotation(double R[9], double quat[4])
{
    double q[4], n = 0;
    int i;
    for (i = 0; i < 4; i++) { q[i] = between(-1, 1); n += q[i] * q[i]; }
    n = sqrt(n);
    for (i = 0; i < 4; i++) q[i] /= n;
    if (quat) memcpy(quat, q, sizeof q);
    if (R) {
        double w = q[0], x = q[1], y = q[2], z = q[3];
        R[0] = 1 - 2 * (y * y + z * z); R[1] = 2 * (x * y - w * z);     R[2] = 2 * (x * z + w * y);
        R[3] = 2 * (x * y + w * z);     R[4] = 1 - 2 * (x * x + z * z); R[5] = 2 * (y * z - w * x);
        R[6] = 2 * (x * z - w * y);     R[7] = 2 * (y * z + w * x);     R[8] = 1 - 2 * (x * x + y * y);
    }
}

/* principal moments (a, b, c) obeying the triangle inequality, in a random
 * frame: I = Q diag Q^T */
static void random_body_inertia(double I[9], double scale)
{
    double Q[9], a = between(0.5, 1.5) * scale, b = between(0.5, 1.5) * scale, c;
    double lo = fabs(a - b), hi = a + b, dg[3];
    int i, j, k;
    c = lo + (hi - lo) * between(0.1, 0.9);
    dg[0] = a; dg[1] = b; dg[2] = c;
    random_rotation(Q, NULL);
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            double s = 0;
            for (k = 0; k < 3; k++) s += Q[3 * i + k] * dg[k] * Q[3 * j + k];
            I[3 * i + j] = s;
        }
    for (i = 0; i < 3; i++)
        for (j = 0; j < i; j++) I[3 * i + j] = I[3 * j + i] = 0.5 * (I[3 * i + j] + I[3 * j + i]);
}

static void unit_vector(double v[3])
{
    double n;
    do {
        v[0] = between(-1, 1); v[1] = between(-1, 1); v[2] = between(-1, 1);
        n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    } while (n < 0.1 || n > 1.0);
    v[0] /= n; v[1] /= n; v[2] /= n;
}

/* A random tree: each link's parent is the base or any earlier link; with
 * chain != 0 every link hangs on the previous one (the deepest tree). With
 * pd != 0, every joint gets a PD actuator towards a random target and gravity
 * is off (all joint torques internal). */
static cd_model *tree(int njoint, int free_base, int chain, int pd)
{
    cd_model *m = cd_model_create();
    cd_system_desc sd = cd_system_desc_default();
    cd_error e;
    int s, j;
    cr_assert(m);
    sd.type = free_base ? CD_BASE_FREE : CD_BASE_FIXED;
    sd.mass = between(2, 30);
    random_body_inertia(sd.inertia, between(0.5, 4));
    random_rotation(NULL, sd.quat);
    for (j = 0; j < 3; j++) sd.pos[j] = between(-2, 2);
    s = cd_model_add_system(m, &sd, &e);
    cr_assert(s >= 0, "%s", e.msg);
    for (j = 0; j < njoint; j++) {
        cd_link_desc l = cd_link_desc_default();
        int k;
        l.parent = chain ? j : (int)(rnd() * (j + 1));
        if (l.parent > j) l.parent = j;
        l.type = rnd() < 0.65 ? CD_JOINT_REVOLUTE : CD_JOINT_PRISMATIC;
        random_rotation(l.rot, NULL);
        unit_vector(l.axis);
        for (k = 0; k < 3; k++) {
            l.pos[k] = between(-0.4, 0.4);
            l.com[k] = between(-0.2, 0.2);
        }
        l.mass = between(0.2, 4);
        random_body_inertia(l.inertia, between(0.01, 0.3));
        l.qd0 = pd ? between(-0.5, 0.5) : 0.0;
        k = cd_model_add_link(m, s, &l, &e);
        cr_assert(k >= 0, "%s", e.msg);
        if (pd) {
            cd_actuator a;
            memset(&a, 0, sizeof a);
            a.type = CD_ACT_PD;
            a.kp = between(1, 5);
            a.kd = 0.1;
            a.qref = between(-1, 1);
            a.tau0 = between(-0.5, 0.5);
            cr_assert_eq(cd_model_set_actuator(m, k, &a, &e), CD_OK, "%s", e.msg);
        }
    }
    unit_vector(m->gravity);
    for (j = 0; j < 3; j++) m->gravity[j] *= pd ? 0.0 : between(0, 10);
    cr_assert_eq(cd_model_finalize(m, &e), CD_OK, "%s", e.msg);
    return m;
}

/* random state, generalized forces and wrenches on every body */
static void randomize(const cd_model *m, cd_data *d)
{
    cd_sys_state st = cd_state_of(m, d, 0);
    int i;
    if (st.pos) {
        random_rotation(NULL, st.quat);
        for (i = 0; i < 3; i++) {
            st.pos[i] = between(-2, 2);
            st.vel[i] = between(-1, 1);
            st.angvel[i] = between(-1, 1);
        }
    }
    for (i = 0; i < st.njoint; i++) {
        st.q[i] = between(-3, 3);
        st.qd[i] = between(-2, 2);
    }
    cd_kinematics(m, d);
    for (i = 0; i < m->nv; i++) d->tau[i] = between(-5, 5);
    for (i = 0; i < 6 * m->nbody; i++) d->body_fext[i] = between(-3, 3);
}

static double vmax(const double *a, int n)
{
    double r = 0;
    int i;
    for (i = 0; i < n; i++)
        if (fabs(a[i]) > r) r = fabs(a[i]);
    return r;
}

Test(aba, matches_crba_and_inverts_rne_on_random_trees)
{
    double worst = 0, worst_rt = 0;
    int trial, nabove = 0;
    aba_seed = 20261124;
    for (trial = 0; trial < 240; trial++) {
        int nj = 1 + (trial * 7) % 40, free_base = trial % 2 == 0, chain = trial % 5 == 0;
        cd_model *m = tree(nj, free_base, chain, 0);
        cd_error e;
        cd_data *d = cd_data_create(m, 0, &e);
        int n = m->sys_ndof[0];
        double *crba = malloc((size_t)n * sizeof(double)), *tau = malloc((size_t)n * sizeof(double));
        double *tau0 = malloc((size_t)n * sizeof(double)), rel, rt;
        cr_assert(d && crba && tau && tau0, "%s", e.msg);
        randomize(m, d);
        memcpy(tau0, d->tau, (size_t)n * sizeof(double));
        cr_assert_eq(cd_forward_dynamics_method(m, d, CD_FD_CRBA), CD_OK);
        memcpy(crba, d->udot, (size_t)n * sizeof(double));
        memset(d->udot, 0, (size_t)n * sizeof(double));
        cr_assert_eq(cd_forward_dynamics_method(m, d, CD_FD_ABA), CD_OK);
        {
            double diff[512];
            int i;
            cr_assert(n <= 512);
            for (i = 0; i < n; i++) diff[i] = d->udot[i] - crba[i];
            rel = vmax(diff, n) / vmax(crba, n);
            /* round trip: RNE(udot_aba) must give back tau */
            cd_inverse_dynamics(m, d, 0, d->udot, tau);
            for (i = 0; i < n; i++) diff[i] = tau[i] - tau0[i];
            rt = vmax(diff, n) / vmax(tau0, n);
        }
        cr_expect_lt(rel, 1e-10, "trial %d (%d joints, %s base): ABA vs CRBA rel %.3e", trial, nj,
                     free_base ? "free" : "fixed", rel);
        cr_expect_lt(rt, 1e-10, "trial %d: RNE(ABA udot) vs tau rel %.3e", trial, rt);
        if (rel > worst) worst = rel;
        if (rt > worst_rt) worst_rt = rt;
        if (n >= cd_fd_aba_min_dof()) nabove++;
        free(crba); free(tau); free(tau0);
        cd_data_free(d);
        cd_model_free(m);
    }
    /* the sample must cover both sides of the crossover */
    cr_expect_gt(nabove, 40, "trees at or above the ABA crossover: %d", nabove);
    cr_log_info("ABA vs CRBA on 240 random trees: worst rel %.2e; RNE round trip %.2e", worst, worst_rt);
}

/* free-floating chain of n links driven by PD actuators towards random
 * targets, zero gravity: joint torques are internal */
static cd_model *pd_chain(int n)
{
    cd_model *m;
    aba_seed = 30;
    m = tree(n, 1, 1, 1);
    m->opt.rtol = 1e-12;
    m->opt.atol = 1e-14;
    return m;
}

Test(aba, free_floating_30_link_chain_conserves_momentum)
{
    cd_model *m = pd_chain(30);
    cd_error e;
    cd_data *d = cd_data_create(m, 0, &e);
    cd_sys_state st;
    double P0[3], L0[3], c0[3], P[3], L[3], c[3], dP, dL, nP, nL;
    int i;
    cr_assert(d, "%s", e.msg);
    cr_assert_geq(m->sys_ndof[0], cd_fd_aba_min_dof(), "the default path must be ABA for this chain");
    st = cd_state_of(m, d, 0);
    for (i = 0; i < 3; i++) { st.vel[i] = 0.1 * (i + 1); st.angvel[i] = 0.05 * (2 - i); }
    cd_kinematics(m, d);
    cd_momentum(m, d, 0, NULL, P0, L0, NULL, c0);
    cr_assert_eq(cd_sim_advance(m, d, 2.0, NULL, NULL, &e), CD_OK, "%s", e.msg);
    cd_kinematics(m, d);
    cd_momentum(m, d, 0, NULL, P, L, NULL, c);
    dP = dL = nP = nL = 0;
    for (i = 0; i < 3; i++) {
        dP += (P[i] - P0[i]) * (P[i] - P0[i]); nP += P0[i] * P0[i];
        dL += (L[i] - L0[i]) * (L[i] - L0[i]); nL += L0[i] * L0[i];
    }
    dP = sqrt(dP / nP);
    dL = sqrt(dL / nL);
    /* integrator error (rtol 1e-12) is the only source of drift */
    cr_expect_lt(dP, 1e-10, "linear momentum drift %.3e relative", dP);
    cr_expect_lt(dL, 1e-10, "angular momentum (about the CoM) drift %.3e relative", dL);
    {
        /* the joints moved: the test is not trivially at rest */
        double moved = 0;
        for (i = 0; i < st.njoint; i++) moved += fabs(st.qd[i]);
        cr_expect_gt(moved, 1e-2, "joint rates sum %.3e", moved);
    }
    cr_log_info("30-link chain, 2 s through ABA: |dP|/|P| %.2e, |dL|/|L| %.2e (%ld rhs)", dP, dL, d->stats.nrhs);
    cd_data_free(d);
    cd_model_free(m);
}

Test(aba, allocates_nothing)
{
#if CD_COUNT_ALLOC
    cd_model *m = pd_chain(30);
    cd_error e;
    cd_data *d = cd_data_create(m, 0, &e);
    int k;
    cr_assert(d, "%s", e.msg);
    cd_kinematics(m, d);
    cd_test_nalloc = 0;
    cd_test_counting = 1;
    for (k = 0; k < 100; k++) cd_forward_dynamics_method(m, d, CD_FD_ABA);
    cd_sim_advance(m, d, 0.05, NULL, NULL, &e);
    cd_test_counting = 0;
    cr_expect_eq(cd_test_nalloc, 0, "%ld allocations in 100 ABA calls and %ld steps", cd_test_nalloc,
                 d->stats.nsteps);
    cr_expect_gt(d->stats.nsteps, 0);
    cd_data_free(d);
    cd_model_free(m);
#else
    cr_skip_test("allocation counting needs glibc malloc (not under ASan)");
#endif
}

Test(aba, singular_articulated_base_is_reported)
{
    /* a 1e-20 kg base carrying a 1 kg link: the base's articulated inertia
     * is singular in floating point (the same case CRBA refuses) */
    cd_model *m = cd_model_create();
    cd_system_desc sd = cd_system_desc_default();
    cd_link_desc l = cd_link_desc_default();
    cd_error e;
    cd_data *d;
    int i;
    sd.mass = 1e-20;
    sd.inertia[0] = sd.inertia[4] = sd.inertia[8] = 1e-20;
    cd_model_add_system(m, &sd, &e);
    l.parent = 0;
    l.pos[0] = 0.5;
    cr_assert(cd_model_add_link(m, 0, &l, &e) >= 0, "%s", e.msg);
    cr_assert_eq(cd_model_finalize(m, &e), CD_OK, "%s", e.msg);
    d = cd_data_create(m, 0, &e);
    cr_assert(d, "%s", e.msg);
    cd_kinematics(m, d);
    for (i = 0; i < m->nv; i++) d->udot[i] = 0.0;
    cr_expect_eq(cd_forward_dynamics_method(m, d, CD_FD_ABA), CD_ENUMERIC);
    cr_expect_eq(cd_forward_dynamics_method(m, d, CD_FD_CRBA), CD_ENUMERIC);
    cd_data_free(d);
    cd_model_free(m);
}
