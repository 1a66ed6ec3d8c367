/*
 * srv_entity.h - the entities in the daemon's sea: one table of id ->
 * shape and track (sim/entity.h) that every feeder enters and every reader
 * asks.  The CIGI service enters its host's Entity Control and resolves
 * entity-relative HAT/HOT requests against it; ocean.v1's ENTITY message
 * (srv_handle.c) enters and removes them; the replicated timeline and the
 * wakes (one concept for all) come to the same table.
 *
 * Tracks are in sim time: a feeder that only knows "now" enters its sample
 * at the daemon's sim clock.  A track runs on SRV_ENTITY_HOLD_S past its
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
#include "ocean_result.h"

/* How long a track runs on past its last sample, s. */
#define SRV_ENTITY_HOLD_S 10.0

typedef struct srv_entities srv_entities;

/* A table for at most max entities (server.max_entities).  OCEAN_EINVAL
 * with why. */
ocean_result srv_entities_create(int max, srv_entities **out, char *why, size_t n);
void srv_entities_destroy(srv_entities *e); /* accepts NULL */

/* Appends sample s to entity d->id's track, entering the entity with
 * shape d first when the table does not hold it (a known entity keeps its
 * shape).  The errors of ocean_entities_add and ocean_entities_sample,
 * with why; on any error the table is unchanged. */
ocean_result srv_entities_sample(srv_entities *e, const ocean_entity_desc *d, const ocean_track_sample *s,
                                 char *why, size_t n);
/* Takes entity id out.  OCEAN_ENOTFOUND. */
ocean_result srv_entities_remove(srv_entities *e, uint32_t id);
/* id's state at sim time t (ocean_entities_state). */
ocean_result srv_entities_state(srv_entities *e, uint32_t id, double t, ocean_entity_state *out);
/* id's newest sample (ocean_entities_last). */
ocean_result srv_entities_last(srv_entities *e, uint32_t id, ocean_track_sample *out);
int srv_entities_count(srv_entities *e);
/* Entity id's shape.  OCEAN_ENOTFOUND. */
ocean_result srv_entities_find(srv_entities *e, uint32_t id, ocean_entity_desc *out);
/* Every entity with a sample (at most max): shape and newest sample, in
 * increasing id, copied under one hold.  Returns how many. */
int srv_entities_snapshot(srv_entities *e, ocean_entity_desc *d, ocean_track_sample *s, int max);
/* Every entity in the sea at sim time t (at most max): shape and state
 * at t, in increasing id, copied under one hold.  Returns how many. */
int srv_entities_at(srv_entities *e, double t, ocean_entity_desc *d, ocean_entity_state *s, int max);

#endif
