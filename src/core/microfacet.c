/* microfacet.c — GGX distribution, Smith masking, visible-normal sampling and Fresnel (microfacet.h). */
#include "microfacet.h"

float ic_ggx_d(ic_vec3 h, float alpha)
{
    if (h.z <= 0.0f)
        return 0.0f;
    float a2 = alpha * alpha, c2 = h.z * h.z;
    float t = c2 * (a2 - 1.0f) + 1.0f;
    return a2 / (IC_PI * t * t);
}

float ic_ggx_lambda(ic_vec3 w, float alpha)
{
    float c2 = w.z * w.z;
    if (c2 <= 0.0f)
        return INFINITY;
    float tan2 = fmaxf(1.0f - c2, 0.0f) / c2;
    return 0.5f * (sqrtf(1.0f + alpha * alpha * tan2) - 1.0f);
}

ic_vec3 ic_ggx_sample_visible(ic_vec3 wo, float alpha, float u1, float u2)
{
    /* the view direction in the hemisphere configuration (roughness 1) */
    ic_vec3 vh = v3_norm(v3(alpha * wo.x, alpha * wo.y, wo.z));
    float len2 = vh.x * vh.x + vh.y * vh.y;
    ic_vec3 t1 = len2 > 0.0f ? v3_scale(v3(-vh.y, vh.x, 0.0f), 1.0f / sqrtf(len2)) : v3(1.0f, 0.0f, 0.0f);
    ic_vec3 t2 = v3_cross(vh, t1);
    /* a point on the projected disk, squeezed towards the visible half */
    float r = sqrtf(u1), phi = 2.0f * IC_PI * u2;
    float p1 = r * cosf(phi), p2 = r * sinf(phi);
    float s = 0.5f * (1.0f + vh.z);
    p2 = (1.0f - s) * sqrtf(fmaxf(0.0f, 1.0f - p1 * p1)) + s * p2;
    ic_vec3 nh = v3_add(v3_add(v3_scale(t1, p1), v3_scale(t2, p2)),
                        v3_scale(vh, sqrtf(fmaxf(0.0f, 1.0f - p1 * p1 - p2 * p2))));
    /* back to the ellipsoid configuration */
    return v3_norm(v3(alpha * nh.x, alpha * nh.y, fmaxf(1e-6f, nh.z)));
}

float ic_ggx_reflect_pdf(ic_vec3 wo, ic_vec3 wi, float alpha)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f)
        return 0.0f;
    ic_vec3 h = v3_norm(v3_add(wo, wi));
    return ic_ggx_g1(wo, alpha) * ic_ggx_d(h, alpha) / (4.0f * wo.z);
}

float ic_fresnel_dielectric(float cos_i, float eta)
{
    cos_i = ic_clampf(cos_i, -1.0f, 1.0f);
    if (cos_i < 0.0f) {
        eta = 1.0f / eta;
        cos_i = -cos_i;
    }
    float sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0f)
        return 1.0f; /* total internal reflection */
    float cos_t = sqrtf(1.0f - sin2_t);
    float rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    float rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    return 0.5f * (rs * rs + rp * rp);
}

/* One channel of the conductor formula (e.g. Born & Wolf; the form with a² + b² of the complex
 * refraction). */
static float fresnel_conductor1(float c, float eta, float k)
{
    float c2 = c * c, s2 = 1.0f - c2;
    float t0 = eta * eta - k * k - s2;
    float a2b2 = sqrtf(fmaxf(t0 * t0 + 4.0f * eta * eta * k * k, 0.0f));
    float a = sqrtf(fmaxf(0.5f * (a2b2 + t0), 0.0f));
    float rs = (a2b2 + c2 - 2.0f * a * c) / (a2b2 + c2 + 2.0f * a * c);
    float t1 = c2 * a2b2 + s2 * s2, t2 = 2.0f * a * c * s2;
    float rp = rs * (t1 - t2) / (t1 + t2);
    return 0.5f * (rs + rp);
}

ic_vec3 ic_fresnel_conductor(float cos_i, ic_vec3 eta, ic_vec3 k)
{
    float c = ic_clampf(cos_i, 0.0f, 1.0f);
    return v3(fresnel_conductor1(c, eta.x, k.x), fresnel_conductor1(c, eta.y, k.y), fresnel_conductor1(c, eta.z, k.z));
}

void ic_coat_albedo_table(float eta, float alpha, float table[IC_COAT_TABLE], float *average)
{
    enum { STRATA = 48 };
    alpha = fmaxf(alpha, IC_GGX_ALPHA_MIN);
    for (int j = 0; j < IC_COAT_TABLE; ++j) {
        /* nodes uniform in √μ: E(μ) rises from its grazing limit over μ ≈ α (shadowing) while Fresnel falls
         * from 1, both too steep for uniform steps in μ when α is small */
        float u = (float)j / (IC_COAT_TABLE - 1), mu = fmaxf(u * u, 1e-3f);
        ic_vec3 wo = v3(sqrtf(1.0f - mu * mu), 0.0f, mu);
        /* E = E_h[F(wo·h)·G2/G1(wo)] with h from the visible normals (its sampling weight) */
        double sum = 0.0;
        for (int a = 0; a < STRATA; ++a)
            for (int b = 0; b < STRATA; ++b) {
                ic_vec3 h = ic_ggx_sample_visible(wo, alpha, (a + 0.5f) / STRATA, (b + 0.5f) / STRATA);
                ic_vec3 wi = v3_reflect(wo, h);
                if (wi.z <= 0.0f)
                    continue;
                sum += ic_fresnel_dielectric(v3_dot(wo, h), eta) * ic_ggx_g2(wo, wi, alpha) / ic_ggx_g1(wo, alpha);
            }
        table[j] = (float)(sum / (STRATA * STRATA));
    }
    /* 2∫E(μ)μ dμ of the interpolated table, by the midpoint rule on a fine grid */
    enum { STEPS = 1024 };
    double avg = 0.0;
    for (int i = 0; i < STEPS; ++i) {
        float mu = (i + 0.5f) / STEPS;
        avg += 2.0 * ic_coat_albedo(table, mu) * mu / STEPS;
    }
    *average = (float)avg;
}

float ic_coat_albedo(const float table[IC_COAT_TABLE], float mu)
{
    float x = sqrtf(ic_clampf(mu, 0.0f, 1.0f)) * (IC_COAT_TABLE - 1);
    int i = (int)x;
    if (i >= IC_COAT_TABLE - 1)
        return table[IC_COAT_TABLE - 1];
    float t = x - (float)i;
    return table[i] + (table[i + 1] - table[i]) * t;
}
