/*
 * test_analytic.c — the path tracer against scenes with a closed-form answer (pbrt-style furnace
 * tests), rendered through the public API exactly as the command does:
 *   1. furnace: camera inside a closed sphere with Kd = 0.5 and Le = 0.5 everywhere sees
 *      L = Le + ρ·L  ⇒  L = Le / (1 − ρ) = 1.0 in every pixel;
 *   2. open plane under a uniform sky of radiance L_sky: every point receives E = π·L_sky, so a
 *      Lambertian plane of albedo ρ seen from above has radiance ρ/π · E = ρ·L_sky;
 *   3. the Cornell box rendered with 1 and 2 threads is bit-identical (counter-based RNG).
 */
#include "test_util.h"

#include "test_render_util.h"

#include <stdio.h>
#include <string.h>

static void test_furnace(void)
{
    test_write_file(IC_TEST_TMP "/furnace.mtl", "newmtl glow\nKd 0.5 0.5 0.5\nKe 0.5 0.5 0.5\n");
    test_write_inward_sphere(IC_TEST_TMP "/furnace.obj", "furnace.mtl", "glow", 1.0f, 48, 24);
    test_write_file(IC_TEST_TMP "/furnace.json",
               "{\n"
               "  \"camera\": {\"eye\": [0.1, 0.05, 0.02], \"target\": [1, 0.2, 0.3], \"up\": [0, 1, 0],\n"
               "             \"fov_y\": 90, \"width\": 24, \"height\": 24},\n"
               "  \"meshes\": [{\"path\": \"furnace.obj\"}]\n"
               "}\n");
    ic_render_options opt = {0};
    opt.spp = 64;
    opt.max_depth = 64;
    ic_image img = {0};
    CHECK(test_render(IC_TEST_TMP "/furnace.json", 0, 0, &opt, &img, NULL), "furnace renders");
    if (!img.rgb)
        return;
    int finite;
    double mean = test_image_mean(&img, &finite);
    CHECK(finite, "furnace: all pixels finite");
    /* Truncation at depth 64 costs 0.5^65: negligible. Noise: 36864 samples, σ per sample < 1. */
    CHECK_NEAR(mean, 1.0, 0.02, "furnace mean radiance (expected Le/(1-rho) = 1)");
    ic_image_free(&img);
}

static void test_open_plane(void)
{
    test_write_file(IC_TEST_TMP "/plane.mtl", "newmtl ground\nKd 0.5 0.5 0.5\n");
    test_write_file(IC_TEST_TMP "/plane.obj",
               "mtllib plane.mtl\nusemtl ground\n"
               "v -1000 0 -1000\nv 1000 0 -1000\nv 1000 0 1000\nv -1000 0 1000\n"
               "f 1 3 2\nf 1 4 3\n");
    test_write_file(IC_TEST_TMP "/plane.json",
               "{\n"
               "  \"camera\": {\"eye\": [0, 1, 0], \"target\": [0, 0, 0.001], \"up\": [0, 0, -1],\n"
               "             \"fov_y\": 60, \"width\": 24, \"height\": 24},\n"
               "  \"meshes\": [{\"path\": \"plane.obj\"}],\n"
               "  \"environment\": {\"radiance\": [2, 2, 2]}\n"
               "}\n");
    ic_render_options opt = {0};
    opt.spp = 64;
    ic_image img = {0};
    CHECK(test_render(IC_TEST_TMP "/plane.json", 0, 0, &opt, &img, NULL), "open plane renders");
    if (!img.rgb)
        return;
    int finite;
    double mean = test_image_mean(&img, &finite);
    CHECK(finite, "open plane: all pixels finite");
    /* E = pi * L_sky = 2 pi; radiance = rho/pi * E = 0.5 * 2 = 1. */
    CHECK_NEAR(mean, 1.0, 0.02, "open plane radiance (expected rho * L_sky = 1)");
    ic_image_free(&img);
    /* The cache with record noise control: every hemisphere ray sees the sky, so each record's σ is
     * zero and it needs no second set (a zero σ once asked for none at all, and scaled σ by 1/√0). */
    opt.integrator = IC_INTEGRATOR_IC;
    opt.spp = 8;
    opt.ic.record_sets = 4;
    CHECK(test_render(IC_TEST_TMP "/plane.json", 0, 0, &opt, &img, NULL), "open plane renders with the cache and "
          "--record-sets 4");
    if (!img.rgb)
        return;
    mean = test_image_mean(&img, &finite);
    CHECK(finite, "open plane, cache: all pixels finite");
    CHECK_NEAR(mean, 1.0, 0.02, "open plane radiance with the cache (expected rho * L_sky = 1)");
    ic_image_free(&img);
}

static void test_thread_independence(void)
{
    ic_render_options opt = {0};
    opt.spp = 4;
    ic_image a = {0}, b = {0};
    ic_error err = {0};
    ic_scene *scene = NULL;
    ic_scene_load_options lo = {0};
    lo.width = 64;
    lo.height = 64;
    if (ic_scene_load(IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json", &lo, &scene, &err) != IC_OK) {
        CHECK(0, "cornell box loads: %s", err.message);
        return;
    }
    opt.threads = 1;
    CHECK(ic_render(scene, &opt, &a, NULL, &err) == IC_OK, "1 thread: %s", err.message);
    opt.threads = 2;
    CHECK(ic_render(scene, &opt, &b, NULL, &err) == IC_OK, "2 threads: %s", err.message);
    CHECK(a.rgb && b.rgb && memcmp(a.rgb, b.rgb, sizeof(float) * 3 * 64 * 64) == 0,
          "1 and 2 threads give bit-identical images");
    int finite;
    double mean = a.rgb ? test_image_mean(&a, &finite) : 0.0;
    CHECK(mean > 0.05, "the Cornell box is lit (mean %g)", mean);
    ic_image_free(&a);
    ic_image_free(&b);
    ic_scene_free(scene);
}

int main(void)
{
    test_furnace();
    test_open_plane();
    test_thread_independence();
    TEST_MAIN_END();
}
