/*
 * test_daylight.c — daylight factors (ic_points_daylight_reference, irrcache/points.h):
 *   1. the reference is 179 × 7π/9 × L_z for a CIE overcast sky; an unobstructed horizontal point on an open
 *      plane has a daylight factor of 100 % within its σ;
 *   2. a room with two windows under the overcast sky (scenes/interiors/sky-room-overcast.json): on a 5 × 3
 *      work-plane grid at 0.8 m the cache's daylight factors agree with a brute-force path-traced reference
 *      (16 384 paths per point): within 2 combined σ at 80 % of the points or more, within 3.5 σ at all,
 *      and all between 1 % and 30 % (a side-lit room);
 *   3. scenes without a CIE overcast sky, or with other lights, are refused.
 */
#include "test_util.h"

#include "test_render_util.h"

#include "irrcache/points.h"

#include <string.h>

#define PI_D 3.14159265358979323846

static ic_scene *load(const char *path, ic_error *err)
{
    ic_scene *scene = NULL;
    ic_scene_load_options lo = {0};
    lo.width = 16;
    lo.height = 16;
    if (ic_scene_load(path, &lo, &scene, err) != IC_OK)
        return NULL;
    return scene;
}

static void test_unobstructed(void)
{
    test_write_file(IC_TEST_TMP "/daylight_plane.mtl", "newmtl ground\nKd 0.2 0.2 0.2\n");
    test_write_file(IC_TEST_TMP "/daylight_plane.obj", "mtllib daylight_plane.mtl\nusemtl ground\n"
                                                       "v -1000 0 -1000\nv 1000 0 -1000\nv 1000 0 1000\n"
                                                       "v -1000 0 1000\nf 1 3 2\nf 1 4 3\n");
    test_write_file(IC_TEST_TMP "/daylight_plane.json",
                    "{\"meshes\": [{\"path\": \"daylight_plane.obj\"}],\n"
                    " \"environment\": {\"sky\": \"cie-overcast\", \"zenith_luminance\": 7000}}\n");
    ic_error err = {0};
    ic_scene *s = load(IC_TEST_TMP "/daylight_plane.json", &err);
    CHECK(s != NULL, "open plane loads: %s", err.message);
    if (!s)
        return;
    double ref = 0.0;
    CHECK(ic_points_daylight_reference(s, &ref, &err) == IC_OK, "reference: %s", err.message);
    CHECK_NEAR(ref, 7.0 * PI_D / 9.0 * 7000.0, 1e-6 * ref, "reference = 7 pi/9 L_z (lux)");
    ic_sensor_point pt = {{3.0f, 0.8f, -2.0f}, {0.0f, 1.0f, 0.0f}};
    ic_points_options opt = {0};
    opt.samples = 4096;
    ic_point_result r;
    CHECK(ic_points_compute(s, &pt, 1, &opt, &r, NULL, &err) == IC_OK, "computes: %s", err.message);
    double df = 100.0 * r.illuminance / ref, sigma = 100.0 * r.illuminance_sigma / ref;
    printf("unobstructed: DF %.4f %% +- %.4f\n", df, sigma);
    CHECK(fabs(df - 100.0) <= 3.0 * sigma + 0.05, "unobstructed DF = 100 %%");
    ic_scene_free(s);
}

static void test_room(void)
{
    ic_error err = {0};
    ic_scene *s = load(IC_SOURCE_DIR "/scenes/interiors/sky-room-overcast.json", &err);
    CHECK(s != NULL, "sky-room-overcast loads: %s", err.message);
    if (!s)
        return;
    double ref = 0.0;
    CHECK(ic_points_daylight_reference(s, &ref, &err) == IC_OK, "reference: %s", err.message);
    enum { NX = 5, NZ = 3, N = NX * NZ };
    ic_sensor_point pts[N];
    for (int k = 0; k < N; ++k) {
        pts[k].position = (ic_vec3){0.5f + (float)(k % NX), 0.8f, 0.5f + (float)(k / NX)};
        pts[k].normal = (ic_vec3){0.0f, 1.0f, 0.0f};
    }
    ic_point_result ic[N], pt[N];
    ic_points_options o_ic = {0}, o_pt = {0};
    o_ic.integrator = IC_INTEGRATOR_IC;
    o_pt.integrator = IC_INTEGRATOR_PT;
    o_pt.samples = 16384;
    CHECK(ic_points_compute(s, pts, N, &o_ic, ic, NULL, &err) == IC_OK, "ic: %s", err.message);
    CHECK(ic_points_compute(s, pts, N, &o_pt, pt, NULL, &err) == IC_OK, "pt: %s", err.message);
    int within2 = 0, within35 = 0, plausible = 0;
    for (int k = 0; k < N; ++k) {
        double a = 100.0 * ic[k].illuminance / ref, b = 100.0 * pt[k].illuminance / ref;
        double sa = 100.0 * ic[k].illuminance_sigma / ref, sb = 100.0 * pt[k].illuminance_sigma / ref;
        double z = fabs(a - b) / sqrt(sa * sa + sb * sb);
        printf("(%.1f, %.1f): DF cache %.3f +- %.3f %%, path traced %.3f +- %.3f %% (%.2f sigma)\n",
               (double)pts[k].position.x, (double)pts[k].position.z, a, sa, b, sb, z);
        within2 += z <= 2.0;
        within35 += z <= 3.5;
        plausible += b > 1.0 && b < 30.0;
    }
    CHECK(within2 >= (int)(0.8 * N), "cache within 2 sigma of the reference at %d of %d points", within2, N);
    CHECK(within35 == N, "cache within 3.5 sigma everywhere (%d of %d)", within35, N);
    CHECK(plausible == N, "side-lit room: DF between 1 and 30 %% (%d of %d)", plausible, N);
    ic_scene_free(s);
}

static void test_refused(void)
{
    ic_error err = {0};
    double ref = 0.0;
    ic_scene *s = load(IC_SOURCE_DIR "/scenes/interiors/sky-room.json", &err);
    CHECK(s != NULL, "sky-room loads: %s", err.message);
    if (s) {
        CHECK(ic_points_daylight_reference(s, &ref, &err) == IC_ERR_INVALID_ARG && strstr(err.message, "overcast"),
              "a constant sky is refused: %s", err.message);
        ic_scene_free(s);
    }
    test_write_file(IC_TEST_TMP "/daylight_sun.json",
                    "{\"meshes\": [{\"path\": \"daylight_plane.obj\"}],\n"
                    " \"lights\": [{\"type\": \"sun\", \"direction\": [0, 1, 1], \"irradiance\": 100}],\n"
                    " \"environment\": {\"sky\": \"cie-overcast\", \"zenith_luminance\": 7000}}\n");
    s = load(IC_TEST_TMP "/daylight_sun.json", &err);
    CHECK(s != NULL, "overcast with a sun loads: %s", err.message);
    if (s) {
        CHECK(ic_points_daylight_reference(s, &ref, &err) == IC_ERR_INVALID_ARG && strstr(err.message, "alone"),
              "another light is refused: %s", err.message);
        ic_scene_free(s);
    }
}

int main(void)
{
    test_unobstructed();
    test_room();
    test_refused();
    TEST_MAIN_END();
}
