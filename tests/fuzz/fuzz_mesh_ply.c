/*
 * fuzz_mesh_ply.c — ic_scene_load of a bare PLY: the loader's header and vertex pre-check, then assimp.
 */
#include "fuzz_scene_load.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_scene_load("mesh.ply", data, size);
}
