/*
 * srv_stats.c - rendering the daemon's counters as Prometheus text and as
 * the /status JSON document.
 *
 * Threads: any thread adds to the counters (atomics); the renderers read
 * them with atomic loads, on the service thread that answers /metrics and
 * /status, and own nothing but the text they return.
 */
#include "srv_stats.h"

#include <cJSON.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static double bucket_edge(int i) { return 1e-4 * pow(1.3, i + 1); }

void srv_stats_latency(srv_stats *s, double seconds)
{
    int i = 0;
    while (i < SRV_LAT_BUCKETS - 1 && seconds > bucket_edge(i)) i++;
    atomic_fetch_add(&s->lat_hist[i], 1);
}

double srv_stats_latency_quantile(const srv_stats *s, double q)
{
    uint64_t n = 0, acc = 0;
    for (int i = 0; i < SRV_LAT_BUCKETS; i++) n += atomic_load(&s->lat_hist[i]);
    if (!n) return 0;
    uint64_t want = (uint64_t)ceil(q * (double)n);
    if (want < 1) want = 1;
    for (int i = 0; i < SRV_LAT_BUCKETS; i++) {
        acc += atomic_load(&s->lat_hist[i]);
        if (acc >= want) return bucket_edge(i);
    }
    return bucket_edge(SRV_LAT_BUCKETS - 1);
}

typedef struct sb {
    char *p;
    size_t len, cap, head;
    int oom;
} sb;

static void sb_printf(sb *b, const char *fmt, ...)
{
    if (b->oom) return;
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        size_t room = b->cap - b->head - b->len;
        int n = vsnprintf(b->p + b->head + b->len, room, fmt, ap);
        va_end(ap);
        if (n < 0) { b->oom = 1; return; }
        if ((size_t)n < room) { b->len += (size_t)n; return; }
        size_t ncap = (b->cap * 2) + (size_t)n;
        char *np = realloc(b->p, ncap);
        if (!np) { b->oom = 1; return; }
        b->p = np;
        b->cap = ncap;
    }
}

#define LD(x) ((unsigned long long)atomic_load(&s->x))

static void metric(sb *b, const char *name, const char *type, const char *help, double v)
{
    sb_printf(b, "# HELP %s %s\n# TYPE %s %s\n%s %.17g\n", name, help, name, type, name, v);
}

/* A counter or gauge of srv_stats as one metric: its value is the field
 * times scale. */
typedef struct stat_metric {
    const char *name, *type, *help;
    size_t field;             /* offsetof(srv_stats, ...) */
    double scale;
} stat_metric;

#define STAT(name, type, help, field, scale) {name, type, help, offsetof(srv_stats, field), scale}

/* The clock's counters, before the per-channel transforms. */
static const stat_metric tick_metrics[] = {
    STAT("oceand_ticks_total", "counter", "Simulation ticks run.", ticks, 1),
    STAT("oceand_idle_ticks_total", "counter", "Idle waits with nobody subscribed, about one a second (no tick "
         "runs then; not a count of ticks).", idle_ticks, 1),
    STAT("oceand_tick_seconds_total", "counter", "Time spent in ticks.", tick_ns_total, 1e-9),
    STAT("oceand_tick_seconds_last", "gauge", "Duration of the last tick.", tick_ns_last, 1e-9),
    STAT("oceand_evaluations_total", "counter", "Ocean evaluations (one per cutoff bucket and time).", evaluations,
         1),
};

/* Frames, tiles, queries, connections and refusals. */
static const stat_metric traffic_metrics[] = {
    STAT("oceand_frames_built_total", "counter", "Frames built for clients.", frames_built, 1),
    STAT("oceand_frames_shared_total", "counter", "Frames that reused another client's encoding (identical but "
         "for camera_seq and mesh_id).", frames_shared, 1),
    STAT("oceand_frames_sent_total", "counter", "Frames written to sockets.", frames_sent, 1),
    STAT("oceand_frames_skipped_total", "counter", "Frames replaced before a slow client could take them "
         "(latest wins).", frames_skipped, 1),
    STAT("oceand_frames_held_total", "counter", "Times a live frame waited because its client's link had a "
         "window of frames unconfirmed (srv_link.h).", frames_held, 1),
    STAT("oceand_bytes_sent_total", "counter", "WebSocket payload bytes written.", bytes_sent, 1),
    STAT("oceand_messages_received_total", "counter", "Client messages received.", messages_received, 1),
    STAT("oceand_tiles_encoded_total", "counter", "Tiles encoded.", tiles_encoded, 1),
    STAT("oceand_tile_cache_hits_total", "counter", "Tile requests served from the cache.", tile_cache_hits, 1),
    STAT("oceand_tile_cache_misses_total", "counter", "Tile requests that had to be encoded.", tile_cache_misses,
         1),
    STAT("oceand_tile_cache_entries", "gauge", "Encoded tiles the caches hold (last sweep; 0 once idle).",
         tile_cache_entries, 1),
    STAT("oceand_tile_cache_bytes", "gauge", "Bytes those tiles take, entries included.", tile_cache_bytes, 1),
    STAT("oceand_queries_total", "counter", "QUERY messages answered.", queries, 1),
    STAT("oceand_query_points_total", "counter", "Points answered.", query_points, 1),
    STAT("oceand_errors_sent_total", "counter", "ERROR replies sent.", errors_sent, 1),
    STAT("oceand_cigi_messages_total", "counter", "CIGI host messages (datagrams) answered with a Start of "
         "Frame.", cigi_messages, 1),
    STAT("oceand_cigi_answers_total", "counter", "CIGI HAT/HOT and Environmental Conditions requests answered.",
         cigi_answers, 1),
    STAT("oceand_cigi_dropped_host_total", "counter", "CIGI datagrams dropped: the sender is not in "
         "server.cigi_hosts.", cigi_drop_host, 1),
    STAT("oceand_cigi_dropped_framing_total", "counter", "CIGI datagrams dropped or cut short: no IG Control "
         "first, another version, a size that is 0, not a multiple of 8 or past the datagram.", cigi_drop_framing, 1),
    STAT("oceand_cigi_dropped_value_total", "counter", "CIGI packets dropped: NaN, infinite or out-of-range "
         "values (cigi_packet_check).", cigi_drop_value, 1),
    STAT("oceand_cigi_dropped_busy_total", "counter", "CIGI host messages dropped: the previous one's requests "
         "were still being answered (a host faster than the daemon's ticks).", cigi_drop_busy, 1),
    STAT("oceand_cigi_ignored_total", "counter", "CIGI packets read and not acted on (packets this version "
         "does not use, inactive or attached entities).",
         cigi_ignored, 1),
    STAT("oceand_wake_patterns_total", "counter", "Ship wake patterns built for point answers (one FFT each, "
         "on the wake builder's thread).", wake_patterns, 1),
    STAT("oceand_wake_build_seconds_total", "counter", "Seconds those builds took.", wake_build_ns, 1e-9),
    STAT("oceand_wake_waits_total", "counter", "Query slices that waited for a wake pattern being built.",
         wake_waits, 1),
    STAT("oceand_connections_total", "counter", "Connections accepted.", connections_total, 1),
    STAT("oceand_disconnects_slow_total", "counter", "Clients dropped for the output limit.", disconnects_slow, 1),
    STAT("oceand_refused_full_total", "counter", "Connections refused at max_clients.", refused_full, 1),
    STAT("oceand_sea_changes_total", "counter", "Sea-state changes applied.", sea_changes, 1),
    STAT("oceand_sea_built_ahead_total", "counter",
         "Sea changes whose ocean was built ahead, off the tick path.", sea_built_ahead, 1),
    STAT("oceand_sea_built_due_total", "counter",
         "Sea changes whose ocean was built on the tick they fell due.", sea_built_due, 1),
    STAT("oceand_reloads_total", "counter", "Configuration reloads (SIGHUP).", reloads, 1),
    STAT("oceand_refused_rate_total", "counter", "Messages refused over server.msg_rate (text frames included).",
         refused_rate, 1),
    STAT("oceand_refused_silent_total", "counter", "Refusals not answered: one ERROR a second at most per client.",
         refused_silent, 1),
    STAT("oceand_refused_admission_total", "counter", "SUBSCRIBEs refused: their price would take the daemon's "
         "admitted work past server.admit_share of its usable cores.", refused_admission, 1),
    STAT("oceand_refused_mesh_total", "counter", "Meshes refused above server.max_mesh_vertices (estimated "
         "before building).", refused_mesh, 1),
    STAT("oceand_coarsened_mesh_total", "counter", "Meshes built at a multiple of server.mesh_error_px (flat_mesh_error_px) to stay "
         "within server.max_mesh_vertices.", coarsened_mesh, 1),
    STAT("oceand_refused_upgrade_total", "counter", "WebSocket upgrades refused (no ocean.v1 subprotocol, "
         "version other than 13).", refused_upgrade, 1),
    STAT("oceand_refused_accept_total", "counter", "Connections closed at accept: file descriptors reserved.",
         accept_refused, 1),
    STAT("oceand_disconnects_partial_total", "counter", "Clients dropped for an unfinished message "
         "(server.partial_seconds, server.partial_total).", disconnects_partial, 1),
    STAT("oceand_disconnects_idle_total", "counter", "Connections closed with BYE idle: no SUBSCRIBE and no "
         "message for server.idle_seconds.", disconnects_idle, 1),
    STAT("oceand_disconnects_output_total", "counter", "Clients dropped when a reply would pass "
         "server.output_hard as it was queued.", disconnects_output, 1),
    STAT("oceand_disconnects_protocol_total", "counter", "Clients closed for breaking RFC 6455 (unmasked frame, "
         "bad close code).", disconnects_protocol, 1),
    STAT("oceand_admin_misses_total", "counter", "Wrong admin tokens.", admin_misses, 1),
    STAT("oceand_admin_locked_total", "counter", "SEA_STATE sets refused in an admin lockout.", admin_locked, 1),
    STAT("oceand_query_slices_total", "counter", "Slices of QUERY work run (a query larger than a tick's budget "
         "takes several).", query_slices, 1),
};

static void stat_metrics(sb *b, const srv_stats *s, const stat_metric *m, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        const atomic_uint_fast64_t *f = (const atomic_uint_fast64_t *)((const char *)s + m[i].field);
        metric(b, m[i].name, m[i].type, m[i].help, (double)(unsigned long long)atomic_load(f) * m[i].scale);
    }
}

/* Each client's share, one family per field of srv_stats_client. */
static const struct client_metric {
    const char *name, *type, *help;
    size_t field;             /* offsetof(srv_stats_client, ...), a double */
    int digits;               /* significant digits printed */
} client_metrics[] = {
    {"oceand_client_cpu_seconds_total", "counter", "Simulation-thread time spent on one client's queries, "
     "replay frames and meshes.", offsetof(srv_stats_client, cpu_seconds), 9},
    {"oceand_client_bytes_sent_total", "counter", "Bytes sent to one client.",
     offsetof(srv_stats_client, bytes_out), 17},
    {"oceand_client_queued_bytes", "gauge", "Bytes queued for one client (allocated size; server.output_hard "
     "bounds it).", offsetof(srv_stats_client, queued), 17},
};

static void per_client_metrics(sb *b, const srv_stats_view *v)
{
    for (size_t k = 0; k < sizeof client_metrics / sizeof client_metrics[0]; k++) {
        const struct client_metric *m = &client_metrics[k];
        sb_printf(b, "# HELP %s %s\n# TYPE %s %s\n", m->name, m->help, m->name, m->type);
        for (int i = 0; i < v->n_per_client; i++) {
            double x = *(const double *)((const char *)&v->per_client[i] + m->field);
            sb_printf(b, "%s{client=\"%u\"} %.*g\n", m->name, v->per_client[i].id, m->digits, x);
        }
    }
}

/* The replicated timeline's health (srv_redis.h): what an operator needs
 * to see a stream that was reset or written with ids far ahead. */
static const stat_metric stream_metrics[] = {
    STAT("oceand_redis_connected", "gauge", "1: the replication thread holds a Redis connection (0 also "
         "without server.redis).", redis_connected, 1),
    STAT("oceand_redis_entries_total", "counter", "Stream entries entered into the sea-state timeline.",
         redis_entries, 1),
    STAT("oceand_redis_skipped_total", "counter", "Stream entries skipped: too large, not one msg field, no "
         "valid SEA_STATE announce, or refused by the timeline.", redis_skipped, 1),
    STAT("oceand_redis_stream_resets_total", "counter", "Times the entry last read was gone from the stream "
         "(deleted, recreated or trimmed): the timeline was read again from its start.", redis_resets, 1),
    STAT("oceand_redis_future_ids_total", "counter", "Stream entries whose id is over 60 s ahead of this "
         "server's clock.", redis_future_ids, 1),
};

static void stream_json(cJSON *o, const srv_stats *s)
{
    cJSON *r = cJSON_AddObjectToObject(o, "redis");
    if (!r) return;
    cJSON_AddBoolToObject(r, "connected", LD(redis_connected) != 0);
    cJSON_AddNumberToObject(r, "entries", (double)LD(redis_entries));
    cJSON_AddNumberToObject(r, "skipped", (double)LD(redis_skipped));
    cJSON_AddNumberToObject(r, "stream_resets", (double)LD(redis_resets));
    cJSON_AddNumberToObject(r, "future_ids", (double)LD(redis_future_ids));
}

/* Admission's figures (srv_admit.h): what admitted work may take and takes. */
static void admission_metrics(sb *b, const srv_stats_view *v)
{
    metric(b, "oceand_admission_capacity_cores", "gauge", "What admitted work may take: "
           "server.admit_share x the usable cores.", v->admit_capacity);
    metric(b, "oceand_admission_usable_cores", "gauge", "Cores the daemon can use: server.workers at most, "
           "less what other processes use (measured).", v->admit_usable);
    metric(b, "oceand_admission_other_processes_cores", "gauge", "Cores other processes of the host used "
           "(measured, smoothed).", v->admit_others);
    metric(b, "oceand_admission_shared_cores", "gauge", "The simulation thread's work not priced per "
           "subscription (measured, smoothed).", v->admit_shared);
    metric(b, "oceand_admission_priced_cores", "gauge", "The admitted layout-0 subscriptions' prices, "
           "summed.", v->admit_priced);
    metric(b, "oceand_admission_priced_subscriptions", "gauge", "Subscriptions holding a price.",
           v->admit_count);
}

static void admission_json(cJSON *o, const srv_stats_view *v)
{
    cJSON *a = cJSON_AddObjectToObject(o, "admission");
    if (!a) return;
    cJSON_AddNumberToObject(a, "capacity_cores", v->admit_capacity);
    cJSON_AddNumberToObject(a, "usable_cores", v->admit_usable);
    cJSON_AddNumberToObject(a, "other_processes_cores", v->admit_others);
    cJSON_AddNumberToObject(a, "shared_cores", v->admit_shared);
    cJSON_AddNumberToObject(a, "priced_cores", v->admit_priced);
    cJSON_AddNumberToObject(a, "priced_subscriptions", v->admit_count);
}

char *srv_stats_prometheus(const srv_stats *s, const srv_stats_view *v, size_t headroom, size_t *len)
{
    sb b = {malloc(headroom + 4096), 0, headroom + 4096, headroom, 0};
    if (!b.p) return NULL;
    metric(&b, "oceand_clients", "gauge", "Connected clients.", v->clients);
    metric(&b, "oceand_clients_subscribed", "gauge", "Clients with a subscription.", v->subscribed);
    metric(&b, "oceand_sim_time_seconds", "gauge", "The shared simulation clock.", v->sim_time);
    metric(&b, "oceand_past_time_limit", "gauge", "1: the clock is past the exact-time limit "
           "(OCEAN_TIME_MAX after server.epoch); every client is closed until a restart with a nearer "
           "server.epoch.", v->past_time_limit != NULL);
    stat_metrics(&b, s, tick_metrics, sizeof tick_metrics / sizeof tick_metrics[0]);
    admission_metrics(&b, v);
    sb_printf(&b, "# HELP oceand_transforms_total Inverse 2-D FFTs run, per channel group.\n"
                  "# TYPE oceand_transforms_total counter\n");
    static const char *const ch[SRV_FX_CHANNELS] = {"height", "displacement", "normals", "foam",
                                                    "velocity"};
    for (int i = 0; i < SRV_FX_CHANNELS; i++)
        sb_printf(&b, "oceand_transforms_total{channel=\"%s\"} %llu\n", ch[i], LD(transforms_by_effect[i]));
    stat_metrics(&b, s, traffic_metrics, sizeof traffic_metrics / sizeof traffic_metrics[0]);
    if (v->n_per_client > 0)
        per_client_metrics(&b, v);
    stat_metrics(&b, s, stream_metrics, sizeof stream_metrics / sizeof stream_metrics[0]);
    metric(&b, "oceand_tick_to_send_p50_seconds", "gauge", "Median time from a tick to the "
           "write of its frame.", srv_stats_latency_quantile(s, 0.5));
    metric(&b, "oceand_tick_to_send_p99_seconds", "gauge", "99th percentile of the same.",
           srv_stats_latency_quantile(s, 0.99));
    if (b.oom) { free(b.p); return NULL; }
    *len = b.len;
    return b.p;
}

char *srv_stats_json(const srv_stats *s, const srv_stats_view *v, size_t headroom, size_t *len)
{
    cJSON *o = cJSON_CreateObject();
    if (!o) return NULL;
    cJSON_AddStringToObject(o, "server", "oceand");
    cJSON_AddStringToObject(o, "version", v->version ? v->version : "");
    cJSON_AddStringToObject(o, "scene", v->scene ? v->scene : "");
    cJSON_AddNumberToObject(o, "port", v->port);
    cJSON_AddNumberToObject(o, "clients", v->clients);
    cJSON_AddNumberToObject(o, "subscribed", v->subscribed);
    cJSON_AddNumberToObject(o, "sim_time", v->sim_time);
    /* /status answers 503 then: a health check takes the replica out */
    cJSON_AddBoolToObject(o, "past_time_limit", v->past_time_limit != NULL);
    if (v->past_time_limit) cJSON_AddStringToObject(o, "error", v->past_time_limit);
    cJSON_AddNumberToObject(o, "tick_rate_hz", v->tick_rate);
    cJSON_AddNumberToObject(o, "wind_u10", v->wind);
    /* Where the scene suggests a viewer starts (the browser viewer opens
     * there unless its URL says otherwise); null without a hint. */
    if (v->has_camera_hint) {
        cJSON *ch = cJSON_AddObjectToObject(o, "camera_hint");
        if (ch) {
            cJSON_AddNumberToObject(ch, "x", v->camera_hint[0]);
            cJSON_AddNumberToObject(ch, "y", v->camera_hint[1]);
            cJSON_AddNumberToObject(ch, "z", v->camera_hint[2]);
            cJSON_AddNumberToObject(ch, "yaw", v->camera_hint[3]);
            cJSON_AddNumberToObject(ch, "pitch", v->camera_hint[4]);
        }
    } else {
        cJSON_AddNullToObject(o, "camera_hint");
    }
    cJSON_AddNumberToObject(o, "ticks", (double)LD(ticks));
    cJSON_AddNumberToObject(o, "idle_ticks", (double)LD(idle_ticks));
    /* ticks counts only ticks that ran (tick_ns_total is theirs); idle
     * ticks are counted apart and may outnumber them, so no subtraction:
     * ticks - idle_ticks wrapped (unsigned) to a mean of 7.6e-18 ms. */
    uint64_t ran = LD(ticks);
    cJSON_AddNumberToObject(o, "tick_ms_mean", ran ? (double)LD(tick_ns_total) * 1e-6 / (double)ran : 0);
    cJSON_AddNumberToObject(o, "evaluations", (double)LD(evaluations));
    cJSON_AddNumberToObject(o, "transforms", (double)LD(transforms));
    cJSON_AddNumberToObject(o, "frames_built", (double)LD(frames_built));
    cJSON_AddNumberToObject(o, "frames_shared", (double)LD(frames_shared));
    cJSON_AddNumberToObject(o, "frames_sent", (double)LD(frames_sent));
    cJSON_AddNumberToObject(o, "frames_skipped", (double)LD(frames_skipped));
    cJSON_AddNumberToObject(o, "frames_held", (double)LD(frames_held));
    cJSON_AddNumberToObject(o, "bytes_sent", (double)LD(bytes_sent));
    cJSON_AddNumberToObject(o, "tile_cache_hits", (double)LD(tile_cache_hits));
    cJSON_AddNumberToObject(o, "tile_cache_misses", (double)LD(tile_cache_misses));
    cJSON_AddNumberToObject(o, "tile_cache_entries", (double)LD(tile_cache_entries));
    cJSON_AddNumberToObject(o, "tile_cache_bytes", (double)LD(tile_cache_bytes));
    cJSON_AddNumberToObject(o, "queries", (double)LD(queries));
    cJSON_AddNumberToObject(o, "errors_sent", (double)LD(errors_sent));
    cJSON_AddNumberToObject(o, "disconnects_slow", (double)LD(disconnects_slow));
    cJSON_AddNumberToObject(o, "tick_to_send_p50_ms", 1e3 * srv_stats_latency_quantile(s, 0.5));
    cJSON_AddNumberToObject(o, "tick_to_send_p99_ms", 1e3 * srv_stats_latency_quantile(s, 0.99));
    stream_json(o, s);
    admission_json(o, v);
    char *txt = cJSON_PrintUnformatted(o);
    cJSON_Delete(o);
    if (!txt) return NULL;
    size_t n = strlen(txt);
    char *out = malloc(headroom + n + 1);
    if (out) {
        memcpy(out + headroom, txt, n + 1);
        *len = n;
    }
    cJSON_free(txt);
    return out;
}
