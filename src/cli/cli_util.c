/* Helpers shared by every file of src/cli (cli_util.h). */
#define _POSIX_C_SOURCE 200809L
#include "cli_util.h"

#include <errno.h>
#include <hdf5.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

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

char *cli_fmt_num(char *buf, double v)
{
    int prec;
    for (prec = 15; prec <= 17; prec++) {
        snprintf(buf, CLI_NUM, "%.*g", prec, v);
        if (!isfinite(v) || strtod(buf, NULL) == v) break;
    }
    return buf;
}

void cli_put_num(FILE *out, double v)
{
    char b[CLI_NUM];
    fputs(cli_fmt_num(b, v), out);
}

int cli_regular_input(const char *path, const char *what, char *msg, size_t len)
{
    struct stat st;
    if (stat(path, &st) != 0 || S_ISREG(st.st_mode)) return 0;
    snprintf(msg, len, "'%s' is not a %s: it is %s", path, what,
             S_ISDIR(st.st_mode) ? "a directory" : S_ISFIFO(st.st_mode) ? "a FIFO (a named pipe)" :
             S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode) ? "a device" : "not a regular file");
    return -1;
}

double cli_read_limit(const char *path)
{
    const char *e = getenv("CAPDYN_READ_TIMEOUT");
    struct stat st;
    double v;
    if (e && cli_number(e, &v) == 0 && v > 0) return v;
    return 60.0 + (stat(path, &st) == 0 ? (double)st.st_size / 1e6 : 0.0);
}

/* Reading a file in a child process (docs/reliability.md, "Untrusted
 * results files"). The readers check every size and index they take from a
 * file, but libhdf5 1.10 itself can crash on a damaged file (measured: a
 * flipped bit in an attribute's size field) or loop. The child writes its
 * stdout into a temporary file; the parent copies it out only if the child
 * exited (with its status), so a crash or a hang becomes one error line and
 * exit status 1, with nothing half printed. */
int cli_isolated(const char *path, int (*fn)(void *), void *arg)
{
    FILE *tmp;
    pid_t pid;
    int st;
    char buf[65536];
    size_t n;
    double limit = cli_read_limit(path);
    if (getenv("CAPDYN_NO_ISOLATION")) return fn(arg);
    fflush(NULL);
    tmp = tmpfile();
    if (!tmp) {
        cli_error("cannot create a temporary file to read '%s': %s", path, strerror(errno));
        return CLI_FAIL;
    }
    pid = fork();
    if (pid < 0) {
        fclose(tmp);
        cli_error("cannot start the process that reads '%s': %s", path, strerror(errno));
        return CLI_FAIL;
    }
    if (pid == 0) {
        int rc = CLI_FAIL;
        struct sigaction sa;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = SIG_DFL;
        sigemptyset(&sa.sa_mask);
        sigaction(SIGALRM, &sa, NULL);
        alarm((unsigned)(limit < 1 ? 1 : limit > 1e6 ? 1e6 : ceil(limit)));
        H5Eset_auto2(H5E_DEFAULT, NULL, NULL); /* one message of ours, not HDF5's diagnostics */
        if (dup2(fileno(tmp), STDOUT_FILENO) >= 0) rc = fn(arg);
        if (fflush(stdout) != 0 && rc == CLI_OK) {
            cli_error("writing the output failed");
            rc = CLI_FAIL;
        }
        _exit(rc);
    }
    while (waitpid(pid, &st, 0) < 0)
        if (errno != EINTR) {
            fclose(tmp);
            cli_error("waiting for the reading process failed: %s", strerror(errno));
            return CLI_FAIL;
        }
    if (WIFSIGNALED(st) && WTERMSIG(st) == SIGALRM) {
        fclose(tmp);
        cli_error("'%s': reading the file took more than %.0f s (the time limit, CAPDYN_READ_TIMEOUT): the file is "
                  "damaged or not a capdyn file; nothing was printed",
                  path, limit);
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
    {
        int bad = 0, e = 0;
        while ((n = fread(buf, 1, sizeof buf, tmp)) > 0)
            if (fwrite(buf, 1, n, stdout) != n) { bad = 1; e = errno; break; }
        fclose(tmp);
        /* a failed write may have been dropped from the buffer already:
         * fflush alone can then return 0, so the stream's error flag counts */
        if (fflush(stdout) != 0 && !bad) { bad = 1; e = errno; }
        if (bad || ferror(stdout)) {
            cli_error("writing the output failed: %s", strerror(e ? e : EIO));
            return CLI_FAIL;
        }
    }
    return WEXITSTATUS(st);
}
