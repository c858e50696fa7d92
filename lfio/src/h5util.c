/*
 * h5util.c - the HDF5 plumbing shared by lfio's file formats (see h5util.h):
 * error silencing and translation, bounded typed attributes, dataset layouts,
 * hyperslab transfers, the atomic writer and the checked opener.
 *
 * Invariants:
 *   - Every HDF5 failure is recorded with lfio__h5_fail() before any other
 *     HDF5 call (which would clear the error stack), so messages carry
 *     HDF5's own reason and checksum failures are recognised.
 *   - Strings read from files are bounded before they are allocated; a
 *     dataset is checked against its expected layout before it is read.
 *   - A write either renames a complete, fsynced file over its target or
 *     leaves the target untouched and removes its temporary (the project's
 *     one writer, ilf/atomic_file.h, and its one rule for temporary names).
 *     HDF5 writes the temporary through lfio's streaming driver, which never
 *     reports a failed write to it (h5stream.c, build_and_write()); a
 *     collective write lets MPI-IO write the temporary.
 */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "chunks.h"
#include "h5util.h"
#include "ilf/atomic_file.h"
#include "internal.h"

/* Most bytes HDF5's metadata cache holds per open file, as the cache counts
 * them (serialised sizes: objects' decoded headers come on top, which is why
 * writers also evict objects on close). Its default (32 MiB, grown on
 * demand) kept tens of MiB alive while a radiance-map file of thousands of
 * maps was written; lfio touches each object once, in order, so a small
 * cache costs no extra I/O worth noting. */
#define METADATA_CACHE_MAX ((size_t)2 << 20)

/* ------------------------------------------------------------------- errors */

/* The caller's HDF5 automatic error handler, saved while lfio is silent. */

/* Saves the calling thread's HDF5 error printer and turns printing off. */
void lfio__h5_quiet_begin(lfio__h5_quiet *q)
{
    q->func = NULL;
    q->data = NULL;
    H5Eget_auto2(H5E_DEFAULT, &q->func, &q->data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}

/* Restores the printer saved by lfio__h5_quiet_begin(). */
void lfio__h5_quiet_end(const lfio__h5_quiet *q)
{
    H5Eset_auto2(H5E_DEFAULT, q->func, q->data);
}

/* What the HDF5 error stack says about the last failure. */
struct stack_info {
    int checksum;       /* some record reports a checksum mismatch */
    char reason[160];   /* the innermost record's description */
};

/* @return 1 if text contains "checksum" in any letter case. */
static int mentions_checksum(const char *text)
{
    static const char word[] = "checksum";
    for (; text && *text; text++) {
        size_t k = 0;
        while (word[k] && text[k] && (text[k] | 0x20) == word[k])
            k++;
        if (!word[k])
            return 1;
    }
    return 0;
}

/* H5Ewalk2 visitor: notes checksum records and keeps the innermost description. */
static herr_t stack_visit(unsigned n, const H5E_error2_t *e, void *data)
{
    struct stack_info *si = data;
    /* HDF5 1.10 reports a Fletcher32 failure as "data error detected by Fletcher32
     * checksum" (Data storage / Read failed) and a metadata one as "incorrect
     * metadata checksum ...": the word is the stable part of both. */
    if (mentions_checksum(e->desc) || mentions_checksum(e->func_name))
        si->checksum = 1;
    if (n == 0 && e->desc)
        snprintf(si->reason, sizeof si->reason, "%s", e->desc);
    return 0;
}

/*
 * Records a failure of the HDF5 call just made, as "<path>: <obj>: <what> (<reason>)".
 * Must be called before any other HDF5 call, which would clear the stack.
 * @return LFIO_ERR_CHECKSUM if the stack reports a checksum mismatch, else st.
 */
lfio_status lfio__h5_fail(lfio_status st, const char *path, const char *obj, const char *what)
{
    struct stack_info si = {0, ""};
    H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, stack_visit, &si);
    if (si.checksum)
        return lfio__fail(LFIO_ERR_CHECKSUM, "%s: %s: checksum mismatch (%s)", path, obj, what);
    if (si.reason[0])
        return lfio__fail(st, "%s: %s: %s (%s)", path, obj, what, si.reason);
    return lfio__fail(st, "%s: %s: %s", path, obj, what);
}

/* Closes any HDF5 identifier; invalid (negative) ids are ignored, which keeps cleanup paths simple. */
void lfio__h5_close(hid_t id)
{
    if (id < 0)
        return;
    switch (H5Iget_type(id)) {
    case H5I_FILE: H5Fclose(id); break;
    case H5I_GROUP: H5Gclose(id); break;
    case H5I_DATASET: H5Dclose(id); break;
    case H5I_ATTR: H5Aclose(id); break;
    case H5I_DATATYPE: H5Tclose(id); break;
    case H5I_DATASPACE: H5Sclose(id); break;
    case H5I_GENPROP_LST: H5Pclose(id); break;
    default: break;
    }
}

/* @return the index of the first value of v[0..count) that is negative, NaN or infinite; count if none. */
size_t lfio__first_bad_value(const float *v, size_t count)
{
    for (size_t k = 0; k < count; k++)
        if (!(v[k] >= 0.0f && v[k] <= 3.4028234663852886e38f))
            return k;
    return count;
}

/* Writes "[a, b, ...]" for dims into buf. */
void lfio__h5_format_dims(char *buf, size_t size, int rank, const hsize_t *dims)
{
    size_t used = 0;
    used += (size_t)snprintf(buf, size, "[");
    for (int k = 0; k < rank && used < size; k++)
        used += (size_t)snprintf(buf + used, size - used, "%s%llu", k ? ", " : "",
                                 (unsigned long long)dims[k]);
    if (used < size)
        snprintf(buf + used, size - used, "]");
}

/* ------------------------------------------------------------ stored data */

/* The filters a dataset's pipeline holds, each at most once and in this order: HDF5's shuffle, deflate
 * and Fletcher-32, what lfio writes (any of them may be absent: other writers' files). */
typedef struct pipeline {
    int shuffle, deflate, fletcher32;
} pipeline;

/* Checks the filter pipeline of dcpl (dataset obj) and notes its filters in *pl. Any other filter is
 * refused: HDF5 would load plugins for unknown ones, and scale-offset, n-bit and szip change or hide
 * what the values are. @return LFIO_OK or LFIO_ERR_FORMAT. */
static lfio_status check_pipeline(const char *path, const char *obj, hid_t dcpl, pipeline *pl)
{
    static const H5Z_filter_t order[3] = {H5Z_FILTER_SHUFFLE, H5Z_FILTER_DEFLATE, H5Z_FILTER_FLETCHER32};
    int *const seen[3] = {&pl->shuffle, &pl->deflate, &pl->fletcher32};
    *pl = (pipeline){0, 0, 0};
    int n = H5Pget_nfilters(dcpl);
    if (n < 0)
        return lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, "cannot read its filter pipeline");
    unsigned next = 0; /* the first filter of order[] still allowed */
    for (int f = 0; f < n; f++) {
        unsigned flags = 0, config = 0, cd[8];
        size_t ncd = 8;
        char name[64] = "";
        H5Z_filter_t id = H5Pget_filter2(dcpl, (unsigned)f, &flags, &ncd, cd, sizeof name, name, &config);
        unsigned k = next;
        while (k < 3 && order[k] != id)
            k++;
        if (k == 3)
            return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: filter %d ('%.40s') in place %d of its pipeline: lfio reads "
                              "shuffle, deflate and fletcher32 only, each once and in that order",
                              path, obj, (int)id, name, f + 1);
        *seen[k] = 1;
        next = k + 1;
    }
    return LFIO_OK;
}

/* @return the fewest bytes a stored chunk of chunk_bytes can take through pipeline pl: a zlib stream has
 * 6 bytes around its data (LFIO__H5_INFLATE_MAX). */
static uint64_t stored_least(uint64_t chunk_bytes, const pipeline *pl)
{
    return (pl->deflate ? 6 + chunk_bytes / LFIO__H5_INFLATE_MAX : chunk_bytes) + (pl->fletcher32 ? 4 : 0);
}

/* @return the most bytes a stored chunk of chunk_bytes can take through pipeline pl: HDF5's deflate
 * filter gives up past ceil(1.001 n) + 12 bytes (the chunk is then stored unfiltered, which its filter
 * mask says, and lfio refuses). */
static uint64_t stored_most(uint64_t chunk_bytes, const pipeline *pl)
{
    return (pl->deflate ? chunk_bytes + (chunk_bytes + 999) / 1000 + 12 : chunk_bytes) + (pl->fletcher32 ? 4 : 0);
}

/* @return the size of the file path names in *bytes, or an error (message set). */
static lfio_status file_bytes(const char *path, uint64_t *bytes)
{
    struct stat sb;
    if (stat(path, &sb) != 0)
        return lfio__fail(LFIO_ERR_IO, "%s: cannot stat: %s", path, strerror(errno));
    *bytes = (uint64_t)sb.st_size;
    return LFIO_OK;
}

/* Checks contiguous dataset d (obj) of bytes: stored whole, inside the file. @return LFIO_OK or LFIO_ERR_FORMAT. */
static lfio_status check_contiguous(const char *path, const char *obj, hid_t d, uint64_t bytes, uint64_t file)
{
    haddr_t at = H5Dget_offset(d);
    if (bytes == 0)
        return LFIO_OK;
    if (at == HADDR_UNDEF)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: declares %llu bytes but stores none (lfio reads only data "
                          "stored in the file)", path, obj, (unsigned long long)bytes);
    if (at > file || bytes > file - at)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: its %llu bytes at offset %llu lie past the end of the file "
                          "(%llu bytes)", path, obj, (unsigned long long)bytes, (unsigned long long)at,
                          (unsigned long long)file);
    return LFIO_OK;
}

/* What the chunks of one dataset must be like, and what the walk over them found. */
typedef struct chunk_walk {
    int rank;
    hsize_t dims[H5S_MAX_RANK], chunk[H5S_MAX_RANK];
    uint64_t chunk_bytes;   /* values of a chunk */
    uint64_t least, most;   /* stored bytes of a chunk */
    uint64_t file;          /* bytes in the file */
    uint64_t stored;        /* bytes of the chunks seen so far */
    uint64_t count, missing;
    hsize_t first_missing[H5S_MAX_RANK];
    int whole;              /* refuse any chunk not stored (lfio__h5_expect_whole()) */
} chunk_walk;

/* H5Ewalk2 visitor: notes a record saying that a chunk is not stored. */
static herr_t unallocated_visit(unsigned n, const H5E_error2_t *e, void *data)
{
    (void)n;
    if (e->desc && (strstr(e->desc, "not allocated") || strstr(e->desc, "address isn't defined")))
        *(int *)data = 1;
    return 0;
}

/* Finds the stored size of the chunk at offset of dataset d, 0 if it is not stored: HDF5 1.10 looks it up
 * in the index directly, and fails for a chunk never written, saying "chunk storage is not allocated" (or,
 * once a read has cached the chunk, "chunk address isn't defined").
 * @return 0, or -1 with HDF5's error stack kept. */
static int stored_size(hid_t d, const hsize_t *offset, hsize_t *size)
{
    *size = 0;
    if (H5Dget_chunk_storage_size(d, offset, size) >= 0)
        return 0;
    int unallocated = 0;
    H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, unallocated_visit, &unallocated);
    if (!unallocated)
        return -1;
    H5Eclear2(H5E_DEFAULT);
    *size = 0;
    return 0;
}

/* Checks the stored size of the chunk at offset of dataset d (obj) as chunk_walk w says: HDF5 finds it in
 * the index directly (where its address and filter mask take a walk over the index per chunk, which
 * lfio__h5_xfer() checks when it reads the chunk). @return LFIO_OK or LFIO_ERR_FORMAT. */
static lfio_status check_chunk(const char *path, const char *obj, hid_t d, const hsize_t *offset, chunk_walk *w)
{
    hsize_t size = 0;
    char at[128];
    if (stored_size(d, offset, &size) < 0) {
        char what[192];
        lfio__h5_format_dims(at, sizeof at, w->rank, offset);
        snprintf(what, sizeof what, "cannot look up the chunk at %s", at);
        return lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, what);
    }
    if (size == 0) { /* not stored; counted: a message says how many */
        if (w->missing++ == 0)
            memcpy(w->first_missing, offset, sizeof w->first_missing);
        return LFIO_OK;
    }
    if (size < w->least || size > w->most) {
        lfio__h5_format_dims(at, sizeof at, w->rank, offset);
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: the chunk at %s stores %llu bytes; its filters make %llu to %llu",
                          path, obj, at, (unsigned long long)size, (unsigned long long)w->least,
                          (unsigned long long)w->most);
    }
    w->stored += size;
    if (w->stored > w->file) /* chunks sharing bytes: an index pointing many chunks at one stream */
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: its chunks store more bytes than the file holds (%llu): they "
                          "overlap", path, obj, (unsigned long long)w->file);
    return LFIO_OK;
}

/* Looks up every chunk of dataset d (obj) on its grid, in order, by its coordinates: the index is
 * asked w->count questions, never walked (a cycle in it cannot make this loop). @return LFIO_OK or LFIO_ERR_FORMAT. */
static lfio_status walk_chunks(const char *path, const char *obj, hid_t d, chunk_walk *w)
{
    hsize_t offset[H5S_MAX_RANK] = {0};
    lfio_status st = LFIO_OK;
    for (uint64_t k = 0; st == LFIO_OK && k < w->count; k++) {
        st = check_chunk(path, obj, d, offset, w);
        for (int a = w->rank - 1; a >= 0; a--) { /* the next grid position, last axis fastest */
            offset[a] += w->chunk[a];
            if (offset[a] < w->dims[a])
                break;
            offset[a] = 0;
        }
    }
    /* Chunks never written read as the fill value: accepted (other writers leave them out) while what the
     * dataset declares stays within what its stored bytes could inflate to, so that reading it allocates
     * in proportion to the file, never a size declared with nothing behind it. */
    uint64_t declared = w->count * w->chunk_bytes; /* no overflow: at most the file's bytes times 4 MiB */
    if (st == LFIO_OK && w->missing > 0 && (w->whole || declared / LFIO__H5_INFLATE_MAX > w->stored)) {
        char at[128];
        lfio__h5_format_dims(at, sizeof at, w->rank, w->first_missing);
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: %llu of its %llu chunks are not stored (the first at %s): it "
                        "declares %llu bytes of values and stores %llu", path, obj, (unsigned long long)w->missing,
                        (unsigned long long)w->count, at, (unsigned long long)declared, (unsigned long long)w->stored);
    }
    return st;
}

/* Checks chunked dataset d (obj, layout l, created with dcpl, filters pl) and every one of its chunks;
 * with whole, refuses any chunk not stored. @return LFIO_OK or LFIO_ERR_FORMAT. */
static lfio_status check_chunked(const char *path, const char *obj, hid_t d, hid_t dcpl, const lfio__h5_layout *l,
                                 const pipeline *pl, uint64_t file, int whole)
{
    chunk_walk w = {.rank = l->rank, .file = file, .count = 1, .whole = whole};
    if (H5Pget_chunk(dcpl, l->rank, w.chunk) != l->rank)
        return lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, "cannot read its chunk shape");
    uint64_t chunk_bytes = l->size;
    for (int a = 0; a < l->rank; a++) {
        w.dims[a] = l->dims[a];
        if (w.chunk[a] == 0 || !lfio__mul_u64(chunk_bytes, w.chunk[a], &chunk_bytes))
            chunk_bytes = UINT64_MAX;
        else
            w.count *= (w.dims[a] + w.chunk[a] - 1) / w.chunk[a]; /* at most the elements: dims were checked */
    }
    if (chunk_bytes > LFIO__H5_CHUNK_MAX) {
        char shape[128];
        lfio__h5_format_dims(shape, sizeof shape, l->rank, w.chunk);
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: chunks of %s values, more than the %zu bytes a chunk may hold",
                          path, obj, shape, LFIO__H5_CHUNK_MAX);
    }
    /* v1 and v2 B-trees are walked recursively by HDF5, without a bound on their depth (a cycle in a v1
     * tree recurses until the stack overflows), and v1 nodes carry no checksum; HDF5 1.10 gives every
     * dataset lfio writes one of the others, whose depth is fixed. */
    H5D_chunk_index_t index;
    if (H5Dget_chunk_index_type(d, &index) < 0)
        return lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, "cannot read its chunk index type");
    if (index != H5D_CHUNK_IDX_SINGLE && index != H5D_CHUNK_IDX_NONE && index != H5D_CHUNK_IDX_FARRAY &&
        index != H5D_CHUNK_IDX_EARRAY)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: its chunks are indexed by a %s B-tree, which lfio does not walk: "
                          "it reads the chunk indexes of HDF5 1.10's file format (h5repack or h5py's "
                          "libver=\"v110\" writes them)", path, obj, index == H5D_CHUNK_IDX_BTREE ? "version 1" : "version 2");
    w.chunk_bytes = chunk_bytes;
    w.least = stored_least(chunk_bytes, pl);
    w.most = stored_most(chunk_bytes, pl);
    /* every chunk takes at least w.least bytes of the file: a count beyond that is refused before the walk */
    if (w.count > file / w.least)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: declares %llu chunks of at least %llu stored bytes each, more "
                          "than the file's %llu bytes hold", path, obj, (unsigned long long)w.count,
                          (unsigned long long)w.least, (unsigned long long)file);
    return walk_chunks(path, obj, d, &w);
}

/* Checks that the layout of dataset obj (from its creation list dcpl) keeps its values in the file
 * itself, chunked or contiguous. @return LFIO_OK or LFIO_ERR_FORMAT. */
static lfio_status check_layout(const char *path, const char *obj, hid_t dcpl, H5D_layout_t layout)
{
    int external = layout == H5D_VIRTUAL ? 0 : H5Pget_external_count(dcpl);
    if (layout == H5D_LAYOUT_ERROR || external < 0)
        return lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, "cannot read its storage layout");
    if (layout == H5D_VIRTUAL)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: is a virtual dataset, whose values come from other datasets or "
                          "files: lfio reads only data stored in the file", path, obj);
    if (external > 0)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: keeps its values in %d external file(s): lfio reads only data "
                          "stored in the file", path, obj, external);
    if (layout != H5D_CHUNKED && layout != H5D_CONTIGUOUS)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: is stored %s: lfio reads chunked and contiguous datasets only",
                          path, obj, layout == H5D_COMPACT ? "compact, in its object header" : "in an unknown layout");
    return LFIO_OK;
}

/* @return the little-endian unsigned integer of n bytes (n <= 8) at p. */
static uint64_t get_le(const unsigned char *p, unsigned n)
{
    uint64_t v = 0;
    for (unsigned k = n; k-- > 0;)
        v = v << 8 | p[k];
    return v;
}

/* Finds the class of the layout message among the messages of an object header's first chunk, h[0..n)
 * (version 1 or 2 of the format). @return 0 compact, 1 contiguous, 2 chunked, 3 virtual; -1 if the
 * header is of another version, damaged, or has its layout elsewhere. */
static int header_layout_class(const unsigned char *h, size_t n)
{
    size_t at, end, head; /* first message, end of the chunk's messages, bytes of a message's header */
    int v2 = n >= 6 && memcmp(h, "OHDR", 4) == 0 && h[4] == 2;
    if (v2) {
        unsigned flags = h[5], width = 1u << (flags & 3);
        at = 6 + (flags & 0x20 ? 16 : 0) + (flags & 0x10 ? 4 : 0);
        if (at + width > n)
            return -1;
        end = at + width + (size_t)get_le(h + at, width);
        at += width;
        head = 4 + (flags & 0x04 ? 2 : 0);
    } else if (n >= 16 && h[0] == 1) {
        at = 16;
        end = 16 + (size_t)get_le(h + 8, 4);
        head = 8;
    } else {
        return -1;
    }
    end = end < n ? end : n;
    while (at + head <= end) {
        unsigned type = v2 ? h[at] : (unsigned)get_le(h + at, 2);
        size_t size = (size_t)get_le(h + at + (v2 ? 1 : 2), 2);
        const unsigned char *m = h + at + head;
        if (type == 8 && at + head + 3 <= end) /* layout: version, then (before version 3, after the rank) class */
            return m[0] >= 3 ? m[1] : m[2];
        at += head + size;
    }
    return -1;
}

/* Reads the first chunk of the object header of object name of g (a hard link) from the file itself and
 * @return the class of its layout message (header_layout_class()), -1 if it cannot tell. HDF5 decodes a
 * virtual dataset's layout from the global heap as it opens the dataset, and a crafted heap makes
 * HDF5 1.10.8 loop there: a virtual dataset must be refused before H5Dopen2(). */
static int stored_layout_class(const char *path, hid_t g, const char *name)
{
    H5O_info_t info;
    hsize_t base = 0;
    hid_t file = H5Iget_file_id(g), fcpl = file >= 0 ? H5Fget_create_plist(file) : -1;
    int known = fcpl >= 0 && H5Pget_userblock(fcpl, &base) >= 0
                && H5Oget_info_by_name2(g, name, &info, H5O_INFO_BASIC, H5P_DEFAULT) >= 0 && info.addr != HADDR_UNDEF;
    lfio__h5_close(fcpl);
    lfio__h5_close(file);
    H5Eclear2(H5E_DEFAULT); /* what fails here, H5Dopen2 reports */
    unsigned char h[4096];
    int fd = known ? open(path, O_RDONLY) : -1;
    ssize_t n = fd >= 0 ? pread(fd, h, sizeof h, (off_t)(base + info.addr)) : -1;
    if (fd >= 0)
        close(fd);
    return n > 0 ? header_layout_class(h, (size_t)n) : -1;
}

lfio_status lfio__h5_open_dataset(const char *path, const char *obj, hid_t g, const char *name, hid_t dapl, hid_t *out)
{
    *out = -1;
    lfio_status st = lfio__h5_expect_link(path, obj, g, name, "dataset");
    if (st != LFIO_OK)
        return st;
    if (stored_layout_class(path, g, name) == H5D_VIRTUAL)
        return check_layout(path, obj, -1, H5D_VIRTUAL);
    hid_t d = H5Dopen2(g, name, dapl >= 0 ? dapl : H5P_DEFAULT);
    if (d < 0)
        return lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, "cannot open as a dataset");
    /* before anything asks for its extent: HDF5 opens the source files of a virtual dataset with an
     * unlimited mapping to compute it (a FIFO among them blocks the open) */
    hid_t dcpl = H5Dget_create_plist(d);
    st = dcpl < 0 ? lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, "cannot read its storage layout")
                  : check_layout(path, obj, dcpl, H5Pget_layout(dcpl));
    lfio__h5_close(dcpl);
    if (st != LFIO_OK)
        lfio__h5_close(d);
    else
        *out = d;
    return st;
}

/* Checks how dataset d (obj, layout l already matched) is stored, before any of its values is read
 * (see h5util.h); with whole, refuses any chunk not stored. @return LFIO_OK or LFIO_ERR_FORMAT. */
static lfio_status check_storage(const char *path, const char *obj, hid_t d, const lfio__h5_layout *l, int whole)
{
    uint64_t file = 0, bytes = l->size;
    lfio_status st = file_bytes(path, &file);
    if (st != LFIO_OK)
        return st;
    for (int a = 0; a < l->rank; a++)
        bytes *= l->dims[a]; /* no overflow: the callers bound the dims before they check a dataset */
    hid_t dcpl = H5Dget_create_plist(d);
    H5D_layout_t layout = dcpl < 0 ? H5D_LAYOUT_ERROR : H5Pget_layout(dcpl);
    pipeline pl;
    st = dcpl < 0 ? lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, "cannot read its storage layout")
                  : check_layout(path, obj, dcpl, layout);
    if (st == LFIO_OK)
        st = check_pipeline(path, obj, dcpl, &pl);
    if (st == LFIO_OK)
        st = layout == H5D_CONTIGUOUS ? check_contiguous(path, obj, d, bytes, file)
                                      : check_chunked(path, obj, d, dcpl, l, &pl, file, whole);
    lfio__h5_close(dcpl);
    return st;
}

lfio_status lfio__h5_expect_whole(const char *path, const char *obj, hid_t d, const lfio__h5_layout *l)
{
    return check_storage(path, obj, d, l, 1);
}

/* Sets bit k of map (atomically: readers of one lfio_reader may share it across threads). */
static void vetted_set(lfio__h5_vetted *map, uint64_t k)
{
    atomic_fetch_or(&map[k / 8], (unsigned char)(1u << (k % 8)));
}

/* What vet_chunks() needs of a dataset: its dims, chunk shape and grid, pipeline and chunk sizes. */
typedef struct vet_info {
    int rank;
    hsize_t dims[H5S_MAX_RANK], chunk[H5S_MAX_RANK], grid[H5S_MAX_RANK];
    pipeline pl;
    size_t chunk_bytes, least, most;
} vet_info;

/* Fills *v for dataset dset (obj). @return 1 if its chunks are filtered (and then need vetting), 0 if
 * not, -1 on failure (message set). */
static int vet_info_get(const char *path, const char *obj, hid_t dset, vet_info *v)
{
    hid_t dcpl = H5Dget_create_plist(dset), space = H5Dget_space(dset), t = H5Dget_type(dset);
    int chunked = dcpl >= 0 && H5Pget_layout(dcpl) == H5D_CHUNKED;
    v->rank = space >= 0 ? H5Sget_simple_extent_ndims(space) : -1;
    int ok = t >= 0 && v->rank >= 0 && v->rank <= H5S_MAX_RANK && H5Sget_simple_extent_dims(space, v->dims, NULL) >= 0
             && (!chunked || H5Pget_chunk(dcpl, v->rank, v->chunk) == v->rank);
    int rc = ok ? 0 : -1;
    if (!ok)
        lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, "cannot read its storage layout");
    else if (chunked && check_pipeline(path, obj, dcpl, &v->pl) != LFIO_OK)
        rc = -1;
    else if (chunked && (v->pl.shuffle || v->pl.deflate || v->pl.fletcher32))
        rc = 1;
    /* HDF5 makes every chunk dimension >= 1; the product stays below 2^54 until it passes the maximum */
    uint64_t bytes = rc == 1 ? H5Tget_size(t) : 0;
    for (int a = 0; rc == 1 && a < v->rank; a++) {
        bytes = bytes <= LFIO__H5_CHUNK_MAX ? bytes * v->chunk[a] : bytes;
        v->grid[a] = (v->dims[a] + v->chunk[a] - 1) / v->chunk[a];
    }
    if (rc == 1 && (bytes == 0 || bytes > LFIO__H5_CHUNK_MAX)) /* lfio__h5_check_dataset() refuses these */
        rc = -1, lfio__fail(LFIO_ERR_FORMAT, "%s: %s: chunks of more than %zu bytes", path, obj, LFIO__H5_CHUNK_MAX);
    if (rc == 1) {
        v->chunk_bytes = (size_t)bytes;
        v->least = (size_t)stored_least(bytes, &v->pl);
        v->most = (size_t)stored_most(bytes, &v->pl);
    }
    lfio__h5_close(t);
    lfio__h5_close(space);
    lfio__h5_close(dcpl);
    return rc;
}

/* Vets the chunk at offset of dataset dset (obj) with v's shape: reads it as stored, checks its filter
 * mask (every filter applied), its size and its checksum, and inflates it with lfio's bounded inflater,
 * into raw (v->most bytes) and out (v->chunk_bytes). @return LFIO_OK; LFIO_ERR_CHECKSUM; LFIO_ERR_FORMAT;
 * LFIO_ERR_IO. */
static lfio_status vet_one(const char *path, const char *obj, hid_t dset, const vet_info *v, const hsize_t *offset,
                           unsigned char *raw, unsigned char *out)
{
    uint32_t mask = 0;
    hsize_t size = 0;
    char at[128];
    lfio__h5_format_dims(at, sizeof at, v->rank, offset);
    if (stored_size(dset, offset, &size) < 0)
        return lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, "cannot look up a chunk");
    if (size == 0) /* not stored: HDF5 fills it, filtering nothing */
        return LFIO_OK;
    if (size < v->least || size > v->most)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: the chunk at %s stores %llu bytes; its filters make %zu to %zu",
                          path, obj, at, (unsigned long long)size, v->least, v->most);
    if (H5Dread_chunk(dset, H5P_DEFAULT, offset, &mask, raw) < 0)
        return lfio__h5_fail(LFIO_ERR_IO, path, obj, "cannot read a stored chunk");
    if (mask != 0)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: the chunk at %s skipped filters (filter mask 0x%x): its values "
                          "would be read without them, its checksum unchecked", path, obj, at, (unsigned)mask);
    lfio__stored c = {raw, (size_t)size, v->chunk_bytes, 1};
    int rc = lfio__chunks_check(&c, v->pl.fletcher32, v->pl.deflate, out);
    if (rc == LFIO__STORED_CHECKSUM)
        return lfio__fail(LFIO_ERR_CHECKSUM, "%s: %s: checksum mismatch (the chunk at %s)", path, obj, at);
    if (rc != LFIO__STORED_OK)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: the stored chunk at %s does not inflate to its %zu bytes", path,
                          obj, at, v->chunk_bytes);
    return LFIO_OK;
}

/* Vets every filtered chunk of dset (obj) that the hyperslab [start, start+count) touches and map (if not
 * NULL) does not mark, before HDF5 filters them: HDF5's deflate filter doubles its buffer for as long as
 * a stream goes on (lfio's stops at the chunk's size), and HDF5 skips the filters a chunk's mask names.
 * @return LFIO_OK or the first chunk's failure. */
static lfio_status vet_chunks(const char *path, const char *obj, hid_t dset, int rank, const hsize_t *start,
                              const hsize_t *count, lfio__h5_vetted *map)
{
    vet_info v;
    int need = vet_info_get(path, obj, dset, &v);
    if (need <= 0)
        return need == 0 ? LFIO_OK : LFIO_ERR_FORMAT;
    if (v.rank != rank)
        return lfio__fail(LFIO_ERR_ARG, "%s: %s: a selection of rank %d on a dataset of rank %d", path, obj, rank, v.rank);
    hsize_t first[H5S_MAX_RANK], c[H5S_MAX_RANK], offset[H5S_MAX_RANK];
    for (int a = 0; a < rank; a++)
        first[a] = c[a] = start[a] / v.chunk[a];
    unsigned char *raw = NULL, *out = NULL; /* made for the first chunk to vet: a repeated read needs none */
    lfio_status st = LFIO_OK;
    for (int more = 1; st == LFIO_OK && more;) {
        uint64_t k = 0;
        for (int a = 0; a < rank; a++) {
            k = k * v.grid[a] + c[a];
            offset[a] = c[a] * v.chunk[a];
        }
        if (map == NULL || !(atomic_load(&map[k / 8]) & (1u << (k % 8)))) {
            if (raw == NULL && ((raw = malloc(v.most)) == NULL || (out = malloc(v.chunk_bytes)) == NULL)) {
                st = lfio__fail(LFIO_ERR_NOMEM, "%s: %s: out of memory", path, obj);
                break;
            }
            st = vet_one(path, obj, dset, &v, offset, raw, out);
            if (st == LFIO_OK && map != NULL)
                vetted_set(map, k);
        }
        more = 0;
        for (int a = rank - 1; a >= 0 && !more; a--) { /* the next chunk of the selection, last axis fastest */
            if (++c[a] <= (start[a] + count[a] - 1) / v.chunk[a])
                more = 1;
            else
                c[a] = first[a];
        }
    }
    free(out);
    free(raw);
    return st;
}

size_t lfio__h5_vetted_bytes(hid_t dset)
{
    vet_info v;
    if (vet_info_get("", "", dset, &v) <= 0)
        return 0;
    uint64_t chunks = 1;
    for (int a = 0; a < v.rank; a++)
        chunks *= v.grid[a]; /* bounded by lfio__h5_check_dataset(): at most the file's bytes */
    return (size_t)((chunks + 7) / 8);
}

/* Transfers a hyperslab of dset to or from buf through transfer list dxpl; with !mine this process
 * selects nothing (its part of a collective write). An empty hyperslab transfers nothing. */
static lfio_status xfer(const char *path, const char *obj, hid_t dset, int write, hid_t mtype, int rank,
                        const hsize_t *start, const hsize_t *count, void *buf, hid_t dxpl, int mine,
                        lfio__h5_vetted *vetted)
{
    hsize_t nelem = 1;
    for (int k = 0; k < rank; k++)
        nelem *= count[k];
    if (nelem == 0)
        return LFIO_OK;
    lfio_status st = write ? LFIO_OK : vet_chunks(path, obj, dset, rank, start, count, vetted);
    if (st != LFIO_OK)
        return st;
    hid_t fspace = H5Dget_space(dset);
    /* the memory space has the selection's shape (buf is packed row-major): HDF5 then copies whole
     * rows, where a flat one against a 2-D selection took its element-by-element iterator */
    hid_t mspace = H5Screate_simple(rank, count, NULL);
    herr_t rc = -1;
    int selected = fspace >= 0 && mspace >= 0
                   && (mine ? H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start, NULL, count, NULL)
                            : (H5Sselect_none(fspace) < 0 ? -1 : H5Sselect_none(mspace))) >= 0;
    if (selected)
        rc = write ? H5Dwrite(dset, mtype, mspace, fspace, dxpl, buf)
                   : H5Dread(dset, mtype, mspace, fspace, dxpl, buf);
    if (rc < 0) /* before closing: any HDF5 call clears the error stack */
        st = lfio__h5_fail(LFIO_ERR_IO, path, obj, write ? "cannot write" : "cannot read");
    lfio__h5_close(mspace);
    lfio__h5_close(fspace);
    return st;
}

lfio_status lfio__h5_xfer(const char *path, const char *obj, hid_t dset, int write, hid_t mtype,
                          int rank, const hsize_t *start, const hsize_t *count, void *buf)
{
    return xfer(path, obj, dset, write, mtype, rank, start, count, buf, H5P_DEFAULT, 1, NULL);
}

lfio_status lfio__h5_read_vetted(const char *path, const char *obj, hid_t dset, hid_t mtype, int rank,
                                 const hsize_t *start, const hsize_t *count, void *buf, lfio__h5_vetted *vetted)
{
    return xfer(path, obj, dset, 0, mtype, rank, start, count, buf, H5P_DEFAULT, 1, vetted);
}

#ifdef LFIO_MPI
/* @return 1 if dset's file was opened with the MPI-IO driver (lfio__h5_write_collective), else 0. */
static int written_collectively(hid_t dset)
{
    hid_t file = H5Iget_file_id(dset);
    hid_t fapl = file >= 0 ? H5Fget_access_plist(file) : -1;
    int mpio = fapl >= 0 && H5Pget_driver(fapl) == H5FD_MPIO;
    lfio__h5_close(fapl);
    lfio__h5_close(file);
    return mpio;
}
#endif

lfio_status lfio__h5_write_part(const char *path, const char *obj, hid_t dset, hid_t mtype, int rank,
                                const hsize_t *start, const hsize_t *count, const void *buf, int mine)
{
#ifdef LFIO_MPI
    if (written_collectively(dset)) {
        /* Filtered (deflated, checksummed) datasets take parallel writes only collectively. */
        static const char nothing = 0;
        hid_t dxpl = H5Pcreate(H5P_DATASET_XFER);
        if (dxpl < 0 || H5Pset_dxpl_mpio(dxpl, H5FD_MPIO_COLLECTIVE) < 0) {
            lfio__h5_close(dxpl);
            return lfio__h5_fail(LFIO_ERR_IO, path, obj, "cannot set up a collective write");
        }
        lfio_status st = xfer(path, obj, dset, 1, mtype, rank, start, count, (void *)(mine ? buf : &nothing),
                              dxpl, mine, NULL);
        lfio__h5_close(dxpl);
        return st;
    }
#endif
    return mine ? xfer(path, obj, dset, 1, mtype, rank, start, count, (void *)buf, H5P_DEFAULT, 1, NULL) : LFIO_OK;
}

/* ----------------------------------------------------------------- attributes */

/* Creates attribute name on id with file type ftype over space and writes buf (memory type mtype). */
static lfio_status put_attr(const char *path, const char *obj, hid_t id, const char *name, hid_t ftype,
                            hid_t space, hid_t mtype, const void *buf)
{
    lfio_status st = LFIO_OK;
    hid_t a = H5Acreate2(id, name, ftype, space, H5P_DEFAULT, H5P_DEFAULT);
    if (a < 0 || H5Awrite(a, mtype, buf) < 0) {
        char what[96];
        snprintf(what, sizeof what, "cannot write attribute '%s'", name);
        st = lfio__h5_fail(LFIO_ERR_IO, path, obj, what);
    }
    lfio__h5_close(a);
    return st;
}

/* Writes string attribute name = value as a fixed-length, NUL-terminated string (ASCII unless value is not). */
lfio_status lfio__h5_put_str_attr(const char *path, const char *obj, hid_t id, const char *name,
                                  const char *value)
{
    int ascii = 1;
    for (const unsigned char *c = (const unsigned char *)value; *c; c++)
        ascii &= *c < 128;
    hid_t t = H5Tcopy(H5T_C_S1);
    hid_t space = H5Screate(H5S_SCALAR);
    lfio_status st;
    if (t < 0 || space < 0 || H5Tset_size(t, strlen(value) + 1) < 0
        || H5Tset_strpad(t, H5T_STR_NULLTERM) < 0
        || H5Tset_cset(t, ascii ? H5T_CSET_ASCII : H5T_CSET_UTF8) < 0)
        st = lfio__h5_fail(LFIO_ERR_IO, path, obj, "cannot make a string type");
    else
        st = put_attr(path, obj, id, name, t, space, t, value);
    lfio__h5_close(space);
    lfio__h5_close(t);
    return st;
}

/* Writes a numeric attribute: a scalar when count is 0, else a 1-D array of count values. */
lfio_status lfio__h5_put_num_attr(const char *path, const char *obj, hid_t id, const char *name,
                                  hid_t ftype, hid_t mtype, hsize_t count, const void *value)
{
    hid_t space = count ? H5Screate_simple(1, &count, NULL) : H5Screate(H5S_SCALAR);
    lfio_status st = space < 0 ? lfio__h5_fail(LFIO_ERR_IO, path, obj, "cannot make a dataspace")
                               : put_attr(path, obj, id, name, ftype, space, mtype, value);
    lfio__h5_close(space);
    return st;
}

/*
 * Opens attribute name of id and checks that it holds count elements (count 1:
 * a scalar or [1]; otherwise a 1-D array) of class cls, each at most max_size bytes.
 * @return LFIO_OK and *out; LFIO_ERR_FORMAT (or what HDF5 reports) with *out = -1.
 */
static lfio_status open_attr(const char *path, const char *obj, hid_t id, const char *name,
                             H5T_class_t cls, hssize_t count, size_t max_size, hid_t *out)
{
    static const char *const class_names[] = {"integer", "float", "time", "string", "bitfield",
                                              "opaque", "compound", "reference", "enum",
                                              "variable-length", "array"};
    *out = -1;
    htri_t exists = H5Aexists(id, name);
    if (exists < 0)
        return lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, "cannot list attributes");
    if (exists == 0)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: missing attribute '%s'", path, obj, name);
    hid_t a = H5Aopen(id, name, H5P_DEFAULT);
    if (a < 0) {
        char what[96];
        snprintf(what, sizeof what, "cannot open attribute '%s'", name);
        return lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, what);
    }
    hid_t t = H5Aget_type(a), space = H5Aget_space(a);
    H5T_class_t got = t < 0 ? H5T_NO_CLASS : H5Tget_class(t);
    size_t size = t < 0 ? 0 : H5Tget_size(t);
    int rank = space < 0 ? -1 : H5Sget_simple_extent_ndims(space);
    hssize_t npoints = space < 0 ? -1 : H5Sget_simple_extent_npoints(space);
    int is_vlen = got == H5T_STRING && H5Tis_variable_str(t) > 0;
    lfio__h5_close(space);
    lfio__h5_close(t);
    lfio_status st = LFIO_OK;
    if (got != cls) {
        int known = got >= 0 && (size_t)got < sizeof class_names / sizeof class_names[0];
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: attribute '%s' is of class %s, expected %s", path,
                        obj, name, known ? class_names[got] : "unknown", class_names[cls]);
    } else if (rank < 0 || rank > 1 || npoints != count || (rank == 0 && count != 1)) {
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: attribute '%s' has %lld elements in %d dimensions, expected %lld",
                        path, obj, name, (long long)npoints, rank, (long long)count);
    } else if (!is_vlen && (size == 0 || size > max_size)) {
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: attribute '%s' has elements of %zu bytes, at most %zu allowed",
                        path, obj, name, size, max_size);
    }
    if (st != LFIO_OK)
        lfio__h5_close(a);
    else
        *out = a;
    return st;
}

/*
 * Reads string attribute name of id (fixed or variable length) of at most max_len bytes.
 * @return LFIO_OK and *out (malloc'd, the caller frees); an error with *out = NULL.
 */
lfio_status lfio__h5_get_str_attr(const char *path, const char *obj, hid_t id, const char *name,
                                  size_t max_len, char **out)
{
    *out = NULL;
    hid_t a;
    /* A fixed-length string of max_len characters may carry its NUL: max_len + 1 bytes. */
    lfio_status st = open_attr(path, obj, id, name, H5T_STRING, 1, max_len + 1, &a);
    if (st != LFIO_OK)
        return st;
    hid_t ftype = H5Aget_type(a);
    hid_t mtype = H5Tcopy(ftype);
    char what[96];
    snprintf(what, sizeof what, "cannot read attribute '%s'", name);
    if (ftype < 0 || mtype < 0) {
        st = lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, what);
    } else if (H5Tis_variable_str(ftype) > 0) {
        /* The memory type copies the file's character set: HDF5 refuses to convert between sets. */
        char *text = NULL;
        if (H5Aread(a, mtype, &text) < 0 || text == NULL)
            st = lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, what);
        else if (strlen(text) > max_len)
            st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: attribute '%s' is longer than %zu bytes",
                            path, obj, name, max_len);
        else if ((*out = malloc(strlen(text) + 1)) == NULL)
            st = lfio__fail(LFIO_ERR_NOMEM, "%s: %s: out of memory", path, obj);
        else
            strcpy(*out, text);
        if (text)
            H5free_memory(text);
    } else {
        size_t size = H5Tget_size(ftype); /* checked <= max_len + 1 by open_attr() */
        *out = calloc(size + 1, 1);
        if (*out == NULL)
            st = lfio__fail(LFIO_ERR_NOMEM, "%s: %s: out of memory", path, obj);
        else if (H5Aread(a, mtype, *out) < 0)
            st = lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, what);
        else if (strlen(*out) > max_len)
            st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: attribute '%s' is longer than %zu bytes",
                            path, obj, name, max_len);
    }
    lfio__h5_close(mtype);
    lfio__h5_close(ftype);
    lfio__h5_close(a);
    if (st != LFIO_OK) {
        free(*out);
        *out = NULL;
    }
    return st;
}

/* Checks that string attribute name of id equals expected. @return LFIO_OK or LFIO_ERR_FORMAT. */
lfio_status lfio__h5_expect_str_attr(const char *path, const char *obj, hid_t id, const char *name,
                                     const char *expected)
{
    char *text;
    lfio_status st = lfio__h5_get_str_attr(path, obj, id, name, LFIO__H5_TEXT_MAX, &text);
    if (st == LFIO_OK && strcmp(text, expected) != 0)
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: attribute '%s' is '%s', expected '%s'", path, obj,
                        name, text, expected);
    free(text);
    return st;
}

/* Reads count doubles from float attribute name of id and checks that they are finite. */
lfio_status lfio__h5_get_f64_attr(const char *path, const char *obj, hid_t id, const char *name,
                                  hssize_t count, double *out)
{
    hid_t a;
    lfio_status st = open_attr(path, obj, id, name, H5T_FLOAT, count, 8, &a);
    if (st != LFIO_OK)
        return st;
    if (H5Aread(a, H5T_NATIVE_DOUBLE, out) < 0) {
        char what[96];
        snprintf(what, sizeof what, "cannot read attribute '%s'", name);
        st = lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, what);
    }
    for (hssize_t k = 0; st == LFIO_OK && k < count; k++)
        if (!isfinite(out[k]))
            st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: attribute '%s' is not finite", path, obj, name);
    lfio__h5_close(a);
    return st;
}

/* Reads scalar integer attribute name of id (any width up to 64 bits) and checks lo <= value <= hi. */
lfio_status lfio__h5_get_int_attr(const char *path, const char *obj, hid_t id, const char *name,
                                  int64_t lo, int64_t hi, int64_t *out)
{
    hid_t a;
    lfio_status st = open_attr(path, obj, id, name, H5T_INTEGER, 1, 8, &a);
    if (st != LFIO_OK)
        return st;
    /* HDF5 clips out-of-range values on conversion, and clipped values fail the range test. */
    if (H5Aread(a, H5T_NATIVE_INT64, out) < 0) {
        char what[96];
        snprintf(what, sizeof what, "cannot read attribute '%s'", name);
        st = lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, what);
    } else if (*out < lo || *out > hi) {
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: attribute '%s' = %lld is outside [%lld, %lld]",
                        path, obj, name, (long long)*out, (long long)lo, (long long)hi);
    }
    lfio__h5_close(a);
    return st;
}

/* -------------------------------------------------------------------- groups */

/* Checks that link name of g exists and is a hard link, telling a damaged group from a missing link
 * (see h5util.h). H5Lget_info reads the link alone: a soft or external one is not followed. */
lfio_status lfio__h5_expect_link(const char *path, const char *obj, hid_t g, const char *name, const char *what)
{
    htri_t exists = H5Lexists(g, name, H5P_DEFAULT);
    if (exists < 0)
        return lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, "cannot look it up");
    if (!exists)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: missing %s", path, obj, what);
    H5L_info_t info;
    if (H5Lget_info(g, name, &info, H5P_DEFAULT) < 0)
        return lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, "cannot look it up");
    if (info.type == H5L_TYPE_HARD)
        return LFIO_OK;
    return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: is %s: lfio follows no links (it reads nothing from elsewhere in "
                      "the file or from other files)", path, obj,
                      info.type == H5L_TYPE_SOFT ? "a soft link" : info.type == H5L_TYPE_EXTERNAL ? "an external link"
                                                                                            : "a user-defined link");
}

/* Checks that group g (obj) keeps its links in its object header or in a dense index (HDF5 1.8's formats
 * and later: a v2 B-tree whose depth is bounded), not in a symbol table: its version 1 B-tree carries no
 * checksum and HDF5 walks it recursively without a bound (a node that is its own child overflows the
 * stack). The header says which, before any link of the group is looked up. */
static lfio_status check_group_format(const char *path, const char *obj, hid_t g)
{
    H5O_info_t info;
    if (H5Oget_info2(g, &info, H5O_INFO_HDR) < 0)
        return lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, "cannot read its object header");
    const unsigned symbol_table_message = 0x11; /* H5O_STAB_ID of the file format */
    if (info.hdr.mesg.present & ((uint64_t)1 << symbol_table_message))
        return lfio__fail(LFIO_ERR_FORMAT, "%s: %s: is a group of HDF5's original format, whose links a version 1 "
                          "B-tree indexes, which lfio does not walk (h5repack or h5py's libver=\"v110\" writes "
                          "groups lfio reads)", path, obj);
    return LFIO_OK;
}

lfio_status lfio__h5_open_group(const char *path, const char *obj, hid_t parent, const char *name, const char *what,
                                hid_t *out)
{
    *out = -1;
    lfio_status st = lfio__h5_expect_link(path, obj, parent, name, what);
    if (st != LFIO_OK)
        return st;
    hid_t g = H5Gopen2(parent, name, H5P_DEFAULT);
    if (g < 0)
        return lfio__h5_fail(LFIO_ERR_FORMAT, path, obj, "cannot open as a group");
    if ((st = check_group_format(path, obj, g)) != LFIO_OK)
        lfio__h5_close(g);
    else
        *out = g;
    return st;
}

/* Creates group name in parent with its attributes in its checksummed object header (see h5util.h). */
lfio_status lfio__h5_create_group(const char *path, const char *obj, hid_t parent, const char *name, hid_t *out)
{
    hid_t gcpl = H5Pcreate(H5P_GROUP_CREATE);
    *out = gcpl >= 0 && H5Pset_attr_phase_change(gcpl, 64, 64) >= 0 && H5Pset_obj_track_times(gcpl, 0) >= 0
               ? H5Gcreate2(parent, name, H5P_DEFAULT, gcpl, H5P_DEFAULT)
               : -1;
    lfio_status st = *out < 0 ? lfio__h5_fail(LFIO_ERR_IO, path, obj, "cannot create group") : LFIO_OK;
    lfio__h5_close(gcpl);
    return st;
}

/* ------------------------------------------------------------------ datasets */

/* @return the little-endian file datatype of l: IEEE float, or unsigned integer of l's size. */
hid_t lfio__h5_file_type(const lfio__h5_layout *l)
{
    if (l->cls == H5T_INTEGER)
        return l->size == 4 ? H5T_STD_U32LE : H5T_STD_U8LE;
    return l->size == 4 ? H5T_IEEE_F32LE : H5T_IEEE_F64LE;
}

/* Creates dataset l in group g, chunked and checksummed, with units and axes (see h5util.h). */
lfio_status lfio__h5_create_dataset(const char *path, const char *gobj, hid_t g,
                                    const lfio__h5_layout *l, hid_t *out)
{
    char obj[128];
    snprintf(obj, sizeof obj, "%s/%s", gobj, l->name);
    *out = -1;
    lfio_status st = LFIO_OK;
    /* A chunk may not exceed a fixed dimension, so an empty axis is made extensible:
     * every dataset then keeps the same chunked, checksummed layout, also when empty. */
    hsize_t maxdims[4];
    for (int k = 0; k < l->rank; k++)
        maxdims[k] = l->dims[k] == 0 ? H5S_UNLIMITED : l->dims[k];
    /* A name with a path in it (a mask level) goes into a group its writer made: HDF5 would make a
     * missing one with default properties, which record times. */
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    hid_t space = H5Screate_simple(l->rank, l->dims, maxdims);
    /* Fletcher32 goes last so it covers the bytes as stored and is checked first on reading. */
    int ok = dcpl >= 0 && space >= 0
             && H5Pset_chunk(dcpl, l->rank, l->chunk) >= 0
             && (!l->deflate || (H5Pset_shuffle(dcpl) >= 0 && H5Pset_deflate(dcpl, (unsigned)l->deflate) >= 0))
             && H5Pset_fletcher32(dcpl) >= 0 && H5Pset_obj_track_times(dcpl, 0) >= 0;
    if (ok)
        *out = H5Dcreate2(g, l->name, lfio__h5_file_type(l), space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    if (*out < 0)
        st = lfio__h5_fail(LFIO_ERR_IO, path, obj, "cannot create dataset");
    lfio__h5_close(space);
    lfio__h5_close(dcpl);
    if (st == LFIO_OK)
        st = lfio__h5_put_str_attr(path, obj, *out, "units", l->units);
    if (st == LFIO_OK)
        st = lfio__h5_put_str_attr(path, obj, *out, "axes", l->axes);
    if (st != LFIO_OK) {
        lfio__h5_close(*out);
        *out = -1;
    }
    return st;
}

/* Describes an element type for messages, e.g. "float of 8 bytes". */
static void describe_type(char *buf, size_t size, H5T_class_t cls, size_t elem)
{
    snprintf(buf, size, "%s of %zu bytes",
             cls == H5T_FLOAT ? "float" : cls == H5T_INTEGER ? "integer" : "non-numeric type", elem);
}

/* Opens dataset l of group g and checks its type, shape, units and axes against l (see h5util.h). */
lfio_status lfio__h5_check_dataset(const char *path, const char *gobj, hid_t g, const lfio__h5_layout *l,
                                   const char *source, hid_t dapl, hid_t *out)
{
    char obj[128], got[64], want[64];
    snprintf(obj, sizeof obj, "%s/%s", gobj, l->name);
    if (out)
        *out = -1;
    hid_t d;
    lfio_status st = lfio__h5_open_dataset(path, obj, g, l->name, dapl, &d);
    if (st != LFIO_OK)
        return st;
    hid_t t = H5Dget_type(d), space = H5Dget_space(d);
    H5T_class_t cls = t < 0 ? H5T_NO_CLASS : H5Tget_class(t);
    size_t elem = t < 0 ? 0 : H5Tget_size(t);
    int simple = space >= 0 && H5Sget_simple_extent_type(space) == H5S_SIMPLE;
    int rank = simple ? H5Sget_simple_extent_ndims(space) : -1;
    hsize_t dims[H5S_MAX_RANK];
    if (rank >= 0 && rank <= H5S_MAX_RANK && H5Sget_simple_extent_dims(space, dims, NULL) < 0)
        rank = -1;
    lfio__h5_close(space);
    lfio__h5_close(t);
    st = LFIO_OK;
    int same_dims = rank == l->rank;
    for (int k = 0; same_dims && k < rank; k++)
        same_dims = dims[k] == l->dims[k];
    if (cls != l->cls || elem != l->size) {
        describe_type(got, sizeof got, cls, elem);
        describe_type(want, sizeof want, l->cls, l->size);
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: element type is %s, expected %s", path, obj, got, want);
    } else if (!same_dims) {
        if (rank >= 0)
            lfio__h5_format_dims(got, sizeof got, rank, dims);
        else
            snprintf(got, sizeof got, "not a simple array");
        lfio__h5_format_dims(want, sizeof want, l->rank, l->dims);
        st = lfio__fail(LFIO_ERR_FORMAT, "%s: %s: dims mismatch: shape %s, expected %s from %s",
                        path, obj, got, want, source);
    }
    if (st == LFIO_OK)
        st = check_storage(path, obj, d, l, 0);
    if (st == LFIO_OK)
        st = lfio__h5_expect_str_attr(path, obj, d, "units", l->units);
    if (st == LFIO_OK)
        st = lfio__h5_expect_str_attr(path, obj, d, "axes", l->axes);
    if (st == LFIO_OK && out)
        *out = d;
    else
        lfio__h5_close(d);
    return st;
}

/* ------------------------------------------------------------------- files */

/* Bounds fapl's metadata cache to METADATA_CACHE_MAX. @return 0, or -1 if HDF5 refuses. */
static int small_metadata_cache(hid_t fapl)
{
    H5AC_cache_config_t cfg;
    cfg.version = H5AC__CURR_CACHE_CONFIG_VERSION;
    if (H5Pget_mdc_config(fapl, &cfg) < 0)
        return -1;
    cfg.set_initial_size = 1;
    cfg.initial_size = METADATA_CACHE_MAX / 2;
    cfg.min_size = METADATA_CACHE_MAX / 4;
    cfg.max_size = METADATA_CACHE_MAX;
    return H5Pset_mdc_config(fapl, &cfg) < 0 ? -1 : 0;
}

/* @return a file creation property list whose root group records no times (every object lfio
 * creates records none: the same content gives the same bytes), or -1. */
static hid_t untimed_fcpl(void)
{
    hid_t fcpl = H5Pcreate(H5P_FILE_CREATE);
    if (fcpl >= 0 && H5Pset_obj_track_times(fcpl, 0) < 0) {
        lfio__h5_close(fcpl);
        return -1;
    }
    return fcpl;
}

/* Records the failure of step for path. @return LFIO_ERR_NOMEM for ENOMEM, else LFIO_ERR_IO. */
static lfio_status atomic_fail(const char *path, int err, const char *step)
{
    if (err == ENOMEM)
        return lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", path);
    return lfio__fail(LFIO_ERR_IO, "%s: %s: %s", path, step, strerror(err));
}

/*
 * Builds the file on fd, the temporary, through lfio's streaming driver
 * (h5stream.c): HDF5 writes as it goes, so memory holds its caches rather
 * than the file. HDF5 1.10 cannot recover from a write failing inside
 * H5Dclose/H5Fclose (HDFFV-11052); the driver never lets one fail, keeps its
 * error for here and finishes the file in memory, which is then discarded.
 * @return LFIO_OK; an error (LFIO_ERR_IO naming the temporary's failure).
 */
static lfio_status build_and_write(const char *path, const char *name, lfio__h5_fill_fn fill, const void *content,
                                   int fd)
{
    lfio_status st = LFIO_OK;
    /* the driver's error cell: freed once HDF5 has closed the file (see lfio__h5_stream_fapl()) */
    int *err = calloc(1, sizeof *err);
    if (err == NULL)
        return lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", path);
    hid_t driver = lfio__h5_stream_register(), fapl = driver >= 0 ? H5Pcreate(H5P_FILE_ACCESS) : -1;
    /* Version 1.8+ structures carry metadata checksums; strong close releases every
     * object with the file, so no forgotten id outlives it. */
    if (fapl < 0 || lfio__h5_stream_fapl(fapl, driver, fd, err) != 0
        || H5Pset_libver_bounds(fapl, H5F_LIBVER_V110, H5F_LIBVER_LATEST) < 0
        || H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG) < 0 || small_metadata_cache(fapl) < 0)
        st = lfio__h5_fail(LFIO_ERR_IO, path, "/", "cannot set file access properties");
    /* Evicting each object from the metadata cache when it is closed keeps memory to the
     * objects open at once: otherwise HDF5 held every written object's decoded header
     * (attributes, dataspaces) until the file closed, 24 MB for the classroom's 3,035 maps.
     * An optimisation only: a parallel HDF5 before 1.14.3 refuses it for every driver, and
     * the file is the same without it. */
    if (st == LFIO_OK && H5Pset_evict_on_close(fapl, 1) < 0)
        H5Eclear2(H5E_DEFAULT); /* no stale entry for a later failure's message */
    hid_t fcpl = st == LFIO_OK ? untimed_fcpl() : -1;
    /* name (the temporary's) is only HDF5's: the driver writes to fd */
    hid_t file = fcpl >= 0 ? H5Fcreate(name, H5F_ACC_TRUNC, fcpl, fapl) : -1;
    if (st == LFIO_OK && file < 0)
        st = lfio__h5_fail(LFIO_ERR_IO, path, "/", "cannot create the file");
    lfio__h5_close(fapl);
    lfio__h5_close(fcpl);
    if (st == LFIO_OK)
        st = fill(path, file, content);
    /* closing writes what HDF5 still caches; no write fails inside it (see above) */
    int closed = file < 0 || H5Fclose(file) >= 0;
    if (!closed && st == LFIO_OK)
        st = lfio__h5_fail(LFIO_ERR_IO, path, "/", "cannot close the file");
    /* the driver's own error says more than HDF5's (out of memory opening it, or the disk's reason) */
    if (*err != 0 && (st == LFIO_OK || st == LFIO_ERR_IO))
        st = atomic_fail(path, *err, "cannot write the temporary file");
    /* a file HDF5 could not close keeps the driver and its error cell, which it may still use at exit */
    if (closed) {
        free(err);
        if (driver >= 0)
            H5FDunregister(driver);
    }
    H5Eclear2(H5E_DEFAULT);
    return st;
}

/* Builds the file in a temporary beside path and puts it in place (ilf/atomic_file.h). */
lfio_status lfio__h5_write_atomic(const char *path, lfio__h5_fill_fn fill, const void *content)
{
    lfio__h5_quiet q;
    lfio__h5_quiet_begin(&q);
    ilf_atomic *a = NULL;
    const char *step = NULL;
    int err = ilf_atomic_new(path, &a, &step);
    lfio_status st = err != 0 ? atomic_fail(path, err, step) : LFIO_OK;
    if (st == LFIO_OK)
        st = build_and_write(path, ilf_atomic_temp_path(a), fill, content, ilf_atomic_fd(a));
    if (st == LFIO_OK && (err = ilf_atomic_commit(a, &step)) != 0)
        st = atomic_fail(path, err, step);
    ilf_atomic_release(a); /* removes the temporary unless it was put in place */
    lfio__h5_quiet_end(&q);
    return st;
}

#ifdef LFIO_MPI
lfio_status lfio__h5_agree_over(const char *path, lfio_status st, MPI_Comm comm)
{
    int mine = (int)st, worst = 0;
    if (MPI_Allreduce(&mine, &worst, 1, MPI_INT, MPI_MAX, comm) != MPI_SUCCESS)
        worst = LFIO_ERR_IO;
    if (st != LFIO_OK || worst == 0)
        return st;
    return lfio__fail((lfio_status)worst, "%s: another rank failed while writing it", path);
}

/* The communicator of the collective write under way in this process, or MPI_COMM_NULL. */
static MPI_Comm writing_comm = MPI_COMM_NULL;

/* Opens the temporary tmp for a collective write over comm. @return the file, or -1 (message set). */
static hid_t create_shared(const char *path, const char *tmp, MPI_Comm comm)
{
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS), fcpl = untimed_fcpl(), file = -1;
    int ready = fapl >= 0 && fcpl >= 0 && H5Pset_fapl_mpio(fapl, comm, MPI_INFO_NULL) >= 0
                && H5Pset_libver_bounds(fapl, H5F_LIBVER_V110, H5F_LIBVER_LATEST) >= 0
                && small_metadata_cache(fapl) >= 0 && H5Pset_all_coll_metadata_ops(fapl, 1) >= 0
                && H5Pset_coll_metadata_write(fapl, 1) >= 0;
    /* H5Fcreate is collective: every rank enters it or none does, or those that did would wait forever */
    lfio_status st = ready ? LFIO_OK
                           : lfio__h5_fail(LFIO_ERR_IO, path, "/", "cannot set up a collective write's properties");
    if (lfio__h5_agree_over(path, st, comm) == LFIO_OK && (file = H5Fcreate(tmp, H5F_ACC_TRUNC, fcpl, fapl)) < 0)
        lfio__h5_fail(LFIO_ERR_IO, path, "/", "cannot create the temporary file for a collective write");
    lfio__h5_close(fapl);
    lfio__h5_close(fcpl);
    return file;
}

/* The collective writer (h5util.h): rank 0 names the temporary, every rank writes its part through
 * MPI-IO, the ranks agree on the outcome, rank 0 places the file, and every rank learns its status. */
lfio_status lfio__h5_write_collective(const char *path, lfio__h5_fill_fn fill, const void *content, MPI_Comm comm)
{
    lfio__h5_quiet q;
    lfio__h5_quiet_begin(&q);
    int rank = 0;
    MPI_Comm_rank(comm, &rank);
    char *tmp = NULL;
    ilf_atomic *a = NULL;
    const char *step = NULL;
    unsigned long len = 0;
    int err = rank == 0 ? ilf_atomic_new(path, &a, &step) : 0;
    lfio_status st = err != 0 ? atomic_fail(path, err, step) : LFIO_OK;
    /* HDF5 opens the temporary by name; it stays empty until then */
    if (a != NULL && (tmp = strdup(ilf_atomic_temp_path(a))) == NULL)
        st = lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", path);
    if (rank == 0 && tmp != NULL)
        len = (unsigned long)strlen(tmp) + 1;
    if (MPI_Bcast(&len, 1, MPI_UNSIGNED_LONG, 0, comm) != MPI_SUCCESS)
        st = lfio__fail(LFIO_ERR_IO, "%s: cannot share the temporary file's name between ranks", path);
    if (rank != 0 && len > 0 && (tmp = malloc(len)) == NULL)
        st = lfio__fail(LFIO_ERR_NOMEM, "%s: out of memory", path);
    st = lfio__h5_agree_over(path, st, comm);
    if (st == LFIO_OK && MPI_Bcast(tmp, (int)len, MPI_CHAR, 0, comm) != MPI_SUCCESS)
        st = lfio__fail(LFIO_ERR_IO, "%s: cannot share the temporary file's name between ranks", path);
    hid_t file = st == LFIO_OK ? create_shared(path, tmp, comm) : -1;
    st = lfio__h5_agree_over(path, st == LFIO_OK && file < 0 ? LFIO_ERR_IO : st, comm);
    writing_comm = comm;
    if (st == LFIO_OK)
        st = fill(path, file, content);
    writing_comm = MPI_COMM_NULL;
    if (file >= 0 && H5Fclose(file) < 0 && st == LFIO_OK)
        st = lfio__h5_fail(LFIO_ERR_IO, path, "/", "cannot close the temporary file");
    st = lfio__h5_agree_over(path, st, comm);
    if (rank == 0 && st == LFIO_OK && (err = ilf_atomic_commit(a, &step)) != 0)
        st = atomic_fail(path, err, step);
    ilf_atomic_release(a); /* rank 0: removes the temporary unless it was put in place */
    /* Every rank learns whether rank 0 placed the file. */
    int placed = st == LFIO_OK;
    if (MPI_Bcast(&placed, 1, MPI_INT, 0, comm) != MPI_SUCCESS)
        placed = 0;
    if (!placed && st == LFIO_OK)
        st = lfio__fail(LFIO_ERR_IO, "%s: rank 0 could not put it in place", path);
    free(tmp);
    lfio__h5_quiet_end(&q);
    return st;
}
#endif

lfio_status lfio__h5_agree(const char *path, lfio_status st)
{
#ifdef LFIO_MPI
    if (writing_comm != MPI_COMM_NULL)
        return lfio__h5_agree_over(path, st, writing_comm);
#endif
    (void)path;
    return st;
}

/* Checks that the superblock of HDF5 file path (found where HDF5 looks for it: at byte 0, 512, 1024, 2048
 * ...) is of version 2 or later, HDF5 1.8's format, which carries a checksum. Versions 0 and 1 carry none:
 * a damaged or crafted field of theirs (the root group's address, the end of the file) reaches HDF5's
 * metadata reads unchecked, and lfio writes neither. @return LFIO_OK; LFIO_ERR_FORMAT; LFIO_ERR_IO. */
static lfio_status check_superblock(const char *path)
{
    static const unsigned char signature[8] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};
    int fd = open(path, O_RDONLY);
    struct stat sb;
    if (fd < 0 || fstat(fd, &sb) != 0) {
        lfio_status st = lfio__fail(LFIO_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
        if (fd >= 0)
            close(fd);
        return st;
    }
    int version = -1;
    unsigned char head[9];
    for (off_t at = 0; version < 0 && at + (off_t)sizeof head <= sb.st_size; at = at ? 2 * at : 512)
        if (pread(fd, head, sizeof head, at) == (ssize_t)sizeof head && memcmp(head, signature, 8) == 0)
            version = head[8];
    close(fd);
    if (version < 0)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: not an HDF5 file", path);
    if (version < 2)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: superblock of version %d (HDF5's original format, without "
                          "checksums): lfio reads files of HDF5 1.8's format and later (h5repack, or h5py's "
                          "libver=\"v110\", writes them)", path, version);
    return LFIO_OK;
}

/* Checks that path names a readable regular file in HDF5 format, before HDF5 opens it. */
static lfio_status check_file(const char *path)
{
    struct stat sb;
    if (stat(path, &sb) != 0) {
        int err = errno;
        return lfio__fail(err == ENOENT || err == ENOTDIR ? LFIO_ERR_NOTFOUND : LFIO_ERR_IO,
                          "%s: cannot open: %s", path, strerror(err));
    }
    if (!S_ISREG(sb.st_mode))
        return lfio__fail(LFIO_ERR_FORMAT, "%s: not a regular file", path);
    int fd = open(path, O_RDONLY);
    if (fd < 0)
        return lfio__fail(LFIO_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    close(fd);
    /* The file is readable, so a failing signature search means "not HDF5", not an I/O error. */
    if (H5Fis_hdf5(path) <= 0)
        return lfio__fail(LFIO_ERR_FORMAT, "%s: not an HDF5 file", path);
    return check_superblock(path);
}

/* Opens path read-only after check_file(), with strong close (see h5util.h). */
lfio_status lfio__h5_open_read(const char *path, hid_t *file)
{
    *file = -1;
    lfio_status st = check_file(path);
    if (st != LFIO_OK)
        return st;
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    if (fapl >= 0) {
        H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG);
        small_metadata_cache(fapl); /* an optimisation: on failure the default cache serves */
    }
    *file = H5Fopen(path, H5F_ACC_RDONLY, fapl >= 0 ? fapl : H5P_DEFAULT);
    if (*file < 0)
        st = lfio__h5_fail(LFIO_ERR_FORMAT, path, "/", "cannot open as HDF5");
    else if ((st = check_group_format(path, "/", *file)) != LFIO_OK) {
        lfio__h5_close(*file);
        *file = -1;
    }
    lfio__h5_close(fapl);
    return st;
}
