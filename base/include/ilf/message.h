/*
 * ilf/message.h - the one way a library writes its per-thread error message.
 *
 * Each library owns its message buffer (messages are per library, so one
 * library's failure never overwrites another's); this formats into such a
 * buffer of ILF_MESSAGE_BYTES with the one truncation rule: a message too
 * long for the buffer is cut at the last whole UTF-8 character that fits,
 * so a cut message is still text. An argument may be the buffer itself
 * ("%s: %s", context, current message): formatting goes through a copy.
 * Labels and element paths, which may be cut anywhere, are formatted with
 * ilf_format_cut() instead.
 */
#ifndef ILF_MESSAGE_H
#define ILF_MESSAGE_H

#include <stdarg.h>
#include <stddef.h>

#include "ilf/limits.h"

/* Formats fmt and ap into buf (ILF_MESSAGE_BYTES bytes) under the rule above. @return the length written. */
size_t ilf_message_vformat(char *buf, const char *fmt, va_list ap);

/* As ilf_message_vformat, with the arguments given directly. @return the length written. */
size_t ilf_message_format(char *buf, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* snprintf into out (cap bytes) for a label or an element path: a result too long for out ends in "..."
 * (when cap >= 4), so a reader sees it was cut. */
void ilf_format_cut(char *out, size_t cap, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

#endif /* ILF_MESSAGE_H */
