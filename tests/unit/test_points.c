/*
 * test_points.c — irradiance and illuminance at sensor points (irrcache/points.h) against closed forms:
 *   1. open plane under a uniform sky of radiance L: a sensor facing up receives E = πL; one facing
 *      sideways sees half the sky and half the ground (radiance ρL), E = πL(1 + ρ)/2, and over 40 seeds
 *      its error stays within 2σ about 94 % of the time (σ from 16 replicates: 15 degrees of freedom;
 *      checked: at least 85 %, for the cache too, whose single record's relative variance then comes from
 *      repeated gathers); facing down, E = πρL; the same with the plane one triangle 2e12 across;
 *   2. a sensor facing a single emitting rectangle: E by Lambert's polygon formula, both estimators; a
 *      row of sensors under a black square in the open sky, E = L(π − P) with P by Lambert's formula at
 *      each: the sky is sampled at each sensor, never interpolated; sensors in a black cube under a
 *      square skylight declared as a portal, E = P of the opening; a closed white furnace (albedo and
 *      emission 0.5): E = π, every bounce summed;
 *   3. the Cornell box: the cache and the path tracer agree within their error bars (plus the cache's
 *      interpolation bias, which σ leaves out) at a few points; on an 8 × 8 work-plane grid the cache is
 *      within 2σ of an 8192-sample reference at 80 % of the points or more; on a 30 × 30 grid records are
 *      shared (fewer than half as many as points), and 1 and 2 threads agree there too;
 *   4. 1 and 2 threads give identical results for both estimators; a zero normal is refused by index;
 *      illuminance uses Radiance's 179 lm/W and RGB weights;
 *   5. work-plane grids (ic_points_grid): count, centred positions, height and normal; bad boxes refused.
 */
#include "test_util.h"

#include "test_render_util.h"

#include "irrcache/points.h"
#include "core/vecmath.h"

#include <stdlib.h>
#include <string.h>

#define PI_D 3.14159265358979323846

static ic_scene *load(const char *path)
{
    ic_error err = {0};
    ic_scene *scene = NULL;
    ic_scene_load_options lo = {0};
    lo.width = 16;
    lo.height = 16;
    if (ic_scene_load(path, &lo, &scene, &err) != IC_OK)
        fprintf(stderr, "load %s: %s\n", path, err.message);
    return scene;
}

static ic_sensor_point sensor(float x, float y, float z, float nx, float ny, float nz)
{
    ic_sensor_point s = {{x, y, z}, {nx, ny, nz}};
    return s;
}

static void test_illuminance_convention(void)
{
    ic_vec3 white = {1.0f, 1.0f, 1.0f};
    CHECK_NEAR(ic_illuminance(white), 179.0, 1e-6, "white 1 W/m2 is 179 lux");
    ic_vec3 green = {0.0f, 1.0f, 0.0f};
    CHECK_NEAR(ic_illuminance(green), 179.0 * 0.670114631, 1e-6, "green weight");
}

/* The ground (name.obj: the OBJ vertices and faces in geometry, Kd 0.5) under the sky L = (1, 2, 3), and
 * sensors facing up, sideways and down (E = πρL: the ground's radiance ρL all round); calibrate: σ's
 * calibration too. */
static void test_open_plane(const char *name, const char *geometry, int calibrate)
{
    char path[512], text[512];
    snprintf(path, sizeof path, IC_TEST_TMP "/%s.mtl", name);
    test_write_file(path, "newmtl ground\nKd 0.5 0.5 0.5\n");
    snprintf(path, sizeof path, IC_TEST_TMP "/%s.obj", name);
    snprintf(text, sizeof text, "mtllib %s.mtl\nusemtl ground\n%s", name, geometry);
    test_write_file(path, text);
    snprintf(path, sizeof path, IC_TEST_TMP "/%s.json", name);
    snprintf(text, sizeof text,
             "{\n"
             "  \"camera\": {\"eye\": [0, 1, 0], \"target\": [0, 0, 0.001], \"up\": [0, 0, -1],\n"
             "             \"fov_y\": 60, \"width\": 16, \"height\": 16},\n"
             "  \"meshes\": [{\"path\": \"%s.obj\"}],\n"
             "  \"environment\": {\"radiance\": [1, 2, 3]}\n"
             "}\n",
             name);
    test_write_file(path, text);
    ic_scene *scene = load(path);
    if (!scene) {
        CHECK(0, "%s loads", name);
        return;
    }
    ic_error err = {0};
    const double L[3] = {1.0, 2.0, 3.0}, rho = 0.5;
    ic_sensor_point pts[3] = {sensor(0, 0.5f, 0, 0, 1, 0), sensor(0, 1.0f, 0, 1, 0, 0), sensor(0, 0.5f, 0, 0, -1, 0)};
    const double expect_up[3] = {PI_D * L[0], PI_D * L[1], PI_D * L[2]};
    for (int integ = 0; integ < 2; ++integ) {
        ic_points_options opt = {0};
        opt.integrator = integ ? IC_INTEGRATOR_IC : IC_INTEGRATOR_PT;
        opt.samples = 256;
        ic_point_result res[3];
        const char *est = integ ? "ic" : "pt";
        if (ic_points_compute(scene, pts, 3, &opt, res, NULL, &err) != IC_OK) {
            CHECK(0, "%s, %s computes: %s", name, est, err.message);
            continue;
        }
        float e_up[3] = {res[0].irradiance.x, res[0].irradiance.y, res[0].irradiance.z};
        float s_up[3] = {res[0].irradiance_sigma.x, res[0].irradiance_sigma.y, res[0].irradiance_sigma.z};
        for (int c = 0; c < 3; ++c)
            CHECK(fabs(e_up[c] - expect_up[c]) <= 3.0 * s_up[c] + 2e-3 * expect_up[c],
                  "%s, %s: facing up, channel %d: E %.6g vs piL %.6g (sigma %.3g)", name, est, c, e_up[c],
                  expect_up[c], s_up[c]);
        double lux = ic_illuminance(res[0].irradiance);
        CHECK_NEAR(res[0].illuminance, lux, 1e-3 * lux, "illuminance from the irradiance");
        printf("%s, %s: facing up E = (%.5f %.5f %.5f), pi L = (%.5f %.5f %.5f), %.2f +- %.3f lux\n", name, est,
               e_up[0], e_up[1], e_up[2], expect_up[0], expect_up[1], expect_up[2], res[0].illuminance,
               res[0].illuminance_sigma);
        const double expect[3] = {0.0, PI_D * (L[1] * (1.0 + rho) / 2.0), PI_D * rho * L[1]};
        for (int i = 1; i < 3; ++i) {
            printf("%s, %s: %s E_g = %.5f +- %.4f, expected %.5f\n", name, est, i == 1 ? "sideways" : "facing down",
                   res[i].irradiance.y, res[i].irradiance_sigma.y, expect[i]);
            CHECK(fabs(res[i].irradiance.y - expect[i]) <= 4.0 * res[i].irradiance_sigma.y + 0.01 * expect[i],
                  "%s, %s: %s E %.6g vs %.6g (sigma %.3g)", name, est, i == 1 ? "sideways" : "facing down",
                  res[i].irradiance.y, expect[i], res[i].irradiance_sigma.y);
        }
    }
    if (!calibrate) {
        ic_scene_free(scene);
        return;
    }
    /* σ's calibration: each estimator's error against the closed form over 40 seeds, the sideways sensor
     * alone. The cache's σ then rests on a single record: from its half-set difference (one degree of
     * freedom) it covered the error at 2σ for 25 of 40 seeds; from repeated gathers, 39. */
    double side_lux = 179.0 * PI_D * (1.0 + rho) / 2.0 *
                      (0.265074126 * L[0] + 0.670114631 * L[1] + 0.064811243 * L[2]);
    for (int integ = 0; integ < 2; ++integ) {
        int inside = 0, inside1 = 0, seeds = 40;
        for (int k = 0; k < seeds; ++k) {
            ic_points_options opt = {0};
            opt.integrator = integ ? IC_INTEGRATOR_IC : IC_INTEGRATOR_PT;
            opt.samples = 64;
            opt.seed = (uint64_t)k + 1;
            ic_point_result res;
            if (ic_points_compute(scene, &pts[1], 1, &opt, &res, NULL, &err) != IC_OK)
                break;
            inside += fabs(res.illuminance - side_lux) < 2.0 * res.illuminance_sigma;
            inside1 += fabs(res.illuminance - side_lux) < res.illuminance_sigma;
        }
        const char *est = integ ? "ic" : "pt";
        printf("%s: sideways sensor within 2 sigma for %d of %d seeds, within 1 sigma for %d\n", est, inside, seeds,
               inside1);
        CHECK(inside >= (int)(0.85 * seeds), "%s: 2-sigma coverage %d of %d (expected about 94 %%)", est, inside,
              seeds);
    }
    ic_scene_free(scene);
}

/* Irradiance at (p, n) from a polygon of unit radiance seen unoccluded (Lambert's formula). */
static double polygon_irradiance(const ic_vec3 *v, int count, ic_vec3 p, ic_vec3 n)
{
    double sum = 0.0;
    for (int i = 0; i < count; ++i) {
        ic_vec3 a = v3_norm(v3_sub(v[i], p)), b = v3_norm(v3_sub(v[(i + 1) % count], p));
        double ang = acos(fmax(-1.0, fmin(1.0, (double)v3_dot(a, b))));
        sum += ang * v3_dot(v3_norm(v3_cross(a, b)), n);
    }
    return 0.5 * fabs(sum);
}

static void test_emitting_polygon(void)
{
    /* A 1 × 0.6 rectangle at height 1, emitting downwards (radiance 5), and nothing else. */
    test_write_file(IC_TEST_TMP "/points_lamp.mtl", "newmtl lamp\nKd 0 0 0\nKe 5 5 5\n");
    test_write_file(IC_TEST_TMP "/points_lamp.obj",
                    "mtllib points_lamp.mtl\nusemtl lamp\n"
                    "v -0.3 1 -0.2\nv 0.7 1 -0.2\nv 0.7 1 0.4\nv -0.3 1 0.4\n"
                    "f 1 2 3\nf 1 3 4\n");
    test_write_file(IC_TEST_TMP "/points_lamp.json",
                    "{\n"
                    "  \"camera\": {\"eye\": [0, 0, 3], \"target\": [0, 0.5, 0], \"up\": [0, 1, 0],\n"
                    "             \"fov_y\": 60, \"width\": 16, \"height\": 16},\n"
                    "  \"meshes\": [{\"path\": \"points_lamp.obj\"}]\n"
                    "}\n");
    ic_scene *scene = load(IC_TEST_TMP "/points_lamp.json");
    if (!scene) {
        CHECK(0, "lamp scene loads");
        return;
    }
    ic_vec3 quad[4] = {{-0.3f, 1, -0.2f}, {0.7f, 1, -0.2f}, {0.7f, 1, 0.4f}, {-0.3f, 1, 0.4f}};
    ic_sensor_point pts[2] = {sensor(0, 0, 0, 0, 1, 0), sensor(0.5f, 0.4f, 0.8f, 0, 0.6f, -0.8f)};
    ic_error err = {0};
    for (int integ = 0; integ < 2; ++integ) {
        ic_points_options opt = {0};
        opt.integrator = integ ? IC_INTEGRATOR_IC : IC_INTEGRATOR_PT;
        ic_point_result res[2];
        if (ic_points_compute(scene, pts, 2, &opt, res, NULL, &err) != IC_OK) {
            CHECK(0, "lamp computes: %s", err.message);
            continue;
        }
        for (int i = 0; i < 2; ++i) {
            ic_vec3 nn = v3_norm(pts[i].normal);
            double expect = 5.0 * polygon_irradiance(quad, 4, pts[i].position, nn);
            printf("%s: lamp point %d: E = %.5f +- %.5f, Lambert %.5f\n", integ ? "ic" : "pt", i, res[i].irradiance.x,
                   res[i].irradiance_sigma.x, expect);
            CHECK(fabs(res[i].irradiance.x - expect) <= 4.0 * res[i].irradiance_sigma.x + 0.005 * expect,
                  "%s point %d: E %.6g vs Lambert %.6g (sigma %.3g)", integ ? "ic" : "pt", i, res[i].irradiance.x,
                  expect, res[i].irradiance_sigma.x);
        }
    }
    ic_scene_free(scene);
}

/* Sky light is never interpolated between sensors: a black 0.2 m square 0.3 m above a row of upward
 * sensors 2 cm apart (on a black ground, so there is no indirect light) casts its shadow on the sky:
 * E = L (π − P), P the square's projected solid angle by Lambert's formula. The records the sensors share
 * hold no sky light (their rays' sky is left to each sensor's own samples); when they held it, all 31
 * sensors shared one record, and the sensors away from it took its shadowed sky (14 % off at the worst
 * sensor, 27 σ). */
static void test_sky_shadow(void)
{
    test_write_file(IC_TEST_TMP "/points_shade.mtl", "newmtl black\nKd 0 0 0\n");
    test_write_file(IC_TEST_TMP "/points_shade.obj",
                    "mtllib points_shade.mtl\nusemtl black\n"
                    "v -100 0 -100\nv 100 0 -100\nv 100 0 100\nv -100 0 100\n"
                    "v -0.1 0.35 -0.1\nv 0.1 0.35 -0.1\nv 0.1 0.35 0.1\nv -0.1 0.35 0.1\n"
                    "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\n");
    test_write_file(IC_TEST_TMP "/points_shade.json",
                    "{\n"
                    "  \"camera\": {\"eye\": [0, 1, 0], \"target\": [0, 0, 0.001], \"up\": [0, 0, -1],\n"
                    "             \"fov_y\": 60, \"width\": 16, \"height\": 16},\n"
                    "  \"meshes\": [{\"path\": \"points_shade.obj\"}],\n"
                    "  \"environment\": {\"radiance\": [1, 1, 1]}\n"
                    "}\n");
    ic_scene *scene = load(IC_TEST_TMP "/points_shade.json");
    if (!scene) {
        CHECK(0, "shade scene loads");
        return;
    }
    enum { N = 31 };
    ic_sensor_point pts[N];
    for (int i = 0; i < N; ++i)
        pts[i] = sensor(-0.3f + 0.02f * (float)i, 0.05f, 0.0f, 0, 1, 0);
    const ic_vec3 square[4] = {{-0.1f, 0.35f, -0.1f}, {0.1f, 0.35f, -0.1f}, {0.1f, 0.35f, 0.1f}, {-0.1f, 0.35f, 0.1f}};
    ic_points_options opt = {0};
    opt.integrator = IC_INTEGRATOR_IC;
    ic_point_result res[N];
    ic_points_stats st;
    ic_error err = {0};
    if (ic_points_compute(scene, pts, N, &opt, res, &st, &err) != IC_OK) {
        CHECK(0, "shade computes: %s", err.message);
        ic_scene_free(scene);
        return;
    }
    double worst = 0.0, worst_sigmas = 0.0;
    for (int i = 0; i < N; ++i) {
        double expect = PI_D - polygon_irradiance(square, 4, pts[i].position, pts[i].normal);
        double e = res[i].irradiance.y, sg = res[i].irradiance_sigma.y;
        worst = fmax(worst, fabs(e - expect) / expect);
        worst_sigmas = fmax(worst_sigmas, fabs(e - expect) / sg);
        CHECK(fabs(e - expect) <= 4.0 * sg + 1e-3 * expect, "sensor %d (x %.2f): E %.6g, Lambert %.6g (sigma %.3g)", i,
              (double)pts[i].position.x, e, expect, sg);
    }
    printf("sky shadow: %u records for %d sensors; worst error %.3f %% (%.1f sigma)\n", st.records, N, 100.0 * worst,
           worst_sigmas);
    CHECK(st.records < N, "the sensors share records (%u for %d)", st.records, N);
    ic_scene_free(scene);
}

/* The sky through a portal, sampled at each sensor: a black 2 m cube whose ceiling has a 1 m square hole,
 * declared as a portal, under a uniform sky (L = 1): an upward sensor inside receives E = P, the hole's
 * projected solid angle by Lambert's formula, and nothing else (black walls: no indirect light). */
static void test_sky_portal(void)
{
    test_write_file(IC_TEST_TMP "/points_skylight.mtl", "newmtl black\nKd 0 0 0\n");
    /* Floor, four walls and the ceiling around the hole x, z in [0.5, 1.5]. */
    test_write_file(IC_TEST_TMP "/points_skylight.obj",
                    "mtllib points_skylight.mtl\nusemtl black\n"
                    "v 0 0 0\nv 2 0 0\nv 2 0 2\nv 0 0 2\nv 0 2 0\nv 2 2 0\nv 2 2 2\nv 0 2 2\n"
                    "v 0.5 2 0.5\nv 1.5 2 0.5\nv 1.5 2 1.5\nv 0.5 2 1.5\n"
                    "f 1 2 3 4\nf 1 5 6 2\nf 2 6 7 3\nf 3 7 8 4\nf 4 8 5 1\n"
                    "f 5 9 10 6\nf 6 10 11 7\nf 7 11 12 8\nf 8 12 9 5\n");
    test_write_file(IC_TEST_TMP "/points_skylight.json",
                    "{\n"
                    "  \"camera\": {\"eye\": [1, 1, 1.9], \"target\": [1, 1, 0], \"up\": [0, 1, 0],\n"
                    "             \"fov_y\": 60, \"width\": 16, \"height\": 16},\n"
                    "  \"meshes\": [{\"path\": \"points_skylight.obj\"}],\n"
                    "  \"environment\": {\"radiance\": [1, 1, 1],\n"
                    "    \"portals\": [[[0.5, 2, 0.5], [1.5, 2, 0.5], [1.5, 2, 1.5], [0.5, 2, 1.5]]]}\n"
                    "}\n");
    ic_scene *scene = load(IC_TEST_TMP "/points_skylight.json");
    if (!scene) {
        CHECK(0, "skylight scene loads");
        return;
    }
    const ic_vec3 hole[4] = {{0.5f, 2, 0.5f}, {1.5f, 2, 0.5f}, {1.5f, 2, 1.5f}, {0.5f, 2, 1.5f}};
    ic_sensor_point pts[4] = {sensor(1, 0.5f, 1, 0, 1, 0), sensor(0.3f, 0.8f, 0.4f, 0, 1, 0),
                              sensor(1.7f, 1.2f, 1.2f, 0, 1, 0), sensor(0.2f, 1.0f, 1.0f, 1, 0, 0)};
    ic_points_options opt = {0};
    opt.integrator = IC_INTEGRATOR_IC;
    ic_point_result res[4];
    ic_error err = {0};
    if (ic_points_compute(scene, pts, 4, &opt, res, NULL, &err) != IC_OK) {
        CHECK(0, "skylight computes: %s", err.message);
        ic_scene_free(scene);
        return;
    }
    for (int i = 0; i < 4; ++i) {
        double expect = polygon_irradiance(hole, 4, pts[i].position, pts[i].normal);
        double e = res[i].irradiance.y, sg = res[i].irradiance_sigma.y;
        printf("skylight sensor %d: E = %.5f +- %.5f, Lambert %.5f\n", i, e, sg, expect);
        CHECK(fabs(e - expect) <= 4.0 * sg + 2e-3 * expect, "skylight sensor %d: E %.6g, Lambert %.6g (sigma %.3g)", i,
              e, expect, sg);
    }
    ic_scene_free(scene);
}

/* A closed furnace: inside a sphere with albedo 0.5 and emission 0.5 everywhere, radiance is
 * L = Le / (1 − ρ) = 1 in every direction, so any sensor receives E = π, all bounces summed. */
static void test_furnace(void)
{
    test_write_file(IC_TEST_TMP "/points_furnace.mtl", "newmtl glow\nKd 0.5 0.5 0.5\nKe 0.5 0.5 0.5\n");
    test_write_inward_sphere(IC_TEST_TMP "/points_furnace.obj", "points_furnace.mtl", "glow", 1.0f, 48, 24);
    test_write_file(IC_TEST_TMP "/points_furnace.json",
                    "{\n"
                    "  \"camera\": {\"eye\": [0.1, 0.05, 0.02], \"target\": [1, 0.2, 0.3], \"up\": [0, 1, 0],\n"
                    "             \"fov_y\": 90, \"width\": 16, \"height\": 16},\n"
                    "  \"meshes\": [{\"path\": \"points_furnace.obj\"}]\n"
                    "}\n");
    ic_scene *scene = load(IC_TEST_TMP "/points_furnace.json");
    if (!scene) {
        CHECK(0, "furnace loads");
        return;
    }
    ic_sensor_point pts[3] = {sensor(0, 0, 0, 0, 1, 0), sensor(0.3f, -0.2f, 0.1f, 1, 1, 0),
                              sensor(-0.5f, 0.4f, 0.2f, 0, 0, -1)};
    ic_error err = {0};
    for (int integ = 0; integ < 2; ++integ) {
        ic_points_options opt = {0};
        opt.integrator = integ ? IC_INTEGRATOR_IC : IC_INTEGRATOR_PT;
        opt.max_depth = 64; /* truncation leaves 0.5^64 of E */
        ic_point_result res[3];
        if (ic_points_compute(scene, pts, 3, &opt, res, NULL, &err) != IC_OK) {
            CHECK(0, "furnace computes: %s", err.message);
            continue;
        }
        for (int i = 0; i < 3; ++i) {
            printf("%s: furnace point %d: E = %.5f +- %.5f, expected pi\n", integ ? "ic" : "pt", i,
                   res[i].irradiance.y, res[i].irradiance_sigma.y);
            /* The sphere's 2,208 flat facets hold a little less than the unit sphere's volume: 1 % slack. */
            CHECK(fabs(res[i].irradiance.y - PI_D) <= 4.0 * res[i].irradiance_sigma.y + 0.01 * PI_D,
                  "%s furnace point %d: E %.6g vs pi (sigma %.3g)", integ ? "ic" : "pt", i, res[i].irradiance.y,
                  res[i].irradiance_sigma.y);
        }
    }
    ic_scene_free(scene);
}

/* What the progress callback saw: the phases in the order first seen, every share, the last call. */
typedef struct progress_log {
    const char *phases[8];
    int n_phases, calls, bad_share;
    const char *last_phase;
    double last_share;
} progress_log;

static void log_progress(void *user, const char *phase, double fraction)
{
    progress_log *l = user;
    if (!l->last_phase || strcmp(l->last_phase, phase) != 0) {
        int seen = 0;
        for (int k = 0; k < l->n_phases; ++k)
            seen |= strcmp(l->phases[k], phase) == 0;
        if (!seen && l->n_phases < 8)
            l->phases[l->n_phases++] = phase;
    }
    /* a share in [0, 1], or −1 where the library cannot say (the hit stage) */
    if (!((fraction >= 0.0 && fraction <= 1.0) || (fraction == -1.0 && strcmp(phase, "hit records") == 0)))
        l->bad_share = 1;
    ++l->calls;
    l->last_phase = phase;
    l->last_share = fraction;
}

/* Progress reports change nothing and end with every sensor estimated: the phases in their order. */
static void check_progress(const char *what, const progress_log *l, const char *const *want, int n_want)
{
    int order = l->n_phases == n_want;
    for (int k = 0; order && k < n_want; ++k)
        order = strcmp(l->phases[k], want[k]) == 0;
    CHECK(order && !l->bad_share && l->last_phase && strcmp(l->last_phase, "sensors") == 0 && l->last_share == 1.0,
          "%s progress: %d phases (first %s), %d calls, a share out of range %d, last %s %g", what, l->n_phases,
          l->n_phases ? l->phases[0] : "none", l->calls, l->bad_share, l->last_phase ? l->last_phase : "none",
          l->last_share);
}

static void test_cornell(void)
{
    ic_scene *scene = load(IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json");
    if (!scene) {
        CHECK(0, "Cornell box loads");
        return;
    }
    enum { N = 5 };
    ic_sensor_point pts[N] = {sensor(-0.7f, 0.8f, 0.6f, 0, 1, 0), sensor(0.7f, 0.8f, 0.7f, 0, 1, 0),
                              sensor(-0.98f, 1.0f, 0.0f, 1, 0, 0), sensor(0.0f, 1.9f, 0.5f, 0, -1, 0),
                              sensor(0.0f, 0.3f, 0.9f, 0, 0, -1)};
    ic_point_result pt[N], ic[N], ic2[N], pt2[N];
    ic_error err = {0};
    ic_points_options opt = {0};
    opt.samples = 2048;
    opt.threads = 1;
    ic_points_stats st_pt, st_ic;
    int ok = ic_points_compute(scene, pts, N, &opt, pt, &st_pt, &err) == IC_OK;
    CHECK(ok, "Cornell pt: %s", err.message);
    opt.threads = 2;
    progress_log pt_log = {0};
    opt.progress = log_progress;
    opt.progress_user = &pt_log;
    ok = ok && ic_points_compute(scene, pts, N, &opt, pt2, NULL, &err) == IC_OK;
    CHECK(ok && memcmp(pt, pt2, sizeof pt) == 0, "pt: 1 and 2 threads identical");
    const char *const pt_phases[] = {"sensors"};
    check_progress("pt", &pt_log, pt_phases, 1);
    opt.progress = NULL;
    opt.integrator = IC_INTEGRATOR_IC;
    opt.threads = 1;
    ok = ok && ic_points_compute(scene, pts, N, &opt, ic, &st_ic, &err) == IC_OK;
    CHECK(ok, "Cornell ic: %s", err.message);
    opt.threads = 2;
    progress_log ic_log = {0};
    opt.progress = log_progress;
    opt.progress_user = &ic_log;
    ok = ok && ic_points_compute(scene, pts, N, &opt, ic2, NULL, &err) == IC_OK;
    CHECK(ok && memcmp(ic, ic2, sizeof ic) == 0, "ic: 1 and 2 threads identical");
    const char *const ic_phases[] = {"hit records", "sensor records", "sensors"};
    check_progress("ic", &ic_log, ic_phases, 3);
    opt.progress = NULL;
    /* The default gathering grid given as zero (above) and spelled out are one grid: the hit records get
     * the same fraction of it (they once took the sensors' whole grid when it was left at zero). */
    ic_gather_opts grid;
    ic_gather_opts_default(&grid);
    opt.ic.gather.theta_strata = grid.theta_strata;
    opt.ic.gather.phi_strata = (uint32_t)lround(3.14159265358979 * grid.theta_strata);
    ic_points_stats st_explicit;
    ok = ok && ic_points_compute(scene, pts, N, &opt, ic2, &st_explicit, &err) == IC_OK;
    CHECK(ok && memcmp(ic, ic2, sizeof ic) == 0 && st_explicit.rays == st_ic.rays &&
              st_explicit.hit_records == st_ic.hit_records,
          "ic: the default grid and the same grid given explicitly agree (rays %llu vs %llu)",
          (unsigned long long)st_ic.rays, (unsigned long long)st_explicit.rays);
    opt.ic.gather.theta_strata = opt.ic.gather.phi_strata = 0;
    if (!ok) {
        ic_scene_free(scene);
        return;
    }
    printf("Cornell: pt %.3f s, %llu rays; ic %.3f s, %llu rays, %u records\n", st_pt.seconds,
           (unsigned long long)st_pt.rays, st_ic.seconds, (unsigned long long)st_ic.rays, st_ic.records);
    for (int i = 0; i < N; ++i) {
        double d = ic[i].illuminance - pt[i].illuminance;
        double s = sqrt(ic[i].illuminance_sigma * ic[i].illuminance_sigma +
                        pt[i].illuminance_sigma * pt[i].illuminance_sigma);
        printf("Cornell point %d: pt %.3f +- %.3f lux, ic %.3f +- %.3f lux, difference %.2f sigma\n", i,
               pt[i].illuminance, pt[i].illuminance_sigma, ic[i].illuminance, ic[i].illuminance_sigma,
               s > 0.0 ? d / s : 0.0);
        CHECK(pt[i].illuminance > 0.0, "point %d is lit", i);
        /* σ leaves the interpolation bias out: allow 2 % of the value on top of 3σ. */
        CHECK(fabs(d) <= 3.0 * s + 0.02 * pt[i].illuminance, "point %d: ic %.4g vs pt %.4g lux (sigma %.3g)", i,
              ic[i].illuminance, pt[i].illuminance, s);
    }
    ic_scene_free(scene);
}

/* The cache's σ against a path-traced reference on a work plane, and records shared on a dense one. */
static void test_cornell_grid(void)
{
    ic_scene *scene = load(IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json");
    if (!scene)
        return;
    enum { G = 8, DENSE = 30 };
    static ic_sensor_point pts[DENSE * DENSE];
    static ic_point_result ref[G * G], ic[DENSE * DENSE];
    for (int i = 0; i < G * G; ++i)
        pts[i] = sensor(-0.85f + 1.7f * (float)(i % G) / (G - 1), 1.4f, -0.85f + 1.7f * (float)(i / G) / (G - 1), 0,
                        1, 0);
    ic_error err = {0};
    ic_points_options opt = {0};
    opt.samples = 8192;
    int ok = ic_points_compute(scene, pts, G * G, &opt, ref, NULL, &err) == IC_OK;
    opt.integrator = IC_INTEGRATOR_IC;
    ok = ok && ic_points_compute(scene, pts, G * G, &opt, ic, NULL, &err) == IC_OK;
    CHECK(ok, "grid: %s", err.message);
    int inside = 0;
    double rel = 0.0;
    for (int i = 0; ok && i < G * G; ++i) {
        double s = sqrt(ic[i].illuminance_sigma * ic[i].illuminance_sigma +
                        ref[i].illuminance_sigma * ref[i].illuminance_sigma);
        inside += fabs(ic[i].illuminance - ref[i].illuminance) < 2.0 * s;
        rel += fabs(ic[i].illuminance - ref[i].illuminance) / ref[i].illuminance / (G * G);
    }
    printf("Cornell 8x8 grid: cache within 2 sigma of the reference at %d of %d points, mean error %.2f %%\n", inside,
           G * G, 100.0 * rel);
    CHECK(inside >= (int)(0.8 * G * G), "cache within 2 sigma at %d of %d points (expected about 95 %%)", inside, G * G);
    CHECK(rel < 0.05, "mean relative error %.3f", rel);
    /* 3 cm apart, the sensors share records. */
    for (int i = 0; i < DENSE * DENSE; ++i)
        pts[i] = sensor(-0.435f + 0.87f * (float)(i % DENSE) / (DENSE - 1), 1.4f,
                        -0.435f + 0.87f * (float)(i / DENSE) / (DENSE - 1), 0, 1, 0);
    ic_points_stats st;
    opt.light_samples = 16;
    opt.threads = 1;
    CHECK(ic_points_compute(scene, pts, DENSE * DENSE, &opt, ic, &st, &err) == IC_OK, "dense grid: %s", err.message);
    static ic_point_result ic2[DENSE * DENSE];
    opt.threads = 2;
    CHECK(ic_points_compute(scene, pts, DENSE * DENSE, &opt, ic2, NULL, &err) == IC_OK &&
              memcmp(ic, ic2, sizeof ic2) == 0,
          "dense grid (several construction passes): 1 and 2 threads identical");
    printf("Cornell %dx%d grid: %u records\n", DENSE, DENSE, st.records);
    CHECK(st.records > 0 && st.records < DENSE * DENSE / 2, "records shared: %u for %d points", st.records,
          DENSE * DENSE);
    ic_scene_free(scene);
}

static void test_bad_points(void)
{
    ic_scene *scene = load(IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json");
    if (!scene)
        return;
    ic_sensor_point pts[2] = {sensor(0, 1, 0, 0, 1, 0), sensor(0, 1, 0, 0, 0, 0)};
    ic_point_result res[2];
    ic_error err = {0};
    CHECK(ic_points_compute(scene, pts, 2, NULL, res, NULL, &err) == IC_ERR_INVALID_ARG, "zero normal refused");
    CHECK(strstr(err.message, "sensor points[1] (0-based): its normal is zero") != NULL, "message names the point: %s",
          err.message);
    /* Beyond 1e18 the ray tracer cannot start rays (it asserted); a tiny or a huge normal is a direction. */
    pts[1] = sensor(2e18f, 1, 0, 0, 1, 0);
    CHECK(ic_points_compute(scene, pts, 2, NULL, res, NULL, &err) == IC_ERR_INVALID_ARG &&
              strstr(err.message, "sensor points[1] (0-based): a position coordinate lies beyond 1e18"),
          "a position beyond 1e18 refused: %s", err.message);
    ic_points_options small = {0};
    small.samples = 16;
    pts[1] = sensor(0, 1, 0, 0, 1e-40f, 0);
    pts[0] = sensor(0, 1, 0, 0, 3e38f, 3e38f);
    CHECK(ic_points_compute(scene, pts, 2, &small, res, NULL, &err) == IC_OK, "tiny and huge normals: %s",
          err.message);
    CHECK(isfinite(res[0].illuminance) && isfinite(res[1].illuminance) && res[1].illuminance > 0.0,
          "their results are finite: %g, %g", res[0].illuminance, res[1].illuminance);
    /* Fewer samples than replicates: still IC_POINT_REPLICATES of them, so that σ is an estimate. */
    small.samples = 1;
    pts[0] = sensor(0, 1, 0, 0, 1, 0);
    CHECK(ic_points_compute(scene, pts, 1, &small, res, NULL, &err) == IC_OK && res[0].illuminance_sigma > 0.0,
          "one sample asked: 16 taken, sigma %g > 0", res[0].illuminance_sigma);
    pts[0] = sensor(0, 1, 0, 0, 1, 0);
    pts[1] = sensor(0, 1, 0, 0, 0, 0);
    ic_points_options opt = {0};
    opt.samples = -1;
    CHECK(ic_points_compute(scene, pts, 1, &opt, res, NULL, &err) == IC_ERR_INVALID_ARG, "negative samples refused");
    opt.samples = 16;
    opt.threads = IC_MAX_THREADS + 1;
    CHECK(ic_points_compute(scene, pts, 1, &opt, res, NULL, &err) == IC_ERR_INVALID_ARG,
          "threads above IC_MAX_THREADS: %s", ic_result_name(err.code));
    opt.threads = 0;
    CHECK(ic_points_compute(scene, pts, 0, NULL, NULL, NULL, &err) == IC_OK, "no points: nothing to do");
    opt.samples = 0;
    opt.integrator = IC_INTEGRATOR_IC;
    opt.max_depth = 1;
    CHECK(ic_points_compute(scene, pts, 1, &opt, res, NULL, &err) == IC_ERR_INVALID_ARG,
          "the cache refuses max depth 1 (direct light only), which the path tracer serves");
    opt.integrator = IC_INTEGRATOR_PT;
    opt.samples = 16;
    CHECK(ic_points_compute(scene, pts, 1, &opt, res, NULL, &err) == IC_OK, "pt: max depth 1: %s", err.message);
    ic_scene_free(scene);
}

/* ic_points_grid: whole cells centred in the floor area, at y0 + height, facing up; bad boxes refused. */
static void test_grid(void)
{
    ic_error err = {0};
    ic_points_grid_spec g = {{0.0f, 1.0f, -2.0f}, {4.0f, 4.0f, 1.0f}, 1.0, 0.8};
    ic_sensor_point *p = NULL;
    uint32_t cols = 0, rows = 0;
    CHECK(ic_points_grid(&g, &p, &cols, &rows, &err) == IC_OK && cols == 4 && rows == 3, "4 x 3 m at 1 m: 4 x 3 (%u x %u)",
          cols, rows);
    int bad = 0;
    for (uint32_t r = 0; p && r < rows; ++r)
        for (uint32_t c = 0; c < cols; ++c) {
            const ic_sensor_point *s = &p[r * cols + c];
            bad += fabsf(s->position.x - (0.5f + (float)c)) > 1e-6f || fabsf(s->position.y - 1.8f) > 1e-6f ||
                   fabsf(s->position.z - (-1.5f + (float)r)) > 1e-6f || s->normal.y != 1.0f || s->normal.x != 0.0f ||
                   s->normal.z != 0.0f;
        }
    CHECK(bad == 0, "cell centres at y0 + height, facing up, row by row in z (%d wrong)", bad);
    free(p);
    /* 4.2 × 1.1 at 1 m: 4 × 1 whole cells, centred (margins 0.6 and 0.55) */
    ic_points_grid_spec g2 = {{0.0f, 0.0f, 0.0f}, {4.2f, 3.0f, 1.1f}, 1.0, 0.8};
    CHECK(ic_points_grid(&g2, &p, &cols, &rows, &err) == IC_OK && cols == 4 && rows == 1, "4.2 x 1.1: 4 x 1");
    CHECK(p && fabsf(p[0].position.x - 0.6f) < 1e-5f && fabsf(p[3].position.x - 3.6f) < 1e-5f &&
              fabsf(p[0].position.z - 0.55f) < 1e-5f,
          "centred: first x 0.6, last 3.6, z 0.55");
    free(p);
    /* Sides that are whole numbers of cells as written, whose float corners fall short of it (0.7 is
     * 0.69999999 as a float): every cell counted, e.g. 7 x 7 at 0.1 m over 0.7 x 0.7 m, not 6 x 6. */
    int short_sides = 0;
    for (int k = 1; k <= 60; ++k) {
        ic_points_grid_spec gk = {{0.0f, 0.0f, -1.3f}, {(float)(k / 10.0), 3.0f, (float)(-1.3 + k / 10.0)}, 0.1, 0.8};
        short_sides += (double)gk.hi.x < k / 10.0;
        p = NULL;
        int ok = ic_points_grid(&gk, &p, &cols, &rows, &err) == IC_OK && cols == (uint32_t)k && rows == (uint32_t)k;
        CHECK(ok, "%.1f x %.1f m at 0.1 m: %d x %d cells (%u x %u)", k / 10.0, k / 10.0, k, k, cols, rows);
        /* centred: the first and last centres half a cell from the sides */
        CHECK(p && fabsf(p[0].position.x - 0.05f) < 1e-5f && fabsf(p[cols - 1].position.x - (float)(k / 10.0 - 0.05)) < 1e-5f,
              "%.1f m: centres half a cell in", k / 10.0);
        free(p);
    }
    CHECK(short_sides > 10, "the case is tested: %d of the sides fall short as floats", short_sides);
    /* The plane at the box's top is in the box (y0 + height <= y1), as written: 1.9 m in a box 1.9 m high
     * (the float top 1.89999998 once refused the double 1.9). */
    ic_points_grid_spec top = {{-1.0f, 0.0f, -1.0f}, {1.0f, 1.9f, 1.0f}, 0.5, 1.9};
    p = NULL;
    CHECK(ic_points_grid(&top, &p, &cols, &rows, &err) == IC_OK && cols == 4 && rows == 4 && p &&
              p[0].position.y == 1.9f,
          "a plane at the box's top: %s", err.message);
    free(p);
    CHECK(ic_points_grid(NULL, &p, &cols, &rows, &err) == IC_ERR_INVALID_ARG &&
              ic_points_grid(&top, NULL, &cols, &rows, &err) == IC_ERR_INVALID_ARG,
          "NULL spec or result refused, not a crash");
    ic_points_grid_spec bad_specs[] = {
        {{0, 0, 0}, {4, 3, 4}, 0.0, 0.8},   /* zero spacing */
        {{0, 0, 0}, {4, 3, 4}, 5.0, 0.8},   /* no whole cell */
        {{0, 0, 0}, {4, 0.5f, 4}, 1.0, 0.8}, /* plane above the box */
        {{4, 0, 0}, {0, 3, 4}, 1.0, 0.8},   /* x0 > x1 */
        {{0, 0, 0}, {1e6f, 3, 1e6f}, 1e-2, 0.8}, /* 10^16 points */
        {{0, 0, 0}, {4, 3, 4}, 1.0, -1.0},  /* negative height */
    };
    for (size_t k = 0; k < sizeof bad_specs / sizeof bad_specs[0]; ++k) {
        p = NULL;
        CHECK(ic_points_grid(&bad_specs[k], &p, &cols, &rows, &err) == IC_ERR_INVALID_ARG && !p && strstr(err.message, "grid"),
              "bad grid %zu refused: %s", k, err.message);
    }
}

/* A record is not read through a surface: sensors half a millimetre under the Cornell box's floor (facing
 * up, at its underside: no light reaches them) read the records of the sensors above it, which the weights
 * accept, until the look-up tested that each record is in view of the point: those half a millimetre above
 * the floor gave 10.96 and 14.30 lux (the path tracer: 0); and those on the floor itself (y = 0, a
 * calculation grid at floor level) 10.28 and 15.74 lux while the ray's ends were moved off the floor
 * towards each other, which took the record's end under the floor. */
static void test_thin_surface(void)
{
    ic_scene *scene = load(IC_SOURCE_DIR "/scenes/cornell-box/cornell-box.json");
    if (!scene)
        return;
    enum { N = 4 };
    const float above[2] = {5e-4f, 0.0f};
    for (int a = 0; a < 2; ++a) {
        const ic_sensor_point pts[N] = {sensor(0.0f, above[a], 0.8f, 0, 1, 0), sensor(0.0f, -5e-4f, 0.8f, 0, 1, 0),
                                        sensor(-0.7f, above[a], 0.0f, 0, 1, 0), sensor(-0.7f, -5e-4f, 0.0f, 0, 1, 0)};
        ic_point_result res[N];
        ic_points_options opt = {0};
        opt.integrator = IC_INTEGRATOR_IC;
        ic_error err = {0};
        int ok = ic_points_compute(scene, pts, N, &opt, res, NULL, &err) == IC_OK;
        CHECK(ok, "thin surface: %s", err.message);
        for (int i = 0; ok && i < N; i += 2) {
            printf("thin surface: at y = %g %.4g lux, under the floor %.4g lux\n", (double)above[a], res[i].illuminance,
                   res[i + 1].illuminance);
            CHECK(res[i].illuminance > 5.0, "sensor %d at y = %g is lit (%.4g lux)", i, (double)above[a],
                  res[i].illuminance);
            CHECK(res[i + 1].illuminance < 1e-3 * res[i].illuminance, "sensor %d under the floor reads %.4g lux from "
                  "y = %g (the path tracer: 0)", i + 1, res[i + 1].illuminance, (double)above[a]);
        }
    }
    ic_scene_free(scene);
}

int main(void)
{
    test_grid();
    test_illuminance_convention();
    test_open_plane("points_plane", "v -1000 0 -1000\nv 1000 0 -1000\nv 1000 0 1000\nv -1000 0 1000\nf 1 3 2\nf 1 4 3\n", 1);
    /* one triangle 2e12 across, whose |e1 × e2|² overflows a float: it was dropped as zero area */
    test_open_plane("points_big", "v -1e12 0 -1e12\nv 1e12 0 -1e12\nv 0 0 1e12\nf 1 3 2\n", 0);
    test_emitting_polygon();
    test_sky_shadow();
    test_sky_portal();
    test_furnace();
    test_cornell();
    test_cornell_grid();
    test_thin_surface();
    test_bad_points();
    TEST_MAIN_END();
}
