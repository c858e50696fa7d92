/*
 * manifest_write.c - writing capture manifests (cap_manifest_write(), capture/capture.h): the pattern form
 * of docs/capture.md, so that the library that reads manifests (manifest.c) is also the one that writes
 * them. The text is formatted JSON: one key a line, nested objects indented by a tab a level, a tab after
 * each key's colon, arrays on one line with ", " between items.
 *
 * Invariants: the whole text is built in memory before anything touches the file system, then written
 * through base's one atomic writer (ilf/atomic_file.h), so path holds the old file or the new one; a
 * number reads back as the double it was (its 15 significant digits when they do, else 17; whole numbers
 * in int's range as integers); strings are escaped as JSON requires (quote, backslash, control bytes),
 * other bytes (UTF-8 included) written as they are.
 */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "capture/capture.h"
#include "ilf/atomic_file.h"
#include "internal.h"

/* Writes depth tabs. */
static void put_indent(FILE *f, int depth)
{
    for (int k = 0; k < depth; k++)
        fputc('\t', f);
}

/* @return the letter after the backslash that escapes byte c in a JSON string, or 0 for none. */
static char escape_letter(unsigned char c)
{
    switch (c) {
    case '"': return '"';
    case '\\': return '\\';
    case '\b': return 'b';
    case '\f': return 'f';
    case '\n': return 'n';
    case '\r': return 'r';
    case '\t': return 't';
    default: return 0;
    }
}

/* Writes s as a JSON string. */
static void put_string(FILE *f, const char *s)
{
    fputc('"', f);
    for (const unsigned char *c = (const unsigned char *)s; *c; c++) {
        char letter = escape_letter(*c);
        if (letter)
            fprintf(f, "\\%c", letter);
        else if (*c < 0x20)
            fprintf(f, "\\u%04x", *c);
        else
            fputc(*c, f);
    }
    fputc('"', f);
}

/* Writes x (finite) as a JSON number: a whole number in int's range as an integer, else the shorter of 15
 * and 17 significant digits that reads back as x (to within a relative DBL_EPSILON). */
static void put_number(FILE *f, double x)
{
    if (x >= INT_MIN && x <= INT_MAX && x == (double)(int)x) {
        fprintf(f, "%d", (int)x);
        return;
    }
    char text[32];
    snprintf(text, sizeof text, "%1.15g", x);
    double back = strtod(text, NULL), most = fmax(fabs(back), fabs(x));
    if (!(fabs(back - x) <= most * DBL_EPSILON))
        snprintf(text, sizeof text, "%1.17g", x);
    fputs(text, f);
}

/* Writes the key of a member at depth, its colon and the tab after it. */
static void put_key(FILE *f, int depth, const char *key)
{
    put_indent(f, depth);
    put_string(f, key);
    fputs(":\t", f);
}

/* Writes key: [x, y, z] at depth, then end (",\n" or "\n"). */
static void put_vector(FILE *f, int depth, const char *key, const double v[3], const char *end)
{
    put_key(f, depth, key);
    fputc('[', f);
    for (int a = 0; a < 3; a++) {
        fputs(a ? ", " : "", f);
        put_number(f, v[a]);
    }
    fprintf(f, "]%s", end);
}

/* Writes a plane's members (plane, grid, slab, pattern) at depth; the last without its line's end. */
static void put_plane(FILE *f, int depth, const cap_manifest_plane *p)
{
    const lfio_slab_desc *d = p->desc;
    put_key(f, depth, "plane");
    fputs("{\n", f);
    put_vector(f, depth + 1, "origin", d->origin, ",\n");
    put_vector(f, depth + 1, "u", d->u, ",\n");
    put_vector(f, depth + 1, "v", d->v, "\n");
    put_indent(f, depth);
    fputs("},\n", f);
    put_key(f, depth, "grid");
    fputs("{\n", f);
    put_key(f, depth + 1, "nu");
    put_number(f, d->nu);
    fputs(",\n", f);
    put_key(f, depth + 1, "nv");
    put_number(f, d->nv);
    fputc('\n', f);
    put_indent(f, depth);
    fputs("},\n", f);
    put_key(f, depth, "slab");
    put_string(f, d->name);
    fputs(",\n", f);
    put_key(f, depth, "pattern");
    put_string(f, p->pattern);
}

/* Writes key: "value",\n at depth. */
static void put_text_member(FILE *f, int depth, const char *key, const char *value)
{
    put_key(f, depth, key);
    put_string(f, value);
    fputs(",\n", f);
}

/* Writes the whole manifest of spec (checked) to f. */
static void put_manifest(FILE *f, const cap_manifest_spec *spec)
{
    fputs("{\n", f);
    put_key(f, 1, "n");
    put_number(f, spec->n);
    fputs(",\n", f);
    put_text_member(f, 1, "units", spec->units == LFIO_UNITS_RELATIVE ? "relative" : "radiance");
    put_text_member(f, 1, "projection", cap_projection_name(spec->projection));
    put_text_member(f, 1, "colour_space", cap_colour_space_name(spec->colour_space));
    if (spec->nplanes == 1) {
        put_plane(f, 1, &spec->planes[0]);
    } else {
        put_key(f, 1, "planes");
        fputc('[', f);
        for (size_t k = 0; k < spec->nplanes; k++) {
            fputs(k ? ", {\n" : "{\n", f);
            put_plane(f, 3, &spec->planes[k]);
            fputc('\n', f);
            put_indent(f, 2);
            fputc('}', f);
        }
        fputc(']', f);
    }
    fputs("\n}\n", f);
}

/* @return 1 if v's three values are finite. */
static int finite3(const double v[3])
{
    return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]);
}

/* Checks what put_manifest() writes. @return CAP_OK, or CAP_ERR_ARG naming the value at fault. */
static cap_status check_spec(const char *path, const cap_manifest_spec *spec)
{
    if (spec->planes == NULL || spec->nplanes < 1 || spec->nplanes > CAP_PLANES_MAX)
        return cap__fail(CAP_ERR_ARG, "%s: a manifest has 1 to %u planes, got %zu%s", path, CAP_PLANES_MAX,
                         spec->nplanes, spec->planes == NULL ? " (NULL)" : "");
    if (spec->n < 1 || spec->n > LFIO_SLAB_MAX_N)
        return cap__fail(CAP_ERR_ARG, "%s: n %u is outside 1 .. %u", path, spec->n, LFIO_SLAB_MAX_N);
    if ((spec->units != LFIO_UNITS_RADIANCE && spec->units != LFIO_UNITS_RELATIVE)
        || cap_projection_name(spec->projection)[0] == '\0' || cap_colour_space_name(spec->colour_space)[0] == '\0')
        return cap__fail(CAP_ERR_ARG, "%s: unknown units, projection or colour space", path);
    for (size_t k = 0; k < spec->nplanes; k++) {
        const cap_manifest_plane *p = &spec->planes[k];
        if (p->desc == NULL || p->pattern == NULL)
            return cap__fail(CAP_ERR_ARG, "%s: plane %zu: NULL slab description or pattern", path, k);
        if (!finite3(p->desc->origin) || !finite3(p->desc->u) || !finite3(p->desc->v) || p->desc->nu < 1
            || p->desc->nv < 1 || memchr(p->desc->name, '\0', sizeof p->desc->name) == NULL)
            return cap__fail(CAP_ERR_ARG, "%s: plane %zu: a plane of finite vectors, a grid of at least 1 x 1 "
                             "and a terminated slab name are needed", path, k);
    }
    return CAP_OK;
}

cap_status cap_manifest_write(const char *path, const cap_manifest_spec *spec)
{
    if (path == NULL || path[0] == '\0' || spec == NULL)
        return cap__fail(CAP_ERR_ARG, "cap_manifest_write: NULL or empty argument");
    cap_status st = check_spec(path, spec);
    if (st != CAP_OK)
        return st;
    char *text = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    if (f == NULL)
        return cap__fail(CAP_ERR_NOMEM, "%s: out of memory", path);
    put_manifest(f, spec);
    int bad = ferror(f);
    if (fclose(f) != 0 || bad) {
        free(text);
        return cap__fail(CAP_ERR_NOMEM, "%s: out of memory", path);
    }
    const char *step = "";
    int code = ilf_atomic_write(path, text, size, &step);
    free(text);
    if (code != 0)
        return cap__fail(CAP_ERR_OUTPUT, "%s: %s: %s", path, step, strerror(code));
    return CAP_OK;
}
