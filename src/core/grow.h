/*
 * grow.h — a growable array's reservation: doubling, so that appending n items costs O(n) copies.
 */
#ifndef IC_CORE_GROW_H
#define IC_CORE_GROW_H

#include "irrcache/common.h"

#include <stdlib.h>

/* Grows *array (elements of `size` bytes, *cap of them) to hold at least `need`, doubling from 64; on
 * failure *array and *cap stay as they were. */
static inline ic_result ic_grow(void **array, size_t *cap, size_t need, size_t size)
{
    if (need <= *cap)
        return IC_OK;
    size_t n = *cap ? *cap : 64;
    while (n < need)
        n *= 2;
    void *a = realloc(*array, n * size);
    if (!a)
        return IC_ERR_OOM;
    *array = a;
    *cap = n;
    return IC_OK;
}

#endif
