/*
 * kdtree.h — a static k-d tree over shading points for radius queries (Křivánek et al. 2006 §4.2: "shading points
 * are stored in a k-D tree [Jen01] to quickly locate the points in a record's influence area").
 *
 * The tree is balanced and implicit (Jensen 2001, "Realistic Image Synthesis Using Photon Mapping"
 * §6.3): the points are permuted so that the median of every range is its node, split on the axis of
 * the range's largest extent; children are the two half-ranges. No node structs, no pointers: one
 * index array, one position array, one axis byte per node. Built once (shading points never move),
 * queried many times; a query allocates nothing (fixed traversal stack) and visits points through a
 * callback, so the caller decides what to do with them without a result buffer.
 *
 * Determinism: the build is a pure function of the input order (median selection without random
 * pivots), and a query visits points in an order that depends only on the tree and the query.
 */
#ifndef IC_INTEGRATORS_KDTREE_H
#define IC_INTEGRATORS_KDTREE_H

#include "core/vecmath.h"

#include <stdint.h>

typedef struct ic_kdtree {
    uint32_t count;
    uint32_t *index;       /* caller's point index of each node, in tree order */
    ic_vec3 *pos;          /* position of each node, in tree order (hot during queries) */
    uint8_t *axis;         /* split axis of each node (0 x, 1 y, 2 z) */
} ic_kdtree;

/* Called for every point within the query radius; index is the caller's point index. */
typedef void (*ic_kdtree_visit_fn)(void *user, uint32_t index);

/* Builds the tree over count points (copied). IC_ERR_OOM on allocation failure (tree left empty). */
ic_result ic_kdtree_build(ic_kdtree *t, const ic_vec3 *points, uint32_t count);
/* Frees the tree's arrays; a zeroed or freed tree is a no-op. */
void ic_kdtree_free(ic_kdtree *t);
/* Visits every point with |p − q| ≤ radius (closed ball: callers use it for conservative supersets). */
void ic_kdtree_radius(const ic_kdtree *t, ic_vec3 q, float radius, ic_kdtree_visit_fn visit, void *user);

#endif
