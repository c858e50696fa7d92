/*
 * test_radmap_mpi.c - lfio_radmap_write_each_mpi() (lfio/radmap_mpi.h), run
 * under mpirun with any number of ranks (ctest runs 1, 2 and 3):
 *   - a file written by every rank together reads back through
 *     lfio_radmap_read() with exactly the patches given, and holds what the
 *     serial writer writes (empty patches and a 100,000-cell one included),
 *     in format 2 byte for byte, or in format 1 when asked; fewer patches
 *     than ranks too;
 *   - the 100,000-cell patch (7 chunks of each cell dataset) first, then
 *     last: with 3 ranks, ranks holding runs shorter than a chunk, and rows
 *     sent to a rank two ahead and two back (ranks own the chunks by an even
 *     deal of the cells, not of the patches): the serial writer's bytes again;
 *   - a describe() that fails on the last rank alone fails the write on every
 *     rank (with "another rank" in the others' messages), leaves an existing
 *     file as it was and no temporary beside it;
 *   - a patch every rank refuses gives LFIO_ERR_ARG everywhere, the same way;
 *   - lfio_radmap_write_rows_mpi(), every rank holding every cell, in both
 *     orders, with rows NULL and with a rows function: the serial writer's
 *     bytes; rows is asked for each patch after describing it, slices of at
 *     most LFIO_RADMAP_ROWS_MAX, and every cell of the file once over all
 *     the ranks (no rank takes another's); rows failing on the last rank
 *     alone fails the write everywhere, leaving no file; format 1 reads back;
 *   - 600 patches, whose tables are large enough to be deflated (the last
 *     rank compresses them for rank 0), by both collective writes: the
 *     serial writer's bytes.
 * Every rank prints its own "N passed, M failed" line; the exit status is
 * nonzero on a rank that failed, which fails the job.
 */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mpi.h>

#include "check.h"
#include "radmap_patches.h"
#include "lfio/radmap.h"
#include "lfio/radmap_mpi.h"

#define NPATCHES 7

static int rank, ranks;
static struct test_patch patches[NPATCHES];
static const char *fail_on_rank_label; /* set: describe() fails for this patch on the last rank */
/* orders of describe_ordered(): the 100,000-cell patch first, then last */
static const size_t orders[2][NPATCHES] = {{3, 0, 1, 2, 4, 5, 6}, {0, 1, 2, 4, 5, 6, 3}};
static int order;
static const size_t *order_map;    /* describe() and rows(): patch k is patches[order_map[k]] (NULL: patches[k]) */
static size_t last_described;      /* the patch describe() gave last, as numbered by the writer */
static uint64_t rows_asked;        /* cells rows() gave on this rank */
static int rows_broken;            /* calls of rows() outside its contract */
static int fail_rows_on_last;      /* set: rows() fails on the last rank */

/* describe(): patch k, failing once on the last rank for the patch labelled fail_on_rank_label. */
static lfio_status describe(void *user, size_t k, lfio_radmap_patch *out)
{
    (void)user;
    last_described = k;
    *out = patches[order_map ? order_map[k] : k].p;
    if (fail_on_rank_label && rank == ranks - 1 && strcmp(out->label, fail_on_rank_label) == 0)
        return LFIO_ERR_NOMEM;
    return LFIO_OK;
}

/* describe(): the patches in the order orders[order]. */
static lfio_status describe_ordered(void *user, size_t k, lfio_radmap_patch *out)
{
    order_map = orders[order];
    lfio_status st = describe(user, k, out);
    order_map = NULL;
    return st;
}

/* lfio_radmap_rows_fn: cells [first, first + count) of patch k (as describe() numbers it with order_map),
 * counted, each call checked against the contract of lfio_radmap_write_rows_mpi(). */
static lfio_status rows(void *user, size_t k, uint32_t first, uint32_t count, lfio_radmap_rows *out)
{
    (void)user;
    const struct test_patch *t = &patches[order_map ? order_map[k] : k];
    if (k != last_described || count > LFIO_RADMAP_ROWS_MAX || first > t->p.ncells || count > t->p.ncells - first)
        rows_broken++;
    else
        rows_asked += count;
    if (fail_rows_on_last && rank == ranks - 1)
        return LFIO_ERR_NOMEM;
    *out = (lfio_radmap_rows){t->ij + 2 * (size_t)first, t->area + first, t->centre + 3 * (size_t)first,
                              t->irradiance + 3 * (size_t)first, t->radiosity + 3 * (size_t)first};
    return LFIO_OK;
}

/* @return 1 if files a and b hold the same bytes, else 0. */
static int same_bytes(const char *a, const char *b)
{
    FILE *fa = fopen(a, "rb"), *fb = fopen(b, "rb");
    int same = fa != NULL && fb != NULL;
    for (int ca = 0, cb = 0; same && ca != EOF;) {
        ca = getc(fa), cb = getc(fb);
        same = ca == cb;
    }
    if (fa)
        fclose(fa);
    if (fb)
        fclose(fb);
    return same;
}

/* @return how many names in folder dir start with prefix. */
static int count_prefixed(const char *dir, const char *prefix)
{
    DIR *d = opendir(dir);
    int n = 0;
    for (struct dirent *e; d && (e = readdir(d)) != NULL;)
        n += strncmp(e->d_name, prefix, strlen(prefix)) == 0;
    if (d)
        closedir(d);
    return n;
}

/* The patches of describe_many(): every made patch but the 100,000-cell one, over and over. */
static const size_t small_patches[6] = {0, 1, 2, 4, 5, 6};
#define MANY 600

/* describe(): patch k is made patch small_patches[k % 6]. */
static lfio_status describe_many(void *user, size_t k, lfio_radmap_patch *out)
{
    lfio_status st = describe(user, small_patches[k % 6], out);
    last_described = k;
    return st;
}

/* Writes MANY patches by both collective writes and by the serial one: the same bytes. */
static void check_many(const char *dir)
{
    char serial[512], each[512], held[512];
    snprintf(serial, sizeof serial, "%s/many-serial-%d.h5", dir, ranks);
    snprintf(each, sizeof each, "%s/many-each-%d.h5", dir, ranks);
    snprintf(held, sizeof held, "%s/many-held-%d.h5", dir, ranks);
    lfio_status st = lfio_radmap_write_each_mpi(each, "test_radmap_mpi", "scene.json", MANY, describe_many, NULL,
                                                MPI_COMM_WORLD);
    CHECK(st == LFIO_OK, "collective write of %d patches: %s", MANY, lfio_errmsg());
    st = lfio_radmap_write_rows_mpi(held, "test_radmap_mpi", "scene.json", MANY, describe_many, NULL, NULL, NULL,
                                    MPI_COMM_WORLD);
    CHECK(st == LFIO_OK, "write of %d patches, every cell held: %s", MANY, lfio_errmsg());
    if (rank == 0) {
        st = lfio_radmap_write_each(serial, "test_radmap_mpi", "scene.json", MANY, describe_many, NULL);
        CHECK(st == LFIO_OK, "serial write of %d patches: %s", MANY, lfio_errmsg());
    }
    MPI_Barrier(MPI_COMM_WORLD);
    CHECK(same_bytes(each, serial), "%s and %s differ", each, serial);
    CHECK(same_bytes(held, serial), "%s and %s differ", held, serial);
    MPI_Barrier(MPI_COMM_WORLD);
}

/* Writes path by lfio_radmap_write_rows_mpi(), every rank holding every cell, count patches in order o
 * (NULL: as made), their cells from rows() (with_rows) or described. @return its status. */
static lfio_status write_held(const char *path, size_t count, const size_t *o, int with_rows, int format)
{
    lfio_radmap_write_options opt;
    lfio_radmap_write_options_init(&opt);
    opt.format_version = format;
    order_map = o;
    lfio_status st = lfio_radmap_write_rows_mpi(path, "test_radmap_mpi", "scene.json", count, describe,
                                                with_rows ? rows : NULL, NULL, &opt, MPI_COMM_WORLD);
    order_map = NULL;
    return st;
}

/* lfio_radmap_write_rows_mpi() in both orders and without or with rows(): the serial writer's bytes, every
 * cell asked once over the ranks; then rows() failing on one rank, then format 1. */
static void check_write_held(const char *dir)
{
    uint64_t cells = 0;
    for (int k = 0; k < NPATCHES; k++)
        cells += patches[k].p.ncells;
    for (int o = 0; o < 2; o++)
        for (int with_rows = 0; with_rows < 2; with_rows++) {
            char held[512], serial[512];
            snprintf(held, sizeof held, "%s/held%d%d-%d.h5", dir, o, with_rows, ranks);
            snprintf(serial, sizeof serial, "%s/order%d-serial-%d.h5", dir, o, ranks);
            rows_asked = 0, rows_broken = 0;
            lfio_status st = write_held(held, NPATCHES, orders[o], with_rows, 2);
            CHECK(st == LFIO_OK, "write with every cell held, order %d, rows %d: %s", o, with_rows, lfio_errmsg());
            uint64_t asked = 0;
            int broken = 0;
            MPI_Allreduce(&rows_asked, &asked, 1, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
            MPI_Allreduce(&rows_broken, &broken, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
            CHECK(broken == 0, "order %d: %d calls of rows() broke its contract", o, broken);
            if (with_rows)
                CHECK(asked == cells, "order %d: rows() gave %llu cells over the ranks, the file has %llu", o,
                      (unsigned long long)asked, (unsigned long long)cells);
            MPI_Barrier(MPI_COMM_WORLD);
            CHECK(same_bytes(held, serial), "%s and %s differ", held, serial);
            MPI_Barrier(MPI_COMM_WORLD);
        }

    /* one cell: no cell dataset deflated, rank 0 takes them itself */
    static const size_t tiny_only[1] = {4};
    char tiny[512], tiny_serial[512];
    snprintf(tiny, sizeof tiny, "%s/held-tiny-%d.h5", dir, ranks);
    snprintf(tiny_serial, sizeof tiny_serial, "%s/serial-tiny-%d.h5", dir, ranks);
    CHECK(patches[4].p.ncells > 0 && patches[4].p.ncells < 16, "the tiny patch has %u cells", patches[4].p.ncells);
    CHECK(write_held(tiny, 1, tiny_only, 1, 2) == LFIO_OK, "one cell, every cell held: %s", lfio_errmsg());
    if (rank == 0) {
        order_map = tiny_only;
        CHECK(lfio_radmap_write_each(tiny_serial, "test_radmap_mpi", "scene.json", 1, describe, NULL) == LFIO_OK,
              "serial write of one cell: %s", lfio_errmsg());
        order_map = NULL;
    }
    MPI_Barrier(MPI_COMM_WORLD);
    CHECK(same_bytes(tiny, tiny_serial), "%s and %s differ", tiny, tiny_serial);
    MPI_Barrier(MPI_COMM_WORLD);

    /* rows() fails on the last rank alone: every rank fails, no file, no temporary */
    char failed[512];
    snprintf(failed, sizeof failed, "%s/heldfail-%d.h5", dir, ranks);
    fail_rows_on_last = 1;
    lfio_status st = write_held(failed, NPATCHES, NULL, 1, 2);
    fail_rows_on_last = 0;
    CHECK(st != LFIO_OK, "rank %d: a write whose rows() failed on rank %d succeeded", rank, ranks - 1);
    if (rank != ranks - 1)
        CHECK(strstr(lfio_errmsg(), "another rank") != NULL, "rank %d: message '%s'", rank, lfio_errmsg());
    MPI_Barrier(MPI_COMM_WORLD);
    CHECK(count_prefixed(dir, "heldfail-") == 0, "a file or temporary is left for %s", failed);
    MPI_Barrier(MPI_COMM_WORLD);

    /* format 1: each rank's patches asked whole */
    char v1[512];
    snprintf(v1, sizeof v1, "%s/held-format1-%d.h5", dir, ranks);
    st = write_held(v1, NPATCHES, NULL, 1, 1);
    CHECK(st == LFIO_OK, "format 1 with every cell held: %s", lfio_errmsg());
    MPI_Barrier(MPI_COMM_WORLD);
    lfio_radmap *a = NULL;
    CHECK(lfio_radmap_read(v1, &a) == LFIO_OK && lfio_radmap_format_version(a) == 1
              && lfio_radmap_count(a) == NPATCHES, "read %s: %s", v1, lfio_errmsg());
    for (size_t k = 0; a && k < NPATCHES && k < lfio_radmap_count(a); k++) {
        lfio_radmap_patch pa;
        char what[64];
        snprintf(what, sizeof what, "format 1 held, rank %d, patch %zu", rank, k);
        CHECK(lfio_radmap_get(a, k, &pa) == LFIO_OK, "%s: get", what);
        check_patch_equal(&pa, &patches[k].p, what);
    }
    lfio_radmap_destroy(a);
    MPI_Barrier(MPI_COMM_WORLD);
}

int main(int argc, char **argv)
{
    MPI_Init(&argc, &argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &ranks);
    const char *dir = argc > 1 ? argv[1] : ".";
    char shared[512], serial[512];
    snprintf(shared, sizeof shared, "%s/shared-%d.h5", dir, ranks);
    snprintf(serial, sizeof serial, "%s/serial-%d.h5", dir, ranks);

    static const char *labels[NPATCHES] = {"floor", "empty", "wall", "big", "tiny", "ceiling", "sparse"};
    const double sides[NPATCHES] = {2, 0.5, 1.5, 10, 0.3, 2, 4};
    const double cells[NPATCHES] = {0.1, 0.1, 0.25, 0.03125, 0.3, 0.5, 0.2};
    for (int k = 0; k < NPATCHES; k++)
        make_patch(&patches[k], labels[k], (uint32_t)k, sides[k], 0.5 * k, cells[k], k == 6 ? 3 : 0);
    patches[1].p.ncells = 0; /* a patch with no cells */

    /* Written together, read back, equal to what the serial writer writes. */
    lfio_status st = lfio_radmap_write_each_mpi(shared, "test_radmap_mpi", "scene.json", NPATCHES, describe, NULL,
                                                MPI_COMM_WORLD);
    CHECK(st == LFIO_OK, "collective write: %s", lfio_errmsg());
    if (rank == 0) {
        st = lfio_radmap_write_each(serial, "test_radmap_mpi", "scene.json", NPATCHES, describe, NULL);
        CHECK(st == LFIO_OK, "serial write: %s", lfio_errmsg());
    }
    MPI_Barrier(MPI_COMM_WORLD);
    lfio_radmap *a = NULL, *b = NULL;
    CHECK(lfio_radmap_read(shared, &a) == LFIO_OK, "read %s: %s", shared, lfio_errmsg());
    CHECK(lfio_radmap_read(serial, &b) == LFIO_OK, "read %s: %s", serial, lfio_errmsg());
    if (a && b) {
        CHECK(lfio_radmap_count(a) == NPATCHES && lfio_radmap_count(b) == NPATCHES, "patch counts");
        CHECK(strcmp(lfio_radmap_creator(a), "test_radmap_mpi") == 0 && strcmp(lfio_radmap_scene(a), "scene.json") == 0,
              "creator and scene");
        for (size_t k = 0; k < NPATCHES && k < lfio_radmap_count(a); k++) {
            lfio_radmap_patch pa, pb;
            char what[64];
            snprintf(what, sizeof what, "rank %d, patch %zu", rank, k);
            CHECK(lfio_radmap_get(a, k, &pa) == LFIO_OK && lfio_radmap_get(b, k, &pb) == LFIO_OK, "%s: get", what);
            check_patch_equal(&pa, &patches[k].p, what);
            check_patch_equal(&pa, &pb, what);
        }
    }
    CHECK(lfio_radmap_format_version(a) == 2 && lfio_radmap_format_version(b) == 2, "format 2 written");
    CHECK(same_bytes(shared, serial), "%s and %s differ", shared, serial);
    lfio_radmap_destroy(a);
    lfio_radmap_destroy(b);
    MPI_Barrier(MPI_COMM_WORLD);

    /* Runs shorter than a chunk, rows traded forward and back over two ranks (with 3 ranks). */
    for (order = 0; order < 2; order++) {
        char shared_big[512], serial_big[512];
        snprintf(shared_big, sizeof shared_big, "%s/order%d-shared-%d.h5", dir, order, ranks);
        snprintf(serial_big, sizeof serial_big, "%s/order%d-serial-%d.h5", dir, order, ranks);
        st = lfio_radmap_write_each_mpi(shared_big, "test_radmap_mpi", "scene.json", NPATCHES, describe_ordered, NULL,
                                        MPI_COMM_WORLD);
        CHECK(st == LFIO_OK, "collective write, order %d: %s", order, lfio_errmsg());
        if (rank == 0) {
            st = lfio_radmap_write_each(serial_big, "test_radmap_mpi", "scene.json", NPATCHES, describe_ordered, NULL);
            CHECK(st == LFIO_OK, "serial write, order %d: %s", order, lfio_errmsg());
        }
        MPI_Barrier(MPI_COMM_WORLD);
        CHECK(same_bytes(shared_big, serial_big), "%s and %s differ", shared_big, serial_big);
        CHECK(!same_bytes(shared_big, serial), "the comparison can fail: %s and %s are the same", shared_big, serial);
        MPI_Barrier(MPI_COMM_WORLD);
    }

    check_write_held(dir);
    check_many(dir);

    /* Format 1 on request, and format 2 of fewer patches than ranks (a rank with no cells of its own). */
    for (size_t v = 1; v <= 2; v++) {
        char path[512];
        const size_t count = v == 1 ? NPATCHES : 2;
        snprintf(path, sizeof path, "%s/format%zu-%d.h5", dir, v, ranks);
        lfio_radmap_write_options opt;
        lfio_radmap_write_options_init(&opt);
        opt.format_version = (int)v;
        st = lfio_radmap_write_with_mpi(path, "test_radmap_mpi", NULL, count, describe, NULL, &opt, MPI_COMM_WORLD);
        CHECK(st == LFIO_OK, "collective write of format %zu: %s", v, lfio_errmsg());
        MPI_Barrier(MPI_COMM_WORLD);
        CHECK(lfio_radmap_read(path, &a) == LFIO_OK && lfio_radmap_format_version(a) == (int)v
                  && lfio_radmap_count(a) == count, "read %s: %s", path, lfio_errmsg());
        for (size_t k = 0; a && k < count && k < lfio_radmap_count(a); k++) {
            lfio_radmap_patch pa;
            char what[64];
            snprintf(what, sizeof what, "format %zu, rank %d, patch %zu", v, rank, k);
            CHECK(lfio_radmap_get(a, k, &pa) == LFIO_OK, "%s: get", what);
            check_patch_equal(&pa, &patches[k].p, what);
        }
        lfio_radmap_destroy(a);
        a = NULL;
        MPI_Barrier(MPI_COMM_WORLD);
    }

    /* One rank fails to describe a patch: every rank fails, the old file stays, no temporary. */
    fail_on_rank_label = "tiny";
    st = lfio_radmap_write_each_mpi(shared, "second", "other.json", NPATCHES, describe, NULL, MPI_COMM_WORLD);
    fail_on_rank_label = NULL;
    CHECK(st != LFIO_OK, "rank %d: a write that failed on rank %d succeeded", rank, ranks - 1);
    if (rank != ranks - 1)
        CHECK(strstr(lfio_errmsg(), "another rank") != NULL, "rank %d: message '%s'", rank, lfio_errmsg());
    MPI_Barrier(MPI_COMM_WORLD);
    CHECK(lfio_radmap_read(shared, &a) == LFIO_OK && strcmp(lfio_radmap_creator(a), "test_radmap_mpi") == 0,
          "the file written before is untouched: %s", lfio_errmsg());
    lfio_radmap_destroy(a);
    CHECK(count_prefixed(dir, "shared-") == 1, "a temporary is left beside %s", shared);
    MPI_Barrier(MPI_COMM_WORLD); /* rank 0 must not start the next write while others still look */

    /* A patch every rank refuses. */
    patches[2].p.cell_size = -1;
    st = lfio_radmap_write_each_mpi(shared, "third", NULL, NPATCHES, describe, NULL, MPI_COMM_WORLD);
    CHECK(st == LFIO_ERR_ARG && strstr(lfio_errmsg(), "wall") != NULL, "rank %d: bad patch gave %d '%s'", rank,
          (int)st, lfio_errmsg());
    patches[2].p.cell_size = 0.25;
    MPI_Barrier(MPI_COMM_WORLD);
    CHECK(count_prefixed(dir, "shared-") == 1, "a temporary is left beside %s", shared);

    for (int k = 0; k < NPATCHES; k++)
        free_patch(&patches[k]);
    int code = check_report();
    MPI_Finalize();
    return code;
}
