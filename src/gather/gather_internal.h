/*
 * gather_internal.h — what the gather files share: the gatherer object, its cell grid, and the
 * estimator that turns a filled M×N grid of cosine-weighted samples into E, σ, gradients and distances.
 *
 * Both samplers reduce to the same picture: the hemisphere split into M strata in sin²θ (equal
 * projected solid angle π/(MN) each) times N strata in φ, exactly one sample per cell. The stratified
 * sampler builds that grid by jittering; the progressive sampler gets it for free because a Hammersley
 * set of 2^m points is a (0,m,2)-net in base 2 (Niederreiter 1992, "Random Number Generation and
 * Quasi-Monte Carlo Methods", §4.1): every M×N grid of elementary intervals with M·N = 2^m holds exactly
 * one point. One estimator (gather_grid.c) then serves both.
 */
#ifndef IC_GATHER_INTERNAL_H
#define IC_GATHER_INTERNAL_H

#include "irrcache/gather.h"

#include "core/vecmath.h"

/* Purposes that separate the random streams of one point (ic_rng_make's last word). */
enum { IC_GATHER_STREAM_STRATIFIED = 0x5354, IC_GATHER_STREAM_PROGRESSIVE = 0x5052, IC_GATHER_STREAM_HEMICUBE = 0x4843,
       IC_GATHER_STREAM_RADIANCE = 0x5241 };

/* What one wall between two cells contributes to the translational gradient and Hessian per unit
 * radiance difference, before dividing by its distance r (gradient: g/r, Hessian: h/r²); tangent-frame
 * components. Orientation: the contribution is (L_left − L_right)·g/r, where "left" is the side the wall's
 * normal ω × dω/ds points to (gather_hessian.c). */
typedef struct ic_wall_factors {
    double g[2];              /* ∂/∂x_t, ∂/∂x_b */
    double h[3];              /* h_tt, h_tb (symmetrised), h_bb */
} ic_wall_factors;

/* A wall of the hemicube: texels `left` and `right` and its factors. */
typedef struct ic_hemicube_wall {
    uint32_t left, right;
    ic_wall_factors f;
} ic_hemicube_wall;

/* Per-resolution hemicube tables (gather_hemicube.c), built once per gatherer. Texel order: the top
 * face row by row, then the four side half-faces (+x, +y, −x, −y). */
typedef struct ic_hemicube {
    uint32_t resolution;      /* N: texels across the top face */
    uint32_t texels;          /* 3N² */
    uint32_t walls;
    ic_vec3 *dir;             /* unit texel-centre directions, local frame */
    double *solid_angle;      /* ∫_texel dω (sums to 2π) */
    double *weight;           /* irradiance weight ∫_texel cosθ dω (sums to π) */
    double (*rot)[2];         /* rotational-gradient weight ∫_texel (n × ω) dω, (t, b) components */
    uint8_t *half;            /* checkerboard half of the σ estimate */
    double half_scale;        /* π / Σ_{half = 0} weight */
    ic_hemicube_wall *wall;
} ic_hemicube;

struct ic_gatherer {
    ic_gather_opts opts;      /* resolved: no zero defaults left */
    ic_trace_fn trace;
    void *user;
    uint32_t cell_capacity;   /* cells (= rays of one grid) the buffers below hold */
    uint32_t batch;           /* rays per trace call, ≤ cell_capacity */
    /* The grid, cell index = k*M + j (φ-column major, so one column is one coherent ray group). */
    ic_vec3 *cell_dir;        /* local direction (x = sinθcosφ, y = sinθsinφ, z = cosθ) */
    ic_vec3 *cell_radiance;   /* traced radiance, sanitised */
    float *cell_dist;         /* hit distance, INFINITY on a miss */
    uint8_t *cell_half;       /* 0/1: which half of the odd/even split the sample belongs to */
    /* One trace call's worth of rays. */
    ic_vec3 *ray_org, *ray_dir, *ray_radiance;
    float *ray_dist;
    uint32_t *ray_cell;       /* cell each ray's result goes to */
    double *tan_scratch;      /* per-θ-stratum tanθ, cell_capacity entries (≥ any M) */
    ic_hemicube hemicube;     /* tables for opts.hemicube_resolution */
    ic_wall_factors *grid_walls; /* opts.with_hessian: per θ stratum j, the canonical φ-wall (2j) and
                                    θ-wall (2j+1) of the stratified grid (gather_hessian.c) */
};

/* Running sums of one point's estimate over one or more grids ("rounds"). Each grid of n rays adds n
 * times its own estimate, so dividing by the total ray count gives the ray-count-weighted average of
 * the rounds: the variance-optimal weights for independent Monte Carlo estimates, and for E exactly
 * the plain average of all samples. */
typedef struct ic_gather_acc {
    double e[3];              /* Σ n·E */
    double e_half[3];         /* Σ n·E', E' from the half with cell_half == 0 */
    double rot[3][2];         /* Σ n·∇r E per channel, local (t, b) components */
    double trans[3][2];       /* Σ n·∇t E per channel, local (t, b) components */
    double inv_dist;          /* Σ 1/d over hits */
    float min_dist;           /* min hit distance */
    uint32_t rays, hits;
} ic_gather_acc;

/* Empty accumulator. */
void ic_gather_acc_init(ic_gather_acc *acc);

/* Traces one chunk of count ≤ g->batch rays: ray r leaves origin along frame·cell_dir[ray_cell[r]]
 * (g->ray_cell filled by the caller); the sanitised results are stored in those cells. */
void ic_gather_trace_chunk(ic_gatherer *g, const ic_frame *frame, ic_vec3 origin, uint32_t count);

/* Adds the estimate of the filled M×N grid (azimuth of the first φ boundary phi0) to acc. */
void ic_gather_grid_accumulate(const ic_gatherer *g, uint32_t M, uint32_t N, float phi0, ic_gather_acc *acc);

/* Writes acc's estimate, gradients turned to world space with frame, into out. */
void ic_gather_acc_finish(const ic_gather_acc *acc, const ic_frame *frame, ic_gather_result *out);

/* Builds g->hemicube for g->opts.hemicube_resolution (IC_ERR_OOM); frees it. */
ic_result ic_gather_hemicube_init(ic_gatherer *g);
void ic_gather_hemicube_free(ic_gatherer *g);

/* Wall factors (gather_hessian.c) of a great-circle arc from unit a to unit b (local frame), of a
 * meridian φ from θ0 to θ1, and of a parallel θ from φ0 to φ1 (the directions of increasing s). */
ic_wall_factors ic_gather_arc_factors(ic_vec3 a, ic_vec3 b);
ic_wall_factors ic_gather_meridian_factors(double phi, double theta0, double theta1);
ic_wall_factors ic_gather_parallel_factors(double theta, double phi0, double phi1);

/* Builds g->grid_walls for the stratified M×N grid (IC_ERR_OOM). */
ic_result ic_gather_hessian_init(ic_gatherer *g);
/* Fills out's Hessian fields from the filled M×N grid (azimuth phi0) of a stratified gather. */
void ic_gather_hessian_grid(const ic_gatherer *g, uint32_t M, uint32_t N, float phi0, const ic_frame *frame,
                            ic_gather_result *out);

/* Frame around a point's normal; IC_ERR_INVALID_ARG if the normal is zero or not finite. */
ic_result ic_gather_point_frame(const ic_gather_point *pt, ic_frame *frame);

#endif
