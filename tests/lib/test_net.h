/*
 * test_net.h - what the integration tests share for talking to a daemon:
 * a monotonic clock, a free loopback port, the oceand binary of this build
 * started as a child process, and protocol messages sent and awaited over
 * the raw client of test_ws.h.
 *
 * For cmocka test programs only: the message helpers assert (cmocka's
 * assert_*), so a failure is reported at the test that made the call.
 */
#ifndef TEST_NET_H
#define TEST_NET_H

#include <stddef.h>
#include <stdint.h>
#include <sys/types.h>

#include "oceanclient.h"
#include "proto.h"
#include "test_ws.h"

/* Seconds on CLOCK_MONOTONIC. */
double test_now_s(void);

/* A loopback TCP port nothing listens on at the time of the call (the
 * kernel's choice for port 0), or -1.  Another process may take it before
 * the caller binds it; tests start one daemon per port they asked for. */
int test_free_port(void);

/* The oceand binary of this build: $OCEAND_BIN, else $BUILD/oceand, else
 * build/oceand, written into buf.  Returns buf. */
const char *test_oceand_bin(char *buf, size_t len);

/* Starts `bin --config config/oceand.conf --port port args...` as a child
 * (args: NULL-terminated, may be NULL), its stdout sent to /dev/null.
 * Returns the child's pid, or -1 if fork failed. */
pid_t test_oceand_spawn(const char *bin, int port, const char *const *args);

/* Connects an oc_client to ws://127.0.0.1:port/, retrying every 50 ms up
 * to `tries` times while the daemon starts.  On failure *out is NULL and
 * err holds the last error. */
ocean_result test_oceand_connect(int port, int tries, oc_client **out, char *err, size_t errlen);

/* Stops a child started by test_oceand_spawn (SIGTERM, then reaps it);
 * returns its wait status. */
int test_oceand_stop(pid_t pid);

/* Encodes m into a malloc'ed buffer of *len bytes; asserts it encodes. */
uint8_t *test_msg_encode(proto_msg *m, size_t *len);

/* Sends m as one binary message; asserts it went out. */
void test_msg_send(test_ws *w, proto_msg *m);

/* Reads messages until one of `type` arrives within ms, decoded into *m
 * (the caller frees it with proto_msg_free); others are dropped.  1 if it
 * came, 0 on timeout, close or EOF. */
int test_msg_wait(test_ws *w, unsigned type, int ms, proto_msg *m);

#endif
