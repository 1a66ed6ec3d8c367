/*
 * srv_hub.c - the hub: clients, settings, the shared clock and the
 * sea-state timeline (see srv_hub.h).
 */
#include "srv_hub.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "srv_client.h"
#include "srv_convert.h"
#include "srv_entity.h"
#include "srv_entlog.h"
#include "srv_wakes.h"
#include "srv_fingerprint.h"

double srv_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- hub ------------------------------------------------------------------ */

ocean_result srv_hub_init(srv_hub *h, const srv_settings *s)
{
    memset(h, 0, sizeof *h);
    if (pthread_mutex_init(&h->lock, NULL)) return OCEAN_ENOMEM;
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    int e = pthread_cond_init(&h->wake, &ca);
    pthread_condattr_destroy(&ca);
    if (e) {
        pthread_mutex_destroy(&h->lock);
        return OCEAN_ENOMEM;
    }
    char why[160];
    if (srv_entities_create(s->srv.max_entities, s->srv.entity_track_keep, &h->entities, why, sizeof why) !=
        OCEAN_OK) {
        fprintf(stderr, "oceand: %s\n", why);
        pthread_cond_destroy(&h->wake);
        pthread_mutex_destroy(&h->lock);
        return OCEAN_ENOMEM;
    }
    if (srv_wakes_create(s->srv.max_entities, &h->stats, &h->wakes) != OCEAN_OK) {
        fprintf(stderr, "oceand: cannot start the wake builder\n");
        srv_entities_destroy(h->entities);
        pthread_cond_destroy(&h->wake);
        pthread_mutex_destroy(&h->lock);
        return OCEAN_ENOMEM;
    }
    h->settings = *s;
    h->file_params = s->params;
    h->tick_rate = s->srv.tick_rate;
    h->next_id = 1;
    struct timespec rt;
    clock_gettime(CLOCK_REALTIME, &rt);
    double epoch;
    if (!s->srv.epoch[0] || srv_epoch_parse(s->srv.epoch, &epoch, NULL, 0) != OCEAN_OK) {
        /* default: the start, to the nanosecond */
        h->epoch_s = (int64_t)rt.tv_sec;
        h->epoch_frac = 1e-9 * (double)rt.tv_nsec;
    } else {
        h->epoch_s = (int64_t)floor(epoch);
        h->epoch_frac = epoch - floor(epoch);
    }
    srv_sea_from_params(&s->params, &h->sea_now);
    h->sea_effective = srv_hub_sim_time(h);
    srv_fingerprint(s, h->fingerprint);
    return OCEAN_OK;
}

void srv_hub_fini(srv_hub *h)
{
    /* Clients still listed (the service thread was torn down) go now. */
    while (h->clients) {
        srv_client *c = h->clients;
        h->clients = c->next;
        srv_client_unref(c);
    }
    srv_wakes_destroy(h->wakes);
    srv_entities_destroy(h->entities);
    pthread_cond_destroy(&h->wake);
    pthread_mutex_destroy(&h->lock);
}

double srv_hub_sim_time(const srv_hub *h)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    /* whole seconds apart from the fraction: a Unix time as one double
     * would keep only ~0.2 us */
    return (double)((int64_t)ts.tv_sec - h->epoch_s) + (1e-9 * (double)ts.tv_nsec - h->epoch_frac);
}

double srv_hub_sim_time_at(const srv_hub *h, double unix_s)
{
    double w = floor(unix_s);
    return (double)((int64_t)w - h->epoch_s) + ((unix_s - w) - h->epoch_frac);
}

/* ---- the sea-state timeline ------------------------------------------------- */

srv_msg *srv_hub_sea_announce(const proto_sea *sea, double eff, double now)
{
    proto_msg m;
    srv_sea_announce(sea, eff, now, &m);
    srv_msg *q = srv_msg_new();
    if (!q) return NULL;
    if (proto_encode(&q->buf, &m, NULL, 0) != OCEAN_OK) {
        srv_msg_free(q);
        return NULL;
    }
    return q;
}

double srv_hub_sea_lead(const srv_hub *h)
{
    return 2 * h->sea_build_s + 2 / h->tick_rate;
}

ocean_result srv_hub_sea_schedule(srv_hub *h, const ocean_params *p, double requested, double lead, double *eff,
                                  char *why, size_t whylen)
{
    double now = srv_hub_sim_time(h);
    double e = requested > now + lead ? requested : now + lead;
    /* earliest first: moving past one never brings e nearer an earlier
     * one; a time asked for that equals a pending one replaces it, a time
     * moved onto one goes past it */
    int moved = 0;
    for (int k = 0; k < h->n_sea_pending && lead > 0; k++) {
        double ek = h->sea_pending[k].effective_time;
        if (fabs(e - ek) < lead && (ek != e || moved)) {
            e = ek + lead;
            moved = 1;
        }
    }
    int at = 0;
    while (at < h->n_sea_pending && h->sea_pending[at].effective_time < e) at++;
    int replace = at < h->n_sea_pending && h->sea_pending[at].effective_time == e;
    if (!replace && h->n_sea_pending >= SRV_SEA_PENDING_MAX) {
        if (why)
            snprintf(why, whylen, "SEA_STATE set refused: %d changes are already pending "
                     "(the most a server holds); wait until one takes effect", SRV_SEA_PENDING_MAX);
        return OCEAN_ERATE;
    }
    if (!replace) {
        memmove(&h->sea_pending[at + 1], &h->sea_pending[at],
                (size_t)(h->n_sea_pending - at) * sizeof h->sea_pending[0]);
        h->n_sea_pending++;
    }
    srv_sea_change *c = &h->sea_pending[at];
    c->effective_time = e;
    c->params = *p;
    srv_sea_from_params(p, &c->sea);
    h->sea_gen++;
    for (srv_client *k = h->clients; k; k = k->next) {
        if (k->closed || !k->hello_sent) continue;
        srv_msg *q = srv_hub_sea_announce(&c->sea, e, now);
        if (q) srv_client_queue(k, q);
    }
    pthread_cond_signal(&h->wake);
    if (eff) *eff = e;
    return OCEAN_OK;
}

int srv_hub_sea_take_due(srv_hub *h, double t, srv_sea_change *out)
{
    int n = 0;
    while (n < h->n_sea_pending && h->sea_pending[n].effective_time <= t) n++;
    if (!n) return 0;
    *out = h->sea_pending[n - 1];
    memmove(&h->sea_pending[0], &h->sea_pending[n], (size_t)(h->n_sea_pending - n) * sizeof h->sea_pending[0]);
    h->n_sea_pending -= n;
    h->sea_now = out->sea;
    h->sea_effective = out->effective_time;
    h->settings.params = out->params;
    return 1;
}

void srv_hub_broadcast(srv_hub *h, const proto_msg *m)
{
    for (srv_client *k = h->clients; k; k = k->next) {
        if (k->closed || !k->hello_sent) continue;
        srv_msg *q = srv_msg_encode(m);
        if (q) srv_client_queue(k, q);
    }
}

ocean_result srv_hub_entity_enter(srv_hub *h, const proto_msg *m, char *why, size_t n)
{
    const proto_entity *e = &m->u.entity;
    ocean_entity_desc d;
    ocean_track_sample s;
    srv_entity_from_msg(e, &d, &s);
    ocean_result r;
    /* the entry and its broadcast under one hold of hub.lock: a client
     * joining gets it either in its HELLO's timeline or as the broadcast,
     * never both, never neither */
    pthread_mutex_lock(&h->lock);
    /* In force no earlier than its entity's last entry.  Entries come in
     * the order they were made (the shared stream's, with replicas), but
     * their times are each maker's clock plus its lead: a removal made on
     * one replica just after a sample made on another may carry a time a
     * moment before the sample's.  Every reader of the stream moves it
     * alike (each folds the same entries into the same table). */
    proto_msg at = *m;
    at.hdr.sim_time = fmax(m->hdr.sim_time, srv_entities_floor(h->entities, e->id));
    double from = at.hdr.sim_time;
    if (e->op == PROTO_ENTITY_GONE) {
        r = srv_entities_remove(h->entities, e->id, from);
        if (r != OCEAN_OK)
            snprintf(why, n, r == OCEAN_ENOTFOUND ? "no entity %u in the sea" : "entity %u: a removal at %.6f s, not a finite time",
                     e->id, from);
    } else {
        r = srv_entities_sample(h->entities, &d, &s, from, why, n);
    }
    if (r == OCEAN_OK) srv_hub_broadcast(h, &at);
    /* in the order entered (the lock held): the log rebuilds the table */
    if (r == OCEAN_OK && h->entlog) srv_entlog_append(h->entlog, &at);
    pthread_mutex_unlock(&h->lock);
    if (r != OCEAN_OK) return r;
    if (e->op == PROTO_ENTITY_ANNOUNCE) srv_wakes_ahead(h, &d, &s);
    srv_hub_wake_net(h);
    return OCEAN_OK;
}

void srv_hub_wake_net(srv_hub *h)
{
    if (h->wake_net) h->wake_net(h->wake_ctx);
}
