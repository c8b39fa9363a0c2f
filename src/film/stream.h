/*
 * stream.h — pieces of a plane (an image's tiles) sent to every other rank as they are finished, while the
 * next ones render, instead of all at once when the work is over: each rank's sends and receipts then
 * overlap its own rendering, and only the last pieces are left to wait for. Over the comm's messages
 * (irrcache/comm.h: post, sent, take); used only where ic_comm_has_messages.
 *
 * Threads: ic_stream_finished may be called from any thread; everything else only from the thread that
 * calls the comm (the film's thread 0, which is the caller of ic_render). A piece's bytes are made by
 * `pack` on that thread, after its worker said it was finished, so a piece's values are read only once
 * they are final. Every rank must know how many pieces it will receive (`expected`).
 */
#ifndef IC_FILM_STREAM_H
#define IC_FILM_STREAM_H

#include "core/comm.h"

/* Writes piece's bytes to `to` (room for max_piece_bytes) and returns their number; it may also put the
 * piece's values in the receiving rank's own plane (the same values a receiver unpacks). */
typedef size_t (*ic_stream_pack_fn)(void *user, int64_t piece, unsigned char *to);
/* Puts a received piece's bytes in place; returns the number it read (which must be the message's). */
typedef size_t (*ic_stream_unpack_fn)(void *user, int64_t piece, const unsigned char *from);

typedef struct ic_stream ic_stream;

/* A stream of `own` pieces from this rank (slots 0 … own − 1) to every other rank, and of `expected`
 * pieces from the others, of at most max_piece_bytes each. `pieces` bounds the pieces' names (0 …
 * pieces − 1), against which received ones are checked. */
ic_result ic_stream_begin(ic_stream **out, ic_comm *comm, int64_t own, int64_t expected, int64_t pieces,
                          size_t max_piece_bytes, ic_stream_pack_fn pack, ic_stream_unpack_fn unpack, void *user,
                          ic_error *err);
/* Any thread: this rank's slot `slot` holds finished piece `piece` (each slot once). */
void ic_stream_finished(ic_stream *s, int64_t slot, int64_t piece);
/* The comm's thread, between two pieces of work: sends what is finished, unpacks what has arrived, and
 * releases the sends that are done; never waits. A failure is kept for ic_stream_end. */
void ic_stream_service(ic_stream *s);
/* The comm's thread, after the work: sends what is left, waits for the pieces still to come and for
 * every send, then for every rank to be as far (a sum: the next stream's messages cannot be taken for this
 * one's), and frees the stream. Collective. Returns the first failure, if any (with its message in err). */
ic_result ic_stream_end(ic_stream *s, ic_error *err);

#endif
