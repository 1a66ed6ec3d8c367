/*
 * cmd_query.c - `ocean-client query`: the daemon's height, normal,
 * velocity, foam and error bound at world points.
 */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cJSON.h>

#include "occli.h"
#include "ocean_time.h"

/* Parses "x1,z1;x2,z2;..." into a new array of 2n doubles. */
static int parse_points(const char *s, double **out, size_t *n)
{
    size_t cap = 16, cnt = 0;
    double *v = malloc(cap * 2 * sizeof *v);
    if (!v)
        return -1;
    const char *p = s;
    while (*p) {
        double xz[2];
        for (int k = 0; k < 2; k++) {
            while (*p == ' ')
                p++;
            char *end;
            errno = 0;
            xz[k] = strtod(p, &end);
            if (end == p || errno == ERANGE || !isfinite(xz[k]))
                goto bad;
            p = end;
            while (*p == ' ')
                p++;
            if (k == 0) {
                if (*p != ',')
                    goto bad;
                p++;
            }
        }
        if (*p == ';')
            p++;
        else if (*p)
            goto bad;
        if (cnt == cap) {
            cap *= 2;
            double *nv = realloc(v, cap * 2 * sizeof *nv);
            if (!nv)
                goto bad;
            v = nv;
        }
        v[2 * cnt] = xz[0];
        v[2 * cnt + 1] = xz[1];
        cnt++;
    }
    if (!cnt)
        goto bad;
    *out = v;
    *n = cnt;
    return 0;
bad:
    free(v);
    return -1;
}

static void query_print_json(const oc_query_result *q, const double *xz, size_t n)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "t", q->t);
    cJSON *arr = cJSON_AddArrayToObject(o, "points");
    for (uint32_t i = 0; i < q->count && i < n; i++) {
        const proto_query_sample *sm = &q->samples[i];
        cJSON *p = cJSON_CreateObject();
        cJSON_AddNumberToObject(p, "x", xz[2 * i]);
        cJSON_AddNumberToObject(p, "z", xz[2 * i + 1]);
        cJSON_AddNumberToObject(p, "height", sm->height);
        double nv[3] = {sm->normal[0], sm->normal[1], sm->normal[2]};
        double vv[3] = {sm->velocity[0], sm->velocity[1], sm->velocity[2]};
        cJSON_AddItemToObject(p, "normal", cJSON_CreateDoubleArray(nv, 3));
        cJSON_AddItemToObject(p, "velocity", cJSON_CreateDoubleArray(vv, 3));
        cJSON_AddNumberToObject(p, "foam", sm->foam);
        cJSON_AddNumberToObject(p, "error_bound", sm->error_bound);
        cJSON_AddItemToArray(arr, p);
    }
    occli_print_json(o);
}

static void query_print_text(const oc_query_result *q, const double *xz, size_t n)
{
    printf("# t = %.9g s\n%12s %12s %10s %26s %26s %6s %10s\n", q->t, "x", "z", "height", "normal", "velocity",
           "foam", "error");
    for (uint32_t i = 0; i < q->count && i < n; i++) {
        const proto_query_sample *sm = &q->samples[i];
        printf("%12.4f %12.4f %10.5f  (%7.4f,%7.4f,%7.4f)  (%7.3f,%7.3f,%7.3f) %6.3f %10.3g\n", xz[2 * i],
               xz[2 * i + 1], sm->height, sm->normal[0], sm->normal[1], sm->normal[2], sm->velocity[0],
               sm->velocity[1], sm->velocity[2], sm->foam, sm->error_bound);
    }
}

int cmd_query(int argc, char **argv)
{
    const char *points = NULL;
    double t = NAN;
    int json = 0, timeout_ms = 5000;
    const occli_opt opts[] = {
        {"points", OCCLI_STRING, &points, 0, 0, "\"X1,Z1;X2,Z2;...\"  world points (required)", NULL},
        {"t", OCCLI_DOUBLE, &t, -OCEAN_TIME_MAX, OCEAN_TIME_MAX, "T  sim time to evaluate (default: the latest tick)", NULL},
        {"json", OCCLI_FLAG, &json, 0, 0, "print a JSON object", NULL},
        {"timeout", OCCLI_INT, &timeout_ms, 1, 3600000, "MS  connect / answer timeout", NULL},
    };
    const char *pos[1];
    int np = 0;
    int pr = occli_parse(argc, argv,
                         "usage: ocean-client query URL --points \"x1,z1;x2,z2\" [--t T] [--json]\n"
                         "Asks the server for height, normal, velocity, foam and an error bound at each point.",
                         opts, (int)(sizeof opts / sizeof opts[0]), pos, 1, &np);
    if (pr)
        return pr == 1 ? 0 : 2;
    if (np != 1) {
        fprintf(stderr, "ocean-client query: needs the server URL (see --help)\n");
        return 2;
    }
    if (!points) {
        fprintf(stderr, "ocean-client query: option '--points' is required\n");
        return 2;
    }
    double *xz;
    size_t n;
    if (parse_points(points, &xz, &n) != 0) {
        fprintf(stderr, "ocean-client query: option '--points': '%s' is not \"x1,z1;x2,z2;...\" of finite numbers\n",
                points);
        return 2;
    }
    oc_client *c = occli_connect("query", pos[0], NULL, timeout_ms);
    if (!c) {
        free(xz);
        return 1;
    }
    oc_query_result q;
    ocean_result r = oc_client_query(c, xz, n, !isnan(t), isnan(t) ? 0 : t, timeout_ms, &q);
    if (r != OCEAN_OK) {
        char err[512];
        oc_client_last_error(c, err, sizeof err);
        fprintf(stderr, "ocean-client query: %s\n", err[0] ? err : ocean_strerror(r));
        oc_client_destroy(c);
        free(xz);
        return 1;
    }
    if (json)
        query_print_json(&q, xz, n);
    else
        query_print_text(&q, xz, n);
    oc_query_result_free(&q);
    oc_client_destroy(c);
    free(xz);
    return 0;
}
