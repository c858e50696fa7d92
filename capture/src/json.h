/*
 * json.h - strict JSON reading for the capture library's input files
 * (manifests and proxies): reading a file, parsing it with positions in
 * syntax errors, and typed, range-checked values whose failures name the
 * file and the element ("m.json: plane.u[2]: not a finite number").
 * Not installed, not public.
 *
 * Invariants: every function either stores a valid value or fails with
 * CAP_ERR_INPUT and one message; nothing is stored on failure except where
 * stated; element names longer than CAP__ELEM_MAX end in "...".
 */
#ifndef CAPTURE_JSON_H
#define CAPTURE_JSON_H

#include <cjson/cJSON.h>
#include <stddef.h>
#include <stdint.h>

#include "capture/common.h"
#include "lfio/lightfield.h"

#define CAP__ELEM_MAX 96

/* Fails with "PATH: ELEM: <fmt>" (ELEM and its colon left out when empty). @return CAP_ERR_INPUT. */
cap_status cap__json_bad(const char *path, const char *elem, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* out = "elem.key" ("key" when elem is empty); out = "elem[k]". */
void cap__json_member_name(char out[CAP__ELEM_MAX], const char *elem, const char *key);
void cap__json_item_name(char out[CAP__ELEM_MAX], const char *elem, size_t k);

/* @return what kind of value j is, for messages: "a number", "an object", ... */
const char *cap__json_kind(const cJSON *j);

/* Reads a file of at most max_bytes and parses it (a UTF-8 byte order mark is skipped; NUL bytes
 * are refused; syntax errors give "PATH:LINE:COLUMN"). @return CAP_OK and *root (cJSON_Delete it). */
cap_status cap__json_load(const char *path, size_t max_bytes, cJSON **root);

/* j must be an object whose keys are all in allowed (NULL-terminated) and none repeated. */
cap_status cap__json_keys(const char *path, const cJSON *j, const char *elem, const char *const *allowed);

/* *out = member key of obj, or NULL; a missing required member is an error. */
cap_status cap__json_member(const char *path, const cJSON *obj, const char *elem, const char *key, int required,
                            const cJSON **out);

cap_status cap__json_number(const char *path, const cJSON *j, const char *elem, double *out);
cap_status cap__json_positive(const char *path, const cJSON *j, const char *elem, double *out);
cap_status cap__json_vector3(const char *path, const cJSON *j, const char *elem, double out[3]);
cap_status cap__json_uint(const char *path, const cJSON *j, const char *elem, uint32_t lo, uint32_t hi,
                          uint32_t *out);
/* *out is set to "" first, so it is never left undefined. */
cap_status cap__json_string(const char *path, const cJSON *j, const char *elem, const char **out);

/* A slab name: 1 to LFIO_NAME_MAX of A-Z a-z 0-9 _ - . copied into name. */
cap_status cap__json_slab_name(const char *path, const cJSON *j, const char *elem, char name[LFIO_NAME_MAX + 1]);

/* The required "origin", "u", "v" members of obj (which may hold other keys, checked by the caller)
 * into d, with u and v nonzero and orthogonal as lfio requires. */
cap_status cap__json_rectangle(const char *path, const cJSON *obj, const char *elem, lfio_slab_desc *d);

/* A grid object {"nu", "nv"}, each 1 .. 65536, into d->nu and d->nv. */
cap_status cap__json_grid(const char *path, const cJSON *j, const char *elem, lfio_slab_desc *d);

#endif /* CAPTURE_JSON_H */
