/*
 * stale_image_module.c - a stand-in for an image module from another build
 * (tests/CMakeLists.txt builds it as libstale_image_module.so): it exports
 * the entry function, but its table's version is one above this build's, so
 * capture/src/image.c must refuse it. Its functions are NULL, so a loader
 * that called them instead would crash the test.
 */
#include "image_module.h"

static const cap__image_module table = {CAP__IMAGE_MODULE_VERSION + 1u, NULL, NULL};

/** @return the stale table. */
__attribute__((visibility("default"))) const cap__image_module *ilfkit_image_module(void);

const cap__image_module *ilfkit_image_module(void)
{
    return &table;
}
