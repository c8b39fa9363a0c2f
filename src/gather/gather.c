/*
 * gather.c — gatherer lifecycle, option defaults and validation, and the threaded batch helper
 * (include/irrcache/gather.h).
 *
 * A gatherer's buffers are sized once, at creation, for the larger of the stratified grid (M·N cells)
 * and the progressive last round (max_rays cells), so no gather allocates per ray. ic_gather_batch
 * makes one gatherer per thread and hands out fixed chunks of points through ic_parallel_for; every
 * point's result depends only on (seed, key), and is written to its own slot, so the output is the same
 * for any thread count.
 */
#include "gather_internal.h"

#include "irrcache/defaults.h"

#include "core/threads.h"

#include <stdatomic.h>
#include <stdlib.h>

/* Beyond 2^24 rays per grid the float directions and 24-bit radical inverses stop being exact. */
#define MAX_GRID_RAYS (1u << 24)
/* Points per work item of ic_gather_batch: enough to amortise scheduling, small enough to balance. */
#define BATCH_CHUNK_POINTS 8u

static int is_pow2(uint32_t x) { return x && !(x & (x - 1)); }

void ic_gather_opts_default(ic_gather_opts *o)
{
    *o = (ic_gather_opts){0};
    o->method = IC_GATHER_STRATIFIED;
    o->theta_strata = IC_DEFAULT_THETA_STRATA;
    o->phi_strata = IC_DEFAULT_PHI_STRATA; /* ≈ π·M (Ward et al. 1988) */
    o->tgrad = IC_GATHER_TGRAD_IMPROVED;
    o->first_round_rays = 4096;
    o->max_rays = 65536;
    o->round_growth = 4;
    o->threshold = 0.02f;
    o->batch_rays = 4096;
    o->hemicube_resolution = 16; /* 768 rays: nearest to the 800 of the stratified default (BENCHMARKS.md) */
}

/* Fills zero fields with defaults and checks the result. */
static ic_result resolve_opts(const ic_gather_opts *in, ic_gather_opts *o, ic_error *err)
{
    ic_gather_opts d;
    ic_gather_opts_default(&d);
    *o = in ? *in : d;
    if (!o->theta_strata)
        o->theta_strata = d.theta_strata;
    if (!o->phi_strata) {
        /* round(π·M) past 2^32 would wrap (to 0 for M = 1367130513, an empty grid the size check passes):
         * any M above the ray limit is refused below, so saturate. */
        long long phi = llround((double)IC_PI * o->theta_strata);
        o->phi_strata = phi > (long long)UINT32_MAX ? UINT32_MAX : (uint32_t)phi;
    }
    if (!o->first_round_rays)
        o->first_round_rays = d.first_round_rays;
    if (!o->max_rays)
        o->max_rays = o->first_round_rays > d.max_rays ? o->first_round_rays : d.max_rays;
    if (!o->round_growth)
        o->round_growth = d.round_growth;
    if (o->threshold == 0.0f)
        o->threshold = d.threshold;
    if (!o->batch_rays)
        o->batch_rays = d.batch_rays;
    if (!o->hemicube_resolution)
        o->hemicube_resolution = d.hemicube_resolution;

    if ((unsigned)o->method > IC_GATHER_HEMICUBE)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "gather: unknown method %d; use IC_GATHER_STRATIFIED, "
                            "IC_GATHER_PROGRESSIVE or IC_GATHER_HEMICUBE", (int)o->method);
    if (o->hemicube_resolution % 2 || o->hemicube_resolution > IC_GATHER_MAX_HEMICUBE)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "gather: hemicube_resolution %u must be even and at most %u",
                            o->hemicube_resolution, IC_GATHER_MAX_HEMICUBE);
    if ((unsigned)o->tgrad > IC_GATHER_TGRAD_WARD_HECKBERT)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "gather: unknown translational-gradient form %d", (int)o->tgrad);
    if ((uint64_t)o->theta_strata * o->phi_strata > MAX_GRID_RAYS)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "gather: %u×%u strata exceed %u rays; use fewer strata",
                            o->theta_strata, o->phi_strata, MAX_GRID_RAYS);
    if (!is_pow2(o->first_round_rays) || o->first_round_rays < 64 || !is_pow2(o->max_rays) ||
        o->max_rays < o->first_round_rays || o->max_rays > MAX_GRID_RAYS)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "gather: progressive rounds need powers of two with "
                            "64 <= first_round_rays (%u) <= max_rays (%u) <= %u", o->first_round_rays,
                            o->max_rays, MAX_GRID_RAYS);
    if (!is_pow2(o->round_growth) || o->round_growth < 2 || o->round_growth > 256)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "gather: round_growth %u must be a power of two in [2, 256]",
                            o->round_growth);
    if (!isfinite(o->threshold))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "gather: threshold must be finite");
    /* Whole groups of 32 rays per trace call (Frolov et al. 2012 §4.1), but never fewer than 32. */
    o->batch_rays = o->batch_rays < 32 ? 32 : o->batch_rays & ~31u;
    return IC_OK;
}

ic_result ic_gatherer_create(const ic_gather_opts *opts, ic_trace_fn trace, void *user, ic_gatherer **out,
                             ic_error *err)
{
    if (!out)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "gather: out is NULL");
    *out = NULL;
    if (!trace)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "gather: no trace callback given");
    ic_gatherer *g = calloc(1, sizeof *g);
    if (!g)
        return ic_error_set(err, IC_ERR_OOM, "gather: out of memory creating a gatherer");
    ic_result res = resolve_opts(opts, &g->opts, err);
    if (res != IC_OK) {
        free(g);
        return res;
    }
    g->trace = trace;
    g->user = user;
    const uint32_t grid = g->opts.theta_strata * g->opts.phi_strata;
    const uint32_t hemicube = 3 * g->opts.hemicube_resolution * g->opts.hemicube_resolution;
    g->cell_capacity = grid > g->opts.max_rays ? grid : g->opts.max_rays;
    if (hemicube > g->cell_capacity)
        g->cell_capacity = hemicube;
    g->batch = g->opts.batch_rays < g->cell_capacity ? g->opts.batch_rays : g->cell_capacity;

    const size_t cells = g->cell_capacity, rays = g->batch;
    g->cell_dir = malloc(cells * sizeof *g->cell_dir);
    g->cell_radiance = malloc(cells * sizeof *g->cell_radiance);
    g->cell_dist = malloc(cells * sizeof *g->cell_dist);
    g->cell_half = malloc(cells * sizeof *g->cell_half);
    g->ray_org = malloc(rays * sizeof *g->ray_org);
    g->ray_dir = malloc(rays * sizeof *g->ray_dir);
    g->ray_radiance = malloc(rays * sizeof *g->ray_radiance);
    g->ray_dist = malloc(rays * sizeof *g->ray_dist);
    g->ray_cell = malloc(rays * sizeof *g->ray_cell);
    g->tan_scratch = malloc(cells * sizeof *g->tan_scratch);
    if (!g->tan_scratch || !g->cell_dir || !g->cell_radiance || !g->cell_dist || !g->cell_half || !g->ray_org || !g->ray_dir ||
        !g->ray_radiance || !g->ray_dist || !g->ray_cell) {
        ic_gatherer_destroy(g);
        return ic_error_set(err, IC_ERR_OOM, "gather: out of memory for %zu-cell buffers", cells);
    }
    /* Hemicube tables (~0.5 ms at N = 16, BENCHMARKS.md) only for a hemicube gatherer or an explicit
     * resolution, so other gatherers cost what they did; on request, the grid's wall factors. */
    const int wants_hemicube = g->opts.method == IC_GATHER_HEMICUBE || (opts && opts->hemicube_resolution);
    if ((wants_hemicube && ic_gather_hemicube_init(g) != IC_OK) ||
        (g->opts.with_hessian && ic_gather_hessian_init(g) != IC_OK)) {
        ic_gatherer_destroy(g);
        return ic_error_set(err, IC_ERR_OOM, "gather: out of memory for the hemicube and Hessian tables");
    }
    *out = g;
    return IC_OK;
}

void ic_gatherer_destroy(ic_gatherer *g)
{
    if (!g)
        return;
    free(g->cell_dir);
    free(g->cell_radiance);
    free(g->cell_dist);
    free(g->cell_half);
    free(g->ray_org);
    free(g->ray_dir);
    free(g->ray_radiance);
    free(g->ray_dist);
    free(g->ray_cell);
    free(g->tan_scratch);
    ic_gather_hemicube_free(g);
    free(g->grid_walls);
    free(g);
}

const ic_gather_opts *ic_gatherer_opts(const ic_gatherer *g) { return g ? &g->opts : NULL; }

typedef struct batch_ctx {
    ic_gatherer **gatherers;         /* one per thread */
    const ic_gather_point *pts;
    ic_gather_result *out;
    uint32_t count;
    atomic_int status;               /* first failure, IC_OK if none */
} batch_ctx;

static void batch_item(void *p, int64_t item, int thread)
{
    batch_ctx *ctx = p;
    ic_gatherer *g = ctx->gatherers[thread];
    const uint32_t first = (uint32_t)item * BATCH_CHUNK_POINTS;
    const uint32_t n = ctx->count - first < BATCH_CHUNK_POINTS ? ctx->count - first : BATCH_CHUNK_POINTS;
    ic_result res = IC_OK;
    if (g->opts.method == IC_GATHER_PROGRESSIVE) {
        res = ic_gather_progressive(g, ctx->pts + first, n, ctx->out + first);
    } else if (g->opts.method == IC_GATHER_HEMICUBE) {
        for (uint32_t i = 0; i < n && res == IC_OK; ++i)
            res = ic_gather_hemicube(g, &ctx->pts[first + i], &ctx->out[first + i]);
    } else {
        for (uint32_t i = 0; i < n && res == IC_OK; ++i)
            res = ic_gather_stratified(g, &ctx->pts[first + i], &ctx->out[first + i]);
    }
    if (res != IC_OK) {
        int expected = IC_OK;
        atomic_compare_exchange_strong(&ctx->status, &expected, (int)res);
    }
}

ic_result ic_gather_batch(const ic_gather_opts *opts, ic_trace_fn trace, void *user, int threads,
                          const ic_gather_point *pts, uint32_t count, ic_gather_result *out, ic_error *err)
{
    if (count && (!pts || !out))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "gather: NULL points or results");
    if (count == 0)
        return IC_OK;
    const int64_t items = ((int64_t)count + BATCH_CHUNK_POINTS - 1) / BATCH_CHUNK_POINTS;
    int n_threads = ic_resolve_threads(threads);
    if (n_threads > items)
        n_threads = (int)items;

    batch_ctx ctx;
    ctx.gatherers = calloc((size_t)n_threads, sizeof *ctx.gatherers);
    if (!ctx.gatherers)
        return ic_error_set(err, IC_ERR_OOM, "gather: out of memory for %d gatherers", n_threads);
    ic_result res = IC_OK;
    for (int t = 0; t < n_threads && res == IC_OK; ++t)
        res = ic_gatherer_create(opts, trace, user, &ctx.gatherers[t], err);
    if (res == IC_OK) {
        ctx.pts = pts;
        ctx.out = out;
        ctx.count = count;
        atomic_init(&ctx.status, IC_OK);
        res = ic_parallel_for(n_threads, items, batch_item, &ctx);
        if (res != IC_OK)
            ic_error_set(err, res, "gather: could not start %d threads", n_threads);
        else if ((res = (ic_result)atomic_load(&ctx.status)) != IC_OK)
            ic_error_set(err, res, "gather: a point failed (%s): check that normals are non-zero and "
                         "positions finite", ic_result_name(res));
    }
    for (int t = 0; t < n_threads; ++t)
        ic_gatherer_destroy(ctx.gatherers[t]);
    free(ctx.gatherers);
    return res;
}
