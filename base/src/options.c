/*
 * options.c - ilf_options_take() (ilf/options.h): a caller's options struct
 * into the library's, the part the caller's size says it holds.
 *
 * Invariants: src's size is read before any other byte of it, and no byte
 * past that size is read; dst changes only when the size is accepted.
 */
#include "ilf/options.h"

#include <string.h>

int ilf_options_take(void *dst, size_t dst_size, const void *src, size_t least)
{
    size_t size;
    memcpy(&size, src, sizeof size);
    if (size < least || size < sizeof size || size > dst_size)
        return 0;
    memcpy(dst, src, size);
    return 1;
}
