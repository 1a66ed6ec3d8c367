/*
 * srv_wakes.c - the ships' wakes in the point answers (see srv_wakes.h).
 */
#include "srv_wakes.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include "srv_hub.h"
#include "srv_msg.h"
#include "rotor_wash.h"

#define WANT_MAX 16        /* patterns waiting for the builder */

/* A built pattern's WAKE message, shared by every viewer that needs it. */
typedef struct wake_msg {
    wake_params p;
    srv_msg *m;            /* its bytes in a blob */
} wake_msg;

struct srv_wakes {
    pthread_t thread;
    int started;
    int max_entities;
    srv_stats *stats;
    pthread_mutex_t lock;
    pthread_cond_t cond;
    /* below: [lock] */
    int stop;
    wake_field *field;
    rotor_wash *rotors;    /* made at the first rotorcraft; immutable then */
    wake_params want[WANT_MAX];
    int n_want;            /* want[0] is the one being built */
    wake_msg *msgs;        /* the built patterns' messages, oldest first */
    int n_msgs, max_msgs;
};

/* Queues p unless it is queued already [lock]. */
static void want(srv_wakes *w, const wake_params *p)
{
    for (int i = 0; i < w->n_want; i++)
        if (wake_params_equal(&w->want[i], p)) return;
    if (w->n_want == WANT_MAX) return;   /* asked for again by the next slice */
    w->want[w->n_want++] = *p;
    pthread_cond_broadcast(&w->cond);
}

/* Pattern pat's WAKE message in a shared blob, or NULL (logged). */
static srv_msg *wake_encode(const wake_pattern *pat)
{
    int nx, nz;
    const float *coef = wake_pattern_coefficients(pat, &nx, &nz);
    const wake_params *p = wake_pattern_params(pat);
    proto_codec_params cp;
    proto_codec_params_default(&cp);
    cp.accuracy = SRV_WAKE_ACCURACY;
    proto_buf pay;
    proto_buf_init(&pay, 0);
    double err = 0;
    char why[200] = "";
    srv_msg *q = NULL;
    if (proto_plane_encode(NULL, PROTO_CODEC_QZ, &cp, nx, nz, coef, &pay, &err, why, sizeof why) == OCEAN_OK) {
        proto_msg m;
        proto_msg_init(&m, PROTO_WAKE);   /* header sim_time 0: a pattern is timeless */
        m.u.wake = (proto_wake){.speed = p->speed, .length = p->length, .beam = p->beam, .depth = p->depth,
                                .nx = (uint16_t)nx, .nz = (uint16_t)nz, .codec = PROTO_CODEC_QZ,
                                .error_bound = (float)(wake_pattern_bound(pat) + err),
                                .payload_len = (uint32_t)pay.len, .payload = proto_buf_data(&pay)};
        q = srv_msg_encode(&m);
        if (q && srv_msg_make_shared(q) != OCEAN_OK) {
            srv_msg_free(q);
            q = NULL;
        }
    } else {
        fprintf(stderr, "oceand: wake pattern of %g m/s, %g m: not encoded: %s\n", p->speed, p->length, why);
    }
    proto_buf_free(&pay);
    return q;
}

/* Keeps q as p's message, the oldest making way [lock]. */
static void msg_keep(srv_wakes *w, const wake_params *p, srv_msg *q)
{
    if (!q) return;
    if (w->n_msgs == w->max_msgs) {
        srv_msg_free(w->msgs[0].m);
        memmove(&w->msgs[0], &w->msgs[1], sizeof w->msgs[0] * (size_t)--w->n_msgs);
    }
    w->msgs[w->n_msgs++] = (wake_msg){*p, q};
}

static void *builder(void *arg)
{
    srv_wakes *w = arg;
    /* background work: the threads that serve clients go first */
    if (setpriority(PRIO_PROCESS, (id_t)syscall(SYS_gettid), 10) != 0) {}
    pthread_mutex_lock(&w->lock);
    for (;;) {
        while (!w->stop && w->n_want == 0) pthread_cond_wait(&w->cond, &w->lock);
        if (w->stop) break;
        wake_params p = w->want[0];
        pthread_mutex_unlock(&w->lock);
        wake_pattern *pat = NULL;
        char why[256] = "";
        double t0 = srv_now();
        ocean_result r = wake_pattern_create(&p, &pat, why, sizeof why);
        double took = srv_now() - t0;
        if (r != OCEAN_OK) fprintf(stderr, "oceand: wake pattern: %s\n", why);
        if (r == OCEAN_OK && w->stats) {
            atomic_fetch_add(&w->stats->wake_patterns, 1);
            atomic_fetch_add(&w->stats->wake_build_ns, (uint64_t)(took * 1e9));
        }
        srv_msg *q = pat ? wake_encode(pat) : NULL;
        pthread_mutex_lock(&w->lock);
        msg_keep(w, &p, q);
        wake_field_insert(w->field, pat);
        memmove(&w->want[0], &w->want[1], sizeof w->want[0] * (size_t)--w->n_want);
    }
    pthread_mutex_unlock(&w->lock);
    return NULL;
}

ocean_result srv_wakes_create(int max_entities, srv_stats *stats, srv_wakes **out)
{
    *out = NULL;
    srv_wakes *w = calloc(1, sizeof *w);
    if (!w) return OCEAN_ENOMEM;
    w->max_entities = max_entities;
    w->stats = stats;
    pthread_mutex_init(&w->lock, NULL);
    pthread_cond_init(&w->cond, NULL);
    w->max_msgs = 2 * max_entities + 8;
    w->msgs = calloc((size_t)w->max_msgs, sizeof *w->msgs);
    if (!w->msgs || wake_field_create(2 * max_entities + 8, &w->field) != OCEAN_OK ||
        pthread_create(&w->thread, NULL, builder, w) != 0) {
        srv_wakes_destroy(w);
        return OCEAN_ENOMEM;
    }
    w->started = 1;
    *out = w;
    return OCEAN_OK;
}

void srv_wakes_destroy(srv_wakes *w)
{
    if (!w) return;
    if (w->started) {
        pthread_mutex_lock(&w->lock);
        w->stop = 1;
        pthread_cond_broadcast(&w->cond);
        pthread_mutex_unlock(&w->lock);
        pthread_join(w->thread, NULL);
    }
    wake_field_destroy(w->field);
    rotor_wash_destroy(w->rotors);
    for (int i = 0; i < w->n_msgs; i++) srv_msg_free(w->msgs[i].m);
    free(w->msgs);
    pthread_cond_destroy(&w->cond);
    pthread_mutex_destroy(&w->lock);
    free(w);
}

ocean_result srv_wakes_sample(srv_wakes *w, srv_entities *e, double t, double depth, const double *xz, size_t n,
                              wake_sample *out)
{
    int max = srv_entities_kept(e);
    if (max == 0) {   /* no entity: no wake, and nothing to hold */
        memset(out, 0, sizeof *out * n);
        return OCEAN_OK;
    }
    ocean_entity_desc *d = malloc(sizeof *d * (size_t)max);
    ocean_entity_state *s = malloc(sizeof *s * (size_t)max);
    if (!d || !s) {
        free(d);
        free(s);
        return OCEAN_ENOMEM;
    }
    int count = srv_entities_at(e, t, d, s, max);
    wake_params need[WANT_MAX];
    pthread_mutex_lock(&w->lock);
    int missing = wake_field_missing(w->field, d, s, count, depth, xz, n, need, WANT_MAX);
    for (int i = 0; i < missing && i < WANT_MAX; i++) want(w, &need[i]);
    ocean_result r = missing ? OCEAN_ESTATE : wake_field_sample(w->field, d, s, count, depth, xz, n, out);
    if (r == OCEAN_OK && !w->rotors && srv_entities_rotorcraft(e)) r = rotor_wash_create(&w->rotors);
    const rotor_wash *rotors = w->rotors;
    pthread_mutex_unlock(&w->lock);
    if (r == OCEAN_OK && rotors) r = srv_entities_rotor_wash(e, rotors, t, xz, n, out);
    if (missing && w->stats) atomic_fetch_add(&w->stats->wake_waits, 1);
    free(d);
    free(s);
    return r;
}

void srv_wakes_ahead(srv_hub *h, const ocean_entity_desc *d, const ocean_track_sample *s)
{
    srv_wakes *w = h->wakes;
    pthread_mutex_lock(&h->lock);
    double depth = h->sea_now.depth_m;
    pthread_mutex_unlock(&h->lock);
    double a = s->heading_deg * (M_PI / 180);
    ocean_entity_state st = {s->x, s->z, s->altitude_m, s->heading_deg, s->speed, s->speed * cos(a),
                             s->speed * sin(a), 0, 0};
    double at[2] = {s->x, s->z};   /* every rung reaches the ship's own place */
    wake_params need[2];
    pthread_mutex_lock(&w->lock);
    int missing = wake_field_missing(w->field, d, &st, 1, depth, at, 1, need, 2);
    for (int i = 0; i < missing && i < 2; i++) want(w, &need[i]);
    pthread_mutex_unlock(&w->lock);
}

srv_msg *srv_wakes_message(srv_wakes *w, const wake_params *p)
{
    srv_msg *q = NULL;
    pthread_mutex_lock(&w->lock);
    int i = w->n_msgs - 1;
    while (i >= 0 && !wake_params_equal(&w->msgs[i].p, p)) i--;
    if (i >= 0) q = srv_msg_share(w->msgs[i].m);
    else want(w, p);
    pthread_mutex_unlock(&w->lock);
    return q;
}

int srv_wakes_pending(srv_wakes *w)
{
    pthread_mutex_lock(&w->lock);
    int n = w->n_want;
    pthread_mutex_unlock(&w->lock);
    return n;
}
