/*
 * foam.h - whitecap foam: where the sea breaks, and how much of it is white.
 *
 * Pure functions, no state (the ocean stays a pure function of (sea, seed,
 * t)).  The model has two parts.
 *
 * Where: Longuet-Higgins' breaking criterion.  A surface breaks where its
 * downward acceleration exceeds g/2 (the crest of the limiting Stokes wave,
 * Longuet-Higgins 1963, "The generation of capillary waves by steep
 * gravity waves", JFM 16, 138; Longuet-Higgins 1985, "Accelerations in
 * steep gravity waves", JPO 15, 1570).  For the linear deep-water field
 * the vertical acceleration is d2eta/dt2 = -sum w^2 eta_k = -g sum k eta_k,
 * and the choppy displacement's derivatives already hold sum k eta_k:
 * Dxx + Dzz = -lambda sum k eta_k.  So the breaking index
 *     beta = -(a_z / g) = -(Dxx + Dzz) / lambda
 * needs no extra transform; beta > 1/2 is active breaking (foam 1).
 *
 * How much: whitecap coverage is set by the energy the waves lose to
 * breaking, which in a wind sea balances the wind's input, proportional to
 * the friction velocity cubed (Wu 1979, "Oceanic whitecaps and sea state",
 * JPO 9, 1064; Phillips 1985, JFM 156, 505, sec. 6; Melville 1996, Annu.
 * Rev. Fluid Mech. 28, 279):
 *     W = K u*^3,   u* = sqrt(C_D) U10,  C_D = (0.8 + 0.065 U10) 1e-3 (Wu 1982).
 * K is a CALIBRATION CONSTANT, OCEAN_FOAM_K = 0.1693 s^3/m^3, fitted once
 * so that W equals Monahan & O'Muircheartaigh 1980 (W = 3.84e-6 U10^3.41)
 * at U10 = 12 m/s and nowhere else; tests/test_foam.c checks the coverage
 * of evaluated fields at 8, 12, 16, 20 and 26 m/s against Monahan.
 *
 * Why not a pure geometric threshold: a fully developed sea is
 * geometrically self-similar (Hs kp, and every slope or a/g statistic of
 * the dominant band, is independent of U10), so any fixed threshold on
 * beta, on the Jacobian or on slopes gives a coverage that grows only
 * through the fixed short-wave end of the band - logarithmically with
 * U10, against Monahan's U10^3.41.  (Measured in tests/test_foam.c on the
 * ship-bridge and storm oceans: beta > 1/2 alone covers 0.007 % to 0.37 %
 * and 0.001 % to 0.14 % between 8 and 26 m/s, where Monahan gives 0.46 %
 * to 26 %.)  The breaking criterion decides where the foam is, the energy
 * balance how much.
 *
 * The foam field: foam = clamp((beta - a) / (1/2 - a), 0, 1): 1 where the
 * Longuet-Higgins criterion holds (active breaking), fading to 0 at
 * beta = a on the flanks (the residual, stage-B foam of Monahan & Lu 1990,
 * which stays near the crests that made it).  For the Gaussian linear
 * field with std sigma_beta - as its reader reads it: ocean_stats.c counts
 * the power bilinear or cubic reading takes from near-Nyquist waves, one
 * ramp per reading (ocean.h ocean_foam_reading) - a is chosen
 * so the expected mean of foam, trails included (below), is W.  A filtered frame (fewer short waves, smaller sigma_beta) gets a
 * lower a: its mean foam is still W, spread more evenly - the whitecap
 * coverage of a sea does not depend on the camera.  When even a = -inf
 * cannot reach W (sigma_beta = 0: everything filtered) the field is the
 * uniform value W.  When active breaking alone exceeds W, a = 1/2 (a step
 * at the criterion).
 *
 * Persistence: a whitecap outlives the crest that made it.  Behind the
 * breaking crest the foam patch decays about exponentially, e-folding in
 * tau = 3.85 s in sea water (Monahan 1971, "Oceanic whitecaps", JPO 1,
 * 139: 3.85 s salt, 2.54 s fresh; Callaghan et al. 2012 see 0.5-8 s in
 * the field, longer for larger breakers), and it stays with the water,
 * not with the crest.  The frame's fields are indexed by the water's rest
 * position (the displacement moves every sample with its particle), so a
 * trail is a function of how long ago the crest passed that sample.  That
 * is read from the breaking index's analytic signal in time,
 * Z = beta + i q (q: each wave's beta a quarter period later, the Hilbert
 * transform in t, one more transform of the spectrum): |Z| is the crest
 * value of the wave group passing the sample, and arg Z the phase since
 * that crest (0 at the crest, growing at the mean rate omega = m1/m0 of
 * beta's spectrum: Rice 1944, "Mathematical analysis of random noise",
 * sec. 3.4; Longuet-Higgins 1957, Phil. Trans. A 249, 321).  So
 *     foam = max(f(beta), f(|Z|) exp(-arg Z / (omega tau)))
 * with f the ramp below: the active foam, or the crest's foam decayed for
 * the time since it passed, until the next crest.  Nothing accumulates:
 * foam is still a function of the waves at t alone.  The trail reaches
 * back one local wave period at most, which for the waves that break
 * (periods above 2 tau in a storm's dominant band) is most of its decay.
 *
 * Whitecap coverage (the definition every part of oceand uses): the area
 * mean of the foam field, foam in [0, 1] read as the fraction of a sample's
 * area that is white.  Chosen over "fraction of area with foam >= 0.5"
 * because it is what a renderer paints (foam as opacity) and it is
 * conserved by averaging: a coarse tile, a filtered level and the finest
 * level all report the same coverage, while a thresholded fraction would
 * change with resolution.
 */
#ifndef OCEAN_FOAM_H
#define OCEAN_FOAM_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "ocean_result.h"

/* Active breaking: beta = -a_z / g above this (Longuet-Higgins). */
#define OCEAN_FOAM_BETA_BREAK 0.5
/* Calibration constant of W = K u*^3 (see above), s^3/m^3. */
#define OCEAN_FOAM_K 0.1693
/* The wind speed K was calibrated at. */
#define OCEAN_FOAM_CALIBRATION_U10 12.0
/* e-folding time of a whitecap's foam after its crest has passed, s
 * (Monahan 1971, sea water). */
#define OCEAN_FOAM_DECAY_S 3.85

/* W = K u*^3 for U10 in m/s (0 for U10 <= 0 or NaN), capped at 0.95: a
 * sea is never solid white. */
double ocean_foam_coverage_target(double u10);

/* Monahan & O'Muircheartaigh 1980 (JPO 10, 2094, eq. 5): W = 3.84e-6
 * U10^3.41, as a fraction (0..1).  For reports; not used by the model. */
double ocean_foam_monahan(double u10);

/* The ramp of one evaluated field, and its trails. */
typedef struct ocean_foam_map {
    double a;        /* beta at which foam starts (may be < 0) */
    double b;        /* beta at which foam is 1 (OCEAN_FOAM_BETA_BREAK) */
    double uniform;  /* >= 0: the field is this constant (sigma = 0) */
    double decay;    /* 1 / (omega tau): the trail's decay per radian of
                        phase since its crest; INFINITY: no trail */
} ocean_foam_map;

/* Solves a for a field whose beta is Gaussian with std sigma and mean
 * frequency omega (rad/s; 0: a field that does not move, no trails) so
 * that the expected mean foam, trails included, is w (0 <= w < 1).
 * OCEAN_EINVAL for NaN/negative sigma or omega, or w outside [0, 1).
 * The last few solutions are kept per thread (a solve with trails
 * integrates numerically, about a millisecond). */
ocean_result ocean_foam_map_solve(double sigma, double omega, double w, ocean_foam_map *out);

/* Expected mean foam of the map over a Gaussian beta of std sigma: closed
 * form without trails (E[(X-a)+] - E[(X-b)+] over b - a), else over the
 * envelope (Rayleigh) and the phase since the crest (uniform), which are
 * independent for a Gaussian field. */
double ocean_foam_map_mean(const ocean_foam_map *m, double sigma);

/* The active foam at breaking index beta: the ramp alone. */
static inline double ocean_foam_ramp(const ocean_foam_map *m, double beta)
{
    if (m->uniform >= 0.0)
        return m->uniform;
    if (m->b <= m->a)
        return beta >= m->b ? 1.0 : 0.0;
    double f = (beta - m->a) / (m->b - m->a);
    return !(f > 0.0) ? 0.0 : (f > 1.0 ? 1.0 : f); /* NaN beta: no foam */
}

/* exp(-decay theta), theta = arg(beta + i q) in [0, 2 pi): how much of its
 * crest's foam a trail keeps.  Plain float arithmetic, no calls, so the
 * field pass (ocean.c) vectorises it: theta from a minimax arctangent
 * (|error| < 1e-5 rad; Abramowitz & Stegun 4.4.49's form, degree 11),
 * the exponential as 2^x with a degree-6 polynomial on the fraction
 * (relative error < 2e-5).  tests/test_foam.c checks it against libm. */
static inline float ocean_foam_fade(float beta, float q, float decay)
{
    float ab = beta < 0.0f ? -beta : beta, aq = q < 0.0f ? -q : q;
    float mx = ab > aq ? ab : aq, mn = ab > aq ? aq : ab;
    float den = mx > 0.0f ? mx : 1.0f, t = mn / den, t2 = t * t;
    float th = t * (0.99997726f + t2 * (-0.33262347f + t2 * (0.19354346f + t2 * (-0.11643287f +
                t2 * (0.05265332f + t2 * -0.01172120f)))));
    float th1 = 1.57079633f - th, th2, th3;
    th = aq > ab ? th1 : th;
    th2 = 3.14159265f - th;
    th = beta < 0.0f ? th2 : th;
    th3 = 6.28318531f - th;
    th = q < 0.0f ? th3 : th;
    float x = -decay * th * 1.44269504f; /* 2^x = e^(-decay th) */
    x = x > -126.0f ? x : -126.0f;
    float fl = floorf(x);
    int n = (int)fl;
    float f = x - fl;
    float p = 1.0f + f * (0.693147181f + f * (0.240226507f + f * (0.0555041087f + f * (0.00961812911f +
              f * (0.00133335581f + f * 0.000154035304f)))));
    union { int32_t i; float f; } sc = {.i = (n + 127) * (1 << 23)};
    return p * sc.f;
}

/* Foam at one point with breaking index beta and its quadrature q (the
 * analytic signal's imaginary part, above): the active foam or the last
 * crest's trail, whichever is whiter. */
static inline double ocean_foam_value(const ocean_foam_map *m, double beta, double q)
{
    double fi = ocean_foam_ramp(m, beta);
    if (!(m->decay < INFINITY) || fi >= 1.0 || m->uniform >= 0.0)
        return fi;
    double e = sqrt(beta * beta + q * q);
    if (!(e > m->a))
        return fi; /* the crest itself made no foam (or NaN) */
    double tr = ocean_foam_ramp(m, e) * ocean_foam_fade((float)beta, (float)q, (float)m->decay);
    return tr > fi ? tr : fi;
}

/* Whitecap coverage of n foam samples (a tile, a field): their mean, each
 * clamped to [0, 1]; NaN samples are skipped; 0 for n = 0 or all NaN. */
double ocean_whitecap_coverage(const float *foam, size_t n);

/* Whitecap coverage of an evaluated frame over the square [x0, x0 + size)
 * x [z0, z0 + size) (world metres), as tiles of spacing size / n carry it:
 * the mean foam of n x n point samples (ocean_frame_sample_some), n in
 * 1..4096.  Use a square of at least the largest patch for the sea's
 * coverage (smaller squares see a few wave groups only).  OCEAN_EINVAL
 * for NULL, non-finite or non-positive size, non-finite corner, n out of
 * range; 0 for a frame without foam channels. */
struct ocean_frame;
ocean_result ocean_whitecap_coverage_frame(const struct ocean_frame *f, double x0, double z0,
                                           double size_m, int n, double *out);

#endif
