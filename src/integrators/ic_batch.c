/*
 * ic_batch.c — batch construction (`--strategy batch`, the default), Frolov et al. 2012 §3.1 step by step:
 *   pass 0      primary position/normal buffers → geometry discontinuity on a mip pyramid → blend →
 *               deterministic dithering → candidates (ic_screen.c);
 *   passes 1…n  screen stage (first `screen_passes` passes): irradiance discontinuity of the current
 *               cache look-ups, same pyramid and dithering, pixels that already made a record dropped;
 *               world stage: eye paths, hit points on every bounce where no record is valid, Morton
 *               sort, clusters bounded by a box size, several candidates with distinct normals per
 *               cluster (ic_world.c);
 *   each stage's candidates are gathered in parallel (ic_ic_gather_points: results do not depend on the
 *   thread count) and inserted in one transaction (ic_cache_insert_batch: validity-radius clamping,
 *   neighbour clamping, in a fixed order). Converged when the share of the world stage's look-up points
 *   that find no record (the points where the final render will read the cache) falls below
 *   `uncovered` once the screen passes are done, or when such a pass adds fewer than pass_growth times
 *   the image's records already made (late passes cover ever fewer look-ups, which otherwise take a
 *   path-traced bounce, for the same rays a record: on Sponza and staircase2 the passes after the first
 *   ~10 took 12–18 % of the rays for 3–6 % of the low-pass error; BENCHMARKS.md, "When batch
 *   construction stops"), or when a pass finds fewer than min_candidates; max_passes is a safety bound,
 *   and stopping there is reported (cut_short). A last coverage sweep adds records for any pixel centre
 *   still uncovered, so every primary shading point has at least one contributing record.
 */
#include "ic_internal.h"

#include "core/threads.h"
#include "film/film.h"
#include "integrators/ic_screen.h"
#include "integrators/ic_world.h"

#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

typedef struct world_job {
    ic_ctx *c;
    int pass;
    ic_candidate *slots;       /* WORLD_SLOTS per traced pixel */
    uint8_t *slot_count;
    uint8_t *visited;          /* per eye path: look-up points visited (uncovered ones are in slots) */
    int stride, cols, rows;
    int64_t first;             /* this process's block of eye paths starts here */
    uint64_t *rays;
} world_job;

/* One eye path per stride×stride block (Frolov et al. 2012 §3.1.3): the path visits the points where the final
 * render will look the cache up — the first surface with a smooth lobe after ideal specular chains,
 * then the surfaces reached through glossy lobes — and every such point where no record is valid
 * becomes a candidate. (The seed collects hits on every bounce because its final render fetches the
 * cache along whole paths; ours path-traces record radiance, so deeper diffuse bounces never look up.) */
static void world_path(void *p, int64_t own_item, int thread)
{
    world_job *j = p;
    int64_t item = j->first + own_item;
    ic_ctx *c = j->c;
    const ic_camera *cam = &c->tr->scene->camera;
    int bx = (int)(item % j->cols), by = (int)(item / j->cols);
    ic_rng rng = ic_rng_make(c->seed, (uint64_t)item, (uint64_t)j->pass, 0x776f726c64ULL);
    int x = bx * j->stride + (int)ic_rng_below(&rng, (uint32_t)j->stride);
    int y = by * j->stride + (int)ic_rng_below(&rng, (uint32_t)j->stride);
    if (x >= cam->width)
        x = cam->width - 1;
    if (y >= cam->height)
        y = cam->height - 1;
    uint32_t pixel = (uint32_t)(y * cam->width + x);
    ic_ray ray;
    ic_candidate *out = &j->slots[item * WORLD_SLOTS];
    int n = 0, smooth_hits = 0;
    /* Outside a fisheye's circle the path ends before it starts. */
    int bounce_end = ic_camera_ray(cam, (float)x + ic_rng_float(&rng), (float)y + ic_rng_float(&rng), &ray)
                         ? MAX_SPECULAR_CHAIN : -1;
    float t_path = 0.0f; /* length of the path from the camera to this hit */
    uint64_t *rays = &j->rays[thread * PAD];
    for (int bounce = 0; bounce <= bounce_end && smooth_hits < WORLD_SLOTS; ++bounce) {
        ic_hit hit;
        ++*rays;
        ic_accel_intersect1(c->tr->accel, &ray, &hit);
        if (hit.triangle == IC_NO_HIT)
            break;
        t_path += hit.t;
        ic_surface s;
        ic_scene_surface(c->tr->scene, hit.triangle, hit.u, hit.v, &s);
        ic_vec3 wo = v3_neg(ray.dir);
        ic_bsdf b;
        ic_bsdf_init(&b, c->tr->scene, &s, wo);
        ic_bsdf_sample bs;
        if (ic_bsdf_has_smooth(&b)) {
            ic_cache_lookup q = ic_cache_lookup_at(s.p, b.cache_n, IC_ACCEPT_CONSTRUCTION);
            ic_cache_estimate e;
            if (!ic_cache_query(c->cache, &q, &e)) {
                out[n].p = s.p;
                out[n].n = b.cache_n;
                /* A pixel's footprint at the point: the camera's directly, and the path length times the
                 * pixel angle behind reflections (a mirror's ray differential; a glossy lobe widens it,
                 * so this bounds the records from below without making them smaller than they may
                 * be). Without it, records seen in a glossy floor had no size floor and construction
                 * never converged there. */
                out[n].footprint = ic_camera_footprint(cam, (float)x + 0.5f, (float)y + 0.5f, t_path);
                out[n].key = ic_ic_world_key(pixel, j->pass, smooth_hits);
                ++n;
            }
            ++smooth_hits;
            if (!ic_bsdf_sample_glossy(&b, wo, ic_rng_float(&rng), ic_rng_float(&rng), &bs))
                break;
        } else if (!ic_bsdf_sample_dir(&b, wo, ic_rng_float(&rng), ic_rng_float(&rng), ic_rng_float(&rng), &bs)) {
            break;
        }
        ray = ic_spawn_ray(&s, bs.wi);
    }
    j->slot_count[item] = (uint8_t)n;
    j->visited[item] = (uint8_t)smooth_hits;
}

/* Collects world-stage candidates in item order (deterministic), then clusters and selects;
 * uncovered_share gets the share of the eye paths' look-up points that found no record; the paths' own time
 * is added to *sweep_seconds, the clustering's (exchanges excluded) to *cluster_seconds. */
static ic_result world_stage(ic_ctx *c, int pass, ic_candidate **out, uint32_t *out_count, double *uncovered_share,
                             double *sweep_seconds, double *cluster_seconds, ic_error *err)
{
    const ic_camera *cam = &c->tr->scene->camera;
    world_job j;
    memset(&j, 0, sizeof j);
    j.c = c;
    j.pass = pass;
    j.stride = c->o.world_stride;
    j.cols = (cam->width + j.stride - 1) / j.stride;
    j.rows = (cam->height + j.stride - 1) / j.stride;
    int64_t items = (int64_t)j.cols * j.rows;
    j.slots = malloc(sizeof *j.slots * (size_t)items * WORLD_SLOTS);
    j.slot_count = calloc((size_t)items, 1);
    j.visited = calloc((size_t)items, 1);
    j.rays = calloc((size_t)c->threads * PAD, sizeof *j.rays);
    if (!j.slots || !j.slot_count || !j.visited || !j.rays) {
        free(j.slots);
        free(j.slot_count);
        free(j.visited);
        free(j.rays);
        return ic_error_set(err, IC_ERR_OOM, "out of memory for world-space candidates");
    }
    /* Several processes (c->comm): a block of eye paths each; their candidates, in path order, exchanged. */
    uint64_t first, own;
    ic_comm_block((uint64_t)items, ic_comm_size(c->comm), ic_comm_rank(c->comm), &first, &own);
    j.first = (int64_t)first;
    double t0 = ic_seconds();
    ic_result r = ic_parallel_for(c->threads, (int64_t)own, world_path, &j);
    *sweep_seconds += ic_seconds() - t0;
    if (r != IC_OK)
        ic_error_set(err, r, "could not start threads");
    for (int t = 0; t < c->threads; ++t)
        atomic_fetch_add(&c->rays, j.rays[t * PAD]);
    uint64_t n = 0;
    double visited = 0.0;
    for (int64_t i = j.first; i < j.first + (int64_t)own; ++i) {
        visited += j.visited[i];
        for (int k = 0; k < j.slot_count[i]; ++k)
            j.slots[n++] = j.slots[i * WORLD_SLOTS + k];
    }
    /* Clustered where they lie on the Morton order: under several processes each clusters a range of it
     * and only the kept candidates go to every process (ic_world_select_shared). */
    uint64_t total = n;
    if (r == IC_OK) {
        const ic_scene *sc = c->tr->scene;
        double t1 = ic_seconds(), comm1 = c->comm ? c->comm->seconds : 0.0;
        r = ic_world_select_shared(c->comm, j.slots, (uint32_t)n, sc->bounds_min, sc->bounds_max,
                                   c->o.cluster_size * c->work_extent, 3, 30.0f, out, out_count, &total, &visited,
                                   err);
        *cluster_seconds += ic_seconds() - t1 - (c->comm ? c->comm->seconds - comm1 : 0.0);
    } else {
        free(j.slots);
    }
    *uncovered_share = visited > 0.0 ? (double)total / visited : 0.0;
    free(j.slot_count);
    free(j.visited);
    free(j.rays);
    return r;
}

/* ic_ic_lookup_all, its time outside the exchange between processes added to *sweep_seconds. */
static ic_result timed_lookup_all(ic_ctx *c, float *lum, uint8_t *covered, int want_lum, double *sweep_seconds)
{
    double t0 = ic_seconds(), comm0 = c->comm ? c->comm->seconds : 0.0;
    ic_result r = ic_ic_lookup_all(c, lum, covered, IC_ACCEPT_CONSTRUCTION, want_lum);
    *sweep_seconds += ic_seconds() - t0 - (c->comm ? c->comm->seconds - comm0 : 0.0);
    return r;
}

/* This process's block of rows [*y0, *y1) (ic_comm_block's rule; the whole image for one process). Each
 * process makes the need map, dithers and looks for uncovered pixels on its own rows; only the chosen
 * pixels are exchanged. */
static void own_rows(const ic_ctx *c, int *y0, int *y1)
{
    uint64_t first = 0, rows = 0;
    ic_comm_block((uint64_t)c->g.height, ic_comm_size(c->comm), ic_comm_rank(c->comm), &first, &rows);
    *y0 = (int)first;
    *y1 = (int)(first + rows);
}

/* The need map (from geometry when lum is NULL, else from the look-ups' luminance) on this process's rows,
 * the same there whichever process makes it. Adds the seconds it took to *seconds. */
static ic_result own_need(ic_ctx *c, const float *lum, float *need, double *seconds, ic_error *err)
{
    int y0, y1;
    own_rows(c, &y0, &y1);
    double t0 = ic_seconds();
    ic_result r = lum ? ic_screen_value_need(&c->g, lum, c->threads, y0, y1, need)
                      : ic_screen_geometry_need(&c->g, c->o.normal_weight, c->threads, y0, y1, need);
    *seconds += ic_seconds() - t0;
    return r == IC_OK ? IC_OK : ic_error_set(err, r, "out of memory for the discontinuity map");
}

/* Candidates at pixels (pixel_candidates): under several processes most lie in other processes' rows, whose
 * shading points are traced again (ic_ic_gbuffer_point), so on the threads. */
typedef struct pixel_job {
    const ic_ctx *c;
    const uint32_t *pix;
    ic_candidate *cand;
    uint64_t tag;
} pixel_job;

static void pixel_candidate(void *p, int64_t item, int thread)
{
    (void)thread;
    const pixel_job *j = p;
    j->cand[item] = ic_ic_candidate_at_pixel(j->c, j->pix[item], j->tag);
}

/* pix[0, n) (room for one a pixel), this process's chosen pixels in raster order, become every process's
 * in raster order (the blocks of rows are in rank order), and candidates at them into cand; *count gets
 * their number. */
static ic_result pixel_candidates(ic_ctx *c, uint32_t *pix, uint32_t n, ic_candidate *cand, uint64_t tag,
                                  uint32_t *count, ic_error *err)
{
    uint64_t total = n;
    ic_result r = ic_comm_allgather_counted(c->comm, pix, n, sizeof *pix, &total, err);
    if (r != IC_OK)
        return r;
    *count = (uint32_t)total;
    if (!ic_comm_is_shared(c->comm)) { /* every point is in the G-buffer: no threads needed */
        for (uint64_t i = 0; i < total; ++i)
            cand[i] = ic_ic_candidate_at_pixel(c, pix[i], tag);
        return IC_OK;
    }
    pixel_job j = {c, pix, cand, tag};
    r = ic_parallel_for(c->threads, (int64_t)total, pixel_candidate, &j);
    return r == IC_OK ? IC_OK : ic_error_set(err, r, "could not start threads");
}

/* Candidates from dithering a need map (this process's rows, then exchanged); pixels that already made a
 * record are dropped (has_record: only a row's own process reads or marks it). The dithering's seconds
 * are added to *seconds (a share of the work the processes divide, like the need map's). */
static ic_result dithered_candidates(ic_ctx *c, const float *need, uint32_t *pix, ic_candidate *cand, uint64_t tag,
                                     uint32_t *count, double *seconds, ic_error *err)
{
    int y0, y1;
    own_rows(c, &y0, &y1);
    double t0 = ic_seconds();
    uint32_t np = ic_screen_dither(&c->g, need, c->o.dither_threshold, y0, y1, pix);
    uint32_t n = 0;
    for (uint32_t i = 0; i < np; ++i) {
        if (c->has_record[pix[i]])
            continue;
        c->has_record[pix[i]] = 1;
        pix[n++] = pix[i];
    }
    *seconds += ic_seconds() - t0;
    return pixel_candidates(c, pix, n, cand, tag, count, err);
}

/* Adds records at pixel centres that no record covers (construction acceptance), clustered so that
 * one record serves a whole uncovered patch; repeats until every shading point is covered. Each process
 * makes the candidates of its own rows, and the clustering is shared out along the Morton order as the
 * world stage's is (ic_world_select_shared); its seconds, exchanges excluded, are added to *cluster_seconds. */
static ic_result coverage_sweep(ic_ctx *c, float *lum, uint8_t *covered, phase_times *pt, uint32_t *added,
                                double *sweep_seconds, double *cluster_seconds, ic_error *err)
{
    *added = 0;
    int y0, y1;
    own_rows(c, &y0, &y1);
    const size_t first = (size_t)y0 * (size_t)c->g.width, end = (size_t)y1 * (size_t)c->g.width;
    /* Out of time, uncovered points take the final render's fallback (one path-traced hemisphere ray). */
    for (int round = 0; round < 16 && !ic_ic_out_of_time(c); ++round) {
        ic_result r = timed_lookup_all(c, lum, covered, 0, sweep_seconds);
        if (r != IC_OK)
            return ic_error_set(err, r, "could not start threads");
        /* This process's rows: their candidates and clustering are its share of the work. */
        double t0 = ic_seconds(), comm0 = c->comm ? c->comm->seconds : 0.0;
        uint32_t own = 0;
        for (size_t i = first; i < end; ++i)
            own += c->g.valid[i] && !covered[i];
        /* zeroed: the candidates' padding travels in the exchanges */
        ic_candidate *mine = calloc(own ? own : 1, sizeof *mine), *cand = NULL;
        if (!mine)
            return ic_error_set(err, IC_ERR_OOM, "out of memory for %u uncovered pixels", own);
        own = 0;
        for (size_t i = first; i < end; ++i)
            if (c->g.valid[i] && !covered[i])
                mine[own++] = ic_ic_candidate_at_pixel(c, (uint32_t)i, 0x40 | (uint64_t)round);
        /* Small clusters: each selected record covers at least its own pixel, so this terminates. */
        const ic_scene *sc = c->tr->scene;
        uint32_t n = 0;
        uint64_t total = 0;
        double visited = 0.0;
        r = ic_world_select_shared(c->comm, mine, own, sc->bounds_min, sc->bounds_max,
                                   0.25f * c->o.cluster_size * c->work_extent, 3, 30.0f, &cand, &n, &total, &visited,
                                   err);
        *cluster_seconds += ic_seconds() - t0 - (c->comm ? c->comm->seconds - comm0 : 0.0);
        if (r == IC_OK && total > 0)
            r = ic_ic_gather_and_insert(c, cand, n, pt, err);
        free(cand);
        if (r != IC_OK || total == 0)
            return r;
        *added += n;
    }
    return IC_OK;
}

ic_pass_end ic_ic_batch_pass_end(int truncated, int converged, int (*out_of_time)(ic_ctx *), ic_ctx *c)
{
    if (converged && !truncated)
        return IC_PASS_CONVERGED;
    return truncated || out_of_time(c) ? IC_PASS_STOPPED : IC_PASS_CONTINUE;
}

/* Adds this process's communication since the last call to pass `pass` of the statistics. */
static void count_traffic(ic_ctx *c, ic_render_stats *st, int pass)
{
    if (!c->comm || pass < 0 || pass >= IC_STATS_PASSES)
        return;
    st->rank_comm_seconds_per_pass[pass] += c->comm->seconds - c->comm_seconds_counted;
    st->rank_comm_bytes_per_pass[pass] += c->comm->bytes - c->comm_bytes_counted;
    c->comm_seconds_counted = c->comm->seconds;
    c->comm_bytes_counted = c->comm->bytes;
}

/* Records where the image's hemisphere rays land, before any of the image's own (the sensors' hit stage,
 * ic_hit_stage.c, with probes from every shading point): about three quarters of the hemisphere rays'
 * diffuse hits on Sponza and staircase2 found no record of an earlier pass and path-traced their bounces,
 * which took most of the gathering's rays. The hit records are a kind of their own (IC_HIT_KIND): the
 * hemisphere rays' look-ups read them where no image record accepts, and nothing else does, so the
 * image is interpolated from its own records as before. Their rays: half the strata each way (1/4 of
 * a record's): every image record reads many of them, so their error is shared, and with 1/16 one
 * staircase2 seed in six was 1.5 times worse than the others (1/64 left a window-lit room's mean moving
 * by ±2.5 % from seed to seed); no gradients: from the 2 × 7 grid of 1/64 of the rays they were noise
 * that extrapolation turned into bias (that room's mean −1.9 % over six seeds; BENCHMARKS.md). */
#define IMAGE_HIT_STRATA_DIV 2
#define IMAGE_HIT_KEY_TAG 0x696d616765686974ULL
static ic_result image_hit_stage(ic_ctx *c, size_t npix, phase_times *pt, ic_error *err)
{
    /* The valid pixels in raster order are the points; the stage reads only its probes' (filled from
     * ic_ic_gbuffer_point: under several processes a pixel's row may be another's, and each process
     * needs only its own block of the probes' points). */
    uint32_t m = 0;
    for (size_t i = 0; i < npix; ++i)
        m += c->g.valid[i];
    ic_vec3 *p = calloc(m ? m : 1, sizeof *p), *n = calloc(m ? m : 1, sizeof *n);
    if (!p || !n) {
        free(p);
        free(n);
        return ic_error_set(err, IC_ERR_OOM, "out of memory for the hit stage's %u points", m);
    }
    const uint32_t probes = ic_ic_hit_probes(m);
    /* Under several processes each traces a block of the probes (ic_hit_stage.c): only their points. */
    uint64_t k0, own;
    ic_comm_block(probes, ic_comm_size(c->comm), ic_comm_rank(c->comm), &k0, &own);
    const uint32_t lo = own ? ic_ic_hit_probe_point((uint32_t)k0, m) : 1,
                   hi = own ? ic_ic_hit_probe_point((uint32_t)(k0 + own - 1), m) : 0;
    for (uint32_t i = 0, k = 0, at = 0; k < probes && i < npix; ++i) {
        if (!c->g.valid[i])
            continue;
        if (ic_ic_hit_probe_point(k, m) == at && at >= lo && at <= hi)
            ic_ic_gbuffer_point(c, i, &p[at], &n[at], NULL);
        while (k < probes && ic_ic_hit_probe_point(k, m) <= at)
            ++k;
        ++at;
    }
    c->hit_kind = (int)IC_HIT_KIND;
    /* With a time budget, the hit records take at most a quarter of construction's share: the image's
     * own records come after them. */
    const double deadline = c->deadline, now = ic_seconds();
    if (deadline > 0.0)
        c->deadline = now + 0.25 * fmax(deadline - now, 0.0);
    ic_result r = ic_ic_hit_stage(c, p, n, m, IMAGE_HIT_KEY_TAG, IC_HIT_KIND, IMAGE_HIT_STRATA_DIV, 0, pt, err);
    c->deadline = deadline;
    free(p);
    free(n);
    return r;
}

ic_result ic_ic_build_batch(ic_ctx *c, const ic_render_options *opt, ic_render_stats *st, phase_times *pt,
                             ic_error *err)
{
    size_t npix = (size_t)c->g.width * c->g.height;
    float *need = malloc(sizeof *need * npix);
    float *lum = calloc(npix, sizeof *lum); /* rows no need map of this process reads stay 0 */
    uint8_t *covered = malloc(npix);
    uint32_t *pix = malloc(sizeof *pix * npix);
    ic_candidate *cand = malloc(sizeof *cand * npix);
    ic_result r = IC_OK;
    double sweeps = 0.0; /* seconds in the eye paths and look-up sweeps, exchanges excluded */
    double need_seconds = 0.0; /* in this process's rows of the need maps and their dithering */
    double cluster_seconds = 0.0; /* in this process's range of the world stage's Morton order */
    if (c->comm) {
        c->comm_seconds_counted = c->comm->seconds;
        c->comm_bytes_counted = c->comm->bytes;
    }
    if (!need || !lum || !covered || !pix || !cand) {
        r = ic_error_set(err, IC_ERR_OOM, "out of memory for the construction buffers");
        goto done;
    }
    if (c->o.hit_records != IC_CACHE_OFF && c->hit_lookups && !ic_ic_cancelled(c)) {
        ic_ic_report(opt, "hit records", 0.0);
        r = image_hit_stage(c, npix, pt, err);
        if (r != IC_OK)
            goto done;
    }
    const uint32_t hit_records = ic_cache_count(c->cache);
    /* Pass 0: geometry discontinuity. */
    ic_ic_report(opt, "cache pass 0", 0.0);
    uint32_t n = 0, before0 = ic_cache_count(c->cache);
    if ((r = own_need(c, NULL, need, &need_seconds, err)) != IC_OK ||
        (r = dithered_candidates(c, need, pix, cand, 0, &n, &need_seconds, err)) != IC_OK)
        goto done;
    r = ic_ic_gather_and_insert(c, cand, n, pt, err);
    if (r != IC_OK)
        goto done;
    count_traffic(c, st, 0);
    st->records_per_pass[0] = ic_cache_count(c->cache) - before0; /* fewer than n if time or an interrupt cut it */
    st->passes = 1;
    st->cut_short = 1; /* until the cache has converged */
    for (int pass = 1; pass <= c->o.max_passes && !ic_ic_cancelled(c); ++pass) {
        ic_ic_report(opt, "cache passes", (double)pass / (double)(c->o.max_passes + 1));
        uint32_t found = 0, before = ic_cache_count(c->cache);
        const uint64_t ungathered_before = c->ungathered;
        if (pass <= c->o.screen_passes) {
            r = timed_lookup_all(c, lum, covered, 1, &sweeps);
            if (r != IC_OK) {
                ic_error_set(err, r, "the look-up sweep of cache pass %d failed (%s)", pass, ic_result_name(r));
                goto done;
            }
            if ((r = own_need(c, lum, need, &need_seconds, err)) != IC_OK)
                goto done;
            /* Pixels no record covers ask for at least the 16-pixel spacing; later passes (and the
             * world stage, which clusters uncovered hits) fill what remains. */
            int y0, y1;
            own_rows(c, &y0, &y1);
            const double t_floor = ic_seconds();
            for (size_t i = (size_t)y0 * c->g.width; i < (size_t)y1 * c->g.width; ++i)
                if (c->g.valid[i] && !covered[i])
                    need[i] = fmaxf(need[i], c->o.dither_threshold);
            need_seconds += ic_seconds() - t_floor;
            if ((r = dithered_candidates(c, need, pix, cand, ic_ic_screen_key_tag(pass), &n, &need_seconds, err)) != IC_OK)
                goto done;
            found += n;
            r = ic_ic_gather_and_insert(c, cand, n, pt, err);
            if (r != IC_OK)
                goto done;
        }
        if (ic_ic_cancelled(c)) { /* interrupted inside the screen stage: the pass ends here */
            if (pass < IC_STATS_PASSES)
                st->records_per_pass[pass] = ic_cache_count(c->cache) - before;
            st->passes = pass + 1;
            break;
        }
        ic_candidate *wc = NULL;
        uint32_t wn = 0;
        double uncovered = 1.0;
        r = world_stage(c, pass, &wc, &wn, &uncovered, &sweeps, &cluster_seconds, err);
        if (r == IC_OK)
            r = ic_ic_gather_and_insert(c, wc, wn, pt, err);
        free(wc);
        if (r != IC_OK)
            goto done;
        found += wn;
        const uint32_t added = ic_cache_count(c->cache) - before;
        if (pass < IC_STATS_PASSES)
            st->records_per_pass[pass] = added;
        count_traffic(c, st, pass);
        st->passes = pass + 1;
        st->uncovered_share = uncovered;
        /* Converged, once the screen stage has had its passes: the final render's look-ups (the eye paths'
         * points, measured before this pass's records) almost all find records, or this pass added few
         * records for the image's records already made (pass_growth; the hit records, which only hemisphere
         * rays read, do not count: at 40×30 they outnumber the image's). */
        const int slowed = c->o.pass_growth.mode != IC_CACHE_OFF &&
                           (double)added < (double)c->o.pass_growth.value * (double)(before - hit_records);
        const int converged = (int)found < c->o.min_candidates ||
                              (pass >= c->o.screen_passes && (uncovered < c->o.uncovered || slowed));
        const ic_pass_end end = ic_ic_batch_pass_end(c->ungathered != ungathered_before, converged, ic_ic_out_of_time, c);
        if (end == IC_PASS_CONVERGED) {
            st->cut_short = 0;
            break;
        }
        if (end == IC_PASS_STOPPED) {
            st->cut_by_time = !ic_ic_cancelled(c);
            break;
        }
    }
    uint32_t added;
    const uint32_t before_sweep = ic_cache_count(c->cache);
    r = coverage_sweep(c, lum, covered, pt, &added, &sweeps, &cluster_seconds, err);
    st->coverage_records = ic_cache_count(c->cache) - before_sweep;
    count_traffic(c, st, st->passes - 1);
    /* The parts of construction that the processes share out (the rest of it, clustering,
     * every process does alike): reported apart so that a scaling model can tell them apart. */
    ic_stats_add_phase(st, "eye paths and look-ups", sweeps + pt->probes);
    ic_stats_add_phase(st, "need maps", need_seconds);
    ic_stats_add_phase(st, "clustering", cluster_seconds);
done:
    free(need);
    free(lum);
    free(covered);
    free(pix);
    free(cand);
    return r;
}
