/*
 * tessellate.h — the analytic shapes scene files name (spheres, disks and rings, cones and cylinders) as
 * triangles, for a scene that holds only triangles, shared by the Mitsuba and Radiance readers; and polygons
 * as triangles that keep their outline (mesh files' faces of more than three vertices).
 *
 * Accuracy: IC_TESS_SEGMENTS segments around every circle and IC_TESS_RINGS latitude bands on a sphere,
 * vertices on the true surface. The chord then departs from the circle by at most r·(1 − cos(π/64)) =
 * 0.0012·r; a ring's or a cylinder's area is sin(2π/64)/(2π/64) = 99.84 % of the true one and a sphere's
 * 99.6 % (docs/scene-format.md). Spheres, cones and cylinders carry the true surface normal at every
 * vertex, so their shading is smooth; disks and rings are flat.
 *
 * Each function writes into caller-provided arrays of IC_TESS_MAX_VERTICES positions (and normals) and
 * IC_TESS_MAX_TRIANGLES × 3 indices, and returns the vertex and triangle counts. Triangles wind
 * counter-clockwise seen from the side the surface faces (the outside of a sphere or cone, +axis of a
 * disk).
 */
#ifndef IC_SCENE_TESSELLATE_H
#define IC_SCENE_TESSELLATE_H

#include "core/vecmath.h"

#include <stdint.h>

#define IC_TESS_SEGMENTS 64
#define IC_TESS_RINGS 32
#define IC_TESS_MAX_VERTICES ((IC_TESS_RINGS + 1) * (IC_TESS_SEGMENTS + 1))
#define IC_TESS_MAX_TRIANGLES (2 * IC_TESS_RINGS * IC_TESS_SEGMENTS)

/* A sphere as a latitude-longitude mesh about +z, with outward unit normals in n; the polar bands are fans
 * about the exact poles (no triangle of zero area). */
void ic_tess_sphere(ic_vec3 centre, float radius, ic_vec3 *p, ic_vec3 *n, uint32_t *tri, uint32_t *vertex_count,
                    uint32_t *tri_count);
/* A flat ring between radii r0 < r1 about centre in the plane spanned by the orthonormal u, v; facing
 * u × v. r0 = 0 gives a disk: a fan around the centre. */
void ic_tess_ring(ic_vec3 centre, ic_vec3 u, ic_vec3 v, float r0, float r1, ic_vec3 *p, uint32_t *tri,
                  uint32_t *vertex_count, uint32_t *tri_count);
/* The side of a truncated cone from p0 (radius r0) to p1 (radius r1), open at both ends, with outward
 * unit normals in n; one radius may be 0 (a point cone), equal radii give a cylinder. */
void ic_tess_cone(ic_vec3 p0, ic_vec3 p1, float r0, float r1, ic_vec3 *p, ic_vec3 *n, uint32_t *tri,
                  uint32_t *vertex_count, uint32_t *tri_count);
/* An orthonormal u, v with u × v = the unit vector a. */
void ic_tess_basis(ic_vec3 a, ic_vec3 *u, ic_vec3 *v);
/* A simple polygon of nv vertices p (planar or nearly so, either winding) as at most nv − 2 triangles (*tri_count
 * of them) that keep its outline: a fan from the first vertex when it is convex, else ear clipping (Meisters
 * 1975). A vertex met twice (the seam that joins a hole to the outline) is handled. Triangles of zero area (a
 * vertex on an edge, one repeated) are left out of a polygon that has others; a polygon with no other keeps
 * them, for the scene to drop and report. tri (3·(nv − 2) indices into p) gets them, idx (nv) is scratch.
 * Returns 0 if part of a concave polygon had to be a fan (self-intersecting, or over IC_TESS_EAR_MAX_VERTICES
 * vertices). */
#define IC_TESS_EAR_MAX_VERTICES 4096
int ic_tess_polygon(const ic_vec3 *p, uint32_t nv, uint32_t *idx, uint32_t *tri, uint32_t *tri_count);
/* Turns every triangle over (and the normals, when n is not NULL). */
void ic_tess_flip(ic_vec3 *n, uint32_t vertex_count, uint32_t *tri, uint32_t tri_count);

#endif
