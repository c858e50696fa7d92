/*
 * cmd_reproject.c - `ilf reproject IN.h5 --proxy PROXY -o OUT.h5`: depth
 * correction. Every slab of IN (a captured light field, one slab per capture
 * plane; or the one --slab names) is merged onto proxy geometry (a JSON list
 * of rectangles, or a mesh read with assimp whose faces are rectangular
 * quads or triangles paired into rectangles), one output slab per rectangle
 * (capture/reproject.h). The share of each proxy slab's etendue that the
 * capture covers, and of the whole proxy's, is printed; each slab's share is
 * stored in OUT.h5 as its coverage_fraction attribute, and which samples the
 * capture covers as its coverage dataset.
 *
 * Invariants: the output folder is checked and the input read before any
 * work; OUT.h5, coverage included, is written atomically by lfio, so a
 * failure leaves no partial file; stdout carries the summary (nothing with
 * --quiet), stderr errors and the progress bar.
 */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "capture/reproject.h"
#include "cli.h"
#include "ilf/pool.h"
#include "ilf/limits.h"
#include "lfio/partition.h"
#include "commands.h"

#define REPROJECT_CREATOR "ilf reproject (ilfkit " ILFKIT_VERSION ")"

typedef struct reproject_options {
    const char *input;
    const char *proxy;
    const char *output;
    const char *slab;
    uint32_t n;          /* 0: the captured slab's */
    uint32_t grid[2];
    uint32_t strata;
    unsigned threads;
    int plain;
    int quiet;
} reproject_options;

enum reproject_option_id { OPT_PROXY, OPT_OUTPUT, OPT_SLAB, OPT_N, OPT_GRID, OPT_STRATA, OPT_PLAIN, OPT_THREADS,
                           OPT_QUIET };

static const cli_option reproject_options_table[] = {
    {"proxy", 0, "PROXY", "rectangles: a .json list, or a mesh of rectangles (quads, or triangle pairs) (required)"},
    {"output", 'o', "OUT.h5", "light field file to write, one slab per rectangle (required)"},
    {"slab", 0, "NAME|INDEX", "use this captured slab of IN.h5 alone (default: every slab, merged)"},
    {"n", 0, "N", "partition level of rectangles that do not give one (default: the captured slabs' finest)"},
    {"grid", 0, "NUxNV", "positions of rectangles that do not give them (default 16x16)"},
    {"strata", 0, "S", "S*S rays per solid angle, 1 .. 16 (default 2)"},
    {"plain", 0, NULL, "look every probe up along the ray's direction (no depth correction), to compare"},
    {"threads", 0, "N", "worker threads, 0 = every processor (default 0); the result does not depend on it"},
    {"quiet", 'q', NULL, "no progress bar and no summary on stdout"},
};

static const cli_usage reproject_usage = {
    "reproject",
    "IN.h5 --proxy PROXY -o OUT.h5 [--slab S] [--n N] [--grid NUxNV] [--strata S]\n"
    "                     [--plain] [--threads N] [--quiet]",
    "Depth correction: each ray leaving a proxy rectangle's front is traced back, as a\n"
    "line, to each captured slab's plane; the probes around the crossing are asked for\n"
    "the light they saw coming from the ray's point on the proxy, and the captures that\n"
    "cover the ray are blended by how finely each resolves it (docs/capture.md).\n"
    "Rays no capture covers carry no light; the covered share of each proxy slab's\n"
    "etendue is printed and stored in OUT.h5 (attribute /slabs/K/coverage_fraction,\n"
    "dataset /slabs/K/coverage; 'ilf info' shows both), and the whole proxy's printed.",
    "ilf reproject probes.h5 --proxy data/capture/proxy.json -o lamp.h5\n"
    "ilf reproject probes.h5 --proxy quads.obj --grid 32x32 --n 16 -o proxy.h5",
};

/* ------------------------------------------------------------ options */

static int apply_option(const cli_parser *p, int opt, const char *value, void *ctx)
{
    reproject_options *o = ctx;
    switch (opt) {
    case OPT_PROXY:
        o->proxy = value;
        return 1;
    case OPT_OUTPUT:
        o->output = value;
        return 1;
    case OPT_SLAB:
        o->slab = value;
        return 1;
    case OPT_N:
        return cli_value_u32(p, value, 1, LFIO_SLAB_MAX_N, &o->n);
    case OPT_GRID:
        return cli_value_u32_pair(p, value, 'x', 1, 65536, o->grid);
    case OPT_STRATA:
        return cli_value_u32(p, value, 1, 16, &o->strata);
    case OPT_PLAIN:
        o->plain = 1;
        return 1;
    case OPT_THREADS:
        return cli_value_threads(p, value, &o->threads);
    default:
        o->quiet = 1;
        return 1;
    }
}

/* Parses argv into *o. @return -1 to go on, or an exit code (help printed, or a reported error). */
static int parse_arguments(reproject_options *o, int argc, char **argv)
{
    int code = cli_parse(&reproject_usage, reproject_options_table,
                         sizeof reproject_options_table / sizeof reproject_options_table[0], argc, argv, &o->input,
                         apply_option, o);
    if (code != -1)
        return code;
    const char *problem = NULL;
    if (o->input == NULL)
        problem = "no input light field given (see 'ilf reproject --help')";
    else if (o->proxy == NULL)
        problem = "--proxy PROXY is required";
    else if (o->output == NULL || o->output[0] == '\0')
        problem = "-o OUT.h5 is required";
    if (problem != NULL) {
        cli_error("reproject", "%s", problem);
        return ILF_EXIT_USAGE;
    }
    return -1;
}

/* ------------------------------------------------------------ work */

/* The captured slabs: every slab of the input, or the one --slab names. */
typedef struct captured_set {
    lfio_slab **slabs;
    size_t count;
} captured_set;

static void captured_free(captured_set *c)
{
    for (size_t k = 0; k < c->count; k++)
        lfio_slab_destroy(c->slabs[k]);
    free(c->slabs);
    memset(c, 0, sizeof *c);
}

/* Reads the captured slabs of the input. @return an exit code, and *c on success. */
static int read_captured(const reproject_options *o, captured_set *c)
{
    lfio_reader *r = NULL;
    size_t index = 0;
    lfio_status st = lfio_reader_open(o->input, &r);
    if (st != LFIO_OK)
        return cli_lfio_failure("reproject", st, CLI_INPUT, o->input);
    int code = ILF_EXIT_OK;
    size_t count = lfio_reader_slab_count(r);
    if (o->slab != NULL)
        code = cli_select_slab("reproject", o->input, r, o->slab, &index) ? ILF_EXIT_OK : ILF_EXIT_USAGE;
    else if (count > CAP_CAPTURED_MAX) {
        cli_error("reproject", "%s: %zu slabs; at most %u are merged (choose one with --slab)", o->input, count,
                  CAP_CAPTURED_MAX);
        code = ILF_EXIT_USAGE;
    }
    count = o->slab != NULL ? 1 : count;
    if (code == ILF_EXIT_OK && (c->slabs = calloc(count, sizeof *c->slabs)) == NULL) {
        cli_error("reproject", "out of memory");
        code = ILF_EXIT_FAILED;
    }
    for (size_t k = 0; code == ILF_EXIT_OK && k < count; k++) {
        if ((st = lfio_reader_read_slab(r, o->slab != NULL ? index : k, &c->slabs[k])) != LFIO_OK)
            code = cli_lfio_failure("reproject", st, CLI_INPUT, o->input);
        else
            c->count++;
    }
    if (code == ILF_EXIT_OK && count > 1) {
        lfio_units units = lfio_slab_get_desc(c->slabs[0])->units;
        for (size_t k = 1; code == ILF_EXIT_OK && k < count; k++)
            if (lfio_slab_get_desc(c->slabs[k])->units != units) {
                cli_error("reproject", "%s: slabs '%s' and '%s' have different radiance units; merge slabs of one "
                          "unit (or choose one with --slab)", o->input, lfio_slab_get_desc(c->slabs[0])->name,
                          lfio_slab_get_desc(c->slabs[k])->name);
                code = ILF_EXIT_USAGE;
            }
    }
    lfio_reader_close(r);
    if (code != ILF_EXIT_OK)
        captured_free(c);
    return code;
}

/* @return the total positions over the proxy's rectangles. */
/* @return the rays one position of rectangle d samples (directions times strata squared): the progress bar's
 * work, since rectangles of different partition levels cost different amounts per position. */
static uint64_t position_rays(const lfio_slab_desc *d, uint32_t strata)
{
    return 4ull * d->n * d->n * strata * strata;
}

/* @return the rays of every rectangle of the proxy. */
static uint64_t proxy_rays(const cap_proxy *proxy, uint32_t strata)
{
    uint64_t total = 0;
    for (size_t k = 0; k < cap_proxy_count(proxy); k++) {
        const lfio_slab_desc *d = cap_proxy_get_desc(proxy, k);
        total += (uint64_t)d->nu * d->nv * position_rays(d, strata);
    }
    return total;
}

/* Checks that the output the proxy asks for (every rectangle's slab, and the rays that fill them) is within
 * ILF_REPROJECT_MAX_BYTES and ILF_REPROJECT_MAX_RAYS, before any work. @return an exit code. */
static int check_work(const reproject_options *o, const cap_proxy *proxy)
{
    double bytes = 0.0, values = 0.0;
    for (size_t k = 0; k < cap_proxy_count(proxy); k++) {
        const lfio_slab_desc *d = cap_proxy_get_desc(proxy, k);
        bytes += (double)lfio_slab_desc_bytes(d);
        values += (double)d->nu * d->nv * (double)lfio_part_hemi_count(d->n);
    }
    double strata = o->strata ? (double)o->strata : 2.0, rays = values * strata * strata; /* 0: the default 2 */
    char size[32], limit[32];
    if (bytes > (double)ILF_REPROJECT_MAX_BYTES) {
        cli_error("reproject", "%s: %zu rectangle%s ask for %s of radiance, more than the limit of %s (ilf/limits.h)",
                  o->proxy, cap_proxy_count(proxy), cap_proxy_count(proxy) == 1 ? "" : "s",
                  cli_format_bytes((long long)(bytes < 9e18 ? bytes : 9e18), size, sizeof size),
                  cli_format_bytes((long long)ILF_REPROJECT_MAX_BYTES, limit, sizeof limit));
        return ILF_EXIT_USAGE;
    }
    if (rays > (double)ILF_REPROJECT_MAX_RAYS) {
        cli_error("reproject", "%s: %zu rectangle%s ask for %.3g rays, more than the limit of %.3g (ilf/limits.h)",
                  o->proxy, cap_proxy_count(proxy), cap_proxy_count(proxy) == 1 ? "" : "s", rays,
                  (double)ILF_REPROJECT_MAX_RAYS);
        return ILF_EXIT_USAGE;
    }
    return ILF_EXIT_OK;
}

/* The shared bar, the rays of the slabs already made and those of one position of this one. */
typedef struct slab_progress {
    cli_progress *bar;
    uint64_t offset, per_position;
} slab_progress;

/* cap_progress_fn: a slab's positions done, shown as rays after those of the earlier slabs. */
static void on_slab_progress(void *user, uint64_t done, uint64_t total)
{
    const slab_progress *sp = user;
    ilf_capture_progress(sp->bar, sp->offset + done * sp->per_position, total);
}

/* Makes one output slab per rectangle into lf, coverage in cov[k]. @return an exit code. */
static int reproject_all(const reproject_options *o, const captured_set *captured, const cap_proxy *proxy,
                         lfio_lightfield *lf, cap_coverage *cov)
{
    cli_progress bar;
    slab_progress sp = {&bar, 0, 0};
    cap_reproject_options ro = {o->plain ? CAP_REPROJECT_PLAIN : CAP_REPROJECT_DEPTH, o->strata, o->threads,
                                o->quiet ? NULL : on_slab_progress, &sp, NULL};
    uint32_t strata = o->strata ? o->strata : 2; /* cap_reproject_options' default */
    unsigned threads = ilf_thread_count(o->threads);
    char rays[32];
    snprintf(rays, sizeof rays, "%.3g", (double)proxy_rays(proxy, strata));
    cli_set_quiet(o->quiet);
    cli_settings("reproject", "method %s, %zu rectangle%s, %ux%u rays per solid angle, %s rays, %u thread%s",
                 o->plain ? "plain" : "depth-corrected", cap_proxy_count(proxy),
                 cap_proxy_count(proxy) == 1 ? "" : "s", (unsigned)strata, (unsigned)strata, rays, threads,
                 threads == 1 ? "" : "s");
    if (!o->quiet)
        cli_progress_start(&bar, "reproject", proxy_rays(proxy, strata));
    int code = ILF_EXIT_OK;
    for (size_t k = 0; code == ILF_EXIT_OK && k < cap_proxy_count(proxy); k++) {
        const lfio_slab_desc *d = cap_proxy_get_desc(proxy, k);
        lfio_slab *slab = NULL;
        sp.per_position = position_rays(d, strata);
        /* The proxy's sizes passed lfio's 64 GiB radiance limit, so this count fits in size_t. */
        ro.covered = malloc((size_t)(4 * (uint64_t)d->n * d->n * d->nu * d->nv));
        if (ro.covered == NULL) {
            cli_error("reproject", "out of memory for the coverage of '%s'", d->name);
            code = ILF_EXIT_FAILED;
            break;
        }
        cap_status st = cap_reproject_field((const lfio_slab *const *)captured->slabs, captured->count, d, &ro, &slab,
                                            &cov[k]);
        if (st != CAP_OK)
            code = ilf_capture_failure("reproject", st);
        sp.offset += (uint64_t)d->nu * d->nv * sp.per_position;
        lfio_status ls = code == ILF_EXIT_OK ? lfio_lightfield_take_slab(lf, slab) : LFIO_OK;
        if (ls == LFIO_OK && code == ILF_EXIT_OK)
            ls = lfio_lightfield_set_coverage(lf, k, ro.covered);
        if (ls == LFIO_OK && code == ILF_EXIT_OK)
            ls = lfio_lightfield_set_coverage_fraction(lf, k, cov[k].fraction);
        if (ls != LFIO_OK)
            code = cli_lfio_failure("reproject", ls, CLI_OUTPUT, o->output);
        free(ro.covered);
        ro.covered = NULL;
    }
    if (!o->quiet)
        cli_progress_finish(&bar);
    return code;
}

/* @return the covered share of the etendue of every slab of lf together: each slab's share weighted by its
 * etendue, its area times pi. */
static double proxy_coverage(const lfio_lightfield *lf, const cap_coverage *cov)
{
    double covered = 0.0, total = 0.0;
    for (size_t k = 0; k < lfio_lightfield_slab_count(lf); k++) {
        const lfio_slab_desc *d = lfio_slab_get_desc(lfio_lightfield_slab(lf, k));
        double uu = d->u[0] * d->u[0] + d->u[1] * d->u[1] + d->u[2] * d->u[2];
        double vv = d->v[0] * d->v[0] + d->v[1] * d->v[1] + d->v[2] * d->v[2];
        double area = sqrt(uu * vv);
        covered += area * cov[k].fraction;
        total += area;
    }
    return total > 0.0 ? covered / total : 0.0;
}

/* Writes OUT.h5 (radiance and coverage) and prints what was written. @return an exit code. */
static int write_outputs(const reproject_options *o, lfio_lightfield *lf, const cap_coverage *cov)
{
    char size[32];
    lfio_status ls = lfio_lightfield_set_creator(lf, REPROJECT_CREATOR);
    if (ls == LFIO_OK)
        ls = lfio_lightfield_write(lf, o->output);
    if (ls != LFIO_OK)
        return cli_lfio_failure("reproject", ls, CLI_OUTPUT, o->output);
    if (o->quiet)
        return ILF_EXIT_OK;
    for (size_t k = 0; k < lfio_lightfield_slab_count(lf); k++) {
        const lfio_slab_desc *d = lfio_slab_get_desc(lfio_lightfield_slab(lf, k));
        printf("slab '%s': %" PRIu32 "x%" PRIu32 " positions, n %" PRIu32 ", coverage %.2f%% (%" PRIu64 " of %" PRIu64
               " rays)\n", d->name, d->nu, d->nv, d->n, 100.0 * cov[k].fraction, cov[k].covered, cov[k].rays);
    }
    size_t count = lfio_lightfield_slab_count(lf);
    if (count > 1)
        printf("coverage of the whole proxy: %.2f%% of its etendue\n", 100.0 * proxy_coverage(lf, cov));
    printf("wrote %s: %zu slab%s with coverage, %s (%s)\n", o->output, count, count == 1 ? "" : "s",
           cli_format_bytes(cli_file_size(o->output), size, sizeof size), o->plain ? "plain lookup" : "depth-corrected");
    return ILF_EXIT_OK;
}

/* @return the finest partition level of the captured slabs: the default level of the proxy's slabs. */
static uint32_t max_level(const captured_set *c)
{
    uint32_t n = 1;
    for (size_t k = 0; k < c->count; k++)
        if (lfio_slab_get_desc(c->slabs[k])->n > n)
            n = lfio_slab_get_desc(c->slabs[k])->n;
    return n;
}

int ilf_cmd_reproject(int argc, char **argv)
{
    reproject_options o = {0};
    o.grid[0] = o.grid[1] = 16;
    int code = parse_arguments(&o, argc, argv);
    if (code >= 0)
        return code;
    if ((code = cli_output_check("reproject", o.output)) != ILF_EXIT_OK)
        return code;
    cli_output_watch(o.output);
    captured_set captured = {NULL, 0};
    cap_proxy *proxy = NULL;
    lfio_lightfield *lf = NULL;
    cap_coverage *cov = NULL;
    code = read_captured(&o, &captured);
    if (code == ILF_EXIT_OK) {
        cap_proxy_defaults def = {o.grid[0], o.grid[1], o.n ? o.n : max_level(&captured)};
        cap_status st = cap_proxy_load(o.proxy, &def, &proxy);
        code = st == CAP_OK ? ILF_EXIT_OK : ilf_capture_failure("reproject", st);
    }
    if (code == ILF_EXIT_OK)
        code = check_work(&o, proxy);
    if (code == ILF_EXIT_OK && (lfio_lightfield_new(&lf) != LFIO_OK ||
                                (cov = calloc(cap_proxy_count(proxy), sizeof *cov)) == NULL)) {
        cli_error("reproject", "out of memory");
        code = ILF_EXIT_FAILED;
    }
    if (code == ILF_EXIT_OK)
        code = reproject_all(&o, &captured, proxy, lf, cov);
    if (code == ILF_EXIT_OK)
        code = write_outputs(&o, lf, cov);
    free(cov);
    lfio_lightfield_destroy(lf);
    cap_proxy_destroy(proxy);
    captured_free(&captured);
    return code;
}
