/* fuzz_mesh_glb.c — ic_scene_load of a bare binary glTF (.glb: JSON and BIN chunks). */
#include "fuzz_scene_load.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_scene_load("mesh.glb", data, size);
}
