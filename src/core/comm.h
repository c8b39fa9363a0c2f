/*
 * comm.h — the library's side of irrcache/comm.h: the collective operations of a render's processes,
 * timed and counted into the comm, and a one-process no-op when the comm is NULL or has one rank. The
 * layers above call only these, so a single process never pays for the indirection.
 */
#ifndef IC_CORE_COMM_H
#define IC_CORE_COMM_H

#include "irrcache/comm.h"

/* 1 when comm joins more than one process. */
static inline int ic_comm_is_shared(const ic_comm *comm) { return comm && comm->size > 1; }
static inline int ic_comm_rank(const ic_comm *comm) { return ic_comm_is_shared(comm) ? comm->rank : 0; }
static inline int ic_comm_size(const ic_comm *comm) { return ic_comm_is_shared(comm) ? comm->size : 1; }

/* The share of `count` items that rank r takes under the fixed block rule (contiguous, in rank order,
 * sizes differing by at most one): items [*first, *first + *n). */
void ic_comm_block(uint64_t count, int size, int r, uint64_t *first, uint64_t *n);

/* Every rank's block of bytes[r] bytes (the same array on every rank), in rank order, gathered into all
 * on every rank; this rank's block is already in place at its offset (the sum of bytes[q], q < rank).
 * A no-op for one process; `what` names the data in messages. */
ic_result ic_comm_allgather_sized(ic_comm *comm, void *all, const uint64_t *bytes, const char *what, ic_error *err);
/* Every rank's block of `item_bytes`-byte items under ic_comm_block's rule for `count` items, gathered
 * into all (room for count items) on every rank; this rank's block is already in place at its offset.
 * A no-op for one process; `what` names the data in messages. */
ic_result ic_comm_allgather_blocks(ic_comm *comm, void *all, uint64_t count, size_t item_bytes, const char *what,
                                   ic_error *err);
/* This rank's `count` items of `item_bytes` bytes at the start of items (room for every rank's) become
 * every rank's items, in rank order, on every rank; *total gets their number. For one process *total =
 * count and nothing moves. */
ic_result ic_comm_allgather_counted(ic_comm *comm, void *items, uint64_t count, size_t item_bytes, uint64_t *total,
                                    ic_error *err);
/* Gathers results for `count` items (a gather: `arrays` output arrays, out_bytes[a] bytes an item) on a
 * share of the ranks each and leaves every item's results on every rank in out[a], in item order. Rank r
 * of N takes items r, r + N, r + 2N, … (interleaved: neighbouring items, which cost alike, spread over every
 * rank): their inputs (in: count items of in_bytes) are picked into a contiguous array, gather is called
 * once on them, writing to its block of rank-ordered buffers (ic_comm_block's sizes), and the blocks are
 * exchanged and put back in item order. sent_bytes (NULL: whole items) says how much of each item of
 * array a travels, its first sent_bytes[a] bytes: the gather must leave the rest of every item zero, and
 * the other ranks' items get zeros there. For one process (or no items) gather runs once on in and out
 * themselves. *own gets the number of items this rank gathered; `what` names the items in messages. */
#define IC_COMM_SHARE_MAX_ARRAYS 4
typedef ic_result (*ic_comm_gather_fn)(void *user, const void *in, uint64_t n, void *const *out, ic_error *err);
ic_result ic_comm_share_gather(ic_comm *comm, const void *in, size_t in_bytes, uint64_t count, int arrays,
                               void *const *out, const size_t *out_bytes, const size_t *sent_bytes,
                               ic_comm_gather_fn gather, void *user, const char *what, uint64_t *own, ic_error *err);
/* All-to-all: matrix[q * N + r] is the bytes rank q sends rank r (the same N × N matrix on every rank, so
 * each knows what it receives and where its blocks lie in the others' buffers). send holds this rank's
 * blocks in rank order; recv (room for the column's sum) gets the blocks sent to this rank, in rank order.
 * Through the comm's alltoall or, without one, an all-gather of every rank's whole send buffer from which
 * each keeps its own blocks. For one process the one block is copied. `what` names the data in messages. */
ic_result ic_comm_alltoall(ic_comm *comm, const void *send, const uint64_t *matrix, void *recv, const char *what,
                           ic_error *err);
/* 1 when the comm joins several processes and can send them messages (irrcache/comm.h's post, sent, take). */
static inline int ic_comm_has_messages(const ic_comm *comm)
{
    return ic_comm_is_shared(comm) && comm->post && comm->sent && comm->take;
}
/* The comm's post, sent and take, timed and counted (take's bytes), with an error message on failure;
 * only where ic_comm_has_messages. */
ic_result ic_comm_post(ic_comm *comm, int to, const void *buf, uint64_t bytes, void **request, ic_error *err);
ic_result ic_comm_sent(ic_comm *comm, void *request, int wait, int *done, ic_error *err);
ic_result ic_comm_take(ic_comm *comm, void *buf, uint64_t room, int wait, int *from, uint64_t *bytes, ic_error *err);
/* Sums count doubles over the ranks, in place (a no-op for one process). */
ic_result ic_comm_sum(ic_comm *comm, double *values, uint64_t count, ic_error *err);
/* Copies root's bytes to every rank (a no-op for one process). */
ic_result ic_comm_broadcast(ic_comm *comm, void *buf, uint64_t bytes, int root, ic_error *err);

#endif
