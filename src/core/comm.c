/* comm.c — timed collective operations over a caller's transport (comm.h). */
#include "core/comm.h"

#include <stdio.h>
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
    if (r == IC_ERR_UNSUPPORTED)
        return ic_error_set(err, r, "%s between the render's processes: too large for the transport (over 2 GiB "
                            "to or from one process); give a smaller image or fewer points", what);
    return ic_error_set(err, r, "%s between the render's processes failed (%s); see the transport's own "
                        "message", what, ic_result_name(r));
}

ic_result ic_comm_allgather_sized(ic_comm *comm, void *all, const uint64_t *bytes, const char *what, ic_error *err)
{
    if (!ic_comm_is_shared(comm))
        return IC_OK;
    uint64_t mine = 0, total = 0;
    for (int r = 0; r < comm->size; ++r) {
        if (r < comm->rank)
            mine += bytes[r];
        total += bytes[r];
    }
    double t0 = now();
    /* The transport reads this rank's block from its place in `all` (in-place all-gather). */
    ic_result r = comm->allgather(comm->user, (const char *)all + mine, all, bytes);
    comm->seconds += now() - t0;
    comm->bytes += total - bytes[comm->rank];
    return r == IC_OK ? IC_OK : failed(err, r, what);
}

ic_result ic_comm_allgather_blocks(ic_comm *comm, void *all, uint64_t count, size_t item_bytes, const char *what,
                                   ic_error *err)
{
    if (!ic_comm_is_shared(comm))
        return IC_OK;
    uint64_t *counts = malloc(sizeof *counts * (size_t)comm->size);
    if (!counts)
        return ic_error_set(err, IC_ERR_OOM, "out of memory for %d ranks' counts", comm->size);
    uint64_t first, n;
    for (int r = 0; r < comm->size; ++r) {
        ic_comm_block(count, comm->size, r, &first, &n);
        counts[r] = n * item_bytes;
    }
    ic_result r = ic_comm_allgather_sized(comm, all, counts, what, err);
    free(counts);
    return r;
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
    if (res != IC_OK) { /* the other ranks' counts never came: nothing to add up */
        comm->seconds += now() - t0;
        free(counts);
        free(sizes);
        return failed(err, res, "exchanging counts");
    }
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

ic_result ic_comm_share_gather(ic_comm *comm, const void *in, size_t in_bytes, uint64_t count, int arrays,
                               void *const *out, const size_t *out_bytes, const size_t *sent_bytes,
                               ic_comm_gather_fn gather, void *user, const char *what, uint64_t *own, ic_error *err)
{
    int ranks = ic_comm_size(comm), rank = ic_comm_rank(comm);
    *own = count;
    if (arrays > IC_COMM_SHARE_MAX_ARRAYS)
        return ic_error_set(err, IC_ERR_INTERNAL, "%d output arrays to share; at most %d", arrays,
                            IC_COMM_SHARE_MAX_ARRAYS);
    if (ranks == 1 || count == 0)
        return gather(user, in, count, out, err);
    uint64_t first;
    ic_comm_block(count, ranks, rank, &first, own);
    char *mine = malloc(in_bytes * (*own ? *own : 1));
    /* Each rank's results travel in one all-gather: its block holds, array after array, its items' first
     * sent[a] bytes (one exchange, so one latency, however many arrays). */
    size_t sent[IC_COMM_SHARE_MAX_ARRAYS], stride = 0;
    for (int a = 0; a < arrays; ++a) {
        sent[a] = sent_bytes && sent_bytes[a] < out_bytes[a] ? sent_bytes[a] : out_bytes[a];
        stride += sent[a];
    }
    char *all[IC_COMM_SHARE_MAX_ARRAYS] = {0};
    void *block[IC_COMM_SHARE_MAX_ARRAYS] = {0};
    char *packed = malloc(count * stride > 0 ? count * stride : 1);
    ic_result r = mine && packed ? IC_OK : IC_ERR_OOM;
    for (int a = 0; a < arrays && r == IC_OK; ++a) {
        all[a] = calloc(*own ? *own : 1, out_bytes[a]);
        block[a] = all[a];
        r = all[a] ? IC_OK : IC_ERR_OOM;
    }
    if (r != IC_OK)
        r = ic_error_set(err, IC_ERR_OOM, "out of memory for %llu %s", (unsigned long long)count, what);
    for (uint64_t k = 0; r == IC_OK && k < *own; ++k)
        memcpy(mine + k * in_bytes, (const char *)in + ((uint64_t)rank + k * (uint64_t)ranks) * in_bytes, in_bytes);
    if (r == IC_OK)
        r = gather(user, mine, *own, block, err);
    char *at = packed + first * stride;
    for (int a = 0; a < arrays && r == IC_OK; ++a)
        for (uint64_t k = 0; k < *own; ++k, at += sent[a])
            memcpy(at, all[a] + k * out_bytes[a], sent[a]);
    char exchanging[96];
    snprintf(exchanging, sizeof exchanging, "exchanging %s", what);
    if (r == IC_OK)
        r = ic_comm_allgather_blocks(comm, packed, count, stride, exchanging, err);
    for (int q = 0; r == IC_OK && q < ranks; ++q) {
        uint64_t q_first, q_own;
        ic_comm_block(count, ranks, q, &q_first, &q_own);
        const char *from = packed + q_first * stride;
        for (int a = 0; a < arrays; ++a)
            for (uint64_t k = 0; k < q_own; ++k, from += sent[a]) {
                char *to = (char *)out[a] + ((uint64_t)q + k * (uint64_t)ranks) * out_bytes[a];
                memcpy(to, from, sent[a]);
                memset(to + sent[a], 0, out_bytes[a] - sent[a]);
            }
    }
    free(mine);
    free(packed);
    for (int a = 0; a < arrays; ++a)
        free(all[a]);
    return r;
}

ic_result ic_comm_alltoall(ic_comm *comm, const void *send, const uint64_t *matrix, void *recv, const char *what,
                           ic_error *err)
{
    if (!ic_comm_is_shared(comm)) {
        memcpy(recv, send, matrix[0]);
        return IC_OK;
    }
    const size_t n = (size_t)comm->size, me = (size_t)comm->rank;
    uint64_t *out = malloc(sizeof *out * n), *in = malloc(sizeof *in * n);
    if (!out || !in) {
        free(out);
        free(in);
        return ic_error_set(err, IC_ERR_OOM, "out of memory for %d ranks' counts", comm->size);
    }
    uint64_t received = 0, all_bytes = 0, mine_at = 0;
    for (size_t q = 0; q < n; ++q) {
        out[q] = matrix[me * n + q];
        in[q] = matrix[q * n + me];
        received += q == me ? 0 : in[q];
    }
    double t0 = now();
    ic_result r = IC_OK;
    if (comm->alltoall) {
        r = comm->alltoall(comm->user, send, out, recv, in);
        comm->bytes += received;
    } else {
        /* Every rank's whole buffer to every rank (out[] reused as the buffers' sizes). */
        for (size_t q = 0; q < n; ++q) {
            uint64_t sz = 0;
            for (size_t k = 0; k < n; ++k)
                sz += matrix[q * n + k];
            if (q < me)
                mine_at += sz;
            all_bytes += sz;
            out[q] = sz;
        }
        char *all = malloc(all_bytes ? all_bytes : 1);
        if (!all) {
            r = IC_ERR_OOM;
        } else {
            memcpy(all + mine_at, send, out[me]);
            r = comm->allgather(comm->user, all + mine_at, all, out);
            uint64_t at = 0, put = 0;
            for (size_t q = 0; r == IC_OK && q < n; ++q) {
                uint64_t skip = 0;
                for (size_t k = 0; k < me; ++k)
                    skip += matrix[q * n + k];
                memcpy((char *)recv + put, all + at + skip, in[q]);
                put += in[q];
                at += out[q];
            }
            free(all);
        }
        comm->bytes += all_bytes - out[me];
    }
    comm->seconds += now() - t0;
    free(out);
    free(in);
    if (r == IC_ERR_OOM)
        return ic_error_set(err, r, "out of memory for %s (%d ranks)", what, comm->size);
    return r == IC_OK ? IC_OK : failed(err, r, what);
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

ic_result ic_comm_post(ic_comm *comm, int to, const void *buf, uint64_t bytes, void **request, ic_error *err)
{
    double t0 = now();
    ic_result r = comm->post(comm->user, to, buf, bytes, request);
    comm->seconds += now() - t0;
    return r == IC_OK ? IC_OK : failed(err, r, "sending a finished tile");
}

ic_result ic_comm_sent(ic_comm *comm, void *request, int wait, int *done, ic_error *err)
{
    double t0 = now();
    ic_result r = comm->sent(comm->user, request, wait, done);
    comm->seconds += now() - t0;
    return r == IC_OK ? IC_OK : failed(err, r, "sending a finished tile");
}

ic_result ic_comm_take(ic_comm *comm, void *buf, uint64_t room, int wait, int *from, uint64_t *bytes, ic_error *err)
{
    double t0 = now();
    *bytes = 0;
    ic_result r = comm->take(comm->user, buf, room, wait, from, bytes);
    comm->seconds += now() - t0;
    comm->bytes += *bytes;
    return r == IC_OK ? IC_OK : failed(err, r, "receiving a finished tile");
}
