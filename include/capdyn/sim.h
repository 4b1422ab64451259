/* capdyn: simulation data (cd_data), kinematics, dynamics, contact and the
 * event-driven integrator. Everything here works on a finalized cd_model and
 * a cd_data created from it; no call allocates after cd_data_create() except
 * the implicit GSL steppers (rk4imp, msbdf), which allocate inside GSL. */
#ifndef CAPDYN_SIM_H
#define CAPDYN_SIM_H

#include "capdyn/model.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum { CD_MODE_OPEN = 0, CD_MODE_STICK = 1, CD_MODE_SLIP = 2 } cd_slot_mode;

typedef enum {
    CD_EV_ONSET = 0,       /* open -> stick: penetration (or normal force) crosses 0 upward */
    CD_EV_SEPARATION,      /* stick/slip -> open: normal force or penetration crosses 0 */
    CD_EV_STICK_SLIP,      /* |f_t| reaches mu_s f_n */
    CD_EV_SLIP_STICK,      /* slip velocity reverses against the slip direction */
    CD_EV_SLIP_TURN,       /* slip direction re-anchored (3-D slip turning past 90 deg) */
    CD_EV_GEOM_FAIL,       /* libccd returned a non-finite or inconsistent answer */
    CD_EV_NKINDS
} cd_event_kind;

/* Name of an event kind ("onset", "separation", "stick_slip", ...). */
const char *cd_event_kind_name(cd_event_kind k);
const char *cd_slot_mode_name(cd_slot_mode m);

/* One logged event. Forces are those just before the switch. */
typedef struct {
    double t;             /* [s] */
    int kind;             /* cd_event_kind */
    int slot;
    int body_a, body_b;   /* check-point body, shape body */
    int mode_from, mode_to;
    double x;             /* penetration [m] */
    double fn;            /* normal force [N] */
    double ft;            /* tangential force magnitude [N] */
} cd_event;

/* Integrator and event statistics, cumulative since cd_data_reset(). */
typedef struct {
    long nrhs;            /* right-hand-side evaluations */
    long nsteps;          /* accepted steps */
    long nrejected;       /* rejected trial steps (adaptive) */
    long nevents;         /* events located */
    long nlocate_steps;   /* fixed steps spent locating events */
    long nwarn_geom;      /* bad libccd answers */
    long nwarn_dwell;     /* switches deferred by the dwell rule */
    long nrenorm;         /* quaternion renormalisations */
    double h_last, h_min_seen, h_max_seen;
} cd_stats;

/* Simulation data: state, modes, outputs of the last evaluation and all the
 * work space. Fields are readable; write only y (then call cd_forward) and t. */
typedef struct cd_data {
    double t;             /* [s] */
    double *y;            /* (ny) continuous state, layout in docs/dynamics.md */
    double *ydot;         /* (ny) its derivative at the last evaluation */

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

    /* dynamics */
    double *udot;         /* (nv) generalized accelerations */
    double *tau;          /* (nv) applied generalized forces: actuation (+ base forces) */
    double *body_fext;    /* (nbody x 6) external wrench [n about ref; f], from contacts and user */
    double *body_fuser;   /* (nbody x 6) user wrench [torque about CoM; force at CoM], world */
    double *H;            /* (maxdof x maxdof) scratch for one system's mass matrix */
    double *work;         /* (4 maxdof + 12 nbody) scratch */
    double *jwork;        /* (12 maxdof + 36) scratch of cd_generalized_jacobian */
    void *body_rbi;       /* (nbody) spatial inertias (private scratch) */

    /* contact slots (valid after an evaluation) */
    int *slot_mode;       /* cd_slot_mode (discrete, changed only at events) */
    double *slot_dir;     /* (nslot x 3) slip direction anchored at the last event */
    double *slot_tswitch; /* (nslot) time of the last switch [s] */
    double *slot_x;       /* (nslot) penetration, >0 inside [m] */
    double *slot_xdot;    /* (nslot) penetration rate [m/s] */
    double *slot_fn;      /* (nslot) normal force [N] (0 when open) */
    double *slot_ft;      /* (nslot x 3) tangential force on the check-point body [N] */
    double *slot_point;   /* (nslot x 3) contact point, world [m] */
    double *slot_normal;  /* (nslot x 3) unit normal, from shape toward check point */
    double *slot_vt;      /* (nslot x 3) tangential relative velocity at the contact point [m/s] */
    double *slot_va;      /* (nslot x 3) slip (anchor) velocity while slipping [m/s] */
    double *slot_fnraw;   /* (nslot) the normal law before the no-pull rule [N] */
    int *slot_geomfail;   /* (nslot) 1 if the last geometry query was rejected */
    int *slot_held;       /* (nslot) 1 while the chattering guard suspends the slot's switches:
                             its forces are then clipped to f_n >= 0 and |f_t| <= mu_max f_n */

    /* event log: a ring buffer of the last ev_cap events; ev_count is the total */
    cd_event *ev;
    int ev_cap;
    long ev_count;

    cd_stats stats;
    void *integ;          /* private integrator state (GSL objects, buffers) */
} cd_data;

/* Allocates data for a finalized model and sets the initial state from the
 * model (cd_data_reset). event_capacity is the ring size of the event log
 * (0 = 4096). Returns NULL (err filled) on failure. */
cd_data *cd_data_create(const cd_model *m, int event_capacity, cd_error *err);
/* Frees data; NULL is a no-op. */
void cd_data_free(cd_data *d);
/* Resets time, state, modes, log and statistics to the model's initial values. */
void cd_data_reset(const cd_model *m, cd_data *d);

/* Event i counted from the oldest still held (0 .. min(ev_count, ev_cap)-1). */
const cd_event *cd_data_event(const cd_data *d, long i);

/* ---- state accessors (views into d->y) -------------------------------------- */
/* Pointers into y for system s: base CoM position (3), quaternion (4), joint
 * positions (n), base CoM velocity (3), base angular velocity (3, world), joint
 * rates (n). Base parts are NULL for a fixed base. */
typedef struct { double *pos, *quat, *q, *vel, *angvel, *qd; int njoint; } cd_sys_state;
cd_sys_state cd_state_of(const cd_model *m, const cd_data *d, int sys);
/* Joint position/rate of a link body (0 for a base). */
double cd_joint_q(const cd_model *m, const cd_data *d, int body);
double cd_joint_qd(const cd_model *m, const cd_data *d, int body);

/* ---- kinematics and dynamics ------------------------------------------------ */
/* Poses and velocities of every body from d->y. */
void cd_kinematics(const cd_model *m, cd_data *d);
/* World position and velocity of a point given in the body frame. */
void cd_point_world(const cd_model *m, const cd_data *d, int body, const double p_body[3],
                    double p_world[3], double v_world[3]);

/* Inverse dynamics of system s (recursive Newton-Euler) after cd_kinematics:
 * given accelerations udot_s (sys_ndof, ordered [vdot0; wdot0; qdd] for a free
 * base), gravity and the external wrenches in d->body_fext, returns in tau_s
 * the generalized forces [f0; n0 about the base CoM; joint torques] needed. */
void cd_inverse_dynamics(const cd_model *m, cd_data *d, int s, const double *udot_s, double *tau_s);
/* Mass matrix of system s (sys_ndof^2, row-major) after cd_kinematics. */
void cd_mass_matrix(const cd_model *m, cd_data *d, int s, double *H);
/* Forward dynamics of every system: udot = H^-1 (tau + J^T F - h). Uses d->tau
 * and d->body_fext as they are (call cd_forward for the full pipeline).
 * CD_ENUMERIC if a mass matrix is not positive definite. */
cd_status cd_forward_dynamics(const cd_model *m, cd_data *d);

/* Jacobian of a point fixed on `body` (p_body in the body frame), after
 * cd_kinematics: J (6 x sys_ndof, row-major) maps the system's generalized
 * velocities ([v0; w0; qd] for a free base, qd for a fixed one) to the
 * point's world velocity (rows 0-2) and the body's angular velocity (rows 3-5). */
void cd_point_jacobian(const cd_model *m, const cd_data *d, int body, const double p_body[3], double *J);

/* Generalized Jacobian of a free-floating system (Umetani & Yoshida, IEEE
 * T-RA 1989; SpaceDyn's calc_GJ), after cd_kinematics: with the system's
 * momentum zero, the point's [v; w] = Jg qd, Jg = J_q - J_b H_b^-1 H_bq
 * (6 x njoint, row-major). Uses d's work space. CD_EINVAL for a fixed base
 * (use cd_point_jacobian), CD_ENUMERIC if H_b is singular; err may be NULL. */
cd_status cd_generalized_jacobian(const cd_model *m, cd_data *d, int body, const double p_body[3], double *Jg,
                                  cd_error *err);

/* Energy and momenta of system s (after cd_kinematics). Kinetic energy [J];
 * linear momentum [kg m/s]; angular momentum about the system CoM and about
 * the world origin [kg m^2/s]; system CoM [m]. Any output may be NULL. */
void cd_momentum(const cd_model *m, const cd_data *d, int s, double *ke, double P[3],
                 double L_com[3], double L_origin[3], double com[3]);
/* Gravitational potential energy of system s: -sum m_i g.c_i [J]. */
double cd_potential_energy(const cd_model *m, const cd_data *d, int s);

/* Full pipeline at (t, y): kinematics, contacts (modes as they are), actuation,
 * dynamics, then ydot. CD_ENUMERIC on a non-finite value. */
cd_status cd_forward(const cd_model *m, cd_data *d);

/* ---- contact geometry (exposed for tests and tools) ------------------------- */
/* Signed distance from a point (shape frame) to a shape of a finalized model
 * (>0 outside), outward unit normal and closest surface point (shape frame):
 * exact for every type, convex hulls included (face planes built at
 * finalize). radius is unused (kept for symmetry with the libccd query).
 * Returns 0, or -1 if the answer is not finite. */
int cd_shape_distance(const cd_model *m, int shape, const double p[3], double radius,
                      double *dist, double n[3], double s[3]);
/* The same answer computed independently through libccd (GJK/EPA penetration
 * of a sphere of radius `radius` against the shape's support function;
 * accurate to ~1e-6 m, allocates: for tests and tools, never used in a step).
 * Valid only when the sphere penetrates; returns 1 when separated, 0 on
 * success, -1 on a bad answer or for a plane. */
int cd_shape_distance_ccd(const cd_model *m, int shape, const double p[3], double radius,
                          double *dist, double n[3], double s[3]);

/* ---- the event-driven integrator ------------------------------------------- */
/* Called after every accepted step or located event; return non-zero to stop
 * (cd_sim_advance then returns CD_EINTERRUPT). May be NULL. */
typedef int (*cd_step_callback)(const cd_model *m, const cd_data *d, void *user);

/* Advances from d->t to t_end (exactly), locating every event on the way.
 * Returns CD_OK, or CD_ESTALL / CD_EMAXSTEPS / CD_ENUMERIC / CD_EINTERRUPT with
 * err filled; d then holds the last good state. */
cd_status cd_sim_advance(const cd_model *m, cd_data *d, double t_end,
                         cd_step_callback cb, void *user, cd_error *err);

/* Proposes a contact law by the paper's rule; see cd_contact_law_from_rule. */

#ifdef __cplusplus
}
#endif
#endif
