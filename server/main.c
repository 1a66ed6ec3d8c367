/*
 * main.c - build/oceand: the networked ocean-state daemon.
 *
 *   oceand [--config FILE] [--port P] [--bind ADDR] [--scene NAME]
 *          [--set KEY=VALUE]... [--dump-config] [--version] [--help]
 *
 * Signals: SIGHUP reloads the configuration file (a bad file keeps the
 * running configuration and logs file:line); SIGTERM and SIGINT send every
 * client BYE with a close reason and exit 0.  Signals are taken with
 * sigwait on the main thread, so no handler races the worker threads.
 */
#include <arpa/inet.h>
#include <errno.h>
#include <getopt.h>
#include <malloc.h>
#include <ifaddrs.h>
#include <net/if.h>
#include <netinet/in.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "ocean.h"
#include "srv_daemon.h"

#define MAX_SETS 64

/* Where an installed oceand finds its viewer and scenes when no --config
 * names them: `make install` compiles this file with -DOCEAND_DATADIR=
 * PREFIX/share/oceand.  build/oceand has none and keeps the config table's
 * defaults, which are relative to the source tree (what `make run` uses). */
#ifdef OCEAND_DATADIR
static const char *const datadir_sets[] = {"server.web_root=" OCEAND_DATADIR "/web",
                                           "server.scene_dir=" OCEAND_DATADIR "/scenes"};
#define N_DATADIR_SETS 2
#else
static const char *const datadir_sets[] = {NULL};
#define N_DATADIR_SETS 0
#endif
#ifndef OCEAND_SYSCONFDIR
#define OCEAND_SYSCONFDIR "config"
#endif

/* The one table of command-line options: getopt's table, the parser's
 * dispatch and --help are all made from it, and the defaults --help shows
 * are read from the settings the daemon really starts with, so the help
 * cannot drift from the code. */
typedef enum od_kind {
    OD_CONFIG,   /* --config FILE */
    OD_KEY,      /* shorthand for --set KEY=VALUE */
    OD_SET,      /* --set KEY=VALUE */
    OD_DUMP,     /* --dump-config */
    OD_VERSION,  /* --version */
    OD_HELP      /* --help */
} od_kind;

typedef struct od_opt {
    const char *name;   /* long option without "--" */
    char letter;        /* short option, 0 for none */
    const char *arg;    /* argument name; NULL for a flag */
    od_kind kind;
    const char *key;    /* OD_KEY: the config key it sets */
    const char *help;
} od_opt;

static const od_opt od_opts[] = {
    {"config", 'c', "FILE", OD_CONFIG, NULL,
     "configuration file (every key documented in " OCEAND_SYSCONFDIR "/oceand.conf);\n"
#ifdef OCEAND_DATADIR
     "without it " OCEAND_SYSCONFDIR "/oceand.conf if readable, else the built-in defaults below"},
#else
     "without it the built-in defaults below"},
#endif
    {"port", 'p', "P", OD_KEY, "server.port", "listen port; 0 picks a free one"},
    {"bind", 'b', "ADDR", OD_KEY, "server.bind", "listen address; \"\" for all interfaces"},
    {"scene", 's', "NAME", OD_KEY, "server.scene", "scene name in server.scene_dir, or a .conf path"},
    {"set", 'S', "KEY=VALUE", OD_SET, NULL, "override any key (repeatable), e.g. --set sea.wind=15"},
    {"dump-config", 'D', NULL, OD_DUMP, NULL, "print every key as the command line resolves it (config file, scene, --set) and exit"},
    {"version", 'V', NULL, OD_VERSION, NULL, "print the version and the protocol and exit"},
    {"help", 'h', NULL, OD_HELP, NULL, "this text"},
};
#define N_OD_OPTS (int)(sizeof od_opts / sizeof od_opts[0])

/* The built-in server.* settings (with an installed oceand's data
 * directory), without loading a scene, so --help works in any directory. */
static srv_config *help_defaults(conf_set *set, const conf_table **t, void **tg)
{
    srv_config *c = calloc(1, sizeof *c);
    if (!c) return NULL;
    t[0] = srv_config_table();
    tg[0] = c;
    *set = (conf_set){t, tg, 1};
    char err[512];
    ocean_result r = conf_defaults(set, err, sizeof err);
    for (int i = 0; r == OCEAN_OK && i < N_DATADIR_SETS; i++) r = conf_apply(datadir_sets[i], set, err, sizeof err);
    if (r != OCEAN_OK) {
        free(c);
        return NULL;
    }
    return c;
}

/* The default of a config key as the config file would spell it. */
static void key_default(const conf_set *set, const srv_config *d, const char *key, char *buf, size_t len)
{
    const conf_entry *e = d ? conf_find(set, key, NULL) : NULL;
    if (!e || conf_format(e, d, buf, len) < 0) snprintf(buf, len, "?");
}

static void usage(FILE *f)
{
    conf_set set;
    const conf_table *t[1];
    void *tg[1];
    srv_config *d = help_defaults(&set, t, tg);
    fprintf(f,
            "usage: oceand [options]\n"
            "\n"
            "Serves one shared FFT ocean to every client over WebSocket (protocol ocean.v1),\n"
            "the browser viewer at http://HOST:PORT/, /metrics (Prometheus) and /status (JSON).\n"
            "\n");
    for (int i = 0; i < N_OD_OPTS; i++) {
        const od_opt *o = &od_opts[i];
        char left[64];
        snprintf(left, sizeof left, "--%s%s%s", o->name, o->arg ? " " : "", o->arg ? o->arg : "");
        fprintf(f, "  %-18s", left);
        for (const char *h = o->help; *h;) {
            size_t n = strcspn(h, "\n");
            fprintf(f, "%s%.*s", h == o->help ? "" : "\n                    ", (int)n, h);
            h += n + (h[n] == '\n');
        }
        if (o->kind == OD_KEY) {
            char v[SRV_PATH_MAX + 16];
            key_default(&set, d, o->key, v, sizeof v);
            fprintf(f, " (%s; default %s)", o->key, v);
        }
        fputc('\n', f);
    }
    if (d)
        fprintf(f,
                "\nBuilt-in defaults: web viewer %s, scenes %s.\n", d->web_root, d->scene_dir);
    fprintf(f,
            "\n"
            "Signals: SIGHUP reloads the config; SIGTERM/SIGINT close every client with\n"
            "a reason and exit 0.  On start the daemon prints \"oceand: listening on\n"
            "http://ADDR:PORT/\" to stdout.\n");
    free(d);
}

/* Binds a throw-away socket where the daemon will listen, so that an address
 * this host does not have, or a port in use, fails here with a message that
 * names the way out, instead of libwebsockets logging a bind error and the
 * daemon running with no socket.  SO_REUSEADDR as libwebsockets sets it, so
 * a port left in TIME_WAIT by a previous run is not refused.  Returns 0 if
 * the bind would work. */
static int probe_listen(const srv_config *c, char *err, size_t errlen)
{
    struct sockaddr_in sa;
    memset(&sa, 0, sizeof sa);
    sa.sin_family = AF_INET;
    sa.sin_port = htons((uint16_t)c->port);
    sa.sin_addr.s_addr = htonl(INADDR_ANY);
    if (c->bind[0] && inet_pton(AF_INET, c->bind, &sa.sin_addr) != 1) {
        /* libwebsockets also takes an interface name (e.g. "lo"). */
        if (if_nametoindex(c->bind) != 0)
            return 0;
        struct in6_addr a6;
        if (inet_pton(AF_INET6, c->bind, &a6) == 1)
            snprintf(err, errlen, "server.bind: '%s' is an IPv6 address; oceand listens on IPv4 only "
                     "(--bind an IPv4 address or interface, \"\" for all interfaces)", c->bind);
        else
            snprintf(err, errlen, "server.bind: '%s' is neither an IPv4 address nor a network interface "
                     "of this host (--bind ADDR, \"\" for all interfaces)", c->bind);
        return -1;
    }
    int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0)
        return 0;   /* cannot tell; libwebsockets will say */
    int one = 1;
    setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    int rc = bind(fd, (struct sockaddr *)&sa, sizeof sa);
    int e = errno;
    close(fd);
    if (rc == 0)
        return 0;
    const char *addr = c->bind[0] ? c->bind : "0.0.0.0";
    if (e == EADDRNOTAVAIL)
        snprintf(err, errlen, "cannot listen on %s: no interface of this host has that address "
                 "(server.bind; use --bind with one of this host's addresses, or \"\" for all)", addr);
    else if (e == EADDRINUSE)
        snprintf(err, errlen, "cannot listen on %s:%d: the port is in use (another oceand?); choose "
                 "another with --port N or --port 0 for a free one (make run ARGS=\"--port N\")",
                 addr, c->port);
    else if (e == EACCES)
        snprintf(err, errlen, "cannot listen on %s:%d: %s (ports below 1024 need privileges; "
                 "--port N)", addr, c->port, strerror(e));
    else
        snprintf(err, errlen, "cannot listen on %s:%d: %s", addr, c->port, strerror(e));
    return -1;
}

/* The host of the URL the start line prints: the bind address, 0.0.0.0
 * for all interfaces, and for an interface name ("lo") its IPv4 address
 * (no browser opens http://lo:PORT/). */
static void listen_host(const char *bind, char *out, size_t n)
{
    struct in_addr a;
    snprintf(out, n, "%s", bind[0] ? bind : "0.0.0.0");
    if (!bind[0] || inet_pton(AF_INET, bind, &a) == 1) return;
    struct ifaddrs *ifs = NULL;
    if (getifaddrs(&ifs) != 0) return;
    for (struct ifaddrs *i = ifs; i; i = i->ifa_next)
        if (i->ifa_addr && i->ifa_addr->sa_family == AF_INET && strcmp(i->ifa_name, bind) == 0) {
            char ip[INET_ADDRSTRLEN];
            if (inet_ntop(AF_INET, &((struct sockaddr_in *)i->ifa_addr)->sin_addr, ip, sizeof ip))
                snprintf(out, n, "%s", ip);
            break;
        }
    freeifaddrs(ifs);
}

/* Keys the configuration file changed that its scene sets otherwise
 * (srv_settings.overridden): the scene wins, so the edit did nothing. */
static void say_overridden(const srv_settings *s)
{
    if (s->overridden[0])
        fprintf(stderr, "oceand: %s: scene '%s' sets %s otherwise, and a scene wins over the file: "
                "%s; change %s in the scene file, or give --set KEY=VALUE (it wins over both)\n",
                s->path, s->srv.scene, strchr(s->overridden, ',') ? "these keys" : "this key",
                s->overridden, strchr(s->overridden, ',') ? "them" : "it");
}

/* The command line, parsed (sets points into setbuf: not to be copied). */
typedef struct cmdline {
    const char *config;
    const char *sets[MAX_SETS + N_DATADIR_SETS];
    char setbuf[MAX_SETS][600];
    int nsets, nbuf, dump;
    int key_given[N_OD_OPTS]; /* a shorthand (--port ...) was typed for its key */
} cmdline;

/* One option of od_opts into cl; -1 to go on, else the exit code. */
static int take_option(const od_opt *op, cmdline *cl)
{
    if ((op->kind == OD_KEY || op->kind == OD_SET) && cl->nsets >= MAX_SETS) {
        fprintf(stderr, "oceand: too many --set options (max %d)\n", MAX_SETS);
        return 2;
    }
    switch (op->kind) {
    case OD_CONFIG: cl->config = optarg; break;
    case OD_KEY:
        cl->key_given[op - od_opts] = 1;
        snprintf(cl->setbuf[cl->nbuf], sizeof cl->setbuf[cl->nbuf], "%s=%s", op->key, optarg);
        cl->sets[cl->nsets++] = cl->setbuf[cl->nbuf++];
        break;
    case OD_SET:
        /* an explicit --set of a shorthand's key: its errors say --set */
        for (int i = 0; i < N_OD_OPTS; i++)
            if (od_opts[i].kind == OD_KEY && !strncmp(optarg, od_opts[i].key, strlen(od_opts[i].key)) &&
                optarg[strlen(od_opts[i].key)] == '=')
                cl->key_given[i] = 0;
        cl->sets[cl->nsets++] = optarg;
        break;
    case OD_DUMP: cl->dump = 1; break;
    case OD_VERSION: printf("%s (protocol %s)\n", SRV_VERSION, PROTO_SUBPROTOCOL); return 0;
    case OD_HELP: usage(stdout); return 0;
    }
    return -1;
}

/* argv into cl; -1 to go on, else the exit code. */
static int parse_args(int argc, char **argv, cmdline *cl)
{
    struct option lo[N_OD_OPTS + 1];
    char shorts[3 * N_OD_OPTS + 1], *sp = shorts;
    for (int i = 0; i < N_OD_OPTS; i++) {
        lo[i] = (struct option){od_opts[i].name, od_opts[i].arg ? required_argument : no_argument, NULL, 256 + i};
        if (od_opts[i].letter) {
            *sp++ = od_opts[i].letter;
            if (od_opts[i].arg) *sp++ = ':';
        }
    }
    *sp = 0;
    lo[N_OD_OPTS] = (struct option){NULL, 0, NULL, 0};
    int o;
    while ((o = getopt_long(argc, argv, shorts, lo, NULL)) != -1) {
        const od_opt *op = NULL;
        for (int i = 0; i < N_OD_OPTS; i++)
            if (o == 256 + i || (od_opts[i].letter && o == od_opts[i].letter)) op = &od_opts[i];
        if (!op) {
            usage(stderr);
            return 2;
        }
        int rc = take_option(op, cl);
        if (rc >= 0) return rc;
    }
    if (optind < argc) {
        fprintf(stderr, "oceand: unexpected argument '%s'\n", argv[optind]);
        usage(stderr);
        return 2;
    }
#ifdef OCEAND_DATADIR
    /* An installed oceand reads the configuration `make install` put in
     * SYSCONFDIR when no --config names another (the unit passes it too). */
    if (!cl->config && access(OCEAND_SYSCONFDIR "/oceand.conf", R_OK) == 0) {
        cl->config = OCEAND_SYSCONFDIR "/oceand.conf";
        fprintf(stderr, "oceand: reading %s (no --config given)\n", cl->config);
    }
#endif
    /* Without a config file, an installed oceand's data directory comes
     * first, so --port/--set still override it. */
    if (!cl->config && N_DATADIR_SETS) {
        memmove(cl->sets + N_DATADIR_SETS, cl->sets, (size_t)cl->nsets * sizeof *cl->sets);
        for (int i = 0; i < N_DATADIR_SETS; i++) cl->sets[i] = datadir_sets[i];
        cl->nsets += N_DATADIR_SETS;
    }
    return -1;
}

/* The settings of cl into s; 1 (said) when they are refused.  A value
 * refused for a shorthand (--port 70000) is named by the option typed,
 * not by the --set it stands for. */
static int load_settings(const cmdline *cl, srv_settings *s)
{
    char err[1024];
    if (srv_settings_load(cl->config, cl->sets, cl->nsets, s, err, sizeof err) == OCEAN_OK) return 0;
    const char *label = NULL;
    for (int i = 0; i < N_OD_OPTS && strncmp(err, "--set: ", 7) == 0; i++) {
        const char *k = od_opts[i].key;
        size_t kl = k ? strlen(k) : 0;
        if (od_opts[i].kind == OD_KEY && cl->key_given[i] && strncmp(err + 7, k, kl) == 0 && err[7 + kl] == ':')
            label = od_opts[i].name;
    }
    if (label)
        fprintf(stderr, "oceand: --%s: %s\n", label, err + 7);
    else
        fprintf(stderr, "oceand: %s\n", err);
    return 1;
}

static int dump_config(const srv_settings *s)
{
    printf("# oceand --dump-config: every key as this command line resolves it.\n");
    if (s->srv.scene[0])
        printf("# sea.* and ocean.* include scene '%s' and then --set; loading this file\n"
               "# applies the scene over its sea.* and ocean.* again (--set wins over it).\n",
               s->srv.scene);
    return srv_settings_dump(s, stdout) == OCEAN_OK ? 0 : 1;
}

/* SIGHUP: the configuration read again and applied, or refused whole. */
static void reload(srv_daemon *d, const cmdline *cl)
{
    srv_settings *ns = calloc(1, sizeof *ns);
    if (!ns) return;
    char err[1024];
    if (srv_settings_load(cl->config, cl->sets, cl->nsets, ns, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "oceand: reload refused, keeping the running configuration: %s\n", err);
    } else {
        char msg[1024];
        say_overridden(ns);
        srv_daemon_reload(d, ns, msg, sizeof msg);
        printf("oceand: configuration reloaded%s%s\n", msg[0] ? "; " : "", msg);
        fflush(stdout);
    }
    free(ns);
}

/* Starts the daemon on s and serves until SIGTERM or SIGINT (SIGHUP
 * reloads).  The signals are blocked in every thread; this one takes them. */
static int serve(const cmdline *cl, srv_settings *s)
{
    char err[1024];
    if (probe_listen(&s->srv, err, sizeof err) != 0) {
        fprintf(stderr, "oceand: %s\n", err);
        return 1;
    }
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
        return 1;
    }
    char host[INET_ADDRSTRLEN + 64];
    listen_host(s->srv.bind, host, sizeof host);
    printf("oceand: listening on http://%s:%d/ (scene %s, %d cascades of %d^2, tick %g Hz)\n", host,
           srv_daemon_port(d), s->scene.name[0] ? s->scene.name : "(none)", s->params.cascades, s->params.n,
           s->srv.tick_rate);
    fflush(stdout);
    for (;;) {
        int sig = 0;
        if (sigwait(&sigs, &sig) != 0) continue;
        if (sig == SIGHUP) {
            reload(d, cl);
            continue;
        }
        printf("oceand: %s: closing every client\n", sig == SIGTERM ? "SIGTERM" : "SIGINT");
        fflush(stdout);
        break;
    }
    srv_daemon_stop(d);
    printf("oceand: stopped\n");
    return 0;
}

int main(int argc, char **argv)
{
    /* OpenMP worker threads (frame building, the spectrum stage) must sleep
     * when they wait, not spin: on a 2-core host spinning teams starve the
     * libwebsockets thread (even the ~30 us spin that speeds a lone
     * evaluation made 256 viewers' frames later: ocean_wait_policy_setenv).
     * libgomp reads the policy when it loads, so set it and start again. */
    if (ocean_wait_policy_setenv(0))
        execv("/proc/self/exe", argv);
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
    static cmdline cl;
    int rc = parse_args(argc, argv, &cl);
    if (rc >= 0) return rc;
    srv_settings *s = calloc(1, sizeof *s);
    if (!s) return 1;
    if (load_settings(&cl, s)) {
        free(s);
        return 1;
    }
    say_overridden(s);
    rc = cl.dump ? dump_config(s) : serve(&cl, s);
    free(s);
    return rc;
}
