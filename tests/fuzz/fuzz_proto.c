/*
 * fuzz_proto.c - libFuzzer target for the message decoder and the tile
 * decoders (protocol/).
 *
 * Checks beyond "no crash, no sanitizer report":
 *   - a decode either succeeds or returns a non-OK code with a message;
 *   - a decoded message re-encodes to exactly the input bytes (the wire
 *     format has one encoding per message) and decodes again;
 *   - proto_error_reply always yields a decodable ERROR;
 *   - every decoded tile's payload goes through proto_tile_decode, which
 *     returns OK with finite values or a clean error; so does a FRAME's
 *     qz mesh payload through proto_mesh_qz_decode.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "proto.h"

static void fuzz_tile(const proto_tile *t)
{
    int np = proto_tile_planes(t->channels);
    size_t n = (size_t)t->width * t->height * (size_t)np;
    if (np == 0 || n > (1u << 20))
        return;
    float *planes = malloc(n * sizeof *planes);
    if (!planes)
        return;
    char err[256];
    ocean_result r = proto_tile_decode((proto_codec)t->codec, t->width, t->height, t->channels, t->payload,
                                       t->payload_len, planes, err, sizeof err);
    if (r == OCEAN_OK)
        for (size_t i = 0; i < n; i++)
            if (!isfinite(planes[i]))
                abort();
    free(planes);
}

/* A has_mesh 2 record's positions (MESH_VERTICES_QZ): decoded with
 * previous-vertex references (valid for any vertex count; a topology's
 * only choose other decoded vertices), OK with finite |.| <= 1e7 values
 * or a clean error. */
static void fuzz_mesh_qz(const proto_mesh_vertices *v)
{
    size_t n = v->vertex_count;
    if (n == 0 || n > (1u << 16))
        return;
    uint32_t *refs = malloc(3 * n * sizeof *refs);
    float *xyz = malloc(3 * n * sizeof *xyz);
    if (refs && xyz) {
        memset(refs, 0xff, 3 * n * sizeof *refs);
        char err[256];
        if (proto_mesh_qz_decode(v->qz, v->qz_len, (uint32_t)n, refs, xyz, err, sizeof err) == OCEAN_OK)
            for (size_t i = 0; i < 3 * n; i++)
                if (!isfinite(xyz[i]) || fabsf(xyz[i]) > 1e7f)
                    abort();
    }
    free(refs);
    free(xyz);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    proto_msg m;
    char err[512];
    err[0] = 0;
    ocean_result r = proto_decode(data, size, &m, err, sizeof err);
    proto_buf b;
    proto_buf_init(&b, 0);
    if (r != OCEAN_OK) {
        if (!err[0])
            abort();                       /* every failure explains itself */
        if (proto_error_reply(&b, data, size, r, err, 1, 0.0) != OCEAN_OK)
            abort();
        proto_msg e;
        if (proto_decode(proto_buf_data(&b), b.len, &e, NULL, 0) != OCEAN_OK || e.u.error.code != (uint16_t)r)
            abort();
        proto_msg_free(&e);
        proto_buf_free(&b);
        return 0;
    }
    if (proto_encode(&b, &m, err, sizeof err) != OCEAN_OK)
        abort();                           /* decoder accepted what the encoder refuses */
    if (b.len != size || memcmp(proto_buf_data(&b), data, size) != 0)
        abort();                           /* not canonical */
    if (m.hdr.type == PROTO_TILE)
        fuzz_tile(&m.u.tile);
    if (m.hdr.type == PROTO_FRAME)
        for (unsigned i = 0; i < m.u.frame.tile_count && i < 8; i++)
            fuzz_tile(&m.u.frame.tiles[i]);
    if (m.hdr.type == PROTO_FRAME && m.u.frame.has_mesh == 2)
        fuzz_mesh_qz(&m.u.frame.mesh);
    proto_msg_free(&m);
    proto_buf_free(&b);
    return 0;
}
