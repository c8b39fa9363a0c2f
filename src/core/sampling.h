/*
 * sampling.h — warps from the unit square to directions and points, with their pdfs and inverses.
 *
 * Each warp has an inverse so tests can check warp(inverse(x)) = x, and a pdf that integrates to 1
 * (tests/unit/test_sampling.c). Formulas: Shirley & Chiu 1997 (concentric disk), Malley's method for
 * the cosine hemisphere, Pharr/Jakob/Humphreys PBR 3rd ed. §13.6 for the others.
 */
#ifndef IC_CORE_SAMPLING_H
#define IC_CORE_SAMPLING_H

#include <float.h>

#include "rng.h"
#include "vecmath.h"

/* Concentric map of [0,1)^2 onto the unit disk. */
ic_vec3 ic_warp_concentric_disk(float u1, float u2);
/* Inverse of the concentric map (disk point (x, y) → square). */
void ic_warp_concentric_disk_inv(ic_vec3 p, float *u1, float *u2);

/* Cosine-weighted hemisphere about +z; pdf = cos(theta)/pi. */
ic_vec3 ic_warp_cosine_hemisphere(float u1, float u2);
float ic_warp_cosine_hemisphere_pdf(ic_vec3 d);
void ic_warp_cosine_hemisphere_inv(ic_vec3 d, float *u1, float *u2);

/* Uniform hemisphere about +z; pdf = 1/(2 pi). */
ic_vec3 ic_warp_uniform_hemisphere(float u1, float u2);
float ic_warp_uniform_hemisphere_pdf(ic_vec3 d);
void ic_warp_uniform_hemisphere_inv(ic_vec3 d, float *u1, float *u2);

/* Uniform sphere; pdf = 1/(4 pi). */
ic_vec3 ic_warp_uniform_sphere(float u1, float u2);
float ic_warp_uniform_sphere_pdf(ic_vec3 d);
void ic_warp_uniform_sphere_inv(ic_vec3 d, float *u1, float *u2);

/* Normalized Phong lobe cos^n about +z; pdf = (n+1)/(2 pi) cos^n(theta). */
ic_vec3 ic_warp_phong_lobe(float u1, float u2, float exponent);
float ic_warp_phong_lobe_pdf(ic_vec3 d, float exponent);
void ic_warp_phong_lobe_inv(ic_vec3 d, float exponent, float *u1, float *u2);

/* Uniform over the cone of directions within θ_max of +z (a light's disc: the sun), given as
 * one_minus_cos = 1 − cos θ_max > 0 so that a cone a fraction of a degree wide keeps its precision in
 * float (1 − cos θ would round to a few hundred values); pdf = 1/(2π (1 − cos θ_max)) inside. */
ic_vec3 ic_warp_uniform_cone(float u1, float u2, float one_minus_cos);
float ic_warp_uniform_cone_pdf(ic_vec3 d, float one_minus_cos);
void ic_warp_uniform_cone_inv(ic_vec3 d, float one_minus_cos, float *u1, float *u2);

/* Uniform barycentrics (b1, b2) on a triangle (Heitz 2019 low-distortion map is not needed here:
 * the square-root parameterisation, PBR §13.6.4); b0 = 1 - b1 - b2. */
void ic_warp_triangle(float u1, float u2, float *b1, float *b2);
void ic_warp_triangle_inv(float b1, float b2, float *u1, float *u2);

/* Balance-free power heuristic (beta = 2) for MIS with one sample from each strategy. A pdf above
 * about 1.8e19 (a small emitter seen from far away) squares to infinity in float; the weight is then
 * taken from the pdfs' ratio in double, so that it stays in [0, 1] instead of inf / inf. */
static inline float ic_power_heuristic(float pdf_a, float pdf_b)
{
    float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
    if (a + b <= FLT_MAX) /* false for inf and NaN */
        return (a + b) > 0.0f ? a / (a + b) : 0.0f;
    if (!(pdf_a > 0.0f) || pdf_b != pdf_b)
        return 0.0f;
    double r = (double)pdf_b / (double)pdf_a;
    return (float)(1.0 / (1.0 + r * r));
}

/* Radical inverse base 2 (van der Corput), for Hammersley sets. */
static inline float ic_radical_inverse2(uint32_t i) { return (float)(ic_reverse_bits32(i) >> 8) * (1.0f / 16777216.0f); }

#endif
