/*
 * srv_outbox.c - one client's outgoing messages, from whichever thread
 * makes them to the service thread that sends them (see srv_outbox.h).
 */
#include "srv_outbox.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>

struct srv_outbox {
    pthread_mutex_t lock;
    srv_msg *ctrl, *ctrl_tail;          /* [lock] FIFO: HELLO, ERROR, results, replay frames */
    srv_msg *slot_topo;                 /* [lock] latest-wins frame slot: optional */
    srv_msg *slot_frame;                /* [lock]   MESH_TOPOLOGY, then FRAME */
    uint64_t queued_bytes;              /* [lock] ctrl + slot, at allocated size (srv_msg_cost) */
    atomic_uint_fast64_t hard;          /* server.output_hard, as the service thread last saw it */
    atomic_int want_write;              /* something was queued since the service thread looked */
    atomic_int over_hard;               /* a message was refused: over the hard limit */
    void (*notify)(void *ctx);          /* [lock] called, under the lock, after a queue */
    void *notify_ctx;
};

void srv_outbox_set_notify(srv_outbox *o, void (*fn)(void *ctx), void *ctx)
{
    pthread_mutex_lock(&o->lock);
    o->notify = fn;
    o->notify_ctx = ctx;
    pthread_mutex_unlock(&o->lock);
}

ocean_result srv_outbox_create(uint64_t hard, srv_outbox **out)
{
    srv_outbox *o = calloc(1, sizeof *o);
    if (!o) return OCEAN_ENOMEM;
    if (pthread_mutex_init(&o->lock, NULL)) {
        free(o);
        return OCEAN_ENOMEM;
    }
    atomic_init(&o->hard, hard);
    atomic_init(&o->want_write, 0);
    atomic_init(&o->over_hard, 0);
    *out = o;
    return OCEAN_OK;
}

static void free_list(srv_msg *m)
{
    while (m) {
        srv_msg *n = m->next;
        srv_msg_free(m);
        m = n;
    }
}

void srv_outbox_destroy(srv_outbox *o)
{
    if (!o) return;
    free_list(o->ctrl);
    srv_msg_free(o->slot_topo);
    srv_msg_free(o->slot_frame);
    pthread_mutex_destroy(&o->lock);
    free(o);
}

/* The hard output limit holds when a message is queued, not only when the
 * service thread next looks: a client that makes the daemon queue faster
 * than it reads (a flood of refused messages, replay frames it does not
 * read) is cut off at the limit, and the message that would pass it is not
 * kept.  A BYE always goes in (it ends the queue). */
int srv_outbox_queue(srv_outbox *o, srv_msg *m)
{
    m->next = NULL;
    size_t cost = srv_msg_cost(m);
    uint64_t hard = atomic_load(&o->hard);
    int refused = 0;
    pthread_mutex_lock(&o->lock);
    if (hard && !m->close_after && o->queued_bytes + cost > hard) {
        refused = 1;
    } else {
        if (o->ctrl_tail) o->ctrl_tail->next = m;
        else o->ctrl = m;
        o->ctrl_tail = m;
        o->queued_bytes += cost;
        if (o->notify) o->notify(o->notify_ctx);
    }
    pthread_mutex_unlock(&o->lock);
    if (refused) {
        srv_msg_free(m);
        return atomic_exchange(&o->over_hard, 1) ? 1 : 2;
    }
    atomic_store(&o->want_write, 1);
    return 0;
}

int srv_outbox_publish(srv_outbox *o, srv_msg *topo, srv_msg *frame)
{
    srv_msg *drop_f = NULL, *drop_t = NULL;
    pthread_mutex_lock(&o->lock);
    if (o->slot_frame) {
        drop_f = o->slot_frame;
        o->queued_bytes -= srv_msg_cost(drop_f);
    }
    if (topo) {
        if (o->slot_topo) {
            drop_t = o->slot_topo;
            o->queued_bytes -= srv_msg_cost(drop_t);
        }
        o->slot_topo = topo;
        o->queued_bytes += srv_msg_cost(topo);
    }
    o->slot_frame = frame;
    o->queued_bytes += srv_msg_cost(frame);
    pthread_mutex_unlock(&o->lock);
    atomic_store(&o->want_write, 1);
    int skipped = drop_f != NULL;
    srv_msg_free(drop_f);
    srv_msg_free(drop_t);
    return skipped;
}

srv_msg *srv_outbox_take(srv_outbox *o)
{
    srv_msg *m = NULL;
    pthread_mutex_lock(&o->lock);
    if (o->ctrl) {
        m = o->ctrl;
        o->ctrl = m->next;
        if (!o->ctrl) o->ctrl_tail = NULL;
    } else if (o->slot_topo) {
        m = o->slot_topo;
        o->slot_topo = NULL;
        m->live = 1; /* on the link, part of the frame it comes before */
    } else if (o->slot_frame) {
        m = o->slot_frame;
        o->slot_frame = NULL;
        m->live = 1;
    }
    if (m) o->queued_bytes -= srv_msg_cost(m);
    pthread_mutex_unlock(&o->lock);
    if (m) m->next = NULL;
    return m;
}

int srv_outbox_next_is_live(srv_outbox *o)
{
    pthread_mutex_lock(&o->lock);
    int live = !o->ctrl && (o->slot_topo || o->slot_frame);
    pthread_mutex_unlock(&o->lock);
    return live;
}

int srv_outbox_frame_waiting(srv_outbox *o)
{
    pthread_mutex_lock(&o->lock);
    int waiting = o->slot_frame != NULL;
    pthread_mutex_unlock(&o->lock);
    return waiting;
}

uint64_t srv_outbox_queued(srv_outbox *o)
{
    pthread_mutex_lock(&o->lock);
    uint64_t q = o->queued_bytes;
    pthread_mutex_unlock(&o->lock);
    return q;
}

void srv_outbox_set_hard(srv_outbox *o, uint64_t hard) { atomic_store(&o->hard, hard); }

int srv_outbox_over_hard(srv_outbox *o) { return atomic_load(&o->over_hard); }

void srv_outbox_want_write(srv_outbox *o) { atomic_store(&o->want_write, 1); }

int srv_outbox_take_want_write(srv_outbox *o) { return atomic_exchange(&o->want_write, 0); }
