/* comm.c — timed collective operations over a caller's transport (comm.h). */
#include "core/comm.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void ic_comm_block(uint64_t count, int size, int r, uint64_t *first, uint64_t *n)
{
    uint64_t base = count / (uint64_t)size, extra = count % (uint64_t)size;
    uint64_t ur = (uint64_t)r;
    *first = ur * base + (ur < extra ? ur : extra);
    *n = base + (ur < extra ? 1 : 0);
}

static ic_result failed(ic_error *err, ic_result r, const char *what)
{
    return ic_error_set(err, r, "%s between the render's processes failed (%s); see the transport's own "
                        "message", what, ic_result_name(r));
}

ic_result ic_comm_allgather_blocks(ic_comm *comm, void *all, uint64_t count, size_t item_bytes, ic_error *err)
{
    if (!ic_comm_is_shared(comm))
        return IC_OK;
    uint64_t *counts = malloc(sizeof *counts * (size_t)comm->size);
    if (!counts)
        return ic_error_set(err, IC_ERR_OOM, "out of memory for %d ranks' counts", comm->size);
    uint64_t first, n, mine = 0;
    for (int r = 0; r < comm->size; ++r) {
        ic_comm_block(count, comm->size, r, &first, &n);
        counts[r] = n * item_bytes;
        if (r == comm->rank)
            mine = first * item_bytes;
    }
    double t0 = now();
    /* The transport reads this rank's block from its place in `all` (in-place all-gather). */
    ic_result r = comm->allgather(comm->user, (const char *)all + mine, all, counts);
    comm->seconds += now() - t0;
    comm->bytes += count * item_bytes - counts[comm->rank];
    free(counts);
    return r == IC_OK ? IC_OK : failed(err, r, "exchanging records");
}

ic_result ic_comm_allgather_counted(ic_comm *comm, void *items, uint64_t count, size_t item_bytes, uint64_t *total,
                                    ic_error *err)
{
    *total = count;
    if (!ic_comm_is_shared(comm))
        return IC_OK;
    size_t n = (size_t)comm->size;
    uint64_t *counts = malloc(sizeof *counts * n), *sizes = malloc(sizeof *sizes * n);
    if (!counts || !sizes) {
        free(counts);
        free(sizes);
        return ic_error_set(err, IC_ERR_OOM, "out of memory for %d ranks' counts", comm->size);
    }
    counts[comm->rank] = count;
    for (size_t r = 0; r < n; ++r)
        sizes[r] = sizeof *counts;
    double t0 = now();
    ic_result res = comm->allgather(comm->user, &counts[comm->rank], counts, sizes);
    uint64_t offset = 0, sum = 0;
    for (size_t r = 0; r < n; ++r) {
        if ((int)r < comm->rank)
            offset += counts[r];
        sum += counts[r];
        sizes[r] = counts[r] * item_bytes;
    }
    if (res == IC_OK) {
        char *base = items;
        memmove(base + offset * item_bytes, base, count * item_bytes);
        res = comm->allgather(comm->user, base + offset * item_bytes, base, sizes);
    }
    comm->seconds += now() - t0;
    comm->bytes += (sum - count) * item_bytes + (n - 1) * sizeof *counts;
    *total = sum;
    free(counts);
    free(sizes);
    return res == IC_OK ? IC_OK : failed(err, res, "exchanging candidates");
}

ic_result ic_comm_sum(ic_comm *comm, double *values, uint64_t count, ic_error *err)
{
    if (!ic_comm_is_shared(comm) || count == 0)
        return IC_OK;
    double t0 = now();
    ic_result r = comm->sum(comm->user, values, count);
    comm->seconds += now() - t0;
    comm->bytes += count * sizeof *values;
    return r == IC_OK ? IC_OK : failed(err, r, "summing the image");
}

ic_result ic_comm_broadcast(ic_comm *comm, void *buf, uint64_t bytes, int root, ic_error *err)
{
    if (!ic_comm_is_shared(comm) || bytes == 0)
        return IC_OK;
    double t0 = now();
    ic_result r = comm->broadcast(comm->user, buf, bytes, root);
    comm->seconds += now() - t0;
    if (comm->rank != root)
        comm->bytes += bytes;
    return r == IC_OK ? IC_OK : failed(err, r, "a broadcast");
}
