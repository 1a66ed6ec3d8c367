/*
 * bench_codec.c - what each tile codec costs and what it loses, on real
 * ocean tiles (sim/ocean.h, cascade 0 cut into tiles).
 *
 * For every codec (and qz at several accuracy targets): mean bytes per tile
 * and the ratio to raw f32, median encode and decode time per tile, and the
 * height plane's error against f32: max abs, RMS, and PSNR with peak = the
 * tile's range (the worst tile's PSNR is reported, since the target
 * "PSNR >= 50 dB" must hold for every tile).  A second table does the same
 * for all seven planes of a full tile (H DX DZ NU NV FOAM J).
 *
 * A third table (issue 14) puts the qz encoder before proto_codec_ctx (a
 * frozen copy, qz_before.h: a new ZSTD_CCtx and scratch per call, the
 * double least-squares fit) beside today's, context-free and with one
 * context reused, interleaved tile by tile in one run, and counts the
 * payloads that are byte-identical to the old encoder's.
 *
 * A fourth table (issue 14) is the tiles as the browser viewer receives
 * them: layout-1 mip tiles (tile_source.h tile_l1: every mip of every
 * cascade of the scene config/oceand.conf serves, 32 x 32 as
 * server.cascade_tile, channels H DX DZ NU NV BI BQ), qz format 1
 * (before, the frozen encoder) beside format 2 at several accuracies, with
 * the error of every plane, the normal's angle error, the share of the
 * bytes the breaking planes BI BQ take (the tile against the same tile
 * without them), and the planner's byte model (srv_cascade_tile_bytes)
 * against the bytes.
 *
 * Prints markdown tables to stdout and writes tests/bench/out/codec.csv.
 * OCEAN_BENCH_QUICK=1 shrinks the run.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "../lib/bench_util.h"
#include "tile_source.h"
#include "codec.h"
#include "qz_before.h"
#include "srv_cascade.h"

#define TILE 64

typedef struct row {
    const char *name;
    proto_codec codec;
    double accuracy;
    int before;   /* 1: qz format 1, the frozen encoder (qz_before.h) */
} row;

static ocean_result encode_before(const proto_codec_params *p, int w, int h, unsigned ch, const float *planes,
                                  proto_buf *out);

typedef struct result {
    double bytes, enc_ms, dec_ms, maxabs, rms, psnr_min, psnr_mean;
} result;

/* tiles: ntiles tiles of `planes` planes each (height first). */
static int run(const row *rw, unsigned channels, int planes, float **tiles, int ntiles, int reps, result *out)
{
    proto_codec_params prm;
    proto_codec_params_default(&prm);
    if (rw->accuracy > 0)
        prm.accuracy = rw->accuracy;
    size_t m = (size_t)TILE * TILE;
    float *back = malloc(m * planes * sizeof *back);
    double *enc = malloc(sizeof(double) * ntiles * reps), *dec = malloc(sizeof(double) * ntiles * reps);
    proto_buf b;
    proto_buf_init(&b, 0);
    double bytes = 0, sq = 0, maxabs = 0, psum = 0, pmin = INFINITY;
    char err[256];
    for (int t = 0; t < ntiles; t++) {
        for (int r = 0; r < reps; r++) {
            proto_buf_reset(&b);
            double t0 = bench_now_ms();
            if (rw->before ? encode_before(&prm, TILE, TILE, channels, tiles[t], &b) != OCEAN_OK
                           : proto_tile_encode(rw->codec, &prm, TILE, TILE, channels, tiles[t], &b, NULL, err, sizeof err)) {
                fprintf(stderr, "%s: encode: %s\n", rw->name, err);
                return -1;
            }
            double t1 = bench_now_ms();
            if (proto_tile_decode(rw->codec, TILE, TILE, channels, proto_buf_data(&b), proto_buf_len(&b), back,
                                  err, sizeof err)) {
                fprintf(stderr, "%s: decode: %s\n", rw->name, err);
                return -1;
            }
            double t2 = bench_now_ms();
            enc[t * reps + r] = t1 - t0;
            dec[t * reps + r] = t2 - t1;
        }
        bytes += (double)proto_buf_len(&b);
        /* height plane error */
        const float *h = tiles[t];
        float lo = h[0], hi = h[0];
        double tsq = 0;
        for (size_t k = 0; k < m; k++) {
            lo = fminf(lo, h[k]);
            hi = fmaxf(hi, h[k]);
            double d = (double)back[k] - (double)h[k];
            tsq += d * d;
            maxabs = fmax(maxabs, fabs(d));
        }
        sq += tsq;
        double rms = sqrt(tsq / m);
        double psnr = rms > 0 ? 20 * log10(((double)hi - lo) / rms) : INFINITY;
        pmin = fmin(pmin, psnr);
        psum += isfinite(psnr) ? psnr : 200;
    }
    out->bytes = bytes / ntiles;
    out->enc_ms = bench_median(enc, ntiles * reps);
    out->dec_ms = bench_median(dec, ntiles * reps);
    out->maxabs = maxabs;
    out->rms = sqrt(sq / (m * (double)ntiles));
    out->psnr_min = pmin;
    out->psnr_mean = psum / ntiles;
    free(back);
    free(enc);
    free(dec);
    proto_buf_free(&b);
    return 0;
}


/* The old entry point: the dispatch's finite check, then the frozen
 * encoder, so both sides pay for the same validation. */
static ocean_result encode_before(const proto_codec_params *p, int w, int h, unsigned ch, const float *planes,
                                  proto_buf *out)
{
    int np = proto_tile_planes(ch);
    size_t total = (size_t)w * h * np;
    for (size_t i = 0; i < total; i++)
        if (!isfinite(planes[i]))
            return OCEAN_EINVAL;
    return qzb_encode(p, w, h, np, planes, out, NULL, NULL, 0);
}

/* Before/after of the qz encoder on the same tiles, interleaved. */
static int before_after(unsigned ch, int np, float **tiles, int ntiles, int reps, FILE *csv, const char *kind)
{
    proto_codec_params prm;
    proto_codec_params_default(&prm);
    proto_codec_ctx *ctx = NULL;
    if (proto_codec_ctx_create(&ctx) != OCEAN_OK)
        return -1;
    size_t m = (size_t)TILE * TILE;
    int nt = ntiles * reps;
    double *ms[3];
    for (int k = 0; k < 3; k++)
        ms[k] = malloc(sizeof(double) * nt);
    proto_buf b[3];
    for (int k = 0; k < 3; k++)
        proto_buf_init(&b[k], 0);
    float *back = malloc(m * np * sizeof *back);
    double bytes[3] = {0, 0, 0}, pmin = INFINITY;
    int same = 0;
    char err[256];
    for (int t = 0; t < ntiles; t++) {
        for (int r = 0; r < reps; r++)
            for (int k0 = 0; k0 < 3; k0++) {
                int k = (k0 + r + t) % 3; /* rotate who goes first */
                proto_buf_reset(&b[k]);
                double t0 = bench_now_ms();
                ocean_result res = k == 0 ? encode_before(&prm, TILE, TILE, ch, tiles[t], &b[k])
                                 : k == 1 ? proto_tile_encode(PROTO_CODEC_QZ, &prm, TILE, TILE, ch, tiles[t], &b[k],
                                                              NULL, err, sizeof err)
                                          : proto_tile_encode_ctx(ctx, PROTO_CODEC_QZ, &prm, TILE, TILE, ch, tiles[t],
                                                                  &b[k], NULL, err, sizeof err);
                ms[k][t * reps + r] = bench_now_ms() - t0;
                if (res != OCEAN_OK) {
                    fprintf(stderr, "qz before/after: encoder %d failed\n", k);
                    return -1;
                }
            }
        for (int k = 0; k < 3; k++)
            bytes[k] += (double)proto_buf_len(&b[k]);
        if (proto_buf_len(&b[1]) == proto_buf_len(&b[2]) &&
            memcmp(proto_buf_data(&b[1]), proto_buf_data(&b[2]), proto_buf_len(&b[2])) == 0)
            same++;
        if (proto_tile_decode(PROTO_CODEC_QZ, TILE, TILE, ch, proto_buf_data(&b[2]), proto_buf_len(&b[2]), back,
                              err, sizeof err)) {
            fprintf(stderr, "qz before/after: decode: %s\n", err);
            return -1;
        }
        const float *h = tiles[t];
        float lo = h[0], hi = h[0];
        double sq = 0;
        for (size_t k = 0; k < m; k++) {
            lo = fminf(lo, h[k]);
            hi = fmaxf(hi, h[k]);
            double d = (double)back[k] - (double)h[k];
            sq += d * d;
        }
        double rms = sqrt(sq / m);
        pmin = fmin(pmin, rms > 0 ? 20 * log10(((double)hi - lo) / rms) : INFINITY);
    }
    const char *names[3] = {"before (63a4af9: format 1, new ZSTD_CCtx per call)",
                            "after (format 2), context-free proto_tile_encode", "after (format 2), one proto_codec_ctx reused"};
    double raw = 4.0 * m * np, med[3];
    for (int k = 0; k < 3; k++) {
        med[k] = bench_median(ms[k], nt);
        double mbs = raw / 1e6 / (med[k] / 1e3);
        printf("| %s | %.0f | 1/%.1f | %.1f | %.4f | %.1f | %.2f |\n", names[k], bytes[k] / ntiles,
               raw * ntiles / bytes[k], pmin, med[k], mbs, med[0] / med[k]);
        if (csv)
            fprintf(csv, "%s,qz-before-after:%d,%.1f,%.4f,%.4f,,,,%.2f,\n", kind, k, bytes[k] / ntiles,
                    bytes[k] / ntiles / raw, med[k], pmin);
    }
    printf("\n%d of %d tiles: the context-free and the context payloads are byte-identical (the context changes "
           "no byte); the before row is qz format 1, the after rows format 2 (PROTOCOL.md).\n\n",
           same, ntiles);
    for (int k = 0; k < 3; k++) {
        free(ms[k]);
        proto_buf_free(&b[k]);
    }
    free(back);
    proto_codec_ctx_destroy(ctx);
    return 0;
}

/* ---- the tiles the browser viewer receives (issue 14) ----------------------- */

#define L1_T 32

typedef struct l1_tile {
    unsigned ch;
    int np;
    float *pl;
} l1_tile;

/* One row of the layout-1 table over every tile; CSV row kind "layout1". */
static int run_l1(const row *rw, const l1_tile *tiles, int ntiles, int reps, FILE *csv, int *met)
{
    proto_codec_params prm;
    proto_codec_params_default(&prm);
    if (rw->accuracy > 0)
        prm.accuracy = rw->accuracy;
    proto_codec_ctx *ctx = NULL;
    if (proto_codec_ctx_create(&ctx) != OCEAN_OK)
        return -1;
    const size_t n = (size_t)L1_T * L1_T;
    float *back = malloc(PROTO_TILE_MAX_PLANES * n * sizeof *back);
    double *enc = malloc(sizeof(double) * ntiles * reps), *dec = malloc(sizeof(double) * ntiles * reps);
    proto_buf b;
    proto_buf_init(&b, 0);
    double bytes = 0, raw = 0, model = 0, pmin = INFINITY, maxe[PROTO_TILE_MAX_PLANES] = {0}, worst_deg = 0;
    double bytes_nb = 0;   /* the same tiles without BI BQ */
    char err[256];
    proto_subscribe sub;
    memset(&sub, 0, sizeof sub);
    sub.codec = (uint8_t)rw->codec;
    sub.accuracy = (float)prm.accuracy;
    for (int t = 0; t < ntiles; t++) {
        const l1_tile *tl = &tiles[t];
        for (int r = 0; r < reps; r++) {
            proto_buf_reset(&b);
            double t0 = bench_now_ms();
            ocean_result res = rw->before ? encode_before(&prm, L1_T, L1_T, tl->ch, tl->pl, &b)
                                          : proto_tile_encode_ctx(ctx, rw->codec, &prm, L1_T, L1_T, tl->ch, tl->pl, &b,
                                                                  NULL, err, sizeof err);
            double t1 = bench_now_ms();
            if (res != OCEAN_OK ||
                proto_tile_decode(rw->codec, L1_T, L1_T, tl->ch, proto_buf_data(&b), proto_buf_len(&b), back, err,
                                  sizeof err) != OCEAN_OK) {
                fprintf(stderr, "%s: layout-1 tile %d: %s\n", rw->name, t, err);
                return -1;
            }
            enc[t * reps + r] = t1 - t0;
            dec[t * reps + r] = bench_now_ms() - t1;
        }
        bytes += (double)proto_buf_len(&b);
        raw += 4.0 * n * tl->np;
        if (!rw->before) {
            /* BI BQ are the last planes: the tile without them is a prefix */
            proto_buf nb;
            proto_buf_init(&nb, 0);
            if (proto_tile_encode_ctx(ctx, rw->codec, &prm, L1_T, L1_T, tl->ch & ~(unsigned)PROTO_CH_BREAKING, tl->pl,
                                      &nb, NULL, err, sizeof err) == OCEAN_OK)
                bytes_nb += (double)proto_buf_len(&nb);
            proto_buf_free(&nb);
        }
        /* the planner's model counts the FRAME record and TILE header (64) */
        model += srv_cascade_tile_bytes(&sub, tl->ch, L1_T) - 64.0;
        for (int k = 0; k < tl->np; k++)
            for (size_t i = 0; i < n; i++)
                maxe[k] = fmax(maxe[k], fabs((double)back[k * n + i] - tl->pl[k * n + i]));
        float lo = tl->pl[0], hi = lo;
        double sq = 0;
        for (size_t i = 0; i < n; i++) {
            lo = fminf(lo, tl->pl[i]), hi = fmaxf(hi, tl->pl[i]);
            sq += ((double)back[i] - tl->pl[i]) * ((double)back[i] - tl->pl[i]);
        }
        pmin = fmin(pmin, sq > 0 ? 20 * log10(((double)hi - lo) / sqrt(sq / n)) : INFINITY);
        for (size_t i = 0; i < n; i++) {
            float a[3], e[3];
            proto_normal_oct_decode(tl->pl[3 * n + i], tl->pl[4 * n + i], &a[0], &a[1], &a[2]);
            proto_normal_oct_decode(back[3 * n + i], back[4 * n + i], &e[0], &e[1], &e[2]);
            double cx = (double)a[1] * e[2] - (double)a[2] * e[1], cy = (double)a[2] * e[0] - (double)a[0] * e[2],
                   cz = (double)a[0] * e[1] - (double)a[1] * e[0];
            double dot = (double)a[0] * e[0] + (double)a[1] * e[1] + (double)a[2] * e[2];
            worst_deg = fmax(worst_deg, atan2(sqrt(cx * cx + cy * cy + cz * cz), dot) * 180 / M_PI);
        }
    }
    double em = bench_median(enc, ntiles * reps), dm = bench_median(dec, ntiles * reps);
    int is_model = rw->codec == PROTO_CODEC_QZ && !rw->before;
    char mtxt[32] = "-";
    if (is_model)
        snprintf(mtxt, sizeof mtxt, "%+.1f %%", 100.0 * (model - bytes) / bytes);
    char share[32] = "-";
    if (bytes_nb > 0)
        snprintf(share, sizeof share, "%.1f %%", 100.0 * (bytes - bytes_nb) / bytes);
    printf("| %s | %.0f | 1/%.2f | %.2f | %.2e | %.2e | %.2e | %.2e | %.2e | %.2e | %.2e | %s | %.3f | %.3f | %.3f | %s |\n",
           rw->name, bytes / ntiles, raw / bytes, pmin, maxe[0], maxe[1], maxe[2], maxe[3], maxe[4], maxe[5], maxe[6],
           share, worst_deg, em, dm, mtxt);
    if (csv)
        fprintf(csv, "layout1,%s,%.1f,%.4f,%.4f,%.4f,%.6g,,%.2f,\n", rw->name, bytes / ntiles, bytes / raw, em, dm,
                maxe[0], pmin);
    if (met)
        *met = bytes * 8 <= raw && pmin >= 50.0;
    free(back);
    free(enc);
    free(dec);
    proto_buf_free(&b);
    proto_codec_ctx_destroy(ctx);
    return 0;
}

static int layout1_table(int quick, FILE *csv)
{
    tile_l1 s;
    if (tile_l1_open(&s, "config/oceand.conf", "config/scenes/ship-bridge.conf", 100.0)) {
        fprintf(stderr, "bench_codec: cannot build the layout-1 ocean\n");
        return -1;
    }
    int cap = 0;
    for (int c = 0; c < s.cascades; c++)
        for (int m = 0; m < TILE_L1_MIPS; m++)
            cap += tile_l1_count(&s, c, m, L1_T) * tile_l1_count(&s, c, m, L1_T);
    l1_tile *tiles = calloc((size_t)cap, sizeof *tiles);
    int nt = 0, per_mip[3] = {0, 0, 0};
    for (int c = 0; c < s.cascades; c++)
        for (int m = 0; m < TILE_L1_MIPS; m++) {
            int k = tile_l1_count(&s, c, m, L1_T);
            for (int t = 0; t < k * k; t += quick ? 4 : 1) {
                l1_tile *tl = &tiles[nt];
                tl->ch = tile_l1_channels(c);
                tl->np = proto_tile_planes(tl->ch);
                tl->pl = malloc(PROTO_TILE_MAX_PLANES * (size_t)L1_T * L1_T * sizeof(float));
                if (tile_l1_cut(&s, c, m, t % k, t / k, L1_T, tl->pl)) {
                    fprintf(stderr, "bench_codec: layout-1 cut failed\n");
                    return -1;
                }
                nt++;
                if (c < 3) per_mip[c]++;
            }
        }
    int cascades = s.cascades;
    tile_l1_close(&s);
    const row rows[] = {
        {"f32", PROTO_CODEC_F32, 0, 0},
        {"f16", PROTO_CODEC_F16, 0, 0},
        {"qz format 1 (before) acc=1e-3 (the viewer's before)", PROTO_CODEC_QZ, 1e-3, 1},
        {"qz format 1 (before) acc=5e-3", PROTO_CODEC_QZ, 5e-3, 1},
        {"qz acc=1e-2", PROTO_CODEC_QZ, 1e-2, 0},
        {"qz acc=5e-3 (the viewer's)", PROTO_CODEC_QZ, 5e-3, 0},
        {"qz acc=2.5e-3", PROTO_CODEC_QZ, 2.5e-3, 0},
        {"qz acc=1e-3", PROTO_CODEC_QZ, 1e-3, 0},
    };
    const int reps = quick ? 1 : 3;
    printf("\n### Tiles as the browser viewer receives them (issue 14): layout-1 mip tiles, %dx%d, scene ship-bridge "
           "(config/oceand.conf), t = 100 s\n\n", L1_T, L1_T);
    printf("%d tiles: every mip of each of %d cascades (%d / %d / %d tiles), channels H DX DZ NU NV BI BQ, as "
           "server/srv_cascade.c samples them (a viewer whose mesh cannot show a mip gets that mip's "
           "NU NV BI BQ alone: the accuracy section's viewer table gives the ratio of the mix it receives); BI BQ "
           "share = the bytes the breaking planes add, of the tile's; one "
           "proto_codec_ctx per row, median of %d runs. Max "
           "errors are over all tiles (m for H DX DZ; octahedral units for NU NV); normal deg = worst angle between "
           "decoded and input unit normals; model = the planner's srv_cascade_tile_bytes against the measured bytes. "
           "Format 1 rows run the frozen encoder (qz_before.h: a new ZSTD_CCtx per call, as before per-worker "
           "contexts), format 2 rows today's with one context, as the daemon's workers do.\n\n",
           nt, cascades, per_mip[0], per_mip[1], per_mip[2], reps);
    printf("| codec | bytes/tile | vs f32 | H PSNR worst (dB) | H max | DX max | DZ max | NU max | NV max | BI max | "
           "BQ max | BI BQ share | normal deg | encode ms | decode ms | model |\n");
    printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    int met = 0;
    for (size_t r = 0; r < sizeof rows / sizeof rows[0]; r++) {
        int m1 = 0;
        if (run_l1(&rows[r], tiles, nt, reps, csv, &m1))
            return -1;
        if (r == 5)
            met = m1;
    }
    printf("\nTarget (issue 14): the viewer's tiles (qz, accuracy 5e-3) <= 1/8 of raw f32 with worst-tile height PSNR "
           ">= 50 dB: **%s**.\n", met ? "met" : "not met");
    for (int i = 0; i < nt; i++)
        free(tiles[i].pl);
    free(tiles);
    return 0;
}

int main(void)
{
    int quick = bench_quick();
    const row rows[] = {
        {"f32", PROTO_CODEC_F32, 0, 0},
        {"f16", PROTO_CODEC_F16, 0, 0},
        {"qz format 1 (before) acc=5e-3", PROTO_CODEC_QZ, 5e-3, 1},
        {"qz format 1 (before) acc=1e-3", PROTO_CODEC_QZ, 1e-3, 1},
        {"qz acc=1e-2", PROTO_CODEC_QZ, 1e-2, 0},
        {"qz acc=5e-3 (default)", PROTO_CODEC_QZ, 5e-3, 0},
        {"qz acc=4e-3", PROTO_CODEC_QZ, 4e-3, 0},
        {"qz acc=3e-3", PROTO_CODEC_QZ, 3e-3, 0},
        {"qz acc=1e-3", PROTO_CODEC_QZ, 1e-3, 0},
        {"qz acc=1e-4", PROTO_CODEC_QZ, 1e-4, 0},
        {"exr-zip (float)", PROTO_CODEC_EXR_ZIP, 0, 0},
        {"exr-piz (half)", PROTO_CODEC_EXR_PIZ, 0, 0},
        {"exr-b44 (half)", PROTO_CODEC_EXR_B44, 0, 0},
        {"exr-b44a (half)", PROTO_CODEC_EXR_B44A, 0, 0},
    };
    const int nrows = (int)(sizeof rows / sizeof rows[0]);
    /* Three seas: a calm 5 m/s, the default 10 m/s, a 25 m/s storm; each
     * with the default 256 grid over a patch that gives 1-8 m spacing. */
    const struct { const char *name; double u10, patch; } seas[] = {
        {"calm 5 m/s, 256 m patch", 5, 256}, {"default 10 m/s, 1000 m", 10, 1000}, {"storm 25 m/s, 2000 m", 25, 2000}};
    const int per_sea = quick ? 4 : 12, reps = quick ? 2 : 5;
    const int ntiles = 3 * per_sea;
    const int planes_all = proto_tile_planes(PROTO_CH_WORLD);
    size_t m = (size_t)TILE * TILE;
    float *full[3 * 12], *height[3 * 12];
    int k = 0;
    for (int s = 0; s < 3; s++) {
        tile_source src;
        if (tile_source_open(&src, seas[s].u10, 256, seas[s].patch, 1000.0 + 37.0 * s)) {
            fprintf(stderr, "bench_codec: cannot build the ocean\n");
            return 1;
        }
        for (int t = 0; t < per_sea; t++, k++) {
            full[k] = malloc(m * planes_all * sizeof(float));
            tile_source_cut(&src, (t * 53) % src.n, (t * 97) % src.n, TILE, TILE, full[k]);
            height[k] = malloc(m * sizeof(float));
            memcpy(height[k], full[k], m * sizeof(float));
        }
        tile_source_close(&src);
    }
    mkdir("tests/bench/out", 0755);
    FILE *csv = fopen("tests/bench/out/codec.csv", "w");
    if (csv)
        fprintf(csv, "tile,codec,bytes_per_tile,ratio_vs_f32,encode_ms,decode_ms,h_max_abs_m,h_rms_m,h_psnr_min_db,h_psnr_mean_db\n");
    const char *kinds[2] = {"height", "all7"};
    for (int kind = 0; kind < 2; kind++) {
        unsigned ch = kind ? PROTO_CH_WORLD : PROTO_CH_HEIGHT;
        int np = kind ? planes_all : 1;
        double raw = 4.0 * m * np;
        printf("\n### Tile codecs, %dx%d %s tiles (%d real ocean tiles from 3 seas; median of %d runs)\n\n",
               TILE, TILE, kind ? "seven-plane (H DX DZ NU NV FOAM J)" : "height-only", ntiles, reps);
        printf("| codec | bytes/tile | vs f32 | encode ms | decode ms | H max abs (m) | H RMS (m) | H PSNR worst (dB) | H PSNR mean (dB) |\n");
        printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
        for (int r = 0; r < nrows; r++) {
            result res;
            if (run(&rows[r], ch, np, kind ? full : height, ntiles, reps, &res))
                return 1;
            printf("| %s | %.0f | 1/%.1f | %.3f | %.3f | %.2e | %.2e | %.1f | %.1f |\n", rows[r].name, res.bytes,
                   raw / res.bytes, res.enc_ms, res.dec_ms, res.maxabs, res.rms, res.psnr_min, res.psnr_mean);
            if (csv)
                fprintf(csv, "%s,%s,%.1f,%.4f,%.4f,%.4f,%.6g,%.6g,%.2f,%.2f\n", kinds[kind], rows[r].name, res.bytes,
                        res.bytes / raw, res.enc_ms, res.dec_ms, res.maxabs, res.rms, res.psnr_min, res.psnr_mean);
        }
    }
    for (int kind = 0; kind < 2; kind++) {
        unsigned ch = kind ? PROTO_CH_WORLD : PROTO_CH_HEIGHT;
        int np = kind ? planes_all : 1;
        printf("\n### qz encoder before (format 1, no context) and after (format 2, per-worker contexts; issue 14), %dx%d %s tiles, accuracy 5e-3\n\n",
               TILE, TILE, kind ? "seven-plane" : "height-only");
        printf("Interleaved tile by tile in this run; MB/s = raw f32 bytes encoded per second (median time "
               "per tile); H PSNR is the worst tile's.\n\n");
        printf("| encoder | bytes/tile | vs f32 | H PSNR worst (dB) | encode ms | encode MB/s | speed-up |\n");
        printf("|---|---:|---:|---:|---:|---:|---:|\n");
        if (before_after(ch, np, kind ? full : height, ntiles, reps * 3, csv, kinds[kind]))
            return 1;
    }
    if (layout1_table(quick, csv))
        return 1;
    if (csv)
        fclose(csv);
    printf("\nTarget: default codec (qz, accuracy 5e-3) <= 1/8 of f32 bytes with worst-tile height PSNR >= 50 dB.\n");
    for (int i = 0; i < ntiles; i++) {
        free(full[i]);
        free(height[i]);
    }
    return 0;
}
