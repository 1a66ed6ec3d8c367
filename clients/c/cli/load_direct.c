/*
 * load_direct.c - the load generator's default receive path: N viewers over
 * T worker threads, each thread one epoll loop over plain non-blocking
 * sockets speaking just enough RFC 6455 to be a client of oceand (opening
 * handshake with Sec-WebSocket-Accept checked, masked client frames,
 * unmasked server frames read in bulk, fragments, ping, close).  See
 * load_run.h for why the client library is not used here.
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

#include "codec.h"

#define RB_INIT (256u << 10)
#define WS_GUID "258EAFA5-E914-47DA-95CA-C5AB0DC85B11"

enum { V_IDLE, V_TCP, V_SHAKE, V_OPEN, V_DONE };

typedef struct dv {
    int fd, state, index, ready, closed;
    char key[32];
    uint8_t *rb;                 /* receive buffer: [rp, rl) unparsed */
    size_t rcap, rp, rl;
    uint8_t *mb;                 /* fragmented message being assembled */
    size_t mlen, mcap;
    int mop;
    uint8_t *ob;                 /* bytes not yet sent */
    size_t olen, ocap;
    uint32_t seq;
    double last_sim;
    float tick_rate;
    uint32_t last_tick;
    int have_tick;
    uint64_t frames, bytes, skipped, errors, decode_errors, verified, nframe;
    proto_camera cam;
} dv;

typedef struct shared {
    const load_cfg *cfg;
    struct sockaddr_storage sa;
    socklen_t salen;
    oc_url url;
    double t_start;
    atomic_int ready, failed, created, measuring, stop;
} shared;

typedef struct worker {
    shared *S;
    pthread_t th;
    int ep;
    dv **v;
    int nv, next;               /* viewers; next one to connect */
    occli_vec delay;
    double min_delay;           /* over FRAMEs */
    double min_any;             /* over every message, HELLO included */
    uint64_t rng;
    float *scratch;
    size_t scratch_n;
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

static int ensure(uint8_t **b, size_t *cap, size_t need)
{
    if (need <= *cap)
        return 0;
    size_t nc = *cap ? *cap : 4096;
    while (nc < need)
        nc *= 2;
    uint8_t *nb = realloc(*b, nc);
    if (!nb)
        return -1;
    *b = nb;
    *cap = nc;
    return 0;
}

static void ep_mod(worker *w, dv *v, unsigned ev)
{
    struct epoll_event e = {.events = ev, .data.ptr = v};
    epoll_ctl(w->ep, EPOLL_CTL_MOD, v->fd, &e);
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

static int flush_out(worker *w, dv *v)
{
    while (v->olen) {
        ssize_t k = send(v->fd, v->ob, v->olen, MSG_NOSIGNAL);
        if (k < 0) {
            if (errno == EINTR)
                continue;
            if (errno == EAGAIN || errno == EWOULDBLOCK) {
                ep_mod(w, v, EPOLLIN | EPOLLOUT);
                return 0;
            }
            return -1;
        }
        memmove(v->ob, v->ob + k, v->olen - (size_t)k);
        v->olen -= (size_t)k;
    }
    if (v->state == V_OPEN)
        ep_mod(w, v, EPOLLIN);
    return 0;
}

/* Queues one masked client frame (RFC 6455 5.3) and tries to send it. */
static int send_frame(worker *w, dv *v, int opcode, const uint8_t *p, size_t n)
{
    uint8_t h[14];
    size_t hl = 0;
    h[hl++] = (uint8_t)(0x80 | opcode);
    if (n < 126) {
        h[hl++] = (uint8_t)(0x80 | n);
    } else if (n < 65536) {
        h[hl++] = 0x80 | 126;
        h[hl++] = (uint8_t)(n >> 8);
        h[hl++] = (uint8_t)n;
    } else {
        h[hl++] = 0x80 | 127;
        for (int i = 7; i >= 0; i--)
            h[hl++] = (uint8_t)((uint64_t)n >> (8 * i));
    }
    uint32_t mk = rnd32(w);
    uint8_t mask[4] = {(uint8_t)mk, (uint8_t)(mk >> 8), (uint8_t)(mk >> 16), (uint8_t)(mk >> 24)};
    memcpy(h + hl, mask, 4);
    hl += 4;
    if (ensure(&v->ob, &v->ocap, v->olen + hl + n))
        return -1;
    memcpy(v->ob + v->olen, h, hl);
    uint8_t *d = v->ob + v->olen + hl;
    for (size_t i = 0; i < n; i++)
        d[i] = p[i] ^ mask[i & 3];
    v->olen += hl + n;
    return flush_out(w, v);
}

static int send_msg(worker *w, dv *v, proto_msg *m)
{
    m->hdr.seq = v->seq++;
    m->hdr.sim_time = isfinite(v->last_sim) ? v->last_sim : 0.0;
    proto_buf b;
    proto_buf_init(&b, 0);
    char err[256];
    ocean_result r = proto_encode(&b, m, err, sizeof err);
    int rc = r == OCEAN_OK ? send_frame(w, v, 2, proto_buf_data(&b), proto_buf_len(&b)) : -1;
    if (r != OCEAN_OK)
        fprintf(stderr, "ocean-client load: cannot encode %s: %s\n", proto_type_name(m->hdr.type), err);
    proto_buf_free(&b);
    return rc;
}

static void send_camera(worker *w, dv *v)
{
    proto_msg m;
    proto_msg_init(&m, PROTO_CAMERA);
    m.u.camera = v->cam;
    if (send_msg(w, v, &m))
        close_viewer(w, v);
}

/* ---- messages ------------------------------------------------------------ */

/* Full decode of a FRAME, tiles included; 0 if everything decoded. */
static int verify_frame(worker *w, const uint8_t *p, size_t n)
{
    proto_msg m;
    char err[256];
    if (proto_decode(p, n, &m, err, sizeof err) != OCEAN_OK)
        return 1;
    int bad = 0;
    const proto_frame *f = &m.u.frame;
    for (unsigned i = 0; i < f->tile_count; i++) {
        const proto_tile *t = &f->tiles[i];
        size_t cnt = (size_t)proto_tile_planes(t->channels) * t->width * t->height;
        if (cnt > w->scratch_n) {
            float *s = realloc(w->scratch, cnt * sizeof *s);
            if (!s) {
                bad++;
                continue;
            }
            w->scratch = s;
            w->scratch_n = cnt;
        }
        if (proto_tile_decode((proto_codec)t->codec, t->width, t->height, t->channels, t->payload,
                              t->payload_len, w->scratch, NULL, 0) != OCEAN_OK)
            bad++;
        else
            for (size_t k = 0; k < cnt; k++)
                if (!isfinite(w->scratch[k])) {
                    bad++;
                    break;
                }
    }
    if (f->has_mesh && f->mesh.vertex_count && !f->mesh.positions)
        bad++;
    proto_msg_free(&m);
    return bad;
}

static void on_message(worker *w, dv *v, const uint8_t *p, size_t n, double now)
{
    const shared *S = w->S;
    proto_limits lim;
    proto_limits_default(&lim);
    proto_header h;
    char err[256];
    if (proto_header_decode(p, n, &lim, &h, err, sizeof err) != OCEAN_OK) {
        v->decode_errors++;
        return;
    }
    double d = now - h.sim_time;
    if (d < w->min_any)
        w->min_any = d;
    v->last_sim = h.sim_time;
    int measuring = atomic_load_explicit(&w->S->measuring, memory_order_relaxed);
    if (h.type == PROTO_FRAME) {
        if (n < PROTO_HEADER_SIZE + 56) {
            v->decode_errors++;
            return;
        }
        proto_frame f;
        proto_frame_fixed_read(p + PROTO_HEADER_SIZE, &f);
        if (isnan(f.cutoff_k) || f.cutoff_k < 0 || !(f.e_error >= 0 && f.e_error <= 1) || f.has_mesh > 1 ||
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
        if (!measuring)
            return;
        v->frames++;
        v->bytes += n;
        if (occli_vec_push(&w->delay, d))
            w->oom = 1;
        if ((v->nframe++ + (uint64_t)v->index) % (uint64_t)S->cfg->verify_every == 0) {
            v->verified++;
            v->decode_errors += (uint64_t)verify_frame(w, p, n);
        }
        return;
    }
    proto_msg m;
    if (proto_decode(p, n, &m, err, sizeof err) != OCEAN_OK) {
        v->decode_errors++;
        return;
    }
    switch (h.type) {
    case PROTO_HELLO:
        v->tick_rate = m.u.hello.tick_rate_hz;
        if (!v->ready) {
            proto_msg s;
            proto_msg_init(&s, PROTO_SUBSCRIBE);
            s.u.subscribe = S->cfg->sub;
            if (send_msg(w, v, &s)) {
                close_viewer(w, v);
                break;
            }
            send_camera(w, v);
            if (v->state == V_OPEN) {
                v->ready = 1;
                atomic_fetch_add(&w->S->ready, 1);
            }
        }
        break;
    case PROTO_ERROR:
        v->errors++;
        break;
    case PROTO_BYE:
        close_viewer(w, v);
        break;
    default:
        break;
    }
    proto_msg_free(&m);
}

/* Parses every complete frame in [rp, rl). */
static void parse_frames(worker *w, dv *v, double now)
{
    while (v->state == V_OPEN && v->rl - v->rp >= 2) {
        const uint8_t *b = v->rb + v->rp;
        size_t avail = v->rl - v->rp, hl = 2;
        int fin = b[0] >> 7, op = b[0] & 15;
        uint64_t len = b[1] & 127;
        if ((b[0] & 0x70) || (b[1] & 0x80)) {   /* no extensions; server frames are unmasked */
            v->decode_errors++;
            close_viewer(w, v);
            return;
        }
        if (len == 126) {
            if (avail < 4)
                break;
            len = (uint64_t)b[2] << 8 | b[3];
            hl = 4;
        } else if (len == 127) {
            if (avail < 10)
                break;
            len = 0;
            for (int i = 0; i < 8; i++)
                len = len << 8 | b[2 + i];
            hl = 10;
        }
        if (len > PROTO_MAX_MESSAGE_DEFAULT) {
            v->decode_errors++;
            close_viewer(w, v);
            return;
        }
        if (avail < hl + len) {
            /* make room for the whole frame: move it to the front, grow */
            size_t need = hl + (size_t)len;
            if (v->rp && need > v->rcap - v->rp) {
                memmove(v->rb, v->rb + v->rp, avail);
                v->rl = avail;
                v->rp = 0;
            }
            if (ensure(&v->rb, &v->rcap, need)) {
                w->oom = 1;
                close_viewer(w, v);
            }
            return;
        }
        const uint8_t *pl = b + hl;
        v->rp += hl + (size_t)len;
        if (op >= 8) {                       /* control */
            if (op == 9)
                send_frame(w, v, 10, pl, (size_t)len);
            else if (op == 8) {
                send_frame(w, v, 8, pl, len >= 2 ? 2 : 0);
                close_viewer(w, v);
                return;
            }
            continue;
        }
        if (op != 0 && fin) {                /* the usual case: one frame, one message */
            if (op == 2)
                on_message(w, v, pl, (size_t)len, now);
            continue;
        }
        if (op != 0) {
            v->mop = op;
            v->mlen = 0;
        }
        if (ensure(&v->mb, &v->mcap, v->mlen + (size_t)len)) {
            w->oom = 1;
            close_viewer(w, v);
            return;
        }
        memcpy(v->mb + v->mlen, pl, (size_t)len);
        v->mlen += (size_t)len;
        if (fin) {
            if (v->mop == 2)
                on_message(w, v, v->mb, v->mlen, now);
            v->mlen = 0;
        }
    }
    if (v->rp == v->rl)
        v->rp = v->rl = 0;
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
    }
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
    if (ensure(&v->ob, &v->ocap, v->olen + (size_t)n)) {
        close_viewer(w, v);
        return;
    }
    memcpy(v->ob + v->olen, req, (size_t)n);
    v->olen += (size_t)n;
    v->state = V_SHAKE;
    ep_mod(w, v, EPOLLIN);
    if (flush_out(w, v))
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

static void check_handshake(worker *w, dv *v)
{
    uint8_t *end = memmem(v->rb, v->rl, "\r\n\r\n", 4);
    if (!end) {
        if (v->rl > 16384)
            close_viewer(w, v);
        return;
    }
    size_t hlen = (size_t)(end - v->rb) + 4;
    char *head = malloc(hlen + 1);
    if (!head) {
        close_viewer(w, v);
        return;
    }
    memcpy(head, v->rb, hlen);
    head[hlen] = 0;
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
    free(head);
    if (!ok) {
        close_viewer(w, v);
        return;
    }
    v->rp = hlen;
    v->state = V_OPEN;
}

static void on_event(worker *w, dv *v, unsigned ev, double now)
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
    if ((ev & EPOLLOUT) && v->olen && flush_out(w, v)) {
        close_viewer(w, v);
        return;
    }
    if (!(ev & (EPOLLIN | EPOLLERR | EPOLLHUP)))
        return;
    if (v->rl == v->rcap) {
        if (v->rp) {
            memmove(v->rb, v->rb + v->rp, v->rl - v->rp);
            v->rl -= v->rp;
            v->rp = 0;
        } else if (ensure(&v->rb, &v->rcap, v->rcap * 2)) {
            w->oom = 1;
            close_viewer(w, v);
            return;
        }
    }
    ssize_t k = recv(v->fd, v->rb + v->rl, v->rcap - v->rl, 0);
    if (k == 0 || (k < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
        close_viewer(w, v);
        return;
    }
    if (k < 0)
        return;
    v->rl += (size_t)k;
    if (v->state == V_SHAKE)
        check_handshake(w, v);
    if (v->state == V_OPEN)
        parse_frames(w, v, now);
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
        double now = occli_wall();
        for (int i = 0; i < n; i++) {
            dv *v = evs[i].data.ptr;
            if (v->state != V_DONE)
                on_event(w, v, evs[i].events, now);
        }
        if (cfg->speed > 0 && atomic_load(&S->measuring)) {
            mono = occli_mono();
            if (mono - last_cam >= 0.1) {
                for (int i = 0; i < w->nv; i++) {
                    dv *v = w->v[i];
                    if (v->state != V_OPEN || !v->ready)
                        continue;
                    v->cam.pos[0] += cfg->speed * (mono - last_cam);
                    send_camera(w, v);
                }
                last_cam = mono;
            }
        } else {
            last_cam = occli_mono();
        }
    }
    return NULL;
}

static double cpu_now(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
           1e-6 * (double)ru.ru_stime.tv_usec;
}

int load_direct_run(const load_cfg *cfg, load_result *R)
{
    memset(R, 0, sizeof *R);
    R->min_delay = R->min_any = INFINITY;
    shared S;
    memset(&S, 0, sizeof S);
    S.cfg = cfg;
    char err[256];
    if (oc_url_parse(cfg->url, &S.url, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "ocean-client load: %s\n", err);
        return 1;
    }
    if (S.url.tls) {
        fprintf(stderr, "ocean-client load: wss:// needs --library (the direct path speaks plain ws://)\n");
        return 1;
    }
    struct addrinfo hints = {.ai_socktype = SOCK_STREAM}, *ai = NULL;
    char port[16];
    snprintf(port, sizeof port, "%d", S.url.port);
    int g = getaddrinfo(S.url.host, port, &hints, &ai);
    if (g || !ai) {
        fprintf(stderr, "ocean-client load: %s: %s\n", S.url.host, gai_strerror(g));
        return 1;
    }
    memcpy(&S.sa, ai->ai_addr, ai->ai_addrlen);
    S.salen = ai->ai_addrlen;
    freeaddrinfo(ai);

    int nt = cfg->threads < 1 ? 1 : cfg->threads;
    if (nt > cfg->nclients)
        nt = cfg->nclients;
    dv *vs = calloc((size_t)cfg->nclients, sizeof *vs);
    worker *ws = calloc((size_t)nt, sizeof *ws);
    dv **slots = calloc((size_t)cfg->nclients, sizeof *slots);
    int rc = 0, started = 0;
    if (!vs || !ws || !slots) {
        fprintf(stderr, "ocean-client load: out of memory\n");
        rc = 1;
        goto out;
    }
    int side = (int)ceil(sqrt((double)cfg->nclients));
    for (int i = 0; i < cfg->nclients; i++) {
        dv *v = &vs[i];
        v->fd = -1;
        v->index = i;
        v->last_sim = NAN;
        v->cam = cfg->cam0;
        v->cam.pos[0] += cfg->spread * (i % side);
        v->cam.pos[2] += cfg->spread * (i / side);
        v->cam.vel[0] = (float)(v->cam.vel[0] + cfg->speed);
        if (ensure(&v->rb, &v->rcap, RB_INIT)) {
            fprintf(stderr, "ocean-client load: out of memory\n");
            rc = 1;
            goto out;
        }
    }
    /* viewer i goes to worker i % nt, so the connect ramp is shared evenly */
    int k = 0;
    for (int t = 0; t < nt; t++) {
        worker *w = &ws[t];
        w->S = &S;
        w->v = slots + k;
        for (int i = t; i < cfg->nclients; i += nt)
            slots[k++] = &vs[i];
        w->nv = (int)(slots + k - w->v);
        w->min_delay = w->min_any = INFINITY;
        uint64_t seed = 0;
        if (getrandom(&seed, sizeof seed, 0) != sizeof seed)
            seed = (uint64_t)(occli_wall() * 1e9);
        w->rng = seed | 1;
        w->ep = epoll_create1(EPOLL_CLOEXEC);
        if (w->ep < 0) {
            fprintf(stderr, "ocean-client load: epoll: %s\n", strerror(errno));
            rc = 1;
            goto out;
        }
    }
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
    if (!rc) {
        /* every viewer connected (or failed), then the warm-up, then the window */
        double deadline = S.t_start + cfg->ramp + cfg->timeout_ms * 1e-3;
        while (!occli_stop && occli_mono() < deadline &&
               atomic_load(&S.ready) + atomic_load(&S.failed) < cfg->nclients)
            occli_sleep(0.01);
        if (atomic_load(&S.ready) < cfg->nclients)
            fprintf(stderr, "ocean-client load: only %d of %d viewers connected\n", atomic_load(&S.ready),
                    cfg->nclients);
        double warm_end = occli_mono() + cfg->warmup;
        while (!occli_stop && occli_mono() < warm_end)
            occli_sleep(0.01);
        double c0 = cpu_now(), m0 = occli_mono();
        atomic_store(&S.measuring, 1);
        while (!occli_stop && occli_mono() < m0 + cfg->seconds)
            occli_sleep(0.005);
        atomic_store(&S.measuring, 0);
        R->wall = occli_mono() - m0;
        R->cpu = cpu_now() - c0;
        atomic_store(&S.stop, 1);
    }
    for (int t = 0; t < started; t++)
        pthread_join(ws[t].th, NULL);
    R->created = atomic_load(&S.created);
    R->ready = atomic_load(&S.ready);
    R->fmin = UINT64_MAX;
    for (int i = 0; i < cfg->nclients; i++) {
        dv *v = &vs[i];
        R->frames += v->frames;
        R->bytes += v->bytes;
        R->skipped += v->skipped;
        R->errors += v->errors;
        R->decode_errors += v->decode_errors;
        R->verified += v->verified;
        R->closed += v->closed;
        if (v->ready) {
            if (v->frames < R->fmin)
                R->fmin = v->frames;
            if (v->frames > R->fmax)
                R->fmax = v->frames;
        }
    }
    if (R->fmin == UINT64_MAX)
        R->fmin = 0;
    /* merge the raw samples of every thread; the zero point is the global minimum */
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
out:
    for (int i = 0; vs && i < cfg->nclients; i++) {
        dv *v = &vs[i];
        if (v->fd >= 0) {
            static const uint8_t bye[2] = {0x03, 0xE8};   /* close 1000 */
            uint8_t fr[8] = {0x88, 0x82, 0, 0, 0, 0, bye[0], bye[1]};
            if (send(v->fd, fr, sizeof fr, MSG_NOSIGNAL | MSG_DONTWAIT) < 0) { /* closing anyway */ }
            close(v->fd);
        }
        free(v->rb);
        free(v->mb);
        free(v->ob);
    }
    for (int t = 0; ws && t < nt; t++) {
        if (ws[t].ep > 0)
            close(ws[t].ep);
        occli_vec_free(&ws[t].delay);
        free(ws[t].scratch);
    }
    free(slots);
    free(ws);
    free(vs);
    return rc;
}
