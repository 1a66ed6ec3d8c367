/*
 * test_attacks.c - one client cannot hurt the others (issue 15).
 *
 * The attacks of the report, run on loopback against the daemon
 * while a witness viewer (an ordinary live subscriber, 20 Hz) watches.  For
 * each attack the test asserts:
 *   - the documented answer (ERROR code naming the limit, WebSocket close
 *     code, HTTP status);
 *   - the witness keeps >= 95 % of its frames over the attack's window
 *     and never waits more than 200 ms between two of them;
 *   - the process's resident memory stays under a ceiling (baseline +
 *     RSS_CEILING_MB, more under ASan, whose quarantine keeps freed memory
 *     resident).
 * The daemon runs in-process (srv_daemon_start) so the plain and the ASan
 * builds of this program test the plain and the ASan daemon; the fd-limit
 * attack execs build/oceand of the same build under a low RLIMIT_NOFILE.
 * The figures go to stderr as one line per attack and a closing summary
 * (README: "Attacks").
 *
 * Expected answers come from RFC 6455 (sections cited at each attack) and
 * from the daemon's documented limits (config/oceand.conf), never from its
 * own output.
 */
#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <pthread.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <dirent.h>
#include <time.h>
#include <unistd.h>

#include <cmocka.h>
#include <cJSON.h>

#include "cigi.h"
#include "ocean.h"
#include "oceanclient.h"
#include "srv_client.h"
#include "srv_daemon.h"
#include "srv_stats.h"
#include "lib/test_ws.h"
#include "lib/test_net.h"

#define WITNESS_HZ 20.0
#define KEEP_MIN 0.95          /* frames the witness must keep */
#define GAP_MAX_MS 200.0       /* longest wait between two witness frames */
/* Under ASan every frame and every ocean a legitimate sea change builds
 * costs 3-5x: a busy host's sanitizer pass saw the witness keep 84-93 % of
 * its frames through 20 admin sea changes a second (gaps 167-231 ms) while
 * its control window kept 100 %.  That pass judges the attacks' memory and
 * answers, and starvation at these looser bounds; the real-time bounds
 * above are the plain pass's. */
#define KEEP_MIN_ASAN 0.80
#define GAP_MAX_ASAN_MS 400.0
#define RSS_CEILING_MB 256.0   /* growth allowed over the baseline (plain) */
#define RSS_CEILING_ASAN_MB 768.0
#define WINDOW_MIN_S 2.0       /* every attack is watched at least this long */

static int sanitized;
static char tmpdir[256], conf_path[300], exe_dir[512];
static srv_settings settings;
static srv_daemon *daemon_;
static int port;
static oc_loop *loop;

static uint64_t stat_of(atomic_uint_fast64_t *a) { return (uint64_t)atomic_load(a); }

/* ---- the witness, the memory sampler and the per-attack window --------------- */

static struct {
    oc_client *c;
    uint32_t id;
    pthread_mutex_t mu;
    int counting, frames;
    double last, max_gap;
} wit = {.mu = PTHREAD_MUTEX_INITIALIZER};

static void on_witness_frame(void *user, oc_client *c, const oc_frame *f)
{
    (void)user, (void)c, (void)f;
    double t = test_now_s();
    pthread_mutex_lock(&wit.mu);
    if (wit.counting) {
        wit.frames++;
        if (t - wit.last > wit.max_gap) wit.max_gap = t - wit.last;
    }
    wit.last = t;
    pthread_mutex_unlock(&wit.mu);
}

static double rss_mb(void)
{
    FILE *f = fopen("/proc/self/statm", "r");
    if (!f) return 0;
    long pages = 0, res = 0;
    int n = fscanf(f, "%ld %ld", &pages, &res);
    fclose(f);
    return n == 2 ? (double)res * (double)sysconf(_SC_PAGESIZE) / (1 << 20) : 0;
}

static struct {
    pthread_t th;
    atomic_int stop;
    pthread_mutex_t mu;
    double peak;
} mem = {.mu = PTHREAD_MUTEX_INITIALIZER};

static void *mem_main(void *arg)
{
    (void)arg;
    while (!atomic_load(&mem.stop)) {
        double r = rss_mb();
        pthread_mutex_lock(&mem.mu);
        if (r > mem.peak) mem.peak = r;
        pthread_mutex_unlock(&mem.mu);
        usleep(10000);
    }
    return NULL;
}

static double rss_base, rss_ceiling;
static double win_t0;
static int n_attacks;
static double worst_keep = 1e9, worst_gap, worst_rss;

static void window_begin(void)
{
    pthread_mutex_lock(&wit.mu);
    wit.counting = 1;
    wit.frames = 0;
    wit.max_gap = 0;
    wit.last = test_now_s();
    win_t0 = wit.last;
    pthread_mutex_unlock(&wit.mu);
    pthread_mutex_lock(&mem.mu);
    mem.peak = rss_mb();
    pthread_mutex_unlock(&mem.mu);
}

static double loadavg(void)
{
    double l = 0;
    FILE *f = fopen("/proc/loadavg", "r");
    if (f) {
        if (fscanf(f, "%lf", &l) != 1) l = 0;
        fclose(f);
    }
    return l;
}

typedef struct verdict {
    int frames;
    double expected, keep, gap, peak, span;
} verdict;

/* Closes the current window, at least min_s long, into *v. */
static void window_close(verdict *v, double min_s)
{
    while (test_now_s() - win_t0 < min_s) usleep(20000);
    pthread_mutex_lock(&wit.mu);
    double t = test_now_s();
    if (t - wit.last > wit.max_gap) wit.max_gap = t - wit.last; /* a stall at the end counts */
    v->frames = wit.frames;
    v->gap = wit.max_gap;
    double span = t - win_t0;
    wit.counting = 0;
    pthread_mutex_unlock(&wit.mu);
    pthread_mutex_lock(&mem.mu);
    v->peak = mem.peak;
    pthread_mutex_unlock(&mem.mu);
    v->span = span;
    v->expected = floor(span * WITNESS_HZ);
    v->keep = v->frames / v->expected;
}

static double keep_min(void) { return sanitized ? KEEP_MIN_ASAN : KEEP_MIN; }
static double gap_max_ms(void) { return sanitized ? GAP_MAX_ASAN_MS : GAP_MAX_MS; }
static int witness_ok(const verdict *v) { return v->keep >= keep_min() && 1e3 * v->gap <= gap_max_ms(); }

static int n_unjudged, n_retried;
static verdict last;          /* the window an attack closed last */

/* Ends an attack's window: prints its figures, asserts the memory ceiling
 * and keeps the witness's verdict for run_attack. */
static void window_end(const char *name)
{
    window_close(&last, WINDOW_MIN_S);
    if (last.peak - rss_base > worst_rss) worst_rss = last.peak - rss_base;
    fprintf(stderr, "attack %-22s witness %3d/%3.0f frames (%5.1f %%), longest gap %5.1f ms, "
            "RSS peak %6.1f MiB (+%5.1f, ceiling +%.0f), load %.1f\n", name, last.frames,
            last.expected, 100 * last.keep, 1e3 * last.gap, last.peak, last.peak - rss_base,
            rss_ceiling, loadavg());
    assert_true(last.peak - rss_base <= rss_ceiling);
}

/* Runs an attack and judges the witness.  The 2 cores of the CI host are
 * shared with other jobs, whose bursts starve the witness (and the daemon)
 * with no attack at all; so an attack whose window misses the mark is run
 * again, up to ATTACK_TRIES times in all: an attack that really starves the
 * witness does so every time, a burst of host load rarely three times in a
 * row.  If every try misses, a control window with no attack follows, as
 * long as the last try's (a long attack's window has more time to meet a
 * burst of host load than a short control): if the witness misses there
 * too, the host is what starves it and the attack's witness figures are
 * reported as not judged; otherwise the attack fails.  The answers and the
 * memory ceiling are asserted on every try. */
#define ATTACK_TRIES 3
static void run_attack(void (*fn)(void **), void **state)
{
    n_attacks++;
    for (int k = 0; k < ATTACK_TRIES; k++) {
        fn(state);
        if (witness_ok(&last)) {
            if (last.keep < worst_keep) worst_keep = last.keep;
            if (last.gap > worst_gap) worst_gap = last.gap;
            return;
        }
        n_retried++;
        fprintf(stderr, "  the witness missed its mark (try %d of %d)\n", k + 1, ATTACK_TRIES);
    }
    verdict c;
    window_begin();
    window_close(&c, fmax(WINDOW_MIN_S, last.span));
    fprintf(stderr, "  control window, no attack, %.1f s: %d/%.0f frames (%.1f %%), longest gap %.1f ms\n",
            c.span, c.frames, c.expected, 100 * c.keep, 1e3 * c.gap);
    if (!witness_ok(&c)) {
        fprintf(stderr, "  witness not judged: the host starves it without any attack (load %.1f)\n",
                loadavg());
        n_unjudged++;
        return;
    }
    assert_true(last.keep >= keep_min());
    assert_true(1e3 * last.gap <= gap_max_ms());
}

/* ---- raw helpers ------------------------------------------------------------- */

/* The close code the server sends within ms (-1: none, EOF or timeout). */
static int wait_close(test_ws *w, int ms)
{
    double end = test_now_s() + ms / 1000.0;
    while (test_now_s() < end) {
        uint8_t *b;
        size_t n;
        int op = test_ws_recv(w, (int)((end - test_now_s()) * 1000) + 1, &b, &n);
        if (op <= 0) return -1;
        int code = op == 8 && n >= 2 ? b[0] << 8 | b[1] : -2;
        free(b);
        if (op == 8) return code;
    }
    return -1;
}

/* One frame written as-is: masked or not, FIN or not, a claimed payload
 * length and the bytes actually sent. */
static int raw_frame(int fd, int opcode, int fin, int masked, uint64_t claimed, const uint8_t *p,
                     size_t n)
{
    uint8_t h[14];
    size_t hl = 0;
    h[hl++] = (uint8_t)((fin ? 0x80 : 0) | (opcode & 0xf));
    uint8_t mb = masked ? 0x80 : 0;
    if (claimed < 126) h[hl++] = (uint8_t)(mb | claimed);
    else if (claimed < 65536) {
        h[hl++] = mb | 126;
        h[hl++] = (uint8_t)(claimed >> 8);
        h[hl++] = (uint8_t)claimed;
    } else {
        h[hl++] = mb | 127;
        for (int i = 7; i >= 0; i--) h[hl++] = (uint8_t)(claimed >> (8 * i));
    }
    const uint8_t key[4] = {0x37, 0xfa, 0x21, 0x3d};
    if (masked) {
        memcpy(h + hl, key, 4);
        hl += 4;
    }
    uint8_t *buf = malloc(hl + n);
    if (!buf) return -1;
    memcpy(buf, h, hl);
    for (size_t i = 0; i < n; i++) buf[hl + i] = masked ? p[i] ^ key[i & 3] : p[i];
    size_t off = 0;
    while (off < hl + n) {
        ssize_t k = send(fd, buf + off, hl + n - off, MSG_NOSIGNAL);
        if (k <= 0) {
            free(buf);
            return -1;
        }
        off += (size_t)k;
    }
    free(buf);
    return 0;
}

static int tcp_connect(int p)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0) return -1;
    struct sockaddr_in a = {0};
    a.sin_family = AF_INET;
    a.sin_port = htons((uint16_t)p);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (connect(fd, (struct sockaddr *)&a, sizeof a) != 0) {
        close(fd);
        return -1;
    }
    return fd;
}

/* Sends req and reads the response until EOF or ms; returns its length. */
static size_t http_exchange(int fd, const char *req, char *out, size_t cap, int ms)
{
    if (send(fd, req, strlen(req), MSG_NOSIGNAL) < 0) return 0;
    size_t len = 0;
    double end = test_now_s() + ms / 1000.0;
    while (len + 1 < cap && test_now_s() < end) {
        struct pollfd pf = {fd, POLLIN, 0};
        if (poll(&pf, 1, (int)((end - test_now_s()) * 1000) + 1) <= 0) break;
        ssize_t k = recv(fd, out + len, cap - 1 - len, 0);
        if (k <= 0) break;
        len += (size_t)k;
    }
    out[len] = 0;
    return len;
}

static int http_get(int p, const char *path, char *out, size_t cap)
{
    int fd = tcp_connect(p);
    if (fd < 0) return -1;
    char req[256];
    snprintf(req, sizeof req, "GET %s HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n", path);
    size_t n = http_exchange(fd, req, out, cap, 3000);
    close(fd);
    int status = 0;
    if (n > 12) sscanf(out, "HTTP/1.1 %d", &status);
    return status;
}

static void live_subscribe(proto_subscribe *s)
{
    oc_subscribe_default(s);
    /* the witness reads FRAME headers only (its CPU must not limit it) and
     * attackers read nothing: the plain stream, whose frames stand alone */
    s->flags &= (uint8_t)~PROTO_SUB_TIME_INTERP;
    s->tile_size = 32;
    s->lod_levels = 2;
    s->frame_rate_hz = (float)WITNESS_HZ;
}

/* A raw ocean.v1 connection past HELLO, subscribed (live) unless sub is NULL. */
static void attacker_from(test_ws *w, const char *src, const char *path, const proto_subscribe *sub)
{
    assert_int_equal(test_ws_connect_from(w, src, port, path ? path : "/", PROTO_SUBPROTOCOL), 0);
    proto_msg m;
    assert_true(test_msg_wait(w, PROTO_HELLO, 3000, &m));
    proto_msg_free(&m);
    if (sub) {
        proto_msg_init(&m, PROTO_SUBSCRIBE);
        m.u.subscribe = *sub;
        test_msg_send(w, &m);
    }
}

static void attacker(test_ws *w, const char *path, const proto_subscribe *sub)
{
    attacker_from(w, NULL, path, sub);
}

/* Waits for an ERROR with `code` whose text contains `names` (the limit). */
static void expect_error(test_ws *w, ocean_result code, const char *names, int ms)
{
    proto_msg m;
    double end = test_now_s() + ms / 1000.0;
    while (test_now_s() < end) {
        if (!test_msg_wait(w, PROTO_ERROR, (int)((end - test_now_s()) * 1000) + 1, &m)) break;
        int ok = m.u.error.code == code && (!names || strstr(m.u.error.message, names));
        if (!ok)
            fprintf(stderr, "  (other ERROR %s: %s)\n", ocean_strerror((ocean_result)m.u.error.code),
                    m.u.error.message);
        proto_msg_free(&m);
        if (ok) return;
    }
    fprintf(stderr, "no ERROR %s naming '%s'\n", ocean_strerror(code), names ? names : "");
    fail();
}

static void count_frames(test_ws **w, int n, double seconds, int *got);

/* ---- set-up -------------------------------------------------------------------- */

static int cigi_port; /* the daemon's CIGI service (a free UDP port on loopback) */

/* The daemon's config at path: CIGI on port cigi (0: off). */
static void write_conf(const char *path, int max_clients, int cigi)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f,
            "sea.wind = 10\n"
            "ocean.n = %d\n"
            "ocean.cascades = 2\n"
            "ocean.patch = 400\n"
            "ocean.threads = 1\n"
            "server.port = 0\n"
            "server.scene = \"\"\n"
            "server.tick_rate = 20\n"
            "server.admin_token = \"attack-token\"\n"
            "server.admin_lockout = 0.3\n"
            "server.max_message = 1048576\n"
            "server.msg_rate = 200\n"
            "server.msg_burst = 400\n"
            "server.output_soft = 1048576\n"
            "server.output_soft_seconds = 2\n"
            "server.output_hard = 2097152\n"
            "server.max_clients = %d\n"
            "server.partial_seconds = 1\n"
            "server.partial_total = 8388608\n"
            "server.record_dir = \"%s/rec\"\n"
            "server.record_clients = on\n"
            "server.record_max_files = 2\n"
            "server.record_max_bytes = 4096\n"
            "server.max_mesh_vertices = 200000\n"
            "server.near_field_waves = 16\n"
            "server.view_range = 2000\n"
            "server.workers = 2\n"
            "server.cigi_port = %d\n",
            sanitized ? 32 : 64, max_clients, tmpdir, cigi);
    fclose(f);
}

static int group_setup(void **state)
{
    (void)state;
    sanitized = getenv("OCEAN_TEST_SANITIZED") != NULL;
    signal(SIGPIPE, SIG_IGN);
    snprintf(tmpdir, sizeof tmpdir, "/tmp/test_attacks.%d", (int)getpid());
    mkdir(tmpdir, 0755);
    snprintf(conf_path, sizeof conf_path, "%s/oceand.conf", tmpdir);
    cigi_port = test_free_udp_port();
    write_conf(conf_path, 400, cigi_port);
    char err[512];
    if (srv_settings_load(conf_path, NULL, 0, &settings, err, sizeof err) != OCEAN_OK ||
        srv_daemon_start(&settings, &daemon_, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "%s\n", err);
        return -1;
    }
    port = srv_daemon_port(daemon_);
    if (oc_loop_create(&loop, err, sizeof err) != OCEAN_OK || oc_loop_start(loop) != OCEAN_OK) return -1;
    char url[64];
    snprintf(url, sizeof url, "ws://127.0.0.1:%d/", port);
    oc_options o;
    oc_options_default(&o);
    o.url = url;
    o.loop = loop;
    o.header_only = 1; /* the witness's own CPU must not be what limits it */
    o.cb.on_frame = on_witness_frame;
    if (oc_connect(&o, 5000, &wit.c, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "witness: %s\n", err);
        return -1;
    }
    proto_hello hello;
    oc_client_hello(wit.c, &hello);
    wit.id = hello.client_id;
    proto_subscribe s;
    live_subscribe(&s);
    if (oc_client_subscribe(wit.c, &s) != OCEAN_OK) return -1;
    pthread_create(&mem.th, NULL, mem_main, NULL);
    usleep(1500000); /* first frames, plans and caches settle */
    rss_base = rss_mb();
    rss_ceiling = sanitized ? RSS_CEILING_ASAN_MB : RSS_CEILING_MB;
    return 0;
}

static int group_teardown(void **state)
{
    (void)state;
    atomic_store(&mem.stop, 1);
    pthread_join(mem.th, NULL);
    fprintf(stderr, "attacks tried: %d (%d with the witness judged, %d tries repeated); witness "
            "kept >= %.1f %% of its frames (floor %.0f %%), longest gap %.1f ms (ceiling %.0f ms); "
            "RSS peak growth %.1f MiB (ceiling %.0f MiB)%s\n", n_attacks, n_attacks - n_unjudged,
            n_retried, 100 * worst_keep, 100 * keep_min(), 1e3 * worst_gap, gap_max_ms(), worst_rss,
            rss_ceiling, sanitized ? " [ASan]" : "");
    oc_client_destroy(wit.c);
    srv_daemon_stop(daemon_);
    oc_loop_destroy(loop);
    char cmd[400];
    snprintf(cmd, sizeof cmd, "rm -rf %s", tmpdir);
    return system(cmd) == 0 ? 0 : -1;
}

/* ---- RFC 6455 ----------------------------------------------------------------- */

/* RFC 6455 4.4: a version the server does not speak is answered 426 with
 * Sec-WebSocket-Version: 13; RFC 6455 4.2.2 / 1.9: the daemon speaks only
 * ocean.v1, so an upgrade without it is refused (400), never held. */
static void a_rfc_handshake_refusals(void **state)
{
    (void)state;
    srv_hub *h = srv_daemon_hub(daemon_);
    window_begin();
    char resp[2048];
    int fd = tcp_connect(port);
    assert_true(fd >= 0);
    http_exchange(fd, "GET / HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                      "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 99\r\n"
                      "Sec-WebSocket-Protocol: ocean.v1\r\n\r\n", resp, sizeof resp, 2000);
    close(fd);
    assert_true(strncmp(resp, "HTTP/1.1 426", 12) == 0);
    assert_non_null(strstr(resp, "Sec-WebSocket-Version: 13"));
    /* subprotocols offered, none of them ocean.v1 (names are case-sensitive):
     * 400 naming it, as with none at all (lws hung up without a word) */
    const char *others[] = {"chat", "OCEAN.V1"};
    for (int i = 0; i < 2; i++) {
        char req[512];
        snprintf(req, sizeof req, "GET / HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                 "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n"
                 "Sec-WebSocket-Protocol: %s\r\n\r\n", others[i]);
        fd = tcp_connect(port);
        assert_true(fd >= 0);
        http_exchange(fd, req, resp, sizeof resp, 2000);
        close(fd);
        if (strncmp(resp, "HTTP/1.1 400", 12) != 0) fprintf(stderr, "subprotocol %s: '%.60s'\n", others[i], resp);
        assert_true(strncmp(resp, "HTTP/1.1 400", 12) == 0);
        assert_non_null(strstr(resp, "ocean.v1"));
    }
    /* 300 upgrades without the subprotocol, held open by the attacker */
    enum { N = 300 };
    int fds[N], refused = 0;
    pthread_mutex_lock(&h->lock);
    int clients0 = h->n_clients;
    pthread_mutex_unlock(&h->lock);
    for (int i = 0; i < N; i++) {
        fds[i] = tcp_connect(port);
        assert_true(fds[i] >= 0);
        const char *req = "GET / HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                          "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n";
        assert_true(send(fds[i], req, strlen(req), MSG_NOSIGNAL) > 0);
    }
    for (int i = 0; i < N; i++) {
        /* the refusal, then EOF: the daemon holds nothing */
        char r[1024];
        size_t n = 0;
        double end = test_now_s() + 3;
        for (;;) {
            struct pollfd pf = {fds[i], POLLIN, 0};
            if (test_now_s() > end || poll(&pf, 1, 100) < 0) break;
            if (!(pf.revents & POLLIN)) continue;
            ssize_t k = recv(fds[i], r + n, sizeof r - 1 - n, 0);
            if (k <= 0) break;
            n += (size_t)k;
        }
        r[n] = 0;
        if (strncmp(r, "HTTP/1.1 400", 12) == 0 && strstr(r, "ocean.v1")) refused++;
        close(fds[i]);
    }
    assert_int_equal(refused, N);
    pthread_mutex_lock(&h->lock);
    int clients1 = h->n_clients;
    pthread_mutex_unlock(&h->lock);
    assert_int_equal(clients1, clients0);
    window_end("handshake-refusals");
}

/* RFC 6455 5.1: "The server MUST close the connection upon receiving a
 * frame that is not masked" (close 1002, 7.4.1); 8.1: invalid UTF-8 in a
 * text message fails the connection with 1007. */
static void a_rfc_unmasked_and_utf8(void **state)
{
    (void)state;
    window_begin();
    srv_hub *h = srv_daemon_hub(daemon_);
    uint64_t proto0 = stat_of(&h->stats.disconnects_protocol);
    test_ws w;
    attacker(&w, NULL, NULL);
    uint8_t junk[40] = {0};
    assert_int_equal(raw_frame(w.fd, 2, 1, 0, sizeof junk, junk, sizeof junk), 0);
    assert_int_equal(wait_close(&w, 2000), 1002);
    test_ws_close(&w);
    /* the same with the frame's first byte in a TCP segment of its own:
     * the violation is seen after lws has the byte, the connection is
     * flagged and closed from the callback (it was served on: the flag
     * was dropped with the tracker) */
    attacker(&w, NULL, NULL);
    int one = 1;
    setsockopt(w.fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    uint8_t first = 0x82; /* FIN, binary */
    assert_int_equal(send(w.fd, &first, 1, MSG_NOSIGNAL), 1);
    usleep(100000);
    uint8_t rest[1 + sizeof junk];
    rest[0] = sizeof junk; /* no MASK bit */
    memcpy(rest + 1, junk, sizeof junk);
    assert_int_equal(send(w.fd, rest, sizeof rest, MSG_NOSIGNAL), (ssize_t)sizeof rest);
    assert_int_equal(wait_close(&w, 2000), 1002);
    test_ws_close(&w);
    /* both counted as protocol disconnects (/metrics
     * oceand_disconnects_protocol_total), the one lws closed too */
    for (int i = 0; i < 50 && stat_of(&h->stats.disconnects_protocol) < proto0 + 2; i++) usleep(20000);
    assert_true(stat_of(&h->stats.disconnects_protocol) >= proto0 + 2);
    attacker(&w, NULL, NULL);
    const uint8_t bad[] = {'o', 'k', 0xc3, 0x28, 0xff, 0xfe}; /* 0xc3 0x28: invalid sequence */
    assert_int_equal(test_ws_send(&w, 1, bad, sizeof bad), 0);
    assert_int_equal(wait_close(&w, 2000), 1007);
    test_ws_close(&w);
    window_end("unmasked+utf8");
}

/* RFC 6455 7.4.1 / 7.4.2 and the IANA registry: 0-999 are not used,
 * 1004-1006 and 1015 are reserved and "MUST NOT be set as a status code in
 * a Close control frame by an endpoint", 1016-2999 are for future
 * standards, >= 5000 is undefined; a one-byte close payload is malformed
 * (5.5.1).  Each is a protocol error: the server answers 1002.  Valid codes
 * are echoed (5.5.1: the endpoint typically echoes the status code). */
static void a_rfc_close_codes(void **state)
{
    (void)state;
    window_begin();
    const int bad[] = {0, 999, 1004, 1005, 1006, 1015, 1016, 2999, 5000, 65535};
    const int good[] = {1000, 1001, 1003, 1011, 3000, 4999};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0] + 1; i++) {
        test_ws w;
        attacker(&w, NULL, NULL);
        uint8_t p[3] = {(uint8_t)(bad[i % 10] >> 8), (uint8_t)bad[i % 10], 'x'};
        size_t n = i < 10 ? 3 : 1; /* the last: a one-byte payload */
        assert_int_equal(raw_frame(w.fd, 8, 1, 1, n, p, n), 0);
        int got = wait_close(&w, 2000);
        if (got != 1002) fprintf(stderr, "close %d (%zu bytes) answered %d\n", bad[i % 10], n, got);
        assert_int_equal(got, 1002);
        test_ws_close(&w);
    }
    for (size_t i = 0; i < sizeof good / sizeof good[0]; i++) {
        test_ws w;
        attacker(&w, NULL, NULL);
        uint8_t p[2] = {(uint8_t)(good[i] >> 8), (uint8_t)good[i]};
        assert_int_equal(raw_frame(w.fd, 8, 1, 1, 2, p, 2), 0);
        int got = wait_close(&w, 2000);
        assert_int_not_equal(got, 1002);
        assert_true(got == good[i] || got == 1000);
        test_ws_close(&w);
    }
    window_end("close-codes");
}

/* ---- work done for one client ----------------------------------------------------- */

/* The mesh bomb: a 1-degree 1080p camera at 25 m asks for a ~10^7-vertex
 * concentric mesh.  Priced before it is built: ERROR ETOOBIG naming
 * server.max_mesh_vertices, and the client's frames keep coming, without a
 * mesh.  The protocol's extreme cameras (fov 175 and 0.005 degrees,
 * x = 5e9, y = 5e6: PROTOCOL.md, CAMERA) are taken, not refused. */
static void a_mesh_bomb(void **state)
{
    (void)state;
    window_begin();
    test_ws w;
    proto_subscribe s;
    live_subscribe(&s);
    attacker(&w, NULL, &s);
    proto_msg cm;
    proto_msg_init(&cm, PROTO_CAMERA);
    oc_camera_default(&cm.u.camera);
    cm.u.camera.pos[1] = 25;
    cm.u.camera.fov_y_deg = 1;
    cm.u.camera.viewport_w = 1920;
    cm.u.camera.viewport_h = 1080;
    test_msg_send(&w, &cm);
    expect_error(&w, OCEAN_ETOOBIG, "server.max_mesh_vertices", 3000);
    /* frames still come, without a mesh */
    proto_msg m;
    int meshless = 0;
    for (int i = 0; i < 10 && !meshless; i++) {
        assert_true(test_msg_wait(&w, PROTO_FRAME, 2000, &m));
        meshless = !m.u.frame.has_mesh && m.u.frame.camera_seq == cm.hdr.seq;
        proto_msg_free(&m);
    }
    /* the extremes the protocol allows */
    const double fov[] = {175, 60, 60, 0.005};
    const double pos[][3] = {{0, 20, 0}, {5e9, 20, -5e9}, {0, 5e6, 0}, {0, 20, 0}};
    for (int k = 0; k < 4; k++) {
        oc_camera_default(&cm.u.camera);
        cm.u.camera.fov_y_deg = (float)fov[k];
        memcpy(cm.u.camera.pos, pos[k], sizeof pos[k]);
        cm.hdr.seq = 100 + (uint32_t)k;
        test_msg_send(&w, &cm);
        int seen = 0;
        for (int i = 0; i < 40 && !seen; i++) {
            if (!test_msg_wait(&w, PROTO_FRAME, 2000, &m)) break;
            seen = m.u.frame.camera_seq == cm.hdr.seq;
            proto_msg_free(&m);
        }
        if (!seen) fprintf(stderr, "no frame for camera fov %g pos %g %g %g\n", fov[k], pos[k][0],
                           pos[k][1], pos[k][2]);
        assert_true(seen);
    }
    test_ws_close(&w);
    window_end("mesh-bomb");
    assert_true(meshless);
}

/* 16 queries of 65 000 points (each 1.2-1.9 s of work when done inline,
 * issue 15) from one client: the 17th is refused (ERATE naming
 * server.max_pending_queries); the work runs in slices, and another
 * client's small query is answered within a second meanwhile (clients take
 * turns). */
static void a_query_flood(void **state)
{
    (void)state;
    window_begin();
    test_ws w;
    attacker(&w, NULL, NULL);
    enum { PTS = 65000 };
    double *pts = malloc(2 * sizeof(double) * PTS);
    assert_non_null(pts);
    for (int i = 0; i < PTS; i++) {
        pts[2 * i] = 3.7 * (i % 251);
        pts[2 * i + 1] = -2.9 * (i / 251);
    }
    proto_msg q;
    proto_msg_init(&q, PROTO_QUERY);
    q.u.query.count = PTS;
    q.u.query.points = pts;
    /* encoded and masked once, sent 17 times: the attacker's own CPU
     * (in this process, on the daemon's 2 cores) is not the test */
    size_t qlen;
    uint8_t *qb = test_msg_encode(&q, &qlen);
    size_t flen = qlen + 14;
    uint8_t *frame = malloc(flen);
    assert_non_null(frame);
    size_t hl = 0;
    frame[hl++] = 0x82;
    frame[hl++] = 0x80 | 127;
    for (int i = 7; i >= 0; i--) frame[hl++] = (uint8_t)((uint64_t)qlen >> (8 * i));
    memset(frame + hl, 0, 4); /* mask key 0: masked, payload unchanged (RFC 6455 5.3) */
    hl += 4;
    memcpy(frame + hl, qb, qlen);
    free(qb);
    for (int i = 0; i < 17; i++) {
        size_t off = 0;
        while (off < hl + qlen) {
            ssize_t k = send(w.fd, frame + off, hl + qlen - off, MSG_NOSIGNAL);
            assert_true(k > 0);
            off += (size_t)k;
        }
    }
    free(frame);
    expect_error(&w, OCEAN_ERATE, "server.max_pending_queries", 3000);
    /* someone else's small query goes through while the big ones run */
    test_ws o;
    attacker(&o, NULL, NULL);
    q.u.query.count = 100;
    q.u.query.query_id = 777;
    double t0 = test_now_s();
    test_msg_send(&o, &q);
    proto_msg m;
    assert_true(test_msg_wait(&o, PROTO_QUERY_RESULT, 3000, &m));
    double waited = test_now_s() - t0;
    assert_int_equal(m.u.result.query_id, 777);
    proto_msg_free(&m);
    fprintf(stderr, "  small query answered in %.0f ms during the flood\n", 1e3 * waited);
    assert_true(waited < (sanitized ? 2.0 : 1.0));
    test_ws_close(&o);
    test_ws_close(&w);
    free(pts);
    window_end("query-flood");
}

/* 256 replay cameras queued at once (drained in one pass before: no frame
 * for anyone for 15 s): drained server.replay_per_tick a tick; the 257th is
 * refused (ERATE naming server.replay_queue).  A second attacker queues 256
 * and reads nothing: as its frames are queued past server.output_hard it
 * is disconnected, the queue's memory bounded. */
static void a_replay_flood(void **state)
{
    (void)state;
    srv_hub *h = srv_daemon_hub(daemon_);
    uint64_t out0 = stat_of(&h->stats.disconnects_output) + stat_of(&h->stats.disconnects_slow);
    window_begin();
    test_ws w, hog;
    proto_subscribe s;
    live_subscribe(&s);
    s.mode = PROTO_MODE_REPLAY;
    s.mesh_kind = PROTO_MESH_NONE;
    attacker(&w, NULL, &s);
    s.tile_size = 64;
    s.codec = PROTO_CODEC_F32;
    attacker(&hog, NULL, &s);
    test_ws_small_rcvbuf(&hog, 4096);
    proto_msg cm;
    proto_msg_init(&cm, PROTO_CAMERA);
    for (int i = 0; i < 399; i++) {
        /* within the message burst (400): the refusal must be the replay
         * queue's (256).  The simulation thread takes server.replay_per_tick
         * a tick meanwhile: 143 cameras past the queue's length keep it full
         * for 2.4 s of ticks however slowly a busy host reads them. */
        oc_camera_default(&cm.u.camera);
        cm.u.camera.render_time = 0.05 * i;
        cm.hdr.seq = (uint32_t)i;
        test_msg_send(&w, &cm);
        if (i < 256) test_msg_send(&hog, &cm);
    }
    expect_error(&w, OCEAN_ERATE, "server.replay_queue", 3000);
    test_ws_close(&w);
    /* the hog reads nothing: its frames pile up to the hard limit */
    double end = test_now_s() + 5;
    while (test_now_s() < end &&
           stat_of(&h->stats.disconnects_output) + stat_of(&h->stats.disconnects_slow) == out0)
        usleep(50000);
    int cut = stat_of(&h->stats.disconnects_output) + stat_of(&h->stats.disconnects_slow) > out0;
    test_ws_close(&hog);
    window_end("replay-flood");
    assert_true(cut);
}

/* Eight replay clients, four in each layout, each with 256 cameras at
 * times of their own, each within its own limits (server.replay_per_tick
 * a tick, layout 0's tiles under server.max_sample_rate at that rate): the
 * daemon as a whole cannot make 16 replay frames a tick (issue 46: the
 * witness lost its frame rate: 45 % of its frames, with each replay client
 * served 70 frames in 4 s).  Replay frames take what the ticks leave,
 * clients in turn: the witness keeps its rate and every client's replay
 * progresses, those of one layout alike. */
#define CROWD 8
static void a_replay_crowd(void **state)
{
    (void)state;
    window_begin();
    static test_ws w[CROWD];
    for (int k = 0; k < CROWD; k++) {
        proto_subscribe s;
        live_subscribe(&s);
        s.mode = PROTO_MODE_REPLAY;
        if (k % 2) {
            s.layout = PROTO_LAYOUT_WORLD;
            s.tile_size = 64;
            s.lod_levels = 8;
            s.mesh_kind = PROTO_MESH_NONE;
        }
        attacker(&w[k], NULL, &s);
        proto_msg cm;
        proto_msg_init(&cm, PROTO_CAMERA);
        for (int i = 0; i < 256; i++) {
            oc_camera_default(&cm.u.camera);
            cm.u.camera.render_time = 1000.0 * k + 0.05 * i;
            cm.hdr.seq = (uint32_t)i;
            test_msg_send(&w[k], &cm);
        }
    }
    test_ws *all[CROWD];
    for (int k = 0; k < CROWD; k++) all[k] = &w[k];
    int got[CROWD];
    count_frames(all, CROWD, 4.0, got);
    for (int k = 0; k < CROWD; k++) test_ws_close(&w[k]);
    window_end("replay-crowd");
    fprintf(stderr, "  replay frames in 4 s:");
    for (int k = 0; k < CROWD; k++) fprintf(stderr, " %d", got[k]);
    fprintf(stderr, "\n");
    /* in turn, an equal share of time each: within a layout (one cost a
     * frame) the least served client had at least half what the most
     * served had, or (a few frames each: ASan on a busy host served the
     * layout-1 clients 1, 1, 3 and 2) no more than two frames less */
    for (int layout = 0; layout < 2; layout++) {
        int least = INT32_MAX, most = 0;
        for (int k = layout; k < CROWD; k += 2) {
            least = got[k] < least ? got[k] : least;
            most = got[k] > most ? got[k] : most;
        }
        assert_true(least >= 1);
        assert_true(2 * least >= most || most - least <= 2);
    }
}

/* A subscription priced above server.max_sample_rate (128^2 tiles x 8
 * levels, 60 Hz: 31 M samples/s) is refused before any tile is made. */
static void a_heavy_subscriber(void **state)
{
    (void)state;
    window_begin();
    test_ws w;
    proto_subscribe s;
    live_subscribe(&s);
    /* per-camera tiles (layout 0) are what a subscription can make heavy;
     * layout 1's shared tiles are held to the viewer's byte budget */
    s.layout = PROTO_LAYOUT_WORLD;
    s.tile_size = 128;
    s.lod_levels = 8;
    s.frame_rate_hz = 20; /* the test daemon ticks at 20 Hz: more is refused as EINVAL first */
    s.codec = PROTO_CODEC_EXR_PIZ;
    attacker(&w, NULL, &s);
    expect_error(&w, OCEAN_ETOOBIG, "server.max_sample_rate", 3000);
    test_ws_close(&w);
    /* the same tiles in replay mode at a frame rate of next to nothing:
     * a replay's frames come from its CAMERAs (server.replay_per_tick a
     * tick), so it is priced at that rate (it was priced at ~0 and taken) */
    s.mode = PROTO_MODE_REPLAY;
    s.frame_rate_hz = 1e-30f;
    attacker(&w, NULL, &s);
    expect_error(&w, OCEAN_ETOOBIG, "replay_per_tick", 3000);
    test_ws_close(&w);
    /* layout 1 ignores tile_size and lod_levels (PROTOCOL.md, SUBSCRIBE):
     * their largest values and a base spacing that only they made
     * "span 8e7 m" are served, not refused ETOOBIG / EINVAL */
    live_subscribe(&s);
    s.layout = PROTO_LAYOUT_CASCADE;
    s.tile_size = 1024;
    s.lod_levels = 16;
    s.base_spacing_m = 1e4f;
    s.mesh_kind = PROTO_MESH_NONE;
    attacker(&w, NULL, &s);
    proto_msg m;
    assert_true(test_msg_wait(&w, PROTO_FRAME, 3000, &m));
    proto_msg_free(&m);
    test_ws_close(&w);
    window_end("heavy-subscriber");
}

/* The next message of w within ms, decoded into *m: its type, 0 on
 * timeout or a closed connection. */
static unsigned next_msg(test_ws *w, int ms, proto_msg *m)
{
    uint8_t *b;
    size_t n;
    if (test_ws_recv(w, ms, &b, &n) != 2) return 0;
    char err[128];
    ocean_result r = proto_decode(b, n, m, err, sizeof err);
    free(b);
    return r == OCEAN_OK ? m->hdr.type : 0;
}

/* A heavy subscriber's answer: 1 admitted (its first FRAME came), 0 refused
 * with ETOOBIG naming server.admit_share; anything else fails the test. */
static int admitted(test_ws *w)
{
    double end = test_now_s() + 5;
    proto_msg m;
    while (test_now_s() < end) {
        unsigned t = next_msg(w, 200, &m);
        if (!t) continue;
        int frame = t == PROTO_FRAME;
        int refused = t == PROTO_ERROR && m.u.error.code == OCEAN_ETOOBIG &&
                      strstr(m.u.error.message, "server.admit_share");
        if (t == PROTO_ERROR && !refused) fprintf(stderr, "  (other ERROR: %s)\n", m.u.error.message);
        static int said;
        if (refused && !said++) fprintf(stderr, "  refused: %s\n", m.u.error.message);
        proto_msg_free(&m);
        if (frame || refused) return frame;
    }
    fprintf(stderr, "heavy subscriber: neither a FRAME nor an ERROR naming server.admit_share in 5 s\n");
    fail();
    return 0;
}

/* Frames each of the n connections w[] (NULL: skipped) receives over
 * seconds, read in turn, into got[]. */
static void count_frames(test_ws **w, int n, double seconds, int *got)
{
    double end = test_now_s() + seconds;
    for (int i = 0; i < n; i++) got[i] = 0;
    while (test_now_s() < end)
        for (int i = 0; i < n; i++) {
            proto_msg m;
            if (!w[i]) continue;
            unsigned t = next_msg(w[i], 20, &m);
            if (!t) continue;
            got[i] += t == PROTO_FRAME;
            proto_msg_free(&m);
        }
}

/* Four live layout-0 subscriptions, each just under server.max_sample_rate
 * (128^2-sample tiles, 8 levels, exr-piz and qz, cameras at 50 m/s), pass
 * the per-subscription price, while the daemon as a whole cannot make all
 * their tiles (issue 46: all four were taken, each got 25-28 % of its
 * frames and the witness lost its rate).  Each is refused ETOOBIG naming
 * server.admit_share, or admitted and served: >= 80 % of its frames over 3 s
 * (admission prices from costs measured on this host, so which of the two
 * depends on the host; both answers are judged).  A subscription that fits
 * (32^2 tiles, 2 levels, 5 Hz) is still admitted beside them. */
/* Admission's view from /status: 1 with the figures when it answered. */
static int admission_of(double *shared, double *capacity)
{
    char *buf = malloc(1 << 16);
    if (!buf) return 0;
    int ok = 0;
    if (http_get(port, "/status", buf, 1 << 16) == 200) {
        const char *body = strstr(buf, "\r\n\r\n");
        cJSON *o = body ? cJSON_Parse(body + 4) : NULL;
        cJSON *a = o ? cJSON_GetObjectItem(o, "admission") : NULL;
        cJSON *sh = a ? cJSON_GetObjectItem(a, "shared_cores") : NULL;
        cJSON *cap = a ? cJSON_GetObjectItem(a, "capacity_cores") : NULL;
        if (cJSON_IsNumber(sh) && cJSON_IsNumber(cap)) {
            *shared = sh->valuedouble;
            *capacity = cap->valuedouble;
            ok = 1;
        }
        cJSON_Delete(o);
    }
    free(buf);
    return ok;
}

/* Waits (up to 20 s) until the work of the attacks before has left
 * admission's smoothed measure of the shared work: below half the
 * capacity.  The replay clients just before read their frames in this
 * process, which admission counts as the daemon's. */
static void admission_settle(void)
{
    double shared = 0, capacity = 0, end = test_now_s() + 20;
    while (admission_of(&shared, &capacity) && shared > 0.5 * capacity && test_now_s() < end) usleep(200000);
    fprintf(stderr, "  admission before: shared %.3g cores of a capacity of %.3g\n", shared, capacity);
}

#define HEAVY 4
static void a_daemon_capacity(void **state)
{
    (void)state;
    srv_hub *h = srv_daemon_hub(daemon_);
    pthread_mutex_lock(&h->lock);
    srv_config was = h->settings.srv;
    /* an admitted heavy subscriber's frames are megabytes: not what the
     * output limits of this daemon judge here */
    h->settings.srv.output_soft = h->settings.srv.output_hard = 256u << 20;
    double max_rate = h->settings.srv.max_sample_rate, per = h->settings.srv.tiles_per_side;
    pthread_mutex_unlock(&h->lock);
    uint64_t refused0 = stat_of(&h->stats.refused_admission);
    admission_settle();
    window_begin();
    static test_ws heavy[HEAVY];
    test_ws *served[HEAVY + 1] = {0};
    int n_admitted = 0;
    for (int i = 0; i < HEAVY; i++) {
        proto_subscribe s;
        live_subscribe(&s);
        s.layout = PROTO_LAYOUT_WORLD;
        s.tile_size = 128;
        s.lod_levels = 8;
        s.codec = i % 2 ? PROTO_CODEC_QZ : PROTO_CODEC_EXR_PIZ;
        s.frame_rate_hz = (float)(0.99 * max_rate / (per * per * s.lod_levels * 128.0 * 128.0));
        attacker(&heavy[i], NULL, &s);
        proto_msg cm;
        proto_msg_init(&cm, PROTO_CAMERA);
        oc_camera_default(&cm.u.camera);
        cm.u.camera.pos[0] = 1000.0 * i;
        cm.u.camera.vel[0] = 50;
        test_msg_send(&heavy[i], &cm);
        if (admitted(&heavy[i])) served[n_admitted++] = &heavy[i];
    }
    test_ws light;
    proto_subscribe s;
    live_subscribe(&s);
    s.layout = PROTO_LAYOUT_WORLD;
    s.frame_rate_hz = 5;
    attacker(&light, NULL, &s);
    proto_msg fm;
    int light_served = test_msg_wait(&light, PROTO_FRAME, 5000, &fm);
    if (light_served) proto_msg_free(&fm);
    int got[HEAVY] = {0};
    double rate = 0.99 * max_rate / (per * per * 8 * 128.0 * 128.0), seconds = 3;
    count_frames(served, n_admitted, seconds, got);
    for (int i = 0; i < HEAVY; i++) test_ws_close(&heavy[i]);
    test_ws_close(&light);
    pthread_mutex_lock(&h->lock);
    h->settings.srv.output_soft = was.output_soft;
    h->settings.srv.output_hard = was.output_hard;
    pthread_mutex_unlock(&h->lock);
    window_end("daemon-capacity");
    uint64_t refused = stat_of(&h->stats.refused_admission) - refused0;
    fprintf(stderr, "  %d of %d heavy subscribers admitted, %llu refused (oceand_refused_admission_total)",
            n_admitted, HEAVY, (unsigned long long)refused);
    for (int i = 0; i < n_admitted; i++) fprintf(stderr, "%s%d/%.0f frames", i ? ", " : "; ", got[i], rate * seconds);
    fprintf(stderr, "\n");
    assert_int_equal((int)refused, HEAVY - n_admitted);
    for (int i = 0; i < n_admitted; i++) assert_true(got[i] >= 0.8 * rate * seconds);
    assert_true(light_served);
}

/* ---- memory a client can make the daemon hold -------------------------------------- */

/* 60 connections each hold 200 KB of a message that claims 1 MiB and never
 * finishes (+297 MB for 300 such before): the whole is capped by
 * server.partial_total (8 MiB here) and each is closed (1008) after
 * server.partial_seconds (1 s). */
static void a_partial_messages(void **state)
{
    (void)state;
    srv_hub *h = srv_daemon_hub(daemon_);
    uint64_t p0 = stat_of(&h->stats.disconnects_partial);
    window_begin();
    enum { N = 60, PART = 200000 };
    test_ws w[N];
    uint8_t *part = calloc(1, PART);
    assert_non_null(part);
    memcpy(part, "OCNW", 4);
    for (int i = 0; i < N; i++) {
        attacker(&w[i], NULL, NULL);
        raw_frame(w[i].fd, 2, 1, 1, 1 << 20, part, PART);
    }
    /* each is told which limit with close 1008 (PROTOCOL.md "Transport"):
     * the daemon cut them with a bare TCP close before */
    int closed = 0;
    for (int i = 0; i < N; i++) {
        int code = wait_close(&w[i], 3000);
        if (code != 1008) fprintf(stderr, "partial message %d: close %d, not 1008\n", i, code);
        closed += code == 1008;
        test_ws_close(&w[i]);
    }
    free(part);
    assert_int_equal(closed, N);
    assert_true(stat_of(&h->stats.disconnects_partial) - p0 >= N);
    /* a frame header whose payload never comes: unfinished from its first
     * byte (it was held for ever: lws hands over nothing, so the deadline
     * never started) */
    test_ws hw;
    attacker(&hw, NULL, NULL);
    uint8_t hdr[] = {0x82, 0x80 | 126, 0x03, 0xe8, 1, 2, 3, 4}; /* 1000 bytes, masked, none sent */
    assert_int_equal(send(hw.fd, hdr, sizeof hdr, MSG_NOSIGNAL), (ssize_t)sizeof hdr);
    assert_int_equal(wait_close(&hw, 4000), 1008);
    test_ws_close(&hw);
    window_end("partial-messages");
}

/* Connections that ask for nothing (1024 of them held every slot for
 * ever, newcomers got BYE server-full): one that neither subscribes nor
 * sends a message for server.idle_seconds gets BYE idle; a subscribed one
 * (the witness) and one that keeps sending stay. */
static void a_idle_connections(void **state)
{
    (void)state;
    srv_hub *h = srv_daemon_hub(daemon_);
    uint64_t idle0 = stat_of(&h->stats.disconnects_idle);
    pthread_mutex_lock(&h->lock);
    double was = h->settings.srv.idle_seconds;
    h->settings.srv.idle_seconds = 1.0;
    pthread_mutex_unlock(&h->lock);
    window_begin();
    test_ws quiet, talker;
    attacker(&quiet, NULL, NULL);
    attacker(&talker, NULL, NULL);
    proto_msg m, got;
    int bye = -1;
    for (double end = test_now_s() + 4; test_now_s() < end && bye < 0;) {
        proto_msg_init(&m, PROTO_SEA_STATE); /* a get: a message, not a subscription */
        m.u.sea_state.op = PROTO_SEA_GET;
        test_msg_send(&talker, &m);
        if (test_msg_wait(&quiet, PROTO_BYE, 400, &got)) {
            bye = got.u.bye.reason;
            proto_msg_free(&got);
        }
    }
    assert_int_equal(bye, PROTO_BYE_IDLE);
    /* the talker is still served: its SEA_STATE gets are answered */
    proto_msg_init(&m, PROTO_SEA_STATE);
    m.u.sea_state.op = PROTO_SEA_GET;
    test_msg_send(&talker, &m);
    assert_true(test_msg_wait(&talker, PROTO_SEA_STATE, 2000, &got));
    proto_msg_free(&got);
    test_ws_close(&quiet);
    test_ws_close(&talker);
    pthread_mutex_lock(&h->lock);
    h->settings.srv.idle_seconds = was;
    pthread_mutex_unlock(&h->lock);
    assert_true(stat_of(&h->stats.disconnects_idle) > idle0);
    window_end("idle");
}

/* A text-frame flood from a client that does not read (1 M ERRORs, +366
 * MB before): text frames count against the message rate, and refusals are
 * answered once a second, so the replies stay a handful. */
static void a_text_and_garbage_flood(void **state)
{
    (void)state;
    srv_hub *h = srv_daemon_hub(daemon_);
    uint64_t silent0 = stat_of(&h->stats.refused_silent);
    window_begin();
    test_ws w;
    attacker(&w, NULL, NULL);
    test_ws_small_rcvbuf(&w, 4096);
    double t0 = test_now_s();
    for (int i = 0; i < 20000; i++) {
        if (i % 2) test_ws_send(&w, 1, "x", 1);
        else test_ws_send(&w, 2, "garbage!", 8); /* bad binary: an ERROR each within the burst */
    }
    double flood_s = test_now_s() - t0;
    int errors = 0, rate = 0;
    proto_msg m;
    while (test_msg_wait(&w, PROTO_ERROR, 700, &m)) {
        errors++;
        rate += m.u.error.code == OCEAN_ERATE;
        proto_msg_free(&m);
    }
    test_ws_close(&w);
    fprintf(stderr, "  20000 messages in %.2f s: %d ERRORs (%d ERATE), %llu refused silently\n",
            flood_s, errors, rate, (unsigned long long)(stat_of(&h->stats.refused_silent) - silent0));
    /* the burst's worth of answers (server.msg_burst = 400) and one per
     * second of flood for each kind */
    assert_true(errors <= 400 + 2 * (int)ceil(flood_s + 1) + 2);
    assert_true(rate >= 1);
    assert_true(stat_of(&h->stats.refused_silent) - silent0 > 10000);
    window_end("text+garbage-flood");
}

/* A CIGI 3.3 host frame (IG Control, then `requests` HAT/HOT Extended
 * Requests over the sea near the origin) into b. */
static void cigi_frame(proto_buf *b, uint32_t frame, int requests)
{
    const cigi_format f = {3, 3, 1};
    proto_buf_reset(b);
    cigi_packet ig = {.kind = CIGI_IG_CONTROL};
    ig.u.ig.ig_mode = 1;
    ig.u.ig.frame = frame;
    assert_int_equal(cigi_put(b, &f, &ig), OCEAN_OK);
    for (int i = 0; i < requests; i++) {
        cigi_packet q = {.kind = CIGI_HAT_HOT_REQUEST};
        q.u.hat_req = (cigi_hat_hot_request){.id = (uint32_t)i, .type = CIGI_HAT_HOT_EXTENDED,
                                             .coord = CIGI_COORD_GEODETIC, .lat = 1e-4 * i, .lon = 0, .alt = 10};
        assert_int_equal(cigi_put(b, &f, &q), OCEAN_OK);
    }
}

/* A CIGI datagram flood (issue 42): for 2 s (the window), about 20 000 datagrams a
 * second: host frames of 64 Extended Requests each from the allowed host,
 * the same from an address not in server.cigi_hosts, and truncated junk.  The
 * service drops what it cannot take (more than 8 host messages waiting:
 * busy; not allowed: host; bad framing) and counts each by reason; the
 * witness keeps its frames; afterwards an ordinary host frame is answered. */
static void a_cigi_flood(void **state)
{
    (void)state;
    srv_hub *h = srv_daemon_hub(daemon_);
    uint64_t busy0 = stat_of(&h->stats.cigi_drop_busy), host0 = stat_of(&h->stats.cigi_drop_host);
    uint64_t frame0 = stat_of(&h->stats.cigi_drop_framing), msgs0 = stat_of(&h->stats.cigi_messages);
    int good = socket(AF_INET, SOCK_DGRAM, 0), stranger = socket(AF_INET, SOCK_DGRAM, 0);
    struct sockaddr_in from = {.sin_family = AF_INET};
    inet_pton(AF_INET, "127.0.0.2", &from.sin_addr);
    assert_int_equal(bind(stranger, (struct sockaddr *)&from, sizeof from), 0);
    struct sockaddr_in to = {.sin_family = AF_INET, .sin_port = htons((uint16_t)cigi_port)};
    inet_pton(AF_INET, "127.0.0.1", &to.sin_addr);
    proto_buf b;
    proto_buf_init(&b, 0);
    static const uint8_t junk[5] = {1, 24, 3, 0, 0};
    window_begin();
    long sent = 0;
    double t0 = test_now_s();
    for (uint32_t k = 1; test_now_s() - t0 < WINDOW_MIN_S; k++) {
        cigi_frame(&b, k, 64);
        for (int i = 0; i < 16; i++) {
            sendto(good, proto_buf_data(&b), proto_buf_len(&b), 0, (struct sockaddr *)&to, sizeof to);
            sendto(stranger, proto_buf_data(&b), proto_buf_len(&b), 0, (struct sockaddr *)&to, sizeof to);
            sendto(good, junk, sizeof junk, 0, (struct sockaddr *)&to, sizeof to);
            sent += 3;
        }
        usleep(2000); /* about 20 000 datagrams a second, 300 times a 60 Hz host's, without the
                         sender taking a core of its own from the daemon */
    }
    window_end("cigi-flood");
    uint64_t busy = stat_of(&h->stats.cigi_drop_busy) - busy0, host = stat_of(&h->stats.cigi_drop_host) - host0;
    uint64_t framing = stat_of(&h->stats.cigi_drop_framing) - frame0, msgs = stat_of(&h->stats.cigi_messages) - msgs0;
    fprintf(stderr, "  %ld datagrams in %g s: %llu host frames taken, dropped: %llu busy, %llu not allowed, %llu framing\n",
            sent, WINDOW_MIN_S, (unsigned long long)msgs, (unsigned long long)busy, (unsigned long long)host,
            (unsigned long long)framing);
    assert_true(host > 0 && framing > 0 && busy > 0);
    /* the service is still there: a frame is answered (a Start of Frame first) */
    uint8_t buf[8192];
    int answered = 0;
    for (double end = test_now_s() + 10; !answered && test_now_s() < end;) {
        cigi_frame(&b, 999999, 1);
        sendto(good, proto_buf_data(&b), proto_buf_len(&b), 0, (struct sockaddr *)&to, sizeof to);
        struct pollfd p = {.fd = good, .events = POLLIN};
        while (!answered && poll(&p, 1, 500) == 1) {
            ssize_t n = recv(good, buf, sizeof buf, 0);
            answered = n >= 24 && buf[0] == 101 && buf[24] == 103;
        }
    }
    assert_true(answered);
    proto_buf_free(&b);
    close(good);
    close(stranger);
}

/* The files in dir and their bytes. */
static void recordings_count(const char *dir, int *files, long *bytes)
{
    *files = 0, *bytes = 0;
    DIR *d = opendir(dir);
    assert_non_null(d);
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.') continue;
        char p[700];
        snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
        struct stat st;
        if (stat(p, &st) == 0) {
            (*files)++;
            *bytes += st.st_size;
        }
    }
    closedir(d);
}

/* ?record=1 writes nothing unless server.record_clients allows it; with
 * it, server.record_max_files and server.record_max_bytes bound the run. */
static void a_recording_quotas(void **state)
{
    (void)state;
    srv_hub *h = srv_daemon_hub(daemon_);
    window_begin();
    char dir[300];
    snprintf(dir, sizeof dir, "%s/rec", tmpdir);
    pthread_mutex_lock(&h->lock);
    h->settings.srv.record_clients = 0;
    pthread_mutex_unlock(&h->lock);
    test_ws w[3];
    uint64_t files0 = stat_of(&h->record_files);
    attacker(&w[0], "/?record=1", NULL);
    test_ws_close(&w[0]);
    assert_int_equal(stat_of(&h->record_files), files0);
    pthread_mutex_lock(&h->lock);
    h->settings.srv.record_clients = 1;
    pthread_mutex_unlock(&h->lock);
    proto_subscribe s;
    live_subscribe(&s);
    s.mesh_kind = PROTO_MESH_NONE;
    for (int i = 0; i < 3; i++) attacker(&w[i], "/?record=1", &s);
    proto_msg cm;
    proto_msg_init(&cm, PROTO_CAMERA);
    oc_camera_default(&cm.u.camera);
    for (int i = 0; i < 150; i++) {
        cm.u.camera.pos[0] = i;
        test_msg_send(&w[0], &cm);
        usleep(2000);
    }
    usleep(200000);
    for (int i = 0; i < 3; i++) test_ws_close(&w[i]);
    /* the recordings as the daemon leaves them once their clients are
     * gone: two readings 200 ms apart that agree, within a deadline (a
     * loaded host closes them late) */
    int files = -1;
    long bytes = -1;
    for (double end = test_now_s() + 20; test_now_s() < end;) {
        usleep(200000);
        int f;
        long b;
        recordings_count(dir, &f, &b);
        if (f == files && b == bytes && f >= 2) break;
        files = f, bytes = b;
    }
    fprintf(stderr, "  recordings: %d files, %ld bytes (quota 2 files, 4096 bytes + headers)\n", files, bytes);
    assert_int_equal(files, 2);
    assert_true(bytes <= 4096 + 2 * 256);
    window_end("recording-quotas");
}

/* ---- admin token, metrics, statistics -------------------------------------------- */

static void sea_set(test_ws *w, const char *token)
{
    proto_msg ss;
    proto_msg_init(&ss, PROTO_SEA_STATE);
    ss.u.sea_state.op = PROTO_SEA_SET;
    srv_sea_from_params(&settings.params, &ss.u.sea_state.sea);
    snprintf(ss.u.sea_state.token, sizeof ss.u.sea_state.token, "%s", token);
    test_msg_send(w, &ss);
}

/* 1200 sets with the right token, each effective now (issue 46: 76
 * announced, 731 answered ERATE, and the witness starved: the service
 * thread checked every set, 0.4-1.4 ms each, 300 ms of its time in the
 * first half second, with an ERROR queued for each refusal).  A connection
 * makes SRV_SEA_SET_PER_S sets a second after a burst of SRV_SEA_SET_BURST
 * (the rest refused ERATE, answered once a second); each change entered is
 * set a lead ahead and a lead apart (PROTOCOL.md "Sea-state timeline"), so
 * its ocean is built ahead, off the tick path. */
static void a_sea_flood(void **state)
{
    (void)state;
    srv_hub *h = srv_daemon_hub(daemon_);
    uint64_t due0 = stat_of(&h->stats.sea_built_due), ahead0 = stat_of(&h->stats.sea_built_ahead);
    uint64_t changes0 = stat_of(&h->stats.sea_changes);
    window_begin();
    test_ws w;
    attacker(&w, NULL, NULL);
    proto_msg ss;
    proto_msg_init(&ss, PROTO_SEA_STATE);
    ss.u.sea_state.op = PROTO_SEA_SET;
    snprintf(ss.u.sea_state.token, sizeof ss.u.sea_state.token, "attack-token");
    for (int i = 0; i < 1200; i++) {
        srv_sea_from_params(&settings.params, &ss.u.sea_state.sea);
        ss.u.sea_state.sea.wind_u10 += 0.01f * (float)(i + 1);
        test_msg_send(&w, &ss);
    }
    double t0 = test_now_s();
    int announced = 0, refused = 0;
    proto_msg m;
    unsigned t;
    while ((t = next_msg(&w, 1000, &m))) {
        announced += t == PROTO_SEA_STATE;
        refused += t == PROTO_ERROR && m.u.error.code == OCEAN_ERATE;
        proto_msg_free(&m);
    }
    /* every change entered takes effect */
    double answered_s = test_now_s() - t0;
    int left = 1;
    for (double end = test_now_s() + 30; left && test_now_s() < end; usleep(20000)) {
        pthread_mutex_lock(&h->lock);
        left = h->n_sea_pending;
        pthread_mutex_unlock(&h->lock);
    }
    usleep(200000);
    window_end("sea-flood");
    uint64_t due = stat_of(&h->stats.sea_built_due) - due0, ahead = stat_of(&h->stats.sea_built_ahead) - ahead0;
    fprintf(stderr, "  1200 sets: %d announced, %d ERATE answers in %.1f s; %llu changes, %llu oceans built "
            "ahead, %llu when due\n", announced, refused, answered_s,
            (unsigned long long)(stat_of(&h->stats.sea_changes) - changes0), (unsigned long long)ahead,
            (unsigned long long)due);
    /* the daemon's own sea back (outside the window: a change the admin asked for) */
    srv_sea_from_params(&settings.params, &ss.u.sea_state.sea);
    test_msg_send(&w, &ss);
    assert_true(test_msg_wait(&w, PROTO_SEA_STATE, 3000, &m));
    proto_msg_free(&m);
    test_ws_close(&w);
    assert_int_equal(left, 0);
    /* the burst, then the rate (the sets all arrived at once) */
    assert_true(announced >= 1 && announced <= SRV_SEA_SET_BURST + SRV_SEA_SET_PER_S * (answered_s + 1));
    /* a set the bucket lets through is answered (announced, or refused at
     * the pending limit); the floods past the set and message rates are
     * answered once a second each, not once a set */
    assert_true(refused >= 1 && announced + refused <= SRV_SEA_SET_BURST + (SRV_SEA_SET_PER_S + 2) * (answered_s + 1));
}

/* Token guessing (200 a second per connection before): a miss locks the
 * connection and its address out for server.admin_lockout (0.3 s here),
 * doubling; a locked attempt is not even compared (the right token is
 * refused too, ERATE). */
static void a_admin_guessing(void **state)
{
    (void)state;
    srv_hub *h = srv_daemon_hub(daemon_);
    window_begin();
    test_ws w;
    attacker(&w, NULL, NULL);
    sea_set(&w, "guess-1");
    expect_error(&w, OCEAN_EAUTH, "wrong admin token", 2000);
    sea_set(&w, "attack-token");
    expect_error(&w, OCEAN_ERATE, "locked out", 2000);
    uint64_t misses0 = stat_of(&h->stats.admin_misses);
    for (int i = 0; i < 50; i++) sea_set(&w, "guess-2");
    usleep(200000);
    assert_true(stat_of(&h->stats.admin_misses) == misses0); /* none compared */
    window_end("admin-guessing");
    /* the lockout ends: the right token is taken (no ERROR; the sea is
     * announced).  Outside the window: a sea change is the admin's right
     * and rebuilds the ocean. */
    usleep(300000);
    sea_set(&w, "attack-token");
    proto_msg m;
    assert_true(test_msg_wait(&w, PROTO_SEA_STATE, 3000, &m));
    proto_msg_free(&m);
    test_ws_close(&w);
}

/* Many connections from one address, one guess each: that address waits
 * (its own backoff, doubling, and past 20 misses in 10 s the global alarm),
 * the right token from it included; the right token from another address
 * (the admin's host) is taken at once.  The global lock refused the admin
 * too, everywhere, for as long as a guesser kept it going. */
static void a_admin_global_lockout(void **state)
{
    (void)state;
    window_begin();
    test_ws g[22], w;
    for (int i = 0; i < 22; i++) {
        attacker(&g[i], NULL, NULL);
        sea_set(&g[i], "guess-3");
    }
    /* each guess answered (EAUTH, or ERATE once its address waits) before
     * its connection closes: closed at once, a loaded daemon may read the
     * close before the guess, and no guess is ever compared */
    for (int i = 0; i < 22; i++) {
        proto_msg m;
        assert_true(test_msg_wait(&g[i], PROTO_ERROR, 5000, &m));
        assert_true(m.u.error.code == OCEAN_EAUTH || m.u.error.code == OCEAN_ERATE);
        proto_msg_free(&m);
        test_ws_close(&g[i]);
    }
    attacker(&w, NULL, NULL);
    sea_set(&w, "attack-token");
    expect_error(&w, OCEAN_ERATE, "locked out", 2000);
    test_ws_close(&w);
    window_end("admin-global-lockout");
    /* outside the window: a sea change is the admin's right and rebuilds the ocean */
    attacker_from(&w, "127.0.0.2", NULL, NULL);
    sea_set(&w, "attack-token");
    proto_msg m;
    assert_true(test_msg_wait(&w, PROTO_SEA_STATE, 3000, &m));
    proto_msg_free(&m);
    test_ws_close(&w);
}

/* /metrics shows each client's share (CPU seconds on the simulation
 * thread, bytes sent); /status tick_ms_mean is total / ticks run. */
static void a_metrics_and_status(void **state)
{
    (void)state;
    window_begin();
    char *buf = malloc(1 << 20);
    assert_non_null(buf);
    assert_int_equal(http_get(port, "/metrics", buf, 1 << 20), 200);
    char want[96];
    snprintf(want, sizeof want, "oceand_client_bytes_sent_total{client=\"%u\"} ", wit.id);
    char *at = strstr(buf, want);
    assert_non_null(at);
    assert_true(atof(at + strlen(want)) > 0);
    snprintf(want, sizeof want, "oceand_client_cpu_seconds_total{client=\"%u\"} ", wit.id);
    assert_non_null(strstr(buf, want));
    assert_non_null(strstr(buf, "oceand_refused_silent_total"));
    free(buf);
    /* the mean of ticks that ran: 10 ticks of 5 ms with 100 idle ticks is
     * 5 ms (it wrapped to 7.6e-18 when idle ticks outnumbered ticks) */
    srv_stats st;
    memset(&st, 0, sizeof st);
    atomic_store(&st.ticks, 10);
    atomic_store(&st.idle_ticks, 100);
    atomic_store(&st.tick_ns_total, 50000000);
    srv_stats_view v;
    memset(&v, 0, sizeof v);
    size_t len;
    char *js = srv_stats_json(&st, &v, 0, &len);
    assert_non_null(js);
    cJSON *o = cJSON_Parse(js);
    assert_non_null(o);
    assert_float_equal(cJSON_GetObjectItem(o, "tick_ms_mean")->valuedouble, 5.0, 1e-9);
    cJSON_Delete(o);
    free(js);
    window_end("metrics");
}

/* ---- file descriptors: the real binary under a low limit -------------------------- */

/* max_clients 1000 with RLIMIT_NOFILE 256: the daemon says it serves at most
 * 160 (96 kept), refuses the rest with BYE server-full, closes connections
 * at accept beyond the reserve with one log line a second (not one per
 * attempt: 120 000 lines in seconds before) and keeps answering /status. */
/* In the child: the low descriptor limit, stderr to the file arg. */
static void fd_limit_child(void *arg)
{
    struct rlimit rl = {256, 256};
    setrlimit(RLIMIT_NOFILE, &rl);
    int e = open((const char *)arg, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (e >= 0) dup2(e, 2);
}

static void a_fd_limit(void **state)
{
    (void)state;
    window_begin();
    char exe[700], conf2[400], errlog[400];
    snprintf(exe, sizeof exe, "%s/oceand", exe_dir);
    if (access(exe, X_OK) != 0) {
        fprintf(stderr, "no %s\n", exe);
        fail();
    }
    snprintf(conf2, sizeof conf2, "%s/fd.conf", tmpdir);
    write_conf(conf2, 1000, 0);
    snprintf(errlog, sizeof errlog, "%s/fd.err", tmpdir);
    FILE *out;
    int p;
    pid_t pid = test_oceand_exec(exe, conf2, fd_limit_child, errlog, &p, &out);
    assert_true(pid > 0);
    assert_true(p > 0);
    char line[512];
    /* 300 bare TCP connections (no handshake) and 200 WebSocket clients */
    enum { RAW = 300, WS = 200 };
    int raw[RAW];
    for (int i = 0; i < RAW; i++) raw[i] = tcp_connect(p);
    usleep(500000);
    for (int i = 0; i < RAW; i++)
        if (raw[i] >= 0) close(raw[i]);
    usleep(300000);
    static test_ws w[WS];
    int hello = 0, full = 0;
    for (int i = 0; i < WS; i++) {
        if (test_ws_connect(&w[i], p, "/", PROTO_SUBPROTOCOL) != 0) {
            w[i].fd = -1;
            continue;
        }
        /* HELLO, or BYE server-full past the clamp */
        uint8_t *b;
        size_t n;
        proto_msg m;
        if (test_ws_recv(&w[i], 2000, &b, &n) == 2) {
            char err[128];
            if (proto_decode(b, n, &m, err, sizeof err) == OCEAN_OK) {
                hello += m.hdr.type == PROTO_HELLO;
                full += m.hdr.type == PROTO_BYE && m.u.bye.reason == PROTO_BYE_SERVER_FULL;
                proto_msg_free(&m);
            }
            free(b);
        }
    }
    char *st = malloc(65536);
    assert_non_null(st);
    int status = http_get(p, "/status", st, 65536);
    free(st);
    for (int i = 0; i < WS; i++)
        if (w[i].fd >= 0) test_ws_close(&w[i]);
    kill(pid, SIGTERM);
    int ws;
    waitpid(pid, &ws, 0);
    fclose(out);
    FILE *e = fopen(errlog, "r");
    assert_non_null(e);
    int clamp = 0, accept_lines = 0, lines = 0;
    while (fgets(line, sizeof line, e)) {
        lines++;
        if (strstr(line, "serving at most 160 clients")) clamp = 1;
        if (strstr(line, "closed at accept")) accept_lines++;
    }
    fclose(e);
    fprintf(stderr, "  fd limit 256: %d HELLOs, %d told server-full, /status %d, %d log lines "
            "(%d about accept)\n", hello, full, status, lines, accept_lines);
    assert_true(clamp);
    assert_true(hello >= 150 && hello <= 160);
    assert_true(full >= 1);
    assert_int_equal(status, 200);
    assert_true(accept_lines <= 10);
    assert_true(WIFEXITED(ws) && WEXITSTATUS(ws) == 0);
    window_end("fd-limit");
}

static void rfc_handshake_refusals(void **state) { run_attack(a_rfc_handshake_refusals, state); }
static void rfc_unmasked_and_utf8(void **state) { run_attack(a_rfc_unmasked_and_utf8, state); }
static void rfc_close_codes(void **state) { run_attack(a_rfc_close_codes, state); }
static void mesh_bomb(void **state) { run_attack(a_mesh_bomb, state); }
static void query_flood(void **state) { run_attack(a_query_flood, state); }
static void replay_flood(void **state) { run_attack(a_replay_flood, state); }
static void replay_crowd(void **state) { run_attack(a_replay_crowd, state); }
static void heavy_subscriber(void **state) { run_attack(a_heavy_subscriber, state); }
static void daemon_capacity(void **state) { run_attack(a_daemon_capacity, state); }
static void partial_messages(void **state) { run_attack(a_partial_messages, state); }
static void text_and_garbage_flood(void **state) { run_attack(a_text_and_garbage_flood, state); }
static void idle_connections(void **state) { run_attack(a_idle_connections, state); }
static void recording_quotas(void **state) { run_attack(a_recording_quotas, state); }
static void metrics_and_status(void **state) { run_attack(a_metrics_and_status, state); }
static void fd_limit(void **state) { run_attack(a_fd_limit, state); }
static void sea_flood(void **state) { run_attack(a_sea_flood, state); }
static void admin_guessing(void **state) { run_attack(a_admin_guessing, state); }
static void cigi_flood(void **state) { run_attack(a_cigi_flood, state); }
static void admin_global_lockout(void **state) { run_attack(a_admin_global_lockout, state); }

int main(int argc, char **argv)
{
    (void)argc;
    test_wait_policy_passive(argv);
    test_build_dir(argv[0], exe_dir, sizeof exe_dir);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(rfc_handshake_refusals),
        cmocka_unit_test(rfc_unmasked_and_utf8),
        cmocka_unit_test(rfc_close_codes),
        cmocka_unit_test(mesh_bomb),
        cmocka_unit_test(query_flood),
        cmocka_unit_test(replay_flood),
        cmocka_unit_test(replay_crowd),
        cmocka_unit_test(heavy_subscriber),
        cmocka_unit_test(daemon_capacity),
        cmocka_unit_test(partial_messages),
        cmocka_unit_test(text_and_garbage_flood),
        cmocka_unit_test(idle_connections),
        cmocka_unit_test(recording_quotas),
        cmocka_unit_test(metrics_and_status),
        cmocka_unit_test(sea_flood),
        cmocka_unit_test(fd_limit),
        cmocka_unit_test(admin_guessing),
        cmocka_unit_test(cigi_flood),
        cmocka_unit_test(admin_global_lockout), /* last: it locks SEA_STATE for 10 s for 127.0.0.1 */
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
