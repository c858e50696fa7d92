/*
 * radmap.h - radiance-map files: the irradiance and radiosity on the cells
 * of every receiving polygon of a relit scene (the output of `ilf relight`),
 * stored in HDF5 (docs/format.md, "Radiance-map files").
 *
 * Conventions, stated once:
 *   - World frame right-handed, metres. One patch is one receiving polygon,
 *     with its vertices (counter-clockwise seen from its front) and its map
 *     frame: origin, unit orthogonal axes e1 and e2, and normal = e1 x e2,
 *     the front.
 *   - The map is a grid of nu x nv square cells of side cell_size; cell
 *     (i, j) covers origin + [u0 + i*cell_size, u0 + (i+1)*cell_size] * e1
 *     + [v0 + j*cell_size, v0 + (j+1)*cell_size] * e2, clipped to the
 *     polygon. Only the ncells cells whose clipped area is > 0 are stored,
 *     each with its (i, j), its area (m^2) and the world centroid of its
 *     clipped part. A patch may have no cells at all.
 *   - Irradiance and radiosity are W m^-2, linear Rec.709 RGB, float32,
 *     finite and >= 0; a cell's value is the mean over its clipped area.
 *     albedo is in [0, 1], emission (W sr^-1 m^-2) finite and >= 0.
 *   - Arrays are flat and row-major: vertices [nverts][3], cell_ij
 *     [ncells][2] (i then j), cell_area [ncells], cell_centre [ncells][3],
 *     irradiance and radiosity [ncells][3].
 *   - Every pointer in lfio_radmap_patch is borrowed: lfio_radmap_write()
 *     only reads through them during the call; lfio_radmap_get() points
 *     them into the reader's object, valid until lfio_radmap_destroy();
 *     lfio_radmap_headers_get() into the header reader's, valid until its
 *     next call or lfio_radmap_headers_close().
 *   - Status codes and messages as in lfio/lfio.h.
 *
 * Thread safety: a radiance map is read-only once read and may be queried
 * from any number of threads; a header reader (lfio_radmap_headers) is used
 * by one thread at a time.
 *
 * This header is valid C99 and C++.
 */
#ifndef LFIO_RADMAP_H
#define LFIO_RADMAP_H

#include <stddef.h>
#include <stdint.h>

#include "lfio/lfio.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Longest patch label, creator or scene path stored, in bytes, without the terminating NUL. */
#define LFIO_RADMAP_TEXT_MAX 4095u

/** Most patches one file may hold. */
#define LFIO_RADMAP_MAX_PATCHES 1048576u

/** Most vertices one patch's polygon may have. */
#define LFIO_RADMAP_MAX_VERTS 65536u

/** Most cells one file may hold, over all its patches (64 bytes each in memory). */
#define LFIO_RADMAP_MAX_CELLS ((uint64_t)1 << 26)

/** Most vertices one file may hold, over all its patches (format 2 stores their offsets as uint32). */
#define LFIO_RADMAP_MAX_FILE_VERTS ((uint64_t)1 << 28)

/** The newest format_version lfio writes and reads (docs/format.md, section 6); it reads every older one. */
#define LFIO_RADMAP_FORMAT_VERSION 2

/** One receiving polygon and its map; see the conventions above. */
typedef struct lfio_radmap_patch {
    const char *label;        /**< the polygon's element name in the scene file, e.g. "polygons[3]" */
    uint32_t polygon;         /**< scene polygon index */
    uint32_t nverts;          /**< polygon vertices, 3 .. LFIO_RADMAP_MAX_VERTS */
    const double *vertices;   /**< [nverts][3] world, metres */
    double origin[3];         /**< map frame origin, world */
    double e1[3];             /**< first map axis, unit */
    double e2[3];             /**< second map axis, unit, orthogonal to e1 */
    double normal[3];         /**< e1 x e2, the polygon's front */
    double cell_size;         /**< side of a cell, metres, > 0 */
    double u0, v0;            /**< grid offset along e1 and e2, metres */
    uint32_t nu, nv;          /**< grid size */
    uint32_t ncells;          /**< stored cells, at most nu*nv */
    const uint32_t *cell_ij;  /**< [ncells][2] grid indices, i < nu, j < nv */
    const double *cell_area;  /**< [ncells] clipped area, m^2, > 0 */
    const double *cell_centre;/**< [ncells][3] world centroid of the clipped cell */
    const float *irradiance;  /**< [ncells][3] W m^-2 */
    const float *radiosity;   /**< [ncells][3] W m^-2 */
    float albedo[3];          /**< reflectance, 0 .. 1 */
    float emission[3];        /**< exitant radiance, W sr^-1 m^-2 */
} lfio_radmap_patch;

/** The content of a radiance-map file, read whole. Opaque. */
typedef struct lfio_radmap lfio_radmap;

/**
 * Writes count patches (count may be 0) to path atomically, as
 * lfio_lightfield_write() does, with the default options of
 * lfio_radmap_write_options_init() (lfio_radmap_write_with() takes others). creator names the program (NULL: "lfio
 * VERSION"), scene the scene file it relit (NULL: ""). Every patch is checked
 * as the reader checks it, so a written file always reads back.
 * @return LFIO_OK; LFIO_ERR_ARG (the message names the patch and problem); LFIO_ERR_IO; LFIO_ERR_NOMEM.
 */
lfio_status lfio_radmap_write(const char *path, const char *creator, const char *scene,
                              const lfio_radmap_patch *patches, size_t count);

/**
 * Describes patch k (0 .. count - 1, asked in order, once each) of a file
 * being written by lfio_radmap_write_each(): fills *out, whose arrays must
 * stay valid until the next call or the write's end.
 * @return LFIO_OK, or another status to abandon the write (with a message
 * set by lfio or by the caller's own reporting).
 */
typedef lfio_status (*lfio_radmap_describe_fn)(void *user, size_t k, lfio_radmap_patch *out);

/**
 * Writes a file as lfio_radmap_write() does, asking describe for one patch
 * at a time, so that a caller need only hold one patch's arrays. Each patch
 * is checked as it arrives; a bad one, or a failing describe, abandons the
 * write and leaves path as it was.
 * @return as lfio_radmap_write(), or describe's status.
 */
lfio_status lfio_radmap_write_each(const char *path, const char *creator, const char *scene, size_t count,
                                   lfio_radmap_describe_fn describe, void *user);

/** Most cells lfio_radmap_write_rows() asks for at once. */
#define LFIO_RADMAP_ROWS_MAX 16384u

/** Cells [first, first + count) of a patch: each array holds count rows, as in lfio_radmap_patch. */
typedef struct lfio_radmap_rows {
    const uint32_t *cell_ij;  /**< [count][2] */
    const double *cell_area;  /**< [count] */
    const double *cell_centre;/**< [count][3] */
    const float *irradiance;  /**< [count][3] */
    const float *radiosity;   /**< [count][3] */
} lfio_radmap_rows;

/**
 * Gives cells [first, first + count) of patch k, described already, for
 * lfio_radmap_write_rows(): fills *out, whose arrays must stay valid until
 * the next call or the write's end. Asked patch after patch in order, and
 * within a patch in order of first, each cell once, count at most
 * LFIO_RADMAP_ROWS_MAX (0 for a patch of no cells). Format 2 describes
 * every patch before it asks for any cells; format 1 asks for a patch's
 * cells right after describing it.
 * @return LFIO_OK, or another status to abandon the write.
 */
typedef lfio_status (*lfio_radmap_rows_fn)(void *user, size_t k, uint32_t first, uint32_t count,
                                           lfio_radmap_rows *out);

/**
 * Writes a file as lfio_radmap_write_each() does, but describe gives each
 * patch without its cells (its five cell arrays are ignored) and rows gives
 * them a slice at a time, so that a caller need hold at most
 * LFIO_RADMAP_ROWS_MAX cells' arrays (lfio stores them as they come, a
 * batch of whole chunks at a time, filtered on the write's threads; in
 * format 1 it holds one slice's compressed chunks). The
 * file is the same. Each slice is checked as it arrives. rows NULL: the
 * cells are the described patch's arrays, as in lfio_radmap_write_each().
 * @return as lfio_radmap_write_each(), or rows's status.
 */
lfio_status lfio_radmap_write_rows(const char *path, const char *creator, const char *scene, size_t count,
                                   lfio_radmap_describe_fn describe, lfio_radmap_rows_fn rows, void *user);

/**
 * How a write stores its file. Set size to sizeof(lfio_radmap_write_options)
 * (lfio_radmap_write_options_init() does), so that a later lfio with more
 * fields still takes it; fields past size take their defaults.
 */
typedef struct lfio_radmap_write_options {
    size_t size;         /**< sizeof(lfio_radmap_write_options) as the caller was compiled */
    unsigned threads;    /**< threads compressing chunks in a serial write: 0 every core (at most 1024); the chunks'
                          *   bytes are the same whatever the count; MPI writes and big-endian machines compress
                          *   through HDF5 on one thread and ignore it */
    int deflate_level;   /**< zlib level, 0 (no compression) .. 9, of datasets of 1 KiB or more (format 2; default 1) */
    int format_version;  /**< 1 or 2 (LFIO_RADMAP_FORMAT_VERSION, the default): format 1 only for older readers */
} lfio_radmap_write_options;

/** Fills *opt with the defaults: threads 0 (every online core), level 1, the newest format. */
void lfio_radmap_write_options_init(lfio_radmap_write_options *opt);

/**
 * Writes a file as lfio_radmap_write_rows() does, stored as opt says (NULL:
 * the defaults of lfio_radmap_write_options_init()). In format 2 every array
 * is stored once for all patches: when lfio filters the chunks itself (a
 * little-endian machine, deflate_level > 0) a write with rows stores the
 * cells as they come and one without holds them compressed (about the
 * file's size) until it ends; otherwise it holds every cell (64 bytes a
 * cell). Either way the file is the same bytes.
 * @return as lfio_radmap_write_rows(); LFIO_ERR_ARG for options out of range.
 */
lfio_status lfio_radmap_write_with(const char *path, const char *creator, const char *scene, size_t count,
                                   lfio_radmap_describe_fn describe, lfio_radmap_rows_fn rows, void *user,
                                   const lfio_radmap_write_options *opt);

/**
 * Reads a whole file, checking format, attributes, shapes and limits before
 * allocating, then every checksum and value.
 * @return LFIO_OK and *out, owned by the caller; LFIO_ERR_NOTFOUND, LFIO_ERR_IO,
 * LFIO_ERR_FORMAT, LFIO_ERR_CHECKSUM or LFIO_ERR_NOMEM with *out = NULL.
 */
lfio_status lfio_radmap_read(const char *path, lfio_radmap **out);

/**
 * Reads a file's headers: its root attributes and every patch's description
 * and vertices, with the checks of lfio_radmap_read() short of the cell
 * datasets, whose storage and shape are checked but whose values are not
 * read. The patches' ncells is the stored count and their cell arrays
 * (cell_ij, cell_area, cell_centre, irradiance, radiosity) are NULL. Its
 * time and memory grow with the patches and vertices, not with the cells:
 * what a description of the file needs (`ilf info`).
 * @return as lfio_radmap_read().
 */
lfio_status lfio_radmap_read_headers(const char *path, lfio_radmap **out);
/** Releases a radiance map. NULL is a no-op. */
void lfio_radmap_destroy(lfio_radmap *map);

/** @return the number of patches; 0 for NULL. */
size_t lfio_radmap_count(const lfio_radmap *map);

/** Describes patch k in *out, its pointers borrowed from map. @return LFIO_OK or LFIO_ERR_ARG. */
lfio_status lfio_radmap_get(const lfio_radmap *map, size_t k, lfio_radmap_patch *out);

/** @return the creator string stored in the file (borrowed); "" for NULL. */
const char *lfio_radmap_creator(const lfio_radmap *map);

/** @return the scene path stored in the file (borrowed); "" for NULL. */
const char *lfio_radmap_scene(const lfio_radmap *map);

/** @return the format_version of the file map was read from (1 or 2); 0 for NULL. */
int lfio_radmap_format_version(const lfio_radmap *map);
/** @return 1 if map holds its cells (lfio_radmap_read()); 0 if only its headers (lfio_radmap_read_headers()) or NULL. */
int lfio_radmap_has_cells(const lfio_radmap *map);
/** @return the cells stored over every patch; 0 for NULL. */
uint64_t lfio_radmap_cell_count(const lfio_radmap *map);

/** Patches an lfio_radmap_headers reader holds in memory at once (format 2). */
#define LFIO_RADMAP_HEADERS_BLOCK 4096u

/**
 * A reader of a file's patch descriptions a block at a time: its memory is
 * bounded whatever the number of patches (the tables of
 * LFIO_RADMAP_HEADERS_BLOCK patches, their labels, at most
 * LFIO_RADMAP_MAX_VERTS vertices, and HDF5's caches of the open datasets:
 * a few MiB). Format 2 only: a format-1 file (a group a patch) is read
 * whole by lfio_radmap_read_headers(), its memory growing with its patches.
 * Opaque; one thread at a time.
 */
typedef struct lfio_radmap_headers lfio_radmap_headers;

/**
 * Opens path for lfio_radmap_headers_get(). Opening reads no table whole, so
 * that its time is the same whatever the number of patches: it checks the
 * root attributes, every dataset's storage and shape, and the first and last
 * rows of the offset tables (the file's totals of vertices and cells). The
 * other checks of lfio_radmap_read_headers() are made as the data they judge
 * is read by lfio_radmap_headers_get(): the offsets of the block read, the
 * labels as far as the patch got, the patch itself. A caller that gets every
 * patch has made every check of lfio_radmap_read_headers(); one that gets a
 * few has read, and checked, only their blocks. The file stays open until
 * lfio_radmap_headers_close().
 * @return LFIO_OK and *out, owned by the caller; as lfio_radmap_read()
 * otherwise, with *out = NULL.
 */
lfio_status lfio_radmap_headers_open(const char *path, lfio_radmap_headers **out);

/** Closes h. NULL is a no-op. */
void lfio_radmap_headers_close(lfio_radmap_headers *h);

/** @return the number of patches; 0 for NULL. */
size_t lfio_radmap_headers_count(const lfio_radmap_headers *h);

/**
 * Describes patch k in *out as lfio_radmap_read_headers() would (cell arrays
 * NULL, ncells the stored count), checked as that checks it. Reads the
 * block holding k when it is not the one in memory: cheapest with k in
 * order. out's pointers are borrowed from h, valid until the next
 * lfio_radmap_headers_get() or lfio_radmap_headers_close().
 * @return LFIO_OK; LFIO_ERR_ARG (k out of range, NULL); LFIO_ERR_FORMAT,
 * LFIO_ERR_CHECKSUM, LFIO_ERR_IO, LFIO_ERR_NOMEM (the file's problem).
 */
lfio_status lfio_radmap_headers_get(lfio_radmap_headers *h, size_t k, lfio_radmap_patch *out);

/** @return the creator stored in the file (borrowed from h); "" for NULL. */
const char *lfio_radmap_headers_creator(const lfio_radmap_headers *h);

/** @return the scene path stored in the file (borrowed from h); "" for NULL. */
const char *lfio_radmap_headers_scene(const lfio_radmap_headers *h);

/** @return the file's format_version (1 or 2); 0 for NULL. */
int lfio_radmap_headers_format_version(const lfio_radmap_headers *h);

/** @return the cells stored over every patch (the cell offsets' last row, read when opening); 0 for NULL. */
uint64_t lfio_radmap_headers_cell_count(const lfio_radmap_headers *h);

#ifdef __cplusplus
}
#endif

#endif /* LFIO_RADMAP_H */
