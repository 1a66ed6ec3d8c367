/*
 * srv_outbox.h - one client's outgoing messages on their way to the
 * service thread: a FIFO of control messages (HELLO, ERROR, results,
 * SEA_STATE announces, replay frames) and a latest-wins slot for the live
 * frame (and the MESH_TOPOLOGY to send before it), under a hard limit on
 * the bytes they hold.
 *
 * Threads: any thread queues (the service thread its replies, the
 * simulation thread frames and results, whoever enters a sea change its
 * announces); only the simulation thread publishes live frames; only the
 * service thread takes, sets the limit and clears the write request.  The
 * outbox's own lock guards its queue; nothing else is held while it is
 * taken except hub.lock (lock order: hub.lock, then the outbox).
 */
#ifndef SRV_OUTBOX_H
#define SRV_OUTBOX_H

#include <stdint.h>

#include "ocean_result.h"
#include "srv_msg.h"

typedef struct srv_outbox srv_outbox;

/* An empty outbox holding at most `hard` bytes (0: no limit). */
ocean_result srv_outbox_create(uint64_t hard, srv_outbox **out);
/* Frees whatever is still queued.  Accepts NULL. */
void srv_outbox_destroy(srv_outbox *o);

/* Calls fn(ctx) for each message queued in the FIFO, for a reader that is
 * not the service thread (the CIGI service's own client, srv_cigi.h); fn
 * runs under the outbox's lock, so it must be short and take no lock.
 * NULL stops the calls: once this returns, none is under way. */
void srv_outbox_set_notify(srv_outbox *o, void (*fn)(void *ctx), void *ctx);

/* Queues m at the end of the FIFO (takes ownership).  0: queued; else m
 * is freed because the queue would pass the hard limit (a BYE is always
 * queued): 2 the first such refusal (the caller wakes the service thread,
 * which cuts the client), 1 a later one. */
int srv_outbox_queue(srv_outbox *o, srv_msg *m);
/* Puts a live frame (and optionally a topology to send first) into the
 * latest-wins slot, freeing an unsent older frame; an unsent older
 * topology is kept when topo is NULL.  Takes ownership of both.  Returns 1
 * when an unsent frame was replaced (skipped) [sim]. */
int srv_outbox_publish(srv_outbox *o, srv_msg *topo, srv_msg *frame);
/* The next message to send (the FIFO first), or NULL [svc]. */
srv_msg *srv_outbox_take(srv_outbox *o);
/* Whether the next message to send is the live frame (or its topology). */
int srv_outbox_next_is_live(srv_outbox *o);
/* Whether a live frame waits unsent (the next one published replaces it). */
int srv_outbox_frame_waiting(srv_outbox *o);
/* Bytes queued, at allocated size (srv_msg_cost). */
uint64_t srv_outbox_queued(srv_outbox *o);

/* The hard limit (server.output_hard) as the service thread last saw it [svc]. */
void srv_outbox_set_hard(srv_outbox *o, uint64_t hard);
/* Whether a message was refused over the hard limit. */
int srv_outbox_over_hard(srv_outbox *o);
/* Asks the service thread to write (a message was queued, or a
 * confirmation may let a held frame go). */
void srv_outbox_want_write(srv_outbox *o);
/* Whether a write was asked since the last call, clearing it [svc]. */
int srv_outbox_take_want_write(srv_outbox *o);

#endif
