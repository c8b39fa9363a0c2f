/*
 * microfacet.h — the isotropic GGX (Trowbridge-Reitz) microfacet distribution and the Fresnel terms of
 * the rough materials, in the local frame of a surface (+z is the normal).
 *
 * Distribution and Smith masking: Walter et al. 2007 §5.2 (D, G1) and Heitz 2014 §5.3 (the
 * height-correlated masking-shadowing G2 = 1/(1 + Λ(wo) + Λ(wi))). Sampling: the distribution of visible
 * normals, Heitz 2018 ("Sampling the GGX distribution of visible normals"), whose pdf of wi after the
 * reflection is G1(wo)·D(h)/(4·cos θo). Fresnel: the exact dielectric formula and the exact conductor
 * formula for a complex index η + ik (unpolarised light). Kept in core so that the scene can tabulate a
 * coat's albedo at load and the integrators evaluate the same functions.
 */
#ifndef IC_CORE_MICROFACET_H
#define IC_CORE_MICROFACET_H

#include "vecmath.h"

/* Smallest GGX α used: below it the lobe is narrower than float precision resolves near the peak. */
#define IC_GGX_ALPHA_MIN 1e-3f

/* GGX normal distribution D(h) for a unit half vector h (h.z > 0), roughness α. */
float ic_ggx_d(ic_vec3 h, float alpha);
/* Smith Λ(w) of GGX (Heitz 2014 eq. 72). */
float ic_ggx_lambda(ic_vec3 w, float alpha);
/* Smith masking G1(w) = 1/(1 + Λ(w)). */
static inline float ic_ggx_g1(ic_vec3 w, float alpha) { return 1.0f / (1.0f + ic_ggx_lambda(w, alpha)); }
/* Height-correlated masking-shadowing G2(wo, wi) = 1/(1 + Λ(wo) + Λ(wi)). */
static inline float ic_ggx_g2(ic_vec3 wo, ic_vec3 wi, float alpha)
{
    return 1.0f / (1.0f + ic_ggx_lambda(wo, alpha) + ic_ggx_lambda(wi, alpha));
}
/* A half vector drawn from the normals visible from wo (wo.z > 0), by Heitz 2018's construction. */
ic_vec3 ic_ggx_sample_visible(ic_vec3 wo, float alpha, float u1, float u2);
/* Solid-angle pdf of wi = reflect(wo, h) when h is drawn by ic_ggx_sample_visible: G1(wo)·D(h)/(4 wo.z). */
float ic_ggx_reflect_pdf(ic_vec3 wo, ic_vec3 wi, float alpha);

/* Exact Fresnel reflectance of a dielectric for cos of the incident angle and eta = n_t / n_i. */
float ic_fresnel_dielectric(float cos_i, float eta);
/* Exact Fresnel reflectance of a conductor of complex index eta + i·k (per channel), cos_i in [0, 1]. */
ic_vec3 ic_fresnel_conductor(float cos_i, ic_vec3 eta, ic_vec3 k);
/* Schlick's approximation from the reflectance at normal incidence f0. */
static inline ic_vec3 ic_fresnel_schlick(float cos_i, ic_vec3 f0)
{
    float m = 1.0f - ic_clampf(cos_i, 0.0f, 1.0f), m5 = m * m * m * m * m;
    return v3_add(f0, v3_scale(v3_sub(v3s(1.0f), f0), m5));
}

/* Entries of a coat's directional albedo table over cos θ in [0, 1] (uniform in √cos θ). */
#define IC_COAT_TABLE 32
/* Directional albedo E(μ) = ∫ f_spec(wo, wi) cos θi dwi of a GGX dielectric coat (index eta, roughness
 * α, single scattering) at IC_COAT_TABLE cosines μ_j = (j/(IC_COAT_TABLE-1))² (at least 10⁻³), dense at
 * grazing where E changes fastest, by stratified visible-normal quadrature (deterministic); *average gets
 * its cosine-weighted mean 2∫E(μ)μ dμ. */
void ic_coat_albedo_table(float eta, float alpha, float table[IC_COAT_TABLE], float *average);
/* E(μ) from the table, interpolated linearly in √μ. */
float ic_coat_albedo(const float table[IC_COAT_TABLE], float mu);

#endif
