/*
 * octree.c — flat multiple-reference octree and point octree (octree.h; Frolov et al. 2012 §4.2–4.3).
 *
 * Insertion walks every leaf a sphere overlaps with an explicit fixed-size stack; a point (radius 0)
 * goes to exactly one leaf, chosen by the same octant rule as the look-up descent, so k-nearest and
 * radius queries never see an item twice. Queries allocate nothing.
 */
#include "octree.h"

#include "core/morton.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define STACK_SIZE (8 * (IC_OCTREE_MAX_DEPTH + 2))

typedef struct cube {
    float cx, cy, cz, h;
} cube;

static float item_radius(const ic_octree_items *it, uint32_t i) { return ic_octree_item_radius(it, i); }

static cube child_cube(cube c, unsigned octant)
{
    cube r;
    r.h = c.h * 0.5f;
    r.cx = (octant & 1) ? c.cx + r.h : c.cx - r.h;
    r.cy = (octant & 2) ? c.cy + r.h : c.cy - r.h;
    r.cz = (octant & 4) ? c.cz + r.h : c.cz - r.h;
    return r;
}

static unsigned point_octant(cube c, float x, float y, float z)
{
    return (unsigned)(x >= c.cx) | (unsigned)(y >= c.cy) << 1 | (unsigned)(z >= c.cz) << 2;
}

/* max without fmaxf's NaN rules, which keep gcc from inlining it. */
static inline float maxf(float a, float b) { return a > b ? a : b; }

/* Squared distance from p to the closed cube (0 inside). */
static float cube_dist2(cube c, float x, float y, float z)
{
    float ex = maxf(fabsf(x - c.cx) - c.h, 0.0f);
    float ey = maxf(fabsf(y - c.cy) - c.h, 0.0f);
    float ez = maxf(fabsf(z - c.cz) - c.h, 0.0f);
    return ex * ex + ey * ey + ez * ez;
}

/* Does item i belong in the child cube? Points by octant, spheres by closed overlap. */
static int item_in_child(const ic_octree_items *it, uint32_t i, float r, cube parent, unsigned octant)
{
    const ic_float4 *s = &it->sphere[i];
    if (r <= 0.0f)
        return point_octant(parent, s->x, s->y, s->z) == octant;
    return cube_dist2(child_cube(parent, octant), s->x, s->y, s->z) <= r * r;
}

static ic_octree_ref make_ref(const ic_octree_items *it, uint32_t i, float r)
{
    const ic_float4 *s = &it->sphere[i];
    ic_octree_ref ref = {s->x, s->y, s->z, r, i};
    return ref;
}

/* A sphere stays at a node whose half side is at most its radius (cache.h: octree). */
static int stays_at(float r, float h) { return r > 0.0f && h <= r; }

void ic_octree_init(ic_octree *t, uint32_t leaf_capacity, uint32_t max_depth)
{
    memset(t, 0, sizeof *t);
    t->leaf_capacity = leaf_capacity ? leaf_capacity : 1;
    t->max_depth = max_depth > IC_OCTREE_MAX_DEPTH ? IC_OCTREE_MAX_DEPTH : max_depth;
}

void ic_octree_free(ic_octree *t)
{
    free(t->nodes);
    free(t->refs);
    t->nodes = NULL;
    t->refs = NULL;
    t->node_count = t->node_cap = 0;
    t->ref_end = t->ref_cap = t->ref_live = 0;
    t->has_root = 0;
}

size_t ic_octree_bytes(const ic_octree *t)
{
    return (size_t)t->node_cap * sizeof(ic_octree_node) + t->ref_cap * sizeof(ic_octree_ref);
}

static ic_result reserve_refs(ic_octree *t, size_t extra)
{
    if (t->ref_end + extra <= t->ref_cap)
        return IC_OK;
    size_t cap = t->ref_cap ? t->ref_cap : 1024;
    while (cap < t->ref_end + extra)
        cap *= 2;
    ic_octree_ref *r = realloc(t->refs, cap * sizeof *r);
    if (!r)
        return IC_ERR_OOM;
    t->refs = r;
    t->ref_cap = cap;
    return IC_OK;
}

/* Appends 8 leaf nodes; returns the index of the first in *first. */
static ic_result add_children(ic_octree *t, uint32_t *first)
{
    if (t->node_count + 8 > t->node_cap) {
        uint32_t cap = t->node_cap ? t->node_cap * 2 : 64;
        ic_octree_node *n = realloc(t->nodes, (size_t)cap * sizeof *n);
        if (!n)
            return IC_ERR_OOM;
        t->nodes = n;
        t->node_cap = cap;
    }
    *first = t->node_count;
    memset(&t->nodes[t->node_count], 0, 8 * sizeof(ic_octree_node));
    t->node_count += 8;
    return IC_OK;
}

static ic_result reset_root(ic_octree *t, cube c)
{
    t->node_count = 0;
    t->ref_end = 0;
    t->ref_live = 0;
    if (t->node_cap == 0) {
        t->nodes = malloc(64 * sizeof *t->nodes);
        if (!t->nodes)
            return IC_ERR_OOM;
        t->node_cap = 64;
    }
    memset(&t->nodes[0], 0, sizeof t->nodes[0]);
    t->node_count = 1;
    t->cx = c.cx;
    t->cy = c.cy;
    t->cz = c.cz;
    t->half = c.h;
    t->has_root = 1;
    return IC_OK;
}

/* Splits leaf `node` (cube c, depth d) if that helps, recursively. References to spheres at least
 * as large as a child stay in the node; the others move to the children they overlap. */
static ic_result maybe_split(ic_octree *t, const ic_octree_items *it, uint32_t node, cube c, uint32_t depth)
{
    ic_octree_node leaf = t->nodes[node];
    if (leaf.child || leaf.count <= t->leaf_capacity || depth >= t->max_depth)
        return IC_OK;
    float hc = 0.5f * c.h;
    uint32_t counts[8] = {0}, down = 0;
    for (uint32_t k = 0; k < leaf.count; ++k) {
        uint32_t i = t->refs[leaf.begin + k].index;
        float r = item_radius(it, i);
        if (stays_at(r, hc))
            continue;
        ++down;
        for (unsigned o = 0; o < 8; ++o)
            counts[o] += (uint32_t)item_in_child(it, i, r, c, o);
    }
    /* Nothing would move down: the leaf is full of spheres as large as its children. */
    if (down == 0)
        return IC_OK;
    size_t need = 0;
    uint32_t caps[8];
    for (unsigned o = 0; o < 8; ++o) {
        caps[o] = counts[o] < 4 ? 4 : counts[o];
        need += caps[o];
    }
    ic_result rc = reserve_refs(t, need);
    uint32_t first = 0;
    if (rc == IC_OK)
        rc = add_children(t, &first);
    if (rc != IC_OK)
        return rc;
    for (unsigned o = 0; o < 8; ++o) {
        ic_octree_node *ch = &t->nodes[first + o];
        ch->begin = (uint32_t)t->ref_end;
        ch->cap = caps[o];
        t->ref_end += caps[o];
        t->ref_live += caps[o];
    }
    uint32_t kept = 0;
    for (uint32_t k = 0; k < leaf.count; ++k) {
        uint32_t i = t->refs[leaf.begin + k].index;
        float r = item_radius(it, i);
        if (stays_at(r, hc)) {
            t->refs[leaf.begin + kept++] = make_ref(it, i, r); /* compacted in place, order kept */
            continue;
        }
        for (unsigned o = 0; o < 8; ++o)
            if (item_in_child(it, i, r, c, o)) {
                ic_octree_node *ch = &t->nodes[first + o];
                t->refs[ch->begin + ch->count++] = make_ref(it, i, r);
            }
    }
    t->nodes[node].child = first;
    t->nodes[node].count = kept;
    for (unsigned o = 0; o < 8; ++o) {
        rc = maybe_split(t, it, first + o, child_cube(c, o), depth + 1);
        if (rc != IC_OK)
            return rc;
    }
    return IC_OK;
}

static ic_result leaf_append(ic_octree *t, uint32_t node, ic_octree_ref item)
{
    ic_octree_node *n = &t->nodes[node];
    if (n->count == n->cap) {
        /* Move the segment to the end of refs with twice the room; the old one becomes dead. */
        uint32_t cap = n->cap ? n->cap * 2 : 4;
        ic_result rc = reserve_refs(t, cap);
        if (rc != IC_OK)
            return rc;
        n = &t->nodes[node];
        memcpy(&t->refs[t->ref_end], &t->refs[n->begin], (size_t)n->count * sizeof(ic_octree_ref));
        t->ref_live += cap - n->cap;
        n->begin = (uint32_t)t->ref_end;
        n->cap = cap;
        t->ref_end += cap;
    }
    t->refs[n->begin + n->count++] = item;
    return IC_OK;
}

static int root_contains(const ic_octree *t, const ic_octree_items *it, uint32_t i)
{
    const ic_float4 *s = &it->sphere[i];
    float r = item_radius(it, i);
    float h = t->half;
    return s->x - r >= t->cx - h && s->x + r <= t->cx + h && s->y - r >= t->cy - h && s->y + r <= t->cy + h &&
           s->z - r >= t->cz - h && s->z + r <= t->cz + h;
}

/* Cube around the bounds of items 0…count−1, padded ×2 so a growing cache rebuilds rarely. */
static cube fit_root(const ic_octree_items *it, uint32_t count)
{
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = 0; i < count; ++i) {
        const ic_float4 *s = &it->sphere[i];
        float r = item_radius(it, i), p[3] = {s->x, s->y, s->z};
        for (int a = 0; a < 3; ++a) {
            lo[a] = fminf(lo[a], p[a] - r);
            hi[a] = fmaxf(hi[a], p[a] + r);
        }
    }
    cube c;
    c.cx = 0.5f * (lo[0] + hi[0]);
    c.cy = 0.5f * (lo[1] + hi[1]);
    c.cz = 0.5f * (lo[2] + hi[2]);
    float ext = fmaxf(hi[0] - lo[0], fmaxf(hi[1] - lo[1], hi[2] - lo[2]));
    float mag = fmaxf(fabsf(c.cx), fmaxf(fabsf(c.cy), fabsf(c.cz)));
    /* Never a degenerate cube: at least a relative 1e-4 of the coordinates' magnitude. */
    c.h = fmaxf(ext, 1e-4f * (1.0f + mag));
    return c;
}

static ic_result insert_item(ic_octree *t, const ic_octree_items *it, uint32_t index)
{
    struct entry {
        cube c;
        uint32_t node, depth;
    } stack[STACK_SIZE];
    int top = 0;
    float r = item_radius(it, index);
    const ic_float4 *s = &it->sphere[index];
    stack[top++] = (struct entry){{t->cx, t->cy, t->cz, t->half}, 0, 0};
    while (top > 0) {
        struct entry e = stack[--top];
        uint32_t child = t->nodes[e.node].child;
        if (child && !stays_at(r, e.c.h)) {
            if (r <= 0.0f) {
                unsigned o = point_octant(e.c, s->x, s->y, s->z);
                stack[top++] = (struct entry){child_cube(e.c, o), child + o, e.depth + 1};
                continue;
            }
            for (unsigned o = 0; o < 8; ++o) {
                cube cc = child_cube(e.c, o);
                if (cube_dist2(cc, s->x, s->y, s->z) <= r * r)
                    stack[top++] = (struct entry){cc, child + o, e.depth + 1};
            }
            continue;
        }
        ic_result rc = leaf_append(t, e.node, make_ref(it, index, r));
        if (rc == IC_OK)
            rc = maybe_split(t, it, e.node, e.c, e.depth);
        if (rc != IC_OK)
            return rc;
    }
    return IC_OK;
}


typedef struct keyed {
    uint32_t key, index;
} keyed;

static int cmp_keyed(const void *a, const void *b)
{
    const keyed *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return (x->index > y->index) - (x->index < y->index);
}

ic_result ic_octree_build(ic_octree *t, const ic_octree_items *items, uint32_t count)
{
    if (count == 0) {
        t->node_count = 0;
        t->ref_end = t->ref_live = 0;
        t->has_root = 0;
        return IC_OK;
    }
    cube root = fit_root(items, count);
    ic_result rc = reset_root(t, root);
    /* Insert along a Morton curve (ties by index: deterministic), so nodes and reference segments
     * that are close in space end up close in memory — a look-up's descent then misses the
     * processor caches less. */
    keyed *order = malloc((size_t)count * sizeof *order);
    if (!order)
        return rc == IC_OK ? IC_ERR_OOM : rc;
    float scale = 1023.0f / (2.0f * root.h);
    for (uint32_t i = 0; i < count; ++i) {
        const ic_float4 *s = &items->sphere[i];
        float u[3] = {(s->x - (root.cx - root.h)) * scale, (s->y - (root.cy - root.h)) * scale,
                      (s->z - (root.cz - root.h)) * scale};
        uint32_t q[3];
        for (int a = 0; a < 3; ++a)
            q[a] = u[a] <= 0.0f ? 0u : (u[a] >= 1023.0f ? 1023u : (uint32_t)u[a]);
        order[i] = (keyed){ic_morton3_cells(q[0], q[1], q[2]), i};
    }
    qsort(order, count, sizeof *order, cmp_keyed);
    for (uint32_t k = 0; k < count && rc == IC_OK; ++k)
        rc = insert_item(t, items, order[k].index);
    free(order);
    return rc;
}

ic_result ic_octree_insert(ic_octree *t, const ic_octree_items *items, uint32_t index)
{
    if (!t->has_root || !root_contains(t, items, index))
        return ic_octree_build(t, items, index + 1);
    return insert_item(t, items, index);
}

ic_result ic_octree_compact(ic_octree *t)
{
    if (t->ref_end <= 2 * t->ref_live + 4096)
        return IC_OK;
    ic_octree_ref *fresh = malloc((t->ref_live ? t->ref_live : 1) * sizeof *fresh);
    if (!fresh)
        return IC_ERR_OOM;
    size_t end = 0;
    for (uint32_t n = 0; n < t->node_count; ++n) {
        ic_octree_node *node = &t->nodes[n];
        if (node->cap == 0)
            continue;
        memcpy(&fresh[end], &t->refs[node->begin], (size_t)node->count * sizeof *fresh);
        node->begin = (uint32_t)end;
        end += node->cap;
    }
    free(t->refs);
    t->refs = fresh;
    t->ref_end = end;
    t->ref_cap = t->ref_live ? t->ref_live : 1;
    return IC_OK;
}

/* (d², index) order: nearest first, ties by the lower index, so results never depend on layout. */
static int closer(float da, uint32_t ia, float db, uint32_t ib) { return da < db || (da == db && ia < ib); }

uint32_t ic_octree_knn(const ic_octree *t, const ic_octree_items *items, ic_vec3 p, uint32_t k, uint32_t *idx,
                       float *d2)
{
    struct entry {
        cube c;
        uint32_t node;
        float mind2;
    } stack[STACK_SIZE];
    (void)items; /* positions come from the references */
    if (!t->has_root || k == 0)
        return 0;
    uint32_t found = 0;
    int top = 0;
    cube root = {t->cx, t->cy, t->cz, t->half};
    stack[top++] = (struct entry){root, 0, cube_dist2(root, p.x, p.y, p.z)};
    while (top > 0) {
        struct entry e = stack[--top];
        /* Prune cells strictly farther than the current k-th (with a rounding margin). */
        if (found == k && e.mind2 > d2[k - 1] * 1.00001f)
            continue;
        const ic_octree_node *n = &t->nodes[e.node];
        if (!n->child) {
            for (uint32_t j = 0; j < n->count; ++j) {
                const ic_octree_ref *s = &t->refs[n->begin + j];
                uint32_t i = s->index;
                float d = ic_dist2(p.x, p.y, p.z, s->x, s->y, s->z);
                if (found == k && !closer(d, i, d2[k - 1], idx[k - 1]))
                    continue;
                uint32_t pos = found < k ? found++ : k - 1;
                while (pos > 0 && closer(d, i, d2[pos - 1], idx[pos - 1])) {
                    d2[pos] = d2[pos - 1];
                    idx[pos] = idx[pos - 1];
                    --pos;
                }
                d2[pos] = d;
                idx[pos] = i;
            }
            continue;
        }
        /* Push children farthest first so the nearest is explored first. */
        struct entry ch[8];
        for (unsigned o = 0; o < 8; ++o) {
            ch[o].c = child_cube(e.c, o);
            ch[o].node = n->child + o;
            ch[o].mind2 = cube_dist2(ch[o].c, p.x, p.y, p.z);
        }
        for (unsigned a = 1; a < 8; ++a)
            for (unsigned b = a; b > 0 && ch[b].mind2 > ch[b - 1].mind2; --b) {
                struct entry tmp = ch[b];
                ch[b] = ch[b - 1];
                ch[b - 1] = tmp;
            }
        for (unsigned o = 0; o < 8; ++o)
            if (t->nodes[ch[o].node].child || t->nodes[ch[o].node].count)
                stack[top++] = ch[o];
    }
    return found;
}

uint32_t ic_octree_radius(const ic_octree *t, const ic_octree_items *items, ic_vec3 p, float radius,
                          uint32_t *idx, uint32_t capacity)
{
    struct entry {
        cube c;
        uint32_t node;
    } stack[STACK_SIZE];
    (void)items; /* positions come from the references */
    if (!t->has_root || !(radius > 0.0f))
        return 0;
    float r2 = radius * radius, prune = r2 * 1.00001f;
    uint32_t total = 0;
    int top = 0;
    stack[top++] = (struct entry){{t->cx, t->cy, t->cz, t->half}, 0};
    while (top > 0) {
        struct entry e = stack[--top];
        const ic_octree_node *n = &t->nodes[e.node];
        if (!n->child) {
            for (uint32_t j = 0; j < n->count; ++j) {
                const ic_octree_ref *s = &t->refs[n->begin + j];
                if (ic_dist2(p.x, p.y, p.z, s->x, s->y, s->z) < r2) {
                    if (total < capacity)
                        idx[total] = s->index;
                    ++total;
                }
            }
            continue;
        }
        for (unsigned o = 0; o < 8; ++o) {
            cube cc = child_cube(e.c, o);
            if (cube_dist2(cc, p.x, p.y, p.z) <= prune)
                stack[top++] = (struct entry){cc, n->child + o};
        }
    }
    return total;
}
