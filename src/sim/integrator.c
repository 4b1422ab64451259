/* The event-driven integrator.
 *
 * GSL odeiv2 is driven one accepted step at a time (gsl_odeiv2_evolve_apply)
 * with the step, control and evolve objects of a gsl_odeiv2_driver allocated
 * once at cd_data_create (the driver object is needed by msbdf). After every
 * accepted step the switching functions of all slots are evaluated; if any
 * changed sign, the crossing is located by Illinois (modified regula falsi)
 * iterations, each one a single step of a one-step "locator" stepper (rk8pd;
 * classic RK4 in fixed-step mode) of trial length tau from the saved start state, so
 * the located state is the integrator's own solution, not an interpolant.
 * The bracket is shrunk to event_tol; the state lands on the far end (already
 * on the new side), the modes switch, and the stepper is reset: inside a
 * segment the rhs is smooth and the adaptive control stays honest.
 *
 * Chattering guard: a slot may switch at most twice in quick succession
 * (each switch within `dwell` of the previous one: onset followed by an
 * immediate slip at one instant, or two flips landing event_tol apart);
 * after that its switching functions are ignored until `dwell` seconds have
 * passed since its last switch, and steps
 * are clamped to end when a dwell expires, where the slot is re-checked and
 * switched at once if needed (counted in stats.nwarn_dwell).
 *
 * Quaternions are renormalised after every accepted step and every landing
 * (the rhs also uses q/|q|), which keeps |q| - 1 at round-off. */
#include "capdyn/sim.h"
#include "../math/cd_math.h"
#include "../contact/contact.h"
#include "integ.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    const cd_model *m;
    cd_data *d;
    gsl_odeiv2_system sys;
    gsl_odeiv2_driver *drv;   /* adaptive steppers (NULL in fixed mode) */
    gsl_odeiv2_step *loc;     /* rk8pd one-step locator (adaptive modes; NULL in fixed mode) */
    double *y0, *ylo, *yhi, *yerr, *fd_f0, *fd_y;
    double *k1, *k2, *k3, *k4, *ytmp; /* classic RK4 (fixed-step mode) */
    int *nswitch_now;         /* (nslot) switches within `dwell` of the slot's last one */
    double h;                 /* next trial step */
    int fixed;
} cd_integ;

static int rhs(double t, const double y[], double dydt[], void *params)
{
    cd_integ *I = (cd_integ *)params;
    cd_data *d = I->d;
    double *save = d->y, tsave = d->t;
    cd_status st;
    d->y = (double *)y;
    d->t = t;
    st = cd_forward(I->m, d);
    d->y = save;
    d->t = tsave;
    d->stats.nrhs++;
    if (st != CD_OK) return GSL_EBADFUNC;
    memcpy(dydt, d->ydot, (size_t)I->m->ny * sizeof(double));
    return GSL_SUCCESS;
}

/* Finite-difference Jacobian for the implicit steppers (rk4imp, msbdf). */
static int jac(double t, const double y[], double *dfdy, double dfdt[], void *params)
{
    cd_integ *I = (cd_integ *)params;
    int n = I->m->ny, i, j;
    double eps = I->m->opt.fd_eps;
    if (rhs(t, y, I->fd_f0, params) != GSL_SUCCESS) return GSL_EBADFUNC;
    memcpy(I->fd_y, y, (size_t)n * sizeof(double));
    for (j = 0; j < n; j++) {
        double h = eps * (fabs(y[j]) > 1.0 ? fabs(y[j]) : 1.0);
        I->fd_y[j] = y[j] + h;
        if (rhs(t, I->fd_y, I->yerr, params) != GSL_SUCCESS) return GSL_EBADFUNC;
        for (i = 0; i < n; i++) dfdy[i * n + j] = (I->yerr[i] - I->fd_f0[i]) / h;
        I->fd_y[j] = y[j];
    }
    {
        double h = eps * (fabs(t) > 1.0 ? fabs(t) : 1.0);
        if (rhs(t + h, y, I->yerr, params) != GSL_SUCCESS) return GSL_EBADFUNC;
        for (i = 0; i < n; i++) dfdt[i] = (I->yerr[i] - I->fd_f0[i]) / h;
    }
    return GSL_SUCCESS;
}

void cd_integ_free(void *p)
{
    cd_integ *I = (cd_integ *)p;
    if (!I) return;
    if (I->drv) gsl_odeiv2_driver_free(I->drv);
    if (I->loc) gsl_odeiv2_step_free(I->loc);
    free(I->y0); free(I->ylo); free(I->yhi); free(I->yerr); free(I->fd_f0); free(I->fd_y);
    free(I->nswitch_now);
    free(I->k1); free(I->k2); free(I->k3); free(I->k4); free(I->ytmp);
    free(I);
}

void *cd_integ_create(const cd_model *m, cd_data *d, cd_error *err)
{
    cd_integ *I = calloc(1, sizeof *I);
    const gsl_odeiv2_step_type *T = NULL;
    size_t n = (size_t)m->ny;
    int ns = m->nslot ? m->nslot : 1;
    if (!I) goto nomem;
    I->m = m;
    I->d = d;
    I->sys.function = rhs;
    I->sys.jacobian = jac;
    I->sys.dimension = n;
    I->sys.params = I;
    I->fixed = m->opt.stepper == CD_STEP_RK4_FIXED;
    switch (m->opt.stepper) {
    case CD_STEP_RKF45: T = gsl_odeiv2_step_rkf45; break;
    case CD_STEP_RKCK: T = gsl_odeiv2_step_rkck; break;
    case CD_STEP_RK8PD: T = gsl_odeiv2_step_rk8pd; break;
    case CD_STEP_RK4IMP: T = gsl_odeiv2_step_rk4imp; break;
    case CD_STEP_MSBDF: T = gsl_odeiv2_step_msbdf; break;
    default: T = NULL; break;
    }
    if (n == 0) n = 1;
    if (!I->fixed) {
        I->drv = gsl_odeiv2_driver_alloc_standard_new(&I->sys, T, m->opt.h_init, m->opt.atol,
                                                      m->opt.rtol, 1.0, 1.0);
        if (!I->drv) goto nomem;
    }
    if (I->fixed) {
        /* GSL's rk4 stepper, asked for an error estimate, takes a full step
         * and two half steps and returns the latter (11 evaluations for an
         * h/2 result): the embedding mode wants the classic 4-stage RK4. */
        I->k1 = calloc(n, sizeof(double)); I->k2 = calloc(n, sizeof(double));
        I->k3 = calloc(n, sizeof(double)); I->k4 = calloc(n, sizeof(double));
        I->ytmp = calloc(n, sizeof(double));
        if (!I->k1 || !I->k2 || !I->k3 || !I->k4 || !I->ytmp) goto nomem;
    } else {
        I->loc = gsl_odeiv2_step_alloc(gsl_odeiv2_step_rk8pd, n);
        if (!I->loc) goto nomem;
    }
    I->y0 = calloc(n, sizeof(double)); I->ylo = calloc(n, sizeof(double));
    I->yhi = calloc(n, sizeof(double)); I->yerr = calloc(n, sizeof(double));
    I->fd_f0 = calloc(n, sizeof(double)); I->fd_y = calloc(n, sizeof(double));
    I->nswitch_now = calloc((size_t)ns, sizeof(int));
    if (!I->y0 || !I->ylo || !I->yhi || !I->yerr || !I->fd_f0 || !I->fd_y || !I->nswitch_now)
        goto nomem;
    return I;
nomem:
    cd_integ_free(I);
    if (err) { err->status = CD_ENOMEM; snprintf(err->msg, sizeof err->msg, "out of memory creating the integrator"); }
    return NULL;
}

void cd_integ_reset(const cd_model *m, cd_data *d)
{
    cd_integ *I = (cd_integ *)d->integ;
    I->h = I->fixed ? m->opt.h_fixed : m->opt.h_init;
    if (I->drv) {
        gsl_odeiv2_driver_reset(I->drv);
    }
    if (I->loc) gsl_odeiv2_step_reset(I->loc);
    memset(I->nswitch_now, 0, (size_t)(m->nslot ? m->nslot : 1) * sizeof(int));
}

static void renormalize(const cd_model *m, cd_data *d)
{
    int s;
    for (s = 0; s < m->nsys; s++) {
        cd_sys_state x = cd_state_of(m, d, s);
        double n;
        if (!x.quat) continue;
        n = sqrt(x.quat[0] * x.quat[0] + x.quat[1] * x.quat[1] + x.quat[2] * x.quat[2] + x.quat[3] * x.quat[3]);
        if (n > 0) { x.quat[0] /= n; x.quat[1] /= n; x.quat[2] /= n; x.quat[3] /= n; }
        d->stats.nrenorm++;
    }
}

static int in_dwell(const cd_model *m, const cd_data *d, const cd_integ *I, int k)
{
    return I->nswitch_now[k] >= 2 && d->t - d->slot_tswitch[k] < m->opt.dwell;
}

/* min over active slots of the switching functions at d's current state
 * (after cd_forward); the slot and function achieving it in *which. */
static double gmin(const cd_model *m, const cd_data *d, const cd_integ *I, int use_dwell, int *which)
{
    int k;
    double best = HUGE_VAL;
    if (which) *which = -1;
    for (k = 0; k < m->nslot; k++) {
        double gn, gf;
        if (use_dwell && in_dwell(m, d, I, k)) continue;
        if (d->slot_geomfail[k]) continue;
        cd_contact_switch(m, d, k, &gn, &gf);
        if (gn < best) { best = gn; if (which) *which = 2 * k; }
        if (gf < best) { best = gf; if (which) *which = 2 * k + 1; }
    }
    return best;
}

static void log_event(const cd_model *m, cd_data *d, int k, int kind, int from, int to)
{
    cd_event *e = &d->ev[d->ev_count % d->ev_cap];
    e->t = d->t;
    e->kind = kind;
    e->slot = k;
    e->body_a = k >= 0 ? m->cp_body[m->slot_cp[k]] : -1;
    e->body_b = k >= 0 ? m->shape_body[m->slot_shape[k]] : -1;
    e->mode_from = from;
    e->mode_to = to;
    e->x = k >= 0 ? d->slot_x[k] : 0;
    e->fn = k >= 0 ? d->slot_fn[k] : 0;
    e->ft = k >= 0 ? cd_v3_norm(d->slot_ft + 3 * k) : 0;
    d->ev_count++;
    d->stats.nevents++;
}

static void any_tangent(double t[3], const double n[3])
{
    double a[3] = {1, 0, 0};
    if (fabs(n[0]) > 0.9) cd_v3_set(a, 0, 1, 0);
    cd_v3_cross(t, n, a);
    cd_v3_normalize(t);
}

/* Applies the transition that slot k's switching functions call for, at the
 * current (landed) state, after cd_forward. Returns 1 if the mode changed. */
/* Slot k's switching functions (cd_contact_switch). With forgive, zero-time
 * re-checks pardon round-off in the friction functions (e.g. slip -> stick
 * with mu_s = mu_k lands exactly on the cone and must not flip straight back). */
static void switch_functions(const cd_model *m, const cd_data *d, int k, int forgive, double *gn, double *gf)
{
    int mode = d->slot_mode[k];
    cd_contact_switch(m, d, k, gn, gf);
    if (forgive && mode == CD_MODE_STICK && *gf >= -1e-9 * m->law[m->slot_law[k]].mu_s * d->slot_fn[k]) *gf = 0;
    if (forgive && mode == CD_MODE_SLIP && *gf >= -1e-3 * m->opt.v_reg) *gf = 0;
}

static int switch_slot(const cd_model *m, cd_data *d, int k, int forgive)
{
    const cd_contact_law *L = &m->law[m->slot_law[k]];
    double gn, gf, *z = d->y + m->ny_slot_adr + 3 * k;
    const double *n = d->slot_normal + 3 * k, *ft = d->slot_ft + 3 * k, *vt = d->slot_vt + 3 * k;
    int from = d->slot_mode[k], to = from, kind = -1;
    switch_functions(m, d, k, forgive, &gn, &gf);
    if (gn < 0) {
        if (from == CD_MODE_OPEN) { to = CD_MODE_STICK; kind = CD_EV_ONSET; }
        else { to = CD_MODE_OPEN; kind = CD_EV_SEPARATION; }
        cd_v3_zero(z);
    } else if (gf < 0 && from == CD_MODE_STICK) {
        double nf = cd_v3_norm(ft), *s = d->slot_dir + 3 * k;
        to = CD_MODE_SLIP;
        kind = CD_EV_STICK_SLIP;
        /* the slip goes where the stick spring is pulled: against f_t */
        if (nf > 0) cd_v3_scale(s, ft, -1.0 / nf);
        else if (cd_v3_norm(vt) > 0) { cd_v3_copy(s, vt); cd_v3_normalize(s); }
        else any_tangent(s, n);
    } else if (gf < 0 && from == CD_MODE_SLIP) {
        const double *vs = d->slot_va + 3 * k;
        double nv = cd_v3_norm(vs);
        if (nv > 100.0 * m->opt.v_reg) {
            /* 3-D slip that turned past 90 deg at speed: re-anchor, keep slipping */
            kind = CD_EV_SLIP_TURN;
            cd_v3_scale(d->slot_dir + 3 * k, vs, 1.0 / nv);
        } else {
            int i;
            double zw[3];
            to = CD_MODE_STICK;
            kind = CD_EV_SLIP_STICK;
            /* anchor so that f_t is continuous: -(K_t z + D_t v_t) = f_t,
             * stored in the axes of the shape's body (see contact.c) */
            for (i = 0; i < 3; i++) zw[i] = -(ft[i] + L->Dt * vt[i]) / L->Kt;
            cd_m3_tmulv(z, d->body_R + 9 * m->shape_body[m->slot_shape[k]], zw);
        }
    }
    if (kind < 0) return 0;
    log_event(m, d, k, kind, from, to);
    d->slot_mode[k] = to;
    d->slot_tswitch[k] = d->t;
    return 1;
}

/* switch_slot under the chattering guard's bookkeeping: switches more than
 * `dwell` apart start a new count; the second within the window holds the
 * slot (its forces clipped, its functions unwatched) until the window ends. */
static int counted_switch(const cd_model *m, cd_data *d, cd_integ *I, int k, int forgive)
{
    if (d->t - d->slot_tswitch[k] >= m->opt.dwell) I->nswitch_now[k] = 0;
    if (!switch_slot(m, d, k, forgive)) return 0;
    if (++I->nswitch_now[k] >= 2) d->slot_held[k] = 1;
    return 1;
}

/* Switch every slot whose functions are negative at the current state, with
 * zero-time cascades (e.g. onset -> slip) bounded by the chattering guard. */
static cd_status settle_modes(const cd_model *m, cd_data *d, cd_integ *I, int *changed)
{
    int round, k, any;
    cd_status st;
    *changed = 0;
    for (k = 0; k < m->nslot; k++) /* guard windows that have passed */
        if (d->slot_held[k] && d->t - d->slot_tswitch[k] >= m->opt.dwell) d->slot_held[k] = 0;
    for (round = 0; round < 4; round++) {
        st = cd_forward(m, d);
        d->stats.nrhs++;
        if (st != CD_OK) return st;
        any = 0;
        for (k = 0; k < m->nslot; k++) {
            double gn, gf;
            if (d->slot_geomfail[k]) continue;
            switch_functions(m, d, k, 1, &gn, &gf);
            if (!(gn < 0 || gf < 0)) continue;
            if (in_dwell(m, d, I, k)) { d->stats.nwarn_dwell++; continue; }
            if (counted_switch(m, d, I, k, 1)) any = 1;
        }
        if (!any) break;
        *changed = 1;
    }
    if (*changed) {
        st = cd_forward(m, d);
        d->stats.nrhs++;
        if (st != CD_OK) return st;
    }
    return CD_OK;
}

void cd_integ_initial_modes(const cd_model *m, cd_data *d)
{
    int k;
    if (cd_forward(m, d) != CD_OK) return;
    for (k = 0; k < m->nslot; k++)
        if (!d->slot_geomfail[k] && d->slot_x[k] > 0) {
            d->slot_mode[k] = CD_MODE_STICK;
            d->slot_tswitch[k] = d->t;
        }
    (void)cd_forward(m, d);
}

/* Classic RK4, y advanced in place by h: 4 evaluations, no allocation. */
static int rk4_step(cd_integ *I, double t, double h, double *y)
{
    size_t n = (size_t)I->m->ny, i;
    if (rhs(t, y, I->k1, I) != GSL_SUCCESS) return GSL_EBADFUNC;
    for (i = 0; i < n; i++) I->ytmp[i] = y[i] + 0.5 * h * I->k1[i];
    if (rhs(t + 0.5 * h, I->ytmp, I->k2, I) != GSL_SUCCESS) return GSL_EBADFUNC;
    for (i = 0; i < n; i++) I->ytmp[i] = y[i] + 0.5 * h * I->k2[i];
    if (rhs(t + 0.5 * h, I->ytmp, I->k3, I) != GSL_SUCCESS) return GSL_EBADFUNC;
    for (i = 0; i < n; i++) I->ytmp[i] = y[i] + h * I->k3[i];
    if (rhs(t + h, I->ytmp, I->k4, I) != GSL_SUCCESS) return GSL_EBADFUNC;
    for (i = 0; i < n; i++) y[i] += h / 6.0 * (I->k1[i] + 2.0 * I->k2[i] + 2.0 * I->k3[i] + I->k4[i]);
    return GSL_SUCCESS;
}

/* One step of the one-step method of this run (rk8pd, or classic RK4 in
 * fixed-step mode) of length h from (t, y), y updated in place. */
static int one_step(cd_integ *I, double t, double h, double *y)
{
    if (I->fixed) return rk4_step(I, t, h, y);
    gsl_odeiv2_step_reset(I->loc);
    return gsl_odeiv2_step_apply(I->loc, t, h, y, I->yerr, NULL, NULL, &I->sys);
}

/* One locator step of length tau from (t0, y0) into y; then cd_forward. */
static cd_status trial(const cd_model *m, cd_data *d, cd_integ *I, double t0, double tau, double *y)
{
    int st;
    memcpy(y, I->y0, (size_t)m->ny * sizeof(double));
    st = one_step(I, t0, tau, y);
    d->stats.nlocate_steps++;
    if (st != GSL_SUCCESS) return CD_ENUMERIC;
    d->y = y;
    d->t = t0 + tau;
    st = cd_forward(m, d);
    d->stats.nrhs++;
    return st == CD_OK ? CD_OK : CD_ENUMERIC;
}

/* Back to the start of the step after a failure: d holds the last good
 * state (y0 at t0) with its outputs evaluated, as cd_sim_advance promises. */
static void restore_start(const cd_model *m, cd_data *d, const cd_integ *I, double t0, double *ystate)
{
    d->y = ystate;
    memcpy(d->y, I->y0, (size_t)m->ny * sizeof(double));
    d->t = t0;
    (void)cd_forward(m, d);
}

/* Locate the first zero of gmin in (t0, t1] given gmin(t0) >= 0 > gmin(t1),
 * and leave d at the upper end of the final bracket (on the new side). */
static cd_status locate(const cd_model *m, cd_data *d, cd_integ *I, double t0, double t1, double g_hi,
                        int *trigger)
{
    double h = t1 - t0, lo = 0.0, hi = h, glo, ghi = g_hi, *ystate = d->y;
    int side = 0, it;
    cd_status st;
    /* g at the start (modes unchanged) */
    memcpy(I->yhi, d->y, (size_t)m->ny * sizeof(double));
    d->y = I->y0;
    d->t = t0;
    st = cd_forward(m, d);
    if (st != CD_OK) { restore_start(m, d, I, t0, ystate); return st; }
    glo = gmin(m, d, I, 1, NULL);
    if (!(glo > 0)) glo = 0.0;
    for (it = 0; it < 200 && hi - lo > m->opt.event_tol; it++) {
        double tau, g, w = hi - lo;
        /* Illinois: secant on the bracket, the stale end's value halved */
        tau = (glo - ghi) != 0 ? lo + glo * w / (glo - ghi) : lo + 0.5 * w;
        if (!(tau > lo + 0.01 * w && tau < hi - 0.01 * w)) tau = lo + 0.5 * w;
        if (it % 4 == 3) tau = lo + 0.5 * w; /* a bisection now and then bounds the worst case */
        st = trial(m, d, I, t0, tau, I->ylo);
        if (st != CD_OK) { restore_start(m, d, I, t0, ystate); return st; }
        g = gmin(m, d, I, 1, NULL);
        if (g < 0) {
            hi = tau; ghi = g;
            memcpy(I->yhi, I->ylo, (size_t)m->ny * sizeof(double));
            if (side == -1) glo *= 0.5;
            side = -1;
        } else {
            lo = tau; glo = g;
            if (side == 1) ghi *= 0.5;
            side = 1;
        }
    }
    /* land at the upper end (exactly at the step's end if the bracket never moved) */
    d->y = ystate;
    memcpy(d->y, I->yhi, (size_t)m->ny * sizeof(double));
    d->t = hi == h ? t1 : t0 + hi;
    st = cd_forward(m, d);
    d->stats.nrhs++;
    if (st != CD_OK) { restore_start(m, d, I, t0, ystate); return st; }
    (void)gmin(m, d, I, 1, trigger);
    return CD_OK;
}

static double next_dwell_end(const cd_model *m, const cd_data *d, const cd_integ *I)
{
    int k;
    double t = HUGE_VAL;
    for (k = 0; k < m->nslot; k++)
        if (I->nswitch_now[k] >= 2) {
            double e = d->slot_tswitch[k] + m->opt.dwell;
            if (e > d->t && e < t) t = e;
        }
    return t;
}

static void seterr(cd_error *err, cd_status st, const char *msg, double t)
{
    if (!err) return;
    err->status = st;
    snprintf(err->msg, sizeof err->msg, "%s at t = %.9g s", msg, t);
}

cd_status cd_sim_advance(const cd_model *m, cd_data *d, double t_end, cd_step_callback cb,
                         void *user, cd_error *err)
{
    cd_integ *I = (cd_integ *)d->integ;
    long attempts = 0;
    int changed, need_settle = 1;
    cd_status st;
    if (!(t_end >= d->t) || !isfinite(t_end)) {
        seterr(err, CD_EINVAL, "t_end must be finite and not before the current time", d->t);
        return CD_EINVAL;
    }
    while (d->t < t_end) {
        double t0 = d->t, t1 = t_end, tdw, g1;
        int status, at_dwell_end;
        /* modes are re-checked on entry (the caller may have edited y) and
         * where a dwell expired; after an ordinary step the end-of-step
         * evaluation below has already shown them consistent */
        if (need_settle) {
            st = settle_modes(m, d, I, &changed);
            if (st != CD_OK) { seterr(err, st, "non-finite state or singular mass matrix", d->t); return st; }
            need_settle = 0;
            if (changed) {
                if (I->drv) { gsl_odeiv2_evolve_reset(I->drv->e); gsl_odeiv2_step_reset(I->drv->s); }
                if (cb && cb(m, d, user)) { seterr(err, CD_EINTERRUPT, "stopped by the caller", d->t); return CD_EINTERRUPT; }
            }
        }
        tdw = next_dwell_end(m, d, I);
        at_dwell_end = tdw <= t1;
        if (at_dwell_end) t1 = tdw;
        memcpy(I->y0, d->y, (size_t)m->ny * sizeof(double));
        if (I->fixed) {
            double h = I->h < t1 - t0 ? I->h : t1 - t0;
            status = one_step(I, t0, h, d->y);
            if (status == GSL_SUCCESS) d->t = (t1 - t0 <= I->h) ? t1 : t0 + h;
            attempts++;
        } else {
            double t = t0, hmax = m->opt.h_max;
            long before = (long)I->drv->e->failed_steps;
            if (hmax > 0 && I->h > hmax) I->h = hmax;
            /* a step that would end within round-off of t1 would leave a sliver
             * step of ~1e-17 s: aim just past t1 so GSL lands exactly on it */
            if (I->h >= (t1 - t0) * (1.0 - 1e-12) && I->h < (t1 - t0) * (1.0 + 1e-9)) I->h = (t1 - t0) * (1.0 + 1e-9);
            status = gsl_odeiv2_evolve_apply(I->drv->e, I->drv->c, I->drv->s, &I->sys, &t, t1, &I->h, d->y);
            d->stats.nrejected += (long)I->drv->e->failed_steps - before;
            attempts += 1 + (long)I->drv->e->failed_steps - before;
            if (status == GSL_SUCCESS) d->t = t;
        }
        if (status != GSL_SUCCESS) {
            restore_start(m, d, I, t0, d->y);
            if (status == GSL_EBADFUNC) {
                seterr(err, CD_ENUMERIC, "right-hand side produced a non-finite value", t0);
                return CD_ENUMERIC;
            }
            seterr(err, CD_ESTALL, "integrator step failed", t0);
            return CD_ESTALL;
        }
        renormalize(m, d);
        d->stats.nsteps++;
        d->stats.h_last = d->t - t0;
        if (d->stats.h_last < d->stats.h_min_seen && d->t < t1) d->stats.h_min_seen = d->stats.h_last;
        if (d->stats.h_last > d->stats.h_max_seen) d->stats.h_max_seen = d->stats.h_last;
        /* evaluate the end state: outputs and switching functions */
        st = cd_forward(m, d);
        d->stats.nrhs++;
        if (st != CD_OK) {
            restore_start(m, d, I, t0, d->y);
            seterr(err, CD_ENUMERIC, "non-finite state after a step", t0);
            return CD_ENUMERIC;
        }
        g1 = gmin(m, d, I, 1, NULL);
        if (at_dwell_end && d->t == t1) need_settle = 1;
        if (g1 < 0) {
            int trig = -1;
            st = locate(m, d, I, t0, d->t, g1, &trig);
            if (st != CD_OK) { seterr(err, st, "event location failed", t0); return st; }
            renormalize(m, d);
            /* the slot that crossed switches unconditionally (it is on the new side) */
            if (trig >= 0) (void)counted_switch(m, d, I, trig / 2, 0);
            st = settle_modes(m, d, I, &changed);
            if (st != CD_OK) { seterr(err, st, "non-finite state at an event", d->t); return st; }
            if (I->drv) { gsl_odeiv2_evolve_reset(I->drv->e); gsl_odeiv2_step_reset(I->drv->s); }
        }
        /* geometry failures are reported, never silent */
        {
            int k;
            for (k = 0; k < m->nslot; k++)
                if (d->slot_geomfail[k]) { d->stats.nwarn_geom++; log_event(m, d, k, CD_EV_GEOM_FAIL, d->slot_mode[k], d->slot_mode[k]); }
        }
        if (!I->fixed && I->h < m->opt.h_min && d->t < t_end) {
            seterr(err, CD_ESTALL, "step size fell below h_min (stiff or discontinuous dynamics)", d->t);
            return CD_ESTALL;
        }
        if (cb && cb(m, d, user)) { seterr(err, CD_EINTERRUPT, "stopped by the caller", d->t); return CD_EINTERRUPT; }
        if (attempts >= m->opt.max_steps) {
            seterr(err, CD_EMAXSTEPS, "step budget (max_steps) exhausted", d->t);
            return CD_EMAXSTEPS;
        }
    }
    return CD_OK;
}
