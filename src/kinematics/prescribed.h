/* Internal: prescribed joint and base motion (src/kinematics/prescribed.c). */
#ifndef CD_PRESCRIBED_H
#define CD_PRESCRIBED_H
#include "capdyn/sim.h"

/* Prescribed motion of joint body b at time t: position, rate, acceleration. */
void cd_prescribed_joint(const cd_model *m, int b, double t, double *q, double *qd, double *qdd);
/* Writes every prescribed coordinate of y (positions and rates, bases
 * included) for time t; used before each evaluation and after each step. */
void cd_prescribed_apply(const cd_model *m, double t, double *y);

#endif
