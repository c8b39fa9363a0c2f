/*
 * fuzz_scene_radiance.c — ic_scene_load of the Radiance scene reader (primitives and their argument lists,
 * modifiers by name, surfaces tessellated, a mesh through the companion quad.obj, sources).
 */
#include "fuzz_scene_load.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_scene_load("scene.rad", data, size);
}
