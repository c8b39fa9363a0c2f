/* threads.c — parallel-for with an atomic work counter (threads.h). */
#define _GNU_SOURCE
#include "threads.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <unistd.h>

int ic_hardware_threads(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? (int)n : 1;
}

int ic_resolve_threads(int requested) { return requested > 0 ? requested : ic_hardware_threads(); }

typedef struct job {
    ic_parallel_fn fn;
    void *ctx;
    int64_t count;
    atomic_llong next;
} job;

typedef struct worker_arg {
    job *job;
    int thread;
} worker_arg;

static void *worker(void *p)
{
    worker_arg *w = p;
    job *j = w->job;
    for (;;) {
        int64_t i = atomic_fetch_add_explicit(&j->next, 1, memory_order_relaxed);
        if (i >= j->count)
            break;
        j->fn(j->ctx, i, w->thread);
    }
    return NULL;
}

ic_result ic_parallel_for(int threads, int64_t count, ic_parallel_fn fn, void *ctx)
{
    if (count <= 0)
        return IC_OK;
    int n = ic_resolve_threads(threads);
    if ((int64_t)n > count)
        n = (int)count;
    job j;
    j.fn = fn;
    j.ctx = ctx;
    j.count = count;
    atomic_init(&j.next, 0);
    if (n == 1) {
        for (int64_t i = 0; i < count; ++i)
            fn(ctx, i, 0);
        return IC_OK;
    }
    pthread_t *tids = malloc(sizeof *tids * (size_t)n);
    worker_arg *args = malloc(sizeof *args * (size_t)n);
    if (!tids || !args) {
        free(tids);
        free(args);
        return IC_ERR_OOM;
    }
    int started = 0;
    for (int t = 1; t < n; ++t) {
        args[t].job = &j;
        args[t].thread = t;
        if (pthread_create(&tids[t], NULL, worker, &args[t]) != 0)
            break;
        ++started;
    }
    args[0].job = &j;
    args[0].thread = 0;
    worker(&args[0]); /* the calling thread works too; it finishes whatever others did not take */
    for (int t = 1; t <= started; ++t)
        pthread_join(tids[t], NULL);
    free(tids);
    free(args);
    return IC_OK;
}
