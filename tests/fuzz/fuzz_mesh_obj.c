/*
 * fuzz_mesh_obj.c — ic_scene_load of a bare OBJ through assimp and the loader's own OBJ/MTL checks (mtllib
 * quad.mtl resolves to a companion).
 */
#include "fuzz_scene_load.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_scene_load("mesh.obj", data, size);
}
