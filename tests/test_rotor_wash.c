/*
 * test_rotor_wash.c - the water under a rotorcraft's downwash
 * (sim/rotor_wash.h) against the laws it rests on, measured on the heights
 * rotor_wash_add returns for a table of entities:
 *  - Archimedes: the dent a hovering rotor holds in still water displaces
 *    the water whose weight is the thrust pressing on it (the slipstream's
 *    momentum flux, the rotorcraft's weight in hover), within 0.5 %;
 *  - Cauchy-Poisson (Lamb 1932, Hydrodynamics, art. 255): the rings a rotor
 *    sends out when it comes have, at distance r a time tau later, the
 *    phase g tau^2 / (4 r): successive zero crossings differ by pi in it,
 *    within 5 %, near the footprint (where the integral is tabulated) and
 *    far (its stationary-phase form);
 *  - the reading of the ring integral within ROTOR_RING_ERROR of the
 *    integral summed by quadrature, everywhere;
 *  - a rotor hovering since long holds the dent alone; out of the model's
 *    reach (above 4 diameters, faster than twice the hover's induced
 *    velocity) it adds nothing; hard cases stay finite and bounded.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "entity.h"
#include "rotor_wash.h"

#define G 9.81
#define D_ROTOR 16.0      /* a medium helicopter's rotor */

static rotor_wash *wash;

static int setup(void **state)
{
    (void)state;
    return rotor_wash_create(&wash) == OCEAN_OK ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    rotor_wash_destroy(wash);
    return 0;
}

/* A table holding one rotorcraft of diameter D hovering (or moving at
 * speed along +x, climbing at `climb` m/s for its first 5 s) at height h
 * from sim time t0. */
static ocean_entities *climbing_rotor(double D, double h, double speed, double climb, double t0)
{
    ocean_entities *e;
    assert_int_equal(ocean_entities_create(8, OCEAN_ENTITY_HOLD_S, 256, &e, NULL, 0), OCEAN_OK);
    ocean_entity_desc d = {.id = 7, .kind = OCEAN_ENTITY_ROTORCRAFT, .length_m = D};
    for (int i = 0; i < (speed > 0 || climb != 0 ? 60 : 1); i++) {
        ocean_track_sample s = {.t = t0 + i, .x = speed * i, .z = 0, .altitude_m = h + climb * fmin(i, 5),
                                .speed = speed};
        assert_int_equal(ocean_entities_enter(e, &d, &s, t0, NULL, 0), OCEAN_OK);
    }
    return e;
}

static ocean_entities *one_rotor(double D, double h, double speed, double t0)
{
    return climbing_rotor(D, h, speed, 0, t0);
}

static void heights_at(const ocean_entities *e, double t, const double *xz, size_t n, wake_sample *out)
{
    memset(out, 0, sizeof *out * n);
    assert_int_equal(rotor_wash_add(wash, e, t, xz, n, out), OCEAN_OK);
}

static void ring_read_within_bound(void **state)
{
    (void)state;
    double worst = 0, wr = 0, ws = 0;
    for (double rho = 0; rho < 30; rho += 0.73)
        for (double s = 0; s < 80; s += 0.91) {
            double err = fabs(rotor_wash_ring(wash, rho, s, NULL, NULL) - rotor_wash_ring_exact(rho, s));
            if (err > worst) worst = err, wr = rho, ws = s;
        }
    /* across the border of the table, where the stationary phase is poorest */
    for (double rho = 9.5; rho < 16; rho += 0.13)
        for (double s = 0; s < 60; s += 0.77) {
            double err = fabs(rotor_wash_ring(wash, rho, s, NULL, NULL) - rotor_wash_ring_exact(rho, s));
            if (err > worst) worst = err, wr = rho, ws = s;
        }
    printf("ring reading: largest error %.2e (bound %.1e) at rho %.2f, s %.2f\n", worst, ROTOR_RING_ERROR, wr, ws);
    assert_true(worst <= ROTOR_RING_ERROR);
    assert_true(worst > 0);   /* the check reads two different sums */
}

static void dent_weighs_the_thrust(void **state)
{
    (void)state;
    ocean_entities *e = one_rotor(D_ROTOR, 10, 0, 100);
    /* 0.25 m cells over 80 m x 80 m around it, 200 s after it came */
    enum { N = 320 };
    static double xz[2 * N * N];
    static wake_sample w[N * N];
    for (int i = 0; i < N; i++)
        for (int j = 0; j < N; j++) xz[2 * (i * N + j)] = -40 + 0.25 * (j + 0.5), xz[2 * (i * N + j) + 1] = -40 + 0.25 * (i + 0.5);
    heights_at(e, 300, xz, (size_t)N * N, w);
    double volume = 0, deepest = 0;
    for (int i = 0; i < N * N; i++) volume -= w[i].height * 0.0625, deepest = fmin(deepest, w[i].height);
    double thrust = ROTOR_DISK_LOADING * M_PI * D_ROTOR * D_ROTOR / 4;
    double weight = ROTOR_RHO_WATER * G * volume;
    printf("hover at 10 m, 16 m rotor: dent %.4f m deep, displaced water weighs %.0f N, thrust %.0f N\n", deepest,
           weight, thrust);
    assert_true(fabs(weight / thrust - 1) < 0.005);
    double head, c;
    rotor_wash_footprint(D_ROTOR, 10, 0, &head, &c);
    double centre[2] = {0, 0};
    wake_sample at;
    heights_at(e, 300, centre, 1, &at);
    assert_true(fabs(at.height + head) < 1e-12);   /* the dent alone: no ring is left */
    assert_true(at.error == 0);
    ocean_entities_destroy(e);
}

/* The zero crossings of the rings along +x, tau after the step that made
 * them, against the phase g tau^2 / (4 r): the half-waves whose height is
 * at least `least` of the train's largest (the stationary phase is the
 * rings' law where the phase is large and the spectrum varies slowly over
 * a wave's band: the short waves trailing the train lag it, 13-45 % off pi
 * 15 s after the step, where they are 0.4-0.8 of the largest).  Returns the
 * largest phase step off pi, relative; the half-waves counted into *pairs
 * and those within the table (rho <= 10) into *near. */
static double ring_phase_error(double tau, double least, int *pairs, int *near)
{
    const double t0 = 100;
    ocean_entities *e = one_rotor(D_ROTOR, 10, 0, t0);
    int64_t k = (int64_t)floor(t0 / ROTOR_STEP_S);
    if ((double)k * ROTOR_STEP_S < t0) k++;
    enum { N = 6000 };
    static double xz[2 * N], r0[N], peak[N];
    static wake_sample w[N];
    for (int i = 0; i < N; i++) xz[2 * i] = 20 + 0.05 * i, xz[2 * i + 1] = 0;
    heights_at(e, (double)k * ROTOR_STEP_S + tau, xz, N, w);
    double head, c, worst = 0, top = 0;
    rotor_wash_footprint(D_ROTOR, 10, 0, &head, &c);
    int m = 0;
    double p = 0;
    for (int i = 1; i < N; i++) {
        p = fmax(p, fabs(w[i].height));
        if ((w[i - 1].height < 0) == (w[i].height < 0)) continue;
        r0[m] = xz[2 * (i - 1)] + 0.05 * w[i - 1].height / (w[i - 1].height - w[i].height);
        peak[m++] = p;
        top = fmax(top, p);
        p = 0;
    }
    *pairs = *near = 0;
    for (int i = 1; i < m; i++) {
        if (peak[i] < least * top) continue;
        double dphi = G * tau * tau / 4 * (1 / r0[i - 1] - 1 / r0[i]);
        worst = fmax(worst, fabs(dphi / M_PI - 1));
        (*pairs)++;
        *near += r0[i] <= 10 * c;
    }
    printf("rings %.0f s after a 16 m rotor came to 10 m (head %.3f m): %d half-waves over %.1f of the "
           "largest (%.4f m), %d within the table, largest phase step off pi by %.2f %%\n",
           tau, head, *pairs, least, top, *near, 100 * worst);
    ocean_entities_destroy(e);
    return worst;
}

static void rings_follow_cauchy_poisson(void **state)
{
    (void)state;
    int pairs, near;
    /* early: the train's crest within 10 footprint radii, read from the table */
    assert_true(ring_phase_error(15, 0.9, &pairs, &near) < 0.05);
    assert_true(pairs >= 1 && near >= 1);
    /* later: out in the stationary-phase region */
    assert_true(ring_phase_error(40, 0.1, &pairs, &near) < 0.05);
    assert_true(pairs >= 4 && near == 0);
}

static void out_of_reach_adds_nothing(void **state)
{
    (void)state;
    double pts[6] = {0, 0, 30, 0, 0, -50};
    wake_sample w[3];
    ocean_entities *high = one_rotor(D_ROTOR, 4 * D_ROTOR + 1, 0, 100);
    heights_at(high, 130, pts, 3, w);
    for (int i = 0; i < 3; i++) assert_true(w[i].height == 0 && w[i].dhdx == 0 && w[i].error == 0);
    ocean_entities_destroy(high);
    ocean_entities *fast = one_rotor(D_ROTOR, 10, 30, 100);
    heights_at(fast, 130, pts, 3, w);
    for (int i = 0; i < 3; i++) assert_true(w[i].height == 0);
    ocean_entities_destroy(fast);
    /* a ship is not a rotor */
    ocean_entities *e;
    assert_int_equal(ocean_entities_create(8, OCEAN_ENTITY_HOLD_S, 256, &e, NULL, 0), OCEAN_OK);
    ocean_entity_desc d = {.id = 1, .kind = OCEAN_ENTITY_SHIP, .length_m = 100, .beam_m = 15, .draught_m = 5};
    ocean_track_sample s = {.t = 100, .speed = 0};
    assert_int_equal(ocean_entities_enter(e, &d, &s, 100, NULL, 0), OCEAN_OK);
    heights_at(e, 110, pts, 3, w);
    for (int i = 0; i < 3; i++) assert_true(w[i].height == 0);
    double bad[2] = {NAN, 0};
    assert_int_equal(rotor_wash_add(wash, e, 110, bad, 1, w), OCEAN_EINVAL);
    ocean_entities_destroy(e);
    ocean_entities *r = one_rotor(D_ROTOR, 10, 0, 100);
    assert_int_equal(rotor_wash_add(wash, r, 110, bad, 1, w), OCEAN_EINVAL);
    assert_int_equal(rotor_wash_add(wash, r, INFINITY, pts, 1, w), OCEAN_EINVAL);
    ocean_entities_destroy(r);
}

/* Hard cases: the smallest and largest rotors, on the water and at the
 * edge of reach, moving, at t of 1e8 s: every height finite and within
 * three heads of the dent (the rings never outgrow the step that sent
 * them by more than their sum), slopes finite. */
static void hard_cases_stay_bounded(void **state)
{
    (void)state;
    static const double cases[][4] = {{1, 0, 0, 100},  {40, 0, 0, 100},    {40, 150, 5, 100}, {16, 10, 8, 1e8},
                                      {16, 10, 20, 100}, {1, 3.5, 11, 1e8}};
    enum { N = 200 };
    double xz[2 * N];
    wake_sample w[N];
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        const double *k = cases[c];
        ocean_entities *e = one_rotor(k[0], k[1], k[2], k[3]);
        double head, rc, worst = 0;
        rotor_wash_footprint(k[0], k[1], 0, &head, &rc);
        for (double dt = 0.1; dt < 90; dt += 7.3) {
            for (int i = 0; i < N; i++) xz[2 * i] = k[2] * dt + (i - N / 2) * rc * 0.13, xz[2 * i + 1] = (i % 7) * rc * 0.3;
            heights_at(e, k[3] + dt, xz, N, w);
            for (int i = 0; i < N; i++) {
                assert_true(isfinite(w[i].height) && isfinite(w[i].dhdx) && isfinite(w[i].dhdz) && isfinite(w[i].dhdt));
                worst = fmax(worst, fabs(w[i].height));
            }
        }
        printf("rotor %g m at %g m, %g m/s, t %g: head %.4f m, largest |height| %.4f m\n", k[0], k[1], k[2], k[3],
               head, worst);
        assert_true(worst <= 3 * head + 1e-12);
        ocean_entities_destroy(e);
    }
}

/* The slopes and rate of change are the height's own derivatives: in the
 * rings, 15 s after the rotor came, and on the dent of one cruising. */
static void slopes_match_heights(void **state)
{
    (void)state;
    static const double cases[2][5] = {{0, 115.05, 45, 12}, {4, 125.05, 101, 2}};   /* speed, t, x, z */
    for (int c = 0; c < 2; c++) {
        ocean_entities *e = one_rotor(D_ROTOR, 10, cases[c][0], 100);
        const double t = cases[c][1], x = cases[c][2], z = cases[c][3], h = 1e-3;
        double p[10] = {x, z, x + h, z, x - h, z, x, z + h, x, z - h};
        wake_sample w[5], a, b;
        heights_at(e, t, p, 5, w);
        double gx = (w[1].height - w[2].height) / (2 * h), gz = (w[3].height - w[4].height) / (2 * h);
        heights_at(e, t + h, p, 1, &a);
        heights_at(e, t - h, p, 1, &b);
        double gt = (a.height - b.height) / (2 * h);
        printf("at (%g, %g), t %g: height %.5f, dh/dx %.5f (differences %.5f), dh/dz %.5f (%.5f), dh/dt %.5f (%.5f)\n",
               x, z, t, w[0].height, w[0].dhdx, gx, w[0].dhdz, gz, w[0].dhdt, gt);
        double scale = fabs(gx) + fabs(gz);
        assert_true(scale > 2e-4);   /* a slope to check */
        assert_true(fabs(w[0].dhdx - gx) < 0.1 * scale + 1e-5);
        assert_true(fabs(w[0].dhdz - gz) < 0.1 * scale + 1e-5);
        assert_true(fabs(w[0].dhdt - gt) < 0.1 * fabs(gt) + 2e-4);
        ocean_entities_destroy(e);
    }
}

/* A rotor cruising level sends no rings (its dent moves with it, nothing
 * else: 60 m around it the water is still); one coming down from 60 to
 * 10 m in 5 s sends them (its head grows from 3.6 to 7.0 cm, 1.4 mm a
 * lattice step), and they outlast its descent. */
static void changes_send_rings(void **state)
{
    (void)state;
    double far[4] = {0, 60, 150, 60};
    wake_sample w[2];
    ocean_entities *level = one_rotor(D_ROTOR, 10, 8, 100);
    double worst = 0;
    for (double t = 170; t < 200; t += 1.3) {   /* the rings of its coming have faded by 170 s */
        double p[4] = {8 * fmin(t - 100, 70), 60, 8 * fmin(t - 100, 70) - 60, 0};
        heights_at(level, t, p, 2, w);
        worst = fmax(worst, fmax(fabs(w[0].height), fabs(w[1].height)));
    }
    printf("cruising level at 8 m/s: largest height 60 m from it %.2e m\n", worst);
    assert_true(worst < 1e-12);
    ocean_entities_destroy(level);
    ocean_entities *down = climbing_rotor(D_ROTOR, 60, 0, -10, 100);
    ocean_entities *still = one_rotor(D_ROTOR, 10, 0, 100);
    double peak = 0;
    for (double t = 115; t < 145; t += 0.7) {
        wake_sample ws[2];
        heights_at(down, t, far, 2, w);
        heights_at(still, t, far, 2, ws);
        peak = fmax(peak, fmax(fabs(w[0].height - ws[0].height), fabs(w[1].height - ws[1].height)));
    }
    printf("descending from 60 to 10 m in 5 s: beside one that hovered at 10 m, 10-40 s later, 60-160 m out, "
           "rings differ by up to %.4f m\n", peak);
    assert_true(peak > 1e-3);
    ocean_entities_destroy(down);
    ocean_entities_destroy(still);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(ring_read_within_bound),
        cmocka_unit_test(dent_weighs_the_thrust),
        cmocka_unit_test(rings_follow_cauchy_poisson),
        cmocka_unit_test(out_of_reach_adds_nothing),
        cmocka_unit_test(hard_cases_stay_bounded),
        cmocka_unit_test(slopes_match_heights),
        cmocka_unit_test(changes_send_rings),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
