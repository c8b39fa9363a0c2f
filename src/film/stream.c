/* stream.c — finished pieces sent to every other rank while the work goes on (stream.h). */
#include "film/stream.h"

#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

struct ic_stream {
    ic_comm *comm;
    ic_stream_pack_fn pack;
    ic_stream_unpack_fn unpack;
    void *user;
    int64_t own, expected, pieces;
    size_t message_bytes;          /* a piece's name (8 bytes) and its bytes, at most */
    _Atomic int64_t *finished;     /* [own]: slot k + 1 of each finished slot, in the order finished (0: not yet) */
    atomic_llong finished_count;
    int64_t *piece_of;             /* [own]: each slot's piece */
    int64_t sent_upto;             /* finished slots whose sends were posted */
    unsigned char *outbox;         /* [own] messages, each kept until its sends are done */
    void **requests;               /* posted sends, in the order posted */
    int64_t posted, released;      /* requests[released … posted) are still in flight */
    unsigned char *inbox;          /* one received message */
    int64_t received;
    ic_result failure;
    ic_error error;
};

static void stream_free(ic_stream *s)
{
    if (!s)
        return;
    free(s->finished);
    free(s->piece_of);
    free(s->outbox);
    free(s->requests);
    free(s->inbox);
    free(s);
}

ic_result ic_stream_begin(ic_stream **out, ic_comm *comm, int64_t own, int64_t expected, int64_t pieces,
                          size_t max_piece_bytes, ic_stream_pack_fn pack, ic_stream_unpack_fn unpack, void *user,
                          ic_error *err)
{
    *out = NULL;
    ic_stream *s = calloc(1, sizeof *s);
    size_t slots = own > 0 ? (size_t)own : 1, others = (size_t)(comm->size - 1);
    if (s) {
        s->message_bytes = sizeof(int64_t) + max_piece_bytes;
        s->finished = calloc(slots, sizeof *s->finished);
        s->piece_of = calloc(slots, sizeof *s->piece_of);
        s->outbox = malloc(slots * s->message_bytes);
        s->requests = calloc(slots * others, sizeof *s->requests);
        s->inbox = malloc(s->message_bytes);
    }
    if (!s || !s->finished || !s->piece_of || !s->outbox || !s->requests || !s->inbox) {
        stream_free(s);
        return ic_error_set(err, IC_ERR_OOM, "out of memory for sending %lld finished tiles to %d ranks",
                            (long long)own, comm->size - 1);
    }
    s->comm = comm;
    s->pack = pack;
    s->unpack = unpack;
    s->user = user;
    s->own = own;
    s->expected = expected;
    s->pieces = pieces;
    atomic_init(&s->finished_count, 0);
    *out = s;
    return IC_OK;
}

void ic_stream_finished(ic_stream *s, int64_t slot, int64_t piece)
{
    s->piece_of[slot] = piece;
    int64_t k = atomic_fetch_add(&s->finished_count, 1);
    atomic_store_explicit(&s->finished[k], slot + 1, memory_order_release);
}

static void fail(ic_stream *s, ic_result r)
{
    if (s->failure == IC_OK)
        s->failure = r;
}

/* Posts the sends of every slot finished (and published) so far. */
static void send_finished(ic_stream *s)
{
    while (s->failure == IC_OK && s->sent_upto < s->own) {
        int64_t slot = atomic_load_explicit(&s->finished[s->sent_upto], memory_order_acquire) - 1;
        if (slot < 0)
            return; /* not finished yet, or its worker has not published it */
        unsigned char *msg = s->outbox + (size_t)slot * s->message_bytes;
        int64_t piece = s->piece_of[slot];
        memcpy(msg, &piece, sizeof piece);
        size_t bytes = sizeof piece + s->pack(s->user, piece, msg + sizeof piece);
        for (int q = 0; q < s->comm->size && s->failure == IC_OK; ++q)
            if (q != s->comm->rank)
                fail(s, ic_comm_post(s->comm, q, msg, bytes, &s->requests[s->posted++], &s->error));
        ++s->sent_upto;
    }
}

/* Unpacks the messages that have arrived (with wait: until every expected one has). */
static void take_arrived(ic_stream *s, int wait)
{
    while (s->failure == IC_OK && s->received < s->expected) {
        int from = -1;
        uint64_t bytes = 0;
        fail(s, ic_comm_take(s->comm, s->inbox, s->message_bytes, wait, &from, &bytes, &s->error));
        if (s->failure != IC_OK || bytes == 0)
            return;
        int64_t piece = -1;
        if (bytes >= sizeof piece)
            memcpy(&piece, s->inbox, sizeof piece);
        if (piece < 0 || piece >= s->pieces ||
            s->unpack(s->user, piece, s->inbox + sizeof piece) != bytes - sizeof piece) {
            fail(s, ic_error_set(&s->error, IC_ERR_IO, "rank %d sent a finished tile that does not fit this "
                                 "image (%llu bytes); every rank must render the same scene with the same options",
                                 from, (unsigned long long)bytes));
            return;
        }
        ++s->received;
    }
}

/* Releases the sends that are done, oldest first (with wait: all of them). Even after a failure: a send's
 * buffer must outlive it, and the ranks it goes to still take it (they wait for every piece posted). */
static void release_sent(ic_stream *s, int wait)
{
    while (s->released < s->posted) {
        int done = 0;
        ic_error later;
        ic_result r = ic_comm_sent(s->comm, s->requests[s->released], wait, &done,
                                   s->failure == IC_OK ? &s->error : &later);
        fail(s, r);
        if (r != IC_OK || !done)
            return;
        ++s->released;
    }
}

void ic_stream_service(ic_stream *s)
{
    send_finished(s);
    take_arrived(s, 0);
    release_sent(s, 0);
}

ic_result ic_stream_end(ic_stream *s, ic_error *err)
{
    send_finished(s);
    if (s->failure == IC_OK && s->sent_upto < s->own)
        fail(s, ic_error_set(&s->error, IC_ERR_INTERNAL, "%lld of this rank's %lld tiles were never finished",
                             (long long)(s->own - s->sent_upto), (long long)s->own));
    take_arrived(s, 1);
    release_sent(s, 1);
    /* No rank posts the next stream's pieces before every rank has taken this one's: messages keep their
     * order between two ranks, not across senders, so a rank still waiting for this stream's last piece
     * could take another rank's first piece of the next (an AOV's film follows the image's with no
     * collective between them). A rank that failed returns at once: the others may wait for its pieces,
     * and its caller ends the job, as after any failed collective. */
    if (s->failure == IC_OK) {
        double none = 0.0;
        fail(s, ic_comm_sum(s->comm, &none, 1, &s->error));
    }
    ic_result r = s->failure;
    if (r != IC_OK && err)
        *err = s->error;
    if (s->released < s->posted) { /* the transport failed with sends in flight: their buffers stay theirs */
        s->outbox = NULL;
        s->requests = NULL;
    }
    stream_free(s);
    return r;
}
