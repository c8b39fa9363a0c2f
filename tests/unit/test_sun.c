/*
 * test_sun.c — the sun of a clear or Perez sky as a disc (scene.h ic_sun_light, lights.c) and the sky's
 * rotation about the up axis (sky.h), against closed forms:
 *   1. the disc: angular radius 0.2665°, solid angle 2π(1 − cos a) ≈ 6.80e-5 sr, radiance E_dn/(π sin² a)
 *      (so radiance × solid angle = E_dn to O(a²)); radiance inside the disc, none outside; pdf × solid
 *      angle = 1; gensky's default sun's irradiance for "direct_normal": "gensky";
 *   2. light sampling of the disc alone (a rank-1 lattice over the square): a plane facing the sun gets
 *      E_dn, a horizontal one E_dn cos Z_s, one edge-on to the sun E_dn · 2a/(3π) (half the disc, whose
 *      cosine grows linearly across it);
 *   3. through the renderer (`ic_points_compute`, path tracer and cache): sensors facing the sun and
 *      facing north, east, south and west on an open plane get the sky's irradiance (quadrature of the
 *      sky and the lit ground) plus E_dn max(0, n·s), within 3σ;
 *   4. rotation: "rotation_deg": 90 turns the sun and every sky radiance by 90° about +y (right-handed),
 *      and the vertical sensors' irradiances move round with it;
 *   5. a sun light of 20° angular radius (light sampling and the sensor's cosine path both find it, so
 *      the MIS weights matter): sensors facing it, tilted, and edge-on get the closed forms; a glossy
 *      floor under a 10° disc renders to the same mean with the path tracer and the cache;
 *   6. 1 and 2 threads give identical results: points (both estimators) and images (both integrators) of a
 *      glossy floor that reflects the disc, which the camera also sees directly.
 */
#include "test_util.h"

#include "test_render_util.h"

#include "irrcache/points.h"
#include "irrcache/render.h"
#include "scene/scene.h"

#include <string.h>

#define PI_D 3.14159265358979323846

static const char *plane_obj = "mtllib sun_plane.mtl\nusemtl ground\n"
                               "v -1000 0 -1000\nv 1000 0 -1000\nv 1000 0 1000\nv -1000 0 1000\n"
                               "f 1 3 2\nf 1 4 3\n";

/* Loads the open plane (diffuse, glossy, or black) with the given further members of the scene object
 * (environment, camera, lights); NULL (and err) on failure. */
enum { DIFFUSE, GLOSSY, BLACK };
static ic_scene *load_sun(const char *members, int material, ic_error *err)
{
    static const char *const mtl[3] = {"newmtl ground\nKd 0.5 0.5 0.5\n",
                                       "newmtl ground\nKd 0.3 0.3 0.3\nKs 0.2 0.2 0.2\nNs 60\n",
                                       "newmtl ground\nKd 0 0 0\n"};
    test_write_file(IC_TEST_TMP "/sun_plane.mtl", mtl[material]);
    test_write_file(IC_TEST_TMP "/sun_plane.obj", plane_obj);
    char text[2048];
    snprintf(text, sizeof text, "{\n  \"meshes\": [{\"path\": \"sun_plane.obj\"}],\n  %s\n}\n", members);
    test_write_file(IC_TEST_TMP "/sun_scene.json", text);
    ic_scene *scene;
    test_load_scene(IC_TEST_TMP "/sun_scene.json", NULL, 24, 16, 0, &scene, err);
    return scene;
}

/* load_sun for a test that needs the scene: failing to load is a failed check, named what. */
static ic_scene *load_sun_checked(const char *members, int material, const char *what)
{
    ic_error err = {0};
    ic_scene *s = load_sun(members, material, &err);
    CHECK(s != NULL, "%s: %s", what, err.message);
    return s;
}

/* Options of the sensor-point computation with the cache (is_ic) or the path tracer, samples a sensor. */
static ic_points_options points_options(int is_ic, int samples)
{
    ic_points_options opt = {0};
    opt.integrator = is_ic ? IC_INTEGRATOR_IC : IC_INTEGRATOR_PT;
    opt.samples = samples;
    return opt;
}

/* The Perez sky of these tests: the sun 35° up, 30° from north towards east (north is −z). */
#define PEREZ_SKY(extra)                                                                                       \
    "\"environment\": {\"sky\": \"perez\", \"diffuse_horizontal\": 110, \"direct_normal\": 650, "                            \
    "\"sun_direction\": [0.40957602214449591, 0.57357643635104605, -0.70940647991358361]" extra "}"

static const double edn = 650.0;

/* ∫ L(d) max(0, n·d) dω of the environment above the horizon, plus the lit ground below it (radiance
 * ground_radiance: a white-ish Lambertian plane under the sky and sun), by the midpoint rule in (cos θ, φ)
 * over the whole sphere. */
static double sky_irradiance(const ic_scene *s, ic_vec3 n, double ground_radiance)
{
    enum { NM = 600, NP = 1200 };
    double sum = 0.0;
    for (int i = 0; i < NM; ++i) {
        double mu = -1.0 + 2.0 * (i + 0.5) / NM, st = sqrt(1.0 - mu * mu);
        for (int k = 0; k < NP; ++k) {
            double phi = 2.0 * PI_D * (k + 0.5) / NP;
            ic_vec3 d = {(float)(st * cos(phi)), (float)mu, (float)(st * sin(phi))};
            double c = (double)v3_dot(n, d);
            if (c > 0.0)
                sum += (mu > 0.0 ? (double)ic_scene_env_radiance(s, d).y : ground_radiance) * c;
        }
    }
    return sum * (2.0 / NM) * (2.0 * PI_D / NP);
}

static void test_disc(void)
{
    ic_scene *s = load_sun_checked(PEREZ_SKY(""), DIFFUSE, "perez with sun loads");
    if (!s)
        return;
    const ic_sun_light *sun = &s->sun;
    double a = 0.2665 * PI_D / 180.0, omega = 2.0 * PI_D * (1.0 - cos(a));
    printf("disc: radius %.6f rad, solid angle %.4e sr, radiance %.6e W/(m2 sr), radiance x solid angle %.4f\n",
           (double)sun->angular_radius, (double)sun->solid_angle, (double)sun->radiance.y,
           (double)sun->radiance.y * sun->solid_angle);
    CHECK_NEAR(sun->angular_radius, a, 1e-9, "angular radius 0.2665 degrees");
    CHECK_NEAR(sun->solid_angle, omega, 1e-4 * omega, "solid angle 2 pi (1 - cos a)");
    CHECK(fabs(omega - 6.80e-5) < 0.01e-5, "the disc spans 6.80e-5 sr (%.4e)", omega);
    CHECK_NEAR(sun->radiance.y * PI_D * sin(a) * sin(a), edn, 1e-4 * edn, "radiance pi sin^2 a = E_dn");
    CHECK_NEAR(sun->radiance.y * sun->solid_angle, edn, 1e-4 * edn, "radiance x solid angle = E_dn to O(a^2)");
    ic_frame f = ic_frame_from_normal(sun->direction);
    for (int k = 0; k < 8; ++k) { /* 0.95 a and 1.05 a off the centre, in four directions */
        double off = (k < 4 ? 0.95 : 1.05) * a, phi = 0.5 * PI_D * (k % 4) + 0.3;
        ic_vec3 l = {(float)(sin(off) * cos(phi)), (float)(sin(off) * sin(phi)), (float)cos(off)};
        ic_vec3 d = ic_frame_to_world(&f, l);
        float L = ic_scene_sun_radiance(s, d).y, pdf = ic_scene_sun_disc_pdf(s, d);
        if (k < 4)
            CHECK(L == sun->radiance.y && fabs(pdf * (double)sun->solid_angle - 1.0) < 1e-4,
                  "inside the disc: its radiance, pdf x solid angle = 1 (%d)", k);
        else
            CHECK(L == 0.0f && pdf == 0.0f, "outside the disc: nothing (%d)", k);
    }
    ic_vec3 up = {0, 1, 0};
    CHECK(ic_scene_sun_radiance(s, up).y == 0.0f, "the sky elsewhere has no sun in it");
    ic_scene_free(s);
    ic_error err = {0};
    /* gensky's default sun: 6e-5 sr x 1.5e9/208 (1.147 - 0.147/max(sin alt, 0.16)) */
    s = load_sun("\"environment\": {\"sky\": \"cie-clear\", \"zenith_radiance\": 20, \"direct_normal\": \"gensky\", "
                 "\"sun_direction\": [0, 1, 1]}",
                 DIFFUSE, &err);
    CHECK(s != NULL, "clear sky with gensky's sun loads: %s", err.message);
    if (s) {
        double expect = 6e-5 * 1.5e9 / 208.0 * (1.147 - 0.147 / sin(PI_D / 4.0));
        CHECK_NEAR(s->sun.irradiance.y, expect, 1e-4 * expect, "gensky's sun at 45 degrees");
        CHECK(s->sun.angular_radius > 0.0f, "a disc too");
        ic_scene_free(s);
    }
    CHECK_NEAR(ic_sky_gensky_direct_normal(0.05), 6e-5 * 1.5e9 / 208.0 * (1.147 - 0.147 / 0.16), 1e-9,
               "gensky's sun near the horizon: sin(alt) held at 0.16");
}

/* Σ L max(0, n·ω) / pdf over disc samples of a rank-1 lattice (n_samples points). */
static double disc_irradiance(const ic_scene *s, ic_vec3 n, int n_samples)
{
    double sum = 0.0;
    for (int i = 0; i < n_samples; ++i) {
        float u1 = ((float)i + 0.5f) / (float)n_samples;
        float u2 = (float)(i * 0.6180339887498949 - floor(i * 0.6180339887498949));
        ic_light_sample ls;
        if (!ic_scene_sample_sun(s, u1, u2, &ls) || ls.is_delta)
            return -1.0;
        double c = (double)v3_dot(n, ls.wi);
        if (c > 0.0)
            sum += (double)ls.radiance.y * c / (double)ls.pdf;
    }
    return sum / n_samples;
}

static void test_disc_sampling(void)
{
    ic_scene *s = load_sun_checked(PEREZ_SKY(""), DIFFUSE, "loads");
    if (!s)
        return;
    ic_vec3 sd = s->sun.direction, up = {0, 1, 0};
    double a = s->sun.angular_radius;
    double facing = disc_irradiance(s, sd, 1 << 16), horizontal = disc_irradiance(s, up, 1 << 16);
    ic_vec3 edge = v3_norm(v3_cross(sd, up)); /* perpendicular to the sun */
    double edge_on = disc_irradiance(s, edge, 1 << 16), edge_expect = edn * 2.0 * a / (3.0 * PI_D);
    printf("disc sampling: facing %.5f (E_dn %.1f), horizontal %.5f (E_dn cos Z %.5f), edge-on %.6f (%.6f)\n",
           facing, edn, horizontal, edn * sd.y, edge_on, edge_expect);
    CHECK_NEAR(facing, edn, 1e-4 * edn, "a plane facing the sun gets E_dn");
    CHECK_NEAR(horizontal, edn * sd.y, 1e-4 * edn, "a horizontal plane gets E_dn cos Z");
    CHECK_NEAR(edge_on, edge_expect, 5e-3 * edge_expect, "edge-on: half the disc, E_dn 2a/(3 pi)");
    ic_scene_free(s);
}

/* Sensors facing the sun and the four compass points (north −z, east +x) 1 m above the open plane. */
static void compass_points(const ic_scene *s, ic_sensor_point pts[5])
{
    static const float dir[4][3] = {{0, 0, -1}, {1, 0, 0}, {0, 0, 1}, {-1, 0, 0}}; /* N, E, S, W */
    pts[0].position = v3(0.0f, 1.0f, 0.0f);
    pts[0].normal = s->sun.direction;
    for (int k = 0; k < 4; ++k) {
        pts[k + 1].position = v3(0.0f, 1.0f, 0.0f);
        pts[k + 1].normal = v3(dir[k][0], dir[k][1], dir[k][2]);
    }
}

/* Expected irradiance of sensor normal n: the sky, the ground (ρ 0.5 under sky and sun), the sun. */
static double expected(const ic_scene *s, ic_vec3 n)
{
    double ground = 0.5 * (s->env.sky.horizontal + edn * s->sun.direction.y) / PI_D;
    double c = v3_dot(n, s->sun.direction);
    return sky_irradiance(s, n, ground) + edn * (c > 0.0 ? c : 0.0);
}

static void test_points_and_rotation(void)
{
    ic_error err = {0};
    ic_scene *s = load_sun(PEREZ_SKY(""), DIFFUSE, &err);
    ic_scene *r = load_sun(PEREZ_SKY(", \"rotation_deg\": 90"), DIFFUSE, &err);
    CHECK(s && r, "both skies load: %s", err.message);
    if (!s || !r) {
        ic_scene_free(s);
        ic_scene_free(r);
        return;
    }
    /* the rotated sky is the sky turned: sun and radiances */
    ic_vec3 turned = v3_rotate_y(s->sun.direction, 90.0f);
    CHECK(v3_len(v3_sub(turned, r->sun.direction)) < 1e-6f, "the sun turned by 90 degrees about +y");
    double az = atan2(s->sun.direction.x, -s->sun.direction.z), az_r = atan2(r->sun.direction.x, -r->sun.direction.z);
    double turn = fmod((az - az_r) * 180.0 / PI_D + 720.0, 360.0);
    printf("rotation: sun azimuth (from -z towards +x) %.3f -> %.3f degrees\n", az * 180.0 / PI_D, az_r * 180.0 / PI_D);
    CHECK_NEAR(turn, 90.0, 1e-4, "the sun's azimuth moves by 90 degrees (right-handed about +y)");
    for (int k = 0; k < 6; ++k) {
        ic_vec3 d = v3_norm(v3(cosf(1.1f * (float)k), 0.2f + 0.15f * (float)k, sinf(1.1f * (float)k)));
        double a = ic_scene_env_radiance(s, d).y, b = ic_scene_env_radiance(r, v3_rotate_y(d, 90.0f)).y;
        CHECK_NEAR(b, a, 1e-4 * a, "sky radiance turned with it");
    }
    ic_sensor_point pts[5], pts_r[5];
    compass_points(s, pts);
    compass_points(r, pts_r);
    for (int integ = 0; integ < 2; ++integ) {
        ic_points_options opt = points_options(integ, 2048);
        ic_point_result res[5], res_r[5];
        int ok = ic_points_compute(s, pts, 5, &opt, res, NULL, &err) == IC_OK &&
                 ic_points_compute(r, pts_r, 5, &opt, res_r, NULL, &err) == IC_OK;
        CHECK(ok, "points compute: %s", err.message);
        if (!ok)
            break;
        const char *name = integ ? "ic" : "pt";
        /* the cache's interpolation bias is not in σ: its share is bounded by the accuracy */
        double bias = integ ? 1e-2 : 2e-3;
        for (int k = 0; k < 5; ++k) {
            double e = expected(s, pts[k].normal), got = res[k].irradiance.y, sig = res[k].irradiance_sigma.y;
            printf("%s: sensor %d: E %.3f +- %.3f, expected %.3f\n", name, k, got, sig, e);
            CHECK(fabs(got - e) <= 3.0 * sig + bias * e, "%s: sensor %d within 3 sigma of sky + sun", name, k);
        }
        /* turned by +90° (north −z → −x, east +x → −z): the sensor facing compass point k now sees what
         * the one facing the next of N, E, S, W saw */
        for (int k = 0; k < 4; ++k) {
            int from = 1 + (k + 1) % 4, to = 1 + k;
            double a = res[from].irradiance.y, b = res_r[to].irradiance.y;
            double sig = sqrt(res[from].irradiance_sigma.y * res[from].irradiance_sigma.y +
                              res_r[to].irradiance_sigma.y * res_r[to].irradiance_sigma.y);
            printf("%s: rotated: sensor %d %.3f, unrotated sensor %d %.3f\n", name, to, b, from, a);
            CHECK(fabs(a - b) <= 3.0 * sig + bias * a, "%s: rotated sensor %d sees what sensor %d saw", name, to, from);
        }
    }
    ic_scene_free(s);
    ic_scene_free(r);
}

/* A sun light of 20° angular radius, where light sampling and the sensor's cosine path both find the disc
 * often, so the MIS weights matter: over a black plane, a sensor facing it gets E, one tilted by 40°
 * E cos 40° (the disc wholly above its horizon: ∫ ω dω over a cap is its axis × π sin² a), one edge-on
 * L (a − sin(2a)/2) with L = E/(π sin² a) (half the cap, ∫ sin²θ dθ ∫ cos φ dφ). */
static void test_wide_disc(void)
{
    ic_error err = {0};
    ic_scene *s = load_sun_checked("\"lights\": [{\"type\": \"sun\", \"direction\": [0, 1, 0], \"irradiance\": 100, "
                                   "\"angular_radius_deg\": 20}]",
                                   BLACK, "a sun light with a 20 degree disc loads");
    if (!s)
        return;
    ic_scene *bad = load_sun("\"lights\": [{\"type\": \"sun\", \"direction\": [0, 1, 0], \"irradiance\": 1, "
                             "\"angular_radius_deg\": 50}]",
                             BLACK, &err);
    CHECK(bad == NULL && strstr(err.message, "sun_scene.json:") && strstr(err.message, "angular_radius_deg"),
          "a disc wider than 45 degrees is refused: %s", err.message);
    ic_scene_free(bad);
    double a = 20.0 * PI_D / 180.0, L = 100.0 / (PI_D * sin(a) * sin(a));
    double expect[3] = {100.0, 100.0 * cos(40.0 * PI_D / 180.0), L * (a - 0.5 * sin(2.0 * a))};
    ic_sensor_point pts[3] = {{{0, 1, 0}, {0, 1, 0}},
                              {{0, 1, 0}, {(float)sin(40.0 * PI_D / 180.0), (float)cos(40.0 * PI_D / 180.0), 0}},
                              {{0, 1, 0}, {1, 0, 0}}};
    for (int integ = 0; integ < 2; ++integ) {
        ic_points_options opt = points_options(integ, 1024);
        ic_point_result res[3];
        CHECK(ic_points_compute(s, pts, 3, &opt, res, NULL, &err) == IC_OK, "computes: %s", err.message);
        for (int k = 0; k < 3; ++k) {
            double got = res[k].irradiance.y, sig = res[k].irradiance_sigma.y;
            printf("%s: wide disc, sensor %d: E %.4f +- %.4f, expected %.4f\n", integ ? "ic" : "pt", k, got, sig,
                   expect[k]);
            CHECK(fabs(got - expect[k]) <= 3.0 * sig + 1e-3 * expect[k], "%s: wide disc, sensor %d", integ ? "ic" : "pt",
                  k);
        }
    }
    ic_scene_free(s);
}

/* A glossy floor under a sun disc of 10° (and a dim constant sky): the path tracer (light sampling of the
 * disc MIS-weighted against every BSDF sample) and the cache (the disc sampled at every shading point,
 * its glossy share weighted against the final render's glossy path) give the same image on average. */
static void test_glossy_mis(void)
{
    ic_scene_free(load_sun_checked(
        "\"camera\": {\"eye\": [0, 1, 3], \"target\": [0.4096, 0.4264, 2.2906], \"up\": [0, 1, 0], \"fov_y\": 50, "
        "\"width\": 32, \"height\": 24},\n  \"lights\": [{\"type\": \"sun\", \"direction\": [0.4096, 0.5736, -0.7094], "
        "\"irradiance\": 100, \"angular_radius_deg\": 10}],\n  \"environment\": {\"radiance\": 0.5}",
        GLOSSY, "glossy floor loads"));
    double mean[2] = {0.0, 0.0};
    for (int integ = 0; integ < 2; ++integ) {
        ic_render_options opt = {0};
        opt.integrator = integ ? IC_INTEGRATOR_IC : IC_INTEGRATOR_PT;
        opt.spp = 64;
        opt.threads = 2;
        ic_image img = {0};
        int finite = 0;
        if (test_render(IC_TEST_TMP "/sun_scene.json", 0, 0, &opt, &img, NULL))
            mean[integ] = test_image_mean(&img, &finite);
        ic_image_free(&img);
    }
    printf("glossy floor under a 10 degree disc: image mean pt %.4f, ic %.4f\n", mean[0], mean[1]);
    CHECK(mean[0] > 0.0 && fabs(mean[1] - mean[0]) <= 0.015 * mean[0], "pt and ic agree on the glossy floor");
}

static void test_threads(void)
{
    /* the camera looks down at the floor towards the sun, whose reflection is in view (and the sun too) */
    ic_scene *s = load_sun_checked(
        "\"camera\": {\"eye\": [0, 1, 3], \"target\": [0.4096, 0.9, -0.709], \"up\": [0, 1, 0], \"fov_y\": 70, "
        "\"width\": 24, \"height\": 16},\n  " PEREZ_SKY(", \"rotation_deg\": 20"),
        GLOSSY, "glossy floor loads");
    if (!s)
        return;
    ic_error err = {0};
    ic_sensor_point pts[5];
    compass_points(s, pts);
    for (int integ = 0; integ < 2; ++integ) {
        ic_points_options opt = points_options(integ, 64);
        ic_point_result a[5], b[5];
        opt.threads = 1;
        int ok = ic_points_compute(s, pts, 5, &opt, a, NULL, &err) == IC_OK;
        opt.threads = 2;
        ok = ok && ic_points_compute(s, pts, 5, &opt, b, NULL, &err) == IC_OK;
        CHECK(ok && memcmp(a, b, sizeof a) == 0, "points, %s: 1 and 2 threads identical", integ ? "ic" : "pt");
    }
    ic_scene_free(s);
    for (int integ = 0; integ < 2; ++integ) {
        ic_render_options opt = {0};
        opt.integrator = integ ? IC_INTEGRATOR_IC : IC_INTEGRATOR_PT;
        opt.spp = 4;
        ic_image one = {0}, two = {0};
        opt.threads = 1;
        int ok = test_render(IC_TEST_TMP "/sun_scene.json", 0, 0, &opt, &one, NULL);
        opt.threads = 2;
        ok = ok && test_render(IC_TEST_TMP "/sun_scene.json", 0, 0, &opt, &two, NULL);
        CHECK(ok && one.width == two.width && one.height == two.height &&
                  memcmp(one.rgb, two.rgb, sizeof(float) * 3 * (size_t)one.width * one.height) == 0,
              "image, %s: 1 and 2 threads identical", integ ? "ic" : "pt");
        int finite = 0;
        double mean = ok ? test_image_mean(&one, &finite) : 0.0;
        CHECK(finite && mean > 0.0, "image, %s: finite and lit (mean %g)", integ ? "ic" : "pt", mean);
        ic_image_free(&one);
        ic_image_free(&two);
    }
}

int main(void)
{
    test_disc();
    test_disc_sampling();
    test_points_and_rotation();
    test_wide_disc();
    test_glossy_mis();
    test_threads();
    TEST_MAIN_END();
}
