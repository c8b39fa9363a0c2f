/*
 * test_radiance.c — radiance caching on glossy surfaces (--radiance-cache on).
 *
 * 1. White furnace: a glossy plane (no diffuse part) under a constant sky reflects k_s × the Phong
 *    lobe's directional albedo × L at every view; the records' Λ·C must give the path tracer's image,
 *    for two exponents; and for a coloured rough conductor and a rough plastic's coat, whose lobes are
 *    tabulated from the BSDF itself.
 * 2. The glossy Cornell box with a floor of exponent 20: the cache with radiance records against a
 *    path-traced reference (its noise measured from two halves) — image mean within 1 %, relMSE below a
 *    bound, and radiance records actually made on the floor and the sphere.
 * 3. Determinism: 1 and 2 threads give identical images for every strategy, and a saved then loaded
 *    cache (radiance records and their coefficients in the file) renders the identical image; a render
 *    without radiance caching refuses that file.
 * 4. Translational gradients of the coefficients lower the interpolated glossy term's error (a glossy
 *    floor beside a wall, the glossy AOV against the path tracer).
 * 5. Adaptive caching (Křivánek et al. 2006 §4 on the glossy lobe's outgoing radiance) makes more
 *    radiance records for sharper lobes: exponents 3, 10, 30 on the floor beside the wall.
 */
#include "test_util.h"

#include "test_render_util.h"

#include "integrators/ic_radiance.h"

#include "irrcache/image.h"

#include <string.h>

#define GLOSSY20 IC_SOURCE_DIR "/scenes/cornell-box-glossy/cornell-box-glossy-20.json"

static ic_render_options radiance_options(void)
{
    ic_render_options o = {0};
    o.integrator = IC_INTEGRATOR_IC;
    o.spp = 16;
    o.ic.radiance_cache = IC_CACHE_ON;
    o.ic.radiance_max_exponent = 40.0f; /* the sphere (32) too */
    return o;
}

static double rel_mse(const ic_image *a, const ic_image *ref)
{
    double s = 0.0;
    size_t n = (size_t)a->width * a->height * 3;
    for (size_t i = 0; i < n; ++i) {
        double d = a->rgb[i] - ref->rgb[i];
        s += d * d / (ref->rgb[i] * ref->rgb[i] + 1e-2);
    }
    return s / (double)n;
}

static void test_furnace(void)
{
    const float exponents[] = {5.0f, 20.0f};
    for (int e = 0; e < 2; ++e) {
        char mtl[256];
        snprintf(mtl, sizeof mtl, "newmtl mirrorish\nKd 0 0 0\nKs 0.7 0.7 0.7\nNs %g\n", (double)exponents[e]);
        test_write_file(IC_TEST_TMP "/rc_furnace.mtl", mtl);
        test_write_file(IC_TEST_TMP "/rc_furnace.obj", "mtllib rc_furnace.mtl\nusemtl mirrorish\n"
                                                       "v -50 0 -50\nv 50 0 -50\nv 50 0 50\nv -50 0 50\n"
                                                       "f 1 3 2\nf 1 4 3\n");
        /* The material's exponent comes from the JSON override; write it per case. */
        char json[1024];
        snprintf(json, sizeof json,
                 "{\"camera\": {\"eye\": [0, 1, 2], \"target\": [0, 0, -1], \"up\": [0, 1, 0], \"fov_y\": 60, "
                 "\"width\": 40, \"height\": 40}, \"meshes\": [{\"path\": \"rc_furnace.obj\"}], \"materials\": "
                 "{\"mirrorish\": {\"type\": \"glossy\", \"kd\": [0, 0, 0], \"ks\": 0.7, \"ns\": %g}}, "
                 "\"environment\": {\"radiance\": [1, 1, 1]}}",
                 (double)exponents[e]);
        test_write_file(IC_TEST_TMP "/rc_furnace.json", json);
        ic_render_options pt = {0};
        pt.spp = 256;
        ic_image ref = {0}, img = {0};
        ic_render_stats st;
        CHECK(test_render(IC_TEST_TMP "/rc_furnace.json", 0, 0, &pt, &ref, NULL), "furnace reference renders");
        ic_render_options o = radiance_options();
        CHECK(test_render(IC_TEST_TMP "/rc_furnace.json", 0, 0, &o, &img, &st), "furnace cache renders");
        CHECK(st.radiance_records > 0, "exponent %g: %u radiance records", (double)exponents[e], st.radiance_records);
        int f1, f2;
        double mr = test_image_mean(&ref, &f1), mc = test_image_mean(&img, &f2);
        double err = rel_mse(&img, &ref);
        printf("furnace exponent %g: %u radiance records, mean %+.3f %% off the path tracer, relMSE %.2e\n",
               (double)exponents[e], st.radiance_records, 100.0 * (mc / mr - 1.0), err);
        CHECK(f1 && f2, "finite images");
        CHECK(fabs(mc / mr - 1.0) < 0.01, "exponent %g: furnace mean %+.3f %% off", (double)exponents[e],
              100.0 * (mc / mr - 1.0));
        CHECK(err < 2e-3, "exponent %g: furnace relMSE %.2e", (double)exponents[e], err);
        ic_image_free(&ref);
        ic_image_free(&img);
    }
}

/* The same furnace with the microfacet models, whose lobes are tabulated from the BSDF itself: a
 * coloured rough conductor (one table per channel) and a rough plastic with a black base (its coat
 * alone). */
static void test_furnace_microfacet(void)
{
    const char *materials[] = {"{\"type\": \"conductor\", \"ks\": [0.95, 0.65, 0.3], \"alpha\": 0.4}",
                               "{\"type\": \"plastic\", \"kd\": [0, 0, 0], \"alpha\": 0.3}"};
    for (int m = 0; m < 2; ++m) {
        char json[1024];
        snprintf(json, sizeof json,
                 "{\"camera\": {\"eye\": [0, 1, 2], \"target\": [0, 0, -1], \"up\": [0, 1, 0], \"fov_y\": 60, "
                 "\"width\": 40, \"height\": 40}, \"meshes\": [{\"path\": \"rc_furnace.obj\"}], \"materials\": "
                 "{\"mirrorish\": %s}, \"environment\": {\"radiance\": [1, 1, 1]}}",
                 materials[m]);
        test_write_file(IC_TEST_TMP "/rc_furnace_mf.json", json);
        ic_render_options pt = {0};
        pt.spp = 256;
        ic_image ref = {0}, img = {0};
        ic_render_stats st;
        CHECK(test_render(IC_TEST_TMP "/rc_furnace_mf.json", 0, 0, &pt, &ref, NULL), "reference renders");
        ic_render_options o = radiance_options();
        CHECK(test_render(IC_TEST_TMP "/rc_furnace_mf.json", 0, 0, &o, &img, &st), "cache renders");
        int f1, f2;
        double mr = test_image_mean(&ref, &f1), mc = test_image_mean(&img, &f2), err = rel_mse(&img, &ref);
        printf("furnace %s: %u radiance records, mean %+.3f %% off the path tracer, relMSE %.2e\n", materials[m],
               st.radiance_records, 100.0 * (mc / mr - 1.0), err);
        CHECK(st.radiance_records > 0, "%s: radiance records serve it", materials[m]);
        CHECK(fabs(mc / mr - 1.0) < 0.01, "%s: furnace mean %+.3f %% off", materials[m], 100.0 * (mc / mr - 1.0));
        CHECK(err < 2e-3, "%s: furnace relMSE %.2e", materials[m], err);
        ic_image_free(&ref);
        ic_image_free(&img);
    }
}

static void test_glossy_cornell(void)
{
    const int W = 48, H = 48;
    ic_image ref[2] = {{0}, {0}};
    double m[2];
    for (int k = 0; k < 2; ++k) {
        ic_render_options pt = {0};
        pt.spp = 512;
        pt.seed = 101 + (uint64_t)k;
        int finite;
        CHECK(test_render(GLOSSY20, W, H, &pt, &ref[k], NULL), "reference renders");
        m[k] = test_image_mean(&ref[k], &finite);
    }
    double noise = fabs(m[0] - m[1]) / (0.5 * (m[0] + m[1]));
    double ref_err = rel_mse(&ref[0], &ref[1]) / 2.0; /* one half against the truth */
    ic_render_options o = radiance_options();
    ic_image img = {0};
    ic_render_stats st;
    CHECK(test_render(GLOSSY20, W, H, &o, &img, &st), "cache renders");
    int finite;
    double mc = test_image_mean(&img, &finite), mr = 0.5 * (m[0] + m[1]);
    double err = rel_mse(&img, &ref[0]);
    printf("glossy Cornell (floor 20): %u records, %u radiance; reference noise %.3f %% (relMSE %.2e); cache mean "
           "%+.3f %%, relMSE %.2e\n", st.records, st.radiance_records, 100.0 * noise, ref_err,
           100.0 * (mc / mr - 1.0), err);
    CHECK(noise < 0.003, "reference halves differ by %.3f %%", 100.0 * noise);
    CHECK(st.radiance_records > 20, "%u radiance records on the floor and sphere", st.radiance_records);
    CHECK(fabs(mc / mr - 1.0) < 0.01, "cache mean %+.3f %% off the path tracer's", 100.0 * (mc / mr - 1.0));
    CHECK(err < 0.02, "cache relMSE %.2e against the reference", err);
    ic_image_free(&img);
    ic_image_free(&ref[0]);
    ic_image_free(&ref[1]);
}

static int images_equal(const ic_image *a, const ic_image *b)
{
    return a->width == b->width && a->height == b->height &&
           memcmp(a->rgb, b->rgb, sizeof(float) * 3 * (size_t)a->width * a->height) == 0;
}

static void test_determinism(void)
{
    const int W = 40, H = 40;
    ic_image img[4] = {{0}, {0}, {0}, {0}};
    const ic_strategy strategies[] = {IC_STRATEGY_LAZY, IC_STRATEGY_ADAPTIVE, IC_STRATEGY_BATCH};
    for (int k = 0; k < 3; ++k) {
        for (int threads = 1; threads <= 2; ++threads) {
            ic_render_options o = radiance_options();
            o.spp = 4;
            o.threads = threads;
            o.ic.strategy = strategies[k];
            if (k > 0)
                ic_image_free(&img[threads - 1]);
            CHECK(test_render(GLOSSY20, W, H, &o, &img[threads - 1], NULL), "%d threads render", threads);
        }
        CHECK(images_equal(&img[0], &img[1]), "strategy %d: 1 and 2 threads give identical images", (int)strategies[k]);
    }
    /* Off: the same scene without radiance records renders differently (the records are used). */
    ic_render_options o = radiance_options();
    o.spp = 4;
    o.ic.radiance_cache = IC_CACHE_OFF;
    CHECK(test_render(GLOSSY20, W, H, &o, &img[2], NULL), "off renders");
    CHECK(!images_equal(&img[0], &img[2]), "radiance records change the image");
    for (int k = 0; k < 3; ++k)
        ic_image_free(&img[k]);
    /* Save and load: the radiance records' coefficients and the irradiance records' bounce levels travel
     * in the file, so the loaded cache renders the identical image, glossy reflections included. */
    o = radiance_options();
    o.spp = 4;
    o.threads = 2;
    o.ic.save_cache = IC_TEST_TMP "/rc_cache.icc";
    CHECK(test_render(GLOSSY20, W, H, &o, &img[0], NULL), "saving render");
    o.ic.save_cache = NULL;
    o.ic.load_cache = IC_TEST_TMP "/rc_cache.icc";
    ic_render_stats st;
    CHECK(test_render(GLOSSY20, W, H, &o, &img[1], &st), "loaded cache renders");
    CHECK(st.radiance_records > 0, "the loaded cache has %u radiance records", st.radiance_records);
    CHECK(images_equal(&img[0], &img[1]), "a saved and loaded cache renders the identical image");
    /* Without radiance records the file is refused (its records were made with other settings). */
    o.ic.radiance_cache = IC_CACHE_OFF;
    CHECK(!test_render(GLOSSY20, W, H, &o, &img[2], NULL),
          "a cache with radiance records is refused by a render without them");
    /* Nor by one whose --radiance-max-exponent serves no material (the floor's 20 and the sphere's 32 above
     * 10): the message names the exponent, not --hsh-order, which is the same in both. */
    o.ic.radiance_cache = IC_CACHE_ON;
    o.ic.radiance_max_exponent = 10.0f;
    ic_scene *scene = NULL;
    ic_error err = {0};
    ic_scene_load_options lo = {0};
    lo.width = W;
    lo.height = H;
    ic_result r = ic_scene_load(GLOSSY20, &lo, &scene, &err);
    if (r == IC_OK)
        r = ic_render(scene, &o, &img[2], NULL, &err);
    CHECK(r == IC_ERR_MISMATCH && strstr(err.message, "made with --radiance-max-exponent 40, this run has "
                                                      "--radiance-max-exponent 10") && !strstr(err.message, "hsh"),
          "an exponent that serves no material is named: %s", err.message);
    ic_scene_free(scene);
    ic_image_free(&img[0]);
    ic_image_free(&img[1]);
    ic_image_free(&img[2]);
}

/* A purely glossy floor (k_d = 0, Phong exponent e) beside a white wall under a constant sky: the
 * floor's glossy light changes with the distance to the wall. */
static void write_wall_scene(float e)
{
    test_write_file(IC_TEST_TMP "/rc_wall.obj", "mtllib rc_wall.mtl\nusemtl floor\n"
                                                "v -3 0 -3\nv 3 0 -3\nv 3 0 3\nv -3 0 3\nf 1 3 2\nf 1 4 3\n"
                                                "usemtl wall\nv 0.4 0 -3\nv 0.4 0 3\nv 0.4 1.5 3\nv 0.4 1.5 -3\n"
                                                "f 5 6 7\nf 5 7 8\n");
    test_write_file(IC_TEST_TMP "/rc_wall.mtl", "newmtl floor\nKd 0 0 0\nnewmtl wall\nKd 0.8 0.8 0.8\n");
    char json[1024];
    snprintf(json, sizeof json,
             "{\"camera\": {\"eye\": [-1.0, 0.9, 0], \"target\": [0.4, 0, 0], \"up\": [0, 1, 0], \"fov_y\": 50, "
             "\"width\": 64, \"height\": 48}, \"meshes\": [{\"path\": \"rc_wall.obj\"}], \"materials\": "
             "{\"floor\": {\"type\": \"glossy\", \"kd\": [0, 0, 0], \"ks\": 0.8, \"ns\": %g}}, "
             "\"environment\": {\"radiance\": [1, 1, 1]}}",
             (double)e);
    test_write_file(IC_TEST_TMP "/rc_wall.json", json);
}

/* Křivánek et al. 2006 §6, fig. 10: adaptive caching puts more radiance records on sharper lobes. The
 * glossy floor beside the wall, exponents 3, 10 and 30: the discernibility test on outgoing radiance
 * splits records where the reflected wall's light changes across them, and a sharper lobe sees the change
 * sharper. Records may be large (no world radius bound), so the count is what the refinement makes. (Under
 * a distant sky alone every radiance record of a plane holds the same light, and nothing is split.) */
static void test_adaptive_sharpness(void)
{
    const float exponents[] = {3.0f, 10.0f, 30.0f};
    uint32_t count[3];
    for (int e = 0; e < 3; ++e) {
        write_wall_scene(exponents[e]);
        ic_render_options o = radiance_options();
        o.spp = 1;
        o.ic.strategy = IC_STRATEGY_ADAPTIVE;
        o.ic.cache.max_radius = 100.0f;
        ic_image img = {0};
        ic_render_stats st;
        CHECK(test_render(IC_TEST_TMP "/rc_wall.json", 0, 0, &o, &img, &st), "exponent %g renders",
              (double)exponents[e]);
        count[e] = st.radiance_records;
        printf("adaptive, glossy floor of exponent %g beside a wall: %u radiance records\n", (double)exponents[e],
               count[e]);
        ic_image_free(&img);
    }
    CHECK(count[0] < count[1] && count[1] < count[2], "radiance records %u, %u, %u for exponents 3, 10, 30: not "
          "increasing", count[0], count[1], count[2]);
    CHECK(count[2] > 2 * count[0], "exponent 30 has %u radiance records, exponent 3 %u: expected several times more",
          count[2], count[0]);
}

/* Relative MSE of 4×4-pixel block means (the interpolation's error, without pixel noise) over rows
 * y0 … H−1. */
static double block_rel_mse(const ic_image *a, const ic_image *ref, int y0)
{
    double s = 0.0;
    int n = 0;
    for (int by = y0; by + 4 <= a->height; by += 4)
        for (int bx = 0; bx + 4 <= a->width; bx += 4)
            for (int ch = 0; ch < 3; ++ch) {
                double ma = 0.0, mr = 0.0;
                for (int y = by; y < by + 4; ++y)
                    for (int x = bx; x < bx + 4; ++x) {
                        ma += a->rgb[3 * ((size_t)y * a->width + x) + ch];
                        mr += ref->rgb[3 * ((size_t)y * a->width + x) + ch];
                    }
                ma /= 16.0;
                mr /= 16.0;
                s += (ma - mr) * (ma - mr) / (mr * mr + 1e-3);
                ++n;
            }
    return n ? s / n : 0.0;
}

/* Translational gradients of the coefficients (Křivánek et al. 2005) lower the interpolation error: a
 * purely glossy floor (k_d = 0) beside a white wall under a constant sky, whose reflected light changes
 * with the distance to the wall. The floor's pixels are its glossy indirect light alone, so the glossy
 * AOV compares with the path tracer there; block means over the floor (lower 40 % of the image) remove the
 * pixel noise, and two seeds the luck of one record set. */
static void test_gradients(void)
{
    write_wall_scene(10.0f);
    ic_render_options pt = {0};
    pt.spp = 512;
    ic_image ref = {0};
    CHECK(test_render(IC_TEST_TMP "/rc_wall.json", 0, 0, &pt, &ref, NULL), "reference renders");
    double err[2] = {0.0, 0.0};
    for (int grad = 0; grad < 2; ++grad)
        for (uint64_t seed = 1; seed <= 2; ++seed) {
            ic_render_options o = radiance_options();
            o.spp = 2;
            o.seed = seed;
            o.ic.no_gradients = !grad;
            ic_render_aovs aovs;
            memset(&aovs, 0, sizeof aovs);
            aovs.want_glossy = 1;
            o.aovs = &aovs;
            ic_image img = {0};
            CHECK(test_render(IC_TEST_TMP "/rc_wall.json", 0, 0, &o, &img, NULL), "cache renders");
            CHECK(aovs.glossy.rgb != NULL, "the glossy AOV is made");
            if (aovs.glossy.rgb)
                err[grad] += 0.5 * block_rel_mse(&aovs.glossy, &ref, (int)(0.6 * ref.height) / 4 * 4);
            ic_image_free(&aovs.glossy);
            ic_image_free(&img);
        }
    printf("glossy floor beside a wall: block relMSE of the glossy term %.2e without gradients, %.2e with\n",
           err[0], err[1]);
    CHECK(err[1] < err[0], "gradients do not lower the glossy term's error (%.2e with, %.2e without)", err[1], err[0]);
    CHECK(err[1] < 5e-3, "glossy term's block relMSE %.2e with gradients", err[1]);
    ic_image_free(&ref);
}

/* A radiance record's rays: 4 × an irradiance record's by default, but never past IC_MAX_RECORD_RAYS, so that
 * the largest --rays (10^7) does not ask the gatherer for 4·10^7 rays (over its 2^24 grid, refused only after
 * the irradiance records were built); an explicit --radiance-rays is taken as given. */
static void test_radiance_rays(void)
{
    static const struct {
        uint32_t theta, phi;
        int radiance_rays;
        double want, tolerance;
    } cases[] = {
        {0, 0, 0, 4.0 * IC_DEFAULT_RAYS, 0.02},
        {16, 50, 0, 3200.0, 0.02},
        {1784, 5605, 0, IC_MAX_RECORD_RAYS, 0.001},
        {1784, 5605, 5000, 5000.0, 0.02},
        {16, 50, IC_MAX_RECORD_RAYS, IC_MAX_RECORD_RAYS, 0.001},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        ic_ic_options o;
        memset(&o, 0, sizeof o);
        o.gather.theta_strata = cases[k].theta;
        o.gather.phi_strata = cases[k].phi;
        o.radiance_rays = cases[k].radiance_rays;
        const ic_gather_opts go = ic_ic_radiance_gather_opts(&o);
        const double rays = (double)go.theta_strata * go.phi_strata;
        CHECK(fabs(rays / cases[k].want - 1.0) < cases[k].tolerance && rays <= (double)(1u << 24),
              "radiance rays for %u x %u irradiance strata and --radiance-rays %d: %.0f (want about %.0f, at most "
              "2^24)", cases[k].theta, cases[k].phi, cases[k].radiance_rays, rays, cases[k].want);
    }
}

int main(void)
{
    test_radiance_rays();
    test_furnace();
    test_furnace_microfacet();
    test_glossy_cornell();
    test_determinism();
    test_gradients();
    test_adaptive_sharpness();
    TEST_MAIN_END();
}
