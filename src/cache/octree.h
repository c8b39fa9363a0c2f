/*
 * octree.h — flat octree over records: the multiple-reference sphere octree of the irradiance cache
 * and the auxiliary point octree for k-nearest and radius queries (Frolov et al. 2012 §4.2–4.3).
 *
 * One structure serves both (one routine, not two variants). Items are spheres
 * (center, radius = R·a·scale); a point tree is the special case scale = 0.
 *
 * Multiple references, stackless look-up (Frolov et al. 2012 §4.3): a sphere is referenced from every node it
 * overlaps on the level that matches its size — the first nodes on the way down whose half side is
 * at most its radius, or, in a tree built at once (ic_octree_build), whose children's half side is —
 * or from the leaves above that level. Finding every sphere that holds p is
 * then one root-to-leaf descent with no stack and no backtracking, scanning the reference list of
 * each node on the path (almost always only the leaf's and one or two above it). Pure leaf storage,
 * as in Frolov et al. 2012, is the special case where all records are alike in size (which validity clamping
 * brings about); with mixed sizes it would copy a large sphere into every tiny leaf that small
 * neighbours caused, (r/h)² references each — storing by size bounds a record to at most 27 nodes.
 *
 * Nodes live in one array; the 8 children of a node are contiguous and found by index; each node
 * owns a segment [begin, begin+count) of one reference array (index, center and radius: 20 bytes) (capacity cap; a segment moves to the
 * end of the array when it grows, and the array is compacted when more than half of it is dead).
 * A leaf splits when it holds more than leaf_capacity references, the depth limit is not reached,
 * and some reference is smaller than the children (only those move down).
 */
#ifndef IC_CACHE_OCTREE_H
#define IC_CACHE_OCTREE_H

/* The look-up paths (octree, frozen SSE2 and portable, linear) and the brute-force checks answer bit
 * for bit alike only if no a·b + c is fused into an FMA in one and not in another (intrinsics never
 * are). GCC in ISO C mode (-std=c11) does not contract; clang does where the target has FMA
 * (-march=native) unless told not to: here, before the inline arithmetic of the cache's headers
 * (cache_store.h includes this one before core/vecmath.h). */
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#endif

#include "irrcache/common.h"

#include <stdalign.h>
#include <stddef.h>
#include <stdint.h>

/* Hard depth limit: bounds the fixed-size traversal stacks (no allocation during queries). */
#define IC_OCTREE_MAX_DEPTH 32
#define IC_OCTREE_NONE UINT32_MAX

/* A 16-byte aligned float quadruple: hot record fields (position + R, normal + a). */
typedef struct ic_float4 {
    alignas(16) float x;
    float y, z, w;
} ic_float4;

/* How the tree sees items: sphere[i].xyz is the center, radius = sphere[i].w·normal[i].w·scale. */
typedef struct ic_octree_items {
    const ic_float4 *sphere;   /* xyz = position, w = R */
    const ic_float4 *normal;   /* w = a (unused when scale = 0) */
    float scale;               /* 0: a point tree */
} ic_octree_items;

/* Margin on sphere radii: a record accepted by the weight test in float arithmetic must be found in
 * the leaf, even when the test and the overlap test round differently. */
#define IC_OCTREE_RADIUS_MARGIN 1.0001f

/* Item i's sphere radius as the tree stores it: R·a·scale with the margin (0 for a point tree). */
static inline float ic_octree_item_radius(const ic_octree_items *it, uint32_t i)
{
    return it->scale > 0.0f ? it->sphere[i].w * it->normal[i].w * it->scale * IC_OCTREE_RADIUS_MARGIN : 0.0f;
}

/* A reference: the item's index plus a copy of its center and (conservative) radius, so a look-up
 * rejects most references from the node's contiguous segment without touching the record arrays. */
typedef struct ic_octree_ref {
    float x, y, z;             /* item center */
    float r;                   /* item radius when referenced (radii only shrink: an upper bound) */
    uint32_t index;            /* item index */
} ic_octree_ref;

typedef struct ic_octree_node {
    uint32_t child;            /* first of 8 contiguous children; 0 = leaf (the root is never a child) */
    uint32_t begin;            /* leaf: first reference in refs */
    uint32_t count;            /* leaf: references in use */
    uint32_t cap;              /* leaf: references reserved */
} ic_octree_node;

typedef struct ic_octree {
    ic_octree_node *nodes;
    uint32_t node_count, node_cap;
    ic_octree_ref *refs;       /* references, one segment per node */
    size_t ref_end, ref_cap;   /* used / allocated length of refs */
    size_t ref_live;           /* sum of the segments' capacities (the rest of ref_end is dead) */
    float cx, cy, cz, half;    /* root cube: center and half side */
    int has_root;
    uint32_t leaf_capacity, max_depth;
    int threads;               /* ic_octree_build's threads (0: all cores); the tree does not depend on them */
} ic_octree;

/* Empty tree. */
void ic_octree_init(ic_octree *t, uint32_t leaf_capacity, uint32_t max_depth);
/* Frees the tree's arrays (the tree may be re-initialised). */
void ic_octree_free(ic_octree *t);
/* Adds item `index`; items 0…index−1 must already be in the tree (the root grows by rebuilding). */
ic_result ic_octree_insert(ic_octree *t, const ic_octree_items *items, uint32_t index);
/* Empties the tree and builds it top-down from items 0…count−1 under a root fitted to all of them:
 * the tree insertion would grow, except that a sphere as large as a child stays in the node it was
 * handed to (insertion into a node split earlier sends it down one level). IC_ERR_INVALID_ARG, the tree
 * unchanged, where the root's bounds are not finite floats. */
ic_result ic_octree_build(ic_octree *t, const ic_octree_items *items, uint32_t count);
/* Removes the references to items first… from every node, in place (allocates nothing, so it cannot
 * fail): what a failed insertion leaves when the tree cannot be built again. */
void ic_octree_drop_from(ic_octree *t, uint32_t first);
/* Compacts the reference array if more than half of it is dead. */
ic_result ic_octree_compact(ic_octree *t);
/* Bytes held by the tree. */
size_t ic_octree_bytes(const ic_octree *t);

/* Nodes on the root-to-leaf path through p (stackless descent), root first; returns how many
 * (0 when p lies outside the root cube). path must hold IC_OCTREE_MAX_DEPTH + 1 entries. */
static inline uint32_t ic_octree_path(const ic_octree *t, float px, float py, float pz, uint32_t *path)
{
    float cx = t->cx, cy = t->cy, cz = t->cz, h = t->half;
    if (!t->has_root || !(px >= cx - h && px <= cx + h && py >= cy - h && py <= cy + h && pz >= cz - h &&
                          pz <= cz + h))
        return 0;
    uint32_t node = 0, len = 0;
    const ic_octree_node *nodes = t->nodes;
    path[len++] = 0;
    while (nodes[node].child) {
        /* The same centre arithmetic as insertion (ic_octree_child_cell), so a point always
         * follows the cells its references were distributed to. */
        h *= 0.5f;
        unsigned ox = px >= cx, oy = py >= cy, oz = pz >= cz;
        cx = ox ? cx + h : cx - h;
        cy = oy ? cy + h : cy - h;
        cz = oz ? cz + h : cz - h;
        node = nodes[node].child + (ox | oy << 1 | oz << 2);
        path[len++] = node;
    }
    return len;
}

/* A node's cube (the descent's arithmetic: centre and half side) and its cell, the closed box
 * [lo, hi] of the points the descent sends into it: the root's [c − h, c + h], narrowed at every level
 * by the parent's centre, exactly the threshold the descent compares with. A child's centre c ± h/2
 * is rounded, so c ± h rebuilt from it can miss the true cell by half an ulp of the coordinate —
 * more than a small sphere's radius margin covers far from the origin; the cell never does. */
typedef struct ic_octree_cell {
    float cx, cy, cz, h;
    float lo[3], hi[3];
} ic_octree_cell;

static inline ic_octree_cell ic_octree_root_cell(float cx, float cy, float cz, float h)
{
    ic_octree_cell c = {cx, cy, cz, h, {cx - h, cy - h, cz - h}, {cx + h, cy + h, cz + h}};
    return c;
}

static inline ic_octree_cell ic_octree_child_cell(const ic_octree_cell *parent, unsigned octant)
{
    ic_octree_cell c = *parent;
    c.h = parent->h * 0.5f;
    float centre[3] = {parent->cx, parent->cy, parent->cz};
    float *mid[3] = {&c.cx, &c.cy, &c.cz};
    for (int a = 0; a < 3; ++a) {
        int upper = (octant >> a) & 1;
        /* Exactly the descent's update (ic_octree_path). */
        *mid[a] = upper ? centre[a] + c.h : centre[a] - c.h;
        /* The descent goes up iff p ≥ centre: intersect the constraint into the cell. */
        if (upper)
            c.lo[a] = centre[a] > c.lo[a] ? centre[a] : c.lo[a];
        else
            c.hi[a] = centre[a] < c.hi[a] ? centre[a] : c.hi[a];
    }
    return c;
}

/* Squared distance from (x, y, z) to the cell (0 inside), with the weight test's operation order:
 * for p in the cell the rounded result is at most the rounded |p − (x, y, z)|² (ic_dist2). */
static inline float ic_octree_cell_dist2(const ic_octree_cell *cl, float x, float y, float z)
{
    float p[3] = {x, y, z}, e[3];
    for (int a = 0; a < 3; ++a) {
        float below = cl->lo[a] - p[a], above = p[a] - cl->hi[a];
        e[a] = below > 0.0f ? below : (above > 0.0f ? above : 0.0f);
    }
    return e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
}

/* Squared distance in float, computed one way everywhere (queries and brute-force checks agree). */
static inline float ic_dist2(float ax, float ay, float az, float bx, float by, float bz)
{
    float dx = ax - bx, dy = ay - by, dz = az - bz;
    return dx * dx + dy * dy + dz * dz;
}

/* Point tree: the k nearest items to p by (distance², index), nearest first; returns how many. */
uint32_t ic_octree_knn(const ic_octree *t, const ic_octree_items *items, ic_vec3 p, uint32_t k, uint32_t *idx,
                       float *d2);
/* Point tree: items with distance² < radius²; writes up to capacity, returns the total. */
uint32_t ic_octree_radius(const ic_octree *t, const ic_octree_items *items, ic_vec3 p, float radius,
                          uint32_t *idx, uint32_t capacity);

#endif
