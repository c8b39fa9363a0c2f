/* hash.c — FNV-1a, 64 bits (hash.h). */
#include "core/hash.h"

uint64_t ic_fnv1a64(uint64_t h, const void *data, size_t size)
{
    const unsigned char *p = data;
    for (size_t k = 0; k < size; ++k) {
        h ^= p[k];
        h *= 0x100000001b3ULL;
    }
    return h;
}
