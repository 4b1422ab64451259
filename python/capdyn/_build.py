"""cffi builder of capdyn._capdyn (API mode; docs/python.md).

API mode: the declarations below are compiled against capdyn's own headers
at install time, so every struct field and function signature used from
Python is checked by the C compiler (structs are declared partially, with
"...;", and the compiler supplies offsets and sizes). A change of a header
(another field, a new member order) needs a reinstall, not an edit here; a
changed signature fails the install instead of crashing at run time, as ABI
mode (dlopen) would.

Where the headers and libraries are: CAPDYN_INCLUDE_DIR / CAPDYN_LIB_DIR if
set, else the source tree this file sits in (include/ and $CAPDYN_BUILD or
build/, after `make`), else `pkg-config capdyn-io` (an installed capdyn).
The extension links libcapdyn_io.so and libcapdyn.so with an rpath to that
library directory.
"""
import os
import shlex
import subprocess

from cffi import FFI

CDEF = r"""
typedef enum { CD_OK, CD_EINVAL, CD_ENOMEM, CD_ENUMERIC, CD_ESTALL, CD_EMAXSTEPS, CD_EIO,
               CD_EINTERRUPT, CD_EBUDGET, ... } cd_status;
typedef struct { cd_status status; char msg[...]; ...; } cd_error;
const char *cd_status_string(cd_status s);
const char *cd_version(void);

typedef enum { CD_BASE_FREE, CD_BASE_FIXED, ... } cd_base_type;
typedef enum { CD_JOINT_BASE, CD_JOINT_REVOLUTE, CD_JOINT_PRISMATIC, ... } cd_joint_type;
typedef enum { CD_SHAPE_PLANE, CD_SHAPE_SPHERE, CD_SHAPE_BOX, CD_SHAPE_CYLINDER, CD_SHAPE_CAPSULE,
               CD_SHAPE_CONVEX, CD_SHAPE_NTYPES, ... } cd_shape_type;
typedef enum { CD_ACT_NONE, CD_ACT_CONSTANT, CD_ACT_TABLE, CD_ACT_PD, CD_ACT_STEPS, CD_ACT_NTYPES, ... } cd_act_type;
typedef enum { CD_PRESCRIBE_NONE, CD_PRESCRIBE_VELOCITY, CD_PRESCRIBE_WAYPOINTS, ... } cd_prescribe_type;
typedef enum { CD_STEP_RKF45, CD_STEP_RKCK, CD_STEP_RK8PD, CD_STEP_RK4IMP, CD_STEP_MSBDF, CD_STEP_RK4_FIXED,
               CD_STEP_ROS34PW2, CD_STEP_NTYPES, ... } cd_stepper;
typedef enum { CD_FINGER_SPACE, CD_FINGER_TORQUE_SWITCH, CD_FINGER_NTYPES, ... } cd_finger_type;
typedef enum { CD_MODE_OPEN, CD_MODE_STICK, CD_MODE_SLIP, ... } cd_slot_mode;
typedef enum { CD_VERDICT_UNRESOLVED, CD_VERDICT_CAPTURED, CD_VERDICT_ESCAPED, CD_VERDICT_CAGED, ... } cd_verdict;
typedef enum { CD_CTRL_APPROACH, CD_CTRL_CLOSING, CD_CTRL_HOLD, CD_CTRL_DETUMBLE, ... } cd_ctrl_phase;
typedef enum { CD_EV_NKINDS, ... } cd_event_kind;
typedef enum { CD_OWNER_NKINDS, ... } cd_owner_kind;

const char *cd_shape_type_name(cd_shape_type t);
const char *cd_stepper_name(cd_stepper s);
int cd_stepper_from_name(const char *name);
const char *cd_event_kind_name(cd_event_kind k);
const char *cd_owner_kind_name(cd_owner_kind k);
const char *cd_slot_mode_name(cd_slot_mode m);
const char *cd_verdict_name(cd_verdict v);

typedef struct {
    cd_stepper stepper;
    double rtol, atol, h_init, h_max, h_min, h_fixed;
    long max_steps;
    double event_tol, dwell, v_reg, fd_eps;
    long max_evals;
    int equilibrium_start;
    ...;
} cd_options;
cd_options cd_options_default(void);
cd_status cd_options_check(const cd_options *o, cd_error *err);

typedef struct {
    double K, D, p, q, Kt, Dt, mu_s, mu_k, pt, qt;
    int pull;
    int damping;
    ...;
} cd_contact_law;
cd_contact_law cd_contact_law_default(void);
cd_contact_law cd_contact_law_from_rule(double k_soft, double k_ratio, double m_eff, double zeta, double mu);

typedef struct {
    const char *name;
    cd_act_type type;
    double tau0, kp, kd, qref;
    const double *tbl_t, *tbl_v;
    int ntbl;
    int ntrn;
    const int *trn_body;
    const double *trn_ratio;
    double stall_torque, noload_speed;
    ...;
} cd_actuator_desc;
cd_actuator_desc cd_actuator_desc_default(void);

typedef struct {
    const char *name;
    cd_finger_type type;
    int njoint;
    const int *joint_body;
    const double *sync;
    const double *ratio;
    double wire_K, wire_D, threshold, grasp_torque, torque_limit;
    const double *sched_t, *sched_q;
    int nsched;
    double open_at;
    ...;
} cd_finger_desc;
cd_finger_desc cd_finger_desc_default(void);

typedef struct {
    double stiffness, rest, damping, friction, friction_k, friction_d;
    int limited;
    double lower, upper;
    double stop_K, stop_D, stop_p, stop_q;
    cd_prescribe_type prescribe;
    double presc_v, presc_t0;
    const double *presc_t, *presc_q;
    int npresc;
    ...;
} cd_joint_props;
cd_joint_props cd_joint_props_default(void);

typedef struct {
    const char *name;
    cd_base_type type;
    double mass;
    double inertia[9];
    double pos[3];
    double quat[4];
    double vel[3];
    double angvel[3];
    ...;
} cd_system_desc;
typedef struct {
    const char *name;
    int parent;
    cd_joint_type type;
    double pos[3];
    double rot[9];
    double axis[3];
    double mass;
    double com[3];
    double inertia[9];
    double q0, qd0;
    ...;
} cd_link_desc;
cd_system_desc cd_system_desc_default(void);
cd_link_desc cd_link_desc_default(void);

typedef struct cd_model {
    int nsys, nbody, ncp, nshape, nlaw, nslot, nu, nv, ny, nlim, nfric, nuser, nfinger;
    int finalized;
    double gravity[3];
    cd_options opt;
    char **sys_name;
    int *sys_base_type, *sys_body_adr, *sys_nbody, *sys_ndof, *sys_v_adr;
    char **body_name;
    int *body_sys, *body_parent, *body_jnt_type, *body_dof;
    char **act_name;
    int *cp_body;
    int *shape_body, *shape_type;
    int *slot_cp, *slot_shape;
    ...;
} cd_model;
cd_model *cd_model_create(void);
void cd_model_free(cd_model *m);
int cd_model_add_system(cd_model *m, const cd_system_desc *s, cd_error *err);
int cd_model_add_link(cd_model *m, int sys, const cd_link_desc *l, cd_error *err);
int cd_model_add_checkpoint(cd_model *m, int body, const double pos[3], double radius, cd_error *err);
int cd_model_add_shape(cd_model *m, int body, cd_shape_type type, const double pos[3], const double rot[9],
                       const double size[3], const double *verts, int nvert, cd_error *err);
int cd_model_add_law(cd_model *m, const cd_contact_law *law, cd_error *err);
int cd_model_add_pair(cd_model *m, int sys, int body, int shape, int law, cd_error *err);
int cd_model_add_actuator(cd_model *m, const cd_actuator_desc *a, cd_error *err);
cd_status cd_model_set_joint(cd_model *m, int body, const cd_joint_props *p, cd_error *err);
cd_status cd_model_prescribe_base(cd_model *m, int sys, const double v[3], const double w[3], cd_error *err);
int cd_model_add_finger(cd_model *m, const cd_finger_desc *f, cd_error *err);
int cd_model_actuator_id(const cd_model *m, const char *name);
int cd_model_body_id(const cd_model *m, const char *name);
int cd_model_system_id(const cd_model *m, const char *name);
cd_status cd_model_finalize(cd_model *m, cd_error *err);

typedef struct {
    long nrhs, nsteps, nrejected, nevents, nlocate_steps, nwarn_geom, nwarn_dwell, nwarn_budget, nrenorm,
         nrestart, njac;
    double h_last, h_min_seen, h_max_seen;
    ...;
} cd_stats;
typedef struct {
    double t;
    int kind, slot, body_a, body_b, mode_from, mode_to;
    double x, fn, ft;
    int owner_kind, owner;
    ...;
} cd_event;
typedef struct {
    void *(*alloc)(size_t size, void *ctx);
    void (*free)(void *ptr, void *ctx);
    void *ctx;
} cd_allocator;
typedef struct cd_data {
    double t;
    double *y, *ydot;
    cd_options opt;
    double *ctrl, *qfrc_applied, *xfrc_applied, *xfrc_body;
    int *user_mode;
    double *body_R, *body_x, *body_c, *body_w, *body_v;
    double *udot, *qfrc_actuator, *qfrc_passive, *qfrc_constraint, *tau, *act_force;
    int *slot_mode;
    double *slot_x, *slot_fn, *slot_ft, *slot_point, *slot_normal;
    int *lim_mode;
    double *lim_force;
    int *finger_mode;
    double *finger_t0;
    int ev_cap;
    long ev_count;
    cd_stats stats;
    ...;
} cd_data;
typedef int (*cd_step_callback)(const cd_model *m, cd_data *d, void *user);
typedef int (*cd_sample_fn)(const cd_model *m, const cd_data *sample, void *user);
typedef void (*cd_control_fn)(const cd_model *m, cd_data *d, void *user);

cd_data *cd_data_create_ex(const cd_model *m, int event_capacity, const cd_allocator *alloc, cd_error *err);
void cd_data_free(cd_data *d);
cd_status cd_data_reset(const cd_model *m, cd_data *d, cd_error *err);
void cd_data_set_control(cd_data *d, cd_control_fn fn, void *user);
const cd_event *cd_data_event(const cd_data *d, long i);
size_t cd_state_size(const cd_model *m);
void cd_state_get(const cd_model *m, cd_data *d, double *buf);
cd_status cd_state_set(const cd_model *m, cd_data *d, const double *buf, cd_error *err);
cd_status cd_state_copy(const cd_model *m, cd_data *dst, cd_data *src, cd_error *err);
typedef struct { double *pos, *quat, *q, *vel, *angvel, *qd; int njoint; } cd_sys_state;
cd_sys_state cd_state_of(const cd_model *m, const cd_data *d, int sys);

void cd_kinematics(const cd_model *m, cd_data *d);
void cd_mass_matrix(const cd_model *m, cd_data *d, int s, double *H);
void cd_momentum(const cd_model *m, const cd_data *d, int s, double *ke, double P[3], double L_com[3],
                 double L_origin[3], double com[3]);
double cd_potential_energy(const cd_model *m, const cd_data *d, int s);
cd_status cd_forward(const cd_model *m, cd_data *d);
cd_status cd_sim_advance(const cd_model *m, cd_data *d, double t_end, cd_step_callback cb, void *user,
                         cd_error *err);
cd_status cd_step(const cd_model *m, cd_data *d, double h, cd_error *err);

typedef struct cd_sampler cd_sampler;
cd_sampler *cd_sampler_create(const cd_model *m, cd_error *err);
void cd_sampler_free(cd_sampler *s);
cd_status cd_sampler_begin(cd_sampler *s, const cd_model *m, const cd_data *d, double t_first, double dt,
                           cd_error *err);
int cd_sampler_update(cd_sampler *s, const cd_model *m, const cd_data *d, cd_sample_fn fn, void *user);

typedef struct {
    int hand, object;
    double v_max, w_max, dwell, workspace;
    int feature, palm;
    double palm_pos[3], palm_rot[9];
    ...;
} cd_monitor_opts;
typedef struct {
    cd_monitor_opts opt;
    cd_verdict verdict;
    double t_capture, t_escape, peak_fn, peak_tau;
    int n_stick, n_slip;
    double offset[3];
    double offset_norm;
    double point[3];
    int enclosed;
    double v_rel, w_rel, qd_max;
    double t_cage, epsilon;
    ...;
} cd_monitor;
cd_monitor_opts cd_monitor_opts_default(void);
cd_status cd_monitor_init(cd_monitor *mo, const cd_model *m, const cd_data *d, const cd_monitor_opts *opt,
                          cd_error *err);
void cd_monitor_update(cd_monitor *mo, const cd_model *m, const cd_data *d);
cd_status cd_monitor_quality(const cd_monitor *mo, const cd_model *m, const cd_data *d, double *eps,
                             int *closure, cd_error *err);

typedef struct { ...; } cd_ctrl_config;
typedef struct cd_ctrl cd_ctrl;
cd_ctrl *cd_ctrl_create(const cd_model *m, const cd_ctrl_config *c, cd_error *err);
void cd_ctrl_free(cd_ctrl *c);
void cd_ctrl_install(cd_ctrl *c, cd_data *d);
cd_ctrl_phase cd_ctrl_phase_of(const cd_ctrl *c, const cd_data *d);
double cd_ctrl_t_trigger(const cd_ctrl *c);
size_t cd_ctrl_state_size(const cd_ctrl *c);
void cd_ctrl_state_get(const cd_ctrl *c, double *buf);
cd_status cd_ctrl_state_set(cd_ctrl *c, const double *buf, cd_error *err);
typedef struct {
    int target;
    double P0[3], L0[3], dP[3], dL[3];
    double base_angle_max, base_rate, v_rel, w_rel, tau_arm_max;
    ...;
} cd_ctrl_merit;
void cd_ctrl_merit_init(cd_ctrl_merit *f, const cd_ctrl *c, const cd_model *m, const cd_data *d);
void cd_ctrl_merit_update(cd_ctrl_merit *f, const cd_ctrl *c, const cd_model *m, const cd_data *d);

typedef struct {
    cd_model *model;
    char *path, *title, *text, *overrides;
    double duration, output_dt, flush_every;
    int event_capacity, interpolate, no_compress;
    double max_wall_time, max_rhs_evals, min_steps, min_rhs_evals;
    int capture_hand, capture_object;
    cd_ctrl_config *control;
    ...;
} cd_scenario;
cd_scenario *cd_scenario_load(const char *path, const char *const *overrides, int noverrides, cd_error *err);
cd_monitor_opts cd_scenario_monitor_opts(const cd_scenario *sc);
void cd_scenario_free(cd_scenario *sc);

/* Python callbacks (capdyn/core.py) */
extern "Python" void *_cd_py_alloc(size_t size, void *ctx);
extern "Python" void _cd_py_free(void *ptr, void *ctx);
extern "Python" int _cd_py_step(const cd_model *m, cd_data *d, void *user);
extern "Python" int _cd_py_sample(const cd_model *m, const cd_data *sample, void *user);
extern "Python" void _cd_py_control(const cd_model *m, cd_data *d, void *user);
"""

# The builders (include/capdyn/build.h: hands, targets, chasers), when the
# headers have them: declared only then, so that the package also builds
# against a capdyn without them (capdyn.HAVE_BUILDERS tells).
BUILD_CDEF = r"""
typedef struct {
    int type;
    double pos[3];
    double rot[9];
    double radius, length;
    double size[3];
    double height, post;
    const double *verts;
    int nvert;
    ...;
} cd_shape_desc;
cd_shape_desc cd_shape_desc_default(void);
int cd_build_shape(cd_model *m, int body, const cd_shape_desc *s, cd_error *err);
int cd_shape_desc_count(const cd_shape_desc *s);
typedef struct {
    const char *name;
    int fixed;
    double mass;
    double inertia[9];
    double pos[3];
    double quat[4];
    double vel[3];
    double angvel[3];
    int prescribed;
    const cd_shape_desc *shapes;
    int nshape;
    ...;
} cd_target_desc;
cd_target_desc cd_target_desc_default(void);
int cd_build_target(cd_model *m, const cd_target_desc *t, cd_error *err);
int cd_spin_steps(const cd_model *m, double duration, double *rate, double *steps);
typedef struct {
    const char *name;
    int fixed;
    double mass;
    double inertia[9];
    double pos[3], quat[4], vel[3], angvel[3];
    const cd_shape_desc *shapes;
    int nshape;
    const cd_link_desc *arm;
    const cd_joint_props *arm_joint;
    int narm;
    int wheels;
    double wheel_kp, wheel_kd, wheel_torque;
    ...;
} cd_chaser_desc;
cd_chaser_desc cd_chaser_desc_default(void);
int cd_build_chaser(cd_model *m, const cd_chaser_desc *c, cd_error *err);
typedef enum { CD_HAND_SOFT, CD_HAND_TAKO, CD_HAND_SPACE, CD_HAND_TORQUE_SWITCH, CD_HAND_NTYPES, ... } cd_hand_type;
typedef enum { CD_HAND_TWO_OPPOSED, CD_HAND_THREE_120, CD_HAND_TWO_PAIRS, CD_HAND_TWO_INTERLEAVED,
               CD_HAND_NLAYOUTS, ... } cd_hand_layout;
typedef struct {
    const char *name;
    cd_hand_type type;
    cd_hand_layout layout;
    int attach_body;
    double palm_size[3];
    double palm_mass;
    double palm_pos[3];
    double palm_rot[9];
    int nlink;
    double link_length[...];
    double link_mass[...];
    double radius, spacing, checkpoint_spacing, pair_offset, joint_spring, joint_damping;
    int joint_limited;
    double joint_lower[...];
    double joint_upper[...];
    double joint_stop_K[...];
    double joint_stop_D[...];
    double joint_stop_p, joint_stop_q;
    double q0[...];
    double torque, close_time, close_angle, close_start;
    int close_on_trigger;
    double open_at;
    double ratio[...];
    double stall_torque, noload_speed, clutch_threshold, wire_stiffness, wire_damping, torque_limit;
    ...;
} cd_hand_desc;
cd_hand_desc cd_hand_desc_default(void);
typedef struct {
    int sys, palm, palm_shape, nfinger, nlink;
    int finger_body[4][16];
    int ncp, nact;
    int act[...];
    double act_close_u[...];
    int nclutch;
    int clutch[...];
    int law;
    ...;
} cd_hand;
double cd_hand_checkpoint_count(const cd_hand_desc *h);
int cd_build_hand(cd_model *m, const cd_hand_desc *h, cd_hand *out, cd_error *err);
cd_status cd_build_hand_drive(cd_model *m, const cd_hand_desc *h, cd_hand *hand, const cd_contact_law *law,
                              const int *target_sys, int ntarget, cd_error *err);
"""

SOURCE = r"""
#include <capdyn/capdyn.h>
#include <capdyn/io.h>
#include <capdyn/verdict.h>
"""


def _locate():
    inc = os.environ.get("CAPDYN_INCLUDE_DIR")
    lib = os.environ.get("CAPDYN_LIB_DIR")
    if inc and lib:
        return [inc], [lib], []
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.dirname(os.path.dirname(here))
    build = os.environ.get("CAPDYN_BUILD", os.path.join(root, "build"))
    if not os.path.isabs(build):
        build = os.path.join(root, build)
    if os.path.isfile(os.path.join(root, "include", "capdyn", "io.h")) and \
            os.path.exists(os.path.join(build, "libcapdyn_io.so")):
        return [os.path.join(root, "include")], [build], []
    try:
        cflags = subprocess.run(["pkg-config", "--cflags-only-I", "capdyn-io"], check=True,
                                capture_output=True, text=True).stdout
        libdir = subprocess.run(["pkg-config", "--variable=libdir", "capdyn-io"], check=True,
                                capture_output=True, text=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        raise RuntimeError("capdyn: cannot find capdyn's headers and shared libraries: run `make` in the "
                           "source tree first, set CAPDYN_INCLUDE_DIR and CAPDYN_LIB_DIR, or install "
                           "capdyn (make install) so that `pkg-config capdyn-io` finds it")
    return [f[2:] for f in shlex.split(cflags) if f.startswith("-I")], [libdir], []


_inc, _lib, _ = _locate()
HAVE_BUILDERS = any(os.path.isfile(os.path.join(i, "capdyn", "build.h")) for i in _inc)
ffibuilder = FFI()
ffibuilder.cdef(CDEF + (BUILD_CDEF if HAVE_BUILDERS else ""))
if HAVE_BUILDERS:
    SOURCE += "#include <capdyn/build.h>\n"
ffibuilder.set_source(
    "capdyn._capdyn", SOURCE,
    include_dirs=_inc,
    library_dirs=_lib,
    runtime_library_dirs=_lib,
    libraries=["capdyn_io", "capdyn"],
    extra_compile_args=["-std=c99", "-Wall"],
)

if __name__ == "__main__":
    ffibuilder.compile(verbose=True)
