/*
 * srv_net.c - libwebsockets service thread: connections, HTTP pages,
 * hand-over of queued bytes, limits.
 */
#include "srv_net.h"

#include <libwebsockets.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "srv_record.h"

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
};

typedef struct ws_pss {
    srv_client *c;
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

/* ---- HTTP: /metrics and /status ------------------------------------------- */

static void stats_view(srv_net *n, srv_stats_view *v, char *scene, size_t sl)
{
    srv_hub *h = n->hub;
    memset(v, 0, sizeof *v);
    pthread_mutex_lock(&h->lock);
    v->clients = h->n_clients;
    v->subscribed = h->n_subscribed;
    v->tick_rate = h->settings.srv.tick_rate;
    snprintf(scene, sl, "%s", h->settings.scene.name);
    v->wind = h->sea_now.wind_u10;
    v->hs = h->sea_now.hs;
    v->has_camera_hint = h->settings.scene.camera_hint[0] &&
                         ocean_conf_camera_hint_parse(h->settings.scene.camera_hint, v->camera_hint) == OCEAN_OK;
    pthread_mutex_unlock(&h->lock);
    v->sim_time = srv_hub_sim_time(h);
    v->scene = scene;
    v->version = "oceand 0.1";
    v->port = n->port;
}

static int cb_http(struct lws *wsi, enum lws_callback_reasons reason, void *user, void *in,
                   size_t len)
{
    http_pss *pss = user;
    srv_net *n = lws_context_user(lws_get_context(wsi));
    switch (reason) {
    case LWS_CALLBACK_ESTABLISHED: {
        /* A WebSocket that did not offer the ocean.v1 subprotocol lands on
         * the first protocol (this one): close it with a reason rather than
         * leave it in silence (PROTOCOL.md "Transport"). */
        static const char why[] = "subprotocol ocean.v1 required (Sec-WebSocket-Protocol: ocean.v1)";
        lws_close_reason(wsi, LWS_CLOSE_STATUS_PROTOCOL_ERR, (unsigned char *)why, sizeof why - 1);
        return -1;
    }
    case LWS_CALLBACK_HTTP: {
        char uri[128] = "";
        lws_hdr_copy(wsi, uri, sizeof uri, WSI_TOKEN_GET_URI);
        srv_stats_view v;
        char scene[OCEAN_SCENE_NAME_MAX];
        stats_view(n, &v, scene, sizeof scene);
        const char *type;
        if (strncmp(uri, "/metrics", 8) == 0) {
            pss->body = srv_stats_prometheus(&n->hub->stats, &v, LWS_PRE, &pss->len);
            type = "text/plain; version=0.0.4; charset=utf-8";
        } else if (strncmp(uri, "/status", 7) == 0) {
            pss->body = srv_stats_json(&n->hub->stats, &v, LWS_PRE, &pss->len);
            type = "application/json";
        } else {
            return lws_callback_http_dummy(wsi, reason, user, in, len);
        }
        if (!pss->body) {
            lws_return_http_status(wsi, HTTP_STATUS_INTERNAL_SERVER_ERROR, "out of memory");
            return -1;
        }
        uint8_t hdr[LWS_PRE + 512], *start = hdr + LWS_PRE, *p = start, *end = hdr + sizeof hdr - 1;
        if (lws_add_http_common_headers(wsi, HTTP_STATUS_OK, type, pss->len, &p, end) ||
            lws_add_http_header_by_token(wsi, WSI_TOKEN_HTTP_CACHE_CONTROL,
                                         (const unsigned char *)"no-store", 8, &p, end) ||
            lws_finalize_write_http_header(wsi, start, &p, end))
            return 1;
        lws_callback_on_writable(wsi);
        return 0;
    }
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

static void kill_client(srv_client *c, const char *why)
{
    if (!c->wsi || c->closing == 3) return;
    c->closing = 3;
    lws_close_reason(c->wsi, LWS_CLOSE_STATUS_POLICY_VIOLATION, (unsigned char *)why, strlen(why));
    lws_set_timeout(c->wsi, PENDING_TIMEOUT_USER_OK, LWS_TO_KILL_ASYNC);
}

/* Runs on every wake: hands writable requests to lws, enforces limits,
 * drives the shutdown. */
static void on_wake(srv_net *n)
{
    srv_hub *h = n->hub;
    double now = srv_now();
    int stopping = atomic_load(&n->stop);
    pthread_mutex_lock(&h->lock);
    srv_config cfg = h->settings.srv;
    if (stopping && n->stop_phase == 0) {
        n->stop_phase = 1;
        h->stopping = 1;
    }
    for (srv_client *c = h->clients; c; c = c->next) {
        if (!c->wsi || c->closed) continue;
        if (stopping && c->closing != 1 && c->closing != 3 && c->closing != 4) {
            /* queue BYE after whatever is queued; frames stop mattering */
            c->closing = 1;
            srv_client_send_bye(c, PROTO_BYE_SHUTDOWN, "server shutting down");
        }
        uint64_t q = srv_client_queued(c) + c->inflight;
        if (q > cfg.output_hard) {
            char why[120];
            snprintf(why, sizeof why, "slow consumer: %llu bytes queued, over server.output_hard",
                     (unsigned long long)q);
            atomic_fetch_add(&h->stats.disconnects_slow, 1);
            kill_client(c, why);
            continue;
        }
        if (q > cfg.output_soft) {
            if (c->over_soft_since == 0) c->over_soft_since = now;
            else if (now - c->over_soft_since > cfg.output_soft_seconds) {
                atomic_fetch_add(&h->stats.disconnects_slow, 1);
                kill_client(c, "slow consumer: over server.output_soft for too long");
                continue;
            }
        } else {
            c->over_soft_since = 0;
        }
        /* A reader that takes nothing at all for the soft period is gone:
         * output has waited that long with no send completed.  lws holding
         * the rest of a write is one sign; a message waiting for a socket
         * that never turns writable is the other, since the kernel may have
         * taken the last FRAME whole (lws sends it in one piece). */
        int pending = q > 0;
        if (!pending) c->pending_since = 0;
        else if (c->pending_since == 0) c->pending_since = now;
        if (pending && now - fmax(c->pending_since, c->last_progress) > fmax(cfg.output_soft_seconds, 1.0)) {
            atomic_fetch_add(&h->stats.disconnects_slow, 1);
            kill_client(c, "slow consumer: no bytes read for server.output_soft_seconds");
            continue;
        }
        if (atomic_exchange(&c->want_write, 0) || c->closing == 2) lws_callback_on_writable(c->wsi);
    }
    pthread_mutex_unlock(&h->lock);
}

static void send_next(srv_net *n, srv_client *c, struct lws *wsi, int *close_now)
{
    srv_hub *h = n->hub;
    *close_now = 0;
    if (c->closing == 2) { /* client said BYE */
        lws_close_reason(wsi, LWS_CLOSE_STATUS_NORMAL, (unsigned char *)"bye", 3);
        *close_now = 1;
        return;
    }
    if (c->closing == 4) { /* BYE written and flushed */
        lws_close_reason(wsi, LWS_CLOSE_STATUS_GOINGAWAY, (unsigned char *)"server shutting down", 20);
        *close_now = 1;
        return;
    }
    if (lws_partial_buffered(wsi)) {
        lws_callback_on_writable(wsi);
        return;
    }
    c->inflight = 0;
    srv_msg *m = srv_client_take(c);
    if (!m) return;
    size_t len;
    uint8_t *data = srv_msg_wire(m, &len);
    if (len >= PROTO_HEADER_SIZE) proto_st32(data + 16, c->tx_seq++);
    int w = lws_write(wsi, data, len, LWS_WRITE_BINARY);
    double now = srv_now();
    if (w < (int)len) {
        srv_msg_free(m);
        *close_now = 1;
        return;
    }
    c->last_progress = now;
    atomic_fetch_add(&h->stats.bytes_sent, len);
    atomic_fetch_add(&h->stats.messages_sent, 1);
    if (m->is_frame) {
        atomic_fetch_add(&h->stats.frames_sent, 1);
        if (m->tick_wall > 0) srv_stats_latency(&h->stats, now - m->tick_wall);
    }
    if (lws_partial_buffered(wsi)) c->inflight = len;
    if (m->close_after) c->closing = 4;
    srv_msg_free(m);
    /* more to send, or the final close after the BYE */
    lws_callback_on_writable(wsi);
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
    case LWS_CALLBACK_ESTABLISHED: {
        srv_client *c;
        if (srv_client_create(h, wsi, &c) != OCEAN_OK) return -1;
        pss->c = c;
        pthread_mutex_lock(&h->lock);
        int full = h->n_clients > h->settings.srv.max_clients;
        int stopping = h->stopping;
        int record = h->settings.srv.record;
        char dir[SRV_PATH_MAX], scene[OCEAN_SCENE_NAME_MAX];
        snprintf(dir, sizeof dir, "%s", h->settings.srv.record_dir);
        snprintf(scene, sizeof scene, "%s", h->settings.scene.name);
        int verbose = h->settings.srv.verbose;
        pthread_mutex_unlock(&h->lock);
        if (full || stopping) {
            if (full) atomic_fetch_add(&h->stats.refused_full, 1);
            c->closing = 1;
            srv_client_send_bye(c, stopping ? PROTO_BYE_SHUTDOWN : PROTO_BYE_SERVER_FULL,
                                stopping ? "server shutting down"
                                         : "server full: server.max_clients connections in use");
            lws_callback_on_writable(wsi);
            break;
        }
        char arg[16];
        if (lws_get_urlarg_by_name(wsi, "record", arg, sizeof arg) &&
            (strcmp(arg, "record=1") == 0 || strcmp(arg, "1") == 0))
            record = 1;
        if (record) {
            char path[1100], msg[300];
            if (srv_record_open(dir, c->id, scene, "live", &c->rec, path, sizeof path, msg,
                                sizeof msg) != OCEAN_OK)
                fprintf(stderr, "oceand: client %u: not recording: %s\n", c->id, msg);
            else if (verbose)
                fprintf(stderr, "oceand: client %u: recording to %s\n", c->id, path);
        }
        if (verbose) fprintf(stderr, "oceand: client %u connected\n", c->id);
        srv_client_send_hello(c);
        lws_callback_on_writable(wsi);
        break;
    }
    case LWS_CALLBACK_RECEIVE: {
        srv_client *c = pss->c;
        if (!c || c->closing) break;
        pthread_mutex_lock(&h->lock);
        size_t maxm = (size_t)h->settings.srv.max_message;
        pthread_mutex_unlock(&h->lock);
        if (lws_is_first_fragment(wsi)) {
            c->rx_len = 0;
            c->rx_discard = 0;
            c->rx_discarded = 0;
        }
        if (!c->rx_discard && c->rx_len + len > maxm) {
            c->rx_discard = 1;
            c->rx_discarded = c->rx_len;
            /* keep the header for the ERROR's offending type and seq */
            if (c->rx_len > PROTO_HEADER_SIZE) c->rx_len = PROTO_HEADER_SIZE;
        }
        if (c->rx_discard) {
            c->rx_discarded += len;
            size_t keep = c->rx_len < PROTO_HEADER_SIZE ? PROTO_HEADER_SIZE - c->rx_len : 0;
            if (keep > len) keep = len;
            len = keep;
        }
        if (len) {
            if (c->rx_len + len > c->rx_cap) {
                size_t nc = c->rx_cap ? c->rx_cap : 4096;
                while (nc < c->rx_len + len) nc *= 2;
                uint8_t *nb = realloc(c->rx, nc);
                if (!nb) return -1;
                c->rx = nb;
                c->rx_cap = nc;
            }
            memcpy(c->rx + c->rx_len, in, len);
            c->rx_len += len;
        }
        if (!lws_is_final_fragment(wsi) || lws_remaining_packet_payload(wsi)) break;
        if (!lws_frame_is_binary(wsi)) {
            srv_client_send_error(c, NULL, 0, OCEAN_EFORMAT,
                                  "text messages are not part of ocean.v1: send binary WebSocket messages");
        } else if (c->rx_discard) {
            char why[200];
            snprintf(why, sizeof why, "message of %zu bytes or more exceeds server.max_message (%zu bytes)",
                     c->rx_discarded, maxm);
            srv_client_send_error(c, c->rx, c->rx_len, OCEAN_ETOOBIG, why);
        } else {
            srv_client_handle(c, c->rx, c->rx_len);
        }
        c->rx_len = 0;
        c->rx_discard = 0;
        if (atomic_exchange(&c->want_write, 0) || c->closing) lws_callback_on_writable(wsi);
        /* a big reassembly buffer is not kept for the connection's life */
        if (c->rx_cap > (1u << 20)) {
            free(c->rx);
            c->rx = NULL;
            c->rx_cap = 0;
        }
        break;
    }
    case LWS_CALLBACK_SERVER_WRITEABLE: {
        srv_client *c = pss->c;
        if (!c) break;
        int close_now;
        send_next(n, c, wsi, &close_now);
        if (close_now) return -1;
        break;
    }
    case LWS_CALLBACK_CLOSED: {
        srv_client *c = pss->c;
        if (!c) break;
        pthread_mutex_lock(&h->lock);
        int verbose = h->settings.srv.verbose;
        pthread_mutex_unlock(&h->lock);
        if (verbose) fprintf(stderr, "oceand: client %u closed\n", c->id);
        pss->c = NULL;
        srv_client_remove(c);
        break;
    }
    default:
        break;
    }
    return 0;
}

/* ---- lifecycle ---------------------------------------------------------------- */

ocean_result srv_net_create(srv_hub *h, srv_net **out, char *msg, size_t msglen)
{
    srv_net *n = calloc(1, sizeof *n);
    if (!n) return OCEAN_ENOMEM;
    n->hub = h;
    pthread_mutex_lock(&h->lock);
    srv_config cfg = h->settings.srv;
    pthread_mutex_unlock(&h->lock);
    snprintf(n->web_root, sizeof n->web_root, "%s", cfg.web_root);
    lws_set_log_level(cfg.verbose ? (LLL_ERR | LLL_WARN | LLL_NOTICE) : LLL_ERR, NULL);

    n->protocols[0] = (struct lws_protocols){"http", cb_http, sizeof(http_pss), 0, 0, NULL, 0};
    /* tx_packet_size: a FRAME goes to send() whole.  Left at 0, lws caps
     * each send() at rx_buffer_size (64 KiB) and copies the rest of every
     * larger message into its own buffer for a later POLLOUT: at 256
     * viewers that copy was 8 % of the service thread, and the extra
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
    n->m_root = (struct lws_http_mount){.mount_next = &n->m_metrics, .mountpoint = "/",
                                        .origin = n->web_root, .def = "index.html",
                                        .origin_protocol = LWSMPRO_FILE, .mountpoint_len = 1};
    struct lws_context_creation_info info;
    memset(&info, 0, sizeof info);
    info.port = cfg.port;
    info.iface = cfg.bind[0] ? cfg.bind : NULL;
    info.protocols = n->protocols;
    info.mounts = &n->m_root;
    info.user = n;
    info.count_threads = 1;
    info.options = LWS_SERVER_OPTION_DISABLE_IPV6;
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

static void *net_main(void *arg)
{
    srv_net *n = arg;
    srv_hub *h = n->hub;
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
    if (n->ctx) lws_context_destroy(n->ctx);
    free(n);
}
