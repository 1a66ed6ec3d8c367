/*
 * test_spectrum.c - spectra, spreading, dispersion and Beaufort against
 * published laws (each test names its source).
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "spectrum.h"

static void assert_close(double got, double want, double rel)
{
    if (!(fabs(got - want) <= rel * fabs(want)))
        fail_msg("got %.8g, want %.8g (rel tol %g)", got, want, rel);
}

static void test_dispersion_checks(void **state)
{
    (void)state;
    double k = 2.0 * M_PI / 100.0;
    double w = ocean_dispersion(k, 1e4);
    assert_close(w, 0.78510, 1e-4);
    assert_close(2.0 * M_PI / w, 8.003, 2e-4);
    assert_close(w / k, 12.495, 1e-4);
    double ws = ocean_dispersion(k, 10.0);
    assert_close(2.0 * M_PI / ws, 10.724, 2e-4);
    assert_close(ws / k, 9.325, 2e-4);
    /* Inverse, and the group-velocity derivative against a finite difference. */
    assert_close(ocean_wavenumber(w, 1e4), k, 1e-12);
    assert_close(ocean_wavenumber(ws, 10.0), k, 1e-12);
    double depths[] = {0.05, 1.0, 10.0, 11000.0};
    for (size_t i = 0; i < 4; i++) {
        double h = depths[i], kk = 0.3, e = 1e-6;
        double fd = (ocean_dispersion(kk + e, h) - ocean_dispersion(kk - e, h)) / (2 * e);
        assert_close(ocean_dispersion_dk(kk, h), fd, 1e-6);
    }
    /* No overflow where cosh(kh) would: kh = 1e7. */
    double d = ocean_dispersion_dk(1e3, 1e4);
    assert_true(isfinite(d) && d > 0.0);
    assert_close(ocean_dispersion_dk(0.0, 10.0), sqrt(OCEAN_G * 10.0), 1e-12);
}

static void sea_pm(ocean_sea_state *s, double u195)
{
    ocean_sea_state_default(s);
    s->spectrum = OCEAN_SPECTRUM_PM;
    s->wind_u10 = u195 / 1.026;
}

static void test_pierson_moskowitz(void **state)
{
    (void)state;
    ocean_sea_state s;
    sea_pm(&s, 10.0);
    assert_close(ocean_spectrum_hs(&s), 2.133, 1e-3);
    assert_close(ocean_spectrum_peak(&s), 0.8605, 2e-4);
    assert_close(2.0 * M_PI / ocean_spectrum_peak(&s), 7.302, 2e-4);
    /* Hs scales with U^2. */
    sea_pm(&s, 20.0);
    assert_close(ocean_spectrum_hs(&s), 4.0 * 2.133, 1e-3);
    /* w -> 0 is 0, not inf * 0 = NaN. */
    assert_true(ocean_spectrum_s(&s, 1e-300) == 0.0);
    assert_true(ocean_spectrum_s(&s, 0.0) == 0.0);
}

/* The JONSWAP laws of Hasselmann et al. 1973 (Dtsch. Hydrogr. Z. A8(12),
 * sect. 2.6), in the dimensionless fetch chi = g F / U10^2:
 *   peak      w_p = 22 (g^2 / (U10 F))^(1/3)      (f_p = 3.5 (g / U10) chi^-0.33)
 *   Phillips  alpha = 0.076 chi^-0.22
 *   spectrum  S(w) = alpha g^2 w^-5 exp(-5/4 (w_p / w)^4) gamma^r,
 *             r = exp(-(w - w_p)^2 / (2 sigma^2 w_p^2)), gamma = 3.3,
 *             sigma = 0.07 (w <= w_p), 0.09 (w > w_p)
 *   energy    g^2 m0 / U10^4 = 1.6e-7 chi, i.e. with Hs = 4 sqrt(m0):
 *             g Hs / U10^2 = 1.6e-3 chi^(1/2)
 * The spectrum is integrated here by Simpson's rule, independently of
 * spectrum.c: the check value of the model's Hs. */
static double jonswap_published_hs(double u10, double fetch)
{
    const double g = OCEAN_G;
    double chi = g * fetch / (u10 * u10);
    double alpha = 0.076 * pow(chi, -0.22), wp = 22.0 * cbrt(g * g / (u10 * fetch));
    double a = 0.2 * wp, b = 40.0 * wp;
    int n = 400000; /* even */
    double h = (b - a) / n, sum = 0.0;
    for (int i = 0; i <= n; i++) {
        double w = a + i * h, sig = w <= wp ? 0.07 : 0.09;
        double r = exp(-(w - wp) * (w - wp) / (2.0 * sig * sig * wp * wp));
        double sw = alpha * g * g * pow(w, -5.0) * exp(-1.25 * pow(wp / w, 4.0)) * pow(3.3, r);
        sum += sw * (i == 0 || i == n ? 1.0 : (i % 2 ? 4.0 : 2.0));
    }
    /* beyond b the tail is alpha g^2 w^-5 (gamma^r = 1, exp -> 1 to 1e-6) */
    double m0 = sum * h / 3.0 + alpha * g * g / (4.0 * pow(b, 4.0));
    return 4.0 * sqrt(m0);
}

static void test_jonswap(void **state)
{
    (void)state;
    ocean_sea_state s;
    ocean_sea_state_default(&s);
    s.spectrum = OCEAN_SPECTRUM_JONSWAP;
    s.wind_u10 = 10.0;
    s.fetch_m = 1e5;
    const double g = OCEAN_G, chi = g * s.fetch_m / (s.wind_u10 * s.wind_u10);
    /* the peak and alpha laws (Hasselmann et al. 1973, above) */
    assert_close(ocean_spectrum_peak(&s), 22.0 * cbrt(g * g / (s.wind_u10 * s.fetch_m)), 1e-6);
    double w = 30.0;
    assert_close(ocean_spectrum_s(&s, w) * pow(w, 5) / (g * g), 0.076 * pow(chi, -0.22), 2e-3);
    /* Hs: the published spectrum integrated independently (2.14 m) */
    assert_close(ocean_spectrum_hs(&s), jonswap_published_hs(s.wind_u10, s.fetch_m), 2e-3);
    /* Longer fetch, bigger sea - up to full development, never beyond
     * the fully developed Pierson-Moskowitz sea of the same wind. */
    double hs_1e5 = ocean_spectrum_hs(&s);
    s.fetch_m = 1.5e5;
    assert_true(ocean_spectrum_hs(&s) > hs_1e5);
    ocean_sea_state pm = s;
    pm.spectrum = OCEAN_SPECTRUM_PM;
    s.fetch_m = 1e7;
    double full = ocean_spectrum_hs(&s);
    s.fetch_m = 1e6;
    assert_true(ocean_spectrum_hs(&s) == full);
    /* Fully developed: the Pierson-Moskowitz sea's Hs = 0.20925 U19.5^2 / g
     * (1964; U19.5 = 1.026 U10), whatever the wind (capped at PM's peak
     * frequency instead, it had grown to 1.295 x). */
    const double winds[] = {1.0, 10.0, 26.45, 60.0};
    for (int i = 0; i < 4; i++) {
        s.wind_u10 = winds[i];
        s.fetch_m = 1e7;
        double u195 = 1.026 * winds[i], hs_pm = 0.20925 * u195 * u195 / g;
        double got = ocean_spectrum_hs(&s);
        print_message("U10 %g m/s, fetch 1e7 m: Hs %.4f m, fully developed (PM) %.4f m\n", winds[i], got,
                      hs_pm);
        assert_close(got, hs_pm, 2e-3);
        /* and growth stops there, not before: 5 % less fetch, less sea */
        s.fetch_m = 0.95 * 10707.25 * winds[i] * winds[i] / g;
        assert_true(ocean_spectrum_hs(&s) < 0.99 * got);
    }
    (void)pm;
}

/* Hs against the JONSWAP energy growth law, g Hs / U10^2 = 1.6e-3 chi^(1/2)
 * (Hasselmann et al. 1973; chi = g F / U10^2), which gives 1.616 m for
 * U10 = 10 m/s, F = 100 km.
 *
 * KNOWN DISCREPANCY, not a tolerance chosen to pass: the model implements
 * the same paper's spectral form (peak and alpha laws, gamma = 3.3), and
 * that form integrates to Hs = 2.14 m here (test_jonswap), 32 % above the
 * paper's own energy fit (energy 1.75x).  The published parameter fits and
 * the energy fit are not mutually consistent at this fetch; which one the
 * model should honour is an open decision (issue 13, item 7 report).  The
 * bound below (35 %) only holds the model to that documented gap (+21 to
 * +32 % over these cases), so a change that widens it fails; a tighter
 * bound needs the model changed, not the test. */
static void test_jonswap_energy_growth_law(void **state)
{
    (void)state;
    ocean_sea_state s;
    ocean_sea_state_default(&s);
    s.spectrum = OCEAN_SPECTRUM_JONSWAP;
    const double g = OCEAN_G;
    const double winds[] = {10.0, 10.0, 20.0}, fetches[] = {1e5, 2e4, 1e5};
    for (int i = 0; i < 3; i++) {
        s.wind_u10 = winds[i];
        s.fetch_m = fetches[i];
        double u2 = winds[i] * winds[i];
        double law = 1.6e-3 * sqrt(g * fetches[i] / u2) * u2 / g;
        double hs = ocean_spectrum_hs(&s);
        print_message("U10 %g m/s, F %g km: Hs %.4f m, JONSWAP energy law %.4f m (%+.1f %%)\n",
                      winds[i], fetches[i] / 1e3, hs, law, 100.0 * (hs / law - 1.0));
        if (i == 0)
            assert_close(law, 1.615, 1e-3); /* the figure issue 13 quotes */
        assert_close(hs, law, 0.35);
    }
}

static void test_tma(void **state)
{
    (void)state;
    assert_close(ocean_tma_phi(0.5 / sqrt(10.0 / OCEAN_G), 10.0), 0.125, 1e-12);
    assert_close(ocean_tma_phi(1.5 / sqrt(10.0 / OCEAN_G), 10.0), 0.875, 1e-12);
    assert_close(ocean_tma_phi(2.5 / sqrt(10.0 / OCEAN_G), 10.0), 1.0, 1e-12);
    ocean_sea_state s;
    ocean_sea_state_default(&s);
    s.spectrum = OCEAN_SPECTRUM_JONSWAP;
    double deep = ocean_spectrum_hs(&s);
    s.spectrum = OCEAN_SPECTRUM_TMA;
    double prev = 0.0, depths[] = {1.0, 3.0, 10.0, 30.0, 1000.0};
    for (size_t i = 0; i < 5; i++) {
        s.depth_m = depths[i];
        double hs = ocean_spectrum_hs(&s);
        assert_true(hs > prev);
        assert_true(hs <= deep * (1 + 1e-9));
        prev = hs;
    }
    assert_close(prev, deep, 1e-3); /* deep water: Phi = 1 over the spectrum */
}

static double integrate_d(const ocean_sea_state *s, double w)
{
    const int n = 20000;
    double sum = 0.0, h = 2.0 * M_PI / n;
    for (int i = 0; i < n; i++)
        sum += ocean_spreading_d(s, -M_PI + (i + 0.5) * h, w);
    return sum * h;
}

static void test_spreading_integrates_to_one(void **state)
{
    (void)state;
    ocean_sea_state s;
    ocean_sea_state_default(&s);
    double wp = ocean_spectrum_peak(&s);
    double ratios[] = {0.05, 0.3, 0.95, 1.0, 1.3, 1.6, 3.0, 10.0};
    double swells[] = {0.0, 1.0};
    double winds[] = {1.0, 10.0, 70.0};
    for (int k = 0; k < OCEAN_SPREAD_COUNT_; k++)
        for (size_t a = 0; a < 2; a++)
            for (size_t b = 0; b < 3; b++) {
                s.spreading = (ocean_spreading_kind)k;
                s.swell = swells[a];
                s.wind_u10 = winds[b];
                wp = ocean_spectrum_peak(&s);
                for (size_t i = 0; i < sizeof ratios / sizeof ratios[0]; i++) {
                    double got = integrate_d(&s, ratios[i] * wp);
                    if (fabs(got - 1.0) > 2e-3)
                        fail_msg("%s swell %g wind %g w/wp %g: integral %.6f",
                                 ocean_spreading_name(s.spreading), s.swell, s.wind_u10,
                                 ratios[i], got);
                }
            }
}

/* The ring (what depends on |k| alone, computed once for a sweep of
 * directions: the near field's quadrature) gives the point evaluation's F
 * at every direction, for every spectrum and spreading: F k = S(w) dw/dk
 * D(theta, w) with the ring's own w, and the wind's direction as
 * ocean_spectrum_f takes it from the wave vector. */
static void test_ring_sweeps_the_direction(void **state)
{
    (void)state;
    ocean_sea_state s;
    ocean_sea_state_default(&s);
    s.wind_dir_deg = 37.0;
    s.swell = 0.5;
    s.depth_m = 30.0; /* TMA's depth factor and finite-depth dw/dk at work */
    double ks[] = {0.004, 0.03, 0.2, 1.5, 12.0};
    for (int sp = 0; sp < OCEAN_SPECTRUM_COUNT_; sp++)
        for (int sd = 0; sd < OCEAN_SPREAD_COUNT_; sd++)
            for (size_t i = 0; i < sizeof ks / sizeof ks[0]; i++) {
                s.spectrum = (ocean_spectrum_kind)sp;
                s.spreading = (ocean_spreading_kind)sd;
                ocean_spectrum_ring r;
                ocean_spectrum_ring_at(&s, ks[i], &r);
                double w = ocean_dispersion(ks[i], s.depth_m);
                int nonzero = 0;
                for (int j = 0; j < 720; j++) {
                    double th = -M_PI + (j + 0.37) * (2.0 * M_PI / 720);
                    ocean_spreading_dir dir;
                    ocean_spreading_dir_at(s.spreading, th, &dir);
                    double f = ocean_spectrum_ring_f(&r, &dir);
                    double want = r.radial * ocean_spreading_d(&s, th, w) / ks[i];
                    double wa = th + s.wind_dir_deg * (M_PI / 180.0);
                    double point = ocean_spectrum_f(&s, ks[i] * cos(wa), ks[i] * sin(wa));
                    nonzero += f > 0.0;
                    if (!(f == want) || !(fabs(f - point) <= 1e-9 * fabs(point) + 1e-300))
                        fail_msg("%s / %s k %g theta %g: ring %.17g, S dw/dk D / k %.17g, point %.17g",
                                 ocean_spectrum_name(s.spectrum), ocean_spreading_name(s.spreading), ks[i], th,
                                 f, want, point);
                }
                if (ks[i] >= 0.03 && ks[i] <= 1.5 && nonzero == 0) /* about the peak: waves there */
                    fail_msg("%s / %s k %g: F is 0 on the whole ring", ocean_spectrum_name(s.spectrum),
                             ocean_spreading_name(s.spreading), ks[i]);
            }
}

static void test_cos2s_norm(void **state)
{
    (void)state;
    assert_close(ocean_cos2s_norm(1.0), 0.31831, 1e-5);
    assert_close(ocean_cos2s_norm(10.0), 0.90328, 1e-5);
    /* Gamma(2s+1) overflows double at s ~ 85: the log form does not. */
    double q = ocean_cos2s_norm(1e6);
    assert_true(isfinite(q) && q > 0.0);
    assert_close(ocean_cos2s_norm(0.0), 1.0 / (2.0 * M_PI), 1e-12);
}

static void test_beaufort(void **state)
{
    (void)state;
    double prev = -1.0, u;
    ocean_sea_state s;
    ocean_sea_state_default(&s);
    double prev_hs = -1.0;
    for (int f = 0; f <= 12; f++) {
        assert_int_equal(ocean_beaufort_wind(f, &u), OCEAN_OK);
        assert_true(u > prev);
        prev = u;
        s.wind_u10 = u;
        double hs = ocean_spectrum_hs(&s);
        assert_true(hs > prev_hs);
        prev_hs = hs;
        /* The Met Office table as a monotonic band: force 3..9 seas sit
         * within a factor 2 of the "probable" height (fully developed PM
         * exceeds it above force 6: the table is for the open sea's
         * usual, not fully developed, state). */
        static const double probable[13] = {0, 0, 0, 0.6, 1.0, 2.0, 3.0, 4.0, 5.5, 7.0, 9.0, 11.5, 14.0};
        if (f >= 3 && f <= 9)
            assert_true(hs > 0.5 * probable[f] && hs < 2.0 * probable[f]);
    }
    assert_int_equal(ocean_beaufort_wind(13, &u), OCEAN_EINVAL);
    assert_int_equal(ocean_beaufort_wind(-1, &u), OCEAN_EINVAL);
}

static void test_extremes_finite(void **state)
{
    (void)state;
    ocean_sea_state s;
    double winds[] = {0.0, 0.1, 10.0, 70.0, 100.0};
    double depths[] = {0.05, 1.0, 11000.0};
    double fetches[] = {1.0, 1e4, 1e7};
    double ks[] = {0.0, 1e-9, 1e-4, 0.01, 1.0, 100.0, 1e4, 1e7};
    for (int sp = 0; sp < OCEAN_SPECTRUM_COUNT_; sp++)
        for (int sd = 0; sd < OCEAN_SPREAD_COUNT_; sd++)
            for (size_t a = 0; a < 5; a++)
                for (size_t b = 0; b < 3; b++)
                    for (size_t c = 0; c < 3; c++) {
                        ocean_sea_state_default(&s);
                        s.spectrum = (ocean_spectrum_kind)sp;
                        s.spreading = (ocean_spreading_kind)sd;
                        s.wind_u10 = winds[a];
                        s.depth_m = depths[b];
                        s.fetch_m = fetches[c];
                        /* swell narrows the cos-2s spreadings only */
                        s.swell = sd == OCEAN_SPREAD_MITSUYASU || sd == OCEAN_SPREAD_HASSELMANN ? 10.0 : 0.0;
                        assert_int_equal(ocean_sea_state_validate(&s, NULL, 0), OCEAN_OK);
                        for (size_t i = 0; i < 8; i++)
                            for (int d = 0; d < 8; d++) {
                                double th = d * M_PI / 4;
                                double f = ocean_spectrum_f(&s, ks[i] * cos(th), ks[i] * sin(th));
                                if (!isfinite(f) || f < 0.0)
                                    fail_msg("F not finite: %s/%s wind %g depth %g k %g: %g",
                                             ocean_spectrum_name(s.spectrum),
                                             ocean_spreading_name(s.spreading), s.wind_u10,
                                             s.depth_m, ks[i], f);
                            }
                        double hs = ocean_spectrum_hs(&s);
                        assert_true(isfinite(hs) && hs >= 0.0);
                    }
    /* No wind, no sea. */
    ocean_sea_state_default(&s);
    s.wind_u10 = 0.0;
    assert_true(ocean_spectrum_hs(&s) == 0.0);
    assert_true(ocean_spectrum_f(&s, 0.1, 0.0) == 0.0);
}

static void test_validate_refuses(void **state)
{
    (void)state;
    ocean_sea_state s;
    char msg[200];
    ocean_sea_state_default(&s);
    s.wind_u10 = NAN;
    assert_int_equal(ocean_sea_state_validate(&s, msg, sizeof msg), OCEAN_EINVAL);
    assert_non_null(strstr(msg, "wind"));
    ocean_sea_state_default(&s);
    s.depth_m = -1.0;
    assert_int_equal(ocean_sea_state_validate(&s, msg, sizeof msg), OCEAN_EINVAL);
    assert_non_null(strstr(msg, "depth"));
    ocean_sea_state_default(&s);
    s.fetch_m = INFINITY;
    assert_int_equal(ocean_sea_state_validate(&s, msg, sizeof msg), OCEAN_EINVAL);
    assert_non_null(strstr(msg, "fetch"));
    ocean_sea_state_default(&s);
    s.spectrum = (ocean_spectrum_kind)42;
    assert_int_equal(ocean_sea_state_validate(&s, msg, sizeof msg), OCEAN_EINVAL);
    /* choppiness: 0, or at least 1e-3 (at 1e-40 the float displacement
     * channels underflowed and foam came out NaN) */
    ocean_sea_state_default(&s);
    s.choppiness = 1e-40;
    assert_int_equal(ocean_sea_state_validate(&s, msg, sizeof msg), OCEAN_EINVAL);
    assert_non_null(strstr(msg, "choppiness = 1e-40: use 0"));
    s.choppiness = OCEAN_CHOPPINESS_MIN;
    assert_int_equal(ocean_sea_state_validate(&s, msg, sizeof msg), OCEAN_OK);
    s.choppiness = 0.0;
    assert_int_equal(ocean_sea_state_validate(&s, msg, sizeof msg), OCEAN_OK);
    /* swell where the spreading has no s to narrow: refused, not ignored */
    const ocean_spreading_kind no_s[] = {OCEAN_SPREAD_TESSENDORF, OCEAN_SPREAD_DONELAN_BANNER};
    for (int i = 0; i < 2; i++) {
        ocean_sea_state_default(&s);
        s.spreading = no_s[i];
        s.swell = 1.0;
        assert_int_equal(ocean_sea_state_validate(&s, msg, sizeof msg), OCEAN_EINVAL);
        assert_non_null(strstr(msg, "cos-2s"));
        s.swell = 0.0;
        assert_int_equal(ocean_sea_state_validate(&s, msg, sizeof msg), OCEAN_OK);
    }
    ocean_spectrum_kind k;
    assert_int_equal(ocean_spectrum_parse("jonswap", &k), OCEAN_OK);
    assert_int_equal(k, OCEAN_SPECTRUM_JONSWAP);
    assert_int_equal(ocean_spectrum_parse("bogus", &k), OCEAN_EINVAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_dispersion_checks),
        cmocka_unit_test(test_pierson_moskowitz),
        cmocka_unit_test(test_jonswap),
        cmocka_unit_test(test_jonswap_energy_growth_law),
        cmocka_unit_test(test_tma),
        cmocka_unit_test(test_spreading_integrates_to_one),
        cmocka_unit_test(test_ring_sweeps_the_direction),
        cmocka_unit_test(test_cos2s_norm),
        cmocka_unit_test(test_beaufort),
        cmocka_unit_test(test_extremes_finite),
        cmocka_unit_test(test_validate_refuses),
    };
    return cmocka_run_group_tests_name("spectrum", tests, NULL, NULL);
}
