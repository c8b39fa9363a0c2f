/*
 * test_rad_sources.c — Radiance light sources (.rad) at sensors (ic_points_compute), path tracer and cache,
 * against closed forms of Radiance's definitions (Larson & Shakespeare 1998; its reference manual):
 *   1. a `light` disc (a ring of inner radius 0, radiance L, radius R, h above an upward sensor on its axis):
 *      E = L ∫ r_b²/(2(r_b² + h²)) dφ over the 64-gon irrcache makes of it (πL R²/(R² + h²) for the circle);
 *   2. a `spotlight` of the same disc: its radiance only towards directions within half its (full) cone
 *      angle of its direction, a hard edge (Radiance's spotout): with a 20° cone the sensor on the axis sees
 *      the part of the disc within 10° of the axis, E = πL sin² 10°; a sensor 1 m off the axis sees none of
 *      it (every direction from the disc to it lies 14° or more off the axis), E = 0; a 90° cone passes the
 *      whole disc;
 *   3. a `source` of 0.533° (the sun) of radiance L from 36.9° off the zenith: E = L Ω cos θ on an upward
 *      sensor, Ω = 2π(1 − cos 0.2665°), and L Ω facing it;
 *   4. a `source` of 180° (a hemisphere) of a glow of radiance L: an upward sensor reads πL, a sideways one
 *      πL/2, a downward one nothing, as in Radiance (a source is its radiance within its cone); a 90° source
 *      about the zenith gives an upward sensor πL sin² 45° and a sideways one the integral over its cone.
 * Each estimate lies within 3 of its σ of the closed form and the two estimators within 3 combined σ (the
 * sun, a directional light here, has σ 0: within 1e-5; Radiance's disc of the same radiance gives
 * L π sin² a cos θ, 5e-6 less).
 */
#include "test_util.h"
#include "test_render_util.h"

#include "core/vecmath.h"

#include <stdio.h>
#include <string.h>

#define PI_D 3.14159265358979323846

/* Checks both estimators at the sensor against want (exactly 0 for no light at all). */
static void expect(const ic_scene *s, const char *what, ic_vec3 p, ic_vec3 n, double want)
{
    double E[2], sg[2];
    if (!s || !test_sensor_irradiance(s, p, n, IC_INTEGRATOR_PT, 2048, &E[0], &sg[0]) ||
        !test_sensor_irradiance(s, p, n, IC_INTEGRATOR_IC, 0, &E[1], &sg[1]))
        return;
    for (int i = 0; i < 2; ++i) {
        printf("%s, %s: E %.6g +- %.3g, closed form %.6g (%.2f sigma)\n", what, i ? "cache" : "path tracer", E[i],
               sg[i], want, sg[i] > 0.0 ? (E[i] - want) / sg[i] : 0.0);
        if (want == 0.0)
            CHECK(E[i] == 0.0, "%s, %s: E %g, expected none", what, i ? "cache" : "path tracer", E[i]);
        else
            CHECK(fabs(E[i] - want) <= 3.0 * sg[i] + 1e-5 * want, "%s, %s: E %g +- %g, expected %g", what,
                  i ? "cache" : "path tracer", E[i], sg[i], want);
    }
    CHECK(fabs(E[0] - E[1]) <= 3.0 * sqrt(sg[0] * sg[0] + sg[1] * sg[1]) + 1e-5 * want,
          "%s: path tracer %g and cache %g agree within their sigma", what, E[0], E[1]);
}


static ic_scene *load(const char *name, const char *rad)
{
    ic_error err = {0};
    ic_scene *s = test_load_rad_text(name, rad, NULL, 16, 0, &err);
    CHECK(s != NULL, "%s loads: %s", name, err.message);
    return s;
}

/* L ∫ r_b(φ)²/(2(r_b² + h²)) dφ: a regular n-gon inscribed in the circle of radius R, h above the point on
 * its axis (r_b the distance from the axis to the polygon's edge at azimuth φ). */
static double polygon_disc_E(double L, double R, double h, int n)
{
    const int N = 100000;
    double sum = 0.0, wedge = 2.0 * PI_D / n;
    for (int i = 0; i < N; ++i) {
        double phi = (i + 0.5) * 2.0 * PI_D / N, rb = R * cos(PI_D / n) / cos(fmod(phi, wedge) - 0.5 * wedge);
        sum += rb * rb / (2.0 * (rb * rb + h * h));
    }
    return L * sum * 2.0 * PI_D / N;
}

static void test_disc_and_spotlight(void)
{
    const double L = 100.0, R = 0.5, h = 2.0;
    const ic_vec3 up = v3(0.0f, 0.0f, 1.0f);
    ic_scene *s = load("src_disc", "void light lamp\n0\n0\n3 100 100 100\nlamp ring disc\n0\n0\n8 0 0 2 0 0 -1 0 0.5\n");
    const double disc = polygon_disc_E(L, R, h, 64);
    printf("disc: the 64-gon's %.6g, the circle's %.6g\n", disc, PI_D * L * R * R / (R * R + h * h));
    expect(s, "light disc, on its axis", v3(0.0f, 0.0f, 0.0f), up, disc);
    ic_scene_free(s);

    s = load("src_spot20", "void spotlight spot\n0\n0\n7 100 100 100 20 0 0 -1\n"
                           "spot ring disc\n0\n0\n8 0 0 2 0 0 -1 0 0.5\n");
    const double a = 10.0 * PI_D / 180.0; /* half the cone: the lit part of the disc, radius h tan a = 0.35 < R */
    expect(s, "spotlight of 20 degrees, on its axis", v3(0.0f, 0.0f, 0.0f), up, PI_D * L * sin(a) * sin(a));
    expect(s, "spotlight of 20 degrees, 1 m off its axis", v3(1.0f, 0.0f, 0.0f), up, 0.0);
    ic_scene_free(s);

    /* the direction's length (Radiance's focal distance) does not change a local spotlight */
    s = load("src_spot90", "void spotlight spot\n0\n0\n7 100 100 100 90 0 0 -3\n"
                           "spot ring disc\n0\n0\n8 0 0 2 0 0 -1 0 0.5\n");
    expect(s, "spotlight of 90 degrees, on its axis", v3(0.0f, 0.0f, 0.0f), up, disc);
    ic_scene_free(s);
}

static void test_sun(void)
{
    const double L = 1e6, omega = 2.0 * PI_D * (1.0 - cos(0.5 * 0.533 * PI_D / 180.0));
    ic_scene *s = load("src_sun", "void light solar\n0\n0\n3 1e6 1e6 1e6\nsolar source sun\n0\n0\n4 0 0.6 0.8 0.533\n");
    expect(s, "sun of 0.533 degrees, upward sensor", v3(0.0f, 0.0f, 0.0f), v3(0.0f, 0.0f, 1.0f), L * omega * 0.8);
    expect(s, "sun of 0.533 degrees, sensor facing it", v3(0.0f, 0.0f, 0.0f), v3(0.0f, 0.6f, 0.8f), L * omega);
    ic_scene_free(s);
}

/* The irradiance of a sideways sensor (normal +x) from radiance L within the cone of half angle a about +z:
 * ∫ L max(D·x, 0) dω over the cone, by the midpoint rule. */
static double cone_sideways(double L, double a)
{
    const int NT = 2000, NP = 2000;
    double sum = 0.0;
    for (int i = 0; i < NT; ++i) {
        double th = (i + 0.5) * a / NT;
        for (int j = 0; j < NP; ++j) {
            double phi = (j + 0.5) * 2.0 * PI_D / NP, dx = sin(th) * cos(phi);
            sum += dx > 0.0 ? dx * sin(th) : 0.0;
        }
    }
    return L * sum * (a / NT) * (2.0 * PI_D / NP);
}

static void test_wide_sources(void)
{
    const double L = 2.0;
    const ic_vec3 o = v3(0.0f, 0.0f, 0.0f);
    ic_scene *s = load("src_hemi", "void glow skyglow\n0\n0\n4 2 2 2 0\nskyglow source sky\n0\n0\n4 0 0 1 180\n");
    expect(s, "180-degree source, upward sensor", o, v3(0.0f, 0.0f, 1.0f), PI_D * L);
    expect(s, "180-degree source, sideways sensor", o, v3(1.0f, 0.0f, 0.0f), 0.5 * PI_D * L);
    expect(s, "180-degree source, downward sensor", o, v3(0.0f, 0.0f, -1.0f), 0.0);
    ic_scene_free(s);
    s = load("src_cone90", "void light skylight\n0\n0\n3 2 2 2\nskylight source sky\n0\n0\n4 0 0 1 90\n");
    expect(s, "90-degree source, upward sensor", o, v3(0.0f, 0.0f, 1.0f), PI_D * L * 0.5);
    expect(s, "90-degree source, sideways sensor", o, v3(1.0f, 0.0f, 0.0f), cone_sideways(L, 0.25 * PI_D));
    ic_scene_free(s);
}

int main(void)
{
    test_disc_and_spotlight();
    test_sun();
    test_wide_sources();
    TEST_MAIN_END();
}
