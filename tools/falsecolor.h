/*
 * falsecolor.h - a false-colour image of a quantity seen by the camera (the
 * illuminance of `ilf relight --falsecolor`), with a legend: a colour bar
 * from 0 to a top value, its ticks labelled in a tiny built-in bitmap font,
 * and the unit above it. What Radiance's falsecolor does for its pictures.
 *
 * Invariants: the colour of a value depends on value / top alone (linear,
 * 0 at the bottom of the bar, top at its top); values above top show
 * magenta, pixels with no value (< 0: no receiving surface) dark grey; the
 * output is sRGB-encoded, every channel in [0, 1], ready for img_write().
 */
#ifndef ILF_FALSECOLOR_H
#define ILF_FALSECOLOR_H

#include <stddef.h>

/** Ticks on the legend: the bar is labelled at top * k / FALSECOLOR_STEPS, k = 0 .. FALSECOLOR_STEPS. */
#define FALSECOLOR_STEPS 5

/**
 * @return the top of the scale for values v[0 .. count) (negative ones are
 * no value): the smallest of 1, 2 and 5 times a power of ten at or above the
 * 99th percentile (nearest rank) of the positive values, so the ticks are
 * round numbers and a few bright pixels do not flatten the rest; 1 when no
 * value is positive; -1 when memory runs out.
 */
double falsecolor_auto_top(const float *v, size_t count);

/**
 * @return the sRGB colour of value v on a scale of [0, top] into rgb[3]: dark blue at 0 through blue, cyan,
 * green, yellow and orange to red at top; magenta above top; dark grey for v < 0 (no value).
 */
void falsecolor_colour(double v, double top, float rgb[3]);

/**
 * Builds the false-colour image of values ([height][width], row 0 at the top)
 * with the legend to its right, labelled in unit (up to 7 characters of
 * "0-9 . + - e k l u x W m ^ /" and space; others are left blank).
 * @return the image, [*out_height][*out_width][3] floats (malloc'd; the
 * caller frees it), at least as tall as the legend needs; NULL when memory
 * runs out.
 */
float *falsecolor_image(const float *values, int width, int height, double top, const char *unit, int *out_width,
                        int *out_height);

#endif /* ILF_FALSECOLOR_H */
