/*
 * srv_redis.c - the replicated sea-state timeline (see srv_redis.h).
 *
 * Two connections: the reader thread's, blocked in XREAD on the stream, and
 * the publishing one the service thread uses for XADD (guarded by a mutex).
 * Stream entries carry one field, "msg": the bytes of a SEA_STATE announce
 * (PROTOCOL.md), so the stream holds exactly what clients are sent.
 */
#include "srv_redis.h"

#include <hiredis/hiredis.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/time.h>
#include <time.h>

struct srv_redis {
    srv_hub *hub;
    char host[SRV_BIND_MAX];
    int port;
    char key[SRV_REDIS_KEY_MAX];
    double lead;                /* server.sea_lead, s */
    redisContext *rd;           /* [reader thread] */
    redisContext *pub;          /* [pub_lock] */
    pthread_mutex_t pub_lock;
    char last_id[64];           /* [reader thread] last entry read */
    pthread_t thread;
    int running;
    atomic_int stop;
};

static redisContext *connect_to(const srv_redis *r, char *msg, size_t msglen)
{
    struct timeval tv = {2, 0};
    redisContext *c = redisConnectWithTimeout(r->host, r->port, tv);
    if (!c || c->err) {
        snprintf(msg, msglen, "server.redis %s:%d: %s", r->host, r->port, c ? c->errstr : "out of memory");
        if (c) redisFree(c);
        return NULL;
    }
    /* a Redis that stops answering must not hold a thread for ever (the
     * service thread publishes; XREAD blocks 200 ms at most) */
    struct timeval io = {1, 0};
    redisSetTimeout(c, io);
    return c;
}

/* Enters one stream entry into the hub's timeline. */
static void enter(srv_redis *r, const char *bytes, size_t len)
{
    proto_msg m;
    char err[200];
    if (proto_decode((const uint8_t *)bytes, len, &m, err, sizeof err) != OCEAN_OK ||
        m.hdr.type != PROTO_SEA_STATE || m.u.sea_state.op != PROTO_SEA_ANNOUNCE) {
        fprintf(stderr, "oceand: redis stream %s: an entry that is no SEA_STATE announce skipped (%s)\n", r->key,
                err);
        return;
    }
    srv_hub *h = r->hub;
    pthread_mutex_lock(&h->lock);
    ocean_params np;
    srv_params_from_sea(&m.u.sea_state.sea, &h->settings.params, &np);
    char msg[256];
    ocean_result res = ocean_params_validate(&np, msg, sizeof msg);
    if (res == OCEAN_OK) res = srv_hub_sea_schedule(h, &np, m.u.sea_state.effective_time, NULL, msg, sizeof msg);
    pthread_mutex_unlock(&h->lock);
    if (res != OCEAN_OK) fprintf(stderr, "oceand: redis stream %s: change skipped: %s\n", r->key, msg);
    srv_hub_wake_net(h);
}

/* One XREAD (block_ms < 0: without BLOCK); returns the entries read, -1 on
 * a connection error. */
static int read_once(srv_redis *r, int block_ms)
{
    redisReply *rep = block_ms < 0
                          ? redisCommand(r->rd, "XREAD COUNT 64 STREAMS %s %s", r->key, r->last_id)
                          : redisCommand(r->rd, "XREAD COUNT 64 BLOCK %d STREAMS %s %s", block_ms, r->key, r->last_id);
    if (!rep) return -1;
    int n = 0;
    if (rep->type == REDIS_REPLY_ARRAY && rep->elements == 1) {
        redisReply *st = rep->element[0];
        if (st->type == REDIS_REPLY_ARRAY && st->elements == 2 && st->element[1]->type == REDIS_REPLY_ARRAY) {
            redisReply *entries = st->element[1];
            for (size_t i = 0; i < entries->elements; i++) {
                redisReply *e = entries->element[i];
                if (e->type != REDIS_REPLY_ARRAY || e->elements != 2) continue;
                snprintf(r->last_id, sizeof r->last_id, "%s", e->element[0]->str);
                n++;
                redisReply *f = e->element[1];
                for (size_t k = 0; k + 1 < f->elements; k += 2)
                    if (f->element[k]->type == REDIS_REPLY_STRING && strcmp(f->element[k]->str, "msg") == 0)
                        enter(r, f->element[k + 1]->str, f->element[k + 1]->len);
            }
        }
    } else if (rep->type == REDIS_REPLY_ERROR) {
        fprintf(stderr, "oceand: redis XREAD %s: %s\n", r->key, rep->str);
        n = -1;
    }
    freeReplyObject(rep);
    return n;
}

static void *reader(void *arg)
{
    srv_redis *r = arg;
    int said = 0; /* this outage's failed reconnect is logged once */
    while (!atomic_load(&r->stop)) {
        if (!r->rd) {
            char msg[200];
            r->rd = connect_to(r, msg, sizeof msg);
            if (!r->rd) {
                if (!said)
                    fprintf(stderr, "oceand: redis: cannot reconnect (%s); retrying every 0.2 s\n", msg);
                said = 1;
                struct timespec ts = {0, 200 * 1000 * 1000};
                nanosleep(&ts, NULL);
                continue;
            }
            /* An operator watching the log sees the outage end, and from
             * where the timeline is read again. */
            fprintf(stderr, "oceand: redis %s:%d: reconnected; reading stream %s after entry %s\n", r->host,
                    r->port, r->key, r->last_id);
            said = 0;
        }
        if (read_once(r, 200) < 0) {
            if (r->rd->err) {
                fprintf(stderr, "oceand: redis %s:%d: %s; reconnecting\n", r->host, r->port, r->rd->errstr);
                redisFree(r->rd);
                r->rd = NULL;
            }
            struct timespec ts = {0, 200 * 1000 * 1000}; /* no busy loop on a refused XREAD */
            nanosleep(&ts, NULL);
        }
    }
    return NULL;
}

ocean_result srv_redis_start(srv_hub *h, const srv_settings *s, srv_redis **out, char *msg, size_t msglen)
{
    *out = NULL;
    srv_redis *r = calloc(1, sizeof *r);
    if (!r) return OCEAN_ENOMEM;
    r->hub = h;
    const char *colon = strrchr(s->srv.redis, ':');
    if (!colon || colon == s->srv.redis || (size_t)(colon - s->srv.redis) >= sizeof r->host) {
        snprintf(msg, msglen, "server.redis '%s': expected host:port", s->srv.redis);
        free(r);
        return OCEAN_EINVAL;
    }
    snprintf(r->host, sizeof r->host, "%.*s", (int)(colon - s->srv.redis), s->srv.redis);
    char *end;
    long port = strtol(colon + 1, &end, 10);
    if (*end || port < 1 || port > 65535) {
        snprintf(msg, msglen, "server.redis '%s': bad port", s->srv.redis);
        free(r);
        return OCEAN_EINVAL;
    }
    r->port = (int)port;
    snprintf(r->key, sizeof r->key, "%s", s->srv.redis_stream);
    r->lead = s->srv.sea_lead;
    snprintf(r->last_id, sizeof r->last_id, "0");
    atomic_init(&r->stop, 0);
    pthread_mutex_init(&r->pub_lock, NULL);
    r->rd = connect_to(r, msg, msglen);
    r->pub = r->rd ? connect_to(r, msg, msglen) : NULL;
    /* the timeline so far, before any client can connect */
    int got = 0;
    while (r->pub && (got = read_once(r, -1)) > 0) {}
    if (r->pub && got < 0) snprintf(msg, msglen, "server.redis: reading the stream %s failed", r->key);
    if (!r->pub || !r->rd || r->rd->err || got < 0) {
        srv_redis_stop(r);
        return OCEAN_EIO;
    }
    /* changes already in force are the current sea from the first tick
     * (the simulation builds its ocean from the hub's settings after this) */
    srv_sea_change due;
    pthread_mutex_lock(&h->lock);
    srv_hub_sea_take_due(h, srv_hub_sim_time(h), &due);
    pthread_mutex_unlock(&h->lock);
    if (pthread_create(&r->thread, NULL, reader, r) != 0) {
        srv_redis_stop(r);
        return OCEAN_ENOMEM;
    }
    r->running = 1;
    *out = r;
    return OCEAN_OK;
}

void srv_redis_stop(srv_redis *r)
{
    if (!r) return;
    atomic_store(&r->stop, 1);
    if (r->running) pthread_join(r->thread, NULL);
    if (r->rd) redisFree(r->rd);
    if (r->pub) redisFree(r->pub);
    pthread_mutex_destroy(&r->pub_lock);
    free(r);
}

ocean_result srv_redis_publish(srv_redis *r, const proto_sea *sea, double effective_time, char *why,
                               size_t whylen)
{
    double now = srv_hub_sim_time(r->hub);
    if (!(effective_time >= now + r->lead)) {
        snprintf(why, whylen, "SEA_STATE set refused: effective_time %.3f is less than server.sea_lead (%g s) "
                 "ahead of the clock (%.3f): a replicated change must reach every replica before it takes "
                 "effect", effective_time, r->lead, now);
        return OCEAN_EINVAL;
    }
    proto_msg m;
    proto_msg_init(&m, PROTO_SEA_STATE);
    m.hdr.sim_time = now;
    m.u.sea_state.op = PROTO_SEA_ANNOUNCE;
    m.u.sea_state.effective_time = effective_time;
    m.u.sea_state.sea = *sea;
    proto_buf b;
    proto_buf_init(&b, 0);
    char err[200];
    ocean_result res = proto_encode(&b, &m, err, sizeof err);
    if (res != OCEAN_OK) {
        snprintf(why, whylen, "SEA_STATE set refused: %s", err);
        proto_buf_free(&b);
        return res;
    }
    pthread_mutex_lock(&r->pub_lock);
    redisReply *rep = NULL;
    /* A connection Redis closed (a restart) is found dead only by the
     * command that uses it: then reconnect and send once more, so the set
     * that meets the outage's end is stored, not refused (the second try
     * of the same announce would be harmless: replicas replace a change
     * with the same effective time). */
    for (int attempt = 0; attempt < 2 && !rep; attempt++) {
        if (!r->pub || r->pub->err) {
            char msg[200];
            int lost = r->pub != NULL;
            if (r->pub) redisFree(r->pub);
            r->pub = connect_to(r, msg, sizeof msg);
            if (lost && r->pub)
                fprintf(stderr, "oceand: redis %s:%d: publishing connection reconnected\n", r->host, r->port);
        }
        if (!r->pub) break;
        rep = redisCommand(r->pub, "XADD %s * msg %b", r->key, proto_buf_data(&b), b.len);
    }
    int ok = rep && rep->type == REDIS_REPLY_STRING;
    if (!ok)
        snprintf(why, whylen, "SEA_STATE set not stored: Redis %s:%d %s", r->host, r->port,
                 rep && rep->type == REDIS_REPLY_ERROR ? rep->str : r->pub ? r->pub->errstr : "unreachable");
    if (rep) freeReplyObject(rep);
    pthread_mutex_unlock(&r->pub_lock);
    proto_buf_free(&b);
    return ok ? OCEAN_OK : OCEAN_EIO;
}
