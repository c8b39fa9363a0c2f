/*
 * scene_json_light.c — the "lights" (point and sun lights) and "environment" (constant radiance or an
 * equirectangular map; a daylight sky is read by scene_json_sky.c) sections of the JSON scene file.
 */
#include "scene/json_context.h"

#include "core/vecmath.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

ic_result ic_json_parse_portals(json_ctx *c, const cJSON *arr, int line)
{
    static const char *hint = "give \"portals\": [[[x, y, z], [x, y, z], [x, y, z], [x, y, z]], ...], each "
                              "portal the four corners of a window, in order around it";
    if (!cJSON_IsArray(arr) || cJSON_GetArraySize(arr) == 0)
        return ic_json_fail(c, line, IC_ERR_PARSE, "environment 'portals' is not a non-empty array; %s", hint);
    const cJSON *portal;
    int k = 0;
    cJSON_ArrayForEach(portal, arr)
    {
        ++k;
        if (!cJSON_IsArray(portal) || cJSON_GetArraySize(portal) != 4)
            return ic_json_fail(c, line, IC_ERR_PARSE, "portal %d is not an array of four corners; %s", k, hint);
        ic_vec3 corners[4];
        for (int i = 0; i < 4; ++i) {
            const cJSON *q = cJSON_GetArrayItem(portal, i);
            int ok = cJSON_IsArray(q) && cJSON_GetArraySize(q) == 3;
            for (int a = 0; ok && a < 3; ++a) {
                const cJSON *e = cJSON_GetArrayItem(q, a);
                ok = cJSON_IsNumber(e) && isfinite(e->valuedouble) && fabs(e->valuedouble) <= 3.0e38;
            }
            if (!ok)
                return ic_json_fail(c, line, IC_ERR_PARSE, "portal %d, corner %d is not [x, y, z] (3 finite numbers); %s",
                                    k, i + 1, hint);
            ic_result r = ic_json_read_vec3(c, q, line, &corners[i]);
            if (r != IC_OK)
                return r;
        }
        ic_error perr;
        ic_result r = ic_scene_add_portal(c->b->scene, corners, &perr);
        if (r != IC_OK)
            return ic_json_fail(c, line, r, "portal %d: %s", k, perr.message);
    }
    return IC_OK;
}

ic_result ic_json_parse_environment(json_ctx *c, const cJSON *obj, int line)
{
    static const char *valid = "radiance, map, scale, rotation_deg, portals (or sky: see the scene format's Skies)";
    ic_environment *env = &c->b->scene->env;
    ic_result r = ic_json_expect_object(c, obj, line);
    if (r != IC_OK)
        return r;
    if (cJSON_GetObjectItemCaseSensitive(obj, "sky"))
        return ic_json_parse_sky(c, obj, line);
    const char *map = NULL;
    int map_line = line, has_radiance = 0, has_scale = 0;
    ic_vec3 radiance = v3s(0.0f), scale = v3s(1.0f);
    const cJSON *it;
    cJSON_ArrayForEach(it, obj)
    {
        int kl = ic_json_locate_key(c, it->string);
        if (ic_json_is_comment(it->string))
            continue;
        if (!strcmp(it->string, "radiance")) {
            r = ic_json_read_radiance(c, it, kl, &radiance);
            has_radiance = 1;
        } else if (!strcmp(it->string, "map")) {
            r = ic_json_read_string(c, it, kl, &map);
            map_line = kl;
        } else if (!strcmp(it->string, "scale")) {
            r = ic_json_read_color(c, it, kl, &scale);
            has_scale = 1;
        } else if (!strcmp(it->string, "rotation_deg")) {
            r = ic_json_read_float(c, it, kl, &env->rotation_deg);
        } else if (!strcmp(it->string, "portals")) {
            r = ic_json_parse_portals(c, it, kl);
        } else {
            return ic_json_unknown_key(c, kl, it->string, "environment", valid);
        }
        if (r != IC_OK)
            return r;
    }
    if (map && has_radiance)
        return ic_json_fail(c, line, IC_ERR_INVALID_ARG,
                            "environment gives both 'radiance' and 'map'; use 'map' with "
                            "'scale', or 'radiance' alone");
    if (!map && has_scale)
        return ic_json_fail(c, line, IC_ERR_INVALID_ARG,
                            "environment 'scale' applies to a 'map'; give 'radiance' for a "
                            "constant sky");
    if (!map && !has_radiance)
        return ic_json_fail(c, line, IC_ERR_PARSE,
                            "environment needs 'radiance' [r, g, b] or 'map' (an .exr/.hdr file)");
    env->enabled = 1;
    if (!map) {
        env->radiance = radiance;
        return IC_OK;
    }
    char full[IC_SCENE_PATH_MAX];
    r = ic_json_resolve_path(c, map, map_line, "environment map", full, sizeof full);
    if (r != IC_OK)
        return r;
    ic_error ierr;
    r = ic_image_read_max(full, ic_scene_max_texture_pixels(c->opt), IC_SCENE_RAISE_TEXTURE_LIMIT, &env->image,
                          &ierr);
    if (r != IC_OK)
        return ic_json_fail(c, map_line, r, "environment map: %s", ierr.message);
    if ((r = ic_scene_check_env_map(&env->image, scale, map, c->path, map_line, c->err)) != IC_OK)
        return r;
    env->radiance = scale;
    return IC_OK;
}

/* {"type": "spot", "position", "intensity", "direction", "cone_inner", "cone_outer"}: a point light lighting
 * the cone about direction, full inside cone_inner degrees, none outside cone_outer, t² between (as glTF's
 * KHR_lights_punctual). */
static ic_result parse_spot(json_ctx *c, const cJSON *obj, int index, int line)
{
    static const char *valid = "type, position, intensity, direction, cone_inner, cone_outer";
    ic_vec3 pos = v3s(0.0f), intensity = v3s(0.0f), dir = v3s(0.0f);
    float inner = 0.0f, outer = 45.0f;
    int has = 0;
    const cJSON *it;
    cJSON_ArrayForEach(it, obj)
    {
        int kl = ic_json_locate_key(c, it->string);
        ic_result r = IC_OK;
        if (ic_json_is_comment(it->string) || !strcmp(it->string, "type"))
            continue;
        if (!strcmp(it->string, "position"))
            r = ic_json_read_vec3(c, it, kl, &pos), has |= 1;
        else if (!strcmp(it->string, "intensity"))
            r = ic_json_read_radiance(c, it, kl, &intensity), has |= 2;
        else if (!strcmp(it->string, "direction"))
            r = ic_json_read_vec3(c, it, kl, &dir), has |= 4;
        else if (!strcmp(it->string, "cone_inner"))
            r = ic_json_read_float(c, it, kl, &inner);
        else if (!strcmp(it->string, "cone_outer"))
            r = ic_json_read_float(c, it, kl, &outer);
        else
            return ic_json_unknown_key(c, kl, it->string, "a spot light", valid);
        if (r != IC_OK)
            return r;
    }
    if (has != 7)
        return ic_json_fail(c, line, IC_ERR_PARSE, "lights[%d] (spot) needs 'position', 'intensity' and 'direction'",
                            index);
    if (!(v3_len2(dir) > 0.0f))
        return ic_json_fail(c, line, IC_ERR_INVALID_ARG, "lights[%d] spot 'direction' is zero; give where it points",
                            index);
    if (!(inner >= 0.0f && inner < outer && outer <= 180.0f))
        return ic_json_fail(c, line, IC_ERR_INVALID_ARG,
                            "lights[%d] spot cones %g and %g: need 0 <= cone_inner < cone_outer <= 180 (degrees)", index,
                            (double)inner, (double)outer);
    ic_spot_cone cone = {v3_norm(dir), cosf(inner * IC_PI / 180.0f), cosf(outer * IC_PI / 180.0f)};
    if (ic_scene_add_point_light(c->b->scene, pos, intensity, &cone) != IC_OK)
        return ic_json_fail(c, line, IC_ERR_OOM, "out of memory for lights");
    return IC_OK;
}

static ic_result parse_light(json_ctx *c, const cJSON *obj, int index)
{
    ic_scene *s = c->b->scene;
    int line = ic_json_locate_object_start(c);
    if (!cJSON_IsObject(obj))
        return ic_json_fail(c, line, IC_ERR_PARSE, "lights[%d] must be an object with a 'type'", index);
    const cJSON *type = cJSON_GetObjectItemCaseSensitive(obj, "type");
    int type_line = ic_json_peek_key_line(c, "type");
    if (!type || !cJSON_IsString(type))
        return ic_json_fail(c, line, IC_ERR_PARSE, "lights[%d] needs \"type\": \"point\", \"spot\" or \"sun\"",
                            index);
    if (!strcmp(type->valuestring, "spot"))
        return parse_spot(c, obj, index, line);
    int is_point = !strcmp(type->valuestring, "point"), is_sun = !strcmp(type->valuestring, "sun");
    if (!is_point && !is_sun)
        return ic_json_fail(c, type_line, IC_ERR_INVALID_ARG,
                            "unknown light type '%s'; use \"point\", \"spot\" or \"sun\"", type->valuestring);
    const char *valid = is_point ? "type, position, intensity" : "type, direction, irradiance, angular_radius_deg";
    ic_vec3 a = v3s(0.0f), e = v3s(0.0f);
    int has_a = 0, has_e = 0;
    float radius_deg = 0.0f;
    const cJSON *it;
    ic_result r = IC_OK;
    cJSON_ArrayForEach(it, obj)
    {
        int kl = ic_json_locate_key(c, it->string);
        if (ic_json_is_comment(it->string) || !strcmp(it->string, "type"))
            continue;
        if (!strcmp(it->string, is_point ? "position" : "direction")) {
            r = ic_json_read_vec3(c, it, kl, &a);
            has_a = 1;
        } else if (!strcmp(it->string, is_point ? "intensity" : "irradiance")) {
            r = ic_json_read_radiance(c, it, kl, &e);
            has_e = 1;
        } else if (is_sun && !strcmp(it->string, "angular_radius_deg")) {
            r = ic_json_read_float(c, it, kl, &radius_deg);
            if (r == IC_OK && !(radius_deg >= 0.0f && radius_deg <= 45.0f))
                return ic_json_fail(c, kl, IC_ERR_INVALID_ARG,
                                    "lights[%d] sun 'angular_radius_deg' is %g; give 0 (a directional light) to 45",
                                    index, (double)radius_deg);
        } else {
            return ic_json_unknown_key(c, kl, it->string, is_point ? "a point light" : "a sun light", valid);
        }
        if (r != IC_OK)
            return r;
    }
    if (!has_a || !has_e)
        return ic_json_fail(c, line, IC_ERR_PARSE, "lights[%d] (%s) needs %s", index, type->valuestring,
                            is_point ? "'position' and 'intensity'" : "'direction' and 'irradiance'");
    if (is_sun) {
        if (s->sun.enabled)
            return ic_json_fail(c, line, IC_ERR_UNSUPPORTED, "only one sun light is supported; remove lights[%d]",
                                index);
        if (!(v3_len2(a) > 0.0f))
            return ic_json_fail(c, line, IC_ERR_INVALID_ARG,
                                "lights[%d] sun 'direction' is zero; give the direction "
                                "towards the sun",
                                index);
        s->sun.enabled = 1;
        s->sun.direction = v3_norm(a);
        s->sun.irradiance = e;
        s->sun.angular_radius = radius_deg * IC_PI / 180.0f;
        return IC_OK;
    }
    if (ic_scene_add_point_light(s, a, e, NULL) != IC_OK)
        return ic_json_fail(c, line, IC_ERR_OOM, "out of memory for lights");
    return IC_OK;
}

ic_result ic_json_parse_lights(json_ctx *c, const cJSON *arr, int line)
{
    if (!cJSON_IsArray(arr))
        return ic_json_fail(c, line, IC_ERR_PARSE, "'lights' must be an array of light objects");
    int i = 0;
    const cJSON *it;
    cJSON_ArrayForEach(it, arr)
    {
        ic_result r = parse_light(c, it, i++);
        if (r != IC_OK)
            return r;
    }
    return IC_OK;
}
