/* capdyn: builders of the paper's grippers and of capture targets (C99).
 *
 * The generators behind the scenario loader's [gripper] table and its
 * `handrail` shape, callable from C on a model under construction (before
 * cd_model_finalize). A scenario file and these calls give the same model,
 * entry for entry (tests/test_build.c); the loader reads TOML, checks it,
 * fills these descriptors and calls these functions.
 *
 * Descriptors come from a defaults function and are then edited (as
 * cd_options): `cd_hand_desc h = cd_hand_desc_default(); h.type =
 * CD_HAND_SPACE; ...`. The defaults are the loader's defaults
 * (docs/grippers.md). All quantities are SI; angles are radians. The
 * builders never print; on failure they return -1 (or a status) with err
 * filled and the model may hold part of what was being added: discard it
 * (cd_model_free). docs/embedding.md has a complete example. */
#ifndef CAPDYN_BUILD_H
#define CAPDYN_BUILD_H

#include "capdyn/model.h"
#include "capdyn/control.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- shapes, including the generated handrail ------------------------------ */

/* The kind of a shape descriptor: a cd_shape_type, or a handrail (three
 * shapes: a bar and two posts). */
#define CD_SHAPE_HANDRAIL ((int)CD_SHAPE_NTYPES)

typedef struct {
    int type;             /* a cd_shape_type or CD_SHAPE_HANDRAIL; default CD_SHAPE_SPHERE */
    double pos[3];        /* shape frame origin in the body frame [m], default 0 */
    double rot[9];        /* shape frame -> body frame, default identity (a plane's normal is the frame's z) */
    double radius;        /* sphere, cylinder, capsule, handrail bar [m] (> 0), default 0.05 */
    double length;        /* cylinder, capsule (full length along z), handrail (bar along x) [m], default 0.1 */
    double size[3];       /* box: full edge lengths [m], default 0.1 each */
    double height;        /* handrail: bar axis above its base plane z = 0 [m] (> radius), default 0.05 */
    double post;          /* handrail: side of its two square posts [m]; 0 (default) = 2 radius */
    const double *verts;  /* convex: (nvert x 3) points, shape frame [m] (copied); NULL otherwise */
    int nvert;            /* convex: at least 4 */
} cd_shape_desc;

/* The defaults listed above (by value; nothing to free). */
cd_shape_desc cd_shape_desc_default(void);

/* Adds the shape(s) of s to body `body`. A handrail is a round bar of
 * `radius` and `length` along the shape frame's x, `height` above its base
 * plane, on two square posts of side `post` at its ends: a capsule (the
 * bar) and two boxes, added in that order. Returns the id of the first
 * shape added (the others follow), or -1 with err filled. */
int cd_build_shape(cd_model *m, int body, const cd_shape_desc *s, cd_error *err);
/* Shapes cd_build_shape adds for s: 3 for a handrail, else 1. */
int cd_shape_desc_count(const cd_shape_desc *s);

/* ---- targets --------------------------------------------------------------- */

/* A rigid target (one body, a free base unless `fixed`): mass properties,
 * pose, tumbling state and its shapes. A docking fixture is a cylinder on
 * a box post, a solar-array wing a thin box: shapes of this list. */
typedef struct {
    const char *name;     /* copied; default "target" */
    int fixed;            /* 1: fixed base (a fixture of the world); default 0 (free-floating) */
    double mass;          /* [kg] (> 0), default 1 */
    double inertia[9];    /* about the CoM, body frame [kg m^2], default the unit matrix */
    double pos[3];        /* CoM, world [m] */
    double quat[4];       /* orientation (w, x, y, z), default identity */
    double vel[3];        /* CoM velocity, world [m/s] (free base only) */
    double angvel[3];     /* tumbling rate, world [rad/s] (free base only) */
    int prescribed;       /* 1: the base moves at vel, angvel whatever the forces (cd_model_prescribe_base) */
    const cd_shape_desc *shapes; /* (nshape) its shapes, on the base body, in this order */
    int nshape;
} cd_target_desc;

/* The defaults listed above (by value; nothing to free). */
cd_target_desc cd_target_desc_default(void);

/* Adds the target system and its shapes. Returns the system id, or -1 with
 * err filled. */
int cd_build_target(cd_model *m, const cd_target_desc *t, cd_error *err);

/* The cost of a tumbling rate. An adaptive stepper follows a rotation at
 * rate w with steps of a roughly fixed angle at a given tolerance, so a run
 * of `duration` s takes about c(stepper, rtol) |w| duration steps whatever
 * h_max allows: 1e6 rad/s for 1 s is millions of steps. c is the measured
 * steps per radian of a torque-free tumbling box (docs/embedding.md,
 * "Tumbling rate"): rk8pd 2.6, rkck 15, rkf45 22, rk4imp 14.5, msbdf 119,
 * ros34pw2 635 at rtol = 1e-9, scaled by (1e-9 / rtol)^(1/k) with k = 8
 * (rk8pd), 3 (ros34pw2), 6 (msbdf), 5 (the others): a rough figure for a warning
 * (within a factor of 2 of the steps taken on that tumbling box; a spin
 * about a principal axis takes up to 3 times fewer: tests/test_build.c). Returns the free system with the largest
 * initial |angular velocity| (its rate in *rate [rad/s], the steps in
 * *steps), or -1 when no free system rotates or the stepper takes fixed
 * steps (rk4: the cost is duration / h_fixed). rate and steps may be NULL. */
int cd_spin_steps(const cd_model *m, double duration, double *rate, double *steps);

/* ---- chasers ---------------------------------------------------------------- */

/* A chaser: a base (the bus, free unless `fixed`) with its shapes, an arm of
 * revolute or prismatic links, and reaction wheels (the capture
 * controller's base attitude control: an external torque on the base with a
 * per-axis limit; the wheels' own momentum is not modelled, docs/capture.md).
 * A gripper is mounted on the arm's last link with cd_build_hand
 * (attach_body), built right after the chaser. */
typedef struct {
    const char *name;     /* copied; default "chaser" */
    int fixed;            /* 1: fixed base; default 0 (free-floating) */
    double mass;          /* [kg], default 1 */
    double inertia[9];    /* about the CoM, base frame [kg m^2], default the unit matrix */
    double pos[3], quat[4], vel[3], angvel[3]; /* initial state, world (quat default identity) */
    const cd_shape_desc *shapes; /* (nshape) on the base */
    int nshape;
    const cd_link_desc *arm; /* (narm) the arm's links, each after its parent; arm[i].parent is an index
                                into arm (< i), or -1 for the base -- not a body id */
    const cd_joint_props *arm_joint; /* (narm) stops, springs, friction of each joint, or NULL (none) */
    int narm;
    int wheels;           /* 1: reaction wheels on (cd_chaser_wheels); default 0 */
    double wheel_kp, wheel_kd, wheel_torque; /* [N m/rad], [N m s/rad], per-axis limit [N m];
                                default those of cd_ctrl_config_default() */
} cd_chaser_desc;

/* The defaults listed above (by value; nothing to free). */
cd_chaser_desc cd_chaser_desc_default(void);

/* Adds the chaser: its system, base shapes and arm. Arm link i is body
 * m->sys_body_adr[sys] + 1 + i. Returns the system id, or -1 with err filled. */
int cd_build_chaser(cd_model *m, const cd_chaser_desc *c, cd_error *err);

/* The wheels in a capture controller's configuration: cfg->sys = sys and
 * the attitude law's on/gains/limit from c. */
void cd_chaser_wheels(const cd_chaser_desc *c, int sys, cd_ctrl_config *cfg);

/* ---- hands ------------------------------------------------------------------ */

#define CD_HAND_MAX_LINKS 16        /* links per finger */
#define CD_HAND_MAX_FINGERS 4
#define CD_HAND_MAX_CHECKPOINTS 100000 /* per hand (palm and fingers): the model's tables are sized by them */

/* The drive of the fingers (docs/grippers.md):
 *  TORQUE_SOFT    one motor per finger (a Soft Gripper's tendon): a torque step to `torque`
 *                 through `ratio` to every joint of the finger;
 *  TAKO           one motor for all fingers (TAKO's single tendon);
 *  SPACE          clutched fingers (cd_finger_desc): a synchronised closing, then the
 *                 equal-pressure wire mechanism at `torque`;
 *  TORQUE_SWITCH  clutched fingers, Barrett TorqueSwitch: the inner joint brakes at the clutch. */
typedef enum { CD_HAND_SOFT = 0, CD_HAND_TAKO, CD_HAND_SPACE, CD_HAND_TORQUE_SWITCH, CD_HAND_NTYPES } cd_hand_type;
/* Finger layout on the palm face: two opposed fingers, three at 120 degrees,
 * two opposed pairs (at z = -/+ pair_offset), two fingers in parallel planes
 * z = -/+ pair_offset (they pass each other). */
typedef enum { CD_HAND_TWO_OPPOSED = 0, CD_HAND_THREE_120, CD_HAND_TWO_PAIRS, CD_HAND_TWO_INTERLEAVED, CD_HAND_NLAYOUTS } cd_hand_layout;

typedef struct {
    const char *name;     /* system name of a stand-alone hand (copied), default "hand";
                             unused when mounted (the hand is the host system) */
    cd_hand_type type;    /* default CD_HAND_SPACE */
    cd_hand_layout layout;/* default CD_HAND_TWO_OPPOSED */
    int attach_body;      /* -1 (default): a new system with a fixed base (the palm) at palm_pos;
                             else the body (a link without child links) that carries the palm:
                             the fingers become its branches */
    /* palm: a box; its face y = +size_y/2 carries the fingers */
    double palm_size[3];  /* full edges [m], default (0.12, 0.04, 0.04) */
    double palm_mass;     /* [kg], default 2 (stand-alone only; mounted: part of the link's) */
    double palm_pos[3];   /* stand-alone: the base position, world; mounted: the palm frame on the body [m] */
    double palm_rot[9];   /* palm frame -> base / body frame, default identity */
    /* fingers: capsule links with check points along them */
    int nlink;            /* links per finger, 1..CD_HAND_MAX_LINKS, default 2 */
    double link_length[CD_HAND_MAX_LINKS]; /* [m] (> 0), base to tip, default 0.08 each */
    double link_mass[CD_HAND_MAX_LINKS];   /* [kg]; 0 (default) = 0.6 kg/m x length */
    double radius;        /* finger capsules and check points [m], default 0.008 */
    double spacing;       /* between the finger roots (and the palm's check-point row) [m], default 0.1 */
    double checkpoint_spacing; /* along links and palm [m]; 0 (default) = radius */
    double pair_offset;   /* TWO_PAIRS / TWO_INTERLEAVED [m]; 0 (default) = spacing / 2 / 1.5 radius */
    /* every finger joint */
    double joint_spring;  /* release spring toward 0 [N m/rad], default 0 */
    double joint_damping; /* [N m s/rad], default 0 */
    int joint_limited;    /* 1: compliant stops at [joint_lower, joint_upper] of each link; default 0 */
    double joint_lower[CD_HAND_MAX_LINKS], joint_upper[CD_HAND_MAX_LINKS]; /* [rad] */
    double joint_stop_K[CD_HAND_MAX_LINKS], joint_stop_D[CD_HAND_MAX_LINKS]; /* the stops' law per link
                             (cd_joint_props stop_K, stop_D); 0 = the defaults: K 1e3 N m/rad, D critical
                             for the subtree's inertia (docs/dynamics.md says where that overdamps) */
    double joint_stop_p, joint_stop_q; /* its exponents, every finger joint; 0 = 1 */
    double q0[CD_HAND_MAX_LINKS]; /* initial angles [rad], default 0 */
    /* the drive */
    double torque;        /* motor torque (SOFT, TAKO), grasp torque after the clutch (SPACE) [N m], default 0.2 */
    double close_time;    /* closing duration of the schedule [s], default 1 */
    double close_angle;   /* closing angle of the schedule [rad], default 120 deg */
    double close_start;   /* [s], default 0 */
    int close_on_trigger; /* 1: the motors' command / the schedules start at a controller's trigger
                             (cd_ctrl_config close_*), default 0 */
    double open_at;       /* [s] opening after the closing (0 = never, default) */
    double ratio[CD_HAND_MAX_LINKS]; /* torque split base to tip; all 0 (default) = (n - j)^2 */
    double stall_torque, noload_speed; /* motor envelope [N m], [rad/s]; 0 = none (default) */
    double clutch_threshold;   /* [N m], default 0.05 */
    double wire_stiffness;     /* [N m/rad], default 20 */
    double wire_damping;       /* [N m s/rad]; < 0 (default) = critical for a finger about its base joint */
    double torque_limit;       /* coupling limit [N m]; 0 (default) = the stall torque if any, else none; a limit not above clutch_threshold is refused (the clutch could never fire) */
} cd_hand_desc;

/* The defaults listed above (by value; nothing to free). */
cd_hand_desc cd_hand_desc_default(void);

/* What cd_build_hand made: ids for the drive, the controller and the caller. */
typedef struct {
    int sys;              /* the hand's system (the host system when mounted) */
    int palm;             /* the palm body */
    int palm_shape;       /* its box */
    int nfinger, nlink;
    int finger_body[CD_HAND_MAX_FINGERS][CD_HAND_MAX_LINKS]; /* link bodies, base to tip */
    int ncp;              /* check points added */
    /* filled by cd_build_hand_drive */
    int nact;             /* motors (SOFT: one per finger; TAKO: one) */
    int act[CD_HAND_MAX_FINGERS];
    double act_close_u[CD_HAND_MAX_FINGERS]; /* their closing command (with close_on_trigger) */
    int nclutch;          /* clutched fingers (SPACE, TORQUE_SWITCH) */
    int clutch[CD_HAND_MAX_FINGERS];
    int law;              /* the contact law of the hand's pairs */
} cd_hand;

/* Check points the hand of h would get (palm and fingers), computed without
 * making them; a huge value (up to inf) when h's spacing is tiny. -1 if h
 * is not a valid description. Used to bound a hand before it is built. */
double cd_hand_checkpoint_count(const cd_hand_desc *h);

/* Stage 1: the palm and the fingers (links, capsules, check points, joint
 * stops and springs). A stand-alone hand is a new fixed-base system; a
 * mounted one adds links to the system of h->attach_body (build it right
 * after that system's own links: a system's bodies are contiguous).
 * Refused (CD_EINVAL): more than CD_HAND_MAX_CHECKPOINTS check points
 * (checked before any is made), a finger link without check points
 * (checkpoint_spacing longer than the link), initial angles outside the
 * stops. Fills out (required). Returns out->sys or -1 with err filled. */
int cd_build_hand(cd_model *m, const cd_hand_desc *h, cd_hand *out, cd_error *err);

/* Stage 2: the drive (motors or clutched fingers, per h->type) and the
 * contact pairs with law `law`: every finger's check points against the
 * other fingers' links (except fingers in parallel planes that never
 * meet), and the hand's check points against every shape of the systems
 * target_sys[0..ntarget-1]. Call it after those systems exist. Returns
 * CD_OK, or a status with err filled. */
cd_status cd_build_hand_drive(cd_model *m, const cd_hand_desc *h, cd_hand *hand, const cd_contact_law *law,
                              const int *target_sys, int ntarget, cd_error *err);

#ifdef __cplusplus
}
#endif
#endif
