/* Internal: integrator state owned by cd_data. */
#ifndef CD_INTEG_H
#define CD_INTEG_H
#include "capdyn/sim.h"

void *cd_integ_create(const cd_model *m, cd_data *d, cd_error *err);
void cd_integ_free(void *integ);
void cd_integ_reset(const cd_model *m, cd_data *d);
/* Closes (stick) every slot whose switching function says it is in contact
 * at the current state; used at reset. */
void cd_integ_initial_modes(const cd_model *m, cd_data *d);

#endif
