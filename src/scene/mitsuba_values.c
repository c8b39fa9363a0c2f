/*
 * mitsuba_values.c — the values of a Mitsuba scene's elements: attributes with <default> substitution,
 * typed parameters (float, string, index of refraction, colour, point and vector), transforms (lookat,
 * matrix, translate, rotate, scale, each applied after the ones before it), references by id.
 */
#include "scene/mitsuba_internal.h"

#include "core/error_at.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int ic_mts_line(const xmlNode *n) { return n ? (int)xmlGetLineNo(n) : 0; }
const char *ic_mts_file(const ic_mts_ctx *c, const xmlNode *n)
{
    return n && n->doc && n->doc->URL ? (const char *)n->doc->URL : c->path;
}

/* The major number of a version "MAJOR[.MINOR[.PATCH]]" (digits, blanks around it allowed); -1 if the text
 * is not one. */
static int parse_version(const char *v)
{
    int major = -1, parts = 0;
    while (*v == ' ' || *v == '\t')
        ++v;
    for (;;) {
        if (!isdigit((unsigned char)*v))
            return -1;
        char *end;
        long x = strtol(v, &end, 10);
        if (x > 9999)
            return -1;
        if (parts++ == 0)
            major = (int)x;
        v = end;
        if (*v != '.' || parts == 3)
            break;
        ++v;
    }
    while (*v == ' ' || *v == '\t')
        ++v;
    return *v ? -1 : major;
}

int ic_mts_version_major(const xmlNode *n)
{
    const xmlNode *root = n && n->doc ? xmlDocGetRootElement(n->doc) : NULL;
    xmlChar *version = root ? xmlGetProp(root, (const xmlChar *)"version") : NULL;
    int major = version ? parse_version((const char *)version) : 0;
    if (version)
        xmlFree(version);
    return major > 0 ? major : 0;
}

ic_result ic_mts_check_version(ic_mts_ctx *c, const xmlNode *root)
{
    const char *version = ic_mts_attr(c, root, "version");
    if (!version || parse_version(version) >= 0)
        return IC_OK;
    char detail[96];
    snprintf(detail, sizeof detail, "'%.40s'%s", version, strlen(version) > 40 ? "..." : "");
    return ic_mts_fail(c, root, IC_ERR_PARSE, "<scene version> is not a version number such as 0.6.0 or 3.0.0 (leave "
                       "it out for Mitsuba 0.6's defaults): ", detail);
}

int ic_mts_is_element(const xmlNode *n, const char *name)
{
    return n && n->type == XML_ELEMENT_NODE && (!name || !strcmp((const char *)n->name, name));
}

const char *ic_mts_attr(ic_mts_ctx *c, const xmlNode *n, const char *key)
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
                /* the whole name: $a does not match the start of $alpha */
                if (!strncmp(s + 1, c->def_name[d], len) && !isalnum((unsigned char)s[1 + len]) && s[1 + len] != '_') {
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

const char *ic_mts_attr_copy(ic_mts_ctx *c, const xmlNode *n, const char *key, char *buf, size_t size)
{
    const char *v = ic_mts_attr(c, n, key);
    if (!v)
        return NULL;
    snprintf(buf, size, "%s", v);
    return buf;
}

void ic_mts_warn_once(ic_mts_ctx *c, const xmlNode *n, const char *kind, const char *what)
{
    for (int i = 0; i < c->warned_count; ++i)
        if (!strcmp(c->warned[i], kind))
            return;
    if (c->warned_count < MAX_WARNED)
        snprintf(c->warned[c->warned_count++], sizeof c->warned[0], "%s", kind);
    ic_scene_warn(c->b->scene, "%s:%d: %s %s", ic_mts_file(c, n), ic_mts_line(n), kind, what);
}

ic_result ic_mts_fail(ic_mts_ctx *c, const xmlNode *n, ic_result r, const char *what, const char *detail)
{
    return ic_error_set_at(c->err, r, ic_mts_file(c, n), ic_mts_line(n), "%s%s", what, detail ? detail : "");
}

/* A parameter name as Mitsuba 3 spells it: Mitsuba 0.6's camelCase in snake_case, a run of capitals one
 * word ("intIOR" and "int_ior", "toWorld" and "to_world", "diffuseReflectance" and "diffuse_reflectance"). */
static void snake_case(const char *in, char *out, size_t size)
{
    size_t o = 0;
    for (size_t i = 0; in[i] && o + 2 < size; ++i) {
        unsigned char ch = (unsigned char)in[i];
        if (isupper(ch) && i > 0 && (islower((unsigned char)in[i - 1]) || isdigit((unsigned char)in[i - 1])))
            out[o++] = '_';
        out[o++] = (char)tolower(ch);
    }
    out[o] = '\0';
}

/* The child element <tag name="name"> (any tag if tag is NULL), or NULL; the name in either version's
 * spelling (snake_case). */
xmlNode *ic_mts_child(ic_mts_ctx *c, const xmlNode *n, const char *tag, const char *name)
{
    char want[64], have[64];
    snake_case(name, want, sizeof want);
    for (xmlNode *k = n->children; k; k = k->next) {
        if (!ic_mts_is_element(k, tag))
            continue;
        const char *nm = ic_mts_attr(c, k, "name");
        if (!nm)
            continue;
        snake_case(nm, have, sizeof have);
        if (!strcmp(have, want))
            return k;
    }
    return NULL;
}

/* Up to n numbers separated by commas or spaces; returns how many were read, -1 for a word that is not a
 * number or a number that is not finite in a float (strtod reads "nan" and "inf", which reached the
 * camera and the lights). */
int ic_mts_numbers(const char *s, float *out, int n)
{
    int k = 0;
    while (s && *s && k < n) {
        while (*s == ',' || *s == ' ' || *s == '\t' || *s == '\n' || *s == '\r')
            ++s;
        if (!*s)
            break;
        char *end;
        double v = strtod(s, &end);
        if (end == s || !(fabs(v) <= 3.0e38))
            return -1;
        out[k++] = (float)v;
        s = end;
    }
    return k;
}

ic_result ic_mts_float(ic_mts_ctx *c, const xmlNode *n, const char *name, float fallback, float *out)
{
    *out = fallback;
    xmlNode *k = ic_mts_child(c, n, NULL, name);
    if (!k)
        return IC_OK;
    if (!ic_mts_is_element(k, "float") && !ic_mts_is_element(k, "integer"))
        return ic_mts_fail(c, k, IC_ERR_PARSE, "expected a <float> or <integer> for ", name);
    const char *v = ic_mts_attr(c, k, "value");
    if (ic_mts_numbers(v, out, 1) != 1 || !isfinite(*out))
        return ic_mts_fail(c, k, IC_ERR_PARSE, "not a finite number; give one such as 0.5: value of ", name);
    return IC_OK;
}

const char *ic_mts_string(ic_mts_ctx *c, const xmlNode *n, const char *name)
{
    xmlNode *k = ic_mts_child(c, n, "string", name);
    return k ? ic_mts_attr(c, k, "value") : NULL;
}

/* Index of refraction: a number or a named material (Mitsuba's table, the common entries). */
ic_result ic_mts_ior(ic_mts_ctx *c, const xmlNode *n, const char *name, float fallback, float *out)
{
    static const struct { const char *name; float ior; } table[] = {
        {"vacuum", 1.0f},       {"air", 1.000277f}, {"water", 1.333f},        {"bk7", 1.5046f},
        {"polypropylene", 1.49f}, {"acrylic glass", 1.49f}, {"diamond", 2.419f}, {"fused quartz", 1.458f},
        {"pyrex", 1.47f},       {"ethanol", 1.361f}, {"sapphire", 1.77f},     {"water ice", 1.31f}};
    xmlNode *k = ic_mts_child(c, n, NULL, name);
    *out = fallback;
    if (!k)
        return IC_OK;
    if (ic_mts_is_element(k, "float"))
        return ic_mts_float(c, n, name, fallback, out);
    const char *v = ic_mts_attr(c, k, "value");
    for (size_t i = 0; v && i < sizeof table / sizeof table[0]; ++i)
        if (!strcmp(v, table[i].name)) {
            *out = table[i].ior;
            return IC_OK;
        }
    return ic_mts_fail(c, k, IC_ERR_UNSUPPORTED, "unknown index of refraction name for ", name);
}

ic_result ic_mts_texture(ic_mts_ctx *c, const xmlNode *k, int is_data, int32_t *index, int *loaded)
{
    *loaded = 0;
    char type_buf[64];
    const char *type = ic_mts_attr_copy(c, k, "type", type_buf, sizeof type_buf);
    const char *file = ic_mts_string(c, k, "filename");
    if (!type || strcmp(type, "bitmap") || !file)
        return IC_OK;
    char full[IC_SCENE_PATH_MAX], where[IC_SCENE_PATH_MAX + 32];
    snprintf(where, sizeof where, "%s:%d", ic_mts_file(c, k), ic_mts_line(k));
    if (!ic_path_join(c->dir, file, full, sizeof full))
        return ic_mts_fail(c, k, IC_ERR_INVALID_ARG, "texture path too long", NULL);
    ic_result r = ic_scene_check_path(c->b, full, where, "texture", c->err);
    if (r == IC_OK)
        r = ic_scene_texture_load_as(c->b, full, is_data, where, index, c->err);
    *loaded = 1;
    return r;
}

/* A colour: <rgb>, <srgb>, <spectrum> (one value; a wavelength list is averaged, with a warning) or a
 * <float>. A <texture type="bitmap"> is loaded into *texture (when texture is not NULL) with colour 1. */
ic_result ic_mts_color(ic_mts_ctx *c, const xmlNode *n, const char *name, ic_vec3 fallback, ic_vec3 *out,
                             int32_t *texture)
{
    *out = fallback;
    xmlNode *k = ic_mts_child(c, n, NULL, name);
    if (ic_mts_is_element(k, "ref")) { /* a texture declared at the top, by id */
        xmlNode *t = (xmlNode *)ic_mts_find_by_id(c, "texture", ic_mts_attr(c, k, "id"));
        if (!t)
            return ic_mts_fail(c, k, IC_ERR_PARSE, "<ref> to an unknown texture id for ", name);
        k = t;
    }
    if (!k)
        return IC_OK;
    float v[3];
    const char *val = ic_mts_is_element(k, "texture") ? NULL : ic_mts_attr(c, k, "value");
    if (ic_mts_is_element(k, "rgb") || ic_mts_is_element(k, "srgb")) {
        int got = ic_mts_numbers(val, v, 3);
        if (got == 1)
            v[1] = v[2] = v[0];
        else if (got != 3)
            return ic_mts_fail(c, k, IC_ERR_PARSE, "expected three numbers for ", name);
        if (ic_mts_is_element(k, "srgb"))
            for (int i = 0; i < 3; ++i)
                v[i] = v[i] <= 0.04045f ? v[i] / 12.92f : powf((v[i] + 0.055f) / 1.055f, 2.4f);
        *out = v3(v[0], v[1], v[2]);
    } else if (ic_mts_is_element(k, "float") || ic_mts_is_element(k, "spectrum")) {
        if (val && strchr(val, ':')) { /* wavelength:value pairs: their mean */
            double sum = 0.0;
            int count = 0;
            for (const char *s = strchr(val, ':'); s; s = strchr(s + 1, ':')) {
                sum += strtod(s + 1, NULL);
                ++count;
            }
            ic_mts_warn_once(c, k, "<spectrum> with wavelengths", "is rendered as the mean of its values (grey)");
            *out = v3s(count ? (float)(sum / count) : 0.0f);
        } else if (ic_mts_numbers(val, v, 1) == 1) {
            *out = v3s(v[0]);
        } else {
            return ic_mts_fail(c, k, IC_ERR_PARSE, "not a finite number; give one such as 0.5: value of ", name);
        }
    } else if (ic_mts_is_element(k, "texture")) {
        int loaded = 0;
        ic_result r = texture ? ic_mts_texture(c, k, 0, texture, &loaded) : IC_OK;
        if (!loaded && !texture) { /* a texture where only a colour is read: a bitmap is not "other" */
            char kind[96];
            snprintf(kind, sizeof kind, "a <texture> as %.40s", name);
            ic_mts_warn_once(c, k, kind, "is not supported (a colour is read there): a grey 0.5 is used");
            *out = v3s(0.5f);
            return IC_OK;
        }
        if (!loaded) {
            ic_mts_warn_once(c, k, "<texture> other than a bitmap", "is not supported: a grey 0.5 is used");
            *out = v3s(0.5f);
            return IC_OK;
        }
        *out = v3s(1.0f);
        return r;
    } else {
        return ic_mts_fail(c, k, IC_ERR_PARSE, "expected <rgb>, <srgb>, <spectrum>, <float> or <texture> for ", name);
    }
    if (!(out->x >= 0.0f && out->y >= 0.0f && out->z >= 0.0f) || !v3_is_finite(*out))
        return ic_mts_fail(c, k, IC_ERR_INVALID_ARG, "a colour must be finite and >= 0: ", name);
    return IC_OK;
}

ic_result ic_mts_radiance(ic_mts_ctx *c, const xmlNode *n, const char *name, ic_vec3 *out)
{
    ic_result r = ic_mts_color(c, n, name, v3s(1.0f), out, NULL);
    if (r != IC_OK || !ic_radiance_too_large(*out))
        return r;
    const xmlNode *k = ic_mts_child(c, n, NULL, name);
    return ic_error_set_at(c->err, IC_ERR_INVALID_ARG, ic_mts_file(c, k), ic_mts_line(k),
                           "'%s' is " IC_RADIANCE_LIMIT_FMT "; " IC_RADIANCE_LIMIT_FIX, name, IC_RADIANCE_LIMIT_ARGS(*out));
}

/* ---- transforms (row-major 4×4; each operation applies after the ones before it) ---- */

ic_result ic_mts_vec(ic_mts_ctx *c, const xmlNode *k, float fallback, ic_vec3 *out)
{
    const char *value = ic_mts_attr(c, k, "value");
    float v[3] = {fallback, fallback, fallback};
    if (value) {
        int got = ic_mts_numbers(value, v, 3);
        if (got == 1)
            v[1] = v[2] = v[0];
        else if (got != 3)
            return ic_mts_fail(c, k, IC_ERR_PARSE, "expected one or three numbers in 'value'", NULL);
    }
    static const char *axes[3] = {"x", "y", "z"};
    for (int i = 0; i < 3; ++i) {
        const char *a = ic_mts_attr(c, k, axes[i]);
        if (a && ic_mts_numbers(a, &v[i], 1) != 1)
            return ic_mts_fail(c, k, IC_ERR_PARSE, "not a finite number; give one such as 0.5: attribute ", axes[i]);
    }
    *out = v3(v[0], v[1], v[2]);
    return IC_OK;
}

static ic_result point3(ic_mts_ctx *c, const xmlNode *k, const char *key, ic_vec3 *out)
{
    float v[3];
    if (ic_mts_numbers(ic_mts_attr(c, k, key), v, 3) != 3)
        return ic_mts_fail(c, k, IC_ERR_PARSE, "expected three numbers in attribute ", key);
    *out = v3(v[0], v[1], v[2]);
    return IC_OK;
}

static ic_result parse_transform(ic_mts_ctx *c, const xmlNode *t, float m[16])
{
    ic_mat4_identity(m);
    for (xmlNode *k = t->children; k; k = k->next) {
        if (!ic_mts_is_element(k, NULL))
            continue;
        float a[16];
        ic_mat4_identity(a);
        ic_result r = IC_OK;
        ic_vec3 v;
        if (ic_mts_is_element(k, "translate")) {
            if ((r = ic_mts_vec(c, k, 0.0f, &v)) == IC_OK) {
                a[3] = v.x;
                a[7] = v.y;
                a[11] = v.z;
            }
        } else if (ic_mts_is_element(k, "scale")) {
            if ((r = ic_mts_vec(c, k, 1.0f, &v)) == IC_OK) {
                a[0] = v.x;
                a[5] = v.y;
                a[10] = v.z;
            }
        } else if (ic_mts_is_element(k, "rotate")) {
            float angle = 0.0f;
            if ((r = ic_mts_vec(c, k, 0.0f, &v)) == IC_OK && ic_mts_numbers(ic_mts_attr(c, k, "angle"), &angle, 1) != 1)
                r = ic_mts_fail(c, k, IC_ERR_PARSE, "<rotate> needs an angle (degrees)", NULL);
            if (r == IC_OK && v3_len2(v3_norm_any(v)) > 0.0f) { /* Rodrigues' formula about the unit axis */
                ic_vec3 u = v3_norm_any(v);
                float th = angle * IC_PI / 180.0f, cs = cosf(th), sn = sinf(th), t1 = 1.0f - cs;
                float rot[9] = {cs + u.x * u.x * t1,       u.x * u.y * t1 - u.z * sn, u.x * u.z * t1 + u.y * sn,
                                u.y * u.x * t1 + u.z * sn, cs + u.y * u.y * t1,       u.y * u.z * t1 - u.x * sn,
                                u.z * u.x * t1 - u.y * sn, u.z * u.y * t1 + u.x * sn, cs + u.z * u.z * t1};
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j)
                        a[i * 4 + j] = rot[i * 3 + j];
            }
        } else if (ic_mts_is_element(k, "matrix")) {
            if (ic_mts_numbers(ic_mts_attr(c, k, "value"), a, 16) != 16)
                r = ic_mts_fail(c, k, IC_ERR_PARSE, "<matrix> needs 16 numbers (row by row)", NULL);
        } else if (ic_mts_is_element(k, "lookat")) {
            ic_vec3 o = v3s(0.0f), tg = v3s(0.0f), up = v3(0.0f, 1.0f, 0.0f);
            r = point3(c, k, "origin", &o);
            if (r == IC_OK)
                r = point3(c, k, "target", &tg);
            if (r == IC_OK && ic_mts_attr(c, k, "up"))
                r = point3(c, k, "up", &up);
            ic_vec3 dir = v3_norm_any(v3_sub(tg, o)), left = v3_norm_any(v3_cross(up, dir));
            if (r == IC_OK && !(v3_len2(dir) > 0.0f))
                r = ic_mts_fail(c, k, IC_ERR_INVALID_ARG, "<lookat>: 'origin' and 'target' coincide; move the target",
                                NULL);
            if (r == IC_OK && !(v3_len2(left) > 0.0f))
                r = ic_mts_fail(c, k, IC_ERR_INVALID_ARG,
                                "<lookat>: 'up' is zero or parallel to the view direction; pick another up vector", NULL);
            if (r == IC_OK) {
                ic_vec3 nu = v3_cross(dir, left);
                float cols[4][3] = {{left.x, left.y, left.z}, {nu.x, nu.y, nu.z}, {dir.x, dir.y, dir.z}, {o.x, o.y, o.z}};
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 4; ++j)
                        a[i * 4 + j] = cols[j][i];
            }
        } else {
            ic_mts_warn_once(c, k, "<transform> operation", "is not supported and is left out");
            continue;
        }
        if (r != IC_OK)
            return r;
        ic_mat4_mul(a, m, m);
    }
    return IC_OK;
}

ic_result ic_mts_to_world(ic_mts_ctx *c, const xmlNode *n, float m[16])
{
    xmlNode *t = ic_mts_child(c, n, "transform", "toWorld"); /* Mitsuba 3: to_world */
    if (!t) {
        ic_mat4_identity(m);
        return IC_OK;
    }
    return parse_transform(c, t, m);
}

const xmlNode *ic_mts_find_by_id(ic_mts_ctx *c, const char *tag, const char *id_in)
{
    char id[256];
    snprintf(id, sizeof id, "%s", id_in ? id_in : "");
    for (int r = 0; r < c->root_count; ++r)
        for (xmlNode *t = c->roots[r]->children; t; t = t->next) {
            const char *tid = ic_mts_is_element(t, tag) ? ic_mts_attr(c, t, "id") : NULL;
            if (tid && !strcmp(tid, id))
                return t;
        }
    return NULL;
}
