/*
 * test_client.c - the C client library (clients/c/): URL parsing, camera
 * path files, the frame-store format and its byte-for-byte comparison, and
 * the library's network side against a small in-process fake server built
 * on libwebsockets (HELLO, FRAMEs with real tile codecs and a mesh, QUERY,
 * SEA_STATE with a token, ERROR, replay-mode CAMERAs).  When build/oceand
 * exists, one live round trip against the real daemon on a free loopback
 * port as well.
 */
#include <malloc.h>
#include <math.h>
#include <pthread.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <netinet/in.h>
#include <time.h>
#include <unistd.h>

#include <cmocka.h>
#include <libwebsockets.h>

#include "oc_path.h"
#include "oc_store.h"
#include "oceanclient.h"
#include "proto.h"
#include "lib/test_net.h"

/* ================================================================ URLs */

static void url_good(void **state)
{
    (void)state;
    oc_url u;
    char err[256];
    assert_int_equal(oc_url_parse("ws://localhost:8080/", &u, err, sizeof err), OCEAN_OK);
    assert_string_equal(u.host, "localhost");
    assert_int_equal(u.port, 8080);
    assert_string_equal(u.path, "/");
    assert_int_equal(u.tls, 0);

    assert_int_equal(oc_url_parse("ws://127.0.0.1", &u, err, sizeof err), OCEAN_OK);
    assert_string_equal(u.host, "127.0.0.1");
    assert_int_equal(u.port, 80);
    assert_string_equal(u.path, "/");

    assert_int_equal(oc_url_parse("WSS://example.org/ocean?x=1", &u, err, sizeof err), OCEAN_OK);
    assert_int_equal(u.tls, 1);
    assert_int_equal(u.port, 443);
    assert_string_equal(u.path, "/ocean?x=1");

    assert_int_equal(oc_url_parse("ws://[::1]:9001/a/b", &u, err, sizeof err), OCEAN_OK);
    assert_string_equal(u.host, "::1");
    assert_int_equal(u.port, 9001);
    assert_string_equal(u.path, "/a/b");

    assert_int_equal(oc_url_parse("ws://h:65535?q", &u, err, sizeof err), OCEAN_OK);
    assert_int_equal(u.port, 65535);
    assert_string_equal(u.path, "/?q");
}

static void url_bad(void **state)
{
    (void)state;
    struct {
        const char *url, *needle;
    } bad[] = {
        {"http://h:1/", "scheme"},   {"h:1", "scheme"},          {"ws://", "empty host"},
        {"ws://:80/", "empty host"}, {"ws://h:0/", "outside"},   {"ws://h:65536/", "outside"},
        {"ws://h:8x/", "number"},    {"ws://h:/", "number"},     {"ws://u@h/", "user"},
        {"ws://h/a b", "space"},     {"ws://h/#f", "fragment"},  {"ws://[::1/", "']'"},
        {"ws://h:123456/", "number"}, {"ws://[::1]x/", "after"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        oc_url u;
        char err[256] = "";
        ocean_result r = oc_url_parse(bad[i].url, &u, err, sizeof err);
        if (r != OCEAN_EINVAL || !strstr(err, bad[i].needle)) {
            print_error("url \"%s\": result %d, message \"%s\" (wanted \"%s\")\n", bad[i].url, r, err,
                        bad[i].needle);
            fail();
        }
    }
    char longhost[400] = "ws://";
    memset(longhost + 5, 'a', 300);
    longhost[305] = 0;
    oc_url u;
    char err[256];
    assert_int_equal(oc_url_parse(longhost, &u, err, sizeof err), OCEAN_EINVAL);
    assert_non_null(strstr(err, "host longer"));
    assert_int_equal(oc_url_parse(NULL, &u, err, sizeof err), OCEAN_EINVAL);
}

/* ================================================================ paths */

static void path_good(void **state)
{
    (void)state;
    const char *text = "# a comment\n"
                       "\n"
                       " t, x ,y,z,vx,vy,vz,yaw,pitch,roll,fov \r\n"
                       "0,1,2,3,4,5,6,7,8,9,60\n"
                       "# mid comment\n"
                       "0.5, -1e3 ,30,1.25e2,0,0,0,-90,-10,0,45.5\r\n"
                       "0.5,0,0,0,0,0,0,0,0,0,1\n"   /* equal t allowed */
                       /* float fields given past float precision (no final newline) */
                       "0.75,0,0,0,0.123456789012345,0,0,359.99999999,-12.3456789012345,0,179.99999";
    oc_path *p = NULL;
    char err[256] = "";
    assert_int_equal(oc_path_parse(text, strlen(text), "mem", &p, err, sizeof err), OCEAN_OK);
    assert_non_null(p);
    assert_int_equal(p->count, 4);
    /* velocity, angles and fov are kept as the floats CAMERA carries */
    assert_true(p->pts[3].vel[0] == (double)0.123456789012345f && p->pts[3].yaw_deg == 360.0 &&
                p->pts[3].pitch_deg == (double)-12.3456789012345f && p->pts[3].fov_deg == (double)179.99999f);
    assert_true(p->pts[0].t == 0 && p->pts[0].pos[0] == 1 && p->pts[0].pos[2] == 3 && p->pts[0].fov_deg == 60);
    assert_true(p->pts[0].vel[1] == 5 && p->pts[0].yaw_deg == 7 && p->pts[0].roll_deg == 9);
    assert_true(p->pts[1].pos[0] == -1000 && p->pts[1].pos[2] == 125 && p->pts[1].pitch_deg == -10);
    assert_true(p->pts[1].fov_deg == 45.5);
    assert_true(p->pts[0].viewport_w == 1280 && p->pts[0].viewport_h == 720);

    /* write -> parse is lossless */
    char *buf = NULL;
    size_t blen = 0;
    FILE *f = open_memstream(&buf, &blen);
    assert_int_equal(oc_path_write(p, f), OCEAN_OK);
    fclose(f);
    oc_path *q = NULL;
    assert_int_equal(oc_path_parse(buf, blen, "again", &q, err, sizeof err), OCEAN_OK);
    assert_int_equal(q->count, p->count);
    assert_memory_equal(q->pts, p->pts, p->count * sizeof *p->pts);

    /* the daemon's recording format, as server/RECORDING.md shows it */
    const char *rec = "# oceand camera path v1\n# client 7 scene ship-bridge mode live\n"
                      "t,x,y,z,vx,vy,vz,yaw_deg,pitch_deg,roll_deg,fov_y_deg,viewport_w,viewport_h\n"
                      "12.033333333333333,0,25,0,8,0,0,0,-5,0,60,1280,720\n"
                      "12.066666666666666,0.266667,25,0,8,0,0,0,-5,0,60,640,480\n";
    oc_path *r = NULL;
    assert_int_equal(oc_path_parse(rec, strlen(rec), "rec", &r, err, sizeof err), OCEAN_OK);
    assert_int_equal(r->count, 2);
    assert_true(r->pts[0].t == 12.033333333333333 && r->pts[1].pos[0] == 0.266667);
    proto_camera cam;
    oc_path_camera(&r->pts[1], &cam);
    assert_true(cam.pos[0] == 0.266667 && cam.render_time == 12.066666666666666 && cam.viewport_w == 640);
    assert_true(cam.viewport_h == 480 && cam.vel[0] == 8.0f && cam.pitch_deg == -5.0f);
    oc_path_destroy(r);
    /* the CAMERA bounds, which the daemon records, are the path's:
     * |x|, |z| <= 1e10, |y| <= 1e7 (the reader stopped at 1e9 and 1e6) */
    const char *far = "t,x,y,z,vx,vy,vz,yaw,pitch,roll,fov\n"
                      "0,-1e10,1e7,1e10,0,0,0,0,0,0,60\n"
                      "1,9999999999.5,-1e7,-2e9,0,0,0,0,0,0,60\n";
    assert_int_equal(oc_path_parse(far, strlen(far), "far", &r, err, sizeof err), OCEAN_OK);
    assert_true(r->pts[0].pos[0] == -1e10 && r->pts[0].pos[1] == 1e7 && r->pts[0].pos[2] == 1e10);
    oc_path_camera(&r->pts[1], &cam);
    proto_msg cm;
    proto_msg_init(&cm, PROTO_CAMERA);
    cm.u.camera = cam;
    proto_buf cb;
    proto_buf_init(&cb, 0);
    assert_int_equal(proto_encode(&cb, &cm, err, sizeof err), OCEAN_OK);   /* the protocol takes it */
    proto_buf_free(&cb);
    oc_path_destroy(r);
    /* segments: live t is the clock, replay t the client's render_time in
     * its order, so it may go back there and at a change of mode (the
     * daemon wrote such files and the reader refused them) */
    const char *seg = "# oceand camera path v1\n"
                      "t,x,y,z,vx,vy,vz,yaw,pitch,roll,fov\n"
                      "# subscribed at 300: mode live\n"
                      "300.1,0,0,0,0,0,0,0,0,0,60\n"
                      "# subscribed at 301: mode replay\n"
                      "5,0,0,0,0,0,0,0,0,0,60\n"
                      "2,0,0,0,0,0,0,0,0,0,60\n"
                      "# subscribed at 302: mode live\n"
                      "302.1,0,0,0,0,0,0,0,0,0,60\n";
    assert_int_equal(oc_path_parse(seg, strlen(seg), "seg", &r, err, sizeof err), OCEAN_OK);
    assert_int_equal(r->count, 4);
    assert_false(r->monotonic);
    assert_int_equal(r->back_line, 6);
    assert_true(p->monotonic);
    /* written back, it reads back (the writer marks a replay segment) */
    char *sbuf = NULL;
    size_t slen = 0;
    FILE *sf = open_memstream(&sbuf, &slen);
    assert_int_equal(oc_path_write(r, sf), OCEAN_OK);
    fclose(sf);
    oc_path *r2 = NULL;
    if (oc_path_parse(sbuf, slen, "seg2", &r2, err, sizeof err) != OCEAN_OK) fail_msg("%s", err);
    assert_memory_equal(r2->pts, r->pts, r->count * sizeof *r->pts);
    oc_path_destroy(r2);
    free(sbuf);
    oc_path_destroy(r);
    oc_path_camera(&p->pts[1], &cam);
    assert_true(cam.pos[0] == -1000 && cam.render_time == 0.5 && cam.viewport_w == 1280);
    assert_true(cam.fov_y_deg == 45.5f);
    free(buf);
    oc_path_destroy(q);
    oc_path_destroy(p);
    oc_path_destroy(NULL);
}

static void path_bad(void **state)
{
    (void)state;
    const char *H = "t,x,y,z,vx,vy,vz,yaw,pitch,roll,fov\n";
    struct {
        const char *body, *needle;
        int with_header;
    } bad[] = {
        {"", "no header", 0},
        {"t,x,y,z\n0,0,0,0\n", "p:1: expected the header", 0},
        {"# c\nx,t,y,z,vx,vy,vz,yaw,pitch,roll,fov\n", "p:2: expected the header", 0},
        {"", "no camera reports", 1},
        {"0,0,0,0,0,0,0,0,0,0\n", "p:2: expected 11 fields as the header says, got 10", 1},
        {"0,0,0,0,0,0,0,0,0,0,60,1\n", "p:2: expected 11 fields as the header says, got more than 11", 1},
        {"0,0,0,0,0,0,0,0,0,0,60\n# x\n1,0,abc,0,0,0,0,0,0,0,60\n", "p:4: field y \"abc\" is not a number", 1},
        {"0,0,,0,0,0,0,0,0,0,60\n", "p:2: field y is empty", 1},
        {"0,0,0,0,0,0,0,0,0,0,nan\n", "p:2: field fov_y_deg is not a finite", 1},
        {"0,0,0,0,0,0,0,0,0,0,180\n", "p:2: field fov_y_deg outside", 1},
        /* 180.0f on the wire, which the server refuses (it was accepted and
         * written back as "180", which this reader refused) */
        {"0,0,0,0,0,0,0,0,0,0,179.9999999999\n", "p:2: field fov_y_deg outside", 1},
        {"0,0,0,0,0,0,0,0,0,0,0\n", "p:2: field fov_y_deg outside", 1},
        {"0,1.0000001e10,0,0,0,0,0,0,0,0,60\n", "p:2: field x beyond +-1e10 m", 1},
        {"0,0,0,-2e10,0,0,0,0,0,0,60\n", "p:2: field z beyond +-1e10 m", 1},
        {"0,0,2e7,0,0,0,0,0,0,0,60\n", "p:2: field y beyond +-1e7 m", 1},
        {"0,0,0,0,0,0,0,0,0,0,60\n1,0,0,0,0,0,0,0,0,0,60\n0.5,0,0,0,0,0,0,0,0,0,60\n", "p:4: t 0.5 goes back", 1},
        /* a live segment never goes back */
        {"# subscribed at 1: mode replay\n5,0,0,0,0,0,0,0,0,0,60\n# subscribed at 6: mode live\n6,0,0,0,0,0,0,0,0,0,60\n"
         "5.5,0,0,0,0,0,0,0,0,0,60\n", "p:6: t 5.5 goes back", 1},
        {"0,0,0,0,0,0,0,0,0,0,60\n1,0,0,0,0,0,0,0,0,0,inf\n", "p:3: field fov_y_deg is not a finite", 1},
        {"1e999,0,0,0,0,0,0,0,0,0,60\n", "p:2: field t \"1e999\" is not a number", 1},
        {"# oceand camera path v2\n" "t,x,y,z,vx,vy,vz,yaw,pitch,roll,fov\n0,0,0,0,0,0,0,0,0,0,60\n", "p:1: camera path format version 2", 0},
        {"t,x,y,z,vx,vy,vz,yaw_deg,pitch_deg,roll_deg,fov_y_deg,viewport_w\n", "p:1: expected the header", 0},
        {"t,x,y,z,vx,vy,vz,yaw_deg,pitch_deg,roll_deg,fov_y_deg,viewport_w,viewport_h\n0,0,0,0,0,0,0,0,0,0,60,0,720\n", "p:2: field viewport_w must be an integer", 0},
        {"t,x,y,z,vx,vy,vz,yaw_deg,pitch_deg,roll_deg,fov_y_deg,viewport_w,viewport_h\n0,0,0,0,0,0,0,0,0,0,60,1.5,720\n", "p:2: field viewport_w must be an integer", 0},
        {"t,x,y,z,vx,vy,vz,yaw_deg,pitch_deg,roll_deg,fov_y_deg,viewport_w,viewport_h\n0,0,0,0,0,0,0,0,0,0,60,640\n", "p:2: expected 13 fields", 0},
        /* version lines are exact ("v1x", "v01" read as v1) */
        {"# oceand camera path v1x\n", "p:1: malformed version line", 0},
        {"# oceand camera path v01\n", "p:1: malformed version line", 0},
        {"# oceand camera path\n", "p:1: malformed version line", 0},
        /* decimal numbers only ("0x10" read as 16) */
        {"0,0x10,0,0,0,0,0,0,0,0,60\n", "p:2: field x \"0x10\" is not a number", 1},
        /* CAMERA's orientation bounds, not +-3600: replay could not encode them */
        {"0,0,0,0,0,0,0,361,0,0,60\n", "p:2: field yaw_deg beyond +-360 degrees", 1},
        {"0,0,0,0,0,0,0,0,-91,0,60\n", "p:2: field pitch_deg beyond +-90 degrees", 1},
        {"0,0,0,0,0,0,0,0,0,180.5,60\n", "p:2: field roll_deg beyond +-180 degrees", 1},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char text[512];
        snprintf(text, sizeof text, "%s%s", bad[i].with_header ? H : "", bad[i].body);
        oc_path *p = (oc_path *)1;
        char err[256] = "";
        ocean_result r = oc_path_parse(text, strlen(text), "p", &p, err, sizeof err);
        if (r == OCEAN_OK || p != NULL || !strstr(err, bad[i].needle)) {
            print_error("case %zu: result %d, message \"%s\" (wanted \"%s\")\n", i, r, err, bad[i].needle);
            fail();
        }
    }
    /* the offending text is quoted */
    const char *t2 = "t,x,y,z,vx,vy,vz,yaw,pitch,roll,fov\n0,0,0,0,0,0,0,0,0,0,999\n";
    oc_path *p;
    char err[256];
    assert_int_not_equal(oc_path_parse(t2, strlen(t2), "f.csv", &p, err, sizeof err), OCEAN_OK);
    assert_non_null(strstr(err, "\"0,0,0,0,0,0,0,0,0,0,999\""));
    /* ... with its control bytes escaped: a path file is text its reader may
     * not have written, and `ocean-client replay` prints the message to a
     * terminal (an ESC sequence in a field, a DEL, a bidi override in the
     * header were quoted raw; fuzz_path found the DEL) */
    const char *t3[] = {"t,x,y,z,vx,vy,vz,yaw,pitch,roll,fov\n0,0,0,0,0,0,0,0,-10,0,60\x7f\n",
                        "t,x,y,z,vx,vy,vz,yaw,pitch,roll,fov\n0,\x1b]2;pwned\x07,0,0,0,0,0,0,0,0,60\n",
                        "t,x,y\xe2\x80\xae,z\n",
                        "# oceand camera path v1\x1b[2J\n"};
    const char *want[] = {"60\\x7F\"", "\\x1B]2;pwned\\x07", "y\\u202E,z", "v1\\x1B[2J"};
    for (size_t i = 0; i < sizeof t3 / sizeof t3[0]; i++) {
        assert_int_not_equal(oc_path_parse(t3[i], strlen(t3[i]), "f.csv", &p, err, sizeof err), OCEAN_OK);
        for (const char *c = err; *c; c++)
            if ((unsigned char)*c < 0x20 || *c == 0x7f || (c[0] == '\xe2' && c[1] == '\x80' && c[2] == '\xae'))
                fail_msg("case %zu: a control byte 0x%02x quoted raw in \"%s\"", i, (unsigned char)*c, err);
        if (!strstr(err, want[i])) fail_msg("case %zu: \"%s\" does not show %s", i, err, want[i]);
    }
    /* a missing file is reported with its name */
    assert_int_equal(oc_path_load("/nonexistent/x.csv", &p, err, sizeof err), OCEAN_ENOTFOUND);
    assert_non_null(strstr(err, "/nonexistent/x.csv"));
    /* a NULL text says so (the message was empty) */
    err[0] = 0;
    assert_int_equal(oc_path_parse(NULL, 10, "f.csv", &p, err, sizeof err), OCEAN_EINVAL);
    assert_non_null(strstr(err, "text is NULL"));
}

/* ========================================================= frame stores */

static char tmpdir[256];

static void make_tmpdir(void)
{
    if (tmpdir[0])
        return;
    snprintf(tmpdir, sizeof tmpdir, "/tmp/oc_test_client.XXXXXX");
    assert_non_null(mkdtemp(tmpdir));
}

static void tmp_path(char *out, size_t n, const char *name)
{
    make_tmpdir();
    snprintf(out, n, "%s/%s", tmpdir, name);
}

/* Encodes a FRAME with one f32 tile whose samples depend on k. */
static void make_frame(proto_buf *b, uint32_t seq, double t, float k)
{
    float planes[16];
    for (int i = 0; i < 16; i++)
        planes[i] = k + 0.25f * (float)i;
    proto_buf pay;
    proto_buf_init(&pay, 0);
    assert_int_equal(proto_tile_encode(PROTO_CODEC_F32, NULL, 4, 4, PROTO_CH_HEIGHT, planes, &pay, NULL,
                                       NULL, 0),
                     OCEAN_OK);
    proto_tile tile = {0};
    tile.codec = PROTO_CODEC_F32;
    tile.channels = PROTO_CH_HEIGHT;
    tile.width = tile.height = 4;
    tile.spacing = 1.0;
    tile.payload = proto_buf_data(&pay);
    tile.payload_len = (uint32_t)proto_buf_len(&pay);
    proto_msg m;
    proto_msg_init(&m, PROTO_FRAME);
    m.hdr.seq = seq;
    m.hdr.sim_time = t;
    m.u.frame.cutoff_k = 1.5;
    m.u.frame.camera_seq = PROTO_NO_CAMERA;
    m.u.frame.tick = (uint32_t)(t * 10);
    m.u.frame.tile_count = 1;
    m.u.frame.tiles = &tile;
    char err[256];
    assert_int_equal(proto_encode(b, &m, err, sizeof err), OCEAN_OK);
    proto_buf_free(&pay);
}

static void make_hello(proto_buf *b, uint32_t client_id)
{
    proto_msg m;
    proto_msg_init(&m, PROTO_HELLO);
    m.u.hello.client_id = client_id;
    m.u.hello.codecs = 1;
    m.u.hello.mesh_kinds = 1;
    m.u.hello.effects = 1;
    m.u.hello.cutoff_policies = 1;
    m.u.hello.modes = 3;
    m.u.hello.max_message = 1 << 20;
    m.u.hello.max_query_points = 100;
    m.u.hello.max_tile_size = 256;
    m.u.hello.max_lod_levels = 4;
    m.u.hello.max_layers = 1;
    m.u.hello.tick_rate_hz = 30;
    m.u.hello.max_frame_rate_hz = 60;
    m.u.hello.sea.depth_m = 1000;
    m.u.hello.sea.wind_u10 = 10;
    m.u.hello.sea.fetch_m = 1e5;
    m.u.hello.sea.choppiness = 1;
    m.u.hello.sea.phillips_a = 1;
    snprintf(m.u.hello.server_version, sizeof m.u.hello.server_version, "fake");
    char err[256];
    ocean_result r = proto_encode(b, &m, err, sizeof err);
    if (r != OCEAN_OK)
        print_error("hello: %s\n", err);
    assert_int_equal(r, OCEAN_OK);
}

/* Writes a store: a HELLO with client id `hello_id`, then n frames; frame
 * `bad_frame` (if >= 0) gets a different value; seq numbers offset by
 * seq0 (must not matter). */
static void write_store(const char *path, uint32_t hello_id, int n, int bad_frame, uint32_t seq0)
{
    oc_store_writer *w;
    char err[256];
    assert_int_equal(oc_store_writer_open(path, &w, err, sizeof err), OCEAN_OK);
    proto_buf b;
    proto_buf_init(&b, 0);
    make_hello(&b, hello_id);
    assert_int_equal(oc_store_writer_append(w, 0.0, proto_buf_data(&b), proto_buf_len(&b)), OCEAN_OK);
    for (int i = 0; i < n; i++) {
        proto_buf_reset(&b);
        make_frame(&b, seq0 + (uint32_t)i, 0.1 * i, i == bad_frame ? 99.0f : (float)i);
        assert_int_equal(oc_store_writer_append(w, 0.01 * i + (double)hello_id, proto_buf_data(&b),
                                                proto_buf_len(&b)),
                         OCEAN_OK);
    }
    assert_int_equal(oc_store_writer_count(w), (uint64_t)n + 1);
    assert_int_equal(oc_store_writer_close(w), OCEAN_OK);
    proto_buf_free(&b);
}

static void store_round_trip(void **state)
{
    (void)state;
    char path[300];
    tmp_path(path, sizeof path, "rt.frames");
    oc_store_writer *w;
    char err[256];
    assert_int_equal(oc_store_writer_open(path, &w, err, sizeof err), OCEAN_OK);
    proto_buf b[3];
    for (int i = 0; i < 3; i++) {
        proto_buf_init(&b[i], 0);
        make_frame(&b[i], (uint32_t)i, 1.0 + i, (float)i);
        assert_int_equal(oc_store_writer_append(w, 0.5 * i, proto_buf_data(&b[i]), proto_buf_len(&b[i])), OCEAN_OK);
    }
    uint8_t tiny[8] = {0};
    assert_int_equal(oc_store_writer_append(w, 0, tiny, sizeof tiny), OCEAN_EINVAL);
    assert_int_equal(oc_store_writer_close(w), OCEAN_OK);

    oc_store_reader *r;
    assert_int_equal(oc_store_reader_open(path, &r, err, sizeof err), OCEAN_OK);
    for (int i = 0; i < 3; i++) {
        const uint8_t *m;
        size_t len;
        double t;
        assert_int_equal(oc_store_reader_next(r, &m, &len, &t, err, sizeof err), OCEAN_OK);
        assert_int_equal(len, proto_buf_len(&b[i]));
        assert_memory_equal(m, proto_buf_data(&b[i]), len);
        assert_true(t == 0.5 * i);
        proto_msg dm;
        assert_int_equal(proto_decode(m, len, &dm, err, sizeof err), OCEAN_OK);
        assert_int_equal(dm.hdr.type, PROTO_FRAME);
        assert_true(dm.hdr.sim_time == 1.0 + i);
        proto_msg_free(&dm);
    }
    const uint8_t *m;
    size_t len;
    assert_int_equal(oc_store_reader_next(r, &m, &len, NULL, err, sizeof err), OCEAN_ENOTFOUND);
    oc_store_reader_close(r);

    /* truncation inside the last record is reported with its index */
    struct stat st;
    assert_int_equal(stat(path, &st), 0);
    assert_int_equal(truncate(path, st.st_size - 3), 0);
    assert_int_equal(oc_store_reader_open(path, &r, err, sizeof err), OCEAN_OK);
    for (int i = 0; i < 2; i++)
        assert_int_equal(oc_store_reader_next(r, &m, &len, NULL, err, sizeof err), OCEAN_OK);
    assert_int_equal(oc_store_reader_next(r, &m, &len, NULL, err, sizeof err), OCEAN_ETRUNC);
    assert_non_null(strstr(err, "record 2"));
    oc_store_reader_close(r);

    /* not a store; wrong version */
    FILE *f = fopen(path, "wb");
    fputs("hello, world, this is text", f);
    fclose(f);
    assert_int_equal(oc_store_reader_open(path, &r, err, sizeof err), OCEAN_EFORMAT);
    f = fopen(path, "wb");
    fwrite("OCFRAMES\x02\0\0\0\0\0\0\0", 1, 16, f);
    fclose(f);
    assert_int_equal(oc_store_reader_open(path, &r, err, sizeof err), OCEAN_EVERSION);
    for (int i = 0; i < 3; i++)
        proto_buf_free(&b[i]);
}

static void store_compare(void **state)
{
    (void)state;
    char a[300], b[300], c[300], d[300];
    tmp_path(a, sizeof a, "a.frames");
    tmp_path(b, sizeof b, "b.frames");
    tmp_path(c, sizeof c, "c.frames");
    tmp_path(d, sizeof d, "d.frames");
    /* a and b differ only in HELLO client id, receive times and seq: identical */
    write_store(a, 1, 5, -1, 0);
    write_store(b, 2, 5, -1, 1000);
    write_store(c, 1, 5, 3, 0);    /* frame 3 differs */
    write_store(d, 1, 4, -1, 0);   /* one frame fewer */
    oc_store_diff diff;
    char err[256];
    assert_int_equal(oc_store_compare(a, b, 0, &diff, err, sizeof err), OCEAN_OK);
    assert_int_equal(diff.identical, 1);
    assert_int_equal(diff.compared, 5);
    assert_int_equal(diff.first_index, -1);

    assert_int_equal(oc_store_compare(a, c, 0, &diff, err, sizeof err), OCEAN_OK);
    assert_int_equal(diff.identical, 0);
    assert_int_equal(diff.first_index, 3);
    assert_true(diff.first_offset > 32 + 56);
    assert_non_null(strstr(diff.what, "FRAME tile or mesh records"));

    assert_int_equal(oc_store_compare(a, d, 0, &diff, err, sizeof err), OCEAN_OK);
    assert_int_equal(diff.identical, 0);
    assert_int_equal(diff.count_a, 5);
    assert_int_equal(diff.count_b, 4);

    /* comparing HELLOs too sees the client id */
    assert_int_equal(oc_store_compare(a, b, OC_STORE_TYPE_BIT(PROTO_HELLO), &diff, err, sizeof err), OCEAN_OK);
    assert_int_equal(diff.identical, 0);
    assert_int_equal(diff.first_index, 0);

    /* a missing file is an error, not a verdict */
    assert_int_equal(oc_store_compare(a, "/nonexistent.frames", 0, &diff, err, sizeof err), OCEAN_ENOTFOUND);
}

/* ====================================================== the fake server */

typedef struct fake_conn {
    struct fake_conn *next;
    struct lws *wsi;
    proto_buf out[64];
    int out_head, out_len;
    uint32_t seq;
    int subscribed, replay, sent_topology;
    int mesh_qz;          /* layout 0 with mesh_codec qz: has_mesh 2 frames */
    uint32_t tick;
    uint8_t *rx;
    size_t rx_len;
    int close_after;      /* close once the queued messages are written */
} fake_conn;

typedef struct fake_server {
    struct lws_context *ctx;
    pthread_t thread;
    volatile int stop;
    int port;
    fake_conn *conns;     /* service thread only */
    lws_sorted_usec_list_t sul;
    double t;             /* live sim time */
    int frames_per_tick;
    proto_sea sea;
    int connections_seen;
    int cameras_seen;     /* CAMERAs received (__atomic: read by the test) */
    int last_cam_x;       /* pos[0] of the latest, as an int */
    int messages_written; /* lws_write calls that succeeded (__atomic) */
} fake_server;

static void fake_queue(fake_conn *fc, proto_msg *m)
{
    if (fc->out_len == 64)
        return;
    proto_buf *b = &fc->out[(fc->out_head + fc->out_len) % 64];
    proto_buf_init(b, LWS_PRE);
    m->hdr.seq = fc->seq++;
    char err[256];
    if (proto_encode(b, m, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "fake server encode: %s\n", err);
        proto_buf_free(b);
        return;
    }
    fc->out_len++;
    lws_callback_on_writable(fc->wsi);
}

/* Queues arbitrary bytes as one message (for hostile-server tests). */
static void fake_queue_raw(fake_conn *fc, const void *bytes, size_t len)
{
    if (fc->out_len == 64)
        return;
    proto_buf *b = &fc->out[(fc->out_head + fc->out_len) % 64];
    proto_buf_init(b, LWS_PRE);
    if (proto_buf_append(b, bytes, len) != OCEAN_OK) {
        proto_buf_free(b);
        return;
    }
    fc->out_len++;
    lws_callback_on_writable(fc->wsi);
}

/* A frame at time t: a 16x16 qz tile and an 8x8 f32 tile with height
 * sin(x + t), and a 4-vertex mesh (topology sent first). */
static const uint32_t fake_idx[6] = {0, 1, 2, 2, 1, 3};

static void fake_frame(fake_server *s, fake_conn *fc, double t, uint32_t camera_seq)
{
    if (!fc->sent_topology) {
        const uint32_t *idx = fake_idx;
        static const float morph[4] = {0, 0, 0.5f, 1};
        static const uint8_t lev[4] = {0, 0, 0, 0};
        proto_msg m;
        proto_msg_init(&m, PROTO_MESH_TOPOLOGY);
        m.hdr.sim_time = t;
        m.u.topology.mesh_id = 7;
        m.u.topology.mesh_kind = PROTO_MESH_CONCENTRIC;
        m.u.topology.lod_levels = 1;
        m.u.topology.vertex_count = 4;
        m.u.topology.index_count = 6;
        m.u.topology.indices = idx;
        m.u.topology.morph = morph;
        m.u.topology.level = lev;
        fake_queue(fc, &m);
        fc->sent_topology = 1;
    }
    float h16[16 * 16], h8[8 * 8];
    for (int i = 0; i < 16 * 16; i++)
        h16[i] = (float)sin(0.3 * (i % 16) + t);
    for (int i = 0; i < 8 * 8; i++)
        h8[i] = (float)sin(0.5 * (i % 8) + t);
    proto_buf p16, p8;
    proto_buf_init(&p16, 0);
    proto_buf_init(&p8, 0);
    proto_codec_params cp;
    proto_codec_params_default(&cp);
    double e16 = 0;
    proto_tile_encode(PROTO_CODEC_QZ, &cp, 16, 16, PROTO_CH_HEIGHT, h16, &p16, &e16, NULL, 0);
    proto_tile_encode(PROTO_CODEC_F32, &cp, 8, 8, PROTO_CH_HEIGHT, h8, &p8, NULL, NULL, 0);
    proto_tile tiles[2];
    memset(tiles, 0, sizeof tiles);
    tiles[0].codec = PROTO_CODEC_QZ;
    tiles[0].channels = PROTO_CH_HEIGHT;
    tiles[0].width = tiles[0].height = 16;
    tiles[0].spacing = 2;
    tiles[0].error_bound = (float)e16;
    tiles[0].payload = proto_buf_data(&p16);
    tiles[0].payload_len = (uint32_t)proto_buf_len(&p16);
    tiles[1].codec = PROTO_CODEC_F32;
    tiles[1].channels = PROTO_CH_HEIGHT;
    tiles[1].level = 1;
    tiles[1].width = tiles[1].height = 8;
    tiles[1].spacing = 4;
    tiles[1].payload = proto_buf_data(&p8);
    tiles[1].payload_len = (uint32_t)proto_buf_len(&p8);
    float pos[12] = {0, (float)t, 0, 1, 0, 0, 0, 0, 1, 1, 0, 1};
    proto_msg m;
    proto_msg_init(&m, PROTO_FRAME);
    m.hdr.sim_time = t;
    m.u.frame.cutoff_k = INFINITY;
    m.u.frame.e_error = 0.01;
    m.u.frame.camera_seq = camera_seq;
    m.u.frame.tick = fc->tick++;
    m.u.frame.tile_count = 2;
    m.u.frame.tiles = tiles;
    m.u.frame.has_mesh = 1;
    m.u.frame.mesh.mesh_id = 7;
    m.u.frame.mesh.vertex_count = 4;
    m.u.frame.mesh.positions = pos;
    proto_buf qz;
    proto_buf_init(&qz, 0);
    if (fc->mesh_qz) {
        /* the positions as MESH_VERTICES_QZ at the default accuracy; at
         * t = 666 for a mesh_id whose topology was never sent */
        uint32_t refs[12];
        proto_codec_ctx *cx = NULL;
        assert_int_equal(proto_codec_ctx_create(&cx), OCEAN_OK);
        assert_int_equal(proto_mesh_qz_refs(fake_idx, 6, 4, refs), OCEAN_OK);
        assert_int_equal(proto_mesh_qz_encode(cx, PROTO_ACCURACY_DEFAULT, 4, pos, refs, &qz, NULL, NULL, 0), OCEAN_OK);
        proto_codec_ctx_destroy(cx);
        m.u.frame.has_mesh = 2;
        m.u.frame.mesh.qz = proto_buf_data(&qz);
        m.u.frame.mesh.qz_len = (uint32_t)proto_buf_len(&qz);
        if (t == 666)
            m.u.frame.mesh.mesh_id = 99;
    }
    fake_queue(fc, &m);
    proto_buf_free(&qz);
    proto_buf_free(&p16);
    proto_buf_free(&p8);
    (void)s;
}

static void fake_error(fake_conn *fc, const proto_header *h, ocean_result code, const char *text)
{
    proto_msg m;
    proto_msg_init(&m, PROTO_ERROR);
    m.u.error.code = (uint16_t)code;
    m.u.error.offending_type = h->type;
    m.u.error.offending_seq = h->seq;
    snprintf(m.u.error.message, sizeof m.u.error.message, "%s", text);
    fake_queue(fc, &m);
}

static void fake_handle(fake_server *s, fake_conn *fc, const uint8_t *buf, size_t len)
{
    proto_msg m;
    char err[256];
    if (proto_decode(buf, len, &m, err, sizeof err) != OCEAN_OK) {
        fake_error(fc, &m.hdr, OCEAN_EFORMAT, err);
        return;
    }
    switch (m.hdr.type) {
    case PROTO_SUBSCRIBE:
        fc->subscribed = 1;
        fc->replay = m.u.subscribe.mode == PROTO_MODE_REPLAY;
        fc->mesh_qz = m.u.subscribe.layout == PROTO_LAYOUT_WORLD && m.u.subscribe.mesh_codec == PROTO_MESH_CODEC_QZ;
        break;
    case PROTO_CAMERA:
        __atomic_store_n(&s->last_cam_x, (int)m.u.camera.pos[0], __ATOMIC_SEQ_CST);
        __atomic_add_fetch(&s->cameras_seen, 1, __ATOMIC_SEQ_CST);
        if (fc->replay)
            fake_frame(s, fc, m.u.camera.render_time, m.hdr.seq);
        break;
    case PROTO_QUERY: {
        if (m.u.query.points[0] == 777) {
            /* BYE, then the connection closes */
            proto_msg b;
            proto_msg_init(&b, PROTO_BYE);
            b.u.bye.reason = 2;
            snprintf(b.u.bye.message, sizeof b.u.bye.message, "fake server shutting down");
            fake_queue(fc, &b);
            fc->close_after = 1;
            break;
        }
        if (m.u.query.points[0] == 666) {
            /* hostile: a message with a bad magic, then one lying about its
             * length, then a valid answer */
            uint8_t junk[64];
            memset(junk, 0xAB, sizeof junk);
            fake_queue_raw(fc, junk, sizeof junk);
            proto_msg e;
            proto_msg_init(&e, PROTO_BYE);
            proto_buf eb;
            proto_buf_init(&eb, 0);
            if (proto_encode(&eb, &e, err, sizeof err) == OCEAN_OK) {
                proto_st32(proto_buf_data(&eb) + 12, 1000);   /* length lies */
                fake_queue_raw(fc, proto_buf_data(&eb), proto_buf_len(&eb));
            }
            proto_buf_free(&eb);
        }
        if (m.u.query.count > 100) {
            fake_error(fc, &m.hdr, OCEAN_ETOOBIG, "too many points");
            break;
        }
        proto_query_sample smp[100];
        memset(smp, 0, sizeof smp);
        for (uint32_t i = 0; i < m.u.query.count; i++) {
            smp[i].height = (float)(m.u.query.points[2 * i] + 0.5 * m.u.query.points[2 * i + 1]);
            smp[i].normal[1] = 1;
            smp[i].error_bound = 0.001f;
        }
        proto_msg r;
        proto_msg_init(&r, PROTO_QUERY_RESULT);
        r.hdr.sim_time = s->t;
        r.u.result.query_id = m.u.query.query_id;
        r.u.result.count = m.u.query.count;
        r.u.result.t = m.u.query.at_time ? m.u.query.t : s->t;
        r.u.result.samples = smp;
        fake_queue(fc, &r);
        break;
    }
    case PROTO_SEA_STATE:
        if (strcmp(m.u.sea_state.token, "secret") != 0) {
            fake_error(fc, &m.hdr, OCEAN_EAUTH, "bad admin token");
            break;
        }
        s->sea = m.u.sea_state.sea;
        for (fake_conn *k = s->conns; k; k = k->next) {
            proto_msg a;
            proto_msg_init(&a, PROTO_SEA_STATE);
            a.u.sea_state.op = PROTO_SEA_ANNOUNCE;
            a.u.sea_state.effective_time = m.u.sea_state.effective_time;
            a.u.sea_state.sea = s->sea;
            fake_queue(k, &a);
        }
        break;
    default:
        break;
    }
    proto_msg_free(&m);
}

static void fake_tick(lws_sorted_usec_list_t *sul)
{
    fake_server *s = lws_container_of(sul, fake_server, sul);
    s->t += 0.02;
    for (fake_conn *k = s->conns; k; k = k->next)
        if (k->subscribed && !k->replay)
            fake_frame(s, k, s->t, PROTO_NO_CAMERA);
    lws_sul_schedule(s->ctx, 0, &s->sul, fake_tick, 20 * LWS_US_PER_MS);
}

static int fake_cb(struct lws *wsi, enum lws_callback_reasons reason, void *user, void *in, size_t len)
{
    struct lws_context *ctx = lws_get_context(wsi);
    fake_server *s = ctx ? lws_context_user(ctx) : NULL;
    fake_conn *fc = user;
    switch (reason) {
    case LWS_CALLBACK_ESTABLISHED: {
        memset(fc, 0, sizeof *fc);
        fc->wsi = wsi;
        fc->next = s->conns;
        s->conns = fc;
        s->connections_seen++;
        proto_msg m;
        proto_msg_init(&m, PROTO_HELLO);
        m.hdr.sim_time = s->t;
        m.u.hello.codecs = (1u << PROTO_CODEC_COUNT_) - 1;
        m.u.hello.mesh_kinds = 1;
        m.u.hello.effects = PROTO_FX_ALL;
        m.u.hello.cutoff_policies = 7;
        m.u.hello.modes = 3;
        m.u.hello.max_message = 1 << 20;
        m.u.hello.max_query_points = 100;
        m.u.hello.max_tile_size = 256;
        m.u.hello.max_lod_levels = 8;
        m.u.hello.max_layers = 1;
        m.u.hello.tick_rate_hz = 50;
        m.u.hello.max_frame_rate_hz = 60;
        m.u.hello.client_id = (uint32_t)s->connections_seen;
        m.u.hello.sea = s->sea;
        snprintf(m.u.hello.server_version, sizeof m.u.hello.server_version, "fake-1");
        fake_queue(fc, &m);
        break;
    }
    case LWS_CALLBACK_RECEIVE: {
        uint8_t *nb = realloc(fc->rx, fc->rx_len + len);
        if (!nb)
            return -1;
        fc->rx = nb;
        memcpy(fc->rx + fc->rx_len, in, len);
        fc->rx_len += len;
        if (lws_is_final_fragment(wsi) && !lws_remaining_packet_payload(wsi)) {
            fake_handle(s, fc, fc->rx, fc->rx_len);
            fc->rx_len = 0;
        }
        break;
    }
    case LWS_CALLBACK_SERVER_WRITEABLE:
        if (fc->out_len) {
            proto_buf *b = &fc->out[fc->out_head];
            int n = lws_write(wsi, proto_buf_data(b), proto_buf_len(b), LWS_WRITE_BINARY);
            proto_buf_free(b);
            fc->out_head = (fc->out_head + 1) % 64;
            fc->out_len--;
            if (n < 0)
                return -1;
            __atomic_add_fetch(&s->messages_written, 1, __ATOMIC_SEQ_CST);
            if (fc->out_len || fc->close_after)
                lws_callback_on_writable(wsi);
        } else if (fc->close_after) {
            lws_close_reason(wsi, LWS_CLOSE_STATUS_GOINGAWAY, (unsigned char *)"away", 4);
            return -1;
        }
        break;
    case LWS_CALLBACK_CLOSED:
        for (fake_conn **pp = &s->conns; *pp; pp = &(*pp)->next)
            if (*pp == fc) {
                *pp = fc->next;
                break;
            }
        while (fc->out_len) {
            proto_buf_free(&fc->out[fc->out_head]);
            fc->out_head = (fc->out_head + 1) % 64;
            fc->out_len--;
        }
        free(fc->rx);
        fc->rx = NULL;
        break;
    default:
        break;
    }
    return 0;
}

static const struct lws_protocols fake_protocols[] = {
    {"http-only", lws_callback_http_dummy, 0, 0, 0, NULL, 0},
    {PROTO_SUBPROTOCOL, fake_cb, sizeof(fake_conn), 65536, 0, NULL, 0},
    {NULL, NULL, 0, 0, 0, NULL, 0}
};

static void *fake_thread(void *arg)
{
    fake_server *s = arg;
    while (!s->stop)
        lws_service(s->ctx, 0);
    return NULL;
}

static void fake_stop_cb(lws_sorted_usec_list_t *sul) { (void)sul; }

static fake_server *fake_start_tls(const char *cert, const char *key);

static fake_server *fake_start(void) { return fake_start_tls(NULL, NULL); }

/* The fake server; with cert and key (PEM files) it serves wss:// only. */
static fake_server *fake_start_tls(const char *cert, const char *key)
{
    fake_server *s = calloc(1, sizeof *s);
    assert_non_null(s);
    s->sea.depth_m = 1000;
    s->sea.wind_u10 = 10;
    s->sea.fetch_m = 1e5;
    s->sea.phillips_a = 1;
    s->sea.choppiness = 1;
    s->sea.seed = 1;
    s->t = 100.0;
    struct lws_context_creation_info info;
    memset(&info, 0, sizeof info);
    info.port = 0;
    info.iface = "127.0.0.1";
    info.protocols = fake_protocols;
    info.gid = -1;
    info.uid = -1;
    info.user = s;
    if (cert) {
        info.options = LWS_SERVER_OPTION_DO_SSL_GLOBAL_INIT;
        info.ssl_cert_filepath = cert;
        info.ssl_private_key_filepath = key;
    }
    lws_set_log_level(LLL_ERR, NULL);
    s->ctx = lws_create_context(&info);
    assert_non_null(s->ctx);
    s->port = lws_get_vhost_listen_port(lws_get_vhost_by_name(s->ctx, "default"));
    assert_true(s->port > 0);
    lws_sul_schedule(s->ctx, 0, &s->sul, fake_tick, 20 * LWS_US_PER_MS);
    assert_int_equal(pthread_create(&s->thread, NULL, fake_thread, s), 0);
    return s;
}

static void fake_stop(fake_server *s)
{
    s->stop = 1;
    lws_sorted_usec_list_t wake;
    memset(&wake, 0, sizeof wake);
    (void)fake_stop_cb;
    lws_cancel_service(s->ctx);
    pthread_join(s->thread, NULL);
    lws_context_destroy(s->ctx);
    free(s);
}

static void fake_url(fake_server *s, char *out, size_t n) { snprintf(out, n, "ws://127.0.0.1:%d/", s->port); }

/* ============================================================ net tests */

/* Argument errors say which argument, and *out is NULL on every failure
 * (a NULL o was "no options" and left *out as it was). */
static void create_argument_errors(void **state)
{
    (void)state;
    oc_options o;
    oc_options_default(&o);
    o.url = "ws://127.0.0.1:9/";
    char err[256];
    oc_client *c = (oc_client *)&o; /* not NULL: must be cleared */
    assert_int_equal(oc_client_create(NULL, &c, err, sizeof err), OCEAN_EINVAL);
    assert_null(c);
    assert_non_null(strstr(err, "o is NULL"));
    assert_int_equal(oc_client_create(&o, NULL, err, sizeof err), OCEAN_EINVAL);
    assert_non_null(strstr(err, "out is NULL"));
    c = (oc_client *)&o;
    o.url = "http://nowhere/";
    assert_int_equal(oc_client_create(&o, &c, err, sizeof err), OCEAN_EINVAL);
    assert_null(c);
}

static void connect_refused(void **state)
{
    (void)state;
    /* a port nobody listens on: bind, learn, close */
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in a = {0};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    assert_int_equal(bind(fd, (struct sockaddr *)&a, sizeof a), 0);
    socklen_t al = sizeof a;
    getsockname(fd, (struct sockaddr *)&a, &al);
    int port = ntohs(a.sin_port);
    close(fd);
    char url[64];
    snprintf(url, sizeof url, "ws://127.0.0.1:%d/", port);
    oc_options o;
    oc_options_default(&o);
    o.url = url;
    oc_client *c = (oc_client *)1;
    char err[256] = "";
    ocean_result r = oc_connect(&o, 3000, &c, err, sizeof err);
    assert_int_equal(r, OCEAN_EIO);
    assert_null(c);
    assert_true(strlen(err) > 0);

    o.url = "http://x/";
    assert_int_equal(oc_connect(&o, 100, &c, err, sizeof err), OCEAN_EINVAL);
    assert_non_null(strstr(err, "scheme"));
}

/* A client connected to the fake server with the default options. */
static oc_client *fake_client(fake_server *s)
{
    char url[64], err[256] = "";
    fake_url(s, url, sizeof url);
    oc_options o;
    oc_options_default(&o);
    o.url = url;
    oc_client *c = NULL;
    ocean_result r = oc_connect(&o, 5000, &c, err, sizeof err);
    if (r != OCEAN_OK)
        print_error("connect: %s\n", err);
    assert_int_equal(r, OCEAN_OK);
    return c;
}

/* Layout 0 with the library's default mesh codec (qz): has_mesh 2 frames
 * reach the caller with float positions, decoded with the topology, each
 * within the bound the spec states (half the step f32(2a range_y), plus
 * the f32 rounding); a has_mesh 2 frame whose mesh_id names no topology
 * still arrives, without positions, counted as a decode error with the
 * reason. */
static void qz_mesh_frames(void **state)
{
    (void)state;
    fake_server *s = fake_start();
    char err[256] = "";
    oc_client *c = fake_client(s);
    proto_subscribe sub;
    oc_subscribe_default(&sub);
    assert_int_equal(sub.mesh_codec, PROTO_MESH_CODEC_QZ);
    sub.layout = PROTO_LAYOUT_WORLD;
    sub.mode = PROTO_MODE_REPLAY;
    assert_int_equal(oc_client_subscribe(c, &sub), OCEAN_OK);
    proto_camera cam;
    oc_camera_default(&cam);
    cam.render_time = 5;
    assert_int_equal(oc_client_send_camera(c, &cam, NULL), OCEAN_OK);
    oc_frame *f = NULL;
    assert_int_equal(oc_client_next_frame(c, 3000, &f), OCEAN_OK);
    assert_int_equal(f->info.has_mesh, 2);
    assert_non_null(f->topology);
    assert_non_null(f->info.mesh.positions);
    const float want[12] = {0, 5, 0, 1, 0, 0, 0, 0, 1, 1, 0, 1};
    double step = (double)(float)(2 * PROTO_ACCURACY_DEFAULT * 5.0);
    for (int i = 0; i < 12; i++)
        assert_true(fabs((double)f->info.mesh.positions[i] - want[i]) <= 0.5 * step + fabs(want[i]) * 0x1p-24);
    oc_frame_free(f);
    oc_client_stats st0, st1;
    oc_client_get_stats(c, &st0);
    cam.render_time = 666;
    assert_int_equal(oc_client_send_camera(c, &cam, NULL), OCEAN_OK);
    assert_int_equal(oc_client_next_frame(c, 3000, &f), OCEAN_OK);
    assert_int_equal(f->info.has_mesh, 2);
    assert_null(f->info.mesh.positions);
    oc_client_get_stats(c, &st1);
    assert_int_equal(st1.decode_errors, st0.decode_errors + 1);
    oc_client_last_error(c, err, sizeof err);
    assert_non_null(strstr(err, "mesh positions"));
    oc_frame_free(f);
    oc_client_destroy(c);
    fake_stop(s);
}

static void live_frames_and_queries(void **state)
{
    (void)state;
    fake_server *s = fake_start();
    char err[256] = "";
    ocean_result r;
    oc_client *c = fake_client(s);
    assert_int_equal(oc_client_state(c), OC_READY);
    proto_hello h;
    assert_int_equal(oc_client_hello(c, &h), OCEAN_OK);
    assert_string_equal(h.server_version, "fake-1");
    assert_true(h.tick_rate_hz == 50);

    proto_subscribe sub;
    oc_subscribe_default(&sub);
    sub.frame_rate_hz = 50;
    assert_int_equal(oc_client_subscribe(c, &sub), OCEAN_OK);
    proto_camera cam;
    oc_camera_default(&cam);
    assert_int_equal(oc_client_send_camera(c, &cam, NULL), OCEAN_OK);

    for (int i = 0; i < 5; i++) {
        oc_frame *f = NULL;
        r = oc_client_next_frame(c, 3000, &f);
        if (r != OCEAN_OK) {
            oc_client_last_error(c, err, sizeof err);
            oc_client_stats st;
            oc_client_get_stats(c, &st);
            print_error("next_frame: %s: %s (rx %llu frames %llu dec err %llu)\n", ocean_strerror(r), err,
                        (unsigned long long)st.messages_rx, (unsigned long long)st.frames_rx,
                        (unsigned long long)st.decode_errors);
        }
        assert_int_equal(r, OCEAN_OK);
        assert_non_null(f);
        assert_int_equal(f->info.tile_count, 2);
        assert_non_null(f->tiles[0].data);
        assert_non_null(f->tiles[1].data);
        double t = f->hdr.sim_time;
        /* f32 tile is exact, qz within its bound */
        for (int k = 0; k < 64; k++)
            assert_true(f->tiles[1].data[k] == (float)sin(0.5 * (k % 8) + t));
        for (int k = 0; k < 256; k++)
            assert_true(fabs(f->tiles[0].data[k] - (float)sin(0.3 * (k % 16) + t)) <=
                        f->tiles[0].info.error_bound * 1.0001 + 1e-6);
        assert_int_equal(f->info.has_mesh, 1);
        assert_non_null(f->topology);
        assert_int_equal(f->topology->index_count, 6);
        assert_true(f->info.mesh.positions[1] == (float)t);
        assert_true(f->raw_len > 32);
        assert_true(f->latency_ms >= 0 && f->latency_ms < 5000);
        oc_frame_free(f);
    }

    double xz[6] = {1, 2, 3, 4, -5, 10};
    oc_query_result q;
    r = oc_client_query(c, xz, 3, 1, 123.5, 30000, &q);
    assert_int_equal(r, OCEAN_OK);
    assert_int_equal(q.count, 3);
    assert_true(q.t == 123.5);
    assert_true(q.samples[0].height == 2.0f && q.samples[1].height == 5.0f && q.samples[2].height == 0.0f);
    oc_query_result_free(&q);

    /* the server refuses 101 points: its ERROR code comes back */
    double many[2 * 101];
    for (int i = 0; i < 202; i++)
        many[i] = i;
    r = oc_client_query(c, many, 101, 0, 0, 3000, &q);
    assert_int_equal(r, OCEAN_EINVAL);   /* refused locally: HELLO says 100 */
    assert_int_equal(oc_client_query(c, xz, 0, 0, 0, 100, &q), OCEAN_EINVAL);
    xz[1] = NAN;
    assert_int_equal(oc_client_query(c, xz, 3, 0, 0, 100, &q), OCEAN_EINVAL);

    /* sea state: wrong token -> EAUTH with the server's text; right -> announced */
    proto_sea sea;
    double et;
    assert_int_equal(oc_client_sea_state(c, &sea, &et), OCEAN_OK);
    assert_true(sea.wind_u10 == 10);
    sea.wind_u10 = 17;
    assert_int_equal(oc_client_sea_state_set(c, &sea, 200.0, "wrong", 3000), OCEAN_EAUTH);
    char msg[512];
    assert_int_equal(oc_client_last_error(c, msg, sizeof msg), OCEAN_EAUTH);
    assert_non_null(strstr(msg, "bad admin token"));
    assert_int_equal(oc_client_sea_state_set(c, &sea, 200.0, "secret", 3000), OCEAN_OK);
    assert_int_equal(oc_client_sea_state(c, &sea, &et), OCEAN_OK);
    assert_true(sea.wind_u10 == 17 && et == 200.0);

    oc_client_stats st;
    oc_client_get_stats(c, &st);
    assert_true(st.frames_rx >= 5);
    assert_int_equal(st.errors_rx, 1);
    assert_int_equal(st.decode_errors, 0);
    oc_client_destroy(c);
    fake_stop(s);
}

typedef struct async_ctx {
    int answered;
    ocean_result res;
    float h0;
    int frames;
} async_ctx;

static void on_answer(void *user, oc_client *c, ocean_result res, const oc_query_result *r)
{
    (void)c;
    async_ctx *a = user;
    a->res = res;
    if (r && r->count)
        a->h0 = r->samples[0].height;
    __atomic_store_n(&a->answered, 1, __ATOMIC_SEQ_CST);
}

static void on_frame_cb(void *user, oc_client *c, const oc_frame *f)
{
    (void)c;
    (void)f;
    async_ctx *a = user;
    __atomic_add_fetch(&a->frames, 1, __ATOMIC_SEQ_CST);
}

/* A shared loop on a library thread with several clients, callbacks, and
 * an async query. */
static void threaded_shared_loop(void **state)
{
    (void)state;
    fake_server *s = fake_start();
    char url[64];
    fake_url(s, url, sizeof url);
    oc_loop *l;
    char err[256];
    assert_int_equal(oc_loop_create(&l, err, sizeof err), OCEAN_OK);
    assert_int_equal(oc_loop_start(l), OCEAN_OK);
    assert_int_equal(oc_loop_service(l, 10), OCEAN_ESTATE);
    enum { N = 4 };
    oc_client *cs[N];
    async_ctx ac[N];
    memset(ac, 0, sizeof ac);
    for (int i = 0; i < N; i++) {
        oc_options o;
        oc_options_default(&o);
        o.url = url;
        o.loop = l;
        o.decode_tiles = 0;
        o.cb.user = &ac[i];
        o.cb.on_frame = on_frame_cb;
        assert_int_equal(oc_connect(&o, 5000, &cs[i], err, sizeof err), OCEAN_OK);
        proto_subscribe sub;
        oc_subscribe_default(&sub);
        assert_int_equal(oc_client_subscribe(cs[i], &sub), OCEAN_OK);
    }
    double xz[2] = {4, 2};
    for (int i = 0; i < N; i++)
        assert_int_equal(oc_client_query_async(cs[i], xz, 1, 0, 0, on_answer, &ac[i], NULL), OCEAN_OK);
    struct timespec ts = {0, 20 * 1000 * 1000};
    for (int w = 0; w < 250; w++) {
        int done = 1;
        for (int i = 0; i < N; i++)
            if (!__atomic_load_n(&ac[i].answered, __ATOMIC_SEQ_CST) || __atomic_load_n(&ac[i].frames, __ATOMIC_SEQ_CST) < 3)
                done = 0;
        if (done)
            break;
        nanosleep(&ts, NULL);
    }
    for (int i = 0; i < N; i++) {
        assert_int_equal(ac[i].answered, 1);
        assert_int_equal(ac[i].res, OCEAN_OK);
        assert_true(ac[i].h0 == 5.0f);
        assert_true(ac[i].frames >= 3);
    }
    /* destroy one, the others keep receiving */
    oc_client_destroy(cs[0]);
    int before = __atomic_load_n(&ac[1].frames, __ATOMIC_SEQ_CST);
    for (int w = 0; w < 100 && __atomic_load_n(&ac[1].frames, __ATOMIC_SEQ_CST) < before + 3; w++)
        nanosleep(&ts, NULL);
    assert_true(__atomic_load_n(&ac[1].frames, __ATOMIC_SEQ_CST) >= before + 3);
    for (int i = 1; i < N; i++)
        oc_client_destroy(cs[i]);
    oc_loop_destroy(l);
    fake_stop(s);
}

/* Replay mode: each CAMERA gets the frame for its render time, twice the
 * same bytes. */
static void replay_same_bytes(void **state)
{
    (void)state;
    fake_server *s = fake_start();
    char url[64];
    fake_url(s, url, sizeof url);
    uint8_t *runs[2][3];
    size_t lens[2][3];
    for (int run = 0; run < 2; run++) {
        oc_options o;
        oc_options_default(&o);
        o.url = url;
        oc_client *c;
        char err[256];
        assert_int_equal(oc_connect(&o, 5000, &c, err, sizeof err), OCEAN_OK);
        proto_subscribe sub;
        oc_subscribe_default(&sub);
        sub.mode = PROTO_MODE_REPLAY;
        assert_int_equal(oc_client_subscribe(c, &sub), OCEAN_OK);
        for (int k = 0; k < 3; k++) {
            proto_camera cam;
            oc_camera_default(&cam);
            cam.render_time = 10.0 + k;
            uint32_t seq;
            assert_int_equal(oc_client_send_camera(c, &cam, &seq), OCEAN_OK);
            oc_frame *f;
            assert_int_equal(oc_client_next_frame(c, 3000, &f), OCEAN_OK);
            assert_int_equal(f->info.camera_seq, seq);
            assert_true(f->hdr.sim_time == 10.0 + k);
            assert_true(f->camera_rtt_ms >= 0);
            runs[run][k] = malloc(f->raw_len);
            memcpy(runs[run][k], f->raw, f->raw_len);
            lens[run][k] = f->raw_len;
            oc_frame_free(f);
        }
        oc_client_destroy(c);
    }
    for (int k = 0; k < 3; k++) {
        assert_int_equal(lens[0][k], lens[1][k]);
        /* everything but the tick counter, which this fake keeps per connection
         * and the header seq, which may differ */
        assert_memory_equal(runs[0][k] + 32, runs[1][k] + 32, lens[0][k] - 32);
        free(runs[0][k]);
        free(runs[1][k]);
    }
    fake_stop(s);
}

/* Undecodable and oversized messages from the server are counted and
 * skipped; the connection and the requests in flight carry on. */
static void hostile_server_messages(void **state)
{
    (void)state;
    fake_server *s = fake_start();
    char url[64];
    fake_url(s, url, sizeof url);
    oc_options o;
    oc_options_default(&o);
    o.url = url;
    o.max_message = 300;    /* the fake's FRAMEs (> 400 bytes) are refused */
    oc_client *c;
    char err[256];
    assert_int_equal(oc_connect(&o, 5000, &c, err, sizeof err), OCEAN_OK);
    double xz[2] = {666, 1};
    oc_query_result q;
    assert_int_equal(oc_client_query(c, xz, 1, 0, 0, 30000, &q), OCEAN_OK);
    assert_true(q.samples[0].height == 666.5f);
    oc_query_result_free(&q);
    oc_client_stats st;
    oc_client_get_stats(c, &st);
    assert_int_equal(st.decode_errors, 2);
    char msg[512];
    oc_client_last_error(c, msg, sizeof msg);
    assert_non_null(strstr(msg, "undecodable"));
    /* frames over max_message are dropped whole, the stream goes on */
    proto_subscribe sub;
    oc_subscribe_default(&sub);
    assert_int_equal(oc_client_subscribe(c, &sub), OCEAN_OK);
    oc_frame *f = NULL;
    for (int i = 0; i < 10; i++)
        assert_int_equal(oc_service(c, 30), OCEAN_OK);
    /* none; an empty poll is no failure and leaves last_error as it was */
    assert_int_equal(oc_client_next_frame(c, 0, &f), OCEAN_ESTATE);
    oc_client_get_stats(c, &st);
    assert_true(st.decode_errors > 2);
    assert_int_equal(st.frames_rx, 0);
    assert_int_equal(oc_client_last_error(c, msg, sizeof msg), OCEAN_ETOOBIG);
    xz[0] = 2;
    assert_int_equal(oc_client_query(c, xz, 1, 0, 0, 30000, &q), OCEAN_OK);
    assert_true(q.samples[0].height == 2.5f);
    oc_query_result_free(&q);
    assert_int_equal(oc_client_state(c), OC_READY);
    oc_client_destroy(c);
    fake_stop(s);
}

/* header_only: FRAMEs carry their fixed fields and raw bytes, no tiles. */
static void header_only_frames(void **state)
{
    (void)state;
    fake_server *s = fake_start();
    char url[64];
    fake_url(s, url, sizeof url);
    oc_options o;
    oc_options_default(&o);
    o.url = url;
    o.header_only = 1;
    oc_client *c;
    char err[256];
    assert_int_equal(oc_connect(&o, 5000, &c, err, sizeof err), OCEAN_OK);
    proto_subscribe sub;
    oc_subscribe_default(&sub);
    sub.mode = PROTO_MODE_REPLAY;
    assert_int_equal(oc_client_subscribe(c, &sub), OCEAN_OK);
    proto_camera cam;
    oc_camera_default(&cam);
    cam.render_time = 42.25;
    uint32_t seq;
    assert_int_equal(oc_client_send_camera(c, &cam, &seq), OCEAN_OK);
    oc_frame *f;
    assert_int_equal(oc_client_next_frame(c, 3000, &f), OCEAN_OK);
    assert_true(f->hdr.sim_time == 42.25);
    assert_int_equal(f->info.camera_seq, seq);
    assert_int_equal(f->info.tile_count, 2);
    assert_int_equal(f->info.has_mesh, 1);
    assert_true(isinf(f->info.cutoff_k) && f->info.e_error == 0.01);
    assert_null(f->tiles);
    assert_null(f->info.tiles);
    assert_null(f->topology);
    assert_true(f->raw_len > 32 + 56);
    /* the raw bytes are the full message: a full decode of them agrees */
    proto_msg m;
    assert_int_equal(proto_decode(f->raw, f->raw_len, &m, err, sizeof err), OCEAN_OK);
    assert_int_equal(m.u.frame.tick, f->info.tick);
    assert_int_equal(m.u.frame.tile_count, 2);
    proto_msg_free(&m);
    oc_frame_free(f);
    oc_client_stats st;
    oc_client_get_stats(c, &st);
    assert_int_equal(st.decode_errors, 0);
    oc_client_destroy(c);
    fake_stop(s);
}

/* oc_loop_service(timeout) returns within its timeout when nothing
 * happens, also while connections are idle (a timer ripening just as lws
 * starts a service pass once left poll() asleep for 30 s). */
static void service_timeout_is_bounded(void **state)
{
    (void)state;
    fake_server *s = fake_start();
    char url[64];
    fake_url(s, url, sizeof url);
    oc_loop *l;
    char err[256];
    assert_int_equal(oc_loop_create(&l, err, sizeof err), OCEAN_OK);
    oc_options o;
    oc_options_default(&o);
    o.url = url;
    o.loop = l;
    oc_client *c[3];
    for (int i = 0; i < 3; i++)
        assert_int_equal(oc_connect(&o, 5000, &c[i], err, sizeof err), OCEAN_OK);
    double worst = 0;
    for (int i = 0; i < 300; i++) {
        struct timespec a, b;
        clock_gettime(CLOCK_MONOTONIC, &a);
        assert_int_equal(oc_loop_service(l, 1 + i % 7), OCEAN_OK);
        clock_gettime(CLOCK_MONOTONIC, &b);
        double ms = (b.tv_sec - a.tv_sec) * 1e3 + (b.tv_nsec - a.tv_nsec) * 1e-6;
        if (ms > worst)
            worst = ms;
    }
    /* the failure slept in poll() for lws's 30 000 ms: judged by that
     * signature, not by how promptly a loaded host schedules this thread */
    if (worst > 10000) {
        print_error("oc_loop_service(<= 7 ms) took %.1f ms\n", worst);
        fail();
    }
    for (int i = 0; i < 3; i++)
        oc_client_destroy(c[i]);
    oc_loop_destroy(l);
    fake_stop(s);
}

/* oc_service(c, 0) reads everything that has arrived, not one socket
 * chunk: a caller servicing once per 60 Hz step with 80 KB frames got ~6
 * of 30 fps, ever later.  Here the fake server's frames pile up in the
 * socket while nobody services, until it has written 20 more (waited for
 * with a deadline, not a sleep: a loaded host may run its 50 Hz timer
 * late); a single 0-timeout call must then take them all, or read for
 * its whole bound (one chunk per call took about 3). */
static void service_zero_drains(void **state)
{
    (void)state;
    fake_server *s = fake_start();
    oc_client *c = fake_client(s);
    proto_subscribe sub;
    oc_subscribe_default(&sub);
    sub.frame_rate_hz = 50;
    assert_int_equal(oc_client_subscribe(c, &sub), OCEAN_OK);
    oc_frame *f = NULL;
    assert_int_equal(oc_client_next_frame(c, 3000, &f), OCEAN_OK);   /* the stream runs */
    oc_frame_free(f);
    /* frames already written may be in flight or read: counted from here */
    assert_int_equal(oc_service(c, 0), OCEAN_OK);
    oc_client_stats st0, st1;
    oc_client_get_stats(c, &st0);
    int w0 = __atomic_load_n(&s->messages_written, __ATOMIC_SEQ_CST), written = 0;
    struct timespec ts = {0, 10 * 1000 * 1000};
    for (int w = 0; w < 3000 && written < 20; w++) {
        nanosleep(&ts, NULL);
        written = __atomic_load_n(&s->messages_written, __ATOMIC_SEQ_CST) - w0;
    }
    assert_true(written >= 20);
    struct timespec a, b;
    clock_gettime(CLOCK_MONOTONIC, &a);
    assert_int_equal(oc_service(c, 0), OCEAN_OK);
    clock_gettime(CLOCK_MONOTONIC, &b);
    double ms = (b.tv_sec - a.tv_sec) * 1e3 + (b.tv_nsec - a.tv_nsec) * 1e-6;
    oc_client_get_stats(c, &st1);
    uint64_t got = st1.frames_rx - st0.frames_rx;
    /* every message written is a frame, and on loopback in this socket:
     * the call takes them all, or reads until its bound, OC_SERVICE_DRAIN_MS
     * (a flood must not hold the caller; under ASan on a loaded host 13 of
     * 20 took the 10 ms); one chunk per call stopped after ~3, at once */
    if (got + 1 < (uint64_t)written && ms < OC_SERVICE_DRAIN_MS) {
        print_error("one oc_service(c, 0) took %llu of the %d frames written (%llu bytes) and returned after %.1f ms\n",
                    (unsigned long long)got, written, (unsigned long long)(st1.bytes_rx - st0.bytes_rx), ms);
        fail();
    }
    /* the queue kept the newest frame_queue (4) of them */
    int queued = 0;
    while (oc_client_next_frame(c, 0, &f) == OCEAN_OK) {
        queued++;
        oc_frame_free(f);
    }
    assert_true(queued >= 4);
    oc_client_destroy(c);
    fake_stop(s);
}

/* The send queue: in live mode a CAMERA still queued is replaced by the
 * next (only the newest matters; 5000 sent without servicing reach the
 * server as one, the last, under the first's seq); replay CAMERAs are
 * requests and are all kept, up to OC_SEND_QUEUE_MAX queued messages,
 * then OCEAN_ERATE with the reason, until the loop is serviced (the queue
 * used to grow without bound: 1.5 GB in 4 s of a tight loop). */
static void send_queue_bounded(void **state)
{
    (void)state;
    fake_server *s = fake_start();
    oc_client *c = fake_client(s);
    proto_subscribe sub;
    oc_subscribe_default(&sub);
    assert_int_equal(oc_client_subscribe(c, &sub), OCEAN_OK);
    oc_client_stats st0, st1;
    oc_client_get_stats(c, &st0);
    proto_camera cam;
    oc_camera_default(&cam);
    uint32_t seq0 = 0, seq = 0;
    for (int i = 0; i < 5000; i++) {
        cam.pos[0] = i;
        assert_int_equal(oc_client_send_camera(c, &cam, &seq), OCEAN_OK);
        if (i == 0)
            seq0 = seq;
        assert_int_equal(seq, seq0);
    }
    oc_client_get_stats(c, &st1);
    if (st1.messages_tx - st0.messages_tx != 1) {
        print_error("5000 live CAMERAs queued %llu messages\n", (unsigned long long)(st1.messages_tx - st0.messages_tx));
        fail();
    }
    for (int w = 0; w < 300 && __atomic_load_n(&s->cameras_seen, __ATOMIC_SEQ_CST) < 1; w++)
        oc_service(c, 10);
    oc_service(c, 50);
    assert_int_equal(__atomic_load_n(&s->cameras_seen, __ATOMIC_SEQ_CST), 1);
    assert_int_equal(__atomic_load_n(&s->last_cam_x, __ATOMIC_SEQ_CST), 4999);
    /* sent: the next one is a new message */
    assert_int_equal(oc_client_send_camera(c, &cam, &seq), OCEAN_OK);
    assert_int_equal(seq, seq0 + 1);

    sub.mode = PROTO_MODE_REPLAY;
    assert_int_equal(oc_client_subscribe(c, &sub), OCEAN_OK);
    ocean_result r = OCEAN_OK;
    unsigned n = 0;
    for (; n < 5000 && r == OCEAN_OK; n++) {
        cam.render_time = n;
        r = oc_client_send_camera(c, &cam, &seq);
    }
    assert_int_equal(r, OCEAN_ERATE);
    n--;
    /* the camera and SUBSCRIBE above may not have left yet */
    if (n + 3 < OC_SEND_QUEUE_MAX || n > OC_SEND_QUEUE_MAX) {
        print_error("%u replay CAMERAs queued before ERATE (limit %u messages)\n", n, OC_SEND_QUEUE_MAX);
        fail();
    }
    char why[512] = "";
    assert_int_equal(oc_client_last_error(c, why, sizeof why), OCEAN_ERATE);
    assert_non_null(strstr(why, "send queue full"));
    assert_non_null(strstr(why, "1024"));
    /* serviced, the queue drains and sends work again */
    for (int w = 0; w < 300 && r != OCEAN_OK; w++) {
        oc_service(c, 10);
        r = oc_client_send_camera(c, &cam, NULL);
    }
    assert_int_equal(r, OCEAN_OK);
    oc_client_destroy(c);
    fake_stop(s);
}

/* oc_client_last_error describes the latest failure: local refusals
 * (a non-finite query time, a NULL token) and timeouts record their reason
 * (they left it empty or stale); the end of the connection replaces an
 * older local error (it was recorded only when none existed); and calls on
 * the closed client fail with OCEAN_EIO naming the closure, as the header
 * says (they returned OCEAN_ESTATE "not connected"). */
static void errors_follow_the_latest_failure(void **state)
{
    (void)state;
    fake_server *s = fake_start();
    oc_client *c = fake_client(s);
    char msg[512];
    double xz[2] = {1, 2};
    oc_query_result q;
    assert_int_equal(oc_client_query(c, xz, 1, 1, NAN, 100, &q), OCEAN_EINVAL);
    assert_int_equal(oc_client_last_error(c, msg, sizeof msg), OCEAN_EINVAL);
    assert_non_null(strstr(msg, "not finite"));
    /* at_time is 0 or 1 (7 and 255 were sent as 1) */
    assert_int_equal(oc_client_query(c, xz, 1, 7, 1.0, 100, &q), OCEAN_EINVAL);
    assert_int_equal(oc_client_last_error(c, msg, sizeof msg), OCEAN_EINVAL);
    assert_non_null(strstr(msg, "at_time 7"));
    proto_sea sea;
    assert_int_equal(oc_client_sea_state(c, &sea, NULL), OCEAN_OK);
    assert_int_equal(oc_client_sea_state_set(c, &sea, 0, NULL, 100), OCEAN_EINVAL);
    assert_int_equal(oc_client_last_error(c, msg, sizeof msg), OCEAN_EINVAL);
    assert_non_null(strstr(msg, "token"));
    oc_frame *f = NULL;
    assert_int_equal(oc_client_next_frame(c, 50, &f), OCEAN_ESTATE);   /* not subscribed */
    assert_int_equal(oc_client_last_error(c, msg, sizeof msg), OCEAN_ESTATE);
    assert_non_null(strstr(msg, "timed out after 50 ms"));
    /* an older local failure, then the connection is lost */
    assert_int_equal(oc_client_query(c, xz, 0, 0, 0, 100, &q), OCEAN_EINVAL);
    fake_stop(s);
    assert_int_equal(oc_client_next_frame(c, 5000, &f), OCEAN_EIO);
    assert_int_equal(oc_client_state(c), OC_CLOSED);
    assert_int_equal(oc_client_last_error(c, msg, sizeof msg), OCEAN_EIO);
    if (!strstr(msg, "closed")) {
        print_error("last_error after the connection was lost: \"%s\"\n", msg);
        fail();
    }
    assert_int_equal(oc_client_query(c, xz, 1, 0, 0, 100, &q), OCEAN_EIO);
    assert_int_equal(oc_client_last_error(c, msg, sizeof msg), OCEAN_EIO);
    assert_non_null(strstr(msg, "connection is closed"));
    proto_camera cam;
    oc_camera_default(&cam);
    assert_int_equal(oc_client_send_camera(c, &cam, NULL), OCEAN_EIO);
    proto_subscribe sub;
    oc_subscribe_default(&sub);
    assert_int_equal(oc_client_subscribe(c, &sub), OCEAN_EIO);
    assert_int_equal(oc_client_sea_state_set(c, &sea, 0, "secret", 100), OCEAN_EIO);
    assert_int_equal(oc_client_connect_wait(c, 10), OCEAN_EIO);
    oc_client_destroy(c);
}

typedef struct close_seen {
    int calls, reason;
    char message[300];
} close_seen;

static void on_close_cb(void *user, oc_client *c, int reason, const char *message)
{
    (void)c;
    close_seen *cs = user;
    cs->calls++;
    cs->reason = reason;
    snprintf(cs->message, sizeof cs->message, "%s", message);
}

/* on_close after a BYE gets the BYE's reason and message, as the header
 * says (it got "connection closed", the transport's word that follows). */
static void on_close_gets_bye(void **state)
{
    (void)state;
    fake_server *s = fake_start();
    char url[64], err[256];
    fake_url(s, url, sizeof url);
    close_seen cs;
    memset(&cs, 0, sizeof cs);
    oc_options o;
    oc_options_default(&o);
    o.url = url;
    o.cb.user = &cs;
    o.cb.on_close = on_close_cb;
    oc_client *c;
    assert_int_equal(oc_connect(&o, 5000, &c, err, sizeof err), OCEAN_OK);
    double xz[2] = {777, 0};
    oc_query_result q;
    assert_int_equal(oc_client_query(c, xz, 1, 0, 0, 5000, &q), OCEAN_EIO);
    for (int i = 0; i < 100 && oc_client_state(c) != OC_CLOSED; i++)
        oc_service(c, 20);
    assert_int_equal(oc_client_state(c), OC_CLOSED);
    assert_int_equal(cs.calls, 1);
    assert_int_equal(cs.reason, 2);
    if (strcmp(cs.message, "fake server shutting down") != 0) {
        print_error("on_close after BYE got \"%s\"\n", cs.message);
        fail();
    }
    char msg[512];
    assert_int_equal(oc_client_last_error(c, msg, sizeof msg), OCEAN_EIO);
    assert_non_null(strstr(msg, "fake server shutting down"));
    oc_client_destroy(c);
    fake_stop(s);
}

/* Heap in use (glibc: every arena, and mmapped blocks). */
static size_t heap_in_use(void)
{
    struct mallinfo2 mi = mallinfo2();
    return mi.uordblks + mi.hblkhd;
}

/* Clients with private loops (o.loop NULL) alive at the same time: each
 * loop is an lws context, and lws 4.1 made a context with
 * LWS_SERVER_OPTION_DO_SSL_GLOBAL_INIT allocate a new process-wide
 * SSL_CTX ex_data index, so destroying the older loop looked its TLS
 * client context up at the wrong index and kept it with the system CA
 * store, ~0.85 MB a round (ASan: LeakSanitizer reports it at exit; the
 * plain build measures the heap).  And wss:// still works: a TLS fake
 * server whose self-signed certificate is made trusted through
 * SSL_CERT_FILE (skipped without the openssl command). */
static void private_loops_no_leak_and_wss(void **state)
{
    (void)state;
    fake_server *s = fake_start();
    char url[64], err[256] = "";
    fake_url(s, url, sizeof url);
    oc_options o;
    oc_options_default(&o);
    o.url = url;
    size_t before = 0;
    for (int round = 0; round < 7; round++) {
        oc_client *c[2];
        for (int k = 0; k < 2; k++)
            assert_int_equal(oc_connect(&o, 5000, &c[k], err, sizeof err), OCEAN_OK);
        for (int k = 0; k < 2; k++)
            oc_client_destroy(c[k]);
        if (round == 0)
            before = heap_in_use();   /* after the first: OpenSSL's own lazy setup */
    }
    size_t after = heap_in_use();
    if (!getenv("OCEAN_TEST_SANITIZED") && after > before + (2u << 20)) {
        print_error("6 rounds of two private-loop clients grew the heap by %.2f MB\n",
                    (double)(after - before) / 1048576.0);
        fail();
    }
    fake_stop(s);

    char cert[300], key[300], cmd[1024];
    tmp_path(cert, sizeof cert, "cert.pem");
    tmp_path(key, sizeof key, "key.pem");
    snprintf(cmd, sizeof cmd,
             "openssl req -x509 -newkey rsa:2048 -nodes -keyout '%s' -out '%s' -days 2 -subj /CN=localhost "
             "-addext subjectAltName=DNS:localhost >/dev/null 2>&1",
             key, cert);
    if (system(cmd) != 0) {
        print_message("(no openssl command: the wss:// round trip is skipped)\n");
        return;
    }
    char *old_cert = getenv("SSL_CERT_FILE") ? strdup(getenv("SSL_CERT_FILE")) : NULL;
    setenv("SSL_CERT_FILE", cert, 1);
    s = fake_start_tls(cert, key);
    snprintf(url, sizeof url, "wss://localhost:%d/", s->port);
    oc_client *c = NULL;
    ocean_result r = oc_connect(&o, 5000, &c, err, sizeof err);
    if (r != OCEAN_OK)
        print_error("wss connect: %s\n", err);
    assert_int_equal(r, OCEAN_OK);
    double xz[2] = {1, 2};
    oc_query_result q;
    assert_int_equal(oc_client_query(c, xz, 1, 0, 0, 3000, &q), OCEAN_OK);
    assert_true(q.samples[0].height == 2.0f);
    oc_query_result_free(&q);
    oc_client_destroy(c);
    if (old_cert) {
        setenv("SSL_CERT_FILE", old_cert, 1);
        free(old_cert);
    } else {
        unsetenv("SSL_CERT_FILE");
    }
    /* and a certificate nobody trusts is refused */
    r = oc_connect(&o, 5000, &c, err, sizeof err);
    assert_int_equal(r, OCEAN_EIO);
    fake_stop(s);
}

/* A server that accepts the connection and never answers the handshake
 * (here: a listening socket nobody accepts from; the kernel completes the
 * TCP handshake).  The client gives up waiting for HELLO, and destroying
 * it must end its connection for good: lws frees the wsi that the kill
 * timeout closes without a CLIENT_CLOSED, and a client that kept it handed
 * the freed wsi to lws at the loop's next wake-up (`ocean-client query`
 * against such a server crashed about 1 run in 20; here ASan reports the
 * use after free on the second client's connect), and each destroy waited
 * out its whole 2 s kill timeout. */
static void silent_server_destroy(void **state)
{
    (void)state;
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in a = {0};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    assert_int_equal(bind(fd, (struct sockaddr *)&a, sizeof a), 0);
    assert_int_equal(listen(fd, 16), 0);
    socklen_t al = sizeof a;
    getsockname(fd, (struct sockaddr *)&a, &al);
    char url[64], err[256];
    snprintf(url, sizeof url, "ws://127.0.0.1:%d/", ntohs(a.sin_port));
    oc_loop *l;
    assert_int_equal(oc_loop_create(&l, err, sizeof err), OCEAN_OK);
    oc_options o;
    oc_options_default(&o);
    o.url = url;
    o.loop = l;
    for (int i = 0; i < 4; i++) {
        oc_client *c;
        assert_int_equal(oc_client_create(&o, &c, err, sizeof err), OCEAN_OK);
        assert_int_equal(oc_client_connect_wait(c, 200), OCEAN_ESTATE);
        char why[256] = "";
        oc_client_last_error(c, why, sizeof why);
        assert_non_null(strstr(why, "no HELLO"));
        struct timespec t0, t1;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        oc_client_destroy(c);
        clock_gettime(CLOCK_MONOTONIC, &t1);
        double ms = (t1.tv_sec - t0.tv_sec) * 1e3 + (t1.tv_nsec - t0.tv_nsec) * 1e-6;
        /* the failure waited out the close grace (300 ms) and then the
         * whole kill timeout (2 000 ms): judged by that signature, not by
         * how fast this host closes a socket (1 620 ms for the right path
         * under CI with a core busy) */
        if (ms >= 2250) {
            print_error("destroy of a client the server never answered took %.0f ms\n", ms);
            fail();
        }
        /* wake the loop: every wake-up walks the loop's clients */
        assert_int_equal(oc_loop_service(l, 20), OCEAN_OK);
    }
    oc_loop_destroy(l);
    close(fd);
}

/* Many connect/disconnect cycles on one shared, caller-driven loop. */
static void connect_cycles(void **state)
{
    (void)state;
    fake_server *s = fake_start();
    char url[64];
    fake_url(s, url, sizeof url);
    oc_loop *l;
    char err[256];
    assert_int_equal(oc_loop_create(&l, err, sizeof err), OCEAN_OK);
    int n = getenv("OCEAN_TEST_SANITIZED") ? 10 : 30;
    for (int i = 0; i < n; i++) {
        oc_options o;
        oc_options_default(&o);
        o.url = url;
        o.loop = l;
        oc_client *c;
        assert_int_equal(oc_connect(&o, 5000, &c, err, sizeof err), OCEAN_OK);
        if (i % 2) {
            proto_subscribe sub;
            oc_subscribe_default(&sub);
            oc_client_subscribe(c, &sub);
            oc_frame *f;
            assert_int_equal(oc_client_next_frame(c, 3000, &f), OCEAN_OK);
            oc_frame_free(f);
        }
        oc_client_destroy(c);
    }
    oc_loop_destroy(l);
    fake_stop(s);
}

/* ====================================================== the real daemon */

static void daemon_round_trip(void **state)
{
    (void)state;
    oc_client *c = NULL;
    pid_t pid = test_oceand_up(NULL, 100, &c);
    char err[256] = "";
    ocean_result r;
    proto_subscribe sub;
    oc_subscribe_default(&sub);
    assert_int_equal(oc_client_subscribe(c, &sub), OCEAN_OK);
    proto_camera cam;
    oc_camera_default(&cam);
    assert_int_equal(oc_client_send_camera(c, &cam, NULL), OCEAN_OK);
    int frames = 0, read_from = -1;
    for (int i = 0; i < 12; i++) {
        oc_frame *f = NULL;
        r = oc_client_next_frame(c, 5000, &f);
        if (r != OCEAN_OK) {
            oc_client_last_error(c, err, sizeof err);
            print_error("no frame from the daemon: %s (%s)\n", ocean_strerror(r), err);
            break;
        }
        /* the viewer's subscription samples in time: the first frame (KEY)
         * brings tiles, the rest of what the client lacks follows within a
         * few frames (a frame carries at most twice its byte budget), and
         * from then on every frame's view reads the sea in front of the
         * camera from the samples the client holds */
        assert_true(frames > 0 || f->info.tile_count > 0);
        for (unsigned k = 0; k < f->info.tile_count; k++)
            assert_int_equal(f->tiles[k].decode_result, OCEAN_OK);
        oc_sample sm;
        if (f->view_result != OCEAN_OK) print_error("frame %d: %s\n", frames, f->view_error);
        assert_int_equal(f->view_result, OCEAN_OK);
        ocean_result sr = oc_frame_sample(f, cam.pos[0] + 30, cam.pos[2], 0, &sm);
        if (read_from >= 0 || sr == OCEAN_OK) assert_int_equal(sr, OCEAN_OK);
        if (read_from < 0 && sr == OCEAN_OK) read_from = frames;
        frames++;
        oc_frame_free(f);
    }
    double xz[4] = {0, 0, 10.5, -3};
    oc_query_result q = {0};
    ocean_result qr = oc_client_query(c, xz, 2, 0, 0, 30000, &q);
    if (qr != OCEAN_OK) {
        oc_client_last_error(c, err, sizeof err);
        print_error("query: %s (%s)\n", ocean_strerror(qr), err);
    }
    if (qr == OCEAN_OK)
        assert_true(isfinite(q.samples[0].height) && fabsf(q.samples[0].height) < 100);
    oc_query_result_free(&q);
    oc_client_destroy(c);
    test_oceand_stop(pid);
    assert_int_equal(frames, 12);
    assert_true(read_from >= 0 && read_from < 8);
    assert_int_equal(qr, OCEAN_OK);
}

static int cleanup(void **state)
{
    (void)state;
    if (tmpdir[0]) {
        char cmd[300];
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
        if (system(cmd) != 0)
            return 0;
    }
    return 0;
}

int main(void)
{
    signal(SIGPIPE, SIG_IGN);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(url_good),
        cmocka_unit_test(url_bad),
        cmocka_unit_test(path_good),
        cmocka_unit_test(path_bad),
        cmocka_unit_test(store_round_trip),
        cmocka_unit_test(store_compare),
        cmocka_unit_test(create_argument_errors),
        cmocka_unit_test(connect_refused),
        cmocka_unit_test(silent_server_destroy),
        cmocka_unit_test(live_frames_and_queries),
        cmocka_unit_test(qz_mesh_frames),
        cmocka_unit_test(threaded_shared_loop),
        cmocka_unit_test(replay_same_bytes),
        cmocka_unit_test(connect_cycles),
        cmocka_unit_test(private_loops_no_leak_and_wss),
        cmocka_unit_test(service_timeout_is_bounded),
        cmocka_unit_test(service_zero_drains),
        cmocka_unit_test(send_queue_bounded),
        cmocka_unit_test(errors_follow_the_latest_failure),
        cmocka_unit_test(on_close_gets_bye),
        cmocka_unit_test(header_only_frames),
        cmocka_unit_test(hostile_server_messages),
        cmocka_unit_test(daemon_round_trip),
    };
    return cmocka_run_group_tests(tests, NULL, cleanup);
}
