/*
 * scene_json_material.c — the "materials" section of the JSON scene file: overrides of the materials
 * the meshes define, by name.
 */
#include "scene/json_context.h"

#include "core/vecmath.h"

#include <stdio.h>
#include <string.h>

static ic_result parse_material_type(json_ctx *c, const cJSON *it, int line, ic_material_type *type)
{
    static const char *names[] = {"diffuse",   "glossy",  "mirror",      "glass",
                                  "conductor", "plastic", "rough_glass", "thin_glass", "translucent"};
    if (cJSON_IsString(it))
        for (int k = 0; k < (int)(sizeof names / sizeof names[0]); ++k)
            if (!strcmp(it->valuestring, names[k])) {
                *type = (ic_material_type)k;
                return IC_OK;
            }
    return ic_json_fail(c, line, IC_ERR_INVALID_ARG,
                        "unknown material type '%s'; use \"diffuse\", \"glossy\", \"mirror\", "
                        "\"glass\", \"conductor\", \"plastic\", \"rough_glass\", \"thin_glass\" or \"translucent\"",
                        cJSON_IsString(it) ? it->valuestring : "(not a string)");
}

/* An override as read: the fields it gives (has_*) and their values. */
typedef struct material_override {
    ic_material m;               /* the values given */
    int has_type, has_kd, has_ks, has_ns, has_em, has_two, has_ior, has_tex, has_alpha, has_eta, has_k;
    int has_rough_tex, has_metal_tex, has_metal, has_normal_tex, has_normal_scale, has_kt, has_kt_specular;
    int32_t tex;                 /* kd_texture: the texture's index, -1 for none */
} material_override;

/* 1 if a mesh defines a material called name. */
static int material_defined(const ic_scene *s, const char *name)
{
    int found = 0;
    for (uint32_t i = 0; i < s->material_count; ++i)
        found |= !strcmp(s->materials[i].name, name);
    return found;
}

/* The error for an override of a material no mesh defines: lists the names the meshes define, each
 * once, as many as fit. */
static ic_result unknown_material(json_ctx *c, const char *name, int line)
{
    const ic_scene *s = c->b->scene;
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
    return ic_json_fail(c, line, IC_ERR_INVALID_ARG,
                        "material '%s' in \"materials\" is not defined by any mesh; known materials: %s", name,
                        known[0] ? known : "(none)");
}

/* "kd_texture" (is_data 0) and the value textures (1): loads the texture at the path (resolved like every
 * path) into the scene and sets *tex to its index; an empty path leaves *tex as it is (no texture). */
static ic_result read_texture(json_ctx *c, const cJSON *it, int kl, int is_data, int32_t *tex)
{
    const char *p = "";
    ic_result r = ic_json_read_string(c, it, kl, &p);
    if (r == IC_OK && p[0]) {
        char full[IC_SCENE_PATH_MAX], owner[IC_SCENE_PATH_MAX + 32];
        r = ic_json_resolve_path(c, p, kl, "texture", full, sizeof full);
        snprintf(owner, sizeof owner, "%s:%d", c->path, kl);
        if (r == IC_OK)
            r = ic_scene_texture_load_as(c->b, full, is_data, owner, tex, c->err);
    }
    return r;
}

/* A value texture's key: its index + 1 into *slot (ic_material's convention), 0 for an empty path. */
static ic_result read_data_texture(json_ctx *c, const cJSON *it, int kl, int32_t *slot)
{
    int32_t index = -1;
    ic_result r = read_texture(c, it, kl, 1, &index);
    *slot = index + 1;
    return r;
}

/* Reads key `it` (at line kl) of an override into o. */
static ic_result read_override_key(json_ctx *c, const cJSON *it, int kl, material_override *o)
{
    static const char *valid = "type, kd, ks, ns, emission, two_sided, ior, kd_texture, alpha, eta, k, "
                                "roughness_texture, metallic, metallic_texture, normal_texture, normal_scale, kt, "
                                "kt_specular";
    ic_result r = IC_OK;
    if (!strcmp(it->string, "type")) {
        r = parse_material_type(c, it, kl, &o->m.type);
        o->has_type = 1;
    } else if (!strcmp(it->string, "kd")) {
        r = ic_json_read_color(c, it, kl, &o->m.kd);
        o->has_kd = 1;
    } else if (!strcmp(it->string, "ks")) {
        r = ic_json_read_color(c, it, kl, &o->m.ks);
        o->has_ks = 1;
    } else if (!strcmp(it->string, "ns")) {
        r = ic_json_read_float(c, it, kl, &o->m.ns);
        if (r == IC_OK && !(o->m.ns > 0.0f))
            return ic_json_fail(c, kl, IC_ERR_INVALID_ARG, "'ns' must be > 0 (a Phong exponent)");
        o->has_ns = 1;
    } else if (!strcmp(it->string, "emission")) {
        r = ic_json_read_radiance(c, it, kl, &o->m.emission);
        o->has_em = 1;
    } else if (!strcmp(it->string, "two_sided")) {
        if (!cJSON_IsBool(it))
            return ic_json_fail(c, kl, IC_ERR_PARSE, "'two_sided' must be true or false");
        o->m.two_sided_emission = cJSON_IsTrue(it);
        o->has_two = 1;
    } else if (!strcmp(it->string, "ior")) {
        r = ic_json_read_float(c, it, kl, &o->m.ior);
        if (r == IC_OK && !(o->m.ior >= 1.0f))
            return ic_json_fail(c, kl, IC_ERR_INVALID_ARG, "'ior' must be >= 1 (index of refraction)");
        o->has_ior = 1;
    } else if (!strcmp(it->string, "alpha")) {
        r = ic_json_read_float(c, it, kl, &o->m.alpha);
        if (r == IC_OK && !(o->m.alpha >= 0.0f && o->m.alpha <= 1.0f))
            return ic_json_fail(c, kl, IC_ERR_INVALID_ARG, "'alpha' must be in [0, 1] (GGX roughness)");
        o->has_alpha = 1;
    } else if (!strcmp(it->string, "eta")) {
        r = ic_json_read_color(c, it, kl, &o->m.eta);
        o->has_eta = 1;
    } else if (!strcmp(it->string, "k")) {
        r = ic_json_read_color(c, it, kl, &o->m.k);
        o->has_k = 1;
    } else if (!strcmp(it->string, "kt")) {
        r = ic_json_read_color(c, it, kl, &o->m.kt);
        o->has_kt = 1;
    } else if (!strcmp(it->string, "kt_specular")) {
        r = ic_json_read_color(c, it, kl, &o->m.kt_specular);
        o->has_kt_specular = 1;
    } else if (!strcmp(it->string, "kd_texture")) {
        r = read_texture(c, it, kl, 0, &o->tex);
        o->has_tex = 1;
    } else if (!strcmp(it->string, "roughness_texture")) {
        r = read_data_texture(c, it, kl, &o->m.roughness_texture);
        o->has_rough_tex = 1;
    } else if (!strcmp(it->string, "metallic_texture")) {
        r = read_data_texture(c, it, kl, &o->m.metallic_texture);
        o->has_metal_tex = 1;
    } else if (!strcmp(it->string, "normal_texture")) {
        r = read_data_texture(c, it, kl, &o->m.normal_texture);
        o->has_normal_tex = 1;
    } else if (!strcmp(it->string, "metallic")) {
        r = ic_json_read_float(c, it, kl, &o->m.metallic);
        if (r == IC_OK && !(o->m.metallic >= 0.0f && o->m.metallic <= 1.0f))
            return ic_json_fail(c, kl, IC_ERR_INVALID_ARG, "'metallic' must be in [0, 1]");
        o->has_metal = 1;
    } else if (!strcmp(it->string, "normal_scale")) {
        r = ic_json_read_float(c, it, kl, &o->m.normal_scale);
        if (r == IC_OK && !(o->m.normal_scale >= 0.0f && o->m.normal_scale <= 100.0f))
            return ic_json_fail(c, kl, IC_ERR_INVALID_ARG, "'normal_scale' must be in [0, 100]");
        o->has_normal_scale = 1;
    } else {
        return ic_json_unknown_key(c, kl, it->string, "a material override", valid);
    }
    return r;
}

/* Sets the fields o gives in every material called name, then keeps each one's type usable. */
static void apply_override(ic_scene *s, const char *name, const material_override *o)
{
    for (uint32_t i = 0; i < s->material_count; ++i) {
        ic_material *m = &s->materials[i];
        if (strcmp(m->name, name))
            continue;
        if (o->has_type)
            m->type = o->m.type;
        if (o->has_kd)
            m->kd = o->m.kd;
        if (o->has_ks)
            m->ks = o->m.ks;
        if (o->has_ns)
            m->ns = o->m.ns;
        if (o->has_em)
            m->emission = o->m.emission;
        if (o->has_two)
            m->two_sided_emission = o->m.two_sided_emission;
        if (o->has_ior)
            m->ior = o->m.ior;
        if (o->has_tex)
            m->kd_texture = o->tex;
        if (o->has_alpha)
            m->alpha = o->m.alpha;
        if (o->has_eta)
            m->eta = o->m.eta;
        if (o->has_k)
            m->k = o->m.k;
        if (o->has_rough_tex)
            m->roughness_texture = o->m.roughness_texture;
        if (o->has_metal_tex)
            m->metallic_texture = o->m.metallic_texture;
        if (o->has_metal)
            m->metallic = o->m.metallic;
        else if (o->has_metal_tex) /* a metallic texture alone: its values are the metallic */
            m->metallic = 1.0f;
        if (o->has_normal_tex) {
            m->normal_texture = o->m.normal_texture;
            if (!o->has_normal_scale && !(m->normal_scale > 0.0f))
                m->normal_scale = 1.0f;
        }
        if (o->has_normal_scale)
            m->normal_scale = o->m.normal_scale;
        if (o->has_kt)
            m->kt = o->m.kt;
        if (o->has_kt_specular)
            m->kt_specular = o->m.kt_specular;
        /* keep the type usable: a glossy lobe needs an exponent, a mirror or glass a tint */
        if (m->type == IC_MAT_GLOSSY && !(m->ns >= 1.0f))
            m->ns = 1.0f;
        if ((m->type == IC_MAT_MIRROR || m->type == IC_MAT_GLASS || m->type == IC_MAT_CONDUCTOR ||
             m->type == IC_MAT_PLASTIC || m->type == IC_MAT_ROUGH_GLASS || m->type == IC_MAT_THIN_GLASS) &&
            v3_is_black(m->ks) && !o->has_ks)
            m->ks = v3s(1.0f);
        /* a complex index needs its real part: a missing one is that of a pure absorber (1) */
        if (m->type == IC_MAT_CONDUCTOR && !v3_is_black(m->k) && v3_is_black(m->eta))
            m->eta = v3s(1.0f);
    }
}

/* Overrides of one named material; applies to every material of that name from every mesh. */
static ic_result parse_material_override(json_ctx *c, const cJSON *obj, int line)
{
    ic_result r = ic_json_expect_object(c, obj, line);
    if (r != IC_OK)
        return r;
    if (!material_defined(c->b->scene, obj->string))
        return unknown_material(c, obj->string, line);
    material_override o;
    memset(&o, 0, sizeof o);
    o.tex = -1;
    const cJSON *it;
    cJSON_ArrayForEach(it, obj)
    {
        int kl = ic_json_locate_key(c, it->string);
        if (ic_json_is_comment(it->string))
            continue;
        r = read_override_key(c, it, kl, &o);
        if (r != IC_OK)
            return r;
    }
    apply_override(c->b->scene, obj->string, &o);
    return IC_OK;
}

ic_result ic_json_parse_materials(json_ctx *c, const cJSON *obj, int line)
{
    ic_result r = ic_json_expect_object(c, obj, line);
    if (r != IC_OK)
        return r;
    const cJSON *it;
    cJSON_ArrayForEach(it, obj)
    {
        int kl = ic_json_locate_key(c, it->string);
        if (ic_json_is_comment(it->string))
            continue;
        r = parse_material_override(c, it, kl);
        if (r != IC_OK)
            return r;
    }
    return IC_OK;
}
