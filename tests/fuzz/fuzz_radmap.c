/*
 * fuzz_radmap.c - libFuzzer target for the radiance-map reader: each input
 * is a radiance-map file read with lfio_radmap_read() and through
 * lfio_radmap_headers (every patch got, as `ilf info` does). The seeds in
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
    const char *path = fuzz_file_write("radiance.h5", data, size);
    lfio_radmap *map = NULL;
    if (lfio_radmap_read(path, &map) == LFIO_OK)
        lfio_radmap_destroy(map);
    lfio_radmap_headers *h = NULL;
    lfio_status st = lfio_radmap_headers_open(path, &h);
    lfio_radmap_patch p;
    for (size_t k = 0; st == LFIO_OK && k < lfio_radmap_headers_count(h); k++)
        st = lfio_radmap_headers_get(h, k, &p);
    lfio_radmap_headers_close(h);
    return 0;
}
