/*
 * srv_client.h - the part of a client that threads share: its requests
 * (subscription, camera, queued queries and replay cameras) from the
 * service thread to the simulation thread, and its outgoing messages back;
 * the hub that lists the clients and holds the sea-state timeline.
 *
 * Threads and locks:
 *   svc  the libwebsockets service thread: owns every connection (its
 *        per-connection state is srv_session.h), receives and decodes
 *        client messages, sends queued bytes.
 *   sim  the simulation thread: evaluates the ocean, builds frames; what it
 *        keeps per client is its own table (srv_client_sim.h).
 *   main the thread that started the daemon (signals, reload).
 * Every shared member below is tagged [writer / guard].  A client's fields
 * are written by the service thread only, except the two hand-overs: the
 * request queues (queries, replay cameras), which the service thread fills
 * and the simulation thread empties, under hub.lock; and the outgoing
 * queue, which the simulation thread fills and the service thread empties,
 * under out_lock.  Lock order: hub.lock before out_lock; nothing else is
 * held while taking either.
 *
 * Lifetime: a client is reference counted.  The hub list and the service
 * thread's session each hold one from LWS_CALLBACK_ESTABLISHED until
 * LWS_CALLBACK_CLOSED; the simulation thread's table holds one until it
 * sees the client closed, and a batch one while it builds a frame, so a
 * client that disconnects mid-frame is freed when the frame is done, never
 * under it.
 */
#ifndef SRV_CLIENT_H
#define SRV_CLIENT_H

#include <pthread.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

#include "filter.h"
#include "mesh.h"
#include "proto.h"
#include "srv_admin.h"
#include "srv_config.h"
#include "srv_held.h"
#include "srv_msg.h"
#include "srv_outbox.h"
#include "srv_stats.h"

struct lws;
struct srv_record;

/* A pending QUERY, decoded. */
typedef struct srv_query {
    struct srv_query *next;
    uint32_t query_id, seq;
    int at_time;
    double t;
    uint32_t count;
    double *points;     /* 2 * count */
} srv_query;

/* A replay-mode CAMERA waiting for its frame. */
typedef struct srv_replay_cam {
    struct srv_replay_cam *next;
    proto_camera cam;
    uint32_t seq;
} srv_replay_cam;

typedef struct srv_client {
    atomic_int refs;
    uint32_t id;                          /* [const] */
    struct srv_hub *hub;                  /* [const] */

    /* ---- requests: [svc writes / hub.lock] ---- */
    int subscribed;
    uint64_t sub_gen;                     /* bumps on every SUBSCRIBE */
    proto_subscribe sub;
    int has_camera;
    proto_camera cam;
    uint32_t cam_seq;
    srv_query *queries;                   /* FIFO */
    int n_queries;
    int n_queries_active;                 /* taken by the simulation thread, unanswered */
    srv_replay_cam *replay, *replay_tail; /* FIFO */
    int n_replay;
    int closed;                           /* connection gone; sim skips it */
    int hello_sent;                       /* HELLO queued: sea changes are announced to it */
    struct srv_client *next;              /* hub list */

    srv_outbox *out;                      /* [const] its outgoing messages (own lock) */

    /* ---- what the client costs, for /metrics [atomics, any thread] ---- */
    atomic_uint_fast64_t cpu_ns;          /* simulation-thread time spent on its requests */
    atomic_uint_fast64_t bytes_out;       /* bytes sent to it */
    atomic_uint_fast64_t link_bps;        /* [svc writes] the byte rate its link carries, for
                                             the planner (srv_link_bps); 0: the ceiling */

} srv_client;

/* A sea-state change on the timeline: from effective_time (sim time) on,
 * the sea is params.  The hub lists the pending ones (effective_time after
 * the latest tick applied), earliest first. */
typedef struct srv_sea_change {
    double effective_time;
    ocean_params params;
    proto_sea sea;          /* params as announced */
} srv_sea_change;

/* A SUBSCRIBE that changes the subscription rebuilds the client's mesh and
 * topology and restarts its stream: at most SRV_SUBSCRIBE_PER_S a second
 * after a burst of SRV_SUBSCRIBE_BURST; one more is refused (ERATE) and the
 * subscription in force stays.  A SUBSCRIBE equal to the one in force
 * changes nothing and sends nothing. */
#define SRV_SUBSCRIBE_PER_S 2.0
#define SRV_SUBSCRIBE_BURST 4.0

/* Pending changes a hub holds at most; one more is refused (ERATE). */
#define SRV_SEA_PENDING_MAX 16


/* The shared heart of the daemon. */
typedef struct srv_hub {
    pthread_mutex_t lock;
    pthread_cond_t wake;                  /* sim waits here while idle */
    srv_client *clients;                  /* [hub.lock] */
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
    uint64_t sea_gen;                     /* [hub.lock] bumps on every change entered */
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
} srv_hub;

/* The determinism fingerprint (16 hex digits + NUL into out): FNV-1a 64 of
 * everything besides the sea timeline that decides a FRAME's bytes: the
 * compiler, the CPU features that pick code paths (target_clones' avx2;
 * FFTW's SIMD: avx, avx2, fma, avx512f), the FFTW version, plan mode and
 * threads, and the configuration that shapes frames.  Announced in HELLO's
 * server_version (PROTOCOL.md "HELLO"). */
void srv_fingerprint(const srv_settings *s, char out[17]);

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

/* Enters a sea-state change into the timeline and announces it to every
 * client that has had its HELLO [caller holds hub.lock].  The effective time
 * is max(requested, the clock now) (a change never rewrites ticks already
 * served); a change at the same effective time as a pending one replaces it.
 * *eff gets the effective time entered.  OCEAN_ERATE (why filled) when
 * SRV_SEA_PENDING_MAX changes are already pending.  The caller wakes the
 * service thread after unlocking. */
ocean_result srv_hub_sea_schedule(srv_hub *h, const ocean_params *p, double requested, double *eff,
                                  char *why, size_t whylen);
/* Takes from the timeline every change due at sim time t (effective_time
 * <= t), makes the last one the current sea (sea_now, settings.params) and
 * returns 1 with it in *out, or 0 when none is due [caller holds hub.lock]. */
int srv_hub_sea_take_due(srv_hub *h, double t, srv_sea_change *out);
/* Wakes the service thread (lws_cancel_service). */
void srv_hub_wake_net(srv_hub *h);

/* Creates a client (refs = 1, the list's), adds it to the hub. */
ocean_result srv_client_create(srv_hub *h, srv_client **out);
void srv_client_ref(srv_client *c);
/* Drops one reference; the last frees the client.  Accepts NULL. */
void srv_client_unref(srv_client *c);
/* Removes c from the hub list and drops the list's reference [svc]. */
void srv_client_remove(srv_client *c);

/* Queues a finished message (takes ownership of m) [any thread]; the first
 * message refused over server.output_hard wakes the service thread, which
 * cuts the client. */
void srv_client_queue(srv_client *c, srv_msg *m);
/* Hands a built frame (and the topology to send first, may be NULL) to its
 * client: queued in order for replay, into the latest-wins slot live.
 * frame NULL frees topo.  Takes ownership of both [sim side]. */
void srv_client_hand_over(srv_client *c, srv_stats *st, srv_msg *topo, srv_msg *frame, int replay,
                          double tick_wall);
void srv_client_send_error(srv_client *c, const void *bad, size_t badlen, ocean_result code,
                           const char *why);
void srv_client_send_bye(srv_client *c, int reason, const char *why);
/* Queues HELLO and, right behind it, a SEA_STATE announce for every pending
 * change (one hold of hub.lock: no change can fall between them). */
void srv_client_send_hello(srv_client *c);
/* Answers SEA_STATE get: an announce of the current sea (effective_time: when
 * it took effect), then one per pending change, earliest first. */
void srv_client_send_sea_timeline(srv_client *c);

/* Drops the replay cameras c sent and the server has not answered
 * [hub.lock held]. */
void srv_client_drop_replay(srv_client *c);

/* Conversions shared by the daemon's modules. */
void srv_sea_from_params(const ocean_params *p, proto_sea *out);
void srv_params_from_sea(const proto_sea *s, const ocean_params *base, ocean_params *out);
void srv_mesh_camera(const proto_camera *pc, mesh_camera *out);

#endif
