/* capdyn io layer (libcapdyn_io.a): TOML scenarios -> cd_model, and the HDF5
 * results writer/reader. Needs HDF5 and toml++ on top of the core. Nothing
 * here prints or exits; errors come back in cd_error. */
#ifndef CAPDYN_IO_H
#define CAPDYN_IO_H

#include "capdyn/model.h"
#include "capdyn/sim.h"
#include "capdyn/verdict.h"
#include "capdyn/control.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- scenarios ------------------------------------------------------------ */
/* The longest title (bytes) a scenario may have: a results file keeps it in
 * a root attribute (HDF5's object header holds 64 KiB). */
#define CD_TITLE_MAX 4096
/* A loaded scenario: a finalized model plus the run settings that are not
 * part of the physics. Strings are owned by the scenario. */
typedef struct {
    cd_model *model;       /* finalized, owned */
    char *path;            /* the file as given */
    char *title;
    char *text;            /* the scenario text as read (main file; includes appended with a header line) */
    char *overrides;       /* the --set overrides, one per line ("" if none) */
    double duration;       /* [s] */
    double output_dt;      /* sample interval of the results [s] */
    double flush_every;    /* wall-clock seconds between HDF5 flushes */
    int event_capacity;    /* event log ring size for cd_data_create */
    int interpolate;       /* simulation.sampling: 1 = samples by dense output (cd_sampler), 0 = steps stop at samples */
    int no_compress;       /* simulation.compress = false: sample series stored without shuffle + deflate */
    /* work budget of a run (docs/scenario-format.md, [simulation]); the loader
     * refuses a scenario whose least work exceeds max_rhs_evals; a runner
     * (the CLI) stops the run when either is spent. 0 = no limit. */
    double max_wall_time;  /* [s] wall-clock seconds, default 3600 */
    double max_rhs_evals;  /* right-hand-side evaluations, default 1e9 */
    double min_steps;      /* least number of integrator steps the run takes (estimate) */
    double min_rhs_evals;  /* least number of right-hand-side evaluations (estimate) */
    int capture_hand;      /* system of the [gripper]'s hand, -1 if none */
    int capture_object;    /* the object it is to capture ([capture] object, or the first [[target]]), -1 */
    double capture_v_max, capture_w_max, capture_dwell, capture_workspace; /* [capture] (verdict.h) */
    int capture_feature;   /* [capture] feature: the shape tested for enclosure, -1 = the object's CoM */
    int capture_palm;      /* the palm body ([gripper] mounted with system/attach: that link), -1 = the hand's base */
    double capture_palm_pos[3], capture_palm_rot[9]; /* the palm frame on it ([gripper] palm.position, rpy_deg) */
    cd_ctrl_config *control; /* [control]: the built-in capture controller (cd_ctrl_create), NULL if none; owned */
    char *imported;        /* systems imported from URDF: their trees (cd_urdf_describe), "" if none; owned */
    char *warnings;        /* loader warnings, one per line (a non-convex URDF mesh hulled), "" if none; owned */
} cd_scenario;

/* Loads, validates and builds a scenario. overrides are "key.path=value"
 * strings (TOML value syntax: numbers, strings in quotes, arrays), applied
 * after includes; noverrides may be 0. On error returns NULL and err->msg
 * reads "FILE:LINE:COL: key 'a.b[2].c': expected ..., got ..." (CD_EINVAL)
 * or names the file that cannot be read (CD_EIO). */
cd_scenario *cd_scenario_load(const char *path, const char *const *overrides, int noverrides,
                              cd_error *err);
/* The capture monitor's options of a scenario ([gripper] hand, [capture]
 * object, feature and thresholds; hand/object -1 if it has none). */
cd_monitor_opts cd_scenario_monitor_opts(const cd_scenario *sc);

/* The run objects of a scenario as `capdyn run` makes them: *dp its data
 * (cd_data_create with the scenario's event capacity, at the initial
 * state), *ctlp the [control] controller created and installed on that
 * data (NULL if the scenario has none). On failure both are NULL, nothing
 * is left allocated and err says why (cd_data_create's or cd_ctrl_create's
 * message; CD_EINVAL for a NULL argument). */
cd_status cd_scenario_setup(const cd_scenario *sc, cd_data **dp, cd_ctrl **ctlp, cd_error *err);

/* Frees a scenario and its model; NULL is a no-op. */
void cd_scenario_free(cd_scenario *sc);

/* ---- URDF import (docs/urdf.md) ------------------------------------------- */
/* A URDF file read and checked (liburdfdom), ready to be built into a model
 * as one system: revolute, continuous and prismatic joints become capdyn
 * joints, a fixed joint merges its child link (mass, inertia, shapes) into
 * the parent, <collision> boxes, cylinders, spheres and meshes (STL ascii or
 * binary, OBJ; their convex hull) become shapes. Floating and planar
 * joints, <mimic>, loops and cycles are refused with the element and its
 * line. */
typedef struct cd_urdf cd_urdf;

typedef struct {
    const char *name;     /* system name (copied); NULL = the URDF robot name */
    int fixed;            /* 1: fixed base (the root link welded to the world); default 0 (free) */
    double pos[3];        /* root LINK frame origin, world [m] (the base CoM is placed accordingly) */
    double quat[4];       /* root link orientation (w, x, y, z), default identity */
    double vel[3];        /* base CoM velocity, world [m/s] (free base) */
    double angvel[3];     /* base angular velocity, world [rad/s] (free base) */
    int ignore_limits;    /* 1: <limit> lower/upper are not made stops; default 0 */
    double checkpoint_spacing; /* [m] check points along each moving link (docs/urdf.md); 0 (default) = none */
    double checkpoint_radius;  /* [m] their radius, default 0 */
    const char *const *q0_joint; /* (nq0) joint names with an initial position, may be NULL */
    const double *q0;     /* (nq0) [rad | m] */
    int nq0;
} cd_urdf_opts;

/* The defaults listed above (by value). */
cd_urdf_opts cd_urdf_opts_default(void);
/* Reads and checks a URDF file. Returns NULL with err filled ("FILE:LINE:
 * <joint name=\"x\">: ...", CD_EINVAL; CD_EIO for a file that cannot be
 * read, the URDF or a mesh); never prints. Free with cd_urdf_free. */
cd_urdf *cd_urdf_read(const char *path, cd_error *err);
/* Adds the URDF's system to m (before cd_model_finalize). Body 0 of the
 * system is the root link (its frame moved to its CoM), then one body per
 * moving joint, named after its child link, depth first in file order.
 * Returns the system id, or -1 with err filled (a NULL u, m or o:
 * CD_EINVAL naming cd_urdf_build). */
int cd_urdf_build(const cd_urdf *u, cd_model *m, const cd_urdf_opts *o, cd_error *err);
/* The body of joint `joint` in system sys built from u: its id, -2 for a
 * fixed joint (merged), -1 if u has no such joint. */
int cd_urdf_joint_body(const cd_urdf *u, const cd_model *m, int sys, const char *joint);
/* The same before a build: the body's index in the system (1.., the base
 * is 0), -2 for a fixed joint, -1 if none. */
int cd_urdf_joint_index(const cd_urdf *u, const char *joint);
/* Joints of the file (moving and fixed); 0 if u is NULL. */
int cd_urdf_njoint(const cd_urdf *u);
/* Shapes cd_urdf_build adds (one per <collision>), and the name of the k-th
 * in the order added: the <collision name>, else the link's name (LINK_N,
 * N = 1.., for a link with several); NULL if k is out of range. */
int cd_urdf_nshape(const cd_urdf *u);
const char *cd_urdf_shape_name(const cd_urdf *u, int k);
/* Warnings of the import, one per line ("" if none): a non-convex mesh
 * replaced by its hull. Owned by u; NULL if u is NULL. */
const char *cd_urdf_warnings(const cd_urdf *u);
/* The <robot name>. Owned by u; NULL if u is NULL. */
const char *cd_urdf_robot_name(const cd_urdf *u);
/* The imported tree of system sys (bodies, joints, types, masses, limits),
 * one line each; malloc'd (free it), NULL on bad arguments. */
char *cd_urdf_describe(const cd_urdf *u, const cd_model *m, int sys);
/* Frees u; NULL is a no-op. */
void cd_urdf_free(cd_urdf *u);

/* ---- HDF5 results --------------------------------------------------------- */
typedef struct cd_h5_writer cd_h5_writer;

/* Creates the results file path and writes the static description (model
 * layout, names, attributes: scenario text, capdyn version, creation time).
 * The file is written under a temporary name in path's directory and
 * renamed onto path once that and the first sample (committed at once by
 * the first cd_h5_append; by cd_h5_close if there is none) are flushed, so
 * that a file at path always reads whole and an existing file is never
 * truncated, only replaced by a readable one (a symbolic link is followed);
 * the writer then holds an exclusive flock on it until cd_h5_close. Fails
 * with CD_EIO before any simulation if the file cannot be created, if path
 * is sc->path itself (same device and inode, so also through a link), is
 * not a regular file, or is locked by another writer (docs/reliability.md,
 * "Results files"). */
cd_h5_writer *cd_h5_create(const char *path, const cd_model *m, const cd_scenario *sc, cd_error *err);
/* Appends one sample of d (time, system states, slot outputs, diagnostics)
 * and any events logged since the last call. Returns CD_ENUMERIC, with err
 * naming the dataset, element, value and time, if a value of the sample is
 * not finite (the sample is kept), CD_EIO if a commit failed. */
cd_status cd_h5_append(cd_h5_writer *w, const cd_model *m, const cd_data *d, cd_error *err);
/* Flushes to disk and commits the sample counter (readers trust only that). */
cd_status cd_h5_flush(cd_h5_writer *w, cd_error *err);

/* The capture verdict of the run (verdict.h), written by cd_h5_close as the
 * root attributes capture_* (created with the layout when the scenario has
 * a gripper and an object; docs/results-format.md). Keeps a copy. */
typedef struct {
    const char *verdict;  /* "captured", "escaped", "unresolved" */
    double t;             /* [s] time of the verdict (capture or escape), NaN if unresolved */
    double peak_fn;       /* [N] */
    double peak_tau;      /* [N m] */
    double offset[3];     /* [m] object - palm centre at the end, palm frame */
    double epsilon;       /* Ferrari-Canny epsilon of the final contacts (0: no force closure) */
    int n_stick, n_slip;  /* contacts at the end */
    /* a [control] run's figures of merit (control.h, cd_ctrl_merit; docs/capture.md),
     * written as capture_dP ... capture_w_rel_end when the scenario has a [control] */
    double dP[3], dL[3];  /* momentum transferred to the chaser [kg m/s], [kg m^2/s] (about the origin) */
    double base_angle_max;/* [rad] */
    double base_rate_end; /* [rad/s] */
    double t_trigger;     /* [s] grasp trigger, NaN if none */
    double t_rigidise;    /* [s] trigger to the captured verdict, NaN if not captured */
    double v_rel_end, w_rel_end; /* target relative to the chaser base at the end [m/s], [rad/s] */
    double tau_arm_max;   /* [N m] largest arm joint torque the controller applied, at the samples */
} cd_h5_capture;
void cd_h5_set_capture(cd_h5_writer *w, const cd_h5_capture *c);
/* The peaks of every contact slot over every integrator step of the run
 * (nslot each, the model's; capdyn run keeps them in its step callback:
 * docs/cli.md "Peak forces"), written by cd_h5_close as /contacts/fn_step_max,
 * fn_step_body, fn_step_onset, ft_step_max, t_fn_step_body, t_fn_step_onset
 * (docs/results-format.md). An array given as NULL is written as NaN. */
typedef struct {
    const double *fn_max;   /* [N] the largest normal force, onset transients included */
    const double *fn_body;  /* [N] the same outside the onset windows ("peak fn over steps") */
    const double *fn_onset; /* [N] the same inside them ("onset transient"; 0: none) */
    const double *ft_max;   /* [N] the largest |tangential force| */
    const double *t_body;   /* [s] when fn_body was reached (NaN: never) */
    const double *t_onset;  /* [s] when fn_onset was reached (NaN: never) */
} cd_h5_step_peaks;
/* Keeps a copy. No-op if w or p is NULL, nslot is not the model's or the
 * model has no slots. */
void cd_h5_set_step_peaks(cd_h5_writer *w, int nslot, const cd_h5_step_peaks *p);
/* Writes the final statistics and run status, flushes and closes; frees w.
 * status/message describe how the run ended. NULL w is a no-op. */
cd_status cd_h5_close(cd_h5_writer *w, const cd_model *m, const cd_data *d, cd_status run_status,
                      const char *message, cd_error *err);

#ifdef __cplusplus
}
#endif
#endif
