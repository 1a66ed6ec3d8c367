/*
 * ship.c - example: a box hull floated on the shared sea.
 *
 * 64 hull points (8 x 8 under a 20 m x 8 m box, draft 1.5 m) are asked for
 * the sea height in one batch query per step; heave, pitch and roll are
 * integrated over 60 s of sim time (clients/c/oc_ship.h has the physics)
 * and printed twice a second, then a summary with the heave spectrum's
 * peak period beside the sea's dominant period.
 *
 *   ship ws://127.0.0.1:8740/ [options]     against a running oceand
 *   ship --offline [options]                on a local sim/ ocean, no daemon
 *
 * The offline run needs the simulator library beside the client library:
 *   cc ship.c $(pkg-config --cflags --libs oceansim) -lm
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <oceand/oc_ship.h>
#include <oceand/oc_ship_offline.h>
#include <oceand/ocean.h>
#include <oceand/oceanclient.h>

static void usage(FILE *f)
{
    fprintf(f,
            "usage: ship URL [options]        float a box hull on a running oceand\n"
            "       ship --offline [options]  float it on a local ocean (no daemon)\n"
            "\n"
            "Options:\n"
            "  --seconds S    sim seconds to integrate (60)\n"
            "  --dt S         step (0.05)\n"
            "  --speed V      forward speed, m/s (0)\n"
            "  --heading DEG  heading from +x toward +z (0); 90 puts the waves on the beam for\n"
            "                 a wind blowing along +x\n"
            "  --every S      print interval (0.5)\n"
            "  --wind U       offline: wind speed at 10 m, m/s (10)\n"
            "  --seed N       offline: sea seed (1)\n"
            "  --quiet        only the summary\n"
            "  --help\n");
}

static int num(const char *opt, const char *v, double lo, double hi, double *out)
{
    char *end;
    errno = 0;
    double d = v ? strtod(v, &end) : NAN;
    if (!v || end == v || *end || errno || !isfinite(d) || d < lo || d > hi) {
        fprintf(stderr, "ship: option '%s': '%s' is not a number in [%g, %g]\n", opt, v ? v : "", lo, hi);
        return -1;
    }
    *out = d;
    return 0;
}

static void summary(const oc_ship_trace *tr, double tp, int diverged)
{
    double sh = 0, hmax = 0, pmax = 0, rmax = 0;
    for (size_t i = 0; i < tr->n; i++) {
        sh += tr->heave[i] * tr->heave[i];
        hmax = fmax(hmax, fabs(tr->heave[i]));
        pmax = fmax(pmax, fabs(tr->pitch[i]));
        rmax = fmax(rmax, fabs(tr->roll[i]));
    }
    double peak = oc_ship_peak_period(tr->heave, tr->n, tr->dt, 1.0, 30.0);
    printf("# %zu steps of %.3f s: heave rms %.3f m max %.3f m, pitch max %.2f deg, roll max %.2f deg\n", tr->n,
           tr->dt, tr->n ? sqrt(sh / tr->n) : 0, hmax, pmax * 180 / M_PI, rmax * 180 / M_PI);
    printf("# heave spectrum peak period %.2f s; sea dominant period Tp %.2f s%s\n", peak, tp,
           diverged ? "; DIVERGED" : "");
}

static void print_rows(const oc_ship_trace *tr, double every)
{
    printf("%9s %9s %9s %9s\n", "t_s", "heave_m", "pitch_deg", "roll_deg");
    double next = tr->n ? tr->t[0] : 0;
    for (size_t i = 0; i < tr->n; i++)
        if (tr->t[i] >= next - 1e-9) {
            printf("%9.3f %9.4f %9.4f %9.4f\n", tr->t[i], tr->heave[i], tr->pitch[i] * 180 / M_PI,
                   tr->roll[i] * 180 / M_PI);
            next += every;
        }
}

static int run_offline(const oc_ship_params *sp, double seconds, double dt, double every, double wind,
                       double seed, int quiet)
{
    ocean_params op;
    ocean_params_default(&op);
    op.sea.wind_u10 = wind;
    op.seed = (uint64_t)seed;
    op.n = 128;
    op.patch_m = 1600;
    op.threads = 1;
    ocean *o;
    char msg[256];
    if (ocean_create(&op, &o, msg, sizeof msg) != OCEAN_OK) {
        fprintf(stderr, "ship: %s\n", msg);
        return 1;
    }
    ocean_spectrum_stats ss;
    ocean_get_spectrum_stats(o, &ss);
    oc_ship_trace tr;
    ocean_result r = oc_ship_run_offline(sp, o, 0.0, seconds, dt, &tr, msg, sizeof msg);
    ocean_destroy(o);
    if (r != OCEAN_OK && r != OCEAN_EDIVERGED) {
        fprintf(stderr, "ship: %s\n", msg);
        return 1;
    }
    if (!quiet)
        print_rows(&tr, every);
    printf("# offline sea: wind %.1f m/s, Hs %.2f m, Tp %.2f s\n", wind, ss.hs, ss.tp);
    summary(&tr, ss.tp, r == OCEAN_EDIVERGED);
    oc_ship_trace_free(&tr);
    return r == OCEAN_OK ? 0 : 1;
}

static int run_daemon(const char *url, const oc_ship_params *sp, double seconds, double dt, double every,
                      int quiet)
{
    oc_options o;
    oc_options_default(&o);
    o.url = url;
    oc_client *c;
    char err[512];
    if (oc_connect(&o, 5000, &c, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "ship: %s\n", err);
        return 1;
    }
    proto_hello hello;
    oc_client_hello(c, &hello);
    double t0 = oc_client_sim_time(c);
    oc_ship *s;
    if (oc_ship_create(sp, t0, &s, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "ship: %s\n", err);
        oc_client_destroy(c);
        return 1;
    }
    size_t n = oc_ship_point_count(s), steps = (size_t)ceil(seconds / dt);
    double *xz = malloc(2 * n * sizeof *xz), *h = malloc(n * sizeof *h);
    oc_ship_trace tr = {0};
    tr.dt = dt;
    tr.t = malloc((steps + 1) * sizeof(double));
    tr.heave = malloc((steps + 1) * sizeof(double));
    tr.pitch = malloc((steps + 1) * sizeof(double));
    tr.roll = malloc((steps + 1) * sizeof(double));
    int rc = 0, diverged = 0;
    if (!xz || !h || !tr.t || !tr.heave || !tr.pitch || !tr.roll)
        rc = 1;
    for (size_t i = 0; !rc && i <= steps; i++) {
        oc_ship_state st;
        oc_ship_get_state(s, &st);
        tr.t[i] = st.t - t0;
        tr.heave[i] = st.heave;
        tr.pitch[i] = st.pitch;
        tr.roll[i] = st.roll;
        tr.n = i + 1;
        if (i == steps)
            break;
        oc_ship_points(s, xz);
        oc_query_result q;
        ocean_result r = oc_client_query(c, xz, n, 1, st.t, 10000, &q);
        if (r != OCEAN_OK) {
            oc_client_last_error(c, err, sizeof err);
            fprintf(stderr, "ship: query at t = %.3f failed: %s\n", st.t, err[0] ? err : ocean_strerror(r));
            rc = 1;
            break;
        }
        for (size_t j = 0; j < n; j++)
            h[j] = j < q.count ? q.samples[j].height : NAN;
        oc_query_result_free(&q);
        r = oc_ship_step(s, h, dt);
        if (r == OCEAN_EDIVERGED) {
            diverged = 1;
            rc = 1;
        } else if (r != OCEAN_OK) {
            fprintf(stderr, "ship: step failed: %s\n", ocean_strerror(r));
            rc = 1;
        }
    }
    if (tr.n) {
        if (!quiet)
            print_rows(&tr, every);
        printf("# server %s, sea: wind %.1f m/s, Hs %.2f m, Tp %.2f s\n", hello.server_version, hello.sea.wind_u10,
               hello.sea.hs, hello.sea.tp);
        summary(&tr, hello.sea.tp, diverged);
    }
    oc_ship_trace_free(&tr);
    free(xz);
    free(h);
    oc_ship_destroy(s);
    oc_client_destroy(c);
    return rc;
}

int main(int argc, char **argv)
{
    oc_ship_params sp;
    oc_ship_params_default(&sp);
    double seconds = 60, dt = 0.05, every = 0.5, wind = 10, seed = 1;
    int offline = 0, quiet = 0, sea_given = 0;
    const char *url = NULL;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        int bad = 0;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--offline")) {
            offline = 1;
        } else if (!strcmp(a, "--quiet")) {
            quiet = 1;
        } else if (!strcmp(a, "--seconds")) {
            bad = num(a, v, 0.1, 1e5, &seconds), i++;
        } else if (!strcmp(a, "--dt")) {
            bad = num(a, v, 0.001, 0.5, &dt), i++;
        } else if (!strcmp(a, "--speed")) {
            bad = num(a, v, -100, 100, &sp.speed), i++;
        } else if (!strcmp(a, "--heading")) {
            bad = num(a, v, -3600, 3600, &sp.heading_deg), i++;
        } else if (!strcmp(a, "--every")) {
            bad = num(a, v, 0.001, 1e5, &every), i++;
        } else if (!strcmp(a, "--wind")) {
            bad = num(a, v, 0, 60, &wind), i++, sea_given = 1;
        } else if (!strcmp(a, "--seed")) {
            bad = num(a, v, 0, 4294967295.0, &seed), i++, sea_given = 1;
        } else if (a[0] == '-') {
            fprintf(stderr, "ship: unknown option '%s' (see --help)\n", a);
            return 2;
        } else if (!url) {
            url = a;
        } else {
            fprintf(stderr, "ship: unexpected argument '%s'\n", a);
            return 2;
        }
        if (bad)
            return 2;
    }
    if (!offline && !url) {
        usage(stderr);
        return 2;
    }
    if (offline && url) {
        fprintf(stderr, "ship: give either a URL or --offline, not both\n");
        return 2;
    }
    /* Online the sea is the daemon's, shared by every client: a wind or
     * seed given here would be silently ignored. */
    if (url && sea_given) {
        fprintf(stderr, "ship: --wind and --seed choose the sea of --offline only; the daemon's sea is "
                        "shared by every client (change it with: ocean-client sea %s --set --token T --wind U)\n",
                url);
        return 2;
    }
    return offline ? run_offline(&sp, seconds, dt, every, wind, seed, quiet)
                   : run_daemon(url, &sp, seconds, dt, every, quiet);
}
