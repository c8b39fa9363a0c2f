/*
 * fuzz_view_radiance.c — a Radiance view file (--view: rview/rpict's -vt -vp -vd -vu -vh -vv -vs -vl -vo
 * -va, the `rview`/`rpict`/`VIEW=` line forms) read for a small fixed Radiance scene: the options, their
 * numbers and the limits of each view type.
 */
#include "fuzz_scene_load.h"

static const char room[] = "void light lamp 0 0 3 5 5 5\n"
                           "void plastic grey 0 0 5 0.6 0.6 0.6 0 0\n"
                           "grey polygon floor 0 0 12 -1 0 -1  1 0 -1  1 0 1  -1 0 1\n"
                           "lamp polygon panel 0 0 12 -0.2 1.5 -0.2  -0.2 1.5 0.2  0.2 1.5 0.2  0.2 1.5 -0.2\n";

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char scene_path[1024], view_path[1024];
    fuzz_write("room.rad", (const uint8_t *)room, sizeof room - 1, scene_path, sizeof scene_path);
    fuzz_write("room.vf", data, size, view_path, sizeof view_path);
    ic_scene_load_options opt;
    memset(&opt, 0, sizeof opt);
    opt.shared_scenes_dir = fuzz_dir();
    opt.view = view_path;
    ic_scene *scene = NULL;
    ic_error err;
    int ok = ic_scene_load(scene_path, &opt, &scene, &err) == IC_OK;
    fuzz_report(ok, err.message);
    ic_scene_free(scene);
    return 0;
}
