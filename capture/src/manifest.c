/*
 * manifest.c - reading and validating capture manifests (capture/capture.h,
 * docs/capture.md): JSON through base's strict reader (ilf/json.h), every key checked, every value
 * range-checked, every image file checked to exist. A manifest names one plane at its top level, or
 * several under "planes", each read by the same code with its element path as a prefix and the top
 * level's settings as its defaults.
 *
 * Invariants: loading either returns a manifest meeting manifest.h's
 * invariants or fails with one message "FILE: ELEMENT: problem" and frees
 * everything; unknown and repeated keys are errors at every level; nothing
 * is allocated from a count in the file before the count is checked (the
 * planes by CAP_PLANES_MAX, every grid by CAP__MAX_POSITIONS over all planes
 * and lfio's slab size limit first).
 */
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "internal.h"
#include "manifest.h"
#include "ilf/limits.h"

#define PATH_MAX_BYTES ILF_PATH_MAX_BYTES
#define DEFAULT_N 16u
#define DEFAULT_SLAB "capture"

/* What is being parsed: the file, its folder (for relative paths), the manifest being built,
 * the plane being read and the settings given above its positions, which they inherit. */
typedef struct parser {
    const char *path;
    char dir[PATH_MAX_BYTES + 1];
    cap_manifest *m;
    cap__plane *pl;
    cap__entry shared;
    uint64_t positions; /* over the planes read so far */
} parser;

/* Writes the name of member key of the plane being read ("key", or "planes[k].key") into out. @return out. */
static const char *at(const parser *p, const char *key, char out[ILF_JSON_ELEM_MAX])
{
    ilf_json_member_name(out, p->pl->element, key);
    return out;
}

static const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};

/* ------------------------------------------------------------ settings */

static cap_status get_projection(const parser *p, const ilf_json *j, const char *elem, cap_projection *out)
{
    const char *name = "";
    cap_status st = cap__json_string(p->path, j, elem, &name);
    if (st == CAP_OK && !cap_projection_parse(name, out))
        return cap__json_bad(p->path, elem,
                             "unknown projection '%s' (expected equirectangular, mirror_ball or angular_map)", name);
    return st;
}

static cap_status get_colour_space(const parser *p, const ilf_json *j, const char *elem, cap_colour_space *out)
{
    static const cap_colour_space all[] = {CAP_COLOUR_AUTO, CAP_COLOUR_LINEAR, CAP_COLOUR_SRGB};
    const char *name = "";
    cap_status st = cap__json_string(p->path, j, elem, &name);
    if (st != CAP_OK)
        return st;
    for (size_t k = 0; k < sizeof all / sizeof all[0]; k++)
        if (strcmp(name, cap_colour_space_name(all[k])) == 0) {
            *out = all[k];
            return CAP_OK;
        }
    return cap__json_bad(p->path, elem, "unknown colour space '%s' (expected auto, linear or srgb)", name);
}

/* R from {"forward": f, "up": u}: columns forward, up x forward, up (orthogonalised). */
static cap_status get_forward_up(const parser *p, const ilf_json *j, const char *elem, double R[9])
{
    static const char *const keys[] = {"forward", "up", NULL};
    const ilf_json *fj, *uj;
    double f[3], u[3], l[3];
    char fe[ILF_JSON_ELEM_MAX], ue[ILF_JSON_ELEM_MAX];
    ilf_json_member_name(fe, elem, "forward");
    ilf_json_member_name(ue, elem, "up");
    cap_status st = cap__json_keys(p->path, j, elem, keys);
    if (st == CAP_OK)
        st = cap__json_member(p->path, j, elem, "forward", 1, &fj);
    if (st == CAP_OK)
        st = cap__json_member(p->path, j, elem, "up", 1, &uj);
    if (st == CAP_OK)
        st = cap__json_vector3(p->path, fj, fe, f);
    if (st == CAP_OK)
        st = cap__json_vector3(p->path, uj, ue, u);
    if (st != CAP_OK)
        return st;
    if (!cap__normalise(f))
        return cap__json_bad(p->path, fe, "must not be zero");
    double along = a3_dot(u, f);
    for (int a = 0; a < 3; a++)
        u[a] -= along * f[a];
    if (!(a3_len(u) > 1e-9 * (1.0 + fabs(along))) || !cap__normalise(u))
        return cap__json_bad(p->path, elem, "up must not be zero or parallel to forward");
    a3_cross(u, f, l);
    for (int r = 0; r < 3; r++) {
        R[3 * r + 0] = f[r];
        R[3 * r + 1] = l[r];
        R[3 * r + 2] = u[r];
    }
    return CAP_OK;
}

/* An orientation: 3 rows of 3 numbers forming a rotation, or {"forward", "up"}. */
static cap_status get_orientation(const parser *p, const ilf_json *j, const char *elem, double R[9])
{
    if (ilf_json_type_of(j) == ILF_JSON_OBJECT)
        return get_forward_up(p, j, elem, R);
    if (ilf_json_type_of(j) != ILF_JSON_ARRAY || (int)ilf_json_count(j) != 3)
        return cap__json_bad(p->path, elem, "expected 3 rows of 3 numbers or {\"forward\": ..., \"up\": ...}, got %s",
                   ilf_json_kind(j));
    char e[ILF_JSON_ELEM_MAX];
    for (int r = 0; r < 3; r++) {
        ilf_json_item_name(e, elem, (size_t)r);
        cap_status st = cap__json_vector3(p->path, ilf_json_at(j, (size_t)(r)), e, &R[3 * r]);
        if (st != CAP_OK)
            return st;
    }
    if (!cap_rotation_check(R))
        return cap__json_bad(p->path, elem, "not a rotation (rows must be orthonormal within 1e-6, determinant +1)");
    return CAP_OK;
}

/* Reads the optional settings keys of obj into e (projection, orientation, colour_space, scale). */
static cap_status get_settings(const parser *p, const ilf_json *obj, const char *elem, cap__entry *e)
{
    char sub[4][ILF_JSON_ELEM_MAX];
    const ilf_json *j[4];
    static const char *const keys[4] = {"projection", "orientation", "colour_space", "scale"};
    for (int k = 0; k < 4; k++) {
        ilf_json_member_name(sub[k], elem, keys[k]);
        j[k] = ilf_json_get(obj, keys[k]);
    }
    cap_status st = CAP_OK;
    if (j[0] != NULL)
        st = get_projection(p, j[0], sub[0], &e->projection);
    if (st == CAP_OK && j[1] != NULL)
        st = get_orientation(p, j[1], sub[1], e->R);
    if (st == CAP_OK && j[2] != NULL)
        st = get_colour_space(p, j[2], sub[2], &e->colour);
    if (st == CAP_OK && j[3] != NULL)
        st = cap__json_positive(p->path, j[3], sub[3], &e->scale);
    return st;
}

/* ------------------------------------------------------------ files */

/* Resolves file against the manifest's folder into out and checks it is an existing regular file. */
static cap_status resolve_file(const parser *p, const char *elem, const char *file, char out[PATH_MAX_BYTES + 1])
{
    if (file[0] == '\0')
        return cap__json_bad(p->path, elem, "empty file name");
    int len = snprintf(out, PATH_MAX_BYTES + 1, "%s%s", file[0] == '/' ? "" : p->dir, file);
    if (len < 0 || len > PATH_MAX_BYTES)
        return cap__json_bad(p->path, elem, "'%s': path longer than %d bytes", file, PATH_MAX_BYTES);
    struct stat st;
    if (stat(out, &st) != 0)
        return cap__json_bad(p->path, elem, "'%s': %s", out, strerror(errno));
    if (S_ISDIR(st.st_mode))
        return cap__json_bad(p->path, elem, "'%s': is a folder, not an image", out);
    if (!S_ISREG(st.st_mode))
        return cap__json_bad(p->path, elem, "'%s': not a regular file", out);
    return CAP_OK;
}

/* Gives entry e room for count images. */
static cap_status entry_reserve(cap__entry *e, uint32_t count)
{
    e->files = calloc(count, sizeof *e->files);
    e->exposures = calloc(count, sizeof *e->exposures);
    if (e->files == NULL || e->exposures == NULL)
        return cap__fail(CAP_ERR_NOMEM, "out of memory for the manifest");
    e->count = count;
    return CAP_OK;
}

/* Stores image k of entry e: the file resolved and checked, and its exposure. */
static cap_status entry_set_image(const parser *p, cap__entry *e, uint32_t k, const char *elem, const char *file,
                                  double exposure)
{
    char path[PATH_MAX_BYTES + 1];
    cap_status st = resolve_file(p, elem, file, path);
    if (st != CAP_OK)
        return st;
    e->files[k] = malloc(strlen(path) + 1);
    if (e->files[k] == NULL)
        return cap__fail(CAP_ERR_NOMEM, "out of memory for the manifest");
    strcpy(e->files[k], path);
    e->exposures[k] = exposure;
    return CAP_OK;
}

static void entry_free(cap__entry *e)
{
    for (uint32_t k = 0; e->files != NULL && k < e->count; k++)
        free(e->files[k]);
    free(e->files);
    free(e->exposures);
}

/* ------------------------------------------------------------ positions */

/* One bracket image {"file", "exposure"}. */
static cap_status read_bracket_item(const parser *p, const ilf_json *j, const char *elem, cap__entry *e, uint32_t k)
{
    static const char *const keys[] = {"file", "exposure", NULL};
    const ilf_json *fj, *xj;
    const char *file;
    double exposure = 0.0;
    char fe[ILF_JSON_ELEM_MAX], xe[ILF_JSON_ELEM_MAX];
    ilf_json_member_name(fe, elem, "file");
    ilf_json_member_name(xe, elem, "exposure");
    cap_status st = cap__json_keys(p->path, j, elem, keys);
    if (st == CAP_OK)
        st = cap__json_member(p->path, j, elem, "file", 1, &fj);
    if (st == CAP_OK)
        st = cap__json_member(p->path, j, elem, "exposure", 1, &xj);
    if (st == CAP_OK)
        st = cap__json_string(p->path, fj, fe, &file);
    if (st == CAP_OK)
        st = cap__json_positive(p->path, xj, xe, &exposure);
    if (st == CAP_OK)
        st = entry_set_image(p, e, k, fe, file, exposure);
    return st;
}

static cap_status read_bracket(const parser *p, const ilf_json *j, const char *elem, cap__entry *e)
{
    if (ilf_json_type_of(j) != ILF_JSON_ARRAY)
        return cap__json_bad(p->path, elem, "expected an array of {\"file\", \"exposure\"}, got %s", ilf_json_kind(j));
    int count = (int)ilf_json_count(j);
    if (count < 1 || count > (int)CAP_BRACKET_MAX)
        return cap__json_bad(p->path, elem, "%d images; a bracket holds 1 to %u", count, CAP_BRACKET_MAX);
    cap_status st = entry_reserve(e, (uint32_t)count);
    e->bracket = 1;
    char sub[ILF_JSON_ELEM_MAX];
    for (int k = 0; st == CAP_OK && k < count; k++) {
        ilf_json_item_name(sub, elem, (size_t)k);
        st = read_bracket_item(p, ilf_json_at(j, (size_t)(k)), sub, e, (uint32_t)k);
    }
    return st;
}

/* "image" with an optional "exposure", or "bracket": exactly one of the two. */
static cap_status read_images(const parser *p, const ilf_json *j, const char *elem, cap__entry *e)
{
    const ilf_json *ij = ilf_json_get(j, "image");
    const ilf_json *bj = ilf_json_get(j, "bracket");
    const ilf_json *xj = ilf_json_get(j, "exposure");
    char ie[ILF_JSON_ELEM_MAX], be[ILF_JSON_ELEM_MAX], xe[ILF_JSON_ELEM_MAX];
    ilf_json_member_name(ie, elem, "image");
    ilf_json_member_name(be, elem, "bracket");
    ilf_json_member_name(xe, elem, "exposure");
    if ((ij == NULL) == (bj == NULL))
        return cap__json_bad(p->path, elem, "give exactly one of 'image' and 'bracket'");
    if (bj != NULL && xj != NULL)
        return cap__json_bad(p->path, elem, "'exposure' goes inside each bracket item, not beside 'bracket'");
    if (bj != NULL)
        return read_bracket(p, bj, be, e);
    const char *file;
    double exposure = 1.0;
    cap_status st = xj != NULL ? cap__json_positive(p->path, xj, xe, &exposure) : CAP_OK;
    if (st == CAP_OK)
        st = cap__json_string(p->path, ij, ie, &file);
    if (st == CAP_OK)
        st = entry_reserve(e, 1);
    if (st == CAP_OK)
        st = entry_set_image(p, e, 0, ie, file, exposure);
    return st;
}

/* Claims the entry of position (i, j) for element elem. */
static cap_status claim_entry(const parser *p, const char *elem, uint32_t i, uint32_t j, cap__entry **out)
{
    const lfio_slab_desc *d = &p->pl->desc;
    cap__entry *e = &p->pl->entries[(size_t)j * d->nu + i];
    if (e->given)
        return cap__json_bad(p->path, elem, "position (%u, %u) is already given by %s", i, j, e->element);
    *e = p->shared;
    e->given = 1;
    e->files = NULL;
    e->exposures = NULL;
    e->count = 0;
    snprintf(e->element, sizeof e->element, "%.*s", (int)sizeof e->element - 1, elem);
    *out = e;
    return CAP_OK;
}

static cap_status read_position(const parser *p, const ilf_json *j, const char *elem)
{
    static const char *const keys[] = {"i", "j", "image", "exposure", "bracket", "projection",
                                       "orientation", "colour_space", "scale", NULL};
    const lfio_slab_desc *d = &p->pl->desc;
    const ilf_json *ij, *jj;
    uint32_t i = 0, jv = 0;
    char ie[ILF_JSON_ELEM_MAX], je[ILF_JSON_ELEM_MAX];
    ilf_json_member_name(ie, elem, "i");
    ilf_json_member_name(je, elem, "j");
    cap__entry *e = NULL;
    cap_status st = cap__json_keys(p->path, j, elem, keys);
    if (st == CAP_OK)
        st = cap__json_member(p->path, j, elem, "i", 1, &ij);
    if (st == CAP_OK)
        st = cap__json_member(p->path, j, elem, "j", 1, &jj);
    if (st == CAP_OK)
        st = cap__json_uint(p->path, ij, ie, 0, d->nu - 1, &i);
    if (st == CAP_OK)
        st = cap__json_uint(p->path, jj, je, 0, d->nv - 1, &jv);
    if (st == CAP_OK)
        st = claim_entry(p, elem, i, jv, &e);
    if (st == CAP_OK)
        st = get_settings(p, j, elem, e);
    if (st == CAP_OK)
        st = read_images(p, j, elem, e);
    return st;
}

static cap_status read_positions(const parser *p, const ilf_json *j)
{
    char base[ILF_JSON_ELEM_MAX];
    if (ilf_json_type_of(j) != ILF_JSON_ARRAY)
        return cap__json_bad(p->path, at(p, "positions", base), "expected an array, got %s", ilf_json_kind(j));
    at(p, "positions", base);
    char elem[ILF_JSON_ELEM_MAX];
    size_t k = 0;
    for (const ilf_json *c = ilf_json_first(j); c != NULL; c = ilf_json_next(c), k++) {
        ilf_json_item_name(elem, base, k);
        cap_status st = read_position(p, c, elem);
        if (st != CAP_OK)
            return st;
    }
    return CAP_OK;
}

/* Expands the pattern's {i} and {j} for position (i, j), and {k} for bracket image k when brackets is
 * nonzero, into out. */
static cap_status expand_pattern(const parser *p, const char *pattern, uint32_t i, uint32_t j, uint32_t k,
                                 int brackets, char out[PATH_MAX_BYTES + 1])
{
    size_t len = 0;
    char elem[ILF_JSON_ELEM_MAX];
    at(p, "pattern", elem);
    for (const char *c = pattern; *c != '\0';) {
        char piece[16];
        if (strncmp(c, "{i}", 3) == 0 || strncmp(c, "{j}", 3) == 0 || (brackets && strncmp(c, "{k}", 3) == 0)) {
            snprintf(piece, sizeof piece, "%u", c[1] == 'i' ? i : c[1] == 'j' ? j : k);
            c += 3;
        } else if (*c == '{' || *c == '}') {
            return cap__json_bad(p->path, elem, "unknown placeholder near '%.8s' (%s)", c,
                                 brackets ? "only {i}, {j} and {k} are replaced"
                                          : "only {i} and {j} are replaced; {k} needs 'exposures'");
        } else {
            piece[0] = *c++;
            piece[1] = '\0';
        }
        size_t add = strlen(piece);
        if (len + add > PATH_MAX_BYTES)
            return cap__json_bad(p->path, elem, "expands to more than %d bytes", PATH_MAX_BYTES);
        memcpy(out + len, piece, add);
        len += add;
    }
    out[len] = '\0';
    return CAP_OK;
}

/* "exposures": 1 .. CAP_BRACKET_MAX numbers > 0 into ex. @return CAP_OK and *count. */
static cap_status read_exposures(const parser *p, const ilf_json *j, double ex[CAP_BRACKET_MAX], uint32_t *count)
{
    int n = (ilf_json_type_of(j) == ILF_JSON_ARRAY) ? (int)ilf_json_count(j) : -1;
    char base[ILF_JSON_ELEM_MAX];
    at(p, "exposures", base);
    if (n < 1 || n > (int)CAP_BRACKET_MAX)
        return n < 0 ? cap__json_bad(p->path, base, "expected an array of numbers, got %s", ilf_json_kind(j))
                     : cap__json_bad(p->path, base, "%d exposures; a bracket holds 1 to %u", n, CAP_BRACKET_MAX);
    char elem[ILF_JSON_ELEM_MAX];
    cap_status st = CAP_OK;
    for (int k = 0; st == CAP_OK && k < n; k++) {
        ilf_json_item_name(elem, base, (size_t)k);
        st = cap__json_positive(p->path, ilf_json_at(j, (size_t)(k)), elem, &ex[k]);
    }
    *count = (uint32_t)n;
    return st;
}

/* "pattern", one image per position, or with "exposures" (jx, else NULL) a bracket per position: image k of the
 * bracket is the pattern with {k} replaced by k, at exposure k. */
static cap_status read_pattern(const parser *p, const ilf_json *j, const ilf_json *jx)
{
    const lfio_slab_desc *d = &p->pl->desc;
    const char *pattern;
    double exposures[CAP_BRACKET_MAX] = {1.0};
    uint32_t count = 1;
    char elem[ILF_JSON_ELEM_MAX];
    at(p, "pattern", elem);
    cap_status st = cap__json_string(p->path, j, elem, &pattern);
    if (st == CAP_OK && jx != NULL)
        st = read_exposures(p, jx, exposures, &count);
    if (st != CAP_OK)
        return st;
    if (jx != NULL && strstr(pattern, "{k}") == NULL)
        return cap__json_bad(p->path, elem, "must contain {k}: 'exposures' gives a bracket of %u images", count);
    if (d->nu > 1 && strstr(pattern, "{i}") == NULL)
        return cap__json_bad(p->path, elem, "must contain {i}: the grid has %u positions along u", d->nu);
    if (d->nv > 1 && strstr(pattern, "{j}") == NULL)
        return cap__json_bad(p->path, elem, "must contain {j}: the grid has %u positions along v", d->nv);
    char file[PATH_MAX_BYTES + 1];
    for (uint32_t jj = 0; st == CAP_OK && jj < d->nv; jj++)
        for (uint32_t i = 0; st == CAP_OK && i < d->nu; i++) {
            cap__entry *e = NULL;
            st = claim_entry(p, elem, i, jj, &e);
            if (st == CAP_OK)
                st = entry_reserve(e, count);
            if (st == CAP_OK)
                e->bracket = jx != NULL;
            for (uint32_t k = 0; st == CAP_OK && k < count; k++) {
                st = expand_pattern(p, pattern, i, jj, k, jx != NULL, file);
                if (st == CAP_OK)
                    st = entry_set_image(p, e, k, elem, file, exposures[k]);
            }
        }
    return st;
}

/* ------------------------------------------------------------ the slab */

static cap_status read_units(const parser *p, const ilf_json *j, const char *elem, lfio_slab_desc *d)
{
    const char *name;
    cap_status st = cap__json_string(p->path, j, elem, &name);
    if (st != CAP_OK)
        return st;
    if (strcmp(name, "radiance") == 0)
        d->units = LFIO_UNITS_RADIANCE;
    else if (strcmp(name, "relative") == 0)
        d->units = LFIO_UNITS_RELATIVE;
    else
        return cap__json_bad(p->path, elem, "unknown units '%s' (expected radiance or relative)", name);
    return CAP_OK;
}

/* "mask_threshold": a finite number >= 0 that a float holds (lfio's mask threshold). */
static cap_status read_mask_threshold(const parser *p, const ilf_json *j, const char *elem, lfio_slab_desc *d)
{
    ilf_json_ctx c = {.file = p->path};
    double v = 0.0;
    ilf_json_status js = ilf_json_number(&c, j, elem, &v);
    if (js != ILF_JSON_OK)
        return cap__fail_text(CAP_ERR_INPUT, c.message);
    /* a float must hold it: FLT_MAX rounds to itself, anything larger would become infinity */
    if (!(v >= 0.0 && v <= FLT_MAX))
        return cap__json_bad(p->path, elem, "must be >= 0 and at most %g, got %g", (double)FLT_MAX, v);
    d->mask_threshold = (float)v;
    return CAP_OK;
}

/* The keys a plane may give beside its positions to override what it inherits: n, units, mask_threshold. */
static cap_status read_slab_settings(const parser *p, const ilf_json *obj, lfio_slab_desc *d)
{
    const ilf_json *j;
    char elem[ILF_JSON_ELEM_MAX];
    cap_status st = CAP_OK;
    if ((j = ilf_json_get(obj, "n")) != NULL)
        st = cap__json_uint(p->path, j, at(p, "n", elem), 1, LFIO_SLAB_MAX_N, &d->n);
    if (st == CAP_OK && (j = ilf_json_get(obj, "units")) != NULL)
        st = read_units(p, j, at(p, "units", elem), d);
    if (st == CAP_OK && (j = ilf_json_get(obj, "mask_threshold")) != NULL)
        st = read_mask_threshold(p, j, at(p, "mask_threshold", elem), d);
    return st;
}

/* The plane's slab: plane, grid, name and settings over the inherited ones in d, within the limits. */
static cap_status read_slab(parser *p, const ilf_json *obj, lfio_slab_desc *d)
{
    static const char *const plane_keys[] = {"origin", "u", "v", NULL};
    const ilf_json *j;
    const char *here = p->pl->element;
    char elem[ILF_JSON_ELEM_MAX];
    cap_status st = cap__json_member(p->path, obj, here, "plane", 1, &j);
    if (st == CAP_OK)
        st = cap__json_keys(p->path, j, at(p, "plane", elem), plane_keys);
    if (st == CAP_OK)
        st = cap__json_rectangle(p->path, j, elem, d);
    if (st == CAP_OK)
        st = cap__json_member(p->path, obj, here, "grid", 1, &j);
    if (st == CAP_OK)
        st = cap__json_grid(p->path, j, at(p, "grid", elem), d);
    if (st == CAP_OK && (uint64_t)d->nu * d->nv > CAP__MAX_POSITIONS - p->positions)
        return cap__json_bad(p->path, elem, "%u x %u positions; at most %llu are supported%s", d->nu, d->nv,
                             (unsigned long long)CAP__MAX_POSITIONS, p->positions > 0 ? " over all planes" : "");
    if (st == CAP_OK && (j = ilf_json_get(obj, "slab")) != NULL)
        st = cap__json_slab_name(p->path, j, at(p, "slab", elem), d->name);
    if (st == CAP_OK)
        st = read_slab_settings(p, obj, d);
    if (st != CAP_OK)
        return st;
    uint64_t bytes = lfio_slab_desc_bytes(d);
    if (bytes > LFIO_SLAB_MAX_BYTES)
        return cap__json_bad(p->path, here, "the slab would hold %.3g bytes of radiance, over lfio's limit of %.3g",
                             (double)bytes, (double)LFIO_SLAB_MAX_BYTES);
    p->positions += (uint64_t)d->nu * d->nv;
    return CAP_OK;
}

/* ------------------------------------------------------------ planes and the file */

/* Keys of a plane: of a one-plane manifest's top level, or of an item of "planes". */
static const char *const plane_keys[] = {"plane", "grid", "n", "slab", "units", "mask_threshold", "projection",
                                         "orientation", "colour_space", "scale", "pattern", "exposures",
                                         "positions", NULL};

/* Reads plane p->pl from obj: its slab over the inherited description *base, its settings over the
 * inherited *shared, and every position. */
static cap_status read_plane(parser *p, const ilf_json *obj, const lfio_slab_desc *base, const cap__entry *shared)
{
    cap__plane *pl = p->pl;
    const char *here = pl->element;
    char elem[ILF_JSON_ELEM_MAX];
    pl->desc = *base;
    cap_status st = cap__json_keys(p->path, obj, here, plane_keys);
    if (st == CAP_OK)
        st = read_slab(p, obj, &pl->desc);
    p->shared = *shared;
    if (st == CAP_OK)
        st = get_settings(p, obj, here, &p->shared);
    if (st != CAP_OK)
        return st;
    const ilf_json *pattern = ilf_json_get(obj, "pattern");
    const ilf_json *positions = ilf_json_get(obj, "positions");
    const ilf_json *exposures = ilf_json_get(obj, "exposures");
    if ((pattern == NULL) == (positions == NULL))
        return cap__json_bad(p->path, here, "give exactly one of 'pattern' and 'positions'");
    if (exposures != NULL && pattern == NULL)
        return cap__json_bad(p->path, at(p, "exposures", elem),
                             "goes with 'pattern'; a position's bracket lists its own exposures");
    size_t count = (size_t)pl->desc.nu * pl->desc.nv;
    pl->entries = calloc(count, sizeof *pl->entries);
    if (pl->entries == NULL)
        return cap__fail(CAP_ERR_NOMEM, "%s: out of memory for %zu positions", p->path, count);
    st = pattern != NULL ? read_pattern(p, pattern, exposures) : read_positions(p, positions);
    for (size_t k = 0; st == CAP_OK && k < count; k++) {
        if (!pl->entries[k].given)
            return cap__json_bad(p->path, at(p, "positions", elem), "no image for position (%zu, %zu)",
                                 k % pl->desc.nu, k / pl->desc.nu);
        pl->images += pl->entries[k].count;
    }
    p->m->images += pl->images;
    return st;
}

/* The defaults every plane starts from: slab "capture", n 16, radiance, threshold 0; identity, auto, 1. */
static void defaults(lfio_slab_desc *d, cap__entry *e)
{
    lfio_slab_desc_init(d);
    snprintf(d->name, sizeof d->name, "%s", DEFAULT_SLAB);
    d->n = DEFAULT_N;
    memset(e, 0, sizeof *e);
    e->projection = CAP_PROJECTION_EQUIRECTANGULAR;
    memcpy(e->R, identity, sizeof identity);
    e->colour = CAP_COLOUR_AUTO;
    e->scale = 1.0;
}

/* Allocates m's count planes. */
static cap_status alloc_planes(const parser *p, size_t count)
{
    p->m->planes = calloc(count, sizeof *p->m->planes);
    if (p->m->planes == NULL)
        return cap__fail(CAP_ERR_NOMEM, "%s: out of memory", p->path);
    p->m->nplanes = count;
    return CAP_OK;
}

/* {"planes": [...], shared keys}: each item a plane as a one-plane manifest's top level, inheriting
 * n, units, mask_threshold and the image settings from the top level; slab names default to capture<k>. */
static cap_status read_planes(parser *p, const ilf_json *root, const ilf_json *list)
{
    static const char *const keys[] = {"planes", "n", "units", "mask_threshold", "projection", "orientation",
                                       "colour_space", "scale", NULL};
    lfio_slab_desc base;
    cap__entry shared;
    defaults(&base, &shared);
    cap__plane top = {.element = ""};
    p->pl = &top;
    cap_status st = cap__json_keys(p->path, root, "", keys);
    if (st == CAP_OK)
        st = read_slab_settings(p, root, &base);
    if (st == CAP_OK)
        st = get_settings(p, root, "", &shared);
    if (st != CAP_OK)
        return st;
    int count = ilf_json_type_of(list) == ILF_JSON_ARRAY ? (int)ilf_json_count(list) : -1;
    if (count < 1 || count > (int)CAP_PLANES_MAX)
        return count < 0 ? cap__json_bad(p->path, "planes", "expected an array of planes, got %s", ilf_json_kind(list))
                         : cap__json_bad(p->path, "planes", "%d planes; a manifest names 1 to %u", count,
                                         CAP_PLANES_MAX);
    st = alloc_planes(p, (size_t)count);
    for (size_t k = 0; st == CAP_OK && k < (size_t)count; k++) {
        p->pl = &p->m->planes[k];
        snprintf(p->pl->element, sizeof p->pl->element, "planes[%zu]", k);
        snprintf(base.name, sizeof base.name, "%s%zu", DEFAULT_SLAB, k);
        st = read_plane(p, ilf_json_at(list, k), &base, &shared);
        for (size_t q = 0; st == CAP_OK && q < k; q++)
            if (strcmp(p->m->planes[q].desc.name, p->pl->desc.name) == 0)
                st = cap__json_bad(p->path, p->pl->element, "slab name '%s' is already that of %s",
                                   p->pl->desc.name, p->m->planes[q].element);
    }
    return st;
}

static cap_status read_root(parser *p, const ilf_json *root)
{
    if (ilf_json_type_of(root) == ILF_JSON_OBJECT) {
        const ilf_json *list = ilf_json_get(root, "planes");
        if (list != NULL)
            return read_planes(p, root, list);
    }
    lfio_slab_desc base;
    cap__entry shared;
    defaults(&base, &shared);
    cap_status st = alloc_planes(p, 1);
    p->pl = &p->m->planes[0];
    return st == CAP_OK ? read_plane(p, root, &base, &shared) : st;
}

/* Sets p->dir to path's folder with a trailing '/', or "" for a bare file name. */
static cap_status set_folder(parser *p, const char *path)
{
    const char *slash = strrchr(path, '/');
    size_t len = slash != NULL ? (size_t)(slash - path) + 1 : 0;
    if (len > PATH_MAX_BYTES)
        return cap__fail(CAP_ERR_INPUT, "%s: path too long", path);
    memcpy(p->dir, path, len);
    p->dir[len] = '\0';
    return CAP_OK;
}

cap_status cap_manifest_load(const char *path, cap_manifest **out)
{
    if (out != NULL)
        *out = NULL;
    if (path == NULL || out == NULL)
        return cap__fail(CAP_ERR_ARG, "cap_manifest_load: path or out is NULL");
    parser p;
    memset(&p, 0, sizeof p);
    p.path = path;
    ilf_json *root = NULL;
    cap_status st = set_folder(&p, path);
    if (st == CAP_OK)
        st = cap__json_load(path, CAP_MANIFEST_MAX_BYTES, &root);
    if (st == CAP_OK && (p.m = calloc(1, sizeof *p.m)) == NULL)
        st = cap__fail(CAP_ERR_NOMEM, "%s: out of memory", path);
    if (st == CAP_OK && (p.m->path = malloc(strlen(path) + 1)) == NULL)
        st = cap__fail(CAP_ERR_NOMEM, "%s: out of memory", path);
    if (st == CAP_OK) {
        strcpy(p.m->path, path);
        st = read_root(&p, root);
    }
    ilf_json_free(root);
    if (st != CAP_OK) {
        cap_manifest_destroy(p.m);
        return st;
    }
    *out = p.m;
    return CAP_OK;
}

void cap_manifest_destroy(cap_manifest *m)
{
    if (m == NULL)
        return;
    for (size_t q = 0; m->planes != NULL && q < m->nplanes; q++) {
        cap__plane *pl = &m->planes[q];
        size_t count = (size_t)pl->desc.nu * pl->desc.nv;
        for (size_t k = 0; pl->entries != NULL && k < count; k++)
            entry_free(&pl->entries[k]);
        free(pl->entries);
    }
    free(m->planes);
    free(m->path);
    free(m);
}

size_t cap_manifest_plane_count(const cap_manifest *m)
{
    return m != NULL ? m->nplanes : 0;
}

const lfio_slab_desc *cap_manifest_get_desc(const cap_manifest *m, size_t plane)
{
    return m != NULL && plane < m->nplanes ? &m->planes[plane].desc : NULL;
}

uint64_t cap_manifest_image_count(const cap_manifest *m)
{
    return m != NULL ? m->images : 0;
}

cap_status cap_manifest_get_position(const cap_manifest *m, size_t plane, uint32_t i, uint32_t j,
                                     cap_position_info *out)
{
    const cap__plane *pl = m != NULL && plane < m->nplanes ? &m->planes[plane] : NULL;
    if (pl == NULL || out == NULL || i >= pl->desc.nu || j >= pl->desc.nv)
        return cap__fail(CAP_ERR_ARG, "cap_manifest_get_position: no position (%u, %u) on plane %zu", i, j, plane);
    const cap__entry *e = &pl->entries[(size_t)j * pl->desc.nu + i];
    out->i = i;
    out->j = j;
    out->element = e->element;
    out->projection = e->projection;
    memcpy(out->orientation, e->R, sizeof out->orientation);
    out->colour_space = e->colour;
    out->scale = e->scale;
    out->image_count = e->count;
    out->bracket = e->bracket;
    out->files = (const char *const *)e->files;
    out->exposures = e->exposures;
    return CAP_OK;
}

const char *cap_colour_space_name(cap_colour_space c)
{
    switch (c) {
    case CAP_COLOUR_AUTO:
        return "auto";
    case CAP_COLOUR_LINEAR:
        return "linear";
    case CAP_COLOUR_SRGB:
        return "srgb";
    }
    return "";
}

/* ------------------------------------------------------------ JSON values (manifest.h) */

/* Moves the reader's message into capture's error state. @return CAP_OK, CAP_ERR_INPUT or CAP_ERR_NOMEM. */
static cap_status json_result(const ilf_json_ctx *c, ilf_json_status st)
{
    if (st == ILF_JSON_OK)
        return CAP_OK;
    return cap__fail_text(st == ILF_JSON_ERR_NOMEM ? CAP_ERR_NOMEM : CAP_ERR_INPUT, c->message);
}

cap_status cap__json_bad(const char *path, const char *elem, const char *fmt, ...)
{
    char text[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    ilf_json_ctx c = {.file = path};
    return json_result(&c, ilf_json_fail(&c, elem, "%s", text));
}

cap_status cap__json_load(const char *path, size_t max_bytes, ilf_json **root)
{
    ilf_json_ctx c = {.file = path};
    return json_result(&c, ilf_json_load(&c, max_bytes, root));
}

cap_status cap__json_keys(const char *path, const ilf_json *j, const char *elem, const char *const *allowed)
{
    ilf_json_ctx c = {.file = path};
    return json_result(&c, ilf_json_keys(&c, j, elem, allowed));
}

cap_status cap__json_member(const char *path, const ilf_json *obj, const char *elem, const char *key, int required,
                            const ilf_json **out)
{
    ilf_json_ctx c = {.file = path};
    return json_result(&c, ilf_json_member(&c, obj, elem, key, required, out));
}

cap_status cap__json_positive(const char *path, const ilf_json *j, const char *elem, double *out)
{
    ilf_json_ctx c = {.file = path};
    double v = 0.0;
    ilf_json_status st = ilf_json_number(&c, j, elem, &v);
    if (st == ILF_JSON_OK && !(v > 0.0))
        st = ilf_json_fail(&c, elem, "must be > 0, got %g", v);
    if (st == ILF_JSON_OK)
        *out = v;
    return json_result(&c, st);
}

cap_status cap__json_vector3(const char *path, const ilf_json *j, const char *elem, double out[3])
{
    ilf_json_ctx c = {.file = path};
    return json_result(&c, ilf_json_vector(&c, j, elem, 3, out));
}

cap_status cap__json_uint(const char *path, const ilf_json *j, const char *elem, uint32_t lo, uint32_t hi,
                          uint32_t *out)
{
    ilf_json_ctx c = {.file = path};
    uint64_t v = 0;
    ilf_json_status st = ilf_json_integer(&c, j, elem, lo, hi, 0, &v);
    if (st == ILF_JSON_OK)
        *out = (uint32_t)v;
    return json_result(&c, st);
}

cap_status cap__json_string(const char *path, const ilf_json *j, const char *elem, const char **out)
{
    ilf_json_ctx c = {.file = path};
    return json_result(&c, ilf_json_string(&c, j, elem, out));
}

/* ------------------------------------------------------------ slabs */

cap_status cap__json_slab_name(const char *path, const ilf_json *j, const char *elem, char name[LFIO_NAME_MAX + 1])
{
    const char *text;
    cap_status st = cap__json_string(path, j, elem, &text);
    if (st != CAP_OK)
        return st;
    if (!lfio_slab_name_valid(text))
        return cap__json_bad(path, elem, "'%s': use 1 to %d of A-Z a-z 0-9 _ - .", text, LFIO_NAME_MAX);
    memcpy(name, text, strlen(text) + 1);
    return CAP_OK;
}

cap_status cap__json_rectangle(const char *path, const ilf_json *obj, const char *elem, lfio_slab_desc *d)
{
    static const char *const keys[3] = {"origin", "u", "v"};
    double *dest[3] = {d->origin, d->u, d->v};
    for (int k = 0; k < 3; k++) {
        const ilf_json *j;
        char e[ILF_JSON_ELEM_MAX];
        ilf_json_member_name(e, elem, keys[k]);
        cap_status st = cap__json_member(path, obj, elem, keys[k], 1, &j);
        if (st == CAP_OK)
            st = cap__json_vector3(path, j, e, dest[k]);
        if (st != CAP_OK)
            return st;
    }
    int edges = lfio_slab_edges_check(d->u, d->v);
    if (edges == LFIO_EDGES_LENGTH)
        return cap__json_bad(path, elem, "u and v must be nonzero (and their lengths finite)");
    if (edges == LFIO_EDGES_ORTHOGONAL)
        return cap__json_bad(path, elem, "u and v must be orthogonal (u.v = %g)", a3_dot(d->u, d->v));
    return CAP_OK;
}

cap_status cap__json_grid(const char *path, const ilf_json *j, const char *elem, lfio_slab_desc *d)
{
    static const char *const keys[] = {"nu", "nv", NULL};
    const ilf_json *a, *b;
    char ae[ILF_JSON_ELEM_MAX], be[ILF_JSON_ELEM_MAX];
    ilf_json_member_name(ae, elem, "nu");
    ilf_json_member_name(be, elem, "nv");
    cap_status st = cap__json_keys(path, j, elem, keys);
    if (st == CAP_OK)
        st = cap__json_member(path, j, elem, "nu", 1, &a);
    if (st == CAP_OK)
        st = cap__json_member(path, j, elem, "nv", 1, &b);
    if (st == CAP_OK)
        st = cap__json_uint(path, a, ae, 1, 65536, &d->nu);
    if (st == CAP_OK)
        st = cap__json_uint(path, b, be, 1, 65536, &d->nv);
    return st;
}
