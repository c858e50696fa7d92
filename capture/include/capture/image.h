/*
 * image.h - reading and writing images: a C interface over OpenImageIO.
 * The `ilf` command writes its images with it and the capture reads light
 * probes with it.
 *
 * OpenImageIO is loaded lazily: capture/src/image.c implements these
 * functions and, on the first cap_image_write() or cap_image_read() of the
 * process, loads the image module libilfkit_oiio.so (capture/src/image_oiio.cpp,
 * the only file of ilfkit that includes OpenImageIO headers) with dlopen(),
 * once, thread-safely; programs that never read or write an image never map
 * OpenImageIO. The module is taken from $ILFKIT_IMAGE_MODULE (a full path)
 * if that is set and not empty, and then from there only; otherwise from
 * <folder of the program>/../LIBDIR/ilfkit/ (the build tree and a relocated
 * install), then from the configured install's LIBDIR/ilfkit/. A module of
 * another build (a different entry table version) is refused. If no module
 * loads, every read and write fails with its usual status (CAP_ERR_INPUT,
 * CAP_ERR_OUTPUT) and a message naming the image, each module path tried
 * and why it failed; the process does not try again. cap_image_guess_format()
 * and cap_image_free() never load anything.
 *
 * Conventions:
 *   - Pixels are float, interleaved, rows top to bottom: [y][x][channel].
 *   - Reading accepts what OpenImageIO reads (EXR, HDR, TIFF, PNG, JPEG and
 *     more), first subimage, every channel, values as stored: integer files
 *     (8 or 16 bits) are normalised to [0, 1] and keep their transfer
 *     function (no sRGB decoding here); float files are returned unchanged,
 *     including negative, NaN and infinite values (repairs are the caller's).
 *   - Writing chooses the format from the file name's extension, any case:
 *     .exr is written as 32-bit float (never half), .png as 8 bits with
 *     values in [0, 1] quantised as given (callers apply sRGB first).
 *   - Writes are atomic: a temporary file in the same folder is written,
 *     flushed and renamed over the path; on failure the temporary is removed
 *     and an existing file at the path is left as it was.
 *   - On failure a one-line message naming the file goes to err (errlen
 *     bytes, when err is not NULL) and to cap_error_message().
 *   - Calls may run concurrently on different files; nothing throws or exits.
 *
 * This header is valid C99 and C++.
 */
#ifndef CAPTURE_IMAGE_H
#define CAPTURE_IMAGE_H

#include <stddef.h>

#include "capture/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Largest accepted image side, in pixels. */
#define CAP_IMAGE_MAX_SIDE 65536

/** Formats the writer chooses by extension. */
typedef enum cap_image_format {
    CAP_IMAGE_FORMAT_UNKNOWN = 0,
    CAP_IMAGE_FORMAT_EXR = 1, /**< OpenEXR, 32-bit float, linear */
    CAP_IMAGE_FORMAT_PNG = 2  /**< PNG, 8 bits per channel, display-encoded */
} cap_image_format;

/** An image read from a file. */
typedef struct cap_image {
    int width, height; /**< pixels, 1 .. CAP_IMAGE_MAX_SIDE */
    int channels;      /**< channels per pixel, >= 1, in the file's order (usually R, G, B, A) */
    float *pixels;     /**< [y][x][channel]; owned, release with cap_image_free() */
    int integer;       /**< 1 if the file stores integers (8-bit or 16-bit LDR, normalised to [0, 1]), 0 for floats */
    int bits;          /**< bits per stored channel value: 8, 16 (integer or half), 32 or 64 */
} cap_image;

/** @return the writable format for path's extension (.exr or .png, any case); UNKNOWN otherwise or for NULL. */
cap_image_format cap_image_guess_format(const char *path);

/**
 * Writes a width x height image with 1 to 4 channels (3 = RGB, 4 = RGBA),
 * pixels [y][x][channel], atomically.
 * @return CAP_OK; CAP_ERR_ARG (bad size, channel count, NULL or unknown extension); CAP_ERR_OUTPUT (also: no image module); CAP_ERR_NOMEM.
 */
cap_status cap_image_write(const char *path, int width, int height, int channels, const float *pixels, char *err,
                           size_t errlen);

/**
 * Reads the first subimage of path whole (see the conventions above).
 * @return CAP_OK and *img filled; CAP_ERR_INPUT (missing, a folder, unreadable,
 * not an image, too large, no image module) or CAP_ERR_NOMEM with *img zeroed; CAP_ERR_ARG if path or img is NULL.
 */
cap_status cap_image_read(const char *path, cap_image *img, char *err, size_t errlen);

/** Releases img's pixels and zeroes it. NULL is a no-op. */
void cap_image_free(cap_image *img);

#ifdef __cplusplus
}
#endif

#endif /* CAPTURE_IMAGE_H */
