/* Internal contact interface used by the simulation layer. */
#ifndef CD_CONTACT_H
#define CD_CONTACT_H
#include "capdyn/sim.h"

/* Evaluates every slot after cd_kinematics: fills the slot outputs, adds the
 * wrenches to d->body_fext and writes the anchors' derivatives into zdot
 * (3 per slot). */
void cd_contact_eval(const cd_model *m, cd_data *d, double *zdot);

/* Switching functions of slot k (negative = leave the mode); see contact.c. */
void cd_contact_switch(const cd_model *m, const cd_data *d, int k, double *g_norm, double *g_fric);

#endif
