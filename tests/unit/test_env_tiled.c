/*
 * test_env_tiled.c — a tiled OpenEXR (half floats, partial edge tiles; written with OpenEXR's own API)
 * as a scene's environment map: the scene loads, the map keeps its size, and the radiance the renderer
 * sees is the map's (the top rows bright, the bottom rows dark: up is up), times the scene's scale.
 */
#include "test_exr_write.h"
#include "test_util.h"

#include "scene/scene.h"

#include <stdio.h>

int main(void)
{
    ic_image img;
    const int w = 64, h = 32;
    CHECK(ic_image_create(&img, w, h) == IC_OK, "create");
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c)
                img.rgb[3 * (y * w + x) + c] = y < h / 2 ? 4.0f : 0.25f; /* exact in half */
    CHECK(write_tiled_exr(IC_TEST_TMP "/env_tiled.exr", &img, 16, 12, 1), "tiled half EXR written");
    FILE *f = fopen(IC_TEST_TMP "/env_tiled_floor.obj", "w");
    if (f) {
        fputs("v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nf 1 3 2\nf 1 4 3\n", f);
        fclose(f);
    }
    f = fopen(IC_TEST_TMP "/env_tiled.json", "w");
    if (f) {
        fputs("{\n  \"meshes\": [{\"path\": \"env_tiled_floor.obj\"}],\n"
              "  \"environment\": {\"map\": \"env_tiled.exr\", \"scale\": [2, 2, 2]}\n}\n", f);
        fclose(f);
    }
    ic_scene_load_options lo = {0};
    ic_scene *s = NULL;
    ic_error err = {0};
    CHECK(ic_scene_load(IC_TEST_TMP "/env_tiled.json", &lo, &s, &err) == IC_OK, "the scene with a tiled map loads: %s",
          err.message);
    if (s) {
        CHECK(s->env.enabled && s->env.image.width == w && s->env.image.height == h, "the map's size: %dx%d",
              s->env.image.width, s->env.image.height);
        ic_vec3 up = ic_scene_env_radiance(s, v3(0.0f, 1.0f, 0.0f)), down = ic_scene_env_radiance(s, v3(0.0f, -1.0f, 0.0f));
        CHECK(fabsf(up.y - 8.0f) < 1e-4f && fabsf(down.y - 0.5f) < 1e-4f,
              "the sky above is the map's top times 2 (%g), below its bottom times 2 (%g)", up.y, down.y);
        ic_scene_free(s);
    }
    ic_image_free(&img);
    TEST_MAIN_END();
}
