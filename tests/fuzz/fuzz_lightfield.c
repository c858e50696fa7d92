/*
 * fuzz_lightfield.c - libFuzzer target for the light field reader: each
 * input is a light field file read whole with lfio_lightfield_read() and
 * checked completely with lfio_verify(). The seeds in
 * corpus/fuzz_lightfield/ are small files from `ilf synth`, whole and cut.
 * Either call may fail; neither may crash, leak or overflow.
 */
#include <stddef.h>
#include <stdint.h>

#include "fuzz_file.h"
#include "lfio/lightfield.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *path = fuzz_file_write("lightfield.h5", data, size);
    lfio_lightfield *lf = NULL;
    if (lfio_lightfield_read(path, &lf) == LFIO_OK)
        lfio_lightfield_destroy(lf);
    lfio_verify(path, NULL);
    return 0;
}
