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
 * any work (the threads' record), call_between is not called.
 * @return 0, or -1 when memory ran out (every out is then freed and NULL). */
int lfio__chunks_filter(lfio__chunk *c, size_t n, unsigned threads, void (*call_between)(void *), void *user);

/* Frees the out buffers of c[0..n). */
void lfio__chunks_free(lfio__chunk *c, size_t n);

#endif /* LFIO_CHUNKS_H */
