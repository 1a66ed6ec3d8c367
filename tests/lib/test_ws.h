/*
 * test_ws.h - a deliberately dumb blocking WebSocket client for tests: it
 * sends arbitrary bytes (hostile input, text frames, oversized messages)
 * that a proper client library refuses to produce, and it can stop reading
 * altogether to play a slow consumer.
 */
#ifndef TEST_WS_H
#define TEST_WS_H

#include <stddef.h>
#include <stdint.h>

typedef struct test_ws {
    int fd;
    uint8_t *buf;      /* receive buffer */
    size_t len, cap;
} test_ws;

/* Connects to 127.0.0.1:port and completes the handshake for subprotocol
 * (NULL: none), with an optional path ("/?record=1").  0 on success. */
int test_ws_connect(test_ws *w, int port, const char *path, const char *subprotocol);
/* The same from source address src (e.g. "127.0.0.2": a client of another
 * host, on loopback), or from any when src is NULL. */
int test_ws_connect_from(test_ws *w, const char *src, int port, const char *path, const char *subprotocol);
void test_ws_close(test_ws *w);
/* Sends one message as a single frame (opcode 2 binary, 1 text). */
int test_ws_send(test_ws *w, int opcode, const void *data, size_t len);
/* Sends bytes [from, to) of that frame as it goes on the wire (header
 * included; to is clamped to its end): a message begun and finished later. */
int test_ws_send_part(test_ws *w, int opcode, const void *data, size_t len, size_t from, size_t to);
/* Receives the next complete data message within timeout_ms.  Returns its
 * opcode (1, 2, 8 for close) and a malloc'ed payload in *out / *outlen;
 * 0 on timeout, -1 on error or EOF. */
int test_ws_recv(test_ws *w, int timeout_ms, uint8_t **out, size_t *outlen);
/* Shrinks the socket's receive buffer (call before connect has no effect;
 * this sets it on the open socket). */
void test_ws_small_rcvbuf(test_ws *w, int bytes);

#endif
