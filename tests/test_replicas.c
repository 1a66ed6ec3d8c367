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
 *
 * Entities set through one replica (ocean.v1, CIGI) reach every replica
 * at one instant, and queries in a ship's wake get the same bytes from
 * each, and from one started after the sets.
 *
 * The timeline tests: a replica started 20, 200 and 2000 changes after
 * another serves the same sea and the same live bytes; a stalled Redis
 * (SIGSTOP) costs a viewer no frame while a set waits for it; every set is
 * answered (after a far-future id and a deleted stream, at the pending
 * limit); a
 * stream of oversized and garbage entries is read in bounded batches,
 * logged in one line of counts, and a replica still starts on it.
 */
#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <netinet/in.h>
#include <pthread.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stdatomic.h>
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
#include <hiredis/hiredis.h>

#include "cigi.h"
#include "oceanclient.h"
#include "proto.h"
#include "srv_client.h"
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
static int redis_port;

/* The replicas' stream: one per test run. */
static const char *stream_key(void)
{
    static char key[64];
    snprintf(key, sizeof key, "test:%d", (int)getpid());
    return key;
}

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

/* A directory of its own for each test's configurations and logs (the
 * teardown removes it). */
static void make_tmp(void)
{
    static int n;
    snprintf(tmp, sizeof tmp, "/tmp/test_replicas.%d.%d", (int)getpid(), n++);
    mkdir(tmp, 0755);
}

/* Redis on port `port`, without persistence, logging to tmp/logname. */
static void redis_start(int port, const char *logname)
{
    char ports[16], log[600];
    snprintf(ports, sizeof ports, "%d", port);
    snprintf(log, sizeof log, "%s/%s", tmp, logname);
    /* at nice 10: the 2 cores of a CI host go to the daemon first, so what
     * the witness measures is the daemon's work, not Redis storing what a
     * test writes (in production Redis has a machine of its own) */
    char *rargv[] = {"nice", "-n", "10", "redis-server", "--port", ports, "--bind", "127.0.0.1", "--save", "",
                     "--appendonly", "no", "--dir", tmp, NULL};
    pids[0] = spawn(log, rargv);
    assert_true(wait_port(port, 10));
    redis_port = port;
}

/* Waits for replica `pid` to listen on `port`: 1; 0 after `secs`, or as
 * soon as it ends (*status: its wait status, else -1). */
static int wait_replica(pid_t pid, int port, double secs, int *status)
{
    double end = test_now_s() + secs;
    *status = -1;
    while (test_now_s() < end) {
        if (port_open(port)) return 1;
        if (waitpid(pid, status, WNOHANG) == pid) return 0;
        usleep(50000);
    }
    return 0;
}

/* A replica that did not come up says why on stderr: how it ended, or
 * where each of its threads is and the CPU seconds it used (a slow start
 * keeps using them, a hang does not). */
static void replica_explain(pid_t pid, int status)
{
    if (status != -1) {
        fprintf(stderr, "replica pid %d ended: %s %d\n", (int)pid, WIFSIGNALED(status) ? "signal" : "exit",
                WIFSIGNALED(status) ? WTERMSIG(status) : WEXITSTATUS(status));
        return;
    }
    char cmd[300];
    snprintf(cmd, sizeof cmd,
             "cut -d' ' -f14,15 /proc/%d/stat >&2; timeout 60 gdb -batch -p %d -ex 'thread apply all bt 8' "
             "2>/dev/null | grep -E '^(Thread|#)' >&2",
             (int)pid, (int)pid);
    if (system(cmd) != 0) fprintf(stderr, "replica pid %d: no stacks (gdb missing?)\n", (int)pid);
}

/* Replica k (1 or 2) on `port`, sharing the stream of the Redis that
 * redis_start started, logging to tmp/logname; returns once it listens
 * (it reads the stream's whole timeline first: within `deadline` s). */
static char replica_extra[128];  /* more lines for the next replica's config */

static void replica_start_within(int k, int port, const char *logname, double deadline)
{
    char path[600], log[600], text[1024], exe[600];
    snprintf(path, sizeof path, "%s/r%d.conf", tmp, k);
    snprintf(text, sizeof text,
             "sea.wind = 10\nocean.n = 64\nocean.cascades = 2\nocean.patch = 400\nocean.threads = 1\n"
             "server.port = %d\nserver.scene = \"\"\nserver.tick_rate = 30\n"
             "server.admin_token = \"test-token\"\nserver.epoch = %s\n"
             "server.redis = 127.0.0.1:%d\nserver.redis_stream = \"%s\"\nserver.sea_lead = 0.5\n"
             "server.near_field_waves = 32\nserver.view_range = 2000\nserver.workers = 1\n"
             /* admission prices from the host's speed: not what these replicas judge */
             "server.admit_share = 0\n%s",
             port, EPOCH_ISO, redis_port, stream_key(), replica_extra);
    write_file(path, text);
    snprintf(exe, sizeof exe, "%s/oceand", exe_dir);
    snprintf(log, sizeof log, "%s/%s", tmp, logname);
    char *oargv[] = {exe, "--config", path, NULL};
    pids[k] = spawn(log, oargv);
    int status = -1;
    if (!wait_replica(pids[k], port, deadline, &status)) {
        replica_explain(pids[k], status);
        if (status != -1) pids[k] = 0; /* reaped */
        char tail[2048] = "";
        FILE *f = fopen(log, "r");
        size_t n = f ? fread(tail, 1, sizeof tail - 1, f) : 0;
        if (f) fclose(f);
        tail[n] = 0;
        fail_msg("replica %d does not listen on port %d after %.0f s; its log: %s", k, port, deadline, tail);
    }
}

static void replica_start(int k, int port, const char *logname) { replica_start_within(k, port, logname, 20); }

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

/* Next message of `type` (0: any; decoded into *m; raw bytes into *raw if asked).
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
        if (r == OCEAN_OK && (m->hdr.type == type || type == 0)) { /* type 0: any */
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

/* Subscribes w live in `layout` at `hz`, at the camera every live test uses. */
static void subscribe_live(test_ws *w, int layout, float hz)
{
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
    sm.u.subscribe.frame_rate_hz = hz;
    raw_send(w, &sm);
    proto_msg c;
    proto_msg_init(&c, PROTO_CAMERA);
    oc_camera_default(&c.u.camera);
    c.u.camera.pos[0] = 1234.5;
    c.u.camera.pos[1] = 25;
    raw_send(w, &c);
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
    for (int k = 0; k < 2; k++) subscribe_live(dd[k], layout, 30);
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
    make_tmp();
    int prd = test_free_port(), p1 = test_free_port(), p2 = test_free_port(), ph = test_free_port();
    assert_true(prd > 0 && p1 > 0 && p2 > 0 && ph > 0);
    char path[600], log[600], text[4096];

    redis_start(prd, "redis.log");
    replica_start(1, p1, "r1.log");
    replica_start(2, p2, "r2.log");

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
        replica_start(1, p1, "r1b.log");
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
        redis_start(prd, "redis2.log");
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
}

/* ---- the timeline tests ------------------------------------------------------------ */

static int tools_missing(void)
{
    if (have("redis-server")) return 0;
    print_message("redis-server missing (.ci/deps.sh installs it)\n");
    return 1;
}

/* Redis (pids[0]) and replica 1 (pids[1]) on *p1; a connection to Redis
 * (the teardown closes it). */
static redisContext *test_rc;
static redisContext *cluster_up(int *p1)
{
    make_tmp();
    int prd = test_free_port();
    *p1 = test_free_port();
    assert_true(prd > 0 && *p1 > 0);
    redis_start(prd, "redis.log");
    replica_start(1, *p1, "r1.log");
    test_rc = redisConnect("127.0.0.1", prd);
    assert_true(test_rc && !test_rc->err);
    return test_rc;
}

/* The wind of change i in the tests' sequences: every change another sea. */
static double wind_of(int i) { return 6.0 + 0.005 * i; }

/* Appends changes first .. first+n-1 straight into the stream as a replica
 * stores a set (one pipeline): a SEA_STATE announce in field msg, sea `base`
 * with wind_of(i), effective at `eff`. */
static void stream_append(redisContext *rc, const proto_sea *base, int first, int n, double eff)
{
    for (int i = first; i < first + n; i++) {
        proto_msg m;
        proto_msg_init(&m, PROTO_SEA_STATE);
        m.hdr.sim_time = sim_now();
        m.u.sea_state.op = PROTO_SEA_ANNOUNCE;
        m.u.sea_state.effective_time = eff;
        m.u.sea_state.sea = *base;
        m.u.sea_state.sea.wind_u10 = wind_of(i);
        proto_buf b;
        proto_buf_init(&b, 0);
        assert_int_equal(proto_encode(&b, &m, NULL, 0), OCEAN_OK);
        redisAppendCommand(rc, "XADD %s * msg %b", stream_key(), proto_buf_data(&b), b.len);
        proto_buf_free(&b);
    }
    for (int i = 0; i < n; i++) {
        redisReply *rep;
        assert_int_equal(redisGetReply(rc, (void **)&rep), REDIS_OK);
        assert_int_equal(rep->type, REDIS_REPLY_STRING);
        freeReplyObject(rep);
    }
}

/* The sea a new client of the replica on `port` gets in its HELLO. */
static proto_sea hello_sea(int port)
{
    test_ws w;
    proto_hello h;
    connect_hello(&w, port, &h);
    test_ws_close(&w);
    return h.sea;
}

/* Waits (30 s at most) until the replica on `port` serves wind w. */
static void wait_wind(int port, double w)
{
    double end = test_now_s() + 30, got = 0;
    while (test_now_s() < end) {
        got = hello_sea(port).wind_u10;
        if (fabs(got - w) < 1e-9) return;
        usleep(50000);
    }
    fail_msg("the replica on port %d serves wind %.2f, not %.2f", port, got, w);
}

/* The witness: a live viewer of replica 1 (20 Hz, layout 1) read by a
 * thread of its own while a test does what it judges; it must keep 95 % of
 * the frame rate it had before and no wait between frames over 600 ms (or
 * over twice its longest wait before, on a host too loaded for 600 ms
 * without anything being done to the daemon).  The stalls it is there for
 * are the daemon waiting on Redis (its calls time out after about 1 s) or
 * building oceans on the tick: a stall of 250 ms already costs the rate
 * 5 % (frames are replaced, not queued), and one of 1 s the gap.  A busy
 * host alone delayed one frame by 475-570 ms in runs whose control window,
 * nothing done, then kept 200 ms: a single gap is the host's noise, so the
 * bound stays above it. */
typedef struct witness {
    test_ws w;
    pthread_t thread;
    atomic_int stop;
    int frames, lost;   /* [thread until joined] */
    double gap, last;   /* [thread until joined] longest wait, time of the last frame */
    double base_rate, base_gap;
    double t0;
} witness;

/* Reads the viewer for `secs`, counting its FRAMEs; 0 when it closed. */
static int witness_read(witness *v, double secs)
{
    double end = test_now_s() + secs;
    while (test_now_s() < end && !atomic_load(&v->stop)) {
        uint8_t *b;
        size_t n;
        int op = test_ws_recv(&v->w, 10, &b, &n);
        if (op < 0 || op == 8) {
            if (op == 8) free(b);
            return 0;
        }
        if (op == 0) continue;
        proto_msg f;
        if (proto_decode(b, n, &f, NULL, 0) == OCEAN_OK) {
            if (f.hdr.type == PROTO_FRAME) {
                double now = test_now_s();
                v->gap = fmax(v->gap, now - v->last);
                v->last = now;
                v->frames++;
            }
            proto_msg_free(&f);
        }
        free(b);
    }
    return 1;
}

static void *witness_main(void *arg)
{
    witness *v = arg;
    while (!atomic_load(&v->stop))
        if (!witness_read(v, 0.1)) v->lost = 1;
    return NULL;
}

/* The witness's frame rate, Hz. */
#define WITNESS_HZ 20

/* Connects and subscribes the witness, reads 3 s of its stream (its gaps
 * before) and starts its thread. */
static void witness_start(witness *v, int port)
{
    memset(v, 0, sizeof *v);
    proto_hello h;
    connect_hello(&v->w, port, &h);
    subscribe_live(&v->w, PROTO_LAYOUT_CASCADE, WITNESS_HZ);
    v->last = test_now_s();
    assert_true(witness_read(v, 1.0)); /* the stream starts */
    v->frames = 0;
    v->gap = 0;
    assert_true(witness_read(v, 3.0)); /* its gaps before, for the gap rule */
    /* judged against the rate it asked for, not this window's: on a busy
     * host a 3 s window measured 21/s (frames held back before it) or
     * 16/s (the witness starved), and windows judged against it read 87 %
     * to 121 % with nothing wrong (clean runs here, a core busy); a host
     * that cannot hold 20 Hz starves the control too, and is not judged */
    v->base_rate = WITNESS_HZ;
    v->base_gap = v->gap;
    assert_true(v->frames > 0);
    v->frames = 0;
    v->gap = 0;
    v->t0 = v->last = test_now_s();
    atomic_init(&v->stop, 0);
    assert_int_equal(pthread_create(&v->thread, NULL, witness_main, v), 0);
}

/* Stops the witness and prints what it saw since witness_start (over 4 s
 * at least); returns its share of the rate it asked for. */
static double witness_report(witness *v, const char *what)
{
    /* over a shorter window one frame more or less is over 1 % of the rate */
    while (test_now_s() - v->t0 < 4.0) usleep(20000);
    atomic_store(&v->stop, 1);
    pthread_join(v->thread, NULL);
    double now = test_now_s();
    v->gap = fmax(v->gap, now - v->last);
    double keep = v->frames / (now - v->t0) / v->base_rate;
    print_message("%s: witness %d frames in %.2f s (%.0f %% of the rate it asked for), longest gap %.0f ms "
                  "(%.0f ms before)\n", what, v->frames, now - v->t0, 100 * keep, 1e3 * v->gap, 1e3 * v->base_gap);
    test_ws_close(&v->w);
    assert_false(v->lost);
    return keep;
}

/* Whether the witness kept `keep` of its rate and its gaps short. */
static int witness_kept(const witness *v, double keep)
{
    return keep >= 0.95 && v->gap <= fmax(0.6, 2.0 * v->base_gap);
}

/* After a witness missed its mark on every try: a window with nothing done
 * to the daemon.  1 when the witness misses there too: then the host's
 * other jobs starve it, not what the test did, and the test's witness is
 * reported as not judged. */
static int witness_starved(int port)
{
    witness v;
    witness_start(&v, port);
    int starved = !witness_kept(&v, witness_report(&v, "control: nothing done"));
    if (starved) print_message("witness not judged: the host starves it with nothing done to the daemon\n");
    return starved;
}

/* witness_report, judged (witness_starved when it missed). */
static void witness_judge(witness *v, int port, const char *what)
{
    double keep = witness_report(v, what);
    assert_true(witness_kept(v, keep) || witness_starved(port));
}

/* A replica started 20, 200 and 2000 changes after another (every change
 * in force when it starts) serves the latest sea, as the running one does,
 * and the same live bytes tick for tick.  The first 20 come in tens, each
 * ten in force before the next, as sets spread over time do. */
static void late_replicas_agree(void **state)
{
    (void)state;
    if (tools_missing()) skip();
    int p1, p2 = test_free_port();
    redisContext *rc = cluster_up(&p1);
    proto_sea base = hello_sea(p1);
    static const int marks[] = {20, 200, 2000};
    int total = 0;
    /* No witness here: each group of changes takes effect at once, its
     * ocean built on the tick that applies it (not ahead of time, as a
     * change announced ahead is), which this test does not judge. */
    for (int k = 0; k < 3; k++) {
        while (total < marks[k]) {
            int n = total < 20 ? 10 : marks[k] - total < 300 ? marks[k] - total : 300;
            stream_append(rc, &base, total, n, sim_now() - 1);
            total += n;
            wait_wind(p1, wind_of(total - 1));
        }
        replica_start(2, p2, "r2.log");
        proto_sea s2 = hello_sea(p2);
        if (fabs(s2.wind_u10 - wind_of(total - 1)) > 1e-9)
            fail_msg("after %d changes the new replica serves wind %.2f, the running one %.2f", total,
                     s2.wind_u10, wind_of(total - 1));
        test_ws d1, d2;
        proto_hello h1, h2;
        connect_hello(&d1, p1, &h1);
        connect_hello(&d2, p2, &h2);
        print_message("%d changes apart:\n", total);
        live_identical(&d1, &d2, PROTO_LAYOUT_CASCADE);
        test_ws_close(&d1);
        test_ws_close(&d2);
        stop(&pids[2], SIGTERM);
    }
    stop(&pids[1], SIGTERM); /* its shutdown too runs under the sanitizers */
}

/* ---- entities ---------------------------------------------------------------------- */

/* An ENTITY set of ship id (120 x 15 x 5 m) at (x, -20) steaming along +x
 * at `speed` m/s, sample time t; or a remove (x NaN). */
static void ship_at(test_ws *w, uint32_t id, double t, double x, double speed)
{
    proto_msg m;
    proto_msg_init(&m, PROTO_ENTITY);
    proto_entity *e = &m.u.entity;
    e->id = id;
    e->op = isnan(x) ? PROTO_ENTITY_REMOVE : PROTO_ENTITY_SET;
    if (!isnan(x)) {
        e->kind = 0, e->t = t, e->x = x, e->z = -20, e->speed = (float)speed, e->heading_deg = 0;
        e->length_m = 120, e->beam_m = 15, e->draught_m = 5;
    }
    snprintf(e->token, sizeof e->token, "ent");
    raw_send(w, &m);
}

static void ship_send(test_ws *w, uint32_t id, double t, double x) { ship_at(w, id, t, x, 8); }

#define WAKES_MAX 8

/* The WAKE messages a layout-1 viewer on w gets for `seconds` or until it
 * holds `want`: their bytes past the header's seq, into got[] (malloc'd)
 * after the *n already there, ordered by their parameters; *n counts
 * them. */
static void wakes_collect(test_ws *w, int want, double seconds, uint8_t *got[WAKES_MAX], size_t len[WAKES_MAX],
                          int *count)
{
    int n = *count;
    for (double end = test_now_s() + seconds; n < want && test_now_s() < end;) {
        proto_msg m;
        uint8_t *raw;
        size_t rawlen;
        if (wait_type(w, PROTO_WAKE, 1000, &m, &raw, &rawlen) != 1) continue;
        proto_msg_free(&m);
        int at = n;
        while (at > 0 && memcmp(raw + PROTO_HEADER_SIZE, got[at - 1] + PROTO_HEADER_SIZE - 24, 32) < 0) at--;
        memmove(&got[at + 1], &got[at], sizeof got[0] * (size_t)(n - at));
        memmove(&len[at + 1], &len[at], sizeof len[0] * (size_t)(n - at));
        got[at] = malloc(rawlen - 24);
        memcpy(got[at], raw + 24, rawlen - 24);
        len[at] = rawlen - 24;
        free(raw);
        if (++n == WAKES_MAX) break;
    }
    *count = n;
}

/* The next ENTITY of op about id on w (an announce: of the sample of track
 * time t; NAN: any); returns the instant it takes effect (its header
 * sim_time).  A deadline of 60 s: an entry goes through
 * Redis and comes between the live frames of a subscribed viewer, which a
 * loaded host (a core held, the sanitizer build beside the tests) reads
 * slowly; 20 s ran out once there. */
static double entity_wait_t(test_ws *w, int op, uint32_t id, double t)
{
    proto_msg m;
    for (double end = test_now_s() + 60; test_now_s() < end;) {
        if (wait_type(w, 0, 60000, &m, NULL, NULL) != 1) break;
        if (m.hdr.type == PROTO_ERROR) fail_msg("ERROR for entity %u: %s", id, m.u.error.message);
        if (m.hdr.type != PROTO_ENTITY) {
            proto_msg_free(&m);
            continue;
        }
        double from = m.hdr.sim_time;
        int match = m.u.entity.op == op && m.u.entity.id == id && (isnan(t) || m.u.entity.t == t);
        proto_msg_free(&m);
        if (match) return from;
    }
    fail_msg("no ENTITY op %d of entity %u", op, id);
    return 0;
}

static double entity_wait(test_ws *w, int op, uint32_t id) { return entity_wait_t(w, op, id, NAN); }

/* A CIGI host's surface wind, sent to one replica's CIGI port, enters the
 * shared timeline as an admin's set does: every replica serves it (the set
 * was refused at first, its effective time computed a moment before the
 * stream's lead check); so does its Entity Control, every replica
 * announcing the ship at one instant.  The host repeats its frame until the wind shows:
 * the first may come before the CIGI port is bound. */
static void cigi_wind_reaches_every_replica(void **state)
{
    (void)state;
    if (tools_missing()) skip();
    int cport = test_free_port(), p1, p2 = test_free_port();
    snprintf(replica_extra, sizeof replica_extra, "server.cigi_port = %d\n", cport);
    cluster_up(&p1);
    replica_extra[0] = '\0';
    replica_start(2, p2, "r2.log");
    const cigi_format f = {3, 3, 1};
    proto_buf b;
    proto_buf_init(&b, 0);
    cigi_packet ig = {.kind = CIGI_IG_CONTROL}, atm = {.kind = CIGI_ATMOSPHERE_CONTROL};
    ig.u.ig.ig_mode = 1;
    atm.u.atmosphere = (cigi_atmosphere){.enable = 1, .humidity = 50, .visibility = 10000, .wind_h = 17.5,
                                         .wind_dir = 270, .pressure = 1013};
    assert_int_equal(cigi_put(&b, &f, &ig), OCEAN_OK);
    assert_int_equal(cigi_put(&b, &f, &atm), OCEAN_OK);
    int fd = socket(AF_INET, SOCK_DGRAM, 0);
    struct sockaddr_in to = {.sin_family = AF_INET, .sin_port = htons((uint16_t)cport)};
    inet_pton(AF_INET, "127.0.0.1", &to.sin_addr);
    double got = 0;
    for (double end = test_now_s() + 30; test_now_s() < end && got != 17.5;) {
        sendto(fd, proto_buf_data(&b), proto_buf_len(&b), 0, (struct sockaddr *)&to, sizeof to);
        usleep(500000);
        got = hello_sea(p1).wind_u10;
    }
    if (got != 17.5) fail_msg("the replica the host spoke to serves wind %.2f, not 17.50", got);
    wait_wind(p2, 17.5);
    /* the host's ship, placed on replica 1, is announced by replica 2 at
     * the instant the stream gives it, and replica 1 at the same */
    test_ws v1, v2;
    proto_hello h;
    connect_hello(&v1, p1, &h);
    connect_hello(&v2, p2, &h);
    cigi_packet ship = {.kind = CIGI_ENTITY_CONTROL};
    ship.u.entity = (cigi_entity){.id = 44, .state = CIGI_ENTITY_ACTIVE, .clamp = CIGI_CLAMP_CONFORMAL,
                                  .lat = 0.001, .lon = 0.001, .yaw = 90};
    proto_buf b2;
    proto_buf_init(&b2, 0);
    assert_int_equal(cigi_put(&b2, &f, &ig), OCEAN_OK);
    assert_int_equal(cigi_put(&b2, &f, &ship), OCEAN_OK);
    double t0 = sim_now();
    sendto(fd, proto_buf_data(&b2), proto_buf_len(&b2), 0, (struct sockaddr *)&to, sizeof to);
    proto_buf_free(&b2);
    double f1 = entity_wait(&v1, PROTO_ENTITY_ANNOUNCE, 44), f2 = entity_wait(&v2, PROTO_ENTITY_ANNOUNCE, 44);
    if (f1 != f2) fail_msg("the host's ship in force from %.6f on replica 1, %.6f on replica 2", f1, f2);
    assert_true(f1 >= t0 + 0.5); /* server.sea_lead */
    test_ws_close(&v1);
    test_ws_close(&v2);
    close(fd);
    proto_buf_free(&b);
    stop(&pids[2], SIGTERM);
    stop(&pids[1], SIGTERM);
}

#define WAKE_POINTS 64

/* The answer of the replica w is connected to for WAKE_POINTS points
 * around (x, -20) at sim time t, into out. */
static void wake_query(test_ws *w, double t, double x, proto_query_sample *out)
{
    static uint32_t qid;
    double pts[2 * WAKE_POINTS];
    for (int i = 0; i < WAKE_POINTS; i++) {
        pts[2 * i] = x - 60 + 120.0 * (i % 8) / 7;
        pts[2 * i + 1] = -20 - 40 + 80.0 * (i / 8) / 7;
    }
    proto_msg m;
    proto_msg_init(&m, PROTO_QUERY);
    m.u.query = (proto_query){.query_id = ++qid, .count = WAKE_POINTS, .at_time = 1, .t = t, .points = pts};
    raw_send(w, &m);
    /* a replica builds a wake pattern it lacks before it answers (0.1-10 s,
     * at nice 10: far longer on a busy host) */
    if (wait_type(w, PROTO_QUERY_RESULT, 120000, &m, NULL, NULL) != 1) fail_msg("no QUERY_RESULT");
    assert_int_equal(m.u.result.query_id, qid);
    assert_int_equal(m.u.result.count, WAKE_POINTS);
    memcpy(out, m.u.result.samples, sizeof *out * WAKE_POINTS);
    proto_msg_free(&m);
}

static void answers_same(const proto_query_sample *a, const proto_query_sample *b, const char *what)
{
    if (memcmp(a, b, sizeof *a * WAKE_POINTS) == 0) return;
    for (int i = 0; i < WAKE_POINTS; i++)
        if (memcmp(&a[i], &b[i], sizeof *a))
            fail_msg("%s: point %d: height %.9g against %.9g", what, i, a[i].height, b[i].height);
}

/* Ships set through one replica reach every replica through the stream:
 * the setter's reply and the other replica's clients get the same
 * announce, in force from one instant at least server.sea_lead ahead.  A
 * query around the second ship, 300 m astern in the first's wake, at an
 * instant both are in force gets the same bytes from both replicas and
 * from a replica started after the sets (which folds them from the
 * stream); a third, faster ship added, layout-1 viewers of the first and
 * the late replica get the same WAKE patterns, byte for byte; a removal
 * sent to the other replica is gone from its own instant on, and the
 * instants before it answer as they did. */
static void entities_reach_every_replica(void **state)
{
    (void)state;
    if (tools_missing()) skip();
    int p1, p2 = test_free_port(), p3 = test_free_port();
    snprintf(replica_extra, sizeof replica_extra, "server.entity_token = \"ent\"\n");
    cluster_up(&p1);
    replica_start(2, p2, "r2.log");
    test_ws a, b, c;
    proto_hello h;
    connect_hello(&a, p1, &h);
    connect_hello(&b, p2, &h);
    double t0 = sim_now(), in_force = 0;
    for (uint32_t id = 31; id <= 32; id++) {
        ship_send(&a, id, t0, id == 31 ? 0 : -300);
        double fa = entity_wait(&a, PROTO_ENTITY_ANNOUNCE, id), fb = entity_wait(&b, PROTO_ENTITY_ANNOUNCE, id);
        if (fa != fb) fail_msg("entity %u in force from %.6f on replica 1, %.6f on replica 2", id, fa, fb);
        assert_true(fa >= t0 + 0.5); /* server.sea_lead */
        in_force = fmax(in_force, fa);
    }
    double tq = in_force + 1, x32 = -300 + 8 * (tq - t0);
    proto_query_sample q1[WAKE_POINTS], q2[WAKE_POINTS], q3[WAKE_POINTS];
    wake_query(&a, tq, x32, q1);
    wake_query(&b, tq, x32, q2);
    answers_same(q1, q2, "replica 2 against replica 1");
    replica_start(3, p3, "r3.log");
    connect_hello(&c, p3, &h);
    assert_true(entity_wait(&c, PROTO_ENTITY_ANNOUNCE, 31) > 0); /* a joiner hears the entities in force */
    wake_query(&c, tq, x32, q3);
    answers_same(q1, q3, "a replica started after the sets against replica 1");
    /* a third ship, twice as fast: viewers of replicas 1 and 3 get the
     * same two wake patterns (8 and 16 m/s are rungs of the ladder: one
     * pattern each), byte for byte */
    while (sim_now() < tq) usleep(20000); /* what comes now takes effect after tq: tq is its past */
    double t33 = sim_now();
    ship_at(&b, 33, t33, -600, 16);
    entity_wait(&a, PROTO_ENTITY_ANNOUNCE, 33);
    entity_wait(&c, PROTO_ENTITY_ANNOUNCE, 33);
    subscribe_live(&a, PROTO_LAYOUT_CASCADE, 10);
    subscribe_live(&c, PROTO_LAYOUT_CASCADE, 10);
    uint8_t *wa[WAKES_MAX], *wc[WAKES_MAX];
    size_t la[WAKES_MAX], lc[WAKES_MAX];
    int na = 0, nc = 0;
    /* ships 31 and 33 sampled on along their tracks every few seconds: a
     * ship is held 10 s after its last sample, and a held ship makes no
     * wake (a busy host's builds at nice 10 took longer than that) */
    for (double end = test_now_s() + 120; (na < 2 || nc < 2) && test_now_s() < end;) {
        double tn = sim_now();
        ship_send(&a, 31, tn, 8 * (tn - t0));
        ship_at(&b, 33, tn, -600 + 16 * (tn - t33), 16);
        wakes_collect(&a, 2, 2.0, wa, la, &na);
        wakes_collect(&c, 2, 2.0, wc, lc, &nc);
    }
    if (na != 2 || nc != 2) fail_msg("WAKE patterns: replica 1 sent %d, replica 3 %d, of the 2 the ships need", na, nc);
    for (int i = 0; i < 2; i++) {
        if (la[i] != lc[i] || memcmp(wa[i], wc[i], la[i]) != 0)
            fail_msg("WAKE %d: %zu bytes from replica 1, %zu from replica 3, not the same", i, la[i], lc[i]);
        print_message("WAKE %d: %zu bytes, the same from both replicas\n", i, la[i] + 24);
        free(wa[i]);
        free(wc[i]);
    }
    /* Ship 31's last sample is in the stream before its removal is made:
     * made on another replica, a sample still on its way would follow the
     * removal there and start a new life, which a replica may not have read
     * yet when asked about the instant after the removal (ahead of the
     * clock, not settled) */
    double t31 = sim_now();
    ship_send(&a, 31, t31, 8 * (t31 - t0));
    entity_wait_t(&a, PROTO_ENTITY_ANNOUNCE, 31, t31);
    /* the remover hears first: a refusal would come to it alone */
    ship_send(&b, 31, 0, NAN);
    double gone = entity_wait(&b, PROTO_ENTITY_GONE, 31);
    assert_true(gone > tq && gone == entity_wait(&a, PROTO_ENTITY_GONE, 31));
    /* replica 3 read the removal too before it is asked about the instant
     * after it (a second past the removal: still ahead of the clock, where
     * an entry not yet read would change the answer) */
    assert_true(gone == entity_wait(&c, PROTO_ENTITY_GONE, 31));
    wake_query(&a, tq, x32, q2);
    answers_same(q1, q2, "replica 1 before the removal's instant, asked after it");
    wake_query(&a, gone + 1, x32 + 8, q1);
    wake_query(&c, gone + 1, x32 + 8, q3);
    answers_same(q1, q3, "after the removal, replica 3 against replica 1");
    test_ws_close(&a);
    test_ws_close(&b);
    test_ws_close(&c);
    replica_extra[0] = '\0';
    stop(&pids[3], SIGTERM);
    stop(&pids[2], SIGTERM);
    stop(&pids[1], SIGTERM);
}

/* A set while Redis is stopped (SIGSTOP) is answered EIO by the
 * replication thread, and the witness keeps its frames meanwhile: the
 * service thread never waits for Redis.  Tried up to 3 times: a burst of
 * load from the host's other jobs can cost the witness a frame on any try,
 * a stalled Redis would on every one (and a control window with nothing
 * done tells a host that starves the witness on every try). */
static void stalled_redis_costs_no_frame(void **state)
{
    (void)state;
    if (tools_missing()) skip();
    int p1;
    cluster_up(&p1);
    test_ws s;
    proto_hello hs;
    connect_hello(&s, p1, &hs);
    int ok = 0;
    for (int attempt = 0; attempt < 3 && !ok; attempt++) {
        witness v;
        witness_start(&v, p1);
        kill(pids[0], SIGSTOP);
        proto_msg set, m;
        proto_msg_init(&set, PROTO_SEA_STATE);
        set.u.sea_state.op = PROTO_SEA_SET;
        set.u.sea_state.sea = hs.sea;
        set.u.sea_state.sea.wind_u10 = 12;
        snprintf(set.u.sea_state.token, sizeof set.u.sea_state.token, "test-token");
        set.u.sea_state.effective_time = sim_now() + 10;
        double t0 = test_now_s();
        raw_send(&s, &set);
        int answered = wait_type(&s, PROTO_ERROR, 8000, &m, NULL, NULL);
        double answer_s = test_now_s() - t0;
        usleep(300000); /* the witness goes on a little after the answer */
        kill(pids[0], SIGCONT);
        double keep = witness_report(&v, "a set while Redis is stopped");
        assert_int_equal(answered, 1);
        print_message("the set was answered %s after %.2f s\n", ocean_strerror((ocean_result)m.u.error.code),
                      answer_s);
        assert_int_equal(m.u.error.code, OCEAN_EIO);
        proto_msg_free(&m);
        ok = witness_kept(&v, keep);
    }
    assert_true(ok || witness_starved(p1));
    test_ws_close(&s);
    stop(&pids[1], SIGTERM);
}

/* A set through replica 1 (on test_ws w): its announce or an ERROR within
 * 8 s; returns the ERROR's code, OCEAN_OK for the announce. */
static ocean_result set_answer(test_ws *w, const proto_sea *sea, double eff)
{
    proto_msg set, m;
    proto_msg_init(&set, PROTO_SEA_STATE);
    set.u.sea_state.op = PROTO_SEA_SET;
    set.u.sea_state.sea = *sea;
    set.u.sea_state.effective_time = eff;
    snprintf(set.u.sea_state.token, sizeof set.u.sea_state.token, "test-token");
    raw_send(w, &set);
    double end = test_now_s() + 8;
    while (test_now_s() < end) {
        uint8_t *b;
        size_t n;
        int op = test_ws_recv(w, (int)((end - test_now_s()) * 1000) + 1, &b, &n);
        assert_true(op >= 0 && op != 8);
        if (op == 0) break;
        int r = -1; /* nothing yet */
        if (proto_decode(b, n, &m, NULL, 0) == OCEAN_OK) {
            if (m.hdr.type == PROTO_SEA_STATE && m.u.sea_state.effective_time == eff) r = OCEAN_OK;
            if (m.hdr.type == PROTO_ERROR) r = m.u.error.code;
            proto_msg_free(&m);
        }
        free(b);
        if (r >= 0) return (ocean_result)r;
    }
    fail_msg("no answer within 8 s to a set effective at %.3f", eff);
    return OCEAN_EIO;
}

/* GET path on the replica at port: the body (status line and headers
 * skipped) into out. */
static void http_body(int port, const char *path, char *out, size_t cap)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port),
                            .sin_addr.s_addr = htonl(INADDR_LOOPBACK)};
    assert_int_equal(connect(fd, (struct sockaddr *)&a, sizeof a), 0);
    char req[200];
    int n = snprintf(req, sizeof req, "GET %s HTTP/1.0\r\nHost: x\r\n\r\n", path);
    assert_int_equal(write(fd, req, (size_t)n), n);
    size_t len = 0;
    ssize_t got;
    while (len + 1 < cap && (got = read(fd, out + len, cap - 1 - len)) > 0) len += (size_t)got;
    close(fd);
    out[len] = 0;
    char *body = strstr(out, "\r\n\r\n");
    if (body) memmove(out, body + 4, strlen(body + 4) + 1);
}

/* What the set tests start from: cluster_up (Redis, replica 1 on port), a
 * client of replica 1 (w) whose first set (30 s ahead, sea) is announced,
 * then the witness (v) started: the simulation thread builds the ocean of
 * the earliest pending change ahead of time, and that build is not what
 * these tests judge (every later change of theirs is later).  Skips the
 * test without Redis. */
typedef struct set_case {
    int port;
    test_ws w;
    proto_sea sea;
    witness v;
    redisContext *rc;
} set_case;

static void set_ready(set_case *k)
{
    if (tools_missing()) skip();
    k->rc = cluster_up(&k->port);
    proto_hello h;
    connect_hello(&k->w, k->port, &h);
    k->sea = h.sea;
    k->sea.wind_u10 = 11;
    assert_int_equal(set_answer(&k->w, &k->sea, sim_now() + 30), OCEAN_OK);
    witness_start(&k->v, k->port);
}

/* A stream entry far in the future, then the stream deleted: the next set
 * still comes back (the reset is seen, and shown in /status and /metrics
 * with the far-future id). */
static void sets_answered_after_a_reset(void **state)
{
    (void)state;
    set_case k;
    set_ready(&k);
    proto_msg far;
    proto_msg_init(&far, PROTO_SEA_STATE);
    far.hdr.sim_time = sim_now();
    far.u.sea_state.op = PROTO_SEA_ANNOUNCE;
    far.u.sea_state.effective_time = sim_now() + 40;
    far.u.sea_state.sea = k.sea;
    proto_buf b;
    proto_buf_init(&b, 0);
    assert_int_equal(proto_encode(&b, &far, NULL, 0), OCEAN_OK);
    redisReply *rep = redisCommand(k.rc, "XADD %s 9999999999999-0 msg %b", stream_key(), proto_buf_data(&b), b.len);
    assert_true(rep && rep->type == REDIS_REPLY_STRING);
    freeReplyObject(rep);
    proto_buf_free(&b);
    assert_int_equal(wait_type(&k.w, PROTO_SEA_STATE, 3000, &far, NULL, NULL), 1); /* read: announced */
    rep = redisCommand(k.rc, "DEL %s", stream_key());
    freeReplyObject(rep);
    k.sea.wind_u10 = 12;
    assert_int_equal(set_answer(&k.w, &k.sea, sim_now() + 50), OCEAN_OK);
    witness_judge(&k.v, k.port, "a far-future id, then the stream deleted");
    char body[16384];
    http_body(k.port, "/status", body, sizeof body);
    if (!strstr(body, "\"stream_resets\":1") || !strstr(body, "\"future_ids\":1")) fail_msg("/status: %s", body);
    http_body(k.port, "/metrics", body, sizeof body);
    assert_non_null(strstr(body, "oceand_redis_stream_resets_total 1\n"));
    assert_non_null(strstr(body, "oceand_redis_future_ids_total 1\n"));
    test_ws_close(&k.w);
    stop(&pids[1], SIGTERM);
}

/* With the pending changes at their limit, one more set is refused ERATE,
 * not left unanswered. */
static void sets_answered_at_the_pending_limit(void **state)
{
    (void)state;
    set_case k;
    set_ready(&k);
    int announced = 0;
    ocean_result r = OCEAN_OK;
    for (int i = 0; i < SRV_SEA_PENDING_MAX && r == OCEAN_OK; i++) {
        k.sea.wind_u10 = 13 + 0.1 * i;
        r = set_answer(&k.w, &k.sea, sim_now() + 60 + i);
        announced += r == OCEAN_OK;
    }
    witness_judge(&k.v, k.port, "sets up to the pending limit and one more");
    print_message("%d sets announced after the first, then %s\n", announced, ocean_strerror(r));
    assert_int_equal(r, OCEAN_ERATE);
    assert_int_equal(announced, SRV_SEA_PENDING_MAX - 1);
    test_ws_close(&k.w);
    stop(&pids[1], SIGTERM);
}

/* VmHWM (peak resident set) of process pid, MB. */
static double peak_mb(pid_t pid)
{
    char path[64], line[256];
    snprintf(path, sizeof path, "/proc/%d/status", (int)pid);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    double kb = -1;
    while (fgets(line, sizeof line, f))
        if (sscanf(line, "VmHWM: %lf kB", &kb) == 1) break;
    fclose(f);
    assert_true(kb >= 0);
    return kb / 1024;
}

/* Lines of tmp/name that contain `needle`. */
static int log_lines(const char *name, const char *needle)
{
    char path[600], line[4096];
    snprintf(path, sizeof path, "%s/%s", tmp, name);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    int n = 0;
    while (fgets(line, sizeof line, f)) n += strstr(line, needle) != NULL;
    fclose(f);
    return n;
}

enum { HOSTILE_BIG = 16, HOSTILE_GARBAGE = 20000 };

/* Appends HOSTILE_BIG entries of 4 MB and HOSTILE_GARBAGE small ones that
 * are no change (half with a msg that is no message, half without msg). */
static void hostile_append(redisContext *rc)
{
    size_t big = 4u << 20;
    char *blob = malloc(big);
    assert_non_null(blob);
    memset(blob, 'x', big);
    for (int i = 0; i < HOSTILE_BIG; i++) redisAppendCommand(rc, "XADD %s * msg %b", stream_key(), blob, big);
    for (int i = 0; i < HOSTILE_GARBAGE; i++)
        redisAppendCommand(rc, i % 2 ? "XADD %s * msg %d" : "XADD %s * other %d", stream_key(), i);
    for (int i = 0; i < HOSTILE_BIG + HOSTILE_GARBAGE; i++) {
        redisReply *rep;
        assert_int_equal(redisGetReply(rc, (void **)&rep), REDIS_OK);
        freeReplyObject(rep);
    }
    free(blob);
}

/* 16 entries of 4 MB and 20 000 garbage entries: the replica reads them in
 * bounded batches (its peak memory grows by far less than one entry's
 * worth of them), counts them in /status, logs them in one line of counts,
 * still takes sets, and a replica started on that stream starts and serves
 * the same sea.  The witness is judged as in the stall test: up to 3 tries. */
static void hostile_stream_bounded(void **state)
{
    (void)state;
    if (tools_missing()) skip();
    int p1, p2 = test_free_port();
    test_ws w;
    proto_hello h;
    redisContext *rc = cluster_up(&p1);
    connect_hello(&w, p1, &h);
    proto_sea sea = h.sea;
    double peak0 = 0;
    int tries = 0, kept = 0;
    double reading = 0; /* seconds the replica had the hostile entries to read */
    while (!kept && tries < 3) {
        witness v;
        witness_start(&v, p1);
        if (!tries) peak0 = peak_mb(pids[1]);
        double t0 = test_now_s();
        hostile_append(rc);
        tries++;
        /* a set stored after them comes back: the replica has read them
         * all (30 s ahead: no new ocean is built while the witness is
         * judged) */
        sea.wind_u10 = 8 + 0.1 * tries;
        assert_int_equal(set_answer(&w, &sea, sim_now() + 30 + tries), OCEAN_OK);
        reading += test_now_s() - t0;
        kept = witness_kept(&v, witness_report(&v, "16 entries of 4 MB and 20 000 garbage entries"));
    }
    assert_true(kept || witness_starved(p1));
    int n = tries * (HOSTILE_BIG + HOSTILE_GARBAGE);
    double grew = peak_mb(pids[1]) - peak0;
    int lines = log_lines("r1.log", "redis stream");
    print_message("%d hostile entries: peak memory +%.1f MB, %d log lines\n", n, grew, lines);
    /* half of the 64 MB the large entries hold, none of them held; under
     * the sanitizers the peak counts every byte freed meanwhile (their
     * quarantine keeps it), the witness's frames too: not judged there */
    int sanitized = getenv("OCEAN_TEST_SANITIZED") != NULL;
    assert_true(sanitized || grew < 32);
    /* one line of counts per 10 s at most, over however long a slow host
     * (ASan: 50 s) took to read them */
    int most = 1 + tries + (int)(reading / 10.0);
    if (lines < 1 || lines > most) fail_msg("%d log lines of skipped entries over %.0f s (want 1 to %d)", lines, reading, most);
    char body[16384], want[64];
    snprintf(want, sizeof want, "\"skipped\":%d", n);
    http_body(p1, "/status", body, sizeof body);
    if (!strstr(body, want)) fail_msg("/status after %d hostile entries: %s", n, body);
    sea.wind_u10 = 9;
    assert_int_equal(set_answer(&w, &sea, sim_now() + 1), OCEAN_OK);
    wait_wind(p1, 9);
    /* 60 000 entries, 48 of them 4 MB, read before it listens: on a host
     * with a core busy Redis answered a batch of them in more than the
     * reader's second, and the reads of fewer entries took over 20 s */
    replica_start_within(2, p2, "r2.log", 180);
    assert_true(hello_sea(p2).wind_u10 == 9);
    assert_true(log_lines("r2.log", "redis stream") == 1);
    double start_peak = peak_mb(pids[2]) - peak0;
    print_message("a replica started on that stream: peak memory %+.1f MB against the first's before them\n",
                  start_peak);
    assert_true(sanitized || start_peak < 32);
    test_ws_close(&w);
    stop(&pids[1], SIGTERM);
}

static int teardown(void **state)
{
    (void)state;
    if (test_rc) redisFree(test_rc);
    test_rc = NULL;
    for (int i = 3; i >= 0; i--) {
        if (pids[i] > 0) kill(pids[i], SIGCONT); /* a test that failed with Redis stopped */
        stop(&pids[i], SIGKILL);
    }
    if (tmp[0] && getenv("TEST_KEEP_LOGS")) { /* TEST_KEEP_LOGS=1: the logs stay, for a failure's reader */
        fprintf(stderr, "logs kept in %s\n", tmp);
    } else if (tmp[0]) {
        char cmd[300];
        snprintf(cmd, sizeof cmd, "rm -rf %s", tmp);
        if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", tmp);
    }
    tmp[0] = 0;
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
    const char *filter = getenv("TEST_FILTER"); /* TEST_FILTER=NAME (a cmocka pattern): those tests */
    if (filter && *filter) cmocka_set_test_filter(filter);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(replicas_behind_haproxy, teardown),
        cmocka_unit_test_teardown(late_replicas_agree, teardown),
        cmocka_unit_test_teardown(cigi_wind_reaches_every_replica, teardown),
        cmocka_unit_test_teardown(entities_reach_every_replica, teardown),
        cmocka_unit_test_teardown(stalled_redis_costs_no_frame, teardown),
        cmocka_unit_test_teardown(sets_answered_after_a_reset, teardown),
        cmocka_unit_test_teardown(sets_answered_at_the_pending_limit, teardown),
        cmocka_unit_test_teardown(hostile_stream_bounded, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
