/* Internal: actuation seam. */
#ifndef CD_ACTUATION_H
#define CD_ACTUATION_H
#include "capdyn/sim.h"
/* Writes d->tau (all nv entries) for time d->t and the current state. */
void cd_actuation(const cd_model *m, cd_data *d);
#endif
