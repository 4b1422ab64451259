/* capdyn info: opens a results file, checks that every dataset of it reads,
 * and prints its report (cli_report, src/cli/report.c: the same report that
 * capdyn run prints at its end). */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"

#include <string.h>

static const char *info_help =
    "usage: capdyn info RESULTS.h5\n"
    "\n"
    "Summary of a results file: title, scenario, run status, committed samples\n"
    "and time span, events by kind, systems, contact slots that closed with\n"
    "their largest forces, integrator statistics, energy and momentum drift.\n"
    "Works on a file whose run was killed (it reads the committed samples only)\n"
    "and on a file that a run is still writing.\n";

int cmd_info(int argc, char **argv)
{
    const char *path = NULL;
    cd_h5r *r;
    cd_error err;
    int i;
    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) {
            fputs(info_help, stdout);
            return CLI_OK;
        }
        if (argv[i][0] == '-' && argv[i][1]) return cli_usage("info", "unknown option '%s'", argv[i]);
        if (path) return cli_usage("info", "unexpected argument '%s' (one results file)", argv[i]);
        path = argv[i];
    }
    if (!path) return cli_usage("info", "missing the results file");
    r = cd_h5r_open(path, &err);
    if (!r) {
        cli_error("%s", err.msg);
        return CLI_FAIL;
    }
    /* a file is called readable only if every dataset of it reads (issue 28) */
    if (cd_h5r_verify(r, path, &err) != 0) {
        cli_error("%s", err.msg);
        cd_h5r_close(r);
        return CLI_FAIL;
    }
    cli_report(stdout, r, path, NULL);
    cd_h5r_close(r);
    return CLI_OK;
}
