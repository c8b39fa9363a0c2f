/*
 * cache.c — the irradiance cache: parameters, record store, insertion and interpolation
 * (include/irrcache/cache.h).
 *
 * Interpolation is seed 000 §3 eq. 1 for irradiance:
 *   E(p) = Σ_{i∈S} w_i(p) E_i(p) / Σ_{i∈S} w_i(p),
 *   E_i(p) = E_i + (n_i × n)·∇r E_i + (p − p_i)·∇t E_i   (per channel, clamped ≥ 0),
 * with Ward's or Tabellion–Lamorlette's weight (cache_internal.h: ic_record_weight). The set S comes
 * from a single root-to-leaf descent of the multiple-reference octree (seed 004 §4.3).
 *
 * Insertion (one record or a batch) runs the clamp steps of cache.h in a fixed order; records keep
 * the caller's order as their indices, and every parallel step writes per-record slots only, so the
 * cache never depends on the thread count.
 */
#include "cache_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
/* Eight entries at a time where the CPU has AVX2 (chosen at run time; the build stays baseline). */
#if defined(__SSE2__) && defined(__x86_64__) && defined(__GNUC__)
#define IC_HAVE_AVX2_PATH 1
#include <immintrin.h>
#define IC_TARGET_AVX2 __attribute__((target("avx2")))
#endif

/* The frozen look-up's loop is written once and instantiated per code path (SSE2, portable). */
#if defined(__GNUC__)
#define IC_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define IC_ALWAYS_INLINE inline
#endif

ic_result ic_cache_params_resolve(const ic_cache_params *in, ic_cache_params *out, ic_error *err)
{
    ic_cache_params p;
    if (in)
        p = *in;
    else
        memset(&p, 0, sizeof p);
    if (p.weight != IC_WEIGHT_WARD && p.weight != IC_WEIGHT_TABELLION)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: unknown weight kind %d; use IC_WEIGHT_WARD or "
                            "IC_WEIGHT_TABELLION", (int)p.weight);
    if (p.accuracy == 0.0f)
        p.accuracy = p.weight == IC_WEIGHT_WARD ? 0.2f : 1.0f;
    if (p.final_accuracy_scale == 0.0f)
        p.final_accuracy_scale = 1.0f;
    if (p.behind_tolerance == 0.0f)
        p.behind_tolerance = 0.05f;
    if (p.max_radius == 0.0f)
        p.max_radius = INFINITY;
    if (p.validity_k == 0)
        p.validity_k = 6;
    if (p.validity_angle_deg == 0.0f)
        p.validity_angle_deg = 30.0f;
    if (p.gradient_difference_threshold == 0.0f)
        p.gradient_difference_threshold = 0.1f;
    if (p.leaf_capacity == 0)
        p.leaf_capacity = 12;
    if (p.max_depth == 0)
        p.max_depth = 20;
    if (p.gradient_clamp == IC_CACHE_DEFAULT)
        p.gradient_clamp = IC_CACHE_ON;
    if (p.neighbor_clamp == IC_CACHE_DEFAULT)
        p.neighbor_clamp = IC_CACHE_ON;
    if (p.validity_clamp == IC_CACHE_DEFAULT)
        p.validity_clamp = IC_CACHE_ON;
    if (p.gradient_difference == IC_CACHE_DEFAULT)
        p.gradient_difference = IC_CACHE_OFF;
    if (p.freeze == IC_CACHE_DEFAULT)
        p.freeze = IC_CACHE_ON;

    if (!(p.accuracy > 0.0f && isfinite(p.accuracy)))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: accuracy %g must be positive", (double)p.accuracy);
    if (!(p.final_accuracy_scale >= 1.0f && isfinite(p.final_accuracy_scale)))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: final_accuracy_scale %g must be at least 1",
                            (double)p.final_accuracy_scale);
    if (!(p.behind_tolerance >= 0.0f && isfinite(p.behind_tolerance)))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: behind_tolerance %g must not be negative",
                            (double)p.behind_tolerance);
    if (!(p.min_radius >= 0.0f && isfinite(p.min_radius)) || !(p.max_radius >= p.min_radius))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: radius bounds [%g, %g] are not an interval",
                            (double)p.min_radius, (double)p.max_radius);
    if (!(p.min_radius_pixels >= 0.0f && p.max_radius_pixels >= 0.0f && isfinite(p.max_radius_pixels)) ||
        (p.max_radius_pixels > 0.0f && p.max_radius_pixels < p.min_radius_pixels))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: pixel radius bounds [%g, %g] are not an interval",
                            (double)p.min_radius_pixels, (double)p.max_radius_pixels);
    const ic_cache_switch sw[5] = {p.gradient_clamp, p.neighbor_clamp, p.validity_clamp, p.gradient_difference,
                                   p.freeze};
    for (int k = 0; k < 5; ++k)
        if (sw[k] != IC_CACHE_ON && sw[k] != IC_CACHE_OFF)
            return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: a switch (clamp or freeze) has value %d; use IC_CACHE_ON "
                                "or IC_CACHE_OFF", (int)sw[k]);
    if (p.validity_k > 16)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: validity_k %u must be in 1…16", p.validity_k);
    if (!(p.validity_angle_deg > 0.0f && p.validity_angle_deg < 180.0f))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: validity_angle_deg %g must be in (0, 180)",
                            (double)p.validity_angle_deg);
    if (!(p.gradient_difference_threshold > 0.0f && isfinite(p.gradient_difference_threshold)))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: gradient_difference_threshold must be positive");
    if (p.max_depth > IC_OCTREE_MAX_DEPTH)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: max_depth %u exceeds %d", p.max_depth,
                            IC_OCTREE_MAX_DEPTH);
    if (p.threads < 0)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: threads %d must not be negative", p.threads);
    *out = p;
    return IC_OK;
}

ic_result ic_cache_create(const ic_cache_params *params, ic_cache **out, ic_error *err)
{
    if (!out)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: no output handle");
    *out = NULL;
    ic_cache_params p;
    ic_result rc = ic_cache_params_resolve(params, &p, err);
    if (rc != IC_OK)
        return rc;
    ic_cache *c = calloc(1, sizeof *c);
    if (!c)
        return ic_error_set(err, IC_ERR_OOM, "cache: out of memory");
    c->params = p;
    ic_cache_set_lookup_path(c, IC_LOOKUP_BEST);
    c->tree_scale = fmaxf(1.0f, p.final_accuracy_scale);
    ic_octree_init(&c->tree, p.leaf_capacity, p.max_depth);
    /* Points: small buckets keep k-nearest searches short; depth as deep as allowed. */
    ic_octree_init(&c->points, 8, IC_OCTREE_MAX_DEPTH);
    *out = c;
    return IC_OK;
}

void ic_cache_destroy(ic_cache *c)
{
    if (!c)
        return;
    ic_octree_free(&c->tree);
    ic_octree_free(&c->points);
    ic_frozen_free(&c->frozen);
    free(c->sphere);
    free(c->normal);
    free(c->cold);
    free(c->scratch);
    free(c->changed);
    free(c);
}

const ic_cache_params *ic_cache_get_params(const ic_cache *c) { return &c->params; }
uint32_t ic_cache_count(const ic_cache *c) { return c ? c->count : 0; }
size_t ic_cache_bytes_per_record(void) { return 2 * sizeof(ic_float4) + sizeof(ic_record_cold); }

size_t ic_cache_memory_bytes(const ic_cache *c)
{
    return sizeof *c + (size_t)c->cap * ic_cache_bytes_per_record() + ic_octree_bytes(&c->tree) +
           ic_octree_bytes(&c->points) + (size_t)c->scratch_cap * sizeof(uint32_t) + ic_frozen_bytes(&c->frozen);
}

/* Depth-first walk of the octree below `node` (at `depth`, `above` references on the path to it). */
static void index_walk(const ic_octree *t, uint32_t node, uint32_t depth, uint64_t above, ic_cache_index_stats *s,
                       uint64_t *path_sum)
{
    const ic_octree_node *nd = &t->nodes[node];
    ++s->nodes;
    s->references += nd->count;
    uint64_t path = above + nd->count;
    if (nd->child) {
        for (unsigned o = 0; o < 8; ++o)
            index_walk(t, nd->child + o, depth + 1, path, s, path_sum);
        return;
    }
    ++s->leaves;
    s->depth = depth > s->depth ? depth : s->depth;
    s->leaf_references += nd->count;
    s->max_leaf_references = nd->count > s->max_leaf_references ? nd->count : s->max_leaf_references;
    *path_sum += path;
    s->max_path_references = path > s->max_path_references ? (uint32_t)path : s->max_path_references;
}

void ic_cache_get_index_stats(const ic_cache *c, ic_cache_index_stats *out)
{
    memset(out, 0, sizeof *out);
    if (!c || !c->tree.has_root || c->count == 0)
        return;
    uint64_t path_sum = 0;
    index_walk(&c->tree, 0, 0, 0, out, &path_sum);
    out->references_per_record = (double)out->references / c->count;
    out->leaf_references /= out->leaves;
    out->path_references = (double)path_sum / out->leaves;
    const ic_frozen *f = &c->frozen;
    if (f->is_valid && f->leaf_count) {
        out->frozen_leaves = f->leaf_count;
        out->frozen_list_entries = (double)f->entry_count / f->leaf_count;
        for (uint32_t k = 0; k < f->leaf_count; ++k) {
            const ic_frozen_leaf *l = (const ic_frozen_leaf *)(f->list + f->leaf_at[k]);
            out->max_frozen_list_entries =
                l->count > out->max_frozen_list_entries ? l->count : out->max_frozen_list_entries;
        }
    }
}

ic_result ic_cache_reserve(ic_cache *c, uint32_t n)
{
    if (n <= c->cap)
        return IC_OK;
    uint32_t cap = c->cap ? c->cap : 256;
    while (cap < n)
        cap = cap > UINT32_MAX / 2 ? UINT32_MAX : cap * 2;
    ic_float4 *s = realloc(c->sphere, (size_t)cap * sizeof *s);
    if (!s)
        return IC_ERR_OOM;
    c->sphere = s;
    ic_float4 *nn = realloc(c->normal, (size_t)cap * sizeof *nn);
    if (!nn)
        return IC_ERR_OOM;
    c->normal = nn;
    ic_record_cold *cd = realloc(c->cold, (size_t)cap * sizeof *cd);
    if (!cd)
        return IC_ERR_OOM;
    c->cold = cd;
    c->cap = cap;
    return IC_OK;
}

static int vec_finite(ic_vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

/* Checks record k of a batch; writes its step-1 radius to *radius. */
static ic_result check_record(const ic_cache *c, const ic_record *r, uint32_t k, float *radius, ic_error *err)
{
    int ok = vec_finite(r->position) && vec_finite(r->normal) && v3_len2(r->normal) > 0.0f &&
             vec_finite(r->irradiance) && vec_finite(r->tangent) && vec_finite(r->sigma);
    for (int ch = 0; ch < 3 && ok; ++ch)
        ok = vec_finite(r->grad_rot[ch]) && vec_finite(r->grad_trans[ch]);
    if (!ok)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: record %u of the batch has a non-finite field or a "
                            "zero normal", k);
    if (!(r->accuracy >= 0.0f && isfinite(r->accuracy)) || !(r->pixel_footprint >= 0.0f) ||
        !isfinite(r->pixel_footprint))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: record %u of the batch has a negative accuracy or "
                            "pixel footprint", k);
    if (!(r->harmonic_mean_dist > 0.0f))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: record %u of the batch has harmonic_mean_dist %g; "
                            "it must be positive", k, (double)r->harmonic_mean_dist);
    *radius = ic_cache_clamp_record(&c->params, r);
    if (!(*radius > 0.0f && isfinite(*radius)))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: record %u of the batch has an infinite radius; "
                            "cap ray misses in the gatherer or set max_radius", k);
    return IC_OK;
}

static void store_record(ic_cache *c, uint32_t i, const ic_record *r, float radius)
{
    ic_vec3 n = v3_norm(r->normal);
    float a = r->accuracy > 0.0f ? r->accuracy : c->params.accuracy;
    c->sphere[i] = (ic_float4){r->position.x, r->position.y, r->position.z, radius};
    c->normal[i] = (ic_float4){n.x, n.y, n.z, a};
    ic_record_cold *cd = &c->cold[i];
    memset(cd, 0, sizeof *cd);
    cd->irradiance = r->irradiance;
    memcpy(cd->grad_rot, r->grad_rot, sizeof cd->grad_rot);
    memcpy(cd->grad_trans, r->grad_trans, sizeof cd->grad_trans);
    /* A missing tangent gets the canonical frame of the normal. */
    cd->tangent = v3_len2(r->tangent) > 0.0f ? v3_norm(r->tangent) : ic_frame_from_normal(n).t;
    cd->sigma = r->sigma;
    cd->harmonic_mean_dist = r->harmonic_mean_dist;
    cd->pixel_footprint = r->pixel_footprint;
    cd->change_count = 0;
    cd->bounce = r->bounce;
    cd->flags = r->flags;
}

/* Undo a failed insertion (out of memory half-way): drop the new records and rebuild both trees. */
static void roll_back(ic_cache *c, uint32_t first)
{
    c->count = first;
    ic_octree_items pts = ic_cache_point_items(c), sph = ic_cache_tree_items(c);
    ic_octree_build(&c->points, &pts, first);
    ic_octree_build(&c->tree, &sph, first);
}

/* Shared by the single and the batch entry points: a single insertion is a batch of one. */
static ic_result insert_records(ic_cache *c, const ic_record *recs, uint32_t n, uint32_t *out_first, ic_error *err)
{
    if (!c || (!recs && n))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: no cache or no records");
    if (n > UINT32_MAX - 1 - c->count)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: too many records (the index is 32-bit)");
    uint32_t first = c->count;
    if (out_first)
        *out_first = first;
    if (n == 0)
        return IC_OK;
    if (ic_cache_reserve(c, first + n) != IC_OK)
        return ic_error_set(err, IC_ERR_OOM, "cache: out of memory for %u records", first + n);
    /* New records are in no frozen list and the clamps change radii: thaw (before any check can fail,
     * so a refused batch thaws too — the rule stays simple: an insertion call thaws). */
    ic_frozen_free(&c->frozen);
    /* Validate everything before touching the cache: all-or-nothing. */
    for (uint32_t k = 0; k < n; ++k) {
        float radius = 0.0f;
        ic_result rc = check_record(c, &recs[k], k, &radius, err);
        if (rc != IC_OK)
            return rc;
        store_record(c, first + k, &recs[k], radius);
    }
    c->count = first + n;

    ic_octree_items pts = ic_cache_point_items(c), sph = ic_cache_tree_items(c);
    ic_result rc = IC_OK;
    c->changed_len = 0;
    for (uint32_t k = 0; k < n && rc == IC_OK; ++k)
        rc = ic_octree_insert(&c->points, &pts, first + k);
    if (rc == IC_OK && c->params.validity_clamp == IC_CACHE_ON)
        rc = ic_cache_validity_clamp(c, first);
    /* Steps 3 and 4 find "records whose sphere holds p_i" in the sphere octree, so the new records
     * go in now, with their radii after step 2; later shrinking leaves their references
     * conservative, never wrong. */
    for (uint32_t k = 0; k < n && rc == IC_OK; ++k)
        rc = ic_octree_insert(&c->tree, &sph, first + k);
    if (rc == IC_OK && c->params.gradient_difference == IC_CACHE_ON)
        rc = ic_cache_gradient_difference(c, first);
    if (rc == IC_OK && c->params.neighbor_clamp == IC_CACHE_ON)
        rc = ic_cache_neighbor_clamp(c, first);
    /* A large batch rebuilds the octree to fit the final radii (deterministic rule); small ones only
     * compact dead reference segments. */
    if (rc == IC_OK && n > 1 && (uint64_t)n * 8 >= c->count)
        rc = ic_octree_build(&c->tree, &sph, c->count);
    if (rc == IC_OK)
        rc = ic_octree_compact(&c->tree);
    if (rc == IC_OK)
        rc = ic_octree_compact(&c->points);
    if (rc != IC_OK) {
        roll_back(c, first);
        return ic_error_set(err, rc, "cache: out of memory inserting %u records; they were dropped", n);
    }
    return IC_OK;
}

ic_result ic_cache_insert(ic_cache *c, const ic_record *record, uint32_t *out_index, ic_error *err)
{
    return insert_records(c, record, record ? 1 : 0, out_index, err);
}

ic_result ic_cache_insert_batch(ic_cache *c, const ic_record *records, uint32_t count, uint32_t *out_first,
                                ic_error *err)
{
    return insert_records(c, records, count, out_first, err);
}

ic_result ic_cache_rebuild_index(ic_cache *c, ic_error *err)
{
    if (!c)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: no cache");
    ic_frozen_free(&c->frozen);
    ic_octree_items sph = ic_cache_tree_items(c);
    ic_result rc = ic_octree_build(&c->tree, &sph, c->count);
    if (rc == IC_OK)
        rc = ic_octree_compact(&c->tree);
    if (rc != IC_OK)
        return ic_error_set(err, rc, "cache: out of memory rebuilding the octree");
    return c->params.freeze == IC_CACHE_ON ? ic_cache_freeze(c, err) : IC_OK;
}

ic_result ic_cache_freeze(ic_cache *c, ic_error *err)
{
    if (!c)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: no cache");
    if (ic_frozen_build(c) != IC_OK)
        return ic_error_set(err, IC_ERR_OOM, "cache: out of memory freezing the look-up layout (the cache "
                            "stays usable through its octree)");
    return IC_OK;
}

void ic_cache_thaw(ic_cache *c)
{
    if (c)
        ic_frozen_free(&c->frozen);
}

int ic_cache_is_frozen(const ic_cache *c) { return c && c->frozen.is_valid; }

/* Counts record i (accepted with weight w, extrapolated value e3) into the estimate, after its w·E_i(p)
 * went into the caller's sums, and reports it in the caller's buffer while there is room. */
static inline void count_contributor(uint32_t i, float w, const float e3[3], const ic_cache_lookup *q,
                                     ic_cache_estimate *e)
{
    e->weight_sum += w;
    if (e->contributor_count < q->contribution_capacity && q->contributions) {
        ic_cache_contribution *o = &q->contributions[e->contributor_count];
        o->record = i;
        o->weight = w;
        o->value = v3(e3[0], e3[1], e3[2]);
        e->contributions_written = e->contributor_count + 1;
    }
    ++e->contributor_count;
}

/* Accumulates record i (already accepted with weight w, offset dp = p − p_i; ni: its normal; E, gr, gt:
 * its irradiance and rotation and translation gradients) into the estimate. */
static inline void accumulate(uint32_t i, const ic_float4 *ni, const ic_vec3 *E, const ic_vec3 gr[3],
                              const ic_vec3 gt[3], ic_vec3 n, float w, ic_vec3 dp, const ic_cache_lookup *q,
                              ic_cache_estimate *e, float acc[3])
{
    /* (n_i × n): the rotation that takes the record's normal to ours (seed 000 §3). */
    ic_vec3 rot = v3_cross(v3(ni->x, ni->y, ni->z), n);
    float e3[3] = {E->x, E->y, E->z};
    for (int ch = 0; ch < 3; ++ch) {
        float v = e3[ch] + v3_dot(rot, gr[ch]) + v3_dot(dp, gt[ch]);
        /* Extrapolation with large gradients can go negative; irradiance cannot. */
        e3[ch] = v > 0.0f ? v : 0.0f;
        acc[ch] += w * e3[ch];
    }
    count_contributor(i, w, e3, q, e);
}

/* accumulate() from the cache's own arrays. */
static inline void accumulate_record(const ic_cache *c, uint32_t i, ic_vec3 n, float w, ic_vec3 dp,
                                     const ic_cache_lookup *q, ic_cache_estimate *e, float acc[3])
{
    const ic_record_cold *cd = &c->cold[i];
    accumulate(i, &c->normal[i], &cd->irradiance, cd->grad_rot, cd->grad_trans, n, w, dp, q, e, acc);
}

static int finish(ic_cache_estimate *e, const float acc[3])
{
    if (e->weight_sum > 0.0f) {
        float inv = 1.0f / e->weight_sum;
        e->irradiance = v3(acc[0] * inv, acc[1] * inv, acc[2] * inv);
    }
    return e->contributor_count > 0;
}

/* Records of the wrong bounce level or disabled ones are skipped after the weight test: the test only
 * reads the hot arrays, and such records are rare. */
static inline int eligible(const ic_cache *c, uint32_t i, const ic_cache_lookup *q)
{
    const ic_record_cold *cd = &c->cold[i];
    return cd->bounce == q->bounce && !(cd->flags & IC_RECORD_DISABLED);
}

/* Frozen layout: the leaf whose cell holds p — the hint's when p is still in its cell, else found by
 * descent, which updates the hint; NULL outside the root. With SSE2 (unless is_portable) the three axes
 * go side by side: the same comparisons, and c ± h as c + (±h), which IEEE arithmetic rounds alike, so
 * the same leaf; and no branch on an axis's side, which no predictor guesses. */
static IC_ALWAYS_INLINE const ic_frozen_leaf *frozen_leaf(const ic_frozen *f, ic_vec3 p, ic_cache_hint *hint,
                                                          int is_portable)
{
#if defined(__SSE2__)
    if (!is_portable) {
        __m128 pv = _mm_setr_ps(p.x, p.y, p.z, 0.0f);
        if (hint && hint->leaf - 1u < f->leaf_count) {
            const ic_frozen_leaf *l = (const ic_frozen_leaf *)(f->list + f->leaf_at[hint->leaf - 1u]);
            __m128 in = _mm_and_ps(_mm_cmpge_ps(pv, _mm_loadu_ps(l->lo)), _mm_cmplt_ps(pv, _mm_loadu_ps(l->hi)));
            if ((_mm_movemask_ps(in) & 7) == 7)
                return l;
        }
        __m128 cv = _mm_setr_ps(f->cx, f->cy, f->cz, 0.0f), hv = _mm_set1_ps(f->half);
        __m128 root = _mm_and_ps(_mm_cmpge_ps(pv, _mm_sub_ps(cv, hv)), _mm_cmple_ps(pv, _mm_add_ps(cv, hv)));
        if (!f->has_root || (_mm_movemask_ps(root) & 7) != 7)
            return NULL;
        const __m128 sign = _mm_set1_ps(-0.0f), half = _mm_set1_ps(0.5f);
        const uint32_t *node = f->node;
        uint32_t v = node[0];
        while (!(v & IC_FROZEN_LEAF)) {
            hv = _mm_mul_ps(hv, half);
            __m128 upper = _mm_cmpge_ps(pv, cv);
            cv = _mm_add_ps(cv, _mm_xor_ps(hv, _mm_andnot_ps(upper, sign)));
            v = node[v + ((unsigned)_mm_movemask_ps(upper) & 7u)];
        }
        const ic_frozen_leaf *l = (const ic_frozen_leaf *)(f->list + (v & ~IC_FROZEN_LEAF));
        if (hint)
            hint->leaf = l->id + 1u;
        return l;
    }
#endif
    (void)is_portable;
    if (hint && hint->leaf - 1u < f->leaf_count) {
        const ic_frozen_leaf *l = (const ic_frozen_leaf *)(f->list + f->leaf_at[hint->leaf - 1u]);
        if (p.x >= l->lo[0] && p.x < l->hi[0] && p.y >= l->lo[1] && p.y < l->hi[1] && p.z >= l->lo[2] &&
            p.z < l->hi[2])
            return l;
    }
    float cx = f->cx, cy = f->cy, cz = f->cz, h = f->half;
    if (!f->has_root ||
        !(p.x >= cx - h && p.x <= cx + h && p.y >= cy - h && p.y <= cy + h && p.z >= cz - h && p.z <= cz + h))
        return NULL;
    const uint32_t *node = f->node;
    uint32_t v = node[0];
    while (!(v & IC_FROZEN_LEAF)) {
        /* The octree's descent arithmetic (octree.h: ic_octree_path): the same leaf, bit for bit. */
        h *= 0.5f;
        unsigned ox = p.x >= cx, oy = p.y >= cy, oz = p.z >= cz;
        cx = ox ? cx + h : cx - h;
        cy = oy ? cy + h : cy - h;
        cz = oz ? cz + h : cz - h;
        v = node[v + (ox | oy << 1 | oz << 2)];
    }
    const ic_frozen_leaf *l = (const ic_frozen_leaf *)(f->list + (v & ~IC_FROZEN_LEAF));
    if (hint)
        hint->leaf = l->id + 1u;
    return l;
}

/* What a block's contributing entries need for accumulate(): w_i(p) and p − p_i per lane. */
typedef struct block_weights {
    float w[4];
    float dx[4], dy[4], dz[4];
} block_weights;

/* Lane k of the block contributes: it passes ic_weight_test and is eligible (bounce, flags). Entry by
 * entry with ic_weight_test itself: the reference for the SSE2 code below, and the code where SSE2 is
 * absent. */
static inline unsigned block_weights_portable(const ic_cache_params *params, const ic_frozen_block *b, ic_vec3 p,
                                              ic_vec3 n, float s, uint32_t bounce, block_weights *out)
{
    unsigned mask = 0;
    for (unsigned k = 0; k < 4; ++k) {
        ic_float4 sp = {b->x[k], b->y[k], b->z[k], b->R[k]}, np = {b->nx[k], b->ny[k], b->nz[k], b->a[k]};
        ic_vec3 dp;
        if (b->bounce[k] != bounce || (b->flags[k] & IC_RECORD_DISABLED) ||
            !ic_weight_test(params, &sp, &np, p, n, s, &out->w[k], &dp))
            continue;
        out->dx[k] = dp.x;
        out->dy[k] = dp.y;
        out->dz[k] = dp.z;
        mask |= 1u << k;
    }
    return mask;
}

#if defined(__SSE2__)
/* Byte k: all ones where entry k is of this bounce level and not disabled (bounce and flag bytes of up
 * to 16 entries side by side). */
static IC_ALWAYS_INLINE __m128i eligible_bytes(__m128i bounce_bytes, __m128i flag_bytes, uint32_t bounce)
{
    const __m128i disabled = _mm_set1_epi8(IC_RECORD_DISABLED);
    return _mm_andnot_si128(_mm_cmpeq_epi8(_mm_and_si128(flag_bytes, disabled), disabled),
                            _mm_cmpeq_epi8(bounce_bytes, _mm_set1_epi8((char)bounce)));
}

/* block_weights_portable four lanes at a time: ic_weight_test's tests in its order, each with the
 * same float operations on the same operands (packed IEEE add, mul, div and sqrt round like their
 * scalar forms), so every decision and every weight is bit-identical. */
static inline unsigned block_weights_sse2(const ic_cache_params *params, const ic_frozen_record *records,
                                          const ic_frozen_block *b, ic_vec3 p, ic_vec3 n, float s, uint32_t bounce,
                                          block_weights *out)
{
    const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
    __m128 dx = _mm_sub_ps(_mm_set1_ps(p.x), _mm_loadu_ps(b->x));
    __m128 dy = _mm_sub_ps(_mm_set1_ps(p.y), _mm_loadu_ps(b->y));
    __m128 dz = _mm_sub_ps(_mm_set1_ps(p.z), _mm_loadu_ps(b->z));
    __m128 d2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
    __m128 a = _mm_mul_ps(_mm_loadu_ps(b->a), _mm_set1_ps(s)), R = _mm_loadu_ps(b->R), r = _mm_mul_ps(a, R);
    /* Inside the influence sphere: most blocks of a list fail this in every lane and stop here (testing
     * the facing too before stopping was slower: the extra work outweighs the blocks it stops). */
    __m128 pass = _mm_cmplt_ps(d2, _mm_mul_ps(r, r));
    if (!_mm_movemask_ps(pass))
        return 0;
    /* Not facing away (!(ndot <= 0): a NaN goes on, as in the scalar code). */
    __m128 nx = _mm_loadu_ps(b->nx), ny = _mm_loadu_ps(b->ny), nz = _mm_loadu_ps(b->nz);
    __m128 ndot = _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_set1_ps(n.x), nx), _mm_mul_ps(_mm_set1_ps(n.y), ny)),
                             _mm_mul_ps(_mm_set1_ps(n.z), nz));
    pass = _mm_and_ps(pass, _mm_cmpnle_ps(ndot, zero));
    /* Fetch the block's records (all four lanes: a branch per lane to skip the rejected ones was not
     * measured to pay) while the rest of the test runs. */
    for (unsigned k = 0; k < 4; ++k) {
        const char *rec = (const char *)&records[b->slot[k]];
        _mm_prefetch(rec, _MM_HINT_T0);
        _mm_prefetch(rec + sizeof *records - 1, _MM_HINT_T0);
    }
    /* Not behind the record. */
    __m128 behind = _mm_mul_ps(_mm_set1_ps(0.5f),
                               _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, _mm_add_ps(_mm_set1_ps(n.x), nx)),
                                                     _mm_mul_ps(dy, _mm_add_ps(_mm_set1_ps(n.y), ny))),
                                          _mm_mul_ps(dz, _mm_add_ps(_mm_set1_ps(n.z), nz))));
    pass = _mm_and_ps(pass, _mm_cmpnlt_ps(behind, _mm_mul_ps(_mm_set1_ps(-params->behind_tolerance), r)));
    /* max(x, 0) is x > 0 ? x : 0, NaN included (maxps returns its second operand unless x > 0). */
    __m128 dist = _mm_div_ps(_mm_sqrt_ps(d2), R), ndev = _mm_sqrt_ps(_mm_max_ps(_mm_sub_ps(one, ndot), zero)), w;
    if (params->weight == IC_WEIGHT_WARD) {
        __m128 denom = _mm_add_ps(dist, ndev);
        pass = _mm_and_ps(pass, _mm_cmplt_ps(denom, a));
        w = _mm_div_ps(one, _mm_max_ps(denom, _mm_set1_ps(1e-6f)));
    } else {
        __m128 nt = _mm_mul_ps(ndev, _mm_set1_ps(IC_TL_NORMAL_SCALE));
        w = _mm_sub_ps(one, _mm_div_ps(_mm_max_ps(dist, nt), a));
        pass = _mm_and_ps(pass, _mm_cmpgt_ps(w, zero));
    }
    /* Eligible: this bounce level, not disabled (bytes widened to the float lanes' 32 bits). */
    int32_t bounce_bytes, flag_bytes;
    memcpy(&bounce_bytes, b->bounce, 4);
    memcpy(&flag_bytes, b->flags, 4);
    __m128i ok = eligible_bytes(_mm_cvtsi32_si128(bounce_bytes), _mm_cvtsi32_si128(flag_bytes), bounce);
    ok = _mm_unpacklo_epi16(_mm_unpacklo_epi8(ok, ok), _mm_unpacklo_epi8(ok, ok));
    pass = _mm_and_ps(pass, _mm_castsi128_ps(ok));
    _mm_storeu_ps(out->w, w);
    _mm_storeu_ps(out->dx, dx);
    _mm_storeu_ps(out->dy, dy);
    _mm_storeu_ps(out->dz, dz);
    return (unsigned)_mm_movemask_ps(pass);
}
#endif

/* accumulate() for a frozen record, from its rows. */
static inline void accumulate_frozen_portable(const ic_frozen_record *r, const ic_float4 *ni, ic_vec3 n, float w,
                                              ic_vec3 dp, const ic_cache_lookup *q, ic_cache_estimate *e,
                                              float acc[3])
{
    ic_vec3 E = v3(r->row[IC_FROZEN_E][0], r->row[IC_FROZEN_E][1], r->row[IC_FROZEN_E][2]), gr[3], gt[3];
    for (int ch = 0; ch < 3; ++ch) {
        gr[ch] = v3(r->row[IC_FROZEN_GRAD_ROT][ch], r->row[IC_FROZEN_GRAD_ROT + 1][ch],
                    r->row[IC_FROZEN_GRAD_ROT + 2][ch]);
        gt[ch] = v3(r->row[IC_FROZEN_GRAD_TRANS][ch], r->row[IC_FROZEN_GRAD_TRANS + 1][ch],
                    r->row[IC_FROZEN_GRAD_TRANS + 2][ch]);
    }
    accumulate(r->index, ni, &E, gr, gt, n, w, dp, q, e, acc);
}

#if defined(__SSE2__)
/* accumulate() with the three channels in three lanes: per lane the same operations in the same order
 * (E + ((rot.x·gr.x + rot.y·gr.y) + rot.z·gr.z)) + ((dp.x·gt.x + dp.y·gt.y) + dp.z·gt.z), clamped
 * with maxps (v > 0 ? v : 0, NaN included), so each channel is bit-identical to accumulate(). */
/* E_i(p) of record r, R, G and B in lanes 0–2, given rot = n_i × n and dp = p − p_i. */
static IC_ALWAYS_INLINE __m128 extrapolate_sse2(const ic_frozen_record *r, float rx, float ry, float rz, float dx,
                                                float dy, float dz)
{
    const float *row = &r->row[0][0]; /* the rows as one array: row k starts at row + 3k */
    /* Row 6's fourth lane is the index: cleared, so that no stray denormal or NaN enters the sums. */
    const __m128 last = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0));
    __m128 dot_rot = _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_set1_ps(rx), _mm_loadu_ps(row + 3)),
                                           _mm_mul_ps(_mm_set1_ps(ry), _mm_loadu_ps(row + 6))),
                                _mm_mul_ps(_mm_set1_ps(rz), _mm_loadu_ps(row + 9)));
    __m128 dot_trans = _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_set1_ps(dx), _mm_loadu_ps(row + 12)),
                                             _mm_mul_ps(_mm_set1_ps(dy), _mm_loadu_ps(row + 15))),
                                  _mm_mul_ps(_mm_set1_ps(dz), _mm_and_ps(_mm_loadu_ps(row + 18), last)));
    return _mm_max_ps(_mm_add_ps(_mm_add_ps(_mm_loadu_ps(row), dot_rot), dot_trans), _mm_setzero_ps());
}

static inline void accumulate_frozen_sse2(const ic_frozen_record *r, const ic_float4 *ni, ic_vec3 n, float w,
                                          ic_vec3 dp, const ic_cache_lookup *q, ic_cache_estimate *e,
                                          __m128 *acc)
{
    ic_vec3 rot = v3_cross(v3(ni->x, ni->y, ni->z), n);
    __m128 v = extrapolate_sse2(r, rot.x, rot.y, rot.z, dp.x, dp.y, dp.z);
    *acc = _mm_add_ps(*acc, _mm_mul_ps(_mm_set1_ps(w), v));
    float e3[4];
    _mm_storeu_ps(e3, v);
    count_contributor(r->index, w, e3, q, e);
}
#endif

/* Lowest set bit of a 4-bit lane mask. */
static const uint8_t lowest_lane[16] = {0, 0, 1, 0, 2, 0, 1, 0, 3, 0, 1, 0, 2, 0, 1, 0};

/* Start of a frozen look-up: clears the estimate and returns the first block of p's leaf (NULL outside
 * the root), its number of blocks and the acceptance's accuracy scale. */
static IC_ALWAYS_INLINE const ic_frozen_block *frozen_begin(const ic_cache *c, const ic_cache_lookup *q,
                                                            ic_cache_hint *hint, ic_cache_estimate *out,
                                                            int is_portable, uint32_t *blocks, float *s)
{
    memset(out, 0, sizeof *out);
    const ic_frozen_leaf *leaf = frozen_leaf(&c->frozen, q->position, hint, is_portable);
    if (!leaf)
        return NULL;
    *s = q->acceptance == IC_ACCEPT_FINAL ? c->params.final_accuracy_scale : 1.0f;
    /* Bounce levels are stored in bytes: a higher level has no records. */
    *blocks = q->bounce <= UINT8_MAX ? (leaf->count + 3) / 4 : 0;
    out->records_tested = leaf->count;
    return (const ic_frozen_block *)(leaf + 1);
}

/* ic_cache_query on the frozen layout: one list, four entries at a time, with SSE2 unless is_portable
 * (a constant: each caller below gets its own copy of the loop). */
static IC_ALWAYS_INLINE int query_frozen(const ic_cache *c, const ic_cache_lookup *q, ic_cache_hint *hint,
                                         ic_cache_estimate *out, int is_portable)
{
    const ic_frozen *f = &c->frozen;
    float acc[4] = {0.0f, 0.0f, 0.0f, 0.0f}, s;
    ic_vec3 p = q->position, n = q->normal;
    uint32_t blocks;
    const ic_frozen_block *blk = frozen_begin(c, q, hint, out, is_portable, &blocks, &s);
    if (!blk)
        return 0;
#if defined(__SSE2__)
    __m128 acc4 = _mm_setzero_ps();
#endif
    for (uint32_t b = 0; b < blocks; ++b) {
        const ic_frozen_block *o = &blk[b];
        block_weights bw;
#if defined(__SSE2__)
        unsigned mask = is_portable ? block_weights_portable(&c->params, o, p, n, s, q->bounce, &bw)
                                    : block_weights_sse2(&c->params, f->record, o, p, n, s, q->bounce, &bw);
#else
        unsigned mask = block_weights_portable(&c->params, o, p, n, s, q->bounce, &bw);
#endif
        while (mask) {
            unsigned k = lowest_lane[mask];
            mask &= mask - 1;
            const ic_frozen_record *r = &f->record[o->slot[k]];
            ic_float4 ni = {o->nx[k], o->ny[k], o->nz[k], o->a[k]};
            ic_vec3 dp = v3(bw.dx[k], bw.dy[k], bw.dz[k]);
#if defined(__SSE2__)
            if (!is_portable) {
                accumulate_frozen_sse2(r, &ni, n, bw.w[k], dp, q, out, &acc4);
                continue;
            }
#endif
            accumulate_frozen_portable(r, &ni, n, bw.w[k], dp, q, out, acc);
        }
    }
#if defined(__SSE2__)
    if (!is_portable)
        _mm_storeu_ps(acc, acc4);
#endif
    (void)is_portable;
    return finish(out, acc);
}

#if defined(IC_HAVE_AVX2_PATH)
/*
 * The AVX2 look-up tests two blocks (eight list entries) at a time: block_weights_sse2 with 256-bit
 * registers, lane for lane the same operations on the same operands (no FMA: the target is AVX2
 * alone), so every decision and weight is bit-identical. The contributors of a pair of blocks are then
 * packed, in list order, into a buffer with what their extrapolation needs (w_i, p − p_i, n_i × n and
 * the record slot), and the whole list's contributors are summed in one loop at the end: one loop of
 * unpredictable length per look-up instead of one per block pair, whose mispredicted exits cost more
 * than the packing (BENCHMARKS.md "Contributors packed"). Contributors are met in list order, so the
 * sums are those of every other path.
 */
enum { IC_PACKED_CAP = 64 }; /* contributors buffered before they are summed; 8 lanes of slack follow */

typedef struct packed_contributors {
    float w[IC_PACKED_CAP + 8];
    float dx[IC_PACKED_CAP + 8], dy[IC_PACKED_CAP + 8], dz[IC_PACKED_CAP + 8]; /* p − p_i */
    float rx[IC_PACKED_CAP + 8], ry[IC_PACKED_CAP + 8], rz[IC_PACKED_CAP + 8]; /* n_i × n */
    uint32_t slot[IC_PACKED_CAP + 8];
} packed_contributors;

/* The lanes set in a 4-bit mask, in increasing order, one byte each (unused bytes 0). */
static const uint32_t lanes_of_mask4[16] = {0x00000000, 0x00000000, 0x00000001, 0x00000100,
                                            0x00000002, 0x00000200, 0x00000201, 0x00020100,
                                            0x00000003, 0x00000300, 0x00000301, 0x00030100,
                                            0x00000302, 0x00030200, 0x00030201, 0x03020100};

static IC_TARGET_AVX2 inline __m256 load_pair(const float *lo, const float *hi)
{
    return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(lo)), _mm_loadu_ps(hi), 1);
}

/* The permutation that moves the lanes set in an 8-bit mask to the front, in order. */
static IC_TARGET_AVX2 inline __m256i packing_permutation(unsigned mask)
{
    unsigned lo = mask & 15u;
    uint64_t lanes = lanes_of_mask4[lo] |
                     (uint64_t)(lanes_of_mask4[mask >> 4] + 0x04040404u) << (8 * __builtin_popcount(lo));
    return _mm256_cvtepu8_epi32(_mm_cvtsi64_si128((long long)lanes));
}

/* Blocks b0 and b1 (lanes 0–3 and 4–7): appends their contributors to out at position `at` and returns
 * how many there are. Writes up to 8 lanes past them (the buffer's slack). */
static IC_TARGET_AVX2 inline unsigned block_weights_avx2(const ic_cache_params *params,
                                                         const ic_frozen_record *records, const ic_frozen_block *b0,
                                                         const ic_frozen_block *b1, ic_vec3 p, ic_vec3 n, float s,
                                                         uint32_t bounce, packed_contributors *out, unsigned at)
{
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
    __m256 dx = _mm256_sub_ps(_mm256_set1_ps(p.x), load_pair(b0->x, b1->x));
    __m256 dy = _mm256_sub_ps(_mm256_set1_ps(p.y), load_pair(b0->y, b1->y));
    __m256 dz = _mm256_sub_ps(_mm256_set1_ps(p.z), load_pair(b0->z, b1->z));
    __m256 d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
    __m256 a = _mm256_mul_ps(load_pair(b0->a, b1->a), _mm256_set1_ps(s)), R = load_pair(b0->R, b1->R);
    __m256 r = _mm256_mul_ps(a, R);
    __m256 pass = _mm256_cmp_ps(d2, _mm256_mul_ps(r, r), _CMP_LT_OQ);
    if (!_mm256_movemask_ps(pass))
        return 0;
    __m256 nx = load_pair(b0->nx, b1->nx), ny = load_pair(b0->ny, b1->ny), nz = load_pair(b0->nz, b1->nz);
    __m256 qx = _mm256_set1_ps(n.x), qy = _mm256_set1_ps(n.y), qz = _mm256_set1_ps(n.z); /* our normal */
    __m256 ndot = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(qx, nx), _mm256_mul_ps(qy, ny)), _mm256_mul_ps(qz, nz));
    pass = _mm256_and_ps(pass, _mm256_cmp_ps(ndot, zero, _CMP_NLE_UQ));
    /* Fetch all eight records (no branch per lane) while the rest of the test runs. */
    for (unsigned k = 0; k < 8; ++k) {
        const char *rec = (const char *)&records[k < 4 ? b0->slot[k] : b1->slot[k - 4]];
        _mm_prefetch(rec, _MM_HINT_T0);
        _mm_prefetch(rec + sizeof *records - 1, _MM_HINT_T0);
    }
    __m256 behind = _mm256_mul_ps(_mm256_set1_ps(0.5f),
                                  _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, _mm256_add_ps(qx, nx)),
                                                              _mm256_mul_ps(dy, _mm256_add_ps(qy, ny))),
                                                _mm256_mul_ps(dz, _mm256_add_ps(qz, nz))));
    pass = _mm256_and_ps(pass, _mm256_cmp_ps(behind, _mm256_mul_ps(_mm256_set1_ps(-params->behind_tolerance), r),
                                             _CMP_NLT_UQ));
    __m256 dist = _mm256_div_ps(_mm256_sqrt_ps(d2), R);
    __m256 ndev = _mm256_sqrt_ps(_mm256_max_ps(_mm256_sub_ps(one, ndot), zero)), w;
    if (params->weight == IC_WEIGHT_WARD) {
        __m256 denom = _mm256_add_ps(dist, ndev);
        pass = _mm256_and_ps(pass, _mm256_cmp_ps(denom, a, _CMP_LT_OQ));
        w = _mm256_div_ps(one, _mm256_max_ps(denom, _mm256_set1_ps(1e-6f)));
    } else {
        __m256 nt = _mm256_mul_ps(ndev, _mm256_set1_ps(IC_TL_NORMAL_SCALE));
        w = _mm256_sub_ps(one, _mm256_div_ps(_mm256_max_ps(dist, nt), a));
        pass = _mm256_and_ps(pass, _mm256_cmp_ps(w, zero, _CMP_GT_OQ));
    }
    int32_t bounce_bytes[2], flag_bytes[2];
    memcpy(&bounce_bytes[0], b0->bounce, 4);
    memcpy(&bounce_bytes[1], b1->bounce, 4);
    memcpy(&flag_bytes[0], b0->flags, 4);
    memcpy(&flag_bytes[1], b1->flags, 4);
    __m128i ok = eligible_bytes(_mm_setr_epi32(bounce_bytes[0], bounce_bytes[1], 0, 0),
                                _mm_setr_epi32(flag_bytes[0], flag_bytes[1], 0, 0), bounce);
    pass = _mm256_and_ps(pass, _mm256_castsi256_ps(_mm256_cvtepi8_epi32(ok)));
    /* Packed without a branch on the mask (an empty mask writes only slack). n_i × n as v3_cross. */
    unsigned mask = (unsigned)_mm256_movemask_ps(pass);
    __m256i idx = packing_permutation(mask);
    __m256 rx = _mm256_sub_ps(_mm256_mul_ps(ny, qz), _mm256_mul_ps(nz, qy));
    __m256 ry = _mm256_sub_ps(_mm256_mul_ps(nz, qx), _mm256_mul_ps(nx, qz));
    __m256 rz = _mm256_sub_ps(_mm256_mul_ps(nx, qy), _mm256_mul_ps(ny, qx));
    __m256i slots = _mm256_loadu2_m128i((const __m128i *)b1->slot, (const __m128i *)b0->slot);
    _mm256_storeu_ps(out->w + at, _mm256_permutevar8x32_ps(w, idx));
    _mm256_storeu_ps(out->dx + at, _mm256_permutevar8x32_ps(dx, idx));
    _mm256_storeu_ps(out->dy + at, _mm256_permutevar8x32_ps(dy, idx));
    _mm256_storeu_ps(out->dz + at, _mm256_permutevar8x32_ps(dz, idx));
    _mm256_storeu_ps(out->rx + at, _mm256_permutevar8x32_ps(rx, idx));
    _mm256_storeu_ps(out->ry + at, _mm256_permutevar8x32_ps(ry, idx));
    _mm256_storeu_ps(out->rz + at, _mm256_permutevar8x32_ps(rz, idx));
    _mm256_storeu_si256((__m256i *)(out->slot + at), _mm256_permutevar8x32_epi32(slots, idx));
    return (unsigned)__builtin_popcount(mask);
}

/* E_i(p) of packed contributor k (extrapolate_sse2, operand for operand). */
static IC_TARGET_AVX2 inline __m128 extrapolate_packed(const ic_frozen_record *r, const packed_contributors *pc,
                                                       unsigned k)
{
    return extrapolate_sse2(r, pc->rx[k], pc->ry[k], pc->rz[k], pc->dx[k], pc->dy[k], pc->dz[k]);
}

/* The first `count` packed contributors into the sums, in order: R, G, B in *acc, Σ w_i in *weight_sum
 * and |S| in *contributors (kept out of `out` in the common case without a contributions buffer). */
static IC_TARGET_AVX2 inline void sum_packed(const ic_frozen_record *records, const packed_contributors *pc,
                                             unsigned count, const ic_cache_lookup *q, ic_cache_estimate *out,
                                             __m128 *acc, float *weight_sum, uint32_t *contributors)
{
    __m128 acc4 = *acc;
    if (!q->contributions) {
        float ws = *weight_sum;
        for (unsigned k = 0; k < count; ++k) {
            __m128 v = extrapolate_packed(&records[pc->slot[k]], pc, k);
            acc4 = _mm_add_ps(acc4, _mm_mul_ps(_mm_set1_ps(pc->w[k]), v));
            ws += pc->w[k];
        }
        *weight_sum = ws;
        *contributors += count;
    } else {
        out->weight_sum = *weight_sum;
        out->contributor_count = *contributors;
        for (unsigned k = 0; k < count; ++k) {
            const ic_frozen_record *r = &records[pc->slot[k]];
            __m128 v = extrapolate_packed(r, pc, k);
            acc4 = _mm_add_ps(acc4, _mm_mul_ps(_mm_set1_ps(pc->w[k]), v));
            float e3[4];
            _mm_storeu_ps(e3, v);
            count_contributor(r->index, pc->w[k], e3, q, out);
        }
        *weight_sum = out->weight_sum;
        *contributors = out->contributor_count;
    }
    *acc = acc4;
}

/* ic_cache_query on the frozen layout with AVX2: the list two blocks at a time (an odd last block pairs
 * with a block of padding), contributors summed at the end (or whenever the buffer is nearly full). */
static IC_TARGET_AVX2 int query_frozen_avx2(const ic_cache *c, const ic_cache_lookup *q, ic_cache_hint *hint,
                                            ic_cache_estimate *out)
{
    static const ic_frozen_block padding; /* R = a = 0: no distance passes */
    const ic_frozen *f = &c->frozen;
    float acc[4] = {0.0f, 0.0f, 0.0f, 0.0f}, s;
    ic_vec3 p = q->position, n = q->normal;
    uint32_t blocks;
    const ic_frozen_block *blk = frozen_begin(c, q, hint, out, 0, &blocks, &s);
    if (!blk)
        return 0;
    __m128 acc4 = _mm_setzero_ps();
    float weight_sum = 0.0f;
    uint32_t contributors = 0;
    packed_contributors pc;
    unsigned count = 0;
    for (uint32_t b = 0; b < blocks; b += 2) {
        const ic_frozen_block *b1 = b + 1 < blocks ? &blk[b + 1] : &padding;
        count += block_weights_avx2(&c->params, f->record, &blk[b], b1, p, n, s, q->bounce, &pc, count);
        /* One call site: two made the loop measurably slower. */
        if (count > IC_PACKED_CAP - 8 || b + 2 >= blocks) {
            sum_packed(f->record, &pc, count, q, out, &acc4, &weight_sum, &contributors);
            count = 0;
        }
    }
    out->weight_sum = weight_sum;
    out->contributor_count = contributors;
    _mm_storeu_ps(acc, acc4);
    return finish(out, acc);
}

/* 1 where the CPU runs AVX2. Asked at each cache creation: the answer is a read of what the runtime
 * found at start-up, so nothing is cached here and no thread writes shared state. */
static int cpu_has_avx2(void)
{
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") ? 1 : 0;
}
#endif

#if defined(__SSE2__)
static int query_frozen_sse2(const ic_cache *c, const ic_cache_lookup *q, ic_cache_hint *hint, ic_cache_estimate *out)
{
    return query_frozen(c, q, hint, out, 0);
}
#endif

static int query_frozen_portable(const ic_cache *c, const ic_cache_lookup *q, ic_cache_hint *hint,
                                 ic_cache_estimate *out)
{
    return query_frozen(c, q, hint, out, 1);
}

int ic_cache_set_lookup_path(ic_cache *c, ic_lookup_path path)
{
    int avx2 = 0, sse2 = 0;
#if defined(IC_HAVE_AVX2_PATH)
    avx2 = cpu_has_avx2();
#endif
#if defined(__SSE2__)
    sse2 = 1;
#endif
    if (path == IC_LOOKUP_BEST)
        path = avx2 ? IC_LOOKUP_AVX2 : sse2 ? IC_LOOKUP_SSE2 : IC_LOOKUP_PORTABLE;
    if ((path == IC_LOOKUP_AVX2 && !avx2) || (path == IC_LOOKUP_SSE2 && !sse2) || path < IC_LOOKUP_PORTABLE ||
        path > IC_LOOKUP_AVX2)
        return 0;
    c->lookup_path = path;
    return 1;
}

int ic_cache_query(const ic_cache *c, const ic_cache_lookup *q, ic_cache_estimate *out)
{
    return ic_cache_query_hinted(c, q, NULL, out);
}

int ic_cache_query_hinted(const ic_cache *c, const ic_cache_lookup *q, ic_cache_hint *hint, ic_cache_estimate *out)
{
    if (c->frozen.is_valid)
#if defined(IC_HAVE_AVX2_PATH)
        return c->lookup_path == IC_LOOKUP_PORTABLE ? query_frozen_portable(c, q, hint, out)
               : c->lookup_path == IC_LOOKUP_AVX2   ? query_frozen_avx2(c, q, hint, out)
                                                    : query_frozen_sse2(c, q, hint, out);
#elif defined(__SSE2__)
        return c->lookup_path == IC_LOOKUP_PORTABLE ? query_frozen_portable(c, q, hint, out)
                                                    : query_frozen_sse2(c, q, hint, out);
#else
        return query_frozen_portable(c, q, hint, out);
#endif
    float acc[3] = {0.0f, 0.0f, 0.0f};
    memset(out, 0, sizeof *out);
    float s = q->acceptance == IC_ACCEPT_FINAL ? c->params.final_accuracy_scale : 1.0f;
    ic_vec3 p = q->position, n = q->normal;
    uint32_t path[IC_OCTREE_MAX_DEPTH + 1];
    uint32_t len = ic_octree_path(&c->tree, p.x, p.y, p.z, path);
    /* Reference radii are a·R·tree_scale (conservative); scale them to this acceptance. */
    float ref_scale = s / c->tree_scale;
    for (uint32_t l = 0; l < len; ++l) {
        const ic_octree_node *node = &c->tree.nodes[path[l]];
        const ic_octree_ref *refs = c->tree.refs + node->begin;
        out->records_tested += node->count;
        for (uint32_t k = 0; k < node->count; ++k) {
            /* Pre-test from the reference alone: most references fail here, and the record's own
             * arrays are never touched for them. */
            const ic_octree_ref *ref = &refs[k];
            float rr = ref->r * ref_scale;
            if (!(ic_dist2(p.x, p.y, p.z, ref->x, ref->y, ref->z) < rr * rr))
                continue;
            uint32_t i = ref->index;
            float w;
            ic_vec3 dp;
            if (ic_record_weight(c, i, p, n, s, &w, &dp) && eligible(c, i, q))
                accumulate_record(c, i, n, w, dp, q, out, acc);
        }
    }
    return finish(out, acc);
}

int ic_cache_query_linear(const ic_cache *c, const ic_cache_lookup *q, ic_cache_estimate *out)
{
    float acc[3] = {0.0f, 0.0f, 0.0f};
    memset(out, 0, sizeof *out);
    float s = q->acceptance == IC_ACCEPT_FINAL ? c->params.final_accuracy_scale : 1.0f;
    out->records_tested = c->count;
    for (uint32_t i = 0; i < c->count; ++i) {
        float w;
        ic_vec3 dp;
        if (ic_record_weight(c, i, q->position, q->normal, s, &w, &dp) && eligible(c, i, q))
            accumulate_record(c, i, q->normal, w, dp, q, out, acc);
    }
    return finish(out, acc);
}

int ic_cache_record_weight(const ic_cache *c, uint32_t i, ic_vec3 p, ic_vec3 n, ic_cache_acceptance acceptance,
                           float *weight)
{
    float w = 0.0f, s = acceptance == IC_ACCEPT_FINAL ? c->params.final_accuracy_scale : 1.0f;
    ic_vec3 dp;
    int ok = i < c->count && ic_record_weight(c, i, p, n, s, &w, &dp);
    if (weight)
        *weight = ok ? w : 0.0f;
    return ok;
}

ic_result ic_cache_get_record(const ic_cache *c, uint32_t i, ic_record *out)
{
    if (!c || !out || i >= c->count)
        return IC_ERR_INVALID_ARG;
    const ic_float4 *s = &c->sphere[i], *n = &c->normal[i];
    const ic_record_cold *cd = &c->cold[i];
    memset(out, 0, sizeof *out);
    out->position = v3(s->x, s->y, s->z);
    out->normal = v3(n->x, n->y, n->z);
    out->tangent = cd->tangent;
    out->irradiance = cd->irradiance;
    memcpy(out->grad_rot, cd->grad_rot, sizeof out->grad_rot);
    memcpy(out->grad_trans, cd->grad_trans, sizeof out->grad_trans);
    out->sigma = cd->sigma;
    out->harmonic_mean_dist = cd->harmonic_mean_dist;
    out->radius = s->w;
    out->accuracy = n->w;
    out->pixel_footprint = cd->pixel_footprint;
    out->change_count = cd->change_count;
    out->bounce = cd->bounce;
    out->flags = cd->flags;
    return IC_OK;
}

ic_result ic_cache_set_record_accuracy(ic_cache *c, uint32_t i, float accuracy)
{
    /* Raising a_i would grow the influence sphere past the octree's references: refused. */
    if (!c || i >= c->count || !(accuracy > 0.0f) || accuracy > c->normal[i].w)
        return IC_ERR_INVALID_ARG;
    if (accuracy < c->normal[i].w) {
        c->normal[i].w = accuracy;
        ++c->cold[i].change_count;
        ic_frozen_free(&c->frozen); /* the lists hold copies of a_i */
    }
    return IC_OK;
}

ic_result ic_cache_set_record_flags(ic_cache *c, uint32_t i, uint8_t flags)
{
    if (!c || i >= c->count)
        return IC_ERR_INVALID_ARG;
    if (c->cold[i].flags != flags)
        ic_frozen_free(&c->frozen); /* the lists hold copies of the flags */
    c->cold[i].flags = flags;
    return IC_OK;
}

uint32_t ic_cache_knn(const ic_cache *c, ic_vec3 p, uint32_t k, uint32_t *indices, float *dist2)
{
    if (!c || !indices || k == 0)
        return 0;
    if (dist2) {
        ic_octree_items it = ic_cache_point_items(c);
        return ic_octree_knn(&c->points, &it, p, k, indices, dist2);
    }
    /* The search needs the distances; without a caller buffer use a bounded local one in chunks. */
    float local[256];
    if (k > 256)
        k = 256;
    ic_octree_items it = ic_cache_point_items(c);
    return ic_octree_knn(&c->points, &it, p, k, indices, local);
}

uint32_t ic_cache_radius_query(const ic_cache *c, ic_vec3 p, float radius, uint32_t *indices, uint32_t capacity)
{
    if (!c)
        return 0;
    ic_octree_items it = ic_cache_point_items(c);
    return ic_octree_radius(&c->points, &it, p, radius, indices, capacity);
}
