/*
 * radmap_cli.c - radiance-map files for the `ilf` commands: recognising one
 * where a light field was expected, reading one with the command's
 * messages, and `ilf info`'s description of one (text and JSON, the schema
 * in docs/cli.md).
 *
 * Invariants: only lfio's public radiance-map reader touches the file; the
 * same map_summary feeds the text and the JSON output; statistics are
 * weighted by cell area, as a cell's value is the mean over its area; a
 * map's area is its polygon's, which the headers give, so that `ilf info`
 * need not read a cell (lfio_radmap_read_headers()).
 */
#include <cjson/cJSON.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "jsonout.h"
#include "radmap_cli.h"

/* The root attribute "format" of a radiance-map file (docs/format.md, section 6), which the light field
 * reader's refusal quotes when it found one. */
#define RADMAP_FORMAT_NAME "ilfkit-radiance-maps"

lfio_status ilf_radmap_try(const char *path, const char *lf_msg, int whole, lfio_radmap **out, char *msg,
                           size_t msg_size)
{
    lfio_status st = whole ? lfio_radmap_read(path, out) : lfio_radmap_read_headers(path, out);
    if (st == LFIO_OK)
        return LFIO_OK;
    /* A file that fails the radiance-map reader otherwise than on its format is a damaged radiance map. One
     * whose format attribute names radiance maps gets both readers' word: it may be a damaged radiance map or
     * a light field whose attribute is wrong. Anything else is reported as a light field, the kind most
     * commands read, with that reader's message. */
    if (st != LFIO_ERR_FORMAT)
        snprintf(msg, msg_size, "%s", lfio_errmsg());
    else if (strstr(lf_msg, RADMAP_FORMAT_NAME) != NULL)
        snprintf(msg, msg_size, "%s (read as the radiance map its format attribute names; as a light field: %s)",
                 lfio_errmsg(), lf_msg);
    else
        snprintf(msg, msg_size, "%s", lf_msg);
    return st;
}

int ilf_radmap_open(const char *sub, const char *path, lfio_radmap **out)
{
    lfio_status st = lfio_radmap_read(path, out);
    if (st == LFIO_OK)
        return ILF_EXIT_OK;
    return cli_lfio_failure(sub, st, CLI_INPUT, path);
}

/* ------------------------------------------------------------ statistics */

/* Per channel min, max and area-weighted mean of one quantity over cells. */
typedef struct rgb_stats {
    double min[3], max[3], sum[3];
} rgb_stats;

static void stats_init(rgb_stats *s)
{
    for (int c = 0; c < 3; c++) {
        s->min[c] = DBL_MAX;
        s->max[c] = 0.0;
        s->sum[c] = 0.0;
    }
}

static void stats_add(rgb_stats *s, const float *rgb, double area)
{
    for (int c = 0; c < 3; c++) {
        s->min[c] = rgb[c] < s->min[c] ? rgb[c] : s->min[c];
        s->max[c] = rgb[c] > s->max[c] ? rgb[c] : s->max[c];
        s->sum[c] += area * rgb[c];
    }
}

/* Turns sums into means over area; a set of no cells reads 0 throughout. */
static void stats_finish(rgb_stats *s, double area)
{
    for (int c = 0; c < 3; c++) {
        if (s->min[c] == DBL_MAX)
            s->min[c] = 0.0;
        s->sum[c] = area > 0.0 ? s->sum[c] / area : 0.0;
    }
}

/* What info reports about one map. */
typedef struct map_summary {
    lfio_radmap_patch p;
    double area;        /* the polygon's, from its vertices: the headers give it */
    double cell_area;   /* the sum of its cells' areas, the statistics' weight (with stats) */
    rgb_stats irradiance, radiosity;
} map_summary;

/* @return the area of p's planar polygon, m^2: half the length of the sum of its fan's cross products. */
static double polygon_area(const lfio_radmap_patch *p)
{
    const double *v = p->vertices;
    double sum[3] = {0, 0, 0};
    for (uint32_t k = 1; k + 1 < p->nverts; k++) {
        double a[3], b[3];
        for (int i = 0; i < 3; i++) {
            a[i] = v[3 * k + i] - v[i];
            b[i] = v[3 * (k + 1) + i] - v[i];
        }
        sum[0] += a[1] * b[2] - a[2] * b[1];
        sum[1] += a[2] * b[0] - a[0] * b[2];
        sum[2] += a[0] * b[1] - a[1] * b[0];
    }
    return 0.5 * sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
}

/* Summarises p; with stats (its cells read) the area-weighted statistics too. */
static void summarise(const lfio_radmap_patch *p, int stats, map_summary *m)
{
    m->p = *p;
    m->area = polygon_area(p);
    m->cell_area = 0.0;
    stats_init(&m->irradiance);
    stats_init(&m->radiosity);
    for (uint32_t c = 0; stats && c < p->ncells; c++) {
        m->cell_area += p->cell_area[c];
        stats_add(&m->irradiance, p->irradiance + 3 * (size_t)c, p->cell_area[c]);
        stats_add(&m->radiosity, p->radiosity + 3 * (size_t)c, p->cell_area[c]);
    }
    stats_finish(&m->irradiance, m->cell_area);
    stats_finish(&m->radiosity, m->cell_area);
}

/* Adds map m into the whole file's totals t (its sums still sums). */
static void total_add(map_summary *t, const map_summary *m)
{
    t->p.ncells += m->p.ncells;
    t->area += m->area;
    t->cell_area += m->cell_area;
    rgb_stats *ts[2] = {&t->irradiance, &t->radiosity};
    const rgb_stats *ms[2] = {&m->irradiance, &m->radiosity};
    for (int q = 0; q < 2; q++)
        for (int c = 0; c < 3; c++) {
            if (m->p.ncells > 0) {
                ts[q]->min[c] = ms[q]->min[c] < ts[q]->min[c] ? ms[q]->min[c] : ts[q]->min[c];
                ts[q]->max[c] = ms[q]->max[c] > ts[q]->max[c] ? ms[q]->max[c] : ts[q]->max[c];
            }
            ts[q]->sum[c] += ms[q]->sum[c] * m->cell_area;
        }
}

/* ------------------------------------------------------------ text */

static void print_rgb(const char *label, const double v[3])
{
    printf("  %-18s %.9g %.9g %.9g\n", label, v[0], v[1], v[2]);
}

static void print_stats_text(const char *what, const rgb_stats *s)
{
    char label[64];
    snprintf(label, sizeof label, "%s min:", what);
    print_rgb(label, s->min);
    snprintf(label, sizeof label, "%s max:", what);
    print_rgb(label, s->max);
    snprintf(label, sizeof label, "%s mean:", what);
    print_rgb(label, s->sum);
}

static void print_map_text(size_t k, const map_summary *m, int stats)
{
    const lfio_radmap_patch *p = &m->p;
    printf("\nmap %zu: %s (polygon %u)\n", k, p->label, (unsigned)p->polygon);
    printf("  %-18s %u\n", "vertices:", (unsigned)p->nverts);
    print_rgb("normal:", p->normal);
    printf("  %-18s %ux%u cells of %.9g m, %u stored, %.9g m^2\n", "grid:", (unsigned)p->nu, (unsigned)p->nv,
           p->cell_size, (unsigned)p->ncells, m->area);
    printf("  %-18s %.9g %.9g %.9g\n", "albedo:", p->albedo[0], p->albedo[1], p->albedo[2]);
    printf("  %-18s %.9g %.9g %.9g\n", "emission:", p->emission[0], p->emission[1], p->emission[2]);
    if (stats) {
        print_stats_text("irradiance", &m->irradiance);
        print_stats_text("radiosity", &m->radiosity);
    }
}

/* ------------------------------------------------------------ JSON */

static int add_floats(cJSON *obj, const char *key, const float v[3])
{
    double d[3] = {v[0], v[1], v[2]};
    return json_add_doubles(obj, key, d, 3);
}

static int add_stats_json(cJSON *obj, const char *what, const rgb_stats *s)
{
    char key[64];
    snprintf(key, sizeof key, "%s_min", what);
    int ok = json_add_doubles(obj, key, s->min, 3);
    snprintf(key, sizeof key, "%s_max", what);
    ok = ok && json_add_doubles(obj, key, s->max, 3);
    snprintf(key, sizeof key, "%s_mean", what);
    return ok && json_add_doubles(obj, key, s->sum, 3);
}

static cJSON *map_json(const map_summary *m, int stats)
{
    const lfio_radmap_patch *p = &m->p;
    cJSON *o = cJSON_CreateObject();
    if (o == NULL)
        return NULL;
    int ok = cJSON_AddStringToObject(o, "label", p->label) && cJSON_AddNumberToObject(o, "polygon", p->polygon) &&
             cJSON_AddNumberToObject(o, "vertices", p->nverts) && json_add_doubles(o, "normal", p->normal, 3) &&
             cJSON_AddNumberToObject(o, "cell_size", p->cell_size) && cJSON_AddNumberToObject(o, "nu", p->nu) &&
             cJSON_AddNumberToObject(o, "nv", p->nv) && cJSON_AddNumberToObject(o, "cells", p->ncells) &&
             cJSON_AddNumberToObject(o, "area", m->area) && add_floats(o, "albedo", p->albedo) &&
             add_floats(o, "emission", p->emission);
    if (ok && stats)
        ok = add_stats_json(o, "irradiance", &m->irradiance) && add_stats_json(o, "radiosity", &m->radiosity);
    if (!ok) {
        cJSON_Delete(o);
        return NULL;
    }
    return o;
}

/* ------------------------------------------------------------ info */

static cJSON *file_json(const char *path, const lfio_radmap *map, const map_summary *total, int stats)
{
    cJSON *root = cJSON_CreateObject();
    if (root == NULL)
        return NULL;
    int ok = cJSON_AddStringToObject(root, "file", path) && cJSON_AddStringToObject(root, "kind", "radiance map") &&
             cJSON_AddNumberToObject(root, "format_version", lfio_radmap_format_version(map)) &&
             cJSON_AddStringToObject(root, "creator", lfio_radmap_creator(map)) &&
             cJSON_AddStringToObject(root, "scene", lfio_radmap_scene(map)) &&
             cJSON_AddNumberToObject(root, "file_bytes", (double)cli_file_size(path)) &&
             cJSON_AddNumberToObject(root, "cells", total->p.ncells) &&
             cJSON_AddNumberToObject(root, "area", total->area);
    if (ok && stats)
        ok = add_stats_json(root, "irradiance", &total->irradiance) &&
             add_stats_json(root, "radiosity", &total->radiosity);
    if (!ok || cJSON_AddArrayToObject(root, "maps") == NULL) {
        cJSON_Delete(root);
        return NULL;
    }
    return root;
}

static void print_file_text(const char *path, const lfio_radmap *map, const map_summary *total, int stats)
{
    char size[32];
    long long bytes = cli_file_size(path);
    printf("file:             %s\n", path);
    printf("kind:             radiance map\n");
    printf("format version:   %d\n", lfio_radmap_format_version(map));
    printf("creator:          %s\n", lfio_radmap_creator(map));
    printf("scene:            %s\n", lfio_radmap_scene(map));
    printf("file size:        %s (%lld bytes)\n", cli_format_bytes(bytes, size, sizeof size), bytes);
    printf("maps:             %zu\n", lfio_radmap_count(map));
    printf("cells:            %u, %.9g m^2\n", (unsigned)total->p.ncells, total->area);
    if (stats) {
        print_stats_text("irradiance", &total->irradiance);
        print_stats_text("radiosity", &total->radiosity);
    }
}

/* Sums every map into *total. */
static void gather_total(const lfio_radmap *map, int stats, map_summary *total)
{
    memset(total, 0, sizeof *total);
    stats_init(&total->irradiance);
    stats_init(&total->radiosity);
    for (size_t k = 0; k < lfio_radmap_count(map); k++) {
        lfio_radmap_patch p;
        map_summary m;
        lfio_radmap_get(map, k, &p);
        summarise(&p, stats, &m);
        total_add(total, &m);
    }
    stats_finish(&total->irradiance, total->cell_area);
    stats_finish(&total->radiosity, total->cell_area);
}

/* Prints text with two tabs after each newline: a map's object as cJSON_Print indents an element of the
 * root's "maps" array. */
static void print_indented(const char *text)
{
    for (const char *c = text; *c != '\0'; c++) {
        putchar(*c);
        if (*c == '\n')
            fputs("\t\t", stdout);
    }
}

/* Prints the JSON report a map at a time, so that it holds one map's objects whatever the file holds: the
 * root's keys as cJSON_Print gives them with "maps" empty (its last key, so the last '[' of that text), then
 * each map's object indented as an element of that array: the text cJSON_Print gives of the whole tree. Out
 * of memory part-way, the text printed so far is cut off and the exit code says so. @return an exit code. */
static int print_json(const char *path, const lfio_radmap *map, const map_summary *total, int stats)
{
    cJSON *root = file_json(path, map, total, stats);
    char *head = root != NULL ? cJSON_Print(root) : NULL;
    cJSON_Delete(root);
    const char *open = head != NULL ? strrchr(head, '[') : NULL;
    int ok = open != NULL;
    if (ok)
        fwrite(head, 1, (size_t)(open - head) + 1, stdout);
    cJSON_free(head);
    for (size_t k = 0; ok && k < lfio_radmap_count(map); k++) {
        lfio_radmap_patch p;
        map_summary m;
        lfio_radmap_get(map, k, &p);
        summarise(&p, stats, &m);
        cJSON *o = map_json(&m, stats);
        char *text = o != NULL ? cJSON_Print(o) : NULL;
        cJSON_Delete(o);
        ok = text != NULL;
        if (ok) {
            fputs(k > 0 ? ", " : "", stdout);
            print_indented(text);
        }
        cJSON_free(text);
    }
    if (ok)
        fputs("]\n}\n", stdout);
    else
        cli_error("info", "out of memory while building JSON");
    return ok ? ILF_EXIT_OK : ILF_EXIT_FAILED;
}

int ilf_info_radmap(const char *path, const lfio_radmap *map, int json, int stats)
{
    stats = stats && lfio_radmap_has_cells(map);
    map_summary total;
    gather_total(map, stats, &total);
    if (json)
        return print_json(path, map, &total, stats);
    print_file_text(path, map, &total, stats);
    for (size_t k = 0; k < lfio_radmap_count(map); k++) {
        lfio_radmap_patch p;
        map_summary m;
        lfio_radmap_get(map, k, &p);
        summarise(&p, stats, &m);
        print_map_text(k, &m, stats);
    }
    return ILF_EXIT_OK;
}
