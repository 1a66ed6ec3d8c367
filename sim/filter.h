/*
 * filter.h - the velocity-adaptive Butterworth low-pass.
 *
 * Pure functions and small value types, no allocation: the Butterworth gain
 * and its negligible band, the per-client cutoff policies (seed 000 as
 * written, anti-aliasing, none), a frame-to-frame smoother for a client's
 * cutoff, cutoff buckets shared by clients of similar speed, the E_error /
 * energy-redistribution arithmetic over spectral modes, and the dominant
 * wavelength / suggested mesh spacing.  The FFT ocean (ocean.c) applies the
 * gains to its modes, the Gerstner near field (gerstner.c) to its waves.
 *
 * Units: wave numbers in rad/m, frequencies in Hz unless named omega
 * (rad/s), speeds in m/s, times in s.
 */
#ifndef OCEAN_FILTER_H
#define OCEAN_FILTER_H

#include <stddef.h>

#include "ocean_result.h"
#include "spectrum.h"

#define OCEAN_FILTER_DEFAULT_ORDER 6   /* seed 000's sixth-order Butterworth */
#define OCEAN_FILTER_MAX_ORDER 64

/* ---- Butterworth gain --------------------------------------------------- */

/* Amplitude gain H(k) = 1 / sqrt(1 + (k/kc)^(2n)) of the order-n
 * Butterworth at wave number k >= 0 for cutoff kc >= 0, evaluated without
 * overflow or NaN for any ratio (the naive (k/kc)^(2n) overflows float
 * once k/kc > 65536 at n = 4): k <= kc uses
 * q = (k/kc)^n, H = 1/sqrt(1+q^2); k > kc uses q = (kc/k)^n,
 * H = q/sqrt(1+q^2).  Conventions at the edges: kc = INFINITY gives 1 for
 * every k (no filter); kc = 0 gives 0 for every k (everything filtered,
 * ocean_request.cutoff_k = 0); k = INFINITY with finite kc gives 0.
 * Returns NaN for NaN or negative k or kc, or order outside
 * 1..OCEAN_FILTER_MAX_ORDER (callers validate those first). */
double ocean_filter_gain(double k, double kc, int order);

/* The smallest wave number above which H < eps:
 * k_neg = kc ((1 - eps^2) / eps^2)^(1/(2n)), computed in logs.  Every mode
 * with |k| > k_neg has gain below eps, so the FFT may drop that band (and a
 * smaller transform serves once k_neg is below the grid's Nyquist).
 * kc = INFINITY gives INFINITY, kc = 0 gives 0; eps >= 1 gives 0 (every
 * gain is below it), eps <= 0 gives INFINITY.  NaN for invalid kc/order
 * or NaN eps. */
double ocean_filter_negligible_k(double kc, int order, double eps);

/* ---- Cutoff policies ------------------------------------------------------ */

typedef enum ocean_filter_policy {
    OCEAN_FILTER_NONE = 0,       /* no filter: cutoff INFINITY */
    OCEAN_FILTER_SEED = 1,       /* seed 000: fc = f_base + beta |v| */
    OCEAN_FILTER_ANTIALIAS = 2,  /* highest cutoff that does not alias */
    OCEAN_FILTER_POLICY_COUNT_
} ocean_filter_policy;

const char *ocean_filter_policy_name(ocean_filter_policy p);
/* "none", "seed", "antialias" -> policy; OCEAN_EINVAL otherwise. */
ocean_result ocean_filter_policy_parse(const char *name, ocean_filter_policy *out);

/* Parameters of the policies; one per sea state (shared by all clients).
 *
 * seed policy (seed 000 as written):
 *   fc = f_base_hz + beta |v|, beta = beta_fast if |v| > beta_switch_mps
 *   else beta_slow (0.2 and 0.05 Hz per m/s, 5 m/s in the seed);
 *   kc = 2 pi fc / v_wave_mps.
 *   v_wave_mps converts the seed's temporal cutoff into a wave number: a
 *   wave travelling at v_wave with frequency fc has k = 2 pi fc / v_wave.
 *   The seed leaves it open; the default is the phase speed of the dominant
 *   wave, c_p = w_p / k_p (finite depth), so fc = f_p maps to k_p and the
 *   ratio kc/k_p equals fc/f_p.
 *   f_base_hz is the static camera's cutoff frequency.  Default 3 Hz: for
 *   a 10 m/s Pierson-Moskowitz sea (f_p = 0.133 Hz) kc = 22 k_p, which
 *   keeps E_error (about 4 %) under seed 000's 5 % guard (2 Hz gives
 *   6 %); stronger winds (lower f_p) filter less.
 *   Above boost_speed_mps (10 m/s) the seed boosts low frequencies by 3 %:
 *   ocean_filter_cutoff.low_boost = 1 + boost_fraction.
 *
 * antialias policy: kc = min(k_space, k_time) (then lowered by alias_gain):
 *   k_space = 2 pi / (4 dx): at least 4 samples per wavelength at the mesh
 *     spacing dx the client receives (2 is too few for foam and normals:
 *     Crest, wave-harmonic/crest PR #903, moved to 4); no spatial limit
 *     when dx = 0.
 *   k_time solves omega(k) + |v| k = pi fps (finite-depth dispersion with
 *     depth_m): the fastest apparent phase rate of a wave seen from a camera
 *     moving at |v| against it stays below the Nyquist of the frame rate;
 *     no temporal limit when fps = 0.
 *   alias_gain is the largest Butterworth gain allowed at that limit; the
 *   default 1/sqrt(2) puts kc on the limit itself, smaller values move kc
 *   below it by ((1-g^2)/g^2)^(1/(2n)).
 */
typedef struct ocean_filter_config {
    int order;               /* Butterworth order, 1..64 (default 6) */
    double f_base_hz;        /* seed: static cutoff, Hz (default 3) */
    double beta_slow;        /* seed: Hz per m/s at or below the switch (0.05) */
    double beta_fast;        /* seed: Hz per m/s above the switch (0.2) */
    double beta_switch_mps;  /* seed: 5 m/s */
    double boost_speed_mps;  /* seed: low-frequency boost above this (10 m/s) */
    double boost_fraction;   /* seed: 0.03 */
    double v_wave_mps;       /* seed: fc -> kc conversion speed, > 0 */
    double depth_m;          /* antialias: depth of the dispersion relation */
    double alias_gain;       /* antialias: gain at the aliasing limit, (0, 1/sqrt 2] */
} ocean_filter_config;

/* Defaults above; v_wave and depth from the sea state (the dominant wave's
 * phase speed; for a calm sea, which has no dominant wave, the phase speed
 * of a 10 s deep-water wave, 15.6 m/s).  sea may be NULL: 10 m/s PM
 * defaults are used. */
void ocean_filter_config_default(ocean_filter_config *c, const ocean_sea_state *sea);

/* Range and NaN check of every field; the message names the field. */
ocean_result ocean_filter_config_validate(const ocean_filter_config *c, char *msg, size_t msglen);

/* What one client looks like to the filter. */
typedef struct ocean_filter_client {
    double speed_mps;  /* camera speed |v| >= 0, finite */
    double fps;        /* client frame rate, Hz; 0: no temporal limit */
    double spacing_m;  /* finest mesh spacing the client receives; 0: none */
} ocean_filter_client;

/* The cutoff a policy chose for a client. */
typedef struct ocean_filter_cutoff {
    double k;          /* rad/m; INFINITY for "none"; never NaN */
    double hz;         /* seed: fc; antialias: apparent frequency of the
                          cutoff wave (omega(kc) + |v| kc) / 2 pi; NaN for
                          none or when kc is INFINITY */
    double low_boost;  /* gain on the passed band (seed: 1.03 above 10 m/s,
                          else 1); see ocean_filter_cutoff_gain */
    int order;
    int limited_by;    /* antialias: 1 spatial, 2 temporal, 0 neither */
} ocean_filter_cutoff;

/* Chooses the cutoff for client cl under policy p.  OCEAN_EINVAL (and *out
 * untouched) for NaN/Inf/negative speed, fps or spacing, or an invalid
 * config.  Any finite speed gives a finite result (1e6 m/s included). */
ocean_result ocean_filter_cutoff_compute(const ocean_filter_config *c, ocean_filter_policy p,
                                         const ocean_filter_client *cl, ocean_filter_cutoff *out);

/* The per-mode gain the evaluation applies at wave number k:
 * H(k; kc, n) * (1 + (low_boost - 1) H(k)^2).  The boost weight H^2 makes
 * the seed's "boost the low frequencies" smooth: the full boost well below
 * kc, half of it at kc, none above, so no step is added to the mask. */
double ocean_filter_cutoff_gain(const ocean_filter_cutoff *c, double k);

/* ---- Smoothing a client's cutoff over time ------------------------------- */

/* A client's cutoff, moved toward its target every frame by a first-order
 * filter in log k (time constant tau_s) whose step is also rate-limited to
 * max_log_rate per second (|d ln k / dt|).  The step always points toward
 * the target and never passes it, so there is no overshoot; within 1e-6 in
 * ln k it snaps to the target, so it settles exactly.  The state lives in
 * [k_floor, k_ceil]; a target of 0 or INFINITY is approached through that
 * range and reported exactly (0 / INFINITY) once the state reaches the
 * bound: k_floor should be below the longest wave and k_ceil above the
 * shortest wave of the ocean, so those last steps change no gain. */
typedef struct ocean_filter_smoother {
    double tau_s;         /* first-order time constant (default 0.25 s) */
    double max_log_rate;  /* max |d ln k/dt|, 1/s (default 2: x7.4 per s) */
    double k_floor;       /* default 1e-4 rad/m (63 km) */
    double k_ceil;        /* default 1e4 rad/m (0.6 mm) */
    double log_k;         /* state */
    double k;             /* last reported cutoff */
    int primed;           /* 0 until the first update */
} ocean_filter_smoother;

void ocean_filter_smoother_init(ocean_filter_smoother *s);

/* Advances s by dt seconds toward target_k and returns the new cutoff in
 * *k_out.  The first update jumps to the target (there is nothing to pop
 * from).  OCEAN_EINVAL for NaN/negative target, NaN/Inf/negative dt or
 * invalid smoother parameters; the state is then unchanged. */
ocean_result ocean_filter_smoother_update(ocean_filter_smoother *s, double target_k, double dt,
                                          double *k_out);

/* ---- Buckets -------------------------------------------------------------- */

/* Clients are grouped by cutoff so one filtered evaluation serves every
 * client in a bucket.  Levels are geometric:
 *   bucket 0                     cutoff 0 (everything filtered)
 *   bucket i, 1 <= i <= L        k_lo * 2^((i-1)/per_octave)
 *   bucket L+1                   INFINITY (unfiltered)
 * with L = per_octave * octaves + 1, so the levels span k_lo .. k_lo 2^octaves.
 * Defaults: 4 levels per octave (steps of 19 %), k_lo = 2^-10 rad/m
 * (6.4 km), 20 octaves (up to 1024 rad/m, 6 mm): 83 buckets.
 * Quantisation is downward (the largest level <= kc): a client never gets
 * more high-frequency content than its policy asked for, so an antialias
 * cutoff stays alias-free after bucketing; the price is at most one step
 * (19 %) of extra filtering.  Finite kc above the top level maps to the top
 * level (it already passes every wave of a real ocean); kc below k_lo maps
 * to bucket 0. */
typedef struct ocean_filter_buckets {
    int per_octave;  /* 1..64 */
    int octaves;     /* 1..128 */
    double k_lo;     /* > 0, finite */
} ocean_filter_buckets;

void ocean_filter_buckets_default(ocean_filter_buckets *b);
ocean_result ocean_filter_buckets_validate(const ocean_filter_buckets *b);
int ocean_filter_bucket_count(const ocean_filter_buckets *b);
/* kc -> bucket index (downward).  OCEAN_EINVAL for NaN/negative kc. */
ocean_result ocean_filter_bucket_of(const ocean_filter_buckets *b, double kc, int *index);
/* Bucket index -> its representative cutoff; OCEAN_EINVAL out of range.
 * ocean_filter_bucket_of(ocean_filter_bucket_cutoff(i)) == i for every i. */
ocean_result ocean_filter_bucket_cutoff(const ocean_filter_buckets *b, int index, double *kc);

/* ---- E_error and energy redistribution ----------------------------------- */

/* Accumulates, over spectral modes with variance P >= 0 and gain g:
 *   sum P, sum g^2 P, sum (1 - g)^2 P.
 * E_error = ||H - H_f||_2 / ||H||_2 = sqrt(sum (1-g)^2 P / sum P) (the
 * norms of the complex amplitude fields; by Parseval the same in space).
 * Redistribution (seed 000's energy guard): the filtered mode amplitudes
 * are multiplied by one scale s = sqrt(sum P / sum g^2 P), so the filtered
 * field's variance sum (s g)^2 P equals the unfiltered sum P exactly; the
 * E_error of the redistributed field is sqrt(sum (1 - s g)^2 P / sum P). */
typedef struct ocean_filter_energy {
    double sum_p, sum_g2p, sum_1mg2p, sum_gp;
} ocean_filter_energy;

void ocean_filter_energy_init(ocean_filter_energy *e);
/* Adds one mode; NaN/negative P or NaN gain are ignored (they cannot come
 * from a valid spectrum) so a sum is never poisoned. */
void ocean_filter_energy_add(ocean_filter_energy *e, double gain, double p);
/* E_error; 0 when there is no variance at all. */
double ocean_filter_energy_e_error(const ocean_filter_energy *e);
/* Redistribution scale s; 1 when sum P = 0 or nothing passes the filter
 * (sum g^2 P = 0: there is no band to carry the energy). */
double ocean_filter_energy_scale(const ocean_filter_energy *e);
/* E_error of the redistributed field, sqrt(sum (1 - s g)^2 P / sum P)
 * = sqrt(1 - 2 s sum gP / sum P + s^2 sum g^2 P / sum P), clamped >= 0. */
double ocean_filter_energy_e_error_redistributed(const ocean_filter_energy *e);

/* Convenience over arrays: mode wave numbers k[i] and variances p[i],
 * gain ocean_filter_cutoff_gain(c, k[i]).  OCEAN_EINVAL for NULL arrays
 * with n > 0. */
ocean_result ocean_filter_energy_modes(const ocean_filter_cutoff *c, const double *k,
                                       const double *p, size_t n, ocean_filter_energy *out);

/* Over an isotropic 1-D variance density psi(k) (m^2 per rad/m) on
 * [k_a, k_b], 0 < k_a < k_b < INF: composite Gauss-Legendre (8 points) on
 * `panels` log-spaced panels.  OCEAN_EINVAL on bad bounds/panels. */
ocean_result ocean_filter_energy_integrate(const ocean_filter_cutoff *c,
                                           double (*psi)(double k, void *ctx), void *ctx,
                                           double k_a, double k_b, int panels,
                                           ocean_filter_energy *out);

/* ---- Dominant wavelength and mesh spacing -------------------------------- */

/* lambda_dominant = 2 pi / k_p, k_p = ocean_wavenumber(w_p, depth) from
 * the spectrum's peak.  OCEAN_EUNSUPPORTED for a calm sea (no peak),
 * OCEAN_EINVAL for an invalid sea state. */
ocean_result ocean_filter_dominant_wavelength(const ocean_sea_state *sea, double *lambda_m);

/* Seed 000's mesh spacing dx = factor * lambda_dominant, factor in
 * [0.1, 0.5] (OCEAN_EINVAL outside). */
ocean_result ocean_filter_mesh_spacing(const ocean_sea_state *sea, double factor, double *dx_m);

#endif
