/*
 * json.c - the one strict JSON reader (ilf/json.h), over cJSON. The only
 * file of ilfkit that includes cJSON's header to read JSON (test_json_contained).
 *
 * Loading reads the whole file into memory (bounded by the caller's limit,
 * checked against fstat before anything is allocated), refuses NUL bytes,
 * empty files and nesting deeper than ILF_JSON_MAX_DEPTH with the line and
 * column of the fault, then lets cJSON parse, requiring the text to end
 * where the value does. cJSON's own nesting limit is not relied upon: it
 * stops without saying why, so the depth is measured here first.
 *
 * Invariants: every failure leaves one message "FILE[:LINE:COL]: [ELEMENT: ]
 * problem" in the context; numbers handed out by the typed readers are
 * finite, integers exact; a tree is freed by ilf_json_free only.
 */
#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "ilf/file_kind.h"
#include "ilf/json.h"
#include "ilf/message.h"

#if CJSON_NESTING_LIMIT < ILF_JSON_MAX_DEPTH
#error "cJSON's nesting limit is below ILF_JSON_MAX_DEPTH: its refusals would go unexplained"
#endif

ilf_json_status ilf_json_fail(ilf_json_ctx *ctx, const char *elem, const char *fmt, ...)
{
    char text[ILF_MESSAGE_BYTES];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    ilf_format_cut(ctx->message, sizeof ctx->message, "%s: %s%s%s", ctx->file, elem, elem[0] != '\0' ? ": " : "", text);
    return ILF_JSON_ERR_INPUT;
}

/* Writes "FILE: problem" with status st. @return st. */
static ilf_json_status file_fail(ilf_json_ctx *ctx, ilf_json_status st, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static ilf_json_status file_fail(ilf_json_ctx *ctx, ilf_json_status st, const char *fmt, ...)
{
    char text[ILF_MESSAGE_BYTES];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    ilf_format_cut(ctx->message, sizeof ctx->message, "%s: %s", ctx->file, text);
    return st;
}

void ilf_json_member_name(char out[ILF_JSON_ELEM_MAX], const char *elem, const char *key)
{
    ilf_format_cut(out, ILF_JSON_ELEM_MAX, "%s%s%s", elem, elem[0] != '\0' ? "." : "", key);
}

void ilf_json_item_name(char out[ILF_JSON_ELEM_MAX], const char *elem, size_t k)
{
    ilf_format_cut(out, ILF_JSON_ELEM_MAX, "%s[%zu]", elem, k);
}

/* ------------------------------------------------------------ files */

/* Reads the whole file into a NUL-terminated buffer. */
static ilf_json_status read_text(ilf_json_ctx *ctx, size_t max_bytes, char **text, size_t *len)
{
    char why[160];
    int fd;
    /* a FIFO or a device where the file belongs is refused, never waited on */
    int err = ilf_input_open(ctx->file, &fd, why, sizeof why);
    if (err != 0)
        return file_fail(ctx, ILF_JSON_ERR_IO, "%s", why);
    FILE *f = fdopen(fd, "rb");
    if (f == NULL) {
        close(fd);
        return file_fail(ctx, ILF_JSON_ERR_NOMEM, "out of memory");
    }
    struct stat sb;
    ilf_json_status st = ILF_JSON_OK;
    char *buf = NULL;
    if (fstat(fileno(f), &sb) != 0)
        st = file_fail(ctx, ILF_JSON_ERR_IO, "cannot read: %s", strerror(errno));
    else if ((uint64_t)sb.st_size > max_bytes)
        st = file_fail(ctx, ILF_JSON_ERR_INPUT, "%lld bytes, more than the limit of %zu bytes (%zu MiB)",
                       (long long)sb.st_size, max_bytes, max_bytes >> 20);
    else if ((buf = malloc((size_t)sb.st_size + 1)) == NULL)
        st = file_fail(ctx, ILF_JSON_ERR_NOMEM, "out of memory");
    size_t n = st == ILF_JSON_OK ? fread(buf, 1, (size_t)sb.st_size, f) : 0;
    if (st == ILF_JSON_OK && (n != (size_t)sb.st_size || ferror(f)))
        st = file_fail(ctx, ILF_JSON_ERR_IO, "cannot read: %s", ferror(f) ? strerror(errno) : "the file shrank");
    fclose(f);
    if (st != ILF_JSON_OK) {
        free(buf);
        return st;
    }
    buf[n] = '\0';
    *text = buf;
    *len = n;
    return ILF_JSON_OK;
}

/* Sets *line and *col (from 1, col in bytes) of byte pos of text. */
static void line_col(const char *text, size_t pos, unsigned long *line, unsigned long *col)
{
    *line = 1;
    *col = 1;
    for (size_t i = 0; i < pos; i++) {
        if (text[i] == '\n')
            ++*line, *col = 1;
        else
            ++*col;
    }
}

/* Fails for the JSON error at byte pos of text (len bytes), quoting the text around it.
 * @return ILF_JSON_ERR_INPUT. */
static ilf_json_status syntax_error(ilf_json_ctx *ctx, const char *text, size_t len, size_t pos, const char *what)
{
    unsigned long line, col;
    line_col(text, pos, &line, &col);
    size_t rest = pos;
    while (rest < len && strchr(" \t\r\n", text[rest]))
        rest++;
    if (rest >= len) {
        ilf_format_cut(ctx->message, sizeof ctx->message, "%s:%lu:%lu: not valid JSON: %s", ctx->file, line, col,
                   what ? what : "unexpected end of file");
        return ILF_JSON_ERR_INPUT;
    }
    size_t from = pos, to = pos; /* up to 12 bytes either side, within the line */
    while (from > 0 && pos - from < 12 && text[from - 1] != '\n')
        from--;
    while (to < len && to - pos < 12 && text[to] != '\n')
        to++;
    char near[32];
    size_t k = 0;
    for (size_t i = from; i < to; i++)
        near[k++] = text[i] >= 32 && text[i] < 127 ? text[i] : '?';
    near[k] = '\0';
    ilf_format_cut(ctx->message, sizeof ctx->message, "%s:%lu:%lu: not valid JSON: %s near '%s'", ctx->file, line, col,
               what ? what : "unexpected text", near);
    return ILF_JSON_ERR_INPUT;
}

/* @return the byte position of the first '[' or '{' that opens level ILF_JSON_MAX_DEPTH + 1
 * (strings skipped), or len when the text nests no deeper than the limit. */
static size_t too_deep(const char *text, size_t len)
{
    size_t depth = 0;
    int in_string = 0;
    for (size_t i = 0; i < len; i++) {
        if (in_string && text[i] == '\\')
            i++;
        else if (text[i] == '"')
            in_string = !in_string;
        else if (!in_string && (text[i] == '[' || text[i] == '{')) {
            if (++depth > ILF_JSON_MAX_DEPTH)
                return i;
        } else if (!in_string && (text[i] == ']' || text[i] == '}') && depth > 0)
            depth--;
    }
    return len;
}

/* Parses text (len bytes, NUL-terminated) strictly. @return ILF_JSON_OK and *root, or a message. */
static ilf_json_status parse_text(ilf_json_ctx *ctx, const char *text, size_t len, cJSON **root)
{
    size_t start = len >= 3 && memcmp(text, "\xEF\xBB\xBF", 3) == 0 ? 3 : 0; /* a UTF-8 byte order mark */
    const char *nul = memchr(text, '\0', len);
    if (nul)
        return syntax_error(ctx, text, len, (size_t)(nul - text), "a NUL byte");
    size_t first = start;
    while (first < len && strchr(" \t\r\n", text[first]))
        first++;
    if (first == len)
        return file_fail(ctx, ILF_JSON_ERR_INPUT, "not valid JSON: the file is empty; expected a JSON value");
    size_t deep = too_deep(text, len);
    if (deep < len) {
        char what[80];
        snprintf(what, sizeof what, "arrays and objects nested more than %d deep", ILF_JSON_MAX_DEPTH);
        return syntax_error(ctx, text, len, deep, what);
    }
    const char *end = NULL;
    /* the length includes the terminating NUL, which is how cJSON recognises the end of the text */
    *root = cJSON_ParseWithLengthOpts(text + start, len - start + 1, &end, 1);
    if (*root)
        return ILF_JSON_OK;
    size_t pos = end && end >= text && end <= text + len ? (size_t)(end - text) : len;
    return syntax_error(ctx, text, len, pos, NULL);
}

ilf_json_status ilf_json_load(ilf_json_ctx *ctx, size_t max_bytes, ilf_json **root)
{
    char *text = NULL;
    size_t len = 0;
    *root = NULL;
    ilf_json_status st = read_text(ctx, max_bytes, &text, &len);
    if (st == ILF_JSON_OK)
        st = parse_text(ctx, text, len, root);
    free(text);
    return st;
}

ilf_json *ilf_json_parse_quiet(const char *text, size_t len)
{
    return text != NULL && too_deep(text, len) == len ? cJSON_ParseWithLength(text, len) : NULL;
}

void ilf_json_free(ilf_json *root)
{
    cJSON_Delete(root);
}

/* ------------------------------------------------------------ walking */

ilf_json_type ilf_json_type_of(const ilf_json *j)
{
    if (j == NULL)
        return ILF_JSON_NONE;
    if (cJSON_IsBool(j))
        return ILF_JSON_BOOL;
    if (cJSON_IsNull(j))
        return ILF_JSON_NULL;
    if (cJSON_IsNumber(j))
        return ILF_JSON_NUMBER;
    if (cJSON_IsString(j))
        return ILF_JSON_STRING;
    if (cJSON_IsArray(j))
        return ILF_JSON_ARRAY;
    if (cJSON_IsObject(j))
        return ILF_JSON_OBJECT;
    return ILF_JSON_NONE; /* cJSON's raw values: never produced by its parser */
}

const char *ilf_json_kind(const ilf_json *j)
{
    switch (ilf_json_type_of(j)) {
    case ILF_JSON_BOOL: return "a boolean";
    case ILF_JSON_NULL: return "null";
    case ILF_JSON_NUMBER: return "a number";
    case ILF_JSON_STRING: return "a string";
    case ILF_JSON_ARRAY: return "an array";
    case ILF_JSON_OBJECT: return "an object";
    default: return "nothing";
    }
}

size_t ilf_json_count(const ilf_json *j)
{
    size_t n = 0;
    for (const ilf_json *c = ilf_json_first(j); c != NULL; c = c->next)
        n++;
    return n;
}

const ilf_json *ilf_json_first(const ilf_json *j)
{
    return cJSON_IsArray(j) || cJSON_IsObject(j) ? j->child : NULL;
}

const ilf_json *ilf_json_next(const ilf_json *j)
{
    return j != NULL ? j->next : NULL;
}

const char *ilf_json_key(const ilf_json *j)
{
    return j != NULL ? j->string : NULL;
}

const ilf_json *ilf_json_get(const ilf_json *obj, const char *key)
{
    return cJSON_IsObject(obj) ? cJSON_GetObjectItemCaseSensitive(obj, key) : NULL;
}

const ilf_json *ilf_json_at(const ilf_json *j, size_t k)
{
    const ilf_json *c = cJSON_IsArray(j) ? j->child : NULL;
    for (; c != NULL && k > 0; k--)
        c = c->next;
    return c;
}

double ilf_json_value(const ilf_json *j)
{
    return cJSON_IsNumber(j) ? j->valuedouble : NAN;
}

const char *ilf_json_text(const ilf_json *j)
{
    return cJSON_IsString(j) ? j->valuestring : NULL;
}

/* ------------------------------------------------------------ typed values */

ilf_json_status ilf_json_keys(ilf_json_ctx *ctx, const ilf_json *j, const char *elem, const char *const *allowed)
{
    if (!cJSON_IsObject(j))
        return ilf_json_fail(ctx, elem, "expected an object, got %s", ilf_json_kind(j));
    for (const cJSON *c = j->child; c != NULL; c = c->next) {
        size_t a = 0;
        while (allowed[a] != NULL && strcmp(allowed[a], c->string) != 0)
            a++;
        if (allowed[a] == NULL) {
            char list[256] = "";
            for (size_t i = 0; allowed[i] != NULL; i++)
                snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", i ? ", " : "", allowed[i]);
            return ilf_json_fail(ctx, elem, "unknown key '%.100s' (expected %s)", c->string, list);
        }
        for (const cJSON *d = j->child; d != c; d = d->next)
            if (strcmp(d->string, c->string) == 0)
                return ilf_json_fail(ctx, elem, "duplicate key '%s' (a key may not be repeated)", allowed[a]);
    }
    return ILF_JSON_OK;
}

ilf_json_status ilf_json_member(ilf_json_ctx *ctx, const ilf_json *obj, const char *elem, const char *key,
                                int required, const ilf_json **out)
{
    *out = ilf_json_get(obj, key);
    if (*out == NULL && required)
        return ilf_json_fail(ctx, elem, "missing key '%s'", key);
    return ILF_JSON_OK;
}

ilf_json_status ilf_json_number(ilf_json_ctx *ctx, const ilf_json *j, const char *elem, double *out)
{
    if (!cJSON_IsNumber(j))
        return ilf_json_fail(ctx, elem, "expected a number, got %s", ilf_json_kind(j));
    if (!isfinite(j->valuedouble))
        return ilf_json_fail(ctx, elem, "not a finite number (too large for a double)");
    *out = j->valuedouble;
    return ILF_JSON_OK;
}

/* Reads j into out[0..n) when it is an array of exactly n finite numbers, the common case, checked without
 * naming anything (a large scene has millions of vectors). @return 1, or 0 for the readers' checks to say
 * what is wrong. */
static int take_vector(const cJSON *j, size_t n, double *out)
{
    if (!cJSON_IsArray(j))
        return 0;
    size_t k = 0;
    for (const cJSON *e = j->child; e != NULL; e = e->next, k++) {
        if (k == n || !cJSON_IsNumber(e) || !isfinite(e->valuedouble))
            return 0;
        out[k] = e->valuedouble;
    }
    return k == n;
}

ilf_json_status ilf_json_vector(ilf_json_ctx *ctx, const ilf_json *j, const char *elem, size_t n, double *out)
{
    if (take_vector(j, n, out))
        return ILF_JSON_OK;
    if (!cJSON_IsArray(j))
        return ilf_json_fail(ctx, elem, "expected an array of %zu numbers, got %s", n, ilf_json_kind(j));
    size_t count = ilf_json_count(j);
    if (count != n)
        return ilf_json_fail(ctx, elem, "expected %zu numbers, got %zu", n, count);
    size_t i = 0;
    for (const cJSON *e = j->child; e != NULL; e = e->next, i++) {
        char sub[ILF_JSON_ELEM_MAX];
        ilf_json_item_name(sub, elem, i);
        ilf_json_status st = ilf_json_number(ctx, e, sub, &out[i]);
        if (st != ILF_JSON_OK)
            return st;
    }
    return ILF_JSON_OK;
}

ilf_json_status ilf_json_vector_item(ilf_json_ctx *ctx, const ilf_json *j, const char *parent, size_t i, size_t n,
                                     double *out)
{
    if (take_vector(j, n, out))
        return ILF_JSON_OK;
    char elem[ILF_JSON_ELEM_MAX];
    ilf_json_item_name(elem, parent, i);
    return ilf_json_vector(ctx, j, elem, n, out);
}

ilf_json_status ilf_json_integer(ilf_json_ctx *ctx, const ilf_json *j, const char *elem, uint64_t lo, uint64_t hi,
                                 int pow2, uint64_t *out)
{
    char rule[96];
    snprintf(rule, sizeof rule, "%s in %llu..%llu", pow2 ? "a power of two" : "an integer", (unsigned long long)lo,
             (unsigned long long)hi);
    if (!cJSON_IsNumber(j))
        return ilf_json_fail(ctx, elem, "expected %s, got %s", rule, ilf_json_kind(j));
    double d = j->valuedouble;
    if (!(d == floor(d)) || !isfinite(d))
        return ilf_json_fail(ctx, elem, "must be %s, got %.17g (expected a whole number)", rule, d);
    if (!(d >= (double)lo && d <= (double)hi && d <= 9007199254740992.0))
        return ilf_json_fail(ctx, elem, "must be %s, got %.17g (%.17g is outside %llu..%llu)", rule, d, d,
                             (unsigned long long)lo, (unsigned long long)hi);
    uint64_t v = (uint64_t)d;
    if (pow2 && (v & (v - 1)) != 0)
        return ilf_json_fail(ctx, elem, "must be %s, got %.17g", rule, d);
    *out = v;
    return ILF_JSON_OK;
}

ilf_json_status ilf_json_flag(ilf_json_ctx *ctx, const ilf_json *j, const char *elem, int *out)
{
    *out = 0;
    if (cJSON_IsBool(j)) {
        *out = cJSON_IsTrue(j);
        return ILF_JSON_OK;
    }
    if (cJSON_IsNumber(j) && (j->valuedouble == 0 || j->valuedouble == 1)) {
        *out = j->valuedouble == 1;
        return ILF_JSON_OK;
    }
    return ilf_json_fail(ctx, elem, "expected true, false, 0 or 1, got %s", ilf_json_kind(j));
}

ilf_json_status ilf_json_string(ilf_json_ctx *ctx, const ilf_json *j, const char *elem, const char **out)
{
    *out = "";
    if (!cJSON_IsString(j))
        return ilf_json_fail(ctx, elem, "expected a string, got %s", ilf_json_kind(j));
    if (j->valuestring[0] == '\0')
        return ilf_json_fail(ctx, elem, "must not be empty");
    *out = j->valuestring;
    return ILF_JSON_OK;
}
