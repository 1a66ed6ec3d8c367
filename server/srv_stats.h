/*
 * srv_stats.h - the daemon's counters, read by /metrics and /status.
 *
 * Plain atomics: any thread adds, the service thread reads.  A tick-to-send
 * latency histogram (log buckets) gives p50/p99 without storing samples.
 */
#ifndef SRV_STATS_H
#define SRV_STATS_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

#define SRV_LAT_BUCKETS 40   /* 0.1 ms * 1.3^i */
#define SRV_FX_CHANNELS 5     /* height, displacement, normals, foam, velocity */

typedef struct srv_stats {
    atomic_uint_fast64_t ticks, idle_ticks, tick_ns_total, tick_ns_last;
    atomic_uint_fast64_t evaluations, transforms;
    atomic_uint_fast64_t transforms_by_effect[SRV_FX_CHANNELS];
    atomic_uint_fast64_t frames_built, frames_shared, frames_sent, frames_skipped, frames_held;
    atomic_uint_fast64_t bytes_sent, messages_sent, messages_received;
    atomic_uint_fast64_t tiles_encoded, tile_cache_hits, tile_cache_misses;
    /* gauges the simulation thread stores: what its tile caches (layout 0's
     * world tiles and layout 1's cascade tiles) hold after its last sweep */
    atomic_uint_fast64_t tile_cache_entries, tile_cache_bytes;
    atomic_uint_fast64_t queries, query_points, errors_sent;
    atomic_uint_fast64_t connections_total, disconnects_slow, refused_full;
    atomic_uint_fast64_t sea_changes, reloads;
    /* sea changes whose ocean was built ahead, off the tick path, and those
     * built when they fell due (never asked for ahead) */
    atomic_uint_fast64_t sea_built_ahead, sea_built_due;
    /* what was refused to keep one client from hurting the others */
    atomic_uint_fast64_t refused_rate, refused_silent, refused_mesh, refused_upgrade;
    atomic_uint_fast64_t refused_admission;  /* SUBSCRIBEs past server.admit_share */
    atomic_uint_fast64_t coarsened_mesh;     /* meshes built at a coarser budget to fit */
    atomic_uint_fast64_t disconnects_partial, disconnects_output, disconnects_protocol;
    atomic_uint_fast64_t disconnects_idle;   /* BYE idle (server.idle_seconds) */
    atomic_uint_fast64_t admin_misses, admin_locked, accept_refused, query_slices;
    /* the replicated timeline (srv_redis.h): entries entered and skipped,
     * stream resets, far-future ids; connected is a gauge (0 or 1) */
    atomic_uint_fast64_t redis_entries, redis_skipped, redis_resets, redis_future_ids, redis_connected;
    /* the CIGI service (srv_cigi.h): host messages answered, requests
     * answered, datagrams dropped by reason, packets not acted on */
    atomic_uint_fast64_t cigi_messages, cigi_answers, cigi_drop_host, cigi_drop_framing, cigi_drop_value;
    atomic_uint_fast64_t cigi_drop_busy, cigi_ignored;
    /* the ships' wakes in point answers (srv_wakes.h): patterns built and
     * the seconds they took, query slices that waited for one */
    atomic_uint_fast64_t wake_patterns, wake_build_ns, wake_waits;
    atomic_uint_fast64_t lat_hist[SRV_LAT_BUCKETS];
} srv_stats;

/* Records one tick-to-send latency in seconds. */
void srv_stats_latency(srv_stats *s, double seconds);
/* Quantile q (0..1) of the recorded latencies, seconds (upper bucket edge); 0 if none. */
double srv_stats_latency_quantile(const srv_stats *s, double q);

/* One client's share, for /metrics. */
typedef struct srv_stats_client {
    uint32_t id;
    double cpu_seconds;          /* simulation-thread time on its requests */
    double bytes_out;            /* bytes sent to it */
    double queued;               /* bytes queued for it (allocated size) */
} srv_stats_client;

/* Facts that are not counters, for the renderers. */
typedef struct srv_stats_view {
    const srv_stats_client *per_client;  /* n_per_client entries (may be 0) */
    int n_per_client;
    int clients, subscribed;
    double sim_time, tick_rate;
    const char *scene;
    const char *version;
    int port;
    double wind, hs;
    int has_camera_hint;         /* the scene's scene.camera_hint, for viewers */
    double camera_hint[5];       /* x, y, z (m), yaw, pitch (deg) */
    const char *past_time_limit; /* NULL, or why nothing can be served: the clock is past
                                    OCEAN_TIME_MAX after server.epoch */
    /* admission for the daemon as a whole (srv_admit.h), in cores */
    double admit_capacity, admit_usable, admit_others, admit_shared, admit_priced;
    int admit_count;
} srv_stats_view;

/* Prometheus text exposition (version 0.0.4) into a malloc'ed string with
 * `headroom` spare bytes in front (for LWS_PRE); *len gets the text length.
 * NULL on OOM. */
char *srv_stats_prometheus(const srv_stats *s, const srv_stats_view *v, size_t headroom, size_t *len);
/* The same as a JSON object (cJSON). */
char *srv_stats_json(const srv_stats *s, const srv_stats_view *v, size_t headroom, size_t *len);

#endif
