/*
 * srv_cigi.h - the CIGI service: simulator hosts ask oceand, as they ask
 * an image generator, for the water under their points (HAT/HOT), over
 * UDP (server.cigi_port, protocol/CIGI.md).
 *
 * Each host message (a datagram from an address in server.cigi_hosts,
 * opening with IG Control) is answered to its sender, in its version and
 * byte order, with a Start of Frame and one HAT/HOT Response or Extended
 * Response per request, in the order asked.  Geodetic points map onto the
 * ocean's plane through sim/geo.h about server.geo_origin; the points of
 * the messages waiting become one query of the service's own client of the
 * hub (one in flight at a time: a 60 Hz host on 30 Hz ticks has two
 * messages answered a tick), so they are answered as a WebSocket QUERY is
 * (the simulation thread's query work, srv_work.h: the choppy displacement
 * inverted, the near field included, at the sim time of the tick that
 * takes them), and a point
 * whose answer has no error bound (a fold) is answered Valid = 0.  The
 * Start of Frame's timestamp is that sim time in 10 us ticks (mod 2^32),
 * so every answer can be checked against `ocean-sim query --time`.
 * The host's surface wind (Atmosphere Control, or a global Weather
 * Control layer that holds 10 m) sets the sea's wind through the timeline,
 * as an admin's SEA_STATE set does (replicated through Redis when the
 * daemon is): a host that sends its wind every frame changes the sea only
 * when the wind changes, at most SRV_CIGI_SEA_PER_S times a second (the
 * latest wind wins), each change logged with the host's address.
 * The host's entities (Entity Control; Entity Position in 4.0) enter the
 * daemon's entity table (srv_entity.h) at the sim clock, and
 * entity-relative requests are answered at the point their offsets name
 * from the entity's position and heading (Valid = 0 for an entity the
 * table does not hold).  An Environmental Conditions Request's maritime
 * part is answered with a Maritime Surface Conditions Response: the sea's
 * mean level (0: no offset) and the water temperature and clarity a global
 * Maritime Surface Conditions Control last set.  A level offset, whitecaps
 * off and Wave Control are counted (oceand_cigi_ignored_total) and not
 * applied yet.  Drops are counted by reason in /metrics.
 *
 * Threads: the service's own thread owns its socket, its geo plane and
 * the messages it is answering; it reaches the simulation thread only
 * through its client's inbox (under hub.lock) and hears back through the
 * client's outbox, which wakes it (an eventfd).  srv_cigi_start and
 * srv_cigi_stop run on the thread that starts and stops the daemon.
 */
#ifndef SRV_CIGI_H
#define SRV_CIGI_H

#include "srv_hub.h"

typedef struct srv_cigi srv_cigi;

/* Host messages the service answers at once; one more while they wait is
 * dropped (oceand_cigi_dropped_busy_total). */
#define SRV_CIGI_PENDING 8
/* Requests one message may ask; the rest are dropped (busy). */
#define SRV_CIGI_REQUESTS 256
#define SRV_CIGI_ENV_REQUESTS 16
/* Messages the simulation thread has not answered in this long are
 * answered Valid = 0 (the daemon stopping). */
#define SRV_CIGI_PATIENCE 2.0
/* Sea changes a host's wind makes at most, a second. */
#define SRV_CIGI_SEA_PER_S 4.0

/* Binds server.cigi_port on server.bind and starts the thread (nothing
 * when the port is 0: *out NULL).  OCEAN_EINVAL / OCEAN_EIO with msg. */
ocean_result srv_cigi_start(srv_hub *h, srv_cigi **out, char *msg, size_t msglen);
/* Stops the thread and frees everything.  Accepts NULL. */
void srv_cigi_stop(srv_cigi *s);

#endif
