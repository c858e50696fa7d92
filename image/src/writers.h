/*
 * writers.h - image.c's encoders of EXR and PNG (writers.c), which need
 * neither OpenImageIO nor the image module. Internal to the image library.
 */
#ifndef IMAGE_WRITERS_H
#define IMAGE_WRITERS_H

#include <stddef.h>

#include "image/image.h"

/**
 * Writes width x height x channels float pixels ([y][x][channel], arguments
 * already checked by image.c) to the existing file file, replacing its content,
 * in format (EXR or PNG, as image/image.h describes); path is the final name,
 * for messages only. A failed EXR write removes file (OpenEXR's own rule).
 * Thread-safe.
 * @return IMG_OK; IMG_ERR_OUTPUT or IMG_ERR_NOMEM with one line naming path in msg (msglen > 0).
 */
img_status img__write_pixels(const char *file, const char *path, img_format format, int width, int height,
                             int channels, const float *pixels, char *msg, size_t msglen);

#endif /* IMAGE_WRITERS_H */
