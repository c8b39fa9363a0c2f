/*
 * kdtree.c — implicit balanced k-d tree over shading points (kdtree.h; Křivánek et al. 2006 §4.2, Jensen 2001 §6.3).
 */
#include "kdtree.h"

#include <stdlib.h>
#include <string.h>

/* Keys are (coordinate on the axis, point index): distinct, so selection is deterministic and the
 * partition of equal coordinates never depends on pivot luck. */
static int key_less(const ic_kdtree *t, uint32_t a, uint32_t b, int axis)
{
    float ka = v3_get(t->pos[a], axis), kb = v3_get(t->pos[b], axis);
    return ka < kb || (ka == kb && t->index[a] < t->index[b]);
}

static void swap_nodes(ic_kdtree *t, uint32_t a, uint32_t b)
{
    uint32_t ti = t->index[a];
    t->index[a] = t->index[b];
    t->index[b] = ti;
    ic_vec3 tp = t->pos[a];
    t->pos[a] = t->pos[b];
    t->pos[b] = tp;
}

/* Quickselect: afterwards node k holds the k-th key of [lo, hi), smaller keys before, larger after. */
static void select_nth(ic_kdtree *t, uint32_t lo, uint32_t hi, uint32_t k, int axis)
{
    while (hi - lo > 1) {
        uint32_t mid = lo + (hi - lo) / 2;
        swap_nodes(t, mid, hi - 1);
        uint32_t store = lo;
        for (uint32_t i = lo; i < hi - 1; ++i)
            if (key_less(t, i, hi - 1, axis))
                swap_nodes(t, i, store++);
        swap_nodes(t, store, hi - 1);
        if (store == k)
            return;
        if (k < store)
            hi = store;
        else
            lo = store + 1;
    }
}

static void build_range(ic_kdtree *t, uint32_t lo, uint32_t hi)
{
    if (hi <= lo)
        return;
    uint32_t mid = lo + (hi - lo) / 2;
    if (hi - lo > 1) {
        ic_vec3 bmin = t->pos[lo], bmax = t->pos[lo];
        for (uint32_t i = lo + 1; i < hi; ++i) {
            bmin = v3_min(bmin, t->pos[i]);
            bmax = v3_max(bmax, t->pos[i]);
        }
        ic_vec3 ext = v3_sub(bmax, bmin);
        int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
        select_nth(t, lo, hi, mid, axis);
        t->axis[mid] = (uint8_t)axis;
    } else {
        t->axis[mid] = 0;
    }
    /* Depth is ⌈log2 count⌉, so recursion stays shallow. */
    build_range(t, lo, mid);
    build_range(t, mid + 1, hi);
}

ic_result ic_kdtree_build(ic_kdtree *t, const ic_vec3 *points, uint32_t count)
{
    memset(t, 0, sizeof *t);
    if (count == 0)
        return IC_OK;
    t->index = malloc(sizeof *t->index * count);
    t->pos = malloc(sizeof *t->pos * count);
    t->axis = malloc(count);
    if (!t->index || !t->pos || !t->axis) {
        ic_kdtree_free(t);
        return IC_ERR_OOM;
    }
    for (uint32_t i = 0; i < count; ++i) {
        t->index[i] = i;
        t->pos[i] = points[i];
    }
    t->count = count;
    build_range(t, 0, count);
    return IC_OK;
}

void ic_kdtree_free(ic_kdtree *t)
{
    free(t->index);
    free(t->pos);
    free(t->axis);
    memset(t, 0, sizeof *t);
}

void ic_kdtree_radius(const ic_kdtree *t, ic_vec3 q, float radius, ic_kdtree_visit_fn visit, void *user)
{
    /* A balanced tree over < 2^32 points is < 33 levels deep; each level pushes at most one pending
     * range beyond the one being descended, so 64 entries never overflow. */
    uint32_t stack_lo[64], stack_hi[64];
    int top = 0;
    float r2 = radius * radius;
    if (t->count == 0 || !(radius >= 0.0f))
        return;
    stack_lo[0] = 0;
    stack_hi[0] = t->count;
    top = 1;
    while (top > 0) {
        --top;
        uint32_t lo = stack_lo[top], hi = stack_hi[top];
        while (lo < hi) {
            uint32_t mid = lo + (hi - lo) / 2;
            ic_vec3 p = t->pos[mid];
            if (v3_len2(v3_sub(p, q)) <= r2)
                visit(user, t->index[mid]);
            if (hi - lo == 1)
                break;
            int axis = t->axis[mid];
            float d = v3_get(q, axis) - v3_get(p, axis);
            int go_left = d - radius <= 0.0f, go_right = d + radius >= 0.0f;
            if (go_left && go_right) {
                stack_lo[top] = mid + 1;
                stack_hi[top] = hi;
                ++top;
                hi = mid;
            } else if (go_left) {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
    }
}
