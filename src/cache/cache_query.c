/*
 * cache_query.c — interpolation from the irradiance cache on its octree and by linear scan, the
 * single look-up entry points, and neighbour queries on the point tree (include/irrcache/cache.h).
 *
 * Interpolation is Křivánek et al. 2006 §3 eq. 1 for irradiance:
 *   E(p) = Σ_{i∈S} w_i(p) E_i(p) / Σ_{i∈S} w_i(p),
 *   E_i(p) = E_i + (n_i × n)·∇r E_i + (p − p_i)·∇t E_i   (per channel, clamped ≥ 0),
 * with Ward's or Tabellion–Lamorlette's weight (cache_store.h: ic_record_weight). The set S comes
 * from a single root-to-leaf descent of the multiple-reference octree (Frolov et al. 2012 §4.3). A
 * frozen cache answers through the frozen layout instead (cache_frozen_query.c).
 */
#include "cache_store.h"

#include <string.h>

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
    /* (n_i × n): the rotation that takes the record's normal to ours (Křivánek et al. 2006 §3). */
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

/* Records of the wrong bounce level or disabled ones are skipped after the weight test: the test only
 * reads the hot arrays, and such records are rare. */
static inline int eligible(const ic_cache *c, uint32_t i, const ic_cache_lookup *q)
{
    const ic_record_cold *cd = &c->cold[i];
    return cd->bounce == q->bounce && !(cd->flags & IC_RECORD_DISABLED);
}

int ic_cache_query(const ic_cache *c, const ic_cache_lookup *q, ic_cache_estimate *out)
{
    return ic_cache_query_hinted(c, q, NULL, out);
}

/* ic_cache_query on the octree (the cache thawed). With a fallback level, its records are summed
 * apart (into their own estimate and contribution buffer) on the same descent, and answer only where
 * the asked level's do not. */
static int query_octree(const ic_cache *c, const ic_cache_lookup *q, ic_cache_estimate *out)
{
    float acc[3] = {0.0f, 0.0f, 0.0f}, acc2[3] = {0.0f, 0.0f, 0.0f};
    memset(out, 0, sizeof *out);
    ic_cache_lookup q2 = *q;
    q2.bounce = q->fallback - 1u;
    q2.contributions = q->contributions ? q->fallback_contributions : NULL;
    ic_cache_estimate e2;
    memset(&e2, 0, sizeof e2);
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
            if (!ic_record_weight(c, i, p, n, s, &w, &dp))
                continue;
            if (eligible(c, i, q))
                accumulate_record(c, i, n, w, dp, q, out, acc);
            else if (q->fallback && eligible(c, i, &q2))
                accumulate_record(c, i, n, w, dp, &q2, &e2, acc2);
        }
    }
    if (out->contributor_count || !e2.contributor_count)
        return ic_estimate_finish(out, acc);
    e2.records_tested = out->records_tested;
    *out = e2;
    if (q->contributions && e2.contributions_written)
        memcpy(q->contributions, q2.contributions, sizeof *q->contributions * e2.contributions_written);
    return ic_estimate_finish(out, acc2);
}

int ic_cache_query_hinted(const ic_cache *c, const ic_cache_lookup *q, ic_cache_hint *hint, ic_cache_estimate *out)
{
    if (!ic_lookup_is_finite(q)) {
        memset(out, 0, sizeof *out);
        return 0;
    }
    if (!c->frozen.is_valid)
        return query_octree(c, q, out);
    /* The frozen layout's lists filter one level: the fallback is a second look-up. */
    if (c->query_frozen(c, q, hint, out) || !q->fallback)
        return out->contributor_count > 0;
    ic_cache_lookup q2 = *q;
    q2.bounce = q->fallback - 1u;
    return c->query_frozen(c, &q2, hint, out);
}

/* ic_cache_query_linear for one level. */
static int query_linear_level(const ic_cache *c, const ic_cache_lookup *q, ic_cache_estimate *out)
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
    return ic_estimate_finish(out, acc);
}

int ic_cache_query_linear(const ic_cache *c, const ic_cache_lookup *q, ic_cache_estimate *out)
{
    if (!ic_lookup_is_finite(q)) {
        memset(out, 0, sizeof *out);
        return 0;
    }
    if (query_linear_level(c, q, out) || !q->fallback)
        return out->contributor_count > 0;
    ic_cache_lookup q2 = *q;
    q2.bounce = q->fallback - 1u;
    return query_linear_level(c, &q2, out);
}

int ic_cache_record_weight(const ic_cache *c, uint32_t i, ic_vec3 p, ic_vec3 n, ic_cache_acceptance acceptance,
                           float *weight)
{
    float w = 0.0f, s = acceptance == IC_ACCEPT_FINAL ? c->params.final_accuracy_scale : 1.0f;
    ic_vec3 dp;
    ic_cache_lookup q = ic_cache_lookup_at(p, n, acceptance);
    int ok = i < c->count && ic_lookup_is_finite(&q) && ic_record_weight(c, i, p, n, s, &w, &dp);
    if (weight)
        *weight = ok ? w : 0.0f;
    return ok;
}

uint32_t ic_cache_knn(const ic_cache *c, ic_vec3 p, uint32_t k, uint32_t *indices, float *dist2)
{
    if (!c || !indices || k == 0 || !isfinite(p.x) || !isfinite(p.y) || !isfinite(p.z))
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
    return ic_octree_radius(&c->points, &it, p, radius, indices, indices ? capacity : 0);
}
