/*
 * proxy.c - loading proxy geometry for reprojection (cap_proxy_load in
 * capture/reproject.h): a JSON list of rectangles, or a mesh file imported
 * by base's one mesh importer (ilf/mesh.h: the formats and checks scenes
 * get) whose faces are rectangles: quads, or triangles that pair up into
 * rectangles (a triangulated quad, as exporters and assimp write them).
 *
 * Triangles are merged, not given slabs of their own: a slab is a
 * rectangle, and two slabs over one triangulated rectangle, each zeroed
 * outside its half, would sample the diagonal twice or not at all, whereas
 * the merged rectangle is exactly the slab of the quad it came from.
 *
 * Invariants: every rectangle of a loaded proxy has finite, nonzero,
 * orthogonal edges, a valid unique name, a grid and level within lfio's
 * limits; a mesh face that is not a planar rectangle or half of one is an
 * error naming the face, never silently dropped or split; one function,
 * corners_rectangle(), turns both quads and merged pairs into rectangles.
 */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "capture/reproject.h"
#include "internal.h"
#include "ilf/mesh.h"
#include "manifest.h"

/* Largest proxy JSON file accepted (ilf/limits.h). */
#define PROXY_MAX_BYTES ILF_PROXY_JSON_MAX_BYTES
/* Relative tolerance of the rectangle test for mesh faces (edges of single-precision vertices). */
#define RECT_TOL 1e-5

struct cap_proxy {
    size_t count;
    lfio_slab_desc *rects; /* [count] */
};

/* Starts rectangle k with the defaults and the name "<prefix><k>". */
static void rect_init(lfio_slab_desc *d, const cap_proxy_defaults *def, const char *prefix, size_t k)
{
    lfio_slab_desc_init(d);
    snprintf(d->name, sizeof d->name, "%s%zu", prefix, k);
    d->nu = def->nu;
    d->nv = def->nv;
    d->n = def->n;
}

/* @return 1 if rectangle k's name is used by an earlier one. */
static int name_taken(const cap_proxy *p, size_t k)
{
    for (size_t a = 0; a < k; a++)
        if (strcmp(p->rects[a].name, p->rects[k].name) == 0)
            return 1;
    return 0;
}

/* Checks that a rectangle's slab fits lfio's size limit. */
static cap_status check_size(const char *path, const char *elem, const lfio_slab_desc *d)
{
    uint64_t bytes = lfio_slab_desc_bytes(d);
    if (bytes > LFIO_SLAB_MAX_BYTES)
        return cap__json_bad(path, elem, "the slab would hold %.3g bytes of radiance, over lfio's limit", (double)bytes);
    return CAP_OK;
}

/* ------------------------------------------------------------ JSON */

static cap_status read_rect(const char *path, const ilf_json *j, const char *elem, lfio_slab_desc *d)
{
    static const char *const keys[] = {"name", "origin", "u", "v", "grid", "n", NULL};
    const ilf_json *x;
    char e[ILF_JSON_ELEM_MAX];
    cap_status st = cap__json_keys(path, j, elem, keys);
    if (st == CAP_OK)
        st = cap__json_rectangle(path, j, elem, d);
    if (st == CAP_OK && (x = ilf_json_get(j, "name")) != NULL) {
        ilf_json_member_name(e, elem, "name");
        st = cap__json_slab_name(path, x, e, d->name);
    }
    if (st == CAP_OK && (x = ilf_json_get(j, "grid")) != NULL) {
        ilf_json_member_name(e, elem, "grid");
        st = cap__json_grid(path, x, e, d);
    }
    if (st == CAP_OK && (x = ilf_json_get(j, "n")) != NULL) {
        ilf_json_member_name(e, elem, "n");
        st = cap__json_uint(path, x, e, 1, LFIO_SLAB_MAX_N, &d->n);
    }
    if (st == CAP_OK)
        st = check_size(path, elem, d);
    return st;
}

static cap_status load_json(const char *path, const cap_proxy_defaults *def, cap_proxy *p)
{
    ilf_json *root;
    cap_status st = cap__json_load(path, PROXY_MAX_BYTES, &root);
    if (st != CAP_OK)
        return st;
    int count = (ilf_json_type_of(root) == ILF_JSON_ARRAY) ? (int)ilf_json_count(root) : -1;
    if (count < 1 || count > (int)CAP_PROXY_MAX)
        st = count < 0 ? cap__json_bad(path, "", "expected an array of rectangles, got %s", ilf_json_kind(root))
                       : cap__json_bad(path, "", "%d rectangles; a proxy holds 1 to %u", count, CAP_PROXY_MAX);
    if (st == CAP_OK && (p->rects = calloc((size_t)count, sizeof *p->rects)) == NULL)
        st = cap__fail(CAP_ERR_NOMEM, "%s: out of memory", path);
    for (int k = 0; st == CAP_OK && k < count; k++) {
        char elem[ILF_JSON_ELEM_MAX];
        ilf_json_item_name(elem, "", (size_t)k);
        rect_init(&p->rects[k], def, "proxy", (size_t)k);
        st = read_rect(path, ilf_json_at(root, (size_t)(k)), elem, &p->rects[k]);
        p->count = (size_t)k + 1;
        if (st == CAP_OK && name_taken(p, (size_t)k))
            st = cap__json_bad(path, elem, "name '%s' is used twice", p->rects[k].name);
    }
    ilf_json_free(root);
    return st;
}

/* ------------------------------------------------------------ meshes */

/* Copies vertex k of face f of the mesh into out. */
static void vertex(const ilf_mesh *m, const ilf_mesh_face *f, unsigned k, double out[3])
{
    memcpy(out, m->vertices[m->indices[f->first + k]], 3 * sizeof *out);
}

/* Makes d's rectangle from corners c[0..3], in order around it: origin c0, u = c1 - c0, v = c3 - c0.
 * @return NULL, or why the corners are not a rectangle. */
static const char *corners_rectangle(const double c[4][3], lfio_slab_desc *d)
{
    double diag = 0.0;
    for (int a = 0; a < 3; a++) {
        d->origin[a] = c[0][a];
        d->u[a] = c[1][a] - c[0][a];
        d->v[a] = c[3][a] - c[0][a];
        diag += (c[2][a] - c[0][a]) * (c[2][a] - c[0][a]);
    }
    double lu = a3_len(d->u), lv = a3_len(d->v), miss = 0.0;
    for (int a = 0; a < 3; a++)
        miss = fmax(miss, fabs(c[2][a] - (c[0][a] + d->u[a] + d->v[a])));
    if (!(lu > 0.0) || !(lv > 0.0))
        return "has a zero-length edge";
    if (fabs(a3_dot(d->u, d->v)) > RECT_TOL * lu * lv || miss > RECT_TOL * sqrt(diag))
        return "is not a rectangle (v0 v1 v2 v3 must be the corners in order around it)";
    /* lfio wants orthogonality to 1e-9: remove the part of v along u left by rounding. */
    double along = a3_dot(d->u, d->v) / (lu * lu);
    for (int a = 0; a < 3; a++)
        d->v[a] -= along * d->u[a];
    return NULL;
}


/* @return 1 if points a and b are within tol of each other in every coordinate. */
static int same_point(const double a[3], const double b[3], double tol)
{
    return fabs(a[0] - b[0]) <= tol && fabs(a[1] - b[1]) <= tol && fabs(a[2] - b[2]) <= tol;
}

/*
 * Completes triangle t (vertices counter-clockwise from its front) into a rectangle with a later unused
 * triangle: t is rotated so that its corner opposite its longest edge is c[1]; a partner has the directed
 * edge c[0] -> c[2] (t's longest edge, run the other way, as in a consistently wound mesh) and its third
 * vertex becomes c[3]. @return the partner's index in faces, or 0 if there is none (c[3] undefined).
 */
static size_t find_partner(const ilf_mesh *m, const char *used, size_t t, double c[4][3])
{
    double v[3][3], longest = -1.0;
    int opposite = 0;
    for (int k = 0; k < 3; k++)
        vertex(m, &m->faces[t], (unsigned)k, v[k]);
    for (int k = 0; k < 3; k++) {
        double e[3] = {v[(k + 2) % 3][0] - v[(k + 1) % 3][0], v[(k + 2) % 3][1] - v[(k + 1) % 3][1],
                       v[(k + 2) % 3][2] - v[(k + 1) % 3][2]};
        if (a3_len(e) > longest) {
            longest = a3_len(e);
            opposite = k;
        }
    }
    for (int k = 0; k < 3; k++)
        memcpy(c[k], v[(opposite + 2 + k) % 3], sizeof c[k]);
    const double tol = RECT_TOL * longest;
    for (size_t b = t + 1; b < m->nfaces; b++) {
        const ilf_mesh_face *f = &m->faces[b];
        if (used[b] || f->count != 3)
            continue;
        double w[3][3];
        for (int k = 0; k < 3; k++)
            vertex(m, f, (unsigned)k, w[k]);
        for (int k = 0; k < 3; k++)
            if (same_point(w[k], c[0], tol) && same_point(w[(k + 1) % 3], c[2], tol)) {
                memcpy(c[3], w[(k + 2) % 3], sizeof c[3]);
                return b;
            }
    }
    return 0;
}

/*
 * Makes rectangle d from face t (a quad, or a triangle merged with its partner, which is marked used) and
 * names the face(s) in elem. @return NULL, or why no rectangle can be made.
 */
static const char *face_rectangle(const ilf_mesh *m, char *used, size_t t, lfio_slab_desc *d,
                                  char elem[ILF_JSON_ELEM_MAX])
{
    const ilf_mesh_face *f = &m->faces[t];
    snprintf(elem, ILF_JSON_ELEM_MAX, "face %zu (mesh %u face %u)", t, f->mesh, f->face);
    double c[4][3];
    if (f->count == 4) {
        for (int k = 0; k < 4; k++)
            vertex(m, f, (unsigned)k, c[k]);
        return corners_rectangle(c, d);
    }
    if (f->count != 3)
        return "is neither a quad nor a triangle (proxy faces must be rectangles)";
    size_t b = find_partner(m, used, t, c);
    if (b == 0)
        return "is a triangle without a later triangle sharing its longest edge (triangles are accepted in "
               "pairs that form a rectangle)";
    const char *why = corners_rectangle(c, d);
    if (why != NULL)
        return "is a triangle that does not form a rectangle with the triangle sharing its longest edge";
    used[b] = 1;
    snprintf(elem, ILF_JSON_ELEM_MAX, "faces %zu and %zu (mesh %u faces %u and %u)", t, b, f->mesh, f->face,
             m->faces[b].face);
    return NULL;
}

/* Makes one rectangle per quad or merged triangle pair, in the order of their first faces, each named
 * "face<k>" after it (k counting faces over the file's meshes). */
static cap_status mesh_rects(const char *path, const ilf_mesh *m, const cap_proxy_defaults *def, cap_proxy *p)
{
    size_t total = m->nfaces;
    if (total < 1 || total > 2 * (size_t)CAP_PROXY_MAX)
        return cap__json_bad(path, "", "%zu faces; a proxy holds 1 to %u rectangles", total, CAP_PROXY_MAX);
    char *used = calloc(total, 1);
    p->rects = calloc(total, sizeof *p->rects);
    if (used == NULL || p->rects == NULL) {
        free(used);
        return cap__fail(CAP_ERR_NOMEM, "%s: out of memory", path);
    }
    cap_status st = CAP_OK;
    for (size_t t = 0; st == CAP_OK && t < total; t++) {
        if (used[t])
            continue;
        lfio_slab_desc *d = &p->rects[p->count];
        char elem[ILF_JSON_ELEM_MAX];
        rect_init(d, def, "face", t);
        const char *why = face_rectangle(m, used, t, d, elem);
        if (why != NULL)
            st = cap__json_bad(path, elem, "%u vertices: %s", m->faces[t].count, why);
        else if (++p->count > CAP_PROXY_MAX)
            st = cap__json_bad(path, elem, "more than %u rectangles; a proxy holds 1 to %u", CAP_PROXY_MAX,
                               CAP_PROXY_MAX);
        else
            st = check_size(path, elem, d);
    }
    free(used);
    return st;
}

/* Imports the mesh file through the one importer, with every check scenes get (ilf/mesh.h). */
static cap_status load_mesh(const char *path, const cap_proxy_defaults *def, cap_proxy *p)
{
    ilf_mesh *m = NULL;
    char why[ILF_MESSAGE_BYTES];
    ilf_mesh_status ms = ilf_mesh_import(path, &m, why, sizeof why);
    if (ms == ILF_MESH_ERR_NOMEM)
        return cap__fail(CAP_ERR_NOMEM, "%s: out of memory", path);
    if (ms != ILF_MESH_OK)
        return cap__fail(CAP_ERR_INPUT, "%s: %s", path, why);
    cap_status st = mesh_rects(path, m, def, p);
    ilf_mesh_destroy(m);
    return st;
}

/* ------------------------------------------------------------ public */

/* @return 1 if path ends in extension ext (".json"), any case. */
static int has_extension(const char *path, const char *ext)
{
    size_t len = strlen(path), n = strlen(ext);
    if (len < n)
        return 0;
    for (size_t k = 0; k < n; k++)
        if (tolower((unsigned char)path[len - n + k]) != ext[k])
            return 0;
    return 1;
}

cap_status cap_proxy_load(const char *path, const cap_proxy_defaults *defaults, cap_proxy **out)
{
    if (out != NULL)
        *out = NULL;
    if (path == NULL || defaults == NULL || out == NULL)
        return cap__fail(CAP_ERR_ARG, "cap_proxy_load: a required argument is NULL");
    if (defaults->nu < 1 || defaults->nu > 65536 || defaults->nv < 1 || defaults->nv > 65536 ||
        defaults->n < 1 || defaults->n > LFIO_SLAB_MAX_N)
        return cap__fail(CAP_ERR_ARG, "cap_proxy_load: default grid %ux%u or level %u out of range", defaults->nu,
                         defaults->nv, defaults->n);
    cap_proxy *p = calloc(1, sizeof *p);
    if (p == NULL)
        return cap__fail(CAP_ERR_NOMEM, "%s: out of memory", path);
    /* Meshes in every format scenes take, through the same importer and pre-checks (ilf/mesh.h);
     * it refuses the formats whose readers trust a header's counts. */
    cap_status st = has_extension(path, ".json") ? load_json(path, defaults, p) : load_mesh(path, defaults, p);
    if (st != CAP_OK) {
        cap_proxy_destroy(p);
        return st;
    }
    *out = p;
    return CAP_OK;
}

void cap_proxy_destroy(cap_proxy *p)
{
    if (p == NULL)
        return;
    free(p->rects);
    free(p);
}

size_t cap_proxy_count(const cap_proxy *p)
{
    return p != NULL ? p->count : 0;
}

const lfio_slab_desc *cap_proxy_get_desc(const cap_proxy *p, size_t k)
{
    return p != NULL && k < p->count ? &p->rects[k] : NULL;
}
