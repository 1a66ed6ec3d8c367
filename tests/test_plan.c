/*
 * test_plan.c - the scene plan (sim/ocean_plan.h, issue 13 item 6): seas
 * whose peak the patch cannot hold or whose waves exceed the depth-limited
 * breaking height are refused, with the numbers; seas that are possible but
 * poorly served are warned about.  Check values come from the published
 * laws: the Pierson-Moskowitz peak (1964), McCowan (1894), Miche (1944).
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "ocean.h"
#include "ocean_conf.h"
#include "ocean_plan.h"
#include "spectrum.h"

static ocean_result try_create(const ocean_params *p, char *msg, size_t len)
{
    ocean *o = NULL;
    msg[0] = '\0';
    ocean_result r = ocean_create(p, &o, msg, len);
    ocean_destroy(o);
    return r;
}

static int has_item(const ocean_plan *plan, ocean_plan_level level, const char *check)
{
    for (int i = 0; i < plan->count; i++)
        if (plan->item[i].level == level && strcmp(plan->item[i].check, check) == 0)
            return 1;
    return 0;
}

/* A fully developed sea (Pierson & Moskowitz 1964) peaks at
 * w_p = 0.877 g / U19.5, U19.5 = 1.026 U10, so its deep-water dominant
 * wavelength is 2 pi g / w_p^2 and its Hs = 0.21 U19.5^2 / g.  Wind 100 m/s:
 * 8.8 km and 225 m - on the default 1 km patch the grid held Hs 33 m,
 * silently.  Refused at load, accepted once the patch holds the peak. */
static void test_peak_beyond_patch_refused(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.sea.spectrum = OCEAN_SPECTRUM_PM;
    p.n = 32;
    const double winds[] = {100.0, 35.0, 10.0};
    for (int i = 0; i < 3; i++) {
        double u195 = 1.026 * winds[i], wp = 0.877 * OCEAN_G / u195;
        double lp = 2.0 * M_PI * OCEAN_G / (wp * wp), hs = 0.21 * u195 * u195 / OCEAN_G;
        p.sea.wind_u10 = winds[i];
        char msg[512];
        /* 5 % either side of the published peak wavelength */
        p.patch_m = 0.95 * lp;
        assert_int_equal(try_create(&p, msg, sizeof msg), OCEAN_EINVAL);
        double got_l = 0.0, got_hs = 0.0;
        const char *a = strstr(msg, "dominant wavelength"), *b = strstr(msg, "Hs ");
        if (!a || !b || sscanf(a, "dominant wavelength %lf", &got_l) != 1 ||
            sscanf(b, "Hs %lf", &got_hs) != 1)
            fail_msg("wind %g: refusal '%s' lacks the numbers", winds[i], msg);
        if (fabs(got_l - lp) > 0.02 * lp || fabs(got_hs - hs) > 0.02 * hs)
            fail_msg("wind %g: refusal says %g m, Hs %g m; published %g m, %g m", winds[i], got_l,
                     got_hs, lp, hs);
        p.patch_m = 1.05 * lp;
        if (try_create(&p, msg, sizeof msg) != OCEAN_OK)
            fail_msg("wind %g, patch %g m: %s", winds[i], p.patch_m, msg);
    }
    /* The loaders refuse the same way, naming the file. */
    char err[512];
    const char *text = "sea.wind = 100\n";
    assert_int_equal(ocean_conf_load_string("in.conf", text, strlen(text), &p, err, sizeof err),
                     OCEAN_EINVAL);
    assert_non_null(strstr(err, "in.conf"));
    assert_non_null(strstr(err, "exceeds the 1000 m patch"));
}

/* Depth-limited breaking: H_b = min(0.78 d (McCowan 1894), 0.142 L
 * tanh(k d) (Miche 1944)), L the peak wavelength at depth d.  A TMA sea
 * is refused exactly when its Hs exceeds H_b, and warned about when the
 * largest of ~1000 Rayleigh waves, 1.86 Hs (Longuet-Higgins 1952), does. */
static void test_breaking_height(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.n = 32;
    p.patch_m = 500.0;
    p.sea.spectrum = OCEAN_SPECTRUM_TMA;
    p.sea.wind_u10 = 10.0;
    p.sea.fetch_m = 1e5;
    const double depths[] = {0.01, 0.1, 0.5, 1.0, 1.5, 2.0, 3.0, 10.0};
    int refused = 0, warned = 0, clean = 0;
    for (int i = 0; i < 8; i++) {
        double d = depths[i];
        p.sea.depth_m = d;
        double hs = ocean_spectrum_hs(&p.sea);
        double kp = ocean_wavenumber(ocean_spectrum_peak(&p.sea), d);
        double hb = fmin(0.78 * d, 0.142 * (2.0 * M_PI / kp) * tanh(kp * d));
        char msg[512];
        ocean_result r = try_create(&p, msg, sizeof msg);
        ocean_plan plan;
        ocean_plan_init(&plan);
        ocean_plan_params(&p, &plan);
        if (hs > hb) {
            if (r != OCEAN_EINVAL || !strstr(msg, "breaking height"))
                fail_msg("depth %g: Hs %.3g > H_b %.3g but '%s'", d, hs, hb, msg);
            double got;
            const char *a = strstr(msg, "breaking height ");
            assert_true(a && sscanf(a, "breaking height %lf", &got) == 1);
            if (fabs(got - hb) > 0.01 * hb + 1e-4)
                fail_msg("depth %g: message says H_b %g m, published %g m", d, got, hb);
            /* the depth it suggests is accepted when typed back (Hs / 0.78
             * at the refused depth was not: TMA's Hs grows with depth) */
            const char *u = strstr(msg, "use sea.depth >= ");
            double dd;
            assert_true(u && sscanf(u, "use sea.depth >= %lf", &dd) == 1);
            ocean_params q = p;
            q.sea.depth_m = dd;
            char msg2[512];
            if (try_create(&q, msg2, sizeof msg2) != OCEAN_OK)
                fail_msg("depth %g: suggested sea.depth >= %g, which is refused: %s", d, dd, msg2);
            /* and it is the least such depth, to the 3 digits printed */
            q.sea.depth_m = dd * 0.99;
            assert_int_equal(try_create(&q, msg2, sizeof msg2), OCEAN_EINVAL);
            refused++;
        } else {
            if (r != OCEAN_OK)
                fail_msg("depth %g: Hs %.3g <= H_b %.3g refused: %s", d, hs, hb, msg);
            int w = has_item(&plan, OCEAN_PLAN_WARN, "breaking");
            assert_int_equal(w, 1.86 * hs > hb);
            warned += w;
            clean += !w;
        }
    }
    /* the sweep crosses all three regimes (TMA at 1 cm refused among them) */
    assert_true(refused > 0 && warned > 0 && clean > 0);
    p.sea.depth_m = 0.01;
    char err[512];
    const char *scene = "scene.name = x\nscene.effects = height\nsea.spectrum = tma\nsea.depth = 0.01\n";
    ocean_params base;
    ocean_params_default(&base);
    ocean_scene sc;
    assert_int_equal(ocean_conf_scene_load_string("s.conf", scene, strlen(scene), &base, &sc, err,
                                                  sizeof err),
                     OCEAN_EINVAL);
    assert_non_null(strstr(err, "McCowan"));
}

/* A sea the plan allows but the grid does not hold: warned, with the
 * numbers (TMA at 2 m depth peaks at 27 m, shorter than a 1000 m / 64
 * grid's 31 m). */
static void test_grid_hs_warning(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.n = 64;
    p.sea.spectrum = OCEAN_SPECTRUM_TMA;
    p.sea.depth_m = 2.0;
    ocean *o = NULL;
    char msg[512];
    assert_int_equal(ocean_create(&p, &o, msg, sizeof msg), OCEAN_OK);
    ocean_plan plan;
    ocean_plan_init(&plan);
    ocean_plan_ocean(o, NULL, &plan);
    assert_true(has_item(&plan, OCEAN_PLAN_WARN, "peak"));
    ocean_destroy(o);
    /* n = 1024 holds it: no warning */
    p.n = 1024;
    assert_int_equal(ocean_create(&p, &o, msg, sizeof msg), OCEAN_OK);
    ocean_plan_init(&plan);
    ocean_plan_ocean(o, NULL, &plan);
    if (plan.count)
        fail_msg("unexpected: %s", plan.item[0].text);
    ocean_destroy(o);
    /* ocean.k_max stops the grid first: the warning names it, not n (it
     * said the waves ran down to the grid's 7.81 m and advised a larger
     * patch, where k_max had cut everything under 126 m) */
    ocean_params_default(&p);
    p.k_max = 0.05;
    assert_int_equal(ocean_create(&p, &o, msg, sizeof msg), OCEAN_OK);
    ocean_plan_init(&plan);
    ocean_plan_ocean(o, NULL, &plan);
    assert_true(has_item(&plan, OCEAN_PLAN_WARN, "peak"));
    const char *t = plan.item[plan.count - 1].text;
    if (!strstr(t, "down to 126 m (ocean.k_max 0.05 rad/m)") || !strstr(t, "raise ocean.k_max"))
        fail_msg("k_max 0.05: %s", t);
    ocean_destroy(o);
}

/* The near field's plan: an empty band is said, and nothing about the
 * spacing (the daemon's to say when a layout-0 client subscribes at one too
 * coarse: the default 2 m start once warned on every `make run`). */
static void test_near_field_warnings(void **state)
{
    (void)state;
    ocean_params p;
    ocean_params_default(&p);
    p.n = 32;
    ocean *o = NULL;
    char msg[512];
    assert_int_equal(ocean_create(&p, &o, msg, sizeof msg), OCEAN_OK);
    ocean_plan plan;
    /* the shipped 0.1 m .. 0.42 m band */
    ocean_plan_serving sv = {1, 2.0 * M_PI / 0.42, 2.0 * M_PI / 0.1};
    ocean_plan_init(&plan);
    ocean_plan_ocean(o, &sv, &plan);
    assert_false(has_item(&plan, OCEAN_PLAN_WARN, "near"));
    /* an empty band is said, not silently dropped */
    sv.near_k_lo = sv.near_k_hi;
    ocean_plan_init(&plan);
    ocean_plan_ocean(o, &sv, &plan);
    assert_true(has_item(&plan, OCEAN_PLAN_WARN, "near"));
    assert_non_null(strstr(plan.item[plan.count - 1].text, "band is empty"));
    /* no near field asked: nothing to say */
    sv.near_field = 0;
    ocean_plan_init(&plan);
    ocean_plan_ocean(o, &sv, &plan);
    assert_false(has_item(&plan, OCEAN_PLAN_WARN, "near"));
    ocean_destroy(o);
}

/* The shipped scenes pass the plan with nothing to refuse. */
static void test_shipped_scenes_pass(void **state)
{
    (void)state;
    const char *scenes[] = {"config/scenes/flight.conf", "config/scenes/harbour.conf",
                            "config/scenes/ship-bridge.conf", "config/scenes/storm.conf"};
    for (int i = 0; i < 4; i++) {
        ocean_params base;
        ocean_params_default(&base);
        ocean_scene sc;
        char err[512];
        if (ocean_conf_scene_load(scenes[i], &base, &sc, err, sizeof err) != OCEAN_OK)
            fail_msg("%s: %s", scenes[i], err);
        ocean_plan plan;
        ocean_plan_init(&plan);
        ocean_plan_params(&sc.params, &plan);
        assert_int_equal(ocean_plan_count(&plan, OCEAN_PLAN_REFUSE), 0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_peak_beyond_patch_refused),
        cmocka_unit_test(test_breaking_height),
        cmocka_unit_test(test_grid_hs_warning),
        cmocka_unit_test(test_near_field_warnings),
        cmocka_unit_test(test_shipped_scenes_pass),
    };
    return cmocka_run_group_tests_name("plan", tests, NULL, NULL);
}
