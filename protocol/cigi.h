/*
 * cigi.h - the CIGI packets an ocean image generator reads and writes
 * (Common Image Generator Interface, SISO-STD-013): pure encode/decode of
 * UDP datagrams, for the daemon's CIGI service and the host example.
 *
 * A datagram is a message: packets end to end, each opening with its
 * opcode and size.  CIGI 3 (3.2 and 3.3 layouts) packs opcode and size in
 * one byte each and its sender writes every multi-byte field in its own
 * byte order, told by the magic 0x8000 in the first packet (IG Control or
 * Start of Frame); CIGI 4.0 packs size then opcode in 16 bits each, and
 * its byte order is told by the first packet's size (24: one of its bytes
 * is zero).  A reader learns both from the first packet (cigi_format_of)
 * and then reads packet by packet (cigi_reader_next); every packet whose
 * opcode is not one of ours is skipped by its size.  Every layout, with
 * the sources it was checked against, is in protocol/CIGI.md; the fields
 * are described once, in one table per version (cigi.c), which the
 * encoder and the decoder both read.
 *
 * Values: integer fields (bit fields included) in uint32_t members, int8
 * fields in int32_t, float32 and float64 fields in double.  The decoder
 * checks layouts and sizes, not values: a NaN latitude is a valid packet,
 * refused by whoever acts on it (cigi_packet_check says why).
 *
 * Threads: pure functions; a cigi_reader belongs to its caller.
 */
#ifndef PROTO_CIGI_H
#define PROTO_CIGI_H

#include <stddef.h>
#include <stdint.h>

#include "ocean_result.h"
#include "proto_buf.h"

typedef enum cigi_kind {
    CIGI_UNKNOWN = 0,         /* an opcode this codec does not read: skipped */
    CIGI_IG_CONTROL,          /* host -> IG, first in every host message */
    CIGI_ENTITY_CONTROL,      /* 3.x: state and position; 4.0: state */
    CIGI_ENTITY_POSITION,     /* 4.0 only: position, attitude, clamp */
    CIGI_ATMOSPHERE_CONTROL,  /* 3.x only: the global wind */
    CIGI_WEATHER_CONTROL,
    CIGI_MARITIME_CONTROL,    /* Maritime Surface Conditions Control */
    CIGI_WAVE_CONTROL,
    CIGI_HAT_HOT_REQUEST,
    CIGI_ENV_REQUEST,         /* Environmental Conditions Request */
    CIGI_START_OF_FRAME,      /* IG -> host, first in every IG message */
    CIGI_HAT_HOT_RESPONSE,
    CIGI_HAT_HOT_XRESPONSE,   /* HAT/HOT Extended Response */
    CIGI_MARITIME_RESPONSE,   /* Maritime Surface Conditions Response */
    CIGI_KIND_COUNT_
} cigi_kind;

/* A message's version and byte order. */
typedef struct cigi_format {
    uint8_t major;            /* 3 or 4 */
    uint8_t minor;            /* 3.x: 2 or 3 (the 24-byte IG Control and SOF) */
    uint8_t big_endian;       /* multi-byte fields most significant byte first */
} cigi_format;

/* HAT/HOT request types and coordinate systems, Entity Control clamps. */
enum { CIGI_HAT = 0, CIGI_HOT = 1, CIGI_HAT_HOT_EXTENDED = 2 };
enum { CIGI_COORD_GEODETIC = 0, CIGI_COORD_ENTITY = 1 };
enum { CIGI_CLAMP_NONE = 0, CIGI_CLAMP_NONCONFORMAL = 1, CIGI_CLAMP_CONFORMAL = 2 };
enum { CIGI_ENTITY_INACTIVE = 0, CIGI_ENTITY_ACTIVE = 1, CIGI_ENTITY_DESTROYED = 2 };
enum { CIGI_SCOPE_GLOBAL = 0, CIGI_SCOPE_REGIONAL = 1, CIGI_SCOPE_ENTITY = 2 };
/* Environmental Conditions Request: bits of its request type */
enum { CIGI_ENV_MARITIME = 1, CIGI_ENV_TERRESTRIAL = 2, CIGI_ENV_WEATHER = 4, CIGI_ENV_AEROSOL = 8 };

typedef struct cigi_ig_control {
    int32_t database;
    uint32_t ig_mode, timestamp_valid, frame, timestamp, last_ig_frame;  /* timestamp: 10 us ticks */
} cigi_ig_control;

typedef struct cigi_start_of_frame {
    int32_t database;
    uint32_t ig_status, ig_mode, timestamp_valid, earth_model, frame, timestamp, last_host_frame;
} cigi_start_of_frame;

/* Entity Control (3.x) and, split in two, Entity Control / Entity
 * Position (4.0): the fields one packet lacks stay 0. */
typedef struct cigi_entity {
    uint32_t id, state, attach, clamp, type, parent;
    double roll, pitch, yaw;        /* deg */
    double lat, lon, alt;           /* deg, deg, m (child: body offsets, m) */
} cigi_entity;

typedef struct cigi_atmosphere {
    uint32_t enable, humidity;
    double air_temp, visibility, wind_h, wind_v, wind_dir, pressure;  /* wind_dir: deg, from */
} cigi_atmosphere;

typedef struct cigi_weather {
    uint32_t region, layer, humidity, enable, scope, severity;
    double air_temp, visibility, base, thickness, transition;
    double wind_h, wind_v, wind_dir, pressure;
} cigi_weather;

typedef struct cigi_maritime_control {
    uint32_t region, enable, whitecaps, scope;
    double surface_height, water_temp, clarity;
} cigi_maritime_control;

typedef struct cigi_wave {
    uint32_t region, wave_id, enable, scope, breaker;
    double height, wavelength, period, direction, phase, leading;  /* height: trough to crest */
} cigi_wave;

typedef struct cigi_hat_hot_request {
    uint32_t id, type, coord, period, entity;
    double lat, lon, alt;           /* or x, y, z offsets from the entity */
} cigi_hat_hot_request;

typedef struct cigi_env_request {
    uint32_t type, id;
    double lat, lon, alt;
} cigi_env_request;

typedef struct cigi_hat_hot_response {
    uint32_t id, valid, type, frame_lsn;
    double height;
} cigi_hat_hot_response;

typedef struct cigi_hat_hot_xresponse {
    uint32_t id, valid, frame_lsn, material;
    double hat, hot, normal_az, normal_el;  /* deg */
} cigi_hat_hot_xresponse;

typedef struct cigi_maritime_response {
    uint32_t id;
    double surface_height, water_temp, clarity;
} cigi_maritime_response;

typedef struct cigi_packet {
    cigi_kind kind;
    uint16_t opcode, size;          /* as on the wire */
    union {
        cigi_ig_control ig;
        cigi_start_of_frame sof;
        cigi_entity entity;
        cigi_atmosphere atmosphere;
        cigi_weather weather;
        cigi_maritime_control maritime;
        cigi_wave wave;
        cigi_hat_hot_request hat_req;
        cigi_env_request env_req;
        cigi_hat_hot_response hat_resp;
        cigi_hat_hot_xresponse hat_xresp;
        cigi_maritime_response maritime_resp;
    } u;
} cigi_packet;

/* The format of the message d[0..n): its first packet must be IG Control
 * or Start of Frame of CIGI 3.2/3.3 or 4.0.  OCEAN_ETRUNC, OCEAN_EFORMAT
 * (not an IG Control or SOF, bad magic), OCEAN_EVERSION (another version),
 * each with a message in why. */
ocean_result cigi_format_of(const uint8_t *d, size_t n, cigi_format *out, char *why, size_t why_len);

typedef struct cigi_reader {
    const uint8_t *d;
    size_t n, off;
    cigi_format fmt;
} cigi_reader;

void cigi_reader_init(cigi_reader *r, const uint8_t *d, size_t n, const cigi_format *fmt);

/* The next packet into *p (kind CIGI_UNKNOWN for one skipped by its
 * size); *done = 1 and nothing read at the end of the message.  A packet
 * whose size is 0, not a multiple of 8 or under its layout's
 * (OCEAN_EFORMAT), or runs past the message (OCEAN_ETRUNC), ends the
 * reading: what follows it cannot be framed. */
ocean_result cigi_reader_next(cigi_reader *r, cigi_packet *p, int *done, char *why, size_t why_len);

/* Appends p (its kind's layout in format f; p->opcode and p->size are
 * ignored) to b.  IG Control and Start of Frame carry f's version and, in
 * 3.x, the byte-order magic.  OCEAN_EUNSUPPORTED: the kind has no layout
 * in that version; OCEAN_ENOMEM. */
ocean_result cigi_put(proto_buf *b, const cigi_format *f, const cigi_packet *p);

/* OCEAN_OK if p's values are ones an image generator can act on (finite
 * numbers, latitudes and longitudes in range, enumerations known), else
 * OCEAN_EINVAL with why. */
ocean_result cigi_packet_check(const cigi_packet *p, char *why, size_t why_len);

/* The kind's name ("HAT/HOT Request"), for logs and metrics. */
const char *cigi_kind_name(cigi_kind k);

#endif
