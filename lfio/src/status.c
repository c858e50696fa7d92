/*
 * status.c - status names, the per-thread error message, and the version.
 *
 * Each thread has its own message buffer, so concurrent callers never see
 * each other's errors. A failing call writes the buffer; a successful call
 * leaves it alone, so lfio_errmsg() describes the most recent failure.
 */
#include <stdio.h>
#include <string.h>

#include "ilf/message.h"
#include "internal.h"

static _Thread_local char errbuf[ILF_MESSAGE_BYTES];

const char *lfio_status_name(lfio_status s)
{
    switch (s) {
    case LFIO_OK: return "ok";
    case LFIO_ERR_ARG: return "bad argument";
    case LFIO_ERR_NOMEM: return "out of memory";
    case LFIO_ERR_IO: return "input/output error";
    case LFIO_ERR_FORMAT: return "invalid file format";
    case LFIO_ERR_CHECKSUM: return "checksum mismatch";
    case LFIO_ERR_NOTFOUND: return "not found";
    }
    return "unknown status";
}

const char *lfio_errmsg(void)
{
    return errbuf;
}

const char *lfio_version(void)
{
    return LFIO_VERSION_STRING;
}

lfio_status lfio__fail(lfio_status status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    ilf_message_vformat(errbuf, fmt, ap);
    va_end(ap);
    return status;
}

void lfio__clear_error(void)
{
    errbuf[0] = '\0';
}
