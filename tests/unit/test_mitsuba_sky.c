/*
 * test_mitsuba_sky.c — Mitsuba's sun, sky and sunsky emitters, read as the CIE clear sky with gensky's
 * sun (docs/scene-format.md): the sun where sunDirection puts it, or where the date, time and place put
 * it (irrcache's solar position), a disc of the sun's size whose normal irradiance is gensky's for that
 * altitude, times `scale`; sun alone has no sky, sky alone no sun; a sun below the horizon, a second sun
 * and a second sky are one-line errors naming file:line; the approximation is warned once.
 */
#include "test_util.h"
#include "test_files.h"
#include "test_render_util.h"

#include "scene/scene.h"

#include <stdio.h>
#include <string.h>

static ic_scene *load_emitter(const char *emitter, ic_error *err)
{
    char xml[1024];
    snprintf(xml, sizeof xml,
             "<scene version=\"0.6.0\">\n"
             "  <shape type=\"rectangle\"/>\n"
             "  %s\n"
             "</scene>\n",
             emitter);
    ic_scene *s = NULL;
    if (test_write_text(IC_TEST_TMP "/mts_sky.xml", xml))
        test_load_scene(IC_TEST_TMP "/mts_sky.xml", NULL, 0, 0, 0, &s, err);
    return s;
}

int main(void)
{
    ic_error err = {0};
    const double deg = 3.14159265358979323846 / 180.0;
    /* sunsky with sunDirection (0, 1, 1): 45° up, scale 2. */
    ic_scene *s = load_emitter("<emitter type=\"sunsky\"><vector name=\"sunDirection\" x=\"0\" y=\"1\" z=\"1\"/>"
                               "<float name=\"scale\" value=\"2\"/></emitter>", &err);
    CHECK(s != NULL, "sunsky loads: %s", err.message);
    if (s) {
        ic_sky_params p = {0};
        p.model = IC_SKY_CIE_CLEAR;
        p.direct_normal_gensky = 1;
        p.has_sun_direction = 1;
        p.sun_direction = v3(0.0f, 0.70710678f, 0.70710678f);
        ic_sky one;
        char why[128];
        CHECK(ic_sky_init(&one, &p, why, sizeof why), "the unscaled sky: %s", why);
        CHECK(s->env.enabled && s->env.sky.model == IC_SKY_CIE_CLEAR, "the sky: CIE clear");
        CHECK_NEAR(s->env.sky.zenith_radiance, 2.0 * one.zenith_radiance, 1e-9 * one.zenith_radiance,
                   "the sky's radiance scaled by 2");
        CHECK_NEAR(s->env.sky.ground_radiance, 2.0 * one.ground_radiance, 1e-9 * one.ground_radiance,
                   "the ground's radiance scaled by 2");
        CHECK(s->sun.enabled && fabsf(s->sun.direction.y - 0.70710678f) < 1e-6f &&
                  fabsf(s->sun.direction.z - 0.70710678f) < 1e-6f,
              "the sun towards sunDirection: (%g, %g, %g)", s->sun.direction.x, s->sun.direction.y, s->sun.direction.z);
        CHECK_NEAR(s->sun.irradiance.x, 2.0 * ic_sky_gensky_direct_normal(45.0 * deg), 1e-3 * s->sun.irradiance.x,
                   "gensky's normal irradiance at 45°, times 2");
        CHECK_NEAR(s->sun.angular_radius, IC_SKY_SUN_RADIUS_DEG * deg, 1e-7, "a disc of the sun's size");
        const char *w = ic_scene_warnings(s);
        CHECK(strstr(w, "mts_sky.xml:3:") && strstr(w, "CIE clear"), "the approximation warned: %s", w);
        ic_scene_free(s);
    }
    /* sun alone at a date and place: no sky, the sun where irrcache's solar position puts it. */
    s = load_emitter("<emitter type=\"sun\"><integer name=\"month\" value=\"6\"/><integer name=\"day\" value=\"21\"/>"
                     "<float name=\"hour\" value=\"12\"/><float name=\"latitude\" value=\"48\"/>"
                     "<float name=\"longitude\" value=\"11\"/><float name=\"timezone\" value=\"1\"/></emitter>", &err);
    CHECK(s != NULL, "sun loads: %s", err.message);
    if (s) {
        double alt, az;
        ic_sky_sun_position(6, 21, 12.0, 48.0, 11.0, 15.0, &alt, &az);
        CHECK(!s->env.enabled && s->sun.enabled, "sun alone: a sun, no sky");
        CHECK_NEAR(asin(s->sun.direction.y), alt, 1e-4, "the sun's altitude from the date and place");
        /* azimuth from north (−z) towards east (+x) */
        CHECK_NEAR(atan2(s->sun.direction.x, -s->sun.direction.z), az, 1e-3, "the sun's azimuth, north −z");
        ic_scene_free(s);
    }
    s = load_emitter("<emitter type=\"sky\"><vector name=\"sunDirection\" x=\"1\" y=\"1\" z=\"0\"/></emitter>", &err);
    CHECK(s && s->env.enabled && !s->sun.enabled, "sky alone: the sky, no sun disc");
    ic_scene_free(s);
    struct {
        const char *emitters, *says;
    } bad[3] = {
        {"<emitter type=\"sun\"><vector name=\"sunDirection\" x=\"0\" y=\"-1\" z=\"1\"/></emitter>", "above the horizon"},
        {"<emitter type=\"sunsky\"><vector name=\"sunDirection\" x=\"0\" y=\"1\" z=\"1\"/></emitter>"
         "<emitter type=\"directional\"><vector name=\"direction\" x=\"0\" y=\"-1\" z=\"0\"/></emitter>",
         "a second directional"},
        {"<emitter type=\"sky\"><vector name=\"sunDirection\" x=\"0\" y=\"1\" z=\"1\"/></emitter>"
         "<emitter type=\"sky\"><vector name=\"sunDirection\" x=\"0\" y=\"1\" z=\"1\"/></emitter>",
         "second environment"}};
    for (int k = 0; k < 3; ++k) {
        s = load_emitter(bad[k].emitters, &err);
        CHECK(!s && strstr(err.message, "mts_sky.xml:3") && strstr(err.message, bad[k].says) &&
                  !strchr(err.message, '\n'),
              "bad sky %d refused naming file:line: %s", k, err.message);
        ic_scene_free(s);
    }
    TEST_MAIN_END();
}
