/*
 * test_codec.c - tile codecs: half-float conversion, octahedral normals,
 * every codec's round trip within its stated bound on synthetic and real
 * ocean tiles, the default codec's size/PSNR target, EXR payloads read back
 * by OpenEXRCore's own file reader, and hostile payloads refused cleanly.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <openexr.h>

#include "bench/tile_source.h"
#include "bench/qz_before.h"
#include "codec.h"
#include "slope.h"

static int sanitized(void) { return getenv("OCEAN_TEST_SANITIZED") != NULL; }

/* A synthetic sea-like field: a sum of sines with incommensurate wave numbers. */
static void synth(float *p, int w, int h, unsigned channels, double scale)
{
    int np = proto_tile_planes(channels);
    for (int c = 0; c < np; c++)
        for (int i = 0; i < h; i++)
            for (int j = 0; j < w; j++) {
                double x = j * 1.7, z = i * 1.3;
                double v = scale * (sin(0.11 * x + 0.07 * z + c) + 0.4 * sin(0.37 * x - 0.21 * z + 2 * c) +
                                    0.1 * sin(1.9 * x + 1.3 * z));
                p[(size_t)c * w * h + (size_t)i * w + j] = (float)v;
            }
}

static void test_f16_values(void **state)
{
    (void)state;
    assert_int_equal(proto_f16_from_f32(1.0f), 0x3c00);
    assert_int_equal(proto_f16_from_f32(-2.0f), 0xc000);
    assert_int_equal(proto_f16_from_f32(65504.0f), 0x7bff);
    assert_int_equal(proto_f16_from_f32(65519.0f), 0x7bff);
    assert_int_equal(proto_f16_from_f32(65520.0f), 0x7c00);  /* tie rounds to even = inf */
    assert_int_equal(proto_f16_from_f32(0x1p-24f), 0x0001);
    assert_int_equal(proto_f16_from_f32(0x1p-25f), 0x0000);  /* tie to even */
    assert_int_equal(proto_f16_from_f32(0x1.8p-24f), 0x0002); /* 1.5 ulp -> 2 */
    assert_int_equal(proto_f16_from_f32(0x1p-14f), 0x0400);
    assert_int_equal(proto_f16_from_f32(1.0f + 0x1p-11f), 0x3c00); /* tie to even */
    assert_int_equal(proto_f16_from_f32(1.0f + 0x1.8p-11f), 0x3c01);
    assert_int_equal(proto_f16_from_f32(INFINITY), 0x7c00);
    assert_true((proto_f16_from_f32(NAN) & 0x7c00) == 0x7c00 && (proto_f16_from_f32(NAN) & 0x3ff));
    /* every finite half survives half -> float -> half */
    for (uint32_t hv = 0; hv < 0x10000; hv++) {
        if ((hv & 0x7c00) == 0x7c00)
            continue;
        float f = proto_f32_from_f16((uint16_t)hv);
        assert_int_equal(proto_f16_from_f32(f), hv);
    }
    assert_true(proto_f32_from_f16(0x3555) > 0.333f && proto_f32_from_f16(0x3555) < 0.3334f);
}

static void test_octahedral(void **state)
{
    (void)state;
    srand(7);
    double worst = 0;
    for (int k = 0; k < 20000; k++) {
        float v[3];
        double l2;
        do {
            for (int i = 0; i < 3; i++)
                v[i] = 2.0f * rand() / (float)RAND_MAX - 1.0f;
            l2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        } while (l2 < 1e-4 || l2 > 1);
        float u, w, n[3];
        proto_normal_oct_encode(v[0], v[1], v[2], &u, &w);
        assert_true(fabsf(u) <= 1.0f && fabsf(w) <= 1.0f);
        proto_normal_oct_decode(u, w, &n[0], &n[1], &n[2]);
        double l = sqrt(l2), d = 0;
        for (int i = 0; i < 3; i++)
            d = fmax(d, fabs(n[i] - v[i] / l));
        worst = fmax(worst, d);
    }
    assert_true(worst < 1e-5);
    float u, w, n[3];
    proto_normal_oct_encode(0, 1, 0, &u, &w); /* straight up -> centre */
    assert_true(u == 0 && w == 0);
    proto_normal_oct_encode(0, -1, 0, &u, &w); /* straight down -> corner */
    assert_true(fabsf(u) == 1 && fabsf(w) == 1);
    proto_normal_oct_decode(u, w, &n[0], &n[1], &n[2]);
    assert_true(n[1] < -0.999f);
    /* slopes helper: slope (0.5, -0.25) -> normal (-0.5, 1, 0.25) / |.| */
    float sx = 0.5f, sz = -0.25f;
    proto_normals_from_slopes(&sx, &sz, 1, &u, &w);
    proto_normal_oct_decode(u, w, &n[0], &n[1], &n[2]);
    double l = sqrt(0.25 + 1 + 0.0625);
    assert_true(fabs(n[0] + 0.5 / l) < 1e-6 && fabs(n[1] - 1 / l) < 1e-6 && fabs(n[2] - 0.25 / l) < 1e-6);
}

static void test_names(void **state)
{
    (void)state;
    for (int c = 0; c < PROTO_CODEC_COUNT_; c++) {
        proto_codec back;
        assert_int_equal(proto_codec_parse(proto_codec_name((proto_codec)c), &back), OCEAN_OK);
        assert_int_equal(back, c);
    }
    proto_codec x;
    assert_int_equal(proto_codec_parse("jpeg", &x), OCEAN_ETYPE);
    assert_int_equal(proto_tile_planes(PROTO_CH_ALL), 9);
    assert_int_equal(proto_tile_planes(PROTO_CH_NORMAL), 2);
    assert_int_equal(proto_tile_planes(0), 0);
    assert_int_equal(proto_tile_planes(0x80), 0);
    assert_int_equal(proto_tile_planes(PROTO_CH_BREAKING), 2);
    assert_string_equal(proto_tile_plane_name(PROTO_CH_HEIGHT | PROTO_CH_NORMAL | PROTO_CH_FOAM, 2), "NV");
    assert_string_equal(proto_tile_plane_name(PROTO_CH_ALL, 6), "J");
    assert_string_equal(proto_tile_plane_name(PROTO_CH_ALL, 8), "BQ");
    assert_string_equal(proto_tile_plane_name(PROTO_CH_NORMAL | PROTO_CH_BREAKING, 2), "BI");
    assert_null(proto_tile_plane_name(PROTO_CH_ALL, 9));
    assert_null(proto_tile_plane_name(PROTO_CH_HEIGHT, 1));
}

/* Round trip of one tile with codec c; checks the reported error, the
 * a-priori bound per plane and returns the payload size. */
static size_t roundtrip(proto_codec c, const proto_codec_params *p, int w, int h, unsigned ch, const float *src)
{
    int np = proto_tile_planes(ch);
    size_t n = (size_t)w * h;
    float *back = malloc(n * np * sizeof *back);
    proto_buf b;
    proto_buf_init(&b, 16);
    char err[256] = "";
    double merr = -1;
    ocean_result r = proto_tile_encode(c, p, w, h, ch, src, &b, &merr, err, sizeof err);
    if (r != OCEAN_OK)
        fail_msg("%s encode %dx%d: %s", proto_codec_name(c), w, h, err);
    r = proto_tile_decode(c, w, h, ch, proto_buf_data(&b), proto_buf_len(&b), back, err, sizeof err);
    if (r != OCEAN_OK)
        fail_msg("%s decode %dx%d: %s", proto_codec_name(c), w, h, err);
    double measured = 0, h_range = 0;
    for (int k = 0; k < np; k++) {
        const float *s = src + k * n, *d = back + k * n;
        float lo = s[0], hi = s[0];
        double e = 0;
        for (size_t i = 0; i < n; i++) {
            lo = fminf(lo, s[i]);
            hi = fmaxf(hi, s[i]);
            e = fmax(e, fabs((double)d[i] - s[i]));
        }
        if (k == 0 && (ch & PROTO_CH_HEIGHT))
            h_range = (double)hi - lo;
        double bound = proto_codec_plane_error_bound(c, p, ch, k, lo, hi, h_range);
        /* the per-plane budget is never looser than the relative one, but
         * for the normals (absolute) and DX/DZ (height's metres) */
        const char *nm = proto_tile_plane_name(ch, k);
        if (c == PROTO_CODEC_QZ && nm && (!strcmp(nm, "H") || !strcmp(nm, "J") || !strcmp(nm, "FOAM")))
            assert_true(bound <= proto_codec_error_bound(c, p, lo, hi));
        if (e > bound)
            fail_msg("%s plane %d: error %g above bound %g", proto_codec_name(c), k, e, bound);
        measured = fmax(measured, e);
    }
    if (proto_codec_lossless(c))
        assert_true(measured == 0.0);
    if (fabs(measured - merr) > 1e-12)
        fail_msg("%s: reported error %g, measured %g", proto_codec_name(c), merr, measured);
    size_t len = proto_buf_len(&b);
    proto_buf_free(&b);
    free(back);
    return len;
}

static void test_roundtrip_synthetic(void **state)
{
    (void)state;
    proto_codec_params p;
    proto_codec_params_default(&p);
    const int sizes[][2] = {{1, 1}, {2, 3}, {5, 4}, {17, 9}, {64, 64}, {33, 65}};
    const unsigned chans[] = {PROTO_CH_HEIGHT, PROTO_CH_ALL, PROTO_CH_NORMAL | PROTO_CH_FOAM};
    float *buf = malloc(PROTO_TILE_MAX_PLANES * 65 * 65 * sizeof *buf);
    for (int c = 0; c < PROTO_CODEC_COUNT_; c++)
        for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++)
            for (size_t k = 0; k < 3; k++) {
                synth(buf, sizes[s][0], sizes[s][1], chans[k], 3.0);
                assert_true(roundtrip((proto_codec)c, &p, sizes[s][0], sizes[s][1], chans[k], buf) > 0);
            }
    /* constant planes, a plane of zeros, tiny and large magnitudes */
    for (int c = 0; c < PROTO_CODEC_COUNT_; c++) {
        for (int i = 0; i < 64; i++)
            buf[i] = 1.25f;
        roundtrip((proto_codec)c, &p, 8, 8, PROTO_CH_HEIGHT, buf);
        memset(buf, 0, 64 * sizeof *buf);
        roundtrip((proto_codec)c, &p, 8, 8, PROTO_CH_HEIGHT, buf);
        synth(buf, 8, 8, PROTO_CH_HEIGHT, 1e-6);
        roundtrip((proto_codec)c, &p, 8, 8, PROTO_CH_HEIGHT, buf);
        synth(buf, 8, 8, PROTO_CH_HEIGHT, 3e4);
        roundtrip((proto_codec)c, &p, 8, 8, PROTO_CH_HEIGHT, buf);
    }
    free(buf);
}

static void test_qz_accuracy(void **state)
{
    (void)state;
    float *buf = malloc(48 * 40 * sizeof *buf), *back = malloc(48 * 40 * sizeof *back);
    synth(buf, 48, 40, PROTO_CH_HEIGHT, 2.0);
    float lo = buf[0], hi = buf[0];
    for (int i = 0; i < 48 * 40; i++)
        lo = fminf(lo, buf[i]), hi = fmaxf(hi, buf[i]);
    size_t prev = 0;
    const double accs[] = {0.5, 0.1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6};
    for (size_t a = 0; a < sizeof accs / sizeof accs[0]; a++) {
        proto_codec_params p;
        proto_codec_params_default(&p);
        p.accuracy = accs[a];
        proto_buf b;
        proto_buf_init(&b, 0);
        double merr;
        assert_int_equal(proto_tile_encode(PROTO_CODEC_QZ, &p, 48, 40, PROTO_CH_HEIGHT, buf, &b, &merr, NULL, 0), OCEAN_OK);
        assert_int_equal(proto_tile_decode(PROTO_CODEC_QZ, 48, 40, PROTO_CH_HEIGHT, proto_buf_data(&b), b.len, back, NULL, 0), OCEAN_OK);
        double e = 0;
        for (int i = 0; i < 48 * 40; i++)
            e = fmax(e, fabs((double)back[i] - buf[i]));
        /* the accuracy target: max error <= accuracy * range (+ float rounding) */
        assert_true(e <= accs[a] * (hi - lo) * (1 + 1e-6) + 4 * 0x1p-24);
        assert_true(e == merr);
        assert_true(b.len >= prev); /* finer accuracy never gets smaller */
        prev = b.len;
        proto_buf_free(&b);
    }
    /* accuracy outside its range is refused */
    proto_codec_params p;
    proto_codec_params_default(&p);
    p.accuracy = 1e-9;
    proto_buf b;
    proto_buf_init(&b, 0);
    char err[128];
    assert_int_equal(proto_tile_encode(PROTO_CODEC_QZ, &p, 48, 40, PROTO_CH_HEIGHT, buf, &b, NULL, err, sizeof err), OCEAN_EINVAL);
    assert_int_equal(b.len, 0);
    free(buf);
    free(back);
}

/* The default codec on real ocean tiles: <= 1/8 of f32 bytes, height PSNR
 * (peak = tile range) >= 50 dB for every tile; every codec within bound. */
static void test_real_ocean(void **state)
{
    (void)state;
    const struct { double u10, patch; } seas[] = {{5, 256}, {10, 1000}, {25, 2000}};
    const int T = 64, per = sanitized() ? 2 : 6;
    size_t m = (size_t)T * T;
    float *tile = malloc(PROTO_TILE_MAX_PLANES * m * sizeof *tile), *back = malloc(m * sizeof *back);
    double total = 0;
    int count = 0;
    proto_codec_params p;
    proto_codec_params_default(&p);
    for (int s = 0; s < 3; s++) {
        tile_source src;
        assert_int_equal(tile_source_open(&src, seas[s].u10, 256, seas[s].patch, 500.0), 0);
        for (int t = 0; t < per; t++) {
            tile_source_cut(&src, t * 29, t * 71, T, T, tile);
            proto_buf b;
            proto_buf_init(&b, 0);
            char err[256];
            assert_int_equal(proto_tile_encode(PROTO_CODEC_DEFAULT, &p, T, T, PROTO_CH_HEIGHT, tile, &b, NULL, err, sizeof err), OCEAN_OK);
            assert_int_equal(proto_tile_decode(PROTO_CODEC_DEFAULT, T, T, PROTO_CH_HEIGHT, proto_buf_data(&b), b.len, back, err, sizeof err), OCEAN_OK);
            float lo = tile[0], hi = tile[0];
            double sq = 0;
            for (size_t k = 0; k < m; k++) {
                lo = fminf(lo, tile[k]);
                hi = fmaxf(hi, tile[k]);
                sq += ((double)back[k] - tile[k]) * ((double)back[k] - tile[k]);
            }
            double psnr = 20 * log10((hi - lo) / sqrt(sq / m));
            if (psnr < 50.0)
                fail_msg("sea %d tile %d: PSNR %.2f dB < 50", s, t, psnr);
            total += (double)b.len;
            count++;
            proto_buf_free(&b);
            if (t == 0)
                for (int c = 0; c < PROTO_CODEC_COUNT_; c++)
                    roundtrip((proto_codec)c, &p, T, T, PROTO_CH_WORLD, tile);
        }
        tile_source_close(&src);
    }
    double ratio = total / count / (4.0 * m);
    print_message("default codec: %.0f bytes per 64x64 height tile = 1/%.2f of f32\n", total / count, 1 / ratio);
    assert_true(ratio <= 1.0 / 8.0);
    free(tile);
    free(back);
}

/* ---- qz format 2 on the tiles the browser viewer receives ---------------- */

/* Layout-1 mip tiles of the scene `make run` serves (config/oceand.conf's
 * scene, every mip of every cascade, 32 x 32 as server.cascade_tile, the
 * viewer's channels), at the viewer's accuracy 5e-3:
 *  - the quantised levels travel losslessly: every decoded sample equals
 *    f32(base + round((x - base) / step) * step) recomputed here from the
 *    header's base and step, so the LSX predictor (with its reference
 *    plane) round-trips exactly;
 *  - each plane within its stated budget; the normal's angle error, from
 *    the decoded and the input unit vectors, within 2.2 x accuracy rad
 *    (test_normal_budget_angle) and below a tenth of the per-axis slope
 *    spread the viewer always adds for the waves shorter than the
 *    simulation (sqrt of the tail's mss_x, mss_z: Elfouhaily et al. 1997
 *    via slope.h, as srv_cascade.c sends it), so the shaded glint cannot
 *    tell; foam within half of 1/255;
 *  - height PSNR (peak = tile range) >= 50 dB on every tile;
 *  - issue 14's target: all tiles together <= 1/8 of their f32 bytes. */
static void test_qz_layout1_tiles(void **state)
{
    (void)state;
    tile_l1 s;
    assert_int_equal(tile_l1_open(&s, "config/oceand.conf", "config/scenes/ship-bridge.conf", 100.0), 0);
    const int T = 32;
    proto_codec_params p;
    proto_codec_params_default(&p);
    p.accuracy = 5e-3;
    float *tile = malloc(PROTO_TILE_MAX_PLANES * T * T * sizeof *tile), *back = malloc(PROTO_TILE_MAX_PLANES * T * T * sizeof *back);
    double bytes = 0, raw = 0, worst_deg = 0, worst_psnr = INFINITY;
    int tiles = 0, with_ref = 0;
    for (int c = 0; c < s.cascades; c++)
        for (int m = 0; m < TILE_L1_MIPS; m++) {
            int nt = tile_l1_count(&s, c, m, T);
            for (int t = 0; t < nt * nt; t += sanitized() ? 7 : 1) {
                unsigned ch = tile_l1_channels(c);
                int np = proto_tile_planes(ch);
                size_t n = (size_t)T * T;
                assert_int_equal(tile_l1_cut(&s, c, m, t % nt, t / nt, T, tile), 0);
                proto_buf b;
                proto_buf_init(&b, 0);
                char err[256];
                assert_int_equal(proto_tile_encode(PROTO_CODEC_QZ, &p, T, T, ch, tile, &b, NULL, err, sizeof err), OCEAN_OK);
                assert_int_equal(proto_tile_decode(PROTO_CODEC_QZ, T, T, ch, b.mem, b.len, back, err, sizeof err), OCEAN_OK);
                const uint8_t *d = b.mem;
                assert_int_equal(d[1], 2); /* format 2 */
                size_t off = 4;
                double h_range = 0;
                for (int k = 0; k < np; k++) {
                    float base, step;
                    memcpy(&base, d + off, 4);
                    memcpy(&step, d + off + 4, 4);
                    int pred = d[off + 9], ref = d[off + 10];
                    with_ref += pred == 3 && ref == 0;
                    off += 12 + (pred == 3 ? 2 * (ref == 255 ? 8 : 17) : 0);
                    const float *x = tile + k * n, *y = back + k * n;
                    float lo = x[0], hi = x[0];
                    for (size_t i = 0; i < n; i++)
                        lo = fminf(lo, x[i]), hi = fmaxf(hi, x[i]);
                    assert_true(base == lo);
                    if (k == 0)
                        h_range = (double)hi - lo;
                    double bound = proto_codec_plane_error_bound(PROTO_CODEC_QZ, &p, ch, k, lo, hi, h_range);
                    /* levels round half up (PROTOCOL.md), clamped to the top level */
                    double top = llround(((double)hi - lo) / step);
                    for (size_t i = 0; i < n; i++) {
                        double tq = ((double)x[i] - base) / step, lev = trunc(tq);
                        lev = fmin(lev + (tq - lev >= 0.5), top);
                        float want = (float)((double)base + lev * step);
                        if (y[i] != want)
                            fail_msg("c%d m%d tile %d plane %d sample %zu: %.9g, levels give %.9g", c, m, t, k, i,
                                     (double)y[i], (double)want);
                        if (fabs((double)y[i] - x[i]) > bound)
                            fail_msg("plane %d error %g above bound %g", k, fabs((double)y[i] - x[i]), bound);
                    }
                    if (k >= 5) /* BI, BQ: accuracy x max(range, 3/2) (PROTOCOL.md "qz") */
                        assert_true(bound <= p.accuracy * fmax((double)hi - lo, 1.5) * (1 + 1e-6) + 1e-6);
                }
                double sq = 0;
                float lo = tile[0], hi = tile[0];
                for (size_t i = 0; i < n; i++) {
                    sq += ((double)back[i] - tile[i]) * ((double)back[i] - tile[i]);
                    lo = fminf(lo, tile[i]), hi = fmaxf(hi, tile[i]);
                }
                worst_psnr = fmin(worst_psnr, 20 * log10((hi - lo) / sqrt(sq / n)));
                for (size_t i = 0; i < n; i++) {
                    float a[3], e[3];
                    proto_normal_oct_decode(tile[3 * n + i], tile[4 * n + i], &a[0], &a[1], &a[2]);
                    proto_normal_oct_decode(back[3 * n + i], back[4 * n + i], &e[0], &e[1], &e[2]);
                    double dot = fmin(1.0, (double)a[0] * e[0] + (double)a[1] * e[1] + (double)a[2] * e[2]);
                    /* acos loses precision near 1: use the cross product's norm */
                    double cx = (double)a[1] * e[2] - (double)a[2] * e[1], cy = (double)a[2] * e[0] - (double)a[0] * e[2],
                           cz = (double)a[0] * e[1] - (double)a[1] * e[0];
                    worst_deg = fmax(worst_deg, atan2(sqrt(cx * cx + cy * cy + cz * cz), dot) * 180 / M_PI);
                }
                bytes += (double)b.len;
                raw += 4.0 * np * n;
                tiles++;
                proto_buf_free(&b);
            }
        }
    ocean_filter_config fc;
    ocean_filter_config_default(&fc, &ocean_get_params(s.o)->sea);
    ocean_slope_stats ss;
    assert_int_equal(ocean_slope_variance(s.o, NULL, INFINITY, fc.order, &ss), OCEAN_OK);
    double tail_deg = sqrt(fmin(ss.tail.mss_x, ss.tail.mss_z)) * 180 / M_PI;
    tile_l1_close(&s);
    print_message("layout-1 tiles: %d, 1/%.2f of f32, worst height PSNR %.2f dB, worst normal %.3f deg (tail spread %.2f deg), %d planes with H reference\n",
                  tiles, raw / bytes, worst_psnr, worst_deg, tail_deg, with_ref);
    assert_true(tiles > 0);
    assert_true(with_ref > 0);
    assert_true(worst_psnr >= 50.0);
    assert_true(worst_deg <= 2.2 * p.accuracy * 180 / M_PI);
    assert_true(worst_deg <= 0.1 * tail_deg);
    assert_true(bytes * 8 <= raw);
    free(tile);
    free(back);
}

/* The normal budget's angle: over the upper hemisphere (|slope| up to 2,
 * 63 deg), moving (u, v) by up to e = accuracy / 2 per component turns
 * the decoded unit normal by at most 2.2 x accuracy rad (0.63 deg at 5e-3):
 * the geometry behind the bound PROTOCOL.md states, checked by direct
 * evaluation of the octahedral map (Cigolle et al. 2014, JCGT 3(2)) at
 * two accuracies (the map is smooth, so the bound scales with e). */
static void test_normal_budget_angle(void **state)
{
    (void)state;
    for (int ai = 0; ai < 2; ai++) {
    const double acc = ai ? 1e-3 : 5e-3, e = acc / 2;
    double worst = 0;
    for (int a = 0; a <= 60; a++)
        for (int b = 0; b < 48; b++) {
            double th = atan(2.0) * a / 60, ph = 2 * M_PI * b / 48;
            float u, v;
            proto_normal_oct_encode((float)(sin(th) * cos(ph)), (float)cos(th), (float)(sin(th) * sin(ph)), &u, &v);
            float n0[3];
            proto_normal_oct_decode(u, v, &n0[0], &n0[1], &n0[2]);
            for (int du = -1; du <= 1; du++)
                for (int dv = -1; dv <= 1; dv++) {
                    float n1[3];
                    proto_normal_oct_decode((float)(u + du * e), (float)(v + dv * e), &n1[0], &n1[1], &n1[2]);
                    double cx = (double)n0[1] * n1[2] - (double)n0[2] * n1[1], cy = (double)n0[2] * n1[0] - (double)n0[0] * n1[2],
                           cz = (double)n0[0] * n1[1] - (double)n0[1] * n1[0];
                    double dot = (double)n0[0] * n1[0] + (double)n0[1] * n1[1] + (double)n0[2] * n1[2];
                    worst = fmax(worst, atan2(sqrt(cx * cx + cy * cy + cz * cz), dot) * 180 / M_PI);
                }
        }
    print_message("normal budget %g per component: worst %.3f deg\n", e, worst);
    assert_true(worst * M_PI / 180 <= 2.2 * acc);
    /* and the bound is not loose by more than 30 % */
    assert_true(worst * M_PI / 180 >= 0.7 * 2.2 * acc);
    }
}

/* Payloads of qz format 1 (written before format 2, e.g. in recordings)
 * still decode, to the values the format-1 encoder (a frozen copy,
 * tests/bench/qz_before.h) meant. */
static void test_qz_format1_still_decodes(void **state)
{
    (void)state;
    const int W = 40, H = 24;
    size_t n = (size_t)W * H;
    /* format 1 predates the breaking planes: the seven planes it knew */
    const unsigned ch7 = PROTO_CH_WORLD;
    float *src = malloc(7 * n * sizeof *src), *back = malloc(7 * n * sizeof *back);
    synth(src, W, H, ch7, 3.0);
    proto_codec_params p;
    proto_codec_params_default(&p);
    proto_buf b;
    proto_buf_init(&b, 0);
    assert_int_equal(qzb_encode(&p, W, H, 7, src, &b, NULL, NULL, 0), OCEAN_OK);
    assert_int_equal(b.mem[1], 1);
    assert_int_equal(proto_tile_decode(PROTO_CODEC_QZ, W, H, ch7, b.mem, b.len, back, NULL, 0), OCEAN_OK);
    for (int k = 0; k < 7; k++) {
        float lo = src[k * n], hi = lo;
        for (size_t i = 0; i < n; i++)
            lo = fminf(lo, src[k * n + i]), hi = fmaxf(hi, src[k * n + i]);
        double bound = proto_codec_error_bound(PROTO_CODEC_QZ, &p, lo, hi);
        for (size_t i = 0; i < n; i++)
            assert_true(fabs((double)back[k * n + i] - src[k * n + i]) <= bound);
    }
    proto_buf_free(&b);
    free(src);
    free(back);
}

/* Format 2's header rules: a reference to a later plane or to itself, a
 * planar plane naming a reference, weights cut short, reserved bytes set:
 * ECODEC, never a crash or a read past the end. */
static void test_qz2_hostile_headers(void **state)
{
    (void)state;
    const int W = 20, H = 12;
    unsigned ch = PROTO_CH_HEIGHT | PROTO_CH_DX | PROTO_CH_NORMAL;
    size_t n = (size_t)W * H;
    float *src = malloc(4 * n * sizeof *src), *back = malloc(4 * n * sizeof *back);
    synth(src, W, H, ch, 2.0);
    proto_buf b;
    proto_buf_init(&b, 0);
    assert_int_equal(proto_tile_encode(PROTO_CODEC_QZ, NULL, W, H, ch, src, &b, NULL, NULL, 0), OCEAN_OK);
    assert_int_equal(proto_tile_decode(PROTO_CODEC_QZ, W, H, ch, b.mem, b.len, back, NULL, 0), OCEAN_OK);
    /* find plane 1 (DX): it must use LSX with H as reference */
    size_t o1 = 4 + 12 + (b.mem[4 + 9] == 3 ? 16 : 0);
    assert_int_equal(b.mem[o1 + 9], 3);
    assert_int_equal(b.mem[o1 + 10], 0);
    uint8_t *c = malloc(b.len);
    char err[256];
    const struct { size_t at; uint8_t v; } bad[] = {
        {o1 + 10, 1},   /* reference to itself */
        {o1 + 10, 3},   /* reference to a later plane */
        {o1 + 9, 1},    /* planar naming a reference */
        {o1 + 9, 2},    /* LS6 is format 1 only */
        {o1 + 11, 1},   /* reserved */
        {2, 1},         /* header reserved */
        {0, 3},         /* plane count */
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        memcpy(c, b.mem, b.len);
        c[bad[k].at] = bad[k].v;
        assert_int_equal(proto_tile_decode(PROTO_CODEC_QZ, W, H, ch, c, b.len, back, err, sizeof err), OCEAN_ECODEC);
    }
    /* every truncation */
    for (size_t len = 0; len < b.len; len++)
        assert_int_equal(proto_tile_decode(PROTO_CODEC_QZ, W, H, ch, b.mem, len, back, err, sizeof err), OCEAN_ECODEC);
    free(c);
    proto_buf_free(&b);
    free(src);
    free(back);
}

/* ---- fixed qz vectors: tests/vectors/codec ------------------------------- */

/* NAME.qz is one qz payload, NAME.txt its tile (codec, format, width,
 * height, channels), NAME.f32 the planes a conforming decoder makes of it
 * (little-endian binary32, plane after plane), bit for bit; the browser
 * decoder is held to the same files (tests/browser/protocol.test.mjs).
 * The payloads are a 16 x 12 window of a real layout-1 tile (default
 * scene, cascade 0, mip 1) at accuracy 5e-3: format 2 as encoders write it
 * today, format 1 as recordings made before hold it.  Regenerate:
 * build/tests/test_codec --write-vectors tests/vectors/codec (only when
 * the format changes: the expectations are the decoder's contract). */
#define CV_W 16
#define CV_H 12
#define CV_CH (PROTO_CH_HEIGHT | PROTO_CH_DX | PROTO_CH_DZ | PROTO_CH_NORMAL | PROTO_CH_FOAM)
static const struct { const char *name; int format; } codec_vectors[] = {{"qz2_viewer_tile", 2}, {"qz1_viewer_tile", 1}};

static const char *codec_vector_dir(void)
{
    const char *d = getenv("OCEAN_CODEC_VECTORS");
    return d ? d : "tests/vectors/codec";
}

static int put_file(const char *dir, const char *name, const char *ext, const void *p, size_t n)
{
    char path[600];
    snprintf(path, sizeof path, "%s/%s.%s", dir, name, ext);
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(p, 1, n, f) != n) {
        fprintf(stderr, "cannot write %s\n", path);
        if (f)
            fclose(f);
        return -1;
    }
    return fclose(f);
}

static uint8_t *get_file(const char *dir, const char *name, const char *ext, size_t *n)
{
    char path[600];
    snprintf(path, sizeof path, "%s/%s.%s", dir, name, ext);
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long l = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *b = malloc(l > 0 ? (size_t)l + 1 : 1);
    *n = l > 0 && fread(b, 1, (size_t)l, f) == (size_t)l ? (size_t)l : 0;
    fclose(f);
    b[*n] = 0;
    return b;
}

static int write_codec_vectors(const char *dir)
{
    tile_l1 s;
    if (tile_l1_open(&s, "config/oceand.conf", "config/scenes/ship-bridge.conf", 100.0))
        return 1;
    float *tile = malloc(6 * 32 * 32 * sizeof *tile), win[6 * CV_W * CV_H], dec[6 * CV_W * CV_H];
    if (tile_l1_cut(&s, 0, 1, 3, 2, 32, tile))
        return 1;
    for (int p = 0; p < 6; p++)
        for (int i = 0; i < CV_H; i++)
            for (int j = 0; j < CV_W; j++)
                win[(p * CV_H + i) * CV_W + j] = tile[(p * 32 + i) * 32 + j];
    free(tile);
    tile_l1_close(&s);
    proto_codec_params p;
    proto_codec_params_default(&p);
    p.accuracy = 5e-3;
    for (size_t v = 0; v < sizeof codec_vectors / sizeof codec_vectors[0]; v++) {
        proto_buf b;
        proto_buf_init(&b, 0);
        ocean_result r = codec_vectors[v].format == 2
                             ? proto_tile_encode(PROTO_CODEC_QZ, &p, CV_W, CV_H, CV_CH, win, &b, NULL, NULL, 0)
                             : qzb_encode(&p, CV_W, CV_H, 6, win, &b, NULL, NULL, 0);
        if (r != OCEAN_OK || b.mem[1] != codec_vectors[v].format ||
            proto_tile_decode(PROTO_CODEC_QZ, CV_W, CV_H, CV_CH, b.mem, b.len, dec, NULL, 0) != OCEAN_OK)
            return 1;
        uint8_t le[sizeof dec];
        for (size_t i = 0; i < 6 * CV_W * CV_H; i++)
            proto_stf32(le + 4 * i, dec[i]);
        char txt[256];
        int tl = snprintf(txt, sizeof txt, "codec = qz\nformat = %d\nwidth = %d\nheight = %d\nchannels = 0x%x\n",
                          codec_vectors[v].format, CV_W, CV_H, (unsigned)CV_CH);
        if (put_file(dir, codec_vectors[v].name, "qz", b.mem, b.len) ||
            put_file(dir, codec_vectors[v].name, "f32", le, sizeof le) ||
            put_file(dir, codec_vectors[v].name, "txt", txt, (size_t)tl))
            return 1;
        proto_buf_free(&b);
    }
    return 0;
}

/* The committed payloads decode to the committed samples, bit for bit;
 * the format-2 vector uses LSX with the H plane as reference, so the
 * contract covers it; every truncation of them is refused. */
static void test_codec_vectors(void **state)
{
    (void)state;
    for (size_t v = 0; v < sizeof codec_vectors / sizeof codec_vectors[0]; v++) {
        size_t nq = 0, nf = 0, nt = 0;
        uint8_t *q = get_file(codec_vector_dir(), codec_vectors[v].name, "qz", &nq);
        uint8_t *f = get_file(codec_vector_dir(), codec_vectors[v].name, "f32", &nf);
        char *t = (char *)get_file(codec_vector_dir(), codec_vectors[v].name, "txt", &nt);
        if (!q || !f || !t)
            fail_msg("codec vector %s missing in %s (run from the repository root)", codec_vectors[v].name,
                     codec_vector_dir());
        int fmt = 0, w = 0, h = 0;
        unsigned ch = 0;
        assert_int_equal(sscanf(t, "codec = qz\nformat = %d\nwidth = %d\nheight = %d\nchannels = 0x%x", &fmt, &w, &h, &ch), 4);
        int np = proto_tile_planes(ch);
        assert_int_equal(nf, 4 * (size_t)np * w * h);
        assert_int_equal(q[1], fmt);
        float *dec = malloc(nf);
        char err[256];
        assert_int_equal(proto_tile_decode(PROTO_CODEC_QZ, w, h, ch, q, nq, dec, err, sizeof err), OCEAN_OK);
        for (size_t i = 0; i < nf / 4; i++) {
            float want = proto_ldf32(f + 4 * i);
            if (memcmp(&want, &dec[i], 4))
                fail_msg("%s sample %zu: %.9g, expected %.9g", codec_vectors[v].name, i, (double)dec[i], (double)want);
        }
        if (fmt == 2) {
            int refs = 0;
            for (int c = 0, o = 4; c < np; c++) {
                refs += q[o + 9] == 3 && q[o + 10] == 0;
                o += 12 + (q[o + 9] == 3 ? 2 * (q[o + 10] == 255 ? 8 : 17) : 0);
            }
            assert_true(refs > 0);
        }
        for (size_t l = 0; l < nq; l++)
            assert_int_equal(proto_tile_decode(PROTO_CODEC_QZ, w, h, ch, q, l, dec, err, sizeof err), OCEAN_ECODEC);
        free(dec);
        free(q);
        free(f);
        free(t);
    }
}

/* Writes the EXR payload to a file and opens it with OpenEXRCore's own file
 * reader: proves the payload is a standalone .exr with the documented
 * channels, size and compression. */
static void test_exr_file(void **state)
{
    (void)state;
    const proto_codec cs[] = {PROTO_CODEC_EXR_ZIP, PROTO_CODEC_EXR_PIZ, PROTO_CODEC_EXR_B44, PROTO_CODEC_EXR_B44A};
    const exr_compression_t ct[] = {EXR_COMPRESSION_ZIP, EXR_COMPRESSION_PIZ, EXR_COMPRESSION_B44, EXR_COMPRESSION_B44A};
    const int W = 40, H = 24;
    unsigned ch = PROTO_CH_HEIGHT | PROTO_CH_NORMAL | PROTO_CH_JACOBIAN;
    float *src = malloc(4 * W * H * sizeof *src), *back = malloc(4 * W * H * sizeof *back);
    synth(src, W, H, ch, 1.5);
    for (int k = 0; k < 4; k++) {
        proto_buf b;
        proto_buf_init(&b, 0);
        double merr;
        assert_int_equal(proto_tile_encode(cs[k], NULL, W, H, ch, src, &b, &merr, NULL, 0), OCEAN_OK);
        assert_int_equal(proto_ld32(proto_buf_data(&b)), 20000630u); /* EXR magic 76 2f 31 01 */
        char path[] = "/tmp/test_codec_XXXXXX";
        int fd = mkstemp(path);
        assert_true(fd >= 0);
        assert_int_equal(write(fd, proto_buf_data(&b), b.len), (ssize_t)b.len);
        close(fd);
        exr_context_t ctx;
        exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
        assert_int_equal(exr_start_read(&ctx, path, &init), EXR_ERR_SUCCESS);
        exr_compression_t comp;
        assert_int_equal(exr_get_compression(ctx, 0, &comp), EXR_ERR_SUCCESS);
        assert_int_equal(comp, ct[k]);
        exr_attr_box2i_t dw;
        assert_int_equal(exr_get_data_window(ctx, 0, &dw), EXR_ERR_SUCCESS);
        assert_int_equal(dw.max.x - dw.min.x + 1, W);
        assert_int_equal(dw.max.y - dw.min.y + 1, H);
        const exr_attr_chlist_t *cl;
        assert_int_equal(exr_get_channels(ctx, 0, &cl), EXR_ERR_SUCCESS);
        assert_int_equal(cl->num_channels, 4);
        const char *names[4] = {"H", "J", "NU", "NV"}; /* EXR sorts channel names */
        for (int i = 0; i < 4; i++) {
            assert_string_equal(cl->entries[i].name.str, names[i]);
            assert_int_equal(cl->entries[i].pixel_type, k == 0 ? EXR_PIXEL_FLOAT : EXR_PIXEL_HALF);
        }
        exr_finish(&ctx);
        unlink(path);
        /* and the in-memory reader gives the values back within the bound */
        assert_int_equal(proto_tile_decode(cs[k], W, H, ch, proto_buf_data(&b), b.len, back, NULL, 0), OCEAN_OK);
        for (int pl = 0; pl < 4; pl++) {
            float lo = INFINITY, hi = -INFINITY;
            for (int i = 0; i < W * H; i++)
                lo = fminf(lo, src[pl * W * H + i]), hi = fmaxf(hi, src[pl * W * H + i]);
            double bound = proto_codec_error_bound(cs[k], NULL, lo, hi);
            for (int i = 0; i < W * H; i++)
                assert_true(fabs((double)back[pl * W * H + i] - src[pl * W * H + i]) <= fmin(bound, merr));
        }
        /* the same file with the wrong expectation is refused */
        char err[256];
        assert_int_equal(proto_tile_decode(cs[k], W + 1, H, ch, proto_buf_data(&b), b.len, back, err, sizeof err), OCEAN_ECODEC);
        assert_int_equal(proto_tile_decode(cs[k], W, H, PROTO_CH_HEIGHT, proto_buf_data(&b), b.len, back, err, sizeof err), OCEAN_ECODEC);
        proto_buf_free(&b);
    }
    free(src);
    free(back);
}

static void test_encode_refusals(void **state)
{
    (void)state;
    float v[16];
    synth(v, 4, 4, PROTO_CH_HEIGHT, 1);
    proto_buf b;
    proto_buf_init(&b, 0);
    char err[256];
    assert_int_equal(proto_tile_encode((proto_codec)99, NULL, 4, 4, PROTO_CH_HEIGHT, v, &b, NULL, err, sizeof err), OCEAN_ETYPE);
    assert_int_equal(proto_tile_encode(PROTO_CODEC_F32, NULL, 0, 4, PROTO_CH_HEIGHT, v, &b, NULL, err, sizeof err), OCEAN_EINVAL);
    assert_int_equal(proto_tile_encode(PROTO_CODEC_F32, NULL, 4, 4, 0, v, &b, NULL, err, sizeof err), OCEAN_EINVAL);
    assert_int_equal(proto_tile_encode(PROTO_CODEC_F32, NULL, 4, 4, 0x80, v, &b, NULL, err, sizeof err), OCEAN_EINVAL);
    assert_int_equal(proto_tile_encode(PROTO_CODEC_F32, NULL, 4, 4, PROTO_CH_HEIGHT, NULL, &b, NULL, err, sizeof err), OCEAN_EINVAL);
    for (int c = 0; c < PROTO_CODEC_COUNT_; c++) {
        v[5] = NAN;
        assert_int_equal(proto_tile_encode((proto_codec)c, NULL, 4, 4, PROTO_CH_HEIGHT, v, &b, NULL, err, sizeof err), OCEAN_EINVAL);
        assert_non_null(strstr(err, "non-finite"));
        v[5] = INFINITY;
        assert_int_equal(proto_tile_encode((proto_codec)c, NULL, 4, 4, PROTO_CH_HEIGHT, v, &b, NULL, err, sizeof err), OCEAN_EINVAL);
        v[5] = 1e5f;
        ocean_result r = proto_tile_encode((proto_codec)c, NULL, 4, 4, PROTO_CH_HEIGHT, v, &b, NULL, err, sizeof err);
        int half = c == PROTO_CODEC_F16 || c == PROTO_CODEC_EXR_PIZ || c == PROTO_CODEC_EXR_B44 || c == PROTO_CODEC_EXR_B44A;
        assert_int_equal(r, half ? OCEAN_ECODEC : OCEAN_OK);
        v[5] = 0.5f;
        proto_buf_reset(&b);
    }
    assert_int_equal(b.len, 0);
    proto_buf_free(&b);
}

/* Hostile payloads: every truncation and many corruptions of a valid
 * payload decode to OK or OCEAN_ECODEC, never read out of bounds (ASan). */
static void test_decode_hostile(void **state)
{
    (void)state;
    const int W = 16, H = 12;
    unsigned ch = PROTO_CH_HEIGHT | PROTO_CH_DX;
    float src[2 * 16 * 12], back[2 * 16 * 12];
    synth(src, W, H, ch, 2);
    srand(11);
    for (int c = 0; c < PROTO_CODEC_COUNT_; c++) {
        proto_buf b;
        proto_buf_init(&b, 0);
        assert_int_equal(proto_tile_encode((proto_codec)c, NULL, W, H, ch, src, &b, NULL, NULL, 0), OCEAN_OK);
        size_t n = b.len;
        uint8_t *copy = malloc(n);
        char err[256];
        size_t stride = (c >= PROTO_CODEC_EXR_ZIP && sanitized()) ? 7 : 1;
        for (size_t cut = 0; cut < n; cut += stride) {
            memcpy(copy, proto_buf_data(&b), cut);
            uint8_t *exact = malloc(cut ? cut : 1); /* exact-size buffer so ASan sees any overread */
            memcpy(exact, copy, cut);
            ocean_result r = proto_tile_decode((proto_codec)c, W, H, ch, exact, cut, back, err, sizeof err);
            free(exact);
            if (r != OCEAN_ECODEC)
                fail_msg("%s truncated to %zu/%zu gave %d", proto_codec_name((proto_codec)c), cut, n, r);
        }
        int flips = sanitized() ? 60 : 400;
        for (int k = 0; k < flips; k++) {
            memcpy(copy, proto_buf_data(&b), n);
            int nf = 1 + rand() % 4;
            for (int f = 0; f < nf; f++)
                copy[rand() % n] ^= (uint8_t)(1 + rand() % 255);
            ocean_result r = proto_tile_decode((proto_codec)c, W, H, ch, copy, n, back, err, sizeof err);
            if (r != OCEAN_OK && r != OCEAN_ECODEC)
                fail_msg("%s corrupted: %d %s", proto_codec_name((proto_codec)c), r, err);
            if (r == OCEAN_OK)
                for (int i = 0; i < 2 * W * H; i++)
                    assert_true(isfinite(back[i]));
        }
        /* one byte too many */
        uint8_t *longer = malloc(n + 1);
        memcpy(longer, proto_buf_data(&b), n);
        longer[n] = 0;
        ocean_result r = proto_tile_decode((proto_codec)c, W, H, ch, longer, n + 1, back, err, sizeof err);
        if (c <= PROTO_CODEC_QZ)
            assert_int_equal(r, OCEAN_ECODEC);
        free(longer);
        free(copy);
        proto_buf_free(&b);
    }
    /* f32 payload holding NaN is refused */
    uint8_t raw[8];
    proto_stf32(raw, 1.0f);
    proto_stf32(raw + 4, NAN);
    assert_int_equal(proto_tile_decode(PROTO_CODEC_F32, 2, 1, PROTO_CH_HEIGHT, raw, 8, back, NULL, 0), OCEAN_ECODEC);
}

/* One proto_codec_ctx reused across tiles of every shape, plane count,
 * zstd level and accuracy writes exactly the bytes a fresh context-free
 * encode writes (nothing of a tile or a level leaks into the next), and
 * each payload decodes within the accuracy bound (the encoder's residual
 * loops agree with the decoder's predictor, qz_predict). */
static void test_codec_ctx_reuse(void **state)
{
    (void)state;
    proto_codec_ctx *ctx = NULL;
    assert_int_equal(proto_codec_ctx_create(&ctx), OCEAN_OK);
    proto_codec_ctx_destroy(NULL);
    const struct { int w, h; unsigned ch; int level; double acc; } cases[] = {
        {64, 64, PROTO_CH_HEIGHT, 3, 5e-3}, {17, 5, PROTO_CH_ALL, 19, 1e-3}, {128, 96, PROTO_CH_HEIGHT, 1, 1e-6},
        {3, 3, PROTO_CH_DX | PROTO_CH_DZ, 3, 0.5}, {4, 9, PROTO_CH_HEIGHT, 3, 1e-2}, {64, 64, PROTO_CH_ALL, 3, 5e-3},
        {1, 40, PROTO_CH_HEIGHT, 7, 1e-4}, {40, 1, PROTO_CH_FOAM, 3, 1e-4}, {64, 64, PROTO_CH_HEIGHT, 3, 5e-3},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        int w = cases[k].w, h = cases[k].h, np = proto_tile_planes(cases[k].ch);
        size_t n = (size_t)w * h * np;
        float *src = malloc(n * sizeof *src), *back = malloc(n * sizeof *back);
        synth(src, w, h, cases[k].ch, 1.0 + (double)k);
        proto_codec_params p;
        proto_codec_params_default(&p);
        p.zstd_level = cases[k].level;
        p.accuracy = cases[k].acc;
        proto_buf a, b;
        proto_buf_init(&a, 0);
        proto_buf_init(&b, 0);
        double ea, eb;
        assert_int_equal(proto_tile_encode_ctx(ctx, PROTO_CODEC_QZ, &p, w, h, cases[k].ch, src, &a, &ea, NULL, 0),
                         OCEAN_OK);
        assert_int_equal(proto_tile_encode(PROTO_CODEC_QZ, &p, w, h, cases[k].ch, src, &b, &eb, NULL, 0), OCEAN_OK);
        assert_int_equal(a.len, b.len);
        assert_memory_equal(proto_buf_data(&a), proto_buf_data(&b), a.len);
        assert_true(ea == eb);
        assert_int_equal(proto_tile_decode(PROTO_CODEC_QZ, w, h, cases[k].ch, proto_buf_data(&a), a.len, back, NULL, 0),
                         OCEAN_OK);
        for (int c = 0; c < np; c++) {
            const float *s = src + (size_t)c * w * h, *d = back + (size_t)c * w * h;
            float lo = s[0], hi = s[0];
            double e = 0;
            for (int i = 0; i < w * h; i++) {
                lo = fminf(lo, s[i]);
                hi = fmaxf(hi, s[i]);
                e = fmax(e, fabs((double)d[i] - s[i]));
            }
            assert_true(e <= cases[k].acc * (hi - lo) * (1 + 1e-6) + 4 * 0x1p-24 * fmax(fabs(lo), fabs(hi)));
        }
        /* Non-qz codecs take the context too and ignore it. */
        proto_buf_reset(&a);
        assert_int_equal(proto_tile_encode_ctx(ctx, PROTO_CODEC_F16, &p, w, h, cases[k].ch, src, &a, NULL, NULL, 0),
                         OCEAN_OK);
        assert_int_equal(a.len, n * 2);
        proto_buf_free(&a);
        proto_buf_free(&b);
        free(src);
        free(back);
    }
    proto_codec_ctx_destroy(ctx);
}

/* MESH_VERTICES_QZ prediction references (PROTOCOL.md), worked by hand on
 * a quad of two triangles (0,2,1), (1,2,3): vertex 1 has no triangle whose
 * other vertices are both decoded (previous vertex); vertex 2's triangle
 * (0,2,1) has 1 and 0 decoded but no other triangle on edge 1-0
 * (midpoint of 1 and 0); vertex 3's (1,2,3) has 1, 2 and triangle (0,2,1)
 * across that edge (parallelogram 1 + 2 - 0).  An index out of range is
 * refused. */
static void test_mesh_qz_refs(void **state)
{
    (void)state;
    const uint32_t idx[6] = {0, 2, 1, 1, 2, 3};
    uint32_t refs[12];
    assert_int_equal(proto_mesh_qz_refs(idx, 6, 4, refs), OCEAN_OK);
    const uint32_t N = PROTO_MESH_QZ_NONE;
    const uint32_t want[12] = {N, N, N, N, N, N, 1, 0, N, 1, 2, 0};
    assert_memory_equal(refs, want, sizeof want);
    assert_int_equal(proto_mesh_qz_refs(idx, 6, 3, refs), OCEAN_EINVAL);
    assert_int_equal(proto_mesh_qz_refs(idx, 5, 4, refs), OCEAN_EINVAL);
}

/* A displaced lattice mesh (G x G, two triangles a cell, row-major) round
 * trips within the stated bound per axis (half the step + f32 rounding),
 * with steps f32(2a range_y) on every axis, in well under the f32 bytes;
 * one context gives the same bytes as a fresh one; every truncation and
 * a wrong vertex count are refused, corrupt bytes never give a non-finite
 * or out-of-range position; NaN input and a bad accuracy are refused. */
static void test_mesh_qz_roundtrip(void **state)
{
    (void)state;
    enum { G = 40, V = G * G, I = 6 * (G - 1) * (G - 1) };
    static uint32_t idx[I], refs[3 * V];
    static float xyz[3 * V], back[3 * V];
    int k = 0;
    for (int i = 0; i + 1 < G; i++)
        for (int j = 0; j + 1 < G; j++) {
            uint32_t a = (uint32_t)(i * G + j);
            const uint32_t t[6] = {a, a + G, a + 1, a + 1, a + G, a + G + 1};
            memcpy(idx + k, t, sizeof t);
            k += 6;
        }
    for (int i = 0; i < G; i++)
        for (int j = 0; j < G; j++) {
            float *q = xyz + 3 * (i * G + j);
            q[0] = (float)(1e4 + 2.0 * j + 0.5 * sin(0.3 * i + 0.2 * j));
            q[1] = (float)(2.0 * sin(0.25 * j) * cos(0.15 * i));
            q[2] = (float)(-3e4 + 2.0 * i + 0.4 * cos(0.35 * j));
        }
    assert_int_equal(proto_mesh_qz_refs(idx, I, V, refs), OCEAN_OK);
    proto_codec_ctx *cx = NULL, *cy = NULL;
    assert_int_equal(proto_codec_ctx_create(&cx), OCEAN_OK);
    assert_int_equal(proto_codec_ctx_create(&cy), OCEAN_OK);
    const double accs[3] = {1e-3, 5e-3, 0.5};
    for (int a = 0; a < 3; a++) {
        proto_buf b, c;
        proto_buf_init(&b, 0);
        proto_buf_init(&c, 0);
        double merr[3];
        assert_int_equal(proto_mesh_qz_encode(cx, accs[a], V, xyz, refs, &b, merr, NULL, 0), OCEAN_OK);
        assert_int_equal(proto_mesh_qz_encode(cy, accs[a], V, xyz, refs, &c, NULL, NULL, 0), OCEAN_OK);
        assert_int_equal(b.len, c.len);
        assert_memory_equal(proto_buf_data(&b), proto_buf_data(&c), b.len);
        assert_true(b.len < 12u * V / 2);
        assert_int_equal(proto_mesh_qz_decode(proto_buf_data(&b), b.len, V, refs, back, NULL, 0), OCEAN_OK);
        proto_mesh_qz_info in;
        assert_int_equal(proto_mesh_qz_header(proto_buf_data(&b), b.len, V, &in, NULL, 0), OCEAN_OK);
        /* the step the spec states: f32(2 a range_y) on every axis */
        float ylo = xyz[1], yhi = xyz[1];
        for (int v = 0; v < V; v++) {
            ylo = fminf(ylo, xyz[3 * v + 1]);
            yhi = fmaxf(yhi, xyz[3 * v + 1]);
        }
        float s = (float)(2.0 * accs[a] * ((double)yhi - (double)ylo));
        for (int ax = 0; ax < 3; ax++) {
            assert_true(in.step[ax] == s);
            double e = 0, amax = 0;
            for (int v = 0; v < V; v++) {
                e = fmax(e, fabs((double)back[3 * v + ax] - (double)xyz[3 * v + ax]));
                amax = fmax(amax, fabs((double)xyz[3 * v + ax]));
            }
            assert_true(e <= 0.5 * s + amax * 0x1p-24);
            assert_true(e == merr[ax]);
        }
        if (a == 1) {
            char err[200];
            for (size_t cut = 0; cut < b.len; cut++)
                assert_int_equal(proto_mesh_qz_decode(proto_buf_data(&b), cut, V, refs, back, err, sizeof err),
                                 OCEAN_ECODEC);
            assert_int_equal(proto_mesh_qz_decode(proto_buf_data(&b), b.len, V - 1, refs, back, NULL, 0), OCEAN_ECODEC);
            uint32_t rng = 12345;
            for (int t = 0; t < 400; t++) {
                uint8_t *m = malloc(b.len);
                memcpy(m, proto_buf_data(&b), b.len);
                rng = rng * 1664525u + 1013904223u;
                m[(rng >> 8) % b.len] ^= (uint8_t)(1u << (rng % 8));
                if (proto_mesh_qz_decode(m, b.len, V, refs, back, NULL, 0) == OCEAN_OK)
                    for (int v = 0; v < 3 * V; v++)
                        assert_true(isfinite(back[v]) && fabsf(back[v]) <= 1e7f);
                free(m);
            }
        }
        proto_buf_free(&b);
        proto_buf_free(&c);
    }
    proto_buf b;
    proto_buf_init(&b, 0);
    assert_int_equal(proto_mesh_qz_encode(cx, 1e-9, V, xyz, refs, &b, NULL, NULL, 0), OCEAN_EINVAL);
    xyz[7] = NAN;
    assert_int_equal(proto_mesh_qz_encode(cx, 5e-3, V, xyz, refs, &b, NULL, NULL, 0), OCEAN_EINVAL);
    assert_int_equal(b.len, 0);
    proto_buf_free(&b);
    proto_codec_ctx_destroy(cx);
    proto_codec_ctx_destroy(cy);
}

int main(int argc, char **argv)
{
    if (argc == 3 && strcmp(argv[1], "--write-vectors") == 0)
        return write_codec_vectors(argv[2]);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_f16_values),
        cmocka_unit_test(test_octahedral),
        cmocka_unit_test(test_names),
        cmocka_unit_test(test_roundtrip_synthetic),
        cmocka_unit_test(test_qz_accuracy),
        cmocka_unit_test(test_codec_ctx_reuse),
        cmocka_unit_test(test_real_ocean),
        cmocka_unit_test(test_qz_layout1_tiles),
        cmocka_unit_test(test_normal_budget_angle),
        cmocka_unit_test(test_qz_format1_still_decodes),
        cmocka_unit_test(test_qz2_hostile_headers),
        cmocka_unit_test(test_codec_vectors),
        cmocka_unit_test(test_exr_file),
        cmocka_unit_test(test_encode_refusals),
        cmocka_unit_test(test_decode_hostile),
        cmocka_unit_test(test_mesh_qz_refs),
        cmocka_unit_test(test_mesh_qz_roundtrip),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
