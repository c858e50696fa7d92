/*
 * h5util.h - the HDF5 plumbing lfio's file formats share (light field files
 * in lightfield_io.c, radiance-map files in radmap_io.c): silencing HDF5 and turning
 * its error stack into lfio messages, typed and bounded attributes, dataset
 * layouts created and checked from one description, hyperslab transfers,
 * and the atomic file writer (through h5stream.c's driver).
 *
 * Only lfio's I/O sources include this header (it includes hdf5.h).
 * Conventions of every function here:
 *   - path names the file and obj the HDF5 object in messages, which read
 *     "<path>: <obj>: <problem>"; a failing call records its message with
 *     lfio__fail() and returns the status.
 *   - An HDF5 error stack that mentions a checksum becomes LFIO_ERR_CHECKSUM.
 *   - Nothing is allocated from a size read from a file: attribute strings
 *     are bounded by the caller's maximum, datasets are checked against an
 *     expected layout before anything is read.
 *   - None of these functions silences HDF5 itself: public entry points wrap
 *     their whole body in lfio__h5_quiet_begin() / lfio__h5_quiet_end().
 *   - Nothing of a file is trusted before it is checked: the structure lfio
 *     walks holds hard links only (no soft or external links), and a dataset
 *     is read only after lfio__h5_check_dataset() has checked its storage
 *     (docs/robustness.md, "HDF5 features"): chunked or contiguous in the file
 *     itself, lfio's own filters, chunk indexes that cannot loop, chunks of
 *     a size their pipeline can produce and in proportion to the file; a
 *     filtered chunk is vetted by lfio (filter mask, checksum, a bounded
 *     inflate) before HDF5's filters see it (lfio__h5_xfer()).
 */
#ifndef LFIO_H5UTIL_H
#define LFIO_H5UTIL_H

#include <stddef.h>
#include <stdint.h>

#include <hdf5.h>

#include "lfio/lfio.h"

/* Longest free-text string attribute read from a file (units, axes, frame ...), in bytes. */
#define LFIO__H5_TEXT_MAX 1023

/* Largest chunk of a dataset lfio reads, in bytes (values, before filtering). lfio writes chunks of at
 * most 384 KiB; the bound keeps what one chunk can make HDF5 allocate, and one stored chunk inflate to,
 * small whatever a file declares. */
#define LFIO__H5_CHUNK_MAX ((size_t)4 << 20)

/* Most bytes one byte of a deflate stream inflates to: deflate codes at most 258 bytes (one match) in 2
 * bits. A dataset's declared size is held to this many times the bytes it stores. */
#define LFIO__H5_INFLATE_MAX 1032u

/* ---------------------------------------------------------------- errors */

/* The caller's HDF5 automatic error handler, saved while lfio is silent. */
typedef struct lfio__h5_quiet {
    H5E_auto2_t func;
    void *data;
} lfio__h5_quiet;

/* Saves the calling thread's HDF5 error printer and turns printing off. */
void lfio__h5_quiet_begin(lfio__h5_quiet *q);

/* Restores the printer saved by lfio__h5_quiet_begin(). */
void lfio__h5_quiet_end(const lfio__h5_quiet *q);

/*
 * Records a failure of the HDF5 call just made, as "<path>: <obj>: <what> (<reason>)".
 * Must be called before any other HDF5 call, which would clear the stack.
 * @return LFIO_ERR_CHECKSUM if the stack reports a checksum mismatch, else st.
 */
lfio_status lfio__h5_fail(lfio_status st, const char *path, const char *obj, const char *what);

/* Closes any HDF5 identifier; negative ids are ignored, which keeps cleanup paths simple. */
void lfio__h5_close(hid_t id);

/* Writes "[a, b, ...]" for the rank dims into buf. */
void lfio__h5_format_dims(char *buf, size_t size, int rank, const hsize_t *dims);

/* @return the index of the first of v[0..count) that is negative, NaN or infinite; count if none. */
size_t lfio__first_bad_value(const float *v, size_t count);

/* ------------------------------------------------------------ attributes */

/* Writes string attribute name = value as a fixed-length, NUL-terminated string (ASCII unless value is not). */
lfio_status lfio__h5_put_str_attr(const char *path, const char *obj, hid_t id, const char *name,
                                  const char *value);

/* Writes a numeric attribute (file type ftype, memory type mtype): a scalar when count is 0, else count values. */
lfio_status lfio__h5_put_num_attr(const char *path, const char *obj, hid_t id, const char *name,
                                  hid_t ftype, hid_t mtype, hsize_t count, const void *value);

/*
 * Reads string attribute name of id (fixed or variable length) of at most max_len bytes.
 * @return LFIO_OK and *out (malloc'd, the caller frees); an error with *out = NULL.
 */
lfio_status lfio__h5_get_str_attr(const char *path, const char *obj, hid_t id, const char *name,
                                  size_t max_len, char **out);

/* Checks that string attribute name of id (at most LFIO__H5_TEXT_MAX bytes) equals expected.
 * @return LFIO_OK or LFIO_ERR_FORMAT. */
lfio_status lfio__h5_expect_str_attr(const char *path, const char *obj, hid_t id, const char *name,
                                     const char *expected);

/* Reads count finite doubles from float attribute name (count 1: scalar or [1]). @return LFIO_OK or LFIO_ERR_FORMAT. */
lfio_status lfio__h5_get_f64_attr(const char *path, const char *obj, hid_t id, const char *name,
                                  hssize_t count, double *out);

/* Reads scalar integer attribute name (any width up to 64 bits) and checks lo <= value <= hi. */
lfio_status lfio__h5_get_int_attr(const char *path, const char *obj, hid_t id, const char *name,
                                  int64_t lo, int64_t hi, int64_t *out);

/* ---------------------------------------------------------------- groups */

/*
 * Checks that link name of group g exists and is a hard link (a soft link or
 * an external link, which would take the object from elsewhere or from
 * another file, is refused before it is followed); obj is the linked
 * object's full name and what its kind ("dataset") for messages.
 * @return LFIO_OK; LFIO_ERR_FORMAT "<path>: <obj>: missing <what>" or naming
 * the kind of link; or, when HDF5 cannot tell because g itself is damaged,
 * what its error stack says (LFIO_ERR_CHECKSUM for a checksum mismatch).
 */
lfio_status lfio__h5_expect_link(const char *path, const char *obj, hid_t g, const char *name, const char *what);

/*
 * Opens group name of parent (obj, its full name, and what, its kind, for
 * messages) after lfio__h5_expect_link(), and checks that it does not index
 * its links with a symbol table (HDF5's original format: a version 1 B-tree
 * without checksums, which HDF5 walks without a bound on its depth).
 * @return LFIO_OK and *out open; LFIO_ERR_FORMAT (or what HDF5 reports) with *out = -1.
 */
lfio_status lfio__h5_open_group(const char *path, const char *obj, hid_t parent, const char *name, const char *what,
                                hid_t *out);

/*
 * Creates group name in parent (obj names it in messages) with up to 64
 * attributes kept in its object header. HDF5 moves more than 8 into a
 * fractal heap, whose blocks carry no checksum: a damaged slab origin would
 * then read back silently. @return LFIO_OK and *out open; LFIO_ERR_IO with *out = -1.
 */
lfio_status lfio__h5_create_group(const char *path, const char *obj, hid_t parent, const char *name, hid_t *out);

/* -------------------------------------------------------------- datasets */

/* The stored layout of one dataset: what the writer creates and the reader expects. */
typedef struct lfio__h5_layout {
    char name[32];      /* path below the owning group */
    int rank;           /* 1 .. 4 */
    hsize_t dims[4];    /* may be 0: the dataset is then created extensible along that axis */
    hsize_t chunk[4];   /* each >= 1 */
    H5T_class_t cls;    /* H5T_FLOAT or H5T_INTEGER (unsigned) */
    size_t size;        /* element size in bytes: 4 or 8 for floats, 1 or 4 for integers */
    const char *units;  /* value of the "units" attribute */
    const char *axes;   /* value of the "axes" attribute */
    int deflate;        /* 1 to 9: shuffle and deflate at that zlib level before the checksum; 0: neither */
} lfio__h5_layout;

/* @return the little-endian file datatype of layout l. */
hid_t lfio__h5_file_type(const lfio__h5_layout *l);

/*
 * Creates dataset l in group g (gobj), chunked with a Fletcher32 checksum,
 * creating intermediate groups, with its units and axes attributes.
 * @return LFIO_OK and *out open; LFIO_ERR_IO with *out = -1.
 */
lfio_status lfio__h5_create_dataset(const char *path, const char *gobj, hid_t g,
                                    const lfio__h5_layout *l, hid_t *out);

/*
 * Opens dataset name of group g (obj, its full name, for messages) with
 * access list dapl (or the default when negative) after
 * lfio__h5_expect_link(), and checks that its values are kept in the file
 * itself (not virtual, no external storage, chunked or contiguous) before
 * anything asks for its extent, which makes HDF5 open the source files of
 * some virtual datasets. A virtual layout found in the first chunk of the
 * object header, read from the file's bytes, is refused before HDF5 opens
 * the dataset (opening decodes its mappings from the global heap).
 * @return LFIO_OK and *out open; LFIO_ERR_FORMAT with *out = -1.
 */
lfio_status lfio__h5_open_dataset(const char *path, const char *obj, hid_t g, const char *name, hid_t dapl,
                                  hid_t *out);

/*
 * Opens dataset l of group g (gobj) with access list dapl (or the default
 * when negative) and checks its link (a hard one), class, element size,
 * rank, dims, storage (see the top of this file) and its units and axes
 * without reading data; source says in messages where the expected dims
 * came from ("the slab's attributes"). Its chunks are looked up one by one,
 * after checks that bound their number by the file's size.
 * @return LFIO_OK and *out open if out is not NULL; LFIO_ERR_FORMAT.
 */
lfio_status lfio__h5_check_dataset(const char *path, const char *gobj, hid_t g, const lfio__h5_layout *l,
                                   const char *source, hid_t dapl, hid_t *out);

/*
 * Checks dataset d (obj, open and checked by lfio__h5_check_dataset() against
 * layout l) as that does, and that every one of its chunks is stored: a
 * chunk never written reads as the fill value, which lfio accepts from other
 * writers but never writes, so lfio_verify() reports it.
 * @return LFIO_OK or LFIO_ERR_FORMAT.
 */
lfio_status lfio__h5_expect_whole(const char *path, const char *obj, hid_t d, const lfio__h5_layout *l);

/*
 * Transfers the hyperslab [start, start+count) of dset to or from buf (packed,
 * row-major) as memory type mtype; an empty hyperslab transfers nothing.
 * Reading, every filtered chunk the hyperslab touches is first vetted:
 * read as stored, its filter mask checked (a chunk that skipped a filter is
 * refused), its checksum checked and its stream inflated by lfio, which
 * stops at the chunk's size. One that does not inflate to exactly its
 * chunk's bytes fails the read (LFIO_ERR_FORMAT) before HDF5's filter,
 * which would grow its buffer for as long as the stream goes on, sees it.
 * @return LFIO_OK; LFIO_ERR_IO, LFIO_ERR_FORMAT or LFIO_ERR_CHECKSUM with the message set.
 */
lfio_status lfio__h5_xfer(const char *path, const char *obj, hid_t dset, int write, hid_t mtype,
                          int rank, const hsize_t *start, const hsize_t *count, void *buf);

/* A map of the chunks of a dataset that a reader has vetted (lfio__h5_read_vetted()): one bit a chunk, in
 * row-major order of the chunk grid, set from any thread. */
typedef _Atomic unsigned char lfio__h5_vetted;

/* @return the bytes of a zeroed map for dset (see lfio__h5_read_vetted()); 0 when its chunks are not
 * filtered, which then needs none. dset must have passed lfio__h5_check_dataset(). */
size_t lfio__h5_vetted_bytes(hid_t dset);

/*
 * Reads the hyperslab [start, start+count) of dset as lfio__h5_xfer() does, vetting only the chunks map
 * does not mark yet and marking them (map: lfio__h5_vetted_bytes() zeroed bytes, or NULL to vet every
 * chunk touched): repeated partial reads of one dataset then inflate each chunk once more, not once a read.
 * @return as lfio__h5_xfer().
 */
lfio_status lfio__h5_read_vetted(const char *path, const char *obj, hid_t dset, hid_t mtype, int rank,
                                 const hsize_t *start, const hsize_t *count, void *buf, lfio__h5_vetted *map);

/*
 * Writes the hyperslab [start, start+count) of dset from buf, as lfio__h5_xfer()
 * does, when mine; when !mine writes nothing. In a file being written by
 * lfio__h5_write_collective() every rank must call it for every dataset, in
 * the same order: the transfer is collective, and a rank that is not `mine`
 * takes part with nothing selected.
 * @return LFIO_OK; LFIO_ERR_IO with the message set.
 */
lfio_status lfio__h5_write_part(const char *path, const char *obj, hid_t dset, hid_t mtype, int rank,
                                const hsize_t *start, const hsize_t *count, const void *buf, int mine);

/* ----------------------------------------------------------------- files */

/* Fills the open, empty file with its content. @return LFIO_OK or an error with the message set. */
typedef lfio_status (*lfio__h5_fill_fn)(const char *path, hid_t file, const void *content);

/*
 * Writes a file atomically: fill() builds it in a temporary beside path
 * (lfio__h5_stream_fapl(), 1.10 object formats, strong close), which is
 * fsynced and renamed over path, then the folder is fsynced.
 * On failure path is untouched and the temporary removed. Silences HDF5.
 * @return LFIO_OK; the status of fill(); LFIO_ERR_IO; LFIO_ERR_NOMEM.
 */
lfio_status lfio__h5_write_atomic(const char *path, lfio__h5_fill_fn fill, const void *content);

/*
 * Registers lfio's streaming driver (h5stream.c) with HDF5, for one write:
 * the caller unregisters it (H5FDunregister) once the file is closed, so no
 * id outlives the write or is shared between threads.
 * @return the driver's id, or -1.
 */
hid_t lfio__h5_stream_register(void);

/*
 * Makes fapl write a new, empty file straight to descriptor fd (through a
 * duplicate: fd stays the caller's) with driver, lfio__h5_stream_register()'s
 * id. HDF5 never sees a write fail: the first failure's errno is stored in
 * *err (0 at the start), the file is finished in memory, and the caller must
 * discard it. *err must outlive the file: if HDF5 fails to close it, HDF5
 * may still flush it at exit.
 * @return 0, or -1 if HDF5 refused the driver.
 */
int lfio__h5_stream_fapl(hid_t fapl, hid_t driver, int fd, int *err);

/*
 * Inside the fill() of lfio__h5_write_collective(), where one rank can fail
 * alone (a step that is not an HDF5 call), every rank calls this so that all
 * of them stop together. Elsewhere it returns st.
 * @return st if this process failed; else LFIO_OK, or an error saying another rank failed.
 */
lfio_status lfio__h5_agree(const char *path, lfio_status st);

#ifdef LFIO_MPI
/*
 * Collective over comm (every rank calls it): every rank learns whether any
 * failed, for a step where one rank can fail alone.
 * @return st if this rank failed; else LFIO_OK if every rank succeeded, or
 * an error whose message says that another rank failed writing path.
 */
lfio_status lfio__h5_agree_over(const char *path, lfio_status st, MPI_Comm comm);

/*
 * Writes a file atomically over the ranks of comm (collective: every rank
 * calls it with the same path and fill): rank 0 creates the temporary beside
 * path, every rank opens it with HDF5's MPI-IO driver (1.10 object formats,
 * collective metadata) and runs fill(), which must make the same HDF5 calls
 * on every rank; once every rank has closed it without error, rank 0 fsyncs
 * it and renames it over path, then fsyncs the folder. On failure path is
 * untouched and the temporary removed. Silences HDF5.
 * @return on every rank: LFIO_OK once the file is in place; this rank's
 * error, or another rank's (with a message saying so).
 */
lfio_status lfio__h5_write_collective(const char *path, lfio__h5_fill_fn fill, const void *content,
                                      MPI_Comm comm);
#endif

/*
 * Checks that path is a readable regular HDF5 file, then opens it read-only
 * with strong close, and checks its root group as lfio__h5_open_group() does.
 * Does not silence HDF5.
 * @return LFIO_OK and *file; LFIO_ERR_NOTFOUND, LFIO_ERR_IO or LFIO_ERR_FORMAT with *file = -1.
 */
lfio_status lfio__h5_open_read(const char *path, hid_t *file);

#endif /* LFIO_H5UTIL_H */
