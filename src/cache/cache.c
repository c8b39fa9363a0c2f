/*
 * cache.c — the irradiance cache's parameters and record store: creation, insertion, index rebuilds,
 * freezing and thawing, and record access (include/irrcache/cache.h).
 *
 * Insertion (one record or a batch) runs the clamp steps of cache.h in a fixed order; records keep
 * the caller's order as their indices, and every parallel step writes per-record slots only, so the
 * cache never depends on the thread count. Look-ups: cache_query.c (octree, linear scan) and
 * cache_frozen_query.c (the frozen layout).
 */
#include "cache_store.h"

#include "irrcache/defaults.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Castaño's gradient-difference τ at the default accuracy (cache_clamp.c, step 3). */
#define GRADIENT_DIFFERENCE_THRESHOLD 0.1f

ic_result ic_cache_params_resolve(const ic_cache_params *in, ic_cache_params *out, ic_error *err)
{
    ic_cache_params p;
    if (in)
        p = *in;
    else
        memset(&p, 0, sizeof p);
    if (p.weight != IC_WEIGHT_WARD && p.weight != IC_WEIGHT_TABELLION && p.weight != IC_WEIGHT_ERROR)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: unknown weight kind %d; use IC_WEIGHT_WARD, "
                            "IC_WEIGHT_TABELLION or IC_WEIGHT_ERROR", (int)p.weight);
    if (p.accuracy == 0.0f)
        p.accuracy = p.weight == IC_WEIGHT_TABELLION ? IC_DEFAULT_ACCURACY_TL : IC_DEFAULT_ACCURACY_WARD;
    if (p.final_accuracy_scale == 0.0f)
        p.final_accuracy_scale = IC_DEFAULT_FINAL_ACCURACY_SCALE;
    if (p.behind_tolerance == 0.0f)
        p.behind_tolerance = 0.05f;
    if (p.max_radius == 0.0f)
        p.max_radius = INFINITY;
    if (p.validity_k == 0)
        p.validity_k = 6;
    if (p.validity_angle_deg == 0.0f)
        p.validity_angle_deg = 30.0f;
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
    if (p.gradient_difference_threshold == 0.0f) {
        /* In proportion to the accuracy (T–L's a read on Ward's scale, so that either default gives 0.1):
         * Δ is a relative error between two records' first-order predictions, the kind of error a bounds.
         * A fixed τ turned a looser accuracy into more records, not fewer: larger records meet farther
         * neighbours, Δ grows with the distance, and every pass's records shrank their neighbours again
         * (the Cornell box at a = 1: 22,486 records in 31 passes against 9,520 at a = 0.15). Unused with
         * the scaling off, where it stays 0.1, as cache files made then keep it. */
        float a = p.weight == IC_WEIGHT_TABELLION ? p.accuracy * (IC_DEFAULT_ACCURACY_WARD / IC_DEFAULT_ACCURACY_TL)
                                                  : p.accuracy;
        p.gradient_difference_threshold =
            GRADIENT_DIFFERENCE_THRESHOLD * (p.gradient_difference == IC_CACHE_ON ? a / IC_DEFAULT_ACCURACY_WARD : 1.0f);
    }

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
    if (p.threads < 0 || p.threads > IC_MAX_THREADS)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: threads %d must be in 0…%d", p.threads, IC_MAX_THREADS);
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
    c->tree.threads = c->points.threads = p.threads;
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
    free(c->squeeze);
    free(c->cold);
    free(c->scratch);
    free(c->changed);
    free(c->undo);
    ic_cache_payload_free(c);
    free(c);
}

const ic_cache_params *ic_cache_get_params(const ic_cache *c) { return c ? &c->params : NULL; }
uint32_t ic_cache_count(const ic_cache *c) { return c ? c->count : 0; }
void ic_cache_set_comm(ic_cache *c, ic_comm *comm)
{
    if (c)
        c->comm = comm;
}
size_t ic_cache_bytes_per_record(void) { return 3 * sizeof(ic_float4) + sizeof(ic_record_cold); }
uint32_t ic_cache_ellipse_count(const ic_cache *c) { return c ? c->ellipse_count : 0; }

size_t ic_cache_memory_bytes(const ic_cache *c)
{
    if (!c)
        return 0;
    return sizeof *c + (size_t)c->cap * ic_cache_bytes_per_record() + ic_octree_bytes(&c->tree) +
           ic_octree_bytes(&c->points) + (size_t)c->scratch_cap * sizeof(uint32_t) + ic_frozen_bytes(&c->frozen) +
           ic_cache_payload_bytes(c);
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
    if (!out)
        return;
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
    ic_float4 *sq = realloc(c->squeeze, (size_t)cap * sizeof *sq);
    if (!sq)
        return IC_ERR_OOM;
    c->squeeze = sq;
    ic_record_cold *cd = realloc(c->cold, (size_t)cap * sizeof *cd);
    if (!cd)
        return IC_ERR_OOM;
    c->cold = cd;
    c->cap = cap;
    return IC_OK;
}

static int vec_finite(ic_vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

/* a_i of a record being inserted: its own, or params.accuracy for 0. */
static float insert_accuracy(const ic_cache *c, const ic_record *r)
{
    return r->accuracy > 0.0f ? r->accuracy : c->params.accuracy;
}

/* Checks record k of a batch; writes its step-1 radius to *radius and its ellipse ratio after step 1
 * to *rho (1: round). */
static ic_result check_record(const ic_cache *c, const ic_record *r, uint32_t k, float *radius, float *rho,
                              ic_error *err)
{
    int ok = vec_finite(r->position) && vec_finite(r->normal) && v3_len2(r->normal) > 0.0f &&
             vec_finite(r->irradiance) && vec_finite(r->tangent) && vec_finite(r->sigma) &&
             vec_finite(r->ellipse_axis);
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
    if (!(r->ellipse_ratio >= 0.0f && r->ellipse_ratio <= 1.0f))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: record %u of the batch has ellipse ratio %g; it must "
                            "be in (0, 1], or 0 for a round record", k, (double)r->ellipse_ratio);
    *radius = ic_cache_clamp_radius(&c->params, r, r->harmonic_mean_dist);
    if (!(*radius > 0.0f && isfinite(*radius)))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: record %u of the batch has an infinite radius; "
                            "cap ray misses in the gatherer or set max_radius", k);
    /* The octree's radius, as ic_octree_item_radius computes it once stored. */
    ic_float4 s = {r->position.x, r->position.y, r->position.z, *radius};
    float reach = *radius * insert_accuracy(c, r) * c->tree_scale * IC_OCTREE_RADIUS_MARGIN;
    if (!ic_cache_sphere_in_range(&s, reach))
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: record %u of the batch at (%g, %g, %g) with radius %g "
                            "reaches beyond %g, the largest coordinate a cache holds; move the scene nearer the "
                            "origin or set max_radius", k, (double)s.x, (double)s.y, (double)s.z, (double)*radius,
                            IC_CACHE_MAX_COORD);
    *rho = 1.0f;
    if (r->ellipse_ratio > 0.0f && r->ellipse_ratio < 1.0f) {
        /* Step 1 bounds both semi-axes alike (cache.h: ELLIPTICAL RECORDS). */
        ic_vec3 n = v3_norm(r->normal), u = r->ellipse_axis;
        u = v3_sub(u, v3_scale(n, v3_dot(u, n)));
        if (!(v3_len2(u) > 1e-12f))
            return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: record %u of the batch is elliptical but its "
                                "ellipse axis is zero or along the normal", k);
        float minor = ic_cache_clamp_radius(&c->params, r, r->harmonic_mean_dist * r->ellipse_ratio);
        /* Floored so that 1/ρ² (ic_squeeze_of) stays finite: else k = inf, 0·inf = NaN in the weight,
         * and the record would never contribute nor load from its file. */
        *rho = fmaxf(fminf(minor / *radius, 1.0f), IC_CACHE_MIN_ELLIPSE_RATIO);
    }
    return IC_OK;
}

static void store_record(ic_cache *c, uint32_t i, const ic_record *r, float radius, float rho)
{
    ic_vec3 n = v3_norm(r->normal);
    float a = insert_accuracy(c, r);
    c->sphere[i] = (ic_float4){r->position.x, r->position.y, r->position.z, radius};
    c->normal[i] = (ic_float4){n.x, n.y, n.z, a};
    ic_vec3 u = rho < 1.0f ? v3_norm(v3_sub(r->ellipse_axis, v3_scale(n, v3_dot(r->ellipse_axis, n)))) : v3(0, 0, 0);
    c->squeeze[i] = ic_squeeze_of(u, rho);
    c->ellipse_count += rho < 1.0f;
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

/* Undo a failed insertion (out of memory half-way): drop the new records, restore the existing ones
 * that steps 3–4 lowered and rebuild both trees; a build that fails too leaves its tree as it was, so
 * the references to the dropped records go first. The tree's references must cover the radii: if it
 * was built from the lowered ones (tree_lowered) and cannot be built again, the lowerings are redone.
 * Returns 0 in that case, else 1. */
static int roll_back(ic_cache *c, uint32_t first, int tree_lowered)
{
    for (uint32_t i = first; i < c->count; ++i)
        c->ellipse_count -= c->squeeze[i].w < 1.0f;
    c->count = first;
    ic_cache_payload_truncate(c, first);
    ic_octree_drop_from(&c->points, first);
    ic_octree_drop_from(&c->tree, first);
    ic_cache_undo_clamps(c, 1);
    ic_octree_items pts = ic_cache_point_items(c), sph = ic_cache_tree_items(c);
    ic_octree_build(&c->points, &pts, first);
    if (ic_octree_build(&c->tree, &sph, first) != IC_OK && tree_lowered) {
        ic_cache_undo_clamps(c, 0);
        return 0;
    }
    return 1;
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
    uint32_t ellipses = c->ellipse_count;
    for (uint32_t k = 0; k < n; ++k) {
        float radius = 0.0f, rho = 1.0f;
        ic_result rc = check_record(c, &recs[k], k, &radius, &rho, err);
        if (rc != IC_OK) {
            c->ellipse_count = ellipses;
            return rc;
        }
        store_record(c, first + k, &recs[k], radius, rho);
    }
    c->count = first + n;

    ic_octree_items pts = ic_cache_point_items(c), sph = ic_cache_tree_items(c);
    ic_result rc = IC_OK;
    c->changed_len = 0;
    c->undo_len = 0;
    /* A large batch (deterministic rule) rebuilds both trees, on the threads, instead of inserting
     * into them one record at a time: the clamps ask the trees for sets of records (nearest, within
     * reach), which do not depend on the tree's shape. */
    const int large = n > 1 && (uint64_t)n * 8 >= c->count;
    if (large)
        rc = ic_octree_build(&c->points, &pts, c->count);
    else
        for (uint32_t k = 0; k < n && rc == IC_OK; ++k)
            rc = ic_octree_insert(&c->points, &pts, first + k);
    if (rc == IC_OK && c->params.validity_clamp == IC_CACHE_ON)
        rc = ic_cache_validity_clamp(c, first);
    /* Steps 3 and 4 find "records whose sphere holds p_i" in the sphere octree, so the new records
     * go in now, with their radii after step 2; later shrinking leaves their references
     * conservative, never wrong. */
    if (rc == IC_OK && large)
        rc = ic_octree_build(&c->tree, &sph, c->count);
    else
        for (uint32_t k = 0; k < n && rc == IC_OK; ++k)
            rc = ic_octree_insert(&c->tree, &sph, first + k);
    if (rc == IC_OK && c->params.gradient_difference == IC_CACHE_ON)
        rc = ic_cache_gradient_difference(c, first);
    if (rc == IC_OK && c->params.neighbor_clamp == IC_CACHE_ON)
        rc = ic_cache_neighbor_clamp(c, first);
    /* After a large batch the sphere octree is built again to fit the final radii; small ones only
     * compact dead reference segments. */
    int tree_lowered = 0; /* the tree's references were made from the radii steps 3–4 left */
    if (rc == IC_OK && large) {
        rc = ic_octree_build(&c->tree, &sph, c->count);
        tree_lowered = rc == IC_OK;
    }
    if (rc == IC_OK)
        rc = ic_octree_compact(&c->tree);
    if (rc == IC_OK)
        rc = ic_octree_compact(&c->points);
    if (rc != IC_OK) {
        const char *kept = roll_back(c, first, tree_lowered)
                               ? ""
                               : " (the existing records keep the radii the clamps lowered: the octree could not "
                                 "be built again)";
        if (rc == IC_ERR_INVALID_ARG) /* the octree's bounds overflow float (check_record prevents it) */
            return ic_error_set(err, rc, "cache: inserting %u records failed: the octree's bounds overflow; "
                                "they were dropped%s", n, kept);
        if (rc != IC_ERR_OOM) /* the clamps' exchanges between processes (c->comm) */
            return ic_error_set(err, rc, "cache: inserting %u records failed (%s) while the processes shared their "
                                "clamps; they were dropped%s", n, ic_result_name(rc), kept);
        return ic_error_set(err, rc, "cache: out of memory inserting %u records; they were dropped%s", n, kept);
    }
    return IC_OK;
}

ic_result ic_cache_insert(ic_cache *c, const ic_record *record, uint32_t *out_index, ic_error *err)
{
    /* One record or an error: a NULL record is not an empty batch (its index would name no record). */
    return insert_records(c, record, 1, out_index, err);
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
        return ic_error_set(err, rc, rc == IC_ERR_OOM ? "cache: out of memory rebuilding the octree"
                                                      : "cache: the octree's bounds overflow (records too far out)");
    return c->params.freeze == IC_CACHE_ON ? ic_cache_freeze(c, err) : IC_OK;
}

ic_result ic_cache_freeze(ic_cache *c, ic_error *err)
{
    if (!c)
        return ic_error_set(err, IC_ERR_INVALID_ARG, "cache: no cache");
    if (ic_frozen_build(c) != IC_OK)
        return ic_error_set(err, IC_ERR_OOM, "cache: out of memory freezing the look-up layout (the cache "
                            "stays usable through its octree)");
    ic_cache_select_frozen_query(c);
    return IC_OK;
}

void ic_cache_thaw(ic_cache *c)
{
    if (c)
        ic_frozen_free(&c->frozen);
}

int ic_cache_is_frozen(const ic_cache *c) { return c && c->frozen.is_valid; }

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
    const ic_float4 *e = &c->squeeze[i];
    if (e->w < 1.0f) {
        out->ellipse_axis = v3_norm(v3(e->x, e->y, e->z));
        out->ellipse_ratio = e->w;
    }
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

ic_result ic_cache_set_record_value(ic_cache *c, uint32_t i, ic_vec3 irradiance, const ic_vec3 grad_rot[3],
                                    const ic_vec3 grad_trans[3], ic_vec3 sigma)
{
    if (!c || i >= c->count || !grad_rot || !grad_trans || !vec_finite(irradiance) || !vec_finite(sigma) ||
        irradiance.x < 0.0f || irradiance.y < 0.0f || irradiance.z < 0.0f)
        return IC_ERR_INVALID_ARG;
    for (int k = 0; k < 3; ++k)
        if (!vec_finite(grad_rot[k]) || !vec_finite(grad_trans[k]))
            return IC_ERR_INVALID_ARG;
    ic_record_cold *cd = &c->cold[i];
    cd->irradiance = irradiance;
    memcpy(cd->grad_rot, grad_rot, sizeof cd->grad_rot);
    memcpy(cd->grad_trans, grad_trans, sizeof cd->grad_trans);
    cd->sigma = sigma;
    ic_frozen_free(&c->frozen); /* the lists hold copies of the values */
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
