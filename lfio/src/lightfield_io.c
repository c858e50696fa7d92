/*
 * lightfield_io.c - light field files: the atomic HDF5 writer, the validating reader
 * with partial reads, and lfio_verify() (format version 1, docs/format.md).
 *
 * The HDF5 plumbing it shares with radmap_io.c (error translation,
 * attributes, dataset layouts, the atomic writer) is in h5util.c. Invariants:
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
 *   - A slab's coverage dataset is optional: written when the light field
 *     has coverage for the slab, checked (type, shape, values 0 or 1) when a
 *     file has one, never required, so files without it stay valid. So is
 *     its coverage_fraction attribute (a finite number in [0, 1]).
 *   - The derived datasets (direction, solid angles, position, mask) are
 *     produced and checked by one block-streaming function, so writing and
 *     verifying use the same recomputation and bounded memory.
 *   - A write either renames a complete, fsynced file over its target or
 *     leaves the target untouched and removes its temporary
 *     (lfio__h5_write_atomic()).
 *   - An lfio_reader keeps one open radiance dataset per slab (and its
 *     coverage dataset, if any) and nothing else mutable but a map of the
 *     radiance chunks partial reads have vetted (h5util.h), whose bits are
 *     set atomically, so reads on one reader from several threads only
 *     make HDF5 calls, which HDF5 serialises, and atomic updates.
 */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "chunks.h"
#include "h5util.h"
#include "ilf/limits.h"
#include "ilf/options.h"
#include "ilf/pool.h"
#include "internal.h"

#define FORMAT_NAME "ilfkit-lightfield"
#define FORMAT_VERSION 1
#define MAX_SLABS 65536
/* Bounds on strings read from files, so a hostile header cannot make us allocate much.
 * CREATOR_MAX is what lfio_lightfield_set_creator() holds, so every creator read can be kept. */
#define CREATOR_MAX 255
/* Elements per block when streaming the derived datasets (bounded memory at any n). */
#define BLOCK_ELEMS 196608
/* Absolute tolerance of lfio_verify() for recomputed doubles. */
#define VERIFY_TOL 1e-12
/* zlib level of radiance and coverage: written once by a capture, read many times. */
#define LF_DEFLATE_LEVEL 4
/* Largest chunk cache given to one radiance dataset of a reader. */
#define READER_CACHE_MAX ((size_t)64 << 20)

#define FRAME_TEXT                                                                              \
    "right-handed, metres; e1 = u/|u|, e2 = v/|v|, e3 = e1 x e2 (slab normal, partition pole +z);" \
    " direction = propagation direction, front hemisphere w.e3 >= 0, ids 0..4n^2-1;"              \
    " position (i, j) at cell centre origin + (i+0.5)/nu*u + (j+0.5)/nv*v"

/* ------------------------------------------------------------ dataset layouts */

enum ds_kind { DS_RADIANCE, DS_DIRECTION, DS_SOLID_ANGLE, DS_PROJ_SOLID_ANGLE, DS_POSITION, DS_MASK, DS_COVERAGE };

/* One dataset of a slab: what it holds and how it is stored. */
struct ds_spec {
    enum ds_kind kind;
    uint32_t mask_n;        /* partition level of a DS_MASK dataset */
    lfio__h5_layout lay;    /* name below the slab's group, type, shape, chunks, units, axes */
};

/* The five fixed datasets, the mask levels, and the optional coverage. */
#define MAX_SPECS (6 + LFIO_MAX_MASK_LEVELS)

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
    sp->lay.cls = H5T_FLOAT;
    sp->lay.size = 8;
    switch (kind) {
    case DS_RADIANCE:
        /* Chunks of 32 directions x 16 x 16 positions: one direction's image and one
         * position's directions each touch a small fraction of the chunks. */
        snprintf(sp->lay.name, sizeof sp->lay.name, "radiance");
        sp->lay.rank = 4;
        sp->lay.dims[0] = ndir, sp->lay.dims[1] = d->nv, sp->lay.dims[2] = d->nu, sp->lay.dims[3] = 3;
        sp->lay.chunk[0] = min_h(ndir, 32), sp->lay.chunk[1] = min_h(d->nv, 16);
        sp->lay.chunk[2] = min_h(d->nu, 16), sp->lay.chunk[3] = 3;
        sp->lay.size = 4;
        sp->lay.units = units_name(d->units);
        sp->lay.axes = "dir:v:u:rgb";
        sp->lay.deflate = LF_DEFLATE_LEVEL;
        break;
    case DS_COVERAGE:
        /* Radiance's layout without its channels, chunked alike so the same reads stay cheap. */
        snprintf(sp->lay.name, sizeof sp->lay.name, "coverage");
        sp->lay.rank = 3;
        sp->lay.dims[0] = ndir, sp->lay.dims[1] = d->nv, sp->lay.dims[2] = d->nu;
        sp->lay.chunk[0] = min_h(ndir, 32), sp->lay.chunk[1] = min_h(d->nv, 16), sp->lay.chunk[2] = min_h(d->nu, 16);
        sp->lay.cls = H5T_INTEGER;
        sp->lay.size = 1;
        sp->lay.units = "1";
        sp->lay.axes = "dir:v:u";
        sp->lay.deflate = LF_DEFLATE_LEVEL;
        break;
    case DS_DIRECTION:
        snprintf(sp->lay.name, sizeof sp->lay.name, "direction");
        sp->lay.rank = 2;
        sp->lay.dims[0] = ndir, sp->lay.dims[1] = 3;
        sp->lay.chunk[0] = min_h(ndir, 8192), sp->lay.chunk[1] = 3;
        sp->lay.units = "1";
        sp->lay.axes = "dir:xyz";
        break;
    case DS_SOLID_ANGLE:
    case DS_PROJ_SOLID_ANGLE:
        snprintf(sp->lay.name, sizeof sp->lay.name, "%s",
                 kind == DS_SOLID_ANGLE ? "solid_angle" : "projected_solid_angle");
        sp->lay.rank = 1;
        sp->lay.dims[0] = ndir;
        sp->lay.chunk[0] = min_h(ndir, 16384);
        sp->lay.units = "sr";
        sp->lay.axes = "dir";
        break;
    case DS_POSITION:
        snprintf(sp->lay.name, sizeof sp->lay.name, "position");
        sp->lay.rank = 3;
        sp->lay.dims[0] = d->nv, sp->lay.dims[1] = d->nu, sp->lay.dims[2] = 3;
        sp->lay.chunk[0] = min_h(d->nv, 64), sp->lay.chunk[1] = min_h(d->nu, 64), sp->lay.chunk[2] = 3;
        sp->lay.units = "m";
        sp->lay.axes = "v:u:xyz";
        break;
    case DS_MASK:
        snprintf(sp->lay.name, sizeof sp->lay.name, "mask/level_%u", mask_n);
        sp->lay.rank = 1;
        sp->lay.dims[0] = 4 * (hsize_t)mask_n * mask_n;
        sp->lay.chunk[0] = min_h(sp->lay.dims[0], 65536);
        sp->lay.cls = H5T_INTEGER;
        sp->lay.size = 1;
        sp->lay.units = "1";
        sp->lay.axes = "dir";
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

/* ------------------------------------------------------------ derived datasets */

/* One pass over a derived dataset: writing recomputed values, or comparing stored ones with them. */
struct stream {
    const char *path;
    const char *obj;          /* the dataset's full name, for messages */
    const lfio_slab *s;
    const struct ds_spec *sp;
    hid_t dset;
    int verify;               /* 0: write; 1: read and compare */
    lfio__h5_vetted *vetted;  /* verify: the chunks vetted so far (blocks share chunks), or NULL */
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
        case DS_COVERAGE:
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
            lfio__h5_format_dims(idx, sizeof idx, j->sp->lay.rank, at);
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
    const int b = sp->lay.rank == 3 ? 1 : 0;
    const hsize_t outer = b ? sp->lay.dims[0] : 1;
    const hsize_t inner = sp->lay.rank > b + 1 ? sp->lay.dims[b + 1] : 1;
    const hsize_t rows_per_block = BLOCK_ELEMS / inner;
    double *want = malloc(BLOCK_ELEMS * sizeof *want);
    double *got = j->verify ? malloc(BLOCK_ELEMS * sizeof *got) : NULL;
    lfio_status st = LFIO_OK;
    if (want == NULL || (j->verify && got == NULL))
        st = lfio__fail(LFIO_ERR_NOMEM, "%s: %s: out of memory", j->path, j->obj);
    for (hsize_t o = 0; st == LFIO_OK && o < outer; o++) {
        for (hsize_t r0 = 0; st == LFIO_OK && r0 < sp->lay.dims[b]; r0 += rows_per_block) {
            hsize_t start[3] = {0, 0, 0}, count[3] = {sp->lay.dims[0], sp->lay.dims[1], sp->lay.dims[2]};
            if (b) {
                start[0] = o;
                count[0] = 1;
            }
            start[b] = r0;
            count[b] = min_h(rows_per_block, sp->lay.dims[b] - r0);
            fill_expected(j->s, sp, start, count[b], want);
            st = j->verify ? lfio__h5_read_vetted(j->path, j->obj, j->dset, H5T_NATIVE_DOUBLE, sp->lay.rank, start,
                                                  count, got, j->vetted)
                           : lfio__h5_xfer(j->path, j->obj, j->dset, 1, H5T_NATIVE_DOUBLE, sp->lay.rank, start, count,
                                           want);
            if (st == LFIO_OK && j->verify)
                compare_block(j, start, b, inner, want, got, count[b] * inner);
        }
    }
    free(got);
    free(want);
    return st;
}

/* ----------------------------------------------------------------- writing */

/* Creates dataset sp in slab group g (gobj) as lfio__h5_create_dataset() does, plus the n of a mask level. */
static lfio_status create_dataset(const char *path, const char *gobj, hid_t g,
                                  const struct ds_spec *sp, hid_t *out)
{
    lfio_status st = lfio__h5_create_dataset(path, gobj, g, &sp->lay, out);
    if (st == LFIO_OK && sp->kind == DS_MASK) {
        char obj[128];
        snprintf(obj, sizeof obj, "%s/%s", gobj, sp->lay.name);
        st = lfio__h5_put_num_attr(path, obj, *out, "n", H5T_STD_U32LE, H5T_NATIVE_UINT32, 0, &sp->mask_n);
        if (st != LFIO_OK) {
            lfio__h5_close(*out);
            *out = -1;
        }
    }
    return st;
}

/* Writes the attributes of slab group g (obj) describing slab s. */
static lfio_status write_slab_attrs(const char *path, const char *obj, hid_t g, const lfio_slab *s)
{
    const lfio_slab_desc *d = &s->desc;
    lfio_status st = lfio__h5_put_str_attr(path, obj, g, "name", d->name);
    if (st == LFIO_OK)
        st = lfio__h5_put_num_attr(path, obj, g, "origin", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 3, d->origin);
    if (st == LFIO_OK)
        st = lfio__h5_put_num_attr(path, obj, g, "u", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 3, d->u);
    if (st == LFIO_OK)
        st = lfio__h5_put_num_attr(path, obj, g, "v", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 3, d->v);
    if (st == LFIO_OK)
        st = lfio__h5_put_str_attr(path, obj, g, "length_units", "m");
    if (st == LFIO_OK)
        st = lfio__h5_put_num_attr(path, obj, g, "nu", H5T_STD_U32LE, H5T_NATIVE_UINT32, 0, &d->nu);
    if (st == LFIO_OK)
        st = lfio__h5_put_num_attr(path, obj, g, "nv", H5T_STD_U32LE, H5T_NATIVE_UINT32, 0, &d->nv);
    if (st == LFIO_OK)
        st = lfio__h5_put_num_attr(path, obj, g, "n", H5T_STD_U32LE, H5T_NATIVE_UINT32, 0, &d->n);
    if (st == LFIO_OK)
        st = lfio__h5_put_str_attr(path, obj, g, "radiance_units", units_name(d->units));
    if (st == LFIO_OK)
        st = lfio__h5_put_str_attr(path, obj, g, "colour_space", "linear Rec.709");
    if (st == LFIO_OK)
        st = lfio__h5_put_num_attr(path, obj, g, "mask_threshold", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, 0,
                                   &d->mask_threshold);
    if (st == LFIO_OK)
        st = lfio__h5_put_str_attr(path, obj, g, "frame", FRAME_TEXT);
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
    size_t p = lfio__first_bad_value(s->radiance, total);
    if (p == total)
        return LFIO_OK;
    uint64_t q = p / 3, dir = q / s->npos, ij = q % s->npos;
    return bad_value_fail(st, path, k, dir, ij % s->desc.nu, ij / s->desc.nu, s->radiance[p]);
}

/* Writes slab s, with its coverage unless that is NULL and its covered share unless that is NaN, as group
 * /slabs/k of the file whose "slabs" group is slabs. */
static lfio_status write_slab(const char *path, hid_t slabs, size_t k, const lfio_slab *s, const uint8_t *coverage,
                              double fraction)
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
    if (coverage)
        ds_spec_make(&s->desc, DS_COVERAGE, 0, &specs[nspecs++]);
    hid_t g;
    if ((st = lfio__h5_create_group(path, obj, slabs, name, &g)) != LFIO_OK)
        return st;
    st = write_slab_attrs(path, obj, g, s);
    if (st == LFIO_OK && !isnan(fraction))
        st = lfio__h5_put_num_attr(path, obj, g, "coverage_fraction", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 0, &fraction);
    if (st == LFIO_OK && nlev > 0) {
        /* made here rather than on the way to its levels, where HDF5 would give it default
         * properties: it records no times, as no object lfio writes does */
        char mobj[128];
        hid_t mg;
        snprintf(mobj, sizeof mobj, "%s/mask", obj);
        if ((st = lfio__h5_create_group(path, mobj, g, "mask", &mg)) == LFIO_OK)
            lfio__h5_close(mg);
    }
    for (int t = 0; st == LFIO_OK && t < nspecs; t++) {
        hid_t d;
        char dobj[128];
        snprintf(dobj, sizeof dobj, "%s/%s", obj, specs[t].lay.name);
        st = create_dataset(path, obj, g, &specs[t], &d);
        if (st != LFIO_OK)
            break;
        const hsize_t zero[4] = {0, 0, 0, 0};
        if (specs[t].kind == DS_RADIANCE) {
            st = lfio__h5_xfer(path, dobj, d, 1, H5T_NATIVE_FLOAT, 4, zero, specs[t].lay.dims, s->radiance);
        } else if (specs[t].kind == DS_COVERAGE) {
            st = lfio__h5_xfer(path, dobj, d, 1, H5T_NATIVE_UINT8, 3, zero, specs[t].lay.dims, (void *)coverage);
        } else {
            struct stream j = {path, dobj, s, &specs[t], d, 0, NULL, 0, ""};
            st = stream_derived(&j);
        }
        /* Closing flushes the chunk cache: the last chunks reach the file only here. */
        if (H5Dclose(d) < 0 && st == LFIO_OK)
            st = lfio__h5_fail(LFIO_ERR_IO, path, dobj, "cannot flush dataset");
    }
    if (H5Gclose(g) < 0 && st == LFIO_OK)
        st = lfio__h5_fail(LFIO_ERR_IO, path, obj, "cannot close group");
    return st;
}

/* Writes the root attributes and every slab of the light field content into the open, empty file. */
static lfio_status write_contents(const char *path, hid_t file, const void *content)
{
    const lfio_lightfield *lf = content;
    const int32_t version = FORMAT_VERSION;
    const int32_t count = (int32_t)lfio_lightfield_slab_count(lf);
    lfio_status st = lfio__h5_put_str_attr(path, "/", file, "format", FORMAT_NAME);
    if (st == LFIO_OK)
        st = lfio__h5_put_num_attr(path, "/", file, "format_version", H5T_STD_I32LE, H5T_NATIVE_INT32, 0, &version);
    if (st == LFIO_OK)
        st = lfio__h5_put_str_attr(path, "/", file, "creator", lfio_lightfield_creator(lf));
    if (st == LFIO_OK)
        st = lfio__h5_put_num_attr(path, "/", file, "slab_count", H5T_STD_I32LE, H5T_NATIVE_INT32, 0, &count);
    if (st != LFIO_OK)
        return st;
    hid_t slabs;
    if ((st = lfio__h5_create_group(path, "/slabs", file, "slabs", &slabs)) != LFIO_OK)
        return st;
    for (size_t k = 0; st == LFIO_OK && k < (size_t)count; k++)
        st = write_slab(path, slabs, k, lfio_lightfield_slab(lf, k), lfio_lightfield_coverage(lf, k),
                        lfio_lightfield_coverage_fraction(lf, k));
    lfio__h5_close(slabs);
    return st;
}

/* Checks lf, then writes it with lfio__h5_write_atomic(). */
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
    return lfio__h5_write_atomic(path, write_contents, lf);
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
    hid_t *coverage;          /* nslabs open coverage datasets, shapes checked; -1 where a slab has none */
    double *fraction;         /* nslabs coverage_fraction attributes, in [0, 1]; NaN where a slab has none */
    lfio__h5_vetted **vetted; /* nslabs maps of the radiance chunks partial reads have vetted (or NULL) */
    unsigned threads;         /* lfio_read_options.threads, checked: whole reads inflate chunks on these */
};

/* Reads and checks the root attributes into r (version, creator, slab count). */
static lfio_status read_root(lfio_reader *r)
{
    int64_t version, count;
    lfio_status st = lfio__h5_expect_str_attr(r->path, "/", r->file, "format", FORMAT_NAME);
    if (st == LFIO_OK)
        st = lfio__h5_get_int_attr(r->path, "/", r->file, "format_version", INT32_MIN, INT32_MAX, &version);
    if (st == LFIO_OK && version > FORMAT_VERSION)
        st = lfio__fail(LFIO_ERR_FORMAT,
                        "%s: /: format_version %lld is newer than this library reads (version %d)",
                        r->path, (long long)version, FORMAT_VERSION);
    if (st == LFIO_OK && version < 1)
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: /: invalid format_version %lld", r->path, (long long)version);
    if (st == LFIO_OK)
        st = lfio__h5_get_str_attr(r->path, "/", r->file, "creator", CREATOR_MAX, &r->creator);
    if (st == LFIO_OK)
        st = lfio__h5_get_int_attr(r->path, "/", r->file, "slab_count", 1, MAX_SLABS, &count);
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
    lfio_status st = lfio__h5_get_str_attr(path, obj, g, "name", LFIO_NAME_MAX, &text);
    if (st == LFIO_OK)
        strcpy(d->name, text);
    free(text);
    text = NULL;
    if (st == LFIO_OK)
        st = lfio__h5_get_f64_attr(path, obj, g, "origin", 3, d->origin);
    if (st == LFIO_OK)
        st = lfio__h5_get_f64_attr(path, obj, g, "u", 3, d->u);
    if (st == LFIO_OK)
        st = lfio__h5_get_f64_attr(path, obj, g, "v", 3, d->v);
    if (st == LFIO_OK)
        st = lfio__h5_expect_str_attr(path, obj, g, "length_units", "m");
    if (st == LFIO_OK)
        st = lfio__h5_get_int_attr(path, obj, g, "nu", 1, UINT32_MAX, &nu);
    if (st == LFIO_OK)
        st = lfio__h5_get_int_attr(path, obj, g, "nv", 1, UINT32_MAX, &nv);
    if (st == LFIO_OK)
        st = lfio__h5_get_int_attr(path, obj, g, "n", 1, LFIO_SLAB_MAX_N, &n);
    if (st == LFIO_OK)
        st = lfio__h5_get_str_attr(path, obj, g, "radiance_units", LFIO__H5_TEXT_MAX, &text);
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
        st = lfio__h5_expect_str_attr(path, obj, g, "colour_space", "linear Rec.709");
    if (st == LFIO_OK)
        st = lfio__h5_get_f64_attr(path, obj, g, "mask_threshold", 1, &threshold);
    if (st == LFIO_OK && (threshold < 0 || threshold > 3.4028234663852886e38))
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: mask_threshold %g out of range", path, obj, threshold);
    /* frame is documentation for readers: it must exist, its text is not parsed. */
    if (st == LFIO_OK)
        st = lfio__h5_get_str_attr(path, obj, g, "frame", LFIO__H5_TEXT_MAX, &text);
    free(text);
    d->nu = (uint32_t)nu;
    d->nv = (uint32_t)nv;
    d->n = (uint32_t)n;
    d->mask_threshold = (float)threshold;
    return st;
}

/* Checks desc d of slab obj against the radiance size limit, then lfio__check_desc().
 * A file over the limit breaks the format's rules (docs/format.md, section 4): LFIO_ERR_FORMAT,
 * so that it counts as bad input and not as the reader running out of memory. */
static lfio_status check_slab_desc(const char *path, const char *obj, const lfio_slab_desc *d)
{
    uint64_t bytes = 0;
    int fits = lfio__mul_u64(4 * (uint64_t)d->n, d->n, &bytes) && lfio__mul_u64(bytes, d->nu, &bytes)
               && lfio__mul_u64(bytes, d->nv, &bytes) && lfio__mul_u64(bytes, 3 * sizeof(float), &bytes);
    if (!fits || bytes > LFIO_SLAB_MAX_BYTES)
        return lfio__fail(LFIO_ERR_FORMAT,
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
        nchunk[k] = (sp->lay.dims[k] + sp->lay.chunk[k] - 1) / sp->lay.chunk[k];
    const hsize_t *chunk = sp->lay.chunk;
    size_t chunk_bytes = (size_t)(chunk[0] * chunk[1] * chunk[2] * chunk[3] * sp->lay.size);
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

/*
 * Opens dataset sp of slab group g (gobj) and checks it as lfio__h5_check_dataset()
 * does, plus the mask group and the n of a mask level.
 * @return LFIO_OK and *out open if out is not NULL; LFIO_ERR_FORMAT.
 */
static lfio_status check_dataset(const char *path, const char *gobj, hid_t g, const struct ds_spec *sp,
                                 hid_t dapl, hid_t *out)
{
    /* H5Lexists fails rather than answering 0 when an intermediate group is missing; and the mask group's
     * links are looked up below, so its format is checked first. */
    char obj[128];
    snprintf(obj, sizeof obj, "%s/mask", gobj);
    hid_t mask = -1;
    lfio_status st = sp->kind == DS_MASK ? lfio__h5_open_group(path, obj, g, "mask", "group", &mask) : LFIO_OK;
    lfio__h5_close(mask);
    if (st != LFIO_OK)
        return st;
    hid_t d = -1;
    st = lfio__h5_check_dataset(path, gobj, g, &sp->lay, "the slab's attributes", dapl, &d);
    if (st == LFIO_OK && sp->kind == DS_MASK) {
        int64_t m;
        snprintf(obj, sizeof obj, "%s/%s", gobj, sp->lay.name);
        st = lfio__h5_get_int_attr(path, obj, d, "n", sp->mask_n, sp->mask_n, &m);
    }
    if (st == LFIO_OK && out)
        *out = d;
    else
        lfio__h5_close(d);
    return st;
}

/* Reads the optional coverage_fraction attribute of slab group g (obj) into *out: NaN when absent. */
static lfio_status read_fraction(const char *path, const char *obj, hid_t g, double *out)
{
    *out = NAN;
    htri_t has = H5Aexists(g, "coverage_fraction");
    if (has < 0)
        return lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, "cannot look for a coverage_fraction attribute");
    if (has == 0)
        return LFIO_OK;
    double value = NAN;
    lfio_status st = lfio__h5_get_f64_attr(path, obj, g, "coverage_fraction", 1, &value);
    if (st == LFIO_OK && !(value >= 0.0 && value <= 1.0))
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: coverage_fraction %g is not in [0, 1]", path, obj, value);
    if (st == LFIO_OK)
        *out = value;
    return st;
}

/* Opens group /slabs/k, reads and checks its description into r->desc[k], checks every dataset and keeps radiance open. */
static lfio_status open_slab(lfio_reader *r, hid_t slabs, size_t k)
{
    char obj[64], name[24];
    snprintf(name, sizeof name, "%zu", k);
    snprintf(obj, sizeof obj, "/slabs/%zu", k);
    char what[64];
    snprintf(what, sizeof what, "slab group (slab_count is %zu)", r->nslabs);
    hid_t g;
    lfio_status st = lfio__h5_open_group(r->path, obj, slabs, name, what, &g);
    if (st != LFIO_OK)
        return st;
    st = read_desc(r->path, obj, g, &r->desc[k]);
    if (st == LFIO_OK)
        st = check_slab_desc(r->path, obj, &r->desc[k]);
    struct ds_spec specs[MAX_SPECS];
    int nspecs = st == LFIO_OK ? slab_specs(&r->desc[k], specs) : 0;
    for (int t = 0; st == LFIO_OK && t < nspecs; t++) {
        int keep = specs[t].kind == DS_RADIANCE;
        hid_t dapl = keep ? radiance_dapl(&specs[t]) : -1;
        st = check_dataset(r->path, obj, g, &specs[t], dapl, keep ? &r->radiance[k] : NULL);
        lfio__h5_close(dapl);
    }
    if (st == LFIO_OK)
        st = read_fraction(r->path, obj, g, &r->fraction[k]);
    size_t map_bytes = st == LFIO_OK ? lfio__h5_vetted_bytes(r->radiance[k]) : 0;
    if (map_bytes > 0 && (r->vetted[k] = calloc(map_bytes, 1)) == NULL)
        st = lfio__fail(LFIO_ERR_NOMEM, "%s: %s: out of memory", r->path, obj);
    /* Coverage is optional: absent is fine, present must have the layout the slab's attributes imply. */
    htri_t has = st == LFIO_OK ? H5Lexists(g, "coverage", H5P_DEFAULT) : 0;
    if (has < 0)
        st = lfio__h5_fail(LFIO_ERR_FORMAT, r->path, obj, "cannot look for a coverage dataset");
    if (has > 0) {
        struct ds_spec sp;
        ds_spec_make(&r->desc[k], DS_COVERAGE, 0, &sp);
        st = check_dataset(r->path, obj, g, &sp, -1, &r->coverage[k]);
    }
    lfio__h5_close(g);
    return st;
}

/* qsort comparator: slab descriptions by name, equal names by place, so a repeat follows its first use. */
static int compare_names(const void *a, const void *b)
{
    const lfio_slab_desc *da = *(const lfio_slab_desc *const *)a, *db = *(const lfio_slab_desc *const *)b;
    int c = strcmp(da->name, db->name);
    return c != 0 ? c : (da > db) - (da < db);
}

/* Checks that no two slabs of r share a name (sorting, so 65536 slabs stay cheap). @return LFIO_OK,
 * LFIO_ERR_FORMAT naming both slabs, or LFIO_ERR_NOMEM. */
static lfio_status check_unique_names(const lfio_reader *r)
{
    const lfio_slab_desc **sorted = malloc(r->nslabs * sizeof *sorted);
    if (sorted == NULL)
        return lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", r->path);
    for (size_t k = 0; k < r->nslabs; k++)
        sorted[k] = &r->desc[k];
    qsort(sorted, r->nslabs, sizeof *sorted, compare_names);
    lfio_status st = LFIO_OK;
    for (size_t k = 1; st == LFIO_OK && k < r->nslabs; k++)
        if (strcmp(sorted[k - 1]->name, sorted[k]->name) == 0)
            st = lfio__fail(LFIO_ERR_FORMAT, "%s: /slabs/%td and /slabs/%td: slab name '%s' is used twice", r->path,
                            sorted[k - 1] - r->desc, sorted[k] - r->desc, sorted[k]->name);
    free(sorted);
    return st;
}

/* Closes everything r holds and frees it. */
static void reader_free(lfio_reader *r)
{
    if (r == NULL)
        return;
    for (size_t k = 0; r->radiance && k < r->nslabs; k++)
        lfio__h5_close(r->radiance[k]);
    for (size_t k = 0; r->coverage && k < r->nslabs; k++)
        lfio__h5_close(r->coverage[k]);
    for (size_t k = 0; r->vetted && k < r->nslabs; k++)
        free((void *)r->vetted[k]);
    lfio__h5_close(r->file);
    free(r->vetted);
    free(r->radiance);
    free(r->coverage);
    free(r->fraction);
    free(r->desc);
    free(r->creator);
    free(r->path);
    free(r);
}

void lfio_read_options_init(lfio_read_options *opt)
{
    if (opt == NULL)
        return;
    memset(opt, 0, sizeof *opt);
    opt->size = sizeof *opt;
}

/* Reads the caller's options (NULL: the defaults) into *o, the part of them their size holds. @return LFIO_OK,
 * or LFIO_ERR_ARG naming the problem. */
static lfio_status take_read_options(const char *path, const lfio_read_options *opt, lfio_read_options *o)
{
    lfio_read_options_init(o);
    if (opt != NULL && !ilf_options_take(o, sizeof *o, opt, offsetof(lfio_read_options, threads) + sizeof opt->threads))
        return lfio__fail(LFIO_ERR_ARG, "%s: lfio_read_options.size %zu is not one this library knows", path,
                          opt->size);
    if (o->threads > ILF_MAX_THREADS)
        return lfio__fail(LFIO_ERR_ARG, "%s: read options out of range (threads %u, at most %u)", path, o->threads,
                          ILF_MAX_THREADS);
    return LFIO_OK;
}

/* lfio_reader_open_with() without silencing HDF5: the body shared with lfio_lightfield_read_with() and
 * lfio_verify(). */
static lfio_status reader_open_impl(const char *path, const lfio_read_options *opt, lfio_reader **out)
{
    *out = NULL;
    lfio_read_options o;
    lfio_status st = take_read_options(path, opt, &o);
    hid_t file;
    if (st == LFIO_OK)
        st = lfio__h5_open_read(path, &file);
    if (st != LFIO_OK)
        return st;
    lfio_reader *r = calloc(1, sizeof *r);
    if (r == NULL || (r->path = malloc(strlen(path) + 1)) == NULL) {
        free(r);
        lfio__h5_close(file);
        return lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", path);
    }
    strcpy(r->path, path);
    r->file = file;
    r->threads = o.threads;
    st = read_root(r);
    /* nslabs <= MAX_SLABS here, so these allocations are bounded. */
    if (st == LFIO_OK && ((r->desc = calloc(r->nslabs, sizeof *r->desc)) == NULL
                          || (r->radiance = malloc(r->nslabs * sizeof *r->radiance)) == NULL
                          || (r->coverage = malloc(r->nslabs * sizeof *r->coverage)) == NULL
                          || (r->fraction = malloc(r->nslabs * sizeof *r->fraction)) == NULL
                          || (r->vetted = calloc(r->nslabs, sizeof *r->vetted)) == NULL))
        st = lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", path);
    for (size_t k = 0; r->radiance && k < r->nslabs; k++)
        r->radiance[k] = -1;
    for (size_t k = 0; r->coverage && k < r->nslabs; k++)
        r->coverage[k] = -1;
    hid_t slabs = -1;
    if (st == LFIO_OK)
        st = lfio__h5_open_group(path, "/slabs", r->file, "slabs", "group", &slabs);
    for (size_t k = 0; st == LFIO_OK && k < r->nslabs; k++)
        st = open_slab(r, slabs, k);
    lfio__h5_close(slabs);
    if (st == LFIO_OK)
        st = check_unique_names(r);
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

/* Where decoded radiance chunks go (place_chunk()): the dataset's values, its shape and chunk shape, and
 * each chunk's first element. */
typedef struct chunk_places {
    float *values;
    hsize_t dims[4], chunk[4];
    const hsize_t *offset; /* [n][4] */
} chunk_places;

/* Copies decoded chunk k's part inside the dataset to its place (lfio__chunks_unfilter()'s place). */
static void place_chunk(void *user, size_t k, const unsigned char *values)
{
    const chunk_places *p = user;
    const hsize_t *o = p->offset + 4 * k, *d = p->dims, *c = p->chunk;
    hsize_t n[4];
    for (int a = 0; a < 4; a++)
        n[a] = d[a] - o[a] < c[a] ? d[a] - o[a] : c[a];
    for (hsize_t a = 0; a < n[0]; a++)
        for (hsize_t b = 0; b < n[1]; b++)
            for (hsize_t e = 0; e < n[2]; e++)
                memcpy(p->values + (((o[0] + a) * d[1] + o[1] + b) * d[2] + o[2] + e) * d[3] + o[3],
                       values + (((a * c[1] + b) * c[2] + e) * c[3]) * sizeof(float), (size_t)n[3] * sizeof(float));
}

/* @return 1 if dataset d, of shape dims, is stored as lfio writes radiance (little-endian float32 in chunks
 * within its shape, shuffle, deflate and Fletcher-32 in that order) with every chunk there, each filtered
 * and of a plausible size; their shape in chunk, their count in *n; else 0. */
static int stored_as_lfio(hid_t d, const hsize_t *dims, hsize_t *chunk, hsize_t *n)
{
    hid_t t = H5Dget_type(d), dcpl = H5Dget_create_plist(d);
    int ok = LFIO_LITTLE_ENDIAN && t >= 0 && dcpl >= 0 && H5Tequal(t, H5T_IEEE_F32LE) > 0 &&
             H5Pget_layout(dcpl) == H5D_CHUNKED && H5Pget_chunk(dcpl, 4, chunk) == 4 && H5Pget_nfilters(dcpl) == 3;
    static const H5Z_filter_t pipeline[3] = {H5Z_FILTER_SHUFFLE, H5Z_FILTER_DEFLATE, H5Z_FILTER_FLETCHER32};
    for (unsigned f = 0; ok && f < 3; f++) {
        unsigned flags = 0, config = 0, cd[8];
        size_t ncd = 8;
        ok = H5Pget_filter2(dcpl, f, &flags, &ncd, cd, 0, NULL, &config) == pipeline[f];
    }
    hsize_t expected = 1;
    for (int a = 0; ok && a < 4; a++) {
        ok = chunk[a] >= 1 && chunk[a] <= (dims[a] ? dims[a] : 1);
        expected *= (dims[a] + chunk[a] - 1) / chunk[a];
    }
    /* HDF5 1.10 takes the dataset's own dataspace here, not H5S_ALL */
    hid_t space = ok ? H5Dget_space(d) : -1;
    ok = ok && space >= 0 && H5Dget_num_chunks(d, space, n) >= 0 && *n == expected;
    lfio__h5_close(space);
    lfio__h5_close(dcpl);
    lfio__h5_close(t);
    return ok;
}

/* Reads the radiance dataset d of a slab (object obj of path, shape dims) into values by undoing its
 * pipeline on lfio's own threads, when it is stored as lfio writes it (stored_as_lfio()): HDF5 only hands
 * over the stored chunks (H5Dread_chunk), whose inflating is most of a read. @return 1 with *st the read's
 * status (reported); 0 when it is stored otherwise, nothing read or reported (HDF5 then reads it). */
static int read_radiance_direct(const char *path, const char *obj, hid_t d, const hsize_t *dims, unsigned threads,
                                float *values, lfio_status *st)
{
    chunk_places places = {values, {dims[0], dims[1], dims[2], dims[3]}, {0}, NULL};
    hsize_t n = 0;
    if (!stored_as_lfio(d, dims, places.chunk, &n) || n == 0)
        return 0;
    size_t chunk_bytes = sizeof(float);
    for (int a = 0; a < 4; a++)
        chunk_bytes *= (size_t)places.chunk[a];
    /* a stored chunk is at most its deflated bound and the checksum (lfio__h5_check_dataset() refused larger
     * ones); a chunk that fails a check here goes to HDF5's path, where lfio__h5_xfer() vets it and says why */
    size_t most = lfio__chunks_stored_most(chunk_bytes), total = 0;
    hsize_t *offset = malloc((size_t)n * 4 * sizeof *offset);
    lfio__stored *c = calloc((size_t)n, sizeof *c);
    if (offset == NULL || c == NULL) { /* out of memory is reported, never absorbed by HDF5's reading */
        free(offset);
        free(c);
        *st = lfio__fail(LFIO_ERR_NOMEM, "%s: %s: out of memory for %llu chunks", path, obj, (unsigned long long)n);
        return 1;
    }
    hid_t space = H5Dget_space(d);
    int direct = space >= 0;
    for (hsize_t k = 0; direct && k < n; k++) {
        unsigned mask = 0;
        haddr_t addr = 0;
        hsize_t size = 0;
        direct = H5Dget_chunk_info(d, space, k, offset + 4 * k, &mask, &addr, &size) >= 0 && mask == 0 &&
                 size >= 4 && size <= most;
        /* a chunk starts on the chunk grid inside the dataset (place_chunk() relies on it) */
        for (int a = 0; direct && a < 4; a++)
            direct = offset[4 * k + a] < dims[a] && offset[4 * k + a] % places.chunk[a] == 0;
        c[k] = (lfio__stored){NULL, (size_t)size, chunk_bytes, sizeof(float)};
        total += (size_t)size;
    }
    lfio__h5_close(space);
    unsigned char *stored = direct ? malloc(total ? total : 1) : NULL;
    if (!direct || stored == NULL) {
        free(offset);
        free(c);
        if (direct) /* out of memory: as HDF5 would be */
            *st = lfio__fail(LFIO_ERR_NOMEM, "%s: %s: out of memory for %zu bytes of stored chunks", path, obj, total);
        return direct;
    }
    *st = LFIO_OK;
    size_t at = 0;
    for (hsize_t k = 0; *st == LFIO_OK && k < n; at += c[k++].in_bytes) {
        uint32_t mask = 0;
        c[k].in = stored + at;
        if (H5Dread_chunk(d, H5P_DEFAULT, offset + 4 * k, &mask, stored + at) < 0)
            *st = lfio__h5_fail(LFIO_ERR_IO, path, obj, "cannot read");
    }
    places.offset = offset;
    size_t bad = 0;
    int rc = *st == LFIO_OK ? lfio__chunks_unfilter(c, (size_t)n, ilf_thread_count(threads),
                                                    place_chunk, &places, &bad)
                            : LFIO__STORED_OK;
    if (rc == LFIO__STORED_CHECKSUM)
        *st = lfio__fail(LFIO_ERR_CHECKSUM, "%s: %s: checksum mismatch (cannot read)", path, obj);
    else if (rc == LFIO__STORED_BROKEN)
        *st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: cannot read: stored chunk %zu does not inflate to its %zu bytes",
                         path, obj, bad, chunk_bytes);
    else if (rc == LFIO__STORED_NOMEM)
        *st = lfio__fail(LFIO_ERR_NOMEM, "%s: %s: out of memory", path, obj);
    free(stored);
    free(offset);
    free(c);
    return 1;
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
    if (!read_radiance_direct(r->path, obj, r->radiance[k], sp.lay.dims, r->threads, s->radiance, &st))
        st = lfio__h5_xfer(r->path, obj, r->radiance[k], 0, H5T_NATIVE_FLOAT, 4, zero, sp.lay.dims, s->radiance);
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

/* Reads slab k's coverage (which it must have) into buf and checks its values (HDF5 not silenced). */
static lfio_status read_coverage_impl(lfio_reader *r, size_t k, uint8_t *buf)
{
    char obj[64];
    snprintf(obj, sizeof obj, "/slabs/%zu/coverage", k);
    struct ds_spec sp;
    ds_spec_make(&r->desc[k], DS_COVERAGE, 0, &sp);
    const hsize_t zero[3] = {0, 0, 0};
    lfio_status st = lfio__h5_xfer(r->path, obj, r->coverage[k], 0, H5T_NATIVE_UINT8, 3, zero, sp.lay.dims, buf);
    const uint64_t npos = (uint64_t)r->desc[k].nu * r->desc[k].nv;
    const size_t total = (size_t)(sp.lay.dims[0] * npos);
    for (size_t e = 0; st == LFIO_OK && e < total; e++)
        if (buf[e] > 1)
            st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: value %u at dir %llu, i %llu, j %llu (expected 0 or 1)", r->path,
                            obj, buf[e], (unsigned long long)(e / npos),
                            (unsigned long long)(e % npos % r->desc[k].nu), (unsigned long long)(e % npos / r->desc[k].nu));
    return st;
}

/* Opens path and checks all its metadata (see reader_open_impl()), silently. */
lfio_status lfio_reader_open_with(const char *path, const lfio_read_options *opt, lfio_reader **out)
{
    if (out == NULL)
        return lfio__fail(LFIO_ERR_ARG, "lfio_reader_open: NULL argument");
    *out = NULL;
    if (path == NULL || path[0] == '\0')
        return lfio__fail(LFIO_ERR_ARG, "lfio_reader_open: NULL or empty path");
    lfio__h5_quiet q;
    lfio__h5_quiet_begin(&q);
    lfio_status st = reader_open_impl(path, opt, out);
    lfio__h5_quiet_end(&q);
    return st;
}

lfio_status lfio_reader_open(const char *path, lfio_reader **out)
{
    return lfio_reader_open_with(path, NULL, out);
}

/* Closes the file and frees the reader; NULL is a no-op. */
void lfio_reader_close(lfio_reader *r)
{
    lfio__h5_quiet q;
    if (r == NULL)
        return;
    lfio__h5_quiet_begin(&q);
    reader_free(r);
    lfio__h5_quiet_end(&q);
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
    lfio__h5_quiet q;
    lfio__h5_quiet_begin(&q);
    st = lfio__h5_read_vetted(r->path, obj, r->radiance[k], H5T_NATIVE_FLOAT, 4, start, count, img, r->vetted[k]);
    lfio__h5_quiet_end(&q);
    const size_t total = (size_t)d->nu * d->nv * 3;
    size_t p = st == LFIO_OK ? lfio__first_bad_value(img, total) : total;
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
    lfio__h5_quiet q;
    lfio__h5_quiet_begin(&q);
    st = lfio__h5_read_vetted(r->path, obj, r->radiance[k], H5T_NATIVE_FLOAT, 4, start, count, rgb, r->vetted[k]);
    lfio__h5_quiet_end(&q);
    const size_t total = (size_t)ndir * 3;
    size_t p = st == LFIO_OK ? lfio__first_bad_value(rgb, total) : total;
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
    lfio__h5_quiet q;
    lfio__h5_quiet_begin(&q);
    st = read_slab_impl(r, k, out);
    lfio__h5_quiet_end(&q);
    return st;
}

double lfio_reader_coverage_fraction(const lfio_reader *r, size_t k)
{
    return r != NULL && k < r->nslabs ? r->fraction[k] : NAN;
}

/* @return 1 if slab k has a coverage dataset; 0 otherwise or for bad arguments. */
int lfio_reader_has_coverage(const lfio_reader *r, size_t k)
{
    return r != NULL && k < r->nslabs && r->coverage[k] >= 0;
}

/* Reads slab k's coverage whole (see read_coverage_impl()), silently. */
lfio_status lfio_reader_read_coverage(lfio_reader *r, size_t k, uint8_t *coverage)
{
    lfio_status st = check_slab_arg(r, k, coverage, "lfio_reader_read_coverage");
    if (st != LFIO_OK)
        return st;
    if (r->coverage[k] < 0)
        return lfio__fail(LFIO_ERR_ARG, "%s: /slabs/%zu: the slab has no coverage dataset", r->path, k);
    lfio__h5_quiet q;
    lfio__h5_quiet_begin(&q);
    st = read_coverage_impl(r, k, coverage);
    lfio__h5_quiet_end(&q);
    return st;
}

/* Reads slab k's coverage, if it has one, into slab k of lf (HDF5 not silenced). */
static lfio_status read_coverage_into(lfio_reader *r, size_t k, lfio_lightfield *lf)
{
    if (r->coverage[k] < 0)
        return LFIO_OK;
    const lfio_slab *s = lfio_lightfield_slab(lf, k);
    uint8_t *buf = malloc((size_t)(s->ndir * s->npos));
    lfio_status st = buf ? read_coverage_impl(r, k, buf)
                         : lfio__fail(LFIO_ERR_NOMEM, "%s: /slabs/%zu/coverage: out of memory", r->path, k);
    /* Values were checked: set_coverage can only run out of memory. */
    if (st == LFIO_OK && lfio_lightfield_set_coverage(lf, k, buf) != LFIO_OK)
        st = lfio__fail(LFIO_ERR_NOMEM, "%s: /slabs/%zu/coverage: out of memory", r->path, k);
    free(buf);
    return st;
}

/* lfio_lightfield_read() without silencing HDF5. */
static lfio_status lightfield_read_impl(const char *path, const lfio_read_options *opt, lfio_lightfield **out)
{
    lfio_reader *r = NULL;
    lfio_lightfield *lf = NULL;
    lfio_status st = reader_open_impl(path, opt, &r);
    if (st == LFIO_OK && lfio_lightfield_new(&lf) != LFIO_OK)
        st = lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", path);
    if (st == LFIO_OK && lfio_lightfield_set_creator(lf, r->creator) != LFIO_OK)
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: /: creator rejected by lfio_lightfield_set_creator", path);
    for (size_t k = 0; st == LFIO_OK && k < r->nslabs; k++) {
        lfio_slab *s;
        st = read_slab_impl(r, k, &s);
        /* Names, and that they differ, were checked on opening: take_slab can only run out of memory. */
        if (st == LFIO_OK && lfio_lightfield_take_slab(lf, s) != LFIO_OK)
            st = lfio__fail(LFIO_ERR_NOMEM, "%s: /slabs/%zu: out of memory", path, k);
        if (st == LFIO_OK)
            st = read_coverage_into(r, k, lf);
        /* checked in [0, 1] on opening */
        if (st == LFIO_OK)
            lfio_lightfield_set_coverage_fraction(lf, k, r->fraction[k]);
    }
    reader_free(r);
    if (st != LFIO_OK)
        lfio_lightfield_destroy(lf);
    else
        *out = lf;
    return st;
}

/* Reads every slab of path into a new light field, silently. */
lfio_status lfio_lightfield_read_with(const char *path, const lfio_read_options *opt, lfio_lightfield **out)
{
    if (out == NULL)
        return lfio__fail(LFIO_ERR_ARG, "lfio_lightfield_read: NULL argument");
    *out = NULL;
    if (path == NULL || path[0] == '\0')
        return lfio__fail(LFIO_ERR_ARG, "lfio_lightfield_read: NULL or empty path");
    lfio__h5_quiet q;
    lfio__h5_quiet_begin(&q);
    lfio_status st = lightfield_read_impl(path, opt, out);
    lfio__h5_quiet_end(&q);
    return st;
}

lfio_status lfio_lightfield_read(const char *path, lfio_lightfield **out)
{
    return lfio_lightfield_read_with(path, NULL, out);
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
    lfio__h5_close(dcpl);
    if (rc < 0)
        note(v, lfio__fail(LFIO_ERR_FORMAT, "%s: %s: stored without a fletcher32 checksum", path, obj));
}

/* Verifies slab k: reads its radiance, then checks every dataset's checksum filter, that every chunk of it is
 * stored, and the derived values. */
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
        note(v, lfio__h5_fail(LFIO_ERR_FORMAT, r->path, gobj, "cannot open as a group"));
        lfio_slab_destroy(s);
        return;
    }
    struct ds_spec specs[MAX_SPECS];
    int nspecs = slab_specs(&s->desc, specs);
    for (int t = 0; t < nspecs; t++) {
        char obj[128];
        snprintf(obj, sizeof obj, "%s/%s", gobj, specs[t].lay.name);
        hid_t d = H5Dopen2(g, specs[t].lay.name, H5P_DEFAULT);
        if (d < 0) {
            note(v, lfio__h5_fail(LFIO_ERR_FORMAT, r->path, obj, "cannot open as a dataset"));
            continue;
        }
        verify_checksummed(v, r->path, obj, d);
        if (lfio__h5_expect_whole(r->path, obj, d, &specs[t].lay) != LFIO_OK)
            note(v, LFIO_ERR_FORMAT);
        if (specs[t].kind != DS_RADIANCE) {
            size_t map_bytes = lfio__h5_vetted_bytes(d);
            struct stream j = {r->path, obj, s, &specs[t], d, 1, map_bytes ? calloc(map_bytes, 1) : NULL, 0, ""};
            st = map_bytes && j.vetted == NULL ? lfio__fail(LFIO_ERR_NOMEM, "%s: %s: out of memory", r->path, obj)
                                               : stream_derived(&j);
            free((void *)j.vetted);
            if (st != LFIO_OK)
                note(v, st);
            else if (j.mismatches)
                note(v, lfio__fail(LFIO_ERR_FORMAT, "%s: %s: %llu values differ from recomputed ones, first %s",
                                   r->path, obj, (unsigned long long)j.mismatches, j.first));
        }
        lfio__h5_close(d);
    }
    if (r->coverage[k] >= 0) {
        char obj[128];
        snprintf(obj, sizeof obj, "%s/coverage", gobj);
        verify_checksummed(v, r->path, obj, r->coverage[k]);
        struct ds_spec cov;
        ds_spec_make(&s->desc, DS_COVERAGE, 0, &cov);
        if (lfio__h5_expect_whole(r->path, obj, r->coverage[k], &cov.lay) != LFIO_OK)
            note(v, LFIO_ERR_FORMAT);
        uint8_t *buf = malloc((size_t)(s->ndir * s->npos));
        st = buf ? read_coverage_impl(r, k, buf) : lfio__fail(LFIO_ERR_NOMEM, "%s: %s: out of memory", r->path, obj);
        if (st != LFIO_OK)
            note(v, st);
        free(buf);
    }
    H5G_info_t info;
    uint32_t nlev = (uint32_t)nspecs - 5;
    if (H5Gget_info_by_name(g, "mask", &info, H5P_DEFAULT) < 0)
        note(v, lfio__h5_fail(LFIO_ERR_FORMAT, r->path, gobj, "cannot list the mask group"));
    else if (info.nlinks != nlev)
        note(v, lfio__fail(LFIO_ERR_FORMAT, "%s: %s/mask: holds %llu objects, expected %u mask levels",
                           r->path, gobj, (unsigned long long)info.nlinks, nlev));
    lfio__h5_close(g);
    lfio_slab_destroy(s);
}

/* Opens path, reads every slab and compares every derived dataset; counts problems, returns the first one's status. */
lfio_status lfio_verify(const char *path, lfio_verify_report *report)
{
    struct vstate v = {LFIO_OK, 0, ""};
    if (path == NULL || path[0] == '\0') {
        note(&v, lfio__fail(LFIO_ERR_ARG, "lfio_verify: NULL or empty path"));
    } else {
        lfio__h5_quiet q;
        lfio__h5_quiet_begin(&q);
        lfio_reader *r = NULL;
        lfio_status st = reader_open_impl(path, NULL, &r);
        if (st != LFIO_OK)
            note(&v, st);
        for (size_t k = 0; r && k < r->nslabs; k++)
            verify_slab(&v, r, k);
        reader_free(r);
        lfio__h5_quiet_end(&q);
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
