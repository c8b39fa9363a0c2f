/*
 * mitsuba_scene.c — Mitsuba 0.6 and 3 XML scene files, the subset the public research scenes use, parsed
 * with libxml2 (no network access, no entity expansion) and mapped onto irrcache's scene:
 *
 *   sensor perspective (fov, fovAxis, toWorld: lookat / matrix / translate / rotate / scale), its film's
 *   width and height, its sampler's sampleCount; shapes obj, ply (through assimp), rectangle, disk, cube,
 *   sphere, with toWorld and flipNormals; BSDFs diffuse, plastic / roughplastic, conductor / roughconductor
 *   (named materials or eta/k), dielectric / roughdielectric, twosided, by reference or inline; area, point,
 *   spot, constant, envmap and directional emitters; <default> parameters and $name substitution.
 *
 * Every other element is named in one warning per kind (element, type and file:line) and skipped or
 * approximated as the warning says; nothing is dropped silently. Roughness distributions other than GGX
 * are rendered as GGX of the same α. Directions: Mitsuba's sensor looks down its +Z with +Y up.
 */
#include "scene/scene_internal.h"

#include "core/read_file.h"
#include "core/vecmath.h"
#include "irrcache/defaults.h"

#include <libxml/parser.h>
#include <libxml/tree.h>

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_DEFAULTS 64
#define MAX_WARNED 64
#define VALUE_MAX 1024

typedef struct mts_ctx {
    ic_scene_builder *b;
    const ic_scene_load_options *opt;
    const char *path;
    char dir[IC_SCENE_PATH_MAX];
    ic_error *err;
    xmlNode *root;
    char def_name[MAX_DEFAULTS][64], def_value[MAX_DEFAULTS][256];
    int def_count;
    char warned[MAX_WARNED][96]; /* element kinds already warned about */
    int warned_count;
    char value[4][VALUE_MAX];   /* substituted attribute values, used round-robin */
    int next_value;
} mts_ctx;

static int line_of(const xmlNode *n) { return n ? (int)xmlGetLineNo(n) : 0; }

static int is_element(const xmlNode *n, const char *name)
{
    return n && n->type == XML_ELEMENT_NODE && (!name || !strcmp((const char *)n->name, name));
}

/* An attribute with every $name of a <default> replaced; NULL if absent. */
static const char *attr(mts_ctx *c, const xmlNode *n, const char *key)
{
    xmlChar *raw = xmlGetProp(n, (const xmlChar *)key);
    if (!raw)
        return NULL;
    char *out = c->value[c->next_value++ & 3];
    size_t o = 0;
    for (const char *s = (const char *)raw; *s && o + 1 < VALUE_MAX;) {
        int done = 0;
        if (*s == '$')
            for (int d = 0; d < c->def_count && !done; ++d) {
                size_t len = strlen(c->def_name[d]);
                if (!strncmp(s + 1, c->def_name[d], len)) {
                    size_t vlen = strlen(c->def_value[d]);
                    if (o + vlen >= VALUE_MAX)
                        vlen = VALUE_MAX - 1 - o;
                    memcpy(out + o, c->def_value[d], vlen);
                    o += vlen;
                    s += 1 + len;
                    done = 1;
                }
            }
        if (!done)
            out[o++] = *s++;
        if (o >= VALUE_MAX)
            o = VALUE_MAX - 1;
    }
    out[o] = '\0';
    xmlFree(raw);
    return out;
}

/* attr copied into buf (attr's own buffers are reused by later calls); NULL if absent. */
static const char *attr_copy(mts_ctx *c, const xmlNode *n, const char *key, char *buf, size_t size)
{
    const char *v = attr(c, n, key);
    if (!v)
        return NULL;
    snprintf(buf, size, "%s", v);
    return buf;
}

static const xmlNode *find_by_id(mts_ctx *c, const char *tag, const char *id_in);

static void warn_once(mts_ctx *c, const xmlNode *n, const char *kind, const char *what)
{
    for (int i = 0; i < c->warned_count; ++i)
        if (!strcmp(c->warned[i], kind))
            return;
    if (c->warned_count < MAX_WARNED)
        snprintf(c->warned[c->warned_count++], sizeof c->warned[0], "%s", kind);
    ic_scene_warn(c->b->scene, "%s:%d: %s %s", c->path, line_of(n), kind, what);
}

static ic_result fail(mts_ctx *c, const xmlNode *n, ic_result r, const char *what, const char *detail)
{
    return ic_error_set(c->err, r, "%s:%d: %s%s", c->path, line_of(n), what, detail ? detail : "");
}

/* The child element <tag name="name"> (any tag if tag is NULL), or NULL. */
static xmlNode *child_named(mts_ctx *c, const xmlNode *n, const char *tag, const char *name)
{
    for (xmlNode *k = n->children; k; k = k->next) {
        if (!is_element(k, tag))
            continue;
        const char *nm = attr(c, k, "name");
        if (nm && !strcmp(nm, name))
            return k;
    }
    return NULL;
}

/* Up to n numbers separated by commas or spaces; returns how many were read. */
static int parse_numbers(const char *s, float *out, int n)
{
    int k = 0;
    while (s && *s && k < n) {
        while (*s == ',' || *s == ' ' || *s == '\t' || *s == '\n' || *s == '\r')
            ++s;
        if (!*s)
            break;
        char *end;
        double v = strtod(s, &end);
        if (end == s)
            return -1;
        out[k++] = (float)v;
        s = end;
    }
    return k;
}

static ic_result float_param(mts_ctx *c, const xmlNode *n, const char *name, float fallback, float *out)
{
    *out = fallback;
    xmlNode *k = child_named(c, n, NULL, name);
    if (!k)
        return IC_OK;
    if (!is_element(k, "float") && !is_element(k, "integer"))
        return fail(c, k, IC_ERR_PARSE, "expected a <float> or <integer> for ", name);
    const char *v = attr(c, k, "value");
    if (parse_numbers(v, out, 1) != 1 || !isfinite(*out))
        return fail(c, k, IC_ERR_PARSE, "not a number: value of ", name);
    return IC_OK;
}

static const char *string_param(mts_ctx *c, const xmlNode *n, const char *name)
{
    xmlNode *k = child_named(c, n, "string", name);
    return k ? attr(c, k, "value") : NULL;
}

/* Index of refraction: a number or a named material (Mitsuba's table, the common entries). */
static ic_result ior_param(mts_ctx *c, const xmlNode *n, const char *name, float fallback, float *out)
{
    static const struct { const char *name; float ior; } table[] = {
        {"vacuum", 1.0f},       {"air", 1.000277f}, {"water", 1.333f},        {"bk7", 1.5046f},
        {"polypropylene", 1.49f}, {"acrylic glass", 1.49f}, {"diamond", 2.419f}, {"fused quartz", 1.458f},
        {"pyrex", 1.47f},       {"ethanol", 1.361f}, {"sapphire", 1.77f},     {"water ice", 1.31f}};
    xmlNode *k = child_named(c, n, NULL, name);
    *out = fallback;
    if (!k)
        return IC_OK;
    if (is_element(k, "float"))
        return float_param(c, n, name, fallback, out);
    const char *v = attr(c, k, "value");
    for (size_t i = 0; v && i < sizeof table / sizeof table[0]; ++i)
        if (!strcmp(v, table[i].name)) {
            *out = table[i].ior;
            return IC_OK;
        }
    return fail(c, k, IC_ERR_UNSUPPORTED, "unknown index of refraction name for ", name);
}

/* A colour: <rgb>, <srgb>, <spectrum> (one value; a wavelength list is averaged, with a warning) or a
 * <float>. A <texture type="bitmap"> is loaded into *texture (when texture is not NULL) with colour 1. */
static ic_result color_param(mts_ctx *c, const xmlNode *n, const char *name, ic_vec3 fallback, ic_vec3 *out,
                             int32_t *texture)
{
    *out = fallback;
    xmlNode *k = child_named(c, n, NULL, name);
    if (is_element(k, "ref")) { /* a texture declared at the top, by id */
        xmlNode *t = (xmlNode *)find_by_id(c, "texture", attr(c, k, "id"));
        if (!t)
            return fail(c, k, IC_ERR_PARSE, "<ref> to an unknown texture id for ", name);
        k = t;
    }
    if (!k)
        return IC_OK;
    float v[3];
    const char *val = is_element(k, "texture") ? NULL : attr(c, k, "value");
    if (is_element(k, "rgb") || is_element(k, "srgb")) {
        int got = parse_numbers(val, v, 3);
        if (got == 1)
            v[1] = v[2] = v[0];
        else if (got != 3)
            return fail(c, k, IC_ERR_PARSE, "expected three numbers for ", name);
        if (is_element(k, "srgb"))
            for (int i = 0; i < 3; ++i)
                v[i] = v[i] <= 0.04045f ? v[i] / 12.92f : powf((v[i] + 0.055f) / 1.055f, 2.4f);
        *out = v3(v[0], v[1], v[2]);
    } else if (is_element(k, "float") || is_element(k, "spectrum")) {
        if (val && strchr(val, ':')) { /* wavelength:value pairs: their mean */
            double sum = 0.0;
            int count = 0;
            for (const char *s = strchr(val, ':'); s; s = strchr(s + 1, ':')) {
                sum += strtod(s + 1, NULL);
                ++count;
            }
            warn_once(c, k, "<spectrum> with wavelengths", "is rendered as the mean of its values (grey)");
            *out = v3s(count ? (float)(sum / count) : 0.0f);
        } else if (parse_numbers(val, v, 1) == 1) {
            *out = v3s(v[0]);
        } else {
            return fail(c, k, IC_ERR_PARSE, "not a number: value of ", name);
        }
    } else if (is_element(k, "texture")) {
        char type_buf[64];
        const char *type = attr_copy(c, k, "type", type_buf, sizeof type_buf);
        const char *file = string_param(c, k, "filename");
        if (!texture || !type || strcmp(type, "bitmap") || !file) {
            warn_once(c, k, "<texture> other than a bitmap", "is not supported: a grey 0.5 is used");
            *out = v3s(0.5f);
            return IC_OK;
        }
        char full[IC_SCENE_PATH_MAX], where[IC_SCENE_PATH_MAX + 32];
        snprintf(where, sizeof where, "%s:%d", c->path, line_of(k));
        if (!ic_path_join(c->dir, file, full, sizeof full))
            return fail(c, k, IC_ERR_INVALID_ARG, "texture path too long", NULL);
        ic_result r = ic_scene_check_path(c->b, full, where, "texture", c->err);
        if (r == IC_OK)
            r = ic_scene_texture_load(c->b, full, where, texture, c->err);
        *out = v3s(1.0f);
        return r;
    } else {
        return fail(c, k, IC_ERR_PARSE, "expected <rgb>, <srgb>, <spectrum>, <float> or <texture> for ", name);
    }
    if (!(out->x >= 0.0f && out->y >= 0.0f && out->z >= 0.0f) || !v3_is_finite(*out))
        return fail(c, k, IC_ERR_INVALID_ARG, "a colour must be finite and >= 0: ", name);
    return IC_OK;
}

/* ---- transforms (row-major 4×4; each operation applies after the ones before it) ---- */

static void mat_identity(float m[16])
{
    memset(m, 0, sizeof(float) * 16);
    m[0] = m[5] = m[10] = m[15] = 1.0f;
}

/* m = a·m */
static void mat_premul(const float a[16], float m[16])
{
    float r[16];
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            float s = 0.0f;
            for (int k = 0; k < 4; ++k)
                s += a[i * 4 + k] * m[k * 4 + j];
            r[i * 4 + j] = s;
        }
    memcpy(m, r, sizeof r);
}

static ic_result vec_attrs(mts_ctx *c, const xmlNode *k, float fallback, ic_vec3 *out)
{
    const char *value = attr(c, k, "value");
    float v[3] = {fallback, fallback, fallback};
    if (value) {
        int got = parse_numbers(value, v, 3);
        if (got == 1)
            v[1] = v[2] = v[0];
        else if (got != 3)
            return fail(c, k, IC_ERR_PARSE, "expected one or three numbers in 'value'", NULL);
    }
    static const char *axes[3] = {"x", "y", "z"};
    for (int i = 0; i < 3; ++i) {
        const char *a = attr(c, k, axes[i]);
        if (a && parse_numbers(a, &v[i], 1) != 1)
            return fail(c, k, IC_ERR_PARSE, "not a number: attribute ", axes[i]);
    }
    *out = v3(v[0], v[1], v[2]);
    return IC_OK;
}

static ic_result point3(mts_ctx *c, const xmlNode *k, const char *key, ic_vec3 *out)
{
    float v[3];
    if (parse_numbers(attr(c, k, key), v, 3) != 3)
        return fail(c, k, IC_ERR_PARSE, "expected three numbers in attribute ", key);
    *out = v3(v[0], v[1], v[2]);
    return IC_OK;
}

static ic_result parse_transform(mts_ctx *c, const xmlNode *t, float m[16])
{
    mat_identity(m);
    for (xmlNode *k = t->children; k; k = k->next) {
        if (!is_element(k, NULL))
            continue;
        float a[16];
        mat_identity(a);
        ic_result r = IC_OK;
        ic_vec3 v;
        if (is_element(k, "translate")) {
            if ((r = vec_attrs(c, k, 0.0f, &v)) == IC_OK) {
                a[3] = v.x;
                a[7] = v.y;
                a[11] = v.z;
            }
        } else if (is_element(k, "scale")) {
            if ((r = vec_attrs(c, k, 1.0f, &v)) == IC_OK) {
                a[0] = v.x;
                a[5] = v.y;
                a[10] = v.z;
            }
        } else if (is_element(k, "rotate")) {
            float angle = 0.0f;
            if ((r = vec_attrs(c, k, 0.0f, &v)) == IC_OK && parse_numbers(attr(c, k, "angle"), &angle, 1) != 1)
                r = fail(c, k, IC_ERR_PARSE, "<rotate> needs an angle (degrees)", NULL);
            if (r == IC_OK && v3_len2(v) > 0.0f) { /* Rodrigues' formula about the unit axis */
                ic_vec3 u = v3_norm(v);
                float th = angle * IC_PI / 180.0f, cs = cosf(th), sn = sinf(th), t1 = 1.0f - cs;
                float rot[9] = {cs + u.x * u.x * t1,       u.x * u.y * t1 - u.z * sn, u.x * u.z * t1 + u.y * sn,
                                u.y * u.x * t1 + u.z * sn, cs + u.y * u.y * t1,       u.y * u.z * t1 - u.x * sn,
                                u.z * u.x * t1 - u.y * sn, u.z * u.y * t1 + u.x * sn, cs + u.z * u.z * t1};
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j)
                        a[i * 4 + j] = rot[i * 3 + j];
            }
        } else if (is_element(k, "matrix")) {
            if (parse_numbers(attr(c, k, "value"), a, 16) != 16)
                r = fail(c, k, IC_ERR_PARSE, "<matrix> needs 16 numbers (row by row)", NULL);
        } else if (is_element(k, "lookat")) {
            ic_vec3 o, tg, up = v3(0.0f, 1.0f, 0.0f);
            r = point3(c, k, "origin", &o);
            if (r == IC_OK)
                r = point3(c, k, "target", &tg);
            if (r == IC_OK && attr(c, k, "up"))
                r = point3(c, k, "up", &up);
            ic_vec3 dir = v3_norm(v3_sub(tg, o)), left = v3_cross(up, dir);
            if (r == IC_OK && !(v3_len2(left) > 0.0f))
                r = fail(c, k, IC_ERR_INVALID_ARG, "<lookat>: 'up' is parallel to the view direction", NULL);
            if (r == IC_OK) {
                left = v3_norm(left);
                ic_vec3 nu = v3_cross(dir, left);
                float cols[4][3] = {{left.x, left.y, left.z}, {nu.x, nu.y, nu.z}, {dir.x, dir.y, dir.z}, {o.x, o.y, o.z}};
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 4; ++j)
                        a[i * 4 + j] = cols[j][i];
            }
        } else {
            warn_once(c, k, "<transform> operation", "is not supported and is left out");
            continue;
        }
        if (r != IC_OK)
            return r;
        mat_premul(a, m);
    }
    return IC_OK;
}

static ic_result to_world(mts_ctx *c, const xmlNode *n, float m[16])
{
    xmlNode *t = child_named(c, n, "transform", "toWorld");
    if (!t)
        t = child_named(c, n, "transform", "to_world");
    if (!t) {
        mat_identity(m);
        return IC_OK;
    }
    return parse_transform(c, t, m);
}

/* ---- sensor ---- */

static ic_result parse_sensor(mts_ctx *c, const xmlNode *n)
{
    char type_buf[64];
    const char *type = attr_copy(c, n, "type", type_buf, sizeof type_buf);
    if (!type || (strcmp(type, "perspective") && strcmp(type, "thinlens"))) {
        warn_once(c, n, "<sensor> of this type", "is not supported: the camera is fitted to the scene");
        return IC_OK;
    }
    if (!strcmp(type, "thinlens"))
        warn_once(c, n, "<sensor type=\"thinlens\">", "is rendered as a pinhole (no depth of field)");
    float m[16], fov = 0.0f, w = 768.0f, h = 576.0f, spp = 0.0f;
    ic_result r = to_world(c, n, m);
    if (r == IC_OK)
        r = float_param(c, n, "fov", 0.0f, &fov);
    if (r == IC_OK && fov == 0.0f) {
        float focal = 0.0f;
        const char *fl = string_param(c, n, "focalLength");
        if (!fl)
            fl = string_param(c, n, "focal_length");
        if (fl && sscanf(fl, "%fmm", &focal) == 1 && focal > 0.0f) /* 35 mm film: 36 mm wide */
            fov = 2.0f * atanf(18.0f / focal) * 180.0f / IC_PI;
        else
            fov = 39.3077f; /* Mitsuba's default, a 50 mm lens */
    }
    if (r != IC_OK)
        return r;
    if (!(fov > 0.0f && fov < 180.0f))
        return fail(c, n, IC_ERR_INVALID_ARG, "fov must be in (0, 180) degrees", NULL);
    for (xmlNode *k = n->children; k && r == IC_OK; k = k->next) {
        if (is_element(k, "film")) {
            r = float_param(c, k, "width", w, &w);
            if (r == IC_OK)
                r = float_param(c, k, "height", h, &h);
        } else if (is_element(k, "sampler")) {
            r = float_param(c, k, "sampleCount", 0.0f, &spp);
            if (r == IC_OK && spp == 0.0f)
                r = float_param(c, k, "sample_count", 0.0f, &spp);
        }
    }
    if (r != IC_OK)
        return r;
    if (!(w >= 1.0f && h >= 1.0f && w <= 65536.0f && h <= 65536.0f))
        return fail(c, n, IC_ERR_INVALID_ARG, "the film's width and height must be in [1, 65536]", NULL);
    ic_camera *cam = &c->b->scene->camera;
    cam->width = c->opt->width > 0 ? c->opt->width : (int)w;
    cam->height = c->opt->height > 0 ? c->opt->height : (int)h;
    /* fovAxis: x (default), y, diagonal, smaller, larger */
    const char *axis = string_param(c, n, "fovAxis");
    if (!axis)
        axis = string_param(c, n, "fov_axis");
    float aw = (float)cam->width, ah = (float)cam->height, t = tanf(0.5f * fov * IC_PI / 180.0f);
    if (!axis || !strcmp(axis, "x") || (!strcmp(axis, "smaller") && aw <= ah) || (!strcmp(axis, "larger") && aw >= ah))
        t *= ah / aw;
    else if (!strcmp(axis, "diagonal"))
        t *= ah / sqrtf(aw * aw + ah * ah);
    else if (strcmp(axis, "y") && strcmp(axis, "smaller") && strcmp(axis, "larger"))
        return fail(c, n, IC_ERR_INVALID_ARG, "unknown fovAxis; use x, y, diagonal, smaller or larger", NULL);
    cam->fov_y_deg = 2.0f * atanf(t) * 180.0f / IC_PI;
    cam->eye = ic_xform_point(m, v3s(0.0f));
    cam->target = v3_add(cam->eye, ic_xform_dir(m, v3(0.0f, 0.0f, 1.0f)));
    cam->up = ic_xform_dir(m, v3(0.0f, 1.0f, 0.0f));
    if (spp >= 1.0f && spp <= (float)IC_MAX_SPP)
        c->b->scene->settings.spp = (int)spp;
    return IC_OK;
}

/* ---- BSDFs ---- */

/* Conductors by name: RGB fits of measured complex indices (the values renderers commonly tabulate for
 * Mitsuba's names). */
static int conductor_preset(const char *name, ic_vec3 *eta, ic_vec3 *k)
{
    static const struct { const char *name; float eta[3], k[3]; } table[] = {
        {"Au", {0.143119f, 0.374957f, 1.44248f}, {3.98316f, 2.38572f, 1.60322f}},
        {"Ag", {0.155265f, 0.116723f, 0.138342f}, {4.82835f, 3.12225f, 2.14696f}},
        {"Al", {1.65746f, 0.880369f, 0.521229f}, {9.22387f, 6.26952f, 4.837f}},
        {"Cu", {0.200438f, 0.924033f, 1.10221f}, {3.91295f, 2.45285f, 2.14219f}},
        {"Cr", {4.36968f, 2.9167f, 1.6547f}, {5.20643f, 4.23136f, 3.75495f}},
    };
    for (size_t i = 0; i < sizeof table / sizeof table[0]; ++i)
        if (!strcmp(name, table[i].name)) {
            *eta = v3(table[i].eta[0], table[i].eta[1], table[i].eta[2]);
            *k = v3(table[i].k[0], table[i].k[1], table[i].k[2]);
            return 1;
        }
    return 0;
}

static const xmlNode *find_by_id(mts_ctx *c, const char *tag, const char *id_in)
{
    char id[256];
    snprintf(id, sizeof id, "%s", id_in ? id_in : "");
    for (xmlNode *t = c->root->children; t; t = t->next) {
        const char *tid = is_element(t, tag) ? attr(c, t, "id") : NULL;
        if (tid && !strcmp(tid, id))
            return t;
    }
    return NULL;
}

static ic_result parse_bsdf(mts_ctx *c, const xmlNode *n, ic_material *m, int depth)
{
    char type_buf[64];
    const char *type = attr_copy(c, n, "type", type_buf, sizeof type_buf);
    if (!type)
        return fail(c, n, IC_ERR_PARSE, "<bsdf> needs a type", NULL);
    if (depth > 8)
        return fail(c, n, IC_ERR_PARSE, "BSDFs nested too deeply", NULL);
    /* wrappers: their first inner BSDF */
    int is_wrapper = !strcmp(type, "twosided") || !strcmp(type, "bumpmap") || !strcmp(type, "normalmap") ||
                     !strcmp(type, "mask") || !strcmp(type, "blendbsdf") || !strcmp(type, "coating");
    if (is_wrapper) {
        if (strcmp(type, "twosided")) {
            char kind[80];
            snprintf(kind, sizeof kind, "<bsdf type=\"%s\">", type);
            warn_once(c, n, kind, "is not supported: its (first) inner BSDF is used alone");
        }
        for (xmlNode *k = n->children; k; k = k->next) {
            if (is_element(k, "bsdf"))
                return parse_bsdf(c, k, m, depth + 1);
            if (is_element(k, "ref")) {
                const xmlNode *t = find_by_id(c, "bsdf", attr(c, k, "id") ? attr(c, k, "id") : "");
                if (t)
                    return parse_bsdf(c, t, m, depth + 1);
            }
        }
        return fail(c, n, IC_ERR_PARSE, "this BSDF wraps no BSDF", NULL);
    }
    ic_result r = IC_OK;
    float ext = 1.000277f, in = 1.5046f;
    int rough = !strncmp(type, "rough", 5);
    const char *base = rough ? type + 5 : type;
    if (rough) {
        xmlNode *a = child_named(c, n, NULL, "alpha");
        if (a && !is_element(a, "float"))
            warn_once(c, a, "a textured roughness", "is not supported: alpha 0.1 is used");
        else
            r = float_param(c, n, "alpha", 0.1f, &m->alpha);
        const char *dist = string_param(c, n, "distribution");
        if (r == IC_OK && dist && strcmp(dist, "ggx"))
            warn_once(c, n, "a microfacet distribution other than GGX", "is rendered as GGX of the same alpha");
        if (r == IC_OK && !(m->alpha >= 0.0f && m->alpha <= 4.0f))
            return fail(c, n, IC_ERR_INVALID_ARG, "alpha must be in [0, 4]", NULL);
        m->alpha = fminf(m->alpha, 1.0f);
    }
    if (!strcmp(type, "diffuse")) {
        m->type = IC_MAT_DIFFUSE;
        r = color_param(c, n, "reflectance", v3s(0.5f), &m->kd, &m->kd_texture);
    } else if (!strcmp(base, "plastic")) {
        m->type = IC_MAT_PLASTIC;
        r = color_param(c, n, "diffuseReflectance", v3s(0.5f), &m->kd, &m->kd_texture);
        if (r == IC_OK)
            r = color_param(c, n, "specularReflectance", v3s(1.0f), &m->ks, NULL);
        if (r == IC_OK)
            r = ior_param(c, n, "intIOR", 1.49f, &in);
        if (r == IC_OK)
            r = ior_param(c, n, "extIOR", 1.000277f, &ext);
        m->ior = in / ext;
    } else if (!strcmp(base, "conductor")) {
        m->type = IC_MAT_CONDUCTOR;
        char name_buf[64];
        const char *name = string_param(c, n, "material");
        snprintf(name_buf, sizeof name_buf, "%s", name ? name : "Cu");
        name = name_buf;
        if (!strcmp(name, "none")) {
            m->ks = v3s(1.0f); /* a perfect reflector: F = 1 through Schlick with F0 = 1 */
        } else if (!conductor_preset(name, &m->eta, &m->k)) {
            char kind[96];
            snprintf(kind, sizeof kind, "conductor material '%.40s'", name);
            warn_once(c, n, kind, "is not in irrcache's table (Au, Ag, Al, Cu, Cr, none): Cu is used");
            conductor_preset("Cu", &m->eta, &m->k);
        }
        if (r == IC_OK)
            r = color_param(c, n, "eta", m->eta, &m->eta, NULL);
        if (r == IC_OK)
            r = color_param(c, n, "k", m->k, &m->k, NULL);
        if (r == IC_OK && strcmp(name, "none"))
            r = color_param(c, n, "specularReflectance", v3s(1.0f), &m->ks, NULL);
        if (r == IC_OK)
            r = ior_param(c, n, "extEta", 1.000277f, &ext);
        m->eta = v3_scale(m->eta, 1.0f / ext);
        m->k = v3_scale(m->k, 1.0f / ext);
    } else if (!strcmp(base, "dielectric") || !strcmp(type, "thindielectric")) {
        if (!strcmp(type, "thindielectric"))
            warn_once(c, n, "<bsdf type=\"thindielectric\">", "is rendered as a solid dielectric");
        m->type = rough ? IC_MAT_ROUGH_GLASS : IC_MAT_GLASS;
        m->ks = v3s(1.0f);
        r = ior_param(c, n, "intIOR", 1.5046f, &in);
        if (r == IC_OK)
            r = ior_param(c, n, "extIOR", 1.000277f, &ext);
        m->ior = fmaxf(in / ext, 1.0f);
    } else {
        char kind[80];
        snprintf(kind, sizeof kind, "<bsdf type=\"%.40s\">", type);
        warn_once(c, n, kind, "is not supported: a diffuse grey 0.5 is used");
        m->type = IC_MAT_DIFFUSE;
        m->kd = v3s(0.5f);
    }
    return r;
}

/* ---- shapes ---- */

/* The shape's material: its inline or referenced BSDF (a diffuse 0.5 without one), with its area emitter. */
static ic_result shape_material(mts_ctx *c, const xmlNode *n, ic_material *m, int *has_bsdf)
{
    memset(m, 0, sizeof *m);
    m->type = IC_MAT_DIFFUSE;
    m->kd = v3s(0.5f);
    m->kd_texture = -1;
    m->ior = 1.5f;
    *has_bsdf = 0;
    ic_result r = IC_OK;
    for (xmlNode *k = n->children; k && r == IC_OK; k = k->next) {
        if (is_element(k, "bsdf")) {
            r = parse_bsdf(c, k, m, 0);
            *has_bsdf = 1;
        } else if (is_element(k, "ref")) {
            char id[256];
            const char *given = attr_copy(c, k, "id", id, sizeof id);
            const xmlNode *t = given ? find_by_id(c, "bsdf", id) : NULL;
            if (!t)
                return fail(c, k, IC_ERR_PARSE, "<ref> to an unknown BSDF id: ", given ? id : "(none)");
            r = parse_bsdf(c, t, m, 0);
            *has_bsdf = 1;
        } else if (is_element(k, "emitter")) {
            char type_buf[64];
            const char *type = attr_copy(c, k, "type", type_buf, sizeof type_buf);
            if (!type || strcmp(type, "area"))
                return fail(c, k, IC_ERR_UNSUPPORTED, "a shape's emitter must be of type \"area\"", NULL);
            r = color_param(c, k, "radiance", v3s(1.0f), &m->emission, NULL);
        }
    }
    snprintf(m->name, sizeof m->name, "%.100s:%d", attr(c, n, "id") ? attr(c, n, "id") : "shape", line_of(n));
    return r;
}

/* Triangles of a primitive shape in its local frame: rectangle, disk, cube, sphere. */
static ic_result primitive(mts_ctx *c, const xmlNode *n, const char *type, uint32_t material, const float m[16],
                           int flip, const char *where)
{
    enum { SEG = 64, RINGS = 32, MAXV = (RINGS + 1) * (SEG + 1) };
    ic_vec3 *p = malloc(sizeof *p * MAXV * 2), *nn = p ? p + MAXV : NULL;
    uint32_t *tri = malloc(sizeof *tri * RINGS * SEG * 6), nv = 0, nt = 0;
    if (!p || !tri) {
        free(p);
        free(tri);
        return fail(c, n, IC_ERR_OOM, "out of memory for a shape", NULL);
    }
    const ic_vec3 *normals = NULL;
    if (!strcmp(type, "rectangle")) {
        static const float q[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
        for (int i = 0; i < 4; ++i)
            p[nv++] = v3(q[i][0], q[i][1], 0.0f);
        static const uint32_t t[6] = {0, 1, 2, 0, 2, 3};
        memcpy(tri, t, sizeof t);
        nt = 2;
    } else if (!strcmp(type, "disk")) {
        p[nv++] = v3s(0.0f);
        for (int i = 0; i < SEG; ++i) {
            float a = 2.0f * IC_PI * i / SEG;
            p[nv++] = v3(cosf(a), sinf(a), 0.0f);
            tri[3 * nt] = 0;
            tri[3 * nt + 1] = 1 + i;
            tri[3 * nt + 2] = 1 + (i + 1) % SEG;
            ++nt;
        }
    } else if (!strcmp(type, "cube")) {
        for (int face = 0; face < 6; ++face) { /* axis face/2, side ± */
            int ax = face / 2;
            float sgn = face % 2 ? 1.0f : -1.0f;
            ic_vec3 nrm = v3s(0.0f), u = v3s(0.0f), v = v3s(0.0f);
            ((float *)&nrm)[ax] = sgn;
            ((float *)&u)[(ax + 1) % 3] = 1.0f;
            v = v3_cross(nrm, u);
            for (int i = 0; i < 4; ++i) {
                float su = (i == 1 || i == 2) ? 1.0f : -1.0f, sv = i >= 2 ? 1.0f : -1.0f;
                p[nv + i] = v3_add(nrm, v3_add(v3_scale(u, su), v3_scale(v, sv)));
            }
            static const uint32_t t[6] = {0, 1, 2, 0, 2, 3};
            for (int i = 0; i < 6; ++i)
                tri[3 * nt + i] = nv + t[i];
            nv += 4;
            nt += 2;
        }
    } else { /* sphere: a latitude-longitude mesh with smooth normals */
        ic_vec3 centre = v3s(0.0f);
        float radius = 1.0f;
        xmlNode *ck = child_named(c, n, "point", "center");
        ic_result r = ck ? vec_attrs(c, ck, 0.0f, &centre) : IC_OK;
        if (r == IC_OK)
            r = float_param(c, n, "radius", 1.0f, &radius);
        if (r != IC_OK) {
            free(p);
            free(tri);
            return r;
        }
        for (int j = 0; j <= RINGS; ++j)
            for (int i = 0; i <= SEG; ++i) {
                float th = IC_PI * j / RINGS, ph = 2.0f * IC_PI * i / SEG;
                ic_vec3 d = v3(sinf(th) * cosf(ph), sinf(th) * sinf(ph), cosf(th));
                nn[nv] = d;
                p[nv++] = v3_add(centre, v3_scale(d, radius));
            }
        for (int j = 0; j < RINGS; ++j)
            for (int i = 0; i < SEG; ++i) {
                uint32_t a = j * (SEG + 1) + i, b = a + SEG + 1;
                uint32_t t[6] = {a, b, a + 1, a + 1, b, b + 1}; /* outward winding */
                memcpy(&tri[3 * nt], t, sizeof t);
                nt += 2;
            }
        normals = nn;
    }
    if (flip)
        for (uint32_t t = 0; t < nt; ++t) {
            uint32_t s = tri[3 * t + 1];
            tri[3 * t + 1] = tri[3 * t + 2];
            tri[3 * t + 2] = s;
        }
    if (flip && normals)
        for (uint32_t i = 0; i < nv; ++i)
            nn[i] = v3_neg(nn[i]);
    ic_result r = ic_scene_append_triangles(c->b, p, normals, nv, tri, nt, material, m, where, c->err);
    free(p);
    free(tri);
    return r;
}

static ic_result parse_shape(mts_ctx *c, const xmlNode *n)
{
    char type_buf[64];
    const char *type = attr_copy(c, n, "type", type_buf, sizeof type_buf);
    if (!type)
        return fail(c, n, IC_ERR_PARSE, "<shape> needs a type", NULL);
    int is_file = !strcmp(type, "obj") || !strcmp(type, "ply");
    int is_prim = !strcmp(type, "rectangle") || !strcmp(type, "disk") || !strcmp(type, "cube") || !strcmp(type, "sphere");
    if (!is_file && !is_prim) {
        char kind[80];
        snprintf(kind, sizeof kind, "<shape type=\"%.40s\">", type);
        warn_once(c, n, kind, "is not supported and is left out");
        return IC_OK;
    }
    float m[16];
    ic_material mat;
    int has_bsdf = 0, flip = 0;
    ic_result r = to_world(c, n, m);
    if (r == IC_OK)
        r = shape_material(c, n, &mat, &has_bsdf);
    xmlNode *fk = child_named(c, n, "boolean", "flipNormals");
    if (!fk)
        fk = child_named(c, n, "boolean", "flip_normals");
    flip = fk && attr(c, fk, "value") && !strcmp(attr(c, fk, "value"), "true");
    if (r != IC_OK)
        return r;
    char where[IC_SCENE_PATH_MAX + 32];
    snprintf(where, sizeof where, "%s:%d", c->path, line_of(n));
    uint32_t index;
    if (is_prim) {
        r = ic_scene_add_material(c->b, &mat, c->path, &index, c->err);
        return r == IC_OK ? primitive(c, n, type, index, m, flip, where) : r;
    }
    const char *file = string_param(c, n, "filename");
    if (!file)
        return fail(c, n, IC_ERR_PARSE, "this shape needs <string name=\"filename\">", NULL);
    char full[IC_SCENE_PATH_MAX];
    if (!ic_path_join(c->dir, file, full, sizeof full))
        return fail(c, n, IC_ERR_INVALID_ARG, "mesh path too long", NULL);
    if ((r = ic_scene_check_path(c->b, full, where, "mesh", c->err)) != IC_OK)
        return r;
    if (!ic_path_exists(full))
        return ic_error_set(c->err, IC_ERR_IO, "%s: mesh '%s' not found; check the path", where, file);
    if (flip)
        warn_once(c, n, "flipNormals on a mesh file", "is not supported: the file's winding is kept");
    ic_scene *s = c->b->scene;
    uint32_t first_tri = s->triangle_count, first_mat = s->material_count;
    c->b->import_where = where;
    r = ic_mesh_import(c->b, full, m, where, c->err);
    if (r != IC_OK || !has_bsdf) /* without a BSDF the file's own materials stay (an extension of Mitsuba's) */
        return r;
    if ((r = ic_scene_add_material(c->b, &mat, c->path, &index, c->err)) != IC_OK)
        return r;
    for (uint32_t m2 = first_mat; m2 < index; ++m2) {
        c->b->material_tris[index] += c->b->material_tris[m2];
        c->b->material_tris[m2] = 0;
    }
    for (uint32_t t = first_tri; t < s->triangle_count; ++t)
        s->triangle_material[t] = index;
    return IC_OK;
}

/* ---- emitters ---- */

static ic_result parse_emitter(mts_ctx *c, const xmlNode *n)
{
    char type_buf[64];
    const char *type = attr_copy(c, n, "type", type_buf, sizeof type_buf);
    ic_scene *s = c->b->scene;
    float m[16];
    ic_result r = to_world(c, n, m);
    if (r != IC_OK || !type)
        return r != IC_OK ? r : fail(c, n, IC_ERR_PARSE, "<emitter> needs a type", NULL);
    if (!strcmp(type, "point") || !strcmp(type, "spot")) {
        ic_vec3 pos = ic_xform_point(m, v3s(0.0f)), intensity;
        xmlNode *pk = child_named(c, n, "point", "position");
        if (pk && (r = vec_attrs(c, pk, 0.0f, &pos)) != IC_OK)
            return r;
        if ((r = color_param(c, n, "intensity", v3s(1.0f), &intensity, NULL)) != IC_OK)
            return r;
        if (!strcmp(type, "point"))
            return ic_scene_add_point_light(s, pos, intensity, NULL) == IC_OK
                       ? IC_OK
                       : fail(c, n, IC_ERR_OOM, "out of memory for the lights", NULL);
        float cutoff = 20.0f, beam;
        if ((r = float_param(c, n, "cutoffAngle", 20.0f, &cutoff)) != IC_OK ||
            (r = float_param(c, n, "beamWidth", cutoff * 0.75f, &beam)) != IC_OK)
            return r;
        if (!(cutoff > 0.0f && cutoff <= 90.0f && beam >= 0.0f && beam <= cutoff))
            return fail(c, n, IC_ERR_INVALID_ARG, "spot: need 0 < beamWidth <= cutoffAngle <= 90 degrees", NULL);
        warn_once(c, n, "<emitter type=\"spot\">", "falls off between beamWidth and cutoffAngle as t² (glTF's curve)");
        ic_spot_cone cone = {ic_xform_dir(m, v3(0.0f, 0.0f, 1.0f)), cosf(beam * IC_PI / 180.0f),
                             cosf(cutoff * IC_PI / 180.0f)};
        if (cone.cos_inner <= cone.cos_outer)
            cone.cos_inner = cone.cos_outer + 1e-6f;
        return ic_scene_add_point_light(s, pos, intensity, &cone) == IC_OK
                   ? IC_OK
                   : fail(c, n, IC_ERR_OOM, "out of memory for the lights", NULL);
    }
    if (!strcmp(type, "constant")) {
        s->env.enabled = 1;
        return color_param(c, n, "radiance", v3s(1.0f), &s->env.radiance, NULL);
    }
    if (!strcmp(type, "directional")) {
        ic_vec3 d = ic_xform_dir(m, v3(0.0f, 0.0f, 1.0f));
        xmlNode *dk = child_named(c, n, "vector", "direction");
        if (dk && (r = vec_attrs(c, dk, 0.0f, &d)) != IC_OK)
            return r;
        if (!(v3_len2(d) > 0.0f))
            return fail(c, n, IC_ERR_INVALID_ARG, "directional: the direction is zero", NULL);
        if (s->sun.enabled)
            return fail(c, n, IC_ERR_UNSUPPORTED, "a second directional emitter; irrcache renders one sun", NULL);
        s->sun.enabled = 1;
        s->sun.direction = v3_neg(v3_norm(d));
        return color_param(c, n, "irradiance", v3s(1.0f), &s->sun.irradiance, NULL);
    }
    if (!strcmp(type, "envmap")) {
        char file_buf[IC_SCENE_PATH_MAX];
        const char *file = string_param(c, n, "filename");
        if (file)
            file = strncpy(file_buf, file, sizeof file_buf - 1);
        file_buf[sizeof file_buf - 1] = '\0';
        float scale = 1.0f;
        if (!file)
            return fail(c, n, IC_ERR_PARSE, "envmap needs <string name=\"filename\">", NULL);
        if ((r = float_param(c, n, "scale", 1.0f, &scale)) != IC_OK)
            return r;
        char full[IC_SCENE_PATH_MAX], where[IC_SCENE_PATH_MAX + 32];
        snprintf(where, sizeof where, "%s:%d", c->path, line_of(n));
        if (!ic_path_join(c->dir, file, full, sizeof full))
            return fail(c, n, IC_ERR_INVALID_ARG, "envmap path too long", NULL);
        if ((r = ic_scene_check_path(c->b, full, where, "environment map", c->err)) != IC_OK)
            return r;
        ic_error ierr;
        ic_image_free(&s->env.image);
        r = ic_image_read_max(full, ic_scene_max_texture_pixels(c->opt), IC_SCENE_RAISE_TEXTURE_LIMIT, &s->env.image,
                              &ierr);
        if (r != IC_OK)
            return ic_error_set(c->err, r, "%s: %s", where, ierr.message);
        s->env.enabled = 1;
        s->env.radiance = v3s(scale);
        warn_once(c, n, "<emitter type=\"envmap\">",
                  "is mapped with irrcache's lat-long convention (+y up); its toWorld rotation is not applied");
        return IC_OK;
    }
    char kind[80];
    snprintf(kind, sizeof kind, "<emitter type=\"%.40s\">", type);
    warn_once(c, n, kind, "is not supported and is left out");
    return IC_OK;
}

static ic_result parse_scene(mts_ctx *c)
{
    ic_result r = IC_OK;
    for (xmlNode *n = c->root->children; n; n = n->next)
        if (is_element(n, "default") && c->def_count < MAX_DEFAULTS) {
            const char *name = attr(c, n, "name"), *value = attr(c, n, "value");
            if (!name || !value)
                return fail(c, n, IC_ERR_PARSE, "<default> needs name and value", NULL);
            snprintf(c->def_name[c->def_count], sizeof c->def_name[0], "%s", name);
            snprintf(c->def_value[c->def_count], sizeof c->def_value[0], "%s", attr(c, n, "value"));
            ++c->def_count;
        }
    int has_sensor = 0;
    for (xmlNode *n = c->root->children; n && r == IC_OK; n = n->next) {
        if (!is_element(n, NULL) || is_element(n, "default") || is_element(n, "bsdf") || is_element(n, "texture") ||
            is_element(n, "integrator"))
            continue; /* BSDFs and textures are read where they are referenced; the integrator is irrcache's */
        if (is_element(n, "sensor")) {
            r = has_sensor++ ? IC_OK : parse_sensor(c, n);
        } else if (is_element(n, "shape")) {
            r = parse_shape(c, n);
        } else if (is_element(n, "emitter")) {
            r = parse_emitter(c, n);
        } else {
            char kind[80];
            snprintf(kind, sizeof kind, "<%.40s>", (const char *)n->name);
            warn_once(c, n, kind, "is not supported and is left out");
        }
    }
    c->b->scene->camera.width = has_sensor ? c->b->scene->camera.width : 0;
    return r;
}

ic_result ic_scene_load_mitsuba(ic_scene_builder *b, const char *path, const ic_scene_load_options *opt, ic_error *err)
{
    char *text = NULL;
    size_t len = 0;
    uint64_t max_bytes = opt->max_scene_bytes ? opt->max_scene_bytes : IC_DEFAULT_MAX_SCENE_FILE_BYTES;
    ic_result rr = ic_read_regular_file(path, "scene file", max_bytes,
                                        "keep geometry in mesh files, or raise the limit with --max-scene-bytes",
                                        &text, &len, NULL, err);
    if (rr != IC_OK)
        return rr;
    if (len > (size_t)INT_MAX) {
        free(text);
        return ic_error_set(err, IC_ERR_UNSUPPORTED, "%s: too large for the XML parser", path);
    }
    /* no network, no external entities or DTDs loaded (the defaults), no messages printed */
    xmlInitParser();
    xmlDoc *doc = xmlReadMemory(text, (int)len, path, NULL, XML_PARSE_NONET | XML_PARSE_NOWARNING | XML_PARSE_NOERROR);
    free(text);
    if (!doc) {
        const xmlError *e = xmlGetLastError();
        char msg[256] = "not well-formed XML";
        if (e && e->message) {
            snprintf(msg, sizeof msg, "%s", e->message);
            msg[strcspn(msg, "\n")] = '\0';
        }
        return ic_error_set(err, IC_ERR_PARSE, "%s:%d: %s; fix the XML", path, e ? e->line : 0, msg);
    }
    mts_ctx *c = calloc(1, sizeof *c);
    if (!c) {
        xmlFreeDoc(doc);
        return ic_error_set(err, IC_ERR_OOM, "%s: out of memory", path);
    }
    c->b = b;
    c->opt = opt;
    c->path = path;
    c->err = err;
    ic_path_dirname(path, c->dir, sizeof c->dir);
    c->root = xmlDocGetRootElement(doc);
    ic_result r;
    if (!is_element(c->root, "scene"))
        r = fail(c, c->root, IC_ERR_PARSE, "the root element must be <scene> (a Mitsuba scene file)", NULL);
    else
        r = parse_scene(c);
    int has_camera = c->b->scene->camera.width > 0;
    free(c);
    xmlFreeDoc(doc);
    if (r != IC_OK)
        return r;
    r = ic_scene_finalize(b, err);
    if (r == IC_OK && !has_camera)
        ic_scene_fit_camera(b->scene, opt->width > 0 ? opt->width : IC_DEFAULT_WIDTH,
                            opt->height > 0 ? opt->height : IC_DEFAULT_HEIGHT);
    return r;
}
