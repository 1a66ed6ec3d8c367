/*
 * srv_client.h - the part of a client that threads share: its requests
 * (subscription, camera; queries and replay cameras in its inbox) from the
 * service thread to the simulation thread, its outbox of messages back, and
 * the replies the daemon queues to it.
 *
 * Threads and locks:
 *   svc  the libwebsockets service thread: owns every connection (its
 *        per-connection state is srv_session.h), receives and decodes
 *        client messages, sends queued bytes.
 *   sim  the simulation thread: evaluates the ocean, builds frames; what it
 *        keeps per client is its own table (srv_client_sim.h).
 *   main the thread that started the daemon (signals, reload).
 * Every member is tagged [writer / guard].  The service thread writes a
 * client's requests under hub.lock; the simulation thread writes only the
 * count of queries it has taken.  The two hand-overs are objects of their
 * own, created with the client and never replaced: the inbox
 * (srv_inbox.h: the service thread pushes, the simulation thread takes,
 * under hub.lock) and the outbox (srv_outbox.h, its own lock: any thread
 * queues, the service thread takes).  Lock order: hub.lock before an
 * outbox's lock.
 *
 * Lifetime: a client is reference counted.  The hub list and the service
 * thread's session each hold one from LWS_CALLBACK_ESTABLISHED until
 * LWS_CALLBACK_CLOSED; the simulation thread's table holds one until it
 * sees the client closed, and a batch one while it builds a frame, so a
 * client that disconnects mid-frame is freed when the frame is done, never
 * under it.
 */
#ifndef SRV_CLIENT_H
#define SRV_CLIENT_H

#include <pthread.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

#include "proto.h"
#include "srv_convert.h"
#include "srv_hub.h"
#include "srv_inbox.h"
#include "srv_msg.h"
#include "srv_outbox.h"
#include "srv_stats.h"

typedef struct srv_client {
    atomic_int refs;
    uint32_t id;                          /* [const] */
    struct srv_hub *hub;                  /* [const] */
    int internal;                         /* [const] a service of the daemon (the CIGI
                                             service), no connection: not in n_clients */

    /* ---- requests: [svc writes / hub.lock] ---- */
    int subscribed;
    uint64_t sub_gen;                     /* bumps on every SUBSCRIBE */
    proto_subscribe sub;
    int has_camera;
    proto_camera cam;
    uint32_t cam_seq;
    int closed;                           /* connection gone; sim skips it */
    int hello_sent;                       /* HELLO queued: sea changes are announced to it */
    struct srv_client *next;              /* hub list */
    int n_queries_active;                 /* [sim writes / hub.lock] queries taken, unanswered */

    /* ---- the hand-overs, each with its own rules ---- */
    srv_inbox *in;                        /* [const] its queued QUERYs and replay cameras */
    srv_outbox *out;                      /* [const] its outgoing messages */

    /* ---- what the client costs, for /metrics [atomics: one writer, any reader] ---- */
    atomic_uint_fast64_t cpu_ns;          /* [sim] simulation-thread time spent on its requests */
    atomic_uint_fast64_t bytes_out;       /* [svc] bytes sent to it */
    atomic_uint_fast64_t link_bps;        /* [svc] the byte rate its link carries, for the
                                             planner (srv_link_bps); 0: the ceiling */
} srv_client;

/* A SUBSCRIBE that changes the subscription rebuilds the client's mesh and
 * topology and restarts its stream: at most SRV_SUBSCRIBE_PER_S a second
 * after a burst of SRV_SUBSCRIBE_BURST; one more is refused (ERATE) and the
 * subscription in force stays.  A SUBSCRIBE equal to the one in force
 * changes nothing and sends nothing. */
#define SRV_SUBSCRIBE_PER_S 2.0
#define SRV_SUBSCRIBE_BURST 4.0

/* SEA_STATE sets a connection may make: SRV_SEA_SET_PER_S a second after a
 * burst of SRV_SEA_SET_BURST (more than the 16 changes the server holds
 * pending, so one connection can reach that limit); one more is refused
 * ERATE, answered once a second. */
#define SRV_SEA_SET_PER_S 4.0
#define SRV_SEA_SET_BURST 20.0
/* ENTITY sets and removes a connection may make: a 60 Hz host moving two
 * entities, with room for a burst (each is announced to every client). */
#define SRV_ENTITY_SET_PER_S 120.0
#define SRV_ENTITY_SET_BURST 240.0
/* An ENTITY set's sample lies within this of the server's sim clock, s: a
 * track is where its entity is now, not a plan far ahead or behind. */
#define SRV_ENTITY_T_WINDOW 60.0

/* Creates a client (refs = 1, the list's), adds it to the hub. */
ocean_result srv_client_create(srv_hub *h, srv_client **out);
/* The same for a service of the daemon (internal): it asks what a client
 * asks, but holds no connection, so no slot of server.max_clients, and
 * /status and /metrics do not count it. */
ocean_result srv_client_create_internal(srv_hub *h, srv_client **out);
void srv_client_ref(srv_client *c);
/* Drops one reference; the last frees the client.  Accepts NULL. */
void srv_client_unref(srv_client *c);
/* Removes c from the hub list and drops the list's reference [svc]. */
void srv_client_remove(srv_client *c);

/* Queues a finished message (takes ownership of m) [any thread]; the first
 * message refused over server.output_hard wakes the service thread, which
 * cuts the client. */
void srv_client_queue(srv_client *c, srv_msg *m);
/* Hands a built frame (and the topology to send first, may be NULL) to its
 * client: queued in order for replay, into the latest-wins slot live.
 * frame NULL frees topo.  Takes ownership of both [sim side].  Returns 1
 * when the frame replaced an unsent live frame. */
int srv_client_hand_over(srv_client *c, srv_stats *st, srv_msg *topo, srv_msg *frame, int replay,
                          double tick_wall);
void srv_client_send_error(srv_client *c, const void *bad, size_t badlen, ocean_result code,
                           const char *why);
void srv_client_send_bye(srv_client *c, int reason, const char *why);
/* Queues HELLO and, right behind it, a SEA_STATE announce for every pending
 * change (one hold of hub.lock: no change can fall between them). */
void srv_client_send_hello(srv_client *c);
/* Answers SEA_STATE get: an announce of the current sea (effective_time: when
 * it took effect), then one per pending change, earliest first. */
void srv_client_send_sea_timeline(srv_client *c);
/* Queues to c an ENTITY announce of each live entity in the hub's table
 * (at most max), its newest sample stamped with the sim time that sample
 * takes effect: the list ENTITY get answers.  Takes only the table's lock
 * and sends no ERROR (callers may hold hub.lock).  OCEAN_ENOMEM: nothing
 * queued. */
ocean_result srv_client_queue_entities(srv_client *c, int max);
/* Queues to c every kept entry of the table's timeline, as the announces
 * and gones that entered them (srv_entities_each's order): what a client
 * joining needs to hold the same entries as one that watched them come,
 * so that every instant the server keeps reads the same for both.  Takes
 * only the table's lock (callers may hold hub.lock).  Returns the number of
 * entries; one that cannot be encoded for lack of memory is said on
 * stderr. */
int srv_client_queue_entity_entries(srv_client *c);


#endif
