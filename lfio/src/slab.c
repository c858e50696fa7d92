/*
 * slab.c - one slab of a light field: validation, storage, writes that keep
 * the zero-radiance mask exact, and radiance and irradiance queries.
 *
 * Invariants (see internal.h): the radiance array is finite and >= 0, the
 * frame e1, e2, e3 is orthonormal and right-handed, the solid-angle tables
 * hold the exact values of lfio_part_solid_angle() and
 * lfio_part_projected_solid_angle() about the pole, and the mask agrees with
 * the radiance after every public call returns. Writes validate their whole
 * input before changing anything, so a rejected write leaves the slab as it was.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ilf/vec.h"
#include "internal.h"
#include "mask.h"


/* @return 1 if all three components are finite. */
static int finite3(const double a[3])
{
    return isfinite(a[0]) && isfinite(a[1]) && isfinite(a[2]);
}

void lfio_slab_desc_init(lfio_slab_desc *d)
{
    memset(d, 0, sizeof *d);
    d->u[0] = 1.0;
    d->v[1] = 1.0;
    d->nu = d->nv = d->n = 1;
    d->units = LFIO_UNITS_RADIANCE;
    d->mask_threshold = 0.0f;
}

int lfio_slab_name_valid(const char *name)
{
    return name != NULL && lfio__valid_name(name);
}

int lfio_slab_edges_check(const double u[3], const double v[3])
{
    if (u == NULL || v == NULL || !finite3(u) || !finite3(v))
        return LFIO_EDGES_LENGTH;
    double lu = sqrt(a3_dot(u, u)), lv = sqrt(a3_dot(v, v));
    /* the product too: where it overflows, the orthogonality test below would pass anything */
    if (!(lu > 0.0) || !(lv > 0.0) || !isfinite(lu * lv))
        return LFIO_EDGES_LENGTH;
    if (fabs(a3_dot(u, v)) > 1e-9 * lu * lv)
        return LFIO_EDGES_ORTHOGONAL;
    return LFIO_EDGES_OK;
}

uint64_t lfio_slab_desc_bytes(const lfio_slab_desc *d)
{
    uint64_t ndir = 4u * (uint64_t)d->n * d->n, cells, floats, bytes;
    if (!lfio__mul_u64(d->nu, d->nv, &cells) || !lfio__mul_u64(cells, ndir, &floats) ||
        !lfio__mul_u64(floats, 3u * sizeof(float), &bytes))
        return UINT64_MAX;
    return bytes;
}

lfio_status lfio_slab_desc_check(const lfio_slab_desc *desc)
{
    char why[128];
    if (desc == NULL)
        return lfio__fail(LFIO_ERR_ARG, "lfio_slab_desc_check: desc is NULL");
    if (lfio__check_desc(desc, why, sizeof why) != LFIO_OK)
        return lfio__fail(LFIO_ERR_ARG, "slab '%s': %s", desc->name, why);
    return LFIO_OK;
}

int lfio__valid_name(const char *name)
{
    const char *end = memchr(name, '\0', LFIO_NAME_MAX + 1);
    size_t len = end ? (size_t)(end - name) : LFIO_NAME_MAX + 1;
    if (len == 0 || len > LFIO_NAME_MAX)
        return 0;
    for (size_t k = 0; k < len; k++) {
        char c = name[k];
        int ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                 c == '_' || c == '-' || c == '.';
        if (!ok)
            return 0;
    }
    return 1;
}

lfio_status lfio__check_desc(const lfio_slab_desc *d, char *why, size_t why_size)
{
    const char *problem = NULL;
    int edges = lfio_slab_edges_check(d->u, d->v);
    if (memchr(d->name, '\0', sizeof d->name) == NULL)
        problem = "name is not NUL-terminated";
    else if (d->name[0] && !lfio__valid_name(d->name))
        problem = "name must be 1-63 characters of letters, digits, '_', '-', '.'";
    else if (!finite3(d->origin) || !finite3(d->u) || !finite3(d->v))
        problem = "origin, u and v must be finite";
    else if (edges == LFIO_EDGES_LENGTH)
        problem = "u and v must be nonzero and finite in length";
    else if (edges == LFIO_EDGES_ORTHOGONAL)
        problem = "u and v must be orthogonal";
    else if (d->nu < 1 || d->nv < 1)
        problem = "nu and nv must be at least 1";
    else if (d->n < 1 || d->n > LFIO_SLAB_MAX_N)
        problem = "n must be between 1 and 4096";
    else if (d->units != LFIO_UNITS_RADIANCE && d->units != LFIO_UNITS_RELATIVE)
        problem = "units must be radiance or relative";
    else if (!(d->mask_threshold >= 0.0f) || !isfinite(d->mask_threshold))
        problem = "mask threshold must be finite and >= 0";
    else if (lfio_slab_desc_bytes(d) > LFIO_SLAB_MAX_BYTES)
        problem = "radiance array would exceed 64 GiB";
    if (!problem)
        return LFIO_OK;
    if (why && why_size)
        snprintf(why, why_size, "%s", problem);
    return LFIO_ERR_ARG;
}

/* Sets up the orthonormal slab frame from u and v. */
static void make_frame(lfio_slab *s)
{
    const double *u = s->desc.u, *v = s->desc.v;
    s->len_u = sqrt(a3_dot(u, u));
    s->len_v = sqrt(a3_dot(v, v));
    for (int k = 0; k < 3; k++) {
        s->e1[k] = u[k] / s->len_u;
        s->e2[k] = v[k] / s->len_v;
    }
    s->e3[0] = s->e1[1] * s->e2[2] - s->e1[2] * s->e2[1];
    s->e3[1] = s->e1[2] * s->e2[0] - s->e1[0] * s->e2[2];
    s->e3[2] = s->e1[0] * s->e2[1] - s->e1[1] * s->e2[0];
    double l3 = sqrt(a3_dot(s->e3, s->e3));
    for (int k = 0; k < 3; k++)
        s->e3[k] /= l3;
}

/* Fills the solid-angle tables for the hemisphere about the pole. */
static void fill_tables(lfio_slab *s)
{
    const double pole[3] = {0.0, 0.0, 1.0};
    for (uint64_t d = 0; d < s->ndir; d++) {
        s->solid_angle[d] = lfio_part_solid_angle(s->desc.n, d);
        s->proj_solid_angle[d] = lfio_part_projected_solid_angle(s->desc.n, d, pole);
    }
}

lfio_status lfio_slab_new(const lfio_slab_desc *desc, lfio_slab **out)
{
    if (!out)
        return lfio__fail(LFIO_ERR_ARG, "lfio_slab_new: out is NULL");
    *out = NULL;
    if (!desc)
        return lfio__fail(LFIO_ERR_ARG, "lfio_slab_new: desc is NULL");
    if (lfio_slab_desc_check(desc) != LFIO_OK)
        return LFIO_ERR_ARG;
    lfio_slab *s = calloc(1, sizeof *s);
    if (!s)
        return lfio__fail(LFIO_ERR_NOMEM, "slab '%s': out of memory", desc->name);
    s->desc = *desc;
    s->ndir = lfio_part_hemi_count(desc->n);
    s->npos = (uint64_t)desc->nu * desc->nv;
    make_frame(s);
    /* one float past the last triple: mix_directions() loads triples four floats at a time */
    s->radiance = calloc(s->ndir * s->npos * 3 + 1, sizeof(float));
    s->solid_angle = malloc(s->ndir * sizeof(double));
    s->proj_solid_angle = malloc(s->ndir * sizeof(double));
    if (!s->radiance || !s->solid_angle || !s->proj_solid_angle || lfio__mask_alloc(s) != LFIO_OK) {
        lfio_slab_destroy(s);
        return lfio__fail(LFIO_ERR_NOMEM, "slab '%s': cannot allocate %llu directions x %llu positions",
                          desc->name, (unsigned long long)lfio_part_hemi_count(desc->n),
                          (unsigned long long)((uint64_t)desc->nu * desc->nv));
    }
    fill_tables(s);
    *out = s;
    return LFIO_OK;
}

void lfio_slab_destroy(lfio_slab *s)
{
    if (!s)
        return;
    lfio__mask_free(s);
    free(s->radiance);
    free(s->solid_angle);
    free(s->proj_solid_angle);
    free(s);
}

const lfio_slab_desc *lfio_slab_get_desc(const lfio_slab *s)
{
    return &s->desc;
}

uint64_t lfio_slab_dir_count(const lfio_slab *s)
{
    return s->ndir;
}

lfio_status lfio_slab_support(const lfio_slab *s, uint32_t (*box)[4])
{
    if (s == NULL || box == NULL)
        return lfio__fail(LFIO_ERR_ARG, "lfio_slab_support: %s is NULL", s == NULL ? "slab" : "box");
    uint32_t nu = s->desc.nu, nv = s->desc.nv;
    for (uint64_t k = 0; k < s->ndir; k++) {
        uint32_t b[4] = {UINT32_MAX, 0, UINT32_MAX, 0};
        /* leaf_count counts values above the threshold; at threshold 0 a count of 0 means all zero */
        int dark = s->leaf_count[k] == 0 && s->desc.mask_threshold == 0.0f;
        for (uint32_t j = 0; j < nv && !dark; j++)
            for (uint32_t i = 0; i < nu; i++) {
                const float *p = s->radiance + ((k * nv + j) * (uint64_t)nu + i) * 3;
                if (p[0] != 0.0f || p[1] != 0.0f || p[2] != 0.0f) {
                    b[0] = i < b[0] ? i : b[0];
                    b[1] = i > b[1] ? i : b[1];
                    b[2] = j < b[2] ? j : b[2];
                    b[3] = j > b[3] ? j : b[3];
                }
            }
        if (b[0] == UINT32_MAX)
            b[0] = 1, b[1] = 0; /* empty */
        memcpy(box[k], b, sizeof b);
    }
    return LFIO_OK;
}

const float *lfio_slab_radiance(const lfio_slab *s)
{
    return s->radiance;
}

/* @return 1 if all count*3 values are finite and >= 0. */
static int valid_values(const float *v, uint64_t count)
{
    for (uint64_t k = 0; k < count * 3; k++)
        if (!(v[k] >= 0.0f) || !isfinite(v[k]))
            return 0;
    return 1;
}

/* Stores one sample and keeps the mask exact. Values are already valid. */
static void store(lfio_slab *s, uint64_t dir, uint64_t pos, const float rgb[3])
{
    float *p = s->radiance + (dir * s->npos + pos) * 3;
    int was = lfio__above(p, s->desc.mask_threshold);
    p[0] = rgb[0];
    p[1] = rgb[1];
    p[2] = rgb[2];
    lfio__mask_update(s, dir, was, lfio__above(p, s->desc.mask_threshold));
}

lfio_status lfio_slab_write(lfio_slab *s, uint64_t dir, uint32_t i, uint32_t j, const float rgb[3])
{
    if (dir >= s->ndir || i >= s->desc.nu || j >= s->desc.nv)
        return lfio__fail(LFIO_ERR_ARG, "slab '%s': sample (dir %llu, %u, %u) out of range",
                          s->desc.name, (unsigned long long)dir, i, j);
    if (!valid_values(rgb, 1))
        return lfio__fail(LFIO_ERR_ARG, "slab '%s': radiance must be finite and >= 0", s->desc.name);
    store(s, dir, (uint64_t)j * s->desc.nu + i, rgb);
    return LFIO_OK;
}

lfio_status lfio_slab_write_direction(lfio_slab *s, uint64_t dir, const float *img)
{
    if (dir >= s->ndir || !img)
        return lfio__fail(LFIO_ERR_ARG, "slab '%s': direction %llu out of range", s->desc.name,
                          (unsigned long long)dir);
    if (!valid_values(img, s->npos))
        return lfio__fail(LFIO_ERR_ARG, "slab '%s': direction %llu: radiance must be finite and >= 0",
                          s->desc.name, (unsigned long long)dir);
    for (uint64_t q = 0; q < s->npos; q++)
        store(s, dir, q, img + 3 * q);
    return LFIO_OK;
}

lfio_status lfio_slab_write_position(lfio_slab *s, uint32_t i, uint32_t j, const float *rgb)
{
    if (i >= s->desc.nu || j >= s->desc.nv || !rgb)
        return lfio__fail(LFIO_ERR_ARG, "slab '%s': position (%u, %u) out of range", s->desc.name, i, j);
    if (!valid_values(rgb, s->ndir))
        return lfio__fail(LFIO_ERR_ARG, "slab '%s': position (%u, %u): radiance must be finite and >= 0",
                          s->desc.name, i, j);
    uint64_t pos = (uint64_t)j * s->desc.nu + i;
    for (uint64_t d = 0; d < s->ndir; d++)
        store(s, d, pos, rgb + 3 * d);
    return LFIO_OK;
}

lfio_status lfio_slab_read_direction(const lfio_slab *s, uint64_t dir, float *img)
{
    if (dir >= s->ndir || !img)
        return lfio__fail(LFIO_ERR_ARG, "slab '%s': direction %llu out of range", s->desc.name,
                          (unsigned long long)dir);
    memcpy(img, s->radiance + dir * s->npos * 3, s->npos * 3 * sizeof(float));
    return LFIO_OK;
}

lfio_status lfio_slab_read_position(const lfio_slab *s, uint32_t i, uint32_t j, float *rgb)
{
    if (i >= s->desc.nu || j >= s->desc.nv || !rgb)
        return lfio__fail(LFIO_ERR_ARG, "slab '%s': position (%u, %u) out of range", s->desc.name, i, j);
    uint64_t pos = (uint64_t)j * s->desc.nu + i;
    for (uint64_t d = 0; d < s->ndir; d++)
        memcpy(rgb + 3 * d, s->radiance + (d * s->npos + pos) * 3, 3 * sizeof(float));
    return LFIO_OK;
}

lfio_status lfio_slab_position(const lfio_slab *s, uint32_t i, uint32_t j, double x[3])
{
    if (i >= s->desc.nu || j >= s->desc.nv)
        return lfio__fail(LFIO_ERR_ARG, "slab '%s': position (%u, %u) out of range", s->desc.name, i, j);
    double a = (i + 0.5) / s->desc.nu, b = (j + 0.5) / s->desc.nv;
    for (int k = 0; k < 3; k++)
        x[k] = s->desc.origin[k] + a * s->desc.u[k] + b * s->desc.v[k];
    return LFIO_OK;
}

void lfio_slab_to_local(const lfio_slab *s, const double world[3], double local[3])
{
    double l0 = a3_dot(world, s->e1), l1 = a3_dot(world, s->e2), l2 = a3_dot(world, s->e3);
    local[0] = l0;
    local[1] = l1;
    local[2] = l2;
}

void lfio_slab_to_world(const lfio_slab *s, const double local[3], double world[3])
{
    double w[3];
    for (int k = 0; k < 3; k++)
        w[k] = local[0] * s->e1[k] + local[1] * s->e2[k] + local[2] * s->e3[k];
    memcpy(world, w, sizeof w);
}

void lfio_slab_locate(const lfio_slab *s, const double x[3], double *st_s, double *st_t, double *dist)
{
    double r[3] = {x[0] - s->desc.origin[0], x[1] - s->desc.origin[1], x[2] - s->desc.origin[2]};
    if (st_s)
        *st_s = a3_dot(r, s->e1) / s->len_u;
    if (st_t)
        *st_t = a3_dot(r, s->e2) / s->len_v;
    if (dist)
        *dist = a3_dot(r, s->e3);
}

/* Bilinear footprint of (st_s, st_t) over position centres, clamped at the border. */
typedef struct footprint {
    uint64_t pos[4];
    double w[4];
} footprint;

/* The two columns and rows around (a, b) and the fractions between them. */
typedef struct corners {
    uint32_t i0, i1, j0, j1;
    double fu, fv;
} corners;

/* @return the position centres around (a, b), clamped at the border. */
static corners bilinear_corners(const lfio_slab *s, double a, double b)
{
    corners c;
    c.fu = lfio_grid_split(a * s->desc.nu - 0.5, s->desc.nu - 1.0, &c.i0);
    c.fv = lfio_grid_split(b * s->desc.nv - 0.5, s->desc.nv - 1.0, &c.j0);
    c.i1 = c.i0 + 1 < s->desc.nu ? c.i0 + 1 : c.i0, c.j1 = c.j0 + 1 < s->desc.nv ? c.j0 + 1 : c.j0;
    return c;
}

/* @return the bilinear footprint of (a, b) over the grid. */
static footprint bilinear(const lfio_slab *s, double a, double b)
{
    corners c = bilinear_corners(s, a, b);
    footprint f;
    f.pos[0] = (uint64_t)c.j0 * s->desc.nu + c.i0;
    f.pos[1] = (uint64_t)c.j0 * s->desc.nu + c.i1;
    f.pos[2] = (uint64_t)c.j1 * s->desc.nu + c.i0;
    f.pos[3] = (uint64_t)c.j1 * s->desc.nu + c.i1;
    f.w[0] = (1 - c.fu) * (1 - c.fv);
    f.w[1] = c.fu * (1 - c.fv);
    f.w[2] = (1 - c.fu) * c.fv;
    f.w[3] = c.fu * c.fv;
    return f;
}

/* @return the nearest position index to (a, b). */
static uint64_t nearest_position(const lfio_slab *s, double a, double b)
{
    double gu = floor(a * s->desc.nu), gv = floor(b * s->desc.nv);
    gu = fmin(fmax(gu, 0.0), (double)(s->desc.nu - 1));
    gv = fmin(fmax(gv, 0.0), (double)(s->desc.nv - 1));
    return (uint64_t)gv * s->desc.nu + (uint64_t)gu;
}

/* Checks a query's arguments and converts w to the slab frame.
 * @return LFIO_OK, or LFIO_ERR_ARG with a message. */
static lfio_status query_args(const lfio_slab *s, double a, double b, const double w[3], double local[3])
{
    if (!isfinite(a) || !isfinite(b) || !finite3(w) || (w[0] == 0 && w[1] == 0 && w[2] == 0))
        return lfio__fail(LFIO_ERR_ARG, "slab '%s': query needs finite (s, t) and a finite nonzero direction",
                          s->desc.name);
    lfio_slab_to_local(s, w, local);
    return LFIO_OK;
}

lfio_status lfio_slab_radiance_nearest(const lfio_slab *s, double st_s, double st_t, const double w[3],
                                       float rgb[3])
{
    double local[3];
    uint64_t id;
    if (query_args(s, st_s, st_t, w, local) != LFIO_OK)
        return LFIO_ERR_ARG;
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    if (local[2] < 0.0 || !lfio_part_id(s->desc.n, local, &id) || id >= s->ndir)
        return LFIO_OK;
    const float *p = s->radiance + (id * s->npos + nearest_position(s, st_s, st_t)) * 3;
    memcpy(rgb, p, 3 * sizeof(float));
    return LFIO_OK;
}

/* Mixes directions ids (weights wd) at footprint f; a direction beyond the
 * stored hemisphere has no data, so its share goes to ids[0]. Single
 * precision, four lanes per tap (the fourth reads the next value, or the
 * array's padding float, and is dropped): compilers turn each tap into one
 * vector multiply-add, and 16 taps of weights summing to 1 lose no more
 * than float radiance already has. */
static void mix_directions(const lfio_slab *s, footprint f, const uint64_t ids[4], const double wd[4], float rgb[3])
{
    float acc[4] = {0, 0, 0, 0}, fw[4];
    for (int q = 0; q < 4; q++)
        fw[q] = (float)f.w[q];
    for (int k = 0; k < 4; k++) {
        if (!(wd[k] > 0.0))
            continue;
        uint64_t id = ids[k] < s->ndir ? ids[k] : ids[0];
        const float *base = s->radiance + id * s->npos * 3;
        float w = (float)wd[k];
        for (int q = 0; q < 4; q++) {
            const float *p = base + f.pos[q] * 3;
            float wt = w * fw[q];
            for (int c = 0; c < 4; c++)
                acc[c] += wt * p[c];
        }
    }
    for (int c = 0; c < 3; c++)
        rgb[c] = acc[c];
}

lfio_status lfio_slab_radiance_interp(const lfio_slab *s, double st_s, double st_t, const double w[3],
                                      float rgb[3])
{
    double local[3], wd[4];
    uint64_t ids[4];
    if (query_args(s, st_s, st_t, w, local) != LFIO_OK)
        return LFIO_ERR_ARG;
    rgb[0] = rgb[1] = rgb[2] = 0.0f;
    if (local[2] < 0.0 || !lfio_part_interp(s->desc.n, local, ids, wd) || ids[0] >= s->ndir)
        return LFIO_OK;
    mix_directions(s, bilinear(s, st_s, st_t), ids, wd, rgb);
    return LFIO_OK;
}

lfio_status lfio_slab_radiance_mix(const lfio_slab *s, double st_s, double st_t, const uint64_t ids[4],
                                   const double w[4], float rgb[3])
{
    if (!isfinite(st_s) || !isfinite(st_t) || ids[0] >= s->ndir)
        return lfio__fail(LFIO_ERR_ARG, "slab '%s': mix needs finite (s, t) and a stored direction first",
                          s->desc.name);
    mix_directions(s, bilinear(s, st_s, st_t), ids, w, rgb);
    return LFIO_OK;
}

lfio_status lfio_slab_blend(const lfio_slab *s, const uint64_t ids[4], const double w[4], const uint32_t box[4],
                            float *rgb)
{
    if (ids[0] >= s->ndir || box[0] > box[1] || box[2] > box[3] || box[1] >= s->desc.nu || box[3] >= s->desc.nv)
        return lfio__fail(LFIO_ERR_ARG, "slab '%s': a blend needs a stored direction first and a box within the slab",
                          s->desc.name);
    uint32_t ni = box[1] - box[0] + 1;
    for (uint32_t j = box[2]; j <= box[3]; j++) {
        float *row = rgb + (size_t)(j - box[2]) * ni * 3;
        for (size_t c = 0; c < (size_t)ni * 3; c++)
            row[c] = 0.0f;
        for (int k = 0; k < 4; k++) {
            if (!(w[k] > 0.0))
                continue;
            uint64_t id = ids[k] < s->ndir ? ids[k] : ids[0]; /* as mix_directions() */
            const float *src = s->radiance + (id * s->npos + (uint64_t)j * s->desc.nu + box[0]) * 3;
            float wk = (float)w[k];
            for (size_t c = 0; c < (size_t)ni * 3; c++)
                row[c] += wk * src[c];
        }
    }
    return LFIO_OK;
}

void lfio_slab_blend_grid(const lfio_slab *s, const uint32_t box[4], lfio_blend_grid *g)
{
    g->hi[0] = s->desc.nu - 1.0;
    g->hi[1] = s->desc.nv - 1.0;
    /* from the centre of the zero position before the box to the one after it,
     * or without end past the slab's edge, whose position holds its value */
    g->rect[0] = box[0] == 0 ? -INFINITY : box[0] - 1.0;
    g->rect[1] = box[1] + 1 >= s->desc.nu ? INFINITY : box[1] + 1.0;
    g->rect[2] = box[2] == 0 ? -INFINITY : box[2] - 1.0;
    g->rect[3] = box[3] + 1 >= s->desc.nv ? INFINITY : box[3] + 1.0;
    memcpy(g->box, box, sizeof g->box);
    g->ni = box[1] - box[0] + 1;
    g->nj = box[3] - box[2] + 1;
}

void lfio_slab_blend_radiance(const lfio_slab *s, const uint32_t box[4], const float *rgb, double st_s,
                              double st_t, float out[3])
{
    lfio_blend_grid g;
    lfio_slab_blend_grid(s, box, &g);
    lfio_blend_at(&g, rgb, st_s * s->desc.nu - 0.5, st_t * s->desc.nv - 0.5, out);
}

lfio_status lfio_slab_irradiance(const lfio_slab *s, double st_s, double st_t, double rgb[3])
{
    if (!isfinite(st_s) || !isfinite(st_t))
        return lfio__fail(LFIO_ERR_ARG, "slab '%s': irradiance needs finite (s, t)", s->desc.name);
    footprint f = bilinear(s, st_s, st_t);
    double acc[3] = {0, 0, 0};
    for (uint64_t d = 0; d < s->ndir; d++) {
        if (s->leaf_count[d] == 0 && s->desc.mask_threshold == 0.0f)
            continue; /* all zero: the mask says so exactly */
        const float *base = s->radiance + d * s->npos * 3;
        double l[3] = {0, 0, 0};
        for (int q = 0; q < 4; q++)
            for (int c = 0; c < 3; c++)
                l[c] += f.w[q] * base[f.pos[q] * 3 + c];
        for (int c = 0; c < 3; c++)
            acc[c] += l[c] * s->proj_solid_angle[d];
    }
    memcpy(rgb, acc, sizeof acc);
    return LFIO_OK;
}
