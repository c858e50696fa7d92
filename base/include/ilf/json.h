/*
 * ilf/json.h - the one strict JSON reader of ilfkit: scene files (relight),
 * capture manifests and proxies (capture), and the glTF pre-check of the
 * mesh importer all read JSON through it. It is built over cJSON, whose
 * header only base/src/json.c includes (a wall test checks it): a parsed
 * value is the opaque ilf_json, walked with the accessors below.
 *
 * Strictness, the stricter of the two readers it replaced wherever they
 * differed: a file is read whole, bounded by the caller's size limit, and
 * must be a regular file; a UTF-8 byte order mark is skipped; a NUL byte,
 * an empty file, trailing text, NaN or Infinity literals and nesting deeper
 * than ILF_JSON_MAX_DEPTH are refused; objects checked with ilf_json_keys()
 * may hold only the keys allowed, each once; numbers are finite; integers
 * are exact; strings read with ilf_json_string() are not empty.
 *
 * Messages have one format, "FILE:LINE:COL: ELEMENT: problem": LINE:COL
 * (from 1, the column in bytes) where a position is known (syntax errors),
 * ELEMENT a path into the file ("polygons[3].vertices[1][0]") where one is
 * named. A message is written into the caller's ilf_json_ctx, never printed;
 * the caller copies it into its own error state.
 */
#ifndef ILF_JSON_H
#define ILF_JSON_H

#include <stddef.h>
#include <stdint.h>

#include "ilf/limits.h"

/* A parsed JSON value (cJSON inside; opaque here). */
typedef struct cJSON ilf_json;

typedef enum ilf_json_status {
    ILF_JSON_OK = 0,
    ILF_JSON_ERR_INPUT, /* the text or a value breaks a rule; the message names it */
    ILF_JSON_ERR_IO,    /* the file cannot be opened or read, or is not a regular file */
    ILF_JSON_ERR_NOMEM  /* memory ran out */
} ilf_json_status;

typedef enum ilf_json_type {
    ILF_JSON_NONE, /* no value at all (a NULL pointer: a missing member) */
    ILF_JSON_NULL,
    ILF_JSON_BOOL,
    ILF_JSON_NUMBER,
    ILF_JSON_STRING,
    ILF_JSON_ARRAY,
    ILF_JSON_OBJECT
} ilf_json_type;

/* What is being read: the file named at the start of every message, and the last message. */
typedef struct ilf_json_ctx {
    const char *file;
    char message[ILF_MESSAGE_BYTES];
} ilf_json_ctx;

/* ------------------------------------------------------------ parsing */

/* Reads ctx->file (a regular file of at most max_bytes) and parses it strictly.
 * @return ILF_JSON_OK and *root (ilf_json_free it); else *root = NULL and a message. */
ilf_json_status ilf_json_load(ilf_json_ctx *ctx, size_t max_bytes, ilf_json **root);

/* Parses len bytes of text leniently (no terminator needed, no message), for pre-checks that leave
 * whatever they cannot parse to another reader. @return the root (ilf_json_free it), or NULL. */
ilf_json *ilf_json_parse_quiet(const char *text, size_t len);

/* Frees a parsed tree; NULL is a no-op. @return nothing. */
void ilf_json_free(ilf_json *root);

/* ------------------------------------------------------------ walking */

/* @return the type of j; ILF_JSON_NONE for NULL. */
ilf_json_type ilf_json_type_of(const ilf_json *j);

/* @return what j is, for messages: "a number", "an object", ...; "nothing" for NULL. */
const char *ilf_json_kind(const ilf_json *j);

/* @return the number of items of an array or members of an object; 0 for anything else. */
size_t ilf_json_count(const ilf_json *j);

/* @return the first item or member of an array or object, or NULL. */
const ilf_json *ilf_json_first(const ilf_json *j);

/* @return the item or member after j in its array or object, or NULL. */
const ilf_json *ilf_json_next(const ilf_json *j);

/* @return the key of j when it is a member of an object, else NULL. */
const char *ilf_json_key(const ilf_json *j);

/* @return member key of object obj (case-sensitive; the first if repeated), or NULL. */
const ilf_json *ilf_json_get(const ilf_json *obj, const char *key);

/* @return item k of array j, or NULL. */
const ilf_json *ilf_json_at(const ilf_json *j, size_t k);

/* @return the number j holds (not checked for finiteness); NaN if j is not a number. */
double ilf_json_value(const ilf_json *j);

/* @return the text of string j (borrowed from the tree), or NULL if j is not a string. */
const char *ilf_json_text(const ilf_json *j);

/* ------------------------------------------------------------ messages */

/* Longest element path in messages; a longer one ends in "...". */
#define ILF_JSON_ELEM_MAX 256

/* Writes "FILE: ELEM: <fmt>" (ELEM and its colon left out when empty) into ctx->message.
 * @return ILF_JSON_ERR_INPUT. */
ilf_json_status ilf_json_fail(ilf_json_ctx *ctx, const char *elem, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Writes "elem.key" ("key" when elem is empty) into out. @return nothing. */
void ilf_json_member_name(char out[ILF_JSON_ELEM_MAX], const char *elem, const char *key);

/* Writes "elem[k]" into out. @return nothing. */
void ilf_json_item_name(char out[ILF_JSON_ELEM_MAX], const char *elem, size_t k);

/* ------------------------------------------------------------ typed values */

/* j must be an object whose keys are all in allowed (NULL-terminated) and none repeated.
 * @return ILF_JSON_OK, or ILF_JSON_ERR_INPUT naming elem and the key. */
ilf_json_status ilf_json_keys(ilf_json_ctx *ctx, const ilf_json *j, const char *elem, const char *const *allowed);

/* *out = member key of obj, or NULL when absent. @return ILF_JSON_OK, or ILF_JSON_ERR_INPUT
 * ("missing key 'KEY'") when required and absent. */
ilf_json_status ilf_json_member(ilf_json_ctx *ctx, const ilf_json *obj, const char *elem, const char *key,
                                int required, const ilf_json **out);

/* Reads the finite number j. @return ILF_JSON_OK and *out, or ILF_JSON_ERR_INPUT naming elem. */
ilf_json_status ilf_json_number(ilf_json_ctx *ctx, const ilf_json *j, const char *elem, double *out);

/* Reads the array j of exactly n finite numbers into out[0..n).
 * @return ILF_JSON_OK, or ILF_JSON_ERR_INPUT naming elem or the item at fault. */
ilf_json_status ilf_json_vector(ilf_json_ctx *ctx, const ilf_json *j, const char *elem, size_t n, double *out);

/* ilf_json_vector() of j, entry i of array element parent, naming it "parent[i]" only in a message (a large
 * scene's vertices are millions of entries). */
ilf_json_status ilf_json_vector_item(ilf_json_ctx *ctx, const ilf_json *j, const char *parent, size_t i, size_t n,
                                     double *out);

/* Reads a whole number in lo..hi (hi at most 2^53, what a JSON number holds exactly), also a power
 * of two when pow2. @return ILF_JSON_OK and *out, or ILF_JSON_ERR_INPUT naming elem and the rule. */
ilf_json_status ilf_json_integer(ilf_json_ctx *ctx, const ilf_json *j, const char *elem, uint64_t lo, uint64_t hi,
                                 int pow2, uint64_t *out);

/* Reads a flag: true or false, or the integers 1 and 0 that other flags of ilfkit's files use.
 * @return ILF_JSON_OK and *out (1 or 0), or ILF_JSON_ERR_INPUT; *out is 0 on failure. */
ilf_json_status ilf_json_flag(ilf_json_ctx *ctx, const ilf_json *j, const char *elem, int *out);

/* Reads a non-empty string. @return ILF_JSON_OK and *out (borrowed from j), or ILF_JSON_ERR_INPUT;
 * *out is "" on failure, never undefined. */
ilf_json_status ilf_json_string(ilf_json_ctx *ctx, const ilf_json *j, const char *elem, const char **out);

#endif /* ILF_JSON_H */
