/*
 * error.c - the capture library's status names and per-thread error
 * messages (capture/common.h).
 *
 * Invariants: each thread has its own message buffer, so concurrent
 * failures never mix; a message is always one NUL-terminated line (newlines
 * from other libraries' messages become spaces); success leaves it as it was.
 */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "ilf/message.h"
#include "internal.h"

static _Thread_local char message[ILF_MESSAGE_BYTES];

/* Replaces line breaks in message by spaces, so a message is one line. */
static void flatten_message(void)
{
    for (char *c = message; *c != '\0'; c++)
        if (*c == '\n' || *c == '\r')
            *c = ' ';
}

cap_status cap__fail(cap_status status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    ilf_message_vformat(message, fmt, ap);
    va_end(ap);
    flatten_message();
    return status;
}

cap_status cap__fail_prefix(cap_status status, const char *fmt, ...)
{
    char prefix[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(prefix, sizeof prefix, fmt, ap);
    va_end(ap);
    ilf_message_format(message, "%s: %s", prefix, message);
    flatten_message();
    return status;
}

cap_status cap__fail_text(cap_status status, const char *text)
{
    ilf_message_format(message, "%s", text != NULL ? text : "");
    flatten_message();
    return status;
}

const char *cap_error_message(void)
{
    return message;
}

const char *cap_status_name(cap_status s)
{
    switch (s) {
    case CAP_OK:
        return "ok";
    case CAP_ERR_ARG:
        return "bad argument";
    case CAP_ERR_INPUT:
        return "bad input";
    case CAP_ERR_OUTPUT:
        return "cannot write";
    case CAP_ERR_NOMEM:
        return "out of memory";
    }
    return "unknown status";
}
