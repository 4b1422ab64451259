/* Helpers of the capdyn command shared by every file of src/cli: messages,
 * exit codes, number parsing and printing, the clock, and the isolated
 * reader. This header includes no other header of src/cli, and every file
 * of src/cli includes it (through cli.h or directly): the include graph of
 * src/cli has no circle (docs/cli.md, "Source layout"). */
#ifndef CD_CLI_UTIL_H
#define CD_CLI_UTIL_H

#include <stddef.h>
#include <stdio.h>

/* exit codes (docs/cli.md) */
#define CLI_OK 0
#define CLI_FAIL 1        /* runtime error: bad scenario, I/O, integrator failure */
#define CLI_USAGE 2       /* bad command line */
#define CLI_INTERRUPT 130 /* stopped by SIGINT or SIGTERM; results kept */

/* "capdyn: error: ..." on stderr (one line; control characters escaped). */
void cli_error(const char *fmt, ...);
/* A usage error of command cmd (NULL: the top level): the message, a hint to
 * --help, and CLI_USAGE to return. */
int cli_usage(const char *cmd, const char *fmt, ...);
/* Parses a finite number / a non-negative integer; 0 on success. */
int cli_number(const char *s, double *v);
int cli_count(const char *s, long *v);
/* Seconds on a monotonic clock. */
double cli_wall(void);

/* The shortest text of v that strtod reads back as the same double (%.15g,
 * %.16g or %.17g, the first that round-trips; "nan", "inf", "-inf" as
 * printf writes them): every number printed for people that is not given
 * a stated precision goes through this (docs/cli.md, "Numbers"). buf
 * needs CLI_NUM bytes; returns buf. */
#define CLI_NUM 32
char *cli_fmt_num(char *buf, double v);
/* fputs of cli_fmt_num(v). */
void cli_put_num(FILE *out, double v);

/* A file that a reader may open: 0 if path is a regular file (or does not
 * exist: the reader then says so), -1 with msg if it is something else (a
 * FIFO would block the reader forever, a device is never a capdyn file). */
int cli_regular_input(const char *path, const char *what, char *msg, size_t len);

/* Seconds a reading child may take for a file of the given size: 60 s plus
 * 1 s per MB (measured: `export checkpoints --every 1` of a 70 MB Fig. 5
 * file, output_dt 2e-5 s, takes 5.7 s), or
 * CAPDYN_READ_TIMEOUT (seconds) if set. */
double cli_read_limit(const char *path);

/* Runs fn(arg) in a child process (docs/reliability.md, "Untrusted
 * results files"): HDF5's error printing is off in the child, its stdout
 * goes to a temporary file that is copied to ours only if fn returned, and
 * it is killed after cli_read_limit(path) seconds. A crash or the time
 * limit becomes one error line naming path (nothing printed) and CLI_FAIL;
 * otherwise fn's exit status. Memory fn must hand back goes through a
 * MAP_SHARED mapping made by the caller. CAPDYN_NO_ISOLATION=1 calls fn
 * here (for debuggers). */
int cli_isolated(const char *path, int (*fn)(void *), void *arg);

#endif
