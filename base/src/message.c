/*
 * message.c - ilf/message.h: formatting a library's error message, and labels cut with "...".
 *
 * Invariants: the buffer always ends up NUL-terminated and at most
 * ILF_MESSAGE_BYTES long, holding whole UTF-8 characters only; nothing is
 * allocated (a failure path must not need memory). ilf_format_cut() always
 * leaves out NUL-terminated (vsnprintf's rule).
 */
#include "ilf/message.h"

#include <stdio.h>
#include <string.h>

size_t ilf_message_vformat(char *buf, const char *fmt, va_list ap)
{
    char text[ILF_MESSAGE_BYTES];
    int n = vsnprintf(text, sizeof text, fmt, ap);
    size_t len = n < 0 ? 0 : strlen(text);
    if (n >= (int)sizeof text) {
        /* Cut: drop a trailing partial character (continuation bytes, then their lead byte). */
        size_t end = len;
        while (end > 0 && ((unsigned char)text[end - 1] & 0xC0u) == 0x80u)
            end--;
        if (end > 0 && (unsigned char)text[end - 1] >= 0xC0u) {
            unsigned char lead = (unsigned char)text[end - 1];
            size_t need = lead >= 0xF0u ? 4 : lead >= 0xE0u ? 3 : 2;
            len = len - (end - 1) == need ? len : end - 1;
        }
    }
    memcpy(buf, text, len);
    buf[len] = '\0';
    return len;
}

size_t ilf_message_format(char *buf, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    size_t len = ilf_message_vformat(buf, fmt, ap);
    va_end(ap);
    return len;
}

void ilf_format_cut(char *out, size_t cap, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int len = vsnprintf(out, cap, fmt, ap);
    va_end(ap);
    if (len >= 0 && (size_t)len >= cap && cap >= 4)
        memcpy(out + cap - 4, "...", 4);
}
