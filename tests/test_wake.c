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
#include "wake_field.h"
#include "oc_wakes.h"
#include "proto.h"

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
    wake_params p = {U, L, h, 0};
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

/* The angle of maximum amplitude read off g, deg: per column from 10
 * body lengths behind to 90 % of the grid, the row (one side of the
 * track) where the envelope peaks, as an angle from the body. */
static double measured_max_amplitude_deg(const wake_grid *g, double lambda, double L)
{
    int w = (int)fmax(2, lround(0.5 * lambda / g->dx)), izc = (int)lround(-g->z0 / g->dx), cols = 0;
    double sum = 0, xend = g->x0 + 0.9 * (g->nx - 1) * g->dx;
    for (int ix = w; ix < g->nx - w; ix++) {
        double x = g->x0 + ix * g->dx, top = 0;
        if (x < 10 * L || x > xend) continue;
        int best = -1;
        for (int iz = izc + 1; iz < g->nz; iz++) {
            double e = envelope(g, ix, iz, w);
            if (e > top) top = e, best = iz;
        }
        if (best < 0) continue;
        sum += atan((g->z0 + best * g->dx) / x) * 180 / M_PI;
        cols++;
    }
    assert_true(cols >= 40);
    return sum / cols;
}

/* Fast short bodies: above Fr = 0.6 the angle of maximum amplitude
 * narrows as 1/Fr, inside Kelvin's wedge (Rabaud & Moisy 2013, Phys. Rev.
 * Lett. 110, 214503: alpha = 1 / (2 sqrt(2 pi) Fr) at large Fr; Darmon,
 * Benzaquen & Raphael 2014, J. Fluid Mech. 738, R3, for a pressure
 * footprint): within 15 % at Fr 1 and 2, for a hull's footprint (a sixth
 * as wide as long, the daemon's ships) and a round one (the
 * axisymmetric disturbance of Rabaud & Moisy's argument). */
static void fast_hulls_narrow(void **state)
{
    (void)state;
    const double L = 20, frs[2] = {1.0, 2.0};
    for (int round = 0; round < 2; round++)
        for (int i = 0; i < 2; i++) {
            double U = frs[i] * sqrt(G * L), law = 1 / (2 * sqrt(2 * M_PI) * frs[i]) * 180 / M_PI;
            wake_params p = {U, L, INFINITY, round ? L : 0};
            wake_grid g;
            assert_int_equal(wake_steady(&p, &g, NULL, 0), OCEAN_OK);
            double a = measured_max_amplitude_deg(&g, wake_transverse_wavelength(&p), L);
            printf("%s footprint, Fr %.1f: angle of maximum amplitude %.2f deg (Rabaud & Moisy %.2f deg, %+.0f %%)\n",
                   round ? "round" : "hull", frs[i], a, law, 100 * (a / law - 1));
            assert_true(fabs(a / law - 1) <= 0.15);
            assert_true(a < 19.47 * 0.7);
            wake_grid_free(&g);
        }
}

static void bad_parameters(void **state)
{
    (void)state;
    const wake_params bad[] = {{0, 50, INFINITY, 0},  {NAN, 50, INFINITY, 0}, {WAKE_SPEED_MAX * 2, 50, INFINITY, 0},
                               {5, 0.1, INFINITY, 0}, {5, NAN, INFINITY, 0}, {5, 50, 0, 0},
                               {5, 50, NAN, 0},       {5, 50, -3, 0},        {5, 50, INFINITY, NAN},
                               {5, 50, INFINITY, 0.01}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        wake_grid g;
        char msg[200] = "";
        assert_int_equal(wake_steady(&bad[i], &g, msg, sizeof msg), OCEAN_EINVAL);
        assert_null(g.heights);
        assert_non_null(strstr(msg, "wake"));
    }
    wake_params fast = {12, 50, 10, 0};   /* Fh 1.2: no transverse waves */
    assert_true(wake_transverse_wavelength(&fast) == 0);
    wake_grid_free(NULL);
}

/* A deterministic spread of points over the wedge of pattern w. */
static void wedge_points(const wake_pattern *w, double *xz, int n)
{
    double lam = wake_pattern_wavelength(w);
    uint32_t r = 12345;
    for (int i = 0; i < n; i++) {
        r = r * 1664525u + 1013904223u;
        double x = (0.5 + 19.0 * (r >> 8) / 16777216.0) * lam;
        r = r * 1664525u + 1013904223u;
        double z = x * tan(22.0 * M_PI / 180) * (2.0 * (r >> 8) / 16777216.0 - 1);
        xz[2 * i] = x, xz[2 * i + 1] = z;
    }
}

/* The pattern read bicubically stays within its stated bound of the
 * exact series at points off the grid, and the bound is small beside the
 * waves; its slopes are the heights' derivatives; under the hull and
 * beyond the reach it reads 0. */
static void pattern_reads_the_series(void **state)
{
    (void)state;
    const wake_params cases[] = {{10, 100, INFINITY, 0}, {6, 30, 5.0, 5}};
    for (size_t c = 0; c < 2; c++) {
        wake_pattern *w = NULL;
        char msg[200];
        assert_int_equal(wake_pattern_create(&cases[c], &w, msg, sizeof msg), OCEAN_OK);
        enum { N = 48 };
        double xz[2 * N], exact[N], top = 0, worst = 0, local = 0;
        wedge_points(w, xz, N);
        assert_int_equal(wake_pattern_exact(w, xz, N, exact), OCEAN_OK);
        for (int i = 0; i < N; i++) {
            double hx, hz, h = wake_pattern_read(w, xz[2 * i], xz[2 * i + 1], &hx, &hz);
            top = fmax(top, fabs(exact[i]));
            worst = fmax(worst, fabs(h - exact[i]));
            assert_true(fabs(h - exact[i]) <= wake_pattern_bound_at(w, xz[2 * i], xz[2 * i + 1]));
            local = fmax(local, wake_pattern_bound_at(w, xz[2 * i], xz[2 * i + 1]));
            /* central differences: their own error is (k e)^2 / 6 of the slope */
            double e = 1e-3 * wake_pattern_wavelength(w), d;
            double xp = wake_pattern_read(w, xz[2 * i] + e, xz[2 * i + 1], &d, &d);
            double xm = wake_pattern_read(w, xz[2 * i] - e, xz[2 * i + 1], &d, &d);
            double zp = wake_pattern_read(w, xz[2 * i], xz[2 * i + 1] + e, &d, &d);
            double zm = wake_pattern_read(w, xz[2 * i], xz[2 * i + 1] - e, &d, &d);
            assert_true(fabs((xp - xm) / (2 * e) - hx) <= 1e-3 * fabs(hx) + 1e-6);
            assert_true(fabs((zp - zm) / (2 * e) - hz) <= 1e-3 * fabs(hz) + 1e-6);
        }
        printf("pattern U %g L %g depth %g: |read - exact| at most %.2e m, bound there at most %.2e m "
               "(%.2e m anywhere), waves to %.3f m\n",
               cases[c].speed, cases[c].length, cases[c].depth, worst, local, wake_pattern_bound(w), top);
        assert_true(local <= wake_pattern_bound(w));
        assert_true(local < 0.05 * top);
        assert_true(top > 0.05);
        double hx, hz;
        assert_true(wake_pattern_read(w, 0, 0, &hx, &hz) == 0);
        double far = wake_pattern_reach(w) * 1.01;
        assert_true(wake_pattern_read(w, far, 0, &hx, &hz) == 0 && hx == 0 && hz == 0);
        assert_true(wake_pattern_read(w, 0, -far, &hx, &hz) == 0);
        wake_pattern_destroy(w);
    }
    wake_pattern_destroy(NULL);
    wake_pattern *w = (wake_pattern *)&w;
    const wake_params bad = {5, 50, INFINITY, 80};   /* wider than long */
    char msg[200] = "";
    assert_int_equal(wake_pattern_create(&bad, &w, msg, sizeof msg), OCEAN_EINVAL);
    assert_null(w);
    assert_non_null(strstr(msg, "beam"));
}

/* Builds every pattern the ships need for the points into f. */
static void build_missing(wake_field *f, const ocean_entity_desc *d, const ocean_entity_state *st, int n,
                          double depth, const double *xz, size_t np)
{
    wake_params need[8];
    int m = wake_field_missing(f, d, st, n, depth, xz, np, need, 8);
    assert_true(m <= 8);
    for (int i = 0; i < m; i++) {
        wake_pattern *p;
        char msg[200];
        assert_int_equal(wake_pattern_create(&need[i], &p, msg, sizeof msg), OCEAN_OK);
        wake_field_insert(f, p);
    }
    assert_int_equal(wake_field_missing(f, d, st, n, depth, xz, np, NULL, 0), 0);
}

static ocean_entity_state ship_at(double x, double z, double heading_deg, double speed)
{
    double a = heading_deg * M_PI / 180;
    ocean_entity_state s = {x, z, 0, heading_deg, speed, speed * cos(a), speed * sin(a), 0, 0};
    return s;
}

/* Two ships, the second steaming in the first's wake, over finite and
 * deep water: the summed wakes at points around both stay within their
 * bound of the exact sum of the same waves; the bound is small beside
 * them; a ship's wake is its pattern laid along its heading and scaled by
 * its draught; a point beyond every reach reads 0 and needs no pattern. */
static void field_sums_the_ships(void **state)
{
    (void)state;
    const ocean_entity_desc d[2] = {{1, OCEAN_ENTITY_SHIP, 80, 12, 4}, {2, OCEAN_ENTITY_SHIP, 40, 7, 2}};
    const double depths[2] = {INFINITY, 10};   /* depth Froude numbers 0.84, 0.62 */
    for (int c = 0; c < 2; c++) {
        double depth = depths[c];
        /* heading 30 deg; the second 300 m astern of the first, 40 m off its track */
        ocean_entity_state st[2] = {ship_at(1000, -500, 30, 8.3), ship_at(0, 0, 30, 6.1)};
        st[1].x = st[0].x - 300 * cos(M_PI / 6) - 40 * sin(M_PI / 6);
        st[1].z = st[0].z - 300 * sin(M_PI / 6) + 40 * cos(M_PI / 6);
        enum { N = 40 };
        double xz[2 * N], exact[N], top = 0, worst = 0, bound = 0;
        for (int i = 0; i < N; i++) {   /* along the first's track and across the second's hull */
            double back = 20 + 15 * i, off = (i % 5 - 2) * 0.1 * back;
            xz[2 * i] = st[0].x - back * cos(M_PI / 6) - off * sin(M_PI / 6);
            xz[2 * i + 1] = st[0].z - back * sin(M_PI / 6) + off * cos(M_PI / 6);
        }
        wake_field *f;
        assert_int_equal(wake_field_create(8, &f), OCEAN_OK);
        wake_sample w[N];
        w[0].height = 42;
        assert_int_equal(wake_field_sample(f, d, st, 2, depth, xz, N, w), OCEAN_ESTATE);
        assert_true(w[0].height == 42);
        build_missing(f, d, st, 2, depth, xz, N);
        assert_int_equal(wake_field_count(f), 4);
        assert_int_equal(wake_field_sample(f, d, st, 2, depth, xz, N, w), OCEAN_OK);
        assert_int_equal(wake_field_exact(f, d, st, 2, depth, xz, N, exact), OCEAN_OK);
        for (int i = 0; i < N; i++) {
            assert_true(fabs(w[i].height - exact[i]) <= w[i].error);
            top = fmax(top, fabs(exact[i]));
            worst = fmax(worst, fabs(w[i].height - exact[i]));
            bound = fmax(bound, w[i].error);
        }
        printf("two ships, depth %g: wakes to %.3f m, |sum - exact| at most %.2e m, bound at most %.2e m\n", depth,
               top, worst, bound);
        assert_true(top > 0.1 && bound < 0.1 * top);
        /* far from both: nothing, and no pattern asked for */
        double far[2] = {-9000, 9000};
        wake_sample z;
        assert_int_equal(wake_field_missing(f, d, st, 2, depth, far, 1, NULL, 0), 0);
        assert_int_equal(wake_field_sample(f, d, st, 2, depth, far, 1, &z), OCEAN_OK);
        assert_true(z.height == 0 && z.error == 0);
        wake_field_destroy(f);
    }
}

/* A ship on a rung of the speed ladder reads that rung's pattern alone,
 * laid along its heading and scaled by its draught; across a rung the
 * heights are continuous; a moving wake's rate of change is what moving
 * the ship gives; a slow ship, a stopped one and a rotorcraft make none. */
static void field_lays_the_pattern(void **state)
{
    (void)state;
    const ocean_entity_desc d = {7, OCEAN_ENTITY_SHIP, 60, 0, 3};
    double rung = exp2(53.0 / WAKE_RUNGS_PER_OCTAVE);   /* 9.92 m/s */
    ocean_entity_state st = ship_at(0, 0, 90, rung);      /* steaming toward +z */
    double pt[2] = {-25, -180};                            /* behind it, 25 m to its starboard */
    wake_field *f;
    assert_int_equal(wake_field_create(4, &f), OCEAN_OK);
    build_missing(f, &d, &st, 1, INFINITY, pt, 1);
    wake_params p = {rung, 60, INFINITY, 0};
    wake_pattern *alone;
    assert_int_equal(wake_pattern_create(&p, &alone, NULL, 0), OCEAN_OK);
    double sx, sz, want = 3 * wake_pattern_read(alone, 180, 25, &sx, &sz);
    wake_pattern_destroy(alone);
    wake_sample w, lo, hi;
    assert_int_equal(wake_field_sample(f, &d, &st, 1, INFINITY, pt, 1, &w), OCEAN_OK);
    assert_true(fabs(w.height - want) < 1e-9 && fabs(want) > 0.01);
    /* just below and above the rung */
    ocean_entity_state a = ship_at(0, 0, 90, rung * (1 - 1e-7)), b = ship_at(0, 0, 90, rung * (1 + 1e-7));
    build_missing(f, &d, &a, 1, INFINITY, pt, 1);
    build_missing(f, &d, &b, 1, INFINITY, pt, 1);
    assert_int_equal(wake_field_sample(f, &d, &a, 1, INFINITY, pt, 1, &lo), OCEAN_OK);
    assert_int_equal(wake_field_sample(f, &d, &b, 1, INFINITY, pt, 1, &hi), OCEAN_OK);
    assert_true(fabs(lo.height - w.height) < 1e-5 && fabs(hi.height - w.height) < 1e-5);
    /* 1 ms later the ship is 1 cm on */
    ocean_entity_state later = st;
    later.z += rung * 1e-3;
    wake_sample l;
    assert_int_equal(wake_field_sample(f, &d, &later, 1, INFINITY, pt, 1, &l), OCEAN_OK);
    assert_true(fabs((l.height - w.height) / 1e-3 - w.dhdt) < 1e-3 * fabs(w.dhdt) + 1e-5);
    /* no wake */
    ocean_entity_desc rotor = {8, OCEAN_ENTITY_ROTORCRAFT, 15, 0, 0};
    ocean_entity_state slow = ship_at(0, 0, 90, 0.09 * sqrt(9.81 * 60)), stopped = ship_at(0, 0, 90, 0);
    const ocean_entity_desc dd[3] = {d, d, rotor};
    const ocean_entity_state ss[3] = {slow, stopped, st};
    wake_sample none;
    assert_int_equal(wake_field_sample(f, dd, ss, 3, INFINITY, pt, 1, &none), OCEAN_OK);
    assert_true(none.height == 0 && none.error == 0);
    double bad[2] = {NAN, 0};
    assert_int_equal(wake_field_sample(f, &d, &st, 1, INFINITY, bad, 1, &none), OCEAN_EINVAL);
    wake_field_destroy(f);
    wake_field_destroy(NULL);
}

/* A renderer's grid of the wakes (oc_wakes_grid) keeps their mean-square
 * slope at any spacing: a 120 m ship at 8 m/s read on squares of 4 and
 * 16 m spacing, the slopes the grid holds plus the variance it hands to
 * the roughness against the wake's slope variance on a square of 1 m
 * spacing over the same area, within 15 %; at 16 m most of it is handed
 * over. */
static void grid_keeps_the_slopes(void **state)
{
    (void)state;
    oc_wakes *w;
    assert_int_equal(oc_wakes_create(&w), OCEAN_OK);
    proto_msg m;
    proto_msg_init(&m, PROTO_ENTITY);
    m.hdr.sim_time = 0;
    m.u.entity = (proto_entity){.op = PROTO_ENTITY_ANNOUNCE, .kind = 0, .id = 5, .t = 0, .x = 0, .z = 0,
                                .heading_deg = 0, .speed = 8, .length_m = 120, .beam_m = 15, .draught_m = 5};
    assert_int_equal(oc_wakes_entity(w, &m), OCEAN_OK);
    const ocean_entity_desc d = {5, OCEAN_ENTITY_SHIP, 120, 15, 5};
    ocean_entity_state st = ship_at(0, 0, 0, 8);
    wake_params need[4];
    int k = wake_field_rungs(&d, &st, 1, INFINITY, 0, 0, 1e4, need, 4);
    for (int i = 0; i < k; i++) {
        wake_pattern *p;
        assert_int_equal(wake_pattern_create(&need[i], &p, NULL, 0), OCEAN_OK);
        oc_wakes_keep(w, p);
    }
    /* the square 40-424 m behind the ship, across its wedge */
    const double x0 = -424, z0 = -192, side = 384;
    enum { F = 385 };
    static float fine[4 * F * F];
    assert_int_equal(oc_wakes_grid(w, 1, INFINITY, x0, z0, 1.0, F, fine), OCEAN_OK);
    double want = 0;
    for (int i = 0; i < F * F; i++)
        want += (0.5 * (fine[4 * i + 1] * fine[4 * i + 1] + fine[4 * i + 2] * fine[4 * i + 2]) + fine[4 * i + 3]) / (F * F);
    static const double spacing[2] = {4, 16};
    double handed[2];
    for (int c = 0; c < 2; c++) {
        int n = (int)(side / spacing[c]) + 1;
        static float g[4 * 97 * 97];
        assert_int_equal(oc_wakes_grid(w, 1, INFINITY, x0, z0, spacing[c], n, g), OCEAN_OK);
        double held = 0, carried = 0;
        for (int i = 0; i < n * n; i++) {
            held += 0.5 * (g[4 * i + 1] * g[4 * i + 1] + g[4 * i + 2] * g[4 * i + 2]) / (n * n);
            carried += g[4 * i + 3] / (n * n);
        }
        handed[c] = carried / (held + carried);
        printf("ship 120 m, 8 m/s: wake slope variance a side %.3g; on a %g m square held %.3g + handed to the "
               "roughness %.3g = %.3g (%.0f %% of it handed)\n", want, spacing[c], held, carried, held + carried,
               100 * handed[c]);
        assert_true(fabs((held + carried) / want - 1) < 0.15);
    }
    assert_true(handed[1] > 0.5 && handed[1] > 2 * handed[0]);
    float bad[4 * 9];
    assert_int_equal(oc_wakes_grid(w, 1, INFINITY, NAN, 0, 4, 3, bad), OCEAN_EINVAL);
    assert_int_equal(oc_wakes_grid(w, 1, INFINITY, 0, 0, 4, 2, bad), OCEAN_EINVAL);
    oc_wakes_destroy(w);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(deep_kelvin),
        cmocka_unit_test(finite_depth_widens),
        cmocka_unit_test(fast_hulls_narrow),
        cmocka_unit_test(bad_parameters),
        cmocka_unit_test(pattern_reads_the_series),
        cmocka_unit_test(field_sums_the_ships),
        cmocka_unit_test(field_lays_the_pattern),
        cmocka_unit_test(grid_keeps_the_slopes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
