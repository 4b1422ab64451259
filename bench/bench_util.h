/* Helpers the benchmark programs share (bench_speed.c, bench_scenarios.c,
 * bench_ticks.c): output to the terminal and to a results file, clocks,
 * sorting. Static functions: each program includes this once. */
#ifndef CAPDYN_BENCH_UTIL_H
#define CAPDYN_BENCH_UTIL_H

#include <stdarg.h>
#include <stdio.h>
#include <time.h>

/* the results file that say() copies to (NULL: the terminal only) */
static FILE *out_file;

/* print to stdout and to the results file */
static void say(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;
static void say(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vprintf(fmt, ap);
    va_end(ap);
    if (out_file) {
        va_start(ap, fmt);
        vfprintf(out_file, fmt, ap);
        va_end(ap);
    }
    fflush(stdout);
}

/* seconds on a clock (CLOCK_MONOTONIC, CLOCK_THREAD_CPUTIME_ID, ...) */
static inline double clock_s(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* qsort comparison of doubles, ascending */
static inline int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

#endif
