/*
 * test_rad_sky.c — gensky's and gendaylit's output pasted into a Radiance scene (a brightfunc of
 * skybright.cal or perezlum.cal modifying the glows of the sources `sky` and `ground`), against Radiance's
 * definitions of those functions, written out again here from the .cal files and integrated by brute force:
 *   1. the environment equals colour × the function (its CIE or Perez sky above the horizon, its ground
 *      brightness below, the two blended near the horizon by the weights (Dz + 1.01)^±10) in every direction;
 *   2. gensky -c: an upward sensor (ic_points_compute, path tracer) reads the CIE overcast closed form
 *      7π/9 L_z plus the horizon blending's share (a 1-D quadrature, −0.14 %), within its σ; a downward one
 *      π L_ground plus the blending's share (+0.3 %);
 *   3. gensky +s (the CIE clear sky and its sun) and gendaylit (Perez): an upward sensor reads a midpoint
 *      quadrature of the function over the hemisphere plus the sun's L Ω sin α, within its σ; a coloured
 *      glow tints the sky;
 *   4. the skies of gensky -u (uniform) and -i (intermediate) and gendaylit's black sun under an overcast
 *      sky (`3 0.0 0.0 0.0`) load;
 *   5. malformed skies are refused with one line naming file:line: a wrong argument count, a NaN, a sun
 *      direction of zero length, a sky type out of range, another function of skybright.cal, a transform,
 *      a surface made of a sky glow; a sky function modifying a plastic is warned about; a plain wide source
 *      beside the sky is one more cone of it (the last defined gives a direction its radiance).
 * `irrcache points` on the pasted overcast sky against the JSON scene's cie-overcast: test_cli_rad.c.
 */
#include "test_util.h"

#include "test_rad_sky.h"
#include "test_render_util.h"

#include "irrcache/points.h"
#include "scene/scene.h"

#include <string.h>

#define PI_D 3.14159265358979323846

/* ---- the scenes ---- */

static ic_scene *load_text(const char *name, const char *text)
{
    ic_error err = {0};
    ic_scene *s = test_load_rad_text(name, text, NULL, 16, 0, &err);
    CHECK(s != NULL, "%s loads: %s", name, err.message);
    return s;
}

/* The largest relative difference between the environment's green channel and colour × f over a grid of
 * directions (both hemispheres, the horizon's neighbourhood included). */
static double worst_pointwise(const ic_scene *s, test_sky_fn f, const double *A, double sky_colour, double ground_colour)
{
    double worst = 0.0;
    for (int i = 0; i <= 90; ++i)
        for (int k = 0; k < 36; ++k) {
            double el = (i - 45) * 2.0 * PI_D / 180.0 + 0.003, az = k * 10.0 * PI_D / 180.0 + 0.05;
            ic_vec3 d = {(float)(cos(el) * cos(az)), (float)(cos(el) * sin(az)), (float)sin(el)};
            double want = (d.z > 0.0f ? sky_colour : ground_colour) * f(A, d.x, d.y, d.z);
            double got = ic_scene_env_radiance(s, d).y;
            double rel = fabs(got - want) / fmax(want, 1e-30);
            if (rel > worst)
                worst = rel;
        }
    return worst;
}

/* Loads text as NAME.rad and checks its environment against the glows' colours × f in every direction of the
 * grid; the scene, or NULL. */
static ic_scene *load_sky(const char *name, const char *text, test_sky_fn f, const double *A, double sky_colour,
                          double ground_colour)
{
    ic_scene *s = load_text(name, text);
    if (!s)
        return NULL;
    double worst = worst_pointwise(s, f, A, sky_colour, ground_colour);
    printf("%s: the environment against the .cal file's function: largest relative difference %.2e\n", name, worst);
    CHECK(worst < 1e-5, "%s: the environment is the function's sky (%.2e)", name, worst);
    return s;
}

/* E at a sensor at (0, 0, 1) facing +z (up) or −z, by the path tracer with 8192 samples. */
static ic_point_result sensor(const ic_scene *s, int up)
{
    ic_sensor_point pt = {{0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, up ? 1.0f : -1.0f}};
    ic_points_options opt = {0};
    opt.samples = 8192;
    opt.threads = 2;
    ic_point_result r = {0};
    ic_error err = {0};
    CHECK(ic_points_compute(s, &pt, 1, &opt, &r, NULL, &err) == IC_OK, "points compute: %s", err.message);
    return r;
}

static void test_overcast(void)
{
    /* gensky -ang 40 30 -c: zenith (8.6 sin 40° + 0.123) 1000/179, ground 0.2 × 0.777778 × the zenith */
    const double A[8] = {0, 2, 31.6, 4.91};
    char text[2048];
    test_gensky_text(text, sizeof text, "", "skybr skybright.cal", "3 2 3.16e+01 4.91e+00", "1 1 1", "1 1 1");
    ic_scene *s = load_sky("rad_sky_overcast", text, test_skybr, A, 1.0, 1.0);
    if (!s)
        return;
    CHECK(!ic_scene_warnings(s)[0], "no warning: %s", ic_scene_warnings(s));
    double closed = 7.0 * PI_D / 9.0 * A[2], up_blend = test_overcast_blend_share(A, 1), up_quad = test_sky_quadrature(test_skybr, A, 1);
    double ground = PI_D * A[3], down_blend = test_overcast_blend_share(A, 0), down_quad = test_sky_quadrature(test_skybr, A, 0);
    ic_point_result u = sensor(s, 1), d = sensor(s, 0);
    printf("overcast: up %.4f +- %.4f W/m2; 7 pi/9 L_z %.4f, with the horizon blending %+.4f: %.4f (quadrature "
           "%.4f)\n",
           u.irradiance.y, u.irradiance_sigma.y, closed, up_blend, closed + up_blend, up_quad);
    printf("overcast: down %.4f +- %.4f W/m2; pi L_ground %.4f, with the horizon blending %+.4f: %.4f (quadrature "
           "%.4f)\n",
           d.irradiance.y, d.irradiance_sigma.y, ground, down_blend, ground + down_blend, down_quad);
    CHECK(fabs(up_quad - (closed + up_blend)) < 1e-5 * closed, "the quadrature agrees with the closed form");
    CHECK(fabs(u.irradiance.y - (closed + up_blend)) <= 3.0 * u.irradiance_sigma.y + 1e-4 * closed,
          "up: 7 pi/9 L_z and the blending within 3 sigma");
    CHECK(fabs(d.irradiance.y - (ground + down_blend)) <= 3.0 * d.irradiance_sigma.y + 1e-4 * ground,
          "down: pi L_ground and the blending within 3 sigma");
    CHECK(fabs(d.irradiance.y - ground) <= 5e-3 * ground, "down: pi L_ground within the blending's 0.5 %%");
    CHECK(!s->sun.enabled, "no sun");
    /* The daylight factor's reference under gensky -c's sky is what that sky gives an unobstructed plane (the
     * blending included: 7π/9 L_z alone would make the open sensor read 100.14 %), and the sensor reads 100 %. */
    double ref = 0.0;
    ic_error err = {0};
    CHECK(ic_points_daylight_reference(s, &ref, &err) == IC_OK, "gensky -c: a daylight factor reference (%s)",
          err.message);
    CHECK(fabs(ref - IC_LUMINOUS_EFFICACY * (closed + up_blend)) <= 1e-5 * ref,
          "the reference %.4f lux is 179 x the sky's horizontal irradiance %.4f", ref,
          IC_LUMINOUS_EFFICACY * (closed + up_blend));
    double df = 100.0 * u.illuminance / ref, df_sigma = 100.0 * u.illuminance_sigma / ref;
    printf("overcast: the open sensor's daylight factor %.3f +- %.3f %%\n", df, df_sigma);
    CHECK(fabs(df - 100.0) <= 3.0 * df_sigma + 1e-3, "the open sensor's daylight factor is 100 %% within 3 sigma");
    ic_scene_free(s);
}

static void test_clear(void)
{
    /* gensky -ang 40 30 +s: the default zenith brightness for turbidity 2.75, F2 = 0.274 f(Z_s), the ground
     * with the sun's share, the sun 0.5° across */
    const double A[8] = {0, 1, 11.4, 20.2, 0.5, -0.383022, -0.663414, 0.642788};
    const double solar = 6.62e6, omega = 2.0 * PI_D * (1.0 - cos(0.25 * PI_D / 180.0));
    char text[2048];
    test_gensky_text(text, sizeof text,
              "void light solar\n0\n0\n3 6.62e+06 6.62e+06 6.62e+06\n\nsolar source sun\n0\n0\n4 -0.383022 -0.663414 "
              "0.642788 0.5\n",
              "skybr skybright.cal", "7 1 1.14e+01 2.02e+01 5.00e-01 -0.383022 -0.663414 0.642788", "1 1 1", "1 1 1");
    ic_scene *s = load_sky("rad_sky_clear", text, test_skybr, A, 1.0, 1.0);
    if (!s)
        return;
    double sky = test_sky_quadrature(test_skybr, A, 1), sun = solar * omega * A[7];
    ic_point_result u = sensor(s, 1);
    printf("clear: up %.3f +- %.3f W/m2; quadrature of skybright.cal %.3f + the sun L Omega sin(alt) %.3f = %.3f\n",
           u.irradiance.y, u.irradiance_sigma.y, sky, sun, sky + sun);
    CHECK(s->sun.enabled && fabs(s->sun.irradiance.y - solar * omega) < 1e-5 * solar * omega, "the sun: L Omega");
    CHECK(fabs(u.irradiance.y - (sky + sun)) <= 3.0 * u.irradiance_sigma.y + 1e-4 * (sky + sun),
          "up: the sky's quadrature and the sun within 3 sigma");
    ic_scene_free(s);
}

static void test_perez(void)
{
    /* gendaylit-style: diffuse normalisation, ground brightness, Perez a–e (ε 2.5, Δ 0.3, sun 35° up),
     * the sun direction; a bluish sky glow and a brownish ground */
    const double A[11] = {0,        31.74,     31.46,    -1.022759, -0.832733, 12.035792,
                          -3.112467, 0.019786, 0.526541, -0.627507, 0.573576};
    char text[2048];
    test_gensky_text(text, sizeof text,
              "void light solar\n0\n0\n3 8.828e+06 8.828e+06 8.828e+06\n\nsolar source sun\n0\n0\n4 0.526541 "
              "-0.627507 0.573576 0.533000\n",
              "skybright perezlum.cal",
              "10 3.174e+01 3.146e+01 -1.022759 -0.832733 12.035792 -3.112467 0.019786 0.526541 -0.627507 0.573576 ",
              "0.9 1 1.2", "1 0.8 0.6");
    ic_scene *s = load_sky("rad_sky_perez", text, test_perezlum, A, 1.0, 0.8); /* green */
    if (!s)
        return;
    ic_vec3 zen = ic_scene_env_radiance(s, v3(0.0f, 0.0f, 1.0f)), nadir = ic_scene_env_radiance(s, v3(0.0f, 0.0f, -1.0f));
    CHECK(fabs(zen.x / zen.y - 0.9) < 1e-5 && fabs(zen.z / zen.y - 1.2) < 1e-5 && fabs(nadir.x - 31.46) < 1e-3 &&
              fabs(nadir.z - 0.6 * 31.46) < 1e-3,
          "the glows' colours tint the sky and the ground");
    double omega = 2.0 * PI_D * (1.0 - cos(0.5 * 0.533 * PI_D / 180.0));
    double sky = test_sky_quadrature(test_perezlum, A, 1), sun = 8.828e6 * omega * A[10];
    ic_point_result u = sensor(s, 1);
    printf("perez: up %.3f +- %.3f W/m2; quadrature of perezlum.cal %.3f + the sun %.3f = %.3f\n", u.irradiance.y,
           u.irradiance_sigma.y, sky, sun, sky + sun);
    CHECK(fabs(u.irradiance.y - (sky + sun)) <= 3.0 * u.irradiance_sigma.y + 1e-4 * (sky + sun),
          "up: the sky's quadrature and the sun within 3 sigma");
    ic_scene_free(s);
}

static void test_other_skies(void)
{
    char text[2048];
    /* gensky -u (uniform) and -i (intermediate), pointwise */
    const double U[8] = {0, 3, 10.0, 2.0}, I[8] = {0, 4, 12.0, 6.0, 0.8, 0.5, 0.5, 0.707107};
    test_gensky_text(text, sizeof text, "", "skybr skybright.cal", "3 3 10 2", "1 1 1", "1 1 1");
    ic_scene *uniform = load_sky("rad_sky_uniform", text, test_skybr, U, 1.0, 1.0);
    double ref = 0.0;
    ic_error err = {0};
    CHECK(!uniform || (ic_points_daylight_reference(uniform, &ref, &err) == IC_ERR_INVALID_ARG &&
                       strstr(err.message, "gensky's -c")),
          "no daylight factor under gensky -u's sky: %s", err.message);
    ic_scene_free(uniform);
    test_gensky_text(text, sizeof text, "", "skybr skybright.cal", "7 4 12 6 0.8 0.5 0.5 0.707107", "1 1 1", "1 1 1");
    ic_scene_free(load_sky("rad_sky_inter", text, test_skybr, I, 1.0, 1.0));
    /* gendaylit under an overcast sky writes a black sun: it emits nothing (it was refused as "needs a light") */
    test_gensky_text(text, sizeof text, "void light solar\n0\n0\n3 0.0 0.0 0.0\n\nsolar source sun\n0\n0\n4 0 -0.5 0.866 0.533\n",
              "skybright perezlum.cal", "10 2.0e+01 3.0e+00 -1 -0.3 0 -1 0 0 -0.5 0.866025", "1 1 1", "1 1 1");
    ic_scene *s = load_text("rad_sky_dark_sun", text);
    if (s) {
        CHECK(!s->sun.enabled && s->env.sky.model == IC_SKY_RADIANCE, "a black sun is no light, the sky is");
        ic_scene_free(s);
    }
}

static void expect_error(const char *name, const char *text, const char *const *want)
{
    ic_error err = {0};
    ic_scene *s = test_load_rad_text(name, text, NULL, 16, 0, &err);
    test_check_refused(name, s, &err, want);
}

static void test_errors(void)
{
    char text[2048];
    test_gensky_text(text, sizeof text, "", "skybr skybright.cal", "6 1 1.14e+01 2.02e+01 5.00e-01 -0.383022 -0.663414",
              "1 1 1", "1 1 1");
    expect_error("rad_sky_count", text,
                 (const char *[]){"rad_sky_count.rad:3:", "brightfunc 'skyfunc'", "has 6 real arguments", "takes 7",
                                  NULL});
    test_gensky_text(text, sizeof text, "", "skybright perezlum.cal", "7 1 1.14e+01 2.02e+01 5.00e-01 0 0 1", "1 1 1",
              "1 1 1");
    expect_error("rad_sky_count10", text, (const char *[]){"rad_sky_count10.rad:3:", "has 7", "takes 10", NULL});
    test_gensky_text(text, sizeof text, "", "skybr skybright.cal", "7 1 nan 2.02e+01 5.00e-01 -0.383022 -0.663414 0.642788",
              "1 1 1", "1 1 1");
    expect_error("rad_sky_nan", text, (const char *[]){"rad_sky_nan.rad:6:", "'nan'", "not a finite number", NULL});
    test_gensky_text(text, sizeof text, "", "skybr skybright.cal", "7 1 1.14e+01 2.02e+01 5.00e-01 0 0 0", "1 1 1", "1 1 1");
    expect_error("rad_sky_sun0", text,
                 (const char *[]){"rad_sky_sun0.rad:3:", "sun direction (A5–A7) has length 0", NULL});
    test_gensky_text(text, sizeof text, "", "skybright perezlum.cal", "10 20 3 -1 -0.3 0 -1 0 0 0 0", "1 1 1", "1 1 1");
    expect_error("rad_sky_perez_sun0", text,
                 (const char *[]){"rad_sky_perez_sun0.rad:3:", "sun direction (A8–A10) has length 0", NULL});
    test_gensky_text(text, sizeof text, "", "skybr skybright.cal", "3 5 10 2", "1 1 1", "1 1 1");
    expect_error("rad_sky_type", text, (const char *[]){"rad_sky_type.rad:3:", "sky type", NULL});
    test_gensky_text(text, sizeof text, "", "skybr skybright.cal", "3 2 -10 2", "1 1 1", "1 1 1");
    expect_error("rad_sky_negative", text, (const char *[]){"rad_sky_negative.rad:3:", "zenith brightness", NULL});
    test_gensky_text(text, sizeof text, "", "skybright skybright.cal", "3 2 10 2", "1 1 1", "1 1 1");
    expect_error("rad_sky_function", text,
                 (const char *[]){"rad_sky_function.rad:3:", "function 'skybr'", "not 'skybright'", NULL});
    test_gensky_text(text, sizeof text, "", "skybr skybright.cal -rz 90", "3 2 10 2", "1 1 1", "1 1 1");
    char *two /* write_sky's string count is 2: 4 with the transform */ = strstr(text, "2 skybr skybright.cal -rz 90");
    if (two)
        two[0] = '4';
    expect_error("rad_sky_xform", text, (const char *[]){"rad_sky_xform.rad:3:", "transform ('-rz'", NULL});
    test_gensky_text(text, sizeof text, "", "skybr skybright.cal", "3 2 10 2", "1 1 1", "1 1 1");
    char more[4096];
    snprintf(more, sizeof more, "%s\nsky_glow polygon dome\n0\n0\n9 0 0 5 1 0 5 0 1 5\n", text);
    expect_error("rad_sky_surface", more,
                 (const char *[]){"rad_sky_surface.rad:28:", "'sky_glow'", "sky function of line 3", "sources only",
                                  NULL});
    /* a plain wide source beside the sky is one more cone of it, of its glow's radiance (7 here): where it
     * overlaps the sky, the source defined last gives a direction its radiance, as the sky's own do */
    const ic_vec3 in_cone = v3(0.0f, 0.8f, 0.6f), zenith = v3(0.0f, 0.0f, 1.0f); /* 36.9° from +y; outside */
    for (int after = 0; after < 2; ++after) {
        static const char plain[] = "void glow plain\n0\n0\n4 7 7 7 0\nplain source extra\n0\n0\n4 0 1 0 90\n";
        snprintf(more, sizeof more, "%s\n%s", after ? text : plain, after ? plain : text);
        ic_scene *s = load_text(after ? "rad_sky_plain_after" : "rad_sky_plain_before", more);
        if (!s)
            continue;
        const double A[8] = {0, 2, 10, 2, 1, 0, 0, 1}, sky_in = test_skybr(A, 0.0, 0.8, 0.6), sky_zen = test_skybr(A, 0.0, 0.0, 1.0);
        const double got_in = ic_scene_env_radiance(s, in_cone).y, got_zen = ic_scene_env_radiance(s, zenith).y;
        CHECK(fabs(got_in - (after ? 7.0 : sky_in)) < 1e-4 * got_in && fabs(got_zen - sky_zen) < 1e-4 * sky_zen,
              "a plain 90-degree source %s the sky: %g in its cone (expected %g), %g at the zenith (expected %g)",
              after ? "after" : "before", got_in, after ? 7.0 : sky_in, got_zen, sky_zen);
        ic_scene_free(s);
    }
    /* a sky function modifying a plastic is warned about, and the plastic used without it */
    ic_error err = {0};
    ic_scene *s = test_load_rad_text("rad_sky_plastic",
                                     "void brightfunc skyfunc\n2 skybr skybright.cal\n0\n3 2 10 2\n"
                                     "skyfunc plastic p\n0\n0\n5 .5 .5 .5 0 0\np polygon q\n0\n0\n9 0 0 0 1 0 0 0 1 0\n",
                                     NULL, 16, 0, &err);
    CHECK(s && strstr(ic_scene_warnings(s), "rad_sky_plastic.rad:5: a sky function"), "sky function on a plastic: %s",
          s ? ic_scene_warnings(s) : err.message);
    ic_scene_free(s);
}

int main(void)
{
    test_overcast();
    test_clear();
    test_perez();
    test_other_skies();
    test_errors();
    TEST_MAIN_END();
}
