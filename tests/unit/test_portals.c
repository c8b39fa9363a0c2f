/*
 * test_portals.c — sampling the environment through portals (docs/scene-format.md, "Portals").
 *
 * - Under a 2 × 1 portal, 1.5 above a receiver under its corner, a constant sky L gives through it
 *   π L F with F the point-to-parallel-rectangle form factor: portal sampling's estimate matches.
 * - A rectangle (solid-angle sampling) beside a skewed parallelogram (area sampling): the sampler's pdf
 *   is ic_scene_portal_pdf's and integrates to 1 from three points.
 * - Every sample's pdf is what ic_scene_portal_pdf returns for its direction, the pdf integrates to 1
 *   over the sphere, it is 0 along directions through no portal, and ic_scene_light_pdf_env_at agrees
 *   with the light sampler's pdf.
 * - A point outside every portal (above it) samples the sky as if there were none.
 * - The path tracer stays unbiased: under an open sky a sensor still gets E = π L (the directions
 *   through no portal come from BSDF sampling under MIS); in the sky-room (two windows) direct light
 *   through portals has the same mean as without them and several times less noise.
 * - Bad portals (three corners, not a parallelogram, degenerate, not an array) are refused with the
 *   scene file's line; a portal 1e12 across (|e1 × e2|² beyond a float) is not degenerate.
 */
#include "core/sampling.h"
#include "irrcache/points.h"
#include "scene/scene.h"
#include "test_files.h"
#include "test_util.h"

#include <stdint.h>
#include <string.h>

#define PI 3.14159265358979323846

static float rnd(uint64_t *s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return (float)((*s * 2685821657736338717ULL) >> 40) * (1.0f / 16777216.0f);
}

/* Loads a scene written from text (its mesh lives in tests/scenes: outside paths allowed); NULL and the
 * message in err on failure. */
static ic_scene *load_text(const char *name, const char *text, ic_error *err)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s", IC_TEST_TMP, name);
    if (!test_write_text(path, text))
        return NULL;
    ic_scene_load_options opt = {0};
    opt.allow_outside_paths = 1;
    ic_scene *s = NULL;
    return ic_scene_load(path, &opt, &s, err) == IC_OK ? s : NULL;
}

/* Point-to-parallel-rectangle form factor, receiver under a corner of an a × b rectangle at height c. */
static double form_factor_corner(double a, double b, double c)
{
    double A = a / c, B = b / c, sa = sqrt(1 + A * A), sb = sqrt(1 + B * B);
    return (A / sa * atan(B / sa) + B / sb * atan(A / sb)) / (2 * PI);
}

/* A constant sky of radiance 2, a portal 2 × 1 at y = 1.5 over [0, 2] × [0, 1] whose corners go +x then
 * +z (normal −y: the interior is below), and a small quad far away so that the scene has a mesh. */
#define OPEN_SCENE                                                                                        \
    "{\n \"meshes\": [{\"path\": \"" IC_SOURCE_DIR "/tests/scenes/plain_quad.obj\",\n"                    \
    "   \"transform\": {\"translate\": [50, -20, 50]}}],\n"                                             \
    " \"environment\": {\"radiance\": [2, 2, 2],\n"                                                      \
    "   \"portals\": [[[0, 1.5, 0], [2, 1.5, 0], [2, 1.5, 1], [0, 1.5, 1]]]}\n}\n"

static void test_sampling(void)
{
    ic_error err = {0};
    ic_scene *s = load_text("portal_open.json", OPEN_SCENE, &err);
    CHECK(s != NULL, "portal scene loads: %s", err.message);
    if (!s)
        return;
    CHECK(s->env.portal_count == 1 && fabsf(s->env.portal_area - 2.0f) < 1e-5f && s->env.portals[0].normal.y < -0.99f,
          "one portal of area 2 facing down (%u, %g)", s->env.portal_count, (double)s->env.portal_area);
    const ic_vec3 p = v3(0.0f, 0.0f, 0.0f), n = v3(0.0f, 1.0f, 0.0f);
    CHECK(ic_scene_portals_apply(s, p) && !ic_scene_portals_apply(s, v3(0.5f, 3.0f, 0.5f)), "inside below, outside above");
    uint64_t st = 0x9e3779b97f4a7c15ULL;
    const int N = 400000;
    double sum = 0.0;
    int pdf_bad = 0, failed = 0;
    for (int i = 0; i < N; ++i) {
        ic_vec3 wi, q;
        float pdf;
        if (!ic_scene_sample_portal(s, p, rnd(&st), rnd(&st), rnd(&st), &wi, &q, &pdf)) {
            ++failed;
            continue;
        }
        pdf_bad += fabsf(pdf - ic_scene_portal_pdf(s, p, wi)) > 1e-4f * pdf;
        sum += 2.0 * fmax(v3_dot(wi, n), 0.0) / pdf;
    }
    double want = PI * 2.0 * form_factor_corner(2.0, 1.0, 1.5), got = sum / N;
    printf("portal under a corner: E %.5f, form factor gives %.5f\n", got, want);
    CHECK(failed == 0, "%d samples failed", failed);
    CHECK(pdf_bad == 0, "%d samples' pdf differs from ic_scene_portal_pdf", pdf_bad);
    CHECK(fabs(got - want) < 0.005 * want, "E through the portal %.5f, expected %.5f", got, want);
    /* The pdf integrates to 1 over the sphere (uniform directions); 0 through no portal. */
    double integral = 0.0;
    int outside_bad = 0;
    const int M = 400000;
    for (int i = 0; i < M; ++i) {
        ic_vec3 d = ic_warp_uniform_sphere(rnd(&st), rnd(&st));
        float pdf = ic_scene_portal_pdf(s, p, d);
        integral += pdf * 4.0 * PI / M;
        outside_bad += d.y <= 0.0f && pdf != 0.0f;
    }
    CHECK(fabs(integral - 1.0) < 0.02, "portal pdf integrates to %.4f over the sphere", integral);
    CHECK(outside_bad == 0, "%d downward directions with a portal pdf", outside_bad);
    /* The light sampler: through the portal below it, over the sphere above it. */
    int light_bad = 0, through = 0;
    for (int i = 0; i < 10000; ++i) {
        ic_vec3 at = i % 2 ? p : v3(0.5f, 3.0f, 0.5f);
        ic_light_sample ls;
        if (!ic_scene_sample_light(s, at, rnd(&st), rnd(&st), rnd(&st), &ls))
            continue;
        light_bad += fabsf(ls.pdf - ic_scene_light_pdf_env_at(s, at, ls.wi)) > 1e-4f * ls.pdf;
        through += i % 2 && ic_scene_portal_pdf(s, at, ls.wi) > 0.0f;
    }
    CHECK(light_bad == 0, "%d light samples whose pdf differs from ic_scene_light_pdf_env_at", light_bad);
    CHECK(through == 5000, "from inside, every light sample goes through the portal (%d of 5000)", through);
    CHECK(fabsf(ic_scene_light_pdf_env_at(s, v3(0.5f, 3.0f, 0.5f), n) - 1.0f / (4.0f * (float)PI)) < 1e-6f,
          "above the portal, the sphere's pdf");
    /* MIS keeps the path tracer unbiased: an open sky still gives π L to a sensor under the portal. */
    ic_sensor_point sp = {v3(1.0f, 0.0f, 0.5f), n};
    ic_points_options po = {0};
    po.integrator = IC_INTEGRATOR_PT;
    po.samples = 65536;
    po.threads = 2;
    ic_point_result res;
    CHECK(ic_points_compute(s, &sp, 1, &po, &res, NULL, &err) == IC_OK, "points: %s", err.message);
    printf("open sky with a portal: E %.5f +- %.5f, expected %.5f\n", (double)res.irradiance.y,
           (double)res.irradiance_sigma.y, 2.0 * PI);
    CHECK(fabs(res.irradiance.y - 2.0 * PI) < fmax(3.0 * res.irradiance_sigma.y, 1e-3) &&
              fabs(res.irradiance.y - 2.0 * PI) < 0.01 * 2.0 * PI,
          "open sky through MIS: E %.5f +- %.5f, expected %.5f", (double)res.irradiance.y,
          (double)res.irradiance_sigma.y, 2.0 * PI);
    ic_scene_free(s);
}

/* A rectangle (sampled by solid angle) beside a skewed parallelogram (sampled by area): from points
 * below both, every sample's pdf is ic_scene_portal_pdf's, and the pdf integrates to 1. */
static void test_mixed_portals(void)
{
    ic_error err = {0};
    ic_scene *s = load_text("portal_mixed.json",
                            "{\n \"meshes\": [{\"path\": \"" IC_SOURCE_DIR "/tests/scenes/plain_quad.obj\",\n"
                            "   \"transform\": {\"translate\": [50, -20, 50]}}],\n"
                            " \"environment\": {\"radiance\": [1, 1, 1], \"portals\": [\n"
                            "   [[0, 1.5, 0], [2, 1.5, 0], [2, 1.5, 1], [0, 1.5, 1]],\n"
                            "   [[3, 2, 0], [5, 2, 0], [5.5, 2, 1], [3.5, 2, 1]]]}\n}\n",
                            &err);
    CHECK(s != NULL, "mixed portals load: %s", err.message);
    if (!s)
        return;
    CHECK(s->env.portal_count == 2 && s->env.portals[0].rectangle && !s->env.portals[1].rectangle,
          "a rectangle and a skewed parallelogram");
    uint64_t st = 0x243f6a8885a308d3ULL;
    const ic_vec3 at[3] = {v3(1.0f, 0.0f, 0.5f), v3(4.0f, 0.5f, 0.2f), v3(2.5f, 1.4f, 0.5f)};
    for (int i = 0; i < 3; ++i) {
        int pdf_bad = 0, n = 0;
        for (int k = 0; k < 100000; ++k) {
            ic_vec3 wi, q;
            float pdf;
            if (!ic_scene_sample_portal(s, at[i], rnd(&st), rnd(&st), rnd(&st), &wi, &q, &pdf))
                continue;
            ++n;
            pdf_bad += fabsf(pdf - ic_scene_portal_pdf(s, at[i], wi)) > 2e-3f * pdf;
        }
        double integral = 0.0;
        const int M = 400000;
        for (int k = 0; k < M; ++k)
            integral += ic_scene_portal_pdf(s, at[i], ic_warp_uniform_sphere(rnd(&st), rnd(&st))) * 4.0 * PI / M;
        printf("mixed portals, point %d: %d samples, pdf integral %.4f\n", i, n, integral);
        CHECK(n > 99000 && pdf_bad == 0, "point %d: %d samples, %d with another pdf than ic_scene_portal_pdf", i, n,
              pdf_bad);
        CHECK(fabs(integral - 1.0) < 0.02, "point %d: the pdf integrates to %.4f", i, integral);
    }
    ic_scene_free(s);
}

/* The sky-room's direct light (max depth 1) at four sensors, with and without its portals. */
static void test_sky_room(void)
{
    static const char *const scenes[2] = {IC_SOURCE_DIR "/scenes/interiors/sky-room-overcast.json",
                                          "sky_room_no_portals"};
    ic_error err = {0};
    ic_scene_load_options lo = {0};
    ic_scene *with = NULL, *without = NULL;
    CHECK(ic_scene_load(scenes[0], &lo, &with, &err) == IC_OK, "%s: %s", scenes[0], err.message);
    if (!with)
        return;
    CHECK(with->env.portal_count == 2, "the sky-room declares its two windows (%u portals)", with->env.portal_count);
    CHECK(ic_scene_load(scenes[0], &lo, &without, &err) == IC_OK, "%s: %s", scenes[0], err.message);
    if (!without) {
        ic_scene_free(with);
        return;
    }
    without->env.portal_count = 0; /* the same scene sampled over the whole sphere */
    without->light_select = with->light_select;
    ic_sensor_point sp[4] = {{v3(1.0f, 0.8f, 1.0f), v3(0, 1, 0)},
                             {v3(3.5f, 0.8f, 2.0f), v3(0, 1, 0)},
                             {v3(2.5f, 1.2f, 3.9f), v3(0, 0, -1)},
                             {v3(4.5f, 0.8f, 3.5f), v3(0, 1, 0)}};
    ic_points_options po = {0};
    po.integrator = IC_INTEGRATOR_PT;
    po.samples = 8192;
    po.max_depth = 1;
    po.threads = 2;
    ic_point_result a[4], b[4];
    CHECK(ic_points_compute(with, sp, 4, &po, a, NULL, &err) == IC_OK, "with portals: %s", err.message);
    CHECK(ic_points_compute(without, sp, 4, &po, b, NULL, &err) == IC_OK, "without: %s", err.message);
    double ratio = 0.0;
    for (int i = 0; i < 4; ++i) {
        double s = sqrt(a[i].illuminance_sigma * a[i].illuminance_sigma + b[i].illuminance_sigma * b[i].illuminance_sigma);
        printf("sky-room sensor %d: with portals %.1f +- %.1f lux, without %.1f +- %.1f\n", i, a[i].illuminance,
               a[i].illuminance_sigma, b[i].illuminance, b[i].illuminance_sigma);
        CHECK(fabs(a[i].illuminance - b[i].illuminance) < 4.0 * s, "sensor %d: %.1f and %.1f differ by more than 4 sigma",
              i, a[i].illuminance, b[i].illuminance);
        ratio += b[i].illuminance_sigma / a[i].illuminance_sigma / 4.0;
    }
    printf("sky-room: sigma without portals / with, mean %.2f\n", ratio);
    CHECK(ratio > 2.0, "portals cut the direct light's noise by %.2f only", ratio);
    without->env.portal_count = with->env.portal_count;
    ic_scene_free(with);
    ic_scene_free(without);
}

static void expect_refusal(const char *name, const char *portals, const char *words)
{
    static char text[64 * (IC_MAX_PORTALS + 2) + 1024];
    snprintf(text, sizeof text,
             "{\n \"meshes\": [{\"path\": \"" IC_SOURCE_DIR "/tests/scenes/plain_quad.obj\"}],\n"
             " \"environment\": {\"radiance\": [1, 1, 1],\n   \"portals\": %s}\n}\n",
             portals);
    ic_error err = {0};
    ic_scene *s = load_text(name, text, &err);
    CHECK(s == NULL && strstr(err.message, name) && strstr(err.message, ":4:") && strstr(err.message, words),
          "%s refused with its line and '%s': %s", name, words, err.message);
    ic_scene_free(s);
}

static void test_bad_portals(void)
{
    expect_refusal("portal_three.json", "[[[0, 1, 0], [1, 1, 0], [1, 1, 1]]]", "four corners");
    expect_refusal("portal_skew.json", "[[[0, 1, 0], [1, 1, 0], [1.5, 1, 1], [0, 1, 1]]]", "parallelogram");
    expect_refusal("portal_flat.json", "[[[0, 1, 0], [1, 1, 0], [2, 1, 0], [1, 1, 0]]]", "degenerate");
    expect_refusal("portal_object.json", "{\"corner\": [0, 0, 0]}", "non-empty array");
    expect_refusal("portal_nan.json", "[[[0, 1, 0], [1, 1, 0], [1, 1, 1], [0, 1, \"x\"]]]",
                   "portal 1, corner 4 is not [x, y, z]");
    expect_refusal("portal_2d.json", "[[[0, 1, 0], [1, 1], [1, 1, 1], [0, 1, 1]]]", "portal 1, corner 2 is not [x, y, z]");
    /* One more than the limit, each a unit square along x. */
    static char many[64 * (IC_MAX_PORTALS + 1) + 8];
    size_t len = 0;
    many[len++] = '[';
    for (int k = 0; k <= IC_MAX_PORTALS; ++k)
        len += (size_t)snprintf(many + len, sizeof many - len, "%s[[%d, 1, 0], [%d, 1, 0], [%d, 1, 1], [%d, 1, 1]]",
                                k ? ", " : "", 2 * k, 2 * k + 1, 2 * k + 1, 2 * k);
    snprintf(many + len, sizeof many - len, "]");
    expect_refusal("portal_many.json", many, "more than 256 portals");
}

/* A directional sun in the plane of every portal (here straight up, windows vertical) meets the openings
 * edge-on; it must keep a share of the light samples all the same: a delta light has no other way in,
 * and it lights the points outside the portals at full strength. */
static void test_sun_in_portal_plane(void)
{
    ic_error err = {0};
    ic_scene *s = load_text("portal_sun.json",
                            "{\n \"meshes\": [{\"path\": \"" IC_SOURCE_DIR "/tests/scenes/plain_quad.obj\"}],\n"
                            " \"lights\": [{\"type\": \"sun\", \"direction\": [0, 1, 0], \"irradiance\": [100, 100, 100]}],\n"
                            " \"environment\": {\"radiance\": [1, 1, 1],\n"
                            "   \"portals\": [[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]]}\n}\n",
                            &err);
    CHECK(s != NULL, "sun and a vertical portal load: %s", err.message);
    if (!s)
        return;
    CHECK(s->sun.enabled && s->light_select.sun > 0.0f, "the sun keeps a share of the light samples: %g",
          (double)s->light_select.sun);
    ic_scene_free(s);
}

/* A portal 1e12 across: |e1 × e2|² overflows a float, and it was refused as degenerate; its area and unit
 * normal (−y: corners +x then +z) are those of the double-precision cross product. */
static void test_big_portal(void)
{
    ic_error err = {0};
    ic_scene *s = load_text("portal_big.json",
                            "{\n \"meshes\": [{\"path\": \"" IC_SOURCE_DIR "/tests/scenes/plain_quad.obj\"}],\n"
                            " \"environment\": {\"radiance\": [1, 1, 1],\n"
                            "   \"portals\": [[[0, 3, 0], [2e12, 3, 0], [2e12, 3, 1e12], [0, 3, 1e12]]]}\n}\n",
                            &err);
    CHECK(s != NULL, "a 2e12 x 1e12 portal loads: %s", err.message);
    if (!s)
        return;
    const ic_portal *pt = &s->env.portals[0];
    CHECK(s->env.portal_count == 1 && fabs(pt->area / 2e24 - 1.0) < 1e-6, "its area %g (2e24)", (double)pt->area);
    CHECK(pt->normal.x == 0.0f && pt->normal.y == -1.0f && pt->normal.z == 0.0f, "its normal (%g %g %g)",
          (double)pt->normal.x, (double)pt->normal.y, (double)pt->normal.z);
    ic_scene_free(s);
}

int main(void)
{
    test_sun_in_portal_plane();
    test_sampling();
    test_mixed_portals();
    test_sky_room();
    test_bad_portals();
    test_big_portal();
    TEST_MAIN_END();
}
