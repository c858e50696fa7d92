/*
 * test_scene.c - the scene loader (relight/scene.h) against the corpus in
 * tests/scenes and the data scenes in data/.
 *
 * Usage: test_scene SCENES_DIR DATA_DIR. Light field files are written at
 * run time into $ILF_TEST_TMP (or /tmp) together with the scenes that use
 * them. Good scenes must load with the expected counts, defaults, normals
 * and materials, and every loaded polygon is checked here, independently of
 * the loader, against the invariants of scene_model.h. Bad scenes are
 * one table: file, expected status, expected substring of the message; the
 * message must also name the scene file. tests/scenes/rooms holds one room
 * in every mesh format (gen_rooms.py), which must give the same polygons,
 * lamp, irradiance and view.
 */
#define _XOPEN_SOURCE 700 /* POSIX 2008 and realpath() */

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "check.h"
#include "relight/engine.h"
#include "relight/scene.h"
#include "emitter.h" /* rl__slab_tables_new(): a run's light field tables */
#include "maps.h"
#include "scene_model.h"

static const char *corpus; /* tests/scenes */
static const char *datadir;
static char tmpdir[1024];

/* Writes dir/name to out. @return out. */
static const char *join(char *out, size_t cap, const char *dir, const char *name)
{
    snprintf(out, cap, "%s/%s", dir, name);
    return out;
}

/* Loads dir/name, reporting a failure. @return the scene or NULL. */
static rl_scene *load(const char *dir, const char *name)
{
    char path[2048];
    rl_scene *s = NULL;
    rl_status st = rl_scene_load(join(path, sizeof path, dir, name), &s);
    CHECK(st == RL_OK && s, "%s: status %d: %s", path, (int)st, rl_errmsg());
    return st == RL_OK ? s : NULL;
}

/* @return 1 if a and b agree to tol in every component. */
static int near3(const double a[3], double x, double y, double z, double tol)
{
    return fabs(a[0] - x) <= tol && fabs(a[1] - y) <= tol && fabs(a[2] - z) <= tol;
}

/* @return the index of the material called name, or -1. */
static long material(const rl_scene *s, const char *name)
{
    for (size_t k = 0; k < s->nmaterials; k++)
        if (strcmp(s->materials[k].name, name) == 0)
            return (long)k;
    return -1;
}

/* Checks every polygon of s against the invariants, computed here from the vertices alone. */
static void check_invariants(const rl_scene *s, const char *name)
{
    for (size_t i = 0; i < s->npolygons; i++) {
        const rl_polygon *p = &s->polygons[i];
        CHECK(p->count >= 3 && (size_t)p->first + p->count <= s->nvertices, "%s: polygon %zu range", name, i);
        CHECK(p->material < s->nmaterials, "%s: polygon %zu material", name, i);
        if (p->count < 3 || (size_t)p->first + p->count > s->nvertices)
            continue;
        const double(*v)[3] = s->vertices + p->first;
        size_t n = p->count;
        double nrm[3] = {0, 0, 0}, diam = 0;
        for (size_t k = 0; k < n; k++) {
            const double *a = v[k], *b = v[(k + 1) % n];
            nrm[0] += (a[1] - b[1]) * (a[2] + b[2]);
            nrm[1] += (a[2] - b[2]) * (a[0] + b[0]);
            nrm[2] += (a[0] - b[0]) * (a[1] + b[1]);
            for (size_t m = 0; m < n; m++)
                diam = fmax(diam, sqrt((v[k][0] - v[m][0]) * (v[k][0] - v[m][0]) +
                                       (v[k][1] - v[m][1]) * (v[k][1] - v[m][1]) +
                                       (v[k][2] - v[m][2]) * (v[k][2] - v[m][2])));
        }
        double len = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
        CHECK(fabs(len / 2 - p->area) <= 1e-9 * fmax(1, p->area), "%s: polygon %zu area %g vs %g", name, i,
              len / 2, p->area);
        CHECK(p->area > 1e-12 * diam * diam, "%s: polygon %zu has no area", name, i);
        CHECK(near3(p->normal, nrm[0] / len, nrm[1] / len, nrm[2] / len, 1e-9), "%s: polygon %zu normal", name, i);
        double worst = 0, turn_min = INFINITY;
        for (size_t k = 0; k < n; k++) {
            double d[3] = {v[k][0] - v[0][0], v[k][1] - v[0][1], v[k][2] - v[0][2]};
            worst = fmax(worst, fabs(d[0] * p->normal[0] + d[1] * p->normal[1] + d[2] * p->normal[2]));
            const double *a = v[k], *b = v[(k + 1) % n], *c = v[(k + 2) % n];
            double e[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, f[3] = {c[0] - b[0], c[1] - b[1], c[2] - b[2]};
            double x[3] = {e[1] * f[2] - e[2] * f[1], e[2] * f[0] - e[0] * f[2], e[0] * f[1] - e[1] * f[0]};
            turn_min = fmin(turn_min, x[0] * p->normal[0] + x[1] * p->normal[1] + x[2] * p->normal[2]);
        }
        CHECK(worst <= 2e-6 * diam, "%s: polygon %zu is %g off its plane", name, i, worst);
        CHECK(turn_min > 0, "%s: polygon %zu is not strictly convex", name, i);
    }
}

/* ------------------------------------------------------------ good scenes */

static void test_minimal(void)
{
    rl_scene *s = load(corpus, "good_minimal.json");
    if (!s)
        return;
    rl_sampling def;
    rl_sampling_default(&def);
    rl_job job;
    rl_job_default(s, &job);
    const rl_sampling *got = &job.sampling;
    CHECK(rl_scene_polygon_count(s) == 1, "polygons %zu", rl_scene_polygon_count(s));
    CHECK(rl_scene_lightfield_count(s) == 0 && rl_scene_lightfield_bytes(s) == 0, "light fields");
    CHECK(job.cell_size == 0.05 && job.cell_size == RL_DEFAULT_CELL_SIZE, "default cell size %g", job.cell_size);
    CHECK(!rl_scene_has_camera(s), "no camera");
    CHECK(got->method == RL_METHOD_CULLED && got->partition_n == 32 && got->rays_per_solid_angle == 4 &&
              got->samples_per_cell == def.samples_per_cell && got->bounces == 0 && got->seed == 1,
          "default sampling");
    CHECK(memcmp(got, &def, sizeof def) == 0, "sampling equals rl_sampling_default");
    CHECK(s->nmaterials == 1 && s->materials[0].albedo[1] == 0.8f && s->materials[0].emission[2] == 0.0f,
          "default material");
    CHECK(near3(s->polygons[0].normal, 0, 0, 1, 1e-15), "counter-clockwise from +z faces +z");
    CHECK(fabs(s->polygons[0].area - 1) < 1e-15, "area %g", s->polygons[0].area);
    CHECK(strcmp(s->polygons[0].label, "polygons[0]") == 0, "label %s", s->polygons[0].label);
    check_invariants(s, "good_minimal.json");
    rl_scene_destroy(s);
}

static void test_full(void)
{
    rl_scene *s = load(corpus, "good_full.json");
    if (!s)
        return;
    rl_job job;
    rl_job_default(s, &job);
    const rl_sampling *g = &job.sampling;
    CHECK(rl_scene_polygon_count(s) == 3, "polygons %zu", rl_scene_polygon_count(s));
    CHECK(job.cell_size == 0.1, "cell size");
    CHECK(g->method == RL_METHOD_NAIVE && g->partition_n == 16 && g->rays_per_solid_angle == 8 &&
              g->samples_per_cell == 32 && g->bounces == 3 && g->seed == 42,
          "sampling read");
    CHECK(rl_scene_has_camera(s), "camera");
    CHECK(near3(s->camera.up, 0, 0, 1, 0) && s->camera.fov_deg == 60 && s->camera.width == 320 &&
              s->camera.height == 240 && near3(s->camera.position, 0.5, -3, 1, 0),
          "camera values and default up");
    long lamp = material(s, "lamp");
    CHECK(lamp >= 0 && s->materials[lamp].emission[0] == 10 && s->materials[lamp].albedo[0] == 0, "lamp");
    if (s->npolygons == 3) {
        CHECK(near3(s->polygons[0].normal, 0, 0, -1, 1e-15), "clockwise from +z faces -z");
        CHECK(s->polygons[1].count == 4, "collinear and repeated vertices removed: %u", s->polygons[1].count);
        CHECK(near3(s->polygons[1].normal, 0, 0, 1, 1e-15), "lamp faces +z");
        CHECK((long)s->polygons[1].material == lamp, "lamp material");
        CHECK(near3(s->polygons[2].normal, -1, 0, 0, 1e-15), "right-hand rule: z then y gives -x");
        CHECK(fabs(s->polygons[2].area - 0.5) < 1e-15, "triangle area");
    }
    check_invariants(s, "good_full.json");
    rl_scene_destroy(s);
}

static void test_meshes(void)
{
    rl_scene *s = load(corpus, "good_mesh_quad.json");
    if (s) {
        CHECK(s->npolygons == 1 && s->polygons[0].count == 4, "planar convex quad kept whole");
        CHECK(s->npolygons == 1 && near3(s->polygons[0].normal, 0, 0, 1, 1e-15), "quad faces +z");
        CHECK(s->npolygons == 1 && strcmp(s->polygons[0].label, "meshes[0] (quad.obj) face 0") == 0, "label '%s'",
              s->npolygons ? s->polygons[0].label : "");
        check_invariants(s, "good_mesh_quad.json");
        rl_scene_destroy(s);
    }
    s = load(corpus, "good_mesh_nonplanar.json");
    if (s) {
        CHECK(s->npolygons == 2, "non-planar quad split into %zu polygons", s->npolygons);
        for (size_t i = 0; i < s->npolygons; i++)
            CHECK(s->polygons[i].count == 3 && s->polygons[i].normal[2] > 0.9, "triangle %zu faces up", i);
        check_invariants(s, "good_mesh_nonplanar.json");
        rl_scene_destroy(s);
    }
    s = load(corpus, "good_mesh_lshape.json");
    if (s) {
        double area = 0;
        /* ear clipping gives 4 triangles, merged back into the fewest convex pieces an L allows */
        CHECK(s->npolygons == 2, "L-shaped face: %zu polygons, 2 convex pieces expected", s->npolygons);
        for (size_t i = 0; i < s->npolygons; i++) {
            area += s->polygons[i].area;
            CHECK(s->polygons[i].count == 4 && near3(s->polygons[i].normal, 0, 0, 1, 1e-15) &&
                      strstr(s->polygons[i].label, "face 0 (+1 merged)"),
                  "piece %zu: %u vertices, '%s'", i, s->polygons[i].count, s->polygons[i].label);
        }
        CHECK(fabs(area - 3) < 1e-12, "parts cover the L: area %g", area);
        check_invariants(s, "good_mesh_lshape.json");
        rl_scene_destroy(s);
    }
    s = load(corpus, "good_mesh_mtl.json");
    if (s) {
        long red = material(s, "with_mtl.obj:Red"), lamp = material(s, "with_mtl.obj:Lamp");
        CHECK(s->npolygons == 2 && s->nmaterials == 2, "mtl scene: %zu polygons, %zu materials", s->npolygons,
              s->nmaterials);
        CHECK(red >= 0 && fabsf(s->materials[red].albedo[0] - 0.7f) < 1e-6f &&
                  fabsf(s->materials[red].albedo[1] - 0.1f) < 1e-6f && s->materials[red].emission[0] == 0,
              "Kd becomes albedo");
        CHECK(lamp >= 0 && s->materials[lamp].emission[0] == 5 && s->materials[lamp].emission[1] == 4 &&
                  s->materials[lamp].emission[2] == 3 && s->materials[lamp].albedo[0] == 0,
              "Ke becomes emission");
        if (s->npolygons == 2) {
            CHECK((long)s->polygons[0].material == red && (long)s->polygons[1].material == lamp, "face materials");
            CHECK(near3(s->polygons[1].normal, 0, 0, -1, 1e-15), "lamp faces down");
        }
        check_invariants(s, "good_mesh_mtl.json");
        rl_scene_destroy(s);
    }
    s = load(corpus, "good_mesh_ply.json");
    if (s) {
        CHECK(s->npolygons == 2, "PLY: %zu polygons", s->npolygons);
        if (s->npolygons == 2) {
            CHECK(s->polygons[0].count == 4 && near3(s->polygons[0].normal, 0, 0, 1, 1e-15), "PLY quad");
            CHECK(s->polygons[1].count == 3 && near3(s->polygons[1].normal, 0, 0, -1, 1e-15), "PLY triangle");
            CHECK(s->polygons[0].material == 0, "PLY without materials uses the entry's material");
        }
        check_invariants(s, "good_mesh_ply.json");
        rl_scene_destroy(s);
    }
    s = load(corpus, "good_mixed.json");
    if (s) {
        CHECK(s->npolygons == 6, "mixed: %zu polygons", s->npolygons);
        CHECK(s->nmaterials == 3, "a mesh file read twice shares its materials: %zu", s->nmaterials);
        check_invariants(s, "good_mixed.json");
        rl_scene_destroy(s);
    }
}

/* ------------------------------------------------------------- bad scenes */

typedef struct bad_case {
    const char *file;
    rl_status status;
    const char *expect; /* substring of rl_errmsg() */
} bad_case;

static const bad_case bad_cases[] = {
    /* structure and types */
    {"bad_unknown_key.json", RL_ERR_INPUT, ": unknown key 'lights' (expected materials, polygons"},
    {"bad_material_key.json", RL_ERR_INPUT, "materials.white: unknown key 'colour'"},
    {"bad_polygon_key.json", RL_ERR_INPUT, "polygons[0]: unknown key 'normal'"},
    {"bad_threads.json", RL_ERR_INPUT, "sampling: unknown key 'threads'"},
    {"bad_camera_key.json", RL_ERR_INPUT, "camera: unknown key 'fov'"},
    {"bad_duplicate_key.json", RL_ERR_INPUT, "duplicate key 'sampling'"},
    {"bad_duplicate_material.json", RL_ERR_INPUT, "materials.a: duplicate material"},
    {"bad_root_array.json", RL_ERR_INPUT, "expected a JSON object at the top level, got an array"},
    {"bad_polygons_type.json", RL_ERR_INPUT, "polygons: expected an array, got an object"},
    {"bad_vertices_type.json", RL_ERR_INPUT, "polygons[0].vertices: expected an array"},
    {"bad_albedo_type.json", RL_ERR_INPUT, "materials.white.albedo: expected an array of 3 numbers, got a string"},
    {"bad_albedo_range.json", RL_ERR_INPUT, "materials.white: albedo[0] is 1.5, outside [0, 1]"},
    {"bad_emission_negative.json", RL_ERR_INPUT, "materials.lamp: emission[1] is -1"},
    {"bad_name_long.json", RL_ERR_INPUT, "must be 1 to 63 bytes long"},
    {"bad_huge_number.json", RL_ERR_INPUT, "polygons[0].vertices[1][0]: not a finite number"},
    {"bad_vertex_length.json", RL_ERR_INPUT, "polygons[0].vertices[2]: expected 3 numbers, got 2"},
    {"bad_vertex_string.json", RL_ERR_INPUT, "polygons[0].vertices[1][1]: expected a number, got a string"},
    {"bad_two_vertices.json", RL_ERR_INPUT, "polygons[0]: needs at least 3 vertices, got 2"},
    {"bad_missing_material.json", RL_ERR_INPUT, "polygons[0].material: unknown material 'blue'"},
    {"bad_polygon_no_material.json", RL_ERR_INPUT, "polygons[0]: missing key 'material'"},
    /* geometry */
    {"bad_nonplanar.json", RL_ERR_INPUT, "polygons[1]: not planar (vertex "},
    {"bad_nonconvex.json", RL_ERR_INPUT, "polygons[0]: not convex (the corner at vertex 3 turns the other way)"},
    {"bad_star.json", RL_ERR_INPUT, "polygons[0]: not convex (the boundary winds around 2 times)"},
    {"bad_spike.json", RL_ERR_INPUT, "polygons[0]: not convex (the boundary turns back on itself at vertex 1)"},
    {"bad_collinear.json", RL_ERR_INPUT, "polygons[0]: degenerate (zero area"},
    {"bad_coincident.json", RL_ERR_INPUT, "polygons[0]: degenerate (all vertices coincide)"},
    {"bad_repeated.json", RL_ERR_INPUT, "polygons[0]: degenerate (fewer than 3 distinct vertices)"},
    {"bad_retrace.json", RL_ERR_INPUT, "polygons[0]: degenerate (zero area"},
    {"bad_tiny_area.json", RL_ERR_INPUT, "polygons[0]: degenerate (zero area"},
    /* meshes */
    {"bad_missing_mesh.json", RL_ERR_INPUT, "meshes[0]: cannot open '"},
    {"bad_mesh_no_material.json", RL_ERR_INPUT, "meshes[0]: quad.obj has faces without a material"},
    {"bad_mesh_garbage.json", RL_ERR_INPUT, "meshes[0]: cannot read '"},
    {"bad_mesh_material.json", RL_ERR_INPUT, "meshes[0].material: unknown material 'nope'"},
    {"bad_mesh_directory.json", RL_ERR_INPUT, "is not a regular file"},
    {"bad_mesh_up.json", RL_ERR_INPUT, "meshes[0].up: expected \"z\" or \"y\", got 'x'"},
    {"bad_mesh_flip.json", RL_ERR_INPUT, "meshes[0].flip: expected true, false, 0 or 1, got a string"},
    {"bad_mesh_two_sided.json", RL_ERR_INPUT, "meshes[0].two_sided: expected true, false, 0 or 1, got a number"},
    /* light fields */
    {"bad_missing_lightfield.json", RL_ERR_INPUT, "lightfields[0]: "},
    /* a generated file that is missing: the message says how to make it */
    {"bad_missing_lightfield_made_by.json", RL_ERR_INPUT,
     "nothere.h5: cannot open: No such file or directory (it is generated: ilf synth --kind constant -o nothere.h5)"},
    {"bad_made_by_type.json", RL_ERR_INPUT, "lightfields[0].made_by: expected a string, got a number"},
    {"bad_lightfield_not_h5.json", RL_ERR_INPUT, "lightfields[0]: "},
    {"bad_slab_type.json", RL_ERR_INPUT, "lightfields[0].slab: expected a slab name or index, got a boolean"},
    {"bad_transform_shear.json", RL_ERR_INPUT, "lightfields[0].transform: the upper 3x3 must be a rotation times a uniform scale (it shears"},
    {"bad_transform_scale.json", RL_ERR_INPUT, "lightfields[0].transform: the upper 3x3 must be a rotation times a uniform scale (it shears"},
    {"bad_transform_mirror.json", RL_ERR_INPUT, "lightfields[0].transform: the upper 3x3 must have a positive determinant"},
    {"bad_transform_lastrow.json", RL_ERR_INPUT, "lightfields[0].transform: the last row must be [0, 0, 0, 1]"},
    {"bad_transform_length.json", RL_ERR_INPUT, "lightfields[0].transform: expected 16 numbers, got 15"},
    {"bad_transform_row.json", RL_ERR_INPUT, "lightfields[0].transform[1]: expected 4 numbers, got 3"},
    {"bad_transform_zero.json", RL_ERR_INPUT, "its scale is 0"},
    /* settings */
    {"bad_partition_3.json", RL_ERR_INPUT, "sampling.partition_n: must be a power of two in 1..4096, got 3"},
    {"bad_partition_0.json", RL_ERR_INPUT, "sampling.partition_n: must be a power of two in 1..4096, got 0"},
    {"bad_partition_8192.json", RL_ERR_INPUT, "sampling.partition_n: must be a power of two in 1..4096, got 8192"},
    {"bad_partition_fraction.json", RL_ERR_INPUT, "sampling.partition_n: must be a power of two in 1..4096, got 4.5"},
    {"bad_rays_0.json", RL_ERR_INPUT, "sampling.rays_per_solid_angle: must be an integer in 1..65536, got 0"},
    {"bad_samples_big.json", RL_ERR_INPUT, "sampling.samples_per_cell: must be an integer in 1..1048576"},
    {"bad_bounces.json", RL_ERR_INPUT, "sampling.bounces: must be an integer in 0..64, got 65"},
    {"bad_seed_negative.json", RL_ERR_INPUT, "sampling.seed: must be an integer in 0..9007199254740992, got -1"},
    {"bad_method.json", RL_ERR_INPUT, "sampling.method: unknown method 'fast'"},
    {"bad_method_type.json", RL_ERR_INPUT, "sampling.method: expected a string, got a number"},
    {"bad_cell_size.json", RL_ERR_INPUT, "radiance_maps.cell_size: must be > 0 metres, got 0"},
    {"bad_cell_size_type.json", RL_ERR_INPUT, "radiance_maps.cell_size: expected a number, got a string"},
    {"bad_camera_same.json", RL_ERR_INPUT, "camera: position and look_at must be distinct points"},
    {"bad_camera_up.json", RL_ERR_INPUT, "camera: up must not be zero or parallel to the view direction"},
    {"bad_camera_fov.json", RL_ERR_INPUT, "camera.fov_deg: must lie strictly between 0 and 180 degrees, got 180"},
    {"bad_camera_width.json", RL_ERR_INPUT, "camera.width: must be an integer in 1..16384, got 0"},
    {"bad_camera_height.json", RL_ERR_INPUT, "camera.height: must be an integer in 1..16384, got 20000"},
    {"bad_camera_missing.json", RL_ERR_INPUT, "camera: missing key 'position'"},
    /* not JSON */
    {"bad_truncated.json", RL_ERR_INPUT, "bad_truncated.json:4:1: not valid JSON: unexpected end of file"},
    {"bad_syntax.json", RL_ERR_INPUT, "bad_syntax.json:2:30: not valid JSON"},
    {"bad_empty.json", RL_ERR_INPUT, "the file is empty"},
    {"bad_not_json.json", RL_ERR_INPUT, "bad_not_json.json:1:1: not valid JSON: unexpected text near 'hello, world'"},
    {"bad_trailing.json", RL_ERR_INPUT, "bad_trailing.json:1:4: not valid JSON"},
    {"bad_nul.json", RL_ERR_INPUT, "bad_nul.json:1:17: not valid JSON: a NUL byte"},
    {"nothere.json", RL_ERR_IO, "nothere.json: cannot open: "},
    {".", RL_ERR_IO, "is a directory"},
};

static void test_bad(void)
{
    size_t count = sizeof bad_cases / sizeof bad_cases[0];
    for (size_t k = 0; k < count; k++) {
        const bad_case *c = &bad_cases[k];
        char path[2048];
        rl_scene *s = (rl_scene *)&path; /* must be reset to NULL */
        rl_status st = rl_scene_load(join(path, sizeof path, corpus, c->file), &s);
        const char *msg = rl_errmsg();
        CHECK(st == c->status, "%s: status %d, expected %d (%s)", c->file, (int)st, (int)c->status, msg);
        CHECK(s == NULL, "%s: no scene on failure", c->file);
        CHECK(strstr(msg, path) != NULL, "%s: message names the file: %s", c->file, msg);
        CHECK(strstr(msg, c->expect) != NULL, "%s: message '%s' lacks '%s'", c->file, msg, c->expect);
        if (st == RL_OK)
            rl_scene_destroy(s);
    }
    CHECK(count >= 25, "corpus of %zu bad scenes", count);
}

/* ----------------------------------------------------------- settings table */

/* The one table of sampling settings agrees with rl_sampling_default() and with the loader's messages. */
static void test_settings_table(void)
{
    rl_sampling def, x;
    rl_sampling_default(&def);
    memset(&x, 0, sizeof x);
    size_t n = rl_sampling_setting_count();
    CHECK(n == 13 && rl_sampling_setting(n) == NULL, "%zu settings", n);
    for (size_t k = 0; k < n; k++) {
        const rl_setting_info *s = rl_sampling_setting(k);
        double v = -1;
        CHECK(rl_sampling_get(&def, k, &v) && v == s->default_value, "%s: default %g, table %g", s->key, v,
              s->default_value);
        CHECK(rl_sampling_setting_allows(k, s->default_value, 1) && rl_sampling_setting_find(s->key) == k,
              "%s: default allowed, found", s->key);
        CHECK(rl_sampling_set(&x, k, s->default_value), "%s: set", s->key);
        CHECK(!rl_sampling_setting_allows(k, 2 * s->hi + 1, 1), "%s: above its bound", s->key);
    }
    CHECK(memcmp(&x, &def, sizeof x) == 0, "the table's defaults are rl_sampling_default()'s");
    char rule[128];
    size_t pn = rl_sampling_setting_find("partition_n"), te = rl_sampling_setting_find("target_error");
    CHECK(strcmp(rl_sampling_setting_rule(pn, rule, sizeof rule), "a power of two in 1..4096") == 0, "rule %s", rule);
    CHECK(strcmp(rl_sampling_setting_rule(te, rule, sizeof rule), "in (0, 1]") == 0, "rule %s", rule);
    CHECK(strcmp(rl_sampling_setting_rule(0, rule, sizeof rule), "culled, naive, area, solidangle or adaptive") == 0,
          "rule %s", rule);
    CHECK(!rl_sampling_setting_allows(pn, 3, 1) && rl_sampling_setting_allows(pn, 4096, 1), "power of two");
    CHECK(!rl_sampling_setting_allows(te, 0, 1) && rl_sampling_setting_allows(te, 1, 1), "(0, 1]");
    size_t seed = rl_sampling_setting_find("seed");
    CHECK(!rl_sampling_setting_allows(seed, 18446744073709549568.0, 1) &&
              rl_sampling_setting_allows(seed, 18446744073709549568.0, 0),
          "the seed's bound holds for text only");
    CHECK(rl_sampling_setting_find("threads") == n && rl_sampling_setting_find("time_budget") == n &&
              rl_sampling_setting_find(NULL) == n,
          "run options are not settings");
}

/* ----------------------------------------------------------- run options */

static void write_text(const char *name, const char *text);

/* Threads and the time budget are run options, checked by each call that runs the engine; a scene file's
 * time budget is only a suggestion, handed out by rl_job_default(). */
static void test_run_options(void)
{
    rl_run_options def;
    memset(&def, 0xff, sizeof def);
    rl_run_options_default(&def);
    CHECK(def.threads == 0 && def.progress == NULL && def.progress_user == NULL && def.time_budget == 0,
          "rl_run_options_default");
    rl_run_options_default(NULL);
    write_text("budget.json", "{\"materials\": {\"m\": {}}, \"polygons\": [{\"material\": \"m\", \"vertices\": [[0, 0, 0], [1, 0, 0], [1, 1, 0]]}],\n"
                              " \"sampling\": {\"method\": \"adaptive\", \"time_budget\": 2.5}}\n");
    rl_scene *s = load(tmpdir, "budget.json");
    if (!s)
        return;
    rl_job job, none;
    rl_job_default(s, &job);
    rl_job_default(NULL, &none);
    CHECK(job.run.time_budget == 2.5 && none.run.time_budget == 0, "scene time budget %g", job.run.time_budget);
    const struct {
        const char *field;
        rl_run_options value;
    } bad[] = {
        {"threads", {.threads = RL_MAX_THREADS + 1}},
        {"time_budget", {.time_budget = -1}},
        {"time_budget", {.time_budget = INFINITY}},
        {"time_budget", {.time_budget = NAN}},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        rl_solution *sol = (rl_solution *)&def;
        rl_ray_bench rb;
        double pt[6] = {0.5, 0.2, 1, 0, 0, -1}, e[3];
        rl_job b = job;
        b.run = bad[k].value;
        CHECK(rl_relight(s, &b, &sol) == RL_ERR_ARG && sol == NULL, "bad %s accepted", bad[k].field);
        CHECK(strstr(rl_errmsg(), bad[k].field) != NULL, "message '%s' names %s", rl_errmsg(), bad[k].field);
        CHECK(rl_irradiance(s, &b, pt, 1, e, NULL) == RL_ERR_ARG, "irradiance: bad %s accepted", bad[k].field);
        CHECK(rl_bench_rays(s, &bad[k].value, 10, &rb) == RL_ERR_ARG, "bench: bad %s accepted", bad[k].field);
    }
    rl_job one = job;
    one.run = (rl_run_options){.threads = 1};
    rl_solution *sol = NULL;
    CHECK(rl_relight(s, &one, &sol) == RL_OK && sol != NULL, "one thread: %s", rl_errmsg());
    CHECK(sol == NULL || rl_solution_render(sol, NULL, (float[3]){0}) == RL_ERR_ARG, "render without a camera");
    rl_solution_destroy(sol);
    CHECK(rl_relight(s, NULL, &sol) == RL_OK && sol != NULL, "NULL job: %s", rl_errmsg());
    rl_solution_destroy(sol);
    rl_scene_destroy(s);
}

/* ----------------------------------------------------------- light fields */

/* Writes text to tmpdir/name. */
static void write_text(const char *name, const char *text)
{
    char path[2048];
    FILE *f = fopen(join(path, sizeof path, tmpdir, name), "w");
    CHECK(f != NULL, "cannot write %s", path);
    if (f) {
        fputs(text, f);
        fclose(f);
    }
}

/* Writes tmpdir/lf.h5: slabs "a" (lfio's default 1 m square facing +z) and "light" (2 m, centred). @return 1 on success. */
static int write_lightfield(void)
{
    char path[2048];
    lfio_lightfield *lf = NULL;
    if (lfio_lightfield_new(&lf) != LFIO_OK)
        return 0;
    int ok = 1;
    for (int k = 0; k < 2 && ok; k++) {
        lfio_slab_desc d;
        lfio_slab_desc_init(&d);
        strcpy(d.name, k == 0 ? "a" : "light");
        if (k == 1) {
            d.origin[0] = -1, d.origin[1] = -1, d.origin[2] = 0;
            d.u[0] = 2, d.v[1] = 2;
        }
        lfio_slab *s = NULL;
        ok = lfio_slab_new(&d, &s) == LFIO_OK && lfio_lightfield_take_slab(lf, s) == LFIO_OK;
    }
    ok = ok && lfio_lightfield_write(lf, join(path, sizeof path, tmpdir, "lf.h5")) == LFIO_OK;
    CHECK(ok, "writing %s: %s", path, lfio_errmsg());
    lfio_lightfield_destroy(lf);
    return ok;
}

static void test_lightfields(void)
{
    if (!write_lightfield())
        return;
    write_text("lf_default.json", "{\"lightfields\": [{\"file\": \"lf.h5\"}]}\n");
    write_text("lf_named.json",
               "{\"lightfields\": [{\"file\": \"lf.h5\", \"slab\": \"light\",\n"
               "  \"transform\": [[1, 0, 0, 2.5], [0, -1, 0, 2.5], [0, 0, -1, 2.98], [0, 0, 0, 1]]}]}\n");
    write_text("lf_scaled.json", "{\"lightfields\": [{\"file\": \"lf.h5\", \"slab\": 1,\n"
                                 "  \"transform\": [0, -2, 0, 1, 2, 0, 0, 0, 0, 0, 2, 3, 0, 0, 0, 1]}]}\n");
    write_text("lf_two.json", "{\"lightfields\": [{\"file\": \"lf.h5\", \"slab\": 0}, {\"file\": \"lf.h5\", \"slab\": \"a\"},\n"
                              "  {\"file\": \"lf.h5\", \"slab\": \"light\"}]}\n");
    write_text("lf_noslab.json", "{\"lightfields\": [{\"file\": \"lf.h5\", \"slab\": \"nope\"}]}\n");
    write_text("lf_index.json", "{\"lightfields\": [{\"file\": \"lf.h5\", \"slab\": 2}]}\n");
    write_text("lf_negative.json", "{\"lightfields\": [{\"file\": \"lf.h5\", \"slab\": -1}]}\n");
    write_text("lf_late.json", "{\"lightfields\": [{\"file\": \"lf.h5\"}, {\"file\": \"lf.h5\", \"slab\": \"x\"}]}\n");

    rl_scene *s = load(tmpdir, "lf_default.json");
    uint64_t file_bytes = 0; /* the radiance of both of lf.h5's slabs, held whichever one the scene uses */
    if (s) {
        const rl_lightfield *lf = &s->lightfields[0];
        CHECK(rl_scene_lightfield_count(s) == 1 && lf->lf && lf->slab, "one light field");
        CHECK(lfio_lightfield_slab_count(lf->lf) == 2, "lf.h5 has two slabs");
        for (size_t k = 0; k < lfio_lightfield_slab_count(lf->lf); k++) {
            const lfio_slab_desc *d = lfio_slab_get_desc(lfio_lightfield_slab(lf->lf, k));
            file_bytes += (uint64_t)d->nu * d->nv * 4 * d->n * d->n * 3 * sizeof(float); /* 4n^2 directions */
        }
        CHECK(rl_scene_lightfield_bytes(s) == file_bytes, "light field bytes %llu, the file's radiance %llu",
              (unsigned long long)rl_scene_lightfield_bytes(s), (unsigned long long)file_bytes);
        CHECK(strcmp(lfio_slab_get_desc(lf->slab)->name, "a") == 0, "slab 0 by default");
        CHECK(lf->scale == 1 && lf->rot[0][0] == 1 && lf->rot[1][1] == 1 && lf->rot[2][2] == 1 && lf->rot[0][1] == 0,
              "identity by default");
        const lfio_slab_desc *d = lfio_slab_get_desc(lf->slab);
        CHECK(near3(lf->origin, d->origin[0], d->origin[1], d->origin[2], 0) && near3(lf->u, 1, 0, 0, 0) &&
                  near3(lf->v, 0, 1, 0, 0),
              "slab placed as stored");
        CHECK(strcmp(lf->label, "lightfields[0]") == 0, "label %s", lf->label);
        rl_scene_destroy(s);
    }
    s = load(tmpdir, "lf_named.json");
    if (s) {
        const rl_lightfield *lf = &s->lightfields[0];
        CHECK(strcmp(lfio_slab_get_desc(lf->slab)->name, "light") == 0, "slab by name");
        CHECK(near3(lf->origin, 1.5, 3.5, 2.98, 1e-15), "origin by the affine map: %g %g %g", lf->origin[0],
              lf->origin[1], lf->origin[2]);
        CHECK(near3(lf->u, 2, 0, 0, 0) && near3(lf->v, 0, -2, 0, 0), "u, v by the linear part");
        double n[3] = {lf->u[1] * lf->v[2] - lf->u[2] * lf->v[1], lf->u[2] * lf->v[0] - lf->u[0] * lf->v[2],
                       lf->u[0] * lf->v[1] - lf->u[1] * lf->v[0]};
        CHECK(n[2] < 0, "turned over: the slab faces down");
        CHECK(near3(lf->translate, 2.5, 2.5, 2.98, 0), "translation");
        rl_scene_destroy(s);
    }
    s = load(tmpdir, "lf_scaled.json");
    if (s) {
        const rl_lightfield *lf = &s->lightfields[0];
        CHECK(lf->scale == 2, "uniform scale %g", lf->scale);
        CHECK(lf->rot[0][1] == -1 && lf->rot[1][0] == 1 && lf->rot[2][2] == 1, "rotation part");
        CHECK(near3(lf->origin, 3, -2, 3, 1e-15) && near3(lf->u, 0, 4, 0, 0) && near3(lf->v, -4, 0, 0, 0),
              "scaled and turned: origin %g %g %g", lf->origin[0], lf->origin[1], lf->origin[2]);
        rl_scene_destroy(s);
    }
    s = load(tmpdir, "lf_two.json");
    if (s) {
        const rl_lightfield *l = s->lightfields;
        CHECK(rl_scene_lightfield_count(s) == 3 && l[0].slab && l[0].slab == l[1].slab && l[2].slab &&
                  l[2].slab != l[0].slab,
              "three emitters from one file, two of them one slab");
        CHECK(l[0].owns_lf && !l[1].owns_lf && !l[2].owns_lf && l[1].lf == l[0].lf && l[2].lf == l[0].lf,
              "the file is read once and shared");
        rl_slab_tables *t = rl__slab_tables_new(s); /* a run's: the scene holds none */
        CHECK(t && t[0].owned && !t[1].owned && t[1].support == t[0].support && t[2].owned &&
                  t[2].support != t[0].support,
              "a slab's support table is shared, another slab's is its own");
        rl__slab_tables_destroy(t, rl_scene_lightfield_count(s));
        CHECK(rl_scene_lightfield_bytes(s) == file_bytes, "three emitters of one file hold its radiance once: %llu",
              (unsigned long long)rl_scene_lightfield_bytes(s));
        rl_scene_destroy(s);
    }
    static const bad_case bad[] = {
        {"lf_noslab.json", RL_ERR_INPUT, "lightfields[0].slab: no slab named 'nope' in '"},
        {"lf_index.json", RL_ERR_INPUT, "lightfields[0].slab: slab index 2 is out of range"},
        {"lf_negative.json", RL_ERR_INPUT, "lightfields[0].slab: must be an integer in 0..4294967295, got -1"},
        {"lf_late.json", RL_ERR_INPUT, "lf.h5' (it has 'a', 'light')"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        char path[2048];
        rl_scene *t = NULL;
        rl_status st = rl_scene_load(join(path, sizeof path, tmpdir, bad[k].file), &t);
        CHECK(st == bad[k].status && !t, "%s: status %d", bad[k].file, (int)st);
        CHECK(strstr(rl_errmsg(), path) && strstr(rl_errmsg(), bad[k].expect), "%s: '%s'", bad[k].file, rl_errmsg());
    }
}

/* ---------------------------------------------------------- the settings */

/* A job is checked as a whole by rl_job_check() and by every call that solves; the scene it runs on is only
 * read, so its file's suggestion stays what it was. */
static void test_job_check(void)
{
    rl_scene *s = load(corpus, "good_minimal.json");
    if (!s)
        return;
    rl_job job, file;
    rl_job_default(s, &file);
    job = file;
    rl_sampling x;
    rl_sampling_default(&x);
    x.method = RL_METHOD_AREA, x.partition_n = 4096, x.rays_per_solid_angle = 65536;
    x.seed = UINT64_MAX;
    job.sampling = x;
    CHECK(job.size == sizeof job && rl_job_check(&job) == RL_OK, "valid settings: %s", rl_errmsg());
    const struct {
        const char *field;
        rl_sampling value;
    } bad[] = {
        {"partition_n", {.partition_n = 3, .rays_per_solid_angle = 1, .samples_per_cell = 1, .target_error = 0.05}},
        {"partition_n", {.partition_n = 8192, .rays_per_solid_angle = 1, .samples_per_cell = 1, .target_error = 0.05}},
        {"rays_per_solid_angle", {.partition_n = 1, .rays_per_solid_angle = 0, .samples_per_cell = 1, .target_error = 0.05}},
        {"samples_per_cell", {.partition_n = 1, .rays_per_solid_angle = 1, .samples_per_cell = 0, .target_error = 0.05}},
        {"bounces", {.partition_n = 1, .rays_per_solid_angle = 1, .samples_per_cell = 1, .bounces = 65, .target_error = 0.05}},
        {"descend", {.partition_n = 1, .rays_per_solid_angle = 1, .samples_per_cell = 1, .descend = 2, .target_error = 0.05}},
        {"bounce_cell_factor", {.partition_n = 1, .rays_per_solid_angle = 1, .samples_per_cell = 1, .bounce_cell_factor = 65,
                                .target_error = 0.05}},
        {"target_error", {.partition_n = 1, .rays_per_solid_angle = 1, .samples_per_cell = 1, .target_error = 0}},
        {"target_error", {.partition_n = 1, .rays_per_solid_angle = 1, .samples_per_cell = 1, .target_error = 2}},
        {"method", {.method = (rl_method)7, .partition_n = 1, .rays_per_solid_angle = 1, .samples_per_cell = 1, .target_error = 0.05}},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        rl_job b = job;
        b.sampling = bad[k].value;
        CHECK(rl_job_check(&b) == RL_ERR_ARG, "bad %s accepted", bad[k].field);
        CHECK(strstr(rl_errmsg(), bad[k].field) != NULL, "message '%s' names %s", rl_errmsg(), bad[k].field);
        rl_solution *sol = (rl_solution *)&b;
        CHECK(rl_relight(s, &b, &sol) == RL_ERR_ARG && sol == NULL, "relight: bad %s accepted", bad[k].field);
    }
    const struct {
        const char *field;
        size_t size;
        double cell_size;
    } bad_job[] = {
        {"cell_size", sizeof job, 0}, {"cell_size", sizeof job, -0.1}, {"cell_size", sizeof job, INFINITY},
        {"cell_size", sizeof job, NAN}, {"size", 0, 0.1}, {"size", sizeof job + 8, 0.1},
    };
    for (size_t k = 0; k < sizeof bad_job / sizeof bad_job[0]; k++) {
        rl_job b = job;
        b.size = bad_job[k].size, b.cell_size = bad_job[k].cell_size;
        CHECK(rl_job_check(&b) == RL_ERR_ARG, "bad %s accepted", bad_job[k].field);
        CHECK(strstr(rl_errmsg(), bad_job[k].field) != NULL, "message '%s' names %s", rl_errmsg(), bad_job[k].field);
    }
    CHECK(rl_job_check(NULL) == RL_ERR_ARG, "NULL job");
    rl_job again;
    rl_job_default(s, &again);
    CHECK(memcmp(&again.sampling, &file.sampling, sizeof x) == 0 && again.cell_size == file.cell_size,
          "the scene's suggestion kept");
    rl_job_default(s, NULL);
    rl_scene_destroy(s);

    rl_scene *none = (rl_scene *)&x;
    CHECK(rl_scene_load(NULL, &none) == RL_ERR_ARG && none == NULL, "NULL path");
    CHECK(rl_scene_load("x.json", NULL) == RL_ERR_ARG, "NULL out");
    rl_scene_destroy(NULL);
    rl_job def;
    rl_job_default(NULL, &def);
    CHECK(rl_scene_polygon_count(NULL) == 0, "NULL scene accessors");
    rl_sampling_default(&x);
    CHECK(memcmp(&def.sampling, &x, sizeof x) == 0 && def.cell_size == RL_DEFAULT_CELL_SIZE, "a NULL scene's job");
}

/* ----------------------------------------------------------- data scenes */

/* @return 1 if path names a file that can be opened. */
static int exists(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (f)
        fclose(f);
    return f != NULL;
}

/* Checks that the first five polygons (floor, ceiling, three walls) face the point c. */
static void check_room(const rl_scene *s, const char *name, double cx, double cy, double cz)
{
    for (size_t i = 0; i < 5 && i < s->npolygons; i++) {
        const rl_polygon *p = &s->polygons[i];
        const double *v = s->vertices[p->first];
        double d = (cx - v[0]) * p->normal[0] + (cy - v[1]) * p->normal[1] + (cz - v[2]) * p->normal[2];
        CHECK(d > 0, "%s: room surface %zu faces away from the room", name, i);
    }
}

static void test_data(void)
{
    char path[2048];
    rl_scene *s = load(datadir, "beams_diffuse.json");
    if (s) {
        CHECK(s->npolygons == 47 && s->nlightfields == 0, "beams_diffuse: %zu polygons", s->npolygons);
        CHECK(s->cell_size == 0.05 && s->sampling.partition_n == 32 && s->sampling.rays_per_solid_angle == 4 &&
                  s->sampling.bounces == 2 && s->has_camera,
              "beams_diffuse settings");
        size_t emitters = 0;
        for (size_t i = 0; i < s->npolygons; i++)
            if (s->materials[s->polygons[i].material].emission[0] > 0) {
                emitters++;
                CHECK(s->polygons[i].normal[2] < -0.999, "the emitter faces down");
            }
        CHECK(emitters == 1, "one diffuse emitter, got %zu", emitters);
        check_room(s, "beams_diffuse.json", 2.5, 2.5, 1.5);
        check_invariants(s, "beams_diffuse.json");
        rl_scene_destroy(s);
    }
    s = load(datadir, "classroom.json");
    if (s) {
        CHECK(s->npolygons >= 2800 && s->npolygons <= 3200, "classroom: %zu polygons", s->npolygons);
        CHECK(s->cell_size == 0.1 && s->sampling.bounces == 0 && s->has_camera, "classroom settings");
        size_t emitters = 0;
        for (size_t i = 0; i < s->npolygons; i++)
            emitters += s->materials[s->polygons[i].material].emission[0] > 0;
        CHECK(emitters == 4, "four ceiling emitters, got %zu", emitters);
        check_room(s, "classroom.json", 5, 4, 1.6);
        check_invariants(s, "classroom.json");
        rl_scene_destroy(s);
    }
    if (!exists(join(path, sizeof path, datadir, "beams_lightfield.h5"))) {
        printf("%s missing: beams.json not loaded (see data/README.md)\n", path);
        return;
    }
    s = load(datadir, "beams.json");
    if (s) {
        CHECK(s->npolygons == 46 && s->nlightfields == 1, "beams: %zu polygons, %zu light fields", s->npolygons,
              s->nlightfields);
        if (s->nlightfields == 1) {
            const rl_lightfield *lf = &s->lightfields[0];
            double nz = lf->u[0] * lf->v[1] - lf->u[1] * lf->v[0];
            CHECK(nz < 0 && lf->origin[2] > 2.5 && lf->origin[2] < 3, "the light field hangs below the ceiling, facing down");
        }
        check_room(s, "beams.json", 2.5, 2.5, 1.5);
        check_invariants(s, "beams.json");
        rl_scene_destroy(s);
    }
}

/* ------------------------------------------------------ coarse bounces */

/*
 * rl__map_interpolate(), which carries bounce light from the coarse cells it is
 * gathered on to the radiance cells: a field linear in the map's frame,
 * given at the coarse cells' centres, comes back exactly at every fine cell
 * whose four surrounding centres exist, and nowhere outside the range of
 * the coarse values (no overshoot at the edges of a triangle).
 */
static void test_interpolation(void)
{
    write_text("interp.json", "{\"materials\": {\"g\": {}}, \"polygons\": ["
                              "{\"material\": \"g\", \"vertices\": [[0,0,0],[2,0,0],[2,1.5,0],[0,1.5,0]]},"
                              "{\"material\": \"g\", \"vertices\": [[0,0,1],[1.3,0,1],[0,1.1,1]]}],"
                              "\"radiance_maps\": {\"cell_size\": 0.05}}");
    rl_scene *s = load(tmpdir, "interp.json");
    rl_map *fine = NULL, *coarse = NULL;
    size_t nf = 0, nc = 0;
    if (!s || rl__maps_build(s, s->cell_size, s->sampling.bounces > 0, 3, &fine, &nf) != RL_OK || rl__maps_build_sized(s, 0.2, 1, &coarse, &nc) != RL_OK) {
        CHECK(0, "maps: %s", rl_errmsg());
        rl__maps_free(fine, nf);
        rl_scene_destroy(s);
        return;
    }
    CHECK(nf == 2 && nc == 2, "%zu fine and %zu coarse maps", nf, nc);
    /* cells clipped on three threads are those of one */
    rl_map *one = NULL;
    size_t none = 0;
    CHECK(rl__maps_build(s, s->cell_size, s->sampling.bounces > 0, 1, &one, &none) == RL_OK && none == nf, "maps on one thread: %s", rl_errmsg());
    for (size_t m = 0; one && m < none && m < nf; m++) {
        int same = one[m].ncells == fine[m].ncells && one[m].nu == fine[m].nu && one[m].nv == fine[m].nv;
        for (uint32_t k = 0; same && k < one[m].ncells; k++) {
            rl_cell a = rl__map_cell(&one[m], k), b = rl__map_cell(&fine[m], k);
            same = a.i == b.i && a.j == b.j && a.clipped == b.clipped;
        }
        CHECK(same, "map %zu: cells on three threads differ from one's", m);
    }
    rl__maps_free(one, none);
    for (size_t m = 0; m < nf && m < nc; m++) {
        rl_map *c = &coarse[m], *f = &fine[m];
        double lo = INFINITY, hi = -INFINITY;
        for (uint32_t k = 0; k < c->ncells; k++) {
            const rl_cell ck = rl__map_cell(c, k);
            double u = c->u0 + (ck.i + 0.5) * c->cell, v = c->v0 + (ck.j + 0.5) * c->cell;
            for (int ch = 0; ch < 3; ch++)
                c->e_pass[k][ch] = 1.0 + 2.0 * u - 3.0 * v + ch;
            lo = fmin(lo, c->e_pass[k][0]);
            hi = fmax(hi, c->e_pass[k][0]);
        }
        rl__map_interpolate(c, NULL, f);
        long exact = 0, interior = 0, outside = 0;
        for (uint32_t k = 0; k < f->ncells; k++) {
            v2 poly[RL_MAX_POLY_VERTS + 4];
            v2 q = rl__polygon_centroid(poly, rl__map_cell_polygon(f, k, poly));
            double a = (q.x - c->u0) / c->cell - 0.5, b = (q.y - c->v0) / c->cell - 0.5;
            int i0 = (int)floor(a), j0 = (int)floor(b), all = i0 >= 0 && j0 >= 0 && i0 + 1 < (int)c->nu &&
                                                         j0 + 1 < (int)c->nv;
            for (int dj = 0; all && dj <= 1; dj++)
                for (int di = 0; all && di <= 1; di++)
                    all = rl__map_grid_cell(c, (size_t)(i0 + di), (size_t)(j0 + dj)) >= 0;
            outside += !(f->e_pass[k][0] >= lo - 1e-12 && f->e_pass[k][0] <= hi + 1e-12);
            if (!all)
                continue;
            interior++;
            exact += fabs(f->e_pass[k][0] - (1.0 + 2.0 * q.x - 3.0 * q.y)) < 1e-9 &&
                     fabs(f->e_pass[k][2] - (3.0 + 2.0 * q.x - 3.0 * q.y)) < 1e-9;
        }
        CHECK(interior > 0 && exact == interior, "map %zu: %ld of %ld interior cells linear", m, exact, interior);
        CHECK(outside == 0, "map %zu: %ld cells outside the coarse range", m, outside);
    }
    rl__maps_free(fine, nf);
    rl__maps_free(coarse, nc);
    rl_scene_destroy(s);
}

/*
 * rl__polygon_holds(), which tells an occluder above a polygon's inside from
 * one at its edge, and rl__map_mark_direct(), which marks the fine cells of
 * every coarse cell that is flagged or has a flagged neighbour: exactly the
 * fine cells whose centroid lies in the 3 x 3 coarse cells around the flag.
 */
static void test_mark_direct(void)
{
    const v2 square[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    const v2 tri[3] = {{0, 0}, {2, 0}, {0, 1}};
    CHECK(rl__polygon_holds(square, 4, (v2){0.5, 0.5}, 0.49) && !rl__polygon_holds(square, 4, (v2){0.5, 0.5}, 0.51),
          "holds: the square's centre is 0.5 from its edges");
    CHECK(rl__polygon_holds(square, 4, (v2){1.0, 0.5}, 0.0) && !rl__polygon_holds(square, 4, (v2){1.0, 0.5}, 1e-9) &&
              !rl__polygon_holds(square, 4, (v2){1.1, 0.5}, 0.0) && !rl__polygon_holds(square, 4, (v2){0.5, -1e-9}, 0),
          "holds: on an edge only with no margin, never outside");
    CHECK(rl__polygon_holds(tri, 3, (v2){0.5, 0.25}, 0.2) && !rl__polygon_holds(tri, 3, (v2){1.2, 0.5}, 0.0),
          "holds: a triangle's inside and a point past its long edge");
    write_text("mark.json", "{\"materials\": {\"g\": {}}, \"polygons\": ["
                            "{\"material\": \"g\", \"vertices\": [[0,0,0],[2,0,0],[2,1.5,0],[0,1.5,0]]}],"
                            "\"radiance_maps\": {\"cell_size\": 0.05}}");
    rl_scene *s = load(tmpdir, "mark.json");
    rl_map *fine = NULL, *coarse = NULL;
    size_t nf = 0, nc = 0;
    if (!s || rl__maps_build(s, s->cell_size, s->sampling.bounces > 0, 1, &fine, &nf) != RL_OK || rl__maps_build_sized(s, 0.2, 2, &coarse, &nc) != RL_OK ||
        nf != 1 || nc != 1) {
        CHECK(0, "maps: %s", rl_errmsg());
        rl__maps_free(fine, nf);
        rl__maps_free(coarse, nc);
        rl_scene_destroy(s);
        return;
    }
    rl_map *c = &coarse[0], *f = &fine[0];
    uint8_t *near = calloc(c->ncells, 1), *gathered = calloc(c->ncells, 1), *subset = calloc(f->ncells, 1);
    CHECK(near && gathered && subset, "mark: out of memory");
    if (near && gathered && subset) {
        c->near = near;
        CHECK(rl__map_mark_direct(c, f, gathered, subset) == 0, "mark: nothing flagged, nothing marked");
        for (int flagged = 0; flagged < 2; flagged++) {
            /* an inside cell, then the corner cell */
            uint32_t ci = flagged ? 0 : 4, cj = flagged ? 0 : 3;
            int32_t cell = rl__map_grid_cell(c, ci, (size_t)cj);
            memset(near, 0, c->ncells);
            near[cell] = 1;
            uint32_t marked = rl__map_mark_direct(c, f, gathered, subset), want = 0, agree = 0;
            for (uint32_t k = 0; k < f->ncells; k++) {
                /* the fine grid nests in the coarse one: 4 x 4 fine cells to a coarse cell */
                long di = (long)(rl__map_cell(f, k).i / 4) - (long)ci, dj = (long)(rl__map_cell(f, k).j / 4) - (long)cj;
                int w = labs(di) <= 1 && labs(dj) <= 1;
                want += (uint32_t)w;
                agree += (uint32_t)(w == subset[k]);
            }
            CHECK(marked == want && agree == f->ncells && want > 0, "mark: %u marked, %u expected, %u of %u agree",
                  marked, want, agree, f->ncells);
            uint32_t ngathered = 0;
            for (uint32_t k = 0; k < c->ncells; k++) {
                ngathered += gathered[k];
                for (int ch = 0; ch < 3; ch++)
                    c->e_pass[k][ch] = gathered[k] ? 1e6 : 1.0;
            }
            CHECK(ngathered == (flagged ? 4u : 9u), "mark: %u coarse cells gathered", ngathered);
            /* the interpolated cells never read a gathered coarse cell, and the gathered cells keep theirs */
            for (uint32_t k = 0; k < f->ncells; k++)
                f->e_pass[k][0] = f->e_pass[k][2] = -7.0;
            f->subset = subset;
            rl__map_interpolate(c, gathered, f);
            f->subset = NULL;
            uint32_t ones = 0, kept = 0;
            for (uint32_t k = 0; k < f->ncells; k++) {
                ones += !subset[k] && f->e_pass[k][0] == 1.0 && f->e_pass[k][2] == 1.0;
                kept += subset[k] && f->e_pass[k][0] == -7.0 && f->e_pass[k][2] == -7.0;
            }
            CHECK(ones == f->ncells - marked && kept == marked,
                  "mark: %u of %u interpolated cells read only the others, %u of %u gathered cells untouched", ones,
                  f->ncells - marked, kept, marked);
        }
    }
    c->near = NULL;
    free(near);
    free(gathered);
    free(subset);
    rl__maps_free(fine, nf);
    rl__maps_free(coarse, nc);
    rl_scene_destroy(s);
}

/* The cell budget: a map whose grid alone exceeds it fails the build, named, on one thread or several
 * (the several-thread build places every grid first), and nothing is kept. */
static void test_cell_budget(void)
{
    write_text("budget.json", "{\"materials\": {\"g\": {}}, \"polygons\": ["
                              "{\"material\": \"g\", \"vertices\": [[0,0,0],[1,0,0],[1,1,0],[0,1,0]]},"
                              "{\"material\": \"g\", \"vertices\": [[0,0,1],[0,1000,1],[1000,1000,1],[1000,0,1]]}],"
                              "\"radiance_maps\": {\"cell_size\": 0.05}}");
    rl_scene *s = load(tmpdir, "budget.json");
    CHECK(s != NULL, "budget: %s", rl_errmsg());
    for (unsigned threads = 1; s && threads <= 2; threads++) {
        rl_map *maps = NULL;
        size_t n = 7;
        rl_status st = rl__maps_build(s, s->cell_size, s->sampling.bounces > 0, threads, &maps, &n);
        CHECK(st == RL_ERR_INPUT && maps == NULL && n == 0, "budget, %u threads: status %d, %zu maps", threads,
              (int)st, n);
        CHECK(strstr(rl_errmsg(), "polygons[1]: more than 67108864 radiance cells") != NULL,
              "budget, %u threads: message '%s'", threads, rl_errmsg());
        rl__maps_free(maps, n);
    }
    rl_scene_destroy(s);
}

/* ------------------------------------------------------- mesh formats */

/* The room of tests/scenes/rooms in every format gen_rooms.py writes. */
static const char *const room_formats[] = {"obj", "gltf", "glb", "ply", "stl", "fbx", "3ds"};
#define ROOM_FORMATS (sizeof room_formats / sizeof *room_formats)

/* Points of the room (x y z, normal): under the lamp's centre facing up, low on a wall, on another wall. */
static const double room_points[] = {1, 1, 0.5, 0, 0, 1, 0.3, 0.4, 1, 1, 0, 0, 1.5, 1.8, 1.2, 0, -1, 0};
#define ROOM_POINTS 3

/* Irradiance under the centre of a square of radiance L, half side a, at height h (Lambert's formula). */
static double square_irradiance(double L, double a, double h)
{
    double x = a / h, r = sqrt(1 + x * x);
    return 4 * ILF_PI * L * (2 * x / r * atan(x / r)) / (2 * ILF_PI);
}

/* Loads the room in format fmt, checks its polygons and lamp, and writes its irradiance at room_points
 * (one bounce) to e and its view to img (48 x 36 rgb). @return 1, or 0 on a failure reported. */
static int room_measure(const char *fmt, double e[3 * ROOM_POINTS], float *img)
{
    char dir[2048], name[64];
    snprintf(dir, sizeof dir, "%s/rooms", corpus);
    snprintf(name, sizeof name, "room_%s.json", fmt);
    rl_scene *s = load(dir, name);
    if (!s)
        return 0;
    /* six walls and the lamp, whatever the format made of them (glTF, STL, 3DS: triangles) */
    CHECK(s->npolygons == 7, "%s: %zu polygons, 7 expected (the triangles of each wall merged)", fmt, s->npolygons);
    double lamp = -1;
    for (size_t k = 0; k < s->nmaterials; k++)
        if (s->materials[k].emission[0] > 0)
            lamp = s->materials[k].emission[0];
    CHECK(lamp == 20, "%s: the lamp's radiance is %g W sr^-1 m^-2, 20 expected", fmt, lamp);
    for (size_t i = 0; i < s->npolygons; i++) {
        const rl_polygon *p = &s->polygons[i];
        CHECK(p->count == 4 && fabs(p->area - (s->materials[p->material].emission[0] > 0 ? 0.64 : 4)) < 1e-6,
              "%s: polygon %zu (%s) has %u vertices and area %g", fmt, i, p->label, p->count, p->area);
    }
    check_invariants(s, name);
    rl_job job;
    rl_job_default(s, &job);
    rl_solution *sol = NULL;
    int ok = rl_irradiance(s, &job, room_points, ROOM_POINTS, e, NULL) == RL_OK &&
             rl_relight(s, &job, &sol) == RL_OK && rl_solution_render(sol, &job.run, img) == RL_OK;
    CHECK(ok, "%s: %s", fmt, rl_errmsg());
    /* direct light alone under the lamp's centre: Lambert's formula for a 0.8 m square 1.4 m above */
    job.sampling.bounces = 0;
    double d[3] = {0, 0, 0}, exact = square_irradiance(20, 0.4, 1.4);
    ok = ok && rl_irradiance(s, &job, room_points, 1, d, NULL) == RL_OK;
    CHECK(ok && fabs(d[0] / exact - 1) < 1e-6, "%s: direct light %.7g W m^-2 under the lamp, %.7g expected", fmt,
          d[0], exact);
    rl_solution_destroy(sol);
    rl_scene_destroy(s);
    return ok;
}

/*
 * The same room from every format gives the same light: the lamp's
 * radiance (OBJ's Ke 20, glTF's emissiveFactor 1 times
 * KHR_materials_emissive_strength 20, FBX's EmissiveColor 1 times
 * EmissiveFactor 20, 3DS, the PLY and STL entries' material), the axes
 * (glTF and FBX are Y-up) and the walls (glTF, STL and 3DS write each as
 * two triangles, merged back). In every format the direct light under the
 * lamp is Lambert's closed form to 1e-6; irradiance with one bounce agrees
 * with OBJ's within 0.1%, and so does the view, pixel by pixel: a
 * triangulated wall left in triangles (the diagonal seam of the smooth
 * view) differs by tens of per cent.
 */
static void test_mesh_formats(void)
{
    enum { W = 48, H = 36 };
    static float img[ROOM_FORMATS][W * H * 3];
    double e[ROOM_FORMATS][3 * ROOM_POINTS];
    int ok[ROOM_FORMATS];
    for (size_t f = 0; f < ROOM_FORMATS; f++)
        ok[f] = room_measure(room_formats[f], e[f], img[f]);
    if (!ok[0])
        return;
    /* one bounce adds to the direct light, never removes */
    double direct = square_irradiance(20, 0.4, 1.4);
    CHECK(e[0][0] > direct && e[0][0] < 1.3 * direct, "OBJ: %g W m^-2 under the lamp, direct alone %g", e[0][0],
          direct);
    float peak = 0;
    for (size_t k = 0; k < W * H * 3; k++)
        peak = fmaxf(peak, img[0][k]);
    CHECK(peak > 0, "the OBJ room's view is black");
    for (size_t f = 1; f < ROOM_FORMATS; f++) {
        if (!ok[f])
            continue;
        double worst = 0;
        for (size_t k = 0; k < 3 * ROOM_POINTS; k++)
            worst = fmax(worst, fabs(e[f][k] / e[0][k] - 1));
        CHECK(worst <= 1e-3, "%s: irradiance differs from OBJ's by %.3g%%", room_formats[f], 100 * worst);
        double diff = 0; /* relative, pixel by pixel: the walls are 40 times darker than the lamp */
        for (size_t k = 0; k < W * H * 3; k++)
            diff = fmax(diff, fabs(img[f][k] - img[0][k]) / fmax(img[0][k], 1e-6 * peak));
        CHECK(diff <= 1e-3, "%s: a pixel of the view differs from OBJ's by %.3g%%", room_formats[f], 100 * diff);
    }
}

/* Writes tmpdir/name from an OBJ body and loads it as the only mesh, material "m". @return the scene or NULL. */
static rl_scene *load_obj(const char *name, const char *obj, const char *entry_extra)
{
    char json[1024], scene[128];
    write_text(name, obj);
    snprintf(json, sizeof json, "{\"materials\": {\"m\": {}, \"lamp\": {\"emission\": [2, 2, 2]}}, "
             "\"meshes\": [{\"file\": \"%s\", \"material\": \"m\"%s}]}", name, entry_extra);
    snprintf(scene, sizeof scene, "%s.json", name);
    write_text(scene, json);
    return load(tmpdir, scene);
}

/*
 * rl_scene_load_with(): a scene's light fields read on 1 and on 3 threads hold the same radiance as with the
 * defaults; threads past the limit and a size the library does not know are refused by name.
 */
static void test_load_options(void)
{
    char path[2048];
    join(path, sizeof path, tmpdir, "lf_default.json");
    rl_scene *want = load(tmpdir, "lf_default.json");
    for (unsigned threads = 1; want && threads <= 3; threads += 2) {
        rl_scene_load_options opt;
        rl_scene_load_options_default(&opt);
        opt.threads = threads;
        rl_scene *s = NULL;
        CHECK(rl_scene_load_with(path, &opt, &s) == RL_OK && s, "load on %u threads: %s", threads, rl_errmsg());
        for (size_t k = 0; s && k < lfio_lightfield_slab_count(want->lightfields[0].lf); k++) {
            const lfio_slab *a = lfio_lightfield_slab(want->lightfields[0].lf, k);
            const lfio_slab *b = lfio_lightfield_slab(s->lightfields[0].lf, k);
            size_t bytes = (size_t)lfio_slab_desc_bytes(lfio_slab_get_desc(a));
            CHECK(b && memcmp(lfio_slab_radiance(a), lfio_slab_radiance(b), bytes) == 0,
                  "slab %zu on %u threads: the same radiance", k, threads);
        }
        rl_scene_destroy(s);
    }
    rl_scene_destroy(want);
    rl_scene_load_options opt;
    rl_scene_load_options_default(&opt);
    CHECK(opt.size == sizeof opt && opt.threads == 0, "load defaults");
    opt.threads = 1025;
    rl_scene *s = NULL;
    CHECK(rl_scene_load_with(path, &opt, &s) == RL_ERR_ARG && s == NULL && strstr(rl_errmsg(), "threads 1025"),
          "too many threads: %s", rl_errmsg());
    opt.threads = 1;
    opt.size = sizeof opt + 8;
    CHECK(rl_scene_load_with(path, &opt, &s) == RL_ERR_ARG && s == NULL &&
              strstr(rl_errmsg(), "rl_scene_load_options.size"), "unknown size: %s", rl_errmsg());
}

/*
 * Merging: a hexagon written as a fan of four triangles comes back as the
 * hexagon; a coplanar neighbour of another material, one bent out of the
 * plane, two coplanar triangles that only touch at a corner, and an L of
 * two quads (whose union is not convex) stay apart.
 */
static void test_mesh_merge(void)
{
    rl_scene *s = load_obj("fan.obj",
                           "v 0 0 0\nv 2 0 0\nv 3 1 0\nv 2 2 0\nv 0 2 0\nv -1 1 0\n"
                           "f 1 2 3\nf 1 3 4\nf 1 4 5\nf 1 5 6\n"
                           "v 3 1 0\nv 2 0 0\nv 4 0 1\nf 7 8 9\n" /* shares the edge 2-3, bent out of plane */
                           "v 10 0 0\nv 11 0 0\nv 11 1 0\nv 12 1 0\nv 12 2 0\n"
                           "f 10 11 12\nf 12 13 14\n" /* meet at a corner */
                           "v 20 0 0\nv 21 0 0\nv 21 1 0\nv 20 1 0\nv 22 -1 0\n"
                           "f 15 16 17 18\nf 15 19 16\n", /* share an edge; their union is not convex */
                           "");
    if (!s)
        return;
    size_t hexagon = 0, triangles = 0, quads = 0;
    for (size_t i = 0; i < s->npolygons; i++) {
        hexagon += s->polygons[i].count == 6 && fabs(s->polygons[i].area - 6) < 1e-12 &&
                   strstr(s->polygons[i].label, "face 0 (+3 merged)") != NULL;
        triangles += s->polygons[i].count == 3;
        quads += s->polygons[i].count == 4;
    }
    CHECK(hexagon == 1, "the fan of four triangles is one hexagon labelled 'face 0 (+3 merged)'");
    CHECK(s->npolygons == 6 && triangles == 4 && quads == 1, "%zu polygons: %zu triangles, %zu quads",
          s->npolygons, triangles, quads);
    check_invariants(s, "fan.obj");
    rl_scene_destroy(s);
    /* the two triangles of a quad, one lit and one not: not merged */
    write_text("twomat.mtl", "newmtl A\nKd 0.5 0.5 0.5\nnewmtl B\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
    s = load_obj("twomat.obj", "mtllib twomat.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                 "usemtl A\nf 1 2 3\nusemtl B\nf 1 3 4\n", "");
    if (s) {
        CHECK(s->npolygons == 2, "triangles of different materials merged: %zu polygons", s->npolygons);
        rl_scene_destroy(s);
    }
}

/* Irradiance at (0.5, 0.5, z) facing the way sign says. @return its red channel, or -1 on failure. */
static double lamp_side(const rl_scene *s, double z, double sign)
{
    double p[6] = {0.5, 0.5, z, 0, 0, sign}, e[3];
    rl_status st = rl_irradiance(s, NULL, p, 1, e, NULL); /* the job the scene file suggests */
    CHECK(st == RL_OK, "irradiance: %s", rl_errmsg());
    return st == RL_OK ? e[0] : -1;
}

/* The view of a two-sided unit square lamp of radiance 3 (two coincident polygons, back to back) from above
 * and from below: every pixel that sees it shows its radiance, whichever of the two the ray meets first. */
static void two_sided_view(rl_scene *s)
{
    enum { N = 16 };
    float img[N * N * 3];
    for (int side = 0; side < 2; side++) {
        double z = side ? -1 : 1;
        rl_camera *c = &s->camera;
        *c = (rl_camera){{0.5, 0.5, z}, {0.5, 0.5, 0}, {0, 1, 0}, 30, N, N};
        s->has_camera = 1;
        rl_solution *sol = NULL;
        int ok = rl_relight(s, NULL, &sol) == RL_OK && rl_solution_render(sol, NULL, img) == RL_OK;
        CHECK(ok, "two-sided view: %s", rl_errmsg());
        size_t lit = 0;
        for (size_t k = 0; ok && k < N * N * 3; k++)
            lit += img[k] == 3.0f;
        CHECK(lit == N * N * 3, "two-sided lamp seen from %s: %zu of %d channels show its radiance",
              side ? "below" : "above", lit, N * N * 3);
        rl_solution_destroy(sol);
    }
}

/*
 * Per-mesh options: a unit square lamp facing up (counter-clockwise from
 * above) lights a point above it and not one below; "flip": true turns it
 * over; "two_sided": true lights both, each as much as the one side alone;
 * "up": "y" turns the file's +y to the scene's +z.
 */
static void test_mesh_options(void)
{
    static const char *const square = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
    const char *extra[] = {"", ", \"flip\": true", ", \"two_sided\": true", ", \"flip\": 1, \"two_sided\": 1"};
    double above[4], below[4];
    size_t count[4] = {0};
    for (int k = 0; k < 4; k++) {
        char name[32], entry[96];
        snprintf(name, sizeof name, "lamp%d.obj", k);
        snprintf(entry, sizeof entry, "%s", extra[k]);
        char json[512], scene[64];
        write_text(name, square);
        snprintf(json, sizeof json, "{\"materials\": {\"lamp\": {\"albedo\": [0, 0, 0], \"emission\": [3, 3, 3]}}, "
                 "\"meshes\": [{\"file\": \"%s\", \"material\": \"lamp\"%s}], \"sampling\": {\"bounces\": 0}}",
                 name, entry);
        snprintf(scene, sizeof scene, "%s.json", name);
        write_text(scene, json);
        rl_scene *s = load(tmpdir, scene);
        above[k] = s ? lamp_side(s, 0.5, -1) : -1;
        below[k] = s ? lamp_side(s, -0.5, 1) : -1;
        count[k] = s ? s->npolygons : 0;
        if (s)
            check_invariants(s, scene);
        if (s && k == 2)
            two_sided_view(s);
        rl_scene_destroy(s);
    }
    double lit = square_irradiance(3, 0.5, 0.5);
    CHECK(fabs(above[0] / lit - 1) < 1e-3 && below[0] == 0, "one-sided: %g above (%g expected), %g below", above[0],
          lit, below[0]);
    CHECK(above[1] == 0 && fabs(below[1] / lit - 1) < 1e-3, "flip: %g above, %g below", above[1], below[1]);
    CHECK(fabs(above[2] / lit - 1) < 1e-3 && fabs(below[2] / lit - 1) < 1e-3 && count[2] == 2,
          "two_sided: %g above, %g below, %zu polygons", above[2], below[2], count[2]);
    CHECK(fabs(above[3] / lit - 1) < 1e-3 && fabs(below[3] / lit - 1) < 1e-3 && count[3] == 2,
          "flip and two_sided: %g above, %g below", above[3], below[3]);

    /* "up": the glTF room as stored (+y up) puts its lamp at y = 1.9; the default turns it to z = 1.9 */
    char dir[2048];
    snprintf(dir, sizeof dir, "%s/rooms", corpus);
    char json[2300], *abs = realpath(dir, NULL); /* the scene is in tmpdir */
    snprintf(json, sizeof json, "{\"meshes\": [{\"file\": \"%s/room.gltf\", \"up\": \"z\"}]}", abs ? abs : dir);
    free(abs);
    write_text("room_asis.json", json);
    for (int asis = 0; asis < 2; asis++) {
        rl_scene *s = asis ? load(tmpdir, "room_asis.json") : load(dir, "room_gltf.json");
        double lamp_y = NAN, lamp_z = NAN;
        for (size_t i = 0; s && i < s->npolygons; i++)
            if (s->materials[s->polygons[i].material].emission[0] > 0) {
                lamp_y = s->vertices[s->polygons[i].first][1];
                lamp_z = s->vertices[s->polygons[i].first][2];
            }
        if (asis)
            CHECK(fabs(lamp_y - 1.9) < 1e-6, "\"up\": \"z\" keeps glTF's +y up: lamp at y = %g", lamp_y);
        else
            CHECK(fabs(lamp_z - 1.9) < 1e-6, "glTF's +y turned up by default: lamp at z = %g", lamp_z);
        rl_scene_destroy(s);
    }
}

/* Writes tmpdir/name: the text of tests/scenes/rooms/room.<ext> with its first `from` replaced by `to`.
 * @return 1, or 0 with a failure reported when from is not there. */
static int room_variant(const char *ext, const char *from, const char *to, const char *name)
{
    char path[2048];
    snprintf(path, sizeof path, "%s/rooms/room.%s", corpus, ext);
    FILE *f = fopen(path, "rb");
    static char text[65536], out[65536 + 64];
    size_t n = f ? fread(text, 1, sizeof text - 1, f) : 0;
    if (f)
        fclose(f);
    text[n] = '\0';
    char *at = strstr(text, from);
    CHECK(at != NULL && strlen(to) <= 64, "room.%s has no '%s'", ext, from);
    if (!at || strlen(to) > 64)
        return 0;
    snprintf(out, sizeof out, "%.*s%s%s", (int)(at - text), text, to, at + strlen(from));
    write_text(name, out);
    return 1;
}

/* An FBX room in centimetres (UnitScaleFactor 1) comes in a hundred times smaller than the same room in
 * metres (100): its lamp 1.9 cm up, not 1.9 m. */
static void test_mesh_fbx_units(void)
{
    if (!room_variant("fbx", "\"UnitScaleFactor\", \"double\", \"Number\", \"\", 100",
                      "\"UnitScaleFactor\", \"double\", \"Number\", \"\", 1", "room_cm.fbx"))
        return;
    write_text("room_cm.json", "{\"meshes\": [{\"file\": \"room_cm.fbx\"}]}");
    rl_scene *s = load(tmpdir, "room_cm.json");
    double top = -INFINITY;
    for (size_t k = 0; s && k < s->nvertices; k++)
        top = fmax(top, s->vertices[k][2]);
    CHECK(s && fabs(top - 0.02) < 1e-9, "an FBX file in centimetres: its 2 m room is %g m high, 0.02 expected", top);
    rl_scene_destroy(s);
}

/* A glTF lamp whose KHR_materials_emissive_strength is negative is refused, naming the material. */
static void test_mesh_bad_strength(void)
{
    if (!room_variant("gltf", "\"emissiveStrength\": 20", "\"emissiveStrength\": -2", "negative.gltf"))
        return;
    write_text("negative.json", "{\"meshes\": [{\"file\": \"negative.gltf\"}]}");
    rl_scene *s = NULL;
    char path[2048];
    snprintf(path, sizeof path, "%s/negative.json", tmpdir);
    rl_status st = rl_scene_load(path, &s);
    CHECK(st == RL_ERR_INPUT && strstr(rl_errmsg(), "materials[1]: KHR_materials_emissive_strength") != NULL,
          "negative strength: status %d: %s", (int)st, rl_errmsg());
    rl_scene_destroy(s);
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: test_scene SCENES_DIR DATA_DIR\n");
        return 2;
    }
    corpus = argv[1];
    datadir = argv[2];
    const char *base = getenv("ILF_TEST_TMP");
    base = base && *base ? base : "/tmp";
    snprintf(tmpdir, sizeof tmpdir, "%s/test_scene", base);
    mkdir(base, 0777); /* either may exist already */
    mkdir(tmpdir, 0777);

    test_minimal();
    test_full();
    test_meshes();
    test_bad();
    test_lightfields();
    test_load_options();
    test_job_check();
    test_settings_table();
    test_run_options();
    test_data();
    test_interpolation();
    test_mark_direct();
    test_cell_budget();
    test_mesh_formats();
    test_mesh_merge();
    test_mesh_options();
    test_mesh_bad_strength();
    test_mesh_fbx_units();
    return check_report();
}
