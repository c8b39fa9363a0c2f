/*
 * cache_clamp.c — the radius clamps of the irradiance cache, in the order cache.h documents.
 *
 *   1. gradient-magnitude clamp, Křivánek et al. 2006 §5.1 eq. 2, then R bounds;
 *   2. validity-radius clamp, Frolov et al. 2012 §4.2;
 *   3. gradient-difference scaling, Castaño 2014;
 *   4. neighbor clamping, Křivánek et al. 2006 §5.2.
 *
 * Radii here are R_i (the value in the weights); the influence radius is r_i = a_i·R_i (cache.h).
 * "Within reach" (steps 3, 4): |p_i − p_j| < max(r_i, r_j). Steps 2–4 only ever lower R, and each is
 * deterministic: step 2 writes per-record slots from read-only inputs (so it runs in parallel),
 * step 3 computes every target from the radii before the step and then takes minima, step 4 is a
 * sequential label-correcting pass ordered by (R, index), whose neighbour searches for the new records
 * run in parallel beforehand.
 */
#include "cache_store.h"

#include "core/comm.h"
#include "core/grow.h"
#include "core/threads.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

/* Luminance and the luminance gradient (a linear combination of the channel gradients). */
static float lum3(ic_vec3 e) { return v3_lum(e); }
static ic_vec3 lum_gradient(const ic_vec3 g[3])
{
    return v3_add(v3_add(v3_scale(g[0], 0.2126f), v3_scale(g[1], 0.7152f)), v3_scale(g[2], 0.0722f));
}

float ic_cache_clamp_radius(const ic_cache_params *p, const ic_record *r, float axis)
{
    float R = axis;
    if (p->gradient_clamp == IC_CACHE_ON) {
        /* Křivánek et al. 2006 §5.1 eq. 2 on luminance Y: if |∇t Y|/Y > 1/R then R := Y/|∇t Y|.
         * The split-sphere model bounds the gradient by Y/R; a measured gradient above that bound
         * means the field changes faster than the geometry suggests, so the record must be smaller. */
        float Y = lum3(r->irradiance), g = v3_len(lum_gradient(r->grad_trans));
        if (Y > 0.0f && g * R > Y)
            R = Y / g;
    }
    /* Bounds after the gradient clamp (as Radiance does), so R_min also caps gradient noise. */
    float lo = p->min_radius, hi = p->max_radius;
    if (r->pixel_footprint > 0.0f) {
        if (p->min_radius_pixels > 0.0f)
            lo = fmaxf(lo, p->min_radius_pixels * r->pixel_footprint);
        if (p->max_radius_pixels > 0.0f)
            hi = fminf(hi, p->max_radius_pixels * r->pixel_footprint);
    }
    if (lo > hi)
        lo = hi; /* contradictory world and pixel bounds: the ceiling wins */
    return fminf(fmaxf(R, lo), hi);
}

static float influence(const ic_cache *c, uint32_t i) { return c->normal[i].w * c->sphere[i].w; }

/* Grows an index buffer to hold `need` (doubling; unchanged on failure). */
static ic_result grow_indices(uint32_t **buf, uint32_t *cap, uint32_t need)
{
    size_t n = *cap;
    ic_result r = ic_grow((void **)buf, &n, need, sizeof **buf);
    if (r == IC_OK)
        *cap = n > UINT32_MAX ? UINT32_MAX : (uint32_t)n;
    return r;
}

/* Records j ≠ i of i's bounce level within reach of i, into *buf (grown as needed, capacity *cap). Returns
 * the count; UINT32_MAX when out of memory. Reads the cache only, so threads may call it at once with
 * buffers of their own. */
static uint32_t reach_into(const ic_cache *c, uint32_t i, uint32_t **buf, uint32_t *cap)
{
    const ic_float4 *si = &c->sphere[i];
    ic_vec3 p = v3(si->x, si->y, si->z);
    float ri = influence(c, i), ri2 = ri * ri;
    ic_octree_items pts = ic_cache_point_items(c);
    /* j inside i's sphere: a radius query over positions. */
    uint32_t n = ic_octree_radius(&c->points, &pts, p, ri, *buf, *cap);
    if (n > *cap) {
        if (grow_indices(buf, cap, n) != IC_OK)
            return UINT32_MAX;
        n = ic_octree_radius(&c->points, &pts, p, ri, *buf, *cap);
    }
    /* Drop i itself (distance 0 is inside its own sphere) and records of other bounce levels: levels are
     * separate caches that never interpolate together, so they do not clamp each other either. */
    uint8_t level = c->cold[i].bounce;
    uint32_t m = 0;
    for (uint32_t k = 0; k < n; ++k)
        if ((*buf)[k] != i && c->cold[(*buf)[k]].bounce == level)
            (*buf)[m++] = (*buf)[k];
    /* i inside j's sphere: exactly the records the octree path through p_i references whose sphere
     * holds p_i (the references are conservative: radii only shrink after a record goes in); those
     * already found above are skipped by the complementary distance test. */
    uint32_t path[IC_OCTREE_MAX_DEPTH + 1];
    uint32_t len = ic_octree_path(&c->tree, p.x, p.y, p.z, path);
    for (uint32_t l = 0; l < len; ++l) {
        const ic_octree_node *node = &c->tree.nodes[path[l]];
        for (uint32_t k = 0; k < node->count; ++k) {
            uint32_t j = c->tree.refs[node->begin + k].index;
            if (j == i || c->cold[j].bounce != level)
                continue;
            const ic_float4 *sj = &c->sphere[j];
            float d2 = ic_dist2(p.x, p.y, p.z, sj->x, sj->y, sj->z), rj = influence(c, j);
            if (!(d2 < ri2) && d2 < rj * rj) {
                if (grow_indices(buf, cap, m + 1) != IC_OK)
                    return UINT32_MAX;
                (*buf)[m++] = j;
            }
        }
    }
    return m;
}

uint32_t ic_cache_reach(ic_cache *c, uint32_t i) { return reach_into(c, i, &c->scratch, &c->scratch_cap); }

static float distance(const ic_cache *c, uint32_t i, uint32_t j)
{
    const ic_float4 *a = &c->sphere[i], *b = &c->sphere[j];
    return sqrtf(ic_dist2(a->x, a->y, a->z, b->x, b->y, b->z));
}

/* ---- Step 2: validity-radius clamping (Frolov et al. 2012 §4.2) ------------------------------- */

/* Candidates examined per record: the 8·k nearest. Enough for k distinct directions on any surface
 * patch; a record on the rim of the cached region may find fewer and is then left alone. */
#define VALIDITY_CANDIDATES_PER_K 8
#define VALIDITY_MAX_CANDIDATES (VALIDITY_CANDIDATES_PER_K * 16 + 1)

typedef struct validity_job {
    ic_cache *c;
    uint32_t first;
    uint32_t k;
    float cos_min_angle;
} validity_job;

static void validity_one(void *ctx, int64_t item, int thread)
{
    (void)thread;
    validity_job *job = ctx;
    ic_cache *c = job->c;
    uint32_t i = job->first + (uint32_t)item;
    uint32_t idx[VALIDITY_MAX_CANDIDATES];
    float d2[VALIDITY_MAX_CANDIDATES];
    ic_vec3 dirs[16];
    const ic_float4 *si = &c->sphere[i], *ni = &c->normal[i];
    ic_vec3 p = v3(si->x, si->y, si->z), n = v3(ni->x, ni->y, ni->z);
    ic_octree_items pts = ic_cache_point_items(c);
    /* +1: the record itself is its own nearest neighbour. */
    uint32_t m = ic_octree_knn(&c->points, &pts, p, job->k * VALIDITY_CANDIDATES_PER_K + 1, idx, d2);
    uint32_t taken = 0;
    float farthest2 = 0.0f;
    for (uint32_t q = 0; q < m && taken < job->k; ++q) {
        if (idx[q] == i || !(d2[q] > 0.0f) || c->cold[idx[q]].bounce != c->cold[i].bounce)
            continue; /* itself, a coincident record (no direction), or another bounce level's cache */
        const ic_float4 *sj = &c->sphere[idx[q]];
        ic_vec3 delta = v3(sj->x - p.x, sj->y - p.y, sj->z - p.z);
        /* Direction in the tangent plane; a neighbour straight above keeps its 3-D direction. */
        ic_vec3 v = v3_madd(delta, n, -v3_dot(delta, n));
        if (!(v3_len2(v) > 1e-12f * v3_len2(delta)))
            v = delta;
        v = v3_norm(v);
        int distinct = 1;
        for (uint32_t t = 0; t < taken && distinct; ++t)
            distinct = v3_dot(v, dirs[t]) <= job->cos_min_angle;
        if (distinct) {
            dirs[taken++] = v;
            farthest2 = d2[q];
        }
    }
    if (taken < job->k)
        return;
    /* Clamp the influence radius a_i·R_i to the farthest of the k; R moves with it. */
    float far = sqrtf(farthest2);
    if (ni->w * si->w > far)
        c->sphere[i].w = far / ni->w;
}

ic_result ic_cache_validity_clamp(ic_cache *c, uint32_t first)
{
    uint32_t n = c->count - first;
    /* Several processes (ic_cache_set_comm): a block of the new records each, their radii exchanged. */
    uint64_t block, own;
    ic_comm_block(n, ic_comm_size(c->comm), ic_comm_rank(c->comm), &block, &own);
    validity_job job = {c, first + (uint32_t)block, c->params.validity_k,
                        cosf(c->params.validity_angle_deg * (IC_PI / 180.0f))};
    /* Each item reads positions only and writes its own radius: any thread or process count, same result. */
    ic_result r = IC_OK;
    if (own < 64) {
        for (uint32_t k = 0; k < own; ++k)
            validity_one(&job, k, 0);
    } else {
        r = ic_parallel_for(c->params.threads, (int64_t)own, validity_one, &job);
    }
    if (r != IC_OK || !ic_comm_is_shared(c->comm))
        return r;
    float *radius = malloc(sizeof *radius * (n ? n : 1));
    if (!radius)
        return IC_ERR_OOM;
    for (uint64_t k = block; k < block + own; ++k)
        radius[k] = c->sphere[first + k].w;
    r = ic_comm_allgather_blocks(c->comm, radius, n, sizeof *radius, "exchanging validity radii", NULL);
    for (uint32_t k = 0; r == IC_OK && k < n; ++k)
        c->sphere[first + k].w = radius[k];
    free(radius);
    return r;
}

/* ---- Step 3: gradient-difference scaling (Castaño 2014) --------------------------------------- */

/*
 * Criterion. For records i, j within reach, on the same smooth surface (n_i·n_j ≥ cos 30°), with
 * luminances Y_i, Y_j > 0, luminance gradients g_i, g_j (the translational gradients mixed with the
 * Rec. 709 weights) and d = |p_i − p_j|:
 *     Δ_ij = |g_i − g_j| · d / min(Y_i, Y_j).
 * Δ bounds the sum of the two first-order prediction errors, |E_i + g_i·(p_j−p_i) − E_j| +
 * |E_j + g_j·(p_i−p_j) − E_i| ≥ |(g_i − g_j)·(p_j − p_i)|, relative to the smaller irradiance: a
 * second-order change between the records that neither gradient sees. If Δ_ij > τ
 * (gradient_difference_threshold) both radii are scaled by f = d / (r_i + r_j), so the influence
 * spheres stop overlapping and a later pass places records between them. A record is never taken below
 * 0.25 of the radius it was inserted with (ic_cache_clamp_radius of its harmonic-mean distance), however
 * many neighbours scale it: near-coincident records are not erased, and a record shrunk by each new
 * neighbour in turn (lazy construction with large records: 3,623 records after 300 s where 328 sufficed
 * without the step) cannot fall without end. Targets are computed from the radii before the step and
 * each record keeps the smallest, so the result does not depend on the order of pairs.
 */
#define GRADDIFF_MIN_COS 0.8660254f
#define GRADDIFF_MIN_SCALE 0.25f

/* The radius record i was inserted with: its harmonic-mean distance through the gradient clamp and the
 * bounds, as insertion computed it (ellipses: their major axis, which the sphere holds). */
static float inserted_radius(const ic_cache *c, uint32_t i)
{
    const ic_record_cold *cd = &c->cold[i];
    ic_record r;
    memset(&r, 0, sizeof r);
    r.irradiance = cd->irradiance;
    memcpy(r.grad_trans, cd->grad_trans, sizeof r.grad_trans);
    r.pixel_footprint = cd->pixel_footprint;
    return ic_cache_clamp_radius(&c->params, &r, cd->harmonic_mean_dist);
}

/* Remembers an existing record lowered by step 3: its neighbours may now violate step 4. */
static ic_result note_changed(ic_cache *c, uint32_t r)
{
    if (c->changed_len == c->changed_cap) {
        uint32_t cap = c->changed_cap ? c->changed_cap * 2 : 64;
        uint32_t *v = realloc(c->changed, (size_t)cap * sizeof *v);
        if (!v)
            return IC_ERR_OOM;
        c->changed = v;
        c->changed_cap = cap;
    }
    c->changed[c->changed_len++] = r;
    return IC_OK;
}

/* Lowers R_r to `radius` for steps 3–4. An existing record (r < first) is logged first (c->undo), so
 * a rolled-back insertion can restore it, and counts the change; if the log cannot grow, nothing
 * changes and the step fails. */
static ic_result lower_radius(ic_cache *c, uint32_t r, float radius, uint32_t first)
{
    if (r < first) {
        if (c->undo_len == c->undo_cap) {
            size_t cap = c->undo_cap;
            void *v = c->undo;
            if (ic_grow(&v, &cap, (size_t)c->undo_len + 1, sizeof *c->undo) != IC_OK)
                return IC_ERR_OOM;
            c->undo = v; /* kept even when too large below: the block may have moved */
            if (cap > UINT32_MAX)
                return IC_ERR_OOM;
            c->undo_cap = (uint32_t)cap;
        }
        c->undo[c->undo_len++] = (struct ic_clamp_undo){r, c->cold[r].change_count, c->sphere[r].w, radius};
        ++c->cold[r].change_count;
    }
    c->sphere[r].w = radius;
    return IC_OK;
}

void ic_cache_undo_clamps(ic_cache *c, int undo)
{
    for (uint32_t k = 0; k < c->undo_len; ++k) {
        const struct ic_clamp_undo *u = &c->undo[undo ? c->undo_len - 1 - k : k];
        c->sphere[u->record].w = undo ? u->radius : u->lowered;
        c->cold[u->record].change_count = undo ? u->change_count : u->change_count + 1;
    }
}

typedef struct target {
    uint32_t record;
    float radius;
} target;

ic_result ic_cache_gradient_difference(ic_cache *c, uint32_t first)
{
    target *list = NULL;
    size_t len = 0, cap = 0;
    float tau = c->params.gradient_difference_threshold;
    for (uint32_t i = first; i < c->count; ++i) {
        uint32_t n = ic_cache_reach(c, i);
        if (n == UINT32_MAX) {
            free(list);
            return IC_ERR_OOM;
        }
        const ic_record_cold *ci = &c->cold[i];
        float Yi = lum3(ci->irradiance);
        ic_vec3 gi = lum_gradient(ci->grad_trans);
        for (uint32_t k = 0; k < n; ++k) {
            uint32_t j = c->scratch[k];
            const ic_record_cold *cj = &c->cold[j];
            const ic_float4 *ni = &c->normal[i], *nj = &c->normal[j];
            if (ni->x * nj->x + ni->y * nj->y + ni->z * nj->z < GRADDIFF_MIN_COS)
                continue;
            float Yj = lum3(cj->irradiance), Ymin = fminf(Yi, Yj);
            if (!(Ymin > 0.0f))
                continue;
            float d = distance(c, i, j);
            float delta = v3_len(v3_sub(gi, lum_gradient(cj->grad_trans))) * d / Ymin;
            if (!(delta > tau))
                continue;
            float f = fmaxf(d / (influence(c, i) + influence(c, j)), GRADDIFF_MIN_SCALE);
            if (len + 2 > cap) {
                size_t nc = cap ? cap * 2 : 256;
                target *t = realloc(list, nc * sizeof *t);
                if (!t) {
                    free(list);
                    return IC_ERR_OOM;
                }
                list = t;
                cap = nc;
            }
            list[len++] = (target){i, fmaxf(c->sphere[i].w * f, GRADDIFF_MIN_SCALE * inserted_radius(c, i))};
            list[len++] = (target){j, fmaxf(c->sphere[j].w * f, GRADDIFF_MIN_SCALE * inserted_radius(c, j))};
        }
    }
    ic_result rc = IC_OK;
    for (size_t k = 0; k < len && rc == IC_OK; ++k) {
        uint32_t r = list[k].record;
        if (list[k].radius < c->sphere[r].w) {
            rc = lower_radius(c, r, list[k].radius, first);
            if (rc == IC_OK && r < first)
                rc = note_changed(c, r);
        }
    }
    free(list);
    return rc;
}

/* ---- Step 4: neighbor clamping (Křivánek et al. 2006 §5.2) ------------------------------------ */

/*
 * The paper clamps a new record by its neighbours, R_i := min(R_i, R_j + |p_i − p_j|), then the
 * neighbours by it, R_j := min(R_j, R_i + |p_i − p_j|). Lowering R_j can break the same constraint
 * between j and its own neighbours, so this runs to a fixed point: a label-correcting pass over a
 * min-heap keyed by (R, index). The heap starts with the new records; a popped record first pulls
 * (clamps itself by its neighbours), then pushes (clamps its neighbours, queueing those that
 * changed); existing records lowered by step 3 are seeds too. Radii only decrease, so it terminates, and at
 * the end every pair within reach satisfies |R_i − R_j| ≤ |p_i − p_j| — the triangle-inequality argument of
 * the paper's Fig. 3.
 *
 * The pass itself is sequential (who is within reach depends on the radii it lowers, so its result
 * depends on its order), but finding neighbours, its costly part, is not: since radii only shrink, the
 * records within reach of a new record when it is popped are among those within reach when the step
 * begins. Those lists are found first, in parallel (on the cache's threads; with several processes a
 * block of new records each, the lists exchanged), and the pass keeps the entries still within reach.
 * The result is the sequential pass's, bit for bit. An existing record lowered on the way searches the
 * octrees when popped, as before.
 */
typedef struct reach_lists {
    const ic_cache *c;
    uint32_t first;        /* list k is record first + k's */
    uint64_t *at;          /* per list of this block: (thread << 40) | offset in that thread's arena */
    uint32_t *len;         /* per list of this block: its length */
    uint32_t **arena;      /* per thread */
    uint32_t *arena_len, *arena_cap;
    uint32_t **buf;        /* per thread: one record's list as it is found */
    uint32_t *buf_cap;
    atomic_int failed;
} reach_lists;

static void find_list(void *ctx, int64_t item, int thread)
{
    reach_lists *L = ctx;
    uint32_t n = reach_into(L->c, L->first + (uint32_t)item, &L->buf[thread], &L->buf_cap[thread]);
    L->at[item] = ((uint64_t)thread << 40) | L->arena_len[thread];
    L->len[item] = 0;
    if (n == 0)
        return; /* nothing to copy (the arena may not exist yet) */
    if (n == UINT32_MAX || n > UINT32_MAX - L->arena_len[thread] ||
        grow_indices(&L->arena[thread], &L->arena_cap[thread], L->arena_len[thread] + n) != IC_OK) {
        atomic_store(&L->failed, 1);
        return;
    }
    memcpy(L->arena[thread] + L->arena_len[thread], L->buf[thread], sizeof *L->buf[thread] * n);
    L->len[item] = n;
    L->arena_len[thread] += n;
}

/* Neighbour lists as several processes exchange them: each entry as the difference from the one before it
 * (the first from the record's own index), zigzag-coded and written 7 bits a byte, low first, the high bit
 * saying that more follow. Neighbours lie near in space and records were made in passes of nearby
 * candidates, so most differences take one or two bytes: on Sponza 43 % of the four bytes an index takes. */
static size_t pack_index(uint8_t *out, uint32_t prev, uint32_t v)
{
    int64_t d = (int64_t)v - (int64_t)prev;
    uint64_t z = d < 0 ? ((uint64_t)(-(d + 1)) << 1) | 1u : (uint64_t)d << 1;
    size_t k = 0;
    while (z >= 0x80u) {
        out[k++] = (uint8_t)(z | 0x80u);
        z >>= 7;
    }
    out[k++] = (uint8_t)z;
    return k;
}

/* The entry after prev packed at in[*at, end); 0 if the bytes end inside it, it takes more than the five
 * groups any entry needs (a difference of 33 bits at most, so that prev + d cannot overflow) or it is out of
 * range. */
static int unpack_index(const uint8_t *in, size_t end, size_t *at, uint32_t prev, uint32_t *v)
{
    uint64_t z = 0;
    for (int shift = 0; shift < 35 && *at < end; shift += 7) {
        uint8_t b = in[(*at)++];
        z |= (uint64_t)(b & 0x7fu) << shift;
        if (!(b & 0x80u)) {
            int64_t d = z & 1u ? -(int64_t)(z >> 1) - 1 : (int64_t)(z >> 1);
            int64_t x = (int64_t)prev + d;
            if (x < 0 || x > (int64_t)UINT32_MAX)
                return 0;
            *v = (uint32_t)x;
            return 1;
        }
    }
    return 0;
}

/* This process's block of lists (records first + block + k, k < own; their entries in L's arenas) packed into
 * *packed, then every process's lengths and packed size exchanged: L->len gets every record's length and
 * (*packed_bytes)[q] process q's packed size. */
static ic_result exchange_lengths(ic_comm *comm, const struct reach_lists *L, uint32_t n, uint32_t first,
                                  uint64_t block, uint64_t own, uint8_t **packed, uint64_t **packed_bytes)
{
    const int ranks = comm->size;
    uint64_t entries = 0;
    for (uint64_t k = 0; k < own; ++k)
        entries += L->len[block + k];
    /* the block's lengths, then its packed size (two words): each process's part of head */
    uint32_t *head = malloc(sizeof *head * ((size_t)n + 2 * (size_t)ranks));
    uint64_t *bytes = malloc(sizeof *bytes * (size_t)ranks);
    *packed = malloc(entries * 5 + 1);
    *packed_bytes = malloc(sizeof **packed_bytes * (size_t)ranks);
    ic_result r = head && bytes && *packed && *packed_bytes ? IC_OK : IC_ERR_OOM;
    size_t size = 0;
    for (uint64_t k = 0; r == IC_OK && k < own; ++k) {
        const uint64_t at = L->at[k];
        const uint32_t *list = L->arena[at >> 40] + (at & ((1ull << 40) - 1));
        uint32_t prev = first + (uint32_t)(block + k);
        for (uint32_t e = 0; e < L->len[block + k]; ++e) {
            size += pack_index(*packed + size, prev, list[e]);
            prev = list[e];
        }
    }
    uint64_t at = 0;
    for (int q = 0; r == IC_OK && q < ranks; ++q) {
        uint64_t b0, bn;
        ic_comm_block(n, ranks, q, &b0, &bn);
        bytes[q] = sizeof *head * (bn + 2);
        if (q == comm->rank) {
            memcpy(head + at, L->len + block, sizeof *head * own);
            head[at + own] = (uint32_t)size;
            head[at + own + 1] = (uint32_t)((uint64_t)size >> 32);
        }
        at += bn + 2;
    }
    if (r == IC_OK)
        r = ic_comm_allgather_sized(comm, head, bytes, "exchanging neighbour counts", NULL);
    at = 0;
    for (int q = 0; r == IC_OK && q < ranks; ++q) {
        uint64_t b0, bn;
        ic_comm_block(n, ranks, q, &b0, &bn);
        memcpy(L->len + b0, head + at, sizeof *head * bn);
        (*packed_bytes)[q] = head[at + bn] | (uint64_t)head[at + bn + 1] << 32;
        at += bn + 2;
    }
    free(head);
    free(bytes);
    return r;
}

/* Every process's packed block (this one's in packed), exchanged and unpacked into index at offset (this
 * process's own lists are in place already). */
static ic_result exchange_lists(ic_comm *comm, const uint8_t *packed, const uint64_t *packed_bytes, uint32_t n,
                                uint32_t first, const uint32_t *len, const uint32_t *offset, uint32_t *index)
{
    const int ranks = comm->size;
    uint64_t all = 0, mine = 0;
    for (int q = 0; q < ranks; ++q) {
        mine += q < comm->rank ? packed_bytes[q] : 0;
        all += packed_bytes[q];
    }
    uint8_t *buf = malloc(all ? all : 1);
    if (!buf)
        return IC_ERR_OOM;
    memcpy(buf + mine, packed, packed_bytes[comm->rank]);
    ic_result r = ic_comm_allgather_sized(comm, buf, packed_bytes, "exchanging neighbour lists", NULL);
    size_t at = 0;
    for (int q = 0; r == IC_OK && q < ranks; ++q) {
        uint64_t b0, bn;
        ic_comm_block(n, ranks, q, &b0, &bn);
        const size_t end = at + packed_bytes[q];
        for (uint64_t k = b0; r == IC_OK && q != comm->rank && k < b0 + bn; ++k) {
            uint32_t prev = first + (uint32_t)k, *out = index + offset[k];
            for (uint32_t e = 0; e < len[k]; ++e) {
                if (!unpack_index(buf, end, &at, prev, &out[e])) {
                    r = IC_ERR_IO; /* a block that does not hold its lists: the transport damaged it */
                    break;
                }
                prev = out[e];
            }
        }
        if (r == IC_OK && q != comm->rank && at != end)
            r = IC_ERR_IO;
        at = end;
    }
    free(buf);
    return r;
}

/* The lists of records [first, first + n) under the current radii, into *offset (n + 1 entries) and *index,
 * in record order; a block each with several processes, exchanged. */
static ic_result find_lists(ic_cache *c, uint32_t first, uint32_t n, uint32_t **offset, uint32_t **index)
{
    int threads = ic_resolve_threads(c->params.threads);
    uint64_t block, own;
    ic_comm_block(n, ic_comm_size(c->comm), ic_comm_rank(c->comm), &block, &own);
    reach_lists L = {c, first + (uint32_t)block, NULL, NULL, NULL, NULL, NULL, NULL, NULL, 0};
    L.at = malloc(sizeof *L.at * (own ? own : 1));
    L.len = calloc(n ? n : 1, sizeof *L.len);
    L.arena = calloc((size_t)threads, sizeof *L.arena);
    L.arena_len = calloc((size_t)threads, sizeof *L.arena_len);
    L.arena_cap = calloc((size_t)threads, sizeof *L.arena_cap);
    L.buf = calloc((size_t)threads, sizeof *L.buf);
    L.buf_cap = calloc((size_t)threads, sizeof *L.buf_cap);
    *offset = malloc(sizeof **offset * ((size_t)n + 1));
    *index = NULL;
    ic_result r = L.at && L.len && L.arena && L.arena_len && L.arena_cap && L.buf && L.buf_cap && *offset ? IC_OK
                                                                                                 : IC_ERR_OOM;
    atomic_init(&L.failed, 0);
    /* This block's lengths at their place in the lengths of all, for the exchange. */
    uint32_t *all_len = L.len;
    if (all_len)
        L.len = all_len + block;
    /* On the threads; on the calling thread alone for a small batch or where threads cannot start (then
     * nothing ran). */
    if (r == IC_OK && (own < 64 || ic_parallel_for(threads, (int64_t)own, find_list, &L) != IC_OK))
        for (uint64_t k = 0; k < own; ++k)
            find_list(&L, (int64_t)k, 0);
    L.len = all_len;
    if (r == IC_OK && atomic_load(&L.failed))
        r = IC_ERR_OOM;
    /* Several processes: this block's lists packed (pack_lists), their lengths and packed size exchanged */
    uint8_t *packed = NULL;
    uint64_t *packed_bytes = NULL;
    if (r == IC_OK && ic_comm_is_shared(c->comm))
        r = exchange_lengths(c->comm, &L, n, first, block, own, &packed, &packed_bytes);
    uint64_t total = 0;
    for (uint32_t k = 0; r == IC_OK && k < n; ++k) {
        (*offset)[k] = (uint32_t)total;
        total += L.len[k];
    }
    if (r == IC_OK && total >= UINT32_MAX)
        r = IC_ERR_OOM;
    if (r == IC_OK) {
        (*offset)[n] = (uint32_t)total;
        *index = malloc(sizeof **index * (total ? total : 1));
        r = *index ? IC_OK : IC_ERR_OOM;
    }
    for (uint64_t k = 0; r == IC_OK && k < own; ++k) {
        uint64_t at = L.at[k];
        if (L.len[block + k] > 0)
            memcpy(*index + (*offset)[block + k], L.arena[at >> 40] + (at & ((1ull << 40) - 1)),
                   sizeof **index * L.len[block + k]);
    }
    if (r == IC_OK && ic_comm_is_shared(c->comm))
        r = exchange_lists(c->comm, packed, packed_bytes, n, first, L.len, *offset, *index);
    free(packed);
    free(packed_bytes);
    for (int t = 0; L.arena && t < threads; ++t)
        free(L.arena[t]);
    for (int t = 0; L.buf && t < threads; ++t)
        free(L.buf[t]);
    free(L.at);
    free(L.len);
    free(L.arena);
    free(L.arena_len);
    free(L.arena_cap);
    free(L.buf);
    free(L.buf_cap);
    if (r != IC_OK) {
        free(*offset);
        free(*index);
        *offset = *index = NULL;
    }
    return r;
}

typedef struct heap_entry {
    float radius;
    uint32_t record;
} heap_entry;

static int heap_less(heap_entry a, heap_entry b)
{
    return a.radius < b.radius || (a.radius == b.radius && a.record < b.record);
}

typedef struct heap {
    heap_entry *v;
    size_t len, cap;
} heap;

static int heap_push(heap *h, heap_entry e)
{
    if (h->len == h->cap) {
        size_t nc = h->cap ? h->cap * 2 : 256;
        heap_entry *v = realloc(h->v, nc * sizeof *v);
        if (!v)
            return 0;
        h->v = v;
        h->cap = nc;
    }
    size_t k = h->len++;
    while (k > 0 && heap_less(e, h->v[(k - 1) / 2])) {
        h->v[k] = h->v[(k - 1) / 2];
        k = (k - 1) / 2;
    }
    h->v[k] = e;
    return 1;
}

static heap_entry heap_pop(heap *h)
{
    heap_entry top = h->v[0], last = h->v[--h->len];
    size_t k = 0;
    for (;;) {
        size_t l = 2 * k + 1, m = k;
        heap_entry best = last;
        if (l < h->len && heap_less(h->v[l], best)) {
            m = l;
            best = h->v[l];
        }
        if (l + 1 < h->len && heap_less(h->v[l + 1], best))
            m = l + 1;
        if (m == k)
            break;
        h->v[k] = h->v[m];
        k = m;
    }
    if (h->len)
        h->v[k] = last;
    return top;
}

/* The entries of list (found under radii no smaller than now) within reach of i now, into c->scratch: the
 * tests of reach_into on the current radii, so the set is exactly the one it would find. UINT32_MAX when out
 * of memory. */
static uint32_t still_within_reach(ic_cache *c, uint32_t i, const uint32_t *list, uint32_t len)
{
    if (grow_indices(&c->scratch, &c->scratch_cap, len) != IC_OK)
        return UINT32_MAX;
    const ic_float4 *si = &c->sphere[i];
    float ri = influence(c, i), ri2 = ri * ri;
    uint32_t m = 0;
    for (uint32_t k = 0; k < len; ++k) {
        const ic_float4 *sj = &c->sphere[list[k]];
        float d2 = ic_dist2(si->x, si->y, si->z, sj->x, sj->y, sj->z), rj = influence(c, list[k]);
        if (d2 < ri2 || d2 < rj * rj)
            c->scratch[m++] = list[k];
    }
    return m;
}

ic_result ic_cache_neighbor_clamp(ic_cache *c, uint32_t first)
{
    uint32_t *offset = NULL, *index = NULL;
    ic_result rc = find_lists(c, first, c->count - first, &offset, &index);
    heap h = {NULL, 0, 0};
    /* Seeds: the new records, and existing ones that step 3 lowered. */
    for (uint32_t i = first; i < c->count && rc == IC_OK; ++i)
        if (!heap_push(&h, (heap_entry){c->sphere[i].w, i}))
            rc = IC_ERR_OOM;
    for (uint32_t k = 0; k < c->changed_len && rc == IC_OK; ++k)
        if (!heap_push(&h, (heap_entry){c->sphere[c->changed[k]].w, c->changed[k]}))
            rc = IC_ERR_OOM;
    while (rc == IC_OK && h.len > 0) {
        heap_entry e = heap_pop(&h);
        uint32_t i = e.record;
        if (e.radius != c->sphere[i].w)
            continue; /* stale: i was lowered and queued again */
        uint32_t n = i >= first ? still_within_reach(c, i, index + offset[i - first],
                                                     offset[i - first + 1] - offset[i - first])
                                : ic_cache_reach(c, i);
        if (n == UINT32_MAX) {
            rc = IC_ERR_OOM;
            break;
        }
        /* Pull: R_i := min(R_i, R_j + d_ij). */
        float Ri = c->sphere[i].w;
        for (uint32_t k = 0; k < n; ++k) {
            uint32_t j = c->scratch[k];
            float bound = c->sphere[j].w + distance(c, i, j);
            Ri = bound < Ri ? bound : Ri;
        }
        if (Ri < c->sphere[i].w)
            rc = lower_radius(c, i, Ri, first);
        /* Push: R_j := min(R_j, R_i + d_ij), queueing every record that changed. */
        for (uint32_t k = 0; k < n && rc == IC_OK; ++k) {
            uint32_t j = c->scratch[k];
            float bound = Ri + distance(c, i, j);
            if (bound < c->sphere[j].w) {
                rc = lower_radius(c, j, bound, first);
                if (rc == IC_OK && !heap_push(&h, (heap_entry){bound, j}))
                    rc = IC_ERR_OOM;
            }
        }
    }
    free(h.v);
    free(offset);
    free(index);
    return rc;
}
