/*
 * bench_index.h — one line on the shape of a cache's look-up index (ic_cache_get_index_stats), shared
 * by the benchmarks that build caches.
 */
#ifndef IC_BENCH_INDEX_H
#define IC_BENCH_INDEX_H

#include "irrcache/cache.h"

#include <stdio.h>

static inline void print_index_stats(const char *prefix, const char *label, const ic_cache *cache)
{
    ic_cache_index_stats st;
    ic_cache_get_index_stats(cache, &st);
    printf("%s%s index: %u leaves (depth %u), %.2f references per record; records per leaf %.2f held, %.2f on "
           "the root-to-leaf path, %.2f in the frozen list (max %u)\n",
           prefix, label, st.leaves, st.depth, st.references_per_record, st.leaf_references, st.path_references,
           st.frozen_list_entries, st.max_frozen_list_entries);
}

#endif
