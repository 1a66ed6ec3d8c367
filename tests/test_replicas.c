/*
 * test_replicas.c - replicas behind HAProxy with the sea-state timeline in
 * Redis (issue 16).
 *
 * On loopback: a Redis server, two oceand processes (build/oceand, one epoch,
 * one Redis stream) and HAProxy balancing WebSocket connections over them
 * with health checks on /status.  Clients connect through the proxy and
 * directly; a sea-state change set through the proxy reaches every client of
 * both replicas with one effective time; replay FRAMEs (layout 0, cutoff
 * policy none) are byte-identical across replicas, per-connection fields
 * aside; a replica is killed (SIGKILL) in the middle of a client's stream, the
 * client reconnects through the proxy to the survivor and gets the same bytes
 * for the same camera and time; restarted, the killed replica reads the
 * timeline back from the stream.  Live FRAMEs of one tick are the same bytes
 * on both replicas too.
 */
#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <netinet/in.h>
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
#include <time.h>
#include <unistd.h>

#include <cmocka.h>

#include "oceanclient.h"
#include "proto.h"
#include "lib/test_ws.h"
#include "lib/test_net.h"

/* One epoch for both replicas: midnight UTC yesterday, set in main.  Not a
 * fixed date: the daemon refuses an epoch whose sim time would pass
 * OCEAN_TIME_MAX (about 4.25 years). */
static double EPOCH_UNIX;
static char EPOCH_ISO[32];
#define NFRAMES 8

static char exe_dir[512];
static char tmp[256];
static pid_t pids[4]; /* redis, r1, r2, haproxy */

/* The replicas' sim time, computed here from the epoch (PROTOCOL.md
 * "Simulation clock"). */
static double sim_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec - EPOCH_UNIX + 1e-9 * ts.tv_nsec;
}

static int port_open(int port)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port),
                            .sin_addr.s_addr = htonl(INADDR_LOOPBACK)};
    int ok = connect(fd, (struct sockaddr *)&a, sizeof a) == 0;
    close(fd);
    return ok;
}

static int wait_port(int port, double secs)
{
    double end = test_now_s() + secs;
    while (test_now_s() < end) {
        if (port_open(port)) return 1;
        usleep(50000);
    }
    return 0;
}

static pid_t spawn(const char *log, char *const argv[])
{
    pid_t p = fork();
    if (p == 0) {
        int fd = open(log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd >= 0) {
            dup2(fd, 1);
            dup2(fd, 2);
        }
        setpgid(0, 0);
        execvp(argv[0], argv);
        _exit(127);
    }
    return p;
}

static void stop(pid_t *p, int sig)
{
    if (*p > 0) {
        kill(*p, sig);
        waitpid(*p, NULL, 0);
        *p = 0;
    }
}

static int have(const char *prog)
{
    char cmd[128];
    snprintf(cmd, sizeof cmd, "command -v %s >/dev/null 2>&1", prog);
    return system(cmd) == 0;
}

static void write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

/* Sends m; 0, or -1 when the connection is gone. */
static int try_send(test_ws *w, const proto_msg *m)
{
    proto_buf b;
    proto_buf_init(&b, 0);
    char err[200];
    if (proto_encode(&b, m, err, sizeof err) != OCEAN_OK) fail_msg("encode: %s", err);
    int r = test_ws_send(w, 2, proto_buf_data(&b), b.len);
    proto_buf_free(&b);
    return r;
}

static void raw_send(test_ws *w, const proto_msg *m)
{
    if (try_send(w, m) != 0) fail_msg("sending %s: %s", proto_type_name(m->hdr.type), strerror(errno));
}

/* Next message of `type` (decoded into *m; raw bytes into *raw if asked).
 * 0 on timeout, -1 when the connection closed. */
static int wait_type(test_ws *w, unsigned type, int ms, proto_msg *m, uint8_t **raw, size_t *rawlen)
{
    double end = test_now_s() + ms / 1000.0;
    while (test_now_s() < end) {
        uint8_t *b;
        size_t n;
        int op = test_ws_recv(w, (int)((end - test_now_s()) * 1000) + 1, &b, &n);
        if (op < 0) return -1;
        if (op == 0) return 0;
        if (op == 8) {
            free(b);
            return -1;
        }
        ocean_result r = proto_decode(b, n, m, NULL, 0);
        if (r == OCEAN_OK && m->hdr.type == type) {
            if (raw) {
                *raw = b;
                *rawlen = n;
            } else {
                free(b);
            }
            return 1;
        }
        if (r == OCEAN_OK) proto_msg_free(m);
        free(b);
    }
    return 0;
}

static void connect_hello(test_ws *w, int port, proto_hello *h)
{
    double end = test_now_s() + 5;
    while (test_now_s() < end) {
        if (test_ws_connect(w, port, "/", PROTO_SUBPROTOCOL) == 0) {
            proto_msg m;
            if (wait_type(w, PROTO_HELLO, 3000, &m, NULL, NULL) == 1) {
                *h = m.u.hello;
                proto_msg_free(&m);
                return;
            }
            test_ws_close(w);
        }
        usleep(100000);
    }
    fail_msg("no HELLO from port %d", port);
}

static void subscribe_replay(test_ws *w)
{
    proto_msg m;
    proto_msg_init(&m, PROTO_SUBSCRIBE);
    oc_subscribe_default(&m.u.subscribe);
    m.u.subscribe.layout = PROTO_LAYOUT_WORLD;
    m.u.subscribe.mode = PROTO_MODE_REPLAY;
    m.u.subscribe.cutoff_policy = PROTO_CUTOFF_NONE;
    m.u.subscribe.mesh_kind = PROTO_MESH_CONCENTRIC;
    m.u.subscribe.tile_size = 32;
    m.u.subscribe.lod_levels = 2;
    m.u.subscribe.frame_rate_hz = 10;
    raw_send(w, &m);
}

/* One replay FRAME for the camera at render time t; its bytes with the
 * per-connection fields (header seq, camera_seq, mesh_id) zeroed.  NULL when
 * the connection closed. */
static uint8_t *replay_frame(test_ws *w, double t, size_t *len)
{
    proto_msg c;
    proto_msg_init(&c, PROTO_CAMERA);
    oc_camera_default(&c.u.camera);
    c.u.camera.pos[0] = 1234.5;
    c.u.camera.pos[1] = 25;
    c.u.camera.pos[2] = -321.25;
    c.u.camera.vel[0] = 7;
    c.u.camera.render_time = t;
    if (try_send(w, &c) != 0) return NULL;
    proto_msg m;
    uint8_t *raw = NULL;
    if (wait_type(w, PROTO_FRAME, 10000, &m, &raw, len) != 1) return NULL;
    assert_true(m.hdr.sim_time == t);
    proto_msg_free(&m);
    size_t cam_at, mesh_at;
    assert_int_equal(proto_frame_client_fields(raw, *len, &cam_at, &mesh_at), OCEAN_OK);
    memset(raw + 16, 0, 4);
    memset(raw + cam_at, 0, 4);
    if (mesh_at) memset(raw + mesh_at, 0, 4);
    return raw;
}

/* Subscribes d1 and d2 (connected to the two replicas) live in `layout` at
 * one camera and checks that the FRAMEs of every tick both deliver are the
 * same bytes, per-connection fields (header seq, camera_seq, mesh_id) aside. */
static void live_identical(test_ws *d1, test_ws *d2, int layout)
{
    test_ws *dd[2] = {d1, d2};
    uint32_t lt[2][30];
    uint8_t *lb[2][30];
    size_t ll[2][30];
    int ln[2] = {0, 0};
    proto_msg m;
    for (int k = 0; k < 2; k++) {
        proto_msg sm;
        proto_msg_init(&sm, PROTO_SUBSCRIBE);
        oc_subscribe_default(&sm.u.subscribe);
        /* a time-interpolating frame carries what its own client lacks,
         * which depends on that connection's history (the tick of its KEY
         * frame, a frame replaced unsent): the plain stream, where a tick's
         * frame for one camera is the same for every client */
        sm.u.subscribe.flags &= (uint8_t)~PROTO_SUB_TIME_INTERP;
        sm.u.subscribe.layout = (uint8_t)layout;
        if (layout == PROTO_LAYOUT_WORLD) {
            sm.u.subscribe.cutoff_policy = PROTO_CUTOFF_NONE;
            sm.u.subscribe.mesh_kind = PROTO_MESH_NONE;
            sm.u.subscribe.tile_size = 32;
            sm.u.subscribe.lod_levels = 2;
        }
        sm.u.subscribe.frame_rate_hz = 30;
        raw_send(dd[k], &sm);
        proto_msg c;
        proto_msg_init(&c, PROTO_CAMERA);
        oc_camera_default(&c.u.camera);
        c.u.camera.pos[0] = 1234.5;
        c.u.camera.pos[1] = 25;
        raw_send(dd[k], &c);
    }
    double lend = test_now_s() + 3.0;
    while (test_now_s() < lend && (ln[0] < 30 || ln[1] < 30))
        for (int k = 0; k < 2; k++) {
            uint8_t *raw;
            size_t len;
            if (ln[k] < 30 && wait_type(dd[k], PROTO_FRAME, 20, &m, &raw, &len) == 1) {
                /* before our CAMERA, or still the other layout's frames */
                if (m.u.frame.camera_seq == PROTO_NO_CAMERA || m.u.frame.layout != layout) {
                    proto_msg_free(&m);
                    free(raw);
                    continue;
                }
                size_t cam_at, mesh_at;
                assert_int_equal(proto_frame_client_fields(raw, len, &cam_at, &mesh_at), OCEAN_OK);
                memset(raw + 16, 0, 4);
                memset(raw + cam_at, 0, 4);
                if (mesh_at) memset(raw + mesh_at, 0, 4);
                lt[k][ln[k]] = m.u.frame.tick;
                lb[k][ln[k]] = raw;
                ll[k][ln[k]++] = len;
                proto_msg_free(&m);
            }
        }
    int common = 0;
    for (int i = 0; i < ln[0]; i++)
        for (int q = 0; q < ln[1]; q++)
            if (lt[0][i] == lt[1][q]) {
                assert_int_equal(ll[0][i], ll[1][q]);
                assert_memory_equal(lb[0][i], lb[1][q], ll[0][i]);
                common++;
            }
    for (int k = 0; k < 2; k++)
        for (int i = 0; i < ln[k]; i++) free(lb[k][i]);
    print_message("live layout %d: %d + %d frames, %d ticks from both replicas, identical\n", layout, ln[0],
                  ln[1], common);
    assert_true(common >= 5);
}

static void replicas_behind_haproxy(void **state)
{
    (void)state;
    if (!have("redis-server") || !have("haproxy")) {
        print_message("redis-server or haproxy missing (.ci/deps.sh installs them)\n");
        skip();
    }
    snprintf(tmp, sizeof tmp, "/tmp/test_replicas.%d", (int)getpid());
    mkdir(tmp, 0755);
    int prd = test_free_port(), p1 = test_free_port(), p2 = test_free_port(), ph = test_free_port();
    assert_true(prd > 0 && p1 > 0 && p2 > 0 && ph > 0);
    char path[600], log[600], text[4096], ports[16];

    /* Redis, without persistence */
    snprintf(ports, sizeof ports, "%d", prd);
    snprintf(log, sizeof log, "%s/redis.log", tmp);
    char *rargv[] = {"redis-server", "--port", ports, "--bind", "127.0.0.1", "--save", "",
                     "--appendonly", "no", "--dir", tmp, NULL};
    pids[0] = spawn(log, rargv);
    assert_true(wait_port(prd, 10));

    /* two replicas, one configuration */
    int rp[2] = {p1, p2};
    for (int k = 0; k < 2; k++) {
        snprintf(path, sizeof path, "%s/r%d.conf", tmp, k + 1);
        snprintf(text, sizeof text,
                 "sea.wind = 10\nocean.n = 64\nocean.cascades = 2\nocean.patch = 400\nocean.threads = 1\n"
                 "server.port = %d\nserver.scene = \"\"\nserver.tick_rate = 30\n"
                 "server.admin_token = \"test-token\"\nserver.epoch = %s\n"
                 "server.redis = 127.0.0.1:%d\nserver.redis_stream = \"test:%d\"\nserver.sea_lead = 0.5\n"
                 "server.near_field_waves = 32\nserver.view_range = 2000\nserver.workers = 1\n",
                 rp[k], EPOCH_ISO, prd, (int)getpid());
        write_file(path, text);
        char exe[600];
        snprintf(exe, sizeof exe, "%s/oceand", exe_dir);
        snprintf(log, sizeof log, "%s/r%d.log", tmp, k + 1);
        char *oargv[] = {exe, "--config", path, NULL};
        pids[1 + k] = spawn(log, oargv);
    }
    assert_true(wait_port(p1, 20));
    assert_true(wait_port(p2, 20));

    /* HAProxy: WebSocket passes as HTTP upgrade; health checks on /status */
    snprintf(path, sizeof path, "%s/haproxy.cfg", tmp);
    snprintf(text, sizeof text,
             "global\n  maxconn 256\n  log stderr format raw local0\n"
             "defaults\n  mode http\n  log global\n  option httplog\n  timeout connect 1s\n  timeout client 30s\n  timeout server 30s\n"
             "  timeout tunnel 1h\n  retries 3\n  option redispatch\n"
             "frontend fe\n  bind 127.0.0.1:%d\n  default_backend replicas\n"
             "backend replicas\n  balance roundrobin\n  option httpchk GET /status\n"
             "  http-check expect status 200\n"
             "  server r1 127.0.0.1:%d check inter 200 fall 1 rise 1\n"
             "  server r2 127.0.0.1:%d check inter 200 fall 1 rise 1\n",
             ph, p1, p2);
    write_file(path, text);
    snprintf(log, sizeof log, "%s/haproxy.log", tmp);
    char *hargv[] = {"haproxy", "-db", "-f", path, NULL};
    pids[3] = spawn(log, hargv);
    assert_true(wait_port(ph, 10));
    usleep(800000); /* health checks up */

    /* clients: two through the proxy (round robin: one per replica), one
     * directly on each replica */
    test_ws a, b, d1, d2;
    proto_hello ha, hb, h1, h2;
    connect_hello(&a, ph, &ha);
    connect_hello(&b, ph, &hb);
    connect_hello(&d1, p1, &h1);
    connect_hello(&d2, p2, &h2);
    /* one determinism fingerprint */
    assert_non_null(strstr(h1.server_version, " fp="));
    assert_string_equal(h1.server_version, h2.server_version);
    assert_string_equal(ha.server_version, h1.server_version);

    /* a change too near to reach every replica is refused */
    proto_msg set;
    proto_msg_init(&set, PROTO_SEA_STATE);
    set.u.sea_state.op = PROTO_SEA_SET;
    set.u.sea_state.sea = h1.sea;
    set.u.sea_state.sea.wind_u10 = 14;
    set.u.sea_state.sea.wind_dir_deg = 35;
    snprintf(set.u.sea_state.token, sizeof set.u.sea_state.token, "test-token");
    set.u.sea_state.effective_time = sim_now() + 0.1;
    raw_send(&a, &set);
    proto_msg m;
    assert_int_equal(wait_type(&a, PROTO_ERROR, 3000, &m, NULL, NULL), 1);
    assert_int_equal(m.u.error.code, OCEAN_EINVAL);
    assert_non_null(strstr(m.u.error.message, "sea_lead"));
    proto_msg_free(&m);

    /* set through the proxy: every client of both replicas gets the same
     * announce before it takes effect */
    double eff = sim_now() + 1.5;
    set.u.sea_state.effective_time = eff;
    raw_send(&a, &set);
    test_ws *all[4] = {&a, &b, &d1, &d2};
    for (int k = 0; k < 4; k++) {
        assert_int_equal(wait_type(all[k], PROTO_SEA_STATE, 3000, &m, NULL, NULL), 1);
        assert_int_equal(m.u.sea_state.op, PROTO_SEA_ANNOUNCE);
        assert_true(m.u.sea_state.effective_time == eff);
        assert_true(m.u.sea_state.sea.wind_u10 == 14 && m.u.sea_state.sea.wind_dir_deg == 35);
        assert_true(m.hdr.sim_time < eff);
        proto_msg_free(&m);
    }
    while (sim_now() < eff + 0.5) usleep(50000);
    /* a late joiner of either replica starts from the new sea */
    test_ws j;
    proto_hello hj;
    connect_hello(&j, p2, &hj);
    assert_true(hj.sea.wind_u10 == 14);
    test_ws_close(&j);
    connect_hello(&j, p1, &hj);
    assert_true(hj.sea.wind_u10 == 14);
    test_ws_close(&j);

    /* replay frames: the same bytes from both replicas */
    double times[NFRAMES];
    for (int i = 0; i < NFRAMES; i++) times[i] = eff + 2.0 + i / 30.0;
    uint8_t *ref[NFRAMES];
    size_t reflen[NFRAMES];
    subscribe_replay(&d1);
    subscribe_replay(&d2);
    for (int i = 0; i < NFRAMES; i++) {
        size_t l2;
        ref[i] = replay_frame(&d1, times[i], &reflen[i]);
        uint8_t *o = replay_frame(&d2, times[i], &l2);
        assert_non_null(ref[i]);
        assert_non_null(o);
        assert_int_equal(l2, reflen[i]);
        assert_memory_equal(o, ref[i], l2);
        free(o);
    }

    /* live frames too: the same tick from both replicas is the same bytes,
     * in both layouts (one epoch, one timeline; layout 0 with policy none,
     * layout 1 as the viewer subscribes: nothing depends on history) */
    live_identical(&d1, &d2, PROTO_LAYOUT_WORLD);
    live_identical(&d1, &d2, PROTO_LAYOUT_CASCADE);

    /* the proxied clients stream; replica 1 is killed in the middle */
    subscribe_replay(&a);
    subscribe_replay(&b);
    test_ws *px[2] = {&a, &b};
    for (int k = 0; k < 2; k++)
        for (int i = 0; i < NFRAMES / 2; i++) {
            size_t l;
            uint8_t *o = replay_frame(px[k], times[i], &l);
            assert_non_null(o);
            assert_int_equal(l, reflen[i]);
            assert_memory_equal(o, ref[i], l);
            free(o);
        }
    stop(&pids[1], SIGKILL);
    test_ws_close(&d1);
    int moved = 0;
    for (int k = 0; k < 2; k++) {
        int i0 = NFRAMES / 2;
        for (int i = i0; i < NFRAMES; i++) {
            size_t l;
            uint8_t *o = replay_frame(px[k], times[i], &l);
            if (!o) {
                /* its replica died: reconnect through the proxy (to the
                 * survivor), subscribe again, ask for the same frame */
                moved++;
                test_ws_close(px[k]);
                proto_hello hn;
                connect_hello(px[k], ph, &hn);
                assert_string_equal(hn.server_version, h2.server_version);
                assert_true(hn.sea.wind_u10 == 14);
                subscribe_replay(px[k]);
                o = replay_frame(px[k], times[i], &l);
            }
            assert_non_null(o);
            assert_int_equal(l, reflen[i]);
            assert_memory_equal(o, ref[i], l);
            free(o);
        }
    }
    assert_int_equal(moved, 1); /* round robin put one proxied client on each replica */

    /* the killed replica restarts: it reads the timeline from the stream and
     * serves the same sea and the same bytes at once */
    {
        char exe[600], conf[600];
        snprintf(exe, sizeof exe, "%s/oceand", exe_dir);
        snprintf(conf, sizeof conf, "%s/r1.conf", tmp);
        snprintf(log, sizeof log, "%s/r1b.log", tmp);
        char *oargv[] = {exe, "--config", conf, NULL};
        pids[1] = spawn(log, oargv);
        assert_true(wait_port(p1, 20));
        test_ws r;
        proto_hello hr;
        connect_hello(&r, p1, &hr);
        assert_true(hr.sea.wind_u10 == 14 && hr.sea.wind_dir_deg == 35);
        subscribe_replay(&r);
        size_t l;
        uint8_t *o = replay_frame(&r, times[0], &l);
        assert_non_null(o);
        assert_int_equal(l, reflen[0]);
        assert_memory_equal(o, ref[0], l);
        free(o);
        test_ws_close(&r);
        stop(&pids[1], SIGTERM);
    }

    /* Redis restarts: the first set after it is stored and announced (it
     * was refused once per replica, "SEA_STATE set not stored", the dead
     * publishing connection found only by that XADD), and the replica's log
     * says the reader reconnected (it said only "reconnecting"). */
    {
        stop(&pids[0], SIGKILL);
        snprintf(log, sizeof log, "%s/redis2.log", tmp);
        pids[0] = spawn(log, rargv);
        assert_true(wait_port(prd, 10));
        usleep(600000); /* the reader's retry (every 0.2 s) finds it */
        double eff2 = sim_now() + 1.5;
        set.u.sea_state.effective_time = eff2;
        set.u.sea_state.sea.wind_u10 = 16;
        raw_send(&d2, &set);
        int announced = 0;
        char got[1100] = "nothing within 3 s";
        for (double end = test_now_s() + 3; !announced && test_now_s() < end;) {
            uint8_t *b;
            size_t bl;
            int op = test_ws_recv(&d2, (int)((end - test_now_s()) * 1000) + 1, &b, &bl);
            if (op <= 0) break;
            proto_msg g;
            if (op != 8 && proto_decode(b, bl, &g, NULL, 0) == OCEAN_OK) {
                if (g.hdr.type == PROTO_ERROR) {
                    snprintf(got, sizeof got, "ERROR %s", g.u.error.message);
                    end = 0;
                }
                announced = g.hdr.type == PROTO_SEA_STATE && g.u.sea_state.effective_time == eff2;
                proto_msg_free(&g);
            }
            free(b);
        }
        if (!announced) fail_msg("a set after a Redis restart: %s", got);
        snprintf(path, sizeof path, "%s/r2.log", tmp);
        FILE *lf = fopen(path, "r");
        assert_non_null(lf);
        size_t n = fread(text, 1, sizeof text - 1, lf);
        fclose(lf);
        text[n] = 0;
        if (!strstr(text, "reconnected; reading stream")) fail_msg("replica 2's log: %s", text);
    }

    for (int i = 0; i < NFRAMES; i++) free(ref[i]);
    test_ws_close(&a);
    test_ws_close(&b);
    test_ws_close(&d2);
    stop(&pids[3], SIGTERM);
    stop(&pids[2], SIGTERM);
    stop(&pids[0], SIGTERM);
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf %s", tmp);
    if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", tmp);
}

static int teardown(void **state)
{
    (void)state;
    for (int i = 3; i >= 0; i--) stop(&pids[i], SIGKILL);
    if (tmp[0]) {
        char cmd[300];
        snprintf(cmd, sizeof cmd, "rm -rf %s", tmp);
        if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", tmp);
    }
    return 0;
}

int main(int argc, char **argv)
{
    (void)argc;
    signal(SIGPIPE, SIG_IGN);
    test_build_dir(argv[0], exe_dir, sizeof exe_dir);
    time_t day = time(NULL) / 86400 * 86400 - 86400;
    EPOCH_UNIX = (double)day;
    struct tm tm;
    gmtime_r(&day, &tm);
    strftime(EPOCH_ISO, sizeof EPOCH_ISO, "%Y-%m-%dT%H:%M:%SZ", &tm);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(replicas_behind_haproxy, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
