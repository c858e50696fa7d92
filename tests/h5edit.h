/*
 * h5edit.h - HDF5 file surgery for the tests that check what lfio refuses
 * (test_lightfield_io.c, test_radmap.c): replacing or deleting attributes,
 * overwriting one element, replacing a dataset. Each call opens the file,
 * edits and closes it, and CHECKs that the edit took. Include after check.h.
 */
#ifndef ILF_TEST_H5EDIT_H
#define ILF_TEST_H5EDIT_H

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <hdf5.h>

#include "check.h"

/* Opens path for editing. @return the file id (negative on failure, which is checked). */
static inline hid_t edit_open(const char *path)
{
    hid_t f = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
    CHECK(f >= 0, "cannot open %s for editing", path);
    return f;
}

/* Replaces attribute name of object obj with a value of file type ftype (scalar when count is 0). */
static inline void edit_attr(const char *path, const char *obj, const char *name, hid_t ftype, hid_t mtype,
                             hsize_t count, const void *value)
{
    hid_t f = edit_open(path);
    hid_t o = H5Oopen(f, obj, H5P_DEFAULT);
    if (H5Aexists(o, name) > 0)
        H5Adelete(o, name);
    hid_t space = count ? H5Screate_simple(1, &count, NULL) : H5Screate(H5S_SCALAR);
    hid_t a = H5Acreate2(o, name, ftype, space, H5P_DEFAULT, H5P_DEFAULT);
    CHECK(a >= 0 && H5Awrite(a, mtype, value) >= 0, "edit %s %s@%s", path, obj, name);
    H5Aclose(a);
    H5Sclose(space);
    H5Oclose(o);
    H5Fclose(f);
}

/* Replaces string attribute name of obj with value. */
static inline void edit_attr_str(const char *path, const char *obj, const char *name, const char *value)
{
    hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, strlen(value) + 1);
    edit_attr(path, obj, name, t, t, 0, value);
    H5Tclose(t);
}

/* Removes attribute name of obj. */
static inline void edit_delete_attr(const char *path, const char *obj, const char *name)
{
    hid_t f = edit_open(path);
    CHECK(H5Adelete_by_name(f, obj, name, H5P_DEFAULT) >= 0, "delete %s@%s", obj, name);
    H5Fclose(f);
}

/* Selects element at[] (one coordinate per dimension, at most 4) of d's dataspace. @return the space. */
static inline hid_t edit_select(hid_t d, const hsize_t *at)
{
    static const hsize_t one[4] = {1, 1, 1, 1};
    hid_t fs = H5Dget_space(d);
    H5Sselect_hyperslab(fs, H5S_SELECT_SET, at, NULL, one, NULL);
    return fs;
}

/* Overwrites element at[] of dataset dset with a double value. */
static inline void edit_element(const char *path, const char *dset, const hsize_t *at, double value)
{
    const hsize_t n1 = 1;
    hid_t f = edit_open(path);
    hid_t d = H5Dopen2(f, dset, H5P_DEFAULT);
    hid_t fs = edit_select(d, at), ms = H5Screate_simple(1, &n1, NULL);
    CHECK(H5Dwrite(d, H5T_NATIVE_DOUBLE, ms, fs, H5P_DEFAULT, &value) >= 0, "edit %s", dset);
    H5Sclose(ms);
    H5Sclose(fs);
    H5Dclose(d);
    H5Fclose(f);
}

/* @return element at[] of dataset dset as a double (NAN on failure). */
static inline double peek_element(const char *path, const char *dset, const hsize_t *at)
{
    const hsize_t n1 = 1;
    double value = NAN;
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    hid_t d = H5Dopen2(f, dset, H5P_DEFAULT);
    hid_t fs = edit_select(d, at), ms = H5Screate_simple(1, &n1, NULL);
    H5Dread(d, H5T_NATIVE_DOUBLE, ms, fs, H5P_DEFAULT, &value);
    H5Sclose(ms);
    H5Sclose(fs);
    H5Dclose(d);
    H5Fclose(f);
    return value;
}

/* Replaces dataset dset (full path) by one of type ftype and shape dims, every element *fill (fill NULL: never
 * written, so HDF5's fill value 0 and no storage), with attributes units and axes. */
static inline void edit_replace_dataset(const char *path, const char *dset, hid_t ftype, int rank,
                                        const hsize_t *dims, const double *fill, const char *units,
                                        const char *axes)
{
    hid_t f = edit_open(path);
    CHECK(H5Ldelete(f, dset, H5P_DEFAULT) >= 0, "delete %s", dset);
    hid_t space = H5Screate_simple(rank, dims, NULL);
    hid_t d = H5Dcreate2(f, dset, ftype, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    CHECK(d >= 0, "create %s", dset);
    if (fill != NULL) {
        hsize_t count = 1;
        for (int k = 0; k < rank; k++)
            count *= dims[k];
        double *values = malloc((count ? count : 1) * sizeof *values);
        for (hsize_t k = 0; values != NULL && k < count; k++)
            values[k] = *fill;
        CHECK(values != NULL && H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values) >= 0,
              "fill %s", dset);
        free(values);
    }
    H5Sclose(space);
    H5Dclose(d);
    H5Fclose(f);
    edit_attr_str(path, dset, "units", units);
    edit_attr_str(path, dset, "axes", axes);
}

#endif /* ILF_TEST_H5EDIT_H */
