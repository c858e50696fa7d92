/*
 * srgb.c - the sRGB transfer function of IEC 61966-2-1, both ways: the one
 * copy for the capture library (decoding 8- and 16-bit probes) and the `ilf`
 * command (encoding PNG views and slices).
 *
 * Invariants: the encoder works in double and clamps to [0, 1], the decoder
 * in float without clamping, exactly as their former copies in
 * tools/tonemap.c and capture/src/merge.c did, so outputs stay bit-identical.
 * Neither loads the image module.
 */
#include "image/image.h"

#include <math.h>

/* The curve's constants are written out in each function, in that function's precision: converting one
 * shared double constant to float could round differently from the float literal the former copies used. */

float img_srgb_encode(double linear)
{
    double v = linear <= 0.0031308 ? 12.92 * linear : 1.055 * pow(linear, 1.0 / 2.4) - 0.055;
    return (float)(v < 0.0 ? 0.0 : v > 1.0 ? 1.0 : v);
}

float img_srgb_decode(float encoded)
{
    return encoded <= 0.04045f ? encoded / 12.92f : powf((encoded + 0.055f) / 1.055f, 2.4f);
}
