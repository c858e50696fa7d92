/*
 * fuzz_points.c - libFuzzer target for the points file of `ilf irradiance`
 * (tools/points_file.c): each input is written as a file and read whole. A
 * read may fail; it must not crash, leak, overflow or hang, and what it
 * keeps must be six finite numbers per point with a nonzero normal.
 */
#include <math.h>
#include <stdlib.h>

#include "fuzz_file.h"
#include "points_file.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    point_list list = {NULL, 0, 0};
    int code = points_read(fuzz_file_write("points.txt", data, size), &list);
    for (size_t k = 0; code == 0 && k < list.count; k++) {
        const double *p = list.values + 6 * k;
        for (int c = 0; c < 6; c++)
            if (!isfinite(p[c]))
                abort();
        if (p[3] == 0.0 && p[4] == 0.0 && p[5] == 0.0)
            abort();
    }
    points_free(&list);
    return 0;
}
