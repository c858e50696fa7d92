/*
 * image.c - image/image.h: argument checks, formats by extension, atomic
 * writes (base's ilf/atomic_file.h) and input checks in plain C. Writes are
 * encoded by writers.c (OpenEXR's core library and libpng); reads are decoded
 * by the image module libilfkit_oiio.so (oiio_module.cpp, the table of
 * module.h), loaded on the first read or header read. Programs that never read an image
 * therefore never map OpenImageIO.
 *
 * Where the module is looked for (ILFKIT_IMAGE_MODULE pins it; the build
 * tree, beside a shared library, the install location) and how it is loaded
 * once: base's one module loader, ilf/module.h. Both paths come from CMake
 * (ILFKIT_IMAGE_MODULE_RELATIVE and _INSTALLED).
 *
 * Invariants:
 *   - guess_format, free and write never load the module; argument errors
 *     are reported without loading it.
 *   - A module whose table version differs from IMG__MODULE_VERSION is
 *     refused (ilf/module.h).
 *   - A write either leaves a complete image at the path (renamed from a
 *     flushed temporary in the same folder, so the rename is atomic) or leaves
 *     the path as it was and no temporary behind. The temporary keeps the
 *     path's extension (base's rule), so any reader of a leftover sees the
 *     right type (writers.c is told the format anyway).
 *   - The library holds no message state: every report goes to the caller's
 *     err buffer, so it needs no per-thread storage.
 *   - Every failure message is one line naming the image file; a load
 *     failure also names each module path tried and why it failed.
 */
#include "image/image.h"

#include <ctype.h>
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "ilf/atomic_file.h"
#include "ilf/file_kind.h"
#include "ilf/limits.h"
#include "ilf/module.h"
#include "module.h"
#include "writers.h"

#ifndef ILFKIT_IMAGE_MODULE_RELATIVE
#error "ILFKIT_IMAGE_MODULE_RELATIVE (LIBDIR/ilfkit/<file>, relative to a prefix) must be defined"
#endif
#ifndef ILFKIT_IMAGE_MODULE_INSTALLED
#error "ILFKIT_IMAGE_MODULE_INSTALLED (the module's installed path) must be defined"
#endif

#define MESSAGE_BYTES ILF_MESSAGE_BYTES

/* ------------------------------------------------------------ messages */

/* Formats a message into err (when given). @return status. */
static img_status fail(img_status status, char *err, size_t errlen, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static img_status fail(img_status status, char *err, size_t errlen, const char *fmt, ...)
{
    if (err != NULL && errlen > 0) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err, errlen, fmt, ap);
        va_end(ap);
    }
    return status;
}

const char *img_status_name(img_status s)
{
    switch (s) {
    case IMG_OK:
        return "ok";
    case IMG_ERR_ARG:
        return "bad argument";
    case IMG_ERR_INPUT:
        return "bad input";
    case IMG_ERR_OUTPUT:
        return "cannot write";
    case IMG_ERR_NOMEM:
        return "out of memory";
    }
    return "unknown status";
}

/* ------------------------------------------------------------ the module */

/* Found and loaded by base's module loader (ilf/module.h), once per process. */
static ilf_module module = ILF_MODULE_INIT("ILFKIT_IMAGE_MODULE", ILFKIT_IMAGE_MODULE_RELATIVE,
                                           ILFKIT_IMAGE_MODULE_INSTALLED, IMG__MODULE_ENTRY, IMG__MODULE_VERSION);

/* @return the loaded module, or NULL (and a message naming path, to be read) if it cannot be loaded. */
static const img__module *need_module(const char *path, char *err, size_t errlen)
{
    const img__module *table = ilf_module_get(&module);
    if (table == NULL)
        fail(IMG_ERR_INPUT, err, errlen, "%s: cannot read: image support is not available (%s)", path,
             ilf_module_failure(&module));
    return table;
}

/* ------------------------------------------------------------ names and formats */

/* @return the extension of path's last component without its dot, "" if none. */
static const char *extension_of(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(path, '.');
    return dot != NULL && (slash == NULL || dot > slash) ? dot + 1 : "";
}

/* @return whether a and b are equal, ignoring ASCII case. */
static int equals_ignoring_case(const char *a, const char *b)
{
    for (; *a != '\0' && *b != '\0'; a++, b++)
        if (tolower((unsigned char)*a) != tolower((unsigned char)*b))
            return 0;
    return *a == *b;
}

img_format img_guess_format(const char *path)
{
    if (path == NULL)
        return IMG_FORMAT_UNKNOWN;
    const char *ext = extension_of(path);
    if (equals_ignoring_case(ext, "exr"))
        return IMG_FORMAT_EXR;
    if (equals_ignoring_case(ext, "png"))
        return IMG_FORMAT_PNG;
    if (equals_ignoring_case(ext, "hdr"))
        return IMG_FORMAT_HDR;
    return IMG_FORMAT_UNKNOWN;
}

/* ------------------------------------------------------------ writing */

/* @return IMG_OK if img_write's arguments are usable, else IMG_ERR_ARG with a message; loads nothing. */
static img_status check_write_args(const char *path, int width, int height, int channels, const float *pixels,
                                   char *err, size_t errlen)
{
    if (path == NULL || pixels == NULL)
        return fail(IMG_ERR_ARG, err, errlen, "image path or pixels missing");
    if (img_guess_format(path) == IMG_FORMAT_UNKNOWN)
        return fail(IMG_ERR_ARG, err, errlen, "%s: unsupported image type (use .exr or .png)", path);
    if (width < 1 || height < 1 || width > IMG_MAX_SIDE || height > IMG_MAX_SIDE)
        return fail(IMG_ERR_ARG, err, errlen, "%s: image size %dx%d out of range", path, width, height);
    if (channels < 1 || channels > 4)
        return fail(IMG_ERR_ARG, err, errlen, "%s: %d channels (1 to 4 supported)", path, channels);
    return IMG_OK;
}

/* Encodes into a's temporary and commits it over path. @return a status, with a message on failure. */
static img_status encode_and_commit(ilf_atomic *a, const char *path, int width, int height, int channels,
                                    const float *pixels, char *err, size_t errlen)
{
    char msg[MESSAGE_BYTES] = "";
    img_status status = img__write_pixels(ilf_atomic_temp_path(a), path, img_guess_format(path), width, height,
                                          channels, pixels, msg, sizeof msg);
    if (status != IMG_OK)
        return fail(status, err, errlen, "%s", msg);
    const char *step = NULL;
    int code = ilf_atomic_commit(a, &step);
    if (code != 0)
        return fail(IMG_ERR_OUTPUT, err, errlen, "%s: %s: %s", path, step, strerror(code));
    return IMG_OK;
}

img_status img_write(const char *path, int width, int height, int channels, const float *pixels, char *err,
                     size_t errlen)
{
    img_status status = check_write_args(path, width, height, channels, pixels, err, errlen);
    if (status != IMG_OK)
        return status;
    ilf_atomic *a = NULL;
    const char *step = NULL;
    int code = ilf_atomic_new(path, &a, &step);
    if (code != 0)
        return fail(code == ENOMEM ? IMG_ERR_NOMEM : IMG_ERR_OUTPUT, err, errlen, "%s: cannot create a file there: %s",
                    path, strerror(code));
    status = encode_and_commit(a, path, width, height, channels, pixels, err, errlen);
    ilf_atomic_release(a); /* removes the temporary unless it was committed */
    return status;
}

/* ------------------------------------------------------------ reading */

/* @return IMG_OK if path is a regular file (opened without blocking: a FIFO is refused, never waited on), else
 * IMG_ERR_INPUT with a message naming it. */
static img_status check_readable(const char *path, char *err, size_t errlen)
{
    char why[160];
    int code = ilf_input_check(path, why, sizeof why);
    if (code == EISDIR)
        return fail(IMG_ERR_INPUT, err, errlen, "%s: is a folder, not an image", path);
    if (code != 0)
        return fail(IMG_ERR_INPUT, err, errlen, "%s: %s", path, why);
    return IMG_OK;
}

/* Checks path as a readable regular file and loads the module. @return the module, or NULL with err set. */
static const img__module *reader_for(const char *path, char *err, size_t errlen)
{
    if (check_readable(path, err, errlen) != IMG_OK)
        return NULL;
    return need_module(path, err, errlen);
}

img_status img_read(const char *path, img_image *img, char *err, size_t errlen)
{
    if (img != NULL)
        memset(img, 0, sizeof *img);
    if (path == NULL || img == NULL)
        return fail(IMG_ERR_ARG, err, errlen, "image path or output missing");
    const img__module *m = reader_for(path, err, errlen);
    if (m == NULL)
        return IMG_ERR_INPUT;
    char msg[MESSAGE_BYTES] = "";
    img_status status = m->read(path, img, msg, sizeof msg);
    if (status != IMG_OK) {
        memset(img, 0, sizeof *img);
        return fail(status, err, errlen, "%s", msg);
    }
    return IMG_OK;
}

img_status img_header_read(const char *path, img_header *hdr, char *err, size_t errlen)
{
    if (hdr != NULL)
        memset(hdr, 0, sizeof *hdr);
    if (path == NULL || hdr == NULL)
        return fail(IMG_ERR_ARG, err, errlen, "image path or output missing");
    const img__module *m = reader_for(path, err, errlen);
    if (m == NULL)
        return IMG_ERR_INPUT;
    char msg[MESSAGE_BYTES] = "";
    img_status status = m->header(path, hdr, msg, sizeof msg);
    if (status != IMG_OK) {
        memset(hdr, 0, sizeof *hdr);
        return fail(status, err, errlen, "%s", msg);
    }
    return IMG_OK;
}

void img_free(img_image *img)
{
    if (img == NULL)
        return;
    free(img->pixels);
    memset(img, 0, sizeof *img);
}
