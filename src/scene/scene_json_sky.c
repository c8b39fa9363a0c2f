/*
 * scene_json_sky.c — an "environment" that is an analytic daylight sky ("sky": "cie-overcast",
 * "cie-clear" or "perez"; sky.h, docs/scene-format.md "Skies"). The sky's sun, when it has one, becomes
 * the scene's sun light: a disc of IC_SKY_SUN_RADIUS_DEG.
 */
#include "scene/json_context.h"

#include <math.h>
#include <string.h>

/* One number key of the sky: its value in [lo, hi] (a message saying what to give otherwise). */
static ic_result read_ranged(json_ctx *c, const cJSON *it, int line, double lo, double hi, const char *hint,
                             double *out)
{
    float f = 0.0f;
    ic_result r = ic_json_read_float(c, it, line, &f);
    if (r != IC_OK)
        return r;
    /* Compared as written (a double): the float nearest IC_SCENE_MAX_RADIANCE (1e30) is above it. */
    if (!(it->valuedouble >= lo && it->valuedouble <= hi))
        return ic_json_fail(c, line, IC_ERR_INVALID_ARG, "environment '%s' is %g, outside [%g, %g]; %s", it->string,
                            it->valuedouble, lo, hi, hint);
    *out = f;
    return IC_OK;
}

static const char *const keys[] = {"sky",       "zenith_radiance", "zenith_luminance", "diffuse_horizontal",
                                   "direct_normal", "sun_direction", "month",         "day",
                                   "hour",      "latitude",        "longitude",        "meridian",
                                   "ground_reflectance", "north",  "rotation_deg",     "portals"};
enum { K_SKY, K_ZRAD, K_ZLUM, K_DH, K_DN, K_SUNDIR, K_MONTH, K_DAY, K_HOUR, K_LAT, K_LON, K_MER, K_GROUND, K_NORTH,
       K_ROT, K_PORTALS, K_COUNT };
#define BIT(k) (1u << (k))
#define DATE_KEYS (BIT(K_MONTH) | BIT(K_DAY) | BIT(K_HOUR) | BIT(K_LAT) | BIT(K_LON))

/* Reads the sky's keys into p; *given: bit k set for the k-th name of `keys` present. */
static ic_result read_keys(json_ctx *c, const cJSON *obj, ic_sky_params *p, unsigned *given)
{
    static const char *valid = "sky, zenith_radiance, zenith_luminance, diffuse_horizontal, direct_normal, "
                               "sun_direction, month, day, hour, latitude, longitude, meridian, ground_reflectance, "
                               "north, rotation_deg, portals";
    const cJSON *it;
    cJSON_ArrayForEach(it, obj)
    {
        int kl = ic_json_locate_key(c, it->string);
        if (ic_json_is_comment(it->string))
            continue;
        int k = 0;
        while (k < K_COUNT && strcmp(it->string, keys[k]))
            ++k;
        if (k == K_COUNT)
            return ic_json_unknown_key(c, kl, it->string, "a sky environment", valid);
        *given |= BIT(k);
        ic_result r = IC_OK;
        double v = 0.0, lum = 0.0;
        const char *name = NULL;
        switch (k) {
        case K_SKY:
            r = ic_json_read_string(c, it, kl, &name);
            if (r == IC_OK) {
                p->model = !strcmp(name, "cie-overcast") ? IC_SKY_CIE_OVERCAST
                           : !strcmp(name, "cie-clear")  ? IC_SKY_CIE_CLEAR
                           : !strcmp(name, "perez")      ? IC_SKY_PEREZ
                                                         : IC_SKY_NONE;
                if (p->model == IC_SKY_NONE)
                    return ic_json_fail(c, kl, IC_ERR_INVALID_ARG,
                                        "unknown sky '%s'; use \"cie-overcast\", \"cie-clear\" or \"perez\"", name);
            }
            break;
        case K_ZRAD:
            r = read_ranged(c, it, kl, 1e-30, IC_SCENE_MAX_RADIANCE, "give the zenith radiance in W/(m2 sr), > 0",
                            &p->zenith_radiance);
            break;
        case K_ZLUM:
            r = read_ranged(c, it, kl, 1e-30, IC_SCENE_MAX_RADIANCE, "give the zenith luminance in cd/m2, > 0", &lum);
            p->zenith_radiance = lum / IC_SKY_EFFICACY;
            break;
        case K_DH:
            r = read_ranged(c, it, kl, 1e-30, IC_SCENE_MAX_RADIANCE,
                            "give the diffuse horizontal irradiance in W/m2, > 0",
                            &p->diffuse_horizontal);
            break;
        case K_DN:
            if (cJSON_IsString(it) && !strcmp(it->valuestring, "gensky")) {
                p->direct_normal_gensky = 1;
                break;
            }
            r = read_ranged(c, it, kl, 0.0, IC_SCENE_MAX_RADIANCE,
                            "give the direct normal irradiance in W/m2, >= 0 (or \"gensky\")",
                            &p->direct_normal);
            break;
        case K_SUNDIR:
            r = ic_json_read_vec3(c, it, kl, &p->sun_direction);
            p->has_sun_direction = 1;
            break;
        case K_MONTH:
            r = ic_json_read_int(c, it, kl, 1, 12, "give the month, 1-12", &v);
            p->month = (int)v;
            break;
        case K_DAY:
            r = ic_json_read_int(c, it, kl, 1, 31, "give the day of the month", &v);
            p->day = (int)v;
            break;
        case K_HOUR:
            r = read_ranged(c, it, kl, 0.0, 24.0, "give the local standard time in decimal hours, 0-24", &p->hour);
            break;
        case K_LAT:
            r = read_ranged(c, it, kl, -90.0, 90.0, "give the latitude in degrees north, -90 to 90", &p->latitude);
            break;
        case K_LON:
            r = read_ranged(c, it, kl, -180.0, 180.0, "give the longitude in degrees east, -180 to 180",
                            &p->longitude);
            break;
        case K_MER:
            r = read_ranged(c, it, kl, -180.0, 180.0, "give the time zone's meridian in degrees east, -180 to 180",
                            &p->meridian);
            p->has_meridian = 1;
            break;
        case K_GROUND:
            r = read_ranged(c, it, kl, 0.0, 1.0, "give the ground's reflectance, 0-1", &p->ground_reflectance);
            p->has_ground = 1;
            break;
        case K_ROT:
            r = read_ranged(c, it, kl, -360.0, 360.0, "give the sky's rotation about +y in degrees, -360 to 360",
                            &p->rotation_deg);
            break;
        case K_PORTALS:
            r = ic_json_parse_portals(c, it, kl);
            break;
        default:
            r = ic_json_read_vec3(c, it, kl, &p->north);
            p->has_north = 1;
            break;
        }
        if (r != IC_OK)
            return r;
    }
    return IC_OK;
}

/* The combinations of keys each model accepts (the message names the first offending key). */
static ic_result check_keys(json_ctx *c, int line, const ic_sky_params *p, unsigned given)
{
    static const char *const names[] = {"", "cie-overcast", "cie-clear", "perez"};
    const char *model = names[p->model];
    unsigned brightness = given & (BIT(K_ZRAD) | BIT(K_ZLUM) | BIT(K_DH));
    if (p->model == IC_SKY_PEREZ) {
        if ((given & (BIT(K_DH) | BIT(K_DN))) != (BIT(K_DH) | BIT(K_DN)) || (given & (BIT(K_ZRAD) | BIT(K_ZLUM))))
            return ic_json_fail(c, line, IC_ERR_INVALID_ARG,
                                "the perez sky needs 'diffuse_horizontal' and 'direct_normal' (W/m2, as gendaylit "
                                "-W takes them) and no zenith value");
    } else if (brightness != BIT(K_ZRAD) && brightness != BIT(K_ZLUM) && brightness != BIT(K_DH)) {
        return ic_json_fail(c, line, IC_ERR_INVALID_ARG,
                            "the %s sky needs exactly one of 'zenith_radiance' (W/(m2 sr)), 'zenith_luminance' "
                            "(cd/m2) or 'diffuse_horizontal' (W/m2)",
                            model);
    }
    if (p->direct_normal_gensky && p->model != IC_SKY_CIE_CLEAR)
        return ic_json_fail(c, line, IC_ERR_INVALID_ARG,
                            "'direct_normal': \"gensky\" is gensky's sun of its clear sky; give the %s sky's "
                            "direct normal irradiance in W/m2",
                            model);
    unsigned sun_keys = BIT(K_DN) | BIT(K_SUNDIR) | DATE_KEYS | BIT(K_MER);
    if (p->model == IC_SKY_CIE_OVERCAST) {
        if (given & sun_keys)
            return ic_json_fail(c, line, IC_ERR_INVALID_ARG,
                                "the cie-overcast sky has no sun and does not depend on it; remove 'direct_normal', "
                                "'sun_direction' and the date, time and place");
        return IC_OK;
    }
    int has_dir = (given & BIT(K_SUNDIR)) != 0, date = (given & DATE_KEYS) != 0;
    if (has_dir == date || (date && (given & DATE_KEYS) != DATE_KEYS) || (has_dir && (given & BIT(K_MER))))
        return ic_json_fail(c, line, IC_ERR_INVALID_ARG,
                            "the %s sky needs the sun: either 'sun_direction' [x, y, z] or all of 'month', 'day', "
                            "'hour', 'latitude' and 'longitude' (and optionally 'meridian'), not both",
                            model);
    /* The day must exist in its month (29 February is taken: the year is not given). */
    static const int days_in[12] = {31, 29, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
    if (date && p->day > days_in[p->month - 1])
        return ic_json_fail(c, line, IC_ERR_INVALID_ARG, "'day' %d: month %d has %d days; give a day of that month",
                            p->day, p->month, days_in[p->month - 1]);
    return IC_OK;
}

ic_result ic_json_parse_sky(json_ctx *c, const cJSON *obj, int line)
{
    ic_scene *s = c->b->scene;
    ic_sky_params p;
    memset(&p, 0, sizeof p);
    unsigned given = 0;
    ic_result r = read_keys(c, obj, &p, &given);
    if (r != IC_OK)
        return r;
    if (!(given & BIT(K_SKY)))
        return ic_json_fail(c, line, IC_ERR_PARSE, "environment: no 'sky'");
    r = check_keys(c, line, &p, given);
    if (r != IC_OK)
        return r;
    p.has_date = (given & DATE_KEYS) == DATE_KEYS;
    char why[256];
    r = ic_scene_install_sky(s, &p, 1, 1, 1.0f, why, sizeof why);
    if (r == IC_ERR_UNSUPPORTED)
        return ic_json_fail(c, line, r, "the sky's sun ('direct_normal') and a sun light: give only one");
    return r == IC_OK ? IC_OK : ic_json_fail(c, line, r, "environment sky: %s", why);
}
