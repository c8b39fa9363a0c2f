/*
 * ic_points.c — the irradiance cache at sensor points (include/irrcache/points.h, driven by
 * src/render/points.c): a context without the image's shading points, lazy construction over the
 * sensors in input order (Ward et al. 1988 §3: a look-up at each point, a record gathered and inserted
 * where none is accepted), and per point the interpolated indirect irradiance with the Monte Carlo σ
 * the interpolation carries over from its records (Křivánek et al. 2006 §4.3 for a record's σ).
 */
#include "ic_internal.h"

#include "irrcache/points.h"

#include <math.h>
#include <string.h>

#define POINT_KEY_TAG 0x73656e736f72ULL /* keys of sensor records, apart from the image's */
#define MAX_ROUNDS 8                    /* passes over the points while later records clamp earlier ones */
#define CONTRIBUTION_CAPACITY 256

void ic_ic_sensor(ic_vec3 p, ic_vec3 n, ic_surface *s, ic_bsdf *b)
{
    memset(s, 0, sizeof *s);
    s->p = p;
    s->ng = n;
    s->ns = n;
    s->triangle = IC_NO_HIT;
    memset(b, 0, sizeof *b);
    b->type = IC_MAT_DIFFUSE;
    b->kd = v3s(1.0f);
    b->ior = 1.0f;
    b->p_diffuse = 1.0f;
    b->frame = ic_frame_from_normal(n);
    b->ng = n;
}

ic_result ic_ic_points_ctx_create(const ic_tracer *tr, const ic_render_options *opt, ic_ctx **out, ic_error *err)
{
    ic_render_options o = *opt;
    o.integrator = IC_INTEGRATOR_IC;
    o.time_budget = 0.0;
    o.ic.strategy = IC_STRATEGY_LAZY;
    o.ic.recursive = 0;
    o.ic.load_cache = NULL;
    o.ic.save_cache = NULL;
    /* Every emitter is light-sampled at each sensor: the records carry the environment and indirect
     * light only. */
    o.ic.large_emitters.mode = IC_CACHE_OFF;
    o.ic.record_filter.mode = IC_CACHE_OFF;
    ic_result r = ic_ic_ctx_create(tr, &o, out, NULL, err);
    if (r != IC_OK)
        return r;
    /* The camera's shading points are not used: sensors are the only shading points. */
    ic_ic_gbuffer_free(*out);
    memset(&(*out)->g, 0, sizeof (*out)->g);
    (*out)->has_record = NULL;
    return IC_OK;
}

ic_result ic_ic_points_build(ic_ctx *c, const ic_vec3 *p, const ic_vec3 *n, uint32_t count, ic_error *err)
{
    ic_gather_worker worker;
    memset(&worker, 0, sizeof worker);
    worker.c = c;
    ic_gatherer *g = NULL;
    ic_result r = ic_gatherer_create(&c->o.gather, ic_ic_gather_trace, &worker, &g, err);
    /* Input order, then again while a point lost its cover to a later record's neighbour clamping. */
    for (int round = 0; round < MAX_ROUNDS && r == IC_OK; ++round) {
        uint32_t added = 0;
        for (uint32_t i = 0; i < count && r == IC_OK; ++i) {
            ic_cache_lookup q = ic_cache_lookup_at(p[i], n[i], IC_ACCEPT_CONSTRUCTION);
            ic_cache_estimate e;
            if (ic_cache_query(c->cache, &q, &e))
                continue;
            ic_candidate cd;
            cd.p = p[i];
            cd.n = n[i];
            cd.footprint = 0.0f; /* no pixel: only the world-space radius bounds apply */
            cd.key = ic_hash4(POINT_KEY_TAG, i, (uint64_t)round, 0);
            ic_gather_point gp = ic_ic_gather_point_of(&cd);
            ic_gather_result gr;
            ic_vec3 levels[IC_LEVELS_MAX + 1];
            r = ic_ic_gather_one(&worker, g, &gp, &gr, levels);
            if (r != IC_OK) {
                ic_error_set(err, r, "gathering failed at sensor point %u", i);
                break;
            }
            ic_record rec;
            ic_ic_record_from_gather(c, &cd, &gr, &rec);
            uint32_t index = 0;
            r = ic_cache_insert(c->cache, &rec, &index, err);
            if (r == IC_OK)
                r = ic_ic_keep_levels(c, index, 1, levels, err);
            ++added;
        }
        if (added == 0)
            break;
    }
    ic_gatherer_destroy(g);
    if (r == IC_OK)
        r = ic_cache_freeze(c->cache, err);
    return r;
}

int ic_ic_points_indirect(const ic_ctx *c, ic_vec3 p, ic_vec3 n, ic_vec3 *E, ic_vec3 *sigma, double *sigma_lum)
{
    ic_cache_contribution contrib[CONTRIBUTION_CAPACITY];
    ic_cache_lookup q = ic_cache_lookup_at(p, n, IC_ACCEPT_FINAL);
    q.contributions = contrib;
    q.contribution_capacity = CONTRIBUTION_CAPACITY;
    ic_cache_estimate e;
    if (!ic_cache_query(c->cache, &q, &e))
        return 0;
    *E = e.irradiance;
    /* The estimate is Σ w_i E_i / Σ w_i over records whose noise is independent (each gathered its own
     * rays): its variance is Σ w_i² σ_i² / (Σ w_i)². A record's channels share its rays, so the σ of its
     * luminance is bounded by the weighted sum of the channels' σ (full correlation). Only the first
     * CONTRIBUTION_CAPACITY contributors are weighed; the rest, if any, change the weights little. */
    double var[3] = {0.0, 0.0, 0.0}, var_lum = 0.0, wsum = 0.0;
    for (uint32_t k = 0; k < e.contributions_written; ++k) {
        ic_record rec;
        if (ic_cache_get_record(c->cache, contrib[k].record, &rec) != IC_OK)
            continue;
        double w = contrib[k].weight, s[3] = {rec.sigma.x, rec.sigma.y, rec.sigma.z};
        for (int ch = 0; ch < 3; ++ch)
            var[ch] += w * w * s[ch] * s[ch];
        double sl = IC_LUMINANCE_R * s[0] + IC_LUMINANCE_G * s[1] + IC_LUMINANCE_B * s[2];
        var_lum += w * w * sl * sl;
        wsum += w;
    }
    double inv = wsum > 0.0 ? 1.0 / wsum : 0.0;
    *sigma = v3((float)(sqrt(var[0]) * inv), (float)(sqrt(var[1]) * inv), (float)(sqrt(var[2]) * inv));
    *sigma_lum = sqrt(var_lum) * inv;
    return 1;
}
