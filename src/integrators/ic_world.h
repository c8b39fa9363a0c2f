/*
 * ic_world.h — the world-space stage of Frolov et al. 2012 §3.1.3: hit points where no
 * record is valid (collected on every bounce of eye paths) are sorted along a 3-D Morton (Z) curve,
 * cut into clusters whose bounding box stays under a size limit, and from each cluster a few
 * candidates with distinct normals are kept, so a cluster spanning a corner yields one candidate
 * per wall.
 */
#ifndef IC_INTEGRATORS_IC_WORLD_H
#define IC_INTEGRATORS_IC_WORLD_H

#include "irrcache/common.h"

#include <stdint.h>

/* A world-space candidate: a shading point and a key that orders ties deterministically. */
typedef struct ic_candidate {
    ic_vec3 p, n;
    float footprint;       /* world size of a pixel for pixel-based radius clamps (0: none) */
    uint64_t key;          /* unique, e.g. (pixel << 8 | bounce) */
} ic_candidate;

/* 30-bit 3-D Morton code of p quantised in the box [lo, hi] (10 bits per axis). */
uint32_t ic_morton3(ic_vec3 p, ic_vec3 lo, ic_vec3 hi);

/* Sorts cand (count) along the Morton curve of box [lo, hi] (ties by key), clusters them with a
 * bounding-box diagonal limit max_box, and keeps at most per_cluster candidates per cluster whose
 * normals differ pairwise by more than normal_angle_deg. Compacts the kept ones to the front of
 * cand and returns their number (deterministic for any input order). */
uint32_t ic_world_select(ic_candidate *cand, uint32_t count, ic_vec3 lo, ic_vec3 hi, float max_box,
                         int per_cluster, float normal_angle_deg);

#endif
