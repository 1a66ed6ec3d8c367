/*
 * srv_client_sim.h - what the simulation thread keeps of each client between
 * ticks (the subscription it applied, the mesh and topology the client
 * holds, the cutoff's smoother, the frame schedule, the samples in time it
 * holds), and the table of them the simulation thread owns.
 *
 * Threads: the simulation thread only.  It copies a client's subscription
 * and camera from the client's requests under hub.lock (srv_client.h) and
 * keeps everything else here, where no other thread looks; the planner and
 * the frame builders get a client's entry with its job.
 */
#ifndef SRV_CLIENT_SIM_H
#define SRV_CLIENT_SIM_H

#include <stdint.h>

#include "filter.h"
#include "mesh.h"
#include "proto.h"
#include "srv_client.h"
#include "srv_held.h"
#include "srv_stats.h"
#include "wake_pattern.h"

/* What the simulation thread keeps of one client. */
enum {
    SRV_HELD_AFTER,  /* after the last frame handed over (replay: built in place) */
    SRV_HELD_KNOWN,  /* what the client holds for sure */
    SRV_HELD_NEXT,   /* the live frame being built */
    SRV_HELD_SCRATCH
};

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
    double replay_deficit;       /* replay: seconds of replay work banked (srv_sim.c replay_turn) */
    int mesh_over;               /* the camera's mesh is over server.max_mesh_vertices */
    int mesh_coarsen;            /* cs->mesh is built at mesh_cfg.error_px << this
                                    (srv_client_mesh_fit) */
    uint32_t *qz_refs;           /* mesh_codec qz: the prediction references
                                    (proto_mesh_qz_refs) of topology qz_refs_key,
                                    3 per vertex, made once per topology */
    uint64_t qz_refs_key;
    uint32_t qz_refs_n;          /* vertices qz_refs holds (0: none) */
    /* PROTO_SUB_TIME_INTERP: models of what the client holds (srv_held.h),
     * made from cascade tables held_gen, tile side held_tile, in replay
     * (held_replay 1) or live mode.  A live frame waits in the outbox's
     * latest-wins slot until the service thread takes it, and the next
     * frame replaces it if it is still there: while held_pending, the
     * last frame published may be either, and the client holds
     * held[SRV_HELD_AFTER] (it was taken) or held[SRV_HELD_KNOWN] (it
     * was replaced); the next frame is built on what both hold
     * (srv_cascade.c held_begin) in held[SRV_HELD_NEXT]. */
    srv_held *held[4];
    int held_pending;
    uint64_t held_gen;
    int held_tile, held_replay;
    /* layout 1: the WAKE patterns the client holds, the last
     * PROTO_WAKE_HELD sent, oldest first (PROTOCOL.md "WAKE") */
    wake_params wakes[PROTO_WAKE_HELD];
    int n_wakes;
} srv_client_sim;


/* The simulation thread's entries, one a client in the hub's list, found by
 * the client's id. */
typedef struct srv_client_table srv_client_table;

ocean_result srv_client_table_create(srv_client_table **out);
/* Drops every entry (and its client reference).  Accepts NULL. */
void srv_client_table_destroy(srv_client_table *t);
/* The entry of client c, made (holding a reference to c) when c has none;
 * NULL on OOM. */
srv_client_sim *srv_client_table_get(srv_client_table *t, srv_client *c);
/* Drops the entries of clients that have left the hub [hub.lock held: it
 * reads each client's closed flag]. */
void srv_client_table_sweep(srv_client_table *t);
/* Every entry re-applies its subscription before its next frame (the sea
 * changed: meshes follow the new dominant wavelength). */
void srv_client_table_reapply(srv_client_table *t);

/* The MESH_TOPOLOGY of mesh view v for the client whose entry is cs (a new
 * mesh_id, remembered as the topology the client has; flat/zones: the FLAT
 * arrays of layout 1, or NULL).  NULL on OOM (the client is then sent the
 * topology again next time). */
srv_msg *srv_client_sim_topology(srv_client_sim *cs, const mesh_view *v, double t, const float *flat,
                                 const float *zones);
/* Fits client c's mesh (cs->mesh) to the server's vertex limit for camera
 * mc, priced before anything is built: at the subscription's error budget
 * when it fits, else at the least power-of-two multiple of it, up to the
 * mesh's largest budget, that does (a camera near steep chop asks for more
 * vertices than its budget alone would), rebuilding cs->mesh when the
 * multiple changes, with one ERROR ETOOBIG to c naming both budgets.
 * Returns 1 when cs->mesh may be built for mc; 0 when no budget fits (the
 * frame goes without a mesh, with one ERROR ETOOBIG naming the limit) or
 * the mesh could not be made.  Viewers that share a leader's mesh (same
 * camera and subscription) take the leader's budget. */
int srv_client_sim_mesh_fit(srv_client_sim *cs, srv_client *c, const mesh_camera *mc, int max_vertices,
                            uint32_t cam_seq, srv_stats *st);

#endif
