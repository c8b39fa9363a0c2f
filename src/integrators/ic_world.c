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

/* Byte b of the sort key (morton, key): bytes 0–7 the key's, 8–11 the Morton code's, least significant
 * first. */
static unsigned key_byte(const keyed *k, int b)
{
    return b < 8 ? (unsigned)(k->key >> (8 * b)) & 0xffu : (k->morton >> (8 * (b - 8))) & 0xffu;
}

/* Sorts by (morton, key) ascending: a least-significant-digit radix sort, one stable counting pass per
 * byte, skipping the bytes every entry shares (most of the 64-bit key). The order is total for distinct
 * keys, so it is the one a comparison sort gives. Returns the sorted array: a or tmp. */
static keyed *radix_sort(keyed *a, keyed *tmp, uint32_t n)
{
    for (int b = 0; b < 12; ++b) {
        uint32_t count[256] = {0};
        for (uint32_t i = 0; i < n; ++i)
            ++count[key_byte(&a[i], b)];
        if (count[key_byte(&a[0], b)] == n)
            continue; /* every entry has this byte: the pass would not move anything */
        uint32_t at = 0;
        for (int v = 0; v < 256; ++v) {
            uint32_t c = count[v];
            count[v] = at;
            at += c;
        }
        for (uint32_t i = 0; i < n; ++i)
            tmp[count[key_byte(&a[i], b)]++] = a[i];
        keyed *t = a;
        a = tmp;
        tmp = t;
    }
    return a;
}

uint32_t ic_world_select(ic_candidate *cand, uint32_t count, ic_vec3 lo, ic_vec3 hi, float max_box,
                         int per_cluster, float normal_angle_deg)
{
    if (count == 0)
        return 0;
    keyed *order = malloc(sizeof *order * count), *spare = malloc(sizeof *spare * count);
    ic_candidate *sorted = malloc(sizeof *sorted * count);
    if (!order || !spare || !sorted) {
        free(order);
        free(spare);
        free(sorted);
        return 0;
    }
    for (uint32_t i = 0; i < count; ++i) {
        order[i].morton = ic_morton3(cand[i].p, lo, hi);
        order[i].key = cand[i].key;
        order[i].index = i;
    }
    const keyed *by = radix_sort(order, spare, count);
    for (uint32_t i = 0; i < count; ++i)
        sorted[i] = cand[by[i].index];
    free(order);
    free(spare);

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
