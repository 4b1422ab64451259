/* The capdyn command: the commands and the run loop they share (docs/cli.md,
 * "Source layout"); the helpers every file uses are in cli_util.h. */
#ifndef CD_CLI_H
#define CD_CLI_H

#include <stdio.h>
#include "cli_util.h"
#include "capdyn/io.h"
#include "capdyn/control.h"
#include "../io/h5_read.h"

/* check points deeper inside a shape than their radius at the data's state
 * (an initial pose that overlaps); the deepest described in msg */
#define CLI_OVERLAP_MIN 5e-3 /* [m] */
int cli_initial_overlap(const cd_model *m, const cd_data *d, char *msg, size_t n);
int cmd_run(int argc, char **argv);
int cmd_check(int argc, char **argv);
int cmd_info(int argc, char **argv);
int cmd_export(int argc, char **argv);
int cmd_fmu(int argc, char **argv); /* src/cli/fmu.c, docs/fmu.md */

/* The state of one run's loop (src/cli/run.c): progress bar, the largest
 * contact forces of every step, the work budget. */
typedef struct {
    int progress;          /* draw the bar */
    double t_end, wall0, last_draw;
    double *fn_max, *ft_max;
    /* the onset transient (docs/cli.md, "Peak forces"): a contact's steps
     * from its closing until the law's elastic term K x^p first carries at
     * least as much as the rest (the damper); fn_onset the largest normal
     * force inside those windows, fn_body outside them (each nslot, may be
     * NULL: not kept), onset (nslot) 1 while a slot is in its window */
    double *fn_onset, *fn_body;
    double *t_onset, *t_body; /* (nslot, may be NULL) the times [s] those were reached (NaN: never) */
    unsigned char *onset;
    int drawn;
    /* work budget (simulation.max_wall_time, max_rhs_evals; 0 = no limit):
     * the step callback stops the run and writes why in budget_msg */
    double max_wall, max_rhs;
    double t_start;        /* simulated time at the loop's start (the pace check) */
    char budget_msg[320];
    int until_verdict;     /* end the run at the monitor's verdict (capdyn sweep --until-verdict) */
    const cd_ctrl *ctl;    /* the scenario's built-in controller ([control]), or NULL */
    cd_ctrl_merit *merit;  /* its figures of merit, updated at every sample (with ctl) */
} run_ctx;

/* The run loop of capdyn run, shared with capdyn sweep: the state at t = 0
 * counts for c's maxima; the integrator is advanced to every sample time
 * (k output_dt, the last exactly at the duration) with cd_sim_advance, the
 * monitor (may be NULL) looks at every sample, w (may be NULL: no file)
 * receives every sample and is flushed every flush_every seconds; the step
 * callback enforces the work budget. Ends early (CD_OK) at the monitor's
 * verdict if c->until_verdict. Stops on a failure, a spent budget or
 * SIGINT/SIGTERM caught by capdyn run. Returns the run status; *err says why
 * it stopped (a spent budget: c->budget_msg); wmsg (wlen bytes) receives the
 * first write error of w ("" if none). The caller fills c (fn_max, ft_max
 * of nslot, t_end, wall0, budget) and closes w. */
cd_status cli_run_loop(const cd_scenario *sc, cd_data *d, cd_h5_writer *w, cd_monitor *mon, run_ctx *c,
                       cd_error *err, char *wmsg, size_t wlen);
/* The verdict and figures of merit of a monitor at the end of a run
 * (verdict name static; epsilon NaN if the grasp analysis fails). */
void cli_capture_of(const cd_monitor *mon, const cd_ctrl *ctl, const cd_ctrl_merit *merit, const cd_model *m,
                    const cd_data *d, cd_h5_capture *cap);

int cmd_sweep(int argc, char **argv);
/* n (at least 1) doubles set to NaN, malloc'ed (caller frees); NULL if out of memory */
double *cli_nan_array(int n);

/* Facts only the running process knows, added to the file's report. */
typedef struct {
    double wall;                /* wall time of the run [s] */
    const double *fn_max;       /* (nslot) max normal force over every step [N] */
    const double *ft_max;       /* (nslot) max |tangential force| over every step [N] */
    const double *fn_onset;     /* (nslot) max normal force inside onset windows [N] (run_ctx), or NULL */
    const double *fn_body;      /* (nslot) max normal force outside them [N], or NULL */
    const double *t_onset, *t_body; /* (nslot) when those were reached [s] (NaN: never), or NULL */
    int attitude;               /* 1: the scenario's [control] applies base attitude torque (an external torque) */
} cli_run_extra;

/* Prints the summary of a results file, src/cli/report.c (the body of `capdyn info`, and the
 * end-of-run summary of `capdyn run` with extra != NULL). */
void cli_report(FILE *out, const cd_h5r *r, const char *path, const cli_run_extra *extra);

#endif
