/*
 * srv_client.c - the shared part of each client, the hub and its sea-state
 * timeline, and the replies the daemon queues (see srv_client.h).  What it
 * does with each message a client sends is srv_handle.c's.
 */
#include "srv_client.h"
#include "srv_cascade.h"

#include <fftw3.h>
#include <libwebsockets.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "srv_record.h"
#include "srv_tiles.h"
#include "srv_redis.h"

double srv_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void srv_sea_from_params(const ocean_params *p, proto_sea *o)
{
    memset(o, 0, sizeof *o);
    o->spectrum = (uint8_t)p->sea.spectrum;
    o->spreading = (uint8_t)p->sea.spreading;
    o->seed = p->seed;
    o->wind_u10 = p->sea.wind_u10;
    o->wind_dir_deg = p->sea.wind_dir_deg;
    o->fetch_m = p->sea.fetch_m;
    o->depth_m = p->sea.depth_m;
    o->swell = p->sea.swell;
    o->phillips_a = p->sea.phillips_a;
    o->small_wave_m = p->sea.small_wave_m;
    o->choppiness = p->sea.choppiness;
    double hs = ocean_spectrum_hs(&p->sea);
    double wp = ocean_spectrum_peak(&p->sea);
    o->hs = isfinite(hs) && hs >= 0 && hs <= 1000 ? hs : 0;
    o->tp = wp > 0 && 2 * M_PI / wp <= 1e4 ? 2 * M_PI / wp : 0;
}

void srv_params_from_sea(const proto_sea *s, const ocean_params *base, ocean_params *o)
{
    *o = *base;
    o->sea.spectrum = (ocean_spectrum_kind)s->spectrum;
    o->sea.spreading = (ocean_spreading_kind)s->spreading;
    o->seed = s->seed;
    o->sea.wind_u10 = s->wind_u10;
    o->sea.wind_dir_deg = s->wind_dir_deg;
    o->sea.fetch_m = s->fetch_m;
    o->sea.depth_m = s->depth_m;
    o->sea.swell = s->swell;
    o->sea.phillips_a = s->phillips_a;
    o->sea.small_wave_m = s->small_wave_m;
    o->sea.choppiness = s->choppiness;
}

void srv_mesh_camera(const proto_camera *pc, mesh_camera *c)
{
    mesh_camera_default(c);
    for (int i = 0; i < 3; i++) c->pos[i] = pc->pos[i];
    c->yaw_deg = pc->yaw_deg;
    c->pitch_deg = pc->pitch_deg;
    c->roll_deg = pc->roll_deg;
    c->fov_y_deg = pc->fov_y_deg;
    c->viewport_w = pc->viewport_w;
    c->viewport_h = pc->viewport_h;
}

/* ---- determinism fingerprint ---------------------------------------------- */

static uint64_t fnv(uint64_t h, const void *p, size_t n)
{
    const uint8_t *b = p;
    for (size_t i = 0; i < n; i++) {
        h ^= b[i];
        h *= 0x100000001b3ull;
    }
    return h;
}

static uint64_t fnv_str(uint64_t h, const char *s) { return fnv(h, s, strlen(s) + 1); }

static uint64_t fnv_f64(uint64_t h, double v)
{
    uint64_t u;
    memcpy(&u, &v, 8);
    return fnv(h, &u, 8);
}

static uint64_t fnv_int(uint64_t h, long long v) { return fnv(h, &v, sizeof v); }

void srv_fingerprint(const srv_settings *s, char out[17])
{
    uint64_t h = 0xcbf29ce484222325ull;
    h = fnv_str(h, SRV_VERSION);
    h = fnv_str(h, __VERSION__);
#ifdef __OPTIMIZE__
    h = fnv_int(h, 1);
#endif
    __builtin_cpu_init();
    h = fnv_int(h, __builtin_cpu_supports("avx"));
    h = fnv_int(h, __builtin_cpu_supports("avx2"));
    h = fnv_int(h, __builtin_cpu_supports("fma"));
    h = fnv_int(h, __builtin_cpu_supports("avx512f"));
    h = fnv_str(h, fftwf_version);
    const ocean_params *p = &s->params;
    h = fnv_int(h, p->n);
    h = fnv_int(h, p->cascades);
    h = fnv_f64(h, p->patch_m);
    h = fnv_f64(h, p->cascade_ratio);
    h = fnv_f64(h, p->k_max);
    h = fnv_int(h, p->threads);
    h = fnv_int(h, p->plan_measure);
    h = fnv_f64(h, p->drop_gain);
    const srv_config *c = &s->srv;
    h = fnv_int(h, (long long)s->effects);
    h = fnv_f64(h, c->tick_rate);
    h = fnv_int(h, c->tiles_per_side);
    h = fnv_f64(h, c->base_spacing);
    h = fnv_f64(h, c->view_range);
    h = fnv_f64(h, c->mesh_error_px);
    h = fnv_f64(h, c->px_per_sample);
    h = fnv_f64(h, c->viewer_bytes_per_s);
    h = fnv_int(h, c->cascade_tile);
    h = fnv_int(h, c->near_field_waves);
    h = fnv_f64(h, c->near_field_radius);
    h = fnv_f64(h, c->near_field_min_wavelength);
    snprintf(out, 17, "%016llx", (unsigned long long)h);
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

static srv_msg *sea_announce_msg(const proto_sea *sea, double eff, double now)
{
    proto_msg m;
    proto_msg_init(&m, PROTO_SEA_STATE);
    m.hdr.sim_time = now;
    m.u.sea_state.op = PROTO_SEA_ANNOUNCE;
    m.u.sea_state.effective_time = eff;
    m.u.sea_state.sea = *sea;
    srv_msg *q = srv_msg_new();
    if (!q) return NULL;
    if (proto_encode(&q->buf, &m, NULL, 0) != OCEAN_OK) {
        srv_msg_free(q);
        return NULL;
    }
    return q;
}

ocean_result srv_hub_sea_schedule(srv_hub *h, const ocean_params *p, double requested, double *eff,
                                  char *why, size_t whylen)
{
    double now = srv_hub_sim_time(h);
    double e = requested > now ? requested : now;
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
        srv_msg *q = sea_announce_msg(&c->sea, e, now);
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

void srv_hub_wake_net(srv_hub *h)
{
    if (h->wake_net) h->wake_net(h->wake_ctx);
}

/* ---- messages ------------------------------------------------------------- */

void srv_client_hand_over(srv_client *c, srv_stats *st, srv_msg *topo, srv_msg *frame, int replay, double tick_wall)
{
    if (!frame) {
        srv_msg_free(topo);
        return;
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
    }
}

void srv_client_queue(srv_client *c, srv_msg *m)
{
    if (srv_outbox_queue(c->out, m) == 2) srv_hub_wake_net(c->hub);
}

/* ---- clients -------------------------------------------------------------- */

ocean_result srv_client_create(srv_hub *h, srv_client **out)
{
    srv_client *c = calloc(1, sizeof *c);
    if (!c) return OCEAN_ENOMEM;
    pthread_mutex_lock(&h->lock);
    uint64_t hard = h->settings.srv.output_hard;
    pthread_mutex_unlock(&h->lock);
    if (srv_outbox_create(hard, &c->out) != OCEAN_OK) {
        free(c);
        return OCEAN_ENOMEM;
    }
    atomic_init(&c->refs, 1);
    c->hub = h;
    atomic_init(&c->link_bps, 0);
    pthread_mutex_lock(&h->lock);
    c->id = h->next_id++;
    if (h->next_id == 0) h->next_id = 1;
    c->next = h->clients;
    h->clients = c;
    h->n_clients++;
    pthread_mutex_unlock(&h->lock);
    atomic_fetch_add(&h->stats.connections_total, 1);
    *out = c;
    return OCEAN_OK;
}

void srv_client_ref(srv_client *c) { atomic_fetch_add(&c->refs, 1); }

/* The replay cameras c sent and the server has not yet answered. */
void srv_client_drop_replay(srv_client *c)
{
    while (c->replay) {
        srv_replay_cam *r = c->replay;
        c->replay = r->next;
        free(r);
    }
    c->replay_tail = NULL;
    c->n_replay = 0;
}

static void free_requests(srv_client *c)
{
    while (c->queries) {
        srv_query *q = c->queries;
        c->queries = q->next;
        free(q->points);
        free(q);
    }
    c->n_queries = 0;
    srv_client_drop_replay(c);
}

void srv_client_unref(srv_client *c)
{
    if (!c || atomic_fetch_sub(&c->refs, 1) != 1) return;
    free_requests(c);
    srv_outbox_destroy(c->out);
    free(c);
}

void srv_client_remove(srv_client *c)
{
    srv_hub *h = c->hub;
    pthread_mutex_lock(&h->lock);
    for (srv_client **p = &h->clients; *p; p = &(*p)->next) {
        if (*p == c) {
            *p = c->next;
            h->n_clients--;
            if (c->subscribed) h->n_subscribed--;
            break;
        }
    }
    c->closed = 1;
    free_requests(c);
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
        /* HELLO, then the pending changes, before any later announce */
        srv_client_queue(c, q);
        for (int i = 0; i < h->n_sea_pending; i++) {
            srv_msg *a = sea_announce_msg(&h->sea_pending[i].sea, h->sea_pending[i].effective_time,
                                          m.hdr.sim_time);
            if (a) srv_client_queue(c, a);
        }
        c->hello_sent = 1;
    }
    pthread_mutex_unlock(&h->lock);
}

void srv_client_send_sea_timeline(srv_client *c)
{
    srv_hub *h = c->hub;
    pthread_mutex_lock(&h->lock);
    double now = srv_hub_sim_time(h);
    srv_msg *a = sea_announce_msg(&h->sea_now, h->sea_effective, now);
    if (a) srv_client_queue(c, a);
    for (int i = 0; i < h->n_sea_pending; i++) {
        a = sea_announce_msg(&h->sea_pending[i].sea, h->sea_pending[i].effective_time, now);
        if (a) srv_client_queue(c, a);
    }
    pthread_mutex_unlock(&h->lock);
}

/* ---- incoming ------------------------------------------------------------- */

/* Checks a SUBSCRIBE against this server; fills *eff with the effects that
 * will be served.  OCEAN_OK or an error with why. */
