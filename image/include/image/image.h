/*
 * image/image.h - the image library: reading image files through
 * OpenImageIO, writing EXR and PNG through OpenEXR's C core library and
 * libpng, and the sRGB transfer function. The capture library reads light
 * probes with it; the `ilf` command writes its images (relight's view,
 * slices, rendered probes) with it. It depends on base/ only.
 *
 * OpenImageIO is loaded lazily: image/src/image.c implements these functions
 * and, on the first img_read() or img_header_read() of the process, loads the image
 * module libilfkit_oiio.so (image/src/oiio_module.cpp, the only file of ilfkit
 * that includes OpenImageIO headers) with dlopen() through base's module
 * loader (ilf/module.h), once, thread-safely;
 * programs that never read an image never map OpenImageIO. Writing needs no
 * module (image/src/writers.c). The module
 * is taken from $ILFKIT_IMAGE_MODULE (a full path) if that is set and not
 * empty, and then from there only; otherwise from
 * <folder of the program>/../LIBDIR/ilfkit/ (the build tree and a relocated
 * install), then, when this library is part of a shared library (the installed
 * libcapture), from <folder of that library>/../LIBDIR/ilfkit/, then from the
 * configured install's LIBDIR/ilfkit/. A module of
 * another build (a different entry table version) is refused. If no module
 * loads, every read fails with IMG_ERR_INPUT and a message naming the image,
 * each module path tried and why it failed; the process does not try again.
 * img_write(), img_guess_format(), img_free(), img_status_name() and the sRGB
 * functions never load anything.
 *
 * Conventions:
 *   - Pixels are float, interleaved, rows top to bottom: [y][x][channel].
 *   - Reading accepts what OpenImageIO reads (EXR, HDR, TIFF, PNG, JPEG and
 *     more), first subimage, every channel, values as stored: integer files
 *     (8 or 16 bits) are normalised to [0, 1] and keep their transfer
 *     function (no sRGB decoding here: see img_srgb_decode()); float files
 *     are returned unchanged, including negative, NaN and infinite values
 *     (repairs are the caller's).
 *   - Writing chooses the format from the file name's extension, any case:
 *     .exr is written as 32-bit float (never half), ZIP-compressed scanlines,
 *     values as given; .png as 8 bits with values clamped to [0, 1] and
 *     rounded to the nearest of 255 steps, NaN as 0 (callers apply
 *     img_srgb_encode()). Channels: 1 is gray (EXR "Y"), 2 gray and alpha in
 *     PNG ("R", "G" in EXR), 3 RGB, 4 RGBA. .hdr is Radiance's RGBE
 *     (shared 8-bit exponent, 1% precision), linear, scanlines run-length
 *     encoded, rows top to bottom ("-Y H +X W"); gray is written as r = g = b,
 *     alpha is dropped, negative and NaN values are written as 0.
 *   - Writes are atomic (base's ilf/atomic_file.h): the image is written to
 *     FOLDER/.NAME.tmp-<12 hex>.EXT beside the path, flushed and renamed over
 *     it; on failure the temporary is removed and an existing file at the
 *     path is left as it was (except when only the final flush of the
 *     folder fails: the new image is then in place, and the failure is
 *     still reported).
 *   - On failure a one-line message naming the file goes to err (errlen
 *     bytes, always terminated, when err is not NULL and errlen > 0). The
 *     library keeps no message of its own: err is the only report.
 *   - Every function is thread-safe; calls may run concurrently on different
 *     files. Nothing throws, exits or prints.
 *
 * This header is valid C99 and C++.
 */
#ifndef IMAGE_IMAGE_H
#define IMAGE_IMAGE_H

#include <stddef.h>

#include "ilf/limits.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Largest accepted image side, in pixels, for reading and writing (reason in ilf/limits.h). */
#define IMG_MAX_SIDE ILF_IMAGE_MAX_SIDE

/** Largest accepted width * height * channels of an image read (reason in ilf/limits.h). */
#define IMG_MAX_SAMPLES ILF_IMAGE_MAX_SAMPLES

/** Result of a fallible call; IMG_OK (0) is success. */
typedef enum img_status {
    IMG_OK = 0,
    IMG_ERR_ARG = 1,    /**< an argument is NULL or out of range, or the extension is not writable */
    IMG_ERR_INPUT = 2,  /**< the file to read is missing, a folder, unreadable, not an image or too large */
    IMG_ERR_OUTPUT = 3, /**< the file could not be written */
    IMG_ERR_NOMEM = 4   /**< memory ran out */
} img_status;

/** Formats the writer chooses by extension. */
typedef enum img_format {
    IMG_FORMAT_UNKNOWN = 0,
    IMG_FORMAT_EXR = 1, /**< OpenEXR, 32-bit float, linear */
    IMG_FORMAT_PNG = 2, /**< PNG, 8 bits per channel, display-encoded */
    IMG_FORMAT_HDR = 3  /**< Radiance RGBE (.hdr), linear, run-length encoded scanlines */
} img_format;

/** An image read from a file. */
typedef struct img_image {
    int width, height; /**< pixels, 1 .. IMG_MAX_SIDE */
    int channels;      /**< channels per pixel, >= 1, in the file's order (usually R, G, B, A) */
    float *pixels;     /**< [y][x][channel]; owned, release with img_free() */
    int integer;       /**< 1 if the file stores integers (8-bit or 16-bit LDR, normalised to [0, 1]), 0 for floats */
    int bits;          /**< bits per stored channel value: 8, 16 (integer or half), 32 or 64 */
} img_image;

/** What an image file's header says, read without decoding a pixel (img_header_read()). */
typedef struct img_header {
    int width, height; /**< pixels, 1 .. IMG_MAX_SIDE */
    int channels;      /**< channels per pixel, >= 1; width * height * channels <= IMG_MAX_SAMPLES */
    int integer;       /**< as img_image's */
    int bits;          /**< as img_image's */
} img_header;

/** @return a static name for s ("ok", "bad argument", "bad input", "cannot write", "out of memory", "unknown status"). */
const char *img_status_name(img_status s);

/** @return the writable format for path's extension (.exr, .png or .hdr, any case); UNKNOWN otherwise or for NULL. */
img_format img_guess_format(const char *path);

/**
 * Writes a width x height image with 1 to 4 channels (3 = RGB, 4 = RGBA),
 * pixels [y][x][channel] (read only, borrowed for the call), atomically.
 * @return IMG_OK; IMG_ERR_ARG (bad size, channel count, NULL or unknown extension; nothing created); IMG_ERR_OUTPUT; IMG_ERR_NOMEM.
 */
img_status img_write(const char *path, int width, int height, int channels, const float *pixels, char *err,
                     size_t errlen);

/**
 * Reads the first subimage of path whole (see the conventions above) into
 * *img, whose pixels the caller then owns and releases with img_free().
 * @return IMG_OK and *img filled; IMG_ERR_INPUT (missing, a folder, unreadable, not an image, too large, no image module) or IMG_ERR_NOMEM with *img zeroed; IMG_ERR_ARG if path or img is NULL.
 */
img_status img_read(const char *path, img_image *img, char *err, size_t errlen);

/**
 * Reads only the header of path's first subimage: what img_read() would return, without its pixels and at a
 * cost that does not grow with the image's size. The file is checked as img_read() checks it (a regular file,
 * opened without blocking), and a size img_read() refuses is refused with the same message; pixel data is not
 * looked at, so a later img_read() may still fail on it.
 * @return IMG_OK and *hdr filled; IMG_ERR_INPUT or IMG_ERR_NOMEM with *hdr zeroed; IMG_ERR_ARG if path or hdr is NULL.
 */
img_status img_header_read(const char *path, img_header *hdr, char *err, size_t errlen);

/** Releases img's pixels and zeroes it. NULL is a no-op. */
void img_free(img_image *img);

/** @return the sRGB encoding (IEC 61966-2-1) of a linear value, clamped to [0, 1] (NaN stays NaN); computed in double. */
float img_srgb_encode(double linear);

/** @return the linear value of an sRGB-encoded one (IEC 61966-2-1), not clamped; computed in float. */
float img_srgb_decode(float encoded);

#ifdef __cplusplus
}
#endif

#endif /* IMAGE_IMAGE_H */
