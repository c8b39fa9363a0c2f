/*
 * gather_radiance.c — one radiance-cache record: the hemispherical-harmonics coefficients of the
 * incoming radiance and their translational gradient (Křivánek et al. 2005 (TVCG) §4–5; Křivánek et al.
 * 2006 §4.3 for σ), with the irradiance and its gradient from the same rays.
 *
 * Sampling: uniform solid angle, not cosine-weighted. The m = 0 basis functions do not vanish at the
 * horizon, so projecting them from cosine-distributed samples has infinite variance
 * (docs/radiance-caching.md §2). M rings of equal height in z = cosθ, ring j: z ∈ [1 − (j+1)/M, 1 − j/M],
 * times N sectors in φ starting at a per-record rotation φ0; every cell has solid angle 2π/(MN) and holds
 * one jittered ray, so Λ_k = 2π/(MN) Σ_c L_c H_k(ω_c) is an unbiased stratified estimate. M·N matches
 * the stratified sampler's ray count (opts.theta_strata · opts.phi_strata) with N ≈ 2M.
 *
 * Translational gradient (Ward & Heckbert 1992 §4 for irradiance, Křivánek et al. 2005 (TVCG) §5 for the
 * coefficients; docs/gathering.md derives the form used here). Radiance is taken constant within a
 * cell; moving the point by δ in the tangent plane moves each wall between two neighbouring cells A and
 * B as fast as the nearer of their two surfaces, a point seen at direction ω and distance d moving by
 * −(δ − (δ·ω)ω)/d. With n_A the wall's normal pointing from A into B, the strip the wall sweeps changes
 * any integral ∫ L f dω by (L_A − L_B) ∫_wall f(ω) (−δ·n_A / d) dl. For f = H_k the wall integral is
 * done by two-point Gauss–Legendre along the wall; for f = cosθ it is exact. Walls between two misses,
 * and walls whose two cells see the same radiance, change nothing.
 *
 * Random numbers: ic_rng_make(seed, key, 0, RADIANCE) only, so a record depends on nothing else.
 */
#include "gather_internal.h"

#include "core/rng.h"

#include <string.h>

/* Two-point Gauss–Legendre nodes on [0, 1]: ½ ∓ ½/√3, weights ½. */
static const double GAUSS_NODE[2] = {0.21132486540518711775, 0.78867513459481288225};

/* Per-record sums in double, planar RGB like the output vectors. */
typedef struct radiance_sums {
    double coeff[3 * IC_HSH_MAX_COUNT];
    double grad[2][3 * IC_HSH_MAX_COUNT];   /* ∂Λ/∂t, ∂Λ/∂b */
    double e[3], e_half[3], egrad[3][2];
    double inv_dist;
    float min_dist;
    uint32_t hits, half_count;
} radiance_sums;

/* The ring boundaries: z_j = 1 − j/M, sinθ_j computed without cancellation near the pole. */
static double ring_z(uint32_t j, uint32_t M) { return 1.0 - (double)j / M; }
static double ring_sin(uint32_t j, uint32_t M)
{
    const double u = (double)j / M; /* 1 − z */
    return sqrt(u * (2.0 - u));
}

/* Adds (L_A − L_B)·∫_wall H_k (−n_A/d) dl to the coefficient gradient, the wall integral by two
 * Gauss–Legendre nodes: node i at local direction dir[i], geometric weight (gx[i], gy[i]) that already
 * holds −n_A/d, the node weight and the length element. */
static void add_wall_coefficients(const ic_hsh_basis *basis, const double diff[3], double dir[2][3],
                                  const double gx[2], const double gy[2], radiance_sums *s)
{
    const uint32_t n = ic_hsh_count(basis);
    double h[IC_HSH_MAX_COUNT];
    for (int i = 0; i < 2; ++i) {
        ic_hsh_eval_d(basis, dir[i], h);
        for (int ch = 0; ch < 3; ++ch) {
            const double ax = diff[ch] * gx[i], ay = diff[ch] * gy[i];
            double *gt = s->grad[0] + ch * n, *gb = s->grad[1] + ch * n;
            for (uint32_t k = 0; k < n; ++k) {
                gt[k] += ax * h[k];
                gb[k] += ay * h[k];
            }
        }
    }
}

/* L_A − L_B per channel; 0 if the two cells see the same radiance (the wall changes nothing). */
static int radiance_diff(ic_vec3 a, ic_vec3 b, double diff[3])
{
    diff[0] = (double)a.x - b.x;
    diff[1] = (double)a.y - b.y;
    diff[2] = (double)a.z - b.z;
    return diff[0] != 0.0 || diff[1] != 0.0 || diff[2] != 0.0;
}

/* The θ-wall between ring j (A) and ring j+1 (B) of sector k, at θ_w (z_w, sin_w), φ ∈ [φ_k, φ_k + Δφ].
 * n_A = e_θ = (cosθcosφ, cosθsinφ, −sinθ), dl = sinθ dφ, so per unit δ the wall's weight is
 * −sinθ_w cosθ_w (cosφ, sinφ)/d dφ. */
static void theta_wall(const ic_hsh_basis *basis, const double diff[3], double d, double z_w, double sin_w,
                       double phi_k, double dphi, radiance_sums *s)
{
    /* Irradiance (f = cosθ, constant along the wall): ∫(cosφ, sinφ)dφ = 2 sin(Δφ/2)(cosφ_m, sinφ_m). */
    const double phi_m = phi_k + 0.5 * dphi, chord = 2.0 * sin(0.5 * dphi);
    const double e = -sin_w * z_w * z_w * chord / d;
    for (int ch = 0; ch < 3; ++ch) {
        s->egrad[ch][0] += diff[ch] * e * cos(phi_m);
        s->egrad[ch][1] += diff[ch] * e * sin(phi_m);
    }
    double dir[2][3], gx[2], gy[2];
    for (int i = 0; i < 2; ++i) {
        const double phi = phi_k + GAUSS_NODE[i] * dphi, c = cos(phi), sn = sin(phi);
        const double w = -sin_w * z_w * 0.5 * dphi / d;
        dir[i][0] = sin_w * c;
        dir[i][1] = sin_w * sn;
        dir[i][2] = z_w;
        gx[i] = w * c;
        gy[i] = w * sn;
    }
    add_wall_coefficients(basis, diff, dir, gx, gy, s);
}

/* The φ-wall between sector k (A) and sector k+1 (B) at φ_w, ring j (θ from θ_0 to θ_1). n_A = e_φ =
 * (−sinφ, cosφ, 0), dl = dθ, so per unit δ the wall's weight is −(−sinφ_w, cosφ_w)/d dθ. */
static void phi_wall(const ic_hsh_basis *basis, const double diff[3], double d, double phi_w, double z0,
                     double sin0, double z1, double sin1, radiance_sums *s)
{
    const double vx = -sin(phi_w), vy = cos(phi_w);
    /* Irradiance: ∫ cosθ dθ = sinθ_1 − sinθ_0. */
    const double e = -(sin1 - sin0) / d;
    for (int ch = 0; ch < 3; ++ch) {
        s->egrad[ch][0] += diff[ch] * e * vx;
        s->egrad[ch][1] += diff[ch] * e * vy;
    }
    const double t0 = atan2(sin0, z0), t1 = atan2(sin1, z1);
    double dir[2][3], gx[2], gy[2];
    for (int i = 0; i < 2; ++i) {
        const double t = t0 + GAUSS_NODE[i] * (t1 - t0), st = sin(t);
        const double w = -0.5 * (t1 - t0) / d;
        dir[i][0] = st * cos(phi_w);
        dir[i][1] = st * sin(phi_w);
        dir[i][2] = cos(t);
        gx[i] = w * vx;
        gy[i] = w * vy;
    }
    add_wall_coefficients(basis, diff, dir, gx, gy, s);
}

/* The frame must be orthonormal, right-handed, with its normal along pt's. */
static int frame_fits(const ic_hsh_frame *f, const ic_frame *pf)
{
    const float tol = 1e-4f;
    const ic_vec3 t = f->tangent, b = f->bitangent, n = f->normal;
    if (!v3_is_finite(t) || !v3_is_finite(b) || !v3_is_finite(n))
        return 0;
    return fabsf(v3_len(t) - 1.0f) < tol && fabsf(v3_len(b) - 1.0f) < tol && fabsf(v3_len(n) - 1.0f) < tol &&
           fabsf(v3_dot(t, b)) < tol && fabsf(v3_dot(t, n)) < tol && fabsf(v3_dot(b, n)) < tol &&
           v3_dot(v3_cross(t, b), n) > 1.0f - tol && v3_dot(n, pf->n) > 1.0f - tol;
}

/* M rings and N ≈ 2M sectors with M·N at most the stratified grid's ray count. Rings of equal height in
 * cosθ make the polar cells long and thin (ring 0 spans θ ∈ [0, √(2/M)]), so more rings and fewer
 * sectors than N ≈ 4M pay: at ~800 rays the projection error is 15% lower (docs/gathering.md). */
static void radiance_grid(const ic_gatherer *g, uint32_t *M, uint32_t *N)
{
    const uint32_t rays = g->opts.theta_strata * g->opts.phi_strata;
    uint32_t m = (uint32_t)lround(sqrt(rays / 2.0));
    if (m < 1)
        m = 1;
    *M = m;
    *N = rays / m;
}

ic_result ic_gather_radiance(ic_gatherer *g, const ic_hsh_basis *basis, const ic_gather_point *pt,
                             const ic_hsh_frame *frame, ic_gather_radiance_result *out)
{
    if (!g || !basis || !pt || !frame || !out || !out->coeffs || !out->grad_t || !out->grad_b)
        return IC_ERR_INVALID_ARG;
    ic_frame pf;
    ic_result res = ic_gather_point_frame(pt, &pf);
    if (res != IC_OK || !frame_fits(frame, &pf))
        return IC_ERR_INVALID_ARG;
    const ic_frame lf = {frame->tangent, frame->bitangent, frame->normal};

    uint32_t M, N;
    radiance_grid(g, &M, &N);
    const double two_pi = 2.0 * (double)IC_PI, dphi = two_pi / N;
    ic_rng rng = ic_rng_make(g->opts.seed, pt->key, 0, IC_GATHER_STREAM_RADIANCE);
    const double phi0 = two_pi * ic_rng_float(&rng);

    for (uint32_t k = 0; k < N; ++k) {
        for (uint32_t j = 0; j < M; ++j) {
            const uint32_t c = k * M + j;
            const double u1 = ic_rng_float(&rng), u2 = ic_rng_float(&rng);
            const double z = 1.0 - ((double)j + u1) / M, sin_t = sqrt(fmax(0.0, (1.0 - z) * (1.0 + z)));
            const double phi = phi0 + dphi * ((double)k + u2);
            g->cell_dir[c] = v3((float)(sin_t * cos(phi)), (float)(sin_t * sin(phi)), (float)z);
            g->cell_half[c] = (uint8_t)((j + k) & 1u);
        }
    }
    const uint32_t n_rays = M * N;
    for (uint32_t first = 0; first < n_rays; first += g->batch) {
        const uint32_t count = n_rays - first < g->batch ? n_rays - first : g->batch;
        for (uint32_t r = 0; r < count; ++r)
            g->ray_cell[r] = first + r;
        ic_gather_trace_chunk(g, &lf, pt->position, count);
    }

    radiance_sums sums;
    memset(&sums, 0, sizeof sums);
    radiance_sums *s = &sums;
    s->min_dist = INFINITY;
    const double omega = two_pi / n_rays; /* each cell's solid angle */
    const ic_vec3 *L = g->cell_radiance;
    const float *dist = g->cell_dist;
    for (uint32_t k = 0; k < N; ++k) {
        const double phi_k = phi0 + dphi * k;
        for (uint32_t j = 0; j < M; ++j) {
            const uint32_t c = k * M + j;
            const ic_vec3 dir = g->cell_dir[c];
            ic_hsh_accumulate(basis, dir, L[c], omega, s->coeff);
            const double lv[3] = {L[c].x, L[c].y, L[c].z};
            for (int ch = 0; ch < 3; ++ch) {
                s->e[ch] += lv[ch] * dir.z * omega;
                if (g->cell_half[c] == 0)
                    s->e_half[ch] += lv[ch] * dir.z;
            }
            s->half_count += g->cell_half[c] == 0;
            if (dist[c] < INFINITY) {
                s->inv_dist += 1.0 / dist[c];
                s->min_dist = fminf(s->min_dist, dist[c]);
                ++s->hits;
            }

            double diff[3];
            /* θ-wall to ring j+1 (none at the horizon: cosθ = 0 there). */
            if (j + 1 < M) {
                const uint32_t cb = c + 1;
                const float d = fminf(dist[c], dist[cb]);
                if (d < INFINITY && radiance_diff(L[c], L[cb], diff))
                    theta_wall(basis, diff, d, ring_z(j + 1, M), ring_sin(j + 1, M), phi_k, dphi, s);
            }
            /* φ-wall to sector k+1, wrapping around. */
            if (N > 1) {
                const uint32_t cb = (k + 1 == N ? 0 : k + 1) * M + j;
                const float d = fminf(dist[c], dist[cb]);
                if (d < INFINITY && radiance_diff(L[c], L[cb], diff))
                    phi_wall(basis, diff, d, phi_k + dphi, ring_z(j, M), ring_sin(j, M), ring_z(j + 1, M),
                             ring_sin(j + 1, M), s);
            }
        }
    }

    const uint32_t n = ic_hsh_count(basis);
    for (uint32_t i = 0; i < 3 * n; ++i) {
        out->coeffs[i] = (float)s->coeff[i];
        out->grad_t[i] = (float)s->grad[0][i];
        out->grad_b[i] = (float)s->grad[1][i];
    }
    float e[3], sig[3];
    for (int ch = 0; ch < 3; ++ch) {
        e[ch] = (float)s->e[ch];
        const double e_half = s->half_count ? two_pi * s->e_half[ch] / s->half_count : s->e[ch];
        sig[ch] = (float)fabs(s->e[ch] - e_half);
        out->trans_grad[ch] = v3_add(v3_scale(frame->tangent, (float)s->egrad[ch][0]),
                                     v3_scale(frame->bitangent, (float)s->egrad[ch][1]));
    }
    out->irradiance = v3(e[0], e[1], e[2]);
    out->sigma = v3(sig[0], sig[1], sig[2]);
    out->harmonic_mean_dist = s->inv_dist > 0.0 ? (float)(n_rays / s->inv_dist) : INFINITY;
    out->min_dist = s->min_dist;
    out->ray_count = n_rays;
    out->hit_count = s->hits;
    return IC_OK;
}
