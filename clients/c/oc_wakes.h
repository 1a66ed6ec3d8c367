/*
 * oc_wakes.h - a reader's wakes of the ships: the entity table its ENTITY
 * entries make (each in force from its header sim_time) and the WAKE
 * patterns it received (the last PROTO_WAKE_HELD, the oldest going first,
 * as the server counts on), read as the daemon reads them
 * (sim/wake_field.h; PROTOCOL.md "WAKE").  One implementation for every
 * reader: the C library (oceanclient.c) and the browser viewer's
 * WebAssembly (clients/wasm/oc_wasm.c).
 *
 * Threads: one at a time (the owner's lock); oc_wakes_decode touches no
 * store and may run outside it.
 * OOM: OCEAN_ENOMEM, the store unchanged.
 */
#ifndef OC_WAKES_H
#define OC_WAKES_H

#include <stddef.h>
#include <stdint.h>

#include "proto.h"
#include "wake_field.h"

/* Samples a reader keeps of a track: a daemon's 256 by default
 * (server.entity_track_keep) and more, 68 s of a 60 Hz host (256 KB a
 * track at most). */
#define OC_WAKES_TRACK_KEEP 4096

typedef struct oc_wakes oc_wakes;

ocean_result oc_wakes_create(oc_wakes **out);
void oc_wakes_destroy(oc_wakes *w); /* accepts NULL */

/* An ENTITY announce or gone m into the table, as the server entered it.
 * OCEAN_EINVAL when the table refuses it (the server sent it: an entry
 * older than a joiner's snapshot, or the server's fault); a get or set is
 * no entry (OCEAN_EINVAL). */
ocean_result oc_wakes_entity(oc_wakes *w, const proto_msg *m);

/* A WAKE's pattern, decoded and made readable (a pattern is up to 4096 x
 * 4096 coefficients: outside the owner's lock).  NULL when its payload or
 * parameters are bad, or on OOM. */
wake_pattern *oc_wakes_decode(const proto_wake *p);
/* Keeps pattern p (taken; NULL is ignored). */
void oc_wakes_keep(oc_wakes *w, wake_pattern *p);
/* Patterns kept. */
int oc_wakes_patterns(const oc_wakes *w);

/* The ships' wakes at the n points xz at sim time t over water of the
 * given depth: wake_field_sample of the entities in force at t, and the
 * rotorcraft's downwash (rotor_wash_add; its table made at the first
 * rotorcraft).
 * OCEAN_ESTATE: a pattern a ship there needs has not come; OCEAN_EINVAL,
 * OCEAN_ENOMEM. */
ocean_result oc_wakes_sample(oc_wakes *w, double t, double depth, const double *xz, size_t n, wake_sample *out);

/* The wakes on the n x n points (x0 + i dx, z0 + j dx), row j after row,
 * as a renderer draws them: 4 floats a point, height, dh/dx, dh/dz and
 * the slope variance a side (x and z each) the grid does not hold.  The
 * slopes are the point slopes low-passed by the grid's 5-point tent (a
 * wave shorter than two points would alias into the shading), and the
 * variance the stencil takes out is handed to the roughness, so the
 * wakes' mean-square slope is kept at any spacing.  n in [3, 1024], dx >
 * 0.  The errors of oc_wakes_sample. */
ocean_result oc_wakes_grid(oc_wakes *w, double t, double depth, double x0, double z0, double dx, int n, float *out);

#endif
