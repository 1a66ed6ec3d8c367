/*
 * test_srv_parts.c - the daemon's per-client parts on their own, without a
 * connection or a thread: the token bucket every rate budget uses, a
 * client's inbox (its QUERYs and replay cameras) and outbox (its FIFO and
 * latest-wins frame slot, under a hard byte limit), the simulation
 * thread's table of what it keeps of each client, its model of what a
 * time-interpolating client holds, the sea changes' oceans built ahead,
 * and admission for the daemon as a whole.
 */
#include <math.h>
#include <pthread.h>
#include <setjmp.h>
#include <stdatomic.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "srv_admit.h"
#include "srv_bucket.h"
#include "srv_client.h"
#include "srv_client_sim.h"
#include "srv_held.h"
#include "srv_inbox.h"
#include "srv_outbox.h"
#include "srv_seabuild.h"
#include "ocean_internal.h"
#include "lib/test_net.h"

/* A bucket never used starts full; each take costs its tokens; refused
 * takes cost nothing; tokens come back at the rate, never above the depth;
 * spending may go into debt, which refills pay back. */
static void bucket_rules(void **state)
{
    (void)state;
    srv_bucket b = {0};
    for (int i = 0; i < 4; i++) assert_true(srv_bucket_take(&b, 2.0, 4.0, 100.0, 1));
    assert_false(srv_bucket_take(&b, 2.0, 4.0, 100.0, 1));
    assert_false(srv_bucket_take(&b, 2.0, 4.0, 100.25, 1)); /* 0.5 token */
    assert_true(srv_bucket_take(&b, 2.0, 4.0, 100.5, 1));   /* 1 token */
    assert_true(srv_bucket_refill(&b, 2.0, 4.0, 200.0) == 4.0);
    srv_bucket_spend(&b, 10.0);
    assert_true(b.tokens == -6.0);
    assert_true(srv_bucket_refill(&b, 2.0, 4.0, 203.0) == 0.0);
    assert_false(srv_bucket_take(&b, 2.0, 4.0, 203.0, 1));
    /* a clock that steps back refills nothing */
    assert_true(srv_bucket_refill(&b, 2.0, 4.0, 150.0) == 0.0);
}

static srv_query *query(uint32_t id)
{
    srv_query *q = calloc(1, sizeof *q);
    assert_non_null(q);
    q->query_id = id;
    q->count = 1;
    q->points = calloc(2, sizeof(double));
    return q;
}

static srv_replay_cam *replay_cam(uint32_t seq)
{
    srv_replay_cam *rc = calloc(1, sizeof *rc);
    assert_non_null(rc);
    rc->seq = seq;
    return rc;
}

/* Both queues are FIFOs with their counts; dropping the replay cameras
 * keeps the queries; what is left is freed with the inbox (LSan). */
static void inbox_fifos(void **state)
{
    (void)state;
    srv_inbox *in;
    assert_int_equal(srv_inbox_create(&in), OCEAN_OK);
    for (uint32_t i = 1; i <= 3; i++) {
        srv_inbox_push_query(in, query(i));
        srv_inbox_push_replay(in, replay_cam(10 + i));
    }
    assert_int_equal(srv_inbox_queries(in), 3);
    assert_int_equal(srv_inbox_replays(in), 3);
    srv_query *q = srv_inbox_take_query(in);
    assert_int_equal(q->query_id, 1);
    free(q->points);
    free(q);
    srv_replay_cam *rc = srv_inbox_take_replay(in);
    assert_int_equal(rc->seq, 11);
    free(rc);
    srv_inbox_drop_replays(in);
    assert_int_equal(srv_inbox_replays(in), 0);
    assert_null(srv_inbox_take_replay(in));
    assert_int_equal(srv_inbox_queries(in), 2);
    q = srv_inbox_take_query(in);
    assert_int_equal(q->query_id, 2);
    free(q->points);
    free(q);
    srv_inbox_push_query(in, query(4));
    assert_int_equal(srv_inbox_queries(in), 2);
    srv_inbox_destroy(in);
    srv_inbox_destroy(NULL);
}

static srv_msg *msg_of(size_t bytes, int close_after)
{
    srv_msg *m = srv_msg_new();
    assert_non_null(m);
    assert_int_equal(proto_buf_reserve(&m->buf, bytes), OCEAN_OK);
    memset(proto_buf_data(&m->buf), 0, bytes);
    m->buf.len = bytes;
    m->close_after = close_after;
    return m;
}

/* The FIFO goes before the frame slot; a published frame replaces an unsent
 * one (reported as skipped) and keeps an unsent topology when it brings
 * none; the hard limit refuses a message that would pass it (2 the first
 * time, 1 after), never a BYE; a queue asks for a write once. */
static void outbox_order_and_limit(void **state)
{
    (void)state;
    srv_outbox *o;
    assert_int_equal(srv_outbox_create(0, &o), OCEAN_OK);
    srv_msg *topo = msg_of(10, 0), *f1 = msg_of(20, 0), *f2 = msg_of(30, 0), *c1 = msg_of(40, 0);
    assert_int_equal(srv_outbox_publish(o, topo, f1), 0);
    assert_int_equal(srv_outbox_publish(o, NULL, f2), 1);
    assert_true(srv_outbox_frame_waiting(o));
    assert_true(srv_outbox_next_is_live(o));
    assert_int_equal(srv_outbox_queue(o, c1), 0);
    assert_false(srv_outbox_next_is_live(o));
    assert_true(srv_outbox_take_want_write(o));
    assert_false(srv_outbox_take_want_write(o));
    uint64_t queued = srv_outbox_queued(o);
    assert_true(queued == srv_msg_cost(topo) + srv_msg_cost(f2) + srv_msg_cost(c1));
    srv_msg *m = srv_outbox_take(o);
    assert_ptr_equal(m, c1);
    srv_msg_free(m);
    m = srv_outbox_take(o);
    assert_ptr_equal(m, topo);
    srv_msg_free(m);
    m = srv_outbox_take(o);
    assert_ptr_equal(m, f2);
    assert_true(m->live);
    srv_msg_free(m);
    assert_null(srv_outbox_take(o));
    assert_true(srv_outbox_queued(o) == 0);

    srv_msg *big = msg_of(1000, 0);
    srv_outbox_set_hard(o, srv_msg_cost(big) + 10);
    assert_int_equal(srv_outbox_queue(o, big), 0);
    assert_false(srv_outbox_over_hard(o));
    assert_int_equal(srv_outbox_queue(o, msg_of(100, 0)), 2);
    assert_true(srv_outbox_over_hard(o));
    assert_int_equal(srv_outbox_queue(o, msg_of(100, 0)), 1);
    assert_int_equal(srv_outbox_queue(o, msg_of(100, 1)), 0); /* a BYE always goes in */
    srv_outbox_destroy(o);
    srv_outbox_destroy(NULL);
}

/* One entry per client, the same one each time it is asked for, made
 * with its smoother ready; a closed client's entry goes at the next sweep;
 * reapply asks every entry to apply its subscription again. */
static void client_table(void **state)
{
    (void)state;
    srv_settings s;
    char err[256];
    assert_int_equal(srv_settings_default(&s, err, sizeof err), OCEAN_OK);
    srv_hub h;
    assert_int_equal(srv_hub_init(&h, &s), OCEAN_OK);
    srv_client *c[3];
    for (int i = 0; i < 3; i++) assert_int_equal(srv_client_create(&h, &c[i]), OCEAN_OK);
    srv_client_table *t;
    assert_int_equal(srv_client_table_create(&t), OCEAN_OK);
    srv_client_sim *cs[3];
    for (int i = 2; i >= 0; i--) cs[i] = srv_client_table_get(t, c[i]);
    for (int i = 0; i < 3; i++) {
        assert_non_null(cs[i]);
        assert_ptr_equal(srv_client_table_get(t, c[i]), cs[i]);
        cs[i]->sub_gen = 7;
    }
    assert_true(cs[0] != cs[1] && cs[1] != cs[2]);
    srv_client_ref(c[1]);
    srv_client_remove(c[1]);          /* the hub's reference goes; closed */
    pthread_mutex_lock(&h.lock);
    srv_client_table_sweep(t);
    pthread_mutex_unlock(&h.lock);
    srv_client_sim *again = srv_client_table_get(t, c[1]); /* a new entry for a client seen anew */
    assert_non_null(again);
    assert_true(again->sub_gen == 0);
    assert_ptr_equal(srv_client_table_get(t, c[0]), cs[0]);
    assert_ptr_equal(srv_client_table_get(t, c[2]), cs[2]);
    srv_client_table_reapply(t);
    assert_true(cs[0]->sub_gen == 0 && cs[2]->sub_gen == 0);
    srv_client_table_destroy(t);
    srv_client_table_destroy(NULL);
    srv_client_unref(c[1]);
    srv_hub_fini(&h);
}

/* A held model with window (tick_a, interval) on cascade 0's mips 0 and 1
 * (16 tiles each), sample A holding tiles a[0..na) with channels cha and
 * B tile b with channels chb. */
static srv_held *held_with(uint32_t tick_a, const int *a, int na, int b, unsigned cha, unsigned chb)
{
    srv_held *h;
    assert_int_equal(srv_held_create(&h), OCEAN_OK);
    proto_mip_time t = {.tick_a = tick_a, .interval = 4};
    for (int m = 0; m < 2; m++) {
        assert_int_equal(srv_held_advance(h, 0, m, &t, 16), OCEAN_OK);
        for (int i = 0; i < na; i++) srv_held_add(h, 0, m, 0, a[i], cha);
        srv_held_add(h, 0, m, 1, b, chb);
    }
    srv_held_keyed(h);
    return h;
}

/* What a client holds whichever of two frames reached it: the tiles both
 * models hold in the same window with the same channels; a mip whose
 * windows differ holds nothing; a model that demands a KEY frame makes
 * the meet demand one. */
static void held_meet(void **state)
{
    (void)state;
    const int a[] = {1, 2, 3}, b[] = {2, 3, 4};
    srv_held *x = held_with(10, a, 3, 5, 7, 7), *y = held_with(10, b, 3, 5, 7, 3);
    proto_mip_time later = {.tick_a = 14, .interval = 4};
    assert_int_equal(srv_held_advance(y, 0, 1, &later, 16), OCEAN_OK); /* B moved to A */
    assert_true(srv_held_has(y, 0, 1, 0, 5, 3));
    srv_held_meet(x, y);
    for (int i = 0; i < 16; i++) {
        assert_int_equal(srv_held_has(x, 0, 0, 0, i, 7), i == 2 || i == 3);
        assert_false(srv_held_has(x, 0, 0, 1, i, 7) || srv_held_has(x, 0, 0, 1, i, 3));
        assert_false(srv_held_has(x, 0, 1, 0, i, 7) || srv_held_has(x, 0, 1, 0, i, 3));
    }
    assert_false(srv_held_key(x));
    srv_held *empty;
    assert_int_equal(srv_held_create(&empty), OCEAN_OK);
    srv_held_meet(x, empty);
    assert_true(srv_held_key(x));
    assert_false(srv_held_has(x, 0, 0, 0, 2, 7));
    srv_held_destroy(x);
    srv_held_destroy(y);
    srv_held_destroy(empty);
}

/* The change wanted is built by the module's thread and taken whole
 * (take waits for a build under way, never builds it twice); a change
 * wanted in its place replaces it; a change never wanted is built by the
 * caller; what cannot be built is said with the builder's reason; a
 * build left untaken is freed with the module. */
static void seabuild_ahead(void **state)
{
    (void)state;
    srv_settings s;
    char err[256];
    assert_int_equal(srv_settings_default(&s, err, sizeof err), OCEAN_OK);
    s.params.n = 64;   /* small oceans: this is about who builds them */
    ocean_params a = s.params, b = s.params, bad = s.params;
    a.sea.wind_u10 = 7;
    b.sea.wind_u10 = 9;
    bad.n = 3;         /* not a power of two: ocean_create refuses it */
    srv_seabuild *sb;
    assert_int_equal(srv_seabuild_create(&sb), OCEAN_OK);
    srv_sea_ocean o;
    int ahead = -1;
    double secs = -1;
    srv_seabuild_want(sb, &s, 1, &a, 10.0);
    srv_seabuild_want(sb, &s, 1, &b, 20.0);   /* b is needed first now */
    assert_int_equal(srv_seabuild_take(sb, &s, 1, &b, 20.0, &o, &ahead, &secs, err, sizeof err), OCEAN_OK);
    assert_int_equal(ahead, 1);
    assert_true(secs > 0); /* the builder's time, measured */
    assert_non_null(o.oc);
    srv_sea_ocean_free(&o);
    assert_null(o.oc);
    /* a is no longer wanted: taking it builds it here */
    secs = -1;
    assert_int_equal(srv_seabuild_take(sb, &s, 1, &a, 10.0, &o, &ahead, &secs, err, sizeof err), OCEAN_OK);
    assert_int_equal(ahead, 0);
    assert_true(secs > 0);
    assert_non_null(o.oc);
    srv_sea_ocean_free(&o);
    /* another settings generation is another change */
    srv_seabuild_want(sb, &s, 1, &a, 30.0);
    assert_int_equal(srv_seabuild_take(sb, &s, 2, &a, 30.0, &o, &ahead, &secs, err, sizeof err), OCEAN_OK);
    assert_int_equal(ahead, 0);
    srv_sea_ocean_free(&o);
    srv_seabuild_want(sb, &s, 1, &bad, 40.0);
    err[0] = 0;
    assert_int_not_equal(srv_seabuild_take(sb, &s, 1, &bad, 40.0, &o, &ahead, &secs, err, sizeof err), OCEAN_OK);
    assert_int_equal(ahead, 1);
    assert_null(o.oc);
    assert_true(strlen(err) > 5);
    srv_seabuild_want(sb, &s, 1, &a, 50.0);   /* built, never taken */
    srv_seabuild_destroy(sb);
    srv_seabuild_destroy(NULL);
}

typedef struct discard_job {
    srv_seabuild *sb;
    srv_sea_ocean o;
    atomic_int done;
} discard_job;

static void *discard_main(void *arg)
{
    discard_job *j = arg;
    srv_seabuild_discard(j->sb, &j->o);
    atomic_store(&j->done, 1);
    return NULL;
}

/* The simulation thread hands the oceans it is done with to the builder:
 * freeing one takes FFTW's planner lock, which a build (at nice 10) holds
 * while it plans.  With the lock held elsewhere, a discard returns at once
 * (freeing in place waited for the lock: a tick held up behind a starved
 * background thread); the builder frees it once the lock is free, and
 * destroy frees what is left. */
static void seabuild_frees_off_the_caller(void **state)
{
    (void)state;
    srv_settings s;
    char err[256];
    assert_int_equal(srv_settings_default(&s, err, sizeof err), OCEAN_OK);
    s.params.n = 64;
    srv_seabuild *sb;
    assert_int_equal(srv_seabuild_create(&sb), OCEAN_OK);
    discard_job j = {.sb = sb};
    atomic_init(&j.done, 0);
    assert_int_equal(srv_sea_ocean_build(&s, &s.params, 0, &j.o, err, sizeof err), OCEAN_OK);
    ocean_fft_planner_lock();   /* as a build planning would */
    pthread_t t;
    assert_int_equal(pthread_create(&t, NULL, discard_main, &j), 0);
    double t0 = test_now_s();
    while (!atomic_load(&j.done) && test_now_s() - t0 < 10.0) usleep(1000);
    int returned = atomic_load(&j.done);
    ocean_fft_planner_unlock();
    pthread_join(t, NULL);
    if (!returned) fail_msg("srv_seabuild_discard waited for the planner lock");
    assert_null(j.o.oc);   /* handed over */
    /* and one handed over just before the end */
    assert_int_equal(srv_sea_ocean_build(&s, &s.params, 0, &j.o, err, sizeof err), OCEAN_OK);
    srv_seabuild_discard(sb, &j.o);
    srv_seabuild_destroy(sb);
}

/* Admission: a live layout-0 subscription is priced at its tile samples/s
 * x planes x its codec's measured cost (a codec not measured yet at the
 * dearest measured), layout 1 and replays at nothing; prices are taken
 * while the sum fits server.admit_share of the usable cores, the next is
 * refused ETOOBIG naming the limit with nothing changed, a price given
 * back makes room, a cheaper re-subscription always passes, and share 0
 * admits everything. */
static void admission_prices_and_limits(void **state)
{
    (void)state;
    srv_admit *a = NULL;
    assert_int_equal(srv_admit_create(2, &a), OCEAN_OK);
    srv_admit_tiles(a, PROTO_CODEC_QZ, 0.01, 1e6);        /* 10 ns a plane-sample */
    srv_admit_tiles(a, PROTO_CODEC_EXR_PIZ, 0.04, 1e6);   /* 40 ns */
    srv_admit_sample(a, 100.0);
    srv_config cfg;
    memset(&cfg, 0, sizeof cfg);
    cfg.tiles_per_side = 2;
    cfg.admit_share = 0.5;
    proto_subscribe sub;
    memset(&sub, 0, sizeof sub);
    sub.layout = PROTO_LAYOUT_WORLD;
    sub.mode = PROTO_MODE_LIVE;
    sub.tile_size = 64;
    sub.lod_levels = 8;
    sub.frame_rate_hz = 30;
    sub.effects = PROTO_FX_HEIGHT; /* one plane */
    sub.codec = PROTO_CODEC_QZ;
    double want = 2.0 * 2 * 8 * 64 * 64 * 1 * 30 * 1e-8;
    double price = srv_admit_price(a, &cfg, &sub);
    assert_true(fabs(price - want) < 1e-3 * want);
    sub.codec = PROTO_CODEC_F16; /* not measured: the dearest, exr-piz's */
    assert_true(fabs(srv_admit_price(a, &cfg, &sub) - 4 * want) < 4e-3 * want);
    sub.codec = PROTO_CODEC_QZ;
    proto_subscribe other = sub;
    other.layout = PROTO_LAYOUT_CASCADE;
    assert_true(srv_admit_price(a, &cfg, &other) == 0);
    other = sub;
    other.mode = PROTO_MODE_REPLAY;
    assert_true(srv_admit_price(a, &cfg, &other) == 0);

    srv_admit_view v;
    srv_admit_get_view(a, &cfg, &v);
    assert_true(v.capacity > 0 && fabs(v.capacity - 0.5 * v.usable) < 1e-12);
    int fit = (int)floor((v.capacity - v.shared) / price + 1e-9);
    assert_true(fit >= 1);
    char why[1024];
    for (int i = 0; i < fit; i++) assert_int_equal(srv_admit_take(a, &cfg, &sub, 0, price, why, sizeof why), OCEAN_OK);
    assert_int_equal(srv_admit_take(a, &cfg, &sub, 0, price, why, sizeof why), OCEAN_ETOOBIG);
    assert_non_null(strstr(why, "server.admit_share"));
    srv_admit_get_view(a, &cfg, &v);
    assert_int_equal(v.admitted, fit);
    assert_true(fabs(v.priced - fit * price) < 1e-9);
    /* a cheaper stream for one of them passes; a dearer one does not */
    assert_int_equal(srv_admit_take(a, &cfg, &sub, price, 0.5 * price, why, sizeof why), OCEAN_OK);
    assert_int_equal(srv_admit_take(a, &cfg, &sub, 0.5 * price, 2 * price, why, sizeof why), OCEAN_ETOOBIG);
    srv_admit_release(a, 0.5 * price);
    assert_int_equal(srv_admit_take(a, &cfg, &sub, 0, price, why, sizeof why), OCEAN_OK);
    cfg.admit_share = 0;
    assert_int_equal(srv_admit_take(a, &cfg, &sub, 0, 100.0, why, sizeof why), OCEAN_OK);
    srv_admit_get_view(a, &cfg, &v);
    assert_int_equal(v.admitted, fit + 1);
    srv_admit_destroy(a);
    srv_admit_destroy(NULL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(bucket_rules),
        cmocka_unit_test(inbox_fifos),
        cmocka_unit_test(outbox_order_and_limit),
        cmocka_unit_test(client_table),
        cmocka_unit_test(held_meet),
        cmocka_unit_test(seabuild_ahead),
        cmocka_unit_test(seabuild_frees_off_the_caller),
        cmocka_unit_test(admission_prices_and_limits),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
