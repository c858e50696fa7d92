/*
 * tonemap.h - turning linear radiance images into 8-bit display images for
 * `ilf` (slice, relight): one exposure factor chosen from a percentile of
 * the lit pixels, then the sRGB transfer function (img_srgb_encode).
 *
 * Invariants: pixels are float, interleaved [y][x][channel] with at least 3
 * channels, the first three linear RGB; a fourth (alpha) is never scaled or
 * encoded. Nothing here allocates except tone_percentile_scale().
 */
#ifndef ILF_TONEMAP_H
#define ILF_TONEMAP_H

#include <stddef.h>

/** What the percentile of tone_percentile_scale() is taken of. */
typedef enum tone_measure {
    TONE_PEAK,     /**< max(r, g, b) */
    TONE_LUMINANCE /**< Rec.709 luminance 0.2126 r + 0.7152 g + 0.0722 b */
} tone_measure;

/**
 * Sets *scale to target / the given percentile (nearest rank, in (0, 1]) of
 * measure over the count pixels where it is > 0, or to 1 if there are none.
 * @return 1, or 0 when memory runs out (*scale untouched).
 */
int tone_percentile_scale(const float *pixels, size_t count, int channels, tone_measure measure,
                          double percentile, double target, double *scale);

/** Multiplies the colour channels (not alpha) of count pixels by scale and sRGB-encodes them, in place. */
void tone_apply(float *pixels, size_t count, int channels, double scale);

#endif /* ILF_TONEMAP_H */
