/*
 * srv_hub.h - the shared heart of the daemon: the list of clients, the
 * settings in force, the shared clock (sim time from the epoch) and the
 * sea-state timeline (the changes pending and the sea of the latest tick).
 *
 * Threads: every member is tagged [writer / guard].  hub.lock guards the
 * list, the settings and the timeline; the service thread's own members
 * ([svc]) are never touched by another thread; stats are atomics.
 */
#ifndef SRV_HUB_H
#define SRV_HUB_H

#include <pthread.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

#include "ocean.h"
#include "proto.h"
#include "srv_admin.h"
#include "srv_config.h"
#include "srv_msg.h"
#include "srv_stats.h"

struct srv_client;
struct srv_redis;
struct srv_admit;

/* A sea-state change on the timeline: from effective_time (sim time) on,
 * the sea is params.  The hub lists the pending ones (effective_time after
 * the latest tick applied), earliest first. */
typedef struct srv_sea_change {
    double effective_time;
    ocean_params params;
    proto_sea sea;          /* params as announced */
} srv_sea_change;

/* Pending changes a hub holds at most; one more is refused (ERATE). */
#define SRV_SEA_PENDING_MAX 16


/* The shared heart of the daemon. */
typedef struct srv_hub {
    pthread_mutex_t lock;
    pthread_cond_t wake;                  /* sim waits here while idle */
    struct srv_client *clients;           /* [hub.lock] */
    int n_clients;                        /* [hub.lock] connections */
    int n_subscribed;                     /* [hub.lock] */
    int near_spacing_said;                /* [hub.lock] the layout-0 near-field note, once a run */
    unsigned record_said;                 /* [svc] recording refusals logged (once a run each):
                                             1 max_files, 2 max_bytes, 4 the file cannot be opened */
    uint32_t next_id;                     /* [hub.lock] */
    srv_settings settings;                /* [hub.lock] in force; copy before use */
    ocean_params file_params;             /* [hub.lock] the sea as the configuration last gave it
                                             (settings.params follows SEA_STATE changes too) */
    uint64_t settings_gen;                /* [hub.lock] bumps on reload */
    /* The sea-state timeline.  Every change enters it (and is announced to
     * every client that has had its HELLO) in one hold of hub.lock, and a
     * HELLO is built and queued with the pending changes in one hold too,
     * so no client misses a change whatever the moment it joins. */
    proto_sea sea_now;                    /* [hub.lock] the sea of the latest tick applied */
    double sea_effective;                 /* [hub.lock] the sim time it took effect */
    srv_sea_change sea_pending[SRV_SEA_PENDING_MAX]; /* [hub.lock] earliest first */
    int n_sea_pending;                    /* [hub.lock] */
    int sea_applying;                     /* [hub.lock] a change taken, its ocean not yet in force */
    uint64_t sea_gen;                     /* [hub.lock] bumps on every change entered */
    double sea_build_s;                   /* [hub.lock] wall seconds a sea's ocean takes to build
                                             (smoothed; the simulation thread measures) */
    int stopping;                         /* [hub.lock] */
    void (*wake_net)(void *ctx);          /* [const] wakes the service thread */
    void *wake_ctx;
    int64_t epoch_s;                      /* [const] the epoch (sim t = 0) in Unix time: */
    double epoch_frac;                    /* [const]   whole seconds + fraction [0, 1) */
    double tick_rate;                     /* [hub.lock] */
    uint64_t partial_held;                /* [svc] bytes of unfinished messages, all clients */
    srv_admin admin;                      /* [svc] the admin token's guard */
    atomic_uint_fast64_t record_files;    /* recordings opened this run */
    atomic_uint_fast64_t record_bytes;    /* bytes written to recordings this run */
    srv_stats stats;                      /* atomics */
    char fingerprint[17];                 /* [const] determinism fingerprint, 16 hex digits */
    struct srv_redis *redis;              /* [const once started] replicated timeline, or NULL */
    struct srv_admit *admit;              /* [const once started] admission (srv_admit.h) */
    struct srv_entities *entities;        /* [const] the entity table (srv_entity.h), its own lock */
    struct srv_wakes *wakes;              /* [const] their wakes in point answers (srv_wakes.h), its own lock */
    struct srv_entlog *entlog;            /* [const once started] server.entity_log, or NULL; its own lock */
} srv_hub;

/* Monotonic seconds. */
double srv_now(void);


ocean_result srv_hub_init(srv_hub *h, const srv_settings *s);
void srv_hub_fini(srv_hub *h);
/* The shared simulation clock (s): seconds of the system clock (UTC,
 * CLOCK_REALTIME) since the epoch (server.epoch), any thread.  Daemons given
 * the same epoch on synchronised machines read the same time. */
double srv_hub_sim_time(const srv_hub *h);
/* Sim time at Unix time `unix_s` (for tests and tools). */
double srv_hub_sim_time_at(const srv_hub *h, double unix_s);

/* The lead a change set here needs so that its ocean is built before it
 * falls due, off the tick path: two builds' measured time and two tick
 * periods [hub.lock held]. */
double srv_hub_sea_lead(const srv_hub *h);
/* Enters a sea-state change into the timeline and announces it to every
 * client that has had its HELLO [caller holds hub.lock].  The effective time
 * is max(requested, the clock now + lead) (a change never rewrites ticks
 * already served), moved past any pending change nearer than lead to it, so
 * each change's ocean has its build time (lead 0: the stream's times as
 * they are, for replicas); a change at the same effective time as a pending
 * one replaces it.  *eff gets the effective time entered.  OCEAN_ERATE (why
 * filled) when SRV_SEA_PENDING_MAX changes are already pending.  The caller
 * wakes the service thread after unlocking. */
ocean_result srv_hub_sea_schedule(srv_hub *h, const ocean_params *p, double requested, double lead, double *eff,
                                  char *why, size_t whylen);
/* Takes from the timeline every change due at sim time t (effective_time
 * <= t), makes the last one the current sea (sea_now, settings.params) and
 * returns 1 with it in *out, or 0 when none is due [caller holds hub.lock]. */
int srv_hub_sea_take_due(srv_hub *h, double t, srv_sea_change *out);
/* A SEA_STATE announce of sea, in force from sim time eff, sent at sim
 * time now; NULL on OOM. */
srv_msg *srv_hub_sea_announce(const proto_sea *sea, double eff, double now);
/* Queues message m (an ENTITY announce or gone) to every client that has
 * had its HELLO [caller holds hub.lock]; a client whose copy cannot be
 * made (OOM) misses it.  The caller wakes the service thread after
 * unlocking. */
void srv_hub_broadcast(srv_hub *h, const proto_msg *m);
/* Enters an entity entry into the hub's table: an ENTITY announce (a
 * track sample) or gone (a removal), in force from its header sim_time
 * (sim/entity.h), whoever fed it (an ocean.v1 set, a CIGI host, a Redis
 * entry).  Announces it to every client that has had its HELLO and asks
 * the wake builder for a ship's patterns.  The table's refusals
 * (srv_entities_sample, srv_entities_remove), with why: nothing changed,
 * nothing announced.  Takes hub.lock: the caller must not hold it. */
ocean_result srv_hub_entity_enter(srv_hub *h, const proto_msg *m, char *why, size_t n);
/* Wakes the service thread (lws_cancel_service). */
void srv_hub_wake_net(srv_hub *h);

#endif
