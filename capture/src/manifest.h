/*
 * manifest.h - the loaded manifest's layout, shared by manifest.c (which
 * builds it) and capture.c (which reads it). Not installed, not public.
 *
 * Invariants of a loaded manifest: every grid position has exactly one
 * entry with 1 .. CAP_BRACKET_MAX existing files, positive finite
 * exposures and scale, a rotation, a known projection and colour space;
 * desc passes lfio_slab_new()'s checks.
 */
#ifndef CAPTURE_MANIFEST_H
#define CAPTURE_MANIFEST_H

#include "capture/capture.h"

/** Most positions a manifest may describe. */
#define CAP__MAX_POSITIONS ((uint64_t)1 << 20)

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

struct cap_manifest {
    char *path;          /* as given, for messages */
    lfio_slab_desc desc;
    uint64_t images;
    cap__entry *entries; /* [nv][nu]: entry k = j*nu + i */
};

#endif /* CAPTURE_MANIFEST_H */
