/*
 * test_lights.c — light sampling against analytic answers and against its own pdfs.
 *
 * - Irradiance below a rectangular emitter (parallel, receiver under its centre) estimated with
 *   ic_scene_sample_light matches the point-to-rectangle form factor; for a tilted receiver it matches
 *   brute-force cosine-hemisphere sampling; the back of a one-sided emitter gives nothing.
 * - For every sample, ic_scene_light_pdf_triangle / ic_scene_light_pdf_env return the sampler's pdf,
 *   and light classes are picked with the documented probabilities, also in a scene near the largest
 *   coordinate, where the classes' weights leave a float.
 * - A local light distribution (ic_scene_local_lights) is a distribution, keeps every emitter's defensive
 *   share, agrees with its pdf, gives the same irradiance as selection by power, and less variance.
 * - An environment image: its pdf integrates to 1 over the sphere, importance sampling integrates the
 *   radiance to the same value as uniform sampling, and rotation_deg turns the map about +y.
 */
#include "core/sampling.h"
#include "irrcache/image.h"
#include "scene/scene.h"
#include "test_files.h"
#include "test_util.h"

#include <stdint.h>
#include <string.h>

#define SCENES IC_SOURCE_DIR "/tests/scenes/"

/* xorshift64* → [0, 1) */
static float rnd(uint64_t *s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return (float)((*s * 2685821657736338717ULL) >> 40) * (1.0f / 16777216.0f);
}

static ic_scene *load(const char *path)
{
    /* transformed.json names the Cornell box two folders up, and the scenes written into IC_TEST_TMP name
     * meshes in tests/scenes: outside their folders, so the option is given (test_scene_paths.c) */
    ic_scene_load_options opt = {0};
    opt.allow_outside_paths = 1;
    ic_scene *s = NULL;
    ic_error err = {0};
    ic_result r = ic_scene_load(path, &opt, &s, &err);
    CHECK(r == IC_OK, "%s: %s", path, err.message);
    return s;
}

/* Point-to-parallel-rectangle form factor, receiver under a corner of an a × b rectangle at height c. */
static double form_factor_corner(double a, double b, double c)
{
    double A = a / c, B = b / c, sa = sqrt(1 + A * A), sb = sqrt(1 + B * B);
    return (A / sa * atan(B / sa) + B / sb * atan(A / sb)) / (2 * 3.14159265358979323846);
}

/* Möller–Trumbore distance along d from o to triangle t, or -1. */
static float ray_triangle(const ic_scene *s, uint32_t t, ic_vec3 o, ic_vec3 d)
{
    ic_vec3 p0 = s->positions[s->triangles[3 * t]], p1 = s->positions[s->triangles[3 * t + 1]],
            p2 = s->positions[s->triangles[3 * t + 2]];
    ic_vec3 e1 = v3_sub(p1, p0), e2 = v3_sub(p2, p0), pv = v3_cross(d, e2);
    float det = v3_dot(e1, pv);
    if (fabsf(det) < 1e-12f)
        return -1.0f;
    ic_vec3 tv = v3_sub(o, p0);
    float u = v3_dot(tv, pv) / det;
    ic_vec3 qv = v3_cross(tv, e1);
    float v = v3_dot(d, qv) / det;
    if (u < -1e-4f || v < -1e-4f || u + v > 1.0001f)
        return -1.0f;
    return v3_dot(e2, qv) / det;
}

/* The emissive triangle the sample points at (distance matches), or UINT32_MAX. */
static uint32_t sampled_triangle(const ic_scene *s, ic_vec3 p, const ic_light_sample *ls)
{
    for (uint32_t i = 0; i < s->tri_light_count; ++i) {
        uint32_t t = s->tri_lights[i].triangle;
        float d = ray_triangle(s, t, p, ls->wi);
        if (d > 0.0f && fabsf(d - ls->dist) <= 1e-3f * ls->dist)
            return t;
    }
    return UINT32_MAX;
}

static void test_rectangle_irradiance(void)
{
    ic_scene *s = load(SCENES "quad_light.obj");
    if (!s)
        return;
    CHECK(s->tri_light_count == 2 && s->light_select.tri == 1.0f, "one quad light");
    const double L = 2.0; /* Ke 2 2 2 */
    uint64_t seed = 0x9e3779b97f4a7c15ULL;

    /* parallel: receiver at the origin facing up, emitter 1 × 0.5 at height 1 centred above */
    ic_vec3 p = v3(0, 0, 0), n = v3(0, 1, 0);
    double analytic = 3.14159265358979323846 * L * 4 * form_factor_corner(0.5, 0.25, 1.0);
    const int N = 200000;
    double sum = 0.0;
    int pdf_mismatch = 0, unmatched = 0, not_area = 0;
    for (int i = 0; i < N; ++i) {
        ic_light_sample ls;
        if (!ic_scene_sample_light(s, p, rnd(&seed), rnd(&seed), rnd(&seed), &ls))
            continue;
        not_area += ls.is_delta || !(ls.pdf > 0.0f);
        sum += ls.radiance.x * fmax(0.0, v3_dot(n, ls.wi)) / ls.pdf;
        uint32_t t = sampled_triangle(s, p, &ls);
        if (t == UINT32_MAX) {
            ++unmatched;
            continue;
        }
        float pdf = ic_scene_light_pdf_triangle(s, p, t, ls.wi, ls.dist);
        pdf_mismatch += fabsf(pdf - ls.pdf) > 1e-4f * ls.pdf;
    }
    CHECK_NEAR(sum / N, analytic, 0.005 * analytic, "irradiance under a parallel rectangle (form factor)");
    CHECK(unmatched == 0, "%d samples off the light", unmatched);
    CHECK(not_area == 0, "%d samples not from an area light", not_area);
    CHECK(pdf_mismatch == 0, "%d samples where pdf_triangle differs from the sampler", pdf_mismatch);

    /* tilted receiver off to the side: light sampling vs brute-force cosine-hemisphere sampling */
    p = v3(0.8f, 0.3f, 0.1f);
    n = v3_norm(v3(-1, 1, 0.3f));
    double est = 0.0;
    for (int i = 0; i < N; ++i) {
        ic_light_sample ls;
        if (ic_scene_sample_light(s, p, rnd(&seed), rnd(&seed), rnd(&seed), &ls))
            est += ls.radiance.x * fmax(0.0, v3_dot(n, ls.wi)) / ls.pdf;
    }
    est /= N;
    ic_frame f = ic_frame_from_normal(n);
    const int M = 2000000;
    long hits = 0;
    for (int i = 0; i < M; ++i) {
        ic_vec3 d = ic_frame_to_world(&f, ic_warp_cosine_hemisphere(rnd(&seed), rnd(&seed)));
        if (d.y <= 0.0f)
            continue; /* the emitter's front faces down: only upward rays see it */
        float t = (1.0f - p.y) / d.y;
        float x = p.x + t * d.x, z = p.z + t * d.z;
        hits += fabsf(x) <= 0.5f && fabsf(z) <= 0.25f;
    }
    double brute = 3.14159265358979323846 * L * (double)hits / M;
    CHECK_NEAR(est, brute, 0.01 * brute, "tilted receiver: light sampling vs hemisphere brute force");

    /* above the emitter: its back faces the point, so nothing can be sampled and the pdf is 0 */
    p = v3(0, 2, 0);
    int ok = 0;
    for (int i = 0; i < 1000; ++i) {
        ic_light_sample ls;
        ok += ic_scene_sample_light(s, p, rnd(&seed), rnd(&seed), rnd(&seed), &ls);
    }
    CHECK(ok == 0, "one-sided emitter is dark from behind (%d samples)", ok);
    CHECK(ic_scene_light_pdf_triangle(s, p, s->tri_lights[0].triangle, v3(0, -1, 0), 1.0f) == 0.0f,
          "pdf 0 from behind");
    for (uint32_t t = 0; t < s->triangle_count; ++t)
        if (s->triangle_light[t] < 0)
            CHECK(ic_scene_light_pdf_triangle(s, v3(0, 0.5f, 0), t, v3(0, -1, 0), 0.5f) == 0.0f,
                  "pdf 0 for a non-emitter");
    CHECK(ic_scene_light_pdf_env(s, v3(0, 1, 0)) == 0.0f, "no environment");
    ic_scene_free(s);
}

static void test_mixed_selection(void)
{
    ic_scene *s = load(SCENES "transformed.json");
    if (!s)
        return;
    /* just below the quad emitter (front faces down, at y = -4); the Cornell light is two-sided */
    ic_vec3 p = v3(0, -4.5f, 0);
    uint64_t seed = 12345;
    const int N = 200000;
    int count[4] = {0, 0, 0, 0}, failed = 0, bad_pdf = 0, bad_radiance = 0;
    for (int i = 0; i < N; ++i) {
        ic_light_sample ls;
        if (!ic_scene_sample_light(s, p, rnd(&seed), rnd(&seed), rnd(&seed), &ls)) {
            ++failed;
            continue;
        }
        if (ls.is_delta && isinf(ls.dist)) { /* sun */
            ++count[2];
            bad_pdf += ls.pdf != s->light_select.sun;
            bad_radiance += ls.radiance.x != 3.0f || ls.wi.y != 1.0f;
        } else if (ls.is_delta) { /* point */
            ++count[1];
            bad_pdf += ls.pdf != s->light_select.point;
            float d2 = v3_len2(v3_sub(v3(0, 3, 0), p));
            bad_radiance += fabsf(ls.radiance.x - 5.0f / d2) > 1e-5f;
        } else if (isinf(ls.dist)) { /* environment */
            ++count[3];
            bad_pdf += fabsf(ls.pdf - ic_scene_light_pdf_env(s, ls.wi)) > 1e-6f * ls.pdf;
            bad_pdf += fabsf(ls.pdf - s->light_select.env / (4 * IC_PI)) > 1e-6f * ls.pdf;
            bad_radiance += ls.radiance.y != 0.2f;
        } else {
            ++count[0];
            uint32_t t = sampled_triangle(s, p, &ls);
            bad_pdf += t == UINT32_MAX || fabsf(ic_scene_light_pdf_triangle(s, p, t, ls.wi, ls.dist) - ls.pdf) >
                                              1e-4f * ls.pdf;
        }
    }
    CHECK(failed == 0, "%d failed samples", failed);
    CHECK(bad_pdf == 0, "%d samples whose pdf disagrees with the pdf functions", bad_pdf);
    CHECK(bad_radiance == 0, "%d samples with wrong radiance", bad_radiance);
    const float expect[4] = {s->light_select.tri, s->light_select.point, s->light_select.sun, s->light_select.env};
    for (int k = 0; k < 4; ++k)
        CHECK_NEAR((double)count[k] / N, expect[k], 0.005, "class selection frequency");
    ic_scene_free(s);
}

static void test_environment_map(void)
{
    /* 64 × 32 lat-long map: a vertical gradient and a small bright block */
    ic_image img;
    ic_error err;
    if (ic_image_create(&img, 64, 32) != IC_OK) {
        CHECK(0, "ic_image_create");
        return;
    }
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            for (int c = 0; c < 3; ++c) {
                int bright = x >= 40 && x < 43 && y >= 10 && y < 12;
                img.rgb[3 * (y * img.width + x) + c] = bright ? 50.0f : 0.2f + 0.3f * (float)y / (float)img.height;
            }
    const char *map = IC_TEST_TMP "/scene_env.pfm", *json = IC_TEST_TMP "/scene_env.json";
    CHECK(ic_image_write(map, &img, NULL, &err) == IC_OK, "write env map: %s", err.message);
    ic_image_free(&img);
    CHECK(test_write_text(json, "{\n \"meshes\": [{\"path\": \"" IC_SOURCE_DIR "/tests/scenes/plain_quad.obj\"}],\n"
                           " \"environment\": {\"map\": \"scene_env.pfm\", \"scale\": 2, \"rotation_deg\": 30}\n}\n"),
          "write scene");
    ic_scene *s = load(json);
    if (!s)
        return;
    CHECK(s->env.enabled && s->env.image.width == 64 && s->light_select.env == 1.0f, "env map is the only light");

    /* the pdf integrates to 1 over the sphere (stratified uniform directions) */
    const int G = 800;
    uint64_t seed = 99;
    double pdf_sum = 0.0, lum_uniform = 0.0;
    for (int i = 0; i < G; ++i)
        for (int j = 0; j < G; ++j) {
            ic_vec3 d = ic_warp_uniform_sphere((i + rnd(&seed)) / G, (j + rnd(&seed)) / G);
            pdf_sum += ic_scene_light_pdf_env(s, d);
            lum_uniform += v3_lum(ic_scene_env_radiance(s, d));
        }
    CHECK_NEAR(pdf_sum * 4 * IC_PI / ((double)G * G), 1.0, 0.01, "env pdf integrates to 1");
    lum_uniform *= 4 * IC_PI / ((double)G * G);

    /* importance sampling: pdfs agree with ic_scene_light_pdf_env and the integral of L matches */
    const int N = 400000;
    double lum_is = 0.0;
    int mismatch = 0, failed = 0, bad_radiance = 0;
    for (int i = 0; i < N; ++i) {
        ic_light_sample ls;
        if (!ic_scene_sample_light(s, v3(0, 0, 0), rnd(&seed), rnd(&seed), rnd(&seed), &ls)) {
            ++failed;
            continue;
        }
        lum_is += v3_lum(ls.radiance) / ls.pdf;
        float pdf = ic_scene_light_pdf_env(s, ls.wi);
        mismatch += fabsf(pdf - ls.pdf) > 1e-3f * ls.pdf;
        bad_radiance += v3_len(v3_sub(ls.radiance, ic_scene_env_radiance(s, ls.wi))) > 1e-5f;
    }
    lum_is /= N;
    CHECK(failed < N / 10000, "%d failed env samples", failed);
    CHECK(bad_radiance == 0, "%d samples whose radiance is not the look-up", bad_radiance);
    CHECK(mismatch < N / 1000, "%d env samples whose pdf disagrees (texel boundaries)", mismatch);
    CHECK_NEAR(lum_is, lum_uniform, 0.02 * lum_uniform, "importance-sampled integral of L");

    /* rotation: the block's centre (u = 41.5/64, v = 11/32) is seen rotated by +30° about +y */
    float u = 41.5f / 64.0f, v = 11.0f / 32.0f;
    float phi = (u - 0.5f) * 2 * IC_PI, theta = v * IC_PI;
    ic_vec3 dm = v3(sinf(theta) * sinf(phi), cosf(theta), -sinf(theta) * cosf(phi));
    float a = 30.0f * IC_PI / 180.0f;
    ic_vec3 dw = v3(cosf(a) * dm.x + sinf(a) * dm.z, dm.y, -sinf(a) * dm.x + cosf(a) * dm.z);
    CHECK_NEAR(ic_scene_env_radiance(s, dw).x, 100.0, 1e-3, "bright block after rotation (x scale 2)");
    CHECK(ic_scene_env_radiance(s, dm).x < 2.0f, "not where the unrotated map has it");
    ic_scene_free(s);

    /* constant sky: uniform over the sphere */
    s = load(SCENES "plain_quad.obj");
    if (s) {
        ic_light_sample ls;
        CHECK(ic_scene_sample_light(s, v3(0, 0, 0), 0.5f, 0.3f, 0.7f, &ls), "constant sky sample");
        CHECK_NEAR(ls.pdf, 1.0 / (4 * IC_PI), 1e-7, "uniform sphere pdf");
        CHECK_NEAR(ic_scene_light_pdf_env(s, v3(0, -1, 0)), 1.0 / (4 * IC_PI), 1e-7, "pdf_env");
        CHECK(ls.radiance.x == 1.0f && isinf(ls.dist) && !ls.is_delta, "white sky radiance 1");
    }
    ic_scene_free(s);
}

static void test_local_lights(void)
{
    ic_scene *s = load(SCENES "many_lights.obj");
    if (!s)
        return;
    uint32_t n = s->tri_light_count;
    CHECK(n == 8, "8 emitting triangles (%u)", n);
    float pmf[8], cdf[9];
    ic_vec3 p = v3(0, 0, 0), nrm = v3(0, 1, 0);
    CHECK(ic_scene_local_lights(s, p, nrm, NULL, pmf, cdf) == 1, "local distribution built");
    double sum = 0.0;
    int defensive = 1, monotone = 1;
    for (uint32_t i = 0; i < n; ++i) {
        sum += pmf[i];
        defensive &= pmf[i] >= 0.25f * s->tri_lights[i].power / s->tri_light_power * 0.999f;
        monotone &= cdf[i + 1] >= cdf[i] && fabsf(cdf[i + 1] - cdf[i] - pmf[i]) < 1e-5f;
    }
    CHECK_NEAR(sum, 1.0, 1e-5, "pmf sums to 1");
    CHECK(cdf[0] == 0.0f && cdf[n] == 1.0f && monotone, "cdf matches the pmf");
    CHECK(defensive, "every emitter keeps a quarter of its power share");
    /* the small lamp right above the receiver outweighs its power share; the lamp below it (facing
     * up, behind the receiver's plane) keeps only its defensive share */
    double g0 = s->tri_lights[0].power / s->tri_light_power, g6 = s->tri_lights[6].power / s->tri_light_power;
    CHECK(pmf[0] > 2.0 * g0, "near lamp favoured (%.3f vs power share %.3f)", pmf[0], g0);
    CHECK(pmf[6] < 0.3 * g6, "lamp behind the receiver at its defensive share (%.3f vs %.3f)", pmf[6], g6);

    /* With a base distribution that leaves emitters out (the cache render's, where the records carry
     * large emitters' light), those get nothing and the rest is still a distribution mixed with it. */
    {
        float base[8], bpmf[8], bcdf[9];
        double kept = 0.0;
        for (uint32_t i = 0; i < n; ++i)
            kept += i % 2 ? s->tri_lights[i].power : 0.0;
        for (uint32_t i = 0; i < n; ++i)
            base[i] = i % 2 ? (float)(s->tri_lights[i].power / kept) : 0.0f;
        CHECK(ic_scene_local_lights(s, p, nrm, base, bpmf, bcdf) == 1, "local distribution over a base built");
        double bsum = 0.0;
        int left_out = 1, mixed = 1;
        for (uint32_t i = 0; i < n; ++i) {
            bsum += bpmf[i];
            left_out &= i % 2 || (bpmf[i] == 0.0f && bcdf[i + 1] == bcdf[i]);
            mixed &= !(i % 2) || bpmf[i] >= 0.25f * base[i] * 0.999f;
        }
        CHECK_NEAR(bsum, 1.0, 1e-5, "pmf over a base sums to 1");
        CHECK(left_out && mixed, "emitters the base leaves out get 0; the others keep a quarter of the base");
        for (uint32_t i = 0; i < n; ++i)
            base[i] = 0.0f;
        CHECK(ic_scene_local_lights(s, p, nrm, base, bpmf, bcdf) == 0, "no distribution over an empty base");
    }

    ic_light_selection local = s->light_select;
    local.tri_pmf = pmf;
    local.tri_cdf = cdf;
    const int N = 200000;
    uint64_t seed = 12345;
    double m[2] = {0, 0}, m2[2] = {0, 0};
    int mismatch = 0;
    for (int k = 0; k < 2; ++k) {
        const ic_light_selection *sel = k ? &local : &s->light_select;
        for (int i = 0; i < N; ++i) {
            ic_light_sample ls;
            double e = 0.0;
            if (ic_scene_sample_light_sel(s, sel, p, rnd(&seed), rnd(&seed), rnd(&seed), &ls)) {
                e = ls.radiance.x * fmax(0.0, v3_dot(nrm, ls.wi)) / ls.pdf;
                /* a sample on the diagonal of a quad meets both its triangles: either pdf will do */
                int agree = 0;
                for (uint32_t j = 0; j < n; ++j) {
                    uint32_t t = s->tri_lights[j].triangle;
                    float d = ray_triangle(s, t, p, ls.wi);
                    if (d > 0.0f && fabsf(d - ls.dist) <= 1e-3f * ls.dist)
                        agree |= fabsf(ic_scene_light_pdf_triangle_sel(s, sel, p, t, ls.wi, ls.dist) - ls.pdf) <=
                                 1e-4f * ls.pdf;
                }
                mismatch += !agree;
            }
            m[k] += e;
            m2[k] += e * e;
        }
        m[k] /= N;
        m2[k] = m2[k] / N - m[k] * m[k];
    }
    double sigma = sqrt((m2[0] + m2[1]) / N);
    printf("local lights: E by power %.5f (variance %.4g), local %.5f (variance %.4g)\n", m[0], m2[0], m[1], m2[1]);
    CHECK(mismatch == 0, "%d samples whose pdf differs from pdf_triangle_sel", mismatch);
    CHECK(fabs(m[0] - m[1]) < 4.0 * sigma, "same irradiance by power and by the local distribution");
    CHECK(m2[1] < 0.5 * m2[0], "local selection halves the variance at least");
    ic_scene_free(s);
}

/* The light-class weights of a scene near the largest coordinate (1e18): the sun's pi r^2 lum(E) and,
 * through portals, the sky's pi A lum(L) leave a float although each class's probability is an ordinary
 * number. By the file comment's formulas the ratios do not depend on the scale: sun over environment
 * E / (4 pi L) without portals, E / (pi L) through a horizontal portal under a sun overhead. */
static void test_huge_scene_classes(void)
{
    char mesh[512], path[512], text[1024];
    snprintf(mesh, sizeof mesh, "%s/lights_huge.obj", IC_TEST_TMP);
    CHECK(test_write_text(mesh, "v -1e18 0 -1e18\nv 1e18 0 -1e18\nv 0 0 1e18\nf 1 3 2\n"), "write %s", mesh);
    for (int portal = 0; portal < 2; ++portal) {
        snprintf(path, sizeof path, "%s/lights_huge%d.json", IC_TEST_TMP, portal);
        snprintf(text, sizeof text,
                 "{\"camera\": {\"eye\": [0, 1e17, 0], \"target\": [0, 0, 0], \"up\": [0, 0, 1]},\n"
                 " \"meshes\": [{\"path\": \"%s\"}],\n"
                 " \"lights\": [{\"type\": \"sun\", \"direction\": [0, 1, 0], \"irradiance\": [1000, 1000, 1000]}],\n"
                 " \"environment\": {\"radiance\": [1000, 1000, 1000]%s}}\n",
                 mesh, portal ? ", \"portals\": [[[0, 3, 0], [1e18, 3, 0], [1e18, 3, 1e18], [0, 3, 1e18]]]" : "");
        CHECK(test_write_text(path, text), "write %s", path);
        ic_scene *s = load(path);
        if (!s)
            continue;
        const ic_light_selection *sel = &s->light_select;
        const double want = portal ? 1.0 / IC_PI : 1.0 / (4.0 * IC_PI);
        CHECK(sel->tri == 0.0f && sel->point == 0.0f && fabs(sel->sun + sel->env - 1.0) < 1e-6 &&
                  fabs(sel->sun / sel->env - want) < 1e-5 * want,
              "%s: sun %g, environment %g (their ratio should be %g)", portal ? "through a portal" : "open sky",
              (double)sel->sun, (double)sel->env, want);
        ic_scene_free(s);
    }
}

int main(void)
{
    test_huge_scene_classes();
    test_local_lights();
    test_rectangle_irradiance();
    test_mixed_selection();
    test_environment_map();
    TEST_MAIN_END();
}
