/*
 * gather_progressive.c — progressive Hammersley hemisphere sampling with odd/even convergence
 * (Frolov et al. 2012 §4.1; convergence estimate after Křivánek et al. 2006 §4.3).
 *
 * All points start in the active set. Round r traces n_r = first·growth^r rays (4096, 16384, 65536 by
 * default) for every still-active point; afterwards a point leaves the active set when
 * |Y(E_odd) − Y(E_even)| < threshold · Y(E), or when the round just traced had max_rays rays.
 *
 * Directions. Round r of a point uses the Hammersley set x_i = i/n, y_i = Φ2(i) (i < n = 2^m), mapped to
 * φ = φ0 + 2π x_i and sin²θ = y_i + η/n (cosine-weighted, Malley's method in polar form). Per point and
 * per round, φ0 and η ∈ [0,1) come from ic_rng_make(seed, key, r, PROGRESSIVE): a rotation about the
 * normal plus a shift smaller than the lattice step in y, so the set stays a (0,m,2)-net while
 * neighbouring records (and successive rounds) see decorrelated patterns — without it every record would
 * probe the same directions and alias against the same geometry. Consecutive indices share a φ wedge,
 * so each run of M consecutive rays (M ≥ 32 for n ≥ 4096) is one coherent group of 32·k rays, as the
 * GPU implementation of Frolov et al. 2012 §4.1 arranges its "sectors". Rays go to the tracer in index
 * order.
 *
 * Rounds are independent point sets (a Hammersley set of 4n points does not contain the one of n
 * points); each round's estimate enters the result weighted by its ray count, so no ray is wasted: the
 * irradiance is the average of all the point's samples.
 *
 * Odd/even split. Splitting by index parity would be wrong for Hammersley: i even ⇔ Φ2(i) < ½, so the
 * "even" half would only see the upper half of the sin²θ range. We split by the parity of popcount(i)
 * (Thue–Morse): for any elementary interval of area 2/n the one free index bit decides the parity, so
 * each half is a (0,m−1,2)-net in its own right, and E_even, E_odd are honest half-size estimates.
 *
 * Gradients. Because the set is a (0,m,2)-net, the M×N grid with M = 2^⌊(m−1)/2⌋ (m odd) or 2^(m/2−1)
 * (m even) strata in sin²θ and N = n/M strata in φ (N/M = 2 or 4, the powers of two nearest the π of
 * the stratified sampler) holds exactly one sample per cell; cell (j, k) = (rev_m(i) ≫ (m − log2 M),
 * i ≫ (m − log2 N)). The stratified Ward–Heckbert / Křivánek gradient estimators (gather_grid.c)
 * therefore apply unchanged, with no auxiliary pass and no extra rays. The rotational gradient needs no
 * structure at all (any cosine-weighted set), the translational one needs the wall neighbours that the
 * net provides.
 */
#include "gather_internal.h"

#include "core/rng.h"

#include <stdlib.h>

static uint32_t reverse_bits32(uint32_t i)
{
    i = (i << 16) | (i >> 16);
    i = ((i & 0x00ff00ffu) << 8) | ((i & 0xff00ff00u) >> 8);
    i = ((i & 0x0f0f0f0fu) << 4) | ((i & 0xf0f0f0f0u) >> 4);
    i = ((i & 0x33333333u) << 2) | ((i & 0xccccccccu) >> 2);
    i = ((i & 0x55555555u) << 1) | ((i & 0xaaaaaaaau) >> 1);
    return i;
}

static uint32_t log2_pow2(uint32_t n)
{
    uint32_t m = 0;
    while ((1u << m) < n)
        ++m;
    return m;
}

static uint32_t popcount32(uint32_t x)
{
    x = x - ((x >> 1) & 0x55555555u);
    x = (x & 0x33333333u) + ((x >> 2) & 0x33333333u);
    x = (x + (x >> 4)) & 0x0f0f0f0fu;
    return (x * 0x01010101u) >> 24;
}

typedef struct point_state {
    ic_gather_acc acc;
    ic_frame frame;
} point_state;

/* Traces one round of n = 2^m rays for one point and adds its estimate to acc. */
static void trace_round(ic_gatherer *g, const ic_gather_point *pt, const ic_frame *frame, uint32_t round,
                        uint32_t n, ic_gather_acc *acc)
{
    const uint32_t m = log2_pow2(n);
    const uint32_t log_M = (m & 1u) ? (m - 1) / 2 : m / 2 - 1;
    const uint32_t M = 1u << log_M, N = n >> log_M;
    const uint32_t log_N = m - log_M;

    ic_rng rng = ic_rng_make(g->opts.seed, pt->key, round, IC_GATHER_STREAM_PROGRESSIVE);
    const float phi0 = 2.0f * IC_PI * ic_rng_float(&rng);
    const double eta = ic_rng_double(&rng);
    const double inv_n = 1.0 / n;

    for (uint32_t first = 0; first < n; first += g->batch) {
        const uint32_t count = n - first < g->batch ? n - first : g->batch;
        for (uint32_t r = 0; r < count; ++r) {
            const uint32_t i = first + r;
            const uint32_t rev = m ? reverse_bits32(i) >> (32 - m) : 0;   /* = Φ2(i)·n exactly */
            const uint32_t j = rev >> (m - log_M), k = i >> (m - log_N);
            const uint32_t c = k * M + j;
            const double s2 = ((double)rev + eta) * inv_n;
            const float sin_t = (float)sqrt(s2), cos_t = (float)sqrt(fmax(0.0, 1.0 - s2));
            const float phi = phi0 + 2.0f * IC_PI * (float)((double)i * inv_n);
            g->cell_dir[c] = v3(sin_t * cosf(phi), sin_t * sinf(phi), cos_t);
            g->cell_half[c] = (uint8_t)(popcount32(i) & 1u);
            g->ray_cell[r] = c;
        }
        ic_gather_trace_chunk(g, frame, pt->position, count);
    }
    ic_gather_grid_accumulate(g, M, N, phi0, acc);
}

ic_result ic_gather_progressive(ic_gatherer *g, const ic_gather_point *pts, uint32_t count,
                                ic_gather_result *out)
{
    if (!g || (count && (!pts || !out)))
        return IC_ERR_INVALID_ARG;
    if (count == 0)
        return IC_OK;

    point_state *state = malloc(sizeof *state * count);
    uint32_t *active = malloc(sizeof *active * count);
    if (!state || !active) {
        free(state);
        free(active);
        return IC_ERR_OOM;
    }
    for (uint32_t p = 0; p < count; ++p) {
        ic_result res = ic_gather_point_frame(&pts[p], &state[p].frame);
        if (res != IC_OK) {
            free(state);
            free(active);
            return res;
        }
        ic_gather_acc_init(&state[p].acc);
        active[p] = p;
    }

    const float threshold = g->opts.threshold;
    uint32_t n_active = count, n = g->opts.first_round_rays;
    for (uint32_t round = 0; n_active > 0; ++round) {
        const int last = n >= g->opts.max_rays;
        uint32_t kept = 0;
        for (uint32_t a = 0; a < n_active; ++a) {
            const uint32_t p = active[a];
            point_state *s = &state[p];
            trace_round(g, &pts[p], &s->frame, round, n, &s->acc);
            ic_gather_acc_finish(&s->acc, &s->frame, &out[p]);
            /* σ = |E − E_even| = |E_odd − E_even| / 2 (gather_grid.c), so the Frolov et al. test
             * |E_odd − E_even| / E < threshold reads 2·Y(σ-vector) < threshold·Y(E). Written as a
             * product so E = 0 with no disagreement counts as converged. */
            const double dy = 0.2126 * (s->acc.e[0] - s->acc.e_half[0]) +
                              0.7152 * (s->acc.e[1] - s->acc.e_half[1]) +
                              0.0722 * (s->acc.e[2] - s->acc.e_half[2]);
            const float y_diff = (float)(2.0 * fabs(dy) / s->acc.rays);
            const float y = v3_lum(out[p].irradiance);
            const int converged = threshold >= 0.0f && y_diff <= threshold * y;
            out[p].is_converged = converged;
            if (!converged && !last)
                active[kept++] = p;
        }
        n_active = kept;
        if (!last)
            n = n * g->opts.round_growth > g->opts.max_rays ? g->opts.max_rays : n * g->opts.round_growth;
    }
    free(state);
    free(active);
    return IC_OK;
}
