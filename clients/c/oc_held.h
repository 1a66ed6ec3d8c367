/*
 * oc_held.h - the samples a time-interpolating layout-1 client holds
 * (SUBSCRIBE flag PROTO_SUB_TIME_INTERP; PROTOCOL.md "Samples in time").
 *
 * Each mip of each cascade travels as samples at its own update interval:
 * sample A at tick_a and B at tick_a + interval, every tile sent once per
 * sample, and each FRAME reads (1 - w) A + w B.  The store keeps both
 * samples' decoded tiles from frame to frame, applies each FRAME as the
 * spec says (KEY drops everything; a window starting at the held B moves
 * B to A; any other new window, or interval 0, drops the mip), and gives
 * the tiles of the frame's instant, blended, for the lod rule's view
 * (oc_cascade_view_build).
 *
 * Threading: a store belongs to the one thread that reads a connection's
 * frames in order.
 */
#ifndef OC_HELD_H
#define OC_HELD_H

#include "ocean_result.h"
#include "proto.h"

typedef struct oc_held oc_held;

ocean_result oc_held_create(oc_held **out);
/* Accepts NULL. */
void oc_held_destroy(oc_held *h);

/* Whether frame f (layout 1) needs a store: a KEY frame, or one with a
 * mip that has a time interval. */
int oc_held_frame_timed(const proto_frame *f);

/* Applies FRAME f.  With data, data[i] are the decoded planes of
 * f->tiles[i] (copied into the store; NULL: that tile could not be
 * decoded, and is not held).  Without (data NULL), each tile's payload is
 * copied and decoded only when oc_held_decode needs it, so a reader that
 * applies every frame but looks at few (a page drawing slower than the
 * stream) never decodes a sample replaced before it was looked at.  A
 * frame that is neither KEY nor continues what the store holds is not
 * detectable here: the spec's rules make every frame of one connection,
 * read in order, consistent. */
ocean_result oc_held_apply(oc_held *h, const proto_frame *f, const float *const *data, char *err, size_t errlen);

/* Decodes every held tile that is still a payload.  A tile that does not
 * decode is dropped (the store stays consistent: its place reads as not
 * held); the result is then that tile's decoder error, message in err,
 * and the others are decoded all the same. */
ocean_result oc_held_decode(oc_held *h, char *err, size_t errlen);

/* The tiles of f's instant: for each mip of each cascade of f, its held
 * tiles (interval 0) or, for each tile held in A, the blend (1 - w) A +
 * w B over the channels both carry, or A alone while its B has not come
 * (a tile still a payload, see oc_held_decode, is left out).  error_bound is the larger of A's and
 * B's.  *tiles (proto_tile, no
 * payload) and *data (one malloc'd array per tile) are the caller's to
 * free with oc_held_blend_free. */
ocean_result oc_held_blend(const oc_held *h, const proto_frame *f, proto_tile **tiles, float ***data,
                           unsigned *n);
void oc_held_blend_free(proto_tile *tiles, float **data, unsigned n);

#endif
