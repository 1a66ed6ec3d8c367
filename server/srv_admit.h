/*
 * srv_admit.h - admission for the daemon as a whole: what the admitted live
 * subscriptions cost, priced from costs measured on this host, beside the
 * shared work the simulation thread measures, against the cores the host
 * gives the daemon.
 *
 * A live layout-0 subscription makes its own tiles every frame (world tiles
 * around its camera, priced at tile samples/s x planes x the measured cost
 * of one plane-sample in its codec): that price is reserved for as long as
 * it is subscribed, whether its camera moves or not.  Everything else the
 * daemon does (evaluating the ocean, layout 1's shared tiles, meshes,
 * frames, replays, queries, sending) is measured as it happens, as its CPU
 * time less the live layout-0 tiles': the "shared" load.
 * The capacity is server.admit_share of the cores the daemon can use:
 * server.workers at most, less what other processes use (/proc/stat against
 * the daemon's own getrusage, sampled once a second), half of them at least
 * (the scheduler shares the cores with the others).  A subscription whose
 * price would take the sum past the capacity is refused with an ERROR that
 * names each figure; a subscription that costs nothing of its own (layout 1,
 * whose tiles every viewer shares) is always admitted.
 *
 * Threads: the simulation thread (and srv_sim_create, before any thread
 * runs) reports what its tiles cost with srv_admit_tiles: atomics.  The
 * service thread owns the rest: it samples the rates (srv_admit_sample, from
 * its sweep timer), prices and admits subscriptions (srv_admit_take,
 * srv_admit_release) and reads the figures for /status and /metrics.
 *
 * OOM: srv_admit_create returns OCEAN_ENOMEM; nothing else allocates.
 */
#ifndef SRV_ADMIT_H
#define SRV_ADMIT_H

#include <stddef.h>

#include "ocean.h"
#include "proto.h"
#include "srv_config.h"

typedef struct srv_admit srv_admit;

/* What admission sees, for /status, /metrics and the ERROR text; cores are
 * core-seconds per second. */
typedef struct srv_admit_view {
    double capacity;        /* share x usable: what admitted work may take */
    double usable;          /* cores the daemon can use (server.workers at most) */
    double others;          /* cores other processes used (measured) */
    double shared;          /* the daemon's unpriced work (measured) */
    double priced;          /* the admitted subscriptions' prices, summed */
    int admitted;           /* subscriptions holding a price */
} srv_admit_view;

/* CPU seconds the calling thread has run (what srv_admit_tiles is told). */
double srv_admit_thread_cpu(void);

ocean_result srv_admit_create(int workers, srv_admit **out);
void srv_admit_destroy(srv_admit *a); /* accepts NULL */

/* Live layout-0 tiles of `codec` took cpu_s thread CPU seconds for
 * plane_samples samples (tile samples x planes) [any thread]. */
void srv_admit_tiles(srv_admit *a, unsigned codec, double cpu_s, double plane_samples);

/* Samples the rates since the last call, at most once a second: the
 * daemon's CPU time (getrusage) less what the live layout-0 tiles took
 * (srv_admit_tiles: the prices cover them), the host's busy cores and the
 * codecs' costs [svc]. */
void srv_admit_sample(srv_admit *a, double now);

/* The price of subscription sub (effects already those the scene computes)
 * in cores: 0 for a replay or layout 1 [svc]. */
double srv_admit_price(const srv_admit *a, const srv_config *cfg, const proto_subscribe *sub);

/* Replaces a price held (old; 0: none) by price when the total fits the
 * capacity (or price <= old, or server.admit_share is 0).  Refused:
 * OCEAN_ETOOBIG with the figures in why, the old price held [svc]. */
ocean_result srv_admit_take(srv_admit *a, const srv_config *cfg, const proto_subscribe *sub, double old,
                            double price, char *why, size_t n);
/* A price given back (the client left) [svc]. */
void srv_admit_release(srv_admit *a, double price);

void srv_admit_get_view(const srv_admit *a, const srv_config *cfg, srv_admit_view *v);

#endif
