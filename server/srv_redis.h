/*
 * srv_redis.h - the sea-state timeline shared by replicas through a Redis
 * stream (server.redis).
 *
 * Every replica of one exercise reads the same stream from its start; each
 * entry is one change (a SEA_STATE announce message: effective time and
 * sea), entered into the hub's timeline (srv_hub_sea_schedule) when read, so
 * every replica - and through it every client - holds the same timeline.
 * A SEA_STATE set on any replica is appended to the stream (XADD), never
 * entered directly: its announce comes back through the stream like every
 * other replica's.  A set must be at least server.sea_lead seconds ahead, so
 * the entry reaches every replica before it takes effect.
 */
#ifndef SRV_REDIS_H
#define SRV_REDIS_H

#include "srv_client.h"

typedef struct srv_redis srv_redis;

/* Connects to s->srv.redis ("host:port"), reads the stream up to now into
 * the hub's timeline and starts the reader thread.  OCEAN_EIO with msg when
 * Redis cannot be reached. */
ocean_result srv_redis_start(srv_hub *h, const srv_settings *s, srv_redis **out, char *msg, size_t msglen);
/* Stops the reader and disconnects.  Accepts NULL. */
void srv_redis_stop(srv_redis *r);
/* Appends a change to the stream [svc].  OCEAN_EINVAL when effective_time
 * is less than server.sea_lead ahead of the clock, OCEAN_EIO when Redis
 * does not take it; why says so. */
ocean_result srv_redis_publish(srv_redis *r, const proto_sea *sea, double effective_time, char *why,
                               size_t whylen);

#endif
