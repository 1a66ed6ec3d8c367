/*
 * spectrum.h - wave spectra, directional spreading, dispersion, Beaufort.
 *
 * Pure double-precision functions of the sea state; no allocation, no state.
 * Every formula and check value comes from the published source named where
 * it is used (Pierson & Moskowitz 1964, Hasselmann et al. 1973, Bouws et al.
 * 1985, Horvath 2015, Tessendorf 2001).  Wind speed is always U10 (m/s at
 * 10 m); Pierson-Moskowitz converts to U19.5 itself.
 *
 * Conventions: S(w) is the one-sided variance density in angular frequency
 * (m^2 s/rad), integral S dw = m0.  D(theta, w) integrates to 1 over
 * theta in [-pi, pi], theta measured from the direction waves travel to.
 * The 2-D wave-number density is F(k) = S(w(k)) dw/dk D(theta) / k, with
 * integral F dkx dkz = m0.
 */
#ifndef OCEAN_SPECTRUM_H
#define OCEAN_SPECTRUM_H

#include <stddef.h>

#include "ocean_result.h"

/* g behind the published check values the tests use (deep water, lambda
 * 100 m -> w = sqrt(2 pi g / 100) = 0.78510 rad/s, T = 8.003 s). */
#define OCEAN_G 9.81

typedef enum ocean_spectrum_kind {
    OCEAN_SPECTRUM_PHILLIPS = 0,
    OCEAN_SPECTRUM_PM = 1,
    OCEAN_SPECTRUM_JONSWAP = 2,
    OCEAN_SPECTRUM_TMA = 3,
    OCEAN_SPECTRUM_COUNT_
} ocean_spectrum_kind;

typedef enum ocean_spreading_kind {
    OCEAN_SPREAD_TESSENDORF = 0,   /* (2/pi) cos^2 theta, downwind half plane */
    OCEAN_SPREAD_MITSUYASU = 1,    /* cos-2s, Mitsuyasu's s(w) */
    OCEAN_SPREAD_HASSELMANN = 2,   /* cos-2s, Hasselmann's s(w) */
    OCEAN_SPREAD_DONELAN_BANNER = 3,
    OCEAN_SPREAD_COUNT_
} ocean_spreading_kind;

/* The least non-zero choppiness (ocean_sea_state_validate says why). */
#define OCEAN_CHOPPINESS_MIN 1e-3

typedef struct ocean_sea_state {
    ocean_spectrum_kind spectrum;
    ocean_spreading_kind spreading;
    int whitecaps;        /* 1: whitecaps where the waves break (foam, at the
                             wind's coverage); 0: none (a CIGI host's Maritime
                             Surface Conditions Control may turn them off) */
    int unused_;          /* 0: no padding in the struct (test_conf compares
                             ocean_params whole, to find a field the config
                             table misses) */
    double wind_u10;      /* m/s at 10 m, 0..100 */
    double wind_dir_deg;  /* direction the wind blows toward, degrees from +x to +z */
    double fetch_m;       /* JONSWAP/TMA fetch, 1 m .. 1e7 m */
    double depth_m;       /* water depth, 0.01 m .. 12 km; finite-depth dispersion */
    double swell;         /* swell parameter xi >= 0: s += 16 tanh(wp/w) xi^2 */
    double phillips_a;    /* Phillips constant A (density form, see spectrum.c) */
    double small_wave_m;  /* Phillips small-wave suppression length l, m */
    double choppiness;    /* lambda for the choppy displacement: 0, or
                             OCEAN_CHOPPINESS_MIN .. 10 */
} ocean_sea_state;

/* Shipped defaults: PM, Mitsuyasu, 10 m/s toward +x, 100 km fetch, 4 km deep. */
void ocean_sea_state_default(ocean_sea_state *s);

/* Range/NaN check of every field; message names the field. */
ocean_result ocean_sea_state_validate(const ocean_sea_state *s, char *msg, size_t msglen);

/* Names for options and config ("phillips", "pierson-moskowitz", ...).
 * *_parse returns OCEAN_EINVAL for unknown names. */
const char *ocean_spectrum_name(ocean_spectrum_kind k);
const char *ocean_spreading_name(ocean_spreading_kind k);
ocean_result ocean_spectrum_parse(const char *name, ocean_spectrum_kind *out);
ocean_result ocean_spreading_parse(const char *name, ocean_spreading_kind *out);

/* Dispersion w(k) = sqrt(g k tanh(k h)) and dw/dk, overflow-free for any
 * k >= 0, h > 0 (sech^2 = 1 - tanh^2).  w(0) = 0, dw/dk(0) = sqrt(g h). */
double ocean_dispersion(double k, double depth);
double ocean_dispersion_dk(double k, double depth);
/* Inverse: the k with ocean_dispersion(k, depth) == w (Newton, double). */
double ocean_wavenumber(double w, double depth);

/* Peak angular frequency of the sea state's spectrum (rad/s); 0 for no wind. */
double ocean_spectrum_peak(const ocean_sea_state *s);

/* One-sided S(w) in m^2 s/rad for PM, JONSWAP and TMA (TMA uses depth);
 * for Phillips, the equivalent S(w) of its density form.  0 at w <= 0 and
 * for no wind; never NaN. */
double ocean_spectrum_s(const ocean_sea_state *s, double w);

/* TMA depth factor Phi(w_h), w_h = w sqrt(h/g) (Bouws et al. 1985). */
double ocean_tma_phi(double w, double depth);

/* Directional spreading D(theta, w), theta relative to the wind; integrates
 * to 1 over [-pi, pi] for every w > 0. */
double ocean_spreading_d(const ocean_sea_state *s, double theta, double w);

/* cos-2s normalisation Q(s) = 2^(2s-1) Gamma(s+1)^2 / (pi Gamma(2s+1)),
 * computed in logs (finite for s up to 1e6). */
double ocean_cos2s_norm(double s);

/* 2-D wave-number variance density F(kx, kz) in m^4 (see header comment),
 * including Phillips small-wave suppression.  0 at k = 0. */
double ocean_spectrum_f(const ocean_sea_state *s, double kx, double kz);

/* D(theta, w) at one w, its w-dependent parts (the peak, the spreading
 * exponent and its normalisation: pow, tanh and lgamma) computed once. */
typedef struct ocean_spreading {
    ocean_spreading_kind kind;
    int uniform;          /* 1 / (2 pi) at every theta */
    double sv;            /* cos-2s: the exponent s(w) */
    double lnorm;         /* cos-2s: ln Q(s) */
    double b, pre;        /* Donelan-Banner: beta and b / (2 tanh(b pi)) */
} ocean_spreading;

/* One direction theta (radians from the wind), its theta-dependent parts
 * for spreading `kind` computed once: a sum over wave numbers at one
 * direction takes them from here. */
typedef struct ocean_spreading_dir {
    double theta;         /* reduced to [-pi, pi] */
    double cos_theta;     /* Tessendorf: cos theta */
    double c_half;        /* cos-2s: |cos(theta / 2)| */
    double ln_c_half;     /* cos-2s: its log, when c_half > 0 */
} ocean_spreading_dir;

void ocean_spreading_at(const ocean_sea_state *s, double w, ocean_spreading *out);
void ocean_spreading_dir_at(ocean_spreading_kind kind, double theta, ocean_spreading_dir *out);
/* ocean_spreading_d(s, theta, w) is this of the two above, bit for bit. */
double ocean_spreading_eval(const ocean_spreading *d, const ocean_spreading_dir *dir);

/* F on the ring |k| = k: what depends on k alone (the spectrum, dw/dk and
 * the spreading at w(k)) computed once, for sums that sweep the direction
 * at fixed |k| (quadratures, a mode and its mirror).  ocean_spectrum_f is
 * ocean_spectrum_ring_f of ocean_spectrum_ring_at, bit for bit. */
typedef struct ocean_spectrum_ring {
    double k;             /* |k|, rad/m; F is 0 on the ring unless k > 0 */
    double radial;        /* S(w) dw/dk (Phillips: its density in k) */
    ocean_spreading d;
} ocean_spectrum_ring;

void ocean_spectrum_ring_at(const ocean_sea_state *s, double k, ocean_spectrum_ring *out);
/* F on the ring at direction dir (ocean_spreading_dir_at of the sea's
 * spreading). */
double ocean_spectrum_ring_f(const ocean_spectrum_ring *r, const ocean_spreading_dir *dir);

/* Beaufort force 0..12 -> representative U10 (midpoint of the Met Office
 * band; force 12 gives 35 m/s).  OCEAN_EINVAL outside 0..12. */
ocean_result ocean_beaufort_wind(int force, double *u10);

/* Analytic significant wave height of the 1-D spectrum (numerical
 * integration of S over w in double), m. */
double ocean_spectrum_hs(const ocean_sea_state *s);

#endif
