/*
 * srv_inbox.c - one client's queued QUERYs and replay cameras (see
 * srv_inbox.h).  Every call under hub.lock.
 */
#include "srv_inbox.h"

#include <stdlib.h>

struct srv_inbox {
    srv_query *queries, *queries_tail;
    int n_queries;
    srv_replay_cam *replay, *replay_tail;
    int n_replay;
};

ocean_result srv_inbox_create(srv_inbox **out)
{
    *out = calloc(1, sizeof **out);
    return *out ? OCEAN_OK : OCEAN_ENOMEM;
}

void srv_inbox_destroy(srv_inbox *in)
{
    if (!in) return;
    srv_inbox_clear(in);
    free(in);
}

void srv_inbox_push_query(srv_inbox *in, srv_query *q)
{
    q->next = NULL;
    if (in->queries_tail) in->queries_tail->next = q;
    else in->queries = q;
    in->queries_tail = q;
    in->n_queries++;
}

srv_query *srv_inbox_take_query(srv_inbox *in)
{
    srv_query *q = in->queries;
    if (!q) return NULL;
    in->queries = q->next;
    if (!in->queries) in->queries_tail = NULL;
    in->n_queries--;
    q->next = NULL;
    return q;
}

int srv_inbox_queries(const srv_inbox *in) { return in->n_queries; }

void srv_inbox_push_replay(srv_inbox *in, srv_replay_cam *rc)
{
    rc->next = NULL;
    if (in->replay_tail) in->replay_tail->next = rc;
    else in->replay = rc;
    in->replay_tail = rc;
    in->n_replay++;
}

srv_replay_cam *srv_inbox_take_replay(srv_inbox *in)
{
    srv_replay_cam *rc = in->replay;
    if (!rc) return NULL;
    in->replay = rc->next;
    if (!in->replay) in->replay_tail = NULL;
    in->n_replay--;
    rc->next = NULL;
    return rc;
}

int srv_inbox_replays(const srv_inbox *in) { return in->n_replay; }

void srv_inbox_drop_replays(srv_inbox *in)
{
    srv_replay_cam *rc;
    while ((rc = srv_inbox_take_replay(in))) free(rc);
}

void srv_inbox_clear(srv_inbox *in)
{
    srv_query *q;
    while ((q = srv_inbox_take_query(in))) {
        free(q->points);
        free(q);
    }
    srv_inbox_drop_replays(in);
}
