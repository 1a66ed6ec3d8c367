/*
 * test_wake.c - the steady wake (sim/wake.h) against the published laws of
 * ship waves, measured on the heights the library returns:
 *  - deep water, hull Froude number U / sqrt(g L) below 0.4: the cusp line
 *    at arcsin(1/3) = 19.47 deg within 1 deg, the transverse waves on the
 *    track of wavelength 2 pi U^2 / g within 3 % (Kelvin 1887);
 *  - finite depth, depth Froude number U / sqrt(g h) = 0.9: the cusp line
 *    where Havelock (1908) puts it, within 2 deg: from the dispersion
 *    relation c^2 = (g / k) tanh(k h), the wave travelling at angle psi to
 *    the track is steady when c = U cos psi; in the body's frame its energy
 *    moves at U - c_g along the wave (the water's U less the group
 *    velocity, n = c_g / c), so it leaves at the angle alpha with
 *    tan alpha = n tan psi / (1 + tan^2 psi - n), and the cusp is the
 *    largest alpha (deep water, n = 1/2: arcsin(1/3));
 *  - bad parameters refused.
 * The cusp line is read from the envelope's Airy profile across it (see
 * measured_cusp_deg) from 30 to 58 transverse wavelengths behind, where
 * the near field of a hull of these lengths has faded (at 10-21
 * wavelengths the line read 0.6-2.5 deg wide of the law); the wavelength
 * on the grid ocean-sim wake prints (22 wavelengths behind).
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "wake.h"

#define G 9.81

/* Havelock's cusp half-angle at depth h for speed U (deep: h = inf), deg. */
static double havelock_cusp_deg(double U, double h)
{
    double best = 0;
    for (int i = 1; i < 20000; i++) {
        double psi = i * (M_PI / 2) / 20000, c = U * cos(psi);
        /* the wave number whose phase speed is c */
        double k;
        if (isinf(h)) {
            k = G / (c * c);
        } else {
            if (c * c >= G * h) continue;
            double lo = 0, hi = G / (c * c);
            for (int it = 0; it < 100; it++) {
                double m = 0.5 * (lo + hi);
                if (G / m * tanh(m * h) > c * c) lo = m;
                else hi = m;
            }
            k = 0.5 * (lo + hi);
        }
        double n = isinf(h) || k * h > 300 ? 0.5 : 0.5 * (1 + 2 * k * h / sinh(2 * k * h));
        double t = tan(psi), a = atan(n * t / (1 + t * t - n));
        if (a > best) best = a;
    }
    return best * 180 / M_PI;
}

static float at(const wake_grid *g, int ix, int iz) { return g->heights[(size_t)iz * g->nx + ix]; }

/* The RMS of g's heights over one transverse wavelength along the track
 * (w points either side of column ix), at row iz: the waves' envelope. */
static double envelope(const wake_grid *g, int ix, int iz, int w)
{
    double e = 0;
    for (int d = -w; d <= w; d++) e += (double)at(g, ix + d, iz) * at(g, ix + d, iz);
    return sqrt(e / (2 * w + 1));
}

/* The cusp half-angle read off g from x0 to x1 transverse wavelengths
 * behind, deg.  Across the cusp line the envelope is an Airy function of
 * the distance to the line (the caustic of the two wave systems): it peaks
 * inside (Ai(-1.019) = 0.5357) and is Ai(0) = 0.3550, 0.663 of its peak,
 * on the line itself.  So per column: the outermost envelope maximum, then
 * outward to 0.663 of it. */
static double measured_cusp_deg(const wake_grid *g, double lambda, double x0, double x1)
{
    int w = (int)lround(0.5 * lambda / g->dx), izc = (int)lround(-g->z0 / g->dx), cols = 0;
    double sum = 0;
    for (double x = x0 * lambda; x <= x1 * lambda; x += 0.5 * lambda) {
        int ix = (int)lround((x - g->x0) / g->dx), peak = -1;
        double top = 0;
        for (int iz = izc; iz < g->nz; iz++) top = fmax(top, envelope(g, ix, iz, w));
        for (int iz = g->nz - 2; iz > izc && peak < 0; iz--) {
            double e = envelope(g, ix, iz, w);
            if (e > 0.2 * top && e >= envelope(g, ix, iz - 1, w) && e >= envelope(g, ix, iz + 1, w)) peak = iz;
        }
        if (peak < 0) continue;
        double level = 0.6627 * envelope(g, ix, peak, w);
        for (int iz = peak; iz < g->nz - 1; iz++) {
            double a = envelope(g, ix, iz, w), b = envelope(g, ix, iz + 1, w);
            if (a >= level && b < level) {
                double z = g->z0 + (iz + (a - level) / (a - b)) * g->dx;
                sum += atan(z / x) * 180 / M_PI;
                cols++;
                break;
            }
        }
    }
    assert_true(cols >= 40);
    return sum / cols;
}

/* The transverse wavelength on the track: the mean distance between
 * upward zero crossings of the centre line from 5 to 20 wavelengths. */
static double measured_wavelength(const wake_grid *g, double lambda)
{
    int iz = (int)lround(-g->z0 / g->dx), first = -1, last = -1, n = 0;
    double xf = 0, xl = 0;
    for (int ix = 1; ix < g->nx; ix++) {
        double x = g->x0 + ix * g->dx;
        if (x < 5 * lambda || x > 20 * lambda) continue;
        float a = at(g, ix - 1, iz), b = at(g, ix, iz);
        if (a < 0 && b >= 0) {
            double xc = x - g->dx + g->dx * (-a) / (b - a);
            if (first < 0) first = ix, xf = xc;
            last = ix, xl = xc, n++;
        }
    }
    assert_true(n >= 8 && last > first);
    return (xl - xf) / (n - 1);
}

static void check(double U, double L, double h, double angle_tol)
{
    wake_params p = {U, L, h};
    wake_grid g, far;
    char msg[200];
    assert_int_equal(wake_steady(&p, &g, msg, sizeof msg), OCEAN_OK);
    assert_int_equal(wake_steady_to(&p, 60, &far, msg, sizeof msg), OCEAN_OK);
    double lambda = wake_transverse_wavelength(&p), want = havelock_cusp_deg(U, h);
    double lm = measured_wavelength(&g, lambda), am = measured_cusp_deg(&far, lambda, 30, 58);
    double lk = isinf(h) ? 2 * M_PI * U * U / G : lambda;
    print_message("U %.1f m/s, L %.1f m (Fr %.2f), depth %g m (Fh %.2f): transverse wavelength %.2f m "
                  "(law %.2f m, %+.1f %%), cusp %.2f deg (law %.2f deg)\n",
                  U, L, U / sqrt(G * L), h, isinf(h) ? 0 : U / sqrt(G * h), lm, lk, 100 * (lm / lk - 1), am, want);
    assert_true(fabs(lm / lk - 1) <= 0.03);
    assert_true(fabs(am - want) <= angle_tol);
    wake_grid_free(&g);
    wake_grid_free(&far);
}

static void deep_kelvin(void **state)
{
    (void)state;
    assert_true(fabs(havelock_cusp_deg(10, INFINITY) - asin(1.0 / 3) * 180 / M_PI) < 0.01);
    /* U = 6 m/s (transverse waves 23.06 m) at Fr 0.3 and 0.2, 10 m/s
     * (64.05 m) at Fr 0.38 */
    check(6.0, 6.0 * 6.0 / (G * 0.09), INFINITY, 1.0);
    check(6.0, 6.0 * 6.0 / (G * 0.04), INFINITY, 1.0);
    check(10.0, 100.0 / (G * 0.38 * 0.38), INFINITY, 1.0);
}

static void finite_depth_widens(void **state)
{
    (void)state;
    double U = 6.0, h = U * U / (G * 0.81);   /* Fh = 0.9 */
    double want = havelock_cusp_deg(U, h);
    assert_true(want > 19.47 + 10);          /* the law widens the wedge there: 34.6 deg */
    check(U, 6.0 * 6.0 / (G * 0.09), h, 2.0);
}

static void bad_parameters(void **state)
{
    (void)state;
    const wake_params bad[] = {{0, 50, INFINITY}, {NAN, 50, INFINITY}, {WAKE_SPEED_MAX * 2, 50, INFINITY},
                               {5, 0.1, INFINITY}, {5, NAN, INFINITY}, {5, 50, 0}, {5, 50, NAN}, {5, 50, -3}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        wake_grid g;
        char msg[200] = "";
        assert_int_equal(wake_steady(&bad[i], &g, msg, sizeof msg), OCEAN_EINVAL);
        assert_null(g.heights);
        assert_non_null(strstr(msg, "wake"));
    }
    wake_params fast = {12, 50, 10};   /* Fh 1.2: no transverse waves */
    assert_true(wake_transverse_wavelength(&fast) == 0);
    wake_grid_free(NULL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(deep_kelvin),
        cmocka_unit_test(finite_depth_widens),
        cmocka_unit_test(bad_parameters),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
