/*
 * srv_net.c - the libwebsockets service thread (see srv_net.h): the one
 * thread that owns every connection, from the upgrade's checks to the last
 * byte sent, and the limits that keep one connection from hurting the
 * others.  Each connection's own state is its session (srv_session.h).
 */
#include "srv_net.h"

#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <libwebsockets.h>
#include <math.h>
#include <pthread.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include "ocean_time.h"
#include "srv_admit.h"
#include "srv_handle.h"
#include "srv_session.h"
#include "srv_record.h"

/* File descriptors kept free of client connections: the HTTP pages, the
 * handshakes in progress, recordings, FFTW and the log.  max_clients is
 * clamped to the fd limit minus this; accept refuses above it minus
 * FD_ACCEPT_SLACK, so the process itself never runs out. */
#define FD_RESERVE 96
#define FD_ACCEPT_SLACK 32
/* Longest file path libwebsockets 4.1.6 serves from a file mount: it
 * writes origin "/" uri into char path[256] with lws_snprintf(path,
 * sizeof path - 1, ...), so 254 characters, the rest cut off. */
#define SRV_LWS_FILE_PATH_MAX 254

/* ---- RFC 6455 guard ------------------------------------------------------------
 *
 * libwebsockets 4.1.6 does not check two things a server MUST (RFC 6455
 * 5.1: a server MUST close the connection upon receiving a frame that is
 * not masked; 7.4.1 / 7.4.2: close codes outside 1000-1003, 1007-1011 (and
 * the IANA-registered 1012-1014) and 3000-4999 are a protocol error), and
 * it offers no hook where the frame header is visible.  So the daemon reads
 * the frame headers itself on the way in: recv() is interposed (the
 * executable's definition wins over libc's for libwebsockets' calls) and,
 * for a socket registered as an ocean.v1 connection, the received bytes go
 * through a small frame-header parser before libwebsockets sees them.  A
 * violation is turned into one libwebsockets already answers with close
 * 1002, in the bytes it is about to parse: an unmasked frame gets its RSV1
 * bit set ("rsv bits"), an invalid close code becomes 999.  When the byte
 * to change has already been handed over (a header split across reads) the
 * connection is flagged and closed with 1002 from the callback.  Sockets
 * not registered, and every other byte, pass untouched.
 *
 * A client that sends frames before the server's 101 (RFC 6455 4.1 forbids
 * it) may have its first frames parsed before registration; its tracker
 * then starts mid-stream and may read a violation where there is none:
 * such a client is closed with 1002, which it earned. */

/* TRK_DONE: a violation was found; the connection is over, the tracker
 * reads no more of it but stays its owner's, so the callbacks still see
 * `bad` (clearing the owner there let a flagged connection run on). */
enum { TRK_HDR0, TRK_HDR1, TRK_LEN, TRK_MASK, TRK_PAYLOAD, TRK_DONE };

typedef struct ws_track {
    const void *owner;       /* the wsi that registered this fd; NULL: not tracked */
    uint8_t state, opcode;
    uint8_t need, have;      /* extended length / mask bytes */
    uint64_t len, left;      /* payload length and bytes still to come */
    uint8_t mask[4];
    uint8_t ctl[125];        /* a close frame's payload, unmasked */
    double frame_t;          /* srv_now() at the unfinished frame's first byte; 0: none.
                                Written here, read by the sweep (both [svc]) */
    atomic_int bad;          /* 1: 1002 owed by the callbacks; 2: lws sends it (a
                                byte rewritten here); set here, read by the callbacks */
} ws_track;

static ws_track *trk;        /* indexed by fd; never freed (one per process) */
static int trk_n;
static pthread_mutex_t trk_lock = PTHREAD_MUTEX_INITIALIZER;

static void trk_init(int n)
{
    pthread_mutex_lock(&trk_lock);
    if (!trk && n > 0) {
        trk = calloc((size_t)n, sizeof *trk);
        if (trk) trk_n = n;
    }
    pthread_mutex_unlock(&trk_lock);
}

static ws_track *trk_of(int fd) { return trk && fd >= 0 && fd < trk_n ? &trk[fd] : NULL; }

static void trk_register(struct lws *wsi)
{
    ws_track *t = trk_of(lws_get_socket_fd(wsi));
    if (!t) return;
    memset(t, 0, sizeof *t);
    t->owner = wsi;
}

static void trk_forget(struct lws *wsi)
{
    ws_track *t = trk_of(lws_get_socket_fd(wsi));
    if (t && t->owner == wsi) t->owner = NULL;
}

/* 1 if the close frame payload p[0..n) breaks RFC 6455 7.4. */
static int close_code_bad(const uint8_t *p, size_t n)
{
    if (n == 0) return 0;
    if (n == 1) return 1;
    unsigned code = (unsigned)p[0] << 8 | p[1];
    if (code < 1000 || code >= 5000) return 1;
    if (code >= 1004 && code <= 1006) return 1;
    if (code >= 1015 && code < 3000) return 1;
    return 0;
}

/* Feeds the bytes of one recv() through the tracker; may rewrite them. */
static void trk_feed(ws_track *t, uint8_t *b, size_t n)
{
    long hdr0_at = -1;                     /* this frame's first byte, if in b */
    long code_at[2] = {-1, -1};            /* a close frame's code bytes, if in b */
    for (size_t i = 0; i < n && t->owner && t->state != TRK_DONE;) {
        switch (t->state) {
        case TRK_HDR0:
            t->opcode = b[i] & 0x0f;
            t->frame_t = srv_now();
            hdr0_at = (long)i;
            code_at[0] = code_at[1] = -1;
            t->state = TRK_HDR1;
            i++;
            break;
        case TRK_HDR1: {
            int masked = (b[i] & 0x80) != 0;
            unsigned l7 = b[i] & 0x7f;
            i++;
            /* RFC 6455 5.1: the server MUST close the connection on an
             * unmasked frame; 5.5.1: a close body is empty or starts with a
             * two-byte code, so one byte is malformed (lws answers that with
             * an empty close) */
            if (!masked || (t->opcode == 8 && l7 == 1)) {
                if (hdr0_at >= 0) {
                    b[hdr0_at] |= 0x40;            /* lws: 1002 "rsv bits" */
                    atomic_store(&t->bad, 2);
                } else {
                    atomic_store(&t->bad, 1);
                }
                t->state = TRK_DONE;               /* the connection is over */
                break;
            }
            t->len = l7;
            t->need = l7 == 126 ? 2 : l7 == 127 ? 8 : 0;
            t->have = 0;
            if (t->need) t->len = 0;
            t->state = t->need ? TRK_LEN : TRK_MASK;
            break;
        }
        case TRK_LEN:
            t->len = t->len << 8 | b[i++];
            if (++t->have == t->need) {
                t->have = 0;
                t->state = TRK_MASK;
            }
            break;
        case TRK_MASK:
            t->mask[t->have++] = b[i++];
            if (t->have == 4) {
                t->have = 0;
                t->left = t->len;
                t->state = t->left ? TRK_PAYLOAD : TRK_HDR0;
                if (!t->left) t->frame_t = 0;
            }
            break;
        case TRK_PAYLOAD: {
            uint64_t take = t->left < n - i ? t->left : n - i;
            if (t->opcode == 8 && t->len <= sizeof t->ctl) {
                for (uint64_t k = 0; k < take; k++) {
                    size_t at = (size_t)(t->len - t->left + k);
                    t->ctl[at] = b[i + k] ^ t->mask[at & 3];
                    if (at < 2) code_at[at] = (long)(i + k);
                }
            }
            i += take;
            t->left -= take;
            if (t->left == 0) {
                if (t->opcode == 8 && close_code_bad(t->ctl, (size_t)t->len)) {
                    if (t->len >= 2 && code_at[0] >= 0 && code_at[1] >= 0) {
                        /* 999: a code lws refuses with 1002 itself */
                        b[code_at[0]] = 0x03 ^ t->mask[0];
                        b[code_at[1]] = 0xe7 ^ t->mask[1];
                        atomic_store(&t->bad, 2);
                    } else if (t->len >= 2) {
                        atomic_store(&t->bad, 1);
                    }
                }
                t->state = TRK_HDR0;
                t->frame_t = 0;
            }
            break;
        }
        case TRK_DONE:
            break;
        }
    }
}

typedef ssize_t (*recv_fn)(int, void *, size_t, int);
typedef int (*accept_fn)(int, struct sockaddr *, socklen_t *);
static _Atomic(recv_fn) real_recv;
static _Atomic(accept_fn) real_accept;

ssize_t recv(int fd, void *buf, size_t len, int flags)
{
    recv_fn real = atomic_load(&real_recv);
    if (!real) {
        real = (recv_fn)dlsym(RTLD_NEXT, "recv");
        atomic_store(&real_recv, real);
    }
    ssize_t r = real(fd, buf, len, flags);
    ws_track *t;
    if (r > 0 && !(flags & MSG_PEEK) && (t = trk_of(fd)) && t->owner) trk_feed(t, buf, (size_t)r);
    return r;
}

/* ---- accept: never spin on EMFILE --------------------------------------------
 *
 * lws 4.1.6 logs and returns on an accept() failure, and the listening
 * socket, still readable, brings it straight back: one core spinning and a
 * log line per turn.  accept() is interposed as recv() is: a connection
 * that would take one of the last FD_ACCEPT_SLACK descriptors is closed at
 * once, and on EMFILE / ENFILE a spare descriptor is given up to accept the
 * pending connection and close it (the nginx / libev way), so the backlog
 * drains instead of spinning; either way lws sees EAGAIN, and the log gets
 * one line a second with a count. */

static int fd_limit;          /* soft RLIMIT_NOFILE after raising; 0: unknown */
static int spare_fd = -1;
static atomic_uint_fast64_t *accept_refused_ctr;
static double accept_log_t;
static unsigned accept_log_n;

static void accept_note(const char *why)
{
    if (accept_refused_ctr) atomic_fetch_add(accept_refused_ctr, 1);
    accept_log_n++;
    double now = srv_now();
    if (now - accept_log_t >= 1.0) {
        fprintf(stderr, "oceand: %u connection(s) closed at accept in the last second: %s\n",
                accept_log_n, why);
        accept_log_t = now;
        accept_log_n = 0;
    }
}

int accept(int fd, struct sockaddr *addr, socklen_t *alen)
{
    accept_fn real = atomic_load(&real_accept);
    if (!real) {
        real = (accept_fn)dlsym(RTLD_NEXT, "accept");
        atomic_store(&real_accept, real);
    }
    int r = real(fd, addr, alen);
    if (r < 0 && (errno == EMFILE || errno == ENFILE) && spare_fd >= 0) {
        close(spare_fd);
        int c = real(fd, NULL, NULL);
        if (c >= 0) close(c);
        spare_fd = open("/dev/null", O_RDONLY | O_CLOEXEC);
        accept_note("out of file descriptors (EMFILE)");
        errno = EAGAIN;
        return -1;
    }
    if (r >= 0 && fd_limit > 0 && r >= fd_limit - FD_ACCEPT_SLACK) {
        close(r);
        accept_note("file descriptors reserved (server.max_clients is clamped below the fd limit)");
        errno = EAGAIN;
        return -1;
    }
    return r;
}

/* Raises the soft fd limit to the hard one; returns the soft limit. */
static int raise_fd_limit(void)
{
    struct rlimit rl;
    if (getrlimit(RLIMIT_NOFILE, &rl) != 0) return 0;
    if (rl.rlim_cur < rl.rlim_max) {
        struct rlimit want = rl;
        want.rlim_cur = rl.rlim_max;
        if (setrlimit(RLIMIT_NOFILE, &want) == 0) rl = want;
    }
    if (rl.rlim_cur == RLIM_INFINITY || rl.rlim_cur > (1u << 20)) return 1 << 20;
    return (int)rl.rlim_cur;
}

struct srv_net {
    srv_hub *hub;
    struct lws_context *ctx;
    struct lws_vhost *vh;
    pthread_t thread;
    int running;
    atomic_int stop;            /* [main -> svc] 1: shut down */
    int stop_phase;             /* [svc] 0 run, 1 BYEs sent */
    double stop_deadline;       /* [svc] */
    atomic_int done;            /* [svc -> main] loop ended */
    int port;
    char web_root[SRV_PATH_MAX];
    struct lws_http_mount m_root, m_metrics, m_status;
    struct lws_protocols protocols[3];
    lws_sorted_usec_list_t sweep;  /* [svc] limits are checked 4x a second even when idle */
    int fd_clients;                /* [const] most clients the fd limit allows */
    int time_said;                 /* [svc] past the exact-time limit: logged */
    srv_session *sessions;         /* [svc] every open connection's session */
    double last_wake;              /* [svc] srv_now() at the last on_wake; 0: none yet */
};

typedef struct ws_pss {
    srv_session *s;
} ws_pss;

typedef struct http_pss {
    char *body;   /* LWS_PRE headroom + text */
    size_t len;
} http_pss;

static void net_wake(void *ctx)
{
    srv_net *n = ctx;
    if (n->ctx) lws_cancel_service(n->ctx);
}

/* ---- past the exact-time limit ---------------------------------------------
 *
 * The clock is now - server.epoch, and past OCEAN_TIME_MAX (2^27 s, 4.25
 * years) nothing can be served: no HELLO, FRAME or announce encodes
 * (sim/ocean_time.h).  Rather than leave connections open in silence, every
 * client, connected or new, is told why (BYE shutdown) and closed, and
 * /status answers 503; the epoch is fixed for the run, so only a restart
 * with a nearer server.epoch ends it. */
#define TIME_LIMIT_BYE "sim time is past the exact-time limit OCEAN_TIME_MAX (2^27 s, 4.25 years " \
                       "after server.epoch): nothing can be served; the operator must set " \
                       "server.epoch within 4.25 years of now and restart oceand"
/* the close frame's reason (<= 123 bytes) */
#define TIME_LIMIT_CLOSE "sim time past OCEAN_TIME_MAX (4.25 years after server.epoch): set " \
                         "server.epoch nearer now and restart"

/* 1 when the clock is past the limit; said in the log once a run [svc]. */
static int past_time_limit(srv_net *n)
{
    double t = srv_hub_sim_time(n->hub);
    if (ocean_time_ok(t)) return 0;
    if (!n->time_said)
        fprintf(stderr, "oceand: sim time %.3f s (now - server.epoch) is past the exact-time limit "
                "OCEAN_TIME_MAX (%.0f s, 4.25 years): every client is closed with BYE shutdown, new "
                "ones too, and /status answers 503; set server.epoch within 4.25 years of now and "
                "restart (said once)\n", t, OCEAN_TIME_MAX);
    n->time_said = 1;
    return 1;
}

/* ---- HTTP: /metrics and /status ------------------------------------------- */

/* Admission's figures into v [svc, hub.lock held for the settings]. */
static void admission_view(const srv_hub *h, srv_stats_view *v)
{
    srv_admit_view av;
    if (!h->admit) return;
    srv_admit_get_view(h->admit, &h->settings.srv, &av);
    v->admit_capacity = av.capacity;
    v->admit_usable = av.usable;
    v->admit_others = av.others;
    v->admit_shared = av.shared;
    v->admit_priced = av.priced;
    v->admit_count = av.admitted;
}

/* Fills v; *per gets a malloc'ed per-client array (free it; NULL on OOM). */
static void stats_view(srv_net *n, srv_stats_view *v, char *scene, size_t sl,
                       srv_stats_client **per)
{
    srv_hub *h = n->hub;
    memset(v, 0, sizeof *v);
    pthread_mutex_lock(&h->lock);
    *per = h->n_clients > 0 ? calloc((size_t)h->n_clients, sizeof **per) : NULL;
    int k = 0;
    for (srv_client *c = h->clients; c && *per && k < h->n_clients; c = c->next) {
        if (c->closed || c->internal) continue;
        srv_stats_client *o = &(*per)[k++];
        o->id = c->id;
        o->cpu_seconds = 1e-9 * (double)atomic_load(&c->cpu_ns);
        o->bytes_out = (double)atomic_load(&c->bytes_out);
        o->queued = (double)srv_outbox_queued(c->out);
    }
    v->per_client = *per;
    v->n_per_client = k;
    v->clients = h->n_clients;
    v->subscribed = h->n_subscribed;
    v->tick_rate = h->settings.srv.tick_rate;
    snprintf(scene, sl, "%s", h->settings.scene.name);
    v->wind = h->sea_now.wind_u10;
    v->hs = h->sea_now.hs;
    v->has_camera_hint = h->settings.scene.camera_hint[0] &&
                         ocean_conf_camera_hint_parse(h->settings.scene.camera_hint, v->camera_hint) == OCEAN_OK;
    admission_view(h, v);
    pthread_mutex_unlock(&h->lock);
    v->sim_time = srv_hub_sim_time(h);
    v->past_time_limit = past_time_limit(n) ? TIME_LIMIT_BYE : NULL;
    v->scene = scene;
    v->version = "oceand 0.1";
    v->port = n->port;
}

/* Writes a whole HTTP refusal of a WebSocket upgrade (the caller then
 * returns nonzero, and lws closes).  426 carries Sec-WebSocket-Version: 13
 * (RFC 6455 4.4). */
static int refuse_upgrade(srv_net *n, struct lws *wsi, int status, const char *why)
{
    uint8_t buf[LWS_PRE + 600];
    char *p = (char *)buf + LWS_PRE;
    int body = (int)strlen(why) + 1;
    int k = snprintf(p, 600, "HTTP/1.1 %d %s\r\n%sContent-Type: text/plain\r\n"
                     "Content-Length: %d\r\nConnection: close\r\n\r\n%s\n", status,
                     status == 426 ? "Upgrade Required" : "Bad Request",
                     status == 426 ? "Sec-WebSocket-Version: 13\r\n" : "", body, why);
    if (k > 0 && k < 600) lws_write(wsi, (unsigned char *)p, (size_t)k, LWS_WRITE_HTTP_HEADERS);
    atomic_fetch_add(&n->hub->stats.refused_upgrade, 1);
    return 1;
}

/* The checks of an upgrade libwebsockets leaves to us: version 13 only
 * (lws 4.1.6 treats any version as 13), ocean.v1 only (an upgrade without
 * a subprotocol lands on the HTTP protocol and would be held, uncounted). */
static int filter_upgrade(srv_net *n, struct lws *wsi, int ocean)
{
    /* A WebSocket inside an HTTP/2 stream (RFC 8441, after an h2c
     * upgrade): ocean.v1 is RFC 6455 over its own TCP connection, and the
     * frame tracker (trk_*) and the send path read and write that
     * connection's bytes as such; one SUBSCRIBE on such a stream made
     * lws_write read before the message buffer.  Refused: the stream is
     * reset, the HTTP/2 connection's other streams carry on. */
    if (lws_get_network_wsi(wsi) != wsi) {
        atomic_fetch_add(&n->hub->stats.refused_upgrade, 1);
        return 1;
    }
    char ver[16] = "";
    lws_hdr_copy(wsi, ver, sizeof ver, WSI_TOKEN_VERSION);
    if (strcmp(ver, "13") != 0)
        return refuse_upgrade(n, wsi, 426, "only WebSocket version 13 (RFC 6455) is spoken here");
    if (!ocean)
        return refuse_upgrade(n, wsi, 400, "WebSocket connections must ask for the ocean.v1 "
                              "subprotocol (Sec-WebSocket-Protocol: ocean.v1)");
    return 0;
}

/* GET or HEAD of /metrics or /status (srv_stats.c); everything else the
 * web root mount did not serve: 404, or 405 for other methods. */
static int on_http(srv_net *n, struct lws *wsi, http_pss *pss)
{
    /* The mounts match by prefix: only the exact paths are answered
     * (/metricsfoo is not the metrics), GET and HEAD alike (a 404 to HEAD
     * reads as down to a load balancer's health check);
     * other methods get 405 naming the two.  The method is told by
     * the URI header's length, not by a copy of it: a path too long
     * for the copy made a GET look like no method at all (405). */
    char uri[128] = "";
    int head = 0, ulen = lws_hdr_total_length(wsi, WSI_TOKEN_GET_URI);
    if (ulen <= 0) {
        ulen = lws_hdr_total_length(wsi, WSI_TOKEN_HEAD_URI);
        head = ulen > 0;
    }
    if (ulen <= 0) {
        uint8_t hdr[LWS_PRE + 256], *start = hdr + LWS_PRE, *p = start, *end = hdr + sizeof hdr - 1;
        if (lws_add_http_header_status(wsi, HTTP_STATUS_METHOD_NOT_ALLOWED, &p, end) ||
            lws_add_http_header_by_token(wsi, WSI_TOKEN_HTTP_ALLOW, (const unsigned char *)"GET, HEAD",
                                         9, &p, end) ||
            lws_add_http_header_content_length(wsi, 0, &p, end) ||
            lws_finalize_write_http_header(wsi, start, &p, end))
            return 1;
        return lws_http_transaction_completed(wsi) ? -1 : 0;
    }
    if ((size_t)ulen >= sizeof uri) {
        /* Not /status or /metrics, and not a file the web root mount
         * served (it tried first): not there (404).  A path too long
         * for lws to name as a file never gets here (the 414 of
         * LWS_CALLBACK_FILTER_HTTP_CONNECTION); kept for any mount
         * that skips the filter. */
        int too_long = strlen(n->web_root) + (size_t)ulen > SRV_LWS_FILE_PATH_MAX;
        lws_return_http_status(wsi, too_long ? HTTP_STATUS_REQ_URI_TOO_LONG : HTTP_STATUS_NOT_FOUND,
                               too_long ? "path too long for a file under server.web_root" : NULL);
        return lws_http_transaction_completed(wsi) ? -1 : 0;
    }
    lws_hdr_copy(wsi, uri, sizeof uri, head ? WSI_TOKEN_HEAD_URI : WSI_TOKEN_GET_URI);
    int metrics = strcmp(uri, "/metrics") == 0, status = strcmp(uri, "/status") == 0;
    if (!metrics && !status) {
        lws_return_http_status(wsi, HTTP_STATUS_NOT_FOUND, NULL);
        return lws_http_transaction_completed(wsi) ? -1 : 0;
    }
    srv_stats_view v;
    srv_stats_client *per = NULL;
    char scene[OCEAN_SCENE_NAME_MAX];
    stats_view(n, &v, scene, sizeof scene, &per);
    const char *type;
    if (metrics) {
        pss->body = srv_stats_prometheus(&n->hub->stats, &v, LWS_PRE, &pss->len);
        type = "text/plain; version=0.0.4; charset=utf-8";
    } else {
        pss->body = srv_stats_json(&n->hub->stats, &v, LWS_PRE, &pss->len);
        type = "application/json";
    }
    free(per);
    if (!pss->body) {
        lws_return_http_status(wsi, HTTP_STATUS_INTERNAL_SERVER_ERROR, "out of memory");
        return -1;
    }
    uint8_t hdr[LWS_PRE + 512], *start = hdr + LWS_PRE, *p = start, *end = hdr + sizeof hdr - 1;
    /* past the exact-time limit this replica serves nothing: /status
     * says so to health checks (503, its body says why); /metrics
     * stays 200 for the scraper (oceand_past_time_limit 1) */
    unsigned code = status && v.past_time_limit ? HTTP_STATUS_SERVICE_UNAVAILABLE : HTTP_STATUS_OK;
    if (lws_add_http_common_headers(wsi, code, type, pss->len, &p, end) ||
        lws_add_http_header_by_token(wsi, WSI_TOKEN_HTTP_CACHE_CONTROL,
                                     (const unsigned char *)"no-store", 8, &p, end) ||
        lws_finalize_write_http_header(wsi, start, &p, end))
        return 1;
    if (head) { /* the headers GET would send, Content-Length included, no body */
        free(pss->body);
        pss->body = NULL;
        return lws_http_transaction_completed(wsi) ? -1 : 0;
    }
    lws_callback_on_writable(wsi);
    return 0;
}

static int cb_http(struct lws *wsi, enum lws_callback_reasons reason, void *user, void *in,
                   size_t len)
{
    http_pss *pss = user;
    srv_net *n = lws_context_user(lws_get_context(wsi));
    switch (reason) {
    case LWS_CALLBACK_FILTER_HTTP_CONNECTION: {
        /* Before the web root mount looks for a file: lws names it as
         * web_root "/" path in 255 bytes and cuts the rest, so a longer
         * path whose first bytes name a file would be served that file (or
         * 415 for a name without a type) in place of the one asked for. */
        int ulen = lws_hdr_total_length(wsi, WSI_TOKEN_GET_URI);
        if (ulen <= 0) ulen = lws_hdr_total_length(wsi, WSI_TOKEN_HEAD_URI);
        if (ulen > 0 && strlen(n->web_root) + 1 + (size_t)ulen > SRV_LWS_FILE_PATH_MAX) {
            lws_return_http_status(wsi, HTTP_STATUS_REQ_URI_TOO_LONG,
                                   "path too long for a file under server.web_root");
            return 1;
        }
        break;
    }
    case LWS_CALLBACK_HTTP_CONFIRM_UPGRADE: {
        /* A WebSocket upgrade that does not offer ocean.v1 at all (only
         * "chat", or a different case) never reaches a protocol's filter:
         * lws 4.1.6 finds no protocol and hangs up without a word.  Answer
         * it here, as one without any subprotocol is answered (400). */
        if (!in || strcasecmp((const char *)in, "websocket") != 0) break;
        char list[256] = "";
        lws_hdr_copy(wsi, list, sizeof list, WSI_TOKEN_PROTOCOL);
        int offered = 0;
        for (char *save = NULL, *tok = strtok_r(list, ", \t", &save); tok && !offered;
             tok = strtok_r(NULL, ", \t", &save))
            offered = strcmp(tok, PROTO_SUBPROTOCOL) == 0;
        if (!offered)
            return refuse_upgrade(n, wsi, 400, "WebSocket connections must ask for the ocean.v1 "
                                  "subprotocol (Sec-WebSocket-Protocol: ocean.v1)");
        break;
    }
    case LWS_CALLBACK_FILTER_PROTOCOL_CONNECTION:
        return filter_upgrade(n, wsi, 0);
    case LWS_CALLBACK_ESTABLISHED: {
        /* A WebSocket that did not offer the ocean.v1 subprotocol lands on
         * the first protocol (this one): close it with a reason rather than
         * leave it in silence (PROTOCOL.md "Transport"). */
        static const char why[] = "subprotocol ocean.v1 required (Sec-WebSocket-Protocol: ocean.v1)";
        lws_close_reason(wsi, LWS_CLOSE_STATUS_PROTOCOL_ERR, (unsigned char *)why, sizeof why - 1);
        return -1;
    }
    case LWS_CALLBACK_HTTP:
        return on_http(n, wsi, pss);
    case LWS_CALLBACK_HTTP_WRITEABLE: {
        if (!pss->body) break;
        int w = lws_write(wsi, (unsigned char *)pss->body + LWS_PRE, pss->len, LWS_WRITE_HTTP_FINAL);
        free(pss->body);
        pss->body = NULL;
        if (w < 0) return -1;
        if (lws_http_transaction_completed(wsi)) return -1;
        return 0;
    }
    case LWS_CALLBACK_CLOSED_HTTP:
    case LWS_CALLBACK_HTTP_DROP_PROTOCOL:
        free(pss ? pss->body : NULL);
        if (pss) pss->body = NULL;
        break;
    default:
        break;
    }
    return lws_callback_http_dummy(wsi, reason, user, in, len);
}

/* ---- WebSocket: ocean.v1 ----------------------------------------------------- */

/* Ends c for breaking a limit: the close frame with `code` and `why` goes
 * out at the next writeable callback (send_next), once what lws holds of
 * the last message is flushed, so the client learns which limit; a client
 * that cannot take even that within KILL_GRACE_S is cut without it. */
#define KILL_GRACE_S 2
static void kill_client_code(srv_session *s, enum lws_close_status code, const char *why)
{
    if (!s->wsi || s->closing == 3) return;
    s->closing = 3;
    s->kill_code = (uint16_t)code;
    snprintf(s->kill_why, sizeof s->kill_why, "%s", why);
    lws_set_timeout(s->wsi, PENDING_TIMEOUT_USER_OK, KILL_GRACE_S);
    lws_callback_on_writable(s->wsi);
}

static void kill_client(srv_session *s, const char *why)
{
    kill_client_code(s, LWS_CLOSE_STATUS_POLICY_VIOLATION, why);
}

/* The client's read budget after refilling to now (server.read_rate, one
 * max_message plus one read buffer deep) [svc]. */
static double rx_budget(srv_session *s, const srv_config *cfg, double now)
{
    return srv_bucket_refill(&s->read, cfg->read_rate, (double)cfg->max_message + 65536, now);
}

/* The reading side's limits of session s on a wake: a violation lws let
 * through, a refused message over the outbox's hard limit, a paused read
 * whose budget refilled, an unfinished message past its deadline, a
 * connection that asks for nothing.  1 when s is being closed [hub.lock]. */
static int session_input(srv_session *s, const srv_config *cfg, double now)
{
    srv_hub *h = s->c->hub;
    ws_track *t = trk_of(lws_get_socket_fd(s->wsi));
    if (t && t->owner == s->wsi && atomic_load(&t->bad) == 1) {
        atomic_store(&t->bad, 3);              /* counted */
        atomic_fetch_add(&h->stats.disconnects_protocol, 1);
        kill_client_code(s, LWS_CLOSE_STATUS_PROTOCOL_ERR, "protocol error (RFC 6455)");
        return 1;
    }
    if (srv_outbox_over_hard(s->c->out)) {
        atomic_fetch_add(&h->stats.disconnects_output, 1);
        atomic_fetch_add(&h->stats.disconnects_slow, 1);
        kill_client(s, "output over server.output_hard: replies queued faster than read");
        return 1;
    }
    if (s->rx_paused && rx_budget(s, cfg, now) > 0) {
        s->rx_paused = 0;
        lws_rx_flow_control(s->wsi, 1);
    }
    /* (not while we hold its reading back ourselves).  From the frame's
     * first byte (the tracker), not only from the first payload byte lws
     * hands over: a header whose payload never comes is unfinished too. */
    double began = s->rx_started;
    if (t && t->owner == s->wsi && t->frame_t > 0 && (began == 0 || t->frame_t < began))
        began = t->frame_t;
    if (began > 0 && now - began > cfg->partial_seconds && !s->rx_paused) {
        atomic_fetch_add(&h->stats.disconnects_partial, 1);
        kill_client(s, "message unfinished for server.partial_seconds");
        return 1;
    }
    /* A connection that asks for nothing must not hold a slot of
     * server.max_clients for ever (PROTOCOL.md: BYE idle). */
    if (!s->c->subscribed && !s->closing && s->last_rx > 0 && now - s->last_rx > cfg->idle_seconds) {
        atomic_fetch_add(&h->stats.disconnects_idle, 1);
        s->closing = 1;
        snprintf(s->kill_why, sizeof s->kill_why, "idle: no SUBSCRIBE and no message for "
                 "server.idle_seconds");
        srv_client_send_bye(s->c, PROTO_BYE_IDLE, s->kill_why);
        lws_callback_on_writable(s->wsi);
        return 1;
    }
    return 0;
}

/* The sending side's limits of session s on a wake: the bytes queued
 * against server.output_hard and output_soft, and a reader that takes
 * nothing at all.  1 when s is being closed. */
static int session_output(srv_session *s, const srv_config *cfg, double now)
{
    srv_hub *h = s->c->hub;
    uint64_t q = srv_outbox_queued(s->c->out) + s->inflight;
    if (q > cfg->output_hard) {
        /* the limit is named with its value: set below one frame, it cuts
         * a client that is not slow at all */
        char why[120];
        snprintf(why, sizeof why, "slow consumer: %llu bytes queued, over server.output_hard %llu",
                 (unsigned long long)q, (unsigned long long)cfg->output_hard);
        atomic_fetch_add(&h->stats.disconnects_slow, 1);
        kill_client(s, why);
        return 1;
    }
    if (q > cfg->output_soft) {
        if (s->over_soft_since == 0) {
            s->over_soft_since = now;
        } else if (now - s->over_soft_since > cfg->output_soft_seconds) {
            atomic_fetch_add(&h->stats.disconnects_slow, 1);
            kill_client(s, "slow consumer: over server.output_soft for too long");
            return 1;
        }
    } else {
        s->over_soft_since = 0;
    }
    /* A reader that takes nothing at all for the soft period is gone:
     * output has waited that long with no send completed.  lws holding the
     * rest of a write is one sign; a message waiting for a socket that
     * never turns writable is the other, since the kernel may have taken
     * the last FRAME whole (lws sends it in one piece).  A frame the link
     * holds back waits on our plan, not on the reader: a client whose
     * confirmations trail is not one that reads nothing (the hold ends by
     * SRV_LINK_QUIET at the latest, and a reader that then takes nothing
     * is judged from there). */
    int held = srv_outbox_next_is_live(s->c->out) && srv_link_holds(&s->link, now);
    int pending = s->inflight > 0 || (q > 0 && !held);
    if (!pending) s->pending_since = 0;
    else if (s->pending_since == 0) s->pending_since = now;
    if (pending && now - fmax(s->pending_since, s->last_progress) > fmax(cfg->output_soft_seconds, 1.0)) {
        atomic_fetch_add(&h->stats.disconnects_slow, 1);
        kill_client(s, "slow consumer: no bytes read for server.output_soft_seconds");
        return 1;
    }
    return 0;
}

/* The sweep runs the wake 4x a second; a longer gap means the service
 * thread itself did not run (the host stopped or starved the process). */
#define STALL_S 0.5

/* No client could read or send while the service thread did not run for
 * `gap` seconds before now, so no limit's clock counts that span: a daemon
 * resumed after SIGSTOP, or starved on a loaded host, cut its readers as
 * slow consumers for its own silence.  Clocks set after the stall stay. */
static void sessions_skip_stall(srv_net *n, double gap, double now)
{
    double before = now - gap;
    for (srv_session *s = n->sessions; s; s = s->next) {
        double *clk[] = {&s->over_soft_since, &s->pending_since, &s->last_progress, &s->rx_started, &s->last_rx};
        for (size_t i = 0; i < sizeof clk / sizeof clk[0]; i++)
            if (*clk[i] > 0 && *clk[i] <= before) *clk[i] += gap;
        ws_track *t = s->wsi ? trk_of(lws_get_socket_fd(s->wsi)) : NULL;
        if (t && t->owner == s->wsi && t->frame_t > 0 && t->frame_t <= before) t->frame_t += gap;
    }
    if (gap > 2.0)
        fprintf(stderr, "oceand: the service thread did not run for %.1f s (process stopped or starved); "
                "client limits do not count that time\n", gap);
}

/* Runs on every wake: hands writable requests to lws, enforces limits,
 * drives the shutdown. */
static void on_wake(srv_net *n)
{
    srv_hub *h = n->hub;
    double now = srv_now();
    if (n->last_wake > 0 && now - n->last_wake > STALL_S) sessions_skip_stall(n, now - n->last_wake, now);
    n->last_wake = now;
    int stopping = atomic_load(&n->stop);
    int past = past_time_limit(n);
    pthread_mutex_lock(&h->lock);
    srv_config cfg = h->settings.srv;
    if (stopping && n->stop_phase == 0) {
        n->stop_phase = 1;
        h->stopping = 1;
    }
    for (srv_session *s = n->sessions; s; s = s->next) {
        if (!s->wsi || s->c->closed) continue;
        if (s->closing == 3) {
            /* cut already, and counted once: its close waits for the
             * writeable callback or KILL_GRACE_S, not for another limit */
            lws_callback_on_writable(s->wsi);
            continue;
        }
        srv_outbox_set_hard(s->c->out, cfg.output_hard);
        if (session_input(s, &cfg, now)) continue;
        if ((stopping || past) && s->closing != 1 && s->closing != 3 && s->closing != 4) {
            /* queue BYE after whatever is queued; frames stop mattering
             * (past the exact-time limit none can be built any more) */
            s->closing = 1;
            if (!stopping) snprintf(s->kill_why, sizeof s->kill_why, "%s", TIME_LIMIT_CLOSE);
            srv_client_send_bye(s->c, PROTO_BYE_SHUTDOWN, stopping ? "server shutting down" : TIME_LIMIT_BYE);
        }
        if (session_output(s, &cfg, now)) continue;
        if (srv_outbox_take_want_write(s->c->out) || s->closing == 2 || s->closing == 3)
            lws_callback_on_writable(s->wsi);
    }
    pthread_mutex_unlock(&h->lock);
}

static void send_next(srv_net *n, srv_session *s, struct lws *wsi, int *close_now)
{
    srv_hub *h = n->hub;
    *close_now = 0;
    if (s->closing == 2) { /* client said BYE */
        lws_close_reason(wsi, LWS_CLOSE_STATUS_NORMAL, (unsigned char *)"bye", 3);
        *close_now = 1;
        return;
    }
    if (s->closing == 3) { /* a limit: the close frame names it (kill_client_code) */
        if (lws_partial_buffered(wsi)) {
            lws_callback_on_writable(wsi);
            return;
        }
        lws_close_reason(wsi, (enum lws_close_status)s->kill_code, (unsigned char *)s->kill_why,
                         strlen(s->kill_why));
        *close_now = 1;
        return;
    }
    if (s->closing == 4) { /* BYE written and flushed: the close says what it did */
        const char *why = s->kill_why[0] ? s->kill_why : "server shutting down";
        lws_close_reason(wsi, LWS_CLOSE_STATUS_GOINGAWAY, (unsigned char *)why, strlen(why));
        *close_now = 1;
        return;
    }
    if (lws_partial_buffered(wsi)) {
        lws_callback_on_writable(wsi);
        return;
    }
    s->inflight = 0;
    /* a live frame waits while the link has its window in flight; a newer
     * one replaces it meanwhile, and a confirmation asks to write again */
    if (srv_outbox_next_is_live(s->c->out) && !srv_link_may_send(&s->link, srv_now())) {
        atomic_fetch_add(&h->stats.frames_held, 1);
        return;
    }
    srv_msg *m = srv_outbox_take(s->c->out);
    if (!m) return;
    size_t len;
    uint8_t *data = srv_msg_wire(m, &len);
    if (len >= PROTO_HEADER_SIZE) proto_st32(data + 16, s->tx_seq++);
    int w = lws_write(wsi, data, len, LWS_WRITE_BINARY);
    double now = srv_now();
    if (w < (int)len) {
        srv_msg_free(m);
        *close_now = 1;
        return;
    }
    s->last_progress = now;
    atomic_fetch_add(&s->c->bytes_out, len);
    atomic_fetch_add(&h->stats.bytes_sent, len);
    atomic_fetch_add(&h->stats.messages_sent, 1);
    if (m->live && len >= PROTO_HEADER_SIZE) srv_link_sent(&s->link, proto_ldf64(data + 24), len, now);
    if (m->is_frame) {
        atomic_fetch_add(&h->stats.frames_sent, 1);
        if (m->tick_wall > 0) srv_stats_latency(&h->stats, now - m->tick_wall);
    }
    if (lws_partial_buffered(wsi)) s->inflight = len;
    if (m->close_after) s->closing = 4;
    srv_msg_free(m);
    /* more to send, or the final close after the BYE */
    lws_callback_on_writable(wsi);
}

/* A ?record=1 connection or server.record: its camera path is recorded
 * when the operator allows it and the run's quotas have room (each refusal
 * logged once a run: one line per connection let any client that connects
 * fill the log). */
static void maybe_record(srv_hub *h, srv_session *s, struct lws *wsi)
{
    pthread_mutex_lock(&h->lock);
    int record = h->settings.srv.record, record_clients = h->settings.srv.record_clients;
    int record_files = h->settings.srv.record_max_files, verbose = h->settings.srv.verbose;
    uint64_t record_bytes = h->settings.srv.record_max_bytes;
    char dir[SRV_PATH_MAX], scene[OCEAN_SCENE_NAME_MAX];
    snprintf(dir, sizeof dir, "%s", h->settings.srv.record_dir);
    snprintf(scene, sizeof scene, "%s", h->settings.scene.name);
    pthread_mutex_unlock(&h->lock);
    char arg[16];
    if (lws_get_urlarg_by_name(wsi, "record", arg, sizeof arg) &&
        (strcmp(arg, "record=1") == 0 || strcmp(arg, "1") == 0)) {
        /* a client's own request writes a file on the server's disk */
        if (record_clients) record = 1;
        else if (verbose)
            fprintf(stderr, "oceand: client %u: ?record=1 ignored (server.record_clients is off)\n", s->c->id);
    }
    if (record && atomic_load(&h->record_files) >= (uint64_t)record_files) {
        if (!(h->record_said & 1))
            fprintf(stderr, "oceand: client %u: not recording: %d recordings opened this run "
                    "(server.record_max_files); no later client is recorded (said once)\n", s->c->id, record_files);
        h->record_said |= 1;
        record = 0;
    }
    if (record && atomic_load(&h->record_bytes) >= record_bytes) {
        if (!(h->record_said & 2))
            fprintf(stderr, "oceand: client %u: not recording: server.record_max_bytes written this run; no "
                    "later client is recorded (said once)\n", s->c->id);
        h->record_said |= 2;
        record = 0;
    }
    if (!record) return;
    char path[1100], msg[300];
    if (srv_record_open(dir, s->c->id, scene, &s->rec, path, sizeof path, msg, sizeof msg) != OCEAN_OK) {
        if (!(h->record_said & 4))
            fprintf(stderr, "oceand: client %u: not recording: %s (said once a run)\n", s->c->id, msg);
        h->record_said |= 4;
        return;
    }
    atomic_fetch_add(&h->record_files, 1);
    srv_record_set_quota(s->rec, &h->record_bytes, record_bytes);
    if (verbose) fprintf(stderr, "oceand: client %u: recording to %s\n", s->c->id, path);
}

/* A new connection: its client, refused with a BYE that says why when the
 * server is full, stopping or past its clock's end, else greeted (HELLO). */
static int on_established(srv_net *n, struct lws *wsi, ws_pss *pss)
{
    srv_hub *h = n->hub;
    srv_session *s;
    if (srv_session_create(h, wsi, &s) != OCEAN_OK) return -1;
    pss->s = s;
    s->next = n->sessions;
    n->sessions = s;
    lws_get_peer_simple(wsi, s->peer, sizeof s->peer);
    pthread_mutex_lock(&h->lock);
    int maxc = h->settings.srv.max_clients;
    if (n->fd_clients > 0 && maxc > n->fd_clients) maxc = n->fd_clients;
    int full = h->n_clients > maxc, stopping = h->stopping, verbose = h->settings.srv.verbose;
    pthread_mutex_unlock(&h->lock);
    if (past_time_limit(n)) { /* no HELLO can be sent: say why instead of nothing */
        s->closing = 1;
        snprintf(s->kill_why, sizeof s->kill_why, "%s", TIME_LIMIT_CLOSE);
        srv_client_send_bye(s->c, PROTO_BYE_SHUTDOWN, TIME_LIMIT_BYE);
    } else if (full || stopping) {
        if (full) atomic_fetch_add(&h->stats.refused_full, 1);
        s->closing = 1;
        snprintf(s->kill_why, sizeof s->kill_why, "%s",
                 stopping ? "server shutting down" : "server full: server.max_clients connections in use");
        srv_client_send_bye(s->c, stopping ? PROTO_BYE_SHUTDOWN : PROTO_BYE_SERVER_FULL, s->kill_why);
    } else {
        maybe_record(h, s, wsi);
        if (verbose) fprintf(stderr, "oceand: client %u connected\n", s->c->id);
        srv_client_send_hello(s->c);
    }
    lws_callback_on_writable(wsi);
    return 0;
}

/* Appends len bytes of the message being received to s->rx (a message over
 * server.max_message keeps only its header, for the ERROR).  -1 closes the
 * connection: every client's unfinished messages together would pass
 * server.partial_total, or memory ran out. */
static int rx_append(srv_hub *h, srv_session *s, struct lws *wsi, const void *in, size_t len, size_t maxm,
                     uint64_t total)
{
    if (!s->rx_discard && s->rx_len + len > maxm) {
        s->rx_discard = 1;
        s->rx_discarded = s->rx_len;
        if (s->rx_len > PROTO_HEADER_SIZE) s->rx_len = PROTO_HEADER_SIZE;
    }
    if (s->rx_discard) {
        s->rx_discarded += len;
        size_t keep = s->rx_len < PROTO_HEADER_SIZE ? PROTO_HEADER_SIZE - s->rx_len : 0;
        len = keep < len ? keep : len;
    }
    if (!len) return 0;
    if (s->rx_len + len > s->rx_cap) {
        size_t nc = s->rx_cap ? s->rx_cap : 4096;
        while (nc < s->rx_len + len) nc *= 2;
        if (nc > maxm + 4096) nc = maxm + 4096;
        if (h->partial_held - s->rx_held + nc > total) {
            atomic_fetch_add(&h->stats.disconnects_partial, 1);
            srv_session_rx_release(s);
            lws_close_reason(wsi, LWS_CLOSE_STATUS_POLICY_VIOLATION,
                             (unsigned char *)"unfinished messages over server.partial_total", 45);
            return -1;
        }
        uint8_t *nb = realloc(s->rx, nc);
        if (!nb) return -1;
        s->rx = nb;
        h->partial_held += nc - s->rx_held;
        s->rx_held = s->rx_cap = nc;
    }
    memcpy(s->rx + s->rx_len, in, len);
    s->rx_len += len;
    return 0;
}

/* A whole message received: handled (srv_handle.c), then the buffer is
 * cut back (between messages only a small one is kept, and it does not
 * count as unfinished). */
static void rx_complete(srv_hub *h, srv_session *s, struct lws *wsi, size_t maxm)
{
    s->rx_started = 0;
    if (!lws_frame_is_binary(wsi)) {
        srv_handle_text(s);
    } else if (s->rx_discard) {
        char why[200];
        snprintf(why, sizeof why, "message of %zu bytes or more exceeds server.max_message (%zu bytes)",
                 s->rx_discarded, maxm);
        srv_client_send_error(s->c, s->rx, s->rx_len, OCEAN_ETOOBIG, why);
    } else {
        srv_handle(s, s->rx, s->rx_len);
    }
    s->rx_len = 0;
    s->rx_discard = 0;
    if (srv_outbox_take_want_write(s->c->out) || s->closing) lws_callback_on_writable(wsi);
    if (s->rx_cap > 4096) {
        srv_session_rx_release(s);
    } else {
        h->partial_held -= s->rx_held;
        s->rx_held = 0;
    }
}

/* Bytes of a client message: a frame lws's checks marked bad closes the
 * connection (1002); a client over server.read_rate is paused (lws stops
 * reading its socket, TCP pushes back) until its budget refills, so one
 * client's flood cannot hold the service thread from the others. */
static int on_receive(srv_hub *h, struct lws *wsi, srv_session *s, const void *in, size_t len)
{
    if (!s || s->closing) return 0;
    ws_track *t = trk_of(lws_get_socket_fd(wsi));
    if (t && t->owner == wsi && atomic_load(&t->bad) == 1) {
        atomic_store(&t->bad, 3);              /* counted */
        atomic_fetch_add(&h->stats.disconnects_protocol, 1);
        lws_close_reason(wsi, LWS_CLOSE_STATUS_PROTOCOL_ERR, (unsigned char *)"protocol error (RFC 6455)", 25);
        return -1;
    }
    pthread_mutex_lock(&h->lock);
    srv_config cfg = h->settings.srv;
    pthread_mutex_unlock(&h->lock);
    rx_budget(s, &cfg, srv_now());
    srv_bucket_spend(&s->read, (double)len);
    if (s->read.tokens < 0 && !s->rx_paused) {
        s->rx_paused = 1;
        lws_rx_flow_control(wsi, 0);
    }
    if (lws_is_first_fragment(wsi)) {
        s->rx_len = 0;
        s->rx_discard = 0;
        s->rx_discarded = 0;
        s->rx_started = s->last_rx = srv_now();
    }
    if (rx_append(h, s, wsi, in, len, (size_t)cfg.max_message, cfg.partial_total)) return -1;
    if (lws_is_final_fragment(wsi) && !lws_remaining_packet_payload(wsi))
        rx_complete(h, s, wsi, (size_t)cfg.max_message);
    return 0;
}

/* A connection gone: a violation lws answered itself (a byte rewritten by
 * trk_feed) is a protocol disconnect too; its client leaves the hub. */
static void on_closed(srv_net *n, struct lws *wsi, ws_pss *pss)
{
    srv_hub *h = n->hub;
    ws_track *t = trk_of(lws_get_socket_fd(wsi));
    if (t && t->owner == wsi && atomic_load(&t->bad) == 2)
        atomic_fetch_add(&h->stats.disconnects_protocol, 1);
    trk_forget(wsi);
    srv_session *s = pss->s;
    if (!s) return;
    pthread_mutex_lock(&h->lock);
    int verbose = h->settings.srv.verbose;
    pthread_mutex_unlock(&h->lock);
    if (verbose) fprintf(stderr, "oceand: client %u closed\n", s->c->id);
    pss->s = NULL;
    for (srv_session **p = &n->sessions; *p; p = &(*p)->next) {
        if (*p == s) {
            *p = s->next;
            break;
        }
    }
    srv_session_destroy(s);
}

static int cb_ocean(struct lws *wsi, enum lws_callback_reasons reason, void *user, void *in,
                    size_t len)
{
    ws_pss *pss = user;
    srv_net *n = lws_context_user(lws_get_context(wsi));
    srv_hub *h = n ? n->hub : NULL;
    switch (reason) {
    case LWS_CALLBACK_EVENT_WAIT_CANCELLED:
        if (n) on_wake(n);
        break;
    case LWS_CALLBACK_FILTER_PROTOCOL_CONNECTION:
        if (filter_upgrade(n, wsi, 1)) return 1;
        trk_register(wsi);
        break;
    case LWS_CALLBACK_WSI_DESTROY:
        trk_forget(wsi);
        break;
    case LWS_CALLBACK_ESTABLISHED:
        return on_established(n, wsi, pss);
    case LWS_CALLBACK_RECEIVE:
        return on_receive(h, wsi, pss->s, in, len);
    case LWS_CALLBACK_SERVER_WRITEABLE: {
        if (!pss->s) break;
        int close_now;
        send_next(n, pss->s, wsi, &close_now);
        if (close_now) return -1;
        break;
    }
    case LWS_CALLBACK_CLOSED:
        on_closed(n, wsi, pss);
        break;
    default:
        break;
    }
    return 0;
}

/* ---- lifecycle ---------------------------------------------------------------- */

/* libwebsockets' own log lines, prefixed and held to one a second: each
 * request with a 9 KB URL logged "Ran out of header data space" at the
 * default level, so any client could fill the log.  What is held back is
 * counted in the next line.  lws logs from the service thread (and from
 * the thread creating or destroying the context, never at the same time). */
static void lws_log_emit(int level, const char *line)
{
    static double last = -1e9;
    static unsigned long held;
    double now = srv_now();
    if (now - last < 1.0) {
        held++;
        return;
    }
    last = now;
    size_t n = strlen(line);
    while (n && (line[n - 1] == '\n' || line[n - 1] == '\r')) n--;
    if (held)
        fprintf(stderr, "oceand: lws %s: %.*s (and %lu more lws lines in the last seconds)\n",
                level & LLL_ERR ? "error" : level & LLL_WARN ? "warning" : "note", (int)n, line, held);
    else
        fprintf(stderr, "oceand: lws %s: %.*s\n", level & LLL_ERR ? "error" : level & LLL_WARN ? "warning" : "note",
                (int)n, line);
    held = 0;
}

ocean_result srv_net_create(srv_hub *h, srv_net **out, char *msg, size_t msglen)
{
    srv_net *n = calloc(1, sizeof *n);
    if (!n) return OCEAN_ENOMEM;
    n->hub = h;
    pthread_mutex_lock(&h->lock);
    srv_config cfg = h->settings.srv;
    pthread_mutex_unlock(&h->lock);
    snprintf(n->web_root, sizeof n->web_root, "%s", cfg.web_root);
    {
        /* A web root without the viewer served 404 at / and said nothing,
         * as when oceand starts outside the source tree (the relative
         * default); the scene path's refusal says where it looked, so this
         * does too.  A warning: a daemon may serve only WebSocket clients. */
        char index[SRV_PATH_MAX + 16], cwd[512];
        snprintf(index, sizeof index, "%s/index.html", n->web_root);
        if (access(index, R_OK) != 0) {
            if (!getcwd(cwd, sizeof cwd)) snprintf(cwd, sizeof cwd, "?");
            fprintf(stderr, "oceand: warning: server.web_root '%s' has no readable index.html (%s; relative "
                    "paths are read from %s): the browser viewer is not served\n", n->web_root, strerror(errno),
                    cwd);
        }
    }
    lws_set_log_level(cfg.verbose ? (LLL_ERR | LLL_WARN | LLL_NOTICE) : LLL_ERR, lws_log_emit);

    /* Every client is a descriptor: take the hard limit, and serve no more
     * clients than it allows (lws sizes its tables from the soft limit at
     * context creation, so this comes first). */
    int lim = raise_fd_limit();
    if (lim > 0) {
        fd_limit = lim;
        n->fd_clients = lim - FD_RESERVE > 1 ? lim - FD_RESERVE : 1;
        if (cfg.max_clients > n->fd_clients)
            fprintf(stderr, "oceand: server.max_clients %d is above what the file descriptor "
                    "limit allows (RLIMIT_NOFILE %d, %d kept for the daemon): serving at most %d "
                    "clients; raise the limit (ulimit -n, LimitNOFILE=) to serve more\n",
                    cfg.max_clients, lim, FD_RESERVE, n->fd_clients);
        trk_init(lim);
    }
    if (spare_fd < 0) spare_fd = open("/dev/null", O_RDONLY | O_CLOEXEC);
    accept_refused_ctr = &h->stats.accept_refused;

    n->protocols[0] = (struct lws_protocols){"http", cb_http, sizeof(http_pss), 0, 0, NULL, 0};
    /* tx_packet_size: a FRAME goes to send() whole.  Left at 0, lws caps
     * each send() at rx_buffer_size (64 KiB) and copies the rest of every
     * larger message into its own buffer for a later POLLOUT: at 256
     * viewers that copy is 8 % of the service thread, and the extra
     * writeable round per frame added to the fan-out.  What the kernel does
     * not take is still buffered by lws, and still counts as in flight
     * for the output limit. */
    n->protocols[1] = (struct lws_protocols){PROTO_SUBPROTOCOL, cb_ocean, sizeof(ws_pss), 65536, 0,
                                             NULL, PROTO_MAX_MESSAGE_DEFAULT};
    n->m_status = (struct lws_http_mount){.mountpoint = "/status", .origin = "http",
                                          .protocol = "http", .origin_protocol = LWSMPRO_CALLBACK,
                                          .mountpoint_len = 7};
    n->m_metrics = (struct lws_http_mount){.mount_next = &n->m_status, .mountpoint = "/metrics",
                                           .origin = "http", .protocol = "http",
                                           .origin_protocol = LWSMPRO_CALLBACK,
                                           .mountpoint_len = 8};
    /* lws refuses (415) a file whose type it does not know; the viewer's
     * decoders are WebAssembly modules */
    static const struct lws_protocol_vhost_options wasm_mime = {NULL, NULL, ".wasm", "application/wasm"};
    n->m_root = (struct lws_http_mount){.mount_next = &n->m_metrics, .mountpoint = "/",
                                        .origin = n->web_root, .def = "index.html",
                                        .origin_protocol = LWSMPRO_FILE, .mountpoint_len = 1,
                                        .extra_mimetypes = &wasm_mime};
    struct lws_context_creation_info info;
    memset(&info, 0, sizeof info);
    info.port = cfg.port;
    info.iface = cfg.bind[0] ? cfg.bind : NULL;
    info.protocols = n->protocols;
    info.mounts = &n->m_root;
    info.user = n;
    info.count_threads = 1;
    /* VALIDATE_UTF8: invalid UTF-8 in a text frame closes with 1007
     * (RFC 6455 8.1) */
    info.options = LWS_SERVER_OPTION_DISABLE_IPV6 | LWS_SERVER_OPTION_VALIDATE_UTF8;
    info.ka_time = 0;
    n->ctx = lws_create_context(&info);
    if (!n->ctx) {
        snprintf(msg, msglen, "cannot listen on %s:%d (address in use or not available)",
                 cfg.bind[0] ? cfg.bind : "*", cfg.port);
        free(n);
        return OCEAN_EIO;
    }
    n->vh = lws_get_vhost_by_name(n->ctx, "default");
    n->port = n->vh ? lws_get_vhost_listen_port(n->vh) : cfg.port;
    h->wake_net = net_wake;
    h->wake_ctx = n;
    *out = n;
    return OCEAN_OK;
}

int srv_net_port(const srv_net *n) { return n->port; }

/* Limits with a deadline (unfinished messages, output waiting) are checked
 * four times a second even when nothing wakes the service thread. */
static void sweep_cb(lws_sorted_usec_list_t *sul)
{
    /* scheduled before the work: lws times the next wait from the time it
     * read before this callback, so a sweep scheduled after a wake that
     * waited seconds for the hub's lock came that many seconds late */
    srv_net *n = (srv_net *)((char *)sul - offsetof(srv_net, sweep));
    lws_sul_schedule(n->ctx, 0, &n->sweep, sweep_cb, 250 * LWS_US_PER_MS);
    on_wake(n);
    srv_admit_sample(n->hub->admit, srv_now());
}

static void *net_main(void *arg)
{
    srv_net *n = arg;
    srv_hub *h = n->hub;
    lws_sul_schedule(n->ctx, 0, &n->sweep, sweep_cb, 250 * LWS_US_PER_MS);
    for (;;) {
        if (lws_service(n->ctx, 0) < 0) break;
        if (n->stop_phase) {
            pthread_mutex_lock(&h->lock);
            int left = h->n_clients;
            pthread_mutex_unlock(&h->lock);
            if (left == 0 || srv_now() > n->stop_deadline) break;
        }
    }
    atomic_store(&n->done, 1);
    return NULL;
}

ocean_result srv_net_start(srv_net *n)
{
    if (pthread_create(&n->thread, NULL, net_main, n) != 0) return OCEAN_ENOMEM;
    n->running = 1;
    return OCEAN_OK;
}

void srv_net_stop(srv_net *n, double grace)
{
    if (!n || !n->running) return;
    n->stop_deadline = srv_now() + grace;
    atomic_store(&n->stop, 1);
    while (!atomic_load(&n->done)) {
        lws_cancel_service(n->ctx);
        usleep(20000);
    }
    pthread_join(n->thread, NULL);
    n->running = 0;
}

void srv_net_destroy(srv_net *n)
{
    if (!n) return;
    srv_net_stop(n, 0);
    n->hub->wake_net = NULL;
    if (accept_refused_ctr == &n->hub->stats.accept_refused) accept_refused_ctr = NULL;
    if (n->ctx) {
        lws_sul_cancel(&n->sweep);
        lws_context_destroy(n->ctx);
    }
    while (n->sessions) { /* connections lws tore down without a CLOSED callback */
        srv_session *s = n->sessions;
        n->sessions = s->next;
        srv_session_destroy(s);
    }
    free(n);
}
