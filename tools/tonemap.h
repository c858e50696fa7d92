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

/* Luminous efficacy of ilfkit's white, lm/W: Radiance's convention (its WHTEFFICACY), so that illuminance
 * from ilf agrees with Radiance's (docs/cli.md, `irradiance --lux`, says why this number). */
#define TONE_LUMENS_PER_WATT 179.0

/** @return the illuminance in lux of irradiance rgb (W m^-2, linear Rec.709): 179 lm/W times its Rec.709
 * luminance 0.2126 r + 0.7152 g + 0.0722 b. */
double tone_lux(const double rgb[3]);

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

/** A display scale the user fixed, or none: `--exposure EV` multiplies radiance by 2^EV, `--scale W` shows
 * radiance W as white (multiplies by 1/W). */
typedef struct tone_fixed {
    enum { TONE_AUTO, TONE_EXPOSURE, TONE_WHITE } kind;
    double value; /**< EV for TONE_EXPOSURE, W (> 0) for TONE_WHITE */
} tone_fixed;

/** @return 1 with *scale the factor f fixes, or 0 (scale untouched) for TONE_AUTO. */
int tone_fixed_scale(const tone_fixed *f, double *scale);

/** Describes where scale came from, for a command's summary: "from --exposure 1.5", "W 40 shows as white",
 * or auto (the caller's text). @return buf. */
const char *tone_fixed_describe(const tone_fixed *f, const char *auto_text, char *buf, size_t size);

/** Multiplies the colour channels (not alpha) of count pixels by scale and sRGB-encodes them, in place. */
void tone_apply(float *pixels, size_t count, int channels, double scale);

#endif /* ILF_TONEMAP_H */
