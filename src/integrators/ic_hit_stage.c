/*
 * ic_hit_stage.c — records where hemisphere rays land, before the records they serve: Ward's multiple
 * bounces as Radiance's ambient file serves them (Ward et al. 1988 §3), built as the world-space stage of
 * Frolov et al. 2012 §3.1.3 builds records, with probe rays from given points in place of eye paths.
 * The sensors' construction uses it (its records are the irradiance a sensor's rays read at their hits),
 * and so does batch construction of an image (--hit-records, on by default; records of their own kind,
 * without gradients, that only hemisphere rays read: ic_batch.c).
 */
#include "ic_internal.h"

#include "core/comm.h"
#include "core/sampling.h"
#include "core/select.h"
#include "core/threads.h"
#include "integrators/ic_world.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Probe rays per point and pass, and the most passes. */
#define HIT_PROBES 16
#define HIT_PROBES_MAX 4096 /* in all, per pass */
#define HIT_MAX_PASSES 12

/* Probes per pass: HIT_PROBES per point up to HIT_PROBES_MAX in all, spread evenly over the points
 * (the hit records describe the scene, whose size does not grow with the points); probe k's point. */
uint32_t ic_ic_hit_probes(uint32_t count)
{
    return count > HIT_PROBES_MAX / HIT_PROBES ? HIT_PROBES_MAX : count * HIT_PROBES;
}

uint32_t ic_ic_hit_probe_point(uint32_t k, uint32_t count)
{
    return (uint32_t)((uint64_t)k * count / ic_ic_hit_probes(count));
}

/* One pass of probe rays: probe k of the process's block traces from its point and leaves in slot[k] the
 * diffuse hit that no record of kind `bounce` accepts (state[k] 2, its hit distance in the footprint) or
 * none (state[k] 1: a diffuse hit that a record accepts; 0: no diffuse hit). */
typedef struct probe_job {
    ic_ctx *c;
    const ic_vec3 *p, *n;
    uint32_t count, first;
    uint64_t key_tag;
    uint8_t bounce;
    int pass;
    ic_candidate *slot;
    uint8_t *state;
} probe_job;

static void probe_one(void *ctx, int64_t item, int thread)
{
    (void)thread;
    const probe_job *j = ctx;
    ic_ctx *c = j->c;
    const ic_scene *scene = c->tr->scene;
    const uint32_t k = j->first + (uint32_t)item, i = ic_ic_hit_probe_point(k, j->count);
    j->state[item] = 0;
    ic_frame f = ic_frame_from_normal(j->n[i]);
    ic_rng rng = ic_rng_make(c->seed ^ j->key_tag, i, (uint64_t)j->pass, k);
    float u1, u2;
    ic_rng_2d(&rng, &u1, &u2);
    ic_ray ray = {j->p[i], ic_frame_to_world(&f, ic_warp_cosine_hemisphere(u1, u2)), 0.0f, INFINITY};
    ic_hit hit;
    ic_accel_intersect1(c->tr->accel, &ray, &hit);
    if (hit.triangle == IC_NO_HIT)
        return;
    ic_surface s;
    ic_scene_surface(scene, hit.triangle, hit.u, hit.v, &s);
    ic_bsdf b;
    ic_bsdf_init(&b, scene, &s, v3_neg(ray.dir));
    if (!ic_bsdf_has_smooth(&b) || ic_bsdf_has_glossy(&b))
        return; /* only diffuse hits look the cache up */
    j->state[item] = 1;
    ic_cache_lookup q = ic_cache_lookup_at(s.p, b.cache_n, IC_ACCEPT_CONSTRUCTION);
    q.bounce = j->bounce;
    ic_cache_estimate e;
    if (ic_cache_query(c->cache, &q, &e))
        return;
    j->state[item] = 2;
    ic_candidate *cd = &j->slot[item];
    cd->p = s.p;
    cd->n = b.cache_n;
    cd->footprint = hit.t;
    cd->key = ic_hash4(j->key_tag ^ 0x686974ULL, i, (uint64_t)j->pass, k);
}

/* Several processes: every one's count of candidates and of diffuse hits in one exchange, then the
 * candidates (this one's n at the start of cand) in process order; *total and *seen get the sums. */
static ic_result exchange_probes(ic_comm *comm, ic_candidate *cand, uint32_t n, uint64_t *total, double *seen,
                                 ic_error *err)
{
    typedef struct tally {
        uint64_t count;
        double seen;
    } tally;
    const int ranks = comm->size;
    tally *t = malloc(sizeof *t * (size_t)ranks);
    uint64_t *bytes = malloc(sizeof *bytes * (size_t)ranks);
    ic_result r = t && bytes ? IC_OK : ic_error_set(err, IC_ERR_OOM, "out of memory for %d processes' probes", ranks);
    if (r == IC_OK) {
        t[comm->rank] = (tally){n, *seen};
        for (int q = 0; q < ranks; ++q)
            bytes[q] = sizeof *t;
        r = ic_comm_allgather_sized(comm, t, bytes, "exchanging the probes' counts", err);
    }
    uint64_t before = 0;
    *total = 0;
    *seen = 0.0;
    for (int q = 0; r == IC_OK && q < ranks; ++q) {
        before += q < comm->rank ? t[q].count : 0;
        *total += t[q].count;
        *seen += t[q].seen; /* whole numbers: exact in any order */
        bytes[q] = t[q].count * sizeof *cand;
    }
    if (r == IC_OK) {
        memmove(cand + before, cand, sizeof *cand * n);
        r = ic_comm_allgather_sized(comm, cand, bytes, "exchanging the probes' candidates", err);
    }
    free(t);
    free(bytes);
    return r;
}

/* The uncovered diffuse hits of a pass's probes, in probe order, into cand (room for every probe), their hit
 * distances into dist; *m gets their number and *visited the probes' diffuse hits. Several processes trace
 * a block of the probes each (ic_comm_block) on their threads and exchange what they found, so every
 * process gets the candidates one process would find. The tracing's seconds are added to *seconds. */
static ic_result probe_pass(ic_ctx *c, probe_job *j, uint32_t probes, ic_candidate *cand, float *dist, uint32_t *m,
                            double *visited, double *seconds, ic_error *err)
{
    uint64_t first, own;
    ic_comm_block(probes, ic_comm_size(c->comm), ic_comm_rank(c->comm), &first, &own);
    j->first = (uint32_t)first;
    double t0 = ic_seconds();
    ic_result r = ic_parallel_for(c->threads, (int64_t)own, probe_one, j);
    if (r != IC_OK)
        return ic_error_set(err, r, "could not start threads");
    uint32_t n = 0;
    double seen = 0.0;
    for (uint32_t k = 0; k < (uint32_t)own; ++k) {
        seen += j->state[k] != 0;
        if (j->state[k] == 2)
            cand[n++] = j->slot[k];
    }
    *seconds += ic_seconds() - t0;
    atomic_fetch_add_explicit(&c->rays, own, memory_order_relaxed);
    uint64_t total = n;
    if (ic_comm_is_shared(c->comm) && (r = exchange_probes(c->comm, cand, n, &total, &seen, err)) != IC_OK)
        return r;
    for (uint64_t k = 0; k < total; ++k) {
        dist[k] = cand[k].footprint;
        cand[k].footprint = 0.0f;
    }
    *m = (uint32_t)total;
    *visited = seen;
    return IC_OK;
}

/* Fewest θ strata of a hit record that keeps gradients. Its translational gradient is a sum over the
 * walls between strata, and from two or three rings it came out biased: the sky-room's 20 sensors, whose
 * rays read such records (800 rays, hit records of 2 × 7 strata), read 2.8 % low on average over eight
 * seeds; with 4 × 13 strata 0.4 % (within the seeds' spread), and with the gradients left out 0.9 % high
 * (BENCHMARKS.md, "The sensors' σ and the records they read"). */
#define HIT_GRADIENT_MIN_THETA 4u

/* A record's rays then read the irradiance at their hits from these records (ic_ic_gather_trace's
 * look-ups) instead of tracing a path each. Each pass traces HIT_PROBES cosine-distributed rays from
 * every point (at most HIT_PROBES_MAX in all, spread evenly over the points); the diffuse hits that no
 * record accepts are clustered as the world stage clusters eye-path hits and gathered; passes stop when
 * fewer than `uncovered` of the probes' hits go uncovered, or a pass finds fewer than `min_candidates`.
 * Deterministic: the probes depend on the seed, the point and the pass only, and the candidates are
 * collected in point order. */
ic_result ic_ic_hit_stage(ic_ctx *c, const ic_vec3 *p, const ic_vec3 *n, uint32_t count, uint64_t key_tag,
                          uint8_t bounce, uint32_t strata_div, int gradients, phase_times *times, ic_error *err)
{
    if (!c->hit_lookups)
        return IC_OK;
    const ic_scene *scene = c->tr->scene;
    const uint32_t probes = ic_ic_hit_probes(count);
    size_t cap = probes ? probes : 1;
    /* zeroed: the candidates' padding travels in the exchange */
    ic_candidate *cand = calloc(cap, sizeof *cand), *slot = calloc(cap, sizeof *slot);
    float *dist = malloc(sizeof *dist * cap);
    uint8_t *state = malloc(cap);
    if (!cand || !slot || !dist || !state) {
        free(cand);
        free(slot);
        free(dist);
        free(state);
        return ic_error_set(err, IC_ERR_OOM, "out of memory for probe rays from %u points", count);
    }
    probe_job j = {c, p, n, count, 0, key_tag, bounce, 0, slot, state};
    ic_result r = IC_OK;
    for (int pass = 0; pass < HIT_MAX_PASSES && r == IC_OK && !ic_ic_out_of_time(c) && !ic_ic_cancelled(c); ++pass) {
        uint32_t m = 0;
        double visited = 0.0;
        j.pass = pass;
        if ((r = probe_pass(c, &j, probes, cand, dist, &m, &visited, &times->probes, err)) != IC_OK)
            break;
        if (m < (uint32_t)c->o.min_candidates || (double)m <= c->o.uncovered * visited)
            break;
        /* Clusters about a record's size: the accuracy times the median distance of the uncovered hits (a
         * record's R is about the distance its hemisphere rays travel). The scene's diagonal, which sizes
         * the image's world stage, says nothing here: a ground plane around a house makes it huge. */
        float box = c->o.cache.accuracy * ic_kth_smallest(dist, m, m / 2);
        uint32_t kept = 0;
        if (ic_world_select(cand, m, scene->bounds_min, scene->bounds_max, box, 3, 30.0f, &kept) != IC_OK) {
            r = ic_error_set(err, IC_ERR_OOM, "out of memory sorting %u hit-stage candidates", m);
            break;
        }
        m = kept;
        /* Their rays: the strata over strata_div each way. */
        ic_gather_opts keep = c->o.gather, d;
        ic_gather_opts_default(&d);
        uint8_t keep_bounce = c->record_bounce;
        /* Zero strata mean the default grid: divide what they stand for, not zero. */
        uint32_t M = keep.theta_strata ? keep.theta_strata : d.theta_strata;
        uint32_t N = keep.phi_strata ? keep.phi_strata : (uint32_t)lround((double)IC_PI * M);
        c->o.gather.theta_strata = (M + strata_div - 1) / strata_div;
        c->o.gather.phi_strata = (N + strata_div - 1) / strata_div;
        const int with_gradients = gradients && !c->o.no_gradients;
        if (with_gradients && c->o.gather.theta_strata < HIT_GRADIENT_MIN_THETA && M >= HIT_GRADIENT_MIN_THETA) {
            c->o.gather.theta_strata = HIT_GRADIENT_MIN_THETA;
            c->o.gather.phi_strata = (uint32_t)lround((double)IC_PI * HIT_GRADIENT_MIN_THETA);
        }
        c->record_bounce = bounce;
        int keep_no_gradients = c->o.no_gradients;
        c->o.no_gradients = keep_no_gradients || !gradients;
        r = ic_ic_gather_and_insert(c, cand, m, times, err);
        c->o.gather = keep;
        c->record_bounce = keep_bounce;
        c->o.no_gradients = keep_no_gradients;
    }
    free(cand);
    free(slot);
    free(dist);
    free(state);
    return r;
}

