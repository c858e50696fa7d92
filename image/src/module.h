/*
 * module.h - the entry table between image/src/image.c, which implements
 * image/image.h, and the image module libilfkit_oiio.so
 * (image/src/oiio_module.cpp), which image.c loads with dlopen() on the
 * first image read so that programs that never read an image do not map
 * OpenImageIO and its few hundred dependencies (writes go through writers.c).
 *
 * The module exports one C function, IMG__MODULE_ENTRY, returning a static
 * table whose first field is IMG__MODULE_VERSION. Any change to this header
 * that changes the table or the functions' meaning must raise the version,
 * so that a module from another build is refused, not called.
 *
 * Division of work: image.c checks arguments, stats inputs and makes
 * writes atomic (base's atomic writer); the module only decodes headers and pixels. The module is self-contained:
 * it calls nothing of ilfkit (its messages go to the caller's buffer) and
 * never lets an exception out.
 *
 * This header is valid C and C++.
 */
#ifndef IMAGE_MODULE_H
#define IMAGE_MODULE_H

#include <stddef.h>

#include "image/image.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The table layout and meaning this build expects; raise on any change. (Version 2: the module no longer
 * writes; writers.c encodes without OpenImageIO. Version 3: header reads.) */
#define IMG__MODULE_VERSION 3u

/** Name of the exported entry function (an img__module_entry_fn). */
#define IMG__MODULE_ENTRY "ilfkit_image_module"

/** What the module offers. msg (msglen > 0 bytes, never NULL) receives one line on failure. */
typedef struct img__module {
    unsigned version; /**< IMG__MODULE_VERSION of the module's build; first, in every version */

    /**
     * Reads the first subimage of path (an existing file, not a folder) as
     * image/image.h describes, pixels allocated with malloc().
     * @return IMG_OK with *img filled; IMG_ERR_INPUT or IMG_ERR_NOMEM with *img untouched and a message naming path.
     */
    img_status (*read)(const char *path, img_image *img, char *msg, size_t msglen);

    /**
     * Reads only the header of path's first subimage (no pixel is decoded) and checks its size as read()
     * does, so that a size read() refuses is refused here with the same message.
     * @return IMG_OK with *hdr filled; IMG_ERR_INPUT or IMG_ERR_NOMEM with *hdr untouched and a message naming path.
     */
    img_status (*header)(const char *path, img_header *hdr, char *msg, size_t msglen);
} img__module;

/** @return the module's static table (never NULL). */
typedef const img__module *(*img__module_entry_fn)(void);

#ifdef __cplusplus
}
#endif

#endif /* IMAGE_MODULE_H */
