/*
 * vecmath.h — small inline vector math on ic_vec3 (float geometry) and orthonormal frames.
 *
 * Frames use the branchless construction of Duff et al. 2017 ("Building an Orthonormal Basis,
 * Revisited", JCGT 6(1)), which is continuous everywhere but at n.z = -1 exactly.
 */
#ifndef IC_CORE_VECMATH_H
#define IC_CORE_VECMATH_H

#include "irrcache/common.h"

#include <float.h>
#include <math.h>

#define IC_PI 3.14159265358979323846f
#define IC_INV_PI 0.31830988618379067154f

static inline ic_vec3 v3(float x, float y, float z) { ic_vec3 r = {x, y, z}; return r; }
static inline ic_vec3 v3s(float s) { return v3(s, s, s); }
static inline ic_vec3 v3_add(ic_vec3 a, ic_vec3 b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline ic_vec3 v3_sub(ic_vec3 a, ic_vec3 b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline ic_vec3 v3_mul(ic_vec3 a, ic_vec3 b) { return v3(a.x * b.x, a.y * b.y, a.z * b.z); }
static inline ic_vec3 v3_scale(ic_vec3 a, float s) { return v3(a.x * s, a.y * s, a.z * s); }
static inline ic_vec3 v3_madd(ic_vec3 a, ic_vec3 b, float s) { return v3(a.x + b.x * s, a.y + b.y * s, a.z + b.z * s); }
static inline ic_vec3 v3_neg(ic_vec3 a) { return v3(-a.x, -a.y, -a.z); }
static inline float v3_dot(ic_vec3 a, ic_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline ic_vec3 v3_cross(ic_vec3 a, ic_vec3 b)
{
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline float v3_len2(ic_vec3 a) { return v3_dot(a, a); }
static inline float v3_len(ic_vec3 a) { return sqrtf(v3_dot(a, a)); }
static inline ic_vec3 v3_norm(ic_vec3 a)
{
    float l = v3_len(a);
    return l > 0.0f ? v3_scale(a, 1.0f / l) : a;
}
/* |a| and a/|a| for a finite vector of any length: where |a|² is a normal float the plain formulas above
 * (the same bits); where it overflows or underflows (a triangle's cross product with edges beyond about
 * 4e9, or below about 1e-10) a is divided by its largest component first, so that the length and the
 * direction survive. A zero (or NaN) vector has length 0 (NaN) and direction 0. */
static inline float v3_len_any(ic_vec3 a)
{
    float l2 = v3_len2(a);
    if (l2 >= FLT_MIN && l2 <= FLT_MAX)
        return sqrtf(l2);
    float big = fmaxf(fabsf(a.x), fmaxf(fabsf(a.y), fabsf(a.z)));
    return big > 0.0f ? big * v3_len(v3(a.x / big, a.y / big, a.z / big)) : sqrtf(l2);
}
static inline ic_vec3 v3_norm_any(ic_vec3 a)
{
    float l2 = v3_len2(a);
    if (l2 >= FLT_MIN && l2 <= FLT_MAX) /* v3_norm's bits, without its second dot product */
        return v3_scale(a, 1.0f / sqrtf(l2));
    float big = fmaxf(fabsf(a.x), fmaxf(fabsf(a.y), fabsf(a.z)));
    return big > 0.0f ? v3_norm(v3(a.x / big, a.y / big, a.z / big)) : v3s(0.0f);
}
static inline ic_vec3 v3_min(ic_vec3 a, ic_vec3 b) { return v3(fminf(a.x, b.x), fminf(a.y, b.y), fminf(a.z, b.z)); }
static inline ic_vec3 v3_max(ic_vec3 a, ic_vec3 b) { return v3(fmaxf(a.x, b.x), fmaxf(a.y, b.y), fmaxf(a.z, b.z)); }
static inline float v3_maxc(ic_vec3 a) { return fmaxf(a.x, fmaxf(a.y, a.z)); }
static inline float v3_get(ic_vec3 a, int i) { return i == 0 ? a.x : (i == 1 ? a.y : a.z); }
static inline int v3_is_finite(ic_vec3 a) { return isfinite(a.x) && isfinite(a.y) && isfinite(a.z); }
static inline int v3_is_black(ic_vec3 a) { return a.x == 0.0f && a.y == 0.0f && a.z == 0.0f; }
/* Rec. 709 luminance of linear RGB. */
static inline float v3_lum(ic_vec3 c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }
static inline ic_vec3 v3_lerp(ic_vec3 a, ic_vec3 b, float t) { return v3_add(a, v3_scale(v3_sub(b, a), t)); }

/* Orthonormal frame: t, b tangents and n normal (right-handed: t × b = n). */
typedef struct ic_frame {
    ic_vec3 t, b, n;
} ic_frame;

/* Frame around unit normal n (Duff et al. 2017). */
static inline ic_frame ic_frame_from_normal(ic_vec3 n)
{
    float sign = copysignf(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float b = n.x * n.y * a;
    ic_frame f;
    f.t = v3(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    f.b = v3(b, sign + n.y * n.y * a, -n.y);
    f.n = n;
    return f;
}
/* Local (frame) coordinates → world. */
static inline ic_vec3 ic_frame_to_world(const ic_frame *f, ic_vec3 l)
{
    return v3_add(v3_add(v3_scale(f->t, l.x), v3_scale(f->b, l.y)), v3_scale(f->n, l.z));
}
/* World → local (frame) coordinates. */
static inline ic_vec3 ic_frame_to_local(const ic_frame *f, ic_vec3 w)
{
    return v3(v3_dot(w, f->t), v3_dot(w, f->b), v3_dot(w, f->n));
}

/* d rotated by deg degrees about +y, right-handed (+90° turns −z into −x): environments and skies
 * turned about the up axis. */
static inline ic_vec3 v3_rotate_y(ic_vec3 d, float deg)
{
    if (deg == 0.0f)
        return d;
    float a = deg * IC_PI / 180.0f, c = cosf(a), s = sinf(a);
    return v3(c * d.x + s * d.z, d.y, -s * d.x + c * d.z);
}

/* Reflect direction d (pointing away from the surface) about normal n. */
static inline ic_vec3 v3_reflect(ic_vec3 d, ic_vec3 n) { return v3_sub(v3_scale(n, 2.0f * v3_dot(d, n)), d); }

static inline float ic_clampf(float x, float lo, float hi) { return x < lo ? lo : (x > hi ? hi : x); }

#endif
