/*
 * threads.h — a minimal parallel-for over pthreads.
 *
 * Work items are handed out by an atomic counter (dynamic scheduling); results must be written to
 * per-item slots so that the outcome never depends on which thread ran an item.
 */
#ifndef IC_CORE_THREADS_H
#define IC_CORE_THREADS_H

#include "irrcache/common.h"

/* Body of a parallel loop: item index in [0, count), thread index in [0, threads). */
typedef void (*ic_parallel_fn)(void *ctx, int64_t item, int thread);

/* Number of hardware threads (at least 1). */
int ic_hardware_threads(void);

/* Resolves a requested thread count (0 = all hardware threads) to a positive number. */
int ic_resolve_threads(int requested);

/* Runs fn(ctx, i, t) for every i in [0, count) on `threads` threads (0 = all cores).
 * Returns IC_ERR_OOM or IC_ERR_INTERNAL if threads could not be started (then nothing ran). */
ic_result ic_parallel_for(int threads, int64_t count, ic_parallel_fn fn, void *ctx);

#endif
