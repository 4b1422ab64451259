/* control_loop_trace.c -- the trajectory of examples/control_loop.c, for
 * python/tests/test_control_loop.py (bit-identity of the Python loop).
 *
 * It includes the example itself (its main renamed), so that the model
 * (build_model), the controller (control_tick) and the loop are the
 * example's own code, not a copy: it runs the example's ticks 0 .. T_END
 * RATE_HZ - 1 as the example's first run does (cd_step with the
 * fixed-step RK4, opt.max_evals = MAX_EVALS) and writes, after start-up
 * and after every tick, t and the state y as raw doubles to stdout
 * (1 + ny doubles per row), then the ctrl of every tick. Exit 1 on a
 * failure. Built and run by the test (cc, the shared library). */
#define main control_loop_example_main
#include "../../examples/control_loop.c"
#undef main

static int put(const double *v, size_t n)
{
    return fwrite(v, sizeof *v, n, stdout) == n ? 0 : -1;
}

int main(void)
{
    cd_error err;
    cd_model *m;
    cd_data *d;
    arm_ids ids;
    controller ctl;
    const double wn = 2 * 3.14159265358979323846 * 1.5; /* as the example's main */
    const long n_steps = (long)(T_END * RATE_HZ + 0.5);
    long k;
    (void)control_loop_example_main; /* the example's own main is not run */
    memset(&err, 0, sizeof err);
    ctl.q0[0] = 0.0; ctl.q0[1] = 0.3; ctl.q0[2] = -0.6;
    ctl.qT[0] = 0.8; ctl.qT[1] = -0.4; ctl.qT[2] = 1.0;
    ctl.kp = wn * wn;
    ctl.kd = 2 * wn;
    m = build_model(ctl.q0, &ids, &err);
    if (!m) { fprintf(stderr, "trace: model: %s\n", err.msg); return 1; }
    m->opt.stepper = CD_STEP_RK4_FIXED;
    d = cd_data_create(m, 64, &err);
    if (!d) { fprintf(stderr, "trace: data: %s\n", err.msg); cd_model_free(m); return 1; }
    d->opt.max_evals = MAX_EVALS;
    if (put(&d->t, 1) || put(d->y, (size_t)m->ny)) return 1;
    for (k = 0; k < n_steps; k++) {
        if (control_tick(m, d, &ctl, &ids) != 0) { fprintf(stderr, "trace: controller failed\n"); return 1; }
        if (cd_step(m, d, 1.0 / RATE_HZ, &err) != CD_OK) { fprintf(stderr, "trace: %s\n", err.msg); return 1; }
        if (put(&d->t, 1) || put(d->y, (size_t)m->ny)) return 1;
    }
    cd_data_free(d);
    cd_model_free(m);
    return fflush(stdout) == 0 ? 0 : 1;
}
