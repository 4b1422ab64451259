/* Articulated-body forward dynamics (internal to the dynamics layer).
 *
 * cd_forward_dynamics (dynamics.c) calls cd_aba_forward for systems with
 * sys_ndof >= CD_ABA_MIN_DOF and the composite-rigid-body path below that;
 * the crossover is measured by bench/bench_speed.c (docs/performance.md). */
#ifndef CD_ABA_H
#define CD_ABA_H

#include "capdyn/sim.h"

/* Systems with this many generalized velocities or more use ABA. Measured
 * (bench/bench_speed.c, bench/results/2026-11-24.txt, docs/performance.md):
 * ABA is faster than CRBA + Cholesky at every size tried, from a single free
 * body (6 DoF, 200 vs 254 ns with kinematics, minima) and a 1-joint fixed
 * base (211 vs 238 ns) up to 64 joints (10.7 vs 42.8 us): the CRBA path forms every body's spatial inertia
 * twice (RNE bias, then H) and adds the O(n^3) factorisation, while ABA forms
 * them once. So ABA is the default everywhere; CRBA stays available
 * (cd_forward_dynamics_method) and behind cd_mass_matrix. Re-measure with
 * `make bench` when either path changes: it prints the crossover. */
#define CD_ABA_MIN_DOF 1

/* Doubles of ABA scratch per body, taken from the start of d->work (nothing
 * else in work is live during cd_forward_dynamics); cd_data_create sizes
 * work to at least CD_ABA_WORK_PER_BODY nbody. */
#define CD_ABA_WORK_PER_BODY 64

/* Forward dynamics of system s by Featherstone's articulated-body algorithm,
 * after cd_kinematics: reads d->tau, d->body_fext, gravity; writes the
 * system's block of d->udot ([vdot0; wdot0; qdd] for a free base). O(n),
 * allocates nothing. CD_ENUMERIC if an articulated inertia is not positive
 * definite. */
cd_status cd_aba_forward(const cd_model *m, cd_data *d, int s);

#endif
