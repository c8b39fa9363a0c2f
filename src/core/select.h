/*
 * select.h — order statistics and sorting of keyed indices without a comparison callback: the k-th
 * smallest of an array (Hoare's selection) and a stable radix sort of (key, index) pairs.
 */
#ifndef IC_CORE_SELECT_H
#define IC_CORE_SELECT_H

#include <stddef.h>
#include <stdint.h>

/* The k-th smallest of v[0, n) (k < n), v reordered: the value a sort would put at k, whichever pivots are
 * taken (two zeros of either sign compare equal, so either may come back). Expected time linear in n, and
 * O(n log n) whatever the order (what is left is sorted once the partitions have read 8n values). */
float ic_kth_smallest(float *v, size_t n, size_t k);

/* A 32-bit key and the index it belongs to. */
typedef struct ic_key_index {
    uint32_t key, index;
} ic_key_index;

/* Sorts a[0, n) by key, stably (equal keys keep their order), using tmp (room for n) as scratch; returns
 * the sorted array, a or tmp. A least-significant-digit radix sort, a byte a pass, skipping the bytes that
 * every key shares. */
ic_key_index *ic_sort_key_index(ic_key_index *a, ic_key_index *tmp, size_t n);

#endif
