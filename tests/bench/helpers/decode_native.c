/*
 * decode_native.c - the native side of bench_decode.sh: decodes every
 * FRAME of a frame store (ocean-client record) as the browser viewer does,
 * with the C decoders, on one core: the message (proto_decode), each
 * tile's payload (proto_tile_decode) and the viewer's texel block (DX, H,
 * DZ, FOAM and the slopes of the octahedral normal, proto_normal_oct_slopes
 * at the viewer's maximum slope 20).  Prints one line a frame:
 *   frame INDEX TILES BYTES MS FNV
 * with FNV the FNV-1a (32 bit) of the decoded planes' bytes, tile after
 * tile: decode_viewer.mjs prints the same of the WebAssembly build.
 *   usage: decode_native FRAMES
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "codec.h"
#include "oc_store.h"
#include "proto.h"
#include "proto_buf.h"

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return 1e3 * (double)ts.tv_sec + 1e-6 * (double)ts.tv_nsec;
}

static uint32_t fnv1a(uint32_t h, const void *p, size_t n)
{
    const uint8_t *b = p;
    for (size_t i = 0; i < n; i++) h = (h ^ b[i]) * 16777619u;
    return h;
}

/* The viewer's block of one decoded tile (clients/wasm/oc_wasm.c). */
static void block(const float *d, unsigned ch, size_t n, float *disp, float *slope)
{
    int off[6];
    proto_tile_plane_offsets(ch, n, off);
    for (size_t k = 0; k < n; k++) {
        disp[4 * k] = off[1] >= 0 ? d[off[1] + k] : 0;
        disp[4 * k + 1] = off[0] >= 0 ? d[off[0] + k] : 0;
        disp[4 * k + 2] = off[2] >= 0 ? d[off[2] + k] : 0;
        disp[4 * k + 3] = off[5] >= 0 ? d[off[5] + k] : 0;
        if (off[3] >= 0)
            proto_normal_oct_slopes(d[off[3] + k], d[off[4] + k], 20.0f, &slope[2 * k], &slope[2 * k + 1]);
    }
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: decode_native FRAMES\n");
        return 2;
    }
    char err[256];
    oc_store_reader *r = NULL;
    if (oc_store_reader_open(argv[1], &r, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "decode_native: %s\n", err);
        return 1;
    }
    size_t cap = 0;
    float *planes = NULL, *disp = NULL, *slope = NULL;
    const uint8_t *msg;
    size_t len;
    double rt;
    int index = 0, bad = 0;
    ocean_result res;
    while ((res = oc_store_reader_next(r, &msg, &len, &rt, err, sizeof err)) == OCEAN_OK) {
        if (len < PROTO_HEADER_SIZE || proto_ld16(msg + 6) != PROTO_FRAME) continue;
        double t0 = now_ms();
        proto_msg m;
        if (proto_decode(msg, len, &m, err, sizeof err) != OCEAN_OK) {
            fprintf(stderr, "decode_native: frame %d: %s\n", index, err);
            bad = 1;
            break;
        }
        uint32_t h = 2166136261u;
        for (int t = 0; t < m.u.frame.tile_count && !bad; t++) {
            const proto_tile *ti = &m.u.frame.tiles[t];
            int np = proto_tile_planes(ti->channels);
            size_t n = (size_t)ti->width * ti->height;
            if (n * (size_t)np > cap) {
                cap = n * (size_t)np;
                free(planes), free(disp), free(slope);
                planes = malloc(cap * sizeof *planes);
                disp = malloc(4 * cap * sizeof *disp);
                slope = malloc(2 * cap * sizeof *slope);
                if (!planes || !disp || !slope) return 1;
            }
            if (proto_tile_decode(ti->codec, ti->width, ti->height, ti->channels, ti->payload, ti->payload_len,
                                  planes, err, sizeof err) != OCEAN_OK) {
                fprintf(stderr, "decode_native: frame %d tile %d: %s\n", index, t, err);
                bad = 1;
                break;
            }
            block(planes, ti->channels, n, disp, slope);
            h = fnv1a(h, planes, n * (size_t)np * sizeof *planes);
        }
        double ms = now_ms() - t0;
        printf("frame %d %d %zu %.4f %08x\n", index, m.u.frame.tile_count, len, ms, h);
        proto_msg_free(&m);
        index++;
        if (bad) break;
    }
    oc_store_reader_close(r);
    free(planes), free(disp), free(slope);
    if (res != OCEAN_ENOTFOUND && !bad) {
        fprintf(stderr, "decode_native: %s\n", err);
        return 1;
    }
    return bad;
}
