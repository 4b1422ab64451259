/* capdyn analysis (libcapdyn_io.a): measures computed from a finished run or
 * a contact set, for run summaries and capture verdicts. Not part of the
 * embeddable core: the grasp-quality measure needs Qhull (libqhull_r).
 * Nothing here prints or exits; errors come back as cd_status + cd_error.
 * docs/grasp-quality.md gives the definitions, normalisation and limits. */
#ifndef CAPDYN_ANALYSIS_H
#define CAPDYN_ANALYSIS_H

#include "capdyn/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- Ferrari-Canny grasp quality (epsilon, L1 / "sum of normal forces") --- */

/* One point contact of a finger on the object, world frame. */
typedef struct {
    double p[3];  /* contact point [m] */
    double n[3];  /* contact normal pointing INTO the object (the direction the finger
                     pushes); any non-zero length, normalised internally */
    double mu;    /* Coulomb friction coefficient [-], >= 0; 0 = frictionless contact */
    double t[3];  /* optional first tangent of the linearised friction cone (3-D mode);
                     (0,0,0) = chosen from n alone. Give it (e.g. the slip direction or
                     a body-fixed axis) when results must be invariant under rotating
                     the whole grasp; its component along n is removed. */
} cd_grasp_contact;

typedef enum {
    CD_GRASP_SPATIAL = 0, /* 3-D grasp: wrench space 6-D (force, torque) */
    CD_GRASP_PLANAR = 1   /* planar grasp in the plane normal to plane_normal:
                             wrench space 3-D (in-plane force, torque about plane_normal) */
} cd_grasp_mode;

/* Settings; take them from cd_grasp_options_default() and edit. */
typedef struct {
    cd_grasp_mode mode;     /* default CD_GRASP_SPATIAL */
    double plane_normal[3]; /* planar mode: the plane's normal (any non-zero length);
                               default (0,0,1) */
    double rho;             /* torque scale [m]: torques are divided by rho; 0 (default)
                               = max_i |p_i - c| (in-plane distance in planar mode),
                               1 m if every contact sits at c. A given rho must be
                               within a factor 1e6 of max_i |p_i - c|. */
    int cone_edges;         /* 3-D mode: edges m of each linearised friction cone,
                               3..64, default 8. Planar mode always uses the two
                               in-plane edges n +- mu t. */
} cd_grasp_options;

/* The result of cd_grasp_quality_eval. */
typedef struct {
    double epsilon;    /* [-] radius of the largest origin-centred ball inside the convex
                          hull of the primitive wrenches (forces in units of the summed
                          normal force, torques divided by rho); 0 without force closure */
    int force_closure; /* 1 if the origin is strictly inside the hull, else 0 */
    double rho;        /* [m] the torque scale used */
    int dim;           /* wrench-space dimension: 6 (3-D) or 3 (planar) */
    int nwrench;       /* number of primitive wrenches (1 per frictionless contact,
                          m (3-D) or 2 (planar) per frictional one) */
    int nfacet;        /* hull facets examined (0 if no hull was built) */
} cd_grasp_quality;

/* Defaults: 3-D mode, plane_normal (0,0,1), rho = 0 (automatic), 8 cone edges. */
cd_grasp_options cd_grasp_options_default(void);

/* Ferrari-Canny epsilon of n contacts on an object whose reference point
 * (its centre of mass) is c [m], world frame. Each contact i contributes the
 * primitive forces of unit normal component
 *     f_ij = n_i + mu_i (cos th_j t1_i + sin th_j t2_i),  th_j = 2 pi j / m
 * (3-D; only f = n_i if mu_i = 0; planar: f = n_i +- mu_i t_i in the plane)
 * and the wrenches w_ij = (f_ij, (p_i - c) x f_ij / rho). epsilon is the
 * minimum over the hull facets of the distance from the origin to the facet
 * (computed with Qhull). opt may be NULL (defaults); err may be NULL.
 * Returns CD_OK with q filled, including the physically right answer for a
 * degenerate wrench set (fewer than dim+1 wrenches, or wrenches whose hull
 * is flat: lower-dimensional than the wrench space): epsilon 0,
 * force_closure 0.
 * Returns CD_EINVAL (err names the contact and field) on n < 1, a NULL
 * contacts, c or q, a non-finite value, a zero normal (or, planar, a normal
 * perpendicular to the plane), mu < 0, a tangent parallel to its normal,
 * rho < 0 or out of scale (above), lever arms that overflow, cone_edges out
 * of range or an unknown mode; CD_ENUMERIC if Qhull fails (precision or
 * topology error; err carries Qhull's first message line); CD_ENOMEM if
 * allocation fails. On error q->epsilon is 0 and q->force_closure 0.
 * Allocates and frees its own scratch; no global state (reentrant Qhull),
 * so concurrent calls are safe. */
cd_status cd_grasp_quality_eval(const cd_grasp_contact *contacts, int n, const double c[3],
                                const cd_grasp_options *opt, cd_grasp_quality *q, cd_error *err);

#ifdef __cplusplus
}
#endif
#endif
