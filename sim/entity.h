/*
 * entity.h - ships and rotorcraft in the sea: a table of entities, each an
 * id, a shape and a track of samples in sim time, and the state of any of
 * them at any instant.
 *
 * One concept for every feeder: an ocean.v1 client and a CIGI host's Entity
 * Control enter the same samples (docs/design.md, "Entities"), and the sea
 * stays a pure function of its inputs: the state at t depends only on the
 * samples the table holds, in whatever order the instants are asked for,
 * never on earlier calls.
 *
 * A track: samples (t, x, z in double, altitude, heading, speed) entered in
 * strictly increasing t.  Between two samples the position is the cubic
 * Hermite curve through both positions with both velocities (heading and
 * speed) as tangents, so a turn drawn from sparse samples stays smooth and
 * passes through every sample; heading turns the short way, speed and
 * altitude go linearly.  After the last sample the entity goes on at that
 * sample's velocity for at most `hold` seconds, then stays where that left
 * it, stopped (state.held): a feeder that goes silent leaves no ship
 * steaming off forever.  Before its first sample an entity is not in the
 * sea (OCEAN_ENOTFOUND).  A track keeps its last `keep` samples (the
 * table's; a daemon's default OCEAN_TRACK_KEEP); an instant before the
 * oldest kept is OCEAN_ENOTFOUND too.
 *
 * Samples are timeline entries (docs/design.md, "Entities"): each is in
 * force from an instant of its own, `from` (when the daemon entered it,
 * or when a replicated entry takes effect), and the state at t is made of
 * the samples in force at t alone.  A sample entered later never changes
 * an instant before its `from`, so two replicas that enter the same
 * samples with the same `from` agree at every instant, however late each
 * read them.  A removal is an entry too: the entity is gone from its
 * `from` on, and an id entered again after it starts a new life (a new
 * shape, a new track); a gone entity's past is kept until
 * ocean_entities_prune drops it.
 *
 * Every input is checked: NaN or Inf anywhere, sizes and speeds outside the
 * kind's range, samples out of time order, and teleports (a sample whose
 * distance from the previous one needs more than the kind's top speed,
 * with a margin for the feeder's rounding) are refused with a message and
 * change nothing.
 *
 * Threads: a table belongs to one thread; const calls may run in several
 * threads at once when nothing writes it.
 * OOM: OCEAN_ENOMEM, the table unchanged.
 */
#ifndef OCEAN_ENTITY_H
#define OCEAN_ENTITY_H

#include <stddef.h>
#include <stdint.h>

#include "ocean_result.h"

typedef enum ocean_entity_kind {
    OCEAN_ENTITY_SHIP = 0,
    OCEAN_ENTITY_ROTORCRAFT = 1,
    OCEAN_ENTITY_AIRCRAFT = 2,  /* any other flier: a frame for requests, no wake */
    OCEAN_ENTITY_KIND_COUNT_
} ocean_entity_kind;

#define OCEAN_ENTITY_MAX 4096       /* the most a table may be made for */
#define OCEAN_ENTITY_HOLD_S 10.0    /* s an entity goes on at its last velocity, then holds
                                       (every oceand table and reader: PROTOCOL.md "ENTITY") */
#define OCEAN_TRACK_KEEP 256        /* samples a daemon's track keeps by default */
#define OCEAN_TRACK_KEEP_MAX (1 << 20) /* the most a table may keep a track */
#define OCEAN_ENTITY_POS_MAX 2.0e7  /* |x|, |z| in m: half the Earth's circumference */
/* Top speeds (m/s): a fast boat is 25, a helicopter's Vne about 90. */
#define OCEAN_SHIP_SPEED_MAX 30.0
#define OCEAN_ROTOR_SPEED_MAX 100.0
#define OCEAN_ROTOR_ALTITUDE_MAX 5000.0
/* An aircraft: Mach 3 at the ceiling of a U-2 and more. */
#define OCEAN_AIRCRAFT_SPEED_MAX 1000.0
#define OCEAN_AIRCRAFT_ALTITUDE_MAX 30000.0

typedef struct ocean_entity_desc {
    uint32_t id;
    ocean_entity_kind kind;
    double length_m;     /* ship: waterline length [1, 500]; rotorcraft: rotor diameter [1, 40];
                            aircraft: span [1, 100] */
    double beam_m;       /* ship: [0.5, 100]; rotorcraft, aircraft: 0 */
    double draught_m;    /* ship: [0.1, 30]; rotorcraft, aircraft: 0 */
} ocean_entity_desc;

typedef struct ocean_track_sample {
    double t;            /* sim time, s */
    double x, z;         /* world position, m */
    double altitude_m;   /* above mean sea level: rotorcraft [0, 5000], aircraft [0, 30000]; ship: 0 */
    double heading_deg;  /* direction of travel, degrees from +x toward +z (any finite value) */
    double speed;        /* m/s along the heading, [0, the kind's top speed] */
} ocean_track_sample;

typedef struct ocean_entity_state {
    double x, z, altitude_m;
    double heading_deg;  /* [0, 360) */
    double speed;        /* m/s; 0 once held */
    double vx, vz;       /* velocity, m/s */
    int extrapolated;    /* after the last sample */
    int held;            /* after the last sample and its hold: stopped */
} ocean_entity_state;

typedef struct ocean_entities ocean_entities;

/* A table for at most max_entities (1..OCEAN_ENTITY_MAX) entities whose
 * tracks run on hold_s seconds (0..600) past their last sample and keep
 * their last `keep` samples (2..OCEAN_TRACK_KEEP_MAX; memory grows with
 * the samples a track holds, not with keep). */
ocean_result ocean_entities_create(int max_entities, double hold_s, int keep, ocean_entities **out, char *why,
                                   size_t n);
void ocean_entities_destroy(ocean_entities *e); /* accepts NULL */

/* Enters an entity with no track yet (a live one: not removed).
 * OCEAN_EINVAL (shape), OCEAN_ESTATE (a live entity has the id),
 * OCEAN_ETOOBIG (max_entities live already).  Gone entities whose past is
 * still kept take no place: the table keeps as many as there are live
 * ones, the one gone earliest dropped for a new one. */
ocean_result ocean_entities_add(ocean_entities *e, const ocean_entity_desc *d, char *why, size_t n);
/* The live entity id is gone from sim time `from` on (no instant before
 * it changes).  OCEAN_ENOTFOUND: no live entity id; OCEAN_EINVAL: from
 * not finite, or before its newest sample's from. */
ocean_result ocean_entities_remove(ocean_entities *e, uint32_t id, double from);
/* The earliest instant an entry of id may take effect: its live track's
 * newest sample's from, else its last life's removal, else -INFINITY. */
double ocean_entities_floor(const ocean_entities *e, uint32_t id);
/* Drops the past of every entity gone at or before `before`. */
void ocean_entities_prune(ocean_entities *e, double before);

/* Appends a sample to live entity id's track, in force from sim time
 * `from` on.  OCEAN_ENOTFOUND (no live entity id), OCEAN_EINVAL (a value
 * out of range, out of time order, a teleport; from not finite, before the
 * track's previous from, or before the removal of the id's earlier life),
 * OCEAN_ENOMEM (the track could not grow). */
ocean_result ocean_entities_sample(ocean_entities *e, uint32_t id, const ocean_track_sample *s, double from,
                                   char *why, size_t n);
/* A sample of entity d->id, as a feeder gives it: the entity entered with
 * shape d first when no live one has the id, then the sample appended
 * (ocean_entities_sample).  OCEAN_EINVAL for a shape other than the live
 * entity's (a new shape is a new life: remove it first), and the errors
 * of ocean_entities_add and ocean_entities_sample; on any error the
 * table is unchanged. */
ocean_result ocean_entities_enter(ocean_entities *e, const ocean_entity_desc *d, const ocean_track_sample *s,
                                  double from, char *why, size_t n);
/* Whether a and b are the same kind and size (their ids aside). */
int ocean_entity_desc_same(const ocean_entity_desc *a, const ocean_entity_desc *b);
/* What ocean_entities_sample would answer, the table unchanged. */
ocean_result ocean_entities_check(const ocean_entities *e, uint32_t id, const ocean_track_sample *s, double from,
                                  char *why, size_t n);

/* id's state at sim time t, from the samples in force at t.
 * OCEAN_ENOTFOUND: no entity id in the sea at t (none entered, none of its
 * samples in force yet, t before its first kept sample, or gone);
 * OCEAN_EINVAL: t not finite. */
ocean_result ocean_entities_state(const ocean_entities *e, uint32_t id, double t, ocean_entity_state *out);
/* Every entity in the sea at t (at most max): shape and state, in
 * increasing id.  Returns how many. */
int ocean_entities_at(const ocean_entities *e, double t, ocean_entity_desc *d, ocean_entity_state *s, int max);

/* Live entity id's newest sample (whether in force yet or not), and its
 * from into *from (if not NULL).  OCEAN_ENOTFOUND: no live entity id, or
 * no sample yet. */
ocean_result ocean_entities_last(const ocean_entities *e, uint32_t id, ocean_track_sample *out, double *from);

/* One entry of the table's kept timeline: a sample of one life of an
 * entity, or the removal that ends that life. */
typedef struct ocean_entity_entry {
    ocean_entity_desc d;
    int removal;         /* 1: the life ends at `from` (s unused) */
    ocean_track_sample s;
    double from;         /* the instant the entry is in force from */
} ocean_entity_entry;

/* Calls fn with every kept entry, in an order that rebuilds the table when
 * entered one by one into an empty one (ocean_entities_add before a life's
 * first sample, ocean_entities_sample, ocean_entities_remove): id by id,
 * each id's lives in turn, a life's kept samples oldest first, then its
 * removal when it is gone.  Every instant the table can answer then reads
 * the same from both tables.  Returns the number of entries. */
int ocean_entities_each(const ocean_entities *e, void (*fn)(void *ctx, const ocean_entity_entry *en), void *ctx);

/* Live entities (entered and not removed). */
int ocean_entities_count(const ocean_entities *e);
/* Entities live or gone with their past kept: the most ocean_entities_at
 * can return. */
int ocean_entities_kept(const ocean_entities *e);
/* Of those, the ones of kind k. */
int ocean_entities_count_kind(const ocean_entities *e, ocean_entity_kind k);
/* Live entity id's desc.  OCEAN_ENOTFOUND when none is live. */
ocean_result ocean_entities_desc(const ocean_entities *e, uint32_t id, ocean_entity_desc *out);
/* The desc of the i-th live entity (0 <= i < count), in increasing id. */
ocean_result ocean_entities_get(const ocean_entities *e, int i, ocean_entity_desc *out);

#endif
