/*
 * plycheck.c - the structural check of PLY files made before assimp reads
 * them (see plycheck.h).
 *
 * The file is mapped read-only and its header parsed into a list of
 * elements, each with its properties (a scalar type, or a list with a count
 * type and an item type). The body is then walked instance by instance,
 * without storing anything: in binary files by skipping the bytes each
 * property takes, reading every list count; in ASCII files by skipping one
 * blank-separated token per scalar and count + 1 tokens per list. Before an
 * element's instances are walked, its declared count is compared with what
 * the remaining bytes could hold at the least, so a header claiming 10^9
 * instances fails at once instead of after 10^9 steps. Every list count must
 * be a whole number whose items fit in the remaining bytes.
 *
 * Invariants: nothing is allocated from a number in the file (the header
 * tables have fixed capacities); the walk only moves forward and stops at
 * the end of the mapping, so it ends after at most one step per byte plus
 * one per element declared.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* mmap(), fstat(); the build defines it too */
#endif

#include "plycheck.h"
#include "ilf/limits.h"

#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

/* Capacities of the header tables and of one header line's words (ilf/limits.h); a header beyond
 * them is refused. */
#define PLY_MAX_ELEMENTS ILF_PLY_MAX_ELEMENTS
#define PLY_MAX_PROPERTIES ILF_PLY_MAX_PROPERTIES
#define PLY_MAX_WORDS ILF_PLY_MAX_WORDS

typedef enum ply_format { PLY_ASCII, PLY_LITTLE, PLY_BIG } ply_format;

/* A property: item_size bytes per value; count_size > 0 for a list, whose count has that size. */
typedef struct ply_property {
    unsigned item_size;
    unsigned count_size;
    int count_signed;
} ply_property;

typedef struct ply_element {
    char name[32];
    uint64_t count;
    size_t nprops;
    ply_property props[PLY_MAX_PROPERTIES];
} ply_element;

typedef struct ply_header {
    int has_format;
    ply_format format;
    size_t nelems;
    ply_element elems[PLY_MAX_ELEMENTS];
    size_t body; /* offset of the first byte after end_header's line */
} ply_header;

/* The file's bytes and the walk's position in them, with the problem once there is one. */
typedef struct ply_cursor {
    const unsigned char *data;
    size_t size;
    size_t pos;
    char *why;
    size_t why_size;
} ply_cursor;

/* Records the problem in c->why. @return 0, so that callers can `return fail(...)`. */
static int fail(ply_cursor *c, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static int fail(ply_cursor *c, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(c->why, c->why_size, fmt, ap);
    va_end(ap);
    return 0;
}

/* Records that the body ends inside instance index of e. @return 0. */
static int truncated(ply_cursor *c, const ply_element *e, uint64_t index)
{
    return fail(c, "PLY body ends inside '%s' %llu of %llu (the file is truncated or a list length is wrong)",
                e->name, (unsigned long long)index, (unsigned long long)e->count);
}

/* ------------------------------------------------------------- words */

/* @return 1 if ch separates words (blanks; line ends too when lines is set). */
static int is_blank(unsigned char ch, int lines)
{
    return ch == ' ' || ch == '\t' || ch == '\r' || ch == '\v' || ch == '\f' || (lines && ch == '\n');
}

/* @return 1 if the len bytes at word spell text exactly. */
static int word_is(const unsigned char *word, size_t len, const char *text)
{
    return strlen(text) == len && memcmp(word, text, len) == 0;
}

/* Parses len decimal digits at word into *out (no sign). @return 1, or 0 if not digits or over 19 of them. */
static int parse_count(const unsigned char *word, size_t len, uint64_t *out)
{
    uint64_t v = 0;
    if (len == 0 || len > 19)
        return 0;
    for (size_t k = 0; k < len; k++) {
        if (word[k] < '0' || word[k] > '9')
            return 0;
        v = 10 * v + (uint64_t)(word[k] - '0');
    }
    *out = v;
    return 1;
}

/* ------------------------------------------------------------- header */

/* Splits the line [from, to) into at most PLY_MAX_WORDS words. @return their number. */
static size_t split_line(const unsigned char *d, size_t from, size_t to, const unsigned char *w[], size_t wl[])
{
    size_t n = 0;
    for (size_t p = from; p < to && n < PLY_MAX_WORDS;) {
        while (p < to && is_blank(d[p], 0))
            p++;
        size_t start = p;
        while (p < to && !is_blank(d[p], 0))
            p++;
        if (p > start) {
            w[n] = d + start;
            wl[n++] = p - start;
        }
    }
    return n;
}

/* @return the size in bytes of PLY scalar type word (int8 .. float64 and the old names), 0 if unknown. */
static unsigned type_size(const unsigned char *word, size_t len, int *is_signed)
{
    static const struct {
        const char *name;
        unsigned size;
        int is_signed;
    } types[] = {{"char", 1, 1},  {"int8", 1, 1},   {"uchar", 1, 0},  {"uint8", 1, 0},   {"short", 2, 1},
                 {"int16", 2, 1}, {"ushort", 2, 0}, {"uint16", 2, 0}, {"int", 4, 1},     {"int32", 4, 1},
                 {"uint", 4, 0},  {"uint32", 4, 0}, {"float", 4, 1},  {"float32", 4, 1}, {"double", 8, 1},
                 {"float64", 8, 1}};
    for (size_t k = 0; k < sizeof types / sizeof types[0]; k++)
        if (word_is(word, len, types[k].name)) {
            *is_signed = types[k].is_signed;
            return types[k].size;
        }
    return 0;
}

/* Reads a "format" line's words into h. @return 1, or 0 with the problem. */
static int header_format(ply_cursor *c, ply_header *h, const unsigned char *w[], const size_t wl[], size_t n)
{
    static const char *const names[] = {"ascii", "binary_little_endian", "binary_big_endian"};
    for (int f = 0; n >= 2 && f < 3; f++)
        if (word_is(w[1], wl[1], names[f])) {
            h->format = (ply_format)f;
            h->has_format = 1;
            return 1;
        }
    return fail(c, "PLY header: unknown format (expected ascii, binary_little_endian or binary_big_endian)");
}

/* Reads an "element NAME COUNT" line's words into a new element of h. @return 1, or 0 with the problem. */
static int header_element(ply_cursor *c, ply_header *h, const unsigned char *w[], const size_t wl[], size_t n)
{
    if (h->nelems == PLY_MAX_ELEMENTS)
        return fail(c, "PLY header: more than %d elements", PLY_MAX_ELEMENTS);
    ply_element *e = &h->elems[h->nelems];
    memset(e, 0, sizeof *e);
    if (n != 3 || !parse_count(w[2], wl[2], &e->count))
        return fail(c, "PLY header: an element line needs a name and a whole number of instances");
    snprintf(e->name, sizeof e->name, "%.*s", (int)(wl[1] < 31 ? wl[1] : 31), (const char *)w[1]);
    h->nelems++;
    return 1;
}

/* Reads a "property TYPE NAME" or "property list CTYPE ITYPE NAME" line into the last element of h. */
static int header_property(ply_cursor *c, ply_header *h, const unsigned char *w[], const size_t wl[], size_t n)
{
    if (h->nelems == 0)
        return fail(c, "PLY header: a property before any element");
    ply_element *e = &h->elems[h->nelems - 1];
    if (e->nprops == PLY_MAX_PROPERTIES)
        return fail(c, "PLY header: element '%s' has more than %d properties", e->name, PLY_MAX_PROPERTIES);
    ply_property *p = &e->props[e->nprops];
    int item_signed = 0;
    memset(p, 0, sizeof *p);
    if (n == 5 && word_is(w[1], wl[1], "list")) {
        p->count_size = type_size(w[2], wl[2], &p->count_signed);
        p->item_size = type_size(w[3], wl[3], &item_signed);
        if (p->count_size == 0 || p->count_size > 4 || p->item_size == 0)
            return fail(c, "PLY header: element '%s': unknown list types", e->name);
    } else if (n == 3) {
        p->item_size = type_size(w[1], wl[1], &item_signed);
        if (p->item_size == 0)
            return fail(c, "PLY header: element '%s': unknown property type '%.*s'", e->name,
                        (int)(wl[1] < 20 ? wl[1] : 20), (const char *)w[1]);
    } else {
        return fail(c, "PLY header: element '%s': malformed property line", e->name);
    }
    e->nprops++;
    return 1;
}

/* Parses the header of c's file into h, up to and including the end_header line. @return 1, or 0 with the problem. */
/* @return 1 if some line of d (size bytes) starts with the word end_header. */
static int has_end_header(const unsigned char *d, size_t size)
{
    static const char word[] = "end_header";
    for (size_t p = 0; p + sizeof word - 1 <= size; p++)
        if ((p == 0 || d[p - 1] == '\n') && memcmp(d + p, word, sizeof word - 1) == 0)
            return 1;
    return 0;
}

static int parse_header(ply_cursor *c, ply_header *h)
{
    const unsigned char *d = c->data;
    /* said first, so that what is not PLY at all (or cut in its header) is called that */
    if (!has_end_header(d, c->size))
        return fail(c, "PLY header: no end_header line (the file is truncated or not PLY)");
    for (size_t line = 0; c->pos < c->size; line++) {
        const unsigned char *nl = memchr(d + c->pos, '\n', c->size - c->pos);
        size_t end = nl ? (size_t)(nl - d) : c->size;
        const unsigned char *w[PLY_MAX_WORDS];
        size_t wl[PLY_MAX_WORDS];
        /* A header is text: assimp reads a NUL or another control byte differently from this
         * check (a NUL ends its word), so a line holding one could declare counts unseen here. */
        for (size_t p = c->pos; p < end; p++)
            if (d[p] < 0x20 && d[p] != '\t' && d[p] != '\r')
                return fail(c, "PLY header: control byte 0x%02x on line %zu", d[p], line + 1);
        size_t n = split_line(d, c->pos, end, w, wl);
        c->pos = nl ? end + 1 : c->size;
        int ok = 1;
        if (line == 0 || n == 0 || word_is(w[0], wl[0], "comment") || word_is(w[0], wl[0], "obj_info"))
            continue;
        if (word_is(w[0], wl[0], "end_header")) {
            h->body = c->pos;
            if (!h->has_format)
                return fail(c, "PLY header: no format line");
            /* assimp 5.2 skips a line end that opens binary data (assimp issue #5341), then reads every value
             * one byte late: a valid file (a first vertex at x = 0.01 does it) fails or, worse, reads wrong */
            if (h->format != PLY_ASCII && h->body < c->size && d[h->body] == '\n')
                return fail(c, "binary data that opens with byte 0x0a, a line end, which assimp 5.2 skips and then "
                               "reads every value one byte late (assimp issue #5341): save the file as ASCII PLY "
                               "or in another format");
            return 1;
        }
        if (word_is(w[0], wl[0], "format"))
            ok = header_format(c, h, w, wl, n);
        else if (word_is(w[0], wl[0], "element"))
            ok = header_element(c, h, w, wl, n);
        else if (word_is(w[0], wl[0], "property"))
            ok = header_property(c, h, w, wl, n);
        else
            /* an unknown keyword: a reader that took it for a misspelt one would see other counts */
            return fail(c, "PLY header: unknown keyword '%.*s' on line %zu", (int)(wl[0] > 40 ? 40 : wl[0]),
                        (const char *)w[0], line + 1);
        if (!ok)
            return 0;
    }
    return fail(c, "PLY header: no end_header line (the file is truncated or not PLY)");
}

/* ------------------------------------------------------------- body */

/* @return the fewest bytes (binary) or words (ASCII) one instance of e takes: each scalar and each list count. */
static uint64_t instance_minimum(const ply_element *e, ply_format format)
{
    uint64_t least = 0;
    for (size_t k = 0; k < e->nprops; k++)
        least += format == PLY_ASCII ? 1 : e->props[k].count_size ? e->props[k].count_size : e->props[k].item_size;
    return least;
}

/* Refuses e when the remaining bytes cannot hold its declared instances. In ASCII a word
 * takes at least 2 bytes with its separator (the last may lack one). @return 1, or 0 with the problem. */
static int check_declared(ply_cursor *c, const ply_header *h, const ply_element *e)
{
    const uint64_t left = c->size - c->pos;
    const uint64_t least = instance_minimum(e, h->format);
    const uint64_t room = h->format == PLY_ASCII ? left / 2 + 1 : left;
    if (e->count > 0 && least == 0)
        return fail(c, "PLY header declares %llu '%s' elements without properties", (unsigned long long)e->count,
                    e->name);
    if (least > 0 && e->count > room / least)
        return fail(c, "PLY header declares %llu '%s' elements, but only %llu bytes follow (the file is truncated "
                       "or its counts are wrong)",
                    (unsigned long long)e->count, e->name, (unsigned long long)left);
    return 1;
}

/* Reads the size-byte binary list count at c->pos. @return 1 and *count, or 0 if it is negative. */
static int binary_count(ply_cursor *c, ply_format format, const ply_property *p, uint64_t *count)
{
    uint32_t v = 0;
    for (unsigned k = 0; k < p->count_size; k++) {
        unsigned shift = format == PLY_LITTLE ? 8 * k : 8 * (p->count_size - 1 - k);
        v |= (uint32_t)c->data[c->pos + k] << shift;
    }
    c->pos += p->count_size;
    if (p->count_signed && (v >> (8 * p->count_size - 1)) & 1u)
        return 0;
    *count = v;
    return 1;
}

/* Skips one binary instance of e (element number index). @return 1, or 0 with the problem. */
static int skip_binary_instance(ply_cursor *c, ply_format format, const ply_element *e, uint64_t index)
{
    for (size_t k = 0; k < e->nprops; k++) {
        const ply_property *p = &e->props[k];
        uint64_t count = 1;
        if (p->count_size > c->size - c->pos)
            return truncated(c, e, index);
        if (p->count_size > 0 && !binary_count(c, format, p, &count))
            return fail(c, "PLY body: '%s' %llu has a negative list length", e->name, (unsigned long long)index);
        if (count > (c->size - c->pos) / p->item_size)
            return truncated(c, e, index);
        c->pos += count * p->item_size;
    }
    return 1;
}

/* Moves past the next blank-separated word. @return 1 and its extent, or 0 at the end of the file. */
static int next_word(ply_cursor *c, const unsigned char **word, size_t *len)
{
    while (c->pos < c->size && is_blank(c->data[c->pos], 1))
        c->pos++;
    size_t start = c->pos;
    while (c->pos < c->size && !is_blank(c->data[c->pos], 1))
        c->pos++;
    *word = c->data + start;
    *len = c->pos - start;
    return *len > 0;
}

/* Skips one ASCII instance of e (element number index). @return 1, or 0 with the problem. */
static int skip_ascii_instance(ply_cursor *c, const ply_element *e, uint64_t index)
{
    for (size_t k = 0; k < e->nprops; k++) {
        const unsigned char *w;
        size_t wl;
        uint64_t count = 0;
        if (!next_word(c, &w, &wl))
            return truncated(c, e, index);
        if (e->props[k].count_size == 0)
            continue;
        if (!parse_count(w, wl, &count))
            return fail(c, "PLY body: '%s' %llu: list length '%.*s' is not a whole number >= 0", e->name,
                        (unsigned long long)index, (int)(wl < 20 ? wl : 20), (const char *)w);
        if (count > (c->size - c->pos) / 2 + 1)
            return fail(c, "PLY body: '%s' %llu: a list of %llu values cannot fit in the %llu bytes left", e->name,
                        (unsigned long long)index, (unsigned long long)count,
                        (unsigned long long)(c->size - c->pos));
        for (uint64_t i = 0; i < count; i++)
            if (!next_word(c, &w, &wl))
                return truncated(c, e, index);
    }
    return 1;
}

/* Walks every instance of every element of h. @return 1, or 0 with the problem. */
static int walk_body(ply_cursor *c, const ply_header *h)
{
    c->pos = h->body;
    for (size_t k = 0; k < h->nelems; k++) {
        const ply_element *e = &h->elems[k];
        if (!check_declared(c, h, e))
            return 0;
        for (uint64_t i = 0; i < e->count; i++) {
            int ok = h->format == PLY_ASCII ? skip_ascii_instance(c, e, i) : skip_binary_instance(c, h->format, e, i);
            if (!ok)
                return 0;
        }
    }
    return 1;
}

/* ------------------------------------------------------------- files */

/* @return 1 if the size bytes at d start with the PLY magic line "ply". */
static int is_ply(const unsigned char *d, size_t size)
{
    return size >= 4 && memcmp(d, "ply", 3) == 0 && (d[3] == '\n' || (d[3] == '\r' && size >= 5 && d[4] == '\n'));
}

/* Checks the mapped file of size bytes at d; ply_name: its name ends in
 * .ply, so assimp will read it as PLY whatever it holds. @return as ilf__ply_check(). */
static int check_bytes(const unsigned char *d, size_t size, int ply_name, char *why, size_t why_size)
{
    /* assimp takes a file for PLY by its name, or by a leading "ply" in any
     * letter case, and then parses a header this check cannot walk (a
     * 139-byte "plym..." file held it for minutes): only a first line of
     * exactly "ply" is let through to it */
    int ply_prefix = size >= 3 && strncasecmp((const char *)d, "ply", 3) == 0;
    if (!is_ply(d, size)) {
        if (!ply_name && !ply_prefix)
            return 1;
        snprintf(why, why_size, "not a PLY file: its first line is not 'ply'");
        return 0;
    }
    ply_cursor c = {d, size, 0, why, why_size};
    ply_header *h = calloc(1, sizeof *h);
    if (h == NULL)
        return fail(&c, "out of memory");
    int ok = parse_header(&c, h) && walk_body(&c, h);
    free(h);
    return ok;
}

int ilf__ply_check(const char *path, char *why, size_t why_size)
{
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC); /* a FIFO is never waited on: fstat refuses it */
    if (fd < 0)
        return 1; /* assimp reports what is wrong with the file */
    struct stat sb;
    int ok = 1;
    if (fstat(fd, &sb) == 0 && S_ISREG(sb.st_mode) && sb.st_size > 0 && (uint64_t)sb.st_size <= SIZE_MAX) {
        size_t size = (size_t)sb.st_size;
        void *map = mmap(NULL, size, PROT_READ, MAP_PRIVATE, fd, 0);
        if (map != MAP_FAILED) {
            const char *dot = strrchr(path, '.');
            ok = check_bytes(map, size, dot && strcasecmp(dot, ".ply") == 0, why, why_size);
            munmap(map, size);
        }
    }
    close(fd);
    return ok;
}
