/*
 * ic_lazy.c — lazy construction (`--strategy lazy`, Ward et al. 1988): the pixel centres' shading points
 * in raster order, a look-up at each, and on a miss one record gathered and inserted; serial, the
 * reference for the other strategies. With `--recursive`, one cache level per bounce (Radiance's -ab).
 */
#include "ic_internal.h"

#include "film/film.h"

#include <stdatomic.h>
#include <string.h>

/* Recursive caching (Radiance's -ab): one cache level per bounce, all in the one cache, told apart by the
 * records' bounce field. A hemisphere ray of a level-k record returns the environment when it escapes
 * and, at a hit, that surface's direct light (as the final render computes it: environment excluded)
 * plus its diffuse reflection of the level-(k+1) irradiance, looked up in the cache and gathered (and
 * inserted) on a miss; the last level returns direct light only. Construction is serial (lazy), each
 * level with a gatherer of its own, so the recursion never reuses a gatherer's scratch space. */
typedef struct lazy_level {
    ic_ctx *c;
    int level;
    struct lazy_state *state;
} lazy_level;

#define MAX_LEVELS 16

typedef struct lazy_state {
    ic_ctx *c;
    ic_gatherer *g[MAX_LEVELS];
    lazy_level levels[MAX_LEVELS];
    ic_gather_worker worker;   /* the non-recursive gatherer's (bounce levels of hit look-ups) */
    int level_count;
    phase_times *pt;
    ic_result status;          /* first failure inside the recursion (gathering or insertion) */
    ic_error err;
} lazy_state;

static ic_vec3 level_irradiance(lazy_state *ls, int level, const ic_surface *s, ic_vec3 n, float footprint);

static void recursive_trace(void *user, const ic_vec3 *origins, const ic_vec3 *dirs, uint32_t count, float *hit_dist,
                            ic_vec3 *radiance)
{
    lazy_level *lv = user;
    lazy_state *ls = lv->state;
    ic_ctx *c = lv->c;
    uint64_t nrays = 0;
    for (uint32_t j = 0; j < count; ++j) {
        ic_ray ray = {origins[j], dirs[j], 0.0f, INFINITY};
        ic_hit hit;
        ++nrays;
        ic_accel_intersect1(c->tr->accel, &ray, &hit);
        if (hit.triangle == IC_NO_HIT) {
            hit_dist[j] = INFINITY;
            radiance[j] = ic_scene_env_radiance(c->tr->scene, ray.dir);
            continue;
        }
        hit_dist[j] = hit.t;
        ic_surface s;
        ic_scene_surface(c->tr->scene, hit.triangle, hit.u, hit.v, &s);
        ic_vec3 wo = v3_neg(ray.dir);
        ic_bsdf b;
        ic_bsdf_init(&b, c->tr->scene, &s, wo);
        radiance[j] = ic_ic_cached_emission(c, &ray, &hit);
        if (!ic_bsdf_has_smooth(&b))
            continue; /* mirrors and glass seen by hemisphere rays: not followed (as Radiance's ambient) */
        ic_rng rng = ic_rng_make(c->seed, (uint64_t)lv->level, hit.triangle,
                                 ((uint64_t)(uint32_t)(hit.u * 4294967040.0f) << 32) | (uint32_t)(hit.v * 4294967040.0f));
        /* The last level has no cache behind its hits: their direct light comes from every emitter. */
        int last = lv->level + 1 >= ls->level_count;
        ic_vec3 L = ic_ic_direct_light(c, &s, &b, wo, last ? &c->light_sel_all : NULL, &rng, &nrays);
        if (!last && ls->status == IC_OK) {
            /* Deeper levels get the footprint of a pixel 1/128 of the scene wide, so the pixel bounds
             * keep their records at least ~1/85 of it apart (Radiance's -ar 128 plays this part); the
             * scene's width as the camera sees it (ic_ctx.work_extent), not a ground plane's outside. */
            ic_vec3 E = level_irradiance(ls, lv->level + 1, &s, b.cache_n, c->work_extent / 128.0f);
            L = v3_add(L, v3_mul(v3_scale(b.kd, IC_INV_PI), E));
        }
        radiance[j] = v3_add(radiance[j], L);
    }
    atomic_fetch_add_explicit(&c->rays, nrays, memory_order_relaxed);
}

/* Irradiance of cache level `level` at a surface point: interpolated, or gathered and inserted. */
static ic_vec3 level_irradiance(lazy_state *ls, int level, const ic_surface *s, ic_vec3 n, float footprint)
{
    ic_ctx *c = ls->c;
    ic_cache_lookup q = ic_cache_lookup_at(s->p, n, IC_ACCEPT_CONSTRUCTION);
    q.bounce = (uint32_t)level;
    ic_cache_estimate e;
    if (ic_cache_query(c->cache, &q, &e))
        return e.irradiance;
    ic_candidate cd;
    cd.p = s->p;
    cd.n = n;
    cd.footprint = footprint;
    cd.key = ic_hash4(c->seed, (uint64_t)level, ic_cache_count(c->cache), 0x726563ULL);
    ic_gather_point gp = ic_ic_gather_point_of(c, &cd);
    ic_gather_result gr;
    ic_result r = ic_ic_gather_by_method(c, ls->g[level], &gp, &gr);
    if (r != IC_OK) {
        if (ls->status == IC_OK)
            ls->status = ic_error_set(&ls->err, r, "gathering a level-%d record failed", level);
        return v3s(0.0f);
    }
    ic_record rec;
    ic_ic_record_from_gather(c, &cd, &gr, &rec);
    rec.bounce = (uint8_t)level;
    if (ls->status == IC_OK)
        ls->status = ic_cache_insert(c->cache, &rec, NULL, &ls->err);
    return gr.irradiance;
}

ic_result ic_ic_build_lazy(ic_ctx *c, const ic_render_options *opt, ic_render_stats *st, phase_times *pt,
                            ic_error *err)
{
    lazy_state ls;
    memset(&ls, 0, sizeof ls);
    ls.c = c;
    ls.worker.c = c;
    ls.pt = pt;
    ls.level_count = c->o.recursive ? (c->o.bounces < MAX_LEVELS ? c->o.bounces : MAX_LEVELS) : 1;
    ic_result r = IC_OK;
    for (int k = 0; k < ls.level_count && r == IC_OK; ++k) {
        ls.levels[k].c = c;
        ls.levels[k].level = k;
        ls.levels[k].state = &ls;
        r = c->o.recursive ? ic_gatherer_create(&c->o.gather, recursive_trace, &ls.levels[k], &ls.g[k], err)
                           : ic_gatherer_create(&c->o.gather, ic_ic_gather_trace, &ls.worker, &ls.g[k], err);
    }
    size_t npix = (size_t)c->g.width * c->g.height;
    double t_insert = 0.0, t0 = ic_seconds();
    /* Raster order, then again while a pixel lost its cover to a later record's neighbor clamping. An
     * interrupt or the time budget's construction share stops it at the next pixel: the points left
     * uncovered take the final render's fallback. */
    int stopped = 0;
    for (int round = 0; round < 8 && r == IC_OK && !stopped; ++round) {
        uint32_t added = 0;
        for (size_t i = 0; i < npix && r == IC_OK; ++i) {
            if ((i & 4095) == 0 && round == 0)
                ic_ic_report(opt, "lazy cache", (double)i / (double)npix);
            if ((stopped = ic_ic_out_of_time(c)) != 0)
                break;
            if (!c->g.valid[i])
                continue;
            ic_cache_lookup q = ic_cache_lookup_at(c->g.p[i], c->g.n[i], IC_ACCEPT_CONSTRUCTION);
            ic_cache_estimate e;
            if (ic_cache_query(c->cache, &q, &e))
                continue;
            ic_candidate cd = ic_ic_candidate_at_pixel(c, (uint32_t)i, (uint64_t)round);
            ic_gather_point gp = ic_ic_gather_point_of(c, &cd);
            ic_gather_result gr;
            ic_vec3 levels[IC_LEVELS_MAX + 1];
            r = c->o.recursive ? ic_ic_gather_by_method(c, ls.g[0], &gp, &gr)
                               : ic_ic_gather_one(&ls.worker, ls.g[0], &gp, &gr, levels);
            if (r != IC_OK) {
                ic_error_set(err, r, "gathering failed at pixel %zu", i);
                break;
            }
            if (ls.status != IC_OK) {
                r = ic_error_set(err, ls.status, "%s", ls.err.message);
                break;
            }
            ic_record rec;
            ic_ic_record_from_gather(c, &cd, &gr, &rec);
            double t1 = ic_seconds();
            uint32_t index = 0;
            r = ic_cache_insert(c->cache, &rec, &index, err);
            if (r == IC_OK)
                r = ic_ic_keep_levels(c, index, 1, levels, err);
            t_insert += ic_seconds() - t1;
            ++added;
        }
        if (added == 0)
            break;
    }
    /* Deeper levels insert inside the gathering; the split is approximate for recursive caching. */
    pt->insert += t_insert;
    pt->gather += ic_seconds() - t0 - t_insert;
    for (int k = 0; k < ls.level_count; ++k)
        ic_gatherer_destroy(ls.g[k]);
    ic_ic_gather_worker_release(&ls.worker);
    st->passes = 1;
    st->records_per_pass[0] = ic_cache_count(c->cache);
    st->cut_short = stopped;
    st->cut_by_time = stopped && !ic_ic_cancelled(c);
    return r;
}
