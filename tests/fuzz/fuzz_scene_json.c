/*
 * fuzz_scene_json.c — ic_scene_load of the JSON scene loader (camera, meshes by name — the companions
 * quad.obj, tri.bin, checker.pfm —, materials, lights, environment, render).
 */
#include "fuzz_scene_load.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_scene_load("scene.json", data, size);
}
