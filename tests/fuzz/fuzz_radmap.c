/*
 * fuzz_radmap.c - libFuzzer target for the radiance-map reader: each input
 * is a radiance-map file read with lfio_radmap_read(). The seeds in
 * corpus/fuzz_radmap/ are small radiance.h5 files from `ilf relight`, whole
 * and cut. A read may fail; it must not crash, leak or overflow.
 */
#include <stddef.h>
#include <stdint.h>

#include "fuzz_file.h"
#include "lfio/radmap.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    lfio_radmap *map = NULL;
    if (lfio_radmap_read(fuzz_file_write("radiance.h5", data, size), &map) == LFIO_OK)
        lfio_radmap_destroy(map);
    return 0;
}
