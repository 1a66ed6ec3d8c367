/*
 * test_resp.c - srv_resp, the bounded Redis reply reader: what it keeps,
 * what it drops off the socket (and that the connection stays in step
 * after a dropped string or array), and what it refuses.
 *
 * Replies are written into one end of a socket pair by a writer thread (a
 * reply larger than the socket buffer must be read while it is written).
 * And how srv_redis reads through it when Redis is slow: a fake Redis on
 * loopback that never answers a full batch.
 */
#include <pthread.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cmocka.h>

#include "srv_redis.h"
#include "srv_resp.h"

static const srv_resp_limits LIM = {
    .max_string = 16, .max_total = 40, .max_array = 4, .max_nodes = 12, .idle_s = 2.0};

typedef struct wjob {
    int fd;
    const char *bytes;
    size_t len;
} wjob;

static void *writer(void *arg)
{
    wjob *j = arg;
    size_t at = 0;
    while (at < j->len) {
        ssize_t n = write(j->fd, j->bytes + at, j->len - at);
        if (n <= 0) break;
        at += (size_t)n;
    }
    return NULL;
}

/* Reads one reply from the bytes given; *res gets the result. */
static srv_resp *read_bytes(const char *bytes, size_t len, int sv[2], ocean_result *res, char *why, size_t whylen)
{
    wjob j = {sv[1], bytes, len};
    pthread_t t;
    assert_int_equal(pthread_create(&t, NULL, writer, &j), 0);
    srv_resp *r = NULL;
    *res = srv_resp_read(sv[0], &LIM, &r, why, whylen);
    pthread_join(t, NULL);
    return r;
}

static void pair(int sv[2]) { assert_int_equal(socketpair(AF_UNIX, SOCK_STREAM, 0, sv), 0); }

/* An XRANGE-shaped reply: strings within the limit are kept, one over it
 * is dropped with its length, and the next reply reads in step. */
static void keeps_small_drops_large(void **state)
{
    (void)state;
    int sv[2];
    pair(sv);
    size_t big = 1u << 20;
    char *bytes = malloc(big + 256);
    assert_non_null(bytes);
    int k = sprintf(bytes, "*2\r\n*2\r\n$3\r\n1-0\r\n*2\r\n$3\r\nmsg\r\n$5\r\nhello\r\n"
                           "*2\r\n$3\r\n2-0\r\n*2\r\n$3\r\nmsg\r\n$%zu\r\n", big);
    memset(bytes + k, 'x', big);
    memcpy(bytes + k + big, "\r\n", 2);
    char why[200];
    ocean_result res;
    srv_resp *r = read_bytes(bytes, (size_t)k + big + 2, sv, &res, why, sizeof why);
    free(bytes);
    assert_int_equal(res, OCEAN_OK);
    assert_int_equal(r->type, SRV_RESP_ARRAY);
    assert_int_equal(r->n, 2);
    const srv_resp *f0 = &r->elem[0].elem[1], *f1 = &r->elem[1].elem[1];
    assert_string_equal(r->elem[0].elem[0].str, "1-0");
    assert_int_equal(f0->elem[1].type, SRV_RESP_STRING);
    assert_string_equal(f0->elem[1].str, "hello");
    assert_string_equal(r->elem[1].elem[0].str, "2-0");
    assert_int_equal(f1->elem[1].type, SRV_RESP_SKIPPED);
    assert_int_equal(f1->elem[1].integer, (long long)big);
    srv_resp_free(r);
    r = read_bytes(":42\r\n", 5, sv, &res, why, sizeof why);
    assert_int_equal(res, OCEAN_OK);
    assert_int_equal(r->type, SRV_RESP_INTEGER);
    assert_int_equal(r->integer, 42);
    srv_resp_free(r);
    close(sv[0]);
    close(sv[1]);
}

/* Past max_total or an array over max_array: dropped, in step; a small
 * string (an id) is kept past max_total. */
static void bounds_total_and_arrays(void **state)
{
    (void)state;
    static const srv_resp_limits lim = {
        .max_string = 100, .max_total = 150, .max_array = 5, .max_nodes = 12, .idle_s = 2.0};
    char s70[71], bytes[512];
    memset(s70, 'a', 70);
    s70[70] = '\0';
    snprintf(bytes, sizeof bytes, "*5\r\n$70\r\n%s\r\n$70\r\n%s\r\n$70\r\n%s\r\n$3\r\n9-1\r\n"
             "*6\r\n:1\r\n:2\r\n:3\r\n:4\r\n:5\r\n:6\r\n", s70, s70, s70);
    int sv[2];
    pair(sv);
    wjob j = {sv[1], bytes, strlen(bytes)};
    writer(&j);
    char why[200];
    srv_resp *r = NULL;
    assert_int_equal(srv_resp_read(sv[0], &lim, &r, why, sizeof why), OCEAN_OK);
    assert_int_equal(r->n, 5);
    assert_int_equal(r->elem[0].type, SRV_RESP_STRING);
    assert_int_equal(r->elem[1].type, SRV_RESP_STRING);
    assert_int_equal(r->elem[2].type, SRV_RESP_SKIPPED); /* 210 bytes > max_total 150 */
    assert_int_equal(r->elem[2].integer, 70);
    assert_int_equal(r->elem[3].type, SRV_RESP_STRING);  /* small: kept */
    assert_string_equal(r->elem[3].str, "9-1");
    assert_int_equal(r->elem[4].type, SRV_RESP_SKIPPED); /* 6 > max_array 5 */
    assert_int_equal(r->elem[4].integer, 6);
    srv_resp_free(r);
    j = (wjob){sv[1], "-WRONGTYPE no stream\r\n", 22};
    writer(&j);
    assert_int_equal(srv_resp_read(sv[0], &lim, &r, why, sizeof why), OCEAN_OK);
    assert_int_equal(r->type, SRV_RESP_ERROR);
    assert_string_equal(r->str, "WRONGTYPE no stream");
    srv_resp_free(r);
    close(sv[0]);
    close(sv[1]);
}

/* What is no RESP, or ends early, is refused (EIO, why says so). */
static void refuses_what_is_no_resp(void **state)
{
    (void)state;
    static const char *const bad[] = {"?what\r\n", "$5\r\nab", "*x\r\n", "$-2\r\n", ":1\n", "$3\r\nabcXY"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        int sv[2];
        pair(sv);
        char why[200] = "";
        wjob j = {sv[1], bad[i], strlen(bad[i])};
        writer(&j);
        shutdown(sv[1], SHUT_WR);
        srv_resp *r = NULL;
        assert_int_equal(srv_resp_read(sv[0], &LIM, &r, why, sizeof why), OCEAN_EIO);
        assert_null(r);
        assert_non_null(strstr(why, "Redis reply"));
        close(sv[0]);
        close(sv[1]);
    }
}

/* A fake Redis: every XRANGE's COUNT is recorded; one asking for more
 * than `most` entries gets no reply (Redis still building it), the others
 * an empty stream, after slow_ms (a Redis starved of CPU). */
typedef struct fake_redis {
    int listen_fd, port, most, slow_ms;
    int counts[16], n;
    volatile int stop;
} fake_redis;

static void *fake_serve(void *arg)
{
    fake_redis *f = arg;
    while (!f->stop) {
        int c = accept(f->listen_fd, NULL, NULL);
        if (c < 0) break;
        char buf[4096];
        ssize_t n;
        while ((n = read(c, buf, sizeof buf - 1)) > 0) {
            buf[n] = 0;
            const char *at = strstr(buf, "COUNT\r\n$");
            int count = -1;
            if (at && (at = strstr(at + 8, "\r\n"))) count = atoi(at + 2);
            if (f->n < 16) f->counts[f->n++] = count;
            if (count > f->most) continue;   /* no byte: the reader gives up after its wait */
            if (f->slow_ms) usleep((useconds_t)f->slow_ms * 1000);
            if (send(c, "*0\r\n", 4, MSG_NOSIGNAL) != 4) break;
        }
        close(c);
    }
    return NULL;
}

/* Starts a replica (srv_redis_start) on fake Redis f and stops it again;
 * the start's result, msg saying why it failed. */
static ocean_result replica_on_fake(fake_redis *f, char *msg, size_t msglen)
{
    f->listen_fd = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_addr.s_addr = htonl(INADDR_LOOPBACK)};
    socklen_t al = sizeof a;
    assert_int_equal(bind(f->listen_fd, (struct sockaddr *)&a, sizeof a), 0);
    assert_int_equal(listen(f->listen_fd, 4), 0);
    assert_int_equal(getsockname(f->listen_fd, (struct sockaddr *)&a, &al), 0);
    pthread_t t;
    assert_int_equal(pthread_create(&t, NULL, fake_serve, f), 0);
    srv_settings s;
    assert_int_equal(srv_settings_default(&s, msg, msglen), OCEAN_OK);
    snprintf(s.srv.redis, sizeof s.srv.redis, "127.0.0.1:%d", ntohs(a.sin_port));
    srv_hub h;
    assert_int_equal(srv_hub_init(&h, &s), OCEAN_OK);
    srv_redis *r = NULL;
    ocean_result res = srv_redis_start(&h, &s, &r, msg, msglen);
    srv_redis_stop(r);
    f->stop = 1;
    shutdown(f->listen_fd, SHUT_RDWR);
    close(f->listen_fd);
    pthread_join(t, NULL);
    srv_hub_fini(&h);
    return res;
}

/* A replica's first read of a stream whose batches Redis is too slow to
 * answer (no byte within the reader's wait) is asked again with a quarter
 * of the entries, on a new connection, until one comes: the replica
 * starts, where it refused to start on a loaded host. */
static void slow_batches_ask_fewer(void **state)
{
    (void)state;
    fake_redis f = {.most = 64};
    char msg[300] = "";
    if (replica_on_fake(&f, msg, sizeof msg) != OCEAN_OK) fail_msg("the replica did not start: %s", msg);
    assert_true(f.n >= 2);
    assert_int_equal(f.counts[0], SRV_REDIS_BATCH);
    assert_int_equal(f.counts[1], SRV_REDIS_BATCH / 4);
}

/* A starting replica whose one-entry read Redis answers only after 1.3 s
 * (more than the reader's 1 s wait: a Redis at nice 10 on a host with a
 * core busy, still building the replies of the reads abandoned before)
 * waits twice as long for the next: it starts, where it gave up after the
 * one-entry read and refused to start (CI: test_replicas
 * hostile_stream_bounded under ASan with a core busy). */
static void slow_redis_waited_for_at_start(void **state)
{
    (void)state;
    fake_redis f = {.most = 1, .slow_ms = 1300};
    char msg[300] = "";
    if (replica_on_fake(&f, msg, sizeof msg) != OCEAN_OK) fail_msg("the replica did not start: %s", msg);
    /* 256, 64, 16, 4, then one entry at 1 s, and again at a longer wait */
    assert_true(f.n >= 6);
    assert_int_equal(f.counts[3], 4);
    assert_int_equal(f.counts[4], 1);
    assert_int_equal(f.counts[5], 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(keeps_small_drops_large),
        cmocka_unit_test(bounds_total_and_arrays),
        cmocka_unit_test(refuses_what_is_no_resp),
        cmocka_unit_test(slow_batches_ask_fewer),
        cmocka_unit_test(slow_redis_waited_for_at_start),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
