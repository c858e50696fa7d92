/*
 * common.h - status codes, error messages and progress reporting shared by
 * every part of the capture library (image I/O, manifests and capture,
 * probe projections and rendering, reprojection onto proxy geometry).
 *
 * Conventions for the whole library:
 *   - Every public name starts with cap_ (types cap_<object>, functions
 *     cap_<object>_<verb>) or CAP_ (constants).
 *   - Every fallible call returns a cap_status; CAP_OK (0) is success. On
 *     failure cap_error_message() gives one line naming the file and the
 *     element or pixel at fault, for the calling thread.
 *   - Constructors return objects through an out-parameter, NULL on failure;
 *     every destroy or free function accepts NULL.
 *   - The library never exits, aborts or prints: problems come back as a
 *     status and a message, repairs as counts in report structures.
 *   - World frame right-handed, metres; radiance linear Rec.709 RGB in
 *     W sr^-1 m^-2 or relative units, as lfio/lightfield.h states.
 *
 * This header is valid C99 and C++.
 */
#ifndef CAPTURE_COMMON_H
#define CAPTURE_COMMON_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Result of a fallible call. */
typedef enum cap_status {
    CAP_OK = 0,
    CAP_ERR_ARG = 1,    /**< an argument is NULL, out of range or not finite */
    CAP_ERR_INPUT = 2,  /**< an input (manifest, image, proxy, light field) is missing, unreadable or invalid */
    CAP_ERR_OUTPUT = 3, /**< an output could not be written */
    CAP_ERR_NOMEM = 4   /**< memory ran out, or a size exceeds a documented limit */
} cap_status;

/** @return a static name for s ("ok", "bad argument", "bad input", "cannot write", "out of memory"). */
const char *cap_status_name(cap_status s);

/**
 * @return the calling thread's most recent failure message, "" if none; owned
 * by the library and valid until the thread's next failing capture call.
 */
const char *cap_error_message(void);

/**
 * Progress callback: done of total units of work are finished. Called with
 * done increasing, never concurrently (from one thread at a time, possibly a
 * worker thread), and never after the reporting call has returned.
 */
typedef void (*cap_progress_fn)(void *user, uint64_t done, uint64_t total);

#ifdef __cplusplus
}
#endif

#endif /* CAPTURE_COMMON_H */
