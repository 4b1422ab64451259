/* Process and file helpers shared by the tests that run the capdyn command
 * (test_cli.c, test_results_safety.c). Environment: CAPDYN_BIN the binary
 * (default build/capdyn), CAPDYN_ROOT the repository (default .), as `make
 * test` sets them. */
#ifndef CD_TEST_PROC_UTIL_H
#define CD_TEST_PROC_UTIL_H
#include <criterion/criterion.h>
#include <hdf5.h>
#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static inline const char *bin(void)
{
    const char *b = getenv("CAPDYN_BIN");
    return b && *b ? b : "build/capdyn";
}
static inline const char *root(void)
{
    const char *r = getenv("CAPDYN_ROOT");
    return r && *r ? r : ".";
}
static inline void scen(char *out, size_t n, const char *name) { snprintf(out, n, "%s/scenarios/%s", root(), name); }

static inline void make_tmpdir(char *dir, size_t n)
{
    snprintf(dir, n, "/tmp/capdyn_cli_XXXXXX");
    cr_assert_not_null(mkdtemp(dir), "mkdtemp: %s", strerror(errno));
}
static inline void rm_rf(const char *dir)
{
    char cmd[600];
    if (getenv("CAPDYN_KEEP_TEST_FILES")) return;
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0) cr_log_warn("could not remove %s", dir);
}

static inline char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    char *s;
    long n;
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    n = ftell(f);
    fseek(f, 0, SEEK_SET);
    s = malloc((size_t)n + 1);
    if (s && fread(s, 1, (size_t)n, f) != (size_t)n) { free(s); s = NULL; }
    if (s) s[n] = 0;
    fclose(f);
    return s;
}

static inline double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static inline void sleep_s(double s)
{
    struct timespec ts;
    ts.tv_sec = (time_t)s;
    ts.tv_nsec = (long)((s - (double)ts.tv_sec) * 1e9);
    nanosleep(&ts, NULL);
}

/* Starts argv (NULL-terminated) with stdout/stderr into dir/out.txt,
 * dir/err.txt; env entries "K=V" are set in the child. Returns the pid. */
static inline pid_t spawn(const char *dir, char *const argv[], char *const env[])
{
    char o[4096], e[4096];
    pid_t pid;
    cr_assert(strlen(dir) + sizeof "/out.txt" <= sizeof o, "spawn: directory name too long: %s", dir);
    snprintf(o, sizeof o, "%s/out.txt", dir);
    snprintf(e, sizeof e, "%s/err.txt", dir);
    fflush(NULL);
    pid = fork();
    cr_assert(pid >= 0, "fork: %s", strerror(errno));
    if (pid == 0) {
        int fo = open(o, O_WRONLY | O_CREAT | O_TRUNC, 0644), fe = open(e, O_WRONLY | O_CREAT | O_TRUNC, 0644), i;
        if (fo < 0 || fe < 0) _exit(126);
        dup2(fo, 1);
        dup2(fe, 2);
        for (i = 0; env && env[i]; i++) {
            char *eq = strchr(env[i], '=');
            if (!eq) continue;
            *eq = 0;
            setenv(env[i], eq + 1, 1);
        }
        execv(argv[0], argv);
        _exit(127);
    }
    return pid;
}

static inline int wait_status(pid_t pid)
{
    int st;
    cr_assert_eq(waitpid(pid, &st, 0), pid);
    if (WIFEXITED(st)) return WEXITSTATUS(st);
    return 128 + WTERMSIG(st);
}

/* Runs capdyn with the given arguments (NULL-terminated); returns the exit
 * status; *out / *err (if non-NULL) receive its stdout / stderr (free them). */
static inline int capdyn(const char *dir, char **out, char **err, ...)
{
    char *argv[64], path[512];
    va_list ap;
    int n = 0, st;
    argv[n++] = (char *)bin();
    va_start(ap, err);
    while (n < 63 && (argv[n] = va_arg(ap, char *)) != NULL) n++;
    va_end(ap);
    argv[n] = NULL;
    st = wait_status(spawn(dir, argv, NULL));
    snprintf(path, sizeof path, "%s/out.txt", dir);
    if (out) *out = slurp(path);
    snprintf(path, sizeof path, "%s/err.txt", dir);
    if (err) *err = slurp(path);
    return st;
}

static inline hid_t open_ro(const char *path)
{
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS), f;
    H5Pset_file_locking(fapl, 0, 1);
    H5E_BEGIN_TRY { f = H5Fopen(path, H5F_ACC_RDONLY, fapl); } H5E_END_TRY;
    H5Pclose(fapl);
    return f;
}

/* committed_samples of a file being written, or -1 if it cannot be read now */
static inline long long peek_committed(const char *path)
{
    long long v = -1;
    hid_t f = open_ro(path), a;
    if (f < 0) return -1;
    H5E_BEGIN_TRY {
        a = H5Aopen(f, "committed_samples", H5P_DEFAULT);
        if (a >= 0) {
            if (H5Aread(a, H5T_NATIVE_LLONG, &v) < 0) v = -1;
            H5Aclose(a);
        }
        H5Fclose(f);
    } H5E_END_TRY;
    return v;
}

#endif
