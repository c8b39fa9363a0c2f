/*
 * test_filter.c — the record filter (record noise control, ic_filter.c) on records with known values:
 *   1. constant irradiance plus independent noise of known σ: the filter cuts the records' error by
 *      more than 2× and keeps their mean;
 *   2. a step (1 beside 3) plus noise: no record moves towards the other side by more than a few σ
 *      (the spread across the step is far beyond the noise, so the records hardly move), and away from
 *      the edge the error falls as in 1;
 *   2b. right-skewed noise (rare bright records, as light through a gap gives): the filter keeps the
 *      records' mean (a robust mean would pull it down);
 *   3. a linear ramp with its true gradient: the filter, which extrapolates each neighbour with its own
 *      gradient, adds no bias and cuts the noise;
 *   4. records on two perpendicular walls meeting at a corner never mix;
 *   4b. a curved field (a real variation the gradients do not carry) with little noise: the records move
 *      by hardly more than their noise (the shrinkage sees the spread is not noise), where a plain mean
 *      over the neighbourhood would bias them by many σ;
 *   5. 1 and 2 threads give identical records;
 *   6. more neighbours than the filter's buffer: the nearest ones, whatever the insertion order.
 */
#include "test_util.h"

#include "core/rng.h"
#include "integrators/ic_internal.h"

#include <string.h>

#define GRID 40       /* records per side, spacing 0.1 */
#define SPACING 0.1f

typedef float (*truth_fn)(float x);

static float flat(float x) { (void)x; return 1.0f; }
static float step(float x) { return x < 2.0f ? 1.0f : 3.0f; }
static float ramp(float x) { return 1.0f + 0.5f * x; }
static float bowl(float x) { return 1.0f + 0.15f * (x - 2.0f) * (x - 2.0f); }

static double gauss(ic_rng *r)
{
    double u1 = ic_rng_float(r) + 1e-7, u2 = ic_rng_float(r);
    return sqrt(-2.0 * log(u1)) * cos(2.0 * IC_PI * u2);
}

/* A cache of GRID² records on the plane z = 0 (jittered grid), value truth(x) + N(0, σ) in every
 * channel, σ stored as the record's own noise estimate, radius fixed at 0.5 (a·R = 0.15). */
static int skewed_noise; /* make_cache: noise +9σ/3 with probability 0.1, −σ/3 otherwise (mean 0, std σ) */

/* The caches the filter is tested on: a = 0.3, every radius 0.5, no clamping (records keep their values). */
static ic_cache *empty_cache(void)
{
    ic_cache_params p = {0};
    p.accuracy = 0.3f;
    p.min_radius = 0.5f;
    p.max_radius = 0.5f;
    p.neighbor_clamp = IC_CACHE_OFF;
    p.validity_clamp = IC_CACHE_OFF;
    ic_cache *c = NULL;
    ic_error err;
    return ic_cache_create(&p, &c, &err) == IC_OK ? c : NULL;
}

static ic_cache *make_cache(truth_fn truth, float sigma, ic_vec3 gradient, uint64_t seed)
{
    ic_cache *c = empty_cache();
    ic_error err;
    if (!c)
        return NULL;
    ic_rng rng = ic_rng_make(seed, 1, 2, 3);
    for (int i = 0; i < GRID; ++i)
        for (int k = 0; k < GRID; ++k) {
            ic_record r;
            memset(&r, 0, sizeof r);
            float x = ((float)i + 0.2f + 0.6f * ic_rng_float(&rng)) * SPACING;
            float y = ((float)k + 0.2f + 0.6f * ic_rng_float(&rng)) * SPACING;
            float e = truth(x) + (skewed_noise ? (ic_rng_float(&rng) < 0.1f ? 3.0f * sigma : -sigma / 3.0f)
                                               : sigma * (float)gauss(&rng));
            r.position = v3(x, y, 0.0f);
            r.normal = v3(0.0f, 0.0f, 1.0f);
            r.irradiance = v3s(fmaxf(e, 0.0f));
            r.sigma = v3s(sigma);
            for (int ch = 0; ch < 3; ++ch)
                r.grad_trans[ch] = gradient;
            r.harmonic_mean_dist = 0.5f;
            if (ic_cache_insert(c, &r, NULL, &err) != IC_OK) {
                ic_cache_destroy(c);
                return NULL;
            }
        }
    return c;
}

/* RMS error of the records' red channel against truth, over records with |x − 2| ≥ margin; *mean gets
 * the mean signed error. */
static double rms_error(const ic_cache *c, truth_fn truth, float margin, double *mean)
{
    double s2 = 0.0, s = 0.0;
    uint32_t n = 0;
    for (uint32_t i = 0; i < ic_cache_count(c); ++i) {
        ic_record r;
        ic_cache_get_record(c, i, &r);
        if (fabsf(r.position.x - 2.0f) < margin)
            continue;
        double d = (double)r.irradiance.x - truth(r.position.x);
        s2 += d * d;
        s += d;
        ++n;
    }
    *mean = n ? s / n : 0.0;
    return n ? sqrt(s2 / n) : 0.0;
}

static void test_noise(const char *name, truth_fn truth, ic_vec3 gradient)
{
    const float sigma = 0.1f;
    ic_cache *c = make_cache(truth, sigma, gradient, 11);
    CHECK(c != NULL, "%s: cache built", name);
    if (!c)
        return;
    double bias0, bias1;
    double before = rms_error(c, truth, 0.0f, &bias0);
    ic_error err;
    CHECK(ic_ic_filter_cache(c, 2, NULL, IC_DEFAULT_RECORD_FILTER, &err) == IC_OK, "%s: filter runs", name);
    double after = rms_error(c, truth, 0.0f, &bias1);
    printf("%s: record error %.4f before, %.4f after (mean %+.4f, %+.4f)\n", name, before, after, bias0, bias1);
    CHECK(after < 0.5 * before, "%s: error %.4f not cut by 2x from %.4f", name, after, before);
    CHECK(fabs(bias1) < 0.01, "%s: filtered records biased by %+.4f", name, bias1);
    ic_cache_destroy(c);
}

static void test_skewed(void)
{
    skewed_noise = 1;
    ic_cache *c = make_cache(flat, 0.3f, v3s(0.0f), 15);
    skewed_noise = 0;
    CHECK(c != NULL, "skewed: cache built");
    if (!c)
        return;
    double before, after;
    rms_error(c, flat, 0.0f, &before);
    ic_error err;
    CHECK(ic_ic_filter_cache(c, 2, NULL, IC_DEFAULT_RECORD_FILTER, &err) == IC_OK, "skewed: filter runs");
    double rms = rms_error(c, flat, 0.0f, &after);
    printf("skewed: mean error %+.4f before, %+.4f after (rms after %.4f)\n", before, after, rms);
    CHECK(fabs(after - before) < 0.01, "skewed: the filter moved the records' mean by %+.4f", after - before);
    ic_cache_destroy(c);
}

static void test_step(void)
{
    const float sigma = 0.05f;
    ic_cache *c = make_cache(step, sigma, v3s(0.0f), 12);
    CHECK(c != NULL, "step: cache built");
    if (!c)
        return;
    double bias, before = rms_error(c, step, 0.3f, &bias);
    ic_error err;
    CHECK(ic_ic_filter_cache(c, 2, NULL, IC_DEFAULT_RECORD_FILTER, &err) == IC_OK, "step: filter runs");
    double worst = 0.0;
    for (uint32_t i = 0; i < ic_cache_count(c); ++i) {
        ic_record r;
        ic_cache_get_record(c, i, &r);
        worst = fmax(worst, fabs((double)r.irradiance.x - step(r.position.x)));
    }
    double after = rms_error(c, step, 0.3f, &bias);
    printf("step: worst record %.4f off its side (step 2, sigma %.2f); away from it %.4f -> %.4f\n", worst,
           (double)sigma, before, after);
    CHECK(worst < 6.0 * sigma, "step: a record moved %.4f towards the other side", worst);
    CHECK(after < 0.5 * before, "step: error away from the edge %.4f not cut by 2x from %.4f", after, before);
    ic_cache_destroy(c);
}

static void test_corner(void)
{
    ic_cache_params p = {0};
    p.accuracy = 0.3f;
    p.min_radius = 0.5f;
    p.max_radius = 0.5f;
    ic_cache *c = NULL;
    ic_error err;
    CHECK(ic_cache_create(&p, &c, &err) == IC_OK, "corner: cache");
    /* Floor z = 0 (E = 1) and wall x = 0 (E = 5), records 0.05 from the corner line. */
    for (int i = 0; i < 20; ++i) {
        ic_record r;
        memset(&r, 0, sizeof r);
        float t = 0.05f * (float)(i % 10) + 0.05f, y = 0.1f * (float)(i / 10);
        int wall = i & 1;
        r.position = wall ? v3(0.0f, y, t) : v3(t, y, 0.0f);
        r.normal = wall ? v3(1.0f, 0.0f, 0.0f) : v3(0.0f, 0.0f, 1.0f);
        r.irradiance = v3s(wall ? 5.0f : 1.0f);
        r.sigma = v3s(2.0f); /* noise so large the biweight alone would not tell them apart */
        r.harmonic_mean_dist = 0.5f;
        ic_cache_insert(c, &r, NULL, &err);
    }
    CHECK(ic_ic_filter_cache(c, 1, NULL, IC_DEFAULT_RECORD_FILTER, &err) == IC_OK, "corner: filter runs");
    int mixed = 0;
    for (uint32_t i = 0; i < ic_cache_count(c); ++i) {
        ic_record r;
        ic_cache_get_record(c, i, &r);
        float want = r.normal.x > 0.5f ? 5.0f : 1.0f;
        mixed += fabsf(r.irradiance.x - want) > 1e-4f;
    }
    CHECK(mixed == 0, "corner: %d records took light from the other wall", mixed);
    ic_cache_destroy(c);
}

static void test_curved(void)
{
    const float sigma = 0.01f;
    ic_cache *c = make_cache(bowl, sigma, v3s(0.0f), 14);
    CHECK(c != NULL, "curved: cache built");
    if (!c)
        return;
    double bias, before = rms_error(c, bowl, 0.0f, &bias);
    ic_error err;
    CHECK(ic_ic_filter_cache(c, 2, NULL, IC_DEFAULT_RECORD_FILTER, &err) == IC_OK, "curved: filter runs");
    double after = rms_error(c, bowl, 0.0f, &bias);
    printf("curved: record error %.4f before, %.4f after (sigma %.2f)\n", before, after, (double)sigma);
    CHECK(after < 1.3 * before, "curved: the filter biased the records: error %.4f from %.4f", after, before);
    ic_cache_destroy(c);
}

static void test_threads(void)
{
    ic_cache *a = make_cache(step, 0.1f, v3s(0.0f), 13), *b = make_cache(step, 0.1f, v3s(0.0f), 13);
    ic_error err;
    CHECK(a && b, "threads: caches built");
    if (!a || !b)
        return;
    ic_ic_filter_cache(a, 1, NULL, IC_DEFAULT_RECORD_FILTER, &err);
    ic_ic_filter_cache(b, 2, NULL, IC_DEFAULT_RECORD_FILTER, &err);
    int same = 1;
    for (uint32_t i = 0; i < ic_cache_count(a); ++i) {
        ic_record x, y;
        ic_cache_get_record(a, i, &x);
        ic_cache_get_record(b, i, &y);
        same &= memcmp(&x.irradiance, &y.irradiance, sizeof x.irradiance) == 0 &&
                memcmp(x.grad_trans, y.grad_trans, sizeof x.grad_trans) == 0;
    }
    CHECK(same, "threads: 1 and 2 threads filter identically");
    ic_cache_destroy(a);
    ic_cache_destroy(b);
}

/* 6. More neighbours than the filter's buffer (600 noisy records within one record's reach): it takes the
 * nearest ones, so the result does not depend on the order the records were inserted in (the octree's order
 * decided which 256 it saw before). */
static ic_cache *dense_cache(int reversed)
{
    enum { N = 600 };
    static ic_record recs[N];
    ic_rng rng = ic_rng_make(21, 1, 2, 3);
    for (int i = 0; i < N; ++i) {
        ic_record *r = &recs[i];
        memset(r, 0, sizeof *r);
        r->position = v3(0.5f * ic_rng_float(&rng), 0.5f * ic_rng_float(&rng), 0.0f);
        r->normal = v3(0.0f, 0.0f, 1.0f);
        r->irradiance = v3s(fmaxf(1.0f + 0.2f * (float)gauss(&rng), 0.0f));
        r->sigma = v3s(0.2f);
        r->harmonic_mean_dist = 0.5f;
    }
    ic_cache *c = empty_cache();
    ic_error err;
    if (!c)
        return NULL;
    for (int i = 0; i < N; ++i)
        if (ic_cache_insert(c, &recs[reversed ? N - 1 - i : i], NULL, &err) != IC_OK) {
            ic_cache_destroy(c);
            return NULL;
        }
    return c;
}

static void test_dense(void)
{
    ic_cache *a = dense_cache(0), *b = dense_cache(1);
    ic_error err;
    CHECK(a && b, "dense: caches built");
    if (!a || !b)
        return;
    CHECK(ic_ic_filter_cache(a, 2, NULL, IC_DEFAULT_RECORD_FILTER, &err) == IC_OK &&
              ic_ic_filter_cache(b, 2, NULL, IC_DEFAULT_RECORD_FILTER, &err) == IC_OK,
          "dense: filter runs");
    const uint32_t n = ic_cache_count(a);
    uint32_t differ = 0, moved = 0;
    for (uint32_t i = 0; i < n && n == ic_cache_count(b); ++i) {
        ic_record x, y;
        ic_cache_get_record(a, i, &x);
        ic_cache_get_record(b, n - 1 - i, &y);
        differ += memcmp(&x.irradiance, &y.irradiance, sizeof x.irradiance) != 0;
        moved += fabsf(x.irradiance.x - 1.0f) < 0.05f;
    }
    printf("dense: %u of %u records filtered differently when inserted in reverse; %u within 0.05 of the truth\n",
           differ, n, moved);
    CHECK(n == 600 && differ == 0, "dense: the filtered records do not depend on the insertion order (%u of %u "
          "differ)", differ, n);
    CHECK(moved > n / 2, "dense: the filter still pulls the records to the truth (%u of %u within 0.05)", moved, n);
    ic_cache_destroy(a);
    ic_cache_destroy(b);
}

int main(void)
{
    test_dense();
    test_noise("flat", flat, v3s(0.0f));
    test_noise("ramp", ramp, v3(0.5f, 0.0f, 0.0f));
    test_skewed();
    test_step();
    test_corner();
    test_curved();
    test_threads();
    TEST_MAIN_END();
}
