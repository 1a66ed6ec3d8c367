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
#include <stdio.h>
#include <sys/types.h>

#include "oceanclient.h"
#include "proto.h"
#include "test_ws.h"

/* Seconds on CLOCK_MONOTONIC. */
double test_now_s(void);

/* The build directory of the test program run as argv0 (BUILD of
 * BUILD/tests/test_x), where its oceand is, into out (n bytes). */
void test_build_dir(const char *argv0, char *out, size_t n);

/* The start of main() in a program that runs the daemon in process: as
 * build/oceand does, OpenMP teams must sleep, not spin, and libgomp reads
 * the policy when it starts, so this re-executes the program with the
 * policy set (ocean_wait_policy_setenv) and returns only when it is set.
 * LSan's suppressions for lws client contexts: tests/lib/test_ws.c. */
void test_wait_policy_passive(char **argv);

/* A loopback TCP port nothing listens on at the time of the call (the
 * kernel's choice for port 0), or -1.  Another process may take it before
 * the caller binds it; tests start one daemon per port they asked for. */
int test_free_port(void);

/* Runs `exe --config conf` as a child with its stdout on a pipe (after
 * in_child(arg) in the child, unless NULL: limits, stderr) and reads that
 * stdout up to the line announcing http://127.0.0.1:PORT.  Returns the
 * child's pid, or -1 if pipe or fork failed; *port gets PORT (0 if the
 * child's stdout ended first) and *out the rest of that stdout (fclose it
 * once the child is stopped). */
pid_t test_oceand_exec(const char *exe, const char *conf, void (*in_child)(void *), void *arg, int *port,
                       FILE **out);

/* The start of a test against this build's oceand: skips the test (cmocka
 * skip) when the binary or config/oceand.conf is missing; otherwise starts
 * `build/oceand --config config/oceand.conf --port PORT args...` (args
 * NULL-terminated, may be NULL; the binary is $OCEAND_BIN, else
 * $BUILD/oceand, else build/oceand) on a free port, its stdout to
 * /dev/null, and connects *c to ws://127.0.0.1:PORT/, trying every 50 ms up
 * to `tries` times while it starts; fails the test if it cannot.  Returns
 * the child's pid (stop it with test_oceand_stop). */
pid_t test_oceand_up(const char *const *args, int tries, oc_client **c);

/* Stops a child started by test_oceand_up or test_oceand_exec (SIGTERM,
 * then reaps it); returns its wait status. */
int test_oceand_stop(pid_t pid);

/* A free UDP port on loopback (bound, read, released); asserts it finds one. */
int test_free_udp_port(void);

/* Encodes m into a malloc'ed buffer of *len bytes; asserts it encodes. */
uint8_t *test_msg_encode(proto_msg *m, size_t *len);

/* Sends m as one binary message; asserts it went out. */
void test_msg_send(test_ws *w, proto_msg *m);

/* Reads messages until one of `type` arrives within ms, decoded into *m
 * (the caller frees it with proto_msg_free); others are dropped.  1 if it
 * came, 0 on timeout, close or EOF. */
int test_msg_wait(test_ws *w, unsigned type, int ms, proto_msg *m);

#endif
