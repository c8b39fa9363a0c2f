/*
 * accel.h — ray tracing against the scene. The only module that talks to Embree (accel.c includes
 * <embree3/rtcore.h>; nothing else may). Hits come back as the renderer's own ic_hit.
 *
 * Robustness: the BVH is built with RTC_SCENE_FLAG_ROBUST (no rays slipping through shared edges),
 * and secondary rays start from ic_offset_ray_origin(), which moves the origin off
 * the surface along the geometric normal by an amount that scales with the coordinates' magnitude
 * (Wächter & Binder, "A Fast and Robust Method for Avoiding Self-Intersection", Ray Tracing Gems
 * ch. 6), so there is neither acne nor light leaking through corners.
 *
 * Ray counting is the caller's job (per-thread counters), to keep atomics off the per-ray path.
 */
#ifndef IC_GEOM_ACCEL_H
#define IC_GEOM_ACCEL_H

#include "scene/scene.h"

typedef struct ic_accel ic_accel;

/* A ray: origin, unit direction, [tnear, tfar]. */
typedef struct ic_ray {
    ic_vec3 org, dir;
    float tnear, tfar;
} ic_ray;

/* Hit record: triangle index (UINT32_MAX on a miss), distance, Embree barycentrics. */
typedef struct ic_hit {
    uint32_t triangle;
    float t;
    float u, v;
} ic_hit;

#define IC_NO_HIT UINT32_MAX

/* Builds the acceleration structure over scene (which must outlive it). */
ic_result ic_accel_create(const ic_scene *scene, ic_accel **out, ic_error *err);
/* Releases it (NULL is a no-op). */
void ic_accel_destroy(ic_accel *accel);
/* Closest hit of one ray. */
void ic_accel_intersect1(const ic_accel *accel, const ic_ray *ray, ic_hit *hit);
/* 1 if anything blocks the ray within (tnear, tfar). */
int ic_accel_occluded1(const ic_accel *accel, const ic_ray *ray);
/* Closest hits of many rays at once (Embree ray stream, coherent flag when `coherent`). */
void ic_accel_intersect_n(const ic_accel *accel, const ic_ray *rays, ic_hit *hits, uint32_t count, int coherent);
/* Occlusion of many rays at once; occluded[i] = 1 if blocked. */
void ic_accel_occluded_n(const ic_accel *accel, const ic_ray *rays, uint8_t *occluded, uint32_t count, int coherent);

/* Origin moved off a surface at p with geometric normal ng towards the side of direction dir: by 256 ulps of
 * each coordinate (Wächter & Binder), and by at least `floor` near the origin of coordinates, where ulps
 * vanish but the intersection's error does not (it follows the triangles' own coordinates). Below
 * |p_i| = 2^11·floor the floor is taken (Wächter & Binder's 1/32 and 1/65536 for a floor of 2^-16; 256 ulps
 * there are a sixteenth of the floor, so the move jumps at that threshold, as in their method). With the scene's floor
 * (ic_scene.ray_offset_floor), a scene smaller than one unit moves its origins in proportion to its size:
 * with the fixed floor of 1/65536, a Cornell box 2 cm across lost 11 % of its light, its floor point's shadow
 * rays ending on the lamp and the lamp's neighbourhood gaining 15 µm offsets in a 100 µm gap. */
static inline ic_vec3 ic_offset_ray_origin_floor(ic_vec3 p, ic_vec3 ng, ic_vec3 dir, float floor)
{
    const float origin_eps = 2048.0f * floor, int_scale = 256.0f;
    ic_vec3 n = v3_dot(ng, dir) < 0.0f ? v3_neg(ng) : ng;
    float pc[3] = {p.x, p.y, p.z}, nc[3] = {n.x, n.y, n.z}, out[3];
    for (int i = 0; i < 3; ++i) {
        int of = (int)(int_scale * nc[i]);
        union { float f; int32_t i; } u;
        u.f = pc[i];
        u.i += (pc[i] < 0.0f) ? -of : of;
        out[i] = fabsf(pc[i]) < origin_eps ? pc[i] + floor * nc[i] : u.f;
    }
    return v3(out[0], out[1], out[2]);
}

/* The same with the floor of a scene of unit size or more. */
static inline ic_vec3 ic_offset_ray_origin(ic_vec3 p, ic_vec3 ng, ic_vec3 dir)
{
    return ic_offset_ray_origin_floor(p, ng, dir, IC_RAY_OFFSET_FLOOR);
}

/* A shadow ray from p (geometric normal ng; origin offset floor `floor`) towards a point `dist` away along the
 * unit direction dir, stopping short of it by the fraction `shy` of the distance left. The distance is
 * counted from the offset origin: near the origin of coordinates the offset's floor can exceed a fraction
 * of the distance to the light, and a ray that kept the full `dist` reached the light's own surface and was
 * blocked by it (the floor of a 6 cm Cornell box lost nearly all its direct light). */
static inline ic_ray ic_shadow_ray_to(ic_vec3 p, ic_vec3 ng, ic_vec3 dir, float dist, float shy, float floor)
{
    ic_ray r;
    r.org = ic_offset_ray_origin_floor(p, ng, dir, floor);
    r.dir = dir;
    r.tnear = 0.0f;
    if (isinf(dist)) {
        r.tfar = INFINITY;
    } else {
        const float left = dist - v3_dot(v3_sub(r.org, p), dir); /* the offset moved the origin this far on */
        r.tfar = (left > 0.0f ? left : 0.0f) * (1.0f - shy);
    }
    return r;
}

#endif
