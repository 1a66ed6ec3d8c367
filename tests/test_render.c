/*
 * test_render.c - the reference render of the exact sea (sim/cli/render.h):
 *  - its surface is the exact sea: at the displaced point of random
 *    parameter points, the height agrees with the direct double sum of
 *    every wave (ocean_reference.h) plus the near field within the
 *    reading's own bound;
 *  - its footprint levels hand the slope variance they drop to shading:
 *    at every level, the resolved slopes' measured variance plus the
 *    carried moments is the sea's whole mean-square slope (the
 *    geometry-to-BRDF condition of Bruneton, Neyret & Holzschuch 2010),
 *    and the carried part grows as the footprint does;
 *  - relief: from 5 m over the storm sea, crests hide the horizon (the
 *    sea's top edge varies across the image by more than the crests'
 *    angular height), while from 1500 m over it the edge is a straight
 *    line;
 *  - a pure function: the same image from 1 and 2 threads, twice;
 *  - the sun stands where --sun (the viewer's sun=AZ,EL) puts it;
 *  - bad views refused.
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

#include "ocean_reference.h"
#include "render.h"
#include "slope.h"

/* The storm scene's sea (config/scenes/storm.conf) at a reduced grid: Beaufort 10,
 * JONSWAP, choppiness 2.2, three cascades from 2000 m. */
static void storm_params(ocean_params *p, int n)
{
    ocean_params_default(p);
    p->sea.spectrum = OCEAN_SPECTRUM_JONSWAP;
    p->sea.wind_u10 = 26.45;
    p->sea.fetch_m = 300000;
    p->sea.choppiness = 2.2;
    p->sea.wind_dir_deg = 0;
    p->patch_m = 2000;
    p->cascades = 3;
    p->n = n;
    p->threads = 2;
}

/* The near field as oceand builds it for p (64 waves down to 0.1 m). */
static int near_params(ocean_params *p, ocean_gerstner_params *gp)
{
    ocean_gerstner_near_cut(p, 64);
    return ocean_gerstner_near_params(p, 64, 0.1, gp);
}

static double urand(uint64_t *s)
{
    *s = *s * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(*s >> 11) / 9007199254740992.0;
}

static void exact_surface(void **state)
{
    (void)state;
    ocean_params p;
    ocean_gerstner_params gp;
    storm_params(&p, 64);
    assert_int_equal(near_params(&p, &gp), 1);
    const double t = 1234.5;
    char msg[256];
    render_sea *s;
    assert_int_equal(render_sea_create(&p, &gp, OCEAN_FX_ALL | OCEAN_FX_NEAR_FIELD, t, 2, &s, msg, sizeof msg), OCEAN_OK);
    ocean *o;
    ocean_gerstner *g;
    ocean_reference *ref;
    assert_int_equal(ocean_create(&p, &o, msg, sizeof msg), OCEAN_OK);
    assert_int_equal(ocean_gerstner_create(&gp, &g, msg, sizeof msg), OCEAN_OK);
    assert_int_equal(ocean_reference_create(o, t, INFINITY, 6, &ref), OCEAN_OK);
    ocean_gerstner_view v;
    ocean_gerstner_view_default(&v);
    uint64_t seed = 7;
    double worst = 0;
    for (int i = 0; i < 24; i++) {
        double x0 = (urand(&seed) - 0.5) * 4000, z0 = (urand(&seed) - 0.5) * 4000;
        ocean_point e;
        ocean_gerstner_point n;
        ocean_reference_eval(ref, x0, z0, &e);
        assert_int_equal(ocean_gerstner_evaluate(g, &v, t, &x0, &z0, 1, &n), OCEAN_OK);
        double x = x0 + e.dx + n.dx, z = z0 + e.dz + n.dz, h = e.height + n.dy;
        render_point rp;
        assert_int_equal(render_sea_point(s, x, z, 0, &rp), OCEAN_OK);
        if (!isfinite(rp.error)) continue;   /* a folded crest: several surface points over (x, z) */
        double d = fabs(rp.height - h);
        assert_true(d <= rp.error + 1e-4);
        worst = fmax(worst, d);
    }
    printf("# exact surface: largest |height - direct sum| %.3g m\n", worst);
    assert_true(worst < 0.01);
    ocean_reference_destroy(ref);
    ocean_gerstner_destroy(g);
    ocean_destroy(o);
    render_sea_destroy(s);
}

static void levels_keep_slope_variance(void **state)
{
    (void)state;
    ocean_params p;
    storm_params(&p, 128);
    p.sea.choppiness = 0;     /* slopes of the linear height field, as slope.h counts them */
    char msg[256];
    render_sea *s;
    assert_int_equal(render_sea_create(&p, NULL, OCEAN_FX_HEIGHT | OCEAN_FX_NORMALS, 300, 2, &s, msg, sizeof msg),
                     OCEAN_OK);
    ocean_slope_stats total;
    ocean *o;
    assert_int_equal(ocean_create(&p, &o, msg, sizeof msg), OCEAN_OK);
    assert_int_equal(ocean_slope_variance(o, NULL, INFINITY, 6, &total), OCEAN_OK);
    ocean_destroy(o);
    double prev_carried = 0;
    for (double foot = 0.05; foot < 400; foot *= 4) {
        double sum = 0, carried = 0;
        int n = 0;
        uint64_t seed = 11;
        for (int i = 0; i < 4000; i++) {
            render_point rp;
            assert_int_equal(render_sea_point(s, (urand(&seed) - 0.5) * 2000, (urand(&seed) - 0.5) * 2000, foot, &rp),
                             OCEAN_OK);
            sum += rp.slope[0] * rp.slope[0] + rp.slope[1] * rp.slope[1];
            carried = rp.mss[0] + rp.mss[1];
            n++;
        }
        double resolved = sum / n, whole = resolved + carried;
        printf("# footprint %7.2f m: resolved %.4f + carried %.4f = %.4f (sea %.4f)\n", foot, resolved, carried, whole,
               total.mss_total);
        assert_true(fabs(whole / total.mss_total - 1) < 0.1);
        assert_true(carried >= prev_carried);
        prev_carried = carried;
    }
    render_sea_destroy(s);
}

#define EDGE_W 640
#define EDGE_H 180

/* Top sea row of each column (the first row whose pixel is mostly sea):
 * its mean and its range over the columns. */
static void sea_edge(const unsigned char *mask, double *mean, int *range)
{
    double s = 0;
    int lo = EDGE_H, hi = 0;
    for (int x = 0; x < EDGE_W; x++) {
        int y = 0;
        while (y < EDGE_H && mask[y * EDGE_W + x] < 128) y++;
        s += y;
        lo = y < lo ? y : lo;
        hi = y > hi ? y : hi;
    }
    *mean = s / EDGE_W;
    *range = hi - lo;
}

/* The row where column px's sea edge lies on the exact surface: the
 * largest elevation the surface reaches along the column's azimuth, read
 * every metre out to 3 km (footprint 0: the exact waves), as a row. */
static int exact_edge_row(const render_sea *s, double y, int px)
{
    double tan_h = tan(5 * M_PI / 180), aspect = (double)EDGE_W / EDGE_H;
    double nx = (px + 0.5) / EDGE_W * 2 - 1, a = nx * tan_h * aspect;
    double l = sqrt(1 + a * a), dx = 1 / l, dz = a / l;     /* yaw 0: forward +x, right +z */
    double best = -INFINITY;
    for (double d = 1; d < 3000; d += 1) {
        render_point rp;
        render_sea_point(s, d * dx, d * dz, 0, &rp);
        best = fmax(best, (rp.height - y) / d);
    }
    double ny = best * l / tan_h;                           /* the edge's ray, in the image's terms */
    return (int)ceil((1 - ny) * EDGE_H / 2 - 0.5);
}

/* A level view downwind from height y, 10 deg high (18 rows a degree), 34
 * wide; if agree is not NULL, the percentage of sampled columns whose edge
 * is within a row of the exact surface's (exact_edge_row). */
static void render_edge(render_sea *s, double y, double *mean, int *range, int *agree)
{
    render_view v = {.eye = {0, y, 0}, .yaw_deg = 0, .pitch_deg = 0, .fov_deg = 10, .width = EDGE_W,
                     .height = EDGE_H, .supersample = 1, .threads = 2};
    float *rgb = malloc(sizeof(float) * 3 * EDGE_W * EDGE_H);
    unsigned char *mask = malloc(EDGE_W * EDGE_H);
    render_stats st;
    char msg[256];
    assert_int_equal(render_image(s, &v, rgb, mask, &st, msg, sizeof msg), OCEAN_OK);
    sea_edge(mask, mean, range);
    int n = 0, worst = 0, hits = 0;
    for (int px = 8; agree && px < EDGE_W; px += 32, n++) {
        int row = 0;
        while (row < EDGE_H && mask[row * EDGE_W + px] < 128) row++;
        int d = abs(row - exact_edge_row(s, y, px));
        hits += d <= 1;
        worst = d > worst ? d : worst;
    }
    if (agree) {
        printf("# eye at %g m: the edge within a row of the exact surface's in %d of %d columns (worst %d)\n", y,
               hits, n, worst);
        *agree = hits * 100 / n;
    }
    printf("# eye at %g m: sea edge row %.2f, range %d rows (%ld rays, %ld met the sea, %.0f ms)\n", y, *mean,
           *range, st.rays, st.sea_rays, st.ms);
    free(rgb);
    free(mask);
}

static void crests_break_the_horizon(void **state)
{
    (void)state;
    ocean_params p;
    storm_params(&p, 128);
    char msg[256];
    render_sea *s;
    assert_int_equal(render_sea_create(&p, NULL, OCEAN_FX_ALL, 500, 2, &s, msg, sizeof msg), OCEAN_OK);
    double mean;
    int range, agree;
    /* a crest 2 m over a 5 m eye 200 m out rises 0.57 deg (10 rows) over
     * the horizon (row 90), a trough hides nothing behind it */
    render_edge(s, 5, &mean, &range, &agree);
    assert_true(range >= 5);
    assert_true(agree >= 90);
    assert_true(mean < 89.5);
    /* from 1500 m the sea's edge is the horizon of a flat sea, 0.06 deg
     * (1 row) below the centre at the 2e6 m where rays stop meeting waves */
    render_edge(s, 1500, &mean, &range, NULL);
    assert_true(range <= 1);
    assert_true(fabs(mean - 90) <= 1.5);
    render_sea_destroy(s);
}

static void pure_function(void **state)
{
    (void)state;
    ocean_params p;
    storm_params(&p, 64);
    char msg[256];
    render_sea *s;
    assert_int_equal(render_sea_create(&p, NULL, OCEAN_FX_ALL, 77.25, 2, &s, msg, sizeof msg), OCEAN_OK);
    render_view v = {.eye = {100, 30, -50}, .yaw_deg = 10, .pitch_deg = -12, .fov_deg = 50, .width = 48, .height = 32,
                     .supersample = 2, .threads = 1};
    float *a = malloc(sizeof(float) * 3 * 48 * 32), *b = malloc(sizeof(float) * 3 * 48 * 32);
    render_stats st;
    assert_int_equal(render_image(s, &v, a, NULL, &st, msg, sizeof msg), OCEAN_OK);
    assert_true(st.sea_rays > 0 && st.sea_rays < st.rays);
    v.threads = 2;
    assert_int_equal(render_image(s, &v, b, NULL, &st, msg, sizeof msg), OCEAN_OK);
    assert_memory_equal(a, b, sizeof(float) * 3 * 48 * 32);
    for (int i = 0; i < 3 * 48 * 32; i++) assert_true(a[i] >= 0 && a[i] <= 1);
    free(a);
    free(b);
    render_sea_destroy(s);
}

/* The sun stands where --sun puts it, in the camera's own convention
 * (azimuth from +x toward +z as the yaw, elevation as the pitch): a
 * narrow view aimed there sees the disc (white after the tone curve), one
 * aimed the opposite way does not. */
static float centre_of(render_sea *s, double yaw, double pitch, double az, double el)
{
    render_view v = {.eye = {0, 20, 0}, .yaw_deg = yaw, .pitch_deg = pitch, .fov_deg = 2, .width = 9, .height = 9,
                     .supersample = 1, .threads = 1, .sun_given = 1, .sun_deg = {az, el}};
    float rgb[9 * 9 * 3];
    render_stats st;
    char msg[256];
    assert_int_equal(render_image(s, &v, rgb, NULL, &st, msg, sizeof msg), OCEAN_OK);
    return rgb[(4 * 9 + 4) * 3 + 2];
}

static void sun_where_asked(void **state)
{
    (void)state;
    ocean_params p;
    storm_params(&p, 64);
    char msg[256];
    render_sea *s;
    assert_int_equal(render_sea_create(&p, NULL, OCEAN_FX_ALL, 0, 1, &s, msg, sizeof msg), OCEAN_OK);
    float at = centre_of(s, 100, 30, 100, 30), away = centre_of(s, 280, 30, 100, 30), off = centre_of(s, 100, 30, 100, 34);
    printf("# the sun's centre pixel %.3f, the opposite sky %.3f, 4 deg below the sun %.3f\n", at, away, off);
    assert_true(at > 0.99);
    assert_true(away < 0.95 && off < 0.99);
    render_view v = {.eye = {0, 20, 0}, .fov_deg = 60, .width = 2, .height = 2, .supersample = 1, .threads = 1,
                     .sun_given = 1, .sun_deg = {0, 95}};
    float rgb[12];
    render_stats st;
    assert_int_equal(render_image(s, &v, rgb, NULL, &st, msg, sizeof msg), OCEAN_EINVAL);
    render_sea_destroy(s);
}

static void bad_views_refused(void **state)
{
    (void)state;
    ocean_params p;
    storm_params(&p, 64);
    char msg[256];
    render_sea *s;
    assert_int_equal(render_sea_create(&p, NULL, OCEAN_FX_ALL, 0, 2, &s, msg, sizeof msg), OCEAN_OK);
    float rgb[3 * 4];
    render_stats st;
    render_view ok = {.eye = {0, 10, 0}, .fov_deg = 60, .width = 2, .height = 2, .supersample = 1, .threads = 1};
    render_view v = ok;
    v.eye[1] = NAN;
    assert_int_equal(render_image(s, &v, rgb, NULL, &st, msg, sizeof msg), OCEAN_EINVAL);
    v = ok;
    v.fov_deg = 180;
    assert_int_equal(render_image(s, &v, rgb, NULL, &st, msg, sizeof msg), OCEAN_EINVAL);
    v = ok;
    v.supersample = 0;
    assert_int_equal(render_image(s, &v, rgb, NULL, &st, msg, sizeof msg), OCEAN_EINVAL);
    assert_non_null(strstr(msg, "supersample"));
    assert_int_equal(render_image(s, &ok, rgb, NULL, &st, msg, sizeof msg), OCEAN_OK);
    render_sea_destroy(s);
    assert_int_equal(render_sea_create(&p, NULL, OCEAN_FX_ALL, INFINITY, 2, &s, msg, sizeof msg), OCEAN_EINVAL);
    assert_null(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(exact_surface),
        cmocka_unit_test(levels_keep_slope_variance),
        cmocka_unit_test(crests_break_the_horizon),
        cmocka_unit_test(pure_function),
        cmocka_unit_test(sun_where_asked),
        cmocka_unit_test(bad_views_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
