/*
 * oceanclient.h - the C client library of oceand ("ocean.v1" over WebSocket).
 *
 * What a simulator links to see the shared sea: connect to a daemon, read its
 * HELLO, subscribe, report the camera, receive FRAMEs with their tiles
 * already decoded to float planes and their mesh vertices, ask point
 * queries, read and (with the admin token) set the sea state.  The wire
 * format is protocol/ (proto.h, codec.h); this library only moves and
 * decodes messages.  Built on libwebsockets (client side).  No globals.
 *
 * Objects
 *   oc_loop    one libwebsockets context and its event loop.  Many clients
 *              may share one loop (the load generator runs hundreds of
 *              connections on one); a client created without a loop owns a
 *              private one.
 *   oc_client  one connection.
 *   oc_frame   one decoded FRAME, owned by whoever took it (oc_frame_free).
 *
 * Threading contract
 *   Every oc_ function is safe to call from any thread: each loop has a
 *   mutex that guards the state of the loop and of all its clients, and
 *   sending only queues bytes and wakes the loop (lws_cancel_service).
 *   Exactly one thread services a loop at a time, in one of two ways:
 *    - caller-driven (default): the application calls oc_loop_service() or
 *      oc_service() regularly (e.g. once per simulation step).  Blocking
 *      calls (oc_client_connect_wait, oc_client_query, oc_client_next_frame
 *      with a timeout, oc_client_sea_state_set) service the loop themselves
 *      while they wait, so a single-threaded program needs nothing else.
 *      Do not call them from two threads at once on a caller-driven loop.
 *    - threaded: oc_loop_start() runs the service loop on a thread of the
 *      library until oc_loop_stop() / oc_loop_destroy().  Blocking calls
 *      then wait on a condition variable instead of servicing.
 *   Callbacks (oc_callbacks) always run on the servicing thread, with the
 *   loop's mutex NOT held: they may call any oc_ function except the
 *   blocking ones, oc_loop_service/oc_service and *_destroy.
 *
 * Frames
 *   Received FRAMEs go to the on_frame callback if one is set, else into a
 *   per-client queue of options.frame_queue frames (default 4) taken with
 *   oc_client_next_frame().  When the queue is full the OLDEST frame is
 *   dropped (latest wins, as the daemon does) and counted in
 *   oc_client_stats.frames_dropped.
 *   A stream subscribed with SUBSCRIBE flag PROTO_SUB_TIME_INTERP (the
 *   viewer's, oc_subscribe_default's) is not made of whole frames: each FRAME brings only the samples in time that
 *   are due and its view blends the samples the connection holds
 *   (PROTOCOL.md "Samples in time").  A client
 *   with decode_tiles (the default) applies every FRAME to its store on
 *   receipt, in order, so a dropped or skipped frame costs nothing; one with
 *   decode_tiles = 0 or header_only does not follow the stream (no view).
 *   Outside a client, decode one connection's frames in order through an
 *   oc_frame_stream; oc_frame_decode reads a frame alone, which such a
 *   stream's frames are not (KEY frames aside).
 *
 * Latency
 *   FRAME carries the sim time of its tick in the message header, but no
 *   server wall clock.  The library estimates tick-to-receipt latency as
 *     (recv_wall - sim_time) - min over this connection's received messages
 *     of (recv_wall - sim_time)
 *   i.e. it assumes the live sim clock runs at wall-clock rate and takes the
 *   fastest message seen (HELLO included) as zero delay, so it under-reads
 *   by the smallest one-way delay (microseconds on loopback).  In replay
 *   mode that estimate is meaningless; use camera_rtt_ms instead (time from
 *   sending the CAMERA a FRAME answers to receiving the FRAME).
 *
 * Errors: every fallible call returns an ocean_result (sim/ocean_result.h)
 * and, where it takes err/errlen, writes a human message naming the cause.
 * ERROR messages from the server are kept (oc_client_last_error) and given
 * to on_error; a blocking request the server refuses returns the ERROR's
 * code.
 */
#ifndef OCEANCLIENT_H
#define OCEANCLIENT_H

#include <stddef.h>
#include <stdint.h>

#include "oc_cascade.h"
#include "ocean_result.h"
#include "proto.h"

#define OC_VERSION "0.1.0"

/* ------------------------------------------------------------------ URLs */

#define OC_HOST_MAX 255
#define OC_PATH_MAX 1023

typedef struct oc_url {
    int tls;                      /* 1 for wss:// (needs an lws built with TLS) */
    char host[OC_HOST_MAX + 1];   /* name or address; IPv6 without brackets */
    int port;                     /* 1..65535; default 80 (ws) / 443 (wss) */
    char path[OC_PATH_MAX + 1];   /* starts with '/'; default "/" */
} oc_url;

/* Parses "ws://host[:port][/path]" (also "wss://", "[v6addr]" hosts).
 * OCEAN_EINVAL with a message naming the problem for anything else: another
 * scheme, empty host, port outside 1..65535 or not a number, user-info,
 * fragments, control characters, over-long host or path. */
ocean_result oc_url_parse(const char *url, oc_url *out, char *err, size_t errlen);

/* ------------------------------------------------------------------ loop */

typedef struct oc_loop oc_loop;

/* Makes a loop (one lws context, client side only).  *out NULL on failure.
 * wss:// uses OpenSSL's default CA store (SSL_CERT_FILE / SSL_CERT_DIR
 * apply), loaded per loop.  The loop leaves OpenSSL's global init to
 * OpenSSL: an lws 4.1 context made elsewhere in the process with
 * LWS_SERVER_OPTION_DO_SSL_GLOBAL_INIT while loops exist makes lws keep
 * those loops' TLS contexts (~0.85 MB each) when they are destroyed. */
ocean_result oc_loop_create(oc_loop **out, char *err, size_t errlen);
/* Stops the thread if running, closes every client still on the loop
 * (they must be destroyed by their owners before this call or are freed
 * here), frees the loop.  Accepts NULL. */
void oc_loop_destroy(oc_loop *l);
/* The longest oc_loop_service(l, 0) keeps reading while data keeps
 * arriving, in ms (it may overrun by the handling of one message). */
#define OC_SERVICE_DRAIN_MS 10

/* Services the loop for up to timeout_ms.  0 (or less): no waiting, but
 * everything ready now - every connection is read until nothing more has
 * arrived, so one call per simulation step keeps up with any stream the
 * machine can decode - stopping after OC_SERVICE_DRAIN_MS if data keeps
 * coming (a flood cannot hold the caller; the rest waits for the next
 * call).  Above 0: waits, and returns early once at least one message was
 * received or a connection changed state.  OCEAN_ESTATE if the loop runs
 * its own thread. */
ocean_result oc_loop_service(oc_loop *l, int timeout_ms);
/* Runs the service loop on a library thread (see threading contract). */
ocean_result oc_loop_start(oc_loop *l);
/* Stops and joins that thread; no-op if not running. */
void oc_loop_stop(oc_loop *l);

/* ---------------------------------------------------------------- frames */

/* One decoded tile of a FRAME. */
typedef struct oc_tile {
    proto_tile info;   /* level, codec, channels, size, origin, spacing,
                          error_bound; info.payload: the encoded bytes,
                          owned by the frame */
    int planes;        /* proto_tile_planes(info.channels) */
    float *data;       /* planes * width * height floats, plane after plane in
                          codec.h order (H, DX, DZ, NU, NV, FOAM, J); row-major,
                          row = z; NULL if the client was made with
                          decode_tiles = 0 or decoding failed (decode_result) */
    ocean_result decode_result;
} oc_tile;

/* A mesh topology (MESH_TOPOLOGY), shared by reference between the frames
 * that use it. */
typedef struct oc_topology {
    uint32_t mesh_id;
    uint8_t mesh_kind;          /* proto_mesh_kind */
    uint8_t lod_levels;
    uint32_t vertex_count;
    uint32_t index_count;
    const uint32_t *indices;    /* index_count, triangles CCW from above */
    const float *morph;         /* vertex_count */
    const uint8_t *level;       /* vertex_count */
    uint16_t flags;             /* PROTO_TOPO_FLAT: flat and zones are set */
    const float *flat;          /* FLAT: x, z per vertex relative to the
                                   placement origin (layout 1) */
    const float *zones;         /* FLAT: per level g_L, R_L, b_L, 0 */
} oc_topology;

struct oc_frame {
    proto_header hdr;           /* hdr.sim_time: the tick's sim time */
    proto_frame info;           /* cutoff_k, e_error, origin, camera_seq, tick,
                                   tile_count, has_mesh, layout; layout 0: mesh
                                   (vertex positions, relative to
                                   info.mesh.origin; has_mesh 2: sent as qz
                                   and decoded by the client with the
                                   topology); layout 1: cascades (the
                                   cascade block: camera, q, e_total, tail_mss,
                                   mip tables) and placement; info.tiles[i]
                                   equals tiles[i].info (tiles[i].info.cascade:
                                   a layout-1 tile's cascade) */
    oc_tile *tiles;             /* info.tile_count tiles */
    const oc_topology *topology;/* latest topology with info.mesh.mesh_id, or
                                   NULL (no mesh, or topology not received) */
    const uint8_t *raw;         /* the complete wire message */
    size_t raw_len;
    double recv_wall;           /* CLOCK_REALTIME seconds at full receipt */
    double latency_ms;          /* tick-to-receipt estimate (see top) */
    double camera_rtt_ms;       /* CAMERA sent -> this FRAME; -1 if unknown */
    uint64_t index;             /* 0, 1, 2 ... frames received by this client */
    /* Layout 1: the frame's tiles indexed per cascade and mip, for
     * oc_frame_sample, oc_frame_surface and oc_frame_mesh_positions
     * (oc_cascade.h); for a frame of a time-interpolating stream, the
     * blend at the frame's instant of the samples its connection holds
     * (oc_frame_view_tile lists them; tiles[] are only the samples this
     * frame brought).  NULL for layout 0, header-only or undecoded frames,
     * when the tiles do not fit the cascade block, or for a frame of a
     * time-interpolating stream decoded alone (view_result and view_error
     * say why; counted in oc_client_stats.decode_errors). */
    const oc_cascade_view *view;
    ocean_result view_result;
    char view_error[160];
};

/* Frees a frame taken from oc_client_next_frame, oc_frame_decode or
 * oc_frame_stream_decode.  Accepts NULL. */
void oc_frame_free(oc_frame *f);

/* The tiles frame f's view reads (0 without a view): a whole frame's own
 * decoded tiles, or, for a frame of a time-interpolating stream, the tiles
 * of its instant, each the blend (1 - w) A + w B of the samples held
 * (PROTOCOL.md "Samples in time"), for readers that take statistics over a
 * frame's tiles rather than its records. */
unsigned oc_frame_view_tile_count(const oc_frame *f);
/* Tile i of them: *info (payload NULL for a blended tile; for a blend,
 * channels are those both samples carry) and *data, its planes in codec
 * order (proto_tile_planes(info->channels) x width x height floats, owned
 * by the frame).  OCEAN_EINVAL for i out of range or a NULL argument. */
ocean_result oc_frame_view_tile(const oc_frame *f, unsigned i, proto_tile *info, const float **data);

/* Bytes of a FRAME that oc_frame_peek reads: header, fixed fields and a
 * layout-1 cascade block's fixed part. */
#define OC_FRAME_PEEK_BYTES (PROTO_HEADER_SIZE + 56 + PROTO_CASCADE_BLOCK_FIXED)

/* Reads the facts of a FRAME without its records, for readers that keep
 * only a message's first bytes (load generators; they cannot follow a
 * time-interpolating stream, whose frames need their records decoded in
 * order: oc_frame_stream_decode): msg holds the first
 * `have` bytes of a FRAME of `len` bytes whose header the caller checked
 * (proto_header_decode).  Fills f's fixed fields and, for layout 1, the
 * fixed part of f->cascades (count, order, q, camera, min_spacing_m,
 * e_total, tail_mss; not the entries), range-checked; *records_at (may be
 * NULL) gets the offset of the first record, after the cascade block.
 * Needs have >= 88 (layout 0) or OC_FRAME_PEEK_BYTES (layout 1): OCEAN_ETRUNC
 * otherwise, or when len cannot hold tile_count records (and the mesh
 * record); OCEAN_EINVAL / EFORMAT / ETYPE for bad fields. */
ocean_result oc_frame_peek(const uint8_t *msg, size_t have, size_t len, proto_frame *f, size_t *records_at,
                           char *err, size_t errlen);

/* Decodes one complete FRAME message (msg/len, copied) into a frame of its
 * own, as a client with decode_tiles = 1 would receive it: tiles decoded,
 * the layout-1 view built.  For tools that read recorded frames and for
 * tests.  recv_wall 0, latency and camera_rtt -1, topology NULL.  On
 * failure *out is NULL and err names the cause (a tile that does not
 * decode, or a layout-1 view that does not build, is an error here).
 * A frame of a time-interpolating stream is whole alone only when it is a
 * KEY frame; any other reads the samples of the frames before it and
 * fails here with OCEAN_ESTATE: decode those through an oc_frame_stream. */
ocean_result oc_frame_decode(const uint8_t *msg, size_t len, oc_frame **out, char *err, size_t errlen);

/* The frames of one connection read outside an oc_client (a reader of its
 * own socket, a recording): what a client does on receipt.  Each frame of
 * a time-interpolating stream goes into the stream's store of samples
 * (every frame, in the order received, from the first after SUBSCRIBE or
 * a KEY frame) and its view reads the blend at its instant; a whole frame
 * decodes as with oc_frame_decode.
 * Threading: a stream belongs to the one thread that reads its frames. */
typedef struct oc_frame_stream oc_frame_stream;

/* OCEAN_EINVAL for a NULL out, OCEAN_ENOMEM. */
ocean_result oc_frame_stream_create(oc_frame_stream **out);
/* Accepts NULL; frames already decoded stay valid. */
void oc_frame_stream_destroy(oc_frame_stream *s);
/* The next FRAME of the stream, as oc_frame_decode (same results; a frame
 * that fails is still applied to the store as far as it decoded, as a
 * client does).  A message that does not decode at all is not applied:
 * the frames after it may then read OCEAN_ESTATE or OCEAN_ENOTFOUND until
 * the next KEY frame. */
ocean_result oc_frame_stream_decode(oc_frame_stream *s, const uint8_t *msg, size_t len, oc_frame **out, char *err,
                                    size_t errlen);

/* Decodes the compressed mesh positions of a layout-0 frame with
 * has_mesh 2 (MESH_VERTICES_QZ) with the frame's topology t (same mesh_id
 * and vertex count): info.mesh.positions points at them afterwards, owned
 * by the frame.  A client decodes them on receipt (the frames it hands out
 * have positions whenever it holds the topology; decode_errors counts the
 * others); this is for frames from oc_frame_decode, which has no topology
 * (their info.mesh.positions is NULL until then).  OCEAN_OK for a frame
 * with f32 positions; OCEAN_ESTATE for a frame without a layout-0 mesh;
 * OCEAN_EINVAL for a topology that does not match; OCEAN_ECODEC for a
 * payload that does not decode. */
ocean_result oc_frame_mesh_decode(oc_frame *f, const oc_topology *t, char *err, size_t errlen);

/* --------------------------------------------------------------- clients */

typedef struct oc_client oc_client;

typedef struct oc_callbacks {
    void *user;
    /* A decoded FRAME, borrowed for the duration of the call.  When set,
     * frames are not queued. */
    void (*on_frame)(void *user, oc_client *c, const oc_frame *f);
    /* Every message received, before any other processing: the raw bytes
     * (one complete wire message) and its decoded form (NULL if it failed
     * to decode; then res is the reason; with header_only a FRAME has only
     * its header and fixed fields).  For recorders and tools. */
    void (*on_message)(void *user, oc_client *c, const uint8_t *raw, size_t len,
                       const proto_msg *msg, ocean_result res);
    /* An ERROR message from the server. */
    void (*on_error)(void *user, oc_client *c, const proto_error *e);
    /* A SEA_STATE announcement. */
    void (*on_sea_state)(void *user, oc_client *c, const proto_sea_state *s);
    /* An ENTITY announce or gone (PROTOCOL.md "ENTITY"): an entity's newest
     * sample, or its leaving; this client's own sets come back so too. */
    void (*on_entity)(void *user, oc_client *c, const proto_entity *e);
    /* The connection ended: after BYE (reason, message from it), a close
     * frame, or a failed connect (reason -1, message says why). */
    void (*on_close)(void *user, oc_client *c, int bye_reason, const char *message);
} oc_callbacks;

typedef struct oc_options {
    const char *url;          /* ws://host:port/ (required) */
    oc_loop *loop;            /* shared loop, or NULL for a private one */
    oc_callbacks cb;
    int frame_queue;          /* queued frames when on_frame is NULL (4), 1..1024 */
    int decode_tiles;         /* 1: decode tile payloads to floats (default);
                                 0: tiles stay encoded and there is no view,
                                 so a time-interpolating stream is not
                                 followed (see "Frames" above) */
    int header_only;          /* 1: FRAMEs are checked (header, length) and
                                 only their fixed fields read (oc_frame.info:
                                 cutoff_k, e_error, origin, camera_seq, tick,
                                 tile_count, has_mesh, layout and a layout-1
                                 cascade block's fixed part (oc_frame_peek);
                                 tiles NULL, info.tiles NULL, no mesh data,
                                 no view): for load generators,
                                 whose own CPU must not limit the test.
                                 A time-interpolating stream is then not
                                 followed: its frames are counted, never
                                 read.  Other messages are decoded fully.
                                 (0) */
    uint32_t max_message;     /* largest message accepted, bytes
                                 (PROTO_MAX_MESSAGE_DEFAULT) */
    const char *origin;       /* Origin header, NULL: none */
} oc_options;

/* Defaults as noted above; url NULL. */
void oc_options_default(oc_options *o);

typedef enum oc_state {
    OC_CONNECTING = 0,  /* TCP/WebSocket handshake or waiting for HELLO */
    OC_READY = 1,       /* HELLO received */
    OC_CLOSED = 2       /* closed or failed; see oc_client_last_error */
} oc_state;

/* Starts connecting (non-blocking): parses the URL, makes the private loop
 * if needed and queues the connect, which the servicing thread issues
 * (lws_client_connect_via_info, subprotocol PROTO_SUBPROTOCOL) on its next
 * pass; progress happens while the loop is serviced, and a refused or
 * failed connect shows as OC_CLOSED with the reason in
 * oc_client_last_error.  OCEAN_EINVAL for a bad URL or options, or a NULL
 * o or out (err says which).  On any failure *out is NULL (out permitting). */
ocean_result oc_client_create(const oc_options *o, oc_client **out, char *err, size_t errlen);

/* Closes the connection (sends BYE NORMAL and a close frame when it can
 * within a short grace period) and frees the client.  Frames already taken
 * stay valid.  Accepts NULL. */
void oc_client_destroy(oc_client *c);

/* oc_client_create + oc_client_connect_wait; on failure *out is NULL and err
 * says why. */
ocean_result oc_connect(const oc_options *o, int timeout_ms, oc_client **out, char *err,
                        size_t errlen);

/* Waits until HELLO arrived (OCEAN_OK), the connection failed (OCEAN_EIO)
 * or timeout_ms passed (OCEAN_ESTATE). */
ocean_result oc_client_connect_wait(oc_client *c, int timeout_ms);

oc_state oc_client_state(const oc_client *c);
oc_loop *oc_client_loop(const oc_client *c);
/* oc_loop_service on the client's loop. */
ocean_result oc_service(oc_client *c, int timeout_ms);

/* The HELLO (OCEAN_ESTATE before it arrived). */
ocean_result oc_client_hello(const oc_client *c, proto_hello *out);

/* The sim time of the latest message received (HELLO's at first) whose
 * header carries the server's clock (not an ENTITY's, which carries the
 * instant its entry takes effect, nor a WAKE's): the server's clock as
 * last seen, for queries "now" at an explicit time.  NAN before HELLO. */
double oc_client_sim_time(const oc_client *c);

/* Text and code of the most recent failure on this client ("" and
 * OCEAN_OK if none): an ERROR from the server, a call that failed (bad
 * arguments, a full send queue, a timeout: "timed out after N ms: ..."),
 * an undecodable message, or the end of the connection (the BYE's or
 * close frame's text, else why it was lost), which replaces any earlier
 * one.  An empty oc_client_next_frame poll (timeout 0) is not a failure. */
ocean_result oc_client_last_error(const oc_client *c, char *buf, size_t buflen);

/* The qz accuracy of oc_subscribe_default (the viewer's: height tiles >=
 * 50 dB PSNR at about 1/8.5 of f32 with qz format 2, PROTOCOL.md "qz"), as
 * a double. */
#define OC_ACCURACY_DEFAULT 5e-3

/* A SUBSCRIBE with the library's defaults, the browser viewer's
 * (clients/web): layout 1 (shared cascade tiles; the library sums the
 * cascades and displaces the mesh: oc_frame_sample,
 * oc_frame_mesh_positions), samples in time (flags
 * PROTO_SUB_TIME_INTERP: each mip travels once per its own update
 * interval - a quarter of the bytes at ship-bridge for the same plan,
 * which the daemon spends on finer mips within its byte budget - and each
 * frame's view blends two samples the connection holds, within the
 * codec's error at `accuracy`; a client that decodes its frames follows the stream by
 * itself, but a reader of headers only, of frames alone (oc_frame_decode)
 * or of some of a connection's frames cannot: it clears the flag, or
 * decodes every frame in order (oc_frame_stream; "Frames" at the top),
 * every effect, every cascade (layers 4; the
 * server sends those it has), concentric mesh, codec qz at accuracy
 * OC_ACCURACY_DEFAULT (5e-3), 64-sample tiles, antialias cutoff policy,
 * live at 30 Hz, 8 LOD levels
 * (layout 0 only), server default spacing and range.  Subscribing as the
 * viewer does lets the daemon serve the library the very tile encodings it
 * already made for viewers.  Set layout = 0 for server-summed world tiles
 * and server-displaced mesh vertices, which then travel compressed
 * (mesh_codec qz, MESH_VERTICES_QZ at `accuracy`; the library decodes
 * them, so info.mesh.positions holds floats as with f32); set mesh_codec
 * to PROTO_MESH_CODEC_F32 for raw f32 positions.  oc_client_subscribe
 * sends mesh_codec 0 for layout 1, which ignores it. */
void oc_subscribe_default(proto_subscribe *s);

/* Sends SUBSCRIBE (validated by the encoder first).  May be sent again to
 * change the subscription.  OCEAN_ESTATE before READY, OCEAN_EIO once the
 * connection closed (every send does the same). */
ocean_result oc_client_subscribe(oc_client *c, const proto_subscribe *s);

/* A level camera at (0, 20, 0), 60 degree fov, 1920x1080, at rest. */
void oc_camera_default(proto_camera *cam);

/* Messages a client queues before the socket takes them (every kind but
 * the BYE of oc_client_destroy), and their bytes: beyond either, sends fail
 * with OCEAN_ERATE ("send queue full", oc_client_last_error) until the
 * loop has been serviced.  A caller-driven loop writes only while it is
 * serviced. */
#define OC_SEND_QUEUE_MAX 1024u
#define OC_SEND_QUEUE_MAX_BYTES (8u << 20)

/* Sends CAMERA.  *seq_out (may be NULL) gets the message's seq, which the
 * answering FRAME carries as info.camera_seq.
 * Live mode (the last SUBSCRIBE's mode; live before any): only the newest
 * camera matters, so a CAMERA still queued unsent is replaced by this one,
 * which takes its seq (*seq_out then repeats it): reporting the camera
 * every simulation step never queues stale ones.
 * Replay mode: cam->render_time names the sim time to render; each CAMERA
 * is a request answered by one FRAME and is never replaced, so a
 * caller-driven loop must be serviced between them: beyond
 * OC_SEND_QUEUE_MAX queued messages the call fails with OCEAN_ERATE.
 * The daemon limits every client to server.msg_rate messages per second
 * (200 in the shipped config, bursts up to server.msg_burst, 400) and at
 * most server.replay_queue (256) unanswered replay CAMERAs; beyond, it
 * refuses with ERROR ERATE (on_error, oc_client_last_error): a client
 * stepping faster than ~100 Hz should not send a CAMERA every step. */
ocean_result oc_client_send_camera(oc_client *c, const proto_camera *cam, uint32_t *seq_out);

/* Takes the oldest queued frame, waiting up to timeout_ms (0: no wait,
 * -1: forever).  OCEAN_OK and *out, or OCEAN_ESTATE on timeout (*out NULL;
 * last_error "timed out after N ms" unless timeout_ms is 0) or OCEAN_EIO
 * once the connection is closed and the queue empty. */
ocean_result oc_client_next_frame(oc_client *c, int timeout_ms, oc_frame **out);

/* Latest topology received (borrowed; valid until the client is destroyed
 * or a new topology with the same id replaces it - frames keep theirs). */
const oc_topology *oc_client_topology(oc_client *c);

/* ---------------------------------------------------------------- queries */

typedef struct oc_query_result {
    uint32_t query_id;
    double t;                      /* sim time evaluated */
    uint32_t count;
    proto_query_sample *samples;   /* count, owned: oc_query_result_free */
} oc_query_result;

void oc_query_result_free(oc_query_result *r);   /* accepts NULL; zeroes r */

/* Callback of an asynchronous query: res is OCEAN_OK and r the answer
 * (borrowed), or the ERROR's code (r NULL), or OCEAN_EIO if the connection
 * closed first. */
typedef void (*oc_query_fn)(void *user, oc_client *c, ocean_result res,
                            const oc_query_result *r);

/* Sends QUERY for n points xz[2i], xz[2i+1] (world x, z in double).
 * at_time 0: the latest tick (t ignored); 1: at sim time t; any other
 * value is refused (OCEAN_EINVAL).  The answer
 * goes to fn (on the servicing thread).  *query_id (may be NULL) gets the
 * id.  OCEAN_EINVAL for n = 0, n above the server's limit or non-finite
 * input. */
ocean_result oc_client_query_async(oc_client *c, const double *xz, size_t n, int at_time,
                                   double t, oc_query_fn fn, void *user, uint32_t *query_id);

/* Blocking query: as above, waiting up to timeout_ms for the answer.
 * OCEAN_OK and *out filled (free with oc_query_result_free), the server's
 * ERROR code, OCEAN_EIO if the connection closed, OCEAN_ESTATE on
 * timeout. */
ocean_result oc_client_query(oc_client *c, const double *xz, size_t n, int at_time, double t,
                             int timeout_ms, oc_query_result *out);

/* -------------------------------------------------------------- sea state */

/* The sea state last announced (HELLO or SEA_STATE ANNOUNCE), with its
 * effective time, which may lie ahead (a pending change): for the sea of a
 * given tick use oc_client_sea_at.  OCEAN_ESTATE before HELLO. */
ocean_result oc_client_sea_state(const oc_client *c, proto_sea *out, double *effective_time);

/* Entries of the sea-state timeline a client keeps (older ones are dropped). */
#define OC_SEA_TIMELINE_MAX 64

/* The ships' wakes at one point: height (m), its slopes, and the bound on
 * |height - the exact sum of the same waves| (m). */
typedef struct oc_wake {
    double height, dhdx, dhdz, error;
} oc_wake;

/* The ships' wakes at the n points xz (x, z pairs) at sim time t, as the
 * server answers them: the entities in force at t by the ENTITY entries
 * received (each from its header sim_time), each ship's steady wake read
 * from the WAKE patterns received (PROTOCOL.md "WAKE"), over the depth of
 * the sea in force at t, and the rotorcraft's downwash from their tracks
 * alone (PROTOCOL.md "QUERY").  A subscription (either layout) receives the
 * patterns of the ships whose wakes reach its view range.  OCEAN_ESTATE: a pattern
 * a ship there needs has not come yet (or no HELLO); OCEAN_EINVAL: a point
 * not finite; OCEAN_ENOMEM. */
ocean_result oc_client_wakes(oc_client *c, double t, const double *xz, size_t n, oc_wake *out);

/* The sea in force at sim time t by the timeline the server sent (HELLO's
 * sea, then every announce from its effective time; PROTOCOL.md "Sea-state
 * timeline"): what every client and the server use for a tick at t.
 * *effective_time (may be NULL) gets the entry's time (-inf for HELLO's).
 * OCEAN_ESTATE before HELLO, OCEAN_EINVAL for a non-finite t. */
ocean_result oc_client_sea_at(const oc_client *c, double t, proto_sea *out, double *effective_time);

/* Sends SEA_STATE SET with the admin token and waits up to timeout_ms for
 * the server's ANNOUNCE (OCEAN_OK) or ERROR about it (its code, e.g.
 * OCEAN_EAUTH; text via oc_client_last_error).  OCEAN_ESTATE on timeout. */
ocean_result oc_client_sea_state_set(oc_client *c, const proto_sea *sea, double effective_time,
                                     const char *token, int timeout_ms);

/* Asks the server for its timeline (SEA_STATE get) and waits up to
 * timeout_ms for the state in force now and the sim time it took effect
 * (the answer's first announce: its effective time is not after the
 * message's own sim time, which tells it from a pending change's).
 * HELLO's sea carries no time of its own: a client that joined after a
 * change learns when it took effect this way.  OCEAN_ESTATE on timeout
 * or while another SEA_STATE request of this client waits. */
ocean_result oc_client_sea_state_fetch(oc_client *c, int timeout_ms, proto_sea *out, double *effective_time);

/* Sends ENTITY (PROTOCOL.md "ENTITY"): op set (a track sample, entering
 * the entity if new) or remove, each with the entity token, or get (every
 * entity's newest sample comes back).  It does not wait: the server's
 * announces come to on_entity, a refusal to on_error.  The fields are
 * checked as the server's decoder checks them (OCEAN_EINVAL, EFORMAT or
 * ETYPE, last_error says which); OCEAN_ERATE when the send queue is full.
 * The daemon takes 120 sets a second from a connection after a burst of
 * 240: a host stepping at 60 Hz may move two entities every step. */
ocean_result oc_client_send_entity(oc_client *c, const proto_entity *e);

/* ------------------------------------------------------------------ stats */

typedef struct oc_client_stats {
    uint64_t messages_rx, bytes_rx;     /* every message received */
    uint64_t messages_tx, bytes_tx;
    uint64_t frames_rx;                 /* FRAMEs received */
    uint64_t frames_dropped;            /* dropped from a full queue */
    uint64_t frames_gap;                /* frames the server skipped for us
                                           (latest wins): from gaps in
                                           info.tick beyond the expected step
                                           round(tick_rate / frame_rate) */
    uint64_t decode_errors;             /* messages or tiles that failed */
    uint64_t errors_rx;                 /* ERROR messages */
    uint64_t wakes_rx;                  /* WAKE patterns kept */
    uint64_t wakes_refused;             /* WAKEs whose pattern could not be read */
    uint64_t entity_refused;            /* ENTITY entries the client's table refused */
} oc_client_stats;

void oc_client_get_stats(const oc_client *c, oc_client_stats *out);

#endif
