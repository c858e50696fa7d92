/*
 * maps.c - radiance maps on receiving polygons.
 *
 * Each receiving polygon gets a frame (origin at its first vertex, e1 along
 * its first edge, e2 = n x e1) and a grid of square cells of the scene's
 * cell size over its bounding rectangle. Only cells whose intersection with
 * the polygon has area survive; a cell cut by the polygon's border is marked,
 * and its clipped polygon is clipped again whenever it is asked for, so cell
 * values are means over the part that is really surface. Memory is 8 bytes
 * per cell that exists plus one index per grid square, or, where every
 * square of the grid is a cell, one bit per cell (which are cut).
 */
#include <stdlib.h>
#include <string.h>

#include "ilf/limits.h"
#include "ilf/pool.h"
#include "lfio/radmap.h"
#include "maps.h"

/* Cells a scene may have in all (ilf/limits.h says why). */
#define MAX_TOTAL_CELLS ILF_MAP_MAX_CELLS
_Static_assert(ILF_MAP_MAX_CELLS <= LFIO_RADMAP_MAX_CELLS, "a solved scene must fit a radiance-map file");

int rl__polygon_holds(const v2 *p, uint32_t count, v2 q, double margin)
{
    for (uint32_t i = 0; i < count; i++) {
        v2 a = p[i], b = p[(i + 1) % count];
        double ex = b.x - a.x, ey = b.y - a.y, len = sqrt(ex * ex + ey * ey);
        /* signed distance to the left of the edge: inside for a counter-clockwise polygon */
        if (!(len > 0))
            continue;
        if ((ex * (q.y - a.y) - ey * (q.x - a.x)) / len < margin)
            return 0;
    }
    return 1;
}

double rl__polygon_area2(const v2 *p, uint32_t count)
{
    double a = 0.0;
    for (uint32_t i = 1; i + 1 < count; i++)
        a += v2_cross(v2_sub(p[i], p[0]), v2_sub(p[i + 1], p[0]));
    return 0.5 * a;
}

void rl__polygon_sampler_init(rl_polygon_sampler *s, const v2 *p, uint32_t count)
{
    /* the fan's doubled areas once, summed as rl__polygon_area2() sums them */
    double a = 0.0;
    for (uint32_t t = 1; t + 1 < count; t++) {
        double c = v2_cross(v2_sub(p[t], p[0]), v2_sub(p[t + 1], p[0]));
        a += c;
        s->w[t] = 0.5 * c;
    }
    s->p = p;
    s->count = count;
    s->total = 0.5 * a;
}

v2 rl__polygon_sampler_point(const rl_polygon_sampler *s, double a, double b)
{
    const v2 *p = s->p;
    uint32_t count = s->count;
    if (count < 3)
        return p[0];
    /* pick a fan triangle by area with a, then reuse a's remainder */
    double acc = 0.0, pick = a * s->total, w = 0.0;
    uint32_t t = 1;
    for (; t + 1 < count; t++) {
        w = s->w[t];
        if (pick < acc + w || t + 2 == count)
            break;
        acc += w;
    }
    /* clamped by comparisons, not fmin/fmax (calls in this hot path): the quotient is finite */
    double r = 0.5;
    if (w > 0) {
        r = (pick - acc) / w;
        r = r > 0.0 ? (r < 1.0 ? r : 1.0) : 0.0;
    }
    /* uniform in a triangle: the square-root warp */
    double su = sqrt(r);
    double l0 = 1 - su, l1 = su * (1 - b), l2 = su * b;
    return (v2){l0 * p[0].x + l1 * p[t].x + l2 * p[t + 1].x, l0 * p[0].y + l1 * p[t].y + l2 * p[t + 1].y};
}

v2 rl__sample_polygon(const v2 *p, uint32_t count, double a, double b)
{
    rl_polygon_sampler s;
    rl__polygon_sampler_init(&s, p, count);
    return rl__polygon_sampler_point(&s, a, b);
}

/* Sets up m's frame and 2D polygon from scene polygon k. @return RL_OK or RL_ERR_NOMEM. */
static rl_status map_frame(const rl_scene *scene, uint32_t k, rl_map *m)
{
    const rl_polygon *pg = &scene->polygons[k];
    const double (*v)[3] = scene->vertices + pg->first;
    m->polygon = (int32_t)k;
    m->frame.origin = v3_load(v[0]);
    m->frame.n = v3_load(pg->normal);
    m->frame.e1 = v3_norm(v3_sub(v3_load(v[1]), v3_load(v[0])));
    m->frame.e2 = v3_cross(m->frame.n, m->frame.e1);
    m->npoly = pg->count;
    if ((m->poly = malloc(pg->count * sizeof *m->poly)) == NULL)
        return RL_ERR_NOMEM;
    for (uint32_t i = 0; i < pg->count; i++)
        m->poly[i] = frame_project(&m->frame, v3_load(v[i]));
    return RL_OK;
}

/* Clips the square of cell (i, j) to m's polygon, whose edges' half-planes are edges[m->npoly] (or NULL:
 * not known). A square whose corners all lie in every half-plane, as the clip tests them, is what the clip
 * would give back unchanged: it is given back without clipping (most squares of a large polygon).
 * @return the clipped vertex count. */
static uint32_t clip_square(const rl_map *m, const rl_halfplane *edges, uint32_t i, uint32_t j, v2 *out)
{
    double x0 = m->u0 + i * m->cell, y0 = m->v0 + j * m->cell, x1 = x0 + m->cell, y1 = y0 + m->cell;
    const v2 square[4] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
    int inside = edges != NULL;
    for (uint32_t e = 0; inside && e < m->npoly; e++)
        for (int k = 0; k < 4 && inside; k++)
            inside = edges[e].a * square[k].x + edges[e].b * square[k].y + edges[e].c >= 0;
    if (inside) {
        memcpy(out, square, sizeof square);
        return 4;
    }
    v2 scratch[RL_MAX_POLY_VERTS + 8];
    return (uint32_t)rl__clip_to_polygon(square, 4, m->poly, m->npoly, out, scratch);
}

/* Places the grid of m over its polygon (u0, v0, nu, nv). @return RL_OK, or RL_ERR_INPUT when the grid
 * would exceed the scene's cell budget. */
static rl_status map_grid(rl_map *m)
{
    double u1 = -INFINITY, v1 = -INFINITY;
    m->u0 = m->v0 = INFINITY;
    for (uint32_t i = 0; i < m->npoly; i++) {
        m->u0 = fmin(m->u0, m->poly[i].x);
        m->v0 = fmin(m->v0, m->poly[i].y);
        u1 = fmax(u1, m->poly[i].x);
        v1 = fmax(v1, m->poly[i].y);
    }
    double gu = fmax(1.0, ceil((u1 - m->u0) / m->cell - 1e-9));
    double gv = fmax(1.0, ceil((v1 - m->v0) / m->cell - 1e-9));
    if (!(gu * gv <= (double)MAX_TOTAL_CELLS))
        return RL_ERR_INPUT;
    m->nu = (uint32_t)gu;
    m->nv = (uint32_t)gv;
    return RL_OK;
}

/* Fills the cells of m, whose grid is placed (map_grid()). @return RL_OK or RL_ERR_NOMEM. */
static rl_status map_cells(rl_map *m)
{
    size_t squares = (size_t)m->nu * m->nv;
    m->grid = malloc(squares * sizeof *m->grid);
    m->cells = malloc(squares * sizeof *m->cells);
    if (!m->grid || !m->cells)
        return RL_ERR_NOMEM;
    /* Cells below tiny are clipping slivers along the border. Relative to the
     * polygon too: a polygon much smaller than a cell is one small cell, not none. */
    const double full = m->cell * m->cell, tiny = 1e-12 * fmin(full, rl__polygon_area2(m->poly, m->npoly));
    v2 poly[RL_MAX_POLY_VERTS + 8];
    rl_halfplane edges[RL_MAX_POLY_VERTS];
    for (uint32_t e = 0; e < m->npoly; e++)
        edges[e] = edge_halfplane(m->poly[e], m->poly[(e + 1) % m->npoly]);
    m->ncells = 0;
    for (uint32_t j = 0; j < m->nv; j++)
        for (uint32_t i = 0; i < m->nu; i++) {
            uint32_t count = clip_square(m, edges, i, j, poly);
            double area = count >= 3 ? rl__polygon_area2(poly, count) : 0.0;
            m->grid[(size_t)j * m->nu + i] = -1;
            if (!(area > tiny))
                continue;
            rl_cell *c = &m->cells[m->ncells];
            c->i = i;
            c->j = j;
            c->clipped = area < full * (1 - 1e-9);
            m->grid[(size_t)j * m->nu + i] = (int32_t)m->ncells++;
        }
    /* a grid whose every square is a cell is the identity, and its cells follow from their index but
     * for being cut: a rectangle needs a bit a cell */
    if (m->ncells == squares) {
        if ((m->cut = calloc(squares / 8 + 1, 1)) == NULL)
            return RL_ERR_NOMEM;
        for (size_t c = 0; c < squares; c++)
            m->cut[c >> 3] |= (uint8_t)(m->cells[c].clipped << (c & 7));
        free(m->grid);
        free(m->cells);
        m->grid = NULL;
        m->cells = NULL;
    }
    /* the cells were allocated for every square of the bounding grid: a triangle needs about half */
    if (m->ncells < squares) {
        rl_cell *fit = realloc(m->cells, (m->ncells ? m->ncells : 1) * sizeof *fit);
        if (fit)
            m->cells = fit;
    }
    return RL_OK;
}

/* Allocates the accumulators of m: a total, a pass and e_prev only when it re-emits (bounces follow),
 * else one array for all, so a direct-only run keeps 24 bytes a cell instead of 72.
 * @return RL_OK or RL_ERR_NOMEM. */
static rl_status map_accumulators(rl_map *m, int re_emits)
{
    size_t n = m->ncells ? m->ncells : 1;
    m->e_pass = calloc(n, sizeof *m->e_pass);
    /* a map that never re-emits has one pass to hold (the direct pass, or one bounce gathered on
     * coarse cells): its total is that pass's array, 24 bytes a cell fewer */
    m->e_total = re_emits ? calloc(n, sizeof *m->e_total) : m->e_pass;
    m->e_prev = re_emits ? calloc(n, sizeof *m->e_prev) : NULL;
    return m->e_total && m->e_pass && (m->e_prev || !re_emits) ? RL_OK : RL_ERR_NOMEM;
}

static rl_status build(const rl_scene *scene, double cell, int re_emit, unsigned threads, rl_map **maps,
                       size_t *count);

rl_status rl__maps_build(const rl_scene *scene, double cell, int re_emit, unsigned threads, rl_map **maps,
                         size_t *count)
{
    return build(scene, cell, re_emit, threads, maps, count);
}

rl_status rl__maps_build_sized(const rl_scene *scene, double cell, unsigned threads, rl_map **maps, size_t *count)
{
    return build(scene, cell, 0, threads, maps, count);
}

/* The cells of the maps whose grids are placed (ilf_parallel_for()'s fn over them): each map's own. */
typedef struct cells_job {
    rl_map *maps;
    int re_emit;
    rl_status *status; /* [map] */
} cells_job;

/* Makes the cells and accumulators of map m, its status in status[m] (ilf_parallel_for()'s fn). */
static void build_cells(void *arg, size_t m)
{
    cells_job *j = arg;
    rl_status st = map_cells(&j->maps[m]);
    j->status[m] = st == RL_OK ? map_accumulators(&j->maps[m], j->re_emit) : st;
}

/* Reports st, the failure of the map of polygon k. @return st. */
static rl_status map_failed(const rl_scene *scene, uint32_t k, rl_status st)
{
    if (st == RL_ERR_INPUT)
        return rl__fail(st, "%s: %s: more than %llu radiance cells in the scene; raise radiance_maps.cell_size",
                        scene->path, scene->polygons[k].label, (unsigned long long)MAX_TOTAL_CELLS);
    return rl__fail(st, "%s: %s: out of memory for its radiance map", scene->path, scene->polygons[k].label);
}

/* Builds the maps with cells of side cell; re_emit: they will light bounce passes (e_prev). The frames
 * and grids are placed first, in order; the cells (every square clipped to the polygon) are then made
 * on up to threads threads when the grids together stay within the cell budget, so that all of them
 * may be allocated at once, else a map at a time, the budget checked as they come. A failure names its
 * map: the first whose grid alone passes the budget, else the first at which the cells so far pass it or
 * memory runs out. */
static rl_status build(const rl_scene *scene, double cell, int re_emit, unsigned threads, rl_map **maps,
                       size_t *count)
{
    size_t n = 0, m = 0;
    uint64_t total = 0, squares = 0;
    *maps = NULL;
    *count = 0;
    for (size_t k = 0; k < scene->npolygons; k++) {
        const float *al = scene->materials[scene->polygons[k].material].albedo;
        n += al[0] > 0 || al[1] > 0 || al[2] > 0;
    }
    rl_map *out = calloc(n ? n : 1, sizeof *out);
    rl_status *status = malloc((n ? n : 1) * sizeof *status);
    if (!out || !status) {
        free(out);
        free(status);
        return rl__fail(RL_ERR_NOMEM, "out of memory for %zu radiance maps", n);
    }
    rl_status st = RL_OK;
    for (size_t k = 0; k < scene->npolygons && st == RL_OK; k++) {
        const rl_material *mat = &scene->materials[scene->polygons[k].material];
        if (!(mat->albedo[0] > 0 || mat->albedo[1] > 0 || mat->albedo[2] > 0))
            continue;
        rl_map *mp = &out[m++];
        mp->cell = cell;
        memcpy(mp->albedo, mat->albedo, sizeof mp->albedo);
        memcpy(mp->emission, mat->emission, sizeof mp->emission);
        st = map_frame(scene, (uint32_t)k, mp);
        if (st == RL_OK)
            st = map_grid(mp);
        if (st != RL_OK)
            map_failed(scene, (uint32_t)k, st);
        squares += (uint64_t)mp->nu * mp->nv;
    }
    int parallel = st == RL_OK && threads > 1 && squares <= MAX_TOTAL_CELLS;
    cells_job job = {out, re_emit, status};
    if (parallel)
        ilf_parallel_for(threads, m, build_cells, &job);
    for (size_t q = 0; q < m && st == RL_OK; q++) {
        if (!parallel)
            build_cells(&job, q);
        st = status[q];
        total += out[q].ncells;
        if (st == RL_OK && total > MAX_TOTAL_CELLS)
            st = RL_ERR_INPUT;
        if (st != RL_OK)
            map_failed(scene, (uint32_t)out[q].polygon, st);
    }
    free(status);
    if (st != RL_OK) {
        rl__maps_free(out, m);
        return st;
    }
    *maps = out;
    *count = m;
    return RL_OK;
}

/* @return 1 if coarse cell c or one of the eight around it is flagged near. */
static int near_around(const rl_map *coarse, uint32_t cell)
{
    const rl_cell c = rl__map_cell(coarse, cell);
    for (int dj = -1; dj <= 1; dj++)
        for (int di = -1; di <= 1; di++) {
            int64_t i = (int64_t)c.i + di, j = (int64_t)c.j + dj;
            if (i < 0 || j < 0 || i >= coarse->nu || j >= coarse->nv)
                continue;
            int32_t n = rl__map_grid_cell(coarse, i, j);
            if (n >= 0 && coarse->near[n])
                return 1;
        }
    return 0;
}

uint32_t rl__map_mark_direct(const rl_map *coarse, const rl_map *fine, uint8_t *gathered, uint8_t *subset)
{
    for (uint32_t c = 0; c < coarse->ncells; c++)
        gathered[c] = coarse->near && near_around(coarse, c);
    uint32_t marked = 0;
    for (uint32_t k = 0; k < fine->ncells; k++) {
        v2 q = rl__map_cell_centroid(fine, k, NULL);
        int64_t home = rl__map_cell_at(coarse, q);
        subset[k] = (uint8_t)(home < 0 ? coarse->near != NULL : gathered[home]);
        marked += subset[k];
    }
    return marked;
}

rl_status rl__map_point(v3 p, v3 n, rl_map *out)
{
    memset(out, 0, sizeof *out);
    out->polygon = -1;
    out->frame.origin = p;
    out->frame.n = n;
    v3 helper = fabs(n.x) < 0.9 ? v3_make(1, 0, 0) : v3_make(0, 1, 0);
    out->frame.e1 = v3_norm(v3_cross(helper, n));
    out->frame.e2 = v3_cross(n, out->frame.e1);
    out->npoly = 1;
    if ((out->poly = calloc(1, sizeof *out->poly)) == NULL)
        return RL_ERR_NOMEM;
    out->cell = 1.0;
    out->nu = out->nv = 1;
    out->cut = calloc(1, 1); /* its one square is its one cell: no grid */
    if (!out->cut)
        return RL_ERR_NOMEM;
    out->u0 = out->v0 = -0.5;
    out->ncells = 1;
    out->cut[0] = 1;
    return map_accumulators(out, 0);
}

void rl__map_settle(rl_map *m)
{
    const int re_emits = m->e_prev != NULL;
    if (m->e_pass != m->e_total)
        free(m->e_pass);
    if (re_emits && m->e_prev != m->e_total)
        free(m->e_prev);
    m->e_pass = m->e_total;
    m->e_prev = re_emits ? m->e_total : NULL;
}

void rl__maps_free(rl_map *maps, size_t count)
{
    for (size_t k = 0; maps && k < count; k++) {
        free(maps[k].poly);
        free(maps[k].grid);
        free(maps[k].cells);
        free(maps[k].cut);
        /* a settled map's arrays are one (rl__map_settle()) */
        if (maps[k].e_total != maps[k].e_pass)
            free(maps[k].e_total);
        if (maps[k].e_prev != maps[k].e_total && maps[k].e_prev != maps[k].e_pass)
            free(maps[k].e_prev);
        free(maps[k].e_pass);
    }
    free(maps);
}

uint32_t rl__map_cell_polygon(const rl_map *m, uint32_t cell, v2 *out)
{
    if (m->polygon < 0) {
        out[0] = m->poly[0];
        return 1;
    }
    const rl_cell c = rl__map_cell(m, cell);
    if (c.clipped)
        return clip_square(m, NULL, c.i, c.j, out);
    double x0 = m->u0 + c.i * m->cell, y0 = m->v0 + c.j * m->cell;
    out[0] = (v2){x0, y0};
    out[1] = (v2){x0 + m->cell, y0};
    out[2] = (v2){x0 + m->cell, y0 + m->cell};
    out[3] = (v2){x0, y0 + m->cell};
    return 4;
}

v2 rl__map_cell_centroid(const rl_map *m, uint32_t c, double *area)
{
    const rl_cell cell = m->polygon < 0 ? (rl_cell){0, 0, 1} : rl__map_cell(m, c);
    if (!cell.clipped) { /* a whole square: its centre, no clipping */
        if (area)
            *area = m->cell * m->cell;
        return (v2){m->u0 + (cell.i + 0.5) * m->cell, m->v0 + (cell.j + 0.5) * m->cell};
    }
    v2 poly[RL_MAX_POLY_VERTS + 8];
    uint32_t n = rl__map_cell_polygon(m, c, poly);
    if (area)
        *area = n >= 3 ? rl__polygon_area2(poly, n) : 0.0;
    return rl__polygon_centroid(poly, n);
}

int64_t rl__map_cell_at(const rl_map *m, v2 q)
{
    double fi = floor((q.x - m->u0) / m->cell), fj = floor((q.y - m->v0) / m->cell);
    if (!(fi >= 0 && fj >= 0 && fi < m->nu && fj < m->nv))
        return -1;
    return rl__map_grid_cell(m, (size_t)fi, (size_t)fj);
}

void rl__map_radiance(const rl_map *m, int64_t cell, double out[3])
{
    for (int c = 0; c < 3; c++)
        out[c] = cell < 0 ? 0.0 : m->albedo[c] * m->e_prev[cell][c] / ILF_PI;
}

int64_t rl__map_cell_near(const rl_map *m, v2 q)
{
    if (m->nu == 0 || m->nv == 0)
        return -1;
    size_t square = rl__map_square_clamped(m, q);
    int64_t i = (int64_t)(square % m->nu), j = (int64_t)(square / m->nu);
    /* the square itself, then the four that share a side with it, then the four corners */
    static const int8_t around[9][2] = {{0, 0}, {-1, 0}, {1, 0}, {0, -1}, {0, 1}, {-1, -1}, {1, -1}, {-1, 1}, {1, 1}};
    for (int r = 0; r < 9; r++) {
        int64_t ii = i + around[r][0], jj = j + around[r][1];
        if (ii >= 0 && jj >= 0 && ii < m->nu && jj < m->nv && rl__map_grid_cell(m, (size_t)ii, (size_t)jj) >= 0)
            return rl__map_grid_cell(m, (size_t)ii, (size_t)jj);
    }
    return -1;
}

/* rl__map_sample() over the cells not marked in skip (NULL: every cell), which count as outside the
 * polygon. */
static void map_sample_skipping(const rl_map *m, const uint8_t *skip, v2 q, const double (*values)[3], double out[3])
{
    double a = (q.x - m->u0) / m->cell - 0.5, b = (q.y - m->v0) / m->cell - 0.5;
    double fa = floor(a), fb = floor(b), t = a - fa, s = b - fb;
    double acc[3] = {0, 0, 0}, wsum = 0.0;
    for (int dj = 0; dj <= 1; dj++)
        for (int di = 0; di <= 1; di++) {
            double ci = fa + di, cj = fb + dj, w = (di ? t : 1 - t) * (dj ? s : 1 - s);
            if (ci < 0 || cj < 0 || ci >= m->nu || cj >= m->nv || !(w > 0))
                continue;
            int32_t c = rl__map_grid_cell(m, ci, cj);
            if (c < 0 || (skip && skip[c]))
                continue; /* outside the polygon: the others carry the value to the edge */
            for (int ch = 0; ch < 3; ch++)
                acc[ch] += w * values[c][ch];
            wsum += w;
        }
    if (!(wsum > 0)) { /* no centre around: the cell that holds q */
        int64_t c = rl__map_cell_at(m, q);
        for (int ch = 0; ch < 3; ch++)
            out[ch] = c < 0 ? 0.0 : values[c][ch];
        return;
    }
    for (int ch = 0; ch < 3; ch++)
        out[ch] = acc[ch] / wsum;
}

void rl__map_sample(const rl_map *m, v2 q, const double (*values)[3], double out[3])
{
    map_sample_skipping(m, NULL, q, values, out);
}

void rl__map_interpolate(const rl_map *coarse, const uint8_t *gathered, rl_map *fine)
{
    for (uint32_t k = 0; k < fine->ncells; k++) {
        if (fine->subset && fine->subset[k])
            continue; /* gathered itself */
        map_sample_skipping(coarse, gathered, rl__map_cell_centroid(fine, k, NULL),
                            (const double(*)[3])coarse->e_pass, fine->e_pass[k]);
    }
}
