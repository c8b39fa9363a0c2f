/*
 * scene_json.c — the JSON scene file (format: docs/scene-format.md), parsed with cJSON.
 *
 * Every message names the scene file and a line. cJSON keeps no positions, so a syntax error's line is
 * counted up to where the parser stopped, and a key's line is found by searching the text for `"key":`
 * from a cursor that walks forward as the document is visited in its own order (objects' keys are
 * handled in file order, so the n-th occurrence found is the one being handled). The top level is
 * visited in a fixed order (meshes before the material overrides that refer to them), each section
 * restarting the search at its own key. Unknown keys are errors that list the valid ones: a typo
 * should not silently drop a setting. Keys starting with '_' are comments and ignored.
 */
#include "scene/scene_internal.h"

#include "core/vecmath.h"

#include <cjson/cJSON.h>

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Largest scene file accepted (scene files are small; meshes live in their own files). */
#define MAX_SCENE_FILE_BYTES (64u << 20)
#define MAX_RESOLUTION 65536

typedef struct json_ctx {
    const char *path;              /* the scene file, for messages */
    char dir[IC_SCENE_PATH_MAX];   /* its directory: relative paths resolve against it */
    const char *text;              /* the file's text */
    size_t len;
    size_t cursor;                 /* key search starts here */
    int line;                      /* line of the last key found */
    const ic_scene_load_options *opt;
    ic_scene_builder *b;
    ic_error *err;
} json_ctx;

/* ------------------------------------------------------------------------------------------------ */
/* positions and messages */

static int line_of(const json_ctx *c, size_t off)
{
    int line = 1;
    for (size_t i = 0; i < off && i < c->len; ++i)
        line += c->text[i] == '\n';
    return line;
}

/* Offset just past the next `"key"` followed by ':' at or after `from`, or (size_t)-1. */
static size_t find_key(const json_ctx *c, const char *key, size_t from)
{
    size_t klen = strlen(key);
    for (size_t i = from; i + klen + 2 <= c->len; ++i) {
        if (c->text[i] != '"' || strncmp(c->text + i + 1, key, klen) != 0 || c->text[i + 1 + klen] != '"')
            continue;
        size_t j = i + klen + 2;
        while (j < c->len && (c->text[j] == ' ' || c->text[j] == '\t' || c->text[j] == '\n' || c->text[j] == '\r'))
            ++j;
        if (j < c->len && c->text[j] == ':')
            return j + 1;
    }
    return (size_t)-1;
}

/* Moves the cursor past the next occurrence of key and returns its line (the last line if absent). */
static int locate_key(json_ctx *c, const char *key)
{
    size_t at = find_key(c, key, c->cursor);
    if (at != (size_t)-1) {
        c->line = line_of(c, at);
        c->cursor = at;
    }
    return c->line;
}

/* Line of the next occurrence of key without moving the cursor. */
static int peek_key_line(const json_ctx *c, const char *key)
{
    size_t at = find_key(c, key, c->cursor);
    return at != (size_t)-1 ? line_of(c, at) : c->line;
}

/* Moves the cursor to the next '{' (the start of an array's object element) and returns its line. */
static int locate_object_start(json_ctx *c)
{
    const char *brace = memchr(c->text + c->cursor, '{', c->len - c->cursor);
    if (brace) {
        c->cursor = (size_t)(brace - c->text) + 1;
        c->line = line_of(c, c->cursor);
    }
    return c->line;
}

static ic_result fail(json_ctx *c, int line, ic_result code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static ic_result fail(json_ctx *c, int line, ic_result code, const char *fmt, ...)
{
    char msg[900];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return ic_error_set(c->err, code, "%s:%d: %s", c->path, line, msg);
}

static int is_comment(const char *key) { return key && key[0] == '_'; }

static ic_result unknown_key(json_ctx *c, int line, const char *key, const char *where, const char *valid)
{
    return fail(c, line, IC_ERR_PARSE, "unknown key '%s' in %s; valid keys: %s", key, where, valid);
}

/* ------------------------------------------------------------------------------------------------ */
/* values */

static ic_result read_number(json_ctx *c, const cJSON *it, int line, double *out)
{
    if (!cJSON_IsNumber(it) || !isfinite(it->valuedouble))
        return fail(c, line, IC_ERR_PARSE, "'%s' must be a number", it->string);
    *out = it->valuedouble;
    return IC_OK;
}

static ic_result read_float(json_ctx *c, const cJSON *it, int line, float *out)
{
    double d = 0.0;
    ic_result r = read_number(c, it, line, &d);
    if (r == IC_OK && fabs(d) > 3.0e38)
        return fail(c, line, IC_ERR_PARSE, "'%s' = %g is out of range", it->string, d);
    *out = (float)d;
    return r;
}

/* An integer in [lo, hi]. */
static ic_result read_int(json_ctx *c, const cJSON *it, int line, double lo, double hi, const char *hint,
                          double *out)
{
    if (!cJSON_IsNumber(it) || !isfinite(it->valuedouble) || it->valuedouble != floor(it->valuedouble) ||
        it->valuedouble < lo || it->valuedouble > hi) {
        char shown[64];
        if (cJSON_IsNumber(it))
            snprintf(shown, sizeof shown, "%g", it->valuedouble);
        else
            snprintf(shown, sizeof shown, "a non-number");
        return fail(c, line, IC_ERR_INVALID_ARG, "'%s' is %s but must be an integer from %.0f to %.0f; %s",
                    it->string, shown, lo, hi, hint);
    }
    *out = it->valuedouble;
    return IC_OK;
}

static ic_result read_vec3(json_ctx *c, const cJSON *it, int line, ic_vec3 *out)
{
    float v[3];
    if (!cJSON_IsArray(it) || cJSON_GetArraySize(it) != 3)
        return fail(c, line, IC_ERR_PARSE, "'%s' must be an array of 3 numbers, like [0, 1, 0]", it->string);
    for (int k = 0; k < 3; ++k) {
        const cJSON *e = cJSON_GetArrayItem(it, k);
        if (!cJSON_IsNumber(e) || !isfinite(e->valuedouble) || fabs(e->valuedouble) > 3.0e38)
            return fail(c, line, IC_ERR_PARSE, "'%s' must be an array of 3 finite numbers, like [0, 1, 0]",
                        it->string);
        v[k] = (float)e->valuedouble;
    }
    *out = v3(v[0], v[1], v[2]);
    return IC_OK;
}

/* A colour: one non-negative number (grey) or [r, g, b]. */
static ic_result read_color(json_ctx *c, const cJSON *it, int line, ic_vec3 *out)
{
    ic_result r;
    if (cJSON_IsNumber(it)) {
        float g;
        r = read_float(c, it, line, &g);
        *out = v3s(g);
    } else {
        r = read_vec3(c, it, line, out);
    }
    if (r != IC_OK)
        return fail(c, line, IC_ERR_PARSE, "'%s' must be a colour: a number or [r, g, b]", it->string);
    if (out->x < 0.0f || out->y < 0.0f || out->z < 0.0f)
        return fail(c, line, IC_ERR_INVALID_ARG, "'%s' has a negative component; colours must be >= 0", it->string);
    return IC_OK;
}

static ic_result read_string(json_ctx *c, const cJSON *it, int line, const char **out)
{
    if (!cJSON_IsString(it) || !it->valuestring)
        return fail(c, line, IC_ERR_PARSE, "'%s' must be a string", it->string);
    *out = it->valuestring;
    return IC_OK;
}

static ic_result expect_object(json_ctx *c, const cJSON *it, int line)
{
    if (!cJSON_IsObject(it))
        return fail(c, line, IC_ERR_PARSE, "'%s' must be an object { ... }", it->string);
    return IC_OK;
}

/* ------------------------------------------------------------------------------------------------ */
/* paths */

/* Resolves a path from the scene file: relative to its directory, or "shared:rest" against the shared
 * scenes folder (option, $IRRCACHE_SCENES, <dir>/../../../shared/scenes, <dir>/../../shared/scenes —
 * the first that holds the file). Reports `what` not found at line. */
static ic_result resolve_path(json_ctx *c, const char *given, int line, const char *what, char *out, size_t size)
{
    char tried[IC_SCENE_PATH_MAX] = "";
    if (!given[0])
        return fail(c, line, IC_ERR_INVALID_ARG, "empty path for %s; give a file name", what);
    if (!strncmp(given, "shared:", 7)) {
        const char *rest = given + 7;
        char up3[IC_SCENE_PATH_MAX + 32], up2[IC_SCENE_PATH_MAX + 32];
        snprintf(up3, sizeof up3, "%s/../../../shared/scenes", c->dir);
        snprintf(up2, sizeof up2, "%s/../../shared/scenes", c->dir);
        const char *env = getenv("IRRCACHE_SCENES");
        const char *dirs[4] = {c->opt->shared_scenes_dir, (env && *env) ? env : NULL, up3, up2};
        for (int k = 0; k < 4; ++k) {
            if (!dirs[k] || !dirs[k][0])
                continue;
            if (!ic_path_join(dirs[k], rest, out, size))
                return fail(c, line, IC_ERR_INVALID_ARG, "path of %s '%s' is too long; shorten it", what, given);
            if (ic_path_exists(out))
                return IC_OK;
            if (!tried[0])
                snprintf(tried, sizeof tried, "%s", out);
        }
        char abs_path[IC_SCENE_PATH_MAX];
        ic_path_absolute(tried, abs_path, sizeof abs_path);
        return fail(c, line, IC_ERR_IO,
                    "%s '%s' not found (resolved to %s); check the path, or point $IRRCACHE_SCENES or the "
                    "shared_scenes_dir option at the shared scenes folder",
                    what, given, abs_path);
    }
    if (!ic_path_join(c->dir, given, out, size))
        return fail(c, line, IC_ERR_INVALID_ARG, "path of %s '%s' is too long; shorten it", what, given);
    if (!ic_path_exists(out)) {
        char abs_path[IC_SCENE_PATH_MAX];
        ic_path_absolute(out, abs_path, sizeof abs_path);
        return fail(c, line, IC_ERR_IO, "%s '%s' not found (resolved to %s); check the path", what, given, abs_path);
    }
    return IC_OK;
}

/* ------------------------------------------------------------------------------------------------ */
/* sections */

typedef struct camera_spec {
    int given;
    int line;
    ic_vec3 eye, target, up;
    int has_eye, has_target;
    float fov_deg;
    int fov_is_x, has_fov;
    int width, height;
} camera_spec;

static ic_result check_fov(json_ctx *c, const cJSON *it, int line, float *fov)
{
    ic_result r = read_float(c, it, line, fov);
    if (r != IC_OK)
        return r;
    if (!(*fov > 0.0f && *fov < 180.0f))
        return fail(c, line, IC_ERR_INVALID_ARG,
                    "'%s' = %g is outside (0, 180); give the full field-of-view angle in degrees", it->string,
                    (double)*fov);
    return IC_OK;
}

static ic_result parse_camera(json_ctx *c, const cJSON *obj, int line, camera_spec *cam)
{
    static const char *valid = "eye, target, up, fov_y, fov_x, width, height";
    ic_result r = expect_object(c, obj, line);
    if (r != IC_OK)
        return r;
    cam->given = 1;
    cam->line = line;
    const cJSON *it;
    cJSON_ArrayForEach(it, obj)
    {
        int kl = locate_key(c, it->string);
        double d;
        if (is_comment(it->string))
            continue;
        if (!strcmp(it->string, "eye")) {
            r = read_vec3(c, it, kl, &cam->eye);
            cam->has_eye = 1;
        } else if (!strcmp(it->string, "target")) {
            r = read_vec3(c, it, kl, &cam->target);
            cam->has_target = 1;
        } else if (!strcmp(it->string, "up")) {
            r = read_vec3(c, it, kl, &cam->up);
        } else if (!strcmp(it->string, "fov_y") || !strcmp(it->string, "fov_x")) {
            if (cam->has_fov)
                return fail(c, kl, IC_ERR_INVALID_ARG, "camera gives both fov_x and fov_y; keep one");
            r = check_fov(c, it, kl, &cam->fov_deg);
            cam->has_fov = 1;
            cam->fov_is_x = !strcmp(it->string, "fov_x");
        } else if (!strcmp(it->string, "width")) {
            r = read_int(c, it, kl, 1, MAX_RESOLUTION, "give the image width in pixels", &d);
            cam->width = (int)d;
        } else if (!strcmp(it->string, "height")) {
            r = read_int(c, it, kl, 1, MAX_RESOLUTION, "give the image height in pixels", &d);
            cam->height = (int)d;
        } else {
            return unknown_key(c, kl, it->string, "camera", valid);
        }
        if (r != IC_OK)
            return r;
    }
    if (!cam->has_eye || !cam->has_target)
        return fail(c, line, IC_ERR_PARSE, "camera needs 'eye' and 'target' (3-vectors)");
    ic_vec3 view = v3_sub(cam->target, cam->eye);
    if (!(v3_len2(view) > 0.0f))
        return fail(c, line, IC_ERR_INVALID_ARG, "camera 'eye' and 'target' coincide; move the target");
    if (!(v3_len2(v3_cross(v3_norm(view), v3_norm(cam->up))) > 1e-10f))
        return fail(c, line, IC_ERR_INVALID_ARG, "camera 'up' is zero or parallel to the view direction; pick "
                                                 "another up vector");
    return IC_OK;
}

static ic_result parse_render(json_ctx *c, const cJSON *obj, int line)
{
    static const char *valid = "spp, max_depth, seed, exposure";
    ic_scene_settings *st = &c->b->scene->settings;
    ic_result r = expect_object(c, obj, line);
    if (r != IC_OK)
        return r;
    const cJSON *it;
    cJSON_ArrayForEach(it, obj)
    {
        int kl = locate_key(c, it->string);
        double d;
        if (is_comment(it->string))
            continue;
        if (!strcmp(it->string, "spp")) {
            r = read_int(c, it, kl, 1, 1 << 24, "give samples per pixel", &d);
            st->spp = (int)d;
        } else if (!strcmp(it->string, "max_depth")) {
            r = read_int(c, it, kl, 1, 1024, "give the maximum path length in bounces", &d);
            st->max_depth = (int)d;
        } else if (!strcmp(it->string, "seed")) {
            r = read_int(c, it, kl, 0, 9007199254740992.0, "give a non-negative integer seed", &d);
            st->seed = (uint64_t)d;
        } else if (!strcmp(it->string, "exposure")) {
            r = read_float(c, it, kl, &st->exposure);
            st->has_exposure = 1;
        } else {
            return unknown_key(c, kl, it->string, "render", valid);
        }
        if (r != IC_OK)
            return r;
    }
    return IC_OK;
}

static ic_result parse_environment(json_ctx *c, const cJSON *obj, int line)
{
    static const char *valid = "radiance, map, scale, rotation_deg";
    ic_environment *env = &c->b->scene->env;
    ic_result r = expect_object(c, obj, line);
    if (r != IC_OK)
        return r;
    const char *map = NULL;
    int map_line = line, has_radiance = 0, has_scale = 0;
    ic_vec3 radiance = v3s(0.0f), scale = v3s(1.0f);
    const cJSON *it;
    cJSON_ArrayForEach(it, obj)
    {
        int kl = locate_key(c, it->string);
        if (is_comment(it->string))
            continue;
        if (!strcmp(it->string, "radiance")) {
            r = read_color(c, it, kl, &radiance);
            has_radiance = 1;
        } else if (!strcmp(it->string, "map")) {
            r = read_string(c, it, kl, &map);
            map_line = kl;
        } else if (!strcmp(it->string, "scale")) {
            r = read_color(c, it, kl, &scale);
            has_scale = 1;
        } else if (!strcmp(it->string, "rotation_deg")) {
            r = read_float(c, it, kl, &env->rotation_deg);
        } else {
            return unknown_key(c, kl, it->string, "environment", valid);
        }
        if (r != IC_OK)
            return r;
    }
    if (map && has_radiance)
        return fail(c, line, IC_ERR_INVALID_ARG, "environment gives both 'radiance' and 'map'; use 'map' with "
                                                 "'scale', or 'radiance' alone");
    if (!map && has_scale)
        return fail(c, line, IC_ERR_INVALID_ARG, "environment 'scale' applies to a 'map'; give 'radiance' for a "
                                                 "constant sky");
    if (!map && !has_radiance)
        return fail(c, line, IC_ERR_PARSE, "environment needs 'radiance' [r, g, b] or 'map' (an .exr/.hdr file)");
    env->enabled = 1;
    if (!map) {
        env->radiance = radiance;
        return IC_OK;
    }
    char full[IC_SCENE_PATH_MAX];
    r = resolve_path(c, map, map_line, "environment map", full, sizeof full);
    if (r != IC_OK)
        return r;
    ic_error ierr;
    r = ic_image_read(full, &env->image, &ierr);
    if (r != IC_OK)
        return fail(c, map_line, r, "environment map: %s", ierr.message);
    env->radiance = scale;
    return IC_OK;
}

static ic_result parse_light(json_ctx *c, const cJSON *obj, int index)
{
    ic_scene *s = c->b->scene;
    int line = locate_object_start(c);
    if (!cJSON_IsObject(obj))
        return fail(c, line, IC_ERR_PARSE, "lights[%d] must be an object with a 'type'", index);
    const cJSON *type = cJSON_GetObjectItemCaseSensitive(obj, "type");
    int type_line = peek_key_line(c, "type");
    if (!type || !cJSON_IsString(type))
        return fail(c, line, IC_ERR_PARSE, "lights[%d] needs \"type\": \"point\" or \"sun\"", index);
    int is_point = !strcmp(type->valuestring, "point"), is_sun = !strcmp(type->valuestring, "sun");
    if (!is_point && !is_sun)
        return fail(c, type_line, IC_ERR_INVALID_ARG, "unknown light type '%s'; use \"point\" or \"sun\"",
                    type->valuestring);
    const char *valid = is_point ? "type, position, intensity" : "type, direction, irradiance";
    ic_vec3 a = v3s(0.0f), e = v3s(0.0f);
    int has_a = 0, has_e = 0;
    const cJSON *it;
    ic_result r = IC_OK;
    cJSON_ArrayForEach(it, obj)
    {
        int kl = locate_key(c, it->string);
        if (is_comment(it->string) || !strcmp(it->string, "type"))
            continue;
        if (!strcmp(it->string, is_point ? "position" : "direction")) {
            r = read_vec3(c, it, kl, &a);
            has_a = 1;
        } else if (!strcmp(it->string, is_point ? "intensity" : "irradiance")) {
            r = read_color(c, it, kl, &e);
            has_e = 1;
        } else {
            return unknown_key(c, kl, it->string, is_point ? "a point light" : "a sun light", valid);
        }
        if (r != IC_OK)
            return r;
    }
    if (!has_a || !has_e)
        return fail(c, line, IC_ERR_PARSE, "lights[%d] (%s) needs %s", index, type->valuestring,
                    is_point ? "'position' and 'intensity'" : "'direction' and 'irradiance'");
    if (is_sun) {
        if (s->sun.enabled)
            return fail(c, line, IC_ERR_UNSUPPORTED, "only one sun light is supported; remove lights[%d]", index);
        if (!(v3_len2(a) > 0.0f))
            return fail(c, line, IC_ERR_INVALID_ARG, "lights[%d] sun 'direction' is zero; give the direction "
                                                     "towards the sun",
                        index);
        s->sun.enabled = 1;
        s->sun.direction = v3_norm(a);
        s->sun.irradiance = e;
        return IC_OK;
    }
    ic_point_light *grown = realloc(s->point_lights, sizeof *grown * (s->point_light_count + 1));
    if (!grown)
        return fail(c, line, IC_ERR_OOM, "out of memory for lights");
    s->point_lights = grown;
    s->point_lights[s->point_light_count].position = a;
    s->point_lights[s->point_light_count].intensity = e;
    ++s->point_light_count;
    return IC_OK;
}

static ic_result parse_lights(json_ctx *c, const cJSON *arr, int line)
{
    if (!cJSON_IsArray(arr))
        return fail(c, line, IC_ERR_PARSE, "'lights' must be an array of light objects");
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

/* Rotation by angle (radians) about unit axis (Rodrigues), row-major 4x4. */
static void rotation_matrix(ic_vec3 axis, float angle, float m[16])
{
    float cs = cosf(angle), sn = sinf(angle), t = 1.0f - cs;
    float x = axis.x, y = axis.y, z = axis.z;
    ic_mat4_identity(m);
    m[0] = t * x * x + cs;
    m[1] = t * x * y - sn * z;
    m[2] = t * x * z + sn * y;
    m[4] = t * x * y + sn * z;
    m[5] = t * y * y + cs;
    m[6] = t * y * z - sn * x;
    m[8] = t * x * z - sn * y;
    m[9] = t * y * z + sn * x;
    m[10] = t * z * z + cs;
}

static ic_result parse_transform(json_ctx *c, const cJSON *obj, int line, float m[16])
{
    static const char *valid = "translate, rotate_deg, rotate_axis, rotate_angle_deg, scale";
    ic_result r = expect_object(c, obj, line);
    if (r != IC_OK)
        return r;
    ic_vec3 translate = v3s(0.0f), rot_deg = v3s(0.0f), axis = v3s(0.0f), scale = v3s(1.0f);
    float angle = 0.0f;
    int has_euler = 0, has_axis = 0, has_angle = 0, scale_line = line;
    const cJSON *it;
    cJSON_ArrayForEach(it, obj)
    {
        int kl = locate_key(c, it->string);
        if (is_comment(it->string))
            continue;
        if (!strcmp(it->string, "translate")) {
            r = read_vec3(c, it, kl, &translate);
        } else if (!strcmp(it->string, "rotate_deg")) {
            r = read_vec3(c, it, kl, &rot_deg);
            has_euler = 1;
        } else if (!strcmp(it->string, "rotate_axis")) {
            r = read_vec3(c, it, kl, &axis);
            has_axis = 1;
            if (r == IC_OK && !(v3_len2(axis) > 0.0f))
                return fail(c, kl, IC_ERR_INVALID_ARG, "'rotate_axis' is zero; give a non-zero axis");
        } else if (!strcmp(it->string, "rotate_angle_deg")) {
            r = read_float(c, it, kl, &angle);
            has_angle = 1;
        } else if (!strcmp(it->string, "scale")) {
            scale_line = kl;
            if (cJSON_IsNumber(it)) {
                float sc;
                r = read_float(c, it, kl, &sc);
                scale = v3s(sc);
            } else {
                r = read_vec3(c, it, kl, &scale);
            }
        } else {
            return unknown_key(c, kl, it->string, "transform", valid);
        }
        if (r != IC_OK)
            return r;
    }
    if (has_euler && (has_axis || has_angle))
        return fail(c, line, IC_ERR_INVALID_ARG, "transform gives both 'rotate_deg' and an axis-angle rotation; "
                                                 "keep one");
    if (has_axis != has_angle)
        return fail(c, line, IC_ERR_INVALID_ARG, "'rotate_axis' and 'rotate_angle_deg' go together; give both");
    if (scale.x == 0.0f || scale.y == 0.0f || scale.z == 0.0f)
        return fail(c, scale_line, IC_ERR_INVALID_ARG, "'scale' has a zero component; the mesh would be flat");

    /* M = T · R · S, with R = Rz · Ry · Rx for Euler angles (x applied first) */
    float s4[16], r4[16], t4[16], tmp[16];
    ic_mat4_identity(s4);
    s4[0] = scale.x;
    s4[5] = scale.y;
    s4[10] = scale.z;
    const float deg = IC_PI / 180.0f;
    if (has_axis) {
        rotation_matrix(v3_norm(axis), angle * deg, r4);
    } else {
        float rx[16], ry[16], rz[16];
        rotation_matrix(v3(1, 0, 0), rot_deg.x * deg, rx);
        rotation_matrix(v3(0, 1, 0), rot_deg.y * deg, ry);
        rotation_matrix(v3(0, 0, 1), rot_deg.z * deg, rz);
        ic_mat4_mul(ry, rx, tmp);
        ic_mat4_mul(rz, tmp, r4);
    }
    ic_mat4_identity(t4);
    t4[3] = translate.x;
    t4[7] = translate.y;
    t4[11] = translate.z;
    ic_mat4_mul(r4, s4, tmp);
    ic_mat4_mul(t4, tmp, m);
    return IC_OK;
}

/* "matrix": 16 numbers row-major, or 4 rows of 4; affine (last row 0 0 0 1) and invertible. */
static ic_result parse_matrix(json_ctx *c, const cJSON *it, int line, float m[16])
{
    static const char *shape = "'matrix' must be 16 numbers (row-major 4x4) or 4 rows of 4 numbers";
    int n = cJSON_IsArray(it) ? cJSON_GetArraySize(it) : 0;
    if (n == 16) {
        for (int k = 0; k < 16; ++k) {
            const cJSON *e = cJSON_GetArrayItem(it, k);
            if (!cJSON_IsNumber(e) || !isfinite(e->valuedouble))
                return fail(c, line, IC_ERR_PARSE, "%s", shape);
            m[k] = (float)e->valuedouble;
        }
    } else if (n == 4) {
        for (int i = 0; i < 4; ++i) {
            const cJSON *row = cJSON_GetArrayItem(it, i);
            if (!cJSON_IsArray(row) || cJSON_GetArraySize(row) != 4)
                return fail(c, line, IC_ERR_PARSE, "%s", shape);
            for (int j = 0; j < 4; ++j) {
                const cJSON *e = cJSON_GetArrayItem(row, j);
                if (!cJSON_IsNumber(e) || !isfinite(e->valuedouble))
                    return fail(c, line, IC_ERR_PARSE, "%s", shape);
                m[4 * i + j] = (float)e->valuedouble;
            }
        }
    } else {
        return fail(c, line, IC_ERR_PARSE, "%s", shape);
    }
    if (m[12] != 0.0f || m[13] != 0.0f || m[14] != 0.0f || m[15] != 1.0f)
        return fail(c, line, IC_ERR_INVALID_ARG, "'matrix' must be affine: its last row must be [0, 0, 0, 1]");
    float det = m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
                m[2] * (m[4] * m[9] - m[5] * m[8]);
    if (det == 0.0f)
        return fail(c, line, IC_ERR_INVALID_ARG, "'matrix' is singular (the mesh would be flattened)");
    return IC_OK;
}

static ic_result parse_mesh(json_ctx *c, const cJSON *obj, int index)
{
    static const char *valid = "path, transform, matrix";
    int line = locate_object_start(c);
    if (!cJSON_IsObject(obj))
        return fail(c, line, IC_ERR_PARSE, "meshes[%d] must be an object with a 'path'", index);
    const char *path = NULL;
    int path_line = line, has_xform = 0;
    float m[16];
    ic_mat4_identity(m);
    const cJSON *it;
    ic_result r = IC_OK;
    cJSON_ArrayForEach(it, obj)
    {
        int kl = locate_key(c, it->string);
        if (is_comment(it->string))
            continue;
        if (!strcmp(it->string, "path")) {
            r = read_string(c, it, kl, &path);
            path_line = kl;
        } else if (!strcmp(it->string, "transform") || !strcmp(it->string, "matrix")) {
            if (has_xform)
                return fail(c, kl, IC_ERR_INVALID_ARG, "meshes[%d] gives both 'transform' and 'matrix'; keep one",
                            index);
            has_xform = 1;
            r = !strcmp(it->string, "matrix") ? parse_matrix(c, it, kl, m) : parse_transform(c, it, kl, m);
        } else {
            return unknown_key(c, kl, it->string, "a mesh", valid);
        }
        if (r != IC_OK)
            return r;
    }
    if (!path)
        return fail(c, line, IC_ERR_PARSE, "meshes[%d] needs a 'path' to a mesh file", index);
    char full[IC_SCENE_PATH_MAX];
    r = resolve_path(c, path, path_line, "mesh", full, sizeof full);
    if (r != IC_OK)
        return r;
    return ic_mesh_import(c->b, full, m, c->err);
}

static ic_result parse_meshes(json_ctx *c, const cJSON *arr, int line)
{
    if (!cJSON_IsArray(arr) || cJSON_GetArraySize(arr) == 0)
        return fail(c, line, IC_ERR_PARSE, "'meshes' must be a non-empty array of {\"path\": ...} objects");
    int i = 0;
    const cJSON *it;
    cJSON_ArrayForEach(it, arr)
    {
        ic_result r = parse_mesh(c, it, i++);
        if (r != IC_OK)
            return r;
    }
    return IC_OK;
}

static ic_result parse_material_type(json_ctx *c, const cJSON *it, int line, ic_material_type *type)
{
    static const char *names[] = {"diffuse", "glossy", "mirror", "glass"};
    if (cJSON_IsString(it))
        for (int k = 0; k < 4; ++k)
            if (!strcmp(it->valuestring, names[k])) {
                *type = (ic_material_type)k;
                return IC_OK;
            }
    return fail(c, line, IC_ERR_INVALID_ARG, "unknown material type '%s'; use \"diffuse\", \"glossy\", \"mirror\" "
                                             "or \"glass\"",
                cJSON_IsString(it) ? it->valuestring : "(not a string)");
}

/* Overrides of one named material; applies to every material of that name from every mesh. */
static ic_result parse_material_override(json_ctx *c, const cJSON *obj, int line)
{
    static const char *valid = "type, kd, ks, ns, emission, two_sided, ior, kd_texture";
    ic_scene *s = c->b->scene;
    ic_result r = expect_object(c, obj, line);
    if (r != IC_OK)
        return r;
    int found = 0;
    for (uint32_t i = 0; i < s->material_count; ++i)
        found |= !strcmp(s->materials[i].name, obj->string);
    if (!found) {
        char known[512] = "";
        size_t used = 0;
        for (uint32_t i = 0; i < s->material_count && used + 4 < sizeof known; ++i) {
            int dup = 0;
            for (uint32_t j = 0; j < i; ++j)
                dup |= !strcmp(s->materials[j].name, s->materials[i].name);
            if (dup)
                continue;
            int n = snprintf(known + used, sizeof known - used, "%s'%s'", used ? ", " : "", s->materials[i].name);
            if (n < 0 || (size_t)n >= sizeof known - used) {
                snprintf(known + used, sizeof known - used, ", ...");
                break;
            }
            used += (size_t)n;
        }
        return fail(c, line, IC_ERR_INVALID_ARG,
                    "material '%s' in \"materials\" is not defined by any mesh; known materials: %s", obj->string,
                    known[0] ? known : "(none)");
    }
    ic_material o;
    memset(&o, 0, sizeof o);
    int has_type = 0, has_kd = 0, has_ks = 0, has_ns = 0, has_em = 0, has_two = 0, has_ior = 0, has_tex = 0;
    int32_t tex = -1;
    const cJSON *it;
    cJSON_ArrayForEach(it, obj)
    {
        int kl = locate_key(c, it->string);
        if (is_comment(it->string))
            continue;
        if (!strcmp(it->string, "type")) {
            r = parse_material_type(c, it, kl, &o.type);
            has_type = 1;
        } else if (!strcmp(it->string, "kd")) {
            r = read_color(c, it, kl, &o.kd);
            has_kd = 1;
        } else if (!strcmp(it->string, "ks")) {
            r = read_color(c, it, kl, &o.ks);
            has_ks = 1;
        } else if (!strcmp(it->string, "ns")) {
            r = read_float(c, it, kl, &o.ns);
            if (r == IC_OK && !(o.ns > 0.0f))
                return fail(c, kl, IC_ERR_INVALID_ARG, "'ns' must be > 0 (a Phong exponent)");
            has_ns = 1;
        } else if (!strcmp(it->string, "emission")) {
            r = read_color(c, it, kl, &o.emission);
            has_em = 1;
        } else if (!strcmp(it->string, "two_sided")) {
            if (!cJSON_IsBool(it))
                return fail(c, kl, IC_ERR_PARSE, "'two_sided' must be true or false");
            o.two_sided_emission = cJSON_IsTrue(it);
            has_two = 1;
        } else if (!strcmp(it->string, "ior")) {
            r = read_float(c, it, kl, &o.ior);
            if (r == IC_OK && !(o.ior >= 1.0f))
                return fail(c, kl, IC_ERR_INVALID_ARG, "'ior' must be >= 1 (index of refraction)");
            has_ior = 1;
        } else if (!strcmp(it->string, "kd_texture")) {
            const char *p = "";
            r = read_string(c, it, kl, &p);
            if (r == IC_OK && p[0]) {
                char full[IC_SCENE_PATH_MAX], owner[IC_SCENE_PATH_MAX + 32];
                r = resolve_path(c, p, kl, "texture", full, sizeof full);
                snprintf(owner, sizeof owner, "%s:%d", c->path, kl);
                if (r == IC_OK)
                    r = ic_scene_texture_load(s, full, owner, &tex, c->err);
            }
            has_tex = 1;
        } else {
            return unknown_key(c, kl, it->string, "a material override", valid);
        }
        if (r != IC_OK)
            return r;
    }
    for (uint32_t i = 0; i < s->material_count; ++i) {
        ic_material *m = &s->materials[i];
        if (strcmp(m->name, obj->string))
            continue;
        if (has_type)
            m->type = o.type;
        if (has_kd)
            m->kd = o.kd;
        if (has_ks)
            m->ks = o.ks;
        if (has_ns)
            m->ns = o.ns;
        if (has_em)
            m->emission = o.emission;
        if (has_two)
            m->two_sided_emission = o.two_sided_emission;
        if (has_ior)
            m->ior = o.ior;
        if (has_tex)
            m->kd_texture = tex;
        /* keep the type usable: a glossy lobe needs an exponent, a mirror or glass a tint */
        if (m->type == IC_MAT_GLOSSY && !(m->ns >= 1.0f))
            m->ns = 1.0f;
        if ((m->type == IC_MAT_MIRROR || m->type == IC_MAT_GLASS) && v3_is_black(m->ks) && !has_ks)
            m->ks = v3s(1.0f);
    }
    return IC_OK;
}

static ic_result parse_materials(json_ctx *c, const cJSON *obj, int line)
{
    ic_result r = expect_object(c, obj, line);
    if (r != IC_OK)
        return r;
    const cJSON *it;
    cJSON_ArrayForEach(it, obj)
    {
        int kl = locate_key(c, it->string);
        if (is_comment(it->string))
            continue;
        r = parse_material_override(c, it, kl);
        if (r != IC_OK)
            return r;
    }
    return IC_OK;
}

/* ------------------------------------------------------------------------------------------------ */
/* the file */

static ic_result read_text(const char *path, char **text, size_t *len, ic_error *err)
{
    FILE *fp = fopen(path, "rb");
    if (!fp) {
        int open_errno = errno; /* before resolving the path, which may set errno itself */
        char abs_path[IC_SCENE_PATH_MAX];
        ic_path_absolute(path, abs_path, sizeof abs_path);
        return ic_error_set(err, IC_ERR_IO, "%s: cannot open the scene file (%s; resolved to %s); check the path",
                            path, strerror(open_errno), abs_path);
    }
    char *buf = NULL;
    size_t n = 0;
    if (fseek(fp, 0, SEEK_END) == 0) {
        long size = ftell(fp);
        if (size >= 0 && (unsigned long)size <= MAX_SCENE_FILE_BYTES && fseek(fp, 0, SEEK_SET) == 0) {
            buf = malloc((size_t)size + 1);
            if (buf)
                n = fread(buf, 1, (size_t)size, fp);
            if (buf && n != (size_t)size) {
                free(buf);
                buf = NULL;
            }
        } else if (size > (long)MAX_SCENE_FILE_BYTES) {
            fclose(fp);
            return ic_error_set(err, IC_ERR_INVALID_ARG, "%s: scene file larger than %u MiB; keep geometry in mesh "
                                                         "files",
                                path, MAX_SCENE_FILE_BYTES >> 20);
        }
    }
    fclose(fp);
    if (!buf)
        return ic_error_set(err, IC_ERR_IO, "%s: cannot read the scene file; check the file and the disk", path);
    buf[n] = '\0';
    *text = buf;
    *len = n;
    return IC_OK;
}

/* Short excerpt of the text at off, on one line, for syntax errors. */
static void excerpt(const char *text, size_t len, size_t off, char *out, size_t size)
{
    size_t k = 0;
    for (size_t i = off; i < len && k + 1 < size && k < 24; ++i) {
        char ch = text[i];
        if (ch == '\n' || ch == '\r')
            break;
        out[k++] = (ch >= 32 && ch < 127) ? ch : '?';
    }
    out[k] = '\0';
}

enum { SEC_CAMERA, SEC_MESHES, SEC_MATERIALS, SEC_LIGHTS, SEC_ENVIRONMENT, SEC_RENDER, SEC_COUNT };
static const char *const SECTION_NAMES[SEC_COUNT] = {"camera", "meshes", "materials", "lights", "environment", "render"};

static ic_result load_document(json_ctx *c, const cJSON *root)
{
    const cJSON *node[SEC_COUNT] = {0};
    size_t at[SEC_COUNT] = {0};
    int line[SEC_COUNT] = {0};
    if (!cJSON_IsObject(root))
        return fail(c, 1, IC_ERR_PARSE, "a scene file must be one JSON object { \"meshes\": [...], ... }");
    const cJSON *it;
    cJSON_ArrayForEach(it, root)
    {
        int kl = locate_key(c, it->string);
        if (is_comment(it->string))
            continue;
        int k = 0;
        while (k < SEC_COUNT && strcmp(it->string, SECTION_NAMES[k]))
            ++k;
        if (k == SEC_COUNT)
            return unknown_key(c, kl, it->string, "the scene",
                               "camera, meshes, materials, lights, environment, render");
        node[k] = it;
        at[k] = c->cursor;
        line[k] = kl;
    }
    if (!node[SEC_MESHES])
        return fail(c, 1, IC_ERR_PARSE, "the scene has no \"meshes\"; add \"meshes\": [{\"path\": \"model.obj\"}]");

    /* sections in dependency order: meshes before the overrides that name their materials */
    static const int order[] = {SEC_RENDER, SEC_CAMERA, SEC_ENVIRONMENT, SEC_LIGHTS, SEC_MESHES, SEC_MATERIALS};
    camera_spec cam = {0};
    cam.up = v3(0.0f, 1.0f, 0.0f);
    cam.width = IC_DEFAULT_WIDTH;
    cam.height = IC_DEFAULT_HEIGHT;
    for (size_t i = 0; i < sizeof order / sizeof order[0]; ++i) {
        int k = order[i];
        if (!node[k])
            continue;
        c->cursor = at[k];
        c->line = line[k];
        ic_result r;
        switch (k) {
        case SEC_CAMERA: r = parse_camera(c, node[k], line[k], &cam); break;
        case SEC_MESHES: r = parse_meshes(c, node[k], line[k]); break;
        case SEC_MATERIALS: r = parse_materials(c, node[k], line[k]); break;
        case SEC_LIGHTS: r = parse_lights(c, node[k], line[k]); break;
        case SEC_ENVIRONMENT: r = parse_environment(c, node[k], line[k]); break;
        default: r = parse_render(c, node[k], line[k]); break;
        }
        if (r != IC_OK)
            return r;
    }

    ic_result r = ic_scene_finalize(c->b, c->err);
    if (r != IC_OK)
        return r;

    ic_scene *s = c->b->scene;
    int width = c->opt->width > 0 ? c->opt->width : cam.width;
    int height = c->opt->height > 0 ? c->opt->height : cam.height;
    if (!cam.given) {
        ic_scene_fit_camera(s, width, height);
        return IC_OK;
    }
    s->camera.eye = cam.eye;
    s->camera.target = cam.target;
    s->camera.up = v3_norm(cam.up);
    s->camera.width = width;
    s->camera.height = height;
    float fov = cam.has_fov ? cam.fov_deg : 45.0f;
    if (cam.fov_is_x) /* keep the horizontal angle at the final resolution */
        fov = 2.0f * atanf(tanf(0.5f * fov * IC_PI / 180.0f) * (float)height / (float)width) * 180.0f / IC_PI;
    s->camera.fov_y_deg = fov;
    return IC_OK;
}

ic_result ic_scene_load_json(ic_scene_builder *b, const char *path, const ic_scene_load_options *opt, ic_error *err)
{
    char *text = NULL;
    size_t len = 0;
    ic_result r = read_text(path, &text, &len, err);
    if (r != IC_OK)
        return r;
    json_ctx c;
    memset(&c, 0, sizeof c);
    c.path = path;
    ic_path_dirname(path, c.dir, sizeof c.dir);
    c.text = text;
    c.len = len;
    c.line = 1;
    c.opt = opt;
    c.b = b;
    c.err = err;

    const char *end = NULL;
    cJSON *root = cJSON_ParseWithLengthOpts(text, len, &end, 0);
    if (!root) {
        size_t off = (end && end >= text && end <= text + len) ? (size_t)(end - text) : 0;
        char near[32];
        excerpt(text, len, off, near, sizeof near);
        r = fail(&c, line_of(&c, off), IC_ERR_PARSE,
                 "malformed JSON %s%s%s; fix the syntax (a missing comma, quote or bracket?)",
                 off >= len ? "at the end of the file" : "near '", off >= len ? "" : near, off >= len ? "" : "'");
    } else {
        r = load_document(&c, root);
        cJSON_Delete(root);
    }
    free(text);
    return r;
}
