/* capdyn: simulation data (cd_data), kinematics, dynamics, contact and the
 * event-driven integrator. Everything here works on a finalized cd_model and
 * a cd_data created from it; no step allocates after cd_data_create(), with
 * any stepper (the implicit rk4imp and msbdf are capdyn's own since they
 * replaced GSL's, which allocated inside their LU). */
#ifndef CAPDYN_SIM_H
#define CAPDYN_SIM_H

#include "capdyn/model.h"
#include "capdyn/data.h"

#ifdef __cplusplus
extern "C" {
#endif

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

/* Full pipeline at (t, y): kinematics, the control callback, contacts (modes
 * as they are), joint elements and actuation, the inputs, dynamics, then
 * ydot. CD_ENUMERIC on a non-finite value. d->tau is the sum
 * qfrc_actuator + qfrc_passive + qfrc_applied (the user's wrenches go to
 * body_fext, not to tau). */
cd_status cd_forward(const cd_model *m, cd_data *d);

/* Outputs of slot k at d's last evaluation as the full evaluation gives
 * them, also for a slot the broad phase skipped (d->slot_far[k]: computed
 * here from d's kinematics, bit for bit what evaluating it would have
 * written). Any output pointer may be NULL. No allocation. */
void cd_contact_slot_outputs(const cd_model *m, const cd_data *d, int k, double *x, double *xdot, double *fnraw,
                             double point[3], double normal[3], double vt[3]);
/* Fills in the outputs of every slot the last evaluation skipped (and
 * clears d->slot_far): afterwards every slot_* array holds the full
 * evaluation's values. */
void cd_contact_complete(const cd_model *m, cd_data *d);

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
 * (cd_sim_advance then returns CD_EINTERRUPT). It may write the inputs
 * (ctrl, qfrc_applied, xfrc_*): a change takes effect from that instant, the
 * stepper restarting there. May be NULL. */
typedef int (*cd_step_callback)(const cd_model *m, cd_data *d, void *user);

/* Advances from d->t to t_end (exactly), locating every event on the way.
 * Inputs changed since the previous call, an edited y or t, and every
 * schedule breakpoint restart the stepper at that instant (a torque step is
 * exact, never smeared over a step). Returns CD_OK, or CD_ESTALL /
 * CD_EMAXSTEPS / CD_ENUMERIC / CD_EINTERRUPT / CD_EBUDGET (opt.max_evals)
 * with err filled; d then holds the last good state. */
cd_status cd_sim_advance(const cd_model *m, cd_data *d, double t_end,
                         cd_step_callback cb, void *user, cd_error *err);

/* One step of a fixed-rate loop: advances by exactly h, to t = t_origin + k h
 * (k counted since the origin, which is set where h changes or t/y are
 * written, so time never drifts). With the fixed-step stepper (rk4) this is
 * one classic RK4 step: 4 evaluations when nothing changed since the last
 * call (the end-of-step evaluation serves as the next first stage), events
 * inside the step located as in cd_sim_advance; with an adaptive stepper it
 * is cd_sim_advance to that time. With opt.max_evals > 0 the call never
 * spends more evaluations than that: an event is then landed at the end of
 * its current bracket (stats.nwarn_budget counts it); CD_EBUDGET if the
 * budget cannot cover one step with an event (20 evaluations: the re-check
 * after a changed input 5, the step 4, the event's bracket start 1 and a
 * reserve of 10 for the landing, the mode cascade and the rest of the step).
 * A schedule breakpoint inside the step splits it: 4 more evaluations each. */
cd_status cd_step(const cd_model *m, cd_data *d, double h, cd_error *err);

/* ---- dense output: samples by interpolation (src/sim/sampler.c) ----------
 * A run sampled every dt need not stop the integrator at every sample: call
 * cd_sim_advance once over the whole span with a step callback that calls
 * cd_sampler_update. Every sample time t_k = t_first + k dt inside the last
 * step (t_prev, t] gets the cubic Hermite interpolant of the step's end
 * states and derivatives (with the step's modes: an event ends a step, so
 * the modes are constant inside it), evaluated on the sampler's own data
 * (cd_forward: every output of the sample is that of the interpolated
 * state), and passed to fn. The interpolation error is O(h^4 y'''') of the
 * step h, third order: below the step's own error for steps the error
 * control accepts (docs/dynamics.md, "Dense output"). The sampler's
 * evaluations are not counted in d->stats; a sample's stats are the run's
 * at the end of the step that contains it. Allocates at create only. */
typedef struct cd_sampler cd_sampler;
/* Called for each sample; `sample` holds the interpolated state, evaluated.
 * Return non-zero to stop (cd_sampler_update then returns it). */
typedef int (*cd_sample_fn)(const cd_model *m, const cd_data *sample, void *user);
cd_sampler *cd_sampler_create(const cd_model *m, cd_error *err);
void cd_sampler_free(cd_sampler *s);
/* Starts at d's current state (evaluated, e.g. right after cd_data_create or
 * a step callback); samples at t_first + k dt, k = 0, 1, ..., those <= d->t
 * excluded. CD_EINVAL for dt <= 0 or non-finite times. */
cd_status cd_sampler_begin(cd_sampler *s, const cd_model *m, const cd_data *d, double t_first, double dt,
                           cd_error *err);
/* After an accepted step or an event (d evaluated at its end, as in a step
 * callback): emits every sample in (t_prev, d->t] in order, then takes d's
 * state as the start of the next step. Returns 0, fn's non-zero value, or
 * -1 if a sample state cannot be evaluated (non-finite). */
int cd_sampler_update(cd_sampler *s, const cd_model *m, const cd_data *d, cd_sample_fn fn, void *user);
/* The next sample time. */
double cd_sampler_next(const cd_sampler *s);


#ifdef __cplusplus
}
#endif
#endif
