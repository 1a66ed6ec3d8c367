/*
 * test_filter.c - Butterworth gain, cutoff policies, smoothing, buckets,
 * E_error / redistribution and dominant wavelength (sim/filter.h).
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "filter.h"
#include "spectrum.h"

#define assert_close(a, b, tol)                                                          \
    do {                                                                                 \
        double a_ = (a), b_ = (b), t_ = (tol);                                           \
        if (!(fabs(a_ - b_) <= t_)) {                                                    \
            print_error("%s = %.17g, expected %.17g (tol %g)\n", #a, a_, b_, t_);        \
            fail();                                                                      \
        }                                                                                \
    } while (0)

static void gain_at_cutoff_is_half_power(void **state)
{
    (void)state;
    const double kcs[] = {1e-300, 1e-3, 1.0, 37.5, 1e300};
    for (int n = 1; n <= OCEAN_FILTER_MAX_ORDER; n++)
        for (size_t i = 0; i < sizeof kcs / sizeof kcs[0]; i++)
            assert_close(ocean_filter_gain(kcs[i], kcs[i], n), M_SQRT1_2, 1e-15);
    assert_close(ocean_filter_gain(1.0, 1.0, 6), 0.70711, 5e-6);
}

static void gain_reference_values(void **state)
{
    (void)state;
    /* Butterworth (1930): H(2 fc, n = 4) = 1 / sqrt(1 + 2^8) = 0.0623783 */
    assert_close(ocean_filter_gain(2.0, 1.0, 4), 0.0623783, 5e-8);
    assert_close(ocean_filter_gain(0.2, 0.1, 4), 0.0623783, 5e-8);
    /* n = 1: H = 1/sqrt(1 + r^2) */
    assert_close(ocean_filter_gain(3.0, 1.0, 1), 1.0 / sqrt(10.0), 1e-15);
    assert_close(ocean_filter_gain(0.5, 1.0, 2), 1.0 / sqrt(1.0 + 0.0625), 1e-15);
    /* seed 000: H(f) = 1/sqrt(1 + (f/fc)^12) at f = 1.5 fc */
    assert_close(ocean_filter_gain(1.5, 1.0, 6), 1.0 / sqrt(1.0 + pow(1.5, 12)), 1e-15);
}

static void gain_monotone_and_bounded(void **state)
{
    (void)state;
    const int orders[] = {1, 2, 4, 6, 12, 64};
    for (size_t o = 0; o < sizeof orders / sizeof orders[0]; o++) {
        double prev = 2.0;
        for (int i = -3000; i <= 3000; i++) {
            double k = pow(10.0, i * 0.1); /* 1e-300 .. 1e300 around kc = 1 */
            double h = ocean_filter_gain(k, 1.0, orders[o]);
            assert_false(isnan(h));
            assert_true(h >= 0.0 && h <= 1.0);
            assert_true(h <= prev);
            prev = h;
        }
        assert_true(prev == 0.0 || prev < 1e-200);
    }
}

static void gain_extreme_ratios(void **state)
{
    (void)state;
    const double ks[] = {0.0, 1e-300, 4.9e-324, 1.0, 1e300, 1.7e308, INFINITY};
    const double kcs[] = {0.0, 4.9e-324, 1e-300, 1.0, 1e300, 1.7e308, INFINITY};
    for (size_t i = 0; i < 7; i++)
        for (size_t j = 0; j < 7; j++)
            for (int n = 1; n <= 64; n *= 2) {
                double h = ocean_filter_gain(ks[i], kcs[j], n);
                assert_false(isnan(h));
                assert_true(h >= 0.0 && h <= 1.0);
            }
    assert_true(ocean_filter_gain(1e-300, 1.0, 6) == 1.0);
    assert_true(ocean_filter_gain(1e300, 1.0, 6) == 0.0);
    assert_true(ocean_filter_gain(1.0, 1e-300, 4) == 0.0);
    assert_true(ocean_filter_gain(1.0, 1e300, 4) == 1.0);
    assert_true(ocean_filter_gain(5.0, 0.0, 6) == 0.0);   /* cutoff 0 */
    assert_true(ocean_filter_gain(0.0, 0.0, 6) == 0.0);
    assert_true(ocean_filter_gain(INFINITY, INFINITY, 6) == 1.0);
    assert_true(ocean_filter_gain(INFINITY, 1.0, 6) == 0.0);
    assert_true(ocean_filter_gain(1e9, INFINITY, 6) == 1.0);
    /* invalid inputs are NaN, not a plausible gain */
    assert_true(isnan(ocean_filter_gain(NAN, 1.0, 6)));
    assert_true(isnan(ocean_filter_gain(1.0, NAN, 6)));
    assert_true(isnan(ocean_filter_gain(-1.0, 1.0, 6)));
    assert_true(isnan(ocean_filter_gain(1.0, -1.0, 6)));
    assert_true(isnan(ocean_filter_gain(1.0, 1.0, 0)));
    assert_true(isnan(ocean_filter_gain(1.0, 1.0, 65)));
}

static void negligible_band_edge(void **state)
{
    (void)state;
    const double eps[] = {1e-2, 1e-4, 1e-8, 0.5};
    const int orders[] = {1, 4, 6, 12};
    for (size_t e = 0; e < 4; e++)
        for (size_t o = 0; o < 4; o++) {
            double kn = ocean_filter_negligible_k(2.5, orders[o], eps[e]);
            assert_true(isfinite(kn) && kn > 2.5);
            assert_true(ocean_filter_gain(kn * (1 + 1e-9), 2.5, orders[o]) < eps[e]);
            assert_true(ocean_filter_gain(kn * (1 - 1e-9), 2.5, orders[o]) > eps[e]);
        }
    /* order 6, eps 1e-4: (1e8 - 1)^(1/12) */
    assert_close(ocean_filter_negligible_k(1.0, 6, 1e-4), pow(1e8 - 1.0, 1.0 / 12.0), 1e-13);
    assert_true(ocean_filter_negligible_k(INFINITY, 6, 1e-4) == INFINITY);
    assert_true(ocean_filter_negligible_k(0.0, 6, 1e-4) == 0.0);
    assert_true(ocean_filter_negligible_k(1.0, 6, 1.0) == 0.0);
    assert_true(ocean_filter_negligible_k(1.0, 6, 0.0) == INFINITY);
    assert_true(isnan(ocean_filter_negligible_k(1.0, 6, NAN)));
    assert_true(isnan(ocean_filter_negligible_k(-1.0, 6, 0.1)));
    assert_close(ocean_filter_negligible_k(3.0, 6, M_SQRT1_2), 3.0, 1e-14);
}

static void config_defaults_and_validation(void **state)
{
    (void)state;
    ocean_sea_state sea;
    ocean_sea_state_default(&sea);
    ocean_filter_config c;
    ocean_filter_config_default(&c, &sea);
    char msg[128];
    assert_int_equal(ocean_filter_config_validate(&c, msg, sizeof msg), OCEAN_OK);
    assert_int_equal(c.order, 6);
    /* v_wave is the dominant wave's phase speed: w_p / k_p with
     * w(k_p) = w_p; deep water c = g / w_p. */
    double wp = ocean_spectrum_peak(&sea);
    assert_true(wp > 0.0);
    assert_close(c.v_wave_mps, OCEAN_G / wp, 1e-6 * OCEAN_G / wp);
    /* In 10 m of water the dominant wave travels slower than in deep water. */
    ocean_sea_state shallow = sea;
    shallow.depth_m = 10.0;
    ocean_filter_config cs;
    ocean_filter_config_default(&cs, &shallow);
    double kp = ocean_wavenumber(ocean_spectrum_peak(&shallow), 10.0);
    assert_close(cs.v_wave_mps, ocean_dispersion(kp, 10.0) / kp, 1e-9);
    assert_true(cs.v_wave_mps < c.v_wave_mps);
    /* calm sea: documented fallback of a 10 s wave */
    ocean_sea_state calm = sea;
    calm.wind_u10 = 0.0;
    ocean_filter_config cc;
    ocean_filter_config_default(&cc, &calm);
    assert_close(cc.v_wave_mps, OCEAN_G * 10.0 / (2 * M_PI), 1e-12);

    ocean_filter_config bad = c;
    bad.order = 0;
    assert_int_equal(ocean_filter_config_validate(&bad, msg, sizeof msg), OCEAN_EINVAL);
    assert_non_null(strstr(msg, "order"));
    bad = c;
    bad.v_wave_mps = NAN;
    assert_int_equal(ocean_filter_config_validate(&bad, msg, sizeof msg), OCEAN_EINVAL);
    assert_non_null(strstr(msg, "v_wave"));
    bad = c;
    bad.alias_gain = 0.9;
    assert_int_equal(ocean_filter_config_validate(&bad, msg, sizeof msg), OCEAN_EINVAL);

    ocean_filter_policy p;
    assert_int_equal(ocean_filter_policy_parse("antialias", &p), OCEAN_OK);
    assert_int_equal(p, OCEAN_FILTER_ANTIALIAS);
    assert_int_equal(ocean_filter_policy_parse("Seed", &p), OCEAN_EINVAL);
    assert_string_equal(ocean_filter_policy_name(OCEAN_FILTER_SEED), "seed");
}

static void seed_policy_reproduces_formula(void **state)
{
    (void)state;
    ocean_filter_config c;
    ocean_filter_config_default(&c, NULL);
    const double speeds[] = {0.0, 1.0, 4.999, 5.0, 5.0001, 9.99, 10.0, 10.01, 50.0, 300.0, 1e6};
    for (size_t i = 0; i < sizeof speeds / sizeof speeds[0]; i++) {
        double v = speeds[i];
        ocean_filter_client cl = {v, 60.0, 1.0};
        ocean_filter_cutoff out;
        assert_int_equal(ocean_filter_cutoff_compute(&c, OCEAN_FILTER_SEED, &cl, &out), OCEAN_OK);
        /* seed 000: fc = f_base + beta |v|, beta 0.2 above 5 m/s else 0.05 */
        double beta = v > 5.0 ? 0.2 : 0.05;
        double fc = 3.0 + beta * v;
        assert_close(out.hz, fc, 1e-12 * fc);
        assert_close(out.k, 2 * M_PI * fc / c.v_wave_mps, 1e-12 * out.k);
        /* 3 % low-frequency boost above 10 m/s */
        assert_true(out.low_boost == (v > 10.0 ? 1.03 : 1.0));
        assert_int_equal(out.order, 6);
        assert_true(isfinite(out.k));
    }
    /* the seed policy's cutoff rises with speed (f_c = f_base + beta |v|,
     * as the design card writes it, although a faster camera needs less) */
    ocean_filter_client a = {20, 60, 0}, b = {40, 60, 0};
    ocean_filter_cutoff ca, cb;
    ocean_filter_cutoff_compute(&c, OCEAN_FILTER_SEED, &a, &ca);
    ocean_filter_cutoff_compute(&c, OCEAN_FILTER_SEED, &b, &cb);
    assert_true(cb.k > ca.k);
    /* a custom f_base / v_wave goes straight into the formula */
    c.f_base_hz = 0.5;
    c.v_wave_mps = 3.0;
    ocean_filter_client s = {2.0, 0, 0};
    ocean_filter_cutoff o;
    assert_int_equal(ocean_filter_cutoff_compute(&c, OCEAN_FILTER_SEED, &s, &o), OCEAN_OK);
    assert_close(o.k, 2 * M_PI * 0.6 / 3.0, 1e-15);
}

static void boost_gain_is_smooth(void **state)
{
    (void)state;
    ocean_filter_cutoff c = {.k = 2.0, .hz = 1.0, .low_boost = 1.03, .order = 6};
    assert_close(ocean_filter_cutoff_gain(&c, 1e-3), 1.03, 1e-12);
    assert_close(ocean_filter_cutoff_gain(&c, 2.0), M_SQRT1_2 * 1.015, 1e-12);
    assert_close(ocean_filter_cutoff_gain(&c, 20.0), ocean_filter_gain(20.0, 2.0, 6), 1e-12);
    double prev = ocean_filter_cutoff_gain(&c, 0.0);
    for (int i = 1; i <= 4000; i++) {
        double k = i * 1e-3;
        double g = ocean_filter_cutoff_gain(&c, k);
        assert_true(g <= prev + 1e-15);                  /* still monotone */
        assert_true(fabs(g - prev) < 0.01);              /* no step at kc */
        prev = g;
    }
    c.low_boost = 1.0;
    assert_true(ocean_filter_cutoff_gain(&c, 1.3) == ocean_filter_gain(1.3, 2.0, 6));
}

static void antialias_limits(void **state)
{
    (void)state;
    ocean_filter_config c;
    ocean_filter_config_default(&c, NULL);
    ocean_filter_cutoff o;
    /* spatial: 4 samples per wavelength at dx */
    ocean_filter_client sp = {0.0, 60.0, 0.5};
    assert_int_equal(ocean_filter_cutoff_compute(&c, OCEAN_FILTER_ANTIALIAS, &sp, &o), OCEAN_OK);
    assert_close(o.k, 2 * M_PI / (4 * 0.5), 1e-15);
    assert_int_equal(o.limited_by, 1);
    /* temporal: omega(k) + |v| k = pi fps at the cutoff */
    const double speeds[] = {0.0, 1.0, 30.0, 300.0, 1e6};
    for (int i = 0; i < 5; i++) {
        ocean_filter_client tp = {speeds[i], 60.0, 0.0};
        assert_int_equal(ocean_filter_cutoff_compute(&c, OCEAN_FILTER_ANTIALIAS, &tp, &o), OCEAN_OK);
        assert_int_equal(o.limited_by, 2);
        assert_true(isfinite(o.k) && o.k > 0.0);
        double w = ocean_dispersion(o.k, c.depth_m) + speeds[i] * o.k;
        assert_close(w, M_PI * 60.0, 1e-12 * M_PI * 60.0);
        assert_close(o.hz, 30.0, 1e-10);
    }
    /* at rest, deep water: omega = pi fps -> k = (pi fps)^2 / g */
    ocean_filter_client rest = {0.0, 10.0, 0.0};
    ocean_filter_cutoff_compute(&c, OCEAN_FILTER_ANTIALIAS, &rest, &o);
    assert_close(o.k, pow(M_PI * 10.0, 2) / OCEAN_G, 1e-9 * o.k);
    /* no constraint at all: unfiltered */
    ocean_filter_client free_ = {100.0, 0.0, 0.0};
    ocean_filter_cutoff_compute(&c, OCEAN_FILTER_ANTIALIAS, &free_, &o);
    assert_true(isinf(o.k));
    /* a smaller alias_gain pulls kc below the limit so H(limit) = alias_gain */
    c.alias_gain = 0.01;
    ocean_filter_cutoff_compute(&c, OCEAN_FILTER_ANTIALIAS, &sp, &o);
    assert_close(ocean_filter_gain(M_PI, o.k, 6), 0.01, 1e-12);
}

static void antialias_falls_with_speed(void **state)
{
    (void)state;
    ocean_filter_config c;
    ocean_filter_config_default(&c, NULL);
    const double depths[] = {4000.0, 10.0, 0.5};
    for (int d = 0; d < 3; d++) {
        c.depth_m = depths[d];
        double prev = INFINITY;
        int strict = 0;
        for (int i = 0; i <= 1200; i++) {
            double v = i == 0 ? 0.0 : 1e-3 * pow(10.0, i * 0.0075); /* .. 1e6 m/s */
            ocean_filter_client cl = {v, 60.0, 0.05};
            ocean_filter_cutoff o;
            assert_int_equal(ocean_filter_cutoff_compute(&c, OCEAN_FILTER_ANTIALIAS, &cl, &o),
                             OCEAN_OK);
            assert_true(isfinite(o.k) && o.k > 0.0);
            assert_true(o.k <= prev);
            if (o.limited_by == 2) {
                assert_true(o.k < prev);
                strict++;
            }
            prev = o.k;
        }
        assert_true(strict > 500);
        /* 1e6 m/s: about pi fps / v */
        assert_close(prev, M_PI * 60.0 / 1e6, 1e-3 * prev);
    }
}

static void hostile_client_inputs(void **state)
{
    (void)state;
    ocean_filter_config c;
    ocean_filter_config_default(&c, NULL);
    ocean_filter_cutoff o = {.k = 42.0};
    const double bad[] = {NAN, INFINITY, -INFINITY, -1.0, -1e-300};
    for (int p = 0; p < OCEAN_FILTER_POLICY_COUNT_; p++)
        for (int i = 0; i < 5; i++) {
            ocean_filter_client s = {bad[i], 60, 1};
            assert_int_equal(ocean_filter_cutoff_compute(&c, p, &s, &o), OCEAN_EINVAL);
            ocean_filter_client f = {10, bad[i], 1};
            assert_int_equal(ocean_filter_cutoff_compute(&c, p, &f, &o), OCEAN_EINVAL);
            ocean_filter_client d = {10, 60, bad[i]};
            assert_int_equal(ocean_filter_cutoff_compute(&c, p, &d, &o), OCEAN_EINVAL);
            assert_true(o.k == 42.0); /* untouched */
        }
    ocean_filter_client ok = {1e6, 60, 1};
    for (int p = 0; p < OCEAN_FILTER_POLICY_COUNT_; p++) {
        assert_int_equal(ocean_filter_cutoff_compute(&c, p, &ok, &o), OCEAN_OK);
        assert_false(isnan(o.k));
        if (p != OCEAN_FILTER_NONE)
            assert_true(isfinite(o.k) && o.k > 0.0);
        else
            assert_true(isinf(o.k) && isnan(o.hz));
    }
    assert_int_equal(ocean_filter_cutoff_compute(&c, OCEAN_FILTER_POLICY_COUNT_, &ok, &o),
                     OCEAN_EINVAL);
    assert_int_equal(ocean_filter_cutoff_compute(NULL, OCEAN_FILTER_SEED, &ok, &o), OCEAN_EINVAL);
}

/* ---- smoothing along a recorded flight ---------------------------------- */

/* 0 -> 300 m/s in 20 s (smoothstep), 5 s at 300, back to 0 in 20 s, 10 s
 * at rest, recorded at 60 fps. */
static double flight_speed(double t)
{
    double s;
    if (t < 20.0) {
        s = t / 20.0;
        return 300.0 * s * s * (3 - 2 * s);
    }
    if (t < 25.0)
        return 300.0;
    if (t < 45.0) {
        s = 1.0 - (t - 25.0) / 20.0;
        return 300.0 * s * s * (3 - 2 * s);
    }
    return 0.0;
}

static void check_smoothed_flight(ocean_filter_policy policy, double spacing)
{
    ocean_filter_config c;
    ocean_filter_config_default(&c, NULL);
    ocean_filter_smoother s;
    ocean_filter_smoother_init(&s);
    const double fps = 60.0, dt = 1.0 / fps;
    const int frames = (int)(55.0 * fps);
    double prev = NAN, tmin = INFINITY, tmax = 0.0, target = NAN, worst = 0.0;
    for (int f = 0; f <= frames; f++) {
        ocean_filter_client cl = {flight_speed(f * dt), fps, spacing};
        ocean_filter_cutoff o;
        assert_int_equal(ocean_filter_cutoff_compute(&c, policy, &cl, &o), OCEAN_OK);
        target = o.k;
        tmin = fmin(tmin, target);
        tmax = fmax(tmax, target);
        double k;
        assert_int_equal(ocean_filter_smoother_update(&s, target, dt, &k), OCEAN_OK);
        assert_true(isfinite(k) && k > 0.0);
        if (f > 0) {
            double step = log(k) - log(prev), want = log(target) - log(prev);
            /* bounded relative change per frame */
            assert_true(fabs(step) <= s.max_log_rate * dt + 1e-12);
            /* toward the target, never past it: no overshoot */
            assert_true(step * want >= 0.0);
            assert_true(fabs(step) <= fabs(want) + 1e-15);
            worst = fmax(worst, fabs(step));
        }
        /* never outside the range of targets seen */
        assert_true(k >= tmin * (1 - 1e-12) && k <= tmax * (1 + 1e-12));
        prev = k;
    }
    /* the profile really moved the target, and the cutoff settled on it */
    assert_true(tmax / tmin > 4.0);
    assert_true(worst > 0.0);
    assert_true(prev == target);
}

static void smoother_along_accelerating_flight(void **state)
{
    (void)state;
    check_smoothed_flight(OCEAN_FILTER_ANTIALIAS, 0.05);
    check_smoothed_flight(OCEAN_FILTER_SEED, 0.05); /* has a jump at 5 m/s */
}

/* policy -> smoother -> bucket, as the server runs it each frame: the
 * bucketed cutoff never exceeds the smoothed one, and a whole flight
 * needs only a handful of distinct filtered evaluations. */
static void flight_pipeline_buckets(void **state)
{
    (void)state;
    ocean_filter_config c;
    ocean_filter_config_default(&c, NULL);
    ocean_filter_smoother s;
    ocean_filter_smoother_init(&s);
    ocean_filter_buckets b;
    ocean_filter_buckets_default(&b);
    const double dt = 1.0 / 60;
    int seen[128] = {0}, distinct = 0, switches = 0, last = -1;
    for (int f = 0; f <= 55 * 60; f++) {
        ocean_filter_client cl = {flight_speed(f * dt), 60.0, 0.05};
        ocean_filter_cutoff o;
        assert_int_equal(ocean_filter_cutoff_compute(&c, OCEAN_FILTER_ANTIALIAS, &cl, &o), OCEAN_OK);
        double k, kb;
        int j;
        assert_int_equal(ocean_filter_smoother_update(&s, o.k, dt, &k), OCEAN_OK);
        assert_int_equal(ocean_filter_bucket_of(&b, k, &j), OCEAN_OK);
        assert_int_equal(ocean_filter_bucket_cutoff(&b, j, &kb), OCEAN_OK);
        assert_true(kb <= k);
        assert_true(j < 128);
        if (!seen[j]++)
            distinct++;
        if (j != last)
            switches++;
        last = j;
    }
    printf("flight: %d distinct buckets, %d bucket changes in %d frames\n", distinct, switches,
           55 * 60 + 1);
    /* 0 -> 300 m/s moves the cutoff ~5 octaves: ~20 buckets, each entered
     * once on the way down and once on the way up */
    assert_true(distinct >= 10 && distinct <= 30);
    assert_true(switches <= 2 * distinct + 2);
}

static void smoother_edges(void **state)
{
    (void)state;
    ocean_filter_smoother s;
    ocean_filter_smoother_init(&s);
    double k;
    assert_int_equal(ocean_filter_smoother_update(&s, 1.0, 0.0, &k), OCEAN_OK);
    assert_true(k == 1.0); /* first update: no history, no pop */
    /* step to 0 (everything filtered): approached through k_floor, then 0 */
    int frames = 0;
    do {
        assert_int_equal(ocean_filter_smoother_update(&s, 0.0, 1.0 / 60, &k), OCEAN_OK);
        frames++;
    } while (k != 0.0 && frames < 100000);
    assert_true(k == 0.0);
    /* ln(1e4) at 2/s needs at least 4.6 s */
    assert_true(frames >= (int)(log(1.0 / s.k_floor) / s.max_log_rate * 60) - 1);
    /* and up to INFINITY (no filter) */
    frames = 0;
    do {
        assert_int_equal(ocean_filter_smoother_update(&s, INFINITY, 1.0 / 60, &k), OCEAN_OK);
        frames++;
    } while (!isinf(k) && frames < 100000);
    assert_true(isinf(k));
    /* dt = 0 does not move the state: it stays at the ceiling, which
     * filters no wave of a real ocean, and is now reported as that */
    assert_int_equal(ocean_filter_smoother_update(&s, 1.0, 0.0, &k), OCEAN_OK);
    assert_close(k, s.k_ceil, 1e-9 * s.k_ceil);
    /* hostile input leaves the state alone */
    ocean_filter_smoother before = s;
    assert_int_equal(ocean_filter_smoother_update(&s, NAN, 0.1, &k), OCEAN_EINVAL);
    assert_int_equal(ocean_filter_smoother_update(&s, -1.0, 0.1, &k), OCEAN_EINVAL);
    assert_int_equal(ocean_filter_smoother_update(&s, 1.0, NAN, &k), OCEAN_EINVAL);
    assert_int_equal(ocean_filter_smoother_update(&s, 1.0, -0.1, &k), OCEAN_EINVAL);
    assert_int_equal(ocean_filter_smoother_update(&s, 1.0, INFINITY, &k), OCEAN_EINVAL);
    assert_memory_equal(&before, &s, sizeof s);
    /* a long pause lands on the target */
    assert_int_equal(ocean_filter_smoother_update(&s, 3.0, 1e6, &k), OCEAN_OK);
    assert_true(k == exp(log(3.0)));
}

/* ---- buckets -------------------------------------------------------------- */

static void bucket_round_trip(void **state)
{
    (void)state;
    ocean_filter_buckets b;
    ocean_filter_buckets_default(&b);
    int n = ocean_filter_bucket_count(&b);
    assert_int_equal(n, 4 * 20 + 1 + 2);
    double prev = -1.0;
    for (int i = 0; i < n; i++) {
        double kc;
        int j;
        assert_int_equal(ocean_filter_bucket_cutoff(&b, i, &kc), OCEAN_OK);
        assert_true(kc > prev);
        prev = kc;
        assert_int_equal(ocean_filter_bucket_of(&b, kc, &j), OCEAN_OK);
        assert_int_equal(j, i);
    }
    double kc;
    assert_int_equal(ocean_filter_bucket_cutoff(&b, 0, &kc), OCEAN_OK);
    assert_true(kc == 0.0);
    assert_int_equal(ocean_filter_bucket_cutoff(&b, n - 1, &kc), OCEAN_OK);
    assert_true(isinf(kc));
    assert_int_equal(ocean_filter_bucket_cutoff(&b, 1, &kc), OCEAN_OK);
    assert_true(kc == 1.0 / 1024);
    assert_int_equal(ocean_filter_bucket_cutoff(&b, 1 + 40, &kc), OCEAN_OK);
    assert_true(kc == 1.0); /* octaves are exact powers of two */
    assert_int_equal(ocean_filter_bucket_cutoff(&b, n, &kc), OCEAN_EINVAL);
    assert_int_equal(ocean_filter_bucket_cutoff(&b, -1, &kc), OCEAN_EINVAL);

    /* other layouts round-trip too */
    for (int per = 1; per <= 12; per++) {
        ocean_filter_buckets c = {per, 13, 0.003};
        for (int i = 0; i < ocean_filter_bucket_count(&c); i++) {
            int j;
            ocean_filter_bucket_cutoff(&c, i, &kc);
            assert_int_equal(ocean_filter_bucket_of(&c, kc, &j), OCEAN_OK);
            assert_int_equal(j, i);
        }
    }
}

static void bucket_quantises_downward(void **state)
{
    (void)state;
    ocean_filter_buckets b;
    ocean_filter_buckets_default(&b);
    double step = exp2(1.0 / b.per_octave);
    for (int i = 0; i < 20000; i++) {
        double kc = exp(-6.9 + 13.8 * i / 20000.0); /* 1e-3 .. 1e3 */
        int j;
        double lo, hi;
        assert_int_equal(ocean_filter_bucket_of(&b, kc, &j), OCEAN_OK);
        ocean_filter_bucket_cutoff(&b, j, &lo);
        ocean_filter_bucket_cutoff(&b, j + 1, &hi);
        assert_true(lo <= kc && kc < hi);         /* never more than asked */
        assert_true(kc / lo < step * (1 + 1e-12)); /* at most one step below */
    }
    int j;
    assert_int_equal(ocean_filter_bucket_of(&b, 0.0, &j), OCEAN_OK);
    assert_int_equal(j, 0);
    assert_int_equal(ocean_filter_bucket_of(&b, 1e-9, &j), OCEAN_OK);
    assert_int_equal(j, 0);
    assert_int_equal(ocean_filter_bucket_of(&b, 1e300, &j), OCEAN_OK);
    assert_int_equal(j, ocean_filter_bucket_count(&b) - 2);
    assert_int_equal(ocean_filter_bucket_of(&b, INFINITY, &j), OCEAN_OK);
    assert_int_equal(j, ocean_filter_bucket_count(&b) - 1);
    assert_int_equal(ocean_filter_bucket_of(&b, NAN, &j), OCEAN_EINVAL);
    assert_int_equal(ocean_filter_bucket_of(&b, -1.0, &j), OCEAN_EINVAL);
    ocean_filter_buckets bad = {0, 20, 1.0};
    assert_int_equal(ocean_filter_bucket_of(&bad, 1.0, &j), OCEAN_EINVAL);
    assert_int_equal(ocean_filter_bucket_count(&bad), 0);
    bad = (ocean_filter_buckets){4, 2000, 1.0};
    assert_int_equal(ocean_filter_buckets_validate(&bad), OCEAN_EINVAL);

    /* clients of similar speed share a bucket: 60 fps, antialias */
    ocean_filter_config c;
    ocean_filter_config_default(&c, NULL);
    int seen[256] = {0}, distinct = 0;
    for (int v = 100; v <= 300; v++) {
        ocean_filter_client cl = {v, 60.0, 0.0};
        ocean_filter_cutoff o;
        ocean_filter_cutoff_compute(&c, OCEAN_FILTER_ANTIALIAS, &cl, &o);
        assert_int_equal(ocean_filter_bucket_of(&b, o.k, &j), OCEAN_OK);
        if (!seen[j]++)
            distinct++;
    }
    /* 201 speeds spanning 1.58 octaves of cutoff fall into 7 buckets */
    assert_true(distinct <= 8);
}

/* ---- E_error and redistribution ---------------------------------------- */

static void energy_exact_on_synthetic_modes(void **state)
{
    (void)state;
    ocean_filter_energy e;
    ocean_filter_energy_init(&e);
    const double g[] = {1.0, 0.5, 0.0, 0.25};
    const double p[] = {1.0, 2.0, 3.0, 4.0};
    for (int i = 0; i < 4; i++)
        ocean_filter_energy_add(&e, g[i], p[i]);
    /* sum P = 10, sum (1-g)^2 P = 0 + 0.5 + 3 + 2.25 = 5.75, sum g^2 P = 1 + 0.5 + 0 + 0.25 */
    assert_close(ocean_filter_energy_e_error(&e), sqrt(5.75 / 10.0), 1e-15);
    double s = ocean_filter_energy_scale(&e);
    assert_close(s, sqrt(10.0 / 1.75), 1e-15);
    double v = 0.0, err = 0.0;
    for (int i = 0; i < 4; i++) {
        v += s * g[i] * s * g[i] * p[i];
        err += (1 - s * g[i]) * (1 - s * g[i]) * p[i];
    }
    assert_close(v, 10.0, 1e-13); /* variance kept */
    assert_close(ocean_filter_energy_e_error_redistributed(&e), sqrt(err / 10.0), 1e-13);
    /* poison is ignored, not summed */
    ocean_filter_energy before = e;
    ocean_filter_energy_add(&e, NAN, 1.0);
    ocean_filter_energy_add(&e, 0.5, NAN);
    ocean_filter_energy_add(&e, 0.5, -1.0);
    ocean_filter_energy_add(&e, 0.5, INFINITY);
    assert_memory_equal(&before, &e, sizeof e);
    /* nothing passes (cutoff 0): E_error 1, no scale to apply */
    ocean_filter_energy z;
    ocean_filter_energy_init(&z);
    ocean_filter_energy_add(&z, 0.0, 2.0);
    assert_close(ocean_filter_energy_e_error(&z), 1.0, 0);
    assert_true(ocean_filter_energy_scale(&z) == 1.0);
    /* no variance at all */
    ocean_filter_energy_init(&z);
    assert_true(ocean_filter_energy_e_error(&z) == 0.0);
    assert_true(ocean_filter_energy_scale(&z) == 1.0);
    /* scale stays finite with a vanishing passed band */
    ocean_filter_energy_init(&z);
    ocean_filter_energy_add(&z, 1e-160, 1e-10);
    ocean_filter_energy_add(&z, 0.0, 1e300);
    assert_true(isfinite(ocean_filter_energy_scale(&z)));
}

static void energy_modes_match_direct_sums(void **state)
{
    (void)state;
    /* synthetic k^-3 spectrum on 2000 modes, seed policy with the boost */
    double k[2000], p[2000];
    for (int i = 0; i < 2000; i++) {
        k[i] = 0.01 * (i + 1);
        p[i] = pow(k[i], -3.0) * 1e-3;
    }
    ocean_filter_cutoff c = {.k = 3.0, .hz = 1, .low_boost = 1.03, .order = 6};
    ocean_filter_energy e;
    assert_int_equal(ocean_filter_energy_modes(&c, k, p, 2000, &e), OCEAN_OK);
    double sp = 0, sg2 = 0, se = 0;
    for (int i = 0; i < 2000; i++) {
        double g = ocean_filter_cutoff_gain(&c, k[i]);
        sp += p[i];
        sg2 += g * g * p[i];
        se += (1 - g) * (1 - g) * p[i];
    }
    assert_close(ocean_filter_energy_e_error(&e), sqrt(se / sp), 1e-14);
    assert_close(ocean_filter_energy_scale(&e), sqrt(sp / sg2), 1e-14);
    assert_int_equal(ocean_filter_energy_modes(&c, NULL, p, 3, &e), OCEAN_EINVAL);
    assert_int_equal(ocean_filter_energy_modes(&c, NULL, NULL, 0, &e), OCEAN_OK);
    assert_true(e.sum_p == 0.0);
}

static double psi_test(double k, void *ctx)
{
    (void)ctx;
    double d = 1.0 + k * k;
    return 2.0 * k / (d * d); /* integrates to 1 over (0, inf) */
}

static void energy_integrate_closed_form(void **state)
{
    (void)state;
    /* order 1, kc = 1: H^2 = 1/(1+k^2); int 2k/(1+k^2)^3 dk = 1/2 */
    ocean_filter_cutoff c = {.k = 1.0, .hz = NAN, .low_boost = 1.0, .order = 1};
    ocean_filter_energy e;
    assert_int_equal(ocean_filter_energy_integrate(&c, psi_test, NULL, 1e-9, 1e9, 400, &e),
                     OCEAN_OK);
    assert_close(e.sum_p, 1.0, 1e-12);
    assert_close(e.sum_g2p, 0.5, 1e-12);
    assert_close(ocean_filter_energy_scale(&e), sqrt(2.0), 1e-12);
    /* E_error^2 = 1 - 2 int H psi + 1/2; int H psi = int 2k (1+k^2)^-2.5 dk = 2/3 */
    assert_close(ocean_filter_energy_e_error(&e), sqrt(1.5 - 4.0 / 3.0), 1e-12);
    c.k = INFINITY;
    ocean_filter_energy_integrate(&c, psi_test, NULL, 1e-9, 1e9, 400, &e);
    assert_true(ocean_filter_energy_e_error(&e) == 0.0);
    assert_int_equal(ocean_filter_energy_integrate(&c, psi_test, NULL, 0.0, 1.0, 4, &e),
                     OCEAN_EINVAL);
    assert_int_equal(ocean_filter_energy_integrate(&c, psi_test, NULL, 2.0, 1.0, 4, &e),
                     OCEAN_EINVAL);
    assert_int_equal(ocean_filter_energy_integrate(&c, NULL, NULL, 1.0, 2.0, 4, &e),
                     OCEAN_EINVAL);
}

/* S(w) of PM as a density in k (deep water): psi(k) = S(w) dw/dk. */
static double psi_sea(double k, void *ctx)
{
    const ocean_sea_state *s = ctx;
    double w = ocean_dispersion(k, s->depth_m);
    return ocean_spectrum_s(s, w) * ocean_dispersion_dk(k, s->depth_m);
}

static void seed_default_meets_energy_guard(void **state)
{
    (void)state;
    /* The documented default f_base = 3 Hz keeps a static camera's E_error
     * under seed 000's 5 % for a 10 m/s PM sea. */
    ocean_sea_state sea;
    ocean_sea_state_default(&sea);
    ocean_filter_config c;
    ocean_filter_config_default(&c, &sea);
    ocean_filter_client still = {0.0, 60.0, 0.0};
    ocean_filter_cutoff o;
    ocean_filter_cutoff_compute(&c, OCEAN_FILTER_SEED, &still, &o);
    double kp = pow(ocean_spectrum_peak(&sea), 2) / OCEAN_G;
    assert_close(o.k / kp, 3.0 / (ocean_spectrum_peak(&sea) / (2 * M_PI)), 1e-6 * o.k / kp);
    ocean_filter_energy e;
    assert_int_equal(ocean_filter_energy_integrate(&o, psi_sea, &sea, 1e-3 * kp, 1e4 * kp, 800, &e),
                     OCEAN_OK);
    double err = ocean_filter_energy_e_error(&e);
    printf("seed policy at rest: kc = %.4g rad/m = %.3g k_p, E_error = %.4f\n", o.k, o.k / kp, err);
    assert_true(err > 0.02 && err < 0.05);
    /* the redistributed field is closer in variance, not in shape */
    assert_close(ocean_filter_energy_scale(&e) * ocean_filter_energy_scale(&e) * e.sum_g2p,
                 e.sum_p, 1e-12 * e.sum_p);
}

/* ---- dominant wavelength ---------------------------------------------- */

static void dominant_wavelength_and_spacing(void **state)
{
    (void)state;
    ocean_sea_state sea;
    ocean_sea_state_default(&sea);
    sea.spectrum = OCEAN_SPECTRUM_PM;
    sea.wind_u10 = 10.0;
    sea.depth_m = 4000.0;
    double lambda, dx;
    assert_int_equal(ocean_filter_dominant_wavelength(&sea, &lambda), OCEAN_OK);
    /* PM: wp = 0.87716 g / U19.5, U19.5 = 1.026 U10; deep: lambda = 2 pi g / wp^2 */
    double wp = 0.87716 * OCEAN_G / (1.026 * 10.0);
    assert_close(lambda, 2 * M_PI * OCEAN_G / (wp * wp), 2e-3 * lambda);
    assert_int_equal(ocean_filter_mesh_spacing(&sea, 0.1, &dx), OCEAN_OK);
    assert_close(dx, 0.1 * lambda, 1e-12);
    assert_int_equal(ocean_filter_mesh_spacing(&sea, 0.5, &dx), OCEAN_OK);
    assert_close(dx, 0.5 * lambda, 1e-12);
    assert_int_equal(ocean_filter_mesh_spacing(&sea, 0.09, &dx), OCEAN_EINVAL);
    assert_int_equal(ocean_filter_mesh_spacing(&sea, 0.51, &dx), OCEAN_EINVAL);
    assert_int_equal(ocean_filter_mesh_spacing(&sea, NAN, &dx), OCEAN_EINVAL);
    /* shallow water shortens the dominant wave at the same period */
    ocean_sea_state sh = sea;
    sh.depth_m = 5.0;
    double ls;
    assert_int_equal(ocean_filter_dominant_wavelength(&sh, &ls), OCEAN_OK);
    assert_true(ls < lambda);
    /* stronger wind, longer waves */
    ocean_sea_state st = sea;
    st.wind_u10 = 20.0;
    double l2;
    ocean_filter_dominant_wavelength(&st, &l2);
    assert_close(l2 / lambda, 4.0, 1e-6);
    /* calm sea: no dominant wave */
    sea.wind_u10 = 0.0;
    assert_int_equal(ocean_filter_dominant_wavelength(&sea, &lambda), OCEAN_EUNSUPPORTED);
    sea.wind_u10 = NAN;
    assert_int_equal(ocean_filter_dominant_wavelength(&sea, &lambda), OCEAN_EINVAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(gain_at_cutoff_is_half_power),
        cmocka_unit_test(gain_reference_values),
        cmocka_unit_test(gain_monotone_and_bounded),
        cmocka_unit_test(gain_extreme_ratios),
        cmocka_unit_test(negligible_band_edge),
        cmocka_unit_test(config_defaults_and_validation),
        cmocka_unit_test(seed_policy_reproduces_formula),
        cmocka_unit_test(boost_gain_is_smooth),
        cmocka_unit_test(antialias_limits),
        cmocka_unit_test(antialias_falls_with_speed),
        cmocka_unit_test(hostile_client_inputs),
        cmocka_unit_test(smoother_along_accelerating_flight),
        cmocka_unit_test(flight_pipeline_buckets),
        cmocka_unit_test(smoother_edges),
        cmocka_unit_test(bucket_round_trip),
        cmocka_unit_test(bucket_quantises_downward),
        cmocka_unit_test(energy_exact_on_synthetic_modes),
        cmocka_unit_test(energy_modes_match_direct_sums),
        cmocka_unit_test(energy_integrate_closed_form),
        cmocka_unit_test(seed_default_meets_energy_guard),
        cmocka_unit_test(dominant_wavelength_and_spacing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
