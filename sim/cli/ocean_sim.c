/*
 * ocean_sim.c - `ocean-sim`, the offline tool: one binary, one subcommand
 * per job (stats, bake, sample, bench, query, filter, mesh).
 */
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "ocean.h"

static const struct {
    const char *name;
    int (*fn)(int, char **);
    const char *what;
} commands[] = {
    {"stats", cmd_stats, "statistics of one evaluation (Hs, Tp, folding, cost)"},
    {"bake", cmd_bake, "OpenEXR sequences of displacement, normals and foam"},
    {"sample", cmd_sample, "height time series at a point (CSV)"},
    {"bench", cmd_bench, "ms per evaluation beside FFTW alone"},
    {"query", cmd_query, "height, normal, velocity, foam at world points"},
    {"filter", cmd_filter, "cutoff a camera speed gets under a policy, and its cost"},
    {"mesh", cmd_mesh, "build a LOD mesh for a camera, write OBJ"},
    {"wisdom", cmd_wisdom, "time FFTW plans once, write wisdom replicas share"},
    {"wake", cmd_wake, "the steady wake of one moving body (JSON heights)"},
    {"render", cmd_render, "the reference image of the exact sea from a camera (PNG)"},
};

static void usage(FILE *to)
{
    fprintf(to, "usage: ocean-sim COMMAND [options]   (ocean-sim COMMAND --help)\n\ncommands:\n");
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        fprintf(to, "  %-8s %s\n", commands[i].name, commands[i].what);
}

int main(int argc, char **argv)
{
    /* Its work is evaluating: passive with a short spin between an
     * evaluation's parallel regions (ocean_wait_policy_setenv). */
    if (ocean_wait_policy_setenv(1))
        execv("/proc/self/exe", argv);
    if (argc < 2) {
        usage(stderr);
        return 2;
    }
    if (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0 || strcmp(argv[1], "help") == 0) {
        usage(stdout);
        return 0;
    }
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        if (strcmp(argv[1], commands[i].name) == 0)
            return commands[i].fn(argc - 1, argv + 1);
    fprintf(stderr, "error: unknown command '%s'\n", argv[1]);
    usage(stderr);
    return 2;
}
