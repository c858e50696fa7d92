/*
 * lfio.h - status codes, error messages and version of the lfio library.
 *
 * lfio stores sphere-plane incident light fields: slabs of positions on a
 * rectangle, each with radiance for the directions of a sphere partition
 * (see lfio/partition.h), kept in HDF5 files (see lfio/lightfield.h and
 * docs/format.md).
 *
 * Conventions for the whole library:
 *   - Every fallible call returns an lfio_status; LFIO_OK (0) is success.
 *   - On failure, lfio_errmsg() returns a message owned by the library that
 *     names the file, object and problem where there is one.
 *   - Constructors return the object through an out-parameter and leave it
 *     NULL on failure; every destroy function accepts NULL.
 *   - The library never exits or aborts on bad input.
 *
 * This header is valid C99 and C++.
 */
#ifndef LFIO_LFIO_H
#define LFIO_LFIO_H

#ifdef __cplusplus
extern "C" {
#endif

#define LFIO_VERSION_MAJOR 0
#define LFIO_VERSION_MINOR 2
#define LFIO_VERSION_PATCH 0
#define LFIO_VERSION_STRING "0.2.0"

/** Result of a fallible call. */
typedef enum lfio_status {
    LFIO_OK = 0,          /**< success */
    LFIO_ERR_ARG = 1,     /**< an argument is out of range, NULL or not finite */
    LFIO_ERR_NOMEM = 2,   /**< an allocation failed or would exceed a limit */
    LFIO_ERR_IO = 3,      /**< the operating system or HDF5 failed to read or write */
    LFIO_ERR_FORMAT = 4,  /**< a file is not a valid light field file */
    LFIO_ERR_CHECKSUM = 5,/**< stored data fails its checksum */
    LFIO_ERR_NOTFOUND = 6 /**< a named slab, file or object does not exist */
} lfio_status;

/** @return a static, human-readable name for status s ("ok", "bad argument", ...). */
const char *lfio_status_name(lfio_status s);

/**
 * @return the message of the most recent failure in the calling thread; "" if none.
 * The string is owned by the library and valid until the next lfio call in this thread.
 */
const char *lfio_errmsg(void);

/** @return the library's version string, for example "0.2.0". */
const char *lfio_version(void);

#ifdef __cplusplus
}
#endif

#endif /* LFIO_LFIO_H */
