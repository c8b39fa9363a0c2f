/* ic_world.c — Morton sort, bounding-box clustering, distinct-normal selection (Frolov et al. 2012 §3.1.3). */
#include "ic_world.h"

#include "core/morton.h"
#include "core/vecmath.h"

#include <stdlib.h>

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

typedef struct keyed {
    uint32_t morton;
    uint64_t key;
    uint32_t index;
} keyed;

static int cmp_keyed(const void *a, const void *b)
{
    const keyed *x = a, *y = b;
    if (x->morton != y->morton)
        return x->morton < y->morton ? -1 : 1;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return 0;
}

uint32_t ic_world_select(ic_candidate *cand, uint32_t count, ic_vec3 lo, ic_vec3 hi, float max_box,
                         int per_cluster, float normal_angle_deg)
{
    if (count == 0)
        return 0;
    keyed *order = malloc(sizeof *order * count);
    ic_candidate *sorted = malloc(sizeof *sorted * count);
    if (!order || !sorted) {
        free(order);
        free(sorted);
        return 0;
    }
    for (uint32_t i = 0; i < count; ++i) {
        order[i].morton = ic_morton3(cand[i].p, lo, hi);
        order[i].key = cand[i].key;
        order[i].index = i;
    }
    qsort(order, count, sizeof *order, cmp_keyed);
    for (uint32_t i = 0; i < count; ++i)
        sorted[i] = cand[order[i].index];
    free(order);

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
        /* Keep up to per_cluster candidates whose normals differ from those already kept. */
        uint32_t first_kept = kept;
        for (uint32_t i = start; i < end && (int)(kept - first_kept) < per_cluster; ++i) {
            int distinct = 1;
            for (uint32_t j = first_kept; j < kept && distinct; ++j)
                distinct = v3_dot(cand[j].n, sorted[i].n) < cos_limit;
            if (distinct)
                cand[kept++] = sorted[i];
        }
        start = end;
    }
    free(sorted);
    return kept;
}
