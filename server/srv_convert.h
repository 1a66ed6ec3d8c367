/*
 * srv_convert.h - the protocol's types as the simulation's and back: a
 * SEA_STATE's sea as ocean parameters, a CAMERA as a mesh camera, an
 * ENTITY as an entity's shape and track sample.
 *
 * Threads: any (pure functions).
 */
#ifndef SRV_CONVERT_H
#define SRV_CONVERT_H

#include "entity.h"
#include "mesh.h"
#include "ocean.h"
#include "proto.h"

void srv_sea_from_params(const ocean_params *p, proto_sea *out);
void srv_params_from_sea(const proto_sea *s, const ocean_params *base, ocean_params *out);
/* The SEA_STATE announce of sea, in force from sim time eff, sent at sim
 * time now (the message every replica and client reads a change as). */
void srv_sea_announce(const proto_sea *sea, double eff, double now, proto_msg *out);
void srv_mesh_camera(const proto_camera *pc, mesh_camera *out);
/* An ENTITY set's shape and track sample, as the entity table takes them. */
void srv_entity_from_msg(const proto_entity *e, ocean_entity_desc *d, ocean_track_sample *s);
/* The ENTITY message of op (announce: shape and sample; gone: d->id
 * alone) that takes effect at sim time `from` (its header sim_time). */
void srv_entity_msg(unsigned op, const ocean_entity_desc *d, const ocean_track_sample *s, double from, proto_msg *out);


#endif
