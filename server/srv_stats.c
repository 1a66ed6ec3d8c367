/*
 * srv_stats.c - rendering the daemon's counters as Prometheus text and as
 * the /status JSON document.
 */
#include "srv_stats.h"

#include <cJSON.h>
#include <math.h>
#include <stdarg.h>
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

/* The replicated timeline's health (srv_redis.h): what an operator needs
 * to see a stream that was reset or written with ids far ahead. */
static void stream_metrics(sb *b, const srv_stats *s)
{
    metric(b, "oceand_redis_connected", "gauge", "1: the replication thread holds a Redis connection "
           "(0 also without server.redis).", (double)LD(redis_connected));
    metric(b, "oceand_redis_entries_total", "counter", "Stream entries entered into the sea-state "
           "timeline.", (double)LD(redis_entries));
    metric(b, "oceand_redis_skipped_total", "counter", "Stream entries skipped: too large, not one msg "
           "field, no valid SEA_STATE announce, or refused by the timeline.", (double)LD(redis_skipped));
    metric(b, "oceand_redis_stream_resets_total", "counter", "Times the entry last read was gone from the "
           "stream (deleted, recreated or trimmed): the timeline was read again from its start.",
           (double)LD(redis_resets));
    metric(b, "oceand_redis_future_ids_total", "counter", "Stream entries whose id is over 60 s ahead of "
           "this server's clock.", (double)LD(redis_future_ids));
}

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
    metric(&b, "oceand_ticks_total", "counter", "Simulation ticks run.", (double)LD(ticks));
    metric(&b, "oceand_idle_ticks_total", "counter", "Idle waits with nobody subscribed, about one a second (no tick runs then; not a count of ticks).",
           (double)LD(idle_ticks));
    metric(&b, "oceand_tick_seconds_total", "counter", "Time spent in ticks.",
           (double)LD(tick_ns_total) * 1e-9);
    metric(&b, "oceand_tick_seconds_last", "gauge", "Duration of the last tick.",
           (double)LD(tick_ns_last) * 1e-9);
    metric(&b, "oceand_evaluations_total", "counter", "Ocean evaluations (one per cutoff bucket "
           "and time).", (double)LD(evaluations));
    sb_printf(&b, "# HELP oceand_transforms_total Inverse 2-D FFTs run, per channel group.\n"
                  "# TYPE oceand_transforms_total counter\n");
    static const char *const ch[SRV_FX_CHANNELS] = {"height", "displacement", "normals", "foam",
                                                    "velocity"};
    for (int i = 0; i < SRV_FX_CHANNELS; i++)
        sb_printf(&b, "oceand_transforms_total{channel=\"%s\"} %llu\n", ch[i], LD(transforms_by_effect[i]));
    metric(&b, "oceand_frames_built_total", "counter", "Frames built for clients.", (double)LD(frames_built));
    metric(&b, "oceand_frames_shared_total", "counter", "Frames that reused another client's encoding "
           "(identical but for camera_seq and mesh_id).", (double)LD(frames_shared));
    metric(&b, "oceand_frames_sent_total", "counter", "Frames written to sockets.", (double)LD(frames_sent));
    metric(&b, "oceand_frames_skipped_total", "counter", "Frames replaced before a slow client "
           "could take them (latest wins).", (double)LD(frames_skipped));
    metric(&b, "oceand_frames_held_total", "counter", "Times a live frame waited because its client's link "
           "had a window of frames unconfirmed (srv_link.h).", (double)LD(frames_held));
    metric(&b, "oceand_bytes_sent_total", "counter", "WebSocket payload bytes written.", (double)LD(bytes_sent));
    metric(&b, "oceand_messages_received_total", "counter", "Client messages received.",
           (double)LD(messages_received));
    metric(&b, "oceand_tiles_encoded_total", "counter", "Tiles encoded.", (double)LD(tiles_encoded));
    metric(&b, "oceand_tile_cache_hits_total", "counter", "Tile requests served from the cache.",
           (double)LD(tile_cache_hits));
    metric(&b, "oceand_tile_cache_misses_total", "counter", "Tile requests that had to be encoded.",
           (double)LD(tile_cache_misses));
    metric(&b, "oceand_tile_cache_entries", "gauge", "Encoded tiles the caches hold (last sweep; 0 once idle).",
           (double)LD(tile_cache_entries));
    metric(&b, "oceand_tile_cache_bytes", "gauge", "Bytes those tiles take, entries included.",
           (double)LD(tile_cache_bytes));
    metric(&b, "oceand_queries_total", "counter", "QUERY messages answered.", (double)LD(queries));
    metric(&b, "oceand_query_points_total", "counter", "Points answered.", (double)LD(query_points));
    metric(&b, "oceand_errors_sent_total", "counter", "ERROR replies sent.", (double)LD(errors_sent));
    metric(&b, "oceand_connections_total", "counter", "Connections accepted.", (double)LD(connections_total));
    metric(&b, "oceand_disconnects_slow_total", "counter", "Clients dropped for the output limit.",
           (double)LD(disconnects_slow));
    metric(&b, "oceand_refused_full_total", "counter", "Connections refused at max_clients.",
           (double)LD(refused_full));
    metric(&b, "oceand_sea_changes_total", "counter", "Sea-state changes applied.", (double)LD(sea_changes));
    metric(&b, "oceand_reloads_total", "counter", "Configuration reloads (SIGHUP).", (double)LD(reloads));
    metric(&b, "oceand_refused_rate_total", "counter", "Messages refused over server.msg_rate "
           "(text frames included).", (double)LD(refused_rate));
    metric(&b, "oceand_refused_silent_total", "counter", "Refusals not answered: one ERROR a "
           "second at most per client.", (double)LD(refused_silent));
    metric(&b, "oceand_refused_mesh_total", "counter", "Meshes refused above "
           "server.max_mesh_vertices (estimated before building).", (double)LD(refused_mesh));
    metric(&b, "oceand_coarsened_mesh_total", "counter", "Meshes built at a multiple of "
           "server.mesh_error_px to stay within server.max_mesh_vertices.", (double)LD(coarsened_mesh));
    metric(&b, "oceand_refused_upgrade_total", "counter", "WebSocket upgrades refused (no "
           "ocean.v1 subprotocol, version other than 13).", (double)LD(refused_upgrade));
    metric(&b, "oceand_refused_accept_total", "counter", "Connections closed at accept: file "
           "descriptors reserved.", (double)LD(accept_refused));
    metric(&b, "oceand_disconnects_partial_total", "counter", "Clients dropped for an unfinished "
           "message (server.partial_seconds, server.partial_total).", (double)LD(disconnects_partial));
    metric(&b, "oceand_disconnects_idle_total", "counter", "Connections closed with BYE idle: "
           "no SUBSCRIBE and no message for server.idle_seconds.", (double)LD(disconnects_idle));
    metric(&b, "oceand_disconnects_output_total", "counter", "Clients dropped when a reply "
           "would pass server.output_hard as it was queued.", (double)LD(disconnects_output));
    metric(&b, "oceand_disconnects_protocol_total", "counter", "Clients closed for breaking "
           "RFC 6455 (unmasked frame, bad close code).", (double)LD(disconnects_protocol));
    metric(&b, "oceand_admin_misses_total", "counter", "Wrong admin tokens.", (double)LD(admin_misses));
    metric(&b, "oceand_admin_locked_total", "counter", "SEA_STATE sets refused in an admin "
           "lockout.", (double)LD(admin_locked));
    metric(&b, "oceand_query_slices_total", "counter", "Slices of QUERY work run (a query "
           "larger than a tick's budget takes several).", (double)LD(query_slices));
    if (v->n_per_client > 0) {
        sb_printf(&b, "# HELP oceand_client_cpu_seconds_total Simulation-thread time spent on "
                      "one client's queries, replay frames and meshes.\n"
                      "# TYPE oceand_client_cpu_seconds_total counter\n");
        for (int i = 0; i < v->n_per_client; i++)
            sb_printf(&b, "oceand_client_cpu_seconds_total{client=\"%u\"} %.9g\n",
                      v->per_client[i].id, v->per_client[i].cpu_seconds);
        sb_printf(&b, "# HELP oceand_client_bytes_sent_total Bytes sent to one client.\n"
                      "# TYPE oceand_client_bytes_sent_total counter\n");
        for (int i = 0; i < v->n_per_client; i++)
            sb_printf(&b, "oceand_client_bytes_sent_total{client=\"%u\"} %.17g\n",
                      v->per_client[i].id, v->per_client[i].bytes_out);
        sb_printf(&b, "# HELP oceand_client_queued_bytes Bytes queued for one client "
                      "(allocated size; server.output_hard bounds it).\n"
                      "# TYPE oceand_client_queued_bytes gauge\n");
        for (int i = 0; i < v->n_per_client; i++)
            sb_printf(&b, "oceand_client_queued_bytes{client=\"%u\"} %.17g\n",
                      v->per_client[i].id, v->per_client[i].queued);
    }
    stream_metrics(&b, s);
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
