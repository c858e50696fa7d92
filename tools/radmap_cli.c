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
 * need not read a cell (lfio_radmap_headers_open()); the report reads the
 * maps one at a time, twice (the totals, then the maps printed), never
 * holding more than one, and checks every map it reads before printing
 * anything. The text report details the first INFO_MAPS_SHOWN maps unless
 * --maps, and then reads no other map: the cell count is the headers'
 * (the cell offsets' last row) and the total area, which needs every map,
 * is left to --maps, --stats and --json, which read them all; so the
 * default report's time and memory do not grow with the maps (format 2).
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

/* Sets msg to what to report of a failure st of the radiance-map reader on a file the light field reader
 * refused with LFIO_ERR_FORMAT and lf_msg. */
static void try_message(lfio_status st, const char *lf_msg, char *msg, size_t msg_size)
{
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
}

lfio_status ilf_radmap_try(const char *path, const char *lf_msg, lfio_radmap **out, char *msg, size_t msg_size)
{
    lfio_status st = lfio_radmap_read(path, out);
    if (st != LFIO_OK)
        try_message(st, lf_msg, msg, msg_size);
    return st;
}

lfio_status ilf_radmap_try_headers(const char *path, const char *lf_msg, lfio_radmap_headers **out, char *msg,
                                   size_t msg_size)
{
    lfio_status st = lfio_radmap_headers_open(path, out);
    if (st != LFIO_OK)
        try_message(st, lf_msg, msg, msg_size);
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

/* Maps the text report details unless asked for all (--maps): enough to show what a file holds, few enough that
 * the report's time and length stay bounded whatever the number of maps. */
#define INFO_MAPS_SHOWN 10u

/* The report's source: the file read whole (with stats), else its headers a block at a time. */
static size_t src_count(const ilf_radmap_info *in)
{
    return in->map != NULL ? lfio_radmap_count(in->map) : lfio_radmap_headers_count(in->headers);
}

static const char *src_creator(const ilf_radmap_info *in)
{
    return in->map != NULL ? lfio_radmap_creator(in->map) : lfio_radmap_headers_creator(in->headers);
}

static const char *src_scene(const ilf_radmap_info *in)
{
    return in->map != NULL ? lfio_radmap_scene(in->map) : lfio_radmap_headers_scene(in->headers);
}

static int src_format_version(const ilf_radmap_info *in)
{
    return in->map != NULL ? lfio_radmap_format_version(in->map) : lfio_radmap_headers_format_version(in->headers);
}

/* Summarises map k of in's source into *m; its pointers are valid until the next call. */
static lfio_status src_summarise(const ilf_radmap_info *in, size_t k, int stats, map_summary *m)
{
    lfio_radmap_patch p;
    lfio_status st = in->map != NULL ? lfio_radmap_get(in->map, k, &p) : lfio_radmap_headers_get(in->headers, k, &p);
    if (st == LFIO_OK)
        summarise(&p, stats, m);
    return st;
}

static cJSON *file_json(const ilf_radmap_info *in, const map_summary *total, int stats)
{
    const char *path = in->path;
    cJSON *root = cJSON_CreateObject();
    if (root == NULL)
        return NULL;
    int ok = cJSON_AddStringToObject(root, "file", path) && cJSON_AddStringToObject(root, "kind", "radiance map") &&
             cJSON_AddNumberToObject(root, "format_version", src_format_version(in)) &&
             cJSON_AddStringToObject(root, "creator", src_creator(in)) &&
             cJSON_AddStringToObject(root, "scene", src_scene(in)) &&
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

/* Prints the text summary; total's area when the report reads every map (whole: --maps, --stats), else the
 * cell count alone, whatever the number of maps, so that the summary's lines do not depend on it. */
static void print_file_text(const ilf_radmap_info *in, const map_summary *total, int stats, int whole)
{
    const char *path = in->path;
    char size[32];
    long long bytes = cli_file_size(path);
    printf("file:             %s\n", path);
    printf("kind:             radiance map\n");
    printf("format version:   %d\n", src_format_version(in));
    printf("creator:          %s\n", src_creator(in));
    printf("scene:            %s\n", src_scene(in));
    printf("file size:        %s (%lld bytes)\n", cli_format_bytes(bytes, size, sizeof size), bytes);
    printf("maps:             %zu\n", src_count(in));
    if (whole)
        printf("cells:            %u, %.9g m^2\n", (unsigned)total->p.ncells, total->area);
    else
        printf("cells:            %u\n", (unsigned)total->p.ncells);
    if (stats) {
        print_stats_text("irradiance", &total->irradiance);
        print_stats_text("radiosity", &total->radiosity);
    }
}

/* Sums maps [0, n) into *total, checking each as it is read: a damaged map among them fails here, before
 * anything is printed. */
static lfio_status gather_total(const ilf_radmap_info *in, int stats, size_t n, map_summary *total)
{
    memset(total, 0, sizeof *total);
    stats_init(&total->irradiance);
    stats_init(&total->radiosity);
    lfio_status st = LFIO_OK;
    for (size_t k = 0; st == LFIO_OK && k < n; k++) {
        map_summary m;
        st = src_summarise(in, k, stats, &m);
        if (st == LFIO_OK)
            total_add(total, &m);
    }
    stats_finish(&total->irradiance, total->cell_area);
    stats_finish(&total->radiosity, total->cell_area);
    return st;
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

/* Prints map k's object as an element of the root's "maps" array. @return an lfio status (LFIO_ERR_NOMEM
 * when cJSON runs out of memory, reported by the caller). */
static lfio_status print_map_json(const ilf_radmap_info *in, size_t k, int stats)
{
    map_summary m;
    lfio_status st = src_summarise(in, k, stats, &m);
    cJSON *o = st == LFIO_OK ? map_json(&m, stats) : NULL;
    char *text = o != NULL ? cJSON_Print(o) : NULL;
    cJSON_Delete(o);
    if (st == LFIO_OK && text == NULL)
        st = LFIO_ERR_NOMEM;
    if (text != NULL) {
        fputs(k > 0 ? ", " : "", stdout);
        print_indented(text);
    }
    cJSON_free(text);
    return st;
}

/* Reports a failure st of reading a map: lfio's message with the light field reader's as ilf_radmap_try() gives
 * them (a map that does not read is reported as a file that failed to open would be), or cJSON's lack of
 * memory. @return the exit code. */
static int info_failure(const ilf_radmap_info *in, lfio_status st)
{
    if (st == LFIO_ERR_NOMEM) {
        cli_error("info", "out of memory while building the report");
        return ILF_EXIT_FAILED;
    }
    char msg[2048];
    try_message(st, in->lf_msg, msg, sizeof msg);
    return cli_lfio_failure_msg("info", st, CLI_INPUT, in->path, msg);
}

/* Prints the JSON report a map at a time, so that it holds one map's objects whatever the file holds: the
 * root's keys as cJSON_Print gives them with "maps" empty (its last key, so the last '[' of that text), then
 * each map's object indented as an element of that array: the text cJSON_Print gives of the whole tree. Failing
 * part-way, the text printed so far is cut off and the exit code says so. @return an exit code. */
static int print_json(const ilf_radmap_info *in, const map_summary *total, int stats)
{
    cJSON *root = file_json(in, total, stats);
    char *head = root != NULL ? cJSON_Print(root) : NULL;
    cJSON_Delete(root);
    const char *open = head != NULL ? strrchr(head, '[') : NULL;
    lfio_status st = open != NULL ? LFIO_OK : LFIO_ERR_NOMEM;
    if (st == LFIO_OK)
        fwrite(head, 1, (size_t)(open - head) + 1, stdout);
    cJSON_free(head);
    for (size_t k = 0; st == LFIO_OK && k < src_count(in); k++)
        st = print_map_json(in, k, stats);
    if (st != LFIO_OK)
        return info_failure(in, st);
    fputs("]\n}\n", stdout);
    return ILF_EXIT_OK;
}

/* @return the maps the report reads: every map for JSON, --maps or --stats (the file read whole), else the
 * INFO_MAPS_SHOWN the text details. */
static size_t maps_read(const ilf_radmap_info *in)
{
    const size_t count = src_count(in);
    return in->json || in->all_maps || in->map != NULL || count < INFO_MAPS_SHOWN ? count : INFO_MAPS_SHOWN;
}

/* Prints the text report: the file's summary, then the first INFO_MAPS_SHOWN maps (every map with all_maps)
 * and a line counting the rest. @return an exit code. */
static int print_text(const ilf_radmap_info *in, const map_summary *total, int stats)
{
    const size_t count = src_count(in);
    const size_t shown = in->all_maps || count < INFO_MAPS_SHOWN ? count : INFO_MAPS_SHOWN;
    print_file_text(in, total, stats, in->all_maps || in->map != NULL);
    for (size_t k = 0; k < shown; k++) {
        map_summary m;
        lfio_status st = src_summarise(in, k, stats, &m);
        if (st != LFIO_OK)
            return info_failure(in, st);
        print_map_text(k, &m, stats);
    }
    if (shown < count)
        printf("\n... and %zu more maps: ilf info --maps lists them\n", count - shown);
    return ILF_EXIT_OK;
}

int ilf_info_radmap(const ilf_radmap_info *in)
{
    const int stats = in->stats && in->map != NULL && lfio_radmap_has_cells(in->map);
    map_summary total;
    const size_t n = maps_read(in);
    lfio_status st = gather_total(in, stats, n, &total);
    if (st != LFIO_OK)
        return info_failure(in, st);
    if (n < src_count(in)) /* the cells of the maps not read: the headers count every map's */
        total.p.ncells = (uint32_t)lfio_radmap_headers_cell_count(in->headers);
    return in->json ? print_json(in, &total, stats) : print_text(in, &total, stats);
}
