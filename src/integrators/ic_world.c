/* ic_world.c — Morton sort, bounding-box clustering, distinct-normal selection (Frolov et al. 2012 §3.1.3). */
#include "ic_world.h"

#include "core/comm.h"
#include "core/morton.h"
#include "core/select.h"
#include "core/vecmath.h"

#include <stdlib.h>
#include <string.h>

uint32_t ic_morton3(ic_vec3 p, ic_vec3 lo, ic_vec3 hi)
{
    float c[3] = {p.x, p.y, p.z}, l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
    uint32_t q[3];
    for (int i = 0; i < 3; ++i) {
        float ext = h[i] - l[i];
        float t = ext > 0.0f ? (c[i] - l[i]) / ext : 0.0f;
        q[i] = (uint32_t)(ic_clampf(t, 0.0f, 1.0f) * 1023.0f);
    }
    return ic_morton3_cells(q[0], q[1], q[2]);
}

/* Sorts the candidates by (Morton code, key) ascending: three stable radix sorts of their indices
 * (ic_sort_key_index), by the key's low word, its high word, then the Morton code, least significant
 * first. The order is total for distinct keys, so it is the one a comparison sort gives. */
int ic_world_sort(ic_candidate *cand, uint32_t count, ic_vec3 lo, ic_vec3 hi)
{
    if (count < 2)
        return 1;
    ic_key_index *order = malloc(sizeof *order * count), *spare = malloc(sizeof *spare * count);
    ic_candidate *copy = malloc(sizeof *copy * count);
    if (!order || !spare || !copy) {
        free(order);
        free(spare);
        free(copy);
        return 0;
    }
    for (uint32_t i = 0; i < count; ++i)
        order[i] = (ic_key_index){(uint32_t)cand[i].key, i};
    ic_key_index *by = ic_sort_key_index(order, spare, count);
    for (int pass = 1; pass < 3; ++pass) {
        for (uint32_t i = 0; i < count; ++i) {
            const ic_candidate *k = &cand[by[i].index];
            by[i].key = pass == 1 ? (uint32_t)(k->key >> 32) : ic_morton3(k->p, lo, hi);
        }
        by = ic_sort_key_index(by, by == order ? spare : order, count);
    }
    memcpy(copy, cand, sizeof *copy * count);
    for (uint32_t i = 0; i < count; ++i)
        cand[i] = copy[by[i].index];
    free(order);
    free(spare);
    free(copy);
    return 1;
}

/* The box of a and b computed as ic_world_cluster computes a cluster's: a cluster holding both has a box at
 * least as large in every axis, and rounding is monotone, so its diagonal is at least this one. */
int ic_world_gap(ic_vec3 a, ic_vec3 b, float max_box)
{
    return v3_len(v3_sub(v3_max(a, b), v3_min(a, b))) > max_box;
}

uint32_t ic_world_cluster(ic_candidate *sorted, uint32_t count, float max_box, int per_cluster, float normal_angle_deg)
{
    const float cos_limit = cosf(normal_angle_deg * IC_PI / 180.0f);
    uint32_t kept = 0, start = 0;
    while (start < count) {
        /* Grow the cluster while its bounding box diagonal stays within max_box. */
        ic_vec3 bmin = sorted[start].p, bmax = sorted[start].p;
        uint32_t end = start + 1;
        while (end < count) {
            ic_vec3 nmin = v3_min(bmin, sorted[end].p), nmax = v3_max(bmax, sorted[end].p);
            if (v3_len(v3_sub(nmax, nmin)) > max_box)
                break;
            bmin = nmin;
            bmax = nmax;
            ++end;
        }
        /* Keep up to per_cluster candidates whose normals differ from those already kept. The kept ones
         * move to the front: kept never passes i, so nothing is overwritten before it is read. */
        uint32_t first_kept = kept;
        for (uint32_t i = start; i < end && (int)(kept - first_kept) < per_cluster; ++i) {
            int distinct = 1;
            for (uint32_t j = first_kept; j < kept && distinct; ++j)
                distinct = v3_dot(sorted[j].n, sorted[i].n) < cos_limit;
            if (distinct)
                sorted[kept++] = sorted[i];
        }
        start = end;
    }
    return kept;
}

ic_result ic_world_select(ic_candidate *cand, uint32_t count, ic_vec3 lo, ic_vec3 hi, float max_box,
                          int per_cluster, float normal_angle_deg, uint32_t *kept)
{
    *kept = 0;
    if (count == 0)
        return IC_OK;
    if (!ic_world_sort(cand, count, lo, hi))
        return IC_ERR_OOM;
    *kept = ic_world_cluster(cand, count, max_box, per_cluster, normal_angle_deg);
    return IC_OK;
}

/* ---------------------------------------------------------------- several processes */

#define BUCKET_BITS 10 /* the Morton order's ranges are made of 1,024 buckets of its top bits */
#define BUCKETS (1 << BUCKET_BITS)

/* What a process publishes first: its candidates per bucket and its eye paths' visited count. */
typedef struct world_census {
    uint32_t count[BUCKETS];
    double visited;
} world_census;

/* What it publishes after sorting its range: the candidates' number, the index of the first gap inside
 * it (count if none), and the first and last positions. */
typedef struct world_edge {
    uint64_t count, gap;
    ic_vec3 first, last;
} world_edge;

static uint32_t bucket_of(const ic_candidate *c, ic_vec3 lo, ic_vec3 hi)
{
    return ic_morton3(c->p, lo, hi) >> (30 - BUCKET_BITS);
}

ic_result ic_world_select_shared(ic_comm *comm, ic_candidate *own, uint32_t own_count, ic_vec3 lo, ic_vec3 hi,
                                 float max_box, int per_cluster, float normal_angle_deg, ic_candidate **out,
                                 uint32_t *kept, uint64_t *total, double *visited, ic_error *err)
{
    *out = NULL;
    *kept = 0;
    *total = own_count;
    if (!ic_comm_is_shared(comm)) {
        if (ic_world_select(own, own_count, lo, hi, max_box, per_cluster, normal_angle_deg, kept) != IC_OK) {
            free(own);
            return ic_error_set(err, IC_ERR_OOM, "out of memory sorting %u world-space candidates", own_count);
        }
        *out = own;
        return IC_OK;
    }
    const int n = comm->size, me = comm->rank;
    const size_t cand_bytes = sizeof(ic_candidate);
    world_census *census = calloc((size_t)n, sizeof *census);
    world_edge *edge = calloc((size_t)n, sizeof *edge);
    uint64_t *bytes = malloc(sizeof *bytes * (size_t)n * (size_t)n);
    uint16_t *owner = malloc(sizeof *owner * BUCKETS);
    uint32_t *bucket = malloc(sizeof *bucket * (own_count ? own_count : 1));
    ic_candidate *send = malloc(cand_bytes * (own_count ? own_count : 1)), *range = NULL, *heads = NULL,
                 *seq = NULL, *sel = NULL;
    uint64_t *at = calloc((size_t)n + 1, sizeof *at), *head_at = calloc((size_t)n + 1, sizeof *head_at);
    ic_result r = census && edge && bytes && owner && bucket && send && at && head_at
                      ? IC_OK
                      : ic_error_set(err, IC_ERR_OOM, "out of memory for %u world-space candidates", own_count);
    /* 1. Every process's candidates per bucket, and the buckets' owners: contiguous ranges, each bucket to
     * the process whose share of the order its middle falls in. */
    if (r == IC_OK) {
        world_census *mine = &census[me];
        for (uint32_t i = 0; i < own_count; ++i)
            ++mine->count[bucket[i] = bucket_of(&own[i], lo, hi)];
        mine->visited = *visited;
        uint64_t *sizes = at; /* reused: the census's size per process */
        for (int q = 0; q < n; ++q)
            sizes[q] = sizeof *census;
        r = ic_comm_allgather_sized(comm, census, sizes, "exchanging world-space candidate counts", err);
    }
    uint64_t all = 0, mine_total = 0;
    if (r == IC_OK) {
        double v = 0.0;
        for (int q = 0; q < n; ++q) {
            v += census[q].visited;
            for (int b = 0; b < BUCKETS; ++b)
                all += census[q].count[b];
        }
        *visited = v;
        *total = all;
        uint64_t before = 0;
        for (int b = 0; b < BUCKETS; ++b) {
            uint64_t in = 0;
            for (int q = 0; q < n; ++q)
                in += census[q].count[b];
            uint64_t o = all ? (2 * before + in) * (uint64_t)n / (2 * all) : 0;
            owner[b] = (uint16_t)(o < (uint64_t)n ? o : (uint64_t)n - 1);
            before += in;
        }
        for (size_t k = 0; k < (size_t)n * (size_t)n; ++k)
            bytes[k] = 0;
        for (int q = 0; q < n; ++q)
            for (int b = 0; b < BUCKETS; ++b)
                bytes[(size_t)q * n + owner[b]] += census[q].count[b] * cand_bytes;
        for (int q = 0; q < n; ++q)
            mine_total += bytes[(size_t)q * n + me] / cand_bytes;
        range = malloc(cand_bytes * (mine_total ? mine_total : 1));
        if (!range)
            r = ic_error_set(err, IC_ERR_OOM, "out of memory for %llu world-space candidates",
                             (unsigned long long)mine_total);
    }
    /* 2. The candidates to their ranges' processes, in each sender's order; sorted there. */
    if (r == IC_OK) {
        at[0] = 0;
        for (int q = 0; q < n; ++q)
            at[q + 1] = at[q] + bytes[(size_t)me * n + q] / cand_bytes;
        for (uint32_t i = 0; i < own_count; ++i)
            send[at[owner[bucket[i]]]++] = own[i];
        r = ic_comm_alltoall(comm, send, bytes, range, "exchanging world-space candidates", err);
    }
    if (r == IC_OK && mine_total > UINT32_MAX)
        r = ic_error_set(err, IC_ERR_UNSUPPORTED, "%llu world-space candidates in one process's range",
                         (unsigned long long)mine_total);
    const uint32_t m = (uint32_t)mine_total;
    if (r == IC_OK && !ic_world_sort(range, m, lo, hi))
        r = ic_error_set(err, IC_ERR_OOM, "out of memory sorting %u world-space candidates", m);
    /* 3. Every range's first gap and ends. */
    if (r == IC_OK) {
        world_edge *e = &edge[me];
        e->count = m;
        e->gap = m;
        for (uint32_t i = 1; i < m && e->gap == m; ++i)
            if (ic_world_gap(range[i - 1].p, range[i].p, max_box))
                e->gap = i;
        if (m) {
            e->first = range[0].p;
            e->last = range[m - 1].p;
        }
        for (int q = 0; q < n; ++q)
            at[q] = sizeof *edge;
        r = ic_comm_allgather_sized(comm, edge, at, "exchanging world-space candidates' ends", err);
    }
    /* head[q]: the candidates of q's range before its first cluster start that is certain whatever came
     * before: none where q's range begins after a gap (or begins the order), else up to its first gap. */
    uint64_t heads_total = 0;
    if (r == IC_OK) {
        int prev = -1;
        for (int q = 0; q < n; ++q) {
            uint64_t h = 0;
            if (edge[q].count) {
                h = prev < 0 || ic_world_gap(edge[prev].last, edge[q].first, max_box) ? 0 : edge[q].gap;
                prev = q;
            }
            head_at[q + 1] = head_at[q] + h;
            at[q] = h * cand_bytes;
        }
        heads_total = head_at[n];
        heads = malloc(cand_bytes * (heads_total ? heads_total : 1));
        if (!heads)
            r = ic_error_set(err, IC_ERR_OOM, "out of memory for world-space candidates");
        else
            memcpy(heads + head_at[me], range, at[me]);
    }
    if (r == IC_OK)
        r = ic_comm_allgather_sized(comm, heads, at, "exchanging world-space candidates at the ranges' ends", err);
    /* 4. The runs that begin in this range, with the following ranges' heads up to the next certain start. */
    uint32_t mine_kept = 0;
    if (r == IC_OK) {
        const uint64_t h = head_at[me + 1] - head_at[me];
        uint64_t len = m - h;
        int q = me + 1;
        for (; q < n && len; ++q) {
            uint64_t hq = head_at[q + 1] - head_at[q];
            if (!edge[q].count)
                continue;
            len += hq;
            if (hq < edge[q].count)
                break;
        }
        seq = malloc(cand_bytes * (len ? len : 1));
        if (!seq) {
            r = ic_error_set(err, IC_ERR_OOM, "out of memory for world-space candidates");
        } else if (len) {
            memcpy(seq, range + h, cand_bytes * (m - h));
            uint64_t put = m - h;
            for (int k = me + 1; k < q + (q < n); ++k) {
                uint64_t hk = head_at[k + 1] - head_at[k];
                memcpy(seq + put, heads + head_at[k], cand_bytes * hk);
                put += hk;
            }
            mine_kept = ic_world_cluster(seq, (uint32_t)len, max_box, per_cluster, normal_angle_deg);
        }
    }
    /* 5. The kept candidates, in range order, to every process. */
    if (r == IC_OK) {
        sel = malloc(cand_bytes * (all ? all : 1));
        if (!sel) {
            r = ic_error_set(err, IC_ERR_OOM, "out of memory for world-space candidates");
        } else {
            uint64_t got = 0;
            memcpy(sel, seq, cand_bytes * mine_kept);
            r = ic_comm_allgather_counted(comm, sel, mine_kept, cand_bytes, &got, err);
            *kept = (uint32_t)got;
        }
    }
    if (r == IC_OK) {
        *out = sel;
        sel = NULL;
    } else {
        *kept = 0;
    }
    free(own);
    free(census);
    free(edge);
    free(bytes);
    free(owner);
    free(bucket);
    free(send);
    free(range);
    free(heads);
    free(seq);
    free(sel);
    free(at);
    free(head_at);
    return r;
}
