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
    CD_EINTERRUPT  /* a caller's callback asked to stop */
} cd_status;

/* A caller-owned error report. Functions that can fail fill it (if non-NULL)
 * with the status and a one-line message; they never print. */
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
typedef enum {
    CD_ACT_NONE = 0,       /* passive joint (zero torque) */
    CD_ACT_CONSTANT,       /* tau = tau0 */
    CD_ACT_TABLE,          /* tau(t) linear in a time table, held at the ends */
    CD_ACT_PD              /* tau = tau0 + kp (qref - q) - kd qdot */
} cd_act_type;
typedef enum {
    CD_STEP_RKF45 = 0, CD_STEP_RKCK, CD_STEP_RK8PD, CD_STEP_RK4IMP, CD_STEP_MSBDF,
    CD_STEP_RK4_FIXED,     /* classic RK4 with fixed step h_fixed (embedding mode) */
    CD_STEP_NTYPES
} cd_stepper;

/* Name of a shape/stepper type ("plane", "rkf45", ...) and the reverse lookup
 * (returns -1 for an unknown name). */
const char *cd_shape_type_name(cd_shape_type t);
int cd_shape_type_from_name(const char *name);
const char *cd_stepper_name(cd_stepper s);
int cd_stepper_from_name(const char *name);

/* ---- integration options --------------------------------------------------- */
typedef struct {
    cd_stepper stepper;   /* default rk8pd */
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
} cd_options;

/* The defaults listed above. */
cd_options cd_options_default(void);
/* CD_OK if every option is in range (checked again by cd_data_create, since
 * m->opt may be edited after finalize), else CD_EINVAL with err filled. */
cd_status cd_options_check(const cd_options *o, cd_error *err);

/* ---- contact law ---------------------------------------------------------- */
/* Normal:     f_n = K x^p + D |xdot|^q sign(xdot)  (paper eq. 3), never pulling.
 * Tangential: stick  f_t = -(K_t z + D_t v_t)       (paper eq. 4, linear)
 *             slip   |f_t| = mu_k f_n against slip   (paper eq. 5)
 * stick -> slip when |f_t| > mu_s f_n; slip -> stick when the slip velocity
 * reverses. See docs/contact.md. */
typedef struct {
    double K, D, p, q;    /* [N/m^p], [N (s/m)^q], exponents (>= 1) */
    double Kt, Dt;        /* [N/m], [N s/m] tangential stick spring-damper */
    double mu_s, mu_k;    /* static (maximum) and kinetic friction coefficients */
} cd_contact_law;

/* Linear law K = 1e5 N/m, D = 100 N s/m, p = q = 1, K_t = K, D_t = D, mu = 0.5. */
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
    int nv;               /* generalized velocities, all systems */
    int ny;               /* continuous state size (see docs/dynamics.md) */
    int ny_slot_adr;      /* where the per-slot tangential deflections start in y (3 each, shape-body axes) */
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

    /* actuators, one per joint body */
    int *body_act_type;   /* cd_act_type */
    double *body_act;     /* (nbody x 4) tau0, kp, kd, qref */
    int *body_tbl_adr, *body_tbl_n;
    double *tbl_t, *tbl_v;

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
    int *shape_vert_adr, *shape_vert_num;
    double *vert;         /* (nvert x 3) shape frame [m] */
    int nface;            /* hull faces of the convex shapes, built at finalize */
    int *shape_face_adr, *shape_face_num;
    int *face_vert;       /* (nface x 3) vertex indices (into vert) of a face triangle */
    double *face_plane;   /* (nface x 4) outward unit normal and offset: n.p = o on the face */

    /* contact laws and pairs (check points of a system/body x one shape) */
    cd_contact_law *law;
    int *pair_sys, *pair_body, *pair_shape, *pair_law;

    /* the slot table, fixed at finalize: one slot per (check point, shape) */
    int *slot_cp, *slot_shape, *slot_law;

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
/* Sets the actuator of a joint body (table arrays are copied). */
cd_status cd_model_set_actuator(cd_model *m, int body, const cd_actuator *a, cd_error *err);

/* Body id from "system/body" or a body name unique in the model; -1 if none. */
int cd_model_body_id(const cd_model *m, const char *name);
int cd_model_system_id(const cd_model *m, const char *name);

/* Validates (positive masses, positive definite inertias obeying the triangle
 * inequality, finite numbers, orthonormal rotations), lays out the state and
 * builds the slot table. Returns CD_OK or CD_EINVAL with err naming the body. */
cd_status cd_model_finalize(cd_model *m, cd_error *err);

#ifdef __cplusplus
}
#endif
#endif
