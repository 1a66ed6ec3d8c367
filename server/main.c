/*
 * main.c - build/oceand: the networked ocean-state daemon.
 *
 *   oceand [--config FILE] [--port P] [--bind ADDR] [--scene NAME]
 *          [--set KEY=VALUE]... [--dump-config] [--help]
 *
 * Signals: SIGHUP reloads the configuration file (a bad file keeps the
 * running configuration and logs file:line); SIGTERM and SIGINT send every
 * client BYE with a close reason and exit 0.  Signals are taken with
 * sigwait on the main thread, so no handler races the worker threads.
 */
#include <errno.h>
#include <getopt.h>
#include <malloc.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "srv_daemon.h"

#define MAX_SETS 64

static void usage(FILE *f)
{
    fprintf(f,
            "usage: oceand [options]\n"
            "\n"
            "Serves one shared FFT ocean to every client over WebSocket (protocol ocean.v1),\n"
            "the browser viewer at http://HOST:PORT/, /metrics (Prometheus) and /status (JSON).\n"
            "\n"
            "  --config FILE     configuration file (default: built-in defaults;\n"
            "                    see config/oceand.conf, every key documented)\n"
            "  --port P          listen port (server.port); 0 picks a free one\n"
            "  --bind ADDR       listen address (server.bind); \"\" for all interfaces\n"
            "  --scene NAME      scene name in server.scene_dir, or a .conf path\n"
            "  --set KEY=VALUE   override any key (repeatable), e.g. --set sea.wind=15\n"
            "  --dump-config     print the server.* keys with their help and exit\n"
            "  --help            this text\n"
            "\n"
            "Signals: SIGHUP reloads the config; SIGTERM/SIGINT close every client with\n"
            "a reason and exit 0.  On start the daemon prints \"oceand: listening on\n"
            "http://ADDR:PORT/\" to stdout.\n");
}

int main(int argc, char **argv)
{
    /* OpenMP worker threads (frame building, the spectrum stage) must sleep
     * between ticks, not spin: on a 2-core host spinning teams starve the
     * libwebsockets thread.  libgomp reads the policy when it loads, so set
     * it and start again. */
    if (!getenv("OMP_WAIT_POLICY")) {
        setenv("OMP_WAIT_POLICY", "passive", 1);
        execv("/proc/self/exe", argv);
    }
    /* Every tick builds and frees FRAME encodings of 100-200 KB, and
     * libwebsockets copies each partial write's remainder into a fresh
     * buffer.  With glibc's defaults such blocks come from new mmaps or are
     * handed back by heap trimming as soon as they are freed, so each tick
     * faulted and zeroed its pages again: 15 % of the daemon's CPU at 256
     * viewers, and a p99 30-55 ms instead of ~21 ms (tests/bench/REPORT.md).
     * Freed memory stays mapped instead: blocks under 16 MiB come from the
     * heap, which is trimmed only past 256 MiB free.  MALLOC_MMAP_THRESHOLD_
     * and MALLOC_TRIM_THRESHOLD_ in the environment still decide. */
    if (!getenv("MALLOC_MMAP_THRESHOLD_")) mallopt(M_MMAP_THRESHOLD, 16 << 20);
    if (!getenv("MALLOC_TRIM_THRESHOLD_")) mallopt(M_TRIM_THRESHOLD, 256 << 20);
    const char *config = NULL;
    const char *sets[MAX_SETS];
    char setbuf[3][600];
    int nsets = 0, nextra = 0;
    static const struct option opts[] = {
        {"config", required_argument, NULL, 'c'}, {"port", required_argument, NULL, 'p'},
        {"bind", required_argument, NULL, 'b'},   {"scene", required_argument, NULL, 's'},
        {"set", required_argument, NULL, 'S'},    {"dump-config", no_argument, NULL, 'D'},
        {"help", no_argument, NULL, 'h'},         {NULL, 0, NULL, 0}};
    int o;
    while ((o = getopt_long(argc, argv, "c:p:b:s:S:hD", opts, NULL)) != -1) {
        switch (o) {
        case 'c': config = optarg; break;
        case 'p':
        case 'b':
        case 's':
            if (nextra >= 3 || nsets >= MAX_SETS) return 2;
            snprintf(setbuf[nextra], sizeof setbuf[nextra], "server.%s=%s",
                     o == 'p' ? "port" : o == 'b' ? "bind" : "scene", optarg);
            sets[nsets++] = setbuf[nextra++];
            break;
        case 'S':
            if (nsets >= MAX_SETS) {
                fprintf(stderr, "oceand: too many --set options (max %d)\n", MAX_SETS);
                return 2;
            }
            sets[nsets++] = optarg;
            break;
        case 'D': return srv_config_dump(stdout) == OCEAN_OK ? 0 : 1;
        case 'h': usage(stdout); return 0;
        default: usage(stderr); return 2;
        }
    }
    if (optind < argc) {
        fprintf(stderr, "oceand: unexpected argument '%s'\n", argv[optind]);
        usage(stderr);
        return 2;
    }
    srv_settings *s = calloc(1, sizeof *s);
    if (!s) return 1;
    char err[1024];
    if (srv_settings_load(config, sets, nsets, s, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "oceand: %s\n", err);
        free(s);
        return 1;
    }
    /* Block the signals in every thread; the main thread takes them. */
    sigset_t sigs;
    sigemptyset(&sigs);
    sigaddset(&sigs, SIGHUP);
    sigaddset(&sigs, SIGTERM);
    sigaddset(&sigs, SIGINT);
    pthread_sigmask(SIG_BLOCK, &sigs, NULL);
    signal(SIGPIPE, SIG_IGN);

    srv_daemon *d;
    if (srv_daemon_start(s, &d, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "oceand: %s\n", err);
        free(s);
        return 1;
    }
    printf("oceand: listening on http://%s:%d/ (scene %s, %d cascades of %d^2, tick %g Hz)\n",
           s->srv.bind[0] ? s->srv.bind : "0.0.0.0", srv_daemon_port(d),
           s->scene.name[0] ? s->scene.name : "(none)", s->params.cascades, s->params.n,
           s->srv.tick_rate);
    fflush(stdout);
    for (;;) {
        int sig = 0;
        if (sigwait(&sigs, &sig) != 0) continue;
        if (sig == SIGHUP) {
            srv_settings *ns = calloc(1, sizeof *ns);
            if (!ns) continue;
            if (srv_settings_load(config, sets, nsets, ns, err, sizeof err) != OCEAN_OK) {
                fprintf(stderr, "oceand: reload refused, keeping the running configuration: %s\n", err);
            } else {
                char msg[256];
                srv_daemon_reload(d, ns, msg, sizeof msg);
                printf("oceand: configuration reloaded%s%s\n", msg[0] ? "; " : "", msg);
                fflush(stdout);
            }
            free(ns);
            continue;
        }
        printf("oceand: %s: closing every client\n", sig == SIGTERM ? "SIGTERM" : "SIGINT");
        fflush(stdout);
        break;
    }
    srv_daemon_stop(d);
    free(s);
    printf("oceand: stopped\n");
    return 0;
}
