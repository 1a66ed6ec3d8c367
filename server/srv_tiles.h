/*
 * srv_tiles.h - tiles around a camera in world-aligned levels, sampled from
 * an evaluated ocean frame, encoded with a protocol codec, and cached so
 * co-located viewers share the encoded bytes.
 *
 * Level L has sample spacing base * 2^L; its tiles hold size x size samples
 * and tile (ix, iz) starts at world (ix, iz) * size * spacing, so a tile's
 * position depends only on the level grid, never on a camera: two viewers
 * near each other ask for the same keys.  A key is everything the bytes
 * depend on: (time, cutoff bucket, boost, cascades, level, ix, iz, size,
 * spacing, channels, codec, accuracy).
 *
 * Threads: the cache is used by the simulation thread; srv_tile_build may
 * run on several worker threads at once for distinct entries.
 */
#ifndef SRV_TILES_H
#define SRV_TILES_H

#include <stddef.h>
#include <stdint.h>

#include "codec.h"
#include "ocean.h"
#include "proto.h"
#include "proto_buf.h"

typedef struct srv_tile_key {
    double t;          /* sim time of the evaluation */
    double spacing;    /* m */
    int32_t bucket;    /* cutoff bucket (-1: unfiltered query group) */
    float boost;       /* low-frequency boost of the evaluation */
    float accuracy;    /* qz accuracy */
    int32_t ix, iz;
    uint16_t channels; /* PROTO_CH_* */
    uint16_t size;
    uint8_t level, codec, layers;
    uint8_t layout;    /* PROTO_LAYOUT_*: 1 = a cascade tile (level = mip) */
    uint8_t cascade;   /* layout 1 */
    uint8_t pad_[3];
} srv_tile_key;

typedef struct srv_tile {
    srv_tile_key key;
    uint64_t hash;
    uint64_t last_use;     /* generation of the last tick that used it */
    int ready;             /* encoded (result == OK) or failed */
    ocean_result result;
    uint8_t *payload;      /* layout 0: the codec payload; layout 1: the whole
                              FRAME record (proto_tile_record_encode) */
    uint32_t payload_len;
    float error_bound;
    struct srv_tile *next; /* hash chain */
} srv_tile;

typedef struct srv_tile_cache srv_tile_cache;

ocean_result srv_tiles_create(srv_tile_cache **out);
void srv_tiles_destroy(srv_tile_cache *c);  /* accepts NULL */

/* Zeroes padding and fills a key. */
void srv_tile_key_init(srv_tile_key *k);

/* Finds or inserts the entry for k and marks it used in generation gen.
 * *fresh is 1 for a new (not yet built) entry.  NULL on OOM. */
srv_tile *srv_tiles_get(srv_tile_cache *c, const srv_tile_key *k, uint64_t gen, int *fresh);
/* Drops every entry last used before generation keep_from, and counts
 * what the rest take (srv_tiles_bytes). */
void srv_tiles_sweep(srv_tile_cache *c, uint64_t keep_from);
/* Drops everything (the sea changed). */
void srv_tiles_clear(srv_tile_cache *c);
size_t srv_tiles_count(const srv_tile_cache *c);
/* Bytes the entries kept by the last sweep take (entry and payload); 0
 * after srv_tiles_clear. */
size_t srv_tiles_bytes(const srv_tile_cache *c);

/* Channels (PROTO_CH_*) that a PROTO_FX_* effects mask puts in tiles. */
unsigned srv_tiles_channels(unsigned effects);

/* The first tile index of an n x n block around camera coordinate x at
 * tiles of world size w: the camera lies in the block's middle half. */
int32_t srv_tiles_first(double x, double w, int n);

/* Makes b's bytes (b made with headroom 0) the payload of t, in an
 * allocation shrunk to their length, and leaves b empty.  An encoder grows
 * its buffer to the worst case (zstd's bound over the raw planes, about
 * eight times what a qz tile keeps), and cached tiles that kept that
 * capacity held 1.3 GB for 256 layout-0 viewers 2 km apart.  Returns
 * OCEAN_ETOOBIG (t unchanged, b freed) past UINT32_MAX bytes. */
ocean_result srv_tile_take_payload(srv_tile *t, proto_buf *b);

/* Samples the tile t->key describes from frame f and encodes it into
 * t->payload; sets ready, result, error_bound.  Thread safe for distinct t. */
void srv_tile_build(srv_tile *t, const ocean_frame *f);

/* The calling thread's codec context (zstd context and scratch), made on
 * its first tile and freed when the thread exits; NULL if it cannot be made
 * (the codec then makes one per call).  For every tile encoder of the
 * daemon's worker threads. */
proto_codec_ctx *srv_tiles_codec_ctx(void);

/* Encodes the n x n planes of a tile with key k's codec and accuracy on the
 * calling thread's codec context into *out (headroom 0, initialised here;
 * freed on failure); *max_err gets the achieved error bound. */
ocean_result srv_tiles_encode(const srv_tile_key *k, int n, const float *planes, proto_buf *out, double *max_err);

/* Fills a proto_tile (for a FRAME) from a built entry. */
void srv_tile_to_proto(const srv_tile *t, proto_tile *out);

#endif
