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
     * are refused, and the first sweep completes all its variants. The
     * run and the sweep that are refused against last about a second of
     * wall time each, so that they are still writing when the refused
     * commands start: with 0.6 s and 12 x 0.1 s of simulated time (about
     * 0.15 s of wall time, as fast as capdyn had become) the first sweep
     * could end before the second command started, on a loaded machine */
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
    rargv[n++] = "simulation.duration=3";
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
    sargv[n++] = "simulation.duration=1";
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

/* Runs capdyn (args NULL-ended) in dir with extra environment entries; the
 * exit status (128 + signal). ASan (make asan) must not turn a crash in the
 * reading child into an exit status or a report on stderr. */
static int capdyn_envv(const char *dir, char **out, char **err, const char *tmo, char *const *args)
{
    char opt[700], t[64], *env[3], *argv[32], p[700];
    int n = 0, st;
    snprintf(opt, sizeof opt,
             "ASAN_OPTIONS=handle_segv=0:handle_sigbus=0:handle_abort=0:handle_sigfpe=0:detect_leaks=0:"
             "abort_on_error=1:log_path=%s/asan",
             dir);
    snprintf(t, sizeof t, "CAPDYN_READ_TIMEOUT=%s", tmo);
    env[0] = opt;
    env[1] = t;
    env[2] = NULL;
    argv[n++] = (char *)bin();
    while (*args && n < 31) argv[n++] = *args++;
    argv[n] = NULL;
    st = wait_status(spawn(dir, argv, env));
    snprintf(p, sizeof p, "%s/out.txt", dir);
    if (out) *out = slurp(p);
    snprintf(p, sizeof p, "%s/err.txt", dir);
    if (err) *err = slurp(p);
    return st;
}

Test(sweep_safety, damaged_summaries_give_one_line_and_exit_1, .timeout = 120)
{
    /* tests/bad_inputs/summaries: a 2-variant summary with one bit flipped
     * (a value: the checksum; n_variants: 2^30 + 2, refused before any
     * allocation; the format name; the superblock; one that crashes HDF5
     * 1.10 (SIGSEGV) and one that makes it loop, both contained in the
     * reading child) and one cut in half. sweep --table on each: exit 1,
     * nothing on stdout, one error line (no HDF5 diagnostics) containing
     * NN_name.expected if that is not empty. The looping one takes the time
     * limit (1 s here). --resume on a copy of each refuses it the same way
     * and leaves it byte for byte. */
    char bdir[600], tdir[64], sc[600];
    DIR *d;
    struct dirent *e;
    int ncase = 0;
    snprintf(bdir, sizeof bdir, "%s/tests/bad_inputs/summaries", root());
    scen(sc, sizeof sc, "tako_centred.toml");
    make_tmpdir(tdir, sizeof tdir);
    d = opendir(bdir);
    cr_assert_not_null(d, "%s", bdir);
    while ((e = readdir(d)) != NULL) {
        char name[256], path[1200], cp[1200], *want, *out, *err, *before, *after;
        char *tab[4], *res[20];
        size_t l = strlen(e->d_name);
        int rc, n = 0;
        double t0;
        if (l < 4 || strcmp(e->d_name + l - 3, ".h5")) continue;
        snprintf(name, sizeof name, "%.*s", (int)(l - 3), e->d_name);
        snprintf(path, sizeof path, "%s/%s.expected", bdir, name);
        want = slurp(path);
        cr_assert_not_null(want, "%s.expected", name);
        if (*want) want[strlen(want) - 1] = 0;
        snprintf(path, sizeof path, "%s/%s", bdir, e->d_name);
        tab[0] = (char *)"sweep";
        tab[1] = (char *)"--table";
        tab[2] = path;
        tab[3] = NULL;
        t0 = now();
        rc = capdyn_envv(tdir, &out, &err, "1", tab);
        cr_expect_eq(rc, 1, "%s: exit %d: %s", name, rc, err);
        cr_expect(out && !*out, "%s: nothing on stdout", name);
        one_error_line(err, want);
        cr_expect_lt(now() - t0, 20, "%s: within the time limit", name);
        free(out);
        free(err);

        snprintf(cp, sizeof cp, "%s/%s", tdir, e->d_name);
        {
            FILE *f = fopen(path, "rb"), *g = fopen(cp, "wb");
            char buf[4096];
            size_t k;
            cr_assert(f && g);
            while ((k = fread(buf, 1, sizeof buf, f)) > 0) fwrite(buf, 1, k, g);
            fclose(f);
            fclose(g);
        }
        before = slurp(path);
        res[n++] = (char *)"sweep";
        res[n++] = sc;
        res[n++] = (char *)"--set";
        res[n++] = (char *)"simulation.duration=0.02";
        res[n++] = (char *)"--set";
        res[n++] = (char *)"simulation.output_dt=0.01";
        res[n++] = (char *)"--vary";
        res[n++] = (char *)"target.object.mass=0.3,0.4";
        res[n++] = (char *)"--resume";
        res[n++] = (char *)"-q";
        res[n++] = (char *)"-o";
        res[n++] = cp;
        res[n] = NULL;
        rc = capdyn_envv(tdir, &out, &err, "1", res);
        cr_expect_eq(rc, 1, "--resume %s: exit %d: %s", name, rc, err);
        one_error_line(err, want);
        after = slurp(cp);
        /* compared as files of the same size and bytes (they hold zeros) */
        {
            struct stat s1, s2;
            cr_expect(stat(path, &s1) == 0 && stat(cp, &s2) == 0 && s1.st_size == s2.st_size &&
                          before && after && !memcmp(before, after, (size_t)s1.st_size),
                      "--resume %s left the file as it was", name);
        }
        free(before);
        free(after);
        free(out);
        free(err);
        free(want);
        ncase++;
    }
    closedir(d);
    cr_expect_geq(ncase, 7, "the damaged summaries are there");
    rm_rf(tdir);
}

Test(sweep_safety, a_fifo_is_never_opened_as_an_input, .timeout = 30)
{
    /* info, export, sweep --table and sweep --resume -o on a FIFO: refused
     * at once (it would block forever), one error line, exit 1 */
    char dir[64], fifo[600], sc[600], *err;
    double t0 = now();
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "tako_centred.toml");
    snprintf(fifo, sizeof fifo, "%s/p.h5", dir);
    cr_assert_eq(mkfifo(fifo, 0644), 0);
    cr_expect_eq(capdyn(dir, NULL, &err, "info", fifo, NULL), 1);
    one_error_line(err, "is not a results file: it is a FIFO");
    free(err);
    cr_expect_eq(capdyn(dir, NULL, &err, "export", "--every", "2", fifo, "time", NULL), 1);
    one_error_line(err, "is not a results file: it is a FIFO");
    free(err);
    cr_expect_eq(capdyn(dir, NULL, &err, "sweep", "--table", fifo, NULL), 1);
    one_error_line(err, "is not a sweep summary: it is a FIFO");
    free(err);
    cr_expect_eq(capdyn(dir, NULL, &err, "sweep", sc, TINY, TWO, "--resume", "-o", fifo, NULL), 1);
    one_error_line(err, "it exists and is not a regular file");
    free(err);
    cr_expect_lt(now() - t0, 20);
    rm_rf(dir);
}

Test(sweep_safety, the_grid_size_is_checked_before_its_values_are_made, .timeout = 30)
{
    /* four keys of 10^7 values each: 10^28 variants, refused in well under
     * a second (the values of each key were made first: 40 s, 1.5 GB) */
    char dir[64], sc[600], *err;
    double t0;
    make_tmpdir(dir, sizeof dir);
    scen(sc, sizeof sc, "tako_centred.toml");
    t0 = now();
    cr_expect_eq(capdyn(dir, NULL, &err, "sweep", sc, "--vary", "a=0:1:10000000", "--vary", "b=0:1:10000000",
                        "--vary", "c=0:1:10000000", "--vary", "d=0:1:10000000", NULL),
                 1);
    cr_expect_lt(now() - t0, 2.0, "refused at once: %.2f s", now() - t0);
    one_error_line(err, "the grid has 1e+28 variants, more than 10000000");
    free(err);
    /* one variant over the limit */
    cr_expect_eq(capdyn(dir, NULL, &err, "sweep", sc, "--vary", "a=0:1:10001", "--vary", "b=0:1:1000", NULL), 1);
    one_error_line(err, "the grid has 10001000 variants, more than 10000000");
    free(err);
    rm_rf(dir);
}
