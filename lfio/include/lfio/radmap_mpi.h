/*
 * radmap_mpi.h - writing a radiance-map file collectively from the ranks of
 * an MPI job. Present only in an lfio built with MPI (CMake option
 * ILFKIT_MPI, linked with a parallel HDF5); the file written is the one
 * lfio_radmap_write_each() writes (in format 2, the same bytes), read by the
 * same lfio_radmap_read(). Conventions as in lfio/radmap.h.
 *
 * Thread safety: collective over comm; one call at a time per process.
 *
 * This header is valid C99 and C++.
 */
#ifndef LFIO_RADMAP_MPI_H
#define LFIO_RADMAP_MPI_H

#include <mpi.h>

#include "lfio/radmap.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * Writes count patches to path as lfio_radmap_write_each() does, collectively
 * over comm: every rank calls it with the same arguments, and describe must
 * give every rank the same patch k (each rank checks every patch); the arrays
 * of patch k are taken from one rank (see lfio_radmap_write_with_mpi()).
 * Rank 0 writes the file (format 2; in format 1 every rank writes through
 * MPI-IO, so every rank must see path's folder) in a temporary beside path
 * and renames it over path once every rank has done its part; on failure
 * path is untouched.
 * @return on every rank: LFIO_OK once the file is in place; this rank's error,
 * or LFIO_ERR_IO (or another rank's status) with a message that another rank failed.
 */
lfio_status lfio_radmap_write_each_mpi(const char *path, const char *creator, const char *scene, size_t count,
                                       lfio_radmap_describe_fn describe, void *user, MPI_Comm comm);

/**
 * Writes a file as lfio_radmap_write_each_mpi() does, stored as opt says
 * (lfio/radmap.h; NULL: the defaults). In format 2, each rank takes the
 * cells of its own patches, a contiguous run of them (patches
 * [count * rank / size, count * (rank + 1) / size)); the chunks of the
 * compressed cell datasets are dealt evenly over the ranks by cells, each
 * rank receives from the others the cells its chunks need and compresses
 * them on opt's threads (the last rank also the compressed tables: labels,
 * frames, vertices, offsets), and rank 0 gathers every chunk and writes the file
 * alone (without MPI-IO): the bytes lfio_radmap_write_with() writes. In
 * format 1 (or where memory is big-endian), every rank writes its patches
 * through HDF5's MPI-IO driver, collectively, and threads is ignored.
 * @return as lfio_radmap_write_each_mpi(); LFIO_ERR_ARG for options out of range.
 */
lfio_status lfio_radmap_write_with_mpi(const char *path, const char *creator, const char *scene, size_t count,
                                       lfio_radmap_describe_fn describe, void *user,
                                       const lfio_radmap_write_options *opt, MPI_Comm comm);

/**
 * Writes a file as lfio_radmap_write_with_mpi() does, for a job where every
 * rank holds every patch's cells (the ranks of a relight, whose exchanges
 * leave each the whole solution): describe gives patch k without its cells
 * and rows gives them a slice at a time, as in lfio_radmap_write_with()
 * (rows NULL: the described patch's own arrays, on every rank), the same on
 * every rank. In format 2, each rank describes every patch, then takes from
 * rows only the cells of its own chunks (patch k described again first,
 * slices of at most LFIO_RADMAP_ROWS_MAX in order of first) and compresses
 * them, with no trade of cells between the ranks; rank 0 writes the file
 * as lfio_radmap_write_with_mpi() does, the same bytes. In format 1 (or
 * where memory is big-endian), rows is asked for whole patches (count up to
 * the patch's cells), as lfio_radmap_write_with_mpi() takes them. A cell
 * that fails its check is found by the rank that takes it, whose message
 * names it; the others fail with its status and a message that another rank
 * failed.
 * @return as lfio_radmap_write_with_mpi(), or rows's status.
 */
lfio_status lfio_radmap_write_rows_mpi(const char *path, const char *creator, const char *scene, size_t count,
                                       lfio_radmap_describe_fn describe, lfio_radmap_rows_fn rows, void *user,
                                       const lfio_radmap_write_options *opt, MPI_Comm comm);

#ifdef __cplusplus
}
#endif

#endif /* LFIO_RADMAP_MPI_H */
