/*
 * irrcache/gather.h — hemisphere gathering for irradiance-cache records.
 *
 * Given a shading point (position, unit normal, a 64-bit record key), a gather samples the
 * cosine-weighted hemisphere, traces the rays through a caller-supplied callback, and returns the
 * irradiance E, its rotational and translational gradients, the harmonic-mean and minimum hit
 * distances, and a Monte Carlo error estimate σ. Two samplers:
 *
 *   - stratified  : M×N jittered strata, Ward & Heckbert 1992 gradients, translational gradient in the
 *                   original WH92 form or the improved Křivánek et al. 2005 (SCCG) form (default);
 *   - progressive : Hammersley point sets in rounds (4096 → 16384 → 65536 rays by default) until the
 *                   odd/even estimates agree (Frolov et al. 2012 §4.1, Křivánek et al. 2006 §4.3);
 *                   many points per call, only the still-active ones are traced in each round;
 *   - hemicube    : one ray through each texel centre of a five-face hemicube (Castaño 2014), with exact
 *                   per-texel weights precomputed once per gatherer; deterministic for a given point.
 *
 * Optionally (opts.with_hessian, stratified and hemicube), the 2×2 tangent-plane Hessian of irradiance
 * of Schwarzhaupt et al. 2012, and ic_gather_hessian_extent turns it into a record radius or ellipse.
 *
 * The library knows nothing about geometry: it calls ic_trace_fn with batches of rays and reads back
 * hit distances and incoming radiance. Everything random is a pure function of (opts.seed, point key,
 * round), so results never depend on the thread count, on how points are split into calls, or on
 * the batch size the callback sees.
 *
 * Usage:
 *     ic_gather_opts o = {0};                      // zero means default everywhere
 *     ic_gatherer *g;
 *     if (ic_gatherer_create(&o, my_trace, my_scene, &g, &err) != IC_OK) ...
 *     ic_gather_point pt = {position, normal, key};
 *     ic_gather_result r;
 *     ic_gather_stratified(g, &pt, &r);             // or ic_gather_progressive(g, pts, n, results)
 *     ic_gatherer_destroy(g);
 * or, for many points on several threads, ic_gather_batch(&o, my_trace, my_scene, 0, pts, n, results, &err).
 *
 * Ownership and threads: the creator destroys; ic_gatherer_destroy(NULL) is a no-op. A gatherer owns
 * its scratch buffers (sized once at creation: no allocation per ray, one small allocation per
 * progressive call) and is used by one thread at a time; use one gatherer per thread. `user` is
 * borrowed and must outlive the gatherer. The trace callback must be safe to call from several
 * threads at once when ic_gather_batch runs with more than one thread.
 *
 * Units and conventions: irradiance is ∫ L cosθ dω over the hemisphere (a uniform sky of radiance L
 * gives E = πL). Gradients are world-space vectors, one per colour channel: grad[c] is the gradient of
 * channel c (0 = R, 1 = G, 2 = B). They are meant for the interpolation of Křivánek et al. 2006 §3 (cache.h):
 *     E_c(p, n) ≈ E_c + (n_i × n) · rot_grad[c] + (p − p_i) · trans_grad[c].
 */
#ifndef IRRCACHE_GATHER_H
#define IRRCACHE_GATHER_H

#include "irrcache/common.h"
#include "irrcache/hsh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Traces `count` rays (origins[i] + t·dirs[i], t > 0, dirs unit length). For each ray writes the hit
 * distance to hit_dist[i] (INFINITY on a miss; values <= 0 or NaN are treated as misses) and the
 * incoming RGB radiance along the ray to radiance[i] (non-finite values are treated as black). */
typedef void (*ic_trace_fn)(void *user, const ic_vec3 *origins, const ic_vec3 *dirs, uint32_t count,
                            float *hit_dist, ic_vec3 *radiance);

/* Which hemisphere sampler a gatherer uses by default (ic_gather_batch). */
typedef enum ic_gather_method {
    IC_GATHER_STRATIFIED = 0,   /* M×N jittered cosine-weighted strata (default) */
    IC_GATHER_PROGRESSIVE = 1,  /* Hammersley rounds with odd/even convergence (Frolov et al. 2012 §4.1) */
    IC_GATHER_HEMICUBE = 2      /* rays through hemicube texel centres (Castaño 2014) */
} ic_gather_method;

/* Which formula estimates the translational gradient from the stratified cells. */
typedef enum ic_gather_tgrad {
    IC_GATHER_TGRAD_IMPROVED = 0,     /* Křivánek, Gautron, Bouatouch, Pattanaik 2005 (SCCG; default) */
    IC_GATHER_TGRAD_WARD_HECKBERT = 1 /* Ward & Heckbert 1992 (original form; for comparison) */
} ic_gather_tgrad;

/* Gather options; zero means default for every field. */
/* The largest hemicube resolution: 3·512² = 786,432 rays. */
#define IC_GATHER_MAX_HEMICUBE 512u

typedef struct ic_gather_opts {
    ic_gather_method method;       /* sampler used by ic_gather_batch (default stratified) */
    uint64_t seed;                 /* global seed, combined with each point's key (default 0) */
    uint32_t theta_strata;         /* stratified: M, strata in sin²θ (default 16) */
    uint32_t phi_strata;           /* stratified: N, strata in φ (default round(π·M)) */
    ic_gather_tgrad tgrad;         /* translational-gradient formula (default improved) */
    uint32_t first_round_rays;     /* progressive: rays of round 0, a power of two ≥ 64 (default 4096) */
    uint32_t max_rays;             /* progressive: rays of the last round, a power of two (default 65536);
                                      rounds are independent sets, so a point that never converges
                                      traces 4096 + 16384 + 65536 = 86016 rays by default */
    uint32_t round_growth;         /* progressive: ray-count factor per round, a power of two ≥ 2 (default 4) */
    float threshold;               /* progressive: stop when |Y_odd − Y_even| / Y < threshold
                                      (default 0.02; negative: never stop early) */
    uint32_t batch_rays;           /* most rays handed to one trace call (default 4096; rounded down to a
                                      multiple of 32 so coherent groups stay whole) */
    uint32_t hemicube_resolution;  /* hemicube: texels across the top face, even, 2..IC_GATHER_MAX_HEMICUBE
                                      (default 16:
                                      3·16² = 768 rays, the nearest to the stratified 16×50 = 800) */
    int with_hessian;              /* non-zero: stratified and hemicube gathers also fill the Hessian
                                      fields of ic_gather_result (default 0: not computed) */
} ic_gather_opts;

/* A point to gather at. */
typedef struct ic_gather_point {
    ic_vec3 position;              /* ray origin (offset it off the surface, or let the tracer skip self-hits) */
    ic_vec3 normal;                /* unit surface normal; the hemisphere is around it */
    uint64_t key;                  /* record key (e.g. candidate index or pixel): seeds all its random numbers */
} ic_gather_point;

/* What one gather returns. */
typedef struct ic_gather_result {
    ic_vec3 irradiance;            /* E, RGB */
    ic_vec3 rot_grad[3];           /* rotational gradient per channel (world space, ⟂ normal) */
    ic_vec3 trans_grad[3];         /* translational gradient per channel (world space, ⟂ normal) */
    float harmonic_mean_dist;      /* n / Σ_hits 1/d_i over all n rays: a miss counts as d = ∞ and adds 0
                                      to the sum; INFINITY if no ray hit */
    float min_dist;                /* smallest hit distance; INFINITY if no ray hit */
    ic_vec3 sigma;                 /* σ = |E − E'| per channel, E' from half of the rays (Křivánek et al. 2006 §4.3) */
    uint32_t ray_count;            /* rays traced for this point (all rounds) */
    uint32_t hit_count;            /* rays that hit something */
    int is_converged;              /* progressive: 1 if it stopped on the threshold, 0 if it hit max_rays;
                                      stratified and hemicube: always 1 */
    /* Second order (Schwarzhaupt et al. 2012), filled only when opts.with_hessian is set and the
     * sampler is stratified or hemicube; all zero otherwise. The Hessian is the Jacobian of the
     * occlusion-aware translational gradient (each wall between two cells moves with the nearer of
     * their hit distances): E_c(p + d) ≈ E_c + d·trans_grad[c] + ½ dᵀ H_c d for d in the tangent plane,
     * with d = d_t·hessian_t + d_b·hessian_b and H_c = [[h_tt, h_tb], [h_tb, h_bb]]. */
    int has_hessian;               /* 1 if the fields below are filled */
    ic_vec3 hessian_t, hessian_b;  /* the tangent frame of the coefficients (unit, ⟂ normal, t × b = n) */
    float hessian[3][3];           /* per channel c: {h_tt, h_tb, h_bb}, irradiance per length² */
} ic_gather_result;

/* A record extent from a Hessian (ic_gather_hessian_extent). */
typedef struct ic_gather_extent_opts {
    float rel_error;               /* ε: allowed second-order error relative to E (default 0.1) */
    float min_radius;              /* smallest radius and semi-axis (default 0) */
    float max_radius;              /* largest radius and semi-axis (default INFINITY; 0 means default) */
    float min_irradiance;          /* floor on E in ε·E, so a record under a black occluder does not
                                      shrink to nothing (default 0) */
} ic_gather_extent_opts;

typedef struct ic_gather_extent {
    float radius;                  /* isotropic: √(2εE / max|λ|), clamped */
    ic_vec3 axis[2];               /* unit world-space eigenvectors of the tangent-plane Hessian */
    float eigenvalue[2];           /* λ along axis[k], |λ_0| >= |λ_1| */
    float semi_axis[2];            /* √(2εE / |λ_k|) along axis[k], clamped; semi_axis[0] <= semi_axis[1] */
} ic_gather_extent;

/* Opaque per-thread gatherer: resolved options, trace callback, scratch buffers. */
typedef struct ic_gatherer ic_gatherer;

/* Creates a gatherer (opts may be NULL: all defaults). Fails with IC_ERR_INVALID_ARG on bad options
 * (non-power-of-two round sizes, more than 2^24 rays per round…) and IC_ERR_OOM. */
ic_result ic_gatherer_create(const ic_gather_opts *opts, ic_trace_fn trace, void *user, ic_gatherer **out,
                             ic_error *err);
/* Releases a gatherer; NULL is a no-op. */
void ic_gatherer_destroy(ic_gatherer *g);
/* The options in effect, defaults filled in. */
const ic_gather_opts *ic_gatherer_opts(const ic_gatherer *g);

/* Fills `defaults` with every default made explicit (what zero means). */
void ic_gather_opts_default(ic_gather_opts *defaults);

/* Stratified M×N gather at one point. IC_ERR_INVALID_ARG on a zero-length normal or NULL arguments. */
ic_result ic_gather_stratified(ic_gatherer *g, const ic_gather_point *pt, ic_gather_result *out);

/* Progressive gather at `count` points: round by round, only points whose estimate has not converged
 * are traced again. out[i] belongs to pts[i]. Allocates one small per-call state array (IC_ERR_OOM). */
ic_result ic_gather_progressive(ic_gatherer *g, const ic_gather_point *pts, uint32_t count,
                                ic_gather_result *out);

/* Hemicube gather at one point (Castaño 2014): opts.hemicube_resolution = N gives N² + 4·N·N/2 = 3N²
 * rays. The gatherer builds its hemicube tables at creation only if opts.method is IC_GATHER_HEMICUBE
 * or opts.hemicube_resolution is set. IC_ERR_INVALID_ARG on a zero-length normal, NULL arguments or a
 * gatherer without tables. */
ic_result ic_gather_hemicube(ic_gatherer *g, const ic_gather_point *pt, ic_gather_result *out);

/* The record extent a Hessian implies (Schwarzhaupt et al. 2012): with the luminance Hessian H (Rec. 709
 * weights of r->hessian) and E the luminance of r->irradiance, the second-order error ½ dᵀHd equals
 * ε·max(E, min_irradiance) on an ellipse with semi-axes √(2εE/|λ_k|) along the eigenvectors, and on
 * a circle of radius √(2εE / max|λ|) inside it; both clamped to [min_radius, max_radius] (a zero
 * eigenvalue gives max_radius). Pure. IC_ERR_INVALID_ARG if r has no Hessian or opts are invalid. */
ic_result ic_gather_hessian_extent(const ic_gather_result *r, const ic_gather_extent_opts *opts,
                                   ic_gather_extent *out);

/* Gathers `count` points on `threads` threads (0 = all cores) with opts->method, one gatherer per
 * thread; out[i] belongs to pts[i] and is identical for any thread count. */
ic_result ic_gather_batch(const ic_gather_opts *opts, ic_trace_fn trace, void *user, int threads,
                          const ic_gather_point *pts, uint32_t count, ic_gather_result *out, ic_error *err);

/* What one radiance-record gather returns (ic_gather_radiance). The three coefficient vectors are the
 * caller's, 3·n² floats each for a basis of order n, planar RGB as in hsh.h. */
typedef struct ic_gather_radiance_result {
    float *coeffs;                 /* caller-provided: Λ_k = ∫ L(ω) H_k(ω) dω in the frame given */
    float *grad_t;                 /* caller-provided: ∂Λ/∂t, along frame->tangent, per unit length */
    float *grad_b;                 /* caller-provided: ∂Λ/∂b, along frame->bitangent, per unit length */
    ic_vec3 irradiance;            /* E = ∫ L cosθ dω from the same samples */
    ic_vec3 trans_grad[3];         /* ∇E per channel, world space, ⟂ normal, from the same walls */
    float harmonic_mean_dist;      /* as ic_gather_result */
    float min_dist;                /* as ic_gather_result */
    ic_vec3 sigma;                 /* |E − E'|, E' from a checkerboard half of the cells */
    uint32_t ray_count;            /* rays traced */
    uint32_t hit_count;            /* rays that hit something */
} ic_gather_radiance_result;

/* Radiance-record gather at one point (Křivánek et al. 2005 (TVCG)): uniform solid-angle strata, M rings
 * in cosθ × N ≈ 2M sectors with M·N ≤ opts.theta_strata·opts.phi_strata rays, one jittered ray each;
 * the HSH coefficients of the incoming radiance in `frame` and their translational gradient from the
 * occlusion-aware motion of the walls between cells (docs/radiance-caching.md §5). `frame` must be orthonormal,
 * right-handed, with its normal along pt->normal (within 10⁻⁴); the record keeps it for rotations.
 * Random numbers depend only on (opts.seed, pt->key). No allocation. IC_ERR_INVALID_ARG on NULL
 * arguments or coefficient pointers, a zero-length normal or a frame that does not fit. */
ic_result ic_gather_radiance(ic_gatherer *g, const ic_hsh_basis *basis, const ic_gather_point *pt,
                             const ic_hsh_frame *frame, ic_gather_radiance_result *out);

#ifdef __cplusplus
}
#endif
#endif
