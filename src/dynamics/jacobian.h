/* Internal: the generalized Jacobian on some of its columns (jacobian.c). */
#ifndef CD_JACOBIAN_H
#define CD_JACOBIAN_H
#include "capdyn/sim.h"

/* cd_generalized_jacobian's columns cols[0..ncols) (joint indices, 0 = the
 * system's first joint) into Jg (6 x nj, row-major), bit for bit what the
 * whole Jacobian has there; the other columns are left as they are. Leaves
 * in d->H the mass matrix's entries that cd_mass_matrix_cols gives for
 * these columns (mass.h: the base block, their base rows and columns and
 * their diagonal; not the rest). For a controller that drives some joints
 * (the capture controller: the arm, not the fingers). */
cd_status cd_generalized_jacobian_cols(const cd_model *m, cd_data *d, int body, const double p_body[3], double *Jg,
                                       const int *cols, int ncols);

#endif
