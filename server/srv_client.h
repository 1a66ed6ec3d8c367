/*
 * srv_client.h - per-client state, the hub that lists the clients, and the
 * hand-over of bytes between the simulation thread and the libwebsockets
 * service thread.
 *
 * Threads and locks:
 *   svc  the libwebsockets service thread: owns every connection, receives
 *        and decodes client messages, sends queued bytes.
 *   sim  the simulation thread: evaluates the ocean, builds frames.
 *   main the thread that started the daemon (signals, reload).
 * Every shared member below is tagged [owner / guard].  hub.lock guards the
 * client list and each client's "requests" (subscription, camera, queued
 * queries and replay cameras); client.out_lock guards the client's outgoing
 * bytes (control queue and the latest-frame slot).  Lock order: hub.lock
 * before out_lock; nothing else is held while taking either.
 *
 * Lifetime: a client is reference counted.  The hub list holds one
 * reference from LWS_CALLBACK_ESTABLISHED until LWS_CALLBACK_CLOSED; the
 * simulation thread holds one while it builds a frame, so a client that
 * disconnects mid-frame is freed when the frame is done, never under it.
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
#include "srv_link.h"
#include "srv_stats.h"

struct lws;
struct srv_record;

/* Encoded bytes that several queued messages share: one FRAME encoding for
 * every viewer whose frame differs only in its per-client fields (co-located
 * viewers).  Immutable once shared, except that the service thread - the
 * only thread that sends - writes the per-client fields of the message it is
 * about to send just before lws_write (which hands every byte to the kernel
 * or copies what it could not send before returning). */
typedef struct srv_blob {
    atomic_int refs;
    proto_buf buf;      /* LWS_PRE headroom */
} srv_blob;

/* Offset of camera_seq in an encoded FRAME, as proto_frame_client_fields
 * reports it (checked for every shared frame before it is shared). */
#define SRV_FRAME_CAMERA_SEQ_AT (PROTO_HEADER_SIZE + 40)

/* One queued outgoing message: its own bytes (buf, with LWS_PRE headroom)
 * or a reference to shared ones (blob) with the per-client FRAME fields to
 * write into them when sending. */
typedef struct srv_msg {
    struct srv_msg *next;
    proto_buf buf;
    srv_blob *blob;     /* shared bytes, or NULL: buf */
    uint32_t camera_seq;/* blob FRAMEs: this client's camera_seq ... */
    uint32_t mesh_id;   /*   ... and mesh id, */
    uint32_t mesh_id_at;/*   at this byte offset (0: no mesh) */
    double tick_wall;   /* monotonic time of the tick that made it (0: none) */
    int is_frame;       /* counts as a frame for statistics */
    int live;           /* a live FRAME from the latest-wins slot (srv_link counts it) */
    int close_after;    /* close the connection once this is sent (BYE) */
} srv_msg;

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

/* What the simulation thread keeps per client between ticks [sim only]. */
typedef struct srv_client_sim {
    uint64_t sub_gen;            /* subscription generation last applied */
    proto_subscribe sub;
    mesh *mesh;
    mesh_config mesh_cfg;
    uint64_t topo_key;
    uint32_t mesh_id;
    int topo_valid;
    ocean_filter_smoother smoother;
    double last_t;               /* sim time of the last frame (smoother dt) */
    double next_frame_t;         /* live: when the next frame is due */
    double last_frame_t;         /* live: sim time of the last frame scheduled */
    int framed;                  /* a live frame has been scheduled (last_frame_t holds) */
    int primed;
    double cutoff_k;             /* smoothed cutoff of the last frame */
    int mesh_over;               /* the camera's mesh is over server.max_mesh_vertices */
    int mesh_coarsen;            /* cs->mesh is built at mesh_cfg.error_px << this
                                    (srv_client_mesh_fit) */
    uint32_t *qz_refs;           /* mesh_codec qz: the prediction references
                                    (proto_mesh_qz_refs) of topology qz_refs_key,
                                    3 per vertex, made once per topology */
    uint64_t qz_refs_key;
    uint32_t qz_refs_n;          /* vertices qz_refs holds (0: none) */
    /* PROTO_SUB_TIME_INTERP: what the client holds ([0]) and held before
     * its last frame ([1]), made from cascade tables held_gen, tile side
     * held_tile, in replay (held_replay 1) or live mode */
    srv_held *held[2];
    uint64_t held_gen;
    int held_tile, held_replay;
} srv_client_sim;

typedef struct srv_client {
    atomic_int refs;
    uint32_t id;                          /* [const] */
    struct lws *wsi;                      /* [svc] NULL once closed */
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

    /* ---- outgoing: [sim + svc / out_lock] ---- */
    pthread_mutex_t out_lock;
    srv_msg *ctrl, *ctrl_tail;            /* FIFO: HELLO, ERROR, results, replay frames */
    srv_msg *slot_topo;                   /* latest-wins frame slot: optional */
    srv_msg *slot_frame;                  /*   MESH_TOPOLOGY, then FRAME */
    uint64_t queued_bytes;                /* ctrl + slot, at allocated size (srv_msg_cost) */
    atomic_uint_fast64_t output_hard;     /* server.output_hard, as the service thread last saw it */
    atomic_int want_write;                /* svc should ask for WRITEABLE */
    atomic_int over_hard;                 /* a message was refused: over output_hard */

    /* ---- what the client costs, for /metrics [atomics, any thread] ---- */
    atomic_uint_fast64_t cpu_ns;          /* simulation-thread time spent on its requests */
    atomic_uint_fast64_t bytes_out;       /* bytes sent to it */
    atomic_uint_fast64_t link_bps;        /* [svc writes] the byte rate its link carries, for
                                             the planner (srv_link_bps); 0: the ceiling */

    /* ---- service thread only [svc] ---- */
    uint8_t *rx;                          /* message being reassembled */
    size_t rx_len, rx_cap;
    int rx_discard;                       /* dropping an oversized message */
    size_t rx_discarded;
    double bucket;                        /* message-rate tokens */
    double bucket_t;                      /* monotonic time of last refill */
    double rate_err_t;                    /* last ERATE ERROR sent; one per second */
    double text_err_t;                    /* last text-frame ERROR sent; one per second */
    uint64_t rate_refused;                /* messages refused since that ERROR */
    double rx_started;                    /* monotonic time the unfinished message began */
    double last_rx;                       /* monotonic time of the connection or of its last
                                             message's first bytes (server.idle_seconds) */
    double rx_tokens, rx_tokens_t;        /* read budget (server.read_rate), bytes; refill time */
    int rx_paused;                        /* reading paused until the budget refills */
    size_t rx_held;                       /* rx_cap counted in the hub's partial total */
    double sub_tokens, sub_tokens_t;      /* changed SUBSCRIBEs allowed (SRV_SUBSCRIBE_*); refill time */
    srv_link link;                        /* live frames in flight and what the link carries */
    int admin_misses;                     /* wrong admin tokens in a row */
    double admin_until;                   /* SEA_STATE set refused until then (monotonic) */
    char peer[SRV_ADMIN_ADDR_MAX];        /* the client's address (srv_admin's key) */
    uint32_t tx_seq;                      /* header seq of the next message */
    uint64_t inflight;                    /* bytes lws still holds of the last write */
    double over_soft_since;               /* monotonic; 0: under the soft limit */
    double last_progress;                 /* monotonic time of the last completed send */
    double pending_since;                 /* monotonic time output began waiting; 0: none */
    int closing;                          /* 1 BYE queued; 2 client said BYE; 3 cut by a
                                             limit (kill_code, kill_why); 4 BYE sent */
    uint16_t kill_code;                   /* closing 3: the close frame's code */
    char kill_why[124];                   /* and its reason (a close payload <= 125) */
    struct srv_record *rec;

    /* ---- simulation thread only ---- */
    srv_client_sim sim;                   /* [sim] */
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
ocean_result srv_client_create(srv_hub *h, struct lws *wsi, srv_client **out);
void srv_client_ref(srv_client *c);
/* Drops one reference; the last frees the client.  Accepts NULL. */
void srv_client_unref(srv_client *c);
/* Removes c from the hub list and drops the list's reference [svc]. */
void srv_client_remove(srv_client *c);

/* Queues a finished message (takes ownership of m) [any thread]. */
void srv_client_queue(srv_client *c, srv_msg *m);
/* Puts a frame (and optionally a topology message to send first) into the
 * latest-wins slot, freeing an unsent older frame (counted as skipped).
 * An unsent older topology is kept when topo is NULL [sim]. */
void srv_client_publish(srv_client *c, srv_msg *topo, srv_msg *frame);
/* Takes the next message to send (control first), or NULL [svc]. */
srv_msg *srv_client_take(srv_client *c);
uint64_t srv_client_queued(srv_client *c);
/* Whether the next message to send is a live frame (or its topology) from
 * the latest-wins slots, nothing from the control FIFO before it. */
int srv_client_next_is_live(srv_client *c);
/* Whether a live frame waits unsent in the latest-wins slot (the next one
 * published replaces it) [any thread]. */
int srv_client_frame_waiting(srv_client *c);

srv_msg *srv_msg_new(void);
/* A new message holding m's encoding, or NULL on OOM or a message the
 * encoder refuses (logged: the daemon built it, so that is a bug). */
srv_msg *srv_msg_encode(const proto_msg *m);
/* The MESH_TOPOLOGY of mesh view v for a client whose per-client topology
 * state is cs (a new mesh_id, remembered as the topology the client has;
 * flat/zones: the FLAT arrays of layout 1, or NULL).  NULL on OOM (the
 * client is then sent the topology again next time) [sim side]. */
srv_msg *srv_topology_encode(srv_client_sim *cs, const mesh_view *v, double t, const float *flat,
                             const float *zones);
/* Hands a built frame (and the topology to send first, may be NULL) to its
 * client: queued in order for replay, into the latest-wins slot live.
 * frame NULL frees topo.  Takes ownership of both [sim side]. */
void srv_client_hand_over(srv_client *c, srv_stats *st, srv_msg *topo, srv_msg *frame, int replay,
                          double tick_wall);
void srv_msg_free(srv_msg *m);
/* Moves m's own bytes into a new blob of one reference (m then refers to
 * it).  OCEAN_ENOMEM leaves m as it was. */
ocean_result srv_msg_make_shared(srv_msg *m);
/* A new message referring to m's blob (one more reference), with m's
 * per-client fields and flags.  NULL on OOM or if m has no blob. */
srv_msg *srv_msg_share(const srv_msg *m);
/* The message's wire bytes, per-client FRAME fields written in for a blob
 * [service thread only: the bytes may be shared]. */
uint8_t *srv_msg_wire(srv_msg *m, size_t *len);
/* Length of the wire bytes. */
size_t srv_msg_len(const srv_msg *m);
/* What a queued message holds in memory: its allocations (the message, its
 * buffer's headroom and capacity, or the shared blob) plus the allocator's
 * per-block overhead.  The output limits count this, not the wire length:
 * a 110-byte ERROR holds about 400 bytes. */
size_t srv_msg_cost(const srv_msg *m);

/* Builds and queues messages the service thread sends [svc]. */
/* Fits the client's mesh to the server's vertex limit for camera mc, priced
 * before anything is built [the worker that owns the client]: at the
 * subscription's error budget when it fits, else at the least power-of-two
 * multiple of it, up to the mesh's largest budget, that does (a camera
 * near steep chop asks for more vertices than its budget alone would),
 * rebuilding c->sim.mesh when the multiple changes, with one ERROR ETOOBIG
 * naming both budgets.  Returns 1 when c->sim.mesh may be built for mc; 0
 * when no budget fits (the frame goes without a mesh, with one ERROR
 * ETOOBIG naming the limit) or the mesh could not be made.  Viewers that
 * share a leader's mesh (same camera and subscription) take the leader's
 * budget. */
int srv_client_mesh_fit(srv_client *c, const mesh_camera *mc, int max_vertices, uint32_t cam_seq,
                        srv_stats *st);

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
