/* capdyn: choice of the forward-dynamics algorithm.
 *
 * cd_forward_dynamics (sim.h) picks, per system, the composite-rigid-body
 * algorithm with a Cholesky solve (CRBA) for small trees and the O(n)
 * articulated-body algorithm (ABA) from cd_fd_aba_min_dof() generalized
 * velocities on; the crossover was measured on this code (docs/performance.md).
 * Both give the same accelerations to round-off. This header lets a caller
 * (a benchmark, a test, an embedder with unusual trees) force one of them. */
#ifndef CAPDYN_DYNAMICS_H
#define CAPDYN_DYNAMICS_H

#include "capdyn/sim.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    CD_FD_AUTO = 0,  /* CRBA below cd_fd_aba_min_dof() DoFs, ABA from there on */
    CD_FD_CRBA,      /* composite-rigid-body mass matrix + Cholesky, O(n^2)-O(n^3) */
    CD_FD_ABA        /* articulated-body algorithm, O(n) */
} cd_fd_method;

/* cd_forward_dynamics with the algorithm forced (CD_FD_AUTO = the default
 * choice). Same inputs, outputs and failure (CD_ENUMERIC for a mass matrix or
 * an articulated inertia that is not positive definite); allocates nothing. */
cd_status cd_forward_dynamics_method(const cd_model *m, cd_data *d, cd_fd_method method);

/* Number of generalized velocities of a system (6 + joints for a free base,
 * joints for a fixed one) from which CD_FD_AUTO uses ABA. */
int cd_fd_aba_min_dof(void);

#ifdef __cplusplus
}
#endif
#endif
