/*
 * fuzz_mesh_gltf.c — ic_scene_load of a bare glTF 2.0 (JSON; buffers as data: URIs or the companion
 * tri.bin).
 */
#include "fuzz_scene_load.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_scene_load("mesh.gltf", data, size);
}
