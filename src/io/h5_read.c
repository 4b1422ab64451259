/* Reader of capdyn HDF5 results (see h5_read.h and docs/results-format.md).
 *
 * Untrusted input (docs/reliability.md, "Untrusted results files"): every
 * size or index read from a file is checked before it is used: table sizes
 * against the root attributes that repeat them, every index of the static
 * tables against the table it points into, every series' shape and type
 * against the schema (h5_schema.h) and the static tables, the sample count
 * against the rows on disk and a bound, string attributes against a size
 * bound. A file that fails a check is refused with a message naming what
 * is wrong. HDF5 itself may still crash on a damaged file: the CLI reads in
 * a child process for that (src/cli/capdyn.c).
 *
 * Compound tables are read through memory types that name only the members
 * needed: HDF5 matches compound members by name, so the reader keeps working
 * when later format versions add members. */
#include "h5_read.h"

#include <hdf5.h>
#include "h5_util.h"
#include "h5_schema.h"
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>


#define seterr cd_error_set

#define FID(r) ((hid_t)(r)->id)

static hid_t str_t(size_t n)
{
    hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, n);
    H5Tset_strpad(t, H5T_STR_NULLTERM);
    H5Tset_cset(t, H5T_CSET_UTF8); /* the writer's strings are UTF-8 */
    return t;
}
static void mem_str(hid_t ct, const char *name, size_t off, size_t n)
{
    hid_t t = str_t(n);
    H5Tinsert(ct, name, off, t);
    H5Tclose(t);
}
static void mem_arr(hid_t ct, const char *name, size_t off, hsize_t n)
{
    hid_t t = H5Tarray_create2(H5T_NATIVE_DOUBLE, 1, &n);
    H5Tinsert(ct, name, off, t);
    H5Tclose(t);
}

/* Bounds on sizes read from a file (far above anything a run writes). */
#define CD_H5R_MAX_ROWS 2000000000L /* samples, events (the loader allows 1e9 samples) */
#define CD_H5R_MAX_TABLE 10000000L  /* bodies, check points, shapes, vertices, slots */
#define CD_H5R_MAX_STR (1L << 20)   /* a string attribute [bytes] (the writer's are < 64 KiB) */
#define CD_H5R_MAX_TEXT (1L << 30)  /* a text dataset [bytes] */

/* rows of a 1-D table (or the first dimension of a dataset of rank 1..3);
 * returns the count, or -1 if missing, of another rank, or beyond max */
static long table_rows_max(hid_t f, const char *path, long max)
{
    hid_t ds = H5Dopen2(f, path, H5P_DEFAULT), sp;
    hsize_t d[3] = {0, 0, 0};
    int rank;
    if (ds < 0) return -1;
    sp = H5Dget_space(ds);
    rank = sp >= 0 ? H5Sget_simple_extent_ndims(sp) : -1;
    if (rank >= 1 && rank <= 3) H5Sget_simple_extent_dims(sp, d, NULL);
    if (sp >= 0) H5Sclose(sp);
    H5Dclose(ds);
    if (rank < 1 || rank > 3 || d[0] > (hsize_t)max) return -1;
    return (long)d[0];
}
static long table_rows(hid_t f, const char *path) { return table_rows_max(f, path, CD_H5R_MAX_TABLE); }

/* Reads a whole table of n rows (of `cols` values each when cols > 0: a 2-D
 * dataset n x cols) into out, sized for exactly that: a dataset of another
 * shape is refused before HDF5 writes into out. */
static int read_table_cols(hid_t f, const char *path, hid_t mt, long n, long cols, void *out)
{
    hid_t ds, sp;
    hsize_t d[2] = {0, 0};
    herr_t rc = -1;
    int rank;
    if (n <= 0) return 0;
    ds = H5Dopen2(f, path, H5P_DEFAULT);
    if (ds < 0) return -1;
    sp = H5Dget_space(ds);
    rank = sp >= 0 ? H5Sget_simple_extent_ndims(sp) : -1;
    if (rank == (cols > 0 ? 2 : 1)) {
        H5Sget_simple_extent_dims(sp, d, NULL);
        if (d[0] == (hsize_t)n && (cols <= 0 || d[1] == (hsize_t)cols))
            rc = H5Dread(ds, mt, H5S_ALL, H5S_ALL, H5P_DEFAULT, out);
    }
    if (sp >= 0) H5Sclose(sp);
    H5Dclose(ds);
    return rc < 0 ? -1 : 0;
}
static int read_table(hid_t f, const char *path, hid_t mt, long n, void *out)
{ return read_table_cols(f, path, mt, n, 0, out); }

int cd_h5r_exists(const cd_h5r *r, const char *path)
{
    cd_h5_quiet q;
    htri_t e;
    const char *p;
    char buf[512];
    cd_h5_quiet_begin(&q);
    /* H5Lexists needs every intermediate link to exist: walk the path */
    e = 1;
    p = path + 1;
    while (e > 0 && *p) {
        const char *s = strchr(p, '/');
        size_t n = s ? (size_t)(s - path) : strlen(path);
        if (n >= sizeof buf) { e = 0; break; }
        memcpy(buf, path, n);
        buf[n] = 0;
        e = H5Lexists(FID(r), buf, H5P_DEFAULT);
        if (!s) break;
        p = s + 1;
    }
    cd_h5_quiet_end(&q);
    return e > 0;
}

int cd_h5r_vec(const cd_h5r *r, const char *path, double *v, long n)
{
    cd_h5_quiet q;
    hid_t ds, sp;
    int rc = -1;
    if (!cd_h5r_exists(r, path)) return -1;
    cd_h5_quiet_begin(&q);
    ds = H5Dopen2(FID(r), path, H5P_DEFAULT);
    if (ds >= 0) {
        hsize_t dim = 0;
        sp = H5Dget_space(ds);
        rc = -2;
        if (sp >= 0 && H5Sget_simple_extent_ndims(sp) == 1 && H5Sget_simple_extent_dims(sp, &dim, NULL) == 1 &&
            dim == (hsize_t)n && n > 0 && H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) >= 0)
            rc = 0;
        if (sp >= 0) H5Sclose(sp);
        H5Dclose(ds);
    } else {
        rc = -2;
    }
    cd_h5_quiet_end(&q);
    return rc;
}

/* 1 if the attribute holds one element (strings are written as scalars) */
static int attr_is_scalar(hid_t a)
{
    hid_t sp = H5Aget_space(a);
    hssize_t n = sp >= 0 ? H5Sget_simple_extent_npoints(sp) : -1;
    if (sp >= 0) H5Sclose(sp);
    return n == 1;
}

char *cd_h5r_attr_str(const cd_h5r *r, const char *obj, const char *name)
{
    cd_h5_quiet q;
    hid_t a, t, mt;
    char *s = NULL;
    size_t n;
    cd_h5_quiet_begin(&q);
    a = H5Aopen_by_name(FID(r), obj, name, H5P_DEFAULT, H5P_DEFAULT);
    if (a >= 0) {
        t = H5Aget_type(a);
        n = H5Tget_size(t);
        if (H5Tget_class(t) == H5T_STRING && H5Tis_variable_str(t) == 0 && n > 0 && n <= (size_t)CD_H5R_MAX_STR &&
            attr_is_scalar(a)) {
            mt = H5Tcopy(t); /* keep the file's character set: HDF5 will not convert it */
            H5Tset_size(mt, n + 1);
            s = calloc(1, n + 2);
            if (s && H5Aread(a, mt, s) < 0) { free(s); s = NULL; }
            H5Tclose(mt);
        }
        H5Tclose(t);
        H5Aclose(a);
    }
    cd_h5_quiet_end(&q);
    return s;
}

char *cd_h5r_text(const cd_h5r *r, const char *name)
{
    char *s = cd_h5r_attr_str(r, "/", name), path[256];
    cd_h5_quiet q;
    hid_t ds;
    if (!s || strncmp(s, "@dataset /", 10) != 0) return s;
    free(s);
    s = NULL;
    snprintf(path, sizeof path, "/%s", name);
    cd_h5_quiet_begin(&q);
    ds = H5Dopen2(FID(r), path, H5P_DEFAULT);
    if (ds >= 0) {
        hid_t sp = H5Dget_space(ds);
        hssize_t n = H5Sget_simple_extent_npoints(sp);
        if (n < 0 || n > CD_H5R_MAX_TEXT) n = -1; /* refused below */
        s = n >= 0 ? calloc(1, (size_t)n + 1) : NULL;
        if (s && n > 0 && H5Dread(ds, H5T_NATIVE_CHAR, H5S_ALL, H5S_ALL, H5P_DEFAULT, s) < 0) { free(s); s = NULL; }
        H5Sclose(sp);
        H5Dclose(ds);
    }
    cd_h5_quiet_end(&q);
    return s;
}

static int attr_num(const cd_h5r *r, const char *obj, const char *name, hid_t mt, void *v, int n)
{
    cd_h5_quiet q;
    hid_t a, sp;
    int rc = -1;
    cd_h5_quiet_begin(&q);
    a = H5Aopen_by_name(FID(r), obj, name, H5P_DEFAULT, H5P_DEFAULT);
    if (a >= 0) {
        sp = H5Aget_space(a);
        if (H5Sget_simple_extent_npoints(sp) == n && H5Aread(a, mt, v) >= 0) rc = 0;
        H5Sclose(sp);
        H5Aclose(a);
    }
    cd_h5_quiet_end(&q);
    return rc;
}
int cd_h5r_attr_f64(const cd_h5r *r, const char *obj, const char *name, double *v)
{ return attr_num(r, obj, name, H5T_NATIVE_DOUBLE, v, 1); }
int cd_h5r_attr_f64v(const cd_h5r *r, const char *obj, const char *name, double *v, int n)
{ return attr_num(r, obj, name, H5T_NATIVE_DOUBLE, v, n); }
int cd_h5r_attr_i64(const cd_h5r *r, const char *obj, const char *name, long long *v)
{ return attr_num(r, obj, name, H5T_NATIVE_LLONG, v, 1); }

static int attr_int_of(hid_t obj, const char *name, int *v)
{
    hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
    int rc = -1;
    if (a >= 0) {
        if (attr_is_scalar(a) && H5Aread(a, H5T_NATIVE_INT, v) >= 0) rc = 0;
        H5Aclose(a);
    }
    return rc;
}
static int attr_str_of(hid_t obj, const char *name, char *out, size_t len)
{
    hid_t a = H5Aopen(obj, name, H5P_DEFAULT), t, mt;
    int rc = -1;
    char *tmp;
    size_t n;
    out[0] = 0;
    if (a < 0) return -1;
    t = H5Aget_type(a);
    n = H5Tget_size(t);
    if (H5Tget_class(t) != H5T_STRING || H5Tis_variable_str(t) != 0 || n == 0 || n > (size_t)CD_H5R_MAX_STR ||
        !attr_is_scalar(a)) {
        H5Tclose(t);
        H5Aclose(a);
        return -1;
    }
    mt = H5Tcopy(t);
    H5Tset_size(mt, n + 1);
    tmp = calloc(1, n + 2);
    if (tmp && H5Aread(a, mt, tmp) >= 0) {
        snprintf(out, len, "%s", tmp);
        rc = 0;
    }
    free(tmp);
    H5Tclose(mt);
    H5Tclose(t);
    H5Aclose(a);
    return rc;
}

typedef struct { cd_h5r *r; int i; int fail; } sys_iter;

static herr_t sys_cb(hid_t g, const char *name, const H5L_info_t *info, void *op)
{
    sys_iter *it = (sys_iter *)op;
    hid_t gs;
    cd_h5r_sys *s;
    char bt[16];
    (void)info;
    if (it->i >= it->r->nsys) return 0;
    gs = H5Gopen2(g, name, H5P_DEFAULT);
    if (gs < 0) { it->fail = 1; return -1; }
    {
        int idx = -1;
        if (attr_int_of(gs, "index", &idx) < 0 || idx < 0 || idx >= it->r->nsys) {
            H5Gclose(gs);
            it->fail = 1;
            return -1;
        }
        s = it->r->sys + idx;
        if (s->group[0]) { /* two groups claim one index */
            H5Gclose(gs);
            it->fail = 1;
            return -1;
        }
    }
    snprintf(s->group, sizeof s->group, "%s", name[0] ? name : "?");
    if (attr_str_of(gs, "name", s->name, sizeof s->name) < 0) snprintf(s->name, sizeof s->name, "%s", name);
    attr_str_of(gs, "base_type", bt, sizeof bt);
    s->base_free = strcmp(bt, "free") == 0;
    attr_int_of(gs, "njoint", &s->njoint);
    attr_int_of(gs, "body_first", &s->body_first);
    attr_int_of(gs, "nbody", &s->nbody);
    H5Gclose(gs);
    it->i++;
    return 0;
}

void cd_h5r_close(cd_h5r *r)
{
    cd_h5_quiet q;
    if (!r) return;
    cd_h5_quiet_begin(&q);
    if (r->id >= 0) H5Fclose(FID(r));
    cd_h5_quiet_end(&q);
    free(r->sys);
    free(r->body);
    free(r->cp);
    free(r->shape);
    free(r->vert);
    free(r->slot);
    free(r);
}

static int read_static(cd_h5r *r)
{
    hid_t f = FID(r), ct;
    long n;
    int rc = 0;
    /* systems */
    {
        hid_t g = H5Gopen2(f, "/systems", H5P_DEFAULT);
        sys_iter it;
        hsize_t idx = 0;
        H5G_info_t gi;
        if (g < 0) return -1;
        if (H5Gget_info(g, &gi) < 0 || gi.nlinks > (hsize_t)CD_H5R_MAX_TABLE) {
            H5Gclose(g);
            return -1;
        }
        r->nsys = (int)gi.nlinks;
        r->sys = calloc((size_t)(r->nsys ? r->nsys : 1), sizeof *r->sys);
        if (!r->sys) { H5Gclose(g); return -1; }
        it.r = r;
        it.i = 0;
        it.fail = 0;
        H5Literate(g, H5_INDEX_NAME, H5_ITER_NATIVE, &idx, sys_cb, &it);
        H5Gclose(g);
        if (it.fail || it.i != r->nsys) return -1;
    }
    /* bodies */
    n = table_rows(f, "/model/bodies");
    if (n < 0) return -1;
    r->nbody = (int)n;
    r->body = calloc((size_t)(n ? n : 1), sizeof *r->body);
    if (!r->body) return -1;
    ct = H5Tcreate(H5T_COMPOUND, sizeof(cd_h5r_body));
    H5Tinsert(ct, "system", HOFFSET(cd_h5r_body, system), H5T_NATIVE_INT);
    H5Tinsert(ct, "parent", HOFFSET(cd_h5r_body, parent), H5T_NATIVE_INT);
    H5Tinsert(ct, "joint_type", HOFFSET(cd_h5r_body, joint_type), H5T_NATIVE_INT);
    mem_str(ct, "name", HOFFSET(cd_h5r_body, name), sizeof r->body->name);
    mem_str(ct, "full_name", HOFFSET(cd_h5r_body, full_name), sizeof r->body->full_name);
    H5Tinsert(ct, "mass", HOFFSET(cd_h5r_body, mass), H5T_NATIVE_DOUBLE);
    mem_arr(ct, "com", HOFFSET(cd_h5r_body, com), 3);
    mem_arr(ct, "inertia", HOFFSET(cd_h5r_body, inertia), 9);
    rc |= read_table(f, "/model/bodies", ct, n, r->body);
    H5Tclose(ct);
    /* check points */
    n = table_rows(f, "/model/checkpoints");
    if (n < 0) return -1;
    r->ncp = (int)n;
    r->cp = calloc((size_t)(n ? n : 1), sizeof *r->cp);
    if (!r->cp) return -1;
    ct = H5Tcreate(H5T_COMPOUND, sizeof(cd_h5r_cp));
    H5Tinsert(ct, "body", HOFFSET(cd_h5r_cp, body), H5T_NATIVE_INT);
    mem_arr(ct, "pos", HOFFSET(cd_h5r_cp, pos), 3);
    H5Tinsert(ct, "radius", HOFFSET(cd_h5r_cp, radius), H5T_NATIVE_DOUBLE);
    rc |= read_table(f, "/model/checkpoints", ct, n, r->cp);
    H5Tclose(ct);
    /* shapes */
    n = table_rows(f, "/model/shapes");
    if (n < 0) return -1;
    r->nshape = (int)n;
    r->shape = calloc((size_t)(n ? n : 1), sizeof *r->shape);
    if (!r->shape) return -1;
    ct = H5Tcreate(H5T_COMPOUND, sizeof(cd_h5r_shape));
    H5Tinsert(ct, "body", HOFFSET(cd_h5r_shape, body), H5T_NATIVE_INT);
    H5Tinsert(ct, "type", HOFFSET(cd_h5r_shape, type), H5T_NATIVE_INT);
    mem_arr(ct, "pos", HOFFSET(cd_h5r_shape, pos), 3);
    mem_arr(ct, "rot", HOFFSET(cd_h5r_shape, rot), 9);
    mem_arr(ct, "size", HOFFSET(cd_h5r_shape, size), 3);
    H5Tinsert(ct, "vert_adr", HOFFSET(cd_h5r_shape, vert_adr), H5T_NATIVE_INT);
    H5Tinsert(ct, "vert_num", HOFFSET(cd_h5r_shape, vert_num), H5T_NATIVE_INT);
    rc |= read_table(f, "/model/shapes", ct, n, r->shape);
    H5Tclose(ct);
    /* vertices */
    n = table_rows(f, "/model/vertices");
    r->nvert = n > 0 ? (int)n : 0;
    r->vert = calloc((size_t)(r->nvert ? r->nvert : 1) * 3, sizeof(double));
    if (!r->vert) return -1;
    if (r->nvert > 0) rc |= read_table_cols(f, "/model/vertices", H5T_NATIVE_DOUBLE, r->nvert, 3, r->vert);
    /* slots */
    n = table_rows(f, "/contacts/slots");
    if (n < 0) return -1;
    r->nslot = (int)n;
    r->slot = calloc((size_t)(n ? n : 1), sizeof *r->slot);
    if (!r->slot) return -1;
    ct = H5Tcreate(H5T_COMPOUND, sizeof(cd_h5r_slot));
    H5Tinsert(ct, "checkpoint", HOFFSET(cd_h5r_slot, checkpoint), H5T_NATIVE_INT);
    H5Tinsert(ct, "shape", HOFFSET(cd_h5r_slot, shape), H5T_NATIVE_INT);
    H5Tinsert(ct, "body_a", HOFFSET(cd_h5r_slot, body_a), H5T_NATIVE_INT);
    H5Tinsert(ct, "body_b", HOFFSET(cd_h5r_slot, body_b), H5T_NATIVE_INT);
    mem_str(ct, "body_a_name", HOFFSET(cd_h5r_slot, body_a_name), sizeof r->slot->body_a_name);
    mem_str(ct, "body_b_name", HOFFSET(cd_h5r_slot, body_b_name), sizeof r->slot->body_b_name);
    mem_str(ct, "shape_type", HOFFSET(cd_h5r_slot, shape_type), sizeof r->slot->shape_type);
    rc |= read_table(f, "/contacts/slots", ct, n, r->slot);
    H5Tclose(ct);
    return rc ? -1 : 0;
}

/* The static tables hang together: sizes as the root attributes state
 * them, every index inside the table it points into, the systems' bodies
 * contiguous. Returns NULL, or what is wrong. */
static const char *validate_static(cd_h5r *r)
{
    long long a;
    int s, b, k, next = 0;
#define SAME(attr, v) (cd_h5r_attr_i64(r, "/", attr, &a) == 0 && a == (long long)(v))
    if (!SAME("nsys", r->nsys) || !SAME("nbody", r->nbody) || !SAME("ncheckpoint", r->ncp) ||
        !SAME("nshape", r->nshape) || !SAME("nslot", r->nslot))
        return "the sizes of the model tables differ from the root attributes nsys, nbody, ncheckpoint, nshape, nslot";
#undef SAME
    for (s = 0; s < r->nsys; s++) {
        const cd_h5r_sys *y = r->sys + s;
        if (y->body_first != next || y->nbody < 1 || y->nbody > r->nbody - next || y->njoint != y->nbody - 1)
            return "a system's body_first, nbody or njoint does not match the body table";
        next += y->nbody;
    }
    if (next != r->nbody) return "the systems' bodies do not add up to the body table";
    for (b = 0; b < r->nbody; b++) {
        const cd_h5r_body *y = r->body + b;
        if (y->system < 0 || y->system >= r->nsys || y->parent < -1 || y->parent >= b ||
            (y->parent >= 0 && r->body[y->parent].system != y->system) ||
            (y->parent < 0) != (b == r->sys[y->system].body_first))
            return "a body's system or parent index is out of range";
    }
    for (k = 0; k < r->ncp; k++)
        if (r->cp[k].body < 0 || r->cp[k].body >= r->nbody) return "a check point's body index is out of range";
    for (k = 0; k < r->nshape; k++) {
        const cd_h5r_shape *y = r->shape + k;
        if (y->body < 0 || y->body >= r->nbody || y->type < 0 || y->type >= CD_SHAPE_NTYPES || y->vert_adr < 0 ||
            y->vert_num < 0 || y->vert_num > r->nvert - y->vert_adr)
            return "a shape's body, type or vertex range is out of range";
    }
    for (k = 0; k < r->nslot; k++) {
        const cd_h5r_slot *y = r->slot + k;
        if (y->checkpoint < 0 || y->checkpoint >= r->ncp || y->shape < 0 || y->shape >= r->nshape || y->body_a < 0 ||
            y->body_a >= r->nbody || y->body_b < 0 || y->body_b >= r->nbody)
            return "a contact slot's check point, shape or body index is out of range";
    }
    return NULL;
}

/* Why HDF5 would not open path. The one damage a capdyn run leaves is a
 * truncated file: a write that failed (disk full, quota, file size limit)
 * after HDF5 had recorded the larger end-of-file address in the superblock.
 * The superblock (at offset 0, little-endian) says where the file ends:
 * end-of-file address at byte 40 (version 0), 44 (version 1) or 28
 * (versions 2 and 3), with 8-byte addresses. */
static void diagnose(const char *path, cd_error *err)
{
    static const unsigned char sig[8] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};
    unsigned char b[64];
    FILE *fp = fopen(path, "rb");
    struct stat st;
    size_t n;
    int off;
    unsigned long long eoa = 0;
    if (!fp) {
        seterr(err, CD_EIO, "cannot open '%s': no such file or not readable", path);
        return;
    }
    n = fread(b, 1, sizeof b, fp);
    fclose(fp);
    if (n < 8 || memcmp(b, sig, 8) != 0) {
        seterr(err, CD_EIO, "cannot open '%s': not an HDF5 file", path);
        return;
    }
    off = b[8] == 0 ? 40 : b[8] == 1 ? 44 : (b[8] == 2 || b[8] == 3) ? 28 : -1;
    if (off > 0 && n >= (size_t)off + 8 && (b[8] >= 2 || b[13] == 8) && stat(path, &st) == 0) {
        int i;
        for (i = 7; i >= 0; i--) eoa = (eoa << 8) | b[off + i];
        if (eoa > (unsigned long long)st.st_size) {
            seterr(err, CD_EIO,
                   "cannot open '%s': the file is truncated (%llu of the %llu bytes its header names), as a "
                   "run whose writing failed (disk full, quota, file size limit) leaves it; "
                   "'h5clear --increment=0 %s' makes its committed samples readable",
                   path, (unsigned long long)st.st_size, eoa, path);
            return;
        }
    }
    seterr(err, CD_EIO, "cannot open '%s': a damaged HDF5 file (if its run failed writing it, try "
           "'h5clear --increment=0 %s' on a copy)", path, path);
}

cd_h5r *cd_h5r_open(const char *path, cd_error *err)
{
    cd_h5_quiet q;
    hid_t fapl, f;
    cd_h5r *r;
    long long c = -1;
    long rows;
    char *fmt;
    cd_h5_quiet_begin(&q);
    fapl = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_file_locking(fapl, 0, 1);
    /* SWMR read first: HDF5 then reads past the end-of-allocation address
     * that the superblock records. A run killed inside a commit may leave
     * a chunk index already pointing at chunks written beyond the address
     * its superblock (flushed last) records; a plain open refuses to read
     * them ("addr overflow"), although they are complete on disk. Files of
     * an older format do not open that way: then a plain open. */
    /* one attempt per metadata read: SWMR readers retry a read whose
     * checksum fails (by default 100 times, sleeping in between), which
     * made a damaged file take many minutes to refuse */
    H5Pset_metadata_read_attempts(fapl, 1);
    f = H5Fopen(path, H5F_ACC_RDONLY | H5F_ACC_SWMR_READ, fapl);
    if (f < 0) f = H5Fopen(path, H5F_ACC_RDONLY, fapl);
    H5Pclose(fapl);
    cd_h5_quiet_end(&q);
    if (f < 0) {
        diagnose(path, err);
        return NULL;
    }
    r = calloc(1, sizeof *r);
    if (!r) {
        H5Fclose(f);
        seterr(err, CD_ENOMEM, "out of memory");
        return NULL;
    }
    r->id = (long long)f;
    fmt = cd_h5r_attr_str(r, "/", "format");
    if (!fmt || strcmp(fmt, "capdyn-results") != 0) {
        free(fmt);
        cd_h5r_close(r);
        seterr(err, CD_EIO, "'%s' is an HDF5 file but not a capdyn results file (no format = \"capdyn-results\")", path);
        return NULL;
    }
    free(fmt);
    cd_h5_quiet_begin(&q);
    rows = table_rows_max(f, "/time", CD_H5R_MAX_ROWS);
    cd_h5_quiet_end(&q);
    r->nrows = rows > 0 ? rows : 0;
    r->n = r->nrows;
    if (cd_h5r_attr_i64(r, "/", "committed_samples", &c) == 0 && c >= 0 && c < r->n) r->n = (long)c;
    cd_h5_quiet_begin(&q);
    rows = table_rows_max(f, "/events", CD_H5R_MAX_ROWS);
    cd_h5_quiet_end(&q);
    r->nev = rows > 0 ? rows : 0;
    c = -1;
    if (cd_h5r_attr_i64(r, "/", "committed_events", &c) == 0 && c >= 0 && c < r->nev) r->nev = (long)c;
    c = 0;
    cd_h5r_attr_i64(r, "/events", "lost", &c);
    r->ev_lost = c;
    cd_h5_quiet_begin(&q);
    rows = read_static(r);
    cd_h5_quiet_end(&q);
    if (rows < 0) {
        cd_h5r_close(r);
        seterr(err, CD_EIO, "'%s': the model tables (/systems, /model, /contacts/slots) are missing or damaged", path);
        return NULL;
    }
    {
        const char *why = validate_static(r);
        if (why) {
            cd_h5r_close(r);
            seterr(err, CD_EIO, "'%s': a damaged results file: %s", path, why);
            return NULL;
        }
    }
    return r;
}

/* The shape a series at path must have (h5_schema.h and the static
 * tables): its rank and tail dimensions; -1 if path is no known series. */
static int expected_shape(const cd_h5r *r, const char *path, int *rank, hsize_t tail[2], int *type)
{
    const char *name = NULL, *slash;
    cd_h5_group g;
    int sys = -1, i, nt;
    long t[2];
    if (!strncmp(path, "/systems/", 9)) {
        char grp[128];
        size_t n;
        slash = strchr(path + 9, '/');
        n = slash ? (size_t)(slash - (path + 9)) : 0;
        if (!slash || n >= sizeof grp) return -1;
        memcpy(grp, path + 9, n);
        grp[n] = 0;
        for (i = 0; i < r->nsys; i++)
            if (!strcmp(r->sys[i].group, grp)) sys = i;
        if (sys < 0) return -1;
        g = CD_G_SYSTEM;
        name = slash + 1;
    } else if (!strncmp(path, "/contacts/", 10)) {
        g = CD_G_CONTACTS;
        name = path + 10;
    } else if (!strncmp(path, "/diagnostics/", 13)) {
        g = CD_G_DIAGNOSTICS;
        name = path + 13;
    } else if (!strncmp(path, "/actuators/", 11)) {
        g = CD_G_ACTUATORS;
        name = path + 11;
    } else {
        g = CD_G_ROOT;
        name = path + 1;
    }
    for (i = 0; i < CD_H5_NSERIES_DEFS; i++) {
        const cd_h5_series_def *def = cd_h5_series_defs + i;
        if (def->group != g || strcmp(def->name, name) != 0) continue;
        long long nu = 0;
        if (def->shape == CD_SH_NU && (cd_h5r_attr_i64(r, "/actuators", "nactuator", &nu) != 0 || nu < 1 || nu > 1000000))
            return -1;
        cd_h5_shape_rowlen(def->shape, r->nsys, r->nslot, sys >= 0 ? r->sys[sys].njoint : 0,
                           sys >= 0 ? r->sys[sys].nbody : 0, (long)nu, &nt, t);
        *rank = 1 + nt;
        tail[0] = (hsize_t)t[0];
        tail[1] = (hsize_t)t[1];
        *type = def->type;
        return 0;
    }
    return -1;
}

double *cd_h5r_series(const cd_h5r *r, const char *path, size_t *rowlen, cd_error *err)
{
    return cd_h5r_series_head(r, path, r->n, rowlen, err);
}

double *cd_h5r_series_head(const cd_h5r *r, const char *path, long nrows, size_t *rowlen, cd_error *err)
{
    cd_h5_quiet q;
    hid_t ds, fs, ms, ft;
    hsize_t d[3] = {0, 0, 0}, off[3] = {0, 0, 0}, cnt[3], tail[2] = {0, 0};
    int rank, i, erank = 0, etype = 0, ok;
    size_t rl = 1;
    double *v = NULL;
    if (expected_shape(r, path, &erank, tail, &etype) < 0) {
        seterr(err, CD_EIO, "%s is not a time series of the results format", path);
        return NULL;
    }
    cd_h5_quiet_begin(&q);
    ds = H5Dopen2(FID(r), path, H5P_DEFAULT);
    if (ds < 0) {
        cd_h5_quiet_end(&q);
        seterr(err, CD_EIO, "no dataset %s in the results file", path);
        return NULL;
    }
    /* the shape and type the schema and the model tables say, before any
     * size from the file is used */
    fs = H5Dget_space(ds);
    ft = H5Dget_type(ds);
    rank = fs >= 0 ? H5Sget_simple_extent_ndims(fs) : -1;
    ok = rank == erank && ft >= 0 && H5Tget_size(ft) == (etype == CD_H5_F64 || etype == CD_H5_I64 ? 8u : 1u) &&
         H5Tget_class(ft) == (etype == CD_H5_F64 ? H5T_FLOAT : H5T_INTEGER);
    if (ok) H5Sget_simple_extent_dims(fs, d, NULL);
    for (i = 1; ok && i < rank; i++) ok = d[i] == tail[i - 1];
    if (ft >= 0) H5Tclose(ft);
    if (!ok) {
        H5Sclose(fs);
        H5Dclose(ds);
        cd_h5_quiet_end(&q);
        seterr(err, CD_EIO, "dataset %s has another shape or type than the model tables and the format say "
               "(a damaged file)", path);
        return NULL;
    }
    if ((long)d[0] < r->n) {
        H5Sclose(fs);
        H5Dclose(ds);
        cd_h5_quiet_end(&q);
        seterr(err, CD_EIO, "dataset %s is shorter than the committed sample count", path);
        return NULL;
    }
    if (nrows < 0 || nrows > r->n) nrows = r->n;
    for (i = 1; i < rank; i++) rl *= (size_t)d[i];
    cnt[0] = (hsize_t)nrows;
    for (i = 1; i < rank; i++) cnt[i] = d[i];
    v = malloc(((size_t)nrows * rl > 0 ? (size_t)nrows * rl : 1) * sizeof *v);
    if (v && nrows > 0 && rl > 0) {
        H5Sselect_hyperslab(fs, H5S_SELECT_SET, off, NULL, cnt, NULL);
        ms = H5Screate_simple(rank, cnt, NULL);
        if (H5Dread(ds, H5T_NATIVE_DOUBLE, ms, fs, H5P_DEFAULT, v) < 0) {
            free(v);
            v = NULL;
        }
        H5Sclose(ms);
    }
    H5Sclose(fs);
    H5Dclose(ds);
    cd_h5_quiet_end(&q);
    if (!v) {
        seterr(err, CD_EIO, "reading %s failed", path);
        return NULL;
    }
    if (rowlen) *rowlen = rl;
    return v;
}

cd_event *cd_h5r_events(const cd_h5r *r, long *n, cd_error *err)
{
    cd_h5_quiet q;
    hid_t ds, fs, ms, ft, ct, kt, mt, ot;
    hsize_t off = 0, cnt = (hsize_t)r->nev;
    cd_event *ev = calloc((size_t)(r->nev ? r->nev : 1), sizeof *ev);
    herr_t rc = 0;
    int idx;
    *n = 0;
    if (!ev) {
        seterr(err, CD_ENOMEM, "out of memory");
        return NULL;
    }
    if (r->nev == 0) return ev;
    cd_h5_quiet_begin(&q);
    ds = H5Dopen2(FID(r), "/events", H5P_DEFAULT);
    if (ds < 0) {
        cd_h5_quiet_end(&q);
        free(ev);
        seterr(err, CD_EIO, "no /events table");
        return NULL;
    }
    /* the enum members are read with the file's own enum types (HDF5 does not
     * convert enums to plain integers) */
    ft = H5Dget_type(ds);
    idx = H5Tget_member_index(ft, "kind");
    kt = idx >= 0 ? H5Tget_member_type(ft, (unsigned)idx) : -1;
    idx = H5Tget_member_index(ft, "mode_from");
    mt = idx >= 0 ? H5Tget_member_type(ft, (unsigned)idx) : -1;
    idx = H5Tget_member_index(ft, "owner_kind");
    ot = idx >= 0 ? H5Tget_member_type(ft, (unsigned)idx) : -1;
    ct = H5Tcreate(H5T_COMPOUND, sizeof(cd_event));
    H5Tinsert(ct, "t", HOFFSET(cd_event, t), H5T_NATIVE_DOUBLE);
    if (kt >= 0) {
        hid_t nkt = H5Tget_native_type(kt, H5T_DIR_DEFAULT);
        H5Tinsert(ct, "kind", HOFFSET(cd_event, kind), nkt);
        H5Tclose(nkt);
    }
    if (mt >= 0) {
        hid_t nmt = H5Tget_native_type(mt, H5T_DIR_DEFAULT);
        H5Tinsert(ct, "mode_from", HOFFSET(cd_event, mode_from), nmt);
        H5Tinsert(ct, "mode_to", HOFFSET(cd_event, mode_to), nmt);
        H5Tclose(nmt);
    }
    H5Tinsert(ct, "slot", HOFFSET(cd_event, slot), H5T_NATIVE_INT);
    H5Tinsert(ct, "body_a", HOFFSET(cd_event, body_a), H5T_NATIVE_INT);
    H5Tinsert(ct, "body_b", HOFFSET(cd_event, body_b), H5T_NATIVE_INT);
    H5Tinsert(ct, "x", HOFFSET(cd_event, x), H5T_NATIVE_DOUBLE);
    H5Tinsert(ct, "fn", HOFFSET(cd_event, fn), H5T_NATIVE_DOUBLE);
    H5Tinsert(ct, "ft", HOFFSET(cd_event, ft), H5T_NATIVE_DOUBLE);
    if (ot >= 0) { /* files before the owner fields: every event was a slot's */
        hid_t not_ = H5Tget_native_type(ot, H5T_DIR_DEFAULT);
        H5Tinsert(ct, "owner_kind", HOFFSET(cd_event, owner_kind), not_);
        H5Tinsert(ct, "owner", HOFFSET(cd_event, owner), H5T_NATIVE_INT);
        H5Tclose(not_);
    }
    fs = H5Dget_space(ds);
    ms = H5Screate_simple(1, &cnt, NULL);
    rc = H5Sget_simple_extent_ndims(fs) == 1 ? H5Sselect_hyperslab(fs, H5S_SELECT_SET, &off, NULL, &cnt, NULL) : -1;
    if (rc >= 0) rc = H5Dread(ds, ct, ms, fs, H5P_DEFAULT, ev);
    H5Sclose(ms);
    H5Sclose(fs);
    H5Tclose(ct);
    if (kt >= 0) H5Tclose(kt);
    if (mt >= 0) H5Tclose(mt);
    if (ot >= 0) H5Tclose(ot);
    H5Tclose(ft);
    H5Dclose(ds);
    cd_h5_quiet_end(&q);
    if (rc < 0) {
        free(ev);
        seterr(err, CD_EIO, "reading /events failed");
        return NULL;
    }
    if (ot < 0) {
        long e;
        for (e = 0; e < r->nev; e++) { ev[e].owner_kind = CD_OWNER_SLOT; ev[e].owner = ev[e].slot; }
    }
    *n = r->nev;
    return ev;
}

int cd_h5r_system(const cd_h5r *r, const char *name)
{
    int s;
    for (s = 0; s < r->nsys; s++)
        if (strcmp(r->sys[s].name, name) == 0 || strcmp(r->sys[s].group, name) == 0) return s;
    return -1;
}

/* ---- every dataset reads (capdyn info) ------------------------------------------ */
/* Reads each dataset of the file in full, every row on disk and not only the
 * committed ones, in blocks of at most 1 MiB, as h5dump or h5py would: a file
 * whose chunk index or chunks do not read is refused, even if no committed
 * sample lies in them (issue 28: a file renamed into place before its first
 * commit was whole had committed_samples 0 and no dataset that read). */
typedef struct {
    char path[512];
    int bad;
} verify_ctx;

static int verify_dataset(hid_t ds)
{
    hid_t fs = H5Dget_space(ds), ft = H5Dget_type(ds), mt = -1, ms = -1;
    hsize_t d[H5S_MAX_RANK], off[H5S_MAX_RANK], cnt[H5S_MAX_RANK];
    int rank, i, rc = -1;
    size_t esize, rowbytes = 1, block;
    void *buf = NULL;
    if (fs < 0 || ft < 0) goto out;
    rank = H5Sget_simple_extent_ndims(fs);
    if (rank < 0) goto out;
    if (H5Tdetect_class(ft, H5T_VLEN) > 0 || H5Tis_variable_str(ft) > 0) { rc = 0; goto out; } /* not in the format */
    mt = H5Tget_native_type(ft, H5T_DIR_ASCEND);
    esize = mt >= 0 ? H5Tget_size(mt) : 0;
    if (esize == 0) goto out;
    if (rank == 0) {
        buf = malloc(esize);
        rc = buf && H5Dread(ds, mt, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0 ? 0 : -1;
        goto out;
    }
    H5Sget_simple_extent_dims(fs, d, NULL);
    for (i = 1; i < rank; i++) {
        if (d[i] > 0 && rowbytes > ((size_t)1 << 40) / d[i]) goto out;
        rowbytes *= (size_t)d[i];
    }
    rowbytes *= esize;
    block = rowbytes >= (1u << 20) ? 1 : (1u << 20) / rowbytes;
    buf = malloc(rowbytes * block > 0 ? rowbytes * block : 1);
    if (!buf) goto out;
    rc = 0;
    for (off[0] = 0; off[0] < d[0] && rc == 0; off[0] += cnt[0]) {
        cnt[0] = d[0] - off[0] < block ? d[0] - off[0] : block;
        for (i = 1; i < rank; i++) {
            off[i] = 0;
            cnt[i] = d[i];
        }
        ms = H5Screate_simple(rank, cnt, NULL);
        if (ms < 0 || H5Sselect_hyperslab(fs, H5S_SELECT_SET, off, NULL, cnt, NULL) < 0 ||
            H5Dread(ds, mt, ms, fs, H5P_DEFAULT, buf) < 0)
            rc = -1;
        if (ms >= 0) H5Sclose(ms);
        ms = -1;
    }
out:
    free(buf);
    if (mt >= 0) H5Tclose(mt);
    if (ft >= 0) H5Tclose(ft);
    if (fs >= 0) H5Sclose(fs);
    return rc;
}

static herr_t verify_cb(hid_t o, const char *name, const H5O_info_t *info, void *op)
{
    verify_ctx *c = (verify_ctx *)op;
    hid_t ds;
    if (info->type != H5O_TYPE_DATASET) return 0;
    ds = H5Dopen2(o, name, H5P_DEFAULT);
    if (ds < 0 || verify_dataset(ds) < 0) {
        snprintf(c->path, sizeof c->path, "/%s", name);
        c->bad = 1;
    }
    if (ds >= 0) H5Dclose(ds);
    return c->bad ? 1 : 0;
}

int cd_h5r_verify(const cd_h5r *r, const char *path, cd_error *err)
{
    cd_h5_quiet q;
    verify_ctx c;
    herr_t rc;
    memset(&c, 0, sizeof c);
    cd_h5_quiet_begin(&q);
    rc = H5Ovisit2(FID(r), H5_INDEX_NAME, H5_ITER_NATIVE, verify_cb, &c, H5O_INFO_BASIC);
    cd_h5_quiet_end(&q);
    if (c.bad) {
        seterr(err, CD_EIO, "'%s': a damaged results file: dataset %s does not read (its chunk index or data is "
               "damaged; %ld samples committed)", path, c.path, r->n);
        return -1;
    }
    if (rc < 0) {
        seterr(err, CD_EIO, "'%s': a damaged results file: its groups cannot be listed", path);
        return -1;
    }
    return 0;
}
