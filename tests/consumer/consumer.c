/* consumer.c - a minimal program against an installed lfio: it makes a slab,
 * writes it to a file, reads it back and checks one value. */
#include <stdio.h>
#include <string.h>

#include <lfio/lightfield.h>
#include <lfio/partition.h>

int main(int argc, char **argv)
{
    lfio_slab_desc d;
    lfio_slab *s = NULL;
    lfio_lightfield *lf = NULL, *back = NULL;
    float rgb[3] = {1.5f, 2.5f, 3.5f}, got[3 * 4];
    if (argc < 2)
        return 2;
    lfio_slab_desc_init(&d);
    strcpy(d.name, "consumer");
    if (lfio_slab_new(&d, &s) || lfio_slab_write(s, 3, 0, 0, rgb) || lfio_lightfield_new(&lf) ||
        lfio_lightfield_take_slab(lf, s) || lfio_lightfield_write(lf, argv[1]) ||
        lfio_lightfield_read(argv[1], &back)) {
        fprintf(stderr, "consumer: %s\n", lfio_errmsg());
        return 1;
    }
    lfio_slab_read_position(lfio_lightfield_slab(back, 0), 0, 0, got);
    int ok = got[9] == 1.5f && got[11] == 3.5f;
    printf("consumer: lfio %s, %s\n", lfio_version(), ok ? "round trip ok" : "round trip WRONG");
    lfio_lightfield_destroy(lf);
    lfio_lightfield_destroy(back);
    return ok ? 0 : 1;
}
