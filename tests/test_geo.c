/*
 * test_geo.c - the ocean's plane on the Earth (sim/geo.h) against the
 * WGS 84 ellipsoid's published geometry: the meridian arc from the
 * equator (Torge & Mueller, Geodesy, 4th ed., eq. 6.58; 10 001 965.729 m
 * to the pole), the lengths of a degree of latitude and of longitude
 * from the radii of curvature M and N (ibid., eqs. 6.50-6.53); the axes
 * (x north, z east); round trips at 1000 km; and refusals.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "geo.h"

/* WGS 84: semi-major axis and flattening (NIMA TR8350.2, table 3.1) */
static const double A = 6378137.0, F = 1 / 298.257223563;

static ocean_geo *plane(double lat0, double lon0)
{
    ocean_geo *g = NULL;
    char why[200];
    assert_int_equal(ocean_geo_create(lat0, lon0, &g, why, sizeof why), OCEAN_OK);
    return g;
}

static void meridian_arcs(void **state)
{
    (void)state;
    ocean_geo *g = plane(0, 0);
    double x, z;
    /* the quarter meridian of WGS 84 */
    assert_int_equal(ocean_geo_to_plane(g, 90, 0, &x, &z), OCEAN_OK);
    print_message("equator to pole: %.4f m (WGS 84: 10001965.729 m)\n", x);
    assert_true(fabs(x - 10001965.729) < 0.002);
    assert_true(fabs(z) < 1e-6);
    /* to 45 deg: 4 984 944.378 m */
    assert_int_equal(ocean_geo_to_plane(g, 45, 0, &x, &z), OCEAN_OK);
    print_message("equator to 45 deg: %.4f m (WGS 84: 4984944.378 m)\n", x);
    assert_true(fabs(x - 4984944.378) < 0.002);
    ocean_geo_destroy(g);
}

/* Near any origin a small step north is M dphi and east N cos(phi) dlam. */
static void degree_lengths(void **state)
{
    (void)state;
    double e2 = F * (2 - F);
    const double lats[] = {0, 15, 30, 45, 60, 75, 89};
    for (size_t i = 0; i < sizeof lats / sizeof lats[0]; i++) {
        double phi = lats[i] * M_PI / 180, s2 = sin(phi) * sin(phi), w = sqrt(1 - e2 * s2);
        double M = A * (1 - e2) / (w * w * w), N = A / w;
        double d = 1e-4; /* degrees: ~11 m, where the curvature of the path is far below the check */
        ocean_geo *g = plane(lats[i], 10);
        double x, z;
        assert_int_equal(ocean_geo_to_plane(g, lats[i] + d, 10, &x, &z), OCEAN_OK);
        double north = M * d * M_PI / 180, xn = x;
        assert_true(fabs(x - north) < 1e-6 * north);
        assert_true(fabs(z) < 1e-9);
        assert_int_equal(ocean_geo_to_plane(g, lats[i], 10 + d, &x, &z), OCEAN_OK);
        double east = N * cos(phi) * d * M_PI / 180;
        print_message("at %2.0f deg: 1 deg of latitude %.3f m (M: %.3f), of longitude %.3f m (N cos: %.3f)\n",
                      lats[i], xn / d, M * M_PI / 180, z / d, N * cos(phi) * M_PI / 180);
        assert_true(fabs(z - east) < 1e-6 * east);
        assert_true(x > 0 || lats[i] == 0); /* the geodesic east bends poleward of the parallel */
        ocean_geo_destroy(g);
    }
}

/* 1000 km out on every bearing: the plane is the geodesic's distance and
 * bearing, and the two directions undo each other within a millimetre. */
static void round_trips(void **state)
{
    (void)state;
    ocean_geo *g = plane(43.36, -8.41);
    double worst = 0;
    for (int b = 0; b < 360; b += 15) {
        double x = 1e6 * cos(b * M_PI / 180), z = 1e6 * sin(b * M_PI / 180), lat, lon, x2, z2;
        assert_int_equal(ocean_geo_to_geodetic(g, x, z, &lat, &lon), OCEAN_OK);
        assert_int_equal(ocean_geo_to_plane(g, lat, lon, &x2, &z2), OCEAN_OK);
        worst = fmax(worst, hypot(x2 - x, z2 - z));
        /* north of the origin is a higher latitude, east a greater longitude */
        if (b == 0) assert_true(lat > 43.36 + 8 && fabs(lon + 8.41) < 1e-9);
        if (b == 90) assert_true(lon > -8.41 + 10);
    }
    print_message("1000 km on 24 bearings: plane -> geodetic -> plane within %.3g m\n", worst);
    assert_true(worst < 1e-3);
    /* the same point asked twice is the same point, to the bit */
    double x1, z1, x2, z2;
    assert_int_equal(ocean_geo_to_plane(g, 50.1, 1.7, &x1, &z1), OCEAN_OK);
    assert_int_equal(ocean_geo_to_plane(g, 50.1, 1.7, &x2, &z2), OCEAN_OK);
    assert_true(x1 == x2 && z1 == z2);
    ocean_geo_destroy(g);
}

static void refusals(void **state)
{
    (void)state;
    ocean_geo *g = NULL;
    char why[200];
    assert_int_equal(ocean_geo_create(91, 0, &g, why, sizeof why), OCEAN_EINVAL);
    assert_int_equal(ocean_geo_create(0, NAN, &g, why, sizeof why), OCEAN_EINVAL);
    assert_null(g);
    g = plane(10, 20);
    double x, z, lat, lon;
    assert_int_equal(ocean_geo_to_plane(g, NAN, 0, &x, &z), OCEAN_EINVAL);
    assert_int_equal(ocean_geo_to_plane(g, 0, 180.5, &x, &z), OCEAN_EINVAL);
    assert_int_equal(ocean_geo_to_plane(g, -90.01, 0, &x, &z), OCEAN_EINVAL);
    assert_int_equal(ocean_geo_to_geodetic(g, INFINITY, 0, &lat, &lon), OCEAN_EINVAL);
    assert_int_equal(ocean_geo_to_geodetic(g, 2.1e7, 0, &lat, &lon), OCEAN_EINVAL);
    ocean_geo_destroy(g);
    ocean_geo_destroy(NULL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(meridian_arcs),
        cmocka_unit_test(degree_lengths),
        cmocka_unit_test(round_trips),
        cmocka_unit_test(refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
