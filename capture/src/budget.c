/*
 * budget.c - the bound on a capture's whole work (cap__check_samples in
 * probe.h): before any image is decoded, the samples (width * height *
 * channels) of every image the capture will read are summed from the images'
 * headers and the capture is refused past ILF_CAPTURE_MAX_SAMPLES.
 *
 * Invariants: an image is counted once each time the capture reads it (every
 * position and bracket slot naming it), as decoding costs; its header is read
 * once per distinct path (a cache keyed by the path's text, since the
 * manifest holds a copy of the path per slot), so a manifest naming one image
 * at every position costs one header read. Images are visited in the
 * capture's own order (plane, position k = j*nu + i, bracket), so a header
 * that cannot be read is reported for the element the capture would report.
 */
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>

#include "ilf/hash.h"
#include "ilf/limits.h"
#include "image/image.h"
#include "internal.h"
#include "probe.h"

/* One distinct path and its samples. */
typedef struct seen {
    const char *path; /* borrowed from the manifest; NULL for an empty slot */
    uint64_t samples;
} seen;

/* Open addressing, linear probing; size a power of two, at most half full. */
typedef struct seen_table {
    seen *slots;
    size_t size, used;
} seen_table;

/* @return a hash of the text of s (FNV-1a, finished with splitmix64). */
static uint64_t text_hash(const char *s)
{
    uint64_t h = 0xcbf29ce484222325ull;
    for (; *s != '\0'; s++)
        h = (h ^ (unsigned char)*s) * 0x100000001b3ull;
    return ilf_splitmix64(h);
}

/* @return the slot holding path, or the empty slot where it belongs. */
static seen *table_find(const seen_table *t, const char *path)
{
    size_t mask = t->size - 1;
    for (size_t at = (size_t)text_hash(path) & mask;; at = (at + 1) & mask)
        if (t->slots[at].path == NULL || strcmp(t->slots[at].path, path) == 0)
            return &t->slots[at];
}

/* Doubles t's size (from 0: 64 slots). @return 0 when memory ran out (t unchanged). */
static int table_grow(seen_table *t)
{
    seen_table bigger = {calloc(t->size > 0 ? 2 * t->size : 64, sizeof(seen)), t->size > 0 ? 2 * t->size : 64,
                         t->used};
    if (bigger.slots == NULL)
        return 0;
    for (size_t k = 0; k < t->size; k++)
        if (t->slots[k].path != NULL)
            *table_find(&bigger, t->slots[k].path) = t->slots[k];
    free(t->slots);
    *t = bigger;
    return 1;
}

/* The samples of image k of entry e, from the cache or its header. */
static cap_status samples_of(const cap_manifest *m, const cap__entry *e, uint32_t k, seen_table *t,
                             uint64_t *samples)
{
    seen *s = t->size > 0 ? table_find(t, e->files[k]) : NULL;
    if (s != NULL && s->path != NULL) {
        *samples = s->samples;
        return CAP_OK;
    }
    img_header hdr;
    char msg[ILF_MESSAGE_BYTES];
    cap_status st = cap__from_image(img_header_read(e->files[k], &hdr, msg, sizeof msg));
    if (st != CAP_OK) {
        cap__fail_text(st, msg);
        return cap__fail_prefix(st, "%s: %s", m->path, e->element);
    }
    *samples = (uint64_t)hdr.width * (uint64_t)hdr.height * (uint64_t)hdr.channels;
    if (2 * (t->used + 1) > t->size && !table_grow(t))
        return cap__fail(CAP_ERR_NOMEM, "%s: out of memory for the images' sizes", m->path);
    s = table_find(t, e->files[k]);
    s->path = e->files[k];
    s->samples = *samples;
    t->used++;
    return CAP_OK;
}

/* Adds the samples of every image plane pl reads to *total. */
static cap_status add_plane(const cap_manifest *m, const cap__plane *pl, seen_table *t, uint64_t *total)
{
    size_t positions = (size_t)pl->desc.nu * pl->desc.nv;
    for (size_t p = 0; p < positions; p++)
        for (uint32_t k = 0; k < pl->entries[p].count; k++) {
            uint64_t samples = 0;
            cap_status st = samples_of(m, &pl->entries[p], k, t, &samples);
            if (st != CAP_OK)
                return st;
            *total += samples; /* at most 2^24 reads of 2^31 samples: no overflow */
        }
    return CAP_OK;
}

cap_status cap__check_samples(const cap_manifest *m)
{
    seen_table t = {NULL, 0, 0};
    uint64_t total = 0;
    cap_status st = CAP_OK;
    for (size_t q = 0; st == CAP_OK && q < m->nplanes; q++)
        st = add_plane(m, &m->planes[q], &t, &total);
    free(t.slots);
    if (st == CAP_OK && total > ILF_CAPTURE_MAX_SAMPLES)
        st = cap__fail(CAP_ERR_INPUT,
                       "%s: its %" PRIu64 " image reads hold %" PRIu64 " samples in all (width x height x channels, "
                       "an image named again counted again), over the limit of %" PRIu64 " samples a capture reads",
                       m->path, m->images, total, (uint64_t)ILF_CAPTURE_MAX_SAMPLES);
    return st;
}
