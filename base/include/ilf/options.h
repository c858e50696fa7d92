/*
 * ilf/options.h - options structs that can grow. Each options struct a library
 * publishes (lfio_read_options, lfio_radmap_write_options,
 * rl_scene_load_options) starts with `size_t size`, which the caller sets to
 * the struct's size as it was compiled, so that a library with more fields
 * still takes an older caller's struct: the fields past its size keep their
 * defaults. This is the one copy of such a struct into the library's own.
 */
#ifndef ILF_OPTIONS_H
#define ILF_OPTIONS_H

#include <stddef.h>

/*
 * Copies the first size bytes of src, a struct that starts with its size_t
 * size, over dst (dst_size bytes, holding the defaults), so that dst's
 * fields past that size keep them. @return 1; 0 (dst unchanged) if that size
 * is under least (the fields every version has) or over dst_size (a struct
 * newer than the library).
 */
int ilf_options_take(void *dst, size_t dst_size, const void *src, size_t least);

#endif /* ILF_OPTIONS_H */
