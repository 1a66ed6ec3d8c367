/*
 * ocean.c - the FFT ocean (see ocean.h for the contract).
 *
 * Per cascade we keep, for every mode of the half spectrum (kz rows, kx >= 0
 * columns, as FFTW's c2r wants it), the mode's two standing-wave
 * coefficients a and b (from the initial amplitudes h0(k) and conj(h0(-k))
 * below), the angular frequency in double and the wave vector.  An
 * evaluation then runs one pass over the modes (the "spectrum stage") that
 * writes every asked channel's spectrum, and one batched c2r transform per
 * cascade (per group of channels at large N).  The stage touches only the
 * columns of each row that hold a wave (cascade.lo, hi) and writes zeros
 * past them: a coarse cascade's band (a half disc of radius n/4) fills
 * about 20 % of its half spectrum, and its waves lie in the first n/4 of
 * the n/2 + 1 columns, so its transform runs the 2-D c2r's column pass on
 * those columns only (transform_call).  A low cutoff picks a smaller
 * transform: the modes it keeps are the same waves, only fewer of them.
 *
 * Conventions: eta(x) = sum_k h(k,t) e^{i k.x},
 *   h(k,t) = h0(k) e^{-i w t} + conj(h0(-k)) e^{+i w t},   E|h0(k)|^2 = P(k),
 *   P(k) = F(k) dk^2 / 2 so that E[var eta] = sum_k F(k) dk^2 -> m0.
 * The stage evaluates the same h(k,t) as a cos(w t) + b sin(w t), with
 *   a = h0(k) + conj(h0(-k)),   b = i (conj(h0(-k)) - h0(k)),
 * formed in double once: 4 multiplies a mode instead of 8.
 * Choppy displacement D = sum i (k/|k|) h e^{ik.x} times lambda, so a
 * point moves toward the crest as in Gerstner's waves and
 * J = (1 + Dxx)(1 + Dzz) - Dxz^2 < 1 on crests.  The Nyquist row and column
 * are zero in every channel (S. G. Johnson 2011), so the band is symmetric.
 */
#include "ocean.h"
#include "ocean_internal.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <fftw3.h>
#include <omp.h>
#include <stdint.h>
#include <time.h>
#include <sys/stat.h>
#include <unistd.h>
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#include <immintrin.h>
#endif

#include "filter.h"
#include "foam.h"
#include "ocean_plan.h"
#include "ocean_time.h"
#include "wave_rng.h"

enum {
    CH_H, CH_DX, CH_DZ, CH_SX, CH_SZ, CH_DXX, CH_DZZ, CH_DXZ, CH_VX, CH_VY, CH_VZ,
    CH_COUNT
};
#define MAX_LEVELS 9 /* n = 8 .. 2048 */

/* The modes of the half spectrum, n x (n/2 + 1), as structure-of-arrays so
 * the per-row passes vectorise.  Coefficients are float (they are data);
 * the frequency is kept as w / 2 pi in double-double (turns_hi + turns_lo)
 * so the row loop reduces w t to its phase exactly (ocean_time.h).
 * In deep water the stage computes the frequency instead (cascade.deep,
 * deep_turns); the table holds the same double there.
 * Out-of-band modes are all zero.  Rows are FFTW's (row = kz index), except
 * in the two arrays the stage streams for a pair of rows mz, -mz at once
 * (coef and cache): there the pair's rows sit side by side (pair_row), so
 * the stage reads one ascending stream, not a second one running down from
 * the bottom of the array, on which the hardware prefetcher restarts at
 * every row (interleaved A/B, N = 1024: 1.6 % of an evaluation). */
enum { A_RE, A_IM, B_RE, B_IM };          /* a, b: h(k,t) = a cos wt + b sin wt */
enum { C_HR, C_HI, C_TR, C_TI };          /* h(k,t), dh/dt */

typedef struct cascade {
    double patch, dk, k_lo, k_hi;
    double *turns_hi, *turns_lo; /* w / 2 pi = hi + lo, turns per second */
    float *coef[4];         /* a, b by pair_row */
    float *kx;              /* kx of a column (ix dk): one row serves every row */
    float *k, *kinv;        /* kinv = 1/|k| (0 at k = 0) */
    float *var;             /* E|h(k,t)|^2 = P(k) + P(-k) */
    double variance;
    /* h(k,t) and dh/dt of every mode, unfiltered, at time cache_t for the
     * modes of grids up to cache_n: several cutoff buckets in one tick pay
     * for the trigonometry once.  By pair_row. */
    float *cache[4];
    /* Rows mz and -mz hold waves (h0 != 0) only in columns [lo, hi) of
     * row |mz| (empty: lo = hi = 0); the rest of both rows is zero in
     * every channel.  The coarse cascades stop at half their Nyquist, so
     * about 80 % of their modes are zero: the stage reads, evolves and
     * multiplies this range only and writes zeros past it. */
    int *lo, *hi;
    /* Columns of the l-th grid (8 << l points) up to the last that holds a
     * wave of this cascade: transform_call skips the column transforms
     * past it where the ocean has a pruned plan (prune_cols). */
    int width[MAX_LEVELS];
    /* Deep water: from column deep[p] on, the modes of rows +-p have
     * k d >= DEEP_KD, and the stage computes their frequency (deep_turns)
     * instead of reading turns_hi/lo; the table holds the same value.
     * deep[p] = n/2 + 1 (never): a lattice cascade, or shallow water. */
    int *deep;
    double cf;              /* deep_turns' constant: sqrt(g dk) / 2 pi */
    double cache_t;
    int cache_n;
    int cache_dt;           /* 1: dh/dt is cached too (a velocity request) */
    /* A lattice cascade (ocean_create_lattice): its waves, not a spectrum,
     * give h0; NULL for a spectrum cascade. */
    ocean_lattice_wave *lw;
    int nlw;
} cascade;

#define FILTER_MEMO 32
typedef struct filter_memo {
    int used, order;
    double kc, scale, boost, value;
} filter_memo;

/* Index of (kc, order, scale, boost) in a memo table, or -1. */
static int memo_find(const filter_memo *m, double kc, int order, double scale, double boost)
{
    for (int i = 0; i < FILTER_MEMO; i++)
        if (m[i].used && m[i].kc == kc && m[i].order == order && m[i].scale == scale &&
            m[i].boost == boost)
            return i;
    return -1;
}

/* Stores a value, replacing the oldest entry (round robin). */
static void memo_put(filter_memo *m, int *next, double kc, int order, double scale,
                     double boost, double value)
{
    m[*next] = (filter_memo){1, order, kc, scale, boost, value};
    *next = (*next + 1) % FILTER_MEMO;
}

/* What each way of splitting the stage's passes (rows, channels) has cost
 * one kind of cascade evaluation lately: ns per channel of the passes and
 * FFTW calls together, its last SPLIT_WINDOW samples.  Compared by their
 * minimum: a busy machine only ever adds time, so the minimum tracks what
 * a split costs, where an average flipped with every spike (an
 * exponential average chose the slower split a third of the time). */
#define SPLIT_WINDOW 8
typedef struct split_stat {
    double ns[2][SPLIT_WINDOW];
    uint8_t next[2], have[2];
    uint32_t evals;         /* evaluations split_pick chose for, for its probes */
} split_stat;

/* The filter gains of one cutoff bucket on one cascade's n-point grid,
 * (n/2 + 1) per row, including the grid's zeroed Nyquist row and column.
 * A bucket keeps its cutoff for many ticks, so its gains are computed
 * once instead of per tick (a division and a square root per mode). */
#define GAIN_PLANES 12
typedef struct gain_plane {
    int cascade, n, order;
    double kc, scale, boost;
    uint64_t used;          /* LRU stamp; 0: empty */
    size_t cap;             /* floats allocated */
    float *g;
} gain_plane;

/* Grids below this run on one thread: waking the pool for a 32 x 32
 * transform costs more than it saves (a low cutoff bucket's grid). */
#define PARALLEL_MIN_N 64

struct ocean {
    ocean_params p;
    int levels;                         /* plans for n = 8 << l, l < levels */
    cascade cas[OCEAN_MAX_CASCADES];
    fftwf_complex *spec;                /* CH_COUNT x n x (n/2+1) scratch */
    fftwf_plan plan[MAX_LEVELS][CH_COUNT]; /* [level][channels - 1] */
    /* The pruned 2-D transform (transform_call) of every grid of at least
     * PARALLEL_MIN_N points: its first pass (c2c down the columns) over
     * columns [0, prune_cols[l]) only, then the rows' c2r as the 2-D plan
     * does it; run by the cascades whose waves all lie in those columns.
     * prune_cols[l] = 0: the level has no such plans (prune_columns). */
    int prune_cols[MAX_LEVELS];
    fftwf_plan cols_plan[MAX_LEVELS][CH_COUNT], rows_plan[MAX_LEVELS][CH_COUNT];
    int prune;           /* 1: prune where a band allows, 0: never (ocean_force_pruning) */
    ocean_counters counters;
    double k_top;                       /* largest |k| any band holds */
    /* Per-filter sums over every mode cost O(n^2); a tick serving several
     * cutoff buckets asks for the same few again and again.  Redistribution
     * scales are keyed by (cutoff, order), E_error by all four. */
    filter_memo redis_memo[FILTER_MEMO], err_memo[FILTER_MEMO];
    int redis_next, err_next;
    /* std of the breaking index beta per filter (foam.h), same keys */
    filter_memo foam_memo[FILTER_MEMO];
    int foam_next;
    gain_plane gains[GAIN_PLANES];
    uint64_t gain_clock;
    int fused;          /* row pass: 0 plain, 1 AVX2+FMA, 2 AVX-512 (ocean_force_paths) */
    double stream_bytes; /* spectra larger than this are streamed (twice the LLC) */
    int deep_table;     /* 1: the stage reads deep water's w too (ocean_force_frequency_table) */
    int group;           /* channels per FFTW call forced by a test, 0: group_size's rule */
    /* How the stage splits a call over the threads (stage_pass): -1 the
     * faster as measured (split_pick), 0 rows, 1 channels
     * (ocean_force_stage_split).  Timings per cascade, grid level, and
     * whether h(k,t) was cached. */
    int split_mode;
    split_stat split[OCEAN_MAX_CASCADES][MAX_LEVELS][2];
};

struct ocean_frame {
    int cascades;
    int n_max;
    float *block[OCEAN_MAX_CASCADES];   /* CH_COUNT x n x n, fftwf_malloc */
    float *derived[OCEAN_MAX_CASCADES]; /* jacobian, foam: 2 x n x n */
    ocean_field field[OCEAN_MAX_CASCADES];
    ocean_frame_info info;
    double patch[OCEAN_MAX_CASCADES];
    /* The whitecap ramp of this evaluation (foam.h) and 1/lambda, which
     * turns the foam channels' lambda (Dxx + Dzz) into beta = -a_z/g. */
    ocean_foam_map foam_map;
    double foam_inv_lambda;
};

/* FFTW's planner is process-global state: one lock for every ocean. */
static pthread_mutex_t planner_lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_once_t fftw_once = PTHREAD_ONCE_INIT;
static int fftw_threads_ok;

static void fftw_init_once(void)
{
    fftw_threads_ok = fftwf_init_threads();
}

void ocean_params_default(ocean_params *p)
{
    memset(p, 0, sizeof *p);
    ocean_sea_state_default(&p->sea);
    p->seed = 1;
    p->n = 256;
    p->cascades = 1;
    p->patch_m = 1000.0;
    p->cascade_ratio = 4.3;
    p->k_max = INFINITY;
    p->threads = 2;
    p->plan_measure = OCEAN_PLAN_ESTIMATE;
    p->drop_gain = OCEAN_DROP_GAIN_DEFAULT;
}

int ocean_wait_policy_setenv(int spin)
{
    if (getenv("OMP_WAIT_POLICY"))
        return 0;
    setenv("OMP_WAIT_POLICY", "passive", 1);
    if (spin)
        setenv("GOMP_SPINCOUNT", OCEAN_GOMP_SPINCOUNT, 0);
    return 1;
}

ocean_result ocean_params_validate(const ocean_params *p, char *msg, size_t msglen)
{
    if (!p) {
        if (msg) snprintf(msg, msglen, "parameters are NULL");
        return OCEAN_EINVAL;
    }
    ocean_result r = ocean_sea_state_validate(&p->sea, msg, msglen);
    if (r != OCEAN_OK)
        return r;
    if (p->n < OCEAN_MIN_N || p->n > OCEAN_MAX_N || (p->n & (p->n - 1)) != 0) {
        if (msg) snprintf(msg, msglen, "n = %d must be a power of two in [%d, %d]",
                          p->n, OCEAN_MIN_N, OCEAN_MAX_N);
        return OCEAN_EINVAL;
    }
    if (p->cascades < 1 || p->cascades > OCEAN_MAX_CASCADES) {
        if (msg) snprintf(msg, msglen, "cascades = %d is out of range [1, %d]",
                          p->cascades, OCEAN_MAX_CASCADES);
        return OCEAN_EINVAL;
    }
    if (!isfinite(p->patch_m) || p->patch_m < 1.0 || p->patch_m > 1e5) {
        if (msg) snprintf(msg, msglen, "patch = %g m is out of range [1, 100000]", p->patch_m);
        return OCEAN_EINVAL;
    }
    if (!isfinite(p->cascade_ratio) || p->cascade_ratio < 1.5 || p->cascade_ratio > 100.0) {
        if (msg) snprintf(msg, msglen, "cascade_ratio = %g is out of range [1.5, 100]",
                          p->cascade_ratio);
        return OCEAN_EINVAL;
    }
    if (isnan(p->k_max) || p->k_max <= 0.0) {
        if (msg) snprintf(msg, msglen, "k_max = %g must be > 0 (INFINITY for none)", p->k_max);
        return OCEAN_EINVAL;
    }
    if (!(p->drop_gain > 0.0 && p->drop_gain <= M_SQRT1_2 + 1e-12)) {
        if (msg) snprintf(msg, msglen, "drop_gain = %g is out of range (0, 0.7071]", p->drop_gain);
        return OCEAN_EINVAL;
    }
    if (p->threads < 1 || p->threads > 64) {
        if (msg) snprintf(msg, msglen, "threads = %d is out of range [1, 64]", p->threads);
        return OCEAN_EINVAL;
    }
    /* The one time limit (ocean_time.h) holds for waves up to
     * OCEAN_OMEGA_MAX: the shortest wave held is the finest cascade's band
     * corner, or k_max below it. */
    double fine = p->patch_m / pow(p->cascade_ratio, p->cascades - 1);
    double k_top = fmin(M_SQRT2 * (p->n / 2 - 1) * 2.0 * M_PI / fine, p->k_max);
    double w_top = ocean_dispersion(k_top, p->sea.depth_m);
    if (w_top > OCEAN_OMEGA_MAX) {
        if (msg) snprintf(msg, msglen,
                          "the shortest wave held, %.3g m (k = %.4g rad/m, w = %.4g rad/s, finest "
                          "patch %g m at n = %d), is beyond w = %g rad/s (OCEAN_OMEGA_MAX, the "
                          "%.3g m wave the time limit is built on): use ocean.k_max <= %.4g rad/m, a "
                          "smaller n or a larger finest patch",
                          2.0 * M_PI / k_top, k_top, w_top, fine, p->n, OCEAN_OMEGA_MAX,
                          2.0 * M_PI / ocean_wavenumber(OCEAN_OMEGA_MAX, p->sea.depth_m),
                          ocean_wavenumber(OCEAN_OMEGA_MAX, p->sea.depth_m));
        return OCEAN_EINVAL;
    }
    /* The scene plan's refusals (ocean_plan.h): peak beyond the patch,
     * Hs beyond the breaking height. */
    ocean_plan plan;
    ocean_plan_init(&plan);
    ocean_plan_params(p, &plan);
    for (int i = 0; i < plan.count; i++)
        if (plan.item[i].level == OCEAN_PLAN_REFUSE) {
            if (msg) snprintf(msg, msglen, "%s", plan.item[i].text);
            return OCEAN_EINVAL;
        }
    if (p->plan_measure < OCEAN_PLAN_ESTIMATE || p->plan_measure > OCEAN_PLAN_WISDOM) {
        if (msg) snprintf(msg, msglen, "plan = %d is not estimate, measure or wisdom", p->plan_measure);
        return OCEAN_EINVAL;
    }
    if (memchr(p->wisdom, '\0', sizeof p->wisdom) == NULL) {
        if (msg) snprintf(msg, msglen, "wisdom: path not terminated within %d bytes", OCEAN_WISDOM_PATH_MAX);
        return OCEAN_EINVAL;
    }
    if (p->plan_measure == OCEAN_PLAN_WISDOM && p->wisdom[0] == '\0') {
        if (msg) snprintf(msg, msglen, "plan = wisdom needs a wisdom file (ocean.wisdom = PATH; "
                          "`ocean-sim wisdom --out PATH` writes one)");
        return OCEAN_EINVAL;
    }
    return OCEAN_OK;
}

const ocean_params *ocean_get_params(const ocean *o)
{
    return &o->p;
}

void ocean_cascade_band(const ocean *o, int c, double *patch_m, double *k_lo, double *k_hi)
{
    const cascade *cs = &o->cas[c];
    if (patch_m) *patch_m = cs->patch;
    if (k_lo) *k_lo = cs->k_lo;
    if (k_hi) *k_hi = cs->k_hi;
}

/* Index of a signed wave number m in an n-point FFT axis. */
static inline int wrap_index(int m, int n)
{
    return m >= 0 ? m : m + n;
}

/* Row of kz index mz in the pair-ordered arrays of an n-point cascade:
 * 0, then 1, -1, 2, -2, ..., n/2 - 1, -(n/2 - 1), and -n/2 last.  The rows
 * of a smaller grid (|mz| <= n'/2) are a prefix of it. */
static inline size_t pair_row(int mz, int n)
{
    if (mz > 0)
        return (size_t)(2 * mz - 1);
    return mz == 0 ? 0 : mz == -n / 2 ? (size_t)(n - 1) : (size_t)(-2 * mz);
}

/* Stores the standing-wave coefficients of the mode whose initial
 * amplitudes are hp = h0(k) and hm = h0(-k) at index i of cs->coef:
 * a = h0(k) + conj(h0(-k)), b = i (conj(h0(-k)) - h0(k)), in double and
 * rounded once. */
static void coef_put(cascade *cs, size_t i, const double hp[2], const double hm[2])
{
    cs->coef[A_RE][i] = (float)(hp[0] + hm[0]);
    cs->coef[A_IM][i] = (float)(hp[1] - hm[1]);
    cs->coef[B_RE][i] = (float)(hp[1] + hm[1]);
    cs->coef[B_IM][i] = (float)(hm[0] - hp[0]);
}

static inline int in_band(const cascade *cs, double k)
{
    return k >= cs->k_lo && k < cs->k_hi && k > 0.0;
}

/* Variance per mode P(k) = F(k) dk^2 / 2 (see the file comment). */
static double mode_p(const ocean_params *p, const cascade *cs, double kx, double kz)
{
    return ocean_spectrum_f(&p->sea, kx, kz) * cs->dk * cs->dk * 0.5;
}

/* h0 of a lattice cascade at (mx, mz): a wave A cos(k.x - w t + phi) is
 * h0(k) = (A / 2) e^{i phi} (h0(-k) = 0), so that h(k) e^{ik.x} + c.c. is
 * the wave (file comment); waves on one point add. */
static void lattice_h0(const cascade *cs, int mx, int mz, double out[2])
{
    out[0] = out[1] = 0.0;
    for (int i = 0; i < cs->nlw; i++)
        if (cs->lw[i].mx == mx && cs->lw[i].mz == mz) {
            out[0] += 0.5 * cs->lw[i].amplitude * cos(cs->lw[i].phase);
            out[1] += 0.5 * cs->lw[i].amplitude * sin(cs->lw[i].phase);
        }
}

/* h0(k) for the integer wave vector (mx, mz): keyed by (seed, patch, mx, mz). */
static void draw_h0(const ocean_params *p, const cascade *cs, int mx, int mz, double out[2])
{
    if (cs->lw) {
        lattice_h0(cs, mx, mz, out);
        return;
    }
    double kx = mx * cs->dk, kz = mz * cs->dk;
    double k = hypot(kx, kz);
    if (!in_band(cs, k)) {
        out[0] = out[1] = 0.0;
        return;
    }
    double xi[2];
    ocean_rng_normal2(p->seed, OCEAN_RNG_FFT, ocean_rng_patch_salt(cs->patch), mx, mz, xi);
    double a = sqrt(mode_p(p, cs, kx, kz)) * M_SQRT1_2;
    out[0] = xi[0] * a;
    out[1] = xi[1] * a;
}

/* Where tanh(k d) = 1 to 2^-62 (1 - tanh x < 2 e^-2x), w^2 = g k tanh(k d)
 * is the deep-water law w = sqrt(g k) (Airy; Tessendorf 2001, eq. 14). */
#define DEEP_KD 22.0

/* w / 2 pi of mode (mx, mz) in deep water: sqrt(g dk |m|) / 2 pi with
 * |m|^2 = mx^2 + mz^2 exact in double, as cf * |m|^(1/2).  Two correctly
 * rounded square roots and a product, so every path (scalar, AVX2,
 * AVX-512) and every replica gets the same double; it is within 3 ulp of
 * the exact w / 2 pi.  The model's deep-water frequency is this double,
 * read from no table: the stage's frequency table (16 B a pair of modes)
 * was a third of the bytes it streamed from memory every tick, and the
 * phase stays exact for it (ocean_time.h), so only the model's w moves,
 * by under 1e-15 relative. */
static inline double deep_turns(double cf, double m2)
{
    return cf * sqrt(sqrt(m2));
}

/* The per-mode arrays of a cascade of n x (n/2 + 1) modes, zeroed. */
static ocean_result cascade_alloc(cascade *cs, int n)
{
    int half = n / 2 + 1;
    size_t nm = (size_t)n * half;
    int ok = (cs->turns_hi = calloc(nm, sizeof(double))) != NULL;
    ok &= (cs->turns_lo = calloc(nm, sizeof(double))) != NULL;
    for (int j = 0; j < 4; j++) {
        ok &= (cs->coef[j] = calloc(nm, sizeof(float))) != NULL;
        ok &= (cs->cache[j] = malloc(nm * sizeof(float))) != NULL;
    }
    ok &= (cs->kx = calloc((size_t)half, sizeof(float))) != NULL;
    ok &= (cs->k = calloc(nm, sizeof(float))) != NULL;
    ok &= (cs->kinv = calloc(nm, sizeof(float))) != NULL;
    ok &= (cs->var = calloc(nm, sizeof(float))) != NULL;
    ok &= (cs->lo = calloc((size_t)half, sizeof(int))) != NULL;
    ok &= (cs->hi = calloc((size_t)half, sizeof(int))) != NULL;
    ok &= (cs->deep = calloc((size_t)half, sizeof(int))) != NULL;
    cs->cache_n = 0;
    if (!ok)
        return OCEAN_ENOMEM;
    for (int m = 0; m < half; m++)
        cs->deep[m] = half;
    for (int ix = 0; ix < half; ix++)
        cs->kx[ix] = (float)(ix * cs->dk);
    return OCEAN_OK;
}

/* The columns of each row pair (mz, -mz) that hold a wave: cs->lo, cs->hi
 * from the coefficients just stored.  Any of the pair nonzero counts, so a
 * range covers both rows (the stage takes them together). */
static void cascade_ranges(cascade *cs, int n)
{
    int half = n / 2 + 1;
    for (int m = 0; m <= n / 2; m++) {
        size_t up = pair_row(m, n) * half, down = pair_row(-m, n) * half;
        int lo = half, hi = 0;
        for (int ix = 0; ix < half; ix++) {
            int any = 0;
            for (int j = 0; j < 4; j++)
                any |= cs->coef[j][up + ix] != 0.0f || cs->coef[j][down + ix] != 0.0f;
            if (any) {
                lo = lo < ix ? lo : ix;
                hi = ix + 1;
            }
        }
        cs->lo[m] = lo < hi ? lo : 0;
        cs->hi[m] = lo < hi ? hi : 0;
    }
}

static ocean_result cascade_init(ocean *o, int c)
{
    cascade *cs = &o->cas[c];
    const ocean_params *p = &o->p;
    int n = p->n, half = n / 2 + 1;
    cs->patch = p->patch_m / pow(p->cascade_ratio, c);
    cs->dk = 2.0 * M_PI / cs->patch;
    /* Coarser cascades stop at half their Nyquist: at least 4 samples per
     * wavelength (Crest PR #903); the next cascade takes over from there. */
    cs->k_lo = c == 0 ? 0.0 : o->cas[c - 1].k_hi;
    cs->k_hi = c == p->cascades - 1 ? p->k_max : M_PI * n / (2.0 * cs->patch);
    ocean_result r = cascade_alloc(cs, n);
    if (r != OCEAN_OK)
        return r;
    cs->cf = sqrt(OCEAN_G * cs->dk) / OCEAN_TWO_PI_C1;
    /* k grows along a row: deep water is a tail of each row pair. */
    for (int m = 0; m < half; m++) {
        int x = 0;
        while (x < half && !(hypot(x * cs->dk, m * cs->dk) * p->sea.depth_m >= DEEP_KD))
            x++;
        cs->deep[m] = x;
    }
    double var = 0.0;
    for (int iz = 0; iz < n; iz++) {
        int mz = iz < n / 2 ? iz : iz - n;
        for (int ix = 0; ix < half; ix++) {
            size_t i = (size_t)iz * half + ix;
            int mx = ix;
            /* Nyquist row and column stay zero. */
            if (mz == -n / 2 || mx == n / 2)
                continue;
            double kx = mx * cs->dk, kz = mz * cs->dk, k = hypot(kx, kz);
            if (!in_band(cs, k))
                continue;
            double hp[2], hm[2];
            draw_h0(p, cs, mx, mz, hp);
            draw_h0(p, cs, -mx, -mz, hm);
            if (ix >= cs->deep[abs(mz)]) {
                cs->turns_hi[i] = deep_turns(cs->cf, (double)mx * mx + (double)mz * mz);
                cs->turns_lo[i] = 0.0;
            } else {
                ocean_turns_of(ocean_dispersion(k, p->sea.depth_m), &cs->turns_hi[i],
                               &cs->turns_lo[i]);
            }
            coef_put(cs, pair_row(mz, n) * half + ix, hp, hm);
            cs->k[i] = (float)k;
            cs->kinv[i] = (float)(1.0 / k);
            double v = mode_p(p, cs, kx, kz) + mode_p(p, cs, -kx, -kz);
            cs->var[i] = (float)v;
            /* Column 0 holds both k and -k; other columns stand for their mirror too. */
            var += ix == 0 ? v : 2.0 * v;
        }
    }
    cs->variance = var;
    cascade_ranges(cs, n);
    return OCEAN_OK;
}

/* Replaces the process's wisdom by the file's (caller holds planner_lock).
 * Forgetting first keeps plans a MEASURE ocean of this process timed from
 * standing in for the file's, which other replicas do not have. */
static ocean_result wisdom_import(const char *path, char *msg, size_t msglen)
{
    /* A directory opens for reading and then read as "corrupt"; a relative
     * path that is missing is said with the directory it was read from */
    struct stat st;
    FILE *fp = stat(path, &st) == 0 && S_ISDIR(st.st_mode) ? (errno = EISDIR, NULL) : fopen(path, "r");
    if (!fp) {
        int e = errno;
        char cwd[512] = "";
        int rel = path[0] != '/' && getcwd(cwd, sizeof cwd) != NULL;
        if (msg) snprintf(msg, msglen, "wisdom file '%s': %s%s%s (`ocean-sim wisdom --out %s` writes one)",
                          path, strerror(e), rel ? "; relative paths are read from " : "", rel ? cwd : "", path);
        return OCEAN_EIO;
    }
    fftwf_forget_wisdom();
    int ok = fftwf_import_wisdom_from_file(fp);
    fclose(fp);
    if (!ok) {
        fftwf_forget_wisdom();
        if (msg) snprintf(msg, msglen, "wisdom file '%s' is not FFTW single-precision wisdom "
                          "(corrupt, or written by another FFTW build): regenerate it with "
                          "`ocean-sim wisdom --out %s`", path, path);
        return OCEAN_EFORMAT;
    }
    return OCEAN_OK;
}

ocean_result ocean_wisdom_export(const char *path, char *msg, size_t msglen)
{
    if (!path || !*path) {
        if (msg) snprintf(msg, msglen, "wisdom: no output file");
        return OCEAN_EINVAL;
    }
    pthread_once(&fftw_once, fftw_init_once);
    pthread_mutex_lock(&planner_lock);
    FILE *fp = fopen(path, "w");
    int err = fp ? 0 : errno;
    if (fp) {
        fftwf_export_wisdom_to_file(fp);
        if (ferror(fp))
            err = EIO;
        if (fclose(fp) != 0 && !err)
            err = errno;
    }
    pthread_mutex_unlock(&planner_lock);
    if (err) {
        if (msg) snprintf(msg, msglen, "wisdom file '%s': %s", path, strerror(err));
        return OCEAN_EIO;
    }
    return OCEAN_OK;
}

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

/* The lattice cascade of ocean_create_lattice: h0 from the waves (sparse:
 * only their lattice points are non-zero), every other per-mode array as
 * a spectrum cascade fills it, so ocean_evaluate, the mips and the
 * moments treat it like any cascade.  Band [k_lo, k_hi) = the waves' |k|
 * range, so mip levels that hold none of them are empty. */
static ocean_result cascade_init_lattice(ocean *o, const ocean_lattice_wave *w, int count,
                                         char *msg, size_t msglen)
{
    cascade *cs = &o->cas[0];
    const ocean_params *p = &o->p;
    int n = p->n, half = n / 2 + 1;
    cs->patch = p->patch_m;
    cs->dk = 2.0 * M_PI / cs->patch;
    cs->k_lo = INFINITY;
    cs->k_hi = 0.0;
    for (int i = 0; i < count; i++) {
        /* the Nyquist row and column stay empty, as in every cascade */
        if (w[i].mx <= -n / 2 || w[i].mx >= n / 2 || w[i].mz <= -n / 2 || w[i].mz >= n / 2 ||
            (w[i].mx == 0 && w[i].mz == 0) || !isfinite(w[i].amplitude) || w[i].amplitude < 0.0 ||
            !isfinite(w[i].phase)) {
            if (msg) snprintf(msg, msglen, "lattice wave %d: (mx, mz) = (%d, %d), amplitude %g, phase %g: "
                              "indices must be within +-%d and not both 0, amplitude finite and >= 0",
                              i, w[i].mx, w[i].mz, w[i].amplitude, w[i].phase, n / 2 - 1);
            return OCEAN_EINVAL;
        }
        double k = hypot(w[i].mx * cs->dk, w[i].mz * cs->dk);
        cs->k_lo = fmin(cs->k_lo, k);
        cs->k_hi = fmax(cs->k_hi, k);
    }
    if (count == 0)
        cs->k_lo = cs->k_hi = 0.0;
    else
        cs->k_hi = nextafter(cs->k_hi, INFINITY);
    ocean_result r = cascade_alloc(cs, n);
    if (r != OCEAN_OK)
        return r;
    cs->lw = malloc(sizeof *cs->lw * (size_t)(count > 0 ? count : 1));
    if (!cs->lw)
        return OCEAN_ENOMEM;
    memcpy(cs->lw, w, sizeof *cs->lw * (size_t)count);
    cs->nlw = count;
    /* the half spectrum's entries a wave at (mx, mz) touches: (mx, mz)
     * itself when mx >= 0, the mirror (-mx, -mz) otherwise, and both in
     * column 0 (which holds k and -k as separate entries) */
    double var = 0.0;
    for (int i = 0; i < count; i++) {
        int ends[2][2] = {{w[i].mx, w[i].mz}, {-w[i].mx, -w[i].mz}};
        for (int e = 0; e < 2; e++) {
            int mx = ends[e][0], mz = ends[e][1];
            if (mx < 0)
                continue;
            size_t at = (size_t)wrap_index(mz, n) * half + mx;
            if (cs->k[at] != 0.0f)
                continue; /* filled from another wave on the same point */
            double hp[2], hm[2];
            draw_h0(p, cs, mx, mz, hp);
            draw_h0(p, cs, -mx, -mz, hm);
            double kx = mx * cs->dk, kz = mz * cs->dk, k = hypot(kx, kz);
            ocean_turns_of(ocean_dispersion(k, p->sea.depth_m), &cs->turns_hi[at], &cs->turns_lo[at]);
            /* The stage takes one phase for rows mz and -mz (same |k|):
             * the row mirror carries the same w whether or not a wave
             * sits there. */
            size_t mir = (size_t)wrap_index(-mz, n) * half + mx;
            cs->turns_hi[mir] = cs->turns_hi[at];
            cs->turns_lo[mir] = cs->turns_lo[at];
            coef_put(cs, pair_row(mz, n) * half + mx, hp, hm);
            cs->k[at] = (float)k;
            cs->kinv[at] = (float)(1.0 / k);
            /* E|h(k,t)|^2 over time: the two terms' cross product averages out */
            double v = hp[0] * hp[0] + hp[1] * hp[1] + hm[0] * hm[0] + hm[1] * hm[1];
            cs->var[at] = (float)v;
            var += mx == 0 ? v : 2.0 * v;
        }
    }
    /* The stage reads |k| and 1/|k| of row |mz| for rows mz and -mz (kz
     * enters squared): a wave on row -mz alone gets them on row mz too. */
    for (int mz = 1; mz < n / 2; mz++) {
        size_t up = (size_t)mz * half, down = (size_t)wrap_index(-mz, n) * half;
        for (int mx = 0; mx < half; mx++)
            if (cs->k[up + mx] == 0.0f && cs->k[down + mx] != 0.0f) {
                cs->k[up + mx] = cs->k[down + mx];
                cs->kinv[up + mx] = cs->kinv[down + mx];
            }
    }
    cs->variance = var;
    cascade_ranges(cs, n);
    return OCEAN_OK;
}

static ocean_result ocean_build(const ocean_params *p, int lattice, const ocean_lattice_wave *lw,
                                int nlw, ocean **out, char *msg, size_t msglen);

/* Columns of the m-point grid (m = 8 << l) up to the last that holds a wave
 * of cascade cs: pair_range's hi over the grid's row pairs. */
static int cascade_width(const cascade *cs, int m)
{
    int w = 0;
    for (int p = 0; p < m / 2; p++) {
        int hi = cs->hi[p] < m / 2 ? cs->hi[p] : m / 2;
        if (cs->lo[p] < hi && hi > w)
            w = hi;
    }
    return w;
}

/* The columns level l's pruned plans transform: a quarter of the m-point
 * grid (m = 8 << l), where a coarse cascade's half disc of radius m/4
 * ends on its full grid.  Fixed rather than each band's own width, so
 * every ocean of an (N, threads) has the same plans: a wisdom file made
 * from the FFT ocean serves the near field's lattice ocean too.  Grids
 * below PARALLEL_MIN_N: 0, no pruned plans (the 2-D plan is a few
 * microseconds there).  Fills every cascade's width at this level. */
static int prune_columns(ocean *o, int l)
{
    int m = 8 << l;
    for (int c = 0; c < o->p.cascades; c++)
        o->cas[c].width[l] = cascade_width(&o->cas[c], m);
    return m >= PARALLEL_MIN_N ? m / 4 : 0;
}

/* The two passes of level l's pruned c transforms (caller holds
 * planner_lock, with the level's thread count set).  The 2-D c2r of the
 * spectra at o->spec is a c2c down each column (the m rows, stride m/2+1)
 * and then a c2r along each row; a column with no wave stays zero through
 * the first pass, so only columns [0, cols) take it, in place.  The
 * second pass is the 2-D plan's own: out of place, free to overwrite its
 * input (the stage writes every column again before the next call). */
static void plan_pruned(ocean *o, int l, int c, float *tmp, unsigned flags)
{
    int m = 8 << l, half = m / 2 + 1;
    ptrdiff_t plane = (ptrdiff_t)m * half;
    fftwf_iodim col = {m, half, half};
    fftwf_iodim col_many[2] = {{o->prune_cols[l], 1, 1}, {c, plane, plane}};
    o->cols_plan[l][c - 1] = fftwf_plan_guru_dft(1, &col, 2, col_many, o->spec, o->spec,
                                                 FFTW_BACKWARD, flags);
    fftwf_iodim row = {m, 1, 1};
    fftwf_iodim row_many[2] = {{m, half, m}, {c, plane, (ptrdiff_t)m * m}};
    o->rows_plan[l][c - 1] = fftwf_plan_guru_dft_c2r(1, &row, 2, row_many, o->spec, tmp, flags);
}

ocean_result ocean_create(const ocean_params *p, ocean **out, char *msg, size_t msglen)
{
    *out = NULL;
    ocean_result r = ocean_params_validate(p, msg, msglen);
    if (r != OCEAN_OK)
        return r;
    return ocean_build(p, 0, NULL, 0, out, msg, msglen);
}

ocean_result ocean_create_lattice(const ocean_params *p, double patch_m, const ocean_lattice_wave *w,
                                  int count, ocean **out, char *msg, size_t msglen)
{
    if (!out)
        return OCEAN_EINVAL;
    *out = NULL;
    if (!p || (count > 0 && !w) || count < 0 || count > OCEAN_LATTICE_MAX_WAVES) {
        if (msg) snprintf(msg, msglen, "lattice: parameters or waves missing, or count = %d "
                          "outside [0, %d]", count, OCEAN_LATTICE_MAX_WAVES);
        return OCEAN_EINVAL;
    }
    if (!isfinite(patch_m) || patch_m < 1e-3 || patch_m > 1e5) {
        if (msg) snprintf(msg, msglen, "lattice: patch = %g m is out of range [0.001, 100000]", patch_m);
        return OCEAN_EINVAL;
    }
    /* The spectrum checks of ocean_params_validate (peak within the patch,
     * breaking height) are about a spectrum cascade; a lattice carries
     * given waves.  What the evaluation relies on is checked: the grid,
     * threads, planning, the sea (depth, choppiness) and the time limit. */
    ocean_params q = *p;
    q.cascades = 1;
    q.patch_m = patch_m;
    q.k_max = INFINITY;
    ocean_result r = ocean_sea_state_validate(&q.sea, msg, msglen);
    if (r != OCEAN_OK)
        return r;
    if (q.n < OCEAN_MIN_N || q.n > OCEAN_MAX_N || (q.n & (q.n - 1)) != 0 || q.threads < 1 ||
        q.threads > 64 || !(q.drop_gain > 0.0 && q.drop_gain <= M_SQRT1_2 + 1e-12) ||
        q.plan_measure < OCEAN_PLAN_ESTIMATE || q.plan_measure > OCEAN_PLAN_WISDOM ||
        memchr(q.wisdom, '\0', sizeof q.wisdom) == NULL ||
        (q.plan_measure == OCEAN_PLAN_WISDOM && q.wisdom[0] == '\0')) {
        if (msg) snprintf(msg, msglen, "lattice: n = %d, threads = %d, drop_gain = %g or the plan "
                          "mode is invalid (see ocean_params_validate)", q.n, q.threads, q.drop_gain);
        return OCEAN_EINVAL;
    }
    double dk = 2.0 * M_PI / patch_m;
    for (int i = 0; i < count; i++) {
        double w_i = ocean_dispersion(hypot(w[i].mx * dk, w[i].mz * dk), q.sea.depth_m);
        if (!(w_i <= OCEAN_OMEGA_MAX)) {
            if (msg) snprintf(msg, msglen, "lattice wave %d: w = %g rad/s is beyond OCEAN_OMEGA_MAX = %g",
                              i, w_i, OCEAN_OMEGA_MAX);
            return OCEAN_EINVAL;
        }
    }
    return ocean_build(&q, 1, w, count, out, msg, msglen);
}

/* Every cascade's waves: from the spectrum, or the given lattice waves. */
static ocean_result build_cascades(ocean *o, int lattice, const ocean_lattice_wave *lw, int nlw,
                                   char *msg, size_t msglen)
{
    for (int c = 0; c < o->p.cascades; c++) {
        char why[256] = "";
        ocean_result r = lattice ? cascade_init_lattice(o, lw, nlw, why, sizeof why) : cascade_init(o, c);
        if (r != OCEAN_OK) {
            if (msg) {
                if (why[0]) snprintf(msg, msglen, "%s", why);
                else snprintf(msg, msglen, "out of memory for cascade %d", c);
            }
            return r;
        }
    }
    return OCEAN_OK;
}

/* The planner flags of p's plan mode (caller holds planner_lock). */
static ocean_result plan_flags(const ocean_params *p, unsigned *flags, char *msg, size_t msglen)
{
    *flags = FFTW_ESTIMATE;
    if (p->plan_measure == OCEAN_PLAN_ESTIMATE) {
        /* An ESTIMATE planner still takes wisdom of a higher patience, so
         * wisdom left by a MEASURE or WISDOM ocean of this process would
         * make its plans differ from another process's. */
        fftwf_forget_wisdom();
    } else if (p->plan_measure == OCEAN_PLAN_MEASURE) {
        *flags = FFTW_MEASURE;
    } else {
        ocean_result r = wisdom_import(p->wisdom, msg, msglen);
        if (r != OCEAN_OK)
            return r;
        *flags = FFTW_MEASURE | FFTW_WISDOM_ONLY;
    }
    return OCEAN_OK;
}

/* Why level l's c-channel plans (m = 8 << l, nthr threads) could not be
 * made: a wisdom file without them, or FFTW itself. */
static ocean_result plan_failure(const ocean *o, int l, int c, int nthr, unsigned flags, char *msg,
                                 size_t msglen)
{
    int m = 8 << l;
    if (flags & FFTW_WISDOM_ONLY) {
        char what[96];
        if (o->plan[l][c - 1])
            snprintf(what, sizeof what, " (its column pass over %d of %d columns)",
                     o->prune_cols[l], m / 2 + 1);
        else
            what[0] = '\0';
        if (msg) snprintf(msg, msglen, "wisdom file '%s' has no plan for a %dx%d x%d "
                          "transform%s on %d thread%s (made for another N, "
                          "ocean.threads or scene, or by an older oceand?): "
                          "regenerate it with `ocean-sim wisdom`",
                          o->p.wisdom, m, m, c, what, nthr, nthr == 1 ? "" : "s");
        return OCEAN_EUNSUPPORTED;
    }
    if (msg) snprintf(msg, msglen, "FFTW could not plan a %dx%d x%d transform", m, m, c);
    return OCEAN_ENOMEM;
}

/* Every (size, batch) planned once, so evaluations only execute (caller
 * holds planner_lock); tmp is the planner's output scratch. */
static ocean_result plan_all(ocean *o, float *tmp, unsigned flags, char *msg, size_t msglen)
{
    int n = o->p.n;
    for (int l = 0; (8 << l) <= n; l++) {
        int m = 8 << l;
        o->levels = l + 1;
        int nthr = m >= PARALLEL_MIN_N ? o->p.threads : 1;
        if (fftw_threads_ok)
            fftwf_plan_with_nthreads(nthr);
        o->prune_cols[l] = prune_columns(o, l);
        for (int c = 1; c <= CH_COUNT; c++) {
            int dims[2] = {m, m};
            o->plan[l][c - 1] = fftwf_plan_many_dft_c2r(
                2, dims, c, o->spec, NULL, 1, m * (m / 2 + 1), tmp, NULL, 1, m * m, flags);
            if (o->plan[l][c - 1] && o->prune_cols[l])
                plan_pruned(o, l, c, tmp, flags);
            if (!o->plan[l][c - 1] || (o->prune_cols[l] && (!o->cols_plan[l][c - 1] || !o->rows_plan[l][c - 1])))
                return plan_failure(o, l, c, nthr, flags, msg, msglen);
        }
    }
    return OCEAN_OK;
}

static ocean_result ocean_build(const ocean_params *p, int lattice, const ocean_lattice_wave *lw,
                                int nlw, ocean **out, char *msg, size_t msglen)
{
    *out = NULL;
    pthread_once(&fftw_once, fftw_init_once);
    ocean *o = calloc(1, sizeof *o);
    if (!o) {
        if (msg) snprintf(msg, msglen, "out of memory");
        return OCEAN_ENOMEM;
    }
    o->p = *p;
    ocean_force_paths(o, -1, -1);
    o->split_mode = -1;
    o->prune = 1;
    ocean_result r = build_cascades(o, lattice, lw, nlw, msg, msglen);
    if (r != OCEAN_OK) {
        ocean_destroy(o);
        return r;
    }
    int n = p->n;
    {
        const cascade *fin = &o->cas[p->cascades - 1];
        double corner = M_SQRT2 * (n / 2 - 1) * fin->dk;
        o->k_top = fin->k_hi < corner ? fin->k_hi : corner;
    }
    o->spec = fftwf_malloc(sizeof(fftwf_complex) * CH_COUNT * (size_t)n * (n / 2 + 1));
    float *tmp = fftwf_malloc(sizeof(float) * CH_COUNT * (size_t)n * n);
    if (!o->spec || !tmp) {
        fftwf_free(tmp);
        if (msg) snprintf(msg, msglen, "out of memory for %d-point spectra", n);
        ocean_destroy(o);
        return OCEAN_ENOMEM;
    }
    pthread_mutex_lock(&planner_lock);
    unsigned flags;
    r = plan_flags(p, &flags, msg, msglen);
    if (r == OCEAN_OK)
        r = plan_all(o, tmp, flags, msg, msglen);
    pthread_mutex_unlock(&planner_lock);
    fftwf_free(tmp);
    if (r != OCEAN_OK) {
        ocean_destroy(o);
        return r;
    }
    *out = o;
    return OCEAN_OK;
}

void ocean_destroy(ocean *o)
{
    if (!o)
        return;
    pthread_mutex_lock(&planner_lock);
    for (int l = 0; l < MAX_LEVELS; l++)
        for (int c = 0; c < CH_COUNT; c++) {
            if (o->plan[l][c])
                fftwf_destroy_plan(o->plan[l][c]);
            if (o->cols_plan[l][c])
                fftwf_destroy_plan(o->cols_plan[l][c]);
            if (o->rows_plan[l][c])
                fftwf_destroy_plan(o->rows_plan[l][c]);
        }
    pthread_mutex_unlock(&planner_lock);
    fftwf_free(o->spec);
    for (int c = 0; c < OCEAN_MAX_CASCADES; c++) {
        cascade *cs = &o->cas[c];
        free(cs->turns_hi);
        free(cs->turns_lo);
        for (int j = 0; j < 4; j++) {
            free(cs->coef[j]);
            free(cs->cache[j]);
        }
        free(cs->kx);
        free(cs->k);
        free(cs->kinv);
        free(cs->var);
        free(cs->lo);
        free(cs->hi);
        free(cs->deep);
        free(cs->lw);
    }
    for (int i = 0; i < GAIN_PLANES; i++)
        free(o->gains[i].g);
    free(o);
}

void ocean_request_all(ocean_request *r, unsigned effects)
{
    memset(r, 0, sizeof *r);
    for (int c = 0; c < OCEAN_MAX_CASCADES; c++)
        r->effects[c] = effects;
    r->cutoff_k = INFINITY;
    r->order = 6;
    r->low_boost = 1.0;
    r->foam_map = 1;
}

/* Float arithmetic only, so the field pass below vectorises. */
static inline float foam_from_jacobian(float j)
{
    float f = 1.0f - j * (float)(1.0 / OCEAN_FOAM_J_CLEAR);
    return f < 0.0f ? 0.0f : (f > 1.0f ? 1.0f : f);
}

float ocean_foam_from_jacobian(float j)
{
    return foam_from_jacobian(j);
}

ocean_result ocean_frame_create(const ocean *o, ocean_frame **out)
{
    ocean_frame *f = calloc(1, sizeof *f);
    *out = NULL;
    if (!f)
        return OCEAN_ENOMEM;
    f->cascades = o->p.cascades;
    f->n_max = o->p.n;
    for (int c = 0; c < f->cascades; c++) {
        size_t nn = (size_t)o->p.n * o->p.n;
        f->block[c] = fftwf_malloc(sizeof(float) * CH_COUNT * nn);
        f->derived[c] = fftwf_malloc(sizeof(float) * 2 * nn);
        if (!f->block[c] || !f->derived[c]) {
            ocean_frame_destroy(f);
            return OCEAN_ENOMEM;
        }
        f->patch[c] = o->cas[c].patch;
    }
    *out = f;
    return OCEAN_OK;
}

void ocean_frame_destroy(ocean_frame *f)
{
    if (!f)
        return;
    for (int c = 0; c < OCEAN_MAX_CASCADES; c++) {
        fftwf_free(f->block[c]);
        fftwf_free(f->derived[c]);
    }
    free(f);
}

/* A filter whose gain over the whole band stays above 1 - 1e-6 changes
 * no float: the evaluation is the unfiltered one. */
#define NOOP_LOSS 1e-6

/* Waves the filter keeps at under drop_gain of their amplitude are not
 * transformed at all, so a cutoff kc needs a grid holding only
 * 1.096 kc (order 6, the default 1/2): that is what lets a low cutoff run
 * a smaller transform, as seed 000 intends.  The dropped waves count fully
 * in E_error, so the price is always reported. */
static inline double negligible_k(const ocean *o, double kc, int order)
{
    return ocean_filter_negligible_k(kc, order, o->p.drop_gain);
}

/* Which channels an effect mask needs, in block order; returns the count. */
static int channel_list(unsigned effects, int ch[CH_COUNT])
{
    int m = 0;
    if (effects & OCEAN_FX_HEIGHT) ch[m++] = CH_H;
    if (effects & OCEAN_FX_DISPLACEMENT) { ch[m++] = CH_DX; ch[m++] = CH_DZ; }
    if (effects & OCEAN_FX_NORMALS) { ch[m++] = CH_SX; ch[m++] = CH_SZ; }
    if (effects & OCEAN_FX_FOAM) { ch[m++] = CH_DXX; ch[m++] = CH_DZZ; ch[m++] = CH_DXZ; }
    if (effects & OCEAN_FX_VELOCITY) { ch[m++] = CH_VX; ch[m++] = CH_VY; ch[m++] = CH_VZ; }
    return m;
}

/* The gain a wave of wave number k actually gets: waves above kneg are not
 * transformed at all. */
static inline double effective_gain(double k, double kc, int order, double kneg)
{
    return k < kneg ? ocean_filter_gain(k, kc, order) : 0.0;
}

/* Sum over every mode of var * fn(gain), with the half-spectrum weights. */
static void filter_sums(const ocean *o, double kc, int order, double scale, double boost,
                        double *total, double *kept, double *err)
{
    double kneg = negligible_k(o, kc, order);
    int n = o->p.n, half = n / 2 + 1;
    *total = *kept = *err = 0.0;
    for (int c = 0; c < o->p.cascades; c++)
        for (size_t i = 0; i < (size_t)n * half; i++) {
            const cascade *cs = &o->cas[c];
            if (cs->var[i] == 0.0f)
                continue;
            double w = ((i % half) == 0 ? 1.0 : 2.0) * cs->var[i];
            double g = effective_gain(cs->k[i], kc, order, kneg);
            double ge = g * scale * (1.0 + (boost - 1.0) * g * g);
            *total += w;
            *kept += w * g * g;
            *err += w * (1.0 - ge) * (1.0 - ge);
        }
}

static int pick_size(const cascade *cs, int n_full, double kneg);

/* Std of the breaking index beta = sum k eta_k (foam.h) as a point sample
 * reads it: over the modes an evaluation with this filter transforms,
 * sum var k^2 ge^2 A(kx h) A(kz h), where A(th) = (2 + cos th) / 3 is the
 * mean power a wave keeps through bilinear interpolation on a grid of
 * spacing h at a uniformly random point (E|(1-u) + u e^{i th}|^2 over u).
 * Without A the finest cascade's near-Nyquist waves, which bilinear
 * reading damps, would count fully and tiles would show ~half the
 * intended coverage at light winds. */
static double foam_sigma_sum_of(const ocean *o, int only, double kc, int order, double scale, double boost)
{
    double kneg = negligible_k(o, kc, order), s = 0.0;
    int n = o->p.n, half = n / 2 + 1;
    for (int c = 0; c < o->p.cascades; c++) {
        if (only >= 0 && c != only)
            continue;
        const cascade *cs = &o->cas[c];
        if (cs->k_lo >= kneg)
            continue;
        double h = cs->patch / pick_size(cs, n, kneg);
        /* A per column and per row: |mx|, |mz| < n/2. */
        double a[OCEAN_MAX_N / 2];
        for (int m = 0; m < n / 2; m++)
            a[m] = (2.0 + cos(m * cs->dk * h)) / 3.0;
        for (size_t i = 0; i < (size_t)n * half; i++) {
            if (cs->var[i] == 0.0f)
                continue;
            int ix = (int)(i % half), iz = (int)(i / half), mz = iz < n / 2 ? iz : n - iz;
            double w = (ix == 0 ? 1.0 : 2.0) * cs->var[i];
            double g = isinf(kc) ? 1.0 : effective_gain(cs->k[i], kc, order, kneg);
            double ge = g * scale * (1.0 + (boost - 1.0) * g * g);
            double k = cs->k[i];
            s += w * k * k * ge * ge * a[ix < n / 2 ? ix : n / 2 - 1] * a[mz < n / 2 ? mz : n / 2 - 1];
        }
    }
    return sqrt(s);
}

static double foam_sigma_sum(const ocean *o, double kc, int order, double scale, double boost)
{
    return foam_sigma_sum_of(o, -1, kc, order, scale, boost);
}

static double foam_sigma(ocean *o, double kc, int order, double scale, double boost)
{
    int i = memo_find(o->foam_memo, kc, order, scale, boost);
    if (i >= 0)
        return o->foam_memo[i].value;
    double v = foam_sigma_sum(o, kc, order, scale, boost);
    memo_put(o->foam_memo, &o->foam_next, kc, order, scale, boost, v);
    return v;
}

/* sigma_beta of cascade c alone at cutoff kc, memoised beside the
 * whole-sea entries (a negative scale marks the cascade: real scales are
 * positive). */
static double foam_sigma_cascade(ocean *o, int c, double kc, int order)
{
    double tag = -1.0 - c;
    int i = memo_find(o->foam_memo, kc, order, tag, 1.0);
    if (i >= 0)
        return o->foam_memo[i].value;
    double v = foam_sigma_sum_of(o, c, kc, order, 1.0, 1.0);
    memo_put(o->foam_memo, &o->foam_next, kc, order, tag, 1.0, v);
    return v;
}

/* The whitecap ramp for a field of breaking-index std sigma (foam.h). */
/* The whitecap coverage of o's sea: the wind's, but none when the grid
 * holds no wave at all (Phillips A = 0, or k_max below every mode: no
 * breakers, whatever the wind says; it gave 0.93 % of foam on a flat sea).
 * A filter that removes every wave still leaves the sea's coverage, spread
 * evenly (foam.h). */
static double whitecap_target(const ocean *o)
{
    double energy = 0.0;
    for (int c = 0; c < o->p.cascades; c++)
        energy += o->cas[c].variance;
    return energy > 0.0 ? ocean_foam_coverage_target(o->p.sea.wind_u10) : 0.0;
}

static ocean_foam_map foam_map_for(const ocean *o, double sigma)
{
    ocean_foam_map m;
    if (ocean_foam_map_solve(sigma, whitecap_target(o), &m) != OCEAN_OK)
        m = (ocean_foam_map){INFINITY, INFINITY, -1.0};
    return m;
}

/* Beta from the summed foam channels lambda Dxx, lambda Dzz. */
static inline double foam_beta(double dxx, double dzz, double inv_lambda)
{
    return -(dxx + dzz) * inv_lambda;
}

/* Scale on the passed band that restores the unfiltered variance;
 * depends only on (cutoff, order). */
static double redistribution_scale(ocean *o, double kc, int order)
{
    int i = memo_find(o->redis_memo, kc, order, 1.0, 1.0);
    if (i >= 0)
        return o->redis_memo[i].value;
    double total, kept, err;
    filter_sums(o, kc, order, 1.0, 1.0, &total, &kept, &err);
    double v = kept > 0.0 ? sqrt(total / kept) : 1.0;
    memo_put(o->redis_memo, &o->redis_next, kc, order, 1.0, 1.0, v);
    return v;
}

/* E_error = ||H - H_f||_2 / ||H||_2 over the height spectrum, in
 * expectation (E|h(k,t)|^2 = var(k)), so it does not flicker with t and
 * counts the waves a smaller transform dropped. */
static double filter_error(ocean *o, double kc, int order, double scale, double boost)
{
    if (isinf(kc) && scale == 1.0 && boost == 1.0)
        return 0.0;
    int i = memo_find(o->err_memo, kc, order, scale, boost);
    if (i >= 0)
        return o->err_memo[i].value;
    double total, kept, err;
    filter_sums(o, kc, order, scale, boost, &total, &kept, &err);
    double v = total > 0.0 ? sqrt(err / total) : 0.0;
    memo_put(o->err_memo, &o->err_next, kc, order, scale, boost, v);
    return v;
}

ocean_result ocean_cascade_mips(const ocean *o, int c, int order, int max_mips, int *mips, double *kc)
{
    if (!o || c < 0 || c >= o->p.cascades || order < 1 || order > OCEAN_FILTER_MAX_ORDER || max_mips < 1 ||
        !mips || !kc)
        return OCEAN_EINVAL;
    const cascade *cs = &o->cas[c];
    int m = 0;
    kc[m++] = INFINITY;
    for (int n = o->p.n / 2; n >= OCEAN_MIN_N && m < max_mips; n /= 2) {
        double k = (double)(n / 4) * cs->dk;
        /* no wave of the band survives: this mip and all coarser are empty */
        if (cs->k_lo >= negligible_k(o, k, order))
            break;
        kc[m++] = k;
    }
    *mips = m;
    return OCEAN_OK;
}

ocean_result ocean_cascade_moments(const ocean *o, int c, double kc, int order, ocean_moments *out)
{
    if (!o || !out || c < 0 || c >= o->p.cascades || isnan(kc) || kc < 0.0 || order < 1 ||
        order > OCEAN_FILTER_MAX_ORDER)
        return OCEAN_EINVAL;
    const cascade *cs = &o->cas[c];
    double kneg = negligible_k(o, kc, order);
    int n = o->p.n, half = n / 2 + 1;
    double vh = 0, sx = 0, sz = 0, sxz = 0, total = 0, kh = 0, khtt = 0, ks = 0, kstt = 0;
    for (int row = 0; row < n; row++) {
        double kz = (row < n / 2 ? row : row - n) * cs->dk;
        for (int ix = 0; ix < half; ix++) {
            size_t i = (size_t)row * half + ix;
            if (cs->var[i] == 0.0f)
                continue;
            double w = (ix == 0 ? 1.0 : 2.0) * cs->var[i];
            double g = isinf(kc) ? 1.0 : effective_gain(cs->k[i], kc, order, kneg);
            double rem = w * (1.0 - g * g);
            double kx = cs->kx[ix];
            total += w;
            vh += rem;
            sx += rem * kx * kx;
            sz += rem * kz * kz;
            sxz += rem * kx * kz;
            double w2 = 2.0 * M_PI * (cs->turns_hi[i] + cs->turns_lo[i]), k2 = kx * kx + kz * kz;
            w2 *= w2;
            double kept = w * g * g;
            kh += kept;
            khtt += kept * w2 * w2;
            ks += kept * k2;
            kstt += kept * k2 * w2 * w2;
        }
    }
    out->kept_var_h = kh;
    out->kept_var_h_tt = khtt;
    out->kept_mss = ks;
    out->kept_mss_tt = kstt;
    out->var_h = vh;
    out->mss_x = sx;
    out->mss_z = sz;
    out->mss_xz = sxz;
    out->total_var_h = total;
    return OCEAN_OK;
}

double ocean_filtered_variance(const ocean *o, double cutoff_k, int order)
{
    double total, kept, err;
    filter_sums(o, cutoff_k, order, 1.0, 1.0, &total, &kept, &err);
    return kept;
}

/* x mod 2 pi in [-pi, pi], exact to a few ulp of pi (ocean_time.h); for
 * the spatial phases k.x of the reference sums (x already reduced modulo
 * the patch).  Time phases go through ocean_phase(w, t), which keeps the
 * product w t exact too. */
static inline double reduce_phase(double x)
{
    return ocean_phase(x, 1.0);
}

typedef struct stage_args {
    cascade *cs;
    int cached;             /* 1: read h from cs->cache, 0: compute and store */
    int need_dt;            /* dh/dt asked for (velocity channels) */
    int n_full, n;          /* full grid and the grid evaluated */
    int nch;
    const int *ch;
    double t, kc, kneg, scale, boost, lambda;
    int order;
    fftwf_complex *spec;
    float *gain;            /* gain plane of this bucket, or NULL (compute) */
    int gain_ready;         /* 1: gain holds the gains, 0: fill it */
    int fused;              /* 1: AVX2+FMA, 2: AVX-512 row pass (same bits) */
    int stream;             /* 1: write spec with streaming stores */
    int deep_table;         /* 1: read every frequency (ocean_force_frequency_table) */
} stage_args;

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
 * same w and phase (cascade_init fills turns from |k| alone; no current
 * makes w depend on direction): one phase and sin/cos serve both rows,
 * half the stage's trigonometry.  turns is the index of the row's first
 * mode in turns_hi/lo (FFTW's rows), row and mirror those of the two rows
 * in coef and cache (pair_row).  deep: the columns x0 .. x0 + count - 1
 * of rows +-sqrt(mz2) are deep water, so w / 2 pi is deep_turns, not read
 * (cs->deep).  Inlined with literal with_dt, pair and deep, so each
 * variant is one branch-free vector loop.  Out-of-band modes have
 * a = b = 0, so they need no branch either. */
static inline __attribute__((always_inline)) void
row_evolve(const cascade *cs, size_t turns, size_t row, size_t mirror, int count, double t,
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
        double f_hi = deep ? deep_turns(cf, mx * mx + mz2) : fh[ix];
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

/* Columns [*lo, *hi) of row pair p (rows p and n - p) of the n-point grid
 * that hold a wave: the cascade's range (cs->lo, hi) within this grid,
 * whose Nyquist row (p = n/2, mz = -n/2) and column are zero. */
static inline void pair_range(const cascade *cs, int n, int p, int *lo, int *hi)
{
    *lo = *hi = 0;
    if (p < n / 2) {
        *hi = cs->hi[p] < n / 2 ? cs->hi[p] : n / 2;
        *lo = cs->lo[p] < *hi ? cs->lo[p] : *hi;
    }
}

static inline __attribute__((always_inline)) void
spectrum_row_channels(const stage_args *a, int r, int x0, int x1, const int fused)
{
    int n = a->n, half = n / 2 + 1, full_half = a->n_full / 2 + 1;
    size_t plane = (size_t)n * half;
    int mz = r < n / 2 ? r : r - n;
    size_t base = pair_row(mz, a->n_full) * full_half;
    /* |k| and 1/|k| of rows mz and -mz are equal (kz enters squared): both
     * rows of a pair read row |mz|, so the second finds it in L1. */
    size_t kbase = (size_t)wrap_index(mz < 0 ? -mz : mz, a->n_full) * full_half;
    const cascade *cs = a->cs;
    float *c_hr = cs->cache[C_HR] + base, *c_hi = cs->cache[C_HI] + base;
    float *c_tr = cs->cache[C_TR] + base, *c_ti = cs->cache[C_TI] + base;
    const float *kx = cs->kx, *kinv = cs->kinv + kbase;
    const float *hr = c_hr, *hi = c_hi, *tr = c_tr, *ti = c_ti;
    float g[ROW_MAX], fhr[ROW_MAX], fhi[ROW_MAX], ftr[ROW_MAX], fti[ROW_MAX];
    /* Unfiltered, the grid is the full one: the cached h is the spectrum
     * as it stands.  Otherwise apply the gains.  Columns outside [x0, x1)
     * (no wave, or this grid's Nyquist column) are written as zeros. */
    if (!(isinf(a->kc) && a->scale == 1.0 && a->boost == 1.0 && n == a->n_full)) {
        float *gr = a->gain ? a->gain + (size_t)r * half : g;
        if (!a->gain_ready) {
            const float *kk = cs->k + kbase;
            float kc = (float)a->kc, kneg = (float)a->kneg, scale = (float)a->scale;
            float boost = (float)a->boost;
            for (int ix = x0; ix < x1; ix++) {
                float k = kk[ix], gb = k < kneg ? gain_fast(k, kc, a->order) : 0.0f;
                /* The low boost fades in with the gain (ocean_filter_cutoff_gain):
                 * no step at kc. */
                gr[ix] = gb * scale * (1.0f + (boost - 1.0f) * gb * gb);
            }
        }
        const float *restrict gv = gr;
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
        switch (a->ch[j]) {
        case CH_H:
            for (int ix = x0; ix < x1; ix++) { o[ix][0] = hr[ix]; o[ix][1] = hi[ix]; }
            break;
        case CH_DX: /* i k/|k| h */
            for (int ix = x0; ix < x1; ix++) {
                float f = lam * kx[ix] * kinv[ix];
                o[ix][0] = -f * hi[ix]; o[ix][1] = f * hr[ix];
            }
            break;
        case CH_DZ:
            for (int ix = x0; ix < x1; ix++) {
                float f = lam * kz * kinv[ix];
                o[ix][0] = -f * hi[ix]; o[ix][1] = f * hr[ix];
            }
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
        case CH_VX:
            for (int ix = x0; ix < x1; ix++) {
                float f = lam * kx[ix] * kinv[ix];
                o[ix][0] = -f * ti[ix]; o[ix][1] = f * tr[ix];
            }
            break;
        case CH_VY:
            for (int ix = x0; ix < x1; ix++) { o[ix][0] = tr[ix]; o[ix][1] = ti[ix]; }
            break;
        case CH_VZ:
            for (int ix = x0; ix < x1; ix++) {
                float f = lam * kz * kinv[ix];
                o[ix][0] = -f * ti[ix]; o[ix][1] = f * tr[ix];
            }
            break;
        }
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
        if (stream)
            spectrum_row_stream(&dst[0][0], &rowbuf[0][0], 2 * half);
#endif
    }
}

/* row_evolve for one span of a row pair, with_dt and pair made literal. */
static inline __attribute__((always_inline)) void
evolve_span(const stage_args *a, size_t turns, size_t row, size_t mirror, int count, int x0,
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
spectrum_row_body(const stage_args *a, int p, const int fused)
{
    int n = a->n, full_half = a->n_full / 2 + 1;
    int alone = p == 0 || p == n / 2;
    int mz = p < n / 2 ? p : p - n;
    int lo, hi;
    pair_range(a->cs, n, p, &lo, &hi);
    size_t turns = (size_t)wrap_index(mz, a->n_full) * full_half + (size_t)lo;
    size_t row = pair_row(mz, a->n_full) * full_half + (size_t)lo;
    size_t mirror = pair_row(-mz, a->n_full) * full_half + (size_t)lo;
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
static void spectrum_row_plain(const stage_args *a, int r)
{
    spectrum_row_body(a, r, 0);
}

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target("avx2,fma")))
static void spectrum_row_fused(const stage_args *a, int r)
{
    spectrum_row_body(a, r, 1);
}

/* The same source 16 floats wide.  With AVX2 the row loop runs out of
 * registers and reloads the sin/cos coefficients from the stack; 32
 * vector registers hold them (bench_core, "the spectrum stage's paths").
 * Same operations in the same order, no contraction (ISO C: no
 * -ffp-contract), so the same bits (tests/test_ocean.c). */
__attribute__((target("avx512f,avx512vl,avx512dq,avx512bw,avx2,fma,prefer-vector-width=512")))
static void spectrum_row_wide(const stage_args *a, int r)
{
    spectrum_row_body(a, r, 1);
}
#endif

static void spectrum_row(const stage_args *a, int r)
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

/* Jacobian J = (1 + Dxx)(1 + Dzz) - Dxz^2 and foam for rows [r0, r1) of an
 * n-point field; cloned for AVX2 like spectrum_row. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
static void jacobian_rows(ocean_field *fd, long i0, long i1, const ocean_foam_map *m,
                          double inv_lambda)
{
    const float *restrict xx = fd->dxx, *restrict zz = fd->dzz, *restrict xz = fd->dxz;
    float *restrict jac = fd->jacobian, *restrict foam = fd->foam;
    for (long i = i0; i < i1; i++)
        jac[i] = (1.0f + xx[i]) * (1.0f + zz[i]) - xz[i] * xz[i];
    /* foam = clamp((beta - a) / (b - a)) as ocean_foam_value, in float so
     * the pass vectorises; a constant field, or a step, otherwise. */
    if (m->uniform >= 0.0 || !(m->b > m->a)) {
        for (long i = i0; i < i1; i++)
            foam[i] = (float)ocean_foam_value(m, foam_beta(xx[i], zz[i], inv_lambda));
        return;
    }
    float s = (float)(-inv_lambda / (m->b - m->a)), off = (float)(-m->a / (m->b - m->a));
    for (long i = i0; i < i1; i++) {
        float f = (xx[i] + zz[i]) * s + off;
        foam[i] = f < 0.0f ? 0.0f : (f > 1.0f ? 1.0f : f);
    }
}

/* Smallest grid whose band holds every wave below kneg: halving n keeps
 * |m| <= n/4 - 1, so it is allowed while (n/4 - 1) dk >= kneg. */
static int pick_size(const cascade *cs, int n_full, double kneg)
{
    int n = n_full;
    while (n > OCEAN_MIN_N && (n / 4 - 1) * cs->dk >= kneg)
        n /= 2;
    return n;
}

static int level_of(int n)
{
    int l = 0;
    while ((8 << l) < n)
        l++;
    return l;
}

static void set_field_pointers(ocean_frame *f, int c, int n, unsigned effects,
                               const int *ch, int nch, int foam_map)
{
    ocean_field *fd = &f->field[c];
    memset(fd, 0, sizeof *fd);
    fd->n = n;
    fd->patch_m = f->patch[c];
    fd->effects = effects;
    size_t nn = (size_t)n * n;
    for (int j = 0; j < nch; j++) {
        float *p = f->block[c] + (size_t)j * nn;
        switch (ch[j]) {
        case CH_H: fd->height = p; break;
        case CH_DX: fd->dx = p; break;
        case CH_DZ: fd->dz = p; break;
        case CH_SX: fd->slope_x = p; break;
        case CH_SZ: fd->slope_z = p; break;
        case CH_DXX: fd->dxx = p; break;
        case CH_DZZ: fd->dzz = p; break;
        case CH_DXZ: fd->dxz = p; break;
        case CH_VX: fd->vel_x = p; break;
        case CH_VY: fd->vel_y = p; break;
        case CH_VZ: fd->vel_z = p; break;
        }
    }
    if ((effects & OCEAN_FX_FOAM) && foam_map) {
        fd->jacobian = f->derived[c];
        fd->foam = f->derived[c] + nn;
    }
}

/* The gain plane of (cascade, n, filter), found or claimed (least recently
 * used).  *ready says whether it already holds the gains.  NULL when
 * memory runs out: the rows then compute their gains as they go, so an
 * allocation failure costs time, never a wrong field. */
static float *gain_plane_get(ocean *o, int c, int n, double kc, int order, double scale,
                             double boost, int *ready)
{
    gain_plane *victim = &o->gains[0];
    uint64_t now = ++o->gain_clock;
    for (int i = 0; i < GAIN_PLANES; i++) {
        gain_plane *gp = &o->gains[i];
        if (gp->used && gp->cascade == c && gp->n == n && gp->kc == kc && gp->order == order &&
            gp->scale == scale && gp->boost == boost) {
            gp->used = now;
            *ready = 1;
            return gp->g;
        }
        if (gp->used < victim->used)
            victim = gp;
    }
    size_t need = (size_t)n * (n / 2 + 1);
    if (victim->cap < need) {
        float *g = realloc(victim->g, sizeof(float) * need);
        if (!g) {
            *ready = 0;
            return NULL;
        }
        victim->g = g;
        victim->cap = need;
    }
    *victim = (gain_plane){c, n, order, kc, scale, boost, now, victim->cap, victim->g};
    *ready = 0;
    return victim->g;
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

static void stage_split(const cascade *cs, int n, int nt, int *b)
{
    double w[OCEAN_MAX_N / 2 + 1], total = 0.0;
    for (int p = 0; p <= n / 2; p++) {
        int lo, hi;
        pair_range(cs, n, p, &lo, &hi);
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
static void stage_rows(const cascade *cs, int n, int nt, const int *b, int *r0, int *r1)
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
    stage_split(cs, n, m, mine);
    *r0 = mine[t];
    *r1 = mine[t + 1];
}

/* Monotonic nanoseconds, for ocean_counters' time split. */
static inline uint64_t now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
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
static void stage_channels(int gn, int *c0, int *c1)
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
 * (stage_channels) when the call has a channel for every thread, else by
 * rows (stage_rows).  By channel, an evolving pass (a->cached = 0) first
 * evolves this member's rows and writes its channels there from h in L1,
 * then, once every row's h(k,t) and gains are in place, its channels in
 * the other rows from the cache. */
static void stage_pass(const stage_args *a, int nt, const int *split, size_t plane, int by_channel)
{
    const cascade *cs = a->cs;
    int n = a->n, r0, r1;
    stage_rows(cs, n, nt, split, &r0, &r1);
    if (!by_channel) {
        for (int p = r0; p < r1; p++)
            spectrum_row(a, p);
        return;
    }
    int c0, c1;
    stage_channels(a->nch, &c0, &c1);
    stage_args my = *a;
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

/* Channels per FFTW call on the n-point grid.  Eight spectra at N = 1024
 * are 34 MB, more than a last-level cache holds, so one batched transform
 * found what the row pass wrote already evicted and ran from memory; in
 * groups of at most GROUP_BYTES of spectra, each group's row pass writes
 * into the same region of o->spec and its transform reads it from the cache
 * (bench_core, "Channels per FFTW call").  A constant rather than the
 * machine's cache size: the plans a group uses, and so the bits, must not
 * depend on the host (replicas agree bit for bit). */
#define GROUP_BYTES 8.5e6

static int group_size(const ocean *o, int n, int nch)
{
    if (o->group > 0)
        return o->group < nch ? o->group : nch;
    double per = (double)n * (n / 2 + 1) * sizeof(fftwf_complex);
    int g = (int)(GROUP_BYTES / per);
    return g < 1 ? 1 : g < nch ? g : nch;
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

/* The least of split s's recent costs (split_stat). */
static double split_min(const split_stat *st, int s)
{
    double m = INFINITY;
    for (int i = 0; i < st->have[s]; i++)
        m = st->ns[s][i] < m ? st->ns[s][i] : m;
    return m;
}

/* split_pick's choice without a probe: the split the stage runs now. */
static int split_best(const ocean *o, const split_stat *st)
{
    if (o->split_mode >= 0)
        return o->split_mode;
    return st->have[0] && st->have[1] && split_min(st, 1) < split_min(st, 0);
}

/* The split (0 rows, 1 channels) for the next evaluation of a kind: each
 * measured once first, then the faster with a probe of the other. */
static int split_pick(const ocean *o, split_stat *st)
{
    if (o->split_mode >= 0)
        return o->split_mode;
    if (!st->have[0])
        return 0;
    if (!st->have[1])
        return 1;
    int best = split_best(o, st);
    return ++st->evals % SPLIT_PROBE == 0 ? !best : best;
}

static void split_note(split_stat *st, int split, double ns)
{
    st->ns[split][st->next[split]] = ns;
    st->next[split] = (uint8_t)((st->next[split] + 1) % SPLIT_WINDOW);
    if (st->have[split] < SPLIT_WINDOW)
        st->have[split]++;
}

void ocean_force_group(ocean *o, int group)
{
    if (o)
        o->group = group > 0 && group <= CH_COUNT ? group : 0;
}

double ocean_effective_cutoff(const ocean *o, double cutoff_k, int order)
{
    if (isnan(cutoff_k) || cutoff_k < 0.0 || order < 1 || order > OCEAN_FILTER_MAX_ORDER)
        return NAN;
    if (isinf(cutoff_k) || ocean_filter_gain(o->k_top, cutoff_k, order) >= 1.0 - NOOP_LOSS)
        return INFINITY;
    return cutoff_k;
}

/* One FFTW call: the 2-D c2r of gn channels of cascade cs's n-point
 * spectra at o->spec into out.  A cascade whose waves all lie in the
 * first prune_cols columns (the coarse cascades: a half disc of radius
 * n/4) runs the 2-D transform as its two passes and leaves the column
 * pass out where no wave is: those columns are zero on input and stay
 * zero through it, so the result is the same transform (bench_core: the
 * column pass is about half of FFTW's work).  Returns 1 when pruned. */
static int transform_call(ocean *o, const cascade *cs, int n, int gn, float *out)
{
    int l = level_of(n);
    if (o->prune && o->prune_cols[l] && cs->width[l] <= o->prune_cols[l]) {
        fftwf_execute_dft(o->cols_plan[l][gn - 1], o->spec, o->spec);
        fftwf_execute_dft_c2r(o->rows_plan[l][gn - 1], o->spec, out);
        return 1;
    }
    fftwf_execute_dft_c2r(o->plan[l][gn - 1], o->spec, out);
    return 0;
}

void ocean_force_pruning(ocean *o, int prune)
{
    if (o)
        o->prune = prune != 0;
}

static ocean_result request_check(const ocean *o, double t, const ocean_request *r,
                                  const ocean_frame *f)
{
    if (!o || !r || !f || f->cascades != o->p.cascades || f->n_max != o->p.n)
        return OCEAN_EINVAL;
    if (!ocean_time_ok(t) || isnan(r->cutoff_k) || r->cutoff_k < 0.0 || r->order < 1 ||
        r->order > OCEAN_FILTER_MAX_ORDER || !isfinite(r->low_boost) || r->low_boost < 0.0 || r->low_boost > 2.0)
        return OCEAN_EINVAL;
    if (r->per_cascade) {
        if (r->redistribute || (r->low_boost != 0.0 && r->low_boost != 1.0))
            return OCEAN_EINVAL;
        for (int c = 0; c < o->p.cascades; c++)
            if (isnan(r->cascade_cutoff_k[c]) || r->cascade_cutoff_k[c] < 0.0)
                return OCEAN_EINVAL;
    }
    return OCEAN_OK;
}

/* The filter of one evaluation, as every cascade applies it unless the
 * request gives each its own cutoff. */
typedef struct eval_filter {
    double kc, kneg, scale, boost;
} eval_filter;

/* The frame's foam mapping.  The whitecap ramp depends on the filter, not
 * on t: memoised. */
static void frame_foam_setup(ocean *o, const ocean_request *r, const eval_filter *ef, ocean_frame *f)
{
    int any_foam = 0;
    for (int c = 0; c < o->p.cascades; c++)
        any_foam |= (r->effects[c] & OCEAN_FX_FOAM) != 0;
    double lam = o->p.sea.choppiness;
    f->foam_inv_lambda = lam > 0.0 ? 1.0 / lam : 0.0;
    f->info.foam_sigma = any_foam ? foam_sigma(o, ef->kc, r->order, ef->scale, ef->boost) : 0.0;
    f->info.whitecap_target = whitecap_target(o);
    f->foam_map = foam_map_for(o, f->info.foam_sigma);
}

/* Modes of the n-point grid an evolving pass computed, and of those the
 * deep-water ones (ocean_counters). */
static void count_evolved(ocean *o, const cascade *cs, int n)
{
    for (int p = 0; p <= n / 2; p++) {
        int lo, hi;
        pair_range(cs, n, p, &lo, &hi);
        int rows = p == 0 || p == n / 2 ? 1 : 2, d = o->deep_table ? hi : cs->deep[p];
        o->counters.modes_evolved += (uint64_t)(hi - lo) * rows;
        o->counters.modes_deep += (uint64_t)(hi - (d > lo ? (d < hi ? d : hi) : lo)) * rows;
    }
}

/* One FFTW call's a->nch channels: the stage pass writes their spectra
 * (the first call of the tick evolving h(k,t) into the cache, the others
 * reading it back), then FFTW transforms them into out. */
static void stage_and_transform(ocean *o, stage_args *a, int nt, const int *split, size_t plane,
                                int by_channel, float *out)
{
    cascade *cs = a->cs;
    int n = a->n, gn = a->nch;
    uint64_t t0 = now_ns();
#pragma omp parallel num_threads(nt) if (nt > 1)
    stage_pass(a, nt, split, plane, by_channel && gn >= nt);
    uint64_t t1 = now_ns();
    *(a->cached ? &o->counters.ns_channels : &o->counters.ns_evolve) += t1 - t0;
    if (!a->cached) {
        count_evolved(o, cs, n);
        cs->cache_t = a->t;
        cs->cache_n = n;
        cs->cache_dt = a->need_dt;
        a->cached = 1;
    }
    a->gain_ready = a->gain != NULL;
    uint64_t t2 = now_ns();
    o->counters.fft_calls_pruned += transform_call(o, cs, n, gn, out);
    o->counters.ns_fft += now_ns() - t2;
    o->counters.fft_calls++;
    o->counters.fft_calls_by_channel += by_channel && gn >= nt;
}

/* Every channel a->ch[0 .. a->nch) of cascade c into the frame's block,
 * in FFTW calls of group_size channels. */
static void cascade_transform(ocean *o, int c, stage_args *a, ocean_frame *f)
{
    const cascade *cs = a->cs;
    int n = a->n, nch = a->nch;
    const int *ch = a->ch;
    /* Claimed here, where every row fills it, never for a cascade wholly
     * above the cutoff: a claimed plane is trusted from then on. */
    if (!(isinf(a->kc) && a->scale == 1.0 && a->boost == 1.0 && n == a->n_full))
        a->gain = gain_plane_get(o, c, n, a->kc, a->order, a->scale, a->boost, &a->gain_ready);
    int g = group_size(o, n, nch);
    int nt = n >= PARALLEL_MIN_N ? o->p.threads : 1, split[STAGE_MAX_THREADS + 1];
    size_t plane = (size_t)n * (n / 2 + 1);
    stage_split(cs, n, nt, split);
    /* Split by channel or by rows: the same bits, but which is faster
     * depends on how busy this machine's caches are (stage_channels), so
     * the ocean measures both and runs the faster.  Only where a call has
     * a channel for every thread. */
    split_stat *st = &o->split[c][level_of(n)][a->cached];
    int by_channel = nt > 1 && (g < nch ? g : nch) >= nt ? split_pick(o, st) : 0;
    uint64_t c_start = now_ns();
    for (int j0 = 0; j0 < nch; j0 += g) {
        int gn = nch - j0 < g ? nch - j0 : g;
        a->ch = ch + j0;
        a->nch = gn;
        a->stream = (double)gn * n * (n / 2 + 1) * sizeof(fftwf_complex) > o->stream_bytes;
        stage_and_transform(o, a, nt, split, plane, by_channel, f->block[c] + (size_t)j0 * n * n);
    }
    if (nt > 1 && (g < nch ? g : nch) >= nt)
        split_note(st, by_channel, (double)(now_ns() - c_start) / nch);
    for (int j = 0; j < nch; j++) {
        int e = ch[j] == CH_H ? 0 : ch[j] <= CH_DZ ? 1 : ch[j] <= CH_SZ ? 2
              : ch[j] <= CH_DXZ ? 3 : 4;
        o->counters.transforms_by_effect[e]++;
    }
}

/* Cascade c's fields for request r; returns the transforms run. */
static int evaluate_cascade(ocean *o, int c, double t, const ocean_request *r,
                            const eval_filter *ef, ocean_frame *f)
{
    cascade *cs = &o->cas[c];
    int n_full = o->p.n;
    double kc = ef->kc, kneg = ef->kneg;
    if (r->per_cascade) {
        kc = r->cascade_cutoff_k[c];
        kneg = negligible_k(o, kc, r->order);
    }
    unsigned fx = r->effects[c] & (OCEAN_FX_ALL | OCEAN_FX_VELOCITY);
    int ch[CH_COUNT];
    int nch = channel_list(fx, ch);
    /* A cascade wholly above the cutoff contributes zero fields at the
     * smallest size: nothing to transform. */
    int n = cs->k_lo >= kneg ? OCEAN_MIN_N : pick_size(cs, n_full, kneg);
    set_field_pointers(f, c, n, fx, ch, nch, r->foam_map);
    if (nch == 0)
        return 0;
    int transforms = 0;
    if (cs->k_lo >= kneg) {
        memset(f->block[c], 0, sizeof(float) * nch * (size_t)n * n);
    } else {
        /* The row pass caches every mode of the grid it covers, so any
         * later request of the same tick on a grid no larger reuses it. */
        int need_dt = (fx & OCEAN_FX_VELOCITY) != 0;
        int cached = cs->cache_n >= n && cs->cache_t == t && (cs->cache_dt || !need_dt);
        stage_args a = {cs, cached, need_dt, n_full, n, nch, ch, t, kc, kneg, ef->scale, ef->boost,
                        o->p.sea.choppiness, r->order, o->spec, NULL, 0, o->fused,
                        (double)nch * n * (n / 2 + 1) * sizeof(fftwf_complex) > o->stream_bytes,
                        o->deep_table};
        cascade_transform(o, c, &a, f);
        transforms = nch;
    }
    /* Per-cascade mips (the cascade tile layout): each cascade's foam is
     * placed by its own breaking index at its own cutoff, with the whole
     * sea's coverage W (foam.h); the daemon asks foam of one cascade only,
     * so W is not counted twice. */
    ocean_foam_map cmap = f->foam_map;
    if (r->per_cascade && (fx & OCEAN_FX_FOAM))
        cmap = foam_map_for(o, foam_sigma_cascade(o, c, kc, r->order));
    if ((fx & OCEAN_FX_FOAM) && r->foam_map) {
        ocean_field *fd = &f->field[c];
        long nn = (long)n * n, step = (long)n * 8;
#pragma omp parallel for num_threads(o->p.threads) schedule(static) if (n >= PARALLEL_MIN_N)
        for (long i = 0; i < nn; i += step)
            jacobian_rows(fd, i, i + step < nn ? i + step : nn, &cmap, f->foam_inv_lambda);
    }
    return transforms;
}

ocean_result ocean_evaluate(ocean *o, double t, const ocean_request *r, ocean_frame *f)
{
    ocean_result res = request_check(o, t, r, f);
    if (res != OCEAN_OK)
        return res;
    eval_filter ef;
    ef.kc = ocean_effective_cutoff(o, r->cutoff_k, r->order);
    ef.kneg = negligible_k(o, ef.kc, r->order);
    ef.scale = r->redistribute && !isinf(ef.kc) ? redistribution_scale(o, ef.kc, r->order) : 1.0;
    ef.boost = r->low_boost > 0.0 ? r->low_boost : 1.0;
    frame_foam_setup(o, r, &ef, f);
    int transforms = 0;
    for (int c = 0; c < o->p.cascades; c++)
        transforms += evaluate_cascade(o, c, t, r, &ef, f);
    f->info.t = t;
    f->info.cutoff_k = r->per_cascade ? NAN : ef.kc;
    f->info.transforms = transforms;
    f->info.cascades = o->p.cascades;
    f->info.e_error = r->per_cascade ? 0.0 : filter_error(o, ef.kc, r->order, ef.scale, ef.boost);
    o->counters.evaluations++;
    o->counters.transforms += (uint64_t)transforms;
    return OCEAN_OK;
}

/* The FFTW calls of ocean_evaluate(o, ., r, f); with write_spectra, each
 * call's spectra are first overwritten with zeros, split over the threads
 * as the stage would split an evolving pass now (split_best: by channel,
 * or by row pairs). */
static ocean_result transform_groups(ocean *o, const ocean_request *r, ocean_frame *f, int write_spectra)
{
    if (!o || !r || !f || f->cascades != o->p.cascades || isnan(r->cutoff_k) ||
        r->cutoff_k < 0.0 || r->order < 1 || r->order > OCEAN_FILTER_MAX_ORDER)
        return OCEAN_EINVAL;
    double kneg = negligible_k(o, ocean_effective_cutoff(o, r->cutoff_k, r->order), r->order);
    for (int c = 0; c < o->p.cascades; c++) {
        const cascade *cs = &o->cas[c];
        int ch[CH_COUNT];
        int nch = channel_list(r->effects[c] & (OCEAN_FX_ALL | OCEAN_FX_VELOCITY), ch);
        if (nch == 0 || cs->k_lo >= kneg)
            continue;
        int n = pick_size(cs, o->p.n, kneg), half = n / 2 + 1;
        size_t plane = (size_t)n * half;
        int g = group_size(o, n, nch);
        int nt = n >= PARALLEL_MIN_N ? o->p.threads : 1, split[STAGE_MAX_THREADS + 1];
        stage_split(cs, n, nt, split);
        for (int j0 = 0; j0 < nch; j0 += g) {
            int gn = nch - j0 < g ? nch - j0 : g;
            if (write_spectra && nt > 1 && gn >= nt && split_best(o, &o->split[c][level_of(n)][0])) {
#pragma omp parallel num_threads(nt)
                {
                    int c0, c1;
                    stage_channels(gn, &c0, &c1);
                    memset(o->spec + (size_t)c0 * plane, 0, sizeof(fftwf_complex) * plane * (size_t)(c1 - c0));
                }
            } else if (write_spectra) {
#pragma omp parallel num_threads(nt) if (nt > 1)
                {
                    int r0, r1;
                    stage_rows(cs, n, nt, split, &r0, &r1);
                    for (int p = r0; p < r1; p++)
                        for (int j = 0; j < gn; j++) {
                            fftwf_complex *row = o->spec + (size_t)j * plane;
                            memset(row + (size_t)p * half, 0, sizeof(fftwf_complex) * half);
                            if (p != 0 && p != n / 2)
                                memset(row + (size_t)(n - p) * half, 0, sizeof(fftwf_complex) * half);
                        }
                }
            }
            transform_call(o, cs, n, gn, f->block[c] + (size_t)j0 * n * n);
        }
    }
    return OCEAN_OK;
}

ocean_result ocean_transform_only(ocean *o, const ocean_request *r, ocean_frame *f)
{
    return transform_groups(o, r, f, 0);
}

ocean_result ocean_transform_floor(ocean *o, const ocean_request *r, ocean_frame *f)
{
    return transform_groups(o, r, f, 1);
}

const ocean_field *ocean_frame_field(const ocean_frame *f, int cascade)
{
    if (!f || cascade < 0 || cascade >= f->cascades)
        return NULL;
    return &f->field[cascade];
}

void ocean_frame_get_info(const ocean_frame *f, ocean_frame_info *out)
{
    *out = f->info;
}

/* Where (x, z) falls on a cascade's periodic grid.  Reduced in double
 * first: x = 1e7 m keeps sub-millimetre position. */
typedef struct cell {
    int i0, j0;
    double fx, fz;
} cell;

/* floor() for |u| < 2^62 without a libm call (the baseline x86-64 target
 * has no rounding instruction); the same value as floor(u). */
static inline double floor_fast(double u)
{
    double t = (double)(long long)u;
    return t > u ? t - 1.0 : t;
}

static inline cell locate(const ocean_field *fd, double x, double z)
{
    int n = fd->n;
    double u = x / fd->patch_m, v = z / fd->patch_m;
    /* Any real world position is far inside floor_fast's range. */
    u = (u - (fabs(u) < 4e18 ? floor_fast(u) : floor(u))) * n;
    v = (v - (fabs(v) < 4e18 ? floor_fast(v) : floor(v))) * n;
    cell c = {(int)v, (int)u, 0.0, 0.0};
    if (c.j0 >= n) c.j0 = n - 1;
    if (c.i0 >= n) c.i0 = n - 1;
    c.fx = u - c.j0;
    c.fz = v - c.i0;
    return c;
}

/* The four corners of a cell, located once per cascade and shared by every
 * channel read there; bilinear in double, (a (1-fx) + b fx)(1-fz) + (c (1-fx) + d fx) fz. */
typedef struct corners {
    size_t o00, o01, o10, o11;
    double fx, fz;
} corners;

static inline corners corners_of(const ocean_field *fd, double x, double z)
{
    cell q = locate(fd, x, z);
    int n = fd->n, i1 = (q.i0 + 1) & (n - 1), j1 = (q.j0 + 1) & (n - 1);
    size_t r0 = (size_t)q.i0 * n, r1 = (size_t)i1 * n;
    return (corners){r0 + q.j0, r0 + j1, r1 + q.j0, r1 + j1, q.fx, q.fz};
}

static inline double corners_read(const float *g, const corners *k)
{
    double a = g[k->o00], b = g[k->o01], c = g[k->o10], d = g[k->o11];
    return (a * (1.0 - k->fx) + b * k->fx) * (1.0 - k->fz) + (c * (1.0 - k->fx) + d * k->fx) * k->fz;
}

/* Sums go to locals and reach *out once at the end: stores through out
 * (doubles) could alias the field descriptors' doubles, and the compiler
 * would reload every descriptor after every store.  This is the daemon's
 * per-vertex hot path (one call per mesh vertex per client frame). */
void ocean_frame_sample_some(const ocean_frame *f, double x, double z, unsigned want,
                             ocean_point *out)
{
    double h = 0, dx = 0, dz = 0, sx = 0, sz = 0, vx = 0, vy = 0, vz = 0;
    double dxx = 0.0, dzz = 0.0, dxz = 0.0;
    int any_foam = 0;
    for (int c = 0; c < f->cascades; c++) {
        const ocean_field *fd = &f->field[c];
        if (!fd->effects)
            continue;
        const corners k = corners_of(fd, x, z);
        /* A group not wanted reads as a channel not evaluated. */
        if ((want & OCEAN_SAMPLE_HEIGHT) && fd->height)
            h += corners_read(fd->height, &k);
        if (want & OCEAN_SAMPLE_DISPLACEMENT) {
            if (fd->dx) dx += corners_read(fd->dx, &k);
            if (fd->dz) dz += corners_read(fd->dz, &k);
        }
        if (want & OCEAN_SAMPLE_SLOPE) {
            if (fd->slope_x) sx += corners_read(fd->slope_x, &k);
            if (fd->slope_z) sz += corners_read(fd->slope_z, &k);
        }
        if (want & OCEAN_SAMPLE_VELOCITY) {
            if (fd->vel_x) vx += corners_read(fd->vel_x, &k);
            if (fd->vel_y) vy += corners_read(fd->vel_y, &k);
            if (fd->vel_z) vz += corners_read(fd->vel_z, &k);
        }
        if ((want & OCEAN_SAMPLE_FOAM) && fd->dxx) {
            any_foam = 1;
            dxx += corners_read(fd->dxx, &k);
            dzz += corners_read(fd->dzz, &k);
            dxz += corners_read(fd->dxz, &k);
        }
    }
    /* J of the summed displacement, not a sum of per-cascade Jacobians. */
    double jac = (1.0 + dxx) * (1.0 + dzz) - dxz * dxz;
    *out = (ocean_point){.height = h, .dx = dx, .dz = dz, .slope_x = sx, .slope_z = sz,
                         .jacobian = jac,
                         .foam = any_foam ? ocean_foam_value(&f->foam_map,
                                                             foam_beta(dxx, dzz, f->foam_inv_lambda))
                                          : 0.0,
                         .vel_x = vx, .vel_y = vy, .vel_z = vz, .dxx = dxx, .dzz = dzz, .dxz = dxz};
}

double ocean_frame_foam(const ocean_frame *f, double dxx, double dzz)
{
    int any = 0;
    for (int c = 0; c < f->cascades; c++)
        any |= f->field[c].dxx != NULL;
    return any ? ocean_foam_value(&f->foam_map, foam_beta(dxx, dzz, f->foam_inv_lambda)) : 0.0;
}

void ocean_frame_sample(const ocean_frame *f, double x, double z, ocean_point *out)
{
    ocean_frame_sample_some(f, x, z, OCEAN_SAMPLE_ALL, out);
}

void ocean_frame_sample_displacement(const ocean_frame *f, double x, double z,
                                     double *dx, double *dz)
{
    double sx = 0.0, sz = 0.0;
    for (int c = 0; c < f->cascades; c++) {
        const ocean_field *fd = &f->field[c];
        if (!fd->dx)
            continue;
        const corners k = corners_of(fd, x, z);
        sx += corners_read(fd->dx, &k);
        sz += corners_read(fd->dz, &k);
    }
    *dx = sx;
    *dz = sz;
}

/* ---- accurate reading ------------------------------------------------------
 *
 * Bilinear reading of a grid that holds waves up to half its Nyquist rate
 * (coarse cascades) or up to it (the finest) leaves centimetres between
 * grid points: the error is ~ (k h)^2 / 8 of each wave's amplitude, and
 * the coarse cascades put metres of amplitude near k h = pi / 2.  The FFT
 * already gives each field's exact first derivatives at the grid points
 * (slopes for the height, the foam channel's Dxx, Dxz, Dzz for the
 * displacement), so the height and the displacement are read by Hermite
 * interpolation: value and first derivatives at every node, tensor product
 * of the 1-D Hermite interpolant on the 4 nodes -1..2 (degree 7),
 * H_k = (1 - 2 l_k'(x_k)(t - x_k)) l_k^2, K_k = (t - x_k) l_k^2 with l_k
 * the Lagrange basis (Hildebrand, Introduction to Numerical Analysis,
 * 1974, sec. 8.2).  Its 1-D error on a wave of k h = 1, pi/2, pi is 7e-6,
 * 2.5e-4, 4e-2 of the amplitude, against 0.12, 0.29, 1 for bilinear (six
 * nodes would give 2e-8, 5e-6, 9e-3, but cost four times as much for a
 * third less error on the storm scene).  The tensor product needs the cross
 * derivative f_xz at the nodes, which no channel holds: the mean of the
 * differences of f_x along z and of f_z along x, sixth-order central on
 * the coarse cascades (k h <= pi / 2), a 21-point least-squares stencil on
 * the finest, whose diagonal waves reach k h = 2.2 where the sixth-order
 * difference is 30 % off (wide_w).  Channels without derivatives
 * (slopes, velocity, Dxx...) are read by 4 x 4 cubic Lagrange.
 *
 * Measured on the storm scene (Beaufort 10, 3 cascades of N = 256, the
 * finest to its Nyquist rate) against the direct sum of every mode in
 * double: height 0.07 mm RMS, 0.24 mm worst; bilinear 6 cm, 18 cm (1.2 us
 * against 0.15 us per reading of every channel, bench_near).
 *
 * Error bound: per wave, the interpolation error divided by the response
 * of the fourth difference (2 sin(k h / 2))^4 grows with k h, so over a
 * band that stops at k h = pi / 2 (coarse cascades) or pi (the finest) it
 * is at most its value there; the fourth differences of the nodes around
 * the point, along x and along z, measure the local amplitude of exactly
 * the waves that matter (hermite_read). */

#define ACC_REACH 11                  /* nodes -11 .. 12 around the cell */
#define ACC_SPAN (2 * ACC_REACH + 2)
#define ACC_MAXN 4

typedef struct stencil {
    size_t row[ACC_SPAN];             /* offsets of rows i0 - 11 .. i0 + 12 */
    int col[ACC_SPAN];                /* columns j0 - 11 .. j0 + 12 */
    int nodes, first;                 /* Hermite nodes first .. first + nodes - 1 */
    double hu[ACC_MAXN], ku[ACC_MAXN];/* Hermite value and slope bases along x */
    double hv[ACC_MAXN], kv[ACC_MAXN];/* and along z */
    double lu[4], lv[4];              /* cubic Lagrange, nodes -1..2 */
    double h;                         /* grid spacing, m */
    /* The cross-derivative term folded into one weight per row (wz, for
     * f_x differenced along z) and per column (wx, f_z along x), offsets
     * -11 .. 12 by index + ACC_REACH, nonzero in [lo, hi] (stencil_of). */
    double wz[ACC_SPAN], wx[ACC_SPAN];
    int lo, hi;
    int contig;                       /* columns lo .. hi do not wrap */
    size_t off[ACC_MAXN * ACC_MAXN];  /* the 4 x 4 nodes' offsets, row-major */
} stencil;

static void lagrange4(double t, double w[4])
{
    w[0] = -t * (t - 1.0) * (t - 2.0) / 6.0;
    w[1] = (t + 1.0) * (t - 1.0) * (t - 2.0) / 2.0;
    w[2] = -(t + 1.0) * t * (t - 2.0) / 2.0;
    w[3] = (t + 1.0) * t * (t - 1.0) / 6.0;
}

/* Hermite bases on the nodes -1..2 at t, from their Lagrange basis l
 * (lagrange4): H_k = (1 - 2 l_k'(x_k)(t - x_k)) l_k^2, K_k = (t - x_k) l_k^2,
 * where l_k'(x_k) = sum over m != k of 1 / (x_k - x_m). */
static void hermite4(double t, const double l[4], double *hv, double *kv)
{
    static const double lp[4] = {-11.0 / 6.0, -0.5, 0.5, 11.0 / 6.0};
    for (int k = 0; k < 4; k++) {
        double d = t - (k - 1), l2 = l[k] * l[k];
        hv[k] = (1.0 - 2.0 * lp[k] * d) * l2;
        kv[k] = d * l2;
    }
}

/* h times the derivative along one axis at a node, as differences of the
 * nodes m = 1 .. reach away: weights of (node + m) - (node - m).  Sixth-
 * order central for the coarse cascades (k h <= pi / 2). */
static const double cdiff6_w[3] = {45.0 / 60.0, -9.0 / 60.0, 1.0 / 60.0};

/* The same for a grid whose waves reach its Nyquist rate: 21 points,
 * weights fitted by least squares to the exact derivative (relative error
 * of the modified wave number) over k h in (0, 2.3], which holds the whole
 * band |k| h <= pi in the diagonal directions, where a cross derivative
 * matters; relative error <= 3.2e-4 there (the sixth-order difference is
 * 30 % off at k h = 2.2). */
static const double wide_w[10] = {
    0.96149997793578101, -0.42688812746433052, 0.23261704731444471, -0.13048081462293556,
    0.070745166958478364, -0.035655135414171368, 0.016085410075560996, -0.0061669823723281957,
    0.0018241301461298877, -0.00031443106493215573};

/* Fills *sp for reading fd at (x, z) (by pointer: the struct is 700 bytes). */
static void stencil_of(const ocean_field *fd, double x, double z, int finest, stencil *sp)
{
    const int nodes = ACC_MAXN;
    cell q = locate(fd, x, z);
    int n = fd->n, m = n - 1;
    for (int k = 0; k < ACC_SPAN; k++) {
        sp->row[k] = (size_t)((q.i0 + k - ACC_REACH + 4 * n) & m) * n;
        sp->col[k] = (q.j0 + k - ACC_REACH + 4 * n) & m;
    }
    sp->nodes = nodes;
    sp->first = 1 - nodes / 2;
    lagrange4(q.fx, sp->lu);
    lagrange4(q.fz, sp->lv);
    hermite4(q.fx, sp->lu, sp->hu, sp->ku);
    hermite4(q.fz, sp->lv, sp->hv, sp->kv);
    sp->h = fd->patch_m / n;
    /* The tensor product's cross term sums f_xz ku[a] kv[b] over the
     * nodes, and f_xz at a node is a difference of its neighbours: the sum
     * regroups as one weight per row of the f_x plane (per column of f_z)
     * that a node's difference reaches, so a reading costs one pass over
     * those rows instead of one difference per node (4x fewer loads on the
     * finest cascade's 21-point stencil). */
    int reach = finest ? 10 : 3;
    const double *w = finest ? wide_w : cdiff6_w;
    memset(sp->wz, 0, sizeof sp->wz);
    memset(sp->wx, 0, sizeof sp->wx);
    for (int b = 0; b < nodes; b++)
        for (int d = 1; d <= reach; d++) {
            int at = b + sp->first + ACC_REACH; /* node b's index, rows and columns alike */
            sp->wz[at + d] += sp->kv[b] * w[d - 1];
            sp->wz[at - d] -= sp->kv[b] * w[d - 1];
            sp->wx[at + d] += sp->ku[b] * w[d - 1];
            sp->wx[at - d] -= sp->ku[b] * w[d - 1];
        }
    sp->lo = sp->first - reach;
    sp->hi = sp->first + nodes - 1 + reach;
    sp->contig = sp->col[sp->hi + ACC_REACH] - sp->col[sp->lo + ACC_REACH] == sp->hi - sp->lo;
    for (int b = 0; b < nodes; b++)
        for (int a = 0; a < nodes; a++)
            sp->off[b * nodes + a] = sp->row[b + sp->first + ACC_REACH] + (size_t)sp->col[a + sp->first + ACC_REACH];
}

/* Node (r, c) relative to the cell's corner, r and c in -11..12. */
static inline double node(const float *g, const stencil *s, int r, int c)
{
    return g[s->row[r + ACC_REACH] + s->col[c + ACC_REACH]];
}

static double lagrange_read(const float *g, const stencil *s)
{
    /* nodes -1 .. 2 are the Hermite nodes (first = -1): their offsets */
    double acc = 0.0;
    for (int r = 0; r < 4; r++) {
        double rowv = 0.0;
        for (int c = 0; c < 4; c++)
            rowv += s->lu[c] * g[s->off[4 * r + c]];
        acc += s->lv[r] * rowv;
    }
    return acc;
}

/* The larger of two finite values, inlined (libm's fmax is a call). */
static inline double max2(double a, double b)
{
    return a > b ? a : b;
}

/* The envelope terms of hermite_read's bound (see there): *hx, *hz and
 * *hxz from the 8 x 8 nodes around the cell.  Always inlined, so each
 * call with a constant `finest` gets its own copy; a coarse cascade's
 * copy loads and differences no slopes, and gives the terms the general
 * code gave with them zero, bit for bit. */
static inline __attribute__((always_inline)) void envelope(const float *g, const float *gx,
                                                           const float *gz, const stencil *s,
                                                           int finest, double *hx_out,
                                                           double *hz_out, double *hxz_out)
{
    enum { B = ACC_MAXN + 4 };
    double h = s->h, hx = 0.0, hz = 0.0, hxz = 0.0;
    /* The nodes the fourth differences reach (two beyond the 4 x 4 on each
     * side) are loaded once into blk (values), bx (h f_x) and bz (h f_z),
     * not five times each.  The slopes only on the finest cascade: a
     * coarse one stops at k h = pi / 2, where any four consecutive node
     * values hold 0.71 of a wave's amplitude (the bound's factor 2 covers
     * that), so its values alone bound it. */
    float blk[B][B], bx[B][B], bz[B][B];
    for (int i = 0; i < B; i++)
        for (int k = 0; k < B; k++) {
            int r = s->first - 2 + i, c = s->first - 2 + k;
            blk[i][k] = (float)node(g, s, r, c);
            if (finest) {
                bx[i][k] = (float)(h * node(gx, s, r, c));
                bz[i][k] = (float)(h * node(gz, s, r, c));
            }
        }
    /* A wave near the band's top, k h = th_top, beats against the nodes:
     * its node values follow an envelope |cos| that passes through 0 where
     * the wave between them still has its full amplitude (at th = pi - e,
     * A cos(th j + phi) = (-1)^j A cos(e j - phi)).  Its slopes at the
     * nodes then hold that amplitude (h f_x = -th A sin(...)), so the
     * envelope is taken from both: the fourth difference of the values,
     * and that of h times the derivative over th_top.  For one wave of any
     * k h <= th_top the larger of the two is within a factor th_top / th
     * of its amplitude times the difference's response, and where that
     * factor matters (low k h) the values alone hold it. */
    /* Second differences first, each once: along x of the values (vx)
     * and of h f_x (sx), along z of the values (vz) and of h f_z (sz).
     * At the 4 x 4 nodes (block rows and columns 2..5) the fourth
     * differences along x and z (a wave's response (2 sin(th / 2))^4, 16
     * at the Nyquist rate) and the mixed one, second along x and along z
     * ((2 sin(th_x / 2))^2 (2 sin(th_z / 2))^2, large only where both
     * components are), are second differences of those.  The slopes'
     * terms are divided by th_top = pi, the finest cascade's band top. */
    float vx[B][B], vz[B][B], sx[B][B], sz[B][B];
    for (int i = 0; i < B; i++)
        for (int k = 1; k < B - 1; k++) {
            vx[i][k] = blk[i][k - 1] - 2.0f * blk[i][k] + blk[i][k + 1];
            vz[k][i] = blk[k - 1][i] - 2.0f * blk[k][i] + blk[k + 1][i];
            if (finest) {
                sx[i][k] = bx[i][k - 1] - 2.0f * bx[i][k] + bx[i][k + 1];
                sz[k][i] = bz[k - 1][i] - 2.0f * bz[k][i] + bz[k + 1][i];
            }
        }
    for (int i = 2; i < B - 2; i++)
        for (int k = 2; k < B - 2; k++) {
            double d4x = fabs(vx[i][k - 1] - 2.0 * vx[i][k] + vx[i][k + 1]);
            double d4z = fabs(vz[i - 1][k] - 2.0 * vz[i][k] + vz[i + 1][k]);
            double dm = fabs(vx[i - 1][k] - 2.0 * vx[i][k] + vx[i + 1][k]);
            if (finest) {
                d4x = max2(d4x, fabs(sx[i][k - 1] - 2.0 * sx[i][k] + sx[i][k + 1]) / M_PI);
                d4z = max2(d4z, fabs(sz[i - 1][k] - 2.0 * sz[i][k] + sz[i + 1][k]) / M_PI);
                dm = max2(dm, max2(fabs(sx[i - 1][k] - 2.0 * sx[i][k] + sx[i + 1][k]),
                                   fabs(sz[i][k - 1] - 2.0 * sz[i][k] + sz[i][k + 1])) / M_PI);
            }
            if (d4x > hx) hx = d4x;
            if (d4z > hz) hz = d4z;
            if (dm > hxz) hxz = dm;
        }
    *hx_out = hx;
    *hz_out = hz;
    *hxz_out = hxz;
}

/* Hermite reading of value plane g with derivative planes gx (d/dx) and
 * gz (d/dz); *bound (unless NULL) receives its error bound (see the
 * section comment). */
static double hermite_read(const float *g, const float *gx, const float *gz, const stencil *s,
                           int finest, double *bound)
{
    double h = s->h, acc = 0.0, big = 0.0, hx = 0.0, hz = 0.0, hxz = 0.0;
    /* The cross term: h^2 f_xz at the nodes (the mean of f_x differenced
     * along z and f_z along x) times ku kv, by the stencil's folded
     * weights; az[a] sums node column a along z, ax[a] node row a along x,
     * all advanced together: eight independent chains of adds, not one. */
    double az[ACC_MAXN] = {0}, ax[ACC_MAXN] = {0}, cross = 0.0;
    if (s->contig) {
        /* the columns lo .. hi do not wrap: plain pointers, the same sums */
        const int c0 = s->col[s->first + ACC_REACH], cl = s->col[s->lo + ACC_REACH];
        const float *ra[ACC_MAXN];
        for (int a = 0; a < ACC_MAXN; a++)
            ra[a] = gz + s->row[a + s->first + ACC_REACH] + cl - s->lo;
        for (int j = s->lo; j <= s->hi; j++) {
            double wz = s->wz[j + ACC_REACH], wx = s->wx[j + ACC_REACH];
            const float *rj = gx + s->row[j + ACC_REACH] + c0;
            for (int a = 0; a < ACC_MAXN; a++) {
                az[a] += wz * rj[a];
                ax[a] += wx * ra[a][j];
            }
        }
    } else {
        for (int j = s->lo; j <= s->hi; j++) {
            double wz = s->wz[j + ACC_REACH], wx = s->wx[j + ACC_REACH];
            for (int a = 0; a < ACC_MAXN; a++) {
                az[a] += wz * node(gx, s, j, a + s->first);
                ax[a] += wx * node(gz, s, a + s->first, j);
            }
        }
    }
    for (int a = 0; a < ACC_MAXN; a++)
        cross += s->ku[a] * az[a] + s->kv[a] * ax[a];
    acc += 0.5 * cross * h;
    for (int b = 0; b < s->nodes; b++) {          /* row node r (z) */
        for (int a = 0; a < s->nodes; a++) {      /* column node c (x) */
            size_t o = s->off[b * ACC_MAXN + a];
            double fv = g[o], fx = gx[o] * h, fz = gz[o] * h;
            acc += fv * s->hu[a] * s->hv[b] + fx * s->ku[a] * s->hv[b] + fz * s->hu[a] * s->kv[b];
            if (bound && fabs(fv) > big)
                big = fabs(fv);
        }
    }
    if (bound) {
        if (finest)
            envelope(g, gx, gz, s, 1, &hx, &hz, &hxz);
        else
            envelope(g, gx, gz, s, 0, &hx, &hz, &hxz);
    }
    /* Per wave, the 1-D error over the fourth difference's response peaks
     * at the band's top: 6.3e-5 at k h = pi / 2 (coarse cascades' edge),
     * 2.7e-3 at pi (the finest; 1.3e-3 at k h = 2.8: 1.5e-3 is taken,
     * which the factor 2 below lifts above the value at pi).  Along each
     * axis the error is at most that ratio times the high-passed field,
     * whose local envelope the nodes (values and slopes, above) sample; a
     * factor 2 covers the envelope between nodes.  On the finest cascade
     * the cross derivative's 21-point stencil is fitted up to k h = 2.3: a
     * wave with both components high (past it in one, or a band that
     * fills the square grid to its corners, ocean.k_max = inf) is read
     * with a cross term the fourth differences along the axes do not see,
     * so the mixed difference adds its own term, 5e-3 of it.  Scanned wave
     * by wave over every lattice wave of a 64-point grid (400 points
     * each), error over bound is at most 0.95 inside the Nyquist circle
     * (it was 3.7 at k h = 3.04 along an axis, where the nodes' envelope
     * passes through 0, and 1.4 for the cross term), but 2.7 for a lone
     * wave at the square's corner, k h = (3.04, 3.04) (7.2 before): a band
     * that fills the square relies on its corner waves carrying little
     * beside the rest, as in the default sea (0 of 400 query points over
     * their bound, 2 before).  Float storage adds 2^-22 of the nodes'
     * magnitude. */
    double ratio = finest ? 1.5e-3 : 6.3e-5, ratio_xz = finest ? 5e-3 : 0.0;
    if (bound)
        *bound = 2.0 * ratio * (hx + hz) + 2.0 * ratio_xz * hxz + big * 0x1p-22;
    return acc;
}

void ocean_frame_sample_accurate(const ocean_frame *f, double x, double z, unsigned want,
                                 ocean_point *out, ocean_point *err)
{
    enum { H, DX, DZ, SX, SZ, VX, VY, VZ, DXX, DZZ, DXZ, NV };
    double v[NV] = {0}, e[3] = {0};
    int any_foam = 0, blind[3] = {0};
    for (int c = 0; c < f->cascades; c++) {
        const ocean_field *fd = &f->field[c];
        if (!fd->effects)
            continue;
        int finest = c == f->cascades - 1;
        stencil s;
        stencil_of(fd, x, z, finest, &s);
        double b = 0.0, *bp = err ? &b : NULL;
        if ((want & OCEAN_SAMPLE_HEIGHT) && fd->height) {
            if (fd->slope_x) {
                v[H] += hermite_read(fd->height, fd->slope_x, fd->slope_z, &s, finest, bp);
                e[0] += b;
            } else {
                v[H] += lagrange_read(fd->height, &s);
                blind[0] = 1;
            }
        }
        if ((want & OCEAN_SAMPLE_DISPLACEMENT) && fd->dx) {
            if (fd->dxx) {
                v[DX] += hermite_read(fd->dx, fd->dxx, fd->dxz, &s, finest, bp);
                e[1] += b;
                v[DZ] += hermite_read(fd->dz, fd->dxz, fd->dzz, &s, finest, bp);
                e[2] += b;
            } else {
                v[DX] += lagrange_read(fd->dx, &s);
                v[DZ] += lagrange_read(fd->dz, &s);
                blind[1] = blind[2] = 1;
            }
        }
        if (want & OCEAN_SAMPLE_SLOPE) {
            if (fd->slope_x) v[SX] += lagrange_read(fd->slope_x, &s);
            if (fd->slope_z) v[SZ] += lagrange_read(fd->slope_z, &s);
        }
        if (want & OCEAN_SAMPLE_VELOCITY) {
            if (fd->vel_x) v[VX] += lagrange_read(fd->vel_x, &s);
            if (fd->vel_y) v[VY] += lagrange_read(fd->vel_y, &s);
            if (fd->vel_z) v[VZ] += lagrange_read(fd->vel_z, &s);
        }
        if ((want & OCEAN_SAMPLE_FOAM) && fd->dxx) {
            any_foam = 1;
            v[DXX] += lagrange_read(fd->dxx, &s);
            v[DZZ] += lagrange_read(fd->dzz, &s);
            v[DXZ] += lagrange_read(fd->dxz, &s);
        }
    }
    double jac = (1.0 + v[DXX]) * (1.0 + v[DZZ]) - v[DXZ] * v[DXZ];
    *out = (ocean_point){.height = v[H], .dx = v[DX], .dz = v[DZ], .slope_x = v[SX],
                         .slope_z = v[SZ], .jacobian = jac,
                         /* the frame's whitecap foam, as ocean_frame_sample
                          * and every tile (it was the legacy Jacobian ramp,
                          * near 0 where tiles carried the wind's coverage) */
                         .foam = any_foam ? ocean_frame_foam(f, v[DXX], v[DZZ]) : 0.0,
                         .vel_x = v[VX], .vel_y = v[VY], .vel_z = v[VZ], .dxx = v[DXX],
                         .dzz = v[DZZ], .dxz = v[DXZ]};
    if (err)
        *err = (ocean_point){.height = blind[0] ? INFINITY : e[0],
                             .dx = blind[1] ? INFINITY : e[1],
                             .dz = blind[2] ? INFINITY : e[2]};
}

void ocean_frame_get_field_stats(const ocean_frame *f, ocean_field_stats *out)
{
    memset(out, 0, sizeof *out);
    out->min_jacobian = 1.0;
    double var = 0.0;
    int finest = -1;
    for (int c = 0; c < f->cascades; c++) {
        const ocean_field *fd = &f->field[c];
        if (fd->dxx)
            finest = c;
        if (!fd->height)
            continue;
        size_t nn = (size_t)fd->n * fd->n;
        double s = 0.0, s2 = 0.0;
        for (size_t i = 0; i < nn; i++) {
            s += fd->height[i];
            s2 += (double)fd->height[i] * fd->height[i];
        }
        double m = s / nn;
        out->mean += m;
        var += s2 / nn - m * m;
    }
    out->hs = 4.0 * sqrt(var > 0.0 ? var : 0.0);
    if (finest < 0)
        return;
    const ocean_field *fd = &f->field[finest];
    int n = fd->n;
    double h = fd->patch_m / n, folded = 0.0, foam = 0.0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double jac, fm;
            if ((f->cascades == 1 || finest == 0) && fd->jacobian) {
                jac = fd->jacobian[(size_t)i * n + j];
                fm = fd->foam[(size_t)i * n + j];
            } else {
                ocean_point pt;
                ocean_frame_sample_some(f, j * h, i * h, OCEAN_SAMPLE_FOAM, &pt);
                jac = pt.jacobian;
                fm = pt.foam;
            }
            if (jac < out->min_jacobian)
                out->min_jacobian = jac;
            folded += jac < 0.0;
            foam += fm;
        }
    out->folded_fraction = folded / ((double)n * n);
    out->foam_coverage = foam / ((double)n * n);
}

/* The reference sums (ocean_reference_point, ocean_reference_eval): one
 * wave's h(k, t) and dh/dt with the filter's gain, then its terms at a
 * point given e^{i k.x}.  Both paths use these, so they add the same terms. */
typedef struct ref_wave {
    double hr, hi, tr, ti;   /* g h(k, t), g dh/dt */
    int mx, mz;
} ref_wave;

typedef struct ref_sum {
    double h, dx, dz, sx, sz, dxx, dzz, dxz, vx, vy, vz;
} ref_sum;

/* 0 for a wave outside the band or filtered out (nothing to add). */
static int ref_wave_at(const ocean *o, const cascade *cs, int mx, int mz, double t,
                       double cutoff_k, int order, ref_wave *rw)
{
    const ocean_params *p = &o->p;
    double kx = mx * cs->dk, kz = mz * cs->dk, k = hypot(kx, kz);
    if (!in_band(cs, k))
        return 0;
    double g = ocean_filter_gain(k, cutoff_k, order);
    if (g == 0.0)
        return 0;
    double hp[2], hm[2];
    draw_h0(p, cs, mx, mz, hp);
    draw_h0(p, cs, -mx, -mz, hm);
    double w = ocean_dispersion(k, p->sea.depth_m);
    double ph = ocean_phase(w, t), cp = cos(ph), sp = sin(ph);
    /* h = hp e^{-i ph} + conj(hm) e^{i ph} */
    double hr = hp[0] * cp + hp[1] * sp + hm[0] * cp + hm[1] * sp;
    double hi = hp[1] * cp - hp[0] * sp - hm[1] * cp + hm[0] * sp;
    /* dh/dt = -i w A + i w B, A = hp e^{-i ph}, B = conj(hm) e^{i ph} */
    double ar = hp[0] * cp + hp[1] * sp, ai = hp[1] * cp - hp[0] * sp;
    double br = hm[0] * cp + hm[1] * sp, bi = hm[0] * sp - hm[1] * cp;
    rw->hr = g * hr;
    rw->hi = g * hi;
    rw->tr = g * (w * (ai - bi));
    rw->ti = g * (w * (br - ar));
    rw->mx = mx;
    rw->mz = mz;
    return 1;
}

/* Adds wave rw at a point where e^{i k.x} = ce + i se. */
static inline void ref_add(const cascade *cs, double lam, const ref_wave *rw, double ce, double se,
                           ref_sum *a)
{
    double kx = rw->mx * cs->dk, kz = rw->mz * cs->dk, k = hypot(kx, kz);
    /* Re(a e^{i ex}) = ar ce - ai se; Re(i a e^{i ex}) = -ai ce - ar se */
    double re_h = rw->hr * ce - rw->hi * se, re_ih = -rw->hi * ce - rw->hr * se;
    double re_t = rw->tr * ce - rw->ti * se, re_it = -rw->ti * ce - rw->tr * se;
    a->h += re_h;
    a->dx += lam * kx / k * re_ih;
    a->dz += lam * kz / k * re_ih;
    a->sx += kx * re_ih;
    a->sz += kz * re_ih;
    a->dxx += -lam * kx * kx / k * re_h;
    a->dzz += -lam * kz * kz / k * re_h;
    a->dxz += -lam * kx * kz / k * re_h;
    a->vy += re_t;
    a->vx += lam * kx / k * re_it;
    a->vz += lam * kz / k * re_it;
}

/* The point from its sums; J and the whitecap foam as an evaluation with
 * this filter forms them (foam map m). */
static void ref_finish(const ref_sum *a, double lam, const ocean_foam_map *m, ocean_point *out)
{
    *out = (ocean_point){.height = a->h, .dx = a->dx, .dz = a->dz, .slope_x = a->sx,
                         .slope_z = a->sz, .vel_x = a->vx, .vel_y = a->vy, .vel_z = a->vz,
                         .dxx = a->dxx, .dzz = a->dzz, .dxz = a->dxz};
    out->jacobian = (1.0 + a->dxx) * (1.0 + a->dzz) - a->dxz * a->dxz;
    out->foam = ocean_foam_value(m, foam_beta(a->dxx, a->dzz, lam > 0.0 ? 1.0 / lam : 0.0));
}

static ocean_foam_map ref_foam_map(const ocean *o, double cutoff_k, int order)
{
    double kc = ocean_effective_cutoff(o, cutoff_k, order);
    return foam_map_for(o, isnan(kc) ? 0.0 : foam_sigma_sum(o, kc, order, 1.0, 1.0));
}

void ocean_reference_point(const ocean *o, double t, double x, double z,
                           double cutoff_k, int order, ocean_point *out)
{
    const ocean_params *p = &o->p;
    double lam = p->sea.choppiness;
    int n = p->n;
    ref_sum a = {0};
    for (int c = 0; c < p->cascades; c++) {
        const cascade *cs = &o->cas[c];
        /* Phases of e^{ik.x} reduced with x mod patch: exact for any x. */
        double xr = x - floor(x / cs->patch) * cs->patch;
        double zr = z - floor(z / cs->patch) * cs->patch;
        for (int mz = -n / 2 + 1; mz < n / 2; mz++)
            for (int mx = -n / 2 + 1; mx < n / 2; mx++) {
                ref_wave rw;
                if (!ref_wave_at(o, cs, mx, mz, t, cutoff_k, order, &rw))
                    continue;
                double ex = reduce_phase(mx * cs->dk * xr + mz * cs->dk * zr);
                ref_add(cs, lam, &rw, cos(ex), sin(ex), &a);
            }
    }
    ocean_foam_map m = ref_foam_map(o, cutoff_k, order);
    ref_finish(&a, lam, &m, out);
}

struct ocean_reference {
    const ocean *o;
    double lam;
    ocean_foam_map foam;
    size_t count[OCEAN_MAX_CASCADES];
    ref_wave *waves[OCEAN_MAX_CASCADES];
};

ocean_result ocean_reference_create(const ocean *o, double t, double cutoff_k, int order,
                                    ocean_reference **out)
{
    if (!out)
        return OCEAN_EINVAL;
    *out = NULL;
    if (!o || !ocean_time_ok(t) || isnan(cutoff_k) || cutoff_k < 0.0 || order < 1)
        return OCEAN_EINVAL;
    ocean_reference *r = calloc(1, sizeof *r);
    if (!r)
        return OCEAN_ENOMEM;
    r->o = o;
    r->lam = o->p.sea.choppiness;
    int n = o->p.n;
    for (int c = 0; c < o->p.cascades; c++) {
        const cascade *cs = &o->cas[c];
        r->waves[c] = malloc(sizeof(ref_wave) * (size_t)(n - 1) * (size_t)(n - 1));
        if (!r->waves[c]) {
            ocean_reference_destroy(r);
            return OCEAN_ENOMEM;
        }
        /* in ocean_reference_point's order (mz outer), so the sums add alike */
        for (int mz = -n / 2 + 1; mz < n / 2; mz++)
            for (int mx = -n / 2 + 1; mx < n / 2; mx++)
                r->count[c] += ref_wave_at(o, cs, mx, mz, t, cutoff_k, order,
                                           &r->waves[c][r->count[c]]);
    }
    r->foam = ref_foam_map(o, cutoff_k, order);
    *out = r;
    return OCEAN_OK;
}

void ocean_reference_destroy(ocean_reference *r)
{
    if (!r)
        return;
    for (int c = 0; c < OCEAN_MAX_CASCADES; c++)
        free(r->waves[c]);
    free(r);
}

void ocean_reference_eval(const ocean_reference *r, double x, double z, ocean_point *out)
{
    const ocean *o = r->o;
    int n = o->p.n, half = n / 2;
    ref_sum a = {0};
    /* e^{i k.x} = e^{i kx x} e^{i kz z}: 2 (n - 1) sines and cosines a
     * cascade, each of its own reduced phase (no recurrence, so no error
     * grows along the axis), then one complex product a wave. */
    double *ax = malloc(sizeof(double) * 4 * (size_t)n);
    if (!ax) {
        ocean_point nan_pt = {.height = NAN, .dx = NAN, .dz = NAN, .slope_x = NAN, .slope_z = NAN,
                              .jacobian = NAN, .foam = NAN, .vel_x = NAN, .vel_y = NAN,
                              .vel_z = NAN, .dxx = NAN, .dzz = NAN, .dxz = NAN};
        *out = nan_pt;
        return;
    }
    double *cx = ax, *sx = ax + n, *cz = ax + 2 * n, *sz = ax + 3 * n;
    for (int c = 0; c < o->p.cascades; c++) {
        const cascade *cs = &o->cas[c];
        double xr = x - floor(x / cs->patch) * cs->patch;
        double zr = z - floor(z / cs->patch) * cs->patch;
        for (int m = -half + 1; m < half; m++) {
            double px = reduce_phase(m * cs->dk * xr), pz = reduce_phase(m * cs->dk * zr);
            cx[m + half] = cos(px);
            sx[m + half] = sin(px);
            cz[m + half] = cos(pz);
            sz[m + half] = sin(pz);
        }
        const ref_wave *w = r->waves[c];
        for (size_t i = 0; i < r->count[c]; i++) {
            int jx = w[i].mx + half, jz = w[i].mz + half;
            double ce = cx[jx] * cz[jz] - sx[jx] * sz[jz], se = sx[jx] * cz[jz] + cx[jx] * sz[jz];
            ref_add(cs, r->lam, &w[i], ce, se, &a);
        }
    }
    free(ax);
    ref_finish(&a, r->lam, &r->foam, out);
}

void ocean_mode_amplitude(const ocean *o, int c, int mx, int mz, double t, double out[2])
{
    int n = o->p.n;
    out[0] = out[1] = 0.0;
    if (c < 0 || c >= o->p.cascades || mx <= -n / 2 || mx >= n / 2 || mz <= -n / 2 || mz >= n / 2)
        return;
    const cascade *cs = &o->cas[c];
    double hp[2], hm[2];
    draw_h0(&o->p, cs, mx, mz, hp);
    draw_h0(&o->p, cs, -mx, -mz, hm);
    double w = ocean_dispersion(hypot(mx * cs->dk, mz * cs->dk), o->p.sea.depth_m);
    double ph = ocean_phase(w, t), cp = cos(ph), sp = sin(ph);
    out[0] = hp[0] * cp + hp[1] * sp + hm[0] * cp + hm[1] * sp;
    out[1] = hp[1] * cp - hp[0] * sp + hm[0] * sp - hm[1] * cp;
}

void ocean_get_spectrum_stats(const ocean *o, ocean_spectrum_stats *out)
{
    memset(out, 0, sizeof *out);
    for (int c = 0; c < o->p.cascades; c++) {
        out->cascade_variance[c] = o->cas[c].variance;
        out->variance += o->cas[c].variance;
    }
    out->hs = 4.0 * sqrt(out->variance);
    out->wp = ocean_spectrum_peak(&o->p.sea);
    if (out->wp > 0.0) {
        out->tp = 2.0 * M_PI / out->wp;
        out->kp = ocean_wavenumber(out->wp, o->p.sea.depth_m);
        out->lambda_dominant = 2.0 * M_PI / out->kp;
    }
}

void ocean_get_counters(const ocean *o, ocean_counters *out)
{
    *out = o->counters;
}
