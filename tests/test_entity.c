/*
 * test_entity.c - the entity table (sim/entity.h): shapes and samples
 * checked, a track's state at any instant (through every sample, smooth
 * along a turn, on at its last velocity for the hold, then held), the same
 * whatever order the instants are asked in, and refusals that change
 * nothing.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "entity.h"

/* Samples in force from long before every instant asked: the tests of a
 * track's shape; in_force_only_from_its_time tests the in-force rule. */
#define KNOWN (-1e8)

static const ocean_entity_desc frigate = {.id = 7, .kind = OCEAN_ENTITY_SHIP, .length_m = 120, .beam_m = 15,
                                          .draught_m = 5};

static ocean_entities *table(int max, double hold)
{
    ocean_entities *e = NULL;
    assert_int_equal(ocean_entities_create(max, hold, OCEAN_TRACK_KEEP, &e, NULL, 0), OCEAN_OK);
    return e;
}

static ocean_track_sample smp(double t, double x, double z, double heading, double speed)
{
    return (ocean_track_sample){.t = t, .x = x, .z = z, .heading_deg = heading, .speed = speed};
}

static void table_limits(void **state)
{
    (void)state;
    ocean_entities *e = NULL;
    char why[256];
    assert_int_equal(ocean_entities_create(0, 5, 8, &e, why, sizeof why), OCEAN_EINVAL);
    assert_int_equal(ocean_entities_create(4, NAN, 8, &e, why, sizeof why), OCEAN_EINVAL);
    assert_int_equal(ocean_entities_create(4, 5, 1, &e, why, sizeof why), OCEAN_EINVAL);
    assert_int_equal(ocean_entities_create(4, 5, OCEAN_TRACK_KEEP_MAX + 1, &e, why, sizeof why), OCEAN_EINVAL);
    assert_null(e);
    e = table(2, 5);
    assert_int_equal(ocean_entities_add(e, &frigate, why, sizeof why), OCEAN_OK);
    assert_int_equal(ocean_entities_add(e, &frigate, why, sizeof why), OCEAN_ESTATE);
    ocean_entity_desc heli = {.id = 3, .kind = OCEAN_ENTITY_ROTORCRAFT, .length_m = 16};
    assert_int_equal(ocean_entities_add(e, &heli, why, sizeof why), OCEAN_OK);
    ocean_entity_desc third = frigate;
    third.id = 9;
    assert_int_equal(ocean_entities_add(e, &third, why, sizeof why), OCEAN_ETOOBIG);
    assert_non_null(strstr(why, "holds 2"));
    /* in increasing id */
    ocean_entity_desc d;
    assert_int_equal(ocean_entities_count(e), 2);
    assert_int_equal(ocean_entities_get(e, 0, &d), OCEAN_OK);
    assert_int_equal(d.id, 3);
    assert_int_equal(ocean_entities_get(e, 1, &d), OCEAN_OK);
    assert_int_equal(d.id, 7);
    assert_int_equal(ocean_entities_get(e, 2, &d), OCEAN_EINVAL);
    assert_int_equal(ocean_entities_remove(e, 3, KNOWN), OCEAN_OK);
    assert_int_equal(ocean_entities_remove(e, 3, KNOWN), OCEAN_ENOTFOUND);
    assert_int_equal(ocean_entities_add(e, &third, why, sizeof why), OCEAN_OK);
    ocean_entities_destroy(e);
    ocean_entities_destroy(NULL);
}

static void shapes_checked(void **state)
{
    (void)state;
    ocean_entities *e = table(8, 5);
    char why[256];
    ocean_entity_desc bad[] = {
        {.id = 1, .kind = OCEAN_ENTITY_SHIP, .length_m = NAN, .beam_m = 10, .draught_m = 3},
        {.id = 1, .kind = OCEAN_ENTITY_SHIP, .length_m = 600, .beam_m = 10, .draught_m = 3},
        {.id = 1, .kind = OCEAN_ENTITY_SHIP, .length_m = 50, .beam_m = 0, .draught_m = 3},
        {.id = 1, .kind = OCEAN_ENTITY_ROTORCRAFT, .length_m = 80},
        {.id = 1, .kind = OCEAN_ENTITY_ROTORCRAFT, .length_m = 10, .beam_m = 2},
        {.id = 1, .kind = OCEAN_ENTITY_AIRCRAFT, .length_m = 150},
        {.id = 1, .kind = OCEAN_ENTITY_AIRCRAFT, .length_m = 30, .draught_m = 1},
        {.id = 1, .kind = (ocean_entity_kind)5, .length_m = 50, .beam_m = 10, .draught_m = 3},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        why[0] = '\0';
        assert_int_equal(ocean_entities_add(e, &bad[i], why, sizeof why), OCEAN_EINVAL);
        assert_non_null(strstr(why, "entity 1"));
    }
    assert_int_equal(ocean_entities_count(e), 0);
    ocean_entities_destroy(e);
}

/* Samples consistent with a straight run at 10 m/s: the curve between them
 * is that run, on past the last at its velocity for the hold (30 s), then
 * stopped where that left it. */
static void straight_run_and_hold(void **state)
{
    (void)state;
    ocean_entities *e = table(4, 30);
    assert_int_equal(ocean_entities_add(e, &frigate, NULL, 0), OCEAN_OK);
    ocean_entity_state st;
    ocean_track_sample last;
    assert_int_equal(ocean_entities_state(e, 7, 0, &st), OCEAN_ENOTFOUND); /* no track yet */
    assert_int_equal(ocean_entities_last(e, 7, &last, NULL), OCEAN_ENOTFOUND);
    ocean_track_sample a = smp(100, 1e6, -2e6, 90, 10), b = smp(110, 1e6, -2e6 + 100, 90, 10);
    assert_int_equal(ocean_entities_sample(e, 7, &a, KNOWN, NULL, 0), OCEAN_OK);
    assert_int_equal(ocean_entities_sample(e, 7, &b, KNOWN, NULL, 0), OCEAN_OK);
    assert_int_equal(ocean_entities_last(e, 7, &last, NULL), OCEAN_OK);
    assert_true(last.t == 110 && last.z == -2e6 + 100);
    assert_int_equal(ocean_entities_last(e, 8, &last, NULL), OCEAN_ENOTFOUND);
    assert_int_equal(ocean_entities_state(e, 7, 99.9, &st), OCEAN_ENOTFOUND);
    assert_int_equal(ocean_entities_state(e, 7, NAN, &st), OCEAN_EINVAL);
    assert_int_equal(ocean_entities_state(e, 7, 105, &st), OCEAN_OK);
    assert_true(fabs(st.x - 1e6) < 1e-6 && fabs(st.z - (-2e6 + 50)) < 1e-6);
    assert_true(fabs(st.vx) < 1e-9 && fabs(st.vz - 10) < 1e-9 && st.speed == 10 && st.heading_deg == 90);
    assert_false(st.extrapolated);
    assert_int_equal(ocean_entities_state(e, 7, 125, &st), OCEAN_OK);
    assert_true(st.extrapolated && !st.held && fabs(st.z - (-2e6 + 250)) < 1e-6);
    assert_int_equal(ocean_entities_state(e, 7, 1e4, &st), OCEAN_OK);
    assert_true(st.held && st.speed == 0 && st.vz == 0 && fabs(st.z - (-2e6 + 100 + 300)) < 1e-6);
    ocean_entities_destroy(e);
}

/* A turn sampled every 10 s on a circle of 500 m at 8 m/s (9 deg a
 * sample): the curve passes through every sample, stays within 0.1 % of the
 * circle between them, and its heading turns the short way through 360. */
static void turn_is_smooth(void **state)
{
    (void)state;
    ocean_entities *e = table(4, 5);
    assert_int_equal(ocean_entities_add(e, &frigate, NULL, 0), OCEAN_OK);
    const double R = 500, U = 8, w = U / R;
    for (int i = 0; i <= 60; i++) {
        double t = 10.0 * i, a = w * t;
        ocean_track_sample s = smp(t, R * cos(a), R * sin(a), a * 180 / M_PI + 90, U);
        assert_int_equal(ocean_entities_sample(e, 7, &s, KNOWN, NULL, 0), OCEAN_OK);
    }
    double worst = 0;
    int wrapped = 0;
    for (double t = 0; t <= 600; t += 0.37) {
        ocean_entity_state st;
        assert_int_equal(ocean_entities_state(e, 7, t, &st), OCEAN_OK);
        worst = fmax(worst, fabs(hypot(st.x, st.z) - R) / R);
        double want = fmod(w * t * 180 / M_PI + 90, 360);
        double dh = fabs(remainder(st.heading_deg - want, 360));
        assert_true(dh < 0.01);
        assert_true(st.heading_deg >= 0 && st.heading_deg < 360);
        wrapped |= st.heading_deg < 5;
    }
    print_message("turn: the curve strays %.2e of the radius at most\n", worst);
    assert_true(worst < 1e-3);
    assert_true(wrapped);
    ocean_entity_state st;
    assert_int_equal(ocean_entities_state(e, 7, 250, &st), OCEAN_OK);
    assert_true(fabs(st.x - R * cos(w * 250)) < 1e-9 && fabs(st.z - R * sin(w * 250)) < 1e-9);
    ocean_entities_destroy(e);
}

/* The state at t is a function of the samples: asked forwards, backwards
 * or at random, the same bits. */
static void any_order_same_bits(void **state)
{
    (void)state;
    ocean_entities *e = table(4, 20);
    assert_int_equal(ocean_entities_add(e, &frigate, NULL, 0), OCEAN_OK);
    double x = 0, z = 0, h = 10;
    for (int i = 0; i < 40; i++) {
        ocean_track_sample s = smp(2.5 * i, x, z, h, 6 + (i % 5));
        assert_int_equal(ocean_entities_sample(e, 7, &s, KNOWN, NULL, 0), OCEAN_OK);
        x += 2.5 * (6 + (i % 5)) * cos(h * M_PI / 180);
        z += 2.5 * (6 + (i % 5)) * sin(h * M_PI / 180);
        h += (i % 7) - 3;
    }
    enum { N = 400 };
    ocean_entity_state fwd[N], back[N];
    for (int i = 0; i < N; i++)
        assert_int_equal(ocean_entities_state(e, 7, 0.3 * i, &fwd[i]), OCEAN_OK);
    for (int i = N - 1; i >= 0; i--)
        assert_int_equal(ocean_entities_state(e, 7, 0.3 * i, &back[i]), OCEAN_OK);
    assert_memory_equal(fwd, back, sizeof fwd);
    for (int k = 0; k < N; k++) {
        int i = (k * 157) % N;
        ocean_entity_state s;
        assert_int_equal(ocean_entities_state(e, 7, 0.3 * i, &s), OCEAN_OK);
        assert_memory_equal(&s, &fwd[i], sizeof s);
    }
    ocean_entities_destroy(e);
}

/* Entries are in force from their own instants: a sample changes no
 * instant before its `from` (a later sample entered after an instant was
 * asked leaves that instant's answer as it was), a removal leaves the
 * entity's past in the sea, a new life of the id (another shape) starts
 * at or after the removal, and pruning drops the past only. */
static void in_force_from_its_instant(void **state)
{
    (void)state;
    ocean_entities *e = table(2, 30);
    assert_int_equal(ocean_entities_add(e, &frigate, NULL, 0), OCEAN_OK);
    ocean_track_sample a = smp(100, 0, 0, 0, 10), b = smp(110, 100, 40, 45, 10);
    assert_true(ocean_entities_floor(e, 7) == -INFINITY && ocean_entities_floor(e, 99) == -INFINITY);
    assert_int_equal(ocean_entities_sample(e, 7, &a, 100.5, NULL, 0), OCEAN_OK);
    assert_true(ocean_entities_floor(e, 7) == 100.5);
    ocean_entity_state before, st;
    assert_int_equal(ocean_entities_state(e, 7, 100.2, &st), OCEAN_ENOTFOUND); /* not in force yet */
    assert_int_equal(ocean_entities_state(e, 7, 105, &before), OCEAN_OK);
    assert_true(before.extrapolated && fabs(before.x - 50) < 1e-9 && before.z == 0);
    char why[256];
    assert_int_equal(ocean_entities_sample(e, 7, &b, 100.4, why, sizeof why), OCEAN_EINVAL); /* before a's */
    assert_non_null(strstr(why, "in force from"));
    assert_int_equal(ocean_entities_sample(e, 7, &b, 106, NULL, 0), OCEAN_OK);
    assert_int_equal(ocean_entities_state(e, 7, 105, &st), OCEAN_OK);
    assert_memory_equal(&st, &before, sizeof st);                          /* its past unchanged */
    assert_int_equal(ocean_entities_state(e, 7, 106, &st), OCEAN_OK);
    assert_false(st.extrapolated);                                         /* from 106 on: a to b */
    assert_true(st.z > 0);
    /* removed from 120: there until then, gone after; its past stays */
    assert_int_equal(ocean_entities_remove(e, 7, 105.9), OCEAN_EINVAL);
    assert_true(ocean_entities_floor(e, 7) == 106);
    assert_int_equal(ocean_entities_remove(e, 7, 120), OCEAN_OK);
    assert_true(ocean_entities_floor(e, 7) == 120); /* a new life comes after the removal */
    assert_int_equal(ocean_entities_count(e), 0);
    assert_int_equal(ocean_entities_state(e, 7, 119.9, &st), OCEAN_OK);
    assert_int_equal(ocean_entities_state(e, 7, 120, &st), OCEAN_ENOTFOUND);
    assert_int_equal(ocean_entities_remove(e, 7, 130), OCEAN_ENOTFOUND);
    /* a new life of id 7, another shape, from the removal on */
    ocean_entity_desc boat = {.id = 7, .kind = OCEAN_ENTITY_SHIP, .length_m = 12, .beam_m = 4, .draught_m = 1};
    assert_int_equal(ocean_entities_add(e, &boat, NULL, 0), OCEAN_OK);
    ocean_track_sample c = smp(119, 5000, 0, 90, 5);
    assert_int_equal(ocean_entities_sample(e, 7, &c, 119.5, why, sizeof why), OCEAN_EINVAL);
    assert_int_equal(ocean_entities_sample(e, 7, &c, 121, NULL, 0), OCEAN_OK); /* no teleport: a new life */
    ocean_entity_desc d[4];
    ocean_entity_state s[4];
    assert_int_equal(ocean_entities_at(e, 115, d, s, 4), 1);
    assert_true(d[0].length_m == 120 && s[0].x < 1000);
    assert_int_equal(ocean_entities_at(e, 120.5, d, s, 4), 0);   /* between the lives */
    assert_int_equal(ocean_entities_at(e, 125, d, s, 4), 1);
    assert_true(d[0].length_m == 12 && s[0].x == 5000);
    assert_int_equal(ocean_entities_kept(e), 2);
    ocean_entities_prune(e, 119);                                  /* gone at 120: kept */
    assert_int_equal(ocean_entities_kept(e), 2);
    ocean_entities_prune(e, 120);
    assert_int_equal(ocean_entities_kept(e), 1);
    assert_int_equal(ocean_entities_state(e, 7, 115, &st), OCEAN_ENOTFOUND);
    assert_int_equal(ocean_entities_state(e, 7, 125, &st), OCEAN_OK);
    /* gone lives never crowd out live ones: the earliest gone makes way */
    for (uint32_t id = 20; id < 24; id++) {
        ocean_entity_desc k = frigate;
        k.id = id;
        ocean_track_sample p = smp(200, 0, 0, 0, 1);
        assert_int_equal(ocean_entities_add(e, &k, NULL, 0), OCEAN_OK);
        assert_int_equal(ocean_entities_sample(e, id, &p, 200 + id, NULL, 0), OCEAN_OK);
        assert_int_equal(ocean_entities_remove(e, id, 300 + id), OCEAN_OK);
    }
    assert_int_equal(ocean_entities_kept(e), 4);  /* 2 max: 4 records, the live boat and the last 3 gone */
    assert_int_equal(ocean_entities_state(e, 20, 250, &st), OCEAN_ENOTFOUND);
    assert_int_equal(ocean_entities_state(e, 23, 250, &st), OCEAN_OK);
    assert_int_equal(ocean_entities_state(e, 7, 125, &st), OCEAN_OK);
    ocean_entities_destroy(e);
}

/* Every bad sample refused with its reason, the track as it was. */
static void bad_samples_change_nothing(void **state)
{
    (void)state;
    ocean_entities *e = table(4, 5);
    assert_int_equal(ocean_entities_add(e, &frigate, NULL, 0), OCEAN_OK);
    ocean_entity_desc heli = {.id = 3, .kind = OCEAN_ENTITY_ROTORCRAFT, .length_m = 16};
    assert_int_equal(ocean_entities_add(e, &heli, NULL, 0), OCEAN_OK);
    ocean_track_sample a = smp(10, 0, 0, 0, 10);
    assert_int_equal(ocean_entities_sample(e, 7, &a, KNOWN, NULL, 0), OCEAN_OK);
    ocean_entity_state before, after;
    assert_int_equal(ocean_entities_state(e, 7, 12, &before), OCEAN_OK);
    struct { ocean_track_sample s; const char *says; } bad[] = {
        {smp(11, NAN, 0, 0, 10), "finite"},
        {smp(11, 10, 0, INFINITY, 10), "finite"},
        {smp(11, 10, 0, 0, 31), "speed"},
        {smp(11, 10, 0, 0, -1), "speed"},
        {smp(11, 3e7, 0, 0, 10), "|x|"},
        {smp(10, 0, 0, 0, 10), "not after"},
        {smp(9, 0, 0, 0, 10), "not after"},
        {smp(11, 1000, 0, 0, 10), "teleport"},
        {{.t = 11, .x = 10, .altitude_m = 20, .speed = 10}, "altitude"}, /* a ship flies not */
    };
    char why[400];
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        why[0] = '\0';
        assert_int_equal(ocean_entities_sample(e, 7, &bad[i].s, KNOWN, why, sizeof why), OCEAN_EINVAL);
        if (!strstr(why, bad[i].says)) fail_msg("sample %zu: '%s' does not say '%s'", i, why, bad[i].says);
        assert_int_equal(ocean_entities_state(e, 7, 12, &after), OCEAN_OK);
        assert_memory_equal(&before, &after, sizeof before);
    }
    assert_int_equal(ocean_entities_sample(e, 99, &a, KNOWN, why, sizeof why), OCEAN_ENOTFOUND);
    /* a rotorcraft climbs within its range; above it, refused */
    ocean_track_sample h1 = {.t = 0, .altitude_m = 30, .speed = 0};
    ocean_track_sample h2 = {.t = 60, .altitude_m = 6000, .speed = 0};
    assert_int_equal(ocean_entities_sample(e, 3, &h1, KNOWN, NULL, 0), OCEAN_OK);
    assert_int_equal(ocean_entities_sample(e, 3, &h2, KNOWN, why, sizeof why), OCEAN_EINVAL);
    h2.altitude_m = 300;
    assert_int_equal(ocean_entities_sample(e, 3, &h2, KNOWN, NULL, 0), OCEAN_OK);
    assert_int_equal(ocean_entities_state(e, 3, 30, &after), OCEAN_OK);
    assert_true(fabs(after.altitude_m - 165) < 1e-9);
    /* an aircraft flies higher and faster than a rotorcraft may, within its own range */
    ocean_entity_desc jet = {.id = 4, .kind = OCEAN_ENTITY_AIRCRAFT, .length_m = 35};
    assert_int_equal(ocean_entities_add(e, &jet, NULL, 0), OCEAN_OK);
    ocean_track_sample j1 = {.t = 0, .altitude_m = 10000, .speed = 250};
    ocean_track_sample j2 = {.t = 1, .x = 250, .altitude_m = 10000, .speed = 250};
    ocean_track_sample j3 = {.t = 2, .x = 500, .altitude_m = 31000, .speed = 250};
    assert_int_equal(ocean_entities_sample(e, 4, &j1, KNOWN, NULL, 0), OCEAN_OK);
    assert_int_equal(ocean_entities_sample(e, 4, &j2, KNOWN, NULL, 0), OCEAN_OK);
    assert_int_equal(ocean_entities_sample(e, 4, &j3, KNOWN, why, sizeof why), OCEAN_EINVAL);
    assert_non_null(strstr(why, "altitude"));
    /* one good sample still goes in after all that */
    ocean_track_sample b = smp(11, 10, 0, 0, 10);
    assert_int_equal(ocean_entities_sample(e, 7, &b, KNOWN, NULL, 0), OCEAN_OK);
    ocean_entities_destroy(e);
}

/* A track keeps its last OCEAN_TRACK_KEEP samples (or its table's keep): an instant before the
 * oldest kept is not answered (rather than guessed). */
static void track_keeps_its_last_samples(void **state)
{
    (void)state;
    ocean_entities *e = table(4, 5);
    assert_int_equal(ocean_entities_add(e, &frigate, NULL, 0), OCEAN_OK);
    int n = OCEAN_TRACK_KEEP + 44;
    for (int i = 0; i < n; i++) {
        ocean_track_sample s = smp(i, 5.0 * i, 0, 0, 5);
        assert_int_equal(ocean_entities_sample(e, 7, &s, KNOWN, NULL, 0), OCEAN_OK);
    }
    ocean_entity_state st;
    assert_int_equal(ocean_entities_state(e, 7, 43.5, &st), OCEAN_ENOTFOUND);
    assert_int_equal(ocean_entities_state(e, 7, 44, &st), OCEAN_OK);
    assert_true(fabs(st.x - 220) < 1e-9);
    assert_int_equal(ocean_entities_state(e, 7, n - 1.5, &st), OCEAN_OK);
    assert_true(fabs(st.x - 5.0 * (n - 1.5)) < 1e-9);
    ocean_entities_destroy(e);
    /* a table's own keep: 5 (the track grows 4 -> 5, then drops its oldest) */
    assert_int_equal(ocean_entities_create(4, 5, 5, &e, NULL, 0), OCEAN_OK);
    assert_int_equal(ocean_entities_add(e, &frigate, NULL, 0), OCEAN_OK);
    for (int i = 0; i < 12; i++) {
        ocean_track_sample s = smp(i, 5.0 * i, 0, 0, 5);
        assert_int_equal(ocean_entities_sample(e, 7, &s, KNOWN, NULL, 0), OCEAN_OK);
        ocean_track_sample last;
        assert_int_equal(ocean_entities_last(e, 7, &last, NULL), OCEAN_OK);
        assert_true(last.t == i);
    }
    assert_int_equal(ocean_entities_state(e, 7, 6.5, &st), OCEAN_ENOTFOUND);
    assert_int_equal(ocean_entities_state(e, 7, 7, &st), OCEAN_OK);
    assert_true(fabs(st.x - 35) < 1e-9);
    assert_int_equal(ocean_entities_state(e, 7, 9.5, &st), OCEAN_OK);
    assert_true(fabs(st.x - 47.5) < 1e-9);
    ocean_entities_destroy(e);
}

/* Enters en into t as a reader of the table's entries does. */
static void entry_enter(void *ctx, const ocean_entity_entry *en)
{
    ocean_entities *t = ctx;
    ocean_entity_desc known;
    if (en->removal) {
        assert_int_equal(ocean_entities_remove(t, en->d.id, en->from), OCEAN_OK);
        return;
    }
    if (ocean_entities_desc(t, en->d.id, &known) != OCEAN_OK)
        assert_int_equal(ocean_entities_add(t, &en->d, NULL, 0), OCEAN_OK);
    assert_int_equal(ocean_entities_sample(t, en->d.id, &en->s, en->from, NULL, 0), OCEAN_OK);
}

/* A table's entries rebuild it: a copy made from them alone (the late
 * joiner's) answers every instant as the table does, with a wrapped
 * track, a removed life, a new life of the same id and a sample not yet
 * in force. */
static void entries_rebuild_the_table(void **state)
{
    (void)state;
    ocean_entities *e = table(4, 10);
    assert_int_equal(ocean_entities_add(e, &frigate, NULL, 0), OCEAN_OK);
    for (int i = 0; i < OCEAN_TRACK_KEEP + 20; i++) { /* wraps: the first 20 dropped */
        ocean_track_sample s = smp(i, 6.0 * i + 0.01 * i * i, 0.3 * i, 0, 6);
        assert_int_equal(ocean_entities_sample(e, 7, &s, i + 0.25, NULL, 0), OCEAN_OK);
    }
    assert_int_equal(ocean_entities_remove(e, 7, 280), OCEAN_OK);
    ocean_entity_desc boat = {.id = 7, .kind = OCEAN_ENTITY_SHIP, .length_m = 12, .beam_m = 4, .draught_m = 1};
    ocean_entity_desc heli = {.id = 3, .kind = OCEAN_ENTITY_ROTORCRAFT, .length_m = 16};
    assert_int_equal(ocean_entities_add(e, &boat, NULL, 0), OCEAN_OK);
    assert_int_equal(ocean_entities_add(e, &heli, NULL, 0), OCEAN_OK);
    ocean_track_sample b = smp(281, -500, 20, 90, 4), h1 = smp(250, 0, 900, 180, 20), h2 = smp(300, -1000, 900, 180, 20);
    assert_int_equal(ocean_entities_sample(e, 7, &b, 282, NULL, 0), OCEAN_OK);
    assert_int_equal(ocean_entities_sample(e, 3, &h1, 250, NULL, 0), OCEAN_OK);
    assert_int_equal(ocean_entities_sample(e, 3, &h2, 290, NULL, 0), OCEAN_OK); /* ahead of most instants */
    ocean_entities *copy = table(4, 10);
    int n = ocean_entities_each(e, entry_enter, copy);
    assert_int_equal(n, OCEAN_TRACK_KEEP + 1 + 1 + 2); /* frigate's kept samples, its removal, the boat, the heli */
    assert_int_equal(ocean_entities_kept(copy), ocean_entities_kept(e));
    int seen = 0;
    for (double t = 0; t < 320; t += 0.37) {
        ocean_entity_desc d[8], dc[8];
        ocean_entity_state s[8], sc[8];
        int k = ocean_entities_at(e, t, d, s, 8);
        assert_int_equal(ocean_entities_at(copy, t, dc, sc, 8), k);
        assert_memory_equal(d, dc, sizeof *d * (size_t)k);
        assert_memory_equal(s, sc, sizeof *s * (size_t)k);
        seen += k;
    }
    assert_true(seen > 800);
    ocean_entities_destroy(copy);
    ocean_entities_destroy(e);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(table_limits),
        cmocka_unit_test(shapes_checked),
        cmocka_unit_test(straight_run_and_hold),
        cmocka_unit_test(turn_is_smooth),
        cmocka_unit_test(any_order_same_bits),
        cmocka_unit_test(in_force_from_its_instant),
        cmocka_unit_test(bad_samples_change_nothing),
        cmocka_unit_test(track_keeps_its_last_samples),
        cmocka_unit_test(entries_rebuild_the_table),
    };
    return cmocka_run_group_tests_name("entity", tests, NULL, NULL);
}
