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

#define TILE 64

typedef struct row {
    const char *name;
    proto_codec codec;
    double accuracy;
} row;

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
            if (proto_tile_encode(rw->codec, &prm, TILE, TILE, channels, tiles[t], &b, NULL, err, sizeof err)) {
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
        if (proto_buf_len(&b[0]) == proto_buf_len(&b[2]) && proto_buf_len(&b[1]) == proto_buf_len(&b[2]) &&
            memcmp(proto_buf_data(&b[0]), proto_buf_data(&b[2]), proto_buf_len(&b[2])) == 0 &&
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
    const char *names[3] = {"before (63a4af9: new ZSTD_CCtx per call)", "after, context-free proto_tile_encode",
                            "after, one proto_codec_ctx reused"};
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
    printf("\n%d of %d tiles: the three payloads are byte-identical (the format and the bytes are unchanged).\n\n",
           same, ntiles);
    for (int k = 0; k < 3; k++) {
        free(ms[k]);
        proto_buf_free(&b[k]);
    }
    free(back);
    proto_codec_ctx_destroy(ctx);
    return 0;
}

int main(void)
{
    int quick = bench_quick();
    const row rows[] = {
        {"f32", PROTO_CODEC_F32, 0},
        {"f16", PROTO_CODEC_F16, 0},
        {"qz acc=1e-2", PROTO_CODEC_QZ, 1e-2},
        {"qz acc=5e-3 (default)", PROTO_CODEC_QZ, 5e-3},
        {"qz acc=4e-3", PROTO_CODEC_QZ, 4e-3},
        {"qz acc=3e-3", PROTO_CODEC_QZ, 3e-3},
        {"qz acc=1e-3", PROTO_CODEC_QZ, 1e-3},
        {"qz acc=1e-4", PROTO_CODEC_QZ, 1e-4},
        {"exr-zip (float)", PROTO_CODEC_EXR_ZIP, 0},
        {"exr-piz (half)", PROTO_CODEC_EXR_PIZ, 0},
        {"exr-b44 (half)", PROTO_CODEC_EXR_B44, 0},
        {"exr-b44a (half)", PROTO_CODEC_EXR_B44A, 0},
    };
    const int nrows = (int)(sizeof rows / sizeof rows[0]);
    /* Three seas: a calm 5 m/s, the default 10 m/s, a 25 m/s storm; each
     * with the default 256 grid over a patch that gives 1-8 m spacing. */
    const struct { const char *name; double u10, patch; } seas[] = {
        {"calm 5 m/s, 256 m patch", 5, 256}, {"default 10 m/s, 1000 m", 10, 1000}, {"storm 25 m/s, 2000 m", 25, 2000}};
    const int per_sea = quick ? 4 : 12, reps = quick ? 2 : 5;
    const int ntiles = 3 * per_sea;
    const int planes_all = proto_tile_planes(PROTO_CH_ALL);
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
        unsigned ch = kind ? PROTO_CH_ALL : PROTO_CH_HEIGHT;
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
        unsigned ch = kind ? PROTO_CH_ALL : PROTO_CH_HEIGHT;
        int np = kind ? planes_all : 1;
        printf("\n### qz encoder before and after per-worker contexts (issue 14), %dx%d %s tiles, accuracy 5e-3\n\n",
               TILE, TILE, kind ? "seven-plane" : "height-only");
        printf("Interleaved tile by tile in this run; MB/s = raw f32 bytes encoded per second (median time "
               "per tile); H PSNR is the worst tile's.\n\n");
        printf("| encoder | bytes/tile | vs f32 | H PSNR worst (dB) | encode ms | encode MB/s | speed-up |\n");
        printf("|---|---:|---:|---:|---:|---:|---:|\n");
        if (before_after(ch, np, kind ? full : height, ntiles, reps * 3, csv, kinds[kind]))
            return 1;
    }
    if (csv)
        fclose(csv);
    printf("\nTarget: default codec (qz, accuracy 5e-3) <= 1/8 of f32 bytes with worst-tile height PSNR >= 50 dB.\n");
    for (int i = 0; i < ntiles; i++) {
        free(full[i]);
        free(height[i]);
    }
    return 0;
}
