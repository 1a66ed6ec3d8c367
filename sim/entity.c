/*
 * entity.c - the entity table and a track's state at any instant (see
 * entity.h).
 *
 * Entities sit in an array sorted by id (a binary search per lookup), an
 * id's lives in order (the gone ones kept for their past, the live one
 * last); each holds its track as a ring of its last `keep` samples with
 * the instant each is in force from, grown by doubling as samples come
 * (a ship sampled once a second for a minute holds 64, not `keep`).
 */
#include "entity.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "ocean_time.h"

typedef struct entity {
    ocean_entity_desc d;
    ocean_track_sample *s;   /* a ring of cap samples */
    double *from;            /* each sample in force from; never decreasing */
    int cap;
    int head;            /* index of the oldest kept sample */
    int count;
    double gone;         /* gone from this instant on; INFINITY while live */
} entity;

struct ocean_entities {
    int max;
    int keep;            /* samples a track keeps */
    double hold_s;
    int n, n_live;
    entity **by_id;      /* n records of 2 max at most: increasing id, one id's lives in order */
};

/* A teleport is a step that needs more than the top speed by this factor,
 * plus TELEPORT_SLACK_M (a feeder rounds positions and times). */
#define TELEPORT_FACTOR 1.5
#define TELEPORT_SLACK_M 1.0

ocean_result ocean_entities_create(int max_entities, double hold_s, int keep, ocean_entities **out, char *why,
                                   size_t n)
{
    if (!out) return OCEAN_EINVAL;
    *out = NULL;
    if (max_entities < 1 || max_entities > OCEAN_ENTITY_MAX || !(hold_s >= 0 && hold_s <= 600) || keep < 2 ||
        keep > OCEAN_TRACK_KEEP_MAX) {
        ocean_seterr(why, n, "entities: max %d is outside [1, %d], hold %g s outside [0, 600] or keep %d outside "
                     "[2, %d]", max_entities, OCEAN_ENTITY_MAX, hold_s, keep, OCEAN_TRACK_KEEP_MAX);
        return OCEAN_EINVAL;
    }
    ocean_entities *e = calloc(1, sizeof *e);
    if (!e || !(e->by_id = calloc(2 * (size_t)max_entities, sizeof *e->by_id))) {
        free(e);
        return OCEAN_ENOMEM;
    }
    e->max = max_entities;
    e->keep = keep;
    e->hold_s = hold_s;
    *out = e;
    return OCEAN_OK;
}

static void record_free(entity *k)
{
    if (!k) return;
    free(k->s);
    free(k->from);
    free(k);
}

void ocean_entities_destroy(ocean_entities *e)
{
    if (!e) return;
    for (int i = 0; i < e->n; i++) record_free(e->by_id[i]);
    free(e->by_id);
    free(e);
}

/* The index of id's first record, or of where it would go. */
static int find(const ocean_entities *e, uint32_t id)
{
    int lo = 0, hi = e->n;
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (e->by_id[mid]->d.id < id) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

/* id's live record (its last), or NULL; *at gets its index. */
static entity *live(const ocean_entities *e, uint32_t id, int *at)
{
    int i = find(e, id);
    while (i + 1 < e->n && e->by_id[i + 1]->d.id == id) i++;
    if (at) *at = i;
    if (i < e->n && e->by_id[i]->d.id == id && isinf(e->by_id[i]->gone)) return e->by_id[i];
    return NULL;
}

static void record_drop(ocean_entities *e, int at)
{
    record_free(e->by_id[at]);
    memmove(&e->by_id[at], &e->by_id[at + 1], (size_t)(e->n - at - 1) * sizeof *e->by_id);
    e->n--;
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

/* Room for one more record: the gone record gone earliest makes way. */
static void record_room(ocean_entities *e)
{
    if (e->n < 2 * e->max) return;
    int oldest = -1;
    for (int i = 0; i < e->n; i++)
        if (!isinf(e->by_id[i]->gone) && (oldest < 0 || e->by_id[i]->gone < e->by_id[oldest]->gone)) oldest = i;
    record_drop(e, oldest); /* n == 2 max with at most max live: one is gone */
}

ocean_result ocean_entities_add(ocean_entities *e, const ocean_entity_desc *d, char *why, size_t n)
{
    if (!e || !d) return OCEAN_EINVAL;
    ocean_result r = desc_check(d, why, n);
    if (r != OCEAN_OK) return r;
    if (live(e, d->id, NULL)) {
        ocean_seterr(why, n, "entity %u is already in the sea", d->id);
        return OCEAN_ESTATE;
    }
    if (e->n_live >= e->max) {
        ocean_seterr(why, n, "entity %u: the sea holds %d entities already, the most it takes", d->id, e->max);
        return OCEAN_ETOOBIG;
    }
    entity *k = calloc(1, sizeof *k);
    if (!k) return OCEAN_ENOMEM;
    k->d = *d;
    k->gone = INFINITY;
    record_room(e);
    int at;
    live(e, d->id, &at);
    if (at < e->n && e->by_id[at]->d.id <= d->id) at++; /* after the id's earlier lives */
    memmove(&e->by_id[at + 1], &e->by_id[at], (size_t)(e->n - at) * sizeof *e->by_id);
    e->by_id[at] = k;
    e->n++;
    e->n_live++;
    return OCEAN_OK;
}

/* The i-th kept sample of k, oldest first. */
static const ocean_track_sample *sample_at(const entity *k, int i)
{
    return &k->s[(k->head + i) % k->cap];
}

/* The instant the i-th kept sample of k is in force from. */
static double from_at(const entity *k, int i) { return k->from[(k->head + i) % k->cap]; }

/* The earliest instant a new sample of id may be in force: the removal of
 * its life before this one, or its track's newest sample's. */
static double from_floor(const ocean_entities *e, const entity *k, int at)
{
    if (k->count) return from_at(k, k->count - 1);
    if (at > 0 && e->by_id[at - 1]->d.id == k->d.id) return e->by_id[at - 1]->gone;
    return -INFINITY;
}

double ocean_entities_floor(const ocean_entities *e, uint32_t id)
{
    if (!e) return -INFINITY;
    int at;
    const entity *k = live(e, id, &at);
    if (k) return from_floor(e, k, at);
    /* no live one: a new life starts after the removal of the last */
    return at < e->n && e->by_id[at]->d.id == id ? e->by_id[at]->gone : -INFINITY;
}

ocean_result ocean_entities_remove(ocean_entities *e, uint32_t id, double from)
{
    if (!e) return OCEAN_EINVAL;
    int at;
    entity *k = live(e, id, &at);
    if (!k) return OCEAN_ENOTFOUND;
    if (!isfinite(from) || from < from_floor(e, k, at)) return OCEAN_EINVAL;
    if (!k->count) record_drop(e, at); /* never in the sea: no past to keep */
    else k->gone = from;
    e->n_live--;
    return OCEAN_OK;
}

void ocean_entities_prune(ocean_entities *e, double before)
{
    if (!e) return;
    for (int i = e->n - 1; i >= 0; i--)
        if (e->by_id[i]->gone <= before) record_drop(e, i);
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

ocean_result ocean_entities_check(const ocean_entities *e, uint32_t id, const ocean_track_sample *s, double from,
                                  char *why, size_t n)
{
    if (!e || !s) return OCEAN_EINVAL;
    int at;
    const entity *k = live(e, id, &at);
    if (!k) {
        ocean_seterr(why, n, "entity %u is not in the sea (enter it first)", id);
        return OCEAN_ENOTFOUND;
    }
    double floor_from = from_floor(e, k, at);
    if (!isfinite(from) || from < floor_from) {
        ocean_seterr(why, n, "entity %u sample: in force from %.6f s, before %.6f s, when its entity's last "
                     "entry took effect", id, from, floor_from);
        return OCEAN_EINVAL;
    }
    return sample_check(k, s, why, n);
}

/* Room for want (at most keep) samples, the kept ones in order from 0. */
static ocean_result track_grow(entity *k, int want, int keep)
{
    if (want > keep) want = keep;
    ocean_track_sample *s = malloc(sizeof *s * (size_t)want);
    double *from = malloc(sizeof *from * (size_t)want);
    if (!s || !from) {
        free(s);
        free(from);
        return OCEAN_ENOMEM;
    }
    for (int i = 0; i < k->count; i++) {
        s[i] = *sample_at(k, i);
        from[i] = from_at(k, i);
    }
    free(k->s);
    free(k->from);
    k->s = s;
    k->from = from;
    k->cap = want;
    k->head = 0;
    return OCEAN_OK;
}

ocean_result ocean_entities_sample(ocean_entities *e, uint32_t id, const ocean_track_sample *s, double from,
                                   char *why, size_t n)
{
    ocean_result r = ocean_entities_check(e, id, s, from, why, n);
    if (r != OCEAN_OK) return r;
    entity *k = live(e, id, NULL);
    if (k->count == k->cap && k->cap < e->keep && track_grow(k, k->cap ? 2 * k->cap : 4, e->keep) != OCEAN_OK) {
        ocean_seterr(why, n, "entity %u: out of memory for its track", id);
        return OCEAN_ENOMEM;
    }
    if (k->count == k->cap) {
        k->head = (k->head + 1) % k->cap;
        k->count--;
    }
    int slot = (k->head + k->count) % k->cap;
    k->s[slot] = *s;
    k->from[slot] = from;
    k->count++;
    return OCEAN_OK;
}

int ocean_entity_desc_same(const ocean_entity_desc *a, const ocean_entity_desc *b)
{
    return a->kind == b->kind && a->length_m == b->length_m && a->beam_m == b->beam_m &&
           a->draught_m == b->draught_m;
}

ocean_result ocean_entities_enter(ocean_entities *e, const ocean_entity_desc *d, const ocean_track_sample *s,
                                  double from, char *why, size_t n)
{
    if (!e || !d || !s) return OCEAN_EINVAL;
    const entity *k = live(e, d->id, NULL);
    if (k && !ocean_entity_desc_same(&k->d, d)) {
        ocean_seterr(why, n, "entity %u is kind %d, %g x %g x %g m; a sample may not change its kind or size "
                     "(remove it first)", d->id, (int)k->d.kind, k->d.length_m, k->d.beam_m, k->d.draught_m);
        return OCEAN_EINVAL;
    }
    ocean_result r = k ? OCEAN_OK : ocean_entities_add(e, d, why, n);
    if (r == OCEAN_OK) r = ocean_entities_sample(e, d->id, s, from, why, n);
    if (r != OCEAN_OK && !k) ocean_entities_remove(e, d->id, from); /* never in the sea: no record left */
    return r;
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

/* How many of k's kept samples are in force at t (a prefix: froms never
 * decrease along a track). */
static int in_force(const entity *k, double t)
{
    int lo = 0, hi = k->count;
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (from_at(k, mid) <= t) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

/* Record k's state at t from its samples in force then; 0 when it is not
 * in the sea at t. */
static int record_state(const entity *k, double hold_s, double t, ocean_entity_state *out)
{
    int count = t < k->gone ? in_force(k, t) : 0;
    if (!count || t < sample_at(k, 0)->t) return 0;
    memset(out, 0, sizeof *out);
    const ocean_track_sample *last = sample_at(k, count - 1);
    if (t >= last->t) {
        after(last, hold_s, t, out);
        return 1;
    }
    int lo = 0, hi = count - 1; /* sample lo <= t < sample hi */
    while (hi - lo > 1) {
        int mid = lo + (hi - lo) / 2;
        if (sample_at(k, mid)->t <= t) lo = mid;
        else hi = mid;
    }
    between(sample_at(k, lo), sample_at(k, hi), t, out);
    return 1;
}

ocean_result ocean_entities_state(const ocean_entities *e, uint32_t id, double t, ocean_entity_state *out)
{
    if (!e || !out || !isfinite(t)) return OCEAN_EINVAL;
    for (int i = find(e, id); i < e->n && e->by_id[i]->d.id == id; i++)
        if (record_state(e->by_id[i], e->hold_s, t, out)) return OCEAN_OK;
    return OCEAN_ENOTFOUND;
}

int ocean_entities_at(const ocean_entities *e, double t, ocean_entity_desc *d, ocean_entity_state *s, int max)
{
    if (!e || !d || !s || !isfinite(t)) return 0;
    int n = 0;
    for (int i = 0; i < e->n && n < max; i++)
        if (record_state(e->by_id[i], e->hold_s, t, &s[n])) d[n++] = e->by_id[i]->d;
    return n;
}

ocean_result ocean_entities_last(const ocean_entities *e, uint32_t id, ocean_track_sample *out, double *from)
{
    if (!e || !out) return OCEAN_EINVAL;
    const entity *k = live(e, id, NULL);
    if (!k || !k->count) return OCEAN_ENOTFOUND;
    *out = *sample_at(k, k->count - 1);
    if (from) *from = from_at(k, k->count - 1);
    return OCEAN_OK;
}

int ocean_entities_each(const ocean_entities *e, void (*fn)(void *ctx, const ocean_entity_entry *en), void *ctx)
{
    if (!e || !fn) return 0;
    int n = 0;
    for (int i = 0; i < e->n; i++) {
        const entity *k = e->by_id[i];
        ocean_entity_entry en = {.d = k->d};
        for (int j = 0; j < k->count; j++, n++) {
            en.s = *sample_at(k, j);
            en.from = from_at(k, j);
            fn(ctx, &en);
        }
        if (isinf(k->gone)) continue;
        en = (ocean_entity_entry){.d = k->d, .removal = 1, .from = k->gone};
        fn(ctx, &en);
        n++;
    }
    return n;
}

int ocean_entities_count(const ocean_entities *e) { return e ? e->n_live : 0; }

int ocean_entities_kept(const ocean_entities *e) { return e ? e->n : 0; }

int ocean_entities_count_kind(const ocean_entities *e, ocean_entity_kind k)
{
    int n = 0;
    for (int i = 0; e && i < e->n; i++) n += e->by_id[i]->d.kind == k;
    return n;
}

ocean_result ocean_entities_desc(const ocean_entities *e, uint32_t id, ocean_entity_desc *out)
{
    if (!e || !out) return OCEAN_EINVAL;
    const entity *k = live(e, id, NULL);
    if (!k) return OCEAN_ENOTFOUND;
    *out = k->d;
    return OCEAN_OK;
}

ocean_result ocean_entities_get(const ocean_entities *e, int i, ocean_entity_desc *out)
{
    if (!e || !out || i < 0) return OCEAN_EINVAL;
    if (e->n == e->n_live && i < e->n) { /* no gone lives kept: the i-th record */
        *out = e->by_id[i]->d;
        return OCEAN_OK;
    }
    for (int j = 0; j < e->n; j++)
        if (isinf(e->by_id[j]->gone) && i-- == 0) {
            *out = e->by_id[j]->d;
            return OCEAN_OK;
        }
    return OCEAN_EINVAL;
}
