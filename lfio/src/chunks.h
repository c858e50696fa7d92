/*
 * chunks.h - HDF5's filter pipeline for stored chunks (shuffle, then deflate,
 * then a Fletcher-32 checksum appended), run by lfio itself so that chunks can
 * be filtered on several threads before HDF5 stores them as they are
 * (H5Dwrite_chunk). The bytes are the ones HDF5's own filters produce: a file
 * written either way reads the same, and HDF5 checks the checksum on reading.
 * Internal to lfio; no HDF5 here.
 */
#ifndef LFIO_CHUNKS_H
#define LFIO_CHUNKS_H

#include <stddef.h>
#include <stdint.h>

/* 1 where values in memory have the byte order HDF5's little-endian types store (lfio's own filtering then
 * applies), else 0. */
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
#define LFIO_LITTLE_ENDIAN 1
#else
#define LFIO_LITTLE_ENDIAN 0
#endif

/* One chunk to filter: in, its values; out, what to store. */
typedef struct lfio__chunk {
    const unsigned char *raw; /* the chunk's values present (raw_bytes), little-endian as stored */
    size_t raw_bytes;
    size_t chunk_bytes;       /* the whole chunk: past raw_bytes it holds zeros (the fill value) */
    size_t elem;              /* bytes per value, for the shuffle */
    int level;                /* zlib level, 1 .. 9 */
    unsigned char *out;       /* filtered bytes (malloc'd, the caller frees), or NULL */
    size_t out_bytes;
} lfio__chunk;

/* @return the Fletcher-32 checksum of n bytes as HDF5 computes it (16-bit big-endian words, an odd last byte as the high half). */
uint32_t lfio__fletcher32(const unsigned char *p, size_t n);

/* Filters chunks c[0..n) on up to threads threads, the calling thread among them; call_between(user)
 * runs on the calling thread first, while the others work (NULL: nothing). When memory runs out before
 * any work (the workers' scratch or the threads' record), call_between is not called.
 * @return 0, or -1 when memory ran out (every out is then freed and NULL). */
int lfio__chunks_filter(lfio__chunk *c, size_t n, unsigned threads, void (*call_between)(void *), void *user);

/* Frees the out buffers of c[0..n). */
void lfio__chunks_free(lfio__chunk *c, size_t n);

/* One stored chunk to undo the pipeline of: what HDF5 stores for it (shuffled, deflated, Fletcher-32
 * appended), to become chunk_bytes of values of elem bytes each. */
typedef struct lfio__stored {
    const unsigned char *in;
    size_t in_bytes;
    size_t chunk_bytes;
    size_t elem;
} lfio__stored;

/* @return the most bytes the pipeline stores for a chunk of chunk_bytes: zlib's bound and the checksum. */
size_t lfio__chunks_stored_most(size_t chunk_bytes);

/* What lfio__chunks_unfilter() found wrong with a chunk. */
enum { LFIO__STORED_OK, LFIO__STORED_CHECKSUM, LFIO__STORED_BROKEN, LFIO__STORED_NOMEM };

/* Checks stored chunk c of a pipeline ending in deflate when deflate, then Fletcher-32 when fletcher32: its
 * checksum, and that it holds (inflates to) exactly c->chunk_bytes; inflates it into out (that many bytes;
 * still shuffled if it was). @return LFIO__STORED_OK, LFIO__STORED_CHECKSUM or LFIO__STORED_BROKEN. */
int lfio__chunks_check(const lfio__stored *c, int fletcher32, int deflate, unsigned char *out);

/* Undoes the pipeline of c[0..n) on up to threads threads, the calling thread among them: checks each
 * chunk's checksum, inflates and unshuffles it, and hands its values to place(user, k, values) (from any of
 * the threads, values valid during the call only; chunks in any order). Stops early after a failure.
 * @return LFIO__STORED_OK, or the failure of the first failing chunk in index order (*bad its index). */
int lfio__chunks_unfilter(const lfio__stored *c, size_t n, unsigned threads,
                          void (*place)(void *user, size_t k, const unsigned char *values), void *user, size_t *bad);

#endif /* LFIO_CHUNKS_H */
