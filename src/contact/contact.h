/* Internal contact interface used by the simulation layer. */
#ifndef CD_CONTACT_H
#define CD_CONTACT_H
#include "capdyn/sim.h"
#include <math.h>

/* The slip law of a no-pull contact is continued past its separation guard
 * (discontinuity locking, docs/contact.md "Between events: each mode's law
 * continued past its guards"): between events f_n = f_raw may turn negative
 * in the trial stages that overshoot a separation the locator has not found
 * yet (the normal law is continued there already), and the friction mu_k
 * f_n, with the bristle's cone, follows it smoothly instead of dropping to 0
 * at f_n = 0. The located solution never uses the continuation (the slot
 * opens where f_n reaches 0, to event_tol); what it removes is the kink on
 * the guard that cascaded rejected steps before every slipping separation
 * (docs/performance.md sections 13 and 14). A `pull` contact keeps no
 * friction while f_n < 0: that is its law, not a continuation.
 * 0: the friction dropped at f_n = 0 (the law before, a build-time
 * comparison: make BUILD=build-clip EXTRA_CFLAGS=-DCD_CONTACT_SLIP_SMOOTH=0). */
#ifndef CD_CONTACT_SLIP_SMOOTH
#define CD_CONTACT_SLIP_SMOOTH 1
#endif

/* |x|^p sign(x); p = 1: x */
static inline double cd_sgnpow(double x, double p)
{
    if (p == 1.0) return x;
    return x >= 0 ? pow(x, p) : -pow(-x, p);
}

/* The normal law's raw force (before the no-pull rule), one definition for
 * the evaluation (contact.c) and the structured Jacobian (jac.c):
 *   linear (paper eq. 3):       f = K x^p + D xdot^q
 *   Hunt-Crossley (1975):       f = K x^p + D |x|^p xdot^q
 * (signed powers). With dfx, dfv non-NULL: df/dx and df/dxdot, with |x| and
 * |xdot| floored (1e-12 m, 1e-9 m/s) where a power below 1 is infinitely
 * steep at 0 (the Jacobian only has to carry the stiff modes). */
static inline double cd_law_normal(const cd_contact_law *L, double x, double xd, double *dfx, double *dfv)
{
    double ax = fabs(x) > 1e-12 ? fabs(x) : 1e-12, axd = fabs(xd) > 1e-9 ? fabs(xd) : 1e-9;
    double xq = cd_sgnpow(xd, L->q);
    /* the linear law's derivatives in the order jac.c always used (bit for bit) */
    double dk = L->p == 1.0 ? L->K : L->K * L->p * pow(ax, L->p - 1.0);
    double dd = L->q == 1.0 ? L->D : L->D * L->q * pow(axd, L->q - 1.0);
    if (L->damping == CD_DAMP_HUNT_CROSSLEY) {
        double xp = L->p == 1.0 ? fabs(x) : pow(fabs(x), L->p);
        double kx = L->p == 1.0 ? 1.0 : L->p * pow(ax, L->p - 1.0); /* d|x|^p/d|x| */
        if (dfx) *dfx = dk + L->D * (x >= 0 ? 1.0 : -1.0) * kx * xq;
        if (dfv) *dfv = dd * xp;
        return L->K * cd_sgnpow(x, L->p) + L->D * xp * xq;
    }
    if (dfx) *dfx = dk;
    if (dfv) *dfv = dd;
    return L->K * cd_sgnpow(x, L->p) + L->D * xq;
}

/* Clears the broad phase's caches (d->slot_free, d->group_near): a fresh
 * data and a restored state start without them (cd_data_reset,
 * cd_state_set); the results never depend on them. */
void cd_contact_cache_clear(const cd_model *m, cd_data *d);

/* Evaluates every slot after cd_kinematics: fills the slot outputs, adds the
 * wrenches to d->body_fext and writes the anchors' derivatives into zdot
 * (3 per slot). zdot must be the data's own d->ydot + m->ny_slot_adr, the
 * same buffer at every evaluation: a slot the broad phase skipped at the
 * last evaluation and skips again keeps the zeros written then. */
void cd_contact_eval(const cd_model *m, cd_data *d, double *zdot);

/* Switching functions of slot k (g[0] normal, g[1] friction; negative =
 * leave the mode); see contact.c. */
void cd_contact_switch(const cd_model *m, const cd_data *d, int k, int forgive, double g[2]);
/* The same functions for the smallest of all switching functions (the
 * integrator's gmin): returns 0, g unset, for an open slot whose check point
 * is apart from its shape by more than its own radius (x < -r: both
 * functions positive, it cannot switch), else 1 with g as cd_contact_switch
 * gives it. Decided on the exact x, with or without the broad phase. */
int cd_contact_switch_near(const cd_model *m, const cd_data *d, int k, double g[2]);
/* Applies the transition slot k's functions call for at the current state
 * (after an evaluation); fills ev's kind, owner, modes and forces. Returns 1
 * if the mode changed (or the slip direction was re-anchored). */
int cd_contact_transition(const cd_model *m, cd_data *d, int k, int forgive, cd_event *ev);

#endif
