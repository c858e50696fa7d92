/*
 * view.c - what the camera sees of a solution: the first surface along a
 * ray (pick), its shading from the radiance maps (shade, rl_solution_trace)
 * and the camera's image (rl_solution_render, rl_solution_render_irradiance,
 * rl_solution_render_cells), and
 * how much of what the camera sees is the back of a surface (rl__view_faces).
 *
 * Invariants: rendering only reads the solution; each image row is written
 * by the one worker that took it from an atomic counter, and a pixel's value
 * depends on nothing but its ray, so the image does not depend on the thread
 * count. Shading interpolates within one polygon's map only (rl__map_sample).
 */
#include <math.h>
#include <stdatomic.h>
#include <string.h>

#include "engine_internal.h"
#include "ilf/pool.h"

typedef struct render_job {
    const rl_solution *s;
    float *rgb;                 /* radiance per pixel (irradiance with irradiance set), or NULL */
    int irradiance;             /* rgb gets the irradiance of the receiving surface seen, -1 where none */
    int32_t *map_ids, *cell_ids; /* what each pixel sees, or NULL */
    v3 forward, right, up;
    double tan_half, aspect;
    atomic_uint next_row;
} render_job;

/* Finds the front face first hit along a ray: its polygon, map and cell
 * (map or cell -1 when the polygon does not receive). @return 1, or 0 for
 * no hit or a back face. */
static int pick(const rl_solution *s, v3 org, v3 dir, uint32_t *poly, int32_t *map, int64_t *cell, v2 *at)
{
    double t;
    *map = -1;
    *cell = -1;
    if (!rl__tracer_hit(s->tracer, org, dir, 0.0, INFINITY, poly, &t))
        return 0;
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
 * solution says) into e, zero where it does not receive. @return the face's polygon's map (-1: it does not
 * receive, or the ray meets no front face: then *poly is UINT32_MAX). */
static int32_t surface_irradiance(const rl_solution *s, v3 org, v3 dir, uint32_t *poly, double e[3])
{
    int32_t map;
    int64_t cell;
    v2 at;
    e[0] = e[1] = e[2] = 0.0;
    if (!pick(s, org, dir, poly, &map, &cell, &at)) {
        *poly = UINT32_MAX;
        return -1;
    }
    if (cell >= 0 && s->flat)
        memcpy(e, s->maps[map].e_total[cell], 3 * sizeof *e);
    else if (cell >= 0)
        rl__map_sample(&s->maps[map], at, (const double(*)[3])s->maps[map].e_total, e);
    return cell >= 0 ? map : -1;
}

/* Shades the first surface along one camera ray: emission plus albedo * E / pi. */
static void shade(const rl_solution *s, v3 org, v3 dir, float out[3])
{
    uint32_t poly;
    double e[3];
    int32_t map = surface_irradiance(s, org, dir, &poly, e);
    out[0] = out[1] = out[2] = 0.0f;
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
    double e[3];
    int receives = surface_irradiance(s, org, dir, &poly, e) >= 0;
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

/* Sets job's camera frame from the scene's camera. */
static void camera_frame(const rl_camera *cam, render_job *job)
{
    job->forward = v3_norm(v3_sub(v3_load(cam->look_at), v3_load(cam->position)));
    job->right = v3_norm(v3_cross(job->forward, v3_load(cam->up)));
    job->up = v3_cross(job->right, job->forward);
    job->tan_half = tan(cam->fov_deg * ILF_PI / 360.0);
    job->aspect = (double)cam->width / cam->height;
}

/* @return the unit direction of the camera ray through the point (fx, fy) of the image, [0, 1] from the left
 * and from the top. */
static v3 camera_ray(const render_job *job, double fx, double fy)
{
    double sx = (2.0 * fx - 1.0) * job->tan_half * job->aspect, sy = (1.0 - 2.0 * fy) * job->tan_half;
    return v3_norm(v3_add(job->forward, v3_add(v3_scale(job->right, sx), v3_scale(job->up, sy))));
}

void rl__view_faces(const rl_solution *s, uint32_t nx, uint32_t ny, uint64_t *hits, uint64_t *back)
{
    render_job job;
    const rl_camera *cam = &s->scene->camera;
    camera_frame(cam, &job);
    *hits = *back = 0;
    rl__tracer_thread_init();
    for (uint32_t y = 0; y < ny; y++)
        for (uint32_t x = 0; x < nx; x++) {
            v3 d = camera_ray(&job, (x + 0.5) / nx, (y + 0.5) / ny);
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
    const rl_camera *cam = &job->s->scene->camera;
    rl__tracer_thread_init();
    for (;;) {
        unsigned y = atomic_fetch_add(&job->next_row, 1);
        if (y >= cam->height)
            break;
        for (unsigned x = 0; x < cam->width; x++) {
            v3 d = camera_ray(job, (x + 0.5) / cam->width, (y + 0.5) / cam->height);
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
                pick(job->s, v3_load(cam->position), d, &poly, &map, &cell, &at);
                job->map_ids[px] = cell >= 0 ? map : -1;
                job->cell_ids[px] = cell >= 0 ? (int32_t)cell : -1;
            }
        }
    }
}

/* Runs a render job over the camera's rows on the options' threads. */
static rl_status render(const char *call, const rl_solution *s, const rl_run_options *options, float *rgb,
                        int irradiance, int32_t *map_ids, int32_t *cell_ids)
{
    if (!s || (!rgb && !map_ids) || (map_ids && !cell_ids))
        return rl__fail(RL_ERR_ARG, "%s: NULL argument", call);
    rl__run run;
    rl_status st = rl__run_resolve(call, options, &run);
    if (st != RL_OK)
        return st;
    const rl_camera *cam = &s->scene->camera;
    if (!s->scene->has_camera)
        return rl__fail(RL_ERR_ARG, "%s: the scene has no camera", s->scene->path);
    render_job job;
    job.s = s;
    job.rgb = rgb;
    job.irradiance = irradiance;
    job.map_ids = map_ids;
    job.cell_ids = cell_ids;
    camera_frame(cam, &job);
    atomic_init(&job.next_row, 0);
    ilf_parallel(run.threads, render_worker, &job);
    return RL_OK;
}

rl_status rl_solution_render(const rl_solution *s, const rl_run_options *options, float *rgb)
{
    return render("rl_solution_render", s, options, rgb, 0, NULL, NULL);
}

rl_status rl_solution_render_irradiance(const rl_solution *s, const rl_run_options *options, float *rgb)
{
    return render("rl_solution_render_irradiance", s, options, rgb, 1, NULL, NULL);
}

rl_status rl_solution_render_cells(const rl_solution *s, const rl_run_options *options, int32_t *map_ids,
                                   int32_t *cell_ids)
{
    return render("rl_solution_render_cells", s, options, NULL, 0, map_ids, cell_ids);
}
