/*
 * common.c - the engine's per-thread error message, bounded message
 * formatting, array growth, and method names
 * (the sampling settings' table and defaults are in settings.c).
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <stdint.h>
#include <string.h>

#include "ilf/message.h"
#include "common.h"

static _Thread_local char errbuf[ILF_MESSAGE_BYTES];

const char *rl_errmsg(void)
{
    return errbuf;
}

rl_status rl__fail(rl_status status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    ilf_message_vformat(errbuf, fmt, ap);
    va_end(ap);
    return status;
}

void *rl__grow(void *arr, size_t *cap, size_t need, size_t size)
{
    if (need <= *cap && arr)
        return arr;
    size_t n = *cap ? *cap : 16;
    while (n < need) {
        if (n > SIZE_MAX / 2)
            return NULL;
        n *= 2;
    }
    if (n > SIZE_MAX / size)
        return NULL;
    void *p = realloc(arr, n * size);
    if (p)
        *cap = n;
    return p;
}

static const char *const method_names[] = {"culled", "naive", "area", "solidangle", "adaptive"};

const char *rl_method_name(rl_method m)
{
    return (unsigned)m < sizeof method_names / sizeof method_names[0] ? method_names[m] : "unknown";
}

int rl_method_parse(const char *name, rl_method *m)
{
    for (unsigned k = 0; name && k < sizeof method_names / sizeof method_names[0]; k++)
        if (strcmp(name, method_names[k]) == 0) {
            *m = (rl_method)k;
            return 1;
        }
    return 0;
}
