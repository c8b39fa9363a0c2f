/* sampling.c — warps, pdfs and inverses declared in sampling.h. */
#include "sampling.h"

ic_vec3 ic_warp_concentric_disk(float u1, float u2)
{
    float a = 2.0f * u1 - 1.0f, b = 2.0f * u2 - 1.0f;
    if (a == 0.0f && b == 0.0f)
        return v3(0.0f, 0.0f, 0.0f);
    float r, phi;
    if (fabsf(a) > fabsf(b)) {
        r = a;
        phi = (IC_PI / 4.0f) * (b / a);
    } else {
        r = b;
        phi = (IC_PI / 2.0f) - (IC_PI / 4.0f) * (a / b);
    }
    return v3(r * cosf(phi), r * sinf(phi), 0.0f);
}

void ic_warp_concentric_disk_inv(ic_vec3 p, float *u1, float *u2)
{
    float r = sqrtf(p.x * p.x + p.y * p.y);
    float phi = atan2f(p.y, p.x);
    if (phi < -IC_PI / 4.0f)
        phi += 2.0f * IC_PI;
    float a, b;
    if (phi < IC_PI / 4.0f) { /* region a > |b|, a > 0 */
        a = r;
        b = phi * a / (IC_PI / 4.0f);
    } else if (phi < 3.0f * IC_PI / 4.0f) { /* b > |a| */
        b = r;
        a = -(phi - IC_PI / 2.0f) * b / (IC_PI / 4.0f);
    } else if (phi < 5.0f * IC_PI / 4.0f) { /* a < -|b| */
        a = -r;
        b = (phi - IC_PI) * a / (IC_PI / 4.0f);
    } else { /* b < -|a| */
        b = -r;
        a = -(phi - 3.0f * IC_PI / 2.0f) * b / (IC_PI / 4.0f);
    }
    *u1 = 0.5f * (a + 1.0f);
    *u2 = 0.5f * (b + 1.0f);
}

ic_vec3 ic_warp_cosine_hemisphere(float u1, float u2)
{
    ic_vec3 d = ic_warp_concentric_disk(u1, u2);
    d.z = sqrtf(fmaxf(0.0f, 1.0f - d.x * d.x - d.y * d.y));
    return d;
}

float ic_warp_cosine_hemisphere_pdf(ic_vec3 d) { return d.z > 0.0f ? d.z * IC_INV_PI : 0.0f; }

void ic_warp_cosine_hemisphere_inv(ic_vec3 d, float *u1, float *u2) { ic_warp_concentric_disk_inv(d, u1, u2); }

ic_vec3 ic_warp_uniform_hemisphere(float u1, float u2)
{
    float z = u1;
    float r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    float phi = 2.0f * IC_PI * u2;
    return v3(r * cosf(phi), r * sinf(phi), z);
}

float ic_warp_uniform_hemisphere_pdf(ic_vec3 d) { return d.z >= 0.0f ? 1.0f / (2.0f * IC_PI) : 0.0f; }

void ic_warp_uniform_hemisphere_inv(ic_vec3 d, float *u1, float *u2)
{
    float phi = atan2f(d.y, d.x);
    if (phi < 0.0f)
        phi += 2.0f * IC_PI;
    *u1 = d.z;
    *u2 = phi / (2.0f * IC_PI);
}

ic_vec3 ic_warp_uniform_sphere(float u1, float u2)
{
    float z = 1.0f - 2.0f * u1;
    float r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    float phi = 2.0f * IC_PI * u2;
    return v3(r * cosf(phi), r * sinf(phi), z);
}

float ic_warp_uniform_sphere_pdf(ic_vec3 d)
{
    (void)d;
    return 1.0f / (4.0f * IC_PI);
}

void ic_warp_uniform_sphere_inv(ic_vec3 d, float *u1, float *u2)
{
    float phi = atan2f(d.y, d.x);
    if (phi < 0.0f)
        phi += 2.0f * IC_PI;
    *u1 = (1.0f - d.z) * 0.5f;
    *u2 = phi / (2.0f * IC_PI);
}

ic_vec3 ic_warp_phong_lobe(float u1, float u2, float exponent)
{
    float z = powf(u1, 1.0f / (exponent + 1.0f));
    float r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    float phi = 2.0f * IC_PI * u2;
    return v3(r * cosf(phi), r * sinf(phi), z);
}

float ic_warp_phong_lobe_pdf(ic_vec3 d, float exponent)
{
    return d.z > 0.0f ? (exponent + 1.0f) / (2.0f * IC_PI) * powf(d.z, exponent) : 0.0f;
}

void ic_warp_phong_lobe_inv(ic_vec3 d, float exponent, float *u1, float *u2)
{
    float phi = atan2f(d.y, d.x);
    if (phi < 0.0f)
        phi += 2.0f * IC_PI;
    *u1 = powf(fmaxf(d.z, 0.0f), exponent + 1.0f);
    *u2 = phi / (2.0f * IC_PI);
}

/* 1 − cos θ of a unit direction about +z, from its sideways part where θ is small: sin²θ/(1 + cos θ). */
static float one_minus_cos_z(ic_vec3 d)
{
    float s2 = d.x * d.x + d.y * d.y;
    return d.z > 0.0f ? s2 / (1.0f + d.z) : 1.0f - d.z;
}

ic_vec3 ic_warp_uniform_cone(float u1, float u2, float one_minus_cos)
{
    /* 1 − cos θ uniform in [0, 1 − cos θ_max]; sin θ = sqrt(t (2 − t)) for t = 1 − cos θ */
    float t = u1 * one_minus_cos;
    float r = sqrtf(fmaxf(0.0f, t * (2.0f - t)));
    float phi = 2.0f * IC_PI * u2;
    return v3(r * cosf(phi), r * sinf(phi), 1.0f - t);
}

float ic_warp_uniform_cone_pdf(ic_vec3 d, float one_minus_cos)
{
    return one_minus_cos_z(d) <= one_minus_cos ? 1.0f / (2.0f * IC_PI * one_minus_cos) : 0.0f;
}

void ic_warp_uniform_cone_inv(ic_vec3 d, float one_minus_cos, float *u1, float *u2)
{
    float phi = atan2f(d.y, d.x);
    if (phi < 0.0f)
        phi += 2.0f * IC_PI;
    *u1 = one_minus_cos_z(d) / one_minus_cos;
    *u2 = phi / (2.0f * IC_PI);
}

void ic_warp_triangle(float u1, float u2, float *b1, float *b2)
{
    float s = sqrtf(u1);
    *b1 = 1.0f - s;
    *b2 = u2 * s;
}

void ic_warp_triangle_inv(float b1, float b2, float *u1, float *u2)
{
    float s = 1.0f - b1;
    *u1 = s * s;
    *u2 = s > 0.0f ? b2 / s : 0.0f;
}
