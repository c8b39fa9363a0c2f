/*
 * ic_screen.h — the screen-space candidate selection of Frolov et al. 2012 §3.1.1–3.1.2:
 * a discontinuity map (geometry in the first pass, irradiance in later passes) evaluated on every
 * level of a mip pyramid, the up-scaled levels blended into one "need" map, and deterministic
 * dithering that picks every 32nd, 16th, 8th, 4th or 2nd pixel by local need.
 *
 * Geometry discontinuity (Frolov et al. 2012 §3.1.1, surfDisc = k·normDiff + worldPosDiff): at pyramid level l,
 * for each pixel, the largest over its 4 neighbours of
 *     k · (1 − n·n')  +  |n · (p' − p)| / (2^l · footprint)
 * i.e. the normal change plus the distance of the neighbour from this pixel's tangent plane measured
 * in pixels of that level. Measuring the position difference off the tangent plane and in pixels makes
 * the map independent of world scale and blind to in-plane motion (a slanted wall is not a
 * discontinuity); the seed leaves k "depending on world scale", which this normalisation removes.
 * The term is capped at k (a depth step is no worse than a right-angle crease), and level l enters the
 * blend with weight 2^-l (see need_map in ic_screen.c).
 * Irradiance discontinuity (§3.1.2): the relative luminance difference |Y − Y'| / max(Y, Y', ε) of
 * the current cache look-ups, on the same pyramid.
 */
#ifndef IC_INTEGRATORS_IC_SCREEN_H
#define IC_INTEGRATORS_IC_SCREEN_H

#include "irrcache/common.h"

#include <stdint.h>

/* Per-pixel shading-point buffers (one sample at each pixel centre). */
typedef struct ic_gbuffer {
    int width, height;
    ic_vec3 *p;            /* shading point (first non-specular hit) */
    ic_vec3 *n;            /* its shading normal, facing the viewer */
    float *footprint;      /* world-space width of the pixel at the primary hit */
    uint8_t *valid;        /* 1 if the pixel has a shading point */
} ic_gbuffer;

/* Need map from geometry: rows [y0, y1) of a w*h map (0 where invalid; the other rows untouched, so
 * processes can each make a block of rows and exchange them). k_normal weights the normal term. It runs
 * on `threads` threads (any count, the same map). */
ic_result ic_screen_geometry_need(const ic_gbuffer *g, float k_normal, int threads, int y0, int y1, float *need);
/* The pyramid's levels: 1, 2, 4, 8, 16 and 32 pixels, the dithering spacings. */
#define IC_SCREEN_LEVELS 6
/* The rows on either side of [y0, y1) that a need map of those rows reads (the coarsest level's texel
 * rows around theirs): values outside [y0 − IC_SCREEN_HALO, y1 + IC_SCREEN_HALO) do not change it, so a
 * process that makes a block of rows needs only that band of the values. */
#define IC_SCREEN_HALO (2 << (IC_SCREEN_LEVELS - 1))
/* Need map from per-pixel luminance values (e.g. cache look-ups), rows [y0, y1); invalid pixels ignored. */
ic_result ic_screen_value_need(const ic_gbuffer *g, const float *luminance, int threads, int y0, int y1,
                               float *need);
/* Deterministic dithering of rows [y0, y1): pixel (x, y) on the grid of spacing s ∈ {32,16,8,4,2} (the
 * coarsest grid it lies on) is chosen if its need asks for spacing ≤ s; need ≥ threshold·2^(i) asks for
 * spacing 16 >> i (i = 0..3), anything valid asks for 32. Each pixel's choice reads its own need alone, so
 * blocks of rows dithered apart give the whole image's choice. Writes chosen pixel indices in raster
 * order; returns count. */
uint32_t ic_screen_dither(const ic_gbuffer *g, const float *need, float threshold, int y0, int y1, uint32_t *pixels);

#endif
