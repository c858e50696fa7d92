/*
 * cmd_info.c - `ilf info FILE [--json] [--slab NAME|INDEX] [--stats] [--irradiance I,J] [--maps]`:
 * describes a light field file: its format version, creator and size, and for
 * each slab its geometry, sampling, units and stored coverage_fraction; with
 * --stats also its radiance statistics, zero-radiance mask occupancy and the
 * covered share when the slab has a coverage dataset; with --irradiance the
 * irradiance at one position centre. A radiance-map file (radiance.h5, as
 * `ilf relight` writes) is described by radmap_cli.c instead.
 *
 * Invariants: without --stats or --irradiance only the file's headers are
 * read (no slab is decompressed, no radiance map's cell), so info answers
 * at once on any file; with
 * them slabs are read one at a time (the memory needed is one slab, not the
 * file); the same slab_report feeds the text and the JSON output, so they
 * cannot disagree; the JSON schema is the one documented in docs/cli.md.
 */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "jsonout.h"
#include "lfio/lightfield.h"
#include "lfio/partition.h"
#include "radmap_cli.h"

#define INFO_MAX_MASK_LEVELS 32

typedef struct info_options {
    const char *path;
    const char *slab;     /* NULL: every slab */
    int json;
    int want_irradiance;
    int want_stats;       /* --stats: read every slab's data */
    int all_maps;         /* --maps: a radiance map's every map in the text report */
    uint32_t position[2]; /* (i, j) for --irradiance */
} info_options;

/* What info reports about one slab. */
typedef struct slab_report {
    lfio_slab_desc desc;
    uint64_t directions;
    int has_stats;        /* the fields below up to mask_set were gathered (--stats) */
    double min[3], max[3], mean[3];
    double zero_fraction; /* samples whose r, g and b are all 0 */
    uint32_t mask_levels;
    uint32_t mask_n[INFO_MAX_MASK_LEVELS];
    uint64_t mask_set[INFO_MAX_MASK_LEVELS];
    int has_irradiance;
    double irradiance[3];
    double stored_fraction;   /* the coverage_fraction attribute (the share of rays), NaN if none */
    int has_coverage;
    double covered_fraction;  /* etendue-weighted share of covered samples, positions equally */
    uint64_t covered, samples;
} slab_report;

enum info_option_id { OPT_JSON, OPT_SLAB, OPT_STATS, OPT_IRRADIANCE, OPT_MAPS };

static const cli_option info_options_table[] = {
    {"json", 0, NULL, "print JSON (schema in docs/cli.md) instead of text"},
    {"slab", 0, "NAME|INDEX", "describe only this slab (default: every slab)"},
    {"stats", 0, NULL, "also read the data: radiance statistics, mask, coverage (default: headers only)"},
    {"irradiance", 0, "I,J", "also report the irradiance at the centre of position (I,J)"},
    {"maps", 0, NULL, "radiance map: read, check and list every map, and the total area (default: the first 10)"},
};

static const cli_usage info_usage = {
    "info",
    "FILE [--json] [--slab NAME|INDEX] [--stats] [--irradiance I,J] [--maps]",
    "Describes a light field file from its headers alone: format version, creator,\n"
    "file size and, per slab, name, origin, u, v, grid, partition level n, directions,\n"
    "units, mask threshold and the stored coverage_fraction. --stats reads the data\n"
    "too: radiance min/max/mean per channel over all samples, the fraction of zero\n"
    "samples, the mask's set/total bits per level and, for a slab with a coverage\n"
    "dataset (as 'ilf reproject' writes), the covered share of its etendue.\n"
    "--irradiance I,J adds the irradiance at s=(I+0.5)/nu, t=(J+0.5)/nv on a surface\n"
    "facing -e3 (lfio_slab_irradiance).\n"
    "A radiance-map file (radiance.h5 of 'ilf relight') is described too: creator,\n"
    "scene, maps, cells, and per map its label, vertices, grid and cell count. The\n"
    "text reads only the first 10 maps, whatever the file holds; --maps and --json\n"
    "read and check every map and add the total area; --stats reads every cell too\n"
    "and adds the irradiance and radiosity min/max/area-weighted mean. 'ilf verify'\n"
    "checks every value.",
    "ilf info data/beams_lightfield.h5\n"
    "ilf info data/beams_lightfield.h5 --stats\n"
    "ilf info data/beams_lightfield.h5 --json --irradiance 8,8 | python3 -m json.tool\n"
    "ilf info out/beams/radiance.h5 --stats",
};

/* ------------------------------------------------------------ gathering */

static void gather_radiance_stats(const lfio_slab *slab, slab_report *rep)
{
    const float *rad = lfio_slab_radiance(slab);
    uint64_t samples = lfio_slab_dir_count(slab) * rep->desc.nu * rep->desc.nv;
    double sum[3] = {0, 0, 0};
    uint64_t zeros = 0;
    for (int c = 0; c < 3; c++) {
        rep->min[c] = samples > 0 ? rad[c] : 0.0;
        rep->max[c] = rep->min[c];
    }
    for (uint64_t k = 0; k < samples; k++) {
        const float *rgb = rad + 3 * k;
        for (int c = 0; c < 3; c++) {
            rep->min[c] = rgb[c] < rep->min[c] ? rgb[c] : rep->min[c];
            rep->max[c] = rgb[c] > rep->max[c] ? rgb[c] : rep->max[c];
            sum[c] += rgb[c];
        }
        zeros += rgb[0] == 0.0f && rgb[1] == 0.0f && rgb[2] == 0.0f;
    }
    for (int c = 0; c < 3; c++)
        rep->mean[c] = samples > 0 ? sum[c] / (double)samples : 0.0;
    rep->zero_fraction = samples > 0 ? (double)zeros / (double)samples : 0.0;
}

static void gather_mask(const lfio_slab *slab, slab_report *rep)
{
    uint32_t levels = lfio_slab_mask_levels(slab);
    rep->mask_levels = levels < INFO_MAX_MASK_LEVELS ? levels : INFO_MAX_MASK_LEVELS;
    for (uint32_t k = 0; k < rep->mask_levels; k++) {
        rep->mask_n[k] = lfio_slab_mask_n(slab, k);
        rep->mask_set[k] = lfio_slab_mask_count(slab, rep->mask_n[k]);
    }
}

/* Reads slab k's coverage, if it has one, into the report: the share of the slab's etendue (each sample weighted by
 * its solid angle's projected solid angle, positions equally) that is covered. @return an exit code. */
static int gather_coverage(lfio_reader *r, size_t k, const info_options *o, slab_report *rep)
{
    if (!lfio_reader_has_coverage(r, k))
        return ILF_EXIT_OK;
    const uint64_t npos = (uint64_t)rep->desc.nu * rep->desc.nv;
    rep->samples = rep->directions * npos;
    uint8_t *cov = malloc((size_t)rep->samples);
    if (cov == NULL) {
        cli_error("info", "%s: out of memory for the coverage of slab '%s'", o->path, rep->desc.name);
        return ILF_EXIT_FAILED;
    }
    lfio_status st = lfio_reader_read_coverage(r, k, cov);
    if (st != LFIO_OK) {
        free(cov);
        return cli_lfio_failure("info", st, CLI_INPUT, o->path);
    }
    rep->covered_fraction = lfio_coverage_share(&rep->desc, cov, &rep->covered);
    free(cov);
    rep->has_coverage = 1;
    return ILF_EXIT_OK;
}

/* Fills slab k's report from the file's headers alone (checked when the file was opened). */
static void gather_header(const lfio_reader *r, size_t k, slab_report *rep)
{
    memset(rep, 0, sizeof *rep);
    rep->desc = *lfio_reader_slab_desc(r, k);
    rep->directions = lfio_part_hemi_count(rep->desc.n);
    rep->stored_fraction = lfio_reader_coverage_fraction(r, k);
}

/* Fills slab k's report: its headers, and with --stats or --irradiance what its data give (the slab read whole).
 * @return an exit code. */
static int gather_slab(lfio_reader *r, size_t k, const info_options *o, slab_report *rep)
{
    gather_header(r, k, rep);
    if (!o->want_stats && !o->want_irradiance)
        return ILF_EXIT_OK;
    lfio_slab *slab = NULL;
    lfio_status st = lfio_reader_read_slab(r, k, &slab);
    if (st != LFIO_OK)
        return cli_lfio_failure("info", st, CLI_INPUT, o->path);
    int code = ILF_EXIT_OK;
    if (o->want_stats) {
        rep->has_stats = 1;
        gather_radiance_stats(slab, rep);
        gather_mask(slab, rep);
        code = gather_coverage(r, k, o, rep);
    }
    if (code == ILF_EXIT_OK && o->want_irradiance) {
        uint32_t i = o->position[0], j = o->position[1];
        if (i >= rep->desc.nu || j >= rep->desc.nv) {
            cli_error("info", "%s: slab '%s' has %ux%u positions; --irradiance %u,%u is outside", o->path,
                      rep->desc.name, (unsigned)rep->desc.nu, (unsigned)rep->desc.nv, (unsigned)i, (unsigned)j);
            code = ILF_EXIT_USAGE;
        } else {
            double s = (i + 0.5) / rep->desc.nu, t = (j + 0.5) / rep->desc.nv;
            st = lfio_slab_irradiance(slab, s, t, rep->irradiance);
            rep->has_irradiance = st == LFIO_OK;
            if (st != LFIO_OK)
                code = cli_lfio_failure("info", st, CLI_INPUT, o->path);
        }
    }
    lfio_slab_destroy(slab);
    return code;
}

static const char *units_name(lfio_units units)
{
    return units == LFIO_UNITS_RELATIVE ? "relative" : "W sr^-1 m^-2";
}

/* ------------------------------------------------------------ text */

static void print_vec3(const char *label, const double v[3])
{
    printf("  %-16s %.9g %.9g %.9g\n", label, v[0], v[1], v[2]);
}

static void print_file_text(const char *path, lfio_reader *r, long long bytes)
{
    char size[32];
    printf("file:             %s\n", path);
    printf("format version:   %d\n", lfio_reader_format_version(r));
    printf("creator:          %s\n", lfio_reader_creator(r));
    printf("file size:        %s (%lld bytes)\n", cli_format_bytes(bytes, size, sizeof size), bytes);
    printf("slabs:            %zu\n", lfio_reader_slab_count(r));
}

static void print_slab_text(size_t k, const slab_report *rep, const info_options *o)
{
    const lfio_slab_desc *d = &rep->desc;
    printf("\nslab %zu: %s\n", k, d->name);
    print_vec3("origin:", d->origin);
    print_vec3("u:", d->u);
    print_vec3("v:", d->v);
    printf("  %-16s %ux%u positions\n", "grid:", (unsigned)d->nu, (unsigned)d->nv);
    printf("  %-16s %u (%llu directions)\n", "n:", (unsigned)d->n, (unsigned long long)rep->directions);
    printf("  %-16s %s\n", "units:", units_name(d->units));
    printf("  %-16s %.9g\n", "mask threshold:", (double)d->mask_threshold);
    if (rep->has_stats) {
        print_vec3("radiance min:", rep->min);
        print_vec3("radiance max:", rep->max);
        print_vec3("radiance mean:", rep->mean);
        printf("  %-16s %.4f%%\n", "zero samples:", 100.0 * rep->zero_fraction);
    }
    for (uint32_t l = 0; l < rep->mask_levels; l++)
        printf("  %-16s n=%u: %llu/%llu set\n", l == 0 ? "mask:" : "", (unsigned)rep->mask_n[l],
               (unsigned long long)rep->mask_set[l], (unsigned long long)lfio_part_hemi_count(rep->mask_n[l]));
    if (!isnan(rep->stored_fraction))
        printf("  %-16s %.2f%% of the etendue covered, %.2f%% not (attribute coverage_fraction)\n", "covered rays:",
               100.0 * rep->stored_fraction, 100.0 * (1.0 - rep->stored_fraction));
    if (rep->has_coverage)
        printf("  %-16s %.2f%% of the etendue (%llu of %llu samples)\n", "coverage:", 100.0 * rep->covered_fraction,
               (unsigned long long)rep->covered, (unsigned long long)rep->samples);
    if (rep->has_irradiance) {
        char label[64];
        snprintf(label, sizeof label, "irradiance (%u,%u):", (unsigned)o->position[0], (unsigned)o->position[1]);
        printf("  %s %.9g %.9g %.9g\n", label, rep->irradiance[0], rep->irradiance[1], rep->irradiance[2]);
    }
}

/* ------------------------------------------------------------ JSON */

static cJSON *mask_json(const slab_report *rep)
{
    cJSON *mask = cJSON_CreateArray();
    for (uint32_t l = 0; mask != NULL && l < rep->mask_levels; l++) {
        cJSON *level = cJSON_CreateObject();
        if (level == NULL || !cJSON_AddItemToArray(mask, level)) {
            cJSON_Delete(level);
            cJSON_Delete(mask);
            return NULL;
        }
        cJSON_AddNumberToObject(level, "n", rep->mask_n[l]);
        cJSON_AddNumberToObject(level, "set", (double)rep->mask_set[l]);
        cJSON_AddNumberToObject(level, "total", (double)lfio_part_hemi_count(rep->mask_n[l]));
    }
    return mask;
}

/* Builds one entry of "slabs". @return NULL when memory runs out. */
static cJSON *slab_json(const slab_report *rep, const info_options *o)
{
    const lfio_slab_desc *d = &rep->desc;
    cJSON *s = cJSON_CreateObject();
    if (s == NULL)
        return NULL;
    cJSON_AddStringToObject(s, "name", d->name);
    int ok = json_add_doubles(s, "origin", d->origin, 3) && json_add_doubles(s, "u", d->u, 3) &&
             json_add_doubles(s, "v", d->v, 3);
    cJSON_AddNumberToObject(s, "nu", d->nu);
    cJSON_AddNumberToObject(s, "nv", d->nv);
    cJSON_AddNumberToObject(s, "n", d->n);
    cJSON_AddNumberToObject(s, "directions", (double)rep->directions);
    cJSON_AddStringToObject(s, "units", units_name(d->units));
    cJSON_AddNumberToObject(s, "mask_threshold", d->mask_threshold);
    if (rep->has_stats) {
        ok = ok && json_add_doubles(s, "radiance_min", rep->min, 3) &&
             json_add_doubles(s, "radiance_max", rep->max, 3) && json_add_doubles(s, "radiance_mean", rep->mean, 3);
        cJSON_AddNumberToObject(s, "zero_fraction", rep->zero_fraction);
        cJSON *mask = mask_json(rep);
        ok = ok && mask != NULL && cJSON_AddItemToObject(s, "mask", mask);
    }
    if (!isnan(rep->stored_fraction))
        ok = ok && cJSON_AddNumberToObject(s, "coverage_fraction", rep->stored_fraction);
    if (rep->has_coverage) {
        cJSON *c = cJSON_AddObjectToObject(s, "coverage");
        ok = ok && c != NULL && cJSON_AddNumberToObject(c, "fraction", rep->covered_fraction) &&
             cJSON_AddNumberToObject(c, "covered", (double)rep->covered) &&
             cJSON_AddNumberToObject(c, "samples", (double)rep->samples);
    }
    if (rep->has_irradiance) {
        double position[2] = {o->position[0], o->position[1]};
        ok = ok && json_add_doubles(s, "irradiance", rep->irradiance, 3) &&
             json_add_doubles(s, "position", position, 2);
    }
    if (!ok) {
        cJSON_Delete(s);
        return NULL;
    }
    return s;
}

static cJSON *file_json(const char *path, lfio_reader *r, long long bytes)
{
    cJSON *root = cJSON_CreateObject();
    if (root == NULL)
        return NULL;
    cJSON_AddStringToObject(root, "file", path);
    cJSON_AddNumberToObject(root, "format_version", lfio_reader_format_version(r));
    cJSON_AddStringToObject(root, "creator", lfio_reader_creator(r));
    cJSON_AddNumberToObject(root, "file_bytes", (double)bytes);
    if (cJSON_AddArrayToObject(root, "slabs") == NULL) {
        cJSON_Delete(root);
        return NULL;
    }
    return root;
}

/* ------------------------------------------------------------ main */

/* Applies one option to the info_options ctx. @return 1, or 0 after reporting. */
static int apply_option(const cli_parser *p, int opt, const char *value, void *ctx)
{
    info_options *o = ctx;
    if (opt == OPT_JSON)
        o->json = 1;
    else if (opt == OPT_SLAB)
        o->slab = value;
    else if (opt == OPT_STATS)
        o->want_stats = 1;
    else if (opt == OPT_MAPS)
        o->all_maps = 1;
    else
        return o->want_irradiance = cli_value_u32_pair(p, value, ',', 0, UINT32_MAX, o->position);
    return 1;
}

/* Parses argv into *o. @return -1 to go on, or an exit code (help printed, or a reported error). */
static int parse_arguments(info_options *o, int argc, char **argv)
{
    int code = cli_parse(&info_usage, info_options_table, sizeof info_options_table / sizeof info_options_table[0],
                         argc, argv, &o->path, apply_option, o);
    if (code != -1)
        return code;
    if (o->path == NULL) {
        cli_error("info", "no file given (see 'ilf info --help')");
        return ILF_EXIT_USAGE;
    }
    return -1;
}

/* Gathers reports on slabs [first, first + count), one slab in memory at a time. @return an exit code. */
static int gather_slabs(lfio_reader *r, size_t first, size_t count, const info_options *o, slab_report *reps)
{
    int code = ILF_EXIT_OK;
    for (size_t k = 0; k < count && code == ILF_EXIT_OK; k++)
        code = gather_slab(r, first + k, o, &reps[k]);
    return code;
}

static int print_text(lfio_reader *r, size_t first, size_t count, const info_options *o, const slab_report *reps)
{
    print_file_text(o->path, r, cli_file_size(o->path));
    for (size_t k = 0; k < count; k++)
        print_slab_text(first + k, &reps[k], o);
    return ILF_EXIT_OK;
}

static int print_json_report(lfio_reader *r, size_t count, const info_options *o, const slab_report *reps)
{
    cJSON *root = file_json(o->path, r, cli_file_size(o->path));
    cJSON *slabs = cJSON_GetObjectItem(root, "slabs");
    int ok = root != NULL;
    for (size_t k = 0; ok && k < count; k++) {
        cJSON *s = slab_json(&reps[k], o);
        ok = s != NULL && cJSON_AddItemToArray(slabs, s);
        if (!ok)
            cJSON_Delete(s);
    }
    int code = ok ? json_print("info", root) : (cli_error("info", "out of memory while building JSON"), ILF_EXIT_FAILED);
    cJSON_Delete(root);
    return code;
}

/* Gathers everything first, so that a damaged slab leaves no half-printed report. */
static int describe_file(lfio_reader *r, const info_options *o)
{
    size_t first = 0, count = lfio_reader_slab_count(r);
    if (o->slab != NULL) {
        if (!cli_select_slab("info", o->path, r, o->slab, &first))
            return ILF_EXIT_USAGE;
        count = 1;
    }
    slab_report *reps = calloc(count > 0 ? count : 1, sizeof *reps);
    if (reps == NULL) {
        cli_error("info", "out of memory");
        return ILF_EXIT_FAILED;
    }
    int code = gather_slabs(r, first, count, o, reps);
    if (code == ILF_EXIT_OK)
        code = o->json ? print_json_report(r, count, o, reps) : print_text(r, first, count, o, reps);
    free(reps);
    return code;
}

/* A file lfio's light field reader refused as not one: a radiance map (its headers, or read whole for
 * --stats), or the light field reader's message. */
static int describe_radmap(const info_options *o)
{
    char lf_msg[1024], msg[1024];
    snprintf(lf_msg, sizeof lf_msg, "%s", lfio_errmsg());
    ilf_radmap_info in = {o->path, lf_msg, NULL, NULL, o->json, o->want_stats, o->all_maps};
    lfio_radmap *map = NULL;
    lfio_status st = o->want_stats ? ilf_radmap_try(o->path, lf_msg, &map, msg, sizeof msg)
                                   : ilf_radmap_try_headers(o->path, lf_msg, &in.headers, msg, sizeof msg);
    if (st != LFIO_OK)
        return cli_lfio_failure_msg("info", st, CLI_INPUT, o->path, msg);
    in.map = map;
    int code = ILF_EXIT_OK;
    if (o->slab != NULL || o->want_irradiance) {
        cli_error("info", "%s: a radiance map has no slabs: --slab and --irradiance are for light fields", o->path);
        code = ILF_EXIT_USAGE;
    } else {
        code = ilf_info_radmap(&in);
    }
    lfio_radmap_destroy(map);
    lfio_radmap_headers_close(in.headers);
    return code;
}

int ilf_cmd_info(int argc, char **argv)
{
    info_options o = {0};
    int code = parse_arguments(&o, argc, argv);
    if (code >= 0)
        return code;
    lfio_reader *r = NULL;
    lfio_status st = lfio_reader_open(o.path, &r);
    if (st == LFIO_ERR_FORMAT)
        return describe_radmap(&o);
    if (st != LFIO_OK)
        return cli_lfio_failure("info", st, CLI_INPUT, o.path);
    if (o.all_maps) {
        cli_error("info", "%s: a light field has no radiance maps: --maps is for radiance-map files", o.path);
        lfio_reader_close(r);
        return ILF_EXIT_USAGE;
    }
    code = describe_file(r, &o);
    lfio_reader_close(r);
    return code;
}
