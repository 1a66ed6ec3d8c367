/*
 * codec.c - the tile codecs of codec.h but OpenEXR's (proto_exr.c): f32,
 * f16 and qz (quantised + least-squares spatial prediction + zstd; format 2
 * written, formats 1 and 2 read), with the octahedral normals and the
 * half-float conversion they store.  Byte layouts are specified in
 * PROTOCOL.md; this file and that document must change together.
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


static const char *const plane_names[PROTO_SLOT_COUNT] = {"H", "DX", "DZ", "NU", "NV", "FOAM", "J", "BI", "BQ"};
/* The channel bit of each plane slot. */
static const unsigned slot_channel[PROTO_SLOT_COUNT] = {
    PROTO_CH_HEIGHT, PROTO_CH_DX, PROTO_CH_DZ, PROTO_CH_NORMAL, PROTO_CH_NORMAL, PROTO_CH_FOAM, PROTO_CH_JACOBIAN,
    PROTO_CH_BREAKING, PROTO_CH_BREAKING};

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
    for (int s = 0; s < PROTO_SLOT_COUNT; s++)
        n += (channels & slot_channel[s]) != 0;
    return n;
}

void proto_tile_plane_offsets(unsigned channels, size_t wh, int off[PROTO_SLOT_COUNT])
{
    int p = 0;
    for (int s = 0; s < PROTO_SLOT_COUNT; s++)
        off[s] = (channels & slot_channel[s]) ? (int)(wh * (size_t)p++) : -1;
}

/* The slot of plane i of a tile with `channels`; -1 out of range. */
static int plane_slot(unsigned channels, int i)
{
    if (proto_tile_planes(channels) == 0 || i < 0)
        return -1;
    int k = 0;
    for (int s = 0; s < PROTO_SLOT_COUNT; s++)
        if (channels & slot_channel[s]) {
            if (k == i)
                return s;
            k++;
        }
    return -1;
}

const char *proto_tile_plane_name(unsigned channels, int i)
{
    int s = plane_slot(channels, i);
    return s < 0 ? NULL : plane_names[s];
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

void proto_normal_oct_slopes(float u, float v, float max_slope, float *sx, float *sz)
{
    double x = u, z = v, y = 1.0 - fabs(x) - fabs(z);
    if (y < 0) {
        double ox = x;
        x = (1.0 - fabs(z)) * (ox >= 0 ? 1 : -1);
        z = (1.0 - fabs(ox)) * (z >= 0 ? 1 : -1);
    }
    double len = sqrt(x * x + y * y + z * z);
    if (!(len > 0) || !(max_slope > 0)) {
        *sx = *sz = 0;
        return;
    }
    if (y < len / max_slope)
        y = len / max_slope;
    *sx = (float)(-x / y);
    *sz = (float)(-z / y);
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

/* ---- qz format 2 ----------------------------------------------------------- */

/* Format 2 (what the encoder writes; PROTOCOL.md "qz"): per-plane error
 * budgets and the LSX predictor.  Layout-1 mip tiles are band-limited at
 * half their grid's Nyquist, so a sample sits a quarter wavelength from its
 * neighbours at the band's top: the planar (Lorenzo) predictor misses
 * there by up to 1.4 x the amplitude, and the least-squares weights of a
 * wider causal stencil do much better.  DX, DZ and the normals are linear
 * functions of the same spectrum as H (Tessendorf 2001, "Simulating Ocean
 * Water": D = sum -i k/|k| h~ e^{ikx}, slope = sum i k h~ e^{ikx}), so the
 * decoded H plane around the sample - not causal, but already decoded -
 * predicts them further: on the default scene's mip tiles their residuals
 * shrink by about a fifth (an experiment while designing format 2; the
 * result is bench_codec's layout-1 table). */
#define QZ2_FORMAT 2
#define QZ2_PLANE_HEAD 12 /* base f32, step f32, nbytes u8, predictor u8, ref u8, reserved u8 */
#define QZ_PRED_LSX 3
#define QZ_NOREF 255
#define QZ_NOWN 8
#define QZ_NREF 9
#define QZ_NTAP (QZ_NOWN + QZ_NREF)
#define QZ2_QMAX (1 << 21) /* encoder levels stay below: keeps the fit's sums exact */

/* (di, dj) of the own causal taps and of the reference plane's taps. */
static const int8_t qz_own[QZ_NOWN][2] = {{0, -1}, {-1, 0}, {-1, -1}, {-1, 1}, {0, -2}, {-2, 0}, {-1, -2}, {-2, -1}};
static const int8_t qz_ref[QZ_NREF][2] = {{0, 0}, {0, -1}, {0, 1}, {-1, 0}, {1, 0}, {0, -2}, {0, 2}, {-2, 0}, {2, 0}};

/* Plane kind: its slot in H DX DZ NU NV FOAM J. */

/* The step of a plane of slot `kind` whose values span `range`, in a tile
 * whose H plane spans h_range (0: no H plane).  Why each budget:
 *   H, J   accuracy x the plane's range (H: PSNR ~ 4.8 - 20 log10 accuracy dB);
 *   DX, DZ positions, so the height's metres: accuracy x max(H range, own
 *          range) (never finer than their own relative budget);
 *   NU, NV the octahedral normal to accuracy/2 per component, whatever the
 *          tile's slope range: <= 2.2 x accuracy rad of normal angle (0.63
 *          deg at 5e-3; test_codec), a small fraction of the slope spread
 *          every viewer adds for the waves shorter than the simulation
 *          (about 8 deg per axis in the default scene), so the shaded glint
 *          cannot tell, while a calm tile's tiny slope range does not buy
 *          precision nobody sees;
 *   FOAM   accuracy x range, but never coarser than an 8-bit level (1/255);
 *   BI, BQ accuracy x max(range, 3/2): the breaking index's own scale is
 *          its threshold 1/2, and a reader ramps the cascades' sum to foam
 *          over 1/2 - a (0.2-0.5), so at 5e-3 (7.5e-3 of index, 2-4 % of
 *          foam at most) the foam is finer than its grain draws it.  Being
 *          high-pass fields they predict poorly: at accuracy x range alone
 *          they took 35 % of a viewer tile's bytes, here 27 % (bench_codec,
 *          "as the browser viewer receives them").
 * A step that would make more than QZ2_QMAX levels (hostile ranges) falls
 * back to the relative one, which makes at most 1 / (2 accuracy). */
static double qz2_step(double acc, int kind, double range, double h_range)
{
    double s;
    switch (kind) {
    case PROTO_SLOT_DX:
    case PROTO_SLOT_DZ:
        s = qz_step(acc, fmax(range, h_range));
        break;
    case PROTO_SLOT_NU:
    case PROTO_SLOT_NV:
        s = (double)(float)acc;
        break;
    case PROTO_SLOT_FOAM:
        s = fmin(qz_step(acc, range), (double)(float)(1.0 / 255.0));
        break;
    case PROTO_SLOT_BI:
    case PROTO_SLOT_BQ:
        s = qz_step(acc, fmax(range, 1.5));
        break;
    default:
        s = qz_step(acc, range);
        break;
    }
    if (!(range / s < (double)QZ2_QMAX))
        s = qz_step(acc, range);
    return s;
}

static inline int qz_clampi(int v, int hi) { return v < 0 ? 0 : v > hi ? hi : v; }

/* The LSX taps of (i, j) (i >= 2, 2 <= j <= w - 2) into x: the own
 * causal neighbours, then (if rq) the reference plane's, with coordinates
 * clamped into the tile. */
static inline void qz2_taps(const int64_t *q, const int64_t *rq, int w, int h, int i, int j, int64_t *x)
{
    const int64_t *row = q + (size_t)i * w;
    for (int t = 0; t < QZ_NOWN; t++)
        x[t] = row[qz_own[t][0] * w + j + qz_own[t][1]];
    if (rq)
        for (int t = 0; t < QZ_NREF; t++)
            x[QZ_NOWN + t] = rq[(size_t)qz_clampi(i + qz_ref[t][0], h - 1) * w + qz_clampi(j + qz_ref[t][1], w - 1)];
}

/* Format 2's prediction of q[i][j]: LSX where i >= 2 and 2 <= j <= w - 2,
 * floor((sum coef x + 2048) / 4096); elsewhere as format 1's planar. */
static inline int64_t qz2_predict(const int64_t *q, const int64_t *rq, int w, int h, int i, int j, int pred,
                                  const int16_t *coef)
{
    if (i == 0)
        return j == 0 ? 0 : q[j - 1];
    const int64_t *row = q + (size_t)i * w, *up = row - w;
    if (j == 0)
        return up[0];
    if (pred == QZ_PRED_LSX && i >= 2 && j >= 2 && j + 1 < w) {
        int64_t x[QZ_NTAP], s = 0;
        int nt = rq ? QZ_NTAP : QZ_NOWN;
        qz2_taps(q, rq, w, h, i, j, x);
        for (int t = 0; t < nt; t++)
            s += coef[t] * x[t];
        return floordiv4096(s + 2048);
    }
    return row[j - 1] + up[j] - up[j - 1];
}

/* sum a[i] b[i] over n unsigned 32-bit pairs, exactly in 64 bits (the
 * caller keeps the sum below 2^64).  SSE2 multiplies two pairs per
 * pmuludq, even and odd lanes apart; integer sums do not depend on the
 * order, so the portable loop (alone with -DQZ_NO_SIMD) gives the same. */
static uint64_t qz_dot_u32(const uint32_t *a, const uint32_t *b, size_t n)
{
    size_t i = 0;
    uint64_t s = 0;
#if defined(__SSE2__) && !defined(QZ_NO_SIMD)
    __m128i acc = _mm_setzero_si128();
    for (; i + 4 <= n; i += 4) {
        __m128i x = _mm_loadu_si128((const __m128i *)(const void *)(a + i));
        __m128i y = _mm_loadu_si128((const __m128i *)(const void *)(b + i));
        acc = _mm_add_epi64(acc, _mm_mul_epu32(x, y));
        acc = _mm_add_epi64(acc, _mm_mul_epu32(_mm_srli_epi64(x, 32), _mm_srli_epi64(y, 32)));
    }
    uint64_t l[2];
    _mm_storeu_si128((__m128i *)(void *)l, acc);
    s = l[0] + l[1];
#endif
    for (; i < n; i++)
        s += (uint64_t)a[i] * b[i];
    return s;
}

/* Samples the fit reads: a ninth of the LSX region (every third row and
 * column, shifted by one on successive rows) in tiles of 1024 samples or
 * more - encoding 23 % faster than with a quincunx quarter, for 1 % more
 * bytes on the viewer's 32 x 32 tiles (bench_codec: 2582 -> 2606 bytes,
 * 0.095 -> 0.073-0.082 ms a tile; a sixteenth saved little more, 0.070 ms, for
 * 2 %); smaller tiles keep the quarter (every other row and column,
 * shifted on alternate rows), which leaves enough samples for 17 taps.
 * The stride depends on the tile's size alone, so every machine fits the
 * same samples. */
static inline int qz2_fit_stride(int w, int h) { return (long)w * h >= 1024 ? 3 : 2; }

#define QZ2_FOR_FIT_SAMPLES(i, j)                                    \
    for (int st_ = qz2_fit_stride(w, h), i = 2; i < h; i += st_)    \
        for (int j = 2 + (i / st_) % st_; j + 1 < w; j += st_)

static size_t qz2_fit_samples(int w, int h)
{
    size_t s = 0;
    QZ2_FOR_FIT_SAMPLES(i, j)
        s++;
    return s;
}

/* Least-squares LSX weights (x 4096, rounded) for plane q with reference
 * rq (NULL: own taps only), fx scratch of (QZ_NTAP + 1) x
 * qz2_fit_samples(w, h) words.  The normal equations are summed exactly in
 * 64-bit unsigned integers (levels are >= 0 and < QZ2_QMAX = 2^21 here, so
 * each product < 2^42 and a 1024 x 1024 tile's sums < 2^60): the weights
 * are the same on every machine, as two replicas need.  The taps are laid
 * out a column per tap so that each entry is one dot product.  Returns 0
 * if the system is singular, a weight exceeds +-7.9 or the tile is too
 * small. */
static int qz2_fit(const int64_t *q, const int64_t *rq, int w, int h, int16_t *coef, uint32_t *fx)
{
    if (w < 4 || h < 3)
        return 0;
    int nt = rq ? QZ_NTAP : QZ_NOWN;
    size_t S = qz2_fit_samples(w, h), k = 0;
    if (S == 0)
        return 0;
    QZ2_FOR_FIT_SAMPLES(i, j) {
        const int64_t *row = q + (size_t)i * w;
        fx[(size_t)QZ_NTAP * S + k] = (uint32_t)row[j];
        for (int t = 0; t < QZ_NOWN; t++)
            fx[(size_t)t * S + k] = (uint32_t)row[qz_own[t][0] * w + j + qz_own[t][1]];
        if (rq && i + 2 < h && j + 2 < w) {
            const int64_t *rr = rq + (size_t)i * w + j;
            for (int t = 0; t < QZ_NREF; t++)
                fx[(size_t)(QZ_NOWN + t) * S + k] = (uint32_t)rr[qz_ref[t][0] * w + qz_ref[t][1]];
        } else if (rq) {
            int64_t xs[QZ_NTAP];
            qz2_taps(q, rq, w, h, i, j, xs);
            for (int t = QZ_NOWN; t < QZ_NTAP; t++)
                fx[(size_t)t * S + k] = (uint32_t)xs[t];
        }
        k++;
    }
    const uint32_t *v = fx + (size_t)QZ_NTAP * S;
    double A[QZ_NTAP][QZ_NTAP], b[QZ_NTAP];
    for (int i = 0; i < nt; i++) {
        b[i] = (double)qz_dot_u32(fx + (size_t)i * S, v, S);
        for (int c = i; c < nt; c++)
            A[i][c] = A[c][i] = (double)qz_dot_u32(fx + (size_t)i * S, fx + (size_t)c * S, S);
    }
    /* Cholesky A = L L^T (A is a Gram matrix: symmetric, positive
     * definite unless the taps are linearly dependent - a flat or ramp
     * tile - which a vanishing pivot reports): a sixth of Gauss-Jordan's
     * work, in a fixed order, so every machine gets the same weights. */
    double L[QZ_NTAP][QZ_NTAP], y[QZ_NTAP], x[QZ_NTAP];
    for (int i = 0; i < nt; i++) {
        for (int j = 0; j <= i; j++) {
            double sum = A[i][j];
            for (int k = 0; k < j; k++)
                sum -= L[i][k] * L[j][k];
            if (i == j) {
                if (!(sum > 1e-12 * A[i][i]) || !(sum > 0.0))
                    return 0;
                L[i][i] = sqrt(sum);
            } else {
                L[i][j] = sum / L[j][j];
            }
        }
    }
    for (int i = 0; i < nt; i++) {
        double sum = b[i];
        for (int k = 0; k < i; k++)
            sum -= L[i][k] * y[k];
        y[i] = sum / L[i][i];
    }
    for (int i = nt - 1; i >= 0; i--) {
        double sum = y[i];
        for (int k = i + 1; k < nt; k++)
            sum -= L[k][i] * x[k];
        x[i] = sum / L[i][i];
    }
    for (int i = 0; i < nt; i++) {
        if (!isfinite(x[i]) || fabs(x[i]) > 7.9)
            return 0;
        coef[i] = (int16_t)lround(x[i] * 4096.0);
    }
    return 1;
}

/* The LSX sum at q[i][j] (pointer p) away from every edge the clamp
 * touches (i + 2 < h, j + 2 < w): fixed offsets, no branches. */
static inline int64_t qz2_sum_fast(const int64_t *p, const int64_t *r, int w, const int16_t *c)
{
    int64_t s = c[0] * p[-1] + c[1] * p[-w] + c[2] * p[-w - 1] + c[3] * p[-w + 1] + c[4] * p[-2] +
                c[5] * p[-2 * w] + c[6] * p[-w - 2] + c[7] * p[-2 * w - 1];
    if (r)
        s += c[8] * r[0] + c[9] * r[-1] + c[10] * r[1] + c[11] * r[-w] + c[12] * r[w] + c[13] * r[-2] +
             c[14] * r[2] + c[15] * r[-2 * w] + c[16] * r[2 * w];
    return s;
}

/* Whether (i, j) may use qz2_sum_fast: inside the LSX region and, with a
 * reference, two samples from the bottom and right edges. */
static inline int qz2_fast(int w, int h, int i, int j, int pred, int ref)
{
    return pred == QZ_PRED_LSX && i >= 2 && j >= 2 && j + 1 < w && (!ref || (i + 2 < h && j + 2 < w));
}

/* sum |r| of q under the planar predictor (format 1's and the edges'). */
static uint64_t qz2_planar_cost(const int64_t *q, int w, int h)
{
    uint64_t cost = 0;
    for (int j = 1; j < w; j++)
        cost += (uint64_t)llabs(q[j] - q[j - 1]);
    for (int i = 1; i < h; i++) {
        const int64_t *row = q + (size_t)i * w, *up = row - w;
        cost += (uint64_t)llabs(row[0] - up[0]);
        for (int j = 1; j < w; j++)
            cost += (uint64_t)llabs(row[j] - row[j - 1] - up[j] + up[j - 1]);
    }
    return cost + (uint64_t)llabs(q[0]);
}

/* One residual: zigzag into z[k], |r| added to cost, max kept in m. */
#define QZ2_PUT(k, pr)                                    \
    do {                                                  \
        int64_t r_ = q[k] - (pr);                         \
        uint32_t z_ = zigzag(r_);                         \
        z[k] = z_;                                        \
        cost += (uint64_t)(r_ < 0 ? -r_ : r_);            \
        m = z_ > m ? z_ : m;                              \
    } while (0)

/* Residuals of q under (pred, rq, coef) into z exactly as the decoder's
 * qz2_predict, with the interior runs (planar, or LSX away from the
 * clamped edges) peeled off so they carry no branches; returns sum |r|
 * (the cost) and the largest zigzag code. */
static uint64_t qz2_residuals(const int64_t *q, const int64_t *rq, int w, int h, int pred, const int16_t *coef,
                              uint32_t *z, uint32_t *zmax)
{
    uint64_t cost = 0;
    uint32_t m = 0;
    for (int i = 0; i < h; i++) {
        size_t o = (size_t)i * w;
        const int64_t *row = q + o;
        if (i == 0 || pred != QZ_PRED_LSX || i < 2) {
            if (i == 0) {
                for (int j = 0; j < w; j++)
                    QZ2_PUT(o + j, j == 0 ? 0 : row[j - 1]);
                continue;
            }
            QZ2_PUT(o, row[-w]);
            for (int j = 1; j < w; j++)
                QZ2_PUT(o + j, row[j - 1] + row[j - w] - row[j - w - 1]);
            continue;
        }
        /* LSX rows: the fast run is 2 <= j < jend */
        int jend = rq ? (i + 2 < h ? w - 2 : 2) : w - 1;
        if (jend < 2)
            jend = 2;
        int j = 0;
        for (; j < 2 && j < w; j++)
            QZ2_PUT(o + j, qz2_predict(q, rq, w, h, i, j, pred, coef));
        for (; j < jend; j++)
            QZ2_PUT(o + j, floordiv4096(qz2_sum_fast(row + j, rq ? rq + o + j : NULL, w, coef) + 2048));
        for (; j < w; j++)
            QZ2_PUT(o + j, qz2_predict(q, rq, w, h, i, j, pred, coef));
    }
    *zmax = m;
    return cost;
}

/* ---- qz encoder ---------------------------------------------------------- */

/* What a worker keeps between tiles: the zstd context (creating one costs
 * about as much as compressing a small tile) and the scratch planes. */
struct proto_codec_ctx {
    ZSTD_CCtx *zc;
    int zc_level;        /* level zc holds; 0: parameters not set yet */
    size_t cap;          /* words z holds */
    size_t qcap;         /* levels q holds */
    int64_t *q;          /* quantised planes, every plane kept (references) */
    uint32_t *z;         /* zigzag residuals of the plane being encoded */
    size_t rawcap;
    uint8_t *raw;        /* byte planes of every plane's residuals */
    size_t fxcap;
    uint32_t *fx;        /* the fit's taps, a column per tap (qz2_fit) */
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
    free(c->raw);
    free(c->fx);
    free(c);
}

/* Grows *p to hold n elements of el bytes (*cap counts them); 0 if out of
 * memory (*p unchanged). */
static int ctx_grow(void **p, size_t *cap, size_t n, size_t el)
{
    if (n <= *cap)
        return 1;
    void *q = realloc(*p, n * el);
    if (!q)
        return 0;
    *p = q;
    *cap = n;
    return 1;
}

/* Scratch for nq levels (q), n residuals (z), rawlen byte-plane bytes and
 * fxlen fit words; grows only. */
static ocean_result ctx_reserve(proto_codec_ctx *c, size_t nq, size_t n, size_t rawlen, size_t fxlen)
{
    if (!ctx_grow((void **)&c->q, &c->qcap, nq, sizeof *c->q) || !ctx_grow((void **)&c->z, &c->cap, n, sizeof *c->z) ||
        !ctx_grow((void **)&c->raw, &c->rawcap, rawlen, 1) || !ctx_grow((void **)&c->fx, &c->fxcap, fxlen, sizeof *c->fx))
        return OCEAN_ENOMEM;
    return OCEAN_OK;
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

/* Writes residual codes z[0..n) as byte planes into dst (the fewest that
 * hold zmax: byte b of every code, then byte b + 1 ...); returns how many. */
static int qz_byte_planes(const uint32_t *z, size_t n, uint32_t zmax, uint8_t *dst)
{
    int nb = zmax == 0 ? 0 : zmax < 0x100u ? 1 : zmax < 0x10000u ? 2 : zmax < 0x1000000u ? 3 : 4;
    for (int b = 0; b < nb; b++, dst += n)
        for (size_t k = 0; k < n; k++)
            dst[k] = (uint8_t)(z[k] >> (8 * b));
    return nb;
}

/* Appends head[0..headlen) and the zstd frame of the context's raw[0..
 * rawlen) to out: a qz payload's tail.  out is unchanged on failure. */
static ocean_result qz_emit(proto_codec_ctx *cx, proto_buf *out, const uint8_t *head, size_t headlen,
                            size_t rawlen, int level, char *err, size_t errlen)
{
    size_t bound = ZSTD_compressBound(rawlen);
    size_t start = out->len;
    uint8_t *dst;
    ocean_result res = proto_buf_grow(out, headlen + bound, &dst);
    if (res != OCEAN_OK)
        return res;
    memcpy(dst, head, headlen);
    size_t zn = qz_zstd(cx, dst + headlen, bound, cx->raw, rawlen, level);
    if (ZSTD_isError(zn)) {
        proto_buf_truncate(out, start);
        ocean_seterr(err, errlen, "zstd: %s", ZSTD_getErrorName(zn));
        /* A failed frame may leave the context mid-stream: start clean. */
        ZSTD_freeCCtx(cx->zc);
        cx->zc = NULL;
        return OCEAN_ECODEC;
    }
    proto_buf_truncate(out, start + headlen + zn);
    return OCEAN_OK;
}

static ocean_result qz_encode(proto_codec_ctx *cx, const proto_codec_params *p, int w, int h, unsigned channels,
                              int np, const float *planes, proto_buf *out, double *max_err, char *err,
                              size_t errlen)
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
    ocean_result res = ctx_reserve(cx, n * PROTO_TILE_MAX_PLANES, n, n * 4 * (size_t)np + 1, (QZ_NTAP + 1) * qz2_fit_samples(w, h) + 1);
    if (res != OCEAN_OK)
        return res;
    uint32_t *z = cx->z;
    uint8_t *raw = cx->raw;
    uint8_t head[QZ_HEAD + (QZ2_PLANE_HEAD + 2 * QZ_NTAP) * PROTO_TILE_MAX_PLANES + 4];
    memset(head, 0, sizeof head);
    head[0] = (uint8_t)np;
    head[1] = QZ2_FORMAT;
    size_t headlen = QZ_HEAD, rawlen = 0;
    double merr = 0.0, h_range = 0.0;
    int h_plane = -1;
    for (int c = 0; c < np; c++) {
        const float *src = planes + (size_t)c * n;
        int64_t *q = cx->q + (size_t)c * n;
        int kind = plane_slot(channels, c);
        float lo = src[0], hi = src[0];
        for (size_t k = 1; k < n; k++) {
            lo = src[k] < lo ? src[k] : lo;
            hi = src[k] > hi ? src[k] : hi;
        }
        double range = (double)hi - (double)lo;
        double step = (double)(float)qz2_step(acc, kind, range, h_range);
        if (kind == PROTO_SLOT_H) {
            h_plane = c;
            h_range = range;
        }
        /* range / step < 2^21 (qz2_step), so int64 and the fit's sums hold q. */
        int64_t qmax = (int64_t)llround(range / step);
        for (size_t k = 0; k < n; k++) {
            /* t >= 0 (src >= lo): llround(t) without a libm call */
            double t = ((double)src[k] - (double)lo) / step;
            int64_t v = (int64_t)t;
            v += t - (double)v >= 0.5;
            v = v > qmax ? qmax : v;
            q[k] = v;
            double d = fabs((double)(float)((double)lo + (double)v * step) - (double)src[k]);
            merr = d > merr ? d : merr;
        }
        /* H predicts the planes made from the same spectrum */
        const int64_t *rq = (h_plane >= 0 && kind >= 1 && kind <= 4) ? cx->q + (size_t)h_plane * n : NULL;
        int16_t coef[QZ_NTAP] = {0};
        uint32_t zmax;
        int pred = QZ_PRED_PLANAR, nt = 0;
        /* LSX when its fit exists and beats planar on sum |r| (planar's
         * residuals are only written when they are kept) */
        int ok = 0;
        const int64_t *r2 = rq;
        int16_t cf[QZ_NTAP] = {0};
        if (qmax > 0) {
            ok = qz2_fit(q, r2, w, h, cf, cx->fx);
            if (!ok && r2) {
                r2 = NULL;
                ok = qz2_fit(q, NULL, w, h, cf, cx->fx);
            }
        }
        if (ok && qz2_residuals(q, r2, w, h, QZ_PRED_LSX, cf, z, &zmax) < qz2_planar_cost(q, w, h)) {
            pred = QZ_PRED_LSX;
            rq = r2;
            nt = r2 ? QZ_NTAP : QZ_NOWN;
            memcpy(coef, cf, sizeof coef);
        } else {
            qz2_residuals(q, NULL, w, h, QZ_PRED_PLANAR, coef, z, &zmax);
        }
        int nb = qz_byte_planes(z, n, zmax, raw + rawlen);
        rawlen += (size_t)nb * n;
        uint8_t *ph = head + headlen;
        proto_stf32(ph, lo);
        proto_stf32(ph + 4, (float)step);
        ph[8] = (uint8_t)nb;
        ph[9] = (uint8_t)pred;
        ph[10] = (uint8_t)(pred == QZ_PRED_LSX && rq ? h_plane : QZ_NOREF);
        ph[11] = 0;
        for (int k = 0; k < nt; k++)
            proto_st16(ph + QZ2_PLANE_HEAD + 2 * k, (uint16_t)coef[k]);
        headlen += QZ2_PLANE_HEAD + 2 * (size_t)nt;
    }
    proto_st32(head + headlen, (uint32_t)rawlen);
    headlen += 4;
    res = qz_emit(cx, out, head, headlen, rawlen, level, err, errlen);
    if (res == OCEAN_OK && max_err)
        *max_err = merr;
    return res;
}

double proto_codec_plane_error_bound(proto_codec c, const proto_codec_params *p, unsigned channels, int plane,
                                     double lo, double hi, double h_range)
{
    if (c != PROTO_CODEC_QZ)
        return proto_codec_error_bound(c, p, lo, hi);
    int kind = plane_slot(channels, plane);
    if (kind < 0)
        return INFINITY;
    double acc = p ? p->accuracy : PROTO_ACCURACY_DEFAULT;
    double amax = fmax(fabs(lo), fabs(hi)), range = hi - lo;
    double step = (double)(float)qz2_step(acc, kind, range, h_range);
    return step * 0.5 + amax * 0x1p-24 + (range > 0 ? range * 0x1p-40 : 0.0);
}

/* The residual stream of a qz payload: zsrc/zlen must be exactly one zstd
 * frame (with content size) of `want` bytes; *raw gets them (malloc'd,
 * the caller frees).  ECODEC for anything else. */
static ocean_result qz_inflate(const uint8_t *zsrc, size_t zlen, size_t want, uint8_t **raw, char *err,
                               size_t errlen)
{
    *raw = NULL;
    size_t fsz = ZSTD_findFrameCompressedSize(zsrc, zlen);
    if (ZSTD_isError(fsz) || fsz != zlen) {
        ocean_seterr(err, errlen, "qz: zstd frame malformed or followed by junk");
        return OCEAN_ECODEC;
    }
    unsigned long long csz = ZSTD_getFrameContentSize(zsrc, zlen);
    if (csz != want) {
        ocean_seterr(err, errlen, "qz: zstd frame content size does not match %zu", want);
        return OCEAN_ECODEC;
    }
    uint8_t *r = malloc(want ? want : 1);
    if (!r)
        return OCEAN_ENOMEM;
    size_t got = ZSTD_decompress(r, want, zsrc, zlen);
    if (ZSTD_isError(got) || got != want) {
        ocean_seterr(err, errlen, "qz: zstd: %s", ZSTD_isError(got) ? ZSTD_getErrorName(got) : "short output");
        free(r);
        return OCEAN_ECODEC;
    }
    *raw = r;
    return OCEAN_OK;
}

/* The residual of sample k from its nb byte planes of n bytes each
 * (PROTOCOL.md "qz": byte b of every residual, then byte b + 1), zigzag
 * decoded. */
static inline int64_t qz_residual(const uint8_t *raw, size_t n, size_t k, int nb)
{
    uint32_t zz = 0;
    for (int b = 0; b < nb; b++)
        zz |= (uint32_t)raw[(size_t)b * n + k] << (8 * b);
    return unzigzag(zz);
}

/* Keeps decoded level v in *q and its value base + v step in *dst, or
 * refuses it (OCEAN_ECODEC naming plane c and sample (i, j)): a level
 * beyond QZ_Q_LIMIT, or a value that is not finite, is a corrupt payload. */
static inline ocean_result qz_store(int64_t v, float base, double step, int64_t *q, float *dst, int c,
                                    int i, int j, char *err, size_t errlen)
{
    if (v > QZ_Q_LIMIT || v < -QZ_Q_LIMIT) {
        ocean_seterr(err, errlen, "qz plane %d: level %lld out of range at (%d,%d)", c, (long long)v, i, j);
        return OCEAN_ECODEC;
    }
    *q = v;
    float f = (float)((double)base + (double)v * step);
    if (!isfinite(f)) {
        ocean_seterr(err, errlen, "qz plane %d: non-finite value at (%d,%d)", c, i, j);
        return OCEAN_ECODEC;
    }
    *dst = f;
    return OCEAN_OK;
}

/* Format 1 (decoded for payloads recorded before format 2). */
static ocean_result qz1_decode(int w, int h, int np, const uint8_t *data, size_t len, float *planes,
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
    uint8_t *raw = NULL;
    ocean_result res = qz_inflate(data + headlen, len - headlen, want, &raw, err, errlen);
    if (res != OCEAN_OK)
        return res;
    int64_t *q = malloc(n * sizeof *q);
    if (!q) {
        res = OCEAN_ENOMEM;
        goto done;
    }
    size_t off = 0;
    for (int c = 0; c < np; c++) {
        float *dst = planes + (size_t)c * n;
        for (int i = 0; i < h; i++)
            for (int j = 0; j < w; j++) {
                size_t k = (size_t)i * w + j;
                int64_t v = qz_predict(q, w, i, j, pred[c], coef[c]) + qz_residual(raw + off, n, k, nb[c]);
                res = qz_store(v, base[c], step[c], q + k, dst + k, c, i, j, err, errlen);
                if (res != OCEAN_OK)
                    goto done;
            }
        off += (size_t)nb[c] * n;
    }
done:
    free(raw);
    free(q);
    return res;
}

/* Format 2 (PROTOCOL.md "qz"): variable-length plane headers, LSX with an
 * optional reference plane decoded before. */
static ocean_result qz2_decode(int w, int h, int np, const uint8_t *data, size_t len, float *planes,
                               char *err, size_t errlen)
{
    if (len < QZ_HEAD + 4) {
        ocean_seterr(err, errlen, "qz payload of %zu bytes shorter than its header", len);
        return OCEAN_ECODEC;
    }
    if (data[0] != np) {
        ocean_seterr(err, errlen, "qz header says %u planes, tile has %d", data[0], np);
        return OCEAN_ECODEC;
    }
    if (proto_ld16(data + 2) != 0) {
        ocean_seterr(err, errlen, "qz format 2 reserved %u not 0", proto_ld16(data + 2));
        return OCEAN_ECODEC;
    }
    size_t n = (size_t)w * h, want = 0, off = QZ_HEAD;
    float base[PROTO_TILE_MAX_PLANES];
    double step[PROTO_TILE_MAX_PLANES];
    int nb[PROTO_TILE_MAX_PLANES], pred[PROTO_TILE_MAX_PLANES], ref[PROTO_TILE_MAX_PLANES];
    int16_t coef[PROTO_TILE_MAX_PLANES][QZ_NTAP];
    for (int c = 0; c < np; c++) {
        if (len - off < QZ2_PLANE_HEAD + 4) {
            ocean_seterr(err, errlen, "qz payload of %zu bytes ends inside plane %d's header", len, c);
            return OCEAN_ECODEC;
        }
        const uint8_t *ph = data + off;
        base[c] = proto_ldf32(ph);
        float s = proto_ldf32(ph + 4);
        nb[c] = ph[8];
        pred[c] = ph[9];
        ref[c] = ph[10];
        int nt = pred[c] == QZ_PRED_LSX ? (ref[c] == QZ_NOREF ? QZ_NOWN : QZ_NTAP) : 0;
        if (!isfinite(base[c]) || !isfinite(s) || !(s > 0.0f) || nb[c] > 4 || ph[11] != 0 ||
            (pred[c] != QZ_PRED_PLANAR && pred[c] != QZ_PRED_LSX) ||
            (pred[c] == QZ_PRED_PLANAR && ref[c] != QZ_NOREF) || (ref[c] != QZ_NOREF && ref[c] >= c)) {
            ocean_seterr(err, errlen, "qz plane %d header invalid (base %g, step %g, bytes %d, predictor %d, ref %d)", c,
                         (double)base[c], (double)s, nb[c], pred[c], ref[c]);
            return OCEAN_ECODEC;
        }
        if (len - off - QZ2_PLANE_HEAD < 2 * (size_t)nt + 4) {
            ocean_seterr(err, errlen, "qz payload of %zu bytes ends inside plane %d's weights", len, c);
            return OCEAN_ECODEC;
        }
        for (int k = 0; k < nt; k++)
            coef[c][k] = (int16_t)proto_ld16(ph + QZ2_PLANE_HEAD + 2 * k);
        off += QZ2_PLANE_HEAD + 2 * (size_t)nt;
        step[c] = s;
        want += (size_t)nb[c] * n;
    }
    uint32_t rawlen = proto_ld32(data + off);
    off += 4;
    if (rawlen != want) {
        ocean_seterr(err, errlen, "qz residual length %u, header implies %zu", rawlen, want);
        return OCEAN_ECODEC;
    }
    uint8_t *raw = NULL;
    ocean_result res = qz_inflate(data + off, len - off, want, &raw, err, errlen);
    if (res != OCEAN_OK)
        return res;
    int64_t *qall = malloc(n * (size_t)np * sizeof *qall);
    if (!qall) {
        res = OCEAN_ENOMEM;
        goto done;
    }
    size_t ro = 0;
    for (int c = 0; c < np; c++) {
        float *dst = planes + (size_t)c * n;
        int64_t *q = qall + (size_t)c * n;
        const int64_t *rq = ref[c] != QZ_NOREF ? qall + (size_t)ref[c] * n : NULL;
        for (int i = 0; i < h; i++)
            for (int j = 0; j < w; j++) {
                size_t k = (size_t)i * w + j;
                int64_t pr = qz2_fast(w, h, i, j, pred[c], rq != NULL)
                                 ? floordiv4096(qz2_sum_fast(q + k, rq ? rq + k : NULL, w, coef[c]) + 2048)
                                 : qz2_predict(q, rq, w, h, i, j, pred[c], coef[c]);
                int64_t v = pr + qz_residual(raw + ro, n, k, nb[c]);
                res = qz_store(v, base[c], step[c], q + k, dst + k, c, i, j, err, errlen);
                if (res != OCEAN_OK)
                    goto done;
            }
        ro += (size_t)nb[c] * n;
    }
done:
    free(raw);
    free(qall);
    return res;
}

static ocean_result qz_decode(int w, int h, int np, const uint8_t *data, size_t len, float *planes,
                              char *err, size_t errlen)
{
    if (len >= 2 && data[1] == QZ2_FORMAT)
        return qz2_decode(w, h, np, data, len, planes, err, errlen);
    return qz1_decode(w, h, np, data, len, planes, err, errlen);
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
            return qz_encode(ctx, p, w, h, channels, np, planes, out, max_err, err, errlen);
        /* Context-free callers pay for a context per call, as before. */
        proto_codec_ctx *tmp;
        if ((r = proto_codec_ctx_create(&tmp)) != OCEAN_OK)
            return r;
        r = qz_encode(tmp, p, w, h, channels, np, planes, out, max_err, err, errlen);
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

/* ---- qz mesh positions (PROTOCOL.md "MESH_VERTICES_QZ") --------------- */

/* A layout-0 mesh is a flat LOD lattice plus a smooth displacement, and its
 * triangles say which vertices are neighbours: the parallelogram rule
 * (Touma & Gotsman 1998, "Triangle Mesh Compression") predicts a vertex
 * from a decoded triangle across an edge it shares with it, which removes
 * the lattice wherever the mesh is locally a grid and leaves the
 * displacement's local change.  On the default scene's frames it made
 * residuals a quarter smaller than delta coding along the vertex order
 * (bench_codec's mesh table; the vertex order of the concentric builder
 * jumps hundreds of metres between consecutive vertices). */
#define MQZ_PRED_PARALLELOGRAM 1
/* zstd level of the residual stream: its bytes are nearly i.i.d., so the
 * entropy stage does the work; level 1 costs 0.3 % more bytes than 3 on
 * the default scene's meshes and encodes 13 % faster (bench_meshqz; the
 * negative levels skip Huffman literals: 1/3.6 instead of 1/4.9 of f32). */
#define MQZ_ZSTD_LEVEL 1

ocean_result proto_mesh_qz_refs(const uint32_t *indices, uint32_t index_count, uint32_t vertex_count,
                                uint32_t *refs)
{
    if (!refs || (index_count && !indices) || index_count % 3 || vertex_count == 0)
        return OCEAN_EINVAL;
    for (uint32_t i = 0; i < index_count; i++)
        if (indices[i] >= vertex_count)
            return OCEAN_EINVAL;
    /* triangles of each vertex, in index-buffer order (counting sort) */
    uint32_t *start = calloc((size_t)vertex_count + 1, sizeof *start);
    uint32_t *fill = malloc(((size_t)vertex_count + 1) * sizeof *fill);
    uint32_t *tri = malloc((size_t)(index_count ? index_count : 1) * sizeof *tri);
    if (!start || !fill || !tri) {
        free(start);
        free(fill);
        free(tri);
        return OCEAN_ENOMEM;
    }
    for (uint32_t i = 0; i < index_count; i++)
        start[indices[i] + 1]++;
    for (uint32_t v = 0; v < vertex_count; v++)
        start[v + 1] += start[v];
    memcpy(fill, start, ((size_t)vertex_count + 1) * sizeof *fill);
    for (uint32_t i = 0; i < index_count; i++)
        tri[fill[indices[i]]++] = i / 3;
    for (uint32_t v = 0; v < vertex_count; v++) {
        uint32_t *r = refs + 3 * (size_t)v;
        r[0] = r[1] = r[2] = PROTO_MESH_QZ_NONE;
        for (uint32_t k = start[v]; k < start[v + 1] && r[2] == PROTO_MESH_QZ_NONE; k++) {
            const uint32_t *t = indices + 3 * (size_t)tri[k];
            uint32_t a, b;
            if (t[0] == v) a = t[1], b = t[2];
            else if (t[1] == v) a = t[2], b = t[0];
            else a = t[0], b = t[1];
            if (a >= v || b >= v || a == b)
                continue;   /* not both decoded (or degenerate) */
            if (r[0] == PROTO_MESH_QZ_NONE)
                r[0] = a, r[1] = b;
            /* the first other triangle on edge (a, b) whose third vertex is decoded */
            for (uint32_t m = start[a]; m < start[a + 1]; m++) {
                if (tri[m] == tri[k])
                    continue;
                const uint32_t *u = indices + 3 * (size_t)tri[m];
                int has_b = u[0] == b || u[1] == b || u[2] == b;
                uint32_t c = u[0] != a && u[0] != b ? u[0] : u[1] != a && u[1] != b ? u[1] : u[2];
                if (has_b && c != a && c != b && c < v) {
                    r[0] = a, r[1] = b, r[2] = c;
                    break;
                }
            }
        }
    }
    free(start);
    free(fill);
    free(tri);
    return OCEAN_OK;
}

/* The prediction of q[v] (one axis, stride 3) from decoded vertices. */
static inline int64_t mqz_predict(const int64_t *q, const uint32_t *refs, uint32_t v)
{
    const uint32_t *r = refs + 3 * (size_t)v;
    if (r[2] != PROTO_MESH_QZ_NONE)
        return q[3 * (size_t)r[0]] + q[3 * (size_t)r[1]] - q[3 * (size_t)r[2]];
    if (r[0] != PROTO_MESH_QZ_NONE) {
        int64_t s = q[3 * (size_t)r[0]] + q[3 * (size_t)r[1]];
        return s >= 0 ? s / 2 : -((-s + 1) / 2);   /* floor */
    }
    return v ? q[3 * ((size_t)v - 1)] : 0;
}

/* The step of one axis whose values span `range`, from the subscription's
 * y step s (PROTOCOL.md "MESH_VERTICES_QZ"): s itself unless the axis would
 * need 2^29 levels or more, then the f32 at or above range / 2^29. */
static double mqz_step(double s, double range)
{
    double st = s;
    if (range / st >= 0x1p29) {
        float f = (float)(range * 0x1p-29);
        if ((double)f < range * 0x1p-29)
            f = nextafterf(f, INFINITY);
        st = (double)f;
    }
    return st < FLT_MIN ? FLT_MIN : st;
}

ocean_result proto_mesh_qz_steps(double accuracy, uint32_t vertex_count, const float *xyz, float base[3],
                                 float step[3])
{
    if (!xyz || vertex_count == 0 || !(accuracy >= (double)(float)PROTO_ACCURACY_MIN && accuracy <= PROTO_ACCURACY_MAX))
        return OCEAN_EINVAL;
    float lo[3], hi[3];
    for (int a = 0; a < 3; a++)
        lo[a] = hi[a] = xyz[a];
    for (size_t i = 0; i < vertex_count; i++)
        for (int a = 0; a < 3; a++) {
            float v = xyz[3 * i + a];
            if (!isfinite(v))
                return OCEAN_EINVAL;
            lo[a] = v < lo[a] ? v : lo[a];
            hi[a] = v > hi[a] ? v : hi[a];
        }
    double ry = (double)hi[1] - (double)lo[1];
    /* the tiles' height budget (qz H: a x range); x and z in the same
     * metres, as qz's DX and DZ planes; a sea without relief keeps 1 m */
    double s = qz_step(accuracy, ry > 0 ? ry : 1.0);
    for (int a = 0; a < 3; a++) {
        base[a] = lo[a];
        step[a] = (float)mqz_step(s, (double)hi[a] - (double)lo[a]);
    }
    return OCEAN_OK;
}

double proto_mesh_qz_error_bound(const float base[3], const float step[3], uint32_t vertex_count, const float *xyz,
                                 int axis)
{
    (void)base;
    double amax = 0;
    for (size_t i = 0; i < vertex_count; i++)
        amax = fmax(amax, fabs((double)xyz[3 * i + axis]));
    return 0.5 * (double)step[axis] + amax * 0x1p-24;
}

ocean_result proto_mesh_qz_encode(proto_codec_ctx *cx, double accuracy, uint32_t vertex_count, const float *xyz,
                                  const uint32_t *refs, proto_buf *out, double max_err[3], char *err,
                                  size_t errlen)
{
    if (!cx || !refs || !out) {
        ocean_seterr(err, errlen, "mesh qz: NULL argument");
        return OCEAN_EINVAL;
    }
    float base[3], step[3];
    if (proto_mesh_qz_steps(accuracy, vertex_count, xyz, base, step) != OCEAN_OK) {
        ocean_seterr(err, errlen, "mesh qz: accuracy %g outside %g..%g, no vertices or a non-finite position",
                     accuracy, PROTO_ACCURACY_MIN, PROTO_ACCURACY_MAX);
        return OCEAN_EINVAL;
    }
    size_t n = vertex_count;
    ocean_result res = ctx_reserve(cx, 3 * n, n, 12 * n + 1, 0);
    if (res != OCEAN_OK)
        return res;
    int64_t *q = cx->q;
    double merr[3] = {0, 0, 0};
    for (size_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++) {
            double t = ((double)xyz[3 * i + a] - (double)base[a]) / (double)step[a];
            int64_t v = (int64_t)t;   /* t >= 0 */
            v += t - (double)v >= 0.5;
            q[3 * i + a] = v;
            double d = fabs((double)(float)((double)base[a] + (double)v * step[a]) - (double)xyz[3 * i + a]);
            merr[a] = d > merr[a] ? d : merr[a];
        }
    uint8_t head[PROTO_MESH_QZ_HEAD];
    memset(head, 0, sizeof head);
    head[0] = PROTO_MESH_QZ_FORMAT;
    head[1] = MQZ_PRED_PARALLELOGRAM;
    size_t rawlen = 0;
    for (int a = 0; a < 3; a++) {
        uint32_t zmax = 0, *z = cx->z;
        for (uint32_t v = 0; v < vertex_count; v++) {
            z[v] = zigzag(q[3 * (size_t)v + a] - mqz_predict(q + a, refs, v));
            zmax = z[v] > zmax ? z[v] : zmax;
        }
        int nb = qz_byte_planes(z, n, zmax, cx->raw + rawlen);
        rawlen += (size_t)nb * n;
        proto_stf32(head + 4 + 4 * a, base[a]);
        proto_stf32(head + 16 + 4 * a, step[a]);
        head[28 + a] = (uint8_t)nb;
    }
    proto_st32(head + 32, (uint32_t)rawlen);
    res = qz_emit(cx, out, head, sizeof head, rawlen, MQZ_ZSTD_LEVEL, err, errlen);
    if (res == OCEAN_OK && max_err)
        memcpy(max_err, merr, sizeof merr);
    return res;
}

ocean_result proto_mesh_qz_header(const uint8_t *data, size_t len, uint32_t vertex_count, proto_mesh_qz_info *info,
                                  char *err, size_t errlen)
{
    if (!data || len < PROTO_MESH_QZ_HEAD) {
        ocean_seterr(err, errlen, "mesh qz payload of %zu bytes shorter than its %d-byte header", len,
                     PROTO_MESH_QZ_HEAD);
        return OCEAN_ECODEC;
    }
    if (data[0] != PROTO_MESH_QZ_FORMAT || data[1] != MQZ_PRED_PARALLELOGRAM) {
        ocean_seterr(err, errlen, "mesh qz format %u / predictor %u not supported (format 1, predictor 1)", data[0],
                     data[1]);
        return OCEAN_ECODEC;
    }
    if (proto_ld16(data + 2) != 0 || data[31] != 0) {
        ocean_seterr(err, errlen, "mesh qz reserved bytes not 0");
        return OCEAN_ECODEC;
    }
    proto_mesh_qz_info in;
    in.format = data[0];
    in.predictor = data[1];
    uint64_t want = 0;
    for (int a = 0; a < 3; a++) {
        in.base[a] = proto_ldf32(data + 4 + 4 * a);
        in.step[a] = proto_ldf32(data + 16 + 4 * a);
        in.nbytes[a] = data[28 + a];
        if (!isfinite(in.base[a]) || !isfinite(in.step[a]) || !(in.step[a] > 0.0f) || in.nbytes[a] > 4) {
            ocean_seterr(err, errlen, "mesh qz axis %c header invalid (base %g, step %g, bytes %u)", "xyz"[a],
                         (double)in.base[a], (double)in.step[a], in.nbytes[a]);
            return OCEAN_ECODEC;
        }
        want += (uint64_t)in.nbytes[a] * vertex_count;
    }
    in.raw_len = proto_ld32(data + 32);
    if (in.raw_len != want) {
        ocean_seterr(err, errlen, "mesh qz residual length %u, header and %u vertices imply %llu", in.raw_len,
                     vertex_count, (unsigned long long)want);
        return OCEAN_ECODEC;
    }
    unsigned long long csz = ZSTD_getFrameContentSize(data + PROTO_MESH_QZ_HEAD, len - PROTO_MESH_QZ_HEAD);
    size_t fsz = ZSTD_findFrameCompressedSize(data + PROTO_MESH_QZ_HEAD, len - PROTO_MESH_QZ_HEAD);
    if (ZSTD_isError(fsz) || fsz != len - PROTO_MESH_QZ_HEAD || csz != want) {
        ocean_seterr(err, errlen, "mesh qz: zstd frame malformed, followed by junk or not of %llu bytes",
                     (unsigned long long)want);
        return OCEAN_ECODEC;
    }
    if (info)
        *info = in;
    return OCEAN_OK;
}

ocean_result proto_mesh_qz_decode(const uint8_t *data, size_t len, uint32_t vertex_count, const uint32_t *refs,
                                  float *xyz, char *err, size_t errlen)
{
    if (!refs || !xyz || vertex_count == 0) {
        ocean_seterr(err, errlen, "mesh qz: no topology references or output");
        return OCEAN_EINVAL;
    }
    proto_mesh_qz_info in;
    ocean_result res = proto_mesh_qz_header(data, len, vertex_count, &in, err, errlen);
    if (res != OCEAN_OK)
        return res;
    uint8_t *raw = NULL;
    res = qz_inflate(data + PROTO_MESH_QZ_HEAD, len - PROTO_MESH_QZ_HEAD, in.raw_len, &raw, err, errlen);
    if (res != OCEAN_OK)
        return res;
    size_t n = vertex_count, ro = 0;
    int64_t *q = malloc(3 * n * sizeof *q);
    if (!q) {
        free(raw);
        return OCEAN_ENOMEM;
    }
    for (int a = 0; a < 3 && res == OCEAN_OK; a++) {
        for (uint32_t v = 0; v < vertex_count; v++) {
            const uint32_t *r = refs + 3 * (size_t)v;
            /* references come from a checked topology; still, only decoded ones */
            if ((r[0] != PROTO_MESH_QZ_NONE && (r[0] >= v || r[1] >= v)) ||
                (r[2] != PROTO_MESH_QZ_NONE && (r[2] >= v || r[0] == PROTO_MESH_QZ_NONE))) {
                ocean_seterr(err, errlen, "mesh qz: vertex %u refers to a vertex not yet decoded", v);
                res = OCEAN_EINVAL;
                break;
            }
            uint32_t zz = 0;
            for (int b = 0; b < in.nbytes[a]; b++)
                zz |= (uint32_t)raw[ro + (size_t)b * n + v] << (8 * b);
            int64_t lv = mqz_predict(q + a, refs, v) + unzigzag(zz);
            if (lv > QZ_Q_LIMIT || lv < -QZ_Q_LIMIT) {
                ocean_seterr(err, errlen, "mesh qz axis %c: level %lld out of range at vertex %u", "xyz"[a],
                             (long long)lv, v);
                res = OCEAN_ECODEC;
                break;
            }
            q[3 * (size_t)v + a] = lv;
            float f = (float)((double)in.base[a] + (double)lv * (double)in.step[a]);
            if (!isfinite(f) || fabsf(f) > 1e7f) {
                ocean_seterr(err, errlen, "mesh qz axis %c: position %g at vertex %u (finite, |.| <= 1e7)", "xyz"[a],
                             (double)f, v);
                res = OCEAN_ECODEC;
                break;
            }
            xyz[3 * (size_t)v + a] = f;
        }
        ro += (size_t)in.nbytes[a] * n;
    }
    free(raw);
    free(q);
    return res;
}

/* ---- planes of any size ------------------------------------------------ */

/* Block (bi, bj)'s origin and size in a plane of w x h. */
static void plane_block(int w, int h, int bi, int bj, int *x0, int *z0, int *bw, int *bh)
{
    *x0 = bi * PROTO_TILE_MAX_SIZE;
    *z0 = bj * PROTO_TILE_MAX_SIZE;
    *bw = w - *x0 < PROTO_TILE_MAX_SIZE ? w - *x0 : PROTO_TILE_MAX_SIZE;
    *bh = h - *z0 < PROTO_TILE_MAX_SIZE ? h - *z0 : PROTO_TILE_MAX_SIZE;
}

ocean_result proto_plane_encode(proto_codec_ctx *ctx, proto_codec c, const proto_codec_params *p, int w, int h,
                                const float *plane, proto_buf *out, double *max_err, char *err, size_t errlen)
{
    if (w < 1 || h < 1 || w > PROTO_PLANE_MAX_SIZE || h > PROTO_PLANE_MAX_SIZE || !plane) {
        ocean_seterr(err, errlen, "plane %dx%d outside 1..%d", w, h, PROTO_PLANE_MAX_SIZE);
        return OCEAN_EINVAL;
    }
    float *blk = malloc(sizeof *blk * PROTO_TILE_MAX_SIZE * PROTO_TILE_MAX_SIZE);
    if (!blk) return OCEAN_ENOMEM;
    size_t start = out->len;
    double worst = 0;
    ocean_result r = OCEAN_OK;
    int nbx = (w + PROTO_TILE_MAX_SIZE - 1) / PROTO_TILE_MAX_SIZE, nbz = (h + PROTO_TILE_MAX_SIZE - 1) / PROTO_TILE_MAX_SIZE;
    for (int bj = 0; bj < nbz && r == OCEAN_OK; bj++)
        for (int bi = 0; bi < nbx && r == OCEAN_OK; bi++) {
            int x0, z0, bw, bh;
            plane_block(w, h, bi, bj, &x0, &z0, &bw, &bh);
            for (int j = 0; j < bh; j++) memcpy(blk + (size_t)j * bw, plane + (size_t)(z0 + j) * w + x0, sizeof *blk * bw);
            uint8_t *len_at;
            r = proto_buf_grow(out, 4, &len_at);
            size_t before = out->len;
            double e = 0;
            if (r == OCEAN_OK) r = proto_tile_encode_ctx(ctx, c, p, bw, bh, PROTO_CH_HEIGHT, blk, out, &e, err, errlen);
            if (r == OCEAN_OK) proto_st32(proto_buf_data(out) + before - 4, (uint32_t)(out->len - before));
            worst = e > worst ? e : worst;
        }
    free(blk);
    if (r != OCEAN_OK) out->len = start;
    else if (max_err) *max_err = worst;
    return r;
}

ocean_result proto_plane_decode(proto_codec c, int w, int h, const uint8_t *data, size_t len, float *plane,
                                char *err, size_t errlen)
{
    if (w < 1 || h < 1 || w > PROTO_PLANE_MAX_SIZE || h > PROTO_PLANE_MAX_SIZE || !plane || (!data && len)) {
        ocean_seterr(err, errlen, "plane %dx%d outside 1..%d", w, h, PROTO_PLANE_MAX_SIZE);
        return OCEAN_EINVAL;
    }
    float *blk = malloc(sizeof *blk * PROTO_TILE_MAX_SIZE * PROTO_TILE_MAX_SIZE);
    if (!blk) return OCEAN_ENOMEM;
    size_t at = 0;
    ocean_result r = OCEAN_OK;
    int nbx = (w + PROTO_TILE_MAX_SIZE - 1) / PROTO_TILE_MAX_SIZE, nbz = (h + PROTO_TILE_MAX_SIZE - 1) / PROTO_TILE_MAX_SIZE;
    for (int bj = 0; bj < nbz && r == OCEAN_OK; bj++)
        for (int bi = 0; bi < nbx && r == OCEAN_OK; bi++) {
            int x0, z0, bw, bh;
            plane_block(w, h, bi, bj, &x0, &z0, &bw, &bh);
            uint32_t n = len - at >= 4 ? proto_ld32(data + at) : 0;
            if (len - at < 4 || n > len - at - 4) {
                ocean_seterr(err, errlen, "plane block (%d, %d): %zu bytes left, its count says %u", bi, bj,
                             len - at, n);
                r = OCEAN_ECODEC;
                break;
            }
            r = proto_tile_decode(c, bw, bh, PROTO_CH_HEIGHT, data + at + 4, n, blk, err, errlen);
            for (int j = 0; r == OCEAN_OK && j < bh; j++)
                memcpy(plane + (size_t)(z0 + j) * w + x0, blk + (size_t)j * bw, sizeof *blk * bw);
            at += 4 + (size_t)n;
        }
    if (r == OCEAN_OK && at != len) {
        ocean_seterr(err, errlen, "plane: %zu bytes after its last block", len - at);
        r = OCEAN_ECODEC;
    }
    free(blk);
    return r;
}
