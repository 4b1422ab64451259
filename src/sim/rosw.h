/* Internal: the linearly implicit steppers ROS34PW2 (Rosenbrock-W) and RODAS4 (Rosenbrock) (rosw.c). */
#ifndef CD_ROSW_H
#define CD_ROSW_H
#include "capdyn/sim.h"
#include "jac.h"
#include <gsl/gsl_odeiv2.h>
#include <stddef.h>

/* Closed contact slots whose 3 tangential deflections join the implicit
 * (active) set; slots closed beyond this many are treated explicitly (a
 * W-method stays of order 3 with any approximate Jacobian). */
#define CD_ROSW_MAX_SLOTS 96
/* Accepted steps a Jacobian is kept before it is recomputed. */
#ifndef CD_ROSW_JAC_AGE
#define CD_ROSW_JAC_AGE 20
#endif
/* N: the N-th consecutive retry from the same start (the steps before were
 * rejected) renews a Jacobian formed earlier; 0 never does. 2 by default: a
 * first rejection is most often the error estimate asking for a shorter step
 * (docs/performance.md section 15 measures 1, 2 and 0; a build-time trial:
 * -DCD_ROSW_RENEW_ON_RETRY=1). */
#ifndef CD_ROSW_RENEW_ON_RETRY
#define CD_ROSW_RENEW_ON_RETRY 2
#endif

/* 1: rodas4 uses the structured Jacobian (simulation.jacobian) without df/dt
 * instead of the difference one: a build-time trial only (-DCD_RODAS4_STRUCTURED_JAC=1,
 * docs/performance.md section 9: the order is lost and the steps collapse). */
#ifndef CD_RODAS4_STRUCTURED_JAC
#define CD_RODAS4_STRUCTURED_JAC 0
#endif

typedef struct {
    const cd_model *m;        /* set for the duration of one call (as the integrator's) */
    cd_data *d;
    int ny, na_max, na;       /* state size; active unknowns: capacity, current */
    int *act;                 /* (na_max) their indices in y */
    double *J, *W;            /* (na_max^2) Jacobian on the active set; iteration matrix, LU */
    int *perm;                /* (na_max) row interchanges of the LU */
    double *k[6], *g, *ytmp, *fs, *fd, *r; /* stage vectors (ny; g: scratch of the solve and
                                            * the spectral radius); r: (na_max) */
    double *ft;               /* (ny) df/dt at the Jacobian's point (rodas4 only) */
    double gam;               /* the bound method's diagonal gamma (cd_rosw_bind) */
    double fd_eps_plain;      /* cd_rosw_init_plain: the difference increment (no model) */
    int jac_ok, lu_ok;        /* J valid; W holds the LU of I - h gamma J for h = lu_h */
    double jac_t, lu_h;
    long jac_age;             /* accepted steps since J was computed */
    cd_jacw jw;               /* work space of the structured Jacobian (opt.jacobian = CD_JAC_MODEL) */
    /* the reduced solve of a structured Jacobian (rosw.c, reduce()): the
     * active unknowns split into positions P, velocities U and anchors Z */
    int red, nP, nU, nZ;
    int *iP, *iU, *iZ;        /* (na_max each) their places in the active set */
    double *M2;               /* (na_max^2) J_UP J_PU + J_UZ J_ZU, nU x nU */
    double *tu;               /* (na_max) */
    double *sv;               /* (na_max^2 / 2) nonzeros of J_U,PZ then J_PZ,U (reduce()) */
    int *sp, *sc;             /* their row starts (2 na_max + 2) and columns */
    int nrun, *rlo, *rhi;     /* (ny + 2 each) the runs of unknowns that can move (cd_moving_runs) */
    int *jlo, *jhi;           /* (na_max each) each row's first and one past its last nonzero in J
                               * (cd_rosw_spectral_radius) */
    double rho;               /* the spectral radius of J, valid while rho_ok: the stepper's J has */
    int rho_ok;               /* not been formed again since (cd_rosw_spectral_radius) */
} cd_rosw;

/* Bytes of the buffers of cd_rosw_init (16-aligned start). */
size_t cd_rosw_size(const cd_model *m);
/* Lays the buffers out in mem. */
void cd_rosw_init(cd_rosw *w, const cd_model *m, cd_data *d, void *mem);
/* A workspace without a model (tests): every one of the ny unknowns is
 * implicit; the Jacobian is the system's own (gsl_odeiv2_system.jacobian,
 * row-major, with df/dt) if it has one, else forward differences with
 * increment fd_eps. */
size_t cd_rosw_size_plain(int ny);
void cd_rosw_init_plain(cd_rosw *w, int ny, double fd_eps, void *mem);
/* The LU of I - c J on the active set into W (na_max^2) and perm (na_max):
 * of the velocities' block S = I - c J_UU - c^2 M2 when J was reduced
 * (reduce() in rosw.c: a structured Jacobian), else of the whole na x na
 * matrix. 0, or -1 on a zero pivot. */
int cd_rosw_factor_c(const cd_rosw *w, double c, double *W, int *perm);
/* r <- (I - c J)^-1 r, r over the active set, with the LU cd_rosw_factor_c
 * made for the same c and the same J; u, rpz: scratch of na_max each. */
void cd_rosw_solve_c(const cd_rosw *w, double c, const double *W, const int *perm, double *r, double *u,
                     double *rpz);
/* The next step recomputes the Jacobian (a restart: modes, inputs or state changed). */
void cd_rosw_invalidate(cd_rosw *w);

/* Spectral radius of the right-hand side's Jacobian at (t, y) [1/s], by
 * power iteration on the current Jacobian if valid, else on a structured one
 * formed for it (one evaluation; the stepper's own is not replaced). -1 if
 * the evaluation fails. Uses the stage buffers (between steps only). */
double cd_rosw_spectral_radius(cd_rosw *w, double t, const double *y);

/* For the Gauss (gauss4.c) and BDF (bdf.c) steppers, which use this
 * workspace's Jacobian:
 * the active set's capacity; the Jacobian of a ros34pw2 step (no df/dt:
 * simulation.jacobian's structured one, reduce()d, or the forward difference
 * on the active set; plain: the system's own or forward differences) formed
 * at (t, y) with f0 = f(t, y) into w->J (w->na x w->na, row-major, on w->act);
 * GSL_EBADFUNC if an evaluation fails. */
int cd_rosw_na_max(const cd_model *m);
int cd_rosw_jacobian(cd_rosw *w, double t, const double *y, const double *f0, const gsl_odeiv2_system *sys);
/* In-place LU with partial pivoting of a row-major n x n matrix (no
 * allocation); -1 on a zero or non-finite pivot. And its solve, b in place. */
int cd_rosw_lu_decomp(double *A, int n, int *piv);
void cd_rosw_lu_solve(const double *A, int n, const int *piv, double *b);

/* The GSL stepper type. Each step object must be bound to the workspace;
 * a locator's steps share the Jacobian of the main stepper's step start and
 * never invalidate it. */
extern const gsl_odeiv2_step_type *cd_step_ros34pw2;
/* RODAS4 (Hairer & Wanner; rosw.c): order 4(3), L-stable, stiffly accurate,
 * a Rosenbrock method (not W): it renews a finite-difference Jacobian on the
 * active set, and df/dt, at every step start. */
extern const gsl_odeiv2_step_type *cd_step_rodas4;
void cd_rosw_bind(gsl_odeiv2_step *s, cd_rosw *w, int locator);
/* The tableau's nodes c_i = sum_j alpha_ij and gamma_i = gamma + sum_j
 * gamma_ij (tests: against the published ones); returns the stage count. */
int cd_rosw_tableau_sums(const gsl_odeiv2_step_type *T, double *c, double *gsum);

#endif
