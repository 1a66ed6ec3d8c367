/*
 * srv_handle.c - what oceand does with each message a client sends: the
 * admission (message rate, read budget), the decoding, the link's
 * confirmations (srv_link.h), and one handler per message type, found in a
 * table (as Redis finds its commands).
 *
 * Every client message is checked in full before it changes anything: a
 * refused message gets an ERROR naming the field and leaves the client's
 * subscription, camera and queues exactly as they were.
 *
 * Threads: the service thread calls in, one message at a time per client;
 * what the simulation thread reads (subscription, camera, queues) is
 * written under hub.lock.
 */
#include "srv_handle.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "srv_admit.h"
#include "srv_convert.h"
#include "srv_entity.h"
#include "srv_cascade.h"
#include "srv_record.h"
#include "srv_redis.h"
#include "srv_tiles.h"

/* Whether two subscriptions ask for the same stream. */
static int sub_same(const proto_subscribe *a, const proto_subscribe *b)
{
    return a->effects == b->effects && a->mesh_kind == b->mesh_kind && a->codec == b->codec &&
           a->cutoff_policy == b->cutoff_policy && a->mode == b->mode && a->layers == b->layers &&
           a->lod_levels == b->lod_levels && a->tile_size == b->tile_size &&
           a->frame_rate_hz == b->frame_rate_hz && a->accuracy == b->accuracy &&
           a->base_spacing_m == b->base_spacing_m && a->view_range_m == b->view_range_m &&
           a->layout == b->layout && a->mesh_codec == b->mesh_codec && a->flags == b->flags;
}

/* Takes one of the client's SUBSCRIBE changes (SRV_SUBSCRIBE_*): 1 if it may
 * change its subscription now.  Service thread. */
static int sub_token(srv_session *s, double now)
{
    return srv_bucket_take(&s->sub_changes, SRV_SUBSCRIBE_PER_S, SRV_SUBSCRIBE_BURST, now, 1);
}

static ocean_result check_subscribe(const srv_settings *s, proto_subscribe *sub, char *why,
                                    size_t n)
{
    if (!(s->srv.codecs & (1u << sub->codec))) {
        snprintf(why, n, "subscribe.codec %s is disabled on this server (server.codecs)",
                 proto_codec_name((proto_codec)sub->codec));
        return OCEAN_EUNSUPPORTED;
    }
    unsigned eff = sub->effects & s->effects;
    if (!eff) {
        snprintf(why, n, "subscribe.effects 0x%x: none of them is computed in this scene "
                 "(HELLO effects 0x%x)", sub->effects, s->effects & PROTO_FX_ALL);
        return OCEAN_EUNSUPPORTED;
    }
    /* tile_size and lod_levels shape layout 0's per-camera tiles; layout 1
     * ignores them (PROTOCOL.md, SUBSCRIBE), so they are checked there only */
    int world = sub->layout != PROTO_LAYOUT_CASCADE;
    if (world && sub->tile_size > s->srv.max_tile_size) {
        snprintf(why, n, "subscribe.tile_size %u above the server's %d (server.max_tile_size)",
                 sub->tile_size, s->srv.max_tile_size);
        return OCEAN_ETOOBIG;
    }
    if (world && sub->lod_levels > s->srv.max_lod_levels) {
        snprintf(why, n, "subscribe.lod_levels %u above the server's %d (server.max_lod_levels)",
                 sub->lod_levels, s->srv.max_lod_levels);
        return OCEAN_ETOOBIG;
    }
    if (sub->frame_rate_hz > s->srv.max_frame_rate) {
        snprintf(why, n, "subscribe.frame_rate_hz %g above the server's %g (server.max_frame_rate)",
                 (double)sub->frame_rate_hz, s->srv.max_frame_rate);
        return OCEAN_EINVAL;
    }
    if (sub->frame_rate_hz > (float)s->srv.tick_rate) {
        /* one frame per tick at most: a faster rate would be served at the
         * tick rate without a word */
        snprintf(why, n, "subscribe.frame_rate_hz %g above the server's tick rate %g "
                 "(HELLO tick_rate_hz, server.tick_rate): frames are made on ticks",
                 (double)sub->frame_rate_hz, s->srv.tick_rate);
        return OCEAN_EINVAL;
    }
    double spacing = sub->base_spacing_m > 0 ? sub->base_spacing_m : s->srv.base_spacing;
    double top = spacing * ldexp(1.0, sub->lod_levels - 1) * sub->tile_size;
    if (world && top > 1e7) {
        snprintf(why, n, "subscribe: the coarsest tile would span %g m (base spacing %g m, "
                 "%u levels, %u samples); keep it under 10 000 km", top, spacing, sub->lod_levels,
                 sub->tile_size);
        return OCEAN_EINVAL;
    }
    /* Small tiles keep the span above in bounds while the coarsest spacing
     * passes what a TILE can state: accepted, every FRAME then failed to
     * encode (no FRAME, no ERROR, a log line per frame). */
    double coarsest = spacing * ldexp(1.0, sub->lod_levels - 1);
    if (world && coarsest > PROTO_TILE_SPACING_MAX) {
        snprintf(why, n, "subscribe: the coarsest level's spacing would be %g m (base spacing %g m x 2^%u), "
                 "above TILE.spacing's %g m: fewer lod_levels or a smaller base_spacing_m", coarsest,
                 spacing, (unsigned)sub->lod_levels - 1u, PROTO_TILE_SPACING_MAX);
        return OCEAN_EINVAL;
    }
    if (sub->layout == PROTO_LAYOUT_CASCADE) {
        if (sub->mesh_kind != PROTO_MESH_CONCENTRIC && sub->mesh_kind != PROTO_MESH_NONE) {
            snprintf(why, n, "subscribe.layout 1 (cascade tiles) places a concentric mesh or none; mesh_kind %s "
                     "needs layout 0", mesh_kind_name((mesh_kind)sub->mesh_kind));
            return OCEAN_EUNSUPPORTED;
        }
        ocean_params served = s->params;
        served.cascades = srv_settings_layout1_cascades(s); /* with the near field's */
        uint32_t most = srv_cascade_max_tiles(&served, sub->layers, s->srv.cascade_tile);
        if (most > PROTO_MAX_FRAME_TILES) {
            snprintf(why, n, "layout 1: a frame could need %u tiles of server.cascade_tile %d samples, above "
                     "the protocol's %u", most, s->srv.cascade_tile, PROTO_MAX_FRAME_TILES);
            return OCEAN_ETOOBIG;
        }
    } else {
        /* The tile work a per-camera (layout 0) subscription asks for, priced
         * before any is done: samples per second over every level's tiles
         * at its frame rate.  Layout 1 tiles are shared; its bytes are held
         * to server.viewer_bytes_per_s by the planner. */
        double per = s->srv.tiles_per_side;
        /* Replay frames come from CAMERA reports, up to server.replay_per_tick
         * a tick, whatever frame_rate_hz says (1e-30 Hz priced a replay of
         * the heaviest tiles at nothing) */
        int replay = sub->mode == PROTO_MODE_REPLAY;
        double hz = replay ? (double)s->srv.replay_per_tick * s->srv.tick_rate : sub->frame_rate_hz;
        double rate = per * per * sub->lod_levels * (double)sub->tile_size * sub->tile_size * hz;
        if (srv_tiles_channels(eff) && rate > s->srv.max_sample_rate) {
            snprintf(why, n, "subscribe: %.4g tile samples/s (%d x %d tiles x %u levels x %u^2 "
                     "samples x %g Hz%s) above the server's %.4g (server.max_sample_rate)", rate,
                     s->srv.tiles_per_side, s->srv.tiles_per_side, sub->lod_levels, sub->tile_size, hz,
                     replay ? ": a replay's frames, server.replay_per_tick x server.tick_rate" : "",
                     s->srv.max_sample_rate);
            return OCEAN_ETOOBIG;
        }
    }
    sub->effects = (uint8_t)eff;
    int most_layers = sub->layout == PROTO_LAYOUT_CASCADE ? srv_settings_layout1_cascades(s) : s->params.cascades;
    if (sub->layers > most_layers) sub->layers = (uint8_t)most_layers;
    return OCEAN_OK;
}

/* A layout-0 subscription whose level-0 spacing is too coarse for the near
 * field's longest wave (two samples a wave: 2 pi / k_lo < 2 spacing) cannot
 * be carried the near field: its tiles never hold it, and the antialias
 * cutoff that spacing sets (a wavelength of 4 spacings) filters it from the
 * mesh.  Said in the log at the first such subscription of a run: the
 * default spacing is such a one, and a note at every start (when no layout-0
 * client may ever come: the browser viewer subscribes with layout 1) read
 * as a fault in the shipped configuration.  Returns 1 with the text in out
 * when s and sub call for the note [svc, hub.lock held]. */
static int near_spacing_note(const srv_settings *s, const proto_subscribe *sub, uint32_t id, char *out,
                             size_t n)
{
    if (sub->layout != PROTO_LAYOUT_WORLD || !(sub->effects & PROTO_FX_NEAR_FIELD) ||
        !srv_settings_near_cascade(s))
        return 0;
    double spacing = sub->base_spacing_m > 0 ? sub->base_spacing_m : s->srv.base_spacing;
    double longest = 2 * M_PI / s->params.k_max, shortest = s->srv.near_field_min_wavelength;
    if (!(longest < 2 * spacing)) return 0;
    snprintf(out, n, "client %u: layout 0 at a %g m level-0 spacing: the near field's waves (%.3g m to "
             "%.3g m) are all shorter than two samples, so its frames cannot carry them (a spacing "
             "<= %.3g m can; layout 1 carries them in a cascade of its own); said once a run",
             id, spacing, shortest, longest, 0.5 * longest);
    return 1;
}

static int rate_ok(srv_session *s, double rate, double burst)
{
    return srv_bucket_take(&s->messages, rate, burst, srv_now(), 1);
}

/* A refusal a flood would repeat (over the message rate, text frames) is
 * answered at most once a second: a reply per refused message would let a
 * client make the daemon queue as fast as it can send.  The ERROR says how
 * many went unanswered since the last one.  Returns 1 if one may go now. */
static int one_per_window(srv_session *s, double *last)
{
    double now = srv_now();
    if (*last > 0 && now - *last < 1.0) {
        s->rate_refused++;
        atomic_fetch_add(&s->c->hub->stats.refused_silent, 1);
        return 0;
    }
    *last = now;
    return 1;
}

/* A message over one of the connection's rates (what: the limit, said in
 * the ERROR): counted, and answered ERATE once a second (one_per_window)
 * with the count of those refused silently since. */
static void refuse_over_rate(srv_session *s, double *last, const uint8_t *buf, size_t len, const char *what)
{
    atomic_fetch_add(&s->c->hub->stats.refused_rate, 1);
    uint64_t before = s->rate_refused;
    if (!one_per_window(s, last)) return;
    char why[400];
    snprintf(why, sizeof why, "%s; %llu more refused without a reply since the last such ERROR", what,
             (unsigned long long)before);
    s->rate_refused = 0;
    srv_client_send_error(s->c, buf, len, OCEAN_ERATE, why);
}

static int admit(srv_session *s, const srv_config *cfg, const uint8_t *buf, size_t len)
{
    if (rate_ok(s, cfg->msg_rate, cfg->msg_burst)) return 1;
    char what[200];
    snprintf(what, sizeof what, "message refused: more than %g messages/s (burst %d) (server.msg_rate)",
             cfg->msg_rate, cfg->msg_burst);
    refuse_over_rate(s, &s->rate_err_t, buf, len, what);
    return 0;
}

void srv_handle_text(srv_session *s)
{
    srv_hub *h = s->c->hub;
    atomic_fetch_add(&h->stats.messages_received, 1);
    pthread_mutex_lock(&h->lock);
    srv_config cfg = h->settings.srv;
    pthread_mutex_unlock(&h->lock);
    if (!admit(s, &cfg, NULL, 0)) return;
    if (one_per_window(s, &s->text_err_t))
        srv_client_send_error(s->c, NULL, 0, OCEAN_EFORMAT,
                              "text messages are not part of ocean.v1: send binary WebSocket "
                              "messages (one such ERROR a second at most)");
}

/* One decoded client message and what it is handled with [svc]. */
typedef struct srv_in {
    srv_session *s;
    srv_client *c;              /* s->c */
    srv_hub *h;
    const srv_config *cfg;      /* the settings in force, copied */
    const uint8_t *buf;         /* the raw message, for ERROR's offending type and seq */
    size_t len;
    const proto_msg *m;
} srv_in;

static void refuse(const srv_in *in, ocean_result r, const char *why)
{
    srv_client_send_error(in->c, in->buf, in->len, r, why);
}

static void on_subscribe(const srv_in *in)
{
    srv_session *s = in->s;
    srv_client *c = in->c;
    srv_hub *h = in->h;
    proto_subscribe sub = in->m->u.subscribe;
    char why[512], note[400] = "";
    pthread_mutex_lock(&h->lock);
    ocean_result r = check_subscribe(&h->settings, &sub, why, sizeof why);
    if (r == OCEAN_OK && c->subscribed && sub_same(&c->sub, &sub)) {
        /* the stream in force already: nothing to change or send */
        pthread_mutex_unlock(&h->lock);
        return;
    }
    if (r == OCEAN_OK && !sub_token(s, srv_now())) {
        r = OCEAN_ERATE;
        snprintf(why, sizeof why, "SUBSCRIBE changes limited to %g a second (burst %g): refused, the "
                 "subscription in force stays", SRV_SUBSCRIBE_PER_S, SRV_SUBSCRIBE_BURST);
    }
    /* the daemon as a whole: the last check, so a refusal leaves the
     * price in force as it was */
    double price = r == OCEAN_OK ? srv_admit_price(h->admit, &h->settings.srv, &sub) : 0;
    if (r == OCEAN_OK && (r = srv_admit_take(h->admit, &h->settings.srv, &sub, s->price, price, why,
                                             sizeof why)) != OCEAN_OK)
        atomic_fetch_add(&h->stats.refused_admission, 1);
    if (r == OCEAN_OK) {
        s->price = price;
        if (!c->subscribed) h->n_subscribed++;
        /* A live subscription drops the replay backlog, never the QUERYs:
         * they are answered in order whatever the mode. */
        if (sub.mode != PROTO_MODE_REPLAY) srv_inbox_drop_replays(c->in);
        c->subscribed = 1;
        c->sub = sub;
        c->sub_gen++;
        pthread_cond_signal(&h->wake);
        if (!h->near_spacing_said && near_spacing_note(&h->settings, &sub, c->id, note, sizeof note))
            h->near_spacing_said = 1;
    }
    pthread_mutex_unlock(&h->lock);
    if (r != OCEAN_OK) refuse(in, r, why);
    else if (s->rec && srv_record_mode(s->rec, srv_hub_sim_time(h), sub.mode == PROTO_MODE_REPLAY) != OCEAN_OK)
        fprintf(stderr, "oceand: client %u: recording stopped (quota or write error)\n", c->id);
    if (note[0]) fprintf(stderr, "oceand: %s\n", note);
}

/* A replay-mode CAMERA joins the client's replay queue [hub.lock held];
 * its sim time is the render time it asks for. */
static ocean_result replay_camera(const srv_in *in, double *t_rec, char *why, size_t n)
{
    srv_client *c = in->c;
    const proto_camera *k = &in->m->u.camera;
    if (srv_inbox_replays(c->in) >= in->cfg->replay_queue) {
        snprintf(why, n, "replay queue full: %d cameras wait for frames (server.replay_queue); wait for "
                 "FRAMEs before sending more", srv_inbox_replays(c->in));
        return OCEAN_ERATE;
    }
    srv_replay_cam *rc = calloc(1, sizeof *rc);
    if (!rc) {
        snprintf(why, n, "out of memory");
        return OCEAN_ENOMEM;
    }
    rc->cam = *k;
    rc->seq = in->m->hdr.seq;
    srv_inbox_push_replay(c->in, rc);
    *t_rec = k->render_time;
    pthread_cond_signal(&in->h->wake);
    return OCEAN_OK;
}

static void on_camera(const srv_in *in)
{
    srv_session *s = in->s;
    srv_client *c = in->c;
    srv_hub *h = in->h;
    const proto_camera *k = &in->m->u.camera;
    mesh_camera mc;
    srv_mesh_camera(k, &mc);
    char msg[256], why[512];
    if (mesh_camera_validate(&mc, msg, sizeof msg) != OCEAN_OK) {
        snprintf(why, sizeof why, "camera refused: %s", msg);
        refuse(in, OCEAN_EINVAL, why);
        return;
    }
    double t_rec = srv_hub_sim_time(h);
    ocean_result r = OCEAN_OK;
    pthread_mutex_lock(&h->lock);
    if (!c->subscribed) {
        r = OCEAN_ESTATE;
        snprintf(why, sizeof why, "CAMERA before SUBSCRIBE: subscribe first");
    } else if (c->sub.mode == PROTO_MODE_REPLAY) {
        r = replay_camera(in, &t_rec, why, sizeof why);
    } else {
        c->cam = *k;
        c->cam_seq = in->m->hdr.seq;
        c->has_camera = 1;
    }
    pthread_mutex_unlock(&h->lock);
    if (r != OCEAN_OK) {
        refuse(in, r, why);
    } else if (s->rec && (r = srv_record_camera(s->rec, t_rec, k)) != OCEAN_OK) {
        char what[1200];
        fprintf(stderr, "oceand: client %u: recording stopped %s%s\n", c->id,
                r == OCEAN_ETOOBIG ? "at server.record_max_bytes" : "after a write error: ",
                r == OCEAN_ETOOBIG ? "" : srv_record_why(s->rec, what, sizeof what));
    }
}

static void on_query(const srv_in *in)
{
    srv_client *c = in->c;
    srv_hub *h = in->h;
    const proto_query *q = &in->m->u.query;
    srv_query *sq = calloc(1, sizeof *sq);
    double *pts = sq ? malloc(2 * sizeof(double) * q->count) : NULL;
    if (!pts) {
        free(sq);
        refuse(in, OCEAN_ENOMEM, "out of memory for the query");
        return;
    }
    memcpy(pts, q->points, 2 * sizeof(double) * q->count);
    sq->query_id = q->query_id;
    sq->seq = in->m->hdr.seq;
    sq->at_time = q->at_time;
    sq->t = q->t;
    sq->count = q->count;
    sq->points = pts;
    char why[200];
    pthread_mutex_lock(&h->lock);
    int waiting = srv_inbox_queries(c->in) + c->n_queries_active;
    if (waiting < in->cfg->max_pending_queries) {
        srv_inbox_push_query(c->in, sq);
        sq = NULL;
        pthread_cond_signal(&h->wake);
    }
    pthread_mutex_unlock(&h->lock);
    if (sq) {
        free(sq->points);
        free(sq);
        snprintf(why, sizeof why, "%d queries already wait for answers (server.max_pending_queries)", waiting);
        refuse(in, OCEAN_ERATE, why);
    }
}

/* A token (the admin token of a SEA_STATE set, the entity token of an
 * ENTITY set or remove: `what` names it), compared in constant time unless
 * this connection or its address is in the guard's backoff (srv_admin.h:
 * the guesser waits, not the holder of the right token; a waiting attempt
 * is not compared).  One guard for both tokens: a guesser of either waits.
 * 1 if the token is right; else refused (ERROR sent). */
static int token_ok(const srv_in *in, const char *want, const char *token, const char *what)
{
    srv_session *s = in->s;
    srv_hub *h = in->h;
    const srv_config *cfg = in->cfg;
    char why[300];
    double now = srv_now();
    double until = fmax(s->admin_until, srv_admin_locked_until(&h->admin, s->peer, now));
    if (now < until) {
        atomic_fetch_add(&h->stats.admin_locked, 1);
        snprintf(why, sizeof why, "%s refused: tokens locked out for %.1f s more after "
                 "wrong tokens from this connection or address (server.admin_lockout)", what, until - now);
        refuse(in, OCEAN_ERATE, why);
        return 0;
    }
    size_t a = strlen(want), b = strlen(token);
    unsigned diff = (unsigned)(a ^ b);
    for (size_t i = 0; i < a; i++) diff |= (unsigned)(want[i] ^ token[i < b ? i : 0]);
    if (!diff) {
        s->admin_misses = 0;
        srv_admin_hit(&h->admin, s->peer);
        return 1;
    }
    atomic_fetch_add(&h->stats.admin_misses, 1);
    int k = s->admin_misses < 6 ? s->admin_misses : 6, alarm;
    s->admin_misses++;
    s->admin_until = now + cfg->admin_lockout * (double)(1 << k);
    srv_admin_miss(&h->admin, s->peer, cfg->admin_lockout, now, &alarm);
    if (alarm)
        fprintf(stderr, "oceand: more than %d wrong tokens in %d s: SEA_STATE and ENTITY sets locked for %d s "
                "for every address that sent one (the last: %s)\n", SRV_ADMIN_GLOBAL_MISSES, SRV_ADMIN_WINDOW,
                SRV_ADMIN_WINDOW, s->peer);
    snprintf(why, sizeof why, "%s refused: wrong %s token; next attempt in %.1f s (server.admin_lockout)", what,
             want == cfg->admin_token ? "admin" : "entity",
             fmax(s->admin_until, srv_admin_locked_until(&h->admin, s->peer, now)) - now);
    refuse(in, OCEAN_EAUTH, why);
    return 0;
}

/* Takes one of the connection's SEA_STATE sets (SRV_SEA_SET_*): each is
 * checked and built at a cost (ocean_params_validate: 0.4-1.4 ms; an ocean
 * per change), so a client holding the token may not flood them.  Over the
 * rate: refused ERATE, answered once a second as other floods are.
 * Returns 1 if the set may go on. */
static int sea_set_token(const srv_in *in)
{
    srv_session *s = in->s;
    if (srv_bucket_take(&s->sea_sets, SRV_SEA_SET_PER_S, SRV_SEA_SET_BURST, srv_now(), 1)) return 1;
    char what[200];
    snprintf(what, sizeof what, "SEA_STATE set refused: more than %g sets a second (burst %g) from this connection",
             SRV_SEA_SET_PER_S, SRV_SEA_SET_BURST);
    refuse_over_rate(s, &s->sea_err_t, in->buf, in->len, what);
    return 0;
}

/* Every sea change is logged with who made it: the client and its
 * address (the admin token says only that it was an admin). */
static void sea_set_log(const srv_in *in, const proto_sea *sea, double eff, const char *how)
{
    fprintf(stderr,
            "oceand: sea state set by client %u (%s), %s t = %.3f s: spectrum %u, spreading %u, wind %.2f m/s "
            "direction %.1f deg, fetch %.0f m, depth %.0f m, choppiness %.2f, seed %llu\n",
            in->c->id, in->s->peer[0] ? in->s->peer : "?", how, eff, sea->spectrum, sea->spreading, sea->wind_u10,
            sea->wind_dir_deg, sea->fetch_m, sea->depth_m, sea->choppiness, (unsigned long long)sea->seed);
}

static void on_sea_state(const srv_in *in)
{
    srv_hub *h = in->h;
    const proto_sea_state *s = &in->m->u.sea_state;
    if (s->op == PROTO_SEA_GET) {
        srv_client_send_sea_timeline(in->c);
        return;
    }
    if (s->op != PROTO_SEA_SET) {
        refuse(in, OCEAN_EINVAL, "SEA_STATE announce is server-to-client; send op = set");
        return;
    }
    if (!in->cfg->admin_token[0]) {
        refuse(in, OCEAN_EAUTH, "runtime sea-state changes are disabled on this server (server.admin_token is "
                                "empty)");
        return;
    }
    if (!sea_set_token(in)) return;
    if (!token_ok(in, in->cfg->admin_token, s->token, "SEA_STATE set")) return;
    char why[512], msg[256];
    pthread_mutex_lock(&h->lock);
    ocean_params np;
    srv_params_from_sea(&s->sea, &h->settings.params, &np);
    ocean_result r = ocean_params_validate(&np, msg, sizeof msg);
    if (r == OCEAN_OK && h->redis) {
        /* replicated: queued for the shared stream; the announce comes
         * back through it, to every replica's clients alike, or an ERROR */
        pthread_mutex_unlock(&h->lock);
        r = srv_redis_submit(h->redis, in->c, in->buf, in->len, &s->sea, s->effective_time, why, sizeof why);
        if (r != OCEAN_OK) refuse(in, r, why);
        else sea_set_log(in, &s->sea, s->effective_time, "sent to the shared timeline, asked for");
        return;
    }
    double eff = 0;
    if (r == OCEAN_OK) /* entered and announced (to the setter too: that is the reply) in this hold */
        r = srv_hub_sea_schedule(h, &np, s->effective_time, srv_hub_sea_lead(h), &eff, why, sizeof why);
    else
        snprintf(why, sizeof why, "SEA_STATE set refused: %s", msg);
    pthread_mutex_unlock(&h->lock);
    if (r != OCEAN_OK) {
        refuse(in, r, why);
        return;
    }
    sea_set_log(in, &s->sea, eff, "in force from");
    srv_hub_wake_net(h);
}

/* ---- ENTITY ---------------------------------------------------------------- */

/* Takes one of the connection's ENTITY sets or removes (SRV_ENTITY_SET_*):
 * each is announced to every client.  Over the rate: refused ERATE,
 * answered once a second.  Returns 1 if it may go on. */
static int entity_set_token(const srv_in *in)
{
    srv_session *s = in->s;
    if (srv_bucket_take(&s->entity_sets, SRV_ENTITY_SET_PER_S, SRV_ENTITY_SET_BURST, srv_now(), 1)) return 1;
    char what[200];
    snprintf(what, sizeof what, "ENTITY refused: more than %g sets and removes a second (burst %g) from this "
             "connection", SRV_ENTITY_SET_PER_S, SRV_ENTITY_SET_BURST);
    refuse_over_rate(s, &s->entity_err_t, in->buf, in->len, what);
    return 0;
}

/* Enters an ENTITY set or remove as its entry m (an announce or gone, its
 * header sim_time the instant it takes effect): at once, in force from the
 * clock, announced to every client (the setter's reply); or, replicated,
 * queued for the shared stream in force server.sea_lead ahead, the
 * announce or an ERROR coming back through it.  Refused with what, the
 * table's reason and nothing changed. */
static void entity_enter(const srv_in *in, proto_msg *m, const char *what)
{
    srv_hub *h = in->h;
    char why[512], msg[400] = "";
    double now = srv_hub_sim_time(h);
    ocean_result r;
    m->hdr.sim_time = now;
    if (h->redis) {
        r = srv_redis_submit_entity(h->redis, in->c, in->buf, in->len, m, what, why, sizeof why);
    } else {
        r = srv_hub_entity_enter(h, m, msg, sizeof msg);
        snprintf(why, sizeof why, "%s refused: %s%s", what, msg[0] ? msg : ocean_strerror(r),
                 r == OCEAN_ETOOBIG ? " (server.max_entities)" : "");
    }
    if (r != OCEAN_OK) {
        refuse(in, r, why);
        return;
    }
    /* logged when verbose: a token holder may enter and remove 120 a second,
     * and no client may flood the log */
    if (in->cfg->verbose)
        fprintf(stderr, "oceand: %s of entity %u by client %u (%s), in force from t = %.3f s%s\n", what,
                m->u.entity.id, in->c->id, in->s->peer[0] ? in->s->peer : "?", m->hdr.sim_time,
                h->redis ? " (sent to the shared timeline)" : "");
}

/* A track sample of one entity, entering it with its shape if new: what
 * the table refuses (sim/entity.h: ranges, time order, teleports, a full
 * table, a kind or size other than the live entity's) is refused with its
 * reason, and so is a sample away from the clock. */
static void entity_set(const srv_in *in, const proto_entity *e)
{
    double now = srv_hub_sim_time(in->h);
    if (!(fabs(e->t - now) <= SRV_ENTITY_T_WINDOW)) {
        char why[300];
        snprintf(why, sizeof why, "ENTITY set refused: entity.t = %.3f s is more than %g s from the server's "
                 "sim time %.3f s", e->t, SRV_ENTITY_T_WINDOW, now);
        refuse(in, OCEAN_EINVAL, why);
        return;
    }
    proto_msg m;
    ocean_entity_desc d;
    ocean_track_sample smp;
    srv_entity_from_msg(e, &d, &smp);
    srv_entity_msg(PROTO_ENTITY_ANNOUNCE, &d, &smp, now, &m);
    entity_enter(in, &m, "ENTITY set");
}

static void entity_remove(const srv_in *in, uint32_t id)
{
    proto_msg m;
    ocean_entity_desc d = {.id = id};
    srv_entity_msg(PROTO_ENTITY_GONE, &d, NULL, 0, &m);
    entity_enter(in, &m, "ENTITY remove");
}

static void on_entity(const srv_in *in)
{
    const proto_entity *e = &in->m->u.entity;
    if (e->op == PROTO_ENTITY_GET) { /* every entity's newest sample, to the asker alone */
        if (srv_client_queue_entities(in->c, in->cfg->max_entities) != OCEAN_OK)
            refuse(in, OCEAN_ENOMEM, "ENTITY get: out of memory for the list of entities");
        return;
    }
    if (e->op != PROTO_ENTITY_SET && e->op != PROTO_ENTITY_REMOVE) {
        refuse(in, OCEAN_EINVAL, "ENTITY announce and gone are server-to-client; send set, remove or get");
        return;
    }
    if (!in->cfg->entity_token[0]) {
        refuse(in, OCEAN_EAUTH, "entities over ocean.v1 are disabled on this server (server.entity_token is "
                                "empty)");
        return;
    }
    if (!entity_set_token(in)) return;
    if (!token_ok(in, in->cfg->entity_token, e->token, e->op == PROTO_ENTITY_SET ? "ENTITY set" : "ENTITY remove"))
        return;
    if (e->op == PROTO_ENTITY_SET) entity_set(in, e);
    else entity_remove(in, e->id);
}

/* A client's ERROR reports a server message it refused: logged (verbose),
 * never answered (an ERROR for an ERROR could loop).  Its text is quoted
 * with its control bytes escaped: a newline or an ANSI sequence in it must
 * not forge log lines. */
static void on_error(const srv_in *in)
{
    if (!in->cfg->verbose) return;
    const proto_error *e = &in->m->u.error;
    char safe[4 * PROTO_ERROR_MSG_MAX + 1];
    size_t k = 0;
    for (const unsigned char *p = (const unsigned char *)e->message; *p && k + 5 < sizeof safe; p++)
        k += (size_t)(*p < 0x20 || *p == 0x7f || *p == '\\' || *p == '"'
                          ? snprintf(safe + k, sizeof safe - k, "\\x%02x", *p)
                          : snprintf(safe + k, sizeof safe - k, "%c", *p));
    safe[k] = '\0';
    fprintf(stderr, "oceand: client %u reports ERROR %u (%s) for its message type %u seq %u: \"%s\"\n",
            in->c->id, e->code, ocean_strerror((ocean_result)e->code), e->offending_type, e->offending_seq, safe);
}

static void on_bye(const srv_in *in)
{
    in->s->closing = 2; /* close without a reply */
    srv_outbox_want_write(in->c->out);
}

/* What a client may send, and what handles it (the server-to-client types
 * are refused with ETYPE). */
static const struct {
    unsigned type;
    void (*handle)(const srv_in *in);
} handlers[] = {
    {PROTO_SUBSCRIBE, on_subscribe}, {PROTO_CAMERA, on_camera}, {PROTO_QUERY, on_query},
    {PROTO_SEA_STATE, on_sea_state}, {PROTO_ERROR, on_error},   {PROTO_BYE, on_bye},
    {PROTO_ENTITY, on_entity},
};

/* Every message names the last frame the client received (its header's
 * sim_time): the link's confirmations (srv_link.h). */
static void confirm_frames(srv_session *s, double sim_t, const srv_config *cfg)
{
    if (sim_t == 0) return;
    srv_link_confirmed(&s->link, sim_t, cfg->viewer_bytes_per_s, srv_now());
    atomic_store(&s->c->link_bps, (uint64_t)llround(srv_link_bps(&s->link)));
    srv_outbox_want_write(s->c->out);
}

void srv_handle(srv_session *s, const uint8_t *buf, size_t len)
{
    srv_client *c = s->c;
    srv_hub *h = c->hub;
    atomic_fetch_add(&h->stats.messages_received, 1);
    pthread_mutex_lock(&h->lock);
    srv_config cfg = h->settings.srv;
    pthread_mutex_unlock(&h->lock);
    if (!admit(s, &cfg, buf, len)) return;
    proto_limits lim;
    proto_limits_default(&lim);
    lim.max_message = (uint32_t)cfg.max_message;
    lim.max_query_points = (uint32_t)cfg.max_query_points;
    proto_msg m;
    char err[400], why[512];
    ocean_result r = proto_decode_limited(buf, len, &lim, &m, err, sizeof err);
    if (r != OCEAN_OK) {
        snprintf(why, sizeof why, "%s", err[0] ? err : ocean_strerror(r));
        srv_client_send_error(c, buf, len, r, why);
        return;
    }
    confirm_frames(s, m.hdr.sim_time, &cfg);
    srv_in in = {.s = s, .c = c, .h = h, .cfg = &cfg, .buf = buf, .len = len, .m = &m};
    size_t k = 0;
    while (k < sizeof handlers / sizeof handlers[0] && handlers[k].type != m.hdr.type) k++;
    if (k < sizeof handlers / sizeof handlers[0]) {
        handlers[k].handle(&in);
    } else {
        snprintf(why, sizeof why, "%s is a server-to-client message; clients send SUBSCRIBE, CAMERA, QUERY, "
                 "SEA_STATE, ENTITY, ERROR or BYE", proto_type_name(m.hdr.type));
        refuse(&in, OCEAN_ETYPE, why);
    }
    proto_msg_free(&m);
}
