/*
 * fuzz_scene.c - libFuzzer target for the scene reader: each input is a
 * scene file handed to rl_scene_load(). Meshes and light fields it names
 * are looked up beside it, in the target's temporary folder, where nothing
 * else exists; the seeds in corpus/fuzz_scene/ are small valid and invalid
 * scenes. A load may fail; it must not crash, leak or overflow.
 */
#include <stddef.h>
#include <stdint.h>

#include "fuzz_file.h"
#include "relight/scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    rl_scene *scene = NULL;
    if (rl_scene_load(fuzz_file_write("scene.json", data, size), &scene) == RL_OK)
        rl_scene_destroy(scene);
    return 0;
}
