/*
 * irrcache/cache.h — the irradiance cache: records, weights, interpolation, radius clamps, a
 * multiple-reference octree, point queries over record positions, and the cache file.
 *
 * The cache depends on nothing but the C library and irrcache's core (no Embree, no scene), so any
 * renderer, light-map baker or engine can embed it. Methods and where they come from:
 *   - weights and interpolation: Ward et al. 1988, Křivánek et al. 2006 §3, eq. 1;
 *     Tabellion–Lamorlette 2004;
 *   - gradient-magnitude clamping: Křivánek et al. 2006 §5.1, eq. 2;
 *     neighbor clamping: Křivánek et al. 2006 §5.2;
 *   - validity-radius clamping and the multiple-reference octree with stackless look-up:
 *     Frolov et al. 2012 §4.2–4.3;
 *   - gradient-difference scaling: Castaño 2014.
 * Full references: docs/references.md.
 *
 * USAGE
 *   1. ic_cache_params params = {0};            zero means default for every field
 *      params.accuracy = 0.15f;                 set only what you need
 *   2. ic_cache *cache; ic_cache_create(&params, &cache, &err);
 *   3. Fill ic_record values (position, normal, tangent, irradiance, gradients,
 *      harmonic_mean_dist, optionally sigma, pixel_footprint, accuracy, bounce) and insert them:
 *      ic_cache_insert (one record: lazy caching) or ic_cache_insert_batch (many: batch caching).
 *      Insertion applies the radius clamps (see "Clamps" below) and fills record.radius.
 *   4. Look up: ic_cache_lookup q = {.position = p, .normal = n}; ic_cache_estimate e;
 *      if (ic_cache_query(cache, &q, &e)) use e.irradiance, else gather a new record.
 *      For the final render set q.acceptance = IC_ACCEPT_FINAL (looser, final_accuracy_scale).
 *      Many points at once (a row of pixels, a light map's texels): ic_cache_query_batch with an
 *      ic_cache_hint, the same answers at a lower cost per look-up on a frozen cache.
 *   5. Optionally ic_cache_save(cache, path, scene_hash, &err); later ic_cache_load(path, &params,
 *      scene_hash, &cache, &err) refuses files made for another scene or other parameters. With
 *      ic_cache_save_with_settings and ic_cache_load_with_settings the file also keeps the text of the
 *      settings behind scene_hash, and a refusal names the one that differs (SETTINGS TEXT below).
 *   6. ic_cache_destroy(cache).
 *
 * OWNERSHIP AND THREADS
 *   The caller that creates a cache destroys it; destroy(NULL) is a no-op. Records are copied in and
 *   out; records are referenced by uint32_t index (insertion order), never by pointer. Queries
 *   (ic_cache_query, _knn, _radius_query, _get_record …) are const and may run concurrently from any
 *   number of threads; insertion and the record setters must not overlap any other call on the same
 *   cache. No call allocates on the query path; none prints or exits.
 *
 * WEIGHTS
 *   Ward's weight is the inverse of a first-order error estimate; Tabellion–Lamorlette's falls
 *   linearly to zero. IC_WEIGHT_ERROR follows Schwarzhaupt et al. 2012: a record whose extent follows
 *   its Hessian (ic_gather_hessian_extent) errs at displacement d by its error at the extent's edge
 *   times δ_t², δ_t = |d|_i/(a_i R_i) (1 on the edge), the second-order error growing as the square of
 *   the distance; the weight is one minus that share, with the normal change δ_r measured like Ward's,
 *   so that a record weighs what its extent promises and reaches zero exactly at its edge.
 *
 * ELLIPTICAL RECORDS
 *   A record may have an elliptical extent in its tangent plane (Schwarzhaupt et al. 2012: the
 *   eigenvectors of the irradiance Hessian): record.ellipse_ratio ρ in (0, 1) is the minor semi-axis
 *   over the major, record.ellipse_axis the minor axis's direction. Distances in its weight are then
 *   |d|_i² = |d|² + (1/ρ² − 1)(d·u)² (u the unit minor axis), so the extent a_i·R_i is the major
 *   semi-axis and a_i·ρ·R_i the minor; with ρ = 0 or 1 the record is round and |d|_i = |d|. The octree
 *   and every clamp use the sphere of the major semi-axis; clamp step 1 bounds both semi-axes alike
 *   (so ρ may grow), steps 2–4 shrink R_i and keep ρ. A ratio below IC_CACHE_MIN_ELLIPSE_RATIO (1e-6)
 *   after step 1 is raised to it: 1/ρ² must stay a float, and the record is a needle either way.
 *   Frozen look-ups of a cache holding an elliptical record (or using IC_WEIGHT_ERROR) take the
 *   portable code path: round caches keep their SIMD speed.
 *
 * RADII
 *   R_i (record.radius) is the clamped harmonic-mean distance used in the weights. The influence
 *   radius — the sphere outside which a record never contributes — is a_i·R_i for both weights:
 *   Ward, w_i > 1/a_i  ⇒  |p−p_i|/R_i < a_i;  Tabellion–Lamorlette with κ_i = 1/a_i, w_i > 0 ⇒
 *   |p−p_i|/R_i < 1/κ_i = a_i. With IC_ACCEPT_FINAL both use s·a_i (s = final_accuracy_scale).
 *
 * CLAMPS (applied in this order, every step deterministic and independent of the thread count)
 *   1. per record: R := harmonic_mean_dist; gradient-magnitude clamp (Křivánek et al. 2006 eq. 2,
 *      on luminance: if |∇t Y|/Y > 1/R then R := Y/|∇t Y|); then R bounds: R := clamp(R, lo, hi) with
 *      lo = max(min_radius, min_radius_pixels·footprint), hi = min(max_radius,
 *      max_radius_pixels·footprint). The R_min floor is the only step that can raise R.
 *   2. validity-radius clamp (Frolov et al. 2012 §4.2): influence radius ≤ distance to the farthest of the k
 *      nearest records in distinct tangent-plane directions, scanning the 8·k nearest (new records
 *      only; a record with fewer than k distinct directions there is left alone).
 *   3. gradient-difference scaling (Castaño 2014): shrink pairs whose luminance gradients differ.
 *   4. neighbor clamping (Křivánek et al. 2006 §5.2), to a fixed point: |R_i − R_j| ≤ |p_i − p_j|
 *      for every pair within reach (a sequential pass; the new records' neighbours are found
 *      beforehand on params.threads threads).
 *   Two records i, j are "within reach" when |p_i − p_j| < max(a_i·R_i, a_j·R_j): one's position
 *   lies inside the other's (construction) influence sphere. Steps 2–4 only ever shrink radii, of new
 *   and existing records alike.
 *
 * FROZEN LOOK-UPS (for the read-only final render)
 *   ic_cache_freeze (called by ic_cache_rebuild_index and ic_cache_load) copies the octree into a
 *   compact read-only layout, on params.threads threads (the same layout on any number): 4-byte
 *   nodes, the top of the tree then its subtrees, each in depth-first order; per leaf, one contiguous
 *   list of the references on its root-to-leaf path whose sphere can reach the leaf, in path order,
 *   eight to a block with everything the look-up reads side by side — the weight test's fields
 *   (position, R_i, a_i, normal, bounce, flags) and the interpolation data (E_i and both gradients per
 *   channel) — so that the weight test and the extrapolation run eight entries at a time (AVX2,
 *   chosen at run time; four at a time with SSE2; a portable fallback) and a look-up reads one
 *   contiguous run of memory.
 *   A look-up descends (or, with a hint, stays in the previous leaf) and tests one list. A look-up
 *   without a contributions buffer takes a shorter route. A batch (ic_cache_query_batch) finds the
 *   leaves of its next points ahead and fetches the start of their lists, which pays on caches larger
 *   than the CPU's caches.
 *   Results: the octree path's contributors, in the same order, with the same weights, bit for bit;
 *   the extrapolated values E_i(p) (the rotation term evaluated as n·(∇r E_i × n_i)) and the sums
 *   (added in eight interleaved partial sums) may differ from the octree path's in the last bits.
 *   Every frozen code path (AVX2, SSE2, portable) gives the same bits. Any change to the records
 *   (insertion, ic_cache_set_record_accuracy, ic_cache_set_record_flags) thaws the cache: look-ups
 *   go through the octree again until the next freeze. Memory: see ic_cache_memory_bytes; the
 *   index's shape: ic_cache_get_index_stats.
 */
#ifndef IRRCACHE_CACHE_H
#define IRRCACHE_CACHE_H

#include "irrcache/comm.h"
#include "irrcache/common.h"
#include "irrcache/defaults.h"

#include <string.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Opaque cache handle: records, octree, point index. */
typedef struct ic_cache ic_cache;

/* Weighting function of the interpolation. */
typedef enum ic_weight_kind {
    IC_WEIGHT_WARD = 0,       /* w = 1 / (|p−p_i|/R_i + sqrt(1 − n·n_i)), accept w > 1/a_i (Křivánek et al. 2006 §3) */
    IC_WEIGHT_TABELLION = 1,  /* w = 1 − κ_i·max(|p−p_i|/R_i, sqrt(1−n·n_i)/sqrt(1−cos 10°)), κ_i = 1/a_i, accept w > 0 */
    IC_WEIGHT_ERROR = 2       /* w = 1 − (δ_t² + δ_r²), δ_t = |p−p_i|_i/(a_i R_i), δ_r = sqrt(1−n·n_i)/a_i, accept
                                 w > 0: one minus the estimated second-order error over its bound (see WEIGHTS) */
} ic_weight_kind;

/* A switch where zero keeps the documented default. */
typedef enum ic_cache_switch {
    IC_CACHE_DEFAULT = 0,     /* the field's documented default */
    IC_CACHE_ON = 1,          /* enabled */
    IC_CACHE_OFF = 2          /* disabled */
} ic_cache_switch;

/* Cache options. Zero means default in every field. */
typedef struct ic_cache_params {
    ic_weight_kind weight;            /* default Ward */
    float accuracy;                   /* a: default 0.15 (Ward), 1 (T–L, κ = 1/a = 1): irrcache/defaults.h */
    float final_accuracy_scale;       /* s ≥ 1: final render accepts with s·a_i; default 1 */
    float behind_tolerance;           /* ε of the behind test as a fraction of a_i·R_i; default 0.05 */
    float min_radius;                 /* R floor in world units; default 0 (none) */
    float max_radius;                 /* R ceiling in world units; default +inf (none) */
    float min_radius_pixels;          /* R floor in primary-hit pixel footprints; default 0 (none) */
    float max_radius_pixels;          /* R ceiling in primary-hit pixel footprints; default 0 (none) */
    ic_cache_switch gradient_clamp;   /* Křivánek et al. 2006 §5.1 eq. 2; default on */
    ic_cache_switch neighbor_clamp;   /* Křivánek et al. 2006 §5.2; default on */
    ic_cache_switch validity_clamp;   /* Frolov et al. 2012 §4.2; default on */
    uint32_t validity_k;              /* neighbours in distinct directions, 1…16; default 6 */
    float validity_angle_deg;         /* minimum angle between taken directions; default 30 */
    ic_cache_switch gradient_difference; /* Castaño 2014; default off */
    float gradient_difference_threshold; /* τ of the criterion (see cache_clamp.c); default 0.1 × a / 0.15
                                            (T–L's a as 0.15·a; 0.1 at either default accuracy) with
                                            gradient_difference on, 0.1 (unused) with it off */
    uint32_t leaf_capacity;           /* octree: split leaves holding more refs than this; default 12 */
    uint32_t max_depth;               /* octree depth limit, ≤ 32; default 20 */
    ic_cache_switch freeze;           /* ic_cache_rebuild_index and ic_cache_load freeze the cache; default on */
    int threads;                      /* threads for batch insertion and freezing, ≤ IC_MAX_THREADS; default all cores */
    uint64_t max_file_bytes;          /* largest file ic_cache_load reads, checked with fstat before reading;
                                         default IC_DEFAULT_MAX_CACHE_FILE_BYTES (4 GiB) */
} ic_cache_params;

/* Record kinds share one cache and one octree through the bounce field: irradiance records serve
 * levels 0 … IC_BOUNCE_RADIANCE − 1; a radiance record (radiance caching on glossy surfaces, Křivánek et
 * al. 2005) has bounce IC_BOUNCE_RADIANCE + level and carries its incoming radiance as a payload
 * (ic_cache_set_payload). A look-up sees the kind its bounce asks for; weights and clamps are the same. */
#define IC_BOUNCE_RADIANCE 128u

/* Record flags. */
enum {
    IC_RECORD_DISABLED = 1u << 0      /* never contributes to look-ups (kept in the record arrays, the
                                         octree and files; a frozen cache's lists leave it out) */
};

/* Smallest minor-over-major ratio of an elliptical record (ELLIPTICAL RECORDS). */
#define IC_CACHE_MIN_ELLIPSE_RATIO 1e-6f

/* One irradiance record (public, copied in and out; the cache stores it split hot/cold). */
typedef struct ic_record {
    ic_vec3 position;                 /* p_i, world space */
    ic_vec3 normal;                   /* n_i, unit (normalised on insertion) */
    ic_vec3 tangent;                  /* first tangent of the record frame; bitangent = n × t */
    ic_vec3 irradiance;               /* E_i, RGB */
    ic_vec3 grad_rot[3];              /* ∇r E_i per channel (R, G, B): world-space vectors */
    ic_vec3 grad_trans[3];            /* ∇t E_i per channel (R, G, B): world-space vectors */
    ic_vec3 sigma;                    /* Monte Carlo σ of E_i per channel (Křivánek et al. 2006 §4.3), 0 if unknown */
    float harmonic_mean_dist;         /* R from hemisphere sampling (> 0): input of the clamps; +inf (no ray
                                         hit, gather.h) inserts where clamp step 1 bounds R, and saves and loads */
    float radius;                     /* R_i after clamping: output (ignored on insertion) */
    float accuracy;                   /* a_i; 0 on insertion means params.accuracy */
    float pixel_footprint;            /* world size of one pixel at the primary hit; 0 = unknown */
    uint32_t change_count;            /* times a_i or R_i changed after insertion */
    ic_vec3 ellipse_axis;             /* elliptical extent: the minor semi-axis's direction (in the tangent
                                         plane; projected and normalised on insertion); see ELLIPTICAL RECORDS */
    float ellipse_ratio;              /* minor over major semi-axis in (0, 1]; 0 (or 1) = round; at least
                                         IC_CACHE_MIN_ELLIPSE_RATIO once stored */
    uint8_t bounce;                   /* bounce level the record serves (0 = first indirect bounce) */
    uint8_t flags;                    /* IC_RECORD_* */
} ic_record;

/* Which acceptance a look-up uses. */
typedef enum ic_cache_acceptance {
    IC_ACCEPT_CONSTRUCTION = 0,       /* w_i > 1/a_i (Ward) or w_i > 0 (T–L): decides whether to gather */
    IC_ACCEPT_FINAL = 1               /* looser: a_i scaled by final_accuracy_scale */
} ic_cache_acceptance;

/* One record's contribution to a look-up (for adaptive caching: weights, values, σ via the index). */
typedef struct ic_cache_contribution {
    uint32_t record;                  /* record index */
    float weight;                     /* w_i(p) */
    ic_vec3 value;                    /* E_i extrapolated to p with both gradients, clamped ≥ 0 */
} ic_cache_contribution;

/* Caller-owned hint for coherent look-ups on a frozen cache: one per thread, zero-initialised = no
 * hint. It remembers the leaf of the previous look-up; a look-up whose point lies in that leaf's cell
 * skips the descent. It changes speed only, never a result: any value is safe, as the look-up checks
 * the cell. Ignored (and left alone) while the cache is not frozen. */
typedef struct ic_cache_hint {
    uint32_t leaf;                    /* opaque: 1 + leaf of the previous look-up, 0 = none */
} ic_cache_hint;

/* A look-up request. */
typedef struct ic_cache_lookup {
    ic_vec3 position;                 /* p */
    ic_vec3 normal;                   /* n, unit */
    ic_cache_acceptance acceptance;   /* construction (default) or final */
    uint32_t bounce;                  /* only records of this bounce level contribute */
    ic_cache_contribution *contributions; /* optional caller buffer, NULL for none */
    uint32_t contribution_capacity;   /* entries available in contributions */
    uint32_t fallback;                /* 0: none; else 1 + a second bounce level, whose records answer
                                         where none of `bounce` contributes (one descent for both; the
                                         result is what a look-up of `bounce`, then of the second level
                                         if that one found nothing, would give) */
    ic_cache_contribution *fallback_contributions; /* with fallback and contributions: scratch of
                                         contribution_capacity entries for the second level's */
} ic_cache_lookup;

/* A look-up result. */
typedef struct ic_cache_estimate {
    ic_vec3 irradiance;               /* Σ w_i E_i(p) / Σ w_i; zero when no record contributes */
    float weight_sum;                 /* Σ w_i */
    uint32_t contributor_count;       /* |S| (may exceed contributions_written) */
    uint32_t contributions_written;   /* entries written to lookup.contributions */
    uint32_t records_tested;          /* references examined: octree path, or the frozen leaf's list (cost diagnostics) */
} ic_cache_estimate;

/* Fills out with params where every zero field is replaced by its default; checks ranges. */
ic_result ic_cache_params_resolve(const ic_cache_params *params, ic_cache_params *out, ic_error *err);

/* Creates an empty cache (params may be NULL for all defaults). */
ic_result ic_cache_create(const ic_cache_params *params, ic_cache **out, ic_error *err);
/* Frees a cache and everything it owns; NULL is a no-op. */
void ic_cache_destroy(ic_cache *cache);

/* The resolved parameters the cache runs with (NULL for a NULL cache). */
const ic_cache_params *ic_cache_get_params(const ic_cache *cache);
/* Number of records. */
uint32_t ic_cache_count(const ic_cache *cache);
/* Bytes of record storage per record (hot + cold arrays; octree references not included). */
size_t ic_cache_bytes_per_record(void);
/* Records with an elliptical extent (ellipse ratio below 1 after clamping). */
uint32_t ic_cache_ellipse_count(const ic_cache *cache);
/* Bytes the cache holds now: records, octree nodes and references, point index. */
size_t ic_cache_memory_bytes(const ic_cache *cache);

/* The shape of the look-up index (diagnostics and benchmarks; Frolov et al. 2012 §4.3 reports records per leaf). */
typedef struct ic_cache_index_stats {
    uint32_t nodes;                   /* octree nodes */
    uint32_t leaves;                  /* octree leaves */
    uint32_t depth;                   /* deepest leaf (root = 0) */
    uint64_t references;              /* record references in all nodes (a record is in every node it is stored in) */
    double references_per_record;     /* references / records */
    double leaf_references;           /* mean over leaves of the references the leaf itself holds */
    uint32_t max_leaf_references;     /* most references in one leaf */
    double path_references;           /* mean over leaves of the references on the root-to-leaf path: the
                                         records a look-up there tests through the octree */
    uint32_t max_path_references;
    uint32_t frozen_leaves;           /* leaves of the frozen layout (0 while thawed) */
    double frozen_list_entries;       /* mean over them of their list's entries: what a frozen look-up tests */
    uint32_t max_frozen_list_entries;
} ic_cache_index_stats;
/* Fills *out (all zero for an empty cache). */
void ic_cache_get_index_stats(const ic_cache *cache, ic_cache_index_stats *out);

/* Inserts one record (clamps as documented above); its index goes to *out_index (may be NULL).
 * IC_ERR_INVALID_ARG for a record that a cache file could not hold: non-finite fields (but an infinite
 * harmonic_mean_dist whose R clamp step 1 bounds), R ≤ 0, or a sphere |p_i| + R_i +
 * a_i·R_i·max(1, final_accuracy_scale) (after clamp step 1) reaching 1e30 on an axis. */
ic_result ic_cache_insert(ic_cache *cache, const ic_record *record, uint32_t *out_index, ic_error *err);
/* Inserts count records as one batch; they get indices first…first+count−1 in array order.
 * All-or-nothing: an invalid record leaves the records unchanged; an insertion that fails later (out
 * of memory, a failed exchange between processes) drops the new records and restores the radii and
 * change counts of the existing ones that clamp steps 3–4 lowered (unless the octree cannot be built
 * again either: the message says so). Every call, failed or not, drops the frozen layout. */
ic_result ic_cache_insert_batch(ic_cache *cache, const ic_record *records, uint32_t count, uint32_t *out_first,
                                ic_error *err);

/* A look-up at p with normal n under acceptance acc (every other field zero: bounce 0, no buffer). */
static inline ic_cache_lookup ic_cache_lookup_at(ic_vec3 p, ic_vec3 n, ic_cache_acceptance acc)
{
    ic_cache_lookup q;
    memset(&q, 0, sizeof q);
    q.position = p;
    q.normal = n;
    q.acceptance = acc;
    return q;
}

/* Interpolates at q->position; returns 1 if at least one record contributes, else 0 (always 0, with a zero
 * estimate, at a non-finite position or normal: the look-ups below and ic_cache_record_weight alike). */
int ic_cache_query(const ic_cache *cache, const ic_cache_lookup *q, ic_cache_estimate *out);
/* ic_cache_query with a caller-owned hint (one per thread; NULL = none) that it reads and updates:
 * the same result, faster for coherent look-ups on a frozen cache. */
int ic_cache_query_hinted(const ic_cache *cache, const ic_cache_lookup *q, ic_cache_hint *hint,
                          ic_cache_estimate *out);
/* Looks up q[0…count−1] in order, one hint (NULL = none) carried from each to the next: out[k] is
 * what ic_cache_query_hinted(cache, &q[k], hint, &out[k]) gives, bit for bit, without the per-call
 * costs (for a tile of shading points, a lightmap's texels). Returns how many found a contributor. */
size_t ic_cache_query_batch(const ic_cache *cache, const ic_cache_lookup *q, size_t count, ic_cache_hint *hint,
                            ic_cache_estimate *out);
/* ic_cache_query's contributors by a linear scan over all records (sums in record order): the O(N)
 * reference for tests. */
int ic_cache_query_linear(const ic_cache *cache, const ic_cache_lookup *q, ic_cache_estimate *out);

/* The weight test alone for one record (no bounce or flag filter): 1 and *weight = w_i(p, n) if
 * the record is accepted at (p, n) under the given acceptance, else 0. */
int ic_cache_record_weight(const ic_cache *cache, uint32_t index, ic_vec3 p, ic_vec3 n, ic_cache_acceptance acceptance,
                           float *weight);

/* The processes (irrcache/comm.h) that make the same insertions, in the same order, into copies of this
 * cache (NULL, the default: this process alone). Each then computes the validity-radius clamp and the
 * neighbours within reach (for neighbor clamping) of a block of every batch's new records and the blocks
 * are exchanged, so every copy stays the same, bit for
 * bit; insertion becomes a collective operation: every process must make every insertion call. The comm
 * must outlive the insertions. */
void ic_cache_set_comm(ic_cache *cache, ic_comm *comm);
/* Copies record index into *out; IC_ERR_INVALID_ARG if index ≥ count. */
ic_result ic_cache_get_record(const ic_cache *cache, uint32_t index, ic_record *out);
/* Lowers a_i of record index (adaptive caching); raising it is refused. Counts a change. */
ic_result ic_cache_set_record_accuracy(ic_cache *cache, uint32_t index, float accuracy);
/* Replaces the value of record index: E_i, both gradients and σ (a filter over the records, for
 * example); position, normal, a_i and R_i stay. Thaws the frozen layout. IC_ERR_INVALID_ARG for a bad
 * index, a negative irradiance or anything not finite. */
ic_result ic_cache_set_record_value(ic_cache *cache, uint32_t index, ic_vec3 irradiance, const ic_vec3 grad_rot[3],
                                    const ic_vec3 grad_trans[3], ic_vec3 sigma);
/* Sets or clears IC_RECORD_* flags of record index. */
ic_result ic_cache_set_record_flags(ic_cache *cache, uint32_t index, uint8_t flags);
/* Attaches count floats to record index (replacing what it had; count 0 removes it): what a kind of
 * record carries beyond irradiance, such as a radiance record's coefficients. Stored and saved with the
 * record. IC_ERR_INVALID_ARG for a bad index or a non-finite value, IC_ERR_OOM. */
ic_result ic_cache_set_payload(ic_cache *cache, uint32_t index, const float *data, uint32_t count, ic_error *err);
/* The payload of record index and its length in *count (NULL and 0 when it has none). Valid until the
 * next ic_cache_set_payload or insertion. */
const float *ic_cache_payload(const ic_cache *cache, uint32_t index, uint32_t *count);
/* Bytes the payloads hold (included in ic_cache_memory_bytes). */
size_t ic_cache_payload_bytes(const ic_cache *cache);
/* Rebuilds the octree from the current radii (they only shrink, so references go stale-large), then
 * freezes the cache (ic_cache_freeze) unless params.freeze is IC_CACHE_OFF. */
ic_result ic_cache_rebuild_index(ic_cache *cache, ic_error *err);
/* Builds the frozen look-up layout from the current octree (see FROZEN LOOK-UPS); replaces an old one. */
ic_result ic_cache_freeze(ic_cache *cache, ic_error *err);
/* Drops the frozen layout: look-ups go through the octree again (FROZEN LOOK-UPS: same contributors). */
void ic_cache_thaw(ic_cache *cache);
/* 1 while the cache holds a current frozen layout, else 0. */
int ic_cache_is_frozen(const ic_cache *cache);

/* k nearest record positions to p, nearest first (ties by index); returns how many (≤ k) were
 * written to indices and (if non-NULL) squared distances; with dist2 NULL, k is capped at 256. None
 * for a non-finite p. */
uint32_t ic_cache_knn(const ic_cache *cache, ic_vec3 p, uint32_t k, uint32_t *indices, float *dist2);
/* Records with |p_i − p| < radius; writes up to capacity indices (none when indices is NULL) and returns the
 * total number (call again with a larger buffer when the result exceeds capacity). */
uint32_t ic_cache_radius_query(const ic_cache *cache, ic_vec3 p, float radius, uint32_t *indices,
                               uint32_t capacity);

/* Writes the cache to path atomically: magic, version, parameters, scene hash, records, checksum
 * (docs/outputs.md; ic_cache_save_with_settings below adds the settings text). */
ic_result ic_cache_save(const ic_cache *cache, const char *path, uint64_t scene_hash, ic_error *err);
/* Reads a cache file. Refuses (with a one-line message naming the file): wrong magic (IC_ERR_PARSE),
 * other format version or other scene hash or other parameters (IC_ERR_MISMATCH), truncation or a
 * bad checksum (IC_ERR_CORRUPT), a path that is not a regular file or one larger than params->max_file_bytes
 * (IC_ERR_INVALID_ARG, before it is read). params may be NULL for defaults. */
ic_result ic_cache_load(const char *path, const ic_cache_params *params, uint64_t scene_hash, ic_cache **out,
                        ic_error *err);
/* ic_cache_load in two steps, for a program that reads the file once and hands its bytes to several
 * processes: the file's bytes (malloc'd into *data: free() them), checked only as a regular file within
 * params->max_file_bytes; then the cache from those bytes, with every check of ic_cache_load (name: the
 * file's path, for messages). */
ic_result ic_cache_read_file(const char *path, const ic_cache_params *params, void **data, size_t *size,
                             ic_error *err);
ic_result ic_cache_load_memory(const char *name, const void *data, size_t size, const ic_cache_params *params,
                               uint64_t scene_hash, ic_cache **out, ic_error *err);

/* SETTINGS TEXT
 *   scene_hash stands for everything besides the cache parameters that shaped the records; a hash alone
 *   cannot say which of those differs when a file is refused. The _with_settings calls keep, next to the
 *   hash, the caller's text of what went into it, and compare the file's with the caller's when the
 *   hashes differ (only then: a text is never a reason to refuse on its own):
 *     - lines "key=value", each ended by '\n' (not "\r\n"); a key is not empty, has no '=' and is given
 *       once; the text is well-formed UTF-8 without control characters (but the line ends), at most
 *       IC_CACHE_MAX_SETTINGS_BYTES; a caller's text that is not is refused (IC_ERR_INVALID_ARG), a file's
 *       is a damaged file (IC_ERR_CORRUPT);
 *     - the first key whose value differs, or that one text has and the other lacks (the file's lines in
 *       their order first), is named with both values: "made with --rays 800, this run has --rays 102;
 *       rerun with --rays 800, or build the cache again instead of loading it". A key that starts with
 *       "--" reads as an option the user gives (an empty value: a flag), so the message says to rerun
 *       with it; any other key is said as a fact ("made with KEY: VALUE, this run's: VALUE"). A key or
 *       value over 96 bytes is quoted by 96 of them, "..." where cut: two values from where they part,
 *       the scene's name by its end;
 *     - key "scene" holds a digest of the scene's content (a difference: "made for another scene"), key
 *       "scene file" the scene's name for that message (never compared: a moved scene keeps its cache);
 *     - a NULL or empty text on either side, or texts that agree, leave the hashes alone to say it (the
 *       message then says which: no text, or texts that agree, so that what differs is not in them).
 *   The cache never reads the keys otherwise: they are the caller's words (irrcache's renderer uses its
 *   command-line options). ic_cache_save and ic_cache_load are these calls with no text. */
#define IC_CACHE_MAX_SETTINGS_BYTES 65536u
ic_result ic_cache_save_with_settings(const ic_cache *cache, const char *path, uint64_t scene_hash,
                                      const char *settings, ic_error *err);
ic_result ic_cache_load_with_settings(const char *path, const ic_cache_params *params, uint64_t scene_hash,
                                      const char *settings, ic_cache **out, ic_error *err);
ic_result ic_cache_load_memory_with_settings(const char *name, const void *data, size_t size,
                                             const ic_cache_params *params, uint64_t scene_hash,
                                             const char *settings, ic_cache **out, ic_error *err);

/* FNV-1a 64-bit hash of bytes, continuing from h (start with IC_FNV64_OFFSET); for scene hashes too. */
uint64_t ic_fnv1a64(uint64_t h, const void *data, size_t size);
#define IC_FNV64_OFFSET 0xcbf29ce484222325ULL

#ifdef __cplusplus
}
#endif
#endif
