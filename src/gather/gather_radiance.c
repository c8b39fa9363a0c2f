/*
 * gather_radiance.c — one radiance-cache record: the hemispherical-harmonics coefficients of the
 * incoming radiance and their translational gradient (Křivánek et al. 2005 (TVCG); Křivánek et al. 2006
 * §4.3 for σ), with the irradiance and its gradient from the same rays.
 *
 * Sampling: uniform solid angle, not cosine-weighted. The m = 0 basis functions do not vanish at the
 * horizon, so projecting them from cosine-distributed samples has infinite variance
 * (docs/radiance-caching.md §2). M rings of equal height in z = cosθ, ring j: z ∈ [1 − (j+1)/M, 1 − j/M],
 * times N sectors in φ starting at a per-record rotation φ0; every cell has solid angle 2π/(MN) and holds
 * one jittered ray, so Λ_k = 2π/(MN) Σ_c L_c H_k(ω_c) is an unbiased stratified estimate. M·N matches
 * the stratified sampler's ray count (opts.theta_strata · opts.phi_strata) with N ≈ 2M.
 *
 * Translational gradient (Ward & Heckbert 1992 §4 for irradiance, Křivánek et al. 2005 (TVCG) for the
 * coefficients; docs/radiance-caching.md §5 derives the form used here). Radiance is taken constant
 * within a cell; moving the point by δ in the tangent plane moves each wall between two neighbouring
 * cells A and B as fast as the nearer of their two surfaces, a point seen at direction ω and distance d
 * moving by −(δ − (δ·ω)ω)/d. With n_A the wall's normal pointing from A into B, the strip the wall sweeps
 * changes any integral ∫ L f dω by (L_A − L_B) ∫_wall f(ω) (−δ·n_A / d) dl. For f = H_k the wall integral
 * is done by two-point Gauss–Legendre along the wall, ring by ring so that the polar part of the basis is
 * evaluated once per ring; for f = cosθ it is exact. Walls between two misses, and walls whose two cells
 * see the same radiance, change nothing.
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

/* L_A − L_B per channel; 0 if the two cells see the same radiance (the wall changes nothing). */
static int radiance_diff(ic_vec3 a, ic_vec3 b, double diff[3])
{
    diff[0] = (double)a.x - b.x;
    diff[1] = (double)a.y - b.y;
    diff[2] = (double)a.z - b.z;
    return diff[0] != 0.0 || diff[1] != 0.0 || diff[2] != 0.0;
}

/* The basis separates: H_l^{±m}(θ, φ) = A_l^m(θ)·{cos mφ, sin mφ} (hsh.h's cos/sin pairs), so a sum over
 * the walls of one ring boundary, where θ is fixed, needs the azimuthal factors only: per channel and
 * tangent axis, one sum per slot (slot m < n: cos mφ; slot n − 1 + m, 1 ≤ m < n: sin mφ), multiplied by
 * A(θ) once per ring. That makes a wall O(n) instead of O(n²). */
typedef struct azimuth_sums {
    double s[3][2][2 * IC_HSH_MAX_ORDER];
    int is_used;
} azimuth_sums;

/* Adds diff·(gx, gy)·{cos mφ, sin mφ} to the slots. */
static void add_azimuth(uint32_t order, double phi, const double diff[3], double gx, double gy, azimuth_sums *a)
{
    double trig[2 * IC_HSH_MAX_ORDER];
    const double c1 = cos(phi), s1 = sin(phi);
    double cm = 1.0, sm = 0.0;
    trig[0] = 1.0;
    for (uint32_t m = 1; m < order; ++m) {
        const double c = cm * c1 - sm * s1;
        sm = sm * c1 + cm * s1;
        cm = c;
        trig[m] = cm;
        trig[order - 1 + m] = sm;
    }
    const uint32_t slots = 2 * order - 1;
    for (int ch = 0; ch < 3; ++ch) {
        const double ax = diff[ch] * gx, ay = diff[ch] * gy;
        for (uint32_t i = 0; i < slots; ++i) {
            a->s[ch][0][i] += ax * trig[i];
            a->s[ch][1][i] += ay * trig[i];
        }
    }
    a->is_used = 1;
}

/* The polar factors A_l^m(θ) (0 ≤ m ≤ l, at index l(l+1) + m) of `count` polar angles summed: the basis
 * at φ = 0, where cos mφ = 1. */
static void polar_terms(const ic_hsh_basis *basis, const double *z, const double *sin_t, int count, double *A)
{
    const uint32_t n = ic_hsh_count(basis);
    double h[IC_HSH_MAX_COUNT];
    memset(A, 0, n * sizeof *A);
    for (int i = 0; i < count; ++i) {
        const double dir[3] = {sin_t[i], 0.0, z[i]};
        ic_hsh_eval_d(basis, dir, h);
        for (uint32_t k = 0; k < n; ++k)
            A[k] += h[k];
    }
}

/* grad[axis][c·n² + k] += A(θ)·slot sums, for every coefficient k = l(l+1) + m. */
static void flush_azimuth(const ic_hsh_basis *basis, const double *A, const azimuth_sums *a, radiance_sums *s)
{
    const uint32_t order = ic_hsh_order(basis), n = ic_hsh_count(basis);
    for (int ch = 0; ch < 3; ++ch)
        for (int axis = 0; axis < 2; ++axis) {
            const double *slot = a->s[ch][axis];
            double *grad = s->grad[axis] + ch * n;
            for (int l = 0; l < (int)order; ++l)
                for (int m = -l; m <= l; ++m) {
                    const double polar = A[ic_hsh_index(l, m < 0 ? -m : m)];
                    grad[ic_hsh_index(l, m)] += polar * slot[m >= 0 ? m : (int)order - 1 - m];
                }
        }
}

/* The walls of ring j: the θ-walls to ring j+1 (at θ_w = θ_{j+1}) and the φ-walls between its sectors,
 * into the gradients of E and of Λ.
 *   θ-wall between (j, k) = A and (j+1, k) = B, φ ∈ [φ_k, φ_k + Δφ]: n_A = e_θ = (cosθcosφ, cosθsinφ,
 *   −sinθ), dl = sinθ dφ, so per unit δ the weight is −sinθ_w cosθ_w (cosφ, sinφ)/d dφ. For E (f = cosθ,
 *   constant along the wall) ∫(cosφ, sinφ)dφ = 2 sin(Δφ/2)(cosφ_m, sinφ_m) exactly; for Λ two Gauss nodes.
 *   φ-wall between (j, k) = A and (j, k+1) = B at φ_w = φ_{k+1}: n_A = e_φ = (−sinφ, cosφ, 0), dl = dθ,
 *   weight −(−sinφ_w, cosφ_w)/d dθ. For E ∫cosθ dθ = sinθ_{j+1} − sinθ_j exactly; for Λ two Gauss nodes in
 *   θ, the same for every sector of the ring. */
static void ring_walls(const ic_gatherer *g, const ic_hsh_basis *basis, uint32_t M, uint32_t N, uint32_t j,
                       double phi0, radiance_sums *s)
{
    const uint32_t order = ic_hsh_order(basis);
    const ic_vec3 *L = g->cell_radiance;
    const float *dist = g->cell_dist;
    const double dphi = 2.0 * (double)IC_PI / N, chord = 2.0 * sin(0.5 * dphi);
    const double z0 = ring_z(j, M), sin0 = ring_sin(j, M), z1 = ring_z(j + 1, M), sin1 = ring_sin(j + 1, M);
    const double t0 = atan2(sin0, z0), t1 = atan2(sin1, z1);
    azimuth_sums theta_walls, phi_walls;
    memset(&theta_walls, 0, sizeof theta_walls);
    memset(&phi_walls, 0, sizeof phi_walls);
    double diff[3];
    for (uint32_t k = 0; k < N; ++k) {
        const uint32_t c = k * M + j;
        const double phi_k = phi0 + dphi * k;
        /* θ-wall to ring j+1 (none at the horizon, where cosθ = 0). */
        if (j + 1 < M) {
            const uint32_t cb = c + 1;
            const float d = fminf(dist[c], dist[cb]);
            if (d < INFINITY && radiance_diff(L[c], L[cb], diff)) {
                const double phi_m = phi_k + 0.5 * dphi, e = -sin1 * z1 * z1 * chord / d;
                const double w = -sin1 * z1 * 0.5 * dphi / d;
                for (int ch = 0; ch < 3; ++ch) {
                    s->egrad[ch][0] += diff[ch] * e * cos(phi_m);
                    s->egrad[ch][1] += diff[ch] * e * sin(phi_m);
                }
                for (int i = 0; i < 2; ++i) {
                    const double phi = phi_k + GAUSS_NODE[i] * dphi;
                    add_azimuth(order, phi, diff, w * cos(phi), w * sin(phi), &theta_walls);
                }
            }
        }
        /* φ-wall to sector k+1, wrapping around. */
        if (N > 1) {
            const uint32_t cb = (k + 1 == N ? 0 : k + 1) * M + j;
            const float d = fminf(dist[c], dist[cb]);
            if (d < INFINITY && radiance_diff(L[c], L[cb], diff)) {
                const double phi_w = phi_k + dphi, vx = -sin(phi_w), vy = cos(phi_w);
                const double e = -(sin1 - sin0) / d, w = -0.5 * (t1 - t0) / d;
                for (int ch = 0; ch < 3; ++ch) {
                    s->egrad[ch][0] += diff[ch] * e * vx;
                    s->egrad[ch][1] += diff[ch] * e * vy;
                }
                add_azimuth(order, phi_w, diff, w * vx, w * vy, &phi_walls);
            }
        }
    }
    double A[IC_HSH_MAX_COUNT];
    if (theta_walls.is_used) {
        polar_terms(basis, &z1, &sin1, 1, A);
        flush_azimuth(basis, A, &theta_walls, s);
    }
    if (phi_walls.is_used) {
        double zn[2], sn[2];
        for (int i = 0; i < 2; ++i) {
            const double t = t0 + GAUSS_NODE[i] * (t1 - t0);
            zn[i] = cos(t);
            sn[i] = sin(t);
        }
        polar_terms(basis, zn, sn, 2, A);
        flush_azimuth(basis, A, &phi_walls, s);
    }
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
 * sectors than N ≈ 4M pay: at ~800 rays the projection error is 15% lower (docs/radiance-caching.md §5). */
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
    for (uint32_t c = 0; c < n_rays; ++c) {
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
    }
    for (uint32_t j = 0; j < M; ++j)
        ring_walls(g, basis, M, N, j, phi0, s);

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
