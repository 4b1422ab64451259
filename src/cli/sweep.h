/* capdyn sweep: the plan of a sweep, one variant's outcome, the summary file
 * (docs/sweep.md). Internal to src/cli. */
#ifndef CD_CLI_SWEEP_H
#define CD_CLI_SWEEP_H

#include "cli.h"

#define SW_MAX_KEYS 4
#define SW_MAX_VARIANTS 10000000L /* the largest sweep (summary rows) */
#define SW_REASON 512             /* bytes of a failure reason */

/* Status codes of a variant beyond cd_status (docs/sweep.md). */
#define SW_NOT_RUN (-1)           /* not run yet (interrupted sweep) */
#define SW_ELOAD 1000             /* its scenario did not load (an override's value) */
#define SW_ECRASH 1001            /* its worker process died (a signal) */

/* One swept key: a range a:b:n (grid: n values from a to b; Latin
 * hypercube: the interval [a, b]) or a list of TOML values. */
typedef struct {
    char *key;        /* dotted --set path */
    char *spec;       /* the --vary text after '=' */
    int is_range;
    double a, b;
    long n;           /* range: number of grid values */
    char **vals;      /* the list, or the range's grid values (nval) */
    long nval;
} sw_key;

/* The variants of a sweep: val[i * nkey + k] is key k's TOML value in
 * variant i (owned). */
typedef struct {
    int nkey;
    sw_key key[SW_MAX_KEYS];
    int lhs;                  /* 0 grid, 1 Latin hypercube */
    long lhs_n;
    unsigned long long seed;
    long nvar;
    char **val;
} sw_plan;

/* One variant's outcome; fixed size (it crosses a pipe or an MPI message). */
typedef struct {
    long index;
    int status;               /* cd_status of the run (0 ok), SW_ELOAD, SW_ECRASH, SW_NOT_RUN */
    int verdict;              /* cd_verdict, -1 none (no gripper, or not run) */
    double t_capture, t_escape; /* [s] NaN if never */
    double peak_fn;           /* [N] the monitor's, on the object at the samples */
    double peak_tau;          /* [N m] */
    double epsilon;           /* Ferrari-Canny epsilon of the final contacts */
    double offset[3];         /* [m] object - palm centre at the end, palm frame */
    double fn_step_max;       /* [N] largest normal force of any slot over every step */
    double t_final;           /* [s] where the run ended */
    int n_stick, n_slip;
    long nrhs, nsteps, nevents;
    double wall;              /* [s] wall time of the variant (not deterministic) */
    char reason[SW_REASON];   /* failure reason, "" if ok */
} sw_result;

/* Definition of the sweep as stored in the summary (what --resume checks). */
typedef struct {
    const char *scenario;     /* the path as given */
    const char *scenario_text;/* the base scenario's text (cd_scenario.text) */
    const char *overrides;    /* the base --set list, one per line */
    double length;            /* [m] normalising length (0: none) */
    int until_verdict;        /* variants end at their verdict (--until-verdict) */
} sw_meta;

void sw_result_blank(sw_result *r, long index);

/* The summary's place on disk, held for the whole sweep (docs/reliability.md,
 * "Sweeps"): the same protocol as a results file of capdyn run (src/io/h5.c,
 * claim_output): the target is never an input file (same device and inode)
 * nor anything but a regular file; a file another capdyn process writes is
 * flock'ed by it and refused; each write goes to a temporary file in the
 * target's directory, flock'ed, renamed onto the target under a lock on the
 * directory, and keeps its lock (so capdyn run -o, or a second sweep with
 * the same -o, refuses the summary while this sweep runs). */
typedef struct {
    char *path;               /* as given */
    char *target;             /* the file replaced (a symbolic link followed) */
    int lock_fd;              /* our flock'ed summary, -1 before the first write */
} sw_out;

/* Checks path as the summary of a sweep whose inputs are the ninput files
 * input (the scenario); 0, or -1 with msg (out is then empty). */
int sw_out_open(sw_out *out, const char *path, const char *const *input, int ninput, char *msg, size_t len);
void sw_out_close(sw_out *out);

/* Writes the summary to out (a temporary file in its directory, renamed
 * onto it). jobs and total_wall go to /timing. 0 or -1 with msg. */
int sw_summary_write(sw_out *out, const sw_meta *meta, const sw_plan *p, const sw_result *res, int jobs,
                     double total_wall, char *msg, size_t len);
/* A summary file as read back (everything but the units): what --table
 * prints and --resume continues. Strings and arrays owned (sw_summary_free). */
typedef struct {
    long long version;        /* format_version */
    char *capdyn_version, *scenario, *scenario_text, *overrides, *design;
    long long lhs_samples, seed, nvar, nrun, nfail, complete, until_verdict;
    double length;            /* [m] 0: none */
    int nkey;
    char **names, **specs;    /* nkey */
    char **vals;              /* nvar x nkey TOML values */
    double *num;              /* nvar x nkey, NaN where not a number */
    sw_result *res;           /* nvar (wall from /timing) */
    long nslice;              /* region slices (0: no /region) */
    char **slice;
    double *area;
    long long *captured;
    long long jobs;
    double total_wall;
} sw_summary;

/* Reads a summary (every size checked against the file before anything is
 * allocated; the checksums of format_version 2 verified). Run it in a child
 * process (cli_isolated): HDF5 may crash on a damaged file. 0, or -1 with
 * msg naming path and what is wrong (s is then freed). */
int sw_summary_load(const char *path, sw_summary *s, char *msg, size_t len);
void sw_summary_free(sw_summary *s);
/* The results of a summary made by the same sweep (meta, p) into res (nvar
 * entries), read in a child process with a time limit; 0, or -1 after one
 * error line (the file is damaged, or was made by another sweep: the
 * message names what differs). */
int sw_summary_resume(const char *path, const sw_meta *meta, const sw_plan *p, sw_result *res);
/* capdyn sweep --table: prints a summary as columns for gnuplot on stdout,
 * read in a child process with a time limit; an exit status. */
int sw_summary_table(const char *path);

/* Normalised region areas of a grid over at least two numeric ranges (the
 * first two are the plane): for each combination of the other keys' values,
 * captured cells x cell area / length^2 (length 0: 1 m). Returns the number
 * of slices (0 if the sweep has no plane); area, ncap, label (nslice each,
 * label SW_LABEL bytes) may be NULL to count. */
#define SW_LABEL 256
long sw_region(const sw_plan *p, const sw_result *res, double length, double *area, long *ncap, char *label);

#endif
