/*
 * scene_json.c — the JSON scene file (format: docs/scene-format.md), parsed with cJSON: reading the
 * file, its top level, and the "camera" and "render" sections. The other sections are read in
 * scene_json_mesh.c, scene_json_material.c and scene_json_light.c, all with the helpers of
 * scene_json_value.c (declared in json_context.h).
 *
 * Every message names the scene file and a line. cJSON keeps no positions, so a syntax error's line is
 * counted up to where the parser stopped, and a key's line is found by searching the text for `"key":`
 * from a cursor that walks forward as the document is visited in its own order (objects' keys are
 * handled in file order, so the n-th occurrence found is the one being handled). The top level is
 * visited in a fixed order (meshes before the material overrides that refer to them), each section
 * restarting the search at its own key. Unknown keys are errors that list the valid ones: a typo
 * should not silently drop a setting. Keys starting with '_' are comments and ignored.
 */
#include "scene/json_context.h"

#include "core/read_file.h"
#include "core/vecmath.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_RESOLUTION 65536

/* ------------------------------------------------------------------------------------------------ */
/* camera and render */

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
    ic_result r = ic_json_read_float(c, it, line, fov);
    if (r != IC_OK)
        return r;
    if (!(*fov > 0.0f && *fov < 180.0f))
        return ic_json_fail(c, line, IC_ERR_INVALID_ARG,
                            "'%s' = %g is outside (0, 180); give the full field-of-view angle in degrees", it->string,
                            (double)*fov);
    return IC_OK;
}

static ic_result parse_camera(json_ctx *c, const cJSON *obj, int line, camera_spec *cam)
{
    static const char *valid = "eye, target, up, fov_y, fov_x, width, height";
    ic_result r = ic_json_expect_object(c, obj, line);
    if (r != IC_OK)
        return r;
    cam->given = 1;
    cam->line = line;
    const cJSON *it;
    cJSON_ArrayForEach(it, obj)
    {
        int kl = ic_json_locate_key(c, it->string);
        double d;
        if (ic_json_is_comment(it->string))
            continue;
        if (!strcmp(it->string, "eye")) {
            r = ic_json_read_vec3(c, it, kl, &cam->eye);
            cam->has_eye = 1;
        } else if (!strcmp(it->string, "target")) {
            r = ic_json_read_vec3(c, it, kl, &cam->target);
            cam->has_target = 1;
        } else if (!strcmp(it->string, "up")) {
            r = ic_json_read_vec3(c, it, kl, &cam->up);
        } else if (!strcmp(it->string, "fov_y") || !strcmp(it->string, "fov_x")) {
            if (cam->has_fov)
                return ic_json_fail(c, kl, IC_ERR_INVALID_ARG, "camera gives both fov_x and fov_y; keep one");
            r = check_fov(c, it, kl, &cam->fov_deg);
            cam->has_fov = 1;
            cam->fov_is_x = !strcmp(it->string, "fov_x");
        } else if (!strcmp(it->string, "width")) {
            r = ic_json_read_int(c, it, kl, 1, MAX_RESOLUTION, "give the image width in pixels", &d);
            cam->width = (int)d;
        } else if (!strcmp(it->string, "height")) {
            r = ic_json_read_int(c, it, kl, 1, MAX_RESOLUTION, "give the image height in pixels", &d);
            cam->height = (int)d;
        } else {
            return ic_json_unknown_key(c, kl, it->string, "camera", valid);
        }
        if (r != IC_OK)
            return r;
    }
    if (!cam->has_eye || !cam->has_target)
        return ic_json_fail(c, line, IC_ERR_PARSE, "camera needs 'eye' and 'target' (3-vectors)");
    ic_vec3 view = v3_sub(cam->target, cam->eye);
    if (!(v3_len2(view) > 0.0f))
        return ic_json_fail(c, line, IC_ERR_INVALID_ARG, "camera 'eye' and 'target' coincide; move the target");
    if (!(v3_len2(v3_cross(v3_norm(view), v3_norm(cam->up))) > 1e-10f))
        return ic_json_fail(c, line, IC_ERR_INVALID_ARG,
                            "camera 'up' is zero or parallel to the view direction; pick "
                            "another up vector");
    return IC_OK;
}

static ic_result parse_render(json_ctx *c, const cJSON *obj, int line)
{
    static const char *valid = "spp, max_depth, seed, exposure";
    ic_scene_settings *st = &c->b->scene->settings;
    ic_result r = ic_json_expect_object(c, obj, line);
    if (r != IC_OK)
        return r;
    const cJSON *it;
    cJSON_ArrayForEach(it, obj)
    {
        int kl = ic_json_locate_key(c, it->string);
        double d;
        if (ic_json_is_comment(it->string))
            continue;
        if (!strcmp(it->string, "spp")) {
            r = ic_json_read_int(c, it, kl, 1, IC_MAX_SPP, "give samples per pixel", &d);
            st->spp = (int)d;
        } else if (!strcmp(it->string, "max_depth")) {
            r = ic_json_read_int(c, it, kl, 1, IC_MAX_MAX_DEPTH, "give the maximum path length in bounces", &d);
            st->max_depth = (int)d;
        } else if (!strcmp(it->string, "seed")) {
            r = ic_json_read_int(c, it, kl, 0, 9007199254740992.0, "give a non-negative integer seed", &d);
            st->seed = (uint64_t)d;
        } else if (!strcmp(it->string, "exposure")) {
            r = ic_json_read_float(c, it, kl, &st->exposure);
            st->has_exposure = 1;
        } else {
            return ic_json_unknown_key(c, kl, it->string, "render", valid);
        }
        if (r != IC_OK)
            return r;
    }
    return IC_OK;
}

/* ------------------------------------------------------------------------------------------------ */
/* the file */

/* Reads the scene file whole, once fstat says it is a regular file within the size limit (scene files are
 * small: geometry lives in mesh files). */
static ic_result read_text(const char *path, const ic_scene_load_options *opt, char **text, size_t *len,
                           ic_error *err)
{
    int open_errno = 0;
    uint64_t max_bytes = opt && opt->max_scene_bytes ? opt->max_scene_bytes : IC_DEFAULT_MAX_SCENE_FILE_BYTES;
    ic_result r = ic_read_regular_file(path, "scene file", max_bytes, "keep geometry in mesh files, or raise the "
                                       "limit with --max-scene-bytes (max_scene_bytes of ic_scene_load_options)",
                                       text, len, &open_errno, err);
    if (r != IC_OK && open_errno) {
        char abs_path[IC_SCENE_PATH_MAX];
        ic_path_absolute(path, abs_path, sizeof abs_path);
        return ic_error_set(err, IC_ERR_IO, "%s: cannot open the scene file (%s; resolved to %s); check the path",
                            path, strerror(open_errno), abs_path);
    }
    return r;
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
        return ic_json_fail(c, 1, IC_ERR_PARSE, "a scene file must be one JSON object { \"meshes\": [...], ... }");
    const cJSON *it;
    cJSON_ArrayForEach(it, root)
    {
        int kl = ic_json_locate_key(c, it->string);
        if (ic_json_is_comment(it->string))
            continue;
        int k = 0;
        while (k < SEC_COUNT && strcmp(it->string, SECTION_NAMES[k]))
            ++k;
        if (k == SEC_COUNT)
            return ic_json_unknown_key(c, kl, it->string, "the scene",
                                       "camera, meshes, materials, lights, environment, render");
        if (node[k])
            return ic_json_fail(c, kl, IC_ERR_PARSE, "\"%s\" given twice (first at line %d); merge the two sections",
                                it->string, line[k]);
        node[k] = it;
        at[k] = c->cursor;
        line[k] = kl;
    }
    if (!node[SEC_MESHES])
        return ic_json_fail(c, 1, IC_ERR_PARSE,
                            "the scene has no \"meshes\"; add \"meshes\": [{\"path\": \"model.obj\"}]");

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
        case SEC_MESHES: r = ic_json_parse_meshes(c, node[k], line[k]); break;
        case SEC_MATERIALS: r = ic_json_parse_materials(c, node[k], line[k]); break;
        case SEC_LIGHTS: r = ic_json_parse_lights(c, node[k], line[k]); break;
        case SEC_ENVIRONMENT: r = ic_json_parse_environment(c, node[k], line[k]); break;
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
    ic_result r = read_text(path, opt, &text, &len, err);
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
    ic_json_add_shared_roots(&c);

    const char *end = NULL;
    cJSON *root = cJSON_ParseWithLengthOpts(text, len, &end, 0);
    if (!root) {
        size_t off = (end && end >= text && end <= text + len) ? (size_t)(end - text) : 0;
        char near[32];
        excerpt(text, len, off, near, sizeof near);
        r = ic_json_fail(&c, ic_json_line_of(&c, off), IC_ERR_PARSE,
                         "malformed JSON %s%s%s; fix the syntax (a missing comma, quote or bracket?)",
                         off >= len ? "at the end of the file" : "near '", off >= len ? "" : near,
                         off >= len ? "" : "'");
    } else {
        /* One JSON text per file (RFC 8259 §2: whitespace may follow the value, nothing else). */
        size_t off = (end && end >= text && end <= text + len) ? (size_t)(end - text) : len;
        while (off < len && (text[off] == ' ' || text[off] == '\t' || text[off] == '\n' || text[off] == '\r'))
            ++off;
        if (off < len) {
            char near[32];
            excerpt(text, len, off, near, sizeof near);
            r = ic_json_fail(&c, ic_json_line_of(&c, off), IC_ERR_PARSE,
                             "text after the scene's closing brace near '%s'; remove it (one JSON object per file)",
                             near);
        } else {
            r = load_document(&c, root);
        }
        cJSON_Delete(root);
    }
    free(text);
    return r;
}
