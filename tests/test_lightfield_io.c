/*
 * test_lightfield_io.c - light field files (lfio/src/lightfield_io.c): round trips, partial
 * reads, atomic writes, every documented failure of reading, and lfio_verify;
 * and the storage checks light field and radiance-map readers share
 * (lfio/src/h5util.c): links, forged chunks.
 *
 * Bad files are made by writing a good file with lfio and then editing it
 * with the HDF5 API (or by truncating and flipping bytes), so each case
 * differs from a valid file in exactly one way. Every failure must give the
 * expected status, a message naming the file, and print nothing: HDF5's own
 * error printer stays on in this program, and stderr is captured around
 * each lfio call to prove lfio silences it.
 *
 * Files go to $ILF_TEST_TMP/lightfield_io (or /tmp/lightfield_io).
 */
#define _POSIX_C_SOURCE 200809L

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <hdf5.h>
#include <zlib.h>

#include "check.h"
#include "h5edit.h"
#include "lfio/lightfield.h"
#include "lfio/partition.h"
#include "radmap_patches.h"
/* Only for the layout of struct lfio_slab: one test corrupts a slab in memory. */
#include "../lfio/src/internal.h"

static char tmpdir[400];

/* ------------------------------------------------------------------ helpers */

static uint64_t rng_state = 20240611;
/* @return the next value of a splitmix64 sequence (deterministic across runs). */
static uint64_t rng_next(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* @return a uniform double in [0, 1). */
static double rng_unit(void)
{
    return (double)(rng_next() >> 11) * (1.0 / 9007199254740992.0);
}

/* Writes tmpdir/name into buf. @return buf. */
static char *tmp_path(char *buf, size_t size, const char *name)
{
    snprintf(buf, size, "%s/%s", tmpdir, name);
    return buf;
}

/* @return the last component of path. */
static const char *base_name(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

/* Reads a whole file into a malloc'd buffer. @return it and *size, or NULL. */
static unsigned char *slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *buf = malloc(len > 0 ? (size_t)len : 1);
    if (buf && fread(buf, 1, (size_t)len, f) != (size_t)len) {
        free(buf);
        buf = NULL;
    }
    fclose(f);
    *size = (size_t)len;
    return buf;
}

/* Writes size bytes of data to path (replacing it). @return 1 on success. */
static int spit(const char *path, const void *data, size_t size)
{
    FILE *f = fopen(path, "wb");
    if (!f)
        return 0;
    int ok = fwrite(data, 1, size, f) == size;
    return fclose(f) == 0 && ok;
}

/* Copies file src to dst. @return 1 on success. */
static int copy_file(const char *src, const char *dst)
{
    size_t size;
    unsigned char *data = slurp(src, &size);
    int ok = data && spit(dst, data, size);
    free(data);
    return ok;
}

/* Removes the files an earlier run left in tmpdir. */
static void clean_tmpdir(void)
{
    DIR *dir = opendir(tmpdir);
    char p[768];
    for (struct dirent *e; dir && (e = readdir(dir)) != NULL;)
        if (e->d_name[0] != '.') {
            snprintf(p, sizeof p, "%s/%s", tmpdir, e->d_name);
            unlink(p);
        }
    if (dir)
        closedir(dir);
}

/* @return the number of entries of tmpdir whose name contains ".tmp-" (leftover temporaries). */
static int count_temporaries(void)
{
    DIR *dir = opendir(tmpdir);
    int count = 0;
    if (!dir)
        return -1;
    for (struct dirent *e; (e = readdir(dir)) != NULL;)
        count += strstr(e->d_name, ".tmp-") != NULL;
    closedir(dir);
    return count;
}

/* stderr capture: proves that lfio calls print nothing, with HDF5's printer left on. */
static void capture_begin(void)
{
    char p[512];
    check_stderr_begin(tmp_path(p, sizeof p, "stderr.txt"));
}
#define capture_end check_stderr_end

/* --------------------------------------------------------------- test data */

/* Creates a slab with the given geometry and random radiance, some directions all zero. */
static lfio_slab *random_slab(const char *name, uint32_t n, uint32_t nu, uint32_t nv,
                              const double u[3], const double v[3], lfio_units units, float threshold)
{
    lfio_slab_desc d;
    lfio_slab *s = NULL;
    lfio_slab_desc_init(&d);
    snprintf(d.name, sizeof d.name, "%s", name);
    for (int k = 0; k < 3; k++) {
        d.origin[k] = rng_unit() * 4 - 2;
        d.u[k] = u[k];
        d.v[k] = v[k];
    }
    d.n = n, d.nu = nu, d.nv = nv, d.units = units, d.mask_threshold = threshold;
    lfio_status st = lfio_slab_new(&d, &s);
    CHECK(st == LFIO_OK, "slab_new(%s): %s", name, lfio_errmsg());
    if (st != LFIO_OK)
        return NULL;
    size_t count = (size_t)nu * nv * 3;
    float *img = malloc(count * sizeof *img);
    for (uint64_t dir = 0; dir < lfio_slab_dir_count(s); dir++) {
        int dark = rng_unit() < 0.3; /* dark directions give the mask zeros to keep */
        for (size_t e = 0; e < count; e++)
            img[e] = dark ? 0.0f : rng_unit() < 0.2 ? 0.0f : (float)(rng_unit() * 3.0);
        CHECK(lfio_slab_write_direction(s, dir, img) == LFIO_OK, "write_direction: %s", lfio_errmsg());
    }
    free(img);
    return s;
}

/* Builds the multi-slab light field of the round trip: n in {1, 3, 4, 8}, odd grids, rotated
 * frames, and with fine != 0 a last slab at n = 256 whose derived datasets span several blocks. */
static lfio_lightfield *make_lightfield(int fine)
{
    const double ex[3] = {1, 0, 0}, ey[3] = {0, 1, 0}, ez[3] = {0, 0, 1};
    const double t = 0.7, p = 0.4;
    /* A frame rotated about two axes: u and v orthogonal, lengths 0.7 and 1.3. */
    const double ru[3] = {0.7 * cos(t), 0.7 * sin(t), 0};
    const double rv[3] = {-1.3 * sin(t) * cos(p), 1.3 * cos(t) * cos(p), 1.3 * sin(p)};
    const double tu[3] = {1, 1, 0}, tv[3] = {0, 0, 2};
    lfio_lightfield *lf = NULL;
    CHECK(lfio_lightfield_new(&lf) == LFIO_OK, "lightfield_new");
    lfio_lightfield_set_creator(lf, "test_lightfield_io");
    lfio_slab *slabs[] = {
        random_slab("one", 1, 1, 1, ex, ey, LFIO_UNITS_RADIANCE, 0.0f),
        random_slab("three", 3, 17, 33, tu, tv, LFIO_UNITS_RELATIVE, 0.25f),
        random_slab("four.rot", 4, 3, 7, ru, rv, LFIO_UNITS_RADIANCE, 1.5f),
        random_slab("eight-z", 8, 4, 3, ez, ex, LFIO_UNITS_RADIANCE, 0.0f),
        fine ? random_slab("fine_256", 256, 1, 2, ey, ez, LFIO_UNITS_RELATIVE, 2.0f) : NULL,
    };
    for (size_t k = 0; k < sizeof slabs / sizeof slabs[0] && slabs[k]; k++)
        CHECK(lfio_lightfield_take_slab(lf, slabs[k]) == LFIO_OK, "take_slab: %s", lfio_errmsg());
    return lf;
}

/* Checks that two descriptions are equal field by field (doubles bit for bit). */
static void check_desc_equal(const lfio_slab_desc *a, const lfio_slab_desc *b, const char *what)
{
    CHECK(strcmp(a->name, b->name) == 0, "%s: name %s vs %s", what, a->name, b->name);
    CHECK(memcmp(a->origin, b->origin, sizeof a->origin) == 0, "%s: origin", what);
    CHECK(memcmp(a->u, b->u, sizeof a->u) == 0, "%s: u", what);
    CHECK(memcmp(a->v, b->v, sizeof a->v) == 0, "%s: v", what);
    CHECK(a->nu == b->nu && a->nv == b->nv && a->n == b->n, "%s: sizes", what);
    CHECK(a->units == b->units, "%s: units", what);
    CHECK(a->mask_threshold == b->mask_threshold, "%s: mask threshold", what);
}

/* Checks that two slabs have equal descriptions, bit-identical radiance and equal masks. */
static void check_slab_equal(const lfio_slab *a, const lfio_slab *b, const char *what)
{
    check_desc_equal(lfio_slab_get_desc(a), lfio_slab_get_desc(b), what);
    size_t bytes = (size_t)lfio_slab_dir_count(a) * lfio_slab_get_desc(a)->nu * lfio_slab_get_desc(a)->nv
                   * 3 * sizeof(float);
    CHECK(lfio_slab_dir_count(a) == lfio_slab_dir_count(b), "%s: direction count", what);
    CHECK(memcmp(lfio_slab_radiance(a), lfio_slab_radiance(b), bytes) == 0, "%s: radiance differs", what);
    CHECK(lfio_slab_mask_levels(a) == lfio_slab_mask_levels(b), "%s: mask levels", what);
    for (uint32_t k = 0; k < lfio_slab_mask_levels(a); k++) {
        uint32_t m = lfio_slab_mask_n(a, k);
        CHECK(m == lfio_slab_mask_n(b, k), "%s: mask level %u", what, k);
        CHECK(lfio_slab_mask_count(a, m) == lfio_slab_mask_count(b, m), "%s: mask count at %u", what, m);
        uint64_t differ = 0;
        for (uint64_t id = 0; id < 4ull * m * m; id++)
            differ += lfio_slab_mask_test(a, m, id) != lfio_slab_mask_test(b, m, id);
        CHECK(differ == 0, "%s: %llu mask bits differ at level %u", what, (unsigned long long)differ, m);
    }
}

/* --------------------------------------------------------- HDF5 file surgery */

/* Finds the file offset and size of chunk 0 of dataset dset. @return 1 on success. */
static int chunk_location(const char *path, const char *dset, haddr_t *addr, hsize_t *size)
{
    hsize_t offset[4];
    unsigned filter_mask;
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    hid_t d = H5Dopen2(f, dset, H5P_DEFAULT);
    hid_t space = H5Dget_space(d);
    herr_t rc = H5Dget_chunk_info(d, space, 0, offset, &filter_mask, addr, size);
    H5Sclose(space);
    H5Dclose(d);
    H5Fclose(f);
    return rc >= 0;
}

/* XORs the byte at offset of path with 0x5a. @return 1 on success. */
static int flip_byte(const char *path, long offset)
{
    int fd = open(path, O_RDWR);
    unsigned char c = 0;
    int ok = fd >= 0 && pread(fd, &c, 1, offset) == 1;
    c ^= 0x5a;
    ok = ok && pwrite(fd, &c, 1, offset) == 1;
    if (fd >= 0)
        close(fd);
    return ok;
}

/* ------------------------------------------------------------------- tests */

/* Writes lf to path, checking success. */
static void write_ok(const lfio_lightfield *lf, const char *path)
{
    capture_begin();
    lfio_status st = lfio_lightfield_write(lf, path);
    long printed = capture_end();
    CHECK(st == LFIO_OK, "write %s: %s", path, lfio_errmsg());
    CHECK(printed == 0, "write printed %ld bytes", printed);
}

/* Round trip: write, read whole, read through a reader, compare everything; verify the file. */
static void test_round_trip(const lfio_lightfield *lf, const char *path)
{
    write_ok(lf, path);
    CHECK(count_temporaries() == 0, "temporaries left after a good write");
    lfio_lightfield *back = NULL;
    lfio_status st = lfio_lightfield_read(path, &back);
    CHECK(st == LFIO_OK && back, "read %s: %s", path, lfio_errmsg());
    if (!back)
        return;
    CHECK(strcmp(lfio_lightfield_creator(back), "test_lightfield_io") == 0, "creator '%s'", lfio_lightfield_creator(back));
    CHECK(lfio_lightfield_slab_count(back) == lfio_lightfield_slab_count(lf), "slab count");
    for (size_t k = 0; k < lfio_lightfield_slab_count(lf); k++)
        check_slab_equal(lfio_lightfield_slab(lf, k), lfio_lightfield_slab(back, k),
                         lfio_slab_get_desc(lfio_lightfield_slab(lf, k))->name);
    lfio_lightfield_destroy(back);

    /* Writing again over the same path replaces it. */
    write_ok(lf, path);
    lfio_verify_report rep = {99, "x"};
    st = lfio_verify(path, &rep);
    CHECK(st == LFIO_OK && rep.problems == 0 && rep.first[0] == '\0', "verify good file: %s (%s)",
          lfio_status_name(st), rep.first);
}

/* Partial reads through a reader equal the in-memory slices; bad arguments are refused. */
static void test_reader(const lfio_lightfield *lf, const char *path)
{
    lfio_reader *r = NULL;
    lfio_status st = lfio_reader_open(path, &r);
    CHECK(st == LFIO_OK && r, "reader_open: %s", lfio_errmsg());
    if (!r)
        return;
    CHECK(lfio_reader_format_version(r) == 1, "format version %d", lfio_reader_format_version(r));
    CHECK(strcmp(lfio_reader_creator(r), "test_lightfield_io") == 0, "reader creator");
    CHECK(lfio_reader_slab_count(r) == lfio_lightfield_slab_count(lf), "reader slab count");
    CHECK(lfio_reader_slab_desc(r, lfio_reader_slab_count(r)) == NULL, "desc out of range");
    for (size_t k = 0; k < lfio_lightfield_slab_count(lf); k++) {
        const lfio_slab *s = lfio_lightfield_slab(lf, k);
        const lfio_slab_desc *d = lfio_slab_get_desc(s);
        check_desc_equal(d, lfio_reader_slab_desc(r, k), "reader desc");
        size_t img_n = (size_t)d->nu * d->nv * 3, pos_n = (size_t)lfio_slab_dir_count(s) * 3;
        float *want = malloc((img_n > pos_n ? img_n : pos_n) * sizeof(float));
        float *got = malloc((img_n > pos_n ? img_n : pos_n) * sizeof(float));
        uint64_t step = lfio_slab_dir_count(s) > 300 ? 997 : 1; /* every direction of small slabs */
        int bad = 0;
        for (uint64_t dir = 0; dir < lfio_slab_dir_count(s); dir += step) {
            lfio_slab_read_direction(s, dir, want);
            bad += lfio_reader_read_direction(r, k, dir, got) != LFIO_OK
                   || memcmp(want, got, img_n * sizeof(float)) != 0;
        }
        CHECK(bad == 0, "slab %zu: %d directions differ", k, bad);
        bad = 0;
        for (uint32_t j = 0; j < d->nv; j++)
            for (uint32_t i = 0; i < d->nu; i++) {
                lfio_slab_read_position(s, i, j, want);
                bad += lfio_reader_read_position(r, k, i, j, got) != LFIO_OK
                       || memcmp(want, got, pos_n * sizeof(float)) != 0;
            }
        CHECK(bad == 0, "slab %zu: %d positions differ", k, bad);
        lfio_slab *whole = NULL;
        CHECK(lfio_reader_read_slab(r, k, &whole) == LFIO_OK, "read_slab: %s", lfio_errmsg());
        if (whole)
            check_slab_equal(s, whole, "reader_read_slab");
        lfio_slab_destroy(whole);
        CHECK(lfio_reader_read_direction(r, k, lfio_slab_dir_count(s), got) == LFIO_ERR_ARG, "dir range");
        CHECK(lfio_reader_read_position(r, k, d->nu, 0, got) == LFIO_ERR_ARG, "i range");
        CHECK(lfio_reader_read_position(r, k, 0, d->nv, got) == LFIO_ERR_ARG, "j range");
        free(want);
        free(got);
    }
    float px[3];
    lfio_slab *none = (lfio_slab *)1;
    CHECK(lfio_reader_read_direction(r, lfio_reader_slab_count(r), 0, px) == LFIO_ERR_ARG, "slab range");
    CHECK(lfio_reader_read_direction(r, 0, 0, NULL) == LFIO_ERR_ARG, "NULL image");
    CHECK(lfio_reader_read_slab(r, 99, &none) == LFIO_ERR_ARG && none == NULL, "read_slab range");
    lfio_reader_close(r);
    lfio_reader_close(NULL);
}

/* Atomic writes: failures leave no temporaries and never damage an existing file. */
static void test_atomic_write(const lfio_lightfield *lf, const char *good)
{
    char p[512], plain[512];
    lfio_lightfield *empty = NULL;
    lfio_lightfield_new(&empty);
    CHECK(lfio_lightfield_write(empty, tmp_path(p, sizeof p, "empty_lf.h5")) == LFIO_ERR_ARG,
          "empty light field: %s", lfio_errmsg());
    CHECK(access(p, F_OK) != 0, "empty light field created a file");
    lfio_lightfield_destroy(empty);

    /* A missing folder. */
    tmp_path(p, sizeof p, "no_such_folder/missing_dir.h5");
    capture_begin();
    lfio_status st = lfio_lightfield_write(lf, p);
    long printed = capture_end();
    CHECK(st == LFIO_ERR_IO, "missing folder: %s", lfio_status_name(st));
    CHECK(strstr(lfio_errmsg(), "missing_dir.h5") != NULL, "message: %s", lfio_errmsg());
    CHECK(printed == 0, "missing folder printed %ld bytes", printed);
    CHECK(access(tmp_path(p, sizeof p, "no_such_folder"), F_OK) != 0, "folder was created");

    /* A "folder" that is a regular file: fails for root too, unlike chmod. */
    spit(tmp_path(plain, sizeof plain, "plain_file"), "x", 1);
    snprintf(p, sizeof p, "%.400s/under_file.h5", plain);
    st = lfio_lightfield_write(lf, p);
    CHECK(st == LFIO_ERR_IO && strstr(lfio_errmsg(), "under_file.h5"), "file as folder: %s: %s",
          lfio_status_name(st), lfio_errmsg());

    /* A write that fails half-way over an existing good file, from a slab broken in memory. */
    size_t before_size, after_size;
    tmp_path(p, sizeof p, "atomic.h5");
    CHECK(copy_file(good, p), "copy");
    unsigned char *before = slurp(p, &before_size);
    lfio_slab *last = lfio_lightfield_slab(lf, lfio_lightfield_slab_count(lf) - 1);
    float saved = last->radiance[5];
    last->radiance[5] = NAN;
    capture_begin();
    st = lfio_lightfield_write(lf, p);
    printed = capture_end();
    last->radiance[5] = saved;
    CHECK(st != LFIO_OK && strstr(lfio_errmsg(), "atomic.h5") && strstr(lfio_errmsg(), "radiance"),
          "broken slab: %s: %s", lfio_status_name(st), lfio_errmsg());
    CHECK(printed == 0, "broken slab printed %ld bytes", printed);
    unsigned char *after = slurp(p, &after_size);
    CHECK(after && before_size == after_size && memcmp(before, after, before_size) == 0,
          "existing file changed by a failed write");
    free(after);
    CHECK(count_temporaries() == 0, "temporaries left after a failed write");

    /* A genuine I/O failure: the file size limit stops HDF5 mid-write (EFBIG, not a signal). */
    struct rlimit old, small;
    void (*old_handler)(int) = signal(SIGXFSZ, SIG_IGN);
    getrlimit(RLIMIT_FSIZE, &old);
    small = old;
    small.rlim_cur = 16384;
    CHECK(setrlimit(RLIMIT_FSIZE, &small) == 0, "setrlimit");
    st = lfio_lightfield_write(lf, p);
    char msg[512];
    snprintf(msg, sizeof msg, "%s", lfio_errmsg());
    setrlimit(RLIMIT_FSIZE, &old);
    signal(SIGXFSZ, old_handler);
    CHECK(st == LFIO_ERR_IO && strstr(msg, "atomic.h5"), "size limit: %s: %s", lfio_status_name(st), msg);
    after = slurp(p, &after_size);
    CHECK(after && before_size == after_size && memcmp(before, after, before_size) == 0,
          "existing file changed by a write that ran out of space");
    free(after);
    free(before);
    CHECK(count_temporaries() == 0, "temporaries left after an I/O failure");
    CHECK(lfio_verify(p, NULL) == LFIO_OK, "file intact: %s", lfio_errmsg());
}

/* Expects reading path to fail with want and a message naming the file (and needle, if given),
 * printing nothing. data_level: the metadata is valid, so lfio_reader_open() succeeds. */
static void expect_bad(const char *path, lfio_status want, const char *needle, int data_level,
                       const char *what)
{
    lfio_lightfield *lf = (lfio_lightfield *)1;
    capture_begin();
    lfio_status st = lfio_lightfield_read(path, &lf);
    long printed = capture_end();
    const char *msg = lfio_errmsg();
    CHECK(st == want, "%s: read gave %s, expected %s (%s)", what, lfio_status_name(st),
          lfio_status_name(want), msg);
    CHECK(lf == NULL, "%s: output not NULL", what);
    CHECK(strstr(msg, base_name(path)) != NULL, "%s: message does not name the file: %s", what, msg);
    CHECK(!needle || strstr(msg, needle) != NULL, "%s: message lacks '%s': %s", what, needle, msg);
    CHECK(printed == 0, "%s: %ld bytes printed on stderr", what, printed);
    if (st == LFIO_OK)
        lfio_lightfield_destroy(lf);

    lfio_reader *r = (lfio_reader *)1;
    capture_begin();
    st = lfio_reader_open(path, &r);
    printed = capture_end();
    CHECK(data_level ? st == LFIO_OK : (st == want && r == NULL), "%s: reader_open gave %s (%s)", what,
          lfio_status_name(st), lfio_errmsg());
    CHECK(printed == 0, "%s: reader_open printed %ld bytes", what, printed);
    if (st == LFIO_OK)
        lfio_reader_close(r);

    lfio_verify_report rep;
    capture_begin();
    st = lfio_verify(path, &rep);
    printed = capture_end();
    CHECK(st == want && rep.problems >= 1 && strstr(rep.first, base_name(path)), "%s: verify gave %s, %u problems (%s)",
          what, lfio_status_name(st), rep.problems, rep.first);
    CHECK(printed == 0, "%s: verify printed %ld bytes", what, printed);
}

/* Makes tmpdir/name a fresh copy of src. @return its path in buf. */
static char *fresh_copy(char *buf, size_t size, const char *src, const char *name)
{
    tmp_path(buf, size, name);
    CHECK(copy_file(src, buf), "copy to %s", buf);
    return buf;
}

/* HDF5's Fletcher-32 of n bytes (16-bit big-endian words, an odd last byte as the high half), computed
 * here on its own to forge a stored chunk: the test's oracle, not lfio's. */
static uint32_t forge_fletcher32(const unsigned char *p, size_t n)
{
    uint64_t a = 0, b = 0;
    for (size_t i = 0; i + 1 < n; i += 2) {
        a = (a + ((uint32_t)p[i] << 8 | p[i + 1])) % 65535;
        b = (b + a) % 65535;
    }
    if (n % 2) {
        a = (a + ((uint32_t)p[n - 1] << 8)) % 65535;
        b = (b + a) % 65535;
    }
    return (uint32_t)(b << 16 | a);
}

/* Stores values (dims, [dir][v][u][3]) again as dataset dset of path, of file type ftype and creation
 * property list dcpl, writing directions [0, written) only, with lfio's units and axes. */
static void restore_radiance(const char *path, const char *dset, hid_t ftype, hid_t dcpl, const hsize_t *dims,
                             const float *values, hsize_t written, const char *units)
{
    hid_t f = edit_open(path);
    CHECK(H5Ldelete(f, dset, H5P_DEFAULT) >= 0, "delete %s", dset);
    hid_t space = H5Screate_simple(4, dims, NULL);
    hid_t d = H5Dcreate2(f, dset, ftype, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    CHECK(d >= 0, "create %s", dset);
    hsize_t start[4] = {0, 0, 0, 0}, count[4] = {written, dims[1], dims[2], dims[3]};
    hid_t ms = H5Screate_simple(4, count, NULL);
    H5Sselect_hyperslab(space, H5S_SELECT_SET, start, NULL, count, NULL);
    CHECK(written == 0 || H5Dwrite(d, H5T_NATIVE_FLOAT, ms, space, H5P_DEFAULT, values) >= 0, "write %s", dset);
    H5Sclose(ms);
    H5Sclose(space);
    H5Dclose(d);
    H5Fclose(f);
    edit_attr_str(path, dset, "units", units);
    edit_attr_str(path, dset, "axes", "dir:v:u:rgb");
}

/* @return a creation property list: chunks of chunk (NULL: contiguous), then the filters named in
 * pipeline ('s' shuffle, 'd' deflate, 'f' Fletcher-32) in that order. */
static hid_t storage(const hsize_t *chunk, const char *pipeline)
{
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    if (chunk)
        H5Pset_chunk(dcpl, 4, chunk);
    for (const char *c = pipeline; *c; c++)
        if (*c == 's')
            H5Pset_shuffle(dcpl);
        else if (*c == 'd')
            H5Pset_deflate(dcpl, 4);
        else if (*c == 'f')
            H5Pset_fletcher32(dcpl);
    return dcpl;
}

/* Reads path whole with lfio_lightfield_read_with() on threads threads. @return its status. */
static lfio_status read_on_threads(const char *path, unsigned threads, lfio_lightfield **out)
{
    lfio_read_options opt;
    lfio_read_options_init(&opt);
    opt.threads = threads;
    return lfio_lightfield_read_with(path, &opt, out);
}

/* Radiance stored otherwise than lfio writes it reads the same values, on one thread and on three: lfio
 * inflates chunks itself where the storage is its own (other chunk shapes too, partial in every
 * dimension), HDF5 elsewhere (no shuffle, big-endian, contiguous, chunks never written, which read as
 * zeros). A stored chunk whose checksum holds but whose stream does not inflate is refused, named. */
static void test_other_storage(const char *good)
{
    lfio_lightfield *ref = NULL;
    CHECK(lfio_lightfield_read(good, &ref) == LFIO_OK, "read %s: %s", good, lfio_errmsg());
    if (!ref)
        return;
    const lfio_slab *slab = lfio_lightfield_slab(ref, 1);
    const lfio_slab_desc *desc = lfio_slab_get_desc(slab);
    const hsize_t dims[4] = {4 * (hsize_t)desc->n * desc->n, desc->nv, desc->nu, 3};
    const size_t count = (size_t)(dims[0] * dims[1] * dims[2] * dims[3]), half = count / dims[0] * (dims[0] / 2);
    const float *values = lfio_slab_radiance(slab);
    const char *units = desc->units == LFIO_UNITS_RADIANCE ? "W sr^-1 m^-2" : "relative";
    const hsize_t odd[4] = {5, 3, 7, 3}, lfio_shape[4] = {32, 16, 16, 3};
    const struct {
        const char *name;
        const hsize_t *chunk;
        const char *pipeline;
        int big_endian;
        hsize_t written;
    } cases[] = {
        {"odd chunks, lfio's filters", odd, "sdf", 0, dims[0]},
        {"deflate without shuffle", lfio_shape, "df", 0, dims[0]},
        {"big-endian", lfio_shape, "sdf", 1, dims[0]},
        {"contiguous", NULL, "", 0, dims[0]},
        {"half the chunks unwritten", odd, "sdf", 0, dims[0] / 2},
    };
    char p[512], name[64];
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        snprintf(name, sizeof name, "storage%zu.h5", c);
        hid_t dcpl = storage(cases[c].chunk, cases[c].pipeline);
        restore_radiance(fresh_copy(p, sizeof p, good, name), "/slabs/1/radiance",
                         cases[c].big_endian ? H5T_IEEE_F32BE : H5T_IEEE_F32LE, dcpl, dims, values, cases[c].written,
                         units);
        H5Pclose(dcpl);
        for (unsigned threads = 1; threads <= 3; threads += 2) {
            lfio_lightfield *back = NULL;
            lfio_status st = read_on_threads(p, threads, &back);
            CHECK(st == LFIO_OK, "%s, %u threads: %s", cases[c].name, threads, lfio_errmsg());
            const float *got = back ? lfio_slab_radiance(lfio_lightfield_slab(back, 1)) : NULL;
            size_t wrong = 0, kept = cases[c].written == dims[0] ? count : half;
            for (size_t k = 0; got && k < count; k++)
                wrong += got[k] != (k < kept ? values[k] : 0.0f);
            CHECK(got && wrong == 0, "%s, %u threads: %zu values differ", cases[c].name, threads, wrong);
            lfio_lightfield_destroy(back);
        }
        /* readers take unwritten chunks as zeros; verify says that lfio never leaves one out */
        lfio_verify_report rep;
        lfio_status vst = lfio_verify(p, &rep);
        CHECK(cases[c].written == dims[0] || (vst == LFIO_ERR_FORMAT && strstr(rep.first, "/slabs/1/radiance: 132 of its 264 "
                                                                                           "chunks are not stored")),
              "%s: verify: %s", cases[c].name, rep.first);
    }
    /* chunk 0 forged, each time under a right checksum: a stream that inflates short of a chunk (16 bytes),
     * one that inflates past it (ten chunks of zeros: a bomb of under 1 KB), both within the sizes a chunk
     * can take, so that only inflating them finds them; one smaller than that (16 bytes in 15), and one
     * smaller than its checksum (HDF5's Fletcher-32 filter reads before such a buffer); a chunk whose mask
     * says its checksum was skipped, holding an altered value. */
    const size_t chunk_bytes = 32 * 16 * 16 * 3 * sizeof(float);
    unsigned char *zeros = calloc(10 * chunk_bytes, 1), *forged = malloc(2 * chunk_bytes);
    const struct {
        const char *name;
        size_t raw;           /* zero bytes deflated into the stream (0: the stream is `literal`) */
        size_t literal;       /* bytes of a stored chunk made of 0x5a */
        unsigned mask;        /* filter mask stored with it */
        lfio_status want;
        const char *message;  /* of a whole read or verify (or of opening, which refuses it already) */
        const char *partial;  /* of a partial read */
        int at_open;          /* refused when the file is opened */
    } forgeries[] = {
        {"short stream", 0, 0, 0, LFIO_ERR_FORMAT, "stores 15 bytes", "", 1},
        {"bomb", 10 * chunk_bytes, 0, 0, LFIO_ERR_FORMAT, "chunk 0 does not inflate", "does not inflate to its", 0},
        {"noise", 4000, 0, 0, LFIO_ERR_FORMAT, "chunk 0 does not inflate", "does not inflate to its", 0},
        {"under its checksum", 0, 2, 0, LFIO_ERR_FORMAT, "stores 2 bytes", "", 1},
        {"checksum skipped", 0, 0, 4, LFIO_ERR_FORMAT, "skipped filters (filter mask 0x4)", "filter mask 0x4", 0},
    };
    for (size_t c = 0; zeros && forged && c < sizeof forgeries / sizeof forgeries[0]; c++) {
        snprintf(name, sizeof name, "forged%zu.h5", c);
        hid_t dcpl = storage(lfio_shape, "sdf");
        restore_radiance(fresh_copy(p, sizeof p, good, name), "/slabs/1/radiance", H5T_IEEE_F32LE, dcpl, dims,
                         values, dims[0], units);
        H5Pclose(dcpl);
        size_t stored = forgeries[c].literal;
        if (stored > 0) {
            memset(forged, 0x5a, stored);
        } else {
            /* noise: incompressible bytes, which deflate stores as they are */
            for (size_t k = 0; forgeries[c].raw == 4000 && k < 4000; k++)
                zeros[k] = (unsigned char)(rng_next() >> 24);
            uLongf packed = (uLongf)(2 * chunk_bytes - 4);
            CHECK(compress2(forged, &packed, zeros, forgeries[c].raw ? forgeries[c].raw : 16, 4) == Z_OK, "forge");
            memset(zeros, 0, 4000);
            if (forgeries[c].mask) /* a value changed: the stream of another chunk, no checksum after it */
                packed = (uLongf)(2 * chunk_bytes - 4), compress2(forged, &packed, (const Bytef *)values, chunk_bytes, 4);
            uint32_t sum = forge_fletcher32(forged, packed);
            for (int k = 0; k < 4 && !forgeries[c].mask; k++)
                forged[packed + k] = (unsigned char)(sum >> (8 * k));
            stored = packed + (forgeries[c].mask ? 0 : 4);
        }
        hid_t f = edit_open(p), d = H5Dopen2(f, "/slabs/1/radiance", H5P_DEFAULT);
        const hsize_t origin[4] = {0, 0, 0, 0};
        CHECK(H5Dwrite_chunk(d, H5P_DEFAULT, forgeries[c].mask, origin, stored, forged) >= 0, "store the forged chunk");
        H5Dclose(d);
        H5Fclose(f);
        for (unsigned threads = 1; threads <= 3; threads += 2) {
            lfio_lightfield *back = NULL;
            lfio_status st = read_on_threads(p, threads, &back);
            CHECK(st == forgeries[c].want && back == NULL && strstr(lfio_errmsg(), "/slabs/1/radiance") &&
                      strstr(lfio_errmsg(), forgeries[c].message),
                  "forged chunk (%s), %u threads: %s, '%s'", forgeries[c].name, threads, lfio_status_name(st),
                  lfio_errmsg());
            lfio_lightfield_destroy(back);
        }
        /* partial reads go through HDF5's filters: lfio inflates the chunk first, within its bytes */
        lfio_reader *r = NULL;
        lfio_status st = lfio_reader_open(p, &r);
        CHECK(forgeries[c].at_open ? st == forgeries[c].want && r == NULL : st == LFIO_OK, "forged chunk (%s): open %s",
              forgeries[c].name, lfio_errmsg());
        float *img = malloc((size_t)(dims[1] * dims[2] * 3) * sizeof *img), rgb[4 * 64 * 3];
        if (r && img && dims[0] <= 4 * 64) {
            st = lfio_reader_read_direction(r, 1, 0, img);
            CHECK(st == LFIO_ERR_FORMAT && strstr(lfio_errmsg(), forgeries[c].partial),
                  "forged chunk (%s): direction read: %s", forgeries[c].name, lfio_errmsg());
            st = lfio_reader_read_position(r, 1, 0, 0, rgb);
            CHECK(st == LFIO_ERR_FORMAT, "forged chunk (%s): position read: %s", forgeries[c].name, lfio_errmsg());
            CHECK(lfio_reader_read_direction(r, 0, 0, img) == LFIO_OK, "other slabs still readable: %s", lfio_errmsg());
            lfio_verify_report rep;
            CHECK(lfio_verify(p, &rep) == LFIO_ERR_FORMAT && strstr(rep.first, forgeries[c].message),
                  "forged chunk (%s): verify: %s", forgeries[c].name, rep.first);
        }
        free(img);
        lfio_reader_close(r);
    }
    free(forged);
    free(zeros);
    lfio_lightfield_destroy(ref);
}

/* lfio_read_options: reads on 1 and 3 threads, whole and through a reader, give the file's values, the
 * same as the default read; threads past the limit, and sizes this lfio does not know, are refused by name
 * before the file is opened; a size holding only the first field takes the defaults for the rest. */
static void test_read_options(const char *good)
{
    lfio_lightfield *want = NULL;
    CHECK(lfio_lightfield_read(good, &want) == LFIO_OK, "default read: %s", lfio_errmsg());
    for (unsigned threads = 1; want && threads <= 3; threads += 2) {
        lfio_lightfield *back = NULL;
        CHECK(read_on_threads(good, threads, &back) == LFIO_OK, "read on %u threads: %s", threads, lfio_errmsg());
        for (size_t k = 0; back && k < lfio_lightfield_slab_count(want); k++)
            check_slab_equal(lfio_lightfield_slab(want, k), lfio_lightfield_slab(back, k), "read_with");
        lfio_lightfield_destroy(back);
        lfio_read_options opt;
        lfio_read_options_init(&opt);
        opt.threads = threads;
        lfio_reader *r = NULL;
        CHECK(lfio_reader_open_with(good, &opt, &r) == LFIO_OK, "reader_open_with: %s", lfio_errmsg());
        for (size_t k = 0; r && k < lfio_lightfield_slab_count(want); k++) {
            lfio_slab *s = NULL;
            CHECK(lfio_reader_read_slab(r, k, &s) == LFIO_OK, "reader on %u threads: %s", threads, lfio_errmsg());
            if (s)
                check_slab_equal(lfio_lightfield_slab(want, k), s, "reader_open_with");
            lfio_slab_destroy(s);
        }
        lfio_reader_close(r);
    }
    lfio_lightfield_destroy(want);
    lfio_read_options opt;
    lfio_read_options_init(&opt);
    CHECK(opt.size == sizeof opt && opt.threads == 0, "defaults: size %zu, threads %u", opt.size, opt.threads);
    opt.threads = 1025; /* one past the header's "at most 1024" */
    lfio_lightfield *lf = NULL;
    lfio_reader *r = NULL;
    CHECK(lfio_lightfield_read_with(good, &opt, &lf) == LFIO_ERR_ARG && lf == NULL &&
              strstr(lfio_errmsg(), "threads 1025"), "too many threads: %s", lfio_errmsg());
    CHECK(lfio_reader_open_with(good, &opt, &r) == LFIO_ERR_ARG && r == NULL, "reader, too many threads: %s",
          lfio_errmsg());
    opt.threads = 2;
    opt.size = sizeof opt + 8;
    CHECK(lfio_lightfield_read_with(good, &opt, &lf) == LFIO_ERR_ARG && strstr(lfio_errmsg(), "lfio_read_options.size"),
          "unknown size: %s", lfio_errmsg());
    opt.size = sizeof opt.size;
    CHECK(lfio_lightfield_read_with(good, &opt, &lf) == LFIO_ERR_ARG, "size without threads: %s", lfio_errmsg());
    opt.size = offsetof(lfio_read_options, threads) + sizeof opt.threads;
    CHECK(lfio_lightfield_read_with(good, &opt, &lf) == LFIO_OK, "size of the first fields: %s", lfio_errmsg());
    lfio_lightfield_destroy(lf);
}

/* Every documented way a file can be bad. small: a one-slab file (n = 1, 3 x 1 positions). */
static void test_bad_files(const char *good, const char *small)
{
    char p[512];
    expect_bad(tmp_path(p, sizeof p, "does_not_exist.h5"), LFIO_ERR_NOTFOUND, NULL, 0, "missing file");
    spit(tmp_path(p, sizeof p, "empty.h5"), "", 0);
    expect_bad(p, LFIO_ERR_FORMAT, "not an HDF5 file", 0, "empty file");
    const char text[] = "this is a text file, not a light field\n";
    spit(tmp_path(p, sizeof p, "text.h5"), text, sizeof text - 1);
    expect_bad(p, LFIO_ERR_FORMAT, "not an HDF5 file", 0, "text file");

    size_t size;
    unsigned char *data = slurp(good, &size);
    const size_t cuts[] = {size / 10, size / 2, size * 9 / 10, size - 1};
    for (size_t c = 0; data && c < sizeof cuts / sizeof cuts[0]; c++) {
        char what[64];
        snprintf(what, sizeof what, "truncated to %zu of %zu bytes", cuts[c], size);
        spit(tmp_path(p, sizeof p, "truncated.h5"), data, cuts[c]);
        expect_bad(p, LFIO_ERR_FORMAT, NULL, 0, what);
    }
    free(data);

    /* A flipped byte inside a compressed radiance chunk. */
    haddr_t addr = 0;
    hsize_t csize = 0;
    fresh_copy(p, sizeof p, good, "flipped.h5");
    CHECK(chunk_location(p, "/slabs/3/radiance", &addr, &csize) && csize > 8, "chunk info");
    CHECK(flip_byte(p, (long)(addr + csize / 2)), "flip");
    expect_bad(p, LFIO_ERR_CHECKSUM, "/slabs/3/radiance", 1, "flipped radiance byte");
    lfio_reader *r = NULL;
    float buf[256 * 3];
    if (lfio_reader_open(p, &r) == LFIO_OK) {
        CHECK(lfio_reader_read_direction(r, 3, 0, buf) == LFIO_ERR_CHECKSUM, "partial read of a bad chunk: %s",
              lfio_errmsg());
        CHECK(lfio_reader_read_position(r, 3, 0, 0, buf) == LFIO_ERR_CHECKSUM, "position read of a bad chunk");
        CHECK(lfio_reader_read_direction(r, 0, 0, buf) == LFIO_OK, "other slabs still readable: %s", lfio_errmsg());
        lfio_reader_close(r);
    }

    edit_attr_str(fresh_copy(p, sizeof p, small, "wrong_format.h5"), "/", "format", "not-a-lightfield");
    expect_bad(p, LFIO_ERR_FORMAT, "not-a-lightfield", 0, "wrong format string");

    char long_creator[300];
    memset(long_creator, 'x', sizeof long_creator - 1);
    long_creator[sizeof long_creator - 1] = '\0';
    edit_attr_str(fresh_copy(p, sizeof p, small, "long_creator.h5"), "/", "creator", long_creator);
    expect_bad(p, LFIO_ERR_FORMAT, "creator", 0, "creator over 255 bytes");

    const int32_t two = 2, three = 3;
    edit_attr(fresh_copy(p, sizeof p, small, "version2.h5"), "/", "format_version", H5T_STD_I32LE,
              H5T_NATIVE_INT32, 0, &two);
    expect_bad(p, LFIO_ERR_FORMAT, "format_version 2", 0, "format_version 2");
    CHECK(strstr(lfio_errmsg(), "version 1") != NULL, "names the supported version: %s", lfio_errmsg());

    edit_attr(fresh_copy(p, sizeof p, small, "count3.h5"), "/", "slab_count", H5T_STD_I32LE,
              H5T_NATIVE_INT32, 0, &three);
    expect_bad(p, LFIO_ERR_FORMAT, "/slabs/1", 0, "slab_count 3 with one group");

    /* nu claims 2^30 positions: 48 GiB, under the size limit, so only the shape check stops it. */
    const uint32_t huge = 1u << 30;
    edit_attr(fresh_copy(p, sizeof p, small, "huge_nu.h5"), "/slabs/0", "nu", H5T_STD_U32LE,
              H5T_NATIVE_UINT32, 0, &huge);
    expect_bad(p, LFIO_ERR_FORMAT, "dims mismatch", 0, "nu = 2^30");
    const uint32_t huger = 1u << 31;
    edit_attr(p, "/slabs/0", "nu", H5T_STD_U32LE, H5T_NATIVE_UINT32, 0, &huger);
    edit_attr(p, "/slabs/0", "nv", H5T_STD_U32LE, H5T_NATIVE_UINT32, 0, &huger);
    expect_bad(p, LFIO_ERR_FORMAT, "exceeds", 0, "radiance over the size limit");

    const double ones[3] = {1, 1, 1};
    edit_attr(fresh_copy(p, sizeof p, small, "float_nu.h5"), "/slabs/0", "nu", H5T_IEEE_F64LE,
              H5T_NATIVE_DOUBLE, 0, ones);
    expect_bad(p, LFIO_ERR_FORMAT, "'nu'", 0, "nu stored as a float");
    edit_attr(fresh_copy(p, sizeof p, small, "vector_n.h5"), "/slabs/0", "origin", H5T_IEEE_F64LE,
              H5T_NATIVE_DOUBLE, 2, ones);
    expect_bad(p, LFIO_ERR_FORMAT, "'origin'", 0, "origin with 2 elements");
    edit_delete_attr(fresh_copy(p, sizeof p, small, "no_colour.h5"), "/slabs/0", "colour_space");
    expect_bad(p, LFIO_ERR_FORMAT, "colour_space", 0, "missing colour_space");
    edit_attr_str(fresh_copy(p, sizeof p, small, "bad_units.h5"), "/slabs/0", "radiance_units", "lumens");
    expect_bad(p, LFIO_ERR_FORMAT, "lumens", 0, "unknown radiance units");

    const hsize_t rank3[3] = {4, 1, 3}, f64dims[4] = {4, 1, 3, 3};
    edit_replace_dataset(fresh_copy(p, sizeof p, small, "rank3.h5"), "/slabs/0/radiance", H5T_IEEE_F32LE,
                         3, rank3, NULL, "W sr^-1 m^-2", "dir:v:u:rgb");
    expect_bad(p, LFIO_ERR_FORMAT, "dims mismatch", 0, "radiance of rank 3");
    edit_replace_dataset(fresh_copy(p, sizeof p, small, "float64.h5"), "/slabs/0/radiance", H5T_IEEE_F64LE,
                         4, f64dims, NULL, "W sr^-1 m^-2", "dir:v:u:rgb");
    expect_bad(p, LFIO_ERR_FORMAT, "element type", 0, "radiance of float64");
    edit_replace_dataset(fresh_copy(p, sizeof p, small, "axes.h5"), "/slabs/0/radiance", H5T_IEEE_F32LE,
                         4, f64dims, NULL, "W sr^-1 m^-2", "u:v:dir:rgb");
    expect_bad(p, LFIO_ERR_FORMAT, "axes", 0, "radiance with other axes");

    const hsize_t at_nan[4] = {1, 0, 2, 1}, at_neg[4] = {2, 0, 1, 0};
    edit_element(fresh_copy(p, sizeof p, small, "nan.h5"), "/slabs/0/radiance", at_nan, NAN);
    expect_bad(p, LFIO_ERR_FORMAT, "dir 1, i 2, j 0", 1, "NaN radiance");
    edit_element(fresh_copy(p, sizeof p, small, "negative.h5"), "/slabs/0/radiance", at_neg, -1.0);
    expect_bad(p, LFIO_ERR_FORMAT, "dir 2, i 1, j 0", 1, "negative radiance");
    edit_element(fresh_copy(p, sizeof p, small, "inf.h5"), "/slabs/0/radiance", at_neg, INFINITY);
    expect_bad(p, LFIO_ERR_FORMAT, "dir 2, i 1, j 0", 1, "infinite radiance");

    const double skew[3] = {0.5, 1, 0};
    edit_attr(fresh_copy(p, sizeof p, small, "skew.h5"), "/slabs/0", "v", H5T_IEEE_F64LE,
              H5T_NATIVE_DOUBLE, 3, skew);
    expect_bad(p, LFIO_ERR_FORMAT, "orthogonal", 0, "non-orthogonal u, v");
}

/* @return 1 if dataset dset of path is stored with filter id. */
static int has_filter(const char *path, const char *dset, H5Z_filter_t id)
{
    unsigned flags = 0, conf = 0;
    size_t nvals = 0;
    char name[16];
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    hid_t d = H5Dopen2(f, dset, H5P_DEFAULT);
    hid_t dcpl = H5Dget_create_plist(d);
    herr_t rc = H5Pget_filter_by_id2(dcpl, id, &flags, &nvals, NULL, sizeof name, name, &conf);
    H5Pclose(dcpl);
    H5Dclose(d);
    H5Fclose(f);
    return rc >= 0;
}

/* @return a malloc'd coverage pattern for slab s: 0/1 values that differ with dir and position. */
static uint8_t *coverage_pattern(const lfio_slab *s, unsigned seed)
{
    const lfio_slab_desc *d = lfio_slab_get_desc(s);
    size_t total = (size_t)lfio_slab_dir_count(s) * d->nu * d->nv;
    uint8_t *c = malloc(total);
    for (size_t e = 0; e < total; e++)
        c[e] = (uint8_t)((e * 7 + seed) % 3 == 0);
    return c;
}

/* Optional coverage: set, replaced, removed, refused values; written and read back (whole and through a
 * reader) bit for bit next to slabs without it; stored chunked, deflated and checksummed; bad datasets refused. */
static void test_coverage(const char *path)
{
    lfio_lightfield *lf = make_lightfield(0);
    const lfio_slab *s1 = lfio_lightfield_slab(lf, 1), *s3 = lfio_lightfield_slab(lf, 3);
    const lfio_slab_desc *d1 = lfio_slab_get_desc(s1);
    size_t total1 = (size_t)lfio_slab_dir_count(s1) * d1->nu * d1->nv;
    size_t total3 = (size_t)lfio_slab_dir_count(s3) * lfio_slab_get_desc(s3)->nu * lfio_slab_get_desc(s3)->nv;
    uint8_t *c1 = coverage_pattern(s1, 1), *c3 = coverage_pattern(s3, 2);

    CHECK(lfio_lightfield_coverage(lf, 1) == NULL, "a new slab has no coverage");
    c1[total1 - 1] = 2;
    CHECK(lfio_lightfield_set_coverage(lf, 1, c1) == LFIO_ERR_ARG && strstr(lfio_errmsg(), "expected 0 or 1")
              && strstr(lfio_errmsg(), "three"),
          "value 2 refused: %s", lfio_errmsg());
    CHECK(lfio_lightfield_coverage(lf, 1) == NULL, "a refused coverage leaves none");
    c1[total1 - 1] = 1;
    CHECK(lfio_lightfield_set_coverage(lf, 4, c1) == LFIO_ERR_ARG, "slab out of range");
    CHECK(lfio_lightfield_coverage(lf, 4) == NULL, "coverage of a slab out of range");
    /* Set, replace, remove, set again: the copy is what was given last. */
    uint8_t *first = coverage_pattern(s1, 0);
    CHECK(lfio_lightfield_set_coverage(lf, 1, first) == LFIO_OK, "set: %s", lfio_errmsg());
    free(first);
    CHECK(lfio_lightfield_set_coverage(lf, 1, c1) == LFIO_OK, "replace: %s", lfio_errmsg());
    CHECK(lfio_lightfield_coverage(lf, 1) != c1 && memcmp(lfio_lightfield_coverage(lf, 1), c1, total1) == 0,
          "coverage is copied");
    CHECK(lfio_lightfield_set_coverage(lf, 3, c3) == LFIO_OK && lfio_lightfield_set_coverage(lf, 3, NULL) == LFIO_OK
              && lfio_lightfield_coverage(lf, 3) == NULL, "NULL removes coverage");
    CHECK(lfio_lightfield_set_coverage(lf, 3, c3) == LFIO_OK, "set again: %s", lfio_errmsg());

    write_ok(lf, path);
    lfio_lightfield *back = NULL;
    CHECK(lfio_lightfield_read(path, &back) == LFIO_OK, "read with coverage: %s", lfio_errmsg());
    for (size_t k = 0; back && k < 4; k++) {
        const uint8_t *want = k == 1 ? c1 : k == 3 ? c3 : NULL, *got = lfio_lightfield_coverage(back, k);
        size_t total = k == 1 ? total1 : total3;
        CHECK(want ? got && memcmp(want, got, total) == 0 : got == NULL, "slab %zu: coverage read back", k);
        check_slab_equal(lfio_lightfield_slab(lf, k), lfio_lightfield_slab(back, k), "slab beside coverage");
    }
    lfio_lightfield_destroy(back);

    lfio_reader *r = NULL;
    CHECK(lfio_reader_open(path, &r) == LFIO_OK, "reader: %s", lfio_errmsg());
    uint8_t *got = malloc(total1 > total3 ? total1 : total3);
    for (size_t k = 0; r && k < 4; k++) {
        int has = k == 1 || k == 3;
        CHECK(lfio_reader_has_coverage(r, k) == has, "slab %zu: has_coverage", k);
        lfio_status st = lfio_reader_read_coverage(r, k, got);
        CHECK(has ? st == LFIO_OK && memcmp(got, k == 1 ? c1 : c3, k == 1 ? total1 : total3) == 0
                  : st == LFIO_ERR_ARG && strstr(lfio_errmsg(), "no coverage"),
              "slab %zu: read_coverage: %s", k, lfio_errmsg());
    }
    CHECK(!lfio_reader_has_coverage(r, 4) && !lfio_reader_has_coverage(NULL, 0), "has_coverage out of range");
    CHECK(lfio_reader_read_coverage(r, 1, NULL) == LFIO_ERR_ARG, "read_coverage into NULL");
    lfio_reader_close(r);
    free(got);
    CHECK(lfio_verify(path, NULL) == LFIO_OK, "verify a file with coverage: %s", lfio_errmsg());
    CHECK(has_filter(path, "/slabs/1/coverage", H5Z_FILTER_FLETCHER32)
              && has_filter(path, "/slabs/1/coverage", H5Z_FILTER_DEFLATE),
          "coverage is checksummed and deflated");

    /* Bad coverage datasets: wrong shape, wrong type (metadata: refused on opening), a value of 2 (data). */
    char p[512];
    const hsize_t wrong_shape[3] = {lfio_slab_dir_count(s1), d1->nv, d1->nu + 1};
    const hsize_t right_shape[3] = {lfio_slab_dir_count(s1), d1->nv, d1->nu};
    edit_replace_dataset(fresh_copy(p, sizeof p, path, "cov_shape.h5"), "/slabs/1/coverage", H5T_STD_U8LE, 3,
                         wrong_shape, NULL, "1", "dir:v:u");
    expect_bad(p, LFIO_ERR_FORMAT, "/slabs/1/coverage: dims mismatch", 0, "coverage of the wrong shape");
    edit_replace_dataset(fresh_copy(p, sizeof p, path, "cov_rank.h5"), "/slabs/1/coverage", H5T_STD_U8LE, 2,
                         right_shape, NULL, "1", "dir:v");
    expect_bad(p, LFIO_ERR_FORMAT, "/slabs/1/coverage: dims mismatch", 0, "coverage of rank 2");
    edit_replace_dataset(fresh_copy(p, sizeof p, path, "cov_type.h5"), "/slabs/1/coverage", H5T_IEEE_F32LE, 3,
                         right_shape, NULL, "1", "dir:v:u");
    expect_bad(p, LFIO_ERR_FORMAT, "/slabs/1/coverage: element type", 0, "coverage of float32");
    const hsize_t at[3] = {2, 5, 3};
    edit_element(fresh_copy(p, sizeof p, path, "cov_value.h5"), "/slabs/1/coverage", at, 2.0);
    expect_bad(p, LFIO_ERR_FORMAT, "/slabs/1/coverage: value 2 at dir 2, i 3, j 5", 1, "coverage value 2");
    free(c1);
    free(c3);
    lfio_lightfield_destroy(lf);
}

/* lfio_verify finds derived data that no longer matches the geometry and radiance. */
static void test_verify_tampered(const char *good)
{
    char p[512];
    lfio_verify_report rep;
    const hsize_t at5[1] = {5};
    fresh_copy(p, sizeof p, good, "tampered_sa.h5");
    edit_element(p, "/slabs/2/solid_angle", at5, peek_element(p, "/slabs/2/solid_angle", at5) + 1e-6);
    lfio_status st = lfio_verify(p, &rep);
    CHECK(st == LFIO_ERR_FORMAT && rep.problems == 1 && strstr(rep.first, "/slabs/2/solid_angle")
              && strstr(rep.first, "tampered_sa.h5"),
          "tampered solid angle: %s, %u problems: %s", lfio_status_name(st), rep.problems, rep.first);
    CHECK(strcmp(lfio_errmsg(), rep.first) == 0, "errmsg is the first problem: %s", lfio_errmsg());
    lfio_lightfield *lf = NULL;
    CHECK(lfio_lightfield_read(p, &lf) == LFIO_OK, "reading does not check derived data: %s", lfio_errmsg());
    lfio_lightfield_destroy(lf);

    /* Flip one bit of the finest mask level of slab 3 (n = 8) and one of slab 1's direction. */
    fresh_copy(p, sizeof p, good, "tampered_mask.h5");
    const hsize_t at7[1] = {7}, at_dir[2] = {3, 2};
    edit_element(p, "/slabs/3/mask/level_8", at7, 1.0 - peek_element(p, "/slabs/3/mask/level_8", at7));
    edit_element(p, "/slabs/1/direction", at_dir, peek_element(p, "/slabs/1/direction", at_dir) * 1.001);
    st = lfio_verify(p, &rep);
    CHECK(st == LFIO_ERR_FORMAT && rep.problems == 2 && strstr(rep.first, "/slabs/1/direction"),
          "tampered mask and direction: %s, %u problems: %s", lfio_status_name(st), rep.problems, rep.first);

    fresh_copy(p, sizeof p, good, "tampered_pos.h5");
    const hsize_t at_pos[3] = {6, 16, 0};
    edit_element(p, "/slabs/1/position", at_pos, 1e3);
    st = lfio_verify(p, &rep);
    CHECK(st == LFIO_ERR_FORMAT && rep.problems == 1 && strstr(rep.first, "/slabs/1/position")
              && strstr(rep.first, "[6, 16, 0]"),
          "tampered position: %s: %s", lfio_status_name(st), rep.first);

    /* A mask dataset beyond the levels the slab defines. */
    fresh_copy(p, sizeof p, good, "extra_level.h5");
    hid_t f = edit_open(p);
    hsize_t four = 4;
    hid_t space = H5Screate_simple(1, &four, NULL);
    hid_t d = H5Dcreate2(f, "/slabs/0/mask/level_99", H5T_STD_U8LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    H5Dclose(d);
    H5Sclose(space);
    H5Fclose(f);
    st = lfio_verify(p, &rep);
    CHECK(st == LFIO_ERR_FORMAT && rep.problems == 1 && strstr(rep.first, "mask"), "extra mask level: %s",
          rep.first);
    CHECK(lfio_verify(NULL, &rep) == LFIO_ERR_ARG && rep.problems == 1, "verify NULL path");
}

/* Stores data (bytes) as the chunk at the origin of dataset dset of path, with filter mask mask. */
static void store_chunk(const char *path, const char *dset, int rank, const void *data, size_t bytes, uint32_t mask)
{
    hid_t f = edit_open(path), d = H5Dopen2(f, dset, H5P_DEFAULT);
    const hsize_t origin[4] = {0, 0, 0, 0};
    CHECK(rank <= 4 && H5Dwrite_chunk(d, H5P_DEFAULT, mask, origin, bytes, data) >= 0, "store a chunk in %s", dset);
    H5Dclose(d);
    H5Fclose(f);
}

/* Replaces the link to dataset dset (in group group) of path by a soft link to target, or an external
 * link to target in file other when other is not NULL. */
static void relink(const char *path, const char *group, const char *dset, const char *other, const char *target)
{
    hid_t f = edit_open(path), g = H5Gopen2(f, group, H5P_DEFAULT);
    CHECK(H5Ldelete(g, dset, H5P_DEFAULT) >= 0, "unlink %s", dset);
    herr_t rc = other ? H5Lcreate_external(other, target, g, dset, H5P_DEFAULT, H5P_DEFAULT)
                      : H5Lcreate_soft(target, g, dset, H5P_DEFAULT, H5P_DEFAULT);
    CHECK(rc >= 0, "link %s", dset);
    H5Gclose(g);
    H5Fclose(f);
}

/* lfio_radmap_write_with()'s describe: the one patch user points to. */
static lfio_status describe_one(void *user, size_t k, lfio_radmap_patch *out)
{
    (void)k;
    *out = *(const lfio_radmap_patch *)user;
    return LFIO_OK;
}

/* Radiance-map files take the same storage checks as light fields: a dataset reached through a soft or an
 * external link is refused (the external one before its file is opened), and so are forged chunks of a
 * deflated cell dataset (three chunks of 16384 cells): under their checksum, a skipped checksum, a stream
 * inflating ten times past its chunk. Each refusal is LFIO_ERR_FORMAT naming the file and the dataset.
 * In format 1 (a group a patch) and format 2 (each array once for all patches, in /patches). */
static void test_radmap_storage(int format)
{
    const char *group = format == 1 ? "/patches/0" : "/patches";
    char irr[64], verts[64], area[64];
    snprintf(irr, sizeof irr, "%s/irradiance", group);
    snprintf(verts, sizeof verts, "%s/vertices", group);
    snprintf(area, sizeof area, "%s/cell_area", group);
    lfio_radmap_write_options opt;
    lfio_radmap_write_options_init(&opt);
    opt.format_version = format;
    struct test_patch t;
    make_patch(&t, "polygons[0]", 0, 2.0, 0.0, 0.01, 0); /* 40,000 cells */
    char good[512], p[512];
    CHECK(lfio_radmap_write_with(tmp_path(good, sizeof good, "map.h5"), "test_lightfield_io", NULL, 1, describe_one, NULL,
                                 &t.p, &opt) == LFIO_OK,
          "write a radiance map (format %d): %s", format, lfio_errmsg());
    lfio_radmap *map = NULL;
    lfio_radmap_patch back;
    CHECK(lfio_radmap_read(good, &map) == LFIO_OK && lfio_radmap_format_version(map) == format, "read it back: %s",
          lfio_errmsg());
    if (map && lfio_radmap_get(map, 0, &back) == LFIO_OK)
        check_patch_equal(&back, &t.p, "map.h5");
    lfio_radmap_destroy(map);
    const size_t chunk_bytes = 16384 * 3 * sizeof(float);
    unsigned char *zeros = calloc(10 * chunk_bytes, 1), *stream = malloc(2 * chunk_bytes);
    uLongf packed = (uLongf)(2 * chunk_bytes - 4), bomb = packed;
    CHECK(zeros && stream && compress2(stream, &packed, zeros, chunk_bytes, 1) == Z_OK, "deflate a chunk");
    char external[96], soft[96];
    snprintf(external, sizeof external, "%s: is an external link", irr);
    snprintf(soft, sizeof soft, "%s: is a soft link", verts);
    struct {
        const char *name, *needle;
    } cases[] = {
        {"map_external.h5", external},
        {"map_soft.h5", soft},
        {"map_tiny_chunk.h5", "stores 2 bytes"},
        {"map_skipped.h5", "skipped filters (filter mask 0x4)"},
        {"map_bomb.h5", "does not inflate to its 196608 bytes"},
    };
    relink(fresh_copy(p, sizeof p, good, cases[0].name), group, "irradiance", good, irr);
    relink(fresh_copy(p, sizeof p, good, cases[1].name), group, "vertices", NULL, area);
    store_chunk(fresh_copy(p, sizeof p, good, cases[2].name), irr, 2, "\x01\x02", 2, 0);
    /* a stream of zeros where the cells were, its checksum skipped */
    store_chunk(fresh_copy(p, sizeof p, good, cases[3].name), irr, 2, stream, packed, 4);
    if (zeros && stream && compress2(stream, &bomb, zeros, 10 * chunk_bytes, 9) == Z_OK) {
        uint32_t sum = forge_fletcher32(stream, bomb);
        for (int k = 0; k < 4; k++)
            stream[bomb + k] = (unsigned char)(sum >> (8 * k));
        store_chunk(fresh_copy(p, sizeof p, good, cases[4].name), irr, 2, stream, bomb + 4, 0);
    }
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        map = (lfio_radmap *)1;
        capture_begin();
        lfio_status st = lfio_radmap_read(tmp_path(p, sizeof p, cases[c].name), &map);
        long printed = capture_end();
        CHECK(st == LFIO_ERR_FORMAT && map == NULL && strstr(lfio_errmsg(), cases[c].name) &&
                  strstr(lfio_errmsg(), cases[c].needle),
              "%s: %s (%s)", cases[c].name, lfio_status_name(st), lfio_errmsg());
        CHECK(printed == 0, "%s: %ld bytes printed", cases[c].name, printed);
    }
    free(stream);
    free(zeros);
    free_patch(&t);
}

int main(void)
{
    const char *base = getenv("ILF_TEST_TMP");
    snprintf(tmpdir, sizeof tmpdir, "%s/lightfield_io", base && *base ? base : "/tmp");
    mkdir(base && *base ? base : "/tmp", 0755);
    if (mkdir(tmpdir, 0755) != 0 && errno != EEXIST) {
        fprintf(stderr, "cannot create %s: %s\n", tmpdir, strerror(errno));
        return 1;
    }
    clean_tmpdir();
    char good[512], mid[512], small[512];
    tmp_path(good, sizeof good, "good.h5");
    tmp_path(mid, sizeof mid, "mid.h5");
    tmp_path(small, sizeof small, "small.h5");

    lfio_lightfield *lf = make_lightfield(1);
    test_round_trip(lf, good);
    test_reader(lf, good);
    test_read_options(good);
    test_atomic_write(lf, good);
    lfio_lightfield_destroy(lf);

    /* The files the bad-file cases copy and edit: four slabs (small enough to copy
     * often), and one slab with n = 1 and 3 x 1 positions. */
    lf = make_lightfield(0);
    test_round_trip(lf, mid);
    lfio_lightfield_destroy(lf);
    lfio_lightfield *one = NULL;
    const double ex[3] = {1, 0, 0}, ey[3] = {0, 1, 0};
    lfio_lightfield_new(&one);
    lfio_lightfield_set_creator(one, "test_lightfield_io");
    lfio_lightfield_take_slab(one, random_slab("small", 1, 3, 1, ex, ey, LFIO_UNITS_RADIANCE, 0.0f));
    test_round_trip(one, small);
    lfio_lightfield_destroy(one);

    test_bad_files(mid, small);
    test_other_storage(mid);
    char cov[512];
    test_coverage(tmp_path(cov, sizeof cov, "coverage.h5"));
    test_verify_tampered(mid);
    test_radmap_storage(1);
    test_radmap_storage(2);
    CHECK(count_temporaries() == 0, "temporaries left at the end");
    return check_report();
}
