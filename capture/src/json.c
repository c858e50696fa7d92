/*
 * json.c - strict, typed reading of the capture library's JSON inputs
 * (json.h): manifests (manifest.c) and proxies (proxy.c) share it.
 *
 * Invariants: every failure is one line "PATH: ELEMENT: problem" with
 * CAP_ERR_INPUT (CAP_ERR_NOMEM when memory runs out); numbers are finite,
 * whole numbers are exact, strings are what cJSON decoded; a file is read
 * whole, bounded by the caller's size limit, before anything is parsed.
 */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "internal.h"
#include "json.h"

cap_status cap__json_bad(const char *path, const char *elem, const char *fmt, ...)
{
    char text[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    return cap__fail(CAP_ERR_INPUT, "%s: %s%s%s", path, elem, elem[0] != '\0' ? ": " : "", text);
}

/* Marks out as cut short when len, what snprintf wanted to write, did not fit. */
static void mark_cut(char out[CAP__ELEM_MAX], int len)
{
    if (len >= CAP__ELEM_MAX)
        memcpy(out + CAP__ELEM_MAX - 4, "...", 4);
}

void cap__json_member_name(char out[CAP__ELEM_MAX], const char *elem, const char *key)
{
    mark_cut(out, snprintf(out, CAP__ELEM_MAX, "%s%s%s", elem, elem[0] != '\0' ? "." : "", key));
}

void cap__json_item_name(char out[CAP__ELEM_MAX], const char *elem, size_t k)
{
    mark_cut(out, snprintf(out, CAP__ELEM_MAX, "%s[%zu]", elem, k));
}

const char *cap__json_kind(const cJSON *j)
{
    if (cJSON_IsNumber(j))
        return "a number";
    if (cJSON_IsString(j))
        return "a string";
    if (cJSON_IsBool(j))
        return "a boolean";
    if (cJSON_IsNull(j))
        return "null";
    if (cJSON_IsArray(j))
        return "an array";
    if (cJSON_IsObject(j))
        return "an object";
    return "an unknown value";
}

/* ------------------------------------------------------------ files */

/* Reads the whole file into a NUL-terminated buffer. */
static cap_status read_text(const char *path, size_t max_bytes, char **text, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL)
        return cap__fail(CAP_ERR_INPUT, "%s: cannot open: %s", path, strerror(errno));
    struct stat st;
    cap_status status = CAP_OK;
    if (fstat(fileno(f), &st) != 0 || !S_ISREG(st.st_mode))
        status = cap__fail(CAP_ERR_INPUT, "%s: not a regular file", path);
    else if ((uint64_t)st.st_size > max_bytes)
        status = cap__fail(CAP_ERR_INPUT, "%s: %lld bytes, more than the %zu accepted", path,
                           (long long)st.st_size, max_bytes);
    else if ((*text = malloc((size_t)st.st_size + 1)) == NULL)
        status = cap__fail(CAP_ERR_NOMEM, "%s: out of memory", path);
    else if ((*len = fread(*text, 1, (size_t)st.st_size, f)) != (size_t)st.st_size || ferror(f))
        status = cap__fail(CAP_ERR_INPUT, "%s: cannot read: %s", path, strerror(errno));
    if (status == CAP_OK)
        (*text)[*len] = '\0';
    fclose(f);
    return status;
}

/* Parses text, reporting syntax errors with their line and column (from 1, in bytes). */
static cap_status parse_text(const char *path, const char *text, size_t len, cJSON **root)
{
    size_t skip = len >= 3 && memcmp(text, "\xef\xbb\xbf", 3) == 0 ? 3 : 0;
    if (memchr(text, '\0', len) != NULL)
        return cap__fail(CAP_ERR_INPUT, "%s: not valid JSON: contains a NUL byte", path);
    const char *end = NULL;
    /* the length includes the terminating NUL, which is how cJSON recognises the end of the text */
    *root = cJSON_ParseWithLengthOpts(text + skip, len - skip + 1, &end, 1);
    if (*root != NULL)
        return CAP_OK;
    size_t at = end != NULL && end >= text ? (size_t)(end - text) : len;
    unsigned long line = 1, col = 1;
    for (size_t k = 0; k < at && k < len; k++, col++)
        if (text[k] == '\n')
            line++, col = 0;
    return cap__fail(CAP_ERR_INPUT, "%s:%lu:%lu: not valid JSON%s", path, line, col,
                     at >= len ? ": unexpected end of file" : "");
}

cap_status cap__json_load(const char *path, size_t max_bytes, cJSON **root)
{
    char *text = NULL;
    size_t len = 0;
    *root = NULL;
    cap_status st = read_text(path, max_bytes, &text, &len);
    if (st == CAP_OK)
        st = parse_text(path, text, len, root);
    free(text);
    return st;
}

/* ------------------------------------------------------------ values */

cap_status cap__json_keys(const char *path, const cJSON *j, const char *elem, const char *const *allowed)
{
    if (!cJSON_IsObject(j))
        return cap__json_bad(path, elem, "expected an object, got %s", cap__json_kind(j));
    for (const cJSON *c = j->child; c != NULL; c = c->next) {
        size_t k = 0;
        while (allowed[k] != NULL && strcmp(allowed[k], c->string) != 0)
            k++;
        if (allowed[k] == NULL) {
            char list[256] = "";
            for (size_t a = 0; allowed[a] != NULL; a++)
                snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", a ? ", " : "", allowed[a]);
            return cap__json_bad(path, elem, "unknown key '%s' (expected %s)", c->string, list);
        }
        for (const cJSON *d = j->child; d != c; d = d->next)
            if (strcmp(d->string, c->string) == 0)
                return cap__json_bad(path, elem, "key '%s' is repeated", c->string);
    }
    return CAP_OK;
}

cap_status cap__json_member(const char *path, const cJSON *obj, const char *elem, const char *key, int required,
                            const cJSON **out)
{
    *out = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (*out == NULL && required)
        return cap__json_bad(path, elem, "missing key '%s'", key);
    return CAP_OK;
}

cap_status cap__json_number(const char *path, const cJSON *j, const char *elem, double *out)
{
    if (!cJSON_IsNumber(j))
        return cap__json_bad(path, elem, "expected a number, got %s", cap__json_kind(j));
    if (!isfinite(j->valuedouble))
        return cap__json_bad(path, elem, "not a finite number");
    *out = j->valuedouble;
    return CAP_OK;
}

cap_status cap__json_positive(const char *path, const cJSON *j, const char *elem, double *out)
{
    double v = 0.0;
    cap_status st = cap__json_number(path, j, elem, &v);
    if (st == CAP_OK && !(v > 0.0))
        return cap__json_bad(path, elem, "must be > 0, got %g", v);
    if (st == CAP_OK)
        *out = v;
    return st;
}

cap_status cap__json_vector3(const char *path, const cJSON *j, const char *elem, double out[3])
{
    if (!cJSON_IsArray(j))
        return cap__json_bad(path, elem, "expected 3 numbers, got %s", cap__json_kind(j));
    int count = cJSON_GetArraySize(j);
    if (count != 3)
        return cap__json_bad(path, elem, "expected 3 numbers, got %d", count);
    char e[CAP__ELEM_MAX];
    for (int k = 0; k < 3; k++) {
        cap__json_item_name(e, elem, (size_t)k);
        cap_status st = cap__json_number(path, cJSON_GetArrayItem(j, k), e, &out[k]);
        if (st != CAP_OK)
            return st;
    }
    return CAP_OK;
}

cap_status cap__json_uint(const char *path, const cJSON *j, const char *elem, uint32_t lo, uint32_t hi,
                          uint32_t *out)
{
    double v = 0.0;
    cap_status st = cap__json_number(path, j, elem, &v);
    if (st != CAP_OK)
        return st;
    if (v != floor(v))
        return cap__json_bad(path, elem, "expected a whole number, got %g", v);
    if (v < lo || v > hi)
        return cap__json_bad(path, elem, "%g is outside %u..%u", v, lo, hi);
    *out = (uint32_t)v;
    return CAP_OK;
}

cap_status cap__json_string(const char *path, const cJSON *j, const char *elem, const char **out)
{
    *out = "";
    if (!cJSON_IsString(j))
        return cap__json_bad(path, elem, "expected a string, got %s", cap__json_kind(j));
    *out = j->valuestring;
    return CAP_OK;
}

/* ------------------------------------------------------------ slabs */

cap_status cap__json_slab_name(const char *path, const cJSON *j, const char *elem, char name[LFIO_NAME_MAX + 1])
{
    const char *text;
    cap_status st = cap__json_string(path, j, elem, &text);
    if (st != CAP_OK)
        return st;
    if (!lfio_slab_name_valid(text))
        return cap__json_bad(path, elem, "'%s': use 1 to %d of A-Z a-z 0-9 _ - .", text, LFIO_NAME_MAX);
    memcpy(name, text, strlen(text) + 1);
    return CAP_OK;
}

cap_status cap__json_rectangle(const char *path, const cJSON *obj, const char *elem, lfio_slab_desc *d)
{
    static const char *const keys[3] = {"origin", "u", "v"};
    double *dest[3] = {d->origin, d->u, d->v};
    for (int k = 0; k < 3; k++) {
        const cJSON *j;
        char e[CAP__ELEM_MAX];
        cap__json_member_name(e, elem, keys[k]);
        cap_status st = cap__json_member(path, obj, elem, keys[k], 1, &j);
        if (st == CAP_OK)
            st = cap__json_vector3(path, j, e, dest[k]);
        if (st != CAP_OK)
            return st;
    }
    int edges = lfio_slab_edges_check(d->u, d->v);
    if (edges == LFIO_EDGES_LENGTH)
        return cap__json_bad(path, elem, "u and v must be nonzero (and their lengths finite)");
    if (edges == LFIO_EDGES_ORTHOGONAL)
        return cap__json_bad(path, elem, "u and v must be orthogonal (u.v = %g)", cap__dot(d->u, d->v));
    return CAP_OK;
}

cap_status cap__json_grid(const char *path, const cJSON *j, const char *elem, lfio_slab_desc *d)
{
    static const char *const keys[] = {"nu", "nv", NULL};
    const cJSON *a, *b;
    char ae[CAP__ELEM_MAX], be[CAP__ELEM_MAX];
    cap__json_member_name(ae, elem, "nu");
    cap__json_member_name(be, elem, "nv");
    cap_status st = cap__json_keys(path, j, elem, keys);
    if (st == CAP_OK)
        st = cap__json_member(path, j, elem, "nu", 1, &a);
    if (st == CAP_OK)
        st = cap__json_member(path, j, elem, "nv", 1, &b);
    if (st == CAP_OK)
        st = cap__json_uint(path, a, ae, 1, 65536, &d->nu);
    if (st == CAP_OK)
        st = cap__json_uint(path, b, be, 1, 65536, &d->nv);
    return st;
}
