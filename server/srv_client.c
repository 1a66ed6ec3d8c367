/*
 * srv_client.c - per-client state, the hub, the message queues between the
 * simulation and service threads, and the replies the daemon queues.  What
 * it does with each message a client sends is srv_handle.c's.
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
        c->closed = 1;
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

srv_msg *srv_msg_new(void)
{
    srv_msg *m = calloc(1, sizeof *m);
    if (m) proto_buf_init(&m->buf, LWS_PRE);
    return m;
}

srv_msg *srv_msg_encode(const proto_msg *m)
{
    srv_msg *q = srv_msg_new();
    if (!q) return NULL;
    char err[256];
    if (proto_encode(&q->buf, m, err, sizeof err) != OCEAN_OK) {
        /* Once a second at most: a failure repeats with every frame, and
         * any thread may get here. */
        static _Atomic int64_t said_s = INT64_MIN;
        static atomic_uint_fast64_t quiet;
        int64_t now = (int64_t)srv_now(), last = atomic_load(&said_s);
        if (now != last && atomic_compare_exchange_strong(&said_s, &last, now)) {
            uint64_t q_n = atomic_exchange(&quiet, 0);
            fprintf(stderr, "oceand: cannot encode %s: %s", proto_type_name(m->hdr.type), err);
            if (q_n) fprintf(stderr, " (%llu more since the last such line)", (unsigned long long)q_n);
            fputc('\n', stderr);
        } else {
            atomic_fetch_add(&quiet, 1);
        }
        srv_msg_free(q);
        return NULL;
    }
    return q;
}

srv_msg *srv_topology_encode(srv_client_sim *cs, const mesh_view *v, double t, const float *flat,
                             const float *zones)
{
    cs->mesh_id++;
    cs->topo_key = v->topology_key;
    cs->topo_valid = 1;
    proto_msg tm;
    proto_msg_init(&tm, PROTO_MESH_TOPOLOGY);
    tm.hdr.sim_time = t;
    tm.u.topology.mesh_id = cs->mesh_id;
    tm.u.topology.mesh_kind = (uint8_t)v->kind;
    tm.u.topology.lod_levels = (uint8_t)(v->levels < 1 ? 1 : v->levels);
    tm.u.topology.vertex_count = v->vertex_count;
    tm.u.topology.index_count = v->index_count;
    tm.u.topology.indices = v->indices;
    tm.u.topology.morph = v->morph;
    tm.u.topology.level = v->level;
    if (flat) {
        tm.u.topology.flags = PROTO_TOPO_FLAT;
        tm.u.topology.flat = flat;
        tm.u.topology.zones = zones;
    }
    srv_msg *q = srv_msg_encode(&tm);
    if (!q) cs->topo_valid = 0;
    return q;
}

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
    } else {
        srv_client_publish(c, topo, frame);
    }
}

void srv_msg_free(srv_msg *m)
{
    if (!m) return;
    proto_buf_free(&m->buf);
    if (m->blob && atomic_fetch_sub(&m->blob->refs, 1) == 1) {
        proto_buf_free(&m->blob->buf);
        free(m->blob);
    }
    free(m);
}

ocean_result srv_msg_make_shared(srv_msg *m)
{
    if (m->blob) return OCEAN_OK;
    srv_blob *b = malloc(sizeof *b);
    if (!b) return OCEAN_ENOMEM;
    atomic_init(&b->refs, 1);
    b->buf = m->buf;
    proto_buf_init(&m->buf, LWS_PRE);
    m->blob = b;
    return OCEAN_OK;
}

srv_msg *srv_msg_share(const srv_msg *m)
{
    if (!m->blob) return NULL;
    srv_msg *q = srv_msg_new();
    if (!q) return NULL;
    atomic_fetch_add(&m->blob->refs, 1);
    q->blob = m->blob;
    q->camera_seq = m->camera_seq;
    q->mesh_id = m->mesh_id;
    q->mesh_id_at = m->mesh_id_at;
    q->tick_wall = m->tick_wall;
    q->is_frame = m->is_frame;
    q->close_after = m->close_after;
    return q;
}

size_t srv_msg_len(const srv_msg *m)
{
    if (!m) return 0;
    return proto_buf_len(m->blob ? &m->blob->buf : &m->buf);
}

uint8_t *srv_msg_wire(srv_msg *m, size_t *len)
{
    proto_buf *b = m->blob ? &m->blob->buf : &m->buf;
    uint8_t *d = proto_buf_data(b);
    *len = proto_buf_len(b);
    if (m->blob && m->is_frame && *len >= SRV_FRAME_CAMERA_SEQ_AT + 4) {
        proto_st32(d + SRV_FRAME_CAMERA_SEQ_AT, m->camera_seq);
        if (m->mesh_id_at && (size_t)m->mesh_id_at + 4 <= *len) proto_st32(d + m->mesh_id_at, m->mesh_id);
    }
    return d;
}

static void free_list(srv_msg *m)
{
    while (m) {
        srv_msg *n = m->next;
        srv_msg_free(m);
        m = n;
    }
}

/* ---- clients -------------------------------------------------------------- */

ocean_result srv_client_create(srv_hub *h, struct lws *wsi, srv_client **out)
{
    srv_client *c = calloc(1, sizeof *c);
    if (!c) return OCEAN_ENOMEM;
    if (pthread_mutex_init(&c->out_lock, NULL)) {
        free(c);
        return OCEAN_ENOMEM;
    }
    atomic_init(&c->refs, 1);
    atomic_init(&c->want_write, 0);
    c->wsi = wsi;
    c->hub = h;
    c->bucket_t = c->last_progress = srv_now();
    srv_link_init(&c->link);
    atomic_init(&c->link_bps, 0);
    ocean_filter_smoother_init(&c->sim.smoother);
    pthread_mutex_lock(&h->lock);
    c->id = h->next_id++;
    if (h->next_id == 0) h->next_id = 1;
    c->bucket = h->settings.srv.msg_burst;
    atomic_init(&c->output_hard, h->settings.srv.output_hard);
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

/* Closes c's recording, saying what was lost if its file could not take
 * the last lines. */
static void close_recording(srv_client *c)
{
    char why[1200];
    if (c->rec && srv_record_close(c->rec, why, sizeof why) != OCEAN_OK)
        fprintf(stderr, "oceand: client %u: recording incomplete: %s\n", c->id, why);
    c->rec = NULL;
}

void srv_client_unref(srv_client *c)
{
    if (!c || atomic_fetch_sub(&c->refs, 1) != 1) return;
    free_requests(c);
    free_list(c->ctrl);
    srv_msg_free(c->slot_topo);
    srv_msg_free(c->slot_frame);
    mesh_destroy(c->sim.mesh);
    free(c->sim.qz_refs);
    srv_held_destroy(c->sim.held[0]);
    srv_held_destroy(c->sim.held[1]);
    close_recording(c);
    free(c->rx);
    pthread_mutex_destroy(&c->out_lock);
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
    c->wsi = NULL;
    free_requests(c);
    pthread_mutex_unlock(&h->lock);
    close_recording(c);
    srv_client_unref(c);
}

/* glibc malloc: 16 bytes of header per block, rounded to 16. */
#define MALLOC_OVERHEAD 16

size_t srv_msg_cost(const srv_msg *m)
{
    if (!m) return 0;
    size_t n = sizeof *m + MALLOC_OVERHEAD;
    if (m->buf.mem) n += m->buf.head + m->buf.cap + MALLOC_OVERHEAD;
    if (m->blob) n += sizeof *m->blob + m->blob->buf.head + m->blob->buf.cap + 2 * MALLOC_OVERHEAD;
    return n;
}

static size_t msg_bytes(const srv_msg *m) { return srv_msg_cost(m); }

void srv_client_queue(srv_client *c, srv_msg *m)
{
    m->next = NULL;
    /* The hard output limit holds when a message is queued, not only when
     * the service thread next looks: a client that makes the daemon queue
     * faster than it reads (a flood of refused messages, replay frames it
     * does not read) is cut off at the limit, and the message that would
     * pass it is not kept.  A BYE always goes in (it ends the queue). */
    size_t cost = msg_bytes(m);
    uint64_t hard = atomic_load(&c->output_hard);
    int refused = 0;
    pthread_mutex_lock(&c->out_lock);
    if (hard && !m->close_after && c->queued_bytes + cost > hard) {
        refused = 1;
    } else {
        if (c->ctrl_tail) c->ctrl_tail->next = m;
        else c->ctrl = m;
        c->ctrl_tail = m;
        c->queued_bytes += cost;
    }
    pthread_mutex_unlock(&c->out_lock);
    if (refused) {
        srv_msg_free(m);
        if (!atomic_exchange(&c->over_hard, 1)) srv_hub_wake_net(c->hub);
        return;
    }
    atomic_store(&c->want_write, 1);
}

void srv_client_publish(srv_client *c, srv_msg *topo, srv_msg *frame)
{
    srv_msg *drop_f = NULL, *drop_t = NULL;
    pthread_mutex_lock(&c->out_lock);
    if (c->slot_frame) {
        drop_f = c->slot_frame;
        c->queued_bytes -= msg_bytes(drop_f);
    }
    if (topo) {
        if (c->slot_topo) {
            drop_t = c->slot_topo;
            c->queued_bytes -= msg_bytes(drop_t);
        }
        c->slot_topo = topo;
        c->queued_bytes += msg_bytes(topo);
    }
    c->slot_frame = frame;
    c->queued_bytes += msg_bytes(frame);
    pthread_mutex_unlock(&c->out_lock);
    atomic_store(&c->want_write, 1);
    if (drop_f) atomic_fetch_add(&c->hub->stats.frames_skipped, 1);
    srv_msg_free(drop_f);
    srv_msg_free(drop_t);
}

srv_msg *srv_client_take(srv_client *c)
{
    srv_msg *m = NULL;
    pthread_mutex_lock(&c->out_lock);
    if (c->ctrl) {
        m = c->ctrl;
        c->ctrl = m->next;
        if (!c->ctrl) c->ctrl_tail = NULL;
    } else if (c->slot_topo) {
        m = c->slot_topo;
        c->slot_topo = NULL;
    } else if (c->slot_frame) {
        m = c->slot_frame;
        c->slot_frame = NULL;
        m->live = 1;
    }
    if (m) c->queued_bytes -= msg_bytes(m);
    pthread_mutex_unlock(&c->out_lock);
    if (m) m->next = NULL;
    return m;
}

int srv_client_next_is_live(srv_client *c)
{
    pthread_mutex_lock(&c->out_lock);
    int live = !c->ctrl && (c->slot_topo || c->slot_frame);
    pthread_mutex_unlock(&c->out_lock);
    return live;
}

int srv_client_frame_waiting(srv_client *c)
{
    pthread_mutex_lock(&c->out_lock);
    int waiting = c->slot_frame != NULL;
    pthread_mutex_unlock(&c->out_lock);
    return waiting;
}

uint64_t srv_client_queued(srv_client *c)
{
    pthread_mutex_lock(&c->out_lock);
    uint64_t q = c->queued_bytes;
    pthread_mutex_unlock(&c->out_lock);
    return q;
}

/* ---- replies ---------------------------------------------------------------- */

static int verbose(srv_client *c)
{
    pthread_mutex_lock(&c->hub->lock);
    int v = c->hub->settings.srv.verbose;
    pthread_mutex_unlock(&c->hub->lock);
    return v;
}

/* The largest error budget a mesh takes (mesh_config_validate). */
#define MESH_ERROR_PX_MAX 100.0

int srv_client_mesh_fit(srv_client *c, const mesh_camera *mc, int max_vertices, uint32_t cam_seq,
                        srv_stats *st)
{
    srv_client_sim *cs = &c->sim;
    if (!cs->mesh) /* none subscribed, or it failed: not remade before the next SUBSCRIBE */
        return 0;
    const mesh_config *sub = &cs->mesh_cfg;
    mesh_config cfg = *sub;
    double est = 0, est0 = 0;
    int k = 0;
    for (;; k++) {
        cfg.error_px = sub->error_px * (double)(1 << k);
        if (cfg.error_px > MESH_ERROR_PX_MAX || mesh_estimate_vertices(&cfg, mc, &est) != OCEAN_OK) {
            k = -1;
            break;
        }
        if (k == 0)
            est0 = est;
        /* a coarser mesh comes back only with room to spare, so a camera
         * hovering at the limit does not flip topologies every frame */
        if (est <= max_vertices && (k >= cs->mesh_coarsen || est <= 0.8 * max_vertices))
            break;
    }
    if (k < 0) {
        if (!cs->mesh_over) {
            char why[320];
            snprintf(why, sizeof why, "camera %u: its %s mesh is estimated at %.4g vertices, above the "
                     "server's limit of %d (server.max_mesh_vertices), even at %g px; frames come "
                     "without a mesh until a camera asks for less (wider fov, smaller viewport or range)",
                     cam_seq, mesh_kind_name(sub->kind), est0, max_vertices,
                     sub->kind == MESH_CONCENTRIC ? MESH_ERROR_PX_MAX : sub->error_px);
            atomic_fetch_add(&st->refused_mesh, 1);
            srv_client_send_error(c, NULL, 0, OCEAN_ETOOBIG, why);
            cs->mesh_over = 1;
        }
        return 0;
    }
    cs->mesh_over = 0;
    if (k == cs->mesh_coarsen)
        return 1;
    mesh *m = NULL;
    ocean_result r = mesh_create(&cfg, &m);
    if (r != OCEAN_OK) {
        char why[200];
        snprintf(why, sizeof why, "mesh %s unavailable, frames come without a mesh: %s",
                 mesh_kind_name(cfg.kind), ocean_strerror(r));
        srv_client_send_error(c, NULL, 0, r, why);
        return 0;
    }
    mesh_destroy(cs->mesh);
    cs->mesh = m;
    cs->topo_valid = 0;
    if (k > 0) {
        char why[320];
        snprintf(why, sizeof why, "camera %u: its %s mesh at %g px (server.mesh_error_px) would be %.4g "
                 "vertices, above the server's limit of %d (server.max_mesh_vertices); it is drawn at "
                 "%g px (%.4g vertices) while the camera needs it", cam_seq, mesh_kind_name(cfg.kind),
                 sub->error_px, est0, max_vertices, cfg.error_px, est);
        atomic_fetch_add(&st->coarsened_mesh, 1);
        srv_client_send_error(c, NULL, 0, OCEAN_ETOOBIG, why);
    }
    cs->mesh_coarsen = k;
    return 1;
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
