/*
 * srv_wakes.h - the ships' wakes in the daemon's point answers (QUERY and
 * the CIGI service's HAT/HOT, which asks through QUERY): the wake field
 * (sim/wake_field.h) of the hub's entities, its patterns built on this
 * module's own thread, off the threads that serve clients.
 *
 * A query slice asks srv_wakes_sample for the wakes at its points at its
 * sim time.  When a pattern they need is not built yet the slice waits
 * (OCEAN_ESTATE) and the pattern goes to the builder: no answer goes out
 * without the wakes its points lie in, so every daemon answers the same
 * whatever its speed.  What it costs is latency, when a ship reaches a
 * rung of the speed ladder: one FFT build (0.1-10 s at nice 10), asked
 * for as soon as a feeder sets the ship there (srv_wakes_ahead), so a
 * query waits only for what is left of it; a ship at steady speed needs
 * two patterns, kept while they are
 * read (the least recently read go first, past 2 per entity and 8).
 *
 * The same patterns go to viewers (layout 1) as WAKE messages, each
 * encoded once when it is built and shared by every viewer that needs it
 * (srv_wakes_message): a viewer places them along the entities' tracks
 * itself (PROTOCOL.md "WAKE"), so what the wakes cost the daemon grows
 * with the patterns the entities need, not with the viewers.
 *
 * Threads: srv_wakes_sample from any thread; the builder thread; the field
 * and the builder's queue under the module's lock, which is never held
 * while another is taken.
 * OOM: a pattern that cannot be built is logged and asked for again by
 * the next slice that needs it; create fails with OCEAN_ENOMEM.
 */
#ifndef SRV_WAKES_H
#define SRV_WAKES_H

#include <stddef.h>

#include "srv_entity.h"
#include "srv_stats.h"
#include "wake_field.h"

typedef struct srv_wakes srv_wakes;

/* For a table of at most max_entities; stats (may be NULL) counts the
 * builds. */
ocean_result srv_wakes_create(int max_entities, srv_stats *stats, srv_wakes **out);
/* Stops the builder (after the build under way) and frees everything.
 * Accepts NULL. */
void srv_wakes_destroy(srv_wakes *w);

/* The wakes of the ships of e at sim time t over water of the given depth
 * (m) at the n points xz into out.  OCEAN_ESTATE: a pattern they need is
 * being built (out untouched; ask again later); OCEAN_EINVAL: a point not
 * finite. */
ocean_result srv_wakes_sample(srv_wakes *w, srv_entities *e, double t, double depth, const double *xz, size_t n,
                              wake_sample *out);

/* Accuracy of a WAKE message's coefficients, relative to their range (the
 * qz codec's): 5e-5 m for 1 m of head on a pattern whose coefficients span
 * 0.5 m, 0.25 mm on a 5 m draught. */
#define SRV_WAKE_ACCURACY 1e-4

#define SRV_WAKES_HELD PROTO_WAKE_HELD

/* The WAKE message of pattern p (a new message sharing its encoded bytes)
 * when it is built; else NULL, and p goes to the builder [any thread]. */
struct srv_msg *srv_wakes_message(srv_wakes *w, const wake_params *p);

/* Patterns waiting for the builder or being built [any thread]. */
int srv_wakes_pending(srv_wakes *w);

struct srv_hub;
/* Puts the patterns ship d needs at its sample s, over hub h's sea, in
 * the builder's queue (h->wakes), so the queries that follow find them
 * built; takes the hub's lock briefly, never waits for a build [any
 * thread, hub.lock not held]. */
void srv_wakes_ahead(struct srv_hub *h, const ocean_entity_desc *d, const ocean_track_sample *s);

#endif
