/*
 * codec.c - tile codecs f32, f16 and qz (quantised + planar prediction +
 * zstd), octahedral normals and half-float conversion.  The OpenEXR codecs
 * live in proto_exr.c.  Byte layouts are specified in PROTOCOL.md; this file
 * and that document must change together.
 */
#include "codec.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zstd.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif


static const char *const plane_names[PROTO_TILE_MAX_PLANES] = {"H", "DX", "DZ", "NU", "NV", "FOAM", "J"};

void proto_codec_params_default(proto_codec_params *p)
{
    p->accuracy = PROTO_ACCURACY_DEFAULT;
    p->zstd_level = 3;
    p->zip_level = 4;
}

static const char *const codec_names[PROTO_CODEC_COUNT_] = {
    "f32", "f16", "qz", "exr-zip", "exr-piz", "exr-b44", "exr-b44a"};

const char *proto_codec_name(proto_codec c)
{
    return ((unsigned)c < PROTO_CODEC_COUNT_) ? codec_names[c] : "?";
}

ocean_result proto_codec_parse(const char *name, proto_codec *out)
{
    for (int i = 0; name && i < PROTO_CODEC_COUNT_; i++)
        if (strcmp(name, codec_names[i]) == 0) {
            *out = (proto_codec)i;
            return OCEAN_OK;
        }
    return OCEAN_ETYPE;
}

int proto_codec_lossless(proto_codec c)
{
    return c == PROTO_CODEC_F32 || c == PROTO_CODEC_EXR_ZIP;
}

int proto_tile_planes(unsigned channels)
{
    if (channels == 0 || (channels & ~PROTO_CH_ALL))
        return 0;
    int n = 0;
    for (unsigned b = 0; b < 6; b++)
        if (channels & (1u << b))
            n += (b == 3) ? 2 : 1;
    return n;
}

const char *proto_tile_plane_name(unsigned channels, int i)
{
    if (proto_tile_planes(channels) == 0 || i < 0)
        return NULL;
    /* plane slots: H DX DZ NU NV FOAM J; channel bit b covers slot(s) */
    static const int slot_bit[PROTO_TILE_MAX_PLANES] = {0, 1, 2, 3, 3, 4, 5};
    int k = 0;
    for (int s = 0; s < PROTO_TILE_MAX_PLANES; s++)
        if (channels & (1u << slot_bit[s])) {
            if (k == i)
                return plane_names[s];
            k++;
        }
    return NULL;
}

/* ---- half floats ------------------------------------------------------ */

uint16_t proto_f16_from_f32(float f)
{
    uint32_t x;
    memcpy(&x, &f, 4);
    uint32_t sign = (x >> 16) & 0x8000u;
    uint32_t a = x & 0x7fffffffu;
    if (a >= 0x7f800000u)                       /* inf or NaN */
        return (uint16_t)(sign | (a > 0x7f800000u ? 0x7e00u : 0x7c00u));
    if (a >= 0x477ff000u)                       /* >= 65520 rounds to inf */
        return (uint16_t)(sign | 0x7c00u);
    if (a < 0x38800000u) {                      /* below 2^-14: subnormal */
        if (a <= 0x33000000u)                   /* <= 2^-25 rounds to 0 */
            return (uint16_t)sign;
        uint32_t m = (a & 0x7fffffu) | 0x800000u;
        int shift = 126 - (int)(a >> 23);       /* 14 .. 24 */
        uint32_t h = m >> shift;
        uint32_t rem = m & ((1u << shift) - 1u), halfway = 1u << (shift - 1);
        if (rem > halfway || (rem == halfway && (h & 1u)))
            h++;
        return (uint16_t)(sign | h);
    }
    uint32_t h = (a - 0x38000000u) >> 13;
    uint32_t rem = a & 0x1fffu;
    if (rem > 0x1000u || (rem == 0x1000u && (h & 1u)))
        h++;
    return (uint16_t)(sign | h);
}

float proto_f32_from_f16(uint16_t h)
{
    uint32_t sign = ((uint32_t)h & 0x8000u) << 16;
    uint32_t e = (h >> 10) & 0x1fu, m = h & 0x3ffu, x;
    if (e == 0) {
        float v = (float)m * 0x1p-24f;
        memcpy(&x, &v, 4);
        x |= sign;
    } else if (e == 31) {
        x = sign | 0x7f800000u | (m << 13);
    } else {
        x = sign | ((e + 112u) << 23) | (m << 13);
    }
    float f;
    memcpy(&f, &x, 4);
    return f;
}

/* ---- octahedral normals ----------------------------------------------- */

static float sgn1(float x) { return x >= 0.0f ? 1.0f : -1.0f; }

void proto_normal_oct_encode(float nx, float ny, float nz, float *u, float *v)
{
    float s = fabsf(nx) + fabsf(ny) + fabsf(nz);
    if (!(s > 0.0f) || !isfinite(s)) {
        *u = 0.0f;
        *v = 0.0f;
        return;
    }
    float px = nx / s, pz = nz / s;
    if (ny < 0.0f) {
        float ox = (1.0f - fabsf(pz)) * sgn1(px);
        float oz = (1.0f - fabsf(px)) * sgn1(pz);
        px = ox;
        pz = oz;
    }
    *u = px;
    *v = pz;
}

void proto_normal_oct_decode(float u, float v, float *nx, float *ny, float *nz)
{
    float x = u, z = v, y = 1.0f - fabsf(u) - fabsf(v);
    if (y < 0.0f) {
        float ox = (1.0f - fabsf(z)) * sgn1(x);
        float oz = (1.0f - fabsf(x)) * sgn1(z);
        x = ox;
        z = oz;
    }
    float l = sqrtf(x * x + y * y + z * z);
    if (!(l > 0.0f)) {
        *nx = 0.0f, *ny = 1.0f, *nz = 0.0f;
        return;
    }
    *nx = x / l;
    *ny = y / l;
    *nz = z / l;
}

void proto_normals_from_slopes(const float *sx, const float *sz, size_t n, float *nu, float *nv)
{
    for (size_t i = 0; i < n; i++)
        proto_normal_oct_encode(-sx[i], 1.0f, -sz[i], &nu[i], &nv[i]);
}

/* ---- error bounds ----------------------------------------------------- */

static double qz_step(double accuracy, double range)
{
    if (!(range > 0.0))
        return 1.0;
    float s = (float)(2.0 * accuracy * range);
    if (s < FLT_MIN)
        s = FLT_MIN;
    return (double)s;
}

double proto_codec_error_bound(proto_codec c, const proto_codec_params *p, double lo, double hi)
{
    double amax = fmax(fabs(lo), fabs(hi));
    double range = hi - lo;
    switch (c) {
    case PROTO_CODEC_F32:
    case PROTO_CODEC_EXR_ZIP:
        return 0.0;
    case PROTO_CODEC_F16:
    case PROTO_CODEC_EXR_PIZ:
        /* half rounding: half an ulp, at most 2^-11 relative, 2^-25 absolute
         * in the subnormal range */
        return fmax(amax * 0x1p-11, 0x1p-25);
    case PROTO_CODEC_QZ: {
        double acc = p ? p->accuracy : PROTO_ACCURACY_DEFAULT;
        return qz_step(acc, range) * 0.5 + amax * 0x1p-24 + (range > 0 ? range * 0x1p-40 : 0.0);
    }
    case PROTO_CODEC_EXR_B44:
    case PROTO_CODEC_EXR_B44A:
        /* half rounding, then up to 2^(shift-1) ordered steps lost per 4x4
         * block; across zero that can reach half the magnitude (2^9 lost steps of ulp(max)) */
        return amax * 0.5 + fmax(amax * 0x1p-11, 0x1p-25);
    default:
        return INFINITY;
    }
}

/* ---- f32 / f16 -------------------------------------------------------- */

static ocean_result check_args(proto_codec c, int w, int h, unsigned channels, const void *planes,
                               int *np, size_t *nsamp, char *err, size_t errlen)
{
    if ((unsigned)c >= PROTO_CODEC_COUNT_) {
        ocean_seterr(err, errlen, "unknown codec %d", (int)c);
        return OCEAN_ETYPE;
    }
    if (w < 1 || h < 1 || w > PROTO_TILE_MAX_SIZE || h > PROTO_TILE_MAX_SIZE) {
        ocean_seterr(err, errlen, "tile size %dx%d outside 1..%d", w, h, PROTO_TILE_MAX_SIZE);
        return OCEAN_EINVAL;
    }
    int n = proto_tile_planes(channels);
    if (n == 0) {
        ocean_seterr(err, errlen, "bad channel mask 0x%x", channels);
        return OCEAN_EINVAL;
    }
    if (!planes) {
        ocean_seterr(err, errlen, "no sample array");
        return OCEAN_EINVAL;
    }
    *np = n;
    *nsamp = (size_t)w * (size_t)h;
    return OCEAN_OK;
}

static double measure_err(const float *a, const float *b, size_t n)
{
    double m = 0.0;
    for (size_t i = 0; i < n; i++) {
        double d = fabs((double)a[i] - (double)b[i]);
        if (d > m)
            m = d;
    }
    return m;
}

static ocean_result f16_encode(const float *src, size_t n, proto_buf *out, double *max_err,
                               char *err, size_t errlen)
{
    for (size_t i = 0; i < n; i++)
        if (fabsf(src[i]) > 65504.0f) {
            ocean_seterr(err, errlen, "value %g beyond the half-float range", (double)src[i]);
            return OCEAN_ECODEC;
        }
    uint8_t *p;
    ocean_result r = proto_buf_grow(out, n * 2, &p);
    if (r != OCEAN_OK)
        return r;
    double m = 0.0;
    for (size_t i = 0; i < n; i++) {
        uint16_t hv = proto_f16_from_f32(src[i]);
        proto_st16(p + 2 * i, hv);
        double d = fabs((double)proto_f32_from_f16(hv) - (double)src[i]);
        if (d > m)
            m = d;
    }
    if (max_err)
        *max_err = m;
    return OCEAN_OK;
}

/* ---- qz ------------------------------------------------------------------ */

#define QZ_FORMAT 1
#define QZ_HEAD 4          /* planes u8, format u8, reserved u16 */
#define QZ_PLANE_HEAD 24   /* base f32, step f32, nbytes u8, predictor u8, reserved u16, coef i16[6] */
#define QZ_PRED_PLANAR 1
#define QZ_PRED_LS6 2
#define QZ_NCOEF 6
/* |q| beyond this cannot come from our encoder (accuracy >= 1e-6 gives
 * q <= 5e5); a decoder meeting it has hostile input.  It also keeps every
 * predictor sum below 2^53, so a JavaScript decoder computes it exactly. */
#define QZ_Q_LIMIT (1LL << 30)

static inline uint32_t zigzag(int64_t r) { return (uint32_t)((uint64_t)r << 1) ^ (uint32_t)(r >> 63); }
static inline int64_t unzigzag(uint32_t z) { return (int64_t)(z >> 1) ^ -(int64_t)(z & 1u); }

/* floor(a / 4096) for any sign (C's / truncates toward zero). */
static inline int64_t floordiv4096(int64_t a) { return a >= 0 ? a / 4096 : -((-a + 4095) / 4096); }

/* The prediction of q[i][j] from already decoded samples.  LS6 uses the
 * neighbours left, up, up-left, up-right, left-left, up-up with fixed-point
 * weights coef/4096 where all six exist; elsewhere both predictors fall
 * back to: (0,0) -> 0, first row -> left, first column -> up, else planar
 * left + up - up-left. */
static inline int64_t qz_predict(const int64_t *q, int w, int i, int j, int pred, const int16_t *coef)
{
    if (i == 0)
        return j == 0 ? 0 : q[j - 1];
    const int64_t *row = q + (size_t)i * w, *up = row - w;
    if (j == 0)
        return up[0];
    if (pred == QZ_PRED_LS6 && i >= 2 && j >= 2 && j + 1 < w) {
        int64_t s = coef[0] * row[j - 1] + coef[1] * up[j] + coef[2] * up[j - 1] + coef[3] * up[j + 1] +
                    coef[4] * row[j - 2] + coef[5] * (up - w)[j];
        return floordiv4096(s + 2048);
    }
    return row[j - 1] + up[j] - up[j - 1];
}

/* ---- qz encoder ---------------------------------------------------------- */

/* What a worker keeps between tiles: the zstd context (creating one costs
 * about as much as compressing a small tile) and the scratch planes. */
struct proto_codec_ctx {
    ZSTD_CCtx *zc;
    int zc_level;        /* level zc holds; 0: parameters not set yet */
    size_t cap;          /* samples q, z, z2 hold */
    int32_t *q;          /* quantised plane (the encoder's q fits 32 bits) */
    uint32_t *z, *z2;    /* zigzag residuals: kept, candidate */
    size_t rawcap;
    uint8_t *raw;        /* byte planes of every plane's residuals */
};

ocean_result proto_codec_ctx_create(proto_codec_ctx **out)
{
    if (!out)
        return OCEAN_EINVAL;
    *out = calloc(1, sizeof **out);
    return *out ? OCEAN_OK : OCEAN_ENOMEM;
}

void proto_codec_ctx_destroy(proto_codec_ctx *c)
{
    if (!c)
        return;
    ZSTD_freeCCtx(c->zc);
    free(c->q);
    free(c->z);
    free(c->z2);
    free(c->raw);
    free(c);
}

static ocean_result ctx_reserve(proto_codec_ctx *c, size_t n, size_t rawlen)
{
    if (n > c->cap) {
        int32_t *q = realloc(c->q, n * sizeof *q);
        if (q) c->q = q;
        uint32_t *z = realloc(c->z, n * sizeof *z);
        if (z) c->z = z;
        uint32_t *z2 = realloc(c->z2, n * sizeof *z2);
        if (z2) c->z2 = z2;
        if (!q || !z || !z2)
            return OCEAN_ENOMEM;
        c->cap = n;
    }
    if (rawlen > c->rawcap) {
        uint8_t *r = realloc(c->raw, rawlen);
        if (!r)
            return OCEAN_ENOMEM;
        c->raw = r;
        c->rawcap = rawlen;
    }
    return OCEAN_OK;
}

/* Least-squares weights of the LS6 neighbours for this plane, rounded to
 * multiples of 1/4096.  Returns 0 if the system is singular or the tile too
 * small, leaving the planar predictor in charge.  The normal equations are
 * summed in 64-bit integers, exactly (|q| < 2^20 from this encoder, so
 * each product < 2^40 and a 1024 x 1024 tile's sums < 2^60), and only the
 * 21 distinct entries of the symmetric matrix. */
/* One row's contribution to the normal equations (see qz_fit_ls6): the 21
 * distinct products of the six neighbours and the 6 with the sample,
 * summed over j = 2 .. w-2.  Exact in 64-bit unsigned arithmetic, so the
 * SSE2 path and the portable one (alone with -DQZ_NO_SIMD) give the same
 * sums; SSE2 made a default height tile's encode 28 % faster here. */
static void qz_fit_row(const uint32_t *row, const uint32_t *up, const uint32_t *up2, int w, uint64_t *r,
                       uint64_t *rb)
{
    int j = 2;
#if defined(__SSE2__) && !defined(QZ_NO_SIMD)
    /* Two samples per step: each neighbour of (j, j+1) is two adjacent
     * words, widened into the 64-bit lanes pmuludq multiplies. */
    __m128i acc[27], zero = _mm_setzero_si128();
    for (int k = 0; k < 27; k++)
        acc[k] = zero;
    for (; j + 2 < w; j += 2) {
#define QZ_LD(p) _mm_unpacklo_epi32(_mm_loadl_epi64((const __m128i *)(const void *)(p)), zero)
        __m128i n[6] = {QZ_LD(row + j - 1), QZ_LD(up + j), QZ_LD(up + j - 1),
                        QZ_LD(up + j + 1), QZ_LD(row + j - 2), QZ_LD(up2 + j)};
        __m128i v = QZ_LD(row + j);
#undef QZ_LD
        int k = 0;
        for (int a = 0; a < 6; a++)
            for (int c = a; c < 6; c++, k++)
                acc[k] = _mm_add_epi64(acc[k], _mm_mul_epu32(n[a], n[c]));
        for (int a = 0; a < 6; a++)
            acc[21 + a] = _mm_add_epi64(acc[21 + a], _mm_mul_epu32(n[a], v));
    }
    for (int k = 0; k < 27; k++) {
        uint64_t l[2];
        _mm_storeu_si128((__m128i *)(void *)l, acc[k]);
        (k < 21 ? r : rb)[k < 21 ? k : k - 21] += l[0] + l[1];
    }
#endif
    for (; j + 1 < w; j++) {
        uint64_t n[6] = {row[j - 1], up[j], up[j - 1], up[j + 1], row[j - 2], up2[j]}, v = row[j];
        int k = 0;
        for (int a = 0; a < 6; a++)
            for (int c = a; c < 6; c++, k++)
                r[k] += n[a] * n[c];
        for (int a = 0; a < 6; a++)
            rb[a] += n[a] * v;
    }
}

static int qz_fit_ls6(const int32_t *q, int w, int h, int16_t *coef)
{
    if (w < 5 || h < 3)
        return 0;
    /* q >= 0 here, so each product is an unsigned 32 x 32 -> 64 bit
     * multiply (pmuludq on x86, two samples at a time). */
    uint64_t s[QZ_NCOEF * (QZ_NCOEF + 1) / 2] = {0}, sb[QZ_NCOEF] = {0};
    for (int i = 2; i < h; i++) {
        const uint32_t *row = (const uint32_t *)q + (size_t)i * w, *up = row - w, *up2 = up - w;
        uint64_t r[21] = {0}, rb[6] = {0};
        qz_fit_row(row, up, up2, w, r, rb);
        for (int k = 0; k < 21; k++)
            s[k] += r[k];
        for (int k = 0; k < 6; k++)
            sb[k] += rb[k];
    }
    double A[QZ_NCOEF][QZ_NCOEF], b[QZ_NCOEF], x[QZ_NCOEF];
    for (int i = 0, k = 0; i < QZ_NCOEF; i++) {
        b[i] = (double)sb[i];
        for (int c = i; c < QZ_NCOEF; c++, k++)
            A[i][c] = A[c][i] = (double)s[k];
    }
    /* Gaussian elimination with partial pivoting. */
    for (int i = 0; i < QZ_NCOEF; i++) {
        int p = i;
        for (int r = i + 1; r < QZ_NCOEF; r++)
            if (fabs(A[r][i]) > fabs(A[p][i]))
                p = r;
        if (!(fabs(A[p][i]) > 1e-9 * (fabs(A[0][0]) + 1.0)))
            return 0;
        for (int c = 0; c < QZ_NCOEF; c++) {
            double t = A[i][c];
            A[i][c] = A[p][c];
            A[p][c] = t;
        }
        double t = b[i];
        b[i] = b[p];
        b[p] = t;
        for (int r = 0; r < QZ_NCOEF; r++)
            if (r != i) {
                double f = A[r][i] / A[i][i];
                for (int c = 0; c < QZ_NCOEF; c++)
                    A[r][c] -= f * A[i][c];
                b[r] -= f * b[i];
            }
    }
    for (int i = 0; i < QZ_NCOEF; i++) {
        x[i] = b[i] / A[i][i];
        if (!isfinite(x[i]) || fabs(x[i]) > 7.9)
            return 0;
        coef[i] = (int16_t)lround(x[i] * 4096.0);
    }
    return 1;
}

/* One residual: zigzag into *z, |r| added to the cost, max kept. */
#define QZ_PUT(k, pred)                                   \
    do {                                                  \
        int64_t r_ = (int64_t)q[k] - (int64_t)(pred);     \
        uint32_t z_ = zigzag(r_);                         \
        z[k] = z_;                                        \
        cost += (uint64_t)(r_ < 0 ? -r_ : r_);            \
        m = z_ > m ? z_ : m;                              \
    } while (0)

/* Residuals of q under (pred, coef) into z, exactly as qz_predict (the
 * decoder's) predicts, with the edge cases peeled off so the interior
 * loops carry no branches; returns the sum of |r| as a cost estimate and
 * the largest zigzag value in *zmax. */
static uint64_t qz_residuals32(const int32_t *q, int w, int h, int pred, const int16_t *coef, uint32_t *z,
                               uint32_t *zmax)
{
    uint64_t cost = 0;
    uint32_t m = 0;
    QZ_PUT(0, 0);
    for (int j = 1; j < w; j++)
        QZ_PUT(j, q[j - 1]);
    const int64_t c0 = coef[0], c1 = coef[1], c2 = coef[2], c3 = coef[3], c4 = coef[4], c5 = coef[5];
    for (int i = 1; i < h; i++) {
        size_t o = (size_t)i * w;
        const int32_t *row = q + o, *up = row - w;
        QZ_PUT(o, up[0]);
        if (pred != QZ_PRED_LS6 || i < 2 || w < 4) {
            for (int j = 1; j < w; j++)
                QZ_PUT(o + j, (int64_t)row[j - 1] + up[j] - up[j - 1]);
            continue;
        }
        const int32_t *up2 = up - w;
        QZ_PUT(o + 1, (int64_t)row[0] + up[1] - up[0]);
        for (int j = 2; j + 1 < w; j++) {
            int64_t sum = c0 * row[j - 1] + c1 * up[j] + c2 * up[j - 1] + c3 * up[j + 1] + c4 * row[j - 2] +
                          c5 * up2[j];
            /* floor((sum + 2048) / 4096): an arithmetic shift floors (gcc). */
            QZ_PUT(o + j, (sum + 2048) >> 12);
        }
        QZ_PUT(o + w - 1, (int64_t)row[w - 2] + up[w - 1] - up[w - 2]);
    }
    *zmax = m;
    return cost;
}

/* Residual bytes are nearly i.i.d., so zstd's match finder mostly finds
 * short accidental matches that cost more than the literals they replace;
 * minMatch 7 leaves the literals to zstd's Huffman stage.  The context's
 * parameters stick across frames, so they are set when the level changes. */
static size_t qz_zstd(proto_codec_ctx *c, void *dst, size_t cap, const void *src, size_t n, int level)
{
    if (!c->zc) {
        c->zc = ZSTD_createCCtx();
        c->zc_level = 0;
        if (!c->zc)
            return (size_t)-1;
    }
    if (c->zc_level != level) {
        size_t r = ZSTD_CCtx_reset(c->zc, ZSTD_reset_session_and_parameters);
        if (!ZSTD_isError(r))
            r = ZSTD_CCtx_setParameter(c->zc, ZSTD_c_compressionLevel, level);
        if (!ZSTD_isError(r))
            r = ZSTD_CCtx_setParameter(c->zc, ZSTD_c_minMatch, 7);
        if (ZSTD_isError(r)) {
            c->zc_level = 0;
            return r;
        }
        c->zc_level = level;
    }
    return ZSTD_compress2(c->zc, dst, cap, src, n);
}

static ocean_result qz_encode(proto_codec_ctx *cx, const proto_codec_params *p, int w, int h, int np,
                              const float *planes, proto_buf *out, double *max_err, char *err, size_t errlen)
{
    double acc = p->accuracy;
    /* the bound as the f32 the wire carries (float 1e-6 is 9.99999997e-7) */
    if (!(acc >= (double)(float)PROTO_ACCURACY_MIN && acc <= PROTO_ACCURACY_MAX)) {
        ocean_seterr(err, errlen, "qz accuracy %g outside %g..%g", acc, PROTO_ACCURACY_MIN, PROTO_ACCURACY_MAX);
        return OCEAN_EINVAL;
    }
    int level = p->zstd_level;
    if (level < 1 || level > 19)
        level = 3;
    size_t n = (size_t)w * h;
    ocean_result res = ctx_reserve(cx, n, n * 4 * (size_t)np + 1);
    if (res != OCEAN_OK)
        return res;
    int32_t *q = cx->q;
    uint32_t *z = cx->z, *z2 = cx->z2;
    uint8_t *raw = cx->raw;
    uint8_t head[QZ_HEAD + QZ_PLANE_HEAD * PROTO_TILE_MAX_PLANES + 4];
    memset(head, 0, sizeof head);
    head[0] = (uint8_t)np;
    head[1] = QZ_FORMAT;
    size_t rawlen = 0;
    double merr = 0.0;
    for (int c = 0; c < np; c++) {
        const float *src = planes + (size_t)c * n;
        float lo = src[0], hi = src[0];
        for (size_t k = 1; k < n; k++) {
            lo = src[k] < lo ? src[k] : lo;
            hi = src[k] > hi ? src[k] : hi;
        }
        double range = (double)hi - (double)lo;
        double step = qz_step(acc, range);
        /* accuracy >= 1e-6 gives qmax <= 5e5 (< 2^20): int32 holds q. */
        int64_t qmax = (int64_t)llround(range / step);
        for (size_t k = 0; k < n; k++) {
            /* t >= 0 (src >= lo), so llround(t) is the truncation plus one
             * when the fraction is at least 1/2: the same integer without
             * a libm call, which kept this loop from staying in registers. */
            double t = ((double)src[k] - (double)lo) / step;
            int64_t v = (int64_t)t;
            v += t - (double)v >= 0.5;
            v = v > qmax ? qmax : v;
            q[k] = (int32_t)v;
            double d = fabs((double)(float)((double)lo + (double)v * step) - (double)src[k]);
            merr = d > merr ? d : merr;
        }
        int16_t coef[QZ_NCOEF] = {0}, none[QZ_NCOEF] = {0};
        uint32_t zmax, zmax2;
        int pred = QZ_PRED_PLANAR;
        uint64_t cost = qz_residuals32(q, w, h, QZ_PRED_PLANAR, none, z, &zmax);
        if (cost > 0 && qz_fit_ls6(q, w, h, coef)) {
            uint64_t cost2 = qz_residuals32(q, w, h, QZ_PRED_LS6, coef, z2, &zmax2);
            if (cost2 < cost) {
                uint32_t *t = z;
                z = z2;
                z2 = t;
                zmax = zmax2;
                pred = QZ_PRED_LS6;
            }
        }
        if (pred != QZ_PRED_LS6)
            memset(coef, 0, sizeof coef);
        int nb = zmax == 0 ? 0 : zmax < 0x100u ? 1 : zmax < 0x10000u ? 2 : zmax < 0x1000000u ? 3 : 4;
        uint8_t *ph = head + QZ_HEAD + QZ_PLANE_HEAD * c;
        proto_stf32(ph, lo);
        proto_stf32(ph + 4, (float)step);
        ph[8] = (uint8_t)nb;
        ph[9] = (uint8_t)pred;
        for (int k = 0; k < QZ_NCOEF; k++)
            proto_st16(ph + 12 + 2 * k, (uint16_t)coef[k]);
        for (int b = 0; b < nb; b++) {
            uint8_t *dst = raw + rawlen;
            for (size_t k = 0; k < n; k++)
                dst[k] = (uint8_t)(z[k] >> (8 * b));
            rawlen += n;
        }
    }
    size_t headlen = QZ_HEAD + QZ_PLANE_HEAD * (size_t)np;
    proto_st32(head + headlen, (uint32_t)rawlen);
    headlen += 4;
    size_t bound = ZSTD_compressBound(rawlen);
    size_t start = out->len;
    uint8_t *dst;
    if ((res = proto_buf_grow(out, headlen + bound, &dst)) != OCEAN_OK)
        return res;
    memcpy(dst, head, headlen);
    size_t zn = qz_zstd(cx, dst + headlen, bound, raw, rawlen, level);
    if (ZSTD_isError(zn)) {
        proto_buf_truncate(out, start);
        ocean_seterr(err, errlen, "zstd: %s", ZSTD_getErrorName(zn));
        /* A failed frame may leave the context mid-stream: start clean. */
        ZSTD_freeCCtx(cx->zc);
        cx->zc = NULL;
        return OCEAN_ECODEC;
    }
    proto_buf_truncate(out, start + headlen + zn);
    if (max_err)
        *max_err = merr;
    return OCEAN_OK;
}

static ocean_result qz_decode(int w, int h, int np, const uint8_t *data, size_t len, float *planes,
                              char *err, size_t errlen)
{
    size_t headlen = QZ_HEAD + QZ_PLANE_HEAD * (size_t)np + 4;
    if (len < headlen) {
        ocean_seterr(err, errlen, "qz payload of %zu bytes shorter than its %zu-byte header", len, headlen);
        return OCEAN_ECODEC;
    }
    if (data[0] != np) {
        ocean_seterr(err, errlen, "qz header says %u planes, tile has %d", data[0], np);
        return OCEAN_ECODEC;
    }
    if (data[1] != QZ_FORMAT || proto_ld16(data + 2) != 0) {
        ocean_seterr(err, errlen, "qz format %u / reserved %u not supported", data[1], proto_ld16(data + 2));
        return OCEAN_ECODEC;
    }
    size_t n = (size_t)w * h, want = 0;
    float base[PROTO_TILE_MAX_PLANES];
    double step[PROTO_TILE_MAX_PLANES];
    int nb[PROTO_TILE_MAX_PLANES], pred[PROTO_TILE_MAX_PLANES];
    int16_t coef[PROTO_TILE_MAX_PLANES][QZ_NCOEF];
    for (int c = 0; c < np; c++) {
        const uint8_t *ph = data + QZ_HEAD + QZ_PLANE_HEAD * c;
        base[c] = proto_ldf32(ph);
        float s = proto_ldf32(ph + 4);
        nb[c] = ph[8];
        pred[c] = ph[9];
        int coef_nonzero = 0;
        for (int k = 0; k < QZ_NCOEF; k++) {
            coef[c][k] = (int16_t)proto_ld16(ph + 12 + 2 * k);
            coef_nonzero |= coef[c][k] != 0;
        }
        if (!isfinite(base[c]) || !isfinite(s) || !(s > 0.0f) || nb[c] > 4 || proto_ld16(ph + 10) != 0 ||
            (pred[c] != QZ_PRED_PLANAR && pred[c] != QZ_PRED_LS6) || (pred[c] == QZ_PRED_PLANAR && coef_nonzero)) {
            ocean_seterr(err, errlen, "qz plane %d header invalid (base %g, step %g, bytes %d, predictor %d)", c,
                   (double)base[c], (double)s, nb[c], pred[c]);
            return OCEAN_ECODEC;
        }
        step[c] = s;
        want += (size_t)nb[c] * n;
    }
    uint32_t rawlen = proto_ld32(data + headlen - 4);
    if (rawlen != want) {
        ocean_seterr(err, errlen, "qz residual length %u, header implies %zu", rawlen, want);
        return OCEAN_ECODEC;
    }
    const uint8_t *zsrc = data + headlen;
    size_t zlen = len - headlen;
    size_t fsz = ZSTD_findFrameCompressedSize(zsrc, zlen);
    if (ZSTD_isError(fsz) || fsz != zlen) {
        ocean_seterr(err, errlen, "qz: zstd frame malformed or followed by junk");
        return OCEAN_ECODEC;
    }
    unsigned long long csz = ZSTD_getFrameContentSize(zsrc, zlen);
    if (csz != rawlen) {
        ocean_seterr(err, errlen, "qz: zstd frame content size does not match %u", rawlen);
        return OCEAN_ECODEC;
    }
    uint8_t *raw = malloc(want ? want : 1);
    int64_t *q = malloc(n * sizeof *q);
    ocean_result res = OCEAN_OK;
    if (!raw || !q) {
        res = OCEAN_ENOMEM;
        goto done;
    }
    size_t got = ZSTD_decompress(raw, want, zsrc, zlen);
    if (ZSTD_isError(got) || got != want) {
        ocean_seterr(err, errlen, "qz: zstd: %s", ZSTD_isError(got) ? ZSTD_getErrorName(got) : "short output");
        res = OCEAN_ECODEC;
        goto done;
    }
    size_t off = 0;
    for (int c = 0; c < np; c++) {
        float *dst = planes + (size_t)c * n;
        for (int i = 0; i < h; i++)
            for (int j = 0; j < w; j++) {
                size_t k = (size_t)i * w + j;
                uint32_t zz = 0;
                for (int b = 0; b < nb[c]; b++)
                    zz |= (uint32_t)raw[off + (size_t)b * n + k] << (8 * b);
                int64_t v = qz_predict(q, w, i, j, pred[c], coef[c]) + unzigzag(zz);
                if (v > QZ_Q_LIMIT || v < -QZ_Q_LIMIT) {
                    ocean_seterr(err, errlen, "qz plane %d: level %lld out of range at (%d,%d)", c, (long long)v, i, j);
                    res = OCEAN_ECODEC;
                    goto done;
                }
                q[k] = v;
                float f = (float)((double)base[c] + (double)v * step[c]);
                if (!isfinite(f)) {
                    ocean_seterr(err, errlen, "qz plane %d: non-finite value at (%d,%d)", c, i, j);
                    res = OCEAN_ECODEC;
                    goto done;
                }
                dst[k] = f;
            }
        off += (size_t)nb[c] * n;
    }
done:
    free(raw);
    free(q);
    return res;
}

/* ---- dispatch ------------------------------------------------------------ */

ocean_result proto_tile_encode(proto_codec c, const proto_codec_params *p, int w, int h,
                               unsigned channels, const float *planes, proto_buf *out,
                               double *max_err, char *err, size_t errlen)
{
    return proto_tile_encode_ctx(NULL, c, p, w, h, channels, planes, out, max_err, err, errlen);
}

ocean_result proto_tile_encode_ctx(proto_codec_ctx *ctx, proto_codec c, const proto_codec_params *p,
                                   int w, int h, unsigned channels, const float *planes,
                                   proto_buf *out, double *max_err, char *err, size_t errlen)
{
    int np;
    size_t n;
    ocean_result r = check_args(c, w, h, channels, planes, &np, &n, err, errlen);
    if (r != OCEAN_OK)
        return r;
    if (!out) {
        ocean_seterr(err, errlen, "no output buffer");
        return OCEAN_EINVAL;
    }
    proto_codec_params defp;
    if (!p) {
        proto_codec_params_default(&defp);
        p = &defp;
    }
    size_t total = n * (size_t)np;
    for (size_t i = 0; i < total; i++)
        if (!isfinite(planes[i])) {
            ocean_seterr(err, errlen, "non-finite sample in plane %s at index %zu",
                   proto_tile_plane_name(channels, (int)(i / n)), i % n);
            return OCEAN_EINVAL;
        }
    size_t start = out->len;
    switch (c) {
    case PROTO_CODEC_F32: {
        uint8_t *d;
        if ((r = proto_buf_grow(out, total * 4, &d)) != OCEAN_OK)
            return r;
        for (size_t i = 0; i < total; i++)
            proto_stf32(d + 4 * i, planes[i]);
        if (max_err)
            *max_err = 0.0;
        return OCEAN_OK;
    }
    case PROTO_CODEC_F16:
        return f16_encode(planes, total, out, max_err, err, errlen);
    case PROTO_CODEC_QZ: {
        if (ctx)
            return qz_encode(ctx, p, w, h, np, planes, out, max_err, err, errlen);
        /* Context-free callers pay for a context per call, as before. */
        proto_codec_ctx *tmp;
        if ((r = proto_codec_ctx_create(&tmp)) != OCEAN_OK)
            return r;
        r = qz_encode(tmp, p, w, h, np, planes, out, max_err, err, errlen);
        proto_codec_ctx_destroy(tmp);
        return r;
    }
    default:
        break;
    }
    r = proto_exr_encode(c, p, w, h, channels, planes, out, err, errlen);
    if (r != OCEAN_OK || !max_err)
        return r;
    if (proto_codec_lossless(c)) {
        *max_err = 0.0;
        return OCEAN_OK;
    }
    /* Lossy EXR: decode what we wrote and measure. */
    float *back = malloc(total * sizeof *back);
    if (!back) {
        proto_buf_truncate(out, start);
        return OCEAN_ENOMEM;
    }
    r = proto_exr_decode(w, h, channels, proto_buf_data(out) + start, out->len - start, back, err, errlen);
    if (r == OCEAN_OK)
        *max_err = measure_err(planes, back, total);
    else
        proto_buf_truncate(out, start);
    free(back);
    return r;
}

ocean_result proto_tile_decode(proto_codec c, int w, int h, unsigned channels,
                               const uint8_t *data, size_t len, float *planes,
                               char *err, size_t errlen)
{
    int np;
    size_t n;
    ocean_result r = check_args(c, w, h, channels, planes, &np, &n, err, errlen);
    if (r != OCEAN_OK)
        return r;
    if (!data && len) {
        ocean_seterr(err, errlen, "no payload");
        return OCEAN_EINVAL;
    }
    size_t total = n * (size_t)np;
    switch (c) {
    case PROTO_CODEC_F32:
    case PROTO_CODEC_F16: {
        size_t es = c == PROTO_CODEC_F32 ? 4 : 2;
        if (len != total * es) {
            ocean_seterr(err, errlen, "%s payload is %zu bytes, %dx%d x %d planes needs %zu",
                   proto_codec_name(c), len, w, h, np, total * es);
            return OCEAN_ECODEC;
        }
        for (size_t i = 0; i < total; i++) {
            float f = es == 4 ? proto_ldf32(data + 4 * i) : proto_f32_from_f16(proto_ld16(data + 2 * i));
            if (!isfinite(f)) {
                ocean_seterr(err, errlen, "%s payload holds a non-finite value at sample %zu", proto_codec_name(c), i);
                return OCEAN_ECODEC;
            }
            planes[i] = f;
        }
        return OCEAN_OK;
    }
    case PROTO_CODEC_QZ:
        return qz_decode(w, h, np, data, len, planes, err, errlen);
    default:
        return proto_exr_decode(w, h, channels, data, len, planes, err, errlen);
    }
}
