/*
 * fuzz_mesh.c - libFuzzer target for the mesh import path: the hand-written
 * pre-checks (PLY counts, binary glTF headers and chunks, glTF accessor
 * types) and assimp behind them. The first byte of an input picks the
 * format (its value modulo the number of accepted extensions); the rest is
 * written as mesh.<ext> beside a fixed scene that names it, which
 * rl_scene_load() reads. The seeds in corpus/fuzz_mesh/ are small valid
 * meshes of each format, prefixed with their format's byte. A load may
 * fail; it must not crash, leak, overflow or hang.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "fuzz_file.h"
#include "relight/scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const char *const ext[] = {"obj", "ply", "gltf", "glb", "stl", "fbx", "3ds"};
    if (size < 1)
        return 0;
    const char *e = ext[data[0] % (sizeof ext / sizeof *ext)];
    char mesh[16], scene[160];
    snprintf(mesh, sizeof mesh, "mesh.%s", e);
    fuzz_file_write(mesh, data + 1, size - 1);
    int n = snprintf(scene, sizeof scene,
                     "{\"materials\": {\"grey\": {}}, \"meshes\": [{\"file\": \"%s\", \"material\": \"grey\"}]}", mesh);
    rl_scene *s = NULL;
    if (rl_scene_load(fuzz_file_write("scene.json", (const uint8_t *)scene, (size_t)n), &s) == RL_OK)
        rl_scene_destroy(s);
    return 0;
}
