/* Internal: the generic switch table. Switch units 0..nsw-1 are, in order,
 * the contact slots, the joint stops, the joint frictions and the user
 * switches; each has up to two switching functions (negative = leave the
 * mode) and a transition owned by its provider (src/contact/ for slots,
 * src/mechanism/ for stops and friction, the caller's callbacks for user
 * switches). The integrator only locates, logs and counts. */
#ifndef CD_SWITCH_H
#define CD_SWITCH_H
#include "capdyn/sim.h"

/* 1 if unit u is not watched now (a slot whose geometry failed, a user
 * switch without callbacks). */
int cd_sw_skip(const cd_model *m, const cd_data *d, int u);
/* Unit u's functions at the current evaluation. forgive pardons round-off in
 * zero-time re-checks (friction functions only). */
void cd_sw_functions(const cd_model *m, const cd_data *d, int u, int forgive, double g[2]);
/* Applies unit u's transition at the current (landed) state; fills ev
 * (except t). Returns 1 if the unit switched. */
int cd_sw_transition(const cd_model *m, cd_data *d, int u, int forgive, cd_event *ev);

#endif
