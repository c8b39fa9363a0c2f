/*
 * test_sampling.c — every warp in core/sampling.h: inversion (warp(inverse(x)) = x), the pdf
 * integrates to 1 over its domain (numerical quadrature), and the samples' distribution agrees with
 * the pdf (analytic cumulative probability of z > c); the sun-sized cone separately. Plus frames and the counter-based RNG.
 */
#include "test_util.h"

#include "core/rng.h"
#include "core/sampling.h"

#include <string.h>

typedef ic_vec3 (*warp_fn)(float, float, float);
typedef float (*pdf_fn)(ic_vec3, float);
typedef void (*inv_fn)(ic_vec3, float, float *, float *);

static ic_vec3 w_cos(float a, float b, float e) { (void)e; return ic_warp_cosine_hemisphere(a, b); }
static float p_cos(ic_vec3 d, float e) { (void)e; return ic_warp_cosine_hemisphere_pdf(d); }
static void i_cos(ic_vec3 d, float e, float *a, float *b) { (void)e; ic_warp_cosine_hemisphere_inv(d, a, b); }
static ic_vec3 w_uh(float a, float b, float e) { (void)e; return ic_warp_uniform_hemisphere(a, b); }
static float p_uh(ic_vec3 d, float e) { (void)e; return ic_warp_uniform_hemisphere_pdf(d); }
static void i_uh(ic_vec3 d, float e, float *a, float *b) { (void)e; ic_warp_uniform_hemisphere_inv(d, a, b); }
static ic_vec3 w_us(float a, float b, float e) { (void)e; return ic_warp_uniform_sphere(a, b); }
static float p_us(ic_vec3 d, float e) { (void)e; return ic_warp_uniform_sphere_pdf(d); }
static void i_us(ic_vec3 d, float e, float *a, float *b) { (void)e; ic_warp_uniform_sphere_inv(d, a, b); }
static ic_vec3 w_ph(float a, float b, float e) { return ic_warp_phong_lobe(a, b, e); }
static float p_ph(ic_vec3 d, float e) { return ic_warp_phong_lobe_pdf(d, e); }
static void i_ph(ic_vec3 d, float e, float *a, float *b) { ic_warp_phong_lobe_inv(d, e, a, b); }
static ic_vec3 w_cone(float a, float b, float e) { return ic_warp_uniform_cone(a, b, e); }
static float p_cone(ic_vec3 d, float e) { return ic_warp_uniform_cone_pdf(d, e); }
static void i_cone(ic_vec3 d, float e, float *a, float *b) { ic_warp_uniform_cone_inv(d, e, a, b); }

/* P(z > c) for each warp, analytically. */
static double cdf_cos(double c, double e) { (void)e; return c < 0 ? 1.0 : 1.0 - c * c; }
static double cdf_uh(double c, double e) { (void)e; return c < 0 ? 1.0 : 1.0 - c; }
static double cdf_us(double c, double e) { (void)e; return (1.0 - c) / 2.0; }
static double cdf_ph(double c, double e) { return c < 0 ? 1.0 : 1.0 - pow(c, e + 1.0); }
static double cdf_cone(double c, double e) { return c < 1.0 - e ? 1.0 : (1.0 - c) / e; }

typedef struct warp_case {
    const char *name;
    warp_fn warp;
    pdf_fn pdf;
    inv_fn inv;
    double (*cdf_z)(double, double);
    float param;
} warp_case;

static void check_warp(const warp_case *w)
{
    ic_rng rng = ic_rng_make(7, 1, 2, 3);
    /* Inversion. */
    double worst = 0.0;
    for (int i = 0; i < 100000; ++i) {
        float u1 = 0.001f + 0.998f * ic_rng_float(&rng), u2 = 0.001f + 0.998f * ic_rng_float(&rng);
        ic_vec3 d = w->warp(u1, u2, w->param);
        float a, b;
        w->inv(d, w->param, &a, &b);
        ic_vec3 d2 = w->warp(a, b, w->param);
        double e = v3_len(v3_sub(d, d2));
        if (e > worst)
            worst = e;
        if (i == 0)
            CHECK(fabsf(v3_len(d) - 1.0f) < 1e-5f, "%s: unit length", w->name);
    }
    CHECK(worst < 2e-4, "%s: warp(inverse(d)) = d, worst error %g", w->name, worst);
    /* pdf integrates to 1 over the sphere (midpoint quadrature in theta, phi). */
    const int nt = 4000, np = 64;
    double integral = 0.0;
    for (int i = 0; i < nt; ++i) {
        double th = (i + 0.5) * M_PI / nt;
        for (int j = 0; j < np; ++j) {
            double ph = (j + 0.5) * 2.0 * M_PI / np;
            ic_vec3 d = v3((float)(sin(th) * cos(ph)), (float)(sin(th) * sin(ph)), (float)cos(th));
            integral += w->pdf(d, w->param) * sin(th) * (M_PI / nt) * (2.0 * M_PI / np);
        }
    }
    CHECK_NEAR(integral, 1.0, 2e-3, w->name);
    /* Samples follow the pdf: P(z > c) matches the analytic value. */
    const int n = 200000;
    const double cs[3] = {-0.5, 0.3, 0.8};
    int above[3] = {0, 0, 0};
    for (int i = 0; i < n; ++i) {
        ic_vec3 d = w->warp(ic_rng_float(&rng), ic_rng_float(&rng), w->param);
        for (int k = 0; k < 3; ++k)
            above[k] += d.z > cs[k];
    }
    for (int k = 0; k < 3; ++k) {
        double p = w->cdf_z(cs[k], w->param), got = (double)above[k] / n;
        double sd = sqrt(p * (1 - p) / n) + 1e-9;
        CHECK(fabs(got - p) < 5.0 * sd + 1e-6, "%s: P(z > %g) = %g, expected %g", w->name, cs[k], got, p);
    }
}

/* The sun's cone (angular radius 0.2665°, 1 − cos ≈ 1.08e-5): too small for the quadrature above, so:
 * inversion in angle, every sample inside, the pdf times the cap's solid angle is 1, and the fraction of
 * samples within half the radius is a quarter (the cap's area grows as θ²). */
static void check_small_cone(void)
{
    double radius = 0.2665 * M_PI / 180.0, omc = 2.0 * sin(0.5 * radius) * sin(0.5 * radius);
    ic_rng rng = ic_rng_make(9, 4, 5, 6);
    double worst = 0.0;
    int outside = 0, within_half = 0, n = 100000;
    for (int i = 0; i < n; ++i) {
        float u1 = ic_rng_float(&rng), u2 = ic_rng_float(&rng), a, b;
        ic_vec3 d = ic_warp_uniform_cone(u1, u2, (float)omc);
        outside += !(ic_warp_uniform_cone_pdf(d, (float)omc) > 0.0f);
        double theta = asin(sqrt((double)d.x * d.x + (double)d.y * d.y));
        within_half += theta < 0.5 * radius;
        ic_warp_uniform_cone_inv(d, (float)omc, &a, &b);
        ic_vec3 d2 = ic_warp_uniform_cone(a, b, (float)omc);
        double e = v3_len(v3_sub(d, d2)) / radius;
        worst = e > worst ? e : worst;
    }
    CHECK(worst < 1e-3, "small cone: warp(inverse(d)) = d to %g of the radius", worst);
    CHECK(outside == 0, "small cone: every sample inside (%d outside)", outside);
    ic_vec3 axis = {0.0f, 0.0f, 1.0f};
    CHECK_NEAR(ic_warp_uniform_cone_pdf(axis, (float)omc) * 2.0 * M_PI * (1.0 - cos(radius)), 1.0, 1e-5,
               "small cone: pdf × solid angle = 1");
    double p = 0.25, got = (double)within_half / n;
    CHECK(fabs(got - p) < 5.0 * sqrt(p * (1 - p) / n), "small cone: %g of the samples within half the radius", got);
}

static void check_disk_and_triangle(void)
{
    ic_rng rng = ic_rng_make(9, 0, 0, 0);
    double worst = 0.0, worst_t = 0.0, mean_b1 = 0.0;
    for (int i = 0; i < 100000; ++i) {
        float u1 = ic_rng_float(&rng), u2 = ic_rng_float(&rng);
        ic_vec3 p = ic_warp_concentric_disk(u1, u2);
        CHECK(p.x * p.x + p.y * p.y <= 1.0f + 1e-6f, "disk point inside the unit disk");
        float a, b;
        ic_warp_concentric_disk_inv(p, &a, &b);
        worst = fmax(worst, fabs(a - u1) + fabs(b - u2));
        float b1, b2;
        ic_warp_triangle(u1, u2, &b1, &b2);
        CHECK(b1 >= 0 && b2 >= 0 && b1 + b2 <= 1.0f + 1e-6f, "barycentrics inside the triangle");
        ic_warp_triangle_inv(b1, b2, &a, &b);
        worst_t = fmax(worst_t, fabs(a - u1) + fabs(b - u2));
        mean_b1 += b1;
    }
    CHECK(worst < 1e-4, "concentric disk inverse, worst %g", worst);
    CHECK(worst_t < 1e-4, "triangle inverse, worst %g", worst_t);
    /* Uniform on a triangle: E[b1] = 1/3. */
    CHECK_NEAR(mean_b1 / 100000.0, 1.0 / 3.0, 3e-3, "triangle warp mean barycentric");
}

static void check_frames(void)
{
    ic_rng rng = ic_rng_make(3, 3, 3, 3);
    for (int i = 0; i < 10000; ++i) {
        ic_vec3 n = ic_warp_uniform_sphere(ic_rng_float(&rng), ic_rng_float(&rng));
        ic_frame f = ic_frame_from_normal(n);
        CHECK(fabsf(v3_dot(f.t, f.b)) < 1e-5f && fabsf(v3_dot(f.t, f.n)) < 1e-5f && fabsf(v3_dot(f.b, f.n)) < 1e-5f,
              "frame orthogonal");
        CHECK(v3_len(v3_sub(v3_cross(f.t, f.b), f.n)) < 1e-5f, "frame right-handed");
        ic_vec3 w = v3(0.3f, -0.2f, 0.9f);
        ic_vec3 back = ic_frame_to_local(&f, ic_frame_to_world(&f, w));
        CHECK(v3_len(v3_sub(back, w)) < 1e-5f, "to_local(to_world(w)) = w");
    }
}

static void check_rng(void)
{
    ic_rng a = ic_rng_make(42, 10, 20, 30), b = ic_rng_make(42, 10, 20, 30), c = ic_rng_make(42, 10, 21, 30);
    int same = 1, differ = 0;
    double sum = 0.0;
    for (int i = 0; i < 100000; ++i) {
        float x = ic_rng_float(&a), y = ic_rng_float(&b), z = ic_rng_float(&c);
        same &= x == y;
        differ += x != z;
        CHECK(x >= 0.0f && x < 1.0f, "float in [0,1)");
        sum += x;
    }
    CHECK(same, "same key, same stream");
    CHECK(differ > 99000, "different key, different stream (%d differ)", differ);
    CHECK_NEAR(sum / 100000.0, 0.5, 0.005, "uniform mean");
    /* Reproducible across runs: a fixed value pins the generator so cached references stay valid. */
    ic_rng r = ic_rng_make(1, 2, 3, 4);
    uint64_t first = ic_rng_u64(&r);
    ic_rng r2 = ic_rng_make(1, 2, 3, 4);
    CHECK(first == ic_rng_u64(&r2), "first draw reproducible");
    uint32_t counts[10] = {0};
    for (int i = 0; i < 100000; ++i)
        ++counts[ic_rng_below(&r, 10)];
    for (int k = 0; k < 10; ++k)
        CHECK(abs((int)counts[k] - 10000) < 500, "ic_rng_below bucket %d = %u", k, counts[k]);
}

/* The scrambled Sobol' pairs (rng.h): nets, uniformity, decorrelated pairs, lower variance. */
static void check_lds(void)
{
    /* Every power-of-two prefix of a pixel's sequence is a (0,k,2)-net: for each split of the unit
     * square into 2^a × 2^(k−a) equal boxes, every box holds exactly one of the first 2^k points. */
    for (uint64_t key = 1; key <= 5; ++key) {
        for (int k = 1; k <= 10; ++k) {
            uint32_t n = 1u << k;
            int ok = 1;
            for (int a = 0; a <= k && ok; ++a) {
                static unsigned char hits[1024];
                memset(hits, 0, n);
                for (uint32_t i = 0; i < n; ++i) {
                    float u, v;
                    ic_sobol2d(i, key * 7919u, &u, &v);
                    uint32_t cx = (uint32_t)(u * (float)(1u << a)), cy = (uint32_t)(v * (float)(1u << (k - a)));
                    ++hits[cx * (1u << (k - a)) + cy];
                }
                for (uint32_t c = 0; c < n; ++c)
                    ok &= hits[c] == 1;
            }
            CHECK(ok, "key %llu: first %u points form a (0,%d,2)-net", (unsigned long long)key, n, k);
        }
    }
    /* Scrambling makes each point uniform over keys: point 5's u and v fall evenly into 8 bins. */
    uint32_t bu[8] = {0}, bv[8] = {0};
    for (uint64_t key = 0; key < 16000; ++key) {
        float u, v;
        ic_sobol2d(5, key, &u, &v);
        ++bu[(int)(u * 8.0f)];
        ++bv[(int)(v * 8.0f)];
    }
    for (int b = 0; b < 8; ++b)
        CHECK(abs((int)bu[b] - 2000) < 200 && abs((int)bv[b] - 2000) < 200, "point 5 uniform over keys, bin %d: %u %u",
              b, bu[b], bv[b]);
    /* Pairs of one stream are decorrelated: the first and second pair's u over 256 samples. */
    double sxy = 0, sx = 0, sy = 0, sxx = 0, syy = 0;
    for (uint32_t i = 0; i < 256; ++i) {
        ic_rng r = ic_rng_make(9, 0, i, 0);
        ic_rng_enable_lds(&r, 12345, i);
        float u0, v0, u1, v1;
        ic_rng_2d(&r, &u0, &v0);
        ic_rng_2d(&r, &u1, &v1);
        sx += u0, sy += u1, sxx += (double)u0 * u0, syy += (double)u1 * u1, sxy += (double)u0 * u1;
    }
    double cov = sxy / 256 - sx / 256 * sy / 256;
    double corr = cov / sqrt((sxx / 256 - sx * sx / 65536) * (syy / 256 - sy * sy / 65536));
    CHECK(fabs(corr) < 0.2, "pairs 1 and 2 uncorrelated (r = %.3f)", corr);
    /* An unbiased and much less noisy estimator: the fraction of the unit square inside a disk of
     * radius 0.8 about the origin (π·0.64/4) from 64 points, over 2000 keys, against random points. */
    const double truth = IC_PI * 0.64 / 4.0;
    double mean_s = 0, mse_s = 0, mse_r = 0;
    for (uint64_t key = 0; key < 2000; ++key) {
        ic_rng rr = ic_rng_make(77, key, 0, 0);
        int in_s = 0, in_r = 0;
        for (uint32_t i = 0; i < 64; ++i) {
            float u, v;
            ic_sobol2d(i, key + 1000, &u, &v);
            in_s += u * u + v * v < 0.64f;
            u = ic_rng_float(&rr);
            v = ic_rng_float(&rr);
            in_r += u * u + v * v < 0.64f;
        }
        double es = in_s / 64.0, er = in_r / 64.0;
        mean_s += es / 2000.0;
        mse_s += (es - truth) * (es - truth) / 2000.0;
        mse_r += (er - truth) * (er - truth) / 2000.0;
    }
    CHECK_NEAR(mean_s, truth, 4.0 * sqrt(mse_s / 2000.0) + 1e-4, "Sobol' disk estimate unbiased");
    printf("disk from 64 points: Sobol MSE %.3g, random MSE %.3g, pair correlation %.3f\n", mse_s, mse_r, corr);
    CHECK(mse_s < 0.25 * mse_r, "Sobol' MSE %.3g below a quarter of random's %.3g", mse_s, mse_r);
    /* Beyond IC_RNG_LDS_PAIRS pairs, and without enabling, draws are the stream's random numbers. */
    ic_rng a = ic_rng_make(3, 1, 4, 1), b = a;
    float u, v;
    ic_rng_2d(&a, &u, &v);
    CHECK(u == ic_rng_float(&b) && v == ic_rng_float(&b), "disabled stream: pairs are plain draws");
    CHECK(ic_rng_1d(&a) == ic_rng_float(&b), "disabled stream: 1-D draws are plain draws");
    /* A discrete choice by ic_rng_1d over a pixel's 64 samples takes a branch of probability P
     * round(64 P) times, give or take one (each 1-D projection of the net is stratified), where
     * independent draws scatter binomially (standard deviation 1.7 samples at P = 0.05). */
    const float probs[] = {0.05f, 0.3f, 0.5f, 0.83f};
    int worst = 0;
    double spread_random = 0.0;
    for (uint64_t pixel = 0; pixel < 500; ++pixel) {
        for (size_t k = 0; k < sizeof probs / sizeof probs[0]; ++k) {
            int hits = 0, hits_r = 0;
            for (uint32_t i = 0; i < 64; ++i) {
                ic_rng r = ic_rng_make(5, pixel, i, 0);
                ic_rng_enable_lds(&r, ic_hash4(9, pixel, 0, 0), i);
                for (size_t skip = 0; skip < k; ++skip) /* a later dimension for each probability */
                    (void)ic_rng_1d(&r);
                hits += ic_rng_1d(&r) < probs[k];
                hits_r += ic_rng_float(&r) < probs[k];
            }
            int dev = abs(hits - (int)lroundf(64.0f * probs[k]));
            worst = dev > worst ? dev : worst;
            spread_random += (hits_r - 64.0 * probs[k]) * (hits_r - 64.0 * probs[k]) / 2000.0;
        }
    }
    printf("discrete choice over 64 samples: largest deviation %d (Sobol'), rms %.2f (random)\n", worst,
           sqrt(spread_random));
    CHECK(worst <= 1, "1-D choices stratified: off by %d samples", worst);
    CHECK(sqrt(spread_random) > 1.5, "independent draws scatter (rms %.2f)", sqrt(spread_random));
}

/* ic_sobol_dim1 against its definition: the XOR of the direction numbers v_k (v_0 = 2^31,
 * v_k = v_{k-1} xor v_{k-1} >> 1) over the index's set bits; bit reversal and ic_sobol2d against
 * theirs. */
static void check_sobol_dim1(void)
{
    uint64_t state = 0x1234567ULL;
    int mismatches = 0;
    for (uint32_t n = 0; n < 300000; ++n) {
        /* small indices in full, then random 32-bit ones */
        state = state * 6364136223846793005ULL + 1442695040888963407ULL;
        uint32_t i = n < 65536 ? n : (uint32_t)(state >> 32);
        uint32_t r = 0, v = 1u << 31;
        for (uint32_t j = i; j; j >>= 1, v ^= v >> 1)
            if (j & 1u)
                r ^= v;
        mismatches += ic_sobol_dim1(i) != r;
        /* bit reversal against a loop */
        uint32_t rev = 0;
        for (int b = 0; b < 32; ++b)
            rev |= ((i >> b) & 1u) << (31 - b);
        mismatches += ic_reverse_bits32(i) != rev;
        /* the scrambled pair against its definition (ic_sobol2d leaves out reversals that cancel) */
        uint64_t key = state ^ 0x9e3779b97f4a7c15ULL, h = ic_mix64(key);
        uint32_t si = ic_owen_scramble(i, (uint32_t)h);
        uint32_t sx = ic_owen_scramble(ic_reverse_bits32(si), (uint32_t)(h >> 32));
        uint32_t sy = ic_owen_scramble(ic_sobol_dim1(si), (uint32_t)ic_mix64(h ^ 0x5851f42d4c957f2dULL));
        float pu, pv;
        ic_sobol2d(i, key, &pu, &pv);
        mismatches += pu != (float)(sx >> 8) * (1.0f / 16777216.0f) || pv != (float)(sy >> 8) * (1.0f / 16777216.0f);
    }
    CHECK(mismatches == 0, "Sobol' dimension 1, bit reversal and scrambled pairs match their definitions (%d mismatches)", mismatches);
    CHECK(ic_sobol_dim1(1) == 0x80000000u && ic_sobol_dim1(2) == 0xc0000000u && ic_sobol_dim1(3) == 0x40000000u,
          "first points 1/2, 3/4, 1/4");
}

/* The power heuristic in [0, 1] with pdfs whose squares overflow a float (a small emitter far away gave
 * inf / inf = NaN, and NaN illuminance from `irrcache points`), and the same bits as a² / (a² + b²)
 * wherever those stay finite. */
static void check_power_heuristic(void)
{
    CHECK(ic_power_heuristic(2.0f, 1.0f) == 4.0f / 5.0f && ic_power_heuristic(0.0f, 0.0f) == 0.0f &&
              ic_power_heuristic(0.0f, 3.0f) == 0.0f && ic_power_heuristic(1e18f, 1e18f) == 0.5f,
          "finite squares: a^2 / (a^2 + b^2)");
    float big = ic_power_heuristic(1e20f, 1.0f), small = ic_power_heuristic(1.0f, 1e20f),
          even = ic_power_heuristic(3e38f, 3e38f), inf = ic_power_heuristic(INFINITY, 5.0f),
          nan = ic_power_heuristic(NAN, 1.0f);
    CHECK(big == 1.0f && small >= 0.0f && small < 1e-30f && even == 0.5f && inf == 1.0f && nan == 0.0f,
          "overflowing squares: %g %g %g %g %g (1, about 1e-40, 0.5, 1, 0)", big, small, even, inf, nan);
    CHECK(fabsf(ic_power_heuristic(3e19f, 2e19f) - 9.0f / 13.0f) < 1e-6f, "3e19 against 2e19: 9/13");
}

int main(void)
{
    check_power_heuristic();
    const warp_case cases[] = {
        {"cosine hemisphere", w_cos, p_cos, i_cos, cdf_cos, 0.0f},
        {"uniform hemisphere", w_uh, p_uh, i_uh, cdf_uh, 0.0f},
        {"uniform sphere", w_us, p_us, i_us, cdf_us, 0.0f},
        {"phong lobe n=1", w_ph, p_ph, i_ph, cdf_ph, 1.0f},
        {"phong lobe n=20", w_ph, p_ph, i_ph, cdf_ph, 20.0f},
        {"phong lobe n=500", w_ph, p_ph, i_ph, cdf_ph, 500.0f},
        {"cone 1 - cos = 0.3", w_cone, p_cone, i_cone, cdf_cone, 0.3f},
        {"cone 1 - cos = 1.5", w_cone, p_cone, i_cone, cdf_cone, 1.5f},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i)
        check_warp(&cases[i]);
    check_small_cone();
    check_disk_and_triangle();
    check_frames();
    check_rng();
    check_lds();
    check_sobol_dim1();
    TEST_MAIN_END();
}
