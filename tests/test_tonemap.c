/*
 * test_tonemap.c - the exposure of `ilf`'s display images (tools/tonemap.h)
 * against a sort.
 *
 * What is checked:
 *   - tone_percentile_scale() picks the nearest-rank percentile of the lit
 *     pixels' measure, as a full sort of them gives it, for random images
 *     of 1 to 3000 pixels with many ties, dark pixels, both measures and
 *     percentiles from the smallest rank to the largest;
 *   - an image with no lit pixel keeps scale 1;
 *   - tone_apply() encodes colour channels and leaves alpha as it was;
 *   - a fixed scale (--exposure, --scale) is 2^EV or 1/W, and lux are 179 lm/W
 *     times the Rec.709 luminance;
 *   - false colour (tools/falsecolor.h): the top of the scale is the 99th
 *     percentile rounded up to 1, 2 or 5 x 10^k; colours run from the ramp's
 *     bottom to its top, magenta above, grey for no value; the image keeps the
 *     view's pixels and adds a legend with ink (its labels and ticks).
 * The last line is "N passed, M failed".
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "check.h"
#include "falsecolor.h"
#include "image/image.h"
#include "tonemap.h"

static uint64_t rng_state = 2026;

/* @return a uniform double in [0, 1) (splitmix64). */
static double rng_unit(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return (double)((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
}

static int ascending(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* @return the scale the nearest-rank percentile of a sort gives (the measure as tonemap.c computes it). */
static double sorted_scale(const float *px, size_t count, tone_measure measure, double percentile, double target)
{
    float *v = malloc((count + 1) * sizeof *v);
    size_t lit = 0;
    for (size_t k = 0; k < count; k++) {
        const float *p = px + 3 * k;
        float m = measure == TONE_LUMINANCE ? 0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2]
                                            : fmaxf(p[0], fmaxf(p[1], p[2]));
        if (m > 0.0f)
            v[lit++] = m;
    }
    double scale = 1.0;
    if (lit > 0) {
        qsort(v, lit, sizeof *v, ascending);
        size_t rank = (size_t)ceil(percentile * (double)lit);
        scale = target / v[rank > 0 ? (rank <= lit ? rank : lit) - 1 : 0];
    }
    free(v);
    return scale;
}

static void check_percentiles(void)
{
    long bad = 0, trials = 0;
    for (int t = 0; t < 400; t++) {
        size_t count = 1 + (size_t)(rng_unit() * (t < 40 ? 8 : 3000));
        int levels = 1 + (int)(rng_unit() * (t % 3 == 0 ? 4 : 1000)); /* few levels: many ties */
        float *px = malloc(count * 3 * sizeof *px);
        for (size_t k = 0; k < count * 3; k++)
            px[k] = rng_unit() < 0.2 ? 0.0f : (float)(1 + (int)(rng_unit() * levels)) / (float)levels;
        tone_measure measure = t % 2 ? TONE_LUMINANCE : TONE_PEAK;
        const double percentiles[] = {1e-9, 0.1, 0.5, 0.9, 0.999, 1.0};
        for (size_t q = 0; q < sizeof percentiles / sizeof *percentiles; q++) {
            double got = -1.0;
            CHECK(tone_percentile_scale(px, count, 3, measure, percentiles[q], 0.8, &got) == 1, "scale");
            bad += got != sorted_scale(px, count, measure, percentiles[q], 0.8);
            trials++;
        }
        free(px);
    }
    CHECK(bad == 0, "%ld of %ld percentiles differ from a sort's", bad, trials);
    float dark[4 * 3] = {0};
    double scale = -1.0;
    CHECK(tone_percentile_scale(dark, 4, 3, TONE_LUMINANCE, 0.9, 0.8, &scale) == 1 && scale == 1.0,
          "no lit pixel: scale 1 (got %g)", scale);
}

static void check_apply(void)
{
    float px[2 * 4] = {0.25f, 1.0f, 4.0f, 0.5f, 0.0f, 0.01f, 0.1f, 0.75f};
    tone_apply(px, 2, 4, 2.0);
    CHECK(px[0] == img_srgb_encode(0.5) && px[1] == 1.0f && px[2] == 1.0f && px[4] == 0.0f &&
              px[5] == img_srgb_encode(0.02) && px[6] == img_srgb_encode(0.2),
          "colours scaled and encoded");
    CHECK(px[3] == 0.5f && px[7] == 0.75f, "alpha left as it was");
}

static void check_fixed(void)
{
    double scale = 7.0;
    tone_fixed f = {TONE_AUTO, 0.0};
    CHECK(!tone_fixed_scale(&f, &scale) && scale == 7.0, "auto fixes nothing: %g", scale);
    f = (tone_fixed){TONE_EXPOSURE, -1.5};
    CHECK(tone_fixed_scale(&f, &scale) && fabs(scale - pow(2.0, -1.5)) < 1e-15, "exposure -1.5: %g", scale);
    f = (tone_fixed){TONE_WHITE, 4.0};
    CHECK(tone_fixed_scale(&f, &scale) && scale == 0.25, "white 4: %g", scale);
    const double white[3] = {1, 1, 1}, green[3] = {0, 2, 0};
    CHECK(fabs(tone_lux(white) - 179.0) < 1e-12, "lux of 1 W m^-2 white: %g", tone_lux(white));
    CHECK(fabs(tone_lux(green) - 179.0 * 2 * 0.7152) < 1e-12, "lux of green 2: %g", tone_lux(green));
}

/* @return whether two colours are the same within a rounding. */
static int same_colour(const float a[3], const float b[3])
{
    return fabsf(a[0] - b[0]) < 1e-6f && fabsf(a[1] - b[1]) < 1e-6f && fabsf(a[2] - b[2]) < 1e-6f;
}

static void check_falsecolor(void)
{
    /* 1 .. 1000: the 99th percentile is 990, rounded up to 1000; scaled down, 99 -> 100, 0.3 .. 0.39 -> 0.5 */
    float v[1000];
    for (int k = 0; k < 1000; k++)
        v[k] = (float)(k + 1);
    CHECK(falsecolor_auto_top(v, 1000) == 1000.0, "top of 1..1000: %g", falsecolor_auto_top(v, 1000));
    for (int k = 0; k < 1000; k++)
        v[k] = (float)(k + 1) * 0.1f;
    CHECK(fabs(falsecolor_auto_top(v, 1000) - 100.0) < 1e-9, "top of 0.1..100: %g", falsecolor_auto_top(v, 1000));
    for (int k = 0; k < 1000; k++)
        v[k] = k < 10 ? 1e6f : 0.3f + 0.0001f * (float)k; /* a few very bright pixels do not set the top */
    CHECK(falsecolor_auto_top(v, 1000) == 0.5, "top with outliers: %g", falsecolor_auto_top(v, 1000));
    for (int k = 0; k < 1000; k++)
        v[k] = k % 2 ? -1.0f : 0.0f;
    CHECK(falsecolor_auto_top(v, 1000) == 1.0, "top with nothing lit: %g", falsecolor_auto_top(v, 1000));

    float a[3], b[3], magenta[3] = {1, 0, 1}, grey[3];
    falsecolor_colour(-1.0, 10.0, grey);
    falsecolor_colour(0.0, 10.0, a);
    falsecolor_colour(10.0, 10.0, b);
    CHECK(!same_colour(a, b) && !same_colour(a, grey), "0 and the top must differ, and from no value");
    CHECK(b[0] > 0.8f && b[1] < 0.1f && b[2] < 0.1f, "the top is red: %g %g %g", b[0], b[1], b[2]);
    falsecolor_colour(10.001, 10.0, a);
    CHECK(same_colour(a, magenta), "above the top is magenta: %g %g %g", a[0], a[1], a[2]);
    falsecolor_colour(20.0, 40.0, a);
    falsecolor_colour(5.0, 10.0, b);
    CHECK(same_colour(a, b), "a colour depends on value / top alone");

    /* a 4x3 view of 0 .. 11 on a top of 10: its pixels kept in place, a legend beside it */
    float view[12];
    for (int k = 0; k < 12; k++)
        view[k] = k == 5 ? -1.0f : (float)k;
    int w = 0, h = 0;
    float *img = falsecolor_image(view, 4, 3, 10.0, "lux", &w, &h);
    CHECK(img != NULL && w > 4 + 30 && h > 3, "image %dx%d", w, h);
    if (img == NULL)
        return;
    int kept = 1, ink = 0;
    for (int y = 0; y < 3; y++)
        for (int x = 0; x < 4; x++) {
            float want[3];
            falsecolor_colour(view[y * 4 + x], 10.0, want);
            kept &= same_colour(img + 3 * ((size_t)y * w + x), want);
        }
    for (int y = 0; y < h; y++)
        for (int x = 4; x < w; x++)
            ink += img[3 * ((size_t)y * w + x)] == 1.0f && img[3 * ((size_t)y * w + x) + 1] == 1.0f
                   && img[3 * ((size_t)y * w + x) + 2] == 1.0f;
    CHECK(kept, "the view's pixels are not its values' colours");
    CHECK(ink > 100, "the legend has %d pixels of ink (labels, ticks)", ink);
    int in_range = 1;
    for (size_t k = 0; k < (size_t)w * h * 3; k++)
        in_range &= img[k] >= 0.0f && img[k] <= 1.0f;
    CHECK(in_range, "a value outside [0, 1]");
    free(img);
}

int main(void)
{
    check_percentiles();
    check_apply();
    check_fixed();
    check_falsecolor();
    return check_report();
}
