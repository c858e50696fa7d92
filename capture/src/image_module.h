/*
 * image_module.h - the entry table between capture/src/image.c, which
 * implements capture/image.h, and the image module libilfkit_oiio.so
 * (capture/src/image_oiio.cpp), which image.c loads with dlopen() on the
 * first image read or write so that programs that never touch an image do
 * not map OpenImageIO and its few hundred dependencies.
 *
 * The module exports one C function, CAP__IMAGE_MODULE_ENTRY, returning a
 * static table whose first field is CAP__IMAGE_MODULE_VERSION. Any change to
 * this header that changes the table or the functions' meaning must raise the
 * version, so that a module from another build is refused, not called.
 *
 * Division of work: image.c checks arguments, chooses the format by
 * extension, stats inputs and makes writes atomic (temporary file, flush,
 * rename); the module only encodes and decodes pixels. The module is
 * self-contained: it calls nothing of the capture library (its messages go
 * to the caller's buffer) and never lets an exception out.
 *
 * This header is valid C and C++.
 */
#ifndef CAPTURE_IMAGE_MODULE_H
#define CAPTURE_IMAGE_MODULE_H

#include <stddef.h>

#include "capture/image.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The table layout and meaning this build expects; raise on any change. */
#define CAP__IMAGE_MODULE_VERSION 1u

/** Name of the exported entry function (a cap__image_module_entry_fn). */
#define CAP__IMAGE_MODULE_ENTRY "ilfkit_image_module"

/** What the module offers. msg (msglen > 0 bytes, never NULL) receives one line on failure. */
typedef struct cap__image_module {
    unsigned version; /**< CAP__IMAGE_MODULE_VERSION of the module's build; first, in every version */

    /**
     * Writes width x height x channels float pixels ([y][x][channel], sizes
     * already checked) to the existing file file, replacing its content, in
     * format (EXR or PNG); path is the final name, for messages only.
     * @return CAP_OK; CAP_ERR_OUTPUT or CAP_ERR_NOMEM with a message naming path.
     */
    cap_status (*write)(const char *file, const char *path, cap_image_format format, int width, int height,
                        int channels, const float *pixels, char *msg, size_t msglen);

    /**
     * Reads the first subimage of path (an existing file, not a folder) as
     * capture/image.h describes, pixels allocated with malloc().
     * @return CAP_OK with *img filled; CAP_ERR_INPUT or CAP_ERR_NOMEM with *img untouched and a message naming path.
     */
    cap_status (*read)(const char *path, cap_image *img, char *msg, size_t msglen);
} cap__image_module;

/** @return the module's static table (never NULL). */
typedef const cap__image_module *(*cap__image_module_entry_fn)(void);

#ifdef __cplusplus
}
#endif

#endif /* CAPTURE_IMAGE_MODULE_H */
