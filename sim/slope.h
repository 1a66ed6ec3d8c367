/*
 * slope.h - slope second moments of the represented sea, split by what a
 * Butterworth-filtered geometry level carries and what it leaves to shading.
 *
 * After Bruneton, Neyret & Holzschuch 2010 ("Real-time realistic ocean
 * lighting using seamless transitions from geometry to BRDF", Comput.
 * Graph. Forum 29(2)): a level whose geometry holds the
 * waves below its cutoff must hand the slope variance of every shorter
 * wave to the BRDF, so that geometry + roughness shows the same sea from
 * any distance.  This module computes, for one sea (an ocean, optionally
 * its Gerstner near field) and one cutoff (kc, order n):
 *
 *   resolved  the waves geometry carries: each weighted by G(k)^2, with
 *             G the gain the evaluation really applies (the Butterworth
 *             H(k) = 1/sqrt(1 + (k/kc)^2n) of filter.h; the FFT ocean also
 *             drops every mode above ocean_filter_negligible_k(kc, n,
 *             drop_gain), G = 0 there, exactly as ocean_evaluate does);
 *   carried   what geometry leaves out: weight 1 - G(k)^2 on the same
 *             waves, plus the whole short-wave tail (below), which no
 *             level's geometry ever holds;
 *   total     resolved + carried = everything represented, independent of
 *             the cutoff.
 *
 * Three sources, reported separately and summed:
 *   fft   the FFT cascades' own discrete modes, exactly: the sum over every
 *         in-band mode of every cascade of the expected variance
 *         E|h(k,t)|^2 = F(k) dk^2 (F = ocean_spectrum_f, the same P(k) the
 *         ocean draws its amplitudes from; time-independent);
 *   near  the Gerstner near field's waves, each a^2/2 with its amplitude;
 *   tail  waves shorter than the shortest simulated one, up to the
 *         capillary cutoff OCEAN_SLOPE_K_CAPILLARY (1 mm): the sea state's
 *         own spectrum F(k) continued from the simulated edge up to
 *         OCEAN_SLOPE_K_GRAVITY (10 cm wavelength; wave vectors in the
 *         FFT square's corners or a gap before the near field included),
 *         then the short-wave curvature spectrum B_h of Elfouhaily,
 *         Chapron, Katsaros & Vandemark 1997 ("A unified directional
 *         spectrum for long and short wind-driven waves", JGR 102(C7)
 *         15781), eqs. 40-44 and the spreading of eqs. 57-59, beyond the
 *         larger of that and the shortest simulated wave.  Elfouhaily's
 *         spectrum was fitted to Cox & Munk 1954's clean-surface slopes;
 *         our long-wave part is the sea state's spectrum (PM/JONSWAP/TMA/
 *         Phillips, whose saturation range holds the short gravity waves
 *         to 10 cm), B_h adds the gravity-capillary range.  With this tail
 *         the total mean-square slope lies within 10 % of Cox-Munk at
 *         U10 = 5..15 m/s for the shipped PM sea (tests/test_slope.c).
 *
 * Moments (dimensionless, world axes x and z, y up):
 *   mss_x = <(d eta/dx)^2>, mss_z = <(d eta/dz)^2>,
 *   mss_xz = <(d eta/dx)(d eta/dz)>, energy = <eta^2> (m^2).
 * A wave of amplitude a and wave vector (kx, kz) adds a^2/2 times
 * (kx^2, kz^2, kx kz, 1).  Slopes are those of the linear height field
 * (the Gerstner/choppy horizontal displacement is not folded in).
 *
 * The near field's "resolved" share assumes its waves are in the level's
 * geometry at gain H; the daemon fades them out beyond the camera's fade
 * radius, so a level lying outside it should count near_resolved as
 * carried too (the caller knows the fade, this module does not).
 *
 * Cost: ocean_slope_table_create precomputes everything that does not
 * depend on the cutoff (~10-60 ms: one spectrum evaluation per FFT mode and
 * a tail quadrature); ocean_slope_table_get is memoised per (kc, order)
 * (64 entries, round robin): a hit is a table look-up, a miss one pass
 * over the modes whose gain is neither 1 nor 0 (sorted by |k|, prefix
 * sums on both sides), well under a millisecond at N = 256 x 3 cascades.
 */
#ifndef OCEAN_SLOPE_H
#define OCEAN_SLOPE_H

#include <stddef.h>

#include "gerstner.h"
#include "ocean.h"
#include "ocean_result.h"

/* The tail's edges: the sea state's spectrum holds the gravity waves down
 * to 10 cm (2 pi / 0.1 m); Elfouhaily's B_h runs from there (or from the
 * shortest simulated wave, if shorter) to 1 mm, where its capillary
 * factor F_m = exp(-(k/k_m - 1)^2 / 4) (k_m = 370 rad/m) is below 1e-27:
 * the integral is complete. */
#define OCEAN_SLOPE_K_GRAVITY (2.0 * M_PI / 0.1)
#define OCEAN_SLOPE_K_CAPILLARY (2.0 * M_PI / 1e-3)

typedef struct ocean_slope_moments {
    double mss_x, mss_z, mss_xz; /* slope second moments, dimensionless */
    double energy;               /* height variance, m^2 */
} ocean_slope_moments;

typedef struct ocean_slope_stats {
    double k_cut;        /* the cutoff the evaluation applies
                            (ocean_effective_cutoff: INFINITY when it
                            changes nothing); rad/m */
    int order;
    /* per source */
    ocean_slope_moments fft_resolved, fft_carried;
    ocean_slope_moments near_resolved, near_carried; /* 0 without near field */
    ocean_slope_moments tail;        /* always carried, never resolved */
    ocean_slope_moments tail_sea;    /* of which: the sea state's spectrum */
    ocean_slope_moments tail_short;  /* of which: Elfouhaily's B_h */
    /* sums */
    ocean_slope_moments resolved;    /* fft_resolved + near_resolved */
    ocean_slope_moments carried;     /* fft_carried + near_carried + tail */
    ocean_slope_moments total;       /* resolved + carried */
    double mss_resolved, mss_carried, mss_total; /* mss_x + mss_z of each */
    /* the tail's band: from the shortest simulated wave (the FFT square's
     * inscribed edge or k_max, or the near field's k_hi) to the capillary
     * cutoff; B_h starts at k_short */
    double k_sim_top, k_short, k_capillary;
} ocean_slope_stats;

/* Cox & Munk 1954 clean-surface mean-square slope (Cox & Munk 1954,
 * "Measurement of the roughness of the sea surface from photographs of the
 * sun's glitter", JOSA 44(11) 838, eq. of Fig. 7: sigma^2 = 0.003 +
 * 5.12e-3 U, U in m/s at 12.5 m above the sea), from U10: U12.5 = U10 +
 * (u* / kappa) ln(12.5 / 10) (neutral log profile, von Karman kappa =
 * 0.4), u* = sqrt(C_D) U10 with Wu's (1982, JGR 87(C12) 9704) drag law
 * C_D = (0.8 + 0.065 U10) 1e-3.  Reference for tests and reports; NaN for
 * NaN or negative U10. */
double ocean_slope_cox_munk_mss(double u10);
/* U12.5 from U10 as above. */
double ocean_slope_u125(double u10);

/* Elfouhaily et al. 1997 short-wave curvature spectrum B_h(k) (eq. 40:
 * B_h = (alpha_m / 2) (c_m / c) F_m, c_m = 0.23 m/s, k_m = 370 rad/m,
 * c(k) = sqrt(g/k (1 + (k/k_m)^2)), F_m = exp(-(k/k_m - 1)^2 / 4) eq. 41,
 * alpha_m = 0.01 (1 + ln(u* / c_m)) for u* <= c_m, 0.01 (1 + 3 ln(u* / c_m))
 * above, eq. 44, clamped >= 0 below U10 ~ 2.6 m/s where the fit ends),
 * u* from U10 as in ocean_slope_cox_munk_mss.  The omnidirectional
 * spectrum is S(k) = k^-3 B_h; mss = int B_h dk / k.  0 for k <= 0. */
double ocean_slope_elfouhaily_bh(double k, double u10);

typedef struct ocean_slope_table ocean_slope_table;

/* Precomputes the cutoff-independent parts for ocean oc and near field nf
 * (NULL: none) - see the header comment.  Both must outlive the table only
 * for the duration of this call: the table copies what it needs.  The near
 * field should start where the FFT stops (ocean_gerstner_params.k_lo =
 * the finest cascade's k_hi, as the daemon builds it); a gap between them
 * is counted in the tail, an overlap would be counted twice (it is not
 * checked).  OCEAN_EINVAL (oc NULL), OCEAN_ENOMEM; *out NULL on failure,
 * msg names the reason. */
ocean_result ocean_slope_table_create(const ocean *oc, const ocean_gerstner *nf,
                                      ocean_slope_table **out, char *msg, size_t msglen);
void ocean_slope_table_destroy(ocean_slope_table *t); /* accepts NULL */

/* The slope statistics for cutoff k_cut (rad/m, >= 0; INFINITY: no
 * filter, 0: everything filtered) and Butterworth order 1..64.
 * Memoised per (k_cut, order); the table is used by one thread at a time
 * (the memo is its only mutable state).  OCEAN_EINVAL for NULL arguments,
 * NaN or negative k_cut or order out of range (*out untouched). */
ocean_result ocean_slope_table_get(ocean_slope_table *t, double k_cut, int order,
                                   ocean_slope_stats *out);

/* One-shot form: builds a table for (oc, nf), gets (k_cut, order),
 * destroys it (tens of milliseconds: for tools and tests; a per-frame
 * caller keeps a table).  Errors as above. */
ocean_result ocean_slope_variance(const ocean *oc, const ocean_gerstner *nf, double k_cut,
                                  int order, ocean_slope_stats *out);

#endif
