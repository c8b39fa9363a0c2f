/*
 * ic.h — rendering with the irradiance cache (Ward et al. 1988; Frolov et al. 2012 §3).
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

#include "integrators/integrator.h"

/* The integrator itself is ic_ic_integrator_create (integrator.h); its files share ic_internal.h. */

#endif
