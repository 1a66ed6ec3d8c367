/*
 * srv_cigi.c - the CIGI service (see srv_cigi.h).
 *
 * Threads: everything here runs on the service's own thread except
 * srv_cigi_start / srv_cigi_stop and wake_on_answer (called by whichever
 * thread queues into the service client's outbox: it only writes the
 * eventfd).
 */
#include "srv_cigi.h"

#include <arpa/inet.h>
#include <errno.h>
#include <math.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include "cigi.h"
#include "geo.h"
#include "srv_client.h"
#include "srv_config.h"
#include "srv_convert.h"
#include "srv_entity.h"
#include "srv_redis.h"

/* One request of a host message, as it will be answered. */
typedef struct request {
    uint32_t id, type;          /* HAT/HOT id and request type */
    double alt;                 /* the test point's altitude (HAT) */
    int point;                  /* index into the query's points; -1: answered Valid = 0 */
} request;

/* A host message waiting for its answers. */
typedef struct pending {
    double since;               /* monotonic time it was queued */
    struct sockaddr_storage to;
    socklen_t tolen;
    cigi_format fmt;
    uint32_t host_frame;
    int n, npts;                /* requests; the points among them, in xz */
    int first;                  /* its first point's index in the query that carries it */
    int n_env;                  /* Environmental Conditions Requests (maritime), answered after */
    request req[SRV_CIGI_REQUESTS];
    double xz[2 * SRV_CIGI_REQUESTS];
    uint32_t env[SRV_CIGI_ENV_REQUESTS];
} pending;

struct srv_cigi {
    srv_hub *h;
    int fd, efd;
    pthread_t thread;
    int running;
    atomic_int stop;
    srv_client *c;              /* the service's client of the hub */
    ocean_geo *geo;
    double entity_lead;         /* [const] replicated: server.sea_lead, the least an entity entry takes
                                   effect ahead (srv_redis_submit_entity); else 0 */
    struct in6_addr hosts[SRV_CIGI_HOSTS];
    int n_hosts;
    pending p[SRV_CIGI_PENDING];/* in the order queued, answered in that order */
    int head, count;
    int flying;                 /* messages the query in flight carries (the first `flying`) */
    uint32_t query_id;          /* that query's id */
    uint32_t next_query, ig_frame;
    /* the host's sea (its surface wind, its whitecaps), to be entered
     * when want_sea */
    int want_sea;
    double wind_u10, wind_dir;  /* m/s; deg the wind blows toward, from +x (north) to +z; NAN: none set */
    int whitecaps;              /* Maritime Surface Conditions Control's: 1, 0; -1: none set */
    double sent_u10, sent_dir;  /* the last wind entered (NAN: none) */
    int sent_whitecaps;         /* the last whitecaps entered (-1: none) */
    double sea_next;            /* monotonic time the next change may be entered */
    struct sockaddr_storage wind_from; /* who sent it, for the log */
    double water_temp, clarity; /* the host's global Maritime Surface Conditions (deg C, %) */
    uint8_t buf[65536];
};

static void bump(atomic_uint_fast64_t *stat, uint64_t n) { atomic_fetch_add(stat, n); }

/* ---- who may speak ---------------------------------------------------------------- */

static int allowed(const srv_cigi *s, const struct sockaddr_storage *a)
{
    struct in6_addr x;
    memset(&x, 0, sizeof x);
    if (a->ss_family == AF_INET) {
        x.s6_addr[10] = x.s6_addr[11] = 0xFF;
        memcpy(&x.s6_addr[12], &((const struct sockaddr_in *)a)->sin_addr, 4);
    } else if (a->ss_family == AF_INET6) {
        x = ((const struct sockaddr_in6 *)a)->sin6_addr;
    } else {
        return 0;
    }
    for (int i = 0; i < s->n_hosts; i++)
        if (!memcmp(&x, &s->hosts[i], sizeof x)) return 1;
    return 0;
}

/* ---- answers --------------------------------------------------------------------------- */

static void put(proto_buf *b, const cigi_format *f, const cigi_packet *p)
{
    if (cigi_put(b, f, p) != OCEAN_OK) fprintf(stderr, "oceand: cigi: cannot encode %s\n", cigi_kind_name(p->kind));
}

/* One request's response from its sample (NULL: Valid = 0). */
static void put_answer(proto_buf *b, const pending *m, const request *r, const proto_query_sample *q)
{
    cigi_packet p;
    memset(&p, 0, sizeof p);
    int valid = q && isfinite(q->height) && q->error_bound < 3.0e38f;
    double h = valid ? q->height : 0;
    if (r->type == CIGI_HAT_HOT_EXTENDED) {
        p.kind = CIGI_HAT_HOT_XRESPONSE;
        cigi_hat_hot_xresponse *x = &p.u.hat_xresp;
        x->id = r->id;
        x->valid = (uint32_t)valid;
        x->frame_lsn = m->host_frame & 0xF;
        if (valid) {
            x->hot = h;
            x->hat = r->alt - h;
            /* the normal's bearing (x north, z east) and its elevation
             * above the horizontal */
            x->normal_az = atan2(q->normal[2], q->normal[0]) * 180 / M_PI;
            x->normal_el = asin(fmax(-1.0, fmin(1.0, q->normal[1]))) * 180 / M_PI;
        }
    } else {
        p.kind = CIGI_HAT_HOT_RESPONSE;
        cigi_hat_hot_response *x = &p.u.hat_resp;
        x->id = r->id;
        x->valid = (uint32_t)valid;
        x->type = r->type == CIGI_HOT;
        x->frame_lsn = m->host_frame & 0xF;
        if (valid) x->height = r->type == CIGI_HOT ? h : r->alt - h;
    }
    put(b, &m->fmt, &p);
}

/* Sends message m's answer: a Start of Frame carrying the sim time t of
 * the answers, then one response per request (samples NULL: none valid). */
static void answer(srv_cigi *s, const pending *m, double t, const proto_query_sample *samples, uint32_t n_samples)
{
    proto_buf b;
    proto_buf_init(&b, 0);
    cigi_packet sof;
    memset(&sof, 0, sizeof sof);
    sof.kind = CIGI_START_OF_FRAME;
    sof.u.sof.ig_mode = 1; /* Operate */
    sof.u.sof.frame = ++s->ig_frame;
    sof.u.sof.last_host_frame = m->host_frame;
    if (isfinite(t)) {
        sof.u.sof.timestamp_valid = 1;
        sof.u.sof.timestamp = (uint32_t)(uint64_t)llround(fmod(t * 1e5, 4294967296.0) + (t < 0 ? 4294967296.0 : 0));
    }
    put(&b, &m->fmt, &sof);
    for (int i = 0; i < m->n; i++) {
        const request *r = &m->req[i];
        int k = r->point;
        put_answer(&b, m, r, samples && k >= 0 && (uint32_t)k < n_samples ? &samples[k] : NULL);
    }
    for (int i = 0; i < m->n_env; i++) {
        /* the sea's mean surface is the geoid: oceand's sea has no level
         * offset (a host's Maritime Control surface height is not applied) */
        cigi_packet mr = {.kind = CIGI_MARITIME_RESPONSE};
        mr.u.maritime_resp = (cigi_maritime_response){.id = m->env[i], .surface_height = 0,
                                                      .water_temp = s->water_temp, .clarity = s->clarity};
        put(&b, &m->fmt, &mr);
    }
    if (sendto(s->fd, proto_buf_data(&b), proto_buf_len(&b), 0, (const struct sockaddr *)&m->to, m->tolen) < 0)
        fprintf(stderr, "oceand: cigi: cannot answer: %s\n", strerror(errno));
    else
        bump(&s->h->stats.cigi_messages, 1);
    bump(&s->h->stats.cigi_answers, (uint64_t)m->n);
    proto_buf_free(&b);
}

static pending *nth(srv_cigi *s, int i) { return &s->p[(s->head + i) % SRV_CIGI_PENDING]; }

static void pop(srv_cigi *s)
{
    s->head = (s->head + 1) % SRV_CIGI_PENDING;
    s->count--;
}

/* The messages the query in flight carried, answered from its result (or
 * Valid = 0 when samples is NULL), in order. */
static void answer_flying(srv_cigi *s, double t, const proto_query_sample *samples, uint32_t n)
{
    for (; s->flying > 0; s->flying--) {
        pending *m = nth(s, 0);
        int ok = samples && (uint32_t)(m->first + m->npts) <= n;
        answer(s, m, t, ok ? samples + m->first : NULL, ok ? (uint32_t)m->npts : 0);
        pop(s);
    }
}

/* With no query in flight: messages at the head with no point are answered
 * at once; the points of every other waiting message go as one query, so
 * a host faster than the daemon's ticks gets each tick's answers to all
 * its messages since the last. */
static int ask(srv_cigi *s);

static void send_next(srv_cigi *s)
{
    if (s->flying) return;
    while (s->count && nth(s, 0)->npts == 0) {
        answer(s, nth(s, 0), NAN, NULL, 0);
        pop(s);
    }
    if (s->count && ask(s) != 0) {
        s->flying = s->count;
        answer_flying(s, NAN, NULL, 0);    /* out of memory: Valid = 0 */
    }
}

/* The answers the simulation thread queued to the service's client: a
 * QUERY_RESULT (or an ERROR) for the query in flight. */
static void take_answers(srv_cigi *s)
{
    srv_msg *msg;
    while ((msg = srv_outbox_take(s->c->out))) {
        size_t len;
        uint8_t *wire = srv_msg_wire(msg, &len);
        proto_msg pm;
        char err[160];
        if (proto_decode(wire, len, &pm, err, sizeof err) == OCEAN_OK) {
            int query = pm.hdr.type == PROTO_ERROR && pm.u.error.offending_type == PROTO_QUERY;
            if (s->flying && pm.hdr.type == PROTO_QUERY_RESULT && pm.u.result.query_id == s->query_id) {
                answer_flying(s, pm.u.result.t, pm.u.result.samples, pm.u.result.count);
            } else if (s->flying && query) {
                fprintf(stderr, "oceand: cigi: a query was refused: %s\n", pm.u.error.message);
                answer_flying(s, NAN, NULL, 0);
            } else if (pm.hdr.type == PROTO_ERROR && !query) { /* a wind the shared timeline refused */
                fprintf(stderr, "oceand: cigi: the host's wind was refused: %s\n", pm.u.error.message);
            }
            proto_msg_free(&pm);
        }
        srv_msg_free(msg);
    }
    /* a query not answered in time (the daemon stopping) gets Valid = 0 */
    if (s->flying && srv_now() - nth(s, 0)->since > SRV_CIGI_PATIENCE) answer_flying(s, NAN, NULL, 0);
    send_next(s);
}

static void wake_on_answer(void *ctx)
{
    srv_cigi *s = ctx;
    uint64_t one = 1;
    if (write(s->efd, &one, sizeof one) < 0) { /* a full counter already wakes it */ }
}

/* ---- the host's sea ---------------------------------------------------------------------- */

/* The wind of a host packet, to be entered: from_deg is where it blows
 * from (CIGI), the sea's direction where it blows toward. */
static void host_wind(srv_cigi *s, double speed, double from_deg, const pending *m)
{
    s->wind_u10 = speed;
    s->wind_dir = fmod(fmod(from_deg + 180.0, 360.0) + 360.0, 360.0);
    s->wind_from = m->to;
    s->want_sea = 1;
}

/* The address a (IPv4 or IPv6) as text into buf. */
static const char *addr_text(const struct sockaddr_storage *a, char *buf, size_t n)
{
    const void *in = a->ss_family == AF_INET ? (const void *)&((const struct sockaddr_in *)a)->sin_addr
                                             : (const void *)&((const struct sockaddr_in6 *)a)->sin6_addr;
    if (!inet_ntop(a->ss_family, in, buf, (socklen_t)n)) snprintf(buf, n, "?");
    return buf;
}

static int same_wind(double u10, double dir, double u2, double dir2)
{
    double dd = fabs(fmod(dir - dir2 + 540.0, 360.0) - 180.0);
    return fabs(u10 - u2) < 0.005 && dd < 0.05;
}

/* The sea at the end of the timeline with what the host set (its wind, its
 * whitecaps) into *np; 0 when that is the sea already [hub.lock]. */
static int host_sea(const srv_cigi *s, ocean_params *np)
{
    srv_hub *h = s->h;
    *np = h->n_sea_pending ? h->sea_pending[h->n_sea_pending - 1].params : h->settings.params;
    int same = 1;
    if (!isnan(s->wind_u10) && !same_wind(np->sea.wind_u10, np->sea.wind_dir_deg, s->wind_u10, s->wind_dir)) {
        np->sea.wind_u10 = s->wind_u10;
        np->sea.wind_dir_deg = s->wind_dir;
        same = 0;
    }
    if (s->whitecaps >= 0 && np->sea.whitecaps != s->whitecaps) {
        np->sea.whitecaps = s->whitecaps;
        same = 0;
    }
    return !same;
}

/* Submits the host's sea to the shared timeline (server.redis): the set as
 * a SEA_STATE message, whose ERROR names it (take_answers logs it); the
 * shared timeline takes a change at least server.sea_lead ahead when it
 * is submitted, a moment after this: two ticks more.  Called with
 * hub.lock held; returns with it released. */
static ocean_result submit_host_sea(srv_cigi *s, const ocean_params *np, double *eff, char *why, size_t n)
{
    srv_hub *h = s->h;
    proto_msg set;
    proto_msg_init(&set, PROTO_SEA_STATE);
    set.u.sea_state.op = PROTO_SEA_SET;
    srv_sea_from_params(np, &set.u.sea_state.sea);
    *eff = set.u.sea_state.effective_time =
        srv_hub_sim_time(h) + h->settings.srv.sea_lead + 2.0 / h->settings.srv.tick_rate;
    pthread_mutex_unlock(&h->lock);
    proto_buf b;
    proto_buf_init(&b, 0);
    ocean_result r = proto_encode(&b, &set, why, n);
    if (r == OCEAN_OK)
        r = srv_redis_submit(h->redis, s->c, proto_buf_data(&b), proto_buf_len(&b), &set.u.sea_state.sea, *eff,
                             why, n);
    proto_buf_free(&b);
    return r;
}

/* Enters the host's sea into the timeline as an admin's set is entered
 * (srv_handle.c on_sea_state): the sea at the end of the timeline with the
 * host's wind and whitecaps, effective as soon as its ocean can be built. */
static void enter_host_sea(srv_cigi *s)
{
    srv_hub *h = s->h;
    char why[512] = "", msg[256], host[INET6_ADDRSTRLEN];
    addr_text(&s->wind_from, host, sizeof host);
    double eff = 0;
    ocean_params np;
    pthread_mutex_lock(&h->lock);
    ocean_result r = OCEAN_OK;
    if (!host_sea(s, &np)) {
        pthread_mutex_unlock(&h->lock);
    } else if ((r = ocean_params_validate(&np, msg, sizeof msg)) != OCEAN_OK) {
        pthread_mutex_unlock(&h->lock);
        fprintf(stderr, "oceand: cigi: the sea of host %s refused: %s\n", host, msg);
        bump(&h->stats.cigi_drop_value, 1);
        return;
    } else if (h->redis) {
        r = submit_host_sea(s, &np, &eff, why, sizeof why);
        if (r == OCEAN_OK)
            fprintf(stderr, "oceand: sea state set by CIGI host %s, sent to the shared timeline, asked for t = "
                    "%.3f s: wind %.2f m/s toward %.1f deg, whitecaps %s\n", host, eff, np.sea.wind_u10,
                    np.sea.wind_dir_deg, np.sea.whitecaps ? "on" : "off");
    } else {
        r = srv_hub_sea_schedule(h, &np, 0, srv_hub_sea_lead(h), &eff, why, sizeof why);
        pthread_mutex_unlock(&h->lock);
        srv_hub_wake_net(h);
        if (r == OCEAN_OK)
            fprintf(stderr, "oceand: sea state set by CIGI host %s, in force from t = %.3f s: wind %.2f m/s toward "
                    "%.1f deg, whitecaps %s\n", host, eff, np.sea.wind_u10, np.sea.wind_dir_deg,
                    np.sea.whitecaps ? "on" : "off");
    }
    if (r == OCEAN_OK) {
        s->sent_u10 = s->wind_u10, s->sent_dir = s->wind_dir, s->sent_whitecaps = s->whitecaps;
    } else if (why[0]) {
        fprintf(stderr, "oceand: cigi: the sea of host %s not entered: %s\n", host, why);
    }
}

/* The host's latest sea, entered when it differs from the last one
 * entered, at most SRV_CIGI_SEA_PER_S times a second. */
static void follow_host_sea(srv_cigi *s)
{
    if (!s->want_sea || srv_now() < s->sea_next) return;
    s->want_sea = 0;
    if ((isnan(s->wind_u10) || same_wind(s->sent_u10, s->sent_dir, s->wind_u10, s->wind_dir)) &&
        s->whitecaps == s->sent_whitecaps)
        return;
    s->sea_next = srv_now() + 1.0 / SRV_CIGI_SEA_PER_S;
    enter_host_sea(s);
}

/* A wind packet of the host at `host`: Atmosphere Control's global wind,
 * or a Weather Control layer of global scope that holds 10 m (where U10
 * is defined: protocol/CIGI.md "Surface wind"). */
static void take_wind(srv_cigi *s, pending *m, const cigi_packet *p)
{
    if (cigi_packet_check(p, NULL, 0) != OCEAN_OK) {
        bump(&s->h->stats.cigi_drop_value, 1);
        return;
    }
    if (p->kind == CIGI_ATMOSPHERE_CONTROL) {
        host_wind(s, p->u.atmosphere.wind_h, p->u.atmosphere.wind_dir, m);
        return;
    }
    const cigi_weather *w = &p->u.weather;
    if (w->enable && w->scope == CIGI_SCOPE_GLOBAL && w->base <= 10.0 && w->base + w->thickness >= 10.0)
        host_wind(s, w->wind_h, w->wind_dir, m);
    else
        bump(&s->h->stats.cigi_ignored, 1);
}

/* Maritime Surface Conditions Control of global scope: its whitecaps
 * enter the sea (the timeline, as the host's wind does); the water's
 * temperature and clarity are reported back to Environmental Conditions
 * Requests.  Its surface height offset is not applied (counted ignored
 * when it asks for one). */
static void take_maritime(srv_cigi *s, pending *m, const cigi_packet *p)
{
    const cigi_maritime_control *c = &p->u.maritime;
    if (cigi_packet_check(p, NULL, 0) != OCEAN_OK || !isfinite(c->water_temp) || c->water_temp < -2 ||
        c->water_temp > 40 || !(c->clarity >= 0 && c->clarity <= 100)) {
        bump(&s->h->stats.cigi_drop_value, 1);
        return;
    }
    if (c->scope != CIGI_SCOPE_GLOBAL) {
        bump(&s->h->stats.cigi_ignored, 1);
        return;
    }
    s->water_temp = c->water_temp;
    s->clarity = c->clarity;
    if (s->whitecaps != (c->whitecaps != 0)) {
        s->whitecaps = c->whitecaps != 0;
        s->wind_from = m->to;
        s->want_sea = 1;
    }
    if (c->surface_height != 0) bump(&s->h->stats.cigi_ignored, 1);
}

/* An Environmental Conditions Request: its maritime part answered with
 * the message (Maritime Surface Conditions Response); terrestrial,
 * weather and aerosol conditions are no ocean's (counted ignored). */
static void take_env(srv_cigi *s, pending *m, const cigi_packet *p)
{
    const cigi_env_request *q = &p->u.env_req;
    if (cigi_packet_check(p, NULL, 0) != OCEAN_OK) {
        bump(&s->h->stats.cigi_drop_value, 1);
        return;
    }
    if (!(q->type & CIGI_ENV_MARITIME) || (q->type & ~(unsigned)CIGI_ENV_MARITIME))
        bump(&s->h->stats.cigi_ignored, 1);
    if (!(q->type & CIGI_ENV_MARITIME)) return;
    if (m->n_env == SRV_CIGI_ENV_REQUESTS) {
        bump(&s->h->stats.cigi_drop_busy, 1);
        return;
    }
    m->env[m->n_env++] = q->id;
}

/* ---- the host's entities ------------------------------------------------------------------ */

/* CIGI carries no entity's size or kind: a clamped entity is taken for a
 * ship of these dimensions, any other for an aircraft of this span (a
 * frame for its requests, no wake). */
#define CIGI_SHIP_LENGTH_M 100.0
#define CIGI_SHIP_BEAM_M 15.0
#define CIGI_SHIP_DRAUGHT_M 5.0
#define CIGI_AIRCRAFT_SPAN_M 15.0

/* The table's shape for entity e of the host. */
static ocean_entity_desc entity_desc(const cigi_entity *e)
{
    ocean_entity_desc d = {.id = e->id};
    if (e->clamp != CIGI_CLAMP_NONE) {
        d.kind = OCEAN_ENTITY_SHIP;
        d.length_m = CIGI_SHIP_LENGTH_M, d.beam_m = CIGI_SHIP_BEAM_M, d.draught_m = CIGI_SHIP_DRAUGHT_M;
    } else {
        d.kind = OCEAN_ENTITY_AIRCRAFT;
        d.length_m = CIGI_AIRCRAFT_SPAN_M;
    }
    return d;
}

/* Enters the host's entity entry m (an ENTITY announce or gone) in force
 * from `from`: at once, or through the shared timeline (nobody to answer:
 * a refusal falls alike on every replica and is counted there). */
static void entity_put(srv_cigi *s, proto_msg *m, double from)
{
    srv_hub *h = s->h;
    char why[400];
    m->hdr.sim_time = from;
    ocean_result r = h->redis ? srv_redis_submit_entity(h->redis, NULL, NULL, 0, m, "CIGI entity", why, sizeof why)
                              : srv_hub_entity_enter(h, m, why, sizeof why);
    if (r != OCEAN_OK) bump(&h->stats.cigi_drop_value, 1);
}

/* Entity Control (3.x: state and position) or Entity Position (4.0):
 * the entity's sample at the sim clock, its speed the step from its last
 * sample (at most its kind's); destroyed, it leaves.  Entered at once, or,
 * replicated, through the shared timeline server.sea_lead ahead.  The host is the entity's
 * authority: a step the table refuses (a host that repositions it) enters
 * it anew where the host put it.  An attached entity (a part of another)
 * is no entity of the sea. */
static void take_entity(srv_cigi *s, pending *m, const cigi_packet *p)
{
    srv_hub *h = s->h;
    const cigi_entity *e = &p->u.entity;
    if (cigi_packet_check(p, NULL, 0) != OCEAN_OK) {
        bump(&h->stats.cigi_drop_value, 1);
        return;
    }
    double now = srv_hub_sim_time(h);
    double from = now + s->entity_lead;
    ocean_entity_desc d = entity_desc(e);
    proto_msg msg;
    if (p->kind == CIGI_ENTITY_CONTROL && e->state == CIGI_ENTITY_DESTROYED) {
        srv_entity_msg(PROTO_ENTITY_GONE, &d, NULL, from, &msg);
        entity_put(s, &msg, from);
        return;
    }
    int placed = p->kind == CIGI_ENTITY_POSITION || m->fmt.major == 3; /* 4.0's Entity Control is state only */
    if (!placed || e->attach || (p->kind == CIGI_ENTITY_CONTROL && e->state != CIGI_ENTITY_ACTIVE)) {
        bump(&h->stats.cigi_ignored, 1);
        return;
    }
    ocean_track_sample smp = {.t = now, .heading_deg = e->yaw};
    smp.altitude_m = d.kind == OCEAN_ENTITY_SHIP ? 0 : e->alt;
    if (ocean_geo_to_plane(s->geo, e->lat, e->lon, &smp.x, &smp.z) != OCEAN_OK) {
        bump(&h->stats.cigi_drop_value, 1);
        return;
    }
    ocean_track_sample last;
    double vmax = d.kind == OCEAN_ENTITY_SHIP ? OCEAN_SHIP_SPEED_MAX : OCEAN_AIRCRAFT_SPEED_MAX;
    int known = srv_entities_last(h->entities, e->id, &last, NULL) == OCEAN_OK;
    if (known && smp.t > last.t) smp.speed = fmin(vmax, hypot(smp.x - last.x, smp.z - last.z) / (smp.t - last.t));
    if (known && srv_entities_refuses(h->entities, &d, &smp, from)) { /* repositioned: entered anew */
        srv_entity_msg(PROTO_ENTITY_GONE, &d, NULL, from, &msg);
        entity_put(s, &msg, from);
        smp.speed = 0;
    }
    srv_entity_msg(PROTO_ENTITY_ANNOUNCE, &d, &smp, from, &msg);
    entity_put(s, &msg, from);
}

/* An entity-relative request's point: the entity's position at the sim
 * clock and the offsets in its frame (x forward, y right, z down; pitch
 * and roll not applied), into *x, *z and the test point's altitude *alt.
 * 0 when the daemon holds no such entity. */
static int entity_point(srv_cigi *s, const cigi_hat_hot_request *q, double *x, double *z, double *alt)
{
    ocean_entity_state st;
    if (srv_entities_state(s->h->entities, q->entity, srv_hub_sim_time(s->h), &st) != OCEAN_OK) return 0;
    double h = st.heading_deg * (M_PI / 180.0), c = cos(h), sn = sin(h);
    *x = st.x + q->lat * c - q->lon * sn; /* forward is the heading; right is 90 deg clockwise of it */
    *z = st.z + q->lat * sn + q->lon * c;
    *alt = st.altitude_m - q->alt;
    return fabs(*x) <= OCEAN_ENTITY_POS_MAX && fabs(*z) <= OCEAN_ENTITY_POS_MAX;
}

/* ---- host messages ------------------------------------------------------------------- */

/* A HAT/HOT Request into m (and its point into m->xz), or a drop. */
static void take_request(srv_cigi *s, pending *m, const cigi_packet *p)
{
    const cigi_hat_hot_request *q = &p->u.hat_req;
    char why[200];
    if (cigi_packet_check(p, why, sizeof why) != OCEAN_OK) {
        bump(&s->h->stats.cigi_drop_value, 1);
        return;
    }
    if (m->n == SRV_CIGI_REQUESTS) {
        bump(&s->h->stats.cigi_drop_busy, 1);
        return;
    }
    request *r = &m->req[m->n++];
    r->id = q->id;
    r->type = q->type;
    r->alt = q->alt;
    r->point = -1;
    double *xz = &m->xz[2 * m->npts];
    if (q->coord == CIGI_COORD_ENTITY) {
        if (!entity_point(s, q, &xz[0], &xz[1], &r->alt)) return; /* no such entity: Valid = 0 */
    } else if (ocean_geo_to_plane(s->geo, q->lat, q->lon, &xz[0], &xz[1]) != OCEAN_OK) {
        return;
    }
    r->point = m->npts++;
}

/* Queues the points of every waiting message as one query of the
 * service's client; 0 when the inbox took it. */
static int ask(srv_cigi *s)
{
    int n = 0;
    for (int i = 0; i < s->count; i++) {
        nth(s, i)->first = n;
        n += nth(s, i)->npts;
    }
    srv_query *q = calloc(1, sizeof *q);
    double *pts = malloc(sizeof(double) * 2 * (size_t)n);
    if (!q || !pts) {
        free(q);
        free(pts);
        return -1;
    }
    for (int i = 0; i < s->count; i++) {
        const pending *m = nth(s, i);
        memcpy(pts + 2 * m->first, m->xz, sizeof(double) * 2 * (size_t)m->npts);
    }
    q->query_id = s->query_id = ++s->next_query;
    q->seq = s->query_id;
    q->count = (uint32_t)n;
    q->points = pts;
    s->flying = s->count;
    srv_hub *h = s->h;
    pthread_mutex_lock(&h->lock);
    srv_inbox_push_query(s->c->in, q);
    pthread_cond_signal(&h->wake);
    pthread_mutex_unlock(&h->lock);
    return 0;
}

static void take_ig_control(srv_cigi *s, pending *m, const cigi_packet *p)
{
    (void)s;
    m->host_frame = p->u.ig.frame;
}

/* What the service does with each packet a host sends. */
static void (*const take[CIGI_KIND_COUNT_])(srv_cigi *, pending *, const cigi_packet *) = {
    [CIGI_IG_CONTROL] = take_ig_control,         [CIGI_HAT_HOT_REQUEST] = take_request,
    [CIGI_ATMOSPHERE_CONTROL] = take_wind,       [CIGI_WEATHER_CONTROL] = take_wind,
    [CIGI_ENTITY_CONTROL] = take_entity,         [CIGI_ENTITY_POSITION] = take_entity,
    [CIGI_MARITIME_CONTROL] = take_maritime,     [CIGI_ENV_REQUEST] = take_env,
};

/* The packets after IG Control, each to its handler (take); the rest
 * counted. */
static void read_packets(srv_cigi *s, cigi_reader *rd, pending *m)
{
    for (;;) {
        cigi_packet p;
        int done;
        if (cigi_reader_next(rd, &p, &done, NULL, 0) != OCEAN_OK) {
            bump(&s->h->stats.cigi_drop_framing, 1); /* what came before it is answered */
            return;
        }
        if (done) return;
        if (p.kind < CIGI_KIND_COUNT_ && take[p.kind]) take[p.kind](s, m, &p);
        else bump(&s->h->stats.cigi_ignored, 1);
    }
}

static void on_datagram(srv_cigi *s, size_t len, const struct sockaddr_storage *from, socklen_t fromlen)
{
    if (!allowed(s, from)) {
        bump(&s->h->stats.cigi_drop_host, 1);
        return;
    }
    cigi_format f;
    if (cigi_format_of(s->buf, len, &f, NULL, 0) != OCEAN_OK || s->buf[0] == 101 ||
        (f.major == 4 && s->buf[2] == 0xFF)) { /* an IG's Start of Frame is no host message */
        bump(&s->h->stats.cigi_drop_framing, 1);
        return;
    }
    if (s->count == SRV_CIGI_PENDING) {
        bump(&s->h->stats.cigi_drop_busy, 1);
        return;
    }
    pending *m = nth(s, s->count);
    memset(m, 0, offsetof(pending, req));
    m->fmt = f;
    memcpy(&m->to, from, fromlen);
    m->tolen = fromlen;
    m->since = srv_now();
    cigi_reader rd;
    cigi_reader_init(&rd, s->buf, len, &f);
    read_packets(s, &rd, m);
    s->count++;
    send_next(s);
}

/* ---- the thread ------------------------------------------------------------------------- */

static void *cigi_main(void *arg)
{
    srv_cigi *s = arg;
    while (!atomic_load(&s->stop)) {
        struct pollfd pf[2] = {{.fd = s->fd, .events = POLLIN}, {.fd = s->efd, .events = POLLIN}};
        int r = poll(pf, 2, s->want_sea ? 50 : s->count ? 100 : 1000);
        if (r < 0 && errno != EINTR) break;
        if (pf[1].revents & POLLIN) {
            uint64_t v;
            if (read(s->efd, &v, sizeof v) < 0) { /* nothing to drain */ }
        }
        take_answers(s);
        /* at most a burst of datagrams a wake-up: answers are not starved */
        for (int i = 0; i < 64 && (pf[0].revents & POLLIN); i++) {
            struct sockaddr_storage from;
            socklen_t fl = sizeof from;
            ssize_t n = recvfrom(s->fd, s->buf, sizeof s->buf, MSG_DONTWAIT, (struct sockaddr *)&from, &fl);
            if (n < 0) break;
            on_datagram(s, (size_t)n, &from, fl);
        }
        follow_host_sea(s);
    }
    return NULL;
}

static ocean_result open_socket(srv_cigi *s, const srv_config *cfg, char *msg, size_t msglen)
{
    struct addrinfo hints = {.ai_family = AF_UNSPEC, .ai_socktype = SOCK_DGRAM, .ai_flags = AI_PASSIVE |
                             AI_NUMERICHOST | AI_NUMERICSERV}, *ai = NULL;
    char port[16];
    snprintf(port, sizeof port, "%d", cfg->cigi_port);
    int e = getaddrinfo(cfg->bind[0] ? cfg->bind : NULL, port, &hints, &ai);
    if (e) {
        snprintf(msg, msglen, "server.cigi_port: server.bind '%s': %s", cfg->bind, gai_strerror(e));
        return OCEAN_EINVAL;
    }
    s->fd = socket(ai->ai_family, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (s->fd < 0 || bind(s->fd, ai->ai_addr, ai->ai_addrlen) < 0) {
        snprintf(msg, msglen, "server.cigi_port: cannot bind UDP %s port %d: %s", cfg->bind[0] ? cfg->bind : "*",
                 cfg->cigi_port, strerror(errno));
        freeaddrinfo(ai);
        return OCEAN_EIO;
    }
    freeaddrinfo(ai);
    return OCEAN_OK;
}

static ocean_result setup(srv_cigi *s, char *msg, size_t msglen)
{
    const srv_config *cfg = &s->h->settings.srv;
    char why[200];
    double lat, lon;
    if (srv_config_hosts_parse(cfg->cigi_hosts, s->hosts, &s->n_hosts, why, sizeof why) != OCEAN_OK ||
        ocean_geo_origin_parse(cfg->geo_origin, &lat, &lon, why, sizeof why) != OCEAN_OK ||
        ocean_geo_create(lat, lon, &s->geo, why, sizeof why) != OCEAN_OK) {
        snprintf(msg, msglen, "CIGI service: %s", why);
        return OCEAN_EINVAL;
    }
    s->entity_lead = s->h->redis ? cfg->sea_lead : 0;
    ocean_result r = open_socket(s, cfg, msg, msglen);
    if (r != OCEAN_OK) return r;
    s->efd = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    if (s->efd < 0) return OCEAN_EIO;
    r = srv_client_create_internal(s->h, &s->c);
    if (r != OCEAN_OK) return r;
    srv_outbox_set_notify(s->c->out, wake_on_answer, s);
    return OCEAN_OK;
}

ocean_result srv_cigi_start(srv_hub *h, srv_cigi **out, char *msg, size_t msglen)
{
    *out = NULL;
    if (h->settings.srv.cigi_port == 0) return OCEAN_OK;
    srv_cigi *s = calloc(1, sizeof *s);
    if (!s) return OCEAN_ENOMEM;
    s->h = h;
    s->fd = s->efd = -1;
    s->sent_u10 = s->sent_dir = s->wind_u10 = s->wind_dir = NAN;
    s->whitecaps = s->sent_whitecaps = -1;
    ocean_result r = setup(s, msg, msglen);
    if (r == OCEAN_OK && pthread_create(&s->thread, NULL, cigi_main, s) != 0) r = OCEAN_ENOMEM;
    if (r != OCEAN_OK) {
        srv_cigi_stop(s);
        return r;
    }
    s->running = 1;
    *out = s;
    return OCEAN_OK;
}

void srv_cigi_stop(srv_cigi *s)
{
    if (!s) return;
    if (s->running) {
        atomic_store(&s->stop, 1);
        wake_on_answer(s);
        pthread_join(s->thread, NULL);
    }
    if (s->c) {
        srv_outbox_set_notify(s->c->out, NULL, NULL); /* the sim thread may still answer into it */
        srv_client_remove(s->c);
    }
    if (s->fd >= 0) close(s->fd);
    if (s->efd >= 0) close(s->efd);
    ocean_geo_destroy(s->geo);
    free(s);
}
