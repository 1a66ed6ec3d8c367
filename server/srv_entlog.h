/*
 * srv_entlog.h - the entities' timeline on disk (server.entity_log): every
 * entity entry the daemon enters, appended as the ENTITY announce or gone
 * it was announced as (its header sim_time the instant it takes effect),
 * and entered again when a daemon starts on the file.  The sea is a pure
 * function of its inputs, and these are the inputs a camera recording
 * does not hold: a daemon restarted on the log, or one started on a copy,
 * holds the timeline the recording saw, and replays its wakes.
 *
 * File: the line "oceand entity log v1\n", then one record an entry: a
 * u32 (little-endian) length and that many bytes of the message, as
 * PROTOCOL.md encodes it.  A record cut short (the daemon stopped while
 * writing it) ends the log: it is cut off before the next record goes in.
 *
 * Threads: srv_entlog_open and srv_entlog_load before the daemon serves;
 * srv_entlog_append from any thread (it takes the log's own lock; the
 * caller may hold hub.lock).
 * Entries are written through a buffer flushed at least once a second and
 * at close: a daemon that dies loses at most that second of the log.
 * OOM and write errors: an entry that cannot be written stops the log
 * (said once on stderr with the file and the reason); nothing else stops.
 */
#ifndef SRV_ENTLOG_H
#define SRV_ENTLOG_H

#include <stddef.h>

#include "ocean_result.h"
#include "proto.h"

struct srv_hub;
typedef struct srv_entlog srv_entlog;

/* Opens (or creates) the log at path.  OCEAN_EIO with why: it cannot be
 * opened, or holds something other than a log. */
ocean_result srv_entlog_open(const char *path, srv_entlog **out, char *why, size_t n);
void srv_entlog_close(srv_entlog *l); /* accepts NULL */

/* Enters every whole record of the log into the hub, in order
 * (srv_hub_entity_enter): *entered and *refused (the table's refusals, or
 * records that are no ENTITY announce or gone) count them, and a cut
 * record at the end is cut off the file.  OCEAN_EIO with why when the
 * file cannot be read or cut. */
ocean_result srv_entlog_load(srv_entlog *l, struct srv_hub *h, int *entered, int *refused, char *why, size_t n);

/* Appends entry m (an ENTITY announce or gone). */
void srv_entlog_append(srv_entlog *l, const proto_msg *m);

#endif
