/*
 * load_direct.c - the load generator's default receive path: N viewers over
 * T worker threads, each thread one epoll loop over plain non-blocking
 * sockets.  WebSocket framing, masking, fragments, ping/pong and the close
 * handshake are libwslay's (its event API, one context per viewer); this
 * file only does the HTTP Upgrade request and checks the 101 answer
 * (Sec-WebSocket-Accept, subprotocol), which wslay leaves to its user.
 * See load_run.h for why the client library is not used here.
 *
 * Bytes go socket -> the worker's rb in one recv() per readiness event (up
 * to RB_SIZE), then wslay's recv callback serves them from rb: wslay pulls
 * at most 4 KiB per callback, so letting it call recv() itself would cost
 * ~30 system calls per 126 KB FRAME.  wslay always takes all of rb before
 * wslay_event_recv returns, so one rb per worker (hot in cache) serves all
 * of its viewers.
 */
#include "load_run.h"

#include <errno.h>
#include <math.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/epoll.h>
#include <sys/random.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <libwebsockets.h>   /* lws_SHA1, lws_b64_encode_string for the handshake */
#include <wslay/wslay.h>

#include "codec.h"
#include "oc_held.h"
#include "proto_buf.h"

#define RB_SIZE (256u << 10)
#define HB_MAX 16384             /* longest 101 answer head accepted */
#define WS_GUID "258EAFA5-E914-47DA-95CA-C5AB0DC85B11"

enum { V_IDLE, V_TCP, V_SHAKE, V_OPEN, V_DONE };

struct worker;

/* One viewer; touched only by its worker's thread until the join. */
typedef struct dv {
    struct worker *w;
    int fd, state, index, ready, closed;
    int hello_seen;              /* SUBSCRIBE + CAMERA queued, not yet sent */
    unsigned evmask;             /* events registered with epoll */
    char key[32];
    char *hb;                    /* the 101 answer so far (V_SHAKE only) */
    size_t hl;
    uint8_t *mb;                 /* the binary message being received: */
    size_t mlen, mcap;           /*   its first mlen bytes (see ws_frame_start_cb) */
    size_t mtotal, fend;         /*   bytes so far; where the current frame ends */
    int in_data;                 /* the current frame is part of it */
    int decided, whole;          /* type seen; keeping it whole */
    int skip;                    /* 1 not binary, 2 too long (or no memory) */
    uint8_t *ob;                 /* handshake request bytes not yet sent */
    size_t olen;
    wslay_event_context_ptr ws;  /* from the 101 answer on */
    uint32_t seq;
    double last_sim;
    float tick_rate;
    uint32_t last_tick;
    int have_tick;
    uint64_t frames, bytes, skipped, errors, decode_errors, verified, nframe;
    uint64_t frames_layout[2];   /* FRAMEs in the window by layout */
    oc_frame_stream *fs;         /* a followed time-interpolating stream:
                                    every FRAME decoded through it */
    int fill;                    /* a followed stream's frames before its sea
                                    was first read (-1: it was) */
    proto_camera cam;
} dv;

typedef struct shared {
    const load_cfg *cfg;
    struct sockaddr_storage sa;
    socklen_t salen;
    oc_url url;
    double t_start;
    atomic_int ready, failed, created, measuring, stop;
    atomic_int why_set;         /* why[] written (the first closing reason) */
    char why[320];
} shared;

typedef struct worker {
    shared *S;
    pthread_t th;
    int ep;
    dv **v;
    int nv, next;               /* viewers; next one to connect */
    double now;                 /* wall clock of the current epoll batch */
    uint8_t *rb;                /* received bytes: [rp, rl) not yet given to wslay */
    size_t rp, rl;
    occli_vec delay;
    double min_delay;           /* over FRAMEs */
    double min_any;             /* over every message, HELLO included */
    uint64_t rng;
    int oom;
} worker;

/* ---- small helpers ------------------------------------------------------ */

static uint32_t rnd32(worker *w)
{
    w->rng ^= w->rng << 13;
    w->rng ^= w->rng >> 7;
    w->rng ^= w->rng << 17;
    return (uint32_t)(w->rng >> 11);
}

static void ep_set(worker *w, dv *v, unsigned ev)
{
    if (ev == v->evmask)
        return;
    struct epoll_event e = {.events = ev, .data.ptr = v};
    if (epoll_ctl(w->ep, EPOLL_CTL_MOD, v->fd, &e) == 0)
        v->evmask = ev;
}

static void close_viewer(worker *w, dv *v)
{
    if (v->fd >= 0) {
        epoll_ctl(w->ep, EPOLL_CTL_DEL, v->fd, NULL);
        close(v->fd);
        v->fd = -1;
    }
    if (!v->ready && v->state != V_DONE)
        atomic_fetch_add(&w->S->failed, 1);
    if (v->ready)
        v->closed = 1;
    v->state = V_DONE;
}

/* ---- wslay callbacks (user_data is the viewer) ---------------------------- */

/* Serves wslay from rb; an empty rb is EAGAIN, so wslay_event_recv returns
 * once it has consumed what the last recv() brought. */
static ssize_t ws_recv_cb(wslay_event_context_ptr ctx, uint8_t *buf, size_t len, int flags, void *user)
{
    (void)flags;
    dv *v = user;
    if (v->state != V_OPEN) {
        wslay_event_set_error(ctx, WSLAY_ERR_CALLBACK_FAILURE);
        return -1;
    }
    worker *w = v->w;
    size_t n = w->rl - w->rp;
    if (n == 0) {
        wslay_event_set_error(ctx, WSLAY_ERR_WOULDBLOCK);
        return -1;
    }
    if (n > len)
        n = len;
    memcpy(buf, w->rb + w->rp, n);
    w->rp += n;
    return (ssize_t)n;
}

static ssize_t ws_send_cb(wslay_event_context_ptr ctx, const uint8_t *data, size_t len, int flags, void *user)
{
    dv *v = user;
    for (;;) {
        ssize_t k = send(v->fd, data, len, MSG_NOSIGNAL | ((flags & WSLAY_MSG_MORE) ? MSG_MORE : 0));
        if (k >= 0)
            return k;
        if (errno == EINTR)
            continue;
        wslay_event_set_error(ctx, errno == EAGAIN || errno == EWOULDBLOCK ? WSLAY_ERR_WOULDBLOCK
                                                                           : WSLAY_ERR_CALLBACK_FAILURE);
        return -1;
    }
}

/* Client frames are masked (RFC 6455 5.3); the key only has to be
 * unpredictable to a browser-side attacker, which a load generator on
 * loopback has none of: the worker's xorshift, seeded from getrandom(). */
static int ws_genmask_cb(wslay_event_context_ptr ctx, uint8_t *buf, size_t len, void *user)
{
    (void)ctx;
    dv *v = user;
    for (size_t i = 0; i < len; i += 4) {
        uint32_t r = rnd32(v->w);
        memcpy(buf + i, &r, len - i < 4 ? len - i : 4);
    }
    return 0;
}

static void on_message(worker *w, dv *v, const uint8_t *p, size_t have, size_t n, double now);

/* Whether the viewer's next FRAME is one to decode in full: every one of a
 * followed stream, else staggered between viewers (a time-interpolating
 * stream not followed has none that stands alone past its KEY frame, so
 * none); on_message counts it. */
static int frame_wanted_whole(const dv *v)
{
    const load_cfg *cfg = v->w->S->cfg;
    if (v->fs || load_timed(cfg))
        return v->fs != NULL;
    return (v->nframe + (uint64_t)v->index) % (uint64_t)cfg->verify_every == 0;
}

static int mb_reserve(dv *v, size_t need)
{
    if (need <= v->mcap)
        return 0;
    size_t nc = v->mcap ? v->mcap : 4096;
    while (nc < need)
        nc *= 2;
    uint8_t *nb = realloc(v->mb, nc);
    if (!nb)
        return -1;
    v->mb = nb;
    v->mcap = nc;
    return 0;
}

/*
 * Binary messages are received with wslay's buffering off: wslay parses and
 * checks every frame header and hands over payload chunks as they come
 * (from its 4 KiB window).  Kept in mb: the first HEAD_KEEP bytes of every
 * message (header and FRAME fixed fields, checked on every FRAME), and the
 * whole message when it is to be decoded (every non-FRAME, every
 * verify_every'th FRAME).  Generator CPU at 256 viewers x 3.8 MB/s against
 * the hand-written reader this replaced (0.53-0.67 cores in the same runs):
 * with wslay's own buffering (a malloc'd copy of each 4 KiB chunk, then a
 * second copy joining them) +0.3 cores; appending every message whole
 * into mb, +0.1 to +0.2; as here, on a par.
 * Control frames stay buffered by wslay, which answers ping and close.
 */
/* header, FRAME fixed fields and a layout-1 cascade block's fixed part
 * (OC_FRAME_PEEK_BYTES = 144), rounded up */
#define HEAD_KEEP 160
static void ws_frame_start_cb(wslay_event_context_ptr ctx, const struct wslay_event_on_frame_recv_start_arg *arg,
                              void *user)
{
    (void)ctx;
    dv *v = user;
    v->in_data = !wslay_is_ctrl_frame(arg->opcode);
    if (!v->in_data)
        return;
    if (arg->opcode != WSLAY_CONTINUATION_FRAME) {
        v->mlen = v->mtotal = 0;
        v->decided = v->whole = 0;
        v->skip = arg->opcode != WSLAY_BINARY_FRAME;   /* text: not ours */
    }
    if (v->skip)
        return;
    if (arg->payload_length > PROTO_MAX_MESSAGE_DEFAULT - v->mtotal) {
        v->skip = 2;                   /* too long: a decode error at its end */
        return;
    }
    v->fend = v->mtotal + (size_t)arg->payload_length;
    if (mb_reserve(v, v->whole ? v->fend : HEAD_KEEP)) {
        v->w->oom = 1;
        v->skip = 2;
    }
}

static void ws_frame_chunk_cb(wslay_event_context_ptr ctx, const struct wslay_event_on_frame_recv_chunk_arg *arg,
                              void *user)
{
    (void)ctx;
    dv *v = user;
    if (!v->in_data || v->skip)
        return;
    const uint8_t *d = arg->data;
    size_t n = arg->data_length;
    v->mtotal += n;
    /* mb holds a prefix of the message: the keep-whole decision is taken
     * as soon as the header is in, before any byte is dropped */
    while (n) {
        size_t lim = v->whole ? v->fend : HEAD_KEEP;
        if (v->mlen >= lim)
            break;
        size_t k = n < lim - v->mlen ? n : lim - v->mlen;
        memcpy(v->mb + v->mlen, d, k);
        v->mlen += k;
        d += k;
        n -= k;
        if (!v->decided && v->mlen >= PROTO_HEADER_SIZE) {
            v->decided = 1;
            v->whole = proto_ld16(v->mb + 6) != PROTO_FRAME || frame_wanted_whole(v);
            if (v->whole && mb_reserve(v, v->fend)) {
                v->w->oom = 1;
                v->skip = 2;
                return;
            }
        }
    }
}

/* A whole message: binary ones are oceand's. */
static void ws_msg_cb(wslay_event_context_ptr ctx, const struct wslay_event_on_msg_recv_arg *arg, void *user)
{
    (void)ctx;
    dv *v = user;
    if (arg->opcode != WSLAY_BINARY_FRAME || v->state != V_OPEN)
        return;
    if (v->skip) {
        v->decode_errors++;
        close_viewer(v->w, v);
        return;
    }
    on_message(v->w, v, v->mb, v->mlen, v->mtotal, v->w->now);
}

static const struct wslay_event_callbacks ws_callbacks = {
    .recv_callback = ws_recv_cb,
    .send_callback = ws_send_cb,
    .genmask_callback = ws_genmask_cb,
    .on_frame_recv_start_callback = ws_frame_start_cb,
    .on_frame_recv_chunk_callback = ws_frame_chunk_cb,
    .on_msg_recv_callback = ws_msg_cb,
};

/* Sends what wslay has queued; watches for writability while some is left;
 * closes the viewer once wslay reads no more (close received or sent after a
 * protocol error). */
static void ws_pump(worker *w, dv *v)
{
    if (v->state != V_OPEN)
        return;
    if (wslay_event_want_write(v->ws) && wslay_event_send(v->ws) != 0) {
        close_viewer(w, v);
        return;
    }
    if (!wslay_event_want_read(v->ws)) {
        close_viewer(w, v);
        return;
    }
    if (v->hello_seen) {
        v->hello_seen = 0;
        v->ready = 1;
        atomic_fetch_add(&w->S->ready, 1);
    }
    ep_set(w, v, EPOLLIN | (wslay_event_want_write(v->ws) ? EPOLLOUT : 0u));
}

/* Hands the worker's rb to wslay: every complete message goes to
 * on_message.  rb is empty afterwards. */
static void ws_feed(worker *w, dv *v)
{
    int r = wslay_event_recv(v->ws);
    w->rp = w->rl = 0;
    if (v->state != V_OPEN)
        return;                       /* closed from on_message (BYE, send failure) */
    if (r != 0 || (!wslay_event_want_read(v->ws) && !wslay_event_get_close_received(v->ws)))
        v->decode_errors++;           /* framing violation: wslay queued a close */
    ws_pump(w, v);
}

/* Queues one binary message (wslay copies it). */
static int send_msg(worker *w, dv *v, proto_msg *m)
{
    (void)w;
    m->hdr.seq = v->seq++;
    m->hdr.sim_time = isfinite(v->last_sim) ? v->last_sim : 0.0;
    proto_buf b;
    proto_buf_init(&b, 0);
    char err[256];
    ocean_result r = proto_encode(&b, m, err, sizeof err);
    int rc = -1;
    if (r == OCEAN_OK) {
        struct wslay_event_msg wm = {
            .opcode = WSLAY_BINARY_FRAME, .msg = proto_buf_data(&b), .msg_length = proto_buf_len(&b)};
        rc = wslay_event_queue_msg(v->ws, &wm) == 0 ? 0 : -1;
    } else {
        fprintf(stderr, "ocean-client load: cannot encode %s: %s\n", proto_type_name(m->hdr.type), err);
    }
    proto_buf_free(&b);
    return rc;
}

static int queue_camera(worker *w, dv *v)
{
    proto_msg m;
    proto_msg_init(&m, PROTO_CAMERA);
    m.u.camera = v->cam;
    return send_msg(w, v, &m);
}

/* ---- messages ------------------------------------------------------------ */

int load_frame_bad(const oc_frame *f)
{
    int bad = 0;
    /* has_mesh 2 (qz positions): proto_decode checked the payload's header;
     * its positions need the topology, which this reader does not keep */
    if (f->info.has_mesh == 1 && f->info.layout == PROTO_LAYOUT_WORLD && f->info.mesh.vertex_count &&
        !f->info.mesh.positions)
        bad++;
    /* a whole frame without tiles has nothing to read; a time-interpolating
     * one reads the samples its connection holds, and a stream followed
     * wrongly (a frame missed or misapplied) reads nothing there */
    if (f->info.layout == PROTO_LAYOUT_CASCADE && (f->info.tile_count || oc_held_frame_timed(&f->info))) {
        const double *cam = f->info.cascades.camera;
        oc_sample s;
        ocean_result r = oc_frame_sample(f, cam[0], cam[2], 0, &s);
        if (r != OCEAN_OK || !isfinite(s.height))
            bad++;
    }
    return bad;
}

int load_frame_followed_bad(const oc_frame *f, int *fill)
{
    int bad = load_frame_bad(f);
    if (fill && !bad)
        *fill = -1;
    else if (fill && *fill >= 0 && *fill < LOAD_FILL_FRAMES) {
        ++*fill;
        bad = 0;
    }
    return bad;
}

/* Full decode of a FRAME as the client library receives it
 * (oc_frame_decode; through the viewer's stream fs when it follows one,
 * as a client applies every frame on receipt): every record, every tile
 * decoded (the codecs refuse non-finite values), and for layout 1 every
 * tile placed in its cascade's mip grid as the spec lays them out
 * (oc_cascade_view_build); then one point of the sea is read through the
 * lod rule at the frame's camera (load_frame_bad).  0 if all of it held. */
static int verify_frame(oc_frame_stream *fs, int *fill, const uint8_t *p, size_t n)
{
    oc_frame *f = NULL;
    char err[256];
    ocean_result r = fs ? oc_frame_stream_decode(fs, p, n, &f, err, sizeof err)
                        : oc_frame_decode(p, n, &f, err, sizeof err);
    if (r != OCEAN_OK)
        return 1;
    int bad = load_frame_followed_bad(f, fill);
    oc_frame_free(f);
    return bad;
}

/* A FRAME of n bytes, of which p holds the first `have`, received d
 * seconds after its sim time: its head checked, the ticks it skipped
 * counted, and decoded in full when it is one to verify or its viewer
 * follows its stream. */
static void on_frame_message(worker *w, dv *v, const uint8_t *p, size_t have, size_t n, double d)
{
    const shared *S = w->S;
    proto_limits lim;
    proto_limits_default(&lim);
    char err[256];
    int measuring = atomic_load_explicit(&S->measuring, memory_order_relaxed);
    /* fixed fields, and a layout-1 frame's cascade block (its records
     * start after the block): oc_frame_peek reads both from the kept
     * head and checks that n can hold the records it announces */
    proto_frame f;
    if (oc_frame_peek(p, have < n ? have : n, n, &f, NULL, err, sizeof err) != OCEAN_OK ||
        f.tile_count > lim.max_frame_tiles) {
        v->decode_errors++;
        return;
    }
    if (v->have_tick && v->tick_rate > 0) {
        uint32_t dt = f.tick - v->last_tick;
        double step = floor(fmax(1.0, v->tick_rate / S->cfg->sub.frame_rate_hz) + 0.5);
        double missed = floor((double)dt / step + 0.5) - 1;
        if (measuring && missed > 0 && dt < (1u << 30))
            v->skipped += (uint64_t)missed;
    }
    v->last_tick = f.tick;
    v->have_tick = 1;
    if (d < w->min_delay)
        w->min_delay = d;
    /* a followed stream takes every frame, the window's and the ones
     * before it, in order */
    int whole = frame_wanted_whole(v);
    if (whole && v->fs)
        v->decode_errors += (uint64_t)verify_frame(v->fs, &v->fill, p, have);
    if (!measuring)
        return;
    v->frames++;
    v->frames_layout[f.layout]++;
    v->bytes += n;
    if (occli_vec_push(&w->delay, d))
        w->oom = 1;
    if (whole) {
        v->verified++;
        if (!v->fs)
            v->decode_errors += (uint64_t)verify_frame(NULL, NULL, p, have);
    }
    v->nframe++;
}

/* Any other message, whole in p: HELLO answered with SUBSCRIBE and CAMERA,
 * ERROR counted, BYE's reason kept and the viewer closed. */
static void on_other_message(worker *w, dv *v, const uint8_t *p, size_t have)
{
    shared *S = w->S;
    char err[256];
    proto_msg m;
    if (proto_decode(p, have, &m, err, sizeof err) != OCEAN_OK) {
        v->decode_errors++;
        return;
    }
    switch (m.hdr.type) {
    case PROTO_HELLO:
        v->tick_rate = m.u.hello.tick_rate_hz;
        if (!v->ready && !v->hello_seen) {
            /* ready once ws_pump has handed both to the socket */
            proto_msg s;
            proto_msg_init(&s, PROTO_SUBSCRIBE);
            s.u.subscribe = S->cfg->sub;
            if (send_msg(w, v, &s) || queue_camera(w, v)) {
                close_viewer(w, v);
                break;
            }
            v->hello_seen = 1;
        }
        break;
    case PROTO_ERROR:
        v->errors++;
        break;
    case PROTO_BYE:
        if (!atomic_exchange(&S->why_set, 1))
            snprintf(S->why, sizeof S->why, "server said BYE (reason %u): %s", (unsigned)m.u.bye.reason,
                     m.u.bye.message);
        close_viewer(w, v);
        break;
    default:
        break;
    }
    proto_msg_free(&m);
}

/* One binary message of n bytes, of which p holds the first `have`: all of
 * it for every non-FRAME and each FRAME frame_wanted_whole picked, at least
 * the first HEAD_KEEP otherwise. */
static void on_message(worker *w, dv *v, const uint8_t *p, size_t have, size_t n, double now)
{
    proto_limits lim;
    proto_limits_default(&lim);
    proto_header h;
    char err[256];
    /* reads the 32 header bytes only; checks the declared length against n */
    if (have < PROTO_HEADER_SIZE || proto_header_decode(p, n, &lim, &h, err, sizeof err) != OCEAN_OK) {
        v->decode_errors++;
        return;
    }
    double d = now - h.sim_time;
    if (d < w->min_any)
        w->min_any = d;
    v->last_sim = h.sim_time;
    if (h.type == PROTO_FRAME)
        on_frame_message(w, v, p, have, n, d);
    else
        on_other_message(w, v, p, have);
}

/* ---- connection state machine ---------------------------------------------- */

static void start_connect(worker *w, dv *v)
{
    shared *S = w->S;
    atomic_fetch_add(&S->created, 1);
    v->fd = socket(S->sa.ss_family, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (v->fd < 0) {
        close_viewer(w, v);
        return;
    }
    int one = 1;
    setsockopt(v->fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    if (connect(v->fd, (struct sockaddr *)&S->sa, S->salen) < 0 && errno != EINPROGRESS) {
        close_viewer(w, v);
        return;
    }
    v->state = V_TCP;
    struct epoll_event e = {.events = EPOLLOUT | EPOLLIN, .data.ptr = v};
    if (epoll_ctl(w->ep, EPOLL_CTL_ADD, v->fd, &e)) {
        close(v->fd);
        v->fd = -1;
        close_viewer(w, v);
        return;
    }
    v->evmask = e.events;
}

/* Sends the rest of the Upgrade request; -1 on a socket error. */
static int flush_request(worker *w, dv *v)
{
    while (v->olen) {
        ssize_t k = send(v->fd, v->ob, v->olen, MSG_NOSIGNAL);
        if (k < 0) {
            if (errno == EINTR)
                continue;
            if (errno == EAGAIN || errno == EWOULDBLOCK) {
                ep_set(w, v, EPOLLIN | EPOLLOUT);
                return 0;
            }
            return -1;
        }
        memmove(v->ob, v->ob + k, v->olen - (size_t)k);
        v->olen -= (size_t)k;
    }
    ep_set(w, v, EPOLLIN);
    return 0;
}

static void send_handshake(worker *w, dv *v)
{
    const oc_url *u = &w->S->url;
    uint8_t raw[16];
    for (int i = 0; i < 16; i += 4) {
        uint32_t r = rnd32(w);
        memcpy(raw + i, &r, 4);
    }
    lws_b64_encode_string((const char *)raw, 16, v->key, sizeof v->key);
    char req[OC_HOST_MAX + OC_PATH_MAX + 400];
    int n = snprintf(req, sizeof req,
                     "GET %s HTTP/1.1\r\nHost: %s%s%s:%d\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                     "Sec-WebSocket-Key: %s\r\nSec-WebSocket-Version: 13\r\n"
                     "Sec-WebSocket-Protocol: " PROTO_SUBPROTOCOL "\r\n\r\n",
                     u->path, strchr(u->host, ':') ? "[" : "", u->host, strchr(u->host, ':') ? "]" : "",
                     u->port, v->key);
    if (n < 0 || (size_t)n >= sizeof req || !(v->ob = malloc((size_t)n)) || !(v->hb = malloc(HB_MAX + 1))) {
        close_viewer(w, v);
        return;
    }
    memcpy(v->ob, req, (size_t)n);
    v->olen = (size_t)n;
    v->state = V_SHAKE;
    if (flush_request(w, v))
        close_viewer(w, v);
}

/* Value of header `name` in the response head (NUL-terminated), or NULL. */
static const char *find_header(const char *head, const char *name, size_t *vlen)
{
    size_t nl = strlen(name);
    for (const char *l = strstr(head, "\r\n"); l; l = strstr(l, "\r\n")) {
        l += 2;
        if (strncasecmp(l, name, nl) == 0 && l[nl] == ':') {
            const char *s = l + nl + 1;
            while (*s == ' ' || *s == '\t')
                s++;
            const char *e = strstr(s, "\r\n");
            if (!e)
                return NULL;
            while (e > s && (e[-1] == ' ' || e[-1] == '\t'))
                e--;
            *vlen = (size_t)(e - s);
            return s;
        }
    }
    return NULL;
}

/* Once the whole 101 head is in hb: checks it, hands the socket to wslay
 * and gives wslay whatever followed the head. */
static void check_handshake(worker *w, dv *v)
{
    char *end = memmem(v->hb, v->hl, "\r\n\r\n", 4);
    if (!end) {
        if (v->hl >= HB_MAX)
            close_viewer(w, v);
        return;
    }
    size_t hlen = (size_t)(end - v->hb) + 4;
    char saved = v->hb[hlen];
    v->hb[hlen] = 0;                  /* hb has room for it */
    const char *head = v->hb;
    char acc[64], keyg[96];
    unsigned char sha[20];
    snprintf(keyg, sizeof keyg, "%s" WS_GUID, v->key);
    lws_SHA1((const unsigned char *)keyg, strlen(keyg), sha);
    lws_b64_encode_string((const char *)sha, 20, acc, sizeof acc);
    size_t al = 0, pl = 0;
    const char *a = find_header(head, "Sec-WebSocket-Accept", &al);
    const char *p = find_header(head, "Sec-WebSocket-Protocol", &pl);
    int ok = strncmp(head, "HTTP/1.1 101", 12) == 0 && a && al == strlen(acc) && memcmp(a, acc, al) == 0 &&
             p && pl == strlen(PROTO_SUBPROTOCOL) && memcmp(p, PROTO_SUBPROTOCOL, pl) == 0;
    v->hb[hlen] = saved;
    if (!ok || wslay_event_context_client_init(&v->ws, &ws_callbacks, v) != 0) {
        close_viewer(w, v);
        return;
    }
    wslay_event_config_set_no_buffering(v->ws, 1);
    wslay_event_config_set_max_recv_msg_length(v->ws, PROTO_MAX_MESSAGE_DEFAULT);
    free(v->ob);
    v->ob = NULL;
    v->olen = 0;
    v->state = V_OPEN;
    size_t rest = v->hl - hlen;       /* frames that came with the head */
    memcpy(w->rb, v->hb + hlen, rest);
    free(v->hb);
    v->hb = NULL;
    v->hl = 0;
    if (rest) {
        w->rp = 0;
        w->rl = rest;
        ws_feed(w, v);
    }
}

static void on_event(worker *w, dv *v, unsigned ev)
{
    if (v->state == V_TCP) {
        int e = 0;
        socklen_t el = sizeof e;
        if (getsockopt(v->fd, SOL_SOCKET, SO_ERROR, &e, &el) || e || (ev & (EPOLLERR | EPOLLHUP))) {
            close_viewer(w, v);
            return;
        }
        send_handshake(w, v);
        return;
    }
    if (ev & EPOLLOUT) {
        if (v->state == V_SHAKE && v->olen && flush_request(w, v)) {
            close_viewer(w, v);
            return;
        }
        if (v->state == V_OPEN)
            ws_pump(w, v);
        if (v->state == V_DONE)
            return;
    }
    if (!(ev & (EPOLLIN | EPOLLERR | EPOLLHUP)))
        return;
    /* V_SHAKE: hb holds the head so far (check_handshake bounds it);
     * V_OPEN: wslay has taken all of rb by now */
    int shake = v->state == V_SHAKE;
    ssize_t k = shake ? recv(v->fd, v->hb + v->hl, HB_MAX - v->hl, 0) : recv(v->fd, w->rb, RB_SIZE, 0);
    if (k == 0 || (k < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
        close_viewer(w, v);
        return;
    }
    if (k < 0)
        return;
    if (shake) {
        v->hl += (size_t)k;
        check_handshake(w, v);
    } else {
        w->rp = 0;
        w->rl = (size_t)k;
        ws_feed(w, v);
    }
}

static void *worker_main(void *arg)
{
    worker *w = arg;
    shared *S = w->S;
    const load_cfg *cfg = S->cfg;
    struct epoll_event evs[64];
    double last_cam = occli_mono();
    while (!atomic_load(&S->stop)) {
        double mono = occli_mono();
        int timeout = 20;
        while (w->next < w->nv) {
            dv *v = w->v[w->next];
            double due = S->t_start + (cfg->nclients > 1 ? cfg->ramp * v->index / (cfg->nclients - 1) : 0);
            if (due > mono) {
                int ms = (int)ceil((due - mono) * 1e3);
                if (ms < timeout)
                    timeout = ms;
                break;
            }
            start_connect(w, v);
            w->next++;
        }
        int n = epoll_wait(w->ep, evs, 64, timeout);
        w->now = occli_wall();
        for (int i = 0; i < n; i++) {
            dv *v = evs[i].data.ptr;
            if (v->state != V_DONE)
                on_event(w, v, evs[i].events);
        }
        if (cfg->speed > 0 && atomic_load(&S->measuring)) {
            mono = occli_mono();
            if (mono - last_cam >= 0.1) {
                for (int i = 0; i < w->nv; i++) {
                    dv *v = w->v[i];
                    if (v->state != V_OPEN || !v->ready)
                        continue;
                    v->cam.pos[0] += cfg->speed * (mono - last_cam);
                    if (queue_camera(w, v))
                        close_viewer(w, v);
                    else
                        ws_pump(w, v);
                }
                last_cam = mono;
            }
        } else {
            last_cam = occli_mono();
        }
    }
    return NULL;
}

/* The daemon's address from cfg->url (plain ws:// only): 0, or 1 (said). */
static int direct_resolve(const load_cfg *cfg, shared *S)
{
    char err[256];
    if (oc_url_parse(cfg->url, &S->url, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "ocean-client load: %s\n", err);
        return 1;
    }
    if (S->url.tls) {
        fprintf(stderr, "ocean-client load: wss:// needs --library (the direct path speaks plain ws://)\n");
        return 1;
    }
    struct addrinfo hints = {.ai_socktype = SOCK_STREAM}, *ai = NULL;
    char port[16];
    snprintf(port, sizeof port, "%d", S->url.port);
    int g = getaddrinfo(S->url.host, port, &hints, &ai);
    if (g || !ai) {
        fprintf(stderr, "ocean-client load: %s: %s\n", S->url.host, gai_strerror(g));
        return 1;
    }
    memcpy(&S->sa, ai->ai_addr, ai->ai_addrlen);
    S->salen = ai->ai_addrlen;
    freeaddrinfo(ai);
    return 0;
}

/* Viewer i goes to worker i % nt, so the connect ramp is shared evenly;
 * every verify_every-th viewer of a time-interpolating stream follows it.
 * 0, or 1 (said). */
static int direct_viewers_init(const load_cfg *cfg, dv *vs, worker *ws, int nt)
{
    int side = (int)ceil(sqrt((double)cfg->nclients));
    for (int i = 0; i < cfg->nclients; i++) {
        dv *v = &vs[i];
        v->fd = -1;
        v->index = i;
        v->last_sim = NAN;
        load_viewer_place(cfg, i, side, &v->cam);
        v->w = &ws[i % nt];
        if (load_timed(cfg) && i % cfg->verify_every == 0 && oc_frame_stream_create(&v->fs) != OCEAN_OK) {
            fprintf(stderr, "ocean-client load: out of memory\n");
            return 1;
        }
    }
    return 0;
}

/* Each worker's viewers (slots holds them grouped by worker), receive
 * buffer, epoll set and random seed: 0, or 1 (said). */
static int direct_workers_init(const load_cfg *cfg, shared *S, dv *vs, worker *ws, int nt, dv **slots)
{
    int k = 0;
    for (int t = 0; t < nt; t++) {
        worker *w = &ws[t];
        w->S = S;
        w->v = slots + k;
        for (int i = t; i < cfg->nclients; i += nt)
            slots[k++] = &vs[i];
        w->nv = (int)(slots + k - w->v);
        w->min_delay = w->min_any = INFINITY;
        uint64_t seed = 0;
        if (getrandom(&seed, sizeof seed, 0) != sizeof seed)
            seed = (uint64_t)(occli_wall() * 1e9);
        w->rng = seed | 1;
        if (!(w->rb = malloc(RB_SIZE))) {
            fprintf(stderr, "ocean-client load: out of memory\n");
            return 1;
        }
        w->ep = epoll_create1(EPOLL_CLOEXEC);
        if (w->ep < 0) {
            fprintf(stderr, "ocean-client load: epoll: %s\n", strerror(errno));
            return 1;
        }
    }
    return 0;
}

/* While the workers run: every viewer connected (or failed), then the
 * warm-up, then the measured window; the workers are told to stop. */
static void direct_window(const load_cfg *cfg, shared *S, load_result *R)
{
    double deadline = S->t_start + cfg->ramp + cfg->timeout_ms * 1e-3;
    while (!occli_stop && occli_mono() < deadline &&
           atomic_load(&S->ready) + atomic_load(&S->failed) < cfg->nclients)
        occli_sleep(0.01);
    if (atomic_load(&S->ready) < cfg->nclients)
        fprintf(stderr, "ocean-client load: only %d of %d viewers connected\n", atomic_load(&S->ready),
                cfg->nclients);
    double warm_end = occli_mono() + cfg->warmup;
    while (!occli_stop && occli_mono() < warm_end)
        occli_sleep(0.01);
    double c0 = load_cpu_seconds(), m0 = occli_mono();
    atomic_store(&S->measuring, 1);
    while (!occli_stop && occli_mono() < m0 + cfg->seconds)
        occli_sleep(0.005);
    atomic_store(&S->measuring, 0);
    R->wall = occli_mono() - m0;
    R->cpu = load_cpu_seconds() - c0;
    atomic_store(&S->stop, 1);
}

/* Sums the viewers' counts into R, after the join. */
static void direct_collect_viewers(const load_cfg *cfg, const dv *vs, load_result *R)
{
    R->fmin = UINT64_MAX;
    for (int i = 0; i < cfg->nclients; i++) {
        const dv *v = &vs[i];
        R->frames += v->frames;
        R->bytes += v->bytes;
        R->skipped += v->skipped;
        R->errors += v->errors;
        R->decode_errors += v->decode_errors;
        R->verified += v->verified;
        R->frames_layout[0] += v->frames_layout[0];
        R->frames_layout[1] += v->frames_layout[1];
        R->closed += v->closed;
        R->followed += v->ready && v->fs;
        if (v->ready) {
            if (v->frames < R->fmin)
                R->fmin = v->frames;
            if (v->frames > R->fmax)
                R->fmax = v->frames;
        }
    }
    if (R->fmin == UINT64_MAX)
        R->fmin = 0;
}

/* Merges the raw samples of every thread; the zero point is the global
 * minimum. */
static void direct_collect_delays(worker *ws, int nt, load_result *R)
{
    for (int t = 0; t < nt; t++) {
        worker *w = &ws[t];
        if (w->min_delay < R->min_delay)
            R->min_delay = w->min_delay;
        if (w->min_any < R->min_any)
            R->min_any = w->min_any;
        for (size_t i = 0; i < w->delay.n; i++)
            if (occli_vec_push(&R->delay, w->delay.v[i]))
                w->oom = 1;
        if (w->oom)
            fprintf(stderr, "ocean-client load: out of memory in a worker; figures are incomplete\n");
    }
}

static void direct_free(const load_cfg *cfg, dv *vs, worker *ws, int nt, dv **slots)
{
    for (int i = 0; vs && i < cfg->nclients; i++) {
        dv *v = &vs[i];
        if (v->fd >= 0) {
            /* a best-effort close 1000; the socket goes either way */
            if (v->ws && v->state == V_OPEN && wslay_event_queue_close(v->ws, WSLAY_CODE_NORMAL_CLOSURE, NULL, 0) == 0)
                wslay_event_send(v->ws);
            close(v->fd);
        }
        wslay_event_context_free(v->ws);
        oc_frame_stream_destroy(v->fs);
        free(v->hb);
        free(v->mb);
        free(v->ob);
    }
    for (int t = 0; ws && t < nt; t++) {
        if (ws[t].ep > 0)
            close(ws[t].ep);
        occli_vec_free(&ws[t].delay);
        free(ws[t].rb);
    }
    free(slots);
    free(ws);
    free(vs);
}

int load_direct_run(const load_cfg *cfg, load_result *R)
{
    memset(R, 0, sizeof *R);
    R->min_delay = R->min_any = INFINITY;
    shared S;
    memset(&S, 0, sizeof S);
    S.cfg = cfg;
    if (direct_resolve(cfg, &S))
        return 1;
    int nt = cfg->threads < 1 ? 1 : cfg->threads;
    if (nt > cfg->nclients)
        nt = cfg->nclients;
    dv *vs = calloc((size_t)cfg->nclients, sizeof *vs);
    worker *ws = calloc((size_t)nt, sizeof *ws);
    dv **slots = calloc((size_t)cfg->nclients, sizeof *slots);
    if (!vs || !ws || !slots) {
        fprintf(stderr, "ocean-client load: out of memory\n");
        direct_free(cfg, vs, ws, nt, slots);
        return 1;
    }
    if (direct_viewers_init(cfg, vs, ws, nt) || direct_workers_init(cfg, &S, vs, ws, nt, slots)) {
        direct_free(cfg, vs, ws, nt, slots);
        return 1;
    }
    int rc = 0, started = 0;
    S.t_start = occli_mono();
    for (int t = 0; t < nt; t++) {
        if (pthread_create(&ws[t].th, NULL, worker_main, &ws[t])) {
            fprintf(stderr, "ocean-client load: cannot start worker threads\n");
            atomic_store(&S.stop, 1);
            rc = 1;
            break;
        }
        started++;
    }
    if (!rc)
        direct_window(cfg, &S, R);
    for (int t = 0; t < started; t++)
        pthread_join(ws[t].th, NULL);
    R->created = atomic_load(&S.created);
    R->ready = atomic_load(&S.ready);
    if (atomic_load(&S.why_set))
        snprintf(R->why, sizeof R->why, "%s", S.why);
    direct_collect_viewers(cfg, vs, R);
    direct_collect_delays(ws, nt, R);
    direct_free(cfg, vs, ws, nt, slots);
    return rc;
}
