/*
 * mesh.c - polygons for the scene loader: the checks that turn a vertex
 * list into a scene polygon, ear clipping for mesh faces that fail them, and
 * mesh files, imported by base's one mesh importer (ilf/mesh.h), turned into
 * scene polygons and materials.
 *
 * A vertex list becomes a polygon in these steps (check_polygon()), with d
 * its diameter (the largest distance between two of its vertices) and
 * tol = 1e-6 * d:
 *   1. d > 0;
 *   2. a vertex within tol of the previously kept one is dropped
 *      (consecutive duplicates, also across the closing edge), and at least
 *      3 vertices remain;
 *   3. the area, half the length of the Newell vector (the sum of the
 *      cross products of consecutive vertices), exceeds 1e-12 * d^2;
 *   4. every vertex lies within tol of the best-fit plane: the Newell normal
 *      through the vertices' centroid;
 *   5. a vertex within tol of the line through its neighbours is dropped
 *      when it lies between them (collinear); where the boundary turns back
 *      on itself (a spike) a scene polygon is not convex, while a mesh face
 *      just loses the vertex;
 *   6. every corner turns left about the normal and the turns add up to a
 *      single full turn (convex, winding once).
 * The normal stored is the unit Newell vector of what is kept: the
 * right-hand rule normal, so counter-clockwise vertices face the viewer.
 *
 * Mesh files are imported by ilf_mesh_import(), which makes every check
 * before assimp reads them (PLY counts, glTF headers and accessor types,
 * the accepted formats) and returns a polygon soup with emission in the
 * scene's units and the file's declared up axis. Here the soup is turned
 * up (an entry's "up", else what the file declares), its faces that are
 * planar and convex are merged with coplanar neighbours of their material
 * (see Merging below), and each result is added as it is, turned over
 * ("flip") or both ways ("two_sided"). A
 * mesh file that yields no polygon at all is an error rather than an empty
 * contribution: it is almost certainly the wrong file or a broken one.
 *
 * Scene polygons (RL_POLY_STRICT) failing any step are errors whose message
 * names the input vertex at fault. Mesh faces (RL_POLY_SPLIT) failing steps
 * 1-3 are dropped, as they carry no area; failing step 4 or 6 they are
 * projected onto their best-fit plane and ear clipped into triangles, each
 * of which passes the same steps before it is pooled for merging (merged
 * polygons pass them again when appended). Whatever is appended therefore
 * satisfies the polygon invariants of scene_model.h.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh.h"
#include "ilf/limits.h"
#include "ilf/mesh.h"
#include "ilf/vec.h"

static const double plane_tol = 1e-6; /* distances, relative to the diameter */
static const double area_tol = 1e-12; /* areas, relative to the diameter squared */

/* ------------------------------------------------------------ checks */

/* How a vertex list fares against the steps above. */
typedef enum verdict { V_OK, V_DEGENERATE, V_NONPLANAR, V_NONCONVEX } verdict;

/* One vertex list under check: p is the input, keep[0..n) the surviving input indices. */
typedef struct poly_check {
    const double (*p)[3];
    size_t *keep;
    size_t n;
    double diameter;
    double tol;    /* plane_tol * diameter */
    v3 normal;     /* unit Newell normal of the kept vertices */
    double area;
    char why[160]; /* the problem, once the verdict is not V_OK */
} poly_check;

/* @return kept vertex i (0 <= i < 2n), counted cyclically. */
static v3 kept(const poly_check *c, size_t i)
{
    return v3_load(c->p[c->keep[i % c->n]]);
}

/* @return |a - b| for input vertices a and b. */
static double dist(const double a[3], const double b[3])
{
    return v3_len(v3_sub(v3_load(a), v3_load(b)));
}

/* @return the largest distance between two of the n vertices (O(n^2), n <= RL_MAX_POLYGON_VERTICES). */
static double diameter(const double (*p)[3], size_t n)
{
    double best = 0; /* squared, so that the inner loop needs no square root */
    for (size_t i = 0; i < n; i++)
        for (size_t j = i + 1; j < n; j++) {
            v3 d = v3_sub(v3_load(p[i]), v3_load(p[j]));
            double q = v3_dot(d, d);
            best = q > best ? q : best;
        }
    return sqrt(best);
}

/* Keeps the vertices farther than tol from the previously kept one, also across the closing edge. */
static void drop_duplicates(poly_check *c, size_t n)
{
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
        if (m == 0 || dist(c->p[i], c->p[c->keep[m - 1]]) > c->tol)
            c->keep[m++] = i;
    while (m > 1 && dist(c->p[c->keep[m - 1]], c->p[c->keep[0]]) <= c->tol)
        m--;
    c->n = m;
}

/* Sets normal and area from the Newell vector of the kept vertices. @return 1 if the area is large enough. */
static int newell(poly_check *c)
{
    v3 sum = v3_make(0, 0, 0), o = kept(c, 0); /* relative to a vertex, for precision far from the origin */
    for (size_t i = 1; i + 1 < c->n; i++)
        sum = v3_add(sum, v3_cross(v3_sub(kept(c, i), o), v3_sub(kept(c, i + 1), o)));
    double len = v3_len(sum);
    c->area = 0.5 * len;
    if (!(c->area > area_tol * c->diameter * c->diameter) || !isfinite(len))
        return 0;
    c->normal = v3_scale(sum, 1 / len);
    return 1;
}

/* @return 1 if every kept vertex is within tol of the best-fit plane; else 0, naming the farthest in why. */
static int check_plane(poly_check *c)
{
    v3 centre = v3_make(0, 0, 0);
    for (size_t i = 0; i < c->n; i++)
        centre = v3_madd(centre, kept(c, i), 1.0 / (double)c->n);
    size_t worst = 0;
    double off = 0;
    for (size_t i = 0; i < c->n; i++) {
        double h = fabs(v3_dot(v3_sub(kept(c, i), centre), c->normal));
        if (h > off) {
            off = h;
            worst = c->keep[i];
        }
    }
    if (off <= c->tol)
        return 1;
    snprintf(c->why, sizeof c->why, "not planar (vertex %zu is %.3g m off the plane)", worst, off);
    return 0;
}

/* How vertex v sits between its neighbours a and b. */
typedef enum corner { CORNER, STRAIGHT, SPIKE } corner;

/* @return STRAIGHT if v is within tol of segment ab, SPIKE if within tol of its line but outside it. */
static corner classify(v3 a, v3 v, v3 b, double tol)
{
    v3 ab = v3_sub(b, a), av = v3_sub(v, a);
    double len = v3_len(ab);
    if (len <= tol)
        return SPIKE; /* the boundary goes out to v and straight back */
    if (v3_len(v3_cross(av, ab)) / len > tol)
        return CORNER;
    double t = v3_dot(av, ab) / (len * len);
    return t > 0 && t < 1 ? STRAIGHT : SPIKE;
}

/*
 * Drops kept vertices lying on the segment between their neighbours, and
 * spikes too when drop_spikes. @return 1; 0 with why set at a spike otherwise.
 */
static int drop_collinear(poly_check *c, int drop_spikes)
{
    int changed = 1;
    while (changed && c->n >= 3) {
        changed = 0;
        for (size_t i = 0; i < c->n && c->n >= 3;) {
            corner k = classify(kept(c, i + c->n - 1), kept(c, i), kept(c, i + 1), c->tol);
            if (k == CORNER) {
                i++;
                continue;
            }
            if (k == SPIKE && !drop_spikes) {
                snprintf(c->why, sizeof c->why,
                         "not convex (the boundary turns back on itself at vertex %zu)", c->keep[i]);
                return 0;
            }
            memmove(c->keep + i, c->keep + i + 1, (c->n - i - 1) * sizeof *c->keep);
            c->n--;
            changed = 1;
        }
    }
    return 1;
}

/* @return 1 if every corner turns left about the normal and the turns make one full turn; else 0 with why. */
static int check_convex(poly_check *c)
{
    double turning = 0;
    for (size_t i = 0; i < c->n; i++) {
        v3 in = v3_sub(kept(c, i), kept(c, i + c->n - 1)), out = v3_sub(kept(c, i + 1), kept(c, i));
        double s = v3_dot(v3_cross(in, out), c->normal);
        if (!(s > 0)) {
            snprintf(c->why, sizeof c->why, "not convex (the corner at vertex %zu turns the other way)",
                     c->keep[i]);
            return 0;
        }
        turning += atan2(s, v3_dot(in, out));
    }
    if (turning > 3 * ILF_PI) {
        snprintf(c->why, sizeof c->why, "not convex (the boundary winds around %.0f times)",
                 turning / (2 * ILF_PI));
        return 0;
    }
    return 1;
}

/* Sets why for a degenerate polygon. @return V_DEGENERATE. */
static verdict degenerate(poly_check *c, const char *what)
{
    snprintf(c->why, sizeof c->why, "degenerate (%s)", what);
    return V_DEGENERATE;
}

/*
 * Runs steps 1-6 on the n input vertices of c; mesh faces drop spikes and go
 * on past a planarity failure so that keep holds the cleaned face to split.
 * @return the verdict; keep, n, normal and area describe the cleaned polygon
 * unless it is V_DEGENERATE.
 */
static verdict check_polygon(poly_check *c, size_t n, int mesh_face)
{
    c->diameter = diameter(c->p, n);
    if (!(c->diameter > 0))
        return degenerate(c, "all vertices coincide");
    c->tol = plane_tol * c->diameter;
    drop_duplicates(c, n);
    if (c->n < 3)
        return degenerate(c, "fewer than 3 distinct vertices");
    if (!newell(c))
        return degenerate(c, "zero area: the vertices are collinear or retrace each other");
    verdict v = check_plane(c) ? V_OK : V_NONPLANAR;
    if (v == V_NONPLANAR && !mesh_face)
        return v;
    if (!drop_collinear(c, mesh_face))
        return V_NONCONVEX;
    if (c->n < 3 || !newell(c))
        return degenerate(c, "zero area once collinear vertices are removed");
    if (v == V_OK && !check_convex(c))
        v = V_NONCONVEX;
    return v;
}

/* ------------------------------------------------------ ear clipping */

/* @return twice the signed area of triangle a, b, c in the plane (> 0 counter-clockwise). */
static double orient(const double a[2], const double b[2], const double c[2])
{
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

/* Writes the kept vertices of c in a right-handed basis of its plane, relative to the first one, to q. */
static void project(const poly_check *c, double (*q)[2])
{
    v3 n = c->normal, axis = v3_make(0, 0, 0); /* the coordinate axis least aligned with the normal */
    if (fabs(n.x) <= fabs(n.y) && fabs(n.x) <= fabs(n.z))
        axis.x = 1;
    else if (fabs(n.y) <= fabs(n.z))
        axis.y = 1;
    else
        axis.z = 1;
    v3 e1 = v3_norm(v3_madd(axis, n, -v3_dot(axis, n)));
    v3 e2 = v3_cross(n, e1); /* e1 x e2 = n, so the face runs counter-clockwise in (e1, e2) */
    for (size_t i = 0; i < c->n; i++) {
        v3 d = v3_sub(kept(c, i), kept(c, 0));
        q[i][0] = v3_dot(d, e1);
        q[i][1] = v3_dot(d, e2);
    }
}

/* @return 1 if vertex i of the remaining polygon (links next, prev) is an ear: convex, no other vertex in or on it. */
static int is_ear(const double (*q)[2], const int *next, const int *prev, int i)
{
    const double *a = q[prev[i]], *b = q[i], *c = q[next[i]];
    if (!(orient(a, b, c) > 0))
        return 0;
    for (int j = next[next[i]]; j != prev[i]; j = next[j]) {
        const double *p = q[j];
        if ((p[0] == a[0] && p[1] == a[1]) || (p[0] == c[0] && p[1] == c[1]))
            continue; /* a vertex repeated where the boundary touches itself */
        if (orient(a, b, p) >= 0 && orient(b, c, p) >= 0 && orient(c, a, p) >= 0)
            return 0;
    }
    return 1;
}

/*
 * Triangulates the counter-clockwise polygon q[0..m) by ear clipping; link
 * holds 2m ints. @return the number of triangles (m - 2), written to tri as
 * indices into q, or 0 when no ear is left (the polygon crosses itself).
 */
static size_t ear_clip(const double (*q)[2], size_t m, int *link, size_t (*tri)[3])
{
    int *next = link, *prev = link + m;
    for (size_t i = 0; i < m; i++) {
        next[i] = (int)((i + 1) % m);
        prev[i] = (int)((i + m - 1) % m);
    }
    size_t left = m, count = 0, misses = 0;
    int i = 0;
    while (left > 3) {
        if (is_ear(q, next, prev, i)) {
            size_t *t = tri[count++];
            t[0] = (size_t)prev[i], t[1] = (size_t)i, t[2] = (size_t)next[i];
            next[prev[i]] = next[i];
            prev[next[i]] = prev[i];
            i = prev[i];
            left--;
            misses = 0;
        } else {
            if (++misses > left)
                return 0;
            i = next[i];
        }
    }
    size_t *t = tri[count++];
    t[0] = (size_t)prev[i], t[1] = (size_t)i, t[2] = (size_t)next[i];
    return count;
}

/* ----------------------------------------------------------- appending */

/* Appends pts (n <= RL_SCENE_MAX_POLY_VERTS, convex, planar, normal given) as one polygon.
 * @return RL_OK; RL_ERR_INPUT past the limits; RL_ERR_NOMEM. */
static rl_status append_vertices(rl_build *b, const v3 *pts, size_t n, v3 normal, uint32_t material,
                                 const char *label)
{
    rl_scene *s = b->scene;
    if (s->npolygons >= RL_MAX_ELEMENTS)
        return rl__build_fail(b, label, "the scene has more than %zu polygons, the limit", RL_MAX_ELEMENTS);
    if (n > RL_MAX_ELEMENTS - s->nvertices)
        return rl__build_fail(b, label, "the scene has more than %zu vertices, the limit", RL_MAX_ELEMENTS);
    void *v = rl__grow(s->vertices, &b->vertex_cap, s->nvertices + n, sizeof *s->vertices);
    if (v)
        s->vertices = v;
    void *p = v ? rl__grow(s->polygons, &b->polygon_cap, s->npolygons + 1, sizeof *s->polygons) : NULL;
    if (!p)
        return rl__fail(RL_ERR_NOMEM, "%s: out of memory", b->file);
    s->polygons = p;

    rl_polygon *poly = &s->polygons[s->npolygons++];
    memset(poly, 0, sizeof *poly);
    poly->first = (uint32_t)s->nvertices;
    poly->count = (uint32_t)n;
    poly->material = material;
    v3_store(normal, poly->normal);
    double area = 0.0;
    for (size_t i = 1; i + 1 < n; i++)
        area += 0.5 * v3_dot(v3_cross(v3_sub(pts[i], pts[0]), v3_sub(pts[i + 1], pts[0])), normal);
    poly->area = area;
    ilf_format_cut(poly->label, sizeof poly->label, "%s", label);
    for (size_t i = 0; i < n; i++)
        v3_store(pts[i], s->vertices[s->nvertices++]);
    return RL_OK;
}

/* Appends the kept vertices of c as one polygon, or, past the engine's
 * RL_SCENE_MAX_POLY_VERTS, as a fan of convex pieces that share vertex 0
 * (labelled "piece K"). @return as append_vertices(). */
static rl_status append_polygon(rl_build *b, const poly_check *c, uint32_t material, const char *label)
{
    v3 pts[RL_SCENE_MAX_POLY_VERTS];
    if (c->n <= RL_SCENE_MAX_POLY_VERTS) {
        for (size_t i = 0; i < c->n; i++)
            pts[i] = kept(c, i);
        return append_vertices(b, pts, c->n, c->normal, material, label);
    }
    rl_status st = RL_OK;
    for (size_t first = 1, piece = 0; first + 1 < c->n && st == RL_OK; piece++) {
        size_t last = first + RL_SCENE_MAX_POLY_VERTS - 2 < c->n - 1 ? first + RL_SCENE_MAX_POLY_VERTS - 2 : c->n - 1;
        size_t m = 0;
        pts[m++] = kept(c, 0);
        for (size_t i = first; i <= last; i++)
            pts[m++] = kept(c, i);
        char name[sizeof ((rl_polygon *)0)->label];
        ilf_format_cut(name, sizeof name, "%s piece %zu", label, piece);
        st = append_vertices(b, pts, m, c->normal, material, name);
        first = last;
    }
    return st;
}

/* Takes one triangle of a split face: part (checked, its keep indexing at, which holds indices into
 * the face's input vertices), numbered t. @return RL_OK, or a status that stops the split. */
typedef rl_status (*part_sink)(rl_build *b, void *ctx, const poly_check *part, const size_t at[3], size_t t);

/* Ear clips the cleaned face c and hands its non-degenerate triangles to sink. @return as rl__build_polygon(). */
static rl_status clip_face(rl_build *b, poly_check *c, const char *label, part_sink sink, void *ctx)
{
    project(c, b->flat);
    size_t count = ear_clip((const double (*)[2])b->flat, c->n, b->link, b->tris);
    if (count == 0)
        return rl__build_fail(b, label, "cannot be split into triangles (the face crosses itself)");
    for (size_t t = 0; t < count; t++)
        for (int k = 0; k < 3; k++)
            b->tris[t][k] = c->keep[b->tris[t][k]]; /* into the input: keep is reused below */
    for (size_t t = 0; t < count; t++) {
        double corners[3][3];
        for (int k = 0; k < 3; k++)
            memcpy(corners[k], c->p[b->tris[t][k]], sizeof corners[k]);
        poly_check part = {.p = (const double (*)[3])corners, .keep = b->keep};
        if (check_polygon(&part, 3, 1) != V_OK)
            continue; /* a sliver: no area to carry light */
        rl_status st = sink(b, ctx, &part, b->tris[t], t);
        if (st != RL_OK)
            return st;
    }
    return RL_OK;
}

/* What append_part() appends with. */
typedef struct append_ctx {
    uint32_t material;
    const char *label;
} append_ctx;

/* A part_sink that appends the triangle as a polygon labelled "<label> part <t>". */
static rl_status append_part(rl_build *b, void *ctx, const poly_check *part, const size_t at[3], size_t t)
{
    (void)at;
    const append_ctx *a = ctx;
    char name[sizeof ((rl_polygon *)0)->label];
    ilf_format_cut(name, sizeof name, "%s part %zu", a->label, t);
    return append_polygon(b, part, a->material, name);
}

/* @return the index of the first of the n vertices with a coordinate that is not finite, or n. */
static size_t first_nonfinite(const double (*v)[3], size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!isfinite(v[i][0]) || !isfinite(v[i][1]) || !isfinite(v[i][2]))
            return i;
    return n;
}

rl_status rl__build_polygon(rl_build *b, const double (*v)[3], size_t n, uint32_t material,
                            const char *label, rl_poly_policy policy)
{
    if (n < 3)
        return policy == RL_POLY_STRICT
                   ? rl__build_fail(b, label, "needs at least 3 vertices, got %zu", n)
                   : RL_OK;
    size_t bad = first_nonfinite(v, n);
    if (bad < n)
        return rl__build_fail(b, label, "vertex %zu is not finite", bad);

    poly_check c = {.p = v, .keep = b->keep};
    verdict outcome = check_polygon(&c, n, policy == RL_POLY_SPLIT);
    if (outcome == V_OK)
        return append_polygon(b, &c, material, label);
    if (policy == RL_POLY_STRICT)
        return rl__build_fail(b, label, "%s", c.why);
    if (outcome == V_DEGENERATE)
        return RL_OK; /* a mesh face without area carries no light */
    append_ctx a = {material, label};
    return clip_face(b, &c, label, append_part, &a);
}

/* ----------------------------------------------------------- mesh files */

/* Marks a file material not yet turned into a scene material. */
#define MATERIAL_UNSET UINT32_MAX

/*
 * Finds the scene material for file material k: "<shown>:<name>" with the
 * diffuse colour as albedo and the emissive colour as emission, or *fallback
 * when the file has none. @return RL_OK and *out; RL_ERR_INPUT; RL_ERR_NOMEM.
 */
static rl_status file_material(rl_build *b, const ilf_mesh *mesh, uint32_t k, const char *elem,
                               const char *shown, const uint32_t *fallback, uint32_t *out)
{
    const ilf_mesh_material *fm = k < mesh->nmaterials ? &mesh->materials[k] : NULL;
    if (!fm || fm->name[0] == '\0') {
        if (!fallback)
            return rl__build_fail(b, elem, "%s has faces without a material; give the entry a \"material\"",
                                  shown);
        *out = *fallback;
        return RL_OK;
    }
    double albedo[3] = {0.8, 0.8, 0.8}, emission[3] = {0, 0, 0};
    if (fm->has_diffuse)
        memcpy(albedo, fm->diffuse, sizeof albedo);
    if (fm->has_emissive)
        memcpy(emission, fm->emissive, sizeof emission);
    char full[256], where[320];
    ilf_format_cut(full, sizeof full, "%s:%s", shown, fm->name);
    ilf_format_cut(where, sizeof where, "%s (%s) material '%s'", elem, shown, fm->name);
    return rl__build_material(b, where, full, albedo, emission, out);
}

/* Turns every vertex of mesh so that the axis opt chooses (or the file declares) points up (+z). */
static void turn_up(ilf_mesh *mesh, rl_mesh_up up)
{
    if (up == RL_MESH_UP_DECLARED)
        up = mesh->up == ILF_MESH_UP_Y ? RL_MESH_UP_Y : RL_MESH_UP_Z;
    if (up != RL_MESH_UP_Y)
        return;
    for (size_t k = 0; k < mesh->nvertices; k++) {
        double y = mesh->vertices[k][1], z = mesh->vertices[k][2];
        mesh->vertices[k][1] = -z; /* a quarter turn about x: +y to +z, and glTF's forward -z to +y */
        mesh->vertices[k][2] = y;
    }
}

/*
 * Merging. Faces that are planar and convex as they stand (the usual case:
 * triangles, and quads), and the triangles of faces that had to be split,
 * are pooled as loops of welded vertex ids: vertices
 * at bit-identical positions share an id, so that triangles of one quad,
 * which exporters write with the same coordinates whether or not they share
 * an index, find their common edge. Then, in passes until nothing changes,
 * every edge that exactly two pooled loops share, one running a->b and the
 * other b->a (consistent winding, so they face the same way), joins them
 * when they have the same material, every vertex of the pair lies within
 * plane_tol of the pair's diameter of the first loop's plane, and the union
 * stays strictly convex (vertices left on a straight line are dropped) with
 * at most RL_SCENE_MAX_POLY_VERTS vertices. A loop joins at most once per
 * pass, so each pass reads loops that do not change under it; the union
 * keeps the first loop's starting vertex, so a quad written as two
 * triangles (0 1 2) (0 2 3) comes back as the quad 0 1 2 3. Non-convex
 * unions are not formed: a wall with a hole stays in convex pieces. At most
 * ILF_MESH_MERGE_MAX_PASSES passes are made (ilf/limits.h says why).
 */

/* A pooled loop: ids[start .. start + n) of its pool. */
typedef struct loop {
    size_t start;
    uint32_t n;
    uint32_t material;
    uint32_t face;   /* the smallest face number joined into it, for its label */
    uint32_t joined; /* how many faces besides that one */
    uint32_t part;   /* which triangle of a split face it is, or NO_PART */
    v3 normal;
} loop;

/* loop.part of a whole face. */
#define NO_PART UINT32_MAX

/* The pooled loops of one mesh file. */
typedef struct pool {
    loop *loops;
    size_t nloops, loop_cap;
    uint32_t *ids;
    size_t nids, id_cap;
    const double (*at)[3]; /* position of each welded id */
} pool;

/* One directed edge of a pooled loop, keyed by its unordered ends. */
typedef struct edge {
    uint32_t lo, hi; /* its ends, lo < hi */
    uint32_t loop;   /* which loop */
    uint32_t i;      /* it runs from vertex i of the loop to vertex i + 1 */
} edge;

/* qsort order of edges: by ends, then loop. */
static int edge_order(const void *pa, const void *pb)
{
    const edge *a = pa, *b = pb;
    if (a->lo != b->lo)
        return a->lo < b->lo ? -1 : 1;
    if (a->hi != b->hi)
        return a->hi < b->hi ? -1 : 1;
    return a->loop < b->loop ? -1 : a->loop > b->loop;
}

/* A vertex with its index, for welding. */
typedef struct weld_item {
    double p[3];
    uint32_t index;
} weld_item;

/* qsort order of positions: lexicographic, NaN after every number, so the order is total. */
static int weld_order(const void *pa, const void *pb)
{
    const weld_item *a = pa, *b = pb;
    for (int c = 0; c < 3; c++) {
        int na = isnan(a->p[c]), nb = isnan(b->p[c]);
        if (na != nb)
            return na - nb;
        if (!na && a->p[c] != b->p[c])
            return a->p[c] < b->p[c] ? -1 : 1;
    }
    return 0;
}

/* Gives each vertex of mesh the id of the first vertex at its exact position (id[k] <= k).
 * @return id (nvertices), or NULL for memory. */
static uint32_t *weld(const ilf_mesh *mesh)
{
    uint32_t *id = malloc((mesh->nvertices ? mesh->nvertices : 1) * sizeof *id);
    weld_item *w = malloc((mesh->nvertices ? mesh->nvertices : 1) * sizeof *w);
    if (!id || !w) {
        free(id);
        free(w);
        return NULL;
    }
    for (size_t k = 0; k < mesh->nvertices; k++) {
        memcpy(w[k].p, mesh->vertices[k], sizeof w[k].p);
        w[k].index = (uint32_t)k;
    }
    qsort(w, mesh->nvertices, sizeof *w, weld_order);
    /* the smallest index of each run of equal positions names the run */
    for (size_t k = 0; k < mesh->nvertices;) {
        size_t end = k + 1;
        uint32_t least = w[k].index;
        while (end < mesh->nvertices && weld_order(&w[end], &w[k]) == 0)
            least = w[end].index < least ? w[end].index : least, end++;
        for (size_t m = k; m < end; m++)
            id[w[m].index] = least;
        k = end;
    }
    free(w);
    return id;
}

/* Appends a loop of n ids to p. @return 1, or 0 for memory. */
static int pool_add(pool *p, const uint32_t *ids, uint32_t n, loop head)
{
    void *l = rl__grow(p->loops, &p->loop_cap, p->nloops + 1, sizeof *p->loops);
    if (l)
        p->loops = l;
    void *i = l ? rl__grow(p->ids, &p->id_cap, p->nids + n, sizeof *p->ids) : NULL;
    if (!i)
        return 0;
    p->ids = i;
    head.start = p->nids;
    head.n = n;
    memcpy(p->ids + p->nids, ids, n * sizeof *ids);
    p->nids += n;
    p->loops[p->nloops++] = head;
    return 1;
}

/* @return the position of vertex i (cyclic) of loop l. */
static v3 loop_at(const pool *p, const loop *l, size_t i)
{
    return v3_load(p->at[p->ids[l->start + i % l->n]]);
}

/*
 * Joins loop a (its edge from vertex i) with loop c (its edge from vertex j,
 * the same edge reversed) into out (RL_SCENE_MAX_POLY_VERTS + 2 ids) when
 * their union is coplanar and strictly convex. @return its vertex count, or
 * 0 when they do not join.
 */
static uint32_t join(const pool *p, const loop *a, uint32_t i, const loop *c, uint32_t j, uint32_t *out)
{
    if (a->material != c->material || a->n + c->n - 2 > RL_SCENE_MAX_POLY_VERTS + 2)
        return 0;
    uint32_t m = 0;
    for (uint32_t k = 0; k <= i; k++)
        out[m++] = p->ids[a->start + k];
    for (uint32_t k = 2; k < c->n; k++)
        out[m++] = p->ids[c->start + (j + k) % c->n];
    for (uint32_t k = i + 1; k < a->n; k++)
        out[m++] = p->ids[a->start + k];
    double pts[RL_SCENE_MAX_POLY_VERTS + 2][3];
    for (uint32_t k = 0; k < m; k++)
        memcpy(pts[k], p->at[out[k]], sizeof pts[k]);
    size_t keep[RL_SCENE_MAX_POLY_VERTS + 2];
    poly_check chk = {.p = (const double (*)[3])pts, .keep = keep};
    chk.diameter = diameter(chk.p, m);
    chk.tol = plane_tol * chk.diameter;
    v3 o = loop_at(p, a, 0);
    for (uint32_t k = 0; k < m; k++)
        if (fabs(v3_dot(v3_sub(v3_load(pts[k]), o), a->normal)) > chk.tol)
            return 0; /* not coplanar */
    for (size_t k = 0; k < m; k++)
        keep[k] = k;
    chk.n = m;
    chk.normal = a->normal;
    if (!drop_collinear(&chk, 0) || chk.n < 3 || chk.n > RL_SCENE_MAX_POLY_VERTS || !check_convex(&chk))
        return 0;
    for (size_t k = 0; k < chk.n; k++)
        out[k] = out[keep[k]];
    return (uint32_t)chk.n;
}

/* partner[] of a loop joined into another in this pass. */
#define ABSORBED (UINT32_MAX - 1)

/*
 * One pass of merging over p: joins pairs across shared edges, each loop at
 * most once, and compacts the pool. A pair found joinable is recorded by its
 * owner (the loop whose edge came first: partner and the two edge
 * positions) and joined again while the pool is compacted, so that a pass
 * needs 16 bytes per loop besides its edges. @return the number of joins,
 * or -1 for memory.
 */
static long merge_pass(pool *p)
{
    size_t nl = p->nloops ? p->nloops : 1;
    edge *e = malloc((p->nids ? p->nids : 1) * sizeof *e);
    uint32_t *partner = malloc(nl * 3 * sizeof *partner); /* partner, then edge i and j of owners */
    pool next = {.at = p->at};
    long joins = 0;
    if (!e || !partner) {
        joins = -1;
        goto done;
    }
    size_t ne = 0;
    for (uint32_t l = 0; l < p->nloops; l++) {
        partner[l] = UINT32_MAX;
        const loop *lp = &p->loops[l];
        for (uint32_t i = 0; i < lp->n; i++) {
            uint32_t u = p->ids[lp->start + i], v = p->ids[lp->start + (i + 1) % lp->n];
            e[ne++] = (edge){u < v ? u : v, u < v ? v : u, l, i};
        }
    }
    qsort(e, ne, sizeof *e, edge_order);
    uint32_t scratch[RL_SCENE_MAX_POLY_VERTS + 2];
    for (size_t k = 0; k + 1 < ne;) {
        size_t end = k + 1;
        while (end < ne && e[end].lo == e[k].lo && e[end].hi == e[k].hi)
            end++;
        const edge *x = &e[k], *y = &e[k + 1];
        /* exactly two loops on the edge, both free this pass, running it opposite ways */
        if (end - k == 2 && x->loop != y->loop && partner[x->loop] == UINT32_MAX &&
            partner[y->loop] == UINT32_MAX &&
            p->ids[p->loops[x->loop].start + x->i] != p->ids[p->loops[y->loop].start + y->i] &&
            join(p, &p->loops[x->loop], x->i, &p->loops[y->loop], y->i, scratch) > 0) {
            partner[x->loop] = y->loop;
            partner[nl + x->loop] = x->i;
            partner[2 * nl + x->loop] = y->i;
            partner[y->loop] = ABSORBED;
            joins++;
        }
        k = end;
    }
    for (uint32_t l = 0; l < p->nloops && joins >= 0; l++) {
        loop head = p->loops[l];
        const uint32_t *ids = p->ids + head.start;
        if (partner[l] == ABSORBED)
            continue;
        if (partner[l] != UINT32_MAX) {
            const loop *other = &p->loops[partner[l]];
            head.n = join(p, &head, partner[nl + l], other, partner[2 * nl + l], scratch);
            ids = scratch;
            head.face = head.face < other->face ? head.face : other->face;
            head.joined += other->joined + 1;
        }
        if (!pool_add(&next, ids, head.n, head))
            joins = -1;
    }
done:
    free(e);
    free(partner);
    if (joins >= 0) {
        free(p->loops);
        free(p->ids);
        *p = next;
    } else {
        free(next.loops);
        free(next.ids);
    }
    return joins;
}

/* Copies face f of the imported mesh into b->face. @return RL_OK, or RL_ERR_INPUT for too many vertices. */
static rl_status gather_face(rl_build *b, const ilf_mesh *mesh, const ilf_mesh_face *f, const char *label)
{
    if (f->count > RL_MAX_POLYGON_VERTICES)
        return rl__build_fail(b, label, "has %u vertices, more than the limit of %u", f->count,
                              RL_MAX_POLYGON_VERTICES);
    for (uint32_t k = 0; k < f->count; k++)
        memcpy(b->face[k], mesh->vertices[mesh->indices[f->first + k]], sizeof b->face[k]);
    return RL_OK;
}

/* Reverses the n vertices of b->face. */
static void reverse_face(rl_build *b, size_t n)
{
    for (size_t i = 0, j = n - 1; i < j; i++, j--) {
        double t[3];
        memcpy(t, b->face[i], sizeof t);
        memcpy(b->face[i], b->face[j], sizeof t);
        memcpy(b->face[j], t, sizeof t);
    }
}

/* Adds the n vertices of b->face as a mesh face: as they are, turned over (flip), or both ways (two_sided;
 * the turned copy labelled "back"). @return as rl__build_polygon(). */
static rl_status emit_face(rl_build *b, size_t n, uint32_t material, const char *label, const rl_mesh_options *opt)
{
    rl_status st = RL_OK;
    if (!opt->flip || opt->two_sided)
        st = rl__build_polygon(b, (const double (*)[3])b->face, n, material, label, RL_POLY_SPLIT);
    if (st != RL_OK || (!opt->flip && !opt->two_sided))
        return st;
    char back[sizeof ((rl_polygon *)0)->label];
    ilf_format_cut(back, sizeof back, "%s%s", label, opt->two_sided ? " back" : "");
    reverse_face(b, n);
    return rl__build_polygon(b, (const double (*)[3])b->face, n, material, back, RL_POLY_SPLIT);
}

/* Writes the label of a mesh polygon: elem, the file's name (its end when long), the face, and the part
 * of a split face left alone or the number of faces merged into it. */
static void face_label(char *out, size_t cap, const char *elem, const char *shown, size_t face, uint32_t part,
                       uint32_t joined)
{
    size_t len = strlen(shown); /* a long name keeps its end, where the file's own name is */
    char more[32] = "";
    if (joined > 0)
        ilf_format_cut(more, sizeof more, " (+%u merged)", joined);
    else if (part != NO_PART)
        ilf_format_cut(more, sizeof more, " part %u", part);
    ilf_format_cut(out, cap, "%s (%s%s) face %zu%s", elem, len > 40 ? "..." : "", len > 40 ? shown + len - 37 : shown,
               face, more);
}

/* What add_faces() needs besides the builder. */
typedef struct mesh_job {
    const ilf_mesh *mesh;
    const uint32_t *id; /* welded id of each vertex */
    uint32_t *materials; /* scene material per file material, MATERIAL_UNSET until needed */
    const char *elem, *shown;
    const rl_mesh_options *opt;
    pool pool;
} mesh_job;

/* Pools n ids of loop head (its material, face, part and normal set). @return RL_OK or RL_ERR_NOMEM. */
static rl_status pool_loop(rl_build *b, mesh_job *job, const uint32_t *ids, size_t n, loop head)
{
    return pool_add(&job->pool, ids, (uint32_t)n, head) ? RL_OK : rl__fail(RL_ERR_NOMEM, "%s: out of memory", b->file);
}

/* What pool_part() pools with. */
typedef struct pool_ctx {
    mesh_job *job;
    const ilf_mesh_face *face;
    loop head;
} pool_ctx;

/* A part_sink that pools the triangle of a split face. */
static rl_status pool_part(rl_build *b, void *ctx, const poly_check *part, const size_t at[3], size_t t)
{
    pool_ctx *pc = ctx;
    uint32_t ids[3];
    for (size_t k = 0; k < part->n; k++)
        ids[k] = pc->job->id[pc->job->mesh->indices[pc->face->first + at[part->keep[k]]]];
    loop head = pc->head;
    head.part = (uint32_t)t;
    head.normal = part->normal;
    return pool_loop(b, pc->job, ids, part->n, head);
}

/*
 * Pools face f (in b->face, checked finite) when it is planar and convex,
 * or its triangles when it has to be split (so that they can merge back
 * into convex pieces); drops it when it has no area; adds a planar convex
 * face too large to join anything at once. @return as rl__build_polygon(),
 * or RL_ERR_NOMEM.
 */
static rl_status take_face(rl_build *b, mesh_job *job, size_t face_no, uint32_t material, const char *label)
{
    const ilf_mesh_face *f = &job->mesh->faces[face_no];
    poly_check c = {.p = (const double (*)[3])b->face, .keep = b->keep};
    verdict v = check_polygon(&c, f->count, 1);
    loop head = {.material = material, .face = (uint32_t)face_no, .part = NO_PART, .normal = c.normal};
    if (v == V_DEGENERATE)
        return RL_OK; /* a face without area carries no light */
    if (v != V_OK) {
        pool_ctx pc = {job, f, head};
        return clip_face(b, &c, label, pool_part, &pc);
    }
    if (c.n > RL_SCENE_MAX_POLY_VERTS)
        return emit_face(b, f->count, material, label, job->opt);
    uint32_t ids[RL_SCENE_MAX_POLY_VERTS];
    for (size_t k = 0; k < c.n; k++)
        ids[k] = job->id[job->mesh->indices[f->first + c.keep[k]]];
    return pool_loop(b, job, ids, c.n, head);
}

/* Reads every face of the imported mesh: material, vertices, then pooled or added. @return as rl__build_mesh(). */
static rl_status add_faces(rl_build *b, mesh_job *job)
{
    const ilf_mesh *mesh = job->mesh;
    for (size_t face_no = 0; face_no < mesh->nfaces; face_no++) {
        const ilf_mesh_face *f = &mesh->faces[face_no];
        if (f->count < 3)
            continue; /* points and lines carry no light */
        char label[sizeof ((rl_polygon *)0)->label];
        face_label(label, sizeof label, job->elem, job->shown, face_no, NO_PART, 0);
        rl_status st = gather_face(b, mesh, f, label);
        size_t k = f->material < mesh->nmaterials ? f->material : mesh->nmaterials;
        if (st == RL_OK && job->materials[k] == MATERIAL_UNSET)
            st = file_material(b, mesh, (uint32_t)k, job->elem, job->shown, job->opt->fallback, &job->materials[k]);
        size_t bad = st == RL_OK ? first_nonfinite((const double (*)[3])b->face, f->count) : f->count;
        if (bad < f->count) /* before the face is pooled, whose checks assume finite coordinates */
            st = rl__build_fail(b, label, "vertex %zu is not finite", bad);
        if (st == RL_OK)
            st = take_face(b, job, face_no, job->materials[k], label);
        if (st != RL_OK)
            return st;
    }
    return RL_OK;
}

/* qsort order of loops: by first face. */
static int loop_order(const void *pa, const void *pb)
{
    const loop *a = pa, *b = pb;
    return a->face < b->face ? -1 : a->face > b->face;
}

/* Merges the pooled faces and adds what remains, in the order of their first faces. @return as rl__build_mesh(). */
static rl_status add_pool(rl_build *b, mesh_job *job)
{
    long joins = 1;
    for (int pass = 0; pass < ILF_MESH_MERGE_MAX_PASSES && joins > 0; pass++)
        joins = merge_pass(&job->pool);
    if (joins < 0)
        return rl__fail(RL_ERR_NOMEM, "%s: out of memory", b->file);
    if (job->pool.nloops > 1) /* loops is NULL when nothing was pooled */
        qsort(job->pool.loops, job->pool.nloops, sizeof *job->pool.loops, loop_order);
    rl_status st = RL_OK;
    for (size_t l = 0; l < job->pool.nloops && st == RL_OK; l++) {
        const loop *lp = &job->pool.loops[l];
        for (uint32_t k = 0; k < lp->n; k++)
            memcpy(b->face[k], job->pool.at[job->pool.ids[lp->start + k]], sizeof b->face[k]);
        char label[sizeof ((rl_polygon *)0)->label];
        face_label(label, sizeof label, job->elem, job->shown, lp->face, lp->part, lp->joined);
        st = emit_face(b, lp->n, lp->material, label, job->opt);
    }
    return st;
}

rl_status rl__build_mesh(rl_build *b, const char *path, const char *elem, const char *shown,
                         const rl_mesh_options *opt)
{
    ilf_mesh *mesh = NULL;
    char why[ILF_MESSAGE_BYTES];
    ilf_mesh_status ms = ilf_mesh_import(path, &mesh, why, sizeof why);
    if (ms == ILF_MESH_ERR_NOMEM)
        return rl__fail(RL_ERR_NOMEM, "%s: out of memory", b->file);
    if (ms != ILF_MESH_OK)
        return rl__build_fail(b, elem, "%s", why);
    turn_up(mesh, opt->up);
    /* one slot per file material, plus one for meshes whose material index is out of range */
    mesh_job job = {.mesh = mesh, .elem = elem, .shown = shown, .opt = opt, .pool.at = mesh->vertices};
    job.materials = malloc((mesh->nmaterials + 1) * sizeof *job.materials);
    uint32_t *id = weld(mesh);
    job.id = id;
    rl_status st = RL_OK;
    if (!job.materials || !id)
        st = rl__fail(RL_ERR_NOMEM, "%s: out of memory", b->file);
    for (size_t k = 0; st == RL_OK && k <= mesh->nmaterials; k++)
        job.materials[k] = MATERIAL_UNSET;
    size_t before = b->scene->npolygons, faces = mesh->nfaces;
    if (st == RL_OK)
        st = add_faces(b, &job);
    if (st == RL_OK)
        st = add_pool(b, &job);
    free(job.pool.loops);
    free(job.pool.ids);
    free(job.materials);
    free(id);
    ilf_mesh_destroy(mesh);
    /* Every face dropped (points, lines, no area): nothing to light or be lit, almost surely a broken file. */
    if (st == RL_OK && b->scene->npolygons == before)
        return rl__build_fail(b, elem, "'%s' has no face with area (%zu faces, all points, lines or degenerate)",
                              path, faces);
    return st;
}
