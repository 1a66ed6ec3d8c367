/*
 * cmd_wake.c - `ocean-sim wake`: the steady wake of one body as the library
 * evaluates it (sim/wake.h), for checking against the published laws:
 * surface heights in the body's frame, JSON.  No wind sea: it takes no
 * sea-state option.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <cJSON.h>

#include "cli.h"
#include "wake.h"

int cmd_wake(int argc, char **argv)
{
    wake_params p = {.speed = NAN, .length = NAN, .depth = 0};
    double heading = 0;
    int json = 0;
    const cli_opt opts[] = {
        {"speed", CLI_DOUBLE, &p.speed, 1e-3, WAKE_SPEED_MAX, "U     the body's speed, m/s (required)", NULL},
        {"length", CLI_DOUBLE, &p.length, WAKE_LENGTH_MIN, WAKE_LENGTH_MAX,
         "L     its length (the pressure footprint, a sixth as wide), m (required)", NULL},
        {"depth", CLI_DOUBLE, &p.depth, 0, 12000, "H     water depth, m; 0: deep water", NULL},
        {"heading", CLI_DOUBLE, &heading, -360, 360,
         "DEG   the body's heading, printed with the wake (heights are in the body's frame)", NULL},
        {"json", CLI_FLAG, &json, 0, 0, "      print the heights as JSON", NULL},
    };
    int pr = cli_parse(argc, argv, "wake --speed U --length L [--depth H] [--heading DEG] [--json]", opts,
                       (int)(sizeof opts / sizeof opts[0]), NULL, NULL, NULL);
    if (pr) return pr == 1 ? 0 : 2;
    if (isnan(p.speed) || isnan(p.length)) {
        fprintf(stderr, "ocean-sim wake: --speed and --length are required\n");
        return 2;
    }
    if (p.depth == 0) p.depth = INFINITY;
    wake_grid g;
    char msg[256];
    if (wake_steady(&p, &g, msg, sizeof msg) != OCEAN_OK) {
        fprintf(stderr, "ocean-sim wake: %s\n", msg);
        return 1;
    }
    if (!json) {
        printf("wake of U = %g m/s, L = %g m, depth %g m: %d x %d heights from x = %g m, z = %g m, "
               "every %g m; transverse wavelength %g m (--json prints them)\n",
               p.speed, p.length, p.depth, g.nx, g.nz, g.x0, g.z0, g.dx, wake_transverse_wavelength(&p));
        wake_grid_free(&g);
        return 0;
    }
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "speed", p.speed);
    cJSON_AddNumberToObject(o, "length", p.length);
    if (isinf(p.depth)) cJSON_AddNullToObject(o, "depth");
    else cJSON_AddNumberToObject(o, "depth", p.depth);
    cJSON_AddNumberToObject(o, "heading", heading);
    cJSON_AddNumberToObject(o, "x0", g.x0);
    cJSON_AddNumberToObject(o, "z0", g.z0);
    cJSON_AddNumberToObject(o, "dx", g.dx);
    cJSON_AddNumberToObject(o, "nx", g.nx);
    cJSON_AddNumberToObject(o, "nz", g.nz);
    cJSON *h = cJSON_AddArrayToObject(o, "heights");
    for (size_t i = 0; h && i < (size_t)g.nx * g.nz; i++) cJSON_AddItemToArray(h, cJSON_CreateNumber(g.heights[i]));
    char *text = cJSON_PrintUnformatted(o);
    int rc = text ? 0 : 1;
    if (text) puts(text);
    free(text);
    cJSON_Delete(o);
    wake_grid_free(&g);
    return rc;
}
