/*
 * test_gerstner.c - the Gerstner near field (sim/gerstner.h): variance
 * partition with the spectrum and the FFT bands, no loops at extreme
 * settings, velocity and normals against finite differences, fade,
 * per-wave filter gains, phase accuracy far out in space and time,
 * determinism and hostile parameters.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "filter.h"
#include "gerstner.h"
#include "ocean.h"
#include "spectrum.h"

#define assert_close(a, b, tol)                                                          \
    do {                                                                                 \
        double a_ = (a), b_ = (b), t_ = (tol);                                           \
        if (!(fabs(a_ - b_) <= t_)) {                                                    \
            print_error("%s = %.17g, expected %.17g (tol %g)\n", #a, a_, b_, t_);        \
            fail();                                                                      \
        }                                                                                \
    } while (0)

static int sanitized(void)
{
    const char *s = getenv("OCEAN_TEST_SANITIZED");
    return s != NULL && s[0] == '1';
}

static ocean_gerstner *make(const ocean_gerstner_params *p)
{
    ocean_gerstner *g = NULL;
    char msg[160] = "";
    ocean_result r = ocean_gerstner_create(p, &g, msg, sizeof msg);
    if (r != OCEAN_OK)
        print_error("create: %s (%s)\n", ocean_strerror(r), msg);
    assert_int_equal(r, OCEAN_OK);
    assert_non_null(g);
    return g;
}

static double sum_amp(const ocean_gerstner *g, double *sum_ak, double *sum_aw)
{
    double s = 0, sk = 0, sw = 0;
    for (int i = 0; i < ocean_gerstner_count(g); i++) {
        ocean_gerstner_wave w;
        ocean_gerstner_get_wave(g, i, &w);
        s += w.amplitude;
        sk += w.amplitude * w.k;
        sw += w.amplitude * w.omega;
    }
    if (sum_ak)
        *sum_ak = sk;
    if (sum_aw)
        *sum_aw = sw;
    return s;
}

/* Independent integral of F over k_lo <= |k| < k_hi: midpoint rule on
 * 1536 directions x Gauss-Legendre (8 points) on 24 log panels. */
static double band_integral(const ocean_sea_state *sea, double k_lo, double k_hi)
{
    static const double x[4] = {0.1834346424956498, 0.5255324099163290,
                                0.7966664774136267, 0.9602898564975363};
    static const double w[4] = {0.3626837833783620, 0.3137066458778873,
                                0.2223810344533745, 0.1012285362903763};
    const int nt = 1536, np = sanitized() ? 12 : 24;
    double du = log(k_hi / k_lo) / np, dth = 2 * M_PI / nt, sum = 0.0;
    for (int j = 0; j < nt; j++) {
        double th = -M_PI + (j + 0.5) * dth, c = cos(th), s = sin(th);
        for (int p = 0; p < np; p++) {
            double mid = log(k_lo) + (p + 0.5) * du;
            for (int q = 0; q < 8; q++) {
                double k = exp(mid + (q < 4 ? -1 : 1) * x[q & 3] * 0.5 * du);
                sum += ocean_spectrum_f(sea, k * c, k * s) * k * k * w[q & 3] * 0.5 * du * dth;
            }
        }
    }
    return sum;
}

/* The same variance by an independent path: F = S(w) dw/dk D / k with
 * every D integrating to 1, so the band holds int S(w) dw over
 * [w(k_lo), w(k_hi)] (Simpson in ln w, 2e5 intervals). */
static double band_integral_1d(const ocean_sea_state *sea, double k_lo, double k_hi)
{
    double a = log(ocean_dispersion(k_lo, sea->depth_m));
    double b = log(ocean_dispersion(k_hi, sea->depth_m));
    const int n = 200000;
    double h = (b - a) / n, sum = 0.0;
    for (int i = 0; i <= n; i++) {
        double w = exp(a + i * h);
        sum += ocean_spectrum_s(sea, w) * w * (i == 0 || i == n ? 1.0 : (i % 2 ? 4.0 : 2.0));
    }
    return sum * h / 3.0;
}

static void variance_equals_band_integral(void **state)
{
    (void)state;
    struct {
        ocean_spectrum_kind spec;
        ocean_spreading_kind spread;
        double wind, depth;
        int count;
    } cases[] = {
        {OCEAN_SPECTRUM_PM, OCEAN_SPREAD_MITSUYASU, 10.0, 4000.0, 256},
        {OCEAN_SPECTRUM_JONSWAP, OCEAN_SPREAD_HASSELMANN, 20.0, 4000.0, 1024},
        {OCEAN_SPECTRUM_PHILLIPS, OCEAN_SPREAD_TESSENDORF, 10.0, 4000.0, 7},
        {OCEAN_SPECTRUM_TMA, OCEAN_SPREAD_DONELAN_BANNER, 15.0, 3.0, 1},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        ocean_gerstner_params p;
        ocean_gerstner_params_default(&p);
        p.sea.spectrum = cases[c].spec;
        p.sea.spreading = cases[c].spread;
        p.sea.wind_u10 = cases[c].wind;
        p.sea.depth_m = cases[c].depth;
        p.count = cases[c].count;
        p.k_lo = 0.8;
        p.k_hi = 125.0;
        ocean_gerstner *g = make(&p);
        assert_int_equal(ocean_gerstner_count(g), cases[c].count);
        double v = 0.0;
        for (int i = 0; i < ocean_gerstner_count(g); i++) {
            ocean_gerstner_wave w;
            assert_int_equal(ocean_gerstner_get_wave(g, i, &w), OCEAN_OK);
            /* every wave in its band, on the dispersion relation */
            assert_true(w.k >= p.k_lo && w.k < p.k_hi);
            assert_close(hypot(w.kx, w.kz), w.k, 1e-12 * w.k);
            assert_close(w.omega, ocean_dispersion(w.k, p.sea.depth_m), 1e-12 * w.omega);
            assert_true(w.phase >= 0.0 && w.phase < 2 * M_PI);
            v += 0.5 * w.amplitude * w.amplitude;
        }
        double ref = band_integral_1d(&p.sea, p.k_lo, p.k_hi);
        assert_true(ref > 0.0);
        assert_close(v, ref, 1e-9 * ref);
        /* and against a plain 2-D sum of F (midpoint in theta converges
         * slowly at the spreading functions' cusps: 5e-5) */
        double ref2 = band_integral(&p.sea, p.k_lo, p.k_hi);
        assert_close(v, ref2, 5e-5 * ref);
        assert_close(ocean_gerstner_variance(g, NULL), v, 1e-14 * v);
        ocean_gerstner_destroy(g);
    }
}

static void partition_with_fft_bands(void **state)
{
    (void)state;
    /* The ocean keeps |k| < k_max, the Gerstner set takes [k_max, k_hi). */
    ocean_params op;
    ocean_params_default(&op);
    op.n = 256;
    op.patch_m = 800.0;
    op.cascades = 1;
    op.threads = 1;
    /* k_max = 4 k_p: the near field holds ~2.5 % of the variance, enough
     * that counting its band twice (or dropping it) would show below */
    op.k_max = 0.3;
    ocean *o = NULL;
    char msg[160];
    assert_int_equal(ocean_create(&op, &o, msg, sizeof msg), OCEAN_OK);
    double patch, k_lo, k_hi;
    ocean_cascade_band(o, op.cascades - 1, &patch, &k_lo, &k_hi);
    assert_true(k_hi == op.k_max);

    ocean_gerstner_params p;
    ocean_gerstner_params_default(&p);
    p.sea = op.sea;
    p.seed = op.seed;
    p.count = 512;
    p.k_lo = k_hi; /* the finest cascade's upper edge */
    p.k_hi = 10.0 * k_hi;
    ocean_gerstner *g = make(&p);
    for (int i = 0; i < ocean_gerstner_count(g); i++) {
        ocean_gerstner_wave w;
        ocean_gerstner_get_wave(g, i, &w);
        assert_true(w.k >= k_hi); /* none inside the FFT's disc */
    }
    ocean_spectrum_stats st;
    ocean_get_spectrum_stats(o, &st);
    double vg = ocean_gerstner_variance(g, NULL);
    double fft_ref = band_integral(&p.sea, 1e-4, k_hi);
    double ger_ref = band_integral_1d(&p.sea, k_hi, p.k_hi);
    /* the Gerstner part is exact; the FFT part is a Riemann sum on its grid */
    assert_close(vg, ger_ref, 1e-9 * ger_ref);
    assert_close(st.variance, fft_ref, 0.004 * fft_ref);
    /* together they hold the spectrum below k_hi once, not twice */
    double total_ref = fft_ref + ger_ref;
    printf("FFT %.6g m^2 (integral %.6g), Gerstner %.6g m^2 (integral %.6g)\n", st.variance,
           fft_ref, vg, ger_ref);
    assert_close(st.variance + vg, total_ref, 0.004 * total_ref);
    assert_true(vg > 0.02 * st.variance); /* the near field matters here */
    ocean_gerstner_destroy(g);
    ocean_destroy(o);
}

/* Minimum Jacobian over an nx x nx grid of spacing h at (x0, z0). */
static double min_jacobian(const ocean_gerstner *g, const ocean_gerstner_view *v, double t,
                           double x0, double z0, double h, int nx)
{
    double *x = malloc(sizeof(double) * nx), *z = malloc(sizeof(double) * nx);
    ocean_gerstner_point *out = malloc(sizeof *out * nx);
    assert_non_null(x);
    assert_non_null(z);
    assert_non_null(out);
    double jmin = INFINITY;
    for (int r = 0; r < nx; r++) {
        for (int c = 0; c < nx; c++) {
            x[c] = x0 + c * h;
            z[c] = z0 + r * h;
        }
        assert_int_equal(ocean_gerstner_evaluate(g, v, t, x, z, nx, out), OCEAN_OK);
        for (int c = 0; c < nx; c++) {
            assert_true(isfinite(out[c].jacobian));
            jmin = fmin(jmin, out[c].jacobian);
        }
    }
    free(x);
    free(z);
    free(out);
    return jmin;
}

static void no_loops_at_extreme_settings(void **state)
{
    (void)state;
    ocean_gerstner_params p;
    ocean_gerstner_params_default(&p);
    p.sea.wind_u10 = 70.0;
    p.sea.choppiness = 5.0;
    p.count = 1024;
    p.k_lo = 0.02;   /* 314 m: big waves in the set */
    p.k_hi = 10.0;   /* 0.63 m */
    ocean_gerstner *g = make(&p);
    ocean_gerstner_view v;
    ocean_gerstner_view_default(&v);
    double q, steep;
    assert_int_equal(ocean_gerstner_effective_q(g, &v, &q, &steep), OCEAN_OK);
    assert_true(q < 5.0);                 /* the clamp is engaged */
    assert_true(steep <= 1.0 + 1e-12);    /* sum Q k A <= 1 */
    int nx = sanitized() ? 40 : 96; /* 96^2 x 3 points x 1024 waves: 0.8 s */
    double jmin = INFINITY;
    const double t[] = {0.0, 13.7, 1e5};
    for (int i = 0; i < 3; i++)
        jmin = fmin(jmin, min_jacobian(g, &v, t[i], -3.0 + 101.0 * i, 7.0, 0.05, nx));
    printf("70 m/s, choppiness 5, 1024 waves: Q = %.4g, sum QkA = %.6f, min J = %.4f\n",
           q, steep, jmin);
    assert_true(jmin >= 0.0);
    assert_true(jmin < 0.999); /* the waves do compress the surface */

    /* the fade's gradient is part of the bound */
    v.fade_r0 = 2.0;
    v.fade_r1 = 6.0;
    assert_int_equal(ocean_gerstner_effective_q(g, &v, &q, &steep), OCEAN_OK);
    assert_true(steep <= 1.0);
    assert_true(min_jacobian(g, &v, 3.0, -7.0, -7.0, 14.0 / nx, nx) >= 0.0);
    ocean_gerstner_destroy(g);

    /* one wave: the bound is tight, the crest becomes a cusp (J touches 0) */
    p.count = 1;
    p.k_lo = 0.003; /* one wave for the whole band: k A = 0.14 */
    p.k_hi = 0.3;
    p.sea.choppiness = 10.0;
    g = make(&p);
    ocean_gerstner_view_default(&v);
    assert_int_equal(ocean_gerstner_effective_q(g, &v, &q, &steep), OCEAN_OK);
    assert_true(q < p.sea.choppiness);
    assert_close(steep, 1.0, 1e-12);
    ocean_gerstner_wave w;
    ocean_gerstner_get_wave(g, 0, &w);
    /* walk along the wave direction through one wavelength in fine steps */
    double lam = 2 * M_PI / w.k, js = INFINITY;
    for (int i = 0; i < 20000; i++) {
        double s = lam * i / 20000.0, x = s * w.kx / w.k, z = s * w.kz / w.k;
        ocean_gerstner_point pt;
        assert_int_equal(ocean_gerstner_evaluate(g, &v, 0.0, &x, &z, 1, &pt), OCEAN_OK);
        js = fmin(js, pt.jacobian);
    }
    assert_true(js >= -1e-12);
    assert_true(js < 1e-6);
    ocean_gerstner_destroy(g);
}

static void eval1(const ocean_gerstner *g, const ocean_gerstner_view *v, double t, double x,
                  double z, ocean_gerstner_point *o)
{
    assert_int_equal(ocean_gerstner_evaluate(g, v, t, &x, &z, 1, o), OCEAN_OK);
}

static void velocity_and_normal_match_finite_differences(void **state)
{
    (void)state;
    ocean_gerstner_params p;
    ocean_gerstner_params_default(&p);
    p.sea.choppiness = 1.5;
    p.sea.depth_m = 6.0; /* finite depth dispersion */
    p.count = 300;
    ocean_gerstner *g = make(&p);
    ocean_gerstner_view v;
    ocean_gerstner_view_default(&v);
    v.camera_x = 1e6 + 3.0;
    v.camera_z = -2.0;
    v.fade_r0 = 1.0;
    v.fade_r1 = 9.0; /* points inside the fade ramp test its gradient too */
    double sa_k, sa_w, sa = sum_amp(g, &sa_k, &sa_w);
    const double ts[] = {0.0, 17.25, 1e6};
    const double xs[] = {1e6 + 3.2, 1e6 + 7.9, 1e6 - 1.3};
    const double zs[] = {-2.1, 1.7, -5.0};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double t = ts[i], x = xs[j], z = zs[j];
            ocean_gerstner_point c, a, b;
            eval1(g, &v, t, x, z, &c);
            assert_true(c.fade > 0.0);
            const double h = 1e-5;
            eval1(g, &v, t + h, x, z, &a);
            eval1(g, &v, t - h, x, z, &b);
            double tol = 1e-6 * sa_w + 1e-9;
            assert_close(c.vx, (a.dx - b.dx) / (2 * h), tol);
            assert_close(c.vy, (a.dy - b.dy) / (2 * h), tol);
            assert_close(c.vz, (a.dz - b.dz) / (2 * h), tol);
            /* tangents of the displaced surface by differences in x0 */
            const double e = 1e-6;
            ocean_gerstner_point xp, xm, zp, zm;
            eval1(g, &v, t, x + e, z, &xp);
            eval1(g, &v, t, x - e, z, &xm);
            eval1(g, &v, t, x, z + e, &zp);
            eval1(g, &v, t, x, z - e, &zm);
            double tx[3] = {1 + (xp.dx - xm.dx) / (2 * e), (xp.dy - xm.dy) / (2 * e),
                            (xp.dz - xm.dz) / (2 * e)};
            double tz[3] = {(zp.dx - zm.dx) / (2 * e), (zp.dy - zm.dy) / (2 * e),
                            1 + (zp.dz - zm.dz) / (2 * e)};
            double n[3] = {tz[1] * tx[2] - tz[2] * tx[1], tz[2] * tx[0] - tz[0] * tx[2],
                           tz[0] * tx[1] - tz[1] * tx[0]};
            double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            double tn = 1e-6 * (1 + sa_k);
            assert_close(c.nx, n[0] / len, tn);
            assert_close(c.ny, n[1] / len, tn);
            assert_close(c.nz, n[2] / len, tn);
            assert_close(c.jacobian, tx[0] * tz[2] - tz[0] * tx[2], tn);
            assert_close(c.nx * c.nx + c.ny * c.ny + c.nz * c.nz, 1.0, 1e-12);
            assert_true(c.ny > 0.0);
            (void)sa;
        }
    ocean_gerstner_destroy(g);
}

/* long double reference height (phases reduced in extended precision) */
static double reference_height(const ocean_gerstner *g, double t, double x, double z)
{
    const long double two_pi = 6.283185307179586476925286766559L;
    long double h = 0.0L;
    for (int i = 0; i < ocean_gerstner_count(g); i++) {
        ocean_gerstner_wave w;
        ocean_gerstner_get_wave(g, i, &w);
        long double th = (long double)w.kx * x + (long double)w.kz * z -
                         (long double)w.omega * t + w.phase;
        th = fmodl(th, two_pi);
        h += w.amplitude * cosl(th);
    }
    return (double)h;
}

static void phases_accurate_far_out(void **state)
{
    (void)state;
    ocean_gerstner_params p;
    ocean_gerstner_params_default(&p);
    p.count = 256;
    p.k_hi = 400.0; /* omega up to 63 rad/s: omega t = 8.4e9 at the time limit */
    ocean_gerstner *g = make(&p);
    ocean_gerstner_view v;
    ocean_gerstner_view_default(&v);
    double sa = sum_amp(g, NULL, NULL);
    const double ts[] = {0.0, 1e6, OCEAN_TIME_MAX};
    const double xs[] = {0.3, 1e7 + 0.37, -3e6 - 11.1};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            ocean_gerstner_point o;
            eval1(g, &v, ts[i], xs[j], 0.5 * xs[j], &o);
            double ref = reference_height(g, ts[i], xs[j], 0.5 * xs[j]);
            /* naive double phases are off by ~1e-5 rad here */
            assert_close(o.dy, ref, 5e-9 * sa);
        }
    /* beyond the one time limit: refused, not computed */
    double x = 0.3, z = 0.1, tb = nextafter(OCEAN_TIME_MAX, INFINITY);
    ocean_gerstner_point o;
    assert_int_equal(ocean_gerstner_evaluate(g, &v, tb, &x, &z, 1, &o), OCEAN_EINVAL);
    assert_int_equal(ocean_gerstner_evaluate(g, &v, 1e16, &x, &z, 1, &o), OCEAN_EINVAL);
    ocean_gerstner_destroy(g);
}

static void fade_radius(void **state)
{
    (void)state;
    ocean_gerstner_params p;
    ocean_gerstner_params_default(&p);
    p.count = 64;
    ocean_gerstner *g = make(&p);
    ocean_gerstner_view nofade, v;
    ocean_gerstner_view_default(&nofade);
    ocean_gerstner_view_default(&v);
    v.camera_x = 500.0;
    v.camera_z = -40.0;
    v.fade_r0 = 30.0;
    v.fade_r1 = 80.0;
    /* the fade's gradient tightens the steepness clamp a little */
    double qf, qn;
    assert_int_equal(ocean_gerstner_effective_q(g, &v, &qf, NULL), OCEAN_OK);
    assert_int_equal(ocean_gerstner_effective_q(g, &nofade, &qn, NULL), OCEAN_OK);
    assert_true(qf <= qn);
    double prev = 2.0;
    for (int i = 0; i <= 1000; i++) {
        double r = 0.1 * i, x = v.camera_x + r * 0.6, z = v.camera_z + r * 0.8;
        ocean_gerstner_point a, b;
        eval1(g, &v, 5.0, x, z, &a);
        eval1(g, &nofade, 5.0, x, z, &b);
        assert_true(a.fade <= prev);
        prev = a.fade;
        if (r <= 30.0) {
            assert_true(a.fade == 1.0);
            assert_true(a.dy == b.dy && a.vy == b.vy);
            assert_close(a.dx, b.dx * (qf / qn), 1e-12);
            assert_close(a.vz, b.vz * (qf / qn), 1e-12);
        } else if (r >= 80.0) {
            assert_true(a.fade == 0.0);
            assert_true(a.dx == 0.0 && a.dy == 0.0 && a.dz == 0.0 && a.vy == 0.0);
            assert_true(a.ny == 1.0 && a.jacobian == 1.0);
        } else {
            double s = (80.0 - r) / 50.0;
            assert_close(a.fade, s * s * (3 - 2 * s), 1e-12);
            assert_close(a.dy, a.fade * b.dy, 1e-12);
        }
    }
    /* smooth at both radii: no jump across r0 or r1 */
    ocean_gerstner_point in, out;
    eval1(g, &v, 5.0, v.camera_x + 30.0 - 1e-7, v.camera_z, &in);
    eval1(g, &v, 5.0, v.camera_x + 30.0 + 1e-7, v.camera_z, &out);
    assert_close(in.dy, out.dy, 1e-6);
    assert_close(in.ny, out.ny, 1e-6);
    eval1(g, &v, 5.0, v.camera_x, v.camera_z + 80.0 - 1e-7, &in);
    assert_close(in.dy, 0.0, 1e-9);
    /* invalid fades */
    ocean_gerstner_view bad = v;
    double x = 0, z = 0;
    ocean_gerstner_point o;
    bad.fade_r1 = bad.fade_r0;
    assert_int_equal(ocean_gerstner_evaluate(g, &bad, 0, &x, &z, 1, &o), OCEAN_EINVAL);
    bad = v;
    bad.fade_r0 = -1.0;
    assert_int_equal(ocean_gerstner_evaluate(g, &bad, 0, &x, &z, 1, &o), OCEAN_EINVAL);
    bad = v;
    bad.fade_r1 = NAN;
    assert_int_equal(ocean_gerstner_evaluate(g, &bad, 0, &x, &z, 1, &o), OCEAN_EINVAL);
    bad = v;
    bad.camera_x = INFINITY;
    assert_int_equal(ocean_gerstner_evaluate(g, &bad, 0, &x, &z, 1, &o), OCEAN_EINVAL);
    ocean_gerstner_destroy(g);
}

static void filter_gains_per_wave(void **state)
{
    (void)state;
    ocean_gerstner_params p;
    ocean_gerstner_params_default(&p);
    p.count = 200;
    ocean_gerstner *g = make(&p);
    ocean_filter_cutoff c = {.k = 5.0, .hz = NAN, .low_boost = 1.0, .order = 6};
    double vf = 0.0;
    for (int i = 0; i < 200; i++) {
        ocean_gerstner_wave w;
        ocean_gerstner_get_wave(g, i, &w);
        double a = ocean_filter_gain(w.k, 5.0, 6) * w.amplitude;
        vf += 0.5 * a * a;
    }
    assert_close(ocean_gerstner_variance(g, &c), vf, 1e-14 * vf);
    assert_true(vf < ocean_gerstner_variance(g, NULL));

    ocean_gerstner_view v0, vf_, vz;
    ocean_gerstner_view_default(&v0);
    vf_ = v0;
    vf_.filter = c;
    vz = v0;
    vz.filter.k = 0.0;
    /* single-wave check of the gain on the evaluated height */
    double rms0 = 0, rmsf = 0;
    for (int i = 0; i < 400; i++) {
        double x = 0.37 * i, z = 0.11 * i;
        ocean_gerstner_point a, b, zc;
        eval1(g, &v0, 2.0, x, z, &a);
        eval1(g, &vf_, 2.0, x, z, &b);
        eval1(g, &vz, 2.0, x, z, &zc);
        rms0 += a.dy * a.dy;
        rmsf += b.dy * b.dy;
        assert_true(zc.dy == 0.0 && zc.dx == 0.0 && zc.vy == 0.0); /* cutoff 0 */
    }
    assert_true(rmsf < rms0);
    /* the unfiltered view is the same as an infinite cutoff */
    ocean_gerstner_view vi = v0;
    vi.filter.k = INFINITY;
    vi.filter.order = 3;
    ocean_gerstner_point a, b;
    eval1(g, &v0, 2.0, 1.0, 2.0, &a);
    eval1(g, &vi, 2.0, 1.0, 2.0, &b);
    assert_memory_equal(&a, &b, sizeof a);
    /* the seed's boost raises gains above 1, the steepness clamp still holds */
    ocean_gerstner_destroy(g);
    p.sea.choppiness = 10.0;
    p.k_lo = 0.3;
    g = make(&p);
    ocean_gerstner_view vb = v0;
    vb.filter = (ocean_filter_cutoff){.k = 1e3, .hz = NAN, .low_boost = 1.03, .order = 6};
    double q, steep;
    assert_int_equal(ocean_gerstner_effective_q(g, &vb, &q, &steep), OCEAN_OK);
    assert_true(steep <= 1.0 + 1e-12);
    ocean_gerstner_destroy(g);
}

static void deterministic_and_order_free(void **state)
{
    (void)state;
    ocean_gerstner_params p;
    ocean_gerstner_params_default(&p);
    p.count = 100;
    p.seed = 0xC0FFEEull;
    ocean_gerstner *a = make(&p), *b = make(&p);
    for (int i = 0; i < 100; i++) {
        ocean_gerstner_wave wa, wb;
        ocean_gerstner_get_wave(a, i, &wa);
        ocean_gerstner_get_wave(b, i, &wb);
        assert_memory_equal(&wa, &wb, sizeof wa);
    }
    enum { N = 257 };
    double x[N], z[N], xr[N], zr[N];
    for (int i = 0; i < N; i++) {
        x[i] = -300.0 + 2.345 * i; /* spans several 256 m cells */
        z[i] = 1e5 + 0.77 * i;
        xr[N - 1 - i] = x[i];
        zr[N - 1 - i] = z[i];
    }
    ocean_gerstner_view v;
    ocean_gerstner_view_default(&v);
    ocean_gerstner_point oa[N], ob[N], orv[N];
    assert_int_equal(ocean_gerstner_evaluate(a, &v, 123.456, x, z, N, oa), OCEAN_OK);
    assert_int_equal(ocean_gerstner_evaluate(b, &v, 123.456, xr, zr, N, orv), OCEAN_OK);
    for (int i = 0; i < N; i++) {
        assert_memory_equal(&oa[i], &orv[N - 1 - i], sizeof oa[i]);
        eval1(b, &v, 123.456, x[i], z[i], &ob[i]);
        assert_memory_equal(&oa[i], &ob[i], sizeof oa[i]);
    }
    /* another seed, another sea */
    p.seed++;
    ocean_gerstner *c = make(&p);
    ocean_gerstner_wave wa, wc;
    ocean_gerstner_get_wave(a, 0, &wa);
    ocean_gerstner_get_wave(c, 0, &wc);
    assert_true(wa.phase != wc.phase);
    ocean_gerstner_destroy(a);
    ocean_gerstner_destroy(b);
    ocean_gerstner_destroy(c);
}

/* A prepared frame gives the same bytes as the one-shot call, point by
 * point, around a cell corner (4 cached cells) and after a new set. */
static void frame_matches_one_shot(void **state)
{
    (void)state;
    ocean_gerstner_params p;
    ocean_gerstner_params_default(&p);
    p.count = 200;
    ocean_gerstner *g = make(&p);
    ocean_gerstner_frame *fr = NULL;
    assert_int_equal(ocean_gerstner_frame_create(g, &fr), OCEAN_OK);
    ocean_gerstner_view v;
    ocean_gerstner_view_default(&v);
    double x0 = 128.0, z0 = -128.0; /* a corner of four 256 m cells */
    ocean_gerstner_point a, b;
    double x = x0, z = z0;
    assert_int_equal(ocean_gerstner_frame_evaluate(fr, &x, &z, 1, &a), OCEAN_ESTATE);
    double dd[3];
    assert_int_equal(ocean_gerstner_frame_displacement(fr, &x, &z, 1, dd), OCEAN_ESTATE);
    v.camera_x = x0;
    v.camera_z = z0;
    v.fade_r0 = 20.0;
    v.fade_r1 = 60.0;
    v.filter = (ocean_filter_cutoff){.k = 8.0, .hz = NAN, .low_boost = 1.03, .order = 6};
    for (int round = 0; round < 2; round++) {
        double t = round ? 1e7 + 0.25 : 3.5;
        assert_int_equal(ocean_gerstner_frame_set(fr, &v, t), OCEAN_OK);
        for (int i = 0; i < 2000; i++) {
            /* a ring around the corner: successive points change cells */
            double ang = i * 2.399963, r = 0.03 * i;
            x = x0 + r * cos(ang);
            z = z0 + r * sin(ang);
            assert_int_equal(ocean_gerstner_frame_evaluate(fr, &x, &z, 1, &a), OCEAN_OK);
            assert_int_equal(ocean_gerstner_evaluate(g, &v, t, &x, &z, 1, &b), OCEAN_OK);
            assert_memory_equal(&a, &b, sizeof a);
            double d[3];
            assert_int_equal(ocean_gerstner_frame_displacement(fr, &x, &z, 1, d), OCEAN_OK);
            assert_true(d[0] == a.dx && d[1] == a.dy && d[2] == a.dz);
        }
    }
    ocean_gerstner_view bad = v;
    bad.fade_r0 = NAN;
    assert_int_equal(ocean_gerstner_frame_set(fr, &bad, 0.0), OCEAN_EINVAL);
    assert_int_equal(ocean_gerstner_frame_set(fr, &v, INFINITY), OCEAN_EINVAL);
    x = NAN;
    assert_int_equal(ocean_gerstner_frame_evaluate(fr, &x, &z, 1, &a), OCEAN_EINVAL);
    ocean_gerstner_frame_destroy(fr);
    ocean_gerstner_frame_destroy(NULL);
    assert_int_equal(ocean_gerstner_frame_create(NULL, &fr), OCEAN_EINVAL);
    assert_null(fr);
    ocean_gerstner_destroy(g);
}

static void hostile_parameters(void **state)
{
    (void)state;
    ocean_gerstner_params p, bad;
    ocean_gerstner_params_default(&p);
    ocean_gerstner *g = (ocean_gerstner *)&p; /* must be reset to NULL on failure */
    char msg[160];
    bad = p;
    bad.count = 1025;
    assert_int_equal(ocean_gerstner_create(&bad, &g, msg, sizeof msg), OCEAN_EINVAL);
    assert_null(g);
    assert_non_null(strstr(msg, "count"));
    bad = p;
    bad.k_lo = NAN;
    assert_int_equal(ocean_gerstner_create(&bad, &g, msg, sizeof msg), OCEAN_EINVAL);
    assert_non_null(strstr(msg, "k_lo"));
    bad = p;
    bad.k_hi = bad.k_lo;
    assert_int_equal(ocean_gerstner_create(&bad, &g, msg, sizeof msg), OCEAN_EINVAL);
    bad = p;
    bad.k_hi = INFINITY;
    assert_int_equal(ocean_gerstner_create(&bad, &g, msg, sizeof msg), OCEAN_EINVAL);
    /* no wave faster than OCEAN_OMEGA_MAX = 64 rad/s (k = 417.7 rad/m in deep water):
     * the time limit's phase bound holds only up to it */
    bad = p;
    bad.k_hi = 420.0;
    assert_int_equal(ocean_gerstner_create(&bad, &g, msg, sizeof msg), OCEAN_EINVAL);
    assert_non_null(strstr(msg, "k_hi"));
    bad.k_hi = 417.0;
    assert_int_equal(ocean_gerstner_create(&bad, &g, msg, sizeof msg), OCEAN_OK);
    ocean_gerstner_destroy(g);
    g = (ocean_gerstner *)&p;
    bad = p;
    bad.steepness_max = 1.5;
    assert_int_equal(ocean_gerstner_create(&bad, &g, msg, sizeof msg), OCEAN_EINVAL);
    bad = p;
    bad.annuli = -1;
    assert_int_equal(ocean_gerstner_create(&bad, &g, msg, sizeof msg), OCEAN_EINVAL);
    bad = p;
    bad.sea.wind_u10 = NAN;
    assert_int_equal(ocean_gerstner_create(&bad, &g, msg, sizeof msg), OCEAN_EINVAL);
    ocean_gerstner_destroy(NULL);

    /* no waves: a flat, valid near field */
    bad = p;
    bad.count = 0;
    g = make(&bad);
    ocean_gerstner_view v;
    ocean_gerstner_view_default(&v);
    ocean_gerstner_point o;
    eval1(g, &v, OCEAN_TIME_MAX, 1e7, -1e7, &o);
    assert_true(o.dy == 0.0 && o.ny == 1.0 && o.jacobian == 1.0);
    assert_true(ocean_gerstner_variance(g, NULL) == 0.0);
    ocean_gerstner_destroy(g);

    /* calm sea: zero amplitudes, still finite */
    bad = p;
    bad.sea.wind_u10 = 0.0;
    g = make(&bad);
    eval1(g, &v, 3.0, 1.0, 2.0, &o);
    assert_true(o.dy == 0.0 && isfinite(o.ny));
    ocean_gerstner_destroy(g);

    /* hostile evaluation inputs */
    g = make(&p);
    double x = 1.0, z = NAN;
    assert_int_equal(ocean_gerstner_evaluate(g, &v, 0.0, &x, &z, 1, &o), OCEAN_EINVAL);
    z = 1.0;
    assert_int_equal(ocean_gerstner_evaluate(g, &v, NAN, &x, &z, 1, &o), OCEAN_EINVAL);
    assert_int_equal(ocean_gerstner_evaluate(g, &v, INFINITY, &x, &z, 1, &o), OCEAN_EINVAL);
    assert_int_equal(ocean_gerstner_evaluate(g, &v, 0.0, NULL, &z, 1, &o), OCEAN_EINVAL);
    assert_int_equal(ocean_gerstner_evaluate(g, &v, 0.0, NULL, NULL, 0, NULL), OCEAN_OK);
    ocean_gerstner_view bv = v;
    bv.filter.k = NAN;
    assert_int_equal(ocean_gerstner_evaluate(g, &bv, 0.0, &x, &z, 1, &o), OCEAN_EINVAL);
    bv = v;
    bv.filter.k = 1.0;
    bv.filter.order = 0;
    assert_int_equal(ocean_gerstner_evaluate(g, &bv, 0.0, &x, &z, 1, &o), OCEAN_EINVAL);
    ocean_gerstner_wave w;
    assert_int_equal(ocean_gerstner_get_wave(g, -1, &w), OCEAN_EINVAL);
    assert_int_equal(ocean_gerstner_get_wave(g, p.count, &w), OCEAN_EINVAL);
    ocean_gerstner_destroy(g);
    /* a sea the FFT ocean refuses, refused here too: Hs 110 m in 5 cm of
     * water exceeds the depth-limited breaking height (McCowan 1894) */
    p.sea.wind_u10 = 70.0;
    p.sea.depth_m = 0.05;
    p.sea.choppiness = 10.0;
    assert_int_equal(ocean_gerstner_params_validate(&p, msg, sizeof msg), OCEAN_EINVAL);
    assert_non_null(strstr(msg, "breaking height"));
    ocean_gerstner *none = NULL;
    assert_int_equal(ocean_gerstner_create(&p, &none, msg, sizeof msg), OCEAN_EINVAL);
    assert_null(none);
    /* extreme but valid: huge t, far point, steep sea, shallow water (the
     * 70 m/s sea's 4.3 km peak in 150 m: k d = 0.47) */
    p.sea.depth_m = 150.0;
    g = make(&p);
    eval1(g, &v, OCEAN_TIME_MAX, -1e9, 1e9, &o);
    assert_true(isfinite(o.dy) && isfinite(o.dx) && isfinite(o.vx) && isfinite(o.ny));
    assert_true(o.jacobian >= 0.0);
    ocean_gerstner_destroy(g);
}

/* The grid sampler against the direct sum: heights against the long
 * double reference above (no fade, no filter), every plane against the
 * one-point evaluator with a fade and a filter, stored and accumulated. */
static void grid_matches_direct_sum(void **state)
{
    (void)state;
    ocean_gerstner_params p;
    ocean_gerstner_params_default(&p);
    p.count = 128;
    p.sea.choppiness = 1.5;
    ocean_gerstner *g = make(&p);
    double sa = sum_amp(g, NULL, NULL);
    ocean_gerstner_frame *fr = NULL;
    assert_int_equal(ocean_gerstner_frame_create(g, &fr), OCEAN_OK);
    enum { W = 37, H = 29, STRIDE = 40 };
    float pl[8][H * STRIDE];
    ocean_gerstner_grid gr = {.x0 = 1e6 + 0.37, .z0 = -2e5 - 3.1, .spacing = 0.23, .w = W, .h = H,
                              .stride = STRIDE, .accumulate = 0, .height = pl[0], .dx = pl[1],
                              .dz = pl[2], .slope_x = pl[3], .slope_z = pl[4], .dxx = pl[5],
                              .dzz = pl[6], .dxz = pl[7]};
    assert_int_equal(ocean_gerstner_frame_sample_grid(fr, &gr), OCEAN_ESTATE);
    ocean_gerstner_view v;
    ocean_gerstner_view_default(&v);
    double t = 1e5 + 0.125;
    assert_int_equal(ocean_gerstner_frame_set(fr, &v, t), OCEAN_OK);
    assert_int_equal(ocean_gerstner_frame_sample_grid(fr, &gr), OCEAN_OK);
    for (int i = 0; i < H; i += 3)
        for (int j = 0; j < W; j += 2) {
            double x = gr.x0 + j * gr.spacing, z = gr.z0 + i * gr.spacing;
            assert_close(pl[0][i * STRIDE + j], reference_height(g, t, x, z), 1e-6 * sa + 1e-9);
        }
    /* fade and filter, accumulating onto a constant 1 */
    v.camera_x = gr.x0 + 4.0;
    v.camera_z = gr.z0 + 3.0;
    v.fade_r0 = 1.0;
    v.fade_r1 = 3.5;
    v.filter = (ocean_filter_cutoff){.k = 30.0, .hz = NAN, .low_boost = 1.0, .order = 4};
    assert_int_equal(ocean_gerstner_frame_set(fr, &v, t), OCEAN_OK);
    for (int c = 0; c < 8; c++)
        for (int q = 0; q < H * STRIDE; q++)
            pl[c][q] = 1.0f;
    gr.accumulate = 1;
    assert_int_equal(ocean_gerstner_frame_sample_grid(fr, &gr), OCEAN_OK);
    int inside = 0, outside = 0;
    for (int i = 0; i < H; i++)
        for (int j = 0; j < W; j++) {
            double x = gr.x0 + j * gr.spacing, z = gr.z0 + i * gr.spacing;
            ocean_gerstner_point o;
            assert_int_equal(ocean_gerstner_frame_evaluate(fr, &x, &z, 1, &o), OCEAN_OK);
            double want[8] = {o.dy, o.dx, o.dz, o.slope_x, o.slope_z, o.dxx, o.dzz,
                              0.5 * (o.dxz + o.dzx)};
            double scale[8] = {1, 1, 1, 100, 100, 100, 100, 100};
            for (int c = 0; c < 8; c++)
                assert_close(pl[c][i * STRIDE + j], 1.0 + want[c], 2e-7 * (1 + scale[c] * sa));
            if (o.fade == 0.0)
                outside++;
            else if (o.fade == 1.0)
                inside++;
        }
    assert_true(inside > 10 && outside > 100);
    ocean_gerstner_grid bad = gr;
    bad.stride = W - 1;
    assert_int_equal(ocean_gerstner_frame_sample_grid(fr, &bad), OCEAN_EINVAL);
    bad = gr;
    bad.spacing = NAN;
    assert_int_equal(ocean_gerstner_frame_sample_grid(fr, &bad), OCEAN_EINVAL);
    bad = gr;
    bad.w = 0;
    assert_int_equal(ocean_gerstner_frame_sample_grid(fr, &bad), OCEAN_EINVAL);
    assert_int_equal(ocean_gerstner_frame_sample_grid(fr, NULL), OCEAN_EINVAL);
    ocean_gerstner_frame_destroy(fr);
    ocean_gerstner_destroy(g);
}

/* The displacement derivatives and slopes a point carries (query
 * inversion's Newton step uses them) against central differences, with
 * the fade's own gradient inside the fade ring. */
static void derivatives_match_finite_differences(void **state)
{
    (void)state;
    ocean_gerstner_params p;
    ocean_gerstner_params_default(&p);
    p.count = 64;
    p.sea.choppiness = 1.0;
    ocean_gerstner *g = make(&p);
    double sak = 0;
    sum_amp(g, &sak, NULL);
    ocean_gerstner_view v;
    ocean_gerstner_view_default(&v);
    v.fade_r0 = 2.0;
    v.fade_r1 = 6.0;
    const double h = 1e-5;
    for (int i = 0; i < 40; i++) {
        double x = 0.17 * i - 3.0, z = 0.11 * i - 1.0;
        ocean_gerstner_point o, xp, xm, zp, zm;
        eval1(g, &v, 7.5, x, z, &o);
        eval1(g, &v, 7.5, x + h, z, &xp);
        eval1(g, &v, 7.5, x - h, z, &xm);
        eval1(g, &v, 7.5, x, z + h, &zp);
        eval1(g, &v, 7.5, x, z - h, &zm);
        double tol = 1e-5 * (sak + 1.0);
        assert_close(o.dxx, (xp.dx - xm.dx) / (2 * h), tol);
        assert_close(o.dxz, (zp.dx - zm.dx) / (2 * h), tol);
        assert_close(o.dzx, (xp.dz - xm.dz) / (2 * h), tol);
        assert_close(o.dzz, (zp.dz - zm.dz) / (2 * h), tol);
        assert_close(o.slope_x, (xp.dy - xm.dy) / (2 * h), tol);
        assert_close(o.slope_z, (zp.dy - zm.dy) / (2 * h), tol);
        assert_close(o.jacobian, (1 + o.dxx) * (1 + o.dzz) - o.dxz * o.dzx, 1e-12);
    }
    ocean_gerstner_destroy(g);
}


/* The ship-bridge scene's near field (config/scenes/ship-bridge.conf: JONSWAP,
 * Mitsuyasu, Beaufort 6 = 12.3 m/s toward 30 degrees, 100 km fetch,
 * choppiness 1.3; 3 cascades from 1000 m at ratio 4.3, n = 256, so the FFT
 * stops at pi n / L_finest; 64 waves to 0.1 m). */
static void ship_bridge_near_field(ocean_gerstner_params *p, int n)
{
    ocean_gerstner_params_default(p);
    p->sea.spectrum = OCEAN_SPECTRUM_JONSWAP;
    p->sea.spreading = OCEAN_SPREAD_MITSUYASU;
    p->sea.wind_u10 = 12.3;
    p->sea.wind_dir_deg = 30.0;
    p->sea.fetch_m = 1e5;
    p->sea.choppiness = 1.3;
    p->count = 64;
    p->k_lo = M_PI * n / (1000.0 / (4.3 * 4.3));
    p->k_hi = 2 * M_PI / 0.1;
    p->lattice_m = ocean_gerstner_lattice_for(n, p->k_hi);
}

/* Snapped waves (gerstner.h "Lattice"): every wave vector on the lattice
 * 2 pi (i, j) / L within the n-point grid's band, moved by at most half a
 * cell's diagonal from the wave drawn without the lattice, on the
 * dispersion relation of its new |k|, and the set's variance still the
 * band's integral of the spectrum (computed independently, 1-D in w). */
static void lattice_snapping_keeps_variance(void **state)
{
    (void)state;
    const int n = 256;
    ocean_gerstner_params p;
    ship_bridge_near_field(&p, n);
    double L = p.lattice_m;
    assert_close(L, 127 * 0.1, 1e-12);
    ocean_gerstner *g = make(&p);
    ocean_gerstner_params q = p;
    q.lattice_m = 0.0;
    ocean_gerstner *free_set = make(&q);
    double dk = 2 * M_PI / L, v = 0.0;
    int moved = 0;
    for (int i = 0; i < ocean_gerstner_count(g); i++) {
        ocean_gerstner_wave w, w0;
        assert_int_equal(ocean_gerstner_get_wave(g, i, &w), OCEAN_OK);
        assert_int_equal(ocean_gerstner_get_wave(free_set, i, &w0), OCEAN_OK);
        assert_true(abs(w.mx) <= n / 2 - 1 && abs(w.mz) <= n / 2 - 1);
        assert_close(w.kx, w.mx * dk, 1e-12 * w.k);
        assert_close(w.kz, w.mz * dk, 1e-12 * w.k);
        assert_close(w.k, hypot(w.kx, w.kz), 1e-12 * w.k);
        /* the nearest lattice point, unless an earlier wave holds it */
        long rx = lround(w0.kx / dk), rz = lround(w0.kz / dk);
        int held = 0;
        for (int q = 0; q < i; q++) {
            ocean_gerstner_wave e;
            ocean_gerstner_get_wave(g, q, &e);
            assert_false(e.mx == w.mx && e.mz == w.mz); /* every point holds one wave */
            held |= e.mx == rx && e.mz == rz;
        }
        if (held)
            moved++;
        else
            assert_true(hypot(w.kx - w0.kx, w.kz - w0.kz) <= M_SQRT1_2 * dk * (1 + 1e-12));
        assert_close(w.omega, ocean_dispersion(w.k, p.sea.depth_m), 1e-12 * w.omega);
        assert_close(w.amplitude, w0.amplitude, 0.0);
        assert_close(w.phase, w0.phase, 0.0);
        v += 0.5 * w.amplitude * w.amplitude;
    }
    double ref = band_integral_1d(&p.sea, p.k_lo, p.k_hi);
    assert_close(v, ref, 1e-9 * ref);
    assert_close(ocean_gerstner_variance(g, NULL), ref, 1e-9 * ref);
    print_message("lattice %.4g m: %d of %d waves moved past a taken point\n", L, moved,
                  ocean_gerstner_count(g));
    /* a coarse lattice (a 3.1 m patch, 64 waves from 3.7 rad/m): points
     * are shared often, and still every wave gets its own */
    ship_bridge_near_field(&q, 64);
    q.k_lo = M_PI * 64 / (1000.0 / (4.3 * 4.3));
    ocean_gerstner *coarse = make(&q);
    double cdk = 2 * M_PI / q.lattice_m;
    q.lattice_m = 0.0;
    ocean_gerstner *coarse_free = make(&q);
    int shared = 0;
    for (int i = 0; i < ocean_gerstner_count(coarse); i++) {
        ocean_gerstner_wave a_, b_, f_;
        ocean_gerstner_get_wave(coarse, i, &a_);
        ocean_gerstner_get_wave(coarse_free, i, &f_);
        assert_true(abs(a_.mx) <= 31 && abs(a_.mz) <= 31);
        long rx = lround(f_.kx / cdk), rz = lround(f_.kz / cdk);
        int held = 0;
        for (int j = 0; j < i; j++) {
            ocean_gerstner_get_wave(coarse, j, &b_);
            assert_false(a_.mx == b_.mx && a_.mz == b_.mz);
            held |= b_.mx == rx && b_.mz == rz;
        }
        shared += held;
    }
    print_message("lattice 3.1 m: %d of %d waves found their nearest point taken\n", shared,
                  ocean_gerstner_count(coarse));
    assert_true(shared > 0);
    ocean_gerstner_destroy(coarse_free);
    ocean_gerstner_destroy(coarse);
    q = p;
    /* hostile lattice sides */
    q.lattice_m = -1.0;
    ocean_gerstner *bad = NULL;
    assert_int_equal(ocean_gerstner_create(&q, &bad, NULL, 0), OCEAN_EINVAL);
    q.lattice_m = NAN;
    assert_int_equal(ocean_gerstner_create(&q, &bad, NULL, 0), OCEAN_EINVAL);
    assert_true(isnan(ocean_gerstner_lattice_for(4, 10.0)));
    assert_true(isnan(ocean_gerstner_lattice_for(256, INFINITY)));
    ocean_gerstner_destroy(free_set);
    ocean_gerstner_destroy(g);
}

/* The near-field cascade (ocean_create_lattice) evaluated by the FFT equals
 * the exact Gerstner sum of the same snapped waves (ocean_gerstner_evaluate,
 * double precision, no FFT) at every grid point: height, displacement and
 * slopes, to float precision (a few 1e-7 of each channel's largest possible
 * value, the sum of its coefficients' magnitudes); and its moments are the
 * waves' own (A^2/2 times 1, kx^2, kz^2, kx kz). */
static void lattice_cascade_matches_gerstner_sum(void **state)
{
    (void)state;
    const int n = 256;
    ocean_gerstner_params p;
    ship_bridge_near_field(&p, n);
    ocean_gerstner *g = make(&p);
    ocean_gerstner_view v;
    ocean_gerstner_view_default(&v);
    double Q, steep;
    assert_int_equal(ocean_gerstner_effective_q(g, &v, &Q, &steep), OCEAN_OK);
    assert_true(Q > 0.0);
    int M = ocean_gerstner_count(g);
    ocean_lattice_wave lw[64];
    double s_a = 0, s_qa = 0, s_ak = 0, var = 0, mxx = 0, mzz = 0, mxz = 0;
    for (int i = 0; i < M; i++) {
        ocean_gerstner_wave w;
        ocean_gerstner_get_wave(g, i, &w);
        lw[i] = (ocean_lattice_wave){w.mx, w.mz, w.amplitude, w.phase};
        s_a += w.amplitude;
        s_qa += Q * w.amplitude;
        s_ak += w.amplitude * w.k;
        var += 0.5 * w.amplitude * w.amplitude;
        mxx += 0.5 * w.amplitude * w.amplitude * w.kx * w.kx;
        mzz += 0.5 * w.amplitude * w.amplitude * w.kz * w.kz;
        mxz += 0.5 * w.amplitude * w.amplitude * w.kx * w.kz;
    }
    ocean_params op;
    ocean_params_default(&op);
    op.sea = p.sea;
    op.sea.choppiness = Q;
    op.n = n;
    op.threads = 1;
    ocean *oc = NULL;
    char msg[256] = "";
    ocean_result r = ocean_create_lattice(&op, p.lattice_m, lw, M, &oc, msg, sizeof msg);
    if (r != OCEAN_OK)
        print_error("%s\n", msg);
    assert_int_equal(r, OCEAN_OK);
    ocean_frame *f = NULL;
    assert_int_equal(ocean_frame_create(oc, &f), OCEAN_OK);
    ocean_request rq;
    ocean_request_all(&rq, OCEAN_FX_HEIGHT | OCEAN_FX_DISPLACEMENT | OCEAN_FX_NORMALS);
    double t = 3600.0 + 1.0 / 3.0;
    assert_int_equal(ocean_evaluate(oc, t, &rq, f), OCEAN_OK);
    const ocean_field *fd = ocean_frame_field(f, 0);
    assert_int_equal(fd->n, n);
    assert_close(fd->patch_m, p.lattice_m, 0.0);
    /* every grid point against the exact sum */
    size_t nn = (size_t)n * n;
    double *x = malloc(2 * nn * sizeof *x), *z = x + nn;
    ocean_gerstner_point *gp = malloc(nn * sizeof *gp);
    assert_non_null(x);
    assert_non_null(gp);
    double sp = p.lattice_m / n;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            x[(size_t)i * n + j] = j * sp;
            z[(size_t)i * n + j] = i * sp;
        }
    assert_int_equal(ocean_gerstner_evaluate(g, &v, t, x, z, nn, gp), OCEAN_OK);
    double eh = 0, ed = 0, es = 0, rms = 0;
    for (size_t i = 0; i < nn; i++) {
        eh = fmax(eh, fabs(fd->height[i] - gp[i].dy));
        ed = fmax(ed, fmax(fabs(fd->dx[i] - gp[i].dx), fabs(fd->dz[i] - gp[i].dz)));
        es = fmax(es, fmax(fabs(fd->slope_x[i] - gp[i].slope_x), fabs(fd->slope_z[i] - gp[i].slope_z)));
        rms += gp[i].dy * gp[i].dy;
    }
    rms = sqrt(rms / nn);
    print_message("near-field cascade vs Gerstner sum: height %.3g m (sum a %.3g, rms %.3g), "
                  "displacement %.3g m, slope %.3g (sum a k %.3g)\n", eh, s_a, rms, ed, es, s_ak);
    /* the field is really there (not two zeros agreeing) */
    assert_close(rms * rms, var, 0.5 * var);
    assert_true(eh <= 1e-6 * s_a);
    assert_true(ed <= 1e-6 * s_qa);
    assert_true(es <= 1e-6 * s_ak);
    /* moments and mips of the cascade are the waves' own */
    ocean_moments mo;
    assert_int_equal(ocean_cascade_moments(oc, 0, 0.0, 6, &mo), OCEAN_OK);
    assert_close(mo.total_var_h, var, 1e-6 * var);
    assert_close(mo.var_h, var, 1e-6 * var);
    assert_close(mo.mss_x, mxx, 1e-6 * (mxx + mzz));
    assert_close(mo.mss_z, mzz, 1e-6 * (mxx + mzz));
    assert_close(mo.mss_xz, mxz, 1e-6 * (mxx + mzz));
    assert_int_equal(ocean_cascade_moments(oc, 0, INFINITY, 6, &mo), OCEAN_OK);
    assert_close(mo.var_h, 0.0, 0.0);
    int mips = 0;
    double kc[12];
    assert_int_equal(ocean_cascade_mips(oc, 0, 6, 12, &mips, kc), OCEAN_OK);
    /* mip 0 is the whole cascade, mip 1 its half-Nyquist cutoff (n/8) dk
     * (PROTOCOL.md "Cascade mips"); the near field (14.9 to 62.8 rad/m on
     * a 12.7 m patch) holds waves at least there */
    assert_true(mips >= 2);
    assert_true(isinf(kc[0]));
    assert_close(kc[1], (n / 8) * 2 * M_PI / p.lattice_m, 1e-12 * kc[1]);
    print_message("near-field cascade: patch %.4g m, %d mips\n", p.lattice_m, mips);
    /* hostile waves: off the grid's band, the origin */
    ocean_lattice_wave badw = {n / 2, 0, 0.01, 0.0};
    ocean *bad = NULL;
    assert_int_equal(ocean_create_lattice(&op, p.lattice_m, &badw, 1, &bad, msg, sizeof msg), OCEAN_EINVAL);
    badw = (ocean_lattice_wave){0, 0, 0.01, 0.0};
    assert_int_equal(ocean_create_lattice(&op, p.lattice_m, &badw, 1, &bad, msg, sizeof msg), OCEAN_EINVAL);
    badw = (ocean_lattice_wave){3, 4, NAN, 0.0};
    assert_int_equal(ocean_create_lattice(&op, p.lattice_m, &badw, 1, &bad, msg, sizeof msg), OCEAN_EINVAL);
    assert_int_equal(ocean_create_lattice(&op, NAN, lw, M, &bad, msg, sizeof msg), OCEAN_EINVAL);
    assert_null(bad);
    free(gp);
    free(x);
    ocean_frame_destroy(f);
    ocean_destroy(oc);
    ocean_gerstner_destroy(g);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(variance_equals_band_integral),
        cmocka_unit_test(partition_with_fft_bands),
        cmocka_unit_test(no_loops_at_extreme_settings),
        cmocka_unit_test(velocity_and_normal_match_finite_differences),
        cmocka_unit_test(phases_accurate_far_out),
        cmocka_unit_test(fade_radius),
        cmocka_unit_test(filter_gains_per_wave),
        cmocka_unit_test(deterministic_and_order_free),
        cmocka_unit_test(frame_matches_one_shot),
        cmocka_unit_test(hostile_parameters),
        cmocka_unit_test(grid_matches_direct_sum),
        cmocka_unit_test(derivatives_match_finite_differences),
        cmocka_unit_test(lattice_snapping_keeps_variance),
        cmocka_unit_test(lattice_cascade_matches_gerstner_sum),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
