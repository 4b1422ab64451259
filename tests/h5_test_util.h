/* HDF5 read helpers shared by the io tests (test_cli.c, test_h5.c): read a
 * results file's attributes and datasets back with Criterion assertions. */
#ifndef CD_TEST_H5_UTIL_H
#define CD_TEST_H5_UTIL_H
#include <criterion/criterion.h>
#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* An integer attribute of obj. */
static inline long long attr_ll(hid_t obj, const char *name)
{
    long long v = -1;
    hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
    cr_assert(a >= 0, "attribute %s", name);
    cr_assert(H5Aread(a, H5T_NATIVE_LLONG, &v) >= 0);
    H5Aclose(a);
    return v;
}

/* A double attribute of obj. */
static inline double attr_d(hid_t obj, const char *name)
{
    double v = NAN;
    hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
    cr_assert(a >= 0, "attribute %s", name);
    cr_assert(H5Aread(a, H5T_NATIVE_DOUBLE, &v) >= 0);
    H5Aclose(a);
    return v;
}

/* A string attribute of obj, read with its own (UTF-8) string type. */
static inline void attr_s(hid_t obj, const char *name, char *out, size_t n)
{
    hid_t a = H5Aopen(obj, name, H5P_DEFAULT), t, mt;
    char *tmp;
    size_t sz;
    cr_assert(a >= 0, "attribute %s", name);
    t = H5Aget_type(a);
    sz = H5Tget_size(t);
    mt = H5Tcopy(t); /* the file's own string type: its character set (UTF-8) */
    H5Tset_size(mt, sz + 1);
    tmp = calloc(1, sz + 2);
    cr_assert(H5Aread(a, mt, tmp) >= 0);
    snprintf(out, n, "%s", tmp);
    free(tmp);
    H5Tclose(mt);
    H5Tclose(t);
    H5Aclose(a);
}

/* The file's run_status is status and its run_message contains part. */
static inline void expect_run_status(hid_t f, const char *status, const char *part)
{
    char s[1100];
    attr_s(f, "run_status", s, sizeof s);
    cr_expect_str_eq(s, status);
    attr_s(f, "run_message", s, sizeof s);
    cr_expect(strstr(s, part) != NULL, "run_message '%s' names '%s'", s, part);
}

/* Dimensions of a dataset; returns its rank. */
static inline int dims_of(hid_t f, const char *path, hsize_t d[3])
{
    hid_t ds = H5Dopen2(f, path, H5P_DEFAULT), sp;
    int r;
    cr_assert(ds >= 0, "dataset %s", path);
    sp = H5Dget_space(ds);
    d[0] = d[1] = d[2] = 0;
    r = H5Sget_simple_extent_dims(sp, d, NULL);
    H5Sclose(sp);
    H5Dclose(ds);
    return r;
}

/* A whole dataset as doubles (malloc'd, *n values). */
static inline double *read_all(hid_t f, const char *path, size_t *n)
{
    hid_t ds = H5Dopen2(f, path, H5P_DEFAULT), sp;
    hssize_t np;
    double *v;
    cr_assert(ds >= 0, "dataset %s", path);
    sp = H5Dget_space(ds);
    np = H5Sget_simple_extent_npoints(sp);
    v = malloc((size_t)(np > 0 ? np : 1) * sizeof *v);
    if (np > 0) cr_assert(H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) >= 0);
    H5Sclose(sp);
    H5Dclose(ds);
    *n = (size_t)np;
    return v;
}

#endif
