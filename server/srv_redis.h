/*
 * srv_redis.h - the sea-state timeline shared by replicas through a Redis
 * stream (server.redis).
 *
 * Every replica of one exercise holds the stream's whole timeline, applied
 * in stream order, whenever it started: each entry is one change (a
 * SEA_STATE announce: effective time and sea).  An entry takes effect at
 * max(its effective time, the time Redis stored it), the time every replica
 * reading it as it came would have entered it; the sea at any time is the
 * change with the latest such time, a later entry winning a tie.  A replica
 * that starts late folds every entry already in force into its current sea
 * and keeps the rest pending, as a replica running all along holds it.
 *
 * Entities' entries (sim/entity.h) travel the same stream: an ENTITY
 * announce (a track sample) or gone (a removal), its header sim_time the
 * instant it is asked to take effect, at least server.sea_lead ahead.
 * Every replica enters it into its table, in stream order, in force from
 * max(that instant, the time Redis stored it), so all hold the same
 * tracks and agree at every instant; the table's refusals (a teleport,
 * time order, a full table) fall alike on every replica.
 *
 * A SEA_STATE set on any replica is appended to the stream, never entered
 * directly: its announce comes back through the stream like every other
 * replica's, and that announce is the setter's reply; a set the stream
 * cannot take, or every replica skips, is answered with an ERROR.  A set
 * must be at least server.sea_lead seconds ahead, so the entry reaches every
 * replica before it takes effect.
 *
 * Threads: the replication thread owns the Redis connection and does every
 * round trip; the service thread only queues sets (srv_redis_submit) and
 * never waits for Redis.  Entries are read in bounded batches (at most
 * SRV_REDIS_BATCH entries of at most SRV_REDIS_ENTRY_MAX bytes each), their
 * size and shape checked inside Redis before any byte reaches the daemon.
 */
#ifndef SRV_REDIS_H
#define SRV_REDIS_H

#include "srv_client.h"

#define SRV_REDIS_ENTRY_MAX 4096   /* bytes of an entry's msg field; a SEA_STATE announce is < 200 */
#define SRV_REDIS_BATCH 256        /* entries per read: a read holds at most 1 MiB of entries */
#define SRV_REDIS_QUEUE_MAX 16     /* sets waiting for the replication thread; one more: ERATE */
#define SRV_REDIS_FUTURE_S 60.0    /* an entry id further ahead of the clock is far-future */

typedef struct srv_redis srv_redis;

/* Connects to s->srv.redis ("host:port"), folds the stream's whole timeline
 * into the hub (before any client can connect) and starts the replication
 * thread.  OCEAN_EIO with msg when Redis cannot be reached. */
ocean_result srv_redis_start(srv_hub *h, const srv_settings *s, srv_redis **out, char *msg, size_t msglen);
/* Stops the replication thread, answers the sets still waiting (EIO) and
 * disconnects.  Accepts NULL. */
void srv_redis_stop(srv_redis *r);
/* Queues client c's SEA_STATE set (its message bytes bad/badlen, for the
 * ERROR that may answer it) for the stream [svc].  OCEAN_OK: queued, and
 * answered later (the announce, or an ERROR).  Refused at once, why filled:
 * OCEAN_EINVAL when effective_time is less than server.sea_lead ahead of
 * the clock, OCEAN_ERATE when SRV_SEA_PENDING_MAX changes are pending or
 * SRV_REDIS_QUEUE_MAX sets wait already. */
ocean_result srv_redis_submit(srv_redis *r, srv_client *c, const void *bad, size_t badlen, const proto_sea *sea,
                              double effective_time, char *why, size_t whylen);

/* Queues an entity entry m (an ENTITY announce or gone) for the stream
 * [any thread], to take effect at its header sim_time, moved to the clock
 * plus server.sea_lead when that is later (m->hdr.sim_time gets the
 * instant asked for); c (NULL: nobody to answer, as for a CIGI host) gets
 * the announce coming back, or an ERROR (its message bytes bad/badlen)
 * saying `what` was refused.  Refused at once, why filled: OCEAN_ERATE
 * when SRV_REDIS_QUEUE_MAX entries wait already, OCEAN_ENOMEM. */
ocean_result srv_redis_submit_entity(srv_redis *r, srv_client *c, const void *bad, size_t badlen, proto_msg *m,
                                     const char *what, char *why, size_t whylen);

#endif
