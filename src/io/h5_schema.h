/* Internal: the shape of every time series of a results file
 * (docs/results-format.md), shared by the writer (src/io/h5.c, which
 * creates what it lists) and the reader (src/io/h5_read.c, which checks
 * every series it reads against it before trusting a size from the file).
 * A new series is one row here plus its values in cd_h5_append. */
#ifndef CD_H5_SCHEMA_H
#define CD_H5_SCHEMA_H

/* How many values a row of a series has, from the model's sizes. */
typedef enum {
    CD_SH_ONE = 0,   /* 1 (a scalar per sample) */
    CD_SH_V3,        /* 3 */
    CD_SH_V4,        /* 4 */
    CD_SH_NSYS,      /* nsys */
    CD_SH_NSYS3,     /* nsys x 3 */
    CD_SH_NSLOT,     /* nslot */
    CD_SH_NSLOT3,    /* nslot x 3 */
    CD_SH_NJOINT,    /* the system's joints */
    CD_SH_NBODY3,    /* the system's bodies x 3 */
    CD_SH_NBODY4,    /* the system's bodies x 4 */
    CD_SH_NU         /* actuators */
} cd_h5_shape;

enum { CD_H5_F64 = 0, CD_H5_I64, CD_H5_I8 };

/* where a series lives: "/" + name, "/systems/<group>/" + name, ... */
typedef enum { CD_G_ROOT = 0, CD_G_SYSTEM, CD_G_CONTACTS, CD_G_DIAGNOSTICS, CD_G_ACTUATORS } cd_h5_group;

typedef struct {
    cd_h5_group group;
    const char *name;
    int type;            /* CD_H5_F64, CD_H5_I64, CD_H5_I8 */
    cd_h5_shape shape;
    const char *units, *description;
} cd_h5_series_def;

/* Series ids: an index into cd_h5_series_defs. */
typedef enum {
    CD_SER_TIME = 0,
    CD_SER_BASE_POS,
    CD_SER_BASE_QUAT,
    CD_SER_BASE_VEL,
    CD_SER_BASE_ANGVEL,
    CD_SER_Q,
    CD_SER_QD,
    CD_SER_TAU,
    CD_SER_TAU_ACTUATOR,
    CD_SER_TAU_PASSIVE,
    CD_SER_TAU_APPLIED,
    CD_SER_BODY_X,
    CD_SER_BODY_C,
    CD_SER_BODY_QUAT,
    CD_SER_FN,
    CD_SER_FT,
    CD_SER_PENETRATION,
    CD_SER_PENETRATION_RATE,
    CD_SER_POINT,
    CD_SER_NORMAL,
    CD_SER_SLIP_VELOCITY,
    CD_SER_MODE,
    CD_SER_KE,
    CD_SER_PE,
    CD_SER_MOMENTUM,
    CD_SER_L_COM,
    CD_SER_L_ORIGIN,
    CD_SER_COM,
    CD_SER_STEP_SIZE,
    CD_SER_NRHS,
    CD_SER_NSTEPS,
    CD_SER_NREJECTED,
    CD_SER_NEVENTS,
    CD_SER_WALL_TIME,
    CD_SER_CTRL,
    CD_SER_ACT_FORCE,
    CD_SER_ACT_VELOCITY,
    CD_SER_COUNT
} cd_h5_series_id;

/* Every time series, in the writer's order (within a group). The contact
 * series exist only when the model has slots, q and qd only for a system
 * with joints. */
static const cd_h5_series_def cd_h5_series_defs[CD_SER_COUNT] = {
    [CD_SER_TIME] = {CD_G_ROOT, "time", CD_H5_F64, CD_SH_ONE, "s", "simulated time of each sample"},
    [CD_SER_BASE_POS] = {CD_G_SYSTEM, "base_pos", CD_H5_F64, CD_SH_V3, "m", "base CoM position, world (SpaceDyn R0)"},
    [CD_SER_BASE_QUAT] = {CD_G_SYSTEM, "base_quat", CD_H5_F64, CD_SH_V4, "1", "base orientation (w,x,y,z), body -> world"},
    [CD_SER_BASE_VEL] = {CD_G_SYSTEM, "base_vel", CD_H5_F64, CD_SH_V3, "m/s", "base CoM velocity, world"},
    [CD_SER_BASE_ANGVEL] = {CD_G_SYSTEM, "base_angvel", CD_H5_F64, CD_SH_V3, "rad/s", "base angular velocity, world"},
    [CD_SER_Q] = {CD_G_SYSTEM, "q", CD_H5_F64, CD_SH_NJOINT, "rad|m", "joint positions, in body order"},
    [CD_SER_QD] = {CD_G_SYSTEM, "qd", CD_H5_F64, CD_SH_NJOINT, "rad/s|m/s", "joint rates, in body order"},
    [CD_SER_TAU] = {CD_G_SYSTEM, "tau", CD_H5_F64, CD_SH_NJOINT, "N m|N",
     "joint torques applied in all: actuators + passive elements + applied inputs"},
    [CD_SER_TAU_ACTUATOR] = {CD_G_SYSTEM, "tau_actuator", CD_H5_F64, CD_SH_NJOINT, "N m|N",
     "joint torques of the actuators (their laws + ctrl, motor envelope, transmissions, clutched fingers)"},
    [CD_SER_TAU_PASSIVE] = {CD_G_SYSTEM, "tau_passive", CD_H5_F64, CD_SH_NJOINT, "N m|N",
     "joint torques of springs, dampers, Coulomb friction and stops"},
    [CD_SER_TAU_APPLIED] = {CD_G_SYSTEM, "tau_applied", CD_H5_F64, CD_SH_NJOINT, "N m|N",
     "the caller's generalized-force inputs on the joints (qfrc_applied)"},
    [CD_SER_BODY_X] = {CD_G_SYSTEM, "body_x", CD_H5_F64, CD_SH_NBODY3, "m", "body frame origins (joint; base CoM), world"},
    [CD_SER_BODY_C] = {CD_G_SYSTEM, "body_c", CD_H5_F64, CD_SH_NBODY3, "m", "body centres of mass, world"},
    [CD_SER_BODY_QUAT] = {CD_G_SYSTEM, "body_quat", CD_H5_F64, CD_SH_NBODY4, "1", "body orientations (w,x,y,z), body -> world"},
    [CD_SER_FN] = {CD_G_CONTACTS, "fn", CD_H5_F64, CD_SH_NSLOT, "N", "normal force (0 when open)"},
    [CD_SER_FT] = {CD_G_CONTACTS, "ft", CD_H5_F64, CD_SH_NSLOT3, "N", "tangential force on the check-point body, world"},
    [CD_SER_PENETRATION] = {CD_G_CONTACTS, "penetration", CD_H5_F64, CD_SH_NSLOT, "m", "penetration depth, > 0 inside"},
    [CD_SER_PENETRATION_RATE] = {CD_G_CONTACTS, "penetration_rate", CD_H5_F64, CD_SH_NSLOT, "m/s", "penetration rate"},
    [CD_SER_POINT] = {CD_G_CONTACTS, "point", CD_H5_F64, CD_SH_NSLOT3, "m", "contact point, world"},
    [CD_SER_NORMAL] = {CD_G_CONTACTS, "normal", CD_H5_F64, CD_SH_NSLOT3, "1", "unit normal from the shape toward the check point"},
    [CD_SER_SLIP_VELOCITY] = {CD_G_CONTACTS, "slip_velocity", CD_H5_F64, CD_SH_NSLOT3, "m/s", "tangential relative velocity"},
    [CD_SER_MODE] = {CD_G_CONTACTS, "mode", CD_H5_I8, CD_SH_NSLOT, "1", "0 open, 1 stick, 2 slip"},
    [CD_SER_KE] = {CD_G_DIAGNOSTICS, "kinetic_energy", CD_H5_F64, CD_SH_NSYS, "J", "kinetic energy per system"},
    [CD_SER_PE] = {CD_G_DIAGNOSTICS, "potential_energy", CD_H5_F64, CD_SH_NSYS, "J", "gravitational potential energy per system"},
    [CD_SER_MOMENTUM] = {CD_G_DIAGNOSTICS, "momentum", CD_H5_F64, CD_SH_NSYS3, "kg m/s", "linear momentum per system, world"},
    [CD_SER_L_COM] = {CD_G_DIAGNOSTICS, "angular_momentum_com", CD_H5_F64, CD_SH_NSYS3, "kg m^2/s", "angular momentum about the system CoM"},
    [CD_SER_L_ORIGIN] = {CD_G_DIAGNOSTICS, "angular_momentum_origin", CD_H5_F64, CD_SH_NSYS3, "kg m^2/s",
     "angular momentum about the world origin"},
    [CD_SER_COM] = {CD_G_DIAGNOSTICS, "com", CD_H5_F64, CD_SH_NSYS3, "m", "system centre of mass, world"},
    [CD_SER_STEP_SIZE] = {CD_G_DIAGNOSTICS, "step_size", CD_H5_F64, CD_SH_ONE, "s", "last accepted integrator step"},
    [CD_SER_NRHS] = {CD_G_DIAGNOSTICS, "nrhs", CD_H5_I64, CD_SH_ONE, "1", "right-hand-side evaluations so far"},
    [CD_SER_NSTEPS] = {CD_G_DIAGNOSTICS, "nsteps", CD_H5_I64, CD_SH_ONE, "1", "accepted steps so far"},
    [CD_SER_NREJECTED] = {CD_G_DIAGNOSTICS, "nrejected", CD_H5_I64, CD_SH_ONE, "1", "rejected trial steps so far"},
    [CD_SER_NEVENTS] = {CD_G_DIAGNOSTICS, "nevents", CD_H5_I64, CD_SH_ONE, "1", "events located so far"},
    [CD_SER_WALL_TIME] = {CD_G_DIAGNOSTICS, "wall_time", CD_H5_F64, CD_SH_ONE, "s", "wall-clock time since the file was created"},
    [CD_SER_CTRL] = {CD_G_ACTUATORS, "ctrl", CD_H5_F64, CD_SH_NU, "N m|N", "control input of each actuator (d->ctrl)"},
    [CD_SER_ACT_FORCE] = {CD_G_ACTUATORS, "force", CD_H5_F64, CD_SH_NU, "N m|N",
     "actuator torque: law + ctrl, after the motor envelope, before the transmission ratios"},
    [CD_SER_ACT_VELOCITY] = {CD_G_ACTUATORS, "velocity", CD_H5_F64, CD_SH_NU, "rad/s|m/s",
     "transmission rate sum_j ratio_j qdot_j"},
};
#define CD_H5_NSERIES_DEFS ((int)CD_SER_COUNT)

/* The number of values per row of shape sh, and the tail dimensions the
 * dataset has (*ntail 0, 1 or 2). */
static inline long cd_h5_shape_rowlen(cd_h5_shape sh, long nsys, long nslot, long njoint, long nbody, long nu,
                                      int *ntail, long tail[2])
{
    long t0 = 0, t1 = 0;
    int nt = 1;
    switch (sh) {
    case CD_SH_ONE: nt = 0; break;
    case CD_SH_V3: t0 = 3; break;
    case CD_SH_V4: t0 = 4; break;
    case CD_SH_NSYS: t0 = nsys; break;
    case CD_SH_NSYS3: t0 = nsys; t1 = 3; nt = 2; break;
    case CD_SH_NSLOT: t0 = nslot; break;
    case CD_SH_NSLOT3: t0 = nslot; t1 = 3; nt = 2; break;
    case CD_SH_NJOINT: t0 = njoint; break;
    case CD_SH_NU: t0 = nu; break;
    case CD_SH_NBODY3: t0 = nbody; t1 = 3; nt = 2; break;
    case CD_SH_NBODY4: t0 = nbody; t1 = 4; nt = 2; break;
    }
    if (ntail) *ntail = nt;
    if (tail) {
        tail[0] = t0;
        tail[1] = t1;
    }
    return nt == 0 ? 1 : nt == 1 ? t0 : t0 * t1;
}

/* The peaks over every integrator step of each contact slot (not only at
 * the samples: docs/cli.md "Peak forces"), four (nslot) float64 datasets in
 * /contacts. Created with the layout (contiguous, allocated at
 * once, NaN) and written in place by cd_h5_close when the run gave them
 * (cd_h5_set_step_peaks): NaN in a file whose run was killed. Files from
 * before them have no such datasets. */
enum {
    CD_H5_STEP_FN_MAX = 0,
    CD_H5_STEP_FN_BODY,
    CD_H5_STEP_FN_ONSET,
    CD_H5_STEP_FT_MAX,
    CD_H5_STEP_T_BODY,
    CD_H5_STEP_T_ONSET,
    CD_H5_STEP_COUNT
};
static const char *const cd_h5_step_peak_names[CD_H5_STEP_COUNT] = {
    "fn_step_max",     /* [N] the largest normal force over every step, onset transients included */
    "fn_step_body",    /* [N] the same outside the onset windows: "peak fn over steps" */
    "fn_step_onset",   /* [N] the same inside them: "onset transient" (0: none) */
    "ft_step_max",     /* [N] the largest |tangential force| over every step */
    "t_fn_step_body",  /* [s] when fn_step_body was reached (NaN: never) */
    "t_fn_step_onset", /* [s] when fn_step_onset was reached (NaN: never) */
};
static const char *const cd_h5_step_peak_units[CD_H5_STEP_COUNT] = {"N", "N", "N", "N", "s", "s"};

#endif
