/*
 * srv_client.c - the part of a client that threads share, and the replies
 * the daemon queues to it (see srv_client.h).  What it does with each
 * message a client sends is srv_handle.c's.
 */
#include "srv_client.h"

#include "srv_convert.h"
#include "srv_entity.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- messages ------------------------------------------------------------- */

int srv_client_hand_over(srv_client *c, srv_stats *st, srv_msg *topo, srv_msg *frame, int replay, double tick_wall)
{
    if (!frame) {
        srv_msg_free(topo);
        return 0;
    }
    frame->is_frame = 1;
    frame->tick_wall = tick_wall;
    if (topo) topo->tick_wall = tick_wall;
    atomic_fetch_add(&st->frames_built, 1);
    if (replay) {
        if (topo) srv_client_queue(c, topo);
        srv_client_queue(c, frame);
    } else if (srv_outbox_publish(c->out, topo, frame)) {
        atomic_fetch_add(&st->frames_skipped, 1);
        return 1;
    }
    return 0;
}

void srv_client_queue(srv_client *c, srv_msg *m)
{
    if (srv_outbox_queue(c->out, m) == 2) srv_hub_wake_net(c->hub);
}

/* ---- clients -------------------------------------------------------------- */

static ocean_result client_create(srv_hub *h, int internal, srv_client **out)
{
    srv_client *c = calloc(1, sizeof *c);
    if (!c) return OCEAN_ENOMEM;
    pthread_mutex_lock(&h->lock);
    uint64_t hard = h->settings.srv.output_hard;
    pthread_mutex_unlock(&h->lock);
    if (srv_outbox_create(hard, &c->out) != OCEAN_OK || srv_inbox_create(&c->in) != OCEAN_OK) {
        srv_outbox_destroy(c->out);
        free(c);
        return OCEAN_ENOMEM;
    }
    atomic_init(&c->refs, 1);
    c->hub = h;
    c->internal = internal;
    atomic_init(&c->link_bps, 0);
    pthread_mutex_lock(&h->lock);
    c->id = h->next_id++;
    if (h->next_id == 0) h->next_id = 1;
    c->next = h->clients;
    h->clients = c;
    if (!internal) h->n_clients++;
    pthread_mutex_unlock(&h->lock);
    if (!internal) atomic_fetch_add(&h->stats.connections_total, 1);
    *out = c;
    return OCEAN_OK;
}

ocean_result srv_client_create(srv_hub *h, srv_client **out) { return client_create(h, 0, out); }

ocean_result srv_client_create_internal(srv_hub *h, srv_client **out) { return client_create(h, 1, out); }

void srv_client_ref(srv_client *c) { atomic_fetch_add(&c->refs, 1); }


void srv_client_unref(srv_client *c)
{
    if (!c || atomic_fetch_sub(&c->refs, 1) != 1) return;
    srv_outbox_destroy(c->out);
    srv_inbox_destroy(c->in);
    free(c);
}

void srv_client_remove(srv_client *c)
{
    srv_hub *h = c->hub;
    pthread_mutex_lock(&h->lock);
    for (srv_client **p = &h->clients; *p; p = &(*p)->next) {
        if (*p == c) {
            *p = c->next;
            if (!c->internal) h->n_clients--;
            if (c->subscribed) h->n_subscribed--;
            break;
        }
    }
    c->closed = 1;
    srv_inbox_clear(c->in);
    pthread_mutex_unlock(&h->lock);
    srv_client_unref(c);
}

/* ---- replies ---------------------------------------------------------------- */

static int verbose(srv_client *c)
{
    pthread_mutex_lock(&c->hub->lock);
    int v = c->hub->settings.srv.verbose;
    pthread_mutex_unlock(&c->hub->lock);
    return v;
}

void srv_client_send_error(srv_client *c, const void *bad, size_t badlen, ocean_result code,
                           const char *why)
{
    srv_msg *m = srv_msg_new();
    if (!m) return;
    if (proto_error_reply(&m->buf, bad, badlen, code, why, 0, srv_hub_sim_time(c->hub)) != OCEAN_OK) {
        srv_msg_free(m);
        return;
    }
    if (verbose(c)) fprintf(stderr, "oceand: client %u: ERROR %s: %s\n", c->id, ocean_strerror(code), why);
    atomic_fetch_add(&c->hub->stats.errors_sent, 1);
    srv_client_queue(c, m);
}

void srv_client_send_bye(srv_client *c, int reason, const char *why)
{
    srv_msg *m = srv_msg_new();
    if (!m) return;
    proto_msg b;
    proto_msg_init(&b, PROTO_BYE);
    /* past the exact-time limit the clock is no time the encoder takes
     * (as proto_error_reply: 0), and the BYE saying so must still go */
    double now = srv_hub_sim_time(c->hub);
    b.hdr.sim_time = ocean_time_ok(now) ? now : 0.0;
    b.u.bye.reason = (uint16_t)reason;
    snprintf(b.u.bye.message, sizeof b.u.bye.message, "%s", why);
    if (proto_encode(&m->buf, &b, NULL, 0) != OCEAN_OK) {
        srv_msg_free(m);
        return;
    }
    m->close_after = 1;
    srv_client_queue(c, m);
}

ocean_result srv_client_queue_entities(srv_client *c, int max)
{
    ocean_entity_desc *d = malloc(sizeof *d * (size_t)max);
    ocean_track_sample *smp = malloc(sizeof *smp * (size_t)max);
    double *from = malloc(sizeof *from * (size_t)max);
    ocean_result r = d && smp && from ? OCEAN_OK : OCEAN_ENOMEM;
    int n = r == OCEAN_OK ? srv_entities_snapshot(c->hub->entities, d, smp, from, max) : 0;
    for (int i = 0; i < n; i++) {
        proto_msg m;
        srv_entity_msg(PROTO_ENTITY_ANNOUNCE, &d[i], &smp[i], from[i], &m);
        srv_msg *q = srv_msg_encode(&m);
        if (q) srv_client_queue(c, q);
    }
    free(d);
    free(smp);
    free(from);
    return r;
}

typedef struct entry_queue_ctx {
    srv_client *c;
    int lost;
} entry_queue_ctx;

static void entry_queue(void *ctx, const ocean_entity_entry *en)
{
    entry_queue_ctx *x = ctx;
    proto_msg m;
    srv_entity_msg(en->removal ? PROTO_ENTITY_GONE : PROTO_ENTITY_ANNOUNCE, &en->d, &en->s, en->from, &m);
    srv_msg *q = srv_msg_encode(&m);
    if (q) srv_client_queue(x->c, q);
    else x->lost++;
}

int srv_client_queue_entity_entries(srv_client *c)
{
    entry_queue_ctx x = {c, 0};
    int n = srv_entities_each(c->hub->entities, entry_queue, &x);
    if (x.lost)
        fprintf(stderr, "oceand: client %u: out of memory for %d of the %d entries of the entities' timeline (it "
                "may ask for the newest samples: ENTITY get)\n", c->id, x.lost, n);
    return n;
}

void srv_client_send_hello(srv_client *c)
{
    srv_hub *h = c->hub;
    proto_msg m;
    proto_msg_init(&m, PROTO_HELLO);
    proto_hello *o = &m.u.hello;
    pthread_mutex_lock(&h->lock);
    const srv_settings *s = &h->settings;
    o->codecs = s->srv.codecs;
    o->mesh_kinds = 0xF;
    o->effects = (uint8_t)(s->effects & PROTO_FX_ALL);
    o->cutoff_policies = 7;
    o->modes = 3;
    o->max_message = (uint32_t)s->srv.max_message;
    /* the most points a QUERY within max_message can carry: 32 + 24 + 16 N */
    uint32_t fit = s->srv.max_message > 56 ? (uint32_t)((s->srv.max_message - 56) / 16) : 0;
    o->max_query_points = (uint32_t)s->srv.max_query_points < fit ? (uint32_t)s->srv.max_query_points : fit;
    o->max_tile_size = (uint16_t)s->srv.max_tile_size;
    o->max_lod_levels = (uint8_t)s->srv.max_lod_levels;
    /* layout 1 counts the near-field cascade as one more layer */
    o->max_layers = (uint8_t)srv_settings_layout1_cascades(s);
    o->tick_rate_hz = (float)s->srv.tick_rate;
    /* frames go out on ticks: no faster than the tick rate */
    o->max_frame_rate_hz = (float)fmin(s->srv.max_frame_rate, s->srv.tick_rate);
    o->sea = h->sea_now;
    o->client_id = c->id;
    snprintf(o->server_version, sizeof o->server_version, "%s fp=%s", SRV_VERSION, h->fingerprint);
    m.hdr.sim_time = srv_hub_sim_time(h);
    srv_msg *q = srv_msg_new();
    char err[256];
    if (q && proto_encode(&q->buf, &m, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "oceand: cannot encode HELLO: %s\n", err);
        srv_msg_free(q);
        q = NULL;
    }
    if (q) {
        /* HELLO, then the pending changes and the entities' timeline, before
         * any later announce (an entry's broadcast waits for this hold) */
        srv_client_queue(c, q);
        for (int i = 0; i < h->n_sea_pending; i++) {
            srv_msg *a = srv_hub_sea_announce(&h->sea_pending[i].sea, h->sea_pending[i].effective_time,
                                          m.hdr.sim_time);
            if (a) srv_client_queue(c, a);
        }
        srv_client_queue_entity_entries(c);
        c->hello_sent = 1;
    }
    pthread_mutex_unlock(&h->lock);
}

void srv_client_send_sea_timeline(srv_client *c)
{
    srv_hub *h = c->hub;
    pthread_mutex_lock(&h->lock);
    double now = srv_hub_sim_time(h);
    srv_msg *a = srv_hub_sea_announce(&h->sea_now, h->sea_effective, now);
    if (a) srv_client_queue(c, a);
    for (int i = 0; i < h->n_sea_pending; i++) {
        a = srv_hub_sea_announce(&h->sea_pending[i].sea, h->sea_pending[i].effective_time, now);
        if (a) srv_client_queue(c, a);
    }
    pthread_mutex_unlock(&h->lock);
}

/* ---- incoming ------------------------------------------------------------- */

/* Checks a SUBSCRIBE against this server; fills *eff with the effects that
 * will be served.  OCEAN_OK or an error with why. */
