/* Internal: the explicit Prince-Dormand 8(7) stepper behind
 * simulation.integrator = "rk8pd" and the explicit side of "auto" (rk8.c). */
#ifndef CD_RK8_H
#define CD_RK8_H
#include <gsl/gsl_odeiv2.h>

#include "capdyn/sim.h"

/* The GSL stepper type (name "rk8pd", order 8). A step object bound to a
 * model and its data (cd_rk8_bind) works on the unknowns that can move:
 * everything but the stick anchors of the open contact slots, whose
 * derivative is exactly 0 (contact.c); unbound, on every unknown. The
 * model is reached through *mp, read at each step: the integrator's
 * per-call model pointer (NULL between calls: the data keeps no model
 * pointer), so a step while it is NULL works on every unknown. */
extern const gsl_odeiv2_step_type *cd_step_rk8pd;
void cd_rk8_bind(gsl_odeiv2_step *s, const cd_model *const *mp, const cd_data *d);

/* The unknowns that can move at d's current modes: every one but the stick
 * anchors of the open contact slots (derivative exactly 0, contact.c), as
 * runs [lo[i], hi[i]) in increasing order (capacity ny + 2 each); returns
 * their number. Without a model or data, or when m->ny is not ny: one run of
 * all ny. rk8pd and the linearly implicit steppers (rosw.c) step only these. */
int cd_moving_runs(const cd_model *m, const cd_data *d, int ny, int *lo, int *hi);

/* The unknowns the next step of s advances, as runs [lo[i], hi[i]) in
 * increasing order; returns the number of runs (tests). */
int cd_rk8_runs(gsl_odeiv2_step *s, const int **lo, const int **hi);

#endif
