/*
 * srv_daemon.c - start, reload and stop of the daemon's threads.
 */
#include "srv_daemon.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "srv_admit.h"
#include "srv_cigi.h"
#include "srv_entlog.h"
#include "srv_net.h"
#include "srv_redis.h"
#include "srv_sim.h"

struct srv_daemon {
    srv_hub hub;
    srv_sim *sim;
    srv_net *net;
    srv_cigi *cigi;             /* NULL: server.cigi_port 0 */
};

/* server.entity_log: its entries into the table, then every later entry
 * onto it.  Replicated, the stream is the timeline: the log is written,
 * not read. */
static ocean_result entlog_start(srv_hub *h, const srv_settings *s, char *msg, size_t msglen)
{
    if (!s->srv.entity_log[0]) return OCEAN_OK;
    srv_entlog *l;
    ocean_result r = srv_entlog_open(s->srv.entity_log, &l, msg, msglen);
    int entered = 0, refused = 0;
    if (r == OCEAN_OK && !h->redis) r = srv_entlog_load(l, h, &entered, &refused, msg, msglen);
    if (r != OCEAN_OK) {
        srv_entlog_close(l);
        return r;
    }
    if (!h->redis)
        fprintf(stderr, "oceand: server.entity_log %s: %d entries entered, %d refused by the table\n",
                s->srv.entity_log, entered, refused);
    h->entlog = l;
    return OCEAN_OK;
}

ocean_result srv_daemon_start(const srv_settings *s, srv_daemon **out, char *msg, size_t msglen)
{
    *out = NULL;
    srv_daemon *d = calloc(1, sizeof *d);
    if (!d) return OCEAN_ENOMEM;
    ocean_result r = srv_hub_init(&d->hub, s);
    if (r != OCEAN_OK) {
        free(d);
        return r;
    }
    r = srv_admit_create(s->srv.workers, &d->hub.admit);
    if (r != OCEAN_OK) {
        srv_hub_fini(&d->hub);
        free(d);
        return r;
    }
    if (s->srv.redis[0]) {
        /* the shared timeline so far enters the hub before any tick */
        r = srv_redis_start(&d->hub, s, &d->hub.redis, msg, msglen);
        if (r != OCEAN_OK) {
            srv_admit_destroy(d->hub.admit);
            srv_hub_fini(&d->hub);
            free(d);
            return r;
        }
    }
    r = entlog_start(&d->hub, s, msg, msglen);
    if (r == OCEAN_OK) r = srv_sim_create(&d->hub, &d->sim, msg, msglen);
    if (r == OCEAN_OK) r = srv_net_create(&d->hub, &d->net, msg, msglen);
    if (r == OCEAN_OK) r = srv_sim_start(d->sim);
    if (r == OCEAN_OK) r = srv_net_start(d->net);
    if (r == OCEAN_OK) r = srv_cigi_start(&d->hub, &d->cigi, msg, msglen);
    if (r != OCEAN_OK) {
        srv_net_stop(d->net, 0.5);
        srv_sim_stop(d->sim);
        srv_sim_destroy(d->sim);
        srv_net_destroy(d->net);
        srv_redis_stop(d->hub.redis);
        srv_entlog_close(d->hub.entlog);
        srv_admit_destroy(d->hub.admit);
        srv_hub_fini(&d->hub);
        free(d);
        return r;
    }
    *out = d;
    return OCEAN_OK;
}

int srv_daemon_port(const srv_daemon *d) { return srv_net_port(d->net); }
srv_hub *srv_daemon_hub(srv_daemon *d) { return &d->hub; }

ocean_result srv_daemon_reload(srv_daemon *d, const srv_settings *s, char *msg, size_t msglen)
{
    srv_hub *h = &d->hub;
    msg[0] = 0;
    /* A changed sea is built once here, off the lock (the simulation thread
     * ticks on), before any client is told of it: a sea that cannot be
     * built (a wisdom file without its grid's plans) must not be announced
     * to every client and then never served. */
    srv_settings *probe = malloc(sizeof *probe);
    if (!probe) return OCEAN_ENOMEM;
    pthread_mutex_lock(&h->lock);
    int file_sea_changed = memcmp(&h->file_params, &s->params, sizeof s->params) != 0;
    int replicated = h->redis != NULL;
    *probe = *s;
    probe->effects = h->settings.effects; /* fixed by the running scene */
    pthread_mutex_unlock(&h->lock);
    char sea_why[600] = "";
    int sea_ok = !file_sea_changed || replicated ||
                 srv_sim_sea_check(probe, &s->params, sea_why, sizeof sea_why) == OCEAN_OK;
    free(probe);
    pthread_mutex_lock(&h->lock);
    const srv_config *o = &h->settings.srv;
    const char *restart[12]; /* one per key tested below (10) */
    int nr = 0;
    if (o->port != s->srv.port) restart[nr++] = "server.port";
    if (strcmp(o->bind, s->srv.bind)) restart[nr++] = "server.bind";
    if (strcmp(o->web_root, s->srv.web_root)) restart[nr++] = "server.web_root";
    if (strcmp(o->epoch, s->srv.epoch)) restart[nr++] = "server.epoch";
    if (strcmp(o->redis, s->srv.redis) || strcmp(o->redis_stream, s->srv.redis_stream))
        restart[nr++] = "server.redis";
    if (o->workers != s->srv.workers) restart[nr++] = "server.workers";
    if (o->cigi_port != s->srv.cigi_port || strcmp(o->cigi_hosts, s->srv.cigi_hosts) ||
        strcmp(o->geo_origin, s->srv.geo_origin))
        restart[nr++] = "server.cigi_port, server.cigi_hosts, server.geo_origin";
    if (o->max_entities != s->srv.max_entities) restart[nr++] = "server.max_entities";
    if (o->entity_track_keep != s->srv.entity_track_keep) restart[nr++] = "server.entity_track_keep";
    if (strcmp(o->entity_log, s->srv.entity_log)) restart[nr++] = "server.entity_log";
    srv_settings keep = h->settings;
    h->settings = *s;
    /* keys that need a restart keep their running values */
    h->settings.srv.port = keep.srv.port;
    snprintf(h->settings.srv.bind, sizeof h->settings.srv.bind, "%s", keep.srv.bind);
    snprintf(h->settings.srv.web_root, sizeof h->settings.srv.web_root, "%s", keep.srv.web_root);
    h->settings.srv.workers = keep.srv.workers;
    snprintf(h->settings.srv.epoch, sizeof h->settings.srv.epoch, "%s", keep.srv.epoch);
    snprintf(h->settings.srv.redis, sizeof h->settings.srv.redis, "%s", keep.srv.redis);
    snprintf(h->settings.srv.redis_stream, sizeof h->settings.srv.redis_stream, "%s", keep.srv.redis_stream);
    h->settings.srv.cigi_port = keep.srv.cigi_port;
    snprintf(h->settings.srv.cigi_hosts, sizeof h->settings.srv.cigi_hosts, "%s", keep.srv.cigi_hosts);
    snprintf(h->settings.srv.geo_origin, sizeof h->settings.srv.geo_origin, "%s", keep.srv.geo_origin);
    h->settings.srv.max_entities = keep.srv.max_entities;
    h->settings.srv.entity_track_keep = keep.srv.entity_track_keep;
    snprintf(h->settings.srv.entity_log, sizeof h->settings.srv.entity_log, "%s", keep.srv.entity_log);
    /* effects and near field are fixed by the running ocean's scene */
    h->settings.effects = keep.effects;
    h->settings.params = keep.params;
    /* The file's sea against the file's sea of the last load, not against
     * the sea in force: a reload of an unchanged file undid a SEA_STATE set
     * and announced the old sea to every client. */
    /* Refused (it cannot be built, or the timeline is full), the file's sea
     * is not taken as seen: the next reload tries it again, so a refusal
     * never leaves the file's sea unapplied for good. */
    char full_why[200] = "";
    if (file_sea_changed && !sea_ok) {
        /* said in msg, on the "configuration reloaded" line */
    } else if (file_sea_changed && h->redis) {
        fprintf(stderr, "oceand: reload: the sea is replicated (server.redis): the file's sea is not "
                "applied; change it with SEA_STATE set\n");
    } else if (file_sea_changed) {
        /* a changed sea enters the timeline now, announced to every client */
        if (srv_hub_sea_schedule(h, &s->params, -INFINITY, srv_hub_sea_lead(h), NULL, full_why, sizeof full_why) !=
            OCEAN_OK)
            sea_ok = 0;
        else
            fprintf(stderr, "oceand: reload: the file's sea changed: it replaces the sea in force\n");
    }
    if (sea_ok) h->file_params = s->params;
    h->settings_gen++;
    pthread_cond_signal(&h->wake);
    pthread_mutex_unlock(&h->lock);
    srv_hub_wake_net(h);
    atomic_fetch_add(&h->stats.reloads, 1);
    size_t off = 0;
    if (nr) {
        off = (size_t)snprintf(msg, msglen, "restart needed for:");
        for (int i = 0; i < nr && off < msglen; i++)
            off += (size_t)snprintf(msg + off, msglen - off, " %s", restart[i]);
    }
    if (!sea_ok && off < msglen && full_why[0])
        snprintf(msg + off, msglen - off, "%sthe file's sea is not applied: %s; the sea in force is kept, "
                 "and the next reload tries the file's sea again", off ? "; " : "", full_why);
    else if (!sea_ok && off < msglen)
        snprintf(msg + off, msglen - off, "%sthe file's sea is not applied, it cannot be built: %s; the "
                 "sea in force is kept and no client was told of the new one", off ? "; " : "", sea_why);
    return OCEAN_OK;
}

void srv_daemon_stop(srv_daemon *d)
{
    if (!d) return;
    srv_cigi_stop(d->cigi);
    srv_net_stop(d->net, 2.0);
    srv_sim_stop(d->sim);
    srv_net_destroy(d->net);
    srv_sim_destroy(d->sim);
    srv_redis_stop(d->hub.redis);
    srv_entlog_close(d->hub.entlog);
    srv_admit_destroy(d->hub.admit);
    srv_hub_fini(&d->hub);
    free(d);
}
