/* capdyn: the immutable model (cd_model) and the calls that build it.
 *
 * A model is built once, by code or by the scenario loader, and then frozen by
 * cd_model_finalize(). After that it is read-only: any number of cd_data may
 * share it. All quantities are SI (m, kg, s, N, rad); angles in this API are
 * radians. Matrices are 3x3 row-major; quaternions are (w, x, y, z) and rotate
 * body coordinates into world coordinates. See docs/dynamics.md. */
#ifndef CAPDYN_MODEL_H
#define CAPDYN_MODEL_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

#define CD_VERSION_STRING "0.1.0"

/* ---- status and errors -------------------------------------------------- */
typedef enum {
    CD_OK = 0,
    CD_EINVAL,     /* invalid argument or model description */
    CD_ENOMEM,     /* allocation failed (only at creation time) */
    CD_ENUMERIC,   /* non-finite value, singular mass matrix, bad geometry */
    CD_ESTALL,     /* integrator step size fell below h_min */
    CD_EMAXSTEPS,  /* the step budget (cd_options.max_steps) is spent */
    CD_EIO,        /* file input/output (io layer only) */
    CD_EINTERRUPT, /* a caller's callback asked to stop */
    CD_EBUDGET     /* a per-call evaluation or work budget is spent (cd_step, cd_sim_advance) */
} cd_status;

/* A caller-owned error report. Functions that can fail fill it (if non-NULL)
 * with the status and a one-line message; they never print.
 *
 * NULL arguments, the same way in every public function (docs/embedding.md,
 * tests/test_null_args.c): err may always be NULL. A NULL model, data,
 * controller, sampler, monitor, writer or required buffer makes a function
 * returning cd_status return CD_EINVAL (err names the function and the
 * argument), a constructor return NULL (err filled), a function returning
 * an id or index -1, a double NaN, a size 0, a pointer NULL; a void function
 * then does nothing; cd_*_free(NULL) is a no-op. Output pointers documented
 * as optional (e.g. the parts of cd_momentum) may be NULL. */
typedef struct {
    cd_status status;
    char msg[512];
} cd_error;

/* Fills err (if non-NULL) with status st and a printf-style message
 * (truncated to the buffer). For the library's layers and for callers that
 * report through the same struct. */
void cd_error_set(cd_error *err, cd_status st, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Human-readable name of a status ("ok", "invalid argument", ...). */
const char *cd_status_string(cd_status s);
/* Library version, e.g. "0.1.0". */
const char *cd_version(void);

/* ---- enumerations -------------------------------------------------------- */
typedef enum { CD_BASE_FREE = 0, CD_BASE_FIXED = 1 } cd_base_type;
typedef enum { CD_JOINT_BASE = 0, CD_JOINT_REVOLUTE = 1, CD_JOINT_PRISMATIC = 2 } cd_joint_type;
typedef enum {
    CD_SHAPE_PLANE = 0,    /* half-space z <= 0 of the shape frame; size unused */
    CD_SHAPE_SPHERE,       /* size[0] = radius */
    CD_SHAPE_BOX,          /* size = half extents along x, y, z */
    CD_SHAPE_CYLINDER,     /* size[0] = radius, size[1] = half length along z */
    CD_SHAPE_CAPSULE,      /* size[0] = radius, size[1] = half length of the axis segment along z */
    CD_SHAPE_CONVEX,       /* convex hull of vertices (shape frame), through libccd */
    CD_SHAPE_NTYPES
} cd_shape_type;
/* Actuator laws. Each actuator's command is u = law + ctrl[a] (d->ctrl, written
 * by the caller between calls or by a control callback); the motor model, if
 * any, limits u to the torque-speed envelope; the transmission applies
 * ratio_j * u to each of its joints. For PD, q and qdot are the transmission
 * coordinate sum_j ratio_j q_j and its rate. */
typedef enum {
    CD_ACT_NONE = 0,       /* law 0: u = ctrl only (a joint without actuator is passive) */
    CD_ACT_CONSTANT,       /* law tau0 */
    CD_ACT_TABLE,          /* law linear in a time table, held at the ends; breakpoints are located */
    CD_ACT_PD,             /* law tau0 + kp (qref - q) - kd qdot */
    CD_ACT_STEPS,          /* law piecewise constant: v_i on [t_i, t_i+1), v_0 before t_0;
                              every step is an exact time event */
    CD_ACT_NTYPES
} cd_act_type;
typedef enum {
    CD_PRESCRIBE_NONE = 0,
    CD_PRESCRIBE_VELOCITY, /* q = q0 + v (t - t_start) for t >= t_start (q0 before) */
    CD_PRESCRIBE_WAYPOINTS /* q through (t_i, q_i) with minimum-jerk quintic segments
                              (zero velocity and acceleration at every waypoint), held at the ends */
} cd_prescribe_type;
typedef enum {
    CD_STEP_RKF45 = 0, CD_STEP_RKCK, CD_STEP_RK8PD, CD_STEP_RK4IMP, CD_STEP_MSBDF,
    CD_STEP_RK4_FIXED,     /* classic RK4 with fixed step h_fixed (embedding mode) */
    CD_STEP_ROS34PW2,      /* linearly implicit Rosenbrock-W, order 3(2), L-stable: stiff contact (src/sim/rosw.c) */
    CD_STEP_AUTO,          /* rk8pd while the problem is not stiff, msbdf while it is: the switch is decided by
                              the spectral radius of the structured Jacobian against the step (src/sim/integrator.c) */
    CD_STEP_RODAS4,        /* linearly implicit Rosenbrock RODAS4, order 4(3), L-stable, exact (finite-difference) Jacobian renewed every step (src/sim/rosw.c) */
    CD_STEP_NTYPES
} cd_stepper;

/* The smallest non-zero rtol cd_options_check accepts: about 64 ulps of 1.
 * A tighter one cannot be met in double precision (the step collapses). */
#define CD_RTOL_MIN 1e-14

/* cd_options.jacobian */
typedef enum { CD_JAC_MODEL = 0, CD_JAC_FD = 1 } cd_jacobian_kind;

/* Name of a shape/stepper type ("plane", "rkf45", ...) and the reverse lookup
 * (returns -1 for an unknown name). */
const char *cd_shape_type_name(cd_shape_type t);
int cd_shape_type_from_name(const char *name);
const char *cd_stepper_name(cd_stepper s);
int cd_stepper_from_name(const char *name);

/* ---- integration options --------------------------------------------------- */
typedef struct {
    cd_stepper stepper;   /* default CD_STEP_AUTO */
    double rtol;          /* relative tolerance, default 1e-9 */
    double atol;          /* absolute tolerance, default 1e-12 */
    double h_init;        /* first trial step [s], default 1e-5 */
    double h_max;         /* largest step [s], default 1e-2 (0 = unbounded) */
    double h_min;         /* smaller accepted steps stop the run (CD_ESTALL) [s], default 1e-14 */
    double h_fixed;       /* step of CD_STEP_RK4_FIXED [s], default 1e-5 */
    long max_steps;       /* accepted+rejected step budget per cd_sim_advance call, default 10^8 */
    double event_tol;     /* events located to this time tolerance [s], default 1e-10 */
    double dwell;         /* min time between two switches of one slot [s], default 1e-7 */
    double v_reg;         /* slip-direction regularisation speed [m/s], default 1e-6 */
    double fd_eps;        /* relative finite-difference step of implicit steppers' Jacobian, default 1e-7 */
    long max_evals;       /* rhs-evaluation budget per cd_step / cd_sim_advance call (0 = none, default);
                             cd_step lands a located event early rather than exceed it (hard real time) */
    int jacobian;         /* the linearly implicit stepper's Jacobian: CD_JAC_MODEL (default: assembled from
                             the contact laws, joint elements and mass matrix, src/sim/jac.c) or CD_JAC_FD
                             (forward differences on the active set, one evaluation per unknown) */
    int equilibrium_start;/* 1: at reset, contacts closed at t = 0 (and engaged joint stops) start in
                             static equilibrium (normal penetration and stick anchors preloaded by a
                             quasi-static settle); 0 (default): they start with zero tangential deflection */
    int broad_phase;      /* 1 (default): an evaluation skips the velocity work of open slots that are apart
                             from their shape (x < 0) and computes their other outputs on demand (d->slot_far;
                             results bit-identical); 0: every slot evaluated in full (docs/contact.md) */
} cd_options;
/* Which options may change after cd_data_create: every one except `stepper`
 * (the GSL objects are made for it) and `equilibrium_start` / `h_init` (used
 * at reset). cd_data keeps its own copy (d->opt), taken from the model's at
 * creation; edit d->opt between calls. Changing tolerances takes effect at
 * the next call. */

/* The defaults listed above. */
cd_options cd_options_default(void);
/* CD_OK if every option is in range (checked again by cd_data_create, since
 * m->opt may be edited after finalize), else CD_EINVAL with err filled. */
cd_status cd_options_check(const cd_options *o, cd_error *err);

/* ---- contact law ---------------------------------------------------------- */
/* Normal:     f_n = K x^p + D |xdot|^q sign(xdot)  (paper eq. 3, damping
 *             CD_DAMP_LINEAR, the default), or Hunt-Crossley (CD_DAMP_HUNT_CROSSLEY,
 *             Hunt & Crossley 1975): f_n = K x^p + D |x|^p |xdot|^q sign(xdot), whose
 *             damper vanishes with x (no force jump at onset); no pull by
 *             default, or plain Kelvin-Voigt (`pull`) until x returns to 0.
 * Tangential: stick  f_t = -(K_t z^pt + D_t v_t^qt) (paper eq. 4, signed
 *                    vector powers; pt = qt = 1: linear)
 *             slip   |f_t| = mu_k f_n against slip   (paper eq. 5)
 * stick -> slip when |f_t| > mu_s f_n; slip -> stick when the slip velocity
 * reverses. No friction while a `pull` contact is in tension (f_n < 0).
 * p >= 1, q > 0, pt >= 1, qt > 0. See docs/contact.md. */
typedef struct {
    double K, D, p, q;    /* [N/m^p], [N (s/m)^q], exponents (>= 1) */
    double Kt, Dt;        /* [N/m^pt], [N (s/m)^qt] tangential stick spring-damper */
    double mu_s, mu_k;    /* static (maximum) and kinetic friction coefficients */
    double pt, qt;        /* tangential exponents of eq. (4): f_t = -(K_t |z|^pt z/|z| + D_t |v|^qt v/|v|);
                             pt >= 1, qt > 0, default 1 (linear) */
    int pull;             /* 0 (default): no pull, f_n >= 0, separation where min(K x, f_raw) reaches 0;
                             1: plain Kelvin-Voigt, contact kept until x returns to 0, f_n may pull */
    int damping;          /* CD_DAMP_LINEAR (default, eq. 3: D [N (s/m)^q]) or CD_DAMP_HUNT_CROSSLEY
                             (D |x|^p xdot^q: D [N (s/m)^q / m^p]) */
} cd_contact_law;

/* normal damping laws of cd_contact_law.damping */
enum { CD_DAMP_LINEAR = 0, CD_DAMP_HUNT_CROSSLEY = 1 };

/* Linear law K = 1e5 N/m, D = 100 N s/m, p = q = 1, K_t = K, D_t = D, mu = 0.5,
 * pt = qt = 1, no pull, linear damping (CD_DAMP_LINEAR). */
cd_contact_law cd_contact_law_default(void);

/* The paper's rule (sec. 2): the contact is k_ratio (10..100) times stiffer than
 * the softest part k_soft [N/m]; the damping gives damping ratio zeta for the
 * effective mass m_eff [kg]: D = 2 zeta sqrt(K m_eff). Tangential values are set
 * equal to the normal ones; p = q = 1. Friction is left at mu_s = mu_k = mu. */
cd_contact_law cd_contact_law_from_rule(double k_soft, double k_ratio, double m_eff,
                                        double zeta, double mu);

/* ---- actuators ------------------------------------------------------------ */
typedef struct {
    cd_act_type type;
    double tau0;          /* [N m] or [N] constant or feed-forward */
    double kp, kd;        /* [N m/rad], [N m s/rad] (prismatic: N/m, N s/m) */
    double qref;          /* [rad] or [m] */
    const double *tbl_t;  /* table times [s], strictly increasing (copied) */
    const double *tbl_v;  /* table values [N m] (copied) */
    int ntbl;
} cd_actuator;

/* A general actuator: a law (as cd_actuator), a transmission to one or more
 * joints with ratios (one motor driving every joint of a finger), an optional
 * DC-motor torque-speed envelope. */
typedef struct {
    const char *name;     /* copied; may be NULL */
    cd_act_type type;
    double tau0, kp, kd, qref;
    const double *tbl_t, *tbl_v;  /* TABLE / STEPS rows (copied) */
    int ntbl;
    int ntrn;             /* joints driven (>= 1) */
    const int *trn_body;  /* (ntrn) joint bodies (copied) */
    const double *trn_ratio; /* (ntrn) joint torque = ratio x actuator torque (copied) */
    double stall_torque;  /* [N m] > 0 enables the motor model: |u| limited to the line through
                             (0, stall_torque) and (noload_speed, 0) in the direction of motion */
    double noload_speed;  /* [rad/s] of the transmission coordinate, > 0 with stall_torque */
} cd_actuator_desc;
cd_actuator_desc cd_actuator_desc_default(void);

/* A clutched finger (paper sec. 4): its joints are driven through a stiff
 * synchronising coupling (wire stiffness K_w, damping D_w) toward a closing
 * angle schedule theta_s(t) until the coupling's load exceeds the clutch
 * threshold (a located event per finger); then:
 *  SPACE          Space Gripper: the plunger disengages the synchronising
 *                 pulley and the equal-pressure wire mechanism takes over:
 *                 joint j gets ratio_j x grasp_torque (constant).
 *  TORQUE_SWITCH  Barrett TorqueSwitch: the inner (first) joint is braked at
 *                 the angle it had at the switch (a stiff K_w, D_w brake); the
 *                 outer joints go on following the schedule.
 * Coupling torques are limited to torque_limit (the motor's current limit).
 * After open_at (if > 0) the clutch re-engages where the schedule, turning
 * back, has come back to the finger (the coupling would pull it open), and
 * the schedule opens the finger. */
typedef enum { CD_FINGER_SPACE = 0, CD_FINGER_TORQUE_SWITCH = 1, CD_FINGER_NTYPES } cd_finger_type;
typedef struct {
    const char *name;     /* copied; may be NULL */
    cd_finger_type type;
    int njoint;
    const int *joint_body;/* (njoint) joint bodies, base to tip (copied) */
    const double *sync;   /* (njoint) schedule gains: joint j follows q0_j + sync_j theta_s, q0_j its initial angle (NULL: all 1) */
    const double *ratio;  /* (njoint) equal-pressure split after the clutch (NULL: (n - j)^2, j = 0 base) */
    double wire_K, wire_D;/* coupling stiffness [N m/rad] (> 0) and damping [N m s/rad] (>= 0) */
    double threshold;     /* clutch load [N m] (> 0): the largest joint coupling torque */
    double grasp_torque;  /* SPACE: torque scale after the clutch [N m] */
    double torque_limit;  /* |coupling torque| limit [N m] (0 = none) */
    const double *sched_t, *sched_q; /* theta_s(t) [s], [rad], piecewise linear, held at the ends (copied) */
    int nsched;
    double open_at;       /* [s] from then on, re-engage and open (0 = never) */
} cd_finger_desc;
cd_finger_desc cd_finger_desc_default(void);

/* Passive joint elements, limits and prescribed motion of one joint. */
typedef struct {
    double stiffness;     /* passive spring [N m/rad | N/m], >= 0 */
    double rest;          /* its rest position [rad | m] */
    double damping;       /* viscous damper [N m s/rad | N s/m], >= 0 */
    double friction;      /* Coulomb friction torque [N m | N], >= 0 (0 = none): stick-slip with
                             a located switch, like the contact's tangential law */
    double friction_k;    /* stick stiffness [N m/rad]; 0 = friction / 1e-4 rad (breakaway at 0.1 mrad) */
    double friction_d;    /* stick damping [N m s/rad]; 0 = critical for the joint's subtree inertia */
    int limited;          /* 1: compliant stops at lower and upper */
    double lower, upper;  /* [rad | m], lower < upper */
    double stop_K, stop_D, stop_p, stop_q; /* stop law K d^p + D ddot^q (d beyond the limit),
                             no pull; 0 = K 1e3 N m/rad, D critical for the subtree inertia, p = q = 1 */
    cd_prescribe_type prescribe;
    double presc_v, presc_t0;           /* VELOCITY: rate, start time */
    const double *presc_t, *presc_q;    /* WAYPOINTS (copied) */
    int npresc;
} cd_joint_props;
cd_joint_props cd_joint_props_default(void);

/* ---- descriptions used by the builder -------------------------------------- */
typedef struct {
    const char *name;     /* copied; may be NULL */
    cd_base_type type;
    double mass;          /* base mass [kg] (>0) */
    double inertia[9];    /* about the base CoM, base frame [kg m^2] */
    double pos[3];        /* base CoM, world [m] (SpaceDyn R0) */
    double quat[4];       /* base orientation, world (SpaceDyn Q0 as quaternion) */
    double vel[3];        /* CoM velocity, world [m/s] (free base only) */
    double angvel[3];     /* angular velocity, world [rad/s] (free base only) */
} cd_system_desc;

typedef struct {
    const char *name;     /* copied; may be NULL */
    int parent;           /* body id of the parent (same system) */
    cd_joint_type type;   /* CD_JOINT_REVOLUTE or CD_JOINT_PRISMATIC */
    double pos[3];        /* joint origin in the parent frame [m] */
    double rot[9];        /* orientation of the link frame at q = 0 in the parent frame:
                             maps link coordinates to parent coordinates (R_link = R_parent rot) */
    double axis[3];       /* joint axis in the link frame (normalised on add) */
    double mass;          /* [kg] (>0) */
    double com[3];        /* CoM in the link frame (origin at the joint) [m] */
    double inertia[9];    /* about the CoM, link frame [kg m^2] */
    double q0, qd0;       /* initial joint position [rad|m] and rate */
} cd_link_desc;

/* Defaults: unit mass and inertia, identity orientation, z axis, revolute. */
cd_system_desc cd_system_desc_default(void);
cd_link_desc cd_link_desc_default(void);

/* ---- the model -------------------------------------------------------------
 * Flat arrays indexed by integer ids, MuJoCo style. Bodies of one system are
 * contiguous, the base first, every parent before its children. */
typedef struct cd_model {
    int nsys, nbody, ncp, nshape, nvert, nlaw, npair, nslot, ntbl;
    int nu;               /* actuators */
    int ntrn;             /* transmission entries, all actuators */
    int nlim;             /* limited joints */
    int nfric;            /* joints with Coulomb friction */
    int nuser;            /* user switches (cd_model_set_user_switches) */
    int nfinger;          /* clutched fingers (cd_model_add_finger) */
    int npresc;           /* prescribed joints + prescribed bases */
    int nsw;              /* switch units: nslot + nlim + nfric + nfinger + nuser (docs/events.md) */
    int nv;               /* generalized velocities, all systems */
    int ny;               /* continuous state size (see docs/dynamics.md) */
    int ny_slot_adr;      /* where the per-slot tangential deflections start in y (3 each, shape-body axes) */
    int ny_fric_adr;      /* where the joint-friction stick deflections start in y (1 each) */
    int finalized;
    double gravity[3];    /* [m/s^2], world */
    cd_options opt;

    /* systems */
    char **sys_name;
    int *sys_base_type;   /* cd_base_type */
    int *sys_body_adr;    /* first body (the base) */
    int *sys_nbody;
    int *sys_ndof;        /* generalized velocities: 6 + njoint (free) or njoint */
    int *sys_v_adr;       /* first generalized velocity in the global vector */
    int *sys_y_adr;       /* first entry of the system's block in y */
    double *sys_pos0;     /* (nsys x 3) */
    double *sys_quat0;    /* (nsys x 4) */
    double *sys_vel0;     /* (nsys x 3) */
    double *sys_angvel0;  /* (nsys x 3) */

    /* bodies (base and links) */
    char **body_name;
    int *body_sys;
    int *body_parent;     /* -1 for a base */
    int *body_jnt_type;   /* cd_joint_type */
    int *body_dof;        /* global generalized-velocity index of the joint, -1 for a base */
    double *body_jnt_pos; /* (nbody x 3) joint origin in the parent frame [m] */
    double *body_jnt_rot; /* (nbody x 9) link frame at q = 0 in the parent frame (link -> parent coordinates) */
    double *body_axis;    /* (nbody x 3) unit joint axis, link frame */
    double *body_mass;    /* (nbody) [kg] */
    double *body_com;     /* (nbody x 3) CoM in the body frame [m]; 0 for bases */
    double *body_inertia; /* (nbody x 9) about the CoM, body frame [kg m^2] */
    double *body_q0, *body_qd0;

    /* joint elements (per body; 0 for bases) */
    double *body_spring;  /* (nbody x 2) stiffness, rest */
    double *body_damping; /* (nbody) */
    double *body_fric;    /* (nbody x 3) Coulomb torque, stick stiffness, stick damping (resolved) */
    double *body_limit;   /* (nbody x 6) lower, upper, K, D, p, q (resolved) */
    int *body_lim_id;     /* (nbody) index among limited joints, -1 */
    int *body_fric_id;    /* (nbody) index among friction joints, -1 */
    int *lim_body;        /* (nlim) */
    int *fric_body;       /* (nfric) */
    int *body_presc;      /* (nbody) cd_prescribe_type of the joint (bases: of the base) */
    double *body_presc_prm; /* (nbody x 6) joint: v, t0; base: v[3], w[3] (constant, world) */
    int *body_wp_adr, *body_wp_n; /* waypoints in tbl_t / tbl_v */

    /* actuators */
    char **act_name;
    int *act_type;        /* cd_act_type */
    double *act_prm;      /* (nu x 4) tau0, kp, kd, qref */
    double *act_motor;    /* (nu x 2) stall torque [N m], no-load speed [rad/s] (0 = no motor) */
    int *act_tbl_adr, *act_tbl_n;
    int *act_trn_adr, *act_trn_n;
    int *trn_body;        /* (ntrn) */
    double *trn_ratio;    /* (ntrn) */
    int *body_act;        /* (nbody) actuator set by cd_model_set_actuator on this joint, -1 */
    /* clutched fingers */
    char **finger_name;
    int *finger_type;     /* cd_finger_type */
    int *finger_jnt_adr, *finger_jnt_n; /* into fjnt_* */
    int *fjnt_body;       /* joint bodies of all fingers */
    double *fjnt_sync, *fjnt_ratio;
    double *finger_prm;   /* (nfinger x 6) wire_K, wire_D, threshold, grasp_torque, torque_limit, open_at */
    int *finger_tbl_adr, *finger_tbl_n; /* schedule rows in tbl_t / tbl_v */
    int nfjnt;
    double *tbl_t, *tbl_v;
    int nbreak;           /* time events of the schedules (TABLE/STEPS rows, waypoints), sorted, unique */
    double *breaks;       /* (nbreak) [s] */

    /* check points: a sphere of radius r centred at pos on a body */
    int *cp_body;
    double *cp_pos;       /* (ncp x 3) body frame [m] */
    double *cp_radius;    /* (ncp) [m] */

    /* shapes on bodies */
    int *shape_body;
    int *shape_type;      /* cd_shape_type */
    double *shape_pos;    /* (nshape x 3) in the body frame [m] */
    double *shape_rot;    /* (nshape x 9) shape frame -> body frame */
    double *shape_size;   /* (nshape x 3), meaning per type */
    double *shape_rbound; /* (nshape) radius about the shape origin holding the whole shape [m]; HUGE_VAL: plane */
    int *shape_vert_adr, *shape_vert_num;
    double *vert;         /* (nvert x 3) shape frame [m] */
    int nface;            /* hull faces of the convex shapes, built at finalize */
    int *shape_face_adr, *shape_face_num;
    int *face_vert;       /* (nface x 3) vertex indices (into vert) of a face triangle */
    double *face_plane;   /* (nface x 4) outward unit normal and offset: n.p = o on the face */
    int *face_run;        /* (nface) the triangles of one face plane are consecutive: at the first,
                           * how many share its plane (bitwise); 0 at the others */

    /* contact laws and pairs (check points of a system/body x one shape) */
    cd_contact_law *law;
    int *pair_sys, *pair_body, *pair_shape, *pair_law;

    /* the slot table, fixed at finalize: one slot per (check point, shape) */
    int *slot_cp, *slot_shape, *slot_law;
    /* slot groups of the broad phase, fixed at finalize: each a run of consecutive slots
       with the same check-point body and shape (docs/contact.md, "Broad phase") */
    int ngroup;
    int *group_adr, *group_num;  /* (ngroup) first slot, number of slots */
    double *group_pos;    /* (ngroup x 3) centre of the group's check points, body frame [m] */
    double *group_radius; /* (ngroup) radius about it holding every check point's sphere [m] */

} cd_model;

/* A new empty model, gravity zero, default options. NULL if out of memory. */
cd_model *cd_model_create(void);
/* Frees a model and everything it owns; NULL is a no-op. */
void cd_model_free(cd_model *m);

/* Builder calls. Each returns the new object's id (>= 0), or -1 with err
 * filled (CD_EINVAL for a bad description, including after finalize). */
int cd_model_add_system(cd_model *m, const cd_system_desc *s, cd_error *err);
int cd_model_add_link(cd_model *m, int sys, const cd_link_desc *l, cd_error *err);
int cd_model_add_checkpoint(cd_model *m, int body, const double pos[3], double radius, cd_error *err);
/* size may be NULL for a plane; verts (nvert x 3) only for CD_SHAPE_CONVEX. */
int cd_model_add_shape(cd_model *m, int body, cd_shape_type type, const double pos[3],
                       const double rot[9], const double size[3], const double *verts,
                       int nvert, cd_error *err);
int cd_model_add_law(cd_model *m, const cd_contact_law *law, cd_error *err);
/* Check points of system `sys` (only those of `body` if body >= 0) against
 * shape `shape` with law `law`. The shape may belong to the same system (finger
 * against finger of one hand): slots are then not made for check points on
 * the shape's own body or on the bodies jointed to it (parent, children),
 * which touch it at the joint by construction; body == the shape's body is
 * an error. If several pairs produce the same (check point, shape) slot, the
 * first pair's law is kept. */
int cd_model_add_pair(cd_model *m, int sys, int body, int shape, int law, cd_error *err);
/* Sets the actuator of a joint body (table arrays are copied): an actuator
 * with a transmission of ratio 1 to that joint, replacing one set before. */
cd_status cd_model_set_actuator(cd_model *m, int body, const cd_actuator *a, cd_error *err);
/* Adds a general actuator (transmission, motor model); returns its id (index
 * into d->ctrl) or -1 with err filled. */
int cd_model_add_actuator(cd_model *m, const cd_actuator_desc *a, cd_error *err);
/* Sets the passive elements, limits and prescribed motion of a joint body. */
cd_status cd_model_set_joint(cd_model *m, int body, const cd_joint_props *p, cd_error *err);
/* Prescribes the motion of a free base: constant linear velocity v (world,
 * of the base CoM) and angular velocity w (world) from t = 0, exactly (the
 * base then moves like a test rig; the wrench it takes is in d->qfrc_constraint). */
cd_status cd_model_prescribe_base(cd_model *m, int sys, const double v[3], const double w[3], cd_error *err);
/* Adds a clutched finger; returns its id or -1 with err. */
int cd_model_add_finger(cd_model *m, const cd_finger_desc *f, cd_error *err);
/* Reserves n user switches (cd_data_set_user_switches gives their functions). */
cd_status cd_model_set_user_switches(cd_model *m, int n, cd_error *err);
/* Actuator id by name; -1 if none. */
int cd_model_actuator_id(const cd_model *m, const char *name);

/* Body id from "system/body" or a body name unique in the model; -1 if none. */
int cd_model_body_id(const cd_model *m, const char *name);
int cd_model_system_id(const cd_model *m, const char *name);

/* Validates what the builder calls could not check alone (at least one
 * degree of freedom or contact slot; option ranges; convex hulls with volume;
 * joint limits containing q0), lays out the state, builds the slot table, the
 * switch units and the schedule's time events. Each builder call has already
 * checked its own description (positive masses, positive definite inertias
 * obeying the triangle inequality, finite numbers, proper rotations).
 * Returns CD_OK or CD_EINVAL with err naming the body. */
cd_status cd_model_finalize(cd_model *m, cd_error *err);

#ifdef __cplusplus
}
#endif
#endif
