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

#define WANT_MAX 16        /* patterns waiting for the builder */

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
    wake_params want[WANT_MAX];
    int n_want;            /* want[0] is the one being built */
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
        pthread_mutex_lock(&w->lock);
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
    if (wake_field_create(2 * max_entities + 8, &w->field) != OCEAN_OK ||
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
    pthread_mutex_unlock(&w->lock);
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

int srv_wakes_pending(srv_wakes *w)
{
    pthread_mutex_lock(&w->lock);
    int n = w->n_want;
    pthread_mutex_unlock(&w->lock);
    return n;
}
