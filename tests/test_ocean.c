/*
 * test_ocean.c - the FFT ocean: physics against published relations,
 * numerics (Hermitian, Parseval, Jacobian, resolution independence,
 * determinism) and the hard cases, which must stay finite and bounded.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cmocka.h>
#include <fftw3.h>

#include "ocean.h"
#include "ocean_internal.h"
#include "ocean_reference.h"
#include "ocean_time.h"

static int sanitized(void)
{
    return getenv("OCEAN_TEST_SANITIZED") != NULL;
}

static ocean *make(const ocean_params *p)
{
    char msg[256];
    ocean *o = NULL;
    ocean_result r = ocean_create(p, &o, msg, sizeof msg);
    if (r != OCEAN_OK)
        fail_msg("ocean_create: %s", msg);
    return o;
}

static ocean_frame *frame(const ocean *o)
{
    ocean_frame *f = NULL;
    assert_int_equal(ocean_frame_create(o, &f), OCEAN_OK);
    return f;
}

static void eval(ocean *o, ocean_frame *f, double t, unsigned fx)
{
    ocean_request r;
    ocean_request_all(&r, fx);
    assert_int_equal(ocean_evaluate(o, t, &r, f), OCEAN_OK);
}

/* PM sea with U19.5 = 10 m/s on a patch that resolves the peak finely. */
static void pm_params(ocean_params *p, int n)
{
    ocean_params_default(p);
    p->sea.spectrum = OCEAN_SPECTRUM_PM;
    p->sea.wind_u10 = 10.0 / 1.026;
    p->n = n;
    p->patch_m = 2000.0;
}

/* Variance the grid cannot hold: the w^-5 tail above w_max, a g^2/(4 w^4). */
static double pm_tail(const ocean_params *p)
{
    double kmax = M_PI * p->n / p->patch_m;
    double wmax = ocean_dispersion(kmax, p->sea.depth_m);
    return 8.1e-3 * OCEAN_G * OCEAN_G / (4.0 * pow(wmax, 4));
}

static void test_hs_pierson_moskowitz(void **state)
{
    (void)state;
    ocean_params p;
    pm_params(&p, 512);
    ocean *o = make(&p);
    ocean_spectrum_stats ss;
    ocean_get_spectrum_stats(o, &ss);
    /* Published: Hs = 0.20925 U19.5^2 / g = 2.133 m.  The discrete
     * spectrum misses the tail beyond the grid: add it back, then the
     * quadrature of the grid must agree within 1.5 %. */
    double hs_pub = 0.20925 * 100.0 / OCEAN_G;
    double hs_tail = 4.0 * sqrt(ss.variance + pm_tail(&p));
    if (fabs(hs_tail - hs_pub) > 0.015 * hs_pub)
        fail_msg("discrete Hs %.4f (+tail %.4f) vs published %.4f", ss.hs, hs_tail, hs_pub);
    assert_true(fabs(ss.tp - 7.302) < 0.01);
    /* The realised field: 4 std within 8 % (one random sea). */
    ocean_frame *f = frame(o);
    eval(o, f, 0.0, OCEAN_FX_HEIGHT);
    ocean_field_stats fs;
    ocean_frame_get_field_stats(f, &fs);
    if (fabs(fs.hs - ss.hs) > 0.08 * ss.hs)
        fail_msg("realised Hs %.4f vs spectrum %.4f", fs.hs, ss.hs);
    ocean_frame_destroy(f);
    ocean_destroy(o);
}

static void test_hs_jonswap(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.sea.spectrum = OCEAN_SPECTRUM_JONSWAP;
    p.sea.wind_u10 = 10.0;
    p.sea.fetch_m = 1e5;
    p.n = 512;
    p.patch_m = 2000.0;
    ocean *o = make(&p);
    ocean_spectrum_stats ss;
    ocean_get_spectrum_stats(o, &ss);
    double kmax = M_PI * p.n / p.patch_m, wmax = ocean_dispersion(kmax, p.sea.depth_m);
    /* the w^-5 tail above the grid, alpha = 0.076 chi^-0.22 (below) */
    double tail = 0.076 * pow(OCEAN_G * p.sea.fetch_m / 100.0, -0.22) * OCEAN_G * OCEAN_G /
                  (4.0 * pow(wmax, 4));
    double hs = 4.0 * sqrt(ss.variance + tail);
    /* Check value: the published JONSWAP spectrum (Hasselmann et al. 1973:
     * alpha = 0.076 chi^-0.22, w_p = 22 (g^2 / (U F))^(1/3), gamma = 3.3,
     * sigma 0.07 / 0.09) integrated here by Simpson's rule, not spectrum.c's
     * integral; the grid's quadrature must hold it within 2 %.  (The same
     * paper's energy law, g Hs / U^2 = 1.6e-3 chi^(1/2), gives 1.615 m, 32 %
     * less: see test_jonswap_energy_growth_law in test_spectrum.c.) */
    const double g = OCEAN_G, U = p.sea.wind_u10, F = p.sea.fetch_m;
    double alpha = 0.076 * pow(g * F / (U * U), -0.22), wp = 22.0 * cbrt(g * g / (U * F));
    double a = 0.2 * wp, b = 40.0 * wp, h = (b - a) / 200000, m0 = 0.0;
    for (int i = 0; i <= 200000; i++) {
        double w = a + i * h, sig = w <= wp ? 0.07 : 0.09;
        double r = exp(-(w - wp) * (w - wp) / (2.0 * sig * sig * wp * wp));
        double sw = alpha * g * g * pow(w, -5.0) * exp(-1.25 * pow(wp / w, 4.0)) * pow(3.3, r);
        m0 += sw * (i == 0 || i == 200000 ? 1.0 : (i % 2 ? 4.0 : 2.0));
    }
    m0 = m0 * h / 3.0 + alpha * g * g / (4.0 * pow(b, 4.0));
    double hs_pub = 4.0 * sqrt(m0);
    if (fabs(hs - hs_pub) > 0.02 * hs_pub)
        fail_msg("JONSWAP discrete Hs %.4f (+tail) vs published spectrum %.4f", hs, hs_pub);
    ocean_destroy(o);
}

static void test_tma_lowers_hs(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.sea.spectrum = OCEAN_SPECTRUM_TMA;
    p.sea.fetch_m = 2e4;
    p.n = 256;
    p.patch_m = 500.0;
    /* A circular band, so the grid holds every wave up to w(k_max). */
    p.k_max = M_PI * p.n / p.patch_m;
    double prev = 0.0, depths[] = {2.0, 5.0, 20.0, 4000.0};
    for (size_t i = 0; i < 4; i++) {
        p.sea.depth_m = depths[i];
        ocean *o = make(&p);
        ocean_spectrum_stats ss;
        ocean_get_spectrum_stats(o, &ss);
        assert_true(ss.hs > prev);
        /* The grid follows the TMA spectrum integrated over the same band
         * (shallow water shortens the waves, so the band ends at a lower w). */
        double w0 = ocean_dispersion(2.0 * M_PI / p.patch_m, p.sea.depth_m);
        double w1 = ocean_dispersion(p.k_max, p.sea.depth_m), m0 = 0.0;
        for (int k = 0; k < 20000; k++) {
            double w = w0 + (k + 0.5) * (w1 - w0) / 20000;
            m0 += ocean_spectrum_s(&p.sea, w) * (w1 - w0) / 20000;
        }
        double an = 4.0 * sqrt(m0);
        if (fabs(ss.hs - an) > 0.03 * an)
            fail_msg("depth %g: grid Hs %.4f vs analytic %.4f", depths[i], ss.hs, an);
        prev = ss.hs;
        ocean_destroy(o);
    }
}

/* Rice: zero up-crossing period of a Gaussian sea is 2 pi sqrt(m0/m2);
 * m2 needs the dispersion relation, so a wrong w(k) shows here. */
static void test_time_series_periods(void **state)
{
    (void)state;
    double depths[] = {4000.0, 3.0};
    for (size_t d = 0; d < 2; d++) {
        ocean_params p;
        ocean_params_default(&p);
        p.sea.spectrum = d == 0 ? OCEAN_SPECTRUM_PM : OCEAN_SPECTRUM_TMA;
        p.sea.depth_m = depths[d];
        p.sea.wind_u10 = 8.0;
        p.n = 64;
        p.patch_m = 800.0;
        p.threads = 1;
        ocean *o = make(&p);
        ocean_frame *f = frame(o);
        double dk = 2.0 * M_PI / p.patch_m, m0 = 0.0, m2 = 0.0;
        for (int mz = -p.n / 2 + 1; mz < p.n / 2; mz++)
            for (int mx = -p.n / 2 + 1; mx < p.n / 2; mx++) {
                double kx = mx * dk, kz = mz * dk;
                double v = ocean_spectrum_f(&p.sea, kx, kz) * dk * dk;
                double w = ocean_dispersion(hypot(kx, kz), p.sea.depth_m);
                m0 += v;
                m2 += v * w * w;
            }
        double tz = 2.0 * M_PI * sqrt(m0 / m2);
        /* Several points, a long record: count up-crossings. */
        int crossings = 0;
        double total_t = 0.0, dt = 0.1;
        int steps = sanitized() ? 3000 : 8000;
        double prev[4] = {0};
        for (int i = 0; i < steps; i++) {
            eval(o, f, i * dt, OCEAN_FX_HEIGHT);
            for (int q = 0; q < 4; q++) {
                ocean_point pt;
                ocean_frame_sample(f, 100.0 * q + 12.5, 37.5 * q, &pt);
                if (i > 0 && prev[q] < 0.0 && pt.height >= 0.0)
                    crossings++;
                prev[q] = pt.height;
            }
        }
        total_t = 4 * (steps - 1) * dt;
        double tz_obs = total_t / crossings;
        if (fabs(tz_obs - tz) > 0.1 * tz)
            fail_msg("depth %g: observed Tz %.3f s vs Rice %.3f s", depths[d], tz_obs, tz);
        ocean_frame_destroy(f);
        ocean_destroy(o);
    }
}

/* The full complex spectrum, inverse-transformed with c2c, is real: the
 * Hermitian construction holds; and its real part is the c2r field. */
static void test_hermitian_and_parseval(void **state)
{
    (void)state;
    ocean_params p;
    pm_params(&p, 128);
    p.patch_m = 600.0;
    ocean *o = make(&p);
    int n = p.n;
    double t = 123.456;
    fftwf_complex *in = fftwf_malloc(sizeof(fftwf_complex) * n * n);
    fftwf_complex *out = fftwf_malloc(sizeof(fftwf_complex) * n * n);
    fftwf_plan plan = fftwf_plan_dft_2d(n, n, in, out, FFTW_BACKWARD, FFTW_ESTIMATE);
    double spec_var = 0.0;
    for (int iz = 0; iz < n; iz++)
        for (int ix = 0; ix < n; ix++) {
            int mz = iz < n / 2 ? iz : iz - n, mx = ix < n / 2 ? ix : ix - n;
            double h[2];
            ocean_mode_amplitude(o, 0, mx, mz, t, h);
            in[iz * n + ix][0] = (float)h[0];
            in[iz * n + ix][1] = (float)h[1];
            spec_var += h[0] * h[0] + h[1] * h[1];
        }
    fftwf_execute(plan);
    double re2 = 0.0, im2 = 0.0;
    for (int i = 0; i < n * n; i++) {
        re2 += (double)out[i][0] * out[i][0];
        im2 += (double)out[i][1] * out[i][1];
    }
    if (!(sqrt(im2) <= 1e-6 * sqrt(re2)))
        fail_msg("imaginary residue %.3g of the real part", sqrt(im2 / re2));
    ocean_frame *f = frame(o);
    eval(o, f, t, OCEAN_FX_HEIGHT);
    const ocean_field *fd = ocean_frame_field(f, 0);
    double diff = 0.0, var = 0.0, mean = 0.0;
    for (int i = 0; i < n * n; i++) {
        diff = fmax(diff, fabs(fd->height[i] - out[i][0]));
        var += (double)fd->height[i] * fd->height[i];
        mean += fd->height[i];
    }
    mean /= n * n;
    var = var / (n * n) - mean * mean;
    assert_true(diff < 1e-5 * sqrt(re2 / (n * n)) * 10);
    /* Parseval: spatial variance equals the sum of |h(k,t)|^2. */
    if (fabs(var - spec_var) > 1e-4 * spec_var)
        fail_msg("Parseval: spatial %.8g vs spectral %.8g", var, spec_var);
    assert_true(fabs(mean) < 1e-6);
    fftwf_destroy_plan(plan);
    fftwf_free(in);
    fftwf_free(out);
    ocean_frame_destroy(f);
    ocean_destroy(o);
}

static void test_mean_jacobian_is_one(void **state)
{
    (void)state;
    double chop[] = {0.0, 1.0, 2.5, 5.0};
    ocean_params p;
    pm_params(&p, 128);
    p.patch_m = 400.0; /* holds the 350 m peak (ocean_plan.h) */
    p.sea.wind_u10 = 20.0;
    for (size_t i = 0; i < 4; i++) {
        p.sea.choppiness = chop[i];
        ocean *o = make(&p);
        ocean_frame *f = frame(o);
        eval(o, f, 7.0, OCEAN_FX_FOAM);
        const ocean_field *fd = ocean_frame_field(f, 0);
        double s = 0.0;
        for (int k = 0; k < p.n * p.n; k++)
            s += fd->jacobian[k];
        s /= p.n * p.n;
        if (fabs(s - 1.0) > 1e-5)
            fail_msg("choppiness %g: mean J = %.8f", chop[i], s);
        ocean_field_stats fs;
        ocean_frame_get_field_stats(f, &fs);
        if (chop[i] == 0.0)
            assert_true(fs.min_jacobian == 1.0 && fs.folded_fraction == 0.0);
        if (chop[i] == 5.0)
            assert_true(fs.folded_fraction > 0.0); /* storm chop at 5x folds */
        ocean_frame_destroy(f);
        ocean_destroy(o);
    }
}

static void test_hs_independent_of_n(void **state)
{
    (void)state;
    ocean_params p;
    pm_params(&p, 256);
    p.patch_m = 1000.0;
    double hs[3];
    int ns[3] = {256, 512, 1024};
    for (int i = 0; i < 3; i++) {
        p.n = ns[i];
        ocean *o = make(&p);
        ocean_spectrum_stats ss;
        ocean_get_spectrum_stats(o, &ss);
        hs[i] = 4.0 * sqrt(ss.variance + pm_tail(&p));
        ocean_destroy(o);
    }
    /* With the tail accounted for, doubling N changes nothing but quadrature. */
    assert_true(fabs(hs[1] - hs[0]) < 0.005 * hs[0]);
    assert_true(fabs(hs[2] - hs[0]) < 0.005 * hs[0]);
}

/* Same waves at any N: with the band limited to N = 64's circle, N = 64
 * and N = 256 hold exactly the same waves, and the fine grid subsampled
 * every 4th point equals the coarse grid. */
static void test_common_waves_across_n(void **state)
{
    (void)state;
    ocean_params p;
    pm_params(&p, 64);
    p.patch_m = 400.0;
    p.k_max = 31.5 * 2.0 * M_PI / p.patch_m;
    ocean *a = make(&p);
    p.n = 256;
    ocean *b = make(&p);
    ocean_frame *fa = frame(a), *fb = frame(b);
    unsigned fx = OCEAN_FX_HEIGHT | OCEAN_FX_DISPLACEMENT | OCEAN_FX_NORMALS;
    eval(a, fa, 42.0, fx);
    eval(b, fb, 42.0, fx);
    const ocean_field *x = ocean_frame_field(fa, 0), *y = ocean_frame_field(fb, 0);
    double maxd = 0.0, maxh = 0.0;
    for (int i = 0; i < 64; i++)
        for (int j = 0; j < 64; j++) {
            size_t ia = (size_t)i * 64 + j, ib = (size_t)(4 * i) * 256 + 4 * j;
            maxd = fmax(maxd, fabs(x->height[ia] - y->height[ib]));
            maxd = fmax(maxd, fabs(x->dx[ia] - y->dx[ib]));
            maxd = fmax(maxd, fabs(x->slope_z[ia] - y->slope_z[ib]) * 10.0);
            maxh = fmax(maxh, fabs(x->height[ia]));
        }
    if (!(maxd < 1e-5 * maxh + 1e-6))
        fail_msg("N=64 vs N=256 differ by %.3g (max height %.3g)", maxd, maxh);
    /* And amplitudes are keyed by the wave vector: identical in double. */
    for (int mz = -31; mz < 32; mz += 5)
        for (int mx = -31; mx < 32; mx += 3) {
            double ha[2], hb[2];
            ocean_mode_amplitude(a, 0, mx, mz, 3.0, ha);
            ocean_mode_amplitude(b, 0, mx, mz, 3.0, hb);
            assert_true(ha[0] == hb[0] && ha[1] == hb[1]);
        }
    ocean_frame_destroy(fa);
    ocean_frame_destroy(fb);
    ocean_destroy(a);
    ocean_destroy(b);
}

static int fields_equal(const ocean_frame *a, const ocean_frame *b, int cascades)
{
    for (int c = 0; c < cascades; c++) {
        const ocean_field *x = ocean_frame_field(a, c), *y = ocean_frame_field(b, c);
        size_t nn = (size_t)x->n * x->n * sizeof(float);
        const float *px[] = {x->height, x->dx, x->dz, x->slope_x, x->slope_z, x->jacobian, x->foam};
        const float *py[] = {y->height, y->dx, y->dz, y->slope_x, y->slope_z, y->jacobian, y->foam};
        if (x->n != y->n)
            return 0;
        for (int k = 0; k < 7; k++)
            if ((px[k] == NULL) != (py[k] == NULL) || (px[k] && memcmp(px[k], py[k], nn) != 0))
                return 0;
    }
    return 1;
}

static void test_determinism(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.n = 128;
    p.cascades = 3;
    ocean *a = make(&p), *b = make(&p);
    ocean_frame *f1 = frame(a), *f2 = frame(a), *f3 = frame(b);
    eval(a, f1, 5.0, OCEAN_FX_ALL);
    eval(a, f2, 1.0, OCEAN_FX_ALL);
    eval(a, f2, 1e6, OCEAN_FX_ALL);
    eval(a, f2, 5.0, OCEAN_FX_ALL);
    assert_true(fields_equal(f1, f2, 3));
    /* A second ocean (another daemon) agrees bit for bit. */
    eval(b, f3, 5.0, OCEAN_FX_ALL);
    assert_true(fields_equal(f1, f3, 3));
    eval(b, f3, 5.000001, OCEAN_FX_ALL);
    assert_false(fields_equal(f1, f3, 3));
    ocean_frame_destroy(f1);
    ocean_frame_destroy(f2);
    ocean_frame_destroy(f3);
    ocean_destroy(a);
    ocean_destroy(b);
}

/* 2 pi to 113 bits, independent of the library's two-double split. */
#define TWO_PI_Q 6.283185307179586476925286766559005768394Q

/* w t mod 2 pi in __float128: the product of two doubles is exact in
 * 113 bits (53 + 53 <= 113), so this shares nothing with the library's
 * double-double arithmetic. */
static __float128 phase_q(double w, double t)
{
    __float128 x = (__float128)w * (__float128)t;
    __float128 q = x / TWO_PI_Q;
    long long n = (long long)(q + (q >= 0 ? 0.5Q : -0.5Q));
    return x - (__float128)n * TWO_PI_Q;
}

static double wrap_pi(double d)
{
    return d > M_PI ? d - 2.0 * M_PI : d < -M_PI ? d + 2.0 * M_PI : d;
}

/* Item 7 of issue 13: w t mod 2 pi exact below the time limit, against a
 * __float128 reference, for frequencies up to OCEAN_OMEGA_MAX and times up
 * to OCEAN_TIME_MAX.  The old reduction (a rounded product w * t less
 * q * 2pi_hi, whose product with q is not exact) is off by up to ~2e-6 rad
 * at the limit; this asks 4e-15. */
static void test_phase_exact_to_time_limit(void **state)
{
    (void)state;
    double ws[12] = {OCEAN_OMEGA_MAX, nextafter(OCEAN_OMEGA_MAX, 0.0), 1e-3, 0.7853981633974483,
                     17.123456789012345, 2.0 * M_PI};
    /* and frequencies from the dispersion relation, as the ocean holds them */
    double ks[6] = {0.001, 0.0313, 0.5, 3.7, 61.0, 417.0}, hs[6] = {4000, 6, 4000, 0.3, 50, 4000};
    for (int i = 0; i < 6; i++)
        ws[6 + i] = ocean_dispersion(ks[i], hs[i]);
    uint64_t lcg = 12345;
    double worst = 0.0, naive_worst = 0.0;
    for (int i = 0; i < 12; i++)
        for (int j = 0; j < 400; j++) {
            double t;
            if (j == 0) t = OCEAN_TIME_MAX;
            else if (j == 1) t = -OCEAN_TIME_MAX;
            else if (j == 2) t = 0.0;
            else if (j == 3) t = 1e8 + 0.123456789;
            else {
                lcg = lcg * 6364136223846793005ULL + 1442695040888963407ULL;
                double u = (double)(lcg >> 11) / 9007199254740992.0; /* [0, 1) */
                /* log-uniform magnitude 1e-3 .. the limit, either sign */
                t = copysign(1e-3 * pow(OCEAN_TIME_MAX / 1e-3, u), (lcg & 1) ? 1.0 : -1.0);
            }
            double want = (double)phase_q(ws[i], t);
            double got = ocean_phase(ws[i], t);
            double err = fabs(wrap_pi(got - want));
            if (!(err <= 4e-15))
                fail_msg("w = %.17g t = %.17g: phase %.17g, __float128 %.17g (error %.3g rad)",
                         ws[i], t, got, want, err);
            if (!(fabs(got) <= M_PI + 1e-14))
                fail_msg("w = %.17g t = %.17g: phase %.17g outside [-pi, pi]", ws[i], t, got);
            worst = fmax(worst, err);
            double x = ws[i] * t; /* what a plain double product gives */
            naive_worst = fmax(naive_worst, fabs(wrap_pi(remainder(x, 2.0 * M_PI) - want)));
        }
    /* For the report: the plain product's own rounding is the bound the
     * limit is built on (<= 2^-20 rad = 9.5e-7). */
    print_message("phase: worst error %.3g rad (plain double product %.3g rad, bound %.3g)\n",
                  worst, naive_worst, OCEAN_PHASE_ERROR_MAX);
    assert_true(naive_worst <= OCEAN_PHASE_ERROR_MAX);
    /* Beyond what the reduction can hold, NaN rather than a wrong phase. */
    assert_true(isnan(ocean_phase(64.0, 1e300)));
    assert_true(isnan(ocean_phase(NAN, 1.0)));
    assert_true(isnan(ocean_phase(1.0, INFINITY)));
}

/* The vectorised row loop of the FFT ocean against a direct sum of the
 * same waves in long double, with every phase w t reduced in __float128:
 * the float field at the time limit is as good as at t = 0.  Each wave's
 * two amplitudes A, B (h = A e^{-i w t} + B e^{+i w t}) are read at t = 0
 * and at a quarter period, where no large product exists. */
static void test_field_at_time_limit_against_wave_sum(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.n = 32;
    p.patch_m = 10.0;     /* holds the 7.9 m peak of a 3 m/s sea */
    p.cascades = 2;
    p.cascade_ratio = 10.0; /* cascade 1: a 1 m patch, waves of 4.5 cm .. 12.5 cm:
                               w up to 36.7 rad/s, the one tested */
    p.sea.wind_u10 = 3.0;
    p.sea.choppiness = 0.0;
    ocean *o = make(&p);
    ocean_frame *f = frame(o);
    int n = p.n, m = n - 1;
    const int cas = 1;
    double dk = 2.0 * M_PI / (p.patch_m / p.cascade_ratio);
    long double (*ab)[4] = calloc((size_t)m * m, sizeof *ab);
    double *w = calloc((size_t)m * m, sizeof *w);
    assert_non_null(ab);
    assert_non_null(w);
    double w_top = 0.0;
    for (int mz = -n / 2 + 1; mz < n / 2; mz++)
        for (int mx = -n / 2 + 1; mx < n / 2; mx++) {
            size_t i = (size_t)(mz + n / 2 - 1) * m + (size_t)(mx + n / 2 - 1);
            double k = hypot(mx * dk, mz * dk);
            w[i] = ocean_dispersion(k, p.sea.depth_m);
            if (w[i] == 0.0)
                continue;
            double h0[2], h1[2];
            ocean_mode_amplitude(o, cas, mx, mz, 0.0, h0);
            ocean_mode_amplitude(o, cas, mx, mz, M_PI / (2.0 * w[i]), h1);
            if (h0[0] == 0.0 && h0[1] == 0.0 && h1[0] == 0.0 && h1[1] == 0.0) {
                w[i] = 0.0; /* outside this cascade's band */
                continue;
            }
            /* A = (h0 + i h1) / 2, B = (h0 - i h1) / 2 */
            ab[i][0] = 0.5L * ((long double)h0[0] - h1[1]);
            ab[i][1] = 0.5L * ((long double)h0[1] + h1[0]);
            ab[i][2] = 0.5L * ((long double)h0[0] + h1[1]);
            ab[i][3] = 0.5L * ((long double)h0[1] - h1[0]);
            w_top = fmax(w_top, w[i]);
        }
    assert_true(w_top > 30.0);
    ocean_spectrum_stats ss;
    ocean_get_spectrum_stats(o, &ss);
    double times[] = {0.0, 1e8 + 0.37, OCEAN_TIME_MAX, -OCEAN_TIME_MAX,
                      nextafter(OCEAN_TIME_MAX, 0.0)};
    for (size_t it = 0; it < 5; it++) {
        double t = times[it];
        eval(o, f, t, OCEAN_FX_HEIGHT);
        const ocean_field *fd = ocean_frame_field(f, cas);
        assert_int_equal(fd->n, n);
        long double (*h)[2] = calloc((size_t)m * m, sizeof *h);
        assert_non_null(h);
        for (size_t i = 0; i < (size_t)m * m; i++) {
            if (w[i] == 0.0)
                continue;
            long double ph = (long double)phase_q(w[i], t), c = cosl(ph), sn = sinl(ph);
            /* A e^{-i ph} + B e^{+i ph} */
            h[i][0] = ab[i][0] * c + ab[i][1] * sn + ab[i][2] * c - ab[i][3] * sn;
            h[i][1] = ab[i][1] * c - ab[i][0] * sn + ab[i][3] * c + ab[i][2] * sn;
        }
        double se = 0.0, worst = 0.0;
        for (int row = 0; row < n; row += 3)
            for (int col = 0; col < n; col += 5) {
                long double eta = 0.0L;
                for (int mz = -n / 2 + 1; mz < n / 2; mz++)
                    for (int mx = -n / 2 + 1; mx < n / 2; mx++) {
                        size_t i = (size_t)(mz + n / 2 - 1) * m + (size_t)(mx + n / 2 - 1);
                        if (w[i] == 0.0)
                            continue;
                        /* k.x on the grid: 2 pi (mx col + mz row) / n, reduced in integers */
                        int q = ((mx * col + mz * row) % n + n) % n;
                        long double ex = 2.0L * 3.14159265358979323846264338327950288L * q / n;
                        eta += h[i][0] * cosl(ex) - h[i][1] * sinl(ex);
                    }
                double d = fd->height[(size_t)row * n + col] - (double)eta;
                se += d * d;
                worst = fmax(worst, fabs(d));
            }
        free(h);
        double rms = sqrt(se / (11.0 * 7.0));
        double hs1 = 4.0 * sqrt(ss.cascade_variance[cas]);
        print_message("t = %.17g: field vs wave sum RMS %.3g m, worst %.3g m (cascade Hs %.3g m)\n",
                      t, rms, worst, hs1);
        /* float fields: a few float ulps of the largest wave */
        if (!(worst < 2e-6 * hs1))
            fail_msg("t = %.17g: worst height error %.3g m vs cascade Hs %.3g m", t, worst, hs1);
    }
    free(ab);
    free(w);
    ocean_frame_destroy(f);
    ocean_destroy(o);
}

/* Huge t: the float field against the double reference. */
static void test_huge_time_against_reference(void **state)
{
    (void)state;
    ocean_params p;
    pm_params(&p, 64);
    p.patch_m = 500.0;
    p.sea.choppiness = 1.0;
    ocean *o = make(&p);
    ocean_frame *f = frame(o);
    ocean_spectrum_stats ss;
    ocean_get_spectrum_stats(o, &ss);
    double times[] = {0.0, 1e6, OCEAN_TIME_MAX, -OCEAN_TIME_MAX};
    for (size_t i = 0; i < 4; i++) {
        eval(o, f, times[i], OCEAN_FX_HEIGHT | OCEAN_FX_DISPLACEMENT);
        double se = 0.0;
        int cnt = 0;
        for (int q = 0; q < 40; q++) {
            /* Grid points, so bilinear interpolation adds nothing. */
            double x = (q * 7 % 64) * p.patch_m / 64, z = (q * 13 % 64) * p.patch_m / 64;
            ocean_point a, b;
            ocean_frame_sample(f, x, z, &a);
            ocean_reference_point(o, times[i], x, z, INFINITY, 6, &b);
            se += (a.height - b.height) * (a.height - b.height) + (a.dx - b.dx) * (a.dx - b.dx);
            cnt += 2;
        }
        double rms = sqrt(se / cnt);
        if (!(rms < 1e-3 * ss.hs))
            fail_msg("t = %g: RMS error %.3g m vs Hs %.3g m", times[i], rms, ss.hs);
    }
    ocean_frame_destroy(f);
    ocean_destroy(o);
}

/* The reference for many points (ocean_reference_create/eval) is the
 * direct sum of ocean_reference_point with each wave drawn once: every
 * field agrees to double rounding, unfiltered and filtered, at a choppy
 * two-cascade sea, near the origin and 1e7 m out, at t = 0, 1e6 s and
 * OCEAN_TIME_MAX; bad arguments are refused. */
static void reference_context_is_the_direct_sum(void **state)
{
    (void)state;
    ocean_params p;
    pm_params(&p, 32);
    p.cascades = 2;
    p.patch_m = 300.0;
    p.sea.choppiness = 1.5;
    ocean *o = make(&p);
    const double times[] = {0.0, 1e6, OCEAN_TIME_MAX}, cuts[] = {INFINITY, 0.3};
    double worst = 0.0;
    for (int ti = 0; ti < 3; ti++)
        for (int ci = 0; ci < 2; ci++) {
            ocean_reference *r = NULL;
            assert_int_equal(ocean_reference_create(o, times[ti], cuts[ci], 6, &r), OCEAN_OK);
            assert_non_null(r);
            for (int q = 0; q < 12; q++) {
                double far = q % 2 ? 1e7 : 0.0;
                double x = far + 17.3 * q - 90.0, z = -far + 11.1 * q * q - 40.0;
                ocean_point a, b;
                ocean_reference_eval(r, x, z, &a);
                ocean_reference_point(o, times[ti], x, z, cuts[ci], 6, &b);
                const double av[] = {a.height, a.dx, a.dz, a.slope_x, a.slope_z, a.vel_x, a.vel_y,
                                     a.vel_z, a.dxx, a.dzz, a.dxz, a.jacobian, a.foam};
                const double bv[] = {b.height, b.dx, b.dz, b.slope_x, b.slope_z, b.vel_x, b.vel_y,
                                     b.vel_z, b.dxx, b.dzz, b.dxz, b.jacobian, b.foam};
                for (int k = 0; k < 13; k++) {
                    /* rounding of some 2000 terms (2e-15 measured) */
                    double d = fabs(av[k] - bv[k]);
                    if (!(d <= 1e-13))
                        fail_msg("t %g, cutoff %g, point (%g, %g), field %d: %.17g against %.17g",
                                 times[ti], cuts[ci], x, z, k, av[k], bv[k]);
                    worst = fmax(worst, d);
                }
            }
            ocean_reference_destroy(r);
        }
    print_message("reference context vs direct sum: worst difference %.3g\n", worst);
    ocean_reference *r = (ocean_reference *)&p; /* must be cleared on refusal */
    assert_int_equal(ocean_reference_create(NULL, 0.0, INFINITY, 6, &r), OCEAN_EINVAL);
    assert_null(r);
    assert_int_equal(ocean_reference_create(o, NAN, INFINITY, 6, &r), OCEAN_EINVAL);
    assert_int_equal(ocean_reference_create(o, 2.0 * OCEAN_TIME_MAX, INFINITY, 6, &r), OCEAN_EINVAL);
    assert_int_equal(ocean_reference_create(o, 0.0, NAN, 6, &r), OCEAN_EINVAL);
    assert_int_equal(ocean_reference_create(o, 0.0, -1.0, 6, &r), OCEAN_EINVAL);
    assert_int_equal(ocean_reference_create(o, 0.0, INFINITY, 0, &r), OCEAN_EINVAL);
    assert_int_equal(ocean_reference_create(o, 0.0, INFINITY, 6, NULL), OCEAN_EINVAL);
    ocean_reference_destroy(NULL);
    ocean_destroy(o);
}

/* The accurate reading's error bound holds wave by wave: one lattice wave
 * at a time (ocean_create_lattice, amplitude 1), every wave vector of a
 * 32-point grid inside its Nyquist circle, three phases, 60 points each:
 * |reading - the wave| <= the reported bound.  The bound took the
 * envelope from the node values alone and missed a wave near the Nyquist
 * rate, whose node values beat through 0 where the wave between them has
 * its full amplitude (3.7 times the bound at k h = 3.04 along an axis),
 * and the cross term of waves high in both components (1.4 times). */
static void accurate_bound_holds_wave_by_wave(void **state)
{
    (void)state;
    const int n = 32;
    const double L = 32.0, phases[] = {0.3, 1.1, 2.5};
    ocean_params p;
    ocean_params_default(&p);
    p.n = n;
    p.threads = 1;
    p.sea.choppiness = 0.0;
    double worst = 0.0;
    int waves = 0;
    for (int mx = 0; mx < n / 2; mx++)
        for (int mz = 0; mz <= mx; mz++) {
            if ((!mx && !mz) || hypot(mx, mz) > n / 2)
                continue;
            for (int ph = 0; ph < 3; ph++) {
                ocean_lattice_wave w = {mx, mz, 1.0, phases[ph]};
                ocean *o;
                char err[256];
                assert_int_equal(ocean_create_lattice(&p, L, &w, 1, &o, err, sizeof err), OCEAN_OK);
                ocean_frame *f = frame(o);
                ocean_request r;
                ocean_request_all(&r, OCEAN_FX_HEIGHT | OCEAN_FX_NORMALS);
                assert_int_equal(ocean_evaluate(o, 0.0, &r, f), OCEAN_OK);
                double kx = 2 * M_PI * mx / L, kz = 2 * M_PI * mz / L;
                uint64_t st = 99 + (uint64_t)(mx * 64 + mz);
                for (int q = 0; q < 60; q++) {
                    st = st * 6364136223846793005ULL + 1442695040888963407ULL;
                    double x = (double)(st >> 11) * 0x1p-53 * L;
                    st = st * 6364136223846793005ULL + 1442695040888963407ULL;
                    double z = (double)(st >> 11) * 0x1p-53 * L;
                    ocean_point pt, e;
                    ocean_frame_sample_accurate(f, x, z, OCEAN_SAMPLE_HEIGHT, &pt, &e);
                    double d = fabs(pt.height - cos(kx * x + kz * z + phases[ph]));
                    if (!(d <= e.height))
                        fail_msg("wave (%d, %d) (k h %.2f, %.2f), phase %g, at (%.3f, %.3f): error %.4g "
                                 "above its bound %.4g", mx, mz, kx * L / n, kz * L / n, phases[ph], x, z, d,
                                 e.height);
                    worst = fmax(worst, d / e.height);
                }
                ocean_frame_destroy(f);
                ocean_destroy(o);
                waves++;
            }
        }
    print_message("accurate bound, %d single waves: worst error / bound %.3f\n", waves, worst);
}

static void assert_frame_finite(const ocean_frame *f, int cascades, const char *what)
{
    for (int c = 0; c < cascades; c++) {
        const ocean_field *fd = ocean_frame_field(f, c);
        const float *ch[] = {fd->height, fd->dx, fd->dz, fd->slope_x, fd->slope_z,
                             fd->jacobian, fd->foam, fd->vel_x, fd->vel_y, fd->vel_z};
        for (int k = 0; k < 10; k++) {
            if (!ch[k])
                continue;
            for (size_t i = 0; i < (size_t)fd->n * fd->n; i++)
                if (!isfinite(ch[k][i]) || fabsf(ch[k][i]) > 1e6f)
                    fail_msg("%s: cascade %d channel %d sample %zu = %g", what, c, k, i, ch[k][i]);
        }
    }
}

static void run_case(ocean_params *p, double t, const char *what)
{
    ocean *o = make(p);
    ocean_frame *f = frame(o);
    eval(o, f, t, OCEAN_FX_ALL | OCEAN_FX_VELOCITY);
    assert_frame_finite(f, p->cascades, what);
    ocean_spectrum_stats ss;
    ocean_get_spectrum_stats(o, &ss);
    if (!isfinite(ss.hs) || ss.hs < 0.0)
        fail_msg("%s: Hs %g", what, ss.hs);
    ocean_point pt;
    ocean_frame_sample(f, 1e7 + 0.25, -3e6, &pt);
    assert_true(isfinite(pt.height) && isfinite(pt.jacobian));
    ocean_frame_destroy(f);
    ocean_destroy(o);
}

static void test_hard_cases_finite(void **state)
{
    (void)state;
    ocean_params p;
    char what[128];
    double winds[] = {0.0, 0.1, 70.0};
    for (size_t i = 0; i < 3; i++) {
        ocean_params_default(&p);
        p.n = 64;
        p.sea.wind_u10 = winds[i];
        p.patch_m = 1e5; /* holds every spectrum's peak at 70 m/s (ocean_plan.h) */
        for (int sp = 0; sp < OCEAN_SPECTRUM_COUNT_; sp++) {
            p.sea.spectrum = (ocean_spectrum_kind)sp;
            snprintf(what, sizeof what, "wind %g %s", winds[i], ocean_spectrum_name(p.sea.spectrum));
            run_case(&p, 10.0, what);
        }
    }
    double depths[] = {0.05, 1.0, 11000.0};
    for (size_t i = 0; i < 3; i++) {
        ocean_params_default(&p);
        p.n = 64;
        p.sea.spectrum = OCEAN_SPECTRUM_TMA;
        p.sea.depth_m = depths[i];
        /* 10 m/s would break in 5 cm and 1 m of water (ocean_plan.h): the
         * hard case is the shallowest water with a sea that can exist */
        p.sea.wind_u10 = depths[i] < 10.0 ? 1.0 : 10.0;
        snprintf(what, sizeof what, "depth %g", depths[i]);
        run_case(&p, OCEAN_TIME_MAX, what);
    }
    double chops[] = {0.0, 5.0};
    for (size_t i = 0; i < 2; i++) {
        ocean_params_default(&p);
        p.n = 64;
        p.sea.choppiness = chops[i];
        p.sea.wind_u10 = 70.0;
        p.patch_m = 1e4;
        snprintf(what, sizeof what, "choppiness %g", chops[i]);
        run_case(&p, 3.0, what);
    }
    double patches[] = {1.0, 1e5};
    for (size_t i = 0; i < 2; i++) {
        ocean_params_default(&p);
        p.n = 64;
        p.patch_m = patches[i];
        p.cascades = patches[i] > 10 ? 4 : 1;
        if (patches[i] < 10)
            p.sea.wind_u10 = 1.0; /* a 0.9 m peak for the 1 m patch */
        snprintf(what, sizeof what, "patch %g", patches[i]);
        run_case(&p, 100.0, what);
    }
    double fetches[] = {1.0, 1e7};
    for (size_t i = 0; i < 2; i++) {
        ocean_params_default(&p);
        p.n = 32;
        p.sea.spectrum = OCEAN_SPECTRUM_JONSWAP;
        p.sea.fetch_m = fetches[i];
        snprintf(what, sizeof what, "fetch %g", fetches[i]);
        run_case(&p, 0.0, what);
    }
    for (int sd = 0; sd < OCEAN_SPREAD_COUNT_; sd++)
        for (int ext = 0; ext < 2; ext++) {
            ocean_params_default(&p);
            p.n = 32;
            p.sea.spreading = (ocean_spreading_kind)sd;
            /* swell narrows the cos-2s spreadings only (refused elsewhere) */
            int cos2s = sd == OCEAN_SPREAD_MITSUYASU || sd == OCEAN_SPREAD_HASSELMANN;
            p.sea.swell = ext && cos2s ? 10.0 : 0.0;
            p.sea.wind_u10 = ext ? 100.0 : 0.5;
            p.patch_m = ext ? 1e5 : 1000.0;
            snprintf(what, sizeof what, "spreading %s extreme %d", ocean_spreading_name(p.sea.spreading), ext);
            run_case(&p, 1.0, what);
        }
    int ns[] = {8, 16, 2048};
    for (size_t i = 0; i < 3; i++) {
        ocean_params_default(&p);
        p.n = ns[i];
        if (ns[i] == 2048 && sanitized())
            p.n = 1024; /* 11 channels at 2048 under ASan take minutes */
        snprintf(what, sizeof what, "n %d", p.n);
        run_case(&p, 1.0, what);
    }
}

/* DC and Nyquist: zero in every channel's spectrum, so the field has zero
 * mean and no checkerboard (alternating-sign) component. */
static void test_dc_and_nyquist(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.n = 32;
    p.patch_m = 40.0; /* Nyquist band carries energy here if not zeroed */
    p.sea.wind_u10 = 5.0; /* a 22 m peak: the patch holds it (ocean_plan.h) */
    ocean *o = make(&p);
    ocean_frame *f = frame(o);
    eval(o, f, 2.0, OCEAN_FX_ALL);
    const ocean_field *fd = ocean_frame_field(f, 0);
    const float *chs[] = {fd->height, fd->dx, fd->dz, fd->slope_x, fd->slope_z};
    for (int k = 0; k < 5; k++) {
        double mean = 0.0, nyq_x = 0.0, nyq_z = 0.0, mag = 0.0;
        for (int i = 0; i < p.n; i++)
            for (int j = 0; j < p.n; j++) {
                double v = chs[k][i * p.n + j];
                mean += v;
                nyq_x += (j % 2 ? -v : v);
                nyq_z += (i % 2 ? -v : v);
                mag += fabs(v);
            }
        assert_true(fabs(mean) < 1e-5 * mag);
        assert_true(fabs(nyq_x) < 1e-5 * mag);
        assert_true(fabs(nyq_z) < 1e-5 * mag);
    }
    double h[2];
    ocean_mode_amplitude(o, 0, 0, 0, 1.0, h);
    assert_true(h[0] == 0.0 && h[1] == 0.0);
    ocean_frame_destroy(f);
    ocean_destroy(o);
}

static void expect_refused(ocean_params *p, const char *field)
{
    char msg[256] = "";
    ocean *o = NULL;
    assert_int_equal(ocean_create(p, &o, msg, sizeof msg), OCEAN_EINVAL);
    assert_null(o);
    if (!strstr(msg, field))
        fail_msg("message '%s' does not name '%s'", msg, field);
}

static void test_invalid_parameters(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p); p.n = 100; expect_refused(&p, "n = 100");
    ocean_params_default(&p); p.n = 4096; expect_refused(&p, "n");
    ocean_params_default(&p); p.n = 0; expect_refused(&p, "n");
    ocean_params_default(&p); p.sea.wind_u10 = -1; expect_refused(&p, "wind");
    ocean_params_default(&p); p.sea.wind_u10 = NAN; expect_refused(&p, "wind");
    ocean_params_default(&p); p.sea.depth_m = 0; expect_refused(&p, "depth");
    ocean_params_default(&p); p.patch_m = 0; expect_refused(&p, "patch");
    ocean_params_default(&p); p.patch_m = INFINITY; expect_refused(&p, "patch");
    ocean_params_default(&p); p.cascades = 5; expect_refused(&p, "cascades");
    ocean_params_default(&p); p.sea.choppiness = -0.5; expect_refused(&p, "choppiness");
    ocean_params_default(&p); p.threads = 0; expect_refused(&p, "threads");
    ocean_params_default(&p); p.k_max = NAN; expect_refused(&p, "k_max");
    /* Waves faster than OCEAN_OMEGA_MAX would break the time limit's
     * phase bound: a 1 m patch at n = 128 holds a 5.6 mm wave (w = 105 rad/s). */
    ocean_params_default(&p); p.patch_m = 1.0; p.n = 128; p.sea.wind_u10 = 1.0;
    expect_refused(&p, "OCEAN_OMEGA_MAX");
    /* ... which k_max below w = 64 rad/s (k = 417.7 rad/m) makes fine. */
    p.k_max = 400.0;
    ocean_destroy(make(&p));
    /* Evaluation refuses non-finite time and nonsense requests. */
    ocean_params_default(&p);
    p.n = 16;
    ocean *o = make(&p);
    ocean_frame *f = frame(o);
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_HEIGHT);
    assert_int_equal(ocean_evaluate(o, NAN, &r, f), OCEAN_EINVAL);
    assert_int_equal(ocean_evaluate(o, INFINITY, &r, f), OCEAN_EINVAL);
    /* One time limit (ocean_time.h): the limit itself is served, the next
     * double and the t = 1e16 that once gave 3.3 km heights are refused. */
    assert_int_equal(ocean_evaluate(o, OCEAN_TIME_MAX, &r, f), OCEAN_OK);
    assert_int_equal(ocean_evaluate(o, -OCEAN_TIME_MAX, &r, f), OCEAN_OK);
    assert_int_equal(ocean_evaluate(o, nextafter(OCEAN_TIME_MAX, INFINITY), &r, f), OCEAN_EINVAL);
    assert_int_equal(ocean_evaluate(o, -nextafter(OCEAN_TIME_MAX, INFINITY), &r, f), OCEAN_EINVAL);
    assert_int_equal(ocean_evaluate(o, 1e16, &r, f), OCEAN_EINVAL);
    char tmsg[256] = "";
    assert_int_equal(ocean_time_check(1e16, "query.t", tmsg, sizeof tmsg), OCEAN_EINVAL);
    if (!strstr(tmsg, "query.t") || !strstr(tmsg, "134217728") || !strstr(tmsg, "OCEAN_TIME_MAX"))
        fail_msg("time refusal '%s' names neither field nor limit", tmsg);
    assert_int_equal(ocean_time_check(OCEAN_TIME_MAX, "t", NULL, 0), OCEAN_OK);
    r.cutoff_k = -1.0;
    assert_int_equal(ocean_evaluate(o, 0.0, &r, f), OCEAN_EINVAL);
    r.cutoff_k = NAN;
    assert_int_equal(ocean_evaluate(o, 0.0, &r, f), OCEAN_EINVAL);
    ocean_frame_destroy(f);
    ocean_destroy(o);
    ocean_destroy(NULL);
    ocean_frame_destroy(NULL);
}

/* Only the asked channels are transformed, and counters say so. */
static void test_effects_mask_counts_transforms(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.n = 64;
    p.cascades = 2;
    ocean *o = make(&p);
    ocean_frame *f = frame(o);
    struct { unsigned fx; int per_cascade; } cases[] = {
        {OCEAN_FX_HEIGHT, 1}, {OCEAN_FX_HEIGHT | OCEAN_FX_DISPLACEMENT, 3},
        {OCEAN_FX_HEIGHT | OCEAN_FX_DISPLACEMENT | OCEAN_FX_NORMALS, 5},
        {OCEAN_FX_ALL, 9}, {OCEAN_FX_NORMALS, 2}, {OCEAN_FX_FOAM, 4}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        ocean_counters before, after;
        ocean_get_counters(o, &before);
        eval(o, f, 1.0, cases[i].fx);
        ocean_get_counters(o, &after);
        ocean_frame_info info;
        ocean_frame_get_info(f, &info);
        assert_int_equal(info.transforms, 2 * cases[i].per_cascade);
        assert_int_equal(after.transforms - before.transforms, 2 * cases[i].per_cascade);
        const ocean_field *fd = ocean_frame_field(f, 1);
        assert_true((fd->height != NULL) == !!(cases[i].fx & OCEAN_FX_HEIGHT));
        assert_true((fd->dx != NULL) == !!(cases[i].fx & OCEAN_FX_DISPLACEMENT));
        assert_true((fd->slope_x != NULL) == !!(cases[i].fx & OCEAN_FX_NORMALS));
        assert_true((fd->foam != NULL) == !!(cases[i].fx & OCEAN_FX_FOAM));
    }
    /* One cascade only. */
    ocean_request r;
    ocean_request_all(&r, 0);
    r.effects[1] = OCEAN_FX_HEIGHT;
    assert_int_equal(ocean_evaluate(o, 0.0, &r, f), OCEAN_OK);
    ocean_frame_info info;
    ocean_frame_get_info(f, &info);
    assert_int_equal(info.transforms, 1);
    assert_int_equal(ocean_frame_field(f, 0)->effects, 0);
    ocean_counters c;
    ocean_get_counters(o, &c);
    /* Height ran in cases 0-3 on both cascades, then once more. */
    assert_int_equal(c.transforms_by_effect[0], 4 * 2 + 1);
    assert_int_equal(c.transforms_by_effect[3], 2 * 2 * 4); /* foam: cases 3 and 5 */
    ocean_frame_destroy(f);
    ocean_destroy(o);
}

/* Cascades split the spectrum: bands are disjoint and contiguous, and the
 * summed variance matches one fine grid over the same band. */
static void test_cascade_partition(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.n = 128;
    p.cascades = 3;
    ocean *o = make(&p);
    double prev_hi = 0.0;
    for (int c = 0; c < 3; c++) {
        double L, lo, hi;
        ocean_cascade_band(o, c, &L, &lo, &hi);
        assert_true(lo == prev_hi);
        assert_true(hi > lo);
        prev_hi = hi;
    }
    assert_true(isinf(prev_hi));
    ocean_spectrum_stats ss;
    ocean_get_spectrum_stats(o, &ss);
    /* Three cascades of 128 reach much further than one, with nothing
     * counted twice: their variance is that of the analytic spectrum up
     * to the finest Nyquist, within quadrature. */
    double an = ocean_spectrum_hs(&p.sea);
    if (fabs(ss.hs - an) > 0.03 * an)
        fail_msg("3 cascades Hs %.4f vs analytic %.4f", ss.hs, an);
    ocean_frame *f = frame(o);
    eval(o, f, 3.0, OCEAN_FX_HEIGHT | OCEAN_FX_FOAM);
    ocean_field_stats fs;
    ocean_frame_get_field_stats(f, &fs);
    assert_true(fs.hs > 0.8 * ss.hs && fs.hs < 1.2 * ss.hs);
    ocean_destroy(o);
    ocean_frame_destroy(f);
}

/* A low cutoff transforms a smaller grid, E_error grows as the cutoff
 * falls, cutoff 0 leaves nothing, redistribution keeps the variance, and
 * the per-tick cache gives the same bytes as a fresh evaluation. */
static void test_cutoff_evaluation(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.n = 256;
    p.patch_m = 1000.0;
    ocean *o = make(&p), *fresh = make(&p);
    ocean_frame *f = frame(o), *g = frame(fresh);
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_HEIGHT | OCEAN_FX_NORMALS);
    double cutoffs[] = {INFINITY, 1.0, 0.3, 0.1, 0.03, 0.0};
    double prev_e = -1.0;
    int prev_n = 1 << 20;
    for (size_t i = 0; i < 6; i++) {
        r.cutoff_k = cutoffs[i];
        assert_int_equal(ocean_evaluate(o, 9.0, &r, f), OCEAN_OK);
        ocean_frame_info info;
        ocean_frame_get_info(f, &info);
        const ocean_field *fd = ocean_frame_field(f, 0);
        assert_true(info.e_error >= prev_e);
        assert_true(fd->n <= prev_n);
        prev_e = info.e_error;
        prev_n = fd->n;
        /* The cache (filled by the higher cutoffs of this tick) changes nothing. */
        assert_int_equal(ocean_evaluate(fresh, 9.0, &r, g), OCEAN_OK);
        assert_true(fields_equal(f, g, 1));
        assert_frame_finite(f, 1, "cutoff");
    }
    assert_true(prev_e == 1.0);
    assert_int_equal(prev_n, OCEAN_MIN_N);
    ocean_frame_info info;
    ocean_frame_get_info(f, &info);
    assert_int_equal(info.transforms, 0);
    /* A cutoff far above the band filters nothing: the evaluation is the
     * unfiltered one, byte for byte, and says so. */
    assert_true(isinf(ocean_effective_cutoff(o, 1e3, 6)));
    assert_true(ocean_effective_cutoff(o, 0.5, 6) == 0.5);
    assert_true(isnan(ocean_effective_cutoff(o, -1.0, 6)));
    r.cutoff_k = 1e3;
    ocean_evaluate(o, 9.0, &r, f);
    r.cutoff_k = INFINITY;
    ocean_evaluate(fresh, 9.0, &r, g);
    assert_true(fields_equal(f, g, 1));
    {
        ocean_frame_info fi;
        ocean_frame_get_info(f, &fi);
        assert_true(isinf(fi.cutoff_k) && fi.e_error == 0.0);
    }
    /* kc = 0.03 rad/m keeps only long waves: an 8x smaller transform serves. */
    r.cutoff_k = 0.03;
    ocean_evaluate(o, 9.0, &r, f);
    assert_true(ocean_frame_field(f, 0)->n <= p.n / 4);
    /* Redistribution restores the unfiltered variance in expectation. */
    ocean_spectrum_stats ss;
    ocean_get_spectrum_stats(o, &ss);
    double kept = ocean_filtered_variance(o, 0.1, 6);
    assert_true(kept < ss.variance && kept > 0.0);
    r.cutoff_k = 0.1;
    r.redistribute = 1;
    ocean_request_all(&r, OCEAN_FX_HEIGHT);
    r.cutoff_k = 0.1;
    r.redistribute = 1;
    double var = 0.0;
    int samples = 0;
    for (int k = 0; k < 20; k++) {
        ocean_evaluate(o, 50.0 * k, &r, f);
        ocean_field_stats fs;
        ocean_frame_get_field_stats(f, &fs);
        var += fs.hs * fs.hs / 16.0;
        samples++;
    }
    var /= samples;
    if (fabs(var - ss.variance) > 0.15 * ss.variance)
        fail_msg("redistributed variance %.4f vs unfiltered %.4f (filtered %.4f)", var, ss.variance, kept);
    ocean_frame_destroy(f);
    ocean_frame_destroy(g);
    ocean_destroy(o);
    ocean_destroy(fresh);
}

/* ocean.drop_gain: a larger drop gain runs a low cutoff on a smaller
 * grid and reports the waves it left out in E_error. */
static void test_drop_gain(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.n = 256;
    int n_at[2];
    double e_at[2];
    const double drops[2] = {1.0 / 64.0, 0.5};
    for (int d = 0; d < 2; d++) {
        p.drop_gain = drops[d];
        ocean *o = make(&p);
        ocean_frame *f = frame(o);
        ocean_request r;
        ocean_request_all(&r, OCEAN_FX_HEIGHT | OCEAN_FX_NORMALS);
        r.cutoff_k = 0.08; /* Nyquist 0.80 rad/m */
        assert_int_equal(ocean_evaluate(o, 3.0, &r, f), OCEAN_OK);
        ocean_frame_info info;
        ocean_frame_get_info(f, &info);
        n_at[d] = ocean_frame_field(f, 0)->n;
        e_at[d] = info.e_error;
        assert_frame_finite(f, 1, "drop gain");
        ocean_frame_destroy(f);
        ocean_destroy(o);
    }
    /* 1/64 keeps the tail to 2 kc = 0.16 rad/m: a 64 grid (it holds
     * 31 dk = 0.195); 1/2 keeps 1.1 kc = 0.088 rad/m: a 32 grid (15 dk =
     * 0.094). */
    assert_int_equal(n_at[0], 64);
    assert_int_equal(n_at[1], 32);
    /* The dropped band [1.1 kc, 2 kc] holds the spectral peak here (k_p
     * = 0.075 rad/m), so it costs visibly, but it is reported. */
    if (!(e_at[1] > e_at[0] && e_at[1] - e_at[0] < 0.1))
        fail_msg("E_error %.5f (drop 1/64) vs %.5f (drop 1/2)", e_at[0], e_at[1]);
    ocean_params_default(&p); p.drop_gain = 0.0; expect_refused(&p, "drop_gain");
    ocean_params_default(&p); p.drop_gain = 0.8; expect_refused(&p, "drop_gain");
    ocean_params_default(&p); p.drop_gain = NAN; expect_refused(&p, "drop_gain");
}

/* Without foam_map the evaluation skips the J/foam planes, and a point
 * sample still gives the map's J at every grid node. */
static void test_foam_map_on_request(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.n = 64;
    p.sea.choppiness = 2.5;
    ocean *o = make(&p);
    ocean_frame *with = frame(o), *without = frame(o);
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_ALL);
    assert_int_equal(r.foam_map, 1);
    assert_int_equal(ocean_evaluate(o, 7.0, &r, with), OCEAN_OK);
    r.foam_map = 0;
    assert_int_equal(ocean_evaluate(o, 7.0, &r, without), OCEAN_OK);
    const ocean_field *a = ocean_frame_field(with, 0), *b = ocean_frame_field(without, 0);
    assert_non_null(a->jacobian);
    assert_non_null(a->foam);
    assert_null(b->jacobian);
    assert_null(b->foam);
    assert_non_null(b->dxx);
    double h = a->patch_m / a->n, jmin = 1.0;
    for (int i = 0; i < a->n; i += 3)
        for (int j = 0; j < a->n; j += 5) {
            ocean_point pt;
            ocean_frame_sample(without, j * h, i * h, &pt);
            float want = a->jacobian[(size_t)i * a->n + j];
            if (fabs(pt.jacobian - want) > 1e-5 * (1.0 + fabs(want)))
                fail_msg("J at (%d, %d): sample %.7f, map %.7f", i, j, pt.jacobian, (double)want);
            jmin = fmin(jmin, want);
        }
    assert_true(jmin < 1.0); /* the choppy sea has compression to compare */
    ocean_field_stats sa, sb;
    ocean_frame_get_field_stats(with, &sa);
    ocean_frame_get_field_stats(without, &sb);
    assert_true(fabs(sa.min_jacobian - sb.min_jacobian) < 1e-5);
    ocean_frame_destroy(with);
    ocean_frame_destroy(without);
    ocean_destroy(o);
}

/* ocean_frame_sample_some fills exactly the groups asked, each equal to
 * the full sample bit for bit, and leaves the rest as "not evaluated". */
static void test_sample_some_matches_full(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.n = 64;
    p.cascades = 2;
    ocean *o = make(&p);
    ocean_frame *f = frame(o);
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_ALL | OCEAN_FX_VELOCITY);
    assert_int_equal(ocean_evaluate(o, 11.0, &r, f), OCEAN_OK);
    for (unsigned want = 0; want <= OCEAN_SAMPLE_ALL; want++)
        for (int k = 0; k < 25; k++) {
            double x = -3e4 + 2417.3 * k, z = 1e7 - 977.1 * k;
            ocean_point all, some;
            ocean_frame_sample(f, x, z, &all);
            ocean_frame_sample_some(f, x, z, want, &some);
#define SAME(field, bit, idle) \
    if ((want & (bit)) ? some.field != all.field : some.field != (idle)) \
        fail_msg("want 0x%x, " #field ": %.9g vs full %.9g", want, some.field, all.field)
            SAME(height, OCEAN_SAMPLE_HEIGHT, 0.0);
            SAME(dx, OCEAN_SAMPLE_DISPLACEMENT, 0.0);
            SAME(dz, OCEAN_SAMPLE_DISPLACEMENT, 0.0);
            SAME(slope_x, OCEAN_SAMPLE_SLOPE, 0.0);
            SAME(slope_z, OCEAN_SAMPLE_SLOPE, 0.0);
            SAME(dxx, OCEAN_SAMPLE_FOAM, 0.0);
            SAME(jacobian, OCEAN_SAMPLE_FOAM, 1.0);
            SAME(foam, OCEAN_SAMPLE_FOAM, 0.0);
            SAME(vel_y, OCEAN_SAMPLE_VELOCITY, 0.0);
            SAME(vel_x, OCEAN_SAMPLE_VELOCITY, 0.0);
#undef SAME
        }
    ocean_point pt;
    ocean_frame_sample(f, 5.0, 7.0, &pt);
    assert_true(pt.height != 0.0 && pt.vel_y != 0.0 && pt.dxx != 0.0); /* nothing trivially 0 */
    ocean_frame_destroy(f);
    ocean_destroy(o);
}

/* Each cutoff bucket's gains are computed once and kept: after more
 * buckets than are kept, in any order, every evaluation still equals a
 * fresh ocean's, byte for byte. */
static void test_gain_planes_reused_exactly(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.n = 64;
    p.cascades = 2;
    ocean *o = make(&p);
    ocean_frame *f = frame(o);
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_ALL);
    enum { K = 20 };
    for (int pass = 0; pass < 3; pass++)
        for (int i = 0; i < K; i++) {
            int j = pass == 1 ? K - 1 - i : (i * 7) % K;
            r.cutoff_k = 0.02 * pow(1.25, j);
            r.redistribute = j % 3 == 0;
            r.low_boost = j % 4 == 0 ? 1.03 : 1.0;
            double t = 5.0 + pass + 0.01 * i;
            assert_int_equal(ocean_evaluate(o, t, &r, f), OCEAN_OK);
            ocean *fresh = make(&p);
            ocean_frame *g = frame(fresh);
            assert_int_equal(ocean_evaluate(fresh, t, &r, g), OCEAN_OK);
            if (!fields_equal(f, g, 2))
                fail_msg("pass %d cutoff %.4f differs from a fresh ocean", pass, r.cutoff_k);
            ocean_frame_destroy(g);
            ocean_destroy(fresh);
        }
    ocean_frame_destroy(f);
    ocean_destroy(o);
}

/* The spectrum stage's code paths (ocean_internal.h: the plain row pass,
 * the AVX2+FMA and AVX-512 ones, streaming stores)
 * must give the same bits: replicas on different CPUs agree bit for bit
 * only if they do.  Every plane of every cascade, filtered and not, with
 * velocities, at small and large t. */
static void hash_frame(const ocean_frame *f, int cascades, uint64_t *h)
{
    for (int c = 0; c < cascades; c++) {
        const ocean_field *fd = ocean_frame_field(f, c);
        const float *planes[] = {fd->height, fd->dx, fd->dz, fd->slope_x, fd->slope_z,
                                 fd->dxx, fd->dzz, fd->dxz, fd->jacobian, fd->foam,
                                 fd->vel_x, fd->vel_y, fd->vel_z};
        for (size_t k = 0; k < sizeof planes / sizeof planes[0]; k++) {
            if (!planes[k])
                continue;
            const unsigned char *b = (const unsigned char *)planes[k];
            for (size_t i = 0; i < sizeof(float) * (size_t)fd->n * fd->n; i++) {
                *h ^= b[i];
                *h *= 1099511628211ull;
            }
        }
    }
}

/* 1 when the CPU runs row pass `level` of ocean_force_paths (1
 * AVX2+FMA, 2 AVX-512), so the bit-for-bit test says what it compared. */
static int cpu_fused(int level)
{
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
    int fma = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    int wide = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
               __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw");
    return level == 1 ? fma : fma && wide;
#else
    (void)level;
    return 0;
#endif
}

static void test_stage_paths_same_bits(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.n = 128;
    p.cascades = 2;
    p.threads = 2;
    ocean *o = NULL;
    ocean_frame *f = NULL;
    char msg[256];
    assert_int_equal(ocean_create(&p, &o, msg, sizeof msg), OCEAN_OK);
    assert_int_equal(ocean_frame_create(o, &f), OCEAN_OK);
    const double ts[] = {0.0, 1234.5678, 3.0e6 + 0.1};
    const double kcs[] = {INFINITY, 0.4};
    uint64_t ref = 0;
    /* fused 0 plain, 1 AVX2+FMA, 2 AVX-512 (each falls back where the CPU
     * lacks it: print which ones really ran), each without and with
     * streaming stores. */
    for (int path = 0; path < 6; path++) {
        int fused = path % 3, stream = path / 3;
        int ran = ocean_force_paths(o, fused, stream);
        /* The pass asked for runs wherever the CPU has it. */
        assert_int_equal(ran, cpu_fused(2) ? fused : cpu_fused(1) && fused ? 1 : 0);
        uint64_t h = 1469598103934665603ull;
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 2; b++) {
                ocean_request r;
                ocean_request_all(&r, OCEAN_FX_ALL | OCEAN_FX_VELOCITY);
                r.cutoff_k = kcs[b];
                assert_int_equal(ocean_evaluate(o, ts[a], &r, f), OCEAN_OK);
                hash_frame(f, p.cascades, &h);
            }
        print_message("stage path asked %d, ran %d, stream=%d: %016llx\n", fused, ran, stream,
                      (unsigned long long)h);
        if (path == 0)
            ref = h;
        else
            assert_true(h == ref);
    }
    ocean_frame_destroy(f);
    ocean_destroy(o);
    /* The widest pass (AVX-512 where the CPU has it), streaming, against
     * the direct sum of the modes
     * (ocean_reference_point, double, amplitudes drawn afresh): rows mz
     * and -mz share one phase there, and every channel must still be the
     * waves'.  Grid points, so reading adds nothing. */
    pm_params(&p, 64);
    p.patch_m = 500.0;
    p.sea.choppiness = 1.0;
    o = make(&p);
    f = frame(o);
    ocean_force_paths(o, 2, 1);
    ocean_spectrum_stats ss;
    ocean_get_spectrum_stats(o, &ss);
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_ALL | OCEAN_FX_VELOCITY);
    const double t = 1234.5678;
    assert_int_equal(ocean_evaluate(o, t, &r, f), OCEAN_OK);
    double se_h = 0.0, se_s = 0.0, se_v = 0.0, ss_v = 0.0;
    for (int q = 0; q < 48; q++) {
        double x = (q * 7 % 64) * p.patch_m / 64, z = (q * 13 % 64) * p.patch_m / 64;
        ocean_point a, b;
        ocean_frame_sample(f, x, z, &a);
        ocean_reference_point(o, t, x, z, INFINITY, 6, &b);
        se_h += (a.height - b.height) * (a.height - b.height) + (a.dx - b.dx) * (a.dx - b.dx) +
                (a.dz - b.dz) * (a.dz - b.dz);
        se_s += (a.slope_x - b.slope_x) * (a.slope_x - b.slope_x) +
                (a.slope_z - b.slope_z) * (a.slope_z - b.slope_z);
        se_v += (a.vel_y - b.vel_y) * (a.vel_y - b.vel_y);
        ss_v += b.vel_y * b.vel_y;
    }
    double rh = sqrt(se_h / 144), rs = sqrt(se_s / 96), rv = sqrt(se_v / ss_v);
    print_message("fused+stream pass vs direct sum: height/displacement RMS %.3g m (Hs %.3g m), "
                  "slope RMS %.3g, vertical velocity RMS %.3g relative\n", rh, ss.hs, rs, rv);
    assert_true(rh < 1e-4 * ss.hs);
    assert_true(rs < 1e-4);
    assert_true(rv < 1e-4);
    ocean_frame_destroy(f);
    ocean_destroy(o);
}

/* The spectrum stage evolves only the modes that hold a wave: a coarse
 * cascade stops at half its Nyquist (k_hi = pi n / (2 patch)), so most of
 * its grid is zero and must cost no inputs read and no trigonometry.
 * Counted against the band (ocean_cascade_band) and the amplitudes drawn
 * afresh (ocean_mode_amplitude), not against the stage's own ranges: at
 * least every mode with a wave, at most the modes of the band.  A second
 * request of the same tick reuses h(k,t) and evolves nothing. */
static void test_stage_evolves_only_waves(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.n = 128;
    p.cascades = 3;
    ocean *o = make(&p);
    ocean_frame *f = frame(o);
    int n = p.n, half = n / 2 + 1;
    long in_band = 0, with_wave = 0, all = 0;
    for (int c = 0; c < p.cascades; c++) {
        double patch, k_lo, k_hi;
        ocean_cascade_band(o, c, &patch, &k_lo, &k_hi);
        double dk = 2.0 * M_PI / patch;
        long band_c = 0;
        for (int iz = 0; iz < n; iz++)
            for (int ix = 0; ix < half; ix++) {
                int mz = iz < n / 2 ? iz : iz - n;
                all++;
                if (mz == -n / 2 || ix == n / 2)
                    continue;
                double k = hypot(ix * dk, mz * dk);
                if (!(k > 0.0 && k >= k_lo && k < k_hi))
                    continue;
                band_c++;
                double h[2];
                ocean_mode_amplitude(o, c, ix, mz, 0.0, h);
                with_wave += h[0] != 0.0 || h[1] != 0.0;
            }
        in_band += band_c;
        if (c < p.cascades - 1) /* a disc of radius n/4 on the half grid */
            assert_true(band_c < 0.45 * n * half);
    }
    ocean_counters c0, c1, c2;
    ocean_get_counters(o, &c0);
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_ALL);
    assert_int_equal(ocean_evaluate(o, 7.25, &r, f), OCEAN_OK);
    ocean_get_counters(o, &c1);
    long evolved = (long)(c1.modes_evolved - c0.modes_evolved);
    print_message("modes evolved %ld: %ld with a wave, %ld in the bands, %ld on the grids\n",
                  evolved, with_wave, in_band, all);
    assert_true(with_wave > 0);
    assert_true(evolved >= with_wave);
    assert_true(evolved <= in_band);
    assert_true(in_band < 0.7 * all);
    r.cutoff_k = 0.5;
    assert_int_equal(ocean_evaluate(o, 7.25, &r, f), OCEAN_OK);
    ocean_get_counters(o, &c2);
    assert_true(c2.modes_evolved == c1.modes_evolved);
    ocean_frame_destroy(f);
    ocean_destroy(o);
}

/* Deep water (k d >= 22, where tanh(k d) = 1 to 2^-62): the stage
 * computes w = sqrt(g k) from the mode's integer wave vector instead of
 * reading its frequency from memory; shallower modes read theirs.  A sea
 * 30 m deep holds both kinds.  The counter must see exactly the deep
 * modes the stage evolves (bounds from the band and from amplitudes drawn
 * afresh), and the fields must be bit for bit those of the table (every
 * frequency read), on the plain and the widest row pass, with velocity,
 * at an ordinary and at the largest time. */
static void test_deep_water_frequency_computed(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.n = 128;
    p.cascades = 3;
    p.sea.depth_m = 30.0;
    ocean *o = make(&p);
    ocean_frame *f = frame(o);
    int n = p.n, half = n / 2 + 1;
    long deep_wave = 0, deep_band = 0, shallow_wave = 0, shallow_band = 0;
    for (int c = 0; c < p.cascades; c++) {
        double patch, k_lo, k_hi;
        ocean_cascade_band(o, c, &patch, &k_lo, &k_hi);
        double dk = 2.0 * M_PI / patch;
        for (int iz = 0; iz < n; iz++)
            for (int ix = 0; ix < half; ix++) {
                int mz = iz < n / 2 ? iz : iz - n;
                if (mz == -n / 2 || ix == n / 2)
                    continue;
                double k = hypot(ix * dk, mz * dk);
                if (!(k > 0.0 && k >= k_lo && k < k_hi))
                    continue;
                int deep = k * p.sea.depth_m >= 22.0;
                double h[2];
                ocean_mode_amplitude(o, c, ix, mz, 0.0, h);
                int wave = h[0] != 0.0 || h[1] != 0.0;
                deep_band += deep;
                shallow_band += !deep;
                deep_wave += deep && wave;
                shallow_wave += !deep && wave;
            }
    }
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_ALL | OCEAN_FX_VELOCITY);
    ocean_counters c0, c1;
    ocean_get_counters(o, &c0);
    assert_int_equal(ocean_evaluate(o, 7.25, &r, f), OCEAN_OK);
    ocean_get_counters(o, &c1);
    long deep = (long)(c1.modes_deep - c0.modes_deep);
    long evolved = (long)(c1.modes_evolved - c0.modes_evolved);
    print_message("30 m deep: %ld of %ld modes evolved computed their w (%ld deep with a wave, "
                  "%ld deep in the bands, %ld shallow with a wave, %ld in the bands)\n",
                  deep, evolved, deep_wave, deep_band, shallow_wave, shallow_band);
    assert_true(deep_wave > 0 && shallow_wave > 0);
    assert_true(deep >= deep_wave && deep <= deep_band);
    /* (A few shallow modes of this TMA sea are under float's range, so
     * they hold no wave in the stage: no lower bound from them.) */
    assert_true(evolved - deep > 0 && evolved - deep <= shallow_band);
    const double ts[] = {1234.5678, OCEAN_TIME_MAX - 0.5};
    uint64_t ref = 0;
    for (int v = 0; v < 4; v++) {
        int table = v & 1, fused = v & 2 ? 2 : 0;
        ocean_force_paths(o, fused, -1);
        ocean_force_frequency_table(o, table);
        uint64_t h = 1469598103934665603ull;
        ocean_get_counters(o, &c0);
        for (int a = 0; a < 2; a++) {
            assert_int_equal(ocean_evaluate(o, ts[a], &r, f), OCEAN_OK);
            hash_frame(f, p.cascades, &h);
        }
        ocean_get_counters(o, &c1);
        /* The table path reads every frequency. */
        assert_true(table ? c1.modes_deep == c0.modes_deep : c1.modes_deep > c0.modes_deep);
        print_message("row pass %d, %s: %016llx\n", fused, table ? "table" : "computed",
                      (unsigned long long)h);
        if (v == 0)
            ref = h;
        else
            assert_true(h == ref);
    }
    /* Shallow everywhere (k d < 22 for every wave of a 3 m sea of this
     * band, |k| < 0.41 rad/m): nothing is computed. */
    ocean_frame_destroy(f);
    ocean_destroy(o);
    pm_params(&p, 64);
    p.patch_m = 500.0;
    p.sea.depth_m = 3.0;
    o = make(&p);
    f = frame(o);
    ocean_get_counters(o, &c0);
    assert_int_equal(ocean_evaluate(o, 7.25, &r, f), OCEAN_OK);
    ocean_get_counters(o, &c1);
    assert_true(c1.modes_evolved > c0.modes_evolved);
    assert_true(c1.modes_deep == c0.modes_deep);
    ocean_frame_destroy(f);
    ocean_destroy(o);
}

/* ocean_counters' time split: the pass that evolves h(k,t) is timed as
 * ns_evolve, the passes that read it back from the tick's cache as
 * ns_channels, FFTW as ns_fft; all three lie inside ocean_evaluate's own
 * wall time.  bench_core prints them beside its floor table ("Where each
 * evaluation of that table went"). */
static void test_time_split_counters(void **state)
{
    (void)state;
    ocean_params p;
    pm_params(&p, 64);
    p.patch_m = 500.0;
    ocean *o = make(&p);
    ocean_frame *f = frame(o);
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_ALL);
    ocean_counters c0, c1;
    struct timespec w0, w1;
    /* 9 channels two a call: one evolving pass, four reading back. */
    ocean_force_group(o, 2);
    ocean_get_counters(o, &c0);
    clock_gettime(CLOCK_MONOTONIC, &w0);
    assert_int_equal(ocean_evaluate(o, 3.5, &r, f), OCEAN_OK);
    clock_gettime(CLOCK_MONOTONIC, &w1);
    ocean_get_counters(o, &c1);
    uint64_t wall = (uint64_t)(w1.tv_sec - w0.tv_sec) * 1000000000u + (uint64_t)w1.tv_nsec -
                    (uint64_t)w0.tv_nsec;
    uint64_t ev = c1.ns_evolve - c0.ns_evolve, chn = c1.ns_channels - c0.ns_channels,
             fft = c1.ns_fft - c0.ns_fft;
    print_message("N = 64, 4 calls: evolve %llu ns, channels %llu ns, FFTW %llu ns, wall %llu ns\n",
                  (unsigned long long)ev, (unsigned long long)chn, (unsigned long long)fft,
                  (unsigned long long)wall);
    assert_int_equal(c1.fft_calls - c0.fft_calls, 5);
    assert_true(ev > 0 && chn > 0 && fft > 0);
    assert_true(ev + chn + fft <= wall);
    /* The same tick again: h(k,t) is cached, so nothing evolves. */
    ocean_get_counters(o, &c0);
    assert_int_equal(ocean_evaluate(o, 3.5, &r, f), OCEAN_OK);
    ocean_get_counters(o, &c1);
    assert_true(c1.ns_evolve == c0.ns_evolve);
    assert_true(c1.ns_channels > c0.ns_channels && c1.ns_fft > c0.ns_fft);
    /* A new tick in one call: only the evolving pass. */
    ocean_force_group(o, 9);
    ocean_get_counters(o, &c0);
    assert_int_equal(ocean_evaluate(o, 4.5, &r, f), OCEAN_OK);
    ocean_get_counters(o, &c1);
    assert_true(c1.ns_evolve > c0.ns_evolve && c1.ns_fft > c0.ns_fft);
    assert_true(c1.ns_channels == c0.ns_channels);
    ocean_frame_destroy(f);
    ocean_destroy(o);
}

/* One run of test_stage_split_same_bits under split `mode`: every frame
 * hashed into *h; FFTW calls and those split by channel counted. */
static void split_run(ocean *o, ocean_frame *f, int cascades, int mode, double t_off, uint64_t *h,
                      uint64_t *calls, uint64_t *by_ch)
{
    const double ts[] = {1234.5678, 3.0e6 + 0.1};
    const double kcs[] = {INFINITY, 0.4};
    ocean_force_stage_split(o, mode);
    ocean_counters c0, c1;
    ocean_get_counters(o, &c0);
    *h = 1469598103934665603ull;
    for (int g = 0; g < 2; g++) {
        ocean_force_group(o, g ? 2 : 0);
        for (int a = 0; a < 2; a++)
            for (int b = 0; b < 2; b++)
                /* A tick's first evaluation evolves h(k,t); the second
                 * reads it back. */
                for (int again = 0; again < 2; again++) {
                    ocean_request r;
                    /* 11 channels: in calls of 2 the last holds one */
                    ocean_request_all(&r, (OCEAN_FX_ALL | OCEAN_FX_VELOCITY) & ~(unsigned)OCEAN_FX_HEIGHT);
                    r.cutoff_k = kcs[b];
                    assert_int_equal(ocean_evaluate(o, ts[a] + t_off + 10.0 * g, &r, f), OCEAN_OK);
                    hash_frame(f, cascades, h);
                }
    }
    ocean_get_counters(o, &c1);
    *calls = c1.fft_calls - c0.fft_calls;
    *by_ch = c1.fft_calls_by_channel - c0.fft_calls_by_channel;
}

/* The stage splits a call's pass over the threads by rows or by channel
 * (each thread the channels FFTW's threaded plan transforms on it), and by
 * default runs whichever it has measured faster.  Every split must give
 * the same bits: with a filter (the gain plane one thread fills and the
 * other reads) and without, in one call and in calls of 2 (whose last
 * holds one channel: rows), evolving h(k,t) and reading it back.  And the
 * measuring mode must really run both. */
static void test_stage_split_same_bits(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.n = 128;
    p.cascades = 2;
    p.threads = 2;
    const int modes[] = {1, -1};
    for (int m = 0; m < 2; m++) {
        /* A fresh ocean each time: the measuring mode then runs rows on a
         * kind's first evaluation and channels on its second (split_pick),
         * whatever this machine measures, so both must show up. */
        ocean *o = make(&p);
        ocean_frame *f = frame(o);
        uint64_t h, rows, calls, by_ch, rcalls, rby_ch;
        /* Fresh ticks for each run, the same for the mode and for rows. */
        split_run(o, f, p.cascades, modes[m], 100.0 * m, &h, &calls, &by_ch);
        split_run(o, f, p.cascades, 0, 100.0 * m, &rows, &rcalls, &rby_ch);
        print_message("split mode %d: %016llx, %llu of %llu FFTW calls by channel; rows %016llx\n",
                      modes[m], (unsigned long long)h, (unsigned long long)by_ch,
                      (unsigned long long)calls, (unsigned long long)rows);
        assert_true(h == rows);
        assert_true(rcalls == calls && rby_ch == 0);
        assert_true(by_ch > 0 && by_ch < calls);
        ocean_frame_destroy(f);
        ocean_destroy(o);
    }
}

/* Every channel of two fields of the same grid agrees to `tol` relative
 * RMS (a channel zero in b must be zero in a: a cascade wholly above the
 * cutoff); fails naming the channel. */
static void assert_fields_close(const ocean_field *fa, const ocean_field *fb, double tol, const char *what)
{
    assert_int_equal(fa->n, fb->n);
    const float *pa[] = {fa->height, fa->dx, fa->dz, fa->slope_x, fa->slope_z, fa->dxx, fa->dzz,
                         fa->dxz, fa->vel_x, fa->vel_y, fa->vel_z};
    const float *pb[] = {fb->height, fb->dx, fb->dz, fb->slope_x, fb->slope_z, fb->dxx, fb->dzz,
                         fb->dxz, fb->vel_x, fb->vel_y, fb->vel_z};
    for (int k = 0; k < 11; k++) {
        double d2 = 0.0, s2 = 0.0;
        for (size_t i = 0; i < (size_t)fa->n * fa->n; i++) {
            d2 += ((double)pa[k][i] - pb[k][i]) * ((double)pa[k][i] - pb[k][i]);
            s2 += (double)pb[k][i] * pb[k][i];
        }
        if (s2 == 0.0 ? d2 != 0.0 : sqrt(d2 / s2) >= tol)
            fail_msg("%s: channel %d differs by %.3g relative RMS", what, k, s2 > 0.0 ? sqrt(d2 / s2) : d2);
    }
}

/* Channels go to FFTW in groups (at most 8.5 MB of spectra a call, so a
 * group's spectra are still cached when its transform reads them).  Every
 * group size must give every channel's waves: against the direct sum of the
 * modes (ocean_reference_point, double) unfiltered, and against the one-call
 * batch with a filter and velocity (the gain plane and h(k,t) that the first
 * group's row pass fills and the later groups reuse).  And the default rule
 * groups 8 channels at N = 1024 (4.2 MB each) two by two. */
static void test_grouped_transforms(void **state)
{
    (void)state;
    ocean_params p;
    pm_params(&p, 64);
    p.patch_m = 500.0;
    p.sea.choppiness = 1.0;
    ocean *o = make(&p);
    ocean_frame *f = frame(o), *ref = frame(o);
    ocean_spectrum_stats ss;
    ocean_get_spectrum_stats(o, &ss);
    const double t = 987.654;
    const int groups[] = {1, 2, 3, 5};
    for (size_t gi = 0; gi < sizeof groups / sizeof groups[0]; gi++) {
        ocean_force_group(o, groups[gi]);
        ocean_counters c0, c1;
        ocean_get_counters(o, &c0);
        ocean_request r;
        ocean_request_all(&r, OCEAN_FX_ALL | OCEAN_FX_VELOCITY);
        assert_int_equal(ocean_evaluate(o, t, &r, f), OCEAN_OK);
        ocean_get_counters(o, &c1);
        /* 12 channels: height, 2 displacement, 2 slopes, 4 for foam, 3 velocities */
        assert_int_equal(c1.transforms - c0.transforms, 12);
        assert_int_equal(c1.fft_calls - c0.fft_calls, (12 + groups[gi] - 1) / groups[gi]);
        double se_h = 0.0, se_s = 0.0, se_j = 0.0, se_v = 0.0, ss_v = 0.0;
        for (int q = 0; q < 48; q++) {
            double x = (q * 7 % 64) * p.patch_m / 64, z = (q * 13 % 64) * p.patch_m / 64;
            ocean_point a, b;
            ocean_frame_sample(f, x, z, &a);
            ocean_reference_point(o, t, x, z, INFINITY, 6, &b);
            se_h += (a.height - b.height) * (a.height - b.height) + (a.dx - b.dx) * (a.dx - b.dx) +
                    (a.dz - b.dz) * (a.dz - b.dz);
            se_s += (a.slope_x - b.slope_x) * (a.slope_x - b.slope_x) +
                    (a.slope_z - b.slope_z) * (a.slope_z - b.slope_z);
            se_j += (a.jacobian - b.jacobian) * (a.jacobian - b.jacobian);
            se_v += (a.vel_x - b.vel_x) * (a.vel_x - b.vel_x) + (a.vel_y - b.vel_y) * (a.vel_y - b.vel_y) +
                    (a.vel_z - b.vel_z) * (a.vel_z - b.vel_z);
            ss_v += b.vel_x * b.vel_x + b.vel_y * b.vel_y + b.vel_z * b.vel_z;
        }
        double rh = sqrt(se_h / 144), rs = sqrt(se_s / 96), rj = sqrt(se_j / 48), rv = sqrt(se_v / ss_v);
        print_message("%d channels a call vs direct sum: height/displacement RMS %.3g m (Hs %.3g m), "
                      "slope %.3g, Jacobian %.3g, velocity %.3g relative\n", groups[gi], rh, ss.hs, rs,
                      rj, rv);
        assert_true(rh < 1e-4 * ss.hs);
        assert_true(rs < 1e-4);
        assert_true(rj < 1e-4);
        assert_true(rv < 1e-4);
        /* Filtered: same waves as one batched call, to float rounding. */
        r.cutoff_k = 0.3;
        ocean_force_group(o, 0);
        assert_int_equal(ocean_evaluate(o, t + 1.0, &r, ref), OCEAN_OK);
        ocean_force_group(o, groups[gi]);
        assert_int_equal(ocean_evaluate(o, t + 1.0, &r, f), OCEAN_OK);
        assert_fields_close(ocean_frame_field(f, 0), ocean_frame_field(ref, 0), 1e-5, "grouped");
    }
    ocean_frame_destroy(ref);
    ocean_frame_destroy(f);
    ocean_destroy(o);
    /* The default rule at N = 1024: two channels a call. */
    pm_params(&p, 1024);
    o = make(&p);
    f = frame(o);
    ocean_counters c0, c1;
    ocean_get_counters(o, &c0);
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_ALL);
    assert_int_equal(ocean_evaluate(o, t, &r, f), OCEAN_OK);
    ocean_get_counters(o, &c1);
    assert_int_equal(c1.transforms - c0.transforms, 9);
    assert_int_equal(c1.fft_calls - c0.fft_calls, 5);
    ocean_frame_destroy(f);
    ocean_destroy(o);
}

/* A coarse cascade's waves fill columns [0, n/4) of its n x (n/2 + 1)
 * half spectrum, so its 2-D c2r leaves the column transforms of the other
 * columns out (ocean_fft.c, ocean_fft_run).  The pruned transform must be the
 * same transform: every channel of every cascade as the whole-grid 2-D
 * plan makes it, to float rounding, evolving h(k,t) and reading it back,
 * in one call and in calls of 2; and the direct sum of the modes
 * (ocean_reference_point) agrees.  Only the coarse cascades prune, only
 * on their full grid: the finest reaches its grid's Nyquist, and a
 * cutoff that picks a smaller grid fills that grid's columns. */
static void test_pruned_column_pass(void **state)
{
    (void)state;
    ocean_params p;
    pm_params(&p, 128);
    p.cascades = 3;
    p.threads = 2;
    p.patch_m = 1000.0;
    p.cascade_ratio = 4.0; /* cascade 0's grid points lie on every grid: exact samples */
    p.sea.choppiness = 1.0;
    ocean *o = make(&p);
    ocean_frame *f = frame(o), *ref = frame(o);
    const double t = 4321.125;
    const double cutoffs[] = {INFINITY, 0.25};
    for (int g = 0; g < 2; g++)
        for (int kc = 0; kc < 2; kc++) {
            ocean_force_group(o, g ? 2 : 0);
            ocean_request r;
            ocean_request_all(&r, OCEAN_FX_ALL | OCEAN_FX_VELOCITY);
            r.cutoff_k = cutoffs[kc];
            ocean_counters c0, c1, c2;
            ocean_force_pruning(o, 0);
            ocean_get_counters(o, &c0);
            assert_int_equal(ocean_evaluate(o, t + g, &r, ref), OCEAN_OK);
            ocean_force_pruning(o, 1);
            ocean_get_counters(o, &c1);
            assert_int_equal(ocean_evaluate(o, t + g, &r, f), OCEAN_OK);
            ocean_get_counters(o, &c2);
            uint64_t calls = c2.fft_calls - c1.fft_calls, pruned = c2.fft_calls_pruned - c1.fft_calls_pruned;
            int per_cascade = g ? 6 : 1; /* 11 channels: 6 calls of 2, or 1 of 11 */
            print_message("group %d, cutoff %g: %llu of %llu FFTW calls pruned\n", g ? 2 : 11,
                          cutoffs[kc], (unsigned long long)pruned, (unsigned long long)calls);
            assert_int_equal(c1.fft_calls_pruned - c0.fft_calls_pruned, 0);
            /* Coarse cascades on their full grid prune; the finest, and
             * the smaller grid a cutoff picks (its waves fill it), do not. */
            int full_coarse = 0, smaller = 0;
            for (int c = 0; c < 3; c++) {
                int nc = ocean_frame_field(f, c)->n;
                full_coarse += c < 2 && nc == p.n;
                smaller += nc < p.n;
            }
            assert_int_equal(pruned, (uint64_t)(full_coarse * per_cascade));
            assert_int_equal(full_coarse, kc == 0 ? 2 : 1);
            assert_int_equal(smaller, kc == 0 ? 0 : 2);
            for (int c = 0; c < 3; c++)
                assert_fields_close(ocean_frame_field(f, c), ocean_frame_field(ref, c), 1e-6,
                                    c == 0 ? "cascade 0" : c == 1 ? "cascade 1" : "cascade 2");
        }
    /* The pruned coarse cascades against the direct sum of their modes. */
    ocean_force_group(o, 0);
    ocean_counters c0, c1;
    ocean_get_counters(o, &c0);
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_ALL);
    assert_int_equal(ocean_evaluate(o, t, &r, f), OCEAN_OK);
    ocean_get_counters(o, &c1);
    assert_int_equal(c1.fft_calls_pruned - c0.fft_calls_pruned, 2);
    ocean_spectrum_stats ss;
    ocean_get_spectrum_stats(o, &ss);
    double se = 0.0;
    for (int q = 0; q < 40; q++) {
        double x = (q * 37 % 128) * 1000.0 / 128, z = (q * 53 % 128) * 1000.0 / 128;
        ocean_point a, b;
        ocean_frame_sample(f, x, z, &a);
        ocean_reference_point(o, t, x, z, INFINITY, 6, &b);
        se += (a.height - b.height) * (a.height - b.height) + (a.dx - b.dx) * (a.dx - b.dx) +
              (a.dz - b.dz) * (a.dz - b.dz);
    }
    print_message("pruned: height/displacement RMS %.3g m against the direct sum (Hs %.3g m)\n",
                  sqrt(se / 120), ss.hs);
    assert_true(sqrt(se / 120) < 1e-4 * ss.hs);
    ocean_frame_destroy(ref);
    ocean_frame_destroy(f);
    ocean_destroy(o);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hs_pierson_moskowitz),
        cmocka_unit_test(test_hs_jonswap),
        cmocka_unit_test(test_tma_lowers_hs),
        cmocka_unit_test(test_time_series_periods),
        cmocka_unit_test(test_hermitian_and_parseval),
        cmocka_unit_test(test_mean_jacobian_is_one),
        cmocka_unit_test(test_hs_independent_of_n),
        cmocka_unit_test(test_common_waves_across_n),
        cmocka_unit_test(test_determinism),
        cmocka_unit_test(test_phase_exact_to_time_limit),
        cmocka_unit_test(test_field_at_time_limit_against_wave_sum),
        cmocka_unit_test(test_huge_time_against_reference),
        cmocka_unit_test(test_hard_cases_finite),
        cmocka_unit_test(test_dc_and_nyquist),
        cmocka_unit_test(test_invalid_parameters),
        cmocka_unit_test(test_effects_mask_counts_transforms),
        cmocka_unit_test(test_cascade_partition),
        cmocka_unit_test(test_cutoff_evaluation),
        cmocka_unit_test(test_drop_gain),
        cmocka_unit_test(test_foam_map_on_request),
        cmocka_unit_test(test_sample_some_matches_full),
        cmocka_unit_test(test_gain_planes_reused_exactly),
        cmocka_unit_test(test_stage_paths_same_bits),
        cmocka_unit_test(test_stage_evolves_only_waves),
        cmocka_unit_test(test_deep_water_frequency_computed),
        cmocka_unit_test(test_time_split_counters),
        cmocka_unit_test(test_stage_split_same_bits),
        cmocka_unit_test(test_grouped_transforms),
        cmocka_unit_test(test_pruned_column_pass),
        cmocka_unit_test(reference_context_is_the_direct_sum),
        cmocka_unit_test(accurate_bound_holds_wave_by_wave),
    };
    return cmocka_run_group_tests_name("ocean", tests, NULL, NULL);
}
