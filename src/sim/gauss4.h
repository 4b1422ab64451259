/* Internal: the implicit 2-stage Gauss-Legendre stepper behind
 * simulation.integrator = "rk4imp" (gauss4.c). */
#ifndef CD_GAUSS4_H
#define CD_GAUSS4_H
#include "rosw.h"

/* Newton iterations per stage solve before the step is given up (GSL's
 * evolve then retries with half the step). */
#define CD_GAUSS4_NEWTON_MAX 10
/* The simplified Newton iteration stops when its estimated remaining error
 * is below this fraction of the step's tolerance (atol + rtol |y|). */
#define CD_GAUSS4_KAPPA 0.01

typedef struct {
    cd_rosw *rw;              /* the Jacobian on the active set (rosw.c's workspace) */
    int ny, na2_max;          /* state size; 2 x the active set's capacity */
    double *M[2];             /* ((2 na)^2 each) LU of the iteration matrix for the step h and h/2 */
    int *piv[2];              /* (2 na) their row interchanges */
    double lu_h[2];           /* the step each LU is for; 0: none */
    double *z1, *z2, *dz1, *dz2, *f1, *f2, *yt, *ybig, *ymid, *f0, *r; /* (ny); r: (2 na) */
    double *za1, *za2, *zb1, *zb2; /* (ny) the stages of the first and second half step */
    int have_pred;            /* zb* are the last step's, which ended at t_next (starting values) */
    double t_next, h_pred;    /* that end; that half step */
    double rtol, atol;        /* the Newton tolerance (from the data's options; plain: set) */
    double eta;               /* the last contraction estimate theta / (1 - theta) (carried, H&W IV.8) */
    int renew;                /* the last step failed in Newton: renew an old Jacobian */
    long nnewton, nfail;      /* Newton iterations and failed stage solves (tests) */
} cd_gauss4;

/* Bytes of the buffers for a model (on top of cd_rosw_size) and lays them out. */
size_t cd_gauss4_size(const cd_model *m);
void cd_gauss4_init(cd_gauss4 *g, cd_rosw *rw, const cd_model *m, void *mem);
/* Without a model (tests): rw made by cd_rosw_init_plain(ny); rtol/atol
 * are the Newton iteration's tolerance. */
size_t cd_gauss4_size_plain(int ny);
void cd_gauss4_init_plain(cd_gauss4 *g, cd_rosw *rw, int ny, double rtol, double atol, void *mem);

/* The GSL stepper type (name "rk4imp", order 4); each step object must be
 * bound to a workspace before its first step. */
extern const gsl_odeiv2_step_type *cd_step_gauss4;
void cd_gauss4_bind(gsl_odeiv2_step *s, cd_gauss4 *g);

#endif
