/*
 * bsdf_microfacet.h — the GGX lobes of the rough conductor and the rough plastic, for bsdf.c. Directions
 * are in the local frame of the shading normal (+z), pointing away from the surface.
 */
#ifndef IC_INTEGRATORS_BSDF_MICROFACET_H
#define IC_INTEGRATORS_BSDF_MICROFACET_H

#include "bsdf.h"

/* Sets the microfacet fields of b for material m seen at cos θo = cos_o, tint being the material's
 * texture value at the point (1 without one): conductor F0 and plastic effective base albedo. */
void ic_mf_init(ic_bsdf *b, const ic_material *m, float cos_o, ic_vec3 tint);
/* The GGX lobe f(wo, wi) (conductor: all of it; plastic: the coat). */
ic_vec3 ic_mf_glossy(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi);
/* Solid-angle pdf of ic_mf_sample_glossy choosing wi. */
float ic_mf_pdf_glossy(const ic_bsdf *b, ic_vec3 wo, ic_vec3 wi);
/* A direction reflected about a visible normal of wo (may point below the surface: a failed sample). */
ic_vec3 ic_mf_sample_glossy(const ic_bsdf *b, ic_vec3 wo, float u1, float u2);

#endif
