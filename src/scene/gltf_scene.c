/*
 * gltf_scene.c — what makes a glTF 2.0 file a whole scene besides its meshes (which assimp imports in
 * mesh_import.c): the camera and the KHR_lights_punctual lights, read from the file's JSON (a .gltf's text
 * or a .glb's JSON chunk) with the node transforms of the glTF 2.0 specification §3.5 (a node's matrix, or
 * T·R·S, times its parent's). Cameras look down their node's −Z with +Y up; lights shine down −Z.
 *
 * Units: glTF's are metres; a point or spot light's intensity (candela) is taken as the radiant intensity
 * (W/sr per channel) and a directional light's (lux) as the irradiance, colour times intensity, with no
 * photometric conversion. A light's `range` is ignored (the falloff stays inverse-square, as the
 * extension recommends for physically based renderers).
 */
#include "scene/mesh_check.h"
#include "scene/scene_internal.h"

#include "core/vecmath.h"
#include "irrcache/defaults.h"

#include <cjson/cJSON.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Deepest node hierarchy walked (deeper, or a cycle, is an error). */
#define MAX_NODE_DEPTH 64

typedef struct gltf_walk {
    ic_scene_builder *b;
    const char *path;
    const char *camera_name;   /* NULL: the first perspective camera */
    const cJSON *nodes, *cameras, *lights;
    int has_camera;
    float aspect;              /* the chosen camera's aspectRatio, 0 if none */
    int light_count, sun_count;
    uint8_t *visited;          /* per node: walked already (a node has one parent in glTF) */
    ic_vec3 centre;            /* of the meshes' bounds, for distant lights */
    float radius;
    ic_error *err;
} gltf_walk;

static float number_or(const cJSON *obj, const char *key, float fallback)
{
    const cJSON *v = obj ? cJSON_GetObjectItemCaseSensitive(obj, key) : NULL;
    return cJSON_IsNumber(v) && isfinite(v->valuedouble) ? (float)v->valuedouble : fallback;
}

/* Reads array key of obj into out[n] if it has exactly n numbers; returns 1 if it did. */
static int numbers(const cJSON *obj, const char *key, float *out, int n)
{
    const cJSON *a = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!cJSON_IsArray(a) || cJSON_GetArraySize(a) != n)
        return 0;
    int i = 0;
    const cJSON *v;
    cJSON_ArrayForEach(v, a)
    {
        if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble))
            return 0;
        out[i++] = (float)v->valuedouble;
    }
    return 1;
}

/* A node's local transform, row-major: its matrix (glTF stores it by columns), or T·R·S (rotation a unit
 * quaternion x, y, z, w). */
static void node_local(const cJSON *node, float m[16])
{
    float cm[16];
    if (numbers(node, "matrix", cm, 16)) {
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j)
                m[i * 4 + j] = cm[j * 4 + i];
        return;
    }
    float t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
    numbers(node, "translation", t, 3);
    numbers(node, "rotation", q, 4);
    numbers(node, "scale", s, 3);
    float len = sqrtf(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (len > 0.0f)
        for (int i = 0; i < 4; ++i)
            q[i] /= len;
    float x = q[0], y = q[1], z = q[2], w = q[3];
    float r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - z * w),     2 * (x * z + y * w),
                  2 * (x * y + z * w),     1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
                  2 * (x * z - y * w),     2 * (y * z + x * w),     1 - 2 * (x * x + y * y)}; /* rows */
    memset(m, 0, sizeof(float) * 16);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            m[i * 4 + j] = r[i * 3 + j] * s[j];
    m[3] = t[0];
    m[7] = t[1];
    m[11] = t[2];
    m[15] = 1.0f;
}

static const char *name_of(const cJSON *obj)
{
    const cJSON *n = obj ? cJSON_GetObjectItemCaseSensitive(obj, "name") : NULL;
    return cJSON_IsString(n) ? n->valuestring : "";
}

/* The node's camera, if it is the one wanted and none is set yet. */
static ic_result take_camera(gltf_walk *w, const cJSON *node, int index, const float m[16])
{
    const cJSON *ci = cJSON_GetObjectItemCaseSensitive(node, "camera");
    if (w->has_camera || !cJSON_IsNumber(ci))
        return IC_OK;
    const cJSON *cam = cJSON_GetArrayItem(w->cameras, ci->valueint);
    if (!cam)
        return ic_error_set(w->err, IC_ERR_PARSE, "%s: node %d names camera %d, which does not exist; fix the file",
                            w->path, index, ci->valueint);
    if (w->camera_name && strcmp(w->camera_name, name_of(node)) && strcmp(w->camera_name, name_of(cam)))
        return IC_OK;
    const cJSON *type = cJSON_GetObjectItemCaseSensitive(cam, "type");
    const cJSON *persp = cJSON_GetObjectItemCaseSensitive(cam, "perspective");
    if (!cJSON_IsString(type) || strcmp(type->valuestring, "perspective") || !persp) {
        if (w->camera_name)
            return ic_error_set(w->err, IC_ERR_UNSUPPORTED,
                                "%s: camera '%s' is not a perspective camera; irrcache renders perspective views only",
                                w->path, w->camera_name);
        return IC_OK; /* orthographic cameras are passed over */
    }
    float yfov = number_or(persp, "yfov", 0.0f);
    if (!(yfov > 0.0f && yfov < IC_PI))
        return ic_error_set(w->err, IC_ERR_PARSE, "%s: camera %d: yfov %g is not in (0, pi) radians; fix the file",
                            w->path, ci->valueint, (double)yfov);
    ic_camera *c = &w->b->scene->camera;
    c->eye = ic_xform_point(m, v3s(0.0f));
    c->target = v3_add(c->eye, ic_xform_dir(m, v3(0.0f, 0.0f, -1.0f)));
    c->up = ic_xform_dir(m, v3(0.0f, 1.0f, 0.0f));
    c->fov_y_deg = yfov * 180.0f / IC_PI;
    w->aspect = number_or(persp, "aspectRatio", 0.0f);
    w->has_camera = 1;
    return IC_OK;
}

/* The node's KHR_lights_punctual light, if any. */
static ic_result take_light(gltf_walk *w, const cJSON *node, int index, const float m[16])
{
    const cJSON *ext = cJSON_GetObjectItemCaseSensitive(node, "extensions");
    const cJSON *kl = ext ? cJSON_GetObjectItemCaseSensitive(ext, "KHR_lights_punctual") : NULL;
    const cJSON *li = kl ? cJSON_GetObjectItemCaseSensitive(kl, "light") : NULL;
    if (!cJSON_IsNumber(li))
        return IC_OK;
    const cJSON *light = cJSON_GetArrayItem(w->lights, li->valueint);
    const cJSON *type = light ? cJSON_GetObjectItemCaseSensitive(light, "type") : NULL;
    if (!cJSON_IsString(type))
        return ic_error_set(w->err, IC_ERR_PARSE,
                            "%s: node %d names KHR_lights_punctual light %d, which does not exist or has no type; "
                            "fix the file",
                            w->path, index, li->valueint);
    float rgb[3] = {1, 1, 1};
    numbers(light, "color", rgb, 3);
    float intensity = number_or(light, "intensity", 1.0f);
    if (!(intensity >= 0.0f) || rgb[0] < 0.0f || rgb[1] < 0.0f || rgb[2] < 0.0f)
        return ic_error_set(w->err, IC_ERR_PARSE, "%s: light %d: a negative colour or intensity; give values >= 0",
                            w->path, li->valueint);
    ic_vec3 power = v3_scale(v3(rgb[0], rgb[1], rgb[2]), intensity);
    if (ic_radiance_too_large(power))
        return ic_error_set(w->err, IC_ERR_INVALID_ARG, "%s: light %d: its colour times its intensity is "
                            IC_RADIANCE_LIMIT_FMT "; " IC_RADIANCE_LIMIT_FIX, w->path, li->valueint,
                            IC_RADIANCE_LIMIT_ARGS(power));
    ic_vec3 pos = ic_xform_point(m, v3s(0.0f)), axis = ic_xform_dir(m, v3(0.0f, 0.0f, -1.0f));
    ic_scene *s = w->b->scene;
    ic_result r = IC_OK;
    if (!strcmp(type->valuestring, "point")) {
        r = ic_scene_add_point_light(s, pos, power, NULL);
    } else if (!strcmp(type->valuestring, "spot")) {
        const cJSON *spot = cJSON_GetObjectItemCaseSensitive(light, "spot");
        float inner = number_or(spot, "innerConeAngle", 0.0f), outer = number_or(spot, "outerConeAngle", IC_PI / 4);
        if (!(inner >= 0.0f && inner < outer && outer <= IC_PI / 2))
            return ic_error_set(w->err, IC_ERR_PARSE,
                                "%s: spot light %d: cone angles %g and %g must satisfy 0 <= inner < outer <= pi/2",
                                w->path, li->valueint, (double)inner, (double)outer);
        ic_spot_cone cone = {axis, cosf(inner), cosf(outer)};
        r = ic_scene_add_point_light(s, pos, power, &cone);
    } else if (!strcmp(type->valuestring, "directional")) {
        if (w->sun_count++ == 0) {
            s->sun.enabled = 1;
            s->sun.direction = v3_neg(axis);
            s->sun.irradiance = power;
        } else { /* one sun only: the others as point lights far away, with the same irradiance at the centre */
            float d = 1000.0f * w->radius;
            r = ic_scene_add_point_light(s, v3_add(w->centre, v3_scale(axis, -d)), v3_scale(power, d * d), NULL);
        }
    } else {
        return ic_error_set(w->err, IC_ERR_UNSUPPORTED,
                            "%s: light %d has type '%s'; KHR_lights_punctual defines point, spot and directional",
                            w->path, li->valueint, type->valuestring);
    }
    if (r != IC_OK)
        return ic_error_set(w->err, r, "%s: out of memory for the lights", w->path);
    ++w->light_count;
    return IC_OK;
}

static ic_result walk_node(gltf_walk *w, int index, const float parent[16], int depth)
{
    const cJSON *node = cJSON_GetArrayItem(w->nodes, index);
    if (!node)
        return ic_error_set(w->err, IC_ERR_PARSE, "%s: node %d does not exist; fix the file", w->path, index);
    if (depth >= MAX_NODE_DEPTH)
        return ic_error_set(w->err, IC_ERR_PARSE, "%s: the node hierarchy is deeper than %d; fix the file", w->path,
                            MAX_NODE_DEPTH);
    if (w->visited[index]++)
        return ic_error_set(w->err, IC_ERR_PARSE,
                            "%s: node %d is reached twice (two parents, or a cycle); glTF nodes form trees, fix the file",
                            w->path, index);
    float local[16], m[16];
    node_local(node, local);
    ic_mat4_mul(parent, local, m);
    ic_result r = take_camera(w, node, index, m);
    if (r == IC_OK)
        r = take_light(w, node, index, m);
    const cJSON *children = cJSON_GetObjectItemCaseSensitive(node, "children"), *c;
    cJSON_ArrayForEach(c, children)
    {
        if (r != IC_OK)
            break;
        if (cJSON_IsNumber(c))
            r = walk_node(w, c->valueint, m, depth + 1);
    }
    return r;
}

/* The default scene's root nodes (`scene`, else scene 0), or, without scenes, every node no other names
 * as a child. */
static ic_result walk_roots(gltf_walk *w, const cJSON *root)
{
    static const float identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    const cJSON *scenes = cJSON_GetObjectItemCaseSensitive(root, "scenes");
    const cJSON *si = cJSON_GetObjectItemCaseSensitive(root, "scene");
    const cJSON *scene = cJSON_GetArrayItem(scenes, cJSON_IsNumber(si) ? si->valueint : 0);
    ic_result r = IC_OK;
    if (scene) {
        const cJSON *n;
        cJSON_ArrayForEach(n, cJSON_GetObjectItemCaseSensitive(scene, "nodes"))
        {
            if (r == IC_OK && cJSON_IsNumber(n))
                r = walk_node(w, n->valueint, identity, 0);
        }
        return r;
    }
    int count = cJSON_GetArraySize(w->nodes);
    uint8_t *is_child = calloc((size_t)count + 1, 1);
    if (!is_child)
        return ic_error_set(w->err, IC_ERR_OOM, "%s: out of memory", w->path);
    const cJSON *node, *c;
    cJSON_ArrayForEach(node, w->nodes)
    {
        cJSON_ArrayForEach(c, cJSON_GetObjectItemCaseSensitive(node, "children"))
        {
            if (cJSON_IsNumber(c) && c->valueint >= 0 && c->valueint < count)
                is_child[c->valueint] = 1;
        }
    }
    for (int i = 0; i < count && r == IC_OK; ++i)
        if (!is_child[i])
            r = walk_node(w, i, identity, 0);
    free(is_child);
    return r;
}

ic_result ic_gltf_read_scene(ic_scene_builder *b, const char *path, const char *camera_name, int *has_camera,
                             int *light_count, ic_error *err)
{
    *has_camera = 0;
    *light_count = 0;
    FILE *fp = fopen(path, "rb");
    if (!fp)
        return ic_error_set(err, IC_ERR_IO, "%s: cannot read the file again for its cameras and lights", path);
    size_t len = 0;
    char *text = ic_gltf_json(fp, &len);
    fclose(fp);
    cJSON *root = text ? cJSON_ParseWithLength(text, len) : NULL;
    free(text);
    if (!root)
        return ic_error_set(err, IC_ERR_PARSE, "%s: cannot parse the glTF JSON for its cameras and lights", path);
    gltf_walk w;
    memset(&w, 0, sizeof w);
    w.b = b;
    w.path = path;
    w.camera_name = camera_name && camera_name[0] ? camera_name : NULL;
    w.err = err;
    w.nodes = cJSON_GetObjectItemCaseSensitive(root, "nodes");
    w.cameras = cJSON_GetObjectItemCaseSensitive(root, "cameras");
    const cJSON *ext = cJSON_GetObjectItemCaseSensitive(root, "extensions");
    const cJSON *kl = ext ? cJSON_GetObjectItemCaseSensitive(ext, "KHR_lights_punctual") : NULL;
    w.lights = kl ? cJSON_GetObjectItemCaseSensitive(kl, "lights") : NULL;
    /* bounds of the imported meshes, for directional lights past the first */
    const ic_scene *s = b->scene;
    ic_vec3 lo = v3s(INFINITY), hi = v3s(-INFINITY);
    for (uint32_t i = 0; i < s->vertex_count; ++i) {
        lo = v3_min(lo, s->positions[i]);
        hi = v3_max(hi, s->positions[i]);
    }
    w.centre = s->vertex_count ? v3_scale(v3_add(lo, hi), 0.5f) : v3s(0.0f);
    w.radius = s->vertex_count ? fmaxf(0.5f * v3_len(v3_sub(hi, lo)), 1e-3f) : 1.0f;
    w.visited = calloc((size_t)cJSON_GetArraySize(w.nodes) + 1, 1);
    ic_result r = w.visited ? walk_roots(&w, root) : ic_error_set(err, IC_ERR_OOM, "%s: out of memory", path);
    free(w.visited);
    cJSON_Delete(root);
    if (r != IC_OK)
        return r;
    if (w.camera_name && !w.has_camera)
        return ic_error_set(err, IC_ERR_INVALID_ARG,
                            "%s: no camera named '%s' (a node's or a camera's name) in the default scene; check the "
                            "name given with --camera",
                            path, w.camera_name);
    if (w.has_camera) {
        ic_camera *c = &b->scene->camera;
        c->width = b->opt->width > 0 ? b->opt->width : IC_DEFAULT_WIDTH;
        /* the height from the camera's aspectRatio, refused when it gives no usable image (1e-7 gave
         * -2147483648 rows through a float-to-int overflow) */
        double rows = w.aspect > 0.0f ? fmax(1.0, round((double)c->width / w.aspect)) : IC_DEFAULT_HEIGHT;
        if (b->opt->height <= 0 && !(rows <= 65536.0))
            return ic_error_set(err, IC_ERR_INVALID_ARG,
                                "%s: the camera's aspectRatio %g makes %d x %.0f pixels; give an aspectRatio that "
                                "gives at most 65536 rows, or --height",
                                path, (double)w.aspect, c->width, rows);
        c->height = b->opt->height > 0 ? b->opt->height : (int)rows;
    }
    *has_camera = w.has_camera;
    *light_count = w.light_count;
    return IC_OK;
}
