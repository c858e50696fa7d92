/*
 * scene.c - reads scene files (docs/scene.md) with ilf_json into an rl_scene,
 * and the accessors of relight/scene.h.
 *
 * Loading reads and parses the whole file (at most ILF_SCENE_MAX_BYTES) with
 * base's one strict JSON reader (ilf/json.h), then walks the
 * tree section by section: materials, radiance_maps, sampling, camera,
 * polygons, meshes, lightfields. Every value is checked where it is read,
 * and the first problem ends the load with a message
 * "<scene file>: <element>: <problem>", the element written as a path into
 * the file ("polygons[3].vertices[1][0]", "sampling.partition_n"). Defaults
 * are applied for every absent optional key. Polygons and mesh faces go
 * through mesh.c, which establishes the polygon invariants of
 * scene_model.h; this file establishes the others (materials, light
 * field transforms, cell size, sampling, camera).
 *
 * Invariants: a scene returned by rl_scene_load() satisfies every invariant
 * of scene_model.h; on failure nothing is returned and everything
 * allocated on the way (including loaded light fields) is released. No
 * allocation is sized by a count read from a file before that count has
 * been checked against its limit; arrays grow as elements pass their checks.
 */
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "scene_model.h"
#include "build.h"
#include "mesh.h"
#include "ilf/json.h"
#include "ilf/limits.h"
#include "ilf/options.h"
#include "ilf/vec.h"

/* Longest element path in messages. */
#define ELEM_MAX ILF_JSON_ELEM_MAX

/* ------------------------------------------------------------- limits */

/* The allowed values of an integer setting. */
typedef struct int_limit {
    uint64_t lo, hi;
    int pow2; /* also a power of two */
} int_limit;

static const int_limit lim_pixels = {1, ILF_CAMERA_MAX_SIDE, 0};
static const int_limit lim_index = {0, UINT32_MAX, 0};

/* ----------------------------------------------------------- messages */

/* Writes the path of member key of element elem ("sampling" + "seed" = "sampling.seed") to out. */
static void member_elem(char out[ELEM_MAX], const char *elem, const char *key)
{
    ilf_json_member_name(out, elem, key);
}

/* Writes the path of entry i of array element elem ("polygons" + 3 = "polygons[3]") to out. */
static void entry_elem(char out[ELEM_MAX], const char *elem, size_t i)
{
    ilf_json_item_name(out, elem, i);
}

/* ------------------------------------------------------- JSON helpers */
/* The scene's typed reading, through base's one strict reader (ilf/json.h): each helper moves the
 * reader's message "<scene file>: <element>: <problem>" into relight's error state. */

/* Records ctx's message with the status st maps to. @return RL_OK, RL_ERR_INPUT, RL_ERR_IO or RL_ERR_NOMEM. */
static rl_status json_result(const ilf_json_ctx *ctx, ilf_json_status st)
{
    switch (st) {
    case ILF_JSON_OK: return RL_OK;
    case ILF_JSON_ERR_IO: return rl__fail(RL_ERR_IO, "%s", ctx->message);
    case ILF_JSON_ERR_NOMEM: return rl__fail(RL_ERR_NOMEM, "%s", ctx->message);
    default: return rl__fail(RL_ERR_INPUT, "%s", ctx->message);
    }
}

/* @return what j is, for messages ("a string"); "nothing" for NULL. */
static const char *json_kind(const ilf_json *j)
{
    return ilf_json_kind(j);
}

/* @return member key of object obj (case-sensitive), or NULL. */
static const ilf_json *member(const ilf_json *obj, const char *key)
{
    return ilf_json_get(obj, key);
}

/* Checks that j is an object whose keys all appear in allowed (NULL-terminated), each at most once.
 * @return RL_OK or RL_ERR_INPUT naming the key. */
static rl_status json_keys(const rl_build *b, const ilf_json *j, const char *elem, const char *const *allowed)
{
    ilf_json_ctx c = {.file = b->file};
    return json_result(&c, ilf_json_keys(&c, j, elem, allowed));
}

/* Reads the finite number j. @return RL_OK and *out, or RL_ERR_INPUT naming elem. */
static rl_status json_number(const rl_build *b, const ilf_json *j, const char *elem, double *out)
{
    ilf_json_ctx c = {.file = b->file};
    return json_result(&c, ilf_json_number(&c, j, elem, out));
}

/* Reads a vector: the array j of exactly n finite numbers. @return RL_OK and out[0..n), or RL_ERR_INPUT. */
static rl_status json_vector(const rl_build *b, const ilf_json *j, const char *elem, size_t n, double *out)
{
    ilf_json_ctx c = {.file = b->file};
    return json_result(&c, ilf_json_vector(&c, j, elem, n, out));
}

/* Reads an integer allowed by l. @return RL_OK and *out, or RL_ERR_INPUT naming elem and the rule. */
static rl_status json_integer(const rl_build *b, const ilf_json *j, const char *elem, const int_limit *l,
                              uint64_t *out)
{
    ilf_json_ctx c = {.file = b->file};
    return json_result(&c, ilf_json_integer(&c, j, elem, l->lo, l->hi, l->pow2, out));
}

/* Reads a non-empty string. @return RL_OK and *out (borrowed from j), or RL_ERR_INPUT. */
static rl_status json_string(const rl_build *b, const ilf_json *j, const char *elem, const char **out)
{
    ilf_json_ctx c = {.file = b->file};
    return json_result(&c, ilf_json_string(&c, j, elem, out));
}

/* Finds the required member key of obj. @return RL_OK and *out, or RL_ERR_INPUT naming it. */
static rl_status json_required(const rl_build *b, const ilf_json *obj, const char *elem, const char *key,
                               const ilf_json **out)
{
    ilf_json_ctx c = {.file = b->file};
    return json_result(&c, ilf_json_member(&c, obj, elem, key, 1, out));
}

/* -------------------------------------------------------- the builder */

/* Writes file, a path relative to the scene's folder unless absolute, to out. @return RL_OK or RL_ERR_INPUT. */
static rl_status resolve_path(const rl_build *b, const char *elem, const char *file, char *out, size_t cap)
{
    int len = snprintf(out, cap, "%s%s", file[0] == '/' ? "" : b->dir, file);
    if (len < 0 || (size_t)len >= cap)
        return rl__build_fail(b, elem, "the path '%.100s...' is too long", file);
    return RL_OK;
}

/* ----------------------------------------------------------- sections */

/* Reads "materials": an object of name -> {"albedo", "emission"}. */
static rl_status read_materials(rl_build *b, const ilf_json *j)
{
    static const char *const keys[] = {"albedo", "emission", NULL};
    if (ilf_json_type_of(j) != ILF_JSON_OBJECT)
        return rl__build_fail(b, "materials", "expected an object, got %s", json_kind(j));
    for (const ilf_json *m = ilf_json_first(j); m; m = ilf_json_next(m)) {
        char elem[ELEM_MAX], sub[ELEM_MAX];
        member_elem(elem, "materials", ilf_json_key(m));
        uint32_t index;
        if (rl__build_find_material(b, ilf_json_key(m), &index))
            return rl__build_fail(b, elem, "duplicate material");
        double colour[2][3] = {{0.8, 0.8, 0.8}, {0, 0, 0}};
        rl_status st = json_keys(b, m, elem, keys);
        for (int k = 0; k < 2 && st == RL_OK; k++) {
            const ilf_json *c = member(m, keys[k]);
            member_elem(sub, elem, keys[k]);
            if (c)
                st = json_vector(b, c, sub, 3, colour[k]);
        }
        if (st == RL_OK)
            st = rl__build_material(b, elem, ilf_json_key(m), colour[0], colour[1], &index);
        if (st != RL_OK)
            return st;
    }
    return RL_OK;
}

/* Reads the member "material" of obj, which must name a known material. @return RL_OK and *index, or RL_ERR_INPUT. */
static rl_status read_material_ref(const rl_build *b, const ilf_json *j, const char *elem, uint32_t *index)
{
    const char *name = NULL;
    rl_status st = json_string(b, j, elem, &name);
    if (st == RL_OK && !rl__build_find_material(b, name, index))
        st = rl__build_fail(b, elem, "unknown material '%.100s'", name);
    return st;
}

/* Reads one entry of "polygons": {"material", "vertices"}. */
static rl_status read_polygon(rl_build *b, const ilf_json *p, const char *elem)
{
    static const char *const keys[] = {"material", "vertices", NULL};
    char sub[ELEM_MAX];
    const ilf_json *mj = NULL, *vj = NULL;
    uint32_t material = 0;
    rl_status st = json_keys(b, p, elem, keys);
    if (st == RL_OK)
        st = json_required(b, p, elem, "material", &mj);
    if (st == RL_OK) {
        member_elem(sub, elem, "material");
        st = read_material_ref(b, mj, sub, &material);
    }
    if (st == RL_OK)
        st = json_required(b, p, elem, "vertices", &vj);
    if (st != RL_OK)
        return st;
    member_elem(sub, elem, "vertices");
    if (ilf_json_type_of(vj) != ILF_JSON_ARRAY)
        return rl__build_fail(b, sub, "expected an array of [x, y, z] vertices, got %s", json_kind(vj));
    size_t n = ilf_json_count(vj);
    if (n > RL_MAX_POLYGON_VERTICES) /* before anything is read into b->face */
        return rl__build_fail(b, elem, "has %zu vertices, more than the limit of %u", n, RL_MAX_POLYGON_VERTICES);
    size_t i = 0;
    ilf_json_ctx c = {.file = b->file};
    for (const ilf_json *v = ilf_json_first(vj); v; v = ilf_json_next(v), i++)
        if ((st = json_result(&c, ilf_json_vector_item(&c, v, sub, i, 3, b->face[i]))) != RL_OK)
            return st;
    return rl__build_polygon(b, (const double (*)[3])b->face, n, material, elem, RL_POLY_STRICT);
}

/* Reads "polygons": an array of polygons. */
static rl_status read_polygons(rl_build *b, const ilf_json *j)
{
    if (ilf_json_type_of(j) != ILF_JSON_ARRAY)
        return rl__build_fail(b, "polygons", "expected an array, got %s", json_kind(j));
    size_t i = 0;
    for (const ilf_json *p = ilf_json_first(j); p; p = ilf_json_next(p), i++) {
        char elem[ELEM_MAX];
        entry_elem(elem, "polygons", i);
        rl_status st = read_polygon(b, p, elem);
        if (st != RL_OK)
            return st;
    }
    return RL_OK;
}

/* Reads the optional keys "up", "flip" and "two_sided" of mesh entry m into opt. @return RL_OK or RL_ERR_INPUT. */
static rl_status read_mesh_options(const rl_build *b, const ilf_json *m, const char *elem, rl_mesh_options *opt)
{
    char sub[ELEM_MAX];
    ilf_json_ctx c = {.file = b->file};
    const ilf_json *up = member(m, "up");
    rl_status st = RL_OK;
    if (up) {
        const char *axis = NULL;
        member_elem(sub, elem, "up");
        st = json_string(b, up, sub, &axis);
        if (st == RL_OK && strcmp(axis, "z") != 0 && strcmp(axis, "y") != 0)
            st = rl__build_fail(b, sub, "expected \"z\" or \"y\", got '%.40s'", axis);
        opt->up = st == RL_OK && axis[0] == 'y' ? RL_MESH_UP_Y : RL_MESH_UP_Z;
    }
    static const char *const flags[] = {"flip", "two_sided"};
    int *out[] = {&opt->flip, &opt->two_sided};
    for (int k = 0; k < 2 && st == RL_OK; k++) {
        const ilf_json *f = member(m, flags[k]);
        member_elem(sub, elem, flags[k]);
        if (f)
            st = json_result(&c, ilf_json_flag(&c, f, sub, out[k]));
    }
    return st;
}

/* Reads "meshes": an array of {"file", "material", "up", "flip", "two_sided"}. */
static rl_status read_meshes(rl_build *b, const ilf_json *j)
{
    static const char *const keys[] = {"file", "material", "up", "flip", "two_sided", NULL};
    if (ilf_json_type_of(j) != ILF_JSON_ARRAY)
        return rl__build_fail(b, "meshes", "expected an array, got %s", json_kind(j));
    size_t i = 0;
    for (const ilf_json *m = ilf_json_first(j); m; m = ilf_json_next(m), i++) {
        char elem[ELEM_MAX], sub[ELEM_MAX], path[1024];
        entry_elem(elem, "meshes", i);
        const ilf_json *fj = NULL, *mj;
        const char *file = NULL;
        uint32_t material = 0;
        rl_status st = json_keys(b, m, elem, keys);
        if (st == RL_OK)
            st = json_required(b, m, elem, "file", &fj);
        member_elem(sub, elem, "file");
        if (st == RL_OK)
            st = json_string(b, fj, sub, &file);
        if (st == RL_OK)
            st = resolve_path(b, sub, file, path, sizeof path);
        mj = member(m, "material");
        member_elem(sub, elem, "material");
        if (st == RL_OK && mj)
            st = read_material_ref(b, mj, sub, &material);
        rl_mesh_options opt = {.fallback = mj ? &material : NULL, .up = RL_MESH_UP_DECLARED};
        if (st == RL_OK)
            st = read_mesh_options(b, m, elem, &opt);
        if (st == RL_OK)
            st = rl__build_mesh(b, path, elem, file, &opt);
        if (st != RL_OK)
            return st;
    }
    return RL_OK;
}

/* Reads a 4x4 matrix: 16 numbers in row-major order, or 4 rows of 4. @return RL_OK and t, or RL_ERR_INPUT. */
static rl_status read_matrix(const rl_build *b, const ilf_json *j, const char *elem, double t[16])
{
    if (ilf_json_type_of(j) != ILF_JSON_ARRAY || ilf_json_type_of(ilf_json_first(j)) != ILF_JSON_ARRAY)
        return json_vector(b, j, elem, 16, t);
    if ((int)ilf_json_count(j) != 4)
        return rl__build_fail(b, elem, "expected 4 rows of 4 numbers, got %d rows", (int)ilf_json_count(j));
    size_t r = 0;
    for (const ilf_json *row = ilf_json_first(j); row; row = ilf_json_next(row), r++) {
        char sub[ELEM_MAX];
        entry_elem(sub, elem, r);
        rl_status st = json_vector(b, row, sub, 4, t + 4 * r);
        if (st != RL_OK)
            return st;
    }
    return RL_OK;
}

/*
 * Splits the row-major affine map t into rotation, uniform scale and
 * translation (orthogonality to 1e-9 relative, determinant > 0).
 * @return NULL on success, else the problem.
 */
static const char *split_similarity(const double t[16], rl_lightfield *lf)
{
    if (t[12] != 0 || t[13] != 0 || t[14] != 0 || t[15] != 1)
        return "the last row must be [0, 0, 0, 1]";
    double gram[3][3], s2 = 0;
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            gram[i][k] = t[i] * t[k] + t[4 + i] * t[4 + k] + t[8 + i] * t[8 + k];
    for (int i = 0; i < 3; i++)
        s2 += gram[i][i] / 3;
    if (!(s2 > 0) || !isfinite(s2))
        return "the upper 3x3 must be a rotation times a uniform scale > 0 (its scale is 0 or too large)";
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            if (fabs(gram[i][k] - (i == k ? s2 : 0)) > 1e-9 * s2)
                return "the upper 3x3 must be a rotation times a uniform scale (it shears or scales unevenly)";
    double det = t[0] * (t[5] * t[10] - t[6] * t[9]) - t[1] * (t[4] * t[10] - t[6] * t[8]) +
                 t[2] * (t[4] * t[9] - t[5] * t[8]);
    if (!(det > 0))
        return "the upper 3x3 must have a positive determinant (it mirrors)";
    lf->scale = sqrt(s2);
    for (int i = 0; i < 3; i++) {
        for (int k = 0; k < 3; k++)
            lf->rot[i][k] = t[4 * i + k] / lf->scale;
        lf->translate[i] = t[4 * i + 3];
    }
    return NULL;
}

/* out = the linear part of lf's transform applied to x. */
static void transform_vector(const rl_lightfield *lf, const double x[3], double out[3])
{
    for (int i = 0; i < 3; i++)
        out[i] = lf->scale * (lf->rot[i][0] * x[0] + lf->rot[i][1] * x[1] + lf->rot[i][2] * x[2]);
}

/* Lists lf's slab names into buf ("a, b"). */
static void slab_names(const lfio_lightfield *lf, char *buf, size_t cap)
{
    buf[0] = '\0';
    for (size_t k = 0; k < lfio_lightfield_slab_count(lf) && strlen(buf) + 1 < cap; k++)
        snprintf(buf + strlen(buf), cap - strlen(buf), "%s'%s'", k ? ", " : "",
                 lfio_slab_get_desc(lfio_lightfield_slab(lf, k))->name);
}

/* Picks lf's slab given by sj: a name, an index, or NULL for slab 0. @return RL_OK or RL_ERR_INPUT. */
static rl_status pick_slab(const rl_build *b, const ilf_json *sj, const char *elem, rl_lightfield *lf)
{
    size_t count = lfio_lightfield_slab_count(lf->lf);
    uint64_t index = 0;
    if (ilf_json_type_of(sj) == ILF_JSON_STRING) {
        lf->slab = lfio_lightfield_find(lf->lf, ilf_json_text(sj));
        if (lf->slab)
            return RL_OK;
        char names[256];
        slab_names(lf->lf, names, sizeof names);
        return rl__build_fail(b, elem, "no slab named '%.64s' in '%s' (it has %s)", ilf_json_text(sj), lf->file, names);
    }
    rl_status st = sj ? json_integer(b, sj, elem, &lim_index, &index) : RL_OK;
    if (st == RL_OK && index >= count)
        st = rl__build_fail(b, elem, "slab index %llu is out of range: '%s' has %zu slab%s",
                            (unsigned long long)index, lf->file, count, count == 1 ? "" : "s");
    if (st == RL_OK)
        lf->slab = lfio_lightfield_slab(lf->lf, (size_t)index);
    return st;
}

/* @return the first entry of s->lightfields before lf that names file, or NULL. */
static const rl_lightfield *earlier_lightfield(const rl_scene *s, const rl_lightfield *lf, const char *file)
{
    for (const rl_lightfield *k = s->lightfields; k < lf; k++)
        if (strcmp(k->file, file) == 0)
            return k;
    return NULL;
}

/* Reads one entry of "lightfields" into lf; the scene's destroy releases what it owns. */
static rl_status read_lightfield(rl_build *b, const ilf_json *j, const char *elem, rl_lightfield *lf)
{
    static const char *const keys[] = {"file", "slab", "transform", "made_by", NULL};
    char sub[ELEM_MAX];
    const ilf_json *fj = NULL, *sj, *tj, *mj;
    const char *file = NULL, *made_by = NULL;
    double t[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    rl_status st = json_keys(b, j, elem, keys);
    if (st == RL_OK)
        st = json_required(b, j, elem, "file", &fj);
    member_elem(sub, elem, "file");
    if (st == RL_OK)
        st = json_string(b, fj, sub, &file);
    if (st == RL_OK)
        st = resolve_path(b, sub, file, lf->file, sizeof lf->file);
    sj = member(j, "slab");
    member_elem(sub, elem, "slab");
    if (st == RL_OK && sj && ilf_json_type_of(sj) != ILF_JSON_STRING && ilf_json_type_of(sj) != ILF_JSON_NUMBER)
        st = rl__build_fail(b, sub, "expected a slab name or index, got %s", json_kind(sj));
    mj = member(j, "made_by");
    member_elem(sub, elem, "made_by");
    if (st == RL_OK && mj)
        st = json_string(b, mj, sub, &made_by);
    tj = member(j, "transform");
    member_elem(sub, elem, "transform");
    if (st == RL_OK && tj)
        st = read_matrix(b, tj, sub, t);
    const char *why = st == RL_OK ? split_similarity(t, lf) : NULL;
    if (why)
        st = rl__build_fail(b, sub, "%s", why);
    if (st != RL_OK)
        return st;

    /* a file placed several times (lamps of one kind) is read once */
    const rl_lightfield *same = earlier_lightfield(b->scene, lf, lf->file);
    if (same) {
        lf->lf = same->lf;
    } else {
        lfio_read_options ro;
        lfio_read_options_init(&ro);
        ro.threads = b->read_threads;
        lfio_status ls = lfio_lightfield_read_with(lf->file, &ro, &lf->lf);
        if (ls == LFIO_ERR_NOMEM)
            return rl__fail(RL_ERR_NOMEM, "%s: %s: %s", b->file, elem, lfio_errmsg());
        if (ls != LFIO_OK && made_by && access(lf->file, F_OK) != 0 && errno == ENOENT)
            return rl__build_fail(b, elem, "%s (it is generated: %.512s)", lfio_errmsg(), made_by);
        if (ls != LFIO_OK)
            return rl__build_fail(b, elem, "%s", lfio_errmsg());
        lf->owns_lf = 1;
    }
    member_elem(sub, elem, "slab");
    if ((st = pick_slab(b, sj, sub, lf)) != RL_OK)
        return st;
    const lfio_slab_desc *d = lfio_slab_get_desc(lf->slab);
    lf->nu = d->nu, lf->nv = d->nv, lf->n = d->n;
    transform_vector(lf, d->origin, lf->origin);
    for (int i = 0; i < 3; i++)
        lf->origin[i] += lf->translate[i];
    transform_vector(lf, d->u, lf->u);
    transform_vector(lf, d->v, lf->v);
    ilf_format_cut(lf->label, sizeof lf->label, "%s", elem);
    return RL_OK;
}

/* Reads "lightfields": an array of light field emitters. */
static rl_status read_lightfields(rl_build *b, const ilf_json *j)
{
    if (ilf_json_type_of(j) != ILF_JSON_ARRAY)
        return rl__build_fail(b, "lightfields", "expected an array, got %s", json_kind(j));
    rl_scene *s = b->scene;
    size_t i = 0;
    for (const ilf_json *e = ilf_json_first(j); e; e = ilf_json_next(e), i++) {
        void *p = rl__grow(s->lightfields, &b->lightfield_cap, s->nlightfields + 1, sizeof *s->lightfields);
        if (!p)
            return rl__fail(RL_ERR_NOMEM, "%s: out of memory", b->file);
        s->lightfields = p;
        rl_lightfield *lf = &s->lightfields[s->nlightfields++]; /* counted now so that destroy frees it */
        memset(lf, 0, sizeof *lf);
        char elem[ELEM_MAX];
        entry_elem(elem, "lightfields", i);
        rl_status st = read_lightfield(b, e, elem, lf);
        if (st != RL_OK)
            return st;
    }
    return RL_OK;
}

/* Reads "radiance_maps": {"cell_size"}. */
static rl_status read_radiance_maps(rl_build *b, const ilf_json *j)
{
    static const char *const keys[] = {"cell_size", NULL};
    rl_status st = json_keys(b, j, "radiance_maps", keys);
    const ilf_json *c = member(j, "cell_size");
    if (st != RL_OK || !c)
        return st;
    double size = 0;
    if ((st = json_number(b, c, "radiance_maps.cell_size", &size)) != RL_OK)
        return st;
    if (!(size > 0))
        return rl__build_fail(b, "radiance_maps.cell_size", "must be > 0 metres, got %.17g", size);
    b->scene->cell_size = size;
    return RL_OK;
}

/* Reads "sampling": every setting of the table (settings.c), in its order, and the time budget, which
 * the file may still hold as a suggested run option: all three are the job the file suggests (rl_job_default()). */
static rl_status read_sampling(rl_build *b, const ilf_json *j)
{
    enum { MAX_KEYS = 32 };
    const char *keys[MAX_KEYS + 2];
    size_t n = rl_sampling_setting_count();
    for (size_t k = 0; k < n && k < MAX_KEYS; k++)
        keys[k] = rl_sampling_setting(k)->key;
    keys[n < MAX_KEYS ? n : MAX_KEYS] = "time_budget";
    keys[(n < MAX_KEYS ? n : MAX_KEYS) + 1] = NULL;
    rl_sampling *s = &b->scene->sampling;
    rl_status st = json_keys(b, j, "sampling", keys);
    for (size_t k = 0; k < n && st == RL_OK; k++) {
        const rl_setting_info *set = rl_sampling_setting(k);
        const ilf_json *v = member(j, set->key);
        char elem[ELEM_MAX], rule[128];
        member_elem(elem, "sampling", set->key);
        if (!v)
            continue;
        if (set->type == RL_SETTING_METHOD) {
            const char *name = NULL;
            if ((st = json_string(b, v, elem, &name)) == RL_OK && !rl_method_parse(name, &s->method))
                st = rl__build_fail(b, elem, "unknown method '%.64s' (expected %s)", name,
                                    rl_sampling_setting_rule(k, rule, sizeof rule));
        } else if (set->type == RL_SETTING_REAL) {
            double value = 0;
            if ((st = json_number(b, v, elem, &value)) == RL_OK && !rl_sampling_setting_allows(k, value, 1))
                st = rl__build_fail(b, elem, "must be %s, got %.17g", rl_sampling_setting_rule(k, rule, sizeof rule),
                                    value);
            if (st == RL_OK)
                rl_sampling_set(s, k, value);
        } else {
            int_limit lim = {(uint64_t)set->lo, (uint64_t)set->hi, (set->flags & RL_SETTING_POW2) != 0};
            uint64_t value = 0;
            if ((st = json_integer(b, v, elem, &lim, &value)) == RL_OK)
                rl_sampling_set(s, k, (double)value);
        }
    }
    /* the time budget is how to run, not what to compute: kept apart as the scene's suggestion */
    const ilf_json *tb = member(j, "time_budget");
    double *budget = &b->scene->time_budget;
    if (st == RL_OK && tb && (st = json_number(b, tb, "sampling.time_budget", budget)) == RL_OK && !(*budget >= 0))
        st = rl__build_fail(b, "sampling.time_budget", "must be >= 0 seconds, got %.17g", *budget);
    return st;
}

/* Reads "camera": position, look_at, up, fov_deg, width, height. */
static rl_status read_camera(rl_build *b, const ilf_json *j)
{
    static const char *const keys[] = {"position", "look_at", "up", "fov_deg", "width", "height", NULL};
    rl_camera *c = &b->scene->camera;
    double *const vectors[] = {c->position, c->look_at, c->up};
    uint32_t *const sizes[] = {&c->width, &c->height};
    char elem[ELEM_MAX];
    *c = (rl_camera){.up = {0, 0, 1}, .fov_deg = 45, .width = 640, .height = 480};
    rl_status st = json_keys(b, j, "camera", keys);
    for (int k = 0; k < 3 && st == RL_OK; k++) {
        const ilf_json *v = member(j, keys[k]);
        member_elem(elem, "camera", keys[k]);
        if (v)
            st = json_vector(b, v, elem, 3, vectors[k]);
        else if (k < 2)
            st = rl__build_fail(b, "camera", "missing key '%s'", keys[k]);
    }
    const ilf_json *f = member(j, "fov_deg");
    if (st == RL_OK && f && (st = json_number(b, f, "camera.fov_deg", &c->fov_deg)) == RL_OK &&
        !(c->fov_deg > 0 && c->fov_deg < 180))
        st = rl__build_fail(b, "camera.fov_deg", "must lie strictly between 0 and 180 degrees, got %.17g", c->fov_deg);
    for (int k = 0; k < 2 && st == RL_OK; k++) {
        const ilf_json *v = member(j, keys[4 + k]);
        uint64_t value = 0;
        member_elem(elem, "camera", keys[4 + k]);
        if (v && (st = json_integer(b, v, elem, &lim_pixels, &value)) == RL_OK)
            *sizes[k] = (uint32_t)value;
    }
    char why[160];
    if (st == RL_OK && rl__camera_problem(c, why, sizeof why))
        st = rl__build_fail(b, "camera", "%s", why);
    if (st == RL_OK)
        b->scene->has_camera = 1;
    return st;
}

/* Reads the top-level object. */
static rl_status read_scene(rl_build *b, const ilf_json *root)
{
    static const char *const keys[] = {"materials", "polygons", "meshes", "lightfields",
                                       "radiance_maps", "sampling", "camera", NULL};
    typedef rl_status (*reader)(rl_build *, const ilf_json *);
    static const struct {
        const char *key;
        reader read;
    } sections[] = {{"materials", read_materials}, {"radiance_maps", read_radiance_maps},
                    {"sampling", read_sampling},   {"camera", read_camera},
                    {"polygons", read_polygons},   {"meshes", read_meshes},
                    {"lightfields", read_lightfields}};
    if (ilf_json_type_of(root) != ILF_JSON_OBJECT)
        return rl__build_fail(b, "", "expected a JSON object at the top level, got %s", json_kind(root));
    rl_status st = json_keys(b, root, "", keys);
    for (size_t k = 0; k < sizeof sections / sizeof sections[0] && st == RL_OK; k++) {
        const ilf_json *j = member(root, sections[k].key);
        if (j)
            st = sections[k].read(b, j);
    }
    return st;
}

/* ---------------------------------------------------------------- API */

/* Releases b's name table and scratch space. */
static void build_release(rl_build *b)
{
    free(b->names);
    free(b->face);
    free(b->keep);
    free(b->flat);
    free(b->link);
    free(b->tris);
}

/* Sets up b for scene s read from path: folder, scratch space, defaults. @return RL_OK, RL_ERR_INPUT or RL_ERR_NOMEM. */
static rl_status build_init(rl_build *b, rl_scene *s, const char *path)
{
    const size_t n = RL_MAX_POLYGON_VERTICES;
    memset(b, 0, sizeof *b);
    b->scene = s;
    b->file = path;
    const char *slash = strrchr(path, '/');
    size_t dirlen = slash ? (size_t)(slash - path) + 1 : 0;
    if (dirlen >= sizeof b->dir || strlen(path) >= sizeof s->path)
        return rl__fail(RL_ERR_INPUT, "%.100s...: the path is too long", path);
    memcpy(b->dir, path, dirlen);
    memcpy(s->path, path, strlen(path) + 1);
    s->cell_size = RL_DEFAULT_CELL_SIZE;
    rl_sampling_default(&s->sampling);
    b->face = malloc(n * sizeof *b->face);
    b->keep = malloc(n * sizeof *b->keep);
    b->flat = malloc(n * sizeof *b->flat);
    b->link = malloc(2 * n * sizeof *b->link);
    b->tris = malloc(n * sizeof *b->tris);
    if (!b->face || !b->keep || !b->flat || !b->link || !b->tris)
        return rl__fail(RL_ERR_NOMEM, "%s: out of memory", path);
    return RL_OK;
}

void rl_scene_load_options_default(rl_scene_load_options *opt)
{
    if (!opt)
        return;
    memset(opt, 0, sizeof *opt);
    opt->size = sizeof *opt;
}

/* Reads the caller's options (NULL: the defaults) into *o, the part of them their size holds. @return RL_OK,
 * or RL_ERR_ARG naming the problem. */
static rl_status take_load_options(const char *path, const rl_scene_load_options *opt, rl_scene_load_options *o)
{
    rl_scene_load_options_default(o);
    if (opt && !ilf_options_take(o, sizeof *o, opt, offsetof(rl_scene_load_options, threads) + sizeof opt->threads))
        return rl__fail(RL_ERR_ARG, "%s: rl_scene_load_options.size %zu is not one this library knows", path,
                        opt->size);
    if (o->threads > ILF_MAX_THREADS)
        return rl__fail(RL_ERR_ARG, "%s: load options out of range (threads %u, at most %u)", path, o->threads,
                        ILF_MAX_THREADS);
    return RL_OK;
}

rl_status rl_scene_load(const char *path, rl_scene **out)
{
    return rl_scene_load_with(path, NULL, out);
}

rl_status rl_scene_load_with(const char *path, const rl_scene_load_options *opt, rl_scene **out)
{
    if (out)
        *out = NULL;
    if (!path || !out)
        return rl__fail(RL_ERR_ARG, "rl_scene_load: path and out must not be NULL");
    rl_scene_load_options o;
    rl_status st = take_load_options(path, opt, &o);
    if (st != RL_OK)
        return st;
    ilf_json *root = NULL;
    ilf_json_ctx jc = {.file = path};
    st = json_result(&jc, ilf_json_load(&jc, ILF_SCENE_MAX_BYTES, &root));
    if (st != RL_OK)
        return st;

    rl_scene *s = calloc(1, sizeof *s);
    rl_build b;
    memset(&b, 0, sizeof b);
    if (!s)
        st = rl__fail(RL_ERR_NOMEM, "%s: out of memory", path);
    if (st == RL_OK)
        st = build_init(&b, s, path);
    b.read_threads = o.threads;
    if (st == RL_OK)
        st = read_scene(&b, root);
    build_release(&b);
    ilf_json_free(root);
    if (st != RL_OK) {
        rl_scene_destroy(s);
        return st;
    }
    *out = s;
    return RL_OK;
}

void rl_scene_destroy(rl_scene *s)
{
    if (!s)
        return;
    for (size_t k = 0; k < s->nlightfields; k++) {
        if (s->lightfields[k].owns_lf)
            lfio_lightfield_destroy(s->lightfields[k].lf);
    }
    free(s->lightfields);
    free(s->materials);
    free(s->vertices);
    free(s->polygons);
    free(s);
}

size_t rl_scene_polygon_count(const rl_scene *s)
{
    return s ? s->npolygons : 0;
}

size_t rl_scene_lightfield_count(const rl_scene *s)
{
    return s ? s->nlightfields : 0;
}

uint64_t rl_scene_lightfield_bytes(const rl_scene *s)
{
    uint64_t bytes = 0;
    for (size_t k = 0; s && k < s->nlightfields; k++) {
        const lfio_lightfield *lf = s->lightfields[k].lf;
        for (size_t j = 0; s->lightfields[k].owns_lf && j < lfio_lightfield_slab_count(lf); j++)
            bytes += lfio_slab_desc_bytes(lfio_slab_get_desc(lfio_lightfield_slab(lf, j)));
    }
    return bytes;
}

int rl_scene_has_camera(const rl_scene *s)
{
    return s ? s->has_camera : 0;
}

int rl_scene_camera_size(const rl_scene *s, uint32_t *width, uint32_t *height)
{
    if (!s || !s->has_camera)
        return 0;
    *width = s->camera.width;
    *height = s->camera.height;
    return 1;
}
