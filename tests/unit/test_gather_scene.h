/*
 * test_gather_scene.h — the analytic scene the gather tests share: emitting or black rectangles in any
 * orientation, a sky that may be lit only on one side of a plane, and Lambert's polygon formula for
 * exact irradiance.
 *
 *   E(p, n) = L/2 · |Σ_i angle(a_i, a_i+1) · n · normalize(a_i × a_i+1)|,  a_i = v_i − p
 *
 * for an unoccluded polygon of radiance L entirely above the tangent plane. Finite differences of it in p
 * and n are the exact gradients and Hessians (central differences, error O(δ²)).
 */
#ifndef IC_TEST_GATHER_SCENE_H
#define IC_TEST_GATHER_SCENE_H

#include "irrcache/gather.h"

#include "core/vecmath.h"
#include "test_util.h"

#include <string.h>

static const double GS_PI = 3.14159265358979323846;

typedef struct gs_rect {
    ic_vec3 corner, e1, e2;   /* e1 ⟂ e2 */
    ic_vec3 emit;
} gs_rect;

typedef struct gs_scene {
    gs_rect rects[16];
    int n_rects;
    ic_vec3 sky;              /* radiance of a miss */
    int sky_half;             /* non-zero: the sky is lit only where dir · sky_axis > 0 */
    ic_vec3 sky_axis;
} gs_scene;

static inline void gs_trace(void *user, const ic_vec3 *org, const ic_vec3 *dir, uint32_t count, float *hit_dist,
                     ic_vec3 *radiance)
{
    const gs_scene *s = user;
    for (uint32_t r = 0; r < count; ++r) {
        float best = INFINITY;
        ic_vec3 L = s->sky;
        if (s->sky_half && !(v3_dot(dir[r], s->sky_axis) > 0.0f))
            L = v3s(0.0f);
        for (int i = 0; i < s->n_rects; ++i) {
            const gs_rect *q = &s->rects[i];
            ic_vec3 nrm = v3_cross(q->e1, q->e2);
            float dn = v3_dot(dir[r], nrm);
            if (dn == 0.0f)
                continue;
            float t = v3_dot(v3_sub(q->corner, org[r]), nrm) / dn;
            if (!(t > 1e-6f) || t >= best)
                continue;
            ic_vec3 h = v3_sub(v3_madd(org[r], dir[r], t), q->corner);
            float a = v3_dot(h, q->e1) / v3_len2(q->e1), b = v3_dot(h, q->e2) / v3_len2(q->e2);
            if (a < 0.0f || a > 1.0f || b < 0.0f || b > 1.0f)
                continue;
            best = t;
            L = q->emit;
        }
        hit_dist[r] = best;
        radiance[r] = L;
    }
}

/* Irradiance at (p, n) from a convex polygon of unit radiance above the tangent plane (double). */
static inline double gs_polygon_irradiance(const double (*v)[3], int count, const double p[3], const double n[3])
{
    double sum = 0.0;
    for (int i = 0; i < count; ++i) {
        double a[3], b[3];
        for (int k = 0; k < 3; ++k) {
            a[k] = v[i][k] - p[k];
            b[k] = v[(i + 1) % count][k] - p[k];
        }
        double la = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]), lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
        double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
        double lc = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        double ang = atan2(lc, a[0] * b[0] + a[1] * b[1] + a[2] * b[2]);
        (void)la;
        (void)lb;
        sum += ang * (c[0] * n[0] + c[1] * n[1] + c[2] * n[2]) / lc;
    }
    return 0.5 * fabs(sum);
}

/* The rectangle's four corners in double. */
static inline void gs_rect_corners(const gs_rect *q, double v[4][3])
{
    const ic_vec3 c[4] = {q->corner, v3_add(q->corner, q->e1), v3_add(v3_add(q->corner, q->e1), q->e2),
                          v3_add(q->corner, q->e2)};
    for (int i = 0; i < 4; ++i) {
        v[i][0] = c[i].x;
        v[i][1] = c[i].y;
        v[i][2] = c[i].z;
    }
}

static inline double gs_rect_irradiance(const gs_rect *q, const double p[3], const double n[3])
{
    double v[4][3];
    gs_rect_corners(q, v);
    return gs_polygon_irradiance((const double(*)[3])v, 4, p, n);
}

static inline ic_gatherer *gs_gatherer(const ic_gather_opts *o, gs_scene *s)
{
    ic_gatherer *g = NULL;
    ic_error err;
    ic_result r = ic_gatherer_create(o, gs_trace, s, &g, &err);
    CHECK(r == IC_OK, "ic_gatherer_create: %s", r == IC_OK ? "" : err.message);
    return g;
}

/* One gather with the gatherer's own method (stratified or hemicube). */
static inline ic_gather_result gs_gather(ic_gatherer *g, ic_vec3 p, ic_vec3 n, uint64_t key)
{
    ic_gather_point pt = {p, n, key};
    ic_gather_result r;
    memset(&r, 0x5A, sizeof r);
    ic_result res = ic_gatherer_opts(g)->method == IC_GATHER_HEMICUBE ? ic_gather_hemicube(g, &pt, &r)
                                                                       : ic_gather_stratified(g, &pt, &r);
    CHECK(res == IC_OK, "gather: %s", ic_result_name(res));
    return r;
}

static inline double gs_len(ic_vec3 v) { return sqrt((double)v3_dot(v, v)); }

/* Rodrigues, axis ⟂ n: n cos a + (axis × n) sin a. */
static inline ic_vec3 gs_rotate_normal(ic_vec3 n, ic_vec3 axis, float a)
{
    return v3_add(v3_scale(n, cosf(a)), v3_scale(v3_cross(axis, n), sinf(a)));
}

#endif
