/* capdyn: the command-line front end (docs/cli.md).
 *
 *   capdyn run SCENARIO.toml [-o results.h5] [--set k=v ...] [--quiet]
 *   capdyn check SCENARIO.toml [--set k=v ...]
 *   capdyn info results.h5
 *   capdyn export results.h5 WHAT [options]
 *   capdyn fmu SCENARIO.toml -o capture.fmu [--input|--output NAME ...] [--param KEY=VALUE ...]
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
#include <stdio.h>
#include <string.h>

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
    "  fmu SCENARIO.toml -o FILE.fmu [--input NAME ...] [--output NAME ...] [--param KEY=VALUE ...]\n"
    "                     the scenario as an FMI 2.0 co-simulation FMU (docs/fmu.md)\n"
    "\n"
    "'capdyn COMMAND --help' describes a command; docs/cli.md is the manual.\n"
    "exit status: 0 success, 1 runtime error, 2 bad command line, 130 interrupted.\n";

/* info and export of a results file: in a child process (cli_isolated) */
typedef struct {
    int (*fn)(int, char **);
    int argc;
    char **argv;
} cmd_call;
static int call_cmd(void *arg)
{
    cmd_call *c = arg;
    return c->fn(c->argc, c->argv);
}

/* The results file of info / export: the first argument that is neither
 * an option nor the value of one of the options in valued (NULL-ended). */
static const char *file_arg(int argc, char **argv, const char *const *valued)
{
    int i, k;
    for (i = 1; i < argc; i++) {
        if (argv[i][0] != '-' || !argv[i][1]) return argv[i];
        for (k = 0; valued[k]; k++)
            if (!strcmp(argv[i], valued[k])) i++;
    }
    return NULL;
}

static int isolated(int (*fn)(int, char **), int argc, char **argv)
{
    static const char *const valued[] = {"--every", "--frames", "--at", "--view", "--precision", NULL};
    const char *path = file_arg(argc, argv, valued);
    char msg[1024];
    cmd_call c;
    int i;
    for (i = 1; i < argc; i++)
        if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) return fn(argc, argv);
    if (!path) return fn(argc, argv);
    /* a FIFO would block the reader forever: refused before it is opened */
    if (cli_regular_input(path, "results file", msg, sizeof msg) != 0) {
        cli_error("%s", msg);
        return CLI_FAIL;
    }
    c.fn = fn;
    c.argc = argc;
    c.argv = argv;
    return cli_isolated(path, call_cmd, &c);
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
        if (!strcmp(argv[2], "fmu")) return cmd_fmu(2, hv);
        return cli_usage(NULL, "unknown command '%s' (commands: run, check, info, export, sweep, fmu)", argv[2]);
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
    if (!strcmp(cmd, "fmu")) return cmd_fmu(argc - 1, argv + 1);
    if (cmd[0] == '-') return cli_usage(NULL, "unknown option '%s'", cmd);
    return cli_usage(NULL, "unknown command '%s' (commands: run, check, info, export, sweep, fmu)", cmd);
}
