/*
 * ic_radiance.h — radiance caching on glossy surfaces (Křivánek, Gautron, Pattanaik & Bouatouch 2005,
 * "Radiance caching for efficient global illumination computation"; Křivánek et al. 2006 §3): records of
 * the radiance kind (cache.h: IC_BOUNCE_RADIANCE) hold the incoming radiance above their point as
 * hemispherical-harmonics coefficients Λ (irrcache/hsh.h) with their translational gradients, and serve
 * the glossy lobe of the final render's first shading point:
 *
 *     L_o(p, ω_o) = Σ_i w_i · k_s ⊙ [(Λ_i + d_t ∂Λ_i/∂t + d_b ∂Λ_i/∂b) · C_i(ω_o)] / Σ_i w_i,
 *
 * C_i the lobe's coefficients for ω_o expressed in record i's frame (a table over the outgoing elevation
 * per lobe, rotated into the record's frame when the normals differ), (d_t, d_b) = p − p_i in that frame.
 * A Phong lobe is one table times k_s; a microfacet lobe (conductor, plastic's coat) is tabulated from the
 * BSDF itself (ic_bsdf_glossy_local), one table per colour channel unless they agree. Irradiance records keep serving the diffuse lobes; both kinds live in one cache with the same weights,
 * clamps and octree.
 */
#ifndef IC_INTEGRATORS_IC_RADIANCE_H
#define IC_INTEGRATORS_IC_RADIANCE_H

#include "irrcache/cache.h"
#include "irrcache/render.h"

struct ic_ctx;
struct ic_render_stats;
struct phase_times;

/* The radiance cache's state: the HSH basis and one lobe table per served glossy exponent. */
typedef struct ic_radiance ic_radiance;

/* Sets up c->rad for c's options: NULL (and IC_OK) when radiance caching is off or no material of the
 * scene has a glossy lobe the order can represent (exponent ≤ the sharpness threshold). */
ic_result ic_ic_radiance_create(struct ic_ctx *c, ic_error *err);
/* Frees it; NULL is a no-op. */
void ic_ic_radiance_destroy(ic_radiance *r);
/* The gather options of a radiance record: o's, with M × N strata (N ≈ πM) for o->radiance_rays, by default
 * IC_DEFAULT_RADIANCE_RAYS_FACTOR × an irradiance record's rays, at most IC_MAX_RECORD_RAYS. */
ic_gather_opts ic_ic_radiance_gather_opts(const ic_ic_options *o);
/* 1 if material m's glossy lobe is served by radiance records. */
int ic_ic_radiance_serves(const struct ic_ctx *c, uint32_t material);
/* Construction over the image's first-hit points on served materials, after the irradiance records:
 * coarse-to-fine passes over pixel grids of spacing 32 … 2, each gathering the points no radiance
 * record yet accepts, in parallel, and inserting them as one batch (deterministic, thread-count
 * independent); with the adaptive strategy, then passes of §4 refinement on the glossy lobe's outgoing
 * radiance and new records where refinement uncovered points, until one changes nothing. Adds its time
 * to pt, the records made to *made and the a_i lowered to *refinements. */
ic_result ic_ic_radiance_build(struct ic_ctx *c, const ic_render_options *opt, struct phase_times *pt,
                               uint32_t *made, uint32_t *refinements, ic_error *err);
/* The glossy lobe's indirect outgoing radiance at the surface point p (shading normal n, the bsdf's
 * frame) of `material` towards wo, interpolated from the radiance records: returns 0 (L unset) when none
 * accepts p. */
int ic_ic_radiance_lookup(const struct ic_ctx *c, ic_vec3 p, ic_vec3 n, uint32_t material, ic_vec3 wo,
                          ic_cache_hint *hint, ic_vec3 *L);
/* Floats a radiance record's payload holds: Λ, ∂Λ/∂t, ∂Λ/∂b, each 3·n². */
uint32_t ic_ic_radiance_payload_floats(const ic_radiance *r);

#endif
