/*
 * radmap_io.c - radiance-map files (lfio/radmap.h; docs/format.md,
 * "Radiance-map files"): the atomic writer and the validating reader, of
 * format 2 (each array once for all patches: written by default) and
 * format 1 (a group a patch: read, and written when asked).
 *
 * Invariants:
 *   - The layout of every dataset of a patch (name, type, shape, chunks,
 *     units, axes, compression) comes from one table, map_datasets[], through
 *     patch_layout(): the writer creates what the reader checks.
 *   - One function, check_patch(), judges a patch's values (through
 *     check_patch_scalars() and check_patch_arrays(), which the writer
 *     applies to a patch's description and then to each slice of its
 *     cells). The writer refuses (LFIO_ERR_ARG) exactly what the reader
 *     refuses (LFIO_ERR_FORMAT), so every file written reads back.
 *   - Format 2: the writer gathers every patch's description and vertices
 *     and the cells of this writer's patches (all of them in a serial write,
 *     a contiguous run of them on a rank of a collective one, none where
 *     every rank holds every cell and takes its chunks' later), then writes
 *     one dataset at a time, from one table (v2_datasets[], through
 *     v2_layout()) that the reader checks against; the reader checks the
 *     per-patch tables and offsets before it sizes any vertex or cell array.
 *     A collective write on a little-endian machine makes the serial
 *     writer's file byte for byte: the ranks filter the cell datasets'
 *     chunks with the serial writer's filter and rank 0 makes the serial
 *     writer's HDF5 calls, fed those chunks (mpi_write_v2()).
 *   - Format 1: a serial write holds one slice of a patch's cells at a time
 *     (LFIO_RADMAP_ROWS_MAX, a whole number of chunks) and their compressed
 *     chunks; a write through MPI-IO, which HDF5 filters, one whole patch.
 *   - The reader allocates nothing from a number found in a file before
 *     checking it: patch storage grows one validated group at a time, the
 *     vertex and cell counts are bounded (per patch and, for cells, over the
 *     file) and every dataset's type and shape are checked before any array
 *     is allocated.
 *   - A read of the headers (lfio_radmap_read_headers()) makes every check a
 *     whole read makes short of reading the cell datasets: their storage and
 *     shape are checked, their values not, and the patches' cell arrays are
 *     NULL. Its memory is the patch tables and the vertices.
 *   - HDF5 is called from the calling thread alone: the threads of a serial
 *     write (chunks.h) only filter chunks while it makes a patch's objects.
 *   - lfio_radmap_headers (the last section) reads a format-2 file's
 *     headers in blocks of bounded size, with the checks of the headers
 *     read: when it opens, those whose cost does not grow with the patches
 *     (root attributes, every dataset's storage and shape, the offsets'
 *     first and last rows); the offsets' order, the labels and each
 *     patch's own checks as the blocks holding them are read, so that a
 *     reader that gets every patch has made every check of the headers
 *     read and one that gets a few has read no more than their blocks.
 *   - Every public entry point silences HDF5 for its whole duration (or,
 *     lfio_radmap_headers_get(), for each HDF5 read it makes); the
 *     HDF5 plumbing (errors, attributes, layouts, atomic writes) is shared
 *     with light field files through h5util.h.
 */
#include <assert.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "chunks.h"
#include "h5util.h"
#include "ilf/options.h"
#include "ilf/pool.h"
#include "ilf/vec.h"
#include "internal.h"
#include "lfio/radmap.h"
#ifdef LFIO_MPI
#include "lfio/radmap_mpi.h"
#endif

#define FORMAT_NAME "ilfkit-radiance-maps"
#define FORMAT_VERSION 1
/* Rows per chunk: a few hundred KiB of cells, a whole polygon of vertices. */
#define CELL_CHUNK 16384
#define VERTEX_CHUNK 1024
/* Cell datasets smaller than this are stored without shuffle and deflate:
 * zlib would save a few hundred bytes of each and costs a stream set-up of
 * about 64 KiB each time. Writing the light-field classroom's maps (64%
 * of its 15,155 cell datasets are this small at 1.3 M cells, 99% at 51k)
 * takes 0.8x the instructions; its file is 8% larger at 1.3 M cells. */
#define DEFLATE_MIN_BYTES 1024
/* zlib level of the cell datasets: a relight writes its maps on the way out,
 * where level 4 took 0.22 s for the paper's 'beams' (110,750 cells) and level
 * 1 takes 0.14 s for a file 3.4% larger. */
#define MAP_DEFLATE_LEVEL 1
/* Tolerance on the map frame's unit, orthogonal, right-handed axes. */
#define FRAME_TOL 1e-6

/* ------------------------------------------------------------- dataset layouts */

/* The datasets of a patch, in file order. */
enum map_ds { MAP_VERTICES, MAP_CELL_IJ, MAP_CELL_AREA, MAP_CELL_CENTRE, MAP_IRRADIANCE, MAP_RADIOSITY,
              MAP_DS_COUNT };

/* What one dataset of a patch holds; its rows are vertices or cells. */
struct map_dataset {
    const char *name;
    int width;          /* values per row; 0 for a 1-D dataset */
    H5T_class_t cls;    /* H5T_FLOAT or H5T_INTEGER (unsigned) */
    size_t size;        /* bytes per value in the file and in memory */
    const char *units;
    const char *axes;
    int per_vertex;     /* rows are vertices (else cells) */
    int deflate;
};

static const struct map_dataset map_datasets[MAP_DS_COUNT] = {
    {"vertices", 3, H5T_FLOAT, 8, "m", "vertex:xyz", 1, 0},
    {"cell_ij", 2, H5T_INTEGER, 4, "1", "cell:ij", 0, 1},
    {"cell_area", 0, H5T_FLOAT, 8, "m^2", "cell", 0, 1},
    {"cell_centre", 3, H5T_FLOAT, 8, "m", "cell:xyz", 0, 1},
    {"irradiance", 3, H5T_FLOAT, 4, "W m^-2", "cell:rgb", 0, 1},
    {"radiosity", 3, H5T_FLOAT, 4, "W m^-2", "cell:rgb", 0, 1},
};

/* @return the smaller of a and b, but at least 1 (a chunk is never empty). */
static hsize_t chunk_rows(hsize_t rows, hsize_t limit)
{
    hsize_t c = rows < limit ? rows : limit;
    return c > 0 ? c : 1;
}

/* A dataset's shape and labels, as both formats' tables give them. */
struct ds_shape {
    const char *name;
    int width; /* values per row; 0 for a 1-D dataset */
    H5T_class_t cls;
    size_t size;
    const char *units;
    const char *axes;
};

/* Fills *l with the layout of a dataset of shape d and rows rows, in chunks of at most chunk_limit rows,
 * deflated at level when it holds DEFLATE_MIN_BYTES or more (level 0: never). */
static void layout_fill(const struct ds_shape *d, hsize_t rows, hsize_t chunk_limit, int level, lfio__h5_layout *l)
{
    memset(l, 0, sizeof *l);
    snprintf(l->name, sizeof l->name, "%s", d->name);
    l->rank = d->width ? 2 : 1;
    l->dims[0] = rows;
    l->chunk[0] = chunk_rows(rows, chunk_limit);
    if (d->width) {
        l->dims[1] = (hsize_t)d->width;
        l->chunk[1] = (hsize_t)d->width;
    }
    l->cls = d->cls;
    l->size = d->size;
    l->units = d->units;
    l->axes = d->axes;
    l->deflate = level > 0 && rows * (hsize_t)(d->width ? d->width : 1) * d->size >= DEFLATE_MIN_BYTES ? level : 0;
}

/* Fills *l with the layout of dataset which of a patch with nverts vertices and ncells cells. */
static void patch_layout(enum map_ds which, uint32_t nverts, uint32_t ncells, lfio__h5_layout *l)
{
    const struct map_dataset *m = &map_datasets[which];
    const struct ds_shape d = {m->name, m->width, m->cls, m->size, m->units, m->axes};
    layout_fill(&d, m->per_vertex ? nverts : ncells, m->per_vertex ? VERTEX_CHUNK : CELL_CHUNK,
                m->deflate ? MAP_DEFLATE_LEVEL : 0, l);
}

/* @return the native memory type of dataset which. */
static hid_t memory_type(enum map_ds which)
{
    const struct map_dataset *m = &map_datasets[which];
    if (m->cls == H5T_INTEGER)
        return H5T_NATIVE_UINT32;
    return m->size == 4 ? H5T_NATIVE_FLOAT : H5T_NATIVE_DOUBLE;
}

/* @return the number of values dataset which holds for patch p. */
static size_t value_count(enum map_ds which, const lfio_radmap_patch *p)
{
    const struct map_dataset *m = &map_datasets[which];
    size_t rows = m->per_vertex ? p->nverts : p->ncells;
    return rows * (size_t)(m->width ? m->width : 1);
}

/* @return patch p's array for dataset which (borrowed). */
static const void *patch_array(const lfio_radmap_patch *p, enum map_ds which)
{
    switch (which) {
    case MAP_VERTICES: return p->vertices;
    case MAP_CELL_IJ: return p->cell_ij;
    case MAP_CELL_AREA: return p->cell_area;
    case MAP_CELL_CENTRE: return p->cell_centre;
    case MAP_IRRADIANCE: return p->irradiance;
    case MAP_RADIOSITY: return p->radiosity;
    case MAP_DS_COUNT: break;
    }
    return NULL;
}

/* ---------------------------------------------------------------- checking */

/* @return 1 if all count values of v are finite. */
static int all_finite(const double *v, size_t count)
{
    for (size_t k = 0; k < count; k++)
        if (!isfinite(v[k]))
            return 0;
    return 1;
}


/* Checks that e1, e2 are unit and orthogonal and normal = e1 x e2. @return 1, or 0 with a reason in why. */
static int check_frame(const lfio_radmap_patch *p, char *why, size_t why_size)
{
    const double cross[3] = {p->e1[1] * p->e2[2] - p->e1[2] * p->e2[1],
                             p->e1[2] * p->e2[0] - p->e1[0] * p->e2[2],
                             p->e1[0] * p->e2[1] - p->e1[1] * p->e2[0]};
    if (!all_finite(p->origin, 3) || !all_finite(p->e1, 3) || !all_finite(p->e2, 3) || !all_finite(p->normal, 3))
        snprintf(why, why_size, "map frame is not finite");
    else if (fabs(a3_dot(p->e1, p->e1) - 1) > FRAME_TOL || fabs(a3_dot(p->e2, p->e2) - 1) > FRAME_TOL)
        snprintf(why, why_size, "e1 and e2 must be unit vectors");
    else if (fabs(a3_dot(p->e1, p->e2)) > FRAME_TOL)
        snprintf(why, why_size, "e1 and e2 are not orthogonal (e1.e2 = %g)", a3_dot(p->e1, p->e2));
    else if (fabs(p->normal[0] - cross[0]) + fabs(p->normal[1] - cross[1]) + fabs(p->normal[2] - cross[2])
             > FRAME_TOL)
        snprintf(why, why_size, "normal is not e1 x e2");
    else
        return 1;
    return 0;
}

/* @return 1 if every albedo channel is in [0, 1] and every emission channel finite and >= 0. */
static int material_valid(const lfio_radmap_patch *p)
{
    for (int c = 0; c < 3; c++)
        if (!(p->albedo[c] >= 0 && p->albedo[c] <= 1) || !(p->emission[c] >= 0 && isfinite(p->emission[c])))
            return 0;
    return 1;
}

/* Checks the scalars of p: label, counts, grid and material. @return 1, or 0 with a reason in why. */
static int check_patch_scalars(const lfio_radmap_patch *p, char *why, size_t why_size)
{
    if (p->label == NULL || strlen(p->label) > LFIO_RADMAP_TEXT_MAX)
        snprintf(why, why_size, "label is missing or longer than %u bytes", LFIO_RADMAP_TEXT_MAX);
    else if (p->nverts < 3 || p->nverts > LFIO_RADMAP_MAX_VERTS)
        snprintf(why, why_size, "%u vertices, expected 3 to %u", p->nverts, LFIO_RADMAP_MAX_VERTS);
    else if (!(isfinite(p->cell_size) && p->cell_size > 0) || !isfinite(p->u0) || !isfinite(p->v0))
        snprintf(why, why_size, "cell_size must be finite and > 0, u0 and v0 finite");
    else if ((uint64_t)p->ncells > (uint64_t)p->nu * p->nv)
        snprintf(why, why_size, "%u cells in a grid of %u x %u", p->ncells, p->nu, p->nv);
    else if (!check_frame(p, why, why_size))
        return 0;
    else if (!material_valid(p))
        snprintf(why, why_size, "albedo must be in [0, 1] and emission finite and >= 0");
    else
        return 1;
    return 0;
}

/* Checks the arrays of p (present, finite, in range), whose cells are cells [first, first + p->ncells) of
 * its patch (numbered so in messages). @return 1, or 0 with a reason in why. */
static int check_patch_arrays(const lfio_radmap_patch *p, uint32_t first, char *why, size_t why_size)
{
    for (int k = 0; k < MAP_DS_COUNT; k++)
        if (value_count((enum map_ds)k, p) > 0 && patch_array(p, (enum map_ds)k) == NULL) {
            snprintf(why, why_size, "%s is NULL", map_datasets[k].name);
            return 0;
        }
    if (!all_finite(p->vertices, 3 * (size_t)p->nverts)) {
        snprintf(why, why_size, "vertices are not finite");
        return 0;
    }
    for (uint32_t c = 0; c < p->ncells; c++) {
        const uint32_t i = p->cell_ij[2 * c], j = p->cell_ij[2 * c + 1];
        const double area = p->cell_area[c];
        const unsigned long long cell = (unsigned long long)first + c;
        if (i >= p->nu || j >= p->nv)
            snprintf(why, why_size, "cell %llu: (i, j) = (%u, %u) outside the %u x %u grid", cell, i, j, p->nu,
                     p->nv);
        else if (!(isfinite(area) && area > 0))
            snprintf(why, why_size, "cell %llu: area %g is not finite and > 0", cell, area);
        else if (!all_finite(p->cell_centre + 3 * (size_t)c, 3))
            snprintf(why, why_size, "cell %llu: centre is not finite", cell);
        else
            continue;
        return 0;
    }
    const size_t n = 3 * (size_t)p->ncells;
    size_t bad = lfio__first_bad_value(p->irradiance, n);
    const char *name = "irradiance";
    if (bad == n) {
        bad = lfio__first_bad_value(p->radiosity, n);
        name = "radiosity";
    }
    if (bad == n)
        return 1;
    const float value = name[0] == 'i' ? p->irradiance[bad] : p->radiosity[bad];
    snprintf(why, why_size, "%s of cell %llu is %g, expected finite and >= 0", name,
             (unsigned long long)first + bad / 3, (double)value);
    return 0;
}

/* Checks everything about patch p. @return 1, or 0 with a reason in why. */
static int check_patch(const lfio_radmap_patch *p, char *why, size_t why_size)
{
    return check_patch_scalars(p, why, why_size) && check_patch_arrays(p, 0, why, why_size);
}

/* Checks what lfio_radmap_read_headers() holds of patch p: its scalars and its vertices (present and
 * finite; its cell arrays are not read). @return 1, or 0 with a reason in why. */
static int check_patch_header(const lfio_radmap_patch *p, char *why, size_t why_size)
{
    if (!check_patch_scalars(p, why, why_size))
        return 0;
    if (p->vertices == NULL || !all_finite(p->vertices, 3 * (size_t)p->nverts)) {
        snprintf(why, why_size, "vertices are missing or not finite");
        return 0;
    }
    return 1;
}

/* Checks patch p as read whole, or only its headers (headers set). */
static int check_patch_read(const lfio_radmap_patch *p, int headers, char *why, size_t why_size)
{
    return headers ? check_patch_header(p, why, why_size) : check_patch(p, why, why_size);
}

/* ----------------------------------------------------------------- writing */

/* What lfio_radmap_write() puts in a file. */
struct map_content {
    const char *creator;
    const char *scene;
    size_t count;
    lfio_radmap_describe_fn describe;
    lfio_radmap_rows_fn rows; /* NULL: the cells are the described patch's own arrays */
    void *user;
    int rank, ranks; /* this writer among those of a collective write (format 1: patch k's arrays are rank k mod
                      * ranks's; format 2: v2_gather()) */
    int serial;      /* written by lfio_radmap_write_rows() (or _each()), not through MPI-IO (even with one rank) */
    int format;      /* the format version written: 1 or 2 */
    unsigned threads; /* threads compressing chunks in a serial write (0: every core) */
    int level;       /* format 2: zlib level of datasets of 1 KiB or more, 0 for none */
    const struct v2_prepared *prepared; /* format 2 written by rank 0 for the ranks of an MPI job: the content
                                         * gathered and filtered already (NULL: gathered and filtered here) */
    int held_all;    /* an MPI job's: every rank can give every patch's cells (lfio_radmap_write_rows_mpi()) */
};

/* Writes the attributes of patch group g (obj) describing p. */
static lfio_status write_patch_attrs(const char *path, const char *obj, hid_t g, const lfio_radmap_patch *p)
{
    const struct {
        const char *name;
        const double *value;
        hsize_t count;
    } doubles[] = {{"origin", p->origin, 3}, {"e1", p->e1, 3}, {"e2", p->e2, 3}, {"normal", p->normal, 3},
                   {"cell_size", &p->cell_size, 0}, {"u0", &p->u0, 0}, {"v0", &p->v0, 0}};
    const struct {
        const char *name;
        const uint32_t *value;
    } counts[] = {{"polygon", &p->polygon}, {"nu", &p->nu}, {"nv", &p->nv}};
    lfio_status st = lfio__h5_put_str_attr(path, obj, g, "label", p->label);
    for (size_t k = 0; st == LFIO_OK && k < sizeof counts / sizeof counts[0]; k++)
        st = lfio__h5_put_num_attr(path, obj, g, counts[k].name, H5T_STD_U32LE, H5T_NATIVE_UINT32, 0,
                                   counts[k].value);
    for (size_t k = 0; st == LFIO_OK && k < sizeof doubles / sizeof doubles[0]; k++)
        st = lfio__h5_put_num_attr(path, obj, g, doubles[k].name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE,
                                   doubles[k].count, doubles[k].value);
    if (st == LFIO_OK)
        st = lfio__h5_put_str_attr(path, obj, g, "length_units", "m");
    if (st == LFIO_OK)
        st = lfio__h5_put_num_attr(path, obj, g, "albedo", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, 3, p->albedo);
    if (st == LFIO_OK)
        st = lfio__h5_put_num_attr(path, obj, g, "emission", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, 3, p->emission);
    return st;
}

/* A patch being written: its group and datasets, and the chunks filtered apart (chunks.h). */
typedef struct patch_write {
    const char *path;
    hid_t patches;
    size_t k;
    const lfio_radmap_patch *p;
    int mine, direct;
    char obj[64];
    hid_t g, d[MAP_DS_COUNT];
    lfio__h5_layout lay[MAP_DS_COUNT];
    lfio_status st;
} patch_write;

/* Names dataset t of w for messages, in buf. @return buf. */
static const char *dataset_obj(const patch_write *w, int t, char *buf, size_t size)
{
    snprintf(buf, size, "%.63s/%.31s", w->obj, w->lay[t].name);
    return buf;
}

/* Creates w's group, its attributes and its datasets, and writes its vertices (the cells come a slice at a
 * time: write_patch()); stops at the first failure (w->st). */
static void patch_objects(void *arg)
{
    patch_write *w = arg;
    char name[24];
    snprintf(name, sizeof name, "%zu", w->k);
    w->st = lfio__h5_create_group(w->path, w->obj, w->patches, name, &w->g);
    if (w->st == LFIO_OK)
        w->st = write_patch_attrs(w->path, w->obj, w->g, w->p);
    for (int t = 0; w->st == LFIO_OK && t < MAP_DS_COUNT; t++) {
        char dobj[128];
        dataset_obj(w, t, dobj, sizeof dobj);
        w->st = lfio__h5_create_dataset(w->path, w->obj, w->g, &w->lay[t], &w->d[t]);
        if (w->st == LFIO_OK && map_datasets[t].per_vertex) {
            const hsize_t zero[2] = {0, 0};
            w->st = lfio__h5_write_part(w->path, dobj, w->d[t], memory_type((enum map_ds)t), w->lay[t].rank, zero,
                                        w->lay[t].dims, patch_array(w->p, (enum map_ds)t), w->mine);
        }
    }
}

/* Where a chunk goes: its dataset and its first row. */
typedef struct chunk_place {
    int t;
    hsize_t row;
} chunk_place;

/* Lists the chunks of w's deflated datasets that begin in cells [first, first + w->p->ncells), w->p holding
 * those cells, in c and where they go in at (both NULL: counts them). @return their number. */
static size_t patch_chunks(const patch_write *w, uint32_t first, lfio__chunk *c, chunk_place *at)
{
    size_t n = 0;
    const hsize_t end = (hsize_t)first + w->p->ncells;
    for (int t = 0; t < MAP_DS_COUNT; t++) {
        const lfio__h5_layout *l = &w->lay[t];
        size_t row = (size_t)(l->rank == 2 ? l->dims[1] : 1) * l->size;
        const unsigned char *a = patch_array(w->p, (enum map_ds)t);
        /* only cell datasets are deflated, and a slice starts on a chunk's first row */
        for (hsize_t r0 = first; l->deflate && r0 < end; r0 += l->chunk[0], n++) {
            size_t take = (size_t)(l->dims[0] - r0 < l->chunk[0] ? l->dims[0] - r0 : l->chunk[0]);
            if (c)
                c[n] = (lfio__chunk){a + (size_t)(r0 - first) * row, take * row, (size_t)l->chunk[0] * row, l->size,
                                     l->deflate, NULL, 0};
            if (at)
                at[n] = (chunk_place){t, r0};
        }
    }
    return n;
}

/* Writes cells [first, first + w->p->ncells) of w's cell datasets that lfio does not filter itself (all of
 * them unless w->direct, else those without deflate) from w->p, through HDF5.
 * @return LFIO_OK, or LFIO_ERR_IO with the message set. */
static lfio_status write_cell_rows(const patch_write *w, uint32_t first)
{
    for (int t = 0; t < MAP_DS_COUNT; t++) {
        if (map_datasets[t].per_vertex || (w->direct && w->lay[t].deflate))
            continue;
        char dobj[128];
        const hsize_t offset[2] = {first, 0}, count[2] = {w->p->ncells, w->lay[t].dims[1]};
        lfio_status st = lfio__h5_write_part(w->path, dataset_obj(w, t, dobj, sizeof dobj), w->d[t],
                                             memory_type((enum map_ds)t), w->lay[t].rank, offset, count,
                                             patch_array(w->p, (enum map_ds)t), w->mine);
        if (st != LFIO_OK)
            return st;
    }
    return LFIO_OK;
}

/* Stores the n filtered chunks c where at says, as they are. @return LFIO_OK, or LFIO_ERR_IO. */
static lfio_status store_chunks(const patch_write *w, const lfio__chunk *c, const chunk_place *at, size_t n)
{
    for (size_t k = 0; k < n; k++) {
        const hsize_t offset[2] = {at[k].row, 0};
        /* filter mask 0: every filter of the pipeline was applied */
        if (H5Dwrite_chunk(w->d[at[k].t], H5P_DEFAULT, 0, offset, c[k].out_bytes, c[k].out) < 0) {
            char dobj[128];
            return lfio__h5_fail(LFIO_ERR_IO, w->path, dataset_obj(w, at[k].t, dobj, sizeof dobj),
                                 "cannot store a chunk");
        }
    }
    return LFIO_OK;
}

/* Points q at cells [first, first + count) of patch k, described as p: from the caller's rows function
 * (lfio_radmap_write_rows()), else within p's own arrays; and checks them. @return LFIO_OK, rows's
 * status, or LFIO_ERR_ARG naming the patch and the problem. */
static lfio_status patch_slice(const struct map_content *mc, const char *path, size_t k, const lfio_radmap_patch *p,
                               uint32_t first, uint32_t count, lfio_radmap_patch *q)
{
    *q = *p;
    q->ncells = count;
    if (mc->rows != NULL) {
        lfio_radmap_rows r;
        memset(&r, 0, sizeof r);
        lfio_status st = mc->rows(mc->user, k, first, count, &r);
        if (st != LFIO_OK)
            return st;
        q->cell_ij = r.cell_ij, q->cell_area = r.cell_area, q->cell_centre = r.cell_centre;
        q->irradiance = r.irradiance, q->radiosity = r.radiosity;
    } else {
        q->cell_ij = p->cell_ij ? p->cell_ij + 2 * (size_t)first : NULL;
        q->cell_area = p->cell_area ? p->cell_area + first : NULL;
        q->cell_centre = p->cell_centre ? p->cell_centre + 3 * (size_t)first : NULL;
        q->irradiance = p->irradiance ? p->irradiance + 3 * (size_t)first : NULL;
        q->radiosity = p->radiosity ? p->radiosity + 3 * (size_t)first : NULL;
    }
    char why[256];
    if (!check_patch_arrays(q, first, why, sizeof why))
        return lfio__fail(LFIO_ERR_ARG, "%s: patch %zu (%s): %s", path, k, p->label, why);
    return LFIO_OK;
}

/* Every slice but a patch's last is a whole number of chunks, and a patch of more than one slice has every
 * cell dataset deflated, so that lfio's own filtering only ever sees whole chunks of one slice. */
_Static_assert(LFIO_RADMAP_ROWS_MAX % CELL_CHUNK == 0, "a slice is a whole number of chunks");
_Static_assert(LFIO_RADMAP_ROWS_MAX * 4 >= DEFLATE_MIN_BYTES, "a patch of several slices is all deflated");

/* Writes patch p (as described, k of the content mc) as group /patches/k of the file whose "patches" group
 * is patches; its arrays only when mine (a collective write's other ranks take part with nothing).
 * A serial write takes the cells a slice at a time (LFIO_RADMAP_ROWS_MAX), a collective one the whole patch.
 * direct: the deflated datasets' chunks are filtered by lfio on several threads, then stored as they are
 * (a serial write on a little-endian machine: the arrays' bytes are the stored ones), the first slice's
 * while HDF5 makes the patch's objects; HDF5 filters the others. @return LFIO_OK, or the first failure's
 * status (rows's, LFIO_ERR_ARG, LFIO_ERR_NOMEM, LFIO_ERR_IO) with its message. */
static lfio_status write_patch(const struct map_content *mc, const char *path, hid_t patches, size_t k,
                               const lfio_radmap_patch *p, int mine, int direct)
{
    lfio_radmap_patch q = *p;
    patch_write w;
    memset(&w, 0, sizeof w);
    w.path = path, w.patches = patches, w.k = k, w.p = &q, w.mine = mine, w.direct = direct, w.g = -1;
    snprintf(w.obj, sizeof w.obj, "/patches/%zu", k);
    for (int t = 0; t < MAP_DS_COUNT; t++) {
        w.d[t] = -1;
        patch_layout((enum map_ds)t, p->nverts, p->ncells, &w.lay[t]);
    }
    const uint32_t step = mc->serial ? LFIO_RADMAP_ROWS_MAX : p->ncells;
    q.ncells = p->ncells < step ? p->ncells : step;
    size_t cap = direct ? patch_chunks(&w, 0, NULL, NULL) : 0;
    lfio__chunk *c = cap ? malloc(cap * sizeof *c) : NULL;
    chunk_place *at = cap ? malloc(cap * sizeof *at) : NULL;
    if (cap && (c == NULL || at == NULL))
        w.st = lfio__fail(LFIO_ERR_NOMEM, "%s: %s: out of memory", path, w.obj);
    const unsigned threads = ilf_thread_count(mc->threads);
    uint32_t first = 0;
    while (w.st == LFIO_OK) {
        const uint32_t count = p->ncells - first < step ? p->ncells - first : step;
        if ((w.st = patch_slice(mc, path, k, p, first, count, &q)) != LFIO_OK)
            break;
        size_t n = direct ? patch_chunks(&w, first, c, at) : 0;
        if (lfio__chunks_filter(c, n, threads, first == 0 ? patch_objects : NULL, &w) != 0 && w.st == LFIO_OK)
            w.st = lfio__fail(LFIO_ERR_NOMEM, "%s: %s: out of memory", path, w.obj);
        if (w.st == LFIO_OK)
            w.st = store_chunks(&w, c, at, n);
        lfio__chunks_free(c, n);
        if (w.st == LFIO_OK)
            w.st = write_cell_rows(&w, first);
        if ((first += count) >= p->ncells)
            break;
    }
    free(c);
    free(at);
    /* Closing flushes the chunk cache: the last chunks reach the file only here. */
    for (int t = 0; t < MAP_DS_COUNT; t++) {
        char dobj[128];
        if (w.d[t] >= 0 && H5Dclose(w.d[t]) < 0 && w.st == LFIO_OK)
            w.st = lfio__h5_fail(LFIO_ERR_IO, path, dataset_obj(&w, t, dobj, sizeof dobj), "cannot flush dataset");
    }
    if (w.g >= 0 && H5Gclose(w.g) < 0 && w.st == LFIO_OK)
        w.st = lfio__h5_fail(LFIO_ERR_IO, path, w.obj, "cannot close group");
    return w.st;
}

/* ------------------------------------------------------- format 2: writing */

/*
 * Format 2 stores each array once for all patches (docs/format.md, "Format
 * version 2"): the per-patch tables (one row a patch), the offsets of each
 * patch's vertices and cells (patch_count + 1 rows), the NUL-terminated
 * labels one after another, and the vertices and cells of every patch
 * concatenated in patch order. A write is then one transfer a dataset
 * whatever the number of patches. The writer gathers the whole content
 * first (every rank all the tables and vertices, each rank the cells of its
 * own patches: a contiguous run of them; a serial write its cells filtered
 * as they come, v2_stream), then creates and writes the datasets; the
 * reader checks the tables before it sizes the arrays.
 */

/* The datasets of format 2, in file order. */
enum v2_ds { V2_LABEL, V2_POLYGON, V2_NU, V2_NV, V2_ORIGIN, V2_E1, V2_E2, V2_NORMAL, V2_CELL_SIZE, V2_U0, V2_V0,
             V2_ALBEDO, V2_EMISSION, V2_VERTEX_OFFSET, V2_CELL_OFFSET, V2_VERTICES, V2_CELL_IJ, V2_CELL_AREA,
             V2_CELL_CENTRE, V2_IRRADIANCE, V2_RADIOSITY, V2_COUNT };

/* What the rows of a format-2 dataset are. */
enum v2_rows { ROWS_LABEL_BYTES, ROWS_PATCH, ROWS_OFFSET, ROWS_VERTEX, ROWS_CELL };

/* One dataset of format 2: as map_datasets[], and what its rows are. */
struct v2_dataset {
    const char *name;
    int width;
    H5T_class_t cls;
    size_t size;
    const char *units;
    const char *axes;
    enum v2_rows rows;
};

static const struct v2_dataset v2_datasets[V2_COUNT] = {
    {"label", 0, H5T_INTEGER, 1, "1", "byte", ROWS_LABEL_BYTES},
    {"polygon", 0, H5T_INTEGER, 4, "1", "patch", ROWS_PATCH},
    {"nu", 0, H5T_INTEGER, 4, "1", "patch", ROWS_PATCH},
    {"nv", 0, H5T_INTEGER, 4, "1", "patch", ROWS_PATCH},
    {"origin", 3, H5T_FLOAT, 8, "m", "patch:xyz", ROWS_PATCH},
    {"e1", 3, H5T_FLOAT, 8, "1", "patch:xyz", ROWS_PATCH},
    {"e2", 3, H5T_FLOAT, 8, "1", "patch:xyz", ROWS_PATCH},
    {"normal", 3, H5T_FLOAT, 8, "1", "patch:xyz", ROWS_PATCH},
    {"cell_size", 0, H5T_FLOAT, 8, "m", "patch", ROWS_PATCH},
    {"u0", 0, H5T_FLOAT, 8, "m", "patch", ROWS_PATCH},
    {"v0", 0, H5T_FLOAT, 8, "m", "patch", ROWS_PATCH},
    {"albedo", 3, H5T_FLOAT, 4, "1", "patch:rgb", ROWS_PATCH},
    {"emission", 3, H5T_FLOAT, 4, "W sr^-1 m^-2", "patch:rgb", ROWS_PATCH},
    {"vertex_offset", 0, H5T_INTEGER, 4, "1", "patch", ROWS_OFFSET},
    {"cell_offset", 0, H5T_INTEGER, 4, "1", "patch", ROWS_OFFSET},
    {"vertices", 3, H5T_FLOAT, 8, "m", "vertex:xyz", ROWS_VERTEX},
    {"cell_ij", 2, H5T_INTEGER, 4, "1", "cell:ij", ROWS_CELL},
    {"cell_area", 0, H5T_FLOAT, 8, "m^2", "cell", ROWS_CELL},
    {"cell_centre", 3, H5T_FLOAT, 8, "m", "cell:xyz", ROWS_CELL},
    {"irradiance", 3, H5T_FLOAT, 4, "W m^-2", "cell:rgb", ROWS_CELL},
    {"radiosity", 3, H5T_FLOAT, 4, "W m^-2", "cell:rgb", ROWS_CELL},
};

/* Rows per chunk of every format-2 dataset: at most 384 KiB of values. */
#define V2_CHUNK 16384

/* @return the bytes of one row of format-2 dataset t. */
static size_t v2_row_bytes(enum v2_ds t)
{
    const struct v2_dataset *m = &v2_datasets[t];
    return (size_t)(m->width ? m->width : 1) * m->size;
}

/* Fills *l with the layout of format-2 dataset t of rows rows, deflated at level when 1 KiB or more. */
static void v2_layout(enum v2_ds t, uint64_t rows, int level, lfio__h5_layout *l)
{
    const struct v2_dataset *m = &v2_datasets[t];
    const struct ds_shape d = {m->name, m->width, m->cls, m->size, m->units, m->axes};
    layout_fill(&d, rows, V2_CHUNK, level, l);
}

/* @return the native memory type of format-2 dataset t. */
static hid_t v2_memory_type(enum v2_ds t)
{
    const struct v2_dataset *m = &v2_datasets[t];
    if (m->cls == H5T_INTEGER)
        return m->size == 4 ? H5T_NATIVE_UINT32 : H5T_NATIVE_UINT8;
    return m->size == 4 ? H5T_NATIVE_FLOAT : H5T_NATIVE_DOUBLE;
}

/* The whole content of a format-2 file, gathered: one array a dataset. Cells are those of patches
 * [mine_first, mine_end) alone, cells [cell_first, cell_first + rows[cells]) of the file. */
typedef struct v2_content {
    unsigned char *a[V2_COUNT];
    uint64_t rows[V2_COUNT], cap[V2_COUNT];
    size_t mine_first, mine_end;
    uint64_t cell_first;
    struct v2_stream *stream; /* the cells go filtered as they come (v2_stream_add()); NULL: into a[] whole */
} v2_content;

/* Format 2's content ready for the file, made by the ranks of an MPI job for rank 0 to write: v holds
 * every table and the whole arrays of the cell datasets that are not deflated; a deflated dataset t is
 * the n[t] chunks c[t], filtered, in file order. */
struct v2_prepared {
    v2_content v;
    lfio__chunk *c[V2_COUNT];
    size_t n[V2_COUNT];
};

/* A format-2 file's datasets, made in file order before any is written (v2_open_all()). */
typedef struct v2_open {
    hid_t d[V2_COUNT];          /* -1: not made */
    lfio__h5_layout l[V2_COUNT];
} v2_open;

/*
 * A serial write's cell datasets filtered as their rows arrive: the rows of the five cell datasets wait in
 * stages of `batch` whole chunks (the same rows in each), filtered together with lfio's pipeline on the
 * write's threads once full. When the file's datasets are made already (`open`: the cells asked for in a
 * second pass, after every patch is described), the filtered chunks are stored at once and the write holds
 * no more than its stages; otherwise (the cells come with each description) they are kept, compressed, in
 * prep for v2_store_held(). The rows left when every patch is in become the last chunks. Either way the
 * deflated cell datasets' chunks reach the file chunk by chunk, each chunk index in every dataset before
 * the next (v2_store_held() keeps that order), so the file is the same bytes however the cells came and
 * whatever the batch. A whole chunk is V2_CHUNK rows whenever there is one, and a dataset of one stage or
 * less is decided only at the end (deflated when 1 KiB or more, else written from its stage as it is).
 */
typedef struct v2_stream {
    struct v2_prepared *prep;
    const char *path;
    const v2_open *open;            /* the datasets to store each batch in; NULL: keep the batches in prep */
    int later;                      /* the cells are asked after every patch is described (v2_stream_rows()) */
    unsigned char *stage[V2_COUNT]; /* cell dataset t: its rows not filtered yet, at most batch chunks */
    uint64_t staged;                /* rows in each stage */
    uint64_t chunks_done;           /* chunks of each cell dataset filtered so far */
    size_t cap[V2_COUNT];           /* chunks prep->c[t] has room for */
    lfio__chunk *work;              /* one batch's chunks of every cell dataset, in file order */
    enum v2_ds *work_ds;            /* each one's dataset */
    size_t *work_index;             /* and its chunk index within the batch */
    uint32_t batch;                 /* whole chunks filtered together */
    unsigned threads;
    int level;
    lfio_status st;                 /* a failure storing a batch (its message set) */
} v2_stream;

/* Makes room for more rows of dataset t of v. @return 1, or 0 when memory runs out. */
static int v2_reserve(v2_content *v, enum v2_ds t, uint64_t more)
{
    const uint64_t need = v->rows[t] + more;
    if (need <= v->cap[t])
        return 1;
    uint64_t cap = v->cap[t] ? 2 * v->cap[t] : 64;
    while (cap < need)
        cap *= 2;
    if (cap > SIZE_MAX / v2_row_bytes(t))
        return 0;
    void *p = realloc(v->a[t], (size_t)cap * v2_row_bytes(t));
    if (p == NULL)
        return 0;
    v->a[t] = p;
    v->cap[t] = cap;
    return 1;
}

/* Appends rows rows of dataset t of v from src. @return 1, or 0 when memory runs out. */
static int v2_append(v2_content *v, enum v2_ds t, const void *src, uint64_t rows)
{
    if (rows == 0)
        return 1;
    if (!v2_reserve(v, t, rows))
        return 0;
    memcpy(v->a[t] + (size_t)v->rows[t] * v2_row_bytes(t), src, (size_t)rows * v2_row_bytes(t));
    v->rows[t] += rows;
    return 1;
}

/* Frees v's arrays. */
static void v2_free(v2_content *v)
{
    for (int t = 0; t < V2_COUNT; t++)
        free(v->a[t]);
}

/* Appends the table rows of patch p (its label, scalars, frame, material, vertices, next offsets) to v.
 * @return 1, or 0 when memory runs out. */
static int v2_add_patch(v2_content *v, const lfio_radmap_patch *p, uint32_t vertex_end, uint32_t cell_end)
{
    const struct {
        enum v2_ds t;
        const void *src;
    } rows[] = {{V2_POLYGON, &p->polygon},      {V2_NU, &p->nu},         {V2_NV, &p->nv},
                {V2_ORIGIN, p->origin},         {V2_E1, p->e1},          {V2_E2, p->e2},
                {V2_NORMAL, p->normal},         {V2_CELL_SIZE, &p->cell_size}, {V2_U0, &p->u0},
                {V2_V0, &p->v0},                {V2_ALBEDO, p->albedo},  {V2_EMISSION, p->emission},
                {V2_VERTEX_OFFSET, &vertex_end}, {V2_CELL_OFFSET, &cell_end}};
    int ok = v2_append(v, V2_LABEL, p->label, strlen(p->label) + 1);
    for (size_t k = 0; ok && k < sizeof rows / sizeof rows[0]; k++)
        ok = v2_append(v, rows[k].t, rows[k].src, 1);
    return ok && v2_append(v, V2_VERTICES, p->vertices, p->nverts);
}

/* The cell datasets of format 2, in v2_add_cells()'s order, with their format-1 names (patch_array()). */
static const struct {
    enum v2_ds t;
    enum map_ds m;
} v2_cells[] = {{V2_CELL_IJ, MAP_CELL_IJ},
                {V2_CELL_AREA, MAP_CELL_AREA},
                {V2_CELL_CENTRE, MAP_CELL_CENTRE},
                {V2_IRRADIANCE, MAP_IRRADIANCE},
                {V2_RADIOSITY, MAP_RADIOSITY}};
#define V2_CELL_DATASETS (sizeof v2_cells / sizeof v2_cells[0])

static int v2_stream_add(v2_stream *s, const lfio_radmap_patch *q);
static void v2_fill_scalars(unsigned char *const *w, size_t i, const char *label, lfio_radmap_patch *p);

/* Appends cells q (a checked slice of one patch) to v's cell arrays, or to its stream.
 * @return 1, or 0 when memory runs out. */
static int v2_add_cells(v2_content *v, const lfio_radmap_patch *q)
{
    if (v->stream)
        return v2_stream_add(v->stream, q);
    int ok = 1;
    for (size_t k = 0; ok && k < V2_CELL_DATASETS; k++)
        ok = v2_append(v, v2_cells[k].t, patch_array(q, v2_cells[k].m), q->ncells);
    return ok;
}

/* Takes the cells of patch k (described as p), a slice at a time, checked, into v. @return LFIO_OK or the
 * first failure's status. */
static lfio_status v2_gather_cells(const struct map_content *mc, const char *path, size_t k,
                                   const lfio_radmap_patch *p, v2_content *v)
{
    const uint32_t step = mc->serial ? LFIO_RADMAP_ROWS_MAX : p->ncells;
    uint32_t first = 0;
    do {
        lfio_radmap_patch q;
        const uint32_t count = p->ncells - first < step ? p->ncells - first : step;
        lfio_status st = patch_slice(mc, path, k, p, first, count, &q);
        if (st != LFIO_OK)
            return st;
        if (!v2_add_cells(v, &q))
            return lfio__fail(LFIO_ERR_NOMEM, "%s: patch %zu: out of memory", path, k);
        first += count;
    } while (first < p->ncells);
    return LFIO_OK;
}

/* Describes every patch of mc into v, checking each, with the cells of this rank's patches.
 * @return LFIO_OK or the first failure's status. */
static lfio_status v2_gather(const struct map_content *mc, const char *path, v2_content *v)
{
    const uint32_t zero = 0;
    uint64_t vertices = 0, cells = 0;
    /* where every rank holds every cell, an MPI write takes them by chunks later (mpi_take_rows()) */
    v->mine_first = mc->held_all ? mc->count : mc->count * (size_t)mc->rank / (size_t)mc->ranks;
    v->mine_end = mc->held_all ? mc->count : mc->count * ((size_t)mc->rank + 1) / (size_t)mc->ranks;
    if (!v2_append(v, V2_VERTEX_OFFSET, &zero, 1) || !v2_append(v, V2_CELL_OFFSET, &zero, 1))
        return lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", path);
    for (size_t k = 0; k < mc->count; k++) {
        lfio_radmap_patch p;
        memset(&p, 0, sizeof p);
        char why[256];
        lfio_status st = mc->describe(mc->user, k, &p);
        if (st != LFIO_OK)
            return st;
        if (!check_patch_scalars(&p, why, sizeof why))
            return lfio__fail(LFIO_ERR_ARG, "%s: patch %zu (%s): %s", path, k, p.label ? p.label : "no label", why);
        if ((cells += p.ncells) > LFIO_RADMAP_MAX_CELLS)
            return lfio__fail(LFIO_ERR_ARG, "%s: more than %llu cells", path, (unsigned long long)LFIO_RADMAP_MAX_CELLS);
        if ((vertices += p.nverts) > LFIO_RADMAP_MAX_FILE_VERTS)
            return lfio__fail(LFIO_ERR_ARG, "%s: more than %llu vertices", path,
                              (unsigned long long)LFIO_RADMAP_MAX_FILE_VERTS);
        if (p.vertices == NULL || !all_finite(p.vertices, 3 * (size_t)p.nverts))
            return lfio__fail(LFIO_ERR_ARG, "%s: patch %zu (%s): vertices are NULL or not finite", path, k, p.label);
        if (k == v->mine_first)
            v->cell_first = cells - p.ncells;
        if (!v2_add_patch(v, &p, (uint32_t)vertices, (uint32_t)cells))
            return lfio__fail(LFIO_ERR_NOMEM, "%s: patch %zu: out of memory", path, k);
        const int cells_now = !(v->stream && v->stream->later);
        if (cells_now && k >= v->mine_first && k < v->mine_end && (st = v2_gather_cells(mc, path, k, &p, v)) != LFIO_OK)
            return st;
    }
    if (v->mine_first == mc->count)
        v->cell_first = cells;
    return LFIO_OK;
}

/* Lists in c the chunks of rows [from, to) of a dataset of layout l and rows of row bytes, from a (which
 * holds those rows; from and to on chunk boundaries, or to the dataset's end). @return their number. */
static size_t v2_chunk_list(const lfio__h5_layout *l, size_t row, const unsigned char *a, uint64_t from, uint64_t to,
                            lfio__chunk *c)
{
    size_t n = 0;
    for (uint64_t r0 = from; r0 < to; r0 += l->chunk[0], n++) {
        const size_t take = (size_t)(l->dims[0] - r0 < l->chunk[0] ? l->dims[0] - r0 : l->chunk[0]);
        c[n] = (lfio__chunk){a + (size_t)(r0 - from) * row, take * row, (size_t)l->chunk[0] * row, l->size,
                             l->deflate, NULL, 0};
    }
    return n;
}

/* Sets up s to take a serial write's cells, into prep (zeroed) unless stored as they come, filtered at c's
 * level on c's threads. @return 1, or 0 when memory runs out. */
static int v2_stream_init(v2_stream *s, struct v2_prepared *prep, const struct map_content *c, const char *path)
{
    memset(s, 0, sizeof *s);
    s->prep = prep;
    s->path = path;
    s->later = c->rows != NULL;
    s->threads = ilf_thread_count(c->threads);
    /* a batch keeps every thread busy, and at most 8 chunks (3 MiB of the widest dataset) wait */
    s->batch = s->threads < 8 ? (s->threads > 0 ? s->threads : 1) : 8;
    s->level = c->level;
    for (size_t k = 0; k < V2_CELL_DATASETS; k++) {
        const enum v2_ds t = v2_cells[k].t;
        if ((s->stage[t] = malloc((size_t)s->batch * V2_CHUNK * v2_row_bytes(t))) == NULL)
            return 0;
    }
    const size_t most = V2_CELL_DATASETS * s->batch;
    s->work = malloc(most * sizeof *s->work);
    s->work_ds = malloc(most * sizeof *s->work_ds);
    s->work_index = malloc(most * sizeof *s->work_index);
    return s->work && s->work_ds && s->work_index;
}

static lfio_status v2_store_chunk(const char *path, const v2_open *o, enum v2_ds t, size_t k, const lfio__chunk *c);

/* Keeps chunk c (filtered) as the next of cell dataset t in s->prep. @return 1, or 0 when memory runs out. */
static int v2_stream_keep(v2_stream *s, enum v2_ds t, const lfio__chunk *c)
{
    struct v2_prepared *p = s->prep;
    if (p->n[t] == s->cap[t]) {
        size_t cap = s->cap[t] ? 2 * s->cap[t] : 16;
        lfio__chunk *grown = realloc(p->c[t], cap * sizeof *grown);
        if (grown == NULL)
            return 0;
        p->c[t] = grown, s->cap[t] = cap;
    }
    p->c[t][p->n[t]++] = *c;
    return 1;
}

/* Filters the first rows rows of the stages of the cell datasets deflated[] says, as chunks of chunk rows
 * (the last may be short), and stores them (s->open) chunk by chunk, or keeps them. @return 1, or 0 on a
 * failure (s->st says which). */
static int v2_stream_flush(v2_stream *s, uint64_t rows, uint64_t chunk, const int deflated[V2_COUNT])
{
    const size_t n = (size_t)((rows + chunk - 1) / chunk);
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
        for (size_t k = 0; k < V2_CELL_DATASETS; k++) {
            const enum v2_ds t = v2_cells[k].t;
            if (!deflated[t])
                continue;
            const size_t row = v2_row_bytes(t);
            const uint64_t r0 = i * chunk, take = rows - r0 < chunk ? rows - r0 : chunk;
            s->work_ds[m] = t, s->work_index[m] = i;
            s->work[m++] = (lfio__chunk){s->stage[t] + r0 * row, take * row, chunk * row, v2_datasets[t].size,
                                         s->level, NULL, 0};
        }
    assert(m <= V2_CELL_DATASETS * s->batch);
    if (lfio__chunks_filter(s->work, m, s->threads, NULL, NULL) != 0) {
        s->st = lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", s->path);
        return 0;
    }
    /* in the order they were listed: chunk by chunk, each in every dataset */
    for (size_t j = 0; j < m && s->st == LFIO_OK; j++) {
        const enum v2_ds t = s->work_ds[j];
        if (s->open)
            s->st = v2_store_chunk(s->path, s->open, t, (size_t)s->chunks_done + s->work_index[j], &s->work[j]);
        else if (v2_stream_keep(s, t, &s->work[j]))
            s->work[j].out = NULL; /* kept in prep, which frees it */
        else
            s->st = lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", s->path);
    }
    lfio__chunks_free(s->work, m);
    s->chunks_done += n;
    return s->st == LFIO_OK;
}

/* Takes the cells of slice q into s's stages, flushing them each time they fill (batch whole chunks of
 * V2_CHUNK rows: a dataset that fills one has at least that many rows, so it is deflated, since s->level
 * > 0, in chunks of V2_CHUNK rows). @return 1, or 0 on a failure (s->st). */
static int v2_stream_add(v2_stream *s, const lfio_radmap_patch *q)
{
    const uint64_t room = (uint64_t)s->batch * V2_CHUNK;
    static const int all[V2_COUNT] = {[V2_CELL_IJ] = 1, [V2_CELL_AREA] = 1, [V2_CELL_CENTRE] = 1,
                                      [V2_IRRADIANCE] = 1, [V2_RADIOSITY] = 1};
    for (uint64_t done = 0; done < q->ncells;) {
        const uint64_t take = room - s->staged < q->ncells - done ? room - s->staged : q->ncells - done;
        for (size_t k = 0; k < V2_CELL_DATASETS; k++) {
            const enum v2_ds t = v2_cells[k].t;
            const size_t row = v2_row_bytes(t);
            memcpy(s->stage[t] + (size_t)s->staged * row, (const unsigned char *)patch_array(q, v2_cells[k].m) + done * row,
                   (size_t)take * row);
        }
        s->staged += take, done += take;
        if (s->staged == room) {
            if (!v2_stream_flush(s, room, V2_CHUNK, all))
                return 0;
            s->staged = 0;
        }
    }
    return 1;
}

/* Ends s once every patch is in v (cells in all): the rows still staged of a deflated dataset become its
 * last chunks; a dataset that is not deflated (under 1 KiB: all its rows are still in the stage) moves to
 * v's arrays for a plain write. @return LFIO_OK or the failure's status. */
static lfio_status v2_stream_finish(v2_stream *s, v2_content *v, uint64_t cells)
{
    int deflated[V2_COUNT] = {0};
    uint64_t chunk = V2_CHUNK;
    for (size_t k = 0; k < V2_CELL_DATASETS; k++) {
        const enum v2_ds t = v2_cells[k].t;
        lfio__h5_layout l;
        v2_layout(t, cells, s->level, &l);
        deflated[t] = l.deflate != 0;
        chunk = l.chunk[0];
        if (!deflated[t]) {
            assert(s->chunks_done == 0 && s->staged == cells);
            free(v->a[t]);
            v->a[t] = s->stage[t], v->rows[t] = v->cap[t] = s->staged;
            s->stage[t] = NULL;
        }
    }
    if (s->staged > 0 && !v2_stream_flush(s, s->staged, chunk, deflated))
        return s->st;
    s->staged = 0;
    return LFIO_OK;
}

/* Asks for the cells of every patch described in v (all of them, in order: a serial write), a slice at a
 * time, checked, into s. @return LFIO_OK or the first failure's status. */
static lfio_status v2_stream_rows(const struct map_content *mc, const char *path, const v2_content *v,
                                  v2_stream *s)
{
    const uint32_t *voff = (const uint32_t *)v->a[V2_VERTEX_OFFSET];
    const char *label = (const char *)v->a[V2_LABEL];
    for (size_t k = 0; k < mc->count; k++, label += strlen(label) + 1) {
        lfio_radmap_patch p;
        v2_fill_scalars(v->a, k, label, &p);
        p.vertices = (const double *)v->a[V2_VERTICES] + 3 * (size_t)voff[k];
        uint32_t first = 0;
        do {
            lfio_radmap_patch q;
            const uint32_t count = p.ncells - first < LFIO_RADMAP_ROWS_MAX ? p.ncells - first : LFIO_RADMAP_ROWS_MAX;
            lfio_status st = patch_slice(mc, path, k, &p, first, count, &q);
            if (st != LFIO_OK)
                return st;
            if (!v2_stream_add(s, &q))
                return s->st;
            first += count;
        } while (first < p.ncells);
    }
    return LFIO_OK;
}

/* Frees s's stages and work, and the filtered chunks of prep. */
static void v2_stream_free(v2_stream *s, struct v2_prepared *prep)
{
    for (int t = 0; t < V2_COUNT; t++) {
        free(s->stage[t]);
        if (prep->c[t])
            lfio__chunks_free(prep->c[t], prep->n[t]);
        free(prep->c[t]);
    }
    free(s->work);
    free(s->work_ds);
    free(s->work_index);
}

/* Stores filtered chunk c as chunk k of dataset t of o, as it is. @return LFIO_OK, or LFIO_ERR_IO. */
static lfio_status v2_store_chunk(const char *path, const v2_open *o, enum v2_ds t, size_t k, const lfio__chunk *c)
{
    const hsize_t offset[2] = {(hsize_t)k * o->l[t].chunk[0], 0};
    /* filter mask 0: every filter of the pipeline was applied */
    if (H5Dwrite_chunk(o->d[t], H5P_DEFAULT, 0, offset, c->out_bytes, c->out) < 0) {
        char dobj[64];
        snprintf(dobj, sizeof dobj, "/patches/%s", o->l[t].name);
        return lfio__h5_fail(LFIO_ERR_IO, path, dobj, "cannot store a chunk");
    }
    return LFIO_OK;
}

/* Stores the n filtered chunks c of dataset t of o, in order. @return LFIO_OK, or LFIO_ERR_IO. */
static lfio_status v2_store_list(const char *path, const v2_open *o, enum v2_ds t, const lfio__chunk *c, size_t n)
{
    lfio_status st = LFIO_OK;
    for (size_t k = 0; st == LFIO_OK && k < n; k++)
        st = v2_store_chunk(path, o, t, k, &c[k]);
    return st;
}

/* Stores dataset t of o (v's array a, rows [0, o->l[t].dims[0])) as chunks lfio filters on threads threads,
 * then hands to HDF5 as they are. @return LFIO_OK, LFIO_ERR_NOMEM or LFIO_ERR_IO. */
static lfio_status v2_store_direct(const char *path, const v2_open *o, enum v2_ds t, const unsigned char *a,
                                   unsigned threads)
{
    const lfio__h5_layout *l = &o->l[t];
    const size_t n = (size_t)((l->dims[0] + l->chunk[0] - 1) / l->chunk[0]);
    lfio__chunk *c = calloc(n ? n : 1, sizeof *c);
    if (c == NULL)
        return lfio__fail(LFIO_ERR_NOMEM, "%s: /patches/%s: out of memory", path, l->name);
    v2_chunk_list(l, v2_row_bytes(t), a, 0, l->dims[0], c);
    lfio_status st = LFIO_OK;
    if (lfio__chunks_filter(c, n, threads, NULL, NULL) != 0)
        st = lfio__fail(LFIO_ERR_NOMEM, "%s: /patches/%s: out of memory", path, l->name);
    if (st == LFIO_OK)
        st = v2_store_list(path, o, t, c, n);
    lfio__chunks_free(c, n);
    free(c);
    return st;
}

/* @return whether dataset t of o comes as chunks lfio filtered (v2_stream, or an MPI job's prepared
 * content): a deflated cell dataset of a write whose chunks lfio filters (direct). */
static int v2_cells_filtered(const v2_open *o, enum v2_ds t, int direct)
{
    return direct && v2_datasets[t].rows == ROWS_CELL && o->l[t].deflate;
}

/* Makes every dataset of format 2 in group g, in file order, sized for v (cells cells). @return LFIO_OK or
 * the failure's status (the ones made are in o, to close). */
static lfio_status v2_open_all(const struct map_content *mc, const char *path, hid_t g, const v2_content *v,
                               uint64_t cells, v2_open *o)
{
    lfio_status st = LFIO_OK;
    for (int t = 0; st == LFIO_OK && t < V2_COUNT; t++) {
        v2_layout((enum v2_ds)t, v2_datasets[t].rows == ROWS_CELL ? cells : v->rows[t], mc->level, &o->l[t]);
        st = lfio__h5_create_dataset(path, "/patches", g, &o->l[t], &o->d[t]);
    }
    return st;
}

/* Stores the filtered cell chunks prep holds, chunk by chunk, each in every cell dataset (v2_stream's
 * order). @return LFIO_OK, or LFIO_ERR_IO. */
static lfio_status v2_store_held(const char *path, const v2_open *o, const struct v2_prepared *prep, int direct)
{
    size_t most = 0;
    for (size_t k = 0; k < V2_CELL_DATASETS; k++)
        most = prep->n[v2_cells[k].t] > most ? prep->n[v2_cells[k].t] : most;
    lfio_status st = LFIO_OK;
    for (size_t i = 0; i < most; i++)
        for (size_t k = 0; st == LFIO_OK && k < V2_CELL_DATASETS; k++) {
            const enum v2_ds t = v2_cells[k].t;
            if (v2_cells_filtered(o, t, direct) && i < prep->n[t])
                st = v2_store_chunk(path, o, t, i, &prep->c[t][i]);
        }
    return st;
}

/* Writes this rank's part of every dataset of o from v but the cell chunks stored already: the cells of
 * its own patches, every other dataset on rank 0 (all ranks take part in a collective write). direct: lfio
 * filters the deflated datasets' chunks itself. @return LFIO_OK or the failure's status. */
static lfio_status v2_write_rest(const struct map_content *mc, const char *path, const v2_open *o,
                                 const v2_content *v, int direct)
{
    lfio_status st = LFIO_OK;
    for (int t = 0; st == LFIO_OK && t < V2_COUNT; t++) {
        const lfio__h5_layout *l = &o->l[t];
        const int is_cells = v2_datasets[t].rows == ROWS_CELL;
        if (l->dims[0] == 0 || v2_cells_filtered(o, (enum v2_ds)t, direct))
            continue;
        if (direct && l->deflate) {
            /* an MPI job's tables come filtered by its last rank */
            st = mc->prepared ? v2_store_list(path, o, (enum v2_ds)t, mc->prepared->c[t], mc->prepared->n[t])
                              : v2_store_direct(path, o, (enum v2_ds)t, v->a[t], ilf_thread_count(mc->threads));
            continue;
        }
        char dobj[64];
        snprintf(dobj, sizeof dobj, "/patches/%s", l->name);
        const uint64_t first = is_cells ? v->cell_first : 0, rows = v->rows[t];
        const int mine = is_cells ? rows > 0 : mc->rank == 0;
        /* a rank with nothing of its own still takes part (lfio__h5_write_part() selects none when !mine),
         * with a count that is not empty, which it would skip */
        const hsize_t start[2] = {mine ? first : 0, 0}, count[2] = {mine ? rows : l->dims[0], l->dims[1]};
        st = lfio__h5_write_part(path, dobj, o->d[t], v2_memory_type((enum v2_ds)t), l->rank, start, count, v->a[t],
                                 mine);
    }
    return st;
}

/* Closes the datasets of o, in file order (closing flushes the chunk cache: the last chunks reach the file
 * only here). @return st, or the first failure to close when st is LFIO_OK. */
static lfio_status v2_close_all(const char *path, v2_open *o, lfio_status st)
{
    for (int t = 0; t < V2_COUNT; t++) {
        char dobj[64];
        snprintf(dobj, sizeof dobj, "/patches/%s", o->l[t].name);
        if (o->d[t] >= 0 && H5Dclose(o->d[t]) < 0 && st == LFIO_OK)
            st = lfio__h5_fail(LFIO_ERR_IO, path, dobj, "cannot flush dataset");
        o->d[t] = -1;
    }
    return st;
}

/* Writes the root attributes (format, format_version, creator, scene, patch_count) of a file of the given
 * format version. */
static lfio_status write_root(const char *path, hid_t file, const struct map_content *c, int32_t version)
{
    const uint32_t count = (uint32_t)c->count;
    lfio_status st = lfio__h5_put_str_attr(path, "/", file, "format", FORMAT_NAME);
    if (st == LFIO_OK)
        st = lfio__h5_put_num_attr(path, "/", file, "format_version", H5T_STD_I32LE, H5T_NATIVE_INT32, 0,
                                   &version);
    if (st == LFIO_OK)
        st = lfio__h5_put_str_attr(path, "/", file, "creator", c->creator);
    if (st == LFIO_OK)
        st = lfio__h5_put_str_attr(path, "/", file, "scene", c->scene);
    if (st == LFIO_OK)
        st = lfio__h5_put_num_attr(path, "/", file, "patch_count", H5T_STD_U32LE, H5T_NATIVE_UINT32, 0, &count);
    return st;
}

/* write_contents() for format 2: the root attributes; every patch described, and its cells gathered unless
 * c->prepared has them or a serial write asks for them after every description (v2_stream: then stored as
 * they come); every dataset made; the cell datasets' filtered chunks stored, chunk by chunk; the rest
 * written. Whichever way the cells come, the HDF5 calls are the same, in the same order: so are the bytes. */
static lfio_status write_contents_v2(const char *path, hid_t file, const struct map_content *c)
{
    lfio_status st = write_root(path, file, c, 2);
    if (st != LFIO_OK)
        return st;
    struct v2_prepared own;
    v2_stream stream;
    v2_open o;
    memset(&own, 0, sizeof own);
    memset(&stream, 0, sizeof stream);
    for (int t = 0; t < V2_COUNT; t++)
        o.d[t] = -1;
    const int direct = (c->serial || c->prepared) && LFIO_LITTLE_ENDIAN;
    const struct v2_prepared *prep = c->prepared ? c->prepared : &own;
    if (c->prepared == NULL) {
        /* a serial write that lfio filters takes its cells filtered as they come */
        if (direct && c->serial && c->level > 0) {
            own.v.stream = &stream;
            if (!v2_stream_init(&stream, &own, c, path))
                st = lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", path);
        }
        if (st == LFIO_OK)
            st = v2_gather(c, path, &own.v);
        /* describing can fail on one rank of a collective write alone (out of memory): agree before HDF5 */
        st = lfio__h5_agree(path, st);
    }
    const v2_content *v = &prep->v;
    hid_t patches = -1;
    if (st == LFIO_OK)
        st = lfio__h5_create_group(path, "/patches", file, "patches", &patches);
    const uint64_t cells = st == LFIO_OK ? ((const uint32_t *)v->a[V2_CELL_OFFSET])[c->count] : 0;
    if (st == LFIO_OK)
        st = v2_open_all(c, path, patches, v, cells, &o);
    if (st == LFIO_OK && own.v.stream && stream.later) {
        stream.open = &o;
        st = v2_stream_rows(c, path, &own.v, &stream);
    }
    if (st == LFIO_OK && own.v.stream)
        st = v2_stream_finish(&stream, &own.v, cells);
    if (st == LFIO_OK)
        st = v2_store_held(path, &o, prep, direct);
    if (st == LFIO_OK)
        st = v2_write_rest(c, path, &o, v, direct);
    st = v2_close_all(path, &o, st);
    lfio__h5_close(patches);
    v2_stream_free(&stream, &own);
    v2_free(&own.v);
    return st;
}

/* Writes the root attributes and every patch of the map content into the open, empty file. */
static lfio_status write_contents(const char *path, hid_t file, const void *content)
{
    const struct map_content *c = content;
    if (c->format == 2)
        return write_contents_v2(path, file, c);
    lfio_status st = write_root(path, file, c, FORMAT_VERSION);
    if (st != LFIO_OK)
        return st;
    hid_t patches;
    if ((st = lfio__h5_create_group(path, "/patches", file, "patches", &patches)) != LFIO_OK)
        return st;
    uint64_t cells = 0;
    /* lfio filters the chunks itself in a serial write (not through MPI-IO, where HDF5 1.10 stores no chunk
     * as it is), when the arrays' bytes are the file's: little-endian */
    int direct = c->serial && LFIO_LITTLE_ENDIAN;
    for (size_t k = 0; st == LFIO_OK && k < c->count; k++) {
        lfio_radmap_patch p;
        memset(&p, 0, sizeof p);
        char why[256];
        st = c->describe(c->user, k, &p);
        /* describing can fail on one rank of a collective write alone (out of memory) */
        if ((st = lfio__h5_agree(path, st)) != LFIO_OK)
            break;
        if (!check_patch_scalars(&p, why, sizeof why)) {
            st = lfio__fail(LFIO_ERR_ARG, "%s: patch %zu (%s): %s", path, k, p.label ? p.label : "no label", why);
        } else if ((cells += p.ncells) > LFIO_RADMAP_MAX_CELLS) {
            st = lfio__fail(LFIO_ERR_ARG, "%s: more than %llu cells", path,
                            (unsigned long long)LFIO_RADMAP_MAX_CELLS);
        } else {
            st = write_patch(c, path, patches, k, &p, (int)(k % (size_t)c->ranks) == c->rank, direct);
        }
    }
    lfio__h5_close(patches);
    return st;
}

/* Checks the arguments every write shares: the count and the two texts. */
static lfio_status check_write_args(const char *path, const struct map_content *c)
{
    if (c->count > LFIO_RADMAP_MAX_PATCHES)
        return lfio__fail(LFIO_ERR_ARG, "%s: %zu patches, at most %u allowed", path, c->count,
                          LFIO_RADMAP_MAX_PATCHES);
    if (strlen(c->creator) > LFIO_RADMAP_TEXT_MAX || strlen(c->scene) > LFIO_RADMAP_TEXT_MAX)
        return lfio__fail(LFIO_ERR_ARG, "%s: creator or scene longer than %u bytes", path, LFIO_RADMAP_TEXT_MAX);
    return LFIO_OK;
}

void lfio_radmap_write_options_init(lfio_radmap_write_options *opt)
{
    if (opt == NULL)
        return;
    memset(opt, 0, sizeof *opt);
    opt->size = sizeof *opt;
    opt->threads = 0;
    opt->deflate_level = MAP_DEFLATE_LEVEL;
    opt->format_version = LFIO_RADMAP_FORMAT_VERSION;
}

/* Reads the caller's options (NULL: the defaults) into the writer's fields of c, the part of them its size
 * holds. @return LFIO_OK, or LFIO_ERR_ARG naming the bad field. */
static lfio_status take_options(const char *path, const lfio_radmap_write_options *opt, struct map_content *c)
{
    lfio_radmap_write_options o;
    lfio_radmap_write_options_init(&o);
    if (opt != NULL
        && !ilf_options_take(&o, sizeof o, opt, offsetof(lfio_radmap_write_options, threads) + sizeof opt->threads))
        return lfio__fail(LFIO_ERR_ARG, "%s: lfio_radmap_write_options.size %zu is not one this library knows", path,
                          opt->size);
    if (o.threads > 1024 || o.deflate_level < 0 || o.deflate_level > 9 || o.format_version < 1
        || o.format_version > LFIO_RADMAP_FORMAT_VERSION)
        return lfio__fail(LFIO_ERR_ARG, "%s: write options out of range (threads <= 1024, deflate_level 0 .. 9, "
                          "format_version 1 .. %d)", path, LFIO_RADMAP_FORMAT_VERSION);
    c->threads = o.threads;
    c->level = o.deflate_level;
    c->format = o.format_version;
    return LFIO_OK;
}

lfio_status lfio_radmap_write_with(const char *path, const char *creator, const char *scene, size_t count,
                                   lfio_radmap_describe_fn describe, lfio_radmap_rows_fn rows, void *user,
                                   const lfio_radmap_write_options *opt)
{
    if (path == NULL || path[0] == '\0')
        return lfio__fail(LFIO_ERR_ARG, "lfio_radmap_write: NULL or empty path");
    if (describe == NULL && count > 0)
        return lfio__fail(LFIO_ERR_ARG, "%s: NULL describe function", path);
    struct map_content c = {creator ? creator : "lfio " LFIO_VERSION_STRING, scene ? scene : "", count,
                            describe, rows, user, 0, 1, 1, 2, 0, MAP_DEFLATE_LEVEL, NULL, 0};
    lfio_status st = take_options(path, opt, &c);
    if (st == LFIO_OK)
        st = check_write_args(path, &c);
    return st == LFIO_OK ? lfio__h5_write_atomic(path, write_contents, &c) : st;
}

lfio_status lfio_radmap_write_rows(const char *path, const char *creator, const char *scene, size_t count,
                                   lfio_radmap_describe_fn describe, lfio_radmap_rows_fn rows, void *user)
{
    return lfio_radmap_write_with(path, creator, scene, count, describe, rows, user, NULL);
}

lfio_status lfio_radmap_write_each(const char *path, const char *creator, const char *scene, size_t count,
                                   lfio_radmap_describe_fn describe, void *user)
{
    return lfio_radmap_write_rows(path, creator, scene, count, describe, NULL, user);
}

#ifdef LFIO_MPI
/*
 * Format 2 over the ranks of an MPI job. Rank q holds the cells of its own patches, cells
 * [held[q], held[q + 1]) of the file (v2_gather(): patches dealt by count), and owns the chunks of each
 * deflated cell dataset in rows [own[q], own[q + 1]): the file's cells dealt evenly, each bound moved to
 * the nearest chunk's start, so that each rank compresses its share of every dataset, whatever zlib's
 * cost a byte of each (dealt as the patches are, the first of two ranks filtered 88% of the classroom's
 * chunks; its datasets have 4 chunks each, so this deal gives it 64%, as did one of the datasets' bytes
 * one after another, which left it waiting for the other rank). The ranks first trade rows
 * (MPI_Alltoallv) so that each holds its own chunks' (any rank may feed any other: a run shorter than a
 * chunk, a patch of many chunks), filter them with lfio's pipeline on their threads (chunks.h), and send
 * them to rank 0, which writes the file with the serial writer's calls, fed the chunks: the same bytes as
 * lfio_radmap_write_with()'s. Where every rank holds every cell (lfio_radmap_write_rows_mpi(), held_all),
 * there is no trade: each rank describes every patch without its cells, then asks the caller for its own
 * chunks' cells alone (mpi_take_rows()), so the cells are read from the caller once over all the ranks;
 * held is then [0, cells) for rank 0, which alone takes the cells of datasets not deflated (a file of a
 * few cells). Every step where one rank can fail alone ends in an agreement, so no rank waits for a
 * message that will not come.
 */

/* A collective write of format 2 under way on one rank. */
typedef struct mpi_write {
    const struct map_content *mc;
    const char *path;
    MPI_Comm comm;
    struct v2_prepared prep;  /* this rank's: its gathered content, then (rank 0) everything */
    uint64_t cells;           /* of the file */
    uint64_t *held, *own;     /* ranks + 1 cell indices each */
    lfio__h5_layout lay[V2_COUNT];
    unsigned char *rows[V2_COUNT]; /* deflated cell dataset t: the rows of this rank's chunks */
    lfio__chunk *mine;        /* this rank's chunks of every deflated cell dataset, dataset after dataset */
    size_t nmine[V2_COUNT], nmine_all;
    uint64_t *counts;         /* rank 0: V2_COUNT chunk counts a rank */
    unsigned char *spare;     /* rank 0: room for any one filtered chunk, where one arrives that finds no other */
} mpi_write;

/* @return whether t is a cell dataset lfio deflates in w's file. */
static int mpi_deflated(const mpi_write *w, int t)
{
    return v2_datasets[t].rows == ROWS_CELL && w->lay[t].deflate;
}

/* @return whether this rank filters the chunks of t, a table (every dataset but the cells') lfio deflates in
 * w's file: the last rank does, so that rank 0, which stores the file once every chunk has come, starts it
 * sooner (the classroom's tables, 1 MB, took rank 0 33 M instructions of 41 M storing the file, where its
 * cells' chunks took 110 M and the other rank's 84 M). */
static int mpi_table_mine(const mpi_write *w, int t)
{
    return v2_datasets[t].rows != ROWS_CELL && w->lay[t].deflate && w->mc->rank == w->mc->ranks - 1;
}

/* @return the rows of [a0, a1) within [b0, b1), as an int count (rows are at most LFIO_RADMAP_MAX_CELLS). */
static int overlap(uint64_t a0, uint64_t a1, uint64_t b0, uint64_t b1)
{
    const uint64_t lo = a0 > b0 ? a0 : b0, hi = a1 < b1 ? a1 : b1;
    return hi > lo ? (int)(hi - lo) : 0;
}

/* Sets w's cell ranges and layouts from the gathered tables. @return LFIO_OK, or LFIO_ERR_NOMEM. */
static lfio_status mpi_ranges(mpi_write *w)
{
    const struct map_content *mc = w->mc;
    const uint32_t *cell_end = (const uint32_t *)w->prep.v.a[V2_CELL_OFFSET];
    w->cells = cell_end[mc->count];
    for (int t = 0; t < V2_COUNT; t++)
        v2_layout((enum v2_ds)t, v2_datasets[t].rows == ROWS_CELL ? w->cells : w->prep.v.rows[t], mc->level,
                  &w->lay[t]);
    w->held = calloc(2 * ((size_t)mc->ranks + 1), sizeof *w->held);
    if (w->held == NULL)
        return lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", w->path);
    w->own = w->held + mc->ranks + 1;
    /* every cell dataset has the same rows and so the same chunks (v2_layout()) */
    const uint64_t chunk = w->lay[V2_CELL_IJ].chunk[0];
    for (int q = 0; q <= mc->ranks; q++) {
        /* where every rank holds every cell, rank 0 alone takes those of the cell datasets not deflated */
        if (mc->held_all)
            w->held[q] = q == 0 ? 0 : w->cells;
        else
            w->held[q] = cell_end[mc->count * (size_t)q / (size_t)mc->ranks];
        const uint64_t even = w->cells * (uint64_t)q / (uint64_t)mc->ranks, near = (even + chunk / 2) / chunk * chunk;
        /* the last bound is the file's end, whatever chunk it falls in */
        w->own[q] = near < w->cells && q < mc->ranks ? near : w->cells;
    }
    return LFIO_OK;
}

/* Allocates the rows of this rank's chunks of every deflated cell dataset. @return LFIO_OK, or LFIO_ERR_NOMEM. */
static lfio_status mpi_alloc_rows(mpi_write *w)
{
    const int me = w->mc->rank;
    for (int t = 0; t < V2_COUNT; t++)
        if (mpi_deflated(w, t)) {
            w->rows[t] = malloc((size_t)(w->own[me + 1] - w->own[me]) * v2_row_bytes((enum v2_ds)t) + 1);
            if (w->rows[t] == NULL)
                return lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", w->path);
        }
    return LFIO_OK;
}

/* Trades rows of deflated cell dataset t between the ranks so that each holds its own chunks' rows.
 * counts: 4 ints a rank of scratch. @return LFIO_OK, or LFIO_ERR_IO if MPI failed. */
static lfio_status mpi_trade_rows(mpi_write *w, int t, int *counts)
{
    const int me = w->mc->rank, ranks = w->mc->ranks;
    const size_t row = v2_row_bytes((enum v2_ds)t);
    int *sc = counts, *sd = sc + ranks, *rc = sd + ranks, *rd = rc + ranks;
    const uint64_t h0 = w->held[me], h1 = w->held[me + 1], o0 = w->own[me], o1 = w->own[me + 1];
    for (int q = 0; q < ranks; q++) {
        /* this rank's own rows are copied, not sent */
        sc[q] = q == me ? 0 : overlap(h0, h1, w->own[q], w->own[q + 1]);
        sd[q] = sc[q] ? (int)((w->own[q] > h0 ? w->own[q] : h0) - h0) : 0;
        rc[q] = q == me ? 0 : overlap(w->held[q], w->held[q + 1], o0, o1);
        rd[q] = rc[q] ? (int)((w->held[q] > o0 ? w->held[q] : o0) - o0) : 0;
    }
    const int self = overlap(h0, h1, o0, o1);
    if (self > 0) {
        const uint64_t from = h0 > o0 ? h0 : o0;
        memcpy(w->rows[t] + (size_t)(from - o0) * row, w->prep.v.a[t] + (size_t)(from - h0) * row, (size_t)self * row);
    }
    MPI_Datatype type;
    int ok = MPI_Type_contiguous((int)row, MPI_BYTE, &type) == MPI_SUCCESS;
    if (ok) {
        ok = MPI_Type_commit(&type) == MPI_SUCCESS
             && MPI_Alltoallv(w->prep.v.a[t], sc, sd, type, w->rows[t], rc, rd, type, w->comm) == MPI_SUCCESS;
        MPI_Type_free(&type);
    }
    return ok ? LFIO_OK : lfio__fail(LFIO_ERR_IO, "%s: cannot trade cells between ranks", w->path);
}

/* @return the first of the count patches whose cells end after cell (cell_end: the count + 1 offsets), or
 * count. */
static size_t patch_of_cell(const uint32_t *cell_end, size_t count, uint64_t cell)
{
    size_t lo = 0, hi = count;
    while (lo < hi) {
        const size_t mid = lo + (hi - lo) / 2;
        if (cell_end[mid + 1] > cell)
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo;
}

/* Copies the count rows of slice q's cell arrays to row at of dst[t], for every cell dataset t whose dst[t] is
 * set. */
static void copy_slice(const lfio_radmap_patch *q, uint64_t at, unsigned char *const *dst)
{
    const void *src[V2_COUNT] = {[V2_CELL_IJ] = q->cell_ij, [V2_CELL_AREA] = q->cell_area,
                                 [V2_CELL_CENTRE] = q->cell_centre, [V2_IRRADIANCE] = q->irradiance,
                                 [V2_RADIOSITY] = q->radiosity};
    for (int t = 0; t < V2_COUNT; t++)
        if (dst[t] != NULL && src[t] != NULL) {
            const size_t row = v2_row_bytes((enum v2_ds)t);
            memcpy(dst[t] + (size_t)at * row, src[t], (size_t)q->ncells * row);
        }
}

/* Where every rank holds every cell (mc->held_all): takes cells [from, to) of the file from the caller, each
 * patch described again and its cells asked a slice at a time (at most LFIO_RADMAP_ROWS_MAX), checked, into
 * dst[t] (its row 0 the file's cell from) for each cell dataset t whose dst[t] is set.
 * @return LFIO_OK, describe's or rows's status, or LFIO_ERR_ARG naming the patch and the problem. */
static lfio_status mpi_take_rows(const mpi_write *w, uint64_t from, uint64_t to, unsigned char *const *dst)
{
    const struct map_content *mc = w->mc;
    const uint32_t *cell_end = (const uint32_t *)w->prep.v.a[V2_CELL_OFFSET];
    for (size_t k = patch_of_cell(cell_end, mc->count, from); k < mc->count && cell_end[k] < to; k++) {
        if (cell_end[k + 1] == cell_end[k])
            continue;
        lfio_radmap_patch p;
        memset(&p, 0, sizeof p);
        lfio_status st = mc->describe(mc->user, k, &p);
        if (st != LFIO_OK)
            return st;
        if (p.ncells != cell_end[k + 1] - cell_end[k])
            return lfio__fail(LFIO_ERR_ARG, "%s: patch %zu (%s): described with %u cells, then %u", w->path, k,
                              p.label ? p.label : "no label", cell_end[k + 1] - cell_end[k], p.ncells);
        const uint64_t lo = from > cell_end[k] ? from : cell_end[k], hi = to < cell_end[k + 1] ? to : cell_end[k + 1];
        for (uint64_t c0 = lo; c0 < hi;) {
            const uint32_t count = hi - c0 < LFIO_RADMAP_ROWS_MAX ? (uint32_t)(hi - c0) : LFIO_RADMAP_ROWS_MAX;
            lfio_radmap_patch q;
            if ((st = patch_slice(mc, w->path, k, &p, (uint32_t)(c0 - cell_end[k]), count, &q)) != LFIO_OK)
                return st;
            copy_slice(&q, c0 - from, dst);
            c0 += count;
        }
    }
    return LFIO_OK;
}

/* Filters this rank's chunks of every deflated cell dataset, and of every deflated table on the last rank,
 * on the threads asked. @return LFIO_OK, or LFIO_ERR_NOMEM. */
static lfio_status mpi_filter(mpi_write *w)
{
    const int me = w->mc->rank;
    size_t n = 0;
    for (int t = 0; t < V2_COUNT; t++) {
        const uint64_t rows = mpi_deflated(w, t) ? w->own[me + 1] - w->own[me]
                              : mpi_table_mine(w, t) ? w->lay[t].dims[0] : 0;
        n += (size_t)((rows + w->lay[t].chunk[0] - 1) / w->lay[t].chunk[0]);
    }
    if ((w->mine = calloc(n + 1, sizeof *w->mine)) == NULL)
        return lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", w->path);
    for (int t = 0; t < V2_COUNT; t++) {
        const size_t row = v2_row_bytes((enum v2_ds)t);
        if (mpi_deflated(w, t))
            w->nmine[t] = v2_chunk_list(&w->lay[t], row, w->rows[t], w->own[me], w->own[me + 1],
                                        w->mine + w->nmine_all);
        else if (mpi_table_mine(w, t))
            w->nmine[t] = v2_chunk_list(&w->lay[t], row, w->prep.v.a[t], 0, w->lay[t].dims[0], w->mine + w->nmine_all);
        w->nmine_all += w->nmine[t];
    }
    if (lfio__chunks_filter(w->mine, w->nmine_all, ilf_thread_count(w->mc->threads), NULL, NULL) != 0)
        return lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", w->path);
    return LFIO_OK;
}

/* Rank 0: makes room for every rank's chunks (w->counts given; of the cells and of the tables) and for the
 * whole arrays of the cell datasets not deflated (filled here where every rank holds every cell), and
 * moves its own chunks in.
 * @return LFIO_OK, LFIO_ERR_NOMEM, or mpi_take_rows()'s failure. */
static lfio_status mpi_alloc_all(mpi_write *w)
{
    v2_content *v = &w->prep.v;
    size_t at = 0;
    const size_t widest = (size_t)w->lay[V2_CELL_CENTRE].chunk[0] * v2_row_bytes(V2_CELL_CENTRE);
    unsigned char *whole[V2_COUNT] = {NULL};
    int any_whole = 0;
    if ((w->spare = malloc(lfio__chunks_stored_most(widest))) == NULL)
        return lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", w->path);
    /* rank 0 writes the file: its cell datasets from its first row */
    v->cell_first = 0;
    for (int t = 0; t < V2_COUNT; t++) {
        const int is_cells = v2_datasets[t].rows == ROWS_CELL;
        if (!is_cells && !w->lay[t].deflate)
            continue;
        if (is_cells && !mpi_deflated(w, t)) {
            if (!v2_reserve(v, (enum v2_ds)t, w->cells - v->rows[t]))
                return lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", w->path);
            v->rows[t] = w->cells;
            whole[t] = v->a[t];
            any_whole = 1;
            continue;
        }
        size_t n = 0;
        for (int q = 0; q < w->mc->ranks; q++)
            n += (size_t)w->counts[(size_t)q * V2_COUNT + t];
        if ((w->prep.c[t] = calloc(n + 1, sizeof *w->prep.c[t])) == NULL)
            return lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", w->path);
        w->prep.n[t] = n;
        /* rank 0's chunks come first: they move, the rest arrive in rank order (mpi_receive()) */
        memcpy(w->prep.c[t], w->mine + at, w->nmine[t] * sizeof *w->mine);
        memset(w->mine + at, 0, w->nmine[t] * sizeof *w->mine);
        at += w->nmine[t];
    }
    /* where every rank holds every cell, rank 0 takes the cells not deflated (a file of a few cells) itself */
    return w->mc->held_all && any_whole ? mpi_take_rows(w, 0, w->cells, whole) : LFIO_OK;
}

/* Rank 0: receives every other rank's chunks (sizes first; the tables' from the last) and cells not
 * deflated, into room made for them. @return LFIO_OK; LFIO_ERR_NOMEM; LFIO_ERR_IO if MPI failed. */
static lfio_status mpi_receive(mpi_write *w)
{
    size_t at[V2_COUNT];
    for (int t = 0; t < V2_COUNT; t++)
        at[t] = w->nmine[t];
    lfio_status st = LFIO_OK;
    for (int q = 1; q < w->mc->ranks; q++)
        for (int t = 0; t < V2_COUNT; t++) {
            const int is_cells = v2_datasets[t].rows == ROWS_CELL;
            if (!is_cells && !w->lay[t].deflate)
                continue;
            const size_t row = v2_row_bytes((enum v2_ds)t);
            if (is_cells && !mpi_deflated(w, t)) {
                const uint64_t rows = w->held[q + 1] - w->held[q];
                /* no message for no rows (mpi_send()): the array may be NULL */
                if (rows > 0
                    && MPI_Recv(w->prep.v.a[t] + (size_t)w->held[q] * row, (int)(rows * row), MPI_BYTE, q, t,
                                w->comm, MPI_STATUS_IGNORE) != MPI_SUCCESS)
                    st = LFIO_ERR_IO;
                continue;
            }
            for (uint64_t k = 0; k < w->counts[(size_t)q * V2_COUNT + t]; k++, at[t]++) {
                lfio__chunk *c = &w->prep.c[t][at[t]];
                MPI_Status s;
                int bytes = 0;
                /* a chunk's size is known only once it is probed: the sender filtered it */
                if (MPI_Probe(q, t, w->comm, &s) != MPI_SUCCESS || MPI_Get_count(&s, MPI_BYTE, &bytes) != MPI_SUCCESS)
                    st = LFIO_ERR_IO;
                c->out = malloc((size_t)bytes + 1);
                c->out_bytes = (size_t)bytes;
                if (c->out == NULL && st == LFIO_OK)
                    st = LFIO_ERR_NOMEM;
                /* received even without room of its own, or the sender would wait */
                if (MPI_Recv(c->out ? c->out : w->spare, bytes, MPI_BYTE, q, t, w->comm, &s) != MPI_SUCCESS
                    && st == LFIO_OK)
                    st = LFIO_ERR_IO;
            }
        }
    if (st == LFIO_ERR_NOMEM)
        return lfio__fail(st, "%s: out of memory", w->path);
    return st == LFIO_OK ? LFIO_OK : lfio__fail(st, "%s: cannot receive the cells of the other ranks", w->path);
}

/* A rank but 0: sends its chunks (the last rank's with the tables') and its cells not deflated to rank 0.
 * @return LFIO_OK, or LFIO_ERR_IO. */
static lfio_status mpi_send(mpi_write *w)
{
    const int me = w->mc->rank;
    int ok = 1;
    size_t at = 0;
    for (int t = 0; t < V2_COUNT; t++) {
        const int is_cells = v2_datasets[t].rows == ROWS_CELL;
        if (!is_cells && !w->lay[t].deflate)
            continue;
        if (is_cells && !mpi_deflated(w, t)) {
            const uint64_t rows = w->held[me + 1] - w->held[me];
            const int bytes = (int)(rows * v2_row_bytes((enum v2_ds)t));
            ok &= rows == 0 || MPI_Send(w->prep.v.a[t], bytes, MPI_BYTE, 0, t, w->comm) == MPI_SUCCESS;
            continue;
        }
        for (size_t k = 0; k < w->nmine[t]; k++, at++)
            ok &= MPI_Send(w->mine[at].out, (int)w->mine[at].out_bytes, MPI_BYTE, 0, t, w->comm) == MPI_SUCCESS;
    }
    return ok ? LFIO_OK : lfio__fail(LFIO_ERR_IO, "%s: cannot send cells to rank 0", w->path);
}

/* Every rank's part up to rank 0 holding the whole content, filtered, each step agreed.
 * @return on every rank: LFIO_OK, this rank's error, or one saying another rank failed. */
static lfio_status mpi_prepare(mpi_write *w)
{
    const struct map_content *mc = w->mc;
    int *scratch = NULL;
    lfio_status st = lfio__h5_agree_over(w->path, v2_gather(mc, w->path, &w->prep.v), w->comm);
    if (st == LFIO_OK && (st = mpi_ranges(w)) == LFIO_OK && (st = mpi_alloc_rows(w)) == LFIO_OK
        && (scratch = malloc(4 * (size_t)mc->ranks * sizeof *scratch)) == NULL)
        st = lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", w->path);
    if (mc->rank == 0 && st == LFIO_OK && (w->counts = calloc((size_t)mc->ranks * V2_COUNT, sizeof *w->counts)) == NULL)
        st = lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", w->path);
    st = lfio__h5_agree_over(w->path, st, w->comm);
    /* where every rank holds every cell, each takes its own chunks' from the caller: no trade */
    if (st == LFIO_OK && mc->held_all)
        st = mpi_take_rows(w, w->own[mc->rank], w->own[mc->rank + 1], w->rows);
    for (int t = 0; st == LFIO_OK && !mc->held_all && t < V2_COUNT; t++)
        if (mpi_deflated(w, t))
            st = mpi_trade_rows(w, t, scratch);
    free(scratch);
    if (st == LFIO_OK)
        st = mpi_filter(w);
    st = lfio__h5_agree_over(w->path, st, w->comm);
    uint64_t n[V2_COUNT];
    for (int t = 0; t < V2_COUNT; t++)
        n[t] = w->nmine[t];
    if (st == LFIO_OK
        && MPI_Gather(n, V2_COUNT, MPI_UINT64_T, w->counts, V2_COUNT, MPI_UINT64_T, 0, w->comm) != MPI_SUCCESS)
        st = lfio__fail(LFIO_ERR_IO, "%s: cannot gather the chunk counts", w->path);
    if (st == LFIO_OK && mc->rank == 0)
        st = mpi_alloc_all(w);
    st = lfio__h5_agree_over(w->path, st, w->comm);
    if (st == LFIO_OK)
        st = mc->rank == 0 ? mpi_receive(w) : mpi_send(w);
    return lfio__h5_agree_over(w->path, st, w->comm);
}

/* Frees what w holds. */
static void mpi_write_free(mpi_write *w)
{
    for (int t = 0; t < V2_COUNT; t++) {
        if (w->prep.c[t])
            lfio__chunks_free(w->prep.c[t], w->prep.n[t]);
        free(w->prep.c[t]);
        free(w->rows[t]);
    }
    if (w->mine)
        lfio__chunks_free(w->mine, w->nmine_all);
    free(w->mine);
    free(w->held);
    free(w->counts);
    free(w->spare);
    v2_free(&w->prep.v);
}

/* Writes format 2 over comm (lfio_radmap_write_with_mpi()): the ranks prepare the content, rank 0 writes
 * the file alone and tells the others whether it is in place. */
static lfio_status mpi_write_v2(const char *path, struct map_content *c, MPI_Comm comm)
{
    mpi_write w;
    memset(&w, 0, sizeof w);
    w.mc = c, w.path = path, w.comm = comm;
    lfio_status st = mpi_prepare(&w);
    if (st == LFIO_OK && c->rank == 0) {
        c->prepared = &w.prep;
        st = lfio__h5_write_atomic(path, write_contents, c);
    }
    mpi_write_free(&w);
    int placed = st == LFIO_OK;
    if (MPI_Bcast(&placed, 1, MPI_INT, 0, comm) != MPI_SUCCESS)
        placed = 0;
    if (!placed && st == LFIO_OK)
        st = lfio__fail(LFIO_ERR_IO, "%s: rank 0 could not write it", path);
    return st;
}

/* lfio_radmap_write_with_mpi() (rows NULL) and lfio_radmap_write_rows_mpi() (held_all set). */
static lfio_status write_mpi(const char *path, const char *creator, const char *scene, size_t count,
                             lfio_radmap_describe_fn describe, lfio_radmap_rows_fn rows, void *user,
                             const lfio_radmap_write_options *opt, MPI_Comm comm, int held_all)
{
    int rank = 0, ranks = 1;
    if (MPI_Comm_rank(comm, &rank) != MPI_SUCCESS || MPI_Comm_size(comm, &ranks) != MPI_SUCCESS)
        return lfio__fail(LFIO_ERR_ARG, "%s: not a valid MPI communicator", path ? path : "lfio_radmap_write");
    /* Arguments are the same on every rank, so every rank refuses the same ones before any collective call. */
    if (path == NULL || path[0] == '\0')
        return lfio__fail(LFIO_ERR_ARG, "lfio_radmap_write: NULL or empty path");
    if (describe == NULL && count > 0)
        return lfio__fail(LFIO_ERR_ARG, "%s: NULL describe function", path);
    struct map_content c = {creator ? creator : "lfio " LFIO_VERSION_STRING, scene ? scene : "", count,
                            describe, rows, user, rank, ranks, 0, 2, 1, MAP_DEFLATE_LEVEL, NULL, held_all};
    lfio_status st = take_options(path, opt, &c);
    if (st == LFIO_OK)
        st = check_write_args(path, &c);
    if (st != LFIO_OK)
        return st;
    /* lfio's own filter makes HDF5's bytes only where memory is little-endian; elsewhere, and for format 1,
     * every rank writes through MPI-IO and HDF5's filters, its own patches whole */
    if (c.format == 2 && LFIO_LITTLE_ENDIAN)
        return mpi_write_v2(path, &c, comm);
    c.held_all = 0;
    return lfio__h5_write_collective(path, write_contents, &c, comm);
}

lfio_status lfio_radmap_write_with_mpi(const char *path, const char *creator, const char *scene, size_t count,
                                       lfio_radmap_describe_fn describe, void *user,
                                       const lfio_radmap_write_options *opt, MPI_Comm comm)
{
    return write_mpi(path, creator, scene, count, describe, NULL, user, opt, comm, 0);
}

lfio_status lfio_radmap_write_rows_mpi(const char *path, const char *creator, const char *scene, size_t count,
                                       lfio_radmap_describe_fn describe, lfio_radmap_rows_fn rows, void *user,
                                       const lfio_radmap_write_options *opt, MPI_Comm comm)
{
    return write_mpi(path, creator, scene, count, describe, rows, user, opt, comm, 1);
}

lfio_status lfio_radmap_write_each_mpi(const char *path, const char *creator, const char *scene, size_t count,
                                       lfio_radmap_describe_fn describe, void *user, MPI_Comm comm)
{
    return lfio_radmap_write_with_mpi(path, creator, scene, count, describe, user, NULL, comm);
}
#endif

/* lfio_radmap_write()'s describe: patch k of the caller's array. */
static lfio_status describe_array(void *user, size_t k, lfio_radmap_patch *out)
{
    *out = ((const lfio_radmap_patch *)user)[k];
    return LFIO_OK;
}

lfio_status lfio_radmap_write(const char *path, const char *creator, const char *scene,
                              const lfio_radmap_patch *patches, size_t count)
{
    if (path != NULL && path[0] != '\0' && count > 0 && patches == NULL)
        return lfio__fail(LFIO_ERR_ARG, "%s: NULL patches", path);
    return lfio_radmap_write_each(path, creator, scene, count, describe_array, (void *)patches);
}

/* ----------------------------------------------------------------- reading */

/* One patch as read: its arrays (owned) and the description pointing into them. */
struct map_patch {
    char *label;
    void *data[MAP_DS_COUNT]; /* NULL for an empty dataset */
    lfio_radmap_patch pub;
};

struct lfio_radmap {
    char *creator;
    char *scene;
    size_t count;             /* patches read so far; all of them once returned */
    size_t capacity;
    struct map_patch *patches;
    uint64_t cells;           /* over all patches read, <= LFIO_RADMAP_MAX_CELLS */
    int format;               /* the file's format_version */
    int headers;              /* read by lfio_radmap_read_headers(): no cell array was read (all NULL) */
    unsigned char *whole[V2_COUNT]; /* format 2: each dataset's array, which the patches point into */
};

/* Frees one patch's arrays and label. */
static void patch_free(struct map_patch *mp)
{
    for (int t = 0; t < MAP_DS_COUNT; t++)
        free(mp->data[t]);
    free(mp->label);
}

/* Frees map and everything it owns; NULL is a no-op. */
static void map_free(lfio_radmap *map)
{
    if (map == NULL)
        return;
    for (size_t k = 0; k < map->count; k++)
        patch_free(&map->patches[k]);
    free(map->patches);
    for (int t = 0; t < V2_COUNT; t++)
        free(map->whole[t]);
    free(map->creator);
    free(map->scene);
    free(map);
}

/* Reads and checks the root attributes into map. @return LFIO_OK and *count, the number of patches. */
static lfio_status read_root(const char *path, hid_t file, lfio_radmap *map, size_t *count)
{
    int64_t version = 0, n = 0;
    lfio_status st = lfio__h5_expect_str_attr(path, "/", file, "format", FORMAT_NAME);
    if (st == LFIO_OK)
        st = lfio__h5_get_int_attr(path, "/", file, "format_version", INT32_MIN, INT32_MAX, &version);
    if (st == LFIO_OK && version > LFIO_RADMAP_FORMAT_VERSION)
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: /: format_version %lld is newer than this library reads (version %d)",
                        path, (long long)version, LFIO_RADMAP_FORMAT_VERSION);
    map->format = (int)version;
    if (st == LFIO_OK && version < 1)
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: /: invalid format_version %lld", path, (long long)version);
    if (st == LFIO_OK)
        st = lfio__h5_get_str_attr(path, "/", file, "creator", LFIO_RADMAP_TEXT_MAX, &map->creator);
    if (st == LFIO_OK)
        st = lfio__h5_get_str_attr(path, "/", file, "scene", LFIO_RADMAP_TEXT_MAX, &map->scene);
    if (st == LFIO_OK)
        st = lfio__h5_get_int_attr(path, "/", file, "patch_count", 0, LFIO_RADMAP_MAX_PATCHES, &n);
    *count = (size_t)n;
    return st;
}

/* Reads count finite doubles of float attribute name of g into float out. */
static lfio_status get_f32x3_attr(const char *path, const char *obj, hid_t g, const char *name, float out[3])
{
    double v[3];
    lfio_status st = lfio__h5_get_f64_attr(path, obj, g, name, 3, v);
    for (int c = 0; st == LFIO_OK && c < 3; c++)
        out[c] = (float)v[c];
    return st;
}

/* Reads the attributes of patch group g (obj) into mp (label and scalars). */
static lfio_status read_patch_attrs(const char *path, const char *obj, hid_t g, struct map_patch *mp)
{
    lfio_radmap_patch *p = &mp->pub;
    int64_t polygon = 0, nu = 0, nv = 0;
    lfio_status st = lfio__h5_get_str_attr(path, obj, g, "label", LFIO_RADMAP_TEXT_MAX, &mp->label);
    if (st == LFIO_OK)
        st = lfio__h5_get_int_attr(path, obj, g, "polygon", 0, UINT32_MAX, &polygon);
    if (st == LFIO_OK)
        st = lfio__h5_get_int_attr(path, obj, g, "nu", 0, UINT32_MAX, &nu);
    if (st == LFIO_OK)
        st = lfio__h5_get_int_attr(path, obj, g, "nv", 0, UINT32_MAX, &nv);
    if (st == LFIO_OK)
        st = lfio__h5_get_f64_attr(path, obj, g, "origin", 3, p->origin);
    if (st == LFIO_OK)
        st = lfio__h5_get_f64_attr(path, obj, g, "e1", 3, p->e1);
    if (st == LFIO_OK)
        st = lfio__h5_get_f64_attr(path, obj, g, "e2", 3, p->e2);
    if (st == LFIO_OK)
        st = lfio__h5_get_f64_attr(path, obj, g, "normal", 3, p->normal);
    if (st == LFIO_OK)
        st = lfio__h5_get_f64_attr(path, obj, g, "cell_size", 1, &p->cell_size);
    if (st == LFIO_OK)
        st = lfio__h5_get_f64_attr(path, obj, g, "u0", 1, &p->u0);
    if (st == LFIO_OK)
        st = lfio__h5_get_f64_attr(path, obj, g, "v0", 1, &p->v0);
    if (st == LFIO_OK)
        st = lfio__h5_expect_str_attr(path, obj, g, "length_units", "m");
    if (st == LFIO_OK)
        st = get_f32x3_attr(path, obj, g, "albedo", p->albedo);
    if (st == LFIO_OK)
        st = get_f32x3_attr(path, obj, g, "emission", p->emission);
    p->label = mp->label;
    p->polygon = (uint32_t)polygon;
    p->nu = (uint32_t)nu;
    p->nv = (uint32_t)nv;
    return st;
}

/* @return the length of the first axis of dataset name of g (obj, for lfio__h5_open_dataset()'s messages);
 * 0 if it is missing, not an array, not a hard link or not stored in the file, which the full check
 * reports. */
static hsize_t first_axis_length(const char *path, const char *obj, hid_t g, const char *name)
{
    hsize_t dims[H5S_MAX_RANK] = {0};
    hid_t d = -1;
    if (lfio__h5_open_dataset(path, obj, g, name, -1, &d) != LFIO_OK)
        return 0;
    hid_t space = H5Dget_space(d);
    int rank = space < 0 ? -1 : H5Sget_simple_extent_ndims(space);
    if (rank < 1 || rank > H5S_MAX_RANK || H5Sget_simple_extent_dims(space, dims, NULL) < 0)
        dims[0] = 0;
    lfio__h5_close(space);
    lfio__h5_close(d);
    return dims[0];
}

/* Finds the patch's vertex and cell counts from vertices and cell_ij and checks them against the limits. */
static lfio_status read_patch_counts(const char *path, const char *obj, hid_t g, const lfio_radmap *map,
                                     lfio_radmap_patch *p)
{
    char vobj[128], cobj[128];
    snprintf(vobj, sizeof vobj, "%.63s/vertices", obj);
    snprintf(cobj, sizeof cobj, "%.63s/cell_ij", obj);
    const hsize_t nverts = first_axis_length(path, vobj, g, "vertices"), ncells = first_axis_length(path, cobj, g, "cell_ij");
    if (nverts > LFIO_RADMAP_MAX_VERTS)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s/vertices: %llu vertices, at most %u allowed", path, obj,
                          (unsigned long long)nverts, LFIO_RADMAP_MAX_VERTS);
    if (ncells > (hsize_t)p->nu * p->nv)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s/cell_ij: %llu cells in a grid of %u x %u", path, obj,
                          (unsigned long long)ncells, p->nu, p->nv);
    if (ncells > LFIO_RADMAP_MAX_CELLS - map->cells)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s/cell_ij: %llu more cells exceed the limit of %llu per file", path,
                          obj, (unsigned long long)ncells, (unsigned long long)LFIO_RADMAP_MAX_CELLS);
    p->nverts = (uint32_t)nverts;
    p->ncells = (uint32_t)ncells;
    return LFIO_OK;
}

/* Checks every dataset of patch group g against its layout, then reads each into a new array of mp; with
 * headers, only the vertices (the cell datasets checked, not read). */
static lfio_status read_patch_data(const char *path, const char *obj, hid_t g, struct map_patch *mp, int headers)
{
    lfio_radmap_patch *p = &mp->pub;
    lfio__h5_layout lay[MAP_DS_COUNT];
    hid_t dset[MAP_DS_COUNT];
    lfio_status st = LFIO_OK;
    for (int t = 0; t < MAP_DS_COUNT; t++) {
        dset[t] = -1;
        patch_layout((enum map_ds)t, p->nverts, p->ncells, &lay[t]);
        const char *source = map_datasets[t].per_vertex ? "the length of vertices" : "the length of cell_ij";
        if (st == LFIO_OK)
            st = lfio__h5_check_dataset(path, obj, g, &lay[t], source, -1, &dset[t]);
    }
    /* the vertices come first in map_datasets[], the cell datasets after them */
    for (int t = 0; st == LFIO_OK && t < (headers ? MAP_CELL_IJ : MAP_DS_COUNT); t++) {
        const size_t bytes = value_count((enum map_ds)t, p) * map_datasets[t].size;
        char dobj[128];
        snprintf(dobj, sizeof dobj, "%.63s/%s", obj, map_datasets[t].name);
        if (bytes > 0 && (mp->data[t] = malloc(bytes)) == NULL)
            st = lfio__fail(LFIO_ERR_NOMEM, "%s: %s: out of memory", path, dobj);
        const hsize_t zero[2] = {0, 0};
        if (st == LFIO_OK)
            st = lfio__h5_xfer(path, dobj, dset[t], 0, memory_type((enum map_ds)t), lay[t].rank, zero, lay[t].dims,
                               mp->data[t]);
    }
    for (int t = 0; t < MAP_DS_COUNT; t++)
        lfio__h5_close(dset[t]);
    p->vertices = mp->data[MAP_VERTICES];
    p->cell_ij = mp->data[MAP_CELL_IJ];
    p->cell_area = mp->data[MAP_CELL_AREA];
    p->cell_centre = mp->data[MAP_CELL_CENTRE];
    p->irradiance = mp->data[MAP_IRRADIANCE];
    p->radiosity = mp->data[MAP_RADIOSITY];
    return st;
}

/* Reads patch group /patches/k into a new entry of map, checking it completely. */
static lfio_status read_patch(const char *path, hid_t patches, size_t k, lfio_radmap *map)
{
    char obj[64], name[24];
    snprintf(name, sizeof name, "%zu", k);
    snprintf(obj, sizeof obj, "/patches/%zu", k);
    hid_t g;
    lfio_status st = lfio__h5_open_group(path, obj, patches, name, "patch group", &g);
    if (st != LFIO_OK)
        return st;
    if (map->count == map->capacity) {
        size_t grown = map->capacity ? 2 * map->capacity : 16;
        struct map_patch *more = realloc(map->patches, grown * sizeof *more);
        if (more == NULL) {
            lfio__h5_close(g);
            return lfio__fail(LFIO_ERR_NOMEM, "%s: %s: out of memory", path, obj);
        }
        map->patches = more;
        map->capacity = grown;
    }
    struct map_patch *mp = &map->patches[map->count++]; /* counted now, so map_free() releases it */
    memset(mp, 0, sizeof *mp);
    st = read_patch_attrs(path, obj, g, mp);
    if (st == LFIO_OK)
        st = read_patch_counts(path, obj, g, map, &mp->pub);
    if (st == LFIO_OK)
        st = read_patch_data(path, obj, g, mp, map->headers);
    lfio__h5_close(g);
    char why[256];
    if (st == LFIO_OK && !check_patch_read(&mp->pub, map->headers, why, sizeof why))
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: %s", path, obj, why);
    if (st == LFIO_OK)
        map->cells += mp->pub.ncells;
    return st;
}

/* ------------------------------------------------------- format 2: reading */

/* Opens format-2 dataset t of group g, checks it against its layout for rows rows (source: where rows came
 * from, for messages), and reads it whole into a new array *out (NULL when empty); out NULL: checks only. */
static lfio_status v2_read_dataset(const char *path, hid_t g, enum v2_ds t, uint64_t rows, const char *source,
                                   unsigned char **out)
{
    unsigned char *none = NULL;
    const int read = out != NULL;
    if (!read)
        out = &none;
    lfio__h5_layout l;
    v2_layout(t, rows, 0, &l);
    char dobj[64];
    snprintf(dobj, sizeof dobj, "/patches/%s", l.name);
    hid_t d = -1;
    *out = NULL;
    lfio_status st = lfio__h5_check_dataset(path, "/patches", g, &l, source, -1, &d);
    const size_t bytes = read ? (size_t)rows * v2_row_bytes(t) : 0;
    if (st == LFIO_OK && bytes > 0 && (*out = malloc(bytes)) == NULL)
        st = lfio__fail(LFIO_ERR_NOMEM, "%s: %s: out of memory", path, dobj);
    const hsize_t zero[2] = {0, 0};
    if (st == LFIO_OK && read)
        st = lfio__h5_xfer(path, dobj, d, 0, v2_memory_type(t), l.rank, zero, l.dims, *out);
    lfio__h5_close(d);
    return st;
}

/* Checks the offsets table t (count + 1 rows) of map: starting at 0, never decreasing, ending at most at
 * limit. @return LFIO_OK and *total, the last offset; LFIO_ERR_FORMAT. */
static lfio_status v2_check_offsets(const char *path, const lfio_radmap *map, enum v2_ds t, size_t count,
                                    uint64_t limit, uint64_t *total)
{
    const uint32_t *off = (const uint32_t *)map->whole[t];
    for (size_t k = 0; k < count; k++)
        if (off[k + 1] < off[k])
            return lfio__fail(LFIO_ERR_FORMAT, "%s: /patches/%s: offset %zu decreases", path, v2_datasets[t].name, k + 1);
    if (off[0] != 0 || off[count] > limit)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: /patches/%s: must start at 0 and end at most at %llu", path,
                          v2_datasets[t].name, (unsigned long long)limit);
    *total = off[count];
    return LFIO_OK;
}

/* Reads the NUL-terminated labels of count patches into map->whole[V2_LABEL]. */
static lfio_status v2_read_labels(const char *path, hid_t g, lfio_radmap *map, size_t count)
{
    const hsize_t bytes = first_axis_length(path, "/patches/label", g, "label");
    if (bytes > (hsize_t)count * (LFIO_RADMAP_TEXT_MAX + 1))
        return lfio__fail(LFIO_ERR_FORMAT, "%s: /patches/label: %llu bytes for %zu labels of at most %u bytes", path,
                          (unsigned long long)bytes, count, LFIO_RADMAP_TEXT_MAX);
    lfio_status st = v2_read_dataset(path, g, V2_LABEL, bytes, "its own length", &map->whole[V2_LABEL]);
    size_t nul = 0;
    for (hsize_t b = 0; st == LFIO_OK && b < bytes; b++)
        nul += map->whole[V2_LABEL][b] == '\0';
    if (st == LFIO_OK && (nul != count || (bytes > 0 && map->whole[V2_LABEL][bytes - 1] != '\0')))
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: /patches/label: expected %zu NUL-terminated labels", path, count);
    return st;
}

/* Fills the description of row i of format-2 tables w (label, scalars, counts from the offsets), its arrays
 * NULL. */
static void v2_fill_scalars(unsigned char *const *w, size_t i, const char *label, lfio_radmap_patch *p)
{
    const uint32_t *voff = (const uint32_t *)w[V2_VERTEX_OFFSET], *coff = (const uint32_t *)w[V2_CELL_OFFSET];
    memset(p, 0, sizeof *p);
    p->label = label;
    p->polygon = ((const uint32_t *)w[V2_POLYGON])[i];
    p->nu = ((const uint32_t *)w[V2_NU])[i];
    p->nv = ((const uint32_t *)w[V2_NV])[i];
    memcpy(p->origin, w[V2_ORIGIN] + 24 * i, 24);
    memcpy(p->e1, w[V2_E1] + 24 * i, 24);
    memcpy(p->e2, w[V2_E2] + 24 * i, 24);
    memcpy(p->normal, w[V2_NORMAL] + 24 * i, 24);
    memcpy(&p->cell_size, w[V2_CELL_SIZE] + 8 * i, 8);
    memcpy(&p->u0, w[V2_U0] + 8 * i, 8);
    memcpy(&p->v0, w[V2_V0] + 8 * i, 8);
    memcpy(p->albedo, w[V2_ALBEDO] + 12 * i, 12);
    memcpy(p->emission, w[V2_EMISSION] + 12 * i, 12);
    p->nverts = voff[i + 1] - voff[i];
    p->ncells = coff[i + 1] - coff[i];
}

/* Points patch k of map (format 2, its arrays read) into the whole arrays and checks it. */
static lfio_status v2_make_patch(const char *path, lfio_radmap *map, size_t k, const char *label)
{
    struct map_patch *mp = &map->patches[k];
    lfio_radmap_patch *p = &mp->pub;
    unsigned char *const *w = map->whole;
    const uint32_t *voff = (const uint32_t *)w[V2_VERTEX_OFFSET], *coff = (const uint32_t *)w[V2_CELL_OFFSET];
    memset(mp, 0, sizeof *mp);
    v2_fill_scalars(w, k, label, p);
    const size_t v0 = voff[k], c0 = coff[k];
    p->vertices = w[V2_VERTICES] ? (const double *)w[V2_VERTICES] + 3 * v0 : NULL;
    p->cell_ij = w[V2_CELL_IJ] ? (const uint32_t *)w[V2_CELL_IJ] + 2 * c0 : NULL;
    p->cell_area = w[V2_CELL_AREA] ? (const double *)w[V2_CELL_AREA] + c0 : NULL;
    p->cell_centre = w[V2_CELL_CENTRE] ? (const double *)w[V2_CELL_CENTRE] + 3 * c0 : NULL;
    p->irradiance = w[V2_IRRADIANCE] ? (const float *)w[V2_IRRADIANCE] + 3 * c0 : NULL;
    p->radiosity = w[V2_RADIOSITY] ? (const float *)w[V2_RADIOSITY] + 3 * c0 : NULL;
    char why[256];
    if (!check_patch_read(p, map->headers, why, sizeof why))
        return lfio__fail(LFIO_ERR_FORMAT, "%s: /patches: patch %zu: %s", path, k, why);
    map->cells += p->ncells;
    return LFIO_OK;
}

/* Reads the datasets of format-2 group g (count patches, from the root) into map, checking the tables
 * before sizing the vertex and cell arrays from them. */
static lfio_status read_patches_v2(const char *path, hid_t g, lfio_radmap *map, size_t count)
{
    lfio_status st = v2_read_labels(path, g, map, count);
    for (int t = 0; st == LFIO_OK && t < V2_COUNT; t++) {
        const enum v2_rows r = v2_datasets[t].rows;
        if (r == ROWS_PATCH || r == ROWS_OFFSET)
            st = v2_read_dataset(path, g, (enum v2_ds)t, count + (r == ROWS_OFFSET), "patch_count", &map->whole[t]);
    }
    uint64_t vertices = 0, cells = 0;
    if (st == LFIO_OK)
        st = v2_check_offsets(path, map, V2_VERTEX_OFFSET, count, LFIO_RADMAP_MAX_FILE_VERTS, &vertices);
    if (st == LFIO_OK)
        st = v2_check_offsets(path, map, V2_CELL_OFFSET, count, LFIO_RADMAP_MAX_CELLS, &cells);
    for (int t = 0; st == LFIO_OK && t < V2_COUNT; t++) {
        const enum v2_rows r = v2_datasets[t].rows;
        if (r == ROWS_VERTEX || r == ROWS_CELL)
            st = v2_read_dataset(path, g, (enum v2_ds)t, r == ROWS_VERTEX ? vertices : cells,
                                 r == ROWS_VERTEX ? "vertex_offset" : "cell_offset",
                                 r == ROWS_CELL && map->headers ? NULL : &map->whole[t]);
    }
    if (st == LFIO_OK && count > 0 && (map->patches = calloc(count, sizeof *map->patches)) == NULL)
        st = lfio__fail(LFIO_ERR_NOMEM, "%s: /patches: out of memory", path);
    const char *label = (const char *)map->whole[V2_LABEL];
    for (size_t k = 0; st == LFIO_OK && k < count; k++) {
        map->count = map->capacity = k + 1;
        st = v2_make_patch(path, map, k, label);
        label += strlen(label) + 1;
    }
    return st;
}

/* lfio_radmap_read() (lfio_radmap_read_headers() with headers set) without silencing HDF5. */
static lfio_status radmap_read_impl(const char *path, int headers, lfio_radmap **out)
{
    hid_t file = -1, patches = -1;
    size_t count = 0;
    lfio_radmap *map = calloc(1, sizeof *map);
    if (map != NULL)
        map->headers = headers;
    lfio_status st = map ? lfio__h5_open_read(path, &file) : lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", path);
    if (st == LFIO_OK)
        st = read_root(path, file, map, &count);
    if (st == LFIO_OK)
        st = lfio__h5_open_group(path, "/patches", file, "patches", "group", &patches);
    if (st == LFIO_OK && map->format == 2)
        st = read_patches_v2(path, patches, map, count);
    for (size_t k = 0; st == LFIO_OK && map->format == 1 && k < count; k++)
        st = read_patch(path, patches, k, map);
    lfio__h5_close(patches);
    lfio__h5_close(file);
    if (st != LFIO_OK)
        map_free(map);
    else
        *out = map;
    return st;
}

/* Reads path whole or its headers (see radmap_read_impl()), silently; call names the entry point. */
static lfio_status radmap_read(const char *call, const char *path, int headers, lfio_radmap **out)
{
    if (out == NULL)
        return lfio__fail(LFIO_ERR_ARG, "%s: NULL argument", call);
    *out = NULL;
    if (path == NULL || path[0] == '\0')
        return lfio__fail(LFIO_ERR_ARG, "%s: NULL or empty path", call);
    lfio__h5_quiet q;
    lfio__h5_quiet_begin(&q);
    lfio_status st = radmap_read_impl(path, headers, out);
    lfio__h5_quiet_end(&q);
    return st;
}

lfio_status lfio_radmap_read(const char *path, lfio_radmap **out)
{
    return radmap_read("lfio_radmap_read", path, 0, out);
}

lfio_status lfio_radmap_read_headers(const char *path, lfio_radmap **out)
{
    return radmap_read("lfio_radmap_read_headers", path, 1, out);
}

/* Frees map; NULL is a no-op. */
void lfio_radmap_destroy(lfio_radmap *map)
{
    map_free(map);
}

/* @return the number of patches; 0 for NULL. */
size_t lfio_radmap_count(const lfio_radmap *map)
{
    return map ? map->count : 0;
}

/* Copies patch k's description, whose pointers stay owned by map. */
lfio_status lfio_radmap_get(const lfio_radmap *map, size_t k, lfio_radmap_patch *out)
{
    if (map == NULL || out == NULL)
        return lfio__fail(LFIO_ERR_ARG, "lfio_radmap_get: NULL argument");
    if (k >= map->count)
        return lfio__fail(LFIO_ERR_ARG, "lfio_radmap_get: patch %zu out of range (%zu patches)", k, map->count);
    *out = map->patches[k].pub;
    return LFIO_OK;
}

/* @return the stored creator; "" for NULL. */
const char *lfio_radmap_creator(const lfio_radmap *map)
{
    return map ? map->creator : "";
}

/* @return the stored scene path; "" for NULL. */
const char *lfio_radmap_scene(const lfio_radmap *map)
{
    return map ? map->scene : "";
}

/* @return the format_version of the file map was read from; 0 for NULL. */
int lfio_radmap_format_version(const lfio_radmap *map)
{
    return map ? map->format : 0;
}

/* @return 1 if map holds its cell arrays; 0 for headers only or NULL. */
int lfio_radmap_has_cells(const lfio_radmap *map)
{
    return map ? !map->headers : 0;
}

/* @return the stored cells over every patch; 0 for NULL. */
uint64_t lfio_radmap_cell_count(const lfio_radmap *map)
{
    return map ? map->cells : 0;
}

/* ------------------------------------------- format 2: headers a block at a time */

/*
 * lfio_radmap_headers: a format-2 file's tables read LFIO_RADMAP_HEADERS_BLOCK patches at a time, the
 * datasets kept open (HDF5 caches their decompressed chunks, and the vetted maps mean each chunk is
 * inflated by lfio once). Opening reads no table whole: it checks the root attributes, every dataset's
 * storage and shape, and the offset tables' first row (0) and last (the totals, which size the vertex and
 * cell datasets and bound every other row), so that it costs the same whatever the number of patches. The
 * rest of the checks of the whole read are made as the data they judge is read: a block's offsets (in
 * order, at most the total; the blocks overlap by a row, so the blocks together check the whole table),
 * the labels (scanned forward as far as the block asked for reaches, recording where each block of labels
 * starts; the count of labels when the scan reaches the end), and each patch as the whole read checks its
 * headers when it is got. A format-1 file is read whole by lfio_radmap_read_headers() instead (its patches
 * are groups anyway).
 */

/* Vertices a handle reads at once (a chunk's, 384 KiB), unless one patch has more (LFIO_RADMAP_MAX_VERTS at most,
 * 1.5 MiB). */
#define HDR_VERT_WINDOW ((uint64_t)V2_CHUNK)
/* Labels a handle holds at once: at most 1 MiB however long they are. */
#define HDR_LABEL_BLOCK 256u
/* Bytes of labels read at once while opening. */
#define HDR_LABEL_WINDOW 65536u

struct lfio_radmap_headers {
    char *path;
    lfio_radmap *meta;       /* root attributes and cell count; format 1: the whole headers */
    size_t count;            /* patches */
    hid_t file, g;
    hid_t d[V2_COUNT];       /* open tables and vertices; -1 otherwise */
    unsigned char *vetted[V2_COUNT];
    uint64_t *label_start;   /* byte where label block b's first label starts, b = 0 .. label blocks,
                              * known for the blocks the scan has passed */
    uint64_t label_bytes;
    uint64_t scan_pos;       /* labels' bytes scanned so far (a whole number of HDR_LABEL_WINDOW unless all) */
    size_t scan_nul;         /* labels they end */
    uint64_t scan_begin;     /* byte where the label after the last ended starts */
    uint64_t total[V2_COUNT];/* offsets tables: their last row, the vertices or cells of the file */
    size_t block;            /* the block of LFIO_RADMAP_HEADERS_BLOCK patches loaded, SIZE_MAX for none */
    size_t k0, n;            /* its first patch and size */
    unsigned char *tab[V2_COUNT]; /* the block's rows of each table (offsets: n + 1 rows) */
    size_t label_block;      /* the block of HDR_LABEL_BLOCK labels loaded, SIZE_MAX for none */
    char *labels;            /* its labels, NUL-terminated one after another */
    const char *label[HDR_LABEL_BLOCK];
    double *verts;           /* vertices [vfirst, vfirst + vcount) of the file */
    uint64_t vfirst, vcount, vcap;
};

/* Reads rows [first, first + rows) of open dataset t of h into buf, HDF5 silenced: the only HDF5 call of
 * lfio_radmap_headers_get(), which then costs nothing of HDF5 for a patch already in memory. */
static lfio_status hdr_read_rows(lfio_radmap_headers *h, enum v2_ds t, uint64_t first, uint64_t rows, void *buf)
{
    char dobj[64];
    snprintf(dobj, sizeof dobj, "/patches/%s", v2_datasets[t].name);
    const int rank = v2_datasets[t].width ? 2 : 1;
    const hsize_t start[2] = {first, 0}, n[2] = {rows, (hsize_t)v2_datasets[t].width};
    lfio__h5_quiet q;
    lfio__h5_quiet_begin(&q);
    lfio_status st = lfio__h5_read_vetted(h->path, dobj, h->d[t], v2_memory_type(t), rank, start, n, buf,
                                          (lfio__h5_vetted *)h->vetted[t]);
    lfio__h5_quiet_end(&q);
    return st;
}

/* Opens and checks dataset t of h's group for rows rows (source: where rows came from); keep: left open. */
static lfio_status hdr_open_dataset(lfio_radmap_headers *h, enum v2_ds t, uint64_t rows, const char *source,
                                    int keep)
{
    lfio__h5_layout l;
    v2_layout(t, rows, 0, &l);
    /* Read in order, a dataset needs one decompressed chunk cached, the one its next block falls in: HDF5's
     * default cache (1 MiB) would hold two or three of them for every open dataset. */
    hid_t dapl = keep ? H5Pcreate(H5P_DATASET_ACCESS) : -1;
    if (dapl >= 0)
        H5Pset_chunk_cache(dapl, 0, 0, 1.0);
    lfio_status st = lfio__h5_check_dataset(h->path, "/patches", h->g, &l, source, dapl, &h->d[t]);
    lfio__h5_close(dapl);
    const size_t bytes = st == LFIO_OK ? lfio__h5_vetted_bytes(h->d[t]) : 0;
    if (bytes > 0 && (h->vetted[t] = calloc(1, bytes)) == NULL)
        st = lfio__fail(LFIO_ERR_NOMEM, "%s: /patches/%s: out of memory", h->path, v2_datasets[t].name);
    if (!keep || st != LFIO_OK) {
        lfio__h5_close(h->d[t]);
        h->d[t] = -1;
    }
    return st;
}

/* Reads the first and last rows of offsets table t of h: the first must be 0, the last (the file's total,
 * *total) at most limit. The rows between are checked a block at a time (hdr_check_offsets()). */
static lfio_status hdr_offset_ends(lfio_radmap_headers *h, enum v2_ds t, uint64_t limit, uint64_t *total)
{
    uint32_t first = 0, last = 0;
    lfio_status st = hdr_read_rows(h, t, 0, 1, &first);
    if (st == LFIO_OK)
        st = hdr_read_rows(h, t, h->count, 1, &last);
    if (st == LFIO_OK && (first != 0 || last > limit))
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: /patches/%s: must start at 0 and end at most at %llu", h->path,
                        v2_datasets[t].name, (unsigned long long)limit);
    *total = last;
    h->total[t] = last;
    return st;
}

/* Checks the rows [k0, k0 + n] of offsets table t that h's block holds, as v2_check_offsets() checks the
 * table: never decreasing, and at most the table's last row (which the open read). */
static lfio_status hdr_check_offsets(const lfio_radmap_headers *h, enum v2_ds t)
{
    const uint32_t *off = (const uint32_t *)h->tab[t];
    for (size_t i = 1; i <= h->n; i++)
        if (off[i] < off[i - 1])
            return lfio__fail(LFIO_ERR_FORMAT, "%s: /patches/%s: offset %zu decreases", h->path, v2_datasets[t].name,
                              h->k0 + i);
    if (off[h->n] > h->total[t])
        return lfio__fail(LFIO_ERR_FORMAT, "%s: /patches/%s: offset %zu exceeds the last, %llu", h->path,
                          v2_datasets[t].name, h->k0 + h->n, (unsigned long long)h->total[t]);
    return LFIO_OK;
}

/* Scans the labels on from where the scan stopped, a window at a time, until the first need labels are known
 * to end (all of them, and the dataset's end, for need = count): bounds each, records where each block's
 * first starts, and checks their count when the scan reaches the end. */
static lfio_status hdr_scan_labels(lfio_radmap_headers *h, size_t need)
{
    const size_t blocks = h->count / HDR_LABEL_BLOCK + 1;
    unsigned char *buf = NULL;
    lfio_status st = LFIO_OK;
    while (st == LFIO_OK && h->scan_pos < h->label_bytes && (h->scan_nul < need || need >= h->count)) {
        if (buf == NULL && (buf = malloc(HDR_LABEL_WINDOW)) == NULL) {
            st = lfio__fail(LFIO_ERR_NOMEM, "%s: /patches/label: out of memory", h->path);
            break;
        }
        const uint64_t b0 = h->scan_pos;
        const uint64_t n = h->label_bytes - b0 < HDR_LABEL_WINDOW ? h->label_bytes - b0 : HDR_LABEL_WINDOW;
        st = hdr_read_rows(h, V2_LABEL, b0, n, buf);
        for (uint64_t i = 0; st == LFIO_OK && i < n; i++) {
            if (b0 + i - h->scan_begin > LFIO_RADMAP_TEXT_MAX)
                st = lfio__fail(LFIO_ERR_FORMAT, "%s: /patches: patch %zu: label is missing or longer than %u bytes",
                                h->path, h->scan_nul, LFIO_RADMAP_TEXT_MAX);
            if (buf[i] != '\0')
                continue;
            h->scan_begin = b0 + i + 1;
            if (++h->scan_nul % HDR_LABEL_BLOCK == 0 && h->scan_nul / HDR_LABEL_BLOCK <= blocks)
                h->label_start[h->scan_nul / HDR_LABEL_BLOCK] = h->scan_begin;
        }
        h->scan_pos = b0 + n;
    }
    free(buf);
    if (st == LFIO_OK && h->scan_pos >= h->label_bytes && (h->scan_nul != h->count || h->scan_begin != h->label_bytes))
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: /patches/label: expected %zu NUL-terminated labels", h->path, h->count);
    if (st != LFIO_OK)
        h->scan_pos = 0, h->scan_nul = 0, h->scan_begin = 0; /* a failed scan is made again, and fails again */
    return st;
}

/* Opens format-2 group g of h (h->count patches): every dataset's storage and shape checked and the offsets'
 * ends, the tables and vertices left open. */
static lfio_status hdr_open_v2(lfio_radmap_headers *h)
{
    h->label_bytes = first_axis_length(h->path, "/patches/label", h->g, "label");
    lfio_status st = LFIO_OK;
    if (h->label_bytes > (uint64_t)h->count * (LFIO_RADMAP_TEXT_MAX + 1))
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: /patches/label: %llu bytes for %zu labels of at most %u bytes", h->path,
                        (unsigned long long)h->label_bytes, h->count, LFIO_RADMAP_TEXT_MAX);
    if (st == LFIO_OK)
        st = hdr_open_dataset(h, V2_LABEL, h->label_bytes, "its own length", 1);
    if (st == LFIO_OK && (h->label_start = calloc(h->count / HDR_LABEL_BLOCK + 2, sizeof *h->label_start)) == NULL)
        st = lfio__fail(LFIO_ERR_NOMEM, "%s: /patches/label: out of memory", h->path);
    for (int t = 0; st == LFIO_OK && t < V2_COUNT; t++) {
        const enum v2_rows r = v2_datasets[t].rows;
        if (r != ROWS_PATCH && r != ROWS_OFFSET)
            continue;
        st = hdr_open_dataset(h, (enum v2_ds)t, h->count + (r == ROWS_OFFSET), "patch_count", 1);
        const size_t bytes = (LFIO_RADMAP_HEADERS_BLOCK + 1) * v2_row_bytes((enum v2_ds)t);
        if (st == LFIO_OK && (h->tab[t] = malloc(bytes)) == NULL)
            st = lfio__fail(LFIO_ERR_NOMEM, "%s: /patches: out of memory", h->path);
    }
    uint64_t vertices = 0, cells = 0;
    if (st == LFIO_OK)
        st = hdr_offset_ends(h, V2_VERTEX_OFFSET, LFIO_RADMAP_MAX_FILE_VERTS, &vertices);
    if (st == LFIO_OK)
        st = hdr_offset_ends(h, V2_CELL_OFFSET, LFIO_RADMAP_MAX_CELLS, &cells);
    for (int t = 0; st == LFIO_OK && t < V2_COUNT; t++) {
        const enum v2_rows r = v2_datasets[t].rows;
        if (r == ROWS_VERTEX || r == ROWS_CELL)
            st = hdr_open_dataset(h, (enum v2_ds)t, r == ROWS_VERTEX ? vertices : cells,
                                  r == ROWS_VERTEX ? "vertex_offset" : "cell_offset", r == ROWS_VERTEX);
    }
    h->meta->cells = cells;
    return st;
}

/* lfio_radmap_headers_open() without silencing HDF5. */
static lfio_status hdr_open(lfio_radmap_headers *h)
{
    lfio_status st = lfio__h5_open_read(h->path, &h->file);
    if (st == LFIO_OK)
        st = read_root(h->path, h->file, h->meta, &h->count);
    if (st == LFIO_OK && h->meta->format == 1) {
        lfio__h5_close(h->file);
        h->file = -1;
        lfio_radmap_destroy(h->meta);
        h->meta = NULL;
        st = radmap_read_impl(h->path, 1, &h->meta);
        h->count = lfio_radmap_count(h->meta);
        return st;
    }
    if (st == LFIO_OK)
        st = lfio__h5_open_group(h->path, "/patches", h->file, "patches", "group", &h->g);
    if (st == LFIO_OK)
        st = hdr_open_v2(h);
    return st;
}

lfio_status lfio_radmap_headers_open(const char *path, lfio_radmap_headers **out)
{
    if (out == NULL)
        return lfio__fail(LFIO_ERR_ARG, "lfio_radmap_headers_open: NULL argument");
    *out = NULL;
    if (path == NULL || path[0] == '\0')
        return lfio__fail(LFIO_ERR_ARG, "lfio_radmap_headers_open: NULL or empty path");
    lfio_radmap_headers *h = calloc(1, sizeof *h);
    if (h != NULL) {
        h->file = h->g = -1;
        for (int t = 0; t < V2_COUNT; t++)
            h->d[t] = -1;
        h->block = h->label_block = SIZE_MAX;
    }
    if (h == NULL || (h->path = malloc(strlen(path) + 1)) == NULL ||
        (h->meta = calloc(1, sizeof *h->meta)) == NULL) {
        lfio_radmap_headers_close(h);
        return lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", path);
    }
    memcpy(h->path, path, strlen(path) + 1);
    h->meta->headers = 1;
    lfio__h5_quiet q;
    lfio__h5_quiet_begin(&q);
    lfio_status st = hdr_open(h);
    lfio__h5_quiet_end(&q);
    if (st != LFIO_OK)
        lfio_radmap_headers_close(h);
    else
        *out = h;
    return st;
}

void lfio_radmap_headers_close(lfio_radmap_headers *h)
{
    if (h == NULL)
        return;
    lfio__h5_quiet q;
    lfio__h5_quiet_begin(&q);
    for (int t = 0; t < V2_COUNT; t++) {
        lfio__h5_close(h->d[t]);
        free(h->vetted[t]);
        free(h->tab[t]);
    }
    lfio__h5_close(h->g);
    lfio__h5_close(h->file);
    lfio__h5_quiet_end(&q);
    lfio_radmap_destroy(h->meta);
    free(h->label_start);
    free(h->labels);
    free(h->verts);
    free(h->path);
    free(h);
}

/* Loads block b of h: its rows of every table, its offsets checked. */
static lfio_status hdr_load_block(lfio_radmap_headers *h, size_t b)
{
    h->block = SIZE_MAX;
    h->vcount = 0;
    h->k0 = b * LFIO_RADMAP_HEADERS_BLOCK;
    h->n = h->count - h->k0 < LFIO_RADMAP_HEADERS_BLOCK ? h->count - h->k0 : LFIO_RADMAP_HEADERS_BLOCK;
    lfio_status st = LFIO_OK;
    for (int t = 0; st == LFIO_OK && t < V2_COUNT; t++) {
        const enum v2_rows r = v2_datasets[t].rows;
        if (r == ROWS_PATCH || r == ROWS_OFFSET)
            st = hdr_read_rows(h, (enum v2_ds)t, h->k0, h->n + (r == ROWS_OFFSET), h->tab[t]);
        if (st == LFIO_OK && r == ROWS_OFFSET)
            st = hdr_check_offsets(h, (enum v2_ds)t);
    }
    if (st == LFIO_OK)
        h->block = b;
    return st;
}

/* Loads label block b of h: the labels of patches [b * HDR_LABEL_BLOCK, ...), each checked by the scan to be
 * NUL-terminated and at most LFIO_RADMAP_TEXT_MAX bytes. */
static lfio_status hdr_load_labels(lfio_radmap_headers *h, size_t b)
{
    h->label_block = SIZE_MAX;
    const size_t k0 = b * HDR_LABEL_BLOCK, n = h->count - k0 < HDR_LABEL_BLOCK ? h->count - k0 : HDR_LABEL_BLOCK;
    lfio_status scanned = hdr_scan_labels(h, k0 + n);
    if (scanned != LFIO_OK)
        return scanned;
    const uint64_t first = h->label_start[b], end = k0 + n == h->count ? h->label_bytes : h->label_start[b + 1];
    char *labels = realloc(h->labels, end - first + 1);
    if (labels == NULL)
        return lfio__fail(LFIO_ERR_NOMEM, "%s: /patches/label: out of memory", h->path);
    h->labels = labels;
    lfio_status st = hdr_read_rows(h, V2_LABEL, first, end - first, h->labels);
    const char *label = h->labels;
    for (size_t i = 0; st == LFIO_OK && i < n; i++) {
        h->label[i] = label;
        label += strlen(label) + 1;
    }
    if (st == LFIO_OK)
        h->label_block = b;
    return st;
}

/* Makes the vertices of patch i of the loaded block (n of them, at most LFIO_RADMAP_MAX_VERTS) part of h's
 * window, reading on over the block's next patches as far as they fit in HDR_VERT_WINDOW. */
static lfio_status hdr_load_vertices(lfio_radmap_headers *h, size_t i, uint64_t n)
{
    const uint32_t *voff = (const uint32_t *)h->tab[V2_VERTEX_OFFSET];
    const uint64_t first = voff[i];
    if (first >= h->vfirst && first + n <= h->vfirst + h->vcount)
        return LFIO_OK;
    uint64_t end = first + n;
    for (size_t j = i + 1; j <= h->n && voff[j] - first <= HDR_VERT_WINDOW; j++)
        end = voff[j] > end ? voff[j] : end;
    h->vcount = 0;
    if (end - first > h->vcap) {
        const uint64_t cap = end - first > HDR_VERT_WINDOW ? end - first : HDR_VERT_WINDOW;
        double *v = realloc(h->verts, cap * 3 * sizeof *v);
        if (v == NULL)
            return lfio__fail(LFIO_ERR_NOMEM, "%s: /patches/vertices: out of memory", h->path);
        h->verts = v;
        h->vcap = cap;
    }
    h->vfirst = first;
    lfio_status st = hdr_read_rows(h, V2_VERTICES, first, end - first, h->verts);
    if (st == LFIO_OK)
        h->vcount = end - first;
    return st;
}

/* Describes patch k of format-2 h in *out and checks it as lfio_radmap_read_headers() does. */
static lfio_status hdr_get_v2(lfio_radmap_headers *h, size_t k, lfio_radmap_patch *out)
{
    lfio_status st = LFIO_OK;
    if (h->block != k / LFIO_RADMAP_HEADERS_BLOCK)
        st = hdr_load_block(h, k / LFIO_RADMAP_HEADERS_BLOCK);
    if (st == LFIO_OK && h->label_block != k / HDR_LABEL_BLOCK)
        st = hdr_load_labels(h, k / HDR_LABEL_BLOCK);
    if (st != LFIO_OK)
        return st;
    const size_t i = k - h->k0;
    lfio_radmap_patch p;
    v2_fill_scalars(h->tab, i, h->label[k % HDR_LABEL_BLOCK], &p);
    char why[256];
    const uint64_t v0 = ((const uint32_t *)h->tab[V2_VERTEX_OFFSET])[i];
    if (check_patch_scalars(&p, why, sizeof why))
        st = hdr_load_vertices(h, i, p.nverts);
    else
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: /patches: patch %zu: %s", h->path, k, why);
    if (st != LFIO_OK)
        return st;
    p.vertices = h->verts + 3 * (v0 - h->vfirst);
    if (!check_patch_header(&p, why, sizeof why))
        return lfio__fail(LFIO_ERR_FORMAT, "%s: /patches: patch %zu: %s", h->path, k, why);
    *out = p;
    return LFIO_OK;
}

lfio_status lfio_radmap_headers_get(lfio_radmap_headers *h, size_t k, lfio_radmap_patch *out)
{
    if (h == NULL || out == NULL)
        return lfio__fail(LFIO_ERR_ARG, "lfio_radmap_headers_get: NULL argument");
    if (k >= h->count)
        return lfio__fail(LFIO_ERR_ARG, "lfio_radmap_headers_get: patch %zu out of range (%zu patches)", k, h->count);
    return h->meta->format == 1 ? lfio_radmap_get(h->meta, k, out) : hdr_get_v2(h, k, out);
}

size_t lfio_radmap_headers_count(const lfio_radmap_headers *h)
{
    return h ? h->count : 0;
}

const char *lfio_radmap_headers_creator(const lfio_radmap_headers *h)
{
    return h ? lfio_radmap_creator(h->meta) : "";
}

const char *lfio_radmap_headers_scene(const lfio_radmap_headers *h)
{
    return h ? lfio_radmap_scene(h->meta) : "";
}

int lfio_radmap_headers_format_version(const lfio_radmap_headers *h)
{
    return h ? lfio_radmap_format_version(h->meta) : 0;
}

uint64_t lfio_radmap_headers_cell_count(const lfio_radmap_headers *h)
{
    return h ? lfio_radmap_cell_count(h->meta) : 0;
}
