/*
 * region.c - convex clipping and the projected Minkowski sum (S + w)_R.
 *
 * For a point y of S and a direction d of the cone K, the ray y + t*d meets
 * R's plane at the point whose homogeneous coordinates are
 *     H(y, d) = (y2 * w + h * d2, w),  w = -d.n >= 0, h = (y - o).n >= 0,
 * where y2 and d2 are the in-plane components. H is bilinear in (y, d), so
 * every H(y, d) is a positive combination of the H of S's vertices and K's
 * generators, and the region is exactly {p : (p, 1) in cone(H_ij)}. That
 * cone's facets give the half-planes. Rays parallel to the plane (w = 0) are
 * directions at infinity, which the homogeneous form carries with no
 * division; everything stays finite. Whenever the geometry is too
 * degenerate to trust, the region is "all", which is conservative: it can
 * only cost work, never drop light.
 */
#include <assert.h>
#include <stdlib.h>
#include <string.h>

#include "region.h"

size_t rl__clip_poly3(const v3 *p, size_t count, v3 o, v3 n, v3 *out)
{
    size_t m = 0;
    for (size_t i = 0; i < count; i++) {
        v3 a = p[i], b = p[(i + 1) % count];
        double da = v3_dot(v3_sub(a, o), n), db = v3_dot(v3_sub(b, o), n);
        if (da >= 0)
            out[m++] = a;
        if ((da >= 0) != (db >= 0)) {
            double t = da / (da - db);
            out[m++] = v3_madd(a, v3_sub(b, a), t);
        }
    }
    return m;
}

size_t rl__clip_to_view(v3 x, const v3 g[3], const v3 *src, size_t n, v3 *out)
{
    v3 buf[RL_MAX_POLY_VERTS + 8];
    const v3 *cur = src;
    v3 *dst[3] = {out, buf, out};
    for (int k = 0; k < 3 && n >= 3; k++) {
        /* y is seen along the cone when x - y lies on g[k+2]'s side of the plane of g[k], g[k+1] */
        v3 m = v3_cross(g[k], g[(k + 1) % 3]);
        if (v3_dot(m, g[(k + 2) % 3]) < 0)
            m = v3_scale(m, -1.0);
        n = rl__clip_poly3(cur, n, x, v3_scale(m, -1.0), dst[k]);
        cur = dst[k];
    }
    return n >= 3 ? n : 0;
}

/* @return the centroid of the convex polygon p (count vertices). */
v2 rl__polygon_centroid(const v2 *p, uint32_t count)
{
    double a = 0, cx = 0, cy = 0;
    for (uint32_t i = 1; i + 1 < count; i++) {
        double w = v2_cross(v2_sub(p[i], p[0]), v2_sub(p[i + 1], p[0]));
        a += w;
        cx += w * (p[0].x + p[i].x + p[i + 1].x) / 3;
        cy += w * (p[0].y + p[i].y + p[i + 1].y) / 3;
    }
    return a > 0 ? (v2){cx / a, cy / a} : p[0];
}

size_t rl__clip_poly2(const v2 *p, size_t count, rl_halfplane h, v2 *out)
{
    size_t m = 0;
    for (size_t i = 0; i < count; i++) {
        v2 a = p[i], b = p[(i + 1) % count];
        double da = h.a * a.x + h.b * a.y + h.c, db = h.a * b.x + h.b * b.y + h.c;
        if (da >= 0)
            out[m++] = a;
        if ((da >= 0) != (db >= 0)) {
            double t = da / (da - db);
            out[m++] = (v2){a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)};
        }
    }
    return m;
}

size_t rl__clip_to_polygon(const v2 *p, size_t count, const v2 *clip, size_t nclip, v2 *out, v2 *scratch)
{
    v2 *cur = out, *next = scratch;
    if (p != out)
        memmove(out, p, count * sizeof *p);
    for (size_t e = 0; e < nclip && count > 0; e++) {
        count = rl__clip_poly2(cur, count, edge_halfplane(clip[e], clip[(e + 1) % nclip]), next);
        v2 *t = cur;
        cur = next;
        next = t;
    }
    if (cur != out)
        memcpy(out, cur, count * sizeof *cur);
    return count;
}

size_t rl__clip_to_region(const v2 *p, size_t count, const rl_region *r, v2 *out, size_t out_cap)
{
    if (r->empty)
        return 0;
    /* On the stack: this runs for every node of every walk, and cannot fail. */
    enum { CAP = RL_MAX_POLY_VERTS + 4 + RL_REGION_MAX_PLANES };
    v2 buf[2][CAP];
    assert(out_cap <= CAP && count <= out_cap);
    (void)out_cap;
    v2 *cur = buf[0], *next = buf[1];
    memcpy(cur, p, count * sizeof *p);
    size_t m = count;
    for (size_t k = 0; !r->all && k < r->count && m > 0; k++) {
        m = rl__clip_poly2(cur, m, r->h[k], next);
        v2 *t = cur;
        cur = next;
        next = t;
    }
    memcpy(out, cur, m * sizeof *cur);
    return m;
}

int rl__region_contains(const rl_region *r, v2 q)
{
    if (r->empty)
        return 0;
    if (r->all)
        return 1;
    for (size_t k = 0; k < r->count; k++)
        if (r->h[k].a * q.x + r->h[k].b * q.y + r->h[k].c < 0)
            return 0;
    return 1;
}

size_t rl__clip_cone(const v3 *g, size_t count, v3 n, v3 *out)
{
    size_t m = 0;
    for (size_t i = 0; i < count; i++) {
        v3 a = g[i], b = g[(i + 1) % count];
        double da = v3_dot(a, n), db = v3_dot(b, n);
        if (da <= 0)
            out[m++] = a;
        if ((da <= 0) != (db <= 0)) {
            double t = da / (da - db);
            out[m++] = v3_norm(v3_madd(a, v3_sub(b, a), t));
        }
    }
    return m;
}

/* Orders points by x, then y, for the hull. */
static int cmp_v2(const void *pa, const void *pb)
{
    const v2 *a = pa, *b = pb;
    if (a->x != b->x)
        return a->x < b->x ? -1 : 1;
    return (a->y > b->y) - (a->y < b->y);
}

/* Andrew's monotone chain. */
size_t rl__convex_hull2(v2 *pts, size_t n, v2 *hull)
{
    qsort(pts, n, sizeof *pts, cmp_v2);
    size_t k = 0;
    for (size_t i = 0; i < n; i++) {
        while (k >= 2 && v2_cross(v2_sub(hull[k - 1], hull[k - 2]), v2_sub(pts[i], hull[k - 2])) <= 0)
            k--;
        hull[k++] = pts[i];
    }
    for (size_t i = n - 1, t = k + 1; i-- > 0;) {
        while (k >= t && v2_cross(v2_sub(hull[k - 1], hull[k - 2]), v2_sub(pts[i], hull[k - 2])) <= 0)
            k--;
        hull[k++] = pts[i];
    }
    return k > 1 ? k - 1 : k;
}

/* Marks r as the whole plane (the conservative answer). */
static void region_all(rl_region *r)
{
    r->all = 1;
    r->empty = 0;
    r->count = 0;
}

void rl__region_compute(const rl_frame *f, const v3 *s, size_t ns, const v3 *k, size_t nk, double margin,
                    rl_region *out)
{
    enum { MAXH = RL_MAX_POLY_VERTS * 8 };
    v3 h3[MAXH];
    size_t nh = 0;
    int finite = 0;
    out->empty = out->all = 0;
    out->count = 0;
    if (ns == 0 || nk == 0) {
        out->empty = 1;
        return;
    }
    /* A length scale so that the W axis is commensurate with X and Y. */
    double scale = 0.0;
    for (size_t i = 0; i < ns; i++) {
        v2 q = frame_project(f, s[i]);
        scale = fmax(scale, fmax(fabs(q.x), fabs(q.y)));
        scale = fmax(scale, v3_dot(v3_sub(s[i], f->origin), f->n));
    }
    if (!(scale > 0.0) || !isfinite(scale)) {
        region_all(out);
        return;
    }
    for (size_t i = 0; i < ns && nh < MAXH; i++) {
        v2 y2 = frame_project(f, s[i]);
        double h = fmax(0.0, v3_dot(v3_sub(s[i], f->origin), f->n));
        for (size_t j = 0; j < nk && nh < MAXH; j++) {
            double w = fmax(0.0, -v3_dot(k[j], f->n));
            v3 H = {y2.x * w + h * v3_dot(k[j], f->e1), y2.y * w + h * v3_dot(k[j], f->e2), w * scale};
            double len = v3_len(H);
            if (!(len > 1e-300 * scale))
                continue; /* a point of S on R's plane moving along it: no area */
            finite |= w > 0.0;
            h3[nh++] = v3_scale(H, 1.0 / len);
        }
    }
    if (!finite) {
        out->empty = 1; /* every ray runs parallel to R's plane: none arrives */
        return;
    }
    v3 c = {0, 0, 0};
    for (size_t i = 0; i < nh; i++)
        c = v3_add(c, h3[i]);
    if (!(v3_len(c) > 1e-9 * (double)nh)) {
        region_all(out);
        return;
    }
    c = v3_norm(c);
    v3 a = fabs(c.x) < 0.9 ? v3_norm(v3_cross(c, v3_make(1, 0, 0))) : v3_norm(v3_cross(c, v3_make(0, 1, 0)));
    v3 b = v3_cross(c, a);
    v2 pts[MAXH], hull[2 * MAXH + 1];
    for (size_t i = 0; i < nh; i++) {
        double dc = v3_dot(h3[i], c);
        if (!(dc > 1e-9)) {
            region_all(out); /* a cone too wide to project: do not cull */
            return;
        }
        v3 q = v3_scale(h3[i], 1.0 / dc);
        pts[i] = (v2){v3_dot(q, a), v3_dot(q, b)};
    }
    size_t m = rl__convex_hull2(pts, nh, hull);
    if (m < 3) {
        region_all(out);
        return;
    }
    for (size_t i = 0; i < m; i++) {
        v2 p0 = hull[i], p1 = hull[(i + 1) % m];
        v3 q0 = v3_add(c, v3_add(v3_scale(a, p0.x), v3_scale(b, p0.y)));
        v3 q1 = v3_add(c, v3_add(v3_scale(a, p1.x), v3_scale(b, p1.y)));
        v3 nrm = v3_cross(q0, q1);
        /* Two hull vertices that are nearly the same direction (the images
         * of one point under several generators, rounded apart) give a
         * facet whose orientation is noise. Dropping a facet only enlarges
         * the region, so it stays conservative. */
        if (!(v3_len(nrm) > 1e-6 * v3_len(q0) * v3_len(q1)))
            continue;
        if (v3_dot(nrm, c) < 0)
            nrm = v3_scale(nrm, -1.0);
        double ab = hypot(nrm.x, nrm.y);
        if (!(ab > 1e-12 * v3_len(nrm)))
            continue; /* the facet at infinity (W = 0): every finite point passes */
        rl_halfplane hp = {nrm.x / ab, nrm.y / ab, nrm.z * scale / ab + margin};
        out->h[out->count++] = hp;
    }
}
