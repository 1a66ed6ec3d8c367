/*
 * srv_config.c - the server.* table and the daemon's configuration loader.
 *
 * Defaults are chosen so the default subscription of a viewer stays under
 * 4 MB/s at 30 Hz (tiles 2 x 2 per level, qz codec, a 4-pixel mesh) and so
 * the daemon is safe on a public interface only when told to be (loopback
 * bind, admin disabled without a token).
 */
#include "srv_config.h"
#include "ocean_time.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/stat.h>
#include <unistd.h>

#include "codec.h"
#include "geo.h"
#include "proto.h"

#define SRV(f) offsetof(srv_config, f)

static const conf_name codec_names[] = {
    {"f32", 1u << PROTO_CODEC_F32},         {"f16", 1u << PROTO_CODEC_F16},
    {"qz", 1u << PROTO_CODEC_QZ},           {"exr-zip", 1u << PROTO_CODEC_EXR_ZIP},
    {"exr-piz", 1u << PROTO_CODEC_EXR_PIZ}, {"exr-b44", 1u << PROTO_CODEC_EXR_B44},
    {"exr-b44a", 1u << PROTO_CODEC_EXR_B44A}, {NULL, 0}};


/* A tile side that halves with the mips: a power of two. */
static ocean_result tile_pow2_hook(void *target, const conf_entry *e, const void *value, char *msg,
                                   size_t msglen)
{
    (void)target;
    int n = *(const int *)value;
    if (n <= 0 || (n & (n - 1)) != 0) {
        snprintf(msg, msglen, "%s: must be a power of two (8, 16, ..., 256)", e->name);
        return OCEAN_EINVAL;
    }
    return OCEAN_OK;
}

/* server.epoch: refused where it is written (file:line, or the --set),
 * like every other bad value; an empty one is the daemon's start. */
static ocean_result epoch_hook(void *target, const conf_entry *e, const void *value, char *msg, size_t msglen)
{
    (void)target;
    const char *text = value;
    double unix_s;
    if (!text[0] || srv_epoch_parse(text, &unix_s, NULL, 0) == OCEAN_OK) return OCEAN_OK;
    snprintf(msg, msglen, "%s: expected Unix seconds or an ISO 8601 UTC time like 2026-01-01T00:00:00Z "
             "(a real date; Z or +HH:MM required)", e->name);
    return OCEAN_EINVAL;
}

ocean_result srv_config_hosts_parse(const char *text, struct in6_addr *out, int *n, char *why, size_t why_len)
{
    *n = 0;
    const char *p = text;
    while (*p) {
        size_t len = strcspn(p, ",");
        char item[INET6_ADDRSTRLEN + 8];
        while (len && (*p == ' ' || *p == '\t')) p++, len--;
        while (len && (p[len - 1] == ' ' || p[len - 1] == '\t')) len--;
        struct in_addr v4;
        if (len == 0 || len >= sizeof item || *n == SRV_CIGI_HOSTS) {
            ocean_seterr(why, why_len, *n == SRV_CIGI_HOSTS ? "more than %d addresses" : "an empty or overlong "
                         "address (item %d)", *n == SRV_CIGI_HOSTS ? SRV_CIGI_HOSTS : *n + 1);
            return OCEAN_EINVAL;
        }
        memcpy(item, p, len);
        item[len] = 0;
        if (inet_pton(AF_INET, item, &v4) == 1) {
            memset(&out[*n], 0, sizeof out[*n]);
            out[*n].s6_addr[10] = out[*n].s6_addr[11] = 0xFF;
            memcpy(&out[*n].s6_addr[12], &v4, 4);
        } else if (inet_pton(AF_INET6, item, &out[*n]) != 1) {
            ocean_seterr(why, why_len, "'%s' is not an IPv4 or IPv6 address (names are not resolved)", item);
            return OCEAN_EINVAL;
        }
        ++*n;
        p += strcspn(p, ",");
        if (*p) p++;
    }
    return OCEAN_OK;
}

static ocean_result hosts_hook(void *target, const conf_entry *e, const void *value, char *msg, size_t msglen)
{
    (void)target;
    struct in6_addr a[SRV_CIGI_HOSTS];
    int n;
    char why[200];
    if (srv_config_hosts_parse(value, a, &n, why, sizeof why) == OCEAN_OK) return OCEAN_OK;
    snprintf(msg, msglen, "%s: %s", e->name, why);
    return OCEAN_EINVAL;
}

static ocean_result origin_hook(void *target, const conf_entry *e, const void *value, char *msg, size_t msglen)
{
    (void)target;
    double lat, lon;
    char why[200];
    if (ocean_geo_origin_parse(value, &lat, &lon, why, sizeof why) == OCEAN_OK) return OCEAN_OK;
    snprintf(msg, msglen, "%s: %s", e->name, why);
    return OCEAN_EINVAL;
}

static const conf_entry srv_entries[] = {
    {.name = "server.port", .type = CONF_INT, .offset = SRV(port), .min = 0, .max = 65535,
     .def = "8740",
     .help = "TCP port of the WebSocket endpoint and the HTTP pages (viewer, /metrics, "
             "/status); 0 picks a free port and logs it."},
    {.name = "server.bind", .type = CONF_STRING, .offset = SRV(bind), .size = SRV_BIND_MAX,
     .def = "127.0.0.1",
     .help = "Address to listen on; an empty string listens on every interface."},
    {.name = "server.max_clients", .type = CONF_INT, .offset = SRV(max_clients), .min = 1,
     .max = 100000, .def = "1024",
     .help = "Connections served at once; one more is told BYE server-full and closed."},
    {.name = "server.max_message", .type = CONF_INT, .offset = SRV(max_message), .min = 256,
     .max = 64 << 20, .def = "1048576", .unit = "bytes",
     .help = "Largest message a client may send; a longer one is discarded with an ERROR "
             "(1 MiB holds a QUERY of 65 532 points: 56 + 16 per point; HELLO announces "
             "the smaller of this and server.max_query_points)."},
    {.name = "server.msg_rate", .type = CONF_DOUBLE, .offset = SRV(msg_rate), .min = 0.1,
     .max = 1e5, .def = "200", .unit = "messages/s",
     .help = "Sustained messages per second a client may send (token bucket); excess "
             "messages are refused with an ERROR."},
    {.name = "server.msg_burst", .type = CONF_INT, .offset = SRV(msg_burst), .min = 1,
     .max = 100000, .def = "400", .unit = "messages",
     .help = "Depth of the message-rate bucket: how many messages may arrive at once."},
    {.name = "server.output_soft", .type = CONF_U64, .offset = SRV(output_soft), .min = 1024,
     .max = 1e12, .def = "8388608", .unit = "bytes",
     .help = "Soft output limit (redis' client-output-buffer-limit): a client whose queued "
             "bytes stay above this for server.output_soft_seconds is disconnected. Frames "
             "never queue (latest wins); replies and replay frames do."},
    {.name = "server.output_soft_seconds", .type = CONF_DOUBLE, .offset = SRV(output_soft_seconds),
     .min = 0, .max = 3600, .def = "10", .unit = "s",
     .help = "How long a client may stay above the soft output limit, and how long "
             "output may wait with no send completed (a reader that takes nothing; at "
             "least 1 s)."},
    {.name = "server.output_hard", .type = CONF_U64, .offset = SRV(output_hard), .min = 1024,
     .max = 1e12, .def = "33554432", .unit = "bytes",
     .help = "Hard output limit: a client with more bytes queued is disconnected at once "
             "(BYE slow-consumer)."},
    {.name = "server.admin_token", .type = CONF_STRING, .offset = SRV(admin_token),
     .size = SRV_TOKEN_MAX, .def = "",
     .help = "Secret a SEA_STATE set message must carry; empty disables runtime sea-state "
             "changes."},
    {.name = "server.entity_token", .type = CONF_STRING, .offset = SRV(entity_token),
     .size = SRV_TOKEN_MAX, .def = "",
     .help = "Secret an ENTITY set or remove message must carry (a simulator placing its "
             "ships and aircraft in the sea); empty disables entities over ocean.v1 (a CIGI "
             "host's Entity Control still enters them). Wrong tokens wait as the admin "
             "token's do (server.admin_lockout)."},
    {.name = "server.read_rate", .type = CONF_DOUBLE, .offset = SRV(read_rate), .min = 65536,
     .max = 1e12, .def = "8388608", .unit = "bytes/s",
     .help = "Bytes per second the daemon reads from one client (token bucket, one "
             "server.max_message deep): a client sending faster is paused, not dropped, so "
             "decoding its messages cannot starve the other connections."},
    {.name = "server.partial_seconds", .type = CONF_DOUBLE, .offset = SRV(partial_seconds),
     .min = 0.1, .max = 3600, .def = "5", .unit = "s",
     .help = "A message a client has begun (from its first frame header on, fragmented or "
             "not yet all arrived) must be complete within this; a client that holds one "
             "longer is disconnected (close 1008), so half-sent messages cannot pin memory."},
    {.name = "server.idle_seconds", .type = CONF_DOUBLE, .offset = SRV(idle_seconds),
     .min = 1, .max = 86400, .def = "60", .unit = "s",
     .help = "A connection that has not subscribed and has sent no message for this long is "
             "closed with BYE idle, so connections that never ask for anything cannot hold "
             "the server.max_clients slots; a subscribed client may stay silent."},
    {.name = "server.partial_total", .type = CONF_U64, .offset = SRV(partial_total),
     .min = 65536, .max = 1e12, .def = "67108864", .unit = "bytes",
     .help = "Bytes of unfinished client messages the daemon holds at once, all clients "
             "together; the client whose message would pass it is disconnected (close 1008)."},
    {.name = "server.admin_lockout", .type = CONF_DOUBLE, .offset = SRV(admin_lockout),
     .min = 0, .max = 3600, .def = "1", .unit = "s",
     .help = "After a wrong admin token the connection's and its address's SEA_STATE sets "
             "are refused for this long, doubling with each further miss (to 64x); more than "
             "20 misses in 10 s from all addresses together lock every address that missed out "
             "for 10 s.  An address that sent no wrong token is never locked out."},
    {.name = "server.web_root", .type = CONF_STRING, .offset = SRV(web_root), .size = SRV_PATH_MAX,
     .def = "clients/web",
     .help = "Directory served over HTTP at / (the browser viewer); relative to the working "
             "directory."},
    {.name = "server.tick_rate", .type = CONF_DOUBLE, .offset = SRV(tick_rate), .min = 1,
     .max = 240, .def = "30", .unit = "Hz",
     .help = "Simulation ticks per second; one shared clock advances by 1/tick_rate per tick. "
             "A client's frame rate is met on the nearest tick."},
    {.name = "server.epoch", .type = CONF_STRING, .offset = SRV(epoch), .size = SRV_EPOCH_MAX,
     .def = "", .hook = epoch_hook,
     .help = "Instant of sim time 0 on the system clock (UTC): an ISO 8601 time such as "
             "2026-01-01T00:00:00Z, or Unix seconds. Daemons given the same epoch on "
             "NTP/PTP-synchronised machines agree on the sim time and tick index (to their "
             "clock offset). Empty: the daemon's start. Needs a restart to change."},
    {.name = "server.redis", .type = CONF_STRING, .offset = SRV(redis), .size = SRV_BIND_MAX,
     .def = "",
     .help = "host:port of a Redis server holding the sea-state timeline shared by replicas "
             "(a stream, server.redis_stream): every sea-state change is appended there and "
             "applied by every replica at its effective time. Empty: this daemon's timeline is "
             "its own. Needs a restart to change."},
    {.name = "server.redis_stream", .type = CONF_STRING, .offset = SRV(redis_stream),
     .size = SRV_REDIS_KEY_MAX, .def = "oceand:sea",
     .help = "Key of the Redis stream of sea-state changes; replicas of one exercise share it."},
    {.name = "server.cigi_port", .type = CONF_INT, .offset = SRV(cigi_port), .min = 0, .max = 65535,
     .def = "0",
     .help = "UDP port of the CIGI service (protocol/CIGI.md): simulator hosts ask it for the "
             "water under their points (HAT/HOT) and for the sea's conditions, as they ask an "
             "image generator; on server.bind. 0: off. Needs a restart to change."},
    {.name = "server.cigi_hosts", .type = CONF_STRING, .offset = SRV(cigi_hosts), .size = SRV_HOSTS_MAX,
     .def = "127.0.0.1,::1", .hook = hosts_hook,
     .help = "The addresses allowed to speak CIGI to this daemon, comma separated (IPv4 or IPv6 "
             "literals, at most 16): CIGI carries no credentials, so its authority is the "
             "sender's address. A datagram from any other is dropped and counted. Needs a "
             "restart to change."},
    {.name = "server.geo_origin", .type = CONF_STRING, .offset = SRV(geo_origin), .size = SRV_BIND_MAX,
     .def = "0,0", .hook = origin_hook,
     .help = "LAT,LON in degrees (WGS 84) of the point at the ocean's x = z = 0: CIGI's "
             "latitudes and longitudes map onto the ocean's plane about it (sim/geo.h: x "
             "north, z east). Needs a restart to change."},
    {.name = "server.max_entities", .type = CONF_INT, .offset = SRV(max_entities), .min = 1, .max = 4096,
     .def = "64",
     .help = "Entities (ships, aircraft: a CIGI host's Entity Control) the daemon's table holds "
             "at most; one more is refused. Needs a restart to change."},
    {.name = "server.entity_track_keep", .type = CONF_INT, .offset = SRV(entity_track_keep), .min = 16,
     .max = 1048576, .def = "256",
     .help = "Samples of each entity's track the daemon keeps, the newest: an instant before a "
             "track's oldest kept sample has no entity (a QUERY, a replay, a joining client). "
             "256 keep 4 s of a 60 Hz CIGI host, 256 s of a ship sampled each second; memory "
             "grows with the samples a track holds (64 bytes each), not with this. Needs a "
             "restart to change."},
    {.name = "server.entity_log", .type = CONF_STRING, .offset = SRV(entity_log), .size = SRV_PATH_MAX,
     .def = "",
     .help = "File of the entities' timeline: every entity entry the daemon enters (an ENTITY set "
             "or remove, a CIGI host's Entity Control, a replicated entry) is appended to it, and "
             "at start the daemon enters the file's entries first. A daemon restarted on it, or "
             "one started on a copy, holds the timeline a recording saw, so the recording "
             "replays its wakes. Empty: off. Needs a restart to change."},
    {.name = "server.sea_lead", .type = CONF_DOUBLE, .offset = SRV(sea_lead), .min = 0.05,
     .max = 3600, .def = "0.5", .unit = "s",
     .help = "With server.redis: a sea-state change must take effect at least this long after "
             "it is set, so it reaches every replica first; a nearer one is refused."},
    {.name = "server.workers", .type = CONF_INT, .offset = SRV(workers), .min = 1, .max = 64,
     .def = "2",
     .help = "Threads that encode tiles and build meshes each tick (besides FFTW's "
             "ocean.threads)."},
    {.name = "server.scene", .type = CONF_STRING, .offset = SRV(scene), .size = SRV_PATH_MAX,
     .def = "ship-bridge",
     .help = "Scene to serve: a name looked up as server.scene_dir/NAME.conf, or a path (a "
             "value with a '/' or ending in .conf); empty serves the sea above with every effect."},
    {.name = "server.scene_dir", .type = CONF_STRING, .offset = SRV(scene_dir),
     .size = SRV_PATH_MAX, .def = "config/scenes",
     .help = "Directory of scene files."},
    {.name = "server.codecs", .type = CONF_FLAGS, .offset = SRV(codecs), .min = 1,
     .names = codec_names, .def = "all",
     .help = "Tile codecs clients may choose (announced in HELLO); qz is the compact default."},
    {.name = "server.max_frame_rate", .type = CONF_DOUBLE, .offset = SRV(max_frame_rate),
     .min = 0.1, .max = 240, .def = "60", .unit = "Hz",
     .help = "Highest frame rate a client may subscribe to; frames are made on ticks, so "
             "above server.tick_rate a subscription is refused too (naming the tick rate)."},
    {.name = "server.max_tile_size", .type = CONF_INT, .offset = SRV(max_tile_size), .min = 2,
     .max = 1024, .def = "128", .unit = "samples",
     .help = "Largest tile side a client may ask for."},
    {.name = "server.max_lod_levels", .type = CONF_INT, .offset = SRV(max_lod_levels), .min = 1,
     .max = 16, .def = "8",
     .help = "Most tile LOD levels a client may ask for (each doubles the spacing)."},
    {.name = "server.tiles_per_side", .type = CONF_INT, .offset = SRV(tiles_per_side), .min = 1,
     .max = 8, .def = "2",
     .help = "Tiles per level around each camera, n x n, world aligned so the camera sits in "
             "the middle half of the block."},
    {.name = "server.base_spacing", .type = CONF_DOUBLE, .offset = SRV(base_spacing),
     .min = 0.001, .max = 10000, .def = "2", .unit = "m",
     .help = "Level-0 tile sample spacing for clients that leave it to the server."},
    {.name = "server.view_range", .type = CONF_DOUBLE, .offset = SRV(view_range), .min = 10,
     .max = 1e6, .def = "10000", .unit = "m",
     .help = "Mesh radius for clients that leave it to the server."},
    {.name = "server.mesh_error_px", .type = CONF_DOUBLE, .offset = SRV(mesh_error_px),
     .min = 0.1, .max = 64, .def = "16", .unit = "px",
     .help = "Screen-space error budget of the concentric mesh; larger means fewer vertices "
             "(16 px keeps a 20 m camera at 1080p near 5 800 vertices, 70 KB a frame; 4 px "
             "gives 73 000). Clients render fine detail from the tiles. Above sea.choppiness "
             "1.3 the spacing shrinks as 1.3 / choppiness, since the sideways error grows with "
             "it (about 10x the vertices at choppiness 5)."},
    {.name = "server.flat_mesh_error_px", .type = CONF_DOUBLE, .offset = SRV(flat_mesh_error_px),
     .min = 0.1, .max = 64, .def = "8", .unit = "px",
     .help = "The same budget for the mesh a layout-1 client (the browser viewer) displaces "
             "itself: its topology travels once per plan (camera height octave, field of "
             "view, viewport), not its vertices every frame, so it can be finer. At 8 px "
             "the crests 1-3 km out rise over the horizon from 5 m above a storm sea nearly "
             "as the exact sea's do (the sea's edge 5 rows over a flat sea's in a 10 deg "
             "view, the exact sea's 8; at 16 px, 2), for 3.3 times the topology's bytes (660 "
             "KB against 200 KB, 17 853 vertices against 5 425, for a 1080p camera 25 m up, "
             "once per plan)."},
    {.name = "server.px_per_sample", .type = CONF_DOUBLE, .offset = SRV(px_per_sample),
     .min = 0.5, .max = 1024, .def = "1", .unit = "px",
     .help = "Cascade tile layout: the finest detail wanted, as the pixels one tile sample "
             "spans on screen at its distance from the camera.  The viewer's byte budget "
             "(server.viewer_bytes_per_s) coarsens it where it would cost more; finer detail "
             "travels as unresolved slope variance for shading, a smooth lobe where the exact "
             "sea has glints.  Near the water the budget sets the plan; from 1.5 and 10 km the "
             "plan fits at 4 px, and 1 px spends the rest: against a render of the exact sea, "
             "SSIM 0.73 -> 0.78 and 0.84 -> 0.95 over the storm (`make bench`, bench_look)."},
    {.name = "server.cascade_tile", .type = CONF_INT, .offset = SRV(cascade_tile), .min = 8, .max = 256,
     .def = "32", .hook = tile_pow2_hook,
     .help = "Cascade tile layout: side of every tile, in samples (a mip smaller than this is one "
             "tile).  One size for every viewer, so every viewer shares every tile; smaller "
             "tiles fit a camera's footprint closer, larger ones compress a little better."},
    {.name = "server.viewer_bytes_per_s", .type = CONF_DOUBLE, .offset = SRV(viewer_bytes_per_s),
     .min = 1e4, .max = 1e10, .def = "0.85e6", .unit = "B/s",
     .help = "Cascade tile layout: tile bytes one viewer may receive per second at most (its "
             "frame budget is this over its frame rate); a viewer whose link carries less gets its "
             "frames planned for what its link delivers (PROTOCOL.md \"Pacing\").  A camera whose "
             "footprint needs more (a "
             "large viewport, a camera near the water) reads coarser mips until it fits, and "
             "each cascade then refines on its own, finest first, within what is left; the "
             "server plans with a fixed model of each codec's bytes per sample (the same on every replica; "
             "within 1 % of the measured qz bytes, `make bench`), a time-interpolating "
             "subscription's mips (the viewer's) each at its share per frame: 0.85e6 keeps the "
             "viewer under 1 MB/s with frame headers, flying at 60 m/s included (a plain "
             "subscription gets as many bytes of every tick's tiles)."},
    {.name = "server.max_query_points", .type = CONF_INT, .offset = SRV(max_query_points),
     .min = 1, .max = 65536, .def = "65536",
     .help = "Most points one QUERY may carry."},
    {.name = "server.max_pending_queries", .type = CONF_INT, .offset = SRV(max_pending_queries),
     .min = 1, .max = 1024, .def = "16",
     .help = "Queries a client may have unanswered; more are refused with an ERROR."},
    {.name = "server.replay_queue", .type = CONF_INT, .offset = SRV(replay_queue), .min = 1,
     .max = 100000, .def = "256",
     .help = "Replay-mode CAMERA reports a client may have waiting for their frames."},
    {.name = "server.replay_per_tick", .type = CONF_INT, .offset = SRV(replay_per_tick),
     .min = 1, .max = 1024, .def = "2",
     .help = "Replay frames built per client per tick at most; the rest of a client's replay "
             "queue waits for the next ticks.  All clients together take what the live frames "
             "leave of a tick (priced at each layout's measured cost of a replay frame), in turn, "
             "so replaying clients cannot delay everyone's tick."},
    {.name = "server.query_ms", .type = CONF_DOUBLE, .offset = SRV(query_ms), .min = 0.1,
     .max = 1000, .def = "4", .unit = "ms",
     .help = "Time the simulation thread spends on QUERY points per tick, all clients "
             "together (taken in turn); a large query is answered over several ticks."},
    {.name = "server.max_mesh_vertices", .type = CONF_INT, .offset = SRV(max_mesh_vertices),
     .min = 1000, .max = 1 << 30, .def = "262144",
     .help = "Largest mesh the server builds for one camera, priced from the camera before "
             "anything is built.  A concentric mesh above it (a camera near steep chop, a "
             "narrow field of view) is built at server.mesh_error_px (layout 1: flat_mesh_error_px) "
             "doubled until it fits, up "
             "to 100 px (the last step 100 px itself): a layout-0 client is told by one ERROR "
             "ETOOBIG naming both budgets, a layout-1 client reads the lattice it got in "
             "MESH_TOPOLOGY's zones.  Beyond that, "
             "or for the other mesh kinds, the client's frames come without a mesh, with one "
             "ERROR ETOOBIG naming this limit and the estimate."},
    {.name = "server.max_sample_rate", .type = CONF_DOUBLE, .offset = SRV(max_sample_rate),
     .min = 1000, .max = 1e12, .def = "8e6", .unit = "samples/s",
     .help = "Tile samples per second one subscription may ask for (tiles per level x "
             "levels x tile_size^2 x frame rate); above it SUBSCRIBE is refused (ETOOBIG)."},
    {.name = "server.admit_share", .type = CONF_DOUBLE, .offset = SRV(admit_share), .min = 0,
     .max = 1, .def = "0.7",
     .help = "Share of the cores the daemon can use (server.workers at most, less what other "
             "processes use, measured each second, half of them at least) that admitted work may take, the rest left "
             "as headroom for the clients already served.  A live layout-0 subscription is "
             "priced at its tile samples/s x planes x the cost of a plane-sample measured on "
             "this host for its codec; the shared work (evaluating the ocean, layout 1, meshes, "
             "frames, queries) is measured.  A SUBSCRIBE that would take the sum past the share "
             "is refused (ETOOBIG, naming each figure); layout 1 adds no tiles of its own and is "
             "always admitted.  0: no admission for the daemon as a whole (each subscription is "
             "still held to server.max_sample_rate)."},
    {.name = "server.near_field_waves", .type = CONF_INT, .offset = SRV(near_field_waves),
     .min = 0, .max = 1024, .def = "64",
     .help = "Gerstner waves of the near field (scenes with near-field), shorter than the "
             "finest cascade.  They are snapped to the lattice of a periodic patch of "
             "(ocean.n / 2 - 1) x server.near_field_min_wavelength, which layout 1 carries as "
             "one more cascade (with ocean.cascades = 4 there is no room: such a scene is "
             "refused)."},
    {.name = "server.near_field_radius", .type = CONF_DOUBLE, .offset = SRV(near_field_radius),
     .min = 1, .max = 10000, .def = "60", .unit = "m",
     .help = "The near field fades from full strength at half this radius to nothing at it, "
             "around each camera."},
    {.name = "server.near_field_min_wavelength", .type = CONF_DOUBLE,
     .offset = SRV(near_field_min_wavelength), .min = 0.0151, .max = 100, .def = "0.1",
     .unit = "m", .help = "Shortest near-field wavelength.  Shorter waves than 1.51 cm would "
     "oscillate faster than OCEAN_OMEGA_MAX = 64 rad/s in deep water, beyond what the exact-time "
     "limit is built on (sim/ocean_time.h)."},
    {.name = "server.record", .type = CONF_BOOL, .offset = SRV(record), .def = "off",
     .help = "Record every client's camera path (server/RECORDING.md)."},
    {.name = "server.record_clients", .type = CONF_BOOL, .offset = SRV(record_clients),
     .def = "off",
     .help = "Let a client ask for a recording with ?record=1 in its WebSocket URL; off, the "
             "request is ignored (logged)."},
    {.name = "server.record_max_files", .type = CONF_INT, .offset = SRV(record_max_files),
     .min = 0, .max = 1000000, .def = "100",
     .help = "Recordings the daemon opens per run; past it connections are not recorded."},
    {.name = "server.record_max_bytes", .type = CONF_U64, .offset = SRV(record_max_bytes),
     .min = 0, .max = 1e13, .def = "268435456", .unit = "bytes",
     .help = "Bytes the daemon writes to recordings per run, all files together; a "
             "recording that would pass it stops."},
    {.name = "server.record_dir", .type = CONF_STRING, .offset = SRV(record_dir),
     .size = SRV_PATH_MAX, .def = "recordings",
     .help = "Directory of camera-path recordings (created if missing)."},
    {.name = "server.verbose", .type = CONF_BOOL, .offset = SRV(verbose), .def = "off",
     .help = "Log every connection and refused message to stderr."},
};

static const conf_table srv_table = {
    .name = "server",
    .title = "daemon (server.*)",
    .entries = srv_entries,
    .count = sizeof srv_entries / sizeof srv_entries[0],
    .target_size = sizeof(srv_config),
};

const conf_table *srv_config_table(void) { return &srv_table; }

static void set_err(char *err, size_t errlen, const char *fmt, const char *a, const char *b)
{
    if (err && errlen) snprintf(err, errlen, fmt, a, b);
}

ocean_result srv_epoch_parse(const char *text, double *unix_s, char *why, size_t whylen)
{
    const char *p = text;
    char *end;
    int digits_only = *p != 0;
    for (const char *q = p; *q; q++)
        if (!((*q >= '0' && *q <= '9') || *q == '.')) digits_only = 0;
    if (digits_only) {
        double v = strtod(p, &end);
        if (*end || !isfinite(v) || v > 253402300799.0) goto bad;
        *unix_s = v;
        return OCEAN_OK;
    }
    int Y, M, D, h, m, sec, n = 0;
    if (sscanf(p, "%4d-%2d-%2d%*1[T ]%2d:%2d:%2d%n", &Y, &M, &D, &h, &m, &sec, &n) != 6 || n != 19)
        goto bad;
    static const int mdays[12] = {31, 29, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
    if (Y < 1970 || M < 1 || M > 12 || D < 1 || D > mdays[M - 1] || h > 23 || m > 59 || sec > 59 ||
        h < 0 || m < 0 || sec < 0)
        goto bad;
    if (M == 2 && D == 29 && !((Y % 4 == 0 && Y % 100 != 0) || Y % 400 == 0)) goto bad;
    p += n;
    double frac = 0;
    if (*p == '.') {
        double scale = 0.1;
        p++;
        if (*p < '0' || *p > '9') goto bad;
        while (*p >= '0' && *p <= '9') {
            frac += scale * (*p - '0');
            scale *= 0.1;
            p++;
        }
    }
    int off = 0;
    if (*p == 'Z' || *p == 'z') {
        p++;
    } else if (*p == '+' || *p == '-') {
        int oh, om, k = 0;
        if (sscanf(p + 1, "%2d:%2d%n", &oh, &om, &k) != 2 || k != 5 || oh > 23 || om > 59 || oh < 0 ||
            om < 0)
            goto bad;
        off = (*p == '-' ? -1 : 1) * (oh * 3600 + om * 60);
        p += 6;
    } else {
        goto bad; /* a local time would depend on the machine: refused */
    }
    if (*p) goto bad;
    /* days since 1970-01-01 (proleptic Gregorian; Howard Hinnant's
     * days_from_civil algorithm) */
    int y = Y - (M <= 2);
    long era = y / 400;
    long yoe = y - era * 400;
    long doy = (153L * (M + (M > 2 ? -3 : 9)) + 2) / 5 + D - 1;
    long doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    long days = era * 146097 + doe - 719468;
    *unix_s = (double)days * 86400.0 + h * 3600 + m * 60 + sec - off + frac;
    return OCEAN_OK;
bad:
    if (why)
        snprintf(why, whylen, "server.epoch '%.64s': expected Unix seconds or an ISO 8601 UTC time "
                 "like 2026-01-01T00:00:00Z (Z or +HH:MM required)", text);
    return OCEAN_EINVAL;
}

ocean_result srv_settings_default(srv_settings *s, char *err, size_t errlen)
{
    return srv_settings_load(NULL, NULL, 0, s, err, errlen);
}

/* The sea.* and ocean.* keys the file changed from their defaults that
 * the scene sets otherwise, and that stay as the scene set them (no --set
 * over them): the scene wins over the file, so an edit of such a key in
 * the file would otherwise change nothing, without a word.  Comparing
 * against the defaults keeps quiet about a file that spells every key out
 * at its default (the shipped one), which a scene is meant to override.
 * Writes "KEY = FILE (scene: SCENE), ..." into out, or "". */
static void scene_overrides(const ocean_params *file, const ocean_params *scene,
                            const ocean_params *final, char *out, size_t outlen)
{
    ocean_params def;
    ocean_params_default(&def);
    const conf_table *t = ocean_conf_table();
    size_t off = 0;
    out[0] = '\0';
    for (size_t i = 0; i < t->count; i++) {
        const conf_entry *e = &t->entries[i];
        if (e->flags & CONF_F_NOSTORE) continue; /* sea.beaufort: its sea.wind is compared */
        char f[96], d[96], sc[96], fi[96];
        conf_format(e, file, f, sizeof f);
        conf_format(e, &def, d, sizeof d);
        conf_format(e, scene, sc, sizeof sc);
        conf_format(e, final, fi, sizeof fi);
        if (!strcmp(f, d) || !strcmp(f, sc) || strcmp(fi, sc)) continue;
        if (off + 1 >= outlen) break;
        int w = snprintf(out + off, outlen - off, "%s%s = %s (scene: %s)", off ? ", " : "",
                         e->name, f, sc);
        off = w < 0 ? off : off + (size_t)w;
        if (off >= outlen) {
            /* cut at a whole entry: better fewer than a torn one */
            char *comma = strrchr(out, ',');
            if (comma) *comma = '\0';
            break;
        }
    }
}

/* The keys checked together, once every source is applied (each was
 * accepted alone); errors name every source (`from`). */
static ocean_result check_sea(srv_settings *tmp, const char *from, char *err, size_t errlen)
{
    /* The near field takes over where the FFT stops: with ocean.k_max = inf
     * the finest cascade would keep its whole square band and the Gerstner
     * set could not start above it without a gap or an overlap, so the band
     * is cut at the finest grid's Nyquist circle, pi n / L_finest. */
    if (tmp->effects & OCEAN_FX_NEAR_FIELD)
        ocean_gerstner_near_cut(&tmp->params, tmp->srv.near_field_waves);
    char msg[400];
    if (ocean_params_validate(&tmp->params, msg, sizeof msg) != OCEAN_OK) {
        set_err(err, errlen, "%s: %s", from, msg);
        return OCEAN_EINVAL;
    }
    /* Layout 1 carries the near field as one more periodic cascade after
     * the FFT's (srv_cascade.c); the protocol's cascade block holds
     * PROTO_MAX_LAYERS, so a scene needing more is refused here, with the
     * numbers, rather than served without its near field in silence. */
    if (srv_settings_near_cascade(tmp) && tmp->params.cascades + 1 > PROTO_MAX_LAYERS) {
        snprintf(msg, sizeof msg, "ocean.cascades = %d with the near-field effect (server.near_field_waves = %d) "
                 "needs %d layout-1 cascades (the near field is one more), above the protocol's %d: use "
                 "ocean.cascades <= %d, server.near_field_waves = 0, or drop near-field from scene.effects",
                 tmp->params.cascades, tmp->srv.near_field_waves, tmp->params.cascades + 1, PROTO_MAX_LAYERS,
                 PROTO_MAX_LAYERS - 1);
        set_err(err, errlen, "%s: %s", from, msg);
        return OCEAN_EINVAL;
    }
    return OCEAN_OK;
}

/* Keys that contradict each other, each accepted alone: a soft limit
 * above the hard one never acts; a largest message above what all
 * clients together may hold unfinished is never received whole. */
static ocean_result check_limits(const srv_settings *tmp, const char *from, char *err, size_t errlen)
{
    char msg[300];
    if (tmp->srv.output_soft > tmp->srv.output_hard) {
        snprintf(msg, sizeof msg, "server.output_soft %.0f is above server.output_hard %.0f: the soft limit "
                 "would never act; keep output_soft <= output_hard", (double)tmp->srv.output_soft,
                 (double)tmp->srv.output_hard);
        set_err(err, errlen, "%s: %s", from, msg);
        return OCEAN_EINVAL;
    }
    if ((double)tmp->srv.max_message > (double)tmp->srv.partial_total) {
        snprintf(msg, sizeof msg, "server.max_message %.0f is above server.partial_total %.0f: a message that "
                 "large could never be received whole; keep max_message <= partial_total",
                 (double)tmp->srv.max_message, (double)tmp->srv.partial_total);
        set_err(err, errlen, "%s: %s", from, msg);
        return OCEAN_EINVAL;
    }
    return OCEAN_OK;
}

/* Sim time is now - epoch; beyond the exact-time limit the ocean refuses
 * to evaluate (ocean_time.h), so say so now, not with a daemon that
 * serves no frames. */
static ocean_result check_epoch(const srv_settings *tmp, const char *from, char *err, size_t errlen)
{
    if (!tmp->srv.epoch[0]) return OCEAN_OK;
    double e = 0.0;
    char msg[200];
    if (srv_epoch_parse(tmp->srv.epoch, &e, msg, sizeof msg) != OCEAN_OK) {
        set_err(err, errlen, "%s: %s", from, msg);
        return OCEAN_EINVAL;
    }
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    double simt = (double)ts.tv_sec - e;
    if (ocean_time_ok(simt)) return OCEAN_OK;
    if (err)
        snprintf(err, errlen,
                 "%s: server.epoch '%.64s' puts the sim time now at %.0f s, beyond the exact-time limit of "
                 "+-%.0f s (OCEAN_TIME_MAX, 4.25 years): choose an epoch within 4.25 years of now",
                 from, tmp->srv.epoch, simt, OCEAN_TIME_MAX);
    return OCEAN_EINVAL;
}

static ocean_result check_together(srv_settings *tmp, const char *from, char *err, size_t errlen)
{
    ocean_result r = check_sea(tmp, from, err, errlen);
    if (r == OCEAN_OK) r = check_limits(tmp, from, err, errlen);
    if (r == OCEAN_OK) r = check_epoch(tmp, from, err, errlen);
    return r;
}

ocean_result srv_settings_load(const char *path, const char *const *sets, int nsets,
                               srv_settings *out, char *err, size_t errlen)
{
    srv_settings *tmp = calloc(1, sizeof *tmp);
    if (!tmp) return OCEAN_ENOMEM;
    ocean_params_default(&tmp->params);
    const conf_table *tables[] = {ocean_conf_table(), &srv_table};
    void *targets[] = {&tmp->params, &tmp->srv};
    conf_set set = {tables, targets, 2};
    ocean_result r = path ? conf_load_file(path, &set, NULL, err, errlen)
                          : conf_defaults(&set, err, errlen);
    /* The file's own sea and ocean, before --set and the scene: what
     * scene_overrides compares. */
    ocean_params file_params = tmp->params;
    for (int i = 0; r == OCEAN_OK && i < nsets; i++)
        r = conf_apply(sets[i], &set, err, errlen);
    /* What a check of the keys together names: every source that set them
     * (a key given by --set is not the scene file's fault). */
    char from[2 * SRV_PATH_MAX + 96];
    snprintf(from, sizeof from, "%.*s", SRV_PATH_MAX, path ? path : "(defaults)");
    if (r == OCEAN_OK && tmp->srv.scene[0]) {
        char sp[2 * SRV_PATH_MAX + 16];
        ocean_conf_scene_path(tmp->srv.scene_dir, tmp->srv.scene, sp, sizeof sp);
        r = ocean_conf_scene_load(sp, &tmp->params, &tmp->scene, err, errlen);
        size_t spl = strlen(sp);
        if (r == OCEAN_EINVAL && err && strncmp(err, sp, spl) == 0 && strncmp(err + spl, ": ", 2) == 0) {
            /* "scene: text" is the check of the scene over the base (a
             * parse error reads "scene:LINE: text" and stays the file's) */
            char why[2400];
            snprintf(why, sizeof why, "%s with its scene %s%s: %s", from, sp,
                     nsets > 0 ? " and the command line" : "", err + spl + 2);
            snprintf(err, errlen, "%s", why);
        }
        if (r == OCEAN_EIO && sp[0] != '/' && err && errlen) {
            /* The shipped config names its scenes relative to the source
             * tree (make install writes absolute ones): say so, and from
             * where the path was read. */
            char cwd[512], why[2400];
            if (!getcwd(cwd, sizeof cwd)) snprintf(cwd, sizeof cwd, "?");
            snprintf(why, sizeof why, "%s (server.scene '%s'; relative paths are read from the "
                     "working directory %s: start oceand in the source tree, or give "
                     "server.scene_dir or server.scene as an absolute path)", err, tmp->srv.scene, cwd);
            snprintf(err, errlen, "%s", why);
        }
        if (r == OCEAN_OK) {
            tmp->params = tmp->scene.params;
            tmp->effects = tmp->scene.effects;
            size_t fl = strlen(from);
            snprintf(from + fl, sizeof from - fl, " with its scene %.*s", SRV_PATH_MAX, sp);
        }
        /* --set wins over the scene for sea.* and ocean.* too. */
        for (int i = 0; r == OCEAN_OK && i < nsets; i++)
            r = conf_apply(sets[i], &set, err, errlen);
        if (r == OCEAN_OK && path)
            scene_overrides(&file_params, &tmp->scene.params, &tmp->params, tmp->overridden,
                            sizeof tmp->overridden);
    } else if (r == OCEAN_OK) {
        tmp->effects = OCEAN_SCENE_FX_ALL;
        tmp->scene.params = tmp->params;
        tmp->scene.effects = tmp->effects;
    }
    if (nsets > 0) {
        size_t fl = strlen(from);
        snprintf(from + fl, sizeof from - fl, " and the command line");
    }
    if (r == OCEAN_OK) r = check_together(tmp, from, err, errlen);
    if (r == OCEAN_OK) {
        snprintf(tmp->path, sizeof tmp->path, "%s", path ? path : "");
        *out = *tmp;
    }
    free(tmp);
    return r;
}

int srv_settings_near_cascade(const srv_settings *s)
{
    ocean_gerstner_params gp;
    return srv_settings_near_field(s, &s->params, &gp);
}

int srv_settings_near_field(const srv_settings *s, const ocean_params *p, ocean_gerstner_params *gp)
{
    if (!(s->effects & OCEAN_FX_NEAR_FIELD)) {
        ocean_gerstner_params_default(gp);
        return 0;
    }
    return ocean_gerstner_near_params(p, s->srv.near_field_waves, s->srv.near_field_min_wavelength, gp);
}

int srv_settings_layout1_cascades(const srv_settings *s)
{
    return s->params.cascades + srv_settings_near_cascade(s);
}

ocean_result srv_settings_dump(const srv_settings *s, FILE *f)
{
    if (!s || !f) return OCEAN_EINVAL;
    /* conf_dump only reads through the targets */
    const conf_table *tables[] = {ocean_conf_table(), &srv_table};
    void *targets[] = {(void *)&s->params, (void *)&s->srv};
    conf_set set = {tables, targets, 2};
    return conf_dump(f, &set, CONF_DUMP_HELP);
}
