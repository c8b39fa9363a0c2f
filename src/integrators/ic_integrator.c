/*
 * ic_integrator.c — irradiance caching behind the integrator interface (integrator.h).
 *
 * prepare: the shading points and an empty cache (ic_context.c), then the records: loaded from a cache
 * file, or built by the strategy of the options (a table of peers, ic_build_fn) and re-indexed for the
 * final render; saved if asked. sample: the final render (ic_final.c), reading the cache without
 * changing it. aovs: the indirect image (the film again, same samples), and the diagnostics (ic_aov.c).
 */
#include "ic_internal.h"

#include "core/threads.h"
#include "film/film.h"

#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Smallest, mean and largest influence radius a_i·R_i of the records and how many are ellipses (the stats' record
 * extents), the hit stage's records counted apart. */
static void record_extents(const ic_cache *cache, ic_render_stats *st)
{
    uint32_t n = ic_cache_count(cache), hit = 0, ellipses = 0;
    double sum = 0.0;
    float lo = INFINITY, hi = 0.0f;
    for (uint32_t i = 0; i < n; ++i) {
        ic_record r;
        ic_cache_get_record(cache, i, &r);
        if (r.bounce == IC_HIT_KIND) { /* the hit stage's: not the image's records */
            ++hit;
            continue;
        }
        ellipses += r.ellipse_ratio > 0.0f && r.ellipse_ratio < 1.0f;
        float e = r.accuracy * r.radius;
        sum += e;
        lo = fminf(lo, e);
        hi = fmaxf(hi, e);
    }
    st->hit_records = hit;
    n -= hit;
    st->extent_min = n ? lo : 0.0f;
    st->extent_mean = n ? (float)(sum / n) : 0.0f;
    st->extent_max = hi;
    st->ellipse_records = ellipses;
}

static const ic_build_fn strategies[] = {
    [IC_STRATEGY_BATCH] = ic_ic_build_batch,
    [IC_STRATEGY_LAZY] = ic_ic_build_lazy,
    [IC_STRATEGY_ADAPTIVE] = ic_ic_build_adaptive,
};
#define STRATEGY_COUNT (sizeof strategies / sizeof strategies[0])

ic_result ic_ic_build(ic_ctx *c, const ic_render_options *opt, ic_render_stats *st, phase_times *pt, ic_error *err)
{
    if ((unsigned)c->o.strategy >= STRATEGY_COUNT)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "unknown cache strategy %d; use batch, lazy or adaptive",
                            (int)c->o.strategy);
    return strategies[c->o.strategy](c, opt, st, pt, err);
}

/* The integrator's state. The final render's context comes first: the film calls ic_ic_final_sample
 * with this state's address, which is that of its first member. */
typedef struct ic_state {
    ic_final_ctx fc;
    const ic_tracer *tr;
    const ic_render_options *opt;
    ic_ctx *c;
} ic_state;

/* The cache file's records: read by rank 0 alone and broadcast (only it needs the file), then decoded and
 * checked by every rank alike; rank 0's error, when it cannot read the file, becomes every rank's. */
static ic_result load_records(ic_ctx *c, ic_cache **out, ic_error *err)
{
    char settings[IC_RECORDS_SETTINGS_BYTES];
    uint64_t hash = ic_ic_records_identity(c, settings, sizeof settings);
    if (!ic_comm_is_shared(c->comm))
        return ic_cache_load_with_settings(c->o.load_cache, &c->o.cache, hash, settings, out, err);
    struct {
        int64_t result;
        uint64_t size;
        ic_error error;
    } head;
    memset(&head, 0, sizeof head);
    void *data = NULL;
    size_t size = 0;
    if (c->comm->rank == 0) {
        head.result = ic_cache_read_file(c->o.load_cache, &c->o.cache, &data, &size, &head.error);
        head.size = size;
    }
    ic_result r = ic_comm_broadcast(c->comm, &head, sizeof head, 0, err);
    if (r != IC_OK || head.result != IC_OK) {
        free(data);
        if (r == IC_OK)
            *err = head.error;
        return r != IC_OK ? r : (ic_result)head.result;
    }
    if (c->comm->rank != 0 && !(data = malloc(head.size ? head.size : 1)))
        return ic_error_set(err, IC_ERR_OOM, "out of memory for the %llu bytes of %s",
                            (unsigned long long)head.size, c->o.load_cache);
    r = ic_comm_broadcast(c->comm, data, head.size, 0, err);
    if (r == IC_OK)
        r = ic_cache_load_memory_with_settings(c->o.load_cache, data, head.size, &c->o.cache, hash, settings, out,
                                               err);
    free(data);
    return r;
}

/* The records to the cache file, with the settings that shaped them (a later load that refuses it names the
 * one that differs). */
static ic_result save_records(const ic_ctx *c, ic_error *err)
{
    char settings[IC_RECORDS_SETTINGS_BYTES];
    uint64_t hash = ic_ic_records_identity(c, settings, sizeof settings);
    return ic_cache_save_with_settings(c->cache, c->o.save_cache, hash, settings, err);
}

/* The records: loaded (refused, with the cache library's message, when made for another scene, other
 * gathering settings or other cache parameters), or built and re-indexed. Adds construction's own time,
 * outside gathering, insertion and the phases a strategy reports itself, to *t_candidates. */
static ic_result make_records(ic_state *s, ic_render_stats *st, phase_times *pt, double *t_candidates, ic_error *err)
{
    ic_ctx *c = s->c;
    if (c->o.load_cache) {
        ic_cache *loaded = NULL;
        double t0 = ic_seconds();
        ic_result r = load_records(c, &loaded, err);
        if (r != IC_OK)
            return r;
        ic_cache_destroy(c->cache);
        c->cache = loaded;
        pt->insert += ic_seconds() - t0;
        return ic_ic_levels_from_payloads(c, err);
    }
    double t0 = ic_seconds();
    int phases_before = st->phase_count;
    ic_result r = ic_ic_build(c, s->opt, st, pt, err);
    if (r != IC_OK)
        return r;
    /* Discontinuity maps, look-up sweeps, world-stage paths, clustering for batch; the raster sweep
     * for lazy. */
    double own = 0.0;
    for (int k = phases_before; k < st->phase_count; ++k)
        own += st->phases[k].seconds;
    *t_candidates = fmax(ic_seconds() - t0 - pt->gather - pt->insert - own, 0.0);
    if (c->o.record_filter.mode != IC_CACHE_OFF) {
        double tf = ic_seconds();
        r = ic_ic_filter_cache(c->cache, c->threads, c->comm, c->o.record_filter.value, err);
        if (r != IC_OK)
            return r;
        ic_stats_add_phase(st, "record filter", ic_seconds() - tf);
    }
    /* Radiance records after the irradiance ones: their hemisphere rays read those at diffuse hits. */
    uint32_t made = 0, refined = 0;
    if ((r = ic_ic_radiance_build(c, s->opt, pt, &made, &refined, err)) != IC_OK)
        return r;
    st->refinements += refined;
    /* The final render reads a freshly built index: look-ups are faster than through the incrementally
     * grown one, and the summation order of every look-up is the same as after loading a cache file, so
     * a saved and re-loaded cache renders the identical image. The hit stage's records have served
     * their hemisphere rays; disabled, they stay in the cache (and its file) but not in the index. */
    t0 = ic_seconds();
    for (uint32_t i = 0, n = ic_cache_count(c->cache); i < n && r == IC_OK; ++i) {
        ic_record rec;
        ic_cache_get_record(c->cache, i, &rec);
        if (rec.bounce == IC_HIT_KIND)
            r = ic_cache_set_record_flags(c->cache, i, (uint8_t)(rec.flags | IC_RECORD_DISABLED));
    }
    if (r == IC_OK)
        r = ic_cache_rebuild_index(c->cache, err);
    pt->insert += ic_seconds() - t0;
    return r;
}

static ic_result ic_prepare(void *self, ic_render_stats *st, ic_error *err)
{
    ic_state *s = self;
    double t_gbuffer = 0.0, t_candidates = 0.0;
    phase_times pt = {0};
    ic_result r = ic_ic_ctx_create(s->tr, s->opt, &s->c, &t_gbuffer, err);
    if (r == IC_OK)
        r = ic_ic_radiance_create(s->c, err); /* lobe tables, before a cache file is checked against them */
    if (r != IC_OK)
        return r;
    ic_ctx *c = s->c;
    if ((r = make_records(s, st, &pt, &t_candidates, err)) != IC_OK)
        return r;
    /* A cache file that cannot be written costs the file, not the render: the caller reports it. */
    st->save_error[0] = '\0';
    ic_error save_err = {0};
    /* Every process holds the same cache (the level payloads too); rank 0 alone writes it. An interrupted
     * construction's records are not saved: a later --load-cache would take them for a whole cache (a
     * SIGINT during the hit stage left a file of hit records only, which then rendered without a word). */
    if (c->o.save_cache && ic_ic_cancelled(c))
        snprintf(st->save_error, sizeof st->save_error, "%s: not written: the render was interrupted while the cache "
                 "was being built, so it is incomplete", c->o.save_cache);
    else if (c->o.save_cache && (ic_ic_levels_to_payloads(c, &save_err) != IC_OK ||
                            (ic_comm_rank(c->comm) == 0 &&
                             save_records(c, &save_err) != IC_OK)))
        snprintf(st->save_error, sizeof st->save_error, "%s", save_err.message);
    st->records = ic_cache_count(c->cache);
    st->radiance_records = 0;
    for (uint32_t i = 0; c->rad && i < st->records; ++i) {
        ic_record rec;
        ic_cache_get_record(c->cache, i, &rec);
        st->radiance_records += rec.bounce >= IC_BOUNCE_RADIANCE;
    }
    st->radiance_record_bytes = c->rad ? (uint32_t)(ic_cache_bytes_per_record() +
                                                    sizeof(float) * ic_ic_radiance_payload_floats(c->rad))
                                       : 0;
    record_extents(c->cache, st);
    st->cached_emitters = c->cached_emitters;
    st->gather_rays = atomic_load(&c->rays);
    st->rank_records_gathered = c->gathered;
    st->rays = st->gather_rays; /* the driver adds the final render's */

    int hint_count = ic_resolve_threads(s->opt->threads);
    s->fc.c = c;
    s->fc.hints = calloc((size_t)hint_count, sizeof *s->fc.hints);
    s->fc.hint_count = s->fc.hints ? hint_count : 0; /* no hints: slower, the same image */
    r = ic_pixel_lights_init(&s->fc.lights, s->tr->scene, c->light_sel, hint_count, c->g.width, c->g.height);
    if (r != IC_OK)
        return ic_error_set(err, r, "out of memory for the per-thread light tables");
    /* The final render's own phase follows (the driver adds it). */
    if (st->phase_count + 5 <= IC_MAX_PHASES) {
        ic_stats_add_phase(st, "shading points", t_gbuffer);
        ic_stats_add_phase(st, "candidates", t_candidates);
        ic_stats_add_phase(st, "gathering", pt.gather);
        ic_stats_add_phase(st, "insertion", pt.insert);
    }
    return IC_OK;
}

static ic_result ic_aovs(void *self, const ic_image *beauty, const ic_image_loop *loop_in,
                         const ic_image_loop_result *lr, ic_render_aovs *a, int *cancelled, ic_error *err)
{
    ic_state *s = self;
    const ic_ctx *c = s->c;
    ic_pixel_lights_free(&s->fc.lights); /* the indirect AOV samples no lights */
    /* The film again with the same samples, returning one term of the first shading point. */
    int *modes[2] = {&s->fc.indirect_only, &s->fc.glossy_only};
    const int wanted[2] = {a->want_indirect, a->want_glossy};
    ic_image *images[2] = {&a->indirect, &a->glossy};
    const char *phases[2] = {"indirect AOV", "glossy AOV"};
    for (int k = 0; k < 2; ++k) {
        if (!wanted[k])
            continue;
        ic_image_loop loop = *loop_in;
        *modes[k] = 1;
        loop.phase = phases[k];
        loop.time_budget = 0.0;
        loop.adaptive = 0;
        loop.spp = lr->spp_done;
        ic_image_loop_result lr2;
        ic_result r = ic_render_image(&loop, ic_ic_final_sample, &s->fc, images[k], &lr2, err);
        *modes[k] = 0;
        if (r != IC_OK)
            return r;
        if (lr2.cancelled)
            *cancelled = 1;
    }
    ic_result r;
    if (a->want_records && (r = ic_ic_records_image(c, beauty, &a->records)) != IC_OK)
        return ic_error_set(err, r, "out of memory for the records AOV");
    if (a->want_record_list && (r = ic_ic_record_views(c, &a->record_views, &a->record_view_count)) != IC_OK)
        return ic_error_set(err, r, "out of memory for the record list");
    if (a->want_density && (r = ic_ic_density_image(s->c, &a->density)) != IC_OK)
        return ic_error_set(err, r, "out of memory for the density AOV");
    if (a->want_amap && (r = ic_ic_amap_image(c, &a->amap)) != IC_OK)
        return ic_error_set(err, r, "out of memory for the amap AOV");
    return IC_OK;
}

static void ic_destroy(void *self)
{
    ic_state *s = self;
    ic_pixel_lights_free(&s->fc.lights);
    free(s->fc.hints);
    if (s->c)
        ic_ic_radiance_destroy(s->c->rad);
    ic_ic_ctx_destroy(s->c);
    free(s);
}

static const ic_integrator_ops ic_ops = {
    .loop_phase = "final render",
    .stats_phase = "final render",
    .adaptive_by_default = 1, /* as Frolov et al. 2012 §3.2's final render does, where it can */
    .prepare = ic_prepare,
    .sample = ic_ic_final_sample,
    .aovs = ic_aovs,
    .destroy = ic_destroy,
};

ic_result ic_ic_integrator_create(const ic_tracer *tr, const ic_render_options *opt, ic_integrator_obj *out,
                                  ic_error *err)
{
    out->ops = &ic_ops;
    ic_state *s = calloc(1, sizeof *s);
    out->self = s;
    if (!s)
        return ic_error_set(err, IC_ERR_OOM, "out of memory");
    s->tr = tr;
    s->opt = opt;
    /* Checked before any construction work (the shading points alone take a pass over the image). */
    if (opt->ic.strategy == IC_STRATEGY_LAZY && opt->comm && opt->comm->size > 1)
        return ic_error_set(err, IC_ERR_UNSUPPORTED, "the lazy strategy builds the cache one shading point at a "
                            "time, each gather needing every record before it, so it cannot be shared among "
                            "%d processes; use --strategy batch or adaptive, or run one process",
                            opt->comm->size);
    if (opt->ic.recursive && opt->ic.strategy != IC_STRATEGY_LAZY)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "recursive caching builds its levels lazily; use the lazy strategy");
    if ((unsigned)opt->ic.error > IC_ERROR_HESSIAN)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "error metric %d unknown", (int)opt->ic.error);
    if ((unsigned)opt->ic.record_shape > IC_SHAPE_ELLIPTICAL)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "record shape %d unknown", (int)opt->ic.record_shape);
    if (opt->ic.record_shape == IC_SHAPE_ELLIPTICAL && opt->ic.error != IC_ERROR_HESSIAN)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "elliptical records take their axes from the irradiance "
                            "Hessian; add --error hessian, or use round records");
    if (opt->ic.error == IC_ERROR_HESSIAN && opt->ic.gather.method == IC_GATHER_PROGRESSIVE)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "the Hessian error metric needs the stratified or hemicube "
                            "gather (the progressive sampler has no Hessian)");
    return IC_OK;
}
