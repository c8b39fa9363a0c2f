/*
 * mitsuba_bsdf.c — a Mitsuba <bsdf> as an irrcache material: diffuse, plastic / roughplastic, conductor /
 * roughconductor (named metals or eta, k), dielectric / roughdielectric, and the wrappers (twosided; the
 * others warned and passed through). Every roughness distribution is rendered as GGX of the same α.
 */
#include "scene/mitsuba_internal.h"

#include <stdio.h>
#include <string.h>

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

/* A normalmap BSDF's <texture name="normalmap" type="bitmap"> (or a <ref> to one) as the material's
 * tangent-space normal map (scene_query.c), read as values. */
static ic_result normal_map(ic_mts_ctx *c, const xmlNode *n, ic_material *m)
{
    xmlNode *k = ic_mts_child(c, n, NULL, "normalmap");
    if (ic_mts_is_element(k, "ref"))
        k = (xmlNode *)ic_mts_find_by_id(c, "texture", ic_mts_attr(c, k, "id") ? ic_mts_attr(c, k, "id") : "");
    int32_t index = -1;
    int loaded = 0;
    ic_result r = k && ic_mts_is_element(k, "texture") ? ic_mts_texture(c, k, 1, &index, &loaded) : IC_OK;
    if (r == IC_OK && !loaded) {
        ic_mts_warn_once(c, n, "<bsdf type=\"normalmap\"> without a bitmap texture named normalmap",
                         "is not supported: its inner BSDF is used alone");
        return IC_OK;
    }
    m->normal_texture = index + 1;
    m->normal_scale = 1.0f;
    return r;
}

ic_result ic_mts_bsdf(ic_mts_ctx *c, const xmlNode *n, ic_material *m, int depth)
{
    char type_buf[64];
    const char *type = ic_mts_attr_copy(c, n, "type", type_buf, sizeof type_buf);
    if (!type)
        return ic_mts_fail(c, n, IC_ERR_PARSE, "<bsdf> needs a type", NULL);
    if (depth > 8)
        return ic_mts_fail(c, n, IC_ERR_PARSE, "BSDFs nested too deeply", NULL);
    /* wrappers: their first inner BSDF */
    int is_wrapper = !strcmp(type, "twosided") || !strcmp(type, "bumpmap") || !strcmp(type, "normalmap") ||
                     !strcmp(type, "mask") || !strcmp(type, "blendbsdf") || !strcmp(type, "coating");
    if (is_wrapper) {
        if (strcmp(type, "twosided") && strcmp(type, "normalmap")) {
            char kind[80];
            snprintf(kind, sizeof kind, "<bsdf type=\"%s\">", type);
            ic_mts_warn_once(c, n, kind, "is not supported: its (first) inner BSDF is used alone");
        }
        const xmlNode *inner = NULL;
        for (xmlNode *k = n->children; k && !inner; k = k->next) {
            if (ic_mts_is_element(k, "bsdf"))
                inner = k;
            else if (ic_mts_is_element(k, "ref"))
                inner = ic_mts_find_by_id(c, "bsdf", ic_mts_attr(c, k, "id") ? ic_mts_attr(c, k, "id") : "");
        }
        if (!inner)
            return ic_mts_fail(c, n, IC_ERR_PARSE, "this BSDF wraps no BSDF", NULL);
        int inner_count = 0;
        for (xmlNode *k = n->children; k; k = k->next)
            inner_count += ic_mts_is_element(k, "bsdf") || ic_mts_is_element(k, "ref");
        if (!strcmp(type, "twosided") && inner_count > 1)
            ic_mts_warn_once(c, n, "<bsdf type=\"twosided\"> with a back BSDF",
                             "is not supported: the front one is used on both sides");
        ic_result r = ic_mts_bsdf(c, inner, m, depth + 1);
        return r == IC_OK && !strcmp(type, "normalmap") ? normal_map(c, n, m) : r;
    }
    ic_result r = IC_OK;
    float ext = 1.000277f, in = 1.5046f;
    int rough = !strncmp(type, "rough", 5);
    const char *base = rough ? type + 5 : type;
    if (rough) {
        xmlNode *a = ic_mts_child(c, n, NULL, "alpha");
        if (ic_mts_is_element(a, "ref"))
            a = (xmlNode *)ic_mts_find_by_id(c, "texture", ic_mts_attr(c, a, "id") ? ic_mts_attr(c, a, "id") : "");
        if (a && !ic_mts_is_element(a, "float")) {
            /* a bitmap of α per texel (its luminance, read as values) */
            int32_t index = -1;
            int loaded = 0;
            r = ic_mts_is_element(a, "texture") ? ic_mts_texture(c, a, 1, &index, &loaded) : IC_OK;
            if (r == IC_OK && loaded) {
                m->roughness_texture = index + 1;
                m->roughness_is_alpha = 1;
                m->alpha = 1.0f;
            } else if (r == IC_OK) {
                ic_mts_warn_once(c, a, "a roughness texture other than a bitmap", "is not supported: alpha 0.1 is used");
                m->alpha = 0.1f;
            }
        } else {
            r = ic_mts_float(c, n, "alpha", 0.1f, &m->alpha);
        }
        const char *dist = ic_mts_string(c, n, "distribution");
        /* Mitsuba's default distribution is Beckmann: without one given, it is GGX here, said once */
        if (r == IC_OK && (!dist || strcmp(dist, "ggx")))
            ic_mts_warn_once(c, n, dist ? "a microfacet distribution other than GGX" : "a rough BSDF without a distribution "
                             "(Mitsuba's default, Beckmann)", "is rendered as GGX of the same alpha");
        if (r == IC_OK && (ic_mts_string(c, n, "alphaU") || ic_mts_string(c, n, "alpha_u")))
            ic_mts_warn_once(c, n, "an anisotropic alphaU/alphaV", "is not supported: the isotropic alpha is used");
        /* α above 1 is kept as Mitsuba keeps it: GGX stays a normalised distribution of normals there */
        if (r == IC_OK && !(m->alpha >= 0.0f && m->alpha <= 4.0f))
            return ic_mts_fail(c, n, IC_ERR_INVALID_ARG, "alpha must be in [0, 4]", NULL);
    }
    if (!strcmp(type, "diffuse")) {
        m->type = IC_MAT_DIFFUSE;
        r = ic_mts_color(c, n, "reflectance", v3s(0.5f), &m->kd, &m->kd_texture);
    } else if (!strcmp(base, "plastic")) {
        m->type = IC_MAT_PLASTIC;
        r = ic_mts_color(c, n, "diffuseReflectance", v3s(0.5f), &m->kd, &m->kd_texture);
        if (r == IC_OK)
            r = ic_mts_color(c, n, "specularReflectance", v3s(1.0f), &m->ks, NULL);
        if (r == IC_OK)
            r = ic_mts_ior(c, n, "intIOR", 1.49f, &in);
        if (r == IC_OK)
            r = ic_mts_ior(c, n, "extIOR", 1.000277f, &ext);
        m->ior = in / ext;
    } else if (!strcmp(base, "conductor")) {
        m->type = IC_MAT_CONDUCTOR;
        char name_buf[64];
        const char *name = ic_mts_string(c, n, "material");
        /* without a material, Mitsuba 0.6 makes copper, Mitsuba 2 and 3 "none" */
        snprintf(name_buf, sizeof name_buf, "%s", name ? name : ic_mts_version_major(n) >= 2 ? "none" : "Cu");
        name = name_buf;
        if (!strcmp(name, "none")) {
            /* Mitsuba's "none": η = 0, k = 1, whose Fresnel factor is 1 at every angle (a perfect mirror times
             * specularReflectance), and the defaults of an eta or k given alone */
            m->eta = v3s(0.0f);
            m->k = v3s(1.0f);
        } else if (!conductor_preset(name, &m->eta, &m->k)) {
            char kind[96];
            snprintf(kind, sizeof kind, "conductor material '%.40s'", name);
            ic_mts_warn_once(c, n, kind, "is not in irrcache's table (Au, Ag, Al, Cu, Cr, none): Cu is used");
            conductor_preset("Cu", &m->eta, &m->k);
        }
        if (r == IC_OK)
            r = ic_mts_color(c, n, "eta", m->eta, &m->eta, NULL);
        if (r == IC_OK)
            r = ic_mts_color(c, n, "k", m->k, &m->k, NULL);
        if (r == IC_OK) /* a tinted mirror is "none" with a reflectance, in Mitsuba 0.6 and 3 alike */
            r = ic_mts_color(c, n, "specularReflectance", v3s(1.0f), &m->ks, NULL);
        if (r == IC_OK)
            r = ic_mts_ior(c, n, "extEta", 1.000277f, &ext);
        m->eta = v3_scale(m->eta, 1.0f / ext);
        m->k = v3_scale(m->k, 1.0f / ext);
    } else if (!strcmp(base, "dielectric") || !strcmp(type, "thindielectric")) {
        /* thindielectric: a pane without absorption (irrcache sums the inter-reflections per polarisation) */
        m->type = !strcmp(type, "thindielectric") ? IC_MAT_THIN_GLASS : rough ? IC_MAT_ROUGH_GLASS : IC_MAT_GLASS;
        m->ks = v3s(1.0f);
        r = ic_mts_ior(c, n, "intIOR", 1.5046f, &in);
        if (r == IC_OK)
            r = ic_mts_ior(c, n, "extIOR", 1.000277f, &ext);
        if (r == IC_OK && in < ext)
            ic_mts_warn_once(c, n, "a dielectric with intIOR below extIOR (a bubble)",
                             "is not supported: its inside is given the outside's index, so it is invisible");
        m->ior = fmaxf(in / ext, 1.0f);
        static const char *const tints[] = {"specularTransmittance", "specularReflectance"};
        static const char *const tags[] = {"rgb", "spectrum", "srgb", "float", "texture", "ref"};
        for (int t = 0; t < 2; ++t)
            for (int g = 0; g < 6; ++g)
                if (ic_mts_child(c, n, tags[g], tints[t])) {
                    char kind[96];
                    snprintf(kind, sizeof kind, "%s on a dielectric", tints[t]);
                    ic_mts_warn_once(c, n, kind, "is not supported: the glass is clear");
                    break;
                }
    } else {
        char kind[80];
        snprintf(kind, sizeof kind, "<bsdf type=\"%.40s\">", type);
        ic_mts_warn_once(c, n, kind, "is not supported: a diffuse grey 0.5 is used");
        m->type = IC_MAT_DIFFUSE;
        m->kd = v3s(0.5f);
    }
    return r;
}
