/* Helpers of the input-reliability tests (test_loader_limits.c,
 * test_bad_inputs.c): temporary scenario files, the loader on a thread with
 * a small stack (an embedder's thread), and `capdyn` run in a directory with
 * its stderr captured. Static functions: each test file includes this once. */
#ifndef CAPDYN_TEST_LOADER_UTIL_H
#define CAPDYN_TEST_LOADER_UTIL_H

#include "proc_util.h" /* slurp */
#include <criterion/criterion.h>

#include "capdyn/io.h"

#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

/* The stack of an embedder's thread (issue 12). Sanitizers make frames
 * several times larger: under ASan the same test gets 4 times as much. */
#if defined(__SANITIZE_ADDRESS__)
#define LU_STACK (4u * 256u * 1024u)
#else
#define LU_STACK (256u * 1024u)
#endif

static inline const char *lu_root(void)
{
    const char *r = getenv("CAPDYN_ROOT");
    return r && *r ? r : ".";
}

static inline const char *lu_bin(void)
{
    const char *b = getenv("CAPDYN_BIN");
    return b && *b ? b : "build/capdyn";
}

static inline void lu_tmpdir(char *dir, size_t n)
{
    snprintf(dir, n, "/tmp/capdyn_input_XXXXXX");
    cr_assert_not_null(mkdtemp(dir), "mkdtemp: %s", strerror(errno));
}

static inline void lu_rm_rf(const char *dir)
{
    char cmd[600];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0) cr_log_warn("could not remove %s", dir);
}

/* Writes dir/name with printf-style content. */
static inline void lu_write(const char *dir, const char *name, const char *fmt, ...)
{
    char path[1024];
    FILE *f;
    va_list ap;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    f = fopen(path, "w");
    cr_assert_not_null(f, "%s: %s", path, strerror(errno));
    va_start(ap, fmt);
    vfprintf(f, fmt, ap);
    va_end(ap);
    cr_assert_eq(fclose(f), 0);
}


/* ---- the loader on a thread with a LU_STACK stack ---- */
typedef struct {
    const char *path;
    const char *const *ov;
    int nov;
    cd_scenario *sc;
    cd_error err;
} lu_job;

static inline void *lu_job_run(void *p)
{
    lu_job *j = (lu_job *)p;
    j->sc = cd_scenario_load(j->path, j->ov, j->nov, &j->err);
    return NULL;
}

/* Loads path with overrides on a small-stack thread; the scenario (or NULL)
 * is returned, err filled. A stack overflow crashes the test (Criterion
 * reports it as a crash). */
static inline cd_scenario *lu_load_small_stack(const char *path, const char *const *ov, int nov, cd_error *err)
{
    pthread_attr_t a;
    pthread_t t;
    lu_job j;
    memset(&j, 0, sizeof j);
    j.path = path;
    j.ov = ov;
    j.nov = nov;
    cr_assert_eq(pthread_attr_init(&a), 0);
    cr_assert_eq(pthread_attr_setstacksize(&a, LU_STACK), 0);
    cr_assert_eq(pthread_create(&t, &a, lu_job_run, &j), 0);
    cr_assert_eq(pthread_join(t, NULL), 0);
    pthread_attr_destroy(&a);
    *err = j.err;
    return j.sc;
}

/* Runs capdyn with args (NULL-terminated, without the program) in the
 * working directory dir; returns the exit status (128 + signal if killed);
 * *out / *err receive its stdout / stderr (free them; may be NULL). The
 * output goes through temporary files in /tmp, never into dir. */
static inline int lu_capdyn(const char *dir, char **out, char **err, const char *const *args)
{
    char o[] = "/tmp/capdyn_out_XXXXXX", e[] = "/tmp/capdyn_err_XXXXXX";
    const char *argv[64];
    pid_t pid;
    int n = 0, st, fo = mkstemp(o), fe = mkstemp(e);
    cr_assert(fo >= 0 && fe >= 0, "mkstemp: %s", strerror(errno));
    argv[n++] = lu_bin();
    while (n < 63 && args[n - 1]) { argv[n] = args[n - 1]; n++; }
    argv[n] = NULL;
    fflush(NULL);
    pid = fork();
    cr_assert(pid >= 0, "fork: %s", strerror(errno));
    if (pid == 0) {
        if (chdir(dir) != 0) _exit(126);
        dup2(fo, 1);
        dup2(fe, 2);
        execv(argv[0], (char *const *)argv);
        _exit(127);
    }
    close(fo);
    close(fe);
    cr_assert_eq(waitpid(pid, &st, 0), pid);
    if (out) *out = slurp(o);
    if (err) *err = slurp(e);
    unlink(o);
    unlink(e);
    return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
}

#endif
