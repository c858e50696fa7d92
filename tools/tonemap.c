/*
 * tonemap.c - exposure from a percentile of the lit pixels, then the sRGB
 * transfer function of the image library (see tonemap.h), shared by
 * `ilf slice` and `ilf relight`.
 *
 * Invariants: the percentile is the nearest rank over pixels whose measure
 * is > 0, so a dark background never drags the exposure up; encoded values
 * are always in [0, 1]; alpha is left exactly as it was.
 */
#include "tonemap.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "image/image.h"

/* @return the k-th smallest of v[0 .. n) (k < n), reordering v: Hoare's
 * selection with a median-of-three pivot, linear on average where a sort of
 * a 640x480 view's values took 48 ms. */
static float select_kth(float *v, size_t n, size_t k)
{
    size_t lo = 0, hi = n - 1;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        float a = v[lo], b = v[mid], c = v[hi];
        float pivot = a < b ? (b < c ? b : (a < c ? c : a)) : (a < c ? a : (b < c ? c : b));
        size_t i = lo, j = hi;
        /* after the sweep, v[lo .. j] <= pivot <= v[i .. hi], with j < i */
        while (i <= j) {
            while (v[i] < pivot)
                i++;
            while (v[j] > pivot)
                j--;
            if (i <= j) {
                float t = v[i];
                v[i] = v[j];
                v[j] = t;
                i++;
                if (j == 0)
                    break;
                j--;
            }
        }
        if (k <= j)
            hi = j;
        else if (k >= i)
            lo = i;
        else
            return v[k]; /* between the parts: equal to the pivot */
    }
    return v[k];
}

/* @return the chosen measure of one RGB pixel. */
static float pixel_measure(const float *px, tone_measure measure)
{
    if (measure == TONE_LUMINANCE)
        return 0.2126f * px[0] + 0.7152f * px[1] + 0.0722f * px[2];
    float m = px[0] > px[1] ? px[0] : px[1];
    return m > px[2] ? m : px[2];
}

int tone_percentile_scale(const float *pixels, size_t count, int channels, tone_measure measure,
                          double percentile, double target, double *scale_out)
{
    float *values = malloc((count ? count : 1) * sizeof(float));
    size_t lit = 0;
    if (values == NULL)
        return 0;
    for (size_t k = 0; k < count; k++) {
        float m = pixel_measure(pixels + k * (size_t)channels, measure);
        if (m > 0.0f)
            values[lit++] = m;
    }
    double scale = 1.0;
    if (lit > 0) {
        size_t rank = (size_t)ceil(percentile * (double)lit);
        scale = target / select_kth(values, lit, rank > 0 ? (rank <= lit ? rank : lit) - 1 : 0);
    }
    free(values);
    *scale_out = scale;
    return 1;
}

void tone_apply(float *pixels, size_t count, int channels, double scale)
{
    for (size_t k = 0; k < count; k++) {
        float *px = pixels + k * (size_t)channels;
        for (int c = 0; c < 3; c++)
            px[c] = img_srgb_encode(scale * px[c]);
    }
}

int tone_fixed_scale(const tone_fixed *f, double *scale)
{
    if (f->kind == TONE_EXPOSURE)
        *scale = exp2(f->value);
    else if (f->kind == TONE_WHITE)
        *scale = 1.0 / f->value;
    return f->kind != TONE_AUTO;
}

const char *tone_fixed_describe(const tone_fixed *f, const char *auto_text, char *buf, size_t size)
{
    if (f->kind == TONE_EXPOSURE)
        snprintf(buf, size, "from --exposure %g", f->value);
    else if (f->kind == TONE_WHITE)
        snprintf(buf, size, "from --scale: %g shows as white", f->value);
    else
        snprintf(buf, size, "%s", auto_text);
    return buf;
}

double tone_lux(const double rgb[3])
{
    return TONE_LUMENS_PER_WATT * (0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]);
}
