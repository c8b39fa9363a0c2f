/*
 * ic.h — rendering with the irradiance cache (DESIGN.md §7 and §9; seed 004_b98c0b87c8321936.txt §3).
 *
 * Two phases. Construction builds the cache with one of the strategies (lazy: Ward 1988; batch:
 * Frolov et al. 2012 multi-pass); then the final render reads the cache without changing it:
 * direct light by next-event estimation, indirect diffuse from the cache, glossy and specular paths
 * by path tracing.
 *
 * What a record holds: irradiance arriving at the shading point from the hemisphere, *excluding*
 * light that next-event estimation delivers in the final render (emitting triangles, point lights,
 * the sun) and *including* the environment, which is smooth and caches well (as Radiance treats sky
 * "glow"). So a hemisphere ray returns the environment when it escapes, and when it hits a surface:
 * that surface's direct light plus further bounces by path tracing (ic_ic_options.bounces), never the
 * surface's own emission. The final render's light sampling skips the environment accordingly.
 */
#ifndef IC_INTEGRATORS_IC_H
#define IC_INTEGRATORS_IC_H

#include "integrators/pt.h"
#include "irrcache/render.h"

/* Builds the cache and renders the image (called by ic_render for IC_INTEGRATOR_IC). */
ic_result ic_render_ic(const ic_tracer *tr, const ic_render_options *opt, ic_image *out, ic_render_stats *st,
                       ic_error *err);

#endif
