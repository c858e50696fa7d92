/*
 * common.h - the small helpers every relight file may use: the per-thread
 * error message (rl__fail(), read by rl_errmsg()) and array growth
 * (rl__grow()), both in common.c; labels are cut by base's ilf_format_cut().
 */
#ifndef RELIGHT_COMMON_H
#define RELIGHT_COMMON_H

#include <stddef.h>

#include "ilf/message.h"
#include "relight/relight.h"

/* Records a formatted message for rl_errmsg(). @return status. */
rl_status rl__fail(rl_status status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/*
 * @return arr, or arr reallocated to hold at least need elements of size
 * bytes (capacity *cap, doubling); NULL with arr and *cap untouched on failure.
 */
void *rl__grow(void *arr, size_t *cap, size_t need, size_t size);

#endif /* RELIGHT_COMMON_H */
