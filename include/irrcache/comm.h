/*
 * irrcache/comm.h — the processes of one render: how a renderer running as several processes (MPI
 * ranks, one per node) exchanges data, without the library linking any message-passing library.
 *
 * The caller fills an ic_comm with its rank, the number of processes and three collective operations
 * (a fourth, all-to-all, is optional) over its own transport (the irrcache command does so over MPI), and passes it in
 * ic_render_options.comm. Every process then calls ic_render with the same scene and options: the
 * cache's construction gathers each pass's records on one share of the processes each and exchanges
 * them, so every process holds the same cache; the final render divides the image's tiles among them;
 * every process returns the same image, the same records and the same cache as a single process would
 * (same seed, same bits). A NULL comm, or size 1, is one process.
 *
 * The operations are collective: every rank calls each one, in the same order, with matching sizes.
 * They are called from the thread that called ic_render, never from the library's worker threads.
 * A non-IC_OK return ends the render with that result; a transport that cannot recover should end the
 * job itself (MPI_Abort), since the other ranks wait in the operation.
 */
#ifndef IRRCACHE_COMM_H
#define IRRCACHE_COMM_H

#include "irrcache/common.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct ic_comm {
    int rank;              /* this process, 0 … size − 1; rank 0 is the one that writes files */
    int size;              /* processes in the render */
    void *user;            /* handed to the operations */
    /* All-gather: rank r contributes counts[r] bytes from send; recv (room for the sum of counts) gets
     * every rank's block, in rank order. counts is the same array on every rank. send may be this
     * rank's own block inside recv (in place: MPI_IN_PLACE). */
    ic_result (*allgather)(void *user, const void *send, void *recv, const uint64_t *counts);
    /* Element-wise sum of count doubles over all ranks, in place, the same result on every rank. */
    ic_result (*sum)(void *user, double *values, uint64_t count);
    /* root's `bytes` bytes at buf copied into buf on every other rank. */
    ic_result (*broadcast)(void *user, void *buf, uint64_t bytes, int root);
    /* All-to-all (optional): this rank sends send_counts[q] bytes to rank q, the blocks lying in send in
     * rank order; recv (room for the sum of recv_counts) gets recv_counts[q] bytes from each rank q, in
     * rank order. recv_counts[q] on this rank equals send_counts[rank] on rank q. NULL: the library
     * emulates it with allgather, which moves every rank's whole send buffer to every rank (correct, but
     * without the saving in bytes that data meant for one rank allows). */
    ic_result (*alltoall)(void *user, const void *send, const uint64_t *send_counts, void *recv,
                          const uint64_t *recv_counts);
    /* Messages between two ranks (optional: the three together, or none), with which the final render sends
     * each finished tile while it renders the next instead of exchanging the whole image at its end; NULL:
     * the library exchanges it at the end with allgather. These are not collective: they are called from
     * the same thread as the others, whenever that thread is between two pieces of work. Messages from one
     * rank to another arrive in the order they were sent, and apart from the collectives' data.
     * post: starts sending `bytes` bytes at buf to rank `to` and returns at once; *request names the send,
     * whose buffer the library leaves untouched until sent says that it is done. */
    ic_result (*post)(void *user, int to, const void *buf, uint64_t bytes, void **request);
    /* sent: *done = 1 when the send `request` is done (the request is then released), 0 while it is not;
     * with wait non-zero, returns only once it is done. */
    ic_result (*sent)(void *user, void *request, int wait, int *done);
    /* take: a message that has arrived from any rank, into buf (room for `room` bytes): *bytes its length
     * and *from its sender, or *bytes = 0 when none has arrived; with wait non-zero, returns only once one
     * has. A message longer than room is an error. */
    ic_result (*take)(void *user, void *buf, uint64_t room, int wait, int *from, uint64_t *bytes);
    /* Kept by the library: seconds spent in the operations above and bytes they received, over the
     * comm's lifetime (zero them to start counting). */
    double seconds;
    uint64_t bytes;
} ic_comm;

#ifdef __cplusplus
}
#endif
#endif
