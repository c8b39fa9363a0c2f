/*
 * ic_world.h — the world-space stage of Frolov et al. 2012 §3.1.3: hit points where no
 * record is valid (collected on every bounce of eye paths) are sorted along a 3-D Morton (Z) curve,
 * cut into clusters whose bounding box stays under a size limit, and from each cluster a few
 * candidates with distinct normals are kept, so a cluster spanning a corner yields one candidate
 * per wall.
 */
#ifndef IC_INTEGRATORS_IC_WORLD_H
#define IC_INTEGRATORS_IC_WORLD_H

#include "irrcache/comm.h"
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
 * cand and puts their number in *kept (deterministic for any input order). IC_ERR_OOM (cand untouched,
 * *kept 0) when the sort finds no memory: a caller must not take that for "none kept", since under
 * several processes the others would go on to an exchange this one skips. */
ic_result ic_world_select(ic_candidate *cand, uint32_t count, ic_vec3 lo, ic_vec3 hi, float max_box,
                          int per_cluster, float normal_angle_deg, uint32_t *kept);

/* The steps of ic_world_select, for processes that each hold a stretch of the Morton order.
 * ic_world_sort: cand in (Morton code, key) order; 0 if out of memory (cand untouched).
 * ic_world_gap: 1 if consecutive candidates at a and b can never share a cluster (a box holding both is
 * wider than max_box, computed as the clustering computes it), so that the clustering starts a new one at
 * b whatever came before.
 * ic_world_cluster: clusters sorted[0, count) as ic_world_select does and compacts the kept candidates to
 * the front of sorted; returns their number. A cluster must start at sorted[0] (the order's start, or just
 * after a gap) and at whatever follows sorted[count − 1] (the order's end, or a gap).
 */
int ic_world_sort(ic_candidate *cand, uint32_t count, ic_vec3 lo, ic_vec3 hi);
int ic_world_gap(ic_vec3 a, ic_vec3 b, float max_box);
uint32_t ic_world_cluster(ic_candidate *sorted, uint32_t count, float max_box, int per_cluster, float normal_angle_deg);

/* ic_world_select over the candidates of several processes (comm), without any process holding them
 * all. Each process takes a range of the Morton order (contiguous ranges of the code's top bits, balanced
 * by the candidates' counts, which every process publishes), receives that range's candidates (all-to-all)
 * and sorts them. Clusters cannot cross a gap (ic_world_gap), so each run of candidates from one gap to the
 * next is clustered by the process where it begins, with the candidates of the following processes up to
 * their first gap (which every process publishes). The kept candidates come back on every process in the
 * order ic_world_select gives for all the candidates at once: *out (malloc'd), *kept. own (own_count, this
 * process's share, malloc'd) is taken over: freed, or for one process selected in place and returned as
 * *out. *total gets the candidates' number over all processes; *visited (this process's count in, the sum
 * out) rides on the same exchange. */
ic_result ic_world_select_shared(ic_comm *comm, ic_candidate *own, uint32_t own_count, ic_vec3 lo, ic_vec3 hi,
                                 float max_box, int per_cluster, float normal_angle_deg, ic_candidate **out,
                                 uint32_t *kept, uint64_t *total, double *visited, ic_error *err);

#endif
