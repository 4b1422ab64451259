/* Point Jacobians and the generalized Jacobian of a free-floating system.
 *
 * Columns are built from the joint axes in world coordinates (body_axisw)
 * and the joint origins (body_x) that cd_kinematics leaves in d: O(depth)
 * per column, no matrix products. */
#include "capdyn/sim.h"
#include "../math/cd_math.h"
#include "jacobian.h"
#include "mass.h"

#include <string.h>

void cd_point_jacobian(const cd_model *m, const cd_data *d, int body, const double p_body[3], double *J)
{
    if (!m || !d || !p_body || !J) return;
    int s = m->body_sys[body], n = m->sys_ndof[s], b0 = m->sys_body_adr[s], a, k;
    int j0 = m->sys_base_type[s] == CD_BASE_FREE ? 6 : 0;
    double p[3], r[3], c[3];
    memset(J, 0, 6 * (size_t)n * sizeof(double));
    cd_point_world(m, d, body, p_body, p, NULL);
    if (j0) {
        /* base: v = v0 + w0 x (p - r0), w = w0 */
        cd_v3_sub(r, p, d->body_x + 3 * b0);
        for (k = 0; k < 3; k++) {
            double e[3] = {0, 0, 0};
            e[k] = 1.0;
            J[k * n + k] = 1.0;
            cd_v3_cross(c, e, r);
            J[0 * n + 3 + k] = c[0];
            J[1 * n + 3 + k] = c[1];
            J[2 * n + 3 + k] = c[2];
            J[(3 + k) * n + 3 + k] = 1.0;
        }
    }
    /* joints on the path from the body to the base */
    for (a = body; a > b0; a = m->body_parent[a]) {
        int col = j0 + a - b0 - 1;
        const double *z = d->body_axisw + 3 * a;
        if (m->body_jnt_type[a] == CD_JOINT_REVOLUTE) {
            cd_v3_sub(r, p, d->body_x + 3 * a);
            cd_v3_cross(c, z, r);
            for (k = 0; k < 3; k++) {
                J[k * n + col] = c[k];
                J[(3 + k) * n + col] = z[k];
            }
        } else {
            for (k = 0; k < 3; k++) J[k * n + col] = z[k];
        }
    }
}

/* J_g's columns cols[0..ncols) (joint indices 0..nj-1; all when cols is
 * NULL) into Jg (6 x nj, row-major); the other columns are not written.
 * Each column is computed by the same operations whichever are asked. */
static cd_status gen_jacobian(const cd_model *m, cd_data *d, int body, const double p_body[3], double *Jg,
                              const int *cols, int ncols, cd_error *err)
{
    int s = m->body_sys[body], n = m->sys_ndof[s], nj = n - 6, i, j, k, c;
    double *J = d->jwork, *Hb = J + 6 * n, *X = Hb + 36;
    if (m->sys_base_type[s] != CD_BASE_FREE) {
        cd_error_set(err, CD_EINVAL, "generalized Jacobian: system '%s' has a fixed base (use cd_point_jacobian)",
                     m->sys_name[s]);
        return CD_EINVAL;
    }
    if (!cols) ncols = nj;
    cd_point_jacobian(m, d, body, p_body, J);
    cd_mass_matrix_cols(m, d, s, d->H, cols, ncols); /* the base block and rows, the diagonal (cols NULL: all) */
    /* X = H_b^-1 H_bq, one column at a time */
    for (i = 0; i < 6; i++)
        for (j = 0; j < 6; j++) Hb[6 * i + j] = d->H[i * n + j];
    if (cd_chol_decomp(Hb, 6) != 0) {
        cd_error_set(err, CD_ENUMERIC, "generalized Jacobian: the base inertia block of '%s' is singular", m->sys_name[s]);
        return CD_ENUMERIC;
    }
    for (c = 0; c < ncols; c++) {
        double col[6];
        j = cols ? cols[c] : c;
        for (i = 0; i < 6; i++) col[i] = d->H[i * n + 6 + j];
        cd_chol_solve(Hb, 6, col);
        for (i = 0; i < 6; i++) X[6 * j + i] = col[i];
    }
    /* Jg = J_q - J_b X */
    for (i = 0; i < 6; i++)
        for (c = 0; c < ncols; c++) {
            double v;
            j = cols ? cols[c] : c;
            v = J[i * n + 6 + j];
            for (k = 0; k < 6; k++) v -= J[i * n + k] * X[6 * j + k];
            Jg[i * nj + j] = v;
        }
    return CD_OK;
}

cd_status cd_generalized_jacobian(const cd_model *m, cd_data *d, int body, const double p_body[3], double *Jg,
                                  cd_error *err)
{
    if (!m || !d || !p_body || !Jg) {
        cd_error_set(err, CD_EINVAL, "cd_generalized_jacobian: %s is NULL", !m ? "the model" : !d ? "the data" : !p_body ? "p_body" : "Jg");
        return CD_EINVAL;
    }
    return gen_jacobian(m, d, body, p_body, Jg, NULL, 0, err);
}

cd_status cd_generalized_jacobian_cols(const cd_model *m, cd_data *d, int body, const double p_body[3], double *Jg,
                                       const int *cols, int ncols)
{
    return gen_jacobian(m, d, body, p_body, Jg, cols, ncols, NULL);
}
