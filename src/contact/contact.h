/* Internal contact interface used by the simulation layer. */
#ifndef CD_CONTACT_H
#define CD_CONTACT_H
#include "capdyn/sim.h"

/* Evaluates every slot after cd_kinematics: fills the slot outputs, adds the
 * wrenches to d->body_fext and writes the anchors' derivatives into zdot
 * (3 per slot). */
void cd_contact_eval(const cd_model *m, cd_data *d, double *zdot);

/* Switching functions of slot k (g[0] normal, g[1] friction; negative =
 * leave the mode); see contact.c. */
void cd_contact_switch(const cd_model *m, const cd_data *d, int k, int forgive, double g[2]);
/* Applies the transition slot k's functions call for at the current state
 * (after an evaluation); fills ev's kind, owner, modes and forces. Returns 1
 * if the mode changed (or the slip direction was re-anchored). */
int cd_contact_transition(const cd_model *m, cd_data *d, int k, int forgive, cd_event *ev);

#endif
