/*
 * test_held.c - the samples a time-interpolating client holds
 * (clients/c/oc_held.c; PROTOCOL.md "Samples in time"), and the vectors
 * that hold every other implementation of those rules to the same numbers
 * (tests/vectors/held, read by tests/browser/protocol.test.mjs for the
 * viewer's WebAssembly build).
 *
 * A stream of six layout-1 FRAMEs is built with the protocol encoder.
 * Every sample of tile (mip m, ix, iz) taken at tick T holds
 * value(T, plane, m, ix, iz, k) = T + 0.25 plane + 1/64 (8 m + 4 iz + 2 ix)
 * + k / 1024 (k the sample's index), so which sample a client holds shows
 * in every number.  The expected tiles of each frame's instant are written
 * out below from the spec's text, frame by frame (which samples the
 * window rule keeps, which tiles have both samples, the channels both
 * carry, (1 - w) A + w B in binary32 with w = phase / 65536), never taken
 * from the store.
 *
 *   test_held                       the tests (cmocka)
 *   test_held --write-vectors DIR   writes the stream and its expectations
 *                                   (regenerate tests/vectors/held only
 *                                   when the stream below changes)
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "codec.h"
#include "oc_held.h"
#include "proto.h"

#define TS 4          /* tile side */
#define N_FRAMES 6
#define MAX_TILES 8
#define CH_HN (PROTO_CH_HEIGHT | PROTO_CH_NORMAL)

/* One tile of the stream: its place, the tick its samples were taken at,
 * its sample slot and channels; `marker` is added to every value (a tile
 * that replaces another at the same place and tick). */
typedef struct tile_spec {
    int mip, ix, iz;
    uint32_t tick;
    int slot;
    unsigned channels;
    int codec;
    float marker;
} tile_spec;

typedef struct frame_spec {
    uint32_t tick;
    int key;
    proto_mip_time time[2];
    int ntiles;
    tile_spec tile[MAX_TILES];
} frame_spec;

/* The stream (see the expectations below for what each frame tests). */
static const frame_spec stream[N_FRAMES] = {
    /* 0: KEY; mip 0 every 4 ticks, both samples of its four tiles; mip 1 at
     * the frame's own time */
    {100, 1, {{100, 4, 0}, {0, 0, 0}}, 7,
     {{0, 0, 0, 100, 0, CH_HN, PROTO_CODEC_F32, 0}, {0, 1, 0, 100, 0, CH_HN, PROTO_CODEC_F32, 0},
      {0, 0, 1, 100, 0, CH_HN, PROTO_CODEC_F32, 0}, {0, 1, 1, 100, 0, CH_HN, PROTO_CODEC_F32, 0},
      {0, 0, 0, 104, 1, CH_HN, PROTO_CODEC_F32, 0}, {0, 1, 0, 104, 1, CH_HN, PROTO_CODEC_F32, 0},
      {1, 0, 0, 100, 0, PROTO_CH_HEIGHT, PROTO_CODEC_F32, 0}}},
    /* 1: mip 0 keeps its window a quarter on ((1,1) gets its B now, (0,1)
     * never in this window); mip 1 the frame's own time again */
    {101, 0, {{100, 4, 16384}, {0, 0, 0}}, 2,
     {{0, 1, 1, 104, 1, CH_HN, PROTO_CODEC_F32, 0}, {1, 0, 0, 101, 0, PROTO_CH_HEIGHT, PROTO_CODEC_F32, 0}}},
    /* 2: mip 0 half way, its (1,1) B replaced; mip 1 gets a window (a new
     * one: both samples) */
    {102, 0, {{100, 4, 32768}, {102, 2, 0}}, 3,
     {{0, 1, 1, 104, 1, CH_HN, PROTO_CODEC_F32, 1000}, {1, 0, 0, 102, 0, PROTO_CH_HEIGHT, PROTO_CODEC_F32, 0},
      {1, 0, 0, 104, 1, PROTO_CH_HEIGHT, PROTO_CODEC_F32, 0}}},
    /* 3: both windows start at their held B: B moves to A, (0,1) keeps
     * its old A (no B came).  mip 0's new B for three tiles, (0,1)'s with
     * heights only; (1,1) has none */
    {104, 0, {{104, 4, 0}, {104, 2, 0}}, 4,
     {{0, 0, 0, 108, 1, CH_HN, PROTO_CODEC_F32, 0}, {0, 1, 0, 108, 1, CH_HN, PROTO_CODEC_F32, 0},
      {0, 0, 1, 108, 1, PROTO_CH_HEIGHT, PROTO_CODEC_F32, 0}, {1, 0, 0, 106, 1, PROTO_CH_HEIGHT, PROTO_CODEC_F32, 0}}},
    /* 4: mip 0 jumps to a window not starting at its B (no KEY): each
     * tile's newest sample becomes A, then both samples of (0,0) and
     * sample A of (1,0) replace theirs; mip 1 half way */
    {105, 0, {{200, 4, 16384}, {104, 2, 32768}}, 3,
     {{0, 0, 0, 200, 0, CH_HN, PROTO_CODEC_F32, 0}, {0, 0, 0, 204, 1, CH_HN, PROTO_CODEC_F32, 0},
      {0, 1, 0, 200, 0, CH_HN, PROTO_CODEC_F32, 0}}},
    /* 5: KEY drops all; mip 0 at the frame's own time, one tile; mip 1 a
     * window with sample A only (not read until B comes) */
    {106, 1, {{0, 0, 0}, {106, 2, 0}}, 2,
     {{0, 0, 1, 106, 0, CH_HN, PROTO_CODEC_F32, 0}, {1, 0, 0, 106, 0, PROTO_CH_HEIGHT, PROTO_CODEC_F32, 0}}},
};

/* What each frame's instant reads: tile (mip, ix, iz) is the blend of
 * samples taken at ticks ta and tb (markers ma, mb) with weight w, over
 * `channels`; tb < 0: sample A alone (interval 0, or B not come yet). */
typedef struct blend_spec {
    int mip, ix, iz;
    int ta, tb;
    float ma, mb;
    double w;
    unsigned channels;
} blend_spec;

static const struct {
    int n;
    blend_spec b[MAX_TILES];
} expected[N_FRAMES] = {
    /* 0: (0,0), (1,0) at w 0; (0,1), (1,1) A alone (no B yet); mip 1 tick 100 */
    {5, {{0, 0, 0, 100, 104, 0, 0, 0, CH_HN}, {0, 1, 0, 100, 104, 0, 0, 0, CH_HN},
         {0, 0, 1, 100, -1, 0, 0, 0, CH_HN}, {0, 1, 1, 100, -1, 0, 0, 0, CH_HN},
         {1, 0, 0, 100, -1, 0, 0, 0, PROTO_CH_HEIGHT}}},
    {5, {{0, 0, 0, 100, 104, 0, 0, 0.25, CH_HN}, {0, 1, 0, 100, 104, 0, 0, 0.25, CH_HN},
         {0, 0, 1, 100, -1, 0, 0, 0, CH_HN}, {0, 1, 1, 100, 104, 0, 0, 0.25, CH_HN},
         {1, 0, 0, 101, -1, 0, 0, 0, PROTO_CH_HEIGHT}}},
    {5, {{0, 0, 0, 100, 104, 0, 0, 0.5, CH_HN}, {0, 1, 0, 100, 104, 0, 0, 0.5, CH_HN},
         {0, 0, 1, 100, -1, 0, 0, 0, CH_HN}, {0, 1, 1, 100, 104, 0, 1000, 0.5, CH_HN},
         {1, 0, 0, 102, 104, 0, 0, 0, PROTO_CH_HEIGHT}}},
    /* 3: (1,1) A alone: its A is the replaced B; (0,1) its old A (tick
     * 100) blended with the new B */
    {5, {{0, 0, 0, 104, 108, 0, 0, 0, CH_HN}, {0, 1, 0, 104, 108, 0, 0, 0, CH_HN},
         {0, 0, 1, 100, 108, 0, 0, 0, PROTO_CH_HEIGHT}, {0, 1, 1, 104, -1, 1000, 0, 0, CH_HN},
         {1, 0, 0, 104, 106, 0, 0, 0, PROTO_CH_HEIGHT}}},
    /* 4: (1,0) A alone a quarter into its window; (0,1), (1,1) their
     * newest samples (108 heights only; the replaced 104) alone */
    {5, {{0, 0, 0, 200, 204, 0, 0, 0.25, CH_HN}, {0, 1, 0, 200, -1, 0, 0, 0, CH_HN},
         {0, 0, 1, 108, -1, 0, 0, 0, PROTO_CH_HEIGHT}, {0, 1, 1, 104, -1, 1000, 0, 0, CH_HN},
         {1, 0, 0, 104, 106, 0, 0, 0.5, PROTO_CH_HEIGHT}}},
    /* 5: mip 1's window has A alone */
    {2, {{0, 0, 1, 106, -1, 0, 0, 0, CH_HN}, {1, 0, 0, 106, -1, 0, 0, 0, PROTO_CH_HEIGHT}}},
};

static float value(uint32_t tick, int plane, int mip, int ix, int iz, int k, float marker)
{
    return (float)tick + 0.25f * (float)plane + (float)(8 * mip + 4 * iz + 2 * ix) / 64.0f + (float)k / 1024.0f +
           marker;
}

/* The planes of a sample (plane after plane, TS x TS each). */
static void sample_planes(const tile_spec *t, float *out)
{
    int np = proto_tile_planes(t->channels);
    for (int p = 0; p < np; p++)
        for (int k = 0; k < TS * TS; k++)
            out[p * TS * TS + k] = value(t->tick, p, t->mip, t->ix, t->iz, k, t->marker);
}

static void cascade_block(proto_cascade_block *b, const frame_spec *s)
{
    memset(b, 0, sizeof *b);
    b->cascade_count = 1;
    b->order = 6;
    b->flags = s->key ? PROTO_CASCADE_KEY : 0;
    b->spacing_per_m = 0.046875f;
    b->camera[1] = 25.0;
    proto_cascade_entry *e = &b->cascade[0];
    e->patch_m = 64;
    e->n = 2 * TS;
    e->mips = 2;
    e->spacing_per_m = b->spacing_per_m;
    e->mip[0] = (proto_mip_entry){INFINITY, 0.00390625f, 0.001953125f, 0.0f, {0}};
    e->mip[1] = (proto_mip_entry){0.36f, 0.0078125f, 0.00390625f, 0.0f, {0}};
    e->mip[2] = (proto_mip_entry){0.0f, 0.03125f, 0.015625f, 0.0f, {0}};
    e->time[0] = s->time[0];
    e->time[1] = s->time[1];
}

/* Frame i of the stream, encoded into out. */
static void frame_encode(int i, proto_buf *out)
{
    const frame_spec *s = &stream[i];
    proto_tile tiles[MAX_TILES];
    proto_buf pay[MAX_TILES];
    float planes[6 * TS * TS];
    char err[256];
    for (int k = 0; k < s->ntiles; k++) {
        const tile_spec *t = &s->tile[k];
        sample_planes(t, planes);
        proto_buf_init(&pay[k], 0);
        proto_codec_params prm = {0};
        assert_int_equal(proto_tile_encode((proto_codec)t->codec, &prm, TS, TS, t->channels, planes, &pay[k], NULL,
                                           err, sizeof err),
                         OCEAN_OK);
        double spacing = 64.0 / (2 * TS) * (1 << t->mip);
        tiles[k] = (proto_tile){(uint8_t)t->mip, (uint8_t)t->codec, (uint16_t)t->channels, TS, TS, t->ix, t->iz,
                                t->ix * TS * spacing, t->iz * TS * spacing, spacing, 0.0f,
                                (uint32_t)proto_buf_len(&pay[k]), proto_buf_data(&pay[k]), 0, (uint8_t)t->slot};
    }
    proto_msg m;
    proto_msg_init(&m, PROTO_FRAME);
    m.hdr.seq = 500 + (uint32_t)i;
    m.hdr.sim_time = s->tick / 30.0;
    proto_frame *f = &m.u.frame;
    f->layout = PROTO_LAYOUT_CASCADE;
    f->camera_seq = PROTO_NO_CAMERA;
    f->cutoff_k = INFINITY;
    f->tick = s->tick;
    f->tile_count = (uint16_t)s->ntiles;
    f->tiles = tiles;
    cascade_block(&f->cascades, s);
    proto_buf_init(out, 0);
    assert_int_equal(proto_encode(out, &m, err, sizeof err), OCEAN_OK);
    for (int k = 0; k < s->ntiles; k++) proto_buf_free(&pay[k]);
}

/* The expected planes of blend b (binary32 as the spec writes it). */
static void blend_expected(const blend_spec *b, float *out)
{
    int np = proto_tile_planes(b->channels);
    float wa = (float)(1.0 - b->w), wb = (float)b->w;
    /* plane p of the blend is plane p of A's and B's channels: both carry
     * H first and NU, NV after it when they carry normals */
    for (int p = 0; p < np; p++)
        for (int k = 0; k < TS * TS; k++) {
            float a = value((uint32_t)b->ta, p, b->mip, b->ix, b->iz, k, b->ma);
            out[p * TS * TS + k] = b->tb < 0 ? a : wa * a + wb * value((uint32_t)b->tb, p, b->mip, b->ix, b->iz, k, b->mb);
        }
}

/* ---- the store against the expectations --------------------------------- */

static int blend_cmp(const void *a, const void *b)
{
    const proto_tile *x = a, *y = b;
    if (x->level != y->level) return x->level - y->level;
    if (x->iz != y->iz) return x->iz - y->iz;
    return x->ix - y->ix;
}

/* Checks the store's blend at frame i against expected[i], in (mip, iz,
 * ix) order. */
static void check_blend(oc_held *h, const proto_frame *f, int i)
{
    proto_tile *tiles;
    float **data;
    unsigned n;
    assert_int_equal(oc_held_blend(h, f, &tiles, &data, &n), OCEAN_OK);
    assert_int_equal(n, (unsigned)expected[i].n);
    int order[MAX_TILES];
    for (unsigned k = 0; k < n; k++) order[k] = (int)k;
    for (unsigned a = 0; a < n; a++)
        for (unsigned b = a + 1; b < n; b++)
            if (blend_cmp(&tiles[order[b]], &tiles[order[a]]) < 0) {
                int t = order[a];
                order[a] = order[b];
                order[b] = t;
            }
    float want[6 * TS * TS];
    for (unsigned k = 0; k < n; k++) {
        const blend_spec *e = &expected[i].b[k];
        const proto_tile *t = &tiles[order[k]];
        assert_int_equal(t->level, e->mip);
        assert_int_equal(t->ix, e->ix);
        assert_int_equal(t->iz, e->iz);
        assert_int_equal(t->channels, e->channels);
        blend_expected(e, want);
        assert_memory_equal(data[order[k]], want, sizeof(float) * proto_tile_planes(e->channels) * TS * TS);
    }
    oc_held_blend_free(tiles, data, n);
}

/* Runs the stream through a store, tiles decoded by the caller (eager) or
 * held as payloads (lazy, data NULL), checking every frame's instant. */
static void run_stream(int lazy)
{
    oc_held *h;
    assert_int_equal(oc_held_create(&h), OCEAN_OK);
    char err[256];
    for (int i = 0; i < N_FRAMES; i++) {
        proto_buf b;
        frame_encode(i, &b);
        proto_msg m;
        assert_int_equal(proto_decode(proto_buf_data(&b), proto_buf_len(&b), &m, err, sizeof err), OCEAN_OK);
        const proto_frame *f = &m.u.frame;
        float *dec[MAX_TILES] = {0};
        for (unsigned k = 0; !lazy && k < f->tile_count; k++) {
            const proto_tile *t = &f->tiles[k];
            dec[k] = malloc(sizeof(float) * proto_tile_planes(t->channels) * t->width * t->height);
            assert_int_equal(proto_tile_decode((proto_codec)t->codec, t->width, t->height, t->channels, t->payload,
                                               t->payload_len, dec[k], err, sizeof err),
                             OCEAN_OK);
        }
        assert_int_equal(oc_held_apply(h, f, lazy ? NULL : (const float *const *)dec, err, sizeof err), OCEAN_OK);
        if (lazy) assert_int_equal(oc_held_decode(h, err, sizeof err), OCEAN_OK);
        check_blend(h, f, i);
        for (unsigned k = 0; k < f->tile_count; k++) free(dec[k]);
        proto_msg_free(&m);
        proto_buf_free(&b);
    }
    oc_held_destroy(h);
}

static void stream_decoded_by_the_caller(void **state)
{
    (void)state;
    run_stream(0);
}

static void stream_held_as_payloads(void **state)
{
    (void)state;
    run_stream(1);
}

/* A tile whose payload does not decode is dropped with its decoder's
 * error; every other tile is still decoded and blended. */
static void undecodable_tile_dropped(void **state)
{
    (void)state;
    proto_buf b;
    frame_encode(0, &b);
    proto_msg m;
    char err[256];
    assert_int_equal(proto_decode(proto_buf_data(&b), proto_buf_len(&b), &m, err, sizeof err), OCEAN_OK);
    proto_tile tiles[MAX_TILES];
    memcpy(tiles, m.u.frame.tiles, m.u.frame.tile_count * sizeof *tiles);
    uint8_t junk[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    tiles[4].codec = PROTO_CODEC_QZ;  /* B of (0,0) */
    tiles[4].payload = junk;
    tiles[4].payload_len = sizeof junk;
    proto_frame f = m.u.frame;
    f.tiles = tiles;
    oc_held *h;
    assert_int_equal(oc_held_create(&h), OCEAN_OK);
    assert_int_equal(oc_held_apply(h, &f, NULL, err, sizeof err), OCEAN_OK);
    err[0] = 0;
    assert_int_equal(oc_held_decode(h, err, sizeof err), OCEAN_ECODEC);
    assert_non_null(strstr(err, "mip 0 tile (0, 0)"));
    assert_int_equal(oc_held_decode(h, err, sizeof err), OCEAN_OK); /* dropped, not retried */
    proto_tile *bt;
    float **data;
    unsigned n;
    assert_int_equal(oc_held_blend(h, &f, &bt, &data, &n), OCEAN_OK);
    /* every tile: (0,0) of mip 0 reads its A alone */
    assert_int_equal(n, 5);
    oc_held_blend_free(bt, data, n);
    oc_held_destroy(h);
    proto_msg_free(&m);
    proto_buf_free(&b);
}

/* ---- vectors ------------------------------------------------------------- */

static const char *vector_dir(void)
{
    const char *d = getenv("OCEAN_HELD_VECTORS");
    return d ? d : "tests/vectors/held";
}

static void *read_file(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    void *p = malloc(n > 0 ? (size_t)n : 1);
    if (p && fread(p, 1, (size_t)n, f) != (size_t)n) {
        free(p);
        p = NULL;
    }
    fclose(f);
    *len = (size_t)n;
    return p;
}

/* Frame i's expected tiles: a text line per tile "mip ix iz channels"
 * (cascade 0, TS x TS samples) and their planes, tile after tile, as
 * little-endian binary32. */
static int write_expectation(const char *dir, int i)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/frame_%d.txt", dir, i);
    FILE *t = fopen(path, "w");
    snprintf(path, sizeof path, "%s/frame_%d.f32", dir, i);
    FILE *p = fopen(path, "wb");
    if (!t || !p) return -1;
    float want[6 * TS * TS];
    for (int k = 0; k < expected[i].n; k++) {
        const blend_spec *e = &expected[i].b[k];
        fprintf(t, "%d %d %d %u\n", e->mip, e->ix, e->iz, e->channels);
        blend_expected(e, want);
        fwrite(want, sizeof(float), (size_t)proto_tile_planes(e->channels) * TS * TS, p);
    }
    int bad = ferror(t) || ferror(p);
    return (fclose(t) | fclose(p) | bad) ? -1 : 0;
}

static int write_vectors(const char *dir)
{
    for (int i = 0; i < N_FRAMES; i++) {
        proto_buf b;
        frame_encode(i, &b);
        char path[1024];
        snprintf(path, sizeof path, "%s/frame_%d.bin", dir, i);
        FILE *f = fopen(path, "wb");
        int bad = !f || fwrite(proto_buf_data(&b), 1, proto_buf_len(&b), f) != proto_buf_len(&b);
        if (f) bad |= fclose(f) != 0;
        proto_buf_free(&b);
        if (bad || write_expectation(dir, i)) {
            fprintf(stderr, "cannot write the vectors into %s\n", dir);
            return 1;
        }
    }
    return 0;
}

/* The committed vectors are this stream: an implementation tested on
 * them is tested on what this file checks the C store against. */
static void vectors_are_this_stream(void **state)
{
    (void)state;
    for (int i = 0; i < N_FRAMES; i++) {
        char path[1024];
        size_t len;
        snprintf(path, sizeof path, "%s/frame_%d.bin", vector_dir(), i);
        uint8_t *bin = read_file(path, &len);
        if (!bin) fail_msg("%s missing: build/tests/test_held --write-vectors tests/vectors/held", path);
        proto_buf b;
        frame_encode(i, &b);
        assert_int_equal(len, proto_buf_len(&b));
        assert_memory_equal(bin, proto_buf_data(&b), len);
        free(bin);
        proto_buf_free(&b);
        snprintf(path, sizeof path, "%s/frame_%d.f32", vector_dir(), i);
        float *got = read_file(path, &len);
        assert_non_null(got);
        size_t off = 0;
        float want[6 * TS * TS];
        for (int k = 0; k < expected[i].n; k++) {
            size_t cnt = (size_t)proto_tile_planes(expected[i].b[k].channels) * TS * TS;
            blend_expected(&expected[i].b[k], want);
            assert_true((off + cnt) * sizeof(float) <= len);
            assert_memory_equal(got + off, want, cnt * sizeof(float));
            off += cnt;
        }
        assert_int_equal(off * sizeof(float), len);
        free(got);
    }
}

int main(int argc, char **argv)
{
    if (argc == 3 && strcmp(argv[1], "--write-vectors") == 0)
        return write_vectors(argv[2]);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(stream_decoded_by_the_caller),
        cmocka_unit_test(stream_held_as_payloads),
        cmocka_unit_test(undecodable_tile_dropped),
        cmocka_unit_test(vectors_are_this_stream),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
