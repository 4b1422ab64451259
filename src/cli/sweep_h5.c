/* capdyn sweep: the summary file (HDF5, docs/sweep.md "Summary file").
 *
 * Written whole each time (at checkpoints, at an interruption, at the end)
 * under a temporary name in the target's directory and renamed onto it, so
 * the file on disk is always a complete summary of what had finished. The
 * rows are in variant order and every deterministic value is written from
 * the variants' results alone, so that the same sweep gives the same
 * summary for any -j or number of MPI ranks; wall times are in /timing
 * only. Objects are created without time stamps. The target is checked and
 * locked as a results file of capdyn run is (sw_out), and every value is
 * covered by a checksum (below).
 *
 * Read back (--table, --resume) by sw_summary_load in a child process with
 * a time limit (cli_isolated): every size is checked against the file
 * before anything is allocated, and the checksum is verified, so that a
 * damaged file gives one error line, never a crash, a hang or other values
 * (docs/reliability.md, "Sweeps"). */
#define _DEFAULT_SOURCE /* flock */
#define _POSIX_C_SOURCE 200809L
#include "sweep.h"
#include "capdyn/model.h"

#include <errno.h>
#include <fcntl.h>
#include <hdf5.h>
#include <libgen.h>
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#define SW_FORMAT "capdyn-sweep"
#define SW_FORMAT_VERSION 3 /* 3: t_cage; 2: checksums (1: none); older ones still read */

void sw_result_blank(sw_result *r, long index)
{
    memset(r, 0, sizeof *r);
    r->index = index;
    r->status = SW_NOT_RUN;
    r->verdict = -1;
    r->t_capture = r->t_escape = r->t_cage = r->peak_fn = r->peak_tau = r->epsilon = NAN;
    r->offset[0] = r->offset[1] = r->offset[2] = NAN;
    r->fn_step_max = r->t_final = r->wall = NAN;
    r->nrhs = r->nsteps = r->nevents = -1;
    r->n_stick = r->n_slip = -1;
}

/* ---- the checksum ------------------------------------------------------------ */
/* HDF5 checks no raw data (and, in the 1.8 file format the summary uses,
 * not every header): a flipped bit in a value would be read back as another
 * value. The summary carries its own checksum: FNV-1a (64 bit) over the
 * name and the value of every attribute and dataset in the order they are
 * written (numbers as the 8 bytes of their long long or double in memory,
 * strings with their terminating zero), stored as the root attribute
 * "checksum"; /timing has its own, so that the root one is the same for
 * any -j. FNV-1a maps each byte through a bijection of its 64-bit state,
 * so a change of any one byte always changes it (docs/sweep.md). */
#define DG_INIT 0xcbf29ce484222325ULL
static void dg_bytes(unsigned long long *h, const void *v, size_t n)
{
    const unsigned char *b = v;
    size_t i;
    if (!h) return;
    for (i = 0; i < n; i++) {
        *h ^= b[i];
        *h *= 0x100000001b3ULL;
    }
}
static void dg_str(unsigned long long *h, const char *s) { dg_bytes(h, s ? s : "", strlen(s ? s : "") + 1); }

/* ---- writing -------------------------------------------------------------- */

static hid_t str_type(void)
{
    hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, H5T_VARIABLE);
    H5Tset_cset(t, H5T_CSET_UTF8);
    return t;
}

static int attr_str(hid_t loc, const char *name, const char *v, unsigned long long *h)
{
    hid_t t = str_type(), s = H5Screate(H5S_SCALAR), a;
    int rc = -1;
    dg_str(h, name);
    dg_str(h, v);
    a = H5Acreate2(loc, name, t, s, H5P_DEFAULT, H5P_DEFAULT);
    if (a >= 0) {
        rc = H5Awrite(a, t, &v) < 0 ? -1 : 0;
        H5Aclose(a);
    }
    H5Sclose(s);
    H5Tclose(t);
    return rc;
}

static int attr_num(hid_t loc, const char *name, hid_t mem, hid_t file, const void *v)
{
    hid_t s = H5Screate(H5S_SCALAR), a;
    int rc = -1;
    a = H5Acreate2(loc, name, file, s, H5P_DEFAULT, H5P_DEFAULT);
    if (a >= 0) {
        rc = H5Awrite(a, mem, v) < 0 ? -1 : 0;
        H5Aclose(a);
    }
    H5Sclose(s);
    return rc;
}
static int attr_d(hid_t loc, const char *name, double v, unsigned long long *h)
{
    dg_str(h, name);
    dg_bytes(h, &v, sizeof v);
    return attr_num(loc, name, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, &v);
}
static int attr_l(hid_t loc, const char *name, long v, unsigned long long *h)
{
    long long x = v;
    dg_str(h, name);
    dg_bytes(h, &x, sizeof x);
    return attr_num(loc, name, H5T_NATIVE_LLONG, H5T_STD_I64LE, &x);
}

/* a dataset of rank 1 or 2 (cols 0: rank 1), no time stamps */
static int dset(hid_t loc, const char *name, hid_t mem, hid_t file, long rows, int cols, const void *data,
                const char *units, unsigned long long *h)
{
    hsize_t dims[2];
    hid_t s, d, dcpl = H5Pcreate(H5P_DATASET_CREATE);
    int rc = -1;
    dims[0] = (hsize_t)rows;
    dims[1] = (hsize_t)cols;
    if (h && H5Tget_class(mem) != H5T_STRING) { /* numbers: 8 bytes each; strings: dset_str */
        dg_str(h, name);
        dg_bytes(h, data, 8 * (size_t)rows * (size_t)(cols ? cols : 1));
    }
    H5Pset_obj_track_times(dcpl, 0);
    s = H5Screate_simple(cols ? 2 : 1, dims, NULL);
    d = H5Dcreate2(loc, name, file, s, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    if (d >= 0) {
        rc = rows == 0 || H5Dwrite(d, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0 ? 0 : -1;
        if (rc == 0 && units) rc = attr_str(d, "units", units, NULL);
        H5Dclose(d);
    }
    H5Sclose(s);
    H5Pclose(dcpl);
    return rc;
}

static int dset_str(hid_t loc, const char *name, long rows, int cols, const char *const *v, unsigned long long *h)
{
    hid_t t = str_type();
    size_t i;
    int rc;
    dg_str(h, name);
    for (i = 0; i < (size_t)rows * (size_t)(cols ? cols : 1); i++) dg_str(h, v[i]);
    rc = dset(loc, name, t, t, rows, cols, v, NULL, NULL);
    H5Tclose(t);
    return rc;
}

static hid_t group(hid_t loc, const char *name)
{
    hid_t gcpl = H5Pcreate(H5P_GROUP_CREATE), g;
    H5Pset_obj_track_times(gcpl, 0);
    g = H5Gcreate2(loc, name, H5P_DEFAULT, gcpl, H5P_DEFAULT);
    H5Pclose(gcpl);
    return g;
}

/* The result columns, shared by the writer and the reader: name, field,
 * units (NULL: none), the first format_version that has it (0: all). A
 * summary older than a column's version has no such dataset: it reads as
 * NaN and is left out of the checksum, as it was when written. */
typedef struct {
    const char *name;
    size_t off;
    const char *units;
    int since;
} sw_col;
static const sw_col dcols[] = {
    {"t_capture", offsetof(sw_result, t_capture), "s", 0}, {"t_escape", offsetof(sw_result, t_escape), "s", 0},
    {"peak_fn", offsetof(sw_result, peak_fn), "N", 0},     {"peak_tau", offsetof(sw_result, peak_tau), "N m", 0},
    {"epsilon", offsetof(sw_result, epsilon), NULL, 0},    {"fn_step_max", offsetof(sw_result, fn_step_max), "N", 0},
    {"t_final", offsetof(sw_result, t_final), "s", 0},       {"t_cage", offsetof(sw_result, t_cage), "s", 3},
};
/* integer columns: int fields (4 bytes) stored as int32, long fields as int64 */
static const sw_col icols[] = {
    {"status", offsetof(sw_result, status), NULL, 0},  {"verdict", offsetof(sw_result, verdict), NULL, 0},
    {"n_stick", offsetof(sw_result, n_stick), NULL, 0}, {"n_slip", offsetof(sw_result, n_slip), NULL, 0},
};
static const sw_col lcols[] = {
    {"stats_rhs", offsetof(sw_result, nrhs), NULL, 0},
    {"stats_steps", offsetof(sw_result, nsteps), NULL, 0},
    {"events", offsetof(sw_result, nevents), NULL, 0},
};
#define NCOL(a) (sizeof a / sizeof a[0])

/* /region (sw_region) of a grid over two ranges; nothing otherwise. */
static int write_region(hid_t f, const sw_meta *meta, const sw_plan *p, const sw_result *res, unsigned long long *h)
{
    long nslice = sw_region(p, res, meta->length, NULL, NULL, NULL), s;
    int rc = 0;
    hid_t g;
    if (nslice > 0) {
        double *area = malloc(sizeof(double) * (size_t)nslice);
        long *ncap = malloc(sizeof(long) * (size_t)nslice);
        char *lab = malloc((size_t)nslice * SW_LABEL);
        const char **labp = malloc(sizeof *labp * (size_t)nslice);
        if (area && ncap && lab && labp && (g = group(f, "region")) >= 0) {
            long long *lc = malloc(sizeof(long long) * (size_t)nslice);
            sw_region(p, res, meta->length, area, ncap, lab);
            for (s = 0; s < nslice; s++) labp[s] = lab + s * SW_LABEL;
            rc |= dset_str(g, "slice", nslice, 0, labp, h);
            rc |= dset(g, "area", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, nslice, 0, area,
                       meta->length > 0 ? "1 (m^2 / length^2)" : "m^2", h);
            if (lc) {
                for (s = 0; s < nslice; s++) lc[s] = ncap[s];
                rc |= dset(g, "captured", H5T_NATIVE_LLONG, H5T_STD_I64LE, nslice, 0, lc, NULL, h);
                free(lc);
            } else
                rc = -1;
            H5Gclose(g);
        } else
            rc = -1;
        free(area);
        free(ncap);
        free(lab);
        free(labp);
    }
    return rc;
}

/* /mc: the draws per cell, the number of --vary keys, and per grid cell
 * (C order of the --vary keys) the capture probability, its Wilson 95 %
 * interval and the figures of merit's mean and 10/50/90 % quantiles. */
static int write_mc(hid_t f, const sw_plan *p, const sw_result *res)
{
    long nc = p->ncell, c;
    int rc = 0, q;
    sw_cell *cell = malloc(sizeof *cell * (size_t)(nc + 1));
    double *d = malloc(sizeof(double) * (size_t)(nc + 1));
    long long *l = malloc(sizeof(long long) * (size_t)(nc + 1) * 8);
    hid_t g;
    static const struct {
        const char *name, *units;
        size_t off;
    } dc[] = {
        {"p_capture", NULL, offsetof(sw_cell, p)},       {"p_low", NULL, offsetof(sw_cell, lo)},
        {"p_high", NULL, offsetof(sw_cell, hi)},         {"t_capture_mean", "s", offsetof(sw_cell, t_mean)},
        {"t_capture_p10", "s", offsetof(sw_cell, t_p10)}, {"t_capture_p50", "s", offsetof(sw_cell, t_p50)},
        {"t_capture_p90", "s", offsetof(sw_cell, t_p90)}, {"peak_fn_mean", "N", offsetof(sw_cell, f_mean)},
        {"peak_fn_p10", "N", offsetof(sw_cell, f_p10)},   {"peak_fn_p50", "N", offsetof(sw_cell, f_p50)},
        {"peak_fn_p90", "N", offsetof(sw_cell, f_p90)},   {"epsilon_mean", NULL, offsetof(sw_cell, e_mean)},
        {"epsilon_p10", NULL, offsetof(sw_cell, e_p10)},  {"epsilon_p50", NULL, offsetof(sw_cell, e_p50)},
        {"epsilon_p90", NULL, offsetof(sw_cell, e_p90)},
    };
    if (!cell || !d || !l || sw_mc_cells(p, res, cell) != 0 || (g = group(f, "mc")) < 0) {
        free(cell);
        free(d);
        free(l);
        return -1;
    }
    rc |= attr_l(g, "draws_per_cell", p->mc, NULL);
    rc |= attr_l(g, "n_vary", p->nvary, NULL);
    rc |= attr_l(g, "n_cells", nc, NULL);
    rc |= attr_str(g, "generator", "gsl_rng_mt19937, seeded per variant from (seed, index) by splitmix64", NULL);
    for (c = 0; c < nc; c++) l[c] = cell[c].n;
    rc |= dset(g, "n", H5T_NATIVE_LLONG, H5T_STD_I64LE, nc, 0, l, NULL, NULL);
    for (c = 0; c < nc; c++) l[c] = cell[c].ncap;
    rc |= dset(g, "n_captured", H5T_NATIVE_LLONG, H5T_STD_I64LE, nc, 0, l, NULL, NULL);
    for (c = 0; c < nc; c++) l[c] = cell[c].nfail;
    rc |= dset(g, "n_failed", H5T_NATIVE_LLONG, H5T_STD_I64LE, nc, 0, l, NULL, NULL);
    for (c = 0; c < nc; c++)
        for (q = 0; q < 8; q++) l[c * 8 + q] = cell[c].nverdict[q];
    rc |= dset(g, "n_verdict", H5T_NATIVE_LLONG, H5T_STD_I64LE, nc, 8, l, NULL, NULL);
    for (q = 0; q < (int)(sizeof dc / sizeof dc[0]); q++) {
        for (c = 0; c < nc; c++) d[c] = *(const double *)((const char *)&cell[c] + dc[q].off);
        rc |= dset(g, dc[q].name, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, nc, 0, d, dc[q].units, NULL);
    }
    H5Gclose(g);
    free(cell);
    free(d);
    free(l);
    return rc;
}

/* Everything but the file's creation; 0, -1 (an HDF5 call failed: disk
 * full, quota, file size limit, I/O) or -2 (out of memory). */
static int write_body(hid_t f, const sw_meta *meta, const sw_plan *p, const sw_result *res, int jobs,
                      double total_wall)
{
    long n = p->nvar, i, nrun = 0, nfail = 0;
    int k, rc = 0;
    size_t c;
    double *dbuf = malloc(sizeof(double) * (size_t)(3 * n + 1));
    long long *lbuf = malloc(sizeof(long long) * (size_t)(n + 1));
    const char **names = NULL, **specs = NULL, **reasons = NULL;
    double *num = malloc(sizeof(double) * (size_t)(n * p->nkey + 1));
    hid_t g;
    unsigned long long h = DG_INIT, ht = DG_INIT;
    char sum[40];
    if (!dbuf || !lbuf || !num) {
        rc = -2; /* out of memory */
        goto out;
    }
    for (i = 0; i < n; i++) {
        if (res[i].status != SW_NOT_RUN) nrun++;
        if (res[i].status != SW_NOT_RUN && res[i].status != 0) nfail++;
    }
    rc |= attr_str(f, "format", SW_FORMAT, &h);
    rc |= attr_l(f, "format_version", SW_FORMAT_VERSION, &h);
    rc |= attr_str(f, "capdyn_version", cd_version(), &h);
    rc |= attr_str(f, "scenario", meta->scenario, &h);
    rc |= attr_str(f, "scenario_text", meta->scenario_text, &h);
    rc |= attr_str(f, "overrides", meta->overrides, &h);
    rc |= attr_str(f, "design", p->lhs ? "lhs" : "grid", &h);
    rc |= attr_l(f, "lhs_samples", p->lhs ? p->lhs_n : 0, &h);
    rc |= attr_l(f, "seed", (long)p->seed, &h);
    rc |= attr_l(f, "n_variants", n, &h);
    rc |= attr_l(f, "n_run", nrun, &h);
    rc |= attr_l(f, "n_failed", nfail, &h);
    rc |= attr_l(f, "complete", nrun == n, &h);
    rc |= attr_d(f, "length", meta->length, &h);
    rc |= attr_l(f, "until_verdict", meta->until_verdict, &h);

    names = malloc(sizeof *names * (size_t)p->nkey);
    specs = malloc(sizeof *specs * (size_t)p->nkey);
    reasons = malloc(sizeof *reasons * (size_t)(n + 1));
    if (!names || !specs || !reasons) {
        rc = -2;
        goto out;
    }
    for (k = 0; k < p->nkey; k++) {
        names[k] = p->key[k].key;
        specs[k] = p->key[k].spec;
    }
    rc |= dset_str(f, "param_names", p->nkey, 0, names, &h);
    rc |= dset_str(f, "param_specs", p->nkey, 0, specs, &h);
    rc |= dset_str(f, "param_values", n, p->nkey, (const char *const *)p->val, &h);
    for (i = 0; i < n * p->nkey; i++)
        if (cli_number(p->val[i], &num[i]) != 0) num[i] = NAN;
    rc |= dset(f, "param_numeric", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, n, p->nkey, num, NULL, &h);

    for (c = 0; c < NCOL(icols); c++) {
        for (i = 0; i < n; i++) lbuf[i] = *(const int *)((const char *)&res[i] + icols[c].off);
        rc |= dset(f, icols[c].name, H5T_NATIVE_LLONG, c == 1 ? H5T_STD_I8LE : H5T_STD_I32LE, n, 0, lbuf, NULL, &h);
    }
    for (c = 0; c < NCOL(lcols); c++) {
        for (i = 0; i < n; i++) lbuf[i] = *(const long *)((const char *)&res[i] + lcols[c].off);
        rc |= dset(f, lcols[c].name, H5T_NATIVE_LLONG, H5T_STD_I64LE, n, 0, lbuf, NULL, &h);
    }
    for (c = 0; c < NCOL(dcols); c++) {
        for (i = 0; i < n; i++) dbuf[i] = *(const double *)((const char *)&res[i] + dcols[c].off);
        rc |= dset(f, dcols[c].name, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, n, 0, dbuf, dcols[c].units, &h);
    }
    for (i = 0; i < n; i++) reasons[i] = res[i].reason;
    rc |= dset_str(f, "failure", n, 0, reasons, &h);
    for (i = 0; i < n; i++) memcpy(dbuf + 3 * i, res[i].offset, sizeof res[i].offset);
    rc |= dset(f, "offset", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, n, 3, dbuf, "m", &h);

    /* the graspable region of each slice of a grid over two ranges */
    rc |= write_region(f, meta, p, res, &h);
    /* a Monte Carlo sweep's per-cell probabilities (derived from the rows
     * above, outside the checksum) */
    if (p->mc > 0) rc |= write_mc(f, p, res);

    /* what differs between runs of the same sweep */
    g = group(f, "timing");
    if (g >= 0) {
        for (i = 0; i < n; i++) dbuf[i] = res[i].wall;
        rc |= dset(g, "wall", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, n, 0, dbuf, "s", &ht);
        rc |= attr_l(g, "jobs", jobs, &ht);
        rc |= attr_d(g, "total_wall", total_wall, &ht);
        snprintf(sum, sizeof sum, "fnv1a64:%016llx", ht);
        rc |= attr_str(g, "checksum", sum, NULL);
        H5Gclose(g);
    } else
        rc = -1;
    snprintf(sum, sizeof sum, "fnv1a64:%016llx", h);
    rc |= attr_str(f, "checksum", sum, NULL);
out:
    free(dbuf);
    free(lbuf);
    free(num);
    free(names);
    free(specs);
    free(reasons);
    return rc;
}

/* ---- where the summary goes ------------------------------------------------ */

static int same_file(const struct stat *a, const struct stat *b) { return a->st_dev == b->st_dev && a->st_ino == b->st_ino; }

int sw_out_open(sw_out *out, const char *path, const char *const *input, int ninput, char *msg, size_t len)
{
    struct stat st, si;
    int i;
    out->path = out->target = NULL;
    out->lock_fd = -1;
    if (lstat(path, &st) == 0 && S_ISLNK(st.st_mode)) {
        out->target = realpath(path, NULL);
        if (!out->target) {
            snprintf(msg, len, "cannot write the sweep summary '%s': it is a symbolic link to a missing file", path);
            return -1;
        }
    } else if ((out->target = malloc(strlen(path) + 1)) != NULL)
        strcpy(out->target, path);
    out->path = malloc(strlen(path) + 1);
    if (!out->target || !out->path) {
        sw_out_close(out);
        snprintf(msg, len, "out of memory");
        return -1;
    }
    strcpy(out->path, path);
    if (stat(out->target, &st) != 0) return 0; /* a new file */
    if (S_ISDIR(st.st_mode)) {
        snprintf(msg, len, "cannot write the sweep summary '%s': it is a directory", path);
        goto fail;
    }
    if (!S_ISREG(st.st_mode)) {
        snprintf(msg, len, "cannot write the sweep summary '%s': it exists and is not a regular file", path);
        goto fail;
    }
    for (i = 0; i < ninput; i++)
        if (input[i] && stat(input[i], &si) == 0 && same_file(&si, &st)) {
            snprintf(msg, len, "cannot write the sweep summary to '%s': it is the scenario file '%s' (choose another -o)",
                     path, input[i]);
            goto fail;
        }
    return 0;
fail:
    sw_out_close(out);
    return -1;
}

void sw_out_close(sw_out *out)
{
    if (out->lock_fd >= 0) close(out->lock_fd);
    out->lock_fd = -1;
    free(out->path);
    free(out->target);
    out->path = out->target = NULL;
}

/* The temporary file of the next write, created and flock'ed in the
 * target's directory (dir_fd locked by the caller); checks that the target
 * is still ours or free. Returns its descriptor, -1 with msg. */
static int claim_tmp(sw_out *out, char *tmp, size_t tlen, char *msg, size_t len)
{
    struct stat st, mine;
    const char *slash = strrchr(out->target, '/');
    int fd = -1, i;
    if (stat(out->target, &st) == 0) {
        if (!S_ISREG(st.st_mode)) {
            snprintf(msg, len, "cannot write the sweep summary '%s': it exists and is not a regular file", out->path);
            return -1;
        }
        if (out->lock_fd < 0 || fstat(out->lock_fd, &mine) != 0 || !same_file(&mine, &st)) {
            int probe = open(out->target, O_RDONLY | O_NOCTTY | O_CLOEXEC);
            if (probe >= 0) {
                int busy = flock(probe, LOCK_EX | LOCK_NB) != 0 && errno == EWOULDBLOCK;
                close(probe);
                if (busy) {
                    snprintf(msg, len,
                             "cannot write the sweep summary '%s': another capdyn process is writing it (the file is "
                             "locked); choose another -o or wait for it to end",
                             out->path);
                    return -1;
                }
            }
        }
    }
    for (i = 0; i < 100; i++) {
        if (slash)
            snprintf(tmp, tlen, "%.*s/.%s.tmp-%ld-%d", (int)(slash - out->target), out->target, slash + 1,
                     (long)getpid(), i);
        else
            snprintf(tmp, tlen, ".%s.tmp-%ld-%d", out->target, (long)getpid(), i);
        fd = open(tmp, O_RDWR | O_CREAT | O_EXCL | O_NOCTTY | O_CLOEXEC, 0666);
        if (fd >= 0 || errno != EEXIST) break;
    }
    if (fd < 0) {
        snprintf(msg, len, "cannot write the sweep summary '%s': creating a temporary file in its directory: %s",
                 out->path, strerror(errno));
        return -1;
    }
    (void)flock(fd, LOCK_EX | LOCK_NB);
    return fd;
}

int sw_summary_write(sw_out *out, const sw_meta *meta, const sw_plan *p, const sw_result *res, int jobs,
                     double total_wall, char *msg, size_t len)
{
    size_t n = strlen(out->target);
    char *tmp = malloc(n + 64), *dcopy = malloc(n + 1);
    hid_t fapl, fcpl, f;
    int rc, dir_fd, fd;
    if (!tmp || !dcopy) {
        free(tmp);
        free(dcopy);
        snprintf(msg, len, "writing the sweep summary '%s': out of memory", out->path);
        return -1;
    }
    strcpy(dcopy, out->target);
    dir_fd = open(dirname(dcopy), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    free(dcopy);
    if (dir_fd < 0) {
        snprintf(msg, len, "cannot write the sweep summary '%s': %s", out->path, strerror(errno));
        free(tmp);
        return -1;
    }
    (void)flock(dir_fd, LOCK_EX); /* best effort: not every file system has it */
    fd = claim_tmp(out, tmp, n + 64, msg, len);
    if (fd < 0) {
        close(dir_fd);
        free(tmp);
        return -1;
    }
    fapl = H5Pcreate(H5P_FILE_ACCESS);
    fcpl = H5Pcreate(H5P_FILE_CREATE);
    H5Pset_file_locking(fapl, 0, 1);
    H5Pset_obj_track_times(fcpl, 0);
    H5E_BEGIN_TRY { f = H5Fcreate(tmp, H5F_ACC_TRUNC, fcpl, fapl); } H5E_END_TRY;
    H5Pclose(fapl);
    H5Pclose(fcpl);
    if (f < 0) {
        snprintf(msg, len, "cannot create the sweep summary '%s' (temporary '%s')", out->path, tmp);
        rc = -1;
        goto out;
    }
    H5E_BEGIN_TRY { rc = write_body(f, meta, p, res, jobs, total_wall); } H5E_END_TRY;
    H5E_BEGIN_TRY { /* a failed flush (disk full) prints pages of diagnostics otherwise */
        if (H5Fclose(f) < 0 && rc == 0) rc = -1;
    } H5E_END_TRY;
    if (rc == -2)
        snprintf(msg, len, "writing the sweep summary '%s': out of memory; '%s' is left as it was", out->path,
                 out->path);
    else if (rc != 0)
        snprintf(msg, len,
                 "writing the sweep summary '%s' failed (disk full, quota, file size limit or I/O error); '%s' is "
                 "left as it was",
                 out->path, out->path);
    else if (rename(tmp, out->target) != 0) {
        snprintf(msg, len, "cannot rename '%s' onto the sweep summary '%s': %s", tmp, out->path, strerror(errno));
        rc = -1;
    }
out:
    if (rc != 0) {
        unlink(tmp);
        close(fd);
    } else { /* the new summary is ours, the old one is gone */
        if (out->lock_fd >= 0) close(out->lock_fd);
        out->lock_fd = fd;
    }
    close(dir_fd);
    free(tmp);
    return rc == 0 ? 0 : -1;
}

/* ---- reading -------------------------------------------------------------- */

static hid_t open_ro(const char *path)
{
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS), f;
    H5Pset_file_locking(fapl, 0, 1);
    H5E_BEGIN_TRY { f = H5Fopen(path, H5F_ACC_RDONLY, fapl); } H5E_END_TRY;
    H5Pclose(fapl);
    return f;
}

/* a scalar string attribute, malloc'd (NULL if absent) */
static char *read_attr_str(hid_t loc, const char *name)
{
    hid_t a, t, mt;
    char *v = NULL, *out = NULL;
    H5E_BEGIN_TRY { a = H5Aopen(loc, name, H5P_DEFAULT); } H5E_END_TRY;
    if (a < 0) return NULL;
    t = H5Aget_type(a);
    if (H5Tget_class(t) == H5T_STRING && H5Tis_variable_str(t) > 0) {
        mt = str_type();
        if (H5Aread(a, mt, &v) >= 0 && v) {
            out = malloc(strlen(v) + 1);
            if (out) strcpy(out, v);
            H5free_memory(v);
        }
        H5Tclose(mt);
    }
    H5Tclose(t);
    H5Aclose(a);
    return out;
}

static int read_attr_num(hid_t loc, const char *name, hid_t mem, void *v)
{
    hid_t a;
    int rc;
    H5E_BEGIN_TRY { a = H5Aopen(loc, name, H5P_DEFAULT); } H5E_END_TRY;
    if (a < 0) return -1;
    H5E_BEGIN_TRY { rc = H5Aread(a, mem, v) < 0 ? -1 : 0; } H5E_END_TRY;
    H5Aclose(a);
    return rc;
}

/* a dataset of exactly rows x cols (cols 0: rank 1) elements, read as mem */
static int read_ds(hid_t loc, const char *name, hid_t mem, long rows, int cols, void *buf)
{
    hid_t d, s;
    hsize_t dims[2] = {0, 0};
    int rank, rc = -1;
    H5E_BEGIN_TRY { d = H5Dopen2(loc, name, H5P_DEFAULT); } H5E_END_TRY;
    if (d < 0) return -1;
    s = H5Dget_space(d);
    rank = H5Sget_simple_extent_ndims(s);
    if (rank == (cols ? 2 : 1) && H5Sget_simple_extent_dims(s, dims, NULL) == rank && dims[0] == (hsize_t)rows &&
        (!cols || dims[1] == (hsize_t)cols)) {
        if (rows == 0) rc = 0;
        else H5E_BEGIN_TRY { rc = H5Dread(d, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) < 0 ? -1 : 0; } H5E_END_TRY;
    }
    H5Sclose(s);
    H5Dclose(d);
    return rc;
}

/* rows x cols variable-length strings (malloc'd array of H5-owned strings:
 * free with free_strs) */
static char **read_strs(hid_t loc, const char *name, long rows, int cols)
{
    size_t n = (size_t)rows * (size_t)(cols ? cols : 1);
    char **v = calloc(n + 1, sizeof *v);
    hid_t t = str_type();
    if (v && read_ds(loc, name, t, rows, cols, v) != 0) {
        free(v);
        v = NULL;
    }
    H5Tclose(t);
    return v;
}
static void free_strs(char **v, size_t n)
{
    size_t i;
    if (!v) return;
    for (i = 0; i < n; i++) H5free_memory(v[i]);
    free(v);
}

static int same(const char *a, const char *b) { return a && b && strcmp(a, b) == 0; }

/* rows x cols of a dataset's extent (cols 0: rank 1); -1 if absent or of
 * another rank */
static long ds_extent(hid_t loc, const char *name, int want_rank, long *cols)
{
    hid_t d, s;
    hsize_t dims[2] = {0, 0};
    long n = -1;
    H5E_BEGIN_TRY { d = H5Dopen2(loc, name, H5P_DEFAULT); } H5E_END_TRY;
    if (d < 0) return -1;
    s = H5Dget_space(d);
    if (s >= 0 && H5Sget_simple_extent_ndims(s) == want_rank && H5Sget_simple_extent_dims(s, dims, NULL) == want_rank &&
        dims[0] <= (hsize_t)SW_MAX_VARIANTS && dims[1] <= (hsize_t)SW_MAX_VARIANTS) {
        n = (long)dims[0];
        if (cols) *cols = (long)dims[1];
    }
    if (s >= 0) H5Sclose(s);
    H5Dclose(d);
    return n;
}

/* strings read back by HDF5 into a malloc'd copy (NULL entries as "") */
static char **own_strs(char **v, size_t n)
{
    char **o = v ? calloc(n + 1, sizeof *o) : NULL;
    size_t i;
    int ok = o != NULL;
    for (i = 0; ok && i < n; i++) {
        const char *x = v[i] ? v[i] : "";
        if ((o[i] = malloc(strlen(x) + 1)) != NULL) strcpy(o[i], x);
        else ok = 0;
    }
    free_strs(v, v ? n : 0);
    if (!ok && o) {
        for (i = 0; i < n; i++) free(o[i]);
        free(o);
        o = NULL;
    }
    return o;
}
static void free_own(char **v, size_t n)
{
    size_t i;
    if (!v) return;
    for (i = 0; i < n; i++) free(v[i]);
    free(v);
}

void sw_summary_free(sw_summary *s)
{
    free(s->capdyn_version);
    free(s->scenario);
    free(s->scenario_text);
    free(s->overrides);
    free(s->design);
    free_own(s->names, (size_t)s->nkey);
    free_own(s->specs, (size_t)s->nkey);
    free_own(s->vals, (size_t)(s->nvar * s->nkey));
    free(s->num);
    free(s->res);
    free_own(s->slice, (size_t)s->nslice);
    free(s->area);
    free(s->captured);
    memset(s, 0, sizeof *s);
}

/* The checksums of what was read, in the order sw_summary_write feeds them. */
static void digest(const sw_summary *s, unsigned long long *h, unsigned long long *ht)
{
    long i, n = (long)s->nvar;
    size_t c;
    long long x;
    double d;
    *h = *ht = DG_INIT;
#define DG_L(name, v) (dg_str(h, name), x = (v), dg_bytes(h, &x, 8))
    dg_str(h, "format");
    dg_str(h, SW_FORMAT);
    DG_L("format_version", s->version);
    dg_str(h, "capdyn_version");
    dg_str(h, s->capdyn_version);
    dg_str(h, "scenario");
    dg_str(h, s->scenario);
    dg_str(h, "scenario_text");
    dg_str(h, s->scenario_text);
    dg_str(h, "overrides");
    dg_str(h, s->overrides);
    dg_str(h, "design");
    dg_str(h, s->design);
    DG_L("lhs_samples", s->lhs_samples);
    DG_L("seed", s->seed);
    DG_L("n_variants", s->nvar);
    DG_L("n_run", s->nrun);
    DG_L("n_failed", s->nfail);
    DG_L("complete", s->complete);
    dg_str(h, "length");
    dg_bytes(h, &s->length, 8);
    DG_L("until_verdict", s->until_verdict);
    dg_str(h, "param_names");
    for (i = 0; i < s->nkey; i++) dg_str(h, s->names[i]);
    dg_str(h, "param_specs");
    for (i = 0; i < s->nkey; i++) dg_str(h, s->specs[i]);
    dg_str(h, "param_values");
    for (i = 0; i < n * s->nkey; i++) dg_str(h, s->vals[i]);
    dg_str(h, "param_numeric");
    dg_bytes(h, s->num, 8 * (size_t)(n * s->nkey));
    for (c = 0; c < NCOL(icols); c++) {
        dg_str(h, icols[c].name);
        for (i = 0; i < n; i++) {
            x = *(const int *)((const char *)&s->res[i] + icols[c].off);
            dg_bytes(h, &x, 8);
        }
    }
    for (c = 0; c < NCOL(lcols); c++) {
        dg_str(h, lcols[c].name);
        for (i = 0; i < n; i++) {
            x = *(const long *)((const char *)&s->res[i] + lcols[c].off);
            dg_bytes(h, &x, 8);
        }
    }
    for (c = 0; c < NCOL(dcols); c++) {
        if (s->version < dcols[c].since) continue;
        dg_str(h, dcols[c].name);
        for (i = 0; i < n; i++) dg_bytes(h, (const char *)&s->res[i] + dcols[c].off, 8);
    }
    dg_str(h, "failure");
    for (i = 0; i < n; i++) dg_str(h, s->res[i].reason);
    dg_str(h, "offset");
    for (i = 0; i < n; i++) dg_bytes(h, s->res[i].offset, 24);
    if (s->nslice > 0) {
        dg_str(h, "slice");
        for (i = 0; i < s->nslice; i++) dg_str(h, s->slice[i]);
        dg_str(h, "area");
        dg_bytes(h, s->area, 8 * (size_t)s->nslice);
        dg_str(h, "captured");
        dg_bytes(h, s->captured, 8 * (size_t)s->nslice);
    }
    dg_str(ht, "wall");
    for (i = 0; i < n; i++) dg_bytes(ht, &s->res[i].wall, 8);
    dg_str(ht, "jobs");
    dg_bytes(ht, &s->jobs, 8);
    dg_str(ht, "total_wall");
    d = s->total_wall;
    dg_bytes(ht, &d, 8);
#undef DG_L
}

/* the string attribute name of loc into *v; 0 or -1 */
static int need_str(hid_t loc, const char *name, char **v)
{
    *v = read_attr_str(loc, name);
    return *v ? 0 : -1;
}

static int load_body(hid_t f, const char *path, sw_summary *s, char *msg, size_t len)
{
    long n, nk, c2 = 0, i;
    size_t c;
    double *dbuf = NULL;
    long long *lbuf = NULL;
    char *fmt = read_attr_str(f, "format"), *sum = NULL, *sumt = NULL, want[40];
    struct stat st;
    unsigned long long h, ht;
    hid_t g;
    int rc = -1;
#define BAD(...)                                                                                                   \
    do {                                                                                                           \
        snprintf(msg, len, __VA_ARGS__);                                                                           \
        goto out;                                                                                                  \
    } while (0)
    if (!same(fmt, SW_FORMAT)) BAD("'%s' is not a capdyn sweep summary (attribute 'format' is not \"%s\")", path, SW_FORMAT);
    if (read_attr_num(f, "format_version", H5T_NATIVE_LLONG, &s->version) != 0 || s->version < 1 ||
        s->version > SW_FORMAT_VERSION)
        BAD("'%s': format_version %lld is not one this capdyn reads (1 to %d)", path, s->version, SW_FORMAT_VERSION);
    if (need_str(f, "capdyn_version", &s->capdyn_version) || need_str(f, "scenario", &s->scenario) ||
        need_str(f, "scenario_text", &s->scenario_text) || need_str(f, "overrides", &s->overrides) ||
        need_str(f, "design", &s->design) || read_attr_num(f, "lhs_samples", H5T_NATIVE_LLONG, &s->lhs_samples) ||
        read_attr_num(f, "seed", H5T_NATIVE_LLONG, &s->seed) ||
        read_attr_num(f, "n_variants", H5T_NATIVE_LLONG, &s->nvar) ||
        read_attr_num(f, "n_run", H5T_NATIVE_LLONG, &s->nrun) ||
        read_attr_num(f, "n_failed", H5T_NATIVE_LLONG, &s->nfail) ||
        read_attr_num(f, "complete", H5T_NATIVE_LLONG, &s->complete) ||
        read_attr_num(f, "length", H5T_NATIVE_DOUBLE, &s->length) ||
        read_attr_num(f, "until_verdict", H5T_NATIVE_LLONG, &s->until_verdict))
        BAD("'%s': a root attribute of the summary is missing or unreadable (damaged file)", path);
    /* sizes before any allocation: each variant takes at least the 8 bytes
     * of its t_final in the file */
    nk = ds_extent(f, "param_names", 1, NULL);
    n = ds_extent(f, "status", 1, NULL);
    if (nk < 1 || nk > SW_MAX_KEYS || n < 0 || s->nvar != n || stat(path, &st) != 0 ||
        (double)n * 8.0 > (double)st.st_size || ds_extent(f, "param_values", 2, &c2) != n || c2 != nk)
        BAD("'%s': the sizes of the summary disagree (%lld variants, %ld rows, %ld keys; damaged file)", path, s->nvar,
            n, nk);
    s->nkey = (int)nk;
    s->names = own_strs(read_strs(f, "param_names", nk, 0), (size_t)nk);
    s->specs = own_strs(read_strs(f, "param_specs", nk, 0), (size_t)nk);
    s->vals = own_strs(read_strs(f, "param_values", n, (int)nk), (size_t)(n * nk));
    s->num = malloc(sizeof(double) * (size_t)(n * nk + 1));
    s->res = malloc(sizeof *s->res * (size_t)(n + 1));
    dbuf = malloc(sizeof(double) * (size_t)(3 * n + 1));
    lbuf = malloc(sizeof(long long) * (size_t)(n + 1));
    if (!s->names || !s->specs || !s->vals || !s->num || !s->res || !dbuf || !lbuf ||
        read_ds(f, "param_numeric", H5T_NATIVE_DOUBLE, n, (int)nk, s->num))
        BAD("'%s': cannot read the swept values (damaged file, or out of memory)", path);
    for (i = 0; i < n; i++) sw_result_blank(&s->res[i], i);
    for (c = 0; c < NCOL(icols) + NCOL(lcols) + NCOL(dcols); c++) {
        int isd = c >= NCOL(icols) + NCOL(lcols), isl = !isd && c >= NCOL(icols);
        const sw_col *col = isd ? &dcols[c - NCOL(icols) - NCOL(lcols)] : isl ? &lcols[c - NCOL(icols)] : &icols[c];
        if (s->version < col->since) continue; /* not in this summary: NaN (sw_result_blank) */
        if (read_ds(f, col->name, isd ? H5T_NATIVE_DOUBLE : H5T_NATIVE_LLONG, n, 0, isd ? (void *)dbuf : (void *)lbuf))
            BAD("'%s': cannot read the dataset '%s' (damaged file)", path, col->name);
        for (i = 0; i < n; i++) {
            char *fp = (char *)&s->res[i] + col->off;
            if (isd) *(double *)fp = dbuf[i];
            else if (isl) *(long *)fp = (long)lbuf[i];
            else *(int *)fp = (int)lbuf[i];
        }
    }
    {
        char **why = read_strs(f, "failure", n, 0);
        if (!why) BAD("'%s': cannot read the dataset 'failure' (damaged file)", path);
        for (i = 0; i < n; i++) snprintf(s->res[i].reason, sizeof s->res[i].reason, "%s", why[i] ? why[i] : "");
        free_strs(why, (size_t)n);
    }
    if (read_ds(f, "offset", H5T_NATIVE_DOUBLE, n, 3, dbuf) != 0)
        BAD("'%s': cannot read the dataset 'offset' (damaged file)", path);
    for (i = 0; i < n; i++) memcpy(s->res[i].offset, dbuf + 3 * i, sizeof s->res[i].offset);
    H5E_BEGIN_TRY { g = H5Gopen2(f, "region", H5P_DEFAULT); } H5E_END_TRY;
    if (g >= 0) {
        long ns = ds_extent(g, "slice", 1, NULL);
        if (ns < 1 || ns > n) {
            H5Gclose(g);
            BAD("'%s': the region of the summary is damaged", path);
        }
        s->nslice = ns;
        s->slice = own_strs(read_strs(g, "slice", ns, 0), (size_t)ns);
        s->area = malloc(sizeof(double) * (size_t)ns);
        s->captured = malloc(sizeof(long long) * (size_t)ns);
        if (!s->slice || !s->area || !s->captured || read_ds(g, "area", H5T_NATIVE_DOUBLE, ns, 0, s->area) ||
            read_ds(g, "captured", H5T_NATIVE_LLONG, ns, 0, s->captured)) {
            H5Gclose(g);
            BAD("'%s': the region of the summary is damaged", path);
        }
        H5Gclose(g);
    }
    s->mc = 0;
    s->nvary = s->nkey;
    H5E_BEGIN_TRY { g = H5Gopen2(f, "mc", H5P_DEFAULT); } H5E_END_TRY;
    if (g >= 0) {
        int bad_mc = read_attr_num(g, "draws_per_cell", H5T_NATIVE_LLONG, &s->mc) ||
                     read_attr_num(g, "n_vary", H5T_NATIVE_LLONG, &s->nvary) || s->mc < 1 || s->nvary < 0 ||
                     s->nvary > s->nkey;
        H5Gclose(g);
        if (bad_mc) BAD("'%s': the group /mc of the summary is damaged", path);
    }
    H5E_BEGIN_TRY { g = H5Gopen2(f, "timing", H5P_DEFAULT); } H5E_END_TRY;
    if (g < 0) BAD("'%s': the group /timing is missing (damaged file)", path);
    if (read_ds(g, "wall", H5T_NATIVE_DOUBLE, n, 0, dbuf) || read_attr_num(g, "jobs", H5T_NATIVE_LLONG, &s->jobs) ||
        read_attr_num(g, "total_wall", H5T_NATIVE_DOUBLE, &s->total_wall)) {
        H5Gclose(g);
        BAD("'%s': /timing is damaged", path);
    }
    for (i = 0; i < n; i++) s->res[i].wall = dbuf[i];
    sumt = read_attr_str(g, "checksum");
    H5Gclose(g);
    if (s->version >= 2) {
        digest(s, &h, &ht);
        sum = read_attr_str(f, "checksum");
        snprintf(want, sizeof want, "fnv1a64:%016llx", h);
        if (!same(sum, want))
            BAD("'%s': the checksum of the summary does not match its contents (the file is damaged)", path);
        snprintf(want, sizeof want, "fnv1a64:%016llx", ht);
        if (!same(sumt, want))
            BAD("'%s': the checksum of /timing does not match its contents (the file is damaged)", path);
    }
    rc = 0;
out:
#undef BAD
    free(fmt);
    free(sum);
    free(sumt);
    free(dbuf);
    free(lbuf);
    return rc;
}

int sw_summary_load(const char *path, sw_summary *s, char *msg, size_t len)
{
    hid_t f;
    int rc;
    memset(s, 0, sizeof *s);
    if (cli_regular_input(path, "sweep summary", msg, len) != 0) return -1;
    if (access(path, R_OK) != 0) {
        snprintf(msg, len, "cannot open the sweep summary '%s': %s", path, strerror(errno));
        return -1;
    }
    f = open_ro(path);
    if (f < 0) {
        snprintf(msg, len, "cannot open the sweep summary '%s': not an HDF5 file, or damaged", path);
        return -1;
    }
    H5E_BEGIN_TRY { rc = load_body(f, path, s, msg, len); } H5E_END_TRY;
    H5E_BEGIN_TRY { H5Fclose(f); } H5E_END_TRY;
    if (rc != 0) sw_summary_free(s);
    return rc;
}

/* ---- --resume ---------------------------------------------------------------- */

typedef struct {
    const char *path;
    const sw_meta *meta;
    const sw_plan *p;
    sw_result *res; /* shared with the parent */
} resume_job;

/* 0, or -1 with msg: is s the summary of the sweep (meta, p)? */
static int same_sweep(const sw_summary *s, const char *path, const sw_meta *meta, const sw_plan *p, char *msg,
                      size_t len)
{
    long i, n = p->nvar;
    int k;
    if (!same(s->scenario_text, meta->scenario_text)) {
        snprintf(msg, len, "--resume: '%s' was made from another scenario text than '%s' (start a new sweep)", path,
                 meta->scenario);
        return -1;
    }
    if (!same(s->overrides, meta->overrides)) {
        snprintf(msg, len, "--resume: '%s' was made with other --set overrides ('%s')", path, s->overrides);
        return -1;
    }
    if (s->until_verdict != meta->until_verdict) {
        snprintf(msg, len, "--resume: '%s' was made %s --until-verdict", path, s->until_verdict ? "with" : "without");
        return -1;
    }
    if (!same(s->design, p->lhs ? "lhs" : "grid") || s->nvar != n || (p->lhs && s->seed != (long long)p->seed)) {
        snprintf(msg, len, "--resume: '%s' holds a %s sweep of %lld variants (seed %lld), not this %s sweep of %ld",
                 path, s->design, s->nvar, s->seed, p->lhs ? "lhs" : "grid", n);
        return -1;
    }
    if (s->nkey != p->nkey) {
        snprintf(msg, len, "--resume: '%s' was made with other --vary keys (%d, not %d)", path, s->nkey, p->nkey);
        return -1;
    }
    for (k = 0; k < p->nkey; k++)
        if (!same(s->names[k], p->key[k].key)) {
            snprintf(msg, len, "--resume: '%s' varies '%s' as key %d, not '%s'", path, s->names[k], k + 1,
                     p->key[k].key);
            return -1;
        }
    for (i = 0; i < n * p->nkey; i++)
        if (!same(s->vals[i], p->val[i])) {
            snprintf(msg, len, "--resume: '%s': variant %ld has %s=%s, this sweep %s", path, i / p->nkey,
                     p->key[i % p->nkey].key, s->vals[i], p->val[i]);
            return -1;
        }
    return 0;
}

static int resume_child(void *arg)
{
    resume_job *j = arg;
    sw_summary s;
    char msg[2048];
    long i;
    if (sw_summary_load(j->path, &s, msg, sizeof msg) != 0) {
        cli_error("--resume: %s", msg);
        return CLI_FAIL;
    }
    if (same_sweep(&s, j->path, j->meta, j->p, msg, sizeof msg) != 0) {
        cli_error("%s", msg);
        sw_summary_free(&s);
        return CLI_FAIL;
    }
    for (i = 0; i < j->p->nvar; i++) {
        j->res[i] = s.res[i];
        j->res[i].index = i;
        if (j->res[i].status == SW_NOT_RUN) sw_result_blank(&j->res[i], i);
    }
    sw_summary_free(&s);
    return CLI_OK;
}

int sw_summary_resume(const char *path, const sw_meta *meta, const sw_plan *p, sw_result *res)
{
    size_t bytes = sizeof *res * (size_t)(p->nvar > 0 ? p->nvar : 1);
    sw_result *shared;
    resume_job j;
    int rc;
    char msg[1024];
    if (cli_regular_input(path, "sweep summary", msg, sizeof msg) != 0) {
        cli_error("--resume: %s", msg);
        return -1;
    }
    shared = mmap(NULL, bytes, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    if (shared == MAP_FAILED) {
        cli_error("--resume: reading '%s': out of memory", path);
        return -1;
    }
    j.path = path;
    j.meta = meta;
    j.p = p;
    j.res = shared;
    rc = cli_isolated(path, resume_child, &j);
    if (rc == CLI_OK) memcpy(res, shared, bytes);
    munmap(shared, bytes);
    return rc == CLI_OK ? 0 : -1;
}

