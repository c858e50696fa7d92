/*
 * fuzz_file.c - the temporary input file of a libFuzzer target (see
 * fuzz_file.h): one folder per process, made by mkdtemp() under $TMPDIR (or
 * /tmp) on the first call, holding one file per name; both are removed by an
 * atexit() handler, so a run leaves nothing behind unless it crashes.
 * The first call also pins the mesh module (ilf/module.h) to the one this
 * build made, FUZZ_MESH_MODULE, unless ILFKIT_MESH_MODULE is set: the
 * targets live in BUILD/tests/fuzz, where the loader's place beside the
 * program (BUILD/LIBDIR/ilfkit is one folder up from BUILD/tests) misses,
 * and every mesh would otherwise be refused before assimp reads it.
 */
#define _POSIX_C_SOURCE 200809L

#include "fuzz_file.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#ifndef FUZZ_MESH_MODULE
#error "FUZZ_MESH_MODULE (the path of the build's mesh module) must be defined"
#endif

static char folder[4096];
static char path[4096 + 64];

/* atexit handler: removes the input file and the folder. */
static void remove_folder(void)
{
    unlink(path);
    rmdir(folder);
}

/* Creates this process's folder once. Aborts on failure. */
static void make_folder(void)
{
    if (folder[0] != '\0')
        return;
    const char *tmp = getenv("TMPDIR");
    snprintf(folder, sizeof folder, "%s/ilf-fuzz-XXXXXX", tmp != NULL && tmp[0] != '\0' ? tmp : "/tmp");
    if (mkdtemp(folder) == NULL) {
        perror("fuzz_file: mkdtemp");
        abort();
    }
    atexit(remove_folder);
    setenv("ILFKIT_MESH_MODULE", FUZZ_MESH_MODULE, 0);
}

const char *fuzz_file_write(const char *name, const uint8_t *data, size_t size)
{
    make_folder();
    snprintf(path, sizeof path, "%s/%s", folder, name);
    FILE *f = fopen(path, "wb");
    if (f == NULL || (size > 0 && fwrite(data, 1, size, f) != size) || fclose(f) != 0) {
        perror("fuzz_file: writing the input");
        abort();
    }
    return path;
}
