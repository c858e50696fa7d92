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
 *   - a patch every rank refuses gives LFIO_ERR_ARG everywhere, the same way.
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

/* describe(): patch k, failing once on the last rank for the patch labelled fail_on_rank_label. */
static lfio_status describe(void *user, size_t k, lfio_radmap_patch *out)
{
    (void)user;
    *out = patches[k].p;
    if (fail_on_rank_label && rank == ranks - 1 && strcmp(out->label, fail_on_rank_label) == 0)
        return LFIO_ERR_NOMEM;
    return LFIO_OK;
}

/* describe(): the patches in the order orders[order]. */
static lfio_status describe_ordered(void *user, size_t k, lfio_radmap_patch *out)
{
    return describe(user, orders[order][k], out);
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
