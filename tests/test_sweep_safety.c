/* capdyn sweep on bad paths, damaged summaries and limits (issue 24,
 * docs/reliability.md "Sweeps"): the summary gets the output checks of a
 * results file (never the scenario, never a non-regular file, never a file
 * another capdyn process writes), a file size limit ends the sweep with one
 * error line and no temporary file, a summary that is not a regular file
 * or is damaged is refused with one error line, and the size of a grid is
 * checked before any value is built.
 *
 * Every sweep here is 2 to 40 variants of 0.02 to 0.3 s of the centred TAKO
 * scene, so that the suite takes seconds. */
#define _POSIX_C_SOURCE 200809L
#include <criterion/criterion.h>
#include <hdf5.h>
#include "proc_util.h"
#include <dirent.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define TINY "--set", "simulation.duration=0.02", "--set", "simulation.output_dt=0.01"
#define TWO "--vary", "target.object.mass=0.3,0.4"

/* exactly one "capdyn: error: " line containing want */
static void one_error_line(const char *err, const char *want)
{
    cr_expect(err && !strncmp(err, "capdyn: error: ", 15) && strchr(err, '\n') == err + strlen(err) - 1,
              "one error line: %s", err ? err : "(none)");
    cr_expect(err && strstr(err, want) != NULL, "the message says '%s': %s", want, err ? err : "(none)");
}

/* the number of names in dir that start with ".": temporary files */
static int hidden_files(const char *dir)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    int n = 0;
    cr_assert_not_null(d);
    while ((e = readdir(d)) != NULL)
        if (e->d_name[0] == '.' && strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) n++;
    closedir(d);
    return n;
}

static void copy_file(const char *from, const char *to)
{
    char *s = slurp(from);
    FILE *f = fopen(to, "w");
    cr_assert(s && f, "copy %s -> %s", from, to);
    fputs(s, f);
    fclose(f);
    free(s);
}

Test(sweep_safety, the_summary_is_never_the_scenario_nor_a_special_file, .timeout = 60)
{
    /* -o the scenario, a symbolic link to it, a hard link to it, a FIFO, a
     * directory: each refused with one error line, exit 1; the scenario is
     * unchanged byte for byte, the FIFO is still a FIFO, no temporary file */
    char dir[64], sc[600], sym[600], hard[600], fifo[600], *before, *after, *err;
    struct stat st;
    make_tmpdir(dir, sizeof dir);
    scen(sym, sizeof sym, "tako_centred.toml");
    snprintf(sc, sizeof sc, "%s/s.toml", dir);
    copy_file(sym, sc);
    before = slurp(sc);
    snprintf(sym, sizeof sym, "%s/link.h5", dir);
    snprintf(hard, sizeof hard, "%s/hard.h5", dir);
    snprintf(fifo, sizeof fifo, "%s/fifo.h5", dir);
    cr_assert_eq(symlink(sc, sym), 0);
    cr_assert_eq(link(sc, hard), 0);
    cr_assert_eq(mkfifo(fifo, 0644), 0);

    cr_expect_eq(capdyn(dir, NULL, &err, "sweep", sc, TINY, TWO, "-q", "-o", sc, NULL), 1);
    one_error_line(err, "it is the scenario file");
    free(err);
    cr_expect_eq(capdyn(dir, NULL, &err, "sweep", sc, TINY, TWO, "-q", "-o", sym, NULL), 1);
    one_error_line(err, "it is the scenario file");
    free(err);
    cr_expect_eq(capdyn(dir, NULL, &err, "sweep", sc, TINY, TWO, "-q", "-o", hard, NULL), 1);
    one_error_line(err, "it is the scenario file");
    free(err);
    cr_expect_eq(capdyn(dir, NULL, &err, "sweep", sc, TINY, TWO, "-q", "-o", fifo, NULL), 1);
    one_error_line(err, "is not a regular file");
    free(err);
    cr_expect_eq(capdyn(dir, NULL, &err, "sweep", sc, TINY, TWO, "-q", "-o", dir, NULL), 1);
    one_error_line(err, "it is a directory");
    free(err);
    after = slurp(sc);
    cr_expect(after && !strcmp(before, after), "the scenario is unchanged");
    cr_expect(lstat(fifo, &st) == 0 && S_ISFIFO(st.st_mode), "the FIFO is still a FIFO");
    cr_expect_eq(hidden_files(dir), 0, "no temporary file left");
    free(before);
    free(after);
    rm_rf(dir);
}

Test(sweep_safety, a_file_another_capdyn_writes_is_refused_both_ways, .timeout = 120)
{
    /* (1) sweep -o the results file of a running capdyn run: refused, and
     * the run then ends normally with its file readable; (2) while a sweep
     * runs, capdyn run -o its summary and a second sweep with the same -o
     * are refused, and the first sweep completes all its variants. */
    char dir[64], sc[600], r[600], s[600], *err, *out;
    char *rargv[16], *sargv[24];
    int n = 0;
    pid_t pid;
    long long c = -1;
    double t0;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "tako_centred.toml");
    snprintf(r, sizeof r, "%s/run.h5", dir);
    snprintf(s, sizeof s, "%s/sum.h5", dir);

    rargv[n++] = (char *)bin();
    rargv[n++] = "run";
    rargv[n++] = sc;
    rargv[n++] = "-q";
    rargv[n++] = "-o";
    rargv[n++] = r;
    rargv[n++] = "--set";
    rargv[n++] = "simulation.duration=0.6";
    rargv[n] = NULL;
    {
        char sub[600];
        snprintf(sub, sizeof sub, "%s/r", dir);
        mkdir(sub, 0755);
        pid = spawn(sub, rargv, NULL);
    }
    /* wait until the run has committed its first samples */
    for (t0 = now(); now() - t0 < 30 && (c = peek_committed(r)) < 1;) sleep_s(0.02);
    cr_assert_geq(c, 1, "the run has started writing");
    cr_expect_eq(capdyn(dir, NULL, &err, "sweep", sc, TINY, TWO, "-q", "-o", r, NULL), 1);
    one_error_line(err, "another capdyn process is writing it");
    free(err);
    cr_expect_eq(wait_status(pid), 0, "the run ends normally");
    cr_expect_eq(capdyn(dir, &out, &err, "info", r, NULL), 0, "its file is readable: %s", err);
    cr_expect(out && strstr(out, "finished"), "%s", out ? out : "");
    free(out);
    free(err);

    n = 0;
    sargv[n++] = (char *)bin();
    sargv[n++] = "sweep";
    sargv[n++] = sc;
    sargv[n++] = "--set";
    sargv[n++] = "simulation.duration=0.1";
    sargv[n++] = "--vary";
    sargv[n++] = "target.object.mass=0.3:0.4:12";
    sargv[n++] = "-j";
    sargv[n++] = "1";
    sargv[n++] = "-q";
    sargv[n++] = "-o";
    sargv[n++] = s;
    sargv[n] = NULL;
    {
        char sub[600];
        struct stat st;
        snprintf(sub, sizeof sub, "%s/s", dir);
        mkdir(sub, 0755);
        pid = spawn(sub, sargv, NULL);
        for (t0 = now(); now() - t0 < 30 && stat(s, &st) != 0;) sleep_s(0.02);
    }
    cr_expect_eq(capdyn(dir, NULL, &err, "run", sc, "-q", "-o", s, NULL), 1);
    one_error_line(err, "is writing it");
    free(err);
    cr_expect_eq(capdyn(dir, NULL, &err, "sweep", sc, TINY, TWO, "-q", "-o", s, NULL), 1);
    one_error_line(err, "another capdyn process is writing it");
    free(err);
    cr_expect_eq(wait_status(pid), 0, "the first sweep completes");
    cr_expect_eq(capdyn(dir, &out, &err, "sweep", "--table", s, NULL), 0, "%s", err);
    cr_expect(out && strstr(out, ": 12 variants"), "%s", out ? out : "");
    {
        /* every row ran: status column (the 6th field with one key) is 0 */
        char *line = out ? strtok(out, "\n") : NULL;
        int rows = 0;
        for (; line; line = strtok(NULL, "\n")) {
            long idx;
            char v[64], vn[64];
            int verdict, status;
            if (line[0] == '#') continue;
            cr_expect_eq(sscanf(line, "%ld %63s %63s %d %d", &idx, v, vn, &verdict, &status), 5, "%s", line);
            cr_expect_eq(status, 0, "row %s", line);
            rows++;
        }
        cr_expect_eq(rows, 12);
    }
    free(out);
    free(err);
    rm_rf(dir);
}

Test(sweep_safety, a_file_size_limit_ends_the_sweep_with_one_line_and_no_temporary_file, .timeout = 60)
{
    /* ulimit -f 4 (4 blocks of 1 KB in bash, 512 B in dash: in either case
     * below the 16 KB of the summary): exit 1, one error line naming the
     * cause, no SIGXFSZ, no file and no temporary file left */
    char dir[64], sc[600], cmd[2000], *argv[4], *err, path[700];
    struct stat st;
    int rc;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "tako_centred.toml");
    snprintf(cmd, sizeof cmd,
             "ulimit -f 4 && exec '%s' sweep '%s' --set simulation.duration=0.02 --set simulation.output_dt=0.01 "
             "--vary target.object.mass=0.3,0.4 -q -o '%s/sum.h5'",
             bin(), sc, dir);
    argv[0] = "/bin/sh";
    argv[1] = "-c";
    argv[2] = cmd;
    argv[3] = NULL;
    rc = wait_status(spawn(dir, argv, NULL));
    snprintf(path, sizeof path, "%s/err.txt", dir);
    err = slurp(path);
    cr_expect_eq(rc, 1, "exit 1, not a signal (%d): %s", rc, err);
    one_error_line(err, "file size limit");
    free(err);
    snprintf(path, sizeof path, "%s/sum.h5", dir);
    cr_expect_neq(stat(path, &st), 0, "no summary");
    cr_expect_eq(hidden_files(dir), 0, "no temporary file left");
    rm_rf(dir);
}
