/*
 * test_scale.c — a scene and its copy scaled down render alike. Radiance does not depend on the unit of
 * length, so the Cornell box scaled by 1/100 and 1/1000 (camera with it) must give the image of the box at
 * its own size, within the renders' noise, with the path tracer and with the cache. Rays leave a surface
 * from an origin moved off it (Wächter & Binder's offset); near the origin of coordinates that move had a
 * fixed floor of 1/65536, so in a box 2 cm across the floor's shadow rays ended on the lamp's own surface
 * and the lamp's surroundings took 15 µm moves in a 100 µm gap: the image lost 11-16 % of its light.
 */
#include "test_render_util.h"
#include "test_util.h"

#include <stdio.h>

#define CORNELL_DIR IC_SOURCE_DIR "/scenes/cornell-box/"

/* Copies the box's OBJ and MTL next to the scaled scenes (a scene reads only files in its own folder). */
static int copy_file(const char *name)
{
    char from[512], to[512];
    snprintf(from, sizeof from, CORNELL_DIR "%s", name);
    snprintf(to, sizeof to, IC_TEST_TMP "/%s", name);
    FILE *in = fopen(from, "rb"), *out = in ? fopen(to, "wb") : NULL;
    char buf[4096];
    size_t n;
    int ok = in && out;
    while (ok && (n = fread(buf, 1, sizeof buf, in)) > 0)
        ok = fwrite(buf, 1, n, out) == n;
    if (in)
        fclose(in);
    if (out && fclose(out) != 0)
        ok = 0;
    return ok;
}

static void write_scaled(const char *path, double s)
{
    char json[1024];
    snprintf(json, sizeof json,
             "{\"camera\": {\"eye\": [0, %.9g, %.9g], \"target\": [0, %.9g, 0], \"up\": [0, 1, 0], \"fov_y\": 39.3,\n"
             "            \"width\": 32, \"height\": 32},\n"
             " \"meshes\": [{\"path\": \"CornellBox-Original.obj\", \"matrix\": [%.9g, 0, 0, 0, 0, %.9g, 0, 0, 0, 0, %.9g, 0, 0, 0, 0, 1]}]}\n",
             1.0 * s, 3.9 * s, 1.0 * s, s, s, s);
    test_write_file(path, json);
}

int main(void)
{
    CHECK(copy_file("CornellBox-Original.obj") && copy_file("CornellBox-Original.mtl"), "the box's files copied");
    static const double scales[] = {1.0, 0.01, 0.001};
    static const struct {
        const char *name;
        int integrator, spp;
    } kinds[] = {{"path tracer", IC_INTEGRATOR_PT, 64}, {"cache", IC_INTEGRATOR_IC, 16}};
    for (size_t k = 0; k < sizeof kinds / sizeof kinds[0]; ++k) {
        double mean[3] = {0, 0, 0};
        for (size_t i = 0; i < sizeof scales / sizeof scales[0]; ++i) {
            char path[512];
            snprintf(path, sizeof path, IC_TEST_TMP "/scaled-%zu.json", i);
            write_scaled(path, scales[i]);
            ic_render_options o = test_seeded_options(kinds[k].spp, 2, 5);
            o.integrator = kinds[k].integrator;
            ic_image img = {0};
            int finite = 0;
            CHECK(test_render(path, 32, 32, &o, &img, NULL), "%s at scale %g renders", kinds[k].name, scales[i]);
            mean[i] = test_image_mean(&img, &finite);
            CHECK(finite, "%s at scale %g: finite", kinds[k].name, scales[i]);
            ic_image_free(&img);
        }
        printf("%s: image mean %.5f at scale 1, %.5f at 1/100, %.5f at 1/1000\n", kinds[k].name, mean[0], mean[1],
               mean[2]);
        for (size_t i = 1; i < sizeof scales / sizeof scales[0]; ++i)
            CHECK(fabs(mean[i] / mean[0] - 1.0) < 0.01, "%s: the box at scale %g has the mean of the box at scale 1 "
                  "(%.5f against %.5f)", kinds[k].name, scales[i], mean[i], mean[0]);
    }
    TEST_MAIN_END();
}
