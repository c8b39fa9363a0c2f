/*
 * test_microfacet_render.c — the rough materials rendered, path tracer and irradiance cache, on an open
 * plane under a uniform sky of radiance L (every direction above the plane sees L):
 *   1. a rough plastic with a white base is a white furnace: every pixel is L, for both integrators;
 *   2. a smooth conductor with F0 = 1 returns nearly L (the single-scattering loss of α = 0.05 is < 2 %),
 *      and so does a sheet of rough glass (reflected plus transmitted);
 *   3. a coloured rough plastic and a coloured rough conductor: the cache's final render (diffuse lobe
 *      from the records, glossy lobe sampled) agrees with the path tracer within the noise.
 */
#include "test_util.h"

#include "test_render_util.h"

#include <stdio.h>
#include <string.h>

/* Renders the plane with material `json` as ground, by integrator `integ`; returns the mean of channel
 * c (0..2), or -1 if it failed. */
static double render_plane(const char *name, const char *json, ic_integrator integ, int c)
{
    char scene[4096], path[512];
    test_write_file(IC_TEST_TMP "/mf_plane.mtl", "newmtl ground\nKd 0.5 0.5 0.5\n");
    test_write_file(IC_TEST_TMP "/mf_plane.obj", "mtllib mf_plane.mtl\nusemtl ground\n"
                                                 "v -1000 0 -1000\nv 1000 0 -1000\nv 1000 0 1000\nv -1000 0 1000\n"
                                                 "f 1 3 2\nf 1 4 3\n");
    snprintf(scene, sizeof scene,
             "{\n"
             "  \"camera\": {\"eye\": [0, 1, 0], \"target\": [0, 0, 1.2], \"up\": [0, 1, 0],\n"
             "             \"fov_y\": 60, \"width\": 24, \"height\": 24},\n"
             "  \"meshes\": [{\"path\": \"mf_plane.obj\"}],\n"
             "  \"materials\": {\"ground\": %s},\n"
             "  \"environment\": {\"radiance\": [2, 2, 2]}\n"
             "}\n",
             json);
    snprintf(path, sizeof path, IC_TEST_TMP "/mf_%s.json", name);
    test_write_file(path, scene);
    ic_render_options opt = {0};
    opt.integrator = integ;
    opt.spp = 64;
    opt.threads = 2;
    ic_image img = {0};
    if (!test_render(path, 0, 0, &opt, &img, NULL))
        return -1.0;
    double sum = 0.0;
    int finite = 1;
    /* the lower half of the image: the plane (the upper half sees the sky) */
    for (int y = img.height / 2 + 1; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) {
            float v = img.rgb[3 * ((size_t)y * img.width + x) + c];
            finite &= isfinite(v) != 0;
            sum += v;
        }
    int n = (img.height - img.height / 2 - 1) * img.width;
    ic_image_free(&img);
    CHECK(finite, "%s: all pixels finite", name);
    if (getenv("IC_TEST_VERBOSE"))
        printf("%s %d ch%d: %.5f\n", name, (int)integ, c, sum / n);
    return sum / n;
}

int main(void)
{
    static const ic_integrator integ[2] = {IC_INTEGRATOR_PT, IC_INTEGRATOR_IC};
    static const char *iname[2] = {"path tracer", "cache"};
    const char *white = "{\"type\": \"plastic\", \"kd\": 1, \"alpha\": 0.3}";
    const char *mirror = "{\"type\": \"conductor\", \"ks\": 1, \"alpha\": 0.05}";
    const char *glass = "{\"type\": \"rough_glass\", \"alpha\": 0.05, \"ior\": 1.5}";
    for (int i = 0; i < 2; ++i) {
        double m = render_plane("white", white, integ[i], 1);
        CHECK(fabs(m - 2.0) < 0.03, "%s: white rough plastic under L = 2 gives %g (expected 2)", iname[i], m);
        m = render_plane("mirror", mirror, integ[i], 1);
        CHECK(m > 0.98 * 2.0 && m < 2.0 + 0.01, "%s: smooth F0 = 1 conductor gives %g (expected just under 2)",
              iname[i], m);
        m = render_plane("glass", glass, integ[i], 1);
        CHECK(m > 0.98 * 2.0 && m < 2.0 + 0.01, "%s: a sheet of rough glass (alpha 0.05) in the uniform sky gives %g "
              "(expected just under 2: what it reflects and what it lets through)", iname[i], m);
    }
    const char *coloured[2] = {"{\"type\": \"plastic\", \"kd\": [0.7, 0.3, 0.1], \"alpha\": 0.2, \"ior\": 1.6}",
                               "{\"type\": \"conductor\", \"eta\": [0.2, 0.9, 1.1], \"k\": [3.9, 2.4, 2.2], "
                               "\"alpha\": 0.4}"};
    for (int k = 0; k < 2; ++k)
        for (int c = 0; c < 3; ++c) {
            double pt = render_plane("coloured", coloured[k], IC_INTEGRATOR_PT, c);
            double ic = render_plane("coloured", coloured[k], IC_INTEGRATOR_IC, c);
            CHECK(pt > 0.0 && fabs(ic - pt) < 0.02 * pt + 0.005, "%s channel %d: cache %g vs path tracer %g",
                  k ? "conductor" : "plastic", c, ic, pt);
        }
    TEST_MAIN_END();
}
