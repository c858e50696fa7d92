/*
 * common.h - the small helpers every relight file may use: the per-thread
 * error message (rl__fail(), read by rl_errmsg()), bounded formatting
 * (rl__format()) and array growth (rl__grow()), all in common.c.
 */
#ifndef RELIGHT_COMMON_H
#define RELIGHT_COMMON_H

#include <stddef.h>

#include "relight/relight.h"

/* Records a formatted message for rl_errmsg(). @return status. */
rl_status rl__fail(rl_status status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* snprintf into out (cap bytes) that marks a truncated result with a trailing "...". */
void rl__format(char *out, size_t cap, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/*
 * @return arr, or arr reallocated to hold at least need elements of size
 * bytes (capacity *cap, doubling); NULL with arr and *cap untouched on failure.
 */
void *rl__grow(void *arr, size_t *cap, size_t need, size_t size);

#endif /* RELIGHT_COMMON_H */
