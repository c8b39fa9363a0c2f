/*
 * gather_stratified.c — M×N stratified cosine-weighted hemisphere gather (Ward & Heckbert 1992;
 * Křivánek et al. 2005 (SCCG) gradients; σ per Křivánek et al. 2006 §4.3).
 *
 * Cell (j, k) holds one ray with sin²θ = (j + ξ1)/M and φ = φ0 + 2π(k + ξ2)/N: equal projected solid
 * angle per cell, so the estimator weights every ray by π/(MN). φ0 is a per-record rotation about the
 * normal, so neighbouring records with the same M×N pattern do not alias against the same geometry.
 * N defaults to round(π·M), which makes the cells roughly square in solid angle near the pole
 * (Ward 1994 / Radiance use the same ratio). All random numbers come from
 * ic_rng_make(seed, key, 0, STRATIFIED): a record's directions depend on nothing else.
 *
 * Rays are issued column by column (k-major), so each trace batch holds groups of M rays in one φ
 * wedge: nearby directions, which helps the caller's packet/stream tracer.
 *
 * The odd/even split for σ is a checkerboard of the cells, (j + k) mod 2: each half is itself a
 * stratified M×N/2-ish set, so E' is a fair (if coarser) estimate of E.
 */
#include "gather_internal.h"

#include "core/rng.h"

ic_result ic_gather_stratified(ic_gatherer *g, const ic_gather_point *pt, ic_gather_result *out)
{
    if (!g || !pt || !out)
        return IC_ERR_INVALID_ARG;
    ic_frame frame;
    ic_result res = ic_gather_point_frame(pt, &frame);
    if (res != IC_OK)
        return res;

    const uint32_t M = g->opts.theta_strata, N = g->opts.phi_strata;
    ic_rng rng = ic_rng_make(g->opts.seed, pt->key, 0, IC_GATHER_STREAM_STRATIFIED);
    const float phi0 = 2.0f * IC_PI * ic_rng_float(&rng);

    for (uint32_t k = 0; k < N; ++k) {
        for (uint32_t j = 0; j < M; ++j) {
            const uint32_t c = k * M + j;
            const float u1 = ic_rng_float(&rng), u2 = ic_rng_float(&rng);
            const float s2 = ((float)j + u1) / (float)M;
            const float sin_t = sqrtf(s2), cos_t = sqrtf(fmaxf(0.0f, 1.0f - s2));
            const float phi = phi0 + 2.0f * IC_PI * ((float)k + u2) / (float)N;
            g->cell_dir[c] = v3(sin_t * cosf(phi), sin_t * sinf(phi), cos_t);
            g->cell_half[c] = (uint8_t)((j + k) & 1u);
        }
    }

    const uint32_t n = M * N;
    for (uint32_t first = 0; first < n; first += g->batch) {
        const uint32_t count = n - first < g->batch ? n - first : g->batch;
        for (uint32_t r = 0; r < count; ++r)
            g->ray_cell[r] = first + r;
        ic_gather_trace_chunk(g, &frame, pt->position, count);
    }

    ic_gather_acc acc;
    ic_gather_acc_init(&acc);
    ic_gather_grid_accumulate(g, M, N, phi0, &acc);
    ic_gather_acc_finish(&acc, &frame, out);
    out->is_converged = 1;
    if (g->opts.with_hessian)
        ic_gather_hessian_grid(g, M, N, phi0, &frame, out);
    return IC_OK;
}
