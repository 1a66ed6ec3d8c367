/*
 * srv_held.h - what a time-interpolating layout-1 client holds: for each
 * (cascade, mip), the two samples of its time window (A at tick_a, B at
 * tick_a + interval) and which tiles of each it has received, with the
 * channels they carry (PROTOCOL.md "Samples in time").
 *
 * The daemon keeps this model of each such client and sends a tile only
 * when the client does not hold it; the model moves its windows by the
 * very rule the client applies on reading a FRAME, so the two agree
 * without a message between them.  The model may know less than the
 * client (a frame the service thread had not yet written when the next
 * was planned), never more: knowing less costs a tile sent twice.
 *
 * Threads: owned by the simulation thread (srv_client_sim).
 */
#ifndef SRV_HELD_H
#define SRV_HELD_H

#include <stdint.h>

#include "ocean_result.h"
#include "proto.h"

typedef struct srv_held srv_held;

ocean_result srv_held_create(srv_held **out);
/* Accepts NULL. */
void srv_held_destroy(srv_held *h);

/* The client is to hold nothing: the next frame is a KEY frame (as is a
 * new model's first). */
void srv_held_clear(srv_held *h);
/* 1 while the next frame must carry the KEY flag. */
int srv_held_key(const srv_held *h);
/* A frame with the KEY flag was made from this model. */
void srv_held_keyed(srv_held *h);
/* Makes dst a copy of src; OCEAN_ENOMEM leaves dst empty. */
ocean_result srv_held_copy(srv_held *dst, const srv_held *src);
/* Keeps in dst only what src holds too (the same window, channels and
 * tile), and the KEY demand of either: what a client holds whichever of
 * the two it has. */
void srv_held_meet(srv_held *dst, const srv_held *src);

/* Applies a frame's time table to (cascade c, mip m) as the client does
 * before reading the frame's records: interval 0 drops both samples; a
 * window that starts at the held B moves B to A; any other new window
 * drops both.  tiles: tiles of the mip (tiles per side squared).
 * OCEAN_ENOMEM leaves (c, m) empty. */
ocean_result srv_held_advance(srv_held *h, int c, int m, const proto_mip_time *t, int tiles);
/* Drops (c, m) for every mip at or beyond m0 of cascade c (all of c: m0 0). */
void srv_held_drop(srv_held *h, int c, int m0);

/* Whether the client holds tile i of (c, m)'s sample slot (0 A, 1 B) with
 * exactly these channels. */
int srv_held_has(const srv_held *h, int c, int m, int slot, int i, unsigned channels);
/* Records tile i of (c, m)'s slot as held with these channels (a slot
 * holds one channel set: a tile of another set empties it first). */
void srv_held_add(srv_held *h, int c, int m, int slot, int i, unsigned channels);

#endif
