/*
 * bench_refkey.c - the key of a cached reference (bench.h's
 * bench_reference_key()), shared by the solid-angle reference (bench_ref.c)
 * and the path-traced one (bench_ptref.c): a 64-bit FNV-1a hash of a format
 * tag and the ilfkit version; the scene file's bytes; the name and bytes of
 * every file its "meshes" and "lightfields" entries name (files those name in
 * turn, such as an OBJ's .mtl, are not included); and the caller's settings
 * line.
 *
 * Invariants: the same scene files and settings give the same key on every
 * platform; a file that cannot be read gives no key (reported), never a key
 * of what was read so far.
 */
#include <cjson/cJSON.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bench.h"
#include "cli.h"
#include "ilf/file_kind.h"

/* FNV-1a, 64 bits. */
#define FNV_OFFSET 0xcbf29ce484222325ull
#define FNV_PRIME 0x100000001b3ull
/* The tag that starts every key: change it when the cache's contents change meaning. */
#define KEY_TAG "ilfkit bench reference 1, ilfkit " ILFKIT_VERSION

/* @return h extended by size bytes of data (FNV-1a). */
static uint64_t fnv1a(uint64_t h, const void *data, size_t size)
{
    const unsigned char *p = data;
    for (size_t k = 0; k < size; k++) {
        h ^= p[k];
        h *= FNV_PRIME;
    }
    return h;
}

/* Extends *h by the bytes of file path. @return 1, or 0 after reporting. */
static int hash_file(uint64_t *h, const char *path)
{
    char why[160];
    int fd;
    if (ilf_input_open(path, &fd, why, sizeof why) != 0) { /* a FIFO is refused, never waited on */
        cli_error(BENCH_SUB, "%s: %s", path, why);
        return 0;
    }
    FILE *f = fdopen(fd, "rb");
    if (f == NULL) {
        int err = errno;
        close(fd);
        cli_error(BENCH_SUB, "%s: %s", path, strerror(err));
        return 0;
    }
    unsigned char buf[65536];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, f)) > 0)
        *h = fnv1a(*h, buf, n);
    int ok = !ferror(f);
    fclose(f);
    if (!ok)
        cli_error(BENCH_SUB, "%s: read error", path);
    return ok;
}

/* Extends *h by the name and bytes of every "file" in the scene's array `section`. @return 1, or 0 after reporting. */
static int hash_section_files(uint64_t *h, const char *scene, const cJSON *root, const char *section)
{
    const cJSON *item;
    cJSON_ArrayForEach(item, cJSON_GetObjectItemCaseSensitive(root, section))
    {
        const cJSON *file = cJSON_GetObjectItemCaseSensitive(item, "file");
        char path[BENCH_PATH_MAX];
        if (!cJSON_IsString(file))
            continue; /* the loader has already refused such a scene */
        if (!bench_resolve_beside(path, scene, file->valuestring)) {
            cli_error(BENCH_SUB, "%s: path too long: %s", scene, file->valuestring);
            return 0;
        }
        *h = fnv1a(*h, file->valuestring, strlen(file->valuestring) + 1);
        if (!hash_file(h, path))
            return 0;
    }
    return 1;
}

int bench_reference_key(const bench_config *cfg, const char *settings, uint64_t *key)
{
    uint64_t h = fnv1a(FNV_OFFSET, KEY_TAG, sizeof KEY_TAG);
    char *text = bench_read_text(cfg->scene);
    cJSON *root = text != NULL ? cJSON_Parse(text) : NULL;
    int ok = root != NULL;
    if (!ok)
        cli_error(BENCH_SUB, "%s: cannot read the scene again to make its cache key", cfg->scene);
    if (ok) {
        h = fnv1a(h, text, strlen(text));
        ok = hash_section_files(&h, cfg->scene, root, "meshes") &&
             hash_section_files(&h, cfg->scene, root, "lightfields");
    }
    *key = fnv1a(h, settings, strlen(settings));
    cJSON_Delete(root);
    free(text);
    return ok;
}
