/* The event-driven integrator.
 *
 * GSL odeiv2 is driven one accepted step at a time (gsl_odeiv2_evolve_apply)
 * with the step, control and evolve objects of a gsl_odeiv2_driver allocated
 * once at cd_data_create (the driver holds them). After every
 * accepted step the switching functions of every switch unit (src/sim/switch.h:
 * contact slots, joint stops, joint friction, user switches) are evaluated; if
 * any changed sign, the crossing is located by Illinois (modified regula
 * falsi) iterations, each one a single step of a one-step "locator" stepper
 * (rk8pd; classic RK4 in fixed-step mode) of trial length tau from the saved
 * start state, so the located state is the integrator's own solution, not an
 * interpolant. The bracket is shrunk to event_tol; the state lands on the far
 * end (already on the new side), the unit's provider applies its transition,
 * and the stepper is reset: inside a segment the rhs is smooth and the
 * adaptive control stays honest.
 *
 * Time events: steps never cross a schedule breakpoint (STEPS/TABLE rows,
 * waypoints, m->breaks); there the rows switch, the stepper restarts and the
 * modes are re-checked, so a torque step is exact. Call boundaries: the
 * inputs and the state at the end of a call are remembered; if the caller
 * changed either before the next call, the stepper restarts there and the
 * modes are re-checked; if not, the run continues as if it had not stopped
 * (only the step that landed on the boundary was clipped).
 *
 * Chattering guard: a unit may switch at most twice in quick succession
 * (each switch within `dwell` of the previous one: onset followed by an
 * immediate slip at one instant, or two flips landing event_tol apart);
 * after that its switching functions are ignored until `dwell` seconds have
 * passed since its last switch, and steps are clamped to end when a dwell
 * expires, where the unit is re-checked and switched at once if needed
 * (counted in stats.nwarn_dwell).
 *
 * Quaternions are renormalised after every accepted step and every landing
 * (the rhs also uses q/|q|), which keeps |q| - 1 at round-off; prescribed
 * coordinates are set to their exact profile at the same places. */
#include "capdyn/sim.h"
#include "../math/cd_math.h"
#include "../contact/contact.h"
#include "../mechanism/actuation.h"
#include "../kinematics/prescribed.h"
#include "integ.h"
#include "bdf.h"
#include "gauss4.h"
#include "rk8.h"
#include "rosw.h"
#include "switch.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* auto's stiff stepper: msbdf (1, since 2026-11-28: docs/dynamics.md, "auto"), or
 * ros34pw2 as before (build with -DCD_AUTO_BDF=0: for comparisons) */
#ifndef CD_AUTO_BDF
#define CD_AUTO_BDF 1
#endif
/* msbdf (alone, or auto's stiff phases) locates its events on its own trial
 * steps (1, since 2026-11-28: cd_bdf_trial, docs/events.md), or on rk8pd
 * sub-steps across its step as before (0: for comparisons) */
#ifndef CD_BDF_LOCATOR
#define CD_BDF_LOCATOR 1
#endif

/* auto (CD_STEP_AUTO): its stiff stepper is msbdf (CD_AUTO_BDF, above); the
 * rules below were written for ros34pw2 and read the same with msbdf, except
 * the guess of the stiff step (the second rule), which only ros34pw2 builds
 * use: with msbdf only the measured cost hands back to rk8pd.
 * A stiffness check runs every auto_every accepted
 * steps (CD_AUTO_EVERY, doubled up to CD_AUTO_EVERY_MAX after a switch that
 * was measured to be a mistake, below). With rho the spectral radius of the
 * Jacobian and h the step the stepper works at, rk8pd is stability-capped
 * near h rho ~ 5 (its region reaches about 5 on the real and imaginary
 * axes): at h rho > CD_AUTO_STIFF it works at that cap. The choice is on
 * cost: an rk8pd step costs 12-13 evaluations, a ros34pw2 step 4 plus its
 * linear algebra, about CD_AUTO_COST_RATIO times less. So
 *   rk8pd -> ros34pw2 when h rho > CD_AUTO_STIFF;
 *   ros34pw2 -> rk8pd when rk8pd could take min(h_max, CD_AUTO_STIFF / rho)
 *            > CD_AUTO_COST_RATIO h.
 * Two consecutive checks must agree.
 *
 * The model guesses ros34pw2's step, which accuracy may hold far below what
 * its stability allows (order 3 at a tight tolerance), so the cost is also
 * measured: the evaluations per simulated second over the steps between two
 * checks (a window, its events included). On ros34pw2, a window (not the
 * first after the switch) costlier than rk8pd's last one before the switch
 * is a check that asks for rk8pd. At every switch the stepper given up is
 * compared, in its last window, with the other stepper's last window before
 * it was given up: if it cost more, the round trip was a mistake, whichever
 * rule asked for it, and the interval doubles; otherwise it goes back to
 * CD_AUTO_EVERY. (The interval used to double at every switch that came
 * within 5 checks of the one before. Many such switches are right: an
 * impact's transient, which both steppers resolve with short steps and
 * rk8pd with fewer evaluations, hands over to rk8pd, and once it has
 * decayed rk8pd works at its stability cap and must hand back soon; the
 * doubled interval kept the Fig. 5 grasp on rk8pd at its cap for 0.16 s, at
 * 13 evaluations per 0.2 ms.) */
#define CD_AUTO_EVERY 10
#define CD_AUTO_EVERY_MAX 320
#define CD_AUTO_STIFF 2.5
#define CD_AUTO_COST_RATIO 2.0

/* Reserve of evaluations a located event needs after its iterations: the
 * landing (1), the zero-time mode cascade (settle_modes: at most 5) and, in
 * fixed-step mode, the rest of the step (one RK4 step from the event with
 * its end evaluation: 4). */
#define CD_BUDGET_RESERVE 10
/* The least budget a fixed step can keep to: the re-check after a changed
 * input (settle_modes: <= 5), the step (4), the located event's bracket start
 * (1) and the reserve. Breakpoints inside the step split it (4 more each). */
#define CD_STEP_MIN_EVALS (5 + 4 + 1 + CD_BUDGET_RESERVE)
/* The stepper's last evaluation stands for the end state after the
 * quaternions' renormalisation when each |q| was within this of 1: every
 * use of a quaternion (kinematics, outputs) divides by |q|, so the two
 * states describe one configuration, to round-off. */
#define CD_QUAT_SAME 1e-8

typedef struct {
    const cd_model *m;        /* set for the duration of one call only: the data keeps no model pointer */
    cd_data *d;
    gsl_odeiv2_system sys;
    gsl_odeiv2_driver *drv;   /* adaptive steppers (NULL in fixed mode) */
    gsl_odeiv2_step *loc;     /* rk8pd one-step locator (adaptive modes; NULL in fixed mode) */
    double *y0, *ylo, *yhi, *yerr;
    double *k1, *k2, *k3, *k4, *ytmp; /* classic RK4 (fixed-step mode) */
    double *f0s, *f1s;        /* f at the start and the end of the step an event is located in (the Hermite cubic) */
    double *f0chk;            /* f(t0, y0) of the step being taken (the divergence check) */
    double *g_end, *g_cur;    /* every unit's two switching functions (gmin's gv): at the step's end, at a trial */
    double *g_lo, *g_hi;      /* ... at the ends of the locator's bracket (the integrator's own solution) */
    double *g_ilo, *g_ihi;    /* ... at the ends of the bracket on the interpolant */
    double *ylast, tlast;     /* the state of rhs's last evaluation (d's outputs are those of it) */
    int last_valid;           /* ylast/tlast describe d's outputs (no direct cd_forward since) */
    double *in_snap;          /* inputs at the end of the last call */
    double *y_end;            /* y at the end of the last call */
    int nin;                  /* inputs: nu + nv + 12 nbody + nuser (user modes) + nfinger (schedule origins) */
    cd_control_fn ctl_fn;     /* the callbacks at the end of the last call */
    void *ctl_user, *sw_user;
    cd_user_switch_fn sw_fn;
    cd_user_transition_fn tr_fn;
    double hfix_set;          /* opt.h_fixed the fixed step was taken from */
    double t_end, h;          /* time at the end of the last call; next trial step */
    double rtol_set, atol_set;/* the tolerances the GSL control was made with */
    double step_t0, step_h;   /* cd_step: origin and step; t = step_t0 + step_k step_h */
    long step_k;
    long nrhs0;               /* d->stats.nrhs at the start of the call (budget) */
    int have_end;             /* t_end, y_end and in_snap describe the end of a call */
    int fsal;                 /* d->ydot is f(t, y) with the current modes and inputs */
    int restart_pending;      /* the next call restarts the stepper (msbdf/rk4imp snapshot) */
    int fixed, history;       /* fixed-step mode; the stepper keeps state beyond (t, y) (uses_rosw) */
    cd_stepper stepper;       /* the one the GSL objects were made for */
    cd_rosw rw;               /* ros34pw2: Jacobian and stage buffers, shared by stepper and locator */
    cd_gauss4 g4;             /* rk4imp: its stage and iteration-matrix buffers (its Jacobian: rw) */
    cd_bdf bdf;               /* msbdf: its history and iteration-matrix buffers (its Jacobian: rw) */
    /* auto: drv->s and loc are rk8pd; the stiff pair below is ros34pw2 (CD_AUTO_BDF = 0;
     * with msbdf the stiff steps are the BDF's own, bdf above) */
    gsl_odeiv2_step *s_stiff, *loc_stiff;
    int autom;                /* stepper is CD_STEP_AUTO */
    int stiff;                /* auto: the stiff stepper is the current one */
    int auto_hits;            /* consecutive checks that asked for the other stepper */
    int loc_nsub;             /* rk4imp, msbdf: the locator's sub-steps over the step an event is located in */
    int loc_bdf;              /* msbdf: this event is located on msbdf's own trial steps (cd_bdf_trial) */
    double loc_hsub;          /* ... and their length (0: one locator step per trial) */
    long auto_next;           /* accepted steps until the next stiffness check */
    long auto_every;          /* steps between checks (doubled after a switch measured to be a mistake) */
    long auto_since;          /* accepted steps since the last switch */
    long auto_nrhs_reset;     /* auto: stats.nrhs when an event last restarted the window (log_event):
                               * that step's evaluations before it stay out of the new window */
    double auto_tc;           /* auto: start of the check window (the last check or switch) [s] */
    double auto_ec;           /* auto: evaluations in the window (whole number) */
    double auto_rate_exp;     /* auto: rk8pd's evaluations per simulated second in its last window before
                               * the switch to the stiff stepper (0: none measured) */
    double auto_rate_imp;     /* auto: the stiff stepper's in its last window before the switch to rk8pd
                               * (0: none) */
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
    if (st != CD_OK) { I->last_valid = 0; return GSL_EBADFUNC; }
    memcpy(dydt, d->ydot, (size_t)I->m->ny * sizeof(double));
    memcpy(I->ylast, y, (size_t)I->m->ny * sizeof(double));
    I->tlast = t;
    I->last_valid = 1;
    return GSL_SUCCESS;
}

void cd_integ_free(void *p)
{
    cd_integ *I = (cd_integ *)p;
    if (!I) return;
    if (I->drv) gsl_odeiv2_driver_free(I->drv);
    if (I->loc) gsl_odeiv2_step_free(I->loc);
    if (I->s_stiff) gsl_odeiv2_step_free(I->s_stiff);
    if (I->loc_stiff) gsl_odeiv2_step_free(I->loc_stiff);
    I->drv = NULL;
    I->loc = NULL;
    I->s_stiff = I->loc_stiff = NULL;
}

/* the linearly implicit steppers of rosw.c (their workspace: cd_rosw) */
static int rosenbrock(cd_stepper s) { return s == CD_STEP_ROS34PW2 || s == CD_STEP_RODAS4; }
/* the steppers on the rosw workspace (a Jacobian, LU and stage buffers): the
 * Rosenbrock ones, auto's stiff one, and capdyn's Gauss (rk4imp) and BDF
 * (msbdf), which take their Jacobian from it. They are also the steppers
 * whose next step depends on more than (t, y) (I->history). */
static int uses_rosw(cd_stepper s)
{
    return rosenbrock(s) || s == CD_STEP_AUTO || s == CD_STEP_RK4IMP || s == CD_STEP_MSBDF;
}

/* the step in progress is msbdf's: msbdf's own, or auto's while stiff */
static int on_bdf(const cd_integ *I)
{
    return I->stepper == CD_STEP_MSBDF || (CD_AUTO_BDF && I->autom && I->stiff);
}

/* the locator takes one Rosenbrock step: ros34pw2's and rodas4's own, and
 * auto's while stiff when its stiff stepper is ros34pw2 (CD_AUTO_BDF = 0) */
static int rosw_locator(const cd_integ *I)
{
    return rosenbrock(I->stepper) || (!CD_AUTO_BDF && I->stiff);
}

size_t cd_integ_stiff_size(const cd_model *m)
{
    return (uses_rosw(m->opt.stepper) ? cd_rosw_size(m) : 0) +
           (m->opt.stepper == CD_STEP_RK4IMP ? cd_gauss4_size(m) : 0) +
           (m->opt.stepper == CD_STEP_MSBDF || (CD_AUTO_BDF && m->opt.stepper == CD_STEP_AUTO) ? cd_bdf_size(m) : 0);
}

size_t cd_integ_size(const cd_model *m)
{
    size_t n = (size_t)(m->ny ? m->ny : 1), nin = (size_t)(m->nu + m->nv + 12 * m->nbody + m->nuser + m->nfinger);
    /* the struct, then 14 n + 12 nsw + nin doubles (14 buffers of n, 6 of 2 nsw), then the ros34pw2
     * buffers (also the Jacobian of rk4imp and msbdf), then rk4imp's or msbdf's own */
    return sizeof(cd_integ) + 16 + (14 * n + nin + 12 * (size_t)m->nsw + 1) * sizeof(double) + cd_integ_stiff_size(m);
}

void *cd_integ_create(const cd_model *m, cd_data *d, void *mem, cd_error *err)
{
    const gsl_odeiv2_step_type *T = NULL;
    size_t n = (size_t)(m->ny ? m->ny : 1), nin = (size_t)(m->nu + m->nv + 12 * m->nbody + m->nuser + m->nfinger);
    cd_integ *I = (cd_integ *)mem;
    double *p;
    memset(I, 0, cd_integ_size(m));
    p = (double *)(void *)(((uintptr_t)(I + 1) + 15) & ~(uintptr_t)15);
    I->y0 = p; p += n; I->ylo = p; p += n; I->yhi = p; p += n; I->yerr = p; p += n;
    I->k1 = p; p += n; I->k2 = p; p += n;
    I->k3 = p; p += n; I->k4 = p; p += n; I->ytmp = p; p += n; I->y_end = p; p += n;
    I->f0s = p; p += n; I->f1s = p; p += n; I->ylast = p; p += n; I->f0chk = p; p += n;
    I->g_end = p; p += 2 * m->nsw; I->g_cur = p; p += 2 * m->nsw;
    I->g_lo = p; p += 2 * m->nsw; I->g_hi = p; p += 2 * m->nsw;
    I->g_ilo = p; p += 2 * m->nsw; I->g_ihi = p; p += 2 * m->nsw;
    I->in_snap = p;
    p += nin;
    I->nin = (int)nin;
    I->d = d;
    I->sys.function = rhs;
    I->sys.jacobian = NULL; /* every implicit stepper forms its own (rosw.c) */
    I->sys.dimension = n;
    I->sys.params = I;
    I->stepper = d->opt.stepper;
    I->fixed = d->opt.stepper == CD_STEP_RK4_FIXED;
    /* steppers whose next step depends on more than (t, y): a snapshot is a restart point */
    I->history = uses_rosw(d->opt.stepper);
    I->autom = d->opt.stepper == CD_STEP_AUTO;
    switch (d->opt.stepper) {
    case CD_STEP_RKF45: T = gsl_odeiv2_step_rkf45; break;
    case CD_STEP_RKCK: T = gsl_odeiv2_step_rkck; break;
    case CD_STEP_RK8PD: T = cd_step_rk8pd; break; /* capdyn's own (rk8.c): skips the open slots' anchors */
    case CD_STEP_RK4IMP: T = cd_step_gauss4; break; /* capdyn's own (gauss4.c): GSL's allocates in every step */
    case CD_STEP_MSBDF: T = cd_step_bdf; break; /* capdyn's own (bdf.c): GSL's allocates in its LU */
    case CD_STEP_ROS34PW2: T = cd_step_ros34pw2; break;
    case CD_STEP_RODAS4: T = cd_step_rodas4; break;
    case CD_STEP_AUTO: T = cd_step_rk8pd; break;
    default: T = NULL; break;
    }
    if (!I->fixed) {
        I->drv = gsl_odeiv2_driver_alloc_standard_new(&I->sys, T, d->opt.h_init, d->opt.atol, d->opt.rtol, 1.0, 1.0);
        if (!I->drv) goto nomem;
        I->rtol_set = d->opt.rtol;
        I->atol_set = d->opt.atol;
        /* the locator: rk8pd, or the stiff stepper itself (an explicit trial
         * step as long as a stiff step would be unstable) */
        I->loc = gsl_odeiv2_step_alloc(rosenbrock(d->opt.stepper) ? T : cd_step_rk8pd, n);
        if (!I->loc) goto nomem;
        if (T == cd_step_rk8pd) cd_rk8_bind(I->drv->s, &I->m, d);
        if (!rosenbrock(d->opt.stepper)) cd_rk8_bind(I->loc, &I->m, d);
        if (uses_rosw(d->opt.stepper)) cd_rosw_init(&I->rw, m, d, p + 1);
        if (rosenbrock(d->opt.stepper)) {
            cd_rosw_bind(I->drv->s, &I->rw, 0);
            cd_rosw_bind(I->loc, &I->rw, 1);
        }
        if (d->opt.stepper == CD_STEP_RK4IMP) {
            cd_gauss4_init(&I->g4, &I->rw, m, (char *)(void *)(p + 1) + cd_rosw_size(m));
            cd_gauss4_bind(I->drv->s, &I->g4);
        }
        if (d->opt.stepper == CD_STEP_MSBDF || (I->autom && CD_AUTO_BDF))
            cd_bdf_init(&I->bdf, &I->rw, m, (char *)(void *)(p + 1) + cd_rosw_size(m));
        if (d->opt.stepper == CD_STEP_MSBDF) cd_bdf_bind(I->drv->s, &I->bdf);
        if (I->autom && CD_AUTO_BDF) {
            /* auto's stiff stepper: msbdf, located as msbdf is (on its own trial
             * steps, cd_bdf_trial; no stiff locator of its own) */
            I->s_stiff = gsl_odeiv2_step_alloc(cd_step_bdf, n);
            if (!I->s_stiff) goto nomem;
            cd_bdf_bind(I->s_stiff, &I->bdf);
        } else if (I->autom) {
            I->s_stiff = gsl_odeiv2_step_alloc(cd_step_ros34pw2, n);
            I->loc_stiff = gsl_odeiv2_step_alloc(cd_step_ros34pw2, n);
            if (!I->s_stiff || !I->loc_stiff) goto nomem;
            cd_rosw_bind(I->s_stiff, &I->rw, 0);
            cd_rosw_bind(I->loc_stiff, &I->rw, 1);
        }
    }
    return I;
nomem:
    if (I) cd_integ_free(I);
    cd_error_set(err, CD_ENOMEM, "out of memory creating the integrator");
    return NULL;
}

static void restart(cd_data *d, cd_integ *I)
{
    if (I->drv) gsl_odeiv2_driver_reset(I->drv);
    if (I->s_stiff) gsl_odeiv2_step_reset(I->s_stiff);
    I->fsal = 0;
    d->stats.nrestart++;
}

void cd_integ_reset(const cd_model *m, cd_data *d)
{
    cd_integ *I = (cd_integ *)d->integ;
    (void)m;
    I->h = I->fixed ? d->opt.h_fixed : d->opt.h_init;
    I->hfix_set = d->opt.h_fixed;
    if (I->drv) gsl_odeiv2_driver_reset(I->drv);
    if (I->loc) gsl_odeiv2_step_reset(I->loc);
    if (I->s_stiff) gsl_odeiv2_step_reset(I->s_stiff);
    I->stiff = 0;
    I->auto_hits = 0;
    I->auto_next = 0;
    I->auto_every = CD_AUTO_EVERY;
    I->auto_since = 0;
    I->auto_tc = d->t;
    I->auto_ec = 0;
    I->auto_nrhs_reset = 0;
    I->auto_rate_exp = 0;
    I->auto_rate_imp = 0;
    I->have_end = 0;
    I->fsal = 0;
    I->restart_pending = 0;
    I->step_k = 0;
    I->step_h = 0;
    I->step_t0 = 0;
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

/* ya and yb are equal but for the scale of the quaternions (|q_a| within
 * CD_QUAT_SAME of 1, q_b = q_a / |q_a|): one configuration */
static int same_configuration(const cd_model *m, const double *ya, const double *yb)
{
    int s, i, from = 0;
    for (s = 0; s < m->nsys; s++) {
        int q = m->sys_y_adr[s] + 3;
        double n2 = 0, c;
        if (m->sys_base_type[s] != CD_BASE_FREE) continue;
        if (memcmp(ya + from, yb + from, (size_t)(q - from) * sizeof(double)) != 0) return 0;
        for (i = 0; i < 4; i++) n2 += ya[q + i] * ya[q + i];
        if (!(fabs(sqrt(n2) - 1.0) <= CD_QUAT_SAME)) return 0;
        for (i = 0; i < 4; i++) {
            c = ya[q + i] / sqrt(n2);
            if (fabs(c - yb[q + i]) > 4e-16) return 0;
        }
        from = q + 4;
    }
    return memcmp(ya + from, yb + from, (size_t)(m->ny - from) * sizeof(double)) == 0;
}

/* after a step or a landing: unit quaternions, exact prescribed coordinates */
static void clean_state(const cd_model *m, cd_data *d)
{
    renormalize(m, d);
    if (m->npresc) cd_prescribed_apply(m, d->t, d->y);
}

static int in_dwell(const cd_data *d, int u)
{
    return d->sw_nswitch[u] >= 2 && d->t - d->sw_tswitch[u] < d->opt.dwell;
}

/* min over watched units of the switching functions at d's current state
 * (after cd_forward); the unit achieving it in *which. */
static double gmin(const cd_model *m, const cd_data *d, int use_dwell, int *which, double *gv)
{
    int u;
    double best = HUGE_VAL, g[2];
    if (which) *which = -1;
    for (u = 0; u < m->nsw; u++) {
        /* gv: every unit's two functions (+inf for a unit left out: never crossing) */
        if (gv) gv[2 * u] = gv[2 * u + 1] = HUGE_VAL;
        if (use_dwell && in_dwell(d, u)) continue;
        if (cd_sw_skip(m, d, u)) continue;
        if (u < m->nslot) {
            if (!cd_contact_switch_near(m, d, u, g)) continue; /* an open slot far apart: positive */
        } else {
            cd_sw_functions(m, d, u, 0, g);
        }
        if (gv) { gv[2 * u] = g[0]; gv[2 * u + 1] = g[1]; }
        if (g[0] < best) { best = g[0]; if (which) *which = u; }
        if (g[1] < best) { best = g[1]; if (which) *which = u; }
    }
    return best;
}

static void log_event(cd_data *d, const cd_event *ev)
{
    cd_event *e = &d->ev[d->ev_count % d->ev_cap];
    cd_integ *I = (cd_integ *)d->integ;
    *e = *ev;
    e->t = d->t;
    d->ev_count++;
    d->stats.nevents++;
    /* auto: a contact that closes or opens changes the problem's stiffness,
     * so a cost measured across it says little about either stepper after
     * it: auto's measuring window starts again here (auto_check), and on the
     * stiff stepper so does the count to the next check, so that the window
     * it is judged on is a whole one (a window of a step or two, with this
     * event's location in it, costs many times the steady rate). Without
     * this, rk8pd's cost in free flight (700 evaluations per second on the
     * capture twin) was held against msbdf's in the 5 ms after the first
     * touch, and auto went back to rk8pd, which then spent 3 400 evaluations
     * on 70 ms of contact onsets before the stiffness check sent it back. */
    if (I && I->autom && ev->owner_kind == CD_OWNER_SLOT &&
        (ev->mode_from == CD_MODE_OPEN) != (ev->mode_to == CD_MODE_OPEN)) {
        I->auto_tc = d->t;
        I->auto_ec = 0;
        I->auto_nrhs_reset = d->stats.nrhs;
        if (I->stiff) I->auto_next = I->auto_every;
    }
}

/* the unit's transition under the chattering guard's bookkeeping: switches
 * more than `dwell` apart start a new count; the second within the window
 * holds the unit (its forces clipped, its functions unwatched) until the
 * window ends. */
static int counted_switch(const cd_model *m, cd_data *d, int u, int forgive)
{
    cd_event ev;
    if (d->t - d->sw_tswitch[u] >= d->opt.dwell) d->sw_nswitch[u] = 0;
    if (!cd_sw_transition(m, d, u, forgive, &ev)) return 0;
    log_event(d, &ev);
    d->sw_tswitch[u] = d->t;
    if (++d->sw_nswitch[u] >= 2) d->sw_held[u] = 1;
    return 1;
}

/* Switch every unit whose functions are negative at the current state, with
 * zero-time cascades (e.g. onset -> slip) bounded by the chattering guard.
 * Leaves d evaluated (ydot valid for the modes it ends with). */
static cd_status settle_modes(const cd_model *m, cd_data *d, cd_integ *I, int *changed)
{
    int round, u, any;
    cd_status st;
    *changed = 0;
    for (u = 0; u < m->nsw; u++) /* guard windows that have passed */
        if (d->sw_held[u] && d->t - d->sw_tswitch[u] >= d->opt.dwell) d->sw_held[u] = 0;
    for (round = 0; round < 4; round++) {
        st = cd_forward(m, d);
        d->stats.nrhs++;
        if (st != CD_OK) return st;
        any = 0;
        for (u = 0; u < m->nsw; u++) {
            double g[2];
            if (cd_sw_skip(m, d, u)) continue;
            cd_sw_functions(m, d, u, 1, g);
            if (!(g[0] < 0 || g[1] < 0)) continue;
            if (in_dwell(d, u)) { d->stats.nwarn_dwell++; continue; }
            if (counted_switch(m, d, u, 1)) any = 1;
        }
        if (!any) break;
        *changed = 1;
    }
    if (*changed) {
        st = cd_forward(m, d);
        d->stats.nrhs++;
        if (st != CD_OK) return st;
    }
    I->fsal = 1;
    return CD_OK;
}

cd_status cd_integ_initial_modes(const cd_model *m, cd_data *d, cd_error *err)
{
    int k, any = 0;
    /* with an equilibrium start, a check point placed exactly on a surface
     * (|x| at round-off of the placement) counts as closed */
    double tol = d->opt.equilibrium_start ? 1e-9 : 0.0;
    if (m->npresc) cd_prescribed_apply(m, d->t, d->y);
    /* a state that cannot be evaluated is left to the first step to report
     * (with its time); the data stays usable for inspection */
    if (cd_forward(m, d) != CD_OK) return CD_OK;
    for (k = 0; k < m->nslot; k++)
        if (!d->slot_geomfail[k] && d->slot_x[k] > -tol && (d->slot_x[k] > 0 || tol > 0)) {
            d->slot_mode[k] = CD_MODE_STICK;
            d->sw_tswitch[k] = d->t;
            any = 1;
        }
    for (k = 0; k < m->nlim; k++)
        if (d->lim_depth[k] > -tol && (d->lim_depth[k] > 0 || tol > 0)) {
            int b = m->lim_body[k];
            double q = cd_joint_q(m, d, b);
            d->lim_mode[k] = fabs(q - m->body_limit[6 * b]) < fabs(q - m->body_limit[6 * b + 1]) ? CD_LIM_LOWER : CD_LIM_UPPER;
            d->sw_tswitch[m->nslot + k] = d->t;
            any = 1;
        }
    if (d->opt.equilibrium_start && (any || m->nfric)) {
        cd_status st = cd_equilibrium_start(m, d, err);
        if (st != CD_OK) return st;
    }
    /* the switches due at t = 0 (e.g. a joint friction that starts moving
     * slips at once) are resolved here, not at the first advance, so that the
     * data a caller reads or samples at t = 0 holds the forces that are
     * applied (issue 22: a t = 0 sample showed a stick damper's -104 N that
     * never acted); the first advance re-checks and finds them settled */
    {
        int changed;
        if (settle_modes(m, d, (cd_integ *)d->integ, &changed) != CD_OK) (void)cd_forward(m, d);
    }
    return CD_OK;
}

/* Classic RK4, y advanced in place by h: 4 evaluations, 3 when d->ydot
 * already holds f(t, y) (the previous step's end evaluation). */
static int rk4_step(cd_integ *I, double t, double h, double *y, int use_fsal)
{
    size_t n = (size_t)I->m->ny, i;
    if (use_fsal) memcpy(I->k1, I->d->ydot, n * sizeof(double));
    else if (rhs(t, y, I->k1, I) != GSL_SUCCESS) return GSL_EBADFUNC;
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
    gsl_odeiv2_step *loc = I->loc_stiff && I->stiff ? I->loc_stiff : I->loc;
    if (I->fixed) return rk4_step(I, t, h, y, 0);
    /* a Rosenbrock locator starts afresh; rk8pd keeps nothing between steps */
    if (rosw_locator(I)) gsl_odeiv2_step_reset(loc);
    return gsl_odeiv2_step_apply(loc, t, h, y, I->yerr, NULL, NULL, &I->sys);
}

/* rk4imp (and msbdf when one of its own trials fails: trial()) locates
 * with rk8pd steps across its own (implicit) step, which may be far beyond
 * rk8pd's stability limit on a stiff
 * problem: the step of length h is cut into n equal rk8pd sub-steps with
 * rho h/n within rk8pd's real stability interval (CD_AUTO_STIFF, about half
 * of it; at most CD_LOC_MAX_SUB, beyond which the sub-steps stay unstable),
 * rho the spectral radius of the structured Jacobian (docs/events.md section
 * 6, step 4). A trial of length tau takes the sub-steps of that fixed grid
 * up to tau and the rest, so its solution is continuous in tau (the root
 * finder and lower_end_back rely on it). Without the sub-steps a trial
 * could land far off the solution, where a switching function is negative
 * for no physical reason: msbdf on the Fig. 5 grasp landed on a stick-slip
 * pair 15 ns long on a contact 0.32 N inside its cone. */
#define CD_LOC_MAX_SUB 256
static int loc_substeps(double rho, double h)
{
    double n = ceil(h * rho / CD_AUTO_STIFF);
    return n < 1.0 ? 1 : n > CD_LOC_MAX_SUB ? CD_LOC_MAX_SUB : (int)n;
}

/* One locator step of length tau from (t0, y0) into y; then cd_forward. */
static cd_status trial(const cd_model *m, cd_data *d, cd_integ *I, double t0, double tau, double *y)
{
    int st = GSL_SUCCESS, k, nfull = 0;
    double hs = I->loc_hsub;
    if (I->loc_bdf) {
        /* msbdf's own step to tau over its history. Should one fail (its
         * Newton iteration, or a history that does not start at t0), this
         * event's remaining trials take rk8pd sub-steps, as before (2 of the
         * 1 359 trials of the shipped scenarios run with auto) */
        st = cd_bdf_trial(&I->bdf, &I->sys, t0, tau, y);
        if (st == GSL_SUCCESS) goto evaluate;
        I->loc_bdf = 0;
        st = GSL_SUCCESS;
    }
    memcpy(y, I->y0, (size_t)m->ny * sizeof(double));
    if (hs > 0) {
        nfull = (int)floor(tau / hs);
        if (nfull > I->loc_nsub) nfull = I->loc_nsub;
        if (nfull >= 1 && tau - nfull * hs <= 1e-9 * hs) nfull--; /* a sliver left: the last step takes it */
    }
    for (k = 0; k < nfull && st == GSL_SUCCESS; k++) st = one_step(I, t0 + k * hs, hs, y);
    if (st == GSL_SUCCESS) st = one_step(I, t0 + nfull * hs, tau - nfull * hs, y);
evaluate:
    d->stats.nlocate_steps++;
    if (st != GSL_SUCCESS) return CD_ENUMERIC;
    d->y = y;
    d->t = t0 + tau;
    if (m->npresc) cd_prescribed_apply(m, d->t, y);
    st = cd_forward(m, d);
    d->stats.nrhs++;
    return st == CD_OK ? CD_OK : CD_ENUMERIC;
}

/* Back to the start of the step after a failure: d holds the last good
 * state (y0 at t0) with its outputs evaluated, as cd_sim_advance promises. */
static void restore_start(const cd_model *m, cd_data *d, cd_integ *I, double t0, double *ystate)
{
    d->y = ystate;
    memcpy(d->y, I->y0, (size_t)m->ny * sizeof(double));
    d->t = t0;
    (void)cd_forward(m, d);
    I->fsal = 0;
}

/* evaluations one more locator iteration costs (its stages and the forward) */
static long trial_cost(const cd_integ *I)
{
    /* msbdf's own trial, and room for the rk8pd fallback should it fail (trial()) */
    if (I->loc_bdf) return CD_BDF_NEWTON_MAX + 1 + 14 * (long)(I->loc_nsub > 0 ? I->loc_nsub : 1);
    if (I->loc_nsub > 0) return 14 * (long)I->loc_nsub;
    return I->fixed ? 5 : I->stepper == CD_STEP_RODAS4 ? 7 : rosw_locator(I) ? 5 : 14;
}

static int budget_left(const cd_data *d, const cd_integ *I, long need)
{
    return d->opt.max_evals <= 0 || d->stats.nrhs - I->nrhs0 + need + CD_BUDGET_RESERVE <= d->opt.max_evals;
}

/* The cubic Hermite interpolant of the step (t0, y0, f0) -> (t0 + h, y1, f1)
 * at t0 + tau into y, then cd_forward: g at an interpolated state costs one
 * evaluation instead of a locator step. */
static cd_status interp(const cd_model *m, cd_data *d, cd_integ *I, double t0, double h, double tau, double *y)
{
    double th = tau / h, a0 = (1 + 2 * th) * (1 - th) * (1 - th), a1 = th * th * (3 - 2 * th);
    double b0 = tau * (1 - th) * (1 - th), b1 = -tau * th * (1 - th);
    int i;
    cd_status st;
    for (i = 0; i < m->ny; i++) y[i] = a0 * I->y0[i] + a1 * I->yhi[i] + b0 * I->f0s[i] + b1 * I->f1s[i];
    d->y = y;
    d->t = t0 + tau;
    if (m->npresc) cd_prescribed_apply(m, d->t, y);
    st = cd_forward(m, d);
    d->stats.nrhs++;
    d->stats.nlocate_interp++;
    return st == CD_OK ? CD_OK : CD_ENUMERIC;
}

/* A bracket [lo, hi] (times from the step's start) of the first crossing:
 * gmin at its ends, and every unit's two functions there (gmin's gv). */
typedef struct {
    double lo, hi, glo, ghi;
    double *gl, *gh;
} cd_bracket;

/* Where in [0, 1] of the bracket the first unit crosses, by the secant of
 * each function that is negative at hi between its values at the two ends
 * (weighted by al, ah: Illinois), the earliest of them. The secant of gmin
 * itself is a poor guess when gmin is the minimum of several functions:
 * one unit's function at lo and another's, steeper, at hi (soft_wrap's
 * first events: gmin 4e-4 at lo and -0.44 at hi, the secant creeping from
 * lo); each unit's own secant is the guess of SUNDIALS' rootfinding. A unit
 * without a value at lo (left out there: an open slot apart by more than
 * its radius, or in a guard window) gives the middle. */
static double earliest(const cd_model *m, const cd_bracket *b, double al, double ah)
{
    double best = HUGE_VAL;
    int i, n = 2 * m->nsw;
    for (i = 0; i < n; i++) {
        double a, f;
        if (!(b->gh[i] < 0)) continue;
        if (!(b->gl[i] < HUGE_VAL)) f = 0.5;
        else {
            a = b->gl[i] > 0 ? al * b->gl[i] : 0.0;
            f = a / (a - ah * b->gh[i]);
        }
        if (f < best) best = f;
    }
    return best <= 1.0 ? best : 0.5;
}

/* An end of the bracket moves to tau, where gmin is g and every unit's
 * functions are in I->g_cur: side +1 (lo, old side) or -1 (hi, new side). */
static void bracket_move(const cd_model *m, const cd_integ *I, cd_bracket *b, double tau, double g)
{
    if (g < 0) {
        b->hi = tau; b->ghi = g;
        memcpy(b->gh, I->g_cur, (size_t)(2 * m->nsw) * sizeof(double));
    } else {
        b->lo = tau; b->glo = g;
        memcpy(b->gl, I->g_cur, (size_t)(2 * m->nsw) * sizeof(double));
    }
}

/* Illinois (modified regula falsi) on the bracket b, on the interpolant
 * (use_interp) or on locator steps from y0. Leaves the last real state of
 * the upper end in I->yhi when !use_interp. */
static cd_status illinois(const cd_model *m, cd_data *d, cd_integ *I, double t0, double h, int use_interp,
                          cd_bracket *b)
{
    int side = 0, it, edge = 0, edge_missed = 0;
    /* tol_in: an edge trial a hair inside the tolerance, so that the
     * bracket it closes is not a rounding above it (one more iteration) */
    const double tol = d->opt.event_tol, tol_in = tol * (1.0 - 1e-6);
    double al = 1.0, ah = 1.0;
    cd_status st;
    for (it = 0; it < 200 && b->hi - b->lo > tol; it++) {
        double tau, g, w = b->hi - b->lo;
        if (!budget_left(d, I, use_interp ? 1 : trial_cost(I))) { d->stats.nwarn_budget++; break; }
        /* Illinois: the secant of each crossing unit, the stale end's values halved */
        tau = b->lo + earliest(m, b, al, ah) * w;
        if (!(tau > b->lo && tau < b->hi)) tau = b->lo + 0.5 * w;
        edge = 0;
        if (it % 4 == 3 || w <= 2.0 * tol) {
            tau = b->lo + 0.5 * w; /* a bisection now and then bounds the worst case */
        } else if (edge_missed) {
            /* the last edge trial found the crossing farther: a tenth of
             * the bracket from that end (SUNDIALS' rootfinding rule) */
            tau = edge_missed > 0 ? b->lo + 0.1 * w : b->hi - 0.1 * w;
        } else if (tau - b->lo < 0.5 * tol) {
            /* the estimate within half a tolerance of an end: a trial one
             * tolerance from it closes the bracket if the estimate holds
             * (a bisection here, as the old rule made it, halves the
             * bracket per iteration: ~16 iterations per event from a step
             * of 1e-5 s) */
            tau = b->lo + tol_in;
            edge = 1;
        } else if (b->hi - tau < 0.5 * tol) {
            tau = b->hi - tol_in;
            edge = -1;
        }
        edge_missed = 0;
        st = use_interp ? interp(m, d, I, t0, h, tau, I->ylo) : trial(m, d, I, t0, tau, I->ylo);
        if (st != CD_OK) return st;
        g = gmin(m, d, 1, NULL, I->g_cur);
        if (edge) edge_missed = (g < 0) == (edge > 0) ? 0 : edge;
        bracket_move(m, I, b, tau, g);
        if (g < 0) {
            if (!use_interp) memcpy(I->yhi, I->ylo, (size_t)m->ny * sizeof(double));
            if (side == -1) al *= 0.5;
            ah = 1.0;
            side = -1;
        } else {
            if (side == 1) ah *= 0.5;
            al = 1.0;
            side = 1;
        }
    }
    return CD_OK;
}

/* A certification failed: the crossing of the integrator's own solution is
 * beyond the end that failed (side +1: after lo; -1: before hi), off from
 * the interpolant's by the interpolant's error, so near that end. Its
 * distance is estimated from g there and the slope s (< 0) of g on the
 * interpolant, and a locator step 1.5 times as far (then 4 times further,
 * at most 3) brackets it: the Illinois iterations on locator steps then
 * start from a bracket a few times that distance wide instead of the rest
 * of the step. Every bracket end is still the integrator's own solution.
 * Not for rk4imp and msbdf (msbdf now locates on its own trial steps,
 * cd_bdf_trial, with rk8pd sub-steps only as a fallback; the probe has not
 * been measured with them). With rk8pd across a step of an implicit
 * method: before its sub-steps (loc_substeps) that step could lie
 * far outside rk8pd's stability region, where the distance estimate meant
 * nothing; with them the probe would be sound, but on the Fig. 5 grasp at
 * rtol 1e-9 ... 1e-11 it changed little (msbdf 0 to -3 % evaluations,
 * rk4imp 3 to 12 % more locator steps), so they iterate on the rest of the
 * step. */
static int implicit_with_explicit_locator(const cd_integ *I)
{
    return I->stepper == CD_STEP_RK4IMP || on_bdf(I);
}

/* One locator step to t0 + tau, and the bracket end it certifies: the new
 * side (g < 0: *newside = 1) moves hi, its state kept in I->yhi; the old
 * side moves lo. */
static cd_status bracket_at(const cd_model *m, cd_data *d, cd_integ *I, double t0, double tau, cd_bracket *b,
                            int *newside)
{
    double g;
    cd_status st = trial(m, d, I, t0, tau, I->ylo);
    if (st != CD_OK) return st;
    g = gmin(m, d, 1, NULL, I->g_cur);
    *newside = g < 0;
    bracket_move(m, I, b, tau, g);
    if (*newside) memcpy(I->yhi, I->ylo, (size_t)m->ny * sizeof(double));
    return CD_OK;
}

/* The lower end of a bracket at most event_tol wide, certified without a
 * locator step: the upper end's own state (I->yhi, at b->hi, its derivative
 * fhi) taken back to tau along fhi, y(tau) ~ y(hi) - (hi - tau) fhi. The
 * locator's solution from t0 is smooth in its step length, so this differs
 * from a locator step to tau by O(dt^2 |y''|) with dt <= event_tol (1e-10 s:
 * ~1e-20 |y''|), far below the state's round-off: the old side there is the
 * old side of the locator's own solution. Moves b->lo if the state shows the
 * old side (one evaluation instead of a locator step's 13); otherwise the
 * caller takes the locator step (this state is never landed on). */
static cd_status lower_end_back(const cd_model *m, cd_data *d, cd_integ *I, double t0, double tau,
                                const double *fhi, cd_bracket *b)
{
    double g, dt = b->hi - tau;
    int i;
    cd_status st;
    for (i = 0; i < m->ny; i++) I->ylo[i] = I->yhi[i] - dt * fhi[i];
    d->y = I->ylo;
    d->t = t0 + tau;
    if (m->npresc) cd_prescribed_apply(m, d->t, I->ylo);
    st = cd_forward(m, d);
    d->stats.nrhs++;
    if (st != CD_OK) return CD_ENUMERIC;
    g = gmin(m, d, 1, NULL, I->g_cur);
    if (!(g < 0)) bracket_move(m, I, b, tau, g);
    return CD_OK;
}

static cd_status probe(const cd_model *m, cd_data *d, cd_integ *I, double t0, int side, double s, cd_bracket *b)
{
    const double tol = d->opt.event_tol, half = 0.5 * tol * (1.0 - 1e-6);
    double dist = side > 0 ? b->glo / -s : b->ghi / s;
    int k, newside;
    /* first half a tolerance past the estimated crossing and, if that
     * brackets it, half a tolerance before it: the bracket is then one
     * tolerance wide when the estimate holds to half a tolerance (the
     * crossing is off from the interpolant's by a smooth offset, g is
     * linear over it); then 1.5 times as far, and 4 times further twice */
    for (k = 0; k < 4 && b->hi - b->lo > tol; k++) {
        double far = k == 0 ? dist + half : 1.5 * dist * (k == 1 ? 1.0 : k == 2 ? 4.0 : 16.0) + tol;
        double tp = side > 0 ? b->lo + far : b->hi - far;
        cd_status st;
        if (!(tp > b->lo && tp < b->hi) || !budget_left(d, I, trial_cost(I))) continue;
        st = bracket_at(m, d, I, t0, tp, b, &newside);
        if (st != CD_OK) return st;
        if (newside != (side > 0)) continue; /* not yet past the crossing */
        if (k == 0) { /* bracketed at the estimate: its other side */
            double tq = side > 0 ? tp - 2.0 * half : tp + 2.0 * half;
            if (b->hi - b->lo > tol && tq > b->lo && tq < b->hi && budget_left(d, I, trial_cost(I))) {
                st = bracket_at(m, d, I, t0, tq, b, &newside);
                if (st != CD_OK) return st;
            }
        }
        break; /* past the crossing: bracketed */
    }
    return CD_OK;
}

/* Locate the first zero of gmin in (t0, t1] given gmin(t0) >= 0 > gmin(t1),
 * and leave d at the upper end of the final bracket (on the new side).
 * Every unit's functions at t1 are in I->g_end.
 *
 * Adaptive steppers first narrow the bracket on the step's cubic Hermite
 * interpolant (one evaluation per iteration), then certify it with two
 * locator steps from y0: the integrator's own solution must be on the old
 * side at the lower end and on the new side at the upper end, as without
 * the interpolant; where it is not (the interpolant's error moved the
 * crossing), the Illinois iterations go on with locator steps from the
 * bracket that is certified. So the located state is always the
 * integrator's own solution, the bracket at most event_tol wide. */
static cd_status locate_in(const cd_model *m, cd_data *d, cd_integ *I, double t0, double t1, double g_hi,
                           int *trigger);
static cd_status locate(const cd_model *m, cd_data *d, cd_integ *I, double t0, double t1, double g_hi,
                        int *trigger)
{
    /* the locator's sub-steps (set in locate_in) hold for this event only */
    cd_status st;
    I->loc_bdf = CD_BDF_LOCATOR && on_bdf(I);
    st = locate_in(m, d, I, t0, t1, g_hi, trigger);
    I->loc_bdf = 0;
    I->loc_nsub = 0;
    I->loc_hsub = 0.0;
    return st;
}

static cd_status locate_in(const cd_model *m, cd_data *d, cd_integ *I, double t0, double t1, double g_hi,
                           int *trigger)
{
    double h = t1 - t0, *ystate = d->y;
    cd_bracket b;
    cd_status st;
    const size_t ng = (size_t)(2 * m->nsw) * sizeof(double);
    b.lo = 0.0; b.hi = h; b.ghi = g_hi; b.gl = I->g_lo; b.gh = I->g_hi;
    memcpy(b.gh, I->g_end, ng);
    /* the end of the step and its derivative (d was evaluated there) */
    memcpy(I->yhi, d->y, (size_t)m->ny * sizeof(double));
    memcpy(I->f1s, d->ydot, (size_t)m->ny * sizeof(double));
    if (!I->fixed && implicit_with_explicit_locator(I)) {
        /* the sub-steps of the locator (trial), from the spectral radius;
         * its estimate may evaluate d, which is evaluated at (t0, y0) below */
        double rho = cd_rosw_spectral_radius(&I->rw, t0, I->y0);
        if (rho > 0) {
            I->loc_nsub = loc_substeps(rho, h);
            I->loc_hsub = h / I->loc_nsub;
        }
    }
    /* g at the start (modes unchanged) */
    d->y = I->y0;
    d->t = t0;
    st = cd_forward(m, d);
    d->stats.nrhs++;
    if (st != CD_OK) { restore_start(m, d, I, t0, ystate); return st; }
    memcpy(I->f0s, d->ydot, (size_t)m->ny * sizeof(double));
    b.glo = gmin(m, d, 1, NULL, b.gl);
    if (!(b.glo > 0)) b.glo = 0.0;
    if (!I->fixed) {
        cd_bracket ib = b;
        ib.gl = I->g_ilo; ib.gh = I->g_ihi;
        memcpy(ib.gl, b.gl, ng);
        memcpy(ib.gh, b.gh, ng);
        st = illinois(m, d, I, t0, h, 1, &ib);
        if (st != CD_OK) { restore_start(m, d, I, t0, ystate); return st; }
        int failed = 0, newside; /* a certification that failed: +1 the upper end, -1 the lower */
        /* certify the upper end with the integrator's own step */
        if (ib.hi < b.hi && budget_left(d, I, trial_cost(I))) {
            st = bracket_at(m, d, I, t0, ib.hi, &b, &newside);
            if (st != CD_OK) { restore_start(m, d, I, t0, ystate); return st; }
            if (!newside) failed = 1;
        }
        /* and the lower end, if the upper one held: first by the upper end's
         * own state taken back along its derivative (below), then, if that
         * does not show the old side, by a locator step */
        if (b.hi == ib.hi && ib.lo > b.lo && ib.hi - ib.lo <= d->opt.event_tol &&
            budget_left(d, I, 1 + trial_cost(I))) {
            st = lower_end_back(m, d, I, t0, ib.lo, ib.hi < h ? d->ydot : I->f1s, &b);
            if (st != CD_OK) { restore_start(m, d, I, t0, ystate); return st; }
        }
        if (b.hi == ib.hi && ib.lo > b.lo && budget_left(d, I, trial_cost(I))) {
            st = bracket_at(m, d, I, t0, ib.lo, &b, &newside);
            if (st != CD_OK) { restore_start(m, d, I, t0, ystate); return st; }
            if (newside) failed = -1;
        }
        if (failed && ib.hi > ib.lo && ib.ghi - ib.glo < 0 && !implicit_with_explicit_locator(I)) {
            st = probe(m, d, I, t0, failed, (ib.ghi - ib.glo) / (ib.hi - ib.lo), &b);
            if (st != CD_OK) { restore_start(m, d, I, t0, ystate); return st; }
        }
    }
    st = illinois(m, d, I, t0, h, 0, &b);
    if (st != CD_OK) { restore_start(m, d, I, t0, ystate); return st; }
    /* land at the upper end (exactly at the step's end if the bracket never moved) */
    d->y = ystate;
    memcpy(d->y, I->yhi, (size_t)m->ny * sizeof(double));
    d->t = b.hi == h ? t1 : t0 + b.hi;
    st = cd_forward(m, d);
    d->stats.nrhs++;
    if (st != CD_OK) { restore_start(m, d, I, t0, ystate); return st; }
    (void)gmin(m, d, 1, trigger, NULL);
    return CD_OK;
}

/* auto: change stepper (counted in stats; not an event of the model: the
 * event log holds physical switches only) */
static void auto_switch(cd_data *d, cd_integ *I, int to_stiff, double rho)
{
    if (to_stiff) d->stats.nswitch_stiff++;
    else d->stats.nswitch_explicit++;
    d->stats.t_switch_last = d->t;
    I->stiff = to_stiff;
    I->auto_hits = 0;
    I->auto_since = 0;
    I->auto_tc = d->t;
    I->auto_ec = 0;
    if (!(rho >= 0)) I->auto_rate_exp = 0; /* a forced switch measured nothing (auto_check sets the rates) */
    gsl_odeiv2_evolve_reset(I->drv->e);
    gsl_odeiv2_step_reset(I->drv->s);
    gsl_odeiv2_step_reset(I->s_stiff);
    cd_rosw_invalidate(&I->rw);
    I->fsal = 1; /* d was evaluated at the end of the step: outputs stay valid */
    if (!to_stiff && rho > 0 && I->h > CD_AUTO_STIFF / rho) I->h = CD_AUTO_STIFF / rho;
}

/* auto: the stiffness check after an accepted step */
static void auto_check(const cd_model *m, cd_data *d, cd_integ *I)
{
    /* the step the stepper works at: the last one, or its proposal for the
     * next if larger (a step clipped by a sample, breakpoint or event is not
     * the stepper's choice) */
    double rho, h = d->stats.h_last > I->h ? d->stats.h_last : I->h, hmax = d->opt.h_max, reach, win, rate;
    int want;
    (void)m;
    I->auto_since++;
    if (--I->auto_next > 0) return;
    if (I->auto_every < CD_AUTO_EVERY) I->auto_every = CD_AUTO_EVERY;
    I->auto_next = I->auto_every;
    /* the window's evaluations per simulated second; a new window starts */
    win = d->t - I->auto_tc;
    rate = win > 0 ? I->auto_ec / win : HUGE_VAL;
    I->auto_tc = d->t;
    I->auto_ec = 0;
    rho = cd_rosw_spectral_radius(&I->rw, d->t, d->y);
    if (!(rho >= 0)) return;
    if (!I->stiff) {
        want = h * rho > CD_AUTO_STIFF;
    } else {
        /* the guess from rk8pd's stable step is ros34pw2's rule (its step costs 4 evaluations
         * and a factorisation, rk8pd's 13): msbdf's step is not bounded by stability, costs 2-3,
         * and starts at order 1 with a short step after every restart (a switch, an event),
         * where the guess asked for rk8pd after nearly every event (the Fig. 5 grasp twin: 21 874
         * evaluations with it, 16 941 without). With msbdf only the measured cost below decides. */
        want = 0;
        if (!CD_AUTO_BDF) {
            reach = rho > 0 ? CD_AUTO_STIFF / rho : HUGE_VAL;
            if (hmax > 0 && reach > hmax) reach = hmax;
            want = reach > CD_AUTO_COST_RATIO * h;
        }
        /* measured: a whole window after the switch's own costlier than rk8pd's before it */
        if (!want && I->auto_rate_exp > 0 && I->auto_since > I->auto_every && rate > I->auto_rate_exp &&
            rate < HUGE_VAL)
            want = 1;
    }
    if (!want) { I->auto_hits = 0; return; }
    if (++I->auto_hits >= 2) {
        const int to_stiff = !I->stiff;
        /* the stepper given up was measured costlier than the one taken
         * back, in its window before it was given up: the round trip was a
         * mistake, whichever rule asked for it; check less often */
        const double back = to_stiff ? I->auto_rate_imp : I->auto_rate_exp;
        if (back > 0 && rate > back && rate < HUGE_VAL) I->auto_every = 2 * I->auto_every < CD_AUTO_EVERY_MAX ? 2 * I->auto_every : CD_AUTO_EVERY_MAX;
        else I->auto_every = CD_AUTO_EVERY;
        I->auto_next = I->auto_every;
        I->auto_rate_exp = to_stiff && rate < HUGE_VAL ? rate : 0;
        I->auto_rate_imp = !to_stiff && rate < HUGE_VAL ? rate : 0;
        auto_switch(d, I, to_stiff, rho);
    }
}

static double next_dwell_end(const cd_model *m, const cd_data *d)
{
    int u;
    double t = HUGE_VAL;
    for (u = 0; u < m->nsw; u++)
        if (d->sw_nswitch[u] >= 2) {
            double e = d->sw_tswitch[u] + d->opt.dwell;
            if (e > d->t && e < t) t = e;
        }
    return t;
}

/* first schedule breakpoint after t */
static double next_break(const cd_model *m, double t)
{
    int lo = cd_count_le(m->breaks, m->nbreak, t);
    return lo < m->nbreak ? m->breaks[lo] : HUGE_VAL;
}

/* Switch the schedules' rows to those in force at d->t; logs one event per
 * actuator whose row changed. Returns 1 if any did. */
static int schedule_rows(const cd_model *m, cd_data *d, int log)
{
    int a, any = 0;
    for (a = 0; a < m->nu; a++) {
        int p;
        if (m->act_tbl_n[a] == 0) continue;
        p = cd_schedule_piece(m, a, d->t);
        if (p == d->act_piece[a]) continue;
        if (log) {
            cd_event ev;
            memset(&ev, 0, sizeof ev);
            ev.kind = CD_EV_SCHEDULE;
            ev.owner_kind = CD_OWNER_ACTUATOR;
            ev.owner = a;
            ev.slot = ev.body_a = ev.body_b = -1;
            ev.mode_from = d->act_piece[a];
            ev.mode_to = p;
            log_event(d, &ev);
        }
        d->act_piece[a] = p;
        any = 1;
    }
    return any;
}

/* The caller's inputs against the snapshot of the last call's end: returns 1
 * if any differs; with copy, the snapshot takes them. The callbacks count as
 * inputs too (compared by pointer). */
static int inputs_sync(const cd_model *m, cd_data *d, cd_integ *I, int copy)
{
    const double *src[4] = {d->ctrl, d->qfrc_applied, d->xfrc_applied, d->xfrc_body};
    int len[4] = {m->nu, m->nv, 6 * m->nbody, 6 * m->nbody}, k, i, diff = 0;
    double *p = I->in_snap;
    for (k = 0; k < 4; p += len[k], k++) {
        if (!diff && memcmp(p, src[k], (size_t)len[k] * sizeof(double)) != 0) diff = 1;
        if (copy) memcpy(p, src[k], (size_t)len[k] * sizeof(double));
    }
    for (i = 0; i < m->nuser; i++) {
        if (p[i] != (double)d->user_mode[i]) diff = 1;
        if (copy) p[i] = d->user_mode[i];
    }
    p += m->nuser;
    /* the clutched fingers' schedule origins (+inf holds a finger open) */
    if (m->nfinger > 0) {
        if (memcmp(p, d->finger_t0, (size_t)m->nfinger * sizeof(double)) != 0) diff = 1;
        if (copy) memcpy(p, d->finger_t0, (size_t)m->nfinger * sizeof(double));
    }
    if (I->ctl_fn != d->control || I->ctl_user != d->control_user || I->sw_fn != d->user_switch ||
        I->tr_fn != d->user_transition || I->sw_user != d->switch_user)
        diff = 1;
    if (copy) {
        I->ctl_fn = d->control; I->ctl_user = d->control_user;
        I->sw_fn = d->user_switch; I->tr_fn = d->user_transition; I->sw_user = d->switch_user;
    }
    return diff;
}
static int inputs_changed(const cd_model *m, cd_data *d, cd_integ *I) { return inputs_sync(m, d, I, 0); }
static void inputs_get(const cd_model *m, cd_data *d, cd_integ *I) { (void)inputs_sync(m, d, I, 1); }

static void remember_end(const cd_model *m, cd_data *d, cd_integ *I)
{
    memcpy(I->y_end, d->y, (size_t)m->ny * sizeof(double));
    inputs_get(m, d, I);
    I->t_end = d->t;
    I->have_end = 1;
}

static void seterr(cd_error *err, cd_status st, const char *msg, double t)
{
    if (!err) return;
    err->status = st;
    snprintf(err->msg, sizeof err->msg, "%s at t = %.9g s", msg, t);
}

/* A numeric failure names its cause when it is a non-finite input (issue 24:
 * a NaN in d->ctrl was reported as "non-finite state or singular mass
 * matrix"): the first non-finite ctrl, qfrc_applied, xfrc_applied or
 * xfrc_body element, with the actuator or body it belongs to. */
static int nonfinite_input(const cd_model *m, const cd_data *d, char *buf, size_t len)
{
    int i;
    const char *nm;
    for (i = 0; i < m->nu; i++)
        if (!isfinite(d->ctrl[i])) {
            nm = m->act_name && m->act_name[i] && m->act_name[i][0] ? m->act_name[i] : NULL;
            snprintf(buf, len, "d->ctrl[%d] (actuator %s%s%s) is %s", i, nm ? "'" : "", nm ? nm : "unnamed",
                     nm ? "'" : "", isnan(d->ctrl[i]) ? "NaN" : "infinite");
            return 1;
        }
    for (i = 0; i < m->nv; i++)
        if (!isfinite(d->qfrc_applied[i])) {
            snprintf(buf, len, "d->qfrc_applied[%d] is %s", i, isnan(d->qfrc_applied[i]) ? "NaN" : "infinite");
            return 1;
        }
    for (i = 0; i < 6 * m->nbody; i++) {
        const double *w = !isfinite(d->xfrc_applied[i]) ? d->xfrc_applied : !isfinite(d->xfrc_body[i]) ? d->xfrc_body : NULL;
        if (!w) continue;
        nm = m->body_name[i / 6] && m->body_name[i / 6][0] ? m->body_name[i / 6] : NULL;
        snprintf(buf, len, "d->%s[%d] (body %d%s%s%s) is %s", w == d->xfrc_applied ? "xfrc_applied" : "xfrc_body", i,
                 i / 6, nm ? " '" : ", unnamed", nm ? nm : "", nm ? "'" : "", isnan(w[i]) ? "NaN" : "infinite");
        return 1;
    }
    return 0;
}

static void numeric_err(const cd_model *m, const cd_data *d, cd_error *err, cd_status st, const char *msg, double t)
{
    char in[300], both[400];
    if (nonfinite_input(m, d, in, sizeof in)) {
        snprintf(both, sizeof both, "non-finite input: %s", in);
        seterr(err, st, both, t);
    } else {
        seterr(err, st, msg, t);
    }
}

/* Start of a call: runtime options, and what the caller changed since the
 * last one. Returns 1 if the modes must be re-checked before stepping. */
static int begin_call(const cd_model *m, cd_data *d, cd_integ *I, cd_status *st, cd_error *err)
{
    int state_changed, need = 0;
    *st = CD_OK;
    if (cd_options_check(&d->opt, err) != CD_OK) { *st = CD_EINVAL; return 0; }
    if (d->opt.stepper != I->stepper) {
        cd_error_set(err, CD_EINVAL, "opt.stepper cannot change after cd_data_create");
        *st = CD_EINVAL;
        return 0;
    }
    I->m = m;
    I->rw.m = m;
    I->nrhs0 = d->stats.nrhs;
    if (I->fixed && d->opt.h_fixed != I->hfix_set) { /* a runtime option: the new fixed step from now on */
        I->h = d->opt.h_fixed;
        I->hfix_set = d->opt.h_fixed;
    }
    if (!I->fixed && (d->opt.rtol != I->rtol_set || d->opt.atol != I->atol_set)) {
        gsl_odeiv2_control_init(I->drv->c, d->opt.atol, d->opt.rtol, 1.0, 1.0);
        I->rtol_set = d->opt.rtol;
        I->atol_set = d->opt.atol;
    }
    state_changed = !I->have_end || d->t != I->t_end || memcmp(d->y, I->y_end, (size_t)m->ny * sizeof(double)) != 0;
    if (state_changed) schedule_rows(m, d, 0);
    if (state_changed || inputs_changed(m, d, I) || I->restart_pending) {
        restart(d, I);
        I->restart_pending = 0;
        need = 1;
    }
    if (!I->fsal) need = 1; /* outputs may be stale (e.g. a cd_forward on another state) */
    return need;
}

/* A diverged explicit step. GSL's standard control accepts a step when
 * |err_i| <= atol + rtol (|y1_i| + h |f(t1, y1)_i|). Far past its stability
 * limit (h |lambda| of tens: a stick damper on a light fingertip after an
 * event, with the step kept from before it) an explicit step's stages grow
 * by ~ (h lambda)^s, and f(t1, y1) grows faster than y1 and the error, so the
 * test passes: Fig. 5 with h_max = 0.05 "accepted" a 4.7 ms step ending at
 * |y| ~ 1e109. Measured with the derivative at the start, which is the
 * accepted state's, such a step fails by orders of magnitude; an honest step
 * passes the test with either derivative unless f changed tenfold within
 * it (then it was not resolved either). So a step whose error exceeds
 * CD_DIVERGED times that tolerance is rejected like a step that overflowed
 * (auto hands it to the stiff stepper, the others retry at a quarter). */
#define CD_DIVERGED 10.0
static int diverged(const cd_model *m, const cd_integ *I, const double *y1, const double *yerr, double h)
{
    int i;
    for (i = 0; i < m->ny; i++) {
        double tol = I->atol_set + I->rtol_set * (fabs(y1[i]) + h * fabs(I->f0chk[i]));
        if (!(fabs(yerr[i]) <= CD_DIVERGED * tol)) return 1;
    }
    return 0;
}

/* *started is set once the call got past its argument and option checks
 * (a rejected call leaves no trace: the next one still sees the caller's
 * changes). */
static cd_status advance(const cd_model *m, cd_data *d, double t_end, cd_step_callback cb, void *user,
                         cd_error *err, int *started)
{
    cd_integ *I = (cd_integ *)d->integ;
    long attempts = 0;
    int changed, need_settle, hit_break = 0;
    cd_status st;
    *started = 0;
    if (!(t_end >= d->t) || !isfinite(t_end)) {
        seterr(err, CD_EINVAL, "t_end must be finite and not before the current time", d->t);
        return CD_EINVAL;
    }
    need_settle = begin_call(m, d, I, &st, err);
    if (st != CD_OK) return st;
    *started = 1;
    while (d->t < t_end) {
        double t0 = d->t, t1 = t_end, tdw, tbr, g1;
        const long nrhs0 = d->stats.nrhs; /* auto: this step's evaluations, its event's included (but not
                                           * those before a contact change restarted the window) */
        int status, at_dwell_end, at_break;
        /* a schedule breakpoint reached (rows, waypoints, clutch schedules):
         * new rows, restart, re-check the modes */
        if (schedule_rows(m, d, 1) || hit_break) { restart(d, I); need_settle = 1; }
        hit_break = 0;
        /* modes are re-checked on entry (the caller may have edited y or the
         * inputs), at breakpoints and where a dwell expired; after an
         * ordinary step the end-of-step evaluation has already shown them consistent */
        if (need_settle) {
            st = settle_modes(m, d, I, &changed);
            if (st != CD_OK) { numeric_err(m, d, err, st, "non-finite state or singular mass matrix", d->t); return st; }
            need_settle = 0;
            if (changed) {
                restart(d, I);
                I->fsal = 1;
                if (cb && cb(m, d, user)) { seterr(err, CD_EINTERRUPT, "stopped by the caller", d->t); return CD_EINTERRUPT; }
                if (inputs_changed(m, d, I)) { restart(d, I); need_settle = 1; inputs_get(m, d, I); continue; }
            }
        }
        tdw = next_dwell_end(m, d);
        at_dwell_end = tdw <= t1;
        if (at_dwell_end) t1 = tdw;
        tbr = next_break(m, t0);
        at_break = tbr <= t1;
        if (at_break) { t1 = tbr; at_dwell_end = at_dwell_end && tdw == tbr; }
        memcpy(I->y0, d->y, (size_t)m->ny * sizeof(double));
        if (I->fixed) {
            double h = I->h < t1 - t0 ? I->h : t1 - t0;
            status = rk4_step(I, t0, h, d->y, I->fsal);
            if (status == GSL_SUCCESS) d->t = (t1 - t0 <= I->h) ? t1 : t0 + h;
            attempts++;
        } else {
            double t = t0, hmax = d->opt.h_max;
            long before = (long)I->drv->e->failed_steps;
            if (hmax > 0 && I->h > hmax) I->h = hmax;
            /* msbdf refuses a step that grows by more than 1.5x (zero-stability), and evolve
             * then halves it: propose the step it accepts (bdf.h) */
            if (on_bdf(I)) I->h = cd_bdf_step_limit(&I->bdf, t0, I->h);
            /* a step that would end within round-off of t1 would leave a sliver
             * step of ~1e-17 s: aim just past t1 so GSL lands exactly on it */
            if (I->h >= (t1 - t0) * (1.0 - 1e-12) && I->h < (t1 - t0) * (1.0 + 1e-9)) I->h = (t1 - t0) * (1.0 + 1e-9);
            int check = I->fsal && !I->stiff &&
                        (I->autom || I->stepper == CD_STEP_RK8PD || I->stepper == CD_STEP_RKF45 ||
                         I->stepper == CD_STEP_RKCK);
            I->last_valid = 0;
            if (check) memcpy(I->f0chk, d->ydot, (size_t)m->ny * sizeof(double));
            status = gsl_odeiv2_evolve_apply(I->drv->e, I->drv->c, I->stiff ? I->s_stiff : I->drv->s, &I->sys, &t, t1,
                                             &I->h, d->y);
            d->stats.nrejected += (long)I->drv->e->failed_steps - before;
            attempts += 1 + (long)I->drv->e->failed_steps - before;
            if (status == GSL_SUCCESS && check && diverged(m, I, d->y, I->drv->e->yerr, t - t0)) {
                /* rejected: the step it took, not the next one GSL proposes, is cut */
                I->h = t - t0;
                status = GSL_EBADFUNC; /* counted below as a rejected step */
            }
            if (status == GSL_SUCCESS) d->t = t;
        }
        I->fsal = 0;
        if (status != GSL_SUCCESS) {
            restore_start(m, d, I, t0, d->y);
            /* A non-finite value inside a trial step whose start was finite:
             * an explicit step far beyond its stability limit overflows in
             * its stages. That is a step-size failure, not the model's: auto
             * hands the step to the stiff stepper, any other adaptive stepper
             * retries with a quarter of the step. A model that is non-finite
             * at every step size still stops with CD_ENUMERIC once the trial
             * step is below h_min. */
            if (status == GSL_EBADFUNC && !I->fixed) {
                d->stats.nrejected++;
                attempts++;
                restart(d, I);
                if (I->autom && !I->stiff) auto_switch(d, I, 1, -1.0);
                else I->h *= 0.25;
                I->fsal = 0;
                if (I->h >= d->opt.h_min && attempts < d->opt.max_steps && budget_left(d, I, 0)) continue;
                if (!budget_left(d, I, 0)) {
                    seterr(err, CD_EBUDGET, "evaluation budget (max_evals) of this call spent", d->t);
                    return CD_EBUDGET;
                }
            }
            if (status == GSL_EBADFUNC) {
                numeric_err(m, d, err, CD_ENUMERIC, "right-hand side produced a non-finite value", t0);
                return CD_ENUMERIC;
            }
            seterr(err, CD_ESTALL, "integrator step failed", t0);
            return CD_ESTALL;
        }
        clean_state(m, d);
        d->stats.nsteps++;
        d->stats.h_last = d->t - t0;
        if (d->stats.h_last < d->stats.h_min_seen && d->t < t1) d->stats.h_min_seen = d->stats.h_last;
        if (d->stats.h_last > d->stats.h_max_seen) d->stats.h_max_seen = d->stats.h_last;
        /* evaluate the end state: outputs and switching functions. The
         * adaptive steppers' last evaluation is usually f(t1, y1) (their
         * dydt_out): when it was at exactly this time and state (nothing
         * renormalised or prescribed since), d's outputs are already those
         * of the end state, bit for bit, and it is not repeated. */
        if (!I->fixed && I->last_valid && I->tlast == d->t && same_configuration(m, I->ylast, d->y)) {
            st = CD_OK;
            d->stats.nrhs_reused++;
        } else {
            st = cd_forward(m, d);
            d->stats.nrhs++;
        }
        if (st != CD_OK) {
            restore_start(m, d, I, t0, d->y);
            numeric_err(m, d, err, CD_ENUMERIC, "non-finite state after a step", t0);
            return CD_ENUMERIC;
        }
        I->fsal = 1;
        g1 = gmin(m, d, 1, NULL, I->g_end);
        if (at_dwell_end && d->t == t1) need_settle = 1;
        if (at_break && d->t == t1) hit_break = 1;
        if (g1 < 0) {
            int trig = -1;
            I->fsal = 0;
            st = locate(m, d, I, t0, d->t, g1, &trig);
            if (st != CD_OK) { seterr(err, st, "event location failed", t0); return st; }
            clean_state(m, d);
            /* the unit that crossed switches unconditionally (it is on the new side) */
            if (trig >= 0) (void)counted_switch(m, d, trig, 0);
            st = settle_modes(m, d, I, &changed);
            if (st != CD_OK) { seterr(err, st, "non-finite state at an event", d->t); return st; }
            restart(d, I);
            /* auto on rk8pd: an event (a contact closing) may have made the problem stiff, so the
             * stiffness check runs at the next step instead of up to 10 steps on, which rk8pd
             * spent at its stability cap (capture twin: 12 080 -> 11 467 evaluations;
             * space_gripper_cylinder 88 998 -> 78 980) */
            if (I->autom && !I->stiff) I->auto_next = 1;
            I->fsal = 1;
        }
        /* geometry failures are reported, never silent */
        {
            int k;
            for (k = 0; k < m->nslot; k++)
                if (d->slot_geomfail[k]) {
                    cd_event ev;
                    memset(&ev, 0, sizeof ev);
                    ev.kind = CD_EV_GEOM_FAIL;
                    ev.owner_kind = CD_OWNER_SLOT;
                    ev.owner = ev.slot = k;
                    ev.body_a = m->cp_body[m->slot_cp[k]];
                    ev.body_b = m->shape_body[m->slot_shape[k]];
                    ev.mode_from = ev.mode_to = d->slot_mode[k];
                    d->stats.nwarn_geom++;
                    log_event(d, &ev);
                }
        }
        if (I->autom) {
            /* the step as it ended: an event cut it short (h_last is the step before locate) */
            if (I->stiff) d->stats.t_stiff += d->t - t0;
            I->auto_ec += (double)(d->stats.nrhs - (nrhs0 > I->auto_nrhs_reset ? nrhs0 : I->auto_nrhs_reset));
            auto_check(m, d, I);
        }
        if (!I->fixed && I->h < d->opt.h_min && d->t < t_end) {
            seterr(err, CD_ESTALL, "step size fell below h_min (stiff or discontinuous dynamics)", d->t);
            return CD_ESTALL;
        }
        if (cb) {
            inputs_get(m, d, I);
            if (cb(m, d, user)) { seterr(err, CD_EINTERRUPT, "stopped by the caller", d->t); return CD_EINTERRUPT; }
            /* inputs written by the callback take effect from this instant */
            if (inputs_changed(m, d, I)) { restart(d, I); need_settle = 1; }
        }
        if (attempts >= d->opt.max_steps) {
            seterr(err, CD_EMAXSTEPS, "step budget (max_steps) exhausted", d->t);
            return CD_EMAXSTEPS;
        }
        if (d->opt.max_evals > 0 && d->stats.nrhs - I->nrhs0 >= d->opt.max_evals && d->t < t_end) {
            seterr(err, CD_EBUDGET, "evaluation budget (max_evals) of this call spent", d->t);
            return CD_EBUDGET;
        }
    }
    /* a schedule row that starts exactly at t_end belongs to the next call */
    return CD_OK;
}

void cd_integ_locator_counts(const cd_data *d, long *ntrial, long *nfail)
{
    const cd_integ *I = (const cd_integ *)d->integ;
    *ntrial = I ? I->bdf.ntrial : 0;
    *nfail = I ? I->bdf.ntrial_fail : 0;
}

cd_status cd_sim_advance(const cd_model *m, cd_data *d, double t_end, cd_step_callback cb, void *user,
                         cd_error *err)
{
    if (!m || !d) {
        cd_error_set(err, CD_EINVAL, "cd_sim_advance: %s is NULL", !m ? "the model" : "the data");
        return CD_EINVAL;
    }
    cd_integ *I = (cd_integ *)d->integ;
    int started;
    cd_status st = advance(m, d, t_end, cb, user, err, &started);
    if (started) remember_end(m, d, I);
    I->m = NULL;
    I->rw.m = NULL;
    return st;
}

cd_status cd_step(const cd_model *m, cd_data *d, double h, cd_error *err)
{
    if (!m || !d) {
        cd_error_set(err, CD_EINVAL, "cd_step: %s is NULL", !m ? "the model" : "the data");
        return CD_EINVAL;
    }
    cd_integ *I = (cd_integ *)d->integ;
    double t_target, hsave = I->h;
    int started;
    cd_status st;
    if (!(h > 0) || !isfinite(h)) {
        cd_error_set(err, CD_EINVAL, "cd_step: h must be positive and finite, got %g", h);
        return CD_EINVAL;
    }
    if (I->fixed && d->opt.max_evals > 0 && d->opt.max_evals < CD_STEP_MIN_EVALS) {
        cd_error_set(err, CD_EBUDGET,
                     "cd_step: max_evals %ld cannot cover a fixed step with an event (at least %d: the re-check of a "
                     "changed input 5, the step 4, the event's bracket start 1 and reserve %d)",
                     d->opt.max_evals, CD_STEP_MIN_EVALS, CD_BUDGET_RESERVE);
        return CD_EBUDGET;
    }
    /* the time grid: a new origin where h changes or the caller moved t */
    if (h != I->step_h || !I->have_end || d->t != I->step_t0 + (double)I->step_k * I->step_h) {
        I->step_t0 = d->t;
        I->step_h = h;
        I->step_k = 0;
    }
    t_target = I->step_t0 + (double)(I->step_k + 1) * h;
    if (I->fixed) I->h = t_target - d->t;
    st = advance(m, d, t_target, NULL, NULL, err, &started);
    if (I->fixed) I->h = hsave;
    if (st == CD_OK) I->step_k++;
    if (started) remember_end(m, d, I);
    I->m = NULL;
    I->rw.m = NULL;
    return st;
}

/* ---- the integrator's part of the complete state ------------------------------ */
#define INTEG_FIXED_WORDS 19

int cd_integ_state_size(const cd_model *m)
{
    return INTEG_FIXED_WORDS + m->ny + m->nu + m->nv + 12 * m->nbody + m->nuser + m->nfinger;
}

void cd_integ_state_get(const cd_model *m, cd_data *d, double *b)
{
    cd_integ *I = (cd_integ *)d->integ;
    /* a stepper with a history inside GSL restarts here, in this run as in
     * any run restored from this snapshot */
    if (I->history) I->restart_pending = 1;
    b[0] = I->h; b[1] = I->t_end; b[2] = I->step_t0; b[3] = I->step_h; b[4] = (double)I->step_k;
    b[5] = I->have_end; b[6] = I->fsal; b[7] = I->restart_pending; b[8] = I->rtol_set; b[9] = I->atol_set;
    b[10] = I->stiff; b[11] = I->auto_hits; b[12] = (double)I->auto_next;
    b[13] = (double)I->auto_every; b[14] = (double)I->auto_since;
    b[15] = I->auto_tc; b[16] = I->auto_ec; b[17] = I->auto_rate_exp; b[18] = I->auto_rate_imp;
    memcpy(b + INTEG_FIXED_WORDS, I->y_end, (size_t)m->ny * sizeof(double));
    memcpy(b + INTEG_FIXED_WORDS + m->ny, I->in_snap, (size_t)I->nin * sizeof(double));
}

/* cd_state_set's check of the integrator's part, before anything changes:
 * 0, or -1 with why naming the first bad word. */
int cd_integ_state_check(const cd_model *m, const double *b, char *why, size_t len)
{
    static const char *const fixed[INTEG_FIXED_WORDS] = {"step size h", "end time", "cd_step origin",
                                                       "cd_step step", "cd_step step count", "end flag",
                                                       "FSAL flag", "restart flag", "rtol", "atol",
                                                       "auto stepper flag", "auto check agreements",
                                                       "auto steps to the next check", "auto check interval",
                                                       "auto steps since the last switch", "auto check window start",
                                                       "auto evaluations in the window", "auto rk8pd cost rate",
                                                       "auto ros34pw2 cost rate"};
    int i, n = cd_integ_state_size(m);
    for (i = 0; i < INTEG_FIXED_WORDS; i++) {
        double v = b[i];
        int ok = isfinite(v);
        /* kinds: a finite number (end time, cd_step origin, window start), 0 or 1
         * (flags), a whole number >= 0 (counts), else a finite number >= 0 */
        const int any = i == 1 || i == 2 || i == 15, flag = (i >= 5 && i <= 7) || i == 10,
                  whole = i == 4 || (i >= 11 && i <= 14) || i == 16;
        if (ok && !any) ok = v >= 0;
        if (ok && whole) ok = v <= 9007199254740992.0 && v == floor(v);
        if (ok && flag) ok = v == 0 || v == 1;
        if (!ok) {
            snprintf(why, len, "the integrator's %s is %.17g (%s)", fixed[i], v,
                     whole ? "expected a whole number >= 0" : flag ? "expected 0 or 1"
                     : any ? "expected a finite number" : "expected a finite number >= 0");
            return -1;
        }
    }
    for (i = INTEG_FIXED_WORDS; i < n; i++)
        if (!isfinite(b[i]) && !(i >= n - m->nfinger && b[i] == HUGE_VAL)) { /* a schedule origin may be +inf */
            snprintf(why, len, "the integrator's %s value %d is %.17g (expected a finite number%s)",
                     i < INTEG_FIXED_WORDS + m->ny ? "saved end state" : "saved input", i - INTEG_FIXED_WORDS -
                     (i < INTEG_FIXED_WORDS + m->ny ? 0 : m->ny), b[i], i >= n - m->nfinger ? " or +inf" : "");
            return -1;
        }
    return 0;
}

void cd_integ_state_set(const cd_model *m, cd_data *d, const double *b)
{
    cd_integ *I = (cd_integ *)d->integ;
    I->h = b[0]; I->t_end = b[1]; I->step_t0 = b[2]; I->step_h = b[3]; I->step_k = (long)b[4];
    I->have_end = (int)b[5]; I->fsal = (int)b[6]; I->restart_pending = (int)b[7];
    I->stiff = I->autom && b[10] != 0; I->auto_hits = (int)b[11]; I->auto_next = (long)b[12];
    I->auto_every = (long)b[13]; I->auto_since = (long)b[14];
    I->auto_tc = b[15]; I->auto_ec = b[16]; I->auto_rate_exp = b[17]; I->auto_rate_imp = b[18];
    I->auto_nrhs_reset = 0; /* only ever read within the step that set it */
    memcpy(I->y_end, b + INTEG_FIXED_WORDS, (size_t)m->ny * sizeof(double));
    memcpy(I->in_snap, b + INTEG_FIXED_WORDS + m->ny, (size_t)I->nin * sizeof(double));
    /* callbacks are this process's: the restored data keeps its own, unchanged */
    I->ctl_fn = d->control; I->ctl_user = d->control_user;
    I->sw_fn = d->user_switch; I->tr_fn = d->user_transition; I->sw_user = d->switch_user;
    /* the GSL stepper: explicit ones keep nothing between steps but h; a
     * history stepper restarts (restart_pending is set in its snapshots) */
    if (I->drv) {
        gsl_odeiv2_evolve_reset(I->drv->e);
        gsl_odeiv2_step_reset(I->drv->s);
        if (b[8] != I->rtol_set || b[9] != I->atol_set) {
            gsl_odeiv2_control_init(I->drv->c, b[9], b[8], 1.0, 1.0);
            I->rtol_set = b[8];
            I->atol_set = b[9];
        }
    }
}
