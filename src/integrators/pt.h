/*
 * pt.h — the path-traced reference (Veach 1997): next-event estimation with multiple importance
 * sampling (power heuristic), Russian roulette, a maximum depth. Also the pieces the cache
 * integrators reuse: direct light at a surface, and the radiance arriving along a ray.
 */
#ifndef IC_INTEGRATORS_PT_H
#define IC_INTEGRATORS_PT_H

#include "core/rng.h"
#include "geom/accel.h"
#include "integrators/bsdf.h"

typedef struct ic_pt_params {
    int max_depth;         /* maximum number of scattering events (default 8) */
    int rr_depth;          /* Russian roulette starts after this many bounces (default 3) */
} ic_pt_params;

/* What a tracer needs: scene, accelerator, parameters. All read-only and shared by threads. */
typedef struct ic_tracer {
    const ic_scene *scene;
    const ic_accel *accel;
    ic_pt_params pt;
} ic_tracer;

/* Radiance arriving at the ray's origin along a camera ray (path traced). *rays counts traced rays.
 * sel: light selection at the first vertex (NULL: the scene's). */
ic_vec3 ic_pt_li(const ic_tracer *tr, ic_ray ray, const ic_light_selection *sel, ic_rng *rng, uint64_t *rays);

/* Per-thread local light selection: a distribution over the emitting triangles built once per block
 * of IC_LIGHT_BLOCK × IC_LIGHT_BLOCK pixels at a deterministic point of the block (its centre pixel's
 * first surface), so that a scene's many small emitters are sampled by their contribution there, not
 * by power alone (ic_scene_local_lights). Each thread keeps the blocks of one row of a render tile. */
#define IC_LIGHT_BLOCK 4
#define IC_LIGHT_SLOTS 8
typedef struct ic_pixel_lights {
    float *buf;            /* threads × IC_LIGHT_SLOTS × (2·count + 1) floats */
    uint32_t *key;         /* per thread and slot: block + 1 whose distribution is in buf, 0 none */
    int8_t *ok;            /* per thread and slot: 1 if a local distribution exists for that block */
    uint32_t count;        /* emitting triangles (0: local selection off) */
    int threads;
    int width, height;     /* image size (blocks) */
    ic_light_selection base; /* class probabilities the local selections copy, and the triangle
                                distribution (tri_pmf; NULL: by power) they are mixed with */
} ic_pixel_lights;

/* Sets up buffers for `threads` threads and a width × height image (count 0, and no allocation, where
 * the scene has no emitting triangles or too many). Returns IC_ERR_OOM on allocation failure. */
ic_result ic_pixel_lights_init(ic_pixel_lights *pl, const ic_scene *scene, ic_light_selection base, int threads,
                               int width, int height);
void ic_pixel_lights_free(ic_pixel_lights *pl);
/* Where the distribution of pixel's block is built: the block's centre pixel. */
uint32_t ic_pixel_lights_anchor(const ic_pixel_lights *pl, uint32_t pixel);
/* Forgets the blocks this thread keeps: each is built again, its anchor ray traced again, when next needed. */
void ic_pixel_lights_forget(const ic_pixel_lights *pl, int thread);
/* 1 if the block of `pixel` needs its anchor point in this thread (call ic_pixel_lights_get next with it). */
int ic_pixel_lights_need_point(const ic_pixel_lights *pl, int thread, uint32_t pixel);
/* The selection for `pixel` in `thread`, built at (p, n) — the anchor's surface — when the block is not
 * cached; have_point 0 (no surface there) or no emitting triangles: NULL (use the base selection).
 * *out is caller storage. */
const ic_light_selection *ic_pixel_lights_get(const ic_pixel_lights *pl, const ic_scene *scene, int thread,
                                              uint32_t pixel, int have_point, ic_vec3 p, ic_vec3 n,
                                              ic_light_selection *out);

/* How a path continues from a vertex that was not the camera. */
typedef struct ic_path_start {
    int depth;             /* scattering events already made (counts towards max_depth and RR) */
    float pdf;             /* solid-angle pdf that chose the ray at the previous vertex (MIS weight of the
                              emission it finds against light sampling) */
    int is_specular;       /* the previous vertex was a delta lobe (or the camera): emission counts fully */
    int skip_first_emission; /* the first hit's emission is not counted at all (it is direct light,
                                computed elsewhere: hemisphere rays of the irradiance cache) */
    const ic_light_selection *first_sel; /* light selection at the path's first vertex (a pixel's local
                                            distribution); NULL: the scene's, as at every later vertex */
    ic_vec3 *levels;       /* optional (NULL: none), max_depth − depth + 1 entries: each contribution is
                              also added to levels[k], k the scattering events it made after the ray's
                              origin (emission found at the first hit: 0; that hit's light sample: 1) */
    const ic_surface *first_surface; /* optional, with a known first hit (ic_pt_li_hit): its surface and */
    const ic_bsdf *first_bsdf;       /* BSDF towards the ray's origin, as the caller already computed them
                                        (NULL: computed here) */
    /* Optional (NULL: none): at a vertex after the first (at the first too with cached_at_first), the rest
     * of the path's light from a cache. It returns 1 and fills inc[j], j = 1 … remaining (the scattering
     * events the path may still make, the vertex's own reflection the first; at most IC_PT_CACHED_MAX),
     * with the light the vertex sends towards wo by exactly j of them, its emission left out; the path
     * ends there. 0: the path goes on. */
    int (*cached)(void *user, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo, int remaining, ic_rng *rng,
                  uint64_t *rays, ic_vec3 *inc);
    void *cached_user;
    int cached_at_first;   /* 1: cached applies at the first vertex too (a path that starts at a vertex whose
                              own look-up was made already: 0) */
} ic_path_start;

#define IC_PT_CACHED_MAX 16

/* Path-traced radiance arriving at the ray's origin along ray, continuing a path described by st. */
ic_vec3 ic_pt_li_from(const ic_tracer *tr, ic_ray ray, const ic_path_start *st, ic_rng *rng, uint64_t *rays);

/* Same, when the ray's first hit is already known (first_hit may be NULL: it is traced). */
ic_vec3 ic_pt_li_hit(const ic_tracer *tr, ic_ray ray, const ic_hit *first_hit, const ic_path_start *st, ic_rng *rng,
                     uint64_t *rays);

/* Direct light reflected at surface s towards wo from one light sample (NEE, MIS-weighted against
 * BSDF sampling). */
ic_vec3 ic_direct_light(const ic_tracer *tr, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo,
                        const ic_light_selection *sel, ic_rng *rng, uint64_t *rays);
/* The same for b's glossy lobe alone, MIS-weighted against sampling that lobe (ic_bsdf_sample_glossy):
 * where a path's diffuse lobe is estimated otherwise and only its glossy lobe goes on. */
ic_vec3 ic_direct_light_glossy(const ic_tracer *tr, const ic_surface *s, const ic_bsdf *b, ic_vec3 wo,
                               const ic_light_selection *sel, ic_rng *rng, uint64_t *rays);

/* A ray leaving surface s in direction dir, its origin moved off the surface (no self-hits). */
static inline ic_ray ic_spawn_ray(const ic_surface *s, ic_vec3 dir)
{
    ic_ray r;
    r.org = ic_offset_ray_origin_floor(s->p, s->ng, dir, s->offset_floor > 0.0f ? s->offset_floor : IC_RAY_OFFSET_FLOOR);
    r.dir = dir;
    r.tnear = 0.0f;
    r.tfar = INFINITY;
    return r;
}

/* The shadow ray from surface s towards a light sample, stopping just short of the light. */
static inline ic_ray ic_shadow_ray(const ic_surface *s, const ic_light_sample *ls)
{
    return ic_shadow_ray_to(s->p, s->ng, ls->wi, ls->dist, 1e-4f,
                            s->offset_floor > 0.0f ? s->offset_floor : IC_RAY_OFFSET_FLOOR);
}

/* Russian roulette on path throughput after `depth` bounces: returns 0 if the path ends, else scales
 * beta so the estimate stays unbiased. */
static inline int ic_russian_roulette(ic_vec3 *beta, int depth, int rr_depth, ic_rng *rng)
{
    if (depth + 1 < rr_depth)
        return 1;
    float q = fmaxf(0.05f, 1.0f - v3_maxc(*beta));
    if (ic_rng_float(rng) < q)
        return 0;
    *beta = v3_scale(*beta, 1.0f / (1.0f - q));
    return 1;
}

/* Default parameters filled into zero fields. */
ic_pt_params ic_pt_params_resolve(ic_pt_params p);

#endif
