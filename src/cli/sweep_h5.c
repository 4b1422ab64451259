/* capdyn sweep: the summary file (HDF5, docs/sweep.md "Summary file").
 *
 * Written whole each time (at checkpoints, at an interruption, at the end)
 * under a temporary name in the target's directory and renamed onto it, so
 * the file on disk is always a complete summary of what had finished. The
 * rows are in variant order and every deterministic value is written from
 * the variants' results alone, so that the same sweep gives the same
 * summary for any -j or number of MPI ranks; wall times are in /timing
 * only. Objects are created without time stamps. */
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
#include <sys/stat.h>
#include <unistd.h>

#define SW_FORMAT "capdyn-sweep"
#define SW_FORMAT_VERSION 1

void sw_result_blank(sw_result *r, long index)
{
    memset(r, 0, sizeof *r);
    r->index = index;
    r->status = SW_NOT_RUN;
    r->verdict = -1;
    r->t_capture = r->t_escape = r->peak_fn = r->peak_tau = r->epsilon = NAN;
    r->offset[0] = r->offset[1] = r->offset[2] = NAN;
    r->fn_step_max = r->t_final = r->wall = NAN;
    r->nrhs = r->nsteps = r->nevents = -1;
    r->n_stick = r->n_slip = -1;
}

/* ---- writing -------------------------------------------------------------- */

static hid_t str_type(void)
{
    hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, H5T_VARIABLE);
    H5Tset_cset(t, H5T_CSET_UTF8);
    return t;
}

static int attr_str(hid_t loc, const char *name, const char *v)
{
    hid_t t = str_type(), s = H5Screate(H5S_SCALAR), a;
    int rc = -1;
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
static int attr_d(hid_t loc, const char *name, double v) { return attr_num(loc, name, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, &v); }
static int attr_l(hid_t loc, const char *name, long v)
{
    long long x = v;
    return attr_num(loc, name, H5T_NATIVE_LLONG, H5T_STD_I64LE, &x);
}

/* a dataset of rank 1 or 2 (cols 0: rank 1), no time stamps */
static int dset(hid_t loc, const char *name, hid_t mem, hid_t file, long rows, int cols, const void *data,
                const char *units)
{
    hsize_t dims[2];
    hid_t s, d, dcpl = H5Pcreate(H5P_DATASET_CREATE);
    int rc = -1;
    dims[0] = (hsize_t)rows;
    dims[1] = (hsize_t)cols;
    H5Pset_obj_track_times(dcpl, 0);
    s = H5Screate_simple(cols ? 2 : 1, dims, NULL);
    d = H5Dcreate2(loc, name, file, s, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    if (d >= 0) {
        rc = rows == 0 || H5Dwrite(d, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0 ? 0 : -1;
        if (rc == 0 && units) rc = attr_str(d, "units", units);
        H5Dclose(d);
    }
    H5Sclose(s);
    H5Pclose(dcpl);
    return rc;
}

static int dset_str(hid_t loc, const char *name, long rows, int cols, const char *const *v)
{
    hid_t t = str_type();
    int rc = dset(loc, name, t, t, rows, cols, v, NULL);
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
 * units (NULL: none). */
typedef struct {
    const char *name;
    size_t off;
    const char *units;
} sw_col;
static const sw_col dcols[] = {
    {"t_capture", offsetof(sw_result, t_capture), "s"}, {"t_escape", offsetof(sw_result, t_escape), "s"},
    {"peak_fn", offsetof(sw_result, peak_fn), "N"},     {"peak_tau", offsetof(sw_result, peak_tau), "N m"},
    {"epsilon", offsetof(sw_result, epsilon), NULL},    {"fn_step_max", offsetof(sw_result, fn_step_max), "N"},
    {"t_final", offsetof(sw_result, t_final), "s"},
};
/* integer columns: int fields (4 bytes) stored as int32, long fields as int64 */
static const sw_col icols[] = {
    {"status", offsetof(sw_result, status), NULL},  {"verdict", offsetof(sw_result, verdict), NULL},
    {"n_stick", offsetof(sw_result, n_stick), NULL}, {"n_slip", offsetof(sw_result, n_slip), NULL},
};
static const sw_col lcols[] = {
    {"stats_rhs", offsetof(sw_result, nrhs), NULL},
    {"stats_steps", offsetof(sw_result, nsteps), NULL},
    {"events", offsetof(sw_result, nevents), NULL},
};
#define NCOL(a) (sizeof a / sizeof a[0])

static int write_body(hid_t f, const sw_meta *meta, const sw_plan *p, const sw_result *res, int jobs,
                      double total_wall)
{
    long n = p->nvar, i, nrun = 0, nfail = 0, nslice, s;
    int k, rc = 0;
    size_t c;
    double *dbuf = malloc(sizeof(double) * (size_t)(3 * n + 1));
    long long *lbuf = malloc(sizeof(long long) * (size_t)(n + 1));
    const char **names = NULL, **specs = NULL, **reasons = NULL;
    double *num = malloc(sizeof(double) * (size_t)(n * p->nkey + 1));
    hid_t g;
    if (!dbuf || !lbuf || !num) {
        rc = -2; /* out of memory */
        goto out;
    }
    for (i = 0; i < n; i++) {
        if (res[i].status != SW_NOT_RUN) nrun++;
        if (res[i].status != SW_NOT_RUN && res[i].status != 0) nfail++;
    }
    rc |= attr_str(f, "format", SW_FORMAT);
    rc |= attr_l(f, "format_version", SW_FORMAT_VERSION);
    rc |= attr_str(f, "capdyn_version", cd_version());
    rc |= attr_str(f, "scenario", meta->scenario);
    rc |= attr_str(f, "scenario_text", meta->scenario_text);
    rc |= attr_str(f, "overrides", meta->overrides);
    rc |= attr_str(f, "design", p->lhs ? "lhs" : "grid");
    rc |= attr_l(f, "lhs_samples", p->lhs ? p->lhs_n : 0);
    rc |= attr_l(f, "seed", (long)p->seed);
    rc |= attr_l(f, "n_variants", n);
    rc |= attr_l(f, "n_run", nrun);
    rc |= attr_l(f, "n_failed", nfail);
    rc |= attr_l(f, "complete", nrun == n);
    rc |= attr_d(f, "length", meta->length);
    rc |= attr_l(f, "until_verdict", meta->until_verdict);

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
    rc |= dset_str(f, "param_names", p->nkey, 0, names);
    rc |= dset_str(f, "param_specs", p->nkey, 0, specs);
    rc |= dset_str(f, "param_values", n, p->nkey, (const char *const *)p->val);
    for (i = 0; i < n * p->nkey; i++)
        if (cli_number(p->val[i], &num[i]) != 0) num[i] = NAN;
    rc |= dset(f, "param_numeric", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, n, p->nkey, num, NULL);

    for (c = 0; c < NCOL(icols); c++) {
        for (i = 0; i < n; i++) lbuf[i] = *(const int *)((const char *)&res[i] + icols[c].off);
        rc |= dset(f, icols[c].name, H5T_NATIVE_LLONG, c == 1 ? H5T_STD_I8LE : H5T_STD_I32LE, n, 0, lbuf, NULL);
    }
    for (c = 0; c < NCOL(lcols); c++) {
        for (i = 0; i < n; i++) lbuf[i] = *(const long *)((const char *)&res[i] + lcols[c].off);
        rc |= dset(f, lcols[c].name, H5T_NATIVE_LLONG, H5T_STD_I64LE, n, 0, lbuf, NULL);
    }
    for (c = 0; c < NCOL(dcols); c++) {
        for (i = 0; i < n; i++) dbuf[i] = *(const double *)((const char *)&res[i] + dcols[c].off);
        rc |= dset(f, dcols[c].name, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, n, 0, dbuf, dcols[c].units);
    }
    for (i = 0; i < n; i++) reasons[i] = res[i].reason;
    rc |= dset_str(f, "failure", n, 0, reasons);
    for (i = 0; i < n; i++) memcpy(dbuf + 3 * i, res[i].offset, sizeof res[i].offset);
    rc |= dset(f, "offset", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, n, 3, dbuf, "m");

    /* the graspable region of each slice of a grid over two ranges */
    nslice = sw_region(p, res, meta->length, NULL, NULL, NULL);
    if (nslice > 0) {
        double *area = malloc(sizeof(double) * (size_t)nslice);
        long *ncap = malloc(sizeof(long) * (size_t)nslice);
        char *lab = malloc((size_t)nslice * SW_LABEL);
        const char **labp = malloc(sizeof *labp * (size_t)nslice);
        if (area && ncap && lab && labp && (g = group(f, "region")) >= 0) {
            long long *lc = malloc(sizeof(long long) * (size_t)nslice);
            sw_region(p, res, meta->length, area, ncap, lab);
            for (s = 0; s < nslice; s++) labp[s] = lab + s * SW_LABEL;
            rc |= dset_str(g, "slice", nslice, 0, labp);
            rc |= dset(g, "area", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, nslice, 0, area,
                       meta->length > 0 ? "1 (m^2 / length^2)" : "m^2");
            if (lc) {
                for (s = 0; s < nslice; s++) lc[s] = ncap[s];
                rc |= dset(g, "captured", H5T_NATIVE_LLONG, H5T_STD_I64LE, nslice, 0, lc, NULL);
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

    /* what differs between runs of the same sweep */
    g = group(f, "timing");
    if (g >= 0) {
        for (i = 0; i < n; i++) dbuf[i] = res[i].wall;
        rc |= dset(g, "wall", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, n, 0, dbuf, "s");
        rc |= attr_l(g, "jobs", jobs);
        rc |= attr_d(g, "total_wall", total_wall);
        H5Gclose(g);
    } else
        rc = -1;
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

int sw_summary_read(const char *path, const sw_meta *meta, const sw_plan *p, sw_result *res, char *msg, size_t len)
{
    hid_t f = open_ro(path);
    long n = p->nvar, i, nfile = -1;
    long long nv = -1;
    int k, rc = -1;
    size_t c;
    char *fmt = NULL, *text = NULL, *ov = NULL, *design = NULL, **names = NULL, **vals = NULL, **reasons = NULL;
    double *dbuf = NULL;
    long long *lbuf = NULL, seed = -1, uv = -1;
    if (f < 0) {
        snprintf(msg, len, "--resume: cannot open the sweep summary '%s'", path);
        return -1;
    }
    fmt = read_attr_str(f, "format");
    if (!same(fmt, SW_FORMAT)) {
        snprintf(msg, len, "--resume: '%s' is not a capdyn sweep summary (attribute 'format' is not \"%s\")", path,
                 SW_FORMAT);
        goto out;
    }
    text = read_attr_str(f, "scenario_text");
    ov = read_attr_str(f, "overrides");
    design = read_attr_str(f, "design");
    if (read_attr_num(f, "n_variants", H5T_NATIVE_LLONG, &nv) == 0) nfile = (long)nv;
    (void)read_attr_num(f, "seed", H5T_NATIVE_LLONG, &seed);
    if (!same(text, meta->scenario_text)) {
        snprintf(msg, len, "--resume: '%s' was made from another scenario text than '%s' (start a new sweep)", path,
                 meta->scenario);
        goto out;
    }
    if (!same(ov, meta->overrides)) {
        snprintf(msg, len, "--resume: '%s' was made with other --set overrides ('%s')", path, ov ? ov : "?");
        goto out;
    }
    if (read_attr_num(f, "until_verdict", H5T_NATIVE_LLONG, &uv) != 0 || uv != meta->until_verdict) {
        snprintf(msg, len, "--resume: '%s' was made %s --until-verdict", path, uv ? "with" : "without");
        goto out;
    }
    if (!same(design, p->lhs ? "lhs" : "grid") || nfile != n || (p->lhs && seed != (long long)p->seed)) {
        snprintf(msg, len, "--resume: '%s' holds a %s sweep of %ld variants (seed %lld), not this %s sweep of %ld",
                 path, design ? design : "?", nfile, seed, p->lhs ? "lhs" : "grid", n);
        goto out;
    }
    names = read_strs(f, "param_names", p->nkey, 0);
    vals = read_strs(f, "param_values", n, p->nkey);
    if (!names || !vals) {
        snprintf(msg, len, "--resume: '%s' was made with other --vary keys (%d expected)", path, p->nkey);
        goto out;
    }
    for (k = 0; k < p->nkey; k++)
        if (!same(names[k], p->key[k].key)) {
            snprintf(msg, len, "--resume: '%s' varies '%s' as key %d, not '%s'", path, names[k] ? names[k] : "?",
                     k + 1, p->key[k].key);
            goto out;
        }
    for (i = 0; i < n * p->nkey; i++)
        if (!same(vals[i], p->val[i])) {
            snprintf(msg, len, "--resume: '%s': variant %ld has %s=%s, this sweep %s", path, i / p->nkey,
                     p->key[i % p->nkey].key, vals[i] ? vals[i] : "?", p->val[i]);
            goto out;
        }
    dbuf = malloc(sizeof(double) * (size_t)(3 * n + 1));
    lbuf = malloc(sizeof(long long) * (size_t)(n + 1));
    reasons = read_strs(f, "failure", n, 0);
    if (!dbuf || !lbuf || !reasons) {
        snprintf(msg, len, "--resume: cannot read '%s' (failure)", path);
        goto out;
    }
    for (i = 0; i < n; i++) sw_result_blank(&res[i], i);
    for (c = 0; c < NCOL(icols) + NCOL(lcols) + NCOL(dcols); c++) {
        int isd = c >= NCOL(icols) + NCOL(lcols), isl = !isd && c >= NCOL(icols);
        const sw_col *col = isd ? &dcols[c - NCOL(icols) - NCOL(lcols)] : isl ? &lcols[c - NCOL(icols)] : &icols[c];
        if (read_ds(f, col->name, isd ? H5T_NATIVE_DOUBLE : H5T_NATIVE_LLONG, n, 0, isd ? (void *)dbuf : (void *)lbuf)) {
            snprintf(msg, len, "--resume: cannot read '%s' (%s)", path, col->name);
            goto out;
        }
        for (i = 0; i < n; i++) {
            char *fp = (char *)&res[i] + col->off;
            if (isd) *(double *)fp = dbuf[i];
            else if (isl) *(long *)fp = (long)lbuf[i];
            else *(int *)fp = (int)lbuf[i];
        }
    }
    {
        hid_t g;
        H5E_BEGIN_TRY { g = H5Gopen2(f, "timing", H5P_DEFAULT); } H5E_END_TRY;
        if (g >= 0) {
            if (read_ds(g, "wall", H5T_NATIVE_DOUBLE, n, 0, dbuf) == 0)
                for (i = 0; i < n; i++) res[i].wall = dbuf[i];
            H5Gclose(g);
        }
    }
    if (read_ds(f, "offset", H5T_NATIVE_DOUBLE, n, 3, dbuf) != 0) {
        snprintf(msg, len, "--resume: cannot read '%s' (offset)", path);
        goto out;
    }
    for (i = 0; i < n; i++) {
        memcpy(res[i].offset, dbuf + 3 * i, sizeof res[i].offset);
        snprintf(res[i].reason, sizeof res[i].reason, "%s", reasons[i] ? reasons[i] : "");
        if (res[i].status == SW_NOT_RUN) sw_result_blank(&res[i], i);
    }
    rc = 0;
out:
    free(fmt);
    free(text);
    free(ov);
    free(design);
    free_strs(names, (size_t)p->nkey);
    free_strs(vals, (size_t)(n * p->nkey));
    free_strs(reasons, (size_t)n);
    free(dbuf);
    free(lbuf);
    H5Fclose(f);
    return rc;
}

/* rows of a dataset (its first dimension), -1 if absent */
static long ds_rows(hid_t loc, const char *name)
{
    hid_t d, s;
    hsize_t dims[2] = {0, 0};
    long n = -1;
    H5E_BEGIN_TRY { d = H5Dopen2(loc, name, H5P_DEFAULT); } H5E_END_TRY;
    if (d < 0) return -1;
    s = H5Dget_space(d);
    if (H5Sget_simple_extent_ndims(s) >= 1 && H5Sget_simple_extent_dims(s, dims, NULL) >= 1 &&
        dims[0] <= (hsize_t)SW_MAX_VARIANTS)
        n = (long)dims[0];
    H5Sclose(s);
    H5Dclose(d);
    return n;
}

/* a list value as a gnuplot word: quotes dropped, blanks as '_' */
static void put_word(FILE *out, const char *v)
{
    size_t n = strlen(v), i;
    if (n >= 2 && (v[0] == '"' || v[0] == '\'') && v[n - 1] == v[0]) {
        v++;
        n -= 2;
    }
    if (n == 0) fputs("\"\"", out);
    for (i = 0; i < n; i++) fputc(v[i] == ' ' || v[i] == '\t' ? '_' : v[i], out);
}

int sw_summary_table(const char *path, FILE *out, char *msg, size_t len)
{
    hid_t f = open_ro(path), g;
    long n, nk, i, k, ns;
    int rc = -1;
    char *fmt = NULL, **names = NULL, **vals = NULL, **slice = NULL;
    double *num = NULL, *col[8], length = 0, *area = NULL;
    long long *verdict = NULL, *status = NULL;
    static const char *const dnames[8] = {"t_capture", "t_escape", "peak_fn", "peak_tau", "epsilon",
                                          "fn_step_max", "t_final", NULL};
    memset(col, 0, sizeof col);
    if (f < 0) {
        snprintf(msg, len, "cannot open the sweep summary '%s'", path);
        return -1;
    }
    fmt = read_attr_str(f, "format");
    nk = ds_rows(f, "param_names");
    n = ds_rows(f, "status");
    if (!same(fmt, SW_FORMAT) || nk < 1 || nk > SW_MAX_KEYS || n < 0) {
        snprintf(msg, len, "'%s' is not a capdyn sweep summary", path);
        goto out;
    }
    (void)read_attr_num(f, "length", H5T_NATIVE_DOUBLE, &length);
    names = read_strs(f, "param_names", nk, 0);
    vals = read_strs(f, "param_values", n, (int)nk);
    num = malloc(sizeof(double) * (size_t)(n * nk + 1));
    verdict = malloc(sizeof(long long) * (size_t)(n + 1));
    status = malloc(sizeof(long long) * (size_t)(n + 1));
    for (k = 0; k < 7; k++) col[k] = malloc(sizeof(double) * (size_t)(n + 1));
    if (!names || !vals || !num || !verdict || !status || !col[6] ||
        read_ds(f, "param_numeric", H5T_NATIVE_DOUBLE, n, (int)nk, num) ||
        read_ds(f, "verdict", H5T_NATIVE_LLONG, n, 0, verdict) || read_ds(f, "status", H5T_NATIVE_LLONG, n, 0, status)) {
        snprintf(msg, len, "cannot read the sweep summary '%s'", path);
        goto out;
    }
    for (k = 0; k < 7; k++)
        if (!col[k] || read_ds(f, dnames[k], H5T_NATIVE_DOUBLE, n, 0, col[k])) {
            snprintf(msg, len, "cannot read the sweep summary '%s' (%s)", path, dnames[k]);
            goto out;
        }
    fprintf(out, "# capdyn sweep summary '%s': %ld variants\n", path, n);
    fprintf(out, "# length %.17g m (keys with \"position\" in their path / length in the *_norm columns; 0: not normalised)\n", length);
    H5E_BEGIN_TRY { g = H5Gopen2(f, "region", H5P_DEFAULT); } H5E_END_TRY;
    if (g >= 0) {
        ns = ds_rows(g, "slice");
        if (ns > 0) {
            slice = read_strs(g, "slice", ns, 0);
            area = malloc(sizeof(double) * (size_t)ns);
            if (slice && area && read_ds(g, "area", H5T_NATIVE_DOUBLE, ns, 0, area) == 0)
                for (i = 0; i < ns; i++) fprintf(out, "# region %s area %.6g\n", slice[i] ? slice[i] : "", area[i]);
            free_strs(slice, slice ? (size_t)ns : 0);
            slice = NULL;
            free(area);
            area = NULL;
        }
        H5Gclose(g);
    }
    fputs("# index", out);
    for (k = 0; k < nk; k++) fprintf(out, " %s", names[k]);
    for (k = 0; k < nk; k++) fprintf(out, " %s_norm", names[k]);
    fputs(" verdict status t_capture t_escape peak_fn peak_tau epsilon fn_step_max t_final\n", out);
    fputs("# verdict: 0 unresolved, 1 captured, 2 escaped, -1 none; status: 0 ok, -1 not run, else failed\n", out);
    for (i = 0; i < n; i++) {
        fprintf(out, "%ld", i);
        for (k = 0; k < nk; k++) {
            fputc(' ', out);
            put_word(out, vals[i * nk + k] ? vals[i * nk + k] : "");
        }
        for (k = 0; k < nk; k++) {
            fputc(' ', out);
            if (isnan(num[i * nk + k])) put_word(out, vals[i * nk + k] ? vals[i * nk + k] : "");
            else if (length > 0 && names[k] && strstr(names[k], "position"))
                fprintf(out, "%.17g", num[i * nk + k] / length);
            else
                fprintf(out, "%.17g", num[i * nk + k]);
        }
        fprintf(out, " %lld %lld", verdict[i], status[i]);
        for (k = 0; k < 7; k++) fprintf(out, " %.9g", col[k][i]);
        fputc('\n', out);
    }
    rc = 0;
out:
    free(fmt);
    free_strs(names, names ? (size_t)nk : 0);
    free_strs(vals, vals ? (size_t)(n * nk) : 0);
    free(num);
    free(verdict);
    free(status);
    for (k = 0; k < 7; k++) free(col[k]);
    H5Fclose(f);
    return rc;
}
