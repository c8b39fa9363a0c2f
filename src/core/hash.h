/* hash.h — FNV-1a, 64 bits: the cache file's checksum, scene hashes, temporaries' names. The cache module
 * exports it to users as irrcache/cache.h's ic_fnv1a64; it lives here so that core may use it too. */
#ifndef IC_CORE_HASH_H
#define IC_CORE_HASH_H

#include <stddef.h>
#include <stdint.h>

/* FNV-1a 64-bit hash of size bytes, continuing from h (start with IC_FNV64_OFFSET). */
uint64_t ic_fnv1a64(uint64_t h, const void *data, size_t size);
#ifndef IC_FNV64_OFFSET
#define IC_FNV64_OFFSET 0xcbf29ce484222325ULL
#endif

#endif
