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
 */
#include "bsdf_microfacet.h"

void ic_mf_init(ic_bsdf *b, const ic_material *m, float cos_o, ic_vec3 tint)
{
    b->alpha = fmaxf(m->alpha, IC_GGX_ALPHA_MIN);
    b->eta = m->eta;
    b->k = m->k;
    b->coat_albedo = m->coat_albedo;
    b->coat_albedo_avg = m->coat_albedo_avg;
    if (b->type == IC_MAT_CONDUCTOR) {
        b->ks = v3_mul(m->ks, tint);
        b->kd = v3s(0.0f);
        b->p_diffuse = 0.0f;
        return;
    }
    float e_o = ic_coat_albedo(m->coat_albedo, cos_o);
    b->kd = v3_scale(b->kd, 1.0f - e_o);
    float ld = v3_lum(b->kd), ls = e_o * v3_lum(b->ks);
    b->p_diffuse = ld + ls > 0.0f ? ld / (ld + ls) : 1.0f;
}

ic_vec3 ic_mf_glossy(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f)
        return v3s(0.0f);
    ic_vec3 h = v3_norm(v3_add(wo, wi));
    float c = v3_dot(wo, h);
    ic_vec3 F;
    if (b->type == IC_MAT_PLASTIC)
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
