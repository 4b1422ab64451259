/* capdyn: built-in capture controllers for a free-flying chaser (docs/capture.md).
 *
 * One controller drives the arm of a free-floating system (the chaser)
 * through the data's control callback and two of the model's user switches,
 * so that every phase change is a located event and the right-hand side is a
 * function of (t, state, phase) only:
 *   APPROACH  resolved-rate tracking of the grasp pose, which moves with the
 *             target: the palm's commanded twist is the fixture's twist plus a
 *             proportional pose error (the approach along the palm's finger
 *             axis is held back until the lateral error is small: the
 *             pre-grasp), mapped to joint rates by the generalized Jacobian of
 *             the free-floating chaser (damped least squares), then to joint
 *             torques by a rate servo with torque limits;
 *   CLOSING   from the located instant the palm's grasp point comes within
 *             trigger_distance of the fixture: the gripper's close command
 *             (ctrl of its actuators) is on, clutched fingers' closing
 *             schedules start (d->finger_t0), the tracking goes on;
 *   HOLD      close_time later (a located time event): joint impedance about
 *             the joint angles of that instant (the capture pose), absorbing
 *             the target's momentum;
 *   DETUMBLE  (optional) detumble_after later (a located time event): a
 *             damping wrench at the palm against the palm's twist relative
 *             to the base, scaled with the held target's inertia and limited
 *             per axis to what the grasp carries, applied through the arm's
 *             joints (tau = J^T W): the arm's joint rates, and with them the
 *             target's motion relative to the chaser, go to zero through the
 *             contacts; the attitude law then damps the base rate only.
 * Base attitude control (optional): a reaction-wheel torque on the base,
 * PD toward the initial attitude, each component limited; an external torque
 * on the chaser (the wheels' momentum is not modelled).
 * Outputs go to d->qfrc_applied (arm joints), d->xfrc_applied (base torque)
 * and d->ctrl (gripper actuators); nothing allocates after cd_ctrl_create and
 * nothing prints. The controller's memory (trigger, hold and detumble times,
 * the capture pose) lives in the cd_ctrl, not in the data: cd_state_get /
 * cd_state_set do not save it; cd_ctrl_state_get / cd_ctrl_state_set do
 * (save both, next to each other, for a checkpoint). */
#ifndef CAPDYN_CONTROL_H
#define CAPDYN_CONTROL_H

#include "capdyn/sim.h"

#ifdef __cplusplus
extern "C" {
#endif

#define CD_CTRL_MAX_ACT 16

typedef enum { CD_CTRL_APPROACH = 0, CD_CTRL_CLOSING = 1, CD_CTRL_HOLD = 2, CD_CTRL_DETUMBLE = 3 } cd_ctrl_phase;

typedef struct {
    int sys;                /* the chaser: a free-floating system */
    int palm;               /* palm body (a link of sys, or its base) */
    double palm_pos[3];     /* palm frame origin on the palm body, body frame [m] */
    double palm_rot[9];     /* palm frame -> palm body frame */
    int fixture_body;       /* body carrying the capture fixture (the target's) */
    double fixture_pos[3];  /* fixture centre on that body, body frame [m] */
    double fixture_rot[9];  /* fixture frame -> body frame */
    double grasp_point[3];  /* where the fixture centre is to be at the grasp, palm frame [m] */
    double grasp_rot[9];    /* palm frame at the grasp, fixture frame (palm -> fixture coordinates) */
    double approach_axis[3];/* palm-frame unit axis along which the palm closes in (held back until
                               the lateral error is below lateral_tol) */
    double lateral_tol;     /* [m] */
    double kp_pos, kp_rot;  /* pose-error gains [1/s] */
    double v_max, w_max;    /* limits of the commanded palm twist's feedback part [m/s], [rad/s] */
    double dls;             /* damped-least-squares factor [m/s per rad/s, i.e. m] (> 0) */
    double qd_max;          /* joint-rate command limit [rad/s] (the vector is scaled) */
    double rate_gain;       /* rate-servo bandwidth k_v [1/s]: tau_j = H_jj k_v (qd_ref_j - qd_j) */
    double tau_max;         /* |joint torque| limit of the arm [N m] (0 = none) */
    double trigger_distance;/* [m] */
    double close_time;      /* [s] from the trigger to HOLD */
    int nclose;             /* gripper actuators closed at the trigger */
    int close_act[CD_CTRL_MAX_ACT];
    double close_u[CD_CTRL_MAX_ACT]; /* their ctrl while closing and holding [N m] */
    int nclose_finger;      /* clutched fingers (space, torque_switch) whose closing schedule starts at the
                               trigger: d->finger_t0 = +inf before it, the trigger time from then on */
    int close_finger[CD_CTRL_MAX_ACT];
    double imp_wn, imp_zeta;/* HOLD joint impedance: natural frequency w_n [rad/s] and damping ratio zeta:
                               tau_j = H_jj (w_n^2 (q_c_j - q_j) - 2 zeta w_n qd_j) */
    int attitude;           /* 1: base attitude control on */
    double att_kp, att_kd;  /* [N m/rad], [N m s/rad] */
    double att_tau_max;     /* per-axis wheel torque limit [N m] (> 0) */
    int start_hold;         /* 1: HOLD from the start, about the model's initial joint angles, the
                               gripper closed (a target already held); 0 (default): APPROACH */
    int detumble;           /* 1: DETUMBLE detumble_after seconds after HOLD began (needs a third user switch) */
    double detumble_after;  /* [s] from HOLD to DETUMBLE (>= 0) */
    double detumble_gain;   /* DETUMBLE gain k_d [1/s] (> 0): the palm's wrench (at its grasp point, palm axes)
                               W_i = -sat(k_d M_i V_i, W_max,i) against its twist V relative to the base, M_i
                               the held target's mass (forces) or moment of inertia about that axis (moments) */
    double detumble_f_max;  /* [N] W_max of the three force components (> 0) */
    double detumble_n_max[3]; /* [N m] W_max of the moments about the palm's x, y, z (> 0): what the grasp
                               carries without slipping or back-driving the fingers */
    int detumble_base;      /* 1: while detumbling, the attitude law damps the base rate only (k_p = 0), bringing
                               the combined body to rest where it is; 0: it goes on turning it back */
    int user_switch0;       /* the first of the user switches it uses (two; three with detumble) */
} cd_ctrl_config;

/* Defaults: gains kp 1 /s, v_max 0.1 m/s, w_max 0.2 rad/s, dls 0.05 m,
 * qd_max 0.2 rad/s, rate_gain 20 /s, no torque limit, trigger 0.02 m,
 * close_time 1 s, imp_wn 1 rad/s, imp_zeta 1, attitude off (kp 500,
 * kd 2000, limit 1 N m), approach axis +y, lateral_tol 0.01 m, detumble off
 * (after 1 s, gain 1 /s, limits 10 N and 1 N m, base rate damping on); bodies -1. */
cd_ctrl_config cd_ctrl_config_default(void);

typedef struct cd_ctrl cd_ctrl;

/* A controller for model m (finalized, with at least user_switch0 + 2 user
 * switches). Checks the configuration; NULL with err filled (CD_EINVAL,
 * CD_ENOMEM). The config is copied. */
cd_ctrl *cd_ctrl_create(const cd_model *m, const cd_ctrl_config *c, cd_error *err);
/* Frees; NULL is a no-op. */
void cd_ctrl_free(cd_ctrl *c);
/* Installs c as d's control callback and user switches. */
void cd_ctrl_install(cd_ctrl *c, cd_data *d);
/* The control callback and the switch functions (installed by cd_ctrl_install;
 * exposed for callers that chain their own law). user is the cd_ctrl. */
void cd_ctrl_control(const cd_model *m, cd_data *d, void *user);
double cd_ctrl_switch(const cd_model *m, const cd_data *d, int i, void *user);
int cd_ctrl_transition(const cd_model *m, cd_data *d, int i, void *user);
/* Phase of d (its user modes), time of the trigger (NaN before), time HOLD
 * began (NaN before), time DETUMBLE began (NaN before). */
cd_ctrl_phase cd_ctrl_phase_of(const cd_ctrl *c, const cd_data *d);
double cd_ctrl_t_trigger(const cd_ctrl *c);
double cd_ctrl_t_hold(const cd_ctrl *c);
double cd_ctrl_t_detumble(const cd_ctrl *c);
/* The controller's memory, for checkpoints next to cd_state_get: the
 * trigger, HOLD and DETUMBLE times and the capture pose (the joint angles
 * HOLD holds). The phase itself is in the data's user modes (cd_state_get).
 * cd_ctrl_state_size: doubles (3 + 2 + the arm's joints). cd_ctrl_state_get
 * copies it into buf (caller-owned, that size). cd_ctrl_state_set restores
 * it into c, a controller of the same configuration's model (possibly
 * another cd_ctrl, as after a restart): CD_EINVAL with err filled (err may
 * be NULL) if buf is not a controller state of this size, c unchanged.
 * Restoring the data's state and the controller's together and continuing
 * is bit-identical to not having stopped. */
size_t cd_ctrl_state_size(const cd_ctrl *c);
void cd_ctrl_state_get(const cd_ctrl *c, double *buf);
cd_status cd_ctrl_state_set(cd_ctrl *c, const double *buf, cd_error *err);
/* Base attitude error (rotation angle from the initial attitude) [rad], after cd_kinematics. */
double cd_ctrl_base_angle(const cd_ctrl *c, const cd_model *m, const cd_data *d);

/* Figures of merit of a capture run (docs/capture.md), kept sample by sample. */
typedef struct {
    int target;             /* the target system (the fixture's) */
    double P0[3], L0[3];    /* the chaser's momenta at init: linear [kg m/s], angular about the world origin [kg m^2/s] */
    double dP[3], dL[3];    /* momentum transferred to the chaser: now - at init */
    double base_angle_max;  /* largest base rotation from its initial attitude [rad] */
    double base_rate;       /* base angular speed at the last update [rad/s] */
    double v_rel, w_rel;    /* target relative to the chaser base at the last update: speed of the target's
                               CoM relative to the base's rigid motion [m/s], angular speed [rad/s] */
    double tau_arm_max;     /* largest |torque| the controller applied to an arm joint, over the updates [N m] */
} cd_ctrl_merit;
/* Starts the figures of merit at d's current state (after cd_kinematics). */
void cd_ctrl_merit_init(cd_ctrl_merit *f, const cd_ctrl *c, const cd_model *m, const cd_data *d);
/* Updates them (after an evaluation, e.g. at every output sample). */
void cd_ctrl_merit_update(cd_ctrl_merit *f, const cd_ctrl *c, const cd_model *m, const cd_data *d);

#ifdef __cplusplus
}
#endif
#endif
