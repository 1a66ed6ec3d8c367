/*
 * ocean_stage.c - the spectrum stage: one pass over the modes of a
 * cascade that evolves h(k,t) (and dh/dt) into the cascade's cache and
 * writes every asked channel's spectrum for FFTW, row pair by row pair,
 * in loops the compiler vectorises (plain, AVX2+FMA and AVX-512 copies of
 * one source, which give the same bits), split over the evaluation's
 * OpenMP team by rows or by channel, whichever this ocean measured faster.
 * Built with -O3 -fno-math-errno (the Makefile): GCC 12's -O2 cost model
 * leaves the row passes scalar.
 */
#include "ocean.h"
#include "ocean_internal.h"

#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <string.h>
#include <unistd.h>
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#include <immintrin.h>
#endif

#include "ocean_time.h"

void ocean_force_frequency_table(ocean *o, int table)
{
    if (o)
        o->deep_table = table != 0;
}

int ocean_force_paths(ocean *o, int fused, int stream)
{
    if (!o)
        return -1;
    /* The widest pass the CPU runs: 2 needs AVX-512 F, VL, DQ and BW as
     * well as AVX2 and FMA. */
    int can = 0;
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
        can = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
                      __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw")
                  ? 2
                  : 1;
#endif
    o->fused = fused < 0 ? can : fused < can ? fused : can;
    if (stream < 0) {
        /* Stream only what could not stay in the last-level cache at all:
         * a spectrum over twice its size.  Below that the FFT finds the
         * rows written last still cached, which streaming would lose
         * (bench_core, "the spectrum stage's paths": at N = 1024, 34 MB of
         * spectra against a 32 MB cache, streaming cost 10 %). */
        long llc = sysconf(_SC_LEVEL3_CACHE_SIZE);
        if (llc <= 0)
            llc = sysconf(_SC_LEVEL2_CACHE_SIZE);
        o->stream_bytes = llc > 0 ? 2.0 * llc : 64e6;
    } else {
        o->stream_bytes = stream ? 0.0 : INFINITY;
    }
    return o->fused;
}

/* sin and cos of a phase x already reduced to [-pi, pi] (exactly, in
 * double: ocean_phase_turns), branch-free so the row loop vectorises: a
 * reflection onto [-pi/2, pi/2] in float, then Taylor polynomials of
 * degree 11 and 12, whose truncation error there (6e-8, 6e-9) is below
 * float's rounding.  Rounding x to float costs at most 1.2e-7 rad, the
 * same at every t. */
#define PI_F 3.14159265358979f
#define PIO2_F 1.57079632679490f

static inline void phase_sincos(double x, float *s_out, float *c_out)
{
    float r = (float)x;
    /* sin(pi - |r|) = sin |r|, cos(pi - |r|) = -cos |r|: arithmetic, not
     * branches, so it stays one vector instruction stream. */
    float a = fabsf(r);
    float over = (float)(a > PIO2_F);
    float rr = copysignf(a + over * (PI_F - 2.0f * a), r);
    float csign = 1.0f - 2.0f * over;
    float r2 = rr * rr;
    float sn = rr * (1.0f + r2 * (-1.0f / 6 + r2 * (1.0f / 120 + r2 * (-1.0f / 5040 +
               r2 * (1.0f / 362880 + r2 * (-1.0f / 39916800))))));
    float cs = 1.0f + r2 * (-0.5f + r2 * (1.0f / 24 + r2 * (-1.0f / 720 + r2 * (1.0f / 40320 +
               r2 * (-1.0f / 3628800 + r2 * (1.0f / 479001600))))));
    *s_out = sn;
    *c_out = csign * cs;
}

/* Butterworth gain without pow(): q = r^order by squaring.  Same
 * stable split as ocean_filter_gain (filter.h). */
static inline float gain_fast(float k, float kc, int order)
{
    float r = k <= kc ? k / kc : kc / k, q = 1.0f, b = r;
    for (int e = order; e; e >>= 1, b *= b)
        if (e & 1)
            q *= b;
    float inv = 1.0f / sqrtf(1.0f + q * q);
    return k <= kc ? inv : q * inv;
}

/* h(k,t) (and, with_dt, dh/dt) of one row, and with pair of its mirror
 * row too, into the cache.  Rows mz and -mz hold the same |k|, so the
 * same w and phase (ocean_modes_build fills turns from |k| alone; no current
 * makes w depend on direction): one phase and sin/cos serve both rows,
 * half the stage's trigonometry.  turns is the index of the row's first
 * mode in turns_hi/lo (FFTW's rows), row and mirror those of the two rows
 * in coef and cache (ocean_pair_row).  deep: the columns x0 .. x0 + count - 1
 * of rows +-sqrt(mz2) are deep water, so w / 2 pi is ocean_deep_turns, not read
 * (cs->deep).  Inlined with literal with_dt, pair and deep, so each
 * variant is one branch-free vector loop.  Out-of-band modes have
 * a = b = 0, so they need no branch either. */
static inline __attribute__((always_inline)) void
row_evolve(const ocean_cascade *cs, size_t turns, size_t row, size_t mirror, int count, double t,
           int x0, double mz2, const int with_dt, const int fused, const int pair,
           const int deep)
{
    const double *fh = cs->turns_hi + turns, *fl = cs->turns_lo + turns;
    double th, tl;
    ocean_split(t, &th, &tl);
    const float *ar = cs->coef[A_RE] + row, *ai = cs->coef[A_IM] + row;
    const float *br = cs->coef[B_RE] + row, *bi = cs->coef[B_IM] + row;
    float *c_hr = cs->cache[C_HR] + row, *c_hi = cs->cache[C_HI] + row;
    float *c_tr = cs->cache[C_TR] + row, *c_ti = cs->cache[C_TI] + row;
    const float *qar = cs->coef[A_RE] + mirror, *qai = cs->coef[A_IM] + mirror;
    const float *qbr = cs->coef[B_RE] + mirror, *qbi = cs->coef[B_IM] + mirror;
    float *q_hr = cs->cache[C_HR] + mirror, *q_hi = cs->cache[C_HI] + mirror;
    float *q_tr = cs->cache[C_TR] + mirror, *q_ti = cs->cache[C_TI] + mirror;
    const double cf = cs->cf;
#pragma omp simd
    for (int ix = 0; ix < count; ix++) {
        float s, c;
        double mx = (double)(x0 + ix);
        double f_hi = deep ? ocean_deep_turns(cf, mx * mx + mz2) : fh[ix];
        double f_lo = deep ? 0.0 : fl[ix];
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
        double ph = fused ? ocean_phase_turns_fma(f_hi, f_lo, t)
                          : ocean_phase_turns(f_hi, f_lo, t, th, tl);
#else
        double ph = ocean_phase_turns(f_hi, f_lo, t, th, tl);
#endif
        phase_sincos(ph, &s, &c);
        float w = with_dt ? (float)(f_hi * OCEAN_TWO_PI_C1) : 0.0f;
        /* h = a cos + b sin, dh/dt = w (b cos - a sin) */
        c_hr[ix] = ar[ix] * c + br[ix] * s;
        c_hi[ix] = ai[ix] * c + bi[ix] * s;
        if (with_dt) {
            c_tr[ix] = w * (br[ix] * c - ar[ix] * s);
            c_ti[ix] = w * (bi[ix] * c - ai[ix] * s);
        }
        if (pair) {
            q_hr[ix] = qar[ix] * c + qbr[ix] * s;
            q_hi[ix] = qai[ix] * c + qbi[ix] * s;
            if (with_dt) {
                q_tr[ix] = w * (qbr[ix] * c - qar[ix] * s);
                q_ti[ix] = w * (qbi[ix] * c - qai[ix] * s);
            }
        }
    }
}

#define ROW_MAX (OCEAN_MAX_N / 2 + 1)

/* Writes the spectra of every asked channel for one row of the n-point
 * grid, in three passes that each vectorise: h(k,t) for the row (unless
 * cached), the filter gains, then one simple loop per channel. */
/* The row passes vectorise 8 wide with AVX2; the default clone keeps the
 * library runnable on any x86-64 (glibc picks the clone at load time). */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
/* Copies m floats to dst with non-temporal stores, then fences.  For
 * spectra larger than the cache: a plain store first reads the line it
 * writes (the spectra are written whole, never read here), so streaming
 * halves the memory traffic of the stage; values are unchanged. */
__attribute__((target("avx2"))) static void spectrum_row_stream(float *dst, const float *src,
                                                                int m)
{
    int i = 0;
    while (i < m && ((uintptr_t)(dst + i) & 31u))
        dst[i] = src[i], i++;
    for (; i + 8 <= m; i += 8)
        _mm256_stream_ps(dst + i, _mm256_loadu_ps(src + i));
    for (; i < m; i++)
        dst[i] = src[i];
    /* Streaming stores are weakly ordered: fence before the FFT (another
     * thread) reads them. */
    _mm_sfence();
}
#endif

/* The gains of row r's columns [x0, x1): the bucket's gain plane row, filled
 * here unless it already holds them, or g when the bucket has no plane. */
static inline __attribute__((always_inline)) const float *
row_gains(const ocean_stage_args *a, int r, int x0, int x1, size_t kbase, float *g)
{
    float *gr = a->gain ? a->gain + (size_t)r * (a->n / 2 + 1) : g;
    if (!a->gain_ready) {
        const float *kk = a->cs->k + kbase;
        float kc = (float)a->kc, kneg = (float)a->kneg, scale = (float)a->scale;
        float boost = (float)a->boost;
        for (int ix = x0; ix < x1; ix++) {
            float k = kk[ix], gb = k < kneg ? gain_fast(k, kc, a->order) : 0.0f;
            /* The low boost fades in with the gain (ocean_filter_cutoff_gain):
             * no step at kc. */
            gr[ix] = gb * scale * (1.0f + (boost - 1.0f) * gb * gb);
        }
    }
    return gr;
}

/* o = i lam (k/|k|) (re + i im) over columns [x0, x1): a displacement or
 * velocity channel, k the column's kx (col = 1) or the row's kz (col = 0).
 * Inlined with a literal col, so each use is one simple loop. */
static inline __attribute__((always_inline)) void
row_times_ik(float (*o)[2], float lam, const float *kx, float kz, const float *kinv, const float *re,
             const float *im, int x0, int x1, const int col)
{
    for (int ix = x0; ix < x1; ix++) {
        float f = lam * (col ? kx[ix] : kz) * kinv[ix];
        o[ix][0] = -f * im[ix]; o[ix][1] = f * re[ix];
    }
}

/* One channel of a row into o, columns [x0, x1), from the row's filtered
 * h (hr, hi) and dh/dt (tr, ti); kx per column, kz of the row, kinv and kw
 * per column, lam the choppiness. */
static inline __attribute__((always_inline)) void
row_channel(float (*o)[2], int ch, const float *hr, const float *hi, const float *tr,
            const float *ti, const float *kx, const float *kinv, const float *kw, float kz, float lam,
            int x0, int x1)
{
    switch (ch) {
    case CH_H:
        for (int ix = x0; ix < x1; ix++) { o[ix][0] = hr[ix]; o[ix][1] = hi[ix]; }
        break;
    case CH_DX: /* i k/|k| h */
        row_times_ik(o, lam, kx, kz, kinv, hr, hi, x0, x1, 1);
        break;
    case CH_DZ:
        row_times_ik(o, lam, kx, kz, kinv, hr, hi, x0, x1, 0);
        break;
    case CH_SX: /* i k h */
        for (int ix = x0; ix < x1; ix++) { o[ix][0] = -kx[ix] * hi[ix]; o[ix][1] = kx[ix] * hr[ix]; }
        break;
    case CH_SZ:
        for (int ix = x0; ix < x1; ix++) { o[ix][0] = -kz * hi[ix]; o[ix][1] = kz * hr[ix]; }
        break;
    case CH_DXX: /* i kx * i k/|k| h = -kx k/|k| h */
        for (int ix = x0; ix < x1; ix++) {
            float f = -lam * kx[ix] * kx[ix] * kinv[ix];
            o[ix][0] = f * hr[ix]; o[ix][1] = f * hi[ix];
        }
        break;
    case CH_DZZ:
        for (int ix = x0; ix < x1; ix++) {
            float f = -lam * kz * kz * kinv[ix];
            o[ix][0] = f * hr[ix]; o[ix][1] = f * hi[ix];
        }
        break;
    case CH_DXZ:
        for (int ix = x0; ix < x1; ix++) {
            float f = -lam * kx[ix] * kz * kinv[ix];
            o[ix][0] = f * hr[ix]; o[ix][1] = f * hi[ix];
        }
        break;
    case CH_BQ: /* lam |k|/w dh/dt: -lam times beta's quadrature (foam.h) */
        for (int ix = x0; ix < x1; ix++) {
            float f = lam * kw[ix];
            o[ix][0] = f * tr[ix]; o[ix][1] = f * ti[ix];
        }
        break;
    case CH_VX: /* i k/|k| dh/dt */
        row_times_ik(o, lam, kx, kz, kinv, tr, ti, x0, x1, 1);
        break;
    case CH_VY:
        for (int ix = x0; ix < x1; ix++) { o[ix][0] = tr[ix]; o[ix][1] = ti[ix]; }
        break;
    case CH_VZ:
        row_times_ik(o, lam, kx, kz, kinv, tr, ti, x0, x1, 0);
        break;
    }
}

/* Writes the spectra of every asked channel for row r of the n-point grid
 * from the cached h(k,t): the filter gains (row_gains), then one simple
 * loop per channel (row_channel), each of which vectorises. */
static inline __attribute__((always_inline)) void
spectrum_row_channels(const ocean_stage_args *a, int r, int x0, int x1, const int fused)
{
    int n = a->n, half = n / 2 + 1, full_half = a->n_full / 2 + 1;
    size_t plane = (size_t)n * half;
    int mz = r < n / 2 ? r : r - n;
    size_t base = ocean_pair_row(mz, a->n_full) * full_half;
    /* |k| and 1/|k| of rows mz and -mz are equal (kz enters squared): both
     * rows of a pair read row |mz|, so the second finds it in L1. */
    size_t kbase = (size_t)ocean_wrap_index(mz < 0 ? -mz : mz, a->n_full) * full_half;
    const ocean_cascade *cs = a->cs;
    float *c_hr = cs->cache[C_HR] + base, *c_hi = cs->cache[C_HI] + base;
    float *c_tr = cs->cache[C_TR] + base, *c_ti = cs->cache[C_TI] + base;
    const float *kx = cs->kx, *kinv = cs->kinv + kbase, *kw = cs->kw + kbase;
    const float *hr = c_hr, *hi = c_hi, *tr = c_tr, *ti = c_ti;
    float g[ROW_MAX], fhr[ROW_MAX], fhi[ROW_MAX], ftr[ROW_MAX], fti[ROW_MAX];
    /* Unfiltered, the grid is the full one: the cached h is the spectrum
     * as it stands.  Otherwise apply the gains.  Columns outside [x0, x1)
     * (no wave, or this grid's Nyquist column) are written as zeros. */
    if (!(isinf(a->kc) && a->scale == 1.0 && a->boost == 1.0 && n == a->n_full)) {
        const float *restrict gv = row_gains(a, r, x0, x1, kbase, g);
        for (int ix = x0; ix < x1; ix++) {
            fhr[ix] = c_hr[ix] * gv[ix];
            fhi[ix] = c_hi[ix] * gv[ix];
        }
        if (a->need_dt)
            for (int ix = x0; ix < x1; ix++) {
                ftr[ix] = c_tr[ix] * gv[ix];
                fti[ix] = c_ti[ix] * gv[ix];
            }
        hr = fhr;
        hi = fhi;
        tr = ftr;
        ti = fti;
    }
    float kz = (float)(mz * a->cs->dk), lam = (float)a->lambda;
    /* Streaming: each channel's row is made in this L1 buffer and then
     * written past the caches (spectrum_row_stream). */
    float rowbuf[ROW_MAX][2];
    const int stream = fused && a->stream;
    for (int j = 0; j < a->nch; j++) {
        float (*dst)[2] = &a->spec[(size_t)j * plane + (size_t)r * half];
        float (*o)[2] = stream ? rowbuf : dst;
        memset(o, 0, sizeof o[0] * (size_t)x0);
        memset(o + x1, 0, sizeof o[0] * (size_t)(half - x1));
        row_channel(o, a->ch[j], hr, hi, tr, ti, kx, kinv, kw, kz, lam, x0, x1);
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
        if (stream)
            spectrum_row_stream(&dst[0][0], &rowbuf[0][0], 2 * half);
#endif
    }
}

/* row_evolve for one span of a row pair, with_dt and pair made literal. */
static inline __attribute__((always_inline)) void
evolve_span(const ocean_stage_args *a, size_t turns, size_t row, size_t mirror, int count, int x0,
            double mz2, int alone, const int fused, const int deep)
{
    if (count <= 0)
        return;
    if (alone && a->need_dt)
        row_evolve(a->cs, turns, row, row, count, a->t, x0, mz2, 1, fused, 0, deep);
    else if (alone)
        row_evolve(a->cs, turns, row, row, count, a->t, x0, mz2, 0, fused, 0, deep);
    else if (a->need_dt)
        row_evolve(a->cs, turns, row, mirror, count, a->t, x0, mz2, 1, fused, 1, deep);
    else
        row_evolve(a->cs, turns, row, mirror, count, a->t, x0, mz2, 0, fused, 1, deep);
}

/* Rows p and n - p of the n-point grid (mz = p and -p; rows 0 and n/2
 * alone): h(k,t) for both (unless cached), then their channels. */
static inline __attribute__((always_inline)) void
spectrum_row_body(const ocean_stage_args *a, int p, const int fused)
{
    int n = a->n, full_half = a->n_full / 2 + 1;
    int alone = p == 0 || p == n / 2;
    int mz = p < n / 2 ? p : p - n;
    int lo, hi;
    ocean_pair_range(a->cs, n, p, &lo, &hi);
    size_t turns = (size_t)ocean_wrap_index(mz, a->n_full) * full_half + (size_t)lo;
    size_t row = ocean_pair_row(mz, a->n_full) * full_half + (size_t)lo;
    size_t mirror = ocean_pair_row(-mz, a->n_full) * full_half + (size_t)lo;
    if (!a->cached) {
        /* Columns [lo, d) read their frequency, [d, hi) compute it. */
        int d = a->deep_table ? hi : a->cs->deep[p];
        d = d < lo ? lo : d > hi ? hi : d;
        int skip = d - lo;
        double mz2 = (double)mz * mz;
        evolve_span(a, turns, row, mirror, skip, lo, mz2, alone, fused, 0);
        evolve_span(a, turns + skip, row + skip, mirror + skip, hi - d, d, mz2, alone, fused, 1);
    }
    spectrum_row_channels(a, p, lo, hi, fused);
    if (!alone)
        spectrum_row_channels(a, n - p, lo, hi, fused);
}

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
static void spectrum_row_plain(const ocean_stage_args *a, int r)
{
    spectrum_row_body(a, r, 0);
}

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target("avx2,fma")))
static void spectrum_row_fused(const ocean_stage_args *a, int r)
{
    spectrum_row_body(a, r, 1);
}

/* The same source 16 floats wide.  With AVX2 the row loop runs out of
 * registers and reloads the sin/cos coefficients from the stack; 32
 * vector registers hold them (bench_core, "the spectrum stage's paths").
 * Same operations in the same order, no contraction (ISO C: no
 * -ffp-contract), so the same bits (tests/test_ocean.c). */
__attribute__((target("avx512f,avx512vl,avx512dq,avx512bw,avx2,fma,prefer-vector-width=512")))
static void spectrum_row_wide(const ocean_stage_args *a, int r)
{
    spectrum_row_body(a, r, 1);
}
#endif

static void spectrum_row(const ocean_stage_args *a, int r)
{
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
    if (a->fused == 2) {
        spectrum_row_wide(a, r);
        return;
    }
    if (a->fused) {
        spectrum_row_fused(a, r);
        return;
    }
#endif
    spectrum_row_plain(a, r);
}

/* The spectrum stage's split of row pairs 0..n/2 over nt threads: thread
 * t takes pairs [b[t], b[t+1]), contiguous, so two threads meet only at a
 * block's edges (rows b and n - b), where they may share a cache line of
 * a spectrum (a row is 8 (n/2 + 1) bytes, not whole lines).  Interleaved
 * chunks of 4 pairs made every chunk edge such a line: 1-1.5 % more per
 * evaluation (interleaved A/B, N = 256-1024).  The blocks are balanced by
 * weight: a pair's columns with a wave cost STAGE_WAVE_COST times a column
 * of zeros, so a coarse cascade, whose rows beyond |mz| = n/4 are zeros
 * only, is not split into one thread's arithmetic and the other's memset. */
#define STAGE_WAVE_COST 4
#define STAGE_MAX_THREADS 64

void ocean_stage_split(const ocean_cascade *cs, int n, int nt, int *b)
{
    double w[OCEAN_MAX_N / 2 + 1], total = 0.0;
    for (int p = 0; p <= n / 2; p++) {
        int lo, hi;
        ocean_pair_range(cs, n, p, &lo, &hi);
        w[p] = (p == 0 || p == n / 2 ? 1.0 : 2.0) * (n / 2 + 1 + (STAGE_WAVE_COST - 1.0) * (hi - lo));
        total += w[p];
    }
    b[0] = 0;
    double acc = 0.0;
    int p = 0;
    for (int t = 1; t < nt; t++) {
        while (p <= n / 2 && acc + w[p] * 0.5 < total * t / nt)
            acc += w[p++];
        b[t] = p;
    }
    b[nt] = n / 2 + 1;
}

/* The calling team member's rows [*r0, *r1) of the split b made for nt
 * threads; OpenMP may grant a team smaller than asked, and then every
 * member splits again for the team it got, so no row is left out. */
void ocean_stage_rows(const ocean_cascade *cs, int n, int nt, const int *b, int *r0, int *r1)
{
#ifdef _OPENMP
    int t = omp_get_thread_num(), m = omp_get_num_threads();
#else
    int t = 0, m = 1; /* built without OpenMP (the fuzzers): one thread */
#endif
    if (m == nt) {
        *r0 = b[t];
        *r1 = b[t + 1];
        return;
    }
    int mine[STAGE_MAX_THREADS + 1];
    ocean_stage_split(cs, n, m, mine);
    *r0 = mine[t];
    *r1 = mine[t + 1];
}

/* The channels [*c0, *c1) of a gn-channel FFTW call that this team
 * member writes when the stage splits a call by channel: the block of the
 * batch FFTW's threaded plan hands the same member (its threads split a
 * batch of 2-D transforms into blocks of ceil(gn / threads) transforms,
 * member i taking block i: fftw3's X(spawn_loop)).  Then the FFT reads
 * each spectrum from the core that wrote it; split by rows, half of every
 * spectrum a thread transforms was written by the other core, and when this
 * VM's caches are busy that cross-core read cost the FFT 10-20 % (FFTW
 * alone after zero writes, row split 1.15-1.21x, channel split 1.02-1.03x,
 * N = 512 and 1024, same minutes). */
void ocean_stage_channels(int gn, int *c0, int *c1)
{
#ifdef _OPENMP
    int t = omp_get_thread_num(), m = omp_get_num_threads();
#else
    int t = 0, m = 1;
#endif
    int bs = (gn + m - 1) / m;
    *c0 = t * bs < gn ? t * bs : gn;
    *c1 = *c0 + bs < gn ? *c0 + bs : gn;
}

/* This team member's share of one FFTW call's stage pass: split by channel
 * (ocean_stage_channels) when the call has a channel for every thread, else by
 * rows (ocean_stage_rows).  By channel, an evolving pass (a->cached = 0) first
 * evolves this member's rows and writes its channels there from h in L1,
 * then, once every row's h(k,t) and gains are in place, its channels in
 * the other rows from the cache. */
void ocean_stage_pass(const ocean_stage_args *a, int nt, const int *split, size_t plane, int by_channel)
{
    const ocean_cascade *cs = a->cs;
    int n = a->n, r0, r1;
    ocean_stage_rows(cs, n, nt, split, &r0, &r1);
    if (!by_channel) {
        for (int p = r0; p < r1; p++)
            spectrum_row(a, p);
        return;
    }
    int c0, c1;
    ocean_stage_channels(a->nch, &c0, &c1);
    ocean_stage_args my = *a;
    my.ch = a->ch + c0;
    my.nch = c1 - c0;
    my.spec = a->spec + (size_t)c0 * plane;
    if (!a->cached) {
        for (int p = r0; p < r1; p++)
            spectrum_row(&my, p);
#pragma omp barrier
        my.cached = 1;
        my.gain_ready = a->gain != NULL;
        for (int p = 0; p < r0; p++)
            spectrum_row(&my, p);
        for (int p = r1; p <= n / 2; p++)
            spectrum_row(&my, p);
    } else {
        for (int p = 0; p <= n / 2; p++)
            spectrum_row(&my, p);
    }
}

void ocean_force_stage_split(ocean *o, int mode)
{
    if (o)
        o->split_mode = mode == 0 || mode == 1 ? mode : -1;
}

/* Every SPLIT_PROBE-th evaluation of a kind runs the split that is
 * measured slower, so a change in the machine's load (the better split
 * changes with it) is seen within a few seconds at 30 Hz. */
#define SPLIT_PROBE 16

/* The least of split s's recent costs (ocean_split_stat). */
static double split_min(const ocean_split_stat *st, int s)
{
    double m = INFINITY;
    for (int i = 0; i < st->have[s]; i++)
        m = st->ns[s][i] < m ? st->ns[s][i] : m;
    return m;
}

/* ocean_stage_split_pick's choice without a probe: the split the stage runs now. */
int ocean_stage_split_best(const ocean *o, const ocean_split_stat *st)
{
    if (o->split_mode >= 0)
        return o->split_mode;
    return st->have[0] && st->have[1] && split_min(st, 1) < split_min(st, 0);
}

/* The split (0 rows, 1 channels) for the next evaluation of a kind: each
 * measured once first, then the faster with a probe of the other. */
int ocean_stage_split_pick(const ocean *o, ocean_split_stat *st)
{
    if (o->split_mode >= 0)
        return o->split_mode;
    if (!st->have[0])
        return 0;
    if (!st->have[1])
        return 1;
    int best = ocean_stage_split_best(o, st);
    return ++st->evals % SPLIT_PROBE == 0 ? !best : best;
}

void ocean_stage_split_note(ocean_split_stat *st, int split, double ns)
{
    st->ns[split][st->next[split]] = ns;
    st->next[split] = (uint8_t)((st->next[split] + 1) % SPLIT_WINDOW);
    if (st->have[split] < SPLIT_WINDOW)
        st->have[split]++;
}
