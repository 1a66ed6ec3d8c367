/*
 * test_net.c - the integration tests' shared daemon and message helpers
 * (test_net.h).
 */
#include "test_net.h"

#include <arpa/inet.h>
#include <errno.h>
#include <libgen.h>
#include <netinet/in.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <cmocka.h>

#include "ocean.h"
#include "proto_buf.h"

double test_now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

void test_build_dir(const char *argv0, char *out, size_t n)
{
    char tmp[512];
    snprintf(tmp, sizeof tmp, "%s", argv0);
    snprintf(out, n, "%s", dirname(dirname(tmp)));
}

void test_wait_policy_passive(char **argv)
{
    if (ocean_wait_policy_setenv(0)) {
        execv("/proc/self/exe", argv);
        fprintf(stderr, "%s: cannot re-execute with OMP_WAIT_POLICY set: %s\n", argv[0], strerror(errno));
        exit(1);
    }
}

int test_free_port(void)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_addr.s_addr = htonl(INADDR_LOOPBACK)};
    socklen_t l = sizeof a;
    if (fd < 0)
        return -1;
    if (bind(fd, (struct sockaddr *)&a, sizeof a) != 0 || getsockname(fd, (struct sockaddr *)&a, &l) != 0) {
        close(fd);
        return -1;
    }
    close(fd);
    return ntohs(a.sin_port);
}

/* $OCEAND_BIN, else $BUILD/oceand, else build/oceand, into buf. */
static const char *oceand_bin(char *buf, size_t len)
{
    const char *bin = getenv("OCEAND_BIN"), *build = getenv("BUILD");
    if (bin)
        snprintf(buf, len, "%s", bin);
    else
        snprintf(buf, len, "%s/oceand", build ? build : "build");
    return buf;
}

/* bin --config config/oceand.conf --port port args..., stdout to /dev/null.
 * Admission for the daemon as a whole is off: it prices subscriptions from
 * what this host's cores do, and the tests on such a daemon judge other
 * behaviour, which a slow or busy host must not turn into refusals
 * (test_attacks daemon_capacity judges admission). */
static pid_t oceand_spawn(const char *bin, int port, const char *const *args)
{
    char ports[16];
    snprintf(ports, sizeof ports, "%d", port);
    const char *argv[64] = {bin, "--config", "config/oceand.conf", "--port", ports, "--set", "server.admit_share=0"};
    int n = 7;
    for (; args && *args && n < 63; args++)
        argv[n++] = *args;
    argv[n] = NULL;
    pid_t pid = fork();
    if (pid == 0) {
        if (!freopen("/dev/null", "w", stdout))
            _exit(127);
        execv(bin, (char *const *)argv);
        _exit(127);
    }
    return pid;
}

pid_t test_oceand_exec(const char *exe, const char *conf, void (*in_child)(void *), void *arg, int *port,
                       FILE **out)
{
    int pfd[2];
    *port = 0;
    *out = NULL;
    if (pipe(pfd) != 0)
        return -1;
    pid_t pid = fork();
    if (pid < 0) {
        close(pfd[0]);
        close(pfd[1]);
        return -1;
    }
    if (pid == 0) {
        dup2(pfd[1], 1);
        close(pfd[0]);
        if (in_child)
            in_child(arg);
        execl(exe, exe, "--config", conf, (char *)NULL);
        _exit(127);
    }
    close(pfd[1]);
    *out = fdopen(pfd[0], "r");
    if (!*out) {
        close(pfd[0]);
        return pid;
    }
    static const char at_url[] = "http://127.0.0.1:";
    char line[512];
    while (fgets(line, sizeof line, *out)) {
        const char *at = strstr(line, at_url);
        if (at) {
            *port = atoi(at + strlen(at_url));
            break;
        }
    }
    return pid;
}

/* An oc_client on ws://127.0.0.1:port/, tried every 50 ms up to `tries` times. */
static ocean_result oceand_connect(int port, int tries, oc_client **out, char *err, size_t errlen)
{
    char url[64];
    snprintf(url, sizeof url, "ws://127.0.0.1:%d/", port);
    oc_options o;
    oc_options_default(&o);
    o.url = url;
    *out = NULL;
    ocean_result r = OCEAN_EIO;
    for (int i = 0; i < tries && r != OCEAN_OK; i++) {
        r = oc_connect(&o, 2000, out, err, errlen);
        if (r != OCEAN_OK) {
            struct timespec ts = {0, 50 * 1000 * 1000};
            nanosleep(&ts, NULL);
        }
    }
    return r;
}

pid_t test_oceand_up(const char *const *args, int tries, oc_client **c)
{
    char bin[512], err[256] = "";
    oceand_bin(bin, sizeof bin);
    if (access(bin, X_OK) != 0 || access("config/oceand.conf", R_OK) != 0) {
        print_message("(%s not built: the test against the live daemon is skipped)\n", bin);
        skip();
    }
    int port = test_free_port();
    assert_true(port > 0);
    pid_t pid = oceand_spawn(bin, port, args);
    assert_true(pid > 0);
    if (oceand_connect(port, tries, c, err, sizeof err) != OCEAN_OK) {
        test_oceand_stop(pid);
        fail_msg("could not connect to %s: %s", bin, err);
    }
    return pid;
}

int test_oceand_stop(pid_t pid)
{
    int status = 0;
    if (pid <= 0)
        return -1;
    kill(pid, SIGTERM);
    waitpid(pid, &status, 0);
    return status;
}

int test_free_udp_port(void)
{
    int fd = socket(AF_INET, SOCK_DGRAM, 0);
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_addr.s_addr = htonl(INADDR_LOOPBACK)};
    socklen_t l = sizeof a;
    assert_int_equal(bind(fd, (struct sockaddr *)&a, sizeof a), 0);
    assert_int_equal(getsockname(fd, (struct sockaddr *)&a, &l), 0);
    close(fd);
    return ntohs(a.sin_port);
}

uint8_t *test_msg_encode(proto_msg *m, size_t *len)
{
    proto_buf b;
    proto_buf_init(&b, 0);
    char err[256];
    ocean_result r = proto_encode(&b, m, err, sizeof err);
    if (r != OCEAN_OK)
        fprintf(stderr, "encode: %s\n", err);
    assert_int_equal(r, OCEAN_OK);
    *len = b.len;
    return b.mem;
}

void test_msg_send(test_ws *w, proto_msg *m)
{
    size_t len;
    uint8_t *b = test_msg_encode(m, &len);
    assert_int_equal(test_ws_send(w, 2, b, len), 0);
    free(b);
}

int test_msg_wait(test_ws *w, unsigned type, int ms, proto_msg *m)
{
    double end = test_now_s() + ms / 1000.0;
    while (test_now_s() < end) {
        uint8_t *b;
        size_t n;
        int op = test_ws_recv(w, (int)((end - test_now_s()) * 1000) + 1, &b, &n);
        if (op <= 0)
            return 0;
        if (op == 8) {
            free(b);
            return 0;
        }
        char err[256];
        ocean_result r = proto_decode(b, n, m, err, sizeof err);
        free(b);
        if (r == OCEAN_OK && m->hdr.type == type)
            return 1;
        if (r == OCEAN_OK)
            proto_msg_free(m);
    }
    return 0;
}
