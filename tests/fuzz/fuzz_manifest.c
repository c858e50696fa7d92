/*
 * fuzz_manifest.c - libFuzzer target for the capture manifest reader: each
 * input is a manifest handed to cap_manifest_load(). Images it names are
 * looked up beside it, in the target's temporary folder, where nothing else
 * exists, so only the JSON, the plane, the grid, the patterns and the
 * brackets are exercised; when a manifest loads, every position is asked
 * for. The seeds in corpus/fuzz_manifest/ are small valid and invalid
 * manifests. A load may fail; it must not crash, leak or overflow.
 */
#include <stddef.h>
#include <stdint.h>

#include "capture/capture.h"
#include "fuzz_file.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    cap_manifest *m = NULL;
    if (cap_manifest_load(fuzz_file_write("manifest.json", data, size), &m) != CAP_OK)
        return 0;
    for (size_t q = 0; q < cap_manifest_plane_count(m); q++) {
        const lfio_slab_desc *d = cap_manifest_get_desc(m, q);
        for (uint32_t j = 0; j < d->nv && j < 64; j++)
            for (uint32_t i = 0; i < d->nu && i < 64; i++) {
                cap_position_info info;
                cap_manifest_get_position(m, q, i, j, &info);
            }
    }
    cap_manifest_destroy(m);
    return 0;
}
