/*
 * tessellate.c — spheres, rings and cones as triangles (tessellate.h).
 */
#include "scene/tessellate.h"

#include <math.h>

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
