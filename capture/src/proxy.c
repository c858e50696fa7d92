/*
 * proxy.c - loading proxy geometry for reprojection (cap_proxy_load in
 * capture/reproject.h): a JSON list of rectangles, or a mesh file read with
 * assimp whose faces must all be rectangles (only quads are supported).
 *
 * Invariants: every rectangle of a loaded proxy has finite, nonzero,
 * orthogonal edges, a valid unique name, a grid and level within lfio's
 * limits; a mesh face that is not a planar rectangle is an error naming the
 * face, never silently dropped or split.
 */
#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "capture/reproject.h"
#include "internal.h"
#include "json.h"

/* Largest proxy JSON file accepted. */
#define PROXY_MAX_BYTES ((size_t)16 << 20)
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
    double bytes = (double)d->nu * d->nv * 4.0 * d->n * d->n * 12.0;
    if (bytes > (double)LFIO_SLAB_MAX_BYTES)
        return cap__json_bad(path, elem, "the slab would hold %.3g bytes of radiance, over lfio's limit", bytes);
    return CAP_OK;
}

/* ------------------------------------------------------------ JSON */

static cap_status read_rect(const char *path, const cJSON *j, const char *elem, lfio_slab_desc *d)
{
    static const char *const keys[] = {"name", "origin", "u", "v", "grid", "n", NULL};
    const cJSON *x;
    char e[CAP__ELEM_MAX];
    cap_status st = cap__json_keys(path, j, elem, keys);
    if (st == CAP_OK)
        st = cap__json_rectangle(path, j, elem, d);
    if (st == CAP_OK && (x = cJSON_GetObjectItemCaseSensitive(j, "name")) != NULL) {
        cap__json_member_name(e, elem, "name");
        st = cap__json_slab_name(path, x, e, d->name);
    }
    if (st == CAP_OK && (x = cJSON_GetObjectItemCaseSensitive(j, "grid")) != NULL) {
        cap__json_member_name(e, elem, "grid");
        st = cap__json_grid(path, x, e, d);
    }
    if (st == CAP_OK && (x = cJSON_GetObjectItemCaseSensitive(j, "n")) != NULL) {
        cap__json_member_name(e, elem, "n");
        st = cap__json_uint(path, x, e, 1, LFIO_SLAB_MAX_N, &d->n);
    }
    if (st == CAP_OK)
        st = check_size(path, elem, d);
    return st;
}

static cap_status load_json(const char *path, const cap_proxy_defaults *def, cap_proxy *p)
{
    cJSON *root;
    cap_status st = cap__json_load(path, PROXY_MAX_BYTES, &root);
    if (st != CAP_OK)
        return st;
    int count = cJSON_IsArray(root) ? cJSON_GetArraySize(root) : -1;
    if (count < 1 || count > (int)CAP_PROXY_MAX)
        st = count < 0 ? cap__json_bad(path, "", "expected an array of rectangles, got %s", cap__json_kind(root))
                       : cap__json_bad(path, "", "%d rectangles; a proxy holds 1 to %u", count, CAP_PROXY_MAX);
    if (st == CAP_OK && (p->rects = calloc((size_t)count, sizeof *p->rects)) == NULL)
        st = cap__fail(CAP_ERR_NOMEM, "%s: out of memory", path);
    for (int k = 0; st == CAP_OK && k < count; k++) {
        char elem[CAP__ELEM_MAX];
        cap__json_item_name(elem, "", (size_t)k);
        rect_init(&p->rects[k], def, "proxy", (size_t)k);
        st = read_rect(path, cJSON_GetArrayItem(root, k), elem, &p->rects[k]);
        p->count = (size_t)k + 1;
        if (st == CAP_OK && name_taken(p, (size_t)k))
            st = cap__json_bad(path, elem, "name '%s' is used twice", p->rects[k].name);
    }
    cJSON_Delete(root);
    return st;
}

/* ------------------------------------------------------------ meshes */

static void vertex(const struct aiMesh *mesh, unsigned index, double out[3])
{
    out[0] = mesh->mVertices[index].x;
    out[1] = mesh->mVertices[index].y;
    out[2] = mesh->mVertices[index].z;
}

/* Makes d's rectangle from face f of mesh. @return NULL, or why the face is not a rectangle. */
static const char *face_rectangle(const struct aiMesh *mesh, const struct aiFace *f, lfio_slab_desc *d)
{
    if (f->mNumIndices != 4)
        return "is not a quad (only rectangular quads are supported)";
    double c[4][3];
    for (int k = 0; k < 4; k++)
        vertex(mesh, f->mIndices[k], c[k]);
    double diag = 0.0;
    for (int a = 0; a < 3; a++) {
        d->origin[a] = c[0][a];
        d->u[a] = c[1][a] - c[0][a];
        d->v[a] = c[3][a] - c[0][a];
        diag += (c[2][a] - c[0][a]) * (c[2][a] - c[0][a]);
    }
    double lu = cap__norm(d->u), lv = cap__norm(d->v), miss = 0.0;
    for (int a = 0; a < 3; a++)
        miss = fmax(miss, fabs(c[2][a] - (c[0][a] + d->u[a] + d->v[a])));
    if (!(lu > 0.0) || !(lv > 0.0))
        return "has a zero-length edge";
    if (fabs(cap__dot(d->u, d->v)) > RECT_TOL * lu * lv || miss > RECT_TOL * sqrt(diag))
        return "is not a rectangle (v0 v1 v2 v3 must be the corners in order around it)";
    /* lfio wants orthogonality to 1e-9: remove the part of v along u left by rounding. */
    double along = cap__dot(d->u, d->v) / (lu * lu);
    for (int a = 0; a < 3; a++)
        d->v[a] -= along * d->u[a];
    return NULL;
}

/* @return the number of faces over the scene's meshes. */
static size_t face_total(const struct aiScene *sc)
{
    size_t total = 0;
    for (unsigned m = 0; m < sc->mNumMeshes; m++)
        total += sc->mMeshes[m]->mNumFaces;
    return total;
}

static cap_status mesh_rects(const char *path, const struct aiScene *sc, const cap_proxy_defaults *def,
                             cap_proxy *p)
{
    size_t total = face_total(sc);
    if (total < 1 || total > CAP_PROXY_MAX)
        return cap__json_bad(path, "", "%zu faces; a proxy holds 1 to %u", total, CAP_PROXY_MAX);
    p->rects = calloc(total, sizeof *p->rects);
    if (p->rects == NULL)
        return cap__fail(CAP_ERR_NOMEM, "%s: out of memory", path);
    for (unsigned m = 0; m < sc->mNumMeshes; m++)
        for (unsigned f = 0; f < sc->mMeshes[m]->mNumFaces; f++) {
            lfio_slab_desc *d = &p->rects[p->count];
            char elem[CAP__ELEM_MAX];
            snprintf(elem, sizeof elem, "face %zu (mesh %u face %u)", p->count, m, f);
            rect_init(d, def, "face", p->count);
            const char *why = face_rectangle(sc->mMeshes[m], &sc->mMeshes[m]->mFaces[f], d);
            if (why != NULL)
                return cap__json_bad(path, elem, "%u vertices: %s", sc->mMeshes[m]->mFaces[f].mNumIndices, why);
            p->count++;
            cap_status st = check_size(path, elem, d);
            if (st != CAP_OK)
                return st;
        }
    return CAP_OK;
}

static cap_status load_mesh(const char *path, const cap_proxy_defaults *def, cap_proxy *p)
{
    const struct aiScene *sc = aiImportFile(path, aiProcess_PreTransformVertices | aiProcess_ValidateDataStructure);
    if (sc == NULL)
        return cap__fail(CAP_ERR_INPUT, "%s: cannot read the mesh: %s", path, aiGetErrorString());
    cap_status st = mesh_rects(path, sc, def, p);
    aiReleaseImport(sc);
    return st;
}

/* ------------------------------------------------------------ public */

/* @return 1 if path ends in ".json", any case. */
static int is_json(const char *path)
{
    size_t len = strlen(path);
    if (len < 5)
        return 0;
    const char *ext = path + len - 5;
    return ext[0] == '.' && tolower((unsigned char)ext[1]) == 'j' && tolower((unsigned char)ext[2]) == 's' &&
           tolower((unsigned char)ext[3]) == 'o' && tolower((unsigned char)ext[4]) == 'n';
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
    cap_status st = is_json(path) ? load_json(path, defaults, p) : load_mesh(path, defaults, p);
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
