/*
 * bsdf.h — the scattering models of the materials in scene.h, in one place.
 *
 * Lambertian (kd/π), the normalized modified Phong lobe (Lafortune & Willems 1994: ks·(n+2)/(2π)·cos^n α,
 * α between the mirror direction of wo and wi), the ideal mirror and the smooth dielectric (Fresnel
 * reflection/refraction, Schlick-free exact dielectric Fresnel), and the GGX microfacet rough conductor and
 * rough plastic (bsdf_microfacet.c), and the thin pane (reflection and transmission of a sheet summed over
 * its inter-reflections, as Radiance's glass; Born & Wolf §1.6 for the slab), and the translucent sheet
 * (Radiance's trans without its specular reflection: Lambertian reflection, Lambertian transmission and
 * straight-through transmission). All directions are world space and point away from the surface; `ns`
 * is the shading normal on the side of wo for opaque materials.
 *
 * Every non-delta material splits into the same two lobes, which is how the cache's final render treats
 * them all alike: a diffuse lobe that is kd/π times a factor of wi whose cosine-weighted mean is 1 (so
 * kd/π·E is its exact reflection of uniform light; the factor is 1 except for rough plastic), cached, and
 * a glossy lobe (Phong or GGX) that is sampled. The translucent sheet's transmission takes the glossy lobe's
 * place (sampled, never cached): its diffuse part is a smooth lobe below the surface, its straight part a
 * delta that the glossy sampler returns as is_specular.
 */
#ifndef IC_INTEGRATORS_BSDF_H
#define IC_INTEGRATORS_BSDF_H

#include "scene/scene.h"

/* A material evaluated at one surface point. */
typedef struct ic_bsdf {
    ic_material_type type;
    ic_vec3 kd;            /* diffuse albedo (texture applied) */
    ic_vec3 ks;            /* specular albedo */
    float ns;              /* Phong exponent */
    float ior;             /* glass, plastic's coat */
    float alpha;           /* GGX roughness (conductor, plastic) */
    ic_vec3 eta, k;        /* conductor: complex index (k all 0: Schlick from F0 = ks) */
    ic_vec3 kt, kt_specular; /* translucent: diffuse and straight-through transmittance */
    float p_straight;      /* translucent: probability that the transmission lobe's sample goes straight on */
    const float *coat_albedo; /* plastic: the coat's E(μ) table (borrowed from the material) */
    float coat_albedo_avg; /* plastic: its cosine-weighted mean */
    float metal;           /* plastic: weight of the conductor lobe (glTF's metallic), 0 for a plain plastic */
    ic_vec3 metal_f0;      /* plastic with metal > 0: the conductor lobe's F0 (the base colour) */
    float p_diffuse;       /* probability of sampling the diffuse lobe (glossy, plastic) */
    ic_frame frame;        /* around the shading normal */
    ic_vec3 cache_n;       /* the normal the irradiance cache uses here: frame.n, or with a normal map the
                              interpolated normal on frame.n's side (records keyed on it, docs/scene-format.md) */
    ic_vec3 ng;            /* geometric normal */
} ic_bsdf;

typedef struct ic_bsdf_sample {
    ic_vec3 wi;            /* sampled direction */
    ic_vec3 weight;        /* f·|cos|/pdf */
    float pdf;             /* solid-angle pdf (0 for a failed sample; meaningless if is_specular) */
    int is_specular;       /* delta lobe: no MIS, no NEE */
} ic_bsdf_sample;

/* A thin pane of index ior whose one pass at normal incidence transmits tn (per channel), lit at cos θ =
 * cos_i: its reflectance and transmittance summed over the reflections inside it, for each polarisation
 * (Fresnel r, path transmission d = tn^(1/cos θt)): R = r + (1−r)² r d²/(1 − r²d²), T = (1−r)² d/(1 − r²d²),
 * averaged over s and p. With tn = 1, R + T = 1. */
void ic_thin_glass(float cos_i, float ior, ic_vec3 tn, ic_vec3 *R, ic_vec3 *T);

/* Sets up the BSDF at surface s seen from direction wo. */
void ic_bsdf_init(ic_bsdf *b, const ic_scene *scene, const ic_surface *s, ic_vec3 wo);
/* 1 if the material has a non-delta lobe (light sampling makes sense). */
static inline int ic_bsdf_has_smooth(const ic_bsdf *b)
{
    return b->type == IC_MAT_DIFFUSE || b->type == IC_MAT_GLOSSY || b->type == IC_MAT_CONDUCTOR ||
           b->type == IC_MAT_PLASTIC || b->type == IC_MAT_TRANSLUCENT;
}
/* Probability with which ic_bsdf_sample_dir reflects, for materials that reflect or transmit ideally
 * (glass: Fresnel; thin glass: its share of R + T); 1 for the others. The shading-point search follows the
 * larger branch. */
float ic_bsdf_reflect_probability(const ic_bsdf *b, ic_vec3 wo);
/* f(wo, wi) of the non-delta lobes (0 for delta materials). */
ic_vec3 ic_bsdf_eval(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi);
/* Solid-angle pdf of ic_bsdf_sample choosing wi. */
float ic_bsdf_pdf(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi);
/* Samples wi; returns 0 if the sample failed (absorbed). */
int ic_bsdf_sample_dir(const ic_bsdf *b, ic_vec3 wo, float u0, float u1, float u2, ic_bsdf_sample *out);
/* The two non-delta lobes of f(wo, wi) separately: diffuse (kd/π, times the plastic's coat factor) and
 * glossy (Phong or GGX). */
void ic_bsdf_eval_lobes(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi, ic_vec3 *diffuse, ic_vec3 *glossy);
/* 1 if the material has a glossy lobe. */
static inline int ic_bsdf_has_glossy(const ic_bsdf *b)
{
    if (b->type == IC_MAT_TRANSLUCENT)
        return v3_maxc(b->kt) > 0.0f || v3_maxc(b->kt_specular) > 0.0f;
    return (b->type == IC_MAT_GLOSSY || b->type == IC_MAT_CONDUCTOR || b->type == IC_MAT_PLASTIC) &&
           v3_maxc(b->ks) > 0.0f;
}
/* Solid-angle pdf of sampling wi from the glossy lobe alone. */
float ic_bsdf_pdf_glossy(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi);
/* Samples the glossy lobe alone (weight = f_glossy·cos/pdf_glossy); 0 if it fails. */
int ic_bsdf_sample_glossy(const ic_bsdf *b, ic_vec3 wo, float u1, float u2, ic_bsdf_sample *out);
/* The glossy lobe as f(wi, wo) with both directions in the local frame of b->frame (+z the shading
 * normal): isotropic about the normal, for projections onto a basis of the hemisphere (0 below it). */
ic_vec3 ic_bsdf_glossy_local(const ic_bsdf *b, ic_vec3 wi_local, ic_vec3 wo_local);
/* The diffuse lobe's factor of wi (cos θi = cos_i): 1, except for rough plastic's coupling to its coat. */
static inline float ic_bsdf_diffuse_factor(const ic_bsdf *b, float cos_i)
{
    return b->type == IC_MAT_PLASTIC ? (1.0f - ic_coat_albedo(b->coat_albedo, cos_i)) / (1.0f - b->coat_albedo_avg)
                                     : 1.0f;
}

#endif
