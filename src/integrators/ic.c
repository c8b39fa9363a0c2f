/*
 * ic.c — irradiance-cache construction (lazy and batch) and the final render (ic.h).
 *
 * Batch construction follows seed 004_b98c0b87c8321936.txt §3.1 step by step:
 *   pass 0      primary position/normal buffers → geometry discontinuity on a mip pyramid → blend →
 *               deterministic dithering → candidates (ic_screen.c);
 *   passes 1…n  screen stage (first `screen_passes` passes): irradiance discontinuity of the current
 *               cache look-ups, same pyramid and dithering, pixels that already made a record dropped;
 *               world stage: eye paths, hit points on every bounce where no record is valid, Morton
 *               sort, clusters bounded by a box size, several candidates with distinct normals per
 *               cluster (ic_world.c);
 *   each stage's candidates are gathered in parallel (ic_gather_batch: results do not depend on the
 *   thread count) and inserted in one transaction (ic_cache_insert_batch: validity-radius clamping,
 *   neighbour clamping, in a fixed order). Stop at max_passes or when a pass finds fewer than
 *   min_candidates. A last coverage sweep adds records for any pixel centre still uncovered, so every
 *   primary shading point has at least one contributing record.
 * Lazy construction (Ward 1988) visits the pixel centres' shading points in raster order, looks up,
 * and on a miss gathers and inserts one record: serial, the reference for the others.
 */
#include "ic_internal.h"

#include "core/sampling.h"
#include "core/threads.h"
#include "integrators/ic_screen.h"
#include "integrators/ic_world.h"
#include "render/render.h"

#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------- record radiance (trace callback) */

/* 1 if emitting triangle tri is a large emitter whose light the records carry (cache_large_emitters). */
static int emitter_is_cached(const ic_ctx *c, uint32_t tri)
{
    if (!c->direct_pmf || tri >= c->tr->scene->triangle_count)
        return 0;
    int32_t li = c->tr->scene->triangle_light[tri];
    return li >= 0 && !(c->direct_pmf[li] > 0.0f);
}

/* What a hemisphere ray adds for its hit besides the light reflected there: the emission of a large
 * emitter, which is direct light the records carry (zero for any other surface). */
static ic_vec3 cached_emission(const ic_ctx *c, const ic_ray *ray, const ic_hit *hit)
{
    if (!emitter_is_cached(c, hit->triangle))
        return v3s(0.0f);
    ic_surface s;
    ic_scene_surface(c->tr->scene, hit->triangle, hit->u, hit->v, &s);
    return ic_scene_emission(c->tr->scene, &s, v3_neg(ray->dir));
}

/* Radiance leaving a hemisphere ray's hit towards the record, with the cache standing in for the
 * bounces after the hit: kd/π · E(hit) from the records already made, plus the hit's direct light by
 * the final render's estimator (records hold no light of the emitters it samples; ic_ic_direct_light
 * adds it). This is Ward's multiple-bounce scheme (the ambient value of a point is its records' interpolation, Radiance's
 * -ab) inside the batch passes: a pass's records serve the next passes' rays, and the world-space
 * stage puts records where these rays land (seed 004 §3.1.3), which is what makes the look-ups hit;
 * it cuts record cost, which seed 004 §4.6 measures as most of the construction time. Only purely
 * diffuse hits are taken (a glossy hit needs its lobe traced); returns 0 where no record reaches, and
 * the caller path-traces. Deterministic: within a pass the cache is read-only. */
static int hit_from_cache(const ic_ctx *c, const ic_ray *ray, const ic_hit *hit, ic_rng *rng, uint64_t *rays,
                          ic_vec3 *radiance)
{
    const ic_scene *scene = c->tr->scene;
    ic_surface s;
    ic_scene_surface(scene, hit->triangle, hit->u, hit->v, &s);
    ic_vec3 wo = v3_neg(ray->dir);
    ic_bsdf b;
    ic_bsdf_init(&b, scene, &s, wo);
    if (!ic_bsdf_has_smooth(&b) || ic_bsdf_has_glossy(&b))
        return 0;
    ic_cache_lookup q = ic_cache_lookup_at(s.p, b.frame.n, IC_ACCEPT_FINAL);
    ic_cache_estimate e;
    if (!ic_cache_query(c->cache, &q, &e))
        return 0;
    *radiance = v3_add(v3_mul(v3_scale(b.kd, IC_INV_PI), e.irradiance), ic_ic_direct_light(c, &s, &b, wo, NULL, rng, rays));
    return 1;
}

/* Hemisphere rays of a record: what they return is described in ic.h. The path after the first hit
 * is seeded from the ray itself (origin and direction bits), so it does not depend on which batch or
 * thread traced it. */
void ic_ic_gather_trace(void *user, const ic_vec3 *origins, const ic_vec3 *dirs, uint32_t count, float *hit_dist,
                         ic_vec3 *radiance)
{
    ic_ctx *c = user;
    const ic_tracer *tr = &c->gather_tr;
    enum { CHUNK = 256 };
    ic_ray rays[CHUNK];
    ic_hit hits[CHUNK];
    uint64_t nrays = 0;
    for (uint32_t base = 0; base < count; base += CHUNK) {
        uint32_t n = count - base < CHUNK ? count - base : CHUNK;
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
            if (hits[i].triangle == IC_NO_HIT) {
                hit_dist[j] = INFINITY;
                radiance[j] = ic_scene_env_radiance(tr->scene, rays[i].dir);
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
            if (!c->hit_lookups || !hit_from_cache(c, &rays[i], &hits[i], &rng, &nrays, &radiance[j])) {
                /* The hit is the path's second vertex (the record is the first): depth 1. Its emission
                 * is direct light of the record's point, delivered by NEE in the final render. */
                ic_path_start st = {1, 0.0f, 1, 1, NULL};
                radiance[j] = ic_pt_li_hit(tr, rays[i], &hits[i], &st, &rng, &nrays);
            }
            /* ... unless it comes from a large emitter, which the records carry. */
            radiance[j] = v3_add(radiance[j], cached_emission(c, &rays[i], &hits[i]));
        }
    }
    atomic_fetch_add_explicit(&c->rays, nrays, memory_order_relaxed);
}

/* ---------------------------------------------------------------- shading points */

/* Follows a camera ray through ideal specular surfaces to the first surface with a smooth lobe.
 * Glass takes the more likely branch (refraction unless Fresnel reflection dominates): the shading
 * points of the cache must be a deterministic function of the pixel. */
int ic_ic_shading_point(const ic_tracer *tr, ic_ray ray, ic_surface *s, ic_bsdf *b, ic_vec3 *wo, float *t_primary,
                        uint64_t *rays)
{
    for (int k = 0; k <= MAX_SPECULAR_CHAIN; ++k) {
        ic_hit hit;
        ++*rays;
        ic_accel_intersect1(tr->accel, &ray, &hit);
        if (hit.triangle == IC_NO_HIT)
            return 0;
        if (k == 0 && t_primary)
            *t_primary = hit.t;
        ic_scene_surface(tr->scene, hit.triangle, hit.u, hit.v, s);
        *wo = v3_neg(ray.dir);
        ic_bsdf_init(b, tr->scene, s, *wo);
        if (ic_bsdf_has_smooth(b))
            return 1;
        ic_bsdf_sample bs;
        float F = b->type == IC_MAT_GLASS ? ic_fresnel_dielectric(v3_dot(*wo, b->frame.n), b->ior) : 1.0f;
        if (!ic_bsdf_sample_dir(b, *wo, F > 0.5f ? 0.0f : 0.999f, 0.5f, 0.5f, &bs))
            return 0;
        ray = ic_spawn_ray(s, bs.wi);
    }
    return 0;
}

typedef struct gbuffer_job {
    ic_ctx *c;
    uint64_t *rays;            /* per thread, padded */
} gbuffer_job;

#define PAD 8

static void gbuffer_row(void *p, int64_t y, int thread)
{
    gbuffer_job *j = p;
    ic_ctx *c = j->c;
    const ic_camera *cam = &c->tr->scene->camera;
    for (int x = 0; x < cam->width; ++x) {
        size_t i = (size_t)y * cam->width + x;
        ic_ray ray = ic_camera_ray(cam, (float)x + 0.5f, (float)y + 0.5f);
        ic_surface s;
        ic_bsdf b;
        ic_vec3 wo;
        float t_primary = 0.0f;
        c->g.valid[i] = (uint8_t)ic_ic_shading_point(c->tr, ray, &s, &b, &wo, &t_primary, &j->rays[thread * PAD]);
        if (c->g.valid[i]) {
            c->g.p[i] = s.p;
            c->g.n[i] = b.frame.n;
            c->g.footprint[i] = t_primary * c->pixel_angle;
        }
    }
}

static ic_result build_gbuffer(ic_ctx *c, ic_error *err)
{
    const ic_camera *cam = &c->tr->scene->camera;
    size_t n = (size_t)cam->width * cam->height;
    c->g.width = cam->width;
    c->g.height = cam->height;
    c->g.p = calloc(n, sizeof *c->g.p);
    c->g.n = calloc(n, sizeof *c->g.n);
    c->g.footprint = calloc(n, sizeof *c->g.footprint);
    c->g.valid = calloc(n, 1);
    c->has_record = calloc(n, 1);
    uint64_t *rays = calloc((size_t)c->threads * PAD, sizeof *rays);
    if (!c->g.p || !c->g.n || !c->g.footprint || !c->g.valid || !c->has_record || !rays) {
        free(rays);
        return ic_error_set(err, IC_ERR_OOM, "out of memory for the shading-point buffers");
    }
    gbuffer_job j = {c, rays};
    ic_result r = ic_parallel_for(c->threads, cam->height, gbuffer_row, &j);
    for (int t = 0; t < c->threads; ++t)
        atomic_fetch_add(&c->rays, rays[t * PAD]);
    free(rays);
    return r == IC_OK ? IC_OK : ic_error_set(err, r, "could not start threads");
}

static void free_gbuffer(ic_ctx *c)
{
    free(c->g.p);
    free(c->g.n);
    free(c->g.footprint);
    free(c->g.valid);
    free(c->has_record);
}

/* ---------------------------------------------------------------- gathering and insertion */

void ic_ic_record_from_gather(const ic_ctx *c, const ic_candidate *cand, const ic_gather_result *gr, ic_record *rec)
{
    memset(rec, 0, sizeof *rec);
    rec->position = cand->p;
    rec->normal = cand->n;
    rec->tangent = ic_frame_from_normal(cand->n).t;
    rec->irradiance = gr->irradiance;
    if (!c->o.no_gradients) {
        /* Gradient-magnitude clamping (seed 000 §5.1, eq. 2) bounds the extrapolated change by shrinking
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
    rec->pixel_footprint = cand->footprint;
}

ic_gather_point ic_ic_gather_point_of(const ic_candidate *cand)
{
    ic_gather_point gp;
    gp.position = ic_offset_ray_origin(cand->p, cand->n, cand->n);
    gp.normal = cand->n;
    gp.key = cand->key;
    return gp;
}

/* Gathers all candidates in parallel and inserts them as one batch. */
ic_result ic_ic_gather_and_insert(ic_ctx *c, const ic_candidate *cand, uint32_t count, phase_times *pt,
                                   ic_error *err)
{
    if (count == 0)
        return IC_OK;
    ic_gather_point *pts = malloc(sizeof *pts * count);
    ic_gather_result *res = malloc(sizeof *res * count);
    ic_record *recs = malloc(sizeof *recs * count);
    ic_result r = IC_OK;
    if (!pts || !res || !recs) {
        r = ic_error_set(err, IC_ERR_OOM, "out of memory for %u cache candidates", count);
        goto done;
    }
    for (uint32_t i = 0; i < count; ++i)
        pts[i] = ic_ic_gather_point_of(&cand[i]);
    double t0 = ic_seconds();
    r = ic_gather_batch(&c->o.gather, ic_ic_gather_trace, c, c->threads, pts, count, res, err);
    double t1 = ic_seconds();
    pt->gather += t1 - t0;
    if (r != IC_OK)
        goto done;
    for (uint32_t i = 0; i < count; ++i)
        ic_ic_record_from_gather(c, &cand[i], &res[i], &recs[i]);
    r = ic_cache_insert_batch(c->cache, recs, count, NULL, err);
    pt->insert += ic_seconds() - t1;
done:
    free(pts);
    free(res);
    free(recs);
    return r;
}

ic_candidate ic_ic_candidate_at_pixel(const ic_ctx *c, uint32_t pixel, uint64_t tag)
{
    ic_candidate cd;
    cd.p = c->g.p[pixel];
    cd.n = c->g.n[pixel];
    cd.footprint = c->g.footprint[pixel];
    cd.key = ((uint64_t)pixel << 8) | tag;
    return cd;
}

/* ---------------------------------------------------------------- screen-space stage */

typedef struct lookup_job {
    ic_ctx *c;
    float *lum;                /* per pixel luminance of the look-up */
    uint8_t *covered;          /* per pixel: some record contributes */
    ic_cache_acceptance acceptance;
} lookup_job;

/* One row's look-ups, in batches of up to LOOKUP_BATCH pixels with a hint carried along the row
 * (ic_cache_query_batch: the answers of one look-up each, without the per-call costs). */
enum { LOOKUP_BATCH = 64 };

static void lookup_row(void *p, int64_t y, int thread)
{
    (void)thread;
    lookup_job *j = p;
    const ic_gbuffer *g = &j->c->g;
    ic_cache_hint hint = {0};
    ic_cache_lookup q[LOOKUP_BATCH];
    ic_cache_estimate e[LOOKUP_BATCH];
    size_t pixel[LOOKUP_BATCH], m = 0;
    for (int x = 0; x < g->width; ++x) {
        size_t i = (size_t)y * g->width + x;
        j->covered[i] = 0;
        j->lum[i] = 0.0f;
        if (g->valid[i]) {
            q[m] = ic_cache_lookup_at(g->p[i], g->n[i], j->acceptance);
            pixel[m++] = i;
        }
        if (m == LOOKUP_BATCH || (x + 1 == g->width && m > 0)) {
            ic_cache_query_batch(j->c->cache, q, m, &hint, e);
            for (size_t k = 0; k < m; ++k) {
                j->covered[pixel[k]] = (uint8_t)(e[k].contributor_count > 0);
                j->lum[pixel[k]] = v3_lum(e[k].irradiance);
            }
            m = 0;
        }
    }
}

ic_result ic_ic_lookup_all(ic_ctx *c, float *lum, uint8_t *covered, ic_cache_acceptance acc)
{
    lookup_job j = {c, lum, covered, acc};
    return ic_parallel_for(c->threads, c->g.height, lookup_row, &j);
}

/* ---------------------------------------------------------------- world-space stage */

typedef struct world_job {
    ic_ctx *c;
    int pass;
    ic_candidate *slots;       /* WORLD_SLOTS per traced pixel */
    uint8_t *slot_count;
    int stride, cols, rows;
    uint64_t *rays;
} world_job;

/* One eye path per stride×stride block (seed 004 §3.1.3): the path visits the points where the final
 * render will look the cache up — the first surface with a smooth lobe after ideal specular chains,
 * then the surfaces reached through glossy lobes — and every such point where no record is valid
 * becomes a candidate. (The seed collects hits on every bounce because its final render fetches the
 * cache along whole paths; ours path-traces record radiance, so deeper diffuse bounces never look up.) */
static void world_path(void *p, int64_t item, int thread)
{
    world_job *j = p;
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
    ic_ray ray = ic_camera_ray(cam, (float)x + ic_rng_float(&rng), (float)y + ic_rng_float(&rng));
    ic_candidate *out = &j->slots[item * WORLD_SLOTS];
    int n = 0, smooth_hits = 0;
    float t_primary = 0.0f;
    uint64_t *rays = &j->rays[thread * PAD];
    for (int bounce = 0; bounce <= MAX_SPECULAR_CHAIN && smooth_hits < WORLD_SLOTS; ++bounce) {
        ic_hit hit;
        ++*rays;
        ic_accel_intersect1(c->tr->accel, &ray, &hit);
        if (hit.triangle == IC_NO_HIT)
            break;
        if (bounce == 0)
            t_primary = hit.t;
        ic_surface s;
        ic_scene_surface(c->tr->scene, hit.triangle, hit.u, hit.v, &s);
        ic_vec3 wo = v3_neg(ray.dir);
        ic_bsdf b;
        ic_bsdf_init(&b, c->tr->scene, &s, wo);
        ic_bsdf_sample bs;
        if (ic_bsdf_has_smooth(&b)) {
            ic_cache_lookup q = ic_cache_lookup_at(s.p, b.frame.n, IC_ACCEPT_CONSTRUCTION);
            ic_cache_estimate e;
            if (!ic_cache_query(c->cache, &q, &e)) {
                out[n].p = s.p;
                out[n].n = b.frame.n;
                /* Pixel-based radius bounds only hold for what the camera sees directly. */
                out[n].footprint = smooth_hits == 0 ? t_primary * c->pixel_angle : 0.0f;
                out[n].key = ((uint64_t)pixel << 8) | (uint64_t)(0x80 | (j->pass & 0x1f) << 2 | (smooth_hits & 3));
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
}

/* Collects world-stage candidates in item order (deterministic), then clusters and selects. */
static ic_result world_stage(ic_ctx *c, int pass, ic_candidate **out, uint32_t *out_count, ic_error *err)
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
    j.rays = calloc((size_t)c->threads * PAD, sizeof *j.rays);
    if (!j.slots || !j.slot_count || !j.rays) {
        free(j.slots);
        free(j.slot_count);
        free(j.rays);
        return ic_error_set(err, IC_ERR_OOM, "out of memory for world-space candidates");
    }
    ic_result r = ic_parallel_for(c->threads, items, world_path, &j);
    for (int t = 0; t < c->threads; ++t)
        atomic_fetch_add(&c->rays, j.rays[t * PAD]);
    uint32_t n = 0;
    for (int64_t i = 0; i < items; ++i)
        for (int k = 0; k < j.slot_count[i]; ++k)
            j.slots[n++] = j.slots[i * WORLD_SLOTS + k];
    const ic_scene *sc = c->tr->scene;
    *out_count = ic_world_select(j.slots, n, sc->bounds_min, sc->bounds_max, c->o.cluster_size * c->scene_diag, 3,
                                 30.0f);
    *out = j.slots;
    free(j.slot_count);
    free(j.rays);
    return r == IC_OK ? IC_OK : ic_error_set(err, r, "could not start threads");
}

/* ---------------------------------------------------------------- strategies */

void ic_ic_report(const ic_render_options *opt, const char *phase, double f)
{
    if (opt->progress)
        opt->progress(opt->progress_user, phase, f);
}

/* Candidates from dithering a need map; pixels that already made a record are dropped. */
static uint32_t dithered_candidates(ic_ctx *c, const float *need, uint32_t *pix, ic_candidate *cand, uint64_t tag)
{
    uint32_t np = ic_screen_dither(&c->g, need, c->o.dither_threshold, pix);
    uint32_t n = 0;
    for (uint32_t i = 0; i < np; ++i) {
        if (c->has_record[pix[i]])
            continue;
        c->has_record[pix[i]] = 1;
        cand[n++] = ic_ic_candidate_at_pixel(c, pix[i], tag);
    }
    return n;
}

/* Adds records at pixel centres that no record covers (construction acceptance), clustered so that
 * one record serves a whole uncovered patch; repeats until every shading point is covered. */
static ic_result coverage_sweep(ic_ctx *c, float *lum, uint8_t *covered, ic_candidate *cand, phase_times *pt,
                                uint32_t *added, ic_error *err)
{
    *added = 0;
    size_t npix = (size_t)c->g.width * c->g.height;
    for (int round = 0; round < 16; ++round) {
        ic_result r = ic_ic_lookup_all(c, lum, covered, IC_ACCEPT_CONSTRUCTION);
        if (r != IC_OK)
            return ic_error_set(err, r, "could not start threads");
        uint32_t n = 0;
        for (size_t i = 0; i < npix; ++i)
            if (c->g.valid[i] && !covered[i])
                cand[n++] = ic_ic_candidate_at_pixel(c, (uint32_t)i, 0x40 | (uint64_t)round);
        if (n == 0)
            return IC_OK;
        /* Small clusters: each selected record covers at least its own pixel, so this terminates. */
        const ic_scene *sc = c->tr->scene;
        n = ic_world_select(cand, n, sc->bounds_min, sc->bounds_max, 0.25f * c->o.cluster_size * c->scene_diag, 3,
                            30.0f);
        r = ic_ic_gather_and_insert(c, cand, n, pt, err);
        if (r != IC_OK)
            return r;
        *added += n;
    }
    return IC_OK;
}

static ic_result build_batch(ic_ctx *c, const ic_render_options *opt, ic_render_stats *st, phase_times *pt,
                             ic_error *err)
{
    size_t npix = (size_t)c->g.width * c->g.height;
    float *need = malloc(sizeof *need * npix);
    float *lum = malloc(sizeof *lum * npix);
    uint8_t *covered = malloc(npix);
    uint32_t *pix = malloc(sizeof *pix * npix);
    ic_candidate *cand = malloc(sizeof *cand * npix);
    ic_result r = IC_OK;
    if (!need || !lum || !covered || !pix || !cand) {
        r = ic_error_set(err, IC_ERR_OOM, "out of memory for the construction buffers");
        goto done;
    }
    /* Pass 0: geometry discontinuity. */
    ic_ic_report(opt, "cache pass 0", 0.0);
    r = ic_screen_geometry_need(&c->g, c->o.normal_weight, need);
    if (r != IC_OK) {
        ic_error_set(err, r, "out of memory for the discontinuity map");
        goto done;
    }
    uint32_t n = dithered_candidates(c, need, pix, cand, 0);
    r = ic_ic_gather_and_insert(c, cand, n, pt, err);
    if (r != IC_OK)
        goto done;
    st->records_per_pass[0] = n;
    st->passes = 1;
    for (int pass = 1; pass <= c->o.max_passes; ++pass) {
        ic_ic_report(opt, "cache passes", (double)pass / (double)(c->o.max_passes + 1));
        uint32_t found = 0, before = ic_cache_count(c->cache);
        if (pass <= c->o.screen_passes) {
            r = ic_ic_lookup_all(c, lum, covered, IC_ACCEPT_CONSTRUCTION);
            if (r != IC_OK) {
                ic_error_set(err, r, "could not start threads");
                goto done;
            }
            r = ic_screen_value_need(&c->g, lum, need);
            if (r != IC_OK) {
                ic_error_set(err, r, "out of memory for the discontinuity map");
                goto done;
            }
            /* Pixels no record covers ask for at least the 16-pixel spacing; later passes (and the
             * world stage, which clusters uncovered hits) fill what remains. */
            for (size_t i = 0; i < npix; ++i)
                if (c->g.valid[i] && !covered[i])
                    need[i] = fmaxf(need[i], c->o.dither_threshold);
            n = dithered_candidates(c, need, pix, cand, (uint64_t)pass);
            found += n;
            r = ic_ic_gather_and_insert(c, cand, n, pt, err);
            if (r != IC_OK)
                goto done;
        }
        ic_candidate *wc = NULL;
        uint32_t wn = 0;
        r = world_stage(c, pass, &wc, &wn, err);
        if (r == IC_OK)
            r = ic_ic_gather_and_insert(c, wc, wn, pt, err);
        free(wc);
        if (r != IC_OK)
            goto done;
        found += wn;
        if (pass < 32)
            st->records_per_pass[pass] = ic_cache_count(c->cache) - before;
        st->passes = pass + 1;
        if ((int)found < c->o.min_candidates)
            break;
    }
    uint32_t added;
    r = coverage_sweep(c, lum, covered, cand, pt, &added, err);
done:
    free(need);
    free(lum);
    free(covered);
    free(pix);
    free(cand);
    return r;
}

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
        radiance[j] = cached_emission(c, &ray, &hit);
        if (!ic_bsdf_has_smooth(&b))
            continue; /* mirrors and glass seen by hemisphere rays: not followed (as Radiance's ambient) */
        ic_rng rng = ic_rng_make(c->seed, (uint64_t)lv->level, hit.triangle,
                                 ((uint64_t)(uint32_t)(hit.u * 4294967040.0f) << 32) | (uint32_t)(hit.v * 4294967040.0f));
        /* The last level has no cache behind its hits: their direct light comes from every emitter. */
        int last = lv->level + 1 >= ls->level_count;
        ic_vec3 L = ic_ic_direct_light(c, &s, &b, wo, last ? &c->light_sel_all : NULL, &rng, &nrays);
        if (!last && ls->status == IC_OK) {
            /* Deeper levels get the footprint of a pixel 1/128 of the scene wide, so the pixel bounds
             * keep their records at least ~diagonal/85 apart (Radiance's -ar 128 plays this part). */
            ic_vec3 E = level_irradiance(ls, lv->level + 1, &s, b.frame.n, c->scene_diag / 128.0f);
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
    ic_gather_point gp = ic_ic_gather_point_of(&cd);
    ic_gather_result gr;
    ic_result r = c->o.gather.method == IC_GATHER_PROGRESSIVE ? ic_gather_progressive(ls->g[level], &gp, 1, &gr)
                                                              : ic_gather_stratified(ls->g[level], &gp, &gr);
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

static ic_result build_lazy(ic_ctx *c, const ic_render_options *opt, ic_render_stats *st, phase_times *pt,
                            ic_error *err)
{
    lazy_state ls;
    memset(&ls, 0, sizeof ls);
    ls.c = c;
    ls.pt = pt;
    ls.level_count = c->o.recursive ? (c->o.bounces < MAX_LEVELS ? c->o.bounces : MAX_LEVELS) : 1;
    ic_result r = IC_OK;
    for (int k = 0; k < ls.level_count && r == IC_OK; ++k) {
        ls.levels[k].c = c;
        ls.levels[k].level = k;
        ls.levels[k].state = &ls;
        r = c->o.recursive ? ic_gatherer_create(&c->o.gather, recursive_trace, &ls.levels[k], &ls.g[k], err)
                           : ic_gatherer_create(&c->o.gather, ic_ic_gather_trace, c, &ls.g[k], err);
    }
    size_t npix = (size_t)c->g.width * c->g.height;
    double t_insert = 0.0, t0 = ic_seconds();
    /* Raster order, then again while a pixel lost its cover to a later record's neighbor clamping. */
    for (int round = 0; round < 8 && r == IC_OK; ++round) {
        uint32_t added = 0;
        for (size_t i = 0; i < npix && r == IC_OK; ++i) {
            if ((i & 4095) == 0 && round == 0)
                ic_ic_report(opt, "lazy cache", (double)i / (double)npix);
            if (!c->g.valid[i])
                continue;
            ic_cache_lookup q = ic_cache_lookup_at(c->g.p[i], c->g.n[i], IC_ACCEPT_CONSTRUCTION);
            ic_cache_estimate e;
            if (ic_cache_query(c->cache, &q, &e))
                continue;
            ic_candidate cd = ic_ic_candidate_at_pixel(c, (uint32_t)i, (uint64_t)round);
            ic_gather_point gp = ic_ic_gather_point_of(&cd);
            ic_gather_result gr;
            r = c->o.gather.method == IC_GATHER_PROGRESSIVE ? ic_gather_progressive(ls.g[0], &gp, 1, &gr)
                                                            : ic_gather_stratified(ls.g[0], &gp, &gr);
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
            r = ic_cache_insert(c->cache, &rec, NULL, err);
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
    st->passes = 1;
    st->records_per_pass[0] = ic_cache_count(c->cache);
    return r;
}

/* ---------------------------------------------------------------- final render */

/* Indirect diffuse irradiance at a shading point: the cache (final acceptance), or, where no record
 * reaches (points seen only through glossy paths, sub-pixel samples at silhouettes), one cosine-
 * distributed hemisphere ray that returns what a record's ray would: E ≈ π·L. */
static ic_vec3 cached_irradiance(const ic_ctx *c, const ic_surface *s, ic_vec3 n, ic_cache_hint *hint, ic_rng *rng,
                                 uint64_t *rays, int *from_cache)
{
    ic_cache_lookup q = ic_cache_lookup_at(s->p, n, IC_ACCEPT_FINAL);
    ic_cache_estimate e;
    if (ic_cache_query_hinted(c->cache, &q, hint, &e)) {
        *from_cache = 1;
        return e.irradiance;
    }
    *from_cache = 0;
    ic_frame f = ic_frame_from_normal(n);
    ic_vec3 d = ic_frame_to_world(&f, ic_warp_cosine_hemisphere(ic_rng_float(rng), ic_rng_float(rng)));
    ic_ray ray = ic_spawn_ray(s, d);
    ic_hit hit;
    ++*rays;
    ic_accel_intersect1(c->tr->accel, &ray, &hit);
    if (hit.triangle == IC_NO_HIT)
        return v3_scale(ic_scene_env_radiance(c->tr->scene, d), IC_PI);
    ic_path_start st = {1, 0.0f, 1, 1, NULL};
    ic_vec3 L = v3_add(ic_pt_li_hit(&c->gather_tr, ray, &hit, &st, rng, rays), cached_emission(c, &ray, &hit));
    return v3_scale(L, IC_PI);
}

/* Shadow-tested contribution of one light sample (weight for the glossy lobe's MIS given by wg). */
static ic_vec3 shade_light(const ic_ctx *c, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo, const ic_light_sample *ls,
                           int mis, uint64_t *rays)
{
    ic_vec3 fd, fg;
    ic_bsdf_eval_lobes(b, wo, ls->wi, &fd, &fg);
    /* Each lobe is MIS-weighted against its own sampling: the diffuse lobe's cosine sample in
     * ic_ic_direct_light, the glossy lobe's in the final render's path. */
    float cos_pdf = fmaxf(v3_dot(ls->wi, b->frame.n), 0.0f) * IC_INV_PI;
    float wd = mis ? ic_power_heuristic(ls->pdf, cos_pdf) : 1.0f;
    float wg = mis ? ic_power_heuristic(ls->pdf, ic_bsdf_pdf_glossy(b, wo, ls->wi)) : 1.0f;
    ic_vec3 f = v3_add(v3_scale(fd, wd), v3_scale(fg, wg));
    if (v3_is_black(f) || v3_is_black(ls->radiance))
        return v3s(0.0f);
    ic_ray shadow = ic_shadow_ray(s, ls);
    ++*rays;
    if (ic_accel_occluded1(c->tr->accel, &shadow))
        return v3s(0.0f);
    return v3_scale(v3_mul(f, ls->radiance), fabsf(v3_dot(ls->wi, b->frame.n)) / ls->pdf);
}

/* The diffuse lobe's half of the MIS pair for emitting triangles: a cosine-distributed ray that counts
 * the emission it finds, weighted against light sampling. Light sampling alone is noisy next to small
 * emitters (a close point sees a small light under a large solid angle, which the area pdf samples
 * poorly); the records exclude this emission, so nothing is counted twice. */
static ic_vec3 diffuse_emission_sample(const ic_ctx *c, const ic_light_selection *sel, const ic_surface *s,
                                       const ic_bsdf *b, ic_rng *rng, uint64_t *rays)
{
    float u1, u2;
    ic_rng_2d(rng, &u1, &u2);
    if (!(sel->tri > 0.0f) || v3_is_black(b->kd))
        return v3s(0.0f);
    ic_vec3 wi = ic_frame_to_world(&b->frame, ic_warp_cosine_hemisphere(u1, u2));
    float cos_i = v3_dot(wi, b->frame.n);
    if (cos_i <= 0.0f || v3_dot(wi, b->ng) <= 0.0f)
        return v3s(0.0f);
    ic_ray ray = ic_spawn_ray(s, wi);
    ic_hit hit;
    ++*rays;
    ic_accel_intersect1(c->tr->accel, &ray, &hit);
    if (hit.triangle == IC_NO_HIT || c->tr->scene->triangle_light[hit.triangle] < 0)
        return v3s(0.0f);
    ic_surface hs;
    ic_scene_surface(c->tr->scene, hit.triangle, hit.u, hit.v, &hs);
    ic_vec3 le = ic_scene_emission(c->tr->scene, &hs, v3_neg(wi));
    if (v3_is_black(le))
        return v3s(0.0f);
    float pl = ic_scene_light_pdf_triangle_sel(c->tr->scene, sel, s->p, hit.triangle, wi, hit.t);
    /* An emitter light sampling never picks is a large one: the records carry its light. */
    if (!(pl > 0.0f))
        return v3s(0.0f);
    /* f_d·cos/p_cos = kd for the cosine-sampled Lambertian lobe. */
    return v3_scale(v3_mul(b->kd, le), ic_power_heuristic(cos_i * IC_INV_PI, pl));
}

/* Direct light for the final render. The environment is in the records and is not sampled here; the
 * sun, a single delta light, is taken every time (choosing it among the lights would only add noise);
 * triangle and point lights are sampled once by power, and emitting triangles once more through the
 * diffuse lobe (MIS, power heuristic); the glossy lobe's BSDF sample is the final render's path. */
ic_vec3 ic_ic_direct_light(const ic_ctx *c, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo,
                           const ic_light_selection *sel, ic_rng *rng, uint64_t *rays)
{
    if (!sel)
        sel = &c->light_sel;
    float u0 = ic_rng_1d(rng), u1, u2;
    ic_rng_2d(rng, &u1, &u2);
    ic_vec3 L = v3s(0.0f);
    const ic_scene *scene = c->tr->scene;
    if (scene->sun.enabled) {
        ic_light_sample sun;
        sun.wi = scene->sun.direction;
        sun.dist = INFINITY;
        sun.radiance = scene->sun.irradiance;
        sun.pdf = 1.0f;
        sun.is_delta = 1;
        L = shade_light(c, s, b, wo, &sun, 0, rays);
    }
    ic_light_sample ls;
    if (ic_scene_sample_light_sel(scene, sel, s->p, u0, u1, u2, &ls) && ls.pdf > 0.0f)
        L = v3_add(L, shade_light(c, s, b, wo, &ls, !ls.is_delta, rays));
    return v3_add(L, diffuse_emission_sample(c, sel, s, b, rng, rays));
}

typedef struct final_ctx {
    const ic_ctx *c;
    int indirect_only;         /* AOV: indirect diffuse at the first shading point only */
    ic_cache_hint *hints;      /* one per render thread: consecutive samples of a tile share leaves */
    int hint_count;            /* entries in hints (0: none) */
    ic_pixel_lights lights;    /* per-thread local light selection of the pixel being rendered */
} final_ctx;

static ic_vec3 final_sample(void *p, const ic_ray *camera_ray, uint32_t pixel, ic_rng *rng, int thread,
                            uint64_t *rays)
{
    const final_ctx *fc = p;
    /* Hints change speed only, never a result (cache.h), so images stay thread-count independent. */
    ic_cache_hint *hint = thread >= 0 && thread < fc->hint_count ? &fc->hints[thread] : NULL;
    const ic_ctx *c = fc->c;
    const ic_scene *scene = c->tr->scene;
    ic_ray ray = *camera_ray;
    ic_vec3 L = v3s(0.0f), beta = v3s(1.0f);
    int prev_glossy = 0; /* 0: camera or delta lobe, emission counts fully */
    float prev_pdf = 0.0f;
    ic_vec3 prev_p = ray.org;
    /* The first shading point samples lights by the local distribution of the pixel's block (built at
     * the cache shading point of the block's centre pixel, a function of the block alone); later
     * vertices by power. */
    ic_light_selection local;
    const ic_light_selection *sel = NULL, *prev_sel = &c->light_sel;
    if (!fc->indirect_only && fc->lights.count && pixel < (uint32_t)c->g.width * (uint32_t)c->g.height) {
        uint32_t a = ic_pixel_lights_anchor(&fc->lights, pixel);
        sel = ic_pixel_lights_get(&fc->lights, scene, thread, pixel, c->g.valid[a], c->g.p[a], c->g.n[a], &local);
    }
    if (!sel)
        sel = &c->light_sel;
    for (int depth = 0; depth <= c->tr->pt.max_depth; ++depth) {
        ic_hit hit;
        ++*rays;
        ic_accel_intersect1(c->tr->accel, &ray, &hit);
        if (hit.triangle == IC_NO_HIT) {
            /* The environment is never light-sampled in this integrator: full weight. */
            if (!fc->indirect_only)
                L = v3_add(L, v3_mul(beta, ic_scene_env_radiance(scene, ray.dir)));
            break;
        }
        ic_surface s;
        ic_scene_surface(scene, hit.triangle, hit.u, hit.v, &s);
        ic_vec3 wo = v3_neg(ray.dir);
        ic_vec3 le = ic_scene_emission(scene, &s, wo);
        if (!v3_is_black(le) && !fc->indirect_only) {
            float w = prev_glossy ? ic_power_heuristic(prev_pdf, ic_scene_light_pdf_triangle_sel(
                                                                     scene, prev_sel, prev_p, hit.triangle, ray.dir, hit.t))
                                  : 1.0f;
            L = v3_add(L, v3_scale(v3_mul(beta, le), w));
        }
        ic_bsdf b;
        ic_bsdf_init(&b, scene, &s, wo);
        ic_bsdf_sample bs;
        if (!ic_bsdf_has_smooth(&b)) {
            float u0 = ic_rng_1d(rng), u1, u2;
            ic_rng_2d(rng, &u1, &u2);
            if (!ic_bsdf_sample_dir(&b, wo, u0, u1, u2, &bs))
                break;
            beta = v3_mul(beta, bs.weight);
            prev_glossy = 0;
        } else {
            int from_cache;
            ic_vec3 E = cached_irradiance(c, &s, b.frame.n, hint, rng, rays, &from_cache);
            ic_vec3 indirect = v3_mul(v3_scale(b.kd, IC_INV_PI), E);
            if (fc->indirect_only)
                return v3_mul(beta, indirect);
            /* Several light samples per shading point: with indirect light from the cache, the direct
             * light's noise is what is left, and shadow rays are the cheapest rays there are. */
            ic_vec3 direct = v3s(0.0f);
            for (int k = 0; k < c->o.light_samples; ++k)
                direct = v3_add(direct, ic_ic_direct_light(c, &s, &b, wo, sel, rng, rays));
            prev_sel = sel;
            sel = &c->light_sel;
            direct = v3_scale(direct, 1.0f / (float)c->o.light_samples);
            L = v3_add(L, v3_mul(beta, v3_add(indirect, direct)));
            float u1, u2;
            ic_rng_2d(rng, &u1, &u2);
            if (!ic_bsdf_has_glossy(&b) || !ic_bsdf_sample_glossy(&b, wo, u1, u2, &bs))
                break;
            beta = v3_mul(beta, bs.weight);
            prev_glossy = 1;
            prev_pdf = bs.pdf;
        }
        prev_p = s.p;
        if (!ic_russian_roulette(&beta, depth, c->tr->pt.rr_depth, rng))
            break;
        ray = ic_spawn_ray(&s, bs.wi);
    }
    return L;
}

/* ---------------------------------------------------------------- diagnostics */

static int project(const ic_camera *cam, ic_vec3 p, float *fx, float *fy, float *depth)
{
    ic_vec3 fwd = v3_norm(v3_sub(cam->target, cam->eye));
    ic_vec3 right = v3_norm(v3_cross(fwd, cam->up));
    ic_vec3 up = v3_cross(right, fwd);
    ic_vec3 d = v3_sub(p, cam->eye);
    float z = v3_dot(d, fwd);
    if (z <= 0.0f)
        return 0;
    float th = tanf(0.5f * cam->fov_y_deg * IC_PI / 180.0f), aspect = (float)cam->width / (float)cam->height;
    float sx = v3_dot(d, right) / (z * th * aspect), sy = v3_dot(d, up) / (z * th);
    *fx = (sx + 1.0f) * 0.5f * (float)cam->width;
    *fy = (1.0f - sy) * 0.5f * (float)cam->height;
    *depth = z;
    return 1;
}

static void put(ic_image *img, int x, int y, ic_vec3 c)
{
    if (x < 0 || y < 0 || x >= img->width || y >= img->height)
        return;
    float *px = &img->rgb[3 * ((size_t)y * img->width + x)];
    px[0] = c.x;
    px[1] = c.y;
    px[2] = c.z;
}

/* Where a record appears in the image, and whether the camera sees its surface directly (the G-buffer
 * point at its pixel is next to it). */
static ic_record_view view_of(const ic_ctx *c, const ic_record *rec)
{
    const ic_camera *cam = &c->tr->scene->camera;
    ic_record_view v;
    memset(&v, 0, sizeof v);
    v.position = rec->position;
    v.radius = rec->radius;
    v.accuracy = rec->accuracy;
    float z;
    if (!project(cam, rec->position, &v.px, &v.py, &z))
        return v;
    v.radius_px = rec->accuracy * rec->radius / (z * c->pixel_angle);
    int px = (int)v.px, py = (int)v.py;
    if (px < 0 || py < 0 || px >= cam->width || py >= cam->height)
        return v;
    size_t gi = (size_t)py * cam->width + px;
    v.visible = c->g.valid[gi] &&
                v3_len(v3_sub(c->g.p[gi], rec->position)) <= 4.0f * c->g.footprint[gi] + 1e-4f * c->scene_diag;
    return v;
}

static ic_result record_views(const ic_ctx *c, ic_record_view **out, uint32_t *count)
{
    uint32_t n = ic_cache_count(c->cache);
    *out = malloc(sizeof **out * (n ? n : 1));
    *count = 0;
    if (!*out)
        return IC_ERR_OOM;
    for (uint32_t i = 0; i < n; ++i) {
        ic_record rec;
        if (ic_cache_get_record(c->cache, i, &rec) == IC_OK)
            (*out)[(*count)++] = view_of(c, &rec);
    }
    return IC_OK;
}

/* Records the camera sees are drawn as a dot with a circle of their influence radius a_i·R_i, over a
 * darkened copy of the image. */
static ic_result draw_records(const ic_ctx *c, const ic_image *beauty, ic_image *out)
{
    ic_result r = ic_image_create(out, beauty->width, beauty->height);
    if (r != IC_OK)
        return r;
    size_t n = (size_t)beauty->width * beauty->height * 3;
    for (size_t i = 0; i < n; ++i)
        out->rgb[i] = 0.5f * beauty->rgb[i];
    uint32_t count = ic_cache_count(c->cache);
    for (uint32_t i = 0; i < count; ++i) {
        ic_record rec;
        if (ic_cache_get_record(c->cache, i, &rec) != IC_OK)
            continue;
        ic_record_view v = view_of(c, &rec);
        if (!v.visible)
            continue;
        ic_vec3 ring = v3(0.1f, 1.0f, 0.2f), dot = v3(1.0f, 0.15f, 0.1f);
        int steps = (int)(6.3f * v.radius_px) + 8;
        for (int k = 0; k < steps && v.radius_px >= 1.0f; ++k) {
            float a = 2.0f * IC_PI * (float)k / (float)steps;
            put(out, (int)(v.px + v.radius_px * cosf(a)), (int)(v.py + v.radius_px * sinf(a)), ring);
        }
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx)
                put(out, (int)v.px + dx, (int)v.py + dy, dot);
    }
    return IC_OK;
}

static ic_result density_image(ic_ctx *c, ic_image *out)
{
    ic_result r = ic_image_create(out, c->g.width, c->g.height);
    if (r != IC_OK)
        return r;
    ic_cache_hint hint = {0}; /* raster order: neighbouring pixels mostly share a leaf */
    for (int y = 0; y < c->g.height; ++y) {
        for (int x = 0; x < c->g.width; ++x) {
            size_t i = (size_t)y * c->g.width + x;
            if (!c->g.valid[i])
                continue;
            ic_cache_lookup q = ic_cache_lookup_at(c->g.p[i], c->g.n[i], IC_ACCEPT_FINAL);
            ic_cache_estimate e;
            ic_cache_query_hinted(c->cache, &q, &hint, &e);
            out->rgb[3 * i] = out->rgb[3 * i + 1] = out->rgb[3 * i + 2] = (float)e.contributor_count;
        }
    }
    return IC_OK;
}

/* ---------------------------------------------------------------- entry point */

static void resolve_options(ic_ctx *c, const ic_ic_options *in, const ic_scene *scene)
{
    ic_ic_options o = *in;
    /* Records gather as many bounces as the path tracer follows (max_depth scattering events in all,
     * the record's own point being the first): truncating earlier darkens the image measurably. */
    if (o.bounces <= 0)
        o.bounces = c->tr->pt.max_depth > 1 ? c->tr->pt.max_depth - 1 : 1;
    if (o.light_samples <= 0)
        o.light_samples = 1;
    if (o.large_emitters == 0.0f)
        o.large_emitters = IC_LARGE_EMITTERS;
    if (o.max_passes <= 0)
        o.max_passes = 12;
    if (o.min_candidates <= 0)
        o.min_candidates = 16;
    if (o.screen_passes <= 0)
        o.screen_passes = 3;
    if (o.dither_threshold <= 0.0f)
        o.dither_threshold = 0.5f;
    if (o.normal_weight <= 0.0f)
        o.normal_weight = 4.0f;
    if (o.world_stride <= 0)
        o.world_stride = 2;
    if (o.cluster_size <= 0.0f)
        o.cluster_size = 0.05f;
    if (o.cache.accuracy == 0.0f)
        o.cache.accuracy = o.cache.weight == IC_WEIGHT_TABELLION ? 1.0f : 0.3f;
    /* Radius bounds: 0 means the renderer's default, negative switches the bound off. The pixel bounds
     * given to the renderer bound a record's influence radius a·R on screen (what a user sees: "a record
     * covers between 3 and 48 pixels"); the cache clamps R itself, hence the division by a. The floor of
     * 3 pixels, not 1.5: records closer than that mostly average their own Monte Carlo noise; on Sponza
     * at 448×252 it cut records by a quarter and lowered the error (BENCHMARKS.md). */
    float diag = v3_len(v3_sub(scene->bounds_max, scene->bounds_min));
    float min_px = o.cache.min_radius_pixels == 0.0f ? 3.0f : fmaxf(o.cache.min_radius_pixels, 0.0f);
    float max_px = o.cache.max_radius_pixels == 0.0f ? 48.0f : fmaxf(o.cache.max_radius_pixels, 0.0f);
    o.cache.min_radius_pixels = min_px / o.cache.accuracy;
    o.cache.max_radius_pixels = max_px / o.cache.accuracy;
    o.cache.max_radius = o.cache.max_radius == 0.0f ? diag / 8.0f : (o.cache.max_radius < 0.0f ? INFINITY : o.cache.max_radius);
    o.cache.min_radius = fmaxf(o.cache.min_radius, 0.0f);
    c->o = o;
    c->scene_diag = diag > 0.0f ? diag : 1.0f;
}

/* Projected solid angle of triangle (a, b, c) seen from p above the plane with normal n, over π: the
 * share of p's cosine-weighted hemisphere it covers, unoccluded. The solid angle is Van Oosterom and
 * Strackee's (1983) closed form; the cosine is taken at the triangle's centroid (a small triangle's
 * exact value, a fair one for a large triangle seen from afar). */
static double hemisphere_share(ic_vec3 p, ic_vec3 n, ic_vec3 a, ic_vec3 b, ic_vec3 c)
{
    ic_vec3 ra = v3_sub(a, p), rb = v3_sub(b, p), rc = v3_sub(c, p);
    double la = v3_len(ra), lb = v3_len(rb), lc = v3_len(rc);
    double num = fabs((double)v3_dot(ra, v3_cross(rb, rc)));
    double den = la * lb * lc + v3_dot(ra, rb) * lc + v3_dot(ra, rc) * lb + v3_dot(rb, rc) * la;
    double omega = 2.0 * atan2(num, den);
    ic_vec3 d = v3_sub(v3_scale(v3_add(v3_add(a, b), c), 1.0f / 3.0f), p);
    double dl = v3_len(d), cos_r = dl > 0.0 ? v3_dot(d, n) / dl : 0.0;
    return cos_r > 0.0 && isfinite(omega) ? omega * cos_r / IC_PI : 0.0;
}

static int cmp_double(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* Of the light samples a shading point would take on material m's emitting triangles (by area, from
 * every stride-th valid pixel's shading point, 8 each), the fraction no surface hides, among those
 * that face the point and that it faces; 1 when there are none, -1 when out of memory. */
static double visible_fraction(const ic_ctx *c, const ic_scene *s, uint32_t m, size_t stride)
{
    uint32_t count = 0;
    for (uint32_t li = 0; li < s->tri_light_count; ++li)
        count += s->triangle_material[s->tri_lights[li].triangle] == m;
    uint32_t *tri = malloc(sizeof *tri * (count ? count : 1));
    double *cdf = malloc(sizeof *cdf * (count + 1));
    if (!tri || !cdf) {
        free(tri);
        free(cdf);
        return -1.0;
    }
    cdf[0] = 0.0;
    for (uint32_t li = 0, k = 0; li < s->tri_light_count; ++li)
        if (s->triangle_material[s->tri_lights[li].triangle] == m) {
            tri[k] = li;
            cdf[k + 1] = cdf[k] + s->tri_lights[li].area;
            ++k;
        }
    size_t npix = (size_t)c->g.width * c->g.height, seen = 0, open = 0;
    for (size_t i = 0, k = 0; i < npix && count; ++i) {
        if (!c->g.valid[i] || k++ % stride)
            continue;
        ic_rng rng = ic_rng_make(c->seed, 0x6c61726765ULL, i, 0);
        for (int j = 0; j < 8; ++j) {
            /* A triangle by area: the last cdf entry below u. */
            double u = ic_rng_double(&rng) * cdf[count];
            uint32_t lo = 0, hi = count - 1;
            while (lo < hi) {
                uint32_t mid = (lo + hi + 1) / 2;
                if (cdf[mid] <= u)
                    lo = mid;
                else
                    hi = mid - 1;
            }
            const ic_tri_light *l = &s->tri_lights[tri[lo]];
            float b1, b2;
            ic_warp_triangle(ic_rng_float(&rng), ic_rng_float(&rng), &b1, &b2);
            const uint32_t *v = &s->triangles[3 * l->triangle];
            ic_vec3 x = v3_add(v3_add(v3_scale(s->positions[v[0]], 1.0f - b1 - b2), v3_scale(s->positions[v[1]], b1)),
                               v3_scale(s->positions[v[2]], b2));
            ic_vec3 d = v3_sub(x, c->g.p[i]);
            float dist = v3_len(d);
            if (!(dist > 0.0f))
                continue;
            d = v3_scale(d, 1.0f / dist);
            if (v3_dot(d, c->g.n[i]) <= 0.0f || (!l->two_sided && v3_dot(d, l->normal) >= 0.0f))
                continue;
            ic_ray r = {ic_offset_ray_origin(c->g.p[i], c->g.n[i], d), d, 0.0f, dist * (1.0f - 1e-3f)};
            ++seen;
            open += !ic_accel_occluded1(c->tr->accel, &r);
        }
    }
    free(tri);
    free(cdf);
    return seen ? (double)open / (double)seen : 1.0;
}

/* Large emitters. Seed 004 §3 caches all indirect light, and renderers built on a cache leave the sky
 * to the records; this extends that to an emitting material that is large and partly hidden: one that
 * covers, at the median shading point of the image, at least large_emitters of the cosine-weighted
 * hemisphere (hemisphere_share, unoccluded) and of whose light samples at most
 * IC_LARGE_EMITTER_VISIBLE reach it (visible_fraction). Such an emitter — staircase2's window quads —
 * is where light sampling is at its worst (most samples land on hidden parts, and each visible one
 * carries a large weight), while its irradiance varies slowly (a source that large casts soft
 * shadows), which is what the cache interpolates well. It is then not light-sampled in the final
 * render; the hemisphere rays count its emission instead, so the records carry its direct light, as
 * they carry the environment's. A lamp like the Cornell box's (0.6 % of the hemisphere, 90 % of its
 * samples visible) keeps being sampled: the cache would blur its sharper shadows. Fills
 * direct_pmf/direct_cdf and narrows light_sel to the emitters left; returns 0 when out of memory. */
static int cache_large_emitters(ic_ctx *c, const ic_scene *s)
{
    if (!(c->o.large_emitters >= 0.0f) || s->tri_light_count == 0 || !(s->tri_light_power > 0.0f))
        return 1;
    size_t npix = (size_t)c->g.width * c->g.height, valid = 0;
    for (size_t i = 0; i < npix; ++i)
        valid += c->g.valid[i];
    if (valid == 0)
        return 1;
    /* At most ~1024 shading points, evenly through the image, and fewer where there are so many
     * emitting triangles that points × triangles would pass 2^23 (at least ~64 points). */
    size_t want = ((size_t)1 << 23) / s->tri_light_count;
    want = want < 64 ? 64 : want > 1024 ? 1024 : want;
    size_t stride = valid / want + 1, points = 0, cap = valid / stride + 1; /* cap: sampled points, at most */
    /* Shares per emitting material (slot[m]: its row, UINT32_MAX for the others) and sampled point. */
    uint32_t nm = s->material_count, ne = 0;
    uint32_t *slot = malloc(sizeof *slot * (nm ? nm : 1));
    uint8_t *cached_mat = calloc(nm ? nm : 1, 1);
    double *row = malloc(sizeof *row * cap), *share = NULL;
    if (slot) {
        for (uint32_t m = 0; m < nm; ++m)
            slot[m] = v3_is_black(s->materials[m].emission) ? UINT32_MAX : ne++;
        share = calloc((size_t)(ne ? ne : 1) * cap, sizeof *share);
    }
    if (!slot || !share || !cached_mat || !row) {
        free(slot);
        free(share);
        free(cached_mat);
        free(row);
        return 0;
    }
    for (size_t i = 0, k = 0; i < npix; ++i) {
        if (!c->g.valid[i] || k++ % stride)
            continue;
        ic_vec3 p = c->g.p[i], n = c->g.n[i];
        for (uint32_t li = 0; li < s->tri_light_count; ++li) {
            const ic_tri_light *l = &s->tri_lights[li];
            uint32_t t = l->triangle;
            /* Only the emitting side counts. */
            if (!l->two_sided && v3_dot(l->normal, v3_sub(p, l->centroid)) <= 0.0f)
                continue;
            share[(size_t)slot[s->triangle_material[t]] * cap + points] +=
                hemisphere_share(p, n, s->positions[s->triangles[3 * t]], s->positions[s->triangles[3 * t + 1]],
                                 s->positions[s->triangles[3 * t + 2]]);
        }
        ++points;
    }
    uint32_t cached = 0;
    double kept = 0.0;
    for (uint32_t m = 0; m < nm; ++m) {
        if (slot[m] == UINT32_MAX)
            continue;
        memcpy(row, &share[(size_t)slot[m] * cap], sizeof *row * points);
        qsort(row, points, sizeof *row, cmp_double);
        double v = row[points / 2] >= c->o.large_emitters ? visible_fraction(c, s, m, stride) : 1.0;
        if (v < 0.0) {
            free(slot);
            free(share);
            free(row);
            free(cached_mat);
            return 0;
        }
        cached_mat[m] = v <= IC_LARGE_EMITTER_VISIBLE;
    }
    free(slot);
    free(share);
    free(row);
    for (uint32_t i = 0; i < s->tri_light_count; ++i) {
        if (cached_mat[s->triangle_material[s->tri_lights[i].triangle]])
            ++cached;
        else
            kept += s->tri_lights[i].power;
    }
    if (cached == 0) {
        free(cached_mat);
        return 1;
    }
    c->direct_pmf = malloc(sizeof *c->direct_pmf * s->tri_light_count);
    c->direct_cdf = malloc(sizeof *c->direct_cdf * (s->tri_light_count + 1));
    if (!c->direct_pmf || !c->direct_cdf) {
        free(cached_mat);
        return 0;
    }
    double sum = 0.0;
    c->direct_cdf[0] = 0.0f;
    for (uint32_t i = 0; i < s->tri_light_count; ++i) {
        int big = cached_mat[s->triangle_material[s->tri_lights[i].triangle]];
        c->direct_pmf[i] = big || !(kept > 0.0) ? 0.0f : (float)(s->tri_lights[i].power / kept);
        sum += c->direct_pmf[i];
        c->direct_cdf[i + 1] = (float)sum;
    }
    if (kept > 0.0)
        c->direct_cdf[s->tri_light_count] = 1.0f;
    free(cached_mat);
    c->cached_emitters = cached;
    /* The class probabilities follow the power left to sample. */
    double tri = c->light_sel.tri * kept / s->tri_light_power, point = c->light_sel.point;
    c->light_sel.tri = tri + point > 0.0 ? (float)(tri / (tri + point)) : 0.0f;
    c->light_sel.point = tri + point > 0.0 ? (float)(point / (tri + point)) : 0.0f;
    c->light_sel.tri_pmf = kept > 0.0 ? c->direct_pmf : NULL;
    c->light_sel.tri_cdf = kept > 0.0 ? c->direct_cdf : NULL;
    return 1;
}

ic_result ic_ic_ctx_create(const ic_tracer *tr, const ic_render_options *opt, ic_ctx **out, double *gbuffer_seconds,
                           ic_error *err)
{
    *out = NULL;
    ic_ctx *c = calloc(1, sizeof *c);
    if (!c)
        return ic_error_set(err, IC_ERR_OOM, "out of memory");
    c->tr = tr;
    c->seed = opt->seed;
    c->threads = ic_resolve_threads(opt->threads);
    c->pixel_angle = ic_camera_pixel_angle(&tr->scene->camera);
    atomic_init(&c->rays, 0);
    resolve_options(c, &opt->ic, tr->scene);
    float sel_sum = tr->scene->light_select.tri + tr->scene->light_select.point;
    if (sel_sum > 0.0f) {
        c->light_sel.tri = tr->scene->light_select.tri / sel_sum;
        c->light_sel.point = tr->scene->light_select.point / sel_sum;
    }
    c->light_sel_all = c->light_sel;
    c->gather_tr = *tr;
    c->gather_tr.pt.max_depth = c->o.bounces + 1;
    /* With one bounce a hemisphere ray returns its hit's direct light alone; records hold more. */
    c->hit_lookups = !c->o.path_traced_gather && !c->o.recursive && c->o.bounces > 1;
    c->o.gather.seed ^= opt->seed;
    c->o.cache.threads = opt->threads;
    ic_result r = ic_cache_create(&c->o.cache, &c->cache, err);
    double t0 = ic_seconds();
    if (r == IC_OK)
        r = build_gbuffer(c, err);
    if (gbuffer_seconds)
        *gbuffer_seconds = ic_seconds() - t0;
    if (r == IC_OK && !cache_large_emitters(c, tr->scene))
        r = ic_error_set(err, IC_ERR_OOM, "out of memory for the light tables");
    if (r != IC_OK) {
        ic_ic_ctx_destroy(c);
        return r;
    }
    *out = c;
    return IC_OK;
}

void ic_ic_ctx_destroy(ic_ctx *c)
{
    if (!c)
        return;
    ic_cache_destroy(c->cache);
    free_gbuffer(c);
    free(c->direct_pmf);
    free(c->direct_cdf);
    free(c);
}

ic_result ic_ic_build(ic_ctx *c, const ic_render_options *opt, ic_render_stats *st, phase_times *pt, ic_error *err)
{
    return c->o.strategy == IC_STRATEGY_LAZY       ? build_lazy(c, opt, st, pt, err)
           : c->o.strategy == IC_STRATEGY_ADAPTIVE ? ic_ic_build_adaptive(c, opt, st, pt, err)
                                                   : build_batch(c, opt, st, pt, err);
}

/* Hash of everything a record's value depends on besides the cache parameters (which the cache file
 * records itself): geometry, materials, textures' sizes, lights, environment, and how records gather. */
static uint64_t records_hash(const ic_ctx *c)
{
    const ic_scene *s = c->tr->scene;
    uint64_t h = IC_FNV64_OFFSET;
    h = ic_fnv1a64(h, s->positions, sizeof *s->positions * s->vertex_count);
    h = ic_fnv1a64(h, s->triangles, sizeof *s->triangles * 3 * (size_t)s->triangle_count);
    h = ic_fnv1a64(h, s->triangle_material, sizeof *s->triangle_material * s->triangle_count);
    for (uint32_t i = 0; i < s->material_count; ++i) {
        const ic_material *m = &s->materials[i];
        float f[14] = {m->kd.x, m->kd.y, m->kd.z, m->ks.x, m->ks.y, m->ks.z, m->ns, m->emission.x, m->emission.y,
                       m->emission.z, m->ior, (float)m->type, (float)m->kd_texture, (float)m->two_sided_emission};
        h = ic_fnv1a64(h, f, sizeof f);
    }
    for (uint32_t i = 0; i < s->texture_count; ++i) {
        /* The texel values as floats, however they are stored (the hash streams: same bytes, same hash). */
        const ic_texture *t = &s->textures[i];
        size_t n = 3 * (size_t)t->width * (size_t)t->height;
        if (t->rgb) {
            h = ic_fnv1a64(h, t->rgb, sizeof(float) * n);
            continue;
        }
        enum { CHUNK = 768 };
        float chunk[CHUNK];
        for (size_t at = 0; at < n; at += CHUNK) {
            size_t m = n - at < CHUNK ? n - at : CHUNK;
            for (size_t k = 0; k < m; ++k)
                chunk[k] = ic_texture_value(t, at + k);
            h = ic_fnv1a64(h, chunk, sizeof(float) * m);
        }
    }
    h = ic_fnv1a64(h, s->point_lights, sizeof *s->point_lights * s->point_light_count);
    float env[12] = {(float)s->sun.enabled, s->sun.direction.x, s->sun.direction.y, s->sun.direction.z,
                     s->sun.irradiance.x, s->sun.irradiance.y, s->sun.irradiance.z, (float)s->env.enabled,
                     s->env.radiance.x, s->env.radiance.y, s->env.radiance.z, s->env.rotation_deg};
    h = ic_fnv1a64(h, env, sizeof env);
    if (s->env.image.rgb)
        h = ic_fnv1a64(h, s->env.image.rgb, sizeof(float) * 3 * (size_t)s->env.image.width * s->env.image.height);
    h = ic_fnv1a64(h, &c->cached_emitters, sizeof c->cached_emitters);
    if (c->direct_pmf)
        h = ic_fnv1a64(h, c->direct_pmf, sizeof *c->direct_pmf * s->tri_light_count);
    int32_t g[9] = {c->o.bounces, c->o.no_gradients, (int32_t)c->o.gather.method, (int32_t)c->o.gather.theta_strata,
                    (int32_t)c->o.gather.phi_strata, (int32_t)c->o.gather.max_rays, (int32_t)c->o.gather.tgrad,
                    (int32_t)c->o.strategy, c->hit_lookups};
    /* The seed is left out on purpose: records built with one seed are as valid as any others, and a
     * cache re-used with a new seed renders an independent final image over the same records. */
    return ic_fnv1a64(h, g, sizeof g);
}

ic_result ic_render_ic(const ic_tracer *tr, const ic_render_options *opt, ic_image *out, ic_render_stats *st,
                       ic_error *err)
{
    ic_ctx *c = NULL;
    ic_cache_hint *hints = NULL;
    double t_gbuffer = 0.0, t_candidates = 0.0;
    phase_times pt = {0, 0};
    ic_result r = ic_ic_ctx_create(tr, opt, &c, &t_gbuffer, err);
    if (r != IC_OK)
        return r;
    if (c->o.recursive && c->o.strategy != IC_STRATEGY_LAZY) {
        r = ic_error_set(err, IC_ERR_INVALID_ARG, "recursive caching builds its levels lazily; use the lazy strategy");
        goto done;
    }
    if (c->o.load_cache) {
        /* Records from an earlier run: refused (with the cache library's message) when they were made
         * for another scene, other gathering settings or other cache parameters. */
        ic_cache *loaded = NULL;
        double t0 = ic_seconds();
        r = ic_cache_load(c->o.load_cache, &c->o.cache, records_hash(c), &loaded, err);
        if (r != IC_OK)
            goto done;
        ic_cache_destroy(c->cache);
        c->cache = loaded;
        pt.insert += ic_seconds() - t0;
    } else {
        double t0 = ic_seconds();
        int phases_before = st->phase_count;
        r = ic_ic_build(c, opt, st, &pt, err);
        if (r != IC_OK)
            goto done;
        /* What construction spent outside gathering and insertion and outside the phases the strategy
         * reports itself (adaptive: its own): discontinuity maps, look-up sweeps, world-stage paths,
         * clustering for batch; the raster sweep for lazy. */
        double own = 0.0;
        for (int k = phases_before; k < st->phase_count; ++k)
            own += st->phases[k].seconds;
        t_candidates = fmax(ic_seconds() - t0 - pt.gather - pt.insert - own, 0.0);
        /* The final render reads a freshly built index: look-ups are faster than through the
         * incrementally grown one, and the summation order of every look-up is the same as after
         * loading a cache file, so a saved and re-loaded cache renders the identical image. */
        t0 = ic_seconds();
        if ((r = ic_cache_rebuild_index(c->cache, err)) != IC_OK)
            goto done;
        pt.insert += ic_seconds() - t0;
    }
    if (c->o.save_cache && (r = ic_cache_save(c->cache, c->o.save_cache, records_hash(c), err)) != IC_OK)
        goto done;
    st->records = ic_cache_count(c->cache);
    st->cached_emitters = c->cached_emitters;
    st->gather_rays = atomic_load(&c->rays);

    ic_image_loop loop;
    memset(&loop, 0, sizeof loop);
    loop.camera = &tr->scene->camera;
    loop.spp = opt->spp;
    loop.time_budget = opt->time_budget;
    loop.threads = opt->threads;
    loop.seed = opt->seed;
    loop.random_sampler = opt->sampler == IC_SAMPLER_RANDOM;
    /* The final render samples adaptively by default, as seed 004's does (§3.2), where it can. */
    loop.adaptive = opt->adaptive_sampling > 0 ||
                    (opt->adaptive_sampling == 0 && opt->spp >= 8 && !(opt->time_budget > 0.0));
    loop.phase = "final render";
    loop.progress = opt->progress;
    loop.progress_user = opt->progress_user;
    int hint_count = ic_resolve_threads(loop.threads);
    hints = calloc((size_t)hint_count, sizeof *hints);
    final_ctx fc = {c, 0, hints, hints ? hint_count : 0, {0}}; /* no hints: slower, the same image */
    ic_image_loop_result lr;
    r = ic_pixel_lights_init(&fc.lights, tr->scene, c->light_sel, hint_count, c->g.width, c->g.height);
    if (r != IC_OK) {
        ic_error_set(err, r, "out of memory for the per-thread light tables");
        goto done;
    }
    r = ic_render_image(&loop, final_sample, &fc, out, &lr, err);
    ic_pixel_lights_free(&fc.lights); /* the indirect AOV below samples no lights */
    if (r != IC_OK)
        goto done;
    st->spp = lr.spp_done;
    st->spp_max = lr.spp_max;
    st->rays = lr.rays + st->gather_rays;
    if (st->phase_count + 5 <= IC_MAX_PHASES) {
        st->phases[st->phase_count].name = "shading points";
        st->phases[st->phase_count++].seconds = t_gbuffer;
        st->phases[st->phase_count].name = "candidates";
        st->phases[st->phase_count++].seconds = t_candidates;
        st->phases[st->phase_count].name = "gathering";
        st->phases[st->phase_count++].seconds = pt.gather;
        st->phases[st->phase_count].name = "insertion";
        st->phases[st->phase_count++].seconds = pt.insert;
        st->phases[st->phase_count].name = "final render";
        st->phases[st->phase_count++].seconds = lr.seconds;
    }
    if (opt->aovs) {
        ic_render_aovs *a = opt->aovs;
        if (a->want_indirect) {
            fc.indirect_only = 1;
            loop.phase = "indirect AOV";
            loop.time_budget = 0.0;
            loop.adaptive = 0;
            loop.spp = lr.spp_done;
            ic_image_loop_result lr2;
            r = ic_render_image(&loop, final_sample, &fc, &a->indirect, &lr2, err);
            if (r != IC_OK)
                goto done;
        }
        if (a->want_records && (r = draw_records(c, out, &a->records)) != IC_OK) {
            ic_error_set(err, r, "out of memory for the records AOV");
            goto done;
        }
        if (a->want_record_list && (r = record_views(c, &a->record_views, &a->record_view_count)) != IC_OK) {
            ic_error_set(err, r, "out of memory for the record list");
            goto done;
        }
        if (a->want_density && (r = density_image(c, &a->density)) != IC_OK) {
            ic_error_set(err, r, "out of memory for the density AOV");
            goto done;
        }
        if (a->want_amap && (r = ic_ic_amap_image(c, &a->amap)) != IC_OK) {
            ic_error_set(err, r, "out of memory for the amap AOV");
            goto done;
        }
    }
done:
    free(hints);
    ic_ic_ctx_destroy(c);
    return r;
}
