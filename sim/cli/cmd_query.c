/*
 * cmd_query.c - `ocean-sim query`: height, normal, velocity, foam and the
 * error bound at world points, from the same fields clients receive.
 */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cJSON.h>

#include "cli.h"
#include "cli_entities.h"
#include "geo.h"
#include "query.h"

/* Parses "x1,z1;x2,z2;..." (or the lines of a file, "x,z" or "x z" each;
 * '#' starts a comment) into a growing array.  Returns the count or -1
 * after printing what is wrong and where. */
static long parse_points(const char *text, const char *origin, int by_line, double **out)
{
    size_t cap = 64, n = 0;
    double *xz = malloc(sizeof(double) * 2 * cap);
    if (!xz)
        return -1;
    const char *p = text;
    int item = 1;
    while (*p) {
        size_t len = strcspn(p, by_line ? "\n" : ";");
        char buf[256];
        if (len >= sizeof buf) {
            fprintf(stderr, "error: %s %s %d is too long\n", origin, by_line ? "line" : "point", item);
            free(xz);
            return -1;
        }
        memcpy(buf, p, len);
        buf[len] = '\0';
        char *hash = strchr(buf, '#');
        if (hash)
            *hash = '\0';
        char *s = buf;
        while (*s == ' ' || *s == '\t' || *s == '\r')
            s++;
        if (*s) {
            char *end;
            errno = 0;
            double x = strtod(s, &end);
            char *q = end;
            while (*q == ' ' || *q == '\t')
                q++;
            if (*q == ',')
                q++;
            double z = strtod(q, &end);
            while (*end == ' ' || *end == '\t' || *end == '\r')
                end++;
            if (end == q || *end != '\0' || errno == ERANGE || !isfinite(x) || !isfinite(z)) {
                fprintf(stderr, "error: %s %s %d: '%s' is not a finite 'x,z' pair\n", origin,
                        by_line ? "line" : "point", item, buf);
                free(xz);
                return -1;
            }
            if (n == cap) {
                double *g = realloc(xz, sizeof(double) * 4 * cap);
                if (!g) {
                    free(xz);
                    return -1;
                }
                xz = g;
                cap *= 2;
            }
            xz[2 * n] = x;
            xz[2 * n + 1] = z;
            n++;
        }
        p += len;
        if (*p)
            p++;
        item++;
    }
    *out = xz;
    return (long)n;
}

/* What the command line sets beyond the common options. */
typedef struct query_args {
    double t, cutoff;
    const char *points, *file, *geo, *origin;
    const char *entities; /* --entities FILE: ships whose wakes the answers add */
    double *latlon;     /* --geo: the points as given, lat, lon pairs */
} query_args;

/* Parses and checks the arguments: exactly one source of points, and one
 * time (--t or --time).  Returns cli_parse's 0, 1 (help printed) or 2
 * (error printed). */
static int query_args_parse(int argc, char **argv, query_args *a, cli_common *c)
{
    /* t NAN: --t not given; the common --time (every other command's) then
     * says the time, which query once ignored in silence.  cutoff
     * INFINITY: outside --cutoff's range, "not given". */
    *a = (query_args){.t = NAN, .cutoff = INFINITY, .origin = "0,0"};
    const cli_opt opts[] = {
        {"t", CLI_DOUBLE, &a->t, -OCEAN_TIME_MAX, OCEAN_TIME_MAX, "T     simulation time, s (as --time; default 0)", NULL},
        {"points", CLI_STRING, &a->points, 0, 0, "LIST  \"x1,z1;x2,z2;...\" world points, m", NULL},
        {"points-file", CLI_STRING, &a->file, 0, 0, "FILE  one 'x,z' per line ('-': stdin)", NULL},
        {"geo", CLI_STRING, &a->geo, 0, 0, "LIST  \"lat1,lon1;...\" points in degrees (WGS 84), on the plane about --origin", NULL},
        {"origin", CLI_STRING, &a->origin, 0, 0, "LAT,LON  where x = z = 0 for --geo (oceand's server.geo_origin; 0,0)", NULL},
        {"cutoff", CLI_DOUBLE, &a->cutoff, 0, 1e6, "K     Butterworth cutoff, rad/m (not given: unfiltered)", NULL},
        {"entities", CLI_STRING, &a->entities, 0, 0, "FILE  ships whose wakes the answers add: a JSON array of "
         "entries as `ocean-client entity` prints them, several a track, optional \"from\" ('-': stdin)", NULL},
    };
    int r = cli_parse(argc, argv, "query [--t T] --points \"x,z;...\" | --points-file F | --geo \"lat,lon;...\" "
                      "[--origin LAT,LON] [--cutoff K] [--entities FILE] [--json]", opts, 7, c, NULL, NULL);
    if (r)
        return r;
    if (isnan(a->t)) {
        a->t = c->time;
    } else if (c->time != 0.0 && c->time != a->t) {
        fprintf(stderr, "error: query: --t %.17g and --time %.17g disagree: give one\n", a->t, c->time);
        return 2;
    }
    if ((a->points != NULL) + (a->file != NULL) + (a->geo != NULL) != 1) {
        fprintf(stderr, "error: query needs exactly one of --points, --points-file or --geo\n");
        return 2;
    }
    return 0;
}

/* --geo's n (lat, lon) pairs in xz onto the ocean's plane about --origin
 * (sim/geo.h), keeping the pairs in a->latlon.  0, or -1 with the reason
 * printed. */
static int query_points_map(query_args *a, double *xz, long n)
{
    ocean_geo *g;
    char why[200];
    double lat0, lon0;
    ocean_result r = ocean_geo_origin_parse(a->origin, &lat0, &lon0, why, sizeof why);
    if (r == OCEAN_OK) r = ocean_geo_create(lat0, lon0, &g, why, sizeof why);
    if (r != OCEAN_OK) {
        fprintf(stderr, "error: --origin: %s\n", why);
        return -1;
    }
    a->latlon = malloc(sizeof(double) * 2 * (size_t)n);
    for (long i = 0; a->latlon && i < n && r == OCEAN_OK; i++) {
        a->latlon[2 * i] = xz[2 * i];
        a->latlon[2 * i + 1] = xz[2 * i + 1];
        r = ocean_geo_to_plane(g, xz[2 * i], xz[2 * i + 1], &xz[2 * i], &xz[2 * i + 1]);
        if (r != OCEAN_OK)
            fprintf(stderr, "error: --geo point %ld (%.9g, %.9g): latitude in [-90, 90] and longitude in "
                    "[-180, 180] degrees, not the origin's antipode\n", i + 1, a->latlon[2 * i], a->latlon[2 * i + 1]);
    }
    ocean_geo_destroy(g);
    if (!a->latlon) fprintf(stderr, "error: out of memory\n");
    return a->latlon && r == OCEAN_OK ? 0 : -1;
}

/* The points of --points, --points-file or --geo (mapped onto the plane)
 * into *xz.  Returns their count (at least 1), or -1 with the reason
 * printed. */
static long query_points_read(query_args *a, double **xz)
{
    long n;
    *xz = NULL;
    if (a->points || a->geo) {
        n = parse_points(a->points ? a->points : a->geo, a->points ? "--points" : "--geo", 0, xz);
    } else {
        char *text = cli_read_file(a->file);
        if (!text)
            return -1;
        n = parse_points(text, a->file, 1, xz);
        free(text);
    }
    if (n < 0)
        return -1;
    if (n == 0 || (a->geo && query_points_map(a, *xz, n))) {
        if (n == 0) fprintf(stderr, "error: no points given\n");
        free(*xz);
        *xz = NULL;
        return -1;
    }
    return n;
}

/* Evaluates the fields queries read at a->t and answers the n points into
 * res; *ms_eval and *ms_query get the times.  Returns 0, or 2 with the
 * reason printed. */
static int query_answer(ocean *o, ocean_frame *f, const query_args *a, const double *xz, long n,
                        ocean_query_result *res, double *ms_eval, double *ms_query)
{
    ocean_request req;
    ocean_request_all(&req, OCEAN_QUERY_EFFECTS);
    req.cutoff_k = a->cutoff;
    double t0 = cli_now_ms();
    ocean_result er = ocean_evaluate(o, a->t, &req, f);
    double t1 = cli_now_ms();
    size_t bad = 0;
    ocean_result qr = er == OCEAN_OK ? ocean_query_points(f, NULL, NULL, a->t, xz, (size_t)n, NULL, res, &bad) : er;
    double t2 = cli_now_ms();
    *ms_eval = t1 - t0;
    *ms_query = t2 - t1;
    if (qr == OCEAN_OK)
        return 0;
    /* the library refuses what it cannot answer (a point beyond |x|, |z|
     * <= 1e12 m, where a double no longer resolves the waves) rather than
     * print zeros for it */
    if (er != OCEAN_OK)
        fprintf(stderr, "error: evaluation at t = %.9g failed: %s\n", a->t, ocean_strerror(er));
    else
        fprintf(stderr, "error: point %zu (%g, %g) refused: %s (world points within |x|, |z| <= 1e12 m)\n",
                bad + 1, xz[2 * bad], xz[2 * bad + 1], ocean_strerror(qr));
    return 2;
}

static void query_print_json(const query_args *a, const double *xz, long n,
                             const ocean_query_result *res, double ms_eval, double ms_query)
{
    cJSON *j = cJSON_CreateObject(), *arr = cJSON_AddArrayToObject(j, "points");
    cJSON_AddNumberToObject(j, "t", a->t);
    cJSON_AddNumberToObject(j, "cutoff_k", isinf(a->cutoff) ? -1.0 : a->cutoff);
    cJSON_AddNumberToObject(j, "evaluate_ms", ms_eval);
    cJSON_AddNumberToObject(j, "query_ms", ms_query);
    for (long i = 0; i < n; i++) {
        cJSON *p = cJSON_CreateObject();
        cJSON_AddNumberToObject(p, "x", xz[2 * i]);
        cJSON_AddNumberToObject(p, "z", xz[2 * i + 1]);
        if (a->latlon) {
            cJSON_AddNumberToObject(p, "lat", a->latlon[2 * i]);
            cJSON_AddNumberToObject(p, "lon", a->latlon[2 * i + 1]);
        }
        cJSON_AddNumberToObject(p, "height", res[i].height);
        cJSON_AddItemToObject(p, "normal", cJSON_CreateDoubleArray(res[i].normal, 3));
        cJSON_AddItemToObject(p, "velocity", cJSON_CreateDoubleArray(res[i].velocity, 3));
        cJSON_AddNumberToObject(p, "foam", res[i].foam);
        cJSON_AddNumberToObject(p, "error", res[i].error);
        cJSON_AddBoolToObject(p, "folded", res[i].folded);
        cJSON_AddItemToArray(arr, p);
    }
    cli_print_json(j);
}

static void query_print_csv(const double *xz, long n, const ocean_query_result *res)
{
    printf("x,z,height,nx,ny,nz,vx,vy,vz,foam,error,folded\n");
    for (long i = 0; i < n; i++)
        printf("%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.4f,%.3g,%d\n", xz[2 * i],
               xz[2 * i + 1], res[i].height, res[i].normal[0], res[i].normal[1],
               res[i].normal[2], res[i].velocity[0], res[i].velocity[1], res[i].velocity[2],
               res[i].foam, res[i].error, res[i].folded);
}

int cmd_query(int argc, char **argv)
{
    query_args a;
    cli_common c;
    int r = query_args_parse(argc, argv, &a, &c);
    if (r)
        return r == 1 ? 0 : 2;
    double *xz;
    long n = query_points_read(&a, &xz);
    if (n < 0) {
        free(a.latlon);
        return 2;
    }
    ocean_entities *ships = NULL;
    if (a.entities && cli_entities_load(a.entities, &ships)) {
        free(xz);
        free(a.latlon);
        return 2;
    }
    ocean *o;
    ocean_frame *f;
    if (cli_make_ocean(&c, &o, &f)) {
        ocean_entities_destroy(ships);
        free(xz);
        free(a.latlon);
        return 1;
    }
    int status = 0;
    ocean_query_result *res = malloc(sizeof *res * (size_t)n);
    double ms_eval, ms_query;
    if (!res) {
        fprintf(stderr, "error: out of memory\n");
        status = 1;
    } else if ((status = query_answer(o, f, &a, xz, n, res, &ms_eval, &ms_query)) == 0 &&
               !(ships && (status = cli_wakes_apply(ships, a.t, ocean_get_params(o)->sea.depth_m, xz, (size_t)n,
                                                    res)))) {
        if (c.json)
            query_print_json(&a, xz, n, res, ms_eval, ms_query);
        else
            query_print_csv(xz, n, res);
    }
    free(res);
    free(xz);
    free(a.latlon);
    ocean_entities_destroy(ships);
    ocean_frame_destroy(f);
    ocean_destroy(o);
    return status;
}
