/* Invariants of the core: no allocation inside a step, bit-identical results
 * across runs and across data objects sharing one model, and the model being
 * read-only after finalize (STYLE.md 12).
 *
 * Allocation counting interposes malloc/calloc/realloc for this test binary
 * (forwarding to glibc's __libc_* entry points) and counts calls only while
 * `counting` is set; under AddressSanitizer (which owns malloc) the counting
 * test is skipped, the other invariants still run. */
#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "alloc_count.h"

volatile int cd_test_counting;
volatile long cd_test_nalloc;
#define counting cd_test_counting
#define nalloc cd_test_nalloc

#if CD_COUNT_ALLOC
extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
void *malloc(size_t n)
{
    if (counting) nalloc++;
    return __libc_malloc(n);
}
void *calloc(size_t a, size_t b)
{
    if (counting) nalloc++;
    return __libc_calloc(a, b);
}
void *realloc(void *p, size_t n)
{
    if (counting) nalloc++;
    return __libc_realloc(p, n);
}
#endif

/* A grasp-like scene: a 3-link arm on a free base sweeping its check points
 * through a free sphere and a fixed box, with gravity off and torques on. */
static cd_model *scene(int stepper)
{
    cd_model *m = cd_model_create();
    cd_error e;
    cd_system_desc s = cd_system_desc_default();
    cd_link_desc l = cd_link_desc_default();
    cd_contact_law law = cd_contact_law_from_rule(1e3, 10, 0.1, 1.0, 0.4);
    cd_actuator a;
    int arm, ball, wall, b, i, prev, sh_ball, sh_box, lid;
    double half[3] = {0.05, 0.5, 0.5}, pos[3] = {0.45, 0, 0}, r[3] = {0.06, 0, 0};
    s.name = "arm";
    s.mass = 5;
    arm = cd_model_add_system(m, &s, &e);
    prev = m->sys_body_adr[arm];
    for (i = 0; i < 3; i++) {
        double cp[3] = {0.05, 0, 0};
        l.name = i == 0 ? "l0" : (i == 1 ? "l1" : "l2");
        l.parent = prev;
        l.pos[0] = i == 0 ? 0.1 : 0.1;
        l.com[0] = 0.05;
        l.mass = 0.3;
        l.inertia[0] = 1e-4; l.inertia[4] = l.inertia[8] = 4e-4;
        b = cd_model_add_link(m, arm, &l, &e);
        cr_assert(b >= 0, "%s", e.msg);
        cd_model_add_checkpoint(m, b, cp, 0.01, &e);
        cp[0] = 0.1;
        cd_model_add_checkpoint(m, b, cp, 0.01, &e);
        memset(&a, 0, sizeof a);
        a.type = CD_ACT_CONSTANT;
        a.tau0 = 0.05 * (i + 1);
        cd_model_set_actuator(m, b, &a, &e);
        prev = b;
    }
    s = cd_system_desc_default();
    s.name = "ball";
    s.mass = 0.5;
    s.pos[0] = 0.25; s.pos[1] = 0.12;
    s.angvel[2] = 0.3;
    ball = cd_model_add_system(m, &s, &e);
    sh_ball = cd_model_add_shape(m, m->sys_body_adr[ball], CD_SHAPE_SPHERE, NULL, NULL, r, NULL, 0, &e);
    s = cd_system_desc_default();
    s.name = "wall";
    s.type = CD_BASE_FIXED;
    wall = cd_model_add_system(m, &s, &e);
    sh_box = cd_model_add_shape(m, m->sys_body_adr[wall], CD_SHAPE_BOX, pos, NULL, half, NULL, 0, &e);
    lid = cd_model_add_law(m, &law, &e);
    cr_assert(cd_model_add_pair(m, arm, -1, sh_ball, lid, &e) >= 0, "%s", e.msg);
    cr_assert(cd_model_add_pair(m, arm, -1, sh_box, lid, &e) >= 0, "%s", e.msg);
    cr_assert(cd_model_finalize(m, &e) == CD_OK, "%s", e.msg);
    m->opt.stepper = stepper;
    m->opt.rtol = 1e-8;
    m->opt.atol = 1e-10;
    return m;
}

Test(invariants, no_allocation_in_steps_and_events)
{
#if CD_COUNT_ALLOC
    /* every stepper capdyn owns; rk4imp and msbdf are GSL's and allocate in
     * gsl_linalg_LU_decomp (docs/embedding.md: not for flight loops) */
    int steppers[6] = {CD_STEP_RKF45, CD_STEP_RKCK, CD_STEP_RK8PD, CD_STEP_RK4_FIXED, CD_STEP_ROS34PW2, CD_STEP_AUTO}, i;
    for (i = 0; i < 6; i++) {
        cd_model *m = scene(steppers[i]);
        cd_error e;
        cd_data *d = cd_data_create(m, 0, &e);
        cd_status st;
        cr_assert(d);
        nalloc = 0;
        counting = 1;
        st = cd_sim_advance(m, d, 0.3, NULL, NULL, &e);
        counting = 0;
        cr_assert_eq(st, CD_OK, "%s", e.msg);
        cr_expect_gt(d->stats.nevents, 0, "the scene must exercise events (%s)", cd_stepper_name(steppers[i]));
        cr_expect_eq(nalloc, 0, "%ld allocations during %ld steps with %s", nalloc, d->stats.nsteps,
                     cd_stepper_name(steppers[i]));
        cd_data_free(d);
        cd_model_free(m);
    }
#else
    cr_skip_test("allocation counting needs glibc malloc (not under ASan)");
#endif
}

Test(invariants, bit_identical_across_runs_and_data)
{
    /* two data on one model, run in interleaved slices, and a rerun after
     * reset: all three final states must agree bit for bit */
    cd_model *m = scene(CD_STEP_RK8PD);
    cd_error e;
    cd_data *a = cd_data_create(m, 0, &e), *b = cd_data_create(m, 0, &e);
    double t;
    double *ya = malloc((size_t)m->ny * sizeof(double));
    for (t = 0.05; t <= 0.3001; t += 0.05) {
        cr_assert_eq(cd_sim_advance(m, a, t, NULL, NULL, &e), CD_OK, "%s", e.msg);
        cr_assert_eq(cd_sim_advance(m, b, t, NULL, NULL, &e), CD_OK, "%s", e.msg);
    }
    cr_expect_eq(memcmp(a->y, b->y, (size_t)m->ny * sizeof(double)), 0, "two data, one model");
    cr_expect_eq(a->ev_count, b->ev_count);
    memcpy(ya, a->y, (size_t)m->ny * sizeof(double));
    cd_data_reset(m, a, NULL);
    cr_assert_eq(cd_sim_advance(m, a, 0.3, NULL, NULL, &e), CD_OK, "%s", e.msg);
    /* one long advance vs slices: the same steps are not guaranteed (t_end
     * clamps a step), so only the slice-vs-slice comparison is bitwise */
    cr_expect_lt(fabs(a->y[0] - ya[0]), 1e-6, "slicing changes results only within tolerance");
    cd_data_reset(m, b, NULL);
    for (t = 0.05; t <= 0.3001; t += 0.05) cd_sim_advance(m, b, t, NULL, NULL, &e);
    cr_expect_eq(memcmp(b->y, ya, (size_t)m->ny * sizeof(double)), 0, "rerun after reset is bit-identical");
    free(ya);
    cd_data_free(a);
    cd_data_free(b);
    cd_model_free(m);
}

Test(invariants, model_is_read_only_after_finalize)
{
    cd_model *m = scene(CD_STEP_RK8PD);
    cd_error e;
    cd_system_desc s = cd_system_desc_default();
    double z[3] = {0, 0, 0};
    cr_expect_eq(cd_model_add_system(m, &s, &e), -1);
    cr_expect(strstr(e.msg, "finalized") != NULL, "message: %s", e.msg);
    cr_expect_eq(cd_model_add_checkpoint(m, 0, z, 0.1, &e), -1);
    cd_model_free(m);
}
