/*
 * fuzz_scene_load.h — the body shared by the scene and mesh harnesses: the input is written under one
 * fixed name in the scratch folder (beside the companion files of fuzz_util.h) and loaded with
 * ic_scene_load, with small limits so that a header asking for gigabytes is refused, not allocated.
 */
#ifndef IC_FUZZ_SCENE_LOAD_H
#define IC_FUZZ_SCENE_LOAD_H

#include "fuzz_util.h"

#include "irrcache/render.h"

static inline int fuzz_scene_load(const char *name, const uint8_t *data, size_t size)
{
    fuzz_companions();
    char path[1024];
    fuzz_write(name, data, size, path, sizeof path);
    ic_scene_load_options opt;
    memset(&opt, 0, sizeof opt);
    opt.shared_scenes_dir = fuzz_dir();
    opt.max_texture_pixels = 1 << 16;
    opt.max_mesh_elements = 1 << 16;
    ic_scene *scene = NULL;
    ic_error err;
    int ok = ic_scene_load(path, &opt, &scene, &err) == IC_OK;
    fuzz_report(ok, err.message);
    if (ok)
        (void)ic_scene_light_count(scene);
    ic_scene_free(scene);
    return 0;
}

#endif
