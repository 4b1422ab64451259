/* ThreadSanitizer check (make tsan; issue 24): two threads run on one shared,
 * finalized model, each with its own cd_data: a free-floating base with a
 * 3-link arm driven by a PD law (built-in, STEPS schedule on the first joint,
 * breakpoints located as events) and by a control callback adding a
 * feed-forward input; adaptive steps (cd_sim_advance, rk8pd) then a
 * checkpoint (cd_state_get / cd_state_set) and fixed-rate steps (cd_step).
 * Built with -fsanitize=thread by `make tsan`: a data race between the
 * threads (a hidden global, a write to the shared model) is a TSan report
 * and a non-zero exit. Also checks that both threads end bit-identical to a
 * run on the main thread alone. Exit 0 on success; one summary line. */
#define _POSIX_C_SOURCE 200809L
#include <capdyn/capdyn.h>
#include <gsl/gsl_errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NJ 3

typedef struct {
    const cd_model *m;
    double *y_end;     /* (ny) final state */
    double t_end;
    long nevents;
    int ok;
    char msg[600];
} job;

static cd_link_desc rod(int parent, const double pos[3], const double axis[3], double mass, double len, double q0)
{
    cd_link_desc l = cd_link_desc_default();
    l.parent = parent;
    l.type = CD_JOINT_REVOLUTE;
    memcpy(l.pos, pos, sizeof l.pos);
    memcpy(l.axis, axis, sizeof l.axis);
    l.mass = mass;
    l.com[0] = 0.5 * len;
    memset(l.inertia, 0, sizeof l.inertia);
    l.inertia[0] = 1e-3 * mass;
    l.inertia[4] = l.inertia[8] = mass * len * len / 12.0;
    l.q0 = q0;
    return l;
}

static cd_model *build(cd_error *err)
{
    static const double z[3] = {0, 0, 1}, y[3] = {0, 1, 0}, mount[3] = {0.6, 0, 0}, elbow[3] = {0.5, 0, 0};
    static const double steps_t[3] = {0.05, 0.12, 0.2}, steps_v[3] = {0.5, -0.3, 0.1};
    cd_model *m = cd_model_create();
    cd_system_desc base = cd_system_desc_default();
    int j, sys, link[NJ];
    if (!m) return NULL;
    base.name = "spacecraft";
    base.type = CD_BASE_FREE;
    base.mass = 150.0;
    memset(base.inertia, 0, sizeof base.inertia);
    base.inertia[0] = 20.0; base.inertia[4] = 25.0; base.inertia[8] = 30.0;
    base.angvel[0] = 0.01; base.angvel[2] = -0.015;
    sys = cd_model_add_system(m, &base, err);
    if (sys < 0) goto fail;
    for (j = 0; j < NJ; j++) {
        cd_link_desc l = rod(j == 0 ? m->sys_body_adr[sys] : link[j - 1], j == 0 ? mount : elbow, j == 0 ? z : y,
                             4.0, 0.5, 0.3 * (j + 1));
        cd_actuator_desc a = cd_actuator_desc_default();
        double ratio = 1.0;
        link[j] = cd_model_add_link(m, sys, &l, err);
        if (link[j] < 0) goto fail;
        a.type = j == 0 ? CD_ACT_STEPS : CD_ACT_PD;
        if (j == 0) {
            a.tbl_t = steps_t;
            a.tbl_v = steps_v;
            a.ntbl = 3;
        } else {
            a.kp = 20.0;
            a.kd = 2.0;
            a.qref = 0.0;
        }
        a.ntrn = 1;
        a.trn_body = &link[j];
        a.trn_ratio = &ratio;
        if (cd_model_add_actuator(m, &a, err) < 0) goto fail;
    }
    m->opt.stepper = CD_STEP_RK8PD;
    m->opt.rtol = 1e-9;
    m->opt.atol = 1e-11;
    if (cd_model_finalize(m, err) != CD_OK) goto fail;
    return m;
fail:
    cd_model_free(m);
    return NULL;
}

/* the control callback: a feed-forward on the last joint, from (t, state) */
static void control(const cd_model *m, cd_data *d, void *user)
{
    (void)user;
    d->ctrl[m->nu - 1] = 0.2 * cd_joint_q(m, d, m->nbody - 1) * (d->t < 0.1 ? 1.0 : -1.0);
}

static void *run(void *arg)
{
    job *J = (job *)arg;
    const cd_model *m = J->m;
    cd_error e;
    cd_data *d = cd_data_create(m, 0, &e);
    double *ck = NULL;
    long k;
    J->ok = 0;
    if (!d) {
        snprintf(J->msg, sizeof J->msg, "cd_data_create: %s", e.msg);
        return NULL;
    }
    cd_data_set_control(d, control, NULL);
    ck = malloc(cd_state_size(m) * sizeof *ck);
    if (!ck) goto out;
    if (cd_sim_advance(m, d, 0.15, NULL, NULL, &e) != CD_OK) {
        snprintf(J->msg, sizeof J->msg, "cd_sim_advance: %s", e.msg);
        goto out;
    }
    cd_state_get(m, d, ck);
    if (cd_sim_advance(m, d, 0.25, NULL, NULL, &e) != CD_OK || cd_state_set(m, d, ck, &e) != CD_OK ||
        cd_sim_advance(m, d, 0.25, NULL, NULL, &e) != CD_OK) {
        snprintf(J->msg, sizeof J->msg, "advance/restore: %s", e.msg);
        goto out;
    }
    for (k = 0; k < 200; k++)
        if (cd_step(m, d, 1e-3, &e) != CD_OK) {
            snprintf(J->msg, sizeof J->msg, "cd_step: %s", e.msg);
            goto out;
        }
    memcpy(J->y_end, d->y, (size_t)m->ny * sizeof(double));
    J->t_end = d->t;
    J->nevents = d->ev_count;
    J->ok = 1;
out:
    free(ck);
    cd_data_free(d);
    return NULL;
}

int main(void)
{
    cd_error e;
    cd_model *m;
    job ref, th[2];
    pthread_t tid[2];
    int i, rc = 0;
    gsl_set_error_handler_off(); /* the program's choice (the library never changes it) */
    m = build(&e);
    if (!m) {
        fprintf(stderr, "two_threads: building the model: %s\n", e.msg);
        return 1;
    }
    memset(&ref, 0, sizeof ref);
    ref.m = m;
    ref.y_end = calloc((size_t)m->ny, sizeof(double));
    run(&ref); /* the reference, alone */
    if (!ref.ok) {
        fprintf(stderr, "two_threads: reference run: %s\n", ref.msg);
        return 1;
    }
    for (i = 0; i < 2; i++) {
        memset(&th[i], 0, sizeof th[i]);
        th[i].m = m;
        th[i].y_end = calloc((size_t)m->ny, sizeof(double));
        if (pthread_create(&tid[i], NULL, run, &th[i]) != 0) {
            fprintf(stderr, "two_threads: pthread_create failed\n");
            return 1;
        }
    }
    for (i = 0; i < 2; i++) pthread_join(tid[i], NULL);
    for (i = 0; i < 2; i++) {
        if (!th[i].ok) {
            fprintf(stderr, "two_threads: thread %d: %s\n", i, th[i].msg);
            rc = 1;
        } else if (th[i].t_end != ref.t_end || th[i].nevents != ref.nevents ||
                   memcmp(th[i].y_end, ref.y_end, (size_t)m->ny * sizeof(double)) != 0) {
            fprintf(stderr, "two_threads: thread %d ends elsewhere than the run alone\n", i);
            rc = 1;
        }
        free(th[i].y_end);
    }
    if (rc == 0)
        printf("two_threads: 2 threads on one model, t = %.3f s, %ld events each, bit-identical to the run alone\n",
               ref.t_end, ref.nevents);
    free(ref.y_end);
    cd_model_free(m);
    return rc;
}
