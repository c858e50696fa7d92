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
 *   - tone_apply() encodes colour channels and leaves alpha as it was.
 * The last line is "N passed, M failed".
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "check.h"
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

int main(void)
{
    check_percentiles();
    check_apply();
    return check_report();
}
