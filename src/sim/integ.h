/* Internal: integrator state owned by cd_data. */
#ifndef CD_INTEG_H
#define CD_INTEG_H
#include "capdyn/sim.h"

/* Bytes of the integrator's state and buffers (a region of the data's block). */
size_t cd_integ_size(const cd_model *m);
/* The part of it taken by the implicit steppers' dense matrices (0 for the explicit ones). */
size_t cd_integ_stiff_size(const cd_model *m);
/* Sets up the integrator of d in mem (cd_integ_size bytes, 16-aligned) and
 * allocates GSL's stepper objects; NULL with err. */
void *cd_integ_create(const cd_model *m, cd_data *d, void *mem, cd_error *err);
/* Frees GSL's objects (the region itself belongs to the data's block). */
void cd_integ_free(void *integ);
/* Back to the start of a run: step size, guard, stepper history. */
void cd_integ_reset(const cd_model *m, cd_data *d);
/* Closes every slot and stop whose switching function says it is in contact
 * at the current state (used at reset), and with opt.equilibrium_start
 * preloads them to static equilibrium (src/sim/equilibrium.c). */
cd_status cd_integ_initial_modes(const cd_model *m, cd_data *d, cd_error *err);

/* The integrator's part of the complete state (cd_state_*). */
int cd_integ_state_size(const cd_model *m);
void cd_integ_state_get(const cd_model *m, cd_data *d, double *buf);
void cd_integ_state_set(const cd_model *m, cd_data *d, const double *buf);
/* Doubles of the state after the header up to the integrator's part: t and
 * the arrays (state.c); the size of cd_data's undo area. */
size_t cd_state_body_size(const cd_model *m);
/* 0 if the integrator's part of a state buffer is valid, else -1 and why
 * (every word finite, flags 0 or 1, counts whole, h and tolerances >= 0). */
int cd_integ_state_check(const cd_model *m, const double *buf, char *why, size_t len);

/* dst takes what an evaluation needs of src's state (state.c; the sampler). */
void cd_state_copy_eval(const cd_model *m, cd_data *dst, const cd_data *src);

/* msbdf's own locator trials (cd_bdf_trial) in this data so far: solved,
 * and refused or failed (each failure fell back to rk8pd sub-steps); tests. */
void cd_integ_locator_counts(const cd_data *d, long *ntrial, long *nfail);

/* Static equilibrium of the closed contacts and stops (equilibrium.c). */
cd_status cd_equilibrium_start(const cd_model *m, cd_data *d, cd_error *err);

#endif
