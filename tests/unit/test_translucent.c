/*
 * test_translucent.c — the translucent sheet (Radiance's trans): Lambertian reflection kd, Lambertian
 * transmission kt, straight-through transmission kt_specular:
 *   1. the BSDF: sampled weights average to kd on the viewer's side, kt and kt_specular beyond it; the pdf
 *      integrates over the sphere to the probability of a non-straight sample; sampled weights equal
 *      f·|cos|/pdf;
 *   2. a sheet with kd + kt + kt_specular = 1 in a uniform sky is a white furnace: every pixel is the sky's
 *      radiance, path tracer and cache;
 *   3. a sheet in front of a large glowing wall of radiance L (nothing else lit): the camera sees
 *      (kt + kt_specular)·L through it (E = πL behind the sheet), path tracer and cache; 1 and 2 threads
 *      give the same image.
 */
#include "test_util.h"
#include "test_render_util.h"

#include "integrators/bsdf.h"

#include <stdio.h>
#include <string.h>

#define PI_D 3.14159265358979323846

static ic_bsdf sheet(ic_vec3 kd, ic_vec3 kt, ic_vec3 kts)
{
    ic_scene sc;
    memset(&sc, 0, sizeof sc);
    ic_material m;
    memset(&m, 0, sizeof m);
    m.type = IC_MAT_TRANSLUCENT;
    m.kd = kd;
    m.kd_texture = -1;
    m.kt = kt;
    m.kt_specular = kts;
    sc.materials = &m;
    sc.material_count = 1;
    ic_surface s;
    memset(&s, 0, sizeof s);
    s.ng = s.ns = v3(0.0f, 0.0f, 1.0f);
    ic_bsdf b;
    ic_bsdf_init(&b, &sc, &s, v3(0.3f, 0.2f, 0.933f));
    return b;
}

static void test_bsdf(void)
{
    ic_vec3 kd = v3(0.5f, 0.2f, 0.1f), kt = v3(0.2f, 0.3f, 0.1f), kts = v3(0.1f, 0.4f, 0.6f);
    ic_bsdf b = sheet(kd, kt, kts);
    ic_vec3 wo = v3_norm(v3(0.3f, 0.2f, 0.933f));
    /* fine strata of u0 and u1 (they choose the lobes, whose probabilities are no multiples of 1/strata) */
    const int n = 251, m2 = 16, strata = 97;
    ic_vec3 front = v3s(0.0f), back = v3s(0.0f), straight = v3s(0.0f);
    double worst = 0.0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < m2; ++j)
            for (int k = 0; k < strata; ++k) {
                ic_bsdf_sample s;
                float u0 = ((float)k + 0.5f) / (float)strata, u1 = ((float)i + 0.5f) / (float)n, u2 = ((float)j + 0.5f) / (float)m2;
                /* u0 stratifies the lobe choice, (u1, u2) the direction */
                if (!ic_bsdf_sample_dir(&b, wo, u0, u1, u2, &s))
                    continue;
                ic_vec3 w = v3_scale(s.weight, 1.0f / ((float)strata * (float)n * (float)m2));
                if (s.is_specular) {
                    straight = v3_add(straight, w);
                    continue;
                }
                ic_vec3 f = ic_bsdf_eval(&b, wo, s.wi);
                float pdf = ic_bsdf_pdf(&b, wo, s.wi);
                ic_vec3 expect = v3_scale(f, fabsf(s.wi.z) / pdf);
                worst = fmax(worst, fabs(expect.y - s.weight.y) / fmax(1e-6, expect.y));
                if (s.wi.z > 0.0f)
                    front = v3_add(front, w);
                else
                    back = v3_add(back, w);
            }
    CHECK(worst < 1e-4, "sampled weights are f |cos| / pdf (worst relative %g)", worst);
    float want[3][3] = {{kd.x, kd.y, kd.z}, {kt.x, kt.y, kt.z}, {kts.x, kts.y, kts.z}};
    ic_vec3 got[3] = {front, back, straight};
    const char *what[3] = {"reflected (kd)", "diffusely transmitted (kt)", "straight through (kt_specular)"};
    for (int l = 0; l < 3; ++l)
        CHECK(fabsf(got[l].x - want[l][0]) < 0.01f && fabsf(got[l].y - want[l][1]) < 0.01f &&
                  fabsf(got[l].z - want[l][2]) < 0.01f,
              "%s: mean weight (%g %g %g), expected (%g %g %g)", what[l], (double)got[l].x, (double)got[l].y,
              (double)got[l].z, (double)want[l][0], (double)want[l][1], (double)want[l][2]);
    /* ∫ pdf dω over the sphere (midpoint rule in cos θ and φ) = 1 − P(straight) */
    double integral = 0.0;
    const int m = 400;
    for (int i = 0; i < 2 * m; ++i)
        for (int j = 0; j < m; ++j) {
            double mu = -1.0 + (i + 0.5) / m, phi = 2.0 * PI_D * (j + 0.5) / m, st = sqrt(1.0 - mu * mu);
            ic_vec3 wi = v3((float)(st * cos(phi)), (float)(st * sin(phi)), (float)mu);
            integral += ic_bsdf_pdf(&b, wo, wi) * (1.0 / m) * (2.0 * PI_D / m);
        }
    double p_straight = (1.0 - b.p_diffuse) * b.p_straight;
    CHECK(fabs(integral - (1.0 - p_straight)) < 2e-3, "the pdf integrates to %g, expected 1 - P(straight) = %g",
          integral, 1.0 - p_straight);
}

/* A scene of two big quads: the sheet at y = 5 (material `sheet`) and, when wall is set, a wall at y = 10
 * emitting 2 towards the sheet; the camera at the origin looks along +y through a 4° view. env: a uniform
 * sky of 2 instead. Returns the image's mean of channel c. */
static double render(const char *material, int wall, int env, ic_integrator integ, int threads, ic_image *keep)
{
    test_write_file(IC_TEST_TMP "/tl.mtl", "newmtl sheet\nKd 0.5 0.5 0.5\nnewmtl wall\nKd 0 0 0\n");
    char obj[1024];
    snprintf(obj, sizeof obj, "mtllib tl.mtl\nusemtl sheet\n"
                              "v -1000 5 -1000\nv 1000 5 -1000\nv 1000 5 1000\nv -1000 5 1000\nf 1 2 3\nf 1 3 4\n%s",
             wall ? "usemtl wall\nv -1000 10 -1000\nv 1000 10 -1000\nv 1000 10 1000\nv -1000 10 1000\n"
                    "f 5 6 7\nf 5 7 8\n"
                  : "");
    test_write_file(IC_TEST_TMP "/tl.obj", obj);
    char scene[2048];
    snprintf(scene, sizeof scene,
             "{\n  \"camera\": {\"eye\": [0, 0, 0], \"target\": [0, 1, 0], \"up\": [0, 0, 1], \"fov_y\": 4,"
             " \"width\": 8, \"height\": 8},\n"
             "  \"meshes\": [{\"path\": \"tl.obj\"}],\n"
             "  \"materials\": {\"sheet\": %s%s}%s\n}\n",
             material, wall ? ", \"wall\": {\"emission\": 2, \"two_sided\": true}" : "",
             env ? ",\n  \"environment\": {\"radiance\": [2, 2, 2]}" : "");
    test_write_file(IC_TEST_TMP "/tl.json", scene);
    ic_render_options opt = {0};
    opt.integrator = integ;
    opt.spp = 64;
    opt.threads = threads;
    opt.seed = 5;
    opt.has_seed = 1;
    ic_image img = {0};
    double mean = -1.0;
    if (test_render(IC_TEST_TMP "/tl.json", 0, 0, &opt, &img, NULL)) {
        mean = 0.0;
        for (int i = 0; i < img.width * img.height; ++i)
            mean += img.rgb[3 * i + 1] / (double)(img.width * img.height);
    }
    if (keep)
        *keep = img;
    else
        ic_image_free(&img);
    return mean;
}

static void test_renders(void)
{
    static const ic_integrator integ[2] = {IC_INTEGRATOR_PT, IC_INTEGRATOR_IC};
    const char *white = "{\"type\": \"translucent\", \"kd\": 0.4, \"kt\": 0.35, \"kt_specular\": 0.25}";
    const char *lamp = "{\"type\": \"translucent\", \"kd\": 0.3, \"kt\": 0.4, \"kt_specular\": 0.1}";
    for (int k = 0; k < 2; ++k) {
        const char *name = k ? "cache" : "path tracer";
        double m = render(white, 0, 1, integ[k], 2, NULL);
        CHECK(fabs(m - 2.0) < 0.02, "%s: a sheet reflecting and transmitting everything in a uniform sky of 2: %g", name,
              m);
        ic_image one = {0}, two = {0};
        double m1 = render(lamp, 1, 0, integ[k], 1, &one), m2 = render(lamp, 1, 0, integ[k], 2, &two);
        printf("%s: furnace %g (2), sheet before a wall %g (2 (kt + kt_specular) = 1)\n", name, m, m2);
        CHECK(fabs(m2 - 1.0) < 0.03, "%s: the wall through the sheet %g, expected (kt + kt_specular) L = 1", name, m2);
        CHECK(m1 == m2 && one.width == two.width && !memcmp(one.rgb, two.rgb, sizeof(float) * 3 * 64),
              "%s: 1 and 2 threads give the same image", name);
        ic_image_free(&one);
        ic_image_free(&two);
    }
}

int main(void)
{
    test_bsdf();
    test_renders();
    TEST_MAIN_END();
}
