/*
 * h5io.c - light field files: the atomic HDF5 writer, the validating reader
 * with partial reads, and lfio_verify() (format version 1, docs/format.md).
 *
 * This is the only source file that includes hdf5.h. Invariants:
 *   - Every public entry point silences HDF5's error printing for its whole
 *     duration and restores the caller's handler; HDF5 error stacks become
 *     lfio_errmsg() text "<path>: <object>: <problem>", and a stack that
 *     mentions a checksum becomes LFIO_ERR_CHECKSUM.
 *   - Nothing is allocated from a size found in a file before that size has
 *     been checked: the slab description against LFIO_SLAB_MAX_BYTES and
 *     lfio__check_desc(), and every dataset's type and shape against the
 *     description.
 *   - The layout of every dataset (name, type, shape, chunks, units, axes)
 *     comes from one function, ds_spec_make(), which the writer, the
 *     reader's checks and lfio_verify() all use, so they cannot disagree.
 *   - The derived datasets (direction, solid angles, position, mask) are
 *     produced and checked by one block-streaming function, so writing and
 *     verifying use the same recomputation and bounded memory.
 *   - A write either renames a complete, fsynced file over its target or
 *     leaves the target untouched and removes its temporary. HDF5 builds the
 *     file in memory and never writes to disk itself (see build_image()).
 *   - An lfio_reader keeps one open radiance dataset per slab and nothing
 *     else mutable, so reads on one reader only make HDF5 calls, which
 *     HDF5 serialises.
 */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <hdf5.h>

#include "internal.h"

#define FORMAT_NAME "ilfkit-lightfield"
#define FORMAT_VERSION 1
#define MAX_SLABS 65536
/* Bounds on strings read from files, so a hostile header cannot make us allocate much.
 * CREATOR_MAX is what lfio_lightfield_set_creator() holds, so every creator read can be kept. */
#define CREATOR_MAX 255
#define TEXT_MAX 1023
/* Elements per block when streaming the derived datasets (bounded memory at any n). */
#define BLOCK_ELEMS 196608
/* Absolute tolerance of lfio_verify() for recomputed doubles. */
#define VERIFY_TOL 1e-12
/* Growth step of the in-memory file image while writing. */
#define CORE_INCREMENT ((size_t)8 << 20)
/* Largest chunk cache given to one radiance dataset of a reader. */
#define READER_CACHE_MAX ((size_t)64 << 20)

#define FRAME_TEXT                                                                              \
    "right-handed, metres; e1 = u/|u|, e2 = v/|v|, e3 = e1 x e2 (slab normal, partition pole +z);" \
    " direction = propagation direction, front hemisphere w.e3 >= 0, ids 0..4n^2-1;"              \
    " position (i, j) at cell centre origin + (i+0.5)/nu*u + (j+0.5)/nv*v"

/* ------------------------------------------------------------ dataset layouts */

enum ds_kind { DS_RADIANCE, DS_DIRECTION, DS_SOLID_ANGLE, DS_PROJ_SOLID_ANGLE, DS_POSITION, DS_MASK };

/* The stored layout of one dataset of a slab. */
struct ds_spec {
    enum ds_kind kind;
    char name[32];          /* path below the slab's group */
    int rank;
    hsize_t dims[4];
    hsize_t chunk[4];
    H5T_class_t cls;        /* H5T_FLOAT or H5T_INTEGER (unsigned) */
    size_t size;            /* element size in bytes */
    const char *units;
    const char *axes;
    uint32_t mask_n;        /* partition level of a DS_MASK dataset */
};

#define MAX_SPECS (5 + LFIO_MAX_MASK_LEVELS)

/* @return the smaller of a and b. */
static hsize_t min_h(hsize_t a, hsize_t b)
{
    return a < b ? a : b;
}

/* @return the stored name of units u. */
static const char *units_name(lfio_units u)
{
    return u == LFIO_UNITS_RELATIVE ? "relative" : "W sr^-1 m^-2";
}

/* Lists the mask levels of partition level n, coarsest first: the halvings of n down to the first odd one. @return their number. */
static uint32_t mask_levels(uint32_t n, uint32_t levels[LFIO_MAX_MASK_LEVELS])
{
    uint32_t count = 0, m = n;
    for (;;) {
        count++;
        if (m % 2 != 0)
            break;
        m /= 2;
    }
    for (uint32_t k = 0; k < count; k++)
        levels[k] = m << k;
    return count;
}

/* Fills *sp with the layout of dataset kind of a slab described by d (mask_n only for DS_MASK). */
static void ds_spec_make(const lfio_slab_desc *d, enum ds_kind kind, uint32_t mask_n, struct ds_spec *sp)
{
    const hsize_t ndir = 4 * (hsize_t)d->n * d->n;
    memset(sp, 0, sizeof *sp);
    sp->kind = kind;
    sp->cls = H5T_FLOAT;
    sp->size = 8;
    switch (kind) {
    case DS_RADIANCE:
        /* Chunks of 32 directions x 16 x 16 positions: one direction's image and one
         * position's directions each touch a small fraction of the chunks. */
        snprintf(sp->name, sizeof sp->name, "radiance");
        sp->rank = 4;
        sp->dims[0] = ndir, sp->dims[1] = d->nv, sp->dims[2] = d->nu, sp->dims[3] = 3;
        sp->chunk[0] = min_h(ndir, 32), sp->chunk[1] = min_h(d->nv, 16);
        sp->chunk[2] = min_h(d->nu, 16), sp->chunk[3] = 3;
        sp->size = 4;
        sp->units = units_name(d->units);
        sp->axes = "dir:v:u:rgb";
        break;
    case DS_DIRECTION:
        snprintf(sp->name, sizeof sp->name, "direction");
        sp->rank = 2;
        sp->dims[0] = ndir, sp->dims[1] = 3;
        sp->chunk[0] = min_h(ndir, 8192), sp->chunk[1] = 3;
        sp->units = "1";
        sp->axes = "dir:xyz";
        break;
    case DS_SOLID_ANGLE:
    case DS_PROJ_SOLID_ANGLE:
        snprintf(sp->name, sizeof sp->name, "%s",
                 kind == DS_SOLID_ANGLE ? "solid_angle" : "projected_solid_angle");
        sp->rank = 1;
        sp->dims[0] = ndir;
        sp->chunk[0] = min_h(ndir, 16384);
        sp->units = "sr";
        sp->axes = "dir";
        break;
    case DS_POSITION:
        snprintf(sp->name, sizeof sp->name, "position");
        sp->rank = 3;
        sp->dims[0] = d->nv, sp->dims[1] = d->nu, sp->dims[2] = 3;
        sp->chunk[0] = min_h(d->nv, 64), sp->chunk[1] = min_h(d->nu, 64), sp->chunk[2] = 3;
        sp->units = "m";
        sp->axes = "v:u:xyz";
        break;
    case DS_MASK:
        snprintf(sp->name, sizeof sp->name, "mask/level_%u", mask_n);
        sp->rank = 1;
        sp->dims[0] = 4 * (hsize_t)mask_n * mask_n;
        sp->chunk[0] = min_h(sp->dims[0], 65536);
        sp->cls = H5T_INTEGER;
        sp->size = 1;
        sp->units = "1";
        sp->axes = "dir";
        sp->mask_n = mask_n;
        break;
    }
}

/* Fills sp with every dataset of a slab described by d, in file order. @return their number. */
static int slab_specs(const lfio_slab_desc *d, struct ds_spec sp[MAX_SPECS])
{
    static const enum ds_kind fixed[] = {DS_RADIANCE, DS_DIRECTION, DS_SOLID_ANGLE,
                                         DS_PROJ_SOLID_ANGLE, DS_POSITION};
    uint32_t levels[LFIO_MAX_MASK_LEVELS];
    uint32_t nlev = mask_levels(d->n, levels);
    int count = 0;
    for (size_t k = 0; k < sizeof fixed / sizeof fixed[0]; k++)
        ds_spec_make(d, fixed[k], 0, &sp[count++]);
    for (uint32_t k = 0; k < nlev; k++)
        ds_spec_make(d, DS_MASK, levels[k], &sp[count++]);
    return count;
}

/* @return the file datatype of sp (little-endian IEEE float or unsigned byte). */
static hid_t spec_file_type(const struct ds_spec *sp)
{
    if (sp->cls == H5T_INTEGER)
        return H5T_STD_U8LE;
    return sp->size == 4 ? H5T_IEEE_F32LE : H5T_IEEE_F64LE;
}

/* Writes "[a, b, ...]" for dims into buf. */
static void format_dims(char *buf, size_t size, int rank, const hsize_t *dims)
{
    size_t used = 0;
    used += (size_t)snprintf(buf, size, "[");
    for (int k = 0; k < rank && used < size; k++)
        used += (size_t)snprintf(buf + used, size - used, "%s%llu", k ? ", " : "",
                                 (unsigned long long)dims[k]);
    if (used < size)
        snprintf(buf + used, size - used, "]");
}

/* -------------------------------------------------------- HDF5 error handling */

/* The caller's HDF5 automatic error handler, saved while lfio is silent. */
struct h5_quiet {
    H5E_auto2_t func;
    void *data;
};

/* Saves the calling thread's HDF5 error printer and turns printing off. */
static void quiet_begin(struct h5_quiet *q)
{
    q->func = NULL;
    q->data = NULL;
    H5Eget_auto2(H5E_DEFAULT, &q->func, &q->data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}

/* Restores the printer saved by quiet_begin(). */
static void quiet_end(const struct h5_quiet *q)
{
    H5Eset_auto2(H5E_DEFAULT, q->func, q->data);
}

/* What the HDF5 error stack says about the last failure. */
struct stack_info {
    int checksum;       /* some record reports a checksum mismatch */
    char reason[160];   /* the innermost record's description */
};

/* @return 1 if text contains "checksum" in any letter case. */
static int mentions_checksum(const char *text)
{
    static const char word[] = "checksum";
    for (; text && *text; text++) {
        size_t k = 0;
        while (word[k] && text[k] && (text[k] | 0x20) == word[k])
            k++;
        if (!word[k])
            return 1;
    }
    return 0;
}

/* H5Ewalk2 visitor: notes checksum records and keeps the innermost description. */
static herr_t stack_visit(unsigned n, const H5E_error2_t *e, void *data)
{
    struct stack_info *si = data;
    /* HDF5 1.10 reports a Fletcher32 failure as "data error detected by Fletcher32
     * checksum" (Data storage / Read failed) and a metadata one as "incorrect
     * metadata checksum ...": the word is the stable part of both. */
    if (mentions_checksum(e->desc) || mentions_checksum(e->func_name))
        si->checksum = 1;
    if (n == 0 && e->desc)
        snprintf(si->reason, sizeof si->reason, "%s", e->desc);
    return 0;
}

/*
 * Records a failure of the HDF5 call just made, as "<path>: <obj>: <what> (<reason>)".
 * Must be called before any other HDF5 call, which would clear the stack.
 * @return LFIO_ERR_CHECKSUM if the stack reports a checksum mismatch, else st.
 */
static lfio_status h5_fail(lfio_status st, const char *path, const char *obj, const char *what)
{
    struct stack_info si = {0, ""};
    H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, stack_visit, &si);
    if (si.checksum)
        return lfio__fail(LFIO_ERR_CHECKSUM, "%s: %s: checksum mismatch (%s)", path, obj, what);
    if (si.reason[0])
        return lfio__fail(st, "%s: %s: %s (%s)", path, obj, what, si.reason);
    return lfio__fail(st, "%s: %s: %s", path, obj, what);
}

/* Closes any HDF5 identifier; invalid (negative) ids are ignored, which keeps cleanup paths simple. */
static void close_id(hid_t id)
{
    if (id < 0)
        return;
    switch (H5Iget_type(id)) {
    case H5I_FILE: H5Fclose(id); break;
    case H5I_GROUP: H5Gclose(id); break;
    case H5I_DATASET: H5Dclose(id); break;
    case H5I_ATTR: H5Aclose(id); break;
    case H5I_DATATYPE: H5Tclose(id); break;
    case H5I_DATASPACE: H5Sclose(id); break;
    case H5I_GENPROP_LST: H5Pclose(id); break;
    default: break;
    }
}

/* @return the index of the first value of v[0..count) that is negative, NaN or infinite; count if none. */
static size_t first_bad_value(const float *v, size_t count)
{
    for (size_t k = 0; k < count; k++)
        if (!(v[k] >= 0.0f && v[k] <= 3.4028234663852886e38f))
            return k;
    return count;
}

/*
 * Transfers the hyperslab [start, start+count) of dset to or from buf (packed,
 * row-major) as memory type mtype. obj names dset in messages.
 * @return LFIO_OK; LFIO_ERR_IO or LFIO_ERR_CHECKSUM with the message set.
 */
static lfio_status xfer_block(const char *path, const char *obj, hid_t dset, int write, hid_t mtype,
                              int rank, const hsize_t *start, const hsize_t *count, void *buf)
{
    hsize_t nelem = 1;
    for (int k = 0; k < rank; k++)
        nelem *= count[k];
    lfio_status st = LFIO_OK;
    hid_t fspace = H5Dget_space(dset);
    hid_t mspace = H5Screate_simple(1, &nelem, NULL);
    herr_t rc = -1;
    if (fspace >= 0 && mspace >= 0
        && H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start, NULL, count, NULL) >= 0)
        rc = write ? H5Dwrite(dset, mtype, mspace, fspace, H5P_DEFAULT, buf)
                   : H5Dread(dset, mtype, mspace, fspace, H5P_DEFAULT, buf);
    if (rc < 0) /* before closing: any HDF5 call clears the error stack */
        st = h5_fail(LFIO_ERR_IO, path, obj, write ? "cannot write" : "cannot read");
    close_id(mspace);
    close_id(fspace);
    return st;
}

/* ----------------------------------------------------------------- attributes */

/* Creates attribute name on id with file type ftype over space and writes buf (memory type mtype). */
static lfio_status put_attr(const char *path, const char *obj, hid_t id, const char *name, hid_t ftype,
                            hid_t space, hid_t mtype, const void *buf)
{
    lfio_status st = LFIO_OK;
    hid_t a = H5Acreate2(id, name, ftype, space, H5P_DEFAULT, H5P_DEFAULT);
    if (a < 0 || H5Awrite(a, mtype, buf) < 0) {
        char what[96];
        snprintf(what, sizeof what, "cannot write attribute '%s'", name);
        st = h5_fail(LFIO_ERR_IO, path, obj, what);
    }
    close_id(a);
    return st;
}

/* Writes string attribute name = value as a fixed-length, NUL-terminated string (ASCII unless value is not). */
static lfio_status put_str_attr(const char *path, const char *obj, hid_t id, const char *name,
                                const char *value)
{
    int ascii = 1;
    for (const unsigned char *c = (const unsigned char *)value; *c; c++)
        ascii &= *c < 128;
    hid_t t = H5Tcopy(H5T_C_S1);
    hid_t space = H5Screate(H5S_SCALAR);
    lfio_status st;
    if (t < 0 || space < 0 || H5Tset_size(t, strlen(value) + 1) < 0
        || H5Tset_strpad(t, H5T_STR_NULLTERM) < 0
        || H5Tset_cset(t, ascii ? H5T_CSET_ASCII : H5T_CSET_UTF8) < 0)
        st = h5_fail(LFIO_ERR_IO, path, obj, "cannot make a string type");
    else
        st = put_attr(path, obj, id, name, t, space, t, value);
    close_id(space);
    close_id(t);
    return st;
}

/* Writes a numeric attribute: a scalar when count is 0, else a 1-D array of count values. */
static lfio_status put_num_attr(const char *path, const char *obj, hid_t id, const char *name,
                                hid_t ftype, hid_t mtype, hsize_t count, const void *value)
{
    hid_t space = count ? H5Screate_simple(1, &count, NULL) : H5Screate(H5S_SCALAR);
    lfio_status st = space < 0 ? h5_fail(LFIO_ERR_IO, path, obj, "cannot make a dataspace")
                               : put_attr(path, obj, id, name, ftype, space, mtype, value);
    close_id(space);
    return st;
}

/*
 * Opens attribute name of id and checks that it holds count elements (count 1:
 * a scalar or [1]; otherwise a 1-D array) of class cls, each at most max_size bytes.
 * @return LFIO_OK and *out; LFIO_ERR_FORMAT (or what HDF5 reports) with *out = -1.
 */
static lfio_status open_attr(const char *path, const char *obj, hid_t id, const char *name,
                             H5T_class_t cls, hssize_t count, size_t max_size, hid_t *out)
{
    static const char *const class_names[] = {"integer", "float", "time", "string", "bitfield",
                                              "opaque", "compound", "reference", "enum",
                                              "variable-length", "array"};
    *out = -1;
    htri_t exists = H5Aexists(id, name);
    if (exists < 0)
        return h5_fail(LFIO_ERR_FORMAT, path, obj, "cannot list attributes");
    if (exists == 0)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: missing attribute '%s'", path, obj, name);
    hid_t a = H5Aopen(id, name, H5P_DEFAULT);
    if (a < 0) {
        char what[96];
        snprintf(what, sizeof what, "cannot open attribute '%s'", name);
        return h5_fail(LFIO_ERR_FORMAT, path, obj, what);
    }
    hid_t t = H5Aget_type(a), space = H5Aget_space(a);
    H5T_class_t got = t < 0 ? H5T_NO_CLASS : H5Tget_class(t);
    size_t size = t < 0 ? 0 : H5Tget_size(t);
    int rank = space < 0 ? -1 : H5Sget_simple_extent_ndims(space);
    hssize_t npoints = space < 0 ? -1 : H5Sget_simple_extent_npoints(space);
    int is_vlen = got == H5T_STRING && H5Tis_variable_str(t) > 0;
    close_id(space);
    close_id(t);
    lfio_status st = LFIO_OK;
    if (got != cls) {
        int known = got >= 0 && (size_t)got < sizeof class_names / sizeof class_names[0];
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: attribute '%s' is of class %s, expected %s", path,
                        obj, name, known ? class_names[got] : "unknown", class_names[cls]);
    } else if (rank < 0 || rank > 1 || npoints != count || (rank == 0 && count != 1)) {
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: attribute '%s' has %lld elements in %d dimensions, expected %lld",
                        path, obj, name, (long long)npoints, rank, (long long)count);
    } else if (!is_vlen && (size == 0 || size > max_size)) {
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: attribute '%s' has elements of %zu bytes, at most %zu allowed",
                        path, obj, name, size, max_size);
    }
    if (st != LFIO_OK)
        close_id(a);
    else
        *out = a;
    return st;
}

/*
 * Reads string attribute name of id (fixed or variable length) of at most max_len bytes.
 * @return LFIO_OK and *out (malloc'd, the caller frees); an error with *out = NULL.
 */
static lfio_status get_str_attr(const char *path, const char *obj, hid_t id, const char *name,
                                size_t max_len, char **out)
{
    *out = NULL;
    hid_t a;
    /* A fixed-length string of max_len characters may carry its NUL: max_len + 1 bytes. */
    lfio_status st = open_attr(path, obj, id, name, H5T_STRING, 1, max_len + 1, &a);
    if (st != LFIO_OK)
        return st;
    hid_t ftype = H5Aget_type(a);
    hid_t mtype = H5Tcopy(ftype);
    char what[96];
    snprintf(what, sizeof what, "cannot read attribute '%s'", name);
    if (ftype < 0 || mtype < 0) {
        st = h5_fail(LFIO_ERR_FORMAT, path, obj, what);
    } else if (H5Tis_variable_str(ftype) > 0) {
        /* The memory type copies the file's character set: HDF5 refuses to convert between sets. */
        char *text = NULL;
        if (H5Aread(a, mtype, &text) < 0 || text == NULL)
            st = h5_fail(LFIO_ERR_FORMAT, path, obj, what);
        else if (strlen(text) > max_len)
            st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: attribute '%s' is longer than %zu bytes",
                            path, obj, name, max_len);
        else if ((*out = malloc(strlen(text) + 1)) == NULL)
            st = lfio__fail(LFIO_ERR_NOMEM, "%s: %s: out of memory", path, obj);
        else
            strcpy(*out, text);
        if (text)
            H5free_memory(text);
    } else {
        size_t size = H5Tget_size(ftype); /* checked <= max_len + 1 by open_attr() */
        *out = calloc(size + 1, 1);
        if (*out == NULL)
            st = lfio__fail(LFIO_ERR_NOMEM, "%s: %s: out of memory", path, obj);
        else if (H5Aread(a, mtype, *out) < 0)
            st = h5_fail(LFIO_ERR_FORMAT, path, obj, what);
        else if (strlen(*out) > max_len)
            st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: attribute '%s' is longer than %zu bytes",
                            path, obj, name, max_len);
    }
    close_id(mtype);
    close_id(ftype);
    close_id(a);
    if (st != LFIO_OK) {
        free(*out);
        *out = NULL;
    }
    return st;
}

/* Checks that string attribute name of id equals expected. @return LFIO_OK or LFIO_ERR_FORMAT. */
static lfio_status expect_str_attr(const char *path, const char *obj, hid_t id, const char *name,
                                   const char *expected)
{
    char *text;
    lfio_status st = get_str_attr(path, obj, id, name, TEXT_MAX, &text);
    if (st == LFIO_OK && strcmp(text, expected) != 0)
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: attribute '%s' is '%s', expected '%s'", path, obj,
                        name, text, expected);
    free(text);
    return st;
}

/* Reads count doubles from float attribute name of id and checks that they are finite. */
static lfio_status get_f64_attr(const char *path, const char *obj, hid_t id, const char *name,
                                hssize_t count, double *out)
{
    hid_t a;
    lfio_status st = open_attr(path, obj, id, name, H5T_FLOAT, count, 8, &a);
    if (st != LFIO_OK)
        return st;
    if (H5Aread(a, H5T_NATIVE_DOUBLE, out) < 0) {
        char what[96];
        snprintf(what, sizeof what, "cannot read attribute '%s'", name);
        st = h5_fail(LFIO_ERR_FORMAT, path, obj, what);
    }
    for (hssize_t k = 0; st == LFIO_OK && k < count; k++)
        if (!isfinite(out[k]))
            st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: attribute '%s' is not finite", path, obj, name);
    close_id(a);
    return st;
}

/* Reads scalar integer attribute name of id (any width up to 64 bits) and checks lo <= value <= hi. */
static lfio_status get_int_attr(const char *path, const char *obj, hid_t id, const char *name,
                                int64_t lo, int64_t hi, int64_t *out)
{
    hid_t a;
    lfio_status st = open_attr(path, obj, id, name, H5T_INTEGER, 1, 8, &a);
    if (st != LFIO_OK)
        return st;
    /* HDF5 clips out-of-range values on conversion, and clipped values fail the range test. */
    if (H5Aread(a, H5T_NATIVE_INT64, out) < 0) {
        char what[96];
        snprintf(what, sizeof what, "cannot read attribute '%s'", name);
        st = h5_fail(LFIO_ERR_FORMAT, path, obj, what);
    } else if (*out < lo || *out > hi) {
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: attribute '%s' = %lld is outside [%lld, %lld]",
                        path, obj, name, (long long)*out, (long long)lo, (long long)hi);
    }
    close_id(a);
    return st;
}

/* ------------------------------------------------------------ derived datasets */

/* One pass over a derived dataset: writing recomputed values, or comparing stored ones with them. */
struct stream {
    const char *path;
    const char *obj;          /* the dataset's full name, for messages */
    const lfio_slab *s;
    const struct ds_spec *sp;
    hid_t dset;
    int verify;               /* 0: write; 1: read and compare */
    uint64_t mismatches;      /* verify: values off by more than VERIFY_TOL */
    char first[192];          /* verify: the first mismatch, described */
};

/*
 * Computes the values dataset sp of slab s must hold in the block starting at
 * start: `rows` rows along its block axis (directions, or u for position),
 * each of its trailing values (3 for vectors, 1 otherwise).
 */
static void fill_expected(const lfio_slab *s, const struct ds_spec *sp, const hsize_t *start,
                          hsize_t rows, double *out)
{
    for (hsize_t r = 0; r < rows; r++) {
        uint64_t id = start[0] + r;
        double c[3];
        switch (sp->kind) {
        case DS_DIRECTION:
            lfio_part_centroid(s->desc.n, id, c);
            lfio_slab_to_world(s, c, out + 3 * r);
            break;
        case DS_SOLID_ANGLE:
            out[r] = s->solid_angle[id];
            break;
        case DS_PROJ_SOLID_ANGLE:
            out[r] = s->proj_solid_angle[id];
            break;
        case DS_POSITION: /* block axis is u: rows are i at fixed j = start[0] */
            lfio_slab_position(s, (uint32_t)(start[1] + r), (uint32_t)start[0], out + 3 * r);
            break;
        case DS_MASK:
            out[r] = lfio_slab_mask_test(s, sp->mask_n, id) ? 1.0 : 0.0;
            break;
        case DS_RADIANCE: /* stored, not derived */
            break;
        }
    }
}

/* Compares one block; counts values off by more than VERIFY_TOL and describes the first. */
static void compare_block(struct stream *j, const hsize_t *start, int b, hsize_t inner,
                          const double *want, const double *got, hsize_t nelem)
{
    for (hsize_t e = 0; e < nelem; e++) {
        /* Written so that NaN counts as a mismatch. */
        if (fabs(got[e] - want[e]) <= VERIFY_TOL)
            continue;
        if (j->mismatches++ == 0) {
            hsize_t at[3] = {start[0], start[1], start[2]};
            at[b] += e / inner;
            if (inner > 1)
                at[b + 1] = e % inner;
            char idx[64];
            format_dims(idx, sizeof idx, j->sp->rank, at);
            snprintf(j->first, sizeof j->first, "at %s stored %.17g, expected %.17g", idx, got[e],
                     want[e]);
        }
    }
}

/*
 * Streams derived dataset j->sp block by block (BLOCK_ELEMS values at a time):
 * writes the recomputed values, or with j->verify reads the stored ones and
 * compares. Blocks run along the direction axis, or along u inside each row
 * j of position.
 * @return LFIO_OK; LFIO_ERR_NOMEM, LFIO_ERR_IO or LFIO_ERR_CHECKSUM.
 */
static lfio_status stream_derived(struct stream *j)
{
    const struct ds_spec *sp = j->sp;
    const int b = sp->rank == 3 ? 1 : 0;
    const hsize_t outer = b ? sp->dims[0] : 1;
    const hsize_t inner = sp->rank > b + 1 ? sp->dims[b + 1] : 1;
    const hsize_t rows_per_block = BLOCK_ELEMS / inner;
    double *want = malloc(BLOCK_ELEMS * sizeof *want);
    double *got = j->verify ? malloc(BLOCK_ELEMS * sizeof *got) : NULL;
    lfio_status st = LFIO_OK;
    if (want == NULL || (j->verify && got == NULL))
        st = lfio__fail(LFIO_ERR_NOMEM, "%s: %s: out of memory", j->path, j->obj);
    for (hsize_t o = 0; st == LFIO_OK && o < outer; o++) {
        for (hsize_t r0 = 0; st == LFIO_OK && r0 < sp->dims[b]; r0 += rows_per_block) {
            hsize_t start[3] = {0, 0, 0}, count[3] = {sp->dims[0], sp->dims[1], sp->dims[2]};
            if (b) {
                start[0] = o;
                count[0] = 1;
            }
            start[b] = r0;
            count[b] = min_h(rows_per_block, sp->dims[b] - r0);
            fill_expected(j->s, sp, start, count[b], want);
            st = xfer_block(j->path, j->obj, j->dset, !j->verify, H5T_NATIVE_DOUBLE, sp->rank, start,
                            count, j->verify ? (void *)got : (void *)want);
            if (st == LFIO_OK && j->verify)
                compare_block(j, start, b, inner, want, got, count[b] * inner);
        }
    }
    free(got);
    free(want);
    return st;
}

/* ----------------------------------------------------------------- writing */

/* Creates dataset sp in slab group g, chunked with checksums (compressed for radiance), with units and axes. */
static lfio_status create_dataset(const char *path, const char *gobj, hid_t g,
                                  const struct ds_spec *sp, hid_t *out)
{
    char obj[128];
    snprintf(obj, sizeof obj, "%s/%s", gobj, sp->name);
    *out = -1;
    lfio_status st = LFIO_OK;
    hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    hid_t space = H5Screate_simple(sp->rank, sp->dims, NULL);
    /* Fletcher32 goes last so it covers the bytes as stored and is checked first on reading. */
    int ok = lcpl >= 0 && dcpl >= 0 && space >= 0
             && H5Pset_create_intermediate_group(lcpl, 1) >= 0 /* makes "mask" */
             && H5Pset_chunk(dcpl, sp->rank, sp->chunk) >= 0
             && (sp->kind != DS_RADIANCE
                 || (H5Pset_shuffle(dcpl) >= 0 && H5Pset_deflate(dcpl, 4) >= 0))
             && H5Pset_fletcher32(dcpl) >= 0;
    if (ok)
        *out = H5Dcreate2(g, sp->name, spec_file_type(sp), space, lcpl, dcpl, H5P_DEFAULT);
    if (*out < 0)
        st = h5_fail(LFIO_ERR_IO, path, obj, "cannot create dataset");
    close_id(space);
    close_id(dcpl);
    close_id(lcpl);
    if (st == LFIO_OK)
        st = put_str_attr(path, obj, *out, "units", sp->units);
    if (st == LFIO_OK)
        st = put_str_attr(path, obj, *out, "axes", sp->axes);
    if (st == LFIO_OK && sp->kind == DS_MASK)
        st = put_num_attr(path, obj, *out, "n", H5T_STD_U32LE, H5T_NATIVE_UINT32, 0, &sp->mask_n);
    if (st != LFIO_OK) {
        close_id(*out);
        *out = -1;
    }
    return st;
}

/* Writes the attributes of slab group g (obj) describing slab s. */
static lfio_status write_slab_attrs(const char *path, const char *obj, hid_t g, const lfio_slab *s)
{
    const lfio_slab_desc *d = &s->desc;
    lfio_status st = put_str_attr(path, obj, g, "name", d->name);
    if (st == LFIO_OK)
        st = put_num_attr(path, obj, g, "origin", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 3, d->origin);
    if (st == LFIO_OK)
        st = put_num_attr(path, obj, g, "u", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 3, d->u);
    if (st == LFIO_OK)
        st = put_num_attr(path, obj, g, "v", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 3, d->v);
    if (st == LFIO_OK)
        st = put_str_attr(path, obj, g, "length_units", "m");
    if (st == LFIO_OK)
        st = put_num_attr(path, obj, g, "nu", H5T_STD_U32LE, H5T_NATIVE_UINT32, 0, &d->nu);
    if (st == LFIO_OK)
        st = put_num_attr(path, obj, g, "nv", H5T_STD_U32LE, H5T_NATIVE_UINT32, 0, &d->nv);
    if (st == LFIO_OK)
        st = put_num_attr(path, obj, g, "n", H5T_STD_U32LE, H5T_NATIVE_UINT32, 0, &d->n);
    if (st == LFIO_OK)
        st = put_str_attr(path, obj, g, "radiance_units", units_name(d->units));
    if (st == LFIO_OK)
        st = put_str_attr(path, obj, g, "colour_space", "linear Rec.709");
    if (st == LFIO_OK)
        st = put_num_attr(path, obj, g, "mask_threshold", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, 0,
                          &d->mask_threshold);
    if (st == LFIO_OK)
        st = put_str_attr(path, obj, g, "frame", FRAME_TEXT);
    return st;
}

/* Reports an invalid radiance value of slab k at (dir, i, j). @return st. */
static lfio_status bad_value_fail(lfio_status st, const char *path, size_t k, uint64_t dir,
                                  uint64_t i, uint64_t j, float value)
{
    return lfio__fail(st, "%s: /slabs/%zu/radiance: invalid value %g at dir %llu, i %llu, j %llu",
                      path, k, (double)value, (unsigned long long)dir, (unsigned long long)i,
                      (unsigned long long)j);
}

/* Checks a whole slab's radiance array. @return LFIO_OK or st (with the message naming dir, i, j). */
static lfio_status check_radiance(lfio_status st, const char *path, size_t k, const lfio_slab *s)
{
    const size_t total = (size_t)(s->ndir * s->npos * 3);
    size_t p = first_bad_value(s->radiance, total);
    if (p == total)
        return LFIO_OK;
    uint64_t q = p / 3, dir = q / s->npos, ij = q % s->npos;
    return bad_value_fail(st, path, k, dir, ij % s->desc.nu, ij / s->desc.nu, s->radiance[p]);
}

/* Writes slab s as group /slabs/k of the file whose "slabs" group is slabs. */
static lfio_status write_slab(const char *path, hid_t slabs, size_t k, const lfio_slab *s)
{
    char obj[64], name[24];
    snprintf(name, sizeof name, "%zu", k);
    snprintf(obj, sizeof obj, "/slabs/%zu", k);
    /* A slab broken in memory must not become a file the reader rejects. */
    lfio_status st = check_radiance(LFIO_ERR_ARG, path, k, s);
    struct ds_spec specs[MAX_SPECS];
    int nspecs = slab_specs(&s->desc, specs);
    uint32_t nlev = (uint32_t)nspecs - 5;
    /* The file's mask levels follow the header's rule; the slab must agree, or the masks written would be wrong. */
    if (st == LFIO_OK && lfio_slab_mask_levels(s) != nlev)
        st = lfio__fail(LFIO_ERR_ARG, "%s: %s: slab has %u mask levels, expected %u", path, obj,
                        lfio_slab_mask_levels(s), nlev);
    for (uint32_t m = 0; st == LFIO_OK && m < nlev; m++)
        if (lfio_slab_mask_n(s, m) != specs[5 + m].mask_n)
            st = lfio__fail(LFIO_ERR_ARG, "%s: %s: mask level %u is n = %u, expected %u", path, obj,
                            m, lfio_slab_mask_n(s, m), specs[5 + m].mask_n);
    if (st != LFIO_OK)
        return st;
    hid_t g = H5Gcreate2(slabs, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (g < 0)
        return h5_fail(LFIO_ERR_IO, path, obj, "cannot create group");
    st = write_slab_attrs(path, obj, g, s);
    for (int t = 0; st == LFIO_OK && t < nspecs; t++) {
        hid_t d;
        char dobj[128];
        snprintf(dobj, sizeof dobj, "%s/%s", obj, specs[t].name);
        st = create_dataset(path, obj, g, &specs[t], &d);
        if (st != LFIO_OK)
            break;
        if (specs[t].kind == DS_RADIANCE) {
            const hsize_t zero[4] = {0, 0, 0, 0};
            st = xfer_block(path, dobj, d, 1, H5T_NATIVE_FLOAT, 4, zero, specs[t].dims, s->radiance);
        } else {
            struct stream j = {path, dobj, s, &specs[t], d, 0, 0, ""};
            st = stream_derived(&j);
        }
        /* Closing flushes the chunk cache: the last chunks reach the file only here. */
        if (H5Dclose(d) < 0 && st == LFIO_OK)
            st = h5_fail(LFIO_ERR_IO, path, dobj, "cannot flush dataset");
    }
    if (H5Gclose(g) < 0 && st == LFIO_OK)
        st = h5_fail(LFIO_ERR_IO, path, obj, "cannot close group");
    return st;
}

/* Writes the root attributes and every slab of lf into the open, empty file. */
static lfio_status write_contents(const char *path, hid_t file, const lfio_lightfield *lf)
{
    const int32_t version = FORMAT_VERSION;
    const int32_t count = (int32_t)lfio_lightfield_slab_count(lf);
    lfio_status st = put_str_attr(path, "/", file, "format", FORMAT_NAME);
    if (st == LFIO_OK)
        st = put_num_attr(path, "/", file, "format_version", H5T_STD_I32LE, H5T_NATIVE_INT32, 0, &version);
    if (st == LFIO_OK)
        st = put_str_attr(path, "/", file, "creator", lfio_lightfield_creator(lf));
    if (st == LFIO_OK)
        st = put_num_attr(path, "/", file, "slab_count", H5T_STD_I32LE, H5T_NATIVE_INT32, 0, &count);
    if (st != LFIO_OK)
        return st;
    hid_t slabs = H5Gcreate2(file, "slabs", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (slabs < 0)
        return h5_fail(LFIO_ERR_IO, path, "/slabs", "cannot create group");
    for (size_t k = 0; st == LFIO_OK && k < (size_t)count; k++)
        st = write_slab(path, slabs, k, lfio_lightfield_slab(lf, k));
    close_id(slabs);
    return st;
}

/* @return x rotated left by k bits (0 < k < 32). */
static uint32_t rotl32(uint32_t x, int k)
{
    return (x << k) | (x >> (32 - k));
}

/* @return the 4 bytes at p as a little-endian number. */
static uint32_t le32(const unsigned char *p)
{
    return p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* @return Jenkins' lookup3 hash (hashlittle, seed 0) of len bytes: HDF5's metadata checksum. */
static uint32_t metadata_checksum(const unsigned char *k, size_t len)
{
    uint32_t a, b, c;
    a = b = c = 0xdeadbeefu + (uint32_t)len;
    for (; len > 12; len -= 12, k += 12) {
        a += le32(k), b += le32(k + 4), c += le32(k + 8);
        a -= c, a ^= rotl32(c, 4), c += b;
        b -= a, b ^= rotl32(a, 6), a += c;
        c -= b, c ^= rotl32(b, 8), b += a;
        a -= c, a ^= rotl32(c, 16), c += b;
        b -= a, b ^= rotl32(a, 19), a += c;
        c -= b, c ^= rotl32(b, 4), b += a;
    }
    if (len == 0)
        return c;
    uint32_t w[3] = {0, 0, 0}; /* the last 1..12 bytes, zero-padded */
    for (size_t i = 0; i < len; i++)
        w[i / 4] += (uint32_t)k[i] << (8 * (i % 4));
    a += w[0], b += w[1], c += w[2];
    c ^= b, c -= rotl32(b, 14);
    a ^= c, a -= rotl32(c, 11);
    b ^= a, b -= rotl32(a, 25);
    c ^= b, c -= rotl32(b, 16);
    a ^= c, a -= rotl32(c, 4);
    b ^= a, b -= rotl32(a, 14);
    c ^= b, c -= rotl32(b, 24);
    return c;
}

/*
 * Repairs the superblock of an image from H5Fget_file_image(): HDF5 1.10.8
 * clears the "open for writing" status flags in the copy but leaves the old
 * checksum, so the image would not open. Recomputing it gives the bytes a
 * normal H5Fclose would have written (checked by comparing whole files).
 * Superblocks before version 2 have no checksum and need nothing.
 * @return LFIO_OK; LFIO_ERR_IO if the image does not start with a superblock.
 */
static lfio_status finish_superblock(const char *path, unsigned char *image, size_t size)
{
    static const unsigned char signature[8] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};
    if (size < 12 || memcmp(image, signature, sizeof signature) != 0)
        return lfio__fail(LFIO_ERR_IO, "%s: /: file image lacks a superblock", path);
    /* Versions 2 and 3: signature, version, offset size O, length size, flags,
     * four addresses of O bytes, then the checksum of everything before it. */
    unsigned version = image[8], offset_size = image[9];
    size_t covered = 12 + 4 * (size_t)offset_size;
    if (version < 2)
        return LFIO_OK;
    if (version > 3 || (offset_size != 4 && offset_size != 8) || size < covered + 4)
        return lfio__fail(LFIO_ERR_IO, "%s: /: unexpected superblock version %u", path, version);
    uint32_t sum = metadata_checksum(image, covered);
    for (int k = 0; k < 4; k++)
        image[covered + k] = (unsigned char)(sum >> (8 * k));
    return LFIO_OK;
}

/*
 * Builds the whole file in memory with HDF5's core driver (no backing store)
 * and returns its bytes. HDF5 1.10 cannot recover from a failed write to a
 * real file: a flush failing inside H5Dclose/H5Fclose leaves a freed file
 * registered, and the process crashes at exit (HDFFV-11052, fixed in 1.14.1).
 * In memory nothing can fail that way; the bytes then go to disk through
 * write_all(), whose errors are ordinary. The cost: memory about the size of
 * the file, twice over while the image is copied out.
 * @return LFIO_OK and *image (malloc'd), *size; an error with *image = NULL.
 */
static lfio_status build_image(const char *path, const char *name, const lfio_lightfield *lf,
                               unsigned char **image, size_t *size)
{
    *image = NULL;
    *size = 0;
    lfio_status st = LFIO_OK;
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    /* Version 1.8+ structures carry metadata checksums; strong close releases every
     * object with the file, so no forgotten id outlives it. */
    if (fapl < 0 || H5Pset_fapl_core(fapl, CORE_INCREMENT, 0) < 0
        || H5Pset_libver_bounds(fapl, H5F_LIBVER_V110, H5F_LIBVER_LATEST) < 0
        || H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG) < 0)
        st = h5_fail(LFIO_ERR_IO, path, "/", "cannot set file access properties");
    /* name only identifies the in-memory file: the core driver creates nothing on disk. */
    hid_t file = st == LFIO_OK ? H5Fcreate(name, H5F_ACC_TRUNC, H5P_DEFAULT, fapl) : -1;
    if (st == LFIO_OK && file < 0)
        st = h5_fail(LFIO_ERR_IO, path, "/", "cannot create the file in memory");
    close_id(fapl);
    if (st == LFIO_OK)
        st = write_contents(path, file, lf);
    ssize_t bytes = -1;
    /* H5Fget_file_image copies what has reached the driver: flush the metadata cache first. */
    if (st == LFIO_OK && H5Fflush(file, H5F_SCOPE_GLOBAL) < 0)
        st = h5_fail(LFIO_ERR_IO, path, "/", "cannot flush the file in memory");
    if (st == LFIO_OK && (bytes = H5Fget_file_image(file, NULL, 0)) <= 0)
        st = h5_fail(LFIO_ERR_IO, path, "/", "cannot finish the file image");
    if (st == LFIO_OK && (*image = malloc((size_t)bytes)) == NULL)
        st = lfio__fail(LFIO_ERR_NOMEM, "%s: no memory for a file image of %zd bytes", path, bytes);
    if (st == LFIO_OK && H5Fget_file_image(file, *image, (size_t)bytes) != bytes)
        st = h5_fail(LFIO_ERR_IO, path, "/", "cannot copy the file image");
    if (st == LFIO_OK)
        st = finish_superblock(path, *image, (size_t)bytes);
    if (file >= 0 && H5Fclose(file) < 0 && st == LFIO_OK)
        st = h5_fail(LFIO_ERR_IO, path, "/", "cannot close the file in memory");
    if (st != LFIO_OK) {
        free(*image);
        *image = NULL;
    } else {
        *size = (size_t)bytes;
    }
    return st;
}

/* Writes size bytes of data to fd, resuming after partial writes and signals. @return 0 or an errno value. */
static int write_all(int fd, const unsigned char *data, size_t size)
{
    while (size > 0) {
        ssize_t n = write(fd, data, size);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return n < 0 ? errno : EIO;
        data += n;
        size -= (size_t)n;
    }
    return 0;
}

/* fsyncs folder dir so that a rename inside it is durable. @return 0 or an errno value. */
static int sync_folder(const char *dir)
{
    int fd = open(dir, O_RDONLY | O_DIRECTORY);
    if (fd < 0)
        return errno;
    int err = fsync(fd) == 0 ? 0 : errno;
    close(fd);
    return err;
}

/* @return the folder holding path (malloc'd; "." for a bare name), or NULL when out of memory. */
static char *folder_of(const char *path)
{
    const char *slash = strrchr(path, '/');
    size_t len = slash == NULL ? 0 : slash == path ? 1 : (size_t)(slash - path);
    char *dir = malloc(len ? len + 1 : 2);
    if (dir == NULL)
        return NULL;
    if (len)
        memcpy(dir, path, len), dir[len] = '\0';
    else
        strcpy(dir, ".");
    return dir;
}

/* Creates an empty temporary "path.tmp-XXXXXX" beside path. @return LFIO_OK, *tmp (malloc'd) and open *fd; LFIO_ERR_IO. */
static lfio_status make_temp(const char *path, char **tmp, int *fd)
{
    static const char suffix[] = ".tmp-XXXXXX";
    *fd = -1;
    *tmp = malloc(strlen(path) + sizeof suffix);
    if (*tmp == NULL)
        return lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", path);
    strcpy(*tmp, path);
    strcat(*tmp, suffix);
    *fd = mkstemp(*tmp);
    if (*fd < 0) {
        int err = errno;
        free(*tmp);
        *tmp = NULL;
        return lfio__fail(LFIO_ERR_IO, "%s: cannot create a temporary file beside it: %s", path,
                          strerror(err));
    }
    /* mkstemp makes the file private (0600); a replaced file keeps its mode, a new one is 0644. */
    struct stat old;
    fchmod(*fd, stat(path, &old) == 0 && S_ISREG(old.st_mode) ? (old.st_mode & 0777) : 0644);
    return LFIO_OK;
}

/* Builds the file in memory, writes it to a temporary beside path, fsyncs, renames it over path and fsyncs the folder. */
lfio_status lfio_lightfield_write(const lfio_lightfield *lf, const char *path)
{
    if (lf == NULL || path == NULL || path[0] == '\0')
        return lfio__fail(LFIO_ERR_ARG, "lfio_lightfield_write: NULL light field or empty path");
    if (lfio_lightfield_slab_count(lf) == 0)
        return lfio__fail(LFIO_ERR_ARG, "%s: refusing to write a light field without slabs", path);
    if (lfio_lightfield_slab_count(lf) > MAX_SLABS)
        return lfio__fail(LFIO_ERR_ARG, "%s: %zu slabs, at most %d allowed", path,
                          lfio_lightfield_slab_count(lf), MAX_SLABS);
    if (strlen(lfio_lightfield_creator(lf)) > CREATOR_MAX)
        return lfio__fail(LFIO_ERR_ARG, "%s: creator longer than %d bytes", path, CREATOR_MAX);
    struct h5_quiet q;
    quiet_begin(&q);
    char *tmp = NULL, *dir = NULL;
    unsigned char *image = NULL;
    size_t size = 0;
    int fd = -1, err = 0;
    lfio_status st = make_temp(path, &tmp, &fd);
    if (st == LFIO_OK)
        st = build_image(path, tmp, lf, &image, &size);
    if (st == LFIO_OK && ((err = write_all(fd, image, size)) != 0 || (err = fsync(fd) ? errno : 0) != 0))
        st = lfio__fail(LFIO_ERR_IO, "%s: cannot write the temporary file: %s", path, strerror(err));
    free(image);
    if (fd >= 0 && close(fd) != 0 && st == LFIO_OK)
        st = lfio__fail(LFIO_ERR_IO, "%s: cannot close the temporary file: %s", path, strerror(errno));
    if (st == LFIO_OK && rename(tmp, path) != 0)
        st = lfio__fail(LFIO_ERR_IO, "%s: cannot rename the temporary file over it: %s", path,
                        strerror(errno));
    if (st != LFIO_OK && tmp != NULL)
        remove(tmp);
    /* The rename is only durable once the folder's entry is on disk. */
    if (st == LFIO_OK && ((dir = folder_of(path)) == NULL || (err = sync_folder(dir)) != 0))
        st = lfio__fail(LFIO_ERR_IO, "%s: written, but cannot flush its folder: %s", path,
                        dir ? strerror(err) : "out of memory");
    free(dir);
    free(tmp);
    quiet_end(&q);
    return st;
}

/* ----------------------------------------------------------------- reading */

struct lfio_reader {
    char *path;               /* as given, for messages */
    hid_t file;
    int version;
    char *creator;
    size_t nslabs;
    lfio_slab_desc *desc;     /* nslabs, each passed lfio__check_desc() */
    hid_t *radiance;          /* nslabs open radiance datasets, shapes checked */
};

/* Checks that path names a readable regular file in HDF5 format, before HDF5 opens it. */
static lfio_status check_file(const char *path)
{
    struct stat sb;
    if (stat(path, &sb) != 0) {
        int err = errno;
        return lfio__fail(err == ENOENT || err == ENOTDIR ? LFIO_ERR_NOTFOUND : LFIO_ERR_IO,
                          "%s: cannot open: %s", path, strerror(err));
    }
    if (!S_ISREG(sb.st_mode))
        return lfio__fail(LFIO_ERR_FORMAT, "%s: not a regular file", path);
    int fd = open(path, O_RDONLY);
    if (fd < 0)
        return lfio__fail(LFIO_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    close(fd);
    /* The file is readable, so a failing signature search means "not HDF5", not an I/O error. */
    if (H5Fis_hdf5(path) <= 0)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: not an HDF5 file", path);
    return LFIO_OK;
}

/* Reads and checks the root attributes into r (version, creator, slab count). */
static lfio_status read_root(lfio_reader *r)
{
    int64_t version, count;
    lfio_status st = expect_str_attr(r->path, "/", r->file, "format", FORMAT_NAME);
    if (st == LFIO_OK)
        st = get_int_attr(r->path, "/", r->file, "format_version", INT32_MIN, INT32_MAX, &version);
    if (st == LFIO_OK && version > FORMAT_VERSION)
        st = lfio__fail(LFIO_ERR_FORMAT,
                        "%s: /: format_version %lld is newer than this library reads (version %d)",
                        r->path, (long long)version, FORMAT_VERSION);
    if (st == LFIO_OK && version < 1)
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: /: invalid format_version %lld", r->path, (long long)version);
    if (st == LFIO_OK)
        st = get_str_attr(r->path, "/", r->file, "creator", CREATOR_MAX, &r->creator);
    if (st == LFIO_OK)
        st = get_int_attr(r->path, "/", r->file, "slab_count", 1, MAX_SLABS, &count);
    if (st == LFIO_OK) {
        r->version = (int)version;
        r->nslabs = (size_t)count;
    }
    return st;
}

/* Reads the attributes of slab group g (obj) into *d, and checks the units and colour space. */
static lfio_status read_desc(const char *path, const char *obj, hid_t g, lfio_slab_desc *d)
{
    char *text = NULL;
    int64_t nu = 0, nv = 0, n = 0;
    double threshold = 0;
    memset(d, 0, sizeof *d);
    lfio_status st = get_str_attr(path, obj, g, "name", LFIO_NAME_MAX, &text);
    if (st == LFIO_OK)
        strcpy(d->name, text);
    free(text);
    text = NULL;
    if (st == LFIO_OK)
        st = get_f64_attr(path, obj, g, "origin", 3, d->origin);
    if (st == LFIO_OK)
        st = get_f64_attr(path, obj, g, "u", 3, d->u);
    if (st == LFIO_OK)
        st = get_f64_attr(path, obj, g, "v", 3, d->v);
    if (st == LFIO_OK)
        st = expect_str_attr(path, obj, g, "length_units", "m");
    if (st == LFIO_OK)
        st = get_int_attr(path, obj, g, "nu", 1, UINT32_MAX, &nu);
    if (st == LFIO_OK)
        st = get_int_attr(path, obj, g, "nv", 1, UINT32_MAX, &nv);
    if (st == LFIO_OK)
        st = get_int_attr(path, obj, g, "n", 1, LFIO_SLAB_MAX_N, &n);
    if (st == LFIO_OK)
        st = get_str_attr(path, obj, g, "radiance_units", TEXT_MAX, &text);
    if (st == LFIO_OK) {
        if (strcmp(text, units_name(LFIO_UNITS_RADIANCE)) == 0)
            d->units = LFIO_UNITS_RADIANCE;
        else if (strcmp(text, units_name(LFIO_UNITS_RELATIVE)) == 0)
            d->units = LFIO_UNITS_RELATIVE;
        else
            st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: unknown radiance_units '%s'", path, obj, text);
    }
    free(text);
    text = NULL;
    if (st == LFIO_OK)
        st = expect_str_attr(path, obj, g, "colour_space", "linear Rec.709");
    if (st == LFIO_OK)
        st = get_f64_attr(path, obj, g, "mask_threshold", 1, &threshold);
    if (st == LFIO_OK && (threshold < 0 || threshold > 3.4028234663852886e38))
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: mask_threshold %g out of range", path, obj, threshold);
    /* frame is documentation for readers: it must exist, its text is not parsed. */
    if (st == LFIO_OK)
        st = get_str_attr(path, obj, g, "frame", TEXT_MAX, &text);
    free(text);
    d->nu = (uint32_t)nu;
    d->nv = (uint32_t)nv;
    d->n = (uint32_t)n;
    d->mask_threshold = (float)threshold;
    return st;
}

/* Checks desc d of slab obj against the radiance size limit, then lfio__check_desc(). */
static lfio_status check_slab_desc(const char *path, const char *obj, const lfio_slab_desc *d)
{
    uint64_t bytes = 0;
    int fits = lfio__mul_u64(4 * (uint64_t)d->n, d->n, &bytes) && lfio__mul_u64(bytes, d->nu, &bytes)
               && lfio__mul_u64(bytes, d->nv, &bytes) && lfio__mul_u64(bytes, 3 * sizeof(float), &bytes);
    if (!fits || bytes > LFIO_SLAB_MAX_BYTES)
        return lfio__fail(LFIO_ERR_NOMEM,
                          "%s: %s: radiance of %u x %u positions at level %u exceeds the limit of %llu bytes",
                          path, obj, d->nu, d->nv, d->n, (unsigned long long)LFIO_SLAB_MAX_BYTES);
    char why[256] = "";
    if (lfio__check_desc(d, why, sizeof why) != LFIO_OK)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: invalid slab: %s", path, obj, why);
    if (!lfio__valid_name(d->name))
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: invalid slab name '%s'", path, obj, d->name);
    return LFIO_OK;
}

/* @return a dataset access list whose chunk cache holds one direction's or one position's chunks (capped). */
static hid_t radiance_dapl(const struct ds_spec *sp)
{
    hsize_t nchunk[4];
    for (int k = 0; k < 4; k++)
        nchunk[k] = (sp->dims[k] + sp->chunk[k] - 1) / sp->chunk[k];
    size_t chunk_bytes = (size_t)(sp->chunk[0] * sp->chunk[1] * sp->chunk[2] * sp->chunk[3] * sp->size);
    /* Reading directions in order re-reads each chunk chunk[0] times: cache a whole
     * direction's row of chunks (or a position's column) so that happens in memory. */
    hsize_t want = nchunk[1] * nchunk[2] > nchunk[0] ? nchunk[1] * nchunk[2] : nchunk[0];
    size_t bytes = want > READER_CACHE_MAX / chunk_bytes ? READER_CACHE_MAX : (size_t)want * chunk_bytes;
    if (bytes < ((size_t)1 << 20))
        bytes = (size_t)1 << 20;
    size_t slots = (bytes / chunk_bytes) * 100 + 1; /* HDF5 advises ~100 slots per cached chunk */
    hid_t dapl = H5Pcreate(H5P_DATASET_ACCESS);
    if (dapl >= 0)
        H5Pset_chunk_cache(dapl, slots, bytes, H5D_CHUNK_CACHE_W0_DEFAULT);
    return dapl;
}

/* Describes an element type for messages, e.g. "float of 8 bytes". */
static void describe_type(char *buf, size_t size, H5T_class_t cls, size_t elem)
{
    snprintf(buf, size, "%s of %zu bytes",
             cls == H5T_FLOAT ? "float" : cls == H5T_INTEGER ? "integer" : "non-numeric type", elem);
}

/*
 * Opens dataset sp of slab group g (gobj) and checks its class, element size,
 * rank, dims, units and axes (and n of a mask level) without reading data.
 * @return LFIO_OK and *out open if out is not NULL; LFIO_ERR_FORMAT.
 */
static lfio_status check_dataset(const char *path, const char *gobj, hid_t g, const struct ds_spec *sp,
                                 hid_t dapl, hid_t *out)
{
    char obj[128], got[64], want[64];
    snprintf(obj, sizeof obj, "%s/%s", gobj, sp->name);
    if (out)
        *out = -1;
    /* H5Lexists fails rather than answering 0 when an intermediate group is missing. */
    if (sp->kind == DS_MASK && H5Lexists(g, "mask", H5P_DEFAULT) <= 0)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s/mask: missing group", path, gobj);
    if (H5Lexists(g, sp->name, H5P_DEFAULT) <= 0)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: missing dataset", path, obj);
    hid_t d = H5Dopen2(g, sp->name, dapl >= 0 ? dapl : H5P_DEFAULT);
    if (d < 0)
        return h5_fail(LFIO_ERR_FORMAT, path, obj, "cannot open as a dataset");
    hid_t t = H5Dget_type(d), space = H5Dget_space(d);
    H5T_class_t cls = t < 0 ? H5T_NO_CLASS : H5Tget_class(t);
    size_t elem = t < 0 ? 0 : H5Tget_size(t);
    int simple = space >= 0 && H5Sget_simple_extent_type(space) == H5S_SIMPLE;
    int rank = simple ? H5Sget_simple_extent_ndims(space) : -1;
    hsize_t dims[H5S_MAX_RANK];
    if (rank >= 0 && rank <= H5S_MAX_RANK && H5Sget_simple_extent_dims(space, dims, NULL) < 0)
        rank = -1;
    close_id(space);
    close_id(t);
    lfio_status st = LFIO_OK;
    int same_dims = rank == sp->rank;
    for (int k = 0; same_dims && k < rank; k++)
        same_dims = dims[k] == sp->dims[k];
    if (cls != sp->cls || elem != sp->size) {
        describe_type(got, sizeof got, cls, elem);
        describe_type(want, sizeof want, sp->cls, sp->size);
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: element type is %s, expected %s", path, obj, got, want);
    } else if (!same_dims) {
        if (rank >= 0)
            format_dims(got, sizeof got, rank, dims);
        else
            snprintf(got, sizeof got, "not a simple array");
        format_dims(want, sizeof want, sp->rank, sp->dims);
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: dims mismatch: shape %s, expected %s from the slab's attributes",
                        path, obj, got, want);
    }
    if (st == LFIO_OK)
        st = expect_str_attr(path, obj, d, "units", sp->units);
    if (st == LFIO_OK)
        st = expect_str_attr(path, obj, d, "axes", sp->axes);
    if (st == LFIO_OK && sp->kind == DS_MASK) {
        int64_t m;
        st = get_int_attr(path, obj, d, "n", sp->mask_n, sp->mask_n, &m);
    }
    if (st == LFIO_OK && out)
        *out = d;
    else
        close_id(d);
    return st;
}

/* Opens group /slabs/k, reads and checks its description into r->desc[k], checks every dataset and keeps radiance open. */
static lfio_status open_slab(lfio_reader *r, hid_t slabs, size_t k)
{
    char obj[64], name[24];
    snprintf(name, sizeof name, "%zu", k);
    snprintf(obj, sizeof obj, "/slabs/%zu", k);
    if (H5Lexists(slabs, name, H5P_DEFAULT) <= 0)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: missing slab group (slab_count is %zu)", r->path,
                          obj, r->nslabs);
    hid_t g = H5Gopen2(slabs, name, H5P_DEFAULT);
    if (g < 0)
        return h5_fail(LFIO_ERR_FORMAT, r->path, obj, "cannot open as a group");
    lfio_status st = read_desc(r->path, obj, g, &r->desc[k]);
    if (st == LFIO_OK)
        st = check_slab_desc(r->path, obj, &r->desc[k]);
    struct ds_spec specs[MAX_SPECS];
    int nspecs = st == LFIO_OK ? slab_specs(&r->desc[k], specs) : 0;
    for (int t = 0; st == LFIO_OK && t < nspecs; t++) {
        int keep = specs[t].kind == DS_RADIANCE;
        hid_t dapl = keep ? radiance_dapl(&specs[t]) : -1;
        st = check_dataset(r->path, obj, g, &specs[t], dapl, keep ? &r->radiance[k] : NULL);
        close_id(dapl);
    }
    close_id(g);
    return st;
}

/* Closes everything r holds and frees it. */
static void reader_free(lfio_reader *r)
{
    if (r == NULL)
        return;
    for (size_t k = 0; r->radiance && k < r->nslabs; k++)
        close_id(r->radiance[k]);
    close_id(r->file);
    free(r->radiance);
    free(r->desc);
    free(r->creator);
    free(r->path);
    free(r);
}

/* lfio_reader_open() without silencing HDF5: the body shared with lfio_lightfield_read() and lfio_verify(). */
static lfio_status reader_open_impl(const char *path, lfio_reader **out)
{
    *out = NULL;
    lfio_status st = check_file(path);
    if (st != LFIO_OK)
        return st;
    lfio_reader *r = calloc(1, sizeof *r);
    if (r == NULL || (r->path = malloc(strlen(path) + 1)) == NULL) {
        free(r);
        return lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", path);
    }
    strcpy(r->path, path);
    r->file = -1;
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    if (fapl >= 0)
        H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG);
    r->file = H5Fopen(path, H5F_ACC_RDONLY, fapl >= 0 ? fapl : H5P_DEFAULT);
    if (r->file < 0)
        st = h5_fail(LFIO_ERR_FORMAT, path, "/", "cannot open as HDF5");
    close_id(fapl);
    if (st == LFIO_OK)
        st = read_root(r);
    /* nslabs <= MAX_SLABS here, so these allocations are bounded. */
    if (st == LFIO_OK && ((r->desc = calloc(r->nslabs, sizeof *r->desc)) == NULL
                          || (r->radiance = malloc(r->nslabs * sizeof *r->radiance)) == NULL))
        st = lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", path);
    for (size_t k = 0; st == LFIO_OK && k < r->nslabs; k++)
        r->radiance[k] = -1;
    hid_t slabs = -1;
    if (st == LFIO_OK && H5Lexists(r->file, "slabs", H5P_DEFAULT) <= 0)
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: /slabs: missing group", path);
    if (st == LFIO_OK && (slabs = H5Gopen2(r->file, "slabs", H5P_DEFAULT)) < 0)
        st = h5_fail(LFIO_ERR_FORMAT, path, "/slabs", "cannot open as a group");
    for (size_t k = 0; st == LFIO_OK && k < r->nslabs; k++)
        st = open_slab(r, slabs, k);
    close_id(slabs);
    if (st != LFIO_OK)
        reader_free(r);
    else
        *out = r;
    return st;
}

/* Checks r and slab index k of a public call. @return LFIO_OK or LFIO_ERR_ARG. */
static lfio_status check_slab_arg(const lfio_reader *r, size_t k, const void *buf, const char *fn)
{
    if (r == NULL || buf == NULL)
        return lfio__fail(LFIO_ERR_ARG, "%s: NULL argument", fn);
    if (k >= r->nslabs)
        return lfio__fail(LFIO_ERR_ARG, "%s: %s: slab %zu out of range (%zu slabs)", r->path, fn, k,
                          r->nslabs);
    return LFIO_OK;
}

/* Reads slab k whole into a new slab, checking values and rebuilding its mask (HDF5 not silenced). */
static lfio_status read_slab_impl(lfio_reader *r, size_t k, lfio_slab **out)
{
    *out = NULL;
    lfio_slab *s = NULL;
    lfio_status st = lfio_slab_new(&r->desc[k], &s);
    if (st != LFIO_OK) {
        char why[256];
        snprintf(why, sizeof why, "%s", lfio_errmsg()); /* lfio__fail overwrites lfio_errmsg()'s buffer */
        return lfio__fail(st, "%s: /slabs/%zu: %s", r->path, k, why);
    }
    char obj[64];
    snprintf(obj, sizeof obj, "/slabs/%zu/radiance", k);
    struct ds_spec sp;
    ds_spec_make(&r->desc[k], DS_RADIANCE, 0, &sp);
    const hsize_t zero[4] = {0, 0, 0, 0};
    st = xfer_block(r->path, obj, r->radiance[k], 0, H5T_NATIVE_FLOAT, 4, zero, sp.dims, s->radiance);
    if (st == LFIO_OK)
        st = check_radiance(LFIO_ERR_FORMAT, r->path, k, s);
    if (st != LFIO_OK) {
        lfio_slab_destroy(s);
        return st;
    }
    lfio__slab_rebuild_mask(s);
    *out = s;
    return LFIO_OK;
}

/* Opens path and checks all its metadata (see reader_open_impl()), silently. */
lfio_status lfio_reader_open(const char *path, lfio_reader **out)
{
    if (out == NULL)
        return lfio__fail(LFIO_ERR_ARG, "lfio_reader_open: NULL argument");
    *out = NULL;
    if (path == NULL || path[0] == '\0')
        return lfio__fail(LFIO_ERR_ARG, "lfio_reader_open: NULL or empty path");
    struct h5_quiet q;
    quiet_begin(&q);
    lfio_status st = reader_open_impl(path, out);
    quiet_end(&q);
    return st;
}

/* Closes the file and frees the reader; NULL is a no-op. */
void lfio_reader_close(lfio_reader *r)
{
    struct h5_quiet q;
    if (r == NULL)
        return;
    quiet_begin(&q);
    reader_free(r);
    quiet_end(&q);
}

/* @return the number of slabs; 0 for NULL. */
size_t lfio_reader_slab_count(const lfio_reader *r)
{
    return r ? r->nslabs : 0;
}

/* @return slab k's checked description, or NULL. */
const lfio_slab_desc *lfio_reader_slab_desc(const lfio_reader *r, size_t k)
{
    return r && k < r->nslabs ? &r->desc[k] : NULL;
}

/* @return the stored creator string; "" for NULL. */
const char *lfio_reader_creator(const lfio_reader *r)
{
    return r ? r->creator : "";
}

/* @return the stored format version; 0 for NULL. */
int lfio_reader_format_version(const lfio_reader *r)
{
    return r ? r->version : 0;
}

/* Reads radiance[dir, :, :, :] of slab k through a hyperslab, then checks the values. */
lfio_status lfio_reader_read_direction(lfio_reader *r, size_t k, uint64_t dir, float *img)
{
    lfio_status st = check_slab_arg(r, k, img, "lfio_reader_read_direction");
    if (st != LFIO_OK)
        return st;
    const lfio_slab_desc *d = &r->desc[k];
    const uint64_t ndir = 4 * (uint64_t)d->n * d->n;
    if (dir >= ndir)
        return lfio__fail(LFIO_ERR_ARG, "%s: /slabs/%zu: direction %llu out of range (%llu)", r->path,
                          k, (unsigned long long)dir, (unsigned long long)ndir);
    char obj[64];
    snprintf(obj, sizeof obj, "/slabs/%zu/radiance", k);
    const hsize_t start[4] = {dir, 0, 0, 0}, count[4] = {1, d->nv, d->nu, 3};
    struct h5_quiet q;
    quiet_begin(&q);
    st = xfer_block(r->path, obj, r->radiance[k], 0, H5T_NATIVE_FLOAT, 4, start, count, img);
    quiet_end(&q);
    const size_t total = (size_t)d->nu * d->nv * 3;
    size_t p = st == LFIO_OK ? first_bad_value(img, total) : total;
    if (p < total)
        st = bad_value_fail(LFIO_ERR_FORMAT, r->path, k, dir, (p / 3) % d->nu, (p / 3) / d->nu, img[p]);
    return st;
}

/* Reads radiance[:, j, i, :] of slab k through a hyperslab, then checks the values. */
lfio_status lfio_reader_read_position(lfio_reader *r, size_t k, uint32_t i, uint32_t j, float *rgb)
{
    lfio_status st = check_slab_arg(r, k, rgb, "lfio_reader_read_position");
    if (st != LFIO_OK)
        return st;
    const lfio_slab_desc *d = &r->desc[k];
    if (i >= d->nu || j >= d->nv)
        return lfio__fail(LFIO_ERR_ARG, "%s: /slabs/%zu: position (%u, %u) outside %u x %u", r->path, k,
                          i, j, d->nu, d->nv);
    const uint64_t ndir = 4 * (uint64_t)d->n * d->n;
    char obj[64];
    snprintf(obj, sizeof obj, "/slabs/%zu/radiance", k);
    const hsize_t start[4] = {0, j, i, 0}, count[4] = {ndir, 1, 1, 3};
    struct h5_quiet q;
    quiet_begin(&q);
    st = xfer_block(r->path, obj, r->radiance[k], 0, H5T_NATIVE_FLOAT, 4, start, count, rgb);
    quiet_end(&q);
    const size_t total = (size_t)ndir * 3;
    size_t p = st == LFIO_OK ? first_bad_value(rgb, total) : total;
    if (p < total)
        st = bad_value_fail(LFIO_ERR_FORMAT, r->path, k, p / 3, i, j, rgb[p]);
    return st;
}

/* Reads slab k whole (see read_slab_impl()), silently. */
lfio_status lfio_reader_read_slab(lfio_reader *r, size_t k, lfio_slab **out)
{
    if (out == NULL)
        return lfio__fail(LFIO_ERR_ARG, "lfio_reader_read_slab: NULL argument");
    *out = NULL;
    lfio_status st = check_slab_arg(r, k, out, "lfio_reader_read_slab");
    if (st != LFIO_OK)
        return st;
    struct h5_quiet q;
    quiet_begin(&q);
    st = read_slab_impl(r, k, out);
    quiet_end(&q);
    return st;
}

/* lfio_lightfield_read() without silencing HDF5. */
static lfio_status lightfield_read_impl(const char *path, lfio_lightfield **out)
{
    lfio_reader *r = NULL;
    lfio_lightfield *lf = NULL;
    lfio_status st = reader_open_impl(path, &r);
    if (st == LFIO_OK && lfio_lightfield_new(&lf) != LFIO_OK)
        st = lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", path);
    if (st == LFIO_OK && lfio_lightfield_set_creator(lf, r->creator) != LFIO_OK)
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: /: creator rejected by lfio_lightfield_set_creator", path);
    for (size_t k = 0; st == LFIO_OK && k < r->nslabs; k++) {
        lfio_slab *s;
        st = read_slab_impl(r, k, &s);
        /* Names were checked one by one; only a repeat is left for take_slab to refuse. */
        if (st == LFIO_OK && lfio_lightfield_take_slab(lf, s) != LFIO_OK)
            st = lfio__fail(LFIO_ERR_FORMAT, "%s: /slabs/%zu: slab name '%s' is used twice", path, k,
                            r->desc[k].name);
    }
    reader_free(r);
    if (st != LFIO_OK)
        lfio_lightfield_destroy(lf);
    else
        *out = lf;
    return st;
}

/* Reads every slab of path into a new light field, silently. */
lfio_status lfio_lightfield_read(const char *path, lfio_lightfield **out)
{
    if (out == NULL)
        return lfio__fail(LFIO_ERR_ARG, "lfio_lightfield_read: NULL argument");
    *out = NULL;
    if (path == NULL || path[0] == '\0')
        return lfio__fail(LFIO_ERR_ARG, "lfio_lightfield_read: NULL or empty path");
    struct h5_quiet q;
    quiet_begin(&q);
    lfio_status st = lightfield_read_impl(path, out);
    quiet_end(&q);
    return st;
}

/* ---------------------------------------------------------------- verifying */

/* Problems found by lfio_verify() so far. */
struct vstate {
    lfio_status status;   /* of the first problem */
    uint32_t problems;
    char first[512];
};

/* Counts one problem, whose message is the current lfio_errmsg(); keeps the first. */
static void note(struct vstate *v, lfio_status st)
{
    if (v->problems++ == 0) {
        v->status = st;
        snprintf(v->first, sizeof v->first, "%s", lfio_errmsg());
    }
}

/* Checks that dataset d (obj) is stored with a Fletcher32 checksum; notes a problem if not. */
static void verify_checksummed(struct vstate *v, const char *path, const char *obj, hid_t d)
{
    hid_t dcpl = H5Dget_create_plist(d);
    unsigned flags = 0, conf = 0;
    size_t nvals = 0;
    char fname[16];
    herr_t rc = dcpl < 0 ? -1
                         : H5Pget_filter_by_id2(dcpl, H5Z_FILTER_FLETCHER32, &flags, &nvals, NULL,
                                                sizeof fname, fname, &conf);
    close_id(dcpl);
    if (rc < 0)
        note(v, lfio__fail(LFIO_ERR_FORMAT, "%s: %s: stored without a fletcher32 checksum", path, obj));
}

/* Verifies slab k: reads its radiance, then checks every dataset's checksum filter and derived values. */
static void verify_slab(struct vstate *v, lfio_reader *r, size_t k)
{
    lfio_slab *s = NULL;
    lfio_status st = read_slab_impl(r, k, &s);
    if (st != LFIO_OK) {
        note(v, st);
        return;
    }
    char gobj[64];
    snprintf(gobj, sizeof gobj, "/slabs/%zu", k);
    hid_t g = H5Gopen2(r->file, gobj, H5P_DEFAULT);
    if (g < 0) {
        note(v, h5_fail(LFIO_ERR_FORMAT, r->path, gobj, "cannot open as a group"));
        lfio_slab_destroy(s);
        return;
    }
    struct ds_spec specs[MAX_SPECS];
    int nspecs = slab_specs(&s->desc, specs);
    for (int t = 0; t < nspecs; t++) {
        char obj[128];
        snprintf(obj, sizeof obj, "%s/%s", gobj, specs[t].name);
        hid_t d = H5Dopen2(g, specs[t].name, H5P_DEFAULT);
        if (d < 0) {
            note(v, h5_fail(LFIO_ERR_FORMAT, r->path, obj, "cannot open as a dataset"));
            continue;
        }
        verify_checksummed(v, r->path, obj, d);
        if (specs[t].kind != DS_RADIANCE) {
            struct stream j = {r->path, obj, s, &specs[t], d, 1, 0, ""};
            st = stream_derived(&j);
            if (st != LFIO_OK)
                note(v, st);
            else if (j.mismatches)
                note(v, lfio__fail(LFIO_ERR_FORMAT, "%s: %s: %llu values differ from recomputed ones, first %s",
                                   r->path, obj, (unsigned long long)j.mismatches, j.first));
        }
        close_id(d);
    }
    H5G_info_t info;
    uint32_t nlev = (uint32_t)nspecs - 5;
    if (H5Gget_info_by_name(g, "mask", &info, H5P_DEFAULT) < 0)
        note(v, h5_fail(LFIO_ERR_FORMAT, r->path, gobj, "cannot list the mask group"));
    else if (info.nlinks != nlev)
        note(v, lfio__fail(LFIO_ERR_FORMAT, "%s: %s/mask: holds %llu objects, expected %u mask levels",
                           r->path, gobj, (unsigned long long)info.nlinks, nlev));
    close_id(g);
    lfio_slab_destroy(s);
}

/* Opens path, reads every slab and compares every derived dataset; counts problems, returns the first one's status. */
lfio_status lfio_verify(const char *path, lfio_verify_report *report)
{
    struct vstate v = {LFIO_OK, 0, ""};
    if (path == NULL || path[0] == '\0') {
        note(&v, lfio__fail(LFIO_ERR_ARG, "lfio_verify: NULL or empty path"));
    } else {
        struct h5_quiet q;
        quiet_begin(&q);
        lfio_reader *r = NULL;
        lfio_status st = reader_open_impl(path, &r);
        if (st != LFIO_OK)
            note(&v, st);
        for (size_t k = 0; r && k < r->nslabs; k++)
            verify_slab(&v, r, k);
        reader_free(r);
        quiet_end(&q);
    }
    if (report) {
        report->problems = v.problems;
        snprintf(report->first, sizeof report->first, "%s", v.first);
    }
    /* Later problems overwrote lfio_errmsg(); the contract is that it tells the first. */
    if (v.problems)
        lfio__fail(v.status, "%s", v.first);
    return v.status;
}
