/* capdyn: simulation data (cd_data) and its state layout.
 *
 * A cd_data holds everything that changes during a run: the continuous state
 * y, the discrete modes of every switch (contact slots, joint stops, joint
 * friction, user switches), the inputs the caller writes between calls, the
 * outputs of the last evaluation and all work space. It is created from a
 * finalized model and keeps no pointer to it: pass the model to every call.
 * All of its memory is one block taken at cd_data_create (from the caller's
 * allocator if one is given), except GSL's own stepper objects, which GSL
 * allocates itself. After creation nothing allocates except cd_state_copy
 * (one temporary buffer) and cd_data_reset with opt.equilibrium_start (the settle's work
 * space), both through the data's allocator. This header sits below dynamics, contact and the
 * integrator: it knows the layout, not the physics. */
#ifndef CAPDYN_DATA_H
#define CAPDYN_DATA_H

#include "capdyn/model.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum { CD_MODE_OPEN = 0, CD_MODE_STICK = 1, CD_MODE_SLIP = 2 } cd_slot_mode;
/* Modes of a joint stop unit and of a clutched finger. */
typedef enum { CD_LIM_FREE = 0, CD_LIM_LOWER = 1, CD_LIM_UPPER = 2 } cd_limit_mode;
typedef enum { CD_CLUTCH_ENGAGED = 0, CD_CLUTCH_RELEASED = 1 } cd_clutch_mode;

typedef enum {
    CD_EV_ONSET = 0,       /* open -> stick: penetration (or normal force) crosses 0 upward */
    CD_EV_SEPARATION,      /* stick/slip -> open: normal force or penetration crosses 0 */
    CD_EV_STICK_SLIP,      /* |f_t| reaches mu_s f_n (contact) or |tau| the Coulomb torque (joint) */
    CD_EV_SLIP_STICK,      /* slip velocity reverses against the slip direction */
    CD_EV_SLIP_TURN,       /* slip direction re-anchored (3-D slip turning past 90 deg) */
    CD_EV_GEOM_FAIL,       /* libccd returned a non-finite or inconsistent answer */
    CD_EV_LIMIT_ENGAGE,    /* a joint reaches its lower or upper stop */
    CD_EV_LIMIT_RELEASE,   /* the stop's force returns to zero */
    CD_EV_USER,            /* a user switch fired (cd_data_set_user_switches) */
    CD_EV_SCHEDULE,        /* an actuator's STEPS/TABLE row changed (owner: the actuator); waypoints
                              and clutch schedules end steps and restart the stepper, unlogged */
    CD_EV_CLUTCH,          /* a finger's clutch disengaged (load reached its threshold) or re-engaged (open) */
    CD_EV_NKINDS
} cd_event_kind;

/* What an event belongs to. */
typedef enum {
    CD_OWNER_SLOT = 0,     /* owner = contact slot */
    CD_OWNER_JOINT,        /* owner = joint body (stop, friction, prescribed waypoint) */
    CD_OWNER_ACTUATOR,     /* owner = actuator (schedule step) */
    CD_OWNER_USER,         /* owner = user switch index */
    CD_OWNER_FINGER,       /* owner = clutched finger */
    CD_OWNER_NKINDS
} cd_owner_kind;

/* Name of an event kind ("onset", "separation", "stick_slip", ...), owner kind
 * ("slot", "joint", "actuator", "user") and slot mode ("open", ...). */
const char *cd_event_kind_name(cd_event_kind k);
const char *cd_owner_kind_name(cd_owner_kind k);
const char *cd_slot_mode_name(cd_slot_mode m);

/* One logged event. Forces are those just before the switch. For a joint
 * stop x is the depth beyond the limit [rad | m], fn the stop's torque; for
 * joint friction ft is the friction torque. */
typedef struct {
    double t;             /* [s] */
    int kind;             /* cd_event_kind */
    int slot;             /* contact slot, -1 for other owners */
    int body_a, body_b;   /* check-point body, shape body (slot); joint body, -1 (joint) */
    int mode_from, mode_to;
    double x;             /* penetration [m] */
    double fn;            /* normal force [N] */
    double ft;            /* tangential force magnitude [N] */
    int owner_kind;       /* cd_owner_kind */
    int owner;            /* slot, joint body, actuator or user-switch index */
} cd_event;

/* Integrator and event statistics, cumulative since cd_data_reset(). */
typedef struct {
    long nrhs;            /* right-hand-side evaluations */
    long nswitch_stiff;   /* integrator "auto": switches to the stiff stepper (msbdf) */
    long nswitch_explicit;/* ... and back to the explicit one (rk8pd) */
    double t_stiff;       /* ... simulated time spent on the stiff stepper [s] */
    double t_switch_last; /* ... time of the last switch [s] (-1: none) */
    long nrhs_reused;     /* end-of-step evaluations saved: the stepper's last one was at the same (t, y) */
    long nsteps;          /* accepted steps */
    long nrejected;       /* rejected trial steps (adaptive) */
    long nevents;         /* events located */
    long nlocate_steps;   /* fixed steps spent locating events */
    long nlocate_interp;  /* event-locating iterations on the step's Hermite interpolant (one evaluation each) */
    long nwarn_geom;      /* bad libccd answers */
    long nwarn_dwell;     /* switches deferred by the dwell rule */
    long nwarn_budget;    /* events landed early because the per-call evaluation budget ran out */
    long nrenorm;         /* quaternion renormalisations */
    long nrestart;        /* stepper restarts (input changes, schedule steps, events, state sets) */
    long njac;            /* Jacobians formed by the ros34pw2 stepper (finite differences on the active set) */
    double h_last, h_min_seen, h_max_seen;
    double eq_residual;   /* equilibrium start: largest generalized acceleration left [m/s^2 | rad/s^2] */
    int eq_iterations;    /* equilibrium start: Newton iterations taken (0 = not used) */
} cd_stats;

struct cd_data;
/* Control callback: called at every right-hand-side evaluation, after the
 * kinematics of (d->t, d->y) and before the forces are assembled. It may
 * write d->ctrl, d->qfrc_applied, d->xfrc_applied and d->xfrc_body (a
 * continuous control law); it must not change anything else, allocate or
 * block. Its values must depend only on (t, state) for the integrator's
 * error control to be honest. */
typedef void (*cd_control_fn)(const cd_model *m, struct cd_data *d, void *user);
/* User switch i: its switching function (a negative value means "switch
 * now"; it must be continuous in (t, state) between events, and may read
 * d->user_mode[i]) and its transition (called once at the located crossing;
 * it updates d->user_mode[i] and anything the user keeps, and returns the
 * new mode). */
typedef double (*cd_user_switch_fn)(const cd_model *m, const struct cd_data *d, int i, void *user);
typedef int (*cd_user_transition_fn)(const cd_model *m, struct cd_data *d, int i, void *user);

/* Memory for one cd_data: one alloc at creation, one free at cd_data_free. */
typedef struct {
    void *(*alloc)(size_t size, void *ctx);
    void (*free)(void *ptr, void *ctx);
    void *ctx;
} cd_allocator;

/* Simulation data: state, modes, inputs, outputs of the last evaluation and
 * all the work space.
 * What the caller may write between calls: t, y (then the integrator
 * re-checks every mode and restarts its stepper), the inputs (ctrl,
 * qfrc_applied, xfrc_applied, xfrc_body, user_mode, and the callbacks
 * through their setters: a change takes effect exactly at the call
 * boundary, where the stepper restarts), opt (runtime options, see model.h).
 * Everything else is output or private. A call rejected for its arguments
 * (CD_EINVAL before any step) leaves no trace: the next call still sees the
 * changes. */
typedef struct cd_data {
    double t;             /* [s] */
    double *y;            /* (ny) continuous state, layout in docs/dynamics.md */
    double *ydot;         /* (ny) its derivative at the last evaluation */
    cd_options opt;       /* this data's options (copied from the model at creation) */

    /* inputs, written by the caller (or by the control callback) */
    double *ctrl;         /* (nu) actuator commands, added to each actuator's law [N m | N] */
    double *qfrc_applied; /* (nv) generalized forces added to every other [N m | N; base: f, n about CoM] */
    double *xfrc_applied; /* (nbody x 6) wrench on each body, world axes: [torque; force at the CoM] */
    double *xfrc_body;    /* (nbody x 6) wrench on each body, body axes: [torque; force at the CoM] */
    cd_control_fn control;   /* optional continuous control law (cd_data_set_control) */
    void *control_user;
    cd_user_switch_fn user_switch;
    cd_user_transition_fn user_transition;
    void *switch_user;
    int *user_mode;       /* (nuser) modes of the user switches, 0 at reset */

    /* kinematics (valid after cd_kinematics) */
    double *body_R;       /* (nbody x 9) body -> world rotation */
    double *body_x;       /* (nbody x 3) body frame origin (joint; base CoM) [m] */
    double *body_c;       /* (nbody x 3) CoM [m] */
    double *body_w;       /* (nbody x 3) angular velocity [rad/s] */
    double *body_v;       /* (nbody x 3) CoM velocity [m/s] */
    double *body_axisw;   /* (nbody x 3) joint axis in world */
    double *body_V;       /* (nbody x 6) spatial velocity about the system reference point */
    double *body_S;       /* (nbody x 6) joint motion subspace, spatial, about the reference point */
    double *sys_ref;      /* (nsys x 3) reference point of each system (base position) */

    /* generalized forces of the last evaluation (nv each) */
    double *udot;         /* generalized accelerations */
    double *qfrc_actuator;/* from the actuators through their transmissions */
    double *qfrc_passive; /* joint springs, dampers, Coulomb friction and stops */
    double *qfrc_constraint; /* what the prescribed joints/bases take to follow their profile */
    double *tau;          /* the total applied: actuator + passive + applied (the constraint is apart) */
    double *act_force;    /* (nu) actuator torque after the motor envelope [N m | N] */
    double *act_velocity; /* (nu) transmission rate sum_j ratio_j qdot_j [rad/s | m/s] */
    double *body_fext;    /* (nbody x 6) external wrench [n about ref; f], from contacts and inputs */
    double *H;            /* (maxdof x maxdof) scratch for one system's mass matrix */
    double *work;         /* (4 maxdof + 12 nbody) scratch */
    double *jwork;        /* (12 maxdof + 36) scratch of cd_generalized_jacobian */
    void *body_rbi;       /* (2 nbody) spatial inertias (private scratch) */
    double *ypresc;       /* (ny) y with the prescribed entries set to their profile (private) */

    /* contact slots (valid after an evaluation) */
    int *slot_mode;       /* cd_slot_mode (discrete, changed only at events) */
    double *slot_dir;     /* (nslot x 3) slip direction anchored at the last event */
    double *slot_tswitch; /* (nslot) time of the last switch [s] (= sw_tswitch) */
    double *slot_x;       /* (nslot) penetration, >0 inside [m] */
    double *slot_xdot;    /* (nslot) penetration rate [m/s] */
    double *slot_fn;      /* (nslot) normal force [N] (0 when open) */
    double *slot_ft;      /* (nslot x 3) tangential force on the check-point body [N] */
    double *slot_point;   /* (nslot x 3) contact point, world [m] */
    double *slot_normal;  /* (nslot x 3) unit normal, from shape toward check point */
    double *slot_vt;      /* (nslot x 3) tangential relative velocity at the contact point [m/s] */
    double *slot_va;      /* (nslot x 3) slip (anchor) velocity while slipping [m/s] */
    double *slot_fnraw;   /* (nslot) the normal law before the no-pull rule [N] */
    double *shape_R;      /* (nshape x 9) shape -> world rotation at the last evaluation (once per shape) */
    double *shape_xw;     /* (nshape x 3) shape origin, world [m] */
    int *slot_geomfail;   /* (nslot) 1 if the last geometry query was rejected */
    int *slot_far;        /* (nslot) 1 if the last evaluation's broad phase skipped the slot (open and
                             apart; opt.broad_phase): slot_fn = 0 and slot_ft = 0 are current, slot_x
                             is x or (a skipped group of several check points, a free sphere) an upper bound of it,
                             < 0; slot_xdot, slot_fnraw, slot_point, slot_normal, slot_vt are not
                             updated: cd_contact_slot_outputs gives every output as the full
                             evaluation would, cd_contact_complete fills them in */
    double *slot_free;    /* (nslot x 4) broad-phase cache of open slots: a point of the shape's frame
                             and a lower bound of its signed distance to the shape, from an earlier
                             evaluation (a free sphere: any check-point centre closer to that point
                             than the bound minus r is apart); zeroed by cd_data_reset and
                             cd_state_set; a radius <= 0 holds nothing */
    double *group_near;   /* (ngroup x 4) broad-phase cache of slot groups: a point of the shape's frame
                             and the distance to the shape an earlier query found there, within its
                             cut-off (a near sphere: a group centre close enough to it cannot be apart,
                             and the group's query is skipped); HUGE_VAL holds nothing; reset with
                             slot_free */
    int *slot_held;       /* (nslot) 1 while the chattering guard suspends the slot's switches
                             (= sw_held): its forces are then clipped to f_n >= 0 and |f_t| <= mu_max f_n */

    /* joint stops and joint friction (valid after an evaluation) */
    int *lim_mode;        /* (nlim) cd_limit_mode */
    double *lim_depth;    /* (nlim) depth beyond the engaged (or nearest) limit, > 0 inside [rad | m] */
    double *lim_force;    /* (nlim) stop torque on the joint (0 when free) */
    double *lim_raw;      /* (nlim) the stop law before the no-pull rule */
    int *fric_mode;       /* (nfric) CD_MODE_STICK or CD_MODE_SLIP */
    double *fric_dir;     /* (nfric) slip direction (+1 / -1) anchored at the stick -> slip event */
    double *fric_force;   /* (nfric) friction torque on the joint */

    /* clutched fingers */
    int *finger_mode;     /* (nfinger) cd_clutch_mode */
    double *finger_brake; /* (nfinger) TORQUE_SWITCH: inner joint angle at the switch [rad] */
    double *finger_load;  /* (nfinger) largest joint coupling torque [N m] (the clutch's load) */
    double *finger_theta; /* (nfinger) schedule angle theta_s(t - finger_t0) [rad] */
    double *finger_t0;    /* (nfinger) an input: origin of the closing schedule [s], which runs on t - t0 (0 at
                             reset; +inf holds it at its first row, open; e.g. a controller's grasp trigger
                             sets it, docs/capture.md); part of the state */

    /* the generic switch table: units 0..nsw-1 = slots, stops, frictions, fingers, user switches */
    double *sw_tswitch;   /* (nsw) time of the unit's last switch [s] */
    int *sw_nswitch;      /* (nsw) switches within `dwell` of the unit's last one (chattering guard) */
    int *sw_held;         /* (nsw) 1 while the guard suspends the unit's switches */
    int *act_piece;       /* (nu) current row of a STEPS/TABLE schedule (changed at its breakpoints) */

    /* event log: a ring buffer of the last ev_cap events; ev_count is the total */
    cd_event *ev;
    int ev_cap;
    long ev_count;

    cd_stats stats;
    void *integ;          /* private integrator state (GSL objects, buffers) */
    cd_allocator allocator; /* the one that made this data's block */
    void *block;          /* that block */
    double *state_undo;   /* private: cd_state_set keeps the previous state here while it checks the new one */
} cd_data;

/* Allocates data for a finalized model and sets the initial state from the
 * model (cd_data_reset). event_capacity is the ring size of the event log
 * (0 = 4096). Returns NULL (err filled) on failure: CD_EINVAL for a model
 * that is not finalized, has nothing to simulate (no degree of freedom and
 * no contact slot) or options out of range, CD_ENOMEM, or the reset's
 * failure (no static equilibrium for equilibrium_start). */
cd_data *cd_data_create(const cd_model *m, int event_capacity, cd_error *err);
/* The same with a caller's allocator for the data's block (NULL = malloc). */
cd_data *cd_data_create_ex(const cd_model *m, int event_capacity, const cd_allocator *alloc, cd_error *err);
/* Frees data; NULL is a no-op. */
void cd_data_free(cd_data *d);
/* Resets time, state, modes, inputs, log and statistics to the model's
 * initial values (keeps d->opt and the callbacks). CD_OK, or (err filled)
 * with opt.equilibrium_start CD_ENUMERIC if no static equilibrium is found
 * near the initial pose (d is then at that pose with its contacts closed
 * unloaded) and CD_ENOMEM if the settle's work space cannot be had. An
 * initial state that cannot be evaluated (non-finite, singular mass matrix)
 * is not an error here: the first step reports it, with its time. */
cd_status cd_data_reset(const cd_model *m, cd_data *d, cd_error *err);

/* Sets (or clears, with NULL) the control callback. */
void cd_data_set_control(cd_data *d, cd_control_fn fn, void *user);
/* Sets the functions of the model's user switches (cd_model_set_user_switches). */
void cd_data_set_user_switches(cd_data *d, cd_user_switch_fn g, cd_user_transition_fn tr, void *user);

/* Event i counted from the oldest still held (0 .. min(ev_count, ev_cap)-1). */
const cd_event *cd_data_event(const cd_data *d, long i);

/* ---- the complete state ----------------------------------------------------
 * Everything that decides the future of a run: t, y, every discrete mode and
 * anchor (slots, stops, frictions, user switches), the chattering guard's
 * counters, the schedule rows, the inputs, the integrator's next step size
 * and the fixed-rate step counter of cd_step. Packed as doubles (integers are
 * exact). Restoring it and continuing is bit-identical to not having
 * stopped, for every stepper. msbdf keeps a history of accepted points, and
 * rk4imp a Jacobian and starting values (like ros34pw2), that are not
 * copied: for
 * them cd_state_get makes the save point a
 * restart point of the stepper, in the run that goes on as in any run
 * restored from the snapshot (both restart there, so both agree bit for bit). */
size_t cd_state_size(const cd_model *m);
/* Copies the state into buf (cd_state_size doubles). */
void cd_state_get(const cd_model *m, cd_data *d, double *buf);
/* Restores a state got from data of the same model; evaluates it (outputs
 * valid on return). The whole buffer is checked first: CD_EINVAL (err names
 * the first bad element) if it is not a state of this model's size
 * signature, a discrete field is not a whole number in its domain (modes,
 * flags, counts, schedule rows), a value is not finite (a switch time may be
 * -inf) or a free base's quaternion is not unit within 1e-6; CD_ENUMERIC if
 * it cannot be evaluated. On any failure d is unchanged (its previous state
 * is put back; nothing is allocated). err may be NULL. */
cd_status cd_state_set(const cd_model *m, cd_data *d, const double *buf, cd_error *err);
/* dst takes src's complete state (both data of model m). */
cd_status cd_state_copy(const cd_model *m, cd_data *dst, cd_data *src, cd_error *err);

/* ---- state accessors (views into d->y) -------------------------------------- */
/* Pointers into y for system s: base CoM position (3), quaternion (4), joint
 * positions (n), base CoM velocity (3), base angular velocity (3, world), joint
 * rates (n). Base parts are NULL for a fixed base. */
typedef struct { double *pos, *quat, *q, *vel, *angvel, *qd; int njoint; } cd_sys_state;
cd_sys_state cd_state_of(const cd_model *m, const cd_data *d, int sys);
/* Joint position/rate of a link body (0 for a base). */
double cd_joint_q(const cd_model *m, const cd_data *d, int body);
double cd_joint_qd(const cd_model *m, const cd_data *d, int body);

#ifdef __cplusplus
}
#endif
#endif
