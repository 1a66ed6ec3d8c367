/*
 * srv_session.h - one WebSocket connection as the service thread sees it:
 * the message being reassembled, the read and message-rate budgets, the
 * link's pacing, the admin guard's backoff, the output limits' clocks, the
 * close in progress and the recording.
 *
 * Threads: the libwebsockets service thread only, as libwebsockets' minimal
 * examples keep their per-session data.  A session holds one reference to
 * its client (srv_client.h), the part other threads share: the simulation
 * thread and the query workers never see a session, and the service thread
 * hands them copies through the client's requests (hub.lock) and takes
 * their messages from its outgoing queue (out_lock).
 */
#ifndef SRV_SESSION_H
#define SRV_SESSION_H

#include <stddef.h>
#include <stdint.h>

#include "srv_admin.h"
#include "srv_bucket.h"
#include "srv_client.h"
#include "srv_link.h"

struct lws;
struct srv_record;

typedef struct srv_session {
    srv_client *c;                  /* the shared half: one reference */
    struct lws *wsi;
    struct srv_session *next;       /* srv_net's list of sessions */

    /* reading */
    uint8_t *rx;                    /* message being reassembled */
    size_t rx_len, rx_cap;
    int rx_discard;                 /* dropping an oversized message */
    size_t rx_discarded;
    size_t rx_held;                 /* rx_cap counted in the hub's partial total */
    double rx_started;              /* monotonic time the unfinished message began */
    double last_rx;                 /* monotonic time of the connection or of its last
                                       message's first bytes (server.idle_seconds) */
    srv_bucket read;                /* bytes (server.read_rate) */
    int rx_paused;                  /* reading paused until the budget refills */

    /* admission of messages */
    srv_bucket messages;            /* messages (server.msg_rate, server.msg_burst) */
    double rate_err_t;              /* last ERATE ERROR sent; one per second */
    double text_err_t;              /* last text-frame ERROR sent; one per second */
    uint64_t rate_refused;          /* messages refused since that ERROR */
    srv_bucket sub_changes;         /* changed SUBSCRIBEs (SRV_SUBSCRIBE_*) */
    srv_bucket sea_sets;            /* SEA_STATE sets (SRV_SEA_SET_*) */
    double sea_err_t;               /* last ERATE ERROR for a set over that rate */
    srv_bucket entity_sets;         /* ENTITY sets and removes (SRV_ENTITY_SET_*) */
    double entity_err_t;            /* last ERATE ERROR for one over that rate */
    double price;                   /* the subscription's price held in admission (srv_admit.h) */
    int admin_misses;               /* wrong admin tokens in a row */
    double admin_until;             /* SEA_STATE set refused until then (monotonic) */
    char peer[SRV_ADMIN_ADDR_MAX];  /* the client's address (srv_admin's key) */

    /* sending */
    srv_link link;                  /* live frames in flight and what the link carries */
    uint32_t tx_seq;                /* header seq of the next message */
    uint64_t inflight;              /* bytes lws still holds of the last write */
    double over_soft_since;         /* monotonic; 0: under the soft limit */
    double last_progress;           /* monotonic time of the last completed send */
    double pending_since;           /* monotonic time output began waiting; 0: none */
    int closing;                    /* 1 BYE queued; 2 client said BYE; 3 cut by a limit
                                       (kill_code, kill_why); 4 BYE sent */
    uint16_t kill_code;             /* closing 3: the close frame's code */
    char kill_why[124];             /* and its reason (a close payload <= 125) */

    struct srv_record *rec;         /* this connection's recording, or NULL */
} srv_session;

/* A new session for connection wsi with a new client in hub h (the client
 * list's reference and the session's).  OCEAN_ENOMEM. */
ocean_result srv_session_create(srv_hub *h, struct lws *wsi, srv_session **out);
/* Ends the session: its unfinished message leaves the hub's partial total,
 * its recording is closed (saying what was lost), its client leaves the hub
 * and both references are dropped.  Accepts NULL. */
void srv_session_destroy(srv_session *s);
/* Frees the message being reassembled and takes it out of the hub's
 * partial total. */
void srv_session_rx_release(srv_session *s);

#endif
