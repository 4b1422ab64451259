/* Internal: some entries of the mass matrix (dynamics.c). */
#ifndef CD_MASS_H
#define CD_MASS_H
#include "capdyn/sim.h"

/* The entries of cd_mass_matrix's H (system s, n x n, row-major) that the
 * joints cols[0..ncols) (joint indices, 0 = the system's first joint) have
 * on the diagonal and, for a free base, in the base rows and columns, and
 * the base block: bit for bit what the whole H has there. Every other
 * entry is left as it is (not zeroed). For the capture controller, which
 * reads the arm's diagonal, and the generalized Jacobian on some columns,
 * which reads the base rows: the couplings between joints, O(n depth) of
 * the whole H's work, are not computed. cols NULL: the whole H, as
 * cd_mass_matrix. */
void cd_mass_matrix_cols(const cd_model *m, cd_data *d, int s, double *H, const int *cols, int ncols);

#endif
