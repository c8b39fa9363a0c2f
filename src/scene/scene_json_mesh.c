/*
 * scene_json_mesh.c — the "meshes" section of the JSON scene file: each mesh file, placed by a
 * transform (translate, rotate, scale) or a 4x4 matrix, imported into the builder.
 */
#include "scene/json_context.h"

#include "core/vecmath.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

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
    ic_result r = ic_json_expect_object(c, obj, line);
    if (r != IC_OK)
        return r;
    ic_vec3 translate = v3s(0.0f), rot_deg = v3s(0.0f), axis = v3s(0.0f), scale = v3s(1.0f);
    float angle = 0.0f;
    int has_euler = 0, has_axis = 0, has_angle = 0, scale_line = line;
    const cJSON *it;
    cJSON_ArrayForEach(it, obj)
    {
        int kl = ic_json_locate_key(c, it->string);
        if (ic_json_is_comment(it->string))
            continue;
        if (!strcmp(it->string, "translate")) {
            r = ic_json_read_vec3(c, it, kl, &translate);
        } else if (!strcmp(it->string, "rotate_deg")) {
            r = ic_json_read_vec3(c, it, kl, &rot_deg);
            has_euler = 1;
        } else if (!strcmp(it->string, "rotate_axis")) {
            r = ic_json_read_vec3(c, it, kl, &axis);
            has_axis = 1;
            if (r == IC_OK && !(v3_len2(axis) > 0.0f))
                return ic_json_fail(c, kl, IC_ERR_INVALID_ARG, "'rotate_axis' is zero; give a non-zero axis");
        } else if (!strcmp(it->string, "rotate_angle_deg")) {
            r = ic_json_read_float(c, it, kl, &angle);
            has_angle = 1;
        } else if (!strcmp(it->string, "scale")) {
            scale_line = kl;
            if (cJSON_IsNumber(it)) {
                float sc;
                r = ic_json_read_float(c, it, kl, &sc);
                scale = v3s(sc);
            } else {
                r = ic_json_read_vec3(c, it, kl, &scale);
            }
        } else {
            return ic_json_unknown_key(c, kl, it->string, "transform", valid);
        }
        if (r != IC_OK)
            return r;
    }
    if (has_euler && (has_axis || has_angle))
        return ic_json_fail(c, line, IC_ERR_INVALID_ARG,
                            "transform gives both 'rotate_deg' and an axis-angle rotation; "
                            "keep one");
    if (has_axis != has_angle)
        return ic_json_fail(c, line, IC_ERR_INVALID_ARG, "'rotate_axis' and 'rotate_angle_deg' go together; give both");
    if (scale.x == 0.0f || scale.y == 0.0f || scale.z == 0.0f)
        return ic_json_fail(c, scale_line, IC_ERR_INVALID_ARG, "'scale' has a zero component; the mesh would be flat");

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
                return ic_json_fail(c, line, IC_ERR_PARSE, "%s", shape);
            m[k] = (float)e->valuedouble;
        }
    } else if (n == 4) {
        for (int i = 0; i < 4; ++i) {
            const cJSON *row = cJSON_GetArrayItem(it, i);
            if (!cJSON_IsArray(row) || cJSON_GetArraySize(row) != 4)
                return ic_json_fail(c, line, IC_ERR_PARSE, "%s", shape);
            for (int j = 0; j < 4; ++j) {
                const cJSON *e = cJSON_GetArrayItem(row, j);
                if (!cJSON_IsNumber(e) || !isfinite(e->valuedouble))
                    return ic_json_fail(c, line, IC_ERR_PARSE, "%s", shape);
                m[4 * i + j] = (float)e->valuedouble;
            }
        }
    } else {
        return ic_json_fail(c, line, IC_ERR_PARSE, "%s", shape);
    }
    if (m[12] != 0.0f || m[13] != 0.0f || m[14] != 0.0f || m[15] != 1.0f)
        return ic_json_fail(c, line, IC_ERR_INVALID_ARG, "'matrix' must be affine: its last row must be [0, 0, 0, 1]");
    float det = m[0] * (m[5] * m[10] - m[6] * m[9]) - m[1] * (m[4] * m[10] - m[6] * m[8]) +
                m[2] * (m[4] * m[9] - m[5] * m[8]);
    if (det == 0.0f)
        return ic_json_fail(c, line, IC_ERR_INVALID_ARG, "'matrix' is singular (the mesh would be flattened)");
    return IC_OK;
}

static ic_result parse_mesh(json_ctx *c, const cJSON *obj, int index)
{
    static const char *valid = "path, transform, matrix";
    int line = ic_json_locate_object_start(c);
    if (!cJSON_IsObject(obj))
        return ic_json_fail(c, line, IC_ERR_PARSE, "meshes[%d] must be an object with a 'path'", index);
    const char *path = NULL;
    int path_line = line, has_xform = 0, xform_line = 0;
    float m[16];
    ic_mat4_identity(m);
    const cJSON *it;
    ic_result r = IC_OK;
    cJSON_ArrayForEach(it, obj)
    {
        int kl = ic_json_locate_key(c, it->string);
        if (ic_json_is_comment(it->string))
            continue;
        if (!strcmp(it->string, "path")) {
            r = ic_json_read_string(c, it, kl, &path);
            path_line = kl;
        } else if (!strcmp(it->string, "transform") || !strcmp(it->string, "matrix")) {
            if (has_xform)
                return ic_json_fail(c, kl, IC_ERR_INVALID_ARG,
                                    "meshes[%d] gives both 'transform' and 'matrix'; keep one", index);
            has_xform = 1;
            xform_line = kl;
            r = !strcmp(it->string, "matrix") ? parse_matrix(c, it, kl, m) : parse_transform(c, it, kl, m);
        } else {
            return ic_json_unknown_key(c, kl, it->string, "a mesh", valid);
        }
        if (r != IC_OK)
            return r;
    }
    if (!path)
        return ic_json_fail(c, line, IC_ERR_PARSE, "meshes[%d] needs a 'path' to a mesh file", index);
    char full[IC_SCENE_PATH_MAX];
    r = ic_json_resolve_path(c, path, path_line, "mesh", full, sizeof full);
    if (r != IC_OK)
        return r;
    char where[IC_SCENE_PATH_MAX + 32], path_where[IC_SCENE_PATH_MAX + 32];
    snprintf(where, sizeof where, "%s:%d", c->path, xform_line);
    snprintf(path_where, sizeof path_where, "%s:%d", c->path, path_line);
    c->b->import_where = path_where; /* files the mesh names are reported at its path's line */
    r = ic_mesh_import(c->b, full, m, has_xform ? where : NULL, c->err);
    c->b->import_where = NULL;
    return r;
}

ic_result ic_json_parse_meshes(json_ctx *c, const cJSON *arr, int line)
{
    if (!cJSON_IsArray(arr) || cJSON_GetArraySize(arr) == 0)
        return ic_json_fail(c, line, IC_ERR_PARSE, "'meshes' must be a non-empty array of {\"path\": ...} objects");
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
