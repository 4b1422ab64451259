/* The variables of a capdyn FMU (docs/fmu.md), built from a loaded scenario
 * in one fixed order: `capdyn fmu` writes them into modelDescription.xml
 * and the FMU binary builds the same list at fmi2Instantiate, so that a
 * value reference is an index into this list (parameters follow it, in the
 * order of --param). Shared by the CLI (src/cli/fmu.c) and the wrapper
 * (src/fmu/fmu.c); no printing, allocation only in cdf_vars_build. */
#ifndef CD_FMU_VARS_H
#define CD_FMU_VARS_H

#include "capdyn/io.h"

typedef enum { CDF_OUTPUT = 0, CDF_INPUT = 1, CDF_PARAMETER = 2 } cdf_causality;
typedef enum { CDF_REAL = 0, CDF_INTEGER = 1 } cdf_type;
typedef enum {
    CDF_Y = 0,       /* an element of d->y (a = index) */
    CDF_FN_OBJECT,   /* sum of the normal forces of the object's contact slots [N] */
    CDF_N_STICK,     /* object's slots sticking */
    CDF_N_SLIP,      /* object's slots slipping */
    CDF_VERDICT,     /* cd_verdict of the capture monitor */
    CDF_VERDICT_T,   /* [s] time of the verdict, -1 while unresolved */
    CDF_IN_QFRC,     /* d->qfrc_applied[a] [N m | N] */
    CDF_IN_XFRC,     /* d->xfrc_applied[a] (a = 6 body + k: torque 0-2, force 3-5), world axes */
    CDF_IN_CTRL,     /* d->ctrl[a] */
    CDF_PARAM        /* a scenario key (a = index of the --param) */
} cdf_what;

typedef struct {
    char name[128];
    char desc[192];
    int causality;   /* cdf_causality */
    int type;        /* cdf_type */
    int what;        /* cdf_what */
    int a;
} cdf_var;

/* The output and input variables of scenario sc (d: a data of its model,
 * for the state layout; its model, [gripper] /
 * [capture] object, [control]): *vars (malloc'ed, caller frees) and *n.
 * Inputs the [control] controller writes itself (its arm's joint torques,
 * the gripper actuators it closes, the base torque with its attitude law)
 * are left out: its callback would overwrite them. CD_ENOMEM on failure. */
cd_status cdf_vars_build(const cd_scenario *sc, const cd_data *d, cdf_var **vars, int *n, cd_error *err);

#endif
