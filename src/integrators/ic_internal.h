/*
 * ic_internal.h — what the files of the irradiance-cache integrator share. In pipeline order:
 *   ic_context.c    options resolved, the empty cache, shading points, large emitters, cache-file hash
 *   ic_gbuffer.c    shading points per pixel centre, look-ups over all of them
 *   ic_emitters.c   which large emitters the records carry
 *   ic_direct.c     direct light (NEE) as this integrator estimates it
 *   ic_gathering.c  what hemisphere rays return, records from gather results, batch insertion
 *   ic_batch.c, ic_lazy.c, ic_adaptive.c   the construction strategies, peers behind ic_build_fn
 *   ic_final.c      the final render's pixel sample
 *   ic_aov.c        diagnostic images and the record list
 *   ic_integrator.c the integrator interface (integrator.h): prepare, sample, aovs, destroy
 *   ic_probe.c      adaptive construction alone, for tests
 *   ic_points.c     the cache at sensor points (irrcache/points.h)
 *   ic_radiance.c   radiance records on glossy surfaces (ic_radiance.h)
 */
#ifndef IC_INTEGRATORS_IC_INTERNAL_H
#define IC_INTEGRATORS_IC_INTERNAL_H

#include "core/comm.h"
#include "integrators/ic.h"
#include "integrators/ic_radiance.h"
#include "integrators/ic_screen.h"
#include "integrators/ic_world.h"

#include <stdatomic.h>

#define MAX_SPECULAR_CHAIN 8
#define WORLD_SLOTS 4 /* look-up points kept per world-stage eye path */
#define PAD 8         /* uint64 slots between per-thread counters: no false sharing */
#define IC_HESSIAN_SPACING_LENGTH 0.125 /* --error hessian: the length L of a record's semi-axes ε·√(L·ℓ), as a share of
                                           the work extent (ic_ic_record_from_gather) */
#define LOOKUP_CAPACITY 64 /* contributions read back from one cache look-up (adaptive, amap) */
#define IC_LEVELS_MAX 16   /* most bounces whose levels records keep apart for hit look-ups (beyond:
                              hemisphere rays are path-traced) */

/* How a record takes the light of the environment that its hemisphere rays escape to. */
enum {
    IC_ENV_IN_RAYS = 0,      /* the rays count it (the image's records) */
    IC_ENV_AT_POINT,         /* not at all: the points the record serves sample it (ic_ic_env_light) */
    IC_ENV_PORTAL_SAMPLES    /* through portals by light samples (uniform in the openings' solid angle)
                                added to the record, the rays counting only the directions through no
                                portal */
};

typedef struct ic_ctx {
    const ic_tracer *tr;       /* scene, accel, path-tracing parameters of the final render */
    ic_tracer gather_tr;       /* same scene; max_depth set for record radiance (bounces) */
    ic_ic_options o;           /* resolved options */
    ic_cache *cache;
    uint64_t seed;
    int threads;
    float scene_diag;
    float work_extent;         /* the length that candidate clusters (world stage, coverage sweep) and
                                  recursive levels' footprints scale with: scene_diag, at most 2.5 times
                                  what the camera sees (ic_ic_view_extent) */
    atomic_ullong rays;        /* gathering rays (added once per trace call) */
    ic_gbuffer g;              /* valid is held for every pixel; p, n and footprint only on rows
                                  [g_rows[0], g_rows[1]) (ic_ic_gbuffer_point reads any pixel) */
    int g_rows[2];
    uint8_t *has_record;       /* per pixel: a screen-space record was made here */
    int hit_lookups;           /* hemisphere rays take the bounces after their hit from the cache */
    uint8_t record_bounce;     /* the bounce field of the records gathered from candidates: 0, or the
                                  sensors' own kind while ic_ic_points_build makes theirs */
    int hit_kind;              /* ≥ 0: hemisphere rays' look-ups that no bounce-0 record accepts take the
                                  records of this bounce field (an image's hit stage; one look-up for both,
                                  ic_cache_lookup.fallback); −1: none */
    int track_noise;           /* the records gathered now also get the variance their rays take from
                                  the records they read (ic_record_noise.c) into record_noise */
    ic_vec3 *record_noise;     /* per record (record_noise_count of them): that variance; zero for records
                                  gathered without track_noise */
    uint32_t record_noise_count;
    size_t record_noise_capacity;
    uint8_t env_mode;          /* how the records gathered now take the environment their rays escape
                                  to: IC_ENV_IN_RAYS, IC_ENV_AT_POINT or IC_ENV_PORTAL_SAMPLES */
    double deadline;           /* ic_seconds() past which batch and adaptive construction stop (a time
                                  budget's construction share); 0: none */
    int levels;                /* with hit_lookups: bounces B, whose levels the records keep apart;
                                  else 0 */
    ic_vec3 *level_irr;        /* (levels + 1) entries per record, in record order: T_k, the record's
                                  irradiance carried by light of at most k bounces after it (k = 0 is
                                  the large emitters' and the environment's own light), T_B = E_i */
    uint32_t level_records;    /* records level_irr holds */
    uint32_t level_capacity;   /* records it has room for */
    ic_light_selection light_sel; /* final render: triangle and point lights only (the sun is taken
                                     every time, the environment is in the records), and of the
                                     triangles only those not cached (direct_pmf) */
    ic_light_selection light_sel_all; /* the same with every emitting triangle (the last level of
                                         recursive caching, whose hits have no cache behind them) */
    float *direct_pmf;         /* tri_light_count: the final render's distribution over emitting
                                  triangles, 0 for a large emitter whose light the records carry
                                  (ic_emitters.c); NULL when none is */
    float *direct_cdf;         /* its cdf (tri_light_count + 1) */
    uint32_t cached_emitters;  /* emitting triangles whose light the records carry */
    float *cached_pmf;         /* with cached emitters: a distribution over the emitting triangles
                                  (tri_light_count) that picks the cached ones by power, for light
                                  samples of them (ic_ctx.emitter_mis; ic_ic_cached_selection) */
    float *cached_cdf;         /* its cdf (tri_light_count + 1) */
    uint64_t ungathered;       /* candidates ic_ic_gather_and_insert left ungathered (an interrupt or the
                                  time budget stopped their gathering), over the whole construction */
    int emitter_mis;           /* 1 (set by ic_ic_ctx_create): the records gathered take the cached
                                  emitters' light from their rays and from light samples of them,
                                  MIS-weighted (ic_light_samples.c); 0: from
                                  their rays alone (tests compare the two) */
    int large_sampled;         /* 1: an emitter that covers at least large_emitters of the median shading
                                  point's hemisphere is light-sampled though its plain light samples are
                                  noisier than cosine rays (ic_emitters.c), and the hits that records
                                  serve take the full MIS pair (ic_ic_direct_light_at_hit) */
    ic_radiance *rad;          /* radiance caching on glossy lobes (ic_radiance.c); NULL when off */
    ic_comm *comm;             /* the processes sharing construction (ic_ic_gather_points); NULL: one */
    const volatile sig_atomic_t *cancel; /* ic_render_options.cancel: once set, construction stops at its
                                  next pass as at a deadline (not with a shared comm, whose ranks must agree) */
    uint64_t gathered;         /* records whose hemispheres this process gathered */
    double comm_seconds_counted; /* batch: c->comm's counters when last added to a pass's statistics */
    uint64_t comm_bytes_counted;
} ic_ctx;

typedef struct phase_times {
    double gather, insert;
    double probes; /* the hit stage's probe rays, exchanges excluded (shared out among processes) */
} phase_times;

/* The shading point of a camera ray: the first surface with a smooth lobe after ideal specular
 * surfaces (glass takes its more likely branch, so the point is a deterministic function of the ray).
 * Fills the surface, its BSDF and the direction towards the viewer; t_primary (may be NULL) gets the
 * primary hit's distance. Returns 0 if the ray escapes or is absorbed. */
int ic_ic_shading_point(const ic_tracer *tr, ic_ray ray, ic_surface *s, ic_bsdf *b, ic_vec3 *wo, float *t_primary,
                        uint64_t *rays);
/* A record's rays kept for a second pass of the gatherer's arithmetic (gather_set): each ray's hit distance and
 * the light the balance heuristic removed from its hit on a cached emitter, in the order traced. */
typedef struct ic_gather_replay {
    int recording, replaying, failed;
    uint32_t count, next;
    size_t capacity;
    float *dist;
    ic_vec3 *removed;
} ic_gather_replay;

/* The reads of one record's rays from other records, for the part of its noise that comes from them
 * (ic_record_noise.c): per record read, in the order first read, how much of its value the rays passed on
 * (the reads summed as they come: the memory is that of the records read, not of the reads, which were up
 * to LOOKUP_CAPACITY per ray). */
typedef struct ic_noise_term {
    uint32_t record;
    size_t slot;               /* its slot in ic_noise_terms.slot */
    double coef[3];
} ic_noise_term;
typedef struct ic_noise_terms {
    ic_noise_term *terms;
    size_t count, capacity;
    uint32_t *slot;            /* open addressing by record: 1 + its entry in terms, 0 empty; slots a power
                                  of two, at least twice count */
    size_t slots;
    int failed;                /* an allocation failed (reported by ic_ic_gather_one) */
} ic_noise_terms;
/* Adds a read of record `record` that added coef ⊙ E_record's relative change to a ray's radiance. */
void ic_ic_noise_add(ic_noise_terms *t, uint32_t record, ic_vec3 coef);
/* Var of a record's E from the reads t holds, E = scale · Σ_rays radiance (π/N for N cosine-distributed
 * rays): Σ_j (scale · Σ coef_j)² (σ_j/E_j)² per channel, σ_j and E_j record j's own. Empties t. */
ic_vec3 ic_ic_noise_variance(const ic_ctx *c, ic_noise_terms *t, double scale);
void ic_ic_noise_release(ic_noise_terms *t);

/* What one gathering thread's trace callback needs: the context and, with c->levels, the sums over
 * the current point's rays of their radiance split by bounce level (cumulative: sum[k] holds light of at
 * most k bounces after the record, sum[levels] all of it). The caller zeroes sum before each point. */
typedef struct ic_gather_worker {
    ic_ctx *c;
    ic_vec3 sum[IC_LEVELS_MAX + 1];
    /* With c->emitter_mis: the point being gathered, and the counts of its hemisphere rays and of its
     * light samples of the cached emitters (0: their light from the rays alone). */
    const ic_gather_point *pt;
    float mis_rays, mis_lights;
    ic_gather_replay replay;
    ic_noise_terms noise;      /* with c->track_noise: the current point's reads of other records */
    ic_vec3 noise_var;         /* with c->track_noise: the last point's variance from those reads */
} ic_gather_worker;
/* Frees a worker's replay buffers (its other fields are not owned). */
void ic_ic_gather_worker_release(ic_gather_worker *w);
/* Trace callback of hemisphere gathering (ic_trace_fn; user = ic_gather_worker): see ic.h for what it
 * returns. */
void ic_ic_gather_trace(void *user, const ic_vec3 *origins, const ic_vec3 *dirs, uint32_t count, float *hit_dist,
                        ic_vec3 *radiance);
/* Gathers one point with w's gatherer g (the method of c's options); with c->levels, also its level
 * split: levels[k] = T_k for k = 0…c->levels (may be NULL without levels). */
ic_result ic_ic_gather_one(ic_gather_worker *w, ic_gatherer *g, const ic_gather_point *pt, ic_gather_result *out,
                           ic_vec3 *levels);
/* Light samples a record adds to its rays' estimate (ic_light_samples.c). With c->env_mode ==
 * IC_ENV_PORTAL_SAMPLES: the environment through the portals pt lies inside of. With w->mis_lights > 0:
 * the cached emitters' light, w->mis_lights samples weighted against w->mis_rays rays (the balance
 * heuristic; the rays' hits weigh themselves with the same selection's pdf,
 * ic_scene_light_pdf_triangle_sel). Both add to out's irradiance, σ and every bounce level. */
void ic_ic_add_portal_light(ic_ctx *c, const ic_gather_point *pt, ic_gather_result *out, ic_vec3 *levels);
void ic_ic_add_cached_emitter_light(ic_gather_worker *w, const ic_gather_point *pt, ic_gather_result *out,
                                    ic_vec3 *levels);
/* The light selection that samples only the cached emitters, by power (c->cached_pmf): the scene's own
 * light sampling and its pdf (ic_scene_sample_light_sel, ic_scene_light_pdf_triangle_sel) take it. */
ic_light_selection ic_ic_cached_selection(const ic_ctx *c);
/* The light samples of the cached emitters a record of `rays` hemisphere rays takes. */
uint32_t ic_ic_emitter_light_samples(uint32_t rays);
/* Gathers count points in parallel (one gatherer per thread; each point's result depends only on the
 * seed and its key, never on the thread count); levels: (c->levels + 1) entries per point, or NULL.
 * gathered[i] is set to 1 for each point gathered; once the render is cancelled (ic_ic_cancelled) or
 * construction's time is up (ic_ic_past_deadline) the points not yet begun are skipped (0), so that an
 * interrupt or the deadline stops a pass within a few gathers. With c->track_noise, noise (one entry per
 * point, else NULL) gets each point's variance from the records its rays read (ic_record_noise.c). */
ic_result ic_ic_gather_points(ic_ctx *c, const ic_gather_point *pts, uint32_t count, ic_gather_result *out,
                              ic_vec3 *levels, ic_vec3 *noise, uint8_t *gathered, ic_error *err);
/* Moves the results (and level splits, levels may be NULL) of the points gathered[i] marks to the front,
 * in order; returns how many there are. */
uint32_t ic_ic_keep_gathered(const ic_ctx *c, const uint8_t *gathered, uint32_t count, ic_gather_result *res,
                             ic_vec3 *levels);
/* Keeps the level split of records first…first+count−1 (they must follow the last kept one); a no-op
 * without levels. */
ic_result ic_ic_keep_levels(ic_ctx *c, uint32_t first, uint32_t count, const ic_vec3 *levels, ic_error *err);
/* The level split of the irradiance records as their cache payloads (3·(levels + 1) floats each), so a
 * saved cache keeps it; and back into c->level_irr after a load (the leading irradiance records whose
 * payload has that length; a file without them leaves the split empty and look-ups use E_i). No-ops
 * without levels. */
ic_result ic_ic_levels_to_payloads(ic_ctx *c, ic_error *err);
ic_result ic_ic_levels_from_payloads(ic_ctx *c, ic_error *err);
/* The ε of a Hessian extent's semi-axes ε·√(L·ℓ_k) (ic_ic_record_from_gather; Schwarzhaupt et al. 2012), for
 * the cache's weight and accuracy. */
float ic_ic_hessian_error_target(const ic_cache_params *p);
/* Record for candidate cand from a gather result (gradients dropped with no_gradients). */
void ic_ic_record_from_gather(const ic_ctx *c, const ic_candidate *cand, const ic_gather_result *gr, ic_record *rec);
/* Gather point (offset origin, normal, key) of a candidate. */
ic_gather_point ic_ic_gather_point_of(const struct ic_ctx *c, const ic_candidate *cand);
/* Where the hemisphere rays of a record at p (unit normal n) start: p moved off any surface it lies on,
 * to the side n faces. */
ic_vec3 ic_ic_gather_origin(const struct ic_ctx *c, ic_vec3 p, ic_vec3 n);
/* Gathers count candidates in parallel and inserts them as one batch (those gathered, when the render
 * is cancelled during the gathers). */
ic_result ic_ic_gather_and_insert(ic_ctx *c, const ic_candidate *cand, uint32_t count, phase_times *pt, ic_error *err);
/* The hit stage (ic_hit_stage.c): passes of probe rays from the count points p (normals n), cosine-
 * distributed, the diffuse hits no record of kind `bounce` accepts clustered and gathered with the
 * strata over strata_div each way, inserted as records of that kind (without gradients unless
 * `gradients`). key_tag separates its random numbers
 * and keys from other stages'. A no-op unless c->hit_lookups. It reads only the points
 * ic_ic_hit_probe_point(k, count) for k < ic_ic_hit_probes(count), and under several processes only those
 * of this process's block of the k (ic_comm_block). */
uint32_t ic_ic_hit_probes(uint32_t count);
uint32_t ic_ic_hit_probe_point(uint32_t k, uint32_t count);
/* The bounce field of an image's hit-stage records: read only by hemisphere rays' look-ups. */
#define IC_HIT_KIND (IC_BOUNCE_RADIANCE - 2u)
ic_result ic_ic_hit_stage(ic_ctx *c, const ic_vec3 *p, const ic_vec3 *n, uint32_t count, uint64_t key_tag,
                          uint8_t bounce, uint32_t strata_div, int gradients, phase_times *times, ic_error *err);
/* Candidate at a pixel's shading point; tag distinguishes keys of different stages. */
ic_candidate ic_ic_candidate_at_pixel(const ic_ctx *c, uint32_t pixel, uint64_t tag);
/* Looks up every valid pixel: luminance of the estimate and whether any record contributes. With several
 * processes each looks up its block of rows (ic_comm_block) and gets every pixel's `lum` if want_lum;
 * the other ranks' rows of `covered` (and of lum without want_lum) are left as they were. */
ic_result ic_ic_lookup_all(ic_ctx *c, float *lum, uint8_t *covered, ic_cache_acceptance acc, int want_lum);
/* 1 once construction has spent its share of the render's time budget (c->deadline). Several processes
 * (c->comm) go by rank 0's clock, so that all stop at the same pass: a collective call then. */
int ic_ic_out_of_time_shared(ic_ctx *c);
/* 1 once the caller's cancel flag is set (one process only: ranks sharing a render must agree, so there
 * the flag is ignored). Cheap: construction checks it between gathers, inside a pass. */
static inline int ic_ic_cancelled(const ic_ctx *c)
{
    return c->cancel && *c->cancel && !ic_comm_is_shared(c->comm);
}
/* 1 once construction's share of the time budget is spent, for one process: a pass stops gathering
 * there (its points not begun stay ungathered), so that one large pass does not overrun the budget.
 * Processes sharing a render gather whole passes (they must agree on every record) and stop between
 * passes (ic_ic_out_of_time). */
static inline int ic_ic_past_deadline(const ic_ctx *c)
{
    return c->deadline > 0.0 && !ic_comm_is_shared(c->comm) && ic_seconds() > c->deadline;
}
static inline int ic_ic_out_of_time(ic_ctx *c)
{
    if (ic_ic_cancelled(c))
        return 1;
    if (!(c->deadline > 0.0))
        return 0;
    return ic_comm_is_shared(c->comm) ? ic_ic_out_of_time_shared(c) : ic_seconds() > c->deadline;
}
/* Batch construction's candidate keys (pixel << 8 | an 8-bit tag; ic_ic_candidate_at_pixel): the screen
 * stage's tag is its pass (below 0x40), the closing sweep's 0x40 | its round, the world stage's
 * 0x80 | pass << 2 | the path's smooth hit. Passes beyond what a tag holds (32 for the world stage, 64 for the
 * screen stage) add their high bits above the pixel's (bit 48 up), so that no two passes share keys, and
 * hence random streams; the keys of the first passes are as they were. */
static inline uint64_t ic_ic_screen_key_tag(int pass)
{
    return ((uint64_t)pass & 0x3f) | ((uint64_t)pass >> 6) << 48;
}
static inline uint64_t ic_ic_world_key(uint32_t pixel, int pass, int smooth_hit)
{
    return ((uint64_t)pixel << 8) | (uint64_t)(0x80 | ((uint64_t)pass & 0x1f) << 2 | ((uint64_t)smooth_hit & 3)) |
           ((uint64_t)pass >> 5) << 48;
}
/* How a batch construction pass ends (ic_ic_batch_pass_end): another pass, converged, or stopped by the time
 * budget or an interrupt. */
typedef enum ic_pass_end { IC_PASS_CONTINUE, IC_PASS_CONVERGED, IC_PASS_STOPPED } ic_pass_end;
/* The end of a pass that found `found` candidates and gathered them all unless `truncated`; `converged` is
 * the pass's convergence test. A truncated pass is never converged: it added fewer records because its
 * gathering stopped, not because the cache needs fewer. `out_of_time` is asked only when the pass did not
 * converge (it may be a collective call; ic_ic_out_of_time). */
ic_pass_end ic_ic_batch_pass_end(int truncated, int converged, int (*out_of_time)(ic_ctx *), ic_ctx *c);
/* Progress report, if the caller asked for it. */
void ic_ic_report(const ic_render_options *opt, const char *phase, double fraction);
/* How direct light at a surface counts its glossy lobe's share of each light sample: at full weight
 * (light sampling alone carries it: the glossy lobe's indirect light comes from radiance records), MIS-
 * weighted against the glossy lobe's own sample, which continues the path (power heuristic; a delta
 * light at full weight), or not at all (the caller estimates the glossy lobe apart). */
enum { IC_GLOSSY_FULL = 0, IC_GLOSSY_MIS = 1, IC_GLOSSY_NONE = 2 };

/* Direct light at a hemisphere ray's hit that the records serve: the sun and one light sample by
 * the selection, the diffuse lobe's share at full weight and the glossy lobe's as `glossy` says
 * (IC_GLOSSY_NONE where the glossy lobe is traced on apart), without the cosine ray that ic_ic_direct_light
 * weighs them against (MIS). The ray's value is averaged with the record's hundreds of others, where that
 * ray's lower variance next to a small emitter is not seen (the same low-pass error within 1 % on every
 * bench scene with emitters), while it cost a full intersection per hit: 7–13 % of the gathering's rays
 * (BENCHMARKS.md, "Direct light at the hemisphere rays' hits"). Unbiased: light sampling reaches every
 * emitter the final render samples; the records carry the others. Where a large emitter is light-sampled
 * though its plain light samples are noisier than cosine rays (ic_ctx.large_sampled), the MIS pair is
 * kept: such a source's area samples are heavy-tailed (staircase2's middle window: cv² 96 a light
 * sample against 9.6 a cosine ray), and one tail draw in a record is a blotch (that window sampled: the
 * low-pass error 3× higher on one seed of three without the pair; BENCHMARKS.md, "Direct light at the
 * hemisphere rays' hits"). */
ic_vec3 ic_ic_direct_light_at_hit(const ic_ctx *c, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo, int glossy,
                                  ic_rng *rng, uint64_t *rays);
/* Direct light of the final render at s (NEE; the environment is cached, not sampled here); sel: the
 * pixel's local light selection, NULL for the whole-scene one. */
ic_vec3 ic_ic_direct_light(const ic_ctx *c, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo,
                           const ic_light_selection *sel, ic_rng *rng, uint64_t *rays);
/* The same, with the glossy lobe's share counted as `glossy` says (IC_GLOSSY_MIS above; IC_GLOSSY_FULL
 * where radiance records give the glossy lobe's indirect light). */
ic_vec3 ic_ic_direct_light_lobes(const ic_ctx *c, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo,
                                 const ic_light_selection *sel, int glossy, ic_rng *rng, uint64_t *rays);

/* The environment's light at a point whose records leave it out (IC_ENV_AT_POINT): one light sample of
 * the environment alone (through the portals p is inside of) and one cosine-distributed ray that counts
 * the environment where it escapes, MIS (power heuristic) between them; a constant environment seen
 * without portals by the ray alone. b's diffuse lobe only. Five random numbers. */
ic_vec3 ic_ic_env_light(const ic_ctx *c, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo, ic_rng *rng,
                        uint64_t *rays);


/* Shading points of the pixel centres into c->g (and c->has_record); gbuffer_free frees them. One process,
 * or full (several processes that read every pixel's point: the adaptive strategy, the AOVs), holds every
 * point. Otherwise each process computes its block of rows and IC_SCREEN_HALO rows on either side (what
 * its need maps read) and the processes exchange only whether each pixel has a point (a byte a pixel, not
 * 29); other rows' points come from ic_ic_gbuffer_point. */
ic_result ic_ic_gbuffer_build(ic_ctx *c, int full, ic_error *err);
void ic_ic_gbuffer_free(ic_ctx *c);
/* Pixel `pixel`'s shading point as the G-buffer has it, the same bits on every process: read where this
 * process holds its row, else traced again (not counted as rays: the G-buffer counted it once). 0 if the
 * pixel has none. footprint may be NULL. */
int ic_ic_gbuffer_point(const ic_ctx *c, uint32_t pixel, ic_vec3 *p, ic_vec3 *n, float *footprint);
/* The diagonal of the box between the 5th and 95th percentiles of the shading points' coordinates on each
 * axis (at most VIEW_SAMPLES points, evenly through the image): the size of what the camera sees, which a
 * far wall seen through a window barely moves; 0 without shading points. A collective call under several
 * processes; an error when out of memory (not 0: every process must size its clusters alike). */
ic_result ic_ic_view_extent(const ic_ctx *c, float *extent, ic_error *err);
/* What a hemisphere ray adds for its hit besides the light reflected there: the emission of a large
 * emitter the records carry (zero for any other surface). */
/* One gather at pt with g by the method of c's options (stratified, progressive or hemicube). */
ic_result ic_ic_gather_by_method(const ic_ctx *c, ic_gatherer *g, const ic_gather_point *pt, ic_gather_result *out);
ic_vec3 ic_ic_cached_emission(const ic_ctx *c, const ic_ray *ray, const ic_hit *hit);
/* The interpolation of levels T_first … T_{first+levels−1} (ic_ctx.level_irr) over the contributions of
 * one look-up, into E[0 … levels−1]: each contributor's value scaled per channel by T_k / E_i, with the
 * full estimate's weights. Returns 0 (E unset) when a contributor has no levels (a cache file
 * from before the levels were saved with it). last_terms (may be NULL): per contributor, its share of
 * E[levels − 1]. */
int ic_ic_level_estimates(const ic_ctx *c, const ic_cache_contribution *contrib, uint32_t count, int first,
                          int levels, ic_vec3 *E, ic_vec3 *last_terms);
/* Chooses the large emitters the records carry (ic_emitters.c): a collective call under several processes. */
ic_result ic_ic_select_large_emitters(ic_ctx *c, const ic_scene *s, ic_error *err);
/* A cache file's identity: returns the hash of everything a record's value depends on besides the cache
 * parameters (which the file keeps apart), and writes the same as a settings text (irrcache/cache.h: SETTINGS
 * TEXT) to settings, so that a refusal names what differs: the scene's digest and name, then the options
 * behind the hash by their command-line names with their resolved values (an option at a default the hash
 * keeps apart from its value left out). IC_RECORDS_SETTINGS_BYTES holds any (the scene's name is at most
 * 1023 bytes). */
#define IC_RECORDS_SETTINGS_BYTES 4096
uint64_t ic_ic_records_identity(const ic_ctx *c, char *settings, size_t size);

/* The final render's state shared by its threads. */
typedef struct ic_final_ctx {
    const ic_ctx *c;
    int indirect_only;         /* AOV: indirect diffuse at the first shading point only */
    int glossy_only;           /* AOV: the glossy lobe's indirect light from radiance records at the first
                                  shading point only */
    ic_cache_hint *hints;      /* one per render thread: consecutive samples of a tile share leaves */
    int hint_count;            /* entries in hints (0: none) */
    ic_pixel_lights lights;    /* per-thread local light selection of the pixel being rendered */
} ic_final_ctx;
/* One final-render pixel sample (ic_sample_fn; p = ic_final_ctx). */
ic_vec3 ic_ic_final_sample(void *p, const ic_ray *camera_ray, uint32_t pixel, ic_rng *rng, int thread,
                           uint64_t *rays);

/* Diagnostics (ic_aov.c): record dots and circles over beauty, records per pixel centre, and the list of
 * records as the camera sees them (malloc'd). */
ic_result ic_ic_records_image(const ic_ctx *c, const ic_image *beauty, ic_image *out);
ic_result ic_ic_density_image(ic_ctx *c, ic_image *out);
ic_result ic_ic_record_views(const ic_ctx *c, ic_record_view **out, uint32_t *count);

/* Sets up a context for tr and opt: resolved options, an empty cache, the shading-point buffers (used by
 * the integrator's prepare (ic_integrator.c) and by tests that run construction alone). gbuffer_seconds may be NULL. */
ic_result ic_ic_ctx_create(const ic_tracer *tr, const ic_render_options *opt, ic_ctx **out, double *gbuffer_seconds,
                           ic_error *err);
/* Frees a context, its cache (unless the caller took it and set c->cache = NULL) and buffers; NULL is a
 * no-op. Its radiance-cache state (c->rad) is the creator's to free first (ic_ic_radiance_destroy). */
void ic_ic_ctx_destroy(ic_ctx *c);
/* ---- construction strategies: peers behind one signature. Each fills c->cache from the shading
 * points, reports progress through opt, adds its own phases to st (if any) and its gathering and
 * insertion times to pt. */
typedef ic_result (*ic_build_fn)(ic_ctx *c, const ic_render_options *opt, ic_render_stats *st, phase_times *pt,
                                 ic_error *err);
/* Frolov et al. 2012 multi-pass construction (ic_batch.c). */
ic_result ic_ic_build_batch(ic_ctx *c, const ic_render_options *opt, ic_render_stats *st, phase_times *pt,
                            ic_error *err);
/* Ward et al. 1988 lazy construction, and recursive caching per bounce (ic_lazy.c). */
ic_result ic_ic_build_lazy(ic_ctx *c, const ic_render_options *opt, ic_render_stats *st, phase_times *pt,
                           ic_error *err);
/* Křivánek et al. 2006 §4 adaptive caching, Algorithm 1 over the G-buffer shading points (ic_adaptive.c). */
ic_result ic_ic_build_adaptive(ic_ctx *c, const ic_render_options *opt, ic_render_stats *st, phase_times *pt,
                               ic_error *err);
/* Moves every record's value towards a mean over its neighbours within scale times its influence radius
 * (ic_filter.c), on `threads` threads (0: all cores; the result does not depend on it) and, with a comm
 * of several processes, a block of records on each, exchanged; a no-op for scale ≤ 0. */
ic_result ic_ic_filter_cache(ic_cache *cache, int threads, ic_comm *comm, float scale, ic_error *err);
/* The strategy of c's options (construction only, no final render; ic_integrator.c). */
ic_result ic_ic_build(ic_ctx *c, const ic_render_options *opt, ic_render_stats *st, phase_times *pt, ic_error *err);
/* The amap AOV: a_i of the heaviest contributing record per pixel centre on a colour ramp (log scale
 * from --accuracy, blue, down to accuracy / IC_AMAP_RANGE, red). */
ic_result ic_ic_amap_image(const ic_ctx *c, ic_image *out);
#define IC_AMAP_RANGE 32.0f

/* What a test needs to check convergence independently: the converged cache and the shading points
 * with the inputs of the discernibility test. */
typedef struct ic_adaptive_probe {
    ic_cache *cache;           /* owned by the probe */
    uint32_t point_count;
    ic_vec3 *position, *normal;
    ic_vec3 *albedo;           /* ρ/π per channel */
    float *direct;             /* Y of the stored direct light */
    float weber, accuracy;     /* resolved options */
    int passes, converged;
    uint64_t refinements;
    uint32_t unresolved;       /* refinements that found no positive a_i (coincident records) */
} ic_adaptive_probe;
/* Adaptive construction that also fills probe (may be NULL: ic_ic_build_adaptive). */
ic_result ic_ic_build_adaptive_probed(ic_ctx *c, const ic_render_options *opt, ic_render_stats *st, phase_times *pt,
                                      ic_adaptive_probe *probe, ic_error *err);
/* The discernibility test of Křivánek et al. 2006 §4.3 over m ≥ 2 contributions (weights, luminances y
 * of their outgoing radiance, their σ) at a point whose other light has luminance `direct`: the index of
 * the lowest-weight contribution if removing any one is discernible, else −1 (ic_adaptive.c). */
int ic_ic_discernible(const float *weight, const float *y, const float *sigma, const uint32_t *rec_of, uint32_t m,
                      float direct, float weber);
/* The a_i that just excludes a point where the record weighs `weight` (§4.1); 0 when none does. */
float ic_ic_exclusion_accuracy(const ic_ctx *c, float weight, float accuracy);
/* Runs shading-point setup and adaptive construction only (no final render) on scene with opt. */
ic_result ic_ic_adaptive_probe_run(const ic_scene *scene, const ic_render_options *opt, ic_adaptive_probe *out,
                                   ic_error *err);
/* Frees what a probe holds; a zeroed probe is a no-op. */
void ic_ic_adaptive_probe_free(ic_adaptive_probe *p);

/* ---- sensor points (ic_points.c; the driver is src/render/points.c) */
/* A sensor as a surface: a white Lambertian receiver (ρ = 1) at p facing the unit normal n, whose
 * reflected radiance is E/π. */
void ic_ic_sensor(const ic_scene *scene, ic_vec3 p, ic_vec3 n, ic_surface *s, ic_bsdf *b);
/* A context for sensor points: opt resolved as for a render, lazy, every emitter light-sampled, no record
 * filter, no cache files, and no shading points of the camera. */
ic_result ic_ic_points_ctx_create(const ic_tracer *tr, const ic_render_options *opt, ic_ctx **out, ic_error *err);
/* The sensors' records' noise model (ic_ic_points_build): the relative variance (σ_i/E_i)² of R, G, B and
 * luminance pooled over the records, and the values below which a record is dark and keeps its own σ. */
typedef struct ic_points_noise {
    double rel_var[4];
    double dark[4];
} ic_points_noise;
/* The noise model of the sensor records first … records − 1 from their own σ (ic_points.c). */
ic_result ic_ic_points_pool(const ic_ctx *c, uint32_t first, uint32_t records, ic_points_noise *noise, ic_error *err);
/* Construction over the sensors (p[i], unit n[i]): first, with hit look-ups, records where the sensors'
 * hemisphere rays land (*hit_records of them, a kind apart from the sensors'); then in passes, the points
 * no sensor record covers, in input order, each unless it lies within reach of one taken before it in the
 * pass; the pass's records gathered in parallel and inserted as one batch (the records do not depend on
 * the thread count); freezes the cache; fills noise. */
ic_result ic_ic_points_build(ic_ctx *c, const ic_render_options *opt, const ic_vec3 *p, const ic_vec3 *n,
                             uint32_t count, ic_points_noise *noise, uint32_t *hit_records, ic_error *err);
/* The interpolated irradiance at (p, n) (environment and indirect light) and the σ of R, G, B and luminance
 * (Radiance's weights): the noise of the records' own rays (noise) and of the records those read
 * (ic_ctx.record_noise); 0 if no record contributes. */
int ic_ic_points_indirect(const ic_ctx *c, ic_vec3 p, ic_vec3 n, const ic_points_noise *noise, ic_vec3 *E,
                          double sigma[4]);

#endif
