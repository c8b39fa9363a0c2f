/*
 * octree.h — flat octree over records: the multiple-reference sphere octree of the irradiance cache
 * and the auxiliary point octree for k-nearest and radius queries (seed 004 §4.2–4.3).
 *
 * One structure serves both (STYLE.md: one routine, not two variants). Items are spheres
 * (center, radius = R·a·scale); a point tree is the special case scale = 0. A sphere is referenced
 * from every leaf whose cube it overlaps, so finding all spheres that contain p is a single stackless
 * descent from the root to the leaf holding p, then a loop over that leaf's references
 * (seed 004 §4.3). Nodes live in one array; the 8 children of a node are contiguous and found by
 * index; each leaf owns a segment [begin, begin+count) of one reference array (capacity cap, segments
 * move to the end of the array when they grow, and the array is compacted when more than half of it
 * is dead). Leaves split when they hold more than leaf_capacity references, the depth limit is not
 * reached and at least half of the references only partly cover the leaf — splitting a leaf whose
 * spheres all cover it entirely would copy every reference into all 8 children and gain nothing.
 */
#ifndef IC_CACHE_OCTREE_H
#define IC_CACHE_OCTREE_H

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

typedef struct ic_octree_node {
    uint32_t child;            /* first of 8 contiguous children; 0 = leaf (the root is never a child) */
    uint32_t begin;            /* leaf: first reference in refs */
    uint32_t count;            /* leaf: references in use */
    uint32_t cap;              /* leaf: references reserved */
} ic_octree_node;

typedef struct ic_octree {
    ic_octree_node *nodes;
    uint32_t node_count, node_cap;
    uint32_t *refs;            /* item indices, one segment per leaf */
    size_t ref_end, ref_cap;   /* used / allocated length of refs */
    size_t ref_live;           /* sum of leaf capacities (the rest of ref_end is dead) */
    float cx, cy, cz, half;    /* root cube: center and half side */
    int has_root;
    uint32_t leaf_capacity, max_depth;
} ic_octree;

/* Empty tree. */
void ic_octree_init(ic_octree *t, uint32_t leaf_capacity, uint32_t max_depth);
/* Frees the tree's arrays (the tree may be re-initialised). */
void ic_octree_free(ic_octree *t);
/* Adds item `index`; items 0…index−1 must already be in the tree (the root grows by rebuilding). */
ic_result ic_octree_insert(ic_octree *t, const ic_octree_items *items, uint32_t index);
/* Empties the tree and inserts items 0…count−1 under a root fitted to all of them. */
ic_result ic_octree_build(ic_octree *t, const ic_octree_items *items, uint32_t count);
/* Compacts the reference array if more than half of it is dead. */
ic_result ic_octree_compact(ic_octree *t);
/* Bytes held by the tree. */
size_t ic_octree_bytes(const ic_octree *t);

/* Leaf whose cube holds p (stackless root-to-leaf descent), or IC_OCTREE_NONE outside the root. */
static inline uint32_t ic_octree_find_leaf(const ic_octree *t, float px, float py, float pz)
{
    float cx = t->cx, cy = t->cy, cz = t->cz, h = t->half;
    if (!t->has_root || !(px >= cx - h && px <= cx + h && py >= cy - h && py <= cy + h && pz >= cz - h &&
                          pz <= cz + h))
        return IC_OCTREE_NONE;
    uint32_t node = 0;
    const ic_octree_node *nodes = t->nodes;
    while (nodes[node].child) {
        /* The same child-cube arithmetic as the split (octree.c: child_center), so a point always
         * lands in the leaf its references were distributed to. */
        h *= 0.5f;
        unsigned ox = px >= cx, oy = py >= cy, oz = pz >= cz;
        cx = ox ? cx + h : cx - h;
        cy = oy ? cy + h : cy - h;
        cz = oz ? cz + h : cz - h;
        node = nodes[node].child + (ox | oy << 1 | oz << 2);
    }
    return node;
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
