/* Shared by the stepper suites (test_ros4.c, test_gauss4.c): a smooth
 * non-autonomous nonlinear system with a known solution for measuring a
 * stepper's order, a very stiff linear one, and a scenario run (the Fig. 5 grasp's to compare a
 * stepper with a tight rk8pd reference; test_auto.c's to compare auto with its two steppers). */
#ifndef CAPDYN_TESTS_STEPPER_UTIL_H
#define CAPDYN_TESTS_STEPPER_UTIL_H

#include <criterion/criterion.h>
#include <capdyn/capdyn.h>
#include <capdyn/io.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static inline const char *step_root(void)
{
    const char *r = getenv("CAPDYN_ROOT");
    return r && *r ? r : ".";
}

/* The smooth system with the known solution u1 = 2 + sin t, u2 = exp(-t/2):
 *   y1' = -y1^2 + y2 + g1(t),  y2' = -y1 y2 + g2(t),
 *   g1 = cos t + u1^2 - u2,    g2 = -u2/2 + u1 u2.
 * smooth_j gives its exact Jacobian and df/dt. */
static inline void exact(double t, double *u) { u[0] = 2.0 + sin(t); u[1] = exp(-0.5 * t); }

static inline int smooth_f(double t, const double y[], double f[], void *p)
{
    double u[2];
    (void)p;
    exact(t, u);
    f[0] = -y[0] * y[0] + y[1] + cos(t) + u[0] * u[0] - u[1];
    f[1] = -y[0] * y[1] - 0.5 * u[1] + u[0] * u[1];
    return GSL_SUCCESS;
}

static inline int smooth_j(double t, const double y[], double *J, double dfdt[], void *p)
{
    double u[2];
    (void)p;
    exact(t, u);
    J[0] = -2.0 * y[0]; J[1] = 1.0;
    J[2] = -y[1];       J[3] = -y[0];
    dfdt[0] = -sin(t) + 2.0 * u[0] * cos(t) + 0.5 * u[1];
    dfdt[1] = 0.25 * u[1] + cos(t) * u[1] - 0.5 * u[0] * u[1];
    return GSL_SUCCESS;
}

/* The Prothero-Robinson-like stiff linear problem y' = -1e6 (y - cos t), its
 * exact Jacobian and df/dt, the smooth solution through it (stiff_exact: the
 * one every start relaxes to within ~1e-6 s), and a zero "Jacobian" that
 * makes a Newton iteration a fixed-point one (to force its failure). */
static inline int stiff_f(double t, const double y[], double f[], void *p)
{
    (void)p;
    f[0] = -1e6 * (y[0] - cos(t));
    return GSL_SUCCESS;
}

static inline int stiff_j(double t, const double y[], double *J, double dfdt[], void *p)
{
    (void)p;
    (void)y;
    J[0] = -1e6;
    dfdt[0] = -1e6 * sin(t);
    return GSL_SUCCESS;
}

static inline double stiff_exact(double t)
{
    const double l = 1e6;
    return (l * l * cos(t) + l * sin(t)) / (1.0 + l * l);
}

static inline int zero_j(double t, const double y[], double *J, double dfdt[], void *p)
{
    (void)t;
    (void)y;
    (void)p;
    J[0] = 0;
    dfdt[0] = 0;
    return GSL_SUCCESS;
}

/* What a scenario run ends with: every system's coordinates, the slot
 * modes, the counts, the events by kind, auto's switches. */
typedef struct {
    double q[256];
    int modes[256], nq, ns;
    long nrhs, njac, nev, nsteps, kinds[8], nsw_stiff, nsw_explicit;
} outcome;

/* scenarios/<file> with the overrides ov[0..nov), its control installed if
 * it has one, run to t_end (<= 0: the scenario's duration) */
static inline void run_scenario(const char *file, const char **ov, int nov, double t_end, outcome *o)
{
    char path[1024];
    cd_error e;
    cd_scenario *sc;
    cd_data *d;
    cd_ctrl *ctl = NULL;
    const cd_model *m;
    int i, s;
    snprintf(path, sizeof path, "%s/scenarios/%s", step_root(), file);
    sc = cd_scenario_load(path, ov, nov, &e);
    cr_assert(sc, "%s: %s", file, e.msg);
    m = sc->model;
    d = cd_data_create(m, sc->event_capacity, &e);
    cr_assert(d, "%s", e.msg);
    if (sc->control) {
        ctl = cd_ctrl_create(m, sc->control, &e);
        cr_assert(ctl, "%s", e.msg);
        cd_ctrl_install(ctl, d);
    }
    if (!(t_end > 0)) t_end = sc->duration;
    cr_assert_eq(cd_sim_advance(m, d, t_end, NULL, NULL, &e), CD_OK, "%s with %s: %s", file, nov ? ov[0] : "", e.msg);
    memset(o, 0, sizeof *o);
    for (s = 0; s < m->nsys; s++) { /* the coordinates of every system (positions, quaternions, joints) */
        int ya = m->sys_y_adr[s], nj = m->sys_nbody[s] - 1;
        int np = m->sys_base_type[s] == CD_BASE_FREE ? 7 + nj : nj;
        for (i = 0; i < np && o->nq < 256; i++) o->q[o->nq++] = d->y[ya + i];
    }
    o->ns = m->nslot < 256 ? m->nslot : 256;
    for (i = 0; i < o->ns; i++) o->modes[i] = d->slot_mode[i];
    for (i = 0; i < (d->ev_count < d->ev_cap ? d->ev_count : d->ev_cap); i++) {
        const cd_event *ev = cd_data_event(d, i);
        if (ev && ev->kind >= 0 && ev->kind < 8) o->kinds[ev->kind]++;
    }
    o->nrhs = d->stats.nrhs;
    o->njac = d->stats.njac;
    o->nev = d->stats.nevents;
    o->nsteps = d->stats.nsteps;
    o->nsw_stiff = d->stats.nswitch_stiff;
    o->nsw_explicit = d->stats.nswitch_explicit;
    cd_ctrl_free(ctl);
    cd_data_free(d);
    cd_scenario_free(sc);
}

/* The Fig. 5 envelope grasp to t_end with the overrides integ and rtol (and
 * h_max 0.05) */
static inline void run_fig5(const char *integ, const char *rtol, double t_end, outcome *o)
{
    const char *ov[3] = {integ, rtol, "simulation.h_max=0.05"};
    run_scenario("paper_fig5_envelope_grasp.toml", ov, 3, t_end, o);
}

#endif
