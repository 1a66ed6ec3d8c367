/*
 * srv_redis.c - the replicated sea-state timeline (see srv_redis.h).
 *
 * One connection, owned by the replication thread: it stores the queued
 * sets (XADD), reads the stream after the last entry it read, and answers
 * each stored set when it reads that set's entry back.  Stream entries
 * carry one field, "msg": the bytes of a SEA_STATE announce or of an
 * ENTITY announce or gone (PROTOCOL.md), so the stream holds exactly what
 * clients are sent.  Entity entries go straight into the hub's table
 * (srv_hub_entity_enter), in stream order, at start as while running: the
 * table is their fold.
 *
 * Reads are XRANGE of at most SRV_REDIS_BATCH entries after the last one
 * read, through srv_resp's bounded reader: an entry whose msg is over
 * SRV_REDIS_ENTRY_MAX bytes, or that is not one msg field, is read off the
 * socket and dropped, never held, whatever the stream holds.  Each read
 * starts at the entry last read: when it is no longer there (the stream
 * was deleted, recreated or trimmed past it), the timeline is read again
 * from the stream's start.  Redis builds a reply whole before its first
 * byte goes out: a batch of large entries on a loaded host can take longer
 * than a read waits for a byte, so after a read that failed the next asks
 * a quarter as many entries (down to one), and twice as many after each
 * read that did not.
 *
 * Anomalies (entries skipped, resets, far-future ids) are counted in the
 * hub's statistics and logged as one line of counts at most every
 * REPORT_EVERY_S: a stream full of garbage cannot flood the log.
 */
#include "srv_redis.h"

#include "srv_resp.h"

#include <errno.h>
#include <hiredis/hiredis.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <sys/time.h>
#include <time.h>
#include <unistd.h>

#define ID_MAX 48               /* "ms-seq": two 20-digit numbers and a dash */
#define READBACK_S 5.0          /* a stored set not read back by then is answered EIO */
#define REPORT_EVERY_S 10.0
#define START_IDLE_MAX_S 16.0  /* the longest a starting replica waits for a reply's next byte */
#define CATCH_UP_BATCHES 16     /* batches read before stored sets get a turn again */

/* A SEA_STATE set or an entity entry on its way through the stream. */
typedef struct set_req {
    struct set_req *next;
    const char *what;           /* "SEA_STATE set", "ENTITY set", ...: for its answers */
    srv_client *c;              /* one reference held; NULL: nobody to answer (a CIGI host) */
    uint8_t *bad;               /* the set's message, for the ERROR answering it */
    size_t badlen;
    proto_buf entry;            /* the announce to store */
    char id[ID_MAX];            /* its stream id once stored */
    double stored_at;           /* monotonic */
} set_req;

/* Counts since the last report line. */
typedef struct anomalies {
    uint64_t too_large, bad_shape, not_announce, refused, resets, future;
} anomalies;

/* One usable entry, decoded. */
typedef struct entry {
    double stored;              /* sim time Redis stored it, at most the clock */
    double effective;           /* as announced (an ENTITY's: its header sim_time) */
    int is_entity;
    proto_sea sea;
    ocean_params params;
    proto_entity entity;        /* an ENTITY announce or gone */
} entry;

/* The stream's timeline, entry times as every replica reads them (see
 * srv_redis.h), whatever the clock was when this replica read them. */
typedef struct fold {
    srv_sea_change now;                         /* the change in force */
    int have_now;
    srv_sea_change pending[SRV_SEA_PENDING_MAX];/* earliest first */
    int n;
} fold;

struct srv_redis {
    srv_hub *hub;
    char host[SRV_BIND_MAX];
    int port;
    char key[SRV_REDIS_KEY_MAX];
    double lead;                /* server.sea_lead, s */
    double poll_s;              /* between reads while idle */
    redisContext *rc;           /* [replication thread] */
    int lost_said;              /* [replication thread] this outage is logged */
    char last_id[ID_MAX];       /* [replication thread] last entry read */
    int count;                  /* [replication thread] entries the next read asks for */
    int asked;                  /* [replication thread] entries the last read asked for */
    double idle_s;              /* [replication thread] longest wait for a reply's next byte */
    fold timeline;              /* [replication thread] what the entries read so far make */
    ocean_params base;          /* [replication thread] the file's sea, what a change's sea completes;
                                   copied once a batch: the hub's lock is not taken per entry */
    /* [replication thread] what the last batch read while running gives the
     * hub once read: a new change in force (one, whatever the batch holds)
     * and the changes ahead */
    int batch_now;
    srv_sea_change batch_ahead[SRV_REDIS_BATCH];
    int n_batch_ahead;
    set_req *stored;            /* [replication thread] stored, not yet read back */
    anomalies seen;             /* [replication thread] */
    double said_at;             /* [replication thread] monotonic time of the last report */
    pthread_mutex_t lock;
    pthread_cond_t cond;        /* signalled when a set is queued or on stop */
    set_req *queue, *queue_tail;/* [lock] */
    int n_queue;                /* [lock] */
    int stop;                   /* [lock] */
    pthread_t thread;
    int running;
};

/* ---- sets ------------------------------------------------------------------------ */

static void set_free(set_req *q)
{
    srv_client_unref(q->c);
    free(q->bad);
    proto_buf_free(&q->entry);
    free(q);
}

/* Answers a set that will not be announced (code != OCEAN_OK: an ERROR)
 * and frees it.  OCEAN_OK: the announce was its answer. */
static void set_answer(srv_redis *r, set_req *q, ocean_result code, const char *why)
{
    if (code != OCEAN_OK && q->c) {
        char msg[700];
        /* the reasons shared by every kind of entry say whose they are */
        if (strncmp(why, q->what, strlen(q->what)) != 0) snprintf(msg, sizeof msg, "%s %s", q->what, why);
        else snprintf(msg, sizeof msg, "%s", why);
        srv_client_send_error(q->c, q->bad, q->badlen, code, msg);
        srv_hub_wake_net(r->hub);
    }
    set_free(q);
}

static void sets_answer_all(srv_redis *r, set_req **list, ocean_result code, const char *why)
{
    while (*list) {
        set_req *q = *list;
        *list = q->next;
        set_answer(r, q, code, why);
    }
}

/* ---- ids and the clock ---------------------------------------------------------- */

/* "ms-seq" into its two numbers; 0 if s is no stream id. */
static int id_parse(const char *s, uint64_t *ms, uint64_t *seq)
{
    char *end;
    if (!s || *s < '0' || *s > '9') return 0;
    *ms = strtoull(s, &end, 10);
    if (*end != '-' || end[1] < '0' || end[1] > '9') return 0;
    *seq = strtoull(end + 1, &end, 10);
    return *end == '\0';
}

static double unix_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- the connection --------------------------------------------------------------- */

static redisContext *connect_to(const srv_redis *r, char *msg, size_t msglen)
{
    struct timeval tv = {2, 0};
    redisContext *c = redisConnectWithTimeout(r->host, r->port, tv);
    if (!c || c->err) {
        snprintf(msg, msglen, "server.redis %s:%d: %s", r->host, r->port, c ? c->errstr : "out of memory");
        if (c) redisFree(c);
        return NULL;
    }
    /* a Redis that stops answering holds the replication thread 1 s per
     * command at most (a reply's bytes: idle_s, longer only while a replica
     * starts), and never any other thread */
    struct timeval io = {1, 0};
    redisSetTimeout(c, io);
    return c;
}

static void connection_drop(srv_redis *r, const char *why)
{
    if (!r->rc) return;
    fprintf(stderr, "oceand: redis %s:%d: %s; reconnecting\n", r->host, r->port, why);
    redisFree(r->rc);
    r->rc = NULL;
    atomic_store(&r->hub->stats.redis_connected, 0);
}

/* 1 when connected (again). */
static int connection_ensure(srv_redis *r)
{
    if (r->rc) return 1;
    char msg[200];
    r->rc = connect_to(r, msg, sizeof msg);
    if (!r->rc) {
        if (!r->lost_said)
            fprintf(stderr, "oceand: redis: cannot reconnect (%s); retrying every 0.2 s\n", msg);
        r->lost_said = 1;
        return 0;
    }
    /* an operator watching the log sees the outage end, and from where
     * the timeline is read again */
    fprintf(stderr, "oceand: redis %s:%d: reconnected; reading stream %s after entry %s\n", r->host, r->port,
            r->key, r->last_id);
    r->lost_said = 0;
    atomic_store(&r->hub->stats.redis_connected, 1);
    return 1;
}

/* ---- reading ----------------------------------------------------------------------- */

/* The msg of an entry's field list, if it is that one field and within
 * SRV_REDIS_ENTRY_MAX bytes; NULL (counted) otherwise. */
static const srv_resp *entry_msg(srv_redis *r, const srv_resp *fields)
{
    if (fields->type == SRV_RESP_ARRAY && fields->n == 2 && fields->elem[0].type == SRV_RESP_STRING &&
        strcmp(fields->elem[0].str, "msg") == 0) {
        if (fields->elem[1].type == SRV_RESP_STRING) return &fields->elem[1];
        if (fields->elem[1].type == SRV_RESP_SKIPPED) {
            r->seen.too_large++;
            return NULL;
        }
    }
    r->seen.bad_shape++;
    return NULL;
}

/* Decodes a stream entry (its id and field list) into *e; 0 (counted) when
 * it is not a usable change. */
static int entry_decode(srv_redis *r, const char *id, const srv_resp *fields, entry *e)
{
    srv_hub *h = r->hub;
    uint64_t ms, seq;
    if (!id_parse(id, &ms, &seq)) return 0;
    double stored_unix = (double)ms / 1e3;
    if (stored_unix > unix_now() + SRV_REDIS_FUTURE_S) {
        r->seen.future++;
        atomic_fetch_add(&h->stats.redis_future_ids, 1);
    }
    const srv_resp *v = entry_msg(r, fields);
    if (!v) return 0;
    proto_msg m;
    if (proto_decode((const uint8_t *)v->str, v->len, &m, NULL, 0) != OCEAN_OK) {
        r->seen.not_announce++;
        return 0;
    }
    e->stored = fmin(srv_hub_sim_time_at(h, stored_unix), srv_hub_sim_time(h));
    e->is_entity = m.hdr.type == PROTO_ENTITY;
    if (e->is_entity) {
        int ok = (m.u.entity.op == PROTO_ENTITY_ANNOUNCE || m.u.entity.op == PROTO_ENTITY_GONE) &&
                 ocean_time_ok(m.hdr.sim_time);
        e->entity = m.u.entity;
        e->effective = m.hdr.sim_time;
        proto_msg_free(&m);
        if (!ok) r->seen.not_announce++;
        return ok;
    }
    int ok = m.hdr.type == PROTO_SEA_STATE && m.u.sea_state.op == PROTO_SEA_ANNOUNCE &&
             ocean_time_ok(m.u.sea_state.effective_time);
    if (ok) {
        e->sea = m.u.sea_state.sea;
        e->effective = m.u.sea_state.effective_time;
        char msg[256];
        srv_params_from_sea(&e->sea, &r->base, &e->params);
        ok = ocean_params_validate(&e->params, msg, sizeof msg) == OCEAN_OK;
    }
    proto_msg_free(&m);
    if (!ok) r->seen.not_announce++;
    return ok;
}

/* What a reader does with each usable entry; returns OCEAN_OK when the
 * change entered the timeline, else why not. */
typedef ocean_result (*entry_use)(srv_redis *r, const entry *e, void *ctx, char *why, size_t whylen);

/* Answers the stored set whose entry this is, if any. */
static void stored_read_back(srv_redis *r, const char *id, ocean_result res, const char *why)
{
    for (set_req **p = &r->stored; *p; p = &(*p)->next)
        if (strcmp((*p)->id, id) == 0) {
            set_req *q = *p;
            *p = q->next;
            set_answer(r, q, res, why);
            return;
        }
}

/* One entry of a batch ([id, fields]): decoded, used, its set answered.
 * 0 when it is no entry (the reply is not XRANGE's). */
static int batch_entry(srv_redis *r, const srv_resp *item, entry_use use, void *ctx)
{
    srv_hub *h = r->hub;
    if (item->type != SRV_RESP_ARRAY || item->n != 2 || item->elem[0].type != SRV_RESP_STRING ||
        item->elem[0].len >= ID_MAX)
        return 0;
    const char *id = item->elem[0].str;
    snprintf(r->last_id, sizeof r->last_id, "%s", id);
    entry e;
    char why[600] = "refused: its stream entry cannot be read back";
    ocean_result res = OCEAN_EIO;
    if (entry_decode(r, id, &item->elem[1], &e)) {
        res = use(r, &e, ctx, why, sizeof why);
        if (res != OCEAN_OK) r->seen.refused++;
    }
    if (res == OCEAN_OK) atomic_fetch_add(&h->stats.redis_entries, 1);
    else atomic_fetch_add(&h->stats.redis_skipped, 1);
    stored_read_back(r, id, res, why);
    return 1;
}

/* XRANGE from the entry last read (included, to see that it is still
 * there) or from the start, read within bounds; NULL when the connection
 * failed. */
static srv_resp *range_read(srv_redis *r)
{
    /* ids, "msg" and the field lists of entries that are not one field
     * are kept whatever their number (each array at most a batch long);
     * only the msgs count against the bytes of a batch */
    const srv_resp_limits lim = {
        .max_string = SRV_REDIS_ENTRY_MAX,
        .max_total = (size_t)(SRV_REDIS_BATCH + 1) * (SRV_REDIS_ENTRY_MAX + 2 * ID_MAX),
        .max_array = SRV_REDIS_BATCH + 1,
        .max_nodes = (size_t)(SRV_REDIS_BATCH + 2) * (SRV_REDIS_BATCH + 6),
        .idle_s = r->idle_s,
    };
    int from_start = strcmp(r->last_id, "0-0") == 0;
    r->asked = r->count;
    int ok = from_start ? redisAppendCommand(r->rc, "XRANGE %s - + COUNT %d", r->key, r->asked)
                        : redisAppendCommand(r->rc, "XRANGE %s %s + COUNT %d", r->key, r->last_id, r->asked + 1);
    for (int done = 0; ok == REDIS_OK && !done;) ok = redisBufferWrite(r->rc, &done);
    srv_resp *rep = NULL;
    char why[200];
    if (ok != REDIS_OK || srv_resp_read(r->rc->fd, &lim, &rep, why, sizeof why) != OCEAN_OK) {
        if (ok == REDIS_OK) r->count = r->count > 4 ? r->count / 4 : 1;
        connection_drop(r, ok == REDIS_OK ? why : r->rc->errstr);
        return NULL;
    }
    r->count = r->count < SRV_REDIS_BATCH / 2 ? 2 * r->count : SRV_REDIS_BATCH;
    return rep;
}

/* The stream was deleted, recreated or trimmed past the entry last read:
 * a new timeline, read from the stream's start. */
static void stream_reset(srv_redis *r)
{
    memset(&r->timeline, 0, sizeof r->timeline);
    r->seen.resets++;
    atomic_fetch_add(&r->hub->stats.redis_resets, 1);
    snprintf(r->last_id, sizeof r->last_id, "0-0");
}

/* One bounded read after last_id.  Returns the entries read, -1 when the
 * connection failed; *reset 1 when the entry last read was gone (none read:
 * the next read starts at the stream's start).  A key that is no stream is
 * counted, and reads as empty. */
static int batch_read(srv_redis *r, entry_use use, void *ctx, int *reset)
{
    *reset = 0;
    int from_start = strcmp(r->last_id, "0-0") == 0;
    pthread_mutex_lock(&r->hub->lock);
    r->base = r->hub->file_params;
    pthread_mutex_unlock(&r->hub->lock);
    srv_resp *rep = range_read(r);
    if (!rep) return -1;
    int n = 0;
    if (rep->type == SRV_RESP_ARRAY) {
        size_t first = from_start ? 0 : 1;
        const srv_resp *head = rep->n ? &rep->elem[0] : NULL;
        if (!from_start && !(head && head->type == SRV_RESP_ARRAY && head->n == 2 &&
                             head->elem[0].type == SRV_RESP_STRING && strcmp(head->elem[0].str, r->last_id) == 0)) {
            *reset = 1;
            stream_reset(r);
            first = rep->n;
        }
        for (size_t i = first; i < rep->n && n >= 0; i++) n = batch_entry(r, &rep->elem[i], use, ctx) ? n + 1 : -1;
    } else {
        r->seen.refused++; /* an error (a key that is no stream), or no XRANGE reply */
    }
    srv_resp_free(rep);
    if (n < 0) connection_drop(r, "a reply that is no XRANGE");
    return n;
}

/* Logs the anomalies seen since the last line, at most every
 * REPORT_EVERY_S unless forced. */
static void anomalies_report(srv_redis *r, int force)
{
    anomalies *a = &r->seen;
    if (!(a->too_large | a->bad_shape | a->not_announce | a->refused | a->resets | a->future)) return;
    double now = srv_now();
    if (!force && r->said_at > 0 && now - r->said_at < REPORT_EVERY_S) return;
    fprintf(stderr, "oceand: redis stream %s: %" PRIu64 " entries over %d bytes, %" PRIu64 " not one msg "
            "field, %" PRIu64 " no valid SEA_STATE or ENTITY announce, %" PRIu64 " entries or reads refused, "
            "skipped; "
            "%" PRIu64 " resets (read again from the start), %" PRIu64 " ids over %g s ahead of the clock "
            "(counts since the last such line)\n", r->key, a->too_large, SRV_REDIS_ENTRY_MAX, a->bad_shape,
            a->not_announce, a->refused, a->resets, a->future, SRV_REDIS_FUTURE_S);
    memset(a, 0, sizeof *a);
    r->said_at = now;
}

/* ---- the timeline: every entry folded in stream order ------------------------------- */

static void fold_due(fold *f, double t)
{
    int k = 0;
    while (k < f->n && f->pending[k].effective_time <= t) k++;
    if (!k) return;
    f->now = f->pending[k - 1];
    f->have_now = 1;
    memmove(&f->pending[0], &f->pending[k], (size_t)(f->n - k) * sizeof f->pending[0]);
    f->n -= k;
}

/* An entity entry, into the hub's table in force from the later of its
 * time and the time Redis stored it, as every replica enters it. */
static ocean_result entity_entry(srv_redis *r, const entry *e, char *why, size_t whylen)
{
    proto_msg m;
    proto_msg_init(&m, PROTO_ENTITY);
    m.hdr.sim_time = fmax(e->effective, e->stored);
    m.u.entity = e->entity;
    char msg[400] = "";
    ocean_result res = srv_hub_entity_enter(r->hub, &m, msg, sizeof msg);
    if (res != OCEAN_OK)
        snprintf(why, whylen, "ENTITY %s refused: %s", e->entity.op == PROTO_ENTITY_GONE ? "remove" : "set",
                 msg[0] ? msg : ocean_strerror(res));
    return res;
}

/* An entry, as a replica reading it when Redis stored it enters it
 * (srv_hub_sea_schedule at that moment). */
static ocean_result fold_entry(srv_redis *r, const entry *e, void *ctx, char *why, size_t whylen)
{
    if (e->is_entity) return entity_entry(r, e, why, whylen);
    fold *f = ctx;
    fold_due(f, e->stored);
    double at = fmax(e->effective, e->stored);
    int k = 0;
    while (k < f->n && f->pending[k].effective_time < at) k++;
    int replace = k < f->n && f->pending[k].effective_time == at;
    if (!replace && f->n >= SRV_SEA_PENDING_MAX) {
        snprintf(why, whylen, "SEA_STATE set refused: %d changes are already pending", SRV_SEA_PENDING_MAX);
        return OCEAN_ERATE;
    }
    if (!replace) {
        memmove(&f->pending[k + 1], &f->pending[k], (size_t)(f->n - k) * sizeof f->pending[0]);
        f->n++;
    }
    f->pending[k].effective_time = at;
    f->pending[k].params = e->params;
    srv_sea_from_params(&e->params, &f->pending[k].sea);
    return OCEAN_OK;
}

/* The folded timeline becomes the hub's (no client yet). */
static void fold_install(srv_hub *h, fold *f)
{
    pthread_mutex_lock(&h->lock);
    fold_due(f, srv_hub_sim_time(h));
    if (f->have_now) {
        h->settings.params = f->now.params;
        h->sea_now = f->now.sea;
        h->sea_effective = f->now.effective_time;
    }
    for (int i = 0; i < f->n; i++)
        srv_hub_sea_schedule(h, &f->pending[i].params, f->pending[i].effective_time, 0, NULL, NULL, 0);
    pthread_mutex_unlock(&h->lock);
}

/* Reads the whole stream into the hub's timeline; 0, or -1 when Redis
 * failed.  A read that failed is tried again on a new connection, asking
 * a quarter as many entries, then, at one entry, waiting twice as long for
 * the reply up to START_IDLE_MAX_S: a replica that is starting serves
 * nobody yet, and a Redis starved of CPU (or still building the replies of
 * the reads abandoned before) answers late, not never. */
static int timeline_load(srv_redis *r, char *msg, size_t msglen)
{
    int n, reset;
    double t0 = srv_now(), said = t0;
    long long read = 0;
    for (;;) {
        while ((n = batch_read(r, fold_entry, &r->timeline, &reset)) == r->asked || reset) {
            read += n;
            /* a long stream on a slow Redis: the operator sees the start progress */
            if (srv_now() - said >= REPORT_EVERY_S) {
                said = srv_now();
                fprintf(stderr, "oceand: redis: reading stream %s before listening: %lld entries in %.0f s\n", r->key,
                        read, said - t0);
            }
        }
        if (n >= 0) break;
        if (r->asked <= 1) {
            if (r->idle_s >= START_IDLE_MAX_S) break;
            r->idle_s *= 2;
            fprintf(stderr, "oceand: redis: reading stream %s before listening: waiting up to %g s for a reply\n",
                    r->key, r->idle_s);
        }
        if (!(r->rc = connect_to(r, msg, msglen))) break;
    }
    r->idle_s = 1.0;
    if (n >= 0) fold_install(r->hub, &r->timeline);
    anomalies_report(r, 1);
    return n >= 0 ? 0 : -1;
}

/* ---- the timeline while running ----------------------------------------------------- */

/* An entry read as it comes: folded into the timeline as at start, and
 * noted for batch_sync. */
static ocean_result running_entry(srv_redis *r, const entry *e, void *ctx, char *why, size_t whylen)
{
    (void)ctx;
    ocean_result res = fold_entry(r, e, &r->timeline, why, whylen);
    if (res != OCEAN_OK || e->is_entity) return res;
    double at = fmax(e->effective, e->stored);
    if (at <= srv_hub_sim_time(r->hub)) {
        r->batch_now = 1;
    } else if (r->n_batch_ahead < SRV_REDIS_BATCH) {
        r->batch_ahead[r->n_batch_ahead].effective_time = at;
        r->batch_ahead[r->n_batch_ahead++].params = e->params;
    }
    return OCEAN_OK;
}

/* Gives the hub what a batch changed.  Entries already in force (read late:
 * a reconnect, a catch-up, a writer straight into Redis) make at most one
 * new change in force, the timeline's, entered at once: it supersedes the
 * due ones the simulation thread has not taken yet (taken here, so the
 * pending limit counts only changes ahead), and a burst of them costs the
 * simulation one new ocean, not one per entry.  Changes ahead are
 * scheduled at their times. */
static void batch_sync(srv_redis *r)
{
    srv_hub *h = r->hub;
    if (!r->batch_now && !r->n_batch_ahead) return;
    pthread_mutex_lock(&h->lock);
    double now = srv_hub_sim_time(h);
    fold_due(&r->timeline, now);
    if (r->batch_now && r->timeline.have_now) {
        srv_sea_change due;
        srv_hub_sea_take_due(h, now, &due);
        srv_hub_sea_schedule(h, &r->timeline.now.params, now, 0, NULL, NULL, 0);
    }
    for (int i = 0; i < r->n_batch_ahead; i++)
        if (srv_hub_sea_schedule(h, &r->batch_ahead[i].params, r->batch_ahead[i].effective_time, 0, NULL, NULL,
                                 0) != OCEAN_OK)
            r->seen.refused++;
    pthread_mutex_unlock(&h->lock);
    r->batch_now = 0;
    r->n_batch_ahead = 0;
    srv_hub_wake_net(h);
}

/* Reads what the stream gained (a failed read drops the connection). */
static void catch_up(srv_redis *r)
{
    for (int b = 0; b < CATCH_UP_BATCHES; b++) {
        int reset, n = batch_read(r, running_entry, NULL, &reset);
        batch_sync(r);
        if (n < 0 || (n < r->asked && !reset)) return;
    }
}

/* ---- storing sets ------------------------------------------------------------------- */

/* XADD of one set; its id into q->id.  A connection Redis closed (a
 * restart) is found dead only by the command that uses it: then reconnect
 * and send once more, so the set that meets the outage's end is stored, not
 * refused (a second copy would be harmless: replicas replace a change with
 * the same effective time).  A Redis that does not answer in time is not
 * asked twice: the set is answered EIO after one timeout. */
static int set_store(srv_redis *r, set_req *q, char *why, size_t whylen)
{
    redisReply *rep = NULL;
    int timed_out = 0;
    for (int attempt = 0; attempt < 2 && !rep && !timed_out; attempt++) {
        if (!r->rc && !connection_ensure(r)) break;
        rep = redisCommand(r->rc, "XADD %s * msg %b", r->key, proto_buf_data(&q->entry), q->entry.len);
        if (!rep) {
            timed_out = r->rc->err == REDIS_ERR_IO && (errno == EAGAIN || errno == EWOULDBLOCK);
            connection_drop(r, r->rc->errstr);
        }
    }
    int ok = rep && rep->type == REDIS_REPLY_STRING && rep->len < ID_MAX;
    if (ok) snprintf(q->id, sizeof q->id, "%s", rep->str);
    else
        snprintf(why, whylen, "%s not stored: Redis %s:%d %s", q->what, r->host, r->port,
                 rep && rep->type == REDIS_REPLY_ERROR ? rep->str : "unreachable or not answering");
    if (rep) freeReplyObject(rep);
    return ok;
}

/* The queued sets, taken off the queue. */
static set_req *queue_take(srv_redis *r)
{
    pthread_mutex_lock(&r->lock);
    set_req *q = r->queue;
    r->queue = r->queue_tail = NULL;
    r->n_queue = 0;
    pthread_mutex_unlock(&r->lock);
    return q;
}

/* Stores every queued set; the stored wait to be read back. */
static void sets_store(srv_redis *r)
{
    set_req *q = queue_take(r);
    while (q) {
        set_req *next = q->next;
        char why[400];
        if (set_store(r, q, why, sizeof why)) {
            q->stored_at = srv_now();
            q->next = r->stored;
            r->stored = q;
        } else {
            set_answer(r, q, OCEAN_EIO, why);
        }
        q = next;
    }
}

/* Answers the stored sets whose entries did not come back in time. */
static void sets_expire(srv_redis *r)
{
    double now = srv_now();
    for (set_req **p = &r->stored; *p;) {
        set_req *q = *p;
        if (now - q->stored_at < READBACK_S) {
            p = &q->next;
            continue;
        }
        *p = q->next;
        char why[300];
        snprintf(why, sizeof why, "%s stored in stream %s as %s but not read back within %g s (the stream "
                 "was reset or trimmed): not announced", q->what, r->key, q->id, READBACK_S);
        set_answer(r, q, OCEAN_EIO, why);
    }
}

/* ---- the replication thread ------------------------------------------------------- */

/* Waits up to secs for a queued set or the stop; 1 when stopping. */
static int thread_wait(srv_redis *r, double secs)
{
    pthread_mutex_lock(&r->lock);
    if (!r->stop && !r->queue) {
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        double t = (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec + secs;
        ts.tv_sec = (time_t)floor(t);
        ts.tv_nsec = (long)((t - floor(t)) * 1e9);
        pthread_cond_timedwait(&r->cond, &r->lock, &ts);
    }
    int stop = r->stop;
    pthread_mutex_unlock(&r->lock);
    return stop;
}

static void *replicate(void *arg)
{
    srv_redis *r = arg;
    /* reading a hostile stream is background work: the threads that serve
     * clients go first (Linux: a thread's nice value is its own) */
    if (setpriority(PRIO_PROCESS, (id_t)syscall(SYS_gettid), 10) != 0) {}
    while (!thread_wait(r, r->rc ? r->poll_s : 0.2)) {
        if (connection_ensure(r)) {
            sets_store(r);
            if (r->rc) catch_up(r);
        } else {
            char why[300];
            snprintf(why, sizeof why, "not stored: Redis %s:%d unreachable", r->host, r->port);
            set_req *q = queue_take(r);
            sets_answer_all(r, &q, OCEAN_EIO, why);
        }
        sets_expire(r);
        anomalies_report(r, 0);
    }
    return NULL;
}

/* ---- start, stop, submit ----------------------------------------------------------- */

static ocean_result address_parse(srv_redis *r, const char *addr, char *msg, size_t msglen)
{
    const char *colon = strrchr(addr, ':');
    if (!colon || colon == addr || (size_t)(colon - addr) >= sizeof r->host) {
        snprintf(msg, msglen, "server.redis '%s': expected host:port", addr);
        return OCEAN_EINVAL;
    }
    snprintf(r->host, sizeof r->host, "%.*s", (int)(colon - addr), addr);
    char *end;
    long port = strtol(colon + 1, &end, 10);
    if (*end || port < 1 || port > 65535) {
        snprintf(msg, msglen, "server.redis '%s': bad port", addr);
        return OCEAN_EINVAL;
    }
    r->port = (int)port;
    return OCEAN_OK;
}

ocean_result srv_redis_start(srv_hub *h, const srv_settings *s, srv_redis **out, char *msg, size_t msglen)
{
    *out = NULL;
    srv_redis *r = calloc(1, sizeof *r);
    if (!r) return OCEAN_ENOMEM;
    r->hub = h;
    pthread_mutex_init(&r->lock, NULL);
    pthread_cond_init(&r->cond, NULL);
    ocean_result res = address_parse(r, s->srv.redis, msg, msglen);
    if (res != OCEAN_OK) {
        srv_redis_stop(r);
        return res;
    }
    snprintf(r->key, sizeof r->key, "%s", s->srv.redis_stream);
    r->lead = s->srv.sea_lead;
    /* entries reach the replicas well inside the lead */
    r->poll_s = fmin(0.05, r->lead / 4);
    snprintf(r->last_id, sizeof r->last_id, "0-0");
    r->count = SRV_REDIS_BATCH;
    r->idle_s = 1.0;
    r->rc = connect_to(r, msg, msglen);
    if (r->rc && timeline_load(r, msg, msglen) != 0)
        snprintf(msg, msglen, "server.redis: reading the stream %s failed (the line before says why)", r->key);
    if (!r->rc) {
        srv_redis_stop(r);
        return OCEAN_EIO;
    }
    atomic_store(&h->stats.redis_connected, 1);
    if (pthread_create(&r->thread, NULL, replicate, r) != 0) {
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
    pthread_mutex_lock(&r->lock);
    r->stop = 1;
    pthread_cond_broadcast(&r->cond);
    pthread_mutex_unlock(&r->lock);
    if (r->running) pthread_join(r->thread, NULL);
    sets_answer_all(r, &r->queue, OCEAN_EIO, "not stored: the server is stopping");
    sets_answer_all(r, &r->stored, OCEAN_EIO, "not announced: the server is stopping");
    if (r->rc) redisFree(r->rc);
    pthread_cond_destroy(&r->cond);
    pthread_mutex_destroy(&r->lock);
    free(r);
}

/* Whether a change at effective time e would find the pending list full
 * (the replicas would skip its entry). */
static int pending_full(srv_hub *h, double e)
{
    pthread_mutex_lock(&h->lock);
    double now = srv_hub_sim_time(h);
    int ahead = 0, replace = 0;
    for (int i = 0; i < h->n_sea_pending; i++) {
        ahead += h->sea_pending[i].effective_time > now;
        replace |= h->sea_pending[i].effective_time == e;
    }
    pthread_mutex_unlock(&h->lock);
    return ahead >= SRV_SEA_PENDING_MAX && !replace;
}

/* A set request holding its entry m, encoded, and the client's message
 * (c may be NULL: nobody to answer). */
static set_req *set_new(srv_client *c, const void *bad, size_t badlen, const proto_msg *m, const char *what,
                        char *why, size_t whylen)
{
    set_req *q = calloc(1, sizeof *q);
    uint8_t *copy = malloc(badlen ? badlen : 1);
    if (!q || !copy) {
        free(q);
        free(copy);
        snprintf(why, whylen, "%s refused: out of memory", what);
        return NULL;
    }
    if (badlen) memcpy(copy, bad, badlen);
    q->bad = copy;
    q->badlen = badlen;
    q->what = what;
    proto_buf_init(&q->entry, 0);
    char err[200];
    if (proto_encode(&q->entry, m, err, sizeof err) != OCEAN_OK) {
        snprintf(why, whylen, "%s refused: %s", what, err);
        proto_buf_free(&q->entry);
        free(copy);
        free(q);
        return NULL;
    }
    if (c) srv_client_ref(c);
    q->c = c;
    return q;
}

/* Queues q for the replication thread, or frees it: OCEAN_ERATE when the
 * queue is full. */
static ocean_result queue_push(srv_redis *r, set_req *q, char *why, size_t whylen)
{
    pthread_mutex_lock(&r->lock);
    int full = r->n_queue >= SRV_REDIS_QUEUE_MAX;
    if (!full) {
        if (r->queue_tail) r->queue_tail->next = q;
        else r->queue = q;
        r->queue_tail = q;
        r->n_queue++;
        pthread_cond_signal(&r->cond);
    }
    pthread_mutex_unlock(&r->lock);
    if (!full) return OCEAN_OK;
    snprintf(why, whylen, "%s refused: %d entries already wait for Redis %s:%d", q->what, SRV_REDIS_QUEUE_MAX,
             r->host, r->port);
    set_free(q);
    return OCEAN_ERATE;
}

ocean_result srv_redis_submit(srv_redis *r, srv_client *c, const void *bad, size_t badlen, const proto_sea *sea,
                              double effective_time, char *why, size_t whylen)
{
    double now = srv_hub_sim_time(r->hub);
    if (!(effective_time >= now + r->lead)) {
        snprintf(why, whylen, "SEA_STATE set refused: effective_time %.3f is less than server.sea_lead (%g s) "
                 "ahead of the clock (%.3f): a replicated change must reach every replica before it takes "
                 "effect", effective_time, r->lead, now);
        return OCEAN_EINVAL;
    }
    if (pending_full(r->hub, effective_time)) {
        snprintf(why, whylen, "SEA_STATE set refused: %d changes are already pending (the most a server "
                 "holds); wait until one takes effect", SRV_SEA_PENDING_MAX);
        return OCEAN_ERATE;
    }
    proto_msg m;
    srv_sea_announce(sea, effective_time, now, &m);
    set_req *q = set_new(c, bad, badlen, &m, "SEA_STATE set", why, whylen);
    return q ? queue_push(r, q, why, whylen) : OCEAN_EINVAL;
}

ocean_result srv_redis_submit_entity(srv_redis *r, srv_client *c, const void *bad, size_t badlen, proto_msg *m,
                                     const char *what, char *why, size_t whylen)
{
    m->hdr.sim_time = fmax(m->hdr.sim_time, srv_hub_sim_time(r->hub) + r->lead);
    set_req *q = set_new(c, bad, badlen, m, what, why, whylen);
    return q ? queue_push(r, q, why, whylen) : OCEAN_ENOMEM;
}
