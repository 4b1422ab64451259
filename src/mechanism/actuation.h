/* Internal: actuators, transmissions, joint elements (springs, dampers,
 * Coulomb friction, compliant stops) and prescribed joint motion. */
#ifndef CD_ACTUATION_H
#define CD_ACTUATION_H
#include "capdyn/sim.h"

/* Actuator torques at (d->t, state): writes act_velocity, act_force and
 * qfrc_actuator (all nv entries). Schedules use the row in d->act_piece. */
void cd_actuation(const cd_model *m, cd_data *d);
/* Joint springs, dampers, friction and stops: writes qfrc_passive (all nv),
 * lim_* and fric_*, and the friction anchors' rates into zdot (nfric). */
void cd_joint_passive(const cd_model *m, cd_data *d, double *zdot);

/* Row of actuator a's schedule in force at time t (right-continuous): the
 * number of rows whose time is <= t. */
int cd_schedule_piece(const cd_model *m, int a, double t);

/* Switch providers (see src/sim/switch.c). Unit i of each kind; g[0], g[1]
 * its switching functions (negative = leave the mode). */
void cd_limit_functions(const cd_model *m, const cd_data *d, int i, double g[2]);
int cd_limit_transition(const cd_model *m, cd_data *d, int i, cd_event *ev);
void cd_fric_functions(const cd_model *m, const cd_data *d, int i, int forgive, double g[2]);
int cd_fric_transition(const cd_model *m, cd_data *d, int i, cd_event *ev);

/* Clutched fingers (gripper.c): coupling or equal-pressure torques added to
 * qfrc_actuator; their switch provider. */
void cd_gripper_torques(const cd_model *m, cd_data *d);
void cd_finger_functions(const cd_model *m, const cd_data *d, int i, double g[2]);
int cd_finger_transition(const cd_model *m, cd_data *d, int i, cd_event *ev);

#endif
