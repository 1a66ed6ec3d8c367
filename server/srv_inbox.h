/*
 * srv_inbox.h - one client's requests on their way from the service thread
 * to the simulation thread: the QUERYs waiting for their answers and the
 * replay-mode CAMERAs waiting for their frames, each a FIFO.
 *
 * Threads: the service thread pushes, drops the replay cameras when the
 * client subscribes live and everything when it leaves; the simulation
 * thread takes.  The
 * caller holds hub.lock for every call (the simulation thread takes a tick's
 * requests of every client in one hold of it).
 */
#ifndef SRV_INBOX_H
#define SRV_INBOX_H

#include <stdint.h>

#include "ocean_result.h"
#include "proto.h"

/* A pending QUERY, decoded. */
typedef struct srv_query {
    struct srv_query *next;
    uint32_t query_id, seq;
    int at_time;
    double t;
    uint32_t count;
    double *points;     /* 2 * count */
} srv_query;

/* A replay-mode CAMERA waiting for its frame. */
typedef struct srv_replay_cam {
    struct srv_replay_cam *next;
    proto_camera cam;
    uint32_t seq;
} srv_replay_cam;

typedef struct srv_inbox srv_inbox;

ocean_result srv_inbox_create(srv_inbox **out);
/* Frees every request still waiting.  Accepts NULL. */
void srv_inbox_destroy(srv_inbox *in);

/* Appends q (takes ownership). */
void srv_inbox_push_query(srv_inbox *in, srv_query *q);
/* The oldest query (the caller owns it), or NULL. */
srv_query *srv_inbox_take_query(srv_inbox *in);
int srv_inbox_queries(const srv_inbox *in);

/* Appends rc (takes ownership). */
void srv_inbox_push_replay(srv_inbox *in, srv_replay_cam *rc);
/* The oldest replay camera (the caller owns it), or NULL. */
srv_replay_cam *srv_inbox_take_replay(srv_inbox *in);
int srv_inbox_replays(const srv_inbox *in);
/* Frees the replay cameras not yet taken. */
void srv_inbox_drop_replays(srv_inbox *in);

/* Frees every request not yet taken. */
void srv_inbox_clear(srv_inbox *in);

#endif
