/*
 * ic_light_samples.c — light samples a record adds to its hemisphere rays' estimate: the environment
 * through portals (IC_ENV_PORTAL_SAMPLES), and the cached large emitters, whose light the rays also
 * count under the balance heuristic (ic_gathering.c, cached_ray_weight).
 */
#include "ic_internal.h"

#include <stdatomic.h>

/* Running sums of a point's light samples, per channel. */
typedef struct light_sums {
    double sum[3], sum2[3];
} light_sums;

static void light_sums_add(light_sums *s, ic_vec3 e)
{
    const double v[3] = {e.x, e.y, e.z};
    for (int ch = 0; ch < 3; ++ch) {
        s->sum[ch] += v[ch];
        s->sum2[ch] += v[ch] * v[ch];
    }
}

/* Adds times × the mean of the n samples in s to out's irradiance and to every level (light that reaches
 * the point directly is level 0 and up), and its σ to out's σ in quadrature; counts the n shadow rays. */
static void add_light_estimate(ic_ctx *c, const light_sums *s, int n, float times, ic_gather_result *out,
                               ic_vec3 *levels)
{
    atomic_fetch_add_explicit(&c->rays, (uint64_t)n, memory_order_relaxed);
    float mean[3], sigma[3];
    for (int ch = 0; ch < 3; ++ch) {
        double m = s->sum[ch] / n, var = n > 1 ? (s->sum2[ch] - n * m * m) / (n - 1) : 0.0;
        mean[ch] = (float)m * times;
        sigma[ch] = (float)sqrt(fmax(var, 0.0) / n) * times;
    }
    ic_vec3 E = v3(mean[0], mean[1], mean[2]);
    out->irradiance = v3_add(out->irradiance, E);
    out->sigma = v3(sqrtf(out->sigma.x * out->sigma.x + sigma[0] * sigma[0]),
                    sqrtf(out->sigma.y * out->sigma.y + sigma[1] * sigma[1]),
                    sqrtf(out->sigma.z * out->sigma.z + sigma[2] * sigma[2]));
    for (int k = 0; levels && k <= c->levels; ++k)
        levels[k] = v3_add(levels[k], E);
}

#define STREAM_PORTAL 0x706f7274616cULL /* rng purpose: a record's light samples through portals */
/* A record's light samples through portals: one per PORTAL_SAMPLES_DIV of its rays, at least
 * PORTAL_SAMPLES_MIN. The sensors' hit records (50 rays at the sensors' 3,200) had the same error with 8
 * samples as with 50 (BENCHMARKS.md, "Sensor points"): their error is their indirect light's. */
#define PORTAL_SAMPLES_DIV 8u
#define PORTAL_SAMPLES_MIN 8

/* IC_ENV_PORTAL_SAMPLES: the environment's irradiance through the portals pt lies inside of, from light
 * samples uniform in the openings' solid angle (randomised Sobol' pairs keyed by the record), added to
 * the record's irradiance, its bounce levels (the environment's own light is level 0) and, in
 * quadrature, its σ. Its gradients stay the rays' (the light through the openings has none). */
void ic_ic_add_portal_light(ic_ctx *c, const ic_gather_point *pt, ic_gather_result *out, ic_vec3 *levels)
{
    const ic_scene *scene = c->gather_tr.scene;
    if (!scene->env.enabled || !scene->env.portal_count || !ic_scene_portals_apply(scene, pt->position))
        return;
    int n = (int)(out->ray_count / PORTAL_SAMPLES_DIV);
    if (n < PORTAL_SAMPLES_MIN)
        n = PORTAL_SAMPLES_MIN;
    light_sums ls = {{0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}};
    uint64_t key = ic_hash4(c->seed, pt->key, STREAM_PORTAL, 0);
    for (int k = 0; k < n; ++k) {
        ic_rng rng = ic_rng_make(c->seed, pt->key, (uint64_t)k, STREAM_PORTAL);
        ic_rng_enable_lds(&rng, key, (uint32_t)k);
        float u0 = ic_rng_1d(&rng), u1, u2;
        ic_rng_2d(&rng, &u1, &u2);
        ic_vec3 wi, q;
        float pdf;
        if (!ic_scene_sample_portal(scene, pt->position, u0, u1, u2, &wi, &q, &pdf) || !(pdf > 0.0f))
            continue;
        float cos_i = v3_dot(wi, pt->normal);
        if (cos_i <= 0.0f)
            continue;
        ic_ray shadow = {pt->position, wi, 0.0f, INFINITY};
        if (ic_accel_occluded1(c->gather_tr.accel, &shadow))
            continue;
        light_sums_add(&ls, v3_scale(ic_scene_env_radiance(scene, wi), cos_i / pdf));
    }
    add_light_estimate(c, &ls, n, 1.0f, out, levels);
}

#define STREAM_EMITTER 0x656d6974ULL /* rng purpose: a record's light samples of the cached emitters */
/* A record's light samples of the cached emitters: one per EMITTER_SAMPLES_DIV of its rays, at least
 * EMITTER_SAMPLES_MIN. On staircase2 (448×252, six seeds) one per 16 rays left 7 % less low-pass error
 * than one per 8 with fewer rays, and one per 4 or 32 more (BENCHMARKS.md): the fewer the light
 * samples, the more of the emitter's light the rays keep, and with it their gradients. */
#define EMITTER_SAMPLES_DIV 16u
#define EMITTER_SAMPLES_MIN 8

uint32_t ic_ic_emitter_light_samples(uint32_t rays)
{
    uint32_t n = rays / EMITTER_SAMPLES_DIV;
    return n < EMITTER_SAMPLES_MIN ? EMITTER_SAMPLES_MIN : n;
}

/* With emitter_mis: the cached emitters' direct light at pt from n_l light samples (the scene's light
 * sampling restricted to them: a triangle by power among them, a point on it by area), each weighted by the balance heuristic against the point's n_r
 * hemisphere rays, which count their hits on those emitters with the complementary weight
 * (ic_gathering.c, cached_ray_weight): E = Σ_j Le_j cos θ_j / (n_r p_r(ω_j) + n_l p_l(ω_j)). The light
 * samples find an emitter that a record's rays would hit in a few cells, or that a hit record's few hundred would
 * hit by chance (a window seen past balusters); the sum joins the record's irradiance, its levels (the
 * emitters' own light is level 0) and, in quadrature, its σ. Its gradients stay the rays' (which now
 * carry only their weighted share of the emitters' light). */
ic_light_selection ic_ic_cached_selection(const ic_ctx *c)
{
    ic_light_selection sel = {1.0f, 0.0f, 0.0f, 0.0f, c->cached_cdf, c->cached_pmf};
    return sel;
}

void ic_ic_add_cached_emitter_light(ic_gather_worker *w, const ic_gather_point *pt, ic_gather_result *out,
                                    ic_vec3 *levels)
{
    ic_ctx *c = w->c;
    const ic_scene *scene = c->gather_tr.scene;
    const ic_light_selection sel = ic_ic_cached_selection(c);
    const uint32_t n = (uint32_t)w->mis_lights;
    light_sums ls = {{0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}};
    uint64_t key = ic_hash4(c->seed, pt->key, STREAM_EMITTER, 0);
    for (uint32_t k = 0; k < n; ++k) {
        ic_rng rng = ic_rng_make(c->seed, pt->key, (uint64_t)k, STREAM_EMITTER);
        ic_rng_enable_lds(&rng, key, k);
        float u0 = ic_rng_1d(&rng), u1, u2;
        ic_rng_2d(&rng, &u1, &u2);
        ic_light_sample l;
        if (!ic_scene_sample_light_sel(scene, &sel, pt->position, u0, u1, u2, &l))
            continue;
        float cos_p = v3_dot(l.wi, pt->normal);
        if (cos_p <= 0.0f)
            continue;
        ic_ray shadow = {pt->position, l.wi, 0.0f, l.dist * (1.0f - 1e-3f)};
        if (ic_accel_occluded1(c->gather_tr.accel, &shadow))
            continue;
        float pr = w->mis_rays * cos_p / IC_PI, pl = w->mis_lights * l.pdf;
        light_sums_add(&ls, v3_scale(l.radiance, cos_p / (pr + pl)));
    }
    /* The estimate is the samples' sum (each is weighted for all n together): n times their mean. */
    add_light_estimate(c, &ls, (int)n, (float)n, out, levels);
}
