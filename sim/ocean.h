/*
 * ocean.h - the FFT ocean: a pure function of (sea state, seed, t).
 *
 * A Tessendorf ocean with 1-4 cascades.  Each cascade is a periodic patch
 * carrying only its own band of wave numbers, so the summed cascades count
 * every wave once.  The random amplitude of each wave is keyed by its
 * integer wave vector (seed, patch, mx, mz), not by array index, so the same
 * sea evaluated at N = 256 and N = 1024 shares every common wave.
 *
 * Nothing accumulates across evaluations: ocean_evaluate(t) depends only on
 * the parameters and t, so any instant can be computed in any order and two
 * processes agree bit for bit (same build, same thread count).
 *
 * Threads: an ocean is used by one thread at a time (it owns scratch
 * spectra and FFTW plans); FFTW and the spectrum stage use params.threads
 * worker threads internally (an OpenMP team).  Run the process with the
 * wait policy ocean_wait_policy_setenv sets, as oceand does: with libgomp's
 * default spinning barriers, another process holding one of the cores
 * turned a 0.7 ms evaluation at N = 256 on 2 threads into 20-35 ms.
 * Frames are independent objects: one ocean can fill many frames (one per
 * cutoff bucket).
 */
#ifndef OCEAN_H
#define OCEAN_H

#include <stddef.h>
#include <stdint.h>

#include "interp.h"
#include "ocean_result.h"
#include "ocean_time.h"
#include "spectrum.h"

#define OCEAN_MAX_CASCADES 4
#define OCEAN_MIN_N 8
#define OCEAN_MAX_N 2048

/* Effects (channel groups) a caller may ask of a cascade.  Only the inverse
 * transforms the asked channels need are run. */
enum ocean_effect {
    OCEAN_FX_HEIGHT = 1u << 0,       /* eta                              1 FFT */
    OCEAN_FX_DISPLACEMENT = 1u << 1, /* choppy Dx, Dz (scaled by lambda) 2 FFTs */
    OCEAN_FX_NORMALS = 1u << 2,      /* slopes d(eta)/dx, d(eta)/dz      2 FFTs */
    OCEAN_FX_FOAM = 1u << 3,         /* Jacobian -> folding and foam     4 FFTs */
    /* 1u << 4 is the Gerstner near field at the scene/protocol level; the
     * FFT ocean ignores it. */
    OCEAN_FX_NEAR_FIELD = 1u << 4,
    OCEAN_FX_VELOCITY = 1u << 5,     /* orbital velocity (for queries)   3 FFTs */
    OCEAN_FX_ALL = 0xFu              /* the four visual effects */
};

/* How ocean_create plans its transforms.  FFTW_MEASURE picks algorithms by
 * timing them, so two processes planning for themselves may choose
 * different plans and disagree in the last bits; wisdom fixes the choice:
 * every replica that imports the same wisdom file runs the same plans.
 *   ESTIMATE  heuristic plans: instant, and the same in every process
 *   MEASURE   timed plans: fastest, but only bit-identical within a process
 *   WISDOM    the timed plans recorded in params.wisdom (FFTW_WISDOM_ONLY:
 *             a transform the file lacks is an error, never re-timed);
 *             `ocean-sim wisdom --out FILE` writes such a file */
typedef enum ocean_plan_mode {
    OCEAN_PLAN_ESTIMATE = 0,
    OCEAN_PLAN_MEASURE = 1,
    OCEAN_PLAN_WISDOM = 2
} ocean_plan_mode;

#define OCEAN_WISDOM_PATH_MAX 512

typedef struct ocean_params {
    ocean_sea_state sea;
    uint64_t seed;
    int n;                  /* FFT resolution per cascade: power of two, 8..2048 */
    int cascades;           /* 1..OCEAN_MAX_CASCADES */
    double patch_m;         /* size of the largest patch, m (1 m .. 100 km) */
    double cascade_ratio;   /* L_c = patch_m / ratio^c; > 1.5, non-integer avoids
                               cascades tiling in step */
    double k_max;           /* waves with |k| >= k_max are left to the Gerstner
                               near field; INFINITY keeps the finest cascade's
                               full square band */
    int threads;            /* worker threads for FFTW and the spectrum stage */
    int plan_measure;       /* how FFTW plans: an ocean_plan_mode (the name
                               predates the third mode) */
    char wisdom[OCEAN_WISDOM_PATH_MAX]; /* OCEAN_PLAN_WISDOM: FFTW wisdom file
                               every replica imports; "" otherwise */
    double drop_gain;       /* filtered evaluations leave out every wave whose
                               Butterworth gain is below this, so a low cutoff
                               runs on a smaller grid; (0, 1/sqrt 2]: 1/sqrt 2
                               drops the whole band above the cutoff */
} ocean_params;

/* Default drop_gain: waves the filter halves or less are not transformed.
 * For order 6 that is the band above 1.096 kc; bench_filter sweeps the
 * choice (cost beside E_error). */
#define OCEAN_DROP_GAIN_DEFAULT 0.5

/* Fills p with the shipped defaults (PM sea, 10 m/s, N = 256, 1 cascade,
 * 1000 m patch, seed 1). */
void ocean_params_default(ocean_params *p);

/* Sets the OpenMP wait policy in the environment unless OMP_WAIT_POLICY
 * is already there: OMP_WAIT_POLICY=passive and, with spin (unless set),
 * GOMP_SPINCOUNT=OCEAN_GOMP_SPINCOUNT.
 * - Passive: a team member sleeps as soon as it waits.  With libgomp's
 *   default spin (~3 ms) a team member whose core another process holds
 *   cost the others a time slice at every barrier (N = 256 on 2 threads:
 *   0.7 ms became 20-35 ms).
 * - spin = 1: it first spins ~30 us (libgomp: ~10 ns a count).  An
 *   evaluation is a chain of parallel regions (the spectrum stage, FFTW's
 *   passes) microseconds apart, and without the spin each region first
 *   waits for a sleeping thread to be woken: 10-16 % of an evaluation at
 *   N = 512-1024 on 2 threads (bench_core, "OpenMP wait policy").  For
 *   programs whose work is evaluating (ocean-sim, bench_core).  oceand
 *   passes 0: on 2 cores the spinning team took time from the service
 *   thread, and frames at 256 viewers came later (p50 8.0 -> 10.7 ms, p99
 *   16 -> 21 ms).
 * libgomp reads both when it loads: returns 1 when it set something (the
 * caller should re-execute itself, e.g. execv("/proc/self/exe", argv)), 0
 * when the environment had chosen. */
#define OCEAN_GOMP_SPINCOUNT "3000"
int ocean_wait_policy_setenv(int spin);

/* Checks every field of p (ranges, NaN/Inf, power-of-two N, and that no
 * wave held is faster than OCEAN_OMEGA_MAX, the frequency the time limit
 * is built on).  On failure
 * returns OCEAN_EINVAL and writes a message naming the field and the value
 * into msg (if msg != NULL). */
ocean_result ocean_params_validate(const ocean_params *p, char *msg, size_t msglen);

typedef struct ocean ocean;

/* Builds an ocean: validates p, draws every wave's initial amplitude, and
 * makes all FFTW plans.  *out is NULL on failure; msg gets the reason.
 * With OCEAN_PLAN_WISDOM a missing or unreadable wisdom file is OCEAN_EIO,
 * a corrupt one OCEAN_EFORMAT, one that lacks a transform this ocean needs
 * (another N or thread count) OCEAN_EUNSUPPORTED, each with a message
 * naming the file.  FFTW's wisdom is process-global: ESTIMATE
 * oceans forget it before planning (so they stay the same as in any other
 * process), WISDOM oceans replace it by their file's, MEASURE oceans add
 * to it. */
ocean_result ocean_create(const ocean_params *p, ocean **out, char *msg, size_t msglen);

/* One wave A cos(k.x - w t + phi) of a lattice cascade, on the lattice of
 * its patch: k = 2 pi (mx, mz) / patch_m. */
typedef struct ocean_lattice_wave {
    int mx, mz;
    double amplitude;   /* A, m, >= 0 */
    double phase;       /* phi, rad */
} ocean_lattice_wave;
#define OCEAN_LATTICE_MAX_WAVES 4096

/* An ocean of one cascade that carries given waves instead of a spectrum:
 * the Gerstner near field snapped to a periodic patch (gerstner.h
 * "Lattice"), evaluated by the same inverse FFT as any cascade (its h0 is
 * sparse: only the waves' lattice points are non-zero).  From p it takes
 * n, threads, the plan mode, drop_gain and the sea's depth (dispersion)
 * and choppiness, which is the lambda of the displacement channels: give
 * the near field's effective Q (ocean_gerstner_effective_q) and the
 * channels equal the Gerstner sum of the same waves,
 *   D = -Q A (k/|k|) sin(k.x - w t + phi).
 * Every ocean_* function then works on it as on a one-cascade ocean
 * (ocean_cascade_mips/moments, ...); its band
 * [k_lo, k_hi) is the waves' |k| range.  Indices must lie within
 * +-(n/2 - 1) (not both 0) and every w within OCEAN_OMEGA_MAX; count
 * 0..OCEAN_LATTICE_MAX_WAVES.  OCEAN_EINVAL with msg naming the field. */
ocean_result ocean_create_lattice(const ocean_params *p, double patch_m, const ocean_lattice_wave *w,
                                  int count, ocean **out, char *msg, size_t msglen);

/* Writes the FFTW wisdom this process has accumulated (every plan made by
 * OCEAN_PLAN_MEASURE oceans since the last ESTIMATE or WISDOM one) to path,
 * for replicas to import with OCEAN_PLAN_WISDOM.  OCEAN_EIO and a message
 * naming the file if it cannot be written. */
ocean_result ocean_wisdom_export(const char *path, char *msg, size_t msglen);

/* Frees o and its plans.  Accepts NULL. */
void ocean_destroy(ocean *o);

/* The parameters o was built with (after defaults were resolved). */
const ocean_params *ocean_get_params(const ocean *o);

/* Patch size and wave-number band [k_lo, k_hi) of cascade c. */
void ocean_cascade_band(const ocean *o, int c, double *patch_m, double *k_lo, double *k_hi);

/* What a caller wants evaluated. */
typedef struct ocean_request {
    unsigned effects[OCEAN_MAX_CASCADES]; /* OCEAN_FX_* mask per cascade; 0 skips it */
    double cutoff_k;  /* Butterworth low-pass cutoff, rad/m; INFINITY: unfiltered;
                         0 filters everything out */
    int order;        /* Butterworth order n >= 1 (default 6) */
    int redistribute; /* 1: rescale the passed band so the filtered field keeps
                         the unfiltered variance (seed 000's energy guard) */
    double low_boost; /* gain on waves below the cutoff (seed 000's 3 % motion
                         compensation gives 1.03); 1 or 0 means none */
    int foam_map;     /* 1: also fill each foam cascade's jacobian and foam
                         planes (baking, field statistics).  Point samples,
                         queries and the daemon's tiles form J and foam from
                         Dxx, Dzz, Dxz and bq at the point (or send the
                         breaking index itself, layout 1) and need no map,
                         so those requests leave it 0 and skip a full pass
                         over the field.  Not with per_cascade (EINVAL) */
    int per_cascade;  /* 1: cascade c is filtered at cascade_cutoff_k[c]
                         instead of cutoff_k (the mips of ocean_cascade_mips:
                         one frame holds the same mip level of every
                         cascade); redistribute and low_boost must be off,
                         and the frame's e_error is then 0 (not computed) */
    double cascade_cutoff_k[OCEAN_MAX_CASCADES];
} ocean_request;

/* An unfiltered request for the given effects on every cascade, with the
 * foam map (foam_map = 1). */
void ocean_request_all(ocean_request *r, unsigned effects);

/* One cascade's evaluated fields.  Row-major n x n floats, row = z index,
 * column = x index; sample (i, j) sits at world (j, i) * patch / n.  Pointers
 * of channels not evaluated are NULL. */
typedef struct ocean_field {
    int n;              /* grid actually evaluated (< params.n when a low
                           cutoff let a smaller transform serve) */
    double patch_m;
    unsigned effects;
    float *height;
    float *dx, *dz;             /* choppy displacement, already times lambda */
    float *slope_x, *slope_z;   /* d(eta)/dx, d(eta)/dz */
    float *dxx, *dzz, *dxz;     /* lambda * derivatives of Dx, Dz (foam) */
    float *bq;                  /* -lambda * the breaking index's quadrature
                                   in time (foam.h: its trails) */
    float *jacobian;            /* this cascade's folding Jacobian J (< 0: folded);
                                   NULL unless the request asked for foam_map */
    float *foam;                /* whitecap foam 0..1 (foam.h) of this cascade's
                                   own breaking index; likewise */
    float *vel_x, *vel_y, *vel_z; /* orbital velocity of the displaced point, m/s */
} ocean_field;

/* Whitecap foam (foam.h): every foam value an evaluated frame gives - the
 * foam map planes, ocean_frame_sample(_some), the field statistics - is
 * ocean_foam_value(map, beta, q) with beta = -(Dxx + Dzz) / lambda, the
 * linear deep-water downward acceleration over g of the summed cascades
 * (Longuet-Higgins' breaking index; lambda = sea.choppiness, beta = 0 when
 * lambda = 0), q = -bq / lambda its quadrature in time (the trail of the
 * last crest's foam, decaying in Monahan's 3.85 s), and the frame's map
 * solved so that the field's expected mean, trails included, is
 * ocean_foam_coverage_target(U10) for the band and filter that evaluation
 * holds.  Nothing accumulates over time: the trails are read from the
 * waves at t.
 *
 * WHITECAP COVERAGE of any set of foam samples (a tile, a level, a frame)
 * is their area mean (ocean_whitecap_coverage): foam is the white fraction
 * of a sample's area, so the mean is conserved across resolutions and
 * filter cutoffs.  ocean_field_stats.foam_coverage is that mean over the
 * finest cascade's grid.
 *
 * Legacy mapping, 1 where folded fading to 0 at J = OCEAN_FOAM_J_CLEAR;
 * no longer used by frames, samples or queries (bench_accuracy compares
 * folding with it). */
#define OCEAN_FOAM_J_CLEAR 0.5
float ocean_foam_from_jacobian(float j);

typedef struct ocean_frame ocean_frame;

/* Allocates a frame able to hold every channel of every cascade of o. */
ocean_result ocean_frame_create(const ocean *o, ocean_frame **out);
void ocean_frame_destroy(ocean_frame *f);

/* The cutoff an evaluation really applies: INFINITY when the filter's
 * gain stays above 1 - 1e-6 over every wave o holds (the evaluation is
 * then byte-identical to the unfiltered one, so callers can share it),
 * else cutoff_k.  NaN for an invalid cutoff or order. */
double ocean_effective_cutoff(const ocean *o, double cutoff_k, int order);

/* Evaluates the sea at time t (seconds, |t| <= OCEAN_TIME_MAX; beyond it,
 * or NaN/Inf, OCEAN_EINVAL: see ocean_time.h) into f.  Every wave's phase
 * w t is reduced exactly (ocean_phase).  Deterministic: same o
 * parameters, t and r give identical bytes. */
ocean_result ocean_evaluate(ocean *o, double t, const ocean_request *r, ocean_frame *f);

/* Runs only the inverse FFTs ocean_evaluate(o, t, r, f) would run (same
 * sizes, same batches, same plans) on whatever the scratch spectra hold:
 * the "FFTW alone" baseline the benchmarks put beside a full evaluation.
 * f's contents are garbage afterwards. */
ocean_result ocean_transform_only(ocean *o, const ocean_request *r, ocean_frame *f);

/* Per-evaluation facts, valid after ocean_evaluate. */
typedef struct ocean_frame_info {
    double t;
    double cutoff_k;
    double e_error;       /* ||H - H_filtered||_2 / ||H||_2 of the height spectrum */
    int transforms;       /* 2-D inverse real FFTs this evaluation ran */
    int cascades;
    double foam_sigma;    /* std of the breaking index beta over the evaluated
                             band as a bilinear reading holds it (0 without
                             foam channels) */
    double foam_omega;    /* its mean frequency m1 / m0, rad/s: the rate of
                             the trails' phase (foam.h) */
    double whitecap_target; /* ocean_foam_coverage_target(U10): the expected
                               mean of this frame's foam */
} ocean_frame_info;

const ocean_field *ocean_frame_field(const ocean_frame *f, int cascade);
void ocean_frame_get_info(const ocean_frame *f, ocean_frame_info *out);

/* The summed cascades at a world point, bilinear on each periodic grid.
 * x and z are doubles and reduced modulo each patch in double, so points
 * 1e7 m from the origin lose nothing.  Channels not evaluated read as 0
 * (jacobian as 1). */
typedef struct ocean_point {
    double height, dx, dz, slope_x, slope_z, jacobian, foam;
    double vel_x, vel_y, vel_z;
    double dxx, dzz, dxz;   /* derivatives of the displacement (foam channel) */
    double bq;              /* -lambda * beta's quadrature (foam channel; foam.h) */
} ocean_point;
void ocean_frame_sample(const ocean_frame *f, double x, double z, ocean_point *out);

/* How a reader read the breaking index it turns into foam.  The whitecap
 * ramp is solved so that the index's distribution, as read, covers the
 * wind's share of the sea, and a reading changes that distribution:
 * interpolation between grid nodes damps the waves near each grid's
 * Nyquist, bilinear (ocean_frame_sample, layout-0 tiles) more than cubic
 * Lagrange (ocean_frame_sample_accurate, queries), and the exact sum of
 * the waves not at all.  Each reading has its own ramp: on the cubic
 * reading's index the bilinear reading's ramp covered 1.5 times the
 * wind's share (ship-bridge), the exact sum's 0.73 times. */
typedef enum ocean_foam_reading {
    OCEAN_FOAM_BILINEAR = 0,
    OCEAN_FOAM_CUBIC = 1,
    OCEAN_FOAM_EXACT = 2,
    OCEAN_FOAM_READINGS
} ocean_foam_reading;

/* Whitecap foam (foam.h) of a point whose summed displacement derivatives
 * are dxx = lambda Dxx and dzz = lambda Dzz and whose breaking index's
 * quadrature is -bq / lambda (ocean_point's fields, plus the share of any
 * waves the caller adds, e.g. the near field's), with this frame's
 * whitecap ramp for reading rd and trails: ocean_frame_sample's .foam is
 * ocean_frame_foam(f, OCEAN_FOAM_BILINEAR, p.dxx, p.dzz, p.bq).  0 for a
 * frame evaluated without foam channels. */
double ocean_frame_foam(const ocean_frame *f, ocean_foam_reading rd, double dxx, double dzz, double bq);

/* The same where waves the frame does not hold add to dxx, dzz and bq (a
 * near field): their summed dxx + dzz has variance m0 and frequency
 * moment m1 (sum of variance times w), and the ramp is solved for the
 * band the frame (as rd reads it) and they make together, so the coverage
 * there stays the wind's (foam.h).  ocean_frame_foam when m0 = 0. */
double ocean_frame_foam_plus(const ocean_frame *f, ocean_foam_reading rd, double m0, double m1, double dxx,
                             double dzz, double bq);

/* The whitecap ramp of a band (foam.h): the breaking index's std sigma of
 * the band, the ramp's foot a, and the band's mean frequency omega (rad/s,
 * the trails' rate), a solved for the wind's coverage at that std and
 * frequency.  The band as it is, not as some interpolation reads it: a
 * reader that sums bands knows their variance from the mip tables, and
 * the share of it its kernel holds from the read table (PROTOCOL.md
 * "Whitecaps in layout 1"; ocean_moments.kept_mss_read); the Keys-cubic C
 * library reads 0.98-1.10 of the wind's coverage from ship-bridge's 2 m-10
 * km cameras, 0.94-1.06 from flight's (tests/test_fidelity.sh). */
typedef struct ocean_foam_row {
    double sigma, a, omega;
} ocean_foam_row;

/* One row per cutoff kc[0..n-1] (ascending; INFINITY: the whole sea):
 * the band of o's waves (and of `more`'s, a second ocean of the same sea
 * such as the near field's, when not NULL) at that Butterworth cutoff of
 * the given order.  A cutoff that adds no wave to the row before it makes
 * no row, so sigma ascends strictly; *count rows are written.  For a reader
 * that sums bands and finds the ramp by the std it holds (PROTOCOL.md
 * "Whitecaps in layout 1").  Each row solves the ramp with trails (about
 * 2 ms).  No rows (*count 0) for a sea without whitecaps (sea.whitecaps
 * off, or no waves): its readers draw none.  OCEAN_EINVAL for NULL, n < 1,
 * order < 1 or a NaN or negative cutoff. */
ocean_result ocean_foam_table(const ocean *o, const ocean *more, int order, const double *kc, int n,
                              ocean_foam_row *rows, int *count);

/* What ocean_frame_sample_some fills; the rest of the point reads as in a
 * frame without those channels (0, jacobian 1). */
enum {
    OCEAN_SAMPLE_HEIGHT = 1u << 0,
    OCEAN_SAMPLE_DISPLACEMENT = 1u << 1,  /* dx, dz */
    OCEAN_SAMPLE_SLOPE = 1u << 2,         /* slope_x, slope_z */
    OCEAN_SAMPLE_FOAM = 1u << 3,          /* dxx, dzz, dxz, bq, jacobian, foam */
    OCEAN_SAMPLE_VELOCITY = 1u << 4,
    OCEAN_SAMPLE_ALL = (1u << 5) - 1
};

/* ocean_frame_sample restricted to the groups in `want`: a mesh vertex
 * needs height and displacement, a height+normal tile height and slopes,
 * so neither pays for the 8 to 11 channels a full sample interpolates.
 * Each field it fills is bit-identical to ocean_frame_sample's. */
void ocean_frame_sample_some(const ocean_frame *f, double x, double z, unsigned want,
                             ocean_point *out);

/* The summed cascades at a world point read to within about a millimetre
 * of the waves themselves (ocean_frame_sample's bilinear reading leaves
 * centimetres between grid points): height and displacement by Hermite
 * interpolation on 4 x 4 nodes with the frame's own spectral derivatives
 * (slopes; Dxx, Dxz, Dzz), the other channels by 4 x 4 cubic Lagrange.
 * Needs OCEAN_FX_NORMALS for an accurate height and OCEAN_FX_FOAM for an
 * accurate displacement (without them those are read by Lagrange alone).
 * If err is not NULL, err->height, err->dx and err->dz receive a bound on
 * each one's interpolation error against the frame's own waves (see the
 * comment in ocean_accurate.c; INFINITY where a needed derivative channel is
 * missing); its other fields are 0.  Its foam has the cubic reading's
 * ramp (OCEAN_FOAM_CUBIC).  About ten times the cost of the
 * bilinear reading (bench_near): meant for queries, not mesh vertices. */
void ocean_frame_sample_accurate(const ocean_frame *f, double x, double z, unsigned want,
                                 ocean_point *out, ocean_point *err);

/* Statistics of an evaluated frame.  Variance adds over cascades (their
 * bands are disjoint, so cross terms vanish over the plane); the Jacobian
 * is that of the summed displacement, sampled on the finest cascade's grid
 * (where the coarser cascades are smooth).  Fields not evaluated give 0
 * (min_jacobian 1). */
typedef struct ocean_field_stats {
    double mean, hs;             /* of the height; hs = 4 std */
    double min_jacobian, folded_fraction;
    double foam_coverage;        /* mean foam over the finest cascade's grid
                                    nodes: a small patch, read without the
                                    damping of interpolation, so it runs
                                    above the sea's coverage (1.7x the
                                    whitecap target on the default 10 m/s
                                    sea, 2.7x at 8 m/s); for the coverage
                                    tiles carry use
                                    ocean_whitecap_coverage_frame (foam.h) */
} ocean_field_stats;
void ocean_frame_get_field_stats(const ocean_frame *f, ocean_field_stats *out);

/* Only the choppy displacement (dx, dz) of the summed cascades at a world
 * point: the inner step of query inversion, kept lean.  0 where the frame
 * has no displacement. */
void ocean_frame_sample_displacement(const ocean_frame *f, double x, double z,
                                     double *dx, double *dz);

/* h(k, t) of the wave with integer wave vector (mx, mz) of cascade c, in
 * double, built from h0(k) and h0(-k) drawn afresh: 0 outside the band.
 * For any (mx, mz), h(-k, t) = conj(h(k, t)) - the Hermitian symmetry that
 * makes every field real. */
void ocean_mode_amplitude(const ocean *o, int c, int mx, int mz, double t, double out[2]);

/* Statistics of the discretised spectrum. */
typedef struct ocean_spectrum_stats {
    double variance;     /* sum over all bands of E|h(k)|^2, m^2 */
    double hs;           /* 4 sqrt(variance) */
    double cascade_variance[OCEAN_MAX_CASCADES];
    double wp, tp, kp;   /* peak angular frequency, period, wave number */
    double lambda_dominant; /* 2 pi / kp */
} ocean_spectrum_stats;
void ocean_get_spectrum_stats(const ocean *o, ocean_spectrum_stats *out);

/* Cumulative counters since creation. */
typedef struct ocean_counters {
    uint64_t evaluations;
    uint64_t transforms;               /* all 2-D inverse FFTs */
    uint64_t transforms_by_effect[5];  /* height, displacement, normals, foam, velocity */
    uint64_t fft_calls;                /* FFTW executions of ocean_evaluate: transforms go
                                          in groups of at most 8.5 MB of spectra
                                          (N = 1024: 2 a call) */
    uint64_t modes_evolved;            /* modes of the half spectra whose h(k,t) the
                                          spectrum stage computed: only those of a row
                                          that hold a wave (a coarse cascade's band
                                          |k| < pi n / (2 patch) is ~20 % of its grid) */
    uint64_t modes_deep;               /* of those, modes in deep water (k d >= 22), whose
                                          frequency the stage computed (sqrt(g k) / 2 pi)
                                          instead of reading it from memory */
    /* Where ocean_evaluate's time went, in monotonic nanoseconds (wall time
     * of the parallel regions, so per evaluation, not per thread): */
    uint64_t ns_evolve;                /* stage passes that evolved h(k,t) (the first
                                          call of a cascade in a tick) and wrote that
                                          call's spectra */
    uint64_t ns_channels;              /* stage passes that read h(k,t) back from the
                                          tick's cache and wrote their call's spectra */
    uint64_t ns_fft;                   /* FFTW calls */
    uint64_t fft_calls_by_channel;     /* of fft_calls, those whose stage pass was split
                                          over the threads by channel, not by rows */
    uint64_t fft_calls_pruned;         /* of fft_calls, those that left out the column
                                          transforms of the columns no wave reaches: a
                                          coarse cascade's waves fill n/4 of its grid's
                                          n/2 + 1 columns, so its column pass halves */
} ocean_counters;
void ocean_get_counters(const ocean *o, ocean_counters *out);

/* The pyramid of band-limited grids ("mips") of cascade c that the
 * cascade tile layout streams (PROTOCOL.md "Cascade mips"): mip m is the
 * cascade on a grid of n / 2^m at cutoff kc[m] (kc[0] = INFINITY, the
 * whole cascade; kc[m] = (n / 2^(m+2)) dk for m >= 1: the Butterworth
 * cutoff at half the mip's Nyquist, whose gain-1/2 point still lies below
 * that Nyquist, so an ocean_evaluate at kc[m] runs on exactly n / 2^m).
 * *mips counts the mips that hold any wave (at most max_mips, grids of at
 * least OCEAN_MIN_N).  OCEAN_EINVAL for a bad cascade or order. */
ocean_result ocean_cascade_mips(const ocean *o, int c, int order, int max_mips, int *mips, double *kc);

/* Second moments of the waves of cascade c that a Butterworth mask
 * (kc, order) does not carry, as ocean_evaluate applies it (waves below
 * drop_gain left out entirely): each wave weighs E|h|^2 (1 - g^2), so
 * carried + removed = the cascade's whole energy.  Time-independent
 * expectations over the random amplitudes.  kc = INFINITY removes nothing,
 * kc = 0 everything.  The slope moments are what a renderer adds as
 * unresolved roughness (Bruneton, Neyret & Holzschuch 2010). */
typedef struct ocean_moments {
    double var_h;                 /* height variance removed, m^2 */
    double mss_x, mss_z, mss_xz;  /* E[(d eta/dx)^2], E[(d eta/dz)^2], E[...x ...z] removed */
    double total_var_h;           /* the cascade's whole height variance, m^2 */
    /* What the filtered band keeps, and the variance of its second time
     * derivative (w^4 weights, w from the dispersion relation): how fast
     * the kept heights and slopes change, which sets how long a sample of
     * them stays within a linear interpolation's error. */
    double kept_var_h, kept_var_h_tt;   /* m^2, m^2/s^4 */
    double kept_mss, kept_mss_tt;       /* x + z slope variance; its d^2/dt^2, 1/s^4 */
    /* The kept x + z slope variance (the breaking index's, foam.h) as a
     * reading at a uniformly random point between the nodes of the grid
     * this cutoff runs on holds it, per kernel (interp.h), which damps
     * the waves near the grid's Nyquist: kept_mss_read[k] / kept_mss is
     * the share a tile reader interpolating with k keeps (PROTOCOL.md
     * "Whitecaps in layout 1"). */
    double kept_mss_read[OCEAN_INTERP_KERNELS];
} ocean_moments;
ocean_result ocean_cascade_moments(const ocean *o, int c, double kc, int order, ocean_moments *out);

/* Variance the band of o holds after a Butterworth mask (cutoff_k, order);
 * used for E_error and the energy partition. */
double ocean_filtered_variance(const ocean *o, double cutoff_k, int order);

#endif
