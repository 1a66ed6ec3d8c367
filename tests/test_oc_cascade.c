/*
 * test_oc_cascade.c - layout-1 frames in the client library
 * (clients/c/oc_cascade.c): frames are built with the protocol encoder from
 * known fields (constants per mip, analytic sinusoids) and read back
 * through oc_frame_decode and the sampler.
 *
 * Check values come from the fields themselves and from PROTOCOL.md's rules
 * evaluated by hand at chosen points, never from the library's output:
 *  - the lod rule ("Where each mip is read") at points placed at chosen
 *    continuous levels lambda;
 *  - interpolation within a mip against the analytic field, within the
 *    remainder bound of linear interpolation |f - p1| <= h^2/8 max|f''|
 *    applied per axis (bilinear = linear in x then in z; e.g. Atkinson,
 *    "An Introduction to Numerical Analysis", 2nd ed. 1989, sect. 3.1);
 *  - periodic wrap at |x| = 1e7 m against the field at x mod P;
 *  - the mesh rule ("Mesh in layout 1"): morph weights, snapping to the
 *    coarser lattice, displacement read with max(s, g_L).
 *  - samples in time ("Samples in time"): frames of a time-interpolating
 *    stream decoded in order through oc_frame_stream read the blend of
 *    constant samples, computed by hand from the spec's window rule.
 * When build/oceand exists, the heights the library reads from the
 * daemon's layout-1 frames are compared with QUERY_RESULT at the same tick.
 */
#include <math.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <cmocka.h>

#include "codec.h"
#include "oceanclient.h"
#include "proto.h"
#include "lib/test_net.h"

/* ===================================================== frame building */

/* Values of a field at cascade c, mip m, cascade-local (x, z):
 * H, DX, DZ, slope x, slope z, FOAM. */
typedef struct field field;
struct field {
    void (*fn)(const field *F, int c, int m, double x, double z, double out[7]);
    /* which tiles go into the frame (NULL: all) */
    int (*want)(const field *F, int c, int m, int ix, int iz);
    /* the channels of mip m's tiles (NULL: the frame's) */
    unsigned (*chan)(const field *F, int c, int m, unsigned channels);
    double G;                        /* for chan: the block's geometry_spacing_m */
    const field *sample_b;           /* time-interpolating frames: every tile also
                                        travels as sample B, of this field */
    int b_only;                      /* ... and only as sample B */
    double a, kx, kz, phase, chop;   /* sinusoid parameters (cycles per patch) */
    double patch;
};

/* Octahedral encoding of the normal of slopes (sx, sz), PROTOCOL.md
 * "Octahedral normals" (upper hemisphere only here). */
static void oct_encode(double sx, double sz, float *u, float *v)
{
    double nx = -sx, ny = 1, nz = -sz;
    double s = fabs(nx) + fabs(ny) + fabs(nz);
    *u = (float)(nx / s);
    *v = (float)(nz / s);
}

typedef struct built {
    uint8_t *msg;
    size_t len;
} built;

/* Frames are encoded from these (tiles[i].payload is payloads[i]). */
static proto_tile tiles_[PROTO_MAX_FRAME_TILES];
static proto_buf payloads_[PROTO_MAX_FRAME_TILES];

/* Tile (ix, iz) of mip m of cascade c as record nt, sample `slot`: F's
 * values at its grid points, encoded with codec. */
static void emit_tile(const proto_cascade_block *b, const field *F, unsigned frame_channels, int tile_size,
                      proto_codec codec, int c, int m, int ix, int iz, int slot, unsigned nt)
{
    const proto_cascade_entry *e = &b->cascade[c];
    int n = e->n >> m;
    int T = tile_size < n ? tile_size : n;
    double sp = e->patch_m / e->n * ldexp(1.0, m);
    int w = n - ix * T < T ? n - ix * T : T, h = n - iz * T < T ? n - iz * T : T;
    unsigned channels = F->chan ? F->chan(F, c, m, frame_channels) : frame_channels;
    int planes = proto_tile_planes(channels);
    float *pl_ = calloc((size_t)planes * w * h, sizeof(float));
    assert_non_null(pl_);
    for (int i = 0; i < h; i++)
        for (int j = 0; j < w; j++) {
            double v[7];
            F->fn(F, c, m, (ix * T + j) * sp, (iz * T + i) * sp, v);
            int k = 0;
            size_t at = (size_t)i * w + j, wh = (size_t)w * h;
            if (channels & PROTO_CH_HEIGHT)
                pl_[wh * k++ + at] = (float)v[0];
            if (channels & PROTO_CH_DX)
                pl_[wh * k++ + at] = (float)v[1];
            if (channels & PROTO_CH_DZ)
                pl_[wh * k++ + at] = (float)v[2];
            if (channels & PROTO_CH_NORMAL) {
                float u, vv;
                oct_encode(v[3], v[4], &u, &vv);
                pl_[wh * k++ + at] = u;
                pl_[wh * k++ + at] = vv;
            }
            if (channels & PROTO_CH_BREAKING) {
                pl_[wh * k++ + at] = (float)v[5];
                pl_[wh * k++ + at] = (float)v[6];
            }
        }
    proto_buf_init(&payloads_[nt], 0);
    char err[256];
    double maxe = 0;
    assert_int_equal(proto_tile_encode(codec, NULL, w, h, channels, pl_, &payloads_[nt], &maxe, err, sizeof err),
                     OCEAN_OK);
    free(pl_);
    proto_tile *t = &tiles_[nt];
    memset(t, 0, sizeof *t);
    t->level = (uint8_t)m;
    t->codec = (uint8_t)codec;
    t->channels = (uint16_t)channels;
    t->width = (uint16_t)w;
    t->height = (uint16_t)h;
    t->ix = ix;
    t->iz = iz;
    t->origin_x = ix * T * sp;
    t->origin_z = iz * T * sp;
    t->spacing = sp;
    t->error_bound = (float)maxe;
    t->payload_len = (uint32_t)proto_buf_len(&payloads_[nt]);
    t->payload = proto_buf_data(&payloads_[nt]);
    t->cascade = (uint8_t)c;
    t->slot = (uint8_t)slot;
}

/* FRAME bytes of the tiles F wants of every mip of block b (each as sample
 * A from F->fn and, when F->sample_b is set, as sample B from it, or B
 * alone with F->b_only), tick `tick`. */
static built build_frame_at(const proto_cascade_block *b, const field *F, unsigned frame_channels, int tile_size,
                            const proto_mesh_placement *pl, proto_codec codec, uint32_t tick)
{
    unsigned nt = 0;
    for (int c = 0; c < b->cascade_count; c++) {
        const proto_cascade_entry *e = &b->cascade[c];
        for (int m = 0; m < e->mips; m++) {
            int n = e->n >> m, T = tile_size < n ? tile_size : n, tps = (n + T - 1) / T;
            for (int iz = 0; iz < tps; iz++)
                for (int ix = 0; ix < tps; ix++)
                    for (int slot = F->b_only ? 1 : 0; slot < (F->sample_b ? 2 : 1); slot++) {
                        if (F->want && !F->want(F, c, m, ix, iz))
                            continue;
                        assert_true(nt < PROTO_MAX_FRAME_TILES);
                        emit_tile(b, slot ? F->sample_b : F, frame_channels, tile_size, codec, c, m, ix, iz, slot,
                                  nt++);
                    }
        }
    }
    proto_msg m;
    proto_msg_init(&m, PROTO_FRAME);
    m.hdr.sim_time = 12.5;
    proto_frame *f = &m.u.frame;
    f->cutoff_k = INFINITY;
    f->camera_seq = PROTO_NO_CAMERA;
    f->tick = tick;
    f->layout = PROTO_LAYOUT_CASCADE;
    f->cascades = *b;
    f->tile_count = (uint16_t)nt;
    f->tiles = tiles_;
    if (pl) {
        f->has_mesh = 1;
        f->placement = *pl;
    }
    proto_buf out;
    proto_buf_init(&out, 0);
    char err[256] = "";
    ocean_result r = proto_encode(&out, &m, err, sizeof err);
    if (r != OCEAN_OK)
        print_error("encode: %s\n", err);
    assert_int_equal(r, OCEAN_OK);
    built B = {malloc(proto_buf_len(&out)), proto_buf_len(&out)};
    memcpy(B.msg, proto_buf_data(&out), B.len);
    proto_buf_free(&out);
    for (unsigned i = 0; i < nt; i++)
        proto_buf_free(&payloads_[i]);
    return B;
}

static built build_frame(const proto_cascade_block *b, const field *F, unsigned frame_channels, int tile_size,
                         const proto_mesh_placement *pl, proto_codec codec)
{
    return build_frame_at(b, F, frame_channels, tile_size, pl, codec, 7);
}

static oc_frame *decode_built(built B)
{
    oc_frame *f = NULL;
    char err[256] = "";
    ocean_result r = oc_frame_decode(B.msg, B.len, &f, err, sizeof err);
    if (r != OCEAN_OK)
        print_error("oc_frame_decode: %s (%s)\n", ocean_strerror(r), err);
    assert_int_equal(r, OCEAN_OK);
    free(B.msg);
    return f;
}

/* q of the block and of every cascade entry. */
static void block_set_q(proto_cascade_block *b, float q)
{
    b->spacing_per_m = q;
    for (int c = 0; c < b->cascade_count; c++)
        b->cascade[c].spacing_per_m = q;
}

/* A block with one entry per (patch, n, mips, fades); kc per mip as the
 * spec's table wants (mip 0 unfiltered, then > 0, entry `mips` 0); the
 * moments are distinct per (c, m) so their blending can be followed. */
static void block_init(proto_cascade_block *b, int count, const double *patch, const int *n, const int *mips,
                       const int *fades)
{
    memset(b, 0, sizeof *b);
    b->cascade_count = (uint8_t)count;
    b->order = 4;
    b->spacing_per_m = 1.0f / 1024;
    b->camera[1] = 1;
    b->e_total = 0.01f;
    b->tail_mss[0] = 0.004f;
    b->tail_mss[1] = 0.002f;
    b->tail_mss[2] = 0.0005f;
    for (int c = 0; c < count; c++) {
        proto_cascade_entry *e = &b->cascade[c];
        e->patch_m = patch[c];
        e->n = (uint16_t)n[c];
        e->mips = (uint8_t)mips[c];
        e->fades = (uint8_t)fades[c];
        for (int m = 0; m <= mips[c]; m++) {
            e->mip[m].kc = m == mips[c] ? 0.0f : m == 0 ? INFINITY : (float)(M_PI / (patch[c] / n[c] * (1 << m)));
            e->mip[m].mss_x = (float)(1e-3 * (c + 1) * (m + 1));
            e->mip[m].mss_z = (float)(5e-4 * (c + 1) * (m + 2));
            e->mip[m].mss_xz = (float)(-1e-4 * (m + 1));
        }
    }
    block_set_q(b, 1.0f / 1024);
    b->flags = PROTO_CASCADE_FOAM;
    b->foam_rows = 3;
    b->foam[0] = (proto_foam_row){0.02f, -0.03f, 0.8f};
    b->foam[1] = (proto_foam_row){0.08f, 0.1f, 1.1f};
    b->foam[2] = (proto_foam_row){0.2f, 0.3f, 1.5f};
}

/* A world point at horizontal distance d (direction th) from the block's
 * camera where the rule's s is sigma * 2^lambda (|cy| <= 1 here). */
static void point_at_level(const proto_cascade_block *b, double sigma, double lambda, double th, double *x,
                           double *z)
{
    double q = b->spacing_per_m, h = fabs(b->camera[1]) < 1 ? 1 : fabs(b->camera[1]);
    double s = sigma * pow(2.0, lambda);
    double d = sqrt((s / q) * (s / q) - h * h);
    *x = b->camera[0] + d * cos(th);
    *z = b->camera[2] + d * sin(th);
}

/* ===================================================== the lod rule */

static void lod_rule(void **state)
{
    (void)state;
    /* cascade 0: sigma 1000/256; cascade 1: sigma 250/256, 4 times finer,
     * so lambda_1 = lambda_0 + 2 at every point */
    const double patch[2] = {1000, 250};
    const int n[2] = {256, 256}, mips[2] = {6, 4}, fades[2] = {0, 1};
    proto_cascade_block b;
    block_init(&b, 2, patch, n, mips, fades);
    b.camera[0] = 123.25;
    b.camera[2] = -77.5;
    double s0 = 1000.0 / 256;
    struct {
        double lam0;
        int m0[2];
        double w0[2];
        int m1[2];
        double w1[2], fade1;
    } cases[] = {
        /* lambda_0 <= 0: mip 0; lambda_1 = 0.75: mips 0 and 1 */
        {-1.25, {0, -1}, {1, 0}, {0, 1}, {0.25, 0.75}, 1},
        {0.25, {0, 1}, {0.75, 0.25}, {2, 3}, {0.75, 0.25}, 1},
        /* lambda_1 = 3.5 >= mips - 1 = 3: last mip, faded by 4 - 3.5 */
        {1.5, {1, 2}, {0.5, 0.5}, {3, -1}, {0.5, 0}, 0.5},
        {1.9, {1, 2}, {0.1, 0.9}, {3, -1}, {0.1, 0}, 0.1},
        /* lambda_1 = 4.5: faded out */
        {2.5, {2, 3}, {0.5, 0.5}, {3, -1}, {0, 0}, 0},
        /* cascade 0 does not fade: its last mip at any distance */
        {7.0, {5, -1}, {1, 0}, {3, -1}, {0, 0}, 0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        double x, z;
        point_at_level(&b, s0, cases[i].lam0, 0.3 + i, &x, &z);
        oc_lod L;
        assert_int_equal(oc_cascade_lod(&b, x, z, 0, &L), OCEAN_OK);
        assert_int_equal(L.count, 2);
        assert_true(fabs(L.c[0].lambda - cases[i].lam0) < 1e-9);
        assert_true(fabs(L.c[1].lambda - (cases[i].lam0 + 2)) < 1e-9);
        for (int k = 0; k < 2; k++) {
            assert_int_equal(L.c[0].mip[k], cases[i].m0[k]);
            assert_true(fabs(L.c[0].weight[k] - cases[i].w0[k]) < 1e-9);
            if (cases[i].m1[k] >= 0 || L.c[1].mip[k] >= 0)
                assert_int_equal(L.c[1].mip[k], cases[i].m1[k]);
            assert_true(fabs(L.c[1].weight[k] - cases[i].w1[k]) < 1e-9);
        }
        assert_true(fabs(L.c[0].fade - 1) < 1e-12);
        assert_true(fabs(L.c[1].fade - cases[i].fade1) < 1e-9);
    }
    /* min_spacing_m of the block and the caller's floor (g_L) raise s */
    b.min_spacing_m = (float)(s0 * 8);
    oc_lod L;
    assert_int_equal(oc_cascade_lod(&b, b.camera[0], b.camera[2], 0, &L), OCEAN_OK);
    assert_true(fabs(L.s - s0 * 8) < 1e-6 && fabs(L.c[0].lambda - 3) < 1e-6);
    assert_int_equal(oc_cascade_lod(&b, b.camera[0], b.camera[2], s0 * 16, &L), OCEAN_OK);
    assert_true(fabs(L.c[0].lambda - 4) < 1e-12 && L.c[0].mip[0] == 4 && L.c[0].weight[0] == 1);
    /* |cy| below 1 m counts as 1 m: at the camera s = q * 1 */
    b.min_spacing_m = 0;
    b.camera[1] = 0.01;
    assert_int_equal(oc_cascade_lod(&b, b.camera[0], b.camera[2], 0, &L), OCEAN_OK);
    assert_true(fabs(L.s - 1.0 / 1024) < 1e-15);
    /* hostile input */
    assert_int_equal(oc_cascade_lod(&b, NAN, 0, 0, &L), OCEAN_EINVAL);
    assert_int_equal(oc_cascade_lod(&b, 0, 0, INFINITY, &L), OCEAN_EINVAL);
    b.spacing_per_m = 0;
    assert_int_equal(oc_cascade_lod(&b, 0, 0, 0, &L), OCEAN_EINVAL);
}

/* Each cascade at its own q_c (PROTOCOL.md "Where each mip is read"): the
 * server spends what one q for all leaves of the byte budget on the cascades
 * whose next step is cheap, so a cascade's levels follow its entry's q, not
 * the block's. */
static void lod_rule_per_cascade_q(void **state)
{
    (void)state;
    /* as lod_rule: lambda_1 = lambda_0 + 2 at one q; cascade 1 at q / 4
     * reads two levels finer, lambda_1 = lambda_0 */
    const double patch[2] = {1000, 250};
    const int n[2] = {256, 256}, mips[2] = {6, 4}, fades[2] = {0, 1};
    proto_cascade_block b;
    block_init(&b, 2, patch, n, mips, fades);
    b.camera[0] = -40;
    b.camera[1] = 25;
    b.cascade[1].spacing_per_m = b.spacing_per_m / 4;
    double s0 = 1000.0 / 256;
    for (double lam0 = 0.25; lam0 < 5; lam0 += 0.5) {
        double x, z;
        point_at_level(&b, s0, lam0, 1.0 + lam0, &x, &z);
        oc_lod L;
        assert_int_equal(oc_cascade_lod(&b, x, z, 0, &L), OCEAN_OK);
        assert_true(fabs(L.c[0].lambda - lam0) < 1e-9);
        assert_true(fabs(L.c[1].lambda - lam0) < 1e-9);
        assert_true(fabs(L.c[1].s - L.s / 4) < 1e-9 * L.s && fabs(L.c[0].s - L.s) < 1e-9 * L.s);
    }
    /* the floors (block min_spacing_m, the caller's g_L) hold every cascade */
    oc_lod L;
    assert_int_equal(oc_cascade_lod(&b, b.camera[0], b.camera[2], 8 * s0, &L), OCEAN_OK);
    assert_true(fabs(L.c[0].s - 8 * s0) < 1e-9 && fabs(L.c[1].s - 8 * s0) < 1e-9);
    /* a cascade's q must be > 0 and no coarser than the block's */
    b.cascade[1].spacing_per_m = 2 * b.spacing_per_m;
    assert_int_equal(oc_cascade_lod(&b, 0, 0, 0, &L), OCEAN_EINVAL);
    b.cascade[1].spacing_per_m = 0;
    assert_int_equal(oc_cascade_lod(&b, 0, 0, 0, &L), OCEAN_EINVAL);
    b.cascade[1].spacing_per_m = NAN;
    assert_int_equal(oc_cascade_lod(&b, 0, 0, 0, &L), OCEAN_EINVAL);
}

/* ============================================ blending, fading, moments */

/* Constant planes with a distinct value per (cascade, mip). */
static void const_fn(const field *F, int c, int m, double x, double z, double o[7])
{
    (void)F;
    (void)x;
    (void)z;
    o[0] = 10.0 * (c + 1) + (m + 1);
    o[1] = 0.125 * (c + 1) * (m + 1);
    o[2] = -0.0625 * (m + 1);
    o[3] = 0.01 * (c + 1) * (m + 1);
    o[4] = -0.02 * (m + 1);
    o[5] = 0.05 * (c + 1) * (m + 1);
    o[6] = -0.04 * (m + 1);
}

/* Whitecap foam as PROTOCOL.md "Whitecaps in layout 1" states it, written
 * out from the text: the table's a and omega linear in sigma = sqrt(var)
 * between the rows around it (the end rows beyond); the ramp
 * clamp((x - a) / (1/2 - a), 0, 1); the active foam at beta, or the
 * crest's foam at |beta + i q| decayed by exp(-arg / (omega 3.85 s)),
 * arg in [0, 2 pi), whichever is larger. */
static double spec_foam(const proto_cascade_block *b, double var, double beta, double q)
{
    const proto_foam_row *t = b->foam;
    int n = b->foam_rows, i = 0;
    double sg = sqrt(var), a = t[0].a, om = t[0].omega;
    if (sg >= t[n - 1].sigma) {
        a = t[n - 1].a;
        om = t[n - 1].omega;
    } else if (sg > t[0].sigma) {
        while (t[i + 1].sigma < sg) i++;
        double f = (sg - t[i].sigma) / (t[i + 1].sigma - t[i].sigma);
        a = t[i].a + f * (t[i + 1].a - t[i].a);
        om = t[i].omega + f * (t[i + 1].omega - t[i].omega);
    }
    double fi = fmin(1, fmax(0, (beta - a) / (0.5 - a)));
    double e = hypot(beta, q), th = atan2(q, beta);
    if (th < 0) th += 2 * M_PI;
    double tr = e > a ? fmin(1, fmax(0, (e - a) / (0.5 - a))) * exp(-th / (om * 3.85)) : 0;
    return fmax(fi, tr);
}

static void blend_and_fade(void **state)
{
    (void)state;
    const double patch[2] = {1000, 250};
    const int n[2] = {64, 64}, mips[2] = {6, 4}, fades[2] = {0, 1};
    proto_cascade_block b;
    block_init(&b, 2, patch, n, mips, fades);
    b.camera[0] = -5e6;    /* far from the origin: the patches wrap */
    b.camera[2] = 3e6 + 0.5;
    field F = {.fn = const_fn};
    oc_frame *f = decode_built(build_frame(&b, &F, PROTO_CH_HEIGHT | PROTO_CH_DX | PROTO_CH_DZ | PROTO_CH_NORMAL |
                                                       PROTO_CH_BREAKING,
                                           16, NULL, PROTO_CODEC_F32));
    assert_non_null(f->view);
    double s0 = 1000.0 / 64;
    const double lams[] = {-2, 0.25, 1.5, 1.9, 2.5, 7};
    int inside = 0;   /* points whose foam lies on a ramp or a trail, where every term counts */
    for (size_t i = 0; i < sizeof lams / sizeof lams[0]; i++) {
        double x, z;
        point_at_level(&b, s0, lams[i], 1.1 * i, &x, &z);
        /* the expected sum, from the rule evaluated by hand for lambda_0
         * and lambda_1 = lambda_0 + 2 (cascade 1 is 4 times finer) */
        double H = 0, DX = 0, SX = 0, BI = 0, BQ = 0, var = 0, mx = b.tail_mss[0], mxz = b.tail_mss[2];
        for (int c = 0; c < 2; c++) {
            double mx0 = mx, mz = 0;
            double lam = lams[i] + 2 * c, w[PROTO_MAX_MIPS + 1] = {0};
            int M = mips[c];
            double fade = 1;
            if (lam <= 0)
                w[0] = 1;
            else if (lam < M - 1)
                w[(int)lam] = 1 - (lam - floor(lam)), w[(int)lam + 1] = lam - floor(lam);
            else {
                fade = fades[c] ? fmin(1, fmax(0, M - lam)) : 1;
                w[M - 1] = fade;
            }
            for (int m = 0; m < M; m++) {
                double o[7];
                const_fn(&F, c, m, 0, 0, o);
                H += w[m] * o[0];
                DX += w[m] * o[1];
                SX += w[m] * o[3];
                BI += w[m] * o[5];
                BQ += w[m] * o[6];
                mx += w[m] * b.cascade[c].mip[m].mss_x;
                mz += w[m] * b.cascade[c].mip[m].mss_z;
                mxz += w[m] * b.cascade[c].mip[m].mss_xz;
            }
            mx += (1 - fade) * b.cascade[c].mip[M].mss_x;
            mz += (1 - fade) * b.cascade[c].mip[M].mss_z;
            mxz += (1 - fade) * b.cascade[c].mip[M].mss_xz;
            /* two entries blended with weights a, 1 - a add a (1 - a) (coarser - finer) */
            if (lam > 0 && lam < M - 1) {
                int m0 = (int)lam;
                double a = w[m0];
                mx += a * (1 - a) * (b.cascade[c].mip[m0 + 1].mss_x - b.cascade[c].mip[m0].mss_x);
                mz += a * (1 - a) * (b.cascade[c].mip[m0 + 1].mss_z - b.cascade[c].mip[m0].mss_z);
                mxz += a * (1 - a) * (b.cascade[c].mip[m0 + 1].mss_xz - b.cascade[c].mip[m0].mss_xz);
            } else if (fade > 0 && fade < 1) {
                mx += fade * (1 - fade) * (b.cascade[c].mip[M].mss_x - b.cascade[c].mip[M - 1].mss_x);
                mz += fade * (1 - fade) * (b.cascade[c].mip[M].mss_z - b.cascade[c].mip[M - 1].mss_z);
                mxz += fade * (1 - fade) * (b.cascade[c].mip[M].mss_xz - b.cascade[c].mip[M - 1].mss_xz);
            }
            /* the breaking-index variance held: the cascade's slope variance
             * less what its reads leave unresolved */
            var += (double)b.cascade[c].mip[M].mss_x + b.cascade[c].mip[M].mss_z - (mx - mx0) - mz;
        }
        double foam0 = spec_foam(&b, var, BI, BQ);
        inside += foam0 > 0 && foam0 < 1;
        oc_sample s;
        assert_int_equal(oc_frame_sample(f, x, z, 0, &s), OCEAN_OK);
        if (fabs(s.height - H) > 1e-5 || fabs(s.dx - DX) > 1e-6 || fabs(s.slope_x - SX) > 2e-6 ||
            fabs(s.mss[0] - mx) > 1e-7 || fabs(s.mss[2] - mxz) > 1e-7 || fabs(s.foam - foam0) > 1e-6) {
            print_error("lambda_0 %g: H %.9g (want %.9g) DX %.9g (%.9g) SX %.9g (%.9g) mss_x %.9g (%.9g) "
                        "mss_xz %.9g (%.9g) foam %.9g (%.9g)\n",
                        lams[i], s.height, H, s.dx, DX, s.slope_x, SX, s.mss[0], mx, s.mss[2], mxz, s.foam, foam0);
            fail();
        }
        assert_int_equal(s.channels, PROTO_CH_HEIGHT | PROTO_CH_DX | PROTO_CH_DZ | PROTO_CH_NORMAL | PROTO_CH_BREAKING);
        /* the normal is the normal of the summed slopes */
        double nl = sqrt(s.slope_x * s.slope_x + 1 + s.slope_z * s.slope_z);
        assert_true(fabs(s.normal[1] - 1 / nl) < 1e-12 && fabs(s.normal[0] + s.slope_x / nl) < 1e-12);
        /* linear and cubic agree on constant planes */
        oc_sample sl;
        assert_int_equal(oc_frame_sample_interp(f, x, z, 0, OC_INTERP_LINEAR, &sl), OCEAN_OK);
        assert_true(fabs(sl.height - s.height) < 1e-5);
    }
    assert_true(inside >= 4);
    /* hostile input and the wrong layout */
    oc_sample s;
    assert_int_equal(oc_frame_sample(f, NAN, 0, 0, &s), OCEAN_EINVAL);
    assert_int_equal(oc_frame_sample(f, 0, INFINITY, 0, &s), OCEAN_EINVAL);
    assert_int_equal(oc_frame_sample(NULL, 0, 0, 0, &s), OCEAN_EINVAL);
    oc_frame_free(f);

    proto_msg m;
    proto_msg_init(&m, PROTO_FRAME);
    m.u.frame.cutoff_k = 1;
    m.u.frame.camera_seq = PROTO_NO_CAMERA;
    proto_buf out;
    proto_buf_init(&out, 0);
    assert_int_equal(proto_encode(&out, &m, NULL, 0), OCEAN_OK);
    oc_frame *f0 = NULL;
    assert_int_equal(oc_frame_decode(proto_buf_data(&out), proto_buf_len(&out), &f0, NULL, 0), OCEAN_OK);
    assert_null(f0->view);
    assert_int_equal(oc_frame_sample(f0, 0, 0, 0, &s), OCEAN_ESTATE);
    oc_frame_free(f0);
    proto_buf_free(&out);
}

/* Geometry-free mips (PROTOCOL.md "Where each mip is read"): a mip with
 * 2^(m+1) sigma <= G carries NU, NV, BI, BQ alone, as the server sends it. */
static unsigned geometry_free_chan(const field *F, int c, int m, unsigned channels)
{
    (void)c;
    double sigma = 1000.0 / 64;
    if (ldexp(sigma, m + 1) <= F->G)
        channels &= PROTO_CH_NORMAL | PROTO_CH_BREAKING;
    return channels;
}

/* The spec's weights of cascade 0 (6 mips, no fade) at level lam. */
static void level_weights(double lam, int M, double w[PROTO_MAX_MIPS])
{
    memset(w, 0, sizeof(double) * PROTO_MAX_MIPS);
    if (lam <= 0)
        w[0] = 1;
    else if (lam < M - 1)
        w[(int)lam] = 1 - (lam - floor(lam)), w[(int)lam + 1] = lam - floor(lam);
    else
        w[M - 1] = 1;
}

/* With G in the block, height and displacement are read at max(s, G) and
 * slopes, foam and the unresolved moments at s: each from the mips the
 * rule names for its own spacing, so a point near the camera gets its
 * geometry from the first mip that carries it and its normals from the
 * finest.  The same tiles with G = 0 are read at s alone and the point
 * lacks the geometry the fine mips do not carry. */
static void geometry_read_at_G(void **state)
{
    (void)state;
    const double patch = 1000;
    const int n = 64, mips = 6, fades = 0;
    const double sigma = patch / n;
    proto_cascade_block b;
    block_init(&b, 1, &patch, &n, &mips, &fades);
    b.camera[0] = 300;
    b.camera[2] = -200;
    b.geometry_spacing_m = (float)(4 * sigma);   /* mips 0 and 1 geometry-free */
    field F = {.fn = const_fn, .chan = geometry_free_chan, .G = b.geometry_spacing_m};
    const unsigned all = PROTO_CH_HEIGHT | PROTO_CH_DX | PROTO_CH_DZ | PROTO_CH_NORMAL | PROTO_CH_BREAKING;
    oc_frame *f = decode_built(build_frame(&b, &F, all, 16, NULL, PROTO_CODEC_F32));
    const double lams[] = {-2, 0.25, 1.5, 2.5, 3.75};
    for (size_t i = 0; i < sizeof lams / sizeof lams[0]; i++) {
        double x, z, wg[PROTO_MAX_MIPS], ws[PROTO_MAX_MIPS];
        point_at_level(&b, sigma, lams[i], 0.7 * i, &x, &z);
        level_weights(fmax(lams[i], 2.0), mips, wg);  /* log2(G / sigma) = 2 */
        level_weights(lams[i], mips, ws);
        double H = 0, DX = 0, SX = 0, BI = 0, BQ = 0, MX = b.tail_mss[0], MZ = 0;
        for (int m = 0; m < mips; m++) {
            double o[7];
            const_fn(&F, 0, m, 0, 0, o);
            H += wg[m] * o[0];
            DX += wg[m] * o[1];
            SX += ws[m] * o[3];
            BI += ws[m] * o[5];
            BQ += ws[m] * o[6];
            MX += ws[m] * b.cascade[0].mip[m].mss_x;
            MZ += ws[m] * b.cascade[0].mip[m].mss_z;
        }
        double lam = lams[i];
        if (lam > 0 && lam < mips - 1) {
            int m0 = (int)lam;
            double a = ws[m0];
            MX += a * (1 - a) * (b.cascade[0].mip[m0 + 1].mss_x - b.cascade[0].mip[m0].mss_x);
            MZ += a * (1 - a) * (b.cascade[0].mip[m0 + 1].mss_z - b.cascade[0].mip[m0].mss_z);
        }
        /* foam at the shading levels (PROTOCOL.md: slopes, foam at s) */
        double FO = spec_foam(&b, (double)b.cascade[0].mip[mips].mss_x + b.cascade[0].mip[mips].mss_z -
                                      (MX - b.tail_mss[0]) - MZ, BI, BQ);
        oc_sample s;
        assert_int_equal(oc_frame_sample(f, x, z, 0, &s), OCEAN_OK);
        if (fabs(s.height - H) > 1e-5 || fabs(s.dx - DX) > 1e-6 || fabs(s.slope_x - SX) > 2e-6 ||
            fabs(s.foam - FO) > 1e-6 || fabs(s.mss[0] - MX) > 1e-7) {
            print_error("lambda %g: H %.9g (want %.9g) DX %.9g (%.9g) SX %.9g (%.9g) foam %.9g (%.9g) mss_x %.9g "
                        "(%.9g)\n", lams[i], s.height, H, s.dx, DX, s.slope_x, SX, s.foam, FO, s.mss[0], MX);
            fail();
        }
        assert_int_equal(s.channels, all);
        /* the mesh rule's floor g_L >= G reads the same geometry */
        oc_sample sg;
        assert_int_equal(oc_frame_sample(f, x, z, b.geometry_spacing_m, &sg), OCEAN_OK);
        assert_true(fabs(sg.height - H) < 1e-5);
        /* the surface inversion reads geometry at G too */
        assert_int_equal(oc_frame_surface(f, x, z, 0, &sg), OCEAN_OK);
        assert_int_equal(sg.channels, all);
    }
    oc_frame_free(f);
    /* the same tiles without G: near the camera the rule reads mip 0,
     * which has no geometry */
    b.geometry_spacing_m = 0;
    f = decode_built(build_frame(&b, &F, all, 16, NULL, PROTO_CODEC_F32));
    double x, z;
    point_at_level(&b, sigma, 0.25, 0, &x, &z);
    oc_sample s;
    assert_int_equal(oc_frame_sample(f, x, z, 0, &s), OCEAN_OK);
    assert_int_equal(s.channels, PROTO_CH_NORMAL | PROTO_CH_BREAKING);
    assert_true(s.height == 0);
    oc_frame_free(f);
}

/* ============================================ interpolation and wrap */

/* H = a cos(theta), theta = 2 pi (kx x + kz z) / P + phase, with choppy
 * displacement D = -chop a (k / |k|) sin(theta) (Tessendorf 2001) and the
 * slopes of H; foam 0.  The same wave in every mip. */
static void sin_fn(const field *F, int c, int m, double x, double z, double o[7])
{
    (void)c;
    (void)m;
    double kx = 2 * M_PI * F->kx / F->patch, kz = 2 * M_PI * F->kz / F->patch, k = hypot(kx, kz);
    double th = kx * x + kz * z + F->phase;
    o[0] = F->a * cos(th);
    o[1] = -F->chop * F->a * kx / k * sin(th);
    o[2] = -F->chop * F->a * kz / k * sin(th);
    o[3] = -F->a * kx * sin(th);
    o[4] = -F->a * kz * sin(th);
    o[5] = 0;
}

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static double urand(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}

/* One cascade of one mip (so the lod rule always reads mip 0). */
static oc_frame *sine_frame(field *F, double patch, int n, proto_codec codec)
{
    proto_cascade_block b;
    const int mips = 1, fades = 0;
    block_init(&b, 1, &patch, &n, &mips, &fades);
    F->fn = sin_fn;
    F->patch = patch;
    return decode_built(build_frame(&b, F, PROTO_CH_HEIGHT | PROTO_CH_DX | PROTO_CH_DZ | PROTO_CH_NORMAL, 16, NULL,
                                    codec));
}

static void sinusoid_and_wrap(void **state)
{
    (void)state;
    for (int pass = 0; pass < 2; pass++) {
        /* a power-of-two patch (x mod P exact by construction) and the
         * shipped ratio's 1000 / 4.3 m (x mod P only as exact as fmod) */
        double P = pass == 0 ? 256.0 : 1000.0 / 4.3;
        int n = 64;
        field F = {.a = 1.5, .kx = 3, .kz = 2, .phase = 0.3, .chop = 1.0};
        oc_frame *f = sine_frame(&F, P, n, PROTO_CODEC_F32);
        double h = P / n, kx = 2 * M_PI * F.kx / P, kz = 2 * M_PI * F.kz / P;
        /* linear interpolation remainder per axis: (h^2/8)(max|f_xx| + max|f_zz|) */
        double bH = h * h / 8 * F.a * (kx * kx + kz * kz) + 1e-5;
        double bS = h * h / 8 * F.a * kx * (kx * kx + kz * kz) + 1e-5;
        double bD = h * h / 8 * F.chop * F.a * (kx * kx + kz * kz) + 1e-5;
        double worst_lin = 0, worst_cub = 0, worst_l3 = 0;
        for (int i = 0; i < 400; i++) {
            double u = urand() * P, v = urand() * P;
            double ex[7];
            sin_fn(&F, 0, 0, u, v, ex);
            /* the same local point seen from far away: whole periods added */
            double shifts[3][2] = {{0, 0}, {43000 * P, -17 * P}, {-43000 * P, 43001 * P}};
            for (int k = 0; k < 3; k++) {
                double x = u + shifts[k][0], z = v + shifts[k][1];
                oc_sample sl, sc, s3;
                assert_int_equal(oc_frame_sample_interp(f, x, z, 0, OC_INTERP_LINEAR, &sl), OCEAN_OK);
                assert_int_equal(oc_frame_sample(f, x, z, 0, &sc), OCEAN_OK);
                assert_int_equal(oc_frame_sample_interp(f, x, z, 0, OC_INTERP_LANCZOS3, &s3), OCEAN_OK);
                double e3 = fabs(s3.height - ex[0]);
                if (e3 > worst_l3)
                    worst_l3 = e3;
                double el = fabs(sl.height - ex[0]), ec = fabs(sc.height - ex[0]);
                /* at 1e7 m, x itself carries up to an ulp (1.9e-9 m) of rounding */
                if (el > bH || ec > bH || fabs(sl.slope_x - ex[3]) > bS || fabs(sc.slope_x - ex[3]) > bS ||
                    fabs(sl.dx - ex[1]) > bD || fabs(sc.dz - ex[2]) > bD) {
                    print_error("P %g at (%.17g, %.17g): height lin %.9g cub %.9g exact %.9g (bound %.3g); slope "
                                "lin %.9g cub %.9g exact %.9g (bound %.3g)\n",
                                P, x, z, sl.height, sc.height, ex[0], bH, sl.slope_x, sc.slope_x, ex[3], bS);
                    fail();
                }
                if (el > worst_lin)
                    worst_lin = el;
                if (ec > worst_cub)
                    worst_cub = ec;
            }
        }
        /* Keys' kernel is third-order: it reads the
         * wave several times better than bilinear at ~18 samples a
         * wavelength (the reason it is the default) */
        if (!(worst_cub < worst_lin / 4)) {
            print_error("cubic worst %.3g, linear worst %.3g\n", worst_cub, worst_lin);
            fail();
        }
        assert_true(worst_lin > bH / 20);   /* the bound is not vacuous here */
        /* Lanczos-3 holds the near-Nyquist waves better but ripples in its
         * passband (~1 % of a well-sampled wave's amplitude): only the bound */
        if (!(worst_l3 < bH)) {
            print_error("Lanczos-3 worst %.3g (bound %.3g)\n", worst_l3, bH);
            fail();
        }
        print_message("P %g: worst height error linear %.4g, cubic %.4g, Lanczos-3 %.4g (bound %.4g)\n", P,
                      worst_lin, worst_cub, worst_l3, bH);
        oc_frame_free(f);
    }
}

/* ============================================ tiles missing and misplaced */

static int want_one(const field *F, int c, int m, int ix, int iz)
{
    (void)F;
    (void)c;
    return m > 0 || (ix == 1 && iz == 2);
}

static void missing_tiles(void **state)
{
    (void)state;
    double P = 256;
    int n = 64, mips = 3, fades = 0;
    proto_cascade_block b;
    block_init(&b, 1, &P, &n, &mips, &fades);
    block_set_q(&b, 1e-6f);   /* mip 0 everywhere */
    field F = {.fn = sin_fn, .want = want_one, .a = 1, .kx = 1, .kz = 1, .patch = P, .chop = 0.5};
    oc_frame *f = decode_built(build_frame(&b, &F, PROTO_CH_HEIGHT | PROTO_CH_NORMAL, 16, NULL, PROTO_CODEC_F32));
    /* mip 0 holds only tile (1, 2): samples [32, 48) x [16, 32) at 4 m */
    oc_sample s, sl;
    assert_int_equal(oc_frame_sample(f, 4 * 20.5, 4 * 40.5, 0, &s), OCEAN_OK);
    assert_int_equal(oc_frame_sample(f, 4 * 20.5 + 3 * P, 4 * 40.5 - 2 * P, 0, &s), OCEAN_OK);
    assert_int_equal(oc_frame_sample(f, 4 * 5.5, 4 * 40.5, 0, &s), OCEAN_ENOTFOUND);
    assert_true(s.height == 0 && s.channels == 0);
    /* next to the tile's edge the cubic's outer ring is missing: bilinear */
    assert_int_equal(oc_frame_sample(f, 4 * 16.25, 4 * 32.5, 0, &s), OCEAN_OK);
    assert_int_equal(oc_frame_sample_interp(f, 4 * 16.25, 4 * 32.5, 0, OC_INTERP_LINEAR, &sl), OCEAN_OK);
    assert_true(s.height == sl.height);
    oc_sample s3;
    assert_int_equal(oc_frame_sample_interp(f, 4 * 16.25, 4 * 32.5, 0, OC_INTERP_LANCZOS3, &s3), OCEAN_OK);
    assert_true(s3.height == sl.height);
    /* two samples in: Lanczos-3's 6 x 6 is cut, Keys' 4 x 4 fits */
    assert_int_equal(oc_frame_sample(f, 4 * 17.5, 4 * 40.5, 0, &s), OCEAN_OK);
    assert_int_equal(oc_frame_sample_interp(f, 4 * 17.5, 4 * 40.5, 0, OC_INTERP_LANCZOS3, &s3), OCEAN_OK);
    assert_int_equal(oc_frame_sample_interp(f, 4 * 17.5, 4 * 40.5, 0, OC_INTERP_LINEAR, &sl), OCEAN_OK);
    assert_true(s3.height == s.height && s.height != sl.height);
    /* the tile's last column: its right neighbour is missing */
    assert_int_equal(oc_frame_sample(f, 4 * 31.5, 4 * 40, 0, &s), OCEAN_ENOTFOUND);
    /* a coarser mip (all tiles present) serves the same point */
    assert_int_equal(oc_frame_sample(f, 4 * 5.5, 4 * 40.5, 4 * 4, &s), OCEAN_OK);
    /* channels not in the tiles read as zero and are not reported */
    assert_int_equal(s.channels, PROTO_CH_HEIGHT | PROTO_CH_NORMAL);
    assert_true(s.dx == 0 && s.foam == 0);
    oc_frame_free(f);
}

/* ============================================ samples in time */

/* One level everywhere: F->a. */
static void level_fn(const field *F, int c, int m, double x, double z, double o[7])
{
    (void)c;
    (void)m;
    (void)x;
    (void)z;
    memset(o, 0, 7 * sizeof *o);
    o[0] = F->a;
}

static int want_none(const field *F, int c, int m, int ix, int iz)
{
    (void)F;
    (void)c;
    (void)m;
    (void)ix;
    (void)iz;
    return 0;
}

/* Every mip of cascade 0: window (tick_a, interval) at w = phase / 65536. */
static void set_window(proto_cascade_block *b, uint32_t tick_a, uint16_t interval, uint16_t phase)
{
    for (int m = 0; m < b->cascade[0].mips; m++) {
        b->cascade[0].time[m].tick_a = tick_a;
        b->cascade[0].time[m].interval = interval;
        b->cascade[0].time[m].phase = phase;
    }
}

/* Decodes B through stream s (and alone, which gives `alone`: OCEAN_OK for
 * a frame that is whole by itself); frees B's bytes. */
static oc_frame *stream_frame(oc_frame_stream *s, built B, ocean_result alone)
{
    oc_frame *f = NULL;
    char err[256] = "";
    ocean_result r = oc_frame_decode(B.msg, B.len, &f, err, sizeof err);
    if (r != alone)
        print_error("oc_frame_decode alone: %s (%s), expected %s\n", ocean_strerror(r), err, ocean_strerror(alone));
    assert_int_equal(r, alone);
    oc_frame_free(f);
    r = oc_frame_stream_decode(s, B.msg, B.len, &f, err, sizeof err);
    if (r != OCEAN_OK)
        print_error("oc_frame_stream_decode: %s (%s)\n", ocean_strerror(r), err);
    assert_int_equal(r, OCEAN_OK);
    free(B.msg);
    return f;
}

/* The height f reads (mip 0 everywhere: q 1e-6) at a point off the grid. */
static double level_read(const oc_frame *f)
{
    oc_sample sm;
    assert_int_equal(oc_frame_sample(f, 10.3, -20.7, 0, &sm), OCEAN_OK);
    return sm.height;
}

/* Samples in time (PROTOCOL.md), through oc_frame_stream as a client does
 * on receipt: each frame reads (1 - w) A + w B of the samples held; a KEY
 * frame starts the windows it names (the next frame of the same window
 * keeps them: the store once dropped them instead, and every frame after
 * a KEY read nothing until its mips' windows moved twice); a new window
 * makes each tile's newest sample A (the held B when the window starts
 * there).  Only a KEY frame is whole alone.  Constant planes A = 1, B = 3, then B = 5:
 * each expected value is the spec's blend by hand. */
static void time_interp_stream(void **state)
{
    (void)state;
    double P = 64;
    int n = 16, mips = 2, fades = 0;
    proto_cascade_block b;
    block_init(&b, 1, &P, &n, &mips, &fades);
    block_set_q(&b, 1e-6f);
    field b3 = {.fn = level_fn, .a = 3}, key = {.fn = level_fn, .a = 1, .sample_b = &b3};
    field b5 = {.fn = level_fn, .a = 5}, shift = {.fn = level_fn, .sample_b = &b5, .b_only = 1};
    field none = {.fn = level_fn, .want = want_none};
    const unsigned H = PROTO_CH_HEIGHT;
    oc_frame_stream *s = NULL;
    assert_int_equal(oc_frame_stream_create(&s), OCEAN_OK);
    /* KEY, window (100, 4) at w = 1/4: both samples travel */
    b.flags |= PROTO_CASCADE_KEY;
    set_window(&b, 100, 4, 16384);
    oc_frame *f = stream_frame(s, build_frame_at(&b, &key, H, 8, NULL, PROTO_CODEC_F32, 101), OCEAN_OK);
    assert_true(fabs(level_read(f) - 1.5) < 1e-5);
    oc_frame_free(f);
    /* the same window at w = 1/2, no records: the samples held */
    b.flags &= ~PROTO_CASCADE_KEY;
    set_window(&b, 100, 4, 32768);
    f = stream_frame(s, build_frame_at(&b, &none, H, 8, NULL, PROTO_CODEC_F32, 102), OCEAN_ESTATE);
    assert_int_equal(f->info.tile_count, 0);
    assert_true(fabs(level_read(f) - 2.0) < 1e-5);
    /* its view's tiles are the blend: mip 0's 2 x 2 and mip 1's one */
    assert_int_equal(oc_frame_view_tile_count(f), 5);
    proto_tile ti;
    const float *d = NULL;
    assert_int_equal(oc_frame_view_tile(f, 4, &ti, &d), OCEAN_OK);
    assert_true(ti.payload == NULL && ti.channels == H && fabsf(d[0] - 2.0f) < 1e-6f);
    assert_int_equal(oc_frame_view_tile(f, 5, &ti, &d), OCEAN_EINVAL);
    oc_frame_free(f);
    /* the next window starts at B: B becomes A, the new B (5) travels */
    set_window(&b, 104, 4, 0);
    f = stream_frame(s, build_frame_at(&b, &shift, H, 8, NULL, PROTO_CODEC_F32, 104), OCEAN_ESTATE);
    assert_true(fabs(level_read(f) - 3.0) < 1e-5);
    oc_frame_free(f);
    set_window(&b, 104, 4, 49152);
    f = stream_frame(s, build_frame_at(&b, &none, H, 8, NULL, PROTO_CODEC_F32, 107), OCEAN_ESTATE);
    assert_true(fabs(level_read(f) - 4.5) < 1e-5);
    oc_frame_free(f);
    /* a window that does not follow the held one (frames skipped): each
     * tile's newest sample (B = 5) becomes A, read alone until its new
     * samples come; a held tile is replaced, never dropped */
    set_window(&b, 200, 4, 16384);
    f = stream_frame(s, build_frame_at(&b, &none, H, 8, NULL, PROTO_CODEC_F32, 201), OCEAN_ESTATE);
    assert_true(fabs(level_read(f) - 5.0) < 1e-5);
    assert_int_equal(oc_frame_view_tile_count(f), 5);
    oc_frame_free(f);
    oc_frame_stream_destroy(s);
    assert_int_equal(oc_frame_stream_create(NULL), OCEAN_EINVAL);
    assert_int_equal(oc_frame_stream_decode(NULL, NULL, 0, &f, NULL, 0), OCEAN_EINVAL);
    assert_null(f);
}

static void misplaced_tiles(void **state)
{
    (void)state;
    double P = 64;
    int n = 16, mips = 2, fades = 1;
    proto_cascade_block b;
    block_init(&b, 1, &P, &n, &mips, &fades);
    float planes[8 * 8] = {0};
    proto_buf pay;
    proto_buf_init(&pay, 0);
    assert_int_equal(proto_tile_encode(PROTO_CODEC_F32, NULL, 8, 8, PROTO_CH_HEIGHT, planes, &pay, NULL, NULL, 0),
                     OCEAN_OK);
    proto_tile good = {.level = 0, .codec = PROTO_CODEC_F32, .channels = PROTO_CH_HEIGHT, .width = 8, .height = 8,
                       .ix = 1, .iz = 0, .origin_x = 32, .origin_z = 0, .spacing = 4,
                       .payload_len = (uint32_t)proto_buf_len(&pay), .payload = proto_buf_data(&pay)};
    struct {
        const char *what, *needle;
        proto_tile t[2];
        int nt;
    } cases[] = {
        {"wrong spacing", "spacing", {good}, 1},
        {"mip beyond the block", "not in the cascade block", {good}, 1},
        {"wrong origin", "origin", {good}, 1},
        {"index outside", "outside", {good}, 1},
        {"sent twice", "twice", {good, good}, 2},
        {"fine", NULL, {good}, 1},
    };
    cases[0].t[0].spacing = 4.5;
    cases[1].t[0].level = 2;
    cases[1].t[0].spacing = 16;
    cases[2].t[0].origin_x = 31;
    cases[3].t[0].ix = 2;
    cases[3].t[0].origin_x = 64;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        proto_msg m;
        proto_msg_init(&m, PROTO_FRAME);
        m.u.frame.cutoff_k = INFINITY;
        m.u.frame.camera_seq = PROTO_NO_CAMERA;
        m.u.frame.layout = PROTO_LAYOUT_CASCADE;
        m.u.frame.cascades = b;
        m.u.frame.tile_count = (uint16_t)cases[i].nt;
        m.u.frame.tiles = cases[i].t;
        proto_buf out;
        proto_buf_init(&out, 0);
        assert_int_equal(proto_encode(&out, &m, NULL, 0), OCEAN_OK);
        oc_frame *f = NULL;
        char err[256] = "";
        ocean_result r = oc_frame_decode(proto_buf_data(&out), proto_buf_len(&out), &f, err, sizeof err);
        if (cases[i].needle) {
            if (r != OCEAN_EFORMAT || !strstr(err, cases[i].needle)) {
                print_error("%s: %s \"%s\"\n", cases[i].what, ocean_strerror(r), err);
                fail();
            }
            assert_null(f);
        } else {
            assert_int_equal(r, OCEAN_OK);
            oc_frame_free(f);
        }
        proto_buf_free(&out);
    }
    proto_buf_free(&pay);
}

/* ============================================ peek (header-only readers) */

static void peek_cascade_block(void **state)
{
    (void)state;
    const double patch[3] = {1000, 250, 60};
    const int n[3] = {16, 16, 16}, mips[3] = {2, 2, 1}, fades[3] = {0, 1, 1};
    proto_cascade_block b;
    block_init(&b, 3, patch, n, mips, fades);
    b.camera[0] = 1e6;
    b.camera[1] = 300;
    b.e_total = 0.03f;
    b.geometry_spacing_m = 4.0f;
    field F = {.fn = const_fn};
    built B = build_frame(&b, &F, PROTO_CH_HEIGHT, 8, NULL, PROTO_CODEC_F32);
    proto_frame pf;
    size_t at = 0;
    char err[200];
    assert_int_equal(oc_frame_peek(B.msg, OC_FRAME_PEEK_BYTES, B.len, &pf, &at, err, sizeof err), OCEAN_OK);
    assert_int_equal(pf.layout, 1);
    assert_int_equal(pf.cascades.cascade_count, 3);
    assert_true(pf.cascades.camera[0] == 1e6 && pf.cascades.camera[1] == 300);
    assert_true(pf.cascades.e_total == 0.03f);
    assert_true(pf.cascades.geometry_spacing_m == 4.0f);
    assert_int_equal(at, PROTO_HEADER_SIZE + 56 + 56 + 3 * 320 + 200);   /* and the whitecap table */
    /* the first record starts there: its length field is the first tile's */
    assert_int_equal(proto_ld32(B.msg + at), 48 + 8 * 8 * 4);
    assert_int_equal(oc_frame_peek(B.msg, 100, B.len, &pf, &at, err, sizeof err), OCEAN_ETRUNC);
    /* a length that cannot hold the block and the tiles */
    assert_int_equal(oc_frame_peek(B.msg, OC_FRAME_PEEK_BYTES, at + 10, &pf, &at, err, sizeof err), OCEAN_ETRUNC);
    /* a negative G (block offset 52) */
    proto_stf32(B.msg + PROTO_HEADER_SIZE + 56 + 52, -1.0f);
    assert_int_equal(oc_frame_peek(B.msg, OC_FRAME_PEEK_BYTES, B.len, &pf, &at, err, sizeof err), OCEAN_EINVAL);
    proto_stf32(B.msg + PROTO_HEADER_SIZE + 56 + 52, 4.0f);
    B.msg[PROTO_HEADER_SIZE + 56] = 7;   /* cascade_count */
    assert_int_equal(oc_frame_peek(B.msg, OC_FRAME_PEEK_BYTES, B.len, &pf, &at, err, sizeof err), OCEAN_EINVAL);
    B.msg[PROTO_HEADER_SIZE + 51] = 2;   /* layout */
    assert_int_equal(oc_frame_peek(B.msg, OC_FRAME_PEEK_BYTES, B.len, &pf, &at, err, sizeof err), OCEAN_ETYPE);
    free(B.msg);
}

/* ============================================ mesh in layout 1 */

static void morph_weights(void **state)
{
    (void)state;
    const float z[4] = {1, 10, 2, 0};
    /* smoothstep over [R - b, R + b]: 0 inside, 1 from the boundary on */
    assert_true(oc_mesh_morph_weight(z, 8.0, 0) == 0);
    assert_true(oc_mesh_morph_weight(z, 12.0, 0) == 1);
    assert_true(oc_mesh_morph_weight(z, 50.0, 0) == 1);
    assert_true(oc_mesh_morph_weight(z, 10.0, 0) == 0.5);
    /* u = 0.25: 3u^2 - 2u^3 = 0.15625 */
    assert_true(fabs(oc_mesh_morph_weight(z, 9.0, 0) - 0.15625) < 1e-15);
    const float step[4] = {1, 10, 0, 0};
    assert_true(oc_mesh_morph_weight(step, 10.0, 0) == 1);
    assert_true(oc_mesh_morph_weight(step, 9.999, 0) == 0);
    assert_true(oc_mesh_morph_weight(z, 50.0, 1) == 0);
}

/* H = m + 1 in mip m, no displacement: a vertex's height names the mip it read. */
static void mip_index_fn(const field *F, int c, int m, double x, double z, double o[7])
{
    (void)F;
    (void)c;
    (void)x;
    (void)z;
    memset(o, 0, 7 * sizeof *o);
    o[0] = m + 1;
    o[1] = 0.25;
    o[2] = -0.125;
}

static void mesh_positions(void **state)
{
    (void)state;
    /* one cascade, sigma = 0.25 m, 6 mips; q tiny so that s alone would
     * always read mip 0 and only g_L decides */
    double P = 64;
    int n = 256, mips = 6, fades = 0;
    proto_cascade_block b;
    block_init(&b, 1, &P, &n, &mips, &fades);
    block_set_q(&b, 1e-7f);
    b.camera[0] = 1000.5;
    b.camera[1] = 3;
    b.camera[2] = -2000;
    proto_mesh_placement pl = {.mesh_id = 42, .origin = {1000, 0, -2000}};
    field F = {.fn = mip_index_fn};
    oc_frame *f = decode_built(build_frame(&b, &F, PROTO_CH_HEIGHT | PROTO_CH_DX | PROTO_CH_DZ, 64, &pl,
                                           PROTO_CODEC_F32));
    /* three levels: lattices 1, 2, 4 m; zones R 10 / 30 m, blends 2 / 4 m */
    const float zones[12] = {1, 10, 2, 0, 2, 30, 4, 0, 4, 0, 0, 0};
    /* flat positions relative to the origin; the camera is at (+0.5, 0) */
    const float flat[] = {
        3, 1,      /* L0, d 2.7: w 0, stays */
        13, 1,     /* L0, d 12.54 >= R + b: w 1, onto the 2 m lattice (14, 2) */
        10.5, 0,   /* L0, d 10: w 0.5, halfway to (10, 0)... x: 10.5 - 0.5 (10.5 - 10) */
        35, 2,     /* L1, d 34.56 >= 34: w 1, onto the 4 m lattice (36, 4) */
        -37, 3,    /* L1, d 37.6: w 1, (-36, 4) */
        41, 5,     /* L2, coarsest: stays */
    };
    const uint8_t level[] = {0, 0, 0, 1, 1, 2};
    const uint32_t idx[3] = {0, 1, 2};
    const float morph[6] = {0};
    oc_topology t = {.mesh_id = 42, .mesh_kind = PROTO_MESH_CONCENTRIC, .lod_levels = 3, .vertex_count = 6,
                     .index_count = 3, .indices = idx, .morph = morph, .level = level, .flags = PROTO_TOPO_FLAT,
                     .flat = flat, .zones = zones};
    float xyz[18];
    assert_int_equal(oc_frame_mesh_positions(f, &t, xyz), OCEAN_OK);
    /* expected flat x, z after the morph (by hand from the spec's steps 1-2) */
    const double want[6][2] = {{3, 1}, {14, 2}, {10.25, 0}, {36, 4}, {-36, 4}, {41, 5}};
    for (int i = 0; i < 6; i++) {
        /* lambda = log2(g_L / 0.25): L0 -> mip 2, L1 -> 3, L2 -> 4; H = mip + 1 */
        double H = level[i] + 3;
        if (fabs(xyz[3 * i] - (want[i][0] + 0.25)) > 1e-5 || fabs(xyz[3 * i + 1] - H) > 1e-6 ||
            fabs(xyz[3 * i + 2] - (want[i][1] - 0.125)) > 1e-5) {
            print_error("vertex %d: (%g, %g, %g), want (%g, %g, %g)\n", i, xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2],
                        want[i][0] + 0.25, H, want[i][1] - 0.125);
            fail();
        }
    }
    /* the topology must be the placement's and FLAT */
    t.mesh_id = 41;
    assert_int_equal(oc_frame_mesh_positions(f, &t, xyz), OCEAN_EINVAL);
    t.mesh_id = 42;
    t.flags = 0;
    assert_int_equal(oc_frame_mesh_positions(f, &t, xyz), OCEAN_EINVAL);
    oc_frame_free(f);
}

/* ============================================ the surface at a world point */

static void surface_inversion(void **state)
{
    (void)state;
    double P = 256;
    field F = {.a = 1.2, .kx = 5, .kz = 1, .phase = 1.0, .chop = 1.5};
    oc_frame *f = sine_frame(&F, P, 128, PROTO_CODEC_F32);
    double h = P / 128, kx = 2 * M_PI * F.kx / P, kz = 2 * M_PI * F.kz / P;
    double k2 = kx * kx + kz * kz;
    for (int i = 0; i < 50; i++) {
        double x = (urand() - 0.5) * 2e4, z = (urand() - 0.5) * 2e4;
        /* the exact surface: Newton on the analytic p + D(p) = (x, z) */
        long double px = x, pz = z;
        for (int it = 0; it < 60; it++) {
            double o[7];
            sin_fn(&F, 0, 0, (double)px, (double)pz, o);
            long double rx = px + o[1] - x, rz = pz + o[2] - z;
            /* dD/dp = -chop a (k k^T / |k|) cos(theta) */
            long double th = kx * px + kz * pz + F.phase, g = -F.chop * F.a * cosl(th) / sqrtl(k2);
            long double a = 1 + g * kx * kx, bb = g * kx * kz, d = 1 + g * kz * kz, det = a * d - bb * bb;
            px -= (d * rx - bb * rz) / det;
            pz -= (-bb * rx + a * rz) / det;
        }
        double ex[7];
        sin_fn(&F, 0, 0, (double)px, (double)pz, ex);
        oc_sample s;
        assert_int_equal(oc_frame_surface(f, x, z, 0, &s), OCEAN_OK);
        /* height error: the interpolation bound, plus the slope times the
         * displacement's own bound (the point found is off by that much) */
        double bH = h * h / 8 * F.a * k2, bD = h * h / 8 * F.chop * F.a * k2;
        double bound = bH + F.a * sqrt(k2) * 2 * bD + 1e-5;
        if (fabs(s.height - ex[0]) > bound || s.residual > 1e-4) {
            print_error("(%g, %g): surface %.9g exact %.9g (bound %.3g), residual %.3g\n", x, z, s.height, ex[0], bound,
                        s.residual);
            fail();
        }
    }
    oc_frame_free(f);
}

/* ============================================ against the real daemon */

/*
 * The heights the library reads from the daemon's layout-1 frames next to
 * the camera against QUERY_RESULT at the frame's tick (queries are exact
 * sums of the same waves, within their error_bound).  The daemon runs the
 * ship-bridge scene with one pixel per sample and a frame budget no camera
 * reaches (server.px_per_sample = 1, server.viewer_bytes_per_s = 1e10) and
 * without the Gerstner near field (which layout 1 carries as roughness,
 * not in tiles), the client asks for f32 tiles and 1 mm spacing: then the
 * frame carries every wave of every cascade near the camera (e_error = 0,
 * asserted) and what remains is the library's reading of each cascade's
 * grid between its samples (Keys cubic, third-order: waves of a cascade
 * close to its two-samples-a-wavelength limit are read only roughly).
 * Stated bound, over 200 points within 30 m of a camera 10 m up: RMS of
 * (library - query) <= 1.5 cm and every point within 6 cm + the query's
 * own error_bound (ship-bridge: Hs ~ 2.6 m).  Measured against accurate
 * queries: RMS 6 mm, max 2 cm.
 */
static void daemon_layout1_heights(void **state)
{
    (void)state;
    const char *args[] = {"--scene", "ship-bridge", "--set", "server.px_per_sample=1", "--set",
                          "server.viewer_bytes_per_s=1e10", "--set", "server.near_field_waves=0", NULL};
    oc_client *c = NULL;
    pid_t pid = test_oceand_up(args, 200, &c);
    char err[256] = "";
    ocean_result r;
    proto_subscribe sub;
    oc_subscribe_default(&sub);
    /* the library's reading of one tick's tiles against QUERY at that
     * tick: the plain stream (time interpolation adds its own error, up to
     * the quantiser's at the subscription's accuracy, to these f32 tiles) */
    sub.flags &= (uint8_t)~PROTO_SUB_TIME_INTERP;
    sub.codec = PROTO_CODEC_F32;
    sub.base_spacing_m = 0.001f;
    sub.mesh_kind = PROTO_MESH_NONE;
    assert_int_equal(sub.layout, PROTO_LAYOUT_CASCADE);
    assert_int_equal(oc_client_subscribe(c, &sub), OCEAN_OK);
    proto_camera cam;
    oc_camera_default(&cam);
    cam.pos[0] = 1234.5;
    cam.pos[1] = 10;
    cam.pos[2] = -321.25;
    cam.pitch_deg = -30;
    assert_int_equal(oc_client_send_camera(c, &cam, NULL), OCEAN_OK);
    oc_frame *f = NULL;
    /* the first frames may answer before the CAMERA: wait for one made for it */
    for (int i = 0; i < 60; i++) {
        r = oc_client_next_frame(c, 5000, &f);
        if (r != OCEAN_OK)
            break;
        if (f->info.camera_seq != PROTO_NO_CAMERA && f->info.layout == PROTO_LAYOUT_CASCADE &&
            f->info.cascades.camera[0] == cam.pos[0])
            break;
        oc_frame_free(f);
        f = NULL;
    }
    if (!f) {
        oc_client_last_error(c, err, sizeof err);
        print_error("no layout-1 frame for the camera: %s (%s)\n", ocean_strerror(r), err);
    }
    int ok = f != NULL;
    double sum2 = 0, worst = 0, e_error = NAN;
    int got = 0, notfound = 0, beyond = 0;
    if (ok) {
        if (!f->view) {
            print_error("frame has no view: %s\n", f->view_error);
            ok = 0;
        }
        e_error = f->info.e_error;
    }
    if (ok) {
        enum { NP = 200 };
        double xz[2 * NP];
        for (int i = 0; i < NP; i++) {
            double rr = 30 * sqrt(urand()), th = 2 * M_PI * urand();
            xz[2 * i] = cam.pos[0] + rr * cos(th);
            xz[2 * i + 1] = cam.pos[2] + rr * sin(th);
        }
        oc_query_result q = {0};
        r = oc_client_query(c, xz, NP, 1, f->hdr.sim_time, 10000, &q);
        if (r != OCEAN_OK) {
            oc_client_last_error(c, err, sizeof err);
            print_error("query: %s (%s)\n", ocean_strerror(r), err);
            ok = 0;
        } else {
            for (int i = 0; i < NP; i++) {
                oc_sample s;
                ocean_result sr = oc_frame_surface(f, xz[2 * i], xz[2 * i + 1], 0, &s);
                if (sr == OCEAN_ENOTFOUND) {
                    notfound++;
                    continue;
                }
                double d = s.height - q.samples[i].height;
                sum2 += d * d;
                if (fabs(d) > worst)
                    worst = fabs(d);
                if (fabs(d) > 0.06 + q.samples[i].error_bound) {
                    if (beyond++ < 5)
                        print_error("(%.3f, %.3f): library %.4f m, query %.4f m (bound %.2g)\n", xz[2 * i],
                                    xz[2 * i + 1], s.height, q.samples[i].height, q.samples[i].error_bound);
                }
                got++;
            }
            oc_query_result_free(&q);
        }
    }
    oc_frame_free(f);
    oc_client_destroy(c);
    test_oceand_stop(pid);
    assert_true(ok);
    double rms = got ? sqrt(sum2 / got) : NAN;
    print_message("layout-1 heights vs QUERY_RESULT: %d points, RMS %.4f m, max %.4f m, %d outside the tiles, "
                  "frame e_error %g\n", got, rms, worst, notfound, e_error);
    assert_true(e_error == 0);
    assert_int_equal(notfound, 0);
    assert_true(got == 200);
    assert_true(rms <= 0.015);
    assert_int_equal(beyond, 0);
}

int main(void)
{
    signal(SIGPIPE, SIG_IGN);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(lod_rule),
        cmocka_unit_test(lod_rule_per_cascade_q),
        cmocka_unit_test(blend_and_fade),
        cmocka_unit_test(geometry_read_at_G),
        cmocka_unit_test(sinusoid_and_wrap),
        cmocka_unit_test(missing_tiles),
        cmocka_unit_test(time_interp_stream),
        cmocka_unit_test(misplaced_tiles),
        cmocka_unit_test(peek_cascade_block),
        cmocka_unit_test(morph_weights),
        cmocka_unit_test(mesh_positions),
        cmocka_unit_test(surface_inversion),
        cmocka_unit_test(daemon_layout1_heights),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
