/*
 * srv_entity.c - the daemon's entity table (see srv_entity.h): the
 * simulator's table behind one lock.
 */
#include "srv_entity.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>

struct srv_entities {
    pthread_mutex_t lock;
    ocean_entities *t;          /* [lock] */
};

ocean_result srv_entities_create(int max, int keep, srv_entities **out, char *why, size_t n)
{
    *out = NULL;
    srv_entities *e = calloc(1, sizeof *e);
    if (!e) return OCEAN_ENOMEM;
    ocean_result r = ocean_entities_create(max, SRV_ENTITY_HOLD_S, keep, &e->t, why, n);
    if (r != OCEAN_OK) {
        free(e);
        return r;
    }
    pthread_mutex_init(&e->lock, NULL);
    *out = e;
    return OCEAN_OK;
}

void srv_entities_destroy(srv_entities *e)
{
    if (!e) return;
    ocean_entities_destroy(e->t);
    pthread_mutex_destroy(&e->lock);
    free(e);
}

ocean_result srv_entities_sample(srv_entities *e, const ocean_entity_desc *d, const ocean_track_sample *s,
                                 double from, char *why, size_t n)
{
    pthread_mutex_lock(&e->lock);
    ocean_result r = ocean_entities_enter(e->t, d, s, from, why, n);
    /* what an entry's own time says, so every replica keeps the same past */
    if (r == OCEAN_OK && isfinite(from)) ocean_entities_prune(e->t, from - SRV_ENTITY_PAST_S);
    pthread_mutex_unlock(&e->lock);
    return r;
}

int srv_entities_refuses(srv_entities *e, const ocean_entity_desc *d, const ocean_track_sample *s, double from)
{
    pthread_mutex_lock(&e->lock);
    ocean_entity_desc known;
    int refuses = ocean_entities_desc(e->t, d->id, &known) == OCEAN_OK &&
                  (!ocean_entity_desc_same(&known, d) ||
                   ocean_entities_check(e->t, d->id, s, fmax(from, ocean_entities_floor(e->t, d->id)), NULL, 0) != OCEAN_OK);
    pthread_mutex_unlock(&e->lock);
    return refuses;
}

double srv_entities_floor(srv_entities *e, uint32_t id)
{
    pthread_mutex_lock(&e->lock);
    double f = ocean_entities_floor(e->t, id);
    pthread_mutex_unlock(&e->lock);
    return f;
}

ocean_result srv_entities_remove(srv_entities *e, uint32_t id, double from)
{
    pthread_mutex_lock(&e->lock);
    ocean_result r = ocean_entities_remove(e->t, id, from);
    if (r == OCEAN_OK) ocean_entities_prune(e->t, from - SRV_ENTITY_PAST_S);
    pthread_mutex_unlock(&e->lock);
    return r;
}

ocean_result srv_entities_state(srv_entities *e, uint32_t id, double t, ocean_entity_state *out)
{
    pthread_mutex_lock(&e->lock);
    ocean_result r = ocean_entities_state(e->t, id, t, out);
    pthread_mutex_unlock(&e->lock);
    return r;
}

ocean_result srv_entities_last(srv_entities *e, uint32_t id, ocean_track_sample *out, double *from)
{
    pthread_mutex_lock(&e->lock);
    ocean_result r = ocean_entities_last(e->t, id, out, from);
    pthread_mutex_unlock(&e->lock);
    return r;
}

int srv_entities_count(srv_entities *e)
{
    pthread_mutex_lock(&e->lock);
    int c = ocean_entities_count(e->t);
    pthread_mutex_unlock(&e->lock);
    return c;
}

int srv_entities_kept(srv_entities *e)
{
    pthread_mutex_lock(&e->lock);
    int c = ocean_entities_kept(e->t);
    pthread_mutex_unlock(&e->lock);
    return c;
}

ocean_result srv_entities_find(srv_entities *e, uint32_t id, ocean_entity_desc *out)
{
    pthread_mutex_lock(&e->lock);
    ocean_result r = ocean_entities_desc(e->t, id, out);
    pthread_mutex_unlock(&e->lock);
    return r;
}

int srv_entities_snapshot(srv_entities *e, ocean_entity_desc *d, ocean_track_sample *s, double *from, int max)
{
    pthread_mutex_lock(&e->lock);
    int n = 0, count = ocean_entities_count(e->t);
    for (int i = 0; i < count && n < max; i++)
        if (ocean_entities_get(e->t, i, &d[n]) == OCEAN_OK &&
            ocean_entities_last(e->t, d[n].id, &s[n], &from[n]) == OCEAN_OK)
            n++;
    pthread_mutex_unlock(&e->lock);
    return n;
}

int srv_entities_each(srv_entities *e, void (*fn)(void *ctx, const ocean_entity_entry *en), void *ctx)
{
    pthread_mutex_lock(&e->lock);
    int n = ocean_entities_each(e->t, fn, ctx);
    pthread_mutex_unlock(&e->lock);
    return n;
}

int srv_entities_at(srv_entities *e, double t, ocean_entity_desc *d, ocean_entity_state *s, int max)
{
    pthread_mutex_lock(&e->lock);
    int n = ocean_entities_at(e->t, t, d, s, max);
    pthread_mutex_unlock(&e->lock);
    return n;
}

int srv_entities_rotorcraft(srv_entities *e)
{
    pthread_mutex_lock(&e->lock);
    int n = ocean_entities_count_kind(e->t, OCEAN_ENTITY_ROTORCRAFT);
    pthread_mutex_unlock(&e->lock);
    return n;
}

ocean_result srv_entities_rotor_wash(srv_entities *e, const rotor_wash *w, double t, const double *xz, size_t n,
                                     wake_sample *out)
{
    pthread_mutex_lock(&e->lock);
    ocean_result r = rotor_wash_add(w, e->t, t, xz, n, out);
    pthread_mutex_unlock(&e->lock);
    return r;
}
