/*
 * cmd_capture.c - `ilf capture MANIFEST -o OUT.h5`: turns the light probe
 * images a manifest lists (docs/capture.md) into a light field file with
 * one slab per capture plane, using the capture library (capture/capture.h).
 *
 * It also holds the two helpers the capture commands share (commands.h):
 * mapping a capture failure to a message and exit code, and feeding the
 * library's progress callbacks to a progress bar.
 *
 * Invariants: the output folder is checked before any image is read, so a
 * long capture never ends in an output that cannot be placed; the file is
 * written atomically by lfio; stdout carries the summary (nothing with
 * --quiet); stderr carries errors, one warning line per repaired image and
 * the progress bar (only on a terminal, never with --quiet).
 */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "capture/capture.h"
#include "cli.h"
#include "ilf/pool.h"
#include "commands.h"

#define CAPTURE_CREATOR "ilf capture (ilfkit " ILFKIT_VERSION ")"
/* The energy budget: a larger difference is reported as a warning. */
#define ENERGY_BUDGET 0.005

typedef struct capture_options {
    const char *manifest;
    const char *output;
    unsigned threads;
    int quiet;
} capture_options;

enum capture_option_id { OPT_OUTPUT, OPT_THREADS, OPT_QUIET };

static const cli_option capture_options_table[] = {
    {"output", 'o', "OUT.h5", "light field file to write (required)"},
    {"threads", 0, "N", "worker threads, 0 = every processor (default 0); the result does not depend on it"},
    {"quiet", 'q', NULL, "no progress bar and no summary on stdout (warnings are still printed)"},
};

static const cli_usage capture_usage = {
    "capture",
    "MANIFEST -o OUT.h5 [--threads N] [--quiet]",
    "Reads the light probe images a manifest lists (equirectangular, mirror ball or\n"
    "angular map; EXR, HDR, TIFF, PNG, JPEG; single images or exposure brackets) and\n"
    "box-filters each position's images onto the slab's solid angles (docs/capture.md);\n"
    "a manifest naming several planes gives one slab per plane.\n"
    "Negative, NaN and infinite pixel values are repaired and reported, one warning\n"
    "per image. Prints the largest difference between the irradiance computed from the\n"
    "light field and from the images at any position (budget 0.5%).",
    "ilf capture data/capture/studio.json -o studio.h5\n"
    "ilf render-probes data/capture/scene.json --plane -0.5,0.5,1.5:1,0,0:0,-1,0 --grid 2x2 -o probes\n"
    "ilf capture probes/manifest.json -o probes.h5 --threads 2",
};

/* ------------------------------------------------------------ shared helpers */

int ilf_capture_failure(const char *sub, int status)
{
    char line[1024];
    const char *msg = cli_one_line(cap_error_message(), line, sizeof line);
    cli_error(sub, "%s", msg[0] != '\0' ? msg : cap_status_name((cap_status)status));
    return status == CAP_ERR_INPUT || status == CAP_ERR_ARG ? ILF_EXIT_USAGE : ILF_EXIT_FAILED;
}

void ilf_capture_progress(void *bar, uint64_t done, uint64_t total)
{
    (void)total;
    cli_progress_reach(bar, done);
}

/* ------------------------------------------------------------ options */

/* Applies one option to the capture_options ctx. @return 1, or 0 after reporting. */
static int apply_option(const cli_parser *p, int opt, const char *value, void *ctx)
{
    capture_options *o = ctx;
    if (opt == OPT_OUTPUT)
        o->output = value;
    else if (opt == OPT_THREADS)
        return cli_value_threads(p, value, &o->threads);
    else if (opt == OPT_QUIET)
        o->quiet = 1;
    return 1;
}

/* Parses argv into *o. @return -1 to go on, or an exit code (help printed, or a reported error). */
static int parse_arguments(capture_options *o, int argc, char **argv)
{
    int code = cli_parse(&capture_usage, capture_options_table,
                         sizeof capture_options_table / sizeof capture_options_table[0], argc, argv, &o->manifest,
                         apply_option, o);
    if (code != -1)
        return code;
    if (o->manifest == NULL) {
        cli_error("capture", "no manifest given (see 'ilf capture --help')");
        return ILF_EXIT_USAGE;
    }
    if (o->output == NULL || o->output[0] == '\0') {
        cli_error("capture", "-o OUT.h5 is required");
        return ILF_EXIT_USAGE;
    }
    return -1;
}

/* ------------------------------------------------------------ reporting */

/* One warning line for an image whose values were repaired. */
static void warn_repair(const cap_repair *r)
{
    char text[512] = "";
    size_t len = 0;
    if (r->negative > 0)
        len += (size_t)snprintf(text + len, sizeof text - len, "%" PRIu64 " negative value%s (lowest %g) set to 0",
                                r->negative, r->negative == 1 ? "" : "s", (double)r->lowest);
    if (r->nan + r->infinite > 0 && len < sizeof text)
        snprintf(text + len, sizeof text - len, "%s%" PRIu64 " NaN and %" PRIu64
                 " infinite value%s replaced by their neighbours' mean", len > 0 ? "; " : "", r->nan, r->infinite,
                 r->infinite == 1 ? "" : "s");
    fprintf(stderr, "ilf capture: warning: %s: %s\n", r->file, text);
}

/* Writes where the worst energy difference is into out: "position I,J", after the slab's name when there are
 * several. */
static const char *energy_place(const cap_manifest *m, const cap_report *r, char *out, size_t size)
{
    if (cap_manifest_plane_count(m) > 1)
        snprintf(out, size, "slab '%s' position %" PRIu32 ",%" PRIu32, cap_manifest_get_desc(m, r->energy_plane)->name,
                 r->energy_i, r->energy_j);
    else
        snprintf(out, size, "position %" PRIu32 ",%" PRIu32, r->energy_i, r->energy_j);
    return out;
}

/* Warnings: repaired images, unmerged bracket pixels, energy over budget. */
static void print_warnings(const cap_manifest *m, const cap_report *r)
{
    char place[128];
    for (size_t k = 0; k < r->repair_count; k++)
        warn_repair(&r->repairs[k]);
    if (r->unmerged > 0)
        fprintf(stderr,
                "ilf capture: warning: %" PRIu64 " bracket pixel%s clipped or noisy in every exposure (each taken "
                "from the exposure nearest mid-grey)\n", r->unmerged, r->unmerged == 1 ? " was" : "s were");
    if (r->energy_error > ENERGY_BUDGET)
        fprintf(stderr,
                "ilf capture: warning: energy differs by %.3f%% at %s (budget %.1f%%): the partition level n may be "
                "too coarse for the images\n",
                100.0 * r->energy_error, energy_place(m, r, place, sizeof place), 100.0 * ENERGY_BUDGET);
}

/* What was captured: "2x2 positions, 4 images, n 16 (1024 directions)", or for several planes
 * "3 planes, 12 positions, 12 images" (their grids and levels may differ). */
static void print_captured(const capture_options *o, const cap_manifest *m, const cap_report *r)
{
    const lfio_slab_desc *d = cap_manifest_get_desc(m, 0);
    size_t planes = cap_manifest_plane_count(m);
    printf("captured %s: ", o->manifest);
    if (planes == 1)
        printf("%" PRIu32 "x%" PRIu32 " position%s, ", d->nu, d->nv, r->positions == 1 ? "" : "s");
    else
        printf("%zu planes, %" PRIu64 " positions, ", planes, r->positions);
    printf("%" PRIu64 " image%s", r->images, r->images == 1 ? "" : "s");
    if (planes == 1)
        printf(", n %" PRIu32 " (%" PRIu64 " directions)", d->n, (uint64_t)4 * d->n * d->n);
    printf(", sub-pixels %" PRIu32 "..%" PRIu32 " per side\n", r->subdivision_min, r->subdivision_max);
}

static void print_summary(const capture_options *o, const cap_manifest *m, const cap_report *r)
{
    char size[32], place[128];
    print_captured(o, m, r);
    printf("energy: irradiance from the light field vs from the images differs by at most %.4f%% "
           "(%s: %.6g vs %.6g in green)\n",
           100.0 * r->energy_error, energy_place(m, r, place, sizeof place), r->energy_field[1], r->energy_image[1]);
    printf("repairs: %" PRIu64 " negative, %" PRIu64 " NaN, %" PRIu64 " infinite values; %" PRIu64
           " solid angle%s interpolated (image too coarse)\n",
           r->negative, r->nan, r->infinite, r->interpolated, r->interpolated == 1 ? "" : "s");
    size_t planes = cap_manifest_plane_count(m);
    printf("wrote %s: slab%s", o->output, planes == 1 ? "" : "s");
    for (size_t k = 0; k < planes; k++) {
        const lfio_slab_desc *d = cap_manifest_get_desc(m, k);
        if (planes == 1)
            printf(" '%s'", d->name);
        else
            printf("%s '%s' (%" PRIu32 "x%" PRIu32 ", n %" PRIu32 ")", k == 0 ? "" : ",", d->name, d->nu, d->nv, d->n);
    }
    printf(", %s\n", cli_format_bytes(cli_file_size(o->output), size, sizeof size));
}

/* ------------------------------------------------------------ main */

/* Runs the capture with a progress bar unless quiet. @return an exit code. */
static int run_capture(const capture_options *o, const cap_manifest *m, lfio_lightfield **lf, cap_report *r)
{
    uint64_t positions = 0;
    for (size_t k = 0; k < cap_manifest_plane_count(m); k++)
        positions += (uint64_t)cap_manifest_get_desc(m, k)->nu * cap_manifest_get_desc(m, k)->nv;
    cli_progress bar;
    cap_capture_options co = {o->threads, NULL, NULL};
    unsigned threads = ilf_thread_count(o->threads);
    uint64_t images = cap_manifest_image_count(m);
    /* the bar counts positions, each one probe image or one bracket of them */
    cli_set_quiet(o->quiet);
    size_t planes = cap_manifest_plane_count(m);
    const lfio_slab_desc *d = cap_manifest_get_desc(m, 0);
    if (planes == 1)
        cli_settings("capture", "%" PRIu32 "x%" PRIu32 " positions, n %" PRIu32 " (%" PRIu64 " directions), %" PRIu64
                     " image%s, %u thread%s", d->nu, d->nv, d->n, 4 * (uint64_t)d->n * d->n, images,
                     images == 1 ? "" : "s", threads, threads == 1 ? "" : "s");
    else
        cli_settings("capture", "%zu planes, %" PRIu64 " positions, %" PRIu64 " image%s, %u thread%s", planes,
                     positions, images, images == 1 ? "" : "s", threads, threads == 1 ? "" : "s");
    if (!o->quiet) {
        cli_progress_start(&bar, "capture", positions);
        co.progress = ilf_capture_progress;
        co.progress_user = &bar;
    }
    cap_status st = cap_capture_run(m, &co, lf, r);
    if (!o->quiet)
        cli_progress_finish(&bar);
    return st == CAP_OK ? ILF_EXIT_OK : ilf_capture_failure("capture", st);
}

int ilf_cmd_capture(int argc, char **argv)
{
    capture_options o = {0};
    int code = parse_arguments(&o, argc, argv);
    if (code >= 0)
        return code;
    if ((code = cli_output_check("capture", o.output)) != ILF_EXIT_OK)
        return code;
    cli_output_watch(o.output);
    cap_manifest *m = NULL;
    cap_status st = cap_manifest_load(o.manifest, &m);
    if (st != CAP_OK)
        return ilf_capture_failure("capture", st);
    lfio_lightfield *lf = NULL;
    cap_report report;
    code = run_capture(&o, m, &lf, &report);
    if (code == ILF_EXIT_OK) {
        print_warnings(m, &report);
        lfio_status ls = lfio_lightfield_set_creator(lf, CAPTURE_CREATOR);
        if (ls == LFIO_OK)
            ls = lfio_lightfield_write(lf, o.output);
        code = ls == LFIO_OK ? ILF_EXIT_OK : cli_lfio_failure("capture", ls, CLI_OUTPUT, o.output);
    }
    if (code == ILF_EXIT_OK && !o.quiet)
        print_summary(&o, m, &report);
    cap_report_free(&report);
    lfio_lightfield_destroy(lf);
    cap_manifest_destroy(m);
    return code;
}
