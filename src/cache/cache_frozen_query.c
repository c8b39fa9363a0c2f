/*
 * cache_frozen_query.c — look-ups on the irradiance cache's frozen layout (cache_store.h: ic_frozen;
 * built by cache_frozen.c): finding a point's leaf, the portable, SSE2 and AVX2 code paths, the choice
 * among them, and batches of look-ups (include/irrcache/cache.h: FROZEN LOOK-UPS).
 */
#include "cache_store.h"

#include <math.h>
#include <string.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
/* Eight entries at a time where the CPU has AVX2 (chosen at run time; the build stays baseline). */
#if defined(__SSE2__) && defined(__x86_64__) && defined(__GNUC__)
#define IC_HAVE_AVX2_PATH 1
#include <immintrin.h>
#define IC_TARGET_AVX2 __attribute__((target("avx2")))
#endif

/* Helpers of the frozen look-ups are inlined into each code path and into the batch loop. */
#if defined(__GNUC__)
#define IC_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define IC_ALWAYS_INLINE inline
#endif

/* The leaf a hint names; NULL for none or a value out of range (any value is safe). */
static inline const ic_frozen_leaf *hint_leaf(const ic_frozen *f, const ic_cache_hint *hint)
{
    if (!hint || hint->leaf - 1u >= f->leaf_count)
        return NULL;
    return (const ic_frozen_leaf *)(f->list + f->leaf_at[hint->leaf - 1u]);
}

#if defined(__SSE2__)
/* p's leaf by descent from the root (pv: p, 4th lane unused), NULL outside the root. The three axes go
 * side by side: the comparisons of the octree's descent (octree.h: ic_octree_path), and c ± h as
 * c + (±h), which IEEE arithmetic rounds alike, so the same leaf; and no branch on an axis's side,
 * which no predictor guesses. With lo and hi (else NULL) it also stores the leaf's cell there, found
 * as the builder finds it (octree.h: ic_octree_child_cell, the same operations): a point inside it
 * descends to the same leaf. */
static IC_ALWAYS_INLINE const ic_frozen_leaf *descend_sse2(const ic_frozen *f, __m128 pv, __m128 *lo, __m128 *hi)
{
    if (!f->has_root)
        return NULL;
    __m128 l = _mm_loadu_ps(f->root_lo), h = _mm_loadu_ps(f->root_hi);
    if ((_mm_movemask_ps(_mm_and_ps(_mm_cmpge_ps(pv, l), _mm_cmplt_ps(pv, h))) & 7) != 7)
        return NULL;
    __m128 cv = _mm_setr_ps(f->cx, f->cy, f->cz, 0.0f), hv = _mm_set1_ps(f->half);
    const __m128 sign = _mm_set1_ps(-0.0f), half = _mm_set1_ps(0.5f);
    const uint32_t *node = f->node;
    uint32_t v = node[0];
    while (!(v & IC_FROZEN_LEAF)) {
        hv = _mm_mul_ps(hv, half);
        __m128 upper = _mm_cmpge_ps(pv, cv);
        if (lo) { /* the child's cell: above the centre lo = max(lo, centre), below it hi = min(hi, centre) */
            l = _mm_or_ps(_mm_and_ps(upper, _mm_max_ps(l, cv)), _mm_andnot_ps(upper, l));
            h = _mm_or_ps(_mm_and_ps(upper, h), _mm_andnot_ps(upper, _mm_min_ps(h, cv)));
        }
        cv = _mm_add_ps(cv, _mm_xor_ps(hv, _mm_andnot_ps(upper, sign)));
        v = node[v + ((unsigned)_mm_movemask_ps(upper) & 7u)];
    }
    if (lo) {
        *lo = l;
        *hi = h;
    }
    return (const ic_frozen_leaf *)(f->list + (v & ~IC_FROZEN_LEAF));
}
#endif

/* Frozen layout: the leaf whose cell holds p — the hint's when p is still in its cell, else found by
 * descent, which updates the hint; NULL outside the root. With SSE2 (unless is_portable), descend_sse2. */
static IC_ALWAYS_INLINE const ic_frozen_leaf *frozen_leaf(const ic_frozen *f, ic_vec3 p, ic_cache_hint *hint,
                                                          int is_portable)
{
#if defined(__SSE2__)
    if (!is_portable) {
        __m128 pv = _mm_setr_ps(p.x, p.y, p.z, 0.0f);
        const ic_frozen_leaf *l = hint_leaf(f, hint);
        if (l && (_mm_movemask_ps(_mm_and_ps(_mm_cmpge_ps(pv, _mm_loadu_ps(l->lo)),
                                             _mm_cmplt_ps(pv, _mm_loadu_ps(l->hi)))) & 7) == 7)
            return l;
        l = descend_sse2(f, pv, NULL, NULL);
        if (l && hint)
            hint->leaf = l->id + 1u;
        return l;
    }
#endif
    (void)is_portable;
    const ic_frozen_leaf *l = hint_leaf(f, hint);
    if (l && p.x >= l->lo[0] && p.x < l->hi[0] && p.y >= l->lo[1] && p.y < l->hi[1] && p.z >= l->lo[2] &&
        p.z < l->hi[2])
        return l;
    float cx = f->cx, cy = f->cy, cz = f->cz, h = f->half;
    if (!f->has_root ||
        !(p.x >= cx - h && p.x <= cx + h && p.y >= cy - h && p.y <= cy + h && p.z >= cz - h && p.z <= cz + h))
        return NULL;
    const uint32_t *node = f->node;
    uint32_t v = node[0];
    while (!(v & IC_FROZEN_LEAF)) {
        /* The octree's descent arithmetic (octree.h: ic_octree_path): the same leaf, bit for bit. */
        h *= 0.5f;
        unsigned ox = p.x >= cx, oy = p.y >= cy, oz = p.z >= cz;
        cx = ox ? cx + h : cx - h;
        cy = oy ? cy + h : cy - h;
        cz = oz ? cz + h : cz - h;
        v = node[v + (ox | oy << 1 | oz << 2)];
    }
    l = (const ic_frozen_leaf *)(f->list + (v & ~IC_FROZEN_LEAF));
    if (hint)
        hint->leaf = l->id + 1u;
    return l;
}

/*
 * Frozen look-ups. A leaf's list is read one block of eight entries at a time; every test and the
 * extrapolation of Křivánek et al. 2006 §3 run on the eight lanes side by side. The entry at list
 * position k, if it contributes, adds w_i·E_i(p) and w_i to the running sums of lane k mod 8; the eight lane sums
 * are added in one fixed order at the end (lane_total). Every code path — portable C, SSE2
 * (two halves of four lanes), AVX2 (eight) — performs the same IEEE operations on the same operands
 * per lane (packed add, mul, div and sqrt round like their scalar forms; no FMA: contraction is off),
 * so all three give the same bits. Against the octree path: the same contributors in the same order
 * with the same weights; the extrapolated values and the sums differ in rounding only (the rotation
 * term is evaluated as n·(∇r E_i × n_i), cache_store.h; the octree path adds in list order).
 */

/* Offsets of a channel's rows in a block's interpolation data, read as one array of floats. */
enum {
    ROW_E = IC_FROZEN_LANES * IC_FROZEN_E,
    ROT_X = IC_FROZEN_LANES * IC_FROZEN_GRAD_ROT,
    ROT_Y = ROT_X + IC_FROZEN_LANES,
    ROT_Z = ROT_Y + IC_FROZEN_LANES,
    TRANS_X = IC_FROZEN_LANES * IC_FROZEN_GRAD_TRANS,
    TRANS_Y = TRANS_X + IC_FROZEN_LANES,
    TRANS_Z = TRANS_Y + IC_FROZEN_LANES
};

/* Σ of eight lane sums: ((0 + 4) + (2 + 6)) + ((1 + 5) + (3 + 7)), the order of a SIMD reduction. */
static inline float lane_total(const float l[IC_FROZEN_LANES])
{
    return ((l[0] + l[4]) + (l[2] + l[6])) + ((l[1] + l[5]) + (l[3] + l[7]));
}

/* The estimate from the lane sums: acc[c][k] = Σ w_i E_i(p) of channel c in lane k, wsum[k] = Σ w_i. */
static int finish_lanes(ic_cache_estimate *out, float acc[3][IC_FROZEN_LANES], const float wsum[IC_FROZEN_LANES],
                        uint32_t contributors)
{
    float total[3] = {lane_total(acc[0]), lane_total(acc[1]), lane_total(acc[2])};
    out->weight_sum = lane_total(wsum);
    out->contributor_count = contributors;
    return ic_estimate_finish(out, total);
}

/* Writes the contributors among lanes first + k (k: the bits of mask) of block b to the caller's
 * buffer while there is room, in lane order; w and v[c] hold the lanes' weights and values from lane
 * `first` on. */
static void report_lanes(const ic_frozen_block *b, unsigned first, unsigned mask, const float *w, const float *v0,
                         const float *v1, const float *v2, const ic_cache_lookup *q, ic_cache_estimate *out)
{
    for (unsigned k = 0; mask; ++k, mask >>= 1) {
        if (!(mask & 1u) || out->contributions_written >= q->contribution_capacity)
            continue;
        ic_cache_contribution *o = &q->contributions[out->contributions_written++];
        o->record = b->index[first + k];
        o->weight = w[k];
        o->value = v3(v0[k], v1[k], v2[k]);
    }
}

/* One block, entry by entry with ic_weight_test itself: the reference for the SIMD code below, the
 * code where SSE2 is absent, and the path of caches with elliptical records or the error weight
 * (squeeze: the cache's squeeze array, read by record index; NULL when every record is round).
 * Returns the block's number of contributors. */
static unsigned block_portable(const ic_cache_params *params, const ic_float4 *squeeze, const ic_frozen_block *b,
                               ic_vec3 p, ic_vec3 n, float s, const ic_cache_lookup *q, ic_cache_estimate *out,
                               float acc[3][IC_FROZEN_LANES], float wsum[IC_FROZEN_LANES])
{
    float w[IC_FROZEN_LANES] = {0}, v[3][IC_FROZEN_LANES] = {{0}};
    unsigned mask = 0;
    for (unsigned k = 0; k < IC_FROZEN_LANES; ++k) {
        ic_float4 sp = {b->x[k], b->y[k], b->z[k], b->R[k]}, np = {b->nx[k], b->ny[k], b->nz[k], b->a[k]};
        ic_vec3 dp;
        /* Padding entries (R = 0) pass no test; their index is 0, a valid record, for the squeeze. */
        if (b->bounce[k] != q->bounce || (b->flags[k] & IC_RECORD_DISABLED) ||
            !ic_weight_test(params, &sp, &np, squeeze ? &squeeze[b->index[k]] : NULL, p, n, s, &w[k], &dp))
            continue;
        for (int ch = 0; ch < 3; ++ch) {
            /* The rotation term (n_i × n)·∇r E_i as n·(∇r E_i × n_i), the cross product made at freezing. */
            const float *row = b->interp + IC_FROZEN_LANES * IC_FROZEN_ROWS * ch;
            float e = (row[ROW_E + k] + ((n.x * row[ROT_X + k] + n.y * row[ROT_Y + k]) + n.z * row[ROT_Z + k])) +
                      ((dp.x * row[TRANS_X + k] + dp.y * row[TRANS_Y + k]) + dp.z * row[TRANS_Z + k]);
            /* Extrapolation with large gradients can go negative; irradiance cannot. */
            v[ch][k] = e > 0.0f ? e : 0.0f;
            acc[ch][k] += w[k] * v[ch][k];
        }
        wsum[k] += w[k];
        mask |= 1u << k;
    }
    if (q->contributions)
        report_lanes(b, 0, mask, w, v[0], v[1], v[2], q, out);
    unsigned count = 0;
    for (; mask; mask &= mask - 1)
        ++count;
    return count;
}

/* Start of a frozen look-up in p's leaf (NULL: p is outside the root): clears the estimate and returns
 * the leaf's first block (NULL without a leaf), its number of blocks, the acceptance's accuracy scale
 * and whether every entry of the leaf is eligible (q's bounce level, none disabled: the SIMD code then
 * skips that test). */
static IC_ALWAYS_INLINE const ic_frozen_block *leaf_begin(const ic_cache *c, const ic_cache_lookup *q,
                                                          const ic_frozen_leaf *leaf, ic_cache_estimate *out,
                                                          uint32_t *blocks, float *s, int *all_eligible)
{
    memset(out, 0, sizeof *out);
    if (!leaf)
        return NULL;
    *s = q->acceptance == IC_ACCEPT_FINAL ? c->params.final_accuracy_scale : 1.0f;
    /* Bounce levels are stored in bytes: a higher level has no records. */
    *blocks = q->bounce <= UINT8_MAX ? (leaf->count + IC_FROZEN_LANES - 1) / IC_FROZEN_LANES : 0;
    out->records_tested = leaf->count;
    *all_eligible = leaf->all_eligible == q->bounce + 1u;
    return (const ic_frozen_block *)(leaf + 1);
}

/* leaf_begin in the leaf frozen_leaf finds with the hint. */
static IC_ALWAYS_INLINE const ic_frozen_block *frozen_begin(const ic_cache *c, const ic_cache_lookup *q,
                                                            ic_cache_hint *hint, ic_cache_estimate *out,
                                                            int is_portable, uint32_t *blocks, float *s,
                                                            int *all_eligible)
{
    const ic_frozen_leaf *leaf = frozen_leaf(&c->frozen, q->position, hint, is_portable);
    return leaf_begin(c, q, leaf, out, blocks, s, all_eligible);
}

static int query_frozen_portable(const ic_cache *c, const ic_cache_lookup *q, ic_cache_hint *hint,
                                 ic_cache_estimate *out)
{
    float acc[3][IC_FROZEN_LANES] = {{0}}, wsum[IC_FROZEN_LANES] = {0}, s;
    uint32_t blocks, contributors = 0;
    int all_eligible; /* unused: the reference checks every entry */
    const ic_frozen_block *blk = frozen_begin(c, q, hint, out, 1, &blocks, &s, &all_eligible);
    if (!blk)
        return 0;
    for (uint32_t b = 0; b < blocks; ++b)
        contributors += block_portable(&c->params, c->ellipse_count ? c->squeeze : NULL, &blk[b], q->position,
                                       q->normal, s, q, out, acc, wsum);
    return finish_lanes(out, acc, wsum, contributors);
}

#if defined(__SSE2__)
/* Byte k: all ones where entry k is of this bounce level and not disabled (bounce and flag bytes of up
 * to 16 entries side by side). */
static IC_ALWAYS_INLINE __m128i eligible_bytes(__m128i bounce_bytes, __m128i flag_bytes, uint32_t bounce)
{
    const __m128i disabled = _mm_set1_epi8(IC_RECORD_DISABLED);
    return _mm_andnot_si128(_mm_cmpeq_epi8(_mm_and_si128(flag_bytes, disabled), disabled),
                            _mm_cmpeq_epi8(bounce_bytes, _mm_set1_epi8((char)bounce)));
}

/* Lanes h…h+3 of block b (h = 0 or 4), block_portable four lanes at a time: ic_weight_test's tests,
 * each with the same operations on the same operands, then the extrapolation and the lane sums acc[c]
 * and wsum (lanes h…h+3). Returns the lanes' mask. */
static IC_ALWAYS_INLINE unsigned half_sse2(const ic_frozen_block *b, unsigned h, ic_vec3 p, ic_vec3 n, float s,
                                           float neg_tolerance, int ward, int all_eligible, const ic_cache_lookup *q,
                                           ic_cache_estimate *out, __m128 acc[3], __m128 *wsum)
{
    const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
    __m128 dx = _mm_sub_ps(_mm_set1_ps(p.x), _mm_loadu_ps(b->x + h));
    __m128 dy = _mm_sub_ps(_mm_set1_ps(p.y), _mm_loadu_ps(b->y + h));
    __m128 dz = _mm_sub_ps(_mm_set1_ps(p.z), _mm_loadu_ps(b->z + h));
    __m128 d2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
    __m128 a = _mm_mul_ps(_mm_loadu_ps(b->a + h), _mm_set1_ps(s)), R = _mm_loadu_ps(b->R + h), r = _mm_mul_ps(a, R);
    /* Inside the influence sphere: most halves fail this in every lane and stop here. */
    __m128 pass = _mm_cmplt_ps(d2, _mm_mul_ps(r, r));
    if (!_mm_movemask_ps(pass))
        return 0;
    /* Not facing away (!(ndot <= 0): a NaN goes on, as in the scalar code). */
    __m128 qx = _mm_set1_ps(n.x), qy = _mm_set1_ps(n.y), qz = _mm_set1_ps(n.z);
    __m128 nx = _mm_loadu_ps(b->nx + h), ny = _mm_loadu_ps(b->ny + h), nz = _mm_loadu_ps(b->nz + h);
    __m128 ndot = _mm_add_ps(_mm_add_ps(_mm_mul_ps(qx, nx), _mm_mul_ps(qy, ny)), _mm_mul_ps(qz, nz));
    pass = _mm_and_ps(pass, _mm_cmpnle_ps(ndot, zero));
    /* Not behind the record. */
    __m128 behind = _mm_mul_ps(_mm_set1_ps(0.5f),
                               _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, _mm_add_ps(qx, nx)),
                                                     _mm_mul_ps(dy, _mm_add_ps(qy, ny))),
                                          _mm_mul_ps(dz, _mm_add_ps(qz, nz))));
    pass = _mm_and_ps(pass, _mm_cmpnlt_ps(behind, _mm_mul_ps(_mm_set1_ps(neg_tolerance), r)));
    /* max(x, 0) is x > 0 ? x : 0, NaN included (maxps returns its second operand unless x > 0). */
    __m128 dist = _mm_div_ps(_mm_sqrt_ps(d2), R), ndev = _mm_sqrt_ps(_mm_max_ps(_mm_sub_ps(one, ndot), zero)), w;
    if (ward) {
        __m128 denom = _mm_add_ps(dist, ndev);
        pass = _mm_and_ps(pass, _mm_cmplt_ps(denom, a));
        w = _mm_div_ps(one, _mm_max_ps(denom, _mm_set1_ps(1e-6f)));
    } else {
        __m128 nt = _mm_mul_ps(ndev, _mm_set1_ps(IC_TL_NORMAL_SCALE));
        w = _mm_sub_ps(one, _mm_div_ps(_mm_max_ps(dist, nt), a));
        pass = _mm_and_ps(pass, _mm_cmpgt_ps(w, zero));
    }
    /* Eligible: this bounce level, not disabled (bytes widened to the float lanes' 32 bits). */
    if (!all_eligible) {
        int32_t bounce_bytes, flag_bytes;
        memcpy(&bounce_bytes, b->bounce + h, 4);
        memcpy(&flag_bytes, b->flags + h, 4);
        __m128i ok = eligible_bytes(_mm_cvtsi32_si128(bounce_bytes), _mm_cvtsi32_si128(flag_bytes), q->bounce);
        ok = _mm_unpacklo_epi16(_mm_unpacklo_epi8(ok, ok), _mm_unpacklo_epi8(ok, ok));
        pass = _mm_and_ps(pass, _mm_castsi128_ps(ok));
    }
    /* E_i(p) = E_i + n·(∇r E_i × n_i) + (p − p_i)·∇t E_i per channel, clamped ≥ 0; the lanes that do
     * not contribute add +0 (masked after the product, so no NaN or infinity gets in). */
    __m128 v[3];
    for (int ch = 0; ch < 3; ++ch) {
        const float *row = b->interp + IC_FROZEN_LANES * IC_FROZEN_ROWS * ch;
        __m128 rot = _mm_add_ps(_mm_add_ps(_mm_mul_ps(qx, _mm_loadu_ps(row + ROT_X + h)),
                                           _mm_mul_ps(qy, _mm_loadu_ps(row + ROT_Y + h))),
                                _mm_mul_ps(qz, _mm_loadu_ps(row + ROT_Z + h)));
        __m128 trans = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, _mm_loadu_ps(row + TRANS_X + h)),
                                             _mm_mul_ps(dy, _mm_loadu_ps(row + TRANS_Y + h))),
                                  _mm_mul_ps(dz, _mm_loadu_ps(row + TRANS_Z + h)));
        v[ch] = _mm_max_ps(_mm_add_ps(_mm_add_ps(_mm_loadu_ps(row + ROW_E + h), rot), trans), zero);
        acc[ch] = _mm_add_ps(acc[ch], _mm_and_ps(pass, _mm_mul_ps(w, v[ch])));
    }
    *wsum = _mm_add_ps(*wsum, _mm_and_ps(pass, w));
    unsigned mask = (unsigned)_mm_movemask_ps(pass);
    if (q->contributions) {
        float wl[4], v0[4], v1[4], v2[4];
        _mm_storeu_ps(wl, w);
        _mm_storeu_ps(v0, v[0]);
        _mm_storeu_ps(v1, v[1]);
        _mm_storeu_ps(v2, v[2]);
        report_lanes(b, h, mask, wl, v0, v1, v2, q, out);
    }
    return mask;
}

/* (s0 + s2) + (s1 + s3) of four lane sums s_k = l_k + l_{k+4}: lane_total's order. */
static inline float lane_total_sse2(__m128 s)
{
    __m128 t = _mm_add_ps(s, _mm_movehl_ps(s, s)); /* s0 + s2, s1 + s3 */
    return _mm_cvtss_f32(_mm_add_ss(t, _mm_shuffle_ps(t, t, 1)));
}

/* Bits set in a 4-bit mask. */
static const uint8_t bits_in[16] = {0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4};

static int query_frozen_sse2(const ic_cache *c, const ic_cache_lookup *q, ic_cache_hint *hint, ic_cache_estimate *out)
{
    float s;
    uint32_t blocks, contributors = 0;
    int all_eligible;
    const ic_frozen_block *blk = frozen_begin(c, q, hint, out, 0, &blocks, &s, &all_eligible);
    if (!blk)
        return 0;
    ic_vec3 p = q->position, n = q->normal;
    float neg_tolerance = -c->params.behind_tolerance; /* read once, as in query_leaf_avx2 */
    int ward = c->params.weight == IC_WEIGHT_WARD;
    /* Lane sums: [0] lanes 0–3, [1] lanes 4–7. */
    __m128 acc[2][3], wsum[2];
    for (int h = 0; h < 2; ++h) {
        acc[h][0] = acc[h][1] = acc[h][2] = wsum[h] = _mm_setzero_ps();
    }
    for (uint32_t b = 0; b < blocks; ++b)
        for (unsigned h = 0; h < 2; ++h)
            contributors += bits_in[half_sse2(&blk[b], 4 * h, p, n, s, neg_tolerance, ward, all_eligible, q, out,
                                              acc[h], &wsum[h])];
    out->weight_sum = lane_total_sse2(_mm_add_ps(wsum[0], wsum[1]));
    out->contributor_count = contributors;
    float total[3];
    for (int ch = 0; ch < 3; ++ch)
        total[ch] = lane_total_sse2(_mm_add_ps(acc[0][ch], acc[1][ch]));
    return ic_estimate_finish(out, total);
}
#endif

#if defined(IC_HAVE_AVX2_PATH)
/* E_i(p) of a block's eight lanes for one channel (row: the channel's interpolation data), clamped
 * ≥ 0, with block_portable's operations: (E + ((nx·H.x + ny·H.y) + nz·H.z)) + ((dx·∇t.x + …)) where
 * H = ∇r E_i × n_i and n is our normal. */
static IC_TARGET_AVX2 IC_ALWAYS_INLINE __m256 extrapolate_avx2(const float *row, __m256 nx, __m256 ny, __m256 nz,
                                                               __m256 dx, __m256 dy, __m256 dz)
{
    __m256 rot = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(nx, _mm256_loadu_ps(row + ROT_X)),
                                             _mm256_mul_ps(ny, _mm256_loadu_ps(row + ROT_Y))),
                               _mm256_mul_ps(nz, _mm256_loadu_ps(row + ROT_Z)));
    __m256 trans = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, _mm256_loadu_ps(row + TRANS_X)),
                                               _mm256_mul_ps(dy, _mm256_loadu_ps(row + TRANS_Y))),
                                 _mm256_mul_ps(dz, _mm256_loadu_ps(row + TRANS_Z)));
    return _mm256_max_ps(_mm256_add_ps(_mm256_add_ps(_mm256_loadu_ps(row + ROW_E), rot), trans),
                         _mm256_setzero_ps());
}

/* block_portable eight lanes at a time: half_sse2 with 256-bit registers, lane for lane the same
 * operations on the same operands (no FMA: the target is AVX2 alone). Returns the block's mask. */
static IC_TARGET_AVX2 IC_ALWAYS_INLINE unsigned block_avx2(const ic_frozen_block *b, ic_vec3 p, ic_vec3 n, float s,
                                                           uint32_t bounce, float neg_tolerance, int ward,
                                                           int all_eligible, const ic_cache_lookup *q,
                                                           ic_cache_estimate *out,
                                                           int report, __m256 acc[3], __m256 *wsum)
{
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
    __m256 dx = _mm256_sub_ps(_mm256_set1_ps(p.x), _mm256_loadu_ps(b->x));
    __m256 dy = _mm256_sub_ps(_mm256_set1_ps(p.y), _mm256_loadu_ps(b->y));
    __m256 dz = _mm256_sub_ps(_mm256_set1_ps(p.z), _mm256_loadu_ps(b->z));
    __m256 d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
    __m256 a = _mm256_mul_ps(_mm256_loadu_ps(b->a), _mm256_set1_ps(s)), R = _mm256_loadu_ps(b->R);
    __m256 r = _mm256_mul_ps(a, R);
    __m256 pass = _mm256_cmp_ps(d2, _mm256_mul_ps(r, r), _CMP_LT_OQ);
    if (!_mm256_movemask_ps(pass))
        return 0;
    __m256 qx = _mm256_set1_ps(n.x), qy = _mm256_set1_ps(n.y), qz = _mm256_set1_ps(n.z);
    __m256 nx = _mm256_loadu_ps(b->nx), ny = _mm256_loadu_ps(b->ny), nz = _mm256_loadu_ps(b->nz);
    __m256 ndot = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(qx, nx), _mm256_mul_ps(qy, ny)), _mm256_mul_ps(qz, nz));
    pass = _mm256_and_ps(pass, _mm256_cmp_ps(ndot, zero, _CMP_NLE_UQ));
    __m256 behind = _mm256_mul_ps(_mm256_set1_ps(0.5f),
                                  _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, _mm256_add_ps(qx, nx)),
                                                              _mm256_mul_ps(dy, _mm256_add_ps(qy, ny))),
                                                _mm256_mul_ps(dz, _mm256_add_ps(qz, nz))));
    pass = _mm256_and_ps(pass, _mm256_cmp_ps(behind, _mm256_mul_ps(_mm256_set1_ps(neg_tolerance), r),
                                             _CMP_NLT_UQ));
    __m256 dist = _mm256_div_ps(_mm256_sqrt_ps(d2), R);
    __m256 ndev = _mm256_sqrt_ps(_mm256_max_ps(_mm256_sub_ps(one, ndot), zero)), w;
    if (ward) {
        __m256 denom = _mm256_add_ps(dist, ndev);
        pass = _mm256_and_ps(pass, _mm256_cmp_ps(denom, a, _CMP_LT_OQ));
        w = _mm256_div_ps(one, _mm256_max_ps(denom, _mm256_set1_ps(1e-6f)));
    } else {
        __m256 nt = _mm256_mul_ps(ndev, _mm256_set1_ps(IC_TL_NORMAL_SCALE));
        w = _mm256_sub_ps(one, _mm256_div_ps(_mm256_max_ps(dist, nt), a));
        pass = _mm256_and_ps(pass, _mm256_cmp_ps(w, zero, _CMP_GT_OQ));
    }
    if (!all_eligible) {
        __m128i ok = eligible_bytes(_mm_loadl_epi64((const __m128i *)b->bounce),
                                    _mm_loadl_epi64((const __m128i *)b->flags), bounce);
        pass = _mm256_and_ps(pass, _mm256_castsi256_ps(_mm256_cvtepi8_epi32(ok)));
    }
    /* Channel by channel, written out: a loop over an array of sums kept them in memory. */
    __m256 v0 = extrapolate_avx2(b->interp, qx, qy, qz, dx, dy, dz);
    __m256 v1 = extrapolate_avx2(b->interp + IC_FROZEN_LANES * IC_FROZEN_ROWS, qx, qy, qz, dx, dy, dz);
    __m256 v2 = extrapolate_avx2(b->interp + 2 * IC_FROZEN_LANES * IC_FROZEN_ROWS, qx, qy, qz, dx, dy, dz);
    acc[0] = _mm256_add_ps(acc[0], _mm256_and_ps(pass, _mm256_mul_ps(w, v0)));
    acc[1] = _mm256_add_ps(acc[1], _mm256_and_ps(pass, _mm256_mul_ps(w, v1)));
    acc[2] = _mm256_add_ps(acc[2], _mm256_and_ps(pass, _mm256_mul_ps(w, v2)));
    *wsum = _mm256_add_ps(*wsum, _mm256_and_ps(pass, w));
    unsigned mask = (unsigned)_mm256_movemask_ps(pass);
    if (report) {
        float wl[8], e0[8], e1[8], e2[8];
        _mm256_storeu_ps(wl, w);
        _mm256_storeu_ps(e0, v0);
        _mm256_storeu_ps(e1, v1);
        _mm256_storeu_ps(e2, v2);
        report_lanes(b, 0, mask, wl, e0, e1, e2, q, out);
    }
    return mask;
}

/* lane_total in registers: the halves added lane by lane (0 + 4, 1 + 5, 2 + 6, 3 + 7), then
 * lane_total_sse2. */
static IC_TARGET_AVX2 inline float lane_total_avx2(__m256 v)
{
    return lane_total_sse2(_mm_add_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1)));
}

/* The AVX2 look-up of q in its leaf (NULL: outside the root). */
static IC_TARGET_AVX2 IC_ALWAYS_INLINE int query_leaf_avx2(const ic_cache *c, const ic_cache_lookup *q,
                                                           const ic_frozen_leaf *leaf, ic_cache_estimate *out)
{
    float s;
    uint32_t blocks, contributors = 0;
    int all_eligible;
    const ic_frozen_block *blk = leaf_begin(c, q, leaf, out, &blocks, &s, &all_eligible);
    if (!blk)
        return 0;
    __m256 acc[3] = {_mm256_setzero_ps(), _mm256_setzero_ps(), _mm256_setzero_ps()}, wsum = _mm256_setzero_ps();
    ic_vec3 p = q->position, n = q->normal;
    uint32_t bounce = q->bounce;
    /* Read once: the compiler cannot keep them across the stores to *out. */
    float neg_tolerance = -c->params.behind_tolerance;
    int ward = c->params.weight == IC_WEIGHT_WARD;
    /* Two copies of the loop: one reports contributors, the other (the final render's) does not. */
    if (q->contributions)
        for (uint32_t b = 0; b < blocks; ++b)
            contributors += (uint32_t)__builtin_popcount(
                block_avx2(&blk[b], p, n, s, bounce, neg_tolerance, ward, all_eligible, q, out, 1, acc, &wsum));
    else
        for (uint32_t b = 0; b < blocks; ++b)
            contributors += (uint32_t)__builtin_popcount(
                block_avx2(&blk[b], p, n, s, bounce, neg_tolerance, ward, all_eligible, q, out, 0, acc, &wsum));
    out->weight_sum = lane_total_avx2(wsum);
    out->contributor_count = contributors;
    float total[3] = {lane_total_avx2(acc[0]), lane_total_avx2(acc[1]), lane_total_avx2(acc[2])};
    return ic_estimate_finish(out, total);
}

static IC_TARGET_AVX2 int query_frozen_avx2(const ic_cache *c, const ic_cache_lookup *q, ic_cache_hint *hint,
                                            ic_cache_estimate *out)
{
    return query_leaf_avx2(c, q, frozen_leaf(&c->frozen, q->position, hint, 0), out);
}

/*
 * Batches look AHEAD points ahead: while look-up k runs, the leaf of point k + AHEAD is found and the
 * start of its list is prefetched, so a leaf that is not in the CPU's caches has arrived by the time
 * its look-up begins. Finding it must not wait for that leaf either: the hint test of the next point
 * needs the leaf's cell, which the descent computes (descend_sse2) instead of reading it from the
 * leaf's header. So the look-ahead reads only the node array. The cell is exact: a point inside it
 * descends to that leaf, so the answers are the single calls'. A ring of AHEAD leaves, 8 ahead and the
 * first block (1 KiB) prefetched: measured in BENCHMARKS.md ("Timing only the look-up calls").
 */
enum { AHEAD = 8, PREFETCH_BYTES = 1024 };

/* The batch's leaf finder: the leaf whose cell [*lo, *hi) holds p is `cur` (the previous point's);
 * else the descent finds p's leaf, sets *lo and *hi to its cell and prefetches the start of its list.
 * NULL (lo, hi unchanged) when p is outside the root, as frozen_leaf. */
static IC_TARGET_AVX2 IC_ALWAYS_INLINE const ic_frozen_leaf *batch_leaf(const ic_frozen *f, ic_vec3 p, __m128 *lo,
                                                                         __m128 *hi, const ic_frozen_leaf *cur)
{
    __m128 pv = _mm_setr_ps(p.x, p.y, p.z, 0.0f);
    if ((_mm_movemask_ps(_mm_and_ps(_mm_cmpge_ps(pv, *lo), _mm_cmplt_ps(pv, *hi))) & 7) == 7)
        return cur;
    const ic_frozen_leaf *leaf = descend_sse2(f, pv, lo, hi);
    if (leaf)
        for (unsigned o = 0; o < PREFETCH_BYTES; o += 64)
            _mm_prefetch((const char *)leaf + o, _MM_HINT_T0);
    return leaf;
}

/* ic_cache_query_batch on the AVX2 path: the look-up inlined (no call, no dispatch per look-up), leaves
 * found AHEAD points ahead into a ring. The hint is read once and written once; in between the current
 * leaf and its cell stay in registers. */
static IC_TARGET_AVX2 size_t query_batch_avx2(const ic_cache *c, const ic_cache_lookup *q, size_t count,
                                              ic_cache_hint *hint, ic_cache_estimate *out)
{
    const ic_frozen *f = &c->frozen;
    const ic_frozen_leaf *ring[AHEAD], *cur = hint_leaf(f, hint);
    __m128 lo = _mm_set1_ps(INFINITY), hi = _mm_set1_ps(-INFINITY); /* an empty cell: no point is inside */
    if (cur) {
        lo = _mm_loadu_ps(cur->lo);
        hi = _mm_loadu_ps(cur->hi);
    }
    for (size_t k = 0; k < AHEAD && k < count; ++k) {
        ring[k] = batch_leaf(f, q[k].position, &lo, &hi, cur);
        cur = ring[k] ? ring[k] : cur;
    }
    size_t found = 0;
    for (size_t k = 0; k < count; ++k) {
        const ic_frozen_leaf *leaf = ring[k % AHEAD];
        if (k + AHEAD < count) {
            ring[k % AHEAD] = batch_leaf(f, q[k + AHEAD].position, &lo, &hi, cur);
            cur = ring[k % AHEAD] ? ring[k % AHEAD] : cur;
        }
        if (query_leaf_avx2(c, &q[k], ic_lookup_is_finite(&q[k]) ? leaf : NULL, &out[k])) {
            ++found;
        } else if (q[k].fallback) { /* rare: the fallback level's look-up, as ic_cache_query_hinted makes it */
            ic_cache_lookup q2 = q[k];
            q2.bounce = q2.fallback - 1u;
            q2.fallback = 0;
            found += (size_t)ic_cache_query_hinted(c, &q2, NULL, &out[k]);
        }
    }
    if (hint && cur)
        hint->leaf = cur->id + 1u;
    return found;
}

/* 1 where the CPU runs AVX2. Asked at each cache creation: the answer is a read of what the runtime
 * found at start-up, so nothing is cached here and no thread writes shared state. */
static int cpu_has_avx2(void)
{
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") ? 1 : 0;
}
#endif

int ic_cache_set_lookup_path(ic_cache *c, ic_lookup_path path)
{
    int avx2 = 0, sse2 = 0;
#if defined(IC_HAVE_AVX2_PATH)
    avx2 = cpu_has_avx2();
#endif
#if defined(__SSE2__)
    sse2 = 1;
#endif
    if (path == IC_LOOKUP_BEST)
        path = avx2 ? IC_LOOKUP_AVX2 : sse2 ? IC_LOOKUP_SSE2 : IC_LOOKUP_PORTABLE;
    if ((path == IC_LOOKUP_AVX2 && !avx2) || (path == IC_LOOKUP_SSE2 && !sse2) || path < IC_LOOKUP_PORTABLE ||
        path > IC_LOOKUP_AVX2)
        return 0;
    c->lookup_path = path;
    ic_cache_select_frozen_query(c);
    return 1;
}

void ic_cache_select_frozen_query(ic_cache *c)
{
    /* The SIMD paths test round records with the Ward or T–L weight; anything else goes entry by entry. */
    if (ic_cache_needs_portable(c))
        c->query_frozen = query_frozen_portable;
#if defined(IC_HAVE_AVX2_PATH)
    else if (c->lookup_path == IC_LOOKUP_AVX2)
        c->query_frozen = query_frozen_avx2;
#endif
#if defined(__SSE2__)
    else if (c->lookup_path == IC_LOOKUP_SSE2)
        c->query_frozen = query_frozen_sse2;
#endif
    else
        c->query_frozen = query_frozen_portable;
}

size_t ic_cache_query_batch(const ic_cache *c, const ic_cache_lookup *q, size_t count, ic_cache_hint *hint,
                            ic_cache_estimate *out)
{
#if defined(IC_HAVE_AVX2_PATH)
    if (c->frozen.is_valid && c->query_frozen == query_frozen_avx2)
        return query_batch_avx2(c, q, count, hint, out);
#endif
    size_t found = 0;
    for (size_t k = 0; k < count; ++k)
        found += (size_t)ic_cache_query_hinted(c, &q[k], hint, &out[k]);
    return found;
}
