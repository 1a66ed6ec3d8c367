/*
 * test_server.c - integration tests of the daemon (issue 6).
 *
 * The daemon runs in-process (srv_daemon_start on a free loopback port), so
 * ASan sees its threads; the signal test execs build/oceand (the binary of
 * the same build).  Clients are the C client library (clients/c) and, for
 * input no proper client would send and for a reader that never reads, the
 * raw WebSocket client of tests/lib/test_ws.h.
 */
#include <fcntl.h>
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <signal.h>
#include <sys/resource.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include <stdlib.h>

#include <cmocka.h>
#include <cJSON.h>
#include <dirent.h>
#include <malloc.h>

#include "filter.h"
#include "gerstner.h"
#include "foam.h"
#include "ocean.h"
#include "oceanclient.h"
#include "query.h"
#include "slope.h"
#include "srv_cascade.h"
#include "srv_daemon.h"
#include "srv_fingerprint.h"
#include "srv_entity.h"
#include "srv_record.h"
#include "srv_tiles.h"
#include "srv_wakes.h"
#include "wake_field.h"
#include "rotor_wash.h"
#include "lib/test_ws.h"
#include "lib/test_net.h"
#include "oc_path.h"

static int sanitized;
static char tmpdir[256];
static char conf_path[300];
static char exe_dir[512];
static srv_settings settings;
static srv_daemon *daemon_;
static int port;
static oc_loop *bg_loop; /* serviced by a library thread */

static void write_conf(const char *path, double wind, int max_clients)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f,
            "sea.wind = %g\n"
            "ocean.n = %d\n"
            "ocean.cascades = 2\n"
            "ocean.patch = 400\n"
            "ocean.threads = 1\n"
            "server.port = 0\n"
            "server.scene = \"\"\n"
            "server.tick_rate = 30\n"
            "server.admin_token = \"test-token\"\n"
            "server.entity_token = \"entity-token\"\n"
            "server.max_entities = 4\n"
            "server.output_soft = 4194304\n"
            "server.output_soft_seconds = 1\n"
            "server.max_message = 65536\n"
            "server.msg_rate = 50\n"
            "server.msg_burst = 100\n"
            "server.max_clients = %d\n"
            "server.record_dir = \"%s/rec\"\n"
            "server.record_clients = on\n"
            "server.admin_lockout = 0\n"
            "server.admit_share = 0\n" /* see load_settings */
            "server.near_field_waves = 32\n"
            "server.view_range = 2000\n"
            "server.px_per_sample = 48\n"
            "server.workers = 2\n",
            wind, sanitized ? 32 : 64, max_clients, tmpdir);
    fclose(f);
}

static int group_setup(void **state)
{
    (void)state;
    sanitized = getenv("OCEAN_TEST_SANITIZED") != NULL;
    signal(SIGPIPE, SIG_IGN);
    snprintf(tmpdir, sizeof tmpdir, "/tmp/test_server.%d", (int)getpid());
    mkdir(tmpdir, 0755);
    snprintf(conf_path, sizeof conf_path, "%s/oceand.conf", tmpdir);
    write_conf(conf_path, 10, 1000);
    char err[512];
    if (srv_settings_load(conf_path, NULL, 0, &settings, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "%s\n", err);
        return -1;
    }
    if (srv_daemon_start(&settings, &daemon_, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "%s\n", err);
        return -1;
    }
    port = srv_daemon_port(daemon_);
    return port > 0 ? 0 : -1;
}

static int group_teardown(void **state)
{
    (void)state;
    srv_daemon_stop(daemon_);
    oc_loop_destroy(bg_loop);
    char cmd[400];
    snprintf(cmd, sizeof cmd, "rm -rf %s", tmpdir);
    if (system(cmd) != 0) return -1;
    return 0;
}

/* ---- helpers ---------------------------------------------------------------- */


static oc_client *connect_client_on(int p, const oc_callbacks *cb, oc_loop *loop)
{
    char url[64], err[256];
    snprintf(url, sizeof url, "ws://127.0.0.1:%d/", p);
    oc_options o;
    oc_options_default(&o);
    o.url = url;
    o.frame_queue = 64;
    o.loop = loop;
    if (cb) o.cb = *cb;
    oc_client *c = NULL;
    ocean_result r = oc_connect(&o, 5000, &c, err, sizeof err);
    if (r != OCEAN_OK) fprintf(stderr, "connect: %s\n", err);
    assert_int_equal(r, OCEAN_OK);
    return c;
}

static oc_client *connect_client(int p, const oc_callbacks *cb)
{
    return connect_client_on(p, cb, NULL);
}

/* A client whose socket is read by a background thread, so it keeps up
 * while the test does something else. */
static oc_client *connect_bg(int p)
{
    if (!bg_loop) {
        char err[256];
        assert_int_equal(oc_loop_create(&bg_loop, err, sizeof err), OCEAN_OK);
        assert_int_equal(oc_loop_start(bg_loop), OCEAN_OK);
    }
    return connect_client_on(p, NULL, bg_loop);
}

static void small_subscribe(proto_subscribe *s)
{
    oc_subscribe_default(s);
    /* the layout-0 subscription these tests were written for (the library's
     * default became the viewer's layout-1 subscription) */
    s->layout = PROTO_LAYOUT_WORLD;
    s->effects = PROTO_FX_HEIGHT | PROTO_FX_DISPLACEMENT | PROTO_FX_NORMALS;
    s->layers = 1;
    s->accuracy = (float)PROTO_ACCURACY_DEFAULT;
    s->tile_size = 32;
    s->lod_levels = 2;
}

/* How long a test waits for a frame it expects: a deadline that finds a
 * daemon that stopped, not a measure of speed (a loaded host took over 5 s
 * for one the quiet host builds in 20 ms); a wait over SLOW_WAIT_S is
 * said in the log. */
#define FRAME_WAIT_MS 30000
#define SLOW_WAIT_S 5.0

static oc_frame *next_frame(oc_client *c)
{
    oc_frame *f = NULL;
    ocean_result r = oc_client_next_frame(c, FRAME_WAIT_MS, &f);
    if (r != OCEAN_OK) {
        char e[256];
        oc_client_last_error(c, e, sizeof e);
        fprintf(stderr, "no frame (%s): last error: %s\n", ocean_strerror(r), e);
    }
    assert_int_equal(r, OCEAN_OK);
    return f;
}

static void drain_frames(oc_client *c)
{
    oc_frame *f;
    while (oc_client_next_frame(c, 0, &f) == OCEAN_OK) oc_frame_free(f);
}

static uint64_t stat_of(atomic_uint_fast64_t *a) { return (uint64_t)atomic_load(a); }

static ocean *local_ocean(void)
{
    ocean *o;
    char msg[256];
    assert_int_equal(ocean_create(&settings.params, &o, msg, sizeof msg), OCEAN_OK);
    return o;
}

/* ---- tests -------------------------------------------------------------------- */

/* Frames arrive, every tile decodes and equals the simulation at the
 * frame's time and cutoff, the mesh decodes against its topology. */
/* A cached tile holds its encoded bytes, not the encoder's buffer: qz
 * grows that to zstd's worst case over the raw planes, about eight times
 * what the tile keeps, and with the capacity kept 256 layout-0 viewers 2 km
 * apart held 1.3 GB of tiles (bench_server's daemon RSS column). */
static void tile_payload_fits_its_bytes(void **state)
{
    (void)state;
    /* the helper itself: a buffer reserved far past its bytes */
    proto_buf b;
    proto_buf_init(&b, 0);
    assert_int_equal(proto_buf_reserve(&b, 1 << 17), OCEAN_OK);
    for (int i = 0; i < 1000; i++) {
        uint8_t v = (uint8_t)(i * 7);
        assert_int_equal(proto_buf_append(&b, &v, 1), OCEAN_OK);
    }
    srv_tile t1;
    memset(&t1, 0, sizeof t1);
    assert_int_equal(srv_tile_take_payload(&t1, &b), OCEAN_OK);
    assert_null(b.mem);
    assert_int_equal(t1.payload_len, 1000);
    for (int i = 0; i < 1000; i++)
        assert_int_equal(t1.payload[i], (uint8_t)(i * 7));
    assert_true(malloc_usable_size(t1.payload) < 1000 + 64);
    free(t1.payload);

    /* a layout-0 tile as the daemon builds it from the sea it serves: 64 x
     * 64 samples, every channel, qz at the old viewer's accuracy */
    ocean *o = local_ocean();
    ocean_frame *f = NULL;
    assert_int_equal(ocean_frame_create(o, &f), OCEAN_OK);
    ocean_request rq;
    ocean_request_all(&rq, OCEAN_FX_HEIGHT | OCEAN_FX_DISPLACEMENT | OCEAN_FX_NORMALS | OCEAN_FX_FOAM);
    assert_int_equal(ocean_evaluate(o, 12.0, &rq, f), OCEAN_OK);
    srv_tile t;
    memset(&t, 0, sizeof t);
    srv_tile_key_init(&t.key);
    t.key.t = 12.0;
    t.key.spacing = 1.0;
    t.key.accuracy = 1e-3f;
    t.key.ix = 3;
    t.key.iz = -2;
    t.key.channels = (uint16_t)srv_tiles_channels(PROTO_FX_HEIGHT | PROTO_FX_DISPLACEMENT | PROTO_FX_NORMALS |
                                                  PROTO_FX_FOAM);
    t.key.size = 64;
    t.key.codec = PROTO_CODEC_QZ;
    t.key.layers = 1;
    srv_tile_build(&t, f);
    assert_int_equal(t.result, OCEAN_OK);
    size_t raw = (size_t)64 * 64 * sizeof(float) * (size_t)proto_tile_planes(t.key.channels);
    assert_true(t.payload_len > 0 && t.payload_len < raw / 4);
    size_t usable = malloc_usable_size(t.payload);
    print_message("layout-0 tile: %u bytes kept in a %zu-byte block (raw planes %zu bytes)\n", t.payload_len,
                  usable, raw);
    assert_true(usable < (size_t)t.payload_len + 64);
    free(t.payload);
    ocean_frame_destroy(f);
    ocean_destroy(o);
}

static void frames_tiles_and_mesh_decode(void **state)
{
    (void)state;
    oc_client *c = connect_client(port, NULL);
    proto_hello hello;
    assert_int_equal(oc_client_hello(c, &hello), OCEAN_OK);
    assert_true(hello.max_layers == 3); /* 2 cascades + the near field's (layout 1) */
    assert_true(hello.codecs & (1u << PROTO_CODEC_QZ));
    proto_subscribe s;
    small_subscribe(&s);
    assert_int_equal(oc_client_subscribe(c, &s), OCEAN_OK);
    proto_camera cam;
    oc_camera_default(&cam);
    cam.pos[0] = 1234.5;
    cam.pos[2] = -987.25;
    assert_int_equal(oc_client_send_camera(c, &cam, NULL), OCEAN_OK);
    ocean *o = local_ocean();
    ocean_frame *lf;
    assert_int_equal(ocean_frame_create(o, &lf), OCEAN_OK);
    ocean_filter_config fc;
    ocean_filter_config_default(&fc, &settings.params.sea);
    int checked = 0;
    for (int k = 0; k < 40 && checked < 3; k++) {
        oc_frame *f = next_frame(c);
        if (f->info.camera_seq == PROTO_NO_CAMERA) {
            oc_frame_free(f);
            continue;
        }
        assert_int_equal(f->info.tile_count, 2 * 4);
        assert_true(f->info.has_mesh);
        assert_non_null(f->topology);
        assert_int_equal(f->topology->vertex_count, f->info.mesh.vertex_count);
        for (uint32_t i = 0; i < f->topology->index_count; i++)
            assert_true(f->topology->indices[i] < f->topology->vertex_count);
        for (uint32_t i = 0; i < 3 * f->info.mesh.vertex_count; i++)
            assert_true(isfinite(f->info.mesh.positions[i]));
        /* the camera lies inside every level's block of tiles */
        /* same evaluation locally: seed policy at rest, layer 0 only */
        ocean_request rq;
        memset(&rq, 0, sizeof rq);
        rq.effects[0] = OCEAN_FX_HEIGHT | OCEAN_FX_DISPLACEMENT | OCEAN_FX_NORMALS;
        rq.cutoff_k = f->info.cutoff_k;
        rq.order = fc.order;
        rq.low_boost = 1.0;
        assert_int_equal(ocean_evaluate(o, f->hdr.sim_time, &rq, lf), OCEAN_OK);
        double worst = 0;
        for (int t = 0; t < f->info.tile_count; t++) {
            const oc_tile *tl = &f->tiles[t];
            assert_int_equal(tl->decode_result, OCEAN_OK);
            assert_non_null(tl->data);
            assert_int_equal(tl->info.width, 32);
            assert_int_equal(tl->info.channels, PROTO_CH_HEIGHT | PROTO_CH_DX | PROTO_CH_DZ | PROTO_CH_NORMAL);
            /* world aligned: the origin is the tile index times the tile's size */
            double w = 32 * tl->info.spacing;
            assert_true(tl->info.origin_x == tl->info.ix * w && tl->info.origin_z == tl->info.iz * w);
            /* the camera is in the 2 x 2 block of its level */
            assert_true(fabs(tl->info.origin_x + w - cam.pos[0]) <= w * 1.5);
            assert_true(fabs(tl->info.origin_z + w - cam.pos[2]) <= w * 1.5);
            for (int i = 0; i < 32; i += 5)
                for (int j = 0; j < 32; j += 3) {
                    ocean_point p;
                    ocean_frame_sample(lf, tl->info.origin_x + j * tl->info.spacing,
                                       tl->info.origin_z + i * tl->info.spacing, &p);
                    double d = fabs(tl->data[i * 32 + j] - p.height);
                    if (d > worst) worst = d;
                    assert_true(d <= tl->info.error_bound + 1e-4);
                }
        }
        checked++;
        oc_frame_free(f);
    }
    assert_int_equal(checked, 3);
    ocean_frame_destroy(lf);
    ocean_destroy(o);
    oc_client_destroy(c);
}


/* ---- layout 1: cascade tiles ---------------------------------------------------- */

static void cascade_subscribe(proto_subscribe *s)
{
    oc_subscribe_default(s);
    /* these tests hold one frame's tiles against the sea at its own tick
     * (or count them): the plain stream, whose frames carry that tick's
     * tiles; a time-interpolating frame carries samples of other ticks */
    s->flags &= (uint8_t)~PROTO_SUB_TIME_INTERP;
    s->layout = PROTO_LAYOUT_CASCADE;
    s->effects = PROTO_FX_HEIGHT | PROTO_FX_DISPLACEMENT | PROTO_FX_NORMALS | PROTO_FX_FOAM;
    s->layers = 2;
    s->tile_size = 32;
    s->mesh_kind = PROTO_MESH_NONE;
}

/* The first frame answering camera seq `seq` (NULL after ms). */
static oc_frame *frame_for(oc_client *c, uint32_t seq)
{
    double t0 = test_now_s(), end = t0 + FRAME_WAIT_MS / 1000.0;
    while (test_now_s() < end) {
        oc_frame *f = NULL;
        if (oc_client_next_frame(c, 20, &f) != OCEAN_OK) continue;
        if (f->info.camera_seq == seq) {
            if (test_now_s() - t0 > SLOW_WAIT_S) print_message("the frame of camera %u after %.1f s\n", seq, test_now_s() - t0);
            return f;
        }
        oc_frame_free(f);
    }
    return NULL;
}

/* Layout 1: every tile is a grid point copy of its cascade's mip as the
 * simulation evaluates it (at the mip's cutoff, on the mip's grid), the
 * block describes the pyramid, and each mip the lod rule reads around
 * the camera is there (PROTOCOL.md "Where each mip is read"). */
static void cascade_tiles_are_the_mips(void **state)
{
    (void)state;
    oc_client *c = connect_client(port, NULL);
    proto_subscribe s;
    cascade_subscribe(&s);
    assert_int_equal(oc_client_subscribe(c, &s), OCEAN_OK);
    proto_camera cam;
    oc_camera_default(&cam);
    cam.pos[0] = 1234.5;
    cam.pos[1] = 25;
    cam.pos[2] = -987.25;
    uint32_t seq;
    assert_int_equal(oc_client_send_camera(c, &cam, &seq), OCEAN_OK);
    oc_frame *f = frame_for(c, seq);
    assert_non_null(f);
    assert_int_equal(f->info.layout, PROTO_LAYOUT_CASCADE);
    const proto_cascade_block *b = &f->info.cascades;
    assert_int_equal(b->cascade_count, 2);
    assert_true(b->camera[0] == cam.pos[0] && b->camera[1] == cam.pos[1] && b->camera[2] == cam.pos[2]);
    assert_true(b->spacing_per_m > 0);
    /* the short-wave tail (and the near field: the test config has one)
     * always travels as roughness; with normals nothing is lost (e_total 0) */
    assert_true(b->tail_mss[0] > 0 && b->tail_mss[1] > 0);
    assert_true(b->e_total == 0.0f);
    assert_true(f->info.e_error >= 0 && f->info.e_error <= 1);
    ocean *o = local_ocean();
    ocean_frame *lf;
    assert_int_equal(ocean_frame_create(o, &lf), OCEAN_OK);
    int mips[2];
    double kc[2][PROTO_MAX_MIPS];
    for (int k = 0; k < 2; k++) {
        assert_int_equal(ocean_cascade_mips(o, k, b->order, PROTO_MAX_MIPS, &mips[k], kc[k]), OCEAN_OK);
        assert_int_equal(b->cascade[k].mips, mips[k]);
        assert_true(b->cascade[k].patch_m > 0 && b->cascade[k].n == settings.params.n);
        /* the moments grow as mips lose waves; the whole cascade lacks the most */
        for (int m = 0; m < mips[k]; m++)
            assert_true(b->cascade[k].mip[m].mss_x + b->cascade[k].mip[m].mss_z <=
                        b->cascade[k].mip[m + 1].mss_x + b->cascade[k].mip[m + 1].mss_z);
        assert_true(b->cascade[k].mip[mips[k]].mss_x > 0);
    }
    /* which (cascade, mip) pairs the rule reads near the camera */
    int seen[2][PROTO_MAX_MIPS] = {{0}}, checked = 0;
    for (int m = 0; m < PROTO_MAX_MIPS; m++) {
        ocean_request rq;
        memset(&rq, 0, sizeof rq);
        int any = 0;
        for (int k = 0; k < 2; k++) {
            if (m >= mips[k]) continue;
            rq.effects[k] = OCEAN_FX_HEIGHT | OCEAN_FX_DISPLACEMENT | OCEAN_FX_NORMALS | OCEAN_FX_FOAM;
            rq.cascade_cutoff_k[k] = kc[k][m];
            any = 1;
        }
        if (!any) break;
        rq.cutoff_k = INFINITY;
        rq.order = b->order;
        rq.low_boost = 1;
        rq.per_cascade = 1;
        assert_int_equal(ocean_evaluate(o, f->hdr.sim_time, &rq, lf), OCEAN_OK);
        for (int t = 0; t < f->info.tile_count; t++) {
            const oc_tile *tl = &f->tiles[t];
            if (tl->info.level != m) continue;
            int k = tl->info.cascade;
            assert_true(k < 2);
            assert_int_equal(tl->decode_result, OCEAN_OK);
            /* every cascade carries its breaking index, no FOAM plane */
            assert_int_equal(tl->info.channels & (PROTO_CH_FOAM | PROTO_CH_BREAKING), PROTO_CH_BREAKING);
            const ocean_field *fd = ocean_frame_field(lf, k);
            int np = settings.params.n >> m, T = np < 32 ? np : 32;
            assert_int_equal(tl->info.width, T);
            assert_int_equal(fd->n, np);
            double sp = b->cascade[k].patch_m / b->cascade[k].n * ldexp(1.0, m);
            assert_true(tl->info.spacing == sp);
            assert_true(tl->info.origin_x == tl->info.ix * T * sp && tl->info.origin_z == tl->info.iz * T * sp);
            assert_true(tl->info.ix >= 0 && tl->info.ix < np / T && tl->info.iz >= 0 && tl->info.iz < np / T);
            for (int i = 0; i < T; i += 3)
                for (int j = 0; j < T; j += 5) {
                    size_t g = (size_t)(tl->info.iz * T + i) * (size_t)np + (size_t)(tl->info.ix * T + j);
                    assert_true(fabs(tl->data[i * T + j] - fd->height[g]) <= tl->info.error_bound + 1e-5);
                    /* BI, BQ: -(Dxx + Dzz) / lambda and -bq / lambda (foam.h) */
                    int off[PROTO_SLOT_COUNT];
                    proto_tile_plane_offsets(tl->info.channels, (size_t)T * T, off);
                    double il = 1.0 / settings.params.sea.choppiness;
                    assert_true(fabs(tl->data[off[PROTO_SLOT_BI] + i * T + j] + (fd->dxx[g] + fd->dzz[g]) * il) <=
                                tl->info.error_bound + 1e-5);
                    assert_true(fabs(tl->data[off[PROTO_SLOT_BQ] + i * T + j] + fd->bq[g] * il) <=
                                tl->info.error_bound + 1e-5);
                    checked++;
                }
            seen[k][m] = 1;
        }
    }
    assert_true(checked > 100);
    /* the camera's own tile of every mip the rule reads at its nadir is there */
    double cy = fmax(fabs(cam.pos[1]), 1.0);
    for (int k = 0; k < 2; k++) {
        /* each cascade at its own q (PROTOCOL.md "Where each mip is read") */
        double s0 = b->cascade[k].spacing_per_m * cy;
        assert_true(b->cascade[k].spacing_per_m <= b->spacing_per_m);
        double sigma = b->cascade[k].patch_m / b->cascade[k].n;
        double lam = log2(s0 / sigma);
        int m = lam <= 0 ? 0 : (int)floor(lam);
        if (m > mips[k] - 1) m = mips[k] - 1;
        assert_true(seen[k][m]);
        int np = settings.params.n >> m, T = np < 32 ? np : 32;
        double w = T * sigma * ldexp(1.0, m), P = b->cascade[k].patch_m;
        int ix = (int)floor(fmod(fmod(cam.pos[0], P) + P, P) / w), iz = (int)floor(fmod(fmod(cam.pos[2], P) + P, P) / w);
        int found = 0;
        for (int t = 0; t < f->info.tile_count; t++)
            found |= f->tiles[t].info.cascade == k && f->tiles[t].info.level == m && f->tiles[t].info.ix == ix &&
                     f->tiles[t].info.iz == iz;
        assert_true(found);
    }
    oc_frame_free(f);
    ocean_frame_destroy(lf);
    ocean_destroy(o);
    /* what layout 1 cannot serve is refused before any work, naming why */
    /* geometry only (no normals): what the tiles miss is lost (e_total = e_error) */
    proto_subscribe geo = s;
    geo.effects = PROTO_FX_HEIGHT | PROTO_FX_DISPLACEMENT;
    assert_int_equal(oc_client_subscribe(c, &geo), OCEAN_OK);
    cam.pos[1] = 400; /* high enough that the tiles miss some of the sea */
    assert_int_equal(oc_client_send_camera(c, &cam, &seq), OCEAN_OK);
    f = frame_for(c, seq);
    assert_non_null(f);
    assert_true(f->info.e_error > 0);
    assert_true(fabs(f->info.cascades.e_total - f->info.e_error) <= 1e-6);
    /* seed 000's guard: the daemon refines a geometry-only plan until at
     * most 5 % of the height variance is missing (within twice the budget) */
    print_message("geometry only at 400 m: e_total %.4f, q %.4g\n", (double)f->info.cascades.e_total,
                  (double)f->info.cascades.spacing_per_m);
    assert_true(f->info.cascades.e_total <= SRV_CASCADE_E_GUARD);
    for (int t = 0; t < f->info.tile_count; t++)
        assert_int_equal(f->tiles[t].info.channels, PROTO_CH_HEIGHT | PROTO_CH_DX | PROTO_CH_DZ);
    oc_frame_free(f);
    char e[512] = "";
    proto_subscribe bad = s;
    bad.mesh_kind = PROTO_MESH_PROJECTED;
    assert_int_equal(oc_client_subscribe(c, &bad), OCEAN_OK);
    for (int i = 0; i < 100 && oc_client_last_error(c, e, sizeof e) != OCEAN_EUNSUPPORTED; i++) oc_service(c, 20);
    assert_int_equal(oc_client_last_error(c, e, sizeof e), OCEAN_EUNSUPPORTED);
    assert_non_null(strstr(e, "layout"));
    oc_client_destroy(c);
}

/* Loads the built-in defaults with `sets` applied; asserts they load.
 * Admission for the daemon as a whole is off (server.admit_share 0): it
 * prices layout-0 subscriptions from what this host's cores do, and these
 * tests judge other behaviour, which a slow or busy host must not turn into
 * refusals (test_attacks daemon_capacity judges admission). */
static void load_settings(const char *const *sets, int n, srv_settings *out)
{
    char err[512];
    const char *all[40];
    assert_true(n < 39);
    for (int i = 0; i < n; i++) all[i] = sets[i];
    all[n] = "server.admit_share=0";
    ocean_result r = srv_settings_load(NULL, all, n + 1, out, err, sizeof err);
    if (r != OCEAN_OK) fprintf(stderr, "%s\n", err);
    assert_int_equal(r, OCEAN_OK);
}

/* A daemon in this process on the defaults with `sets` applied (their
 * settings in *out); asserts it starts. */
static srv_daemon *start_daemon(const char *const *sets, int n, srv_settings *out)
{
    char err[512];
    srv_daemon *d = NULL;
    load_settings(sets, n, out);
    ocean_result r = srv_daemon_start(out, &d, err, sizeof err);
    if (r != OCEAN_OK) fprintf(stderr, "%s\n", err);
    assert_int_equal(r, OCEAN_OK);
    return d;
}

/* The camera of the browser viewer on a bridge 25 m up (the scene `make
 * run` serves), looking a little down, on a 1920 x 1080 viewport. */
static void bridge_camera(proto_camera *cam)
{
    oc_camera_default(cam);
    cam->pos[0] = 321.5;
    cam->pos[1] = 25;
    cam->pos[2] = -77.25;
    cam->pitch_deg = -15.1;
    cam->fov_y_deg = 60;
    cam->viewport_w = 1920;
    cam->viewport_h = 1080;
}

/* A daemon in this process on the scene `make run` serves (ship-bridge, one
 * FFT thread, two workers); bridge_client adds a client of it with
 * callbacks cb (NULL: frames queued). */
static srv_daemon *bridge_daemon(srv_settings *sb)
{
    const char *sets[] = {"server.port=0", "server.scene=ship-bridge", "ocean.threads=1", "server.workers=2"};
    return start_daemon(sets, 4, sb);
}

static oc_client *bridge_client(srv_daemon **d, srv_settings *sb, const oc_callbacks *cb)
{
    *d = bridge_daemon(sb);
    return connect_client(srv_daemon_port(*d), cb);
}

/* Sends cam and waits for the frame that answers it (asserted). */
static oc_frame *frame_for_camera(oc_client *c, const proto_camera *cam)
{
    uint32_t seq;
    assert_int_equal(oc_client_send_camera(c, cam, &seq), OCEAN_OK);
    oc_frame *f = frame_for(c, seq);
    assert_non_null(f);
    return f;
}

/* A bridge_client subscribed as the viewer is (*s) but without a mesh, and
 * on the plain stream: the frames carry tiles alone, each frame its own
 * tick's, which the budget tests weigh against the byte budget of one
 * frame (a time-interpolating stream's plan counts each mip's tiles once
 * per update interval, PROTOCOL.md "Samples in time": it keeps the budget
 * on average, while a KEY frame, or one whose camera moved, brings both
 * samples of every tile it needs). */
static oc_client *bridge_tiles_client(srv_daemon **d, srv_settings *sb, proto_subscribe *s)
{
    /* at the byte budget the plain stream had before samples in time made
     * the viewer's stream a quarter of it (3.9e6 B/s, 130 KB a frame):
     * these tests are about how the planner spends a frame's budget, and
     * the shipped 0.85e6 spent on every tick's tiles leaves the finest
     * cascades out whatever the rule */
    const char *sets[] = {"server.port=0", "server.scene=ship-bridge", "ocean.threads=1", "server.workers=2",
                          "server.viewer_bytes_per_s=3.9e6"};
    *d = start_daemon(sets, 5, sb);
    oc_client *c = connect_client(srv_daemon_port(*d), NULL);
    oc_subscribe_default(s);
    s->flags &= (uint8_t)~PROTO_SUB_TIME_INTERP;
    s->mesh_kind = PROTO_MESH_NONE;
    assert_int_equal(oc_client_subscribe(c, s), OCEAN_OK);
    return c;
}

/* Layout 1's whitecaps (PROTOCOL.md "Whitecaps in layout 1") on the scene
 * `make run` serves, without a byte budget (the reading, not the plan, is
 * under test): the block carries the sea's whitecap table (its last row is
 * the whole sea's, near field included: above the FFT sea's own); the
 * foam the C library reads on a 400 m square under the camera keeps the
 * wind's coverage (the table's purpose: the fine cascades fade out over
 * the square and the ramp widens with them; 0.0194 against 0.0202 here);
 * and near the camera, where every cascade is read, the foam is the whole
 * sea's point by point: it follows the FFT sea's own foam (ocean_frame_sample
 * of an unfiltered evaluation, every wave summed at the point) with a
 * correlation of 0.93-0.98.  Cascade 0's breaking index alone, which placed
 * layout 1's foam before, holds a small part of the index's variance.  A
 * sea without whitecaps sends neither the table nor the planes. */
/* The mean foam oc_frame_sample_interp reads on a 400 m square about pos
 * (64 x 64 points); *n the points read. */
static double square_coverage(const oc_frame *f, const double pos[3], oc_interp in, int *n)
{
    double sum = 0;
    *n = 0;
    for (int i = 0; i < 64; i++)
        for (int j = 0; j < 64; j++) {
            oc_sample sm;
            if (oc_frame_sample_interp(f, pos[0] + 400 * ((j + 0.5) / 64 - 0.5), pos[2] + 400 * ((i + 0.5) / 64 - 0.5),
                                       0, in, &sm) != OCEAN_OK)
                continue;
            assert_true(sm.channels & PROTO_CH_BREAKING);
            sum += sm.foam;
            (*n)++;
        }
    return *n ? sum / *n : 0;
}

static void whitecaps_of_the_whole_sea(void **state)
{
    (void)state;
    const char *sets[] = {"server.port=0", "server.scene=ship-bridge", "ocean.threads=1", "server.workers=2",
                          "server.viewer_bytes_per_s=1e9"};
    srv_settings sb;
    srv_daemon *d = start_daemon(sets, 5, &sb);
    oc_client *c = connect_client(srv_daemon_port(d), NULL);
    proto_subscribe s;
    oc_subscribe_default(&s);
    s.flags &= (uint8_t)~PROTO_SUB_TIME_INTERP;
    s.mesh_kind = PROTO_MESH_NONE;
    s.effects &= (uint8_t)~PROTO_FX_NEAR_FIELD;   /* the FFT sea alone, as the exact foam below */
    assert_int_equal(oc_client_subscribe(c, &s), OCEAN_OK);
    proto_camera cam;
    bridge_camera(&cam);
    cam.pos[1] = 3;
    cam.pitch_deg = -30;
    oc_frame *f = frame_for_camera(c, &cam);
    const proto_cascade_block *b = &f->info.cascades;
    assert_true(b->flags & PROTO_CASCADE_FOAM);
    ocean *o;
    char msg[256];
    assert_int_equal(ocean_create(&sb.params, &o, msg, sizeof msg), OCEAN_OK);
    double kc[2] = {0.5, INFINITY};
    ocean_foam_row rows[2];
    int nr = 0;
    assert_int_equal(ocean_foam_table(o, NULL, b->order, kc, 2, rows, &nr), OCEAN_OK);
    /* the whole sea's row is the table's last but for the near field's
     * waves, which the daemon's table includes: its sigma is larger */
    assert_true(nr == 2 && b->foam_rows >= 8 && b->foam[b->foam_rows - 1].sigma > rows[1].sigma);
    double W = ocean_foam_coverage_target(sb.params.sea.wind_u10), cover[3];
    int n = 0;
    for (int k = 0; k < 3; k++)
        cover[k] = square_coverage(f, cam.pos, (oc_interp)k, &n);
    print_message("400 m square: %d points read, coverage %.4f (Keys), %.4f (bilinear), %.4f (Lanczos-3), "
                  "the wind's %.4f\n", n, cover[OC_INTERP_CUBIC], cover[OC_INTERP_LINEAR], cover[OC_INTERP_LANCZOS3], W);
    assert_true(n > 1000 && cover[OC_INTERP_CUBIC] > 0.7 * W && cover[OC_INTERP_CUBIC] < 1.3 * W);
    /* each kernel holds its own share of the breaking index's variance
     * (the frame's read table) and finds its ramp by it, so each reads the
     * same coverage of the same waves; by the mip tables alone bilinear
     * read 0.59 of Keys' here (0.0109 against 0.0185) */
    for (int k = 0; k < 3; k++)
        if (fabs(cover[k] / cover[OC_INTERP_CUBIC] - 1) > 0.1)
            fail_msg("interpolation %d reads %.4f, Keys %.4f", k, cover[k], cover[OC_INTERP_CUBIC]);
    /* near the camera: the exact FFT sea's foam */
    ocean_frame *ef;
    assert_int_equal(ocean_frame_create(o, &ef), OCEAN_OK);
    ocean_request rq;
    ocean_request_all(&rq, OCEAN_FX_ALL);
    assert_int_equal(ocean_evaluate(o, f->hdr.sim_time, &rq, ef), OCEAN_OK);
    double sa = 0, sb2 = 0, saa = 0, sbb = 0, sab = 0;
    int m = 0;
    for (int i = 0; i < 400; i++) {
        double x = cam.pos[0] + 12.0 * ((i % 20) / 19.0 - 0.5), z = cam.pos[2] + 12.0 * ((i / 20) / 19.0 - 0.5);
        oc_sample sm;
        ocean_point pt;
        if (oc_frame_sample(f, x, z, 0, &sm) != OCEAN_OK) continue;
        ocean_frame_sample(ef, x, z, &pt);
        sa += sm.foam, sb2 += pt.foam, saa += sm.foam * sm.foam, sbb += pt.foam * pt.foam, sab += sm.foam * pt.foam;
        m++;
    }
    double cov = sab / m - sa / m * sb2 / m, corr = cov / sqrt((saa / m - sa * sa / m / m) * (sbb / m - sb2 * sb2 / m / m));
    print_message("12 m square at the nadir: %d points, foam %.4f against the exact %.4f, correlation %.3f\n", m,
                  sa / m, sb2 / m, corr);
    /* the pattern, not the mean: on 12 m a few whitecaps make the mean,
     * and the exact field's ramp is solved for its own bilinear reading of
     * the band, the table's for the band itself, so the two means differ
     * by 1-36 % between instants (the coverage is judged on 400 m above) */
    assert_true(m == 400 && corr > 0.8);
    ocean_frame_destroy(ef);
    ocean_destroy(o);
    oc_frame_free(f);
    oc_client_destroy(c);
    srv_daemon_stop(d);
    /* a sea without whitecaps (a CIGI host's Maritime Surface Conditions,
     * sea.whitecaps off): no table, no breaking planes, foam 0 everywhere */
    const char *off[] = {"server.port=0", "server.scene=ship-bridge", "ocean.threads=1", "server.workers=2",
                         "server.viewer_bytes_per_s=1e9", "sea.whitecaps=off"};
    d = start_daemon(off, 6, &sb);
    c = connect_client(srv_daemon_port(d), NULL);
    assert_int_equal(oc_client_subscribe(c, &s), OCEAN_OK);
    f = frame_for_camera(c, &cam);
    assert_true(!(f->info.cascades.flags & PROTO_CASCADE_FOAM) && f->info.tile_count > 0);
    for (int t = 0; t < f->info.tile_count; t++) assert_false(f->tiles[t].info.channels & PROTO_CH_BREAKING);
    oc_sample sm;
    assert_int_equal(oc_frame_sample(f, cam.pos[0] + 3, cam.pos[2] - 2, 0, &sm), OCEAN_OK);
    assert_true(sm.foam == 0 && !(sm.channels & PROTO_CH_BREAKING));
    oc_frame_free(f);
    oc_client_destroy(c);
    srv_daemon_stop(d);
}

/* A daemon on the scene `make run` serves at byte budget `budget` and two
 * clients of it with the viewer's subscription without a mesh: *a the
 * plain stream, *b samples in time (the viewer's). */
static srv_daemon *plain_and_timed(const char *budget, srv_settings *sb, oc_client **a, oc_client **b)
{
    char set[64];
    snprintf(set, sizeof set, "server.viewer_bytes_per_s=%s", budget);
    const char *sets[] = {"server.port=0", "server.scene=ship-bridge", "ocean.threads=1", "server.workers=2", set};
    srv_daemon *d = start_daemon(sets, 5, sb);
    *a = connect_client(srv_daemon_port(d), NULL);
    *b = connect_client(srv_daemon_port(d), NULL);
    proto_subscribe s;
    oc_subscribe_default(&s);
    s.mesh_kind = PROTO_MESH_NONE;
    s.flags &= (uint8_t)~PROTO_SUB_TIME_INTERP;
    assert_int_equal(oc_client_subscribe(*a, &s), OCEAN_OK);
    s.flags |= PROTO_SUB_TIME_INTERP;
    assert_int_equal(oc_client_subscribe(*b, &s), OCEAN_OK);
    return d;
}

/* Samples in time (PROTOCOL.md): a client that interpolates in time reads,
 * at every frame, what a client sent every sample at that frame's tick
 * reads, within the quantiser's error, for a fraction of the bytes.  The
 * byte budget is lifted so that both plan the same mips. */
static void time_interp_reads_the_frames_tick(void **state)
{
    (void)state;
    srv_settings sb;
    oc_client *a, *b;
    srv_daemon *d = plain_and_timed("1e9", &sb, &a, &b);
    proto_camera cam;
    bridge_camera(&cam);
    cam.viewport_w = 320; /* a plan both clients make whole, at server.px_per_sample */
    cam.viewport_h = 180;
    double bytes_a = 0, bytes_b = 0, se = 0, sv = 0;
    int compared = 0, points = 0, missing = 0, keys = 0, deltas = 0, interp = 0, frames_a = 0, frames_b = 0;
    uint32_t seq;
    assert_int_equal(oc_client_send_camera(a, &cam, &seq), OCEAN_OK);
    assert_int_equal(oc_client_send_camera(b, &cam, &seq), OCEAN_OK);
    /* the last frames of each, by tick, to meet the other's frame of the
     * same tick (either may lag: a sanitized reader decodes slowly) */
    oc_frame *ra[16] = {0}, *rb[16] = {0};
    int nb[16] = {0};
    double end = test_now_s() + (sanitized ? 120.0 : 40.0);
    while (compared < 12 && test_now_s() < end) {
        oc_frame *f = NULL;
        uint32_t tick = 0;
        if (oc_client_next_frame(a, 5, &f) == OCEAN_OK) {
            if (frames_a++ >= 8) bytes_a += f->raw_len;
            tick = f->info.tick;
            oc_frame_free(ra[tick % 16]);
            ra[tick % 16] = f;
        } else if (oc_client_next_frame(b, 5, &f) == OCEAN_OK) {
            if (frames_b++ >= 8) bytes_b += f->raw_len;
            /* KEY frames only at the start: each that replaced an unsent
             * one (a busy host) is KEY again; none after the first delta
             * frame */
            int key = (f->info.cascades.flags & PROTO_CASCADE_KEY) != 0;
            assert_true(frames_b > 1 || key);
            if (!key) deltas++;
            else keys += deltas > 0;
            for (int c = 0; c < f->info.cascades.cascade_count; c++)
                for (int m = 0; m < f->info.cascades.cascade[c].mips; m++)
                    interp += f->info.cascades.cascade[c].time[m].interval > 0;
            assert_int_equal(f->view_result, OCEAN_OK);
            tick = f->info.tick;
            oc_frame_free(rb[tick % 16]);
            rb[tick % 16] = f;
            nb[tick % 16] = frames_b;
        } else {
            continue;
        }
        oc_frame *fa = ra[tick % 16], *fb = rb[tick % 16];
        if (!fa || !fb || fa->info.tick != fb->info.tick) continue;
        /* b's first frames bring what it lacks over a few frames */
        if (nb[tick % 16] > 8 && fa->view_result == OCEAN_OK) {
            compared++;
            for (int i = 0; i < 15; i++)
                for (int k = 0; k < 15; k++) {
                    double x = cam.pos[0] + 20.0 * (i - 7), z = cam.pos[2] + 20.0 * (k - 7);
                    oc_sample pa, pb;
                    if (oc_frame_sample(fa, x, z, 0, &pa) != OCEAN_OK)
                        continue;
                    /* what the plain frame covers, the held samples cover */
                    if (oc_frame_sample(fb, x, z, 0, &pb) != OCEAN_OK) {
                        missing++;
                        continue;
                    }
                    se += (pa.height - pb.height) * (pa.height - pb.height);
                    sv += pa.height * pa.height;
                    points++;
                }
        }
        oc_frame_free(fa);
        oc_frame_free(fb);
        ra[tick % 16] = rb[tick % 16] = NULL;
    }
    for (int i = 0; i < 16; i++) oc_frame_free(ra[i]), oc_frame_free(rb[i]);
    frames_a -= 8;
    frames_b -= 8;
    print_message("time interp: %d frames compared (%d points, %d not held), height error RMS %.4f of RMS %.3f m; "
                  "bytes/frame %.0f plain, %.0f interpolating; %d key frames after a delta\n",
                  compared, points, missing, sqrt(se / fmax(points, 1)), sqrt(sv / fmax(points, 1)),
                  bytes_a / fmax(frames_a, 1), bytes_b / fmax(frames_b, 1), keys);
    assert_true(compared >= 10);
    assert_true(points >= 50 * compared);
    assert_int_equal(missing, 0);
    assert_int_equal(keys, 0);
    assert_true(interp > 0);
    /* within the quantiser's RMS error at the default accuracy, 2 sqrt(3) a
     * of each band's RMS, summed over the bands: well under 5 % */
    assert_true(sqrt(se / points) <= 0.05 * sqrt(sv / points));
    /* the bytes saved depend on the reader keeping up (a frame that
     * replaces an unsent one carries what that one did): printed here,
     * measured in make bench, never asserted on a host's speed */
    oc_client_destroy(a);
    oc_client_destroy(b);
    srv_daemon_stop(d);
}

/* What a time-interpolating client lacks can come at once (a KEY frame
 * holds every sample); a frame carries at most SRV_CASCADE_BURST_A frame
 * budgets of held samples (estimated by the planner's byte model) and the
 * rest follows in the next frames: no frame is several budgets long on
 * its link, and within a few frames the client holds everything the
 * plain stream's frame covers. */
static void time_interp_key_frame_spread(void **state)
{
    (void)state;
    srv_settings sb;
    oc_client *a, *b;
    srv_daemon *d = plain_and_timed("1.5e6", &sb, &a, &b);
    proto_camera cam;
    bridge_camera(&cam);
    uint32_t seq;
    assert_int_equal(oc_client_send_camera(a, &cam, &seq), OCEAN_OK);
    assert_int_equal(oc_client_send_camera(b, &cam, &seq), OCEAN_OK);
    /* the byte model is the planner's estimate; the encoder's bytes are
     * within a quarter of it on these tiles (bench_codec) */
    double cap = SRV_CASCADE_BURST_A * 1.5e6 / 30.0 * 1.25, biggest = 0, first = 0;
    int frames = 0, whole_at = -1, plain_points = 0, gaps = 0;
    oc_frame *plain = NULL, *got[40] = {0};
    /* the timed stream's frames are kept and judged once the plain
     * stream's frame is in: when that frame comes is the other stream's
     * pace on this host, not something the frame count should carry */
    double end = test_now_s() + (sanitized ? 120.0 : 40.0);
    while ((frames < 40 || !plain) && test_now_s() < end) {
        oc_frame *f = NULL;
        if (!plain && oc_client_next_frame(a, 5, &f) == OCEAN_OK) {
            if (f->info.camera_seq != PROTO_NO_CAMERA)
                plain = f;  /* the plain stream's view of the camera */
            else
                oc_frame_free(f);
        }
        if (frames == 40 || oc_client_next_frame(b, 5, &f) != OCEAN_OK) continue;
        if (f->info.camera_seq == PROTO_NO_CAMERA) {
            oc_frame_free(f);
            continue;
        }
        assert_int_equal(f->view_result, OCEAN_OK);
        got[frames++] = f;
    }
    assert_non_null(plain);
    for (int n = 0; n < frames; n++) {
        oc_frame *f = got[n];
        if (!n) first = (double)f->raw_len;
        biggest = fmax(biggest, (double)f->raw_len);
        /* points ahead of the camera (yaw 0: +x), where both plans read */
        int held = 0, covered = 0;
        for (int i = 1; i <= 15; i++)
            for (int k = -7; k <= 7; k++) {
                double x = cam.pos[0] + 20.0 * i, z = cam.pos[2] + 20.0 * k;
                oc_sample p;
                if (2 * abs(k) > i || oc_frame_sample(plain, x, z, 0, &p) != OCEAN_OK) continue;
                covered++;
                held += oc_frame_sample(f, x, z, 0, &p) == OCEAN_OK;
            }
        if (whole_at < 0 && covered && held == covered) whole_at = n, plain_points = covered;
        if (whole_at >= 0 && held < covered) gaps++;
        oc_frame_free(f);
    }
    print_message("key frame spread: first frame %.0f bytes, largest %.0f (cap %.0f with the model's margin); "
                  "everything the plain frame covers (%d points) held from frame %d, %d frames with gaps after\n",
                  first, biggest, cap, plain_points, whole_at, gaps);
    assert_true(frames >= 20);
    assert_true(biggest <= cap);
    /* a frame planned while the one before waits unsent builds on what
     * the client holds with it and without it: at most the first few
     * are KEY frames, then the sea fills in */
    assert_true(whole_at >= 0 && whole_at < 6);
    assert_int_equal(gaps, 0);
    assert_true(plain_points >= 50);
    oc_frame_free(plain);
    oc_client_destroy(a);
    oc_client_destroy(b);
    srv_daemon_stop(d);
}

/* Frames a link-shaped reader received: wire size, and age (the daemon's
 * sim clock at receipt minus the frame's sim time); with `follow`, the
 * frames whose view did not read the sea in front of the camera. */
typedef struct shaped_frames {
    int n;
    double at[2048], bytes[2048], age[2048];
    double built[2048];      /* the daemon's frames_built when each arrived */
    int unfollowed;
    int read_once, filling;  /* the sea read once; frames before that */
    char why[200];
} shaped_frames;

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* The median of v[i] over frames received at or after `from` (s). */
static double median_since(const shaped_frames *f, const double *v, double from, int *count)
{
    static double tmp[2048];
    int k = 0;
    for (int i = 0; i < f->n; i++)
        if (f->at[i] >= from) tmp[k++] = v[i];
    *count = k;
    if (!k) return NAN;
    qsort(tmp, (size_t)k, sizeof *tmp, cmp_double);
    return tmp[k / 2];
}

/* Frame msg of a followed stream s: decoded in order, as a client does on
 * receipt, and read 30 m in front of the camera; counted in `out` when
 * either fails. */
static void follow_frame(oc_frame_stream *s, const uint8_t *msg, size_t len, const proto_camera *cam,
                         shaped_frames *out)
{
    oc_frame *f = NULL;
    char err[160] = "";
    ocean_result r = oc_frame_stream_decode(s, msg, len, &f, err, sizeof err);
    oc_sample sm;
    /* frames made before the camera's first report look elsewhere */
    int for_cam = r == OCEAN_OK && f->info.camera_seq != PROTO_NO_CAMERA;
    if (for_cam) r = oc_frame_sample(f, cam->pos[0] + 30, cam->pos[2], 0, &sm);
    /* what the client lacks at first comes over a few frames (at most
     * twice a frame's budget each): not read yet is not a miss */
    if (r == OCEAN_ENOTFOUND && !out->read_once && out->filling < 10) {
        out->filling++;
        r = OCEAN_OK;
    } else if (r == OCEAN_OK && for_cam) {
        out->read_once = 1;
    }
    if (r != OCEAN_OK && !out->unfollowed++)
        snprintf(out->why, sizeof out->why, "frame %d: %s %s", out->n, ocean_strerror(r), err);
    oc_frame_free(f);
}

/* A viewer behind a link of `bps` bytes/s (a 32 KB receive buffer, reads
 * paced to bps; 0: unshaped) reporting its camera report_hz times a second
 * with the sim time of the last frame it received, for secs.  follow: with
 * the viewer's subscription (samples in time), every frame decoded through
 * one oc_frame_stream and read; else the plain stream, whose frames this
 * reader need not decode (its CPU must not slow its reading). */
static void read_through_link(srv_daemon *d, double bps, double report_hz, double secs, int follow,
                              shaped_frames *out)
{
    srv_hub *h = srv_daemon_hub(d);
    test_ws w;
    assert_int_equal(test_ws_connect(&w, srv_daemon_port(d), "/", PROTO_SUBPROTOCOL), 0);
    if (bps > 0) test_ws_small_rcvbuf(&w, 32768);
    proto_msg m;
    proto_msg_init(&m, PROTO_SUBSCRIBE);
    oc_subscribe_default(&m.u.subscribe);
    if (!follow) m.u.subscribe.flags &= (uint8_t)~PROTO_SUB_TIME_INTERP;
    test_msg_send(&w, &m);
    oc_frame_stream *fs = NULL;
    if (follow) assert_int_equal(oc_frame_stream_create(&fs), OCEAN_OK);
    proto_camera cam;
    bridge_camera(&cam);
    double t0 = test_now_s(), next_cam = t0, last_t = 0, tokens = 0, tokens_t = t0;
    memset(out, 0, sizeof *out);
    while (test_now_s() - t0 < secs) {
        double now = test_now_s();
        if (now >= next_cam) {
            proto_msg_init(&m, PROTO_CAMERA);
            m.u.camera = cam;
            m.hdr.sim_time = last_t;
            test_msg_send(&w, &m);
            next_cam += 1.0 / report_hz;
        }
        /* the link: bps, with a burst of a tenth of a second */
        tokens = fmin(tokens + bps * (now - tokens_t), 0.1 * bps);
        tokens_t = now;
        if (bps > 0 && tokens <= 0) {
            usleep(2000);
            continue;
        }
        uint8_t *msg = NULL;
        size_t len = 0;
        int op = test_ws_recv(&w, 5, &msg, &len);
        if (op < 0) fail_msg("the shaped reader was disconnected");
        if (op == 2 && len >= PROTO_HEADER_SIZE) {
            tokens -= (double)len;
            if (proto_ld16(msg + 6) == PROTO_FRAME && fs) follow_frame(fs, msg, len, &cam, out);
            if (proto_ld16(msg + 6) == PROTO_FRAME && out->n < 2048) {
                last_t = proto_ldf64(msg + 24);
                out->at[out->n] = test_now_s() - t0;
                out->bytes[out->n] = (double)len;
                out->age[out->n] = srv_hub_sim_time(h) - last_t;
                out->built[out->n] = (double)stat_of(&h->stats.frames_built);
                out->n++;
            }
        }
        free(msg);
    }
    oc_frame_stream_destroy(fs);
    test_ws_close(&w);
}

/* A viewer on a slow link gets coarser frames, never older ones: behind a
 * link of under half of what the viewer's frames take at the ceiling
 * (server.viewer_bytes_per_s; 1 MB/s against 3.9 when that was the
 * ceiling, 0.4 against 0.85 now) it received frames of the ceiling's size
 * ever further behind the clock, buffered in the sockets.  Now the daemon holds
 * a frame while three are unconfirmed and plans that viewer's frames for
 * the rate its link delivers (srv_link.h).  The viewer's subscription
 * samples in time: the frames that replace unsent ones on this link are
 * planned from what the client held before them, and every frame, decoded
 * in order, reads the sea in front of the camera.
 *
 * In the last 4 s the frames are under a third of a second old and the
 * link carries (nearly) every frame the daemon built for this viewer: at
 * the ceiling's size it carried under half of them, the rest replaced
 * while they waited.  That share, not the frames' size, is the measure: a
 * daemon that cannot build 30 frames a second (a loaded host, a sanitizer)
 * rightly plans bigger frames for the rate it does build, and each frame
 * may carry what the client lacks after frames were replaced (the burst
 * caps of srv_cascade.h).
 *
 * The stream begins with two MESH_TOPOLOGYs of about a megabyte together
 * (the layout-1 mesh at server.flat_mesh_error_px = 8): 2.5 s of this link.
 * While they passed, the client named no new frame for over a second, the
 * link took it for quiet and let frames pile up behind them, and 6-10 s in
 * it still carried 70 % of the frames built; now a topology is part of the
 * frame it comes before (srv_link.h), and a client naming its last frame
 * again is no quiet one. */
static void slow_link_gets_coarser_not_older(void **state)
{
    (void)state;
    srv_settings sb;
    srv_daemon *d = bridge_daemon(&sb);
    srv_hub *h = srv_daemon_hub(d);
    const double bps = 0.4e6, secs = sanitized ? 14 : 10;
    static shaped_frames f;
    read_through_link(d, bps, 30, secs, 1, &f);
    int n_size, n_age;
    double size = median_since(&f, f.bytes, secs - 4, &n_size), age = median_since(&f, f.age, secs - 4, &n_age);
    double early = median_since(&f, f.bytes, 0, &n_age);
    double built = n_size > 1 ? f.built[f.n - 1] - f.built[f.n - n_size] : 0;
    double share = built > 0 ? (n_size - 1) / built : 0;
    print_message("%.2g MB/s link: %d frames; last 4 s: %d frames of %.0f built (%.0f %%), median %.0f B (all "
                  "frames' median %.0f, ceiling %.0f a frame), median age %.3f s; %llu frames held; %d frames not "
                  "followed %s\n", bps / 1e6, f.n, n_size, built, 100 * share, size, early,
                  sb.srv.viewer_bytes_per_s / 30, age, (unsigned long long)stat_of(&h->stats.frames_held),
                  f.unfollowed, f.why);
    if (f.unfollowed) fail_msg("%d frames of the stream did not read the sea (first: %s)", f.unfollowed, f.why);
    if (n_size < (sanitized ? 8 : 20)) fail_msg("only %d frames in the last 4 s through a %.0f B/s link", n_size, bps);
    if (share < 0.75)
        fail_msg("the link carried %.0f %% of the %.0f frames built in the last 4 s (median %.0f B through %.0f B/s)",
                 100 * share, built, size, bps);
    if (age > (sanitized ? 0.6 : 0.35)) fail_msg("frames %.3f s old through a %.0f B/s link", age, bps);
    assert_true(stat_of(&h->stats.frames_held) > 0);
    srv_daemon_stop(d);
}

/* Pacing follows how often a client reports, not a fixed count: a viewer
 * on a fast link that reports its camera twice a second still gets its
 * 30 frames a second (a window of three unconfirmed frames held it to six). */
static void rare_reports_are_not_held(void **state)
{
    (void)state;
    srv_settings sb;
    srv_daemon *d = bridge_daemon(&sb);
    const double secs = sanitized ? 10 : 6;
    static shaped_frames f;
    read_through_link(d, 0, 2, secs, 0, &f);
    int n;
    double size = median_since(&f, f.bytes, secs - 3, &n);
    print_message("reports at 2 Hz, unshaped: %d frames in the last 3 s (median %.0f B)\n", n, size);
    /* 90 expected; the fixed window gave 18 (6 a second): a loose bound
     * holds on a busy host and still tells the two apart */
    if (n < (sanitized ? 30 : 45)) fail_msg("%d frames in 3 s at 30 Hz with camera reports at 2 Hz", n);
    srv_daemon_stop(d);
}

/* What a client receives while it re-sends SUBSCRIBE. */
typedef struct resub_count {
    int frames, topologies, erate;
    char erate_text[200];
} resub_count;

static void resub_on_message(void *user, oc_client *c, const uint8_t *raw, size_t len, const proto_msg *m,
                             ocean_result res)
{
    (void)c, (void)raw, (void)len;
    resub_count *k = user;
    if (res != OCEAN_OK || !m) return;
    k->frames += m->hdr.type == PROTO_FRAME;
    k->topologies += m->hdr.type == PROTO_MESH_TOPOLOGY;
}

static void resub_on_error(void *user, oc_client *c, const proto_error *e)
{
    (void)c;
    resub_count *k = user;
    if (e->code != OCEAN_ERATE) return;
    k->erate++;
    snprintf(k->erate_text, sizeof k->erate_text, "%.150s", e->message);
}

/* Reads the client's stream for secs seconds (frames taken and dropped). */
static void pump(oc_client *c, double secs)
{
    double end = test_now_s() + secs;
    while (test_now_s() < end) {
        oc_frame *f = NULL;
        if (oc_client_next_frame(c, 20, &f) == OCEAN_OK) oc_frame_free(f);
    }
}

/* Re-sending SUBSCRIBE buys no frames (each one restarted the stream: a
 * client re-subscribing every tick at 0.05 Hz got a full frame and a
 * topology every tick, 6.7 MB/s): the same SUBSCRIBE changes nothing and
 * sends nothing; a changed one keeps the stream's schedule at its rate, and
 * changes beyond SRV_SUBSCRIBE_BURST, SRV_SUBSCRIBE_PER_S a second, are
 * refused with ERATE. */
static void resubscribe_buys_no_frames(void **state)
{
    (void)state;
    srv_settings sb;
    srv_daemon *d;
    resub_count k = {0};
    oc_callbacks cb = {.user = &k, .on_message = resub_on_message, .on_error = resub_on_error};
    oc_client *c = bridge_client(&d, &sb, &cb);
    proto_subscribe s;
    oc_subscribe_default(&s);
    s.frame_rate_hz = 1;
    assert_int_equal(oc_client_subscribe(c, &s), OCEAN_OK);
    proto_camera cam;
    bridge_camera(&cam);
    oc_frame_free(frame_for_camera(c, &cam));
    pump(c, 0.2);
    int f0 = k.frames, t0 = k.topologies;
    double t_start = test_now_s();
    for (int i = 0; i < 30; i++) {
        assert_int_equal(oc_client_subscribe(c, &s), OCEAN_OK);
        pump(c, 0.05);
    }
    double secs = test_now_s() - t_start;
    print_message("the same SUBSCRIBE 30 times in %.2f s at 1 Hz: %d frames, %d topologies, %d ERATE\n", secs,
                  k.frames - f0, k.topologies - t0, k.erate);
    if (k.frames - f0 > (int)secs + 2) fail_msg("%d frames in %.2f s at 1 Hz", k.frames - f0, secs);
    assert_int_equal(k.topologies, t0);
    assert_int_equal(k.erate, 0);
    f0 = k.frames;
    t_start = test_now_s();
    for (int i = 0; i < 10; i++) {
        s.accuracy = i % 2 ? 5e-3f : 6e-3f;
        assert_int_equal(oc_client_subscribe(c, &s), OCEAN_OK);
        pump(c, 0.02);
    }
    pump(c, 0.3);
    secs = test_now_s() - t_start;
    print_message("10 changed SUBSCRIBEs in %.2f s at 1 Hz: %d frames, %d ERATE\n", secs, k.frames - f0, k.erate);
    if (k.frames - f0 > (int)secs + 2) fail_msg("%d frames in %.2f s at 1 Hz", k.frames - f0, secs);
    if (secs < 2.5 && k.erate < 1) fail_msg("10 changes in %.2f s and none refused", secs);
    if (k.erate) assert_non_null(strstr(k.erate_text, "SUBSCRIBE changes limited"));
    oc_client_destroy(c);
    srv_daemon_stop(d);
}

/* The byte budget holds whatever the field of view: a binocular or sensor
 * view (5 and 2 deg) and degenerate ones (1e-20 deg and the smallest float,
 * 1.4e-45 deg) each get frames within the budget.  The smallest float asked
 * for q = 1.5e-37, whose plan 40 octaves could not coarsen to fit: 335
 * tiles, 856 KB a frame against 130 KB. */
static void narrow_fov_keeps_the_budget(void **state)
{
    (void)state;
    srv_settings sb;
    srv_daemon *d;
    proto_subscribe s;
    oc_client *c = bridge_tiles_client(&d, &sb, &s);
    const float fovs[] = {5.0f, 2.0f, 1e-20f, FLT_TRUE_MIN};
    double budget = sb.srv.viewer_bytes_per_s / s.frame_rate_hz;
    for (size_t k = 0; k < sizeof fovs / sizeof fovs[0]; k++) {
        proto_camera cam;
        bridge_camera(&cam);
        cam.fov_y_deg = fovs[k];
        oc_frame *f = frame_for_camera(c, &cam);
        double bytes = 0;
        for (int t = 0; t < f->info.tile_count; t++) bytes += 64.0 + f->tiles[t].info.payload_len;
        print_message("fov %g deg: q %.4g, %d tiles, %.0f of %.0f B\n", (double)fovs[k],
                      (double)f->info.cascades.spacing_per_m, f->info.tile_count, bytes, budget);
        if (bytes > 1.25 * budget)
            fail_msg("fov %g deg: %.0f tile bytes against a budget of %.0f a frame", (double)fovs[k], bytes, budget);
        assert_true(f->info.tile_count > 0);
        oc_frame_free(f);
    }
    oc_client_destroy(c);
    srv_daemon_stop(d);
}

/* Each cascade its own q.  With one q for every cascade, a plan stops
 * where the next quarter octave of every cascade together does not fit,
 * and a coarse cascade's step costs whole tiles 125 m wide: a camera 25 m
 * up over the scene `make run` serves, with the viewer's subscription and
 * viewport, got 111 of its 130 KB a frame, and at accuracy 1e-3 the finest
 * FFT cascade (54 m patch, where the near sea's slopes are) sent no tile.
 * Now the cascades refine on their own within what is left: some entry's
 * q is below the block's, the finest FFT cascade has tiles, every point of
 * the visible sea reads from tiles the frame has (the server's tile set
 * follows the per-cascade rule the client applies), and the frame spends
 * its budget without passing it. */
static void cascade_q_spends_the_budget(void **state)
{
    (void)state;
    srv_settings sb;
    srv_daemon *d;
    proto_subscribe s;
    oc_client *c = bridge_tiles_client(&d, &sb, &s);
    proto_camera cam;
    bridge_camera(&cam);
    uint32_t seq;
    assert_int_equal(oc_client_send_camera(c, &cam, &seq), OCEAN_OK);
    oc_frame *f = frame_for(c, seq);
    assert_non_null(f);
    const proto_cascade_block *b = &f->info.cascades;
    assert_true(b->cascade_count >= 3);
    int refined = 0, fine_tiles = 0;
    double bytes = 0;
    for (int k = 0; k < b->cascade_count; k++) {
        assert_true(b->cascade[k].spacing_per_m > 0 && b->cascade[k].spacing_per_m <= b->spacing_per_m);
        refined += b->cascade[k].spacing_per_m < b->spacing_per_m;
    }
    for (int t = 0; t < f->info.tile_count; t++) {
        fine_tiles += f->tiles[t].info.cascade == 2;
        bytes += 64.0 + f->tiles[t].info.payload_len;
    }
    double budget = sb.srv.viewer_bytes_per_s / s.frame_rate_hz;
    print_message("25 m: q %.4g; cascade q %.4g %.4g %.4g; %d tiles, %d of the finest FFT cascade; %.0f of %.0f B\n",
                  (double)b->spacing_per_m, (double)b->cascade[0].spacing_per_m, (double)b->cascade[1].spacing_per_m,
                  (double)b->cascade[2].spacing_per_m, f->info.tile_count, fine_tiles, bytes, budget);
    assert_true(refined >= 1);
    if (fine_tiles == 0) fail_msg("the finest FFT cascade sent no tile to a camera 25 m up");
    /* for this camera one q left 15 % of the budget unspent (111 of 130 KB
     * with 5-plane tiles); the refinement's steps are whole quarter octaves
     * of a cascade, which with the breaking planes (7-plane tiles, 38 %
     * more bytes a tile) leave up to 12 % (115 of 130 KB) */
    if (!(bytes >= 0.85 * budget && bytes <= 1.25 * budget))
        fail_msg("%.0f tile bytes against a budget of %.0f a frame", bytes, budget);
    /* every point of the sea in view reads from the frame's tiles */
    int points = 0;
    for (double r = 30; r < 3000; r *= 1.3)
        for (double a = -40; a <= 40; a += 8) {
            double th = (cam.yaw_deg + a) * M_PI / 180;
            double x = cam.pos[0] + r * cos(th), z = cam.pos[2] + r * sin(th); /* yaw 0 looks along +x */
            oc_sample sm;
            ocean_result rr = oc_frame_sample(f, x, z, 0, &sm);
            if (rr != OCEAN_OK) fail_msg("no tile at %.1f m, %.0f deg: %s", r, a, ocean_strerror(rr));
            points++;
        }
    assert_true(points > 100);
    oc_frame_free(f);
    oc_client_destroy(c);
    srv_daemon_stop(d);
}

/* A daemon in this process on the storm scene (defaults otherwise) and a
 * client of it with the viewer's subscription, its mesh included. */
static oc_client *storm_viewer(srv_daemon **d, srv_settings *sb)
{
    const char *sets[] = {"server.port=0", "server.scene=storm", "ocean.threads=1", "server.workers=2"};
    *d = start_daemon(sets, 4, sb);
    oc_client *c = connect_client(srv_daemon_port(*d), NULL);
    proto_subscribe s;
    oc_subscribe_default(&s);
    assert_int_equal(oc_client_subscribe(c, &s), OCEAN_OK);
    return c;
}

/* From altitude the plan fits the budget with bytes to spare, and spends
 * them on detail down to a sample a pixel (server.px_per_sample): over
 * the storm from 10 km, looking down, every cascade's q is the finest
 * wanted, 1 / (pixels per radian).  At 4 px the waves between one and
 * four pixels reached the shading only as a smooth lobe where the exact
 * sea has glints: SSIM against its render 0.84, 0.95 at 1 px (REPORT.md,
 * bench_look), for 0.69 MB/s of the 0.85 MB/s budget at 1920 x 1080. */
static void altitude_plan_reaches_a_sample_a_pixel(void **state)
{
    (void)state;
    srv_settings sb;
    srv_daemon *d;
    oc_client *c = storm_viewer(&d, &sb);
    proto_camera cam;
    oc_camera_default(&cam);
    cam.pos[1] = 10000;
    cam.pitch_deg = -89;
    cam.yaw_deg = 30;
    cam.fov_y_deg = 60;
    cam.viewport_w = 1280;
    cam.viewport_h = 720;
    oc_frame *f = frame_for_camera(c, &cam);
    const proto_cascade_block *b = &f->info.cascades;
    double ppr = 0.5 * cam.viewport_h / tan(0.5 * cam.fov_y_deg * M_PI / 180.0);
    assert_true(b->cascade_count >= 3);
    for (int k = 0; k < b->cascade_count; k++) {
        print_message("10 km: cascade %d q %.5f (a sample a pixel: %.5f)\n", k, (double)b->cascade[k].spacing_per_m,
                      1.0 / ppr);
        if (!(b->cascade[k].spacing_per_m <= 1.001 / ppr))
            fail_msg("cascade %d read at q %.5f from 10 km, coarser than a sample a pixel (%.5f): the budget "
                     "allows it", k, (double)b->cascade[k].spacing_per_m, 1.0 / ppr);
    }
    oc_frame_free(f);
    oc_client_destroy(c);
    srv_daemon_stop(d);
}

/* Relief before texture (srv_cascade.c plan_relief).  From 5 m over the
 * storm sea, level, in a 10 deg view (960 x 270) with the viewer's
 * subscription, the exact sea's crests that break the horizon are 0.7-2.9
 * km out and its dominant waves 240 m long.  One q for every cascade
 * (0.07: all the budget bought) read cascade 0 at 0.07 x 2 km = 140 m
 * there, past the mip that keeps those waves (sigma_m <= lambda / 4 =
 * 60 m): the horizon was ruler-straight.  Now cascade 0 reads them out to
 * 2 km at least (q_0 <= 0.03), bought with its finer cascades' bytes (their
 * slopes reach the shading as roughness) within the same budget. */
static void relief_reads_the_far_crests(void **state)
{
    (void)state;
    srv_settings sb;
    srv_daemon *d;
    oc_client *c = storm_viewer(&d, &sb); /* with its mesh, whose silhouettes the relief is */
    proto_camera cam;
    oc_camera_default(&cam);
    cam.pos[0] = cam.pos[2] = 0;
    cam.pos[1] = 5;
    cam.yaw_deg = 0;
    cam.pitch_deg = 0;
    cam.fov_y_deg = 10;
    cam.viewport_w = 960;
    cam.viewport_h = 270;
    oc_frame *f = frame_for_camera(c, &cam);
    const proto_cascade_block *b = &f->info.cascades;
    assert_true(b->cascade_count >= 3);
    print_message("5 m, 10 deg: block q %.4g; cascade q", (double)b->spacing_per_m);
    for (int k = 0; k < b->cascade_count; k++) print_message(" %.4g", (double)b->cascade[k].spacing_per_m);
    print_message("\n");
    if (!(b->cascade[0].spacing_per_m <= 0.03))
        fail_msg("cascade 0 read at %.0f m 2 km out: the 240 m waves are flat there",
                 2000.0 * b->cascade[0].spacing_per_m);
    oc_frame_free(f);
    oc_client_destroy(c);
    srv_daemon_stop(d);
}

/* Geometry-free mips (PROTOCOL.md "Where each mip is read"): a viewer's
 * frame (mesh + normals) names its mesh's finest lattice g_0 as G, and the
 * tiles of every mip with 2^(m+1) sigma_c <= G carry normals (and cascade
 * 0's foam) without H, DX, DZ - no reader reads them there - while every
 * coarser mip carries all.  The client reads geometry at max(s, G): every
 * point in view still gets height and displacement from tiles that hold
 * them, and the mesh is displaced with no vertex missing.  A subscription
 * without a mesh, or with the full_geometry flag, gets G = 0 and every
 * channel at every mip, and the bytes the normals-only mips leave buy finer
 * mips (no cascade's q coarser than with the full_geometry flag, one
 * finer).  Ship-bridge, the viewer's subscription, a camera 25 m up at
 * 1920 x 1080. */
static void cascade_fine_mips_without_geometry(void **state)
{
    (void)state;
    const char *sets[] = {"server.port=0", "server.scene=ship-bridge", "ocean.threads=1", "server.workers=2",
                          "server.viewer_bytes_per_s=3.9e6"};
    srv_settings sb;
    srv_daemon *d = start_daemon(sets, 5, &sb);
    double qc[2][3] = {{0}};
    /* 2: the viewer's subscription; 1: the same with the full_geometry flag; 0: no mesh */
    for (int run = 2; run >= 0; run--) {
        int with_mesh = run == 2;
        oc_client *c = connect_client(srv_daemon_port(d), NULL);
        proto_subscribe s;
        oc_subscribe_default(&s);
        /* every frame whole, so one frame holds every mip it reads (the
         * rule is the same for samples in time) */
        s.flags &= (uint8_t)~PROTO_SUB_TIME_INTERP;
        /* without foam: at this budget the viewer's plan with the breaking
         * planes (7 planes a tile, 4 in a geometry-free mip) stops short of
         * the mips finer than G (cascade q 0.029, 0.137, 0.068); the
         * geometry-free mips are weighed here on the 5-plane tiles this
         * budget was chosen for */
        s.effects &= (uint8_t)~PROTO_FX_FOAM;
        if (run == 1) s.flags |= PROTO_SUB_FULL_GEOMETRY;
        if (run == 0) s.mesh_kind = PROTO_MESH_NONE;
        assert_int_equal(oc_client_subscribe(c, &s), OCEAN_OK);
        proto_camera cam;
        bridge_camera(&cam);
        uint32_t seq;
        assert_int_equal(oc_client_send_camera(c, &cam, &seq), OCEAN_OK);
        oc_frame *f = frame_for(c, seq);
        assert_non_null(f);
        const proto_cascade_block *b = &f->info.cascades;
        double G = b->geometry_spacing_m;
        int free_tiles = 0, full_tiles = 0;
        double free_bytes = 0;
        for (int t = 0; t < f->info.tile_count; t++) {
            const proto_tile *ti = &f->tiles[t].info;
            const proto_cascade_entry *e = &b->cascade[ti->cascade];
            unsigned geo = PROTO_CH_HEIGHT | PROTO_CH_DX | PROTO_CH_DZ;
            int geometry_free = G > 0 && ldexp(e->patch_m / e->n, ti->level + 1) <= G;
            if (geometry_free) {
                if (ti->channels & geo)
                    fail_msg("cascade %u mip %u (spacing %.3g m, G %.3g m) carries channels 0x%x", ti->cascade,
                             ti->level, ti->spacing, G, ti->channels);
                assert_true(ti->channels & PROTO_CH_NORMAL);
                free_tiles++;
                free_bytes += 64.0 + ti->payload_len;
            } else {
                if ((ti->channels & geo) != geo)
                    fail_msg("cascade %u mip %u (spacing %.3g m, G %.3g m) lacks geometry: channels 0x%x",
                             ti->cascade, ti->level, ti->spacing, G, ti->channels);
                full_tiles++;
            }
        }
        if (run >= 1) /* both with the mesh: the one plan, G apart */
            for (int k = 0; k < 3; k++) qc[run == 2][k] = b->cascade[k].spacing_per_m;
        print_message("%s: G %.3g m; %d tiles without geometry (%.0f B), %d with; cascade q %.4g %.4g %.4g\n",
                      run == 2 ? "viewer (mesh, normals)" : run == 1 ? "viewer, full_geometry" : "no mesh", G,
                      free_tiles, free_bytes, full_tiles, (double)b->cascade[0].spacing_per_m,
                      (double)b->cascade[1].spacing_per_m, (double)b->cascade[2].spacing_per_m);
        if (with_mesh) {
            const oc_topology *tp = oc_client_topology(c);
            assert_non_null(tp);
            assert_true(tp->zones != NULL);
            assert_true(G > 0 && G == tp->zones[0]);
            if (free_tiles == 0) fail_msg("no mip travelled without geometry at G = %.3g m", G);
            /* the mesh is displaced wherever the camera looks (the ring
             * behind it has no tiles: the spec sends the view's sector) */
            float *xyz = malloc(sizeof(float) * 3 * tp->vertex_count);
            size_t missing = 0;
            assert_non_null(xyz);
            oc_frame_mesh_positions_ex(f, tp, OC_INTERP_CUBIC, xyz, &missing);
            const double *o = f->info.placement.origin;
            int in_view = 0, flat = 0;
            for (uint32_t v = 0; v < tp->vertex_count; v++) {
                double x = o[0] + tp->flat[2 * v] - cam.pos[0], z = o[2] + tp->flat[2 * v + 1] - cam.pos[2];
                double r = hypot(x, z), a = atan2(z, x) * 180 / M_PI - cam.yaw_deg;
                if (r < 5 || r > 3000 || fabs(remainder(a, 360)) > 40) continue;
                in_view++;
                flat += xyz[3 * v + 1] == 0.0f;
            }
            print_message("mesh: %zu of %u vertices outside the tiles, %d of the %d in view\n", missing,
                          tp->vertex_count, flat, in_view);
            assert_true(in_view > 100);
            assert_int_equal(flat, 0);
            free(xyz);
        } else {
            assert_true(G == 0);
            assert_int_equal(free_tiles, 0);
        }
        /* every point in view: geometry from tiles that hold it, shading too */
        int points = 0;
        for (double r = 5; r < 3000; r *= 1.3)
            for (double a = -40; a <= 40; a += 8) {
                double th = (cam.yaw_deg + a) * M_PI / 180;
                double x = cam.pos[0] + r * cos(th), z = cam.pos[2] + r * sin(th);
                oc_sample sm;
                ocean_result rr = oc_frame_sample(f, x, z, 0, &sm);
                if (rr != OCEAN_OK) fail_msg("no tile at %.1f m, %.0f deg: %s", r, a, ocean_strerror(rr));
                unsigned want = PROTO_CH_HEIGHT | PROTO_CH_DX | PROTO_CH_DZ | PROTO_CH_NORMAL;
                if ((sm.channels & want) != want)
                    fail_msg("%.1f m, %.0f deg: read channels 0x%x (s %.3g m, G %.3g m)", r, a, sm.channels, sm.s, G);
                points++;
            }
        assert_true(points > 100);
        oc_frame_free(f);
        oc_client_destroy(c);
    }
    /* the bytes the normals-only mips leave buy finer mips: no cascade
     * coarser with G, one at least finer */
    int finer = 0;
    for (int k = 0; k < 3; k++) {
        assert_true(qc[1][k] <= qc[0][k]);
        finer += qc[1][k] < qc[0][k];
    }
    assert_true(finer >= 1);
    srv_daemon_stop(d);
}

/* Issue 13 item 4: in layout 1 the near field is one more periodic cascade
 * (the Gerstner waves snapped to a 12.7 m lattice, gerstner.h "Lattice"),
 * after the FFT's.  Served from the scene `make run` serves (ship-bridge:
 * 3 cascades + near field = 4 layout-1 cascades): a camera 3 m above the
 * water gets near-field tiles that equal the exact Gerstner sum of the
 * same waves, and the cascade's mip table holds the near field's own
 * slope moments (sum A^2 k^2 / 2 over its waves, computed here from the
 * waves), which therefore leave tail_mss (it equals the slope table's
 * short-wave tail alone); from 1500 m no near-field tile is sent and the
 * lod rule reads the cascade's "whole cascade" entry: all its slopes
 * shade. */
static void cascade_near_field_ship_bridge(void **state)
{
    (void)state;
    /* The byte budget is raised so that the lod rule, not the budget,
     * decides: at the default 3.6 MB/s the planner coarsens a 3 m camera's
     * spacing about 35-fold whether or not the near field is served (the
     * finest FFT cascade's mip 0 does not fit either), and near-field tiles
     * come only below about 1.5 m. */
    const char *sets[] = {"server.port=0", "server.scene=ship-bridge", "ocean.threads=1", "server.workers=2",
                          sanitized ? "ocean.n=64" : "ocean.n=256", "server.viewer_bytes_per_s=1e9"};
    srv_settings sb;
    char err[512];
    load_settings(sets, 6, &sb);
    assert_int_equal(sb.params.cascades, 3);
    assert_true(srv_settings_near_cascade(&sb));
    assert_int_equal(srv_settings_layout1_cascades(&sb), 4);
    srv_daemon *d;
    assert_int_equal(srv_daemon_start(&sb, &d, err, sizeof err), OCEAN_OK);
    oc_client *c = connect_client(srv_daemon_port(d), NULL);
    proto_hello h;
    assert_int_equal(oc_client_hello(c, &h), OCEAN_OK);
    assert_int_equal(h.max_layers, 4);
    /* the same near field as the daemon's (srv_sim.c make_ocean) */
    ocean *o;
    char msg[256];
    assert_int_equal(ocean_create(&sb.params, &o, msg, sizeof msg), OCEAN_OK);
    double patch, klo, khi;
    ocean_cascade_band(o, 2, &patch, &klo, &khi);
    ocean_gerstner_params gp;
    assert_true(srv_settings_near_field(&sb, &sb.params, &gp));
    assert_true(gp.k_lo == khi);
    assert_true(fabs(gp.lattice_m - (sb.params.n / 2 - 1) * 0.1) < 1e-12);
    ocean_gerstner *g;
    assert_int_equal(ocean_gerstner_create(&gp, &g, msg, sizeof msg), OCEAN_OK);
    double near[3] = {0, 0, 0};
    for (int i = 0; i < ocean_gerstner_count(g); i++) {
        ocean_gerstner_wave w;
        ocean_gerstner_get_wave(g, i, &w);
        double a2 = 0.5 * w.amplitude * w.amplitude;
        near[0] += a2 * w.kx * w.kx;
        near[1] += a2 * w.kz * w.kz;
        near[2] += a2 * w.kx * w.kz;
    }
    ocean_slope_table *st;
    ocean_slope_stats ss;
    assert_int_equal(ocean_slope_table_create(o, g, &st, msg, sizeof msg), OCEAN_OK);
    assert_int_equal(ocean_slope_table_get(st, INFINITY, 6, &ss), OCEAN_OK);
    ocean_slope_table_destroy(st);
    print_message("near field: patch %.4g m, mss %.4g %.4g; tail %.4g %.4g\n", gp.lattice_m, near[0], near[1],
                  ss.tail.mss_x, ss.tail.mss_z);
    /* the near field's slopes are not a rounding error beside the tail */
    assert_true(near[0] + near[1] > 0.1 * (ss.tail.mss_x + ss.tail.mss_z));

    proto_subscribe s;
    cascade_subscribe(&s);
    s.effects = PROTO_FX_HEIGHT | PROTO_FX_DISPLACEMENT | PROTO_FX_NORMALS | PROTO_FX_NEAR_FIELD;
    s.layers = 4;
    assert_int_equal(oc_client_subscribe(c, &s), OCEAN_OK);
    proto_camera cam;
    oc_camera_default(&cam);
    cam.pos[0] = 1234.5;
    cam.pos[1] = 3;
    cam.pos[2] = -987.25;
    cam.pitch_deg = -30;
    int near_tiles = 0, checked = 0;
    for (int pass = 0; pass < 2; pass++) {
        uint32_t seq;
        assert_int_equal(oc_client_send_camera(c, &cam, &seq), OCEAN_OK);
        oc_frame *f = frame_for(c, seq);
        assert_non_null(f);
        const proto_cascade_block *b = &f->info.cascades;
        assert_int_equal(b->cascade_count, 4);
        const proto_cascade_entry *e = &b->cascade[3];
        assert_true(fabs(e->patch_m - gp.lattice_m) <= 1e-12 * gp.lattice_m);
        assert_int_equal(e->n, sb.params.n);
        assert_int_equal(e->fades, 1);
        assert_true(e->mips >= 2);
        /* mip 0 holds every near-field wave; the "whole cascade" entry lacks them all */
        assert_true(e->mip[0].mss_x == 0 && e->mip[0].mss_z == 0);
        for (int k = 0; k < 3; k++) {
            double got = k == 0 ? e->mip[e->mips].mss_x : k == 1 ? e->mip[e->mips].mss_z : e->mip[e->mips].mss_xz;
            assert_true(fabs(got - near[k]) <= 1e-5 * (near[0] + near[1]));
        }
        /* no double counting: the tail is the short-wave tail alone */
        assert_true(fabs(b->tail_mss[0] - ss.tail.mss_x) <= 1e-5 * ss.tail.mss_x + 1e-9);
        assert_true(fabs(b->tail_mss[1] - ss.tail.mss_z) <= 1e-5 * ss.tail.mss_z + 1e-9);
        double sigma = e->patch_m / e->n;
        double sp_nadir = fmax(b->min_spacing_m, e->spacing_per_m * fmax(fabs(b->camera[1]), 1.0));
        double lam = log2(sp_nadir / sigma);
        if (pass == 0) {
            /* 3 m up: the rule reads the near field's geometry at the nadir */
            print_message("3 m: near-field level %.2f of %d mips, q %.3g\n", lam, e->mips, (double)b->spacing_per_m);
            assert_true(lam < e->mips);
            for (int t = 0; t < f->info.tile_count; t++) {
                const oc_tile *tl = &f->tiles[t];
                if (tl->info.cascade != 3) continue;
                near_tiles++;
                assert_int_equal(tl->decode_result, OCEAN_OK);
                if (tl->info.level != 0) continue;
                /* mip 0 is the unfiltered near field: the exact sum of the waves */
                int T = tl->info.width;
                double x[64], z[64];
                ocean_gerstner_point gpt[64];
                int np = 0;
                for (int i = 0; i < T && np < 64; i += 5)
                    for (int j = 0; j < T && np < 64; j += 7, np++) {
                        x[np] = tl->info.origin_x + j * tl->info.spacing;
                        z[np] = tl->info.origin_z + i * tl->info.spacing;
                    }
                ocean_gerstner_view v;
                ocean_gerstner_view_default(&v);
                assert_int_equal(ocean_gerstner_evaluate(g, &v, f->hdr.sim_time, x, z, (size_t)np, gpt), OCEAN_OK);
                for (int q = 0, i = 0; i < T && q < np; i += 5)
                    for (int j = 0; j < T && q < np; j += 7, q++) {
                        double got = tl->data[i * T + j];
                        assert_true(fabs(got - gpt[q].dy) <= tl->info.error_bound + 1e-6);
                        checked++;
                    }
            }
            print_message("3 m: %d near-field tiles, %d samples checked against the Gerstner sum\n", near_tiles,
                          checked);
            /* what a tile costs, per cascade (the planner's qz model: 0.48 B per sample and plane) */
            for (int k = 0; k < 4; k++) {
                double bytes = 0, samples = 0;
                for (int t = 0; t < f->info.tile_count; t++)
                    if (f->tiles[t].info.cascade == k) {
                        bytes += f->tiles[t].info.payload_len;
                        samples += (double)f->tiles[t].info.width * f->tiles[t].info.height *
                                   proto_tile_planes(f->tiles[t].info.channels);
                    }
                if (samples > 0)
                    print_message("3 m: cascade %d: %.3f B per sample and plane\n", k, bytes / samples);
            }
            assert_true(near_tiles > 0);
            assert_true(checked > 0);
        } else {
            /* 1500 m: no near-field tile; the lod rule fades the cascade out
             * (w = clamp(mips - lambda, 0, 1) = 0), so shading adds its whole
             * entry - the near field's slopes - at every point */
            print_message("1500 m: near-field level %.2f of %d mips\n", lam, e->mips);
            assert_true(lam >= e->mips);
            for (int t = 0; t < f->info.tile_count; t++) assert_true(f->tiles[t].info.cascade != 3);
            assert_true(f->info.tile_count > 0);
        }
        oc_frame_free(f);
        cam.pos[1] = 1500;
        cam.pitch_deg = -15;
    }
    /* a subscription without the near-field effect: 3 cascades, as before,
     * and the near field's waves, in no cascade of the frame, are in its
     * tail (they were in nothing: the sea had a gap between the FFT's top
     * and the near field's, 13 % of its slope variance) */
    s.effects = PROTO_FX_HEIGHT | PROTO_FX_DISPLACEMENT | PROTO_FX_NORMALS;
    assert_int_equal(oc_client_subscribe(c, &s), OCEAN_OK);
    uint32_t seq;
    assert_int_equal(oc_client_send_camera(c, &cam, &seq), OCEAN_OK);
    oc_frame *f = frame_for(c, seq);
    assert_non_null(f);
    assert_int_equal(f->info.cascades.cascade_count, 3);
    const float *tm = f->info.cascades.tail_mss;
    if (!(fabs(tm[0] - (ss.tail.mss_x + near[0])) <= 1e-5 * (ss.tail.mss_x + near[0]) &&
          fabs(tm[1] - (ss.tail.mss_z + near[1])) <= 1e-5 * (ss.tail.mss_z + near[1])))
        fail_msg("without the near-field effect: tail_mss %g %g, want the tail %g %g + the near field %g %g", tm[0],
                 tm[1], ss.tail.mss_x, ss.tail.mss_z, near[0], near[1]);
    oc_frame_free(f);
    oc_client_destroy(c);
    ocean_gerstner_destroy(g);
    ocean_destroy(o);
    srv_daemon_stop(d);
    /* four cascades and a near field do not fit the protocol's cascade
     * block: refused at load, with the numbers */
    const char *four[] = {"server.port=0", "server.scene=ship-bridge", "ocean.cascades=4", "ocean.patch=4000"};
    assert_int_equal(srv_settings_load(NULL, four, 4, &sb, err, sizeof err), OCEAN_EINVAL);
    print_message("refused: %s\n", err);
    assert_non_null(strstr(err, "ocean.cascades = 4"));
    assert_non_null(strstr(err, "near"));
}

/* Layout 1 shares work across cameras: viewers 2 km apart get
 * byte-identical records for the tiles they have in common, and the
 * tiles the daemon encodes per tick stay bounded by the pyramid however
 * many cameras there are. */
static void cascade_tiles_shared_across_cameras(void **state)
{
    (void)state;
    /* a pyramid of 2-sample tiles cannot fit a frame at N = 256: such a
     * subscription is refused (srv_client.c) before any work */
    ocean_params big = settings.params;
    big.n = 256;
    big.cascades = 3;
    assert_true(srv_cascade_max_tiles(&big, 3, 2) > PROTO_MAX_FRAME_TILES);
    assert_int_equal(srv_cascade_max_tiles(&big, 3, 32), 3 * (64 + 16 + 4 + 1 + 1 + 1));
    srv_hub *h = srv_daemon_hub(daemon_);
    enum { NV = 8 };
    oc_client *v[NV];
    uint32_t seq[NV];
    proto_subscribe s;
    cascade_subscribe(&s);
    for (int i = 0; i < NV; i++) {
        v[i] = connect_bg(port);
        assert_int_equal(oc_client_subscribe(v[i], &s), OCEAN_OK);
        proto_camera cam;
        oc_camera_default(&cam);
        cam.pos[0] = 2000.0 * i + 0.5;
        cam.pos[1] = 25;
        cam.pos[2] = -1500.0 * i;
        assert_int_equal(oc_client_send_camera(v[i], &cam, &seq[i]), OCEAN_OK);
    }
    /* every viewer has its first frame, then count a few ticks */
    oc_frame *first[NV];
    for (int i = 0; i < NV; i++) {
        first[i] = frame_for(v[i], seq[i]);
        assert_non_null(first[i]);
    }
    uint64_t e0 = stat_of(&h->stats.tiles_encoded), t0 = stat_of(&h->stats.ticks);
    uint64_t hit0 = stat_of(&h->stats.tile_cache_hits);
    /* a few ticks pass with every camera live */
    for (double until = test_now_s() + 10; test_now_s() < until && stat_of(&h->stats.ticks) < t0 + 3;) usleep(10000);
    uint64_t e1 = stat_of(&h->stats.tiles_encoded), t1 = stat_of(&h->stats.ticks);
    for (int i = 0; i < NV; i++) drain_frames(v[i]);
    /* two viewers' frames of one tick */
    enum { KEEP = 16 };
    oc_frame *fa[KEEP] = {0}, *fb[KEEP] = {0}, *a = NULL, *bb = NULL;
    int na = 0, nb = 0;
    double end = test_now_s() + 5;
    while (test_now_s() < end && !a) {
        oc_frame *f;
        if (na < KEEP && oc_client_next_frame(v[0], 5, &f) == OCEAN_OK) fa[na++] = f;
        if (nb < KEEP && oc_client_next_frame(v[3], 5, &f) == OCEAN_OK) fb[nb++] = f;
        for (int i = 0; i < na && !a; i++)
            for (int j = 0; j < nb && !a; j++)
                if (fa[i]->info.tick == fb[j]->info.tick && fa[i]->info.camera_seq == seq[0] &&
                    fb[j]->info.camera_seq == seq[3]) {
                    a = fa[i];
                    bb = fb[j];
                    fa[i] = fb[j] = NULL;
                }
        if (na == KEEP && nb == KEEP && !a) break;
    }
    for (int i = 0; i < KEEP; i++) {
        oc_frame_free(fa[i]);
        oc_frame_free(fb[i]);
    }
    assert_non_null(a);
    uint32_t pyramid = srv_cascade_max_tiles(&settings.params, 2, 32);
    assert_true(t1 > t0);
    /* cameras far apart still reuse each other's encoded tiles */
    assert_true(stat_of(&h->stats.tile_cache_hits) > hit0);
    /* at most one pyramid per tick, shared by all NV cameras (+1 tick of slack) */
    assert_true(e1 - e0 <= (uint64_t)pyramid * (t1 - t0 + 1));
    assert_int_equal(a->info.tick, bb->info.tick);
    int common = 0;
    for (int i = 0; i < a->info.tile_count; i++)
        for (int j = 0; j < bb->info.tile_count; j++) {
            const proto_tile *x = &a->tiles[i].info, *y = &bb->tiles[j].info;
            if (x->cascade != y->cascade || x->level != y->level || x->ix != y->ix || x->iz != y->iz) continue;
            assert_int_equal(x->payload_len, y->payload_len);
            assert_memory_equal(x->payload, y->payload, x->payload_len);
            common++;
        }
    assert_true(common > 0);
    oc_frame_free(a);
    oc_frame_free(bb);
    for (int i = 0; i < NV; i++) {
        oc_frame_free(first[i]);
        oc_client_destroy(v[i]);
    }
}

/* The cutoff follows the reported speed under each policy: it moves to
 * the policy's bucketed value for the new speed step by step (smoothed),
 * monotonically, never past it. */
static void cutoff_run(ocean_filter_policy pol, double speed)
{
    oc_client *c = connect_client(port, NULL);
    proto_subscribe s;
    small_subscribe(&s);
    s.mesh_kind = PROTO_MESH_NONE;
    s.lod_levels = 1;
    s.cutoff_policy = (uint8_t)pol;
    assert_int_equal(oc_client_subscribe(c, &s), OCEAN_OK);
    proto_camera cam;
    oc_camera_default(&cam);
    uint32_t seq0;
    assert_int_equal(oc_client_send_camera(c, &cam, &seq0), OCEAN_OK);
    double k0 = -1;
    for (int i = 0; i < 60; i++) {
        oc_frame *f = next_frame(c);
        if (f->info.camera_seq == seq0) k0 = f->info.cutoff_k;
        oc_frame_free(f);
        if (k0 > 0 && i > 5) break;
    }
    assert_true(k0 > 0);
    ocean_filter_config fc;
    ocean_filter_config_default(&fc, &settings.params.sea);
    ocean_filter_buckets b;
    ocean_filter_buckets_default(&b);
    ocean_filter_client cl = {speed, 30.0, settings.srv.base_spacing};
    ocean_filter_cutoff target;
    assert_int_equal(ocean_filter_cutoff_compute(&fc, pol, &cl, &target), OCEAN_OK);
    int bi;
    double expect;
    assert_int_equal(ocean_filter_bucket_of(&b, target.k, &bi), OCEAN_OK);
    assert_int_equal(ocean_filter_bucket_cutoff(&b, bi, &expect), OCEAN_OK);
    assert_true(expect != k0);
    double dir = expect < k0 ? -1 : 1;
    cam.vel[0] = (float)speed;
    uint32_t seq;
    assert_int_equal(oc_client_send_camera(c, &cam, &seq), OCEAN_OK);
    double prev = k0, last = k0;
    int steps = 0;
    double end = test_now_s() + 8;
    while (test_now_s() < end && last != expect) {
        oc_frame *f = next_frame(c);
        if (f->info.camera_seq == seq) {
            last = f->info.cutoff_k;
            assert_true(dir * (last - prev) >= 0);    /* monotone toward the target */
            assert_true(dir * (expect - last) >= 0);  /* never past it */
            if (last != prev) steps++;
            prev = last;
        }
        oc_frame_free(f);
    }
    if (last != expect || steps < 2)
        fprintf(stderr, "policy %d: k0 %g expect %g last %g steps %d\n", pol, k0, expect, last, steps);
    assert_true(last == expect);
    assert_true(steps >= 2); /* smoothed: more than one step */
    oc_client_destroy(c);
}

static void cutoff_follows_velocity(void **state)
{
    (void)state;
    cutoff_run(OCEAN_FILTER_ANTIALIAS, 1000.0); /* falls with speed */
    cutoff_run(OCEAN_FILTER_SEED, 200.0);      /* seed 000: fc = f_base + beta |v| rises */
}

/* Queries agree with sim/query.c on the same fields. */
static void queries_agree_with_sim(void **state)
{
    (void)state;
    oc_client *c = connect_client(port, NULL);
    const double xz[] = {0, 0, 13.5, -7.25, 250.0, 125.0, -1e5, 3e4, 1234.5, -987.25};
    size_t n = 5;
    oc_query_result qr;
    assert_int_equal(oc_client_query(c, xz, n, 1, 12.25, 5000, &qr), OCEAN_OK);
    assert_int_equal(qr.count, n);
    assert_true(qr.t == 12.25);
    /* locally: unfiltered, all cascades, query effects, near field unfaded */
    ocean *o = local_ocean();
    ocean_frame *lf;
    assert_int_equal(ocean_frame_create(o, &lf), OCEAN_OK);
    ocean_request rq;
    memset(&rq, 0, sizeof rq);
    for (int k = 0; k < settings.params.cascades; k++) rq.effects[k] = OCEAN_QUERY_EFFECTS;
    rq.cutoff_k = INFINITY;
    ocean_filter_config fc;
    ocean_filter_config_default(&fc, &settings.params.sea);
    rq.order = fc.order;
    rq.low_boost = 1.0;
    assert_int_equal(ocean_evaluate(o, 12.25, &rq, lf), OCEAN_OK);
    double patch, klo, khi;
    ocean_cascade_band(o, settings.params.cascades - 1, &patch, &klo, &khi);
    ocean_gerstner_params gp;
    assert_true(srv_settings_near_field(&settings, &settings.params, &gp)); /* the daemon's near field */
    assert_true(gp.k_lo == khi);
    ocean_gerstner *g = NULL;
    char msg[256];
    assert_int_equal(ocean_gerstner_create(&gp, &g, msg, sizeof msg), OCEAN_OK);
    ocean_query_options opt;
    ocean_query_options_default(&opt);
    ocean_query_result res[5];
    assert_int_equal(ocean_query_points(lf, g, NULL, 12.25, xz, n, &opt, res, NULL), OCEAN_OK);
    double hmax = 0;
    for (size_t i = 0; i < n; i++) {
        const proto_query_sample *sm = &qr.samples[i];
        assert_true(fabs(sm->height - res[i].height) <= 1e-5 + 1e-6 * fabs(res[i].height));
        for (int k = 0; k < 3; k++) {
            assert_true(fabs(sm->normal[k] - res[i].normal[k]) <= 1e-6);
            assert_true(fabs(sm->velocity[k] - res[i].velocity[k]) <= 1e-5 + 1e-6 * fabs(res[i].velocity[k]));
        }
        assert_true(fabs(sm->foam - res[i].foam) <= 1e-6);
        hmax = fmax(hmax, fabs(res[i].height));
    }
    assert_true(hmax > 0.01); /* a real sea, not zeros */
    oc_query_result_free(&qr);
    /* at_time 0 answers at the current tick */
    assert_int_equal(oc_client_query(c, xz, 2, 0, 0, 5000, &qr), OCEAN_OK);
    assert_true(fabs(qr.t - srv_hub_sim_time(srv_daemon_hub(daemon_))) < 2.0);
    oc_query_result_free(&qr);
    /* a query far in the future says when it was evaluated in its body;
     * its header's sim_time is the server's clock (it was the query's t,
     * and one such answer set the client's clock to 1e6 s and every later
     * frame's latency to 1e9 ms) */
    assert_int_equal(oc_client_query(c, xz, 1, 1, 1e6, 5000, &qr), OCEAN_OK);
    assert_true(qr.t == 1e6);
    oc_query_result_free(&qr);
    double now = srv_hub_sim_time(srv_daemon_hub(daemon_)), seen = oc_client_sim_time(c);
    if (!(fabs(seen - now) < 2.0))
        fail_msg("after a query at t = 1e6 the client's clock reads %.3f s, the server's %.3f s", seen, now);
    ocean_gerstner_destroy(g);
    ocean_frame_destroy(lf);
    ocean_destroy(o);
    oc_client_destroy(c);
}

static char *http_get(int p, const char *path);

/* A daemon nobody watches holds no tiles: the caches keep the last ticks'
 * tiles (keyed by their sim time, so no later tick can use them) only
 * until the next sweep, and with nobody subscribed no tick runs.  Seen as
 * an operator sees it: /metrics's tile-cache gauges fall to 0 once the
 * last viewer leaves (they were 0.9 GB after 256 layout-0 viewers). */
static void idle_daemon_drops_its_tiles(void **state)
{
    (void)state;
    srv_hub *h = srv_daemon_hub(daemon_);
    oc_client *c = connect_bg(port);
    proto_subscribe sub;
    oc_subscribe_default(&sub);        /* the viewer's: layout 1, every cascade */
    proto_camera cam;
    oc_camera_default(&cam);
    assert_int_equal(oc_client_subscribe(c, &sub), OCEAN_OK);
    assert_int_equal(oc_client_send_camera(c, &cam, NULL), OCEAN_OK);
    for (int i = 0; i < 3; i++) oc_frame_free(next_frame(c));
    /* the world tiles of layout 0 too */
    small_subscribe(&sub);
    assert_int_equal(oc_client_subscribe(c, &sub), OCEAN_OK);
    for (int i = 0; i < 3; i++) oc_frame_free(next_frame(c));
    assert_true(stat_of(&h->stats.tile_cache_entries) > 0);
    assert_true(stat_of(&h->stats.tile_cache_bytes) > 0);
    char *m = http_get(port, "/metrics");
    assert_non_null(m);
    assert_non_null(strstr(m, "oceand_tile_cache_entries "));
    assert_null(strstr(m, "oceand_tile_cache_entries 0\n"));
    free(m);
    oc_client_destroy(c);
    double end = test_now_s() + 5;
    while (test_now_s() < end && stat_of(&h->stats.tile_cache_entries) > 0) usleep(20000);
    assert_int_equal(stat_of(&h->stats.tile_cache_entries), 0);
    assert_int_equal(stat_of(&h->stats.tile_cache_bytes), 0);
    m = http_get(port, "/metrics");
    assert_non_null(m);
    assert_non_null(strstr(m, "oceand_tile_cache_entries 0\n"));
    assert_non_null(strstr(m, "oceand_tile_cache_bytes 0\n"));
    free(m);
}

/* Two viewers with identical cameras receive identical tile bytes, encoded
 * once (cache hits); their FRAMEs share one encoding, yet each carries its
 * own camera_seq and a mesh_id naming the topology that client received,
 * and the rest of the bytes are the same. */
static void identical_cameras_share_tiles(void **state)
{
    (void)state;
    srv_hub *h = srv_daemon_hub(daemon_);
    oc_client *a = connect_bg(port), *b = connect_bg(port);
    proto_subscribe s;
    small_subscribe(&s);
    proto_camera cam;
    oc_camera_default(&cam);
    cam.pos[0] = 5000;
    cam.pos[2] = 77;
    uint32_t sa, sb;
    /* a has seen a topology before (its mesh ids run ahead of b's: it was
     * subscribed with another view range, so another mesh) and its camera
     * seq differs from b's */
    proto_subscribe s0 = s;
    s0.view_range_m = 2000;
    assert_int_equal(oc_client_subscribe(a, &s0), OCEAN_OK);
    assert_int_equal(oc_client_send_camera(a, &cam, &sa), OCEAN_OK);
    oc_frame_free(next_frame(a));
    assert_int_equal(oc_client_subscribe(a, &s), OCEAN_OK);
    assert_int_equal(oc_client_subscribe(b, &s), OCEAN_OK);
    assert_int_equal(oc_client_send_camera(a, &cam, &sa), OCEAN_OK);
    assert_int_equal(oc_client_send_camera(b, &cam, &sb), OCEAN_OK);
    assert_int_not_equal(sa, sb);
    uint64_t hits0 = stat_of(&h->stats.tile_cache_hits);
    uint64_t shared0 = stat_of(&h->stats.frames_shared);
    oc_frame *fa[32] = {0};
    int na = 0, matched = 0;
    double end = test_now_s() + 5;
    while (test_now_s() < end && matched < 3) {
        oc_frame *f;
        if (oc_client_next_frame(a, 10, &f) == OCEAN_OK) {
            if (f->info.camera_seq == sa && na < 32) fa[na++] = f;
            else oc_frame_free(f);
        }
        if (oc_client_next_frame(b, 10, &f) == OCEAN_OK) {
            for (int i = 0; i < na; i++) {
                if (f->info.camera_seq != sb || fa[i]->info.tick != f->info.tick) continue;
                assert_int_equal(fa[i]->info.tile_count, f->info.tile_count);
                for (int t = 0; t < f->info.tile_count; t++) {
                    assert_int_equal(fa[i]->tiles[t].info.payload_len, f->tiles[t].info.payload_len);
                    assert_memory_equal(fa[i]->tiles[t].info.payload, f->tiles[t].info.payload,
                                        f->tiles[t].info.payload_len);
                }
                assert_int_equal(fa[i]->info.has_mesh, f->info.has_mesh);
                if (f->info.has_mesh) {
                    assert_int_not_equal(fa[i]->info.mesh.mesh_id, f->info.mesh.mesh_id);
                    assert_non_null(f->topology);
                    assert_non_null(fa[i]->topology);
                    assert_int_equal(f->topology->mesh_id, f->info.mesh.mesh_id);
                    assert_int_equal(fa[i]->topology->mesh_id, fa[i]->info.mesh.mesh_id);
                    assert_int_equal(fa[i]->info.mesh.vertex_count, f->info.mesh.vertex_count);
                    assert_memory_equal(fa[i]->info.mesh.positions, f->info.mesh.positions,
                                        12 * (size_t)f->info.mesh.vertex_count);
                }
                /* byte for byte the same but the header's seq and camera_seq */
                assert_int_equal(fa[i]->raw_len, f->raw_len);
                assert_memory_equal(fa[i]->raw, f->raw, 16);
                assert_memory_equal(fa[i]->raw + 20, f->raw + 20, PROTO_HEADER_SIZE + 40 - 20);
                size_t body = f->info.has_mesh == 2 ? 32 + (size_t)f->info.mesh.qz_len
                                                    : 32 + 12 * (size_t)f->info.mesh.vertex_count;
                size_t mid = f->raw_len - (body + 7) / 8 * 8;
                if (f->info.has_mesh && fa[i]->info.mesh.mesh_id != f->info.mesh.mesh_id) {
                    assert_memory_equal(fa[i]->raw + PROTO_HEADER_SIZE + 44, f->raw + PROTO_HEADER_SIZE + 44,
                                        mid - PROTO_HEADER_SIZE - 44);
                    assert_memory_equal(fa[i]->raw + mid + 4, f->raw + mid + 4, f->raw_len - mid - 4);
                } else {
                    assert_memory_equal(fa[i]->raw + PROTO_HEADER_SIZE + 44, f->raw + PROTO_HEADER_SIZE + 44,
                                        f->raw_len - PROTO_HEADER_SIZE - 44);
                }
                matched++;
            }
            oc_frame_free(f);
        }
    }
    for (int i = 0; i < na; i++) oc_frame_free(fa[i]);
    assert_true(matched >= 3);
    assert_true(stat_of(&h->stats.tile_cache_hits) > hits0);
    assert_true(stat_of(&h->stats.frames_shared) > shared0);
    oc_client_destroy(a);
    oc_client_destroy(b);
}

/* Replays one camera path with mesh_codec `mc` into out[0..nframes). */
static void replay_frames(int p, int mc, oc_frame **out, int nframes)
{
    oc_client *c = connect_client(p, NULL);
    proto_subscribe s;
    small_subscribe(&s);
    s.mode = PROTO_MODE_REPLAY;
    s.mesh_codec = (uint8_t)mc;
    assert_int_equal(oc_client_subscribe(c, &s), OCEAN_OK);
    proto_camera cam;
    oc_camera_default(&cam);
    for (int i = 0; i < nframes; i++) {
        cam.pos[0] = 100.0 + 8.0 * i / 30.0;
        cam.pos[1] = 20 + 0.5 * i;
        cam.vel[0] = 8.0f + 20.0f * (float)i;
        cam.yaw_deg = (float)i;
        cam.render_time = 1000.0 + i / 30.0;
        assert_int_equal(oc_client_send_camera(c, &cam, NULL), OCEAN_OK);
    }
    for (int i = 0; i < nframes; i++) {
        out[i] = next_frame(c);
        assert_true(out[i]->hdr.sim_time == 1000.0 + i / 30.0);
    }
    oc_client_destroy(c);
}

/* Replays one camera path and returns the FRAME bytes concatenated. */
static uint8_t *replay_run(int p, size_t *len, int nframes)
{
    oc_frame *f[16];
    assert_true(nframes <= 16);
    replay_frames(p, PROTO_MESH_CODEC_QZ, f, nframes);
    uint8_t *all = NULL;
    size_t n = 0;
    for (int i = 0; i < nframes; i++) {
        all = realloc(all, n + f[i]->raw_len);
        assert_non_null(all);
        memcpy(all + n, f[i]->raw, f[i]->raw_len);
        n += f[i]->raw_len;
        oc_frame_free(f[i]);
    }
    *len = n;
    return all;
}

/* Replay mode: a camera path gives the same bytes on every run and on
 * every instance. */
static void replay_identical_bytes(void **state)
{
    (void)state;
    int nf = sanitized ? 4 : 10;
    size_t l1, l2, l3;
    uint8_t *r1 = replay_run(port, &l1, nf);
    uint8_t *r2 = replay_run(port, &l2, nf);
    assert_int_equal(l1, l2);
    assert_memory_equal(r1, r2, l1);
    srv_daemon *other;
    char err[256];
    assert_int_equal(srv_daemon_start(&settings, &other, err, sizeof err), OCEAN_OK);
    uint8_t *r3 = replay_run(srv_daemon_port(other), &l3, nf);
    srv_daemon_stop(other);
    assert_int_equal(l1, l3);
    assert_memory_equal(r1, r3, l1);
    free(r1);
    free(r2);
    free(r3);
}

/* Layout 0 with mesh_codec qz (issue 14): the same replayed cameras and
 * times as with f32 give the same mesh, each position within the bound
 * the spec states (PROTOCOL.md "MESH_VERTICES_QZ": half the axis step,
 * the step f32(2a . range_y) for every axis unless an axis would need
 * 2^29 levels, plus the f32 rounding of the decoded value), derived here
 * from the f32 frame alone; the record is at most a third of the f32
 * positions' bytes, and the client library hands out decoded floats. */
static void mesh_qz_within_bound(void **state)
{
    (void)state;
    enum { NF = 4 };
    oc_frame *f32[NF], *qz[NF];
    replay_frames(port, PROTO_MESH_CODEC_F32, f32, NF);
    replay_frames(port, PROTO_MESH_CODEC_QZ, qz, NF);
    for (int i = 0; i < NF; i++) {
        const proto_mesh_vertices *a = &f32[i]->info.mesh, *b = &qz[i]->info.mesh;
        assert_int_equal(f32[i]->info.has_mesh, 1);
        assert_int_equal(qz[i]->info.has_mesh, 2);
        assert_int_equal(a->vertex_count, b->vertex_count);
        assert_true(a->origin[0] == b->origin[0] && a->origin[2] == b->origin[2]);
        assert_non_null(b->positions);
        size_t n = a->vertex_count;
        double lo[3], hi[3];
        for (int k = 0; k < 3; k++)
            lo[k] = hi[k] = a->positions[k];
        for (size_t v = 0; v < n; v++)
            for (int k = 0; k < 3; k++) {
                lo[k] = fmin(lo[k], a->positions[3 * v + k]);
                hi[k] = fmax(hi[k], a->positions[3 * v + k]);
            }
        assert_true(hi[1] > lo[1]);   /* a sea with relief */
        double s = (double)(float)(2.0 * (double)(float)PROTO_ACCURACY_DEFAULT * (hi[1] - lo[1]));
        double worst = 0;
        for (int k = 0; k < 3; k++) {
            double step = (hi[k] - lo[k]) / s >= 0x1p29 ? (hi[k] - lo[k]) * 0x1p-29 * (1 + 0x1p-23) : s;
            double bound = 0.5 * step + fmax(fabs(lo[k]), fabs(hi[k])) * 0x1p-24;
            double e = 0;
            for (size_t v = 0; v < n; v++)
                e = fmax(e, fabs((double)b->positions[3 * v + k] - (double)a->positions[3 * v + k]));
            if (!(e <= bound))
                fail_msg("frame %d axis %d: |qz - f32| = %g above the bound %g (step %g)", i, k, e, bound, step);
            worst = fmax(worst, e / bound);
        }
        size_t rec = 32 + b->qz_len;
        if (!(3 * rec <= 12 * n))
            fail_msg("frame %d: qz mesh record %zu bytes, f32 positions %zu", i, rec, 12 * n);
        print_message("frame %d: %zu vertices, qz %zu bytes vs f32 %zu (1/%.1f), worst error %.2f of the bound\n", i,
                      n, rec, 32 + 12 * n, (32.0 + 12.0 * (double)n) / (double)rec, worst);
        oc_frame_free(f32[i]);
        oc_frame_free(qz[i]);
    }
}

/* A reader that never reads skips frames and is dropped; a fast reader
 * beside it keeps its full rate. */
static void slow_reader_never_delays_fast(void **state)
{
    (void)state;
    srv_hub *h = srv_daemon_hub(daemon_);
    uint64_t skipped0 = stat_of(&h->stats.frames_skipped);
    uint64_t slow0 = stat_of(&h->stats.disconnects_slow);
    test_ws slow;
    assert_int_equal(test_ws_connect(&slow, port, "/", PROTO_SUBPROTOCOL), 0);
    test_ws_small_rcvbuf(&slow, 4096);
    proto_msg m;
    proto_msg_init(&m, PROTO_SUBSCRIBE);
    small_subscribe(&m.u.subscribe);
    m.u.subscribe.lod_levels = 4;
    test_msg_send(&slow, &m);
    oc_client *fast = connect_bg(port);
    proto_subscribe s;
    small_subscribe(&s);
    assert_int_equal(oc_client_subscribe(fast, &s), OCEAN_OK);
    drain_frames(fast);
    double t0 = test_now_s();
    int frames = 0;
    double lat[256];
    while (test_now_s() - t0 < 2.5) {
        oc_frame *f;
        if (oc_client_next_frame(fast, 100, &f) == OCEAN_OK) {
            if (frames < 256) lat[frames] = f->latency_ms;
            frames++;
            oc_frame_free(f);
        }
    }
    /* 30 Hz for 2.5 s: 75 frames.  Timing on a shared 2-core host is
     * noisy, so the bound is loose; what matters is that the fast reader is
     * served at all while the slow one's frames are being skipped. */
    if (frames < (sanitized ? 15 : 35))
        fprintf(stderr, "fast reader got %d frames; tick %.1f ms\n", frames,
                stat_of(&h->stats.tick_ns_last) * 1e-6);
    assert_true(frames >= (sanitized ? 15 : 35));
    if (!sanitized) {
        /* the slow reader's frames are skipped once the socket buffers
         * between it and the daemon are full: a deadline, not a speed (on
         * a quiet host loopback's buffers took more than the 2.5 s of
         * frames above, and the test stopped with the slow client open) */
        double until = test_now_s() + 10;
        while (test_now_s() < until && stat_of(&h->stats.frames_skipped) == skipped0) usleep(20000);
        assert_true(stat_of(&h->stats.frames_skipped) > skipped0);
    }
    /* no bytes read for output_soft_seconds (1 s): dropped with a reason */
    double end = test_now_s() + 5;
    while (test_now_s() < end && stat_of(&h->stats.disconnects_slow) == slow0) usleep(50000);
    assert_true(stat_of(&h->stats.disconnects_slow) > slow0);
    /* and counted once: its close frame cannot pass its full buffers, so it
     * stays through the kill's grace (2 s) while the sweep runs 4x a second.
     * Every sweep counted it again, and the next test saw a slow disconnect
     * of its own (CI: trailing_confirmations_are_no_dead_reader, 2 != 1). */
    end = test_now_s() + 15;
    int left = -1;
    while (test_now_s() < end) {
        pthread_mutex_lock(&h->lock);
        left = h->n_clients;
        pthread_mutex_unlock(&h->lock);
        if (left <= 1) break;
        usleep(20000);
    }
    assert_int_equal(left, 1); /* the slow one is gone, the fast one stays */
    assert_int_equal(stat_of(&h->stats.disconnects_slow), slow0 + 1);
    assert_int_equal(oc_client_state(fast), OC_READY); /* the fast one stays */
    oc_frame *f;
    assert_int_equal(oc_client_next_frame(fast, 2000, &f), OCEAN_OK);
    oc_frame_free(f);
    (void)lat;
    test_ws_close(&slow);
    oc_client_destroy(fast);
}

/* The close a raw reader got, for a message: "code N: reason". */
static void close_text(int op, const uint8_t *b, size_t n, char *out, size_t cap)
{
    if (op == 8 && n >= 2) snprintf(out, cap, "close %d: %.*s", b[0] << 8 | b[1], (int)(n - 2), (const char *)b + 2);
    else snprintf(out, cap, "connection lost (op %d)", op);
}

/* A reader whose confirmations trail reads everything it is sent: the link
 * holds its frames back (srv_link.h), and that wait is the daemon's plan,
 * not a reader that takes nothing.  With server.output_soft_seconds 1 s it
 * was cut "no bytes read" a second into the hold (a busy CI host's
 * cutoff_follows_velocity: its client confirmed while frames were in
 * flight). */
static void trailing_confirmations_are_no_dead_reader(void **state)
{
    (void)state;
    srv_hub *h = srv_daemon_hub(daemon_);
    uint64_t slow0 = stat_of(&h->stats.disconnects_slow), held0 = stat_of(&h->stats.frames_held);
    test_ws w;
    assert_int_equal(test_ws_connect(&w, port, "/", PROTO_SUBPROTOCOL), 0);
    proto_msg m;
    proto_msg_init(&m, PROTO_SUBSCRIBE);
    small_subscribe(&m.u.subscribe);
    m.u.subscribe.mesh_kind = PROTO_MESH_NONE;
    test_msg_send(&w, &m);
    enum { NF = 16 };
    double ft[NF];
    int nf = 0;
    char why[160];
    for (double end = test_now_s() + FRAME_WAIT_MS / 1e3; nf < NF && test_now_s() < end;) {
        uint8_t *b = NULL;
        size_t n = 0;
        int op = test_ws_recv(&w, 50, &b, &n);
        if (op == 2 && n >= PROTO_HEADER_SIZE && proto_ld16(b + 6) == PROTO_FRAME) ft[nf++] = proto_ldf64(b + 24);
        free(b);
    }
    assert_int_equal(nf, NF);
    /* one confirmation every 0.4 s, each of the oldest frame not yet
     * confirmed: the window stays in flight, so the link holds */
    proto_camera cam;
    oc_camera_default(&cam);
    double t0 = test_now_s(), next = t0;
    int k = 0;
    while (test_now_s() - t0 < 2.0) {
        if (test_now_s() >= next && k < NF) {
            proto_msg_init(&m, PROTO_CAMERA);
            m.u.camera = cam;
            m.hdr.sim_time = ft[k++];
            test_msg_send(&w, &m);
            next += 0.4;
        }
        uint8_t *b = NULL;
        size_t n = 0;
        int op = test_ws_recv(&w, 5, &b, &n);
        if (op < 0 || op == 8) {
            close_text(op, b, n, why, sizeof why);
            fail_msg("a reader whose frames the link held was cut: %s", why);
        }
        free(b);
    }
    test_ws_close(&w);
    assert_true(stat_of(&h->stats.frames_held) > held0); /* the case was made */
    assert_int_equal(stat_of(&h->stats.disconnects_slow), slow0);
}

/* Sets the running daemon's server.partial_seconds; returns the old value. */
static double partial_seconds_set(srv_hub *h, double v)
{
    pthread_mutex_lock(&h->lock);
    double was = h->settings.srv.partial_seconds;
    h->settings.srv.partial_seconds = v;
    pthread_mutex_unlock(&h->lock);
    return was;
}

/* While the daemon does not run (stopped, or starved on a loaded host) no
 * client can read or send, so no limit counts that time: a message begun
 * 0.3 s before a 2.5 s stall and finished 0.6 s after it is served with
 * server.partial_seconds at 2 s.  The stall is the service thread kept
 * off the hub's lock, as SIGSTOP would keep it off the CPU. */
static void stalled_daemon_counts_no_client_time(void **state)
{
    (void)state;
    srv_hub *h = srv_daemon_hub(daemon_);
    uint64_t part0 = stat_of(&h->stats.disconnects_partial);
    double was = partial_seconds_set(h, 2.0);
    test_ws w;
    assert_int_equal(test_ws_connect(&w, port, "/", PROTO_SUBPROTOCOL), 0);
    proto_msg m;
    assert_true(test_msg_wait(&w, PROTO_HELLO, FRAME_WAIT_MS, &m));
    proto_msg_free(&m);
    proto_msg_init(&m, PROTO_SEA_STATE);
    m.u.sea_state.op = PROTO_SEA_GET;
    size_t len;
    uint8_t *b = test_msg_encode(&m, &len);
    assert_int_equal(test_ws_send_part(&w, 2, b, len, 0, 8), 0); /* header and 2 bytes */
    usleep(300000);                                              /* read by the daemon */
    pthread_mutex_lock(&h->lock);
    usleep(2500000);
    pthread_mutex_unlock(&h->lock);
    usleep(600000); /* past the sweeps after the stall (4 a second) */
    assert_int_equal(test_ws_send_part(&w, 2, b, len, 8, SIZE_MAX), 0);
    free(b);
    int got = test_msg_wait(&w, PROTO_SEA_STATE, FRAME_WAIT_MS, &m);
    if (got) proto_msg_free(&m);
    test_ws_close(&w);
    partial_seconds_set(h, was);
    assert_int_equal(stat_of(&h->stats.disconnects_partial), part0);
    assert_true(got);
}

/* A client's ERROR is logged (server.verbose) with its text quoted and its
 * control bytes escaped: a newline or an ANSI escape in it forged daemon
 * log lines before. */
static void client_error_log_is_escaped(void **state)
{
    (void)state;
    srv_hub *h = srv_daemon_hub(daemon_);
    pthread_mutex_lock(&h->lock);
    int was = h->settings.srv.verbose;
    h->settings.srv.verbose = 1;
    pthread_mutex_unlock(&h->lock);
    char path[600];
    snprintf(path, sizeof path, "%s/verbose.log", tmpdir);
    fflush(stderr);
    int saved = dup(2), fd = open(path, O_CREAT | O_TRUNC | O_WRONLY, 0600);
    assert_true(saved >= 0 && fd >= 0);
    dup2(fd, 2);
    test_ws w;
    assert_int_equal(test_ws_connect(&w, port, "/", PROTO_SUBPROTOCOL), 0);
    proto_msg m;
    assert_true(test_msg_wait(&w, PROTO_HELLO, 3000, &m));
    proto_msg_free(&m);
    proto_msg_init(&m, PROTO_ERROR);
    m.u.error.code = OCEAN_EFORMAT;
    snprintf(m.u.error.message, sizeof m.u.error.message,
             "x\noceand: forged line\n\x1b[2J");
    test_msg_send(&w, &m);
    /* a SEA_STATE get answered after it: the ERROR was handled */
    proto_msg_init(&m, PROTO_SEA_STATE);
    m.u.sea_state.op = PROTO_SEA_GET;
    test_msg_send(&w, &m);
    assert_true(test_msg_wait(&w, PROTO_SEA_STATE, 3000, &m));
    proto_msg_free(&m);
    test_ws_close(&w);
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    close(fd);
    pthread_mutex_lock(&h->lock);
    h->settings.srv.verbose = was;
    pthread_mutex_unlock(&h->lock);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char line[4096];
    int reported = 0, forged = 0, escape = 0;
    while (fgets(line, sizeof line, f)) {
        if (strstr(line, "reports ERROR") && strstr(line, "\"x\\x0aoceand: forged line\\x0a\\x1b[2J\""))
            reported = 1;
        forged |= strncmp(line, "oceand: forged line", 19) == 0;
        escape |= strchr(line, 0x1b) != NULL;
    }
    fclose(f);
    assert_true(reported);
    assert_false(forged);
    assert_false(escape);
}

/* A camera at the edge of the world (x = -1e10 + 10 m, within CAMERA's
 * bound): layout 0's tiles and mesh reach past it, and their
 * origins were refused by the encoder: one frame, then silence and a log
 * line a tick.  Both layouts are served there. */
static void camera_at_the_world_edge(void **state)
{
    (void)state;
    for (int layout = 0; layout < 2; layout++) {
        oc_client *c = connect_bg(port);
        proto_subscribe s;
        small_subscribe(&s);
        s.layout = (uint8_t)(layout ? PROTO_LAYOUT_CASCADE : PROTO_LAYOUT_WORLD);
        s.mesh_kind = PROTO_MESH_CONCENTRIC;
        s.mesh_codec = layout ? 0 : 2;
        s.lod_levels = 4;
        s.frame_rate_hz = 10;
        assert_int_equal(oc_client_subscribe(c, &s), OCEAN_OK);
        proto_camera cam;
        oc_camera_default(&cam);
        cam.pos[0] = -1e10 + 10;
        cam.pos[1] = 20;
        assert_int_equal(oc_client_send_camera(c, &cam, NULL), OCEAN_OK);
        int got = 0;
        double end = test_now_s() + 5;
        while (got < 3 && test_now_s() < end) {
            oc_frame *f;
            if (oc_client_next_frame(c, 200, &f) != OCEAN_OK) continue;
            /* frames made for this camera, every tile decoded */
            int whole = f->info.camera_seq != PROTO_NO_CAMERA && f->info.tile_count > 0;
            for (uint32_t i = 0; whole && i < f->info.tile_count; i++)
                whole = f->tiles[i].decode_result == OCEAN_OK;
            got += whole;
            oc_frame_free(f);
        }
        if (got < 3) fprintf(stderr, "layout %d: %d frames at x = -1e10\n", layout, got);
        assert_true(got >= 3);
        oc_client_destroy(c);
    }
}

typedef struct bad_case {
    const char *what;
    uint8_t *bytes;
    size_t len;
    int opcode;
    ocean_result want;
} bad_case;

/* Every kind of bad input gets its ERROR; the sender's state is untouched
 * and another client keeps receiving. */
static void bad_input_gets_error(void **state)
{
    (void)state;
    oc_client *good = connect_bg(port);
    proto_subscribe gs;
    small_subscribe(&gs);
    gs.mesh_kind = PROTO_MESH_NONE;
    assert_int_equal(oc_client_subscribe(good, &gs), OCEAN_OK);
    drain_frames(good);
    test_ws w;
    assert_int_equal(test_ws_connect(&w, port, "/", PROTO_SUBPROTOCOL), 0);
    proto_msg m;
    assert_true(test_msg_wait(&w, PROTO_HELLO, 3000, &m));
    proto_msg_free(&m);

    /* CAMERA before SUBSCRIBE */
    proto_msg cm;
    proto_msg_init(&cm, PROTO_CAMERA);
    oc_camera_default(&cm.u.camera);
    test_msg_send(&w, &cm);
    assert_true(test_msg_wait(&w, PROTO_ERROR, 3000, &m));
    assert_int_equal(m.u.error.code, OCEAN_ESTATE);
    assert_int_equal(m.u.error.offending_type, PROTO_CAMERA);
    proto_msg_free(&m);

    /* a good subscription: 16-sample tiles, one level, no mesh */
    proto_msg sm;
    proto_msg_init(&sm, PROTO_SUBSCRIBE);
    small_subscribe(&sm.u.subscribe);
    sm.u.subscribe.tile_size = 16;
    sm.u.subscribe.lod_levels = 1;
    sm.u.subscribe.mesh_kind = PROTO_MESH_NONE;
    test_msg_send(&w, &sm);

    bad_case cases[20];
    int nc = 0;
    size_t len;
    uint8_t *good_cam = test_msg_encode(&cm, &len);
    size_t cam_len = len;
    /* shorter than a header */
    cases[nc++] = (bad_case){"truncated", memcpy(malloc(10), good_cam, 10), 10, 2, OCEAN_ETRUNC};
    /* bad magic */
    uint8_t *b = memcpy(malloc(cam_len), good_cam, cam_len);
    b[0] ^= 0xFF;
    cases[nc++] = (bad_case){"magic", b, cam_len, 2, OCEAN_EFORMAT};
    /* version 2 */
    b = memcpy(malloc(cam_len), good_cam, cam_len);
    proto_st16(b + 4, 2);
    cases[nc++] = (bad_case){"version", b, cam_len, 2, OCEAN_EVERSION};
    /* unknown type */
    b = memcpy(malloc(cam_len), good_cam, cam_len);
    proto_st16(b + 6, 99);
    cases[nc++] = (bad_case){"type", b, cam_len, 2, OCEAN_ETYPE};
    /* length lying */
    b = memcpy(malloc(cam_len), good_cam, cam_len);
    proto_st32(b + 12, (uint32_t)(cam_len - PROTO_HEADER_SIZE + 64));
    cases[nc++] = (bad_case){"length", b, cam_len, 2, OCEAN_ETRUNC};
    /* NaN position */
    b = memcpy(malloc(cam_len), good_cam, cam_len);
    proto_stf64(b + PROTO_HEADER_SIZE, NAN);
    cases[nc++] = (bad_case){"nan", b, cam_len, 2, OCEAN_EINVAL};
    /* text frame (valid UTF-8: invalid UTF-8 is closed with 1007, RFC 6455
     * 8.1, tests/test_attacks.c) */
    cases[nc++] = (bad_case){"text", (uint8_t *)strdup("SUBSCRIBE please"), 16, 1, OCEAN_EFORMAT};
    /* oversized */
    size_t big = 65536 + 4096;
    b = calloc(1, big);
    memcpy(b, good_cam, PROTO_HEADER_SIZE);
    cases[nc++] = (bad_case){"oversized", b, big, 2, OCEAN_ETOOBIG};
    /* a server-to-client message */
    proto_msg hm;
    proto_msg_init(&hm, PROTO_QUERY_RESULT);
    proto_query_sample qs = {0};
    hm.u.result.count = 1;
    hm.u.result.samples = &qs;
    cases[nc++] = (bad_case){"server-only", test_msg_encode(&hm, &len), len, 2, OCEAN_ETYPE};
    /* tile size above the server's maximum */
    proto_msg bs = sm;
    bs.u.subscribe.tile_size = 1000;
    cases[nc++] = (bad_case){"tile_size", test_msg_encode(&bs, &len), len, 2, OCEAN_ETOOBIG};
    /* frame rate above the server's maximum */
    bs = sm;
    bs.u.subscribe.frame_rate_hz = 200;
    cases[nc++] = (bad_case){"frame_rate", test_msg_encode(&bs, &len), len, 2, OCEAN_EINVAL};
    /* a coarsest level spacing (1e4 m x 2^7) beyond what a TILE can state,
     * with tiles small enough to pass the span check: it was accepted and
     * then no FRAME could be encoded, without an ERROR */
    bs = sm;
    bs.u.subscribe.tile_size = 2;
    bs.u.subscribe.lod_levels = 8;
    bs.u.subscribe.base_spacing_m = 1e4f;
    cases[nc++] = (bad_case){"coarsest_spacing", test_msg_encode(&bs, &len), len, 2, OCEAN_EINVAL};
    /* unknown codec */
    bs = sm;
    uint8_t *sb = test_msg_encode(&bs, &len);
    sb[PROTO_HEADER_SIZE + 2] = 77;
    cases[nc++] = (bad_case){"codec", sb, len, 2, OCEAN_ETYPE};
    /* camera outside the protocol's range of positions (5e6 m is inside:
     * PROTOCOL.md allows |y| <= 1e7) */
    b = memcpy(malloc(cam_len), good_cam, cam_len);
    proto_stf64(b + PROTO_HEADER_SIZE + 8, 2e7);
    cases[nc++] = (bad_case){"camera_y", b, cam_len, 2, OCEAN_EINVAL};
    /* sea state with a wrong token */
    proto_msg ss;
    proto_msg_init(&ss, PROTO_SEA_STATE);
    ss.u.sea_state.op = PROTO_SEA_SET;
    srv_sea_from_params(&settings.params, &ss.u.sea_state.sea);
    snprintf(ss.u.sea_state.token, sizeof ss.u.sea_state.token, "guess");
    cases[nc++] = (bad_case){"token", test_msg_encode(&ss, &len), len, 2, OCEAN_EAUTH};
    /* a sea the decoder lets through but the simulation refuses */
    ss.u.sea_state.sea.swell = 50;
    snprintf(ss.u.sea_state.token, sizeof ss.u.sea_state.token, "test-token");
    cases[nc++] = (bad_case){"sea_depth", test_msg_encode(&ss, &len), len, 2, OCEAN_EINVAL};

    for (int i = 0; i < nc; i++) {
        assert_int_equal(test_ws_send(&w, cases[i].opcode, cases[i].bytes, cases[i].len), 0);
        int got = test_msg_wait(&w, PROTO_ERROR, 3000, &m);
        if (!got || m.u.error.code != cases[i].want)
            fprintf(stderr, "case %s: got %s (%u: %s), want %s\n", cases[i].what, got ? "ERROR" : "nothing",
                    got ? m.u.error.code : 0, got ? m.u.error.message : "", ocean_strerror(cases[i].want));
        assert_true(got);
        assert_int_equal(m.u.error.code, cases[i].want);
        assert_true(strlen(m.u.error.message) > 5);
        proto_msg_free(&m);
        free(cases[i].bytes);
    }
    /* message rate: a burst beyond server.msg_burst is refused */
    int rate_errors = 0;
    for (int i = 0; i < 150; i++) test_ws_send(&w, 2, good_cam, cam_len);
    while (test_msg_wait(&w, PROTO_ERROR, 500, &m)) {
        if (m.u.error.code == OCEAN_ERATE) rate_errors++;
        proto_msg_free(&m);
    }
    assert_true(rate_errors > 0);
    usleep(300000); /* refill the bucket */
    /* the sender's subscription is untouched: still 16-sample tiles */
    int ok = 0;
    for (int i = 0; i < 5 && !ok; i++) {
        if (!test_msg_wait(&w, PROTO_FRAME, 2000, &m)) break;
        if (m.u.frame.tile_count == 4 && m.u.frame.tiles[0].width == 16 && !m.u.frame.has_mesh) ok = 1;
        proto_msg_free(&m);
    }
    assert_true(ok);
    free(good_cam);
    test_ws_close(&w);
    /* and the other client never stopped */
    int frames = 0;
    oc_frame *f;
    while (oc_client_next_frame(good, 0, &f) == OCEAN_OK) {
        frames++;
        oc_frame_free(f);
    }
    /* a daemon a bad client stalls sends it none; how many more come over
     * the phase is the host's speed (CI with a core busy, beside the browser
     * test: fewer than 10 at 30 Hz) */
    assert_true(frames >= 3);
    oc_client_stats st;
    oc_client_get_stats(good, &st);
    assert_int_equal(st.errors_rx, 0);
    oc_client_destroy(good);
}

static void wait_hub_wind(double wind);

/* Admin sea-state change: refused without the token (above), taken with it
 * at the stated time and announced to every client.  The time leaves the
 * server's lead (PROTOCOL.md "Sea-state timeline": a few build times and two
 * ticks; on a loaded host more than 0.2 s) so it is taken as stated. */
static void sea_state_admin_change(void **state)
{
    (void)state;
    oc_client *c = connect_client(port, NULL);
    proto_sea sea;
    double eff;
    assert_int_equal(oc_client_sea_state(c, &sea, &eff), OCEAN_OK);
    double old_wind = sea.wind_u10;
    sea.wind_u10 = old_wind + 3;
    double at = srv_hub_sim_time(srv_daemon_hub(daemon_)) + 2.0;
    assert_int_equal(oc_client_sea_state_set(c, &sea, at, "test-token", 5000), OCEAN_OK);
    proto_sea now;
    assert_int_equal(oc_client_sea_state(c, &now, &eff), OCEAN_OK);
    assert_true(now.wind_u10 == old_wind + 3);
    assert_true(fabs(eff - at) < 1e-9);
    wait_hub_wind(old_wind + 3);
    oc_client *d = connect_client(port, NULL);
    proto_hello h;
    assert_int_equal(oc_client_hello(d, &h), OCEAN_OK);
    assert_true(h.sea.wind_u10 == old_wind + 3);
    /* back to the original sea for the other tests */
    sea.wind_u10 = old_wind;
    assert_int_equal(oc_client_sea_state_set(c, &sea, 0, "test-token", 5000), OCEAN_OK);
    wait_hub_wind(old_wind);
    oc_client_destroy(d);
    oc_client_destroy(c);
}

/* Every client receives every admin's announces: a SET is answered only by
 * the announce of its own sea (or an ERROR), not by another admin's change
 * that happens to arrive first.  B's set is sent raw, just before A's
 * refused one; A must see its EAUTH, every time. */
static void sea_state_set_answered_by_its_own_announce(void **state)
{
    (void)state;
    oc_client *a = connect_client(port, NULL);
    proto_sea sea;
    double eff;
    assert_int_equal(oc_client_sea_state(a, &sea, &eff), OCEAN_OK);
    const double old_wind = sea.wind_u10;
    test_ws b;
    assert_int_equal(test_ws_connect(&b, port, "/", PROTO_SUBPROTOCOL), 0);
    for (int i = 0; i < 5; i++) {
        proto_msg m;
        proto_msg_init(&m, PROTO_SEA_STATE);
        m.u.sea_state.op = PROTO_SEA_SET;
        m.u.sea_state.effective_time = 0;
        m.u.sea_state.sea = sea;
        m.u.sea_state.sea.wind_u10 = old_wind + 1 + i;
        snprintf(m.u.sea_state.token, sizeof m.u.sea_state.token, "test-token");
        test_msg_send(&b, &m);
        proto_sea mine = sea;
        mine.wind_u10 = old_wind + 2 + i;
        assert_int_equal(oc_client_sea_state_set(a, &mine, 0, "wrong-token", 5000), OCEAN_EAUTH);
    }
    test_ws_close(&b);
    /* back to the original sea for the other tests */
    assert_int_equal(oc_client_sea_state_set(a, &sea, 0, "test-token", 5000), OCEAN_OK);
    wait_hub_wind(old_wind);
    oc_client_destroy(a);
}

/* Changes set "now" (effective time 0) one after another are entered L
 * ahead of the clock and L apart (PROTOCOL.md "Sea-state timeline": L is
 * twice the measured build time of an ocean and two tick periods), so each
 * change's ocean is built ahead, off the tick path, and none when it falls
 * due.  Issue 46: 1200 sets effective now had their oceans built on the
 * tick path, one a tick, and the viewers starved meanwhile. */
static void sea_changes_built_ahead(void **state)
{
    (void)state;
    srv_hub *h = srv_daemon_hub(daemon_);
    oc_client *a = connect_client(port, NULL);
    proto_sea sea;
    double eff;
    assert_int_equal(oc_client_sea_state(a, &sea, &eff), OCEAN_OK);
    /* the changes of the tests before have all taken effect and been counted */
    int left = 1;
    for (double end = test_now_s() + 20; left && test_now_s() < end; usleep(20000)) {
        pthread_mutex_lock(&h->lock);
        left = h->n_sea_pending || h->sea_applying;
        pthread_mutex_unlock(&h->lock);
    }
    assert_int_equal(left, 0);
    uint64_t due0 = atomic_load(&h->stats.sea_built_due), ahead0 = atomic_load(&h->stats.sea_built_ahead);
    test_ws b;
    assert_int_equal(test_ws_connect(&b, port, "/", PROTO_SUBPROTOCOL), 0);
    proto_msg m;
    assert_true(test_msg_wait(&b, PROTO_HELLO, 3000, &m));
    proto_msg_free(&m);
    enum { N = 8 };
    double asked[N], got[N];
    for (int i = 0; i < N; i++) {
        proto_msg_init(&m, PROTO_SEA_STATE);
        m.u.sea_state.op = PROTO_SEA_SET;
        m.u.sea_state.sea = sea;
        m.u.sea_state.sea.wind_u10 = sea.wind_u10 + 0.5 + 0.25 * i;
        snprintf(m.u.sea_state.token, sizeof m.u.sea_state.token, "test-token");
        asked[i] = srv_hub_sim_time(h);
        test_msg_send(&b, &m);
        assert_true(test_msg_wait(&b, PROTO_SEA_STATE, 3000, &m));
        got[i] = m.u.sea_state.effective_time;
        proto_msg_free(&m);
    }
    double tick = 1.0 / settings.srv.tick_rate;
    for (int i = 0; i < N; i++) {
        assert_true(got[i] >= asked[i] + 2 * tick);
        if (i) assert_true(got[i] - got[i - 1] >= 2 * tick);
    }
    double end = test_now_s() + 20;
    left = 1;
    while (left && test_now_s() < end) {
        pthread_mutex_lock(&h->lock);
        left = h->n_sea_pending || h->sea_applying;
        pthread_mutex_unlock(&h->lock);
        usleep(20000);
    }
    uint64_t due = atomic_load(&h->stats.sea_built_due) - due0;
    uint64_t ahead = atomic_load(&h->stats.sea_built_ahead) - ahead0;
    fprintf(stderr, "%d changes set now: entered %.3f-%.3f s ahead, %.3f-%.3f s apart; %llu built ahead, %llu when "
            "due\n", N, got[0] - asked[0], got[N - 1] - asked[N - 1], got[1] - got[0], got[N - 1] - got[N - 2],
            (unsigned long long)ahead, (unsigned long long)due);
    assert_int_equal(left, 0);
    /* built ahead as a rule (before: every one when due, 0 ahead); the
     * builder runs at nice 10, so beside other work it misses some, and two
     * changes that then fall due in one tick are applied as one (a quiet CI
     * run: 6 ahead, 1 when due; a slowed host beside the sanitizer build:
     * 4 ahead, 2 when due).  How many it misses is the host's speed: most
     * built ahead is the mechanism's */
    assert_true(ahead > due && ahead + due <= N);
    test_ws_close(&b);
    /* the original sea back, in force before the next test */
    assert_int_equal(oc_client_sea_state_set(a, &sea, 0, "test-token", 5000), OCEAN_OK);
    wait_hub_wind(sea.wind_u10);
    oc_client_destroy(a);
}

/* ---- the sea-state timeline ------------------------------------------------------ */

/* What one raw client knows of the timeline, built only from what it
 * received (PROTOCOL.md "Sea-state timeline"): the HELLO's sea holds from
 * the client's start, each announce from its effective_time, a later
 * announce at the same effective_time replaces the earlier. */
typedef struct timeline {
    int n;
    double eff[64];
    proto_sea sea[64];
    double hello_t;        /* HELLO header sim_time */
    int hello;
} timeline;

static void tl_add(timeline *tl, double eff, const proto_sea *sea)
{
    int at = 0;
    while (at < tl->n && tl->eff[at] < eff) at++;
    if (!(at < tl->n && tl->eff[at] == eff)) {
        assert_true(tl->n < 64);
        memmove(&tl->eff[at + 1], &tl->eff[at], (size_t)(tl->n - at) * sizeof tl->eff[0]);
        memmove(&tl->sea[at + 1], &tl->sea[at], (size_t)(tl->n - at) * sizeof tl->sea[0]);
        tl->n++;
    }
    tl->eff[at] = eff;
    tl->sea[at] = *sea;
}

/* The sea this client holds for sim time t. */
static const proto_sea *tl_at(const timeline *tl, double t)
{
    const proto_sea *r = NULL;
    for (int i = 0; i < tl->n; i++)
        if (tl->eff[i] <= t) r = &tl->sea[i];
    return r;
}

/* Reads what arrives for `ms` into the timeline; returns the number of
 * SEA_STATE announces read. */
static int tl_read(test_ws *w, timeline *tl, int ms)
{
    int got = 0;
    double end = test_now_s() + ms / 1000.0;
    while (test_now_s() < end) {
        uint8_t *b;
        size_t n;
        int op = test_ws_recv(w, (int)((end - test_now_s()) * 1000) + 1, &b, &n);
        if (op <= 0) break;
        proto_msg m;
        ocean_result r = op == 2 ? proto_decode(b, n, &m, NULL, 0) : OCEAN_EFORMAT;
        free(b);
        if (r != OCEAN_OK) continue;
        if (m.hdr.type == PROTO_HELLO) {
            assert_false(tl->hello);          /* HELLO comes first, once */
            assert_int_equal(tl->n, 0);       /* no announce before it */
            tl->hello = 1;
            tl->hello_t = m.hdr.sim_time;
            tl_add(tl, -INFINITY, &m.u.hello.sea);
        } else if (m.hdr.type == PROTO_SEA_STATE) {
            assert_true(tl->hello);
            assert_int_equal(m.u.sea_state.op, PROTO_SEA_ANNOUNCE);
            tl_add(tl, m.u.sea_state.effective_time, &m.u.sea_state.sea);
            got++;
        }
        proto_msg_free(&m);
    }
    return got;
}

static void sea_connect(test_ws *w, timeline *tl, int ms)
{
    memset(tl, 0, sizeof *tl);
    assert_int_equal(test_ws_connect(w, port, "/", PROTO_SUBPROTOCOL), 0);
    tl_read(w, tl, ms);
    assert_true(tl->hello);
}

static void sea_send(test_ws *w, int op, const proto_sea *sea, double eff)
{
    proto_msg m;
    proto_msg_init(&m, PROTO_SEA_STATE);
    m.u.sea_state.op = (uint8_t)op;
    if (op == PROTO_SEA_SET) {
        m.u.sea_state.sea = *sea;
        m.u.sea_state.effective_time = eff;
        snprintf(m.u.sea_state.token, sizeof m.u.sea_state.token, "test-token");
    }
    test_msg_send(w, &m);
}

static double hub_now(void) { return srv_hub_sim_time(srv_daemon_hub(daemon_)); }

/* Waits until the daemon's current sea has this wind and no change is
 * pending (the changes applied, none left to count in the next test), up
 * to a deadline that finds a stopped daemon: a change's ocean is built at
 * nice 10 (srv_seabuild.h), which a loaded host starves for seconds (a
 * busy clean-clone run passed 5 s, and the next test saw the change). */
static void wait_hub_wind(double wind)
{
    srv_hub *h = srv_daemon_hub(daemon_);
    double end = test_now_s() + FRAME_WAIT_MS / 1000.0;
    double w = -1;
    while (test_now_s() < end) {
        pthread_mutex_lock(&h->lock);
        w = h->sea_now.wind_u10;
        int pending = h->n_sea_pending || h->sea_applying;
        pthread_mutex_unlock(&h->lock);
        if (w == wind && !pending) return;
        usleep(20000);
    }
    fail_msg("the daemon's sea has wind %g, want %g", w, wind);
}

/* Height, normal and velocity the sea `sea` gives at (x, z) and time t,
 * evaluated here with the simulation library (what a QUERY answers). */
static void local_query(const proto_sea *sea, double t, const double *xz, size_t n, ocean_query_result *res)
{
    ocean_params p;
    srv_params_from_sea(sea, &settings.params, &p);
    ocean *o;
    char msg[256];
    assert_int_equal(ocean_create(&p, &o, msg, sizeof msg), OCEAN_OK);
    ocean_frame *lf;
    assert_int_equal(ocean_frame_create(o, &lf), OCEAN_OK);
    ocean_request rq;
    memset(&rq, 0, sizeof rq);
    for (int k = 0; k < p.cascades; k++) rq.effects[k] = OCEAN_QUERY_EFFECTS;
    rq.cutoff_k = INFINITY;
    ocean_filter_config fc;
    ocean_filter_config_default(&fc, &p.sea);
    rq.order = fc.order;
    rq.low_boost = 1.0;
    assert_int_equal(ocean_evaluate(o, t, &rq, lf), OCEAN_OK);
    double patch, klo, khi;
    ocean_cascade_band(o, p.cascades - 1, &patch, &klo, &khi);
    ocean_gerstner_params gp;
    assert_true(srv_settings_near_field(&settings, &p, &gp)); /* the daemon's near field */
    assert_true(gp.k_lo == khi);
    ocean_gerstner *g = NULL;
    assert_int_equal(ocean_gerstner_create(&gp, &g, msg, sizeof msg), OCEAN_OK);
    ocean_query_options opt;
    ocean_query_options_default(&opt);
    assert_int_equal(ocean_query_points(lf, g, NULL, t, xz, n, &opt, res, NULL), OCEAN_OK);
    ocean_gerstner_destroy(g);
    ocean_frame_destroy(lf);
    ocean_destroy(o);
}

static int same_sea(const proto_sea *a, const proto_sea *b)
{
    return a && b && a->wind_u10 == b->wind_u10 && a->seed == b->seed && a->wind_dir_deg == b->wind_dir_deg;
}

/* A change scheduled for later reaches clients that join before it takes
 * effect (HELLO + the pending announce) and after (HELLO with the new sea);
 * every client holds the same sea for every sim time from its HELLO on;
 * the daemon serves that sea from the first tick at or after the effective
 * time (QUERY heights against the simulation library on either side). */
static void sea_timeline_scheduled_change(void **state)
{
    (void)state;
    test_ws a, b, c;
    timeline ta, tb, tc;
    sea_connect(&a, &ta, 300);
    proto_sea old = *tl_at(&ta, hub_now());
    proto_sea nw = old;
    nw.wind_u10 = old.wind_u10 + 4;
    nw.seed = old.seed + 1;
    double eff = hub_now() + 3.0; /* room for a loaded machine before it takes effect */
    sea_send(&a, PROTO_SEA_SET, &nw, eff);
    /* the setter's reply is the announce, with the effective time asked */
    assert_int_equal(tl_read(&a, &ta, 400), 1);
    assert_int_equal(ta.n, 2);
    assert_true(ta.eff[1] == eff);
    /* B joins before the change takes effect */
    sea_connect(&b, &tb, 400);
    assert_true(tb.hello_t < eff);
    assert_true(same_sea(tl_at(&tb, tb.hello_t), &old));
    assert_true(same_sea(tl_at(&tb, eff), &nw));
    /* the server still serves the old sea before eff ... */
    oc_client *q = connect_client(port, NULL);
    /* the C library keeps the timeline too */
    proto_sea lib;
    double lib_eff = 0;
    /* the announce behind HELLO may still be on its way to the library */
    for (double end = test_now_s() + 5; test_now_s() < end; oc_service(q, 20))
        if (oc_client_sea_at(q, eff, &lib, &lib_eff) == OCEAN_OK && lib_eff == eff) break;
    assert_int_equal(oc_client_sea_at(q, eff - 0.01, &lib, &lib_eff), OCEAN_OK);
    assert_true(same_sea(&lib, &old));
    assert_int_equal(oc_client_sea_at(q, eff, &lib, &lib_eff), OCEAN_OK);
    assert_true(same_sea(&lib, &nw) && lib_eff == eff);
    const double xz[] = {13.5, -7.25, 250.0, 125.0, -1e5, 3e4};
    oc_query_result qr;
    ocean_query_result lr[3];
    assert_int_equal(oc_client_query(q, xz, 3, 0, 0, 5000, &qr), OCEAN_OK);
    assert_true(qr.t < eff);
    local_query(&old, qr.t, xz, 3, lr);
    for (int i = 0; i < 3; i++) assert_true(fabs(qr.samples[i].height - lr[i].height) <= 1e-5 + 1e-6 * fabs(lr[i].height));
    oc_query_result_free(&qr);
    /* ... and the new one from its effective time */
    while (hub_now() < eff + 0.3) usleep(50000);
    sea_connect(&c, &tc, 400);
    assert_true(same_sea(tl_at(&tc, tc.hello_t), &nw));
    assert_int_equal(oc_client_query(q, xz, 3, 0, 0, 5000, &qr), OCEAN_OK);
    assert_true(qr.t >= eff);
    local_query(&nw, qr.t, xz, 3, lr);
    double dmax = 0;
    for (int i = 0; i < 3; i++) {
        assert_true(fabs(qr.samples[i].height - lr[i].height) <= 1e-5 + 1e-6 * fabs(lr[i].height));
        dmax = fmax(dmax, fabs(lr[i].height));
    }
    assert_true(dmax > 0.01);
    oc_query_result_free(&qr);
    /* every client holds the same sea at every sim time since it joined */
    tl_read(&a, &ta, 100);
    tl_read(&b, &tb, 100);
    for (double t = tc.hello_t - 3.0; t < eff + 1.0; t += 1.0 / 30) {
        const proto_sea *sa = tl_at(&ta, t), *sb = tl_at(&tb, t), *sc = tl_at(&tc, t);
        const proto_sea *want = t < eff ? &old : &nw;
        if (t >= ta.hello_t) assert_true(same_sea(sa, want));
        if (t >= tb.hello_t) assert_true(same_sea(sb, want));
        if (t >= tc.hello_t) assert_true(same_sea(sc, want));
    }
    /* back to the original sea */
    sea_send(&a, PROTO_SEA_SET, &old, 0);
    wait_hub_wind(old.wind_u10);
    oc_client_destroy(q);
    test_ws_close(&a);
    test_ws_close(&b);
    test_ws_close(&c);
}

/* The late joiner of issue 16: a client connecting right after a change
 * (effective now) is entered gets a HELLO and the announce, never the
 * previous sea alone.  Repeated on the idle daemon, where the old code lost
 * every time. */
static void sea_timeline_late_joiner(void **state)
{
    (void)state;
    test_ws a;
    timeline ta;
    sea_connect(&a, &ta, 300);
    proto_sea old = *tl_at(&ta, hub_now());
    for (int k = 1; k <= 8; k++) {
        proto_sea nw = old;
        nw.wind_u10 = old.wind_u10 + k;
        sea_send(&a, PROTO_SEA_SET, &nw, 0);
        /* no waiting: the joiner races the change */
        test_ws b;
        timeline tb;
        memset(&tb, 0, sizeof tb);
        assert_int_equal(test_ws_connect(&b, port, "/", PROTO_SUBPROTOCOL), 0);
        for (double end = test_now_s() + 5; !tb.hello && test_now_s() < end;) tl_read(&b, &tb, 50);
        int n0 = ta.n;
        for (double end = test_now_s() + 5; ta.n == n0 && test_now_s() < end;) tl_read(&a, &ta, 50);
        assert_true(tb.hello);
        assert_true(ta.n > n0);
        /* from the change's effective time (the server's lead ahead of the
         * set) on, the joiner holds what the setter holds: in its HELLO or
         * in an announce, which on a busy host may reach it well after the
         * setter's (read until it holds it, up to a deadline) */
        double t = fmax(ta.eff[ta.n - 1], tb.hello_t);
        for (double end = test_now_s() + 5; !same_sea(tl_at(&tb, t), &nw) && test_now_s() < end;)
            tl_read(&b, &tb, 50);
        if (!same_sea(tl_at(&tb, t), &nw))
            fail_msg("try %d: the joiner holds wind %g at t = %.3f, everyone else %g", k,
                     tl_at(&tb, t)->wind_u10, t, nw.wind_u10);
        assert_true(same_sea(tl_at(&ta, t), &nw));
        test_ws_close(&b);
    }
    /* the old sea back after the last change made: a set "now" goes in at
     * now + the lead, and the lead shrinks as the builds measured get
     * faster, so on a loaded host it could fall before changes still
     * pending, which would then follow it */
    sea_send(&a, PROTO_SEA_SET, &old, ta.eff[ta.n - 1] + 0.01);
    wait_hub_wind(old.wind_u10);
    test_ws_close(&a);
}

/* SEA_STATE get: the current sea (with the time it took effect) and every
 * pending change, without reconnecting.  The oceans of changes set ahead
 * are built ahead, off the tick path (srv_seabuild.h). */
static void sea_timeline_get(void **state)
{
    (void)state;
    test_ws a;
    timeline ta;
    srv_hub *h = srv_daemon_hub(daemon_);
    uint64_t ahead0 = stat_of(&h->stats.sea_built_ahead), changes0 = stat_of(&h->stats.sea_changes);
    sea_connect(&a, &ta, 300);
    proto_sea old = *tl_at(&ta, hub_now());
    proto_sea n1 = old, n2 = old;
    n1.wind_u10 += 1;
    n2.wind_u10 += 2;
    double t0 = hub_now();
    sea_send(&a, PROTO_SEA_SET, &n2, t0 + 3.0);   /* entered out of order */
    sea_send(&a, PROTO_SEA_SET, &n1, t0 + 1.5);
    assert_int_equal(tl_read(&a, &ta, 300), 2);
    timeline g;
    memset(&g, 0, sizeof g);
    g.hello = 1;   /* get answers announces only */
    sea_send(&a, PROTO_SEA_GET, NULL, 0);
    assert_int_equal(tl_read(&a, &g, 400), 3);
    assert_true(g.eff[0] <= hub_now());
    assert_true(same_sea(&g.sea[0], &old));
    assert_true(g.eff[1] == t0 + 1.5 && same_sea(&g.sea[1], &n1));
    assert_true(g.eff[2] == t0 + 3.0 && same_sea(&g.sea[2], &n2));
    /* a set at a past effective time takes effect now, never earlier */
    proto_sea n3 = old;
    n3.wind_u10 += 3;
    double before = hub_now();
    sea_send(&a, PROTO_SEA_SET, &n3, before - 100);
    timeline r;
    memset(&r, 0, sizeof r);
    r.hello = 1;
    assert_int_equal(tl_read(&a, &r, 300), 1);
    /* entered the server's lead ahead of the clock (a few tenths of a
     * second on a loaded host), never earlier than asked; taken (counted
     * below) */
    assert_true(r.eff[0] >= before && r.eff[0] < before + 5);
    /* after both pending changes are due, get gives n2 alone (entered last in time) */
    while (hub_now() < t0 + 3.3) usleep(50000);
    memset(&g, 0, sizeof g);
    g.hello = 1;
    sea_send(&a, PROTO_SEA_GET, NULL, 0);
    assert_int_equal(tl_read(&a, &g, 400), 1);
    assert_true(same_sea(&g.sea[0], &n2));
    assert_true(g.eff[0] == t0 + 3.0);
    /* n3 (now), n1 and n2 applied; n1 and n2 were pending for over a
     * second: their oceans were built ahead */
    assert_true(stat_of(&h->stats.sea_changes) >= changes0 + 3);
    assert_true(stat_of(&h->stats.sea_built_ahead) >= ahead0 + 2);
    sea_send(&a, PROTO_SEA_SET, &old, 0);
    wait_hub_wind(old.wind_u10);
    test_ws_close(&a);
}

/* SEA_STATE set is checked against the simulation's ranges, which
 * PROTOCOL.md states beside the block's: swell [0, 10], phillips_a [0, 1],
 * small_wave_m [0, 100]; the bound is accepted, beyond it EINVAL names the
 * field. */
static void sea_set_ranges(void **state)
{
    (void)state;
    test_ws a;
    timeline ta;
    sea_connect(&a, &ta, 300);
    proto_sea old = *tl_at(&ta, hub_now());
    struct { const char *name; size_t off; double ok, bad; } f[] = {
        {"swell", offsetof(proto_sea, swell), 10, 10.5},
        {"phillips_a", offsetof(proto_sea, phillips_a), 1, 1.5},
        {"small_wave", offsetof(proto_sea, small_wave_m), 100, 150},
    };
    for (size_t i = 0; i < sizeof f / sizeof f[0]; i++) {
        proto_sea x = old;
        *(double *)((char *)&x + f[i].off) = f[i].bad;
        sea_send(&a, PROTO_SEA_SET, &x, hub_now() + 100);
        proto_msg m;
        assert_true(test_msg_wait(&a, PROTO_ERROR, 3000, &m));
        assert_int_equal(m.u.error.code, OCEAN_EINVAL);
        if (!strstr(m.u.error.message, f[i].name)) fail_msg("%s: %s", f[i].name, m.u.error.message);
        proto_msg_free(&m);
        x = old;
        *(double *)((char *)&x + f[i].off) = f[i].ok;
        sea_send(&a, PROTO_SEA_SET, &x, hub_now() + 0.05 * (double)(i + 1));
        timeline r;
        memset(&r, 0, sizeof r);
        r.hello = 1;
        assert_int_equal(tl_read(&a, &r, 300), 1);
    }
    /* the old sea back, waited for (it is entered a lead ahead, more than
     * 0.5 s on a loaded host) */
    sea_send(&a, PROTO_SEA_SET, &old, hub_now() + 0.5);
    srv_hub *h = srv_daemon_hub(daemon_);
    int same = 0;
    for (double end = test_now_s() + 10; !same && test_now_s() < end; usleep(20000)) {
        pthread_mutex_lock(&h->lock);
        same = h->sea_now.wind_u10 == old.wind_u10 && h->sea_now.swell == old.swell &&
               h->sea_now.phillips_a == old.phillips_a && h->sea_now.small_wave_m == old.small_wave_m &&
               h->n_sea_pending == 0 && !h->sea_applying;
        pthread_mutex_unlock(&h->lock);
    }
    assert_true(same);
    test_ws_close(&a);
}

/* ---- ENTITY (issue 43) ------------------------------------------------------ */

/* An ENTITY set of a ship (120 x 15 x 5 m unless kind says otherwise). */
static void entity_send(test_ws *w, int op, uint32_t id, int kind, double t, double x, double speed, const char *token)
{
    proto_msg m;
    proto_msg_init(&m, PROTO_ENTITY);
    proto_entity *e = &m.u.entity;
    e->op = (uint8_t)op;
    e->id = id;
    if (op == PROTO_ENTITY_SET || op == PROTO_ENTITY_ANNOUNCE) {
        e->kind = (uint8_t)kind;
        e->t = t;
        e->x = x;
        e->z = -20;
        e->speed = (float)speed;
        e->heading_deg = 0;
        e->length_m = kind == 0 ? 120.0f : 16.0f;
        e->beam_m = kind == 0 ? 15.0f : 0.0f;
        e->draught_m = kind == 0 ? 5.0f : 0.0f;
        e->altitude_m = kind == 1 ? 30.0f : 0.0f;
    }
    if (token) snprintf(e->token, sizeof e->token, "%s", token);
    test_msg_send(w, &m);
}

/* The next ENTITY to w, of op; asserts it comes. */
static void entity_expect(test_ws *w, int op, uint32_t id, proto_msg *m)
{
    for (double end = test_now_s() + 5; test_now_s() < end;) {
        assert_true(test_msg_wait(w, PROTO_ENTITY, 3000, m));
        if (m->u.entity.op == op && m->u.entity.id == id) return;
        proto_msg_free(m);
    }
    fail_msg("no ENTITY op %d for id %d", op, (int)id);
}

/* Enters ship or flier id with the entity token at (x, -20), heading +x,
 * and waits for its announce on w. */
static double entity_enter(test_ws *w, uint32_t id, int kind, double t, double x, double speed)
{
    proto_msg m;
    entity_send(w, PROTO_ENTITY_SET, id, kind, t, x, speed, "entity-token");
    entity_expect(w, PROTO_ENTITY_ANNOUNCE, id, &m);
    double from = m.hdr.sim_time; /* the instant the sample takes effect */
    proto_msg_free(&m);
    return from;
}

/* Removes id with token tok and waits for its gone on w; returns the
 * instant it takes effect. */
static double entity_leave(test_ws *w, uint32_t id, const char *tok)
{
    proto_msg m;
    entity_send(w, PROTO_ENTITY_REMOVE, id, 0, 0, 0, 0, tok);
    entity_expect(w, PROTO_ENTITY_GONE, id, &m);
    double from = m.hdr.sim_time;
    proto_msg_free(&m);
    return from;
}

/* An ERROR of code whose message holds `has`; asserts it comes. */
static void error_expect(test_ws *w, ocean_result code, const char *has)
{
    proto_msg m;
    assert_true(test_msg_wait(w, PROTO_ERROR, 3000, &m));
    if (m.u.error.code != code || !strstr(m.u.error.message, has))
        fail_msg("want %s with \"%s\", got %s: %s", ocean_strerror(code), has, ocean_strerror((ocean_result)m.u.error.code),
                 m.u.error.message);
    proto_msg_free(&m);
}

/* The table's newest sample of id is at x (or id is not in it: x NaN). */
static void entity_at(uint32_t id, double x)
{
    ocean_track_sample last;
    ocean_result r = srv_entities_last(srv_daemon_hub(daemon_)->entities, id, &last, NULL);
    if (isnan(x)) assert_int_equal(r, OCEAN_ENOTFOUND);
    else {
        assert_int_equal(r, OCEAN_OK);
        assert_true(last.x == x);
    }
}

/* ENTITY over ocean.v1: a set with the entity token enters a ship and
 * is announced to every client; get answers the asker with every entity,
 * and a client joining later gets them after its HELLO;
 * remove takes it out and says gone to all.  Each hostile set is refused
 * with its reason and changes nothing: a wrong token, NaN, a speed out of
 * range, a teleport, a time far from the clock, a change of kind, an
 * unknown id to remove, one entity past server.max_entities (4 here), an
 * announce sent by a client. */
static void entity_messages(void **state)
{
    (void)state;
    test_ws a, b;
    timeline ta, tb;
    sea_connect(&a, &ta, 300);
    sea_connect(&b, &tb, 300);
    double t0 = hub_now();
    proto_msg m;
    entity_send(&a, PROTO_ENTITY_SET, 7, 0, t0, 100, 5, "entity-token");
    entity_expect(&a, PROTO_ENTITY_ANNOUNCE, 7, &m);
    proto_msg_free(&m);
    entity_expect(&b, PROTO_ENTITY_ANNOUNCE, 7, &m);
    assert_true(m.u.entity.x == 100 && m.u.entity.t == t0 && m.u.entity.length_m == 120.0f && m.u.entity.speed == 5.0f);
    double from7 = m.hdr.sim_time;
    proto_msg_free(&m);
    entity_at(7, 100);
    entity_send(&b, PROTO_ENTITY_GET, 0, 0, 0, 0, 0, NULL);
    entity_expect(&b, PROTO_ENTITY_ANNOUNCE, 7, &m);
    assert_true(m.u.entity.x == 100);
    proto_msg_free(&m);
    /* a client joining later learns it after its HELLO, unasked */
    test_ws late;
    assert_int_equal(test_ws_connect(&late, port, "/", PROTO_SUBPROTOCOL), 0);
    entity_expect(&late, PROTO_ENTITY_ANNOUNCE, 7, &m);
    assert_true(m.u.entity.x == 100 && m.u.entity.t == t0);
    proto_msg_free(&m);
    test_ws_close(&late);

    entity_send(&a, PROTO_ENTITY_SET, 7, 0, t0 + 1, 105, 5, "guess");
    error_expect(&a, OCEAN_EAUTH, "wrong entity token");
    /* NaN in x: the encoder refuses it, so the bytes are forged */
    proto_msg nan;
    proto_msg_init(&nan, PROTO_ENTITY);
    nan.u.entity = (proto_entity){PROTO_ENTITY_SET, 0, 7, t0 + 1, 0, 0, 0, 0, 5, 120, 15, 5, "entity-token"};
    size_t n;
    uint8_t *bytes = test_msg_encode(&nan, &n);
    uint64_t qnan = 0x7FF8000000000000ull;
    memcpy(bytes + PROTO_HEADER_SIZE + 16, &qnan, 8);
    test_ws_send(&a, 2, bytes, n);
    free(bytes);
    error_expect(&a, OCEAN_EINVAL, "entity.x");
    entity_send(&a, PROTO_ENTITY_SET, 7, 0, t0 + 1, 105, 50, "entity-token");
    error_expect(&a, OCEAN_EINVAL, "speed");
    entity_send(&a, PROTO_ENTITY_SET, 7, 0, t0 + 1, 100 + 10000, 5, "entity-token");
    error_expect(&a, OCEAN_EINVAL, "teleport");
    entity_send(&a, PROTO_ENTITY_SET, 7, 0, t0 + 1000, 105, 5, "entity-token");
    error_expect(&a, OCEAN_EINVAL, "sim time");
    entity_send(&a, PROTO_ENTITY_SET, 7, 1, t0 + 1, 105, 5, "entity-token");
    error_expect(&a, OCEAN_EINVAL, "may not change its kind");
    entity_send(&a, PROTO_ENTITY_REMOVE, 99, 0, 0, 0, 0, "entity-token");
    error_expect(&a, OCEAN_ENOTFOUND, "no entity 99");
    entity_send(&a, PROTO_ENTITY_ANNOUNCE, 7, 0, t0 + 1, 105, 5, NULL);
    error_expect(&a, OCEAN_EINVAL, "server-to-client");
    entity_at(7, 100);
    for (uint32_t id = 8; id <= 10; id++) entity_enter(&a, id, 1, t0, 10.0 * id, 0);
    entity_send(&a, PROTO_ENTITY_SET, 11, 1, t0, 110, 0, "entity-token");
    error_expect(&a, OCEAN_ETOOBIG, "server.max_entities");
    entity_at(11, NAN);
    assert_int_equal(srv_entities_count(srv_daemon_hub(daemon_)->entities), 4);

    /* An entry timed before its entity's last takes effect at that last
     * one, on every reader alike: a removal made on one replica just after
     * a sample made on another comes after it in the shared stream, with
     * a time from its own maker's clock that may be a moment earlier. */
    proto_msg early;
    proto_msg_init(&early, PROTO_ENTITY);
    early.u.entity = (proto_entity){.op = PROTO_ENTITY_GONE, .id = 7};
    early.hdr.sim_time = from7 - 0.25;
    char why[256] = "";
    assert_int_equal(srv_hub_entity_enter(srv_daemon_hub(daemon_), &early, why, sizeof why), OCEAN_OK);
    entity_expect(&b, PROTO_ENTITY_GONE, 7, &m);
    assert_true(m.hdr.sim_time == from7);
    proto_msg_free(&m);
    entity_at(7, NAN);
    for (uint32_t id = 8; id <= 10; id++) {
        entity_send(&a, PROTO_ENTITY_REMOVE, id, 0, 0, 0, 0, "entity-token");
        entity_expect(&b, PROTO_ENTITY_GONE, id, &m);
        proto_msg_free(&m);
    }
    assert_int_equal(srv_entities_count(srv_daemon_hub(daemon_)->entities), 0);
    test_ws_close(&a);
    test_ws_close(&b);
}

/* The wakes of the daemon's two ships at sim time t over the sea of
 * timeline ta at the n points xz: the exact series (patterns built here)
 * into exact, and the field's reading of the same patterns into ws (if
 * not NULL). */
static void exact_wakes(const timeline *ta, double t, const double *xz, int n, double *exact, wake_sample *ws)
{
    ocean_params p;
    srv_params_from_sea(tl_at(ta, t), &settings.params, &p);
    ocean_entity_desc d[4];
    ocean_entity_state st[4];
    int k = srv_entities_at(srv_daemon_hub(daemon_)->entities, t, d, st, 4);
    assert_int_equal(k, 2);
    wake_field *f;
    assert_int_equal(wake_field_create(8, &f), OCEAN_OK);
    wake_params need[8];
    int missing = wake_field_missing(f, d, st, k, p.sea.depth_m, xz, (size_t)n, need, 8);
    assert_true(missing >= 1 && missing <= 8);
    for (int i = 0; i < missing; i++) {
        wake_pattern *pat;
        assert_int_equal(wake_pattern_create(&need[i], &pat, NULL, 0), OCEAN_OK);
        wake_field_insert(f, pat);
    }
    assert_int_equal(wake_field_exact(f, d, st, k, p.sea.depth_m, xz, (size_t)n, exact), OCEAN_OK);
    if (ws) assert_int_equal(wake_field_sample(f, d, st, k, p.sea.depth_m, xz, (size_t)n, ws), OCEAN_OK);
    wake_field_destroy(f);
}

/* A ship in another's wake (issue 43): ship 31 steams along +x at 8 m/s
 * and ship 32 follows on its track 300 m astern.  QUERY answers at the
 * second's bow, stern and sides and at points in the first's wake are
 * the wind sea (the simulation library's answer) plus the ships' wakes
 * summed exactly (wake_field_exact, each pattern's waves one by one),
 * within the wakes' own bound, and the answer's error bound covers both
 * parts; the pattern is built when the ships are set, so the first query
 * does not wait; a query before the ships entered the sea has no wake. */
static void wakes_in_queries(void **state)
{
    (void)state;
    test_ws a;
    timeline ta;
    sea_connect(&a, &ta, 300);
    double t0 = hub_now();
    double tq = entity_enter(&a, 31, 0, t0, 0, 8);
    tq = fmax(tq, entity_enter(&a, 32, 0, t0, -300, 8)); /* both in force from tq on */
    assert_true(tq >= t0);
    /* the set asked for the wake's pattern: it is built before any query
     * needs it, and the first query does not wait */
    srv_hub *hub = srv_daemon_hub(daemon_);
    srv_stats *stats = &hub->stats;
    for (double end = test_now_s() + 60; test_now_s() < end && srv_wakes_pending(hub->wakes) > 0;) usleep(20000);
    assert_int_equal(srv_wakes_pending(hub->wakes), 0);
    assert_true(atomic_load(&stats->wake_patterns) >= 1);
    uint64_t waits = atomic_load(&stats->wake_waits);
    enum { N = 7 };
    const double xz[2 * N] = {-240, -20, -360, -20, -300, -28, -300, -12, -100, -20, -150, -45, -200, 5};
    oc_client *q = connect_client(port, NULL);
    oc_query_result qr;
    assert_int_equal(oc_client_query(q, xz, N, 1, tq, 60000, &qr), OCEAN_OK);
    assert_true(qr.t == tq && qr.count == N);
    assert_true(atomic_load(&stats->wake_waits) == waits);
    ocean_query_result lr[N];
    local_query(tl_at(&ta, tq), tq, xz, N, lr);
    /* the exact wakes of the same ships, patterns built here */
    double exact[N], biggest = 0;
    wake_sample ws[N];
    exact_wakes(&ta, tq, xz, N, exact, ws);
    for (int i = 0; i < N; i++) {
        double got = qr.samples[i].height, want = lr[i].height + exact[i];
        printf("(%g, %g): answer %.4f m = sea %.4f + wake %.4f (exact %.4f), error bound %.4f m\n", xz[2 * i],
               xz[2 * i + 1], got, lr[i].height, got - lr[i].height, exact[i], qr.samples[i].error_bound);
        assert_true(fabs(got - want) <= ws[i].error + 1e-5 + 1e-6 * fabs(want));
        assert_true(qr.samples[i].error_bound >= lr[i].error + ws[i].error - 1e-5);
        biggest = fmax(biggest, fabs(exact[i]));
    }
    assert_true(biggest > 0.05);   /* the wake is there to be felt */
    oc_query_result_free(&qr);
    /* before the ships' entries took effect: the wind sea alone */
    double tb = fmin(t0, tq - 1e-3);
    assert_int_equal(oc_client_query(q, xz, N, 1, tb, 30000, &qr), OCEAN_OK);
    local_query(tl_at(&ta, tb), tb, xz, N, lr);
    for (int i = 0; i < N; i++) assert_true(fabs(qr.samples[i].height - lr[i].height) <= 1e-5 + 1e-6 * fabs(lr[i].height));
    oc_query_result_free(&qr);
    oc_client_destroy(q);
    for (uint32_t id = 31; id <= 32; id++) {
        entity_leave(&a, id, "entity-token");
    }
    test_ws_close(&a);
}

/* A round trip on c: every message the daemon queued to it before (the
 * entity entries broadcast so far) has been taken in when it returns. */
static void client_sync(oc_client *c)
{
    proto_sea sea;
    double eff;
    assert_int_equal(oc_client_sea_state_fetch(c, FRAME_WAIT_MS, &sea, &eff), OCEAN_OK);
}

/* A viewer subscribed near the ships (layout 1, or 0 with world), its
 * camera at (x, 25, z). */
static oc_client *wake_viewer(double x, double z, int world)
{
    oc_client *v = connect_client(port, NULL);
    proto_subscribe sub;
    if (world) small_subscribe(&sub);
    else cascade_subscribe(&sub);
    assert_int_equal(oc_client_subscribe(v, &sub), OCEAN_OK);
    proto_camera cam;
    oc_camera_default(&cam);
    cam.pos[0] = x, cam.pos[1] = 25, cam.pos[2] = z;
    assert_int_equal(oc_client_send_camera(v, &cam, NULL), OCEAN_OK);
    return v;
}

/* Services v until its wakes at t can be read (the patterns came). */
static void wakes_read(oc_client *v, double t, const double *xz, int n, oc_wake *got)
{
    ocean_result r = OCEAN_ESTATE;
    for (double end = test_now_s() + 60; test_now_s() < end && r == OCEAN_ESTATE;) {
        oc_service(v, 50);
        oc_frame *f = NULL;
        while (oc_client_next_frame(v, 0, &f) == OCEAN_OK) oc_frame_free(f);
        r = oc_client_wakes(v, t, xz, (size_t)n, got);
    }
    assert_int_equal(r, OCEAN_OK);
}

/* A viewer (layout 1) near two ships gets their wake patterns (WAKE) and
 * places them along the tracks its ENTITY announces give: the C library's
 * wakes at points around the second ship, in the first's wake, are the
 * exact sum of the same waves (the daemon's series, summed here) within
 * the bound the library gives, and the patterns came once each. */
static void wakes_reach_viewers(void **state)
{
    (void)state;
    test_ws a;
    timeline ta;
    sea_connect(&a, &ta, 300);
    oc_client *v = wake_viewer(-150, -20, 0);
    double t0 = hub_now();
    double tq = entity_enter(&a, 41, 0, t0, 0, 8);
    tq = fmax(tq, entity_enter(&a, 42, 0, t0, -300, 8));
    enum { N = 7 };
    const double xz[2 * N] = {-240, -20, -360, -20, -300, -28, -300, -12, -100, -20, -150, -45, -200, 5};
    oc_wake got[N];
    client_sync(v);
    wakes_read(v, tq, xz, N, got);
    oc_client_stats st;
    oc_client_get_stats(v, &st);
    printf("the viewer: %llu WAKE patterns (%llu refused), %llu ENTITY entries refused\n",
           (unsigned long long)st.wakes_rx, (unsigned long long)st.wakes_refused,
           (unsigned long long)st.entity_refused);
    assert_true(st.wakes_rx >= 1 && st.wakes_rx <= 4 && st.wakes_refused == 0 && st.entity_refused == 0);
    /* the exact wakes of the same ships, patterns built here */
    double exact[N], biggest = 0;
    exact_wakes(&ta, tq, xz, N, exact, NULL);
    for (int i = 0; i < N; i++) {
        printf("(%g, %g): the viewer's wake %.5f m, exact %.5f m, bound %.5f m\n", xz[2 * i], xz[2 * i + 1],
               got[i].height, exact[i], got[i].error);
        assert_true(fabs(got[i].height - exact[i]) <= got[i].error + 1e-6);
        biggest = fmax(biggest, fabs(exact[i]));
    }
    assert_true(biggest > 0.05);
    oc_client_destroy(v);
    for (uint32_t id = 41; id <= 42; id++) {
        entity_leave(&a, id, "entity-token");
    }
    test_ws_close(&a);
}

/* A rotorcraft's downwash (sim/rotor_wash.h) in the answers and in the
 * readers: rotor 43 (16 m) entered hovering 30 m over (0, -20); QUERY at
 * the instant its entry takes effect answers the wind sea alone (the
 * water has not moved yet), 30 s later the sea plus the dent and, 100 m
 * out, the rings of its coming, 200 s later the sea plus the dent alone (its head, the
 * thrust over the footprint); a layout-1 viewer's library reads the same
 * downwash from the ENTITY entries alone (no WAKE needed). */
static void rotor_wash_everywhere(void **state)
{
    (void)state;
    test_ws a;
    timeline ta;
    sea_connect(&a, &ta, 300);
    oc_client *v = wake_viewer(0, -20, 0);
    double tq = entity_enter(&a, 43, 1, hub_now(), 0, 0);
    enum { N = 4 };
    const double xz[2 * N] = {0, -20, 6, -20, 0, 20, -120, -20};
    double head, c;
    rotor_wash_footprint(16, 30, 0, &head, &c);
    ocean_entities *mine;
    assert_int_equal(ocean_entities_create(8, OCEAN_ENTITY_HOLD_S, 256, &mine, NULL, 0), OCEAN_OK);
    ocean_entity_desc d = {.id = 43, .kind = OCEAN_ENTITY_ROTORCRAFT, .length_m = 16};
    ocean_track_sample smp = {.t = tq, .x = 0, .z = -20, .altitude_m = 30};
    assert_int_equal(ocean_entities_enter(mine, &d, &smp, tq, NULL, 0), OCEAN_OK);
    rotor_wash *rw;
    assert_int_equal(rotor_wash_create(&rw), OCEAN_OK);
    oc_client *q = connect_client(port, NULL);
    client_sync(v);
    static const double after[3] = {0, 30, 200};
    for (int k = 0; k < 3; k++) {
        double t = tq + after[k];
        oc_query_result qr;
        assert_int_equal(oc_client_query(q, xz, N, 1, t, 60000, &qr), OCEAN_OK);
        ocean_query_result lr[N];
        local_query(tl_at(&ta, t), t, xz, N, lr);
        wake_sample ws[N];
        memset(ws, 0, sizeof ws);
        assert_int_equal(rotor_wash_add(rw, mine, t, xz, N, ws), OCEAN_OK);
        oc_wake got[N];
        wakes_read(v, t, xz, N, got);
        for (int i = 0; i < N; i++) {
            double wash = qr.samples[i].height - lr[i].height;
            printf("t0 + %3.0f s (%g, %g): answer %.4f m = sea %.4f + downwash %.4f (here %.4f, the viewer %.4f)\n",
                   after[k], xz[2 * i], xz[2 * i + 1], qr.samples[i].height, lr[i].height, wash, ws[i].height,
                   got[i].height);
            assert_true(fabs(wash - ws[i].height) <= 1e-5 + 1e-6 * fabs(lr[i].height));
            assert_true(fabs(got[i].height - ws[i].height) <= 1e-9);
            if (k == 0) assert_true(ws[i].height == 0);
        }
        if (k == 1) assert_true(fabs(ws[3].height) > 1e-4);   /* its rings, 100 m out */
        if (k == 2) assert_true(fabs(ws[0].height + head) < 1e-12);                     /* the dent alone */
        oc_query_result_free(&qr);
    }
    printf("hovering 16 m rotor at 30 m: head %.4f m over a footprint of %.2f m\n", head, c);
    assert_true(head > 0.03);
    oc_client_destroy(q);
    oc_client_destroy(v);
    rotor_wash_destroy(rw);
    ocean_entities_destroy(mine);
    entity_leave(&a, 43, "entity-token");
    test_ws_close(&a);
}

/* A client joining late sees the same wakes as one that watched them form
 * (issue 43): ship 45 steams along +x with two samples, ship 46 is entered
 * and removed; a layout-1 viewer connected before every entry and a
 * layout-0 one connected after them (the patterns go to either layout)
 * read the same wakes, bit for bit, at an instant between the entries
 * (ship 45 on its first sample, 46 still in the sea) and now. */
static void wakes_for_late_joiners(void **state)
{
    (void)state;
    test_ws a;
    timeline ta;
    sea_connect(&a, &ta, 300);
    oc_client *watcher = wake_viewer(-150, -20, 0);
    double t0 = hub_now();
    double tm = fmax(entity_enter(&a, 45, 0, t0, 0, 8), entity_enter(&a, 46, 0, t0, -300, 8));
    while (hub_now() < tm + 0.5) usleep(20000); /* the later entries take effect after tm */
    tm += 0.25;
    double later = entity_enter(&a, 45, 0, t0 + 2, 16, 8);
    assert_true(later > tm && entity_leave(&a, 46, "entity-token") > tm);
    oc_client *late = wake_viewer(-150, -20, 1);
    client_sync(watcher); /* both hold every entry before they read */
    client_sync(late);
    enum { N = 6 };
    const double xz[2 * N] = {-240, -20, -360, -20, -300, -28, -100, -20, -150, -45, 60, -30};
    oc_wake w[N], l[N];
    double now = hub_now();
    for (int pass = 0; pass < 2; pass++) {
        double t = pass ? now : tm;
        wakes_read(watcher, t, xz, N, w);
        wakes_read(late, t, xz, N, l);
        double biggest = 0;
        for (int i = 0; i < N; i++) {
            printf("t %.3f (%g, %g): watched %.6f m, joined late %.6f m\n", t, xz[2 * i], xz[2 * i + 1], w[i].height,
                   l[i].height);
            biggest = fmax(biggest, fabs(w[i].height));
        }
        assert_memory_equal(w, l, sizeof w);
        assert_true(biggest > 0.02);
    }
    oc_client_stats st;
    oc_client_get_stats(late, &st);
    assert_true(st.entity_refused == 0 && st.wakes_refused == 0);
    oc_client_destroy(late);
    oc_client_destroy(watcher);
    entity_leave(&a, 45, "entity-token");
    test_ws_close(&a);
}

/* A recorded camera path replays the wakes it saw (issue 43): ship 47
 * turns through three samples while a live viewer watches; the instants
 * of its frames and its camera are the recording.  A client that connects
 * afterwards and replays them (replay mode: a FRAME for each CAMERA's
 * render_time) gets the patterns those instants need and reads, at each,
 * the wake bits the live viewer read. */
static void wakes_replay_as_watched(void **state)
{
    (void)state;
    test_ws a;
    timeline ta;
    sea_connect(&a, &ta, 300);
    oc_client *live = wake_viewer(-150, -20, 0);
    double t0 = hub_now();
    proto_msg m;
    entity_enter(&a, 47, 0, t0, 0, 8);
    enum { F = 4, N = 4 };
    const double xz[2 * N] = {-60, -20, -120, -40, -150, 10, 20, 30};
    double at[F];
    oc_wake w[F][N], r[F][N];
    for (int i = 0; i < F; i++) { /* a frame's instant about every 1.5 s, a sample every 3 s */
        if (i == 1 || i == 3) {
            proto_msg_init(&m, PROTO_ENTITY);
            proto_entity *e = &m.u.entity;
            double h = 15.0 * i, t = t0 + 1.5 * i, x = 8 * 1.5 * i;
            *e = (proto_entity){.op = PROTO_ENTITY_SET, .id = 47, .t = t, .x = x, .z = -20 + 0.5 * i * i,
                                .heading_deg = (float)h, .speed = 8, .length_m = 120, .beam_m = 15, .draught_m = 5,
                                .token = "entity-token"};
            test_msg_send(&a, &m);
            entity_expect(&a, PROTO_ENTITY_ANNOUNCE, 47, &m);
            proto_msg_free(&m);
        }
        client_sync(live);
        oc_frame *f = NULL;
        double want = hub_now() + 0.3;
        do {
            oc_frame_free(f);
            f = next_frame(live);
        } while (f->hdr.sim_time < want);
        at[i] = f->hdr.sim_time;
        oc_frame_free(f);
        wakes_read(live, at[i], xz, N, w[i]);
        while (hub_now() < t0 + 1.5 * (i + 1)) usleep(20000);
    }
    oc_client *rep = connect_client(port, NULL);
    proto_subscribe sub;
    cascade_subscribe(&sub);
    sub.mode = PROTO_MODE_REPLAY;
    assert_int_equal(oc_client_subscribe(rep, &sub), OCEAN_OK);
    client_sync(rep);
    proto_camera cam;
    oc_camera_default(&cam);
    cam.pos[0] = -150, cam.pos[1] = 25, cam.pos[2] = -20;
    for (int i = 0; i < F; i++) {
        cam.render_time = at[i];
        assert_int_equal(oc_client_send_camera(rep, &cam, NULL), OCEAN_OK);
        oc_frame *f = next_frame(rep);
        assert_true(f->hdr.sim_time == at[i]);
        oc_frame_free(f);
        wakes_read(rep, at[i], xz, N, r[i]);
        printf("t %.3f: watched %.6f %.6f %.6f %.6f m, replayed %.6f %.6f %.6f %.6f m\n", at[i], w[i][0].height,
               w[i][1].height, w[i][2].height, w[i][3].height, r[i][0].height, r[i][1].height, r[i][2].height,
               r[i][3].height);
    }
    assert_memory_equal(w, r, sizeof w);
    assert_true(fabs(w[0][0].height) > 0.01 && fabs(w[F - 1][0].height - w[0][0].height) > 1e-4);
    oc_client_destroy(rep);
    oc_client_destroy(live);
    entity_leave(&a, 47, "entity-token");
    test_ws_close(&a);
}

/* Sends an ENTITY set of ship id at (x, z) heading h to w with token tok,
 * and waits for its announce; returns the instant it takes effect. */
static double ship_sample(test_ws *w, uint32_t id, double t, double x, double z, double h, const char *tok)
{
    proto_msg m;
    proto_msg_init(&m, PROTO_ENTITY);
    m.u.entity = (proto_entity){.op = PROTO_ENTITY_SET, .id = id, .t = t, .x = x, .z = z, .heading_deg = (float)h,
                                .speed = 8, .length_m = 120, .beam_m = 15, .draught_m = 5};
    snprintf(m.u.entity.token, sizeof m.u.entity.token, "%s", tok);
    test_msg_send(w, &m);
    entity_expect(w, PROTO_ENTITY_ANNOUNCE, id, &m);
    double from = m.hdr.sim_time;
    proto_msg_free(&m);
    return from;
}

/* The QUERY answers of daemon d at the n points and each instant of at. */
static void log_queries(srv_daemon *d, const double *at, int k, const double *xz, int n, proto_query_sample *out)
{
    oc_client *q = connect_client(srv_daemon_port(d), NULL);
    for (int i = 0; i < k; i++) {
        oc_query_result qr;
        assert_int_equal(oc_client_query(q, xz, (size_t)n, 1, at[i], 60000, &qr), OCEAN_OK);
        assert_true(qr.count == (uint32_t)n && qr.t == at[i]);
        memcpy(out + (size_t)i * n, qr.samples, sizeof *out * (size_t)n);
        oc_query_result_free(&qr);
    }
    oc_client_destroy(q);
}

/* The entities' timeline on disk (server.entity_log, issue 43: recordings
 * keep the entities, replays reproduce them): a daemon appends each entry
 * it enters; a daemon started later on the log answers every instant of
 * the first one's timeline with the same QUERY bytes (wind sea and the
 * ships' wakes) - a turning ship, one removed - though the first is gone.
 * A record cut short at the end is cut off, and a file that is no log is
 * refused with its name. */
static void entity_log_replays_the_wakes(void **state)
{
    (void)state;
    char path[128];
    snprintf(path, sizeof path, "/tmp/oceand-entlog-%d.bin", (int)getpid());
    unlink(path);
    char log_set[200];
    snprintf(log_set, sizeof log_set, "server.entity_log=\"%s\"", path);
    const char *sets[] = {"server.port=0", "server.scene=\"\"", "ocean.n=32", "ocean.cascades=1", "ocean.threads=1",
                          "server.entity_token=\"tok\"", log_set};
    srv_settings sb;
    srv_daemon *a = start_daemon(sets, 7, &sb);
    test_ws w;
    assert_int_equal(test_ws_connect(&w, srv_daemon_port(a), "/", PROTO_SUBPROTOCOL), 0);
    proto_msg m;
    assert_true(test_msg_wait(&w, PROTO_HELLO, 5000, &m));
    proto_msg_free(&m);
    double t0 = srv_hub_sim_time(srv_daemon_hub(a));
    enum { K = 3, N = 4 };
    double at[K];
    ship_sample(&w, 61, t0, 0, 0, 0, "tok");
    at[0] = ship_sample(&w, 62, t0, -300, 40, 0, "tok") + 0.25;
    while (srv_hub_sim_time(srv_daemon_hub(a)) < at[0] + 0.5) usleep(20000);
    at[1] = ship_sample(&w, 61, t0 + 2, 16, 1, 10, "tok") + 0.25;
    entity_leave(&w, 62, "tok");
    while (srv_hub_sim_time(srv_daemon_hub(a)) < at[1] + 0.5) usleep(20000);
    at[2] = ship_sample(&w, 61, t0 + 4, 32, 4, 20, "tok") + 0.25;
    test_ws_close(&w);
    const double xz[2 * N] = {-150, 0, -200, 30, -330, 40, 60, 10};
    proto_query_sample qa[K * N], qb[K * N];
    log_queries(a, at, K, xz, N, qa);
    srv_daemon_stop(a);
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    off_t whole = st.st_size;
    /* a record cut short (the daemon stopped while writing it) */
    FILE *f = fopen(path, "ab");
    assert_non_null(f);
    fputs("\x30\x00", f);
    fclose(f);
    srv_daemon *b = start_daemon(sets, 7, &sb);
    assert_int_equal(srv_entities_kept(srv_daemon_hub(b)->entities), 2);
    log_queries(b, at, K, xz, N, qb);
    for (int i = 0; i < K * N; i++)
        printf("t %.3f (%g, %g): first daemon %.6f m, restarted on its log %.6f m\n", at[i / N], xz[2 * (i % N)],
               xz[2 * (i % N) + 1], qa[i].height, qb[i].height);
    assert_memory_equal(qa, qb, sizeof qa);
    srv_daemon_stop(b);
    assert_int_equal(stat(path, &st), 0);
    assert_true(st.st_size == whole); /* the cut record is gone; the entries read were not written again */
    /* a file that is no log: refused, named */
    f = fopen(path, "wb");
    assert_non_null(f);
    fputs("not a log\n", f);
    fclose(f);
    load_settings(sets, 7, &sb);
    char err[512] = "";
    srv_daemon *c = NULL;
    assert_int_equal(srv_daemon_start(&sb, &c, err, sizeof err), OCEAN_EIO);
    assert_null(c);
    if (!strstr(err, path) || !strstr(err, "not an entity log")) fail_msg("%s", err);
    unlink(path);
}

/* What on_entity saw of entity id (a joiner also gets earlier tests'
 * entries: the timeline the daemon keeps). */
typedef struct entity_seen {
    uint32_t id;
    int announces, gones;
    proto_entity last;
} entity_seen;

static void on_entity_cb(void *user, oc_client *c, const proto_entity *e)
{
    (void)c;
    entity_seen *seen = user;
    if (e->id != seen->id) return;
    if (e->op == PROTO_ENTITY_ANNOUNCE) seen->announces++;
    if (e->op == PROTO_ENTITY_GONE) seen->gones++;
    seen->last = *e;
}

/* The C library's oc_client_send_entity: a set comes back to on_entity as
 * the announce, a remove as gone; a NaN is refused before it is sent. */
static void entity_from_the_library(void **state)
{
    (void)state;
    entity_seen seen = {.id = 21};
    oc_callbacks cb = {.user = &seen, .on_entity = on_entity_cb};
    oc_client *c = connect_client(port, &cb);
    proto_entity e = {PROTO_ENTITY_SET, 1, 21, hub_now(), 400, -300, 60, 90, 20, 16, 0, 0, "entity-token"};
    assert_int_equal(oc_client_send_entity(c, &e), OCEAN_OK);
    for (double end = test_now_s() + 5; !seen.announces && test_now_s() < end;) oc_service(c, 100);
    assert_int_equal(seen.announces, 1);
    assert_true(seen.last.id == 21 && seen.last.kind == 1 && seen.last.x == 400 && seen.last.altitude_m == 60.0f);
    proto_entity bad = e;
    bad.z = NAN;
    assert_int_equal(oc_client_send_entity(c, &bad), OCEAN_EINVAL);
    char why[300];
    oc_client_last_error(c, why, sizeof why);
    if (!strstr(why, "entity.z")) fail_msg("%s", why);
    proto_entity rm = {.op = PROTO_ENTITY_REMOVE, .id = 21, .token = "entity-token"};
    assert_int_equal(oc_client_send_entity(c, &rm), OCEAN_OK);
    for (double end = test_now_s() + 5; !seen.gones && test_now_s() < end;) oc_service(c, 100);
    assert_int_equal(seen.gones, 1);
    entity_at(21, NAN);
    oc_client_destroy(c);
}

/* ENTITY sets beyond SRV_ENTITY_SET_BURST, then SRV_ENTITY_SET_PER_S a
 * second, from one connection are refused ERATE (answered once a second),
 * the rest entered: a daemon whose message rate lets them through. */
static void entity_rate(void **state)
{
    (void)state;
    const char *sets[] = {"server.port=0", "server.scene=\"\"", "ocean.n=32", "ocean.cascades=1", "ocean.threads=1",
                          "server.entity_token=\"tok\"", "server.msg_rate=10000", "server.msg_burst=20000"};
    srv_settings sb;
    srv_daemon *d = start_daemon(sets, 8, &sb);
    test_ws w;
    assert_int_equal(test_ws_connect(&w, srv_daemon_port(d), "/", PROTO_SUBPROTOCOL), 0);
    proto_msg m;
    assert_true(test_msg_wait(&w, PROTO_HELLO, 5000, &m));
    proto_msg_free(&m);
    double t0 = srv_hub_sim_time(srv_daemon_hub(d)), start = test_now_s();
    int sent = 600;
    for (int i = 0; i < sent; i++) entity_send(&w, PROTO_ENTITY_SET, 3, 0, t0 + 0.01 * i, 50, 0, "tok");
    int announced = 0, refused = 0;
    double last = start;
    for (;;) { /* until 1 s passes with nothing */
        uint8_t *b;
        size_t len;
        if (test_ws_recv(&w, 1000, &b, &len) != 2) break;
        char err[256];
        last = test_now_s();
        if (proto_decode(b, len, &m, err, sizeof err) == OCEAN_OK) {
            if (m.hdr.type == PROTO_ENTITY) announced++;
            if (m.hdr.type == PROTO_ERROR && m.u.error.code == OCEAN_ERATE) refused++;
            proto_msg_free(&m);
        }
        free(b);
    }
    /* the daemon took them within `elapsed` (its last reply): the bucket
     * held the burst and refilled at its rate meanwhile */
    double elapsed = last - start;
    int most = (int)(SRV_ENTITY_SET_BURST + SRV_ENTITY_SET_PER_S * elapsed) + 1;
    printf("# %d sets answered within %.3f s: %d announced (at most %d), %d ERATE replies\n", sent, elapsed,
           announced, most, refused);
    assert_true(announced >= (int)SRV_ENTITY_SET_BURST && announced <= most);
    assert_true(refused >= 1 && refused <= 2 + (int)elapsed);
    test_ws_close(&w);
    srv_daemon_stop(d);
}

/* server.epoch: ISO 8601 and Unix seconds give the instant the published
 * calendar gives (2026-01-01T00:00:00Z = 1 767 225 600 s, POSIX time). */
static void epoch_parse(void **state)
{
    (void)state;
    double e;
    assert_int_equal(srv_epoch_parse("2026-01-01T00:00:00Z", &e, NULL, 0), OCEAN_OK);
    assert_true(e == 1767225600.0);
    assert_int_equal(srv_epoch_parse("2026-01-01T01:30:00+01:30", &e, NULL, 0), OCEAN_OK);
    assert_true(e == 1767225600.0);
    assert_int_equal(srv_epoch_parse("2025-12-31 23:59:59.5Z", &e, NULL, 0), OCEAN_OK);
    assert_true(e == 1767225599.5);
    assert_int_equal(srv_epoch_parse("1970-01-01T00:00:00Z", &e, NULL, 0), OCEAN_OK);
    assert_true(e == 0);
    assert_int_equal(srv_epoch_parse("2000-02-29T00:00:00Z", &e, NULL, 0), OCEAN_OK);
    assert_true(e == 951782400.0);
    assert_int_equal(srv_epoch_parse("1767225600.25", &e, NULL, 0), OCEAN_OK);
    assert_true(e == 1767225600.25);
    const char *bad[] = {"2026-01-01T00:00:00", "2026-13-01T00:00:00Z", "2025-02-29T00:00:00Z",
                         "yesterday", "-5", "2026-01-01T00:00:00Zjunk", "1e400", "nan"};
    char why[200];
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        assert_int_equal(srv_epoch_parse(bad[i], &e, why, sizeof why), OCEAN_EINVAL);
        assert_non_null(strstr(why, "server.epoch"));
    }
    /* in a file, a bad epoch is refused at its file:line, like any bad value
     * (it was refused with the file's name alone, after the load) */
    char path[] = "/tmp/oc-epoch-XXXXXX";
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    const char *text = "# a config\nserver.port = 0\nserver.scene = \"\"\nserver.epoch = 2020-02-30T00:00:00Z\n";
    assert_int_equal(write(fd, text, strlen(text)), (ssize_t)strlen(text));
    close(fd);
    srv_settings st;
    char err[600];
    assert_int_equal(srv_settings_load(path, NULL, 0, &st, err, sizeof err), OCEAN_EINVAL);
    char at[64];
    snprintf(at, sizeof at, "%s:4: server.epoch", path);
    if (!strstr(err, at)) fail_msg("a bad epoch's error does not name %s: '%s'", at, err);
    unlink(path);
}

/* The admin guard (srv_admin.h) counts wrong tokens in a sliding window.
 * One miss at t = 0, 19 at t = 9.5 s, then 20 at t = 10.1 s: a fixed window
 * (started by the first miss, restarted at 10.1) saw 20 and 20 and never
 * locked, letting 39 guesses through in 0.6 s; the 21st within 10 s locks.
 * Misses spread thinner than 21 in 10 s never lock.  The alarm locks the
 * addresses that guessed, never another (the admin's); an address's own
 * backoff doubles per miss and a right token resets it. */
static void admin_lock_sliding_window(void **state)
{
    (void)state;
    srv_admin *a = calloc(1, sizeof *a);
    assert_non_null(a);
    int locked = srv_admin_window_miss(a, 1000.0);
    for (int i = 0; i < 19; i++) locked |= srv_admin_window_miss(a, 1009.5 + i * 0.01);
    assert_false(locked); /* 20 misses */
    int at = -1;
    for (int i = 0; i < 20 && at < 0; i++)
        if (srv_admin_window_miss(a, 1010.1 + i * 0.01)) at = i;
    assert_int_equal(at, 1); /* 1010.11: 19 + 2 within the last 10 s */
    /* one miss every 0.51 s: at most 20 in any 10 s */
    memset(a, 0, sizeof *a);
    for (int i = 0; i < 200; i++) assert_false(srv_admin_window_miss(a, 2000.0 + 0.51 * i));
    /* the alarm locks the addresses that guessed, not the others: 21
     * guesses from 10.0.0.1 in 2 s, then an attempt from each address */
    memset(a, 0, sizeof *a);
    int alarm = 0;
    for (int i = 0; i < 21; i++) srv_admin_miss(a, "10.0.0.1", 0.3, 3000.0 + 0.1 * i, &alarm);
    assert_true(alarm);
    assert_true(srv_admin_locked_until(a, "10.0.0.1", 3002.5) >= 3012.0);
    assert_true(srv_admin_locked_until(a, "10.0.0.2", 3002.5) <= 3002.5);
    /* its own backoff doubles per miss (to 64 x the lockout) and a hit resets the count */
    memset(a, 0, sizeof *a);
    srv_admin_miss(a, "10.0.0.3", 0.3, 4000.0, &alarm);
    assert_true(fabs(srv_admin_locked_until(a, "10.0.0.3", 4000.0) - 4000.3) < 1e-9);
    srv_admin_miss(a, "10.0.0.3", 0.3, 4001.0, &alarm);
    assert_true(fabs(srv_admin_locked_until(a, "10.0.0.3", 4001.0) - 4001.6) < 1e-9);
    srv_admin_hit(a, "10.0.0.3");
    srv_admin_miss(a, "10.0.0.3", 0.3, 4002.0, &alarm);
    assert_true(fabs(srv_admin_locked_until(a, "10.0.0.3", 4002.0) - 4002.3) < 1e-9);
    free(a);
}

/* An epoch that puts the sim time beyond the exact-time limit is refused
 * at start, naming the limit (the daemon would serve no frames). */
static void epoch_beyond_time_limit(void **state)
{
    (void)state;
    const char *sets[] = {"server.epoch=1970-01-01T00:00:00Z"};
    srv_settings s1;
    char err[512] = "";
    assert_int_equal(srv_settings_load(conf_path, sets, 1, &s1, err, sizeof err), OCEAN_EINVAL);
    assert_non_null(strstr(err, "OCEAN_TIME_MAX"));
    assert_non_null(strstr(err, "server.epoch"));
    /* a year ago is fine */
    char near[64];
    snprintf(near, sizeof near, "server.epoch=%lld", (long long)time(NULL) - 31536000LL);
    const char *ok[] = {near};
    assert_int_equal(srv_settings_load(conf_path, ok, 1, &s1, err, sizeof err), OCEAN_OK);
}

/* A near-field wavelength the exact-time limit cannot serve is refused by
 * the key's range, before anything is built (was: accepted, then refused at
 * start by the near field's OCEAN_OMEGA_MAX check). */
static void near_field_wavelength_range(void **state)
{
    (void)state;
    srv_settings s1;
    char err[512] = "";
    const char *bad[] = {"server.near_field_min_wavelength=0.01"};
    assert_int_equal(srv_settings_load(conf_path, bad, 1, &s1, err, sizeof err), OCEAN_EINVAL);
    assert_non_null(strstr(err, "server.near_field_min_wavelength"));
    assert_non_null(strstr(err, "0.0151"));
    const char *ok[] = {"server.near_field_min_wavelength=0.0151"};
    assert_int_equal(srv_settings_load(conf_path, ok, 1, &s1, err, sizeof err), OCEAN_OK);
}

/* Two daemons started apart with the same epoch agree on the sim time and
 * the tick of every instant; the tick of a frame is the one the system
 * clock gives at its sim time. */
static void epoch_shared_clock(void **state)
{
    (void)state;
    /* a whole day about a month ago: any epoch within the exact-time limit */
    char ep[64];
    const double epoch_s = (double)(((long long)time(NULL) / 86400 - 30) * 86400);
    snprintf(ep, sizeof ep, "server.epoch=%.0f", epoch_s);
    const char *sets[] = {ep};
    srv_settings s1, s2;
    char err[512];
    assert_int_equal(srv_settings_load(conf_path, sets, 1, &s1, err, sizeof err), OCEAN_OK);
    s2 = s1;
    srv_daemon *d1, *d2;
    assert_int_equal(srv_daemon_start(&s1, &d1, err, sizeof err), OCEAN_OK);
    usleep(123456); /* not a whole number of ticks */
    assert_int_equal(srv_daemon_start(&s2, &d2, err, sizeof err), OCEAN_OK);
    struct timespec rt;
    clock_gettime(CLOCK_REALTIME, &rt);
    double unix_now = (double)rt.tv_sec + 1e-9 * rt.tv_nsec;
    double a = srv_hub_sim_time_at(srv_daemon_hub(d1), unix_now);
    double b = srv_hub_sim_time_at(srv_daemon_hub(d2), unix_now);
    assert_true(a == b);
    assert_true(fabs(a - (unix_now - epoch_s)) < 1e-6);
    /* the frames: same tick -> same sim time on both; tick = floor(t * rate) */
    oc_client *c[2] = {connect_client(srv_daemon_port(d1), NULL), connect_client(srv_daemon_port(d2), NULL)};
    /* both announce the same determinism fingerprint; another grid would not */
    proto_hello h1, h2;
    assert_int_equal(oc_client_hello(c[0], &h1), OCEAN_OK);
    assert_int_equal(oc_client_hello(c[1], &h2), OCEAN_OK);
    assert_string_equal(h1.server_version, h2.server_version);
    char fp[17], fp2[17];
    srv_fingerprint(&s1, fp);
    assert_non_null(strstr(h1.server_version, fp));
    assert_non_null(strstr(h1.server_version, " fp="));
    srv_settings s3 = s1;
    s3.params.n *= 2;
    srv_fingerprint(&s3, fp2);
    assert_string_not_equal(fp, fp2);
    s3 = s1;
    s3.params.plan_measure = !s3.params.plan_measure;
    srv_fingerprint(&s3, fp2);
    assert_string_not_equal(fp, fp2);
    uint32_t ticks[2][40];
    double times[2][40];
    int nt[2] = {0, 0};
    for (int k = 0; k < 2; k++) {
        proto_subscribe sub;
        small_subscribe(&sub);
        sub.mesh_kind = PROTO_MESH_NONE;
        sub.frame_rate_hz = 30;
        assert_int_equal(oc_client_subscribe(c[k], &sub), OCEAN_OK);
    }
    double end = test_now_s() + (sanitized ? 6 : 3);
    while (test_now_s() < end && (nt[0] < 40 || nt[1] < 40)) {
        for (int k = 0; k < 2; k++) {
            oc_frame *f;
            if (nt[k] < 40 && oc_client_next_frame(c[k], 20, &f) == OCEAN_OK) {
                ticks[k][nt[k]] = f->info.tick;
                times[k][nt[k]] = f->hdr.sim_time;
                clock_gettime(CLOCK_REALTIME, &rt);
                double recv_t = (double)rt.tv_sec + 1e-9 * rt.tv_nsec - epoch_s;
                /* shown no later than received, and not long before */
                assert_true(f->hdr.sim_time <= recv_t + 1e-3);
                assert_true(f->hdr.sim_time > recv_t - 2.0);
                assert_true(ticks[k][nt[k]] == (uint32_t)(int64_t)floor(times[k][nt[k]] * 30 + 1e-6));
                nt[k]++;
                oc_frame_free(f);
            }
        }
    }
    int common = 0;
    for (int i = 0; i < nt[0]; i++)
        for (int j = 0; j < nt[1]; j++)
            if (ticks[0][i] == ticks[1][j]) {
                assert_true(times[0][i] == times[1][j]);
                common++;
            }
    assert_true(common >= 5);
    oc_client_destroy(c[0]);
    oc_client_destroy(c[1]);
    srv_daemon_stop(d1);
    srv_daemon_stop(d2);
}

/* ---- the server as PROTOCOL.md states it (issue 16 deviations) ----------------- */

static void raw_query(test_ws *w, uint32_t id, uint32_t n)
{
    double *pts = calloc(2 * (size_t)n, sizeof *pts);
    for (uint32_t i = 0; i < n; i++) pts[2 * i] = i;
    proto_msg q;
    proto_msg_init(&q, PROTO_QUERY);
    q.u.query.query_id = id;
    q.u.query.count = n;
    q.u.query.points = pts;
    test_msg_send(w, &q);
    free(pts);
}

/* Waits for the first FRAME and returns its tile count (-1: none came). */
static int raw_frame_tiles(test_ws *w, int ms)
{
    proto_msg m;
    if (!test_msg_wait(w, PROTO_FRAME, ms, &m)) return -1;
    int n = m.u.frame.tile_count;
    proto_msg_free(&m);
    return n;
}

/* A live SUBSCRIBE drops the replay backlog, not the QUERYs still waiting
 * for the next tick: three QUERYs then a SUBSCRIBE, sent together, get
 * three QUERY_RESULTs in order (they got none, and no ERROR). */
static void subscribe_keeps_pending_queries(void **state)
{
    (void)state;
    for (int round = 0; round < 3; round++) {
        test_ws w;
        assert_int_equal(test_ws_connect(&w, port, "/", PROTO_SUBPROTOCOL), 0);
        proto_msg m;
        assert_true(test_msg_wait(&w, PROTO_HELLO, 3000, &m));
        proto_msg_free(&m);
        for (uint32_t id = 1; id <= 3; id++) raw_query(&w, id, 1);
        proto_msg sm;
        proto_msg_init(&sm, PROTO_SUBSCRIBE);
        small_subscribe(&sm.u.subscribe);
        sm.u.subscribe.mode = PROTO_MODE_LIVE;
        sm.u.subscribe.frame_rate_hz = 1;
        test_msg_send(&w, &sm);
        for (uint32_t id = 1; id <= 3; id++) {
            if (!test_msg_wait(&w, PROTO_QUERY_RESULT, 3000, &m))
                fail_msg("round %d: QUERY %u sent before a SUBSCRIBE was never answered", round, id);
            assert_int_equal(m.u.result.query_id, id);
            proto_msg_free(&m);
        }
        test_ws_close(&w);
    }
}

/* A SUBSCRIBE that a turn between ticks sees (a QUERY sent with it is
 * answered at once, not at the next tick) is applied at the next tick: on
 * a 2 Hz daemon, each layout's stream subscribed without a mesh, then
 * re-subscribed with one together with a QUERY, gets frames with a mesh.
 * It got none, and no ERROR, when the query's turn took the subscription
 * without applying it (the browser viewer queries as soon as it has
 * subscribed; on a busy host its layout-0 page drew nothing). */
static void subscribe_between_ticks_is_applied(void **state)
{
    (void)state;
    const char *sets[] = {"server.port=0", "server.tick_rate=2", "ocean.threads=1", "server.workers=2"};
    srv_settings sb;
    srv_daemon *d = start_daemon(sets, 4, &sb);
    for (int layout = PROTO_LAYOUT_WORLD; layout <= PROTO_LAYOUT_CASCADE; layout++) {
        test_ws w;
        assert_int_equal(test_ws_connect(&w, srv_daemon_port(d), "/", PROTO_SUBPROTOCOL), 0);
        proto_msg m, sm;
        assert_true(test_msg_wait(&w, PROTO_HELLO, FRAME_WAIT_MS, &m));
        proto_msg_free(&m);
        proto_msg_init(&sm, PROTO_SUBSCRIBE);
        if (layout == PROTO_LAYOUT_WORLD) small_subscribe(&sm.u.subscribe);
        else oc_subscribe_default(&sm.u.subscribe);
        sm.u.subscribe.frame_rate_hz = 2;
        sm.u.subscribe.mesh_kind = PROTO_MESH_NONE;
        test_msg_send(&w, &sm);
        assert_true(test_msg_wait(&w, PROTO_FRAME, FRAME_WAIT_MS, &m));
        assert_int_equal(m.u.frame.has_mesh, 0);
        proto_msg_free(&m);
        /* just after a tick: the next is 0.5 s away, the query's turn comes first */
        sm.u.subscribe.mesh_kind = PROTO_MESH_CONCENTRIC;
        test_msg_send(&w, &sm);
        raw_query(&w, 1, 1);
        assert_true(test_msg_wait(&w, PROTO_QUERY_RESULT, FRAME_WAIT_MS, &m));
        proto_msg_free(&m);
        int frames = 0, meshed = 0;
        for (double end = test_now_s() + FRAME_WAIT_MS / 1e3; !meshed && test_now_s() < end; frames++) {
            if (!test_msg_wait(&w, PROTO_FRAME, FRAME_WAIT_MS, &m)) break;
            assert_int_equal(m.u.frame.layout, layout);
            meshed = m.u.frame.has_mesh != 0;
            proto_msg_free(&m);
        }
        if (!meshed)
            fail_msg("layout %d: %d frames after a SUBSCRIBE with a mesh, none carries one", layout, frames);
        print_message("layout %d: the re-subscription's mesh came with frame %d after the query\n", layout, frames);
        test_ws_close(&w);
    }
    srv_daemon_stop(d);
}

/* HELLO's limits are ones the server honours: a QUERY of max_query_points
 * fits max_message (32 + 24 + 16 N bytes) and is answered, one more point is
 * ETOOBIG; max_frame_rate_hz is not above tick_rate_hz and a faster
 * SUBSCRIBE is refused, not served slower in silence; a client ERROR is not
 * answered; SUBSCRIBE accuracy at its lower bound (f32 of 1e-6) gives tiles. */
static void hello_limits_are_honoured(void **state)
{
    (void)state;
    test_ws w;
    assert_int_equal(test_ws_connect(&w, port, "/", PROTO_SUBPROTOCOL), 0);
    proto_msg m;
    assert_true(test_msg_wait(&w, PROTO_HELLO, 3000, &m));
    proto_hello h = m.u.hello;
    proto_msg_free(&m);
    uint32_t fit = (h.max_message - 32 - 24) / 16;
    assert_true(h.max_query_points <= fit);
    assert_true(h.max_query_points == fit); /* the test config: 64 KiB messages, 65 536 points */
    raw_query(&w, 7, h.max_query_points);
    assert_true(test_msg_wait(&w, PROTO_QUERY_RESULT, 5000, &m));
    assert_int_equal(m.u.result.query_id, 7);
    assert_int_equal(m.u.result.count, h.max_query_points);
    proto_msg_free(&m);
    raw_query(&w, 8, h.max_query_points + 1);
    assert_true(test_msg_wait(&w, PROTO_ERROR, 3000, &m));
    assert_int_equal(m.u.error.code, OCEAN_ETOOBIG);
    proto_msg_free(&m);

    /* frame rate: at most the tick rate */
    assert_true(h.max_frame_rate_hz <= h.tick_rate_hz);
    proto_msg sm;
    proto_msg_init(&sm, PROTO_SUBSCRIBE);
    small_subscribe(&sm.u.subscribe);
    sm.u.subscribe.mesh_kind = PROTO_MESH_NONE;
    sm.u.subscribe.tile_size = 16;
    sm.u.subscribe.lod_levels = 1;
    sm.u.subscribe.frame_rate_hz = 2 * h.tick_rate_hz;
    test_msg_send(&w, &sm);
    assert_true(test_msg_wait(&w, PROTO_ERROR, 3000, &m));
    assert_int_equal(m.u.error.code, OCEAN_EINVAL);
    assert_non_null(strstr(m.u.error.message, "tick"));
    proto_msg_free(&m);

    /* accuracy at the spec's lower bound: tiles in every frame, both layouts */
    sm.u.subscribe.frame_rate_hz = h.max_frame_rate_hz;
    sm.u.subscribe.accuracy = (float)1e-6;
    assert_true((double)sm.u.subscribe.accuracy < 1e-6); /* f32 rounds below the bound */
    test_msg_send(&w, &sm);
    assert_true(raw_frame_tiles(&w, 5000) > 0);
    assert_true(raw_frame_tiles(&w, 5000) > 0);
    proto_msg cs;
    proto_msg_init(&cs, PROTO_SUBSCRIBE);
    cascade_subscribe(&cs.u.subscribe);
    cs.u.subscribe.accuracy = (float)1e-6;
    test_msg_send(&w, &cs);
    int tiles = 0;
    for (int i = 0; i < 5; i++) {
        proto_msg f;
        assert_true(test_msg_wait(&w, PROTO_FRAME, 5000, &f));
        if (f.u.frame.layout == PROTO_LAYOUT_CASCADE) tiles = f.u.frame.tile_count;
        proto_msg_free(&f);
    }
    assert_true(tiles > 0);

    /* a client ERROR: no reply, the connection stays */
    proto_msg em;
    proto_msg_init(&em, PROTO_ERROR);
    em.u.error.code = OCEAN_ECODEC;
    em.u.error.offending_type = PROTO_FRAME;
    snprintf(em.u.error.message, sizeof em.u.error.message, "cannot decode that tile");
    test_msg_send(&w, &em);
    assert_false(test_msg_wait(&w, PROTO_ERROR, 600, &m));
    raw_query(&w, 9, 2);
    assert_true(test_msg_wait(&w, PROTO_QUERY_RESULT, 5000, &m));
    assert_int_equal(m.u.result.query_id, 9);
    proto_msg_free(&m);
    test_ws_close(&w);

    /* an upgrade without the subprotocol is refused at the handshake (HTTP
     * 400, test_attacks checks the status), not left in silence; any path
     * serves ocean.v1 */
    test_ws x;
    assert_int_not_equal(test_ws_connect(&x, port, "/", NULL), 0);
    assert_int_equal(test_ws_connect(&x, port, "/any/path?x=1", PROTO_SUBPROTOCOL), 0);
    assert_true(test_msg_wait(&x, PROTO_HELLO, 3000, &m));
    proto_msg_free(&m);
    test_ws_close(&x);
}

/* /metrics and /status answer over plain HTTP. */
static char *http_get(int p, const char *path)
{
    char *out = NULL;
    FILE *pf;
    char cmd[256];
    snprintf(cmd, sizeof cmd,
             "exec 3<>/dev/tcp/127.0.0.1/%d; printf 'GET %s HTTP/1.0\\r\\nHost: x\\r\\n\\r\\n' >&3; cat <&3",
             p, path);
    char full[300];
    snprintf(full, sizeof full, "bash -c \"%s\"", cmd);
    pf = popen(full, "r");
    if (!pf) return NULL;
    size_t cap = 65536, n = 0;
    out = malloc(cap);
    size_t r;
    while ((r = fread(out + n, 1, cap - n - 1, pf)) > 0) n += r;
    out[n] = 0;
    pclose(pf);
    return out;
}

static void http_metrics_and_status(void **state)
{
    (void)state;
    /* a tick of its own (the daemon sleeps with nobody subscribed): alone,
     * the test had none and "ticks" was 0 */
    oc_client *c = connect_client(port, NULL);
    proto_subscribe sub;
    small_subscribe(&sub);
    assert_int_equal(oc_client_subscribe(c, &sub), OCEAN_OK);
    proto_camera cam;
    oc_camera_default(&cam);
    assert_int_equal(oc_client_send_camera(c, &cam, NULL), OCEAN_OK);
    oc_frame_free(next_frame(c));
    oc_client_destroy(c);
    char *m = http_get(port, "/metrics");
    assert_non_null(m);
    assert_non_null(strstr(m, "200 OK"));
    assert_non_null(strstr(m, "oceand_clients "));
    assert_non_null(strstr(m, "oceand_transforms_total{channel=\"height\"}"));
    assert_non_null(strstr(m, "oceand_tile_cache_hits_total"));
    free(m);
    char *s = http_get(port, "/status");
    assert_non_null(s);
    char *body = strstr(s, "\r\n\r\n");
    assert_non_null(body);
    cJSON *j = cJSON_Parse(body + 4);
    assert_non_null(j);
    assert_true(cJSON_IsNumber(cJSON_GetObjectItem(j, "clients")));
    assert_true(cJSON_GetObjectItem(j, "ticks")->valuedouble > 0);
    cJSON_Delete(j);
    free(s);
}

/* The first message within ms: its type (PROTO_BYE's fields in *bye), 0
 * for nothing, -1 for the connection closed without a message. */
static int raw_first_type(test_ws *w, int ms, proto_bye *bye)
{
    uint8_t *b;
    size_t n;
    int op = test_ws_recv(w, ms, &b, &n);
    if (op == 0) return 0;
    if (op < 0) return -1;
    proto_msg m;
    char err[256];
    int type = op == 8 ? -1 : proto_decode(b, n, &m, err, sizeof err) == OCEAN_OK ? (int)m.hdr.type : -2;
    free(b);
    if (type == PROTO_BYE) *bye = m.u.bye;
    if (type > 0) proto_msg_free(&m);
    return type;
}

/* The close frame's reason within ms into why ("" when none came). */
static void raw_close_reason(test_ws *w, int ms, char *why, size_t n)
{
    why[0] = 0;
    double end = test_now_s() + ms / 1000.0;
    while (test_now_s() < end) {
        uint8_t *b;
        size_t len;
        int op = test_ws_recv(w, (int)((end - test_now_s()) * 1000) + 1, &b, &len);
        if (op <= 0) return;
        if (op == 8) {
            snprintf(why, n, "%.*s", len > 2 ? (int)(len - 2) : 0, len > 2 ? (const char *)b + 2 : "");
            free(b);
            return;
        }
        free(b);
    }
}

/* Past the exact-time limit (the clock at OCEAN_TIME_MAX after
 * server.epoch) nothing encodes, and connections hung in silence: a new
 * one got no HELLO, no BYE, no close; a connected one's frames stopped;
 * /status said 200.  Now every client is told (BYE shutdown naming the
 * limit and what to do), then closed, and /status is 503 with
 * past_time_limit. */
static void past_time_limit_closes_clients(void **state)
{
    (void)state;
    char ep[64], err[512];
    /* the limit passes 3 to 4 s from now */
    snprintf(ep, sizeof ep, "server.epoch=%lld", (long long)time(NULL) - (long long)OCEAN_TIME_MAX + 4);
    const char *sets[] = {ep};
    srv_settings s1;
    assert_int_equal(srv_settings_load(conf_path, sets, 1, &s1, err, sizeof err), OCEAN_OK);
    srv_daemon *d;
    if (srv_daemon_start(&s1, &d, err, sizeof err) != OCEAN_OK) fail_msg("%s", err);
    srv_hub *h = srv_daemon_hub(d);
    int p = srv_daemon_port(d);
    double left = OCEAN_TIME_MAX - srv_hub_sim_time(h);
    if (left < 1.0) {
        srv_daemon_stop(d);
        fail_msg("the daemon took too long to start: %.2f s left before the limit", left);
    }
    /* a client connected and subscribed before the limit */
    test_ws a;
    assert_int_equal(test_ws_connect(&a, p, "/", PROTO_SUBPROTOCOL), 0);
    proto_msg m;
    assert_true(test_msg_wait(&a, PROTO_HELLO, 3000, &m));
    proto_msg_free(&m);
    proto_msg sm;
    proto_msg_init(&sm, PROTO_SUBSCRIBE);
    small_subscribe(&sm.u.subscribe);
    sm.u.subscribe.mesh_kind = PROTO_MESH_NONE;
    test_msg_send(&a, &sm);
    assert_true(test_msg_wait(&a, PROTO_FRAME, 3000, &m));
    proto_msg_free(&m);
    while (srv_hub_sim_time(h) <= OCEAN_TIME_MAX) usleep(20000);
    char said[1200] = "";
    size_t k = 0;
    /* the connected client: BYE, then the close */
    int got = 0;
    double end = test_now_s() + 3;
    while (!got && test_now_s() < end) {
        if (!test_msg_wait(&a, PROTO_BYE, (int)((end - test_now_s()) * 1000) + 1, &m)) break;
        got = 1;
        if (m.u.bye.reason != PROTO_BYE_SHUTDOWN || !strstr(m.u.bye.message, "OCEAN_TIME_MAX") ||
            !strstr(m.u.bye.message, "server.epoch") || !strstr(m.u.bye.message, "restart"))
            k += (size_t)snprintf(said + k, sizeof said - k, "connected client: BYE %u '%s'; ", m.u.bye.reason,
                                  m.u.bye.message);
        proto_msg_free(&m);
    }
    if (!got) k += (size_t)snprintf(said + k, sizeof said - k, "connected client: no BYE within 3 s; ");
    char why[200];
    raw_close_reason(&a, 3000, why, sizeof why);
    if (got && !strstr(why, "OCEAN_TIME_MAX"))
        k += (size_t)snprintf(said + k, sizeof said - k, "connected client: close reason '%s'; ", why);
    test_ws_close(&a);
    /* a new client: BYE instead of HELLO, then the close */
    test_ws b;
    assert_int_equal(test_ws_connect(&b, p, "/", PROTO_SUBPROTOCOL), 0);
    proto_bye bye;
    int first = raw_first_type(&b, 3000, &bye);
    if (first != PROTO_BYE)
        k += (size_t)snprintf(said + k, sizeof said - k, "new client: first message %s; ",
                              first == 0 ? "none within 3 s" : first == -1 ? "none, closed" :
                              first == PROTO_HELLO ? "HELLO" : "another type");
    else if (bye.reason != PROTO_BYE_SHUTDOWN || !strstr(bye.message, "OCEAN_TIME_MAX"))
        k += (size_t)snprintf(said + k, sizeof said - k, "new client: BYE %u '%s'; ", bye.reason, bye.message);
    raw_close_reason(&b, 3000, why, sizeof why);
    if (first == PROTO_BYE && !strstr(why, "OCEAN_TIME_MAX"))
        k += (size_t)snprintf(said + k, sizeof said - k, "new client: close reason '%s'; ", why);
    test_ws_close(&b);
    /* health checks take the replica out */
    char *st = http_get(p, "/status");
    assert_non_null(st);
    char *body = strstr(st, "\r\n\r\n");
    cJSON *j = body ? cJSON_Parse(body + 4) : NULL;
    if (strncmp(st, "HTTP/1.", 7) != 0 || strncmp(st + 8, " 503 ", 5) != 0 || !j ||
        !cJSON_IsTrue(cJSON_GetObjectItem(j, "past_time_limit")))
        k += (size_t)snprintf(said + k, sizeof said - k, "/status: %.*s, past_time_limit %s", (int)strcspn(st, "\r"),
                              st, j && cJSON_GetObjectItem(j, "past_time_limit") ? "false" : "missing");
    cJSON_Delete(j);
    free(st);
    srv_daemon_stop(d);
    if (k) fail_msg("past the exact-time limit: %s", said);
}

/* ?record=1 records the camera path in the documented format. */
static void recording_writes_camera_path(void **state)
{
    (void)state;
    test_ws w;
    assert_int_equal(test_ws_connect(&w, port, "/?record=1", PROTO_SUBPROTOCOL), 0);
    proto_msg m;
    assert_true(test_msg_wait(&w, PROTO_HELLO, 3000, &m));
    uint32_t id = m.u.hello.client_id;
    proto_msg_free(&m);
    proto_msg sm;
    proto_msg_init(&sm, PROTO_SUBSCRIBE);
    small_subscribe(&sm.u.subscribe);
    sm.u.subscribe.mesh_kind = PROTO_MESH_NONE;
    test_msg_send(&w, &sm);
    proto_msg cm;
    proto_msg_init(&cm, PROTO_CAMERA);
    oc_camera_default(&cm.u.camera);
    for (int i = 0; i < 3; i++) {
        cm.u.camera.pos[0] = 0.1 * i + 1e6;
        cm.u.camera.vel[2] = 8;
        test_msg_send(&w, &cm);
    }
    /* the mode is known at SUBSCRIBE, not when the file opens: a replay
     * client's file said "mode live" in its header */
    usleep(100000);
    sm.u.subscribe.mode = PROTO_MODE_REPLAY;
    test_msg_send(&w, &sm);
    cm.u.camera.pos[0] = 0.1 * 3 + 1e6;
    cm.u.camera.render_time = 5.0;
    test_msg_send(&w, &cm);
    /* a replay client may scrub back */
    cm.u.camera.pos[0] = 0.1 * 4 + 1e6;
    cm.u.camera.render_time = 2.0;
    test_msg_send(&w, &cm);
    usleep(200000);
    test_ws_close(&w);
    usleep(300000);
    char dir[300];
    snprintf(dir, sizeof dir, "%s/rec", tmpdir);
    DIR *d = opendir(dir);
    assert_non_null(d);
    struct dirent *e;
    char want[64], path[700] = "";
    snprintf(want, sizeof want, "client-%u-", id);
    while ((e = readdir(d)))
        if (strncmp(e->d_name, want, strlen(want)) == 0) snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
    closedir(d);
    assert_true(path[0]);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char line[512];
    int data = 0, modes = 0;
    double t_replay = -1;
    assert_non_null(fgets(line, sizeof line, f));
    assert_string_equal(line, "# oceand camera path v1\n");
    while (fgets(line, sizeof line, f)) {
        if (strstr(line, "mode ")) {
            /* "# subscribed at T: mode live", then "... mode replay" */
            const char *want_mode = modes == 0 ? ": mode live\n" : ": mode replay\n";
            if (strncmp(line, "# subscribed at ", 16) != 0 || !strstr(line, want_mode) || data != 3 * modes)
                fail_msg("mode line %d after %d reports: %s", modes, data, line);
            modes++;
            continue;
        }
        if (line[0] == '#' || line[0] == 't') continue;
        double v[13];
        int n = sscanf(line, "%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2],
                       &v[3], &v[4], &v[5], &v[6], &v[7], &v[8], &v[9], &v[10], &v[11], &v[12]);
        assert_int_equal(n, 13);
        assert_true(v[1] == 0.1 * data + 1e6);
        assert_true(v[6] == 8);
        if (data == 3) t_replay = v[0];
        data++;
    }
    fclose(f);
    assert_int_equal(data, 5);
    assert_int_equal(modes, 2);
    assert_true(t_replay == 5.0); /* a replay report's t is its render_time */
    /* and the reader takes what the daemon writes: live t, then replay t
     * back at 5 and back again at 2 (it refused: "t 5 goes back in time") */
    oc_path *rp = NULL;
    char perr[512] = "";
    if (oc_path_load(path, &rp, perr, sizeof perr) != OCEAN_OK) fail_msg("the recording does not read back: %s", perr);
    assert_int_equal(rp->count, 5);
    assert_false(rp->monotonic);
    assert_true(rp->pts[4].t == 2.0);
    oc_path_destroy(rp);
}

/* ---- recordings are new files ---- */

static void put_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

/* The file's first 255 bytes ("" when it cannot be read). */
static const char *file_text(const char *path, char buf[256])
{
    buf[0] = 0;
    FILE *f = fopen(path, "r");
    if (!f) return buf;
    size_t n = fread(buf, 1, 255, f);
    buf[n] = 0;
    fclose(f);
    return buf;
}

/* A recording is always a new file: the name client-<id>-<unix time>.csv
 * is predictable, and a symlink planted there made the daemon overwrite
 * the link's target (fopen "w" follows it), a dangling one made it create
 * the target, and another run's recording of the same id and second was
 * truncated.  A name that exists is left alone and the recording goes to
 * the same name with a random suffix.  The suffixes were -1 .. -99 once:
 * anyone who could write the directory filled those 100 names and every
 * recording of that client id and second was refused ("client-900004-...
 * and its alternatives -1 .. -99 all exist"). */
static int random_suffix_name(const char *path, const char *dir, uint32_t id)
{
    char head[400];
    int n = snprintf(head, sizeof head, "%s/client-%u-", dir, id);
    if (strncmp(path, head, (size_t)n) != 0) return 0;
    const char *p = path + n;
    while (*p >= '0' && *p <= '9') p++;
    if (*p++ != '-') return 0;
    for (int i = 0; i < 8; i++, p++)
        if (!((*p >= '0' && *p <= '9') || (*p >= 'a' && *p <= 'f'))) return 0;
    return strcmp(p, ".csv") == 0;
}

static void recording_never_overwrites(void **state)
{
    (void)state;
    char dir[300], victim[320], absent[320], name[400], buf[256];
    snprintf(dir, sizeof dir, "%s/rec-excl", tmpdir);
    assert_int_equal(mkdir(dir, 0755), 0);
    snprintf(victim, sizeof victim, "%s/victim.txt", tmpdir);
    snprintf(absent, sizeof absent, "%s/made-through-link.txt", tmpdir);
    put_file(victim, "precious data\n");
    /* every name the next seconds could give (the clock may tick) */
    long long now = (long long)time(NULL);
    for (int d = 0; d < 3; d++) {
        snprintf(name, sizeof name, "%s/client-900001-%lld.csv", dir, now + d);
        assert_int_equal(symlink(victim, name), 0);            /* a planted link */
        snprintf(name, sizeof name, "%s/client-900002-%lld.csv", dir, now + d);
        put_file(name, "# earlier run\n");                      /* another run's recording */
        snprintf(name, sizeof name, "%s/client-900003-%lld.csv", dir, now + d);
        assert_int_equal(symlink(absent, name), 0);            /* a dangling link */
        for (int k = 0; k < 100; k++) {                         /* the old alternatives, filled */
            if (k == 0) snprintf(name, sizeof name, "%s/client-900004-%lld.csv", dir, now + d);
            else snprintf(name, sizeof name, "%s/client-900004-%lld-%d.csv", dir, now + d, k);
            put_file(name, "# earlier run\n");
        }
    }
    char path[4][1100];
    for (int i = 0; i < 4; i++) {
        srv_record *r = NULL;
        char msg[300] = "";
        if (srv_record_open(dir, 900001u + (uint32_t)i, "test", &r, path[i], sizeof path[i], msg, sizeof msg) !=
            OCEAN_OK)
            fail_msg("client %u: recording refused: %s", 900001u + i, msg);
        proto_camera cam;
        oc_camera_default(&cam);
        assert_int_equal(srv_record_camera(r, 1.0, &cam), OCEAN_OK);
        assert_int_equal(srv_record_close(r, NULL, 0), OCEAN_OK);
    }
    if (strcmp(file_text(victim, buf), "precious data\n") != 0)
        fail_msg("a symlink at the recording's name: its target %s was overwritten, now:\n%s", victim, buf);
    if (access(absent, F_OK) == 0)
        fail_msg("a dangling symlink at the recording's name: its target %s was created", absent);
    for (int d = 0; d < 3; d++)
        for (int k = 0; k < 100; k++) {
            if (k == 0) snprintf(name, sizeof name, "%s/client-900004-%lld.csv", dir, now + d);
            else snprintf(name, sizeof name, "%s/client-900004-%lld-%d.csv", dir, now + d, k);
            if (strcmp(file_text(name, buf), "# earlier run\n") != 0)
                fail_msg("an existing file %s was overwritten, now:\n%s", name, buf);
            snprintf(name, sizeof name, "%s/client-900002-%lld.csv", dir, now + d);
            if (strcmp(file_text(name, buf), "# earlier run\n") != 0)
                fail_msg("an existing recording %s was overwritten, now:\n%s", name, buf);
        }
    for (int i = 0; i < 4; i++) {
        struct stat st;
        assert_int_equal(lstat(path[i], &st), 0);
        if (!S_ISREG(st.st_mode) || !random_suffix_name(path[i], dir, 900001u + (uint32_t)i))
            fail_msg("client %u recorded to %s: want a new regular file client-%u-<time>-<8 hex digits>.csv",
                     900001u + i, path[i], 900001u + i);
        assert_non_null(strstr(file_text(path[i], buf), "# oceand camera path v1\n"));
    }
    /* a free name is the plain one */
    {
        srv_record *r = NULL;
        char msg[300] = "", p5[1100], want[400];
        long long t0 = (long long)time(NULL);
        assert_int_equal(srv_record_open(dir, 900005u, "test", &r, p5, sizeof p5, msg, sizeof msg), OCEAN_OK);
        assert_int_equal(srv_record_close(r, NULL, 0), OCEAN_OK);
        int ok = 0;
        for (int d = 0; d < 2 && !ok; d++) {
            snprintf(want, sizeof want, "%s/client-900005-%lld.csv", dir, t0 + d);
            ok = strcmp(p5, want) == 0;
        }
        if (!ok) fail_msg("a free name: recorded to %s, want client-900005-<time>.csv", p5);
    }
    srv_record *r = (srv_record *)1;
    char msg[300] = "", p4[1100];
    /* any other failure names the path and the reason */
    char notdir[320];
    snprintf(notdir, sizeof notdir, "%s/victim.txt", tmpdir);
    assert_int_equal(srv_record_open(notdir, 1u, "test", &r, p4, sizeof p4, msg, sizeof msg), OCEAN_EIO);
    assert_null(r);
    if (!strstr(msg, notdir) || !strstr(msg, "Not a directory")) fail_msg("record_dir a file: %s", msg);
    assert_string_equal(file_text(victim, buf), "precious data\n");
}

/* max_clients: one more connection is told BYE server-full. */
static int full_reason = -2;
static void on_close_full(void *user, oc_client *c, int reason, const char *msg)
{
    (void)user, (void)c, (void)msg;
    full_reason = reason;
}

/* A reload: every key that needs a restart is named (six at once wrote
 * past a four-entry array: ASan's stack-buffer-overflow), and a file whose
 * sea did not change leaves a SEA_STATE change in force (a reload of the
 * same file put the old wind back and announced it to every client). */
static void reload_restart_keys_and_runtime_sea(void **state)
{
    (void)state;
    srv_settings s2 = settings;
    s2.srv.port = 0;
    srv_daemon *d;
    char err[256];
    assert_int_equal(srv_daemon_start(&s2, &d, err, sizeof err), OCEAN_OK);
    srv_hub *h = srv_daemon_hub(d);
    /* the sea changed at run time (as SEA_STATE set does) and applied */
    ocean_params p = s2.params;
    p.sea.wind_u10 = s2.params.sea.wind_u10 + 1.5;
    char why[200];
    pthread_mutex_lock(&h->lock);
    assert_int_equal(srv_hub_sea_schedule(h, &p, -INFINITY, 0, NULL, why, sizeof why), OCEAN_OK);
    pthread_mutex_unlock(&h->lock);
    double end = test_now_s() + 5;
    double wind = 0;
    while (test_now_s() < end) {
        pthread_mutex_lock(&h->lock);
        wind = h->settings.params.sea.wind_u10;
        pthread_mutex_unlock(&h->lock);
        if (wind == p.sea.wind_u10) break;
        usleep(20000);
    }
    assert_true(wind == p.sea.wind_u10);
    /* the same file again: the runtime sea stays, nothing is scheduled */
    char msg[512];
    assert_int_equal(srv_daemon_reload(d, &s2, msg, sizeof msg), OCEAN_OK);
    assert_string_equal(msg, "");
    pthread_mutex_lock(&h->lock);
    int pending = h->n_sea_pending;
    wind = h->settings.params.sea.wind_u10;
    pthread_mutex_unlock(&h->lock);
    assert_int_equal(pending, 0);
    assert_true(wind == p.sea.wind_u10);
    /* six keys that need a restart, all named */
    srv_settings s3 = s2;
    s3.srv.port = 1;
    snprintf(s3.srv.bind, sizeof s3.srv.bind, "127.0.0.2");
    snprintf(s3.srv.web_root, sizeof s3.srv.web_root, "/nonexistent");
    snprintf(s3.srv.epoch, sizeof s3.srv.epoch, "2026-01-01T00:00:00Z");
    snprintf(s3.srv.redis, sizeof s3.srv.redis, "127.0.0.1:1");
    s3.srv.workers = s2.srv.workers + 1;
    assert_int_equal(srv_daemon_reload(d, &s3, msg, sizeof msg), OCEAN_OK);
    const char *keys[] = {"server.port", "server.bind", "server.web_root", "server.epoch", "server.redis",
                          "server.workers"};
    for (int i = 0; i < 6; i++)
        if (!strstr(msg, keys[i])) fail_msg("reload of six restart keys: '%s' lacks %s", msg, keys[i]);
    /* and a changed sea in the file is applied */
    srv_settings s4 = s2;
    s4.params.sea.wind_u10 = s2.params.sea.wind_u10 + 3.0;
    assert_int_equal(srv_daemon_reload(d, &s4, msg, sizeof msg), OCEAN_OK);
    pthread_mutex_lock(&h->lock);
    pending = h->n_sea_pending;
    double next = pending ? h->sea_pending[pending - 1].params.sea.wind_u10 : h->settings.params.sea.wind_u10;
    pthread_mutex_unlock(&h->lock);
    assert_true(next == s4.params.sea.wind_u10);
    srv_daemon_stop(d);
}

/* The mesh a camera gets on steep chop is denser (mesh_roughness: the
 * sideways error grows with the choppiness), so it keeps the error budget;
 * the daemon built every sea's mesh with one roughness. */
static size_t mesh_at_limit(double choppiness, int max_vertices, int layout, double height,
                            unsigned long long *errors, unsigned long long *coarsened, char *err, size_t errlen);

static size_t mesh_vertices_at(double choppiness)
{
    unsigned long long errors, coarsened;
    char e[512];
    return mesh_at_limit(choppiness, settings.srv.max_mesh_vertices, 0, 0.0, &errors, &coarsened, e, sizeof e);
}

/* A camera at the water with a long view range keeps its mesh (20 levels
 * were built, refused as more than a FRAME holds, and the client went
 * without a mesh until its next SUBSCRIBE, whatever its camera), in both
 * layouts. */
static void mesh_low_camera_long_range(void **state)
{
    (void)state;
    for (int layout = 0; layout < 2; layout++) {
        oc_client *c = connect_client(port, NULL);
        proto_subscribe sub;
        small_subscribe(&sub);
        if (layout) sub.layout = PROTO_LAYOUT_CASCADE;
        sub.view_range_m = 1e6f;
        assert_int_equal(oc_client_subscribe(c, &sub), OCEAN_OK);
        proto_camera cam;
        oc_camera_default(&cam);
        cam.pos[1] = 0.5;
        uint32_t seq = 0;
        assert_int_equal(oc_client_send_camera(c, &cam, &seq), OCEAN_OK);
        int meshed = 0;
        for (int k = 0; k < 60 && !meshed; k++) {
            oc_frame *f = next_frame(c);
            if (f->info.camera_seq == seq && f->info.has_mesh) meshed = 1;
            oc_frame_free(f);
        }
        oc_client_stats st;
        oc_client_get_stats(c, &st);
        char e[256] = "";
        oc_client_last_error(c, e, sizeof e);
        if (!meshed || st.errors_rx) fail_msg("layout %d, camera at 0.5 m, range 1e6 m: mesh %d, %llu ERRORs (%s)", layout,
                                              meshed, (unsigned long long)st.errors_rx, e);
        oc_client_destroy(c);
    }
}

static void mesh_denser_on_steep_chop(void **state)
{
    (void)state;
    size_t calm = mesh_vertices_at(1.0), steep = mesh_vertices_at(5.0);
    print_message("mesh vertices: %zu at choppiness 1, %zu at 5\n", calm, steep);
    assert_true(calm > 0);
    assert_true(steep > 4 * calm);
}

/* The vertices of the first meshed frame a daemon on settings s2 sends
 * for subscription sub and camera cam (0 if no frame of that camera came
 * with a mesh); *errors and err: the ERRORs the client got, and the last
 * one's text; *coarsened: the daemon's count of coarsened meshes. */
static size_t mesh_of(const srv_settings *s2, const proto_subscribe *sub, const proto_camera *cam,
                      unsigned long long *errors, unsigned long long *coarsened, char *err, size_t errlen)
{
    srv_daemon *d;
    char e[512];
    assert_int_equal(srv_daemon_start(s2, &d, e, sizeof e), OCEAN_OK);
    oc_client *c = connect_client(srv_daemon_port(d), NULL);
    assert_int_equal(oc_client_subscribe(c, sub), OCEAN_OK);
    uint32_t seq = 0;
    assert_int_equal(oc_client_send_camera(c, cam, &seq), OCEAN_OK);
    size_t n = 0;
    for (int k = 0; k < 40 && !n; k++) {
        /* a deadline, not a speed: half a million vertices take seconds to
         * build, displace and send on a host whose cores are busy */
        oc_frame *f = next_frame(c);
        /* layout 1: the vertices are the topology's (the frame carries
         * only its placement) */
        if (f->info.camera_seq == seq && f->info.has_mesh)
            n = sub->layout == PROTO_LAYOUT_CASCADE ? (f->topology ? f->topology->vertex_count : 0)
                                                    : f->info.mesh.vertex_count;
        oc_frame_free(f);
    }
    oc_client_stats st;
    oc_client_get_stats(c, &st);
    *errors = (unsigned long long)st.errors_rx;
    err[0] = '\0';
    oc_client_last_error(c, err, errlen);
    oc_client_destroy(c);
    *coarsened = (unsigned long long)atomic_load(&srv_daemon_hub(d)->stats.coarsened_mesh);
    srv_daemon_stop(d);
    return n;
}

/* mesh_of for a camera height m over a sea of the given choppiness
 * (height 0: oc_camera_default's), with the server's vertex limit at
 * max_vertices, in the given layout of the tests' small subscription. */
static size_t mesh_at_limit(double choppiness, int max_vertices, int layout, double height,
                            unsigned long long *errors, unsigned long long *coarsened, char *err, size_t errlen)
{
    srv_settings s2 = settings;
    s2.srv.port = 0;
    s2.srv.max_mesh_vertices = max_vertices;
    s2.params.sea.choppiness = choppiness;
    /* a half-million-vertex topology and its frames are tens of MB: a test
     * client on a busy host reads them for longer than the default soft
     * limit's 10 s above 8 MB allow, and the slow-consumer rule (not what
     * this measures) closed it once */
    s2.srv.output_soft = (uint64_t)1 << 30;
    if (s2.srv.output_hard < s2.srv.output_soft) s2.srv.output_hard = s2.srv.output_soft;
    /* and the suite's 1 s with no send completed (a reader that takes
     * nothing): a busy host's test client, turning a 268 k-vertex layout-0
     * topology into positions, read nothing for longer and was closed
     * "no bytes read for server.output_soft_seconds" */
    s2.srv.output_soft_seconds = 60;
    /* both layouts at one budget: at layout 1's own 8 px the unlimited mesh
     * is 3.8 M vertices, a 140 MB topology a test client on a busy host
     * read too slowly (closed "no bytes read" for server.output_soft_seconds) */
    s2.srv.flat_mesh_error_px = s2.srv.mesh_error_px;
    proto_subscribe sub;
    small_subscribe(&sub);
    if (layout) sub.layout = PROTO_LAYOUT_CASCADE;
    proto_camera cam;
    oc_camera_default(&cam);
    if (height > 0) cam.pos[1] = height;
    return mesh_of(&s2, &sub, &cam, errors, coarsened, err, errlen);
}

/* A camera near steep chop whose mesh at the configured error budget is
 * over server.max_mesh_vertices gets it at a coarser budget, within the
 * limit, in both layouts (its frames came without a mesh; at choppiness 10,
 * 2 m up: 485 k vertices against the default limit of 262 144), counted in
 * oceand_coarsened_mesh_total.  Layout 0 is told by one ERROR ETOOBIG
 * naming both budgets (the positions it gets are not those it asked for);
 * layout 1 is not: its MESH_TOPOLOGY zones carry the lattice it got, and a
 * narrow field of view (a sensor, binoculars) is a normal use, not an error
 * line on the viewer. */
static void mesh_fits_the_limit_on_steep_chop(void **state)
{
    (void)state;
    for (int layout = 0; layout < 2; layout++) {
        unsigned long long errors, coarsened;
        char e[1024];
        size_t free_n = mesh_at_limit(10.0, 1 << 30, layout, 2.0, &errors, &coarsened, e, sizeof e);
        assert_true(free_n > 0);
        assert_true(coarsened == 0 && errors == 0);
        int limit = (int)(0.6 * (double)free_n);
        if (limit < 1000) limit = 1000;
        size_t n = mesh_at_limit(10.0, limit, layout, 2.0, &errors, &coarsened, e, sizeof e);
        print_message("layout %d, choppiness 10, 2 m up: %zu vertices unlimited; %zu under a limit of %d (%llu coarsened, "
                      "%llu ERRORs: %s)\n", layout, free_n, n, limit, coarsened, errors, e);
        if (!n) fail_msg("layout %d: no mesh under a limit of %d (%s)", layout, limit, e);
        assert_true(n <= (size_t)limit);
        assert_true(coarsened == 1);
        if (layout == 1) {
            if (errors != 0) fail_msg("layout 1: %llu ERRORs for a coarsened mesh: '%s'", errors, e);
            continue;
        }
        assert_true(errors == 1);
        if (!strstr(e, "server.max_mesh_vertices") || !strstr(e, "is drawn at"))
            fail_msg("layout %d: the ERROR does not name the limit and the budget used: '%s'", layout, e);
    }
}

/* A narrow field of view is a normal use (issue 45: a sensor or binocular
 * view at 2-5 deg): the viewer's subscription (the library's default, layout
 * 1) gets a mesh within the vertex limit and no ERROR line, where it got
 * "is drawn at 32 px" as an ERROR before; the coarsening is counted.  At
 * 2 deg the mesh fits at the largest budget, 100 px, and not at 64: the
 * budget's doubling ends on that largest budget itself (a 2 deg view got no
 * mesh and an ERROR line before).  Below about 1.5 deg at 1080p the
 * concentric mesh does not fit even at 100 px. */
static void narrow_fov_gets_a_mesh_without_error(void **state)
{
    (void)state;
    srv_settings s2 = settings;
    s2.srv.port = 0;
    proto_subscribe sub;
    oc_subscribe_default(&sub);
    assert_int_equal(sub.layout, PROTO_LAYOUT_CASCADE);
    static const struct { double fov, y; } views[] = {{5, 25}, {2, 25}, {2, 3}};
    for (size_t i = 0; i < sizeof views / sizeof views[0]; i++) {
        proto_camera cam;
        oc_camera_default(&cam);
        cam.pos[1] = views[i].y;
        cam.fov_y_deg = views[i].fov;
        cam.viewport_w = 1920;
        cam.viewport_h = 1080;
        unsigned long long errors, coarsened;
        char e[512];
        size_t n = mesh_of(&s2, &sub, &cam, &errors, &coarsened, e, sizeof e);
        print_message("%g deg at %g m: %zu vertices (limit %d), %llu coarsened, %llu ERRORs %s\n", views[i].fov,
                      views[i].y, n, s2.srv.max_mesh_vertices, coarsened, errors, e);
        assert_true(n > 0 && n <= (size_t)s2.srv.max_mesh_vertices);
        assert_true(coarsened >= 1); /* the path this test is about */
        if (errors != 0) fail_msg("%llu ERRORs for a %g deg view: %s", errors, views[i].fov, e);
    }
}

/* A reload whose sea cannot be built (here: a wisdom file without its
 * grid's plans) is not applied: the sea in force stays, no change is
 * scheduled or announced, and msg says why; it said "configuration
 * reloaded", told every client of the new sea, and the simulation thread
 * then logged that it could not build it.  The next reload tries again. */
static void reload_sea_that_cannot_be_built(void **state)
{
    (void)state;
    srv_settings s2 = settings;
    s2.srv.port = 0;
    srv_daemon *d;
    char err[512];
    assert_int_equal(srv_daemon_start(&s2, &d, err, sizeof err), OCEAN_OK);
    srv_hub *h = srv_daemon_hub(d);
    char wis[400];
    snprintf(wis, sizeof wis, "%s/no-such-grid.wisdom", tmpdir);
    assert_int_equal(ocean_wisdom_export(wis, err, sizeof err), OCEAN_OK);
    srv_settings s5 = s2;
    s5.params.n = s2.params.n * 2;
    s5.params.plan_measure = OCEAN_PLAN_WISDOM;
    snprintf(s5.params.wisdom, sizeof s5.params.wisdom, "%s", wis);
    for (int round = 0; round < 2; round++) {
        char msg[1024];
        assert_int_equal(srv_daemon_reload(d, &s5, msg, sizeof msg), OCEAN_OK);
        if (!strstr(msg, "the file's sea is not applied, it cannot be built") || !strstr(msg, wis) ||
            !strstr(msg, "no client was told"))
            fail_msg("reload %d of an unbuildable sea: '%s'", round, msg);
        pthread_mutex_lock(&h->lock);
        int pending = h->n_sea_pending, n = h->settings.params.n;
        pthread_mutex_unlock(&h->lock);
        assert_int_equal(pending, 0);
        assert_int_equal(n, s2.params.n);
    }
    /* the same grid with plans the process can make is applied */
    srv_settings s6 = s2;
    s6.params.n = s2.params.n * 2;
    char msg[1024];
    assert_int_equal(srv_daemon_reload(d, &s6, msg, sizeof msg), OCEAN_OK);
    assert_string_equal(msg, "");
    pthread_mutex_lock(&h->lock);
    int pending = h->n_sea_pending;
    int next = pending ? h->sea_pending[pending - 1].params.n : h->settings.params.n;
    pthread_mutex_unlock(&h->lock);
    assert_int_equal(next, s6.params.n);
    srv_daemon_stop(d);
}

/* A reload whose changed sea the timeline cannot take (16 changes pend)
 * says so and tries again at the next reload: the file's sea was taken as
 * seen and never applied (depth 4000 m served, the file said 3000), while
 * the log said "configuration reloaded". */
static void reload_sea_retried_when_the_timeline_is_full(void **state)
{
    (void)state;
    srv_settings s2 = settings;
    s2.srv.port = 0;
    srv_daemon *d;
    char err[512], msg[1024], why[200];
    assert_int_equal(srv_daemon_start(&s2, &d, err, sizeof err), OCEAN_OK);
    srv_hub *h = srv_daemon_hub(d);
    pthread_mutex_lock(&h->lock);
    double t0 = srv_hub_sim_time(h);
    for (int i = 0; i < SRV_SEA_PENDING_MAX; i++)
        assert_int_equal(srv_hub_sea_schedule(h, &s2.params, t0 + 1000 + i, 0, NULL, why, sizeof why), OCEAN_OK);
    pthread_mutex_unlock(&h->lock);
    srv_settings s3 = s2;
    s3.params.sea.depth_m = s2.params.sea.depth_m > 3000 ? 2000 : 3000;
    assert_int_equal(srv_daemon_reload(d, &s3, msg, sizeof msg), OCEAN_OK);
    if (!strstr(msg, "the file's sea is not applied") || !strstr(msg, "pending") || !strstr(msg, "next reload"))
        fail_msg("a reload into a full timeline: '%s'", msg);
    /* the pending changes take effect (taken as the simulation thread does) */
    pthread_mutex_lock(&h->lock);
    srv_sea_change ch;
    while (srv_hub_sea_take_due(h, t0 + 2000, &ch)) continue;
    assert_int_equal(h->n_sea_pending, 0);
    pthread_mutex_unlock(&h->lock);
    /* the same file again: now its sea is applied */
    assert_int_equal(srv_daemon_reload(d, &s3, msg, sizeof msg), OCEAN_OK);
    assert_string_equal(msg, "");
    /* pending, or (a slow host: its lead passed) already in force */
    pthread_mutex_lock(&h->lock);
    int pending = h->n_sea_pending;
    double depth = pending ? h->sea_pending[pending - 1].params.sea.depth_m : h->settings.params.sea.depth_m;
    pthread_mutex_unlock(&h->lock);
    assert_true(pending <= 1);
    assert_true(depth == s3.params.sea.depth_m);
    srv_daemon_stop(d);
}

/* A scene wins over the configuration file for sea.* and ocean.*: a key
 * the file changed from its default and the scene sets otherwise is named
 * in srv_settings.overridden (oceand prints it), since the edit changes
 * nothing (ocean.n = 512 in oceand.conf with the shipped scene stayed 256,
 * without a word).  Keys the file leaves at their defaults (the shipped
 * file spells every key out), keys the scene does not set, and keys --set
 * gives are not named. */
static void scene_overrides_named(void **state)
{
    (void)state;
    char scene[400], conf[400];
    snprintf(scene, sizeof scene, "%s/override-scene.conf", tmpdir);
    snprintf(conf, sizeof conf, "%s/override.conf", tmpdir);
    FILE *f = fopen(scene, "w");
    assert_non_null(f);
    fprintf(f, "scene.name = over\nscene.effects = height\nsea.wind = 9\nocean.n = 32\nsea.choppiness = 0.5\n");
    fclose(f);
    f = fopen(conf, "w");
    assert_non_null(f);
    fprintf(f, "sea.wind = 15\nocean.n = 64\nocean.seed = 7\nsea.choppiness = 1\nocean.threads = 1\n"
            "server.port = 0\nserver.scene = \"%s\"\n", scene);
    fclose(f);
    srv_settings *s1 = malloc(sizeof *s1);
    assert_non_null(s1);
    char err[1024] = "";
    if (srv_settings_load(conf, NULL, 0, s1, err, sizeof err) != OCEAN_OK) fail_msg("%s", err);
    assert_string_equal(s1->overridden, "sea.wind = 15 (scene: 9), ocean.n = 64 (scene: 32)");
    assert_int_equal(s1->params.n, 32);
    assert_int_equal((int)s1->params.seed, 7);
    const char *sets[] = {"ocean.n=64"};
    if (srv_settings_load(conf, sets, 1, s1, err, sizeof err) != OCEAN_OK) fail_msg("%s", err);
    assert_string_equal(s1->overridden, "sea.wind = 15 (scene: 9)");
    assert_int_equal(s1->params.n, 64);
    /* the shipped file and scene: every key at its default, nothing named */
    if (srv_settings_load("config/oceand.conf", NULL, 0, s1, err, sizeof err) != OCEAN_OK) fail_msg("%s", err);
    assert_string_equal(s1->overridden, "");
    free(s1);
}

/* config/oceand.conf says it documents every server.* key: each key of
 * the daemon's table is there (server.read_rate was missing). */
static void shipped_config_has_every_key(void **state)
{
    (void)state;
    FILE *f = fopen("config/oceand.conf", "r");
    assert_non_null(f);
    static char text[1 << 17];
    size_t n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[n] = 0;
    const conf_table *t = srv_config_table();
    int missing = 0;
    for (size_t i = 0; i < t->count; i++) {
        char want[160], commented[160];
        snprintf(want, sizeof want, "\n%s = ", t->entries[i].name);
        snprintf(commented, sizeof commented, "\n# %s = ", t->entries[i].name);
        if (!strstr(text, want) && !strstr(text, commented)) {
            print_error("config/oceand.conf lacks %s\n", t->entries[i].name);
            missing++;
        }
    }
    assert_int_equal(missing, 0);
}

static void max_clients_refused(void **state)
{
    (void)state;
    srv_settings s2 = settings;
    s2.srv.max_clients = 2;
    srv_daemon *d;
    char err[256];
    assert_int_equal(srv_daemon_start(&s2, &d, err, sizeof err), OCEAN_OK);
    int p = srv_daemon_port(d);
    oc_client *a = connect_client(p, NULL), *b = connect_client(p, NULL);
    char url[64];
    snprintf(url, sizeof url, "ws://127.0.0.1:%d/", p);
    oc_options o;
    oc_options_default(&o);
    o.url = url;
    o.cb.on_close = on_close_full;
    oc_client *c = NULL;
    assert_int_equal(oc_client_create(&o, &c, err, sizeof err), OCEAN_OK);
    double end = test_now_s() + 5;
    while (test_now_s() < end && oc_client_state(c) != OC_CLOSED) oc_service(c, 50);
    assert_int_equal(oc_client_state(c), OC_CLOSED);
    assert_int_equal(full_reason, PROTO_BYE_SERVER_FULL);
    oc_client_destroy(c);
    oc_client_destroy(a);
    oc_client_destroy(b);
    srv_daemon_stop(d);
}

/* 200 connect/disconnect cycles: clean BYEs, abrupt closes, closes in the
 * middle of a subscription; every client is freed (ASan's leak check runs
 * at exit) and the hub is empty afterwards. */
static void connect_disconnect_cycles(void **state)
{
    (void)state;
    srv_hub *h = srv_daemon_hub(daemon_);
    for (int i = 0; i < 200; i++) {
        if (i % 20 == 0) { /* the client library's orderly close */
            oc_client *c = connect_client(port, NULL);
            oc_client_destroy(c);
            continue;
        }
        test_ws w;
        assert_int_equal(test_ws_connect(&w, port, "/", PROTO_SUBPROTOCOL), 0);
        proto_msg m;
        if (i % 2 == 0) {
            assert_true(test_msg_wait(&w, PROTO_HELLO, 3000, &m));
            proto_msg_free(&m);
            proto_msg sm;
            proto_msg_init(&sm, PROTO_SUBSCRIBE);
            small_subscribe(&sm.u.subscribe);
            sm.u.subscribe.mode = (i % 4 == 0) ? PROTO_MODE_LIVE : PROTO_MODE_REPLAY;
            test_msg_send(&w, &sm);
            proto_msg cm;
            proto_msg_init(&cm, PROTO_CAMERA);
            oc_camera_default(&cm.u.camera);
            cm.u.camera.render_time = i;
            test_msg_send(&w, &cm);
            proto_msg q;
            proto_msg_init(&q, PROTO_QUERY);
            double pts[2] = {i, -i};
            q.u.query.count = 1;
            q.u.query.points = pts;
            test_msg_send(&w, &q);
            if (i % 8 == 0 && test_msg_wait(&w, PROTO_FRAME, 3000, &m)) proto_msg_free(&m);
        }
        test_ws_close(&w); /* abrupt: no BYE, no close frame */
    }
    /* a deadline, not a speed: a leaked client never leaves (CI, a core busy
     * beside the browser test: some were still closing after 10 s) */
    double end = test_now_s() + 30;
    int left = -1;
    while (test_now_s() < end) {
        pthread_mutex_lock(&h->lock);
        left = h->n_clients;
        pthread_mutex_unlock(&h->lock);
        if (left == 0) break;
        usleep(20000);
    }
    assert_int_equal(left, 0);
}

/* A recording whose file cannot take its lines says so, with the file and
 * the reason: the real binary, its file size limited (RLIMIT_FSIZE: writes
 * past 600 bytes fail with EFBIG, as on a full disk).  The buffered lines
 * failed at fclose, unchecked: three short recordings on a full disk were
 * left empty and nothing was logged. */
/* In the child: stderr to the file arg, opened before the file size
 * limit; a write past the limit then fails (SIGXFSZ ignored) and the
 * process lives. */
static void fsize_limit_child(void *arg)
{
    int lf = open((const char *)arg, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (lf >= 0) dup2(lf, 2);
    signal(SIGXFSZ, SIG_IGN);
    struct rlimit rl = {600, 600};
    setrlimit(RLIMIT_FSIZE, &rl);
}

static void recording_write_error_is_said(void **state)
{
    (void)state;
    char exe[700], conf[400], log[400];
    snprintf(exe, sizeof exe, "%s/oceand", exe_dir);
    snprintf(conf, sizeof conf, "%s/fsize.conf", tmpdir);
    snprintf(log, sizeof log, "%s/fsize.log", tmpdir);
    write_conf(conf, 10, 100);
    FILE *out;
    int p;
    pid_t pid = test_oceand_exec(exe, conf, fsize_limit_child, log, &p, &out);
    assert_true(pid > 0);
    assert_true(p > 0);
    char line[512];
    test_ws w;
    assert_int_equal(test_ws_connect(&w, p, "/?record=1", PROTO_SUBPROTOCOL), 0);
    proto_msg m;
    assert_true(test_msg_wait(&w, PROTO_HELLO, 3000, &m));
    proto_msg_free(&m);
    proto_msg sm;
    proto_msg_init(&sm, PROTO_SUBSCRIBE);
    small_subscribe(&sm.u.subscribe);
    sm.u.subscribe.mesh_kind = PROTO_MESH_NONE;
    test_msg_send(&w, &sm);
    proto_msg cm;
    proto_msg_init(&cm, PROTO_CAMERA);
    oc_camera_default(&cm.u.camera);
    for (int i = 0; i < 20; i++) { /* ~2.4 KB of lines, past the 600-byte limit */
        cm.u.camera.pos[0] = 1e6 + 0.1 * i;
        test_msg_send(&w, &cm);
    }
    usleep(200000);
    test_ws_close(&w);
    int said = 0;
    double end = test_now_s() + 5;
    while (test_now_s() < end && !said) {
        usleep(100000);
        FILE *lf = fopen(log, "r");
        if (!lf) continue;
        while (fgets(line, sizeof line, lf))
            if (strstr(line, "recording") && strstr(line, "/rec/client-") && strstr(line, "File too large"))
                said = 1;
        fclose(lf);
    }
    kill(pid, SIGTERM);
    int status;
    waitpid(pid, &status, 0);
    fclose(out);
    if (!said) {
        char buf[2000] = "";
        FILE *lf = fopen(log, "r");
        if (lf) {
            size_t n = fread(buf, 1, sizeof buf - 1, lf);
            buf[n] = 0;
            fclose(lf);
        }
        fail_msg("no log line naming the recording and its write error; the log:\n%s", buf);
    }
}

/* SIGHUP reloads (a changed sea is announced), SIGTERM closes every client
 * with BYE shutdown and exits 0: the real binary. */
static int term_reason = -2;
static void on_close_term(void *user, oc_client *c, int reason, const char *msg)
{
    (void)user, (void)c, (void)msg;
    term_reason = reason;
}

static void sighup_and_sigterm(void **state)
{
    (void)state;
    char exe[700];
    snprintf(exe, sizeof exe, "%s/oceand", exe_dir);
    if (access(exe, X_OK) != 0) {
        fprintf(stderr, "no %s\n", exe);
        fail();
    }
    char conf2[400];
    snprintf(conf2, sizeof conf2, "%s/sig.conf", tmpdir);
    write_conf(conf2, 10, 100);
    FILE *out;
    int p;
    pid_t pid = test_oceand_exec(exe, conf2, NULL, NULL, &p, &out);
    assert_true(pid > 0);
    assert_true(p > 0);
    oc_callbacks cb = {0};
    cb.on_close = on_close_term;
    oc_client *c = connect_client(p, &cb);
    proto_sea sea;
    double eff;
    assert_int_equal(oc_client_sea_state(c, &sea, &eff), OCEAN_OK);
    assert_true(sea.wind_u10 == 10);
    /* a bad file is refused and changes nothing; a good one is applied */
    FILE *f = fopen(conf2, "a");
    fprintf(f, "server.tick_rate = fast\n");
    fclose(f);
    kill(pid, SIGHUP);
    usleep(300000);
    write_conf(conf2, 14, 100);
    kill(pid, SIGHUP);
    double end = test_now_s() + 8;
    while (test_now_s() < end) {
        oc_service(c, 50);
        drain_frames(c);
        if (oc_client_sea_state(c, &sea, &eff) == OCEAN_OK && sea.wind_u10 == 14) break;
    }
    assert_true(sea.wind_u10 == 14);
    kill(pid, SIGTERM);
    end = test_now_s() + 8;
    while (test_now_s() < end && oc_client_state(c) != OC_CLOSED) oc_service(c, 50);
    assert_int_equal(oc_client_state(c), OC_CLOSED);
    assert_int_equal(term_reason, PROTO_BYE_SHUTDOWN);
    int status = -1;
    for (int i = 0; i < 100; i++) {
        if (waitpid(pid, &status, WNOHANG) == pid) break;
        usleep(50000);
    }
    if (!WIFEXITED(status)) kill(pid, SIGKILL);
    assert_true(WIFEXITED(status));
    assert_int_equal(WEXITSTATUS(status), 0);
    fclose(out);
    oc_client_destroy(c);
}

int main(int argc, char **argv)
{
    (void)argc;
    test_wait_policy_passive(argv);
    test_build_dir(argv[0], exe_dir, sizeof exe_dir);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(tile_payload_fits_its_bytes),
        cmocka_unit_test(frames_tiles_and_mesh_decode),
        cmocka_unit_test(cascade_tiles_are_the_mips),
        cmocka_unit_test(whitecaps_of_the_whole_sea),
        cmocka_unit_test(cascade_near_field_ship_bridge),
        cmocka_unit_test(cascade_tiles_shared_across_cameras),
        cmocka_unit_test(cutoff_follows_velocity),
        cmocka_unit_test(queries_agree_with_sim),
        cmocka_unit_test(identical_cameras_share_tiles),
        cmocka_unit_test(idle_daemon_drops_its_tiles),
        cmocka_unit_test(replay_identical_bytes),
        cmocka_unit_test(mesh_qz_within_bound),
        cmocka_unit_test(slow_reader_never_delays_fast),
        cmocka_unit_test(trailing_confirmations_are_no_dead_reader),
        cmocka_unit_test(stalled_daemon_counts_no_client_time),
        cmocka_unit_test(bad_input_gets_error),
        cmocka_unit_test(client_error_log_is_escaped),
        cmocka_unit_test(camera_at_the_world_edge),
        cmocka_unit_test(sea_state_admin_change),
        cmocka_unit_test(sea_state_set_answered_by_its_own_announce),
        cmocka_unit_test(sea_changes_built_ahead),
        cmocka_unit_test(sea_timeline_scheduled_change),
        cmocka_unit_test(sea_timeline_late_joiner),
        cmocka_unit_test(sea_timeline_get),
        cmocka_unit_test(sea_set_ranges),
        cmocka_unit_test(entity_messages),
        cmocka_unit_test(entity_rate),
        cmocka_unit_test(entity_from_the_library),
        cmocka_unit_test(wakes_in_queries),
        cmocka_unit_test(rotor_wash_everywhere),
        cmocka_unit_test(wakes_reach_viewers),
        cmocka_unit_test(wakes_for_late_joiners),
        cmocka_unit_test(wakes_replay_as_watched),
        cmocka_unit_test(entity_log_replays_the_wakes),
        cmocka_unit_test(epoch_parse),
        cmocka_unit_test(epoch_shared_clock),
        cmocka_unit_test(epoch_beyond_time_limit),
        cmocka_unit_test(past_time_limit_closes_clients),
        cmocka_unit_test(near_field_wavelength_range),
        cmocka_unit_test(hello_limits_are_honoured),
        cmocka_unit_test(http_metrics_and_status),
        cmocka_unit_test(recording_writes_camera_path),
        cmocka_unit_test(recording_write_error_is_said),
        cmocka_unit_test(recording_never_overwrites),
        cmocka_unit_test(reload_restart_keys_and_runtime_sea),
        cmocka_unit_test(reload_sea_that_cannot_be_built),
        cmocka_unit_test(reload_sea_retried_when_the_timeline_is_full),
        cmocka_unit_test(subscribe_keeps_pending_queries),
        cmocka_unit_test(subscribe_between_ticks_is_applied),
        cmocka_unit_test(admin_lock_sliding_window),
        cmocka_unit_test(mesh_denser_on_steep_chop),
        cmocka_unit_test(mesh_fits_the_limit_on_steep_chop),
        cmocka_unit_test(narrow_fov_gets_a_mesh_without_error),
        cmocka_unit_test(cascade_q_spends_the_budget),
        cmocka_unit_test(altitude_plan_reaches_a_sample_a_pixel),
        cmocka_unit_test(relief_reads_the_far_crests),
        cmocka_unit_test(time_interp_reads_the_frames_tick),
        cmocka_unit_test(time_interp_key_frame_spread),
        cmocka_unit_test(narrow_fov_keeps_the_budget),
        cmocka_unit_test(resubscribe_buys_no_frames),
        cmocka_unit_test(slow_link_gets_coarser_not_older),
        cmocka_unit_test(rare_reports_are_not_held),
        cmocka_unit_test(cascade_fine_mips_without_geometry),
        cmocka_unit_test(mesh_low_camera_long_range),
        cmocka_unit_test(scene_overrides_named),
        cmocka_unit_test(shipped_config_has_every_key),
        cmocka_unit_test(max_clients_refused),
        cmocka_unit_test(connect_disconnect_cycles),
        cmocka_unit_test(sighup_and_sigterm),
    };
    const char *filter = getenv("SERVER_TEST_FILTER"); /* one test (cmocka pattern) while debugging */
    if (filter && *filter) cmocka_set_test_filter(filter);
    /* TEST_FILTER=NAME (a cmocka pattern) runs only the tests it matches */
    if (getenv("TEST_FILTER")) cmocka_set_test_filter(getenv("TEST_FILTER"));
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
