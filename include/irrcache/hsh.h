/*
 * irrcache/hsh.h — hemispherical harmonics (HSH) for radiance caching on glossy surfaces.
 *
 * A radiance-cache record stores the incoming radiance over the hemisphere above a point as RGB
 * coefficient vectors Λ in the HSH basis of Gautron, Křivánek, Pattanaik & Bouatouch 2004; a glossy
 * BRDF seen from ω_o becomes a coefficient vector C(ω_o) of its cosine-weighted lobe, and the outgoing
 * radiance is the dot product Λ·C per channel (Křivánek et al. 2005 (TVCG)). This module provides:
 *
 *   - the basis of order n (n² functions H_l^m, 0 ≤ l < n, −l ≤ m ≤ l, orthonormal over the upper
 *     hemisphere of the local frame, z = normal) and its evaluation by recurrences;
 *   - projection of Monte Carlo samples or of a callback function, reconstruction, dot products;
 *   - rotation of a coefficient vector from one local frame to another: the reference rotation through
 *     spherical harmonics (SH) with the Ivanic–Ruedenberg recurrence, and the fast approximation of
 *     Křivánek et al. 2008 (exact z-rotations around a Taylor-expanded y-rotation), good only for small
 *     angles between the normals;
 *   - BRDF lobe coefficients C(ω_o) from a BRDF callback, by adaptive quadrature, and a table over the
 *     outgoing elevation θ_o for isotropic BRDFs.
 *
 * The mathematics, conventions and measured accuracy are in docs/radiance-caching.md.
 *
 * Usage:
 *     ic_hsh_opts o = {0};                           // zero means default: order 10
 *     o.order = 6;
 *     ic_hsh_basis *b;
 *     if (ic_hsh_basis_create(&o, &b, &err) != IC_OK) ...
 *     uint32_t k = ic_hsh_count(b);                   // n² coefficients per channel
 *     float lambda[3 * IC_HSH_MAX_COUNT];             // planar RGB: channel c at lambda[c·k + i]
 *     ic_hsh_project_cosine(b, dirs, radiance, count, lambda);   // cosine-distributed local directions
 *     ic_hsh_rotation r;
 *     ic_hsh_rotation_from_frames(&record_frame, &shading_frame, &r);
 *     ic_hsh_rotate_fast(b, &r, lambda, 3, lambda_here);         // record frame → shading frame
 *     ic_hsh_lobe_table *t;                                       // once per BRDF
 *     ic_hsh_lobe_table_create(b, my_brdf, my_params, NULL, &t, &err);
 *     float c[IC_HSH_MAX_COUNT];
 *     ic_hsh_lobe_table_eval(t, wo_local, c);
 *     ic_vec3 lo = ic_hsh_shade(b, lambda_here, c);               // outgoing radiance
 *     ic_hsh_lobe_table_destroy(t);
 *     ic_hsh_basis_destroy(b);
 *
 * Ownership and threads: the creator destroys; destroying NULL is a no-op. A basis and a lobe table are
 * read-only after creation and may be shared by any number of threads. A lobe table borrows its basis,
 * which must outlive it. Nothing here allocates except the create functions, ic_hsh_project_function
 * and ic_hsh_lobe_project (their quadrature's cells), and ic_hsh_rotate_exact when given no scratch.
 *
 * Conventions: directions are unit vectors in the local frame (x = tangent, y = bitangent, z = normal);
 * every basis function is zero below the horizon (z < 0). Coefficient k = l(l+1) + m. Channels are
 * planar: a vector of `channels` channels holds channel c at [c·n² + k]. The associated Legendre
 * functions carry no Condon–Shortley phase (−1)^m, so H_1^1 > 0 for x > 0.
 */
#ifndef IRRCACHE_HSH_H
#define IRRCACHE_HSH_H

#include "irrcache/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Largest supported order n (n² coefficients per channel). */
#define IC_HSH_MAX_ORDER 24
/* Largest coefficient count, IC_HSH_MAX_ORDER²: the size of a stack buffer that fits any basis. */
#define IC_HSH_MAX_COUNT (IC_HSH_MAX_ORDER * IC_HSH_MAX_ORDER)

/* Index of H_l^m in a coefficient vector (0 ≤ l, |m| ≤ l). */
static inline uint32_t ic_hsh_index(int l, int m) { return (uint32_t)(l * (l + 1) + m); }

/* Basis options; zero means default for every field. */
typedef struct ic_hsh_opts {
    uint32_t order;        /* n, 1..IC_HSH_MAX_ORDER (default 10: 100 coefficients) */
    uint32_t sh_order;     /* order of the SH expansion behind ic_hsh_rotate_exact and the fast
                              rotation's matrices, ≥ order, ≤ 4·IC_HSH_MAX_ORDER (default 2·order + 8) */
} ic_hsh_opts;

/* Opaque basis: recurrence coefficients and the HSH↔SH conversion and rotation matrices of one order. */
typedef struct ic_hsh_basis ic_hsh_basis;

/* Fills `defaults` with the defaults for a given order (0: the default order). */
void ic_hsh_opts_default(ic_hsh_opts *defaults, uint32_t order);
/* Creates a basis (opts may be NULL). IC_ERR_INVALID_ARG on an order out of range, IC_ERR_OOM. */
ic_result ic_hsh_basis_create(const ic_hsh_opts *opts, ic_hsh_basis **out, ic_error *err);
/* Releases a basis; NULL is a no-op. */
void ic_hsh_basis_destroy(ic_hsh_basis *b);
/* The order n. */
uint32_t ic_hsh_order(const ic_hsh_basis *b);
/* The coefficient count n² (per channel). */
uint32_t ic_hsh_count(const ic_hsh_basis *b);
/* The SH order used by the rotations. */
uint32_t ic_hsh_sh_order(const ic_hsh_basis *b);

/* ---- evaluation --------------------------------------------------------------------------- */

/* Writes the n² basis values H_k(dir) to values (all zero if dir.z < 0). dir must be unit length. */
void ic_hsh_eval(const ic_hsh_basis *b, ic_vec3 dir, float *values);
/* Same in double precision, for quadrature and tests. */
void ic_hsh_eval_d(const ic_hsh_basis *b, const double dir[3], double *values);
/* Evaluates the `channels`-channel coefficient vector at dir; writes one value per channel. */
void ic_hsh_reconstruct(const ic_hsh_basis *b, const float *coeffs, uint32_t channels, ic_vec3 dir,
                        float *out);
/* Σ_k a[k]·b[k] over `count` coefficients (double accumulation). */
float ic_hsh_dot(const float *a, const float *b, uint32_t count);
/* Outgoing radiance: per channel the dot product of an RGB radiance vector with one lobe vector C. */
ic_vec3 ic_hsh_shade(const ic_hsh_basis *b, const float *radiance_rgb, const float *lobe);

/* ---- projection --------------------------------------------------------------------------- */

/* Adds one sample to double sums (3·n², planar RGB): sum[c][k] += weight · radiance_c · H_k(dir).
 * For an estimate from N samples of pdf p use weight = 1 / (N · p(dir)). */
void ic_hsh_accumulate(const ic_hsh_basis *b, ic_vec3 dir, ic_vec3 radiance, double weight, double *sum);
/* Monte Carlo projection of `count` samples drawn with densities pdf[i] (per steradian; NULL: uniform
 * over the hemisphere, 1/2π) into 3·n² RGB coefficients. Samples with pdf ≤ 0 or dir.z < 0 count as zero. */
void ic_hsh_project(const ic_hsh_basis *b, const ic_vec3 *dirs, const ic_vec3 *radiance, const float *pdf,
                    uint32_t count, float *coeffs_rgb);
/* The common case: directions cosine-distributed (pdf cosθ/π), stratified or not, as the gatherer's
 * stratified and progressive samplers draw them. */
void ic_hsh_project_cosine(const ic_hsh_basis *b, const ic_vec3 *dirs, const ic_vec3 *radiance, uint32_t count,
                           float *coeffs_rgb);

/* A scalar function on the upper hemisphere of the local frame (dir unit, dir[2] ≥ 0). */
typedef double (*ic_hsh_function_fn)(void *user, const double dir[3]);

/* Quadrature options for ic_hsh_project_function and the lobe routines; zero means default. The
 * hemisphere is cut into cells in (t, φ), cosθ = sin²(πt/2), each integrated by a q×q Gauss–Legendre rule;
 * the cell whose four halves change its coefficient vector most is split next (global adaptivity), until
 * the summed change is below the tolerance. */
typedef struct ic_hsh_quad_opts {
    double tolerance;      /* target for the summed L2 error estimates, relative to the L2 norm of the
                              first pass's coefficient vector (default 1e-6) */
    uint32_t nodes;        /* q, Gauss–Legendre nodes per cell side, 2..16 (default 6) */
    uint32_t t_cells;      /* initial cells in t (default 8) */
    uint32_t phi_cells;    /* initial cells in φ over 2π (default 16); a lobe narrower than about a cell
                              can go unseen by the first pass: raise both for very sharp lobes */
    uint32_t max_depth;    /* most splits of an initial cell (default 12) */
    uint32_t max_leaves;   /* most cells in the partition (default 65536) */
} ic_hsh_quad_opts;

/* Quadrature statistics (optional output). */
typedef struct ic_hsh_quad_stats {
    uint64_t evaluations;  /* calls of the callback */
    uint32_t leaves;       /* cells in the final partition */
    double error_estimate; /* summed error estimates, relative like the tolerance */
    int is_converged;      /* 1 if error_estimate met the tolerance before max_depth or max_leaves */
} ic_hsh_quad_stats;

/* Projects fn onto the basis by adaptive quadrature: coeffs[k] = ∫ fn·H_k dω (one channel).
 * stats may be NULL. IC_ERR_INVALID_ARG on bad options, IC_ERR_OOM. */
ic_result ic_hsh_project_function(const ic_hsh_basis *b, ic_hsh_function_fn fn, void *user,
                                  const ic_hsh_quad_opts *opts, float *coeffs, ic_hsh_quad_stats *stats,
                                  ic_error *err);

/* ---- rotation ----------------------------------------------------------------------------- */

/* A local frame: orthonormal, right-handed (tangent × bitangent = normal). */
typedef struct ic_hsh_frame {
    ic_vec3 tangent, bitangent, normal;
} ic_hsh_frame;

/* A rotation r of local directions and its ZYZ Euler angles: r = Rz(alpha)·Ry(beta)·Rz(gamma).
 * Rotating a coefficient vector by r gives the coefficients of g(ω) = f(r⁻¹ω). */
typedef struct ic_hsh_rotation {
    double m[3][3];        /* row-major rotation matrix */
    double alpha, beta, gamma; /* radians; beta in [0, π] is the angle between the two z axes */
} ic_hsh_rotation;

/* The rotation from a 3×3 rotation matrix given as 9 doubles, row-major (orthonormal, det +1). */
void ic_hsh_rotation_from_matrix(const double *rowmajor, ic_hsh_rotation *out);
/* The rotation Rz(alpha)·Ry(beta)·Rz(gamma). */
void ic_hsh_rotation_from_euler(double alpha, double beta, double gamma, ic_hsh_rotation *out);
/* The rotation that re-expresses coefficients given in frame `from` (a record's) in frame `to` (a
 * shading point's): m[a][b] = to.axis_a · from.axis_b. */
void ic_hsh_rotation_from_frames(const ic_hsh_frame *from, const ic_hsh_frame *to, ic_hsh_rotation *out);
/* The inverse rotation (transposed matrix). */
void ic_hsh_rotation_invert(const ic_hsh_rotation *r, ic_hsh_rotation *out);

/* Exact rotation about z by angle (radians): mixes the cos mφ / sin mφ pairs. in and out may alias. */
void ic_hsh_rotate_z(const ic_hsh_basis *b, double angle, const float *in, uint32_t channels, float *out);
/* Doubles of scratch ic_hsh_rotate_exact needs (2·L²). */
size_t ic_hsh_rotate_exact_scratch(const ic_hsh_basis *b);
/* Reference rotation: HSH → SH (zero below the horizon), the y-rotation in SH as Rx(−90°)·Rz(β)·Rx(90°)
 * with matrices from the Ivanic–Ruedenberg recurrence, back to HSH by projection onto the upper hemisphere;
 * z-rotations exact. beta = 0 is a pure z-rotation. scratch holds ic_hsh_rotate_exact_scratch(b) doubles,
 * or is NULL (then one allocation per call: IC_ERR_OOM). in and out may alias. */
ic_result ic_hsh_rotate_exact(const ic_hsh_basis *b, const ic_hsh_rotation *r, const float *in,
                              uint32_t channels, float *out, double *scratch);
/* Taylor order of the fast rotation's y-rotation. */
typedef enum ic_hsh_taylor {
    IC_HSH_TAYLOR_SECOND = 0,  /* G₀ + βG + β²/2·G₂ (default) */
    IC_HSH_TAYLOR_FIRST = 1    /* G₀ + βG (first order, as in Křivánek et al. 2008) */
} ic_hsh_taylor;
/* Fast approximate rotation (Křivánek et al. 2008): exact Rz(gamma), the y-rotation by beta through the
 * Taylor expansion of the reference's y-rotation with sparse matrices, exact Rz(alpha). Agrees with
 * ic_hsh_rotate_exact to O(beta³) (second order); see docs/radiance-caching.md for the measured error,
 * which limits it to small beta. No allocation. in and out may alias. */
void ic_hsh_rotate_fast(const ic_hsh_basis *b, const ic_hsh_rotation *r, ic_hsh_taylor taylor, const float *in,
                        uint32_t channels, float *out);

/* ---- BRDF lobes --------------------------------------------------------------------------- */

/* A BRDF f_r(ω_i, ω_o) in 1/sr, local frame, both directions unit with z ≥ 0. The lobe routines
 * multiply it by cosθ_i themselves. */
typedef double (*ic_hsh_brdf_fn)(void *user, const double wi[3], const double wo[3]);

/* Lobe coefficients for one outgoing direction: c[k] = ∫ f_r(ω_i, wo)·cosθ_i·H_k(ω_i) dω_i
 * (opts and stats may be NULL). IC_ERR_INVALID_ARG if wo.z < 0, IC_ERR_OOM. */
ic_result ic_hsh_lobe_project(const ic_hsh_basis *b, ic_hsh_brdf_fn brdf, void *user, ic_vec3 wo,
                              const ic_hsh_quad_opts *opts, float *c, ic_hsh_quad_stats *stats, ic_error *err);

/* Lobe table options; zero means default. */
typedef struct ic_hsh_lobe_table_opts {
    uint32_t theta_count;  /* entries over θ_o in [0°, 90°], uniformly spaced, ≥ 2 (default 46: every 2°) */
    ic_hsh_quad_opts quad; /* quadrature of each entry */
} ic_hsh_lobe_table_opts;

/* Opaque table of lobe vectors over θ_o for an isotropic BRDF (entries at φ_o = 0). */
typedef struct ic_hsh_lobe_table ic_hsh_lobe_table;

/* Builds the table (opts may be NULL); borrows b. IC_ERR_INVALID_ARG, IC_ERR_OOM. */
ic_result ic_hsh_lobe_table_create(const ic_hsh_basis *b, ic_hsh_brdf_fn brdf, void *user,
                                   const ic_hsh_lobe_table_opts *opts, ic_hsh_lobe_table **out, ic_error *err);
/* Releases a table; NULL is a no-op. */
void ic_hsh_lobe_table_destroy(ic_hsh_lobe_table *t);
/* Lobe vector C(wo) (n² floats): cubic interpolation in θ_o between entries, then the exact
 * z-rotation by φ_o. wo is a unit local direction; below the horizon it is clamped to z = 0. */
void ic_hsh_lobe_table_eval(const ic_hsh_lobe_table *t, ic_vec3 wo, float *c);

#ifdef __cplusplus
}
#endif
#endif
