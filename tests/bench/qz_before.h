/*
 * qz_before.h - the qz encoder as it was at 63a4af9 (before proto_codec_ctx
 * and the integer least-squares fit), frozen here so bench_codec can put
 * the before and after encoders side by side in one run and check that
 * they write the same bytes.  Not used by anything shipped.
 */
#ifndef QZB_BEFORE_H
#define QZB_BEFORE_H

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <zstd.h>

#include "codec.h"
#include "proto_buf.h"

#define QZB_FORMAT 1
#define QZB_HEAD 4
#define QZB_PLANE_HEAD 24
#define QZB_PRED_PLANAR 1
#define QZB_PRED_LS6 2
#define QZB_NCOEF 6

static double qzb_step(double accuracy, double range)
{
    if (!(range > 0.0))
        return 1.0;
    float s = (float)(2.0 * accuracy * range);
    if (s < FLT_MIN)
        s = FLT_MIN;
    return (double)s;
}
static inline uint32_t qzb_zigzag(int64_t r) { return (uint32_t)((uint64_t)r << 1) ^ (uint32_t)(r >> 63); }
static inline int64_t qzb_floordiv4096(int64_t a) { return a >= 0 ? a / 4096 : -((-a + 4095) / 4096); }
static inline int64_t qzb_predict(const int64_t *q, int w, int i, int j, int pred, const int16_t *coef)
{
    if (i == 0)
        return j == 0 ? 0 : q[j - 1];
    const int64_t *row = q + (size_t)i * w, *up = row - w;
    if (j == 0)
        return up[0];
    if (pred == QZB_PRED_LS6 && i >= 2 && j >= 2 && j + 1 < w) {
        int64_t s = coef[0] * row[j - 1] + coef[1] * up[j] + coef[2] * up[j - 1] + coef[3] * up[j + 1] +
                    coef[4] * row[j - 2] + coef[5] * (up - w)[j];
        return qzb_floordiv4096(s + 2048);
    }
    return row[j - 1] + up[j] - up[j - 1];
}

/* Least-squares weights of the LS6 neighbours for this plane, rounded to
 * multiples of 1/4096.  Returns 0 if the system is singular or the tile too
 * small, leaving the planar predictor in charge. */
static int qzb_fit_ls6(const int64_t *q, int w, int h, int16_t *coef)
{
    if (w < 5 || h < 3)
        return 0;
    double A[QZB_NCOEF][QZB_NCOEF] = {{0}}, b[QZB_NCOEF] = {0}, x[QZB_NCOEF];
    for (int i = 2; i < h; i++) {
        const int64_t *row = q + (size_t)i * w, *up = row - w, *up2 = up - w;
        for (int j = 2; j + 1 < w; j++) {
            double n[QZB_NCOEF] = {(double)row[j - 1], (double)up[j], (double)up[j - 1], (double)up[j + 1],
                                  (double)row[j - 2], (double)up2[j]};
            double v = (double)row[j];
            for (int a = 0; a < QZB_NCOEF; a++) {
                b[a] += n[a] * v;
                for (int c = 0; c < QZB_NCOEF; c++)
                    A[a][c] += n[a] * n[c];
            }
        }
    }
    /* Gaussian elimination with partial pivoting. */
    for (int i = 0; i < QZB_NCOEF; i++) {
        int p = i;
        for (int r = i + 1; r < QZB_NCOEF; r++)
            if (fabs(A[r][i]) > fabs(A[p][i]))
                p = r;
        if (!(fabs(A[p][i]) > 1e-9 * (fabs(A[0][0]) + 1.0)))
            return 0;
        for (int c = 0; c < QZB_NCOEF; c++) {
            double t = A[i][c];
            A[i][c] = A[p][c];
            A[p][c] = t;
        }
        double t = b[i];
        b[i] = b[p];
        b[p] = t;
        for (int r = 0; r < QZB_NCOEF; r++)
            if (r != i) {
                double f = A[r][i] / A[i][i];
                for (int c = 0; c < QZB_NCOEF; c++)
                    A[r][c] -= f * A[i][c];
                b[r] -= f * b[i];
            }
    }
    for (int i = 0; i < QZB_NCOEF; i++) {
        x[i] = b[i] / A[i][i];
        if (!isfinite(x[i]) || fabs(x[i]) > 7.9)
            return 0;
        coef[i] = (int16_t)lround(x[i] * 4096.0);
    }
    return 1;
}

/* Residuals of q under (pred, coef) into z; returns the sum of |r| as a
 * cost estimate and the largest qzb_zigzag value in *zmax. */
static uint64_t qzb_residuals(const int64_t *q, int w, int h, int pred, const int16_t *coef, uint32_t *z, uint32_t *zmax)
{
    uint64_t cost = 0;
    uint32_t m = 0;
    for (int i = 0; i < h; i++)
        for (int j = 0; j < w; j++) {
            size_t k = (size_t)i * w + j;
            int64_t r = q[k] - qzb_predict(q, w, i, j, pred, coef);
            z[k] = qzb_zigzag(r);
            cost += (uint64_t)(r < 0 ? -r : r);
            if (z[k] > m)
                m = z[k];
        }
    *zmax = m;
    return cost;
}

/* Residual bytes are nearly i.i.d., so zstd's match finder mostly finds
 * short accidental matches that cost more than the literals they replace;
 * minMatch 7 leaves the literals to zstd's Huffman stage. */
static size_t qzb_zstd(void *dst, size_t cap, const void *src, size_t n, int level)
{
    ZSTD_CCtx *cc = ZSTD_createCCtx();
    if (!cc)
        return (size_t)-1;
    size_t r = ZSTD_CCtx_setParameter(cc, ZSTD_c_compressionLevel, level);
    if (!ZSTD_isError(r))
        r = ZSTD_CCtx_setParameter(cc, ZSTD_c_minMatch, 7);
    if (!ZSTD_isError(r))
        r = ZSTD_compress2(cc, dst, cap, src, n);
    ZSTD_freeCCtx(cc);
    return r;
}

static ocean_result qzb_encode(const proto_codec_params *p, int w, int h, int np, const float *planes,
                              proto_buf *out, double *max_err, char *err, size_t errlen)
{
    double acc = p->accuracy;
    if (!(acc >= PROTO_ACCURACY_MIN && acc <= PROTO_ACCURACY_MAX)) {
        ocean_seterr(err, errlen, "qz accuracy %g outside %g..%g", acc, PROTO_ACCURACY_MIN, PROTO_ACCURACY_MAX);
        return OCEAN_EINVAL;
    }
    int level = p->zstd_level;
    if (level < 1 || level > 19)
        level = 3;
    size_t n = (size_t)w * h;
    int64_t *q = malloc(n * sizeof *q);
    uint32_t *z = malloc(n * sizeof *z), *z2 = malloc(n * sizeof *z2);
    uint8_t *raw = malloc(n * 4 * (size_t)np + 1);
    uint8_t head[QZB_HEAD + QZB_PLANE_HEAD * PROTO_TILE_MAX_PLANES + 4];
    ocean_result res = OCEAN_OK;
    if (!q || !z || !z2 || !raw) {
        res = OCEAN_ENOMEM;
        goto done;
    }
    memset(head, 0, sizeof head);
    head[0] = (uint8_t)np;
    head[1] = QZB_FORMAT;
    size_t rawlen = 0;
    double merr = 0.0;
    for (int c = 0; c < np; c++) {
        const float *src = planes + (size_t)c * n;
        float lo = src[0], hi = src[0];
        for (size_t k = 1; k < n; k++) {
            if (src[k] < lo)
                lo = src[k];
            if (src[k] > hi)
                hi = src[k];
        }
        double range = (double)hi - (double)lo;
        double step = qzb_step(acc, range);
        int64_t qmax = (int64_t)llround(range / step);
        for (size_t k = 0; k < n; k++) {
            int64_t v = (int64_t)llround(((double)src[k] - (double)lo) / step);
            if (v < 0)
                v = 0;
            if (v > qmax)
                v = qmax;
            q[k] = v;
            double d = fabs((double)(float)((double)lo + (double)v * step) - (double)src[k]);
            if (d > merr)
                merr = d;
        }
        int16_t coef[QZB_NCOEF] = {0}, none[QZB_NCOEF] = {0};
        uint32_t zmax, zmax2;
        int pred = QZB_PRED_PLANAR;
        uint64_t cost = qzb_residuals(q, w, h, QZB_PRED_PLANAR, none, z, &zmax);
        if (cost > 0 && qzb_fit_ls6(q, w, h, coef)) {
            uint64_t cost2 = qzb_residuals(q, w, h, QZB_PRED_LS6, coef, z2, &zmax2);
            if (cost2 < cost) {
                uint32_t *t = z;
                z = z2;
                z2 = t;
                zmax = zmax2;
                pred = QZB_PRED_LS6;
            }
        }
        if (pred != QZB_PRED_LS6)
            memset(coef, 0, sizeof coef);
        int nb = zmax == 0 ? 0 : zmax < 0x100u ? 1 : zmax < 0x10000u ? 2 : zmax < 0x1000000u ? 3 : 4;
        uint8_t *ph = head + QZB_HEAD + QZB_PLANE_HEAD * c;
        proto_stf32(ph, lo);
        proto_stf32(ph + 4, (float)step);
        ph[8] = (uint8_t)nb;
        ph[9] = (uint8_t)pred;
        for (int k = 0; k < QZB_NCOEF; k++)
            proto_st16(ph + 12 + 2 * k, (uint16_t)coef[k]);
        for (int b = 0; b < nb; b++) {
            for (size_t k = 0; k < n; k++)
                raw[rawlen + k] = (uint8_t)(z[k] >> (8 * b));
            rawlen += n;
        }
    }
    size_t headlen = QZB_HEAD + QZB_PLANE_HEAD * (size_t)np;
    proto_st32(head + headlen, (uint32_t)rawlen);
    headlen += 4;
    size_t bound = ZSTD_compressBound(rawlen);
    size_t start = out->len;
    uint8_t *dst;
    if ((res = proto_buf_grow(out, headlen + bound, &dst)) != OCEAN_OK)
        goto done;
    memcpy(dst, head, headlen);
    size_t zn = qzb_zstd(dst + headlen, bound, raw, rawlen, level);
    if (ZSTD_isError(zn)) {
        proto_buf_truncate(out, start);
        ocean_seterr(err, errlen, "zstd: %s", ZSTD_getErrorName(zn));
        res = OCEAN_ECODEC;
        goto done;
    }
    proto_buf_truncate(out, start + headlen + zn);
    if (max_err)
        *max_err = merr;
done:
    free(q);
    free(z);
    free(z2);
    free(raw);
    return res;
}

#endif
