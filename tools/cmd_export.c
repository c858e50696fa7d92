/*
 * cmd_export.c - `ilf export RADIANCE.h5 -o OUT.glb|OUT.ply|OUT.csv`: the
 * relit surfaces of a radiance map (radiance.h5 of `ilf relight`) for the
 * tools users already have: glTF 2.0 binary for viewers and Blender, PLY
 * with vertex colours, CSV of the cells for a spreadsheet.
 *
 * Geometry: every stored cell becomes its square clipped to its polygon
 * (radmap_mesh.c), fanned into triangles, with vertices of its own so that
 * a cell's colour is flat. Colours: the cell's radiance toward any viewer,
 * radiosity / pi (the surfaces are Lambertian), times one exposure factor
 * (--exposure, --scale, or 1 / the 99th percentile of max(r, g, b) over the
 * cells), clamped to [0, 1]. glTF's COLOR_0 is linear by its specification,
 * so it holds that display value linear (viewers encode it for the screen);
 * PLY's 8-bit colours are sRGB-encoded. The linear physical values are kept
 * beside them: glTF attributes _IRRADIANCE and _RADIOSITY (W m^-2, float
 * VEC3), PLY properties irradiance_r.. and radiosity_r.., CSV columns.
 *
 * Invariants: the radiance map is read only through lfio's public reader;
 * every output is built whole in memory and written atomically; the format
 * is the output's extension unless --format names it.
 */
#include <cjson/cJSON.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "image/image.h"
#include "jsonout.h"
#include "radmap_cli.h"
#include "radmap_mesh.h"
#include "tonemap.h"

typedef enum export_format { FMT_NONE, FMT_GLB, FMT_PLY, FMT_CSV } export_format;

typedef struct export_options {
    const char *path;
    const char *output;
    export_format format;
    tone_fixed tone;
} export_options;

enum export_option_id { OPT_OUTPUT, OPT_FORMAT, OPT_EXPOSURE, OPT_SCALE };

static const cli_option export_options_table[] = {
    {"output", 'o', "FILE", "the file to write (required); .glb, .ply or .csv chooses the format"},
    {"format", 0, "F", "glb, ply or csv (default: from the output's extension)"},
    {"exposure", 0, "EV", "display colours scaled by 2^EV (default: 1 / 99th percentile of max(r,g,b) > 0)"},
    {"scale", 0, "W", "display colours scaled by 1/W: radiance W (W sr^-1 m^-2) shows as white"},
};

static const cli_usage export_usage = {
    "export",
    "RADIANCE.h5 -o OUT.glb|OUT.ply|OUT.csv [--format glb|ply|csv] [--exposure EV | --scale W]",
    "Exports the relit surfaces of a radiance-map file (radiance.h5 of 'ilf relight').\n"
    "glb: glTF 2.0 binary, one node per map, each cell a flat-coloured polygon of its\n"
    "own vertices; COLOR_0 the display colour (linear, as glTF defines it), an unlit\n"
    "material (KHR_materials_unlit), and attributes _IRRADIANCE and _RADIOSITY with\n"
    "the linear values in W m^-2. ply: the same triangles, sRGB-encoded 8-bit vertex\n"
    "colours and float irradiance_r/g/b, radiosity_r/g/b. csv: one row per cell:\n"
    "map, label, i, j, x, y, z (centroid), nx, ny, nz, area, irradiance and radiosity.\n"
    "Display colours show radiance (radiosity / pi) times one exposure factor.",
    "ilf export out/radiance.h5 -o room.glb\n"
    "ilf export out/radiance.h5 -o room.ply --exposure -1\n"
    "ilf export out/radiance.h5 -o cells.csv",
};

/* ------------------------------------------------------------ growing buffers */

typedef struct bytes {
    unsigned char *data;
    size_t size, cap;
    int failed; /* memory ran out: every later append is a no-op */
} bytes;

static void bytes_append(bytes *b, const void *data, size_t size)
{
    if (b->failed)
        return;
    if (b->size + size > b->cap) {
        size_t cap = b->cap > 0 ? b->cap : 4096;
        while (cap < b->size + size)
            cap *= 2;
        unsigned char *grown = realloc(b->data, cap);
        if (grown == NULL) {
            b->failed = 1;
            return;
        }
        b->data = grown;
        b->cap = cap;
    }
    memcpy(b->data + b->size, data, size);
    b->size += size;
}

static void bytes_printf(bytes *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static void bytes_printf(bytes *b, const char *fmt, ...)
{
    char line[8192]; /* a scene path is at most LFIO_RADMAP_TEXT_MAX bytes */
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    if (n > 0)
        bytes_append(b, line, (size_t)n < sizeof line ? (size_t)n : sizeof line - 1);
}

static void bytes_floats(bytes *b, const double *v, int count)
{
    for (int k = 0; k < count; k++) {
        float f = (float)v[k];
        bytes_append(b, &f, sizeof f);
    }
}

/* ------------------------------------------------------------ triangles of a map */

/* The triangles of one map, each cell's own vertices: positions, display colours, irradiance, radiosity
 * ([nverts][3] floats each, as bytes) and indices ([ntris][3] uint32). */
typedef struct patch_mesh {
    bytes pos, colour, irr, rad, idx;
    uint32_t nverts, ntris;
    double min[3], max[3];
} patch_mesh;

static void mesh_reset(patch_mesh *m)
{
    bytes *all[5] = {&m->pos, &m->colour, &m->irr, &m->rad, &m->idx};
    for (int k = 0; k < 5; k++)
        all[k]->size = 0;
    m->nverts = m->ntris = 0;
    for (int i = 0; i < 3; i++) {
        m->min[i] = DBL_MAX;
        m->max[i] = -DBL_MAX;
    }
}

static void mesh_free(patch_mesh *m)
{
    bytes *all[5] = {&m->pos, &m->colour, &m->irr, &m->rad, &m->idx};
    for (int k = 0; k < 5; k++)
        free(all[k]->data);
}

static int mesh_failed(const patch_mesh *m)
{
    return m->pos.failed || m->colour.failed || m->irr.failed || m->rad.failed || m->idx.failed;
}

/* The display value of radiosity b: radiance b / pi times scale, clamped to [0, 1]. */
static void display_colour(const float *b, double scale, double out[3])
{
    for (int c = 0; c < 3; c++) {
        double v = b[c] / ILF_PI * scale;
        out[c] = v < 0.0 ? 0.0 : v > 1.0 ? 1.0 : v;
    }
}

/* Appends the cells of patch p to m. @return 1, or 0 when memory runs out. */
static int mesh_add_patch(patch_mesh *m, const lfio_radmap_patch *p, double scale)
{
    radmap_clipper clip;
    if (!radmap_clipper_init(&clip, p))
        return 0;
    double *world = malloc(sizeof(double) * 3 * clip.cap);
    for (uint32_t k = 0; world != NULL && k < p->ncells; k++) {
        uint32_t n = radmap_clipper_cell(&clip, k, world);
        double colour[3], irr[3], rad[3];
        display_colour(p->radiosity + 3 * (size_t)k, scale, colour);
        for (int c = 0; c < 3; c++) {
            irr[c] = p->irradiance[3 * (size_t)k + c];
            rad[c] = p->radiosity[3 * (size_t)k + c];
        }
        for (uint32_t v = 0; v < n; v++) {
            bytes_floats(&m->pos, world + 3 * v, 3);
            bytes_floats(&m->colour, colour, 3);
            bytes_floats(&m->irr, irr, 3);
            bytes_floats(&m->rad, rad, 3);
            for (int i = 0; i < 3; i++) {
                double x = (float)world[3 * v + i]; /* the bounds of what is stored */
                m->min[i] = x < m->min[i] ? x : m->min[i];
                m->max[i] = x > m->max[i] ? x : m->max[i];
            }
        }
        for (uint32_t t = 1; t + 1 < n; t++) {
            uint32_t tri[3] = {m->nverts, m->nverts + t, m->nverts + t + 1};
            bytes_append(&m->idx, tri, sizeof tri);
            m->ntris++;
        }
        m->nverts += n;
    }
    int ok = world != NULL && !mesh_failed(m);
    free(world);
    radmap_clipper_free(&clip);
    return ok;
}

/* ------------------------------------------------------------ glTF binary */

enum { GL_FLOAT = 5126, GL_UNSIGNED_INT = 5125, GL_ARRAY_BUFFER = 34962, GL_ELEMENT_ARRAY_BUFFER = 34963 };

/* Adds a bufferView over data appended to bin, and an accessor over it. @return the accessor's index, -1 on
 * failure. */
static int add_accessor(cJSON *root, bytes *bin, const bytes *data, uint32_t count, int component, const char *type,
                        int target, const double *min, const double *max)
{
    cJSON *views = cJSON_GetObjectItem(root, "bufferViews"), *accessors = cJSON_GetObjectItem(root, "accessors");
    cJSON *view = cJSON_CreateObject(), *acc = cJSON_CreateObject();
    int ok = view != NULL && acc != NULL && cJSON_AddItemToArray(views, view);
    if (!ok) {
        cJSON_Delete(view);
        cJSON_Delete(acc);
        return -1;
    }
    ok = cJSON_AddItemToArray(accessors, acc);
    if (!ok) {
        cJSON_Delete(acc);
        return -1;
    }
    ok = cJSON_AddNumberToObject(view, "buffer", 0) && cJSON_AddNumberToObject(view, "byteOffset", (double)bin->size) &&
         cJSON_AddNumberToObject(view, "byteLength", (double)data->size) &&
         cJSON_AddNumberToObject(view, "target", target);
    bytes_append(bin, data->data, data->size);
    ok = ok && cJSON_AddNumberToObject(acc, "bufferView", cJSON_GetArraySize(views) - 1) &&
         cJSON_AddNumberToObject(acc, "componentType", component) && cJSON_AddNumberToObject(acc, "count", count) &&
         cJSON_AddStringToObject(acc, "type", type);
    if (ok && min != NULL)
        ok = json_add_doubles(acc, "min", min, 3) && json_add_doubles(acc, "max", max, 3);
    return ok && !bin->failed ? cJSON_GetArraySize(accessors) - 1 : -1;
}

/* Adds map m (named label) as a mesh and a node. @return 1, or 0 when memory runs out. */
static int gltf_add_mesh(cJSON *root, bytes *bin, const patch_mesh *m, const char *label)
{
    int pos = add_accessor(root, bin, &m->pos, m->nverts, GL_FLOAT, "VEC3", GL_ARRAY_BUFFER, m->min, m->max);
    int col = add_accessor(root, bin, &m->colour, m->nverts, GL_FLOAT, "VEC3", GL_ARRAY_BUFFER, NULL, NULL);
    int irr = add_accessor(root, bin, &m->irr, m->nverts, GL_FLOAT, "VEC3", GL_ARRAY_BUFFER, NULL, NULL);
    int rad = add_accessor(root, bin, &m->rad, m->nverts, GL_FLOAT, "VEC3", GL_ARRAY_BUFFER, NULL, NULL);
    int idx = add_accessor(root, bin, &m->idx, 3 * m->ntris, GL_UNSIGNED_INT, "SCALAR", GL_ELEMENT_ARRAY_BUFFER,
                           NULL, NULL);
    if (pos < 0 || col < 0 || irr < 0 || rad < 0 || idx < 0)
        return 0;
    cJSON *mesh = cJSON_CreateObject(), *node = cJSON_CreateObject();
    int ok = mesh != NULL && cJSON_AddItemToArray(cJSON_GetObjectItem(root, "meshes"), mesh);
    ok = ok && node != NULL && cJSON_AddItemToArray(cJSON_GetObjectItem(root, "nodes"), node);
    if (!ok) {
        cJSON_Delete(node);
        return 0;
    }
    int index = cJSON_GetArraySize(cJSON_GetObjectItem(root, "meshes")) - 1;
    cJSON *prims = cJSON_AddArrayToObject(mesh, "primitives"), *prim = cJSON_CreateObject();
    ok = cJSON_AddStringToObject(mesh, "name", label) && prims != NULL && prim != NULL &&
         cJSON_AddItemToArray(prims, prim);
    cJSON *attrs = ok ? cJSON_AddObjectToObject(prim, "attributes") : NULL;
    ok = ok && attrs != NULL && cJSON_AddNumberToObject(attrs, "POSITION", pos) &&
         cJSON_AddNumberToObject(attrs, "COLOR_0", col) && cJSON_AddNumberToObject(attrs, "_IRRADIANCE", irr) &&
         cJSON_AddNumberToObject(attrs, "_RADIOSITY", rad) && cJSON_AddNumberToObject(prim, "indices", idx) &&
         cJSON_AddNumberToObject(prim, "material", 0) && cJSON_AddNumberToObject(prim, "mode", 4);
    ok = ok && cJSON_AddStringToObject(node, "name", label) && cJSON_AddNumberToObject(node, "mesh", index);
    cJSON *scene_nodes = cJSON_GetObjectItem(cJSON_GetArrayItem(cJSON_GetObjectItem(root, "scenes"), 0), "nodes");
    return ok && cJSON_AddItemToArray(scene_nodes, cJSON_CreateNumber(cJSON_GetArraySize(
                                                       cJSON_GetObjectItem(root, "nodes")) - 1));
}

/* The document's fixed part: asset, one scene, one unlit double-sided material, empty arrays. */
static cJSON *gltf_root(const lfio_radmap *map)
{
    cJSON *root = cJSON_CreateObject();
    if (root == NULL)
        return NULL;
    cJSON *asset = cJSON_AddObjectToObject(root, "asset");
    char generator[256];
    snprintf(generator, sizeof generator, "ilf export (ilfkit %s)", ILFKIT_VERSION);
    int ok = asset != NULL && cJSON_AddStringToObject(asset, "version", "2.0") &&
             cJSON_AddStringToObject(asset, "generator", generator);
    cJSON *extras = ok ? cJSON_AddObjectToObject(asset, "extras") : NULL;
    ok = ok && extras != NULL && cJSON_AddStringToObject(extras, "scene", lfio_radmap_scene(map)) &&
         cJSON_AddStringToObject(extras, "creator", lfio_radmap_creator(map)) &&
         cJSON_AddStringToObject(extras, "_IRRADIANCE", "irradiance, W m^-2, linear Rec.709, per cell") &&
         cJSON_AddStringToObject(extras, "_RADIOSITY", "radiosity, W m^-2, linear Rec.709, per cell");
    cJSON *used = ok ? cJSON_AddArrayToObject(root, "extensionsUsed") : NULL;
    ok = ok && used != NULL && cJSON_AddItemToArray(used, cJSON_CreateString("KHR_materials_unlit"));
    ok = ok && cJSON_AddNumberToObject(root, "scene", 0);
    cJSON *scenes = ok ? cJSON_AddArrayToObject(root, "scenes") : NULL, *scene = cJSON_CreateObject();
    ok = ok && scenes != NULL && scene != NULL && cJSON_AddItemToArray(scenes, scene);
    ok = ok && cJSON_AddArrayToObject(scene, "nodes") != NULL;
    const char *arrays[] = {"nodes", "meshes", "accessors", "bufferViews", "buffers", "materials"};
    for (size_t k = 0; ok && k < sizeof arrays / sizeof arrays[0]; k++)
        ok = cJSON_AddArrayToObject(root, arrays[k]) != NULL;
    cJSON *mat = cJSON_CreateObject();
    ok = ok && mat != NULL && cJSON_AddItemToArray(cJSON_GetObjectItem(root, "materials"), mat);
    cJSON *pbr = ok ? cJSON_AddObjectToObject(mat, "pbrMetallicRoughness") : NULL;
    cJSON *ext = ok ? cJSON_AddObjectToObject(mat, "extensions") : NULL;
    ok = ok && cJSON_AddStringToObject(mat, "name", "relit (unlit: the vertex colours as they are)") && pbr != NULL &&
         cJSON_AddNumberToObject(pbr, "metallicFactor", 0) && ext != NULL &&
         cJSON_AddObjectToObject(ext, "KHR_materials_unlit") != NULL && cJSON_AddTrueToObject(mat, "doubleSided");
    if (!ok) {
        cJSON_Delete(root);
        return NULL;
    }
    return root;
}

/* Appends a GLB chunk: length, type, data padded to 4 bytes with pad. */
static void glb_chunk(bytes *out, const char *type, const void *data, size_t size, char pad)
{
    uint32_t padded = (uint32_t)((size + 3) & ~(size_t)3);
    bytes_append(out, &padded, 4);
    bytes_append(out, type, 4);
    bytes_append(out, data, size);
    for (size_t k = size; k < padded; k++)
        bytes_append(out, &pad, 1);
}

/* Builds the whole .glb in out. @return 1; 0 when memory runs out; -1 when it would pass GLB's 32-bit length. */
static int build_glb(const lfio_radmap *map, double scale, bytes *out)
{
    cJSON *root = gltf_root(map);
    bytes bin = {0};
    patch_mesh m = {0};
    int ok = root != NULL;
    for (size_t k = 0; ok && k < lfio_radmap_count(map); k++) {
        lfio_radmap_patch p;
        lfio_radmap_get(map, k, &p);
        mesh_reset(&m);
        ok = mesh_add_patch(&m, &p, scale);
        if (ok && m.ntris > 0) /* a map of no cells has nothing to show, and glTF no empty accessor */
            ok = gltf_add_mesh(root, &bin, &m, p.label);
    }
    cJSON *buffer = ok ? cJSON_CreateObject() : NULL;
    ok = ok && buffer != NULL && cJSON_AddItemToArray(cJSON_GetObjectItem(root, "buffers"), buffer) &&
         cJSON_AddNumberToObject(buffer, "byteLength", (double)bin.size);
    char *json = ok ? cJSON_PrintUnformatted(root) : NULL;
    if (json != NULL) {
        size_t jlen = strlen(json), total = 12 + 8 + ((jlen + 3) & ~(size_t)3) + 8 + ((bin.size + 3) & ~(size_t)3);
        uint32_t header[3] = {0x46546C67u, 2u, (uint32_t)total}; /* "glTF", little-endian */
        bytes_append(out, header, sizeof header);
        glb_chunk(out, "JSON", json, jlen, ' ');
        glb_chunk(out, "BIN\0", bin.data, bin.size, '\0');
        ok = total > UINT32_MAX ? -1 : !out->failed;
    } else {
        ok = 0;
    }
    cJSON_free(json);
    cJSON_Delete(root);
    free(bin.data);
    mesh_free(&m);
    return ok;
}

/* ------------------------------------------------------------ PLY and CSV */

static uint8_t srgb8(double linear)
{
    return (uint8_t)lround(255.0 * img_srgb_encode(linear));
}

/* Builds the whole .ply (ASCII) in out. @return 1, or 0 when memory runs out. */
static int build_ply(const lfio_radmap *map, double scale, bytes *out)
{
    patch_mesh m = {0};
    mesh_reset(&m);
    int ok = 1;
    for (size_t k = 0; ok && k < lfio_radmap_count(map); k++) {
        lfio_radmap_patch p;
        lfio_radmap_get(map, k, &p);
        ok = mesh_add_patch(&m, &p, scale);
    }
    if (ok) {
        bytes_printf(out, "ply\nformat ascii 1.0\ncomment ilf export (ilfkit %s) of a radiance map of %s\n",
                     ILFKIT_VERSION, lfio_radmap_scene(map));
        bytes_printf(out, "comment colours: sRGB display colours; irradiance and radiosity: W m^-2, linear\n");
        bytes_printf(out, "element vertex %u\nproperty float x\nproperty float y\nproperty float z\n", m.nverts);
        bytes_printf(out, "property uchar red\nproperty uchar green\nproperty uchar blue\n");
        bytes_printf(out, "property float irradiance_r\nproperty float irradiance_g\nproperty float irradiance_b\n");
        bytes_printf(out, "property float radiosity_r\nproperty float radiosity_g\nproperty float radiosity_b\n");
        bytes_printf(out, "element face %u\nproperty list uchar uint vertex_indices\nend_header\n", m.ntris);
        const float *pos = (const float *)m.pos.data, *col = (const float *)m.colour.data;
        const float *irr = (const float *)m.irr.data, *rad = (const float *)m.rad.data;
        for (size_t v = 0; v < m.nverts; v++) {
            const size_t i = 3 * v;
            bytes_printf(out, "%.9g %.9g %.9g %u %u %u %.9g %.9g %.9g %.9g %.9g %.9g\n", pos[i], pos[i + 1],
                         pos[i + 2], srgb8(col[i]), srgb8(col[i + 1]), srgb8(col[i + 2]), irr[i], irr[i + 1],
                         irr[i + 2], rad[i], rad[i + 1], rad[i + 2]);
        }
        const uint32_t *idx = (const uint32_t *)m.idx.data;
        for (size_t t = 0; t < m.ntris; t++)
            bytes_printf(out, "3 %u %u %u\n", idx[3 * t], idx[3 * t + 1], idx[3 * t + 2]);
    }
    ok = ok && !out->failed;
    mesh_free(&m);
    return ok;
}

/* Appends text as one CSV field: quoted, with quotes doubled, when it holds a comma, quote or line break. */
static void csv_field(bytes *out, const char *text)
{
    if (strpbrk(text, ",\"\r\n") == NULL) {
        bytes_append(out, text, strlen(text));
        return;
    }
    bytes_append(out, "\"", 1);
    for (const char *c = text; *c != '\0'; c++) {
        if (*c == '"')
            bytes_append(out, "\"\"", 2);
        else
            bytes_append(out, c, 1);
    }
    bytes_append(out, "\"", 1);
}

static int build_csv(const lfio_radmap *map, bytes *out)
{
    bytes_printf(out, "map,label,i,j,x,y,z,nx,ny,nz,area_m2,irradiance_r,irradiance_g,irradiance_b,"
                      "radiosity_r,radiosity_g,radiosity_b\n");
    for (size_t k = 0; k < lfio_radmap_count(map); k++) {
        lfio_radmap_patch p;
        lfio_radmap_get(map, k, &p);
        for (uint32_t c = 0; c < p.ncells; c++) {
            const double *x = p.cell_centre + 3 * (size_t)c;
            const float *e = p.irradiance + 3 * (size_t)c, *b = p.radiosity + 3 * (size_t)c;
            bytes_printf(out, "%zu,", k);
            csv_field(out, p.label);
            bytes_printf(out, ",%u,%u,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n",
                         (unsigned)p.cell_ij[2 * c], (unsigned)p.cell_ij[2 * c + 1], x[0], x[1], x[2], p.normal[0],
                         p.normal[1], p.normal[2], p.cell_area[c], e[0], e[1], e[2], b[0], b[1], b[2]);
        }
    }
    return !out->failed;
}

/* ------------------------------------------------------------ main */

/* The display scale: fixed by the user, or 1 / the 99th percentile of max(r, g, b) of every cell's radiance.
 * @return 1, or 0 when memory runs out. */
static int display_scale(const lfio_radmap *map, const tone_fixed *tone, double *scale)
{
    if (tone_fixed_scale(tone, scale))
        return 1;
    size_t cells = 0;
    for (size_t k = 0; k < lfio_radmap_count(map); k++) {
        lfio_radmap_patch p;
        lfio_radmap_get(map, k, &p);
        cells += p.ncells;
    }
    float *radiance = malloc(sizeof(float) * 3 * (cells > 0 ? cells : 1));
    if (radiance == NULL)
        return 0;
    size_t at = 0;
    for (size_t k = 0; k < lfio_radmap_count(map); k++) {
        lfio_radmap_patch p;
        lfio_radmap_get(map, k, &p);
        for (size_t i = 0; i < 3 * (size_t)p.ncells; i++)
            radiance[at++] = (float)(p.radiosity[i] / ILF_PI);
    }
    int ok = tone_percentile_scale(radiance, cells, 3, TONE_PEAK, 0.99, 1.0, scale);
    free(radiance);
    return ok;
}

static export_format format_named(const char *name)
{
    return strcmp(name, "glb") == 0 ? FMT_GLB : strcmp(name, "ply") == 0 ? FMT_PLY
                                              : strcmp(name, "csv") == 0 ? FMT_CSV : FMT_NONE;
}

static export_format format_of_extension(const char *path)
{
    const char *dot = strrchr(path, '.');
    if (dot == NULL || strchr(dot, '/') != NULL)
        return FMT_NONE;
    char ext[8] = {0};
    for (size_t k = 0; k + 1 < sizeof ext && dot[1 + k] != '\0'; k++)
        ext[k] = (char)(dot[1 + k] >= 'A' && dot[1 + k] <= 'Z' ? dot[1 + k] - 'A' + 'a' : dot[1 + k]);
    return strlen(dot + 1) < sizeof ext ? format_named(ext) : FMT_NONE;
}

static int apply_option(const cli_parser *p, int opt, const char *value, void *ctx)
{
    export_options *o = ctx;
    if (opt == OPT_OUTPUT)
        return cli_single_path("export", &o->output, value);
    if (opt == OPT_FORMAT) {
        o->format = format_named(value);
        if (o->format == FMT_NONE)
            cli_bad_value(p, value, "expected glb, ply or csv");
        return o->format != FMT_NONE;
    }
    return cli_value_tone(p, value, opt == OPT_EXPOSURE, &o->tone);
}

static int parse_arguments(export_options *o, int argc, char **argv)
{
    int code = cli_parse(&export_usage, export_options_table,
                         sizeof export_options_table / sizeof export_options_table[0], argc, argv, &o->path,
                         apply_option, o);
    if (code != -1)
        return code;
    if (o->path == NULL || o->output == NULL) {
        cli_error("export", "%s (see 'ilf export --help')", o->path == NULL ? "no file given" : "no -o FILE given");
        return ILF_EXIT_USAGE;
    }
    if (o->format == FMT_NONE)
        o->format = format_of_extension(o->output);
    if (o->format == FMT_NONE) {
        cli_error("export", "%s: cannot tell the format from the extension: use .glb, .ply or .csv, or --format",
                  o->output);
        return ILF_EXIT_USAGE;
    }
    return -1;
}

static int export_map(const lfio_radmap *map, const export_options *o)
{
    double scale = 1.0;
    bytes out = {0};
    int ok = o->format == FMT_CSV || display_scale(map, &o->tone, &scale);
    if (ok)
        ok = o->format == FMT_GLB ? build_glb(map, scale, &out)
             : o->format == FMT_PLY ? build_ply(map, scale, &out)
                                    : build_csv(map, &out);
    if (ok != 1) {
        free(out.data);
        if (ok < 0)
            cli_error("export", "%s: more than the 4 GiB a glTF binary can hold: export to .ply or .csv", o->output);
        else
            cli_error("export", "%s: out of memory while building the output", o->output);
        return ILF_EXIT_FAILED;
    }
    char err[1024];
    int code = ILF_EXIT_OK;
    if (!file_write_atomic(o->output, out.data, out.size, err, sizeof err)) {
        cli_error("export", "%s", err);
        code = ILF_EXIT_FAILED;
    }
    free(out.data);
    if (code == ILF_EXIT_OK) {
        char size[32];
        printf("wrote %s: %zu maps, %s", o->output, lfio_radmap_count(map),
               cli_format_bytes((long long)out.size, size, sizeof size));
        if (o->format != FMT_CSV)
            printf(", display scale %.6g", scale);
        printf("\n");
    }
    return code;
}

int ilf_cmd_export(int argc, char **argv)
{
    export_options o = {0};
    int code = parse_arguments(&o, argc, argv);
    if (code >= 0)
        return code;
    lfio_radmap *map = NULL;
    code = ilf_radmap_open("export", o.path, &map);
    if (code != ILF_EXIT_OK)
        return code;
    cli_output_watch(o.output);
    code = cli_output_check("export", o.output);
    if (code == ILF_EXIT_OK)
        code = export_map(map, &o);
    lfio_radmap_destroy(map);
    return code;
}
