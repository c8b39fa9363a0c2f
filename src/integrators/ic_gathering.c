/*
 * ic_gathering.c — what a record's hemisphere rays return (the trace callback of ic_gather_batch, with
 * Ward's multiple-bounce look-ups at diffuse hits and large emitters' light), and turning gather results
 * into records: candidates, gather points, parallel gathering and one-batch insertion.
 */
#include "ic_internal.h"

#include "core/grow.h"
#include "core/threads.h"

#include <stdatomic.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

/* 1 if emitting triangle tri is a large emitter whose light the records carry (ic_ic_select_large_emitters). */
static int emitter_is_cached(const ic_ctx *c, uint32_t tri)
{
    if (!c->direct_pmf || tri >= c->tr->scene->triangle_count)
        return 0;
    int32_t li = c->tr->scene->triangle_light[tri];
    return li >= 0 && !(c->direct_pmf[li] > 0.0f);
}

/* The balance heuristic's weight of a hemisphere ray's hit on a cached emitter against the point's light
 * samples of them (ic_light_samples.c; Veach 1997 §9.2, with n_r cosine-distributed rays and n_l light
 * samples). */
static float cached_ray_weight(const ic_gather_worker *w, const ic_ray *ray, const ic_hit *hit)
{
    const ic_ctx *c = w->c;
    if (!(w->mis_lights > 0.0f))
        return 1.0f;
    float cos_p = v3_dot(ray->dir, w->pt->normal), pr = w->mis_rays * fmaxf(cos_p, 0.0f) / IC_PI;
    const ic_light_selection sel = ic_ic_cached_selection(c);
    float pl = w->mis_lights * ic_scene_light_pdf_triangle_sel(c->tr->scene, &sel, ray->org, hit->triangle, ray->dir,
                                                                hit->t);
    return pr + pl > 0.0f ? pr / (pr + pl) : 0.0f;
}

/* What a hemisphere ray adds for its hit besides the light reflected there: the emission of a large
 * emitter, which is direct light the records carry (zero for any other surface). */
ic_vec3 ic_ic_cached_emission(const ic_ctx *c, const ic_ray *ray, const ic_hit *hit)
{
    if (!emitter_is_cached(c, hit->triangle))
        return v3s(0.0f);
    ic_surface s;
    ic_scene_surface(c->tr->scene, hit->triangle, hit->u, hit->v, &s);
    return ic_scene_emission(c->tr->scene, &s, v3_neg(ray->dir));
}

int ic_ic_level_estimates(const ic_ctx *c, const ic_cache_contribution *contrib, uint32_t count, int first,
                          int levels, ic_vec3 *E, ic_vec3 *last_terms)
{
    const int B = c->levels;
    for (int k = 0; k < levels; ++k)
        E[k] = v3s(0.0f);
    /* Over the contributions read back (all but in a pile-up of more than LOOKUP_CAPACITY records,
     * where the first ones written stand for the rest, normalised by their own weights). */
    float wsum = 0.0f;
    for (uint32_t i = 0; i < count; ++i) {
        const ic_cache_contribution *ct = &contrib[i];
        if (ct->record >= c->level_records)
            return 0;
        const ic_vec3 *T = &c->level_irr[(size_t)ct->record * (size_t)(B + 1)];
        /* w·E_i(p)/E_i per channel once, then times each level's T_k. */
        const ic_vec3 tb = T[B];
        const ic_vec3 scale = v3(tb.x > 0.0f ? ct->weight * ct->value.x / tb.x : 0.0f,
                                 tb.y > 0.0f ? ct->weight * ct->value.y / tb.y : 0.0f,
                                 tb.z > 0.0f ? ct->weight * ct->value.z / tb.z : 0.0f);
        for (int k = 0; k < levels; ++k)
            E[k] = v3_add(E[k], v3_mul(scale, T[first + k]));
        if (last_terms)
            last_terms[i] = v3_mul(scale, T[first + levels - 1]);
        wsum += ct->weight;
    }
    float inv = wsum > 0.0f ? 1.0f / wsum : 0.0f;
    for (int k = 0; k < levels; ++k)
        E[k] = v3_scale(E[k], inv);
    for (uint32_t i = 0; last_terms && i < count; ++i)
        last_terms[i] = v3_scale(last_terms[i], inv);
    return 1;
}

/* Radiance leaving a hemisphere ray's hit towards the record, with the cache standing in for the
 * bounces after the hit: kd/π · E(hit) from the records already made, plus the hit's direct light from
 * the lights the final render samples (records hold none of it; ic_ic_direct_light_at_hit). This is
 * Ward's multiple-bounce scheme (the ambient value of a point is its records' interpolation, Radiance's
 * -ab) inside the batch passes: a pass's records serve the next passes' rays,
 * and the world-space stage puts records where these rays land (Frolov et al. 2012 §3.1.3), which is
 * what makes the look-ups hit; it cuts record cost, which Frolov et al. 2012 §4.6 measures as most of
 * the construction time. A hit with a glossy lobe beside its diffuse one takes the records for the
 * diffuse lobe and traces the glossy lobe on (add_glossy_lobe); a glossy or specular surface without a
 * diffuse lobe is not read. Returns 0 where no record reaches, and the caller path-traces. Deterministic:
 * within a pass the cache is read-only.
 *
 * The bounce count stays exact: the records met here hold B bounces of their own, and a ray of a record
 * that is to hold B bounces may take only B − 1 of them. Each record keeps its irradiance split by level
 * (T_k, ic_ctx.level_irr), and the look-up reads the interpolation of T_{k−1} for every level k the
 * ray reports: each contributor's gradient-extrapolated value scaled per channel by its T_{k−1}/E_i, the
 * same weights as the full estimate. cum[k] (k = 1…levels) gets the light of at most k bounces after
 * the point looked up; at a first hit (levels = B) cum[B] is what the ray returns. read_records does it
 * at surface s; hit_from_cache makes the hit's surface and BSDF in the caller's *s and *b, which the
 * path that the caller traces when it returns 0 reuses. */
static int later_from_cache(void *user, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo, int remaining,
                            ic_rng *rng, uint64_t *rays, ic_vec3 *inc);

/* The glossy lobe of a vertex whose diffuse lobe the records serve (read_records), added to cum[k], k =
 * 1 … levels: its share of a light sample (the path tracer's selection, MIS-weighted against the lobe's
 * own sample), then the lobe's sample, path traced on, its later vertices reading the records
 * (later_from_cache). Light found j events after the vertex's reflection counts from cum[j + 1] up. This
 * is the path tracer's own estimate restricted to the glossy lobe, so its weights stay consistent along
 * the path; only the diffuse lobe's sampled direction is replaced by the records. The lobe is traced
 * with the probability p that the BSDF's own sampling gives it, its light weighted 1/p: traced every
 * time, it cost staircase2 (k_d up to 1 beside k_s 0.04 on the wood and tiles) 6–9 % more time for 2–4 %
 * less low-pass error; at p, 1–5 % less with 3–5 % fewer rays (BENCHMARKS.md, "A glossy hit's diffuse
 * lobe from the records"). */
static void add_glossy_lobe(const ic_ctx *c, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo, int levels,
                            ic_rng *rng, uint64_t *rays, ic_vec3 *cum)
{
    const ic_tracer *tr = &c->gather_tr;
    const float p = b->p_diffuse < 1.0f ? 1.0f - b->p_diffuse : 1.0f;
    if (ic_rng_1d(rng) >= p)
        return;
    const float inv_p = 1.0f / p;
    ic_vec3 direct = v3_scale(ic_direct_light_glossy(tr, s, b, wo, &tr->scene->light_select, rng, rays), inv_p);
    float u1, u2;
    ic_rng_2d(rng, &u1, &u2);
    ic_vec3 by_events[IC_LEVELS_MAX + 1], weight = v3s(0.0f);
    for (int k = 0; k < levels; ++k)
        by_events[k] = v3s(0.0f);
    ic_bsdf_sample bs;
    if (ic_bsdf_sample_glossy(b, wo, u1, u2, &bs)) {
        ic_path_start st = {tr->pt.max_depth - levels + 1, bs.pdf, bs.is_specular, 0, NULL, by_events, NULL, NULL,
                            later_from_cache, (void *)c, 1};
        ic_pt_li_from(tr, ic_spawn_ray(s, bs.wi), &st, rng, rays);
        weight = v3_scale(bs.weight, inv_p);
    }
    ic_vec3 acc = direct;
    for (int k = 1; k <= levels; ++k) {
        acc = v3_add(acc, v3_mul(weight, by_events[k - 1]));
        cum[k] = v3_add(cum[k], acc);
    }
}

static int read_records(const ic_ctx *c, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo, int levels,
                        ic_rng *rng, uint64_t *rays, ic_vec3 *cum, ic_noise_terms *noise)
{
    /* A glossy lobe is traced on (add_glossy_lobe) where a diffuse one beside it reads the records; a
     * glossy surface without a diffuse lobe is path traced by the caller. */
    const int glossy = ic_bsdf_has_glossy(b);
    if (!ic_bsdf_has_smooth(b) || (glossy && v3_is_black(b->kd)))
        return 0;
    ic_cache_contribution contrib[LOOKUP_CAPACITY], contrib_hit[LOOKUP_CAPACITY];
    ic_cache_lookup q = ic_cache_lookup_at(s->p, b->cache_n, IC_ACCEPT_FINAL);
    q.contributions = contrib;
    q.contribution_capacity = LOOKUP_CAPACITY;
    if (c->hit_kind >= 0) { /* the hit records, where no image record accepts */
        q.fallback = 1u + (uint32_t)c->hit_kind;
        q.fallback_contributions = contrib_hit;
    }
    ic_cache_estimate e;
    if (!ic_cache_query(c->cache, &q, &e))
        return 0;
    ic_vec3 E[IC_LEVELS_MAX], terms[LOOKUP_CAPACITY];
    if (!ic_ic_level_estimates(c, contrib, e.contributions_written, 0, levels, E, noise ? terms : NULL))
        return 0; /* a contributor without levels: the caller path-traces, no random number drawn */
    ic_vec3 albedo = v3_scale(b->kd, IC_INV_PI);
    for (uint32_t i = 0; noise && i < e.contributions_written; ++i)
        ic_ic_noise_add(noise, contrib[i].record, v3_mul(albedo, terms[i]));
    ic_vec3 direct = ic_ic_direct_light_at_hit(c, s, b, wo, glossy ? IC_GLOSSY_NONE : IC_GLOSSY_FULL, rng, rays);
    for (int k = 1; k <= levels; ++k)
        cum[k] = v3_add(direct, v3_mul(albedo, E[k - 1]));
    if (glossy)
        add_glossy_lobe(c, s, b, wo, levels, rng, rays, cum);
    return 1;
}

static int hit_from_cache(const ic_ctx *c, const ic_ray *ray, const ic_hit *hit, ic_rng *rng, uint64_t *rays,
                          ic_vec3 *cum, ic_surface *s, ic_bsdf *b, ic_noise_terms *noise)
{
    const ic_scene *scene = c->tr->scene;
    ic_scene_surface(scene, hit->triangle, hit->u, hit->v, s);
    ic_vec3 wo = v3_neg(ray->dir);
    ic_bsdf_init(b, scene, s, wo);
    return read_records(c, s, b, wo, c->levels, rng, rays, cum, noise);
}

/* ic_path_start.cached for the path a hemisphere ray traces from a hit that read no records (a glossy or
 * specular hit, or a diffuse one that no record reaches): at the first later vertex the records reach, they
 * stand in for the rest of the path, as at the first hit, and the path ends there. The continuation was
 * most of a record's noise: on Sponza, averaging 16 continuations of every such ray divided a record's
 * variance by 6–14, on staircase2 by 2.2; reading the records at the later vertices lowered their
 * low-pass error by 28 and 13 % (three seeds) with 8 and 15 % fewer rays, and every other scene's by
 * 11–25 % (BENCHMARKS.md, "The records read at every vertex of a hemisphere ray's path"). The bounce
 * count stays exact: a vertex that may make `remaining` more scattering events reads the records'
 * levels up to T_{remaining − 1}, and inc[j] is the light of exactly j events from it. */
_Static_assert(IC_LEVELS_MAX <= IC_PT_CACHED_MAX, "a vertex's increments fit the path tracer's array");

static int later_from_cache(void *user, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo, int remaining,
                            ic_rng *rng, uint64_t *rays, ic_vec3 *inc)
{
    const ic_ctx *c = user;
    ic_vec3 cum[IC_LEVELS_MAX + 1];
    if (remaining > c->levels || !read_records(c, s, b, wo, remaining, rng, rays, cum, NULL))
        return 0;
    cum[0] = v3s(0.0f);
    for (int j = 1; j <= remaining; ++j)
        inc[j] = v3_sub(cum[j], cum[j - 1]);
    return 1;
}

/* Whether a hemisphere ray from p escaping along d counts the environment (c->env_mode). */
static int env_in_rays(const ic_ctx *c, ic_vec3 p, ic_vec3 d)
{
    switch (c->env_mode) {
    case IC_ENV_AT_POINT:
        return 0;
    case IC_ENV_PORTAL_SAMPLES:
        return !(ic_scene_portal_pdf(c->gather_tr.scene, p, d) > 0.0f);
    default:
        return 1;
    }
}

/* Appends n rays' hit distances and removed light to the replay (a failed allocation is reported by
 * gather_set). */
static void record_rays(ic_gather_replay *rp, uint32_t n, const float *dist, const ic_vec3 *removed)
{
    if (rp->failed)
        return;
    const size_t need = (size_t)rp->count + n;
    void *d = rp->dist, *l = rp->removed;
    size_t cap_d = rp->capacity, cap_l = rp->capacity;
    const int grown = ic_grow(&d, &cap_d, need, sizeof *rp->dist) == IC_OK;
    rp->dist = d;
    if (!grown || ic_grow(&l, &cap_l, need, sizeof *rp->removed) != IC_OK) {
        rp->failed = 1;
        return;
    }
    rp->removed = l;
    rp->capacity = cap_l < cap_d ? cap_l : cap_d;
    memcpy(rp->dist + rp->count, dist, sizeof *dist * n);
    memcpy(rp->removed + rp->count, removed, sizeof *removed * n);
    rp->count += n;
}

/* Returns the recorded rays again, in the order they were traced (the gatherer asks for the same
 * directions in the same order for the same point); beyond them, misses of no light. */
static void replay_rays(ic_gather_replay *rp, uint32_t n, float *dist, ic_vec3 *radiance)
{
    for (uint32_t i = 0; i < n; ++i, ++rp->next) {
        const int have = rp->next < rp->count;
        dist[i] = have ? rp->dist[rp->next] : INFINITY;
        radiance[i] = have ? rp->removed[rp->next] : v3s(0.0f);
    }
}

void ic_ic_gather_worker_release(ic_gather_worker *w)
{
    free(w->replay.dist);
    free(w->replay.removed);
    memset(&w->replay, 0, sizeof w->replay);
    ic_ic_noise_release(&w->noise);
}

/* Hemisphere rays of a record: what they return is described in ic.h. The path after the first hit
 * is seeded from the ray itself (origin and direction bits), so it does not depend on which batch or
 * thread traced it. With levels, each ray's light is also split by bounce level into the worker's sums:
 * the environment and large emitters' light at level 0 and up, a look-up's by hit_from_cache, a
 * path-traced ray's by the scattering events after the record (ic_path_start.levels). */
void ic_ic_gather_trace(void *user, const ic_vec3 *origins, const ic_vec3 *dirs, uint32_t count, float *hit_dist,
                         ic_vec3 *radiance)
{
    ic_gather_worker *w = user;
    ic_ctx *c = w->c;
    const ic_tracer *tr = &c->gather_tr;
    const int B = c->levels;
    enum { CHUNK = 256 };
    ic_ray rays[CHUNK];
    ic_hit hits[CHUNK];
    ic_vec3 removed[CHUNK];
    uint64_t nrays = 0;
    if (w->replay.replaying) {
        replay_rays(&w->replay, count, hit_dist, radiance);
        return;
    }
    for (uint32_t base = 0; base < count; base += CHUNK) {
        uint32_t n = count - base < CHUNK ? count - base : CHUNK;
        for (uint32_t i = 0; w->replay.recording && i < n; ++i)
            removed[i] = v3s(0.0f);
        for (uint32_t i = 0; i < n; ++i) {
            rays[i].org = origins[base + i];
            rays[i].dir = dirs[base + i];
            rays[i].tnear = 0.0f;
            rays[i].tfar = INFINITY;
        }
        ic_accel_intersect_n(tr->accel, rays, hits, n, 0);
        nrays += n;
        for (uint32_t i = 0; i < n; ++i) {
            uint32_t j = base + i;
            ic_vec3 cum[IC_LEVELS_MAX + 1];
            if (hits[i].triangle == IC_NO_HIT) {
                hit_dist[j] = INFINITY;
                radiance[j] = env_in_rays(c, rays[i].org, rays[i].dir) ? ic_scene_env_radiance(tr->scene, rays[i].dir)
                                                                      : v3s(0.0f);
                for (int k = 0; k < B; ++k)
                    w->sum[k] = v3_add(w->sum[k], radiance[j]);
                if (B)
                    w->sum[B] = v3_add(w->sum[B], radiance[j]);
                continue;
            }
            hit_dist[j] = hits[i].t;
            union { float f[6]; uint32_t u[6]; } bits;
            bits.f[0] = rays[i].org.x;
            bits.f[1] = rays[i].org.y;
            bits.f[2] = rays[i].org.z;
            bits.f[3] = rays[i].dir.x;
            bits.f[4] = rays[i].dir.y;
            bits.f[5] = rays[i].dir.z;
            ic_rng rng = ic_rng_make(c->seed ^ 0x6761746865720000ULL, ((uint64_t)bits.u[0] << 32) | bits.u[1],
                                     ((uint64_t)bits.u[2] << 32) | bits.u[3], ((uint64_t)bits.u[4] << 32) | bits.u[5]);
            ic_surface hs;
            ic_bsdf hb;
            const int looked = c->hit_lookups != 0;
            if (looked && hit_from_cache(c, &rays[i], &hits[i], &rng, &nrays, cum, &hs, &hb,
                                         c->track_noise ? &w->noise : NULL)) {
                radiance[j] = cum[B];
            } else {
                /* The hit is the path's second vertex (the record is the first): depth 1. Its emission
                 * is direct light of the record's point, delivered by NEE in the final render. */
                ic_vec3 by_events[IC_LEVELS_MAX + 1];
                for (int k = 0; k <= B; ++k)
                    by_events[k] = v3s(0.0f);
                ic_path_start st = {1, 0.0f, 1, 1, NULL, B ? by_events : NULL, looked ? &hs : NULL,
                                    looked ? &hb : NULL, NULL, NULL, 0};
                if (looked) { /* the path's later diffuse vertices read the records too */
                    st.cached = later_from_cache;
                    st.cached_user = c;
                }
                radiance[j] = ic_pt_li_hit(tr, rays[i], &hits[i], &st, &rng, &nrays);
                if (B) {
                    cum[0] = by_events[0];
                    for (int k = 1; k <= B; ++k)
                        cum[k] = v3_add(cum[k - 1], by_events[k]);
                }
            }
            /* ... unless it comes from a large emitter, which the records carry (level 0), weighted
             * against the light samples. */
            ic_vec3 emitted = ic_ic_cached_emission(c, &rays[i], &hits[i]);
            if (!v3_is_black(emitted)) {
                const ic_vec3 whole = emitted;
                emitted = v3_scale(emitted, cached_ray_weight(w, &rays[i], &hits[i]));
                if (w->replay.recording)
                    removed[i] = v3_sub(whole, emitted);
            }
            radiance[j] = v3_add(radiance[j], emitted);
            if (B) {
                w->sum[0] = v3_add(w->sum[0], emitted);
                for (int k = 1; k < B; ++k)
                    w->sum[k] = v3_add(w->sum[k], v3_add(cum[k], emitted));
                w->sum[B] = v3_add(w->sum[B], radiance[j]);
            }
        }
        if (w->replay.recording)
            record_rays(&w->replay, n, hit_dist + base, removed);
    }
    atomic_fetch_add_explicit(&c->rays, nrays, memory_order_relaxed);
}

ic_result ic_ic_gather_by_method(const ic_ctx *c, ic_gatherer *g, const ic_gather_point *pt, ic_gather_result *out)
{
    switch (c->o.gather.method) {
    case IC_GATHER_PROGRESSIVE:
        return ic_gather_progressive(g, pt, 1, out);
    case IC_GATHER_HEMICUBE:
        return ic_gather_hemicube(g, pt, out);
    default:
        return ic_gather_stratified(g, pt, out);
    }
}

/* One hemisphere set of a point (see ic_ic_gather_one). */
static ic_result gather_set(ic_gather_worker *w, ic_gatherer *g, const ic_gather_point *pt, ic_gather_result *out,
                            ic_vec3 *levels)
{
    const int B = w->c->levels;
    for (int k = 0; k <= B; ++k)
        w->sum[k] = v3s(0.0f);
    /* With the cached emitters' light samples, the rays' hits on them count only their balance-heuristic
     * share, which is right for the irradiance (the light samples add the rest) but not for the
     * Hessian: the light samples have none, so a weighted field's Hessian falls short by about the rays'
     * mean weight (a third at 1,800 rays; test_emitter_mis) and the record comes out too large. The
     * Hessian is linear in the rays' radiance for given hit distances, so the share the weights removed
     * is gathered again from the recorded rays (no new tracing) and its Hessian added. The gradients
     * keep the weighted field: whole hits make them noisier, which cost staircase2 13 % more low-pass
     * error (BENCHMARKS.md, "The Hessian of the cached emitters' whole light"). */
    const int whole = w->mis_lights > 0.0f && w->c->o.gather.with_hessian;
    w->replay.recording = whole;
    w->replay.count = 0;
    ic_result r = ic_ic_gather_by_method(w->c, g, pt, out);
    w->replay.recording = 0;
    if (r == IC_OK && whole && out->has_hessian) {
        if (w->replay.failed)
            return IC_ERR_OOM;
        ic_gather_result rest;
        w->replay.replaying = 1;
        w->replay.next = 0;
        r = ic_ic_gather_by_method(w->c, g, pt, &rest);
        w->replay.replaying = 0;
        for (int ch = 0; r == IC_OK && rest.has_hessian && ch < 3; ++ch)
            for (int i = 0; i < 3; ++i)
                out->hessian[ch][i] += rest.hessian[ch][i];
    }
    if (r != IC_OK || !B || !levels)
        return r;
    /* The stratified estimate is π/(MN) times the sum of the rays' radiance, so scaling E by each
     * level's share of that sum gives the level's own estimate exactly (progressive: its rounds' share;
     * hemicube: a weighted sum, for which the unweighted share is an approximation). */
    const float e[3] = {out->irradiance.x, out->irradiance.y, out->irradiance.z};
    const float all[3] = {w->sum[B].x, w->sum[B].y, w->sum[B].z};
    for (int k = 0; k < B; ++k) {
        const float part[3] = {w->sum[k].x, w->sum[k].y, w->sum[k].z};
        float t[3];
        for (int ch = 0; ch < 3; ++ch)
            t[ch] = all[ch] > 0.0f ? e[ch] * fminf(fmaxf(part[ch] / all[ch], 0.0f), 1.0f) : 0.0f;
        levels[k] = v3(t[0], t[1], t[2]);
    }
    levels[B] = out->irradiance;
    return IC_OK;
}

/* Adds set b (weight 1) to the running mean a of k sets. */
static void add_set(ic_gather_result *a, const ic_gather_result *b, int k, ic_vec3 *lev, const ic_vec3 *blev, int B)
{
    float wa = (float)k / (float)(k + 1), wb = 1.0f / (float)(k + 1);
#define MIX(x, y) v3_add(v3_scale((x), wa), v3_scale((y), wb))
    a->irradiance = MIX(a->irradiance, b->irradiance);
    for (int ch = 0; ch < 3; ++ch) {
        a->rot_grad[ch] = MIX(a->rot_grad[ch], b->rot_grad[ch]);
        a->trans_grad[ch] = MIX(a->trans_grad[ch], b->trans_grad[ch]);
    }
    a->sigma = MIX(a->sigma, b->sigma);
    for (int l = 0; lev && l <= B; ++l)
        lev[l] = MIX(lev[l], blev[l]);
#undef MIX
    /* Harmonic means combine harmonically. */
    float ia = a->harmonic_mean_dist > 0.0f ? 1.0f / a->harmonic_mean_dist : 0.0f;
    float ib = b->harmonic_mean_dist > 0.0f ? 1.0f / b->harmonic_mean_dist : 0.0f;
    float inv = ia * wa + ib * wb;
    a->harmonic_mean_dist = inv > 0.0f ? 1.0f / inv : INFINITY;
    a->min_dist = fminf(a->min_dist, b->min_dist);
    a->ray_count += b->ray_count;
    a->hit_count += b->hit_count;
}

/* The point's sets (several with record noise control). */
static ic_result gather_sets(ic_gather_worker *w, ic_gatherer *g, const ic_gather_point *pt, ic_gather_result *out,
                             ic_vec3 *levels)
{
    ic_ctx *c = w->c;
    ic_result r = gather_set(w, g, pt, out, levels);
    if (r != IC_OK || c->o.record_sets <= 1)
        return r;
    /* σ of one set's E (Křivánek et al. 2006 §4.3); sets needed for the target relative σ. */
    float y = v3_lum(out->irradiance), s = v3_lum(out->sigma);
    if (!(y > 0.0f))
        return IC_OK;
    float ratio = s / (y * c->o.record_noise);
    int sets = ratio * ratio > (float)c->o.record_sets ? c->o.record_sets : (int)ceilf(ratio * ratio);
    if (sets <= 1) /* one set is enough (a σ of zero too: every ray returned the same light) */
        return IC_OK;
    const int B = c->levels;
    ic_vec3 blev[IC_LEVELS_MAX + 1];
    for (int k = 1; k < sets; ++k) {
        ic_gather_point p2 = *pt;
        p2.key = ic_hash4(pt->key, (uint64_t)k, 0x73657473ULL, 0);
        ic_gather_result b;
        r = gather_set(w, g, &p2, &b, levels ? blev : NULL);
        if (r != IC_OK)
            return r;
        add_set(out, &b, k, levels, blev, B);
    }
    /* The mean of k independent sets has 1/√k of one set's σ. */
    out->sigma = v3_scale(out->sigma, 1.0f / sqrtf((float)sets));
    return IC_OK;
}

ic_result ic_ic_gather_one(ic_gather_worker *w, ic_gatherer *g, const ic_gather_point *pt, ic_gather_result *out,
                           ic_vec3 *levels)
{
    ic_ctx *c = w->c;
    w->pt = pt;
    w->mis_rays = w->mis_lights = 0.0f;
    /* Stratified gathering of one set only: its rays are cosine-distributed, n_r of them. */
    const ic_gather_opts *go = ic_gatherer_opts(g);
    if (c->emitter_mis && c->cached_emitters && c->cached_pmf && go && go->method == IC_GATHER_STRATIFIED &&
        c->o.record_sets <= 1) {
        uint32_t rays = go->theta_strata * go->phi_strata;
        w->mis_rays = (float)rays;
        w->mis_lights = (float)ic_ic_emitter_light_samples(rays);
    }
    ic_result r = gather_sets(w, g, pt, out, levels); /* w->noise: empty (ic_ic_noise_variance empties it) */
    if (r == IC_OK && c->track_noise) {
        if (w->noise.failed)
            return IC_ERR_OOM;
        w->noise_var = ic_ic_noise_variance(c, &w->noise, out->ray_count ? IC_PI / (double)out->ray_count : 0.0);
    }
    if (r == IC_OK && w->mis_lights > 0.0f)
        ic_ic_add_cached_emitter_light(w, pt, out, levels);
    if (r == IC_OK && c->env_mode == IC_ENV_PORTAL_SAMPLES)
        ic_ic_add_portal_light(c, pt, out, levels);
    w->mis_lights = 0.0f;
    return r;
}

/* Points per work item of ic_ic_gather_points: enough to amortise scheduling, small enough to balance. */
#define GATHER_CHUNK_POINTS 8u

typedef struct gather_job {
    ic_ctx *c;
    ic_gather_worker *workers;   /* one per thread */
    ic_gatherer **gatherers;     /* one per thread */
    const ic_gather_point *pts;
    ic_gather_result *out;
    ic_vec3 *levels;
    ic_vec3 *noise;              /* with c->track_noise: per point, ic_gather_worker.noise_var */
    uint8_t *gathered;           /* per point: 1 once gathered */
    uint32_t count;
    atomic_int status;           /* first failure, IC_OK if none */
} gather_job;

static void gather_item(void *p, int64_t item, int thread)
{
    gather_job *j = p;
    uint32_t first = (uint32_t)item * GATHER_CHUNK_POINTS;
    uint32_t end = j->count - first < GATHER_CHUNK_POINTS ? j->count : first + GATHER_CHUNK_POINTS;
    size_t stride = (size_t)j->c->levels + 1;
    for (uint32_t i = first; i < end; ++i) {
        if (ic_ic_cancelled(j->c) || ic_ic_past_deadline(j->c))
            return; /* interrupted, or construction's share of the time spent: the points not begun stay
                       ungathered */
        ic_result r = ic_ic_gather_one(&j->workers[thread], j->gatherers[thread], &j->pts[i], &j->out[i],
                                       j->levels ? &j->levels[i * stride] : NULL);
        if (r != IC_OK) {
            int expected = IC_OK;
            atomic_compare_exchange_strong(&j->status, &expected, (int)r);
            return;
        }
        if (j->noise)
            j->noise[i] = j->workers[thread].noise_var;
        j->gathered[i] = 1;
    }
}

/* Gathers count points on this process's threads. */
static ic_result gather_here(ic_ctx *c, const ic_gather_point *pts, uint32_t count, ic_gather_result *out,
                             ic_vec3 *levels, ic_vec3 *noise, uint8_t *gathered, ic_error *err)
{
    if (count == 0)
        return IC_OK;
    memset(gathered, 0, count);
    int64_t items = ((int64_t)count + GATHER_CHUNK_POINTS - 1) / GATHER_CHUNK_POINTS;
    int threads = c->threads < items ? c->threads : (int)items;
    gather_job j;
    memset(&j, 0, sizeof j);
    j.c = c;
    j.pts = pts;
    j.out = out;
    j.levels = levels;
    j.noise = noise;
    j.gathered = gathered;
    j.count = count;
    atomic_init(&j.status, IC_OK);
    j.workers = calloc((size_t)threads, sizeof *j.workers);
    j.gatherers = calloc((size_t)threads, sizeof *j.gatherers);
    ic_result r = j.workers && j.gatherers ? IC_OK : ic_error_set(err, IC_ERR_OOM, "out of memory for gatherers");
    for (int t = 0; t < threads && r == IC_OK; ++t) {
        j.workers[t].c = c;
        r = ic_gatherer_create(&c->o.gather, ic_ic_gather_trace, &j.workers[t], &j.gatherers[t], err);
    }
    if (r == IC_OK) {
        r = ic_parallel_for(threads, items, gather_item, &j);
        if (r != IC_OK)
            ic_error_set(err, r, "could not start %d gathering threads", threads);
        else if ((r = (ic_result)atomic_load(&j.status)) == IC_ERR_OOM)
            ic_error_set(err, r, "out of memory keeping a record's rays for its Hessian, or the records "
                         "they read for its sigma");
        else if (r != IC_OK)
            ic_error_set(err, r, "gathering a record failed (%s): a shading point with a zero normal or a "
                         "non-finite position", ic_result_name(r));
    }
    for (int t = 0; j.gatherers && t < threads; ++t)
        ic_gatherer_destroy(j.gatherers[t]);
    for (int t = 0; j.workers && t < threads; ++t)
        ic_ic_gather_worker_release(&j.workers[t]);
    free(j.gatherers);
    free(j.workers);
    return r;
}

/* What gather_block gathers points with: the context and where the points' gathered flags go. */
typedef struct gather_points_job {
    ic_ctx *c;
    uint8_t *gathered;
    int has_levels, has_noise;
} gather_points_job;

/* ic_comm_gather_fn of ic_ic_gather_points: n points into out[0] (results), then out[1] (bounce levels, if
 * kept), then the next (the noise from the records read, if tracked). */
static ic_result gather_block(void *user, const void *pts, uint64_t n, void *const *out, ic_error *err)
{
    gather_points_job *u = user;
    ic_result r = gather_here(u->c, pts, (uint32_t)n, out[0], u->has_levels ? out[1] : NULL,
                              u->has_noise ? out[1 + u->has_levels] : NULL, u->gathered, err);
    /* The counts a result ends its first order with are read by no one after the gather (its records take
     * the values, the statistics count rays as they are traced): zero, so that they need not travel. */
    ic_gather_result *res = out[0];
    for (uint64_t k = 0; k < n; ++k) {
        res[k].ray_count = res[k].hit_count = 0;
        res[k].is_converged = 0;
    }
    return r;
}

/* Several processes (c->comm): point i is gathered by rank i mod N (ic_comm_share_gather: neighbouring
 * points, which cost alike, spread over every rank), and the results are exchanged, so every process holds
 * every result, bit for bit what one process would have gathered: a point's result depends only on the
 * seed, its key and the records already in the cache, which every process holds alike. */
ic_result ic_ic_gather_points(ic_ctx *c, const ic_gather_point *pts, uint32_t count, ic_gather_result *out,
                              ic_vec3 *levels, ic_vec3 *noise, uint8_t *gathered, ic_error *err)
{
    const int shared = ic_comm_size(c->comm) > 1 && count > 0;
    gather_points_job u = {c, gathered, levels != NULL, noise != NULL};
    if (shared) {
        /* Shared: never cancelled (ic_ic_cancelled), so every point is gathered; this rank's own flags
         * go to scratch. */
        memset(gathered, 1, count);
        u.gathered = malloc(count);
        if (!u.gathered)
            return ic_error_set(err, IC_ERR_OOM, "out of memory for %u gather results", count);
    }
    size_t stride = (size_t)c->levels + 1;
    void *const outs[3] = {out, levels ? (void *)levels : (void *)noise, noise};
    const size_t sizes[3] = {sizeof *out, levels ? sizeof *levels * stride : sizeof *noise, sizeof *noise};
    /* Without a Hessian the gatherers leave a result's second-order fields (its last 64 bytes) zero, and
     * gather_block its ray and hit counts and convergence flag: they stay home (76 of the 180 bytes). */
    _Static_assert(offsetof(ic_gather_result, has_hessian) + sizeof(int) + 2 * sizeof(ic_vec3) + 9 * sizeof(float) ==
                       sizeof(ic_gather_result), "the second-order fields end the result");
    _Static_assert(offsetof(ic_gather_result, ray_count) + 2 * sizeof(uint32_t) + sizeof(int) ==
                       offsetof(ic_gather_result, has_hessian), "the counts come just before them");
    const size_t sent[3] = {c->o.gather.with_hessian ? sizeof *out : offsetof(ic_gather_result, ray_count), sizes[1],
                            sizes[2]};
    uint64_t own;
    const int arrays = 1 + (levels != NULL) + (noise != NULL);
    ic_result r = ic_comm_share_gather(c->comm, pts, sizeof *pts, count, arrays, outs, sizes, sent, gather_block, &u,
                                       "gather results", &own, err);
    if (shared) {
        c->gathered += own;
        free(u.gathered);
    } else {
        for (uint32_t i = 0; i < count; ++i)
            c->gathered += gathered[i];
    }
    return r;
}

int ic_ic_out_of_time_shared(ic_ctx *c)
{
    int32_t out = ic_seconds() > c->deadline;
    /* A transport that fails ends the job (comm.h); till then, rank 0's answer or this rank's own. */
    ic_comm_broadcast(c->comm, &out, sizeof out, 0, NULL);
    return out;
}

uint32_t ic_ic_keep_gathered(const ic_ctx *c, const uint8_t *gathered, uint32_t count, ic_gather_result *res,
                             ic_vec3 *levels)
{
    size_t stride = (size_t)c->levels + 1;
    uint32_t k = 0;
    for (uint32_t i = 0; i < count; ++i) {
        if (!gathered[i])
            continue;
        if (k != i) {
            res[k] = res[i];
            if (levels)
                memmove(&levels[k * stride], &levels[i * stride], sizeof *levels * stride);
        }
        ++k;
    }
    return k;
}

ic_result ic_ic_keep_levels(ic_ctx *c, uint32_t first, uint32_t count, const ic_vec3 *levels, ic_error *err)
{
    if (!c->levels || count == 0)
        return IC_OK;
    if (first != c->level_records)
        return ic_error_set(err, IC_ERR_INTERNAL, "bounce levels out of step with the records (%u, %u)", first,
                            c->level_records);
    size_t stride = (size_t)c->levels + 1;
    if (first + count > c->level_capacity) {
        uint32_t cap = c->level_capacity ? c->level_capacity : 1024;
        while (cap < first + count)
            cap *= 2;
        ic_vec3 *grown = realloc(c->level_irr, sizeof *grown * stride * cap);
        if (!grown)
            return ic_error_set(err, IC_ERR_OOM, "out of memory for the records' bounce levels");
        c->level_irr = grown;
        c->level_capacity = cap;
    }
    memcpy(&c->level_irr[(size_t)first * stride], levels, sizeof *levels * stride * count);
    c->level_records = first + count;
    return IC_OK;
}

float ic_ic_hessian_error_target(const ic_cache_params *p)
{
    /* Ward's and the error weight's a is the Hessian extent's ε (0.15 by default); Tabellion–Lamorlette's
     * a only scales their acceptance (1 by default, κ = 1/a), so it maps to Ward's in proportion: the
     * defaults ask the same ε of either (ε = a would give T–L's default records 0.15⁻¹ times as large). */
    return p->weight == IC_WEIGHT_TABELLION ? p->accuracy * (IC_DEFAULT_ACCURACY_WARD / IC_DEFAULT_ACCURACY_TL)
                                            : p->accuracy;
}

void ic_ic_record_from_gather(const ic_ctx *c, const ic_candidate *cand, const ic_gather_result *gr, ic_record *rec)
{
    memset(rec, 0, sizeof *rec);
    rec->position = cand->p;
    rec->normal = cand->n;
    rec->tangent = ic_frame_from_normal(cand->n).t;
    rec->irradiance = gr->irradiance;
    rec->bounce = c->record_bounce;
    if (!c->o.no_gradients) {
        /* Gradient-magnitude clamping (Křivánek et al. 2006 §5.1, eq. 2) bounds the extrapolated change by shrinking
         * R to Y/|∇t Y|; where the R floor (R_min, pixel bound) stops that, the linear model would be
         * extrapolated beyond its validity (seen as bright blotches in concave corners, where 1/r of
         * close hits makes |∇t E| huge). There the gradient itself is scaled so |∇t Y|·R_floor ≤ Y.
         * Likewise the rotational term is kept below Y for the largest normal change the weights accept
         * (|n_i × n| ≲ √2·a). */
        float y = v3_lum(gr->irradiance);
        ic_vec3 gt = v3_add(v3_add(v3_scale(gr->trans_grad[0], 0.2126f), v3_scale(gr->trans_grad[1], 0.7152f)),
                            v3_scale(gr->trans_grad[2], 0.0722f));
        ic_vec3 grt = v3_add(v3_add(v3_scale(gr->rot_grad[0], 0.2126f), v3_scale(gr->rot_grad[1], 0.7152f)),
                             v3_scale(gr->rot_grad[2], 0.0722f));
        float floor_r = fmaxf(c->o.cache.min_radius, c->o.cache.min_radius_pixels * cand->footprint);
        float gt_len = v3_len(gt), grt_len = v3_len(grt);
        float st = (gt_len * floor_r > y && gt_len > 0.0f) ? y / (gt_len * floor_r) : 1.0f;
        float rot_limit = y / (1.4142f * c->o.cache.accuracy);
        float sr = grt_len > rot_limit && grt_len > 0.0f ? rot_limit / grt_len : 1.0f;
        for (int k = 0; k < 3; ++k) {
            rec->grad_rot[k] = v3_scale(gr->rot_grad[k], sr);
            rec->grad_trans[k] = v3_scale(gr->trans_grad[k], st);
        }
    }
    rec->sigma = gr->sigma;
    /* A record that sees nothing (open sky) has an infinite harmonic-mean distance: its radius is
     * then set by the upper bounds. */
    rec->harmonic_mean_dist = isfinite(gr->harmonic_mean_dist) && gr->harmonic_mean_dist > 0.0f
                                  ? gr->harmonic_mean_dist
                                  : c->scene_diag;
    if (c->o.error == IC_ERROR_HESSIAN && gr->has_hessian) {
        /* Schwarzhaupt et al. 2012: first-order extrapolation errs by ½dᵀHd, so along an eigenvector of H
         * the relative error reaches ε at ℓ_k·√ε, ℓ_k = √(2E/|λ_k|) (ic_gather_hessian_extent). A record
         * does not reach that far: its semi-axes are ε·√(L·ℓ_k), L an eighth of the work extent, the
         * spacing that for a given number of records makes the relative error's L1 norm least (a region
         * of area A and spacing s holds A/s² records and errs by about |λ/E|·s²: Σ A|λ/E|s² at a fixed
         * Σ A/s² is least where s⁴ ∝ |E/λ|, records as dense as √|λ/E|, the law behind Radiance's radii
         * ∝ |λ|^(−1/4); docs/gathering.md), where the pointwise bound ℓ_k·√ε would spend records
         * in proportion to |λ/E| on the few places of high curvature (BENCHMARKS.md, "The low-record
         * end"). ε is ic_ic_hessian_error_target's. A round record takes the smaller semi-axis, an
         * elliptical one both (its aspect bounded by IC_MAX_ELLIPSE_ASPECT, so a nearly flat direction does
         * not stretch it across the scene). The weights accept |p − p_i|_i < a·R_i, so R_i is the (major)
         * extent over a; the cache's clamps then apply as to the split sphere's R. */
        ic_gather_extent_opts eo = {0};
        eo.rel_error = ic_ic_hessian_error_target(&c->o.cache);
        eo.max_radius = c->scene_diag;
        ic_gather_extent ext = {0};
        if (ic_gather_hessian_extent(gr, &eo, &ext) == IC_OK) {
            /* ℓ_k from the eigenvalues (not from the pointwise semi-axes, which the extent clamps to
             * max_radius): a flat direction (λ = 0) reaches the scene's diagonal */
            const double eps = eo.rel_error, L = IC_HESSIAN_SPACING_LENGTH * c->work_extent;
            const double E = fmax(v3_lum(gr->irradiance), 0.0);
            for (int k = 0; k < 2; ++k) {
                const double lam = fabs((double)ext.eigenvalue[k]);
                const double s = lam > 0.0 ? eps * sqrt(L * sqrt(2.0 * E / lam)) : INFINITY;
                ext.semi_axis[k] = (float)fmin(s, (double)c->scene_diag);
            }
            ext.radius = ext.semi_axis[0];
        }
        if (ext.radius > 0.0f) {
            float major = ext.radius;
            if (c->o.record_shape == IC_SHAPE_ELLIPTICAL) {
                major = fminf(ext.semi_axis[1], IC_MAX_ELLIPSE_ASPECT * ext.semi_axis[0]);
                if (major > ext.semi_axis[0]) {
                    rec->ellipse_axis = ext.axis[0];
                    rec->ellipse_ratio = ext.semi_axis[0] / major;
                }
            }
            rec->harmonic_mean_dist = major / c->o.cache.accuracy;
        }
    }
    rec->pixel_footprint = cand->footprint;
}

ic_vec3 ic_ic_gather_origin(const ic_ctx *c, ic_vec3 p, ic_vec3 n)
{
    return ic_offset_ray_origin_floor(p, n, n, c->tr->scene->ray_offset_floor);
}

ic_gather_point ic_ic_gather_point_of(const ic_ctx *c, const ic_candidate *cand)
{
    ic_gather_point gp;
    gp.position = ic_ic_gather_origin(c, cand->p, cand->n);
    gp.normal = cand->n;
    gp.key = cand->key;
    return gp;
}

/* Keeps the variance from the records read (noise) of records first … first + count − 1 in
 * c->record_noise; the records before them that have none get zero. */
static ic_result keep_noise(ic_ctx *c, uint32_t first, uint32_t count, const ic_vec3 *noise, ic_error *err)
{
    void *a = c->record_noise;
    if (ic_grow(&a, &c->record_noise_capacity, (size_t)first + count, sizeof *c->record_noise) != IC_OK)
        return ic_error_set(err, IC_ERR_OOM, "out of memory for the records' noise from the records they read");
    c->record_noise = a;
    for (uint32_t i = c->record_noise_count; i < first; ++i)
        c->record_noise[i] = v3s(0.0f);
    memcpy(&c->record_noise[first], noise, sizeof *noise * count);
    c->record_noise_count = first + count;
    return IC_OK;
}

/* Gathers all candidates in parallel and inserts them as one batch. */
ic_result ic_ic_gather_and_insert(ic_ctx *c, const ic_candidate *cand, uint32_t count, phase_times *pt,
                                   ic_error *err)
{
    if (count == 0)
        return IC_OK;
    size_t stride = (size_t)c->levels + 1;
    ic_gather_point *pts = malloc(sizeof *pts * count);
    ic_gather_result *res = malloc(sizeof *res * count);
    ic_record *recs = malloc(sizeof *recs * count);
    ic_vec3 *levels = c->levels ? malloc(sizeof *levels * stride * count) : NULL;
    ic_vec3 *noise = c->track_noise ? malloc(sizeof *noise * count) : NULL;
    uint8_t *gathered = malloc(count);
    ic_result r = IC_OK;
    if (!pts || !res || !recs || !gathered || (c->levels && !levels) || (c->track_noise && !noise)) {
        r = ic_error_set(err, IC_ERR_OOM, "out of memory for %u cache candidates", count);
        goto done;
    }
    for (uint32_t i = 0; i < count; ++i)
        pts[i] = ic_ic_gather_point_of(c, &cand[i]);
    double t0 = ic_seconds();
    r = ic_ic_gather_points(c, pts, count, res, levels, noise, gathered, err);
    double t1 = ic_seconds();
    pt->gather += t1 - t0;
    if (r != IC_OK)
        goto done;
    /* The gathered ones, in candidate order (all of them unless the render was interrupted). */
    uint32_t kept = ic_ic_keep_gathered(c, gathered, count, res, levels);
    c->ungathered += count - kept;
    for (uint32_t i = 0, k = 0; i < count; ++i) {
        if (!gathered[i])
            continue;
        ic_ic_record_from_gather(c, &cand[i], &res[k], &recs[k]);
        if (noise)
            noise[k] = noise[i];
        ++k;
    }
    uint32_t first = 0;
    r = ic_cache_insert_batch(c->cache, recs, kept, &first, err);
    if (r == IC_OK)
        r = ic_ic_keep_levels(c, first, kept, levels, err);
    if (r == IC_OK && noise)
        r = keep_noise(c, first, kept, noise, err);
    pt->insert += ic_seconds() - t1;
done:
    free(pts);
    free(res);
    free(recs);
    free(levels);
    free(noise);
    free(gathered);
    return r;
}

ic_candidate ic_ic_candidate_at_pixel(const ic_ctx *c, uint32_t pixel, uint64_t tag)
{
    ic_candidate cd;
    memset(&cd, 0, sizeof cd); /* its padding too: candidates travel between processes whole */
    ic_ic_gbuffer_point(c, pixel, &cd.p, &cd.n, &cd.footprint);
    cd.key = ((uint64_t)pixel << 8) | tag;
    return cd;
}

ic_result ic_ic_levels_to_payloads(ic_ctx *c, ic_error *err)
{
    if (!c->levels)
        return IC_OK;
    const uint32_t floats = 3u * (uint32_t)(c->levels + 1);
    float buf[3 * (IC_LEVELS_MAX + 1)];
    for (uint32_t i = 0; i < c->level_records; ++i) {
        const ic_vec3 *T = &c->level_irr[(size_t)i * (size_t)(c->levels + 1)];
        for (int k = 0; k <= c->levels; ++k) {
            buf[3 * k] = T[k].x;
            buf[3 * k + 1] = T[k].y;
            buf[3 * k + 2] = T[k].z;
        }
        ic_result r = ic_cache_set_payload(c->cache, i, buf, floats, err);
        if (r != IC_OK)
            return r;
    }
    return IC_OK;
}

ic_result ic_ic_levels_from_payloads(ic_ctx *c, ic_error *err)
{
    if (!c->levels)
        return IC_OK;
    const uint32_t floats = 3u * (uint32_t)(c->levels + 1), n = ic_cache_count(c->cache);
    uint32_t first = 0;
    /* The leading irradiance records that carry their split (the radiance records follow them). */
    while (first < n) {
        ic_record rec;
        uint32_t len;
        if (ic_cache_get_record(c->cache, first, &rec) != IC_OK || rec.bounce >= IC_BOUNCE_RADIANCE ||
            !ic_cache_payload(c->cache, first, &len) || len != floats)
            break;
        ++first;
    }
    if (first == 0)
        return IC_OK;
    ic_vec3 *levels = malloc(sizeof *levels * (size_t)(c->levels + 1) * first);
    if (!levels)
        return ic_error_set(err, IC_ERR_OOM, "out of memory for the records' bounce levels");
    for (uint32_t i = 0; i < first; ++i) {
        const float *p = ic_cache_payload(c->cache, i, NULL);
        for (int k = 0; k <= c->levels; ++k)
            levels[(size_t)i * (size_t)(c->levels + 1) + (size_t)k] = v3(p[3 * k], p[3 * k + 1], p[3 * k + 2]);
    }
    c->level_records = 0;
    ic_result r = ic_ic_keep_levels(c, 0, first, levels, err);
    free(levels);
    return r;
}
