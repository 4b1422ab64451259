/* The failing-allocator test (issue 12; docs/reliability.md "## Input";
 * run by `make test`, not under ASan, whose allocator it would fight).
 *
 * malloc, calloc, realloc, the aligned allocators and free are interposed
 * (this executable defines them, glibc's __libc_* do the work); C++
 * operator new goes through malloc, so toml++ and the loader's own
 * allocations are covered. The work is: cd_scenario_load of
 * tests/failalloc/scene.toml (an include, an override), cd_data_create and
 * a 0.02 s run (cd_sim_advance).
 *
 * First the work runs once with every allocation granted: that counts its
 * allocations, A. Then for every N in 1..A the work runs again with the N-th
 * allocation (counted from the start of the work) failing. Each run must end
 * in one of two ways:
 *   - success (the failed allocation was optional), or
 *   - a clean error: a non-OK status with a one-line message, CD_ENOMEM,
 *     or CD_EIO whose message says the memory ran out (fopen needs memory);
 * and in both cases every allocation of the run is freed (allocations still
 * live after it == before it). A crash, an abort, a leak or any other status
 * fails the test. Exit status 0 when all N pass; the summary on stdout.
 * The whole first part runs four times: with the scene's integrator (auto:
 * rk8pd and ros34pw2), with simulation.integrator = "rk4imp" (capdyn's Gauss
 * stepper, src/sim/gauss4.c, which replaced GSL's: that one allocated in every
 * step and aborted when an allocation failed), with "rodas4" and with
 * "msbdf" (capdyn's BDF stepper, src/sim/bdf.c, which replaced GSL's, whose
 * LU allocated inside steps).
 *
 * One exception, found by this test: Debian's toml++ 3.3 (libtomlplusplus.so)
 * calls std::terminate when an allocation fails inside its parser (the
 * std::bad_alloc crosses one of its noexcept functions), which no caller can
 * catch. An allocation whose call stack is inside that library is therefore
 * granted, not failed, and counted apart ("inside toml++"); every other
 * allocation of the work is failed in turn. Likewise GSL 2.7's
 * gsl_odeiv2_control_standard_new (called by gsl_odeiv2_driver_alloc_*,
 * in cd_data_create) dereferences the NULL of its own failed allocation:
 * allocations under it are granted and counted apart ("inside GSL's control
 * set-up"). docs/reliability.md states both.
 *
 * A second part (test_writer, below) does the same for the HDF5 results
 * writer: a failed allocation must be reported as out of memory, not as a
 * disk problem. */
#define _GNU_SOURCE
#include "capdyn/io.h"
#include "capdyn/sim.h"

#include <dlfcn.h>
#include <errno.h>
#include <execinfo.h>
#include <gsl/gsl_errno.h>
#include <link.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* ---- the interposed allocator ---- */
extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void *__libc_memalign(size_t, size_t);
extern void __libc_free(void *);

static long g_count;    /* allocations requested since the counter was reset */
static long g_fail_at;  /* fail this one (0: none) */
static long g_live;     /* allocations not yet freed */
static int g_armed;     /* counting on */
static long g_in_toml;  /* the failing allocation was inside toml++: granted */
static long g_in_gsl;   /* ... inside GSL's gsl_odeiv2_control_*_new: granted */
static long g_in_h5;    /* ... inside libhdf5 (the writer's phase): granted */
static int g_h5_mode;   /* writer phase: 0 off; count (and fail) only the allocations 1 outside libhdf5,
                           2 inside it */

/* address ranges of libtomlplusplus.so's loaded segments */
static struct { unsigned long lo, hi; } g_toml[8];
static int g_ntoml;
/* ... and of libhdf5.so's */
static struct { unsigned long lo, hi; } g_hdf5[8];
static int g_nhdf5;

static int find_hdf5(struct dl_phdr_info *info, size_t size, void *data)
{
    int i;
    (void)size;
    (void)data;
    if (!info->dlpi_name || !strstr(info->dlpi_name, "libhdf5") || strstr(info->dlpi_name, "_hl")) return 0;
    for (i = 0; i < info->dlpi_phnum && g_nhdf5 < 8; i++)
        if (info->dlpi_phdr[i].p_type == PT_LOAD) {
            g_hdf5[g_nhdf5].lo = info->dlpi_addr + info->dlpi_phdr[i].p_vaddr;
            g_hdf5[g_nhdf5].hi = g_hdf5[g_nhdf5].lo + info->dlpi_phdr[i].p_memsz;
            g_nhdf5++;
        }
    return 1;
}

/* 1: the allocation is made inside libhdf5 */
static int inside_hdf5(void)
{
    void *fr[64];
    int n, i, k, r = 0;
    g_armed = 0;
    n = backtrace(fr, 64);
    for (i = 0; i < n && !r; i++)
        for (k = 0; k < g_nhdf5; k++)
            if ((unsigned long)fr[i] >= g_hdf5[k].lo && (unsigned long)fr[i] < g_hdf5[k].hi) r = 1;
    g_armed = 1;
    return r;
}

static int find_toml(struct dl_phdr_info *info, size_t size, void *data)
{
    int i;
    (void)size;
    (void)data;
    if (!info->dlpi_name || !strstr(info->dlpi_name, "libtomlplusplus")) return 0;
    for (i = 0; i < info->dlpi_phnum && g_ntoml < 8; i++)
        if (info->dlpi_phdr[i].p_type == PT_LOAD) {
            g_toml[g_ntoml].lo = info->dlpi_addr + info->dlpi_phdr[i].p_vaddr;
            g_toml[g_ntoml].hi = g_toml[g_ntoml].lo + info->dlpi_phdr[i].p_memsz;
            g_ntoml++;
        }
    return 1;
}

/* 1: the allocation is made inside toml++, 2: inside GSL's control set-up,
 * 0: elsewhere */
static int known_defect(void)
{
    void *fr[64];
    int n, i, k, r = 0;
    g_armed = 0; /* backtrace and dladdr may allocate */
    n = backtrace(fr, 64);
    for (i = 0; i < n && !r; i++) {
        Dl_info di;
        for (k = 0; k < g_ntoml; k++)
            if ((unsigned long)fr[i] >= g_toml[k].lo && (unsigned long)fr[i] < g_toml[k].hi) r = 1;
        if (!r && dladdr(fr[i], &di) && di.dli_sname && strncmp(di.dli_sname, "gsl_odeiv2_control_", 19) == 0 &&
            strstr(di.dli_sname, "_new"))
            r = 2;
    }
    g_armed = 1;
    return r;
}

static int should_fail(void)
{
    if (!g_armed) return 0;
    if (g_h5_mode) { /* count only the allocations outside (1) or inside (2) libhdf5 */
        if (inside_hdf5() != (g_h5_mode == 2)) {
            g_in_h5 += g_h5_mode == 1;
            return 0;
        }
        return ++g_count == g_fail_at;
    }
    g_count++;
    if (g_count != g_fail_at) return 0;
    switch (known_defect()) {
    case 1: g_in_toml++; return 0;
    case 2: g_in_gsl++; return 0;
    default: return 1;
    }
}

void *malloc(size_t n)
{
    void *p;
    if (should_fail()) { errno = ENOMEM; return NULL; }
    p = __libc_malloc(n);
    if (p) g_live++;
    return p;
}

void *calloc(size_t a, size_t b)
{
    void *p;
    if (should_fail()) { errno = ENOMEM; return NULL; }
    p = __libc_calloc(a, b);
    if (p) g_live++;
    return p;
}

void *realloc(void *q, size_t n)
{
    void *p;
    if (!q) return malloc(n);
    if (n == 0) { free(q); return NULL; }
    if (should_fail()) { errno = ENOMEM; return NULL; }
    p = __libc_realloc(q, n);
    return p;
}

void *memalign(size_t al, size_t n)
{
    void *p;
    if (should_fail()) { errno = ENOMEM; return NULL; }
    p = __libc_memalign(al, n);
    if (p) g_live++;
    return p;
}

void *aligned_alloc(size_t al, size_t n) { return memalign(al, n); }

int posix_memalign(void **out, size_t al, size_t n)
{
    void *p = memalign(al, n);
    if (!p) return ENOMEM;
    *out = p;
    return 0;
}

void free(void *p)
{
    if (!p) return;
    g_live--;
    __libc_free(p);
}

/* ---- the work ---- */
static char g_scene[4096];
static const char *g_integ; /* an integrator override ("simulation.integrator=..."), NULL: the scene's */
static const char *g_label = ""; /* its name in the summary, "rk4imp: " */

/* load + create + run; returns the status, msg filled on error */
static cd_status work(char *msg, size_t len)
{
    const char *ov[2] = {"simulation.duration=0.02", g_integ};
    cd_error err;
    cd_scenario *sc;
    cd_data *d;
    cd_status st;
    msg[0] = 0;
    sc = cd_scenario_load(g_scene, ov, g_integ ? 2 : 1, &err);
    if (!sc) {
        snprintf(msg, len, "%s", err.msg);
        return err.status;
    }
    d = cd_data_create(sc->model, 16, &err);
    if (!d) {
        snprintf(msg, len, "%s", err.msg);
        cd_scenario_free(sc);
        return err.status;
    }
    st = cd_sim_advance(sc->model, d, sc->duration, NULL, NULL, &err);
    if (st != CD_OK) snprintf(msg, len, "%s", err.msg);
    cd_data_free(d);
    cd_scenario_free(sc);
    return st;
}

/* ---- the results writer (issue 24) ----
 * The work: cd_h5_create of a results file, three cd_h5_append (0.02 s of
 * simulation between them, not counted), cd_h5_flush and cd_h5_close.
 * 1. Every allocation of it that capdyn makes fails in turn; each run must
 *    end in success or with CD_ENOMEM and a one-line message that says
 *    "out of memory" and not "disk full" (a failed allocation is not a disk
 *    problem). Allocations inside libhdf5 are granted and counted apart:
 *    HDF5 1.10 does not survive all of its own failed allocations (measured
 *    with this program: a failed allocation inside H5Pset_file_locking
 *    leaves the list damaged and its H5Pclose frees twice; after others,
 *    every later H5Fcreate of the process fails).
 * 2. The first allocation inside libhdf5 (H5Pcreate's, in cd_h5_create)
 *    fails: HDF5's error stack says it could not allocate, and the message
 *    must say "out of memory" (CD_ENOMEM), not name a disk problem.
 * HDF5 keeps free lists, so allocations still live after a run are not
 * counted here. */
static char g_h5dir[4096];

static void rm_results(void)
{
    char p[4200];
    snprintf(p, sizeof p, "%s/r.h5", g_h5dir);
    (void)unlink(p);
}

/* returns the first non-OK status (msg filled) */
static cd_status work_h5(cd_scenario *sc, char *msg, size_t len)
{
    cd_error err;
    cd_data *d;
    cd_h5_writer *w;
    cd_status st = CD_OK, cst;
    char path[4200];
    int k, armed = g_armed; /* allocations outside the writer's calls are not failed */
    msg[0] = 0;
    g_armed = 0;
    d = cd_data_create(sc->model, 16, &err);
    g_armed = armed;
    if (!d) {
        snprintf(msg, len, "cd_data_create: %s", err.msg);
        return err.status;
    }
    snprintf(path, sizeof path, "%s/r.h5", g_h5dir);
    w = cd_h5_create(path, sc->model, sc, &err);
    if (!w) {
        snprintf(msg, len, "%s", err.msg);
        g_armed = 0;
        cd_data_free(d);
        g_armed = armed;
        return err.status;
    }
    for (k = 0; k < 3 && st == CD_OK; k++) {
        g_armed = 0;
        if (k > 0 && cd_sim_advance(sc->model, d, d->t + 0.02, NULL, NULL, &err) != CD_OK) {
            snprintf(msg, len, "the run failed: %s", err.msg);
            st = CD_EINVAL; /* counted as bad */
        }
        g_armed = armed;
        if (st == CD_OK && (st = cd_h5_append(w, sc->model, d, &err)) != CD_OK) snprintf(msg, len, "%s", err.msg);
    }
    if (st == CD_OK && (st = cd_h5_flush(w, &err)) != CD_OK) snprintf(msg, len, "%s", err.msg);
    cst = cd_h5_close(w, sc->model, d, CD_OK, NULL, &err);
    if (st == CD_OK && cst != CD_OK) {
        st = cst;
        snprintf(msg, len, "%s", err.msg);
    }
    g_armed = 0;
    cd_data_free(d);
    g_armed = armed;
    return st;
}

static int test_writer(void)
{
    static const char *const ov[] = {"simulation.duration=0.06"};
    cd_error err;
    cd_scenario *sc;
    char msg[1024];
    long total, n, ok = 0, enomem = 0, bad = 0, in_h5;
    cd_status st;
    const char *tmp = getenv("TMPDIR");
    snprintf(g_h5dir, sizeof g_h5dir, "%s/capdyn_failalloc_XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(g_h5dir)) {
        printf("failalloc: cannot make a temporary directory\n");
        return 1;
    }
    sc = cd_scenario_load(g_scene, ov, 1, &err);
    if (!sc) {
        printf("failalloc: the scenario does not load: %s\n", err.msg);
        return 1;
    }
    st = work_h5(sc, msg, sizeof msg); /* warm-up, twice: HDF5's free lists fill in the first two runs */
    rm_results();
    if (st == CD_OK) st = work_h5(sc, msg, sizeof msg);
    rm_results();
    dl_iterate_phdr(find_hdf5, NULL);
    if (st != CD_OK || g_nhdf5 == 0) {
        printf("failalloc: the results file is not written (%s) or libhdf5 is not loaded\n", msg);
        cd_scenario_free(sc);
        return 1;
    }
    g_count = 0;
    g_fail_at = 0;
    g_in_h5 = 0;
    g_h5_mode = 1; /* the count of capdyn's allocations (those inside libhdf5 are granted) */
    g_armed = 1;
    st = work_h5(sc, msg, sizeof msg);
    g_armed = 0;
    total = g_count;
    in_h5 = g_in_h5;
    rm_results();
    if (st != CD_OK) {
        printf("failalloc: the counting run of the writer failed: %s\n", msg);
        cd_scenario_free(sc);
        return 1;
    }
    for (n = 1; n <= total; n++) {
        if (getenv("FAILALLOC_TRACE")) fprintf(stderr, "failalloc: writer: failing allocation %ld\n", n);
        g_count = 0;
        g_fail_at = n;
        g_armed = 1;
        st = work_h5(sc, msg, sizeof msg);
        g_armed = 0;
        rm_results();
        if (st == CD_OK) {
            ok++;
        } else if (msg[0] == 0 || strchr(msg, '\n')) {
            printf("failalloc: writer: allocation %ld failing: status %s without a one-line message\n", n,
                   cd_status_string(st));
            bad++;
        } else if (st == CD_ENOMEM && strstr(msg, "out of memory") && !strstr(msg, "disk full")) {
            enomem++;
        } else {
            printf("failalloc: writer: allocation %ld of %ld failing: status %s, expected %s saying \"out of memory\": "
                   "%s\n", n, total, cd_status_string(st), cd_status_string(CD_ENOMEM), msg);
            bad++;
        }
    }
    printf("failalloc: %ld allocations by capdyn (and %ld inside HDF5, granted) in results create + 3 appends + "
           "flush + close; failing each: %ld CD_ENOMEM saying out of memory, %ld still succeed, %ld bad\n",
           total, in_h5, enomem, ok, bad);
    /* 2: HDF5's own failed allocation */
    g_h5_mode = 2;
    g_count = 0;
    g_fail_at = 1;
    g_armed = 1;
    st = work_h5(sc, msg, sizeof msg);
    g_armed = 0;
    g_h5_mode = 0;
    rm_results();
    if (st != CD_ENOMEM || !strstr(msg, "cannot create results file") || !strstr(msg, "out of memory")) {
        printf("failalloc: writer: the first allocation inside HDF5 failing: status %s, expected %s saying "
               "\"cannot create results file ...: out of memory\": %s\n", cd_status_string(st),
               cd_status_string(CD_ENOMEM), msg);
        bad++;
    } else {
        printf("failalloc: the first allocation inside HDF5 failing: %s\n", msg);
    }
    cd_scenario_free(sc);
    (void)rmdir(g_h5dir);
    return bad ? 1 : 0;
}

/* The work once with every allocation granted (the count), then with each
 * failing in turn; returns the bad runs (or 1 if the counting run fails). */
static long fail_each(void)
{
    char msg[1024];
    long total, n, ok = 0, enomem = 0, eio = 0, bad = 0, before;
    cd_status st;
    g_in_toml = g_in_gsl = 0;
    before = g_live;
    g_count = 0;
    g_fail_at = 0;
    g_armed = 1;
    st = work(msg, sizeof msg);
    g_armed = 0;
    total = g_count;
    if (st != CD_OK || g_live != before) {
        printf("failalloc: the counting run failed (%s) or leaked %ld allocations\n", msg, g_live - before);
        return 1;
    }
    for (n = 1; n <= total; n++) {
        if (getenv("FAILALLOC_TRACE")) fprintf(stderr, "failalloc: failing allocation %ld\n", n);
        before = g_live;
        g_count = 0;
        g_fail_at = n;
        g_armed = 1;
        st = work(msg, sizeof msg);
        g_armed = 0;
        if (g_live != before) {
            printf("failalloc: allocation %ld of %ld failing: %ld allocations leaked (status %s: %s)\n", n, total,
                   g_live - before, cd_status_string(st), msg);
            bad++;
            continue;
        }
        if (st == CD_OK) {
            ok++; /* includes the allocations inside toml++, granted */
        } else if (msg[0] == 0 || strchr(msg, '\n')) {
            printf("failalloc: allocation %ld failing: status %s without a one-line message\n", n, cd_status_string(st));
            bad++;
        } else if (st == CD_ENOMEM) {
            enomem++;
        } else if (st == CD_EIO && strstr(msg, strerror(ENOMEM))) {
            eio++;
        } else {
            printf("failalloc: allocation %ld failing: status %s, expected %s: %s\n", n, cd_status_string(st),
                   cd_status_string(CD_ENOMEM), msg);
            bad++;
        }
    }
    printf("failalloc: %s%ld allocations in load + create + run; failing each: %ld CD_ENOMEM, %ld CD_EIO (out of memory "
           "opening a file), %ld still succeed (of which %ld inside toml++ and %ld inside GSL's control set-up, "
           "granted), %ld bad\n",
           g_label, total, enomem, eio, ok, g_in_toml, g_in_gsl, bad);
    return bad;
}

int main(void)
{
    const char *root = getenv("CAPDYN_ROOT");
    char msg[1024];
    long bad;
    cd_status st;
    void *fr[4];
    gsl_set_error_handler_off(); /* GSL's default handler aborts on a failed allocation */
    (void)backtrace(fr, 4);      /* its one-time set-up, before counting */
    snprintf(g_scene, sizeof g_scene, "%s/tests/failalloc/scene.toml", root && *root ? root : ".");

    /* warm-up (one-time allocations of the libraries), then the count */
    st = work(msg, sizeof msg);
    if (st != CD_OK) {
        printf("failalloc: the scenario does not run: %s\n", msg);
        return 1;
    }
    dl_iterate_phdr(find_toml, NULL);
    if (g_ntoml == 0) {
        printf("failalloc: libtomlplusplus is not loaded (linked statically?): update this test\n");
        return 1;
    }
    bad = fail_each();
    /* capdyn's other implicit steppers: their workspaces come with the data,
     * their steps allocate nothing */
    g_integ = "simulation.integrator=\"rk4imp\"";
    g_label = "rk4imp: ";
    bad += fail_each();
    g_integ = "simulation.integrator=\"rodas4\"";
    g_label = "rodas4: ";
    bad += fail_each();
    g_integ = "simulation.integrator=\"msbdf\"";
    g_label = "msbdf: ";
    bad += fail_each();
    g_integ = NULL;
    g_label = "";
    return test_writer() || bad ? 1 : 0;
}
