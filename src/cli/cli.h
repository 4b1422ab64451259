/* The capdyn command: declarations shared by the files of src/cli (docs/cli.md). */
#ifndef CD_CLI_H
#define CD_CLI_H

#include <stdio.h>
#include "capdyn/io.h"
#include "../io/h5_read.h"

/* exit codes (docs/cli.md) */
#define CLI_OK 0
#define CLI_FAIL 1        /* runtime error: bad scenario, I/O, integrator failure */
#define CLI_USAGE 2       /* bad command line */
#define CLI_INTERRUPT 130 /* stopped by SIGINT or SIGTERM; results kept */

/* "capdyn: error: ..." on stderr (one line). */
void cli_error(const char *fmt, ...);
/* A usage error of command cmd (NULL: the top level): the message, a hint to
 * --help, and CLI_USAGE to return. */
int cli_usage(const char *cmd, const char *fmt, ...);
/* Parses a finite number / a non-negative integer; 0 on success. */
int cli_number(const char *s, double *v);
int cli_count(const char *s, long *v);
/* Seconds on a monotonic clock. */
double cli_wall(void);

int cmd_run(int argc, char **argv);
int cmd_check(int argc, char **argv);
int cmd_info(int argc, char **argv);
int cmd_export(int argc, char **argv);

/* Facts only the running process knows, added to the file's report. */
typedef struct {
    double wall;                /* wall time of the run [s] */
    const double *fn_max;       /* (nslot) max normal force over every step [N] */
    const double *ft_max;       /* (nslot) max |tangential force| over every step [N] */
} cli_run_extra;

/* Prints the summary of a results file (the body of `capdyn info`, and the
 * end-of-run summary of `capdyn run` with extra != NULL). */
void cli_report(FILE *out, const cd_h5r *r, const char *path, const cli_run_extra *extra);

#endif
