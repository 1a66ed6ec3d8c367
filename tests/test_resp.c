/*
 * test_resp.c - srv_resp, the bounded Redis reply reader: what it keeps,
 * what it drops off the socket (and that the connection stays in step
 * after a dropped string or array), and what it refuses.
 *
 * Replies are written into one end of a socket pair by a writer thread (a
 * reply larger than the socket buffer must be read while it is written).
 */
#include <pthread.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cmocka.h>

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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(keeps_small_drops_large),
        cmocka_unit_test(bounds_total_and_arrays),
        cmocka_unit_test(refuses_what_is_no_resp),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
