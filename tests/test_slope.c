/*
 * test_slope.c - slope second moments (sim/slope.h): total mean-square
 * slope against Cox & Munk 1954 for the shipped sea and every scene's
 * spectrum, the resolved part against slopes measured on evaluated
 * fields, the partition resolved + carried = total at any cutoff, the
 * near field's share against its own variance, Elfouhaily's B_h against
 * its published closed form, and hostile arguments.
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
#include "ocean_conf.h"
#include "slope.h"
#include "spectrum.h"

#define assert_rel(a, b, tol)                                                            \
    do {                                                                                 \
        double a_ = (a), b_ = (b), t_ = (tol);                                           \
        if (!(fabs(a_ - b_) <= t_ * fabs(b_))) {                                         \
            print_error("%s = %.10g, expected %.10g (rel tol %g)\n", #a, a_, b_, t_);    \
            fail();                                                                      \
        }                                                                                \
    } while (0)

/* Cox & Munk 1954 (JOSA 44, 838), clean surface: sigma^2 = 0.003 +
 * 5.12e-3 U12.5 +- 0.004.  U12.5 from U10 by the neutral log profile
 * U(z) = U10 + (u* / 0.4) ln(z/10) with u* = sqrt(C_D) U10 and Wu's (1982)
 * C_D = (0.8 + 0.065 U10) 1e-3; written out here, not taken from slope.c. */
static double cox_munk(double u10)
{
    double ustar = sqrt((0.8 + 0.065 * u10) * 1e-3) * u10;
    double u125 = u10 + ustar / 0.4 * log(1.25);
    return 0.003 + 5.12e-3 * u125;
}

static ocean *make_ocean(const ocean_params *p)
{
    ocean *o = NULL;
    char msg[256];
    ocean_result r = ocean_create(p, &o, msg, sizeof msg);
    if (r != OCEAN_OK)
        print_error("ocean_create: %s\n", msg);
    assert_int_equal(r, OCEAN_OK);
    return o;
}

static void cox_munk_helpers(void **state)
{
    (void)state;
    /* The formula at U12.5 = 10 m/s: 0.003 + 0.0512. */
    assert_rel(0.003 + 5.12e-3 * 10.0, 0.0542, 1e-12);
    assert_rel(ocean_slope_cox_munk_mss(10.0), cox_munk(10.0), 1e-12);
    /* The log profile raises 10 m winds by about 2 % at 12.5 m. */
    double r = ocean_slope_u125(10.0) / 10.0;
    assert_true(r > 1.015 && r < 1.025);
    assert_true(isnan(ocean_slope_cox_munk_mss(NAN)));
    assert_true(isnan(ocean_slope_cox_munk_mss(-1.0)));
}

/* Elfouhaily et al. 1997 eq. 40-44 at k = k_m = 370 rad/m, U10 = 10:
 * u* = sqrt(1.45e-3) 10, alpha_m = 0.01 (1 + 3 ln(u* / 0.23)),
 * c(k_m) = sqrt(2 g / k_m), F_m = 1. */
static void elfouhaily_bh(void **state)
{
    (void)state;
    double ustar = sqrt(1.45e-3) * 10.0;
    double am = 0.01 * (1.0 + 3.0 * log(ustar / 0.23));
    double want = 0.5 * am * 0.23 / sqrt(2.0 * 9.81 / 370.0);
    assert_rel(ocean_slope_elfouhaily_bh(370.0, 10.0), want, 1e-9);
    /* Low wind (u* < c_m): the other branch of eq. 44. */
    double us5 = sqrt((0.8 + 0.065 * 5.0) * 1e-3) * 5.0;
    double am5 = 0.01 * (1.0 + log(us5 / 0.23));
    assert_rel(ocean_slope_elfouhaily_bh(370.0, 5.0), 0.5 * am5 * 0.23 / sqrt(2.0 * 9.81 / 370.0), 1e-9);
    /* The capillary factor exp(-(k/k_m - 1)^2/4) at k = 3 k_m: e^-1. */
    double c3 = sqrt(9.81 / 1110.0 * 10.0);
    assert_rel(ocean_slope_elfouhaily_bh(1110.0, 10.0), 0.5 * am * 0.23 / c3 * exp(-1.0), 1e-9);
    assert_true(ocean_slope_elfouhaily_bh(0.0, 10.0) == 0.0);
    assert_true(ocean_slope_elfouhaily_bh(100.0, 0.0) == 0.0);
}

/* Total mss of the shipped sea (ocean_params_default: PM, 1 cascade,
 * no near field) within 30 % of Cox-Munk at U10 = 5, 10, 15. */
static void cox_munk_default(void **state)
{
    (void)state;
    const double winds[] = {5.0, 10.0, 15.0};
    for (int i = 0; i < 3; i++) {
        ocean_params p;
        ocean_params_default(&p);
        p.threads = 1;
        p.sea.wind_u10 = winds[i];
        ocean *o = make_ocean(&p);
        ocean_slope_stats s;
        assert_int_equal(ocean_slope_variance(o, NULL, INFINITY, 6, &s), OCEAN_OK);
        double cm = cox_munk(winds[i]);
        print_message("default U10 %4.1f: mss %.4f (fft %.4f, tail sea %.4f, B_h %.4f) "
                      "Cox-Munk %.4f ratio %.3f; up %.4f cross %.4f (CM %.4f %.4f)\n",
                      winds[i], s.mss_total, s.fft_resolved.mss_x + s.fft_resolved.mss_z,
                      s.tail_sea.mss_x + s.tail_sea.mss_z,
                      s.tail_short.mss_x + s.tail_short.mss_z, cm, s.mss_total / cm,
                      s.total.mss_x, s.total.mss_z, 3.16e-3 * ocean_slope_u125(winds[i]),
                      0.003 + 1.92e-3 * ocean_slope_u125(winds[i]));
        assert_rel(s.mss_total, cm, 0.30);
        /* Delivered = resolved (geometry) + carried (shading) for every
         * camera: the antialias policy's cutoffs for level-0 spacings of
         * height / 28 (clients/web/main.js) at heights 2 m .. 10 km, speeds
         * 0 .. 300 m/s, 30 fps, and the 8 coarser levels (spacing x 2^l). */
        ocean_slope_table *t;
        assert_int_equal(ocean_slope_table_create(o, NULL, &t, NULL, 0), OCEAN_OK);
        ocean_filter_config fc;
        ocean_filter_config_default(&fc, &p.sea);
        const double heights[] = {2.0, 25.0, 300.0, 1500.0, 10000.0};
        const double speeds[] = {0.0, 15.0, 250.0, 300.0};
        for (int h = 0; h < 5; h++)
            for (int v = 0; v < 4; v++)
                for (int l = 0; l < 8; l++) {
                    ocean_filter_client cl = {speeds[v], 30.0, heights[h] / 28.0 * (1 << l)};
                    ocean_filter_cutoff cut;
                    assert_int_equal(ocean_filter_cutoff_compute(&fc, OCEAN_FILTER_ANTIALIAS, &cl, &cut),
                                     OCEAN_OK);
                    ocean_slope_stats d;
                    assert_int_equal(ocean_slope_table_get(t, cut.k, 6, &d), OCEAN_OK);
                    assert_rel(d.mss_resolved + d.mss_carried, cm, 0.30);
                }
        ocean_slope_table_destroy(t);
        /* Wind toward +x: more slope along the wind than across it. */
        assert_true(s.total.mss_x > s.total.mss_z);
        assert_true(fabs(s.total.mss_xz) < 1e-3 * s.mss_total);
        ocean_destroy(o);
    }
}

/* Each scene's spectrum (config/scenes/NAME.conf over config/oceand.conf),
 * its ocean and its near field as the daemon builds them (server.*
 * defaults: 64 waves down to 0.1 m; k_max at the finest grid's Nyquist
 * circle), with the wind set to 5, 10, 15 m/s. */
static void cox_munk_scenes(void **state)
{
    (void)state;
    const char *scenes[] = {"flight", "harbour", "ship-bridge", "storm"};
    const double winds[] = {5.0, 10.0, 15.0};
    ocean_params base;
    char err[512];
    assert_int_equal(ocean_conf_load("config/oceand.conf", &base, err, sizeof err), OCEAN_OK);
    for (int sc = 0; sc < 4; sc++)
        for (int i = 0; i < 3; i++) {
            char path[256];
            snprintf(path, sizeof path, "config/scenes/%s.conf", scenes[sc]);
            ocean_scene scene;
            ocean_result r = ocean_conf_scene_load(path, &base, &scene, err, sizeof err);
            if (r != OCEAN_OK)
                print_error("%s\n", err);
            assert_int_equal(r, OCEAN_OK);
            ocean_params p = scene.params;
            p.threads = 1;
            p.sea.wind_u10 = winds[i];
            int near = (scene.effects & OCEAN_FX_NEAR_FIELD) != 0;
            if (near && !isfinite(p.k_max))
                p.k_max = M_PI * p.n / (p.patch_m / pow(p.cascade_ratio, p.cascades - 1));
            ocean *o = make_ocean(&p);
            ocean_gerstner *g = NULL;
            if (near) {
                double khi;
                ocean_cascade_band(o, p.cascades - 1, NULL, NULL, &khi);
                ocean_gerstner_params gp;
                ocean_gerstner_params_default(&gp);
                gp.sea = p.sea;
                gp.seed = p.seed;
                gp.count = 64;
                gp.k_lo = khi;
                gp.k_hi = 2.0 * M_PI / 0.1;
                assert_int_equal(ocean_gerstner_create(&gp, &g, err, sizeof err), OCEAN_OK);
            }
            ocean_slope_stats s;
            assert_int_equal(ocean_slope_variance(o, g, INFINITY, 6, &s), OCEAN_OK);
            double cm = cox_munk(winds[i]);
            print_message("%-11s U10 %4.1f: mss %.4f (fft %.4f near %.4f tail %.4f) "
                          "Cox-Munk %.4f ratio %.3f\n",
                          scenes[sc], winds[i], s.mss_total,
                          s.fft_resolved.mss_x + s.fft_resolved.mss_z,
                          s.near_resolved.mss_x + s.near_resolved.mss_z,
                          s.tail.mss_x + s.tail.mss_z, cm, s.mss_total / cm);
            assert_rel(s.mss_total, cm, 0.30);
            ocean_gerstner_destroy(g);
            ocean_destroy(o);
        }
}

/* The FFT part is the exact sum over the ocean's modes: its height
 * variance matches the ocean's own filtered variance for every cutoff, and
 * resolved + carried is the same total at any cutoff. */
static void partition_and_consistency(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.threads = 1;
    p.n = 128;
    p.cascades = 2;
    p.patch_m = 500.0;
    ocean *o = make_ocean(&p);
    ocean_slope_table *t;
    char msg[128];
    assert_int_equal(ocean_slope_table_create(o, NULL, &t, msg, sizeof msg), OCEAN_OK);
    ocean_slope_stats all, s;
    assert_int_equal(ocean_slope_table_get(t, INFINITY, 6, &all), OCEAN_OK);
    ocean_spectrum_stats ss;
    ocean_get_spectrum_stats(o, &ss);
    assert_rel(all.fft_resolved.energy, ss.variance, 1e-6);
    assert_true(all.fft_carried.energy == 0.0);
    const double kcs[] = {0.0, 0.01, 0.05, 0.2, 0.7, 3.0, 1e3};
    const int orders[] = {1, 2, 6, 17};
    for (size_t i = 0; i < sizeof kcs / sizeof kcs[0]; i++)
        for (size_t j = 0; j < 4; j++) {
            assert_int_equal(ocean_slope_table_get(t, kcs[i], orders[j], &s), OCEAN_OK);
            double want = ocean_filtered_variance(o, ocean_effective_cutoff(o, kcs[i], orders[j]),
                                                  orders[j]);
            assert_rel(s.fft_resolved.energy, want, 1e-6);
            assert_rel(s.mss_total, all.mss_total, 1e-12);
            assert_rel(s.total.mss_xz + 1.0, all.total.mss_xz + 1.0, 1e-12);
            assert_rel(s.resolved.energy + s.carried.energy, all.total.energy, 1e-12);
            /* Memo: a second call gives the same bytes. */
            ocean_slope_stats s2;
            assert_int_equal(ocean_slope_table_get(t, kcs[i], orders[j], &s2), OCEAN_OK);
            assert_memory_equal(&s, &s2, sizeof s);
        }
    /* More carried as the cutoff drops. */
    ocean_slope_stats a, b;
    ocean_slope_table_get(t, 1.0, 6, &a);
    ocean_slope_table_get(t, 0.1, 6, &b);
    assert_true(b.mss_carried > a.mss_carried && a.mss_carried > all.mss_carried);
    assert_true(all.mss_carried == all.mss_total - all.mss_resolved ||
                fabs(all.mss_carried - (all.mss_total - all.mss_resolved)) < 1e-12);
    ocean_slope_table_destroy(t);
    ocean_destroy(o);
}

/* The resolved slope variance is what an evaluated field really holds:
 * the mean of slope_x^2, slope_z^2, slope_x slope_z over the grid of an
 * evaluation with the same cutoff (a random realisation of ~10^4 modes,
 * so a few per cent). */
static void resolved_matches_field(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.threads = 1;
    p.sea.wind_dir_deg = 30.0;
    ocean *o = make_ocean(&p);
    ocean_frame *f;
    assert_int_equal(ocean_frame_create(o, &f), OCEAN_OK);
    ocean_slope_table *t;
    assert_int_equal(ocean_slope_table_create(o, NULL, &t, NULL, 0), OCEAN_OK);
    const double kcs[] = {INFINITY, 0.3, 0.08};
    for (int i = 0; i < 3; i++) {
        ocean_request r;
        ocean_request_all(&r, OCEAN_FX_NORMALS);
        r.cutoff_k = kcs[i];
        r.foam_map = 0;
        assert_int_equal(ocean_evaluate(o, 12.5, &r, f), OCEAN_OK);
        const ocean_field *fd = ocean_frame_field(f, 0);
        size_t nn = (size_t)fd->n * fd->n;
        double xx = 0, zz = 0, xz = 0;
        for (size_t j = 0; j < nn; j++) {
            xx += (double)fd->slope_x[j] * fd->slope_x[j];
            zz += (double)fd->slope_z[j] * fd->slope_z[j];
            xz += (double)fd->slope_x[j] * fd->slope_z[j];
        }
        xx /= nn;
        zz /= nn;
        xz /= nn;
        ocean_slope_stats s;
        assert_int_equal(ocean_slope_table_get(t, kcs[i], 6, &s), OCEAN_OK);
        print_message("kc %g: field mss_x %.5f z %.5f xz %.5f; resolved %.5f %.5f %.5f\n", kcs[i],
                      xx, zz, xz, s.resolved.mss_x, s.resolved.mss_z, s.resolved.mss_xz);
        assert_rel(xx, s.resolved.mss_x, 0.05);
        assert_rel(zz, s.resolved.mss_z, 0.05);
        /* The cross term is small beside the diagonal: its tolerance is a
         * tenth of sqrt(mss_x mss_z). */
        assert_true(fabs(xz - s.resolved.mss_xz) <= 0.1 * sqrt(s.resolved.mss_x * s.resolved.mss_z));
    }
    ocean_slope_table_destroy(t);
    ocean_frame_destroy(f);
    ocean_destroy(o);
}

/* The near field's resolved height variance is ocean_gerstner_variance
 * with the same cutoff; unfiltered, the near field and the FFT together
 * leave no gap (the tail's sea part is then only the FFT square's corners,
 * empty with k_max on the Nyquist circle, and the band above the set). */
static void near_field_share(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.threads = 1;
    p.n = 64;
    p.patch_m = 200.0;
    p.k_max = M_PI * p.n / p.patch_m;
    ocean *o = make_ocean(&p);
    double khi;
    ocean_cascade_band(o, 0, NULL, NULL, &khi);
    ocean_gerstner_params gp;
    ocean_gerstner_params_default(&gp);
    gp.sea = p.sea;
    gp.count = 128;
    gp.k_lo = khi;
    gp.k_hi = OCEAN_SLOPE_K_GRAVITY;
    ocean_gerstner *g;
    char err[256];
    assert_int_equal(ocean_gerstner_create(&gp, &g, err, sizeof err), OCEAN_OK);
    ocean_slope_table *t;
    assert_int_equal(ocean_slope_table_create(o, g, &t, NULL, 0), OCEAN_OK);
    const double kcs[] = {INFINITY, 5.0, 1.0};
    for (int i = 0; i < 3; i++) {
        ocean_slope_stats s;
        assert_int_equal(ocean_slope_table_get(t, kcs[i], 6, &s), OCEAN_OK);
        ocean_filter_cutoff c = {.k = s.k_cut, .hz = NAN, .low_boost = 1.0, .order = 6};
        assert_rel(s.near_resolved.energy, ocean_gerstner_variance(g, &c), 1e-9);
        assert_rel(s.near_resolved.energy + s.near_carried.energy, ocean_gerstner_variance(g, NULL),
                   1e-9);
    }
    ocean_slope_stats s;
    ocean_slope_table_get(t, INFINITY, 6, &s);
    assert_rel(s.k_sim_top, OCEAN_SLOPE_K_GRAVITY, 1e-12);
    assert_rel(s.k_short, OCEAN_SLOPE_K_GRAVITY, 1e-12);
    /* The sea part of the tail is only the thin ring of cells straddling
     * the Nyquist circle: well under 1 % of the slope. */
    assert_true(s.tail_sea.mss_x + s.tail_sea.mss_z < 0.01 * s.mss_total);
    ocean_slope_table_destroy(t);
    ocean_gerstner_destroy(g);
    ocean_destroy(o);
}

static void hostile(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.threads = 1;
    p.n = 16;
    ocean *o = make_ocean(&p);
    ocean_slope_stats s;
    assert_int_equal(ocean_slope_variance(NULL, NULL, 1.0, 6, &s), OCEAN_EINVAL);
    assert_int_equal(ocean_slope_variance(o, NULL, NAN, 6, &s), OCEAN_EINVAL);
    assert_int_equal(ocean_slope_variance(o, NULL, -1.0, 6, &s), OCEAN_EINVAL);
    assert_int_equal(ocean_slope_variance(o, NULL, 1.0, 0, &s), OCEAN_EINVAL);
    assert_int_equal(ocean_slope_variance(o, NULL, 1.0, 65, &s), OCEAN_EINVAL);
    assert_int_equal(ocean_slope_variance(o, NULL, 1.0, 6, NULL), OCEAN_EINVAL);
    ocean_slope_table *t = (ocean_slope_table *)&p;
    assert_int_equal(ocean_slope_table_create(NULL, NULL, &t, NULL, 0), OCEAN_EINVAL);
    assert_null(t);
    ocean_slope_table_destroy(NULL);
    /* A calm sea: every moment 0, nothing NaN. */
    ocean_destroy(o);
    p.sea.wind_u10 = 0.0;
    o = make_ocean(&p);
    assert_int_equal(ocean_slope_variance(o, NULL, 0.5, 6, &s), OCEAN_OK);
    assert_true(s.mss_total == 0.0 && s.total.energy == 0.0);
    ocean_destroy(o);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(cox_munk_helpers),
        cmocka_unit_test(elfouhaily_bh),
        cmocka_unit_test(cox_munk_default),
        cmocka_unit_test(cox_munk_scenes),
        cmocka_unit_test(partition_and_consistency),
        cmocka_unit_test(resolved_matches_field),
        cmocka_unit_test(near_field_share),
        cmocka_unit_test(hostile),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
