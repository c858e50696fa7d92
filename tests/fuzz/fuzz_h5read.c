/*
 * fuzz_h5read.c - libFuzzer target for what lfio trusts in an HDF5 file: each
 * input, as arbitrary bytes, is opened as a light field with
 * lfio_reader_open() and read the ways a reader reads (a direction, a
 * position and the coverage of every slab: HDF5's own filters run on the
 * chunks these touch, after lfio has vetted them), then read whole as a
 * radiance-map file with lfio_radmap_read(). The seeds in
 * corpus/fuzz_h5read/ are small valid files and the crafted-storage cases of
 * the hostile suite (a chunk under its checksum, a skipped checksum, a bomb,
 * v1 B-tree cycles, external and virtual data) and its own findings. Any
 * call may fail; none may crash, leak, overflow, hang or allocate beyond
 * what the file's size justifies.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include "fuzz_file.h"
#include "lfio/lightfield.h"
#include "lfio/radmap.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Reads direction 0, position (0, 0) and the coverage of slab k of r, whose description d was checked. */
static void read_slab_parts(lfio_reader *r, size_t k, const lfio_slab_desc *d)
{
    const size_t npos = (size_t)d->nu * d->nv, ndir = 4 * (size_t)d->n * d->n;
    /* the reader checked the slab against LFIO_SLAB_MAX_BYTES; a fuzzer's memory is smaller */
    if (npos > ((size_t)1 << 22) || ndir > ((size_t)1 << 22) || npos * ndir > ((size_t)1 << 24))
        return;
    float *img = malloc(npos * 3 * sizeof *img), *rgb = malloc(ndir * 3 * sizeof *rgb);
    uint8_t *coverage = lfio_reader_has_coverage(r, k) ? malloc(npos * ndir) : NULL;
    if (img)
        lfio_reader_read_direction(r, k, 0, img);
    if (rgb)
        lfio_reader_read_position(r, k, 0, 0, rgb);
    if (coverage)
        lfio_reader_read_coverage(r, k, coverage);
    free(coverage);
    free(rgb);
    free(img);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_file_write("input.h5", data, size);
    lfio_reader *r = NULL;
    if (lfio_reader_open(path, &r) == LFIO_OK) {
        for (size_t k = 0; k < lfio_reader_slab_count(r); k++)
            read_slab_parts(r, k, lfio_reader_slab_desc(r, k));
        lfio_reader_close(r);
    }
    lfio_radmap *map = NULL;
    if (lfio_radmap_read(path, &map) == LFIO_OK)
        lfio_radmap_destroy(map);
    return 0;
}
