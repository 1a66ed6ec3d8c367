/*
 * entity.c - the entity table and a track's state at any instant (see
 * entity.h).
 *
 * Entities sit in an array sorted by id (a binary search per lookup); each
 * holds its track as a ring of its last OCEAN_TRACK_KEEP samples.
 */
#include "entity.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "ocean_time.h"

typedef struct entity {
    ocean_entity_desc d;
    ocean_track_sample s[OCEAN_TRACK_KEEP];
    int head;            /* index of the oldest kept sample */
    int count;
} entity;

struct ocean_entities {
    int max;
    double hold_s;
    int n;
    entity **by_id;      /* n entries, increasing id */
};

/* A teleport is a step that needs more than the top speed by this factor,
 * plus TELEPORT_SLACK_M (a feeder rounds positions and times). */
#define TELEPORT_FACTOR 1.5
#define TELEPORT_SLACK_M 1.0

ocean_result ocean_entities_create(int max_entities, double hold_s, ocean_entities **out, char *why, size_t n)
{
    if (!out) return OCEAN_EINVAL;
    *out = NULL;
    if (max_entities < 1 || max_entities > OCEAN_ENTITY_MAX || !(hold_s >= 0 && hold_s <= 600)) {
        ocean_seterr(why, n, "entities: max %d is outside [1, %d] or hold %g s outside [0, 600]", max_entities,
                     OCEAN_ENTITY_MAX, hold_s);
        return OCEAN_EINVAL;
    }
    ocean_entities *e = calloc(1, sizeof *e);
    if (!e || !(e->by_id = calloc((size_t)max_entities, sizeof *e->by_id))) {
        free(e);
        return OCEAN_ENOMEM;
    }
    e->max = max_entities;
    e->hold_s = hold_s;
    *out = e;
    return OCEAN_OK;
}

void ocean_entities_destroy(ocean_entities *e)
{
    if (!e) return;
    for (int i = 0; i < e->n; i++) free(e->by_id[i]);
    free(e->by_id);
    free(e);
}

/* The index of id, or of where it would go (*found 0). */
static int find(const ocean_entities *e, uint32_t id, int *found)
{
    int lo = 0, hi = e->n;
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (e->by_id[mid]->d.id < id) lo = mid + 1;
        else hi = mid;
    }
    *found = lo < e->n && e->by_id[lo]->d.id == id;
    return lo;
}

static int in_range(double v, double lo, double hi) { return v >= lo && v <= hi; } /* false for NaN */

static ocean_result desc_check(const ocean_entity_desc *d, char *why, size_t n)
{
    if (d->kind == OCEAN_ENTITY_SHIP) {
        if (in_range(d->length_m, 1, 500) && in_range(d->beam_m, 0.5, 100) && in_range(d->draught_m, 0.1, 30))
            return OCEAN_OK;
        ocean_seterr(why, n, "entity %u: a ship's length %g m, beam %g m and draught %g m must lie in [1, 500], "
                     "[0.5, 100] and [0.1, 30]", d->id, d->length_m, d->beam_m, d->draught_m);
        return OCEAN_EINVAL;
    }
    if (d->kind == OCEAN_ENTITY_ROTORCRAFT) {
        if (in_range(d->length_m, 1, 40) && d->beam_m == 0 && d->draught_m == 0) return OCEAN_OK;
        ocean_seterr(why, n, "entity %u: a rotorcraft's rotor diameter %g m must lie in [1, 40], its beam and "
                     "draught 0 (%g, %g)", d->id, d->length_m, d->beam_m, d->draught_m);
        return OCEAN_EINVAL;
    }
    if (d->kind == OCEAN_ENTITY_AIRCRAFT) {
        if (in_range(d->length_m, 1, 100) && d->beam_m == 0 && d->draught_m == 0) return OCEAN_OK;
        ocean_seterr(why, n, "entity %u: an aircraft's span %g m must lie in [1, 100], its beam and draught 0 "
                     "(%g, %g)", d->id, d->length_m, d->beam_m, d->draught_m);
        return OCEAN_EINVAL;
    }
    ocean_seterr(why, n, "entity %u: kind %d is not ship (0), rotorcraft (1) or aircraft (2)", d->id, (int)d->kind);
    return OCEAN_EINVAL;
}

ocean_result ocean_entities_add(ocean_entities *e, const ocean_entity_desc *d, char *why, size_t n)
{
    if (!e || !d) return OCEAN_EINVAL;
    ocean_result r = desc_check(d, why, n);
    if (r != OCEAN_OK) return r;
    int found, at = find(e, d->id, &found);
    if (found) {
        ocean_seterr(why, n, "entity %u is already in the sea", d->id);
        return OCEAN_ESTATE;
    }
    if (e->n >= e->max) {
        ocean_seterr(why, n, "entity %u: the sea holds %d entities already, the most it takes", d->id, e->max);
        return OCEAN_ETOOBIG;
    }
    entity *k = calloc(1, sizeof *k);
    if (!k) return OCEAN_ENOMEM;
    k->d = *d;
    memmove(&e->by_id[at + 1], &e->by_id[at], (size_t)(e->n - at) * sizeof *e->by_id);
    e->by_id[at] = k;
    e->n++;
    return OCEAN_OK;
}

ocean_result ocean_entities_remove(ocean_entities *e, uint32_t id)
{
    if (!e) return OCEAN_EINVAL;
    int found, at = find(e, id, &found);
    if (!found) return OCEAN_ENOTFOUND;
    free(e->by_id[at]);
    memmove(&e->by_id[at], &e->by_id[at + 1], (size_t)(e->n - at - 1) * sizeof *e->by_id);
    e->n--;
    return OCEAN_OK;
}

static double speed_max(ocean_entity_kind k)
{
    return k == OCEAN_ENTITY_SHIP ? OCEAN_SHIP_SPEED_MAX
         : k == OCEAN_ENTITY_ROTORCRAFT ? OCEAN_ROTOR_SPEED_MAX : OCEAN_AIRCRAFT_SPEED_MAX;
}

static double altitude_max(ocean_entity_kind k)
{
    return k == OCEAN_ENTITY_SHIP ? 0 : k == OCEAN_ENTITY_ROTORCRAFT ? OCEAN_ROTOR_ALTITUDE_MAX
                                                                      : OCEAN_AIRCRAFT_ALTITUDE_MAX;
}

static const ocean_track_sample *sample_at(const entity *k, int i)
{
    return &k->s[(k->head + i) % OCEAN_TRACK_KEEP];
}

/* The sample's own values, then its step from the track's last sample. */
static ocean_result sample_check(const entity *k, const ocean_track_sample *s, char *why, size_t n)
{
    double vmax = speed_max(k->d.kind);
    double amax = altitude_max(k->d.kind);
    if (!in_range(s->t, -OCEAN_TIME_MAX, OCEAN_TIME_MAX) || !in_range(s->x, -OCEAN_ENTITY_POS_MAX, OCEAN_ENTITY_POS_MAX) ||
        !in_range(s->z, -OCEAN_ENTITY_POS_MAX, OCEAN_ENTITY_POS_MAX) || !in_range(s->altitude_m, 0, amax) ||
        !isfinite(s->heading_deg) || !in_range(s->speed, 0, vmax)) {
        ocean_seterr(why, n, "entity %u sample: t %g s, position (%g, %g) m, altitude %g m, heading %g deg, speed "
                     "%g m/s: each must be finite, |t| <= %g, |x|, |z| <= %g, altitude in [0, %g], speed in "
                     "[0, %g]", k->d.id, s->t, s->x, s->z, s->altitude_m, s->heading_deg, s->speed,
                     OCEAN_TIME_MAX, OCEAN_ENTITY_POS_MAX, amax, vmax);
        return OCEAN_EINVAL;
    }
    if (!k->count) return OCEAN_OK;
    const ocean_track_sample *p = sample_at(k, k->count - 1);
    double dt = s->t - p->t;
    if (!(dt > 0)) {
        ocean_seterr(why, n, "entity %u sample at t = %.6f s is not after its track's last, %.6f s", k->d.id, s->t,
                     p->t);
        return OCEAN_EINVAL;
    }
    double d = hypot(s->x - p->x, s->z - p->z) + fabs(s->altitude_m - p->altitude_m);
    if (d > TELEPORT_FACTOR * vmax * dt + TELEPORT_SLACK_M) {
        ocean_seterr(why, n, "entity %u sample: %.1f m from the last in %.3f s is %.1f m/s, beyond the %g m/s "
                     "it can move (a teleport: remove the entity and enter it again)", k->d.id, d, dt, d / dt,
                     vmax);
        return OCEAN_EINVAL;
    }
    return OCEAN_OK;
}

ocean_result ocean_entities_sample(ocean_entities *e, uint32_t id, const ocean_track_sample *s, char *why,
                                   size_t n)
{
    if (!e || !s) return OCEAN_EINVAL;
    int found, at = find(e, id, &found);
    if (!found) {
        ocean_seterr(why, n, "entity %u is not in the sea (enter it first)", id);
        return OCEAN_ENOTFOUND;
    }
    entity *k = e->by_id[at];
    ocean_result r = sample_check(k, s, why, n);
    if (r != OCEAN_OK) return r;
    if (k->count == OCEAN_TRACK_KEEP) {
        k->head = (k->head + 1) % OCEAN_TRACK_KEEP;
        k->count--;
    }
    k->s[(k->head + k->count) % OCEAN_TRACK_KEEP] = *s;
    k->count++;
    return OCEAN_OK;
}

static void velocity(const ocean_track_sample *s, double *vx, double *vz)
{
    double h = s->heading_deg * (M_PI / 180.0);
    *vx = s->speed * cos(h);
    *vz = s->speed * sin(h);
}

static double heading_norm(double deg)
{
    double h = fmod(deg, 360.0);
    return h < 0 ? h + 360.0 : h;
}

/* The cubic Hermite curve between samples a and b at t (a->t <= t <= b->t). */
static void between(const ocean_track_sample *a, const ocean_track_sample *b, double t, ocean_entity_state *o)
{
    double h = b->t - a->t, s = (t - a->t) / h, s2 = s * s, s3 = s2 * s;
    double va[2], vb[2];
    velocity(a, &va[0], &va[1]);
    velocity(b, &vb[0], &vb[1]);
    double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2, h11 = s3 - s2;
    double d00 = 6 * s2 - 6 * s, d10 = 3 * s2 - 4 * s + 1, d01 = -6 * s2 + 6 * s, d11 = 3 * s2 - 2 * s;
    o->x = h00 * a->x + h10 * h * va[0] + h01 * b->x + h11 * h * vb[0];
    o->z = h00 * a->z + h10 * h * va[1] + h01 * b->z + h11 * h * vb[1];
    o->vx = (d00 * a->x + d01 * b->x) / h + d10 * va[0] + d11 * vb[0];
    o->vz = (d00 * a->z + d01 * b->z) / h + d10 * va[1] + d11 * vb[1];
    o->altitude_m = a->altitude_m + s * (b->altitude_m - a->altitude_m);
    o->speed = a->speed + s * (b->speed - a->speed);
    double turn = remainder(b->heading_deg - a->heading_deg, 360.0); /* the short way */
    o->heading_deg = heading_norm(a->heading_deg + s * turn);
}

/* On from the last sample at its velocity, for the hold at most. */
static void after(const ocean_track_sample *p, double hold_s, double t, ocean_entity_state *o)
{
    double dt = t - p->t;
    o->held = dt > hold_s;
    if (o->held) dt = hold_s;
    velocity(p, &o->vx, &o->vz);
    o->x = p->x + o->vx * dt;
    o->z = p->z + o->vz * dt;
    o->altitude_m = p->altitude_m;
    o->heading_deg = heading_norm(p->heading_deg);
    o->speed = p->speed;
    o->extrapolated = 1;
    if (o->held) o->speed = o->vx = o->vz = 0;
}

ocean_result ocean_entities_state(const ocean_entities *e, uint32_t id, double t, ocean_entity_state *out)
{
    if (!e || !out || !isfinite(t)) return OCEAN_EINVAL;
    int found, at = find(e, id, &found);
    if (!found) return OCEAN_ENOTFOUND;
    const entity *k = e->by_id[at];
    if (!k->count || t < sample_at(k, 0)->t) return OCEAN_ENOTFOUND;
    memset(out, 0, sizeof *out);
    const ocean_track_sample *last = sample_at(k, k->count - 1);
    if (t >= last->t) {
        after(last, e->hold_s, t, out);
        return OCEAN_OK;
    }
    int lo = 0, hi = k->count - 1; /* sample lo <= t < sample hi */
    while (hi - lo > 1) {
        int mid = lo + (hi - lo) / 2;
        if (sample_at(k, mid)->t <= t) lo = mid;
        else hi = mid;
    }
    between(sample_at(k, lo), sample_at(k, hi), t, out);
    return OCEAN_OK;
}

ocean_result ocean_entities_last(const ocean_entities *e, uint32_t id, ocean_track_sample *out)
{
    if (!e || !out) return OCEAN_EINVAL;
    int found, at = find(e, id, &found);
    if (!found || !e->by_id[at]->count) return OCEAN_ENOTFOUND;
    const entity *k = e->by_id[at];
    *out = *sample_at(k, k->count - 1);
    return OCEAN_OK;
}

int ocean_entities_count(const ocean_entities *e) { return e ? e->n : 0; }

ocean_result ocean_entities_desc(const ocean_entities *e, uint32_t id, ocean_entity_desc *out)
{
    if (!e || !out) return OCEAN_EINVAL;
    int found, i = find(e, id, &found);
    if (!found) return OCEAN_ENOTFOUND;
    *out = e->by_id[i]->d;
    return OCEAN_OK;
}

ocean_result ocean_entities_get(const ocean_entities *e, int i, ocean_entity_desc *out)
{
    if (!e || !out || i < 0 || i >= e->n) return OCEAN_EINVAL;
    *out = e->by_id[i]->d;
    return OCEAN_OK;
}
