/* control_loop.c -- a 1 kHz joint-space control loop around cd_step, as a
 * flight-software prototype would write it (docs/embedding.md).
 *
 * The plant: a free-floating spacecraft (150 kg, drifting at a few cm/s and
 * tumbling at about 1 deg/s) carrying a 3-joint arm. Each joint is driven by
 * an actuator of type CD_ACT_NONE, so its torque is exactly the command the
 * controller writes into d->ctrl.
 *
 * The loop, every 1 ms: read the joint angles and rates (cd_state_of),
 * compute a PD + feed-forward law toward a minimum-jerk reference that moves
 * the arm to a target posture, write d->ctrl, call cd_step(m, d, 1e-3) --
 * one classic RK4 step with the command held constant over it (a zero-order
 * hold, as a real digital controller applies it) -- and check the status.
 *
 * What running it checks (exit status 1 if any fails, so it is a test):
 *  - the arm reaches the target posture: every joint within JOINT_TOL rad and
 *    JOINT_TOL rad/s of it at the end;
 *  - no external force acts, so the linear momentum and the angular momentum
 *    about the system's centre of mass of the whole free-floating system
 *    (base + arm) are conserved: each may drift by at most MOMENTUM_TOL
 *    relative to its initial value (cd_momentum);
 *  - checkpoint/rollback: the complete state saved mid-run (cd_state_get),
 *    restored (cd_state_set) and run again to the end gives a final state
 *    bit-identical to the first run's;
 *  - hard real time: no cd_step call spends more right-hand-side evaluations
 *    than opt.max_evals, and nothing is allocated after start-up (every byte
 *    of the data comes from a fixed static arena, through cd_data_create_ex);
 *  - a step whose command did not change costs 4 evaluations (sim.h).
 *
 * Build (the Makefile does this for every example):
 *   cc -std=c99 -Iinclude examples/control_loop.c build/libcapdyn.a \
 *      $(pkg-config --libs gsl ccd) -lm -o control_loop
 * It needs nothing but <capdyn/capdyn.h> and the C library. The model and the
 * controller are in control_loop_model.h (bench/bench_ticks.c times them). */
#include <capdyn/capdyn.h>
#include "control_loop_model.h" /* the plant (build_model) and the controller (control_tick) */

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#define T_CKPT 2.5           /* where the checkpoint is taken [s] */
#define MAX_EVALS 20         /* evaluation budget of one cd_step call (see main) */
#define JOINT_TOL 1e-4       /* final joint error [rad] and rate [rad/s] */
#define MOMENTUM_TOL 1e-9    /* relative momentum drift */
#define ARENA_BYTES (64 * 1024)
#define HOLD_STEPS 100       /* steps with the command held, at the end */

/* ---- a static arena: all the memory of the simulation data ----------------
 * A bump allocator over a fixed buffer. cd_data_create_ex takes its memory
 * from it at start-up; a counter shows that no call after start-up asks for
 * more. free is a no-op: the arena is given back as a whole at exit. */
typedef struct {
    unsigned char *base;
    size_t cap, used;
    long nalloc, nfree;
} arena;

static void *arena_alloc(size_t n, void *ctx)
{
    arena *a = (arena *)ctx;
    size_t at = (a->used + 15) & ~(size_t)15; /* 16-byte aligned, like malloc */
    if (n > a->cap || at > a->cap - n) return NULL; /* cd_data_create_ex then fails with CD_ENOMEM */
    a->used = at + n;
    a->nalloc++;
    return a->base + at;
}

static void arena_free(void *p, void *ctx)
{
    (void)p;
    ((arena *)ctx)->nfree++;
}

/* ---- the loop ---------------------------------------------------------------- */
typedef struct {
    long ncalls;
    long max_evals_call;     /* most evaluations one cd_step call spent */
} loop_stats;

/* Runs ticks k_from .. k_to - 1 (time k h .. k_to h); saves the complete
 * state into ckpt when the loop reaches tick k_ckpt (ckpt may be NULL).
 * Returns the first failing status (err filled), CD_OK otherwise. */
static cd_status run(const cd_model *m, cd_data *d, controller *c, const arm_ids *ids, long k_from, long k_to,
                     long k_ckpt, double *ckpt, loop_stats *ls, cd_error *err)
{
    const double h = 1.0 / RATE_HZ;
    long k;
    for (k = k_from; k < k_to; k++) {
        long n0 = d->stats.nrhs;
        cd_status st;
        if (ckpt && k == k_ckpt) cd_state_get(m, d, ckpt); /* between calls, before this tick's command */
        if (control_tick(m, d, c, ids) != 0) {
            cd_error_set(err, CD_ENUMERIC, "controller: the base's mass matrix is not positive definite at t = %g s", d->t);
            return CD_ENUMERIC;
        }
        st = cd_step(m, d, h, err);
        /* in flight: CD_EBUDGET means the step did not finish in its budget
         * (d holds the last good state); CD_ENUMERIC a non-finite state. A
         * real loop would switch to a safe mode here; the example stops. */
        if (st != CD_OK) return st;
        ls->ncalls++;
        if (d->stats.nrhs - n0 > ls->max_evals_call) ls->max_evals_call = d->stats.nrhs - n0;
    }
    return CD_OK;
}

static double norm3(const double v[3]) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }
static double dist3(const double a[3], const double b[3])
{
    double e[3];
    e[0] = a[0] - b[0]; e[1] = a[1] - b[1]; e[2] = a[2] - b[2];
    return norm3(e);
}

int main(void)
{
    /* all of the data's memory: a fixed buffer (aligned for any scalar type) */
    static union { long double ld; double d; void *p; } arena_mem[ARENA_BYTES / sizeof(long double)];
    arena ar;
    cd_allocator alloc;
    cd_error err;
    cd_model *m;
    cd_data *d;
    arm_ids ids;
    controller ctl;
    loop_stats ls = {0, 0};
    double *ckpt, *fin1, *fin2, P0[3], L0[3], P1[3], L1[3], dP, dL, emax = 0, rmax = 0;
    const double wn = 2 * 3.14159265358979323846 * 1.5; /* 1.5 Hz closed-loop bandwidth */
    const long n_steps = (long)(T_END * RATE_HZ + 0.5), k_ckpt = (long)(T_CKPT * RATE_HZ + 0.5);
    long nalloc_startup, nalloc_data;
    double evals_new, evals_held = 0;
    cd_status st_hold = CD_OK;
    size_t nstate;
    clock_t c0, c1;
    int j, fails = 0;

    memset(&err, 0, sizeof err);
    ctl.q0[0] = 0.0; ctl.q0[1] = 0.3; ctl.q0[2] = -0.6;
    ctl.qT[0] = 0.8; ctl.qT[1] = -0.4; ctl.qT[2] = 1.0;
    ctl.kp = wn * wn;
    ctl.kd = 2 * wn;

    /* ---- start-up: the only phase that allocates ---- */
    m = build_model(ctl.q0, &ids, &err); /* the model itself is built with malloc, once */
    if (!m) { fprintf(stderr, "control_loop: model: %s\n", err.msg); return 1; }

    ar.base = (unsigned char *)arena_mem;
    ar.cap = sizeof arena_mem;
    ar.used = 0;
    ar.nalloc = ar.nfree = 0;
    alloc.alloc = arena_alloc;
    alloc.free = arena_free;
    alloc.ctx = &ar;
    /* the stepper is fixed when the data is created (its objects are made
     * for it): set it in the model's options first. With the fixed-step RK4
     * no GSL stepper object exists at all, so every byte comes from the arena. */
    m->opt.stepper = CD_STEP_RK4_FIXED;
    d = cd_data_create_ex(m, 64, &alloc, &err);
    if (!d) { fprintf(stderr, "control_loop: data: %s\n", err.msg); cd_model_free(m); return 1; }
    /* Runtime options live in d->opt. The budget: one RK4 step costs 4
     * evaluations when nothing changed since the last call (the end-of-step
     * evaluation serves as the next first stage) and 5 when the command
     * changed (the first stage is evaluated again with the new input); the
     * rest is head-room for locating an event (none in this model: no
     * contacts, no joint stops). cd_step refuses budgets below 20 (the
     * re-check of a changed input, the step, and an event's location reserve). */
    d->opt.max_evals = MAX_EVALS;
    nalloc_data = ar.nalloc;

    /* checkpoint buffers, also from the arena */
    nstate = cd_state_size(m);
    ckpt = (double *)arena_alloc(nstate * sizeof(double), &ar);
    fin1 = (double *)arena_alloc(nstate * sizeof(double), &ar);
    fin2 = (double *)arena_alloc(nstate * sizeof(double), &ar);
    if (!ckpt || !fin1 || !fin2) { fprintf(stderr, "control_loop: arena too small\n"); cd_data_free(d); cd_model_free(m); return 1; }
    nalloc_startup = ar.nalloc;

    cd_kinematics(m, d);
    cd_momentum(m, d, 0, NULL, P0, L0, NULL, NULL);

    /* ---- the real-time phase: run to T_END, checkpoint at T_CKPT ---- */
    c0 = clock();
    if (run(m, d, &ctl, &ids, 0, n_steps, k_ckpt, ckpt, &ls, &err) != CD_OK) {
        fprintf(stderr, "control_loop: %s: %s\n", cd_status_string(err.status), err.msg);
        cd_data_free(d); cd_model_free(m); return 1;
    }
    c1 = clock();
    evals_new = (double)d->stats.nrhs / (double)ls.ncalls;
    cd_state_get(m, d, fin1);
    cd_kinematics(m, d);
    cd_momentum(m, d, 0, NULL, P1, L1, NULL, NULL);
    {
        cd_sys_state x = cd_state_of(m, d, 0);
        for (j = 0; j < NJ; j++) {
            if (fabs(x.q[j] - ctl.qT[j]) > emax) emax = fabs(x.q[j] - ctl.qT[j]);
            if (fabs(x.qd[j]) > rmax) rmax = fabs(x.qd[j]);
        }
        printf("capdyn control_loop: %d-joint arm on a free-floating base, %d Hz, cd_step with %s\n", NJ, RATE_HZ,
               cd_stepper_name(d->opt.stepper));
        printf("  run to t = %.3f s: %ld steps, %ld evaluations (%.2f per step, at most %ld in one call, budget %ld)\n",
               d->t, ls.ncalls, d->stats.nrhs, (double)d->stats.nrhs / (double)ls.ncalls, ls.max_evals_call,
               d->opt.max_evals);
        printf("  final joint error [rad]:   ");
        for (j = 0; j < NJ; j++) printf(" %+.3e", x.q[j] - ctl.qT[j]);
        printf("   (tolerance %.0e)\n", JOINT_TOL);
        printf("  final joint rate [rad/s]:  ");
        for (j = 0; j < NJ; j++) printf(" %+.3e", x.qd[j]);
        printf("   (tolerance %.0e)\n", JOINT_TOL);
    }
    dP = dist3(P1, P0) / norm3(P0);
    dL = dist3(L1, L0) / norm3(L0);
    printf("  momentum drift (relative): linear %.2e, angular about the CoM %.2e   (tolerance %.0e)\n", dP, dL,
           MOMENTUM_TOL);

    /* ---- rollback: restore the checkpoint and run the second half again ---- */
    if (cd_state_set(m, d, ckpt, &err) != CD_OK) {
        fprintf(stderr, "control_loop: restore: %s\n", err.msg);
        cd_data_free(d); cd_model_free(m); return 1;
    }
    printf("  checkpoint restored at t = %.3f s, ", d->t);
    if (run(m, d, &ctl, &ids, k_ckpt, n_steps, -1, NULL, &ls, &err) != CD_OK) {
        fprintf(stderr, "control_loop: rerun: %s: %s\n", cd_status_string(err.status), err.msg);
        cd_data_free(d); cd_model_free(m); return 1;
    }
    cd_state_get(m, d, fin2);
    printf("rerun to t = %.3f s: final state (%lu doubles) %s\n", d->t, (unsigned long)nstate,
           memcmp(fin1, fin2, nstate * sizeof(double)) == 0 ? "bit-identical" : "DIFFERS");
    /* ---- the cost of a step whose input did not change: hold the last
     * command for HOLD_STEPS more ticks (sim.h: 4 evaluations, the previous
     * step's end evaluation serving as the first stage) ---- */
    {
        long n0 = d->stats.nrhs, k;
        for (k = 0; k < HOLD_STEPS && st_hold == CD_OK; k++) st_hold = cd_step(m, d, 1.0 / RATE_HZ, &err);
        evals_held = (double)(d->stats.nrhs - n0) / HOLD_STEPS;
        printf("  command held for %d more steps: %.2f evaluations per step (a new command each tick: %.2f)\n",
               HOLD_STEPS, evals_held, evals_new);
    }
    printf("  memory: %lu of %lu arena bytes; blocks taken at start-up %ld (data %ld, state buffers 3), after it %ld\n",
           (unsigned long)ar.used, (unsigned long)ar.cap, nalloc_startup, nalloc_data, ar.nalloc - nalloc_startup);
    printf("  CPU time: %.1f us per step (this machine; the budget is 1000 us)\n",
           1e6 * (double)(c1 - c0) / CLOCKS_PER_SEC / (double)n_steps);

    /* ---- verdict ---- */
    if (!(emax <= JOINT_TOL && rmax <= JOINT_TOL)) { fprintf(stderr, "FAIL: the arm did not converge\n"); fails++; }
    if (!(dP <= MOMENTUM_TOL && dL <= MOMENTUM_TOL)) { fprintf(stderr, "FAIL: momentum drift\n"); fails++; }
    if (memcmp(fin1, fin2, nstate * sizeof(double)) != 0) { fprintf(stderr, "FAIL: rollback not bit-identical\n"); fails++; }
    if (ls.max_evals_call > MAX_EVALS) { fprintf(stderr, "FAIL: evaluation budget exceeded\n"); fails++; }
    if (ar.nalloc != nalloc_startup) { fprintf(stderr, "FAIL: allocation after start-up\n"); fails++; }
    if (st_hold != CD_OK || evals_held != 4.0) { fprintf(stderr, "FAIL: a step with the command held must cost 4 evaluations\n"); fails++; }

    cd_data_free(d);   /* gives its blocks back to the arena (a no-op here) */
    cd_model_free(m);
    printf("%s\n", fails ? "FAIL" : "PASS");
    return fails ? 1 : 0;
}
