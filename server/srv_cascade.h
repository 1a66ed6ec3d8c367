/*
 * srv_cascade.h - the cascade tile layout (PROTOCOL.md "Layouts", layout 1):
 * what the daemon makes once per tick and every camera shares.
 *
 * Each cascade is periodic on its own patch, so its tiles are the same for
 * every viewer anywhere.  Per tick this module evaluates the mip pyramid of
 * every cascade some live subscriber needs (one ocean evaluation per mip
 * level, all cascades at once, each at its own cutoff), cuts the mips into
 * tiles, encodes each tile once into a ready FRAME record, and then only
 * assembles per camera: the cascade block (mip tables, camera), the list of
 * records the camera's footprint needs, and the mesh placement.  A camera
 * therefore costs a copy of bytes, not a sampling and encoding pass; the
 * encoding cost is bounded by the union of what all cameras need.
 *
 * Threads: used by the simulation thread only; tile encoding runs on
 * server.workers OpenMP threads inside srv_cascade_run.
 */
#ifndef SRV_CASCADE_H
#define SRV_CASCADE_H

#include <stdint.h>

#include "ocean.h"
#include "proto.h"
#include "srv_client_sim.h"
#include "srv_config.h"

typedef struct srv_cascade srv_cascade;

/* The longest update interval of a mip's samples, ticks (PROTOCOL.md
 * "Samples in time"): 2.1 s at 30 Hz, within the shortest period a coarse
 * mip holds at the ship-bridge scene, so no wave is aliased in time. */
#define SRV_CASCADE_MAX_INTERVAL 64

/* The held samples one frame of a time-interpolating client may carry,
 * in frame budgets (server.viewer_bytes_per_s, or the link's rate, over
 * the frame rate): the plan prices each held mip at its share per frame,
 * and this bounds what a KEY frame, or one replacing an unsent frame,
 * carries at once.  Twice the budget lets the staggered windows of a
 * steady stream through whole and spreads a KEY frame over about three. */
#define SRV_CASCADE_BURST 2.0
/* The A samples (what makes the client's sea whole) one frame may carry,
 * in frame budgets: a KEY frame's, or a fast camera's tiles coming into
 * view, go whole unless the burst is larger than this. */
#define SRV_CASCADE_BURST_A 4.0

/* Seed 000's energy guard: at most this fraction of the sea's height
 * variance may be missing from what a client gets (e_total). */
#define SRV_CASCADE_E_GUARD 0.05

/* The finest spacing per metre of distance a plan starts from: a 720-px
 * view 0.002 deg wide.  Any real optic asks for more (a 5 deg binocular
 * view: 2.9e-3); a degenerate field of view (the smallest float, 1e-45 deg)
 * would ask for 1e-37, every tile of every mip, 6.6 times the budget. */
#define SRV_CASCADE_Q_MIN 1e-6

/* One layout-1 frame to build. */
typedef struct srv_cascade_job {
    srv_client *c;         /* holds a reference for the batch: errors and the hand-over */
    srv_client_sim *cs;    /* the client's entry in the simulation thread's table: its
                              subscription, mesh and samples in time */
    double t;              /* sim time of the frame */
    proto_camera cam;
    uint32_t cam_seq;
    uint32_t tick;
    double tick_pos;       /* the frame's time in ticks, t * tick_rate (live: the
                              tick number exactly) */
    int replay;            /* 1: replay frame (queued in order), 0: live */
    double policy_k;       /* the velocity policy's cutoff, rad/m (INFINITY: none) */
    srv_msg *topo, *frame; /* out: MESH_TOPOLOGY (when new) and FRAME */
} srv_cascade_job;

ocean_result srv_cascade_create(srv_cascade **out);
/* Accepts NULL. */
void srv_cascade_destroy(srv_cascade *k);
/* Forgets everything made from the current ocean (the sea changed). */
void srv_cascade_reset(srv_cascade *k);


/* Tiles a layout-1 subscription with tile side `tile_size` may need in one
 * FRAME at most (every tile of every mip of every cascade): the
 * subscription check refuses what would exceed PROTO_MAX_FRAME_TILES. */
uint32_t srv_cascade_max_tiles(const ocean_params *p, int layers, int tile_size);

/* The planner's fixed model of one encoded layout-1 tile's bytes (record
 * and TILE headers included) for subscription sub's codec and accuracy,
 * the given channels and side T: what server.viewer_bytes_per_s is
 * planned against, the same on every replica (bench_codec compares it
 * with the measured bytes). */
double srv_cascade_tile_bytes(const proto_subscribe *sub, unsigned channels, int T);

/* Builds the FRAMEs (and MESH_TOPOLOGYs) of jobs[0..n): evaluates the mips
 * the jobs need at their times, encodes missing tiles (cache generation
 * gen; entries unused for a generation are dropped by the caller's sweep
 * through srv_cascade_sweep), assembles each frame.  Jobs of identical
 * cameras share one encoding.  order is the Butterworth order of the mips;
 * g (may be NULL) the Gerstner near field and nf (may be NULL) the same
 * waves as a lattice cascade (ocean_gerstner_cascade_create): layout 1
 * lists it as the last cascade, after oc's, for subscriptions with the
 * near-field effect, and evaluates it only when one of its tiles is
 * needed.  Without nf the near field's slopes travel in tail_mss.
 * Errors go to the client as ERROR messages;
 * a job whose frame could not be built has frame NULL. */
struct ocean_gerstner;
void srv_cascade_run(srv_cascade *k, ocean *oc, const struct ocean_gerstner *g, ocean *nf, int order,
                     const srv_config *cfg, srv_stats *st, srv_cascade_job *jobs, int n, uint64_t gen);

/* Job j's frame was handed to its client (published 0: there was none to
 * hand), replacing (replaced 1) or not an unsent frame in the latest-wins
 * slot: the model of what a time-interpolating client holds follows. */
void srv_cascade_handed_over(const srv_cascade_job *j, int published, int replaced);

/* Drops cached tiles last used before generation keep_from. */
void srv_cascade_sweep(srv_cascade *k, uint64_t keep_from);

/* Tiles the cache holds and their bytes as of the last sweep
 * (srv_tiles_count, srv_tiles_bytes). */
void srv_cascade_cache_size(const srv_cascade *k, size_t *entries, size_t *bytes);

#endif
