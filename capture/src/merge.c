/*
 * merge.c - reading one capture position's images into a single linear
 * HDR image (cap__load_position in probe.h): read, check sizes, repair bad
 * values, decode the colour space, scale by exposure and merge a bracket
 * with hat weights. The policies are those of capture/capture.h.
 *
 * Invariants: at most one file image is held at a time, next to the
 * bracket accumulators (8 floats per pixel), so memory is bounded by one
 * position's images; repairs are order-independent (replacement values are
 * computed from the image as read, before any replacement is written);
 * every value leaving here is finite and >= 0.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ilf/limits.h"
#include "image/image.h"
#include "internal.h"
#include "probe.h"

/* Hat weight limits on the stored (encoded) value: below NOISE is noise, above CLIP is clipped. */
#define HAT_NOISE 0.02f
#define HAT_CLIP 0.98f

/* Bracket accumulators, per pixel: weighted sum, weight, and the fallback (value closest to mid-grey). */
typedef struct bracket_acc {
    float *sum;      /* [pixels][3] */
    float *weight;   /* [pixels] */
    float *fallback; /* [pixels][3] */
    float *distance; /* [pixels]: |z - 0.5| of the fallback, starts above any possible value */
} bracket_acc;

/* One image as the merge sees it: colour channels in use and the conversion to radiance. */
typedef struct source {
    const img_image *img;
    int colours;    /* 1 (grey) or 3 */
    int srgb;       /* decode the sRGB curve */
    float factor;   /* scale / exposure */
} source;

/* ------------------------------------------------------------ repair */

/* Mean of the finite values, negatives counted as 0, among the 8 neighbours of (x, y) in channel c. */
static float neighbour_mean(const img_image *img, int x, int y, int c)
{
    double sum = 0.0;
    int count = 0;
    for (int dy = -1; dy <= 1; dy++)
        for (int dx = -1; dx <= 1; dx++) {
            int nx = x + dx, ny = y + dy;
            if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= img->width || ny >= img->height)
                continue;
            float v = img->pixels[((size_t)ny * img->width + nx) * img->channels + c];
            if (isfinite(v)) {
                sum += v > 0.0f ? v : 0.0f;
                count++;
            }
        }
    return count > 0 ? (float)(sum / count) : 0.0f;
}

/* Counts NaN and infinite values in the colour channels, noting their indices in where (if not NULL). */
static uint64_t scan_bad(const img_image *img, int colours, size_t *where, uint64_t *nan, uint64_t *inf)
{
    const size_t pixels = (size_t)img->width * img->height;
    uint64_t bad = 0;
    for (size_t p = 0; p < pixels; p++)
        for (int c = 0; c < colours; c++) {
            float v = img->pixels[p * img->channels + c];
            if (isfinite(v))
                continue;
            *(isnan(v) ? nan : inf) += 1;
            if (where != NULL)
                where[bad] = p * img->channels + c;
            bad++;
        }
    return bad;
}

/* Sets negative values to 0, counting them and the lowest. */
static void clamp_negative(img_image *img, int colours, cap_repair *rep)
{
    const size_t pixels = (size_t)img->width * img->height;
    for (size_t p = 0; p < pixels; p++)
        for (int c = 0; c < colours; c++) {
            float *v = &img->pixels[p * img->channels + c];
            if (*v < 0.0f) {
                rep->negative++;
                rep->lowest = fminf(rep->lowest, *v);
                *v = 0.0f;
            }
        }
}

/* Replaces non-finite values by their neighbours' mean (computed before any is written), then negatives by 0. */
static cap_status repair(img_image *img, int colours, cap_repair *rep)
{
    uint64_t nan = 0, inf = 0;
    uint64_t bad = scan_bad(img, colours, NULL, &nan, &inf);
    if (bad > 0) {
        size_t *where = malloc(bad * sizeof *where);
        float *value = malloc(bad * sizeof *value);
        if (where == NULL || value == NULL) {
            free(where);
            free(value);
            return cap__fail(CAP_ERR_NOMEM, "%s: out of memory for repairs", rep->file);
        }
        scan_bad(img, colours, where, &rep->nan, &rep->infinite);
        for (uint64_t k = 0; k < bad; k++) {
            size_t p = where[k] / img->channels;
            value[k] = neighbour_mean(img, (int)(p % img->width), (int)(p / img->width),
                                      (int)(where[k] % img->channels));
        }
        for (uint64_t k = 0; k < bad; k++)
            img->pixels[where[k]] = value[k];
        free(where);
        free(value);
    }
    clamp_negative(img, colours, rep);
    return CAP_OK;
}

/* ------------------------------------------------------------ values */

/* Pixel p's radiance into rgb and its largest stored (encoded) colour value into *z. */
static void pixel_value(const source *s, size_t p, float rgb[3], float *z)
{
    const float *v = &s->img->pixels[p * s->img->channels];
    float top = 0.0f;
    for (int c = 0; c < 3; c++) {
        float e = v[s->colours == 3 ? c : 0];
        top = fmaxf(top, e);
        rgb[c] = (s->srgb ? img_srgb_decode(e) : e) * s->factor;
    }
    *z = top;
}

/* Hat weight of a stored value: 0 at and beyond the noise and clip limits, 1 at 0.5. */
static float hat(float z)
{
    if (z <= HAT_NOISE || z >= HAT_CLIP)
        return 0.0f;
    return z < 0.5f ? (z - HAT_NOISE) / (0.5f - HAT_NOISE) : (HAT_CLIP - z) / (HAT_CLIP - 0.5f);
}

static void store_single(const source *s, float *out)
{
    const size_t pixels = (size_t)s->img->width * s->img->height;
    for (size_t p = 0; p < pixels; p++) {
        float z;
        pixel_value(s, p, &out[3 * p], &z);
    }
}

static void accumulate(const source *s, bracket_acc *acc)
{
    const size_t pixels = (size_t)s->img->width * s->img->height;
    for (size_t p = 0; p < pixels; p++) {
        float rgb[3], z;
        pixel_value(s, p, rgb, &z);
        float w = hat(z), dist = fabsf(z - 0.5f);
        for (int c = 0; c < 3; c++)
            acc->sum[3 * p + c] += w * rgb[c];
        acc->weight[p] += w;
        if (dist < acc->distance[p]) {
            acc->distance[p] = dist;
            memcpy(&acc->fallback[3 * p], rgb, sizeof rgb);
        }
    }
}

/* Writes the merged bracket into out ([pixels][3]); counts pixels without a usable exposure. */
static uint64_t finish_bracket(const bracket_acc *acc, size_t pixels, float *out)
{
    uint64_t unmerged = 0;
    for (size_t p = 0; p < pixels; p++) {
        if (acc->weight[p] > 0.0f) {
            for (int c = 0; c < 3; c++)
                out[3 * p + c] = acc->sum[3 * p + c] / acc->weight[p];
        } else {
            memcpy(&out[3 * p], &acc->fallback[3 * p], 3 * sizeof *out);
            unmerged++;
        }
    }
    return unmerged;
}

static void acc_free(bracket_acc *acc)
{
    free(acc->sum);
    free(acc->weight);
    free(acc->fallback);
    free(acc->distance);
    memset(acc, 0, sizeof *acc);
}

static cap_status acc_alloc(bracket_acc *acc, size_t pixels)
{
    acc->sum = calloc(3 * pixels, sizeof *acc->sum);
    acc->weight = calloc(pixels, sizeof *acc->weight);
    acc->fallback = calloc(3 * pixels, sizeof *acc->fallback);
    acc->distance = malloc(pixels * sizeof *acc->distance);
    if (acc->sum == NULL || acc->weight == NULL || acc->fallback == NULL || acc->distance == NULL) {
        acc_free(acc);
        return cap__fail(CAP_ERR_NOMEM, "out of memory for a bracket of %zu pixels", pixels);
    }
    for (size_t p = 0; p < pixels; p++)
        acc->distance[p] = INFINITY;
    return CAP_OK;
}

/* ------------------------------------------------------------ reading */

cap_status cap__from_image(img_status s)
{
    switch (s) {
    case IMG_OK:
        return CAP_OK;
    case IMG_ERR_ARG:
        return CAP_ERR_ARG;
    case IMG_ERR_INPUT:
        return CAP_ERR_INPUT;
    case IMG_ERR_OUTPUT:
        return CAP_ERR_OUTPUT;
    case IMG_ERR_NOMEM:
        return CAP_ERR_NOMEM;
    }
    return CAP_ERR_INPUT;
}

/* Reads image k of entry e and checks its size. */
static cap_status read_image(const cap_manifest *m, const cap__entry *e, uint32_t k, const cap__hdr *first,
                             img_image *img)
{
    char msg[ILF_MESSAGE_BYTES];
    cap_status st = cap__from_image(img_read(e->files[k], img, msg, sizeof msg));
    if (st != CAP_OK) {
        cap__fail_text(st, msg);
        return cap__fail_prefix(st, "%s: %s", m->path, e->element);
    }
    const char *why = cap_projection_check_size(e->projection, img->width, img->height);
    if (why != NULL)
        st = cap__fail(CAP_ERR_INPUT, "%s: %s: %s: %dx%d: %s", m->path, e->element, e->files[k], img->width,
                       img->height, why);
    else if (k > 0 && (img->width != first->width || img->height != first->height))
        st = cap__fail(CAP_ERR_INPUT, "%s: %s: %s is %dx%d but %s is %dx%d: a bracket's images must have one size",
                       m->path, e->element, e->files[k], img->width, img->height, e->files[0], first->width,
                       first->height);
    if (st != CAP_OK)
        img_free(img);
    return st;
}

/* Describes how image k of e turns into radiance. */
static source make_source(const cap__entry *e, uint32_t k, const img_image *img)
{
    source s;
    s.img = img;
    s.colours = img->channels >= 3 ? 3 : 1;
    s.srgb = e->colour == CAP_COLOUR_SRGB || (e->colour == CAP_COLOUR_AUTO && img->integer);
    s.factor = (float)(e->scale / e->exposures[k]);
    return s;
}

/* Reads, repairs and folds image k into out (single) or acc (bracket). */
static cap_status load_one(const cap_manifest *m, const cap__entry *e, uint32_t k, cap__hdr *out, bracket_acc *acc,
                           cap_repair *rep)
{
    img_image img;
    cap_status st = read_image(m, e, k, out, &img);
    if (st != CAP_OK)
        return st;
    size_t pixels = (size_t)img.width * img.height;
    if (k == 0) {
        out->width = img.width;
        out->height = img.height;
        out->rgb = malloc(3 * pixels * sizeof *out->rgb);
        if (out->rgb == NULL || (e->bracket && acc_alloc(acc, pixels) != CAP_OK))
            st = cap__fail(CAP_ERR_NOMEM, "%s: %s: out of memory for %s", m->path, e->element, e->files[k]);
    }
    source s = make_source(e, k, &img);
    if (st == CAP_OK)
        st = repair(&img, s.colours, rep);
    if (st == CAP_OK && e->bracket)
        accumulate(&s, acc);
    else if (st == CAP_OK)
        store_single(&s, out->rgb);
    img_free(&img);
    return st;
}

cap_status cap__load_position(const cap_manifest *m, const cap__entry *e, uint32_t i, uint32_t j, cap__hdr *out,
                              cap_repair *repairs, uint64_t *unmerged)
{
    bracket_acc acc;
    memset(&acc, 0, sizeof acc);
    memset(out, 0, sizeof *out);
    cap_status st = CAP_OK;
    for (uint32_t k = 0; k < e->count; k++) {
        memset(&repairs[k], 0, sizeof repairs[k]);
        repairs[k].file = e->files[k];
        repairs[k].i = i;
        repairs[k].j = j;
    }
    for (uint32_t k = 0; st == CAP_OK && k < e->count; k++)
        st = load_one(m, e, k, out, &acc, &repairs[k]);
    if (st == CAP_OK && e->bracket)
        *unmerged += finish_bracket(&acc, (size_t)out->width * out->height, out->rgb);
    acc_free(&acc);
    if (st != CAP_OK) {
        free(out->rgb);
        memset(out, 0, sizeof *out);
    }
    return st;
}
