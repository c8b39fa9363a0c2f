/*
 * bsdf_microfacet.h — the GGX lobes of the rough conductor and the rough plastic, for bsdf.c. Directions
 * are in the local frame of the shading normal (+z), pointing away from the surface.
 */
#ifndef IC_INTEGRATORS_BSDF_MICROFACET_H
#define IC_INTEGRATORS_BSDF_MICROFACET_H

#include "bsdf.h"

/* Sets the microfacet fields of b for material m seen at cos θo = cos_o, with GGX α alpha and metallic
 * at the point (ic_scene_microfacet_params), tint being the material's texture value there (1 without
 * one): conductor F0 and plastic effective base albedo. */
void ic_mf_init(ic_bsdf *b, const ic_material *m, float alpha, float metallic, float cos_o, ic_vec3 tint);
/* The GGX lobe f(wo, wi) (conductor: all of it; plastic: the coat). */
ic_vec3 ic_mf_glossy(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi);
/* Solid-angle pdf of ic_mf_sample_glossy choosing wi. */
float ic_mf_pdf_glossy(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi);
/* A direction reflected about a visible normal of wo (may point below the surface: a failed sample). */
ic_vec3 ic_mf_sample_glossy(const ic_bsdf *b, ic_vec3 wo, float u1, float u2);

/* Rough dielectric: f(wo, wi) of reflection and refraction, wo and wi on either side (+z is outside). */
float ic_mf_dielectric_f(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi);
/* Solid-angle pdf of ic_mf_dielectric_sample choosing wi. */
float ic_mf_dielectric_pdf(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi);
/* Samples a visible normal, then reflection (probability F) or refraction; 0 if the sample fails. */
int ic_mf_dielectric_sample(const ic_bsdf *b, ic_vec3 wo, float u0, float u1, float u2, ic_vec3 *wi);

#endif
