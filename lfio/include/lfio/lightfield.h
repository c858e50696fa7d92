/*
 * lightfield.h - sphere-plane incident light fields: slabs, their radiance,
 * queries, the zero-radiance mask, and HDF5 files.
 *
 * Conventions, stated once (docs/format.md states them again for readers of
 * the files):
 *   - World frame: right-handed, metres. A slab is the rectangle
 *     origin + s*u + t*v, s and t in [0, 1]; u and v are its edge vectors
 *     and must be orthogonal, nonzero and finite.
 *   - The slab frame is e1 = u/|u|, e2 = v/|v|, e3 = e1 x e2 (the slab's
 *     normal, its "front"). Directions are stored in the slab frame, with the
 *     partition's pole (+z of lfio/partition.h) along e3.
 *   - L(x, w) is radiance propagating through point x in direction w.
 *     Only the front hemisphere (w.e3 >= 0) is stored: the 4*n*n partition
 *     ids 0 .. 4*n*n-1 of level n, in the slab frame.
 *   - Positions form an nu x nv grid at cell centres:
 *     x(i, j) = origin + (i+0.5)/nu*u + (j+0.5)/nv*v, i < nu along u, j < nv along v.
 *   - Radiance is linear Rec.709 RGB, float32, in W sr^-1 m^-2 or in
 *     relative units (recorded in the slab). Values are finite and >= 0.
 *   - Memory layout of radiance: [dir][j][i][rgb], dir-major ("dir:v:u:rgb").
 *   - Zero-radiance mask: for each level m in n, n/2, n/4, ... down to the
 *     first odd level, one bit per hemisphere id at level m, set when some
 *     direction of level n inside it has max(r,g,b) > threshold at some
 *     position. The mask is kept up to date by every write.
 *
 * Thread safety: queries on a const slab may run concurrently; writes need
 * exclusive access. File I/O may be called from any thread (HDF5 serialises it).
 *
 * This header is valid C99 and C++.
 */
#ifndef LFIO_LIGHTFIELD_H
#define LFIO_LIGHTFIELD_H

#include <stddef.h>
#include <stdint.h>

#include "lfio/lfio.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Longest slab name, in bytes, without the terminating NUL. */
#define LFIO_NAME_MAX 63

/** Units of stored radiance. */
typedef enum lfio_units {
    LFIO_UNITS_RADIANCE = 0, /**< W sr^-1 m^-2 */
    LFIO_UNITS_RELATIVE = 1  /**< relative (uncalibrated) units */
} lfio_units;

/** Geometry and sampling of one slab; every field is an input to lfio_slab_new(). */
typedef struct lfio_slab_desc {
    char name[LFIO_NAME_MAX + 1]; /**< unique within a file; letters, digits, '_', '-', '.' */
    double origin[3];             /**< corner of the rectangle, metres, world frame */
    double u[3];                  /**< first edge, metres, world frame */
    double v[3];                  /**< second edge, orthogonal to u, metres, world frame */
    uint32_t nu;                  /**< positions along u, >= 1 */
    uint32_t nv;                  /**< positions along v, >= 1 */
    uint32_t n;                   /**< partition level, 1 .. LFIO_SLAB_MAX_N */
    lfio_units units;             /**< units of the radiance */
    float mask_threshold;         /**< radiance above which the mask marks a direction, >= 0 */
} lfio_slab_desc;

/** Largest partition level a slab may use. */
#define LFIO_SLAB_MAX_N 4096u

/** Default limit, in bytes, on one slab's radiance array (see lfio_slab_new()). */
#define LFIO_SLAB_MAX_BYTES ((uint64_t)1 << 36)

/** One slab: geometry plus radiance for every (direction, position). Opaque. */
typedef struct lfio_slab lfio_slab;

/** An ordered collection of slabs, the content of one file. Opaque. */
typedef struct lfio_lightfield lfio_lightfield;

/** Fills *d with a 1 m x 1 m slab at the origin facing +z, 1x1 positions, n = 1, no name. */
void lfio_slab_desc_init(lfio_slab_desc *d);

/**
 * Checks desc against every rule lfio_slab_new() applies (the same code):
 * a valid or empty name, finite origin, u and v nonzero, finite and
 * orthogonal (lfio_slab_edges_check()), nu, nv >= 1, n in 1..LFIO_SLAB_MAX_N,
 * known units, a finite mask threshold >= 0, a radiance array of at most
 * LFIO_SLAB_MAX_BYTES. For readers of descriptions (manifests, command
 * lines) that want lfio's verdict before asking for memory.
 * @return LFIO_OK, or LFIO_ERR_ARG with lfio_errmsg() = "slab 'NAME': problem".
 */
lfio_status lfio_slab_desc_check(const lfio_slab_desc *desc);

/**
 * @return the bytes of desc's radiance array, nu*nv*4*n*n*3 floats (UINT64_MAX if that overflows);
 * lfio_slab_new() refuses more than LFIO_SLAB_MAX_BYTES.
 */
uint64_t lfio_slab_desc_bytes(const lfio_slab_desc *desc);

/** @return 1 if name is a valid slab name: 1..LFIO_NAME_MAX characters of A-Z a-z 0-9 _ - . (else 0). */
int lfio_slab_name_valid(const char *name);

/** Verdicts of lfio_slab_edges_check(). */
#define LFIO_EDGES_OK 0         /**< usable slab edges */
#define LFIO_EDGES_LENGTH 1     /**< a component is not finite, a length is 0, or |u|*|v| overflows */
#define LFIO_EDGES_ORTHOGONAL 2 /**< |u.v| > 1e-9 |u| |v| */

/** @return LFIO_EDGES_OK if u and v are a slab's edges as lfio_slab_new() requires, else the first rule broken. */
int lfio_slab_edges_check(const double u[3], const double v[3]);

/* ------------------------------------------------------------------ slabs */

/**
 * Creates a slab with all radiance zero after validating desc (orthogonal
 * finite edges, sizes, a radiance array of at most LFIO_SLAB_MAX_BYTES).
 * @return LFIO_OK and *out, owned by the caller; an error and *out = NULL.
 */
lfio_status lfio_slab_new(const lfio_slab_desc *desc, lfio_slab **out);

/** Releases a slab. NULL is a no-op. */
void lfio_slab_destroy(lfio_slab *s);

/** @return the slab's description (borrowed; valid for the slab's life). */
const lfio_slab_desc *lfio_slab_get_desc(const lfio_slab *s);

/** @return the number of stored directions, 4*n*n. */
uint64_t lfio_slab_dir_count(const lfio_slab *s);

/** @return the radiance array, [dir][j][i][rgb] (borrowed, read-only). */
const float *lfio_slab_radiance(const lfio_slab *s);

/**
 * The per-direction support of s's nonzero radiance: for every stored
 * direction d, box[d] = {i_min, i_max, j_min, j_max}, the smallest box of
 * positions outside which direction d's radiance is zero in every channel
 * (whatever the mask threshold). A direction with no nonzero radiance gets
 * i_min = 1 > i_max = 0. box holds lfio_slab_dir_count(s) entries. Lets a
 * renderer skip the parts of an emitter that are dark along a direction.
 * @return LFIO_OK, or LFIO_ERR_ARG if s or box is NULL.
 */
lfio_status lfio_slab_support(const lfio_slab *s, uint32_t (*box)[4]);

/**
 * Sets the radiance of one sample and updates the mask.
 * @return LFIO_OK; LFIO_ERR_ARG if an index is out of range or a value is negative or not finite.
 */
lfio_status lfio_slab_write(lfio_slab *s, uint64_t dir, uint32_t i, uint32_t j, const float rgb[3]);

/**
 * Sets every position of one direction from img, laid out [j][i][rgb], and updates the mask.
 * @return LFIO_OK; LFIO_ERR_ARG (slab unchanged) if dir is out of range or a value is invalid.
 */
lfio_status lfio_slab_write_direction(lfio_slab *s, uint64_t dir, const float *img);

/**
 * Sets every direction of one position from rgb, laid out [dir][rgb], and updates the mask.
 * @return LFIO_OK; LFIO_ERR_ARG (slab unchanged) if (i, j) is out of range or a value is invalid.
 */
lfio_status lfio_slab_write_position(lfio_slab *s, uint32_t i, uint32_t j, const float *rgb);

/** Copies the radiance of one direction into img ([j][i][rgb]). @return LFIO_OK or LFIO_ERR_ARG. */
lfio_status lfio_slab_read_direction(const lfio_slab *s, uint64_t dir, float *img);

/** Copies the radiance of one position into rgb ([dir][rgb]). @return LFIO_OK or LFIO_ERR_ARG. */
lfio_status lfio_slab_read_position(const lfio_slab *s, uint32_t i, uint32_t j, float *rgb);

/** Gives the world-frame centre of position (i, j). @return LFIO_OK or LFIO_ERR_ARG. */
lfio_status lfio_slab_position(const lfio_slab *s, uint32_t i, uint32_t j, double x[3]);

/** Converts a world-frame direction to the slab frame (no normalisation). */
void lfio_slab_to_local(const lfio_slab *s, const double world[3], double local[3]);

/** Converts a slab-frame direction to the world frame (no normalisation). */
void lfio_slab_to_world(const lfio_slab *s, const double local[3], double world[3]);

/**
 * Finds the slab coordinates (s, t) of the orthogonal projection of world
 * point x onto the slab's plane; *dist is x's signed height along e3.
 * Any argument but s and x may be NULL.
 */
void lfio_slab_locate(const lfio_slab *s, const double x[3], double *st_s, double *st_t, double *dist);

/* ---------------------------------------------------------------- queries */

/**
 * Radiance at slab coordinates (s, t) in world direction w, from the
 * nearest position and the solid angle containing w.
 * rgb = 0 when w points behind the slab (w.e3 < 0).
 * @return LFIO_OK; LFIO_ERR_ARG if w is zero or not finite, or s, t are not finite.
 */
lfio_status lfio_slab_radiance_nearest(const lfio_slab *s, double st_s, double st_t,
                                       const double w[3], float rgb[3]);

/**
 * Radiance at (s, t) in world direction w, interpolated bilinearly between
 * position centres (clamped at the border) and over directions by
 * lfio_part_interp() (neighbours behind the slab count as the containing solid angle).
 * @return as lfio_slab_radiance_nearest().
 */
lfio_status lfio_slab_radiance_interp(const lfio_slab *s, double st_s, double st_t,
                                      const double w[3], float rgb[3]);

/**
 * Radiance at (s, t), bilinear between position centres as
 * lfio_slab_radiance_interp(), mixing the given directions with weights w
 * (as lfio_part_interp() or lfio_part_interp_weights() give them at the
 * slab's n): the interpolation for a caller that already knows them.
 * ids[1..3] beyond the stored hemisphere count as ids[0]. Thread-safe.
 * @return LFIO_OK; LFIO_ERR_ARG if s, t are not finite or ids[0] is not stored.
 */
lfio_status lfio_slab_radiance_mix(const lfio_slab *s, double st_s, double st_t, const uint64_t ids[4],
                                   const double w[4], float rgb[3]);

/**
 * Blends the given directions with weights w, as lfio_slab_radiance_mix()
 * mixes them, at every position of box = {i_min, i_max, j_min, j_max}
 * (inclusive, within the slab) into rgb: (i_max - i_min + 1) * (j_max -
 * j_min + 1) RGB triples, row by row. For a caller that reads one mix at
 * many points: lfio_slab_blend_radiance() then takes 4 taps a point
 * instead of 16. Thread-safe.
 * @return LFIO_OK; LFIO_ERR_ARG if ids[0] is not stored or box is empty or outside the slab.
 */
lfio_status lfio_slab_blend(const lfio_slab *s, const uint64_t ids[4], const double w[4], const uint32_t box[4],
                            float *rgb);

/**
 * Radiance at (s, t) from rgb, an lfio_slab_blend() table over box,
 * bilinear between position centres as lfio_slab_radiance_mix(); positions
 * outside box read 0, so a box that holds every nonzero position of the
 * blended directions (lfio_slab_support()) gives their mix up to float
 * rounding. s and t should be finite (a NaN reads the first position).
 * Thread-safe.
 */
void lfio_slab_blend_radiance(const lfio_slab *s, const uint32_t box[4], const float *rgb, double st_s,
                              double st_t, float out[3]);

/**
 * The slab's position grid as lfio_blend_at() reads an lfio_slab_blend()
 * table: grid coordinates (gu, gv) = (s * nu - 0.5, t * nv - 0.5) put the
 * centre of position (i, j) at (i, j). For a caller whose (s, t) are affine
 * in its own coordinates, so that it can fold this map into theirs.
 */
typedef struct lfio_blend_grid {
    double hi[2];     /**< nu - 1, nv - 1: gu and gv are clamped to [0, hi], the edges' values held */
    double rect[4];   /**< {gu_min, gu_max, gv_min, gv_max}: outside it the table reads 0 (infinite past the slab's
                           edges, where the edges' values hold) */
    uint32_t box[4];  /**< the table's positions, as lfio_slab_blend() took them */
    uint32_t ni, nj;  /**< the table's positions along s and t: box[1] - box[0] + 1, box[3] - box[2] + 1 */
} lfio_blend_grid;

/**
 * Clamps grid coordinate g (lfio_blend_grid) to [0, hi] and splits it into
 * the position centre at or below it, *i, and the fraction past it.
 * @return the fraction, in [0, 1).
 */
static inline double lfio_grid_split(double g, double hi, uint32_t *i)
{
    /* clamped by comparisons, not fmin/fmax: this is the hot path of relighting */
    g = g > 0.0 ? (g < hi ? g : hi) : 0.0;
    *i = (uint32_t)g;
    return g - *i;
}

/** Describes the grid of s for a table over box (not checked: as given to lfio_slab_blend()). */
void lfio_slab_blend_grid(const lfio_slab *s, const uint32_t box[4], lfio_blend_grid *g);

/**
 * lfio_slab_blend_radiance() at grid coordinates (gu, gv) of g (finite):
 * the same value, inline for callers that look up many points.
 */
static inline void lfio_blend_at(const lfio_blend_grid *g, const float *rgb, double gu, double gv, float out[3])
{
    uint32_t i0, j0;
    double fu = lfio_grid_split(gu, g->hi[0], &i0), fv = lfio_grid_split(gv, g->hi[1], &j0);
    /* relative to the box; unsigned wrap-around makes one comparison per
     * tap test both ends. Past the slab's last position a tap's weight is
     * 0 (fu or fv is 0 there), and it reads 0 as outside the box. */
    uint32_t ia = i0 - g->box[0], ja = j0 - g->box[2];
    double wu[2] = {1 - fu, fu}, wv[2] = {1 - fv, fv};
    float acc[3] = {0, 0, 0};
    for (uint32_t b = 0; b < 2; b++) {
        if (ja + b >= g->nj)
            continue;
        const float *row = rgb + (size_t)(ja + b) * g->ni * 3;
        for (uint32_t a = 0; a < 2; a++) {
            if (ia + a >= g->ni)
                continue;
            const float *p = row + (size_t)(ia + a) * 3;
            float wq = (float)(wu[a] * wv[b]);
            for (int c = 0; c < 3; c++)
                acc[c] += wq * p[c];
        }
    }
    out[0] = acc[0];
    out[1] = acc[1];
    out[2] = acc[2];
}

/**
 * Irradiance at (s, t) on a surface facing -e3 that receives the light
 * crossing the slab: sum over dirs of L * projected solid angle about e3,
 * radiance bilinear over positions, piecewise constant over solid angles.
 * Computed in double. W m^-2 when the units are radiance.
 * @return LFIO_OK; LFIO_ERR_ARG if s or t is not finite.
 */
lfio_status lfio_slab_irradiance(const lfio_slab *s, double st_s, double st_t, double rgb[3]);

/* ------------------------------------------------------------------- mask */

/** @return the number of mask levels (1 for odd n; log2(n)+1 for powers of two). */
uint32_t lfio_slab_mask_levels(const lfio_slab *s);

/** @return the partition level of mask level k (k = 0 is the coarsest); 0 if k is out of range. */
uint32_t lfio_slab_mask_n(const lfio_slab *s, uint32_t k);

/**
 * Tests the mask in constant time.
 * @return 1 if hemisphere id at partition level m may carry radiance above
 * the threshold, 0 if it carries none; 1 also when m is not a mask level or id is out of range
 * (the conservative answer).
 */
int lfio_slab_mask_test(const lfio_slab *s, uint32_t m, uint64_t id);

/** @return the number of set bits at partition level m (0 if m is not a mask level). */
uint64_t lfio_slab_mask_count(const lfio_slab *s, uint32_t m);

/* ------------------------------------------------------------ collections */

/** Creates an empty light field. @return LFIO_OK and *out; LFIO_ERR_NOMEM. */
lfio_status lfio_lightfield_new(lfio_lightfield **out);

/** Releases a light field and every slab it owns. NULL is a no-op. */
void lfio_lightfield_destroy(lfio_lightfield *lf);

/**
 * Appends slab s and takes ownership of it, also on failure (it is then destroyed).
 * @return LFIO_OK; LFIO_ERR_ARG if its name is empty, invalid or already used; LFIO_ERR_NOMEM.
 */
lfio_status lfio_lightfield_take_slab(lfio_lightfield *lf, lfio_slab *s);

/** @return the number of slabs. */
size_t lfio_lightfield_slab_count(const lfio_lightfield *lf);

/** @return slab k (borrowed), or NULL if k is out of range. */
lfio_slab *lfio_lightfield_slab(const lfio_lightfield *lf, size_t k);

/** @return the slab named name (borrowed), or NULL if there is none. */
lfio_slab *lfio_lightfield_find(const lfio_lightfield *lf, const char *name);

/** Sets the creator string recorded in files (copied; default "lfio VERSION"). @return LFIO_OK or LFIO_ERR_ARG. */
lfio_status lfio_lightfield_set_creator(lfio_lightfield *lf, const char *creator);

/** @return the creator string (borrowed). */
const char *lfio_lightfield_creator(const lfio_lightfield *lf);

/* ------------------------------------------------------------------ files */

/**
 * Writes lf to path atomically: a temporary file in the same folder is
 * written, flushed and renamed over path; on failure path is untouched and
 * the temporary removed.
 * @return LFIO_OK; LFIO_ERR_ARG if lf has no slabs; LFIO_ERR_IO.
 */
lfio_status lfio_lightfield_write(const lfio_lightfield *lf, const char *path);

/**
 * How a read is done (not what it reads: the values are the same whatever
 * the options). Set size to sizeof(lfio_read_options)
 * (lfio_read_options_init() does), so that a later lfio with more fields
 * still takes it; fields past size take their defaults.
 */
typedef struct lfio_read_options {
    size_t size;       /**< sizeof(lfio_read_options) as the caller was compiled */
    unsigned threads;  /**< threads inflating a slab's radiance chunks in whole reads: 0 every online core (the
                        *   default), 1 the calling thread alone, at most 1024. Files stored as lfio writes them
                        *   are inflated by lfio itself, on these threads; others, and every file on big-endian
                        *   machines, through HDF5 on one. */
} lfio_read_options;

/** Fills *opt with the defaults: threads 0 (every online core). */
void lfio_read_options_init(lfio_read_options *opt);

/**
 * Reads a whole file, checking format, shapes, limits and checksums before
 * and while allocating, and rebuilds each slab's mask from its radiance;
 * with the default options (lfio_lightfield_read_with() takes others).
 * @return LFIO_OK and *out, owned by the caller; LFIO_ERR_NOTFOUND, LFIO_ERR_IO,
 * LFIO_ERR_FORMAT, LFIO_ERR_CHECKSUM or LFIO_ERR_NOMEM with *out = NULL.
 */
lfio_status lfio_lightfield_read(const char *path, lfio_lightfield **out);

/**
 * Reads a whole file as lfio_lightfield_read() does, as opt says (NULL: the
 * defaults of lfio_read_options_init()).
 * @return as lfio_lightfield_read(); LFIO_ERR_ARG for options out of range
 * or of a size this library does not know.
 */
lfio_status lfio_lightfield_read_with(const char *path, const lfio_read_options *opt, lfio_lightfield **out);

/* --------------------------------------------------------------- coverage */

/*
 * Coverage is optional, per slab of a light field: one byte per sample,
 * laid out like the radiance without its channels, [dir][j][i]; 1 where the
 * data behind the sample is known (for example, the capture covers the ray),
 * 0 where it is not and the radiance is only a placeholder (usually 0).
 * Files store it as /slabs/<k>/coverage (docs/format.md); files without it
 * stay valid.
 */

/**
 * Attaches a copy of coverage ([dir][j][i], 4n^2*nu*nv values, each 0 or 1)
 * to slab k of lf, replacing any it had; NULL removes it.
 * @return LFIO_OK; LFIO_ERR_ARG (lf unchanged) if k is out of range or a
 * value is neither 0 nor 1; LFIO_ERR_NOMEM (lf unchanged).
 */
lfio_status lfio_lightfield_set_coverage(lfio_lightfield *lf, size_t k, const uint8_t *coverage);

/**
 * @return the coverage of slab k, [dir][j][i] (borrowed, valid until it is
 * replaced or lf destroyed); NULL if the slab has none or k is out of range.
 */
const uint8_t *lfio_lightfield_coverage(const lfio_lightfield *lf, size_t k);

/*
 * The covered share of a slab's etendue (optional, per slab, like coverage
 * and independent of it): the fraction, 0 .. 1, of the slab's etendue
 * (area times projected solid angle, pi per unit area) whose light the data
 * behind it holds; 1 - fraction of it carries no data (radiance 0 there
 * means "unknown", not "dark"). Files store it as the slab group's float64
 * attribute coverage_fraction (docs/format.md); files without it say nothing.
 */

/**
 * Sets slab k's covered share of the etendue; NaN removes it.
 * @return LFIO_OK; LFIO_ERR_ARG (lf unchanged) if k is out of range or fraction is not NaN and not in [0, 1].
 */
lfio_status lfio_lightfield_set_coverage_fraction(lfio_lightfield *lf, size_t k, double fraction);

/** @return slab k's covered share of the etendue, 0 .. 1; NaN if it has none or k is out of range. */
double lfio_lightfield_coverage_fraction(const lfio_lightfield *lf, size_t k);

/**
 * @return the covered share of a slab's etendue: each sample of coverage
 * ([dir][j][i] for a slab of desc's geometry, values 0 or 1) weighted by the
 * projected solid angle of its direction about the slab's normal, every
 * position equally; 0 for a slab of no directions. *covered (unless NULL)
 * gets the number of covered samples.
 */
double lfio_coverage_share(const lfio_slab_desc *desc, const uint8_t *coverage, uint64_t *covered);

/** An open file whose slabs can be read in part. Opaque. */
typedef struct lfio_reader lfio_reader;

/**
 * Opens a file and validates its metadata (not yet the radiance); its whole
 * reads (lfio_reader_read_slab()) take the default options.
 * @return LFIO_OK and *out; an error as lfio_lightfield_read() with *out = NULL.
 */
lfio_status lfio_reader_open(const char *path, lfio_reader **out);

/**
 * Opens a file as lfio_reader_open() does; its reads are done as opt says
 * (NULL: the defaults; opt is copied).
 * @return as lfio_reader_open(); LFIO_ERR_ARG for options out of range or of
 * a size this library does not know.
 */
lfio_status lfio_reader_open_with(const char *path, const lfio_read_options *opt, lfio_reader **out);

/** Closes the file. NULL is a no-op. */
void lfio_reader_close(lfio_reader *r);

/** @return the number of slabs in the file. */
size_t lfio_reader_slab_count(const lfio_reader *r);

/** @return the description of slab k (borrowed), or NULL if k is out of range. */
const lfio_slab_desc *lfio_reader_slab_desc(const lfio_reader *r, size_t k);

/** @return the creator string stored in the file (borrowed). */
const char *lfio_reader_creator(const lfio_reader *r);

/** @return the format version stored in the file. */
int lfio_reader_format_version(const lfio_reader *r);

/**
 * Reads one direction of slab k into img ([j][i][rgb]) without reading the other directions.
 * @return LFIO_OK; LFIO_ERR_ARG; LFIO_ERR_IO, LFIO_ERR_FORMAT or LFIO_ERR_CHECKSUM.
 */
lfio_status lfio_reader_read_direction(lfio_reader *r, size_t k, uint64_t dir, float *img);

/**
 * Reads every direction of position (i, j) of slab k into rgb ([dir][rgb]).
 * @return as lfio_reader_read_direction().
 */
lfio_status lfio_reader_read_position(lfio_reader *r, size_t k, uint32_t i, uint32_t j, float *rgb);

/**
 * Reads slab k whole.
 * @return LFIO_OK and *out, owned by the caller; an error and *out = NULL.
 */
lfio_status lfio_reader_read_slab(lfio_reader *r, size_t k, lfio_slab **out);

/** @return 1 if slab k of the file has a coverage dataset (its type and shape were checked on opening), else 0. */
int lfio_reader_has_coverage(const lfio_reader *r, size_t k);

/**
 * @return slab k's coverage_fraction attribute, 0 .. 1 (checked on opening); NaN if it has none or k is out of
 * range.
 */
double lfio_reader_coverage_fraction(const lfio_reader *r, size_t k);

/**
 * Reads the coverage of slab k into coverage ([dir][j][i], 4n^2*nu*nv bytes)
 * and checks that every value is 0 or 1.
 * @return LFIO_OK; LFIO_ERR_ARG (also when the slab has no coverage);
 * LFIO_ERR_IO, LFIO_ERR_FORMAT or LFIO_ERR_CHECKSUM.
 */
lfio_status lfio_reader_read_coverage(lfio_reader *r, size_t k, uint8_t *coverage);

/** Result of lfio_verify(). */
typedef struct lfio_verify_report {
    uint32_t problems;   /**< number of problems found */
    char first[512];     /**< the first problem, "" if none */
} lfio_verify_report;

/**
 * Checks a file completely: format, every attribute and shape, every checksum
 * (by reading all data), the stored directions, solid angles and mask against
 * values recomputed from the geometry and radiance, and coverage values (0 or 1).
 * @return LFIO_OK if the file is valid; otherwise the first problem's status,
 * with details in lfio_errmsg() and *report (which may be NULL).
 */
lfio_status lfio_verify(const char *path, lfio_verify_report *report);

#ifdef __cplusplus
}
#endif

#endif /* LFIO_LIGHTFIELD_H */
