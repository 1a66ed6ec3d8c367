/*
 * ocean_time.h - the one time limit of oceand, and the wave phase w t mod 2 pi
 * computed exactly below it.
 *
 * Why there is a limit.  Time is a double (seconds), and every wave's phase
 * is w t.  A double t stands for the instant the caller means only to half
 * an ulp, |dt| <= |t| 2^-53; w (a double from the dispersion relation)
 * likewise carries a relative 2^-53; and a client that follows PROTOCOL.md
 * with a plain double product w * t rounds it by the same half ulp.  Each
 * of these moves the phase by up to |w t| 2^-53, however exactly the
 * reduction itself is done.  The limit is the largest t for which that
 * stays below 1e-6 rad for every wave the simulation can hold:
 *
 *   every wave has w <= OCEAN_OMEGA_MAX = 64 rad/s (a 1.5 cm gravity wave:
 *   deep-water w = sqrt(g k) is the largest over depth, and waves this short
 *   are already below the capillary-gravity minimum of phase speed at
 *   lambda = 1.73 cm, where w^2 = g k tanh(k h) stops describing water;
 *   ocean_params_validate and ocean_gerstner_params_validate refuse shorter);
 *
 *   |w t| 2^-53 <= 2^6 * 2^27 * 2^-53 = 2^-20 rad = 9.5e-7 rad < 1e-6 rad
 *   for |t| <= OCEAN_TIME_MAX = 2^27 s = 134217728 s (4.25 years).
 *
 * Below the limit the reduction adds nothing measurable: ocean_phase and
 * the FFT ocean's row loop form the product w t as an unevaluated sum
 * (Dekker 1971 two-product, no FMA needed, so it vectorises on any x86-64)
 * of w / 2 pi held as a double-double, so the phase is reduced in turns,
 * where taking the nearest integer off is exact; the result is w t mod 2 pi
 * of the two doubles to within a few ulp of pi (< 4e-15 rad; 4.4e-16
 * measured), tested against __float128 in tests/test_ocean.c.  (The FFT
 * ocean computes deep water's w / 2 pi from the wave vector, within 3 ulp
 * of sqrt(g k) / 2 pi, as the dispersion relation's own rounding is within
 * a few: that double is the model's w, and the phase is exact for it.)
 * Above the limit every entry
 * point refuses t with OCEAN_EINVAL: the library (ocean_evaluate, the
 * Gerstner near field, queries), the protocol decoder (header sim_time,
 * camera.render_time, query.t, query_result.t, sea_state.effective_time),
 * the CLIs and oceand (which takes every client time through the decoder;
 * its own clock, seconds since start, reaches the limit after 4.25 years
 * of uptime, when its evaluations are refused too).
 *
 * Dekker's split needs IEEE double arithmetic rounded to nearest with no
 * contraction into FMA (the build's -std=c11 gives -ffp-contract=off) and
 * no -ffast-math.
 */
#ifndef OCEAN_TIME_H
#define OCEAN_TIME_H

#include <stddef.h>

#include "ocean_result.h"

/* Largest angular frequency of any wave the simulation holds, rad/s. */
#define OCEAN_OMEGA_MAX 64.0
/* Largest |t| anything accepts, s: 2^27. */
#define OCEAN_TIME_MAX 134217728.0
/* Phase uncertainty double precision leaves at the limit: 2^-20 rad. */
#define OCEAN_PHASE_ERROR_MAX 9.5367431640625e-07

/* 1 when t is a time anything accepts: finite and |t| <= OCEAN_TIME_MAX
 * (NaN fails both comparisons). */
static inline int ocean_time_ok(double t)
{
    return t >= -OCEAN_TIME_MAX && t <= OCEAN_TIME_MAX;
}

/* OCEAN_OK when ocean_time_ok(t); else OCEAN_EINVAL and a message naming
 * the field (e.g. "query.t"), the value and the limit in msg (if msg != NULL). */
ocean_result ocean_time_check(double t, const char *field, char *msg, size_t msglen);

/* w t mod 2 pi in [-pi, pi] (a few ulp beyond at the ends), w and t taken
 * as the exact values of the two doubles: error < 4e-15 rad for any
 * |w| <= OCEAN_OMEGA_MAX and |t| <= OCEAN_TIME_MAX (and for any |w t| below
 * 2^51 * 2 pi).  NaN when w or t is not finite or |w t| is beyond that.
 * The FFT ocean's vectorised row loop runs the same arithmetic
 * (ocean_phase_turns below), so testing this tests it. */
double ocean_phase(double w, double t);

/* --- the pieces, inline so sim's vector loops can use them ------------- */

/* 2 pi as C1 + C2 (C1 the nearest double, C2 the nearest double to the
 * rest; together 2 pi to 1e-33 relative). */
#define OCEAN_TWO_PI_C1 6.283185307179586232
#define OCEAN_TWO_PI_C2 2.4492935982947064e-16

/* Veltkamp split: x = *hi + *lo exactly, each half at most 26 bits, so a
 * product of two halves is exact in double. */
static inline void ocean_split(double x, double *hi, double *lo)
{
    double c = 134217729.0 * x; /* 2^27 + 1 */
    double h = c - (c - x);
    *hi = h;
    *lo = x - h;
}

/* w / 2 pi as a double-double: *hi + *lo equals it to ~2^-104 relative.
 * For |w| up to ~1e300. */
static inline void ocean_turns_of(double w, double *hi, double *lo)
{
    double f = w / OCEAN_TWO_PI_C1;
    /* Residual w - f (C1 + C2): f C1 is exact as p + e (Dekker), and
     * w - p is exact (p is within an ulp of w, Sterbenz). */
    double fh, fl, ch, cl;
    ocean_split(f, &fh, &fl);
    ocean_split(OCEAN_TWO_PI_C1, &ch, &cl);
    double p = f * OCEAN_TWO_PI_C1;
    double e = ((fh * ch - p) + fh * cl + fl * ch) + fl * cl;
    double r = ((w - p) - e) - f * OCEAN_TWO_PI_C2;
    *hi = f;
    *lo = r / OCEAN_TWO_PI_C1;
}

/* (fh + fl) t mod 1, times 2 pi: the phase, in [-pi, pi] within a few ulp,
 * for |fh t| < 2^51.  th, tl = ocean_split(t), hoisted out of loops.
 * Exact steps: p + e = fh t (Dekker); p - nearest integer (Sterbenz). */
static inline double ocean_phase_turns(double fh, double fl, double t, double th, double tl)
{
    double ah, al;
    ocean_split(fh, &ah, &al);
    double p = fh * t;
    double e = ((ah * th - p) + ah * tl + al * th) + al * tl;
    /* nearest integer without a libm call: 1.5 * 2^52 pushes the fraction
     * out of the significand (|p| < 2^51). */
    double n = (p + 6755399441055744.0) - 6755399441055744.0;
    double r = (p - n) + (e + fl * t);
    return r * OCEAN_TWO_PI_C1;
}

/* ocean_phase_turns with the product's error from one fused multiply-add:
 * fma(fh, t, -p) is fh t - p exactly, as Dekker's sum above is, so both
 * give the same bits.  Only for code compiled for a target with FMA (a
 * call elsewhere would go to libm's software fma). */
#if defined(__GNUC__)
static inline double ocean_phase_turns_fma(double fh, double fl, double t)
{
    double p = fh * t;
    double e = __builtin_fma(fh, t, -p);
    double n = (p + 6755399441055744.0) - 6755399441055744.0;
    double r = (p - n) + (e + fl * t);
    return r * OCEAN_TWO_PI_C1;
}
#endif

#endif
