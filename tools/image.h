/*
 * image.h - reading and writing images for `ilf`, a C interface over
 * OpenImageIO (implemented in image_oiio.cpp, the only file in the tree that
 * includes OpenImageIO headers).
 *
 * Invariants:
 *   - Pixels are float, interleaved, rows top to bottom: [y][x][channel].
 *   - The format follows the file name's extension, case-insensitively:
 *     .exr is written as 32-bit float (never half), .png as 8-bit, with
 *     values in [0, 1] quantised as given (callers apply any transfer
 *     function such as sRGB first).
 *   - Writes are atomic: the image goes to a temporary file in the same
 *     folder, which is flushed and renamed over the path; on failure the
 *     temporary is removed and an existing file at the path is untouched.
 *   - Functions never throw and never exit; errors come back as a status and
 *     a message naming the file.
 */
#ifndef ILF_IMAGE_H
#define ILF_IMAGE_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Result of an image call. */
typedef enum ilfimg_status {
    ILFIMG_OK = 0,
    ILFIMG_ERR_ARG = 1,   /**< bad size, channel count, NULL pointer or unsupported extension */
    ILFIMG_ERR_INPUT = 2, /**< an input file is missing, unreadable or not a valid image */
    ILFIMG_ERR_OUTPUT = 3,/**< an output could not be written */
    ILFIMG_ERR_NOMEM = 4  /**< an allocation failed */
} ilfimg_status;

/** File formats chosen by extension. */
typedef enum ilfimg_format {
    ILFIMG_FORMAT_UNKNOWN = 0,
    ILFIMG_FORMAT_EXR = 1, /**< OpenEXR, 32-bit float, linear */
    ILFIMG_FORMAT_PNG = 2  /**< PNG, 8 bits per channel, display-encoded */
} ilfimg_format;

/** @return the format for path's extension (.exr or .png, any case). */
ilfimg_format ilfimg_format_of(const char *path);

/**
 * Writes a width x height image with 1 to 4 channels (3 = RGB, 4 = RGBA),
 * pixels laid out [y][x][channel], atomically (see above).
 * @return ILFIMG_OK; otherwise an error with a message in err (errlen bytes).
 */
ilfimg_status ilfimg_write(const char *path, int width, int height, int channels, const float *pixels,
                           char *err, size_t errlen);

/**
 * Reads the first subimage of path as float, all channels, [y][x][channel].
 * Values are as stored: linear for EXR, display-encoded in [0, 1] for 8-bit
 * formats such as PNG (no transfer function is undone).
 * @return ILFIMG_OK with *pixels allocated by malloc (free with free());
 * otherwise an error, a message in err and *pixels = NULL.
 */
ilfimg_status ilfimg_read(const char *path, int *width, int *height, int *channels, float **pixels,
                          char *err, size_t errlen);

#ifdef __cplusplus
}
#endif

#endif /* ILF_IMAGE_H */
