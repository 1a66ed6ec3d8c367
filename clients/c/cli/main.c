/*
 * main.c - ocean-client's entry point: the signals that stop a streaming
 * command, the top-level usage and the dispatch to the subcommands
 * (occli.h).
 */
#include <signal.h>
#include <stdio.h>
#include <string.h>

#include "occli.h"

static void on_signal(int sig)
{
    (void)sig;
    occli_stop = 1;
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: ocean-client COMMAND URL [options]   (URL: ws://host:port/)\n"
            "\n"
            "Commands:\n"
            "  watch URL [--seconds S] [--json]         per-frame statistics of a live stream\n"
            "  query URL --points \"x1,z1;x2,z2\" [--t T] [--json]\n"
            "                                           height, normal, velocity at points\n"
            "  record URL --path PATH.csv --out FRAMES  fly a camera path live, save what came back\n"
            "  replay URL PATH.csv --out FRAMES [--check FRAMES]\n"
            "                                           replay mode; --check compares byte for byte\n"
            "  export URL --out DIR                     received tiles as OpenEXR files\n"
            "  load URL --clients N --seconds S --rate HZ [--json]\n"
            "                                           many viewers from one process\n"
            "  sea URL [--set --token T --wind U ...]   show or set the sea state\n"
            "  entity URL [--set|--remove --token T --id N ...]\n"
            "                                           list, place or remove ships and aircraft\n"
            "  fidelity URL --camera-height H --speed V [--frames N] [--json]\n"
            "                                           delivered slope variance, foam, e_error, e_total\n"
            "\n"
            "Run 'ocean-client COMMAND --help' for a command's options.\n");
}

int main(int argc, char **argv)
{
    signal(SIGPIPE, SIG_IGN);
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    if (argc < 2) {
        usage(stderr);
        return 2;
    }
    const char *c = argv[1];
    if (!strcmp(c, "--help") || !strcmp(c, "-h") || !strcmp(c, "help")) {
        usage(stdout);
        return 0;
    }
    if (!strcmp(c, "--version")) {
        printf("ocean-client %s (protocol %s)\n", OC_VERSION, PROTO_SUBPROTOCOL);
        return 0;
    }
    static const struct {
        const char *name;
        int (*fn)(int, char **);
    } cmds[] = {
        {"watch", cmd_watch},   {"query", cmd_query}, {"record", cmd_record}, {"replay", cmd_replay},
        {"export", cmd_export}, {"load", cmd_load},   {"sea", cmd_sea},       {"entity", cmd_entity},
        {"fidelity", cmd_fidelity},
    };
    for (size_t i = 0; i < sizeof cmds / sizeof cmds[0]; i++)
        if (!strcmp(c, cmds[i].name))
            return cmds[i].fn(argc - 1, argv + 1);
    fprintf(stderr, "ocean-client: unknown command '%s'\n", c);
    usage(stderr);
    return 2;
}
