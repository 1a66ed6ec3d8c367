/*
 * srv_entity.h - the entities in the daemon's sea: one table of id ->
 * shape and track (sim/entity.h) that every feeder enters and every reader
 * asks.  The CIGI service enters its host's Entity Control and resolves
 * entity-relative HAT/HOT requests against it; ocean.v1's ENTITY message
 * (srv_handle.c) enters and removes them; the replicated timeline and the
 * wakes (one concept for all) come to the same table.
 *
 * Tracks are in sim time: a feeder that only knows "now" enters its sample
 * at the daemon's sim clock.  Every sample and removal is an entry with
 * the instant it takes effect (sim/entity.h): the daemon's clock when it
 * is entered, or, replicated, the time its Redis entry takes effect
 * (srv_redis.h), so the sea at any instant depends only on the entries.  A track runs on SRV_ENTITY_HOLD_S past its
 * last sample, then holds still (sim/entity.h), so an entity whose feeder
 * went silent stays where it was left.
 *
 * Threads: any thread; the table has its own lock, never held while
 * another lock is taken.
 * OOM: OCEAN_ENOMEM, the table unchanged.
 */
#ifndef SRV_ENTITY_H
#define SRV_ENTITY_H

#include <stddef.h>
#include <stdint.h>

#include "entity.h"
#include "proto.h"
#include "rotor_wash.h"
#include "ocean_result.h"

/* How long a track runs on past its last sample, s. */
#define SRV_ENTITY_HOLD_S PROTO_ENTITY_HOLD_S
/* How long a gone entity's past is kept after its removal, s: a query or
 * replay may ask an instant this far back (a sample lies within 60 s of
 * the clock). */
#define SRV_ENTITY_PAST_S PROTO_ENTITY_PAST_S

typedef struct srv_entities srv_entities;

/* A table for at most max entities (server.max_entities), each track
 * keeping its last keep samples (server.entity_track_keep).  OCEAN_EINVAL
 * with why. */
ocean_result srv_entities_create(int max, int keep, srv_entities **out, char *why, size_t n);
void srv_entities_destroy(srv_entities *e); /* accepts NULL */

/* Appends sample s, in force from sim time `from`, to entity d->id's
 * track, entering the entity with shape d first when no live one has the
 * id.  The errors of ocean_entities_add and ocean_entities_sample, and
 * OCEAN_EINVAL for a shape other than the live entity's, with why; on any
 * error the table is unchanged.  Drops the past of entities gone
 * SRV_ENTITY_PAST_S before `from`. */
ocean_result srv_entities_sample(srv_entities *e, const ocean_entity_desc *d, const ocean_track_sample *s,
                                 double from, char *why, size_t n);
/* 1 when a live entity d->id would refuse sample s in force from `from`
 * (a shape other than its own, a step it cannot make; `from` taken no
 * earlier than its last entry, as srv_hub_entity_enter does), the table
 * unchanged: a feeder that is its entities' authority enters such
 * an entity anew instead. */
int srv_entities_refuses(srv_entities *e, const ocean_entity_desc *d, const ocean_track_sample *s, double from);
/* The earliest instant an entry of id may take effect (ocean_entities_floor). */
double srv_entities_floor(srv_entities *e, uint32_t id);
/* Entity id is gone from sim time `from` on (ocean_entities_remove):
 * OCEAN_ENOTFOUND, OCEAN_EINVAL. */
ocean_result srv_entities_remove(srv_entities *e, uint32_t id, double from);
/* id's state at sim time t (ocean_entities_state). */
ocean_result srv_entities_state(srv_entities *e, uint32_t id, double t, ocean_entity_state *out);
/* id's newest sample and the instant it takes effect (ocean_entities_last). */
ocean_result srv_entities_last(srv_entities *e, uint32_t id, ocean_track_sample *out, double *from);
/* Live entities (ocean_entities_count). */
int srv_entities_count(srv_entities *e);
/* Entities live or gone with their past kept: the most srv_entities_at
 * can return (ocean_entities_kept). */
int srv_entities_kept(srv_entities *e);
/* Entity id's shape.  OCEAN_ENOTFOUND. */
ocean_result srv_entities_find(srv_entities *e, uint32_t id, ocean_entity_desc *out);
/* Every live entity with a sample (at most max): shape, newest sample and
 * the instant it takes effect, in increasing id, copied under one hold.
 * Returns how many. */
int srv_entities_snapshot(srv_entities *e, ocean_entity_desc *d, ocean_track_sample *s, double *from, int max);
/* Calls fn with every kept entry of the table's timeline under one hold
 * (ocean_entities_each: the order that rebuilds the table).  fn may take
 * only leaf locks.  Returns the number of entries. */
int srv_entities_each(srv_entities *e, void (*fn)(void *ctx, const ocean_entity_entry *en), void *ctx);
/* Every entity in the sea at sim time t (at most max): shape and state
 * at t, in increasing id, copied under one hold.  Returns how many. */
int srv_entities_at(srv_entities *e, double t, ocean_entity_desc *d, ocean_entity_state *s, int max);
/* Rotorcraft live or gone with their past kept. */
int srv_entities_rotorcraft(srv_entities *e);
/* Adds the rotorcraft's downwash at sim time t to the n points
 * (rotor_wash_add over the table, under its lock). */
ocean_result srv_entities_rotor_wash(srv_entities *e, const rotor_wash *w, double t, const double *xz, size_t n,
                                     wake_sample *out);

#endif
