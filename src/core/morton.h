/*
 * morton.h — 3-D Morton (Z-order) codes: 10 bits per axis interleaved into 30 bits. Sorting points by
 * them keeps neighbours in space near each other in memory (octree builds, candidate clustering,
 * coherent query orders).
 */
#ifndef IC_CORE_MORTON_H
#define IC_CORE_MORTON_H

#include <stdint.h>

/* Spreads the low 10 bits of v so that two zero bits follow each one. */
static inline uint32_t ic_morton_spread10(uint32_t v)
{
    v &= 1023u;
    v = (v | (v << 16)) & 0x030000FFu;
    v = (v | (v << 8)) & 0x0300F00Fu;
    v = (v | (v << 4)) & 0x030C30C3u;
    v = (v | (v << 2)) & 0x09249249u;
    return v;
}

/* Morton code of integer cell coordinates in [0, 1023]. */
static inline uint32_t ic_morton3_cells(uint32_t x, uint32_t y, uint32_t z)
{
    return ic_morton_spread10(x) | (ic_morton_spread10(y) << 1) | (ic_morton_spread10(z) << 2);
}

#endif
