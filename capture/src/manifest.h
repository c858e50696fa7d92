/*
 * manifest.h - the loaded manifest's layout, shared by manifest.c (which
 * builds it) and capture.c (which reads it). Not installed, not public.
 *
 * Invariants of a loaded manifest: 1 .. CAP_PLANES_MAX planes with distinct
 * slab names and at most CAP__MAX_POSITIONS positions in all; on each plane
 * every grid position has exactly one
 * entry with 1 .. CAP_BRACKET_MAX existing files, positive finite
 * exposures and scale, a rotation, a known projection and colour space;
 * desc passes lfio_slab_new()'s checks.
 */
#ifndef CAPTURE_MANIFEST_H
#define CAPTURE_MANIFEST_H

#include "capture/capture.h"
#include "ilf/json.h"
#include "ilf/limits.h"

/** Most positions a manifest may describe. */
#define CAP__MAX_POSITIONS ILF_CAPTURE_MAX_POSITIONS

typedef struct cap__entry {
    char element[64];  /* "positions[3]" or "pattern" */
    int given;         /* set once the position is described */
    cap_projection projection;
    double R[9];
    cap_colour_space colour;
    double scale;
    uint32_t count;
    int bracket;
    char **files;      /* [count], owned */
    double *exposures; /* [count], owned */
} cap__entry;

/* One capture plane: the slab it becomes and its positions. */
typedef struct cap__plane {
    char element[32];    /* where it is given: "" (the whole file) or "planes[k]" */
    lfio_slab_desc desc;
    uint64_t images;
    cap__entry *entries; /* [nv][nu]: entry k = j*nu + i */
} cap__plane;

struct cap_manifest {
    char *path;          /* as given, for messages */
    size_t nplanes;      /* 1 .. CAP_PLANES_MAX, slab names distinct */
    cap__plane *planes;  /* [nplanes] */
    uint64_t images;     /* over every plane */
};

/* ------------------------------------------------------------ JSON values
 * Capture's typed reading of its JSON inputs (manifests here, proxies in proxy.c), through base's one
 * strict reader (ilf/json.h): each function reads one value and, on failure, moves the reader's
 * message "PATH: ELEM: problem" into capture's error state with CAP_ERR_INPUT (CAP_ERR_NOMEM when
 * memory runs out). Nothing is stored on failure except where stated. */

/* Fails with "PATH: ELEM: <fmt>" (ELEM and its colon left out when empty). @return CAP_ERR_INPUT. */
cap_status cap__json_bad(const char *path, const char *elem, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Reads and parses the JSON file path of at most max_bytes (a file that cannot be opened or read is
 * CAP_ERR_INPUT, as every problem with a capture input is). @return CAP_OK and *root (ilf_json_free it). */
cap_status cap__json_load(const char *path, size_t max_bytes, ilf_json **root);

/* j must be an object whose keys are all in allowed (NULL-terminated) and none repeated. @return CAP_OK or CAP_ERR_INPUT. */
cap_status cap__json_keys(const char *path, const ilf_json *j, const char *elem, const char *const *allowed);

/* *out = member key of obj, or NULL; a missing required member is an error. @return CAP_OK or CAP_ERR_INPUT. */
cap_status cap__json_member(const char *path, const ilf_json *obj, const char *elem, const char *key, int required,
                            const ilf_json **out);

/* A finite number > 0. @return CAP_OK and *out, or CAP_ERR_INPUT. */
cap_status cap__json_positive(const char *path, const ilf_json *j, const char *elem, double *out);

/* An array of 3 finite numbers. @return CAP_OK and out, or CAP_ERR_INPUT. */
cap_status cap__json_vector3(const char *path, const ilf_json *j, const char *elem, double out[3]);

/* A whole number in lo..hi. @return CAP_OK and *out, or CAP_ERR_INPUT. */
cap_status cap__json_uint(const char *path, const ilf_json *j, const char *elem, uint32_t lo, uint32_t hi,
                          uint32_t *out);

/* A non-empty string; *out is set to "" first, so it is never left undefined. @return CAP_OK or CAP_ERR_INPUT. */
cap_status cap__json_string(const char *path, const ilf_json *j, const char *elem, const char **out);

/* A slab name: 1 to LFIO_NAME_MAX of A-Z a-z 0-9 _ - . copied into name. @return CAP_OK or CAP_ERR_INPUT. */
cap_status cap__json_slab_name(const char *path, const ilf_json *j, const char *elem, char name[LFIO_NAME_MAX + 1]);

/* The required "origin", "u", "v" members of obj (which may hold other keys, checked by the caller)
 * into d, with u and v nonzero and orthogonal as lfio requires. @return CAP_OK or CAP_ERR_INPUT. */
cap_status cap__json_rectangle(const char *path, const ilf_json *obj, const char *elem, lfio_slab_desc *d);

/* A grid object {"nu", "nv"}, each 1 .. 65536, into d->nu and d->nv. @return CAP_OK or CAP_ERR_INPUT. */
cap_status cap__json_grid(const char *path, const ilf_json *j, const char *elem, lfio_slab_desc *d);

#endif /* CAPTURE_MANIFEST_H */
