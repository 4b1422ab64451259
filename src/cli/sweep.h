/* capdyn sweep: declarations shared by its files (docs/sweep.md; the
 * layout of src/cli is in docs/cli.md, "Source layout"):
 *   sweep.c         the command: options, the driver
 *   sweep_plan.c    the plan: --vary specs, grid and Latin hypercube, region
 *   sweep_run.c     running the variants: worker processes, MPI ranks
 *   sweep_h5.c      the summary file: writing (with its lock), reading
 *   sweep_report.c  what is printed: progress bar, end report, --table
 *   sweep_mc.c      --mc: the dispersions, each variant's draws, per-cell probability
 *   sweep_merge.c   --merge: shard summaries joined into one
 * Internal to src/cli. */
#ifndef CD_CLI_SWEEP_H
#define CD_CLI_SWEEP_H

#include "cli.h"

#include <signal.h>

#define SW_MAX_VARY 4   /* --vary keys */
#define SW_MAX_DISP 8   /* --disperse keys */
#define SW_MAX_KEYS (SW_MAX_VARY + SW_MAX_DISP)
#define SW_MAX_JOBS 1024
/* Seconds of wall time between two summary checkpoints: a sweep killed
 * without a chance to write (SIGKILL, power) loses at most this much work. */
#define SW_CHECKPOINT 10.0
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
    int dist;         /* a dispersed key (--disperse): SW_DIST_*, 0 a --vary key */
    double prm[8];    /* the distribution's parameters (sweep_mc.c) */
    int nprm;
} sw_key;

/* Distributions of a dispersed key (docs/sweep.md, "Monte Carlo"). */
enum { SW_DIST_NONE, SW_DIST_NORMAL, SW_DIST_UNIFORM, SW_DIST_CONE, SW_DIST_ROTATION, SW_DIST_INERTIA };

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
    long mc;                  /* draws per grid cell (--mc), 0 none */
    long ncell;               /* grid cells (nvar = ncell * mc under --mc) */
    int nvary;                /* the first nvary keys are --vary keys, the rest dispersed */
} sw_plan;

/* One variant's outcome; fixed size (it crosses a pipe or an MPI message). */
typedef struct {
    long index;
    int status;               /* cd_status of the run (0 ok), SW_ELOAD, SW_ECRASH, SW_NOT_RUN */
    int verdict;              /* cd_verdict, -1 none (no gripper, or not run) */
    double t_capture, t_escape; /* [s] NaN if never */
    double t_cage;            /* [s] the monitor's t_cage: the capture conditions first held without force
                               * closure (NaN if never caged; summaries before format_version 3 lack it) */
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
    long long mc, nvary;      /* /mc: draws per cell, --vary keys (no /mc: 0, nkey) */
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

/* The command line of a sweep (sweep.c). */
typedef struct {
    const char *scenario, *output, *keep_dir, *table;
    const char **sets;
    int nsets;
    const char *vary[SW_MAX_VARY + 1];
    int nvary;
    const char *disp[SW_MAX_DISP + 1];
    int ndisp;
    long mc;
    long shard_k, shard_n;    /* --shard K/N (1-based K), 0: all */
    const char **merge;       /* --merge files */
    int nmerge;
    long lhs, jobs;
    unsigned long long seed;
    int quiet, resume, have_jobs, until_verdict, plan;
    double length;
} sw_opts;

/* What a variant needs (constant while the sweep runs). */
typedef struct {
    const sw_opts *o;
    const sw_plan *p;
    sw_out *out;    /* the summary (rank 0 / the parent only) */
} sw_ctx;

/* ---- sweep_plan.c ---- */
/* a NUL-terminated copy of the first n bytes of s (malloc; NULL when out of memory) */
char *sw_dup_str(const char *s, size_t n);
/* The plan of --vary texts vary (nvary), a grid or (lhs > 0) a Latin
 * hypercube of lhs variants with seed: p filled (free with sw_plan_free).
 * CLI_OK, or the exit status after one error line (usage: CLI_USAGE). */
int sw_plan_make(sw_plan *p, const char *const *vary, int nvary, long lhs, unsigned long long seed);
/* The same with --mc draws per cell of the dispersed keys disp (ndisp). */
int sw_plan_make_mc(sw_plan *p, const char *const *vary, int nvary, long lhs, unsigned long long seed,
                    const char *const *disp, int ndisp, long mc);

/* ---- sweep_mc.c ---- */
/* KEY=DIST (normal(m,sd[,lo,hi]), uniform(lo,hi), cone(x,y,z,deg),
 * rotation(w,x,y,z,deg), inertia(a,b,c,rel_sd)) into k. 0, or -1 with msg. */
int sw_disp_parse(sw_key *k, const char *arg, char *msg, size_t len);
/* The values of the dispersed keys of variant idx: one GSL mt19937 stream
 * seeded from (seed, idx) alone, the keys drawn in order; out[k] (TOML
 * text, malloc'd) for each dispersed key. 0, or -1 (out of memory). */
int sw_disp_draw(const sw_key *key, int nkey, unsigned long long seed, long idx, char **out);
/* One value of key k from the generator r (void * = gsl_rng *) as TOML text
 * into buf, its numbers into x (up to 4). */
void sw_disp_one(const sw_key *k, void *r, char *buf, size_t len, double *x);
/* Wilson score interval of k successes in n at 95 % (z = 1.959964). */
void sw_wilson(long k, long n, double *lo, double *hi);
/* Per-cell statistics of a Monte Carlo sweep (n cells). */
typedef struct {
    long n, ncap, nfail, nverdict[8];
    double p, lo, hi;
    double t_mean, t_p10, t_p50, t_p90;      /* capture time [s] of the captured */
    double f_mean, f_p10, f_p50, f_p90;      /* peak normal force [N] */
    double e_mean, e_p10, e_p50, e_p90;      /* epsilon */
} sw_cell;
/* Fills cell[ncell]; 0 or -1 (out of memory). */
int sw_mc_cells(const sw_plan *p, const sw_result *res, sw_cell *cell);
void sw_plan_free(sw_plan *p);
/* The --set list of variant idx: the nsets base overrides, then KEY=VALUE
 * of each swept key; NULL-terminated, malloc'd (sw_overrides_free). NULL
 * if out of memory. */
char **sw_overrides(const char *const *sets, int nsets, const sw_plan *p, long idx);
void sw_overrides_free(char **ov);

/* capdyn sweep --merge (sweep_h5.c): an exit status. */
int sw_merge(const sw_opts *o);
/* Is variant i this process's to run (its shard; status not yet run)? */
int sw_todo(const sw_ctx *cx, const sw_result *res, long i);

/* ---- sweep_run.c ---- */
/* Runs variant idx in this process into r (its failure recorded in r). */
void sw_run_variant(const sw_ctx *cx, long idx, sw_result *r);

/* The progress bar (sweep_report.c). */
typedef struct {
    int on, drawn;
    double t0, last;
    long total, done0; /* done0: finished before this invocation (resume) */
} sw_progress;

/* Runs the variants not yet run (status SW_NOT_RUN) on nj worker processes
 * (size 1) or, under MPI, on the size - 1 other ranks; SIGINT and SIGTERM
 * stop it (the variants in flight are then not run), SIGPIPE is ignored
 * meanwhile; checkpoints the summary every SW_CHECKPOINT s. Returns 0, the
 * signal that stopped it, or -1 on an error (reported). */
int sw_run(const sw_ctx *cx, const sw_meta *meta, sw_result *res, int nj, int size, sw_progress *pg, long *ndone,
           long *nfail, double wall0);
#ifdef CAPDYN_MPI
/* Started by an MPI launcher? */
int sw_under_mpi(void);
/* A worker rank: runs what rank 0 hands out until told to stop. */
void sw_mpi_worker(const sw_ctx *cx);
#endif

/* ---- sweep_report.c ---- */
void sw_draw(sw_progress *pg, long done, long failed, int force);
void sw_clear(sw_progress *pg);
/* The end-of-sweep lines on stdout: counts, regions, failed variants. */
void sw_report_end(const sw_opts *o, const sw_plan *p, const sw_result *res, long ndone, long nfail, long nrun0,
                   double wall, int nj);

#endif
