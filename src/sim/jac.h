/* Internal: the structured (model) Jacobian of the right-hand side for the
 * linearly implicit steppers (jac.c). */
#ifndef CD_JAC_H
#define CD_JAC_H
#include "capdyn/sim.h"
#include <stddef.h>

typedef struct {
    int *map;      /* (ny) index of each y entry in the active set, -1 if not active */
    int *qi, *vi;  /* (nv) y index of each generalized coordinate's position (-1: base, handled apart) and velocity */
    double *dQ;    /* (nv x na_max) generalized-force derivatives, column per active unknown */
    double *G[2];  /* (6 x maxdof) point Jacobians of the two bodies of a slot */
    double *T;     /* (maxdof x 3) G^T A of one side */
    double *L;     /* (maxdof^2) Cholesky factor of one system's mass matrix */
    double *ys;    /* (ny) perturbed state of the joint-element differences */
    double *Q0, *Q1; /* (nv) joint-element generalized forces */
    double *z0, *z1; /* (nfric + 1) joint-friction anchor rates */
    int na_max, maxdof;
} cd_jacw;

/* Bytes of the buffers of cd_jacw_init for na_max active unknowns. */
size_t cd_jacw_size(const cd_model *m, int na_max);
void cd_jacw_init(cd_jacw *w, const cd_model *m, int na_max, void *mem);

/* J (na x na, row-major) ~ df/dy on the active set act[0..na) at (t, y),
 * assembled from the model (docs/performance.md, "The structured Jacobian"):
 *   - kinematic rows exactly (r0' = v0, quat' = 0.5 w x quat, q' = qd);
 *   - velocity rows H^-1 dQ/dy, where dQ/dy holds every contact slot that is
 *     closed (normal spring/damper, stick spring/damper or the slip law's
 *     Coulomb force, each mapped through the contact points' Jacobians:
 *     Gᵀ (dF/dv) G, Gᵀ (dF/dp) G E, Gᵀ dF/dz) and the joint elements and
 *     actuation (springs, dampers, stops, joint friction, motor laws, the
 *     Space/TorqueSwitch couplings: a difference in joint space, which costs
 *     no kinematics);
 *   - the stick anchors' rows R_Bᵀ P G and the joint-friction anchors' rows.
 * Left out (not stiff: of the order of the forces, not of the stiffnesses):
 * the Coriolis and gravity terms, the turning of contact normals and frames
 * with the bodies, the dependence of H on q and the control callback's law.
 * Evaluates f once at (t, y) (counted in stats.nrhs); d's outputs are those of
 * that evaluation on return. CD_ENUMERIC if the evaluation or a mass matrix
 * fails. */
cd_status cd_jac_model(const cd_model *m, cd_data *d, double t, const double *y, const int *act, int na,
                       double *J, cd_jacw *w);

#endif
