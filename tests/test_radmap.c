/*
 * test_radmap.c - radiance-map files (lfio/radmap.h, lfio/src/radmap_io.c):
 * round trips (with an empty patch, an empty file and a patch spanning
 * several chunks), the headers read whole and a block at a time
 * (lfio_radmap_headers), writes a slice of cells at a time, the writer's refusals, atomic writes, and every way a
 * file can be bad.
 *
 * Bad files are made by writing a good file with lfio and changing one
 * thing with the HDF5 API, or by truncating it or flipping one byte of a
 * chunk. Each failure must give the expected status and a message naming
 * the file (and the object where one is given), leave the output NULL and
 * print nothing: HDF5's error printer stays on in this program and stderr
 * is captured around each lfio call to prove that lfio silences it.
 *
 * Files go to $ILF_TEST_TMP/radmap (or /tmp/radmap).
 */
#define _POSIX_C_SOURCE 200809L

#include <dirent.h>
#include <signal.h>
#include <sys/resource.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <hdf5.h>

#include "check.h"
#include "h5edit.h"
#include "radmap_patches.h"
#include "lfio/radmap.h"

/* lfio's rows per cell chunk (radmap_io.c's CELL_CHUNK): a slice's second part spans more than one. */
#define CELL_CHUNK_ROWS 16384u

static char tmpdir[400];

/* ------------------------------------------------------------------ files */

/* Writes tmpdir/name into buf. @return buf. */
static char *tmp_path(char *buf, size_t size, const char *name)
{
    snprintf(buf, size, "%s/%s", tmpdir, name);
    return buf;
}

/* Reads a whole file. @return a malloc'd buffer and *size, or NULL. */
static unsigned char *read_whole(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    unsigned char *buf = NULL;
    long len = -1;
    if (f && fseek(f, 0, SEEK_END) == 0 && (len = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0
        && (buf = malloc((size_t)len + 1)) != NULL && fread(buf, 1, (size_t)len, f) != (size_t)len) {
        free(buf);
        buf = NULL;
    }
    if (f)
        fclose(f);
    *size = len > 0 ? (size_t)len : 0;
    return buf;
}

/* Replaces path with size bytes of data. @return 1 on success. */
static int write_whole(const char *path, const void *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    int ok = f && fwrite(data, 1, size, f) == size;
    return f && fclose(f) == 0 && ok;
}

/* Makes tmpdir/name a copy of src. @return its path in buf. */
static char *copy_to(char *buf, size_t size, const char *src, const char *name)
{
    size_t n;
    unsigned char *data = read_whole(src, &n);
    tmp_path(buf, size, name);
    CHECK(data && write_whole(buf, data, n), "copy %s to %s", src, buf);
    free(data);
    return buf;
}

/* Removes every file of tmpdir; with only_temporaries, counts the ".tmp-" ones instead. @return that count. */
static int sweep_tmpdir(int only_temporaries)
{
    DIR *dir = opendir(tmpdir);
    int count = 0;
    for (struct dirent *e; dir && (e = readdir(dir)) != NULL;) {
        char p[768];
        if (only_temporaries)
            count += strstr(e->d_name, ".tmp-") != NULL;
        else if (e->d_name[0] != '.')
            unlink((snprintf(p, sizeof p, "%s/%s", tmpdir, e->d_name), p));
    }
    if (dir)
        closedir(dir);
    return count;
}

/* stderr redirection around lfio calls: they must print nothing. */
static void quiet_start(void)
{
    char p[512];
    check_stderr_begin(tmp_path(p, sizeof p, "stderr.txt"));
}
#define quiet_stop check_stderr_end

/* A describe function over an array that fails at patch fail_at (SIZE_MAX: never). */
struct describer {
    const lfio_radmap_patch *patches;
    size_t fail_at, asked;
};

/* lfio_radmap_write_with()'s describe over an array (struct describer above). */
static lfio_status describe_some(void *user, size_t k, lfio_radmap_patch *out);

/* Writes count patches to path, checking success and silence: with lfio_radmap_write() for threads 0 (the
 * default), else with lfio_radmap_write_with() compressing on that many threads. */
static void write_ok(const char *path, const lfio_radmap_patch *patches, size_t count, unsigned threads)
{
    lfio_radmap_write_options opt;
    lfio_radmap_write_options_init(&opt);
    opt.threads = threads;
    quiet_start();
    lfio_status st = threads == 0 ? lfio_radmap_write(path, "test_radmap", "scenes/test.json", patches, count)
                                  : lfio_radmap_write_with(path, "test_radmap", "scenes/test.json", count, describe_some,
                                                           NULL, &(struct describer){patches, SIZE_MAX, 0}, &opt);
    long printed = quiet_stop();
    CHECK(st == LFIO_OK, "write %s: %s", path, lfio_errmsg());
    CHECK(printed == 0, "write printed %ld bytes", printed);
}

/* ------------------------------------------------------------------- tests */

/* Writes patches (compressed on threads threads; 0: lfio_radmap_write()), reads them back and compares
 * everything. */
static void test_round_trip(const lfio_radmap_patch *patches, size_t count, const char *path, unsigned threads)
{
    write_ok(path, patches, count, threads);
    CHECK(sweep_tmpdir(1) == 0, "temporaries left after a good write");
    lfio_radmap *map = NULL;
    quiet_start();
    lfio_status st = lfio_radmap_read(path, &map);
    long printed = quiet_stop();
    CHECK(st == LFIO_OK && map != NULL, "read %s: %s", path, lfio_errmsg());
    CHECK(printed == 0, "read printed %ld bytes", printed);
    if (map == NULL)
        return;
    CHECK(strcmp(lfio_radmap_creator(map), "test_radmap") == 0, "creator '%s'", lfio_radmap_creator(map));
    CHECK(strcmp(lfio_radmap_scene(map), "scenes/test.json") == 0, "scene '%s'", lfio_radmap_scene(map));
    CHECK(lfio_radmap_count(map) == count, "count %zu, expected %zu", lfio_radmap_count(map), count);
    for (size_t k = 0; k < count && k < lfio_radmap_count(map); k++) {
        lfio_radmap_patch back;
        CHECK(lfio_radmap_get(map, k, &back) == LFIO_OK, "get %zu", k);
        check_patch_equal(&patches[k], &back, patches[k].label);
    }
    lfio_radmap_patch none;
    CHECK(lfio_radmap_get(map, count, &none) == LFIO_ERR_ARG, "get out of range");
    CHECK(lfio_radmap_get(NULL, 0, &none) == LFIO_ERR_ARG, "get from NULL");
    lfio_radmap_destroy(map);
    lfio_radmap_destroy(NULL);
    CHECK(lfio_radmap_count(NULL) == 0 && strcmp(lfio_radmap_creator(NULL), "") == 0, "NULL accessors");
}


static lfio_status describe_some(void *user, size_t k, lfio_radmap_patch *out)
{
    struct describer *d = user;
    CHECK(k == d->asked, "describe asked for patch %zu after %zu", k, d->asked);
    d->asked++;
    if (k == d->fail_at)
        return LFIO_ERR_NOMEM;
    *out = d->patches[k];
    return LFIO_OK;
}

/* lfio_radmap_write_each(): the same content as lfio_radmap_write() (the bytes differ only in HDF5's
 * object times), patches asked in order, once; a describe that fails abandons the write with its
 * status and leaves an existing file as it was. */
static void test_write_each(const lfio_radmap_patch *patches, size_t count)
{
    char path[512];
    struct describer d = {patches, SIZE_MAX, 0};
    quiet_start();
    lfio_status st = lfio_radmap_write_each(tmp_path(path, sizeof path, "each.h5"), "test_radmap", "scenes/test.json",
                                            count, describe_some, &d);
    quiet_stop();
    CHECK(st == LFIO_OK && d.asked == count, "write_each: %s, %zu asked", lfio_errmsg(), d.asked);
    lfio_radmap *map = NULL;
    CHECK(lfio_radmap_read(path, &map) == LFIO_OK && lfio_radmap_count(map) == count, "read back: %s",
          lfio_errmsg());
    for (size_t k = 0; map != NULL && k < count && k < lfio_radmap_count(map); k++) {
        lfio_radmap_patch back;
        CHECK(lfio_radmap_get(map, k, &back) == LFIO_OK, "get %zu", k);
        check_patch_equal(&patches[k], &back, patches[k].label);
    }
    lfio_radmap_destroy(map);
    size_t a_size = 0;
    unsigned char *a = read_whole(path, &a_size);
    struct describer fail = {patches, 1, 0};
    quiet_start();
    st = lfio_radmap_write_each(path, NULL, NULL, count, describe_some, &fail);
    quiet_stop();
    CHECK(st == LFIO_ERR_NOMEM && fail.asked == 2, "a failing describe: status %d, %zu asked", (int)st, fail.asked);
    size_t c_size = 0;
    unsigned char *c = read_whole(path, &c_size);
    CHECK(c && c_size == a_size && memcmp(a, c, a_size) == 0, "a failed write_each changed the file");
    CHECK(sweep_tmpdir(1) == 0, "temporaries left after a failed write_each");
    CHECK(lfio_radmap_write_each(path, NULL, NULL, 1, NULL, NULL) == LFIO_ERR_ARG, "NULL describe");
    free(a);
    free(c);
}

/* Describes patches without their cells, and gives the cells a slice at a time from buffers of its own (as
 * a caller of lfio_radmap_write_rows() would), checking that lfio asks for the patches in order, for each
 * cell once, in order, after its patch is described, at most LFIO_RADMAP_ROWS_MAX at once; it fails
 * (fail_first) or gives a bad irradiance (bad_cell) when told. */
struct slicer {
    const lfio_radmap_patch *patches;
    size_t described, calls; /* described: patches [0, described) were */
    size_t rows_k;           /* the patch whose cells are being asked for (SIZE_MAX: none yet) */
    uint32_t next, max_count;
    size_t bad_patch, fail_patch; /* SIZE_MAX: never */
    uint32_t bad_cell, fail_first;
    uint32_t *ij;
    double *area, *centre;
    float *irradiance, *radiosity;
};

/* lfio_radmap_describe_fn: patch k without its cells, checking that the patches come in order. @return LFIO_OK. */
static lfio_status describe_bare(void *user, size_t k, lfio_radmap_patch *out)
{
    struct slicer *s = user;
    CHECK(k == s->described, "patch %zu described after %zu", k, s->described);
    *out = s->patches[k];
    out->cell_ij = NULL, out->cell_area = NULL, out->cell_centre = NULL;
    out->irradiance = NULL, out->radiosity = NULL;
    s->described = k + 1;
    return LFIO_OK;
}

/* lfio_radmap_rows_fn: the cells asked for, copied into the slicer's buffers.
 * @return LFIO_OK; LFIO_ERR_NOMEM where told to fail; LFIO_ERR_ARG for a range lfio must not ask. */
static lfio_status rows_copied(void *user, size_t k, uint32_t first, uint32_t count, lfio_radmap_rows *out)
{
    struct slicer *s = user;
    const lfio_radmap_patch *p = &s->patches[k];
    if (k != s->rows_k) {
        /* the next patch, once every cell of the one before was asked for */
        CHECK(s->rows_k == SIZE_MAX ? k == 0 : k == s->rows_k + 1 && s->next == s->patches[s->rows_k].ncells,
              "rows asked for patch %zu after patch %zu left at cell %u", k, s->rows_k, s->next);
        s->rows_k = k;
        s->next = 0;
    }
    CHECK(k < s->described && first == s->next && count <= LFIO_RADMAP_ROWS_MAX &&
              (uint64_t)first + count <= p->ncells,
          "rows asked for patch %zu cells %u + %u (described %zu, next %u, %u cells)", k, first, count, s->described,
          s->next, p->ncells);
    if (!(count <= LFIO_RADMAP_ROWS_MAX && (uint64_t)first + count <= p->ncells))
        return LFIO_ERR_ARG;
    s->next = first + count;
    s->calls++;
    s->max_count = count > s->max_count ? count : s->max_count;
    if (k == s->fail_patch && first == s->fail_first)
        return LFIO_ERR_NOMEM;
    memcpy(s->ij, p->cell_ij + 2 * (size_t)first, 2 * (size_t)count * sizeof *s->ij);
    memcpy(s->area, p->cell_area + first, (size_t)count * sizeof *s->area);
    memcpy(s->centre, p->cell_centre + 3 * (size_t)first, 3 * (size_t)count * sizeof *s->centre);
    memcpy(s->irradiance, p->irradiance + 3 * (size_t)first, 3 * (size_t)count * sizeof *s->irradiance);
    memcpy(s->radiosity, p->radiosity + 3 * (size_t)first, 3 * (size_t)count * sizeof *s->radiosity);
    if (k == s->bad_patch && s->bad_cell >= first && s->bad_cell - first < count)
        s->irradiance[3 * (size_t)(s->bad_cell - first) + 1] = NAN;
    *out = (lfio_radmap_rows){s->ij, s->area, s->centre, s->irradiance, s->radiosity};
    return LFIO_OK;
}

/* Writes patches through lfio_radmap_write_rows() into path (threads 0), or through lfio_radmap_write_with()
 * compressing on threads threads. @return its status; *s its record. */
static lfio_status write_sliced(const char *path, const lfio_radmap_patch *patches, size_t count, struct slicer *s,
                               unsigned threads)
{
    const size_t n = LFIO_RADMAP_ROWS_MAX;
    s->patches = patches;
    s->ij = malloc(2 * n * sizeof *s->ij);
    s->area = malloc(n * sizeof *s->area);
    s->centre = malloc(3 * n * sizeof *s->centre);
    s->irradiance = malloc(3 * n * sizeof *s->irradiance);
    s->radiosity = malloc(3 * n * sizeof *s->radiosity);
    lfio_radmap_write_options opt;
    lfio_radmap_write_options_init(&opt);
    opt.threads = threads;
    quiet_start();
    lfio_status st = threads == 0 ? lfio_radmap_write_rows(path, "test_radmap", "scenes/test.json", count,
                                                           describe_bare, rows_copied, s)
                                  : lfio_radmap_write_with(path, "test_radmap", "scenes/test.json", count,
                                                           describe_bare, rows_copied, s, &opt);
    long printed = quiet_stop();
    CHECK(printed == 0, "write_rows printed %ld bytes", printed);
    free(s->ij);
    free(s->area);
    free(s->centre);
    free(s->irradiance);
    free(s->radiosity);
    return st;
}

/* lfio_radmap_write_rows(): a patch of more cells than one slice is asked for in several, in order, and
 * reads back as written; a bad value in a later slice is refused naming the cell by its place in the
 * patch, and a failing rows abandons the write with its status; both leave an existing file as it was. */
static void test_write_rows(const lfio_radmap_patch *patches, size_t count, const lfio_radmap_patch *big)
{
    CHECK(big->ncells > LFIO_RADMAP_ROWS_MAX + CELL_CHUNK_ROWS, "the big patch has %u cells", big->ncells);
    lfio_radmap_patch all[8];
    for (size_t k = 0; k < count; k++)
        all[k] = patches[k];
    all[count] = *big;
    /* a patch's cells come in ceil(ncells / ROWS_MAX) slices, a patch of no cells in one empty one */
    size_t slices = 0;
    for (size_t k = 0; k <= count; k++)
        slices += all[k].ncells ? (all[k].ncells + LFIO_RADMAP_ROWS_MAX - 1) / LFIO_RADMAP_ROWS_MAX : 1;
    CHECK(slices >= count + 3, "the big patch takes at least three slices (%zu slices in all)", slices);
    char path[512];
    tmp_path(path, sizeof path, "rows.h5");
    /* one thread filters the cells as they come a chunk at a time, three in batches of three chunks (the
     * rest at the end): the same bytes */
    unsigned char *first_file = NULL;
    size_t first_size = 0;
    for (unsigned threads = 1; threads <= 3; threads += 2) {
        struct slicer s = {.rows_k = SIZE_MAX, .bad_patch = SIZE_MAX, .fail_patch = SIZE_MAX};
        lfio_status st = write_sliced(path, all, count + 1, &s, threads);
        CHECK(st == LFIO_OK, "write_rows on %u threads: %s", threads, lfio_errmsg());
        size_t size = 0;
        unsigned char *bytes = read_whole(path, &size);
        if (first_file == NULL)
            first_file = bytes, first_size = size;
        else
            CHECK(bytes && size == first_size && memcmp(bytes, first_file, size) == 0,
                  "write_rows on %u threads wrote other bytes than on one", threads);
        if (bytes != first_file)
            free(bytes);
        CHECK(s.next == big->ncells && s.max_count == LFIO_RADMAP_ROWS_MAX && s.calls == slices,
              "write_rows asked %zu times, at most %u cells, ending at %u", s.calls, s.max_count, s.next);
        lfio_radmap *map = NULL;
        CHECK(lfio_radmap_read(path, &map) == LFIO_OK && lfio_radmap_count(map) == count + 1, "read back: %s",
              lfio_errmsg());
        for (size_t k = 0; map != NULL && k < lfio_radmap_count(map); k++) {
            lfio_radmap_patch back;
            CHECK(lfio_radmap_get(map, k, &back) == LFIO_OK, "get %zu", k);
            check_patch_equal(&all[k], &back, all[k].label);
        }
        lfio_radmap_destroy(map);
    }
    /* the whole patches, described with their cells (lfio_radmap_write()): the same bytes as a slice at a time */
    char whole[512];
    write_ok(tmp_path(whole, sizeof whole, "whole.h5"), all, count + 1, 0);
    size_t whole_size = 0;
    unsigned char *whole_bytes = read_whole(whole, &whole_size);
    CHECK(whole_bytes && whole_size == first_size && memcmp(whole_bytes, first_file, whole_size) == 0,
          "lfio_radmap_write() wrote other bytes than lfio_radmap_write_rows()");
    free(whole_bytes);
    remove(whole);
    free(first_file);
    size_t a_size = 0;
    unsigned char *a = read_whole(path, &a_size);
    const uint32_t bad = LFIO_RADMAP_ROWS_MAX + 1234;
    struct slicer s = {.rows_k = SIZE_MAX, .bad_patch = count, .bad_cell = bad, .fail_patch = SIZE_MAX};
    lfio_status st = write_sliced(path, all, count + 1, &s, 0);
    char want[64];
    snprintf(want, sizeof want, "irradiance of cell %u is nan", bad);
    CHECK(st == LFIO_ERR_ARG && strstr(lfio_errmsg(), want) && strstr(lfio_errmsg(), big->label),
          "a bad value in a later slice: %s: %s", lfio_status_name(st), lfio_errmsg());
    struct slicer f = {.rows_k = SIZE_MAX, .bad_patch = SIZE_MAX, .fail_patch = count, .fail_first = LFIO_RADMAP_ROWS_MAX};
    st = write_sliced(path, all, count + 1, &f, 0);
    /* the second slice fails: lfio asks for no third */
    CHECK(st == LFIO_ERR_NOMEM && f.next == 2 * LFIO_RADMAP_ROWS_MAX, "a failing rows: %s after cell %u",
          lfio_status_name(st), f.next);
    size_t b_size = 0;
    unsigned char *b = read_whole(path, &b_size);
    CHECK(a && b && a_size == b_size && memcmp(a, b, a_size) == 0, "a failed write_rows changed the file");
    CHECK(sweep_tmpdir(1) == 0, "temporaries left after a failed write_rows");
    CHECK(lfio_radmap_write_rows(path, NULL, NULL, 1, NULL, rows_copied, NULL) == LFIO_ERR_ARG, "NULL describe");
    free(a);
    free(b);
}

/* A write that the disk stops part-way (a file size limit of limit bytes: EFBIG, the signal ignored)
 * fails with LFIO_ERR_IO naming the file and the reason, leaves existing as it was and no temporary,
 * and the next write succeeds: lfio's driver kept the error from HDF5 (h5util.c, h5stream.c). */
static void test_write_fails_midway(const lfio_radmap_patch *patches, size_t count, const char *existing,
                                    rlim_t limit)
{
    size_t before_size = 0;
    unsigned char *before = read_whole(existing, &before_size);
    struct rlimit old, small;
    void (*old_handler)(int) = signal(SIGXFSZ, SIG_IGN);
    getrlimit(RLIMIT_FSIZE, &old);
    small = old;
    small.rlim_cur = limit;
    CHECK(setrlimit(RLIMIT_FSIZE, &small) == 0, "setrlimit");
    quiet_start();
    lfio_status st = lfio_radmap_write(existing, "test_radmap", NULL, patches, count);
    long printed = quiet_stop();
    char msg[512];
    snprintf(msg, sizeof msg, "%s", lfio_errmsg());
    setrlimit(RLIMIT_FSIZE, &old);
    signal(SIGXFSZ, old_handler);
    const char *name = strrchr(existing, '/');
    CHECK(st == LFIO_ERR_IO && strstr(msg, name ? name + 1 : existing) && strstr(msg, "too large"),
          "a write stopped at %llu bytes: %s: %s", (unsigned long long)limit, lfio_status_name(st), msg);
    CHECK(printed == 0, "a write stopped part-way printed %ld bytes", printed);
    size_t after_size = 0;
    unsigned char *after = read_whole(existing, &after_size);
    CHECK(before && after && before_size == after_size && memcmp(before, after, before_size) == 0,
          "a write stopped at %llu bytes changed the existing file", (unsigned long long)limit);
    CHECK(sweep_tmpdir(1) == 0, "temporaries left after a write stopped part-way");
    free(before);
    free(after);
    write_ok(existing, patches, count, 0);
}

/* Expects writing p (one patch) to be refused with LFIO_ERR_ARG, a message containing needle, and no file. */
static void expect_refused(const lfio_radmap_patch *p, const char *needle, const char *what)
{
    char path[512];
    tmp_path(path, sizeof path, "refused.h5");
    lfio_status st = lfio_radmap_write(path, NULL, NULL, p, 1);
    CHECK(st == LFIO_ERR_ARG, "%s: write gave %s (%s)", what, lfio_status_name(st), lfio_errmsg());
    CHECK(strstr(lfio_errmsg(), "refused.h5") && strstr(lfio_errmsg(), needle), "%s: message: %s", what,
          lfio_errmsg());
    CHECK(access(path, F_OK) != 0, "%s: a file was created", what);
}

/* The writer refuses every patch the reader would refuse, and fails atomically. */
static void test_writer_refusals(const struct test_patch *good, const char *existing)
{
    lfio_radmap_patch p = good->p;
    p.label = NULL;
    expect_refused(&p, "label", "NULL label");
    p = good->p, p.nverts = 2;
    expect_refused(&p, "vertices", "two vertices");
    p = good->p, p.ncells = p.nu * p.nv + 1;
    expect_refused(&p, "cells in a grid", "more cells than the grid");
    p = good->p, p.cell_size = 0;
    expect_refused(&p, "cell_size", "zero cell size");
    p = good->p, p.e1[0] = 2;
    expect_refused(&p, "unit", "e1 not unit");
    p = good->p, p.normal[2] = -1;
    expect_refused(&p, "normal", "normal not e1 x e2");
    p = good->p, p.albedo[1] = 1.5f;
    expect_refused(&p, "albedo", "albedo above 1");
    p = good->p, p.irradiance = NULL;
    expect_refused(&p, "irradiance is NULL", "NULL irradiance");

    const size_t n = 3 * (size_t)good->p.ncells;
    uint32_t *ij = malloc(2 * (size_t)good->p.ncells * sizeof *ij);
    float *values = malloc(n * sizeof *values);
    double *area = malloc((size_t)good->p.ncells * sizeof *area);
    memcpy(ij, good->ij, 2 * (size_t)good->p.ncells * sizeof *ij);
    memcpy(values, good->irradiance, n * sizeof *values);
    memcpy(area, good->area, (size_t)good->p.ncells * sizeof *area);
    ij[2 * 3 + 1] = good->p.nv;
    p = good->p, p.cell_ij = ij;
    expect_refused(&p, "cell 3", "cell outside the grid");
    values[7] = -1.0f;
    p = good->p, p.radiosity = values;
    expect_refused(&p, "radiosity of cell 2", "negative radiosity");
    values[7] = NAN;
    p = good->p, p.irradiance = values;
    expect_refused(&p, "irradiance of cell 2", "NaN irradiance");
    area[1] = 0;
    p = good->p, p.cell_area = area;
    expect_refused(&p, "area", "zero area");
    free(ij);
    free(values);
    free(area);

    char path[512];
    CHECK(lfio_radmap_write(NULL, NULL, NULL, NULL, 0) == LFIO_ERR_ARG, "NULL path");
    CHECK(lfio_radmap_write(tmp_path(path, sizeof path, "nopatches.h5"), NULL, NULL, NULL, 2) == LFIO_ERR_ARG,
          "NULL patches with a count");

    /* A missing folder fails with LFIO_ERR_IO, silently, creating nothing. */
    quiet_start();
    lfio_status st = lfio_radmap_write(tmp_path(path, sizeof path, "no_such_folder/map.h5"), NULL, NULL, &good->p, 1);
    long printed = quiet_stop();
    CHECK(st == LFIO_ERR_IO && strstr(lfio_errmsg(), "map.h5"), "missing folder: %s: %s", lfio_status_name(st),
          lfio_errmsg());
    CHECK(printed == 0, "missing folder printed %ld bytes", printed);

    /* A refused write over an existing file leaves it exactly as it was. */
    size_t before_size, after_size;
    copy_to(path, sizeof path, existing, "kept.h5");
    unsigned char *before = read_whole(path, &before_size);
    p = good->p, p.cell_size = NAN;
    CHECK(lfio_radmap_write(path, NULL, NULL, &p, 1) == LFIO_ERR_ARG, "NaN cell size over a file");
    unsigned char *after = read_whole(path, &after_size);
    CHECK(before && after && before_size == after_size && memcmp(before, after, before_size) == 0,
          "a refused write changed the existing file");
    free(before);
    free(after);
    CHECK(sweep_tmpdir(1) == 0, "temporaries left after refused writes");
}

/* ------------------------------------------------------- HDF5 file surgery */

/* XORs the middle byte of chunk 0 of dataset dset with 0x5a. @return 1 on success. */
static int flip_chunk_byte(const char *path, const char *dset)
{
    hsize_t offset[2], size = 0;
    haddr_t addr = 0;
    unsigned mask;
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    hid_t d = H5Dopen2(f, dset, H5P_DEFAULT);
    hid_t space = H5Dget_space(d);
    herr_t rc = H5Dget_chunk_info(d, space, 0, offset, &mask, &addr, &size);
    H5Sclose(space);
    H5Dclose(d);
    H5Fclose(f);
    int fd = open(path, O_RDWR);
    unsigned char c = 0;
    int ok = rc >= 0 && size > 8 && fd >= 0 && pread(fd, &c, 1, (off_t)(addr + size / 2)) == 1;
    c ^= 0x5a;
    ok = ok && pwrite(fd, &c, 1, (off_t)(addr + size / 2)) == 1;
    if (fd >= 0)
        close(fd);
    return ok;
}

/* Expects reading path to fail with want, naming the file (and needle), output NULL, nothing printed. */
static void expect_refused_by(lfio_status (*read)(const char *, lfio_radmap **), const char *path, lfio_status want,
                              const char *needle, const char *what)
{
    lfio_radmap *map = (lfio_radmap *)1;
    quiet_start();
    lfio_status st = read(path, &map);
    long printed = quiet_stop();
    const char *msg = lfio_errmsg();
    const char *base = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
    CHECK(st == want, "%s: read gave %s, expected %s (%s)", what, lfio_status_name(st), lfio_status_name(want), msg);
    CHECK(map == NULL, "%s: output not NULL", what);
    CHECK(strstr(msg, base) != NULL, "%s: message does not name the file: %s", what, msg);
    CHECK(needle == NULL || strstr(msg, needle) != NULL, "%s: message lacks '%s': %s", what, needle, msg);
    CHECK(printed == 0, "%s: %ld bytes printed on stderr", what, printed);
    if (st == LFIO_OK)
        lfio_radmap_destroy(map);
}

/* The whole read refuses path with status want and a message naming it and holding needle. */
static void expect_bad(const char *path, lfio_status want, const char *needle, const char *what)
{
    expect_refused_by(lfio_radmap_read, path, want, needle, what);
}

/* Opens path with lfio_radmap_headers_open() and gets every patch, as `ilf info` does. @return the first
 * failure's status, or LFIO_OK; *out is always NULL (for expect_refused_by()). */
static lfio_status read_by_blocks(const char *path, lfio_radmap **out)
{
    *out = NULL;
    lfio_radmap_headers *h = NULL;
    lfio_status st = lfio_radmap_headers_open(path, &h);
    CHECK(st == LFIO_OK || h == NULL, "%s: a failed open leaves its handle NULL", path);
    lfio_radmap_patch p;
    for (size_t k = 0; st == LFIO_OK && k < lfio_radmap_headers_count(h); k++)
        st = lfio_radmap_headers_get(h, k, &p);
    lfio_radmap_headers_close(h);
    return st;
}

/* The three header readers refuse path so: a problem of the tables, offsets or dataset shapes, which the
 * headers show. */
static void expect_bad_headers(const char *path, lfio_status want, const char *needle, const char *what)
{
    expect_refused_by(lfio_radmap_read, path, want, needle, what);
    expect_refused_by(lfio_radmap_read_headers, path, want, needle, what);
    expect_refused_by(read_by_blocks, path, want, needle, what);
}

/* Every documented way a format-1 file can be bad; good has patches 0 (cells), 1 (no cells), 2 (many cells). */
static void test_bad_files(const char *good)
{
    char p[512];
    expect_bad(tmp_path(p, sizeof p, "does_not_exist.h5"), LFIO_ERR_NOTFOUND, NULL, "missing file");
    write_whole(tmp_path(p, sizeof p, "text.h5"), "not a map\n", 10);
    expect_bad(p, LFIO_ERR_FORMAT, "not an HDF5 file", "text file");

    size_t size;
    unsigned char *data = read_whole(good, &size);
    const size_t cuts[] = {0, size / 10, size / 2, size * 9 / 10, size - 1};
    for (size_t c = 0; data && c < sizeof cuts / sizeof cuts[0]; c++) {
        char what[64];
        snprintf(what, sizeof what, "truncated to %zu of %zu bytes", cuts[c], size);
        write_whole(tmp_path(p, sizeof p, "truncated.h5"), data, cuts[c]);
        expect_bad(p, LFIO_ERR_FORMAT, NULL, what);
    }
    free(data);

    copy_to(p, sizeof p, good, "flipped.h5");
    CHECK(flip_chunk_byte(p, "/patches/2/irradiance"), "flip a byte of an irradiance chunk");
    expect_bad(p, LFIO_ERR_CHECKSUM, "/patches/2/irradiance", "flipped irradiance byte");
    copy_to(p, sizeof p, good, "flipped_centre.h5");
    CHECK(flip_chunk_byte(p, "/patches/0/cell_centre"), "flip a byte of a cell_centre chunk");
    expect_bad(p, LFIO_ERR_CHECKSUM, "/patches/0/cell_centre", "flipped cell_centre byte");

    edit_attr_str(copy_to(p, sizeof p, good, "wrong_format.h5"), "/", "format", "ilfkit-lightfield");
    expect_bad(p, LFIO_ERR_FORMAT, "'ilfkit-lightfield', expected 'ilfkit-radiance-maps'", "wrong format string");
    const int32_t three = 3;
    edit_attr(copy_to(p, sizeof p, good, "version3.h5"), "/", "format_version", H5T_STD_I32LE, H5T_NATIVE_INT32, 0,
              &three);
    expect_bad(p, LFIO_ERR_FORMAT, "format_version 3", "format_version 3");
    const uint32_t four = 4, one = 1;
    edit_attr(copy_to(p, sizeof p, good, "count4.h5"), "/", "patch_count", H5T_STD_U32LE, H5T_NATIVE_UINT32, 0,
              &four);
    expect_bad(p, LFIO_ERR_FORMAT, "/patches/3", "patch_count 4 with three groups");
    edit_attr(copy_to(p, sizeof p, good, "small_grid.h5"), "/patches/0", "nv", H5T_STD_U32LE, H5T_NATIVE_UINT32, 0,
              &one);
    expect_bad(p, LFIO_ERR_FORMAT, "cells in a grid", "more cells than nu*nv");
    const double ones[2] = {1, 1};
    edit_attr(copy_to(p, sizeof p, good, "short_origin.h5"), "/patches/0", "origin", H5T_IEEE_F64LE,
              H5T_NATIVE_DOUBLE, 2, ones);
    expect_bad(p, LFIO_ERR_FORMAT, "'origin'", "origin with 2 elements");
    edit_attr_str(copy_to(p, sizeof p, good, "feet.h5"), "/patches/1", "length_units", "ft");
    expect_bad(p, LFIO_ERR_FORMAT, "length_units", "length units not metres");

    /* Wrong shapes and types; patch 0 of good has 12 cells. */
    const hsize_t long_rgb[2] = {13, 3}, rgb[2] = {12, 3}, ij1[1] = {12}, verts2[2] = {4, 2};
    edit_replace_dataset(copy_to(p, sizeof p, good, "long_irr.h5"), "/patches/0/irradiance", H5T_IEEE_F32LE, 2,
                         long_rgb, &(double){1.0}, "W m^-2", "cell:rgb");
    expect_bad(p, LFIO_ERR_FORMAT, "dims mismatch: shape [13, 3], expected [12, 3]", "irradiance with one row too many");
    edit_replace_dataset(copy_to(p, sizeof p, good, "f64_irr.h5"), "/patches/0/irradiance", H5T_IEEE_F64LE, 2, rgb,
                         &(double){1.0}, "W m^-2", "cell:rgb");
    expect_bad(p, LFIO_ERR_FORMAT, "element type", "irradiance of float64");
    edit_replace_dataset(copy_to(p, sizeof p, good, "ij_rank1.h5"), "/patches/0/cell_ij", H5T_STD_U32LE, 1, ij1, &(double){0},
                         "1", "cell:ij");
    expect_bad(p, LFIO_ERR_FORMAT, "/patches/0/cell_ij: dims mismatch", "cell_ij of rank 1");
    edit_replace_dataset(copy_to(p, sizeof p, good, "verts2.h5"), "/patches/1/vertices", H5T_IEEE_F64LE, 2, verts2,
                         &(double){0}, "m", "vertex:xyz");
    expect_bad(p, LFIO_ERR_FORMAT, "/patches/1/vertices: dims mismatch", "vertices with 2 coordinates");
    edit_replace_dataset(copy_to(p, sizeof p, good, "axes.h5"), "/patches/0/radiosity", H5T_IEEE_F32LE, 2, rgb, &(double){1.0},
                         "W m^-2", "rgb:cell");
    expect_bad(p, LFIO_ERR_FORMAT, "axes", "radiosity with other axes");
    edit_replace_dataset(copy_to(p, sizeof p, good, "units.h5"), "/patches/0/radiosity", H5T_IEEE_F32LE, 2, rgb, &(double){1.0},
                         "W sr^-1 m^-2", "cell:rgb");
    expect_bad(p, LFIO_ERR_FORMAT, "units", "radiosity in radiance units");

    /* Values the layout cannot rule out. */
    edit_element(copy_to(p, sizeof p, good, "nan.h5"), "/patches/2/irradiance", (const hsize_t[]){5, 1}, NAN);
    expect_bad(p, LFIO_ERR_FORMAT, "irradiance of cell 5", "NaN irradiance");
    edit_element(copy_to(p, sizeof p, good, "ij_out.h5"), "/patches/0/cell_ij", (const hsize_t[]){2, 0}, 1000);
    expect_bad(p, LFIO_ERR_FORMAT, "outside", "cell index outside the grid");
    edit_element(copy_to(p, sizeof p, good, "inf_centre.h5"), "/patches/0/cell_centre", (const hsize_t[]){0, 2}, INFINITY);
    expect_bad(p, LFIO_ERR_FORMAT, "centre", "infinite centre");

    lfio_radmap *map = (lfio_radmap *)1;
    CHECK(lfio_radmap_read(NULL, &map) == LFIO_ERR_ARG && map == NULL, "NULL path");
    CHECK(lfio_radmap_read(good, NULL) == LFIO_ERR_ARG, "NULL output");
}

/* Every way a format-2 file can be bad that format 1 cannot: good has patches 0 (12 cells), 1 (none) and
 * 2 (40000), so its cells 12 .. 40011 are patch 2's. The storage checks are test_lightfield_io's. */
static void test_bad_files_v2(const char *good)
{
    char p[512];
    copy_to(p, sizeof p, good, "v2_flipped.h5");
    CHECK(flip_chunk_byte(p, "/patches/irradiance"), "flip a byte of an irradiance chunk");
    expect_bad(p, LFIO_ERR_CHECKSUM, "/patches/irradiance", "format 2: flipped irradiance byte");
    const uint32_t four = 4;
    edit_attr(copy_to(p, sizeof p, good, "v2_count4.h5"), "/", "patch_count", H5T_STD_U32LE, H5T_NATIVE_UINT32, 0,
              &four);
    /* The whole reads scan the labels first; the block reader, which scans them only as far as the patches got,
     * finds the tables one row short first. */
    expect_refused_by(lfio_radmap_read, p, LFIO_ERR_FORMAT, "/patches/label", "format 2: patch_count 4, 3 patches");
    expect_refused_by(lfio_radmap_read_headers, p, LFIO_ERR_FORMAT, "/patches/label", "format 2: patch_count 4");
    expect_refused_by(read_by_blocks, p, LFIO_ERR_FORMAT, "expected [4] from patch_count", "format 2: patch_count 4");
    /* patch 1 claims patch 2's first cell: patch 2 then ends past the cells stored */
    edit_element(copy_to(p, sizeof p, good, "v2_offset_late.h5"), "/patches/cell_offset", (const hsize_t[]){2, 0}, 13);
    edit_element(p, "/patches/cell_offset", (const hsize_t[]){3, 0}, 40013);
    expect_bad_headers(p, LFIO_ERR_FORMAT, "/patches/cell_ij: dims mismatch", "format 2: cell offsets past the cells");
    edit_element(copy_to(p, sizeof p, good, "v2_offset_back.h5"), "/patches/cell_offset", (const hsize_t[]){2, 0}, 5);
    expect_bad_headers(p, LFIO_ERR_FORMAT, "/patches/cell_offset: offset 2 decreases", "format 2: decreasing offsets");
    edit_element(copy_to(p, sizeof p, good, "v2_offset_start.h5"), "/patches/vertex_offset", (const hsize_t[]){0, 0}, 1);
    expect_bad_headers(p, LFIO_ERR_FORMAT, "/patches/vertex_offset: must start at 0", "format 2: offsets not from 0");
    edit_element(copy_to(p, sizeof p, good, "v2_small_grid.h5"), "/patches/nv", (const hsize_t[]){0, 0}, 1);
    expect_bad_headers(p, LFIO_ERR_FORMAT, "patch 0: 12 cells in a grid", "format 2: more cells than nu*nv");
    edit_element(copy_to(p, sizeof p, good, "v2_nan.h5"), "/patches/irradiance", (const hsize_t[]){12 + 5, 1}, NAN);
    expect_bad(p, LFIO_ERR_FORMAT, "patch 2: irradiance of cell 5", "format 2: NaN irradiance");
    lfio_radmap *map = NULL;
    CHECK(lfio_radmap_read_headers(p, &map) == LFIO_OK && lfio_radmap_cell_count(map) == 40012,
          "format 2: the headers of a file with a NaN irradiance read (no value is read): %s", lfio_errmsg());
    lfio_radmap_destroy(map);
    edit_element(copy_to(p, sizeof p, good, "v2_albedo.h5"), "/patches/albedo", (const hsize_t[]){1, 2}, 1.5);
    expect_bad_headers(p, LFIO_ERR_FORMAT, "patch 1: albedo", "format 2: albedo above 1");
    edit_element(copy_to(p, sizeof p, good, "v2_label.h5"), "/patches/label", (const hsize_t[]){0, 0}, 0);
    expect_bad_headers(p, LFIO_ERR_FORMAT, "NUL-terminated labels", "format 2: a label split in two");
    const hsize_t rgb[2] = {40012, 3};
    edit_replace_dataset(copy_to(p, sizeof p, good, "v2_units.h5"), "/patches/radiosity", H5T_IEEE_F32LE, 2, rgb, &(double){1.0},
                         "W sr^-1 m^-2", "cell:rgb");
    expect_bad_headers(p, LFIO_ERR_FORMAT, "units", "format 2: radiosity in radiance units");
}

/* Writes count patches to path in format version `format` through lfio_radmap_write_with(). */
static lfio_status write_format(const char *path, const lfio_radmap_patch *patches, size_t count, int format)
{
    lfio_radmap_write_options opt;
    lfio_radmap_write_options_init(&opt);
    opt.format_version = format;
    return lfio_radmap_write_with(path, "test_radmap", "scenes/test.json", count, describe_some,
                                  NULL, &(struct describer){patches, SIZE_MAX, 0}, &opt);
}

/* lfio_radmap_read_headers() of a file of each format: the patches' descriptions and vertices as written,
 * their cell counts, no cell array. */
static void test_read_headers(const lfio_radmap_patch *patches, size_t count)
{
    uint64_t cells = 0;
    for (size_t k = 0; k < count; k++)
        cells += patches[k].ncells;
    for (int format = 1; format <= 2; format++) {
        char path[512], name[32];
        snprintf(name, sizeof name, "headers%d.h5", format);
        CHECK(write_format(tmp_path(path, sizeof path, name), patches, count, format) == LFIO_OK, "write %s: %s",
              name, lfio_errmsg());
        lfio_radmap *map = NULL;
        quiet_start();
        lfio_status st = lfio_radmap_read_headers(path, &map);
        long printed = quiet_stop();
        CHECK(st == LFIO_OK && printed == 0, "read the headers of %s: %s", name, lfio_errmsg());
        if (map == NULL)
            continue;
        CHECK(!lfio_radmap_has_cells(map) && lfio_radmap_cell_count(map) == cells &&
                  lfio_radmap_format_version(map) == format && lfio_radmap_count(map) == count &&
                  strcmp(lfio_radmap_scene(map), "scenes/test.json") == 0,
              "%s: %llu cells, format %d", name, (unsigned long long)lfio_radmap_cell_count(map),
              lfio_radmap_format_version(map));
        for (size_t k = 0; k < count && k < lfio_radmap_count(map); k++) {
            lfio_radmap_patch back, bare = patches[k];
            CHECK(lfio_radmap_get(map, k, &back) == LFIO_OK, "get %zu", k);
            CHECK(back.cell_ij == NULL && back.cell_area == NULL && back.cell_centre == NULL &&
                      back.irradiance == NULL && back.radiosity == NULL,
                  "%s: patch %zu has cell arrays", name, k);
            CHECK(back.ncells == patches[k].ncells, "%s: patch %zu: %u cells, wrote %u", name, k, back.ncells,
                  patches[k].ncells);
            bare.ncells = back.ncells = 0; /* everything but the cells, which were not read */
            check_patch_equal(&bare, &back, patches[k].label);
        }
        lfio_radmap_destroy(map);
        CHECK(lfio_radmap_read(path, &map) == LFIO_OK && lfio_radmap_has_cells(map) &&
                  lfio_radmap_cell_count(map) == cells, "%s read whole holds its cells", name);
        lfio_radmap_destroy(map);
    }
    CHECK(!lfio_radmap_has_cells(NULL) && lfio_radmap_cell_count(NULL) == 0, "NULL accessors");
}

/* A describe function giving count patches, each a copy of one of two with its own label and polygon index:
 * files of more patches than lfio_radmap_headers holds at once. */
struct many {
    const lfio_radmap_patch *two;
    char label[32];
};

static lfio_status describe_many(void *user, size_t k, lfio_radmap_patch *out)
{
    struct many *m = user;
    *out = m->two[k % 2];
    snprintf(m->label, sizeof m->label, "tile %zu", k);
    out->label = m->label;
    out->polygon = (uint32_t)(k * 3);
    return LFIO_OK;
}

/* Patch k of h agrees with patch k of map (both of the headers): same description, no cell arrays. */
static void check_handle_patch(lfio_radmap_headers *h, const lfio_radmap *map, size_t k, const char *what)
{
    lfio_radmap_patch a, b;
    CHECK(lfio_radmap_get(map, k, &a) == LFIO_OK, "%s: get %zu", what, k);
    lfio_status st = lfio_radmap_headers_get(h, k, &b);
    CHECK(st == LFIO_OK, "%s: lfio_radmap_headers_get %zu: %s", what, k, lfio_errmsg());
    if (st != LFIO_OK)
        return;
    CHECK(b.cell_ij == NULL && b.cell_area == NULL && b.irradiance == NULL && b.ncells == a.ncells,
          "%s: patch %zu: cells", what, k);
    a.ncells = b.ncells = 0;
    char name[96];
    snprintf(name, sizeof name, "%s patch %zu", what, k);
    check_patch_equal(&a, &b, name);
}

/* Opens path with lfio_radmap_headers_open() and gets patch 0 alone, as `ilf info` does to print the first maps.
 * @return the first failure's status, or LFIO_OK. */
static lfio_status open_and_get_first(const char *path)
{
    lfio_radmap_headers *h = NULL;
    lfio_status st = lfio_radmap_headers_open(path, &h);
    lfio_radmap_patch p;
    if (st == LFIO_OK)
        st = lfio_radmap_headers_get(h, 0, &p);
    lfio_radmap_headers_close(h);
    return st;
}

/* The block reader reads only the blocks of the patches got: a file of count patches (many, as
 * test_headers_reader() writes it) damaged in its last block opens and gives patch 0, and is refused, as the
 * whole reads refuse it, once that block is got. */
static void test_headers_lazy(const char *many, size_t count)
{
    char p[512];
    /* the last patch's vertices said to start at 0: the vertex offsets decrease in the last block */
    edit_element(copy_to(p, sizeof p, many, "many_offset.h5"), "/patches/vertex_offset", (const hsize_t[]){count - 1, 0},
                 0);
    char needle[96];
    snprintf(needle, sizeof needle, "/patches/vertex_offset: offset %zu decreases", count - 1);
    CHECK(open_and_get_first(p) == LFIO_OK, "%s: opened and patch 0 got: %s", p, lfio_errmsg());
    expect_bad_headers(p, LFIO_ERR_FORMAT, needle, "format 2: an offset decreasing in the last block");
    /* the last label's NUL replaced: the labels end unterminated, one short */
    uint64_t bytes = 0;
    for (size_t k = 0; k < count; k++)
        bytes += (uint64_t)snprintf(NULL, 0, "tile %zu", k) + 1;
    edit_element(copy_to(p, sizeof p, many, "many_label.h5"), "/patches/label", (const hsize_t[]){bytes - 1, 0}, 'x');
    CHECK(open_and_get_first(p) == LFIO_OK, "%s: opened and patch 0 got: %s", p, lfio_errmsg());
    expect_bad_headers(p, LFIO_ERR_FORMAT, "NUL-terminated labels", "format 2: the last label unterminated");
}

/* lfio_radmap_headers reads what lfio_radmap_read_headers() reads, in order and out of order, across its blocks
 * of patches (a file of 2.2 blocks) and of labels, in either format; its arguments are checked. */
static void test_headers_reader(const lfio_radmap_patch *patches, size_t count_small)
{
    const size_t count = 2 * LFIO_RADMAP_HEADERS_BLOCK + 777;
    char path[512];
    CHECK(lfio_radmap_write_each(tmp_path(path, sizeof path, "many.h5"), "test_radmap", "many.json", count,
                                 describe_many, &(struct many){patches, ""}) == LFIO_OK,
          "write %zu patches: %s", count, lfio_errmsg());
    for (int format = 2; format >= 1; format--) {
        const char *file = format == 2 ? path : "headers1.h5";
        char p1[512];
        if (format == 1)
            tmp_path(p1, sizeof p1, file), file = p1;
        lfio_radmap *map = NULL;
        lfio_radmap_headers *h = NULL;
        CHECK(lfio_radmap_read_headers(file, &map) == LFIO_OK, "read the headers of %s", file);
        quiet_start();
        lfio_status st = lfio_radmap_headers_open(file, &h);
        long printed = quiet_stop();
        CHECK(st == LFIO_OK && printed == 0, "lfio_radmap_headers_open %s: %s", file, lfio_errmsg());
        if (map == NULL || h == NULL) {
            lfio_radmap_destroy(map);
            lfio_radmap_headers_close(h);
            continue;
        }
        const size_t n = lfio_radmap_count(map);
        CHECK(n == (format == 2 ? count : count_small) && lfio_radmap_headers_count(h) == n &&
                  lfio_radmap_headers_cell_count(h) == lfio_radmap_cell_count(map) &&
                  lfio_radmap_headers_format_version(h) == format &&
                  strcmp(lfio_radmap_headers_creator(h), lfio_radmap_creator(map)) == 0 &&
                  strcmp(lfio_radmap_headers_scene(h), lfio_radmap_scene(map)) == 0,
              "%s: the handle's file description", file);
        for (size_t k = 0; k < n; k++)
            check_handle_patch(h, map, k, file);
        const size_t jumps[] = {n - 1, 0, n / 2, LFIO_RADMAP_HEADERS_BLOCK % n, 1 % n, n - 1};
        for (size_t j = 0; j < sizeof jumps / sizeof jumps[0]; j++)
            check_handle_patch(h, map, jumps[j], file);
        lfio_radmap_patch p;
        CHECK(lfio_radmap_headers_get(h, n, &p) == LFIO_ERR_ARG && lfio_radmap_headers_get(NULL, 0, &p) == LFIO_ERR_ARG
                  && lfio_radmap_headers_get(h, 0, NULL) == LFIO_ERR_ARG,
              "%s: get out of range or with NULL", file);
        lfio_radmap_destroy(map);
        lfio_radmap_headers_close(h);
    }
    lfio_radmap_headers *h = (lfio_radmap_headers *)1;
    CHECK(lfio_radmap_headers_open(NULL, &h) == LFIO_ERR_ARG && h == NULL && lfio_radmap_headers_open(path, NULL)
              == LFIO_ERR_ARG, "open with NULL");
    CHECK(lfio_radmap_headers_count(NULL) == 0 && lfio_radmap_headers_cell_count(NULL) == 0 &&
              lfio_radmap_headers_format_version(NULL) == 0 && strcmp(lfio_radmap_headers_creator(NULL), "") == 0 &&
              strcmp(lfio_radmap_headers_scene(NULL), "") == 0, "NULL accessors of the handle");
    lfio_radmap_headers_close(NULL);
    test_headers_lazy(path, count);
}

/* @return the format version of the file at path as lfio reads it, or -1 if it does not read. */
static int read_format(const char *path)
{
    lfio_radmap *map = NULL;
    int v = lfio_radmap_read(path, &map) == LFIO_OK ? lfio_radmap_format_version(map) : -1;
    lfio_radmap_destroy(map);
    return v;
}

/* Both formats hold the same content; the options are checked; a format-1 file written by an older build
 * (the fuzzing corpus's seed, beside this file) still reads. */
static void test_formats(const lfio_radmap_patch *patches, size_t count)
{
    char one[512], two[512];
    lfio_radmap *a = NULL, *b = NULL;
    CHECK(write_format(tmp_path(one, sizeof one, "format1.h5"), patches, count, 1) == LFIO_OK, "write format 1: %s",
          lfio_errmsg());
    CHECK(write_format(tmp_path(two, sizeof two, "format2.h5"), patches, count, 2) == LFIO_OK, "write format 2: %s",
          lfio_errmsg());
    CHECK(lfio_radmap_read(one, &a) == LFIO_OK && lfio_radmap_format_version(a) == 1, "read format 1: %s",
          lfio_errmsg());
    CHECK(lfio_radmap_read(two, &b) == LFIO_OK && lfio_radmap_format_version(b) == 2, "read format 2: %s",
          lfio_errmsg());
    for (size_t k = 0; a && b && k < count; k++) {
        lfio_radmap_patch pa, pb;
        CHECK(lfio_radmap_get(a, k, &pa) == LFIO_OK && lfio_radmap_get(b, k, &pb) == LFIO_OK, "get %zu", k);
        check_patch_equal(&pa, &pb, pa.label);
    }
    lfio_radmap_destroy(a);
    lfio_radmap_destroy(b);
    CHECK(lfio_radmap_format_version(NULL) == 0, "format of NULL");
    lfio_radmap_write_options opt;
    lfio_radmap_write_options_init(&opt);
    opt.deflate_level = 0; /* stored without compression: still the same content */
    CHECK(lfio_radmap_write_with(two, NULL, NULL, count, describe_some, NULL, &(struct describer){patches, SIZE_MAX, 0},
                                 &opt) == LFIO_OK && read_format(two) == 2, "format 2 without deflate: %s", lfio_errmsg());
    opt.deflate_level = 10;
    CHECK(lfio_radmap_write_with(two, NULL, NULL, 0, NULL, NULL, NULL, &opt) == LFIO_ERR_ARG, "deflate level 10");
    lfio_radmap_write_options_init(&opt);
    opt.format_version = 3;
    CHECK(lfio_radmap_write_with(two, NULL, NULL, 0, NULL, NULL, NULL, &opt) == LFIO_ERR_ARG, "format 3");
    opt.format_version = 2;
    opt.size = 3;
    CHECK(lfio_radmap_write_with(two, NULL, NULL, 0, NULL, NULL, NULL, &opt) == LFIO_ERR_ARG, "options of size 3");
    /* an older caller's struct (size and threads only) takes the defaults for the rest */
    opt.size = offsetof(lfio_radmap_write_options, deflate_level);
    opt.format_version = 99;
    CHECK(lfio_radmap_write_with(two, NULL, NULL, 0, NULL, NULL, NULL, &opt) == LFIO_OK && read_format(two) == 2,
          "options of an older size: %s", lfio_errmsg());
    char fixture[1024];
    const char *slash = strrchr(__FILE__, '/');
    snprintf(fixture, sizeof fixture, "%.*sfuzz/corpus/fuzz_radmap/square.h5", slash ? (int)(slash - __FILE__ + 1) : 0,
             __FILE__);
    lfio_radmap *old = NULL;
    lfio_radmap_patch p;
    CHECK(lfio_radmap_read(fixture, &old) == LFIO_OK && lfio_radmap_format_version(old) == 1
              && lfio_radmap_count(old) == 1 && lfio_radmap_get(old, 0, &p) == LFIO_OK && p.ncells == 4,
          "format-1 fixture %s: %s", fixture, lfio_errmsg());
    lfio_radmap_destroy(old);
}

int main(void)
{
    const char *base = getenv("ILF_TEST_TMP");
    snprintf(tmpdir, sizeof tmpdir, "%s/radmap", base && *base ? base : "/tmp");
    mkdir(base && *base ? base : "/tmp", 0755);
    if (mkdir(tmpdir, 0755) != 0 && errno != EEXIST) {
        fprintf(stderr, "cannot create %s: %s\n", tmpdir, strerror(errno));
        return 1;
    }
    sweep_tmpdir(0);

    /* Patch 0: a 1 m square emitter at 0.25 m with some cells missing (12 of 16);
     * patch 1: a polygon of the same frame without cells; patch 2: 40000 cells, several chunks. */
    struct test_patch t[4];
    make_patch(&t[0], "polygons[0]", 0, 1.0, 2.0, 0.25, 4);
    make_patch(&t[1], "meshes[0] (room.obj) face 7", 5, 1.0, 0.0, 0.25, 1);
    make_patch(&t[2], "polygons[1] \xc3\xa9tag\xc3\xa8re", 1, 2.0, 0.0, 0.01, 0);
    /* patch 3: deflated datasets of one chunk each, the common case */
    make_patch(&t[3], "polygons[2]", 2, 1.0, 0.5, 0.07, 0);
    CHECK(t[0].p.ncells == 12 && t[1].p.ncells == 0 && t[2].p.ncells == 40000 && t[3].p.ncells == 196,
          "test patch sizes %u %u %u %u", t[0].p.ncells, t[1].p.ncells, t[2].p.ncells, t[3].p.ncells);
    lfio_radmap_patch patches[4] = {t[0].p, t[1].p, t[2].p, t[3].p};

    char good[512], empty[512], lonely[512];
    test_round_trip(patches, 3, tmp_path(good, sizeof good, "good.h5"), 0);
    /* the chunks compressed by lfio on one thread and on several (a slice's chunks, one a dataset, three at once):
     * HDF5 checks each chunk's checksum as it reads them back */
    test_round_trip(patches, 4, good, 1);
    test_round_trip(patches, 4, good, 3);
    test_round_trip(patches, 3, good, 0); /* replaces an existing file */
    test_round_trip(NULL, 0, tmp_path(empty, sizeof empty, "no_patches.h5"), 0);
    test_round_trip(&patches[1], 1, tmp_path(lonely, sizeof lonely, "empty_patch.h5"), 0);
    test_write_each(patches, 3);
    struct test_patch big;
    make_patch(&big, "polygons[9] big", 9, 2.0, 0.5, 0.0065, 0);
    test_write_rows(patches, 3, &big.p);
    free_patch(&big);
    char stopped[512];
    copy_to(stopped, sizeof stopped, good, "stopped.h5");
    /* stopped before the first patch, and among the big patch's chunks (the whole file is about 240 kB) */
    test_write_fails_midway(patches, 4, stopped, 2048);
    test_write_fails_midway(patches, 4, stopped, 96 * 1024);
    test_writer_refusals(&t[0], good);
    test_formats(patches, 4);
    test_read_headers(patches, 4);
    test_headers_reader(patches, 4);
    test_bad_files_v2(good);
    char good1[512];
    CHECK(write_format(tmp_path(good1, sizeof good1, "good1.h5"), patches, 3, 1) == LFIO_OK, "write format 1: %s",
          lfio_errmsg());
    test_bad_files(good1);
    CHECK(sweep_tmpdir(1) == 0, "temporaries left at the end");
    for (int k = 0; k < 4; k++)
        free_patch(&t[k]);
    return check_report();
}
