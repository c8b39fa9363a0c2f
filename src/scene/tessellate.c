/*
 * tessellate.c — spheres, rings and cones as triangles, and polygons as triangles that keep their outline
 * (tessellate.h).
 */
#include "scene/tessellate.h"

#include <math.h>
#include <string.h>

void ic_tess_sphere(ic_vec3 centre, float radius, ic_vec3 *p, ic_vec3 *n, uint32_t *tri, uint32_t *vertex_count,
                    uint32_t *tri_count)
{
    uint32_t nv = 0, nt = 0;
    for (int j = 0; j <= IC_TESS_RINGS; ++j)
        for (int i = 0; i <= IC_TESS_SEGMENTS; ++i) {
            float th = IC_PI * j / IC_TESS_RINGS, ph = 2.0f * IC_PI * i / IC_TESS_SEGMENTS;
            float st = j == 0 || j == IC_TESS_RINGS ? 0.0f : sinf(th); /* the poles exactly (sinf(π) is not 0) */
            ic_vec3 d = v3(st * cosf(ph), st * sinf(ph), cosf(th));
            n[nv] = d;
            p[nv++] = v3_add(centre, v3_scale(d, radius));
        }
    /* Each band is quads of two triangles, but a polar band's quads are triangles: the half with two
     * corners at the pole has no area and is left out (not a sliver of the user's for the scene to drop). */
    for (int j = 0; j < IC_TESS_RINGS; ++j)
        for (int i = 0; i < IC_TESS_SEGMENTS; ++i) {
            uint32_t a = j * (IC_TESS_SEGMENTS + 1) + i, b = a + IC_TESS_SEGMENTS + 1;
            const uint32_t t[2][3] = {{a, b, a + 1}, {a + 1, b, b + 1}}; /* outward winding */
            for (int h = 0; h < 2; ++h) {
                if ((h == 0 && j == 0) || (h == 1 && j == IC_TESS_RINGS - 1))
                    continue;
                for (int k = 0; k < 3; ++k)
                    tri[3 * nt + k] = t[h][k];
                ++nt;
            }
        }
    *vertex_count = nv;
    *tri_count = nt;
}

void ic_tess_ring(ic_vec3 centre, ic_vec3 u, ic_vec3 v, float r0, float r1, ic_vec3 *p, uint32_t *tri,
                  uint32_t *vertex_count, uint32_t *tri_count)
{
    uint32_t nv = 0, nt = 0;
    const int seg = IC_TESS_SEGMENTS;
    if (r0 <= 0.0f) {
        p[nv++] = centre;
        for (int i = 0; i < seg; ++i) {
            float a = 2.0f * IC_PI * i / seg;
            p[nv++] = v3_add(centre, v3_add(v3_scale(u, r1 * cosf(a)), v3_scale(v, r1 * sinf(a))));
            tri[3 * nt] = 0;
            tri[3 * nt + 1] = 1 + i;
            tri[3 * nt + 2] = 1 + (i + 1) % seg;
            ++nt;
        }
    } else {
        for (int i = 0; i < seg; ++i) { /* inner vertex 2i, outer 2i + 1 */
            float a = 2.0f * IC_PI * i / seg;
            ic_vec3 e = v3_add(v3_scale(u, cosf(a)), v3_scale(v, sinf(a)));
            p[nv++] = v3_add(centre, v3_scale(e, r0));
            p[nv++] = v3_add(centre, v3_scale(e, r1));
            uint32_t i0 = 2 * i, o0 = i0 + 1, i1 = 2 * ((i + 1) % seg), o1 = i1 + 1;
            uint32_t t[6] = {i0, o0, o1, i0, o1, i1};
            for (int k = 0; k < 6; ++k)
                tri[3 * nt + k] = t[k];
            nt += 2;
        }
    }
    *vertex_count = nv;
    *tri_count = nt;
}

void ic_tess_basis(ic_vec3 a, ic_vec3 *u, ic_vec3 *v)
{
    ic_vec3 helper = fabsf(a.x) < 0.9f ? v3(1.0f, 0.0f, 0.0f) : v3(0.0f, 1.0f, 0.0f);
    *u = v3_norm(v3_cross(helper, a));
    *v = v3_cross(a, *u);
}

void ic_tess_cone(ic_vec3 p0, ic_vec3 p1, float r0, float r1, ic_vec3 *p, ic_vec3 *n, uint32_t *tri,
                  uint32_t *vertex_count, uint32_t *tri_count)
{
    ic_vec3 axis = v3_sub(p1, p0);
    float h = v3_len(axis);
    ic_vec3 a = v3_scale(axis, 1.0f / h), u, v;
    ic_tess_basis(a, &u, &v);
    uint32_t nv = 0, nt = 0;
    const int seg = IC_TESS_SEGMENTS;
    for (int i = 0; i <= seg; ++i) { /* bottom vertex 2i, top 2i + 1 */
        float ang = 2.0f * IC_PI * i / seg;
        ic_vec3 e = v3_add(v3_scale(u, cosf(ang)), v3_scale(v, sinf(ang)));
        /* the side's normal leans towards the end whose radius is smaller */
        ic_vec3 nrm = v3_norm(v3_add(v3_scale(e, h), v3_scale(a, r0 - r1)));
        n[nv] = nrm;
        p[nv++] = v3_add(p0, v3_scale(e, r0));
        n[nv] = nrm;
        p[nv++] = v3_add(p1, v3_scale(e, r1));
    }
    for (int i = 0; i < seg; ++i) {
        uint32_t b0 = 2 * i, t0 = b0 + 1, b1 = b0 + 2, t1 = b0 + 3;
        if (r0 > 0.0f) { /* no sliver triangles at a point end */
            tri[3 * nt] = b0;
            tri[3 * nt + 1] = b1;
            tri[3 * nt + 2] = t1;
            ++nt;
        }
        if (r1 > 0.0f) {
            tri[3 * nt] = b0;
            tri[3 * nt + 1] = t1;
            tri[3 * nt + 2] = t0;
            ++nt;
        }
    }
    *vertex_count = nv;
    *tri_count = nt;
}

void ic_tess_flip(ic_vec3 *n, uint32_t vertex_count, uint32_t *tri, uint32_t tri_count)
{
    for (uint32_t t = 0; t < tri_count; ++t) {
        uint32_t s = tri[3 * t + 1];
        tri[3 * t + 1] = tri[3 * t + 2];
        tri[3 * t + 2] = s;
    }
    for (uint32_t i = 0; n && i < vertex_count; ++i)
        n[i] = v3_neg(n[i]);
}

/* 1 if r lies strictly inside the angle of triangle corner x, between its edges to the next corner n and
 * from the previous corner pv, about the normal nrm: an edge leaving x towards r enters the triangle. */
static int enters_corner(ic_vec3 pv, ic_vec3 x, ic_vec3 n, ic_vec3 r, ic_vec3 nrm)
{
    ic_vec3 d = v3_sub(r, x);
    return v3_dot(v3_cross(v3_sub(n, x), d), nrm) > 0.0f && v3_dot(v3_cross(v3_sub(x, pv), d), nrm) > 0.0f;
}

/* 1 if vertex b of the polygon turn a→b→c is convex about the polygon's normal nrm and no other vertex
 * lies in the triangle abc (an ear; Meisters 1975). A vertex at one of the corners is the outline passing
 * through that point again, as it does at both ends of the seam that joins a hole to the outline: it is no
 * obstacle unless one of its two edges enters the triangle there. */
static int is_ear(const ic_vec3 *p, const uint32_t *idx, uint32_t count, uint32_t k, ic_vec3 nrm)
{
    ic_vec3 a = p[idx[(k + count - 1) % count]], b = p[idx[k]], cc = p[idx[(k + 1) % count]];
    if (!(v3_dot(v3_cross(v3_sub(b, a), v3_sub(cc, b)), nrm) > 0.0f))
        return 0;
    const ic_vec3 corner[3] = {a, b, cc};
    for (uint32_t j = 0; j < count; ++j) {
        if (j == k || j == (k + 1) % count || j == (k + count - 1) % count)
            continue;
        ic_vec3 q = p[idx[j]];
        int at = -1;
        for (int m = 0; m < 3; ++m)
            if (q.x == corner[m].x && q.y == corner[m].y && q.z == corner[m].z)
                at = m;
        if (at >= 0) {
            ic_vec3 pv = corner[(at + 2) % 3], x = corner[at], n = corner[(at + 1) % 3];
            if (enters_corner(pv, x, n, p[idx[(j + count - 1) % count]], nrm) ||
                enters_corner(pv, x, n, p[idx[(j + 1) % count]], nrm))
                return 0;
            continue;
        }
        if (v3_dot(v3_cross(v3_sub(b, a), v3_sub(q, a)), nrm) >= 0.0f &&
            v3_dot(v3_cross(v3_sub(cc, b), v3_sub(q, b)), nrm) >= 0.0f &&
            v3_dot(v3_cross(v3_sub(a, cc), v3_sub(q, cc)), nrm) >= 0.0f)
            return 0;
    }
    return 1;
}

int ic_tess_polygon(const ic_vec3 *p, uint32_t nv, uint32_t *idx, uint32_t *tri, uint32_t *tri_count)
{
    ic_vec3 nrm = v3s(0.0f); /* Newell's normal: the polygon's area vector */
    for (uint32_t i = 0; i < nv; ++i)
        nrm = v3_add(nrm, v3_cross(p[i], p[(i + 1) % nv]));
    int convex = 1;
    for (uint32_t i = 0; i < nv && convex; ++i)
        convex = v3_dot(v3_cross(v3_sub(p[(i + 1) % nv], p[i]), v3_sub(p[(i + 2) % nv], p[(i + 1) % nv])), nrm) >= 0.0f;
    uint32_t nt = 0, count = nv;
    for (uint32_t i = 0; i < nv; ++i)
        idx[i] = i;
    uint32_t k = 1, misses = 0;
    uint64_t budget = 16u * (uint64_t)nv; /* ear tests, each O(nv): O(nv²) in all */
    while (!convex && nv <= IC_TESS_EAR_MAX_VERTICES && count > 3 && misses < count && budget > 0) {
        --budget; /* ears from the second vertex on */
        k %= count;
        if (!is_ear(p, idx, count, k, nrm)) {
            ++k;
            ++misses;
            continue;
        }
        tri[3 * nt] = idx[(k + count - 1) % count];
        tri[3 * nt + 1] = idx[k];
        tri[3 * nt + 2] = idx[(k + 1) % count];
        ++nt;
        memmove(idx + k, idx + k + 1, sizeof *idx * (count - k - 1));
        --count;
        misses = 0;
    }
    int exact = convex || count == 3;
    for (uint32_t i = 1; i + 1 < count; ++i) { /* a convex polygon, or what ears could not take */
        tri[3 * nt] = idx[0];
        tri[3 * nt + 1] = idx[i];
        tri[3 * nt + 2] = idx[i + 1];
        ++nt;
    }
    /* the scene's test for a triangle without area (mesh_import.c), on the same corners in the same order */
    uint32_t kept = 0;
    for (uint32_t t = 0; t < nt; ++t) {
        ic_vec3 a = p[tri[3 * t]], cr = v3_cross(v3_sub(p[tri[3 * t + 1]], a), v3_sub(p[tri[3 * t + 2]], a));
        if (!v3_is_black(cr))
            memmove(tri + 3 * kept++, tri + 3 * t, 3 * sizeof *tri);
    }
    *tri_count = kept ? kept : nt;
    return exact;
}
