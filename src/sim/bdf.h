/* Internal: the variable-order variable-step BDF stepper behind
 * simulation.integrator = "msbdf" (bdf.c). */
#ifndef CD_BDF_H
#define CD_BDF_H
#include "rosw.h"

#define CD_BDF_KMAX 5        /* the highest order */
#define CD_BDF_NHIST 7       /* solution points kept: order k + 2 for the order choice */
#define CD_BDF_NEWTON_MAX 10 /* Newton iterations before the step is given up (evolve halves it) */
#define CD_BDF_KAPPA 0.01    /* Newton stops when its estimated remaining error is below this x tolerance */
#define CD_BDF_KAPPA_TRIAL 1e-4 /* ... in cd_bdf_trial: a locator's solution must be smooth in its length */
#define CD_BDF_GAMMA_TOL 0.3 /* the iteration matrix is refactored when h/alpha0 changed by more */
#define CD_BDF_RATIO_MAX 1.5 /* above order 1 a step grows by at most this factor (else refused) */
#define CD_BDF_SLIVER 1e-6   /* ... unless the last step was shorter than this times the new one: a
                              * sliver (an output time a few ulps on), after which the history restarts */

typedef struct {
    cd_rosw *rw;              /* the Jacobian on the active set (rosw.c's workspace) */
    int ny, na_max;
    double *Y[CD_BDF_NHIST];  /* (ny each) accepted solution points, [0] the newest */
    double th[CD_BDF_NHIST];  /* their times */
    int nh;                   /* how many are kept */
    double *yp, *F, *dY, *f0, *psi, *ypred; /* (ny) Newton iterate, f, increment, f at the start, history term, predictor */
    double *M, *r, *u, *rpz;  /* (na^2) LU of I - gamma J (reduced to the velocities when J is: rosw.c,
                               * cd_rosw_factor_c); (na each) the Newton right-hand side, scratch */
    int *piv;                 /* (na) */
    double lu_gamma;          /* the gamma M is for; 0: none */
    int k, k_next, k_used, nk; /* order: current, chosen for the next step, of the last apply; steps at k */
    int kmax;                 /* the highest order used (CD_BDF_KMAX) */
    int kfix;                 /* tests: > 0 forces this order once the history allows it */
    int have_pend, nrej;      /* an applied step not yet confirmed by the next call; rejections in a row */
    double t0p, t1p;          /* its start and end */
    double rtol, atol;        /* the Newton and order-choice tolerance (from the data's options; plain: set) */
    double eta;               /* the last contraction estimate theta / (1 - theta) */
    int renew;                /* the last step failed in Newton: renew an old Jacobian */
    long nnewton, nfail, nratio, nsteps_k[CD_BDF_KMAX + 1]; /* Newton iterations, failed solves, refused step growths, steps per order */
    long ntrial, ntrial_fail; /* cd_bdf_trial: trials solved; trials refused or failed (tests) */
} cd_bdf;

size_t cd_bdf_size(const cd_model *m);
void cd_bdf_init(cd_bdf *g, cd_rosw *rw, const cd_model *m, void *mem);
size_t cd_bdf_size_plain(int ny);
void cd_bdf_init_plain(cd_bdf *g, cd_rosw *rw, int ny, double rtol, double atol, void *mem);
/* Tests: appends (t, y) as the newest accepted point of the history (a
 * startup from known values). */
void cd_bdf_seed(cd_bdf *g, double t, const double *y);

/* Event location on msbdf's own solution: the step of the pending (last
 * applied) step's order from its start (t0, the history's newest point) to
 * t0 + tau, tau in (0, h], over the same history, its Newton iteration
 * carried to CD_BDF_KAPPA_TRIAL; the result in y. The history and the
 * pending step are left as they are (the LU may be renewed for the trial's
 * gamma). GSL_SUCCESS, GSL_FAILURE (not at the pending step's start, or
 * Newton did not converge) or GSL_EBADFUNC (a non-finite value). */
int cd_bdf_trial(cd_bdf *g, const gsl_odeiv2_system *sys, double t0, double tau, double *y);

/* The step the next apply at t would take instead of h: h, or the longest
 * step its growth rule (CD_BDF_RATIO_MAX) lets it take, with the history
 * as that apply will see it (the pending step accepted when t is its end).
 * The driver clips its proposal with it: a step refused for its growth is
 * halved by GSL's evolve, to below the last step when the proposal was under
 * 2x it, where the clipped one grows by the full 1.5x. */
double cd_bdf_step_limit(const cd_bdf *g, double t, double h);

/* The GSL stepper type (name "msbdf"; order() the order of the last step);
 * each step object must be bound to a workspace before its first step. */
extern const gsl_odeiv2_step_type *cd_step_bdf;
void cd_bdf_bind(gsl_odeiv2_step *s, cd_bdf *g);

#endif
