/*
 * rng.h — counter-based random numbers.
 *
 * Every random number is a pure function of (seed, stream key, sample, dimension), so an image or a
 * cache never depends on the thread count or on scheduling (STYLE.md, "Threads and determinism").
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

/* A stream: fixed key, running counter. Copyable, 16 bytes, no allocation. */
typedef struct ic_rng {
    uint64_t key;
    uint64_t counter;
} ic_rng;

/* Stream for (seed, a, b, c), e.g. (seed, pixel, sample, purpose). */
static inline ic_rng ic_rng_make(uint64_t seed, uint64_t a, uint64_t b, uint64_t c)
{
    ic_rng r;
    r.key = ic_hash4(seed, a, b, c);
    r.counter = 0;
    return r;
}

static inline uint64_t ic_rng_u64(ic_rng *r) { return ic_mix64(r->key ^ ic_mix64(r->counter++ + 0x9e3779b97f4a7c15ULL)); }

/* Uniform float in [0, 1): 24 random mantissa bits, never 1.0. */
static inline float ic_rng_float(ic_rng *r) { return (float)(ic_rng_u64(r) >> 40) * (1.0f / 16777216.0f); }

/* Uniform double in [0, 1). */
static inline double ic_rng_double(ic_rng *r) { return (double)(ic_rng_u64(r) >> 11) * (1.0 / 9007199254740992.0); }

/* Uniform integer in [0, n), n > 0 (Lemire's multiply-shift; bias below 2^-32 for n < 2^32). */
static inline uint32_t ic_rng_below(ic_rng *r, uint32_t n) { return (uint32_t)(((ic_rng_u64(r) >> 32) * (uint64_t)n) >> 32); }

#endif
