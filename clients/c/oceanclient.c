/*
 * oceanclient.c - the client library: libwebsockets connections, message
 * assembly, decoding into oc_frame, request/answer matching (queries, sea
 * state) and the caller-driven or threaded service loop.
 *
 * Locking: each oc_loop has one mutex `mu` guarding the loop's client list
 * and every field of its clients marked [mu] below.  The lws callback runs
 * on the servicing thread; it decodes without the lock (the rx buffer is
 * touched only by that thread), takes the lock to update state, and calls
 * user callbacks after releasing it.  `busy` counts callbacks in flight on
 * a client so that destroy waits for them.
 */
#include "oceanclient.h"

#include <errno.h>
#include <math.h>
#include <poll.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <libwebsockets.h>

#include "oc_held.h"
#include "oc_wakes.h"

#define CAM_RING 256
#define CLOSE_GRACE_MS 300

static double wall_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double mono_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ================================================================== URL */

/* The port digits [port_s, end) into out->port. */
static ocean_result url_port(const char *url, const char *port_s, const char *end, oc_url *out, char *err,
                             size_t errlen)
{
    size_t pl = (size_t)(end - port_s);
    long v = 0;
    if (pl == 0 || pl > 5) {
        ocean_seterr(err, errlen, "URL \"%.100s\": port must be a number 1..65535", url);
        return OCEAN_EINVAL;
    }
    for (size_t i = 0; i < pl; i++) {
        if (port_s[i] < '0' || port_s[i] > '9') {
            ocean_seterr(err, errlen, "URL \"%.100s\": port must be a number 1..65535", url);
            return OCEAN_EINVAL;
        }
        v = v * 10 + (port_s[i] - '0');
    }
    if (v < 1 || v > 65535) {
        ocean_seterr(err, errlen, "URL \"%.100s\": port %ld outside 1..65535", url, v);
        return OCEAN_EINVAL;
    }
    out->port = (int)v;
    return OCEAN_OK;
}

/* The authority [host, end) - a name, an address or a bracketed IPv6
 * address, then an optional ":port" - into out->host and out->port. */
static ocean_result url_authority(const char *url, const char *host, const char *end, oc_url *out, char *err,
                                  size_t errlen)
{
    if (memchr(host, '@', (size_t)(end - host))) {
        ocean_seterr(err, errlen, "URL \"%.100s\": user information (user@) is not supported", url);
        return OCEAN_EINVAL;
    }
    const char *host_end, *port_s = NULL;
    if (*host == '[') {
        const char *rb = memchr(host, ']', (size_t)(end - host));
        if (!rb) {
            ocean_seterr(err, errlen, "URL \"%.100s\": IPv6 address lacks its closing ']'", url);
            return OCEAN_EINVAL;
        }
        host++;
        host_end = rb;
        if (rb + 1 < end) {
            if (rb[1] != ':') {
                ocean_seterr(err, errlen, "URL \"%.100s\": unexpected text after ']'", url);
                return OCEAN_EINVAL;
            }
            port_s = rb + 2;
        }
    } else {
        const char *colon = memchr(host, ':', (size_t)(end - host));
        host_end = colon ? colon : end;
        if (colon)
            port_s = colon + 1;
    }
    size_t hl = (size_t)(host_end - host);
    if (hl == 0) {
        ocean_seterr(err, errlen, "URL \"%.100s\": empty host", url);
        return OCEAN_EINVAL;
    }
    if (hl > OC_HOST_MAX) {
        ocean_seterr(err, errlen, "URL \"%.100s\": host longer than %d bytes", url, OC_HOST_MAX);
        return OCEAN_EINVAL;
    }
    memcpy(out->host, host, hl);
    out->host[hl] = 0;
    return port_s ? url_port(url, port_s, end, out, err, errlen) : OCEAN_OK;
}

/* The path and query from `path` on ("/" if none; a bare "?query" gets
 * its "/") into out->path. */
static ocean_result url_path(const char *url, const char *path, oc_url *out, char *err, size_t errlen)
{
    if (!*path)
        path = "/";
    size_t plen = strlen(path), lead = *path == '?';
    if (plen + lead > OC_PATH_MAX) {
        ocean_seterr(err, errlen, "URL \"%.100s\": path longer than %d bytes", url, OC_PATH_MAX);
        return OCEAN_EINVAL;
    }
    out->path[0] = '/';
    memcpy(out->path + lead, path, plen + 1);
    return OCEAN_OK;
}

ocean_result oc_url_parse(const char *url, oc_url *out, char *err, size_t errlen)
{
    if (!url || !out) {
        ocean_seterr(err, errlen, "no URL given");
        return OCEAN_EINVAL;
    }
    memset(out, 0, sizeof *out);
    for (const unsigned char *p = (const unsigned char *)url; *p; p++)
        if (*p <= 0x20 || *p == 0x7f) {
            ocean_seterr(err, errlen, "URL \"%.100s\": contains a space or control character", url);
            return OCEAN_EINVAL;
        }
    const char *rest;
    if (!strncasecmp(url, "ws://", 5)) {
        rest = url + 5;
        out->port = 80;
    } else if (!strncasecmp(url, "wss://", 6)) {
        rest = url + 6;
        out->tls = 1;
        out->port = 443;
    } else {
        ocean_seterr(err, errlen, "URL \"%.100s\": scheme must be ws:// or wss://", url);
        return OCEAN_EINVAL;
    }
    if (strchr(url, '#')) {
        ocean_seterr(err, errlen, "URL \"%.100s\": fragments (#) are not allowed", url);
        return OCEAN_EINVAL;
    }
    /* the authority ends at the path or at the query */
    const char *slash = strchr(rest, '/');
    const char *auth_end = slash ? slash : rest + strlen(rest);
    const char *q = memchr(rest, '?', (size_t)(auth_end - rest));
    if (q)
        auth_end = q;
    ocean_result r = url_authority(url, rest, auth_end, out, err, errlen);
    return r != OCEAN_OK ? r : url_path(url, auth_end, out, err, errlen);
}

/* ============================================================ structures */

typedef struct txmsg {
    struct txmsg *next;
    proto_buf buf;           /* with LWS_PRE headroom */
    uint32_t seq;
    int live_camera;         /* a live-mode CAMERA: a newer one replaces it */
} txmsg;

typedef struct pending_query {
    struct pending_query *next;
    uint32_t id, seq;
    oc_query_fn fn;
    void *user;
    int blocking, done;
    ocean_result res;
    oc_query_result result;
} pending_query;

typedef struct topo_ref {
    oc_topology pub;
    atomic_int refs;
    proto_msg msg;
    uint32_t *qz_refs;        /* [const] MESH_VERTICES_QZ prediction references
                                 (layout-0 topologies), made when it arrived */
} topo_ref;

typedef struct frame_priv {
    oc_frame pub;
    proto_msg msg;
    uint8_t *raw;
    topo_ref *topo;
    float *mesh_pos;          /* has_mesh 2: the decoded positions
                                 (pub.info.mesh.positions points here) */
    int timed;                /* a frame of a time-interpolating stream: */
    proto_tile *blend_tiles;  /* the tiles of its instant (oc_held_blend)
                                 the view reads */
    float **blend_data;
    unsigned nblend;
} frame_priv;

struct oc_loop {
    struct lws_context *ctx;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    oc_client *clients;           /* [mu] */
    uint64_t events;              /* [mu] bumped on receipt / state change */
    pthread_t thread;
    int thread_running;           /* [mu] */
    atomic_int stop;
    lws_sorted_usec_list_t sul;   /* servicing thread only */
    int sul_fired;                /* servicing thread only */
    int destroying;
};

struct oc_client {
    oc_held *held;             /* time-interpolating stream: the samples held
                                  (receive thread), made at its first frame */
    oc_wakes *wakes;           /* [mu] the ships' entries and WAKE patterns received, made at the first */
    oc_loop *loop;
    int own_loop;
    oc_client *next;              /* [mu] loop's list */
    struct lws *wsi;              /* [mu] NULL once closed */
    oc_url url;
    oc_options opt;               /* url pointer cleared */
    char origin[256];
    oc_state state;               /* [mu] */
    int busy;                     /* [mu] user callbacks in flight */
    int connect_pending;          /* [mu] connect not yet issued */
    int close_req;                /* [mu] destroy asked the link to close */
    int kill_req;                 /* [mu] destroy gave up on a clean close */
    int want_write;               /* [mu] */
    /* rx assembly: servicing thread only */
    uint8_t *rx;
    size_t rx_len, rx_cap;
    int rx_skip;
    /* tx */
    txmsg *tx_head, *tx_tail;     /* [mu] */
    size_t tx_count, tx_bytes;    /* [mu] queued, not yet given to lws */
    int replay;                   /* [mu] the last SUBSCRIBE asked for replay */
    uint32_t seq;                 /* [mu] */
    double last_sim;              /* [mu] sim time of the latest message */
    double last_frame_sim;        /* [mu] of the latest FRAME (sent in our headers) */
    proto_hello hello;            /* [mu] */
    int have_hello;               /* [mu] */
    proto_sea sea;                /* [mu] */
    double sea_time;              /* [mu] */
    /* the sea-state timeline (PROTOCOL.md "Sea-state timeline"): HELLO's sea
     * from -inf, then each announce from its effective time [mu] */
    double tl_eff[OC_SEA_TIMELINE_MAX];
    proto_sea tl_sea[OC_SEA_TIMELINE_MAX];
    int tl_n;
    float frame_rate;             /* [mu] of the last SUBSCRIBE */
    /* frames [mu] */
    frame_priv **fq;
    int fq_len, fq_head, fq_cap;
    topo_ref *topo;
    uint64_t frame_index;
    uint32_t last_tick;
    int have_tick;
    double min_offset;
    int have_offset;
    struct { uint32_t seq; double wall; } cams[CAM_RING];
    unsigned cam_pos;
    /* requests [mu] */
    pending_query *queries;
    uint32_t next_query_id;
    int sea_wait;                 /* 1 a SET waits for its ANNOUNCE/ERROR, 2 a GET for
                                     the state in force (sea_got, sea_got_t) */
    proto_sea sea_got;
    double sea_got_t;
    proto_sea sea_want;           /* the SET in flight: its announce is the one */
    double sea_want_t;            /* with this sea at or after this time */
    uint32_t sea_seq;
    ocean_result sea_res;
    int sea_done;
    /* errors [mu] */
    ocean_result last_err;
    char last_err_msg[PROTO_ERROR_MSG_MAX + 64];
    int bye_reason;
    int closed_notified;
    int close_recorded;           /* [mu] last_err already says why it ended */
    int bye_received;             /* [mu] the server said BYE: */
    char bye_msg[PROTO_BYE_MSG_MAX + 1];        /* [mu] its message */
    char close_msg[PROTO_ERROR_MSG_MAX + 64];   /* [mu] and this is why */
    oc_client_stats st;           /* [mu] */
};

/* ============================================================== helpers */

static void topo_unref(topo_ref *t)
{
    if (t && atomic_fetch_sub(&t->refs, 1) == 1) {
        proto_msg_free(&t->msg);
        free(t->qz_refs);
        free(t);
    }
}

void oc_frame_free(oc_frame *f)
{
    if (!f)
        return;
    frame_priv *p = (frame_priv *)f;
    if (p->pub.tiles) {
        for (unsigned i = 0; p->pub.info.tiles && i < p->pub.info.tile_count; i++)
            free(p->pub.tiles[i].data);
        free(p->pub.tiles);
    }
    oc_cascade_view_free((oc_cascade_view *)p->pub.view);
    oc_held_blend_free(p->blend_tiles, p->blend_data, p->nblend);
    proto_msg_free(&p->msg);
    free(p->raw);
    free(p->mesh_pos);
    topo_unref(p->topo);
    free(p);
}

/* Decodes a has_mesh 2 frame's positions with refs (those of topology t)
 * into the frame: info.mesh.positions points at them afterwards. */
static ocean_result frame_mesh_qz(frame_priv *p, const oc_topology *t, const uint32_t *refs, char *err,
                                  size_t errlen)
{
    const proto_mesh_vertices *v = &p->pub.info.mesh;
    if (t->vertex_count != v->vertex_count || t->mesh_id != v->mesh_id) {
        ocean_seterr(err, errlen, "mesh qz: the frame's mesh %u has %u vertices, topology %u has %u", v->mesh_id,
                     v->vertex_count, t->mesh_id, t->vertex_count);
        return OCEAN_EINVAL;
    }
    float *pos = malloc(3 * sizeof *pos * (size_t)v->vertex_count);
    if (!pos)
        return OCEAN_ENOMEM;
    ocean_result r = proto_mesh_qz_decode(v->qz, v->qz_len, v->vertex_count, refs, pos, err, errlen);
    if (r != OCEAN_OK) {
        free(pos);
        return r;
    }
    free(p->mesh_pos);
    p->mesh_pos = pos;
    p->pub.info.mesh.positions = pos;
    return OCEAN_OK;
}

ocean_result oc_frame_mesh_decode(oc_frame *f, const oc_topology *t, char *err, size_t errlen)
{
    if (!f || !t || !t->indices) {
        ocean_seterr(err, errlen, "oc_frame_mesh_decode: NULL frame or topology");
        return OCEAN_EINVAL;
    }
    if (f->info.has_mesh != 2)
        return f->info.has_mesh && f->info.layout == PROTO_LAYOUT_WORLD ? OCEAN_OK : OCEAN_ESTATE;
    uint32_t *refs = malloc(3 * sizeof *refs * (size_t)t->vertex_count);
    if (!refs)
        return OCEAN_ENOMEM;
    ocean_result r = proto_mesh_qz_refs(t->indices, t->index_count, t->vertex_count, refs);
    if (r == OCEAN_OK)
        r = frame_mesh_qz((frame_priv *)f, t, refs, err, errlen);
    else
        ocean_seterr(err, errlen, "mesh qz: topology indices out of range");
    free(refs);
    return r;
}

void oc_query_result_free(oc_query_result *r)
{
    if (!r)
        return;
    free(r->samples);
    memset(r, 0, sizeof *r);
}

static void set_local_error(oc_client *c, ocean_result r, const char *fmt, ...)
{
    c->last_err = r;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(c->last_err_msg, sizeof c->last_err_msg, fmt, ap);
    va_end(ap);
}

/* set_local_error under the loop's lock; returns r.  For calls that fail
 * before they touch the connection: last_error describes the latest
 * failure, whatever it was. */
static ocean_result fail_local(oc_client *c, ocean_result r, const char *fmt, ...)
{
    char msg[sizeof c->last_err_msg];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    pthread_mutex_lock(&c->loop->mu);
    set_local_error(c, r, "%s", msg);
    pthread_mutex_unlock(&c->loop->mu);
    return r;
}

/* Encodes m with the client's next seq and queues it.  Caller holds mu. */
static ocean_result queue_msg_locked(oc_client *c, proto_msg *m, uint32_t *seq_out, char *err,
                                     size_t errlen)
{
    if (c->state == OC_CLOSED) {
        ocean_seterr(err, errlen, "the connection is closed (%s)", c->close_msg[0] ? c->close_msg : "closed");
        return OCEAN_EIO;
    }
    if (c->state != OC_READY || !c->wsi || c->close_req) {
        ocean_seterr(err, errlen, c->close_req ? "the client is being destroyed" : "not connected yet (no HELLO)");
        return OCEAN_ESTATE;
    }
    /* bounded: a caller that sends faster than the socket takes (or never
     * services a caller-driven loop) is told, instead of growing without
     * end; BYE still goes */
    if (m->hdr.type != PROTO_BYE && (c->tx_count >= OC_SEND_QUEUE_MAX || c->tx_bytes >= OC_SEND_QUEUE_MAX_BYTES)) {
        ocean_seterr(err, errlen,
                     "send queue full: %zu messages (%zu bytes) not yet written to the socket (limit %u messages, "
                     "%u bytes); service the loop and send less often",
                     c->tx_count, c->tx_bytes, OC_SEND_QUEUE_MAX, OC_SEND_QUEUE_MAX_BYTES);
        return OCEAN_ERATE;
    }
    txmsg *t = calloc(1, sizeof *t);
    if (!t)
        return OCEAN_ENOMEM;
    proto_buf_init(&t->buf, LWS_PRE);
    m->hdr.seq = c->seq;
    /* PROTOCOL.md: a client's header carries the sim time of the last
     * frame it received, 0 before any */
    m->hdr.sim_time = isfinite(c->last_frame_sim) ? c->last_frame_sim : 0.0;
    ocean_result r = proto_encode(&t->buf, m, err, errlen);
    if (r != OCEAN_OK) {
        proto_buf_free(&t->buf);
        free(t);
        return r;
    }
    if (seq_out)
        *seq_out = c->seq;
    t->seq = c->seq++;
    if (c->tx_tail)
        c->tx_tail->next = t;
    else
        c->tx_head = t;
    c->tx_tail = t;
    c->tx_count++;
    c->tx_bytes += proto_buf_len(&t->buf);
    c->want_write = 1;
    c->st.messages_tx++;
    c->st.bytes_tx += proto_buf_len(&t->buf);
    return OCEAN_OK;
}

static void wake(oc_loop *l)
{
    lws_cancel_service(l->ctx);
}

/* ===================================================== receive handling */

/* Deferred user notifications collected under the lock. */
typedef struct notify {
    const proto_msg *msg;
    int call_error, call_sea, call_entity, call_close, call_frame;
    frame_priv *frame;
    pending_query *q;              /* async query to answer */
    int close_reason;
    char close_msg[PROTO_BYE_MSG_MAX + 64];
} notify;

static int sea_same(const proto_sea *a, const proto_sea *b);

static void fail_pending_locked(oc_client *c, pending_query **async_list)
{
    pending_query **pp = &c->queries;
    while (*pp) {
        pending_query *q = *pp;
        if (q->blocking) {
            q->done = 1;
            q->res = OCEAN_EIO;
            pp = &q->next;
        } else {
            *pp = q->next;
            q->res = OCEAN_EIO;
            q->next = *async_list;
            *async_list = q;
        }
    }
    if (c->sea_wait && !c->sea_done) {
        c->sea_done = 1;
        c->sea_res = OCEAN_EIO;
    }
}

static void run_async_failures(oc_client *c, pending_query *list)
{
    while (list) {
        pending_query *n = list->next;
        if (list->fn)
            list->fn(list->user, c, list->res, NULL);
        free(list);
        list = n;
    }
}

/* Marks the client closed; caller holds mu.  Returns 1 if on_close should be
 * called (first time). */
static int mark_closed_locked(oc_client *c, int reason, const char *msg, pending_query **async)
{
    c->state = OC_CLOSED;
    c->wsi = NULL;
    fail_pending_locked(c, async);
    c->loop->events++;
    pthread_cond_broadcast(&c->loop->cv);
    /* the end of the connection is the latest failure, whatever came
     * before; a BYE or close frame received just before has said more */
    if (msg && !c->close_recorded) {
        set_local_error(c, OCEAN_EIO, "%s", msg);
        snprintf(c->close_msg, sizeof c->close_msg, "%s", msg);
        c->close_recorded = 1;
    }
    if (c->bye_reason < 0 || reason >= 0)
        c->bye_reason = reason;
    if (c->closed_notified)
        return 0;
    c->closed_notified = 1;
    return 1;
}

/* Moves decoded FRAME m into a new frame: decodes its tiles when
 * decode_tiles, then builds the layout-1 view.  A tile or view failure is
 * recorded in the frame (decode_result, view_result), not fatal.  NULL
 * only when out of memory (m and raw then still belong to the caller). */
/* The view of a frame of a time-interpolating stream: its records go into
 * the connection's store (held; NULL when the frame is decoded alone,
 * which only a KEY frame can be), and the view reads the blend of the
 * store's samples at the frame's instant. */
static void timed_view(frame_priv *f, oc_held *held)
{
    const proto_frame *info = &f->pub.info;
    oc_held *tmp = NULL;
    f->timed = 1;
    if (!held && !(info->cascades.flags & PROTO_CASCADE_KEY)) {
        f->pub.view_result = OCEAN_ESTATE;
        snprintf(f->pub.view_error, sizeof f->pub.view_error,
                 "a frame of a time-interpolating stream reads the samples of the frames before it: "
                 "decode it through its connection");
        return;
    }
    if (!held && oc_held_create(&tmp) != OCEAN_OK) {
        f->pub.view_result = OCEAN_ENOMEM;
        return;
    }
    held = held ? held : tmp;
    unsigned n = info->tile_count;
    const float **data = calloc(n ? n : 1, sizeof *data);
    ocean_result r = data ? OCEAN_OK : OCEAN_ENOMEM;
    for (unsigned i = 0; data && i < n; i++) data[i] = f->pub.tiles ? f->pub.tiles[i].data : NULL;
    if (r == OCEAN_OK)
        r = oc_held_apply(held, info, data, f->pub.view_error, sizeof f->pub.view_error);
    free(data);
    if (r == OCEAN_OK) r = oc_held_blend(held, info, &f->blend_tiles, &f->blend_data, &f->nblend);
    oc_held_destroy(tmp);
    if (r == OCEAN_OK && f->nblend > UINT16_MAX) r = OCEAN_ETOOBIG;
    if (r != OCEAN_OK) {
        f->pub.view_result = r;
        return;
    }
    proto_frame at = *info;
    at.tiles = f->blend_tiles;
    at.tile_count = (uint16_t)f->nblend;
    oc_cascade_view *v = NULL;
    f->pub.view_result = oc_cascade_view_build(&at, (const float *const *)f->blend_data, &v, f->pub.view_error,
                                               sizeof f->pub.view_error);
    f->pub.view = v;
}

static frame_priv *build_frame(int decode_tiles, oc_held *held, proto_msg *m, uint8_t *raw, size_t len,
                               double now)
{
    frame_priv *f = calloc(1, sizeof *f);
    if (!f)
        return NULL;
    f->msg = *m;
    f->raw = raw;
    f->pub.hdr = f->msg.hdr;
    f->pub.info = f->msg.u.frame;
    f->pub.raw = raw;
    f->pub.raw_len = len;
    f->pub.recv_wall = now;
    f->pub.camera_rtt_ms = -1;
    f->pub.view_result = OCEAN_ESTATE;
    unsigned n = f->pub.info.tile_count;
    if (n && f->pub.info.tiles) {
        f->pub.tiles = calloc(n, sizeof *f->pub.tiles);
        if (!f->pub.tiles) {
            free(f);
            return NULL;
        }
        for (unsigned i = 0; i < n; i++) {
            oc_tile *t = &f->pub.tiles[i];
            t->info = f->pub.info.tiles[i];
            t->planes = proto_tile_planes(t->info.channels);
            t->decode_result = OCEAN_OK;
            if (!decode_tiles)
                continue;
            size_t cnt = (size_t)t->planes * t->info.width * t->info.height;
            t->data = malloc(cnt * sizeof(float));
            if (!t->data) {
                t->decode_result = OCEAN_ENOMEM;
                continue;
            }
            ocean_result r = proto_tile_decode((proto_codec)t->info.codec, t->info.width,
                                               t->info.height, t->info.channels, t->info.payload,
                                               t->info.payload_len, t->data, NULL, 0);
            if (r != OCEAN_OK) {
                free(t->data);
                t->data = NULL;
                t->decode_result = r;
            }
        }
    }
    memset(m, 0, sizeof *m);
    snprintf(f->pub.view_error, sizeof f->pub.view_error, "%s",
             f->pub.info.layout != PROTO_LAYOUT_CASCADE ? "not a layout-1 frame"
             : !decode_tiles                          ? "tiles not decoded"
                                                      : "");
    if (decode_tiles && oc_held_frame_timed(&f->pub.info)) {
        timed_view(f, held);
    } else if (f->pub.info.layout == PROTO_LAYOUT_CASCADE && decode_tiles && f->pub.info.tiles) {
        const float **data = calloc(n ? n : 1, sizeof *data);
        oc_cascade_view *v = NULL;
        if (!data) {
            f->pub.view_result = OCEAN_ENOMEM;
        } else {
            for (unsigned i = 0; i < n; i++)
                data[i] = f->pub.tiles[i].data;
            f->pub.view_result = oc_cascade_view_build(&f->pub.info, data, &v, f->pub.view_error,
                                                       sizeof f->pub.view_error);
            free(data);
        }
        f->pub.view = v;
    } else if (f->pub.info.layout == PROTO_LAYOUT_CASCADE && decode_tiles && !n) {
        /* a frame with no tiles still has a (empty) view: every read is
         * then OCEAN_ENOTFOUND, which says what happened */
        oc_cascade_view *v = NULL;
        f->pub.view_result = oc_cascade_view_build(&f->pub.info, NULL, &v, f->pub.view_error,
                                                   sizeof f->pub.view_error);
        f->pub.view = v;
    }
    return f;
}

/* oc_frame_decode, or oc_frame_stream_decode with the stream's store
 * (held; NULL: the frame alone). */
static ocean_result frame_decode_held(oc_held *held, const uint8_t *msg, size_t len, oc_frame **out, char *err,
                                      size_t errlen)
{
    if (!out)
        return OCEAN_EINVAL;
    *out = NULL;
    if (!msg) {
        ocean_seterr(err, errlen, "no message");
        return OCEAN_EINVAL;
    }
    proto_msg m;
    ocean_result r = proto_decode(msg, len, &m, err, errlen);
    if (r != OCEAN_OK)
        return r;
    if (m.hdr.type != PROTO_FRAME) {
        ocean_seterr(err, errlen, "%s is not a FRAME", proto_type_name(m.hdr.type));
        proto_msg_free(&m);
        return OCEAN_ETYPE;
    }
    uint8_t *raw = malloc(len ? len : 1);
    if (!raw) {
        proto_msg_free(&m);
        return OCEAN_ENOMEM;
    }
    memcpy(raw, msg, len);
    frame_priv *f = build_frame(1, held, &m, raw, len, 0.0);
    if (!f) {
        proto_msg_free(&m);
        free(raw);
        return OCEAN_ENOMEM;
    }
    f->pub.latency_ms = -1;
    for (unsigned i = 0; f->pub.tiles && i < f->pub.info.tile_count; i++)
        if (f->pub.tiles[i].decode_result != OCEAN_OK) {
            r = f->pub.tiles[i].decode_result;
            ocean_seterr(err, errlen, "tile %u does not decode: %s", i, ocean_strerror(r));
            oc_frame_free(&f->pub);
            return r;
        }
    if (f->pub.info.layout == PROTO_LAYOUT_CASCADE && f->pub.view_result != OCEAN_OK) {
        r = f->pub.view_result;
        ocean_seterr(err, errlen, "layout-1 tiles: %s", f->pub.view_error);
        oc_frame_free(&f->pub);
        return r;
    }
    *out = &f->pub;
    return OCEAN_OK;
}

ocean_result oc_frame_decode(const uint8_t *msg, size_t len, oc_frame **out, char *err, size_t errlen)
{
    return frame_decode_held(NULL, msg, len, out, err, errlen);
}

struct oc_frame_stream {
    oc_held *held;
};

ocean_result oc_frame_stream_create(oc_frame_stream **out)
{
    if (!out)
        return OCEAN_EINVAL;
    *out = calloc(1, sizeof **out);
    if (!*out || oc_held_create(&(*out)->held) != OCEAN_OK) {
        free(*out);
        *out = NULL;
        return OCEAN_ENOMEM;
    }
    return OCEAN_OK;
}

void oc_frame_stream_destroy(oc_frame_stream *s)
{
    if (!s)
        return;
    oc_held_destroy(s->held);
    free(s);
}

ocean_result oc_frame_stream_decode(oc_frame_stream *s, const uint8_t *msg, size_t len, oc_frame **out, char *err,
                                    size_t errlen)
{
    if (!s) {
        if (out)
            *out = NULL;
        ocean_seterr(err, errlen, "no stream");
        return OCEAN_EINVAL;
    }
    return frame_decode_held(s->held, msg, len, out, err, errlen);
}

unsigned oc_frame_view_tile_count(const oc_frame *f)
{
    const frame_priv *p = (const frame_priv *)f;
    if (!f || !f->view)
        return 0;
    return p->timed ? p->nblend : f->info.tile_count;
}

ocean_result oc_frame_view_tile(const oc_frame *f, unsigned i, proto_tile *info, const float **data)
{
    const frame_priv *p = (const frame_priv *)f;
    if (!info || !data || i >= oc_frame_view_tile_count(f))
        return OCEAN_EINVAL;
    if (p->timed) {
        *info = p->blend_tiles[i];
        *data = p->blend_data[i];
    } else {
        *info = f->tiles[i].info;
        *data = f->tiles[i].data;
    }
    return OCEAN_OK;
}

ocean_result oc_frame_peek(const uint8_t *msg, size_t have, size_t len, proto_frame *f, size_t *records_at,
                           char *err, size_t errlen)
{
    memset(f, 0, sizeof *f);
    const size_t fixed = PROTO_HEADER_SIZE + 56;
    if (!msg || have > len || have < fixed) {
        ocean_seterr(err, errlen, "FRAME shorter than its 56 fixed bytes");
        return OCEAN_ETRUNC;
    }
    const uint8_t *p = msg + PROTO_HEADER_SIZE;
    proto_frame_fixed_read(p, f);
    if (isnan(f->cutoff_k) || f->cutoff_k < 0 || !(f->e_error >= 0 && f->e_error <= 1) || f->has_mesh > 2 ||
        (f->has_mesh == 2 && f->layout != PROTO_LAYOUT_WORLD) ||
        f->tile_count > PROTO_MAX_FRAME_TILES) {
        ocean_seterr(err, errlen, "FRAME fixed fields out of range");
        return OCEAN_EINVAL;
    }
    if (p[52] | p[53] | p[54] | p[55]) {
        ocean_seterr(err, errlen, "FRAME reserved bytes not 0");
        return OCEAN_EFORMAT;
    }
    size_t at = fixed;
    if (f->layout == PROTO_LAYOUT_CASCADE) {
        if (have < fixed + PROTO_CASCADE_BLOCK_FIXED) {
            ocean_seterr(err, errlen, "layout-1 FRAME shorter than its cascade block");
            return OCEAN_ETRUNC;
        }
        const uint8_t *b = p + 56;
        proto_cascade_block *k = &f->cascades;
        k->cascade_count = b[0];
        k->order = b[1];
        k->spacing_per_m = proto_ldf32(b + 4);
        for (int i = 0; i < 3; i++)
            k->camera[i] = proto_ldf64(b + 8 + 8 * i);
        k->min_spacing_m = proto_ldf32(b + 32);
        k->e_total = proto_ldf32(b + 36);
        for (int i = 0; i < 3; i++)
            k->tail_mss[i] = proto_ldf32(b + 40 + 4 * i);
        k->geometry_spacing_m = proto_ldf32(b + 52);
        int bad = k->cascade_count < 1 || k->cascade_count > PROTO_MAX_LAYERS || k->order < 1 || k->order > 64 ||
                  !(k->spacing_per_m > 0) || !isfinite(k->spacing_per_m) || !(k->min_spacing_m >= 0) ||
                  !isfinite(k->min_spacing_m) || !(k->e_total >= 0 && k->e_total <= 1) ||
                  !(k->tail_mss[0] >= 0) || !(k->tail_mss[1] >= 0) || !isfinite(k->tail_mss[0]) ||
                  !isfinite(k->tail_mss[1]) || !isfinite(k->tail_mss[2]) ||
                  !(k->geometry_spacing_m >= 0 && k->geometry_spacing_m <= 1e6f);
        for (int i = 0; i < 3; i++)
            bad |= !isfinite(k->camera[i]);
        if (bad) {
            ocean_seterr(err, errlen, "FRAME cascade block out of range");
            return OCEAN_EINVAL;
        }
        at += proto_cascade_block_bytes(k->cascade_count, b[2]);
    } else if (f->layout != PROTO_LAYOUT_WORLD) {
        ocean_seterr(err, errlen, "FRAME layout %u unknown", f->layout);
        return OCEAN_ETYPE;
    }
    /* each tile record is at least its 8-byte head and a TILE's 48 bytes; a
     * mesh record at least a placement (layout 1) or MESH_VERTICES' 32 */
    size_t need = at + (size_t)f->tile_count * (8 + 48) + (f->has_mesh ? 8 + 32 : 0);
    if (len < need) {
        ocean_seterr(err, errlen, "FRAME of %zu bytes cannot hold its %u tiles%s", len, f->tile_count,
                     f->has_mesh ? " and mesh" : "");
        return OCEAN_ETRUNC;
    }
    if (records_at)
        *records_at = at;
    return OCEAN_OK;
}

/* Header-only FRAME: proto_header_decode checks the 32-byte header, then
 * oc_frame_peek the fixed fields and a layout-1 cascade block's fixed part;
 * the records are not parsed. */
static ocean_result peek_frame(const uint8_t *raw, size_t len, const proto_limits *lim, proto_msg *m,
                               char *err, size_t errlen)
{
    memset(m, 0, sizeof *m);
    ocean_result r = proto_header_decode(raw, len, lim, &m->hdr, err, errlen);
    if (r != OCEAN_OK)
        return r;
    if (m->hdr.type != PROTO_FRAME)
        return OCEAN_ETYPE;
    r = oc_frame_peek(raw, len, len, &m->u.frame, NULL, err, errlen);
    if (r == OCEAN_OK && m->u.frame.tile_count > lim->max_frame_tiles) {
        snprintf(err, errlen, "FRAME tile_count %u above the limit", m->u.frame.tile_count);
        r = OCEAN_ETOOBIG;
    }
    return r;
}

static void timeline_add(oc_client *c, double eff, const proto_sea *sea);

/* One decoded server message, handled under the loop's lock by its type's
 * handler (rx_handlers). */
typedef struct rx_ctx {
    oc_client *c;
    proto_msg *m;
    frame_priv *fr;            /* FRAME: built from m (NULL: it did not build) */
    int peeked;                /* FRAME: fixed fields only (header_only) */
    double now, sim_time;
    ocean_result mesh_res;     /* FRAME has_mesh 2: its positions' decoding */
    const char *mesh_why;
    uint32_t **new_refs;       /* MESH_TOPOLOGY: its qz prediction references */
    wake_pattern *wake;        /* WAKE: its pattern, decoded before the lock (taken: NULL) */
    notify *nt;                /* what to tell the callbacks after the lock */
} rx_ctx;

static void rx_hello(rx_ctx *x)
{
    oc_client *c = x->c;
    c->hello = x->m->u.hello;
    c->have_hello = 1;
    c->sea = x->m->u.hello.sea;
    c->sea_time = x->m->hdr.sim_time;
    c->tl_n = 0;
    timeline_add(c, -INFINITY, &x->m->u.hello.sea);
    if (c->state == OC_CONNECTING)
        c->state = OC_READY;
}

/* Frames the server skipped between this one and the last (the tick
 * counter against the frame rate). */
static void rx_frame_gap(oc_client *c, const frame_priv *fr)
{
    if (c->have_tick && c->have_hello && c->frame_rate > 0) {
        uint32_t d = fr->pub.info.tick - c->last_tick;
        double step = c->hello.tick_rate_hz / c->frame_rate;
        if (step < 1)
            step = 1;
        step = floor(step + 0.5);
        double missed = floor((double)d / step + 0.5) - 1;
        if (missed > 0 && d < (1u << 30))
            c->st.frames_gap += (uint64_t)missed;
    }
    c->last_tick = fr->pub.info.tick;
    c->have_tick = 1;
}

/* The frame to the callback, or into the queue (the oldest dropped when full). */
static void rx_frame_deliver(oc_client *c, frame_priv *fr, notify *nt)
{
    if (c->opt.cb.on_frame) {
        nt->call_frame = 1;
        nt->frame = fr;
        return;
    }
    if (c->fq_len == c->fq_cap) {
        frame_priv *old = c->fq[c->fq_head];
        c->fq_head = (c->fq_head + 1) % c->fq_cap;
        c->fq_len--;
        c->st.frames_dropped++;
        oc_frame_free(&old->pub);
    }
    c->fq[(c->fq_head + c->fq_len) % c->fq_cap] = fr;
    c->fq_len++;
}

static void rx_frame(rx_ctx *x)
{
    oc_client *c = x->c;
    frame_priv *fr = x->fr;
    if (!fr) {
        c->st.decode_errors++;
        return;
    }
    c->last_frame_sim = x->sim_time;
    fr->pub.index = c->frame_index++;
    fr->pub.latency_ms = 1e3 * (x->now - fr->pub.hdr.sim_time - c->min_offset);
    for (unsigned i = 0; fr->pub.tiles && i < fr->pub.info.tile_count; i++)
        if (fr->pub.tiles[i].decode_result != OCEAN_OK)
            c->st.decode_errors++;
    if (!x->peeked && c->opt.decode_tiles && fr->pub.info.layout == PROTO_LAYOUT_CASCADE &&
        fr->pub.view_result != OCEAN_OK) {
        c->st.decode_errors++;
        set_local_error(c, fr->pub.view_result, "layout-1 FRAME tick %u: %s", fr->pub.info.tick,
                        fr->pub.view_error);
    }
    if (fr->pub.info.camera_seq != PROTO_NO_CAMERA)
        for (int i = 0; i < CAM_RING; i++)
            if (c->cams[i].wall > 0 && c->cams[i].seq == fr->pub.info.camera_seq) {
                fr->pub.camera_rtt_ms = 1e3 * (x->now - c->cams[i].wall);
                break;
            }
    rx_frame_gap(c, fr);
    c->st.frames_rx++;
    uint32_t mesh_id = fr->pub.info.layout == PROTO_LAYOUT_CASCADE ? fr->pub.info.placement.mesh_id
                                                                   : fr->pub.info.mesh.mesh_id;
    if (!x->peeked && fr->pub.info.has_mesh && c->topo && c->topo->pub.mesh_id == mesh_id) {
        fr->topo = c->topo;
        atomic_fetch_add(&c->topo->refs, 1);
        fr->pub.topology = &c->topo->pub;
    }
    if (x->mesh_res != OCEAN_OK) {
        c->st.decode_errors++;
        set_local_error(c, x->mesh_res, "FRAME tick %u: mesh positions: %s", fr->pub.info.tick, x->mesh_why);
    }
    rx_frame_deliver(c, fr, x->nt);
}

static void rx_topology(rx_ctx *x)
{
    oc_client *c = x->c;
    topo_ref *t = calloc(1, sizeof *t);
    if (!t) {
        c->st.decode_errors++;
        return;
    }
    atomic_init(&t->refs, 1);
    t->msg = *x->m;
    memset(x->m, 0, sizeof *x->m);
    const proto_mesh_topology *pt = &t->msg.u.topology;
    t->pub.mesh_id = pt->mesh_id;
    t->pub.mesh_kind = pt->mesh_kind;
    t->pub.lod_levels = pt->lod_levels;
    t->pub.vertex_count = pt->vertex_count;
    t->pub.index_count = pt->index_count;
    t->pub.indices = pt->indices;
    t->pub.morph = pt->morph;
    t->pub.level = pt->level;
    t->pub.flags = pt->flags;
    t->pub.flat = pt->flat;
    t->pub.zones = pt->zones;
    t->qz_refs = *x->new_refs;
    *x->new_refs = NULL;
    topo_unref(c->topo);
    c->topo = t;
}

/* The pending query that `matches` names done with res (and, for an
 * asynchronous one, out of the list, to be answered after the lock). */
static pending_query *query_done(oc_client *c, uint32_t id, uint32_t seq, int by_seq, notify *nt)
{
    for (pending_query **pp = &c->queries; *pp; pp = &(*pp)->next) {
        pending_query *q = *pp;
        if ((by_seq ? q->seq != seq : q->id != id) || q->done)
            continue;
        q->done = 1;
        if (!q->blocking) {
            *pp = q->next;
            nt->q = q;
        }
        return q;
    }
    return NULL;
}

static void rx_query_result(rx_ctx *x)
{
    const proto_query_result *qr = &x->m->u.result;
    pending_query *q = query_done(x->c, qr->query_id, 0, 0, x->nt);
    if (!q)
        return;
    q->result.query_id = qr->query_id;
    q->result.t = qr->t;
    q->result.count = qr->count;
    q->result.samples = malloc(sizeof *qr->samples * (qr->count ? qr->count : 1));
    if (!q->result.samples) {
        q->res = OCEAN_ENOMEM;
        q->result.count = 0;
    } else {
        memcpy(q->result.samples, qr->samples, sizeof *qr->samples * qr->count);
        q->res = OCEAN_OK;
    }
}

static void rx_sea_state(rx_ctx *x)
{
    oc_client *c = x->c;
    const proto_sea_state *ss = &x->m->u.sea_state;
    if (ss->op != PROTO_SEA_ANNOUNCE)
        return;
    c->sea = ss->sea;
    c->sea_time = ss->effective_time;
    timeline_add(c, ss->effective_time, &ss->sea);
    /* Every client sees every admin's announces: only the one of this
     * client's own SET answers it (its sea, entered at max(requested,
     * now), PROTOCOL.md SEA_STATE). */
    if (c->sea_wait == 1 && !c->sea_done && sea_same(&ss->sea, &c->sea_want) && ss->effective_time >= c->sea_want_t) {
        c->sea_done = 1;
        c->sea_res = OCEAN_OK;
    }
    /* a GET's answer opens with the state in force, effective no later
     * than the answer was sent; a pending change's lies ahead of it */
    if (c->sea_wait == 2 && !c->sea_done && ss->effective_time <= x->m->hdr.sim_time) {
        c->sea_got = ss->sea;
        c->sea_got_t = ss->effective_time;
        c->sea_done = 1;
        c->sea_res = OCEAN_OK;
    }
    x->nt->call_sea = 1;
}

static void rx_entity(rx_ctx *x)
{
    oc_client *c = x->c;
    if ((c->wakes || oc_wakes_create(&c->wakes) == OCEAN_OK) && oc_wakes_entity(c->wakes, x->m) != OCEAN_OK)
        c->st.entity_refused++;
    x->nt->call_entity = 1;
}

static void rx_wake(rx_ctx *x)
{
    oc_client *c = x->c;
    if (x->wake && (c->wakes || oc_wakes_create(&c->wakes) == OCEAN_OK)) {
        oc_wakes_keep(c->wakes, x->wake);
        x->wake = NULL;
        c->st.wakes_rx++;
        return;
    }
    c->st.wakes_refused++;
}

static void rx_error(rx_ctx *x)
{
    oc_client *c = x->c;
    const proto_error *e = &x->m->u.error;
    c->st.errors_rx++;
    c->last_err = e->code < OCEAN_RESULT_COUNT_ && e->code ? (ocean_result)e->code : OCEAN_EINVAL;
    snprintf(c->last_err_msg, sizeof c->last_err_msg, "server ERROR %u (%s) about %s seq %u: %s", e->code,
             ocean_strerror((ocean_result)e->code), proto_type_name(e->offending_type), e->offending_seq,
             e->message);
    if (e->offending_type == PROTO_QUERY) {
        pending_query *q = query_done(c, 0, e->offending_seq, 1, x->nt);
        if (q)
            q->res = c->last_err;
    }
    if (e->offending_type == PROTO_SEA_STATE && c->sea_wait && !c->sea_done && e->offending_seq == c->sea_seq) {
        c->sea_done = 1;
        c->sea_res = c->last_err;
    }
    x->nt->call_error = 1;
}

static void rx_bye(rx_ctx *x)
{
    oc_client *c = x->c;
    const proto_bye *b = &x->m->u.bye;
    c->bye_reason = b->reason;
    snprintf(x->nt->close_msg, sizeof x->nt->close_msg, "%s", b->message);
    set_local_error(c, OCEAN_EIO, "server said BYE (reason %u): %s", b->reason, b->message);
    snprintf(c->close_msg, sizeof c->close_msg, "%s", c->last_err_msg);
    c->close_recorded = 1;
    c->bye_received = 1;
    snprintf(c->bye_msg, sizeof c->bye_msg, "%s", b->message);
}

/* What the client does with each server message (the others are ignored). */
static const struct {
    unsigned type;
    void (*handle)(rx_ctx *x);
} rx_handlers[] = {
    {PROTO_HELLO, rx_hello},         {PROTO_FRAME, rx_frame}, {PROTO_MESH_TOPOLOGY, rx_topology},
    {PROTO_QUERY_RESULT, rx_query_result}, {PROTO_SEA_STATE, rx_sea_state}, {PROTO_ERROR, rx_error},
    {PROTO_BYE, rx_bye},             {PROTO_ENTITY, rx_entity}, {PROTO_WAKE, rx_wake},
};

/* MESH_VERTICES_QZ work done outside the loop's lock: a layout-0
 * topology's prediction references, made once when it arrives
 * (*new_refs); a has_mesh 2 frame's positions, decoded with the current
 * topology (held by a reference meanwhile), so callers see floats. */
static ocean_result rx_mesh_work(oc_client *c, const proto_msg *m, unsigned type, frame_priv *fr, int peeked,
                                 uint32_t **new_refs, char *why, size_t whylen)
{
    if (type == PROTO_MESH_TOPOLOGY && !(m->u.topology.flags & PROTO_TOPO_FLAT)) {
        const proto_mesh_topology *pt = &m->u.topology;
        *new_refs = malloc(3 * sizeof **new_refs * (size_t)pt->vertex_count);
        if (*new_refs && proto_mesh_qz_refs(pt->indices, pt->index_count, pt->vertex_count, *new_refs) != OCEAN_OK) {
            free(*new_refs);
            *new_refs = NULL;
        }
    }
    if (!fr || peeked || fr->pub.info.has_mesh != 2)
        return OCEAN_OK;
    oc_loop *l = c->loop;
    pthread_mutex_lock(&l->mu);
    topo_ref *tr = c->topo && c->topo->pub.mesh_id == fr->pub.info.mesh.mesh_id ? c->topo : NULL;
    if (tr)
        atomic_fetch_add(&tr->refs, 1);
    pthread_mutex_unlock(&l->mu);
    ocean_result r = OCEAN_ESTATE;
    snprintf(why, whylen, "no MESH_TOPOLOGY for the frame's mesh %u", fr->pub.info.mesh.mesh_id);
    if (tr && tr->qz_refs)
        r = frame_mesh_qz(fr, &tr->pub, tr->qz_refs, why, whylen);
    topo_unref(tr);
    return r;
}

/* The callbacks a message calls for, after the loop's lock. */
static void rx_notify(oc_client *c, ocean_result res, const proto_msg *m, notify *nt)
{
    if (res == OCEAN_OK) {
        if (nt->call_error && c->opt.cb.on_error)
            c->opt.cb.on_error(c->opt.cb.user, c, &m->u.error);
        if (nt->call_sea && c->opt.cb.on_sea_state)
            c->opt.cb.on_sea_state(c->opt.cb.user, c, &m->u.sea_state);
        if (nt->call_entity && c->opt.cb.on_entity)
            c->opt.cb.on_entity(c->opt.cb.user, c, &m->u.entity);
    }
    if (nt->call_frame) {
        c->opt.cb.on_frame(c->opt.cb.user, c, &nt->frame->pub);
        oc_frame_free(&nt->frame->pub);
    }
    if (nt->q) {
        if (nt->q->fn)
            nt->q->fn(nt->q->user, c, nt->q->res, nt->q->res == OCEAN_OK ? &nt->q->result : NULL);
        oc_query_result_free(&nt->q->result);
        free(nt->q);
    }
}

static void handle_message(oc_client *c, uint8_t *raw, size_t len)
{
    oc_loop *l = c->loop;
    double now = wall_now();
    proto_limits lim;
    proto_limits_default(&lim);
    lim.max_message = c->opt.max_message;
    proto_msg m;
    char err[256];
    ocean_result res;
    int peeked = 0;
    if (c->opt.header_only && len >= 8 && proto_ld16(raw + 6) == PROTO_FRAME) {
        res = peek_frame(raw, len, &lim, &m, err, sizeof err);
        peeked = 1;
    } else {
        res = proto_decode_limited(raw, len, &lim, &m, err, sizeof err);
    }
    pthread_mutex_lock(&l->mu);
    c->busy++;
    pthread_mutex_unlock(&l->mu);
    if (c->opt.cb.on_message)
        c->opt.cb.on_message(c->opt.cb.user, c, raw, len, res == OCEAN_OK ? &m : NULL, res);

    notify nt;
    memset(&nt, 0, sizeof nt);
    frame_priv *fr = NULL;
    unsigned type = res == OCEAN_OK ? m.hdr.type : 0;
    double sim_time = m.hdr.sim_time;
    if (type == PROTO_FRAME) {
        if (c->opt.decode_tiles && !peeked && !c->held && oc_held_frame_timed(&m.u.frame))
            oc_held_create(&c->held);
        fr = build_frame(c->opt.decode_tiles && !peeked, c->held, &m, raw, len, now);   /* moves m into the frame */
    }
    int raw_taken = fr != NULL;
    uint32_t *new_refs = NULL;
    char mesh_why[200] = "";
    ocean_result mesh_res = rx_mesh_work(c, &m, type, fr, peeked, &new_refs, mesh_why, sizeof mesh_why);
    wake_pattern *wake = type == PROTO_WAKE ? oc_wakes_decode(&m.u.wake) : NULL;

    pthread_mutex_lock(&l->mu);
    c->st.messages_rx++;
    c->st.bytes_rx += len;
    l->events++;
    if (res != OCEAN_OK) {
        c->st.decode_errors++;
        set_local_error(c, res, "undecodable message from server: %s", err);
    } else {
        /* every message's header says the server's clock but an ENTITY's
         * (the instant its entry takes effect) and a WAKE's (0) */
        if (type != PROTO_ENTITY && type != PROTO_WAKE) {
            double off = now - sim_time;
            if (!c->have_offset || off < c->min_offset) {
                c->min_offset = off;
                c->have_offset = 1;
            }
            c->last_sim = sim_time;
        }
        rx_ctx x = {.c = c, .m = &m, .fr = fr, .peeked = peeked, .now = now, .sim_time = sim_time,
                    .mesh_res = mesh_res, .mesh_why = mesh_why, .new_refs = &new_refs, .wake = wake, .nt = &nt};
        for (size_t k = 0; k < sizeof rx_handlers / sizeof rx_handlers[0]; k++)
            if (rx_handlers[k].type == type)
                rx_handlers[k].handle(&x);
        wake = x.wake;
    }
    pthread_cond_broadcast(&l->cv);
    pthread_mutex_unlock(&l->mu);
    free(new_refs);   /* not taken: the topology could not be kept */
    wake_pattern_destroy(wake);
    rx_notify(c, res, &m, &nt);
    proto_msg_free(&m);
    if (!raw_taken)
        free(raw);

    pthread_mutex_lock(&l->mu);
    c->busy--;
    pthread_cond_broadcast(&l->cv);
    pthread_mutex_unlock(&l->mu);
}

static void notify_closed(oc_client *c, int reason, const char *msg)
{
    oc_loop *l = c->loop;
    pending_query *async = NULL;
    pthread_mutex_lock(&l->mu);
    int call = mark_closed_locked(c, reason, msg, &async);
    int r = c->bye_reason;
    /* after a BYE, on_close gets its message (the header's contract), not
     * the transport's "connection closed" that follows it */
    char why[sizeof c->close_msg];
    snprintf(why, sizeof why, "%s", c->bye_received ? c->bye_msg : msg ? msg : "");
    c->busy++;
    pthread_mutex_unlock(&l->mu);
    run_async_failures(c, async);
    if (call && c->opt.cb.on_close)
        c->opt.cb.on_close(c->opt.cb.user, c, r, why);
    pthread_mutex_lock(&l->mu);
    c->busy--;
    pthread_cond_broadcast(&l->cv);
    pthread_mutex_unlock(&l->mu);
}

/* ===================================================== lws callback */

/* Issues the connects oc_client_create queued; servicing thread only,
 * called without mu (lws may call back synchronously). */
static void do_connects(oc_loop *l)
{
    for (;;) {
        oc_client *c = NULL;
        pthread_mutex_lock(&l->mu);
        for (oc_client *k = l->clients; k; k = k->next)
            if (k->connect_pending) {
                c = k;
                break;
            }
        if (c) {
            c->connect_pending = 0;
            c->busy++;
        }
        pthread_mutex_unlock(&l->mu);
        if (!c)
            return;
        struct lws_client_connect_info ci;
        memset(&ci, 0, sizeof ci);
        ci.context = l->ctx;
        ci.address = c->url.host;
        ci.port = c->url.port;
        ci.ssl_connection = c->url.tls ? LCCSCF_USE_SSL : 0;
        ci.path = c->url.path;
        ci.host = c->url.host;
        ci.origin = c->opt.origin;
        ci.protocol = PROTO_SUBPROTOCOL;
        ci.ietf_version_or_minus_one = -1;
        ci.userdata = c;
        ci.local_protocol_name = PROTO_SUBPROTOCOL;
        struct lws *w = lws_client_connect_via_info(&ci);
        pthread_mutex_lock(&l->mu);
        if (w && c->state != OC_CLOSED && !c->wsi)
            c->wsi = w;
        int failed = !w && c->state != OC_CLOSED;
        c->busy--;
        pthread_cond_broadcast(&l->cv);
        pthread_mutex_unlock(&l->mu);
        if (failed) {
            char msg[300];
            snprintf(msg, sizeof msg, "cannot connect to %s:%d (libwebsockets refused)", c->url.host,
                     c->url.port);
            notify_closed(c, -1, msg);
        }
    }
}

/* The loop was woken: connections to open, writes and kills to ask of lws. */
static void on_loop_wake(oc_loop *l)
{
    if (!l || l->destroying)
        return;
    do_connects(l);
    pthread_mutex_lock(&l->mu);
    for (oc_client *k = l->clients; k; k = k->next) {
        if (!k->wsi)
            continue;
        if (k->kill_req)
            lws_set_timeout(k->wsi, PENDING_TIMEOUT_CLOSE_SEND, LWS_TO_KILL_ASYNC);
        else if (k->want_write || k->close_req)
            lws_callback_on_writable(k->wsi);
    }
    pthread_mutex_unlock(&l->mu);
}

/* The server's close frame: its code and text become the reason, unless a
 * BYE gave one first. */
static void on_peer_close(oc_client *c, oc_loop *l, const void *in, size_t len)
{
    if (!c || len < 2)
        return;
    const uint8_t *p = in;
    unsigned code = (unsigned)p[0] << 8 | p[1];
    pthread_mutex_lock(&l->mu);
    if (!c->close_recorded) {
        set_local_error(c, OCEAN_EIO, "server closed the connection (code %u: %.*s)", code,
                        (int)(len - 2 > 200 ? 200 : len - 2), (const char *)p + 2);
        snprintf(c->close_msg, sizeof c->close_msg, "%s", c->last_err_msg);
        c->close_recorded = 1;
    }
    pthread_mutex_unlock(&l->mu);
}

/* Bytes of a server message into c->rx; a message over max_message is
 * skipped (said once).  0 when memory ran out: this fragment is dropped
 * with the message. */
static int rx_take(oc_client *c, oc_loop *l, struct lws *wsi, const void *in, size_t len)
{
    if (!c->rx_skip && lws_is_first_fragment(wsi) && c->rx_len == 0) {
        /* size the buffer once for the whole WebSocket frame (the daemon
         * sends each message as one), instead of doubling */
        size_t want = len + lws_remaining_packet_payload(wsi);
        if (want > c->rx_cap && want <= c->opt.max_message) {
            free(c->rx);
            c->rx = malloc(want);
            c->rx_cap = c->rx ? want : 0;
        }
    }
    if (c->rx_skip)
        return 1;
    if (c->rx_len + len > c->opt.max_message) {
        c->rx_skip = 1;
        c->rx_len = 0;
        pthread_mutex_lock(&l->mu);
        c->st.decode_errors++;
        set_local_error(c, OCEAN_ETOOBIG, "server message longer than max_message %u", c->opt.max_message);
        pthread_mutex_unlock(&l->mu);
        return 1;
    }
    if (c->rx_len + len > c->rx_cap) {
        size_t nc = c->rx_cap ? c->rx_cap : 65536;
        while (nc < c->rx_len + len)
            nc *= 2;
        uint8_t *nb = realloc(c->rx, nc);
        if (!nb) {
            c->rx_skip = 1;
            c->rx_len = 0;
            return 0;
        }
        c->rx = nb;
        c->rx_cap = nc;
    }
    memcpy(c->rx + c->rx_len, in, len);
    c->rx_len += len;
    return 1;
}

static void on_receive(oc_client *c, oc_loop *l, struct lws *wsi, const void *in, size_t len)
{
    if (!c)
        return;
    int final = lws_is_final_fragment(wsi) && lws_remaining_packet_payload(wsi) == 0;
    if (lws_is_first_fragment(wsi) && c->rx_len == 0)
        c->rx_skip = 0;
    if (!rx_take(c, l, wsi, in, len) || !final)
        return;
    if (!c->rx_skip && c->rx_len) {
        /* hand the buffer over; a fresh one is grown on demand */
        uint8_t *msg = c->rx;
        size_t mlen = c->rx_len;
        c->rx = NULL;
        c->rx_cap = 0;
        c->rx_len = 0;
        handle_message(c, msg, mlen);
    }
    c->rx_len = 0;
    c->rx_skip = 0;
}

/* The next queued message to the socket, or the close after the last. */
static int on_writeable(oc_client *c, oc_loop *l, struct lws *wsi)
{
    if (!c)
        return 0;
    pthread_mutex_lock(&l->mu);
    txmsg *t = c->tx_head;
    if (t) {
        c->tx_head = t->next;
        if (!c->tx_head)
            c->tx_tail = NULL;
        c->tx_count--;
        c->tx_bytes -= proto_buf_len(&t->buf);
    }
    int more = c->tx_head != NULL;
    c->want_write = more;
    int closing = c->close_req && !more && !t;
    pthread_mutex_unlock(&l->mu);
    if (closing) {
        lws_close_reason(wsi, LWS_CLOSE_STATUS_NORMAL, (unsigned char *)"bye", 3);
        return -1;
    }
    if (!t)
        return 0;
    size_t n = proto_buf_len(&t->buf);
    int w = lws_write(wsi, proto_buf_data(&t->buf), n, LWS_WRITE_BINARY);
    proto_buf_free(&t->buf);
    free(t);
    if (w < (int)n)
        return -1;
    pthread_mutex_lock(&l->mu);
    int again = c->tx_head != NULL || c->close_req;
    pthread_mutex_unlock(&l->mu);
    if (again)
        lws_callback_on_writable(wsi);
    return 0;
}

static int lws_cb(struct lws *wsi, enum lws_callback_reasons reason, void *user, void *in, size_t len)
{
    oc_client *c = (oc_client *)user;
    struct lws_context *ctx = lws_get_context(wsi);
    oc_loop *l = ctx ? lws_context_user(ctx) : NULL;

    switch (reason) {
    case LWS_CALLBACK_EVENT_WAIT_CANCELLED:
        on_loop_wake(l);
        break;
    case LWS_CALLBACK_CLIENT_ESTABLISHED:
        if (!c)
            break;
        pthread_mutex_lock(&l->mu);
        l->events++;
        c->wsi = wsi;
        if (c->want_write || c->close_req)
            lws_callback_on_writable(wsi);
        pthread_cond_broadcast(&l->cv);
        pthread_mutex_unlock(&l->mu);
        break;
    case LWS_CALLBACK_CLIENT_CONNECTION_ERROR: {
        if (!c)
            break;
        char msg[300];
        snprintf(msg, sizeof msg, "connection to %s:%d failed: %s", c->url.host, c->url.port,
                 in ? (const char *)in : "unknown reason");
        /* c may be freed once it is marked closed (oc_client_destroy waits
         * for that): the wsi's later callbacks (WSI_DESTROY) must not see it */
        lws_set_wsi_user(wsi, NULL);
        notify_closed(c, -1, msg);
        break;
    }
    case LWS_CALLBACK_WS_PEER_INITIATED_CLOSE:
        on_peer_close(c, l, in, len);
        break;
    case LWS_CALLBACK_CLIENT_CLOSED:
        if (c) {
            lws_set_wsi_user(wsi, NULL); /* as above: WSI_DESTROY follows */
            notify_closed(c, -1, "connection closed");
        }
        break;
    case LWS_CALLBACK_WSI_DESTROY:
        /* Every wsi ends here.  One that lws closes before its handshake
         * completed (the kill timeout of oc_client_destroy on a server that
         * accepted but never answered) may get neither CLIENT_CLOSED nor
         * CLIENT_CONNECTION_ERROR, and c->wsi must not outlive it: the next
         * EVENT_WAIT_CANCELLED would hand lws the freed wsi.  After those
         * two the user pointer is NULL (c may be gone); here c still holds
         * this wsi, so oc_client_destroy has not freed it. */
        if (c && l) {
            pthread_mutex_lock(&l->mu);
            int mine = c->wsi == wsi;
            pthread_mutex_unlock(&l->mu);
            if (mine)
                notify_closed(c, -1, "connection closed before the WebSocket handshake completed");
        }
        break;
    case LWS_CALLBACK_CLIENT_RECEIVE:
        on_receive(c, l, wsi, in, len);
        break;
    case LWS_CALLBACK_CLIENT_WRITEABLE:
        return on_writeable(c, l, wsi);
    default:
        break;
    }
    return 0;
}

static const struct lws_protocols oc_protocols[] = {
    {PROTO_SUBPROTOCOL, lws_cb, 0, 65536, 0, NULL, 0},
    {NULL, NULL, 0, 0, 0, NULL, 0}
};

/* ================================================================= loop */

ocean_result oc_loop_create(oc_loop **out, char *err, size_t errlen)
{
    if (!out)
        return OCEAN_EINVAL;
    *out = NULL;
    oc_loop *l = calloc(1, sizeof *l);
    if (!l)
        return OCEAN_ENOMEM;
    pthread_mutex_init(&l->mu, NULL);
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&l->cv, &ca);
    pthread_condattr_destroy(&ca);
    atomic_init(&l->stop, 0);

    /* lws logging is process-wide: keep it to errors unless asked. */
    if (!getenv("OC_LWS_LOG"))
        lws_set_log_level(LLL_ERR, NULL);
    struct lws_context_creation_info info;
    memset(&info, 0, sizeof info);
    info.port = CONTEXT_PORT_NO_LISTEN;
    info.protocols = oc_protocols;
    info.gid = -1;
    info.uid = -1;
    info.user = l;
    info.fd_limit_per_thread = 0;
    /* TLS (wss://) needs LWS_SERVER_OPTION_DO_SSL_GLOBAL_INIT on the vhost,
     * which makes its client SSL_CTX, but not on the context: there lws
     * 4.1 redoes OpenSSL's global init per context, which allocates a new
     * SSL_CTX ex_data index into a process-wide variable.  lws stores a
     * client SSL_CTX's refcount record at the index current when it was
     * made and looks it up at the current index when the vhost goes: once
     * a second loop is made, destroying the first finds no record and
     * keeps its SSL_CTX and system CA store (~0.85 MB) for good.  Without
     * the option on the context the index never moves (OpenSSL 1.1+
     * initialises itself), so every loop finds its record. */
    info.options = LWS_SERVER_OPTION_EXPLICIT_VHOSTS;
    l->ctx = lws_create_context(&info);
    if (l->ctx) {
        info.options = LWS_SERVER_OPTION_DO_SSL_GLOBAL_INIT;
        if (!lws_create_vhost(l->ctx, &info)) {
            lws_context_destroy(l->ctx);
            l->ctx = NULL;
        }
    }
    if (!l->ctx) {
        ocean_seterr(err, errlen, "libwebsockets could not create a client context");
        pthread_mutex_destroy(&l->mu);
        pthread_cond_destroy(&l->cv);
        free(l);
        return OCEAN_EIO;
    }
    *out = l;
    return OCEAN_OK;
}

static void free_client_mem(oc_client *c);

void oc_loop_destroy(oc_loop *l)
{
    if (!l)
        return;
    oc_loop_stop(l);
    l->destroying = 1;
    lws_context_destroy(l->ctx);   /* closes any remaining connection */
    oc_client *c = l->clients;
    while (c) {
        oc_client *n = c->next;
        free_client_mem(c);
        c = n;
    }
    pthread_mutex_destroy(&l->mu);
    pthread_cond_destroy(&l->cv);
    free(l);
}

static void sul_cb(lws_sorted_usec_list_t *sul)
{
    oc_loop *l = lws_container_of(sul, oc_loop, sul);
    l->sul_fired = 1;
    /* lws runs ripe timers before it computes its poll timeout: without
     * this wake-up, a timer that ripens just as lws_service starts would
     * leave poll() waiting for lws's next internal timer (up to 30 s). */
    lws_cancel_service(l->ctx);
}

static ocean_result service_locked_check(oc_loop *l)
{
    pthread_mutex_lock(&l->mu);
    int thr = l->thread_running;
    pthread_mutex_unlock(&l->mu);
    return thr ? OCEAN_ESTATE : OCEAN_OK;
}

/* 1 if a connection of l has received bytes waiting (in its socket or
 * buffered inside lws or TLS) or lws wants a forced pass.  Servicing
 * thread only: the wsis stay valid while it does not service. */
static int loop_has_input(oc_loop *l)
{
    if (lws_service_adjust_timeout(l->ctx, 1, 0) == 0)
        return 1;
    struct pollfd fds[64];
    nfds_t n = 0;
    int ready = 0;
    /* mu held throughout (poll does not wait): a client may be destroyed
     * by another thread as soon as it is released */
    pthread_mutex_lock(&l->mu);
    for (oc_client *k = l->clients; k && !ready; k = k->next) {
        if (k->wsi && (fds[n].fd = lws_get_socket_fd(k->wsi)) >= 0) {
            fds[n].events = POLLIN;
            fds[n].revents = 0;
            n++;
        }
        if (n == sizeof fds / sizeof fds[0] || (!k->next && n)) {
            ready = poll(fds, n, 0) > 0;
            n = 0;
        }
    }
    pthread_mutex_unlock(&l->mu);
    return ready;
}

ocean_result oc_loop_service(oc_loop *l, int timeout_ms)
{
    if (!l)
        return OCEAN_EINVAL;
    if (service_locked_check(l) != OCEAN_OK)
        return OCEAN_ESTATE;
    if (timeout_ms <= 0) {
        /* One lws_service pass reads at most one chunk per connection: a
         * caller servicing once per 60 Hz step would get ~6 of 30 fps of
         * 80 KB frames, ever later.  Pass again while anything is ready, within
         * OC_SERVICE_DRAIN_MS so that a flood still returns. */
        double until = mono_now() + OC_SERVICE_DRAIN_MS * 1e-3;
        do
            lws_service(l->ctx, -1);
        while (loop_has_input(l) && mono_now() < until);
        return OCEAN_OK;
    }
    pthread_mutex_lock(&l->mu);
    uint64_t ev0 = l->events;
    pthread_mutex_unlock(&l->mu);
    double deadline = mono_now() + timeout_ms * 1e-3;
    l->sul_fired = 0;
    lws_sul_schedule(l->ctx, 0, &l->sul, sul_cb, (lws_usec_t)timeout_ms * 1000);
    for (;;) {
        if (mono_now() >= deadline || lws_service(l->ctx, 0) < 0)
            break;
        pthread_mutex_lock(&l->mu);
        int changed = l->events != ev0;
        pthread_mutex_unlock(&l->mu);
        if (changed || l->sul_fired || mono_now() >= deadline)
            break;
    }
    lws_sul_cancel(&l->sul);
    return OCEAN_OK;
}

static void *loop_thread(void *arg)
{
    oc_loop *l = arg;
    while (!atomic_load(&l->stop))
        if (lws_service(l->ctx, 0) < 0)
            break;
    return NULL;
}

ocean_result oc_loop_start(oc_loop *l)
{
    if (!l)
        return OCEAN_EINVAL;
    pthread_mutex_lock(&l->mu);
    if (l->thread_running) {
        pthread_mutex_unlock(&l->mu);
        return OCEAN_OK;
    }
    atomic_store(&l->stop, 0);
    if (pthread_create(&l->thread, NULL, loop_thread, l) != 0) {
        pthread_mutex_unlock(&l->mu);
        return OCEAN_ENOMEM;
    }
    l->thread_running = 1;
    pthread_mutex_unlock(&l->mu);
    return OCEAN_OK;
}

void oc_loop_stop(oc_loop *l)
{
    if (!l)
        return;
    pthread_mutex_lock(&l->mu);
    int running = l->thread_running;
    pthread_mutex_unlock(&l->mu);
    if (!running)
        return;
    atomic_store(&l->stop, 1);
    lws_cancel_service(l->ctx);
    pthread_join(l->thread, NULL);
    pthread_mutex_lock(&l->mu);
    l->thread_running = 0;
    pthread_mutex_unlock(&l->mu);
}

/* Waits on the loop: services it (caller-driven) or sleeps on the condition
 * variable (threaded) until pred(c) holds or the deadline passes.  Returns 1
 * if pred held.  Called without mu. */
typedef int (*pred_fn)(oc_client *c, void *arg);

static int wait_until(oc_client *c, int timeout_ms, pred_fn pred, void *arg)
{
    oc_loop *l = c->loop;
    double deadline = timeout_ms < 0 ? INFINITY : mono_now() + timeout_ms * 1e-3;
    for (;;) {
        pthread_mutex_lock(&l->mu);
        int ok = pred(c, arg);
        int thr = l->thread_running;
        if (ok) {
            pthread_mutex_unlock(&l->mu);
            return 1;
        }
        double now = mono_now();
        if (now >= deadline) {
            pthread_mutex_unlock(&l->mu);
            return 0;
        }
        if (thr) {
            struct timespec ts;
            double until = isinf(deadline) ? now + 1.0 : deadline;
            if (until > now + 1.0)
                until = now + 1.0;
            ts.tv_sec = (time_t)until;
            ts.tv_nsec = (long)((until - (double)ts.tv_sec) * 1e9);
            pthread_cond_timedwait(&l->cv, &l->mu, &ts);
            pthread_mutex_unlock(&l->mu);
        } else {
            pthread_mutex_unlock(&l->mu);
            double left = isinf(deadline) ? 1000.0 : (deadline - now) * 1e3;
            int ms = left > 1000 ? 1000 : (int)ceil(left);
            oc_loop_service(l, ms < 1 ? 1 : ms);
        }
    }
}

/* ============================================================== clients */

void oc_options_default(oc_options *o)
{
    memset(o, 0, sizeof *o);
    o->frame_queue = 4;
    o->decode_tiles = 1;
    o->max_message = PROTO_MAX_MESSAGE_DEFAULT;
}

static void free_client_mem(oc_client *c)
{
    oc_held_destroy(c->held);
    oc_wakes_destroy(c->wakes);
    txmsg *t = c->tx_head;
    while (t) {
        txmsg *n = t->next;
        proto_buf_free(&t->buf);
        free(t);
        t = n;
    }
    for (int i = 0; i < c->fq_len; i++)
        oc_frame_free(&c->fq[(c->fq_head + i) % c->fq_cap]->pub);
    free(c->fq);
    pending_query *q = c->queries;
    while (q) {
        pending_query *n = q->next;
        oc_query_result_free(&q->result);
        free(q);
        q = n;
    }
    topo_unref(c->topo);
    free(c->rx);
    free(c);
}

ocean_result oc_client_create(const oc_options *o, oc_client **out, char *err, size_t errlen)
{
    if (out)
        *out = NULL; /* on every failure, as the contract says */
    if (!out || !o) {
        ocean_seterr(err, errlen, !out ? "out is NULL: nowhere to put the client" : "no options (o is NULL)");
        return OCEAN_EINVAL;
    }
    oc_url url;
    ocean_result r = oc_url_parse(o->url, &url, err, errlen);
    if (r != OCEAN_OK)
        return r;
    if (o->frame_queue < 1 || o->frame_queue > 1024) {
        ocean_seterr(err, errlen, "frame_queue %d outside 1..1024", o->frame_queue);
        return OCEAN_EINVAL;
    }
    if (o->max_message < PROTO_HEADER_SIZE) {
        ocean_seterr(err, errlen, "max_message %u below the %d-byte header", o->max_message, PROTO_HEADER_SIZE);
        return OCEAN_EINVAL;
    }
    if (o->origin && strlen(o->origin) >= 256) {
        ocean_seterr(err, errlen, "origin longer than 255 bytes");
        return OCEAN_EINVAL;
    }
    oc_client *c = calloc(1, sizeof *c);
    if (!c)
        return OCEAN_ENOMEM;
    c->fq_cap = o->frame_queue;
    c->fq = calloc((size_t)c->fq_cap, sizeof *c->fq);
    if (!c->fq) {
        free(c);
        return OCEAN_ENOMEM;
    }
    c->url = url;
    c->opt = *o;
    c->opt.url = NULL;
    if (o->origin) {
        snprintf(c->origin, sizeof c->origin, "%s", o->origin);
        c->opt.origin = c->origin;
    }
    c->bye_reason = -1;
    c->next_query_id = 1;
    c->frame_rate = 30.0f;
    if (o->loop) {
        c->loop = o->loop;
    } else {
        r = oc_loop_create(&c->loop, err, errlen);
        if (r != OCEAN_OK) {
            free(c->fq);
            free(c);
            return r;
        }
        c->own_loop = 1;
    }
    oc_loop *l = c->loop;

    /* lws is not thread-safe: the connect is issued by the servicing thread
     * (see do_connects), woken through lws_cancel_service. */
    pthread_mutex_lock(&l->mu);
    c->state = OC_CONNECTING;
    c->connect_pending = 1;
    c->next = l->clients;
    l->clients = c;
    pthread_mutex_unlock(&l->mu);
    wake(l);
    *out = c;
    return OCEAN_OK;
}

static int pred_ready(oc_client *c, void *arg)
{
    (void)arg;
    return c->state != OC_CONNECTING;
}

ocean_result oc_client_connect_wait(oc_client *c, int timeout_ms)
{
    if (!c)
        return OCEAN_EINVAL;
    wait_until(c, timeout_ms, pred_ready, NULL);
    pthread_mutex_lock(&c->loop->mu);
    oc_state s = c->state;
    if (s == OC_CONNECTING)
        set_local_error(c, OCEAN_ESTATE, "timed out after %d ms: no HELLO from %s:%d", timeout_ms, c->url.host,
                        c->url.port);
    pthread_mutex_unlock(&c->loop->mu);
    return s == OC_READY ? OCEAN_OK : s == OC_CLOSED ? OCEAN_EIO : OCEAN_ESTATE;
}

ocean_result oc_connect(const oc_options *o, int timeout_ms, oc_client **out, char *err, size_t errlen)
{
    if (!out)
        return OCEAN_EINVAL;
    *out = NULL;
    oc_client *c;
    ocean_result r = oc_client_create(o, &c, err, errlen);
    if (r != OCEAN_OK)
        return r;
    r = oc_client_connect_wait(c, timeout_ms);
    if (r != OCEAN_OK) {
        oc_client_last_error(c, err, errlen);
        if (err && errlen && !err[0])
            ocean_seterr(err, errlen, "connect to %s:%d failed", c->url.host, c->url.port);
        oc_client_destroy(c);
        return r;
    }
    *out = c;
    return OCEAN_OK;
}

static int pred_closed_idle(oc_client *c, void *arg)
{
    (void)arg;
    return c->wsi == NULL && c->busy == 0;
}

void oc_client_destroy(oc_client *c)
{
    if (!c)
        return;
    oc_loop *l = c->loop;
    pthread_mutex_lock(&l->mu);
    if (c->wsi != NULL && c->state == OC_READY) {
        proto_msg m;
        proto_msg_init(&m, PROTO_BYE);
        m.u.bye.reason = PROTO_BYE_NORMAL;
        snprintf(m.u.bye.message, sizeof m.u.bye.message, "client closing");
        queue_msg_locked(c, &m, NULL, NULL, 0);
    }
    /* The writeable callback sends what is queued (the BYE), then closes. */
    c->connect_pending = 0;
    c->close_req = 1;
    pthread_mutex_unlock(&l->mu);
    wake(l);
    if (!wait_until(c, CLOSE_GRACE_MS, pred_closed_idle, NULL)) {
        /* The peer did not complete the close in time: cut the socket. */
        pthread_mutex_lock(&l->mu);
        c->kill_req = 1;
        pthread_mutex_unlock(&l->mu);
        wake(l);
        wait_until(c, 2000, pred_closed_idle, NULL);
    }
    if (c->own_loop) {
        /* Destroying the context closes what is left (callbacks still see c). */
        oc_loop_destroy(l);   /* also frees c, which is on its list */
        return;
    }
    pthread_mutex_lock(&l->mu);
    for (oc_client **pp = &l->clients; *pp; pp = &(*pp)->next)
        if (*pp == c) {
            *pp = c->next;
            break;
        }
    int orphan = c->wsi != NULL;
    pthread_mutex_unlock(&l->mu);
    if (orphan) {
        /* Still not closed after the kill timeout: leave it to the loop's
         * destruction rather than free memory lws still points to. */
        pthread_mutex_lock(&l->mu);
        c->next = l->clients;
        l->clients = c;
        pthread_mutex_unlock(&l->mu);
        return;
    }
    free_client_mem(c);
}

oc_state oc_client_state(const oc_client *c)
{
    if (!c)
        return OC_CLOSED;
    pthread_mutex_lock(&c->loop->mu);
    oc_state s = c->state;
    pthread_mutex_unlock(&c->loop->mu);
    return s;
}

oc_loop *oc_client_loop(const oc_client *c) { return c ? c->loop : NULL; }

ocean_result oc_service(oc_client *c, int timeout_ms)
{
    if (!c)
        return OCEAN_EINVAL;
    return oc_loop_service(c->loop, timeout_ms);
}

ocean_result oc_client_hello(const oc_client *c, proto_hello *out)
{
    if (!c || !out)
        return OCEAN_EINVAL;
    pthread_mutex_lock(&c->loop->mu);
    int have = c->have_hello;
    if (have)
        *out = c->hello;
    pthread_mutex_unlock(&c->loop->mu);
    return have ? OCEAN_OK : OCEAN_ESTATE;
}

double oc_client_sim_time(const oc_client *c)
{
    if (!c)
        return NAN;
    pthread_mutex_lock(&c->loop->mu);
    double t = c->have_hello ? c->last_sim : NAN;
    pthread_mutex_unlock(&c->loop->mu);
    return t;
}

ocean_result oc_client_last_error(const oc_client *c, char *buf, size_t buflen)
{
    if (!c)
        return OCEAN_EINVAL;
    pthread_mutex_lock(&c->loop->mu);
    ocean_result r = c->last_err;
    if (buf && buflen)
        snprintf(buf, buflen, "%s", c->last_err_msg);
    pthread_mutex_unlock(&c->loop->mu);
    return r;
}

void oc_subscribe_default(proto_subscribe *s)
{
    memset(s, 0, sizeof *s);
    /* the browser viewer's subscription (clients/web/worker.js,
     * chooseSubscription), so the daemon's shared tile encodings serve both */
    s->effects = PROTO_FX_ALL;
    s->mesh_kind = PROTO_MESH_CONCENTRIC;
    s->codec = PROTO_CODEC_QZ;
    s->cutoff_policy = PROTO_CUTOFF_ANTIALIAS;
    s->mode = PROTO_MODE_LIVE;
    s->layers = PROTO_MAX_LAYERS;
    s->lod_levels = 8;
    s->tile_size = 64;
    s->frame_rate_hz = 30.0f;
    s->accuracy = (float)OC_ACCURACY_DEFAULT;
    s->base_spacing_m = 0;
    s->view_range_m = 0;
    s->layout = PROTO_LAYOUT_CASCADE;
    /* a layout-0 subscriber gets its mesh positions compressed (1/4 to 1/5
     * of f32 at 5e-3, decoded here); layout 1 sends none */
    s->mesh_codec = PROTO_MESH_CODEC_QZ;
    /* the viewer holds each mip's samples and blends two in time, so each
     * mip travels once per its own update interval (PROTOCOL.md "Samples
     * in time"): a quarter of the bytes at ship-bridge for the same plan,
     * and within the daemon's byte budget finer mips for them (make bench:
     * bench_accuracy's viewer rows); layout 0 ignores the flag */
    s->flags = PROTO_SUB_TIME_INTERP;
}

void oc_camera_default(proto_camera *cam)
{
    memset(cam, 0, sizeof *cam);
    cam->pos[1] = 20.0;
    cam->fov_y_deg = 60.0f;
    cam->viewport_w = 1920;
    cam->viewport_h = 1080;
}

ocean_result oc_client_subscribe(oc_client *c, const proto_subscribe *s)
{
    if (!c)
        return OCEAN_EINVAL;
    if (!s)
        return fail_local(c, OCEAN_EINVAL, "oc_client_subscribe: no subscription (NULL)");
    proto_msg m;
    proto_msg_init(&m, PROTO_SUBSCRIBE);
    m.u.subscribe = *s;
    /* layout 1 ignores mesh_codec: send 0 there, the byte a daemon that
     * predates mesh_codec requires */
    if (s->layout != PROTO_LAYOUT_WORLD)
        m.u.subscribe.mesh_codec = PROTO_MESH_CODEC_F32;
    char err[256] = "";
    pthread_mutex_lock(&c->loop->mu);
    ocean_result r = queue_msg_locked(c, &m, NULL, err, sizeof err);
    if (r == OCEAN_OK) {
        c->frame_rate = s->frame_rate_hz;
        c->replay = s->mode == PROTO_MODE_REPLAY;
        /* cameras queued before belong to the old subscription: a later
         * live one must not move its content ahead of this SUBSCRIBE */
        for (txmsg *t = c->tx_head; t; t = t->next)
            t->live_camera = 0;
    } else {
        set_local_error(c, r, "cannot send SUBSCRIBE: %s", err[0] ? err : ocean_strerror(r));
    }
    pthread_mutex_unlock(&c->loop->mu);
    if (r == OCEAN_OK)
        wake(c->loop);
    return r;
}

ocean_result oc_client_send_camera(oc_client *c, const proto_camera *cam, uint32_t *seq_out)
{
    if (!c)
        return OCEAN_EINVAL;
    if (!cam)
        return fail_local(c, OCEAN_EINVAL, "oc_client_send_camera: no camera (NULL)");
    proto_msg m;
    proto_msg_init(&m, PROTO_CAMERA);
    m.u.camera = *cam;
    uint32_t seq = 0;
    char err[256] = "";
    pthread_mutex_lock(&c->loop->mu);
    ocean_result r = OCEAN_OK;
    txmsg *old = NULL;
    /* live mode: only the newest camera matters, and a CAMERA still
     * queued has not left: this one takes its place and seq (the seq
     * stays +1 per message sent), so a caller reporting its camera faster
     * than the link carries it does not queue stale ones */
    if (!c->replay && c->state == OC_READY && c->wsi && !c->close_req)
        for (txmsg *t = c->tx_head; t && !old; t = t->next)
            if (t->live_camera)
                old = t;
    if (old) {
        proto_buf nb;
        proto_buf_init(&nb, LWS_PRE);
        seq = old->seq;
        m.hdr.seq = seq;
        m.hdr.sim_time = isfinite(c->last_frame_sim) ? c->last_frame_sim : 0.0;
        r = proto_encode(&nb, &m, err, sizeof err);
        if (r == OCEAN_OK) {
            size_t ol = proto_buf_len(&old->buf), nl = proto_buf_len(&nb);
            c->tx_bytes = c->tx_bytes - ol + nl;
            c->st.bytes_tx = c->st.bytes_tx - ol + nl;
            proto_buf_free(&old->buf);
            old->buf = nb;
            for (int i = 0; i < CAM_RING; i++)
                if (c->cams[i].seq == seq)
                    c->cams[i].wall = wall_now();
        } else {
            proto_buf_free(&nb);
        }
    } else {
        r = queue_msg_locked(c, &m, &seq, err, sizeof err);
        if (r == OCEAN_OK) {
            c->tx_tail->live_camera = !c->replay;
            c->cams[c->cam_pos % CAM_RING].seq = seq;
            c->cams[c->cam_pos % CAM_RING].wall = wall_now();
            c->cam_pos++;
        }
    }
    if (r != OCEAN_OK) {
        set_local_error(c, r, "cannot send CAMERA: %s", err[0] ? err : ocean_strerror(r));
    }
    pthread_mutex_unlock(&c->loop->mu);
    if (r == OCEAN_OK) {
        wake(c->loop);
        if (seq_out)
            *seq_out = seq;
    }
    return r;
}

ocean_result oc_client_send_entity(oc_client *c, const proto_entity *e)
{
    if (!c)
        return OCEAN_EINVAL;
    if (!e)
        return fail_local(c, OCEAN_EINVAL, "oc_client_send_entity: no entity (NULL)");
    proto_msg m;
    proto_msg_init(&m, PROTO_ENTITY);
    m.u.entity = *e;
    char err[256] = "";
    pthread_mutex_lock(&c->loop->mu);
    ocean_result r = queue_msg_locked(c, &m, NULL, err, sizeof err);
    if (r != OCEAN_OK)
        set_local_error(c, r, "cannot send ENTITY: %s", err[0] ? err : ocean_strerror(r));
    pthread_mutex_unlock(&c->loop->mu);
    if (r == OCEAN_OK)
        wake(c->loop);
    return r;
}

static int pred_frame(oc_client *c, void *arg)
{
    (void)arg;
    return c->fq_len > 0 || c->state == OC_CLOSED;
}

ocean_result oc_client_next_frame(oc_client *c, int timeout_ms, oc_frame **out)
{
    if (!c)
        return OCEAN_EINVAL;
    if (!out)
        return fail_local(c, OCEAN_EINVAL, "oc_client_next_frame: no place for the frame (out NULL)");
    *out = NULL;
    if (timeout_ms != 0)
        wait_until(c, timeout_ms, pred_frame, NULL);
    else if (service_locked_check(c->loop) == OCEAN_OK)
        oc_loop_service(c->loop, 0);
    pthread_mutex_lock(&c->loop->mu);
    ocean_result r;
    if (c->fq_len > 0) {
        frame_priv *f = c->fq[c->fq_head];
        c->fq_head = (c->fq_head + 1) % c->fq_cap;
        c->fq_len--;
        *out = &f->pub;
        r = OCEAN_OK;
    } else if (c->state == OC_CLOSED) {
        r = OCEAN_EIO;   /* last_error already says why it closed */
    } else {
        r = OCEAN_ESTATE;
        /* an empty poll (timeout 0) is the normal answer of a caller
         * polling every step, not a failure: it would hide the server's
         * ERRORs within a step */
        if (timeout_ms != 0)
            set_local_error(c, r, "timed out after %d ms: no FRAME arrived", timeout_ms);
    }
    pthread_mutex_unlock(&c->loop->mu);
    return r;
}

const oc_topology *oc_client_topology(oc_client *c)
{
    if (!c)
        return NULL;
    pthread_mutex_lock(&c->loop->mu);
    const oc_topology *t = c->topo ? &c->topo->pub : NULL;
    pthread_mutex_unlock(&c->loop->mu);
    return t;
}

/* ============================================================= queries */

static ocean_result query_send(oc_client *c, const double *xz, size_t n, int at_time, double t,
                               pending_query *q)
{
    if (!xz || n == 0 || n > PROTO_MAX_QUERY_POINTS) {
        pthread_mutex_lock(&c->loop->mu);
        set_local_error(c, OCEAN_EINVAL, "query needs 1..%u points, got %zu", PROTO_MAX_QUERY_POINTS, n);
        pthread_mutex_unlock(&c->loop->mu);
        return OCEAN_EINVAL;
    }
    for (size_t i = 0; i < 2 * n; i++)
        if (!isfinite(xz[i])) {
            pthread_mutex_lock(&c->loop->mu);
            set_local_error(c, OCEAN_EINVAL, "query point %zu is not finite", i / 2);
            pthread_mutex_unlock(&c->loop->mu);
            return OCEAN_EINVAL;
        }
    /* the protocol's two values only (PROTOCOL.md QUERY): any other is
     * refused here rather than sent as 1 */
    if (at_time != 0 && at_time != 1)
        return fail_local(c, OCEAN_EINVAL, "query at_time %d: 0 (the latest tick) or 1 (at t)", at_time);
    if (at_time && !isfinite(t))
        return fail_local(c, OCEAN_EINVAL, "query time t = %g is not finite", t);
    proto_msg m;
    proto_msg_init(&m, PROTO_QUERY);
    m.u.query.count = (uint32_t)n;
    m.u.query.at_time = at_time ? 1 : 0;
    m.u.query.t = at_time ? t : 0.0;
    m.u.query.points = xz;
    char err[256] = "";
    pthread_mutex_lock(&c->loop->mu);
    ocean_result r = OCEAN_OK;
    if (c->have_hello && c->hello.max_query_points && n > c->hello.max_query_points) {
        set_local_error(c, OCEAN_EINVAL, "query of %zu points above the server's limit %u", n,
                        c->hello.max_query_points);
        r = OCEAN_EINVAL;
    }
    if (r == OCEAN_OK) {
        q->id = c->next_query_id++;
        m.u.query.query_id = q->id;
        r = queue_msg_locked(c, &m, &q->seq, err, sizeof err);
        if (r == OCEAN_OK) {
            q->next = c->queries;
            c->queries = q;
        } else {
            set_local_error(c, r, "cannot send QUERY: %s", err[0] ? err : ocean_strerror(r));
        }
    }
    pthread_mutex_unlock(&c->loop->mu);
    if (r == OCEAN_OK)
        wake(c->loop);
    return r;
}

ocean_result oc_client_query_async(oc_client *c, const double *xz, size_t n, int at_time, double t,
                                   oc_query_fn fn, void *user, uint32_t *query_id)
{
    if (!c)
        return OCEAN_EINVAL;
    pending_query *q = calloc(1, sizeof *q);
    if (!q)
        return OCEAN_ENOMEM;
    q->fn = fn;
    q->user = user;
    ocean_result r = query_send(c, xz, n, at_time, t, q);
    if (r != OCEAN_OK) {
        free(q);
        return r;
    }
    if (query_id)
        *query_id = q->id;
    return OCEAN_OK;
}

static int pred_query(oc_client *c, void *arg)
{
    (void)c;
    return ((pending_query *)arg)->done;
}

ocean_result oc_client_query(oc_client *c, const double *xz, size_t n, int at_time, double t,
                             int timeout_ms, oc_query_result *out)
{
    if (!c)
        return OCEAN_EINVAL;
    if (!out)
        return fail_local(c, OCEAN_EINVAL, "oc_client_query: no place for the result (out NULL)");
    memset(out, 0, sizeof *out);
    pending_query *q = calloc(1, sizeof *q);
    if (!q)
        return OCEAN_ENOMEM;
    q->blocking = 1;
    ocean_result r = query_send(c, xz, n, at_time, t, q);
    if (r != OCEAN_OK) {
        free(q);
        return r;
    }
    wait_until(c, timeout_ms, pred_query, q);
    pthread_mutex_lock(&c->loop->mu);
    for (pending_query **pp = &c->queries; *pp; pp = &(*pp)->next)
        if (*pp == q) {
            *pp = q->next;
            break;
        }
    if (!q->done) {
        r = OCEAN_ESTATE;
        set_local_error(c, r, "timed out after %d ms: no QUERY_RESULT for query %u", timeout_ms, q->id);
    } else {
        r = q->res;
    }
    pthread_mutex_unlock(&c->loop->mu);
    if (r == OCEAN_OK)
        *out = q->result;
    else
        oc_query_result_free(&q->result);
    free(q);
    return r;
}

/* =========================================================== sea state */

/* Enters (eff, sea) in c's timeline; the same effective time replaces.  Full:
 * the oldest entry goes (it only describes times long past) [mu]. */
static void timeline_add(oc_client *c, double eff, const proto_sea *sea)
{
    int at = 0;
    while (at < c->tl_n && c->tl_eff[at] < eff)
        at++;
    if (!(at < c->tl_n && c->tl_eff[at] == eff)) {
        if (c->tl_n == OC_SEA_TIMELINE_MAX) {
            if (at == 0)
                return;
            memmove(&c->tl_eff[0], &c->tl_eff[1], (size_t)(at - 1) * sizeof c->tl_eff[0]);
            memmove(&c->tl_sea[0], &c->tl_sea[1], (size_t)(at - 1) * sizeof c->tl_sea[0]);
            at--;
        } else {
            memmove(&c->tl_eff[at + 1], &c->tl_eff[at], (size_t)(c->tl_n - at) * sizeof c->tl_eff[0]);
            memmove(&c->tl_sea[at + 1], &c->tl_sea[at], (size_t)(c->tl_n - at) * sizeof c->tl_sea[0]);
            c->tl_n++;
        }
    }
    c->tl_eff[at] = eff;
    c->tl_sea[at] = *sea;
}

ocean_result oc_client_wakes(oc_client *c, double t, const double *xz, size_t n, oc_wake *out)
{
    if (!c || !xz || !out || !isfinite(t))
        return OCEAN_EINVAL;
    proto_sea sea;
    if (oc_client_sea_at(c, t, &sea, NULL) != OCEAN_OK)
        return OCEAN_ESTATE;
    wake_sample *w = malloc(sizeof *w * (n ? n : 1));
    if (!w)
        return OCEAN_ENOMEM;
    pthread_mutex_lock(&c->loop->mu);
    ocean_result r = OCEAN_OK;
    if (!c->wakes)   /* no ship announced yet: a sea without wakes */
        memset(w, 0, sizeof *w * n);
    else
        r = oc_wakes_sample(c->wakes, t, sea.depth_m, xz, n, w);
    pthread_mutex_unlock(&c->loop->mu);
    for (size_t i = 0; r == OCEAN_OK && i < n; i++)
        out[i] = (oc_wake){w[i].height, w[i].dhdx, w[i].dhdz, w[i].error};
    free(w);
    return r;
}

ocean_result oc_client_sea_at(const oc_client *c, double t, proto_sea *out, double *effective_time)
{
    if (!c || !out || !isfinite(t))
        return OCEAN_EINVAL;
    pthread_mutex_lock(&c->loop->mu);
    int k = -1;
    for (int i = 0; i < c->tl_n; i++)
        if (c->tl_eff[i] <= t)
            k = i;
    if (k >= 0) {
        *out = c->tl_sea[k];
        if (effective_time)
            *effective_time = c->tl_eff[k];
    }
    pthread_mutex_unlock(&c->loop->mu);
    return k >= 0 ? OCEAN_OK : OCEAN_ESTATE;
}

ocean_result oc_client_sea_state(const oc_client *c, proto_sea *out, double *effective_time)
{
    if (!c || !out)
        return OCEAN_EINVAL;
    pthread_mutex_lock(&c->loop->mu);
    int have = c->have_hello;
    if (have) {
        *out = c->sea;
        if (effective_time)
            *effective_time = c->sea_time;
    }
    pthread_mutex_unlock(&c->loop->mu);
    return have ? OCEAN_OK : OCEAN_ESTATE;
}

/* Same sea state, the informational hs and tp aside (the server fills
 * them in). */
static int sea_same(const proto_sea *a, const proto_sea *b)
{
    return a->spectrum == b->spectrum && a->spreading == b->spreading && a->seed == b->seed &&
           a->wind_u10 == b->wind_u10 && a->wind_dir_deg == b->wind_dir_deg &&
           a->fetch_m == b->fetch_m && a->depth_m == b->depth_m && a->swell == b->swell &&
           a->phillips_a == b->phillips_a && a->small_wave_m == b->small_wave_m &&
           a->choppiness == b->choppiness;
}

static int pred_sea(oc_client *c, void *arg)
{
    (void)arg;
    return c->sea_done;
}

/* Sends SEA_STATE m (its token is wiped from m) and waits up to timeout_ms
 * for its answer: mode 1 a set's announce (the sea want from want_t on),
 * mode 2 a get's state in force (left in sea_got, sea_got_t).  One such
 * request per client at a time. */
static ocean_result sea_request(oc_client *c, proto_msg *m, int mode, const proto_sea *want, double want_t,
                                int timeout_ms, proto_sea *got, double *got_t)
{
    char err[256] = "";
    const char *what = mode == 1 ? "set" : "get";
    pthread_mutex_lock(&c->loop->mu);
    ocean_result r = OCEAN_ESTATE;
    if (c->sea_wait)
        set_local_error(c, r, "a SEA_STATE request of this client is still waiting for its answer");
    else if ((r = queue_msg_locked(c, m, &c->sea_seq, err, sizeof err)) != OCEAN_OK)
        set_local_error(c, r, "cannot send SEA_STATE: %s", err[0] ? err : ocean_strerror(r));
    if (r == OCEAN_OK) {
        c->sea_wait = mode;
        c->sea_done = 0;
        if (want) c->sea_want = *want;
        c->sea_want_t = want_t;
    }
    pthread_mutex_unlock(&c->loop->mu);
    memset(m, 0, sizeof *m);   /* the token does not linger on the stack copy */
    if (r != OCEAN_OK)
        return r;
    wake(c->loop);
    wait_until(c, timeout_ms, pred_sea, NULL);
    pthread_mutex_lock(&c->loop->mu);
    if (!c->sea_done) {
        r = OCEAN_ESTATE;
        set_local_error(c, r, "timed out after %d ms: no answer to SEA_STATE %s", timeout_ms, what);
    } else if ((r = c->sea_res) == OCEAN_OK && got) {
        *got = c->sea_got;
        if (got_t) *got_t = c->sea_got_t;
    }
    c->sea_wait = 0;
    c->sea_done = 0;
    pthread_mutex_unlock(&c->loop->mu);
    return r;
}

ocean_result oc_client_sea_state_set(oc_client *c, const proto_sea *sea, double effective_time,
                                     const char *token, int timeout_ms)
{
    if (!c)
        return OCEAN_EINVAL;
    if (!sea || !token)
        return fail_local(c, OCEAN_EINVAL, "oc_client_sea_state_set: no %s (NULL)", !sea ? "sea" : "admin token");
    if (strlen(token) > PROTO_TOKEN_MAX)
        return fail_local(c, OCEAN_EINVAL, "admin token of %zu bytes is longer than %u", strlen(token),
                          (unsigned)PROTO_TOKEN_MAX);
    proto_msg m;
    proto_msg_init(&m, PROTO_SEA_STATE);
    m.u.sea_state.op = PROTO_SEA_SET;
    m.u.sea_state.effective_time = effective_time;
    m.u.sea_state.sea = *sea;
    snprintf(m.u.sea_state.token, sizeof m.u.sea_state.token, "%s", token);
    return sea_request(c, &m, 1, sea, effective_time, timeout_ms, NULL, NULL);
}

ocean_result oc_client_sea_state_fetch(oc_client *c, int timeout_ms, proto_sea *out, double *effective_time)
{
    if (!c || !out)
        return OCEAN_EINVAL;
    proto_msg m;
    proto_msg_init(&m, PROTO_SEA_STATE);
    m.u.sea_state.op = PROTO_SEA_GET;
    return sea_request(c, &m, 2, NULL, 0, timeout_ms, out, effective_time);
}

void oc_client_get_stats(const oc_client *c, oc_client_stats *out)
{
    if (!c || !out)
        return;
    pthread_mutex_lock(&c->loop->mu);
    *out = c->st;
    pthread_mutex_unlock(&c->loop->mu);
}
