/*
 * decode_native.c - the native side of bench_decode.sh: decodes every
 * FRAME of a frame store (ocean-client record) as the browser viewer does,
 * with the C decoders, on one core: the message (proto_decode), each
 * tile's payload (proto_tile_decode) and the viewer's texel block (DX, H,
 * DZ, FOAM and the slopes of the octahedral normal, proto_normal_oct_slopes
 * at the viewer's maximum slope 20).  A time-interpolating stream
 * (PROTOCOL.md "Samples in time") goes through the C library's store as
 * the viewer's workers run it: each frame applied (payloads copied), the
 * samples it lacks decoded, the frame's instant blended and made into
 * texel blocks.  Prints one line a frame:
 *   frame INDEX TILES BYTES MS FNV
 * with TILES the tiles the frame carries and FNV the FNV-1a (32 bit) of
 * the planes of the tiles its instant reads (decoded, or blended), in
 * (cascade, mip, iz, ix) order: decode_viewer.mjs prints the same of the
 * WebAssembly build.
 *   usage: decode_native FRAMES
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "codec.h"
#include "oc_held.h"
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

/* Scratch planes and blocks for tiles of up to n samples and np planes. */
typedef struct scratch {
    size_t cap;
    float *planes, *disp, *slope;
} scratch;

static int scratch_fit(scratch *s, size_t need)
{
    if (need <= s->cap) return 0;
    s->cap = need;
    free(s->planes), free(s->disp), free(s->slope);
    s->planes = malloc(need * sizeof *s->planes);
    s->disp = malloc(4 * need * sizeof *s->disp);
    s->slope = malloc(2 * need * sizeof *s->slope);
    return s->planes && s->disp && s->slope ? 0 : -1;
}

static int tile_cmp(const proto_tile *x, const proto_tile *y)
{
    if (x->cascade != y->cascade) return x->cascade - y->cascade;
    if (x->level != y->level) return x->level - y->level;
    if (x->iz != y->iz) return x->iz - y->iz;
    return x->ix - y->ix;
}

/* A plain frame: every tile decoded into its block; *h the planes' hash
 * in tile order (the frame's order is the daemon's: (cascade, mip, iz,
 * ix) for a plain frame). */
static int plain_frame(const proto_frame *f, scratch *sc, uint32_t *h, char *err, size_t errlen)
{
    for (int t = 0; t < f->tile_count; t++) {
        const proto_tile *ti = &f->tiles[t];
        int np = proto_tile_planes(ti->channels);
        size_t n = (size_t)ti->width * ti->height;
        if (scratch_fit(sc, n * (size_t)np)) return -1;
        if (proto_tile_decode(ti->codec, ti->width, ti->height, ti->channels, ti->payload, ti->payload_len,
                              sc->planes, err, errlen) != OCEAN_OK)
            return -1;
        block(sc->planes, ti->channels, n, sc->disp, sc->slope);
        *h = fnv1a(*h, sc->planes, n * (size_t)np * sizeof *sc->planes);
    }
    return 0;
}

/* A frame of a time-interpolating stream through the store held. */
static int timed_frame(oc_held *held, const proto_frame *f, scratch *sc, uint32_t *h, char *err, size_t errlen)
{
    proto_tile *tiles;
    float **data;
    unsigned n;
    if (oc_held_apply(held, f, NULL, err, errlen) != OCEAN_OK || oc_held_decode(held, err, errlen) != OCEAN_OK ||
        oc_held_blend(held, f, &tiles, &data, &n) != OCEAN_OK)
        return -1;
    unsigned *ord = malloc((n ? n : 1) * sizeof *ord);
    if (!ord) return -1;
    for (unsigned i = 0; i < n; i++) ord[i] = i;
    for (unsigned i = 1; i < n; i++)
        for (unsigned k = i; k > 0 && tile_cmp(&tiles[ord[k]], &tiles[ord[k - 1]]) < 0; k--) {
            unsigned x = ord[k];
            ord[k] = ord[k - 1];
            ord[k - 1] = x;
        }
    int bad = 0;
    for (unsigned i = 0; i < n && !bad; i++) {
        const proto_tile *ti = &tiles[ord[i]];
        size_t cnt = (size_t)ti->width * ti->height, np = (size_t)proto_tile_planes(ti->channels);
        bad = scratch_fit(sc, cnt * np);
        if (!bad) {
            block(data[ord[i]], ti->channels, cnt, sc->disp, sc->slope);
            *h = fnv1a(*h, data[ord[i]], cnt * np * sizeof(float));
        }
    }
    free(ord);
    oc_held_blend_free(tiles, data, n);
    return bad;
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: decode_native FRAMES\n");
        return 2;
    }
    char err[256] = "";
    oc_store_reader *r = NULL;
    oc_held *held = NULL;
    if (oc_store_reader_open(argv[1], &r, err, sizeof err) != OCEAN_OK || oc_held_create(&held) != OCEAN_OK) {
        fprintf(stderr, "decode_native: %s\n", err);
        return 1;
    }
    scratch sc = {0};
    const uint8_t *msg;
    size_t len;
    double rt;
    int index = 0, bad = 0;
    ocean_result res;
    while (!bad && (res = oc_store_reader_next(r, &msg, &len, &rt, err, sizeof err)) == OCEAN_OK) {
        if (len < PROTO_HEADER_SIZE || proto_ld16(msg + 6) != PROTO_FRAME) continue;
        double t0 = now_ms();
        proto_msg m;
        uint32_t h = 2166136261u;
        bad = proto_decode(msg, len, &m, err, sizeof err) != OCEAN_OK;
        if (!bad)
            bad = oc_held_frame_timed(&m.u.frame) ? timed_frame(held, &m.u.frame, &sc, &h, err, sizeof err)
                                                  : plain_frame(&m.u.frame, &sc, &h, err, sizeof err);
        double ms = now_ms() - t0;
        if (bad) {
            fprintf(stderr, "decode_native: frame %d: %s\n", index, err[0] ? err : "out of memory");
            break;
        }
        printf("frame %d %d %zu %.4f %08x\n", index, m.u.frame.tile_count, len, ms, h);
        proto_msg_free(&m);
        index++;
    }
    oc_store_reader_close(r);
    oc_held_destroy(held);
    free(sc.planes), free(sc.disp), free(sc.slope);
    if (!bad && res != OCEAN_ENOTFOUND) {
        fprintf(stderr, "decode_native: %s\n", err);
        return 1;
    }
    return bad;
}
