/*
 * scene_sky.c — an analytic daylight sky (sky.h) put into a scene: the sky as the environment and its
 * sun as a disc of the sun's angular size, for every scene format that describes skies (JSON scenes,
 * Mitsuba's sun and sky emitters).
 */
#include "scene/scene_internal.h"

#include <math.h>
#include <stdio.h>

ic_result ic_scene_install_sky(ic_scene *s, const ic_sky_params *p, int with_sky, int with_sun, float scale,
                               char *why, size_t why_size)
{
    ic_sky sky;
    if (!ic_sky_init(&sky, p, why, why_size))
        return IC_ERR_INVALID_ARG;
    /* Every radiance and irradiance of the sky in proportion (the sky's shape does not change). */
    sky.zenith_radiance *= scale;
    sky.horizontal *= scale;
    sky.ground_radiance *= scale;
    sky.direct_normal *= scale;
    const double most = fmax(sky.zenith_radiance, sky.direct_normal);
    if (!(most <= (float)IC_SCENE_MAX_RADIANCE)) {
        snprintf(why, why_size, "its zenith radiance or its sun's irradiance (times the scale %g) is " IC_RADIANCE_LIMIT_FMT
                 "; give a smaller scale or a dimmer sky", (double)scale, most, IC_SCENE_MAX_RADIANCE);
        return IC_ERR_INVALID_ARG;
    }
    int sun = with_sun && sky.direct_normal > 0.0;
    if (sun && s->sun.enabled) {
        snprintf(why, why_size, "the sky's sun and a sun light: give only one");
        return IC_ERR_UNSUPPORTED;
    }
    if (with_sky) {
        s->env.sky = sky;
        s->env.enabled = 1;
        s->env.radiance = v3s(1.0f);
    }
    if (sun) {
        s->sun.enabled = 1;
        s->sun.direction = sky.sun;
        s->sun.irradiance = v3s((float)sky.direct_normal);
        s->sun.angular_radius = (float)(IC_SKY_SUN_RADIUS_DEG * 3.14159265358979323846 / 180.0);
    }
    return IC_OK;
}
