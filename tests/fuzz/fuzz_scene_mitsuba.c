/*
 * fuzz_scene_mitsuba.c — ic_scene_load of the Mitsuba XML scene loader (sensor, shapes — the companion
 * quad.obj by name —, BSDFs by reference, emitters, defaults).
 */
#include "fuzz_scene_load.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_scene_load("scene.xml", data, size);
}
