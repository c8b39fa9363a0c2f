/*
 * bsdf_microfacet.c — rough conductor and rough plastic (bsdf_microfacet.h).
 *
 * Both reflect by the GGX microfacet model of Walter et al. 2007 (eq. 20: f = F·D·G2/(4 cos θo cos θi)),
 * with the height-correlated Smith G2 (Heitz 2014 §5.3) and visible-normal sampling (Heitz 2018).
 * Conductor: F is the exact conductor Fresnel of a complex index, or Schlick's from an F0 colour.
 * Plastic: a dielectric coat (exact Fresnel of index ior, tint ks) over a Lambertian base coupled as
 * Kelemen & Szirmay-Kalos 2001: f_d = kd·(1 − E(μo))·(1 − E(μi)) / (π·(1 − Ē)), E the coat's directional
 * albedo and Ē its cosine-weighted mean. This term is reciprocal, and with kd = 1 the whole material
 * reflects exactly what arrives (E(μo) + (1 − E(μo))·1): the energy the single-scattering coat loses at
 * high roughness goes to the base instead of vanishing. The bsdf's kd holds kd·(1 − E(μo)), the base's
 * albedo under uniform light, and ic_bsdf_diffuse_factor the factor (1 − E(μi))/(1 − Ē).
 * Metallic m (glTF 2.0 appendix B): the plastic's whole BRDF times 1 − m plus m times a conductor of
 * Schlick F0 = the base colour with the same GGX lobe, f = (1 − m)·f_plastic + m·f_metal; linear in m, so
 * a texel with m = 0 is the plastic and m = 1 the conductor exactly.
 */
#include "bsdf_microfacet.h"

void ic_mf_init(ic_bsdf *b, const ic_material *m, float alpha, float metallic, float cos_o, ic_vec3 tint)
{
    b->alpha = fmaxf(alpha, IC_GGX_ALPHA_MIN);
    b->eta = m->eta;
    b->k = m->k;
    b->coat_albedo = ic_scene_coat_table(m, alpha, &b->coat_albedo_avg);
    b->metal = 0.0f;
    if (b->type == IC_MAT_ROUGH_GLASS) {
        b->kd = v3s(0.0f);
        b->p_diffuse = 0.0f;
        return;
    }
    if (b->type == IC_MAT_CONDUCTOR) {
        b->ks = v3_mul(m->ks, tint);
        b->kd = v3s(0.0f);
        b->p_diffuse = 0.0f;
        return;
    }
    float e_o = ic_coat_albedo(b->coat_albedo, cos_o);
    float ls = e_o * v3_lum(b->ks);
    if (metallic > 0.0f) {
        b->metal = fminf(metallic, 1.0f);
        b->metal_f0 = b->kd;
        b->kd = v3_scale(b->kd, 1.0f - b->metal);
        ls = (1.0f - b->metal) * ls + b->metal * v3_lum(ic_fresnel_schlick(cos_o, b->metal_f0));
    }
    b->kd = v3_scale(b->kd, 1.0f - e_o);
    float ld = v3_lum(b->kd);
    b->p_diffuse = ld + ls > 0.0f ? ld / (ld + ls) : 1.0f;
}

ic_vec3 ic_mf_glossy(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f)
        return v3s(0.0f);
    ic_vec3 h = v3_norm(v3_add(wo, wi));
    float c = v3_dot(wo, h);
    ic_vec3 F;
    if (b->type == IC_MAT_PLASTIC && b->metal > 0.0f)
        F = v3_add(v3_scale(b->ks, (1.0f - b->metal) * ic_fresnel_dielectric(c, b->ior)),
                   v3_scale(ic_fresnel_schlick(c, b->metal_f0), b->metal));
    else if (b->type == IC_MAT_PLASTIC)
        F = v3_scale(b->ks, ic_fresnel_dielectric(c, b->ior));
    else if (v3_is_black(b->k))
        F = ic_fresnel_schlick(c, b->ks);
    else
        F = v3_mul(b->ks, ic_fresnel_conductor(c, b->eta, b->k));
    float dg = ic_ggx_d(h, b->alpha) * ic_ggx_g2(wo, wi, b->alpha) / (4.0f * wo.z * wi.z);
    return v3_scale(F, dg);
}

float ic_mf_pdf_glossy(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi) { return ic_ggx_reflect_pdf(wo, wi, b->alpha); }

ic_vec3 ic_mf_sample_glossy(const ic_bsdf *b, ic_vec3 wo, float u1, float u2)
{
    return v3_reflect(wo, ic_ggx_sample_visible(wo, b->alpha, u1, u2));
}

/* --- rough dielectric (Walter et al. 2007 §5.1–5.3: the generalised half vector of refraction,
 * eq. 16, the BTDF of eq. 21 and the Jacobian of eq. 17). Directions may lie on either side; the frame's
 * +z is the outside (the side the geometric normal points to), ior the inside's index relative to it. */

/* The generalised half vector of the pair, turned to +z; 0 if the pair has none (grazing directions, or a
 * microfacet seen from its back). *etap: n_i/n_o of the transmission (1 for reflection). */
static int dielectric_half(float ior, ic_vec3 wo, ic_vec3 wi, ic_vec3 *wm, float *etap)
{
    if (wo.z == 0.0f || wi.z == 0.0f)
        return 0;
    int reflect = wo.z * wi.z > 0.0f;
    *etap = reflect ? 1.0f : (wo.z > 0.0f ? ior : 1.0f / ior);
    ic_vec3 m = v3_add(v3_scale(wi, *etap), wo);
    if (v3_len2(m) <= 0.0f)
        return 0;
    m = v3_norm(m);
    if (m.z < 0.0f)
        m = v3_neg(m);
    /* both directions must see the microfacet from the side their hemisphere gives */
    if (v3_dot(m, wi) * wi.z <= 0.0f || v3_dot(m, wo) * wo.z <= 0.0f)
        return 0;
    *wm = m;
    return 1;
}

/* Density of the visible normal wm seen from wo (either side). */
static float visible_pdf(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wm)
{
    return ic_ggx_g1(wo, b->alpha) * ic_ggx_d(wm, b->alpha) * fabsf(v3_dot(wo, wm)) / fabsf(wo.z);
}

float ic_mf_dielectric_f(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi)
{
    ic_vec3 wm;
    float etap;
    if (!dielectric_half(b->ior, wo, wi, &wm, &etap))
        return 0.0f;
    float F = ic_fresnel_dielectric(v3_dot(wo, wm), b->ior);
    float dg = ic_ggx_d(wm, b->alpha) * ic_ggx_g2(wo, wi, b->alpha);
    if (wo.z * wi.z > 0.0f)
        return F * dg / (4.0f * fabsf(wo.z * wi.z));
    float denom = v3_dot(wi, wm) + v3_dot(wo, wm) / etap;
    /* Radiance is not scaled by 1/η² across the interface, as for the smooth glass (bsdf.c). */
    return (1.0f - F) * dg * fabsf(v3_dot(wi, wm) * v3_dot(wo, wm) / (wi.z * wo.z * denom * denom));
}

float ic_mf_dielectric_pdf(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi)
{
    ic_vec3 wm;
    float etap;
    if (!dielectric_half(b->ior, wo, wi, &wm, &etap))
        return 0.0f;
    float R = ic_fresnel_dielectric(v3_dot(wo, wm), b->ior), pv = visible_pdf(b, wo, wm);
    if (wo.z * wi.z > 0.0f)
        return R * pv / (4.0f * fabsf(v3_dot(wo, wm)));
    float denom = v3_dot(wi, wm) + v3_dot(wo, wm) / etap;
    return (1.0f - R) * pv * fabsf(v3_dot(wi, wm)) / (denom * denom);
}

int ic_mf_dielectric_sample(const ic_bsdf *b, ic_vec3 wo, float u0, float u1, float u2, ic_vec3 *wi)
{
    if (wo.z == 0.0f)
        return 0;
    ic_vec3 up = wo.z > 0.0f ? wo : v3_neg(wo);
    ic_vec3 wm = ic_ggx_sample_visible(up, b->alpha, u1, u2);
    float c = v3_dot(wo, wm); /* the side of wm that wo sees */
    float R = ic_fresnel_dielectric(c, b->ior);
    if (u0 < R) {
        *wi = v3_reflect(wo, wm);
        return wi->z * wo.z > 0.0f;
    }
    /* refraction about wm: eta = n_i/n_t for the side wo is on */
    float eta = c > 0.0f ? 1.0f / b->ior : b->ior;
    ic_vec3 n = c > 0.0f ? wm : v3_neg(wm);
    float ci = fabsf(c), sin2_t = eta * eta * (1.0f - ci * ci);
    if (sin2_t >= 1.0f)
        return 0;
    *wi = v3_norm(v3_add(v3_scale(v3_neg(wo), eta), v3_scale(n, eta * ci - sqrtf(1.0f - sin2_t))));
    return wi->z * wo.z < 0.0f;
}
