/*
 * proto.h - the oceand wire protocol "ocean.v1": message structs and their
 * encoders/decoders.  Pure functions over bytes; no sockets, no threads, no
 * global state.  PROTOCOL.md is the normative description of every byte;
 * this header is its C binding.
 *
 * Decoding: proto_decode() checks the header, then every length, count, enum
 * and float of the payload before use; it never reads outside [buf, buf+len)
 * and refuses NaN/Inf wherever a number must be finite.  Failures give a
 * specific ocean_result and a human message:
 *   OCEAN_ETRUNC   shorter than the header, or the payload/count says more
 *                  bytes than there are
 *   OCEAN_EFORMAT  bad magic, trailing bytes, reserved bits/bytes not zero,
 *                  bad UTF-8, structural inconsistency
 *   OCEAN_EVERSION header version is not PROTO_VERSION
 *   OCEAN_ETYPE    unknown message type or enum value (codec, mesh kind ...)
 *   OCEAN_ETOOBIG  message, string or count beyond the limits
 *   OCEAN_EINVAL   NaN/Inf or a value outside its documented range
 *   OCEAN_ENOMEM   allocation failed
 * proto_error_reply() builds the ERROR message a server sends back.
 *
 * Ownership: a decoded proto_msg owns all of its variable-length data
 * (tiles, tile payloads, points, indices, positions, samples); call
 * proto_msg_free() when done.  The input buffer may be released right after
 * proto_decode() returns.  For encoding the caller fills a proto_msg whose
 * pointers point at the caller's memory; encoding never takes ownership.
 */
#ifndef PROTO_H
#define PROTO_H

#include <stddef.h>
#include <stdint.h>

#include "codec.h"
#include "entity.h"
#include "ocean_result.h"
#include "proto_buf.h"

#define PROTO_SUBPROTOCOL "ocean.v1"
#define PROTO_MAGIC 0x574E434Fu   /* bytes "OCNW" */
#define PROTO_VERSION 1
#define PROTO_HEADER_SIZE 32

/* Default decoder limits (a server may lower max_message). */
#define PROTO_MAX_MESSAGE_DEFAULT (64u << 20)
#define PROTO_MAX_QUERY_POINTS 65536u
#define PROTO_MAX_FRAME_TILES 4096u
#define PROTO_TILE_SPACING_MAX 1e6  /* TILE.spacing, m (PROTOCOL.md, TILE) */
#define PROTO_MAX_VERTICES (1u << 22)
#define PROTO_MAX_INDICES (3u << 23)
#define PROTO_MAX_LEVEL 31
#define PROTO_MAX_LOD_LEVELS 16
#define PROTO_MAX_LAYERS 4
#define PROTO_MAX_FRAME_RATE 240.0f

/* Maximum string lengths in bytes (UTF-8, no terminator on the wire). */
#define PROTO_VERSION_STR_MAX 63
#define PROTO_TOKEN_MAX 255
#define PROTO_ERROR_MSG_MAX 1023
#define PROTO_BYE_MSG_MAX 255

typedef enum proto_type {
    PROTO_HELLO = 1,
    PROTO_SUBSCRIBE = 2,
    PROTO_CAMERA = 3,
    PROTO_FRAME = 4,
    PROTO_TILE = 5,
    PROTO_MESH_TOPOLOGY = 6,
    PROTO_MESH_VERTICES = 7,
    PROTO_QUERY = 8,
    PROTO_QUERY_RESULT = 9,
    PROTO_SEA_STATE = 10,
    PROTO_ERROR = 11,
    PROTO_BYE = 12,
    PROTO_ENTITY = 13,
    PROTO_WAKE = 14,
    PROTO_TYPE_END_
} proto_type;

enum proto_effect {
    PROTO_FX_HEIGHT = 1,
    PROTO_FX_DISPLACEMENT = 2,
    PROTO_FX_NORMALS = 4,
    PROTO_FX_FOAM = 8,
    PROTO_FX_NEAR_FIELD = 16,
    PROTO_FX_ALL = 31
};

typedef enum proto_mesh_kind {
    PROTO_MESH_CONCENTRIC = 0,
    PROTO_MESH_CHUNKED = 1,
    PROTO_MESH_PROJECTED = 2,
    PROTO_MESH_NONE = 3,
    PROTO_MESH_KIND_COUNT_
} proto_mesh_kind;

typedef enum proto_cutoff_policy {
    PROTO_CUTOFF_NONE = 0,
    PROTO_CUTOFF_SEED = 1,
    PROTO_CUTOFF_ANTIALIAS = 2,
    PROTO_CUTOFF_POLICY_COUNT_
} proto_cutoff_policy;

typedef enum proto_mode {
    PROTO_MODE_LIVE = 0,
    PROTO_MODE_REPLAY = 1,
    PROTO_MODE_COUNT_
} proto_mode;

/* What travels per camera (SUBSCRIBE.layout; PROTOCOL.md "Layouts"). */
typedef enum proto_layout {
    PROTO_LAYOUT_WORLD = 0,    /* per-camera summed world tiles, mesh displaced by the server */
    PROTO_LAYOUT_CASCADE = 1,  /* shared per-cascade mip tiles, the client displaces */
    PROTO_LAYOUT_COUNT_
} proto_layout;

/* SUBSCRIBE.mesh_codec: how a layout-0 FRAME carries mesh positions (the
 * values are those of the tile codecs they resemble). */
typedef enum proto_mesh_codec {
    PROTO_MESH_CODEC_F32 = 0,  /* MESH_VERTICES: raw f32 (FRAME.has_mesh 1) */
    PROTO_MESH_CODEC_QZ = 2    /* MESH_VERTICES_QZ (FRAME.has_mesh 2) */
} proto_mesh_codec;

/* Cascade layout limits: mips per cascade and mip-table entries (mips + 1). */
#define PROTO_MAX_MIPS 12
#define PROTO_MIP_ENTRIES 13
#define PROTO_CASCADE_BLOCK_FIXED 56
#define PROTO_CASCADE_ENTRY_SIZE 320
/* Cascade block flags: KEY, the client drops every sample it holds before
 * it reads this frame's records (PROTOCOL.md "Samples in time"); FOAM, the
 * whitecap table follows the cascade entries (PROTOCOL.md "Whitecaps in
 * layout 1"); READ (only with FOAM), the read table follows the whitecap
 * table. */
#define PROTO_CASCADE_KEY 1u
#define PROTO_CASCADE_FOAM 2u
#define PROTO_CASCADE_READ 4u
/* The read table: per cascade, per mip m < PROTO_MAX_MIPS, one u16 per
 * kernel a reader interpolates a mip with (PROTOCOL.md "Whitecaps in
 * layout 1"). */
enum {
    PROTO_READ_BILINEAR = 0,  /* GL's bilinear filter */
    PROTO_READ_KEYS = 1,      /* Keys (1981) cubic convolution, a = -1/2 */
    PROTO_READ_LANCZOS3 = 2,  /* Lanczos a = 3, normalised (Duchon 1979) */
    PROTO_READ_KERNELS = 3
};
#define PROTO_READ_ENTRY_SIZE (2 * PROTO_READ_KERNELS * PROTO_MAX_MIPS)
/* The whitecap table: rows, and its bytes (u8 rows, 7 reserved, 16 rows of
 * 3 f32). */
#define PROTO_FOAM_ROWS 16
#define PROTO_FOAM_TABLE_SIZE (8 + 12 * PROTO_FOAM_ROWS)
/* A layout-1 tile record's tag: the cascade index, and this bit for sample
 * B of the mip's time window (clear: sample A). */
#define PROTO_TAG_SLOT_B 0x100u
#define PROTO_MESH_PLACEMENT_SIZE 32
/* MESH_TOPOLOGY.flags bit: flat positions and level zones follow. */
#define PROTO_TOPO_FLAT 1u

typedef enum proto_sea_op {
    PROTO_SEA_ANNOUNCE = 0,  /* server -> client: the state in force from effective_time */
    PROTO_SEA_SET = 1,       /* client -> server: admin request, needs the token */
    PROTO_SEA_GET = 2,       /* client -> server: ask for the timeline (no token; the
                              * sea block all zero bytes, effective_time 0) */
    PROTO_SEA_OP_COUNT_
} proto_sea_op;

typedef enum proto_entity_op {
    PROTO_ENTITY_ANNOUNCE = 0, /* server -> client: an entity's shape and newest sample */
    PROTO_ENTITY_SET = 1,      /* client -> server: a track sample, entering the entity if new
                                * (needs the entity token) */
    PROTO_ENTITY_REMOVE = 2,   /* client -> server: take entity id out (needs the token) */
    PROTO_ENTITY_GET = 3,      /* client -> server: ask for every entity (no token, every
                                * field zero) */
    PROTO_ENTITY_GONE = 4,     /* server -> client: entity id left the sea */
    PROTO_ENTITY_OP_COUNT_
} proto_entity_op;

/* How long an entity goes on at its last sample's velocity before it holds
 * still, and how long a removed entity's past is kept, s (PROTOCOL.md
 * "ENTITY"): the server's table and every reader's use the same. */
#define PROTO_ENTITY_HOLD_S OCEAN_ENTITY_HOLD_S
#define PROTO_ENTITY_PAST_S 120.0

/* Entity kinds as sim/entity.h numbers them. */
#define PROTO_ENTITY_KIND_COUNT 3

typedef enum proto_bye_reason {
    PROTO_BYE_NORMAL = 0,
    PROTO_BYE_SHUTDOWN = 1,
    PROTO_BYE_SLOW_CONSUMER = 2,
    PROTO_BYE_PROTOCOL_ERROR = 3,
    PROTO_BYE_AUTH = 4,
    PROTO_BYE_SERVER_FULL = 5,
    PROTO_BYE_IDLE = 6,
    PROTO_BYE_REASON_COUNT_
} proto_bye_reason;

#define PROTO_NO_CAMERA 0xFFFFFFFFu

/* The fixed header of every message (32 bytes on the wire). */
typedef struct proto_header {
    uint16_t version;   /* PROTO_VERSION */
    uint16_t type;      /* proto_type */
    uint32_t flags;     /* 0 in version 1 */
    uint32_t length;    /* payload bytes after the header */
    uint32_t seq;       /* sender's message counter, +1 per message, wraps */
    double sim_time;    /* sender's simulation time, s (finite) */
} proto_header;

/* Sea state as carried by HELLO and SEA_STATE.  Enum values as in
 * sim/spectrum.h (spectrum 0..3, spreading 0..3). */
/* proto_sea.flags */
#define PROTO_SEA_NO_WHITECAPS 0x01   /* no whitecaps: foam 0 everywhere */
#define PROTO_SEA_FLAGS_ALL 0x01

typedef struct proto_sea {
    uint8_t spectrum;
    uint8_t spreading;
    uint8_t flags;      /* PROTO_SEA_* */
    uint64_t seed;
    double wind_u10, wind_dir_deg, fetch_m, depth_m, swell, phillips_a, small_wave_m, choppiness;
    double hs, tp;      /* informational: significant height, peak period (0 unknown) */
} proto_sea;

typedef struct proto_hello {
    uint32_t codecs;          /* bit c set: codec c supported */
    uint8_t mesh_kinds;       /* bit k set: proto_mesh_kind k supported */
    uint8_t effects;          /* PROTO_FX_* the server can compute */
    uint8_t cutoff_policies;  /* bit p set: policy p supported */
    uint8_t modes;            /* bit m set: proto_mode m supported */
    uint32_t max_message;     /* largest client message accepted, bytes */
    uint32_t max_query_points;
    uint16_t max_tile_size;
    uint8_t max_lod_levels;
    uint8_t max_layers;
    float tick_rate_hz;
    float max_frame_rate_hz;
    uint32_t client_id;
    proto_sea sea;
    char server_version[PROTO_VERSION_STR_MAX + 1];
} proto_hello;

typedef struct proto_subscribe {
    uint8_t effects;          /* PROTO_FX_* mask, non-zero */
    uint8_t mesh_kind;        /* proto_mesh_kind */
    uint8_t codec;            /* proto_codec */
    uint8_t cutoff_policy;    /* proto_cutoff_policy */
    uint8_t mode;             /* proto_mode */
    uint8_t layers;           /* cascades wanted, 1..PROTO_MAX_LAYERS */
    uint8_t lod_levels;       /* tile LOD levels, 1..PROTO_MAX_LOD_LEVELS */
    uint16_t tile_size;       /* samples per tile side, 2..PROTO_TILE_MAX_SIZE */
    float frame_rate_hz;      /* (0, PROTO_MAX_FRAME_RATE] */
    float accuracy;           /* qz accuracy target, PROTO_ACCURACY_MIN..MAX */
    float base_spacing_m;     /* level-0 sample spacing; 0 = server default */
    float view_range_m;       /* radius served; 0 = server default */
    uint8_t layout;           /* proto_layout */
    uint8_t mesh_codec;       /* layout 0: how mesh positions travel,
                                 PROTO_MESH_CODEC_F32 (raw f32, FRAME.has_mesh
                                 1) or PROTO_MESH_CODEC_QZ (MESH_VERTICES_QZ at
                                 `accuracy`, has_mesh 2); layout 1 ignores it */
    uint8_t flags;            /* PROTO_SUB_* bits */
} proto_subscribe;

/* SUBSCRIBE.flags. */
enum {
    /* Layout 1: every mip carries height and displacement, whatever the
     * mesh (the frames' geometry_spacing_m is 0), for a client that reads
     * heights finer than its mesh shows; costs the bytes the normals-only
     * mips save. */
    PROTO_SUB_FULL_GEOMETRY = 1,
    /* Layout 1: the client holds each mip's tiles from frame to frame and
     * blends two samples in time; each mip's samples then travel once per
     * its update interval, not once per frame (PROTOCOL.md "Samples in
     * time"). */
    PROTO_SUB_TIME_INTERP = 2,
    PROTO_SUB_FLAGS_ALL = 3
};

typedef struct proto_camera {
    double pos[3];            /* world x, y (up), z, m */
    float vel[3];             /* m/s */
    float yaw_deg, pitch_deg, roll_deg;  /* see PROTOCOL.md "Camera orientation" */
    float fov_y_deg;          /* (0, 180) */
    uint16_t viewport_w, viewport_h;     /* 1..16384 */
    double render_time;       /* replay mode: sim time to render; live: 0 */
} proto_camera;

typedef struct proto_tile {
    uint8_t level;            /* 0..PROTO_MAX_LEVEL, spacing doubles per level */
    uint8_t codec;            /* proto_codec */
    uint16_t channels;        /* PROTO_CH_* mask */
    uint16_t width, height;   /* samples, 1..PROTO_TILE_MAX_SIZE */
    int32_t ix, iz;           /* tile index in its level's world grid */
    double origin_x, origin_z;/* world position of sample (0, 0), m */
    double spacing;           /* m between samples, > 0 */
    float error_bound;        /* max |decoded - simulated| over all samples, >= 0 */
    uint32_t payload_len;
    const uint8_t *payload;   /* codec bytes (see codec.h) */
    uint8_t cascade;          /* not in the TILE body: a layout-1 FRAME record's
                                 tag (the cascade index); 0 otherwise */
    uint8_t slot;             /* layout 1, from the tag: 0 sample A, 1 sample B */
} proto_tile;

/* One entry of a cascade's mip table (layout 1). */
typedef struct proto_mip_entry {
    float kc;                 /* mip's Butterworth cutoff, rad/m (+inf: none);
                                 entry `mips`: 0 */
    float mss_x, mss_z, mss_xz; /* slope moments of the cascade's waves the mip
                                   does not hold */
    uint16_t held[PROTO_READ_KERNELS]; /* with READ, entries 0..mips-1: the
                                   share of the mip's breaking-index variance
                                   a reading with each kernel holds, / 32768
                                   (1..65535: Lanczos' overshoot holds more
                                   than 1); else 0 */
} proto_mip_entry;

/* When mip m's samples were taken (layout 1, PROTOCOL.md "Samples in
 * time").  interval 0: at the frame's own time (every entry field 0). */
typedef struct proto_mip_time {
    uint32_t tick_a;          /* tick of sample A, mod 2^32; B is tick_a + interval */
    uint16_t interval;        /* ticks between samples */
    uint16_t phase;           /* the frame reads (1 - w) A + w B, w = phase / 65536 */
} proto_mip_time;

/* What a client holding a mip's window (valid, tick_a, interval) does
 * with the frame's time entry t (PROTOCOL.md "Samples in time", step 2). */
typedef enum proto_window_step {
    PROTO_WINDOW_KEEP,        /* the same window */
    PROTO_WINDOW_SHIFT,       /* B becomes A, B empty */
    PROTO_WINDOW_DROP         /* both samples dropped */
} proto_window_step;
proto_window_step proto_window_next(int valid, uint32_t tick_a, uint16_t interval, const proto_mip_time *t);

typedef struct proto_cascade_entry {
    double patch_m;
    uint16_t n;               /* grid of mip 0, power of two */
    uint8_t mips;             /* 1..PROTO_MAX_MIPS mips that hold waves */
    uint8_t fades;            /* 1: fades out of geometry beyond its last mip */
    float spacing_per_m;      /* q_c: this cascade's spacing wanted per metre of
                                 distance, > 0 and <= the block's */
    proto_mip_entry mip[PROTO_MIP_ENTRIES]; /* entries 0..mips; the rest 0 */
    proto_mip_time time[PROTO_MAX_MIPS];    /* entries 0..mips-1; the rest 0 */
} proto_cascade_entry;

/* One row of the whitecap table: the ramp of a band whose breaking index
 * has std sigma (PROTOCOL.md "Whitecaps in layout 1"). */
typedef struct proto_foam_row {
    float sigma;              /* the band's breaking-index std, >= 0; rows ascend */
    float a;                  /* the ramp's foot (foam 0 at beta = a, 1 at 1/2) */
    float omega;              /* the band's mean frequency, rad/s, >= 0 (0: no trails) */
} proto_foam_row;

/* The cascade block of a layout-1 FRAME (PROTOCOL.md "Cascade block"). */
typedef struct proto_cascade_block {
    uint8_t cascade_count;    /* 1..PROTO_MAX_LAYERS */
    uint8_t order;            /* Butterworth order of the mips, 1..64 */
    uint8_t flags;            /* PROTO_CASCADE_KEY, _FOAM, _READ */
    float spacing_per_m;      /* q: the coarsest cascade's spacing wanted per metre
                                 of distance, > 0 (each entry has its own) */
    double camera[3];         /* camera position the frame was made for */
    float min_spacing_m;      /* >= 0 */
    float e_total;            /* [0, 1] */
    float tail_mss[3];        /* x, z, xz moments no cascade holds, >= 0 (xz any sign) */
    float geometry_spacing_m; /* G >= 0: height and displacement are read at
                                 max(s_c, G); a mip with 2^(m+1) sigma_c <= G
                                 carries no H, DX, DZ.  0: no such floor */
    proto_cascade_entry cascade[PROTO_MAX_LAYERS];
    uint8_t foam_rows;        /* with PROTO_CASCADE_FOAM: 1..PROTO_FOAM_ROWS, else 0 */
    proto_foam_row foam[PROTO_FOAM_ROWS]; /* rows 0..foam_rows-1; the rest 0 */
} proto_cascade_block;

/* Bytes of a cascade block of `count` cascades with `flags`. */
size_t proto_cascade_block_bytes(unsigned count, unsigned flags);

/* Where a layout-1 FRAME places the flat mesh. */
typedef struct proto_mesh_placement {
    uint32_t mesh_id;
    double origin[3];
} proto_mesh_placement;

/* A pre-encoded FRAME record (proto_tile_record_encode), for servers that
 * encode a tile once and copy it into many FRAMEs. */
typedef struct proto_bytes {
    const uint8_t *p;
    size_t len;
} proto_bytes;

typedef struct proto_mesh_vertices {
    uint32_t mesh_id;
    uint32_t vertex_count;
    double origin[3];         /* world position the vertices are relative to */
    const float *positions;   /* 3 * vertex_count floats x, y, z; in a FRAME
                                 with has_mesh 2: NULL as decoded (the client
                                 decodes qz with the topology:
                                 proto_mesh_qz_decode), unused to encode */
    const uint8_t *qz;        /* FRAME has_mesh 2: the MESH_VERTICES_QZ
                                 payload from its format byte on
                                 (proto_mesh_qz_encode), qz_len bytes */
    uint32_t qz_len;
} proto_mesh_vertices;

typedef struct proto_frame {
    double cutoff_k;          /* Butterworth cutoff used, rad/m; +inf: unfiltered */
    double e_error;           /* spectral energy error of the cutoff, 0..1 */
    double origin[3];         /* world origin of the frame */
    uint32_t camera_seq;      /* seq of the CAMERA this answers, or PROTO_NO_CAMERA */
    uint32_t tick;            /* server tick counter (wraps) */
    uint16_t tile_count;
    const proto_tile *tiles;
    uint8_t has_mesh;         /* 0 none; 1 mesh (layout 0: f32 positions);
                                 2 (layout 0 only): positions as qz */
    proto_mesh_vertices mesh; /* layout 0, valid when has_mesh */
    uint8_t layout;           /* proto_layout */
    const proto_bytes *tile_records; /* encoding only: when non-NULL, tile_count
                                        pre-encoded records used instead of tiles */
    const uint32_t *record_tags;     /* encoding only, with tile_records: each
                                        record's tag (cascade | PROTO_TAG_SLOT_B)
                                        written over the one it was made with;
                                        NULL keeps those */
    proto_mesh_placement placement; /* layout 1, valid when has_mesh */
    proto_cascade_block cascades;   /* layout 1 */
} proto_frame;

typedef struct proto_mesh_topology {
    uint32_t mesh_id;
    uint8_t mesh_kind;        /* concentric, chunked or projected */
    uint8_t lod_levels;       /* 1..PROTO_MAX_LOD_LEVELS */
    uint32_t vertex_count;
    uint32_t index_count;     /* multiple of 3 */
    const uint32_t *indices;  /* triangles, counter-clockwise seen from above */
    const float *morph;       /* per vertex 0..1 */
    const uint8_t *level;     /* per vertex < lod_levels */
    uint16_t flags;           /* PROTO_TOPO_FLAT */
    const float *flat;        /* FLAT: 2 * vertex_count floats x, z */
    const float *zones;       /* FLAT: 4 * lod_levels floats: lattice spacing,
                                 zone radius, blend half-width, 0 */
} proto_mesh_topology;

typedef struct proto_query {
    uint32_t query_id;
    uint32_t count;           /* 1..limit */
    uint8_t at_time;          /* 0: latest tick, 1: at t */
    double t;
    const double *points;     /* 2 * count doubles: x, z */
} proto_query;

/* One answered point of a QUERY (9 floats on the wire). */
typedef struct proto_query_sample {
    float height;
    float normal[3];
    float velocity[3];
    float foam;
    float error_bound;
} proto_query_sample;

typedef struct proto_query_result {
    uint32_t query_id;
    uint32_t count;
    double t;                 /* sim time evaluated */
    const proto_query_sample *samples;
} proto_query_result;

typedef struct proto_sea_state {
    uint8_t op;               /* proto_sea_op */
    double effective_time;    /* sim time the state takes effect */
    proto_sea sea;
    char token[PROTO_TOKEN_MAX + 1];  /* SET: admin token; ANNOUNCE, GET: empty */
} proto_sea_state;

/* ENTITY: a ship, rotorcraft or aircraft in the sea (PROTOCOL.md "ENTITY"). */
typedef struct proto_entity {
    uint8_t op;               /* proto_entity_op */
    uint8_t kind;             /* 0 ship, 1 rotorcraft, 2 aircraft */
    uint32_t id;
    double t;                 /* sim time of the sample */
    double x, z;              /* world position, m */
    float altitude_m, heading_deg, speed;
    float length_m, beam_m, draught_m;
    char token[PROTO_TOKEN_MAX + 1];  /* SET, REMOVE: the entity token; others empty */
} proto_entity;

typedef struct proto_error {
    uint16_t code;            /* ocean_result, non-zero */
    uint16_t offending_type;  /* type of the refused message, 0 if unknown */
    uint32_t offending_seq;   /* its seq, 0 if unknown */
    char message[PROTO_ERROR_MSG_MAX + 1];
} proto_error;

typedef struct proto_bye {
    uint16_t reason;          /* proto_bye_reason */
    char message[PROTO_BYE_MSG_MAX + 1];
} proto_bye;

/* WAKE: one ship's steady wake pattern, sent once to a reader that places
 * it along the entity's track (PROTOCOL.md "WAKE"). */
typedef struct proto_wake {
    double speed, length, beam, depth;  /* the pattern's parameters (depth +inf: deep) */
    uint16_t nx, nz;          /* coefficients along and across the track, 1..PROTO_PLANE_MAX_SIZE */
    uint8_t codec;            /* proto_codec of the payload: one plane of nx x nz (proto_plane_encode) */
    float error_bound;        /* bound on |reading - exact series| for 1 m of head, >= 0 */
    uint32_t payload_len;
    const uint8_t *payload;
} proto_wake;

/* Wake patterns a reader keeps: the server counts on it holding the last
 * PROTO_WAKE_HELD it received. */
#define PROTO_WAKE_HELD 32

typedef struct proto_msg {
    proto_header hdr;         /* hdr.type selects the union member */
    union {
        proto_hello hello;
        proto_subscribe subscribe;
        proto_camera camera;
        proto_frame frame;
        proto_tile tile;
        proto_mesh_topology topology;
        proto_mesh_vertices vertices;
        proto_query query;
        proto_query_result result;
        proto_sea_state sea_state;
        proto_error error;
        proto_bye bye;
        proto_entity entity;
        proto_wake wake;
    } u;
    void *owned_;             /* decoder's allocations; see proto_msg_free */
} proto_msg;

typedef struct proto_limits {
    uint32_t max_message;     /* total bytes incl. header */
    uint32_t max_query_points;
    uint32_t max_frame_tiles;
    uint32_t max_vertices;
    uint32_t max_indices;
} proto_limits;

void proto_limits_default(proto_limits *l);

/* Zeroes m and sets hdr.version and hdr.type. */
void proto_msg_init(proto_msg *m, proto_type type);

/* Frees what proto_decode allocated into m and zeroes m.  Accepts NULL and
 * messages that own nothing (e.g. ones filled by hand for encoding). */
void proto_msg_free(proto_msg *m);

/* Name of a message type ("HELLO", ...), "?" if unknown. */
const char *proto_type_name(unsigned type);

/* Reads and checks only the 32-byte header (magic, version, type, flags,
 * reserved, sim_time, and length against len and limits).  Useful to reject
 * early or to learn the type/seq of a message that fails to decode. */
ocean_result proto_header_decode(const void *buf, size_t len, const proto_limits *lim,
                                 proto_header *out, char *err, size_t errlen);

/* Decodes one complete message (one WebSocket binary message) with the
 * default limits.  On success *msg owns its data (proto_msg_free).  On
 * failure *msg is zeroed except that msg->hdr holds whatever of the header
 * could be read, and err gets a message naming the field. */
ocean_result proto_decode(const void *buf, size_t len, proto_msg *msg, char *err, size_t errlen);
/* As proto_decode with explicit limits (NULL: defaults). */
ocean_result proto_decode_limited(const void *buf, size_t len, const proto_limits *lim,
                                  proto_msg *msg, char *err, size_t errlen);

/* Reads the fixed fields of a FRAME body (the first 51 bytes after the
 * header, PROTOCOL.md) into f without checking them and without touching
 * tiles or mesh: for readers that only want a frame's facts (a load
 * generator).  p must hold at least 51 bytes; the caller validates. */
void proto_frame_fixed_read(const uint8_t *p, proto_frame *f);

/* Where the per-viewer fields of an encoded FRAME sit, so one encoding can
 * serve several viewers whose frames differ only there (the sender
 * rewrites them per send): *camera_seq_at gets the byte offset of
 * camera_seq from the start of msg, *mesh_id_at that of the mesh record's
 * mesh_id (0 when the frame carries no mesh).  msg/len is one whole
 * message as proto_encode wrote it; OCEAN_EFORMAT when it is not a FRAME
 * whose records fit in len (nothing is written then). */
ocean_result proto_frame_client_fields(const uint8_t *msg, size_t len, size_t *camera_seq_at,
                                       size_t *mesh_id_at);

/* Validates msg exactly as the decoder would and appends its encoding to
 * out.  On failure out is unchanged. */
ocean_result proto_encode(proto_buf *out, const proto_msg *msg, char *err, size_t errlen);

/* Builds the ERROR reply for a message that failed with `code`/`why`:
 * the offending type and seq are taken from the bad message's header when
 * its first 32 bytes are readable (0 otherwise).  seq and sim_time are the
 * reply's own header fields.  The message text is truncated to fit. */
ocean_result proto_error_reply(proto_buf *out, const void *bad, size_t badlen, ocean_result code,
                               const char *why, uint32_t seq, double sim_time);

/* Appends to out one FRAME record (u32 length, u32 tag, TILE body, zero
 * padding to 8) holding t, after validating t as the encoder would: the
 * bytes a server encodes once and copies into many FRAMEs through
 * proto_frame.tile_records.  tag is the cascade index of a layout-1 tile
 * (0..PROTO_MAX_LAYERS-1); 0 for layout 0.  On failure out is unchanged. */
ocean_result proto_tile_record_encode(proto_buf *out, const proto_tile *t, uint32_t tag, char *err,
                                      size_t errlen);

/* Size in bytes of the encoded TILE body (without header) for t. */
size_t proto_tile_body_size(const proto_tile *t);

#endif
