/*
 * cmd_slice.c - `ilf slice`: one position's directions, or one direction's
 * positions, of a slab as an EXR or PNG image, read with lfio_reader's
 * partial reads so the slab is never loaded whole.
 *
 *   --position I,J --layout unfold   octahedral unfolding: pixel (a, b) of
 *       [-1,1]^2 with |a|+|b| <= 1 shows slab-frame direction
 *       (a, b, 1-|a|-|b|). Every partition triangle maps to a flat triangle,
 *       so the image shows the cells exactly (nearest, piecewise constant).
 *       Pixels outside the diamond have alpha 0.
 *   --position I,J --layout latlong  the hemisphere in longitude (phi from e1
 *       around e3) and colatitude (theta from the pole at the top row),
 *       interpolated with lfio_part_interp().
 *   --position I,J --envmap  (or --layout envmap) the full sphere of
 *       directions from which light arrives at the position, in the world
 *       frame, as an equirectangular (latlong) environment map with +Z up
 *       as Blender reads one: row 0 is +Z, the middle row the horizon, the
 *       centre column looks along +X and columns to its right turn toward
 *       -Y (longitude phi = atan2(y, x) = pi (1 - 2 (x + 0.5) / width)).
 *       Pixel direction d shows the radiance travelling along -d; the slab
 *       stores only light travelling to its front (-d.e3 >= 0), so the
 *       other hemisphere is black.
 *   --direction ID | --toward X,Y,Z  the nu x nv image of one direction,
 *       image up = +v, column 0 = lowest u.
 *
 * Invariants: EXR receives the raw float radiance; PNG receives the same
 * pixels scaled by one factor (2^EV, 1/W, or 1 / the 99th percentile of the
 * bright pixels' max(r,g,b)), sRGB-encoded and clamped; alpha is never
 * scaled (tonemap.c). Every check of the options happens before the file is opened.
 * A --toward slice that comes out all black is told of with a warning
 * giving the direction's elevation above the slab's plane.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "image/image.h"
#include "tonemap.h"
#include "lfio/lightfield.h"
#include "lfio/partition.h"
#include "cli_limits.h"
#include "ilf/limits.h"

#define SLICE_MAX_SIZE ILF_SLICE_MAX_SIDE

typedef enum slice_mode { SLICE_NONE, SLICE_POSITION, SLICE_DIRECTION, SLICE_TOWARD } slice_mode;
typedef enum slice_layout { LAYOUT_UNFOLD, LAYOUT_LATLONG, LAYOUT_ENVMAP } slice_layout;

typedef struct slice_options {
    const char *path;
    const char *output;
    const char *slab;
    slice_mode mode;
    int mode_count;        /* how many of --position, --direction, --toward were given */
    uint32_t position[2];
    uint64_t direction;
    double toward[3];
    slice_layout layout;
    int layout_given;
    uint32_t size;
    int size_given;
    tone_fixed tone; /* --exposure or --scale, for PNG */
} slice_options;

/* Pixels [y][x][channel], row 0 at the top. */
typedef struct slice_image {
    int width, height, channels;
    float *pixels;
} slice_image;

enum slice_option_id {
    OPT_OUTPUT, OPT_SLAB, OPT_POSITION, OPT_LAYOUT, OPT_ENVMAP, OPT_DIRECTION, OPT_TOWARD, OPT_SIZE, OPT_EXPOSURE,
    OPT_SCALE
};

static const cli_option slice_options_table[] = {
    {"output", 'o', "OUT.exr|OUT.hdr|OUT.png", "image to write (required): EXR or HDR raw float, PNG tone-mapped"},
    {"slab", 0, "NAME|INDEX", "slab to slice (default 0)"},
    {"position", 0, "I,J", "image of the directions at position (I,J)"},
    {"layout", 0, "LAYOUT", "for --position: unfold (default, octahedral), latlong or envmap"},
    {"envmap", 0, NULL, "for --position: a full-sphere world latlong environment map, +Z up (--layout envmap)"},
    {"direction", 0, "ID", "image of the positions for hemisphere direction ID (0 .. 4n^2-1)"},
    {"toward", 0, "X,Y,Z", "image of the positions for the direction containing world direction X,Y,Z"},
    {"size", 0, "PX", "for --position: PX x PX (unfold) or 2PX x PX (latlong, envmap), default 512"},
    {"exposure", 0, "EV", "PNG scale 2^EV (default: 1 / 99th percentile of max(r,g,b) > 0)"},
    {"scale", 0, "W", "PNG scale 1/W: radiance W (W sr^-1 m^-2) shows as white, the same in every image"},
};

static const cli_usage slice_usage = {
    "slice",
    "FILE [--slab NAME|INDEX] (--position I,J [--layout unfold|latlong|envmap] [--size PX]\n"
    "                 | --direction ID | --toward X,Y,Z) -o OUT.exr|OUT.hdr|OUT.png\n"
    "                 [--exposure EV | --scale W]",
    "Writes one slice of a slab as an image, reading only that slice from the file.\n"
    "--position: the directions of one position. 'unfold' maps pixel (a,b), |a|+|b| <= 1,\n"
    "to slab-frame direction (a, b, 1-|a|-|b|), showing each solid angle as a flat\n"
    "triangle (outside the diamond: alpha 0); 'latlong' shows the hemisphere with phi\n"
    "from e1 around e3 across and theta from the pole (top row) down, interpolated;\n"
    "'envmap' (--envmap) is an HDRI of the light arriving at the position: the world's\n"
    "full sphere, equirectangular, +Z up (row 0), the centre column toward +X, as\n"
    "Blender's Environment Texture reads it; the hemisphere behind the slab is black.\n"
    "--direction/--toward: the nu x nv image of one direction (up = +v, left = low u);\n"
    "--toward takes the world direction the light travels in, which must face the\n"
    "slab's front (w.e3 >= 0).",
    "ilf slice data/beams_lightfield.h5 --position 8,8 -o position.png\n"
    "ilf slice data/beams_lightfield.h5 --position 8,8 --layout latlong --size 256 -o position.exr\n"
    "ilf slice data/beams_lightfield.h5 --position 8,8 --envmap -o env.hdr\n"
    "ilf slice data/beams_lightfield.h5 --toward 0,0,1 --exposure -2 -o straight-up.png",
};

/* ------------------------------------------------------------ options */

static int parse_layout(const cli_parser *p, const char *text, slice_layout *layout)
{
    if (strcmp(text, "unfold") == 0)
        *layout = LAYOUT_UNFOLD;
    else if (strcmp(text, "latlong") == 0)
        *layout = LAYOUT_LATLONG;
    else if (strcmp(text, "envmap") == 0)
        *layout = LAYOUT_ENVMAP;
    else
        return cli_bad_value(p, text, "expected unfold, latlong or envmap"), 0;
    return 1;
}

static int parse_direction_id(const cli_parser *p, const char *text, uint64_t *id)
{
    uint32_t value;
    /* The upper bound depends on the file's n; it is checked once the file is open. */
    if (!cli_value_u32(p, text, 0, UINT32_MAX, &value))
        return 0;
    *id = value;
    return 1;
}

static int parse_toward(const cli_parser *p, const char *text, double w[3])
{
    if (!cli_value_doubles(p, text, w, 3))
        return 0;
    if (w[0] == 0.0 && w[1] == 0.0 && w[2] == 0.0)
        return cli_bad_value(p, text, "the direction must be nonzero"), 0;
    return 1;
}

static void count_mode(slice_options *o, slice_mode mode)
{
    o->mode = mode;
    o->mode_count++;
}

/* Applies one option. @return 1, or 0 after reporting. */
static int apply_option(const cli_parser *p, int opt, const char *value, void *ctx)
{
    slice_options *o = ctx;
    switch (opt) {
    case OPT_OUTPUT: o->output = value; return 1;
    case OPT_SLAB: o->slab = value; return 1;
    case OPT_POSITION: count_mode(o, SLICE_POSITION); return cli_value_u32_pair(p, value, ',', 0, UINT32_MAX, o->position);
    case OPT_DIRECTION: count_mode(o, SLICE_DIRECTION); return parse_direction_id(p, value, &o->direction);
    case OPT_TOWARD: count_mode(o, SLICE_TOWARD); return parse_toward(p, value, o->toward);
    case OPT_LAYOUT: o->layout_given = 1; return parse_layout(p, value, &o->layout);
    case OPT_ENVMAP: o->layout_given = 1; o->layout = LAYOUT_ENVMAP; return 1;
    case OPT_SIZE: o->size_given = 1; return cli_value_u32(p, value, 1, SLICE_MAX_SIZE, &o->size);
    case OPT_EXPOSURE: return cli_value_tone(p, value, 1, &o->tone);
    case OPT_SCALE: return cli_value_tone(p, value, 0, &o->tone);
    default: return 0;
    }
}

/* Checks what single options cannot. @return 1, or 0 after reporting. */
static int check_combination(const slice_options *o)
{
    const char *problem = NULL;
    if (o->path == NULL)
        problem = "no file given (see 'ilf slice --help')";
    else if (o->mode_count != 1)
        problem = "give exactly one of --position, --direction and --toward";
    else if (o->output == NULL)
        problem = "-o OUT.exr|OUT.hdr|OUT.png is required";
    else if (img_guess_format(o->output) == IMG_FORMAT_UNKNOWN)
        problem = "the output must end in .exr, .hdr or .png";
    else if (o->mode != SLICE_POSITION && (o->layout_given || o->size_given))
        problem = "--layout, --envmap and --size apply to --position only";
    if (problem != NULL) {
        cli_error("slice", "%s", problem);
        return 0;
    }
    return 1;
}

static int parse_arguments(slice_options *o, int argc, char **argv)
{
    int code = cli_parse(&slice_usage, slice_options_table,
                         sizeof slice_options_table / sizeof slice_options_table[0], argc, argv, &o->path,
                         apply_option, o);
    if (code != -1)
        return code;
    return check_combination(o) ? -1 : ILF_EXIT_USAGE;
}

/* ------------------------------------------------------------ images */

static int image_alloc(slice_image *img, int width, int height, int channels)
{
    img->width = width;
    img->height = height;
    img->channels = channels;
    img->pixels = calloc((size_t)width * (size_t)height * (size_t)channels, sizeof(float));
    if (img->pixels == NULL)
        cli_error("slice", "out of memory for a %dx%d image", width, height);
    return img->pixels != NULL;
}

/* Octahedral unfolding of one position's radiance ([dir][rgb]). */
static void render_unfold(const float *radiance, uint32_t n, slice_image *img)
{
    uint64_t ndir = lfio_part_hemi_count(n);
    for (int y = 0; y < img->height; y++) {
        for (int x = 0; x < img->width; x++) {
            double a = -1.0 + 2.0 * (x + 0.5) / img->width;
            double b = 1.0 - 2.0 * (y + 0.5) / img->height; /* top row is +e2 */
            double d[3] = {a, b, 1.0 - fabs(a) - fabs(b)};
            uint64_t id;
            if (d[2] < 0.0 || !lfio_part_id(n, d, &id) || id >= ndir)
                continue; /* outside the diamond: stays transparent black */
            float *px = img->pixels + ((size_t)y * img->width + x) * 4;
            memcpy(px, radiance + id * 3, 3 * sizeof(float));
            px[3] = 1.0f;
        }
    }
}

/* Interpolated radiance in slab-frame direction d; ids behind the slab use the containing id. */
static void interpolate(const float *radiance, uint32_t n, const double d[3], float rgb[3])
{
    uint64_t ndir = lfio_part_hemi_count(n), ids[4];
    double w[4], sum[3] = {0, 0, 0};
    if (!lfio_part_interp(n, d, ids, w)) {
        rgb[0] = rgb[1] = rgb[2] = 0.0f;
        return;
    }
    for (int k = 0; k < 4; k++) {
        uint64_t id = ids[k] < ndir ? ids[k] : ids[0];
        for (int c = 0; c < 3; c++)
            sum[c] += w[k] * radiance[id * 3 + c];
    }
    for (int c = 0; c < 3; c++)
        rgb[c] = (float)sum[c];
}

/* Latitude-longitude view of the front hemisphere of one position. */
static void render_latlong(const float *radiance, uint32_t n, slice_image *img)
{
    for (int y = 0; y < img->height; y++) {
        double theta = 0.5 * ILF_PI * (y + 0.5) / img->height;
        for (int x = 0; x < img->width; x++) {
            double phi = 2.0 * ILF_PI * (x + 0.5) / img->width;
            double d[3] = {sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta)};
            interpolate(radiance, n, d, img->pixels + ((size_t)y * img->width + x) * 3);
        }
    }
}

/* Makes a one-position slab with desc's geometry: lfio's own world-to-slab conversion, so that the frame's
 * definition has no second copy here (the reader gives only the description). @return an exit code. */
static int slab_frame(const lfio_slab_desc *desc, const char *path, lfio_slab **frame)
{
    lfio_slab_desc tiny = *desc;
    tiny.nu = tiny.nv = tiny.n = 1;
    lfio_status st = lfio_slab_new(&tiny, frame);
    return st == LFIO_OK ? ILF_EXIT_OK : cli_lfio_failure("slice", st, CLI_INPUT, path);
}

/* The full-sphere environment map of one position (see the file's comment for the convention). */
static void render_envmap(const float *radiance, uint32_t n, const lfio_slab *frame, slice_image *img)
{
    for (int y = 0; y < img->height; y++) {
        double elevation = 0.5 * ILF_PI - ILF_PI * (y + 0.5) / img->height;
        for (int x = 0; x < img->width; x++) {
            double phi = ILF_PI * (1.0 - 2.0 * (x + 0.5) / img->width);
            /* the light seen looking along d travels along -d */
            double w[3] = {-cos(elevation) * cos(phi), -cos(elevation) * sin(phi), -sin(elevation)}, local[3];
            lfio_slab_to_local(frame, w, local);
            float *px = img->pixels + ((size_t)y * img->width + x) * 3;
            if (local[2] >= 0.0)
                interpolate(radiance, n, local, px);
        }
    }
}

/* Reads one position and renders it in the chosen layout. @return an exit code. */
static int slice_position(lfio_reader *r, size_t k, const slice_options *o, slice_image *img)
{
    const lfio_slab_desc *d = lfio_reader_slab_desc(r, k);
    uint32_t i = o->position[0], j = o->position[1];
    if (i >= d->nu || j >= d->nv) {
        cli_error("slice", "%s: slab '%s' has %ux%u positions; --position %u,%u is outside", o->path, d->name,
                  (unsigned)d->nu, (unsigned)d->nv, (unsigned)i, (unsigned)j);
        return ILF_EXIT_USAGE;
    }
    float *radiance = malloc((size_t)lfio_part_hemi_count(d->n) * 3 * sizeof(float));
    if (radiance == NULL) {
        cli_error("slice", "out of memory for %u directions", (unsigned)lfio_part_hemi_count(d->n));
        return ILF_EXIT_FAILED;
    }
    int code = ILF_EXIT_OK;
    lfio_status st = lfio_reader_read_position(r, k, i, j, radiance);
    int px = (int)(o->size_given ? o->size : 512);
    int unfold = o->layout == LAYOUT_UNFOLD; /* unfold: PX x PX RGBA; latlong, envmap: 2PX x PX RGB */
    lfio_slab *frame = NULL;
    if (st != LFIO_OK)
        code = cli_lfio_failure("slice", st, CLI_INPUT, o->path);
    else if (o->layout == LAYOUT_ENVMAP)
        code = slab_frame(d, o->path, &frame);
    if (code == ILF_EXIT_OK && !image_alloc(img, unfold ? px : 2 * px, px, unfold ? 4 : 3))
        code = ILF_EXIT_FAILED;
    if (code != ILF_EXIT_OK)
        ;
    else if (unfold)
        render_unfold(radiance, d->n, img);
    else if (o->layout == LAYOUT_LATLONG)
        render_latlong(radiance, d->n, img);
    else
        render_envmap(radiance, d->n, frame, img);
    lfio_slab_destroy(frame);
    free(radiance);
    return code;
}

/* Finds the hemisphere id containing world direction w (slab_frame() converts it). */
static int direction_toward(const lfio_slab_desc *desc, const slice_options *o, uint64_t *id)
{
    lfio_slab *frame = NULL;
    int code = slab_frame(desc, o->path, &frame);
    if (code != ILF_EXIT_OK)
        return code;
    double local[3];
    lfio_slab_to_local(frame, o->toward, local);
    lfio_slab_destroy(frame);
    if (local[2] < 0.0) {
        cli_error("slice", "--toward %g,%g,%g points behind slab '%s' (w.e3 = %g < 0); only its front is stored",
                  o->toward[0], o->toward[1], o->toward[2], desc->name, local[2]);
        return ILF_EXIT_USAGE;
    }
    if (!lfio_part_id(desc->n, local, id)) {
        cli_error("slice", "--toward %g,%g,%g is not a usable direction", o->toward[0], o->toward[1], o->toward[2]);
        return ILF_EXIT_USAGE;
    }
    return ILF_EXIT_OK;
}

/* Warns when the --toward slice img (nu x nv, rgb) is all black: a direction this close to the slab's plane
 * usually carries nothing, and a black image alone does not say why. */
static void warn_black_toward(const slice_options *o, const lfio_slab_desc *d, const slice_image *img)
{
    size_t count = (size_t)img->width * img->height * 3;
    for (size_t k = 0; k < count; k++)
        if (img->pixels[k] != 0.0f)
            return;
    double len = sqrt(o->toward[0] * o->toward[0] + o->toward[1] * o->toward[1] + o->toward[2] * o->toward[2]);
    double e3[3] = {d->u[1] * d->v[2] - d->u[2] * d->v[1], d->u[2] * d->v[0] - d->u[0] * d->v[2],
                    d->u[0] * d->v[1] - d->u[1] * d->v[0]};
    double e3len = sqrt(e3[0] * e3[0] + e3[1] * e3[1] + e3[2] * e3[2]);
    double cosine = (o->toward[0] * e3[0] + o->toward[1] * e3[1] + o->toward[2] * e3[2]) / (len * e3len);
    double elevation = 90.0 - acos(fmin(1.0, fmax(-1.0, cosine))) * 180.0 / ILF_PI;
    cli_warn("--toward %g,%g,%g is %.1f degrees above the plane of slab '%s'%s: every position of the slice is black",
             o->toward[0], o->toward[1], o->toward[2], elevation, d->name, elevation < 10.0 ? " (grazing)" : "");
}

/* Reads one direction and flips it so that +v is up. @return an exit code. */
static int slice_direction(lfio_reader *r, size_t k, const slice_options *o, slice_image *img)
{
    const lfio_slab_desc *d = lfio_reader_slab_desc(r, k);
    uint64_t ndir = lfio_part_hemi_count(d->n), id = o->direction;
    int code = o->mode == SLICE_TOWARD ? direction_toward(d, o, &id) : ILF_EXIT_OK;
    if (code != ILF_EXIT_OK)
        return code;
    if (id >= ndir) {
        cli_error("slice", "%s: slab '%s' has directions 0 to %llu; --direction %llu is outside", o->path, d->name,
                  (unsigned long long)ndir - 1, (unsigned long long)id);
        return ILF_EXIT_USAGE;
    }
    if (!image_alloc(img, (int)d->nu, (int)d->nv, 3))
        return ILF_EXIT_FAILED;
    lfio_status st = lfio_reader_read_direction(r, k, id, img->pixels);
    if (st != LFIO_OK)
        return cli_lfio_failure("slice", st, CLI_INPUT, o->path);
    /* lfio stores row j = 0 at the lowest v; images put row 0 at the top. */
    size_t row = (size_t)d->nu * 3;
    float *tmp = malloc(row * sizeof(float));
    if (tmp == NULL) {
        cli_error("slice", "out of memory");
        return ILF_EXIT_FAILED;
    }
    for (uint32_t top = 0, bottom = d->nv - 1; top < bottom; top++, bottom--) {
        memcpy(tmp, img->pixels + top * row, row * sizeof(float));
        memcpy(img->pixels + top * row, img->pixels + bottom * row, row * sizeof(float));
        memcpy(img->pixels + bottom * row, tmp, row * sizeof(float));
    }
    free(tmp);
    if (o->mode == SLICE_TOWARD)
        warn_black_toward(o, d, img);
    return ILF_EXIT_OK;
}

/* ------------------------------------------------------------ main */

static int write_image(const slice_image *img, const slice_options *o)
{
    char err[512];
    img_status st = img_write(o->output, img->width, img->height, img->channels, img->pixels, err, sizeof err);
    if (st == IMG_OK)
        return ILF_EXIT_OK;
    cli_error("slice", "%s", err);
    return st == IMG_ERR_ARG ? ILF_EXIT_USAGE : ILF_EXIT_FAILED;
}

static void describe_result(const slice_image *img, const slice_options *o, const char *slab, double scale)
{
    printf("wrote %s: %dx%d, ", o->output, img->width, img->height);
    if (o->mode == SLICE_POSITION)
        printf("%s of position (%u,%u)",
               o->layout == LAYOUT_UNFOLD    ? "unfold view"
               : o->layout == LAYOUT_LATLONG ? "latlong view"
                                             : "environment map (equirectangular, +Z up)",
               (unsigned)o->position[0], (unsigned)o->position[1]);
    else
        printf("positions for one direction");
    printf(" of slab '%s'; ", slab);
    char how[96];
    if (img_guess_format(o->output) != IMG_FORMAT_PNG)
        printf("raw radiance (scale 1)%s\n",
               o->tone.kind != TONE_AUTO ? ", --exposure and --scale apply to PNG only" : "");
    else
        printf("scale %.6g (%s)\n", scale, tone_fixed_describe(&o->tone, "auto: 1/99th percentile", how, sizeof how));
}

static int slice_file(lfio_reader *r, const slice_options *o)
{
    size_t k;
    if (!cli_select_slab("slice", o->path, r, o->slab, &k))
        return ILF_EXIT_USAGE;
    slice_image img = {0, 0, 0, NULL};
    int code = o->mode == SLICE_POSITION ? slice_position(r, k, o, &img) : slice_direction(r, k, o, &img);
    double scale = 1.0;
    if (code == ILF_EXIT_OK && img_guess_format(o->output) == IMG_FORMAT_PNG) {
        const size_t count = (size_t)img.width * img.height;
        if (tone_fixed_scale(&o->tone, &scale))
            ;
        else if (!tone_percentile_scale(img.pixels, count, img.channels, TONE_PEAK, 0.99, 1.0, &scale)) {
            cli_error("slice", "out of memory for the exposure of a %dx%d image", img.width, img.height);
            code = ILF_EXIT_FAILED;
        }
        if (code == ILF_EXIT_OK)
            tone_apply(img.pixels, count, img.channels, scale);
    }
    if (code == ILF_EXIT_OK)
        code = write_image(&img, o);
    if (code == ILF_EXIT_OK)
        describe_result(&img, o, lfio_reader_slab_desc(r, k)->name, scale);
    free(img.pixels);
    return code;
}

int ilf_cmd_slice(int argc, char **argv)
{
    slice_options o = {0};
    o.layout = LAYOUT_UNFOLD;
    int code = parse_arguments(&o, argc, argv);
    if (code >= 0)
        return code;
    lfio_reader *r = NULL;
    lfio_status st = lfio_reader_open(o.path, &r);
    if (st != LFIO_OK)
        return cli_lfio_failure("slice", st, CLI_INPUT, o.path);
    cli_output_watch(o.output);
    /* Checked after the input, so that bad input is reported as such first. */
    code = cli_output_check("slice", o.output);
    if (code == ILF_EXIT_OK)
        code = slice_file(r, &o);
    lfio_reader_close(r);
    return code;
}
