/*
 * view.c - what a camera sees of a solution: the first surface along a
 * ray (pick), its shading from the radiance maps, or the light field slab
 * crossed before it (shade, rl_solution_trace), a camera's image
 * (rl_solution_render_camera, rl_solution_render_irradiance_camera,
 * rl_solution_render_cells_camera, and their scene-camera shorthands), and
 * how much of what the scene's camera sees is the back of a surface
 * (rl__view_faces).
 *
 * Invariants: rendering only reads the solution and the camera it is given
 * (the scene is never changed); each image row is written by the one worker
 * that took it from an atomic counter, and a pixel's value depends on
 * nothing but its ray, so the image does not depend on the thread count.
 * Shading interpolates within one polygon's map only (rl__map_sample). A
 * slab is seen from its emitting side only, with the radiance the engine
 * reads from it (rl__emitter_radiance_at); irradiance and cell renders look
 * through slabs, which are not surfaces.
 */
#include <math.h>
#include <stdatomic.h>
#include <string.h>

#include "emitter.h"
#include "engine_internal.h"
#include "ilf/pool.h"

typedef struct render_job {
    const rl_solution *s;
    const rl_camera *cam;
    float *rgb;                 /* radiance per pixel (irradiance with irradiance set), or NULL */
    int irradiance;             /* rgb gets the irradiance of the receiving surface seen, -1 where none */
    int32_t *map_ids, *cell_ids; /* what each pixel sees, or NULL */
    atomic_uint next_row;
} render_job;

/* Finds the front face first hit along a ray: its polygon, map and cell
 * (map or cell -1 when the polygon does not receive), and in *t_first the
 * distance to the first surface, front or back (INFINITY: none). @return 1,
 * or 0 for no hit or a back face. */
static int pick(const rl_solution *s, v3 org, v3 dir, uint32_t *poly, int32_t *map, int64_t *cell, v2 *at,
                double *t_first)
{
    double t;
    *map = -1;
    *cell = -1;
    *t_first = INFINITY;
    if (!rl__tracer_hit(s->tracer, org, dir, 0.0, INFINITY, poly, &t))
        return 0;
    *t_first = t;
    /* the back of a one-sided surface, unless a polygon lies back to back with it (a two-sided mesh, a
     * panel modelled as two faces), whose front the ray meets at the same distance up to rounding */
    if (v3_dot(dir, v3_load(s->scene->polygons[*poly].normal)) >= 0 &&
        !rl__tracer_hit_front(s->tracer, org, dir, t - (1e-9 + 1e-6 * t), t + 1e-9 + 1e-6 * t, poly, &t))
        return 0;
    *map = s->polygon_map[*poly];
    if (*map >= 0) {
        *at = frame_project(&s->maps[*map].frame, v3_madd(org, dir, t));
        *cell = rl__map_cell_at(&s->maps[*map], *at);
    }
    return 1;
}

/* Finds the first front face along a ray and the irradiance on it (W m^-2, flat or interpolated as the
 * solution says) into e, zero where it does not receive; *t_first as pick() gives it. @return the face's
 * polygon's map (-1: it does not receive, or the ray meets no front face: then *poly is UINT32_MAX). */
static int32_t surface_irradiance(const rl_solution *s, v3 org, v3 dir, uint32_t *poly, double e[3], double *t_first)
{
    int32_t map;
    int64_t cell;
    v2 at;
    e[0] = e[1] = e[2] = 0.0;
    if (!pick(s, org, dir, poly, &map, &cell, &at, t_first)) {
        *poly = UINT32_MAX;
        return -1;
    }
    if (cell >= 0 && s->flat)
        memcpy(e, s->maps[map].e_total[cell], 3 * sizeof *e);
    else if (cell >= 0)
        rl__map_sample(&s->maps[map], at, (const double(*)[3])s->maps[map].e_total, e);
    return cell >= 0 ? map : -1;
}

/* Finds the nearest light field slab the ray org + t dir (dir unit) crosses from its emitting side (against
 * its front normal) at 0 < t < t_max, inside its rectangle. @return its index in the scene, or -1; *q the
 * point crossed in the slab's frame (metres along u and v, as its emitter's frame gives them). */
static long slab_crossed(const rl_scene *scene, v3 org, v3 dir, double t_max, v2 *q)
{
    long best = -1;
    for (size_t k = 0; k < scene->nlightfields; k++) {
        const rl_lightfield *lf = &scene->lightfields[k];
        v3 o = v3_load(lf->origin), u = v3_load(lf->u), v = v3_load(lf->v);
        double len_u = v3_len(u), len_v = v3_len(v);
        v3 e1 = v3_scale(u, 1.0 / len_u), e2 = v3_scale(v, 1.0 / len_v), n = v3_cross(e1, e2);
        double facing = v3_dot(dir, n);
        if (!(facing < 0.0))
            continue;
        double t = v3_dot(v3_sub(o, org), n) / facing;
        if (!(t > 0.0 && t < t_max))
            continue;
        v3 r = v3_sub(v3_madd(org, dir, t), o);
        double x = v3_dot(r, e1), y = v3_dot(r, e2);
        if (!(x >= 0.0 && x <= len_u && y >= 0.0 && y <= len_v))
            continue;
        best = (long)k;
        t_max = t;
        *q = (v2){x, y};
    }
    return best;
}

/* The radiance light field k of the scene sends from its point q (slab frame, metres) back along the camera
 * ray dir: what the engine gathers from it (rl__emitter_radiance_at). */
static void slab_radiance(const rl_scene *scene, long k, v2 q, v3 dir, float out[3])
{
    rl_emitter e;
    double rgb[3];
    rl__emitter_from_lightfield(&scene->lightfields[k], NULL, &e); /* no run's tables: nothing culled */
    rl__emitter_radiance_at(&e, q, v3_scale(dir, -1.0), rgb);
    for (int c = 0; c < 3; c++)
        out[c] = (float)rgb[c];
}

int rl_scene_trace_lightfields(const rl_scene *s, const double org[3], const double dir[3], double t_max,
                               float rgb[3])
{
    if (s == NULL || org == NULL || dir == NULL || rgb == NULL || isnan(t_max))
        return 0;
    v3 o = v3_load(org), d = v3_load(dir);
    double len = v3_len(d);
    if (!isfinite(v3_maxabs(o)) || !isfinite(len) || !(len > 0))
        return 0;
    d = v3_scale(d, 1.0 / len);
    v2 q;
    long k = slab_crossed(s, o, d, t_max, &q);
    if (k >= 0)
        slab_radiance(s, k, q, d, rgb);
    return k >= 0;
}

/* Shades one camera ray: the light field slab it crosses before any surface, else the first surface,
 * emission plus albedo * E / pi (0 for a back face or nothing). */
static void shade(const rl_solution *s, v3 org, v3 dir, float out[3])
{
    uint32_t poly;
    double e[3], t_first;
    int32_t map = surface_irradiance(s, org, dir, &poly, e, &t_first);
    v2 q;
    long slab = s->scene->nlightfields > 0 ? slab_crossed(s->scene, org, dir, t_first, &q) : -1;
    out[0] = out[1] = out[2] = 0.0f;
    if (slab >= 0) {
        slab_radiance(s->scene, slab, q, dir, out);
        return;
    }
    if (poly == UINT32_MAX)
        return;
    const rl_material *mat = &s->scene->materials[s->scene->polygons[poly].material];
    for (int c = 0; c < 3; c++)
        out[c] = (float)(mat->emission[c] + (map >= 0 ? s->maps[map].albedo[c] * e[c] / ILF_PI : 0.0));
}

/* The irradiance on the receiving surface seen along one camera ray, -1 in every channel where none is. */
static void irradiance_seen(const rl_solution *s, v3 org, v3 dir, float out[3])
{
    uint32_t poly;
    double e[3], t_first;
    int receives = surface_irradiance(s, org, dir, &poly, e, &t_first) >= 0;
    for (int c = 0; c < 3; c++)
        out[c] = receives ? (float)e[c] : -1.0f;
}

rl_status rl_solution_set_smooth(rl_solution *s, int smooth)
{
    if (!s)
        return rl__fail(RL_ERR_ARG, "rl_solution_set_smooth: NULL solution");
    s->flat = !smooth;
    return RL_OK;
}

rl_status rl_solution_trace(const rl_solution *s, const double org[3], const double dir[3], float rgb[3])
{
    v3 o = v3_load(org), d = v3_load(dir);
    double len = v3_len(d);
    if (!isfinite(v3_maxabs(o)) || !isfinite(len) || !(len > 0))
        return rl__fail(RL_ERR_ARG, "rl_solution_trace: origin and direction must be finite, direction nonzero");
    shade(s, o, v3_scale(d, 1.0 / len), rgb);
    return RL_OK;
}

/* @return the unit direction of camera cam's ray through the centre of pixel (x, y) of an nx x ny grid over
 * its image. */
static v3 pixel_ray(const rl_camera *cam, uint32_t x, uint32_t y, uint32_t nx, uint32_t ny)
{
    double d[3];
    rl_camera_ray(cam, (x + 0.5) / nx, (y + 0.5) / ny, d);
    return v3_load(d);
}

void rl__view_faces(const rl_solution *s, uint32_t nx, uint32_t ny, uint64_t *hits, uint64_t *back)
{
    const rl_camera *cam = &s->scene->camera;
    *hits = *back = 0;
    rl__tracer_thread_init();
    for (uint32_t y = 0; y < ny; y++)
        for (uint32_t x = 0; x < nx; x++) {
            v3 d = pixel_ray(cam, x, y, nx, ny);
            uint32_t poly;
            double t;
            if (!rl__tracer_hit(s->tracer, v3_load(cam->position), d, 0.0, INFINITY, &poly, &t))
                continue;
            ++*hits;
            *back += v3_dot(d, v3_load(s->scene->polygons[poly].normal)) >= 0;
        }
}

/* Worker of a render: renders rows until none are left. */
static void render_worker(void *p, unsigned index)
{
    (void)index; /* rows are shared through the counter */
    render_job *job = p;
    const rl_camera *cam = job->cam;
    rl__tracer_thread_init();
    for (;;) {
        unsigned y = atomic_fetch_add(&job->next_row, 1);
        if (y >= cam->height)
            break;
        for (unsigned x = 0; x < cam->width; x++) {
            v3 d = pixel_ray(cam, x, y, cam->width, cam->height);
            size_t px = (size_t)y * cam->width + x;
            if (job->rgb && job->irradiance)
                irradiance_seen(job->s, v3_load(cam->position), d, job->rgb + 3 * px);
            else if (job->rgb)
                shade(job->s, v3_load(cam->position), d, job->rgb + 3 * px);
            if (job->map_ids) {
                uint32_t poly;
                int32_t map;
                int64_t cell;
                v2 at;
                double t_first;
                pick(job->s, v3_load(cam->position), d, &poly, &map, &cell, &at, &t_first);
                job->map_ids[px] = cell >= 0 ? map : -1;
                job->cell_ids[px] = cell >= 0 ? (int32_t)cell : -1;
            }
        }
    }
}

/* Runs a render job over camera cam's rows on the options' threads. */
static rl_status render(const char *call, const rl_solution *s, const rl_camera *cam, const rl_run_options *options,
                        float *rgb, int irradiance, int32_t *map_ids, int32_t *cell_ids)
{
    if (!s || !cam || (!rgb && !map_ids) || (map_ids && !cell_ids))
        return rl__fail(RL_ERR_ARG, "%s: NULL argument", call);
    rl__run run;
    rl_status st = rl__run_resolve(call, options, &run);
    if (st != RL_OK)
        return st;
    char why[160];
    if (rl__camera_problem(cam, why, sizeof why))
        return rl__fail(RL_ERR_ARG, "%s: camera: %s", call, why);
    render_job job;
    job.s = s;
    job.cam = cam;
    job.rgb = rgb;
    job.irradiance = irradiance;
    job.map_ids = map_ids;
    job.cell_ids = cell_ids;
    atomic_init(&job.next_row, 0);
    ilf_parallel(run.threads, render_worker, &job);
    return RL_OK;
}

/* @return the scene's camera of s, or NULL after failing (RL_ERR_ARG) for a NULL s or a scene without one. */
static const rl_camera *scene_camera(const char *call, const rl_solution *s)
{
    if (s == NULL)
        return rl__fail(RL_ERR_ARG, "%s: NULL argument", call), NULL;
    if (!s->scene->has_camera)
        return rl__fail(RL_ERR_ARG, "%s: the scene has no camera", s->scene->path), NULL;
    return &s->scene->camera;
}

rl_status rl_solution_render_camera(const rl_solution *s, const rl_camera *cam, const rl_run_options *options,
                                    float *rgb)
{
    return render("rl_solution_render_camera", s, cam, options, rgb, 0, NULL, NULL);
}

rl_status rl_solution_render(const rl_solution *s, const rl_run_options *options, float *rgb)
{
    const rl_camera *cam = scene_camera("rl_solution_render", s);
    return cam ? render("rl_solution_render", s, cam, options, rgb, 0, NULL, NULL) : RL_ERR_ARG;
}

rl_status rl_solution_render_irradiance_camera(const rl_solution *s, const rl_camera *cam,
                                               const rl_run_options *options, float *rgb)
{
    return render("rl_solution_render_irradiance_camera", s, cam, options, rgb, 1, NULL, NULL);
}

rl_status rl_solution_render_irradiance(const rl_solution *s, const rl_run_options *options, float *rgb)
{
    const rl_camera *cam = scene_camera("rl_solution_render_irradiance", s);
    return cam ? render("rl_solution_render_irradiance", s, cam, options, rgb, 1, NULL, NULL) : RL_ERR_ARG;
}

rl_status rl_solution_render_cells_camera(const rl_solution *s, const rl_camera *cam, const rl_run_options *options,
                                          int32_t *map_ids, int32_t *cell_ids)
{
    return render("rl_solution_render_cells_camera", s, cam, options, NULL, 0, map_ids, cell_ids);
}

rl_status rl_solution_render_cells(const rl_solution *s, const rl_run_options *options, int32_t *map_ids,
                                   int32_t *cell_ids)
{
    const rl_camera *cam = scene_camera("rl_solution_render_cells", s);
    return cam ? render("rl_solution_render_cells", s, cam, options, NULL, 0, map_ids, cell_ids) : RL_ERR_ARG;
}
