/* capdyn: the command-line front end (docs/cli.md).
 *
 *   capdyn run SCENARIO.toml [-o results.h5] [--set k=v ...] [--quiet]
 *   capdyn check SCENARIO.toml [--set k=v ...]
 *   capdyn info results.h5
 *   capdyn export results.h5 WHAT [options]
 *
 * Only this program turns GSL's abort-on-error handler off (the library
 * reports errors as values and never touches the handler), and only this
 * program turns HDF5's atexit clean-up off (see main). Messages: one line on stderr starting with
 * "capdyn: error: "; exit 2 for a bad command line, 1 for a runtime error,
 * 130 when stopped by a signal. */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"

#include <gsl/gsl_errno.h>
#include <hdf5.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <signal.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static const char *top_help =
    "usage: capdyn COMMAND [ARGS...]\n"
    "       capdyn --help | --version\n"
    "\n"
    "Contact dynamics of free-flying space robots (Yoshida, Nakanishi & Irobe).\n"
    "\n"
    "commands:\n"
    "  run SCENARIO.toml [-o FILE.h5] [--set KEY=VALUE ...] [--quiet]\n"
    "                     simulate a scenario, write an HDF5 results file\n"
    "  check SCENARIO.toml [--set KEY=VALUE ...]\n"
    "                     validate a scenario without running it\n"
    "  info RESULTS.h5    summary of a results file\n"
    "  sweep SCENARIO.toml --vary KEY=A:B:N|V1,V2,... [-j N] [-o SUMMARY.h5]\n"
    "                     many variants on every core, one HDF5 summary\n"
    "  export RESULTS.h5 WHAT [options]\n"
    "                     columns of text for gnuplot (time, system NAME, contacts,\n"
    "                     slot N, slots, events, diagnostics, outline, checkpoints)\n"
    "\n"
    "'capdyn COMMAND --help' describes a command; docs/cli.md is the manual.\n"
    "exit status: 0 success, 1 runtime error, 2 bad command line, 130 interrupted.\n";

/* Writes msg with its control characters escaped (\n, \t, \r, \xNN; C1
 * controls in UTF-8 as \u00NN): a message that quotes a file name or an
 * argument stays one line and cannot drive the terminal. */
static void put_escaped(const char *msg)
{
    const unsigned char *p = (const unsigned char *)msg;
    for (; *p; p++) {
        if (*p == '\n') fputs("\\n", stderr);
        else if (*p == '\t') fputs("\\t", stderr);
        else if (*p == '\r') fputs("\\r", stderr);
        else if (*p < 0x20 || *p == 0x7f) fprintf(stderr, "\\x%02x", *p);
        else if (*p == 0xc2 && p[1] >= 0x80 && p[1] <= 0x9f) fprintf(stderr, "\\u%04x", *++p);
        else fputc(*p, stderr);
    }
}

static void vmessage(const char *fmt, va_list ap)
{
    char buf[4096];
    vsnprintf(buf, sizeof buf, fmt, ap);
    fputs("capdyn: error: ", stderr);
    put_escaped(buf);
}

void cli_error(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vmessage(fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
}

int cli_usage(const char *cmd, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vmessage(fmt, ap);
    va_end(ap);
    if (cmd) fprintf(stderr, " (see 'capdyn %s --help')\n", cmd);
    else fputs(" (see 'capdyn --help')\n", stderr);
    return CLI_USAGE;
}

int cli_number(const char *s, double *v)
{
    char *end;
    double x;
    if (!s || !*s) return -1;
    errno = 0;
    x = strtod(s, &end);
    if (*end || errno || !isfinite(x)) return -1;
    *v = x;
    return 0;
}

int cli_count(const char *s, long *v)
{
    char *end;
    long x;
    if (!s || !*s) return -1;
    errno = 0;
    x = strtol(s, &end, 10);
    if (*end || errno || x < 0) return -1;
    *v = x;
    return 0;
}

double cli_wall(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Reading a results file (info, export) in a child process
 * (docs/reliability.md, "Untrusted results files"). The reader checks
 * every size and index it takes from a file, but libhdf5 1.10 itself can
 * crash on a damaged file (measured: a flipped bit in an attribute's size
 * field). The child writes its stdout into a temporary file; the parent
 * copies it out only if the child exited (with its status), so a crash
 * becomes one error line and exit status 1, with nothing half printed.
 * CAPDYN_NO_ISOLATION=1 reads in this process (for debuggers). */
static int isolated(int (*fn)(int, char **), int argc, char **argv)
{
    const char *path = NULL;
    FILE *tmp;
    pid_t pid;
    int st, i;
    char buf[65536];
    size_t n;
    for (i = 1; i < argc && !path; i++)
        if (argv[i][0] != '-') path = argv[i];
    if (!path || getenv("CAPDYN_NO_ISOLATION")) return fn(argc, argv);
    fflush(NULL);
    tmp = tmpfile();
    if (!tmp) return fn(argc, argv);
    pid = fork();
    if (pid < 0) {
        fclose(tmp);
        return fn(argc, argv);
    }
    if (pid == 0) {
        int rc = CLI_FAIL;
        if (dup2(fileno(tmp), STDOUT_FILENO) >= 0) rc = fn(argc, argv);
        if (fflush(stdout) != 0 && rc == CLI_OK) {
            cli_error("writing the output failed");
            rc = CLI_FAIL;
        }
        exit(rc);
    }
    while (waitpid(pid, &st, 0) < 0)
        if (errno != EINTR) {
            fclose(tmp);
            cli_error("waiting for the reading process failed: %s", strerror(errno));
            return CLI_FAIL;
        }
    if (!WIFEXITED(st)) {
        fclose(tmp);
        cli_error("'%s': reading the file crashed inside the HDF5 library (%s): the file is damaged; nothing was "
                  "printed",
                  path, WIFSIGNALED(st) ? strsignal(WTERMSIG(st)) : "stopped");
        return CLI_FAIL;
    }
    rewind(tmp);
    while ((n = fread(buf, 1, sizeof buf, tmp)) > 0)
        if (fwrite(buf, 1, n, stdout) != n) break;
    fclose(tmp);
    if (fflush(stdout) != 0) {
        cli_error("writing the output failed");
        return CLI_FAIL;
    }
    return WEXITSTATUS(st);
}

int main(int argc, char **argv)
{
    const char *cmd;
    /* Before any HDF5 call: no HDF5 clean-up at exit(). HDF5 1.10 keeps a
     * file whose flush or close failed (disk full) in its id table, half
     * destroyed, and its atexit handler then crashes on it (segfault in
     * H5F__close_cb). Every file is closed explicitly; after a failed write
     * the kernel reclaims what HDF5 could not release. */
    H5dont_atexit();
    /* GSL's default handler aborts the process; errors come back as values.
     * Only this program does this: the library never changes the handler. */
    gsl_set_error_handler_off();
    if (argc < 2) {
        fputs(top_help, stderr);
        return CLI_USAGE;
    }
    cmd = argv[1];
    if (!strcmp(cmd, "--help") || !strcmp(cmd, "-h")) {
        fputs(top_help, stdout);
        return CLI_OK;
    }
    if (!strcmp(cmd, "help")) {
        /* "capdyn help run" = "capdyn run --help" */
        static char help_opt[] = "--help";
        char *hv[2];
        if (argc < 3) {
            fputs(top_help, stdout);
            return CLI_OK;
        }
        hv[0] = argv[2];
        hv[1] = help_opt;
        if (!strcmp(argv[2], "run")) return cmd_run(2, hv);
        if (!strcmp(argv[2], "check")) return cmd_check(2, hv);
        if (!strcmp(argv[2], "info")) return cmd_info(2, hv);
        if (!strcmp(argv[2], "export")) return cmd_export(2, hv);
        if (!strcmp(argv[2], "sweep")) return cmd_sweep(2, hv);
        return cli_usage(NULL, "unknown command '%s' (commands: run, check, info, export, sweep)", argv[2]);
    }
    if (!strcmp(cmd, "--version") || !strcmp(cmd, "-V")) {
        printf("capdyn %s\n", cd_version());
        return CLI_OK;
    }
    if (!strcmp(cmd, "run")) return cmd_run(argc - 1, argv + 1);
    if (!strcmp(cmd, "check")) return cmd_check(argc - 1, argv + 1);
    if (!strcmp(cmd, "info")) return isolated(cmd_info, argc - 1, argv + 1);
    if (!strcmp(cmd, "export")) return isolated(cmd_export, argc - 1, argv + 1);
    if (!strcmp(cmd, "sweep")) return cmd_sweep(argc - 1, argv + 1);
    if (cmd[0] == '-') return cli_usage(NULL, "unknown option '%s'", cmd);
    return cli_usage(NULL, "unknown command '%s' (commands: run, check, info, export, sweep)", cmd);
}
