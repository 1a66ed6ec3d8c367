/*
 * ocean_internal.h - what the files of the FFT ocean share (not installed,
 * not part of the library's API): the ocean's and the frame's structs, the
 * per-cascade mode tables, the small rules every file applies the same way
 * (pair rows, bands, grids, the cell a point falls in), the functions one
 * file provides to the others, and the hooks oceand's own tests and
 * benchmarks use to pick code paths.
 *
 *   ocean.c            the ocean object: create, destroy, evaluate
 *   ocean_modes.c      the mode tables of a cascade (h0, frequencies)
 *   ocean_fft.c        FFTW plans, wisdom and the transform calls
 *   ocean_stage.c      the spectrum stage: the SIMD row passes
 *   ocean_stats.c      expected statistics of the spectrum under a filter
 *   ocean_sample.c     bilinear sampling of a frame, field statistics
 *   ocean_accurate.c   the accurate (Hermite) reading of a frame
 *
 * Thread rules are ocean.h's: an ocean and its frames are used by one
 * thread at a time; the stage's and FFTW's worker threads run inside an
 * evaluation.
 */
#ifndef OCEAN_INTERNAL_H
#define OCEAN_INTERNAL_H

#include <math.h>
#include <stdint.h>
#include <time.h>

#include <fftw3.h>

#include "filter.h"
#include "foam.h"
#include "ocean.h"

enum {
    CH_H, CH_DX, CH_DZ, CH_SX, CH_SZ, CH_DXX, CH_DZZ, CH_DXZ, CH_BQ, CH_VX, CH_VY, CH_VZ,
    CH_COUNT
};
#define MAX_LEVELS 9 /* n = 8 .. 2048 */

/* The modes of the half spectrum, n x (n/2 + 1), as structure-of-arrays so
 * the per-row passes vectorise.  Coefficients are float (they are data);
 * the frequency is kept as w / 2 pi in double-double (turns_hi + turns_lo)
 * so the row loop reduces w t to its phase exactly (ocean_time.h).
 * In deep water the stage computes the frequency instead (cascade.deep,
 * ocean_deep_turns); the table holds the same double there.
 * Out-of-band modes are all zero.  Rows are FFTW's (row = kz index), except
 * in the two arrays the stage streams for a pair of rows mz, -mz at once
 * (coef and cache): there the pair's rows sit side by side (ocean_pair_row), so
 * the stage reads one ascending stream, not a second one running down from
 * the bottom of the array, on which the hardware prefetcher restarts at
 * every row (interleaved A/B, N = 1024: 1.6 % of an evaluation). */
enum { A_RE, A_IM, B_RE, B_IM };          /* a, b: h(k,t) = a cos wt + b sin wt */
enum { C_HR, C_HI, C_TR, C_TI };          /* h(k,t), dh/dt */

typedef struct ocean_cascade {
    double patch, dk, k_lo, k_hi;
    double *turns_hi, *turns_lo; /* w / 2 pi = hi + lo, turns per second */
    float *coef[4];         /* a, b by ocean_pair_row */
    float *kx;              /* kx of a column (ix dk): one row serves every row */
    float *k, *kinv;        /* kinv = 1/|k| (0 at k = 0) */
    float *kw;              /* |k| / omega(k) (0 at k = 0): the foam
                               quadrature's factor on dh/dt */
    float *var;             /* E|h(k,t)|^2 = P(k) + P(-k) */
    double variance;
    /* h(k,t) and dh/dt of every mode, unfiltered, at time cache_t for the
     * modes of grids up to cache_n: several cutoff buckets in one tick pay
     * for the trigonometry once.  By ocean_pair_row. */
    float *cache[4];
    /* Rows mz and -mz hold waves (h0 != 0) only in columns [lo, hi) of
     * row |mz| (empty: lo = hi = 0); the rest of both rows is zero in
     * every channel.  The coarse cascades stop at half their Nyquist, so
     * about 80 % of their modes are zero: the stage reads, evolves and
     * multiplies this range only and writes zeros past it. */
    int *lo, *hi;
    /* Columns of the l-th grid (8 << l points) up to the last that holds a
     * wave of this cascade: ocean_fft_run skips the column transforms
     * past it where the ocean has a pruned plan (prune_cols). */
    int width[MAX_LEVELS];
    /* Deep water: from column deep[p] on, the modes of rows +-p have
     * k d >= DEEP_KD, and the stage computes their frequency (ocean_deep_turns)
     * instead of reading turns_hi/lo; the table holds the same value.
     * deep[p] = n/2 + 1 (never): a lattice cascade, or shallow water. */
    int *deep;
    double cf;              /* ocean_deep_turns' constant: sqrt(g dk) / 2 pi */
    double cache_t;
    int cache_n;
    int cache_dt;           /* 1: dh/dt is cached too (a velocity request) */
    /* A lattice cascade (ocean_create_lattice): its waves, not a spectrum,
     * give h0; NULL for a spectrum cascade. */
    ocean_lattice_wave *lw;
    int nlw;
} ocean_cascade;

#define FILTER_MEMO 32
typedef struct ocean_memo {
    int used, order;
    double kc, scale, boost, value, value2;
} ocean_memo;

/* What each way of splitting the stage's passes (rows, channels) has cost
 * one kind of cascade evaluation lately: ns per channel of the passes and
 * FFTW calls together, its last SPLIT_WINDOW samples.  Compared by their
 * minimum: a busy machine only ever adds time, so the minimum tracks what
 * a split costs, where an average flips with every spike. */
#define SPLIT_WINDOW 8
typedef struct ocean_split_stat {
    double ns[2][SPLIT_WINDOW];
    uint8_t next[2], have[2];
    uint32_t evals;         /* evaluations ocean_stage_split_pick chose for, for its probes */
} ocean_split_stat;

/* The filter gains of one cutoff bucket on one cascade's n-point grid,
 * (n/2 + 1) per row, including the grid's zeroed Nyquist row and column.
 * A bucket keeps its cutoff for many ticks, so its gains are computed
 * once instead of per tick (a division and a square root per mode). */
#define GAIN_PLANES 12
typedef struct ocean_gain_plane {
    int cascade, n, order;
    double kc, scale, boost;
    uint64_t used;          /* LRU stamp; 0: empty */
    size_t cap;             /* floats allocated */
    float *g;
} ocean_gain_plane;

/* Grids below this run on one thread: waking the pool for a 32 x 32
 * transform costs more than it saves (a low cutoff bucket's grid). */
#define PARALLEL_MIN_N 64

struct ocean {
    ocean_params p;
    int levels;                         /* plans for n = 8 << l, l < levels */
    ocean_cascade cas[OCEAN_MAX_CASCADES];
    fftwf_complex *spec;                /* CH_COUNT x n x (n/2+1) scratch */
    fftwf_plan plan[MAX_LEVELS][CH_COUNT]; /* [level][channels - 1] */
    /* The pruned 2-D transform (ocean_fft_run) of every grid of at least
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
    ocean_memo redis_memo[FILTER_MEMO], err_memo[FILTER_MEMO];
    int redis_next, err_next;
    /* the breaking index per filter (foam.h), same keys: for each reading
     * (ocean_foam_reading) its std and mean frequency as that reading
     * holds it, and the map solved for them */
    ocean_memo foam_memo[FILTER_MEMO];
    ocean_foam_map foam_maps[FILTER_MEMO][OCEAN_FOAM_READINGS];
    double foam_read[FILTER_MEMO][OCEAN_FOAM_READINGS][2];
    int foam_next;
    ocean_gain_plane gains[GAIN_PLANES];
    uint64_t gain_clock;
    int fused;          /* row pass: 0 plain, 1 AVX2+FMA, 2 AVX-512 (ocean_force_paths) */
    double stream_bytes; /* spectra larger than this are streamed (twice the LLC) */
    int deep_table;     /* 1: the stage reads deep water's w too (ocean_force_frequency_table) */
    int group;           /* channels per FFTW call forced by a test, 0: group_size's rule */
    /* How the stage splits a call over the threads (ocean_stage_pass): -1 the
     * faster as measured (ocean_stage_split_pick), 0 rows, 1 channels
     * (ocean_force_stage_split).  Timings per cascade, grid level, and
     * whether h(k,t) was cached. */
    int split_mode;
    ocean_split_stat split[OCEAN_MAX_CASCADES][MAX_LEVELS][2];
};

struct ocean_frame {
    int cascades;
    int n_max;
    float *block[OCEAN_MAX_CASCADES];   /* CH_COUNT x n x n, fftwf_malloc */
    float *derived[OCEAN_MAX_CASCADES]; /* jacobian, foam: 2 x n x n */
    ocean_field field[OCEAN_MAX_CASCADES];
    ocean_frame_info info;
    double patch[OCEAN_MAX_CASCADES];
    /* The whitecap ramps of this evaluation (foam.h), one a reading
     * (ocean_foam_reading), with the std and frequency each reading holds
     * (the bilinear one's are info.foam_sigma and foam_omega), and
     * 1/lambda, which turns the foam channels' lambda (Dxx + Dzz) into
     * beta = -a_z/g. */
    ocean_foam_map foam_map[OCEAN_FOAM_READINGS];
    double foam_sigma[OCEAN_FOAM_READINGS], foam_omega[OCEAN_FOAM_READINGS];
    double foam_inv_lambda;
};

/* One FFTW call's spectrum stage pass (ocean_stage_pass): the cascade, the
 * grid, the channels and the filter it writes the spectra of. */
typedef struct ocean_stage_args {
    ocean_cascade *cs;
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
} ocean_stage_args;

/* The largest team the stage splits a pass over (params.threads <= 64). */
#define STAGE_MAX_THREADS 64

/* Index of a signed wave number m in an n-point FFT axis. */
static inline int ocean_wrap_index(int m, int n)
{
    return m >= 0 ? m : m + n;
}

/* Row of kz index mz in the pair-ordered arrays of an n-point cascade:
 * 0, then 1, -1, 2, -2, ..., n/2 - 1, -(n/2 - 1), and -n/2 last.  The rows
 * of a smaller grid (|mz| <= n'/2) are a prefix of it. */
static inline size_t ocean_pair_row(int mz, int n)
{
    if (mz > 0)
        return (size_t)(2 * mz - 1);
    return mz == 0 ? 0 : mz == -n / 2 ? (size_t)(n - 1) : (size_t)(-2 * mz);
}

static inline int ocean_in_band(const ocean_cascade *cs, double k)
{
    return k >= cs->k_lo && k < cs->k_hi && k > 0.0;
}

/* Where tanh(k d) = 1 to 2^-62 (1 - tanh x < 2 e^-2x), w^2 = g k tanh(k d)
 * is the deep-water law w = sqrt(g k) (Airy; Tessendorf 2001, eq. 14). */
#define DEEP_KD 22.0

/* w / 2 pi of mode (mx, mz) in deep water: sqrt(g dk |m|) / 2 pi with
 * |m|^2 = mx^2 + mz^2 exact in double, as cf * |m|^(1/2).  Two correctly
 * rounded square roots and a product, so every path (scalar, AVX2,
 * AVX-512) and every replica gets the same double; it is within 3 ulp of
 * the exact w / 2 pi.  The model's deep-water frequency is this double,
 * read from no table: a frequency table costs the stage 16 B a pair of
 * modes, a third of the bytes it would stream from memory every tick,
 * and the phase stays exact for the computed value (ocean_time.h). */
static inline double ocean_deep_turns(double cf, double m2)
{
    return cf * sqrt(sqrt(m2));
}

/* Columns [*lo, *hi) of row pair p (rows p and n - p) of the n-point grid
 * that hold a wave: the cascade's range (cs->lo, hi) within this grid,
 * whose Nyquist row (p = n/2, mz = -n/2) and column are zero. */
static inline void ocean_pair_range(const ocean_cascade *cs, int n, int p, int *lo, int *hi)
{
    *lo = *hi = 0;
    if (p < n / 2) {
        *hi = cs->hi[p] < n / 2 ? cs->hi[p] : n / 2;
        *lo = cs->lo[p] < *hi ? cs->lo[p] : *hi;
    }
}

/* Beta from the summed foam channels lambda Dxx, lambda Dzz. */
static inline double ocean_foam_beta(double dxx, double dzz, double inv_lambda)
{
    return -(dxx + dzz) * inv_lambda;
}

/* Waves the filter keeps at under drop_gain of their amplitude are not
 * transformed at all, so a cutoff kc needs a grid holding only
 * 1.096 kc (order 6, the default 1/2): that is what lets a low cutoff run
 * a smaller transform, as seed 000 intends.  The dropped waves count fully
 * in E_error, so the price is always reported. */
static inline double ocean_negligible_k(const ocean *o, double kc, int order)
{
    return ocean_filter_negligible_k(kc, order, o->p.drop_gain);
}

/* Smallest grid whose band holds every wave below kneg: halving n keeps
 * |m| <= n/4 - 1, so it is allowed while (n/4 - 1) dk >= kneg. */
static inline int ocean_pick_size(const ocean_cascade *cs, int n_full, double kneg)
{
    int n = n_full;
    while (n > OCEAN_MIN_N && (n / 4 - 1) * cs->dk >= kneg)
        n /= 2;
    return n;
}

static inline int ocean_level_of(int n)
{
    int l = 0;
    while ((8 << l) < n)
        l++;
    return l;
}

/* Where (x, z) falls on a cascade's periodic grid.  Reduced in double
 * first: x = 1e7 m keeps sub-millimetre position. */
typedef struct ocean_cell {
    int i0, j0;
    double fx, fz;
} ocean_cell;

/* floor() for |u| < 2^62 without a libm call (the baseline x86-64 target
 * has no rounding instruction); the same value as floor(u). */
static inline double ocean_floor_fast(double u)
{
    double t = (double)(long long)u;
    return t > u ? t - 1.0 : t;
}

static inline ocean_cell ocean_locate(const ocean_field *fd, double x, double z)
{
    int n = fd->n;
    double u = x / fd->patch_m, v = z / fd->patch_m;
    /* Any real world position is far inside ocean_floor_fast's range. */
    u = (u - (fabs(u) < 4e18 ? ocean_floor_fast(u) : floor(u))) * n;
    v = (v - (fabs(v) < 4e18 ? ocean_floor_fast(v) : floor(v))) * n;
    ocean_cell c = {(int)v, (int)u, 0.0, 0.0};
    if (c.j0 >= n) c.j0 = n - 1;
    if (c.i0 >= n) c.i0 = n - 1;
    c.fx = u - c.j0;
    c.fz = v - c.i0;
    return c;
}

/* Monotonic nanoseconds, for ocean_counters' time split. */
static inline uint64_t ocean_now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000u + (uint64_t)ts.tv_nsec;
}

/* ---- ocean_modes.c: the mode tables */

/* Cascade c's band, h0 and frequencies from the spectrum of o->p. */
ocean_result ocean_modes_build(ocean *o, int c);
/* Cascade 0 from the given lattice waves (ocean_create_lattice); msg says
 * which wave is invalid. */
ocean_result ocean_modes_build_lattice(ocean *o, const ocean_lattice_wave *w, int count,
                                       char *msg, size_t msglen);
/* Frees a cascade's tables (any state ocean_modes_build left, or zeros). */
void ocean_modes_free(ocean_cascade *cs);
/* h0(k) of the integer wave vector (mx, mz), drawn afresh in double. */
void ocean_modes_h0(const ocean_params *p, const ocean_cascade *cs, int mx, int mz, double out[2]);

/* ---- ocean_fft.c: FFTW plans */

/* Once per process, before any other FFTW call (threaded FFTW). */
void ocean_fft_init(void);
/* Every plan o's evaluations run, under the process-wide planner lock
 * (o->spec already allocated). */
ocean_result ocean_fft_plan(ocean *o, char *msg, size_t msglen);
/* Destroys o's plans; accepts an ocean whose planning failed midway. */
void ocean_fft_free(ocean *o);
/* The process-wide planner lock, for the library's other FFTW plans
 * (wake.c): plans are made and destroyed under it, executed without. */
void ocean_fft_planner_lock(void);
void ocean_fft_planner_unlock(void);
/* The 2-D c2r of gn channels of cascade cs's n-point spectra at o->spec
 * into out; returns 1 when it ran the pruned column pass. */
int ocean_fft_run(ocean *o, const ocean_cascade *cs, int n, int gn, float *out);

/* ---- ocean_stage.c: the spectrum stage */

/* The row pairs 0..n/2 of cascade cs's n-point grid split over nt
 * threads, balanced by work: thread t takes [b[t], b[t+1]). */
void ocean_stage_split(const ocean_cascade *cs, int n, int nt, int *b);
/* The calling team member's share: its rows of split b (made for nt), or
 * of a new split when OpenMP granted a smaller team; its channels of a
 * gn-channel call, the block FFTW's threaded plan hands the same member. */
void ocean_stage_rows(const ocean_cascade *cs, int n, int nt, const int *b, int *r0, int *r1);
void ocean_stage_channels(int gn, int *c0, int *c1);
/* This team member's share of one FFTW call's pass: by channel or by rows. */
void ocean_stage_pass(const ocean_stage_args *a, int nt, const int *split, size_t plane, int by_channel);
/* How the next pass of a kind splits (0 rows, 1 channels): the faster of
 * the recent timings in st (best), with a probe of the other now and then
 * (pick); note records a pass's ns per channel. */
int ocean_stage_split_best(const ocean *o, const ocean_split_stat *st);
int ocean_stage_split_pick(const ocean *o, ocean_split_stat *st);
void ocean_stage_split_note(ocean_split_stat *st, int split, double ns);

/* ---- ocean_stats.c: the spectrum under a filter */

/* The foam map (foam.h) of what an evaluation with this filter transforms,
 * read as rd reads it, with the std of its breaking index in *sigma and
 * its mean frequency in *omega (either may be NULL): memoised, and
 * computed. */
ocean_foam_map ocean_stats_foam(ocean *o, ocean_foam_reading rd, double kc, int order, double scale, double boost,
                                double *sigma, double *omega);
/* The exact sums' map of the same band (OCEAN_FOAM_EXACT), not memoised
 * (const o). */
ocean_foam_map ocean_stats_foam_sum(const ocean *o, double kc, int order, double scale, double boost,
                                    double *sigma);
/* The whitecap coverage of o's sea. */
double ocean_stats_whitecap_target(const ocean *o);
/* The redistribution scale of (kc, order) and E_error of a filter, memoised. */
double ocean_stats_redistribution(ocean *o, double kc, int order);
double ocean_stats_error(ocean *o, double kc, int order, double scale, double boost);

/* ---- hooks for oceand's own tests and benchmarks */

/* Chooses the spectrum stage's code paths, which must all give the same
 * bits (tests/test_ocean.c compares them):
 *   fused  2: the AVX-512 row pass (AVX-512 F/VL/DQ/BW, AVX2 and FMA),
 *             1: the AVX2+FMA row pass, 0: the plain pass, -1: the
 *             CPU's best; a pass the CPU lacks falls back to the best
 *             below it;
 *   stream 1: write every spectrum with streaming stores (AVX2+FMA and
 *             AVX-512 passes only), 0: never, -1: spectra larger than
 *             twice the last-level cache (the default).
 * ocean_create applies (-1, -1).  Not thread-safe against a running
 * ocean_evaluate on the same ocean.  Returns the row pass now in force
 * (0, 1 or 2); NULL: does nothing, returns -1. */
int ocean_force_paths(ocean *o, int fused, int stream);

/* table 1: the spectrum stage reads every mode's frequency from its table,
 * deep water's too; 0 (ocean_create's): it computes deep water's
 * (k d >= 22) as sqrt(g k) / 2 pi from the mode's integer wave vector.
 * Both give the same bits (the table holds the computed value); the
 * switch is for the tests and benchmarks that compare them.  Same thread
 * rules as ocean_force_paths; NULL: does nothing. */
void ocean_force_frequency_table(ocean *o, int table);

/* Transforms the channels of an evaluation group channels per FFTW call
 * (1 up to the 11 channels an evaluation can hold; 0 or out of range: the
 * default rule, at most 8.5 MB of spectra a call).  Each group size is its own FFTW plan, so results may differ from
 * the default's in the last bits.  Accepts NULL. */
void ocean_force_group(ocean *o, int group);

/* How the spectrum stage splits an FFTW call's pass over the threads:
 * mode 0 by rows, 1 by channel (each thread the channels FFTW's threaded
 * plan transforms on it), -1 (ocean_create's) whichever the ocean has
 * measured faster, with a probe of the other every 16th evaluation.  A
 * call with fewer channels than threads always splits by rows.  Every
 * mode gives the same bits; the switch is for the tests and benchmarks
 * that compare them.  Same thread rules as ocean_force_paths; NULL: does
 * nothing. */
void ocean_force_stage_split(ocean *o, int mode);

/* prune 0: every transform runs FFTW's whole-grid 2-D plan; 1
 * (ocean_create's): a cascade whose waves stop at a quarter of the grid
 * runs the pruned column pass (ocean_counters.fft_calls_pruned).  Both
 * are the same transform; the bits may differ in the last place (other
 * FFTW plans).  For the tests and benchmarks that compare them; also
 * applies to ocean_transform_only.  Same thread rules as
 * ocean_force_paths; NULL: does nothing. */
void ocean_force_pruning(ocean *o, int prune);

/* ocean_transform_only with each FFTW call's spectra first written
 * (zeros, split over the threads as the spectrum stage splits them): the
 * least any stage that writes the spectra FFTW reads can cost, the floor
 * bench_core puts beside the full evaluation.  f's contents are garbage
 * afterwards. */
ocean_result ocean_transform_floor(ocean *o, const ocean_request *r, ocean_frame *f);

#endif
