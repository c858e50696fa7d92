/*
 * view.c - what the camera sees of a solution: the first surface along a
 * ray (pick), its shading from the radiance maps (shade, rl_solution_trace)
 * and the camera's image (rl_solution_render, rl_solution_render_cells).
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
    float *rgb;                 /* radiance per pixel, or NULL */
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

/* Shades the first surface along one camera ray: emission plus albedo * E / pi. */
static void shade(const rl_solution *s, v3 org, v3 dir, float out[3])
{
    uint32_t poly;
    int32_t map;
    int64_t cell;
    v2 at;
    out[0] = out[1] = out[2] = 0.0f;
    if (!pick(s, org, dir, &poly, &map, &cell, &at))
        return;
    const rl_material *mat = &s->scene->materials[s->scene->polygons[poly].material];
    double e[3] = {0, 0, 0};
    if (cell >= 0 && s->flat)
        memcpy(e, s->maps[map].e_total[cell], sizeof e);
    else if (cell >= 0)
        rl__map_sample(&s->maps[map], at, (const double(*)[3])s->maps[map].e_total, e);
    for (int c = 0; c < 3; c++)
        out[c] = (float)(mat->emission[c] + (cell >= 0 ? s->maps[map].albedo[c] * e[c] / RL_PI : 0.0));
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
            double sx = (2.0 * (x + 0.5) / cam->width - 1.0) * job->tan_half * job->aspect;
            double sy = (1.0 - 2.0 * (y + 0.5) / cam->height) * job->tan_half;
            v3 d = v3_norm(v3_add(job->forward, v3_add(v3_scale(job->right, sx), v3_scale(job->up, sy))));
            size_t px = (size_t)y * cam->width + x;
            if (job->rgb)
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
                        int32_t *map_ids, int32_t *cell_ids)
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
    job.map_ids = map_ids;
    job.cell_ids = cell_ids;
    job.forward = v3_norm(v3_sub(v3_load(cam->look_at), v3_load(cam->position)));
    job.right = v3_norm(v3_cross(job.forward, v3_load(cam->up)));
    job.up = v3_cross(job.right, job.forward);
    job.tan_half = tan(cam->fov_deg * RL_PI / 360.0);
    job.aspect = (double)cam->width / cam->height;
    atomic_init(&job.next_row, 0);
    ilf_parallel(run.threads, render_worker, &job);
    return RL_OK;
}

rl_status rl_solution_render(const rl_solution *s, const rl_run_options *options, float *rgb)
{
    return render("rl_solution_render", s, options, rgb, NULL, NULL);
}

rl_status rl_solution_render_cells(const rl_solution *s, const rl_run_options *options, int32_t *map_ids,
                                   int32_t *cell_ids)
{
    return render("rl_solution_render_cells", s, options, NULL, map_ids, cell_ids);
}
