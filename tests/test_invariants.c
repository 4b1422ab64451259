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
    /* every stepper (rk4imp is capdyn's Gauss stepper, gauss4.c; msbdf its
     * BDF stepper, bdf.c) */
    int steppers[9] = {CD_STEP_RKF45,    CD_STEP_RKCK, CD_STEP_RK8PD,  CD_STEP_RK4_FIXED, CD_STEP_ROS34PW2,
                       CD_STEP_AUTO,     CD_STEP_RODAS4, CD_STEP_RK4IMP, CD_STEP_MSBDF},
        i;
    for (i = 0; i < 9; i++) {
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

/* A ball dropped 1 mm onto a fixed box, gravity on: the contact closes and
 * stays (stiff: K = 1e5 N/m on 0.1 kg, D critical), so auto must switch to
 * ros34pw2 and its switches, stiffness checks and stiff steps allocate
 * nothing either. */
static cd_model *resting_ball(void)
{
    cd_model *m = cd_model_create();
    cd_error e;
    cd_system_desc s = cd_system_desc_default();
    cd_contact_law law = cd_contact_law_from_rule(1e4, 10, 0.1, 1.0, 0.5);
    double half[3] = {0.5, 0.5, 0.05}, pos[3] = {0, 0, -0.05}, c0[3] = {0, 0, 0};
    int ball, floor_, b, sh, lid;
    s.name = "ball";
    s.mass = 0.1;
    s.pos[2] = 0.021; /* radius 0.02: 1 mm above the box's top face at z = 0 */
    ball = cd_model_add_system(m, &s, &e);
    b = m->sys_body_adr[ball];
    cr_assert(cd_model_add_checkpoint(m, b, c0, 0.02, &e) >= 0, "%s", e.msg);
    s = cd_system_desc_default();
    s.name = "floor";
    s.type = CD_BASE_FIXED;
    floor_ = cd_model_add_system(m, &s, &e);
    sh = cd_model_add_shape(m, m->sys_body_adr[floor_], CD_SHAPE_BOX, pos, NULL, half, NULL, 0, &e);
    lid = cd_model_add_law(m, &law, &e);
    cr_assert(cd_model_add_pair(m, ball, -1, sh, lid, &e) >= 0, "%s", e.msg);
    m->gravity[0] = m->gravity[1] = 0;
    m->gravity[2] = -9.81;
    cr_assert(cd_model_finalize(m, &e) == CD_OK, "%s", e.msg);
    m->opt.stepper = CD_STEP_AUTO;
    m->opt.rtol = 1e-6;
    m->opt.atol = 1e-9;
    m->opt.h_max = 0.05;
    return m;
}

Test(invariants, auto_switches_on_a_resting_contact_without_allocating)
{
    cd_model *m = resting_ball();
    cd_error e;
    cd_data *d = cd_data_create(m, 0, &e);
    cd_status st;
    cr_assert(d, "%s", e.msg);
#if CD_COUNT_ALLOC
    nalloc = 0;
    counting = 1;
#endif
    st = cd_sim_advance(m, d, 1.0, NULL, NULL, &e);
#if CD_COUNT_ALLOC
    counting = 0;
    cr_expect_eq(nalloc, 0, "%ld allocations in %ld steps", nalloc, d->stats.nsteps);
#endif
    cr_assert_eq(st, CD_OK, "%s", e.msg);
    /* the ball rests: penetration m g / K within 1 % (K from the rule: 1e4 x 10) */
    cr_expect_eq(d->slot_mode[0], CD_MODE_STICK);
    cr_expect_lt(fabs(d->slot_x[0] - 0.1 * 9.81 / 1e5) / (0.1 * 9.81 / 1e5), 0.01, "penetration %g m", d->slot_x[0]);
    cr_expect_gt(d->stats.nswitch_stiff, 0, "auto never switched to msbdf on a resting stiff contact");
    cr_expect_gt(d->stats.t_stiff, 0.5, "msbdf for %g s of 1 s", d->stats.t_stiff);
    cr_log_info("resting ball: %ld steps, %ld evaluations, %ld switches to stiff, %g s stiff", d->stats.nsteps,
                d->stats.nrhs, d->stats.nswitch_stiff, d->stats.t_stiff);
    cd_data_free(d);
    cd_model_free(m);
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
