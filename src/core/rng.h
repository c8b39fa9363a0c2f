/*
 * rng.h — counter-based random numbers.
 *
 * Every random number is a pure function of (seed, stream key, sample, dimension), so an image or a
 * cache never depends on the thread count or on scheduling.
 * The mixer is a 64-bit finaliser in the style of SplitMix64 / Murmur3's fmix64; the stream key is
 * built by hashing its parts together, and each draw hashes (key, counter).
 */
#ifndef IC_CORE_RNG_H
#define IC_CORE_RNG_H

#include <stdint.h>

static inline uint64_t ic_mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/* Hash of four 64-bit words, order-sensitive. */
static inline uint64_t ic_hash4(uint64_t a, uint64_t b, uint64_t c, uint64_t d)
{
    uint64_t h = ic_mix64(a + 0x9e3779b97f4a7c15ULL);
    h = ic_mix64(h ^ (b + 0x632be59bd9b4e019ULL));
    h = ic_mix64(h ^ (c + 0x85157af5d1b2d5ffULL));
    return ic_mix64(h ^ (d + 0xa0761d6478bd642fULL));
}

/* A stream: fixed key, running counter, and optionally a low-discrepancy sequence for its 2-D draws
 * (ic_rng_2d). Copyable, 32 bytes, no allocation. */
typedef struct ic_rng {
    uint64_t key;
    uint64_t counter;
    uint64_t lds_key;          /* 0: ic_rng_2d draws plain random pairs */
    uint32_t lds_index;        /* this stream's point in the sequence (the pixel's sample number) */
    uint32_t lds_dim;          /* 2-D dimensions drawn so far */
} ic_rng;

/* Stream for (seed, a, b, c), e.g. (seed, pixel, sample, purpose). */
static inline ic_rng ic_rng_make(uint64_t seed, uint64_t a, uint64_t b, uint64_t c)
{
    ic_rng r;
    r.key = ic_hash4(seed, a, b, c);
    r.counter = 0;
    r.lds_key = 0;
    r.lds_index = 0;
    r.lds_dim = 0;
    return r;
}

static inline uint64_t ic_rng_u64(ic_rng *r) { return ic_mix64(r->key ^ ic_mix64(r->counter++ + 0x9e3779b97f4a7c15ULL)); }

/* Uniform float in [0, 1): 24 random mantissa bits, never 1.0. */
static inline float ic_rng_float(ic_rng *r) { return (float)(ic_rng_u64(r) >> 40) * (1.0f / 16777216.0f); }

/* Uniform double in [0, 1). */
static inline double ic_rng_double(ic_rng *r) { return (double)(ic_rng_u64(r) >> 11) * (1.0 / 9007199254740992.0); }

/* Uniform integer in [0, n), n > 0 (Lemire's multiply-shift; bias below 2^-32 for n < 2^32). */
static inline uint32_t ic_rng_below(ic_rng *r, uint32_t n) { return (uint32_t)(((ic_rng_u64(r) >> 32) * (uint64_t)n) >> 32); }

/* ---------------------------------------------------------------- low-discrepancy pairs
 *
 * Scrambled, shuffled Sobol' points in 2-D (Burley 2020, "Practical Hash-based Owen Scrambling",
 * JCGT 9(4)): the first two Sobol' dimensions form a (0,2)-sequence, so every aligned block of 2^k
 * consecutive indices is a (0,k,2)-net — each of the 2^k elementary intervals of any shape holds
 * one point. Nested uniform (Owen) scrambling by the Laine–Karras hash makes every point uniformly
 * distributed (estimates stay unbiased) while keeping the net; scrambling the index with another
 * key decorrelates the pairs of one sample from each other ("padding"). A pixel's samples
 * 0…spp−1 then cover its pixel area, its light-sample square and its BSDF square evenly, which
 * lowers the variance of low-dimensional integrands (pixel filter, direct light) far below that of
 * independent draws, at the same cost. */

static inline uint32_t ic_reverse_bits32(uint32_t i)
{
#if defined(__GNUC__) || defined(__clang__)
    i = __builtin_bswap32(i); /* the byte order, in one instruction */
#else
    i = (i << 16) | (i >> 16);
    i = ((i & 0x00ff00ffu) << 8) | ((i & 0xff00ff00u) >> 8);
#endif
    i = ((i & 0x0f0f0f0fu) << 4) | ((i & 0xf0f0f0f0u) >> 4);
    i = ((i & 0x33333333u) << 2) | ((i & 0xccccccccu) >> 2);
    return ((i & 0x55555555u) << 1) | ((i & 0xaaaaaaaau) >> 1);
}

/* The Laine–Karras permutation (constants from Burley 2020): each bit of the result depends only on
 * the bits below it. */
static inline uint32_t ic_laine_karras(uint32_t x, uint32_t seed)
{
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

/* Owen scrambling of a 32-bit binary fraction: bit b flips by a hash of the bits above it. The
 * Laine–Karras permutation applied to the reversed value acts on the digits below each digit, as
 * Owen's tree does. */
static inline uint32_t ic_owen_scramble(uint32_t x, uint32_t seed)
{
    return ic_reverse_bits32(ic_laine_karras(ic_reverse_bits32(x), seed));
}

/* Second Sobol' dimension (primitive polynomial x + 1: v_k = v_{k-1} xor v_{k-1} >> 1), as a 32-bit
 * fraction: the XOR of v_k over the set bits k of i. Bit 31 − j of v_k is C(k, j) mod 2, which by
 * Lucas' theorem is 1 exactly when j's bits are a subset of k's; so bit 31 − j of the result is the
 * XOR of i's bits at the supersets of j — a superset-sum transform over the five bits of a bit
 * position, five shift-mask-XOR steps (bit-identical to the 32-step loop; test_sampling checks). */
static inline uint32_t ic_superset_xor(uint32_t i)
{
    i ^= (i >> 1) & 0x55555555u;
    i ^= (i >> 2) & 0x33333333u;
    i ^= (i >> 4) & 0x0f0f0f0fu;
    i ^= (i >> 8) & 0x00ff00ffu;
    i ^= (i >> 16) & 0x0000ffffu;
    return i;
}
static inline uint32_t ic_sobol_dim1(uint32_t i) { return ic_reverse_bits32(ic_superset_xor(i)); }

/* Point `index` of the Sobol' pair scrambled by `key`, in [0,1)^2 (24-bit floats, never 1.0):
 * i = owen(index), x = owen(reverse(i)), y = owen(dim1(i)), with the reversals that cancel left out
 * (owen(z) = reverse(LK(reverse(z))), reverse(dim1(i)) = superset_xor(i)). */
static inline void ic_sobol2d(uint32_t index, uint64_t key, float *u, float *v)
{
    uint64_t h = ic_mix64(key);
    uint32_t i = ic_owen_scramble(index, (uint32_t)h);
    uint32_t x = ic_reverse_bits32(ic_laine_karras(i, (uint32_t)(h >> 32)));
    uint32_t y = ic_reverse_bits32(
        ic_laine_karras(ic_superset_xor(i), (uint32_t)ic_mix64(h ^ 0x5851f42d4c957f2dULL)));
    *u = (float)(x >> 8) * (1.0f / 16777216.0f);
    *v = (float)(y >> 8) * (1.0f / 16777216.0f);
}

/* Dimensions per sample taken from the sequence (each ic_rng_2d pair and each ic_rng_1d draw uses
 * one); later ones (deep path vertices) are plain random. */
#define IC_RNG_LDS_PAIRS 32

/* Makes the stream's 2-D draws points of per-`key` scrambled sequences, this stream being point
 * `index` (e.g. key = hash of the pixel, index = sample number). */
static inline void ic_rng_enable_lds(ic_rng *r, uint64_t key, uint32_t index)
{
    r->lds_key = key | 1u;
    r->lds_index = index;
    r->lds_dim = 0;
}

/* A uniform pair in [0,1)^2: the next low-discrepancy dimension when enabled, else two draws. */
static inline void ic_rng_2d(ic_rng *r, float *u, float *v)
{
    if (r->lds_key && r->lds_dim < IC_RNG_LDS_PAIRS) {
        ic_sobol2d(r->lds_index, r->lds_key + 0x9e3779b97f4a7c15ULL * ++r->lds_dim, u, v);
        return;
    }
    *u = ic_rng_float(r);
    *v = ic_rng_float(r);
}

/* A uniform number in [0,1) for a discrete choice (a BSDF lobe, reflection or refraction at glass, a
 * kind of light): one coordinate of the next low-discrepancy dimension when enabled (it uses up one
 * of the IC_RNG_LDS_PAIRS dimensions), else one draw. Over an aligned power-of-two block of a pixel's
 * samples that all reach this dimension, each branch is then taken in proportion to its probability,
 * give or take one sample, instead of binomially; other counts (adaptive sampling, paths of different
 * lengths) keep most of that evenness. */
static inline float ic_rng_1d(ic_rng *r)
{
    if (r->lds_key && r->lds_dim < IC_RNG_LDS_PAIRS) {
        float u, v;
        ic_sobol2d(r->lds_index, r->lds_key + 0x9e3779b97f4a7c15ULL * ++r->lds_dim, &u, &v);
        return u;
    }
    return ic_rng_float(r);
}

#endif
