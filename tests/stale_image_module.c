/*
 * stale_image_module.c - a stand-in for an image module from another build
 * (tests/CMakeLists.txt builds it as libstale_image_module.so): it exports
 * the entry function, but its table's version is one above this build's, so
 * image/src/image.c must refuse it. Its functions are NULL, so a loader
 * that called them instead would crash the test.
 */
#include "module.h"

static const img__module table = {IMG__MODULE_VERSION + 1u, NULL, NULL};

/** @return the stale table. */
__attribute__((visibility("default"))) const img__module *ilfkit_image_module(void);

const img__module *ilfkit_image_module(void)
{
    return &table;
}
