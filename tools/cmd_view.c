/*
 * cmd_view.c - `ilf view RADIANCE.h5 -o OUT.png|.exr|.hdr --position X,Y,Z
 * --look-at X,Y,Z [--up X,Y,Z] [--fov DEG] [--size WxH] [--scene SCENE]`: a
 * camera's view of a relit scene from its radiance map alone, without
 * relighting: each pixel casts one ray through its centre against every
 * map's polygon and shows the nearest surface's radiance, radiosity / pi of
 * the cell it hits (flat cells; emission is in the radiosity), black for the
 * back of a surface (as relight's view draws it) and for nothing hit. With
 * --scene, the scene's light field slabs are seen too, where a ray crosses
 * one from its emitting side before any surface (rl_scene_trace_lightfields).
 *
 * The camera is relight's (relight/camera.h, docs/scene.md "camera"), made
 * by the camera options shared with `ilf relight` (camera_cli.h), its rays
 * rl_camera_ray()'s. EXR and HDR get raw radiance; PNG is exposed as
 * relight's view.png (90th percentile of the lit pixels' luminance shown as
 * 0.8, unless --exposure or --scale fixes it) and sRGB-encoded.
 *
 * Invariants: the radiance map is read only through lfio's public reader;
 * the intersector is a brute-force loop over the maps (no Embree outside
 * relight), so the cost is pixels x maps; a pixel depends on its ray alone.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "camera_cli.h"
#include "cli.h"
#include "commands.h"
#include "cli_limits.h"
#include "ilf/limits.h"
#include "image/image.h"
#include "radmap_cli.h"
#include "radmap_mesh.h"
#include "relight_cli.h"
#include "tonemap.h"

/* relight's view.png exposure (cmd_relight.c), so that the two agree on the same camera. */
#define VIEW_PERCENTILE 0.90
#define VIEW_TARGET 0.8

typedef struct view_options {
    const char *path, *output, *scene;
    camera_overrides camera_given;
    rl_camera cam; /* made from camera_given */
    tone_fixed tone;
} view_options;

/* The camera options take CAMERA_OPT_COUNT ids from OPT_CAMERA. */
enum view_option_id { OPT_OUTPUT, OPT_CAMERA, OPT_EXPOSURE = OPT_CAMERA + CAMERA_OPT_COUNT, OPT_SCALE, OPT_SCENE,
                      OPT_COUNT };

/* The camera's entries are filled by camera_options_fill() before parsing. */
static cli_option view_options_table[OPT_COUNT] = {
    [OPT_OUTPUT] = {"output", 'o', "OUT.png|OUT.exr|OUT.hdr", "image to write (required): EXR or HDR radiance, PNG exposed"},
    [OPT_EXPOSURE] = {"exposure", 0, "EV", "PNG: radiance times 2^EV (default: 90th percentile of luminance -> 0.8)"},
    [OPT_SCALE] = {"scale", 0, "W", "PNG: radiance W (W sr^-1 m^-2) shows as white"},
    [OPT_SCENE] = {"scene", 0, "SCENE.json", "the relit scene: its light field slabs are seen too (default: none)"},
};

static const cli_usage view_usage = {
    "view",
    "RADIANCE.h5 -o OUT.png|OUT.exr|OUT.hdr --position X,Y,Z --look-at X,Y,Z\n"
    "                [--up X,Y,Z] [--fov DEG] [--size WxH] [--exposure EV | --scale W]\n"
    "                [--scene SCENE.json]",
    "Renders a camera's view of a relit scene from its radiance-map file (radiance.h5\n"
    "of 'ilf relight') without relighting: each pixel shows the radiance (radiosity /\n"
    "pi) of the cell its ray meets first, flat per cell; the back of a surface and\n"
    "empty space are black. The camera is as in a scene file: vertical --fov, --up\n"
    "made orthogonal to the view direction. Cost: pixels x maps ray-polygon tests.\n"
    "With --scene (the scene relit; radiance.h5 names it, as given to 'ilf relight',\n"
    "but is not followed on its own), a ray that crosses one of its light field slabs\n"
    "from the emitting side before any surface shows the slab's radiance toward the\n"
    "camera, as 'ilf relight' draws it.",
    "ilf view out/radiance.h5 -o corner.png --position 4,4,1.6 --look-at 2,2,1\n"
    "ilf view out/radiance.h5 -o wide.exr --position 2,-2,1.5 --look-at 2,2,1 --fov 80 --size 320x240",
};

/* ------------------------------------------------------------ the maps as ray targets */

/* A stored cell by its place in the grid, j * nu + i (up to 2^64 - 1: nu and nv are 32-bit). */
typedef struct cell_key {
    uint64_t grid;
    uint32_t cell;
} cell_key;

/* One map prepared for intersection: the polygon in (u, v), and its cells' keys sorted by grid place. */
typedef struct target {
    lfio_radmap_patch p;
    radmap_clipper poly; /* poly.poly: the polygon in (u, v) */
    cell_key *keys;      /* [ncells] */
} target;

static int compare_keys(const void *a, const void *b)
{
    uint64_t x = ((const cell_key *)a)->grid, y = ((const cell_key *)b)->grid;
    return x < y ? -1 : x > y;
}

static void targets_free(target *t, size_t count)
{
    for (size_t k = 0; t != NULL && k < count; k++) {
        radmap_clipper_free(&t[k].poly);
        free(t[k].keys);
    }
    free(t);
}

/* Prepares every map. @return the array, or NULL when memory runs out. */
static target *targets_make(const lfio_radmap *map)
{
    size_t count = lfio_radmap_count(map);
    target *t = calloc(count > 0 ? count : 1, sizeof *t);
    for (size_t k = 0; t != NULL && k < count; k++) {
        lfio_radmap_get(map, k, &t[k].p);
        const lfio_radmap_patch *p = &t[k].p;
        t[k].keys = malloc(sizeof(cell_key) * (p->ncells > 0 ? p->ncells : 1));
        if (t[k].keys == NULL || !radmap_clipper_init(&t[k].poly, p)) {
            targets_free(t, k + 1);
            return NULL;
        }
        for (uint32_t c = 0; c < p->ncells; c++)
            t[k].keys[c] = (cell_key){(uint64_t)p->cell_ij[2 * c + 1] * p->nu + p->cell_ij[2 * c], c};
        qsort(t[k].keys, p->ncells, sizeof(cell_key), compare_keys);
    }
    return t;
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* @return 1 if (u, v) is inside or on the convex polygon poly[n] (counter-clockwise). */
static int inside(const double *poly, uint32_t n, double u, double v)
{
    for (uint32_t k = 0; k < n; k++) {
        const double *a = poly + 2 * k, *b = poly + 2 * ((k + 1) % n);
        if ((b[0] - a[0]) * (v - a[1]) - (b[1] - a[1]) * (u - a[0]) < 0.0)
            return 0;
    }
    return 1;
}

/* The stored cell of t holding (u, v), or -1 (a point on the grid's edge is given the edge's cell). */
static int64_t cell_at(const target *t, double u, double v)
{
    const lfio_radmap_patch *p = &t->p;
    double fi = floor((u - p->u0) / p->cell_size), fj = floor((v - p->v0) / p->cell_size);
    uint64_t i = fi < 0 ? 0 : fi >= p->nu ? p->nu - 1 : (uint64_t)fi;
    uint64_t j = fj < 0 ? 0 : fj >= p->nv ? p->nv - 1 : (uint64_t)fj;
    uint64_t want = j * p->nu + i;
    size_t lo = 0, hi = p->ncells;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (t->keys[mid].grid < want)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < p->ncells && t->keys[lo].grid == want ? (int64_t)t->keys[lo].cell : -1;
}

/* Shades the first surface along the ray org + s dir, s > 0 (dir unit): radiance of its cell, black for a back
 * face. @return the distance to that surface, INFINITY for none. */
static double trace(const target *t, size_t count, const double org[3], const double dir[3], float out[3])
{
    double best = INFINITY, bu = 0, bv = 0;
    const target *hit = NULL;
    int front = 0;
    for (size_t k = 0; k < count; k++) {
        const lfio_radmap_patch *p = &t[k].p;
        double denom = dot3(dir, p->normal);
        if (denom == 0.0)
            continue;
        double rel[3] = {p->origin[0] - org[0], p->origin[1] - org[1], p->origin[2] - org[2]};
        double s = dot3(rel, p->normal) / denom;
        if (!(s > 0.0) || s >= best)
            continue;
        double at[3] = {org[0] + s * dir[0] - p->origin[0], org[1] + s * dir[1] - p->origin[1],
                        org[2] + s * dir[2] - p->origin[2]};
        double u = dot3(at, p->e1), v = dot3(at, p->e2);
        if (!inside(t[k].poly.poly, p->nverts, u, v))
            continue;
        best = s, bu = u, bv = v, hit = &t[k], front = denom < 0.0;
    }
    out[0] = out[1] = out[2] = 0.0f;
    int64_t c = hit != NULL && front ? cell_at(hit, bu, bv) : -1;
    for (int i = 0; c >= 0 && i < 3; i++)
        out[i] = (float)(hit->p.radiosity[3 * (size_t)c + i] / ILF_PI);
    return best;
}

/* ------------------------------------------------------------ camera */

/* Renders the view of o's camera: the maps t, and the light field slabs of scene (NULL: none) crossed before
 * them. */
static void render(const target *t, size_t count, const rl_scene *scene, const view_options *o, float *rgb)
{
    const rl_camera *cam = &o->cam;
    for (uint32_t y = 0; y < cam->height; y++)
        for (uint32_t x = 0; x < cam->width; x++) {
            double d[3];
            float *px = rgb + 3 * ((size_t)y * cam->width + x);
            rl_camera_ray(cam, (x + 0.5) / cam->width, (y + 0.5) / cam->height, d);
            double surface = trace(t, count, cam->position, d, px);
            if (scene != NULL)
                rl_scene_trace_lightfields(scene, cam->position, d, surface, px);
        }
}

/* ------------------------------------------------------------ main */

static int apply_option(const cli_parser *p, int opt, const char *value, void *ctx)
{
    view_options *o = ctx;
    if (opt >= OPT_CAMERA && opt < OPT_CAMERA + CAMERA_OPT_COUNT)
        return camera_option_apply(p, &o->camera_given, opt - OPT_CAMERA, value);
    switch (opt) {
    case OPT_OUTPUT: return cli_single_path("view", &o->output, value);
    case OPT_SCENE: return cli_single_path("view", &o->scene, value);
    case OPT_EXPOSURE: return cli_value_tone(p, value, 1, &o->tone);
    default: return cli_value_tone(p, value, 0, &o->tone);
    }
}

static int parse_arguments(view_options *o, int argc, char **argv)
{
    camera_options_fill(view_options_table + OPT_CAMERA, 0);
    int code = cli_parse(&view_usage, view_options_table, OPT_COUNT, argc, argv, &o->path, apply_option, o);
    if (code != -1)
        return code;
    const char *problem = o->path == NULL        ? "no file given (see 'ilf view --help')"
                          : o->output == NULL    ? "-o OUT.png|OUT.exr|OUT.hdr is required"
                          : img_guess_format(o->output) == IMG_FORMAT_UNKNOWN ? "the output must end in .png, .exr or .hdr"
                                                                               : NULL;
    if (problem != NULL) {
        cli_error("view", "%s", problem);
        return ILF_EXIT_USAGE;
    }
    int made = camera_resolve("view", &o->camera_given, NULL, &o->cam);
    if (made == 0) /* no camera option at all: the view still needs the two it cannot do without */
        cli_error("view", "--position X,Y,Z is required");
    return made == 1 ? -1 : ILF_EXIT_USAGE;
}

/* Exposes rgb for a PNG. @return the scale used, or a negative value when memory runs out. */
static double expose(float *rgb, size_t count, const view_options *o)
{
    double scale = 1.0;
    if (img_guess_format(o->output) != IMG_FORMAT_PNG)
        return scale;
    if (!tone_fixed_scale(&o->tone, &scale) &&
        !tone_percentile_scale(rgb, count, 3, TONE_LUMINANCE, VIEW_PERCENTILE, VIEW_TARGET, &scale))
        return -1.0;
    tone_apply(rgb, count, 3, scale);
    return scale;
}

static int view_map(const lfio_radmap *map, const rl_scene *scene, const view_options *o)
{
    const unsigned width = o->cam.width, height = o->cam.height;
    size_t count = (size_t)width * height;
    float *rgb = calloc(3 * count, sizeof(float));
    target *t = rgb != NULL ? targets_make(map) : NULL;
    double scale = t != NULL ? (render(t, lfio_radmap_count(map), scene, o, rgb), expose(rgb, count, o)) : -1.0;
    targets_free(t, lfio_radmap_count(map));
    int code = ILF_EXIT_OK;
    char err[512];
    if (scale < 0.0) {
        cli_error("view", "out of memory for a %ux%u view", width, height);
        code = ILF_EXIT_FAILED;
    } else {
        img_status st = img_write(o->output, (int)width, (int)height, 3, rgb, err, sizeof err);
        if (st != IMG_OK) {
            cli_error("view", "%s", err);
            code = st == IMG_ERR_ARG ? ILF_EXIT_USAGE : ILF_EXIT_FAILED;
        }
    }
    if (code == ILF_EXIT_OK) {
        char how[96];
        printf("wrote %s: %ux%u, %zu maps, ", o->output, width, height, lfio_radmap_count(map));
        if (scene != NULL)
            printf("%zu light fields, ", rl_scene_lightfield_count(scene));
        if (img_guess_format(o->output) == IMG_FORMAT_PNG)
            printf("scale %.6g (%s)\n", scale,
                   tone_fixed_describe(&o->tone, "auto: 90th percentile of luminance -> 0.8", how, sizeof how));
        else
            printf("raw radiance (scale 1)\n");
    }
    free(rgb);
    return code;
}

int ilf_cmd_view(int argc, char **argv)
{
    view_options o = {0};
    int code = parse_arguments(&o, argc, argv);
    if (code >= 0)
        return code;
    lfio_radmap *map = NULL;
    code = ilf_radmap_open("view", o.path, &map);
    rl_scene *scene = NULL;
    if (code == ILF_EXIT_OK && o.scene != NULL) /* its light fields, not a run: no job */
        code = relight_scene_open("view", o.scene, &(sampling_overrides){0}, &scene, NULL);
    if (code == ILF_EXIT_OK) {
        cli_output_watch(o.output);
        code = cli_output_check("view", o.output);
    }
    if (code == ILF_EXIT_OK)
        code = view_map(map, scene, &o);
    rl_scene_destroy(scene);
    lfio_radmap_destroy(map);
    return code;
}
