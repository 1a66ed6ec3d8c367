/*
 * test_foam.c - whitecap foam (sim/foam.h): coverage measured on evaluated
 * fields and on tile-like samples against Monahan & O'Muircheartaigh 1980
 * at U10 = 8, 12, 16, 20, 26 m/s (the model's one calibration constant was
 * fitted at 12 m/s only), coverage kept by filtered evaluations, the
 * ramp's closed-form mean against a Monte-Carlo Gaussian, the breaking
 * index against the downward acceleration of the same waves, hostile
 * arguments.
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

#include "foam.h"
#include "ocean.h"
#include "ocean_conf.h"
#include "spectrum.h"

/* Monahan & O'Muircheartaigh 1980 (JPO 10, 2094, eq. 5), percent / 100. */
static double monahan(double u10)
{
    return 3.84e-6 * pow(u10, 3.41);
}

static int within_factor(double got, double want, double f)
{
    return got >= want / f && got <= want * f;
}

static void monahan_and_target(void **state)
{
    (void)state;
    /* Monahan at 10 m/s: 3.84e-6 * 10^3.41 = 0.986 %. */
    assert_true(fabs(monahan(10.0) - 9.863e-3) < 1e-5);
    assert_true(fabs(ocean_foam_monahan(10.0) - monahan(10.0)) < 1e-15);
    /* The calibration point itself. */
    assert_true(fabs(ocean_foam_coverage_target(OCEAN_FOAM_CALIBRATION_U10) / monahan(12.0) - 1.0) <
                1e-3);
    const double winds[] = {8.0, 16.0, 20.0, 26.0};
    for (int i = 0; i < 4; i++)
        assert_true(within_factor(ocean_foam_coverage_target(winds[i]), monahan(winds[i]), 2.0));
    assert_true(ocean_foam_coverage_target(0.0) == 0.0);
    assert_true(ocean_foam_coverage_target(NAN) == 0.0);
    assert_true(ocean_foam_coverage_target(100.0) <= 0.95);
}

/* A fixed-seed Gaussian (xorshift + Box-Muller): independent of the
 * closed form it checks. */
static uint64_t rng = 88172645463325252ull;
static double uniform01(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return ((rng >> 11) + 0.5) / 9007199254740992.0;
}

static void ramp_mean_and_solve(void **state)
{
    (void)state;
    const double sigmas[] = {0.02, 0.1, 0.3};
    const double ws[] = {0.001, 0.02, 0.25, 0.8};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 4; j++) {
            ocean_foam_map m;
            assert_int_equal(ocean_foam_map_solve(sigmas[i], ws[j], &m), OCEAN_OK);
            assert_true(m.a <= m.b && m.b == OCEAN_FOAM_BETA_BREAK);
            double mean = ocean_foam_map_mean(&m, sigmas[i]);
            /* Active breaking alone may exceed a small target. */
            double active = 0.5 * erfc(OCEAN_FOAM_BETA_BREAK / sigmas[i] / M_SQRT2);
            assert_true(fabs(mean - fmax(ws[j], active)) < 1e-9);
            /* Monte Carlo over 2e5 Gaussian samples. */
            double s = 0.0;
            const int nmc = 200000;
            for (int k = 0; k < nmc; k++) {
                double g = sqrt(-2.0 * log(uniform01())) * cos(2.0 * M_PI * uniform01());
                s += ocean_foam_value(&m, sigmas[i] * g);
            }
            s /= nmc;
            if (!(fabs(s - mean) < 4.0 * sqrt(mean / nmc) + 1e-4))
                fail_msg("sigma %g w %g: Monte Carlo %.5f vs closed form %.5f", sigmas[i], ws[j], s,
                         mean);
        }
    ocean_foam_map m;
    assert_int_equal(ocean_foam_map_solve(0.0, 0.03, &m), OCEAN_OK);
    assert_true(ocean_foam_value(&m, 0.0) == 0.03 && ocean_foam_value(&m, 5.0) == 0.03);
    assert_int_equal(ocean_foam_map_solve(0.1, 0.02, &m), OCEAN_OK);
    assert_true(ocean_foam_value(&m, NAN) == 0.0);
    assert_int_equal(ocean_foam_map_solve(0.1, 0.0, &m), OCEAN_OK);
    assert_true(ocean_foam_value(&m, 10.0) == 0.0);
    assert_int_equal(ocean_foam_map_solve(NAN, 0.1, &m), OCEAN_EINVAL);
    assert_int_equal(ocean_foam_map_solve(-1.0, 0.1, &m), OCEAN_EINVAL);
    assert_int_equal(ocean_foam_map_solve(0.1, 1.0, &m), OCEAN_EINVAL);
    assert_int_equal(ocean_foam_map_solve(0.1, NAN, &m), OCEAN_EINVAL);
    assert_int_equal(ocean_foam_map_solve(0.1, 0.1, NULL), OCEAN_EINVAL);
    const float tile[] = {0.0f, 1.0f, 0.5f, NAN, 2.0f, -1.0f};
    assert_true(fabs(ocean_whitecap_coverage(tile, 6) - 2.5 / 5.0) < 1e-12);
    assert_true(ocean_whitecap_coverage(NULL, 3) == 0.0);
    assert_true(ocean_whitecap_coverage(tile, 0) == 0.0);
}

static void frame_coverage_hostile(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.threads = 1;
    p.n = 16;
    ocean *o = NULL;
    assert_int_equal(ocean_create(&p, &o, NULL, 0), OCEAN_OK);
    ocean_frame *f;
    assert_int_equal(ocean_frame_create(o, &f), OCEAN_OK);
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_HEIGHT);
    assert_int_equal(ocean_evaluate(o, 1.0, &r, f), OCEAN_OK);
    double c = -1.0;
    /* No foam channels: coverage 0, foam 0. */
    assert_int_equal(ocean_whitecap_coverage_frame(f, 0.0, 0.0, 100.0, 8, &c), OCEAN_OK);
    assert_true(c == 0.0);
    assert_true(ocean_frame_foam(f, -1.0, -1.0) == 0.0);
    assert_int_equal(ocean_whitecap_coverage_frame(NULL, 0.0, 0.0, 100.0, 8, &c), OCEAN_EINVAL);
    assert_int_equal(ocean_whitecap_coverage_frame(f, NAN, 0.0, 100.0, 8, &c), OCEAN_EINVAL);
    assert_int_equal(ocean_whitecap_coverage_frame(f, 0.0, INFINITY, 100.0, 8, &c), OCEAN_EINVAL);
    assert_int_equal(ocean_whitecap_coverage_frame(f, 0.0, 0.0, 0.0, 8, &c), OCEAN_EINVAL);
    assert_int_equal(ocean_whitecap_coverage_frame(f, 0.0, 0.0, NAN, 8, &c), OCEAN_EINVAL);
    assert_int_equal(ocean_whitecap_coverage_frame(f, 0.0, 0.0, 100.0, 0, &c), OCEAN_EINVAL);
    assert_int_equal(ocean_whitecap_coverage_frame(f, 0.0, 0.0, 100.0, 4097, &c), OCEAN_EINVAL);
    assert_int_equal(ocean_whitecap_coverage_frame(f, 0.0, 0.0, 100.0, 8, NULL), OCEAN_EINVAL);
    /* Everything filtered: the foam is the uniform target. */
    p.sea.wind_u10 = 15.0;
    ocean_frame_destroy(f);
    ocean_destroy(o);
    assert_int_equal(ocean_create(&p, &o, NULL, 0), OCEAN_OK);
    assert_int_equal(ocean_frame_create(o, &f), OCEAN_OK);
    ocean_request_all(&r, OCEAN_FX_FOAM);
    r.cutoff_k = 0.0;
    assert_int_equal(ocean_evaluate(o, 1.0, &r, f), OCEAN_OK);
    assert_int_equal(ocean_whitecap_coverage_frame(f, 0.0, 0.0, 100.0, 8, &c), OCEAN_OK);
    assert_true(fabs(c - ocean_foam_coverage_target(15.0)) < 1e-12);
    ocean_frame_destroy(f);
    ocean_destroy(o);
}

static ocean *scene_ocean(const char *name, double u10)
{
    ocean_params base;
    char err[512], path[256];
    assert_int_equal(ocean_conf_load("config/oceand.conf", &base, err, sizeof err), OCEAN_OK);
    snprintf(path, sizeof path, "config/scenes/%s.conf", name);
    ocean_scene scene;
    ocean_result r = ocean_conf_scene_load(path, &base, &scene, err, sizeof err);
    if (r != OCEAN_OK)
        print_error("%s\n", err);
    assert_int_equal(r, OCEAN_OK);
    ocean_params p = scene.params;
    p.threads = 1;
    p.sea.wind_u10 = u10;
    ocean *o = NULL;
    assert_int_equal(ocean_create(&p, &o, err, sizeof err), OCEAN_OK);
    return o;
}

/* Coverage of evaluated fields as the daemon's tiles read them
 * (ocean_frame_sample_some, bilinear, on a 512 x 512 grid over the whole
 * largest patch, offset from every cascade's nodes) within a factor 2 of
 * Monahan, unfiltered and with a cutoff that leaves only the long waves;
 * two instants each. */
static void coverage_against_monahan(void **state)
{
    (void)state;
    const char *scenes[] = {"ship-bridge", "storm"};
    const double winds[] = {8.0, 12.0, 16.0, 20.0, 26.0};
    const double cutoffs[] = {INFINITY, 0.08};
    enum { T = 512 };
    static float foam[T * T];
    for (int sc = 0; sc < 2; sc++)
        for (int i = 0; i < 5; i++) {
            ocean *o = scene_ocean(scenes[sc], winds[i]);
            const ocean_params *p = ocean_get_params(o);
            double h = p->patch_m / T;
            ocean_frame *f;
            assert_int_equal(ocean_frame_create(o, &f), OCEAN_OK);
            for (int c = 0; c < 2; c++) {
                ocean_request r;
                ocean_request_all(&r, OCEAN_FX_FOAM);
                r.cutoff_k = cutoffs[c];
                r.foam_map = 0;
                double tile = 0.0, active = 0.0, finest = 0.0;
                const double times[] = {40.0, 1234.5};
                for (int ti = 0; ti < 2; ti++) {
                    assert_int_equal(ocean_evaluate(o, times[ti], &r, f), OCEAN_OK);
                    ocean_field_stats fs;
                    ocean_frame_get_field_stats(f, &fs);
                    finest += 0.5 * fs.foam_coverage;
                    size_t ones = 0;
                    for (int a = 0; a < T; a++)
                        for (int b = 0; b < T; b++) {
                            ocean_point pt;
                            ocean_frame_sample_some(f, 311.37 + h * b, -52.71 + h * a,
                                                    OCEAN_SAMPLE_FOAM, &pt);
                            foam[a * T + b] = (float)pt.foam;
                            if (b == a)
                                assert_true(ocean_frame_foam(f, pt.dxx, pt.dzz) == pt.foam);
                            /* Longuet-Higgins' criterion alone: a_z < -g/2. */
                            ones += -(pt.dxx + pt.dzz) / p->sea.choppiness > 0.5;
                        }
                    double cov = ocean_whitecap_coverage(foam, T * T), cf;
                    assert_int_equal(ocean_whitecap_coverage_frame(f, 311.37, -52.71, p->patch_m, T, &cf),
                                     OCEAN_OK);
                    assert_true(fabs(cf - cov) < 1e-6);
                    tile += 0.5 * cov;
                    active += 0.5 * (double)ones / (T * T);
                }
                double w = monahan(winds[i]);
                print_message("%-11s U10 %4.1f kc %-5g: coverage %.4f, Monahan %.4f (ratio %.2f); "
                              "finest grid %.4f; criterion alone %.5f\n",
                              scenes[sc], winds[i], cutoffs[c], tile, w, tile / w, finest, active);
                if (!within_factor(tile, w, 2.0))
                    fail_msg("%s U10 %g kc %g: coverage %.4f outside a factor 2 of Monahan %.4f",
                             scenes[sc], winds[i], cutoffs[c], tile, w);
            }
            ocean_frame_destroy(f);
            ocean_destroy(o);
        }
}

/* The breaking index is the downward acceleration over g: beta from the
 * foam channels equals -d2(eta)/dt2 / g of the same waves, from the
 * velocity channel's time derivative by central difference (deep water,
 * so w^2 = g k). */
static void beta_is_downward_acceleration(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.threads = 1;
    p.n = 64;
    p.patch_m = 200.0;
    p.sea.choppiness = 1.7;
    ocean *o = NULL;
    assert_int_equal(ocean_create(&p, &o, NULL, 0), OCEAN_OK);
    ocean_frame *f;
    assert_int_equal(ocean_frame_create(o, &f), OCEAN_OK);
    const double t = 50.0, dt = 1e-3;
    double worst = 0.0, scale = 0.0;
    for (int k = 0; k < 20; k++) {
        double x = 13.7 * k, z = -7.1 * k;
        ocean_point a, b, c;
        ocean_reference_point(o, t, x, z, INFINITY, 6, &b);
        ocean_reference_point(o, t - dt, x, z, INFINITY, 6, &a);
        ocean_reference_point(o, t + dt, x, z, INFINITY, 6, &c);
        double az = (c.vel_y - a.vel_y) / (2.0 * dt);
        double beta = -(b.dxx + b.dzz) / p.sea.choppiness;
        worst = fmax(worst, fabs(beta + az / OCEAN_G));
        scale = fmax(scale, fabs(beta));
    }
    assert_true(scale > 1e-3);
    assert_true(worst < 1e-4 * scale + 1e-7);
    ocean_frame_destroy(f);
    ocean_destroy(o);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(monahan_and_target),
        cmocka_unit_test(ramp_mean_and_solve),
        cmocka_unit_test(frame_coverage_hostile),
        cmocka_unit_test(coverage_against_monahan),
        cmocka_unit_test(beta_is_downward_acceleration),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
