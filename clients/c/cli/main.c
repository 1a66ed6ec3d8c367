/*
 * main.c - ocean-client: the command-line face of the client library.
 * Dispatches to the subcommands and holds the shared option parser and
 * helpers (occli.h).
 */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "occli.h"

volatile sig_atomic_t occli_stop;

static void on_signal(int sig)
{
    (void)sig;
    occli_stop = 1;
}

double occli_mono(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

double occli_wall(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void occli_sleep(double s)
{
    if (!(s > 0))
        return;
    struct timespec ts;
    ts.tv_sec = (time_t)s;
    ts.tv_nsec = (long)((s - (double)ts.tv_sec) * 1e9);
    while (nanosleep(&ts, &ts) != 0 && errno == EINTR && !occli_stop)
        ;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

double occli_percentile(double *v, size_t n, double p)
{
    if (!n)
        return NAN;
    qsort(v, n, sizeof *v, cmp_double);
    double r = p / 100.0 * (double)(n - 1);
    size_t i = (size_t)floor(r);
    if (i + 1 >= n)
        return v[n - 1];
    double f = r - (double)i;
    return v[i] + f * (v[i + 1] - v[i]);
}

int occli_vec_push(occli_vec *a, double x)
{
    if (a->n == a->cap) {
        size_t nc = a->cap ? 2 * a->cap : 1024;
        double *nv = realloc(a->v, nc * sizeof *nv);
        if (!nv)
            return -1;
        a->v = nv;
        a->cap = nc;
    }
    a->v[a->n++] = x;
    return 0;
}

void occli_vec_free(occli_vec *a)
{
    free(a->v);
    memset(a, 0, sizeof *a);
}

int occli_parse_vec(const char *s, double *out, int n)
{
    const char *p = s;
    for (int i = 0; i < n; i++) {
        char *end;
        errno = 0;
        out[i] = strtod(p, &end);
        if (end == p || errno == ERANGE || !isfinite(out[i]))
            return -1;
        p = end;
        while (*p == ' ')
            p++;
        if (i + 1 < n) {
            if (*p != ',')
                return -1;
            p++;
        }
    }
    return *p ? -1 : 0;
}

static void print_usage(FILE *f, const char *usage, const occli_opt *opts, int nopts)
{
    fprintf(f, "%s\n\nOptions:\n", usage);
    for (int i = 0; i < nopts; i++) {
        const char *h = opts[i].help;
        const char *sp = strstr(h, "  ");
        /* A flag takes no argument, so its help has no "ARG  " prefix to
         * strip (its continuation lines are indented with spaces). */
        if (opts[i].kind == OCCLI_FLAG || !sp)
            fprintf(f, "  --%-18s %s\n", opts[i].name, h);
        else {
            char arg[64];
            snprintf(arg, sizeof arg, "%s %.*s", opts[i].name, (int)(sp - h), h);
            fprintf(f, "  --%-18s %s\n", arg, sp + 2);
        }
    }
    fprintf(f, "  --%-18s %s\n", "help", "this text");
}

int occli_parse(int argc, char **argv, const char *usage, const occli_opt *opts, int nopts,
                const char **pos, int max_pos, int *npos)
{
    const char *cmd = argv[0];
    int np = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            print_usage(stdout, usage, opts, nopts);
            return 1;
        }
        if (strncmp(a, "--", 2) != 0 || a[2] == 0) {
            if (a[0] == '-' && a[1] && strcmp(a, "-") != 0) {
                fprintf(stderr, "ocean-client %s: unknown option '%s' (see --help)\n", cmd, a);
                return 2;
            }
            if (np >= max_pos) {
                fprintf(stderr, "ocean-client %s: unexpected argument '%s' (see --help)\n", cmd, a);
                return 2;
            }
            pos[np++] = a;
            continue;
        }
        const char *name = a + 2;
        const char *eq = strchr(name, '=');
        size_t nl = eq ? (size_t)(eq - name) : strlen(name);
        const occli_opt *o = NULL;
        for (int k = 0; k < nopts; k++)
            if (strlen(opts[k].name) == nl && !strncmp(opts[k].name, name, nl)) {
                o = &opts[k];
                break;
            }
        if (!o) {
            fprintf(stderr, "ocean-client %s: unknown option '--%.*s' (see --help)\n", cmd, (int)nl, name);
            return 2;
        }
        if (o->kind == OCCLI_FLAG) {
            if (eq) {
                fprintf(stderr, "ocean-client %s: option '--%s' takes no value\n", cmd, o->name);
                return 2;
            }
            *(int *)o->target = 1;
            continue;
        }
        const char *val = eq ? eq + 1 : NULL;
        if (!val) {
            if (i + 1 >= argc) {
                fprintf(stderr, "ocean-client %s: option '--%s' needs a value\n", cmd, o->name);
                return 2;
            }
            val = argv[++i];
        }
        if (o->kind == OCCLI_STRING) {
            *(const char **)o->target = val;
            continue;
        }
        char *end;
        errno = 0;
        double v = strtod(val, &end);
        if (end == val || *end || errno == ERANGE || !isfinite(v)) {
            fprintf(stderr, "ocean-client %s: option '--%s': '%s' is not a number\n", cmd, o->name, val);
            return 2;
        }
        if (v < o->min || v > o->max) {
            fprintf(stderr, "ocean-client %s: option '--%s': %s outside [%g, %g]\n", cmd, o->name, val,
                    o->min, o->max);
            return 2;
        }
        if (o->kind == OCCLI_INT) {
            if (v != floor(v)) {
                fprintf(stderr, "ocean-client %s: option '--%s': '%s' is not an integer\n", cmd, o->name, val);
                return 2;
            }
            *(int *)o->target = (int)v;
        } else {
            *(double *)o->target = v;
        }
    }
    if (npos)
        *npos = np;
    return 0;
}

void occli_sub_default(occli_sub *s)
{
    memset(s, 0, sizeof *s);
    s->codec = "qz";
    s->effects = "height,displacement,normals";
    s->mesh = "concentric";
    s->policy = "antialias";
    s->rate = 30;
    s->accuracy = PROTO_ACCURACY_DEFAULT;
    s->tile_size = 32;
    s->levels = 4;
    s->layers = 1;
    s->pos = "0,20,0";
    s->vel = "0,0,0";
    s->fov = 60;
    s->timeout_ms = 5000;
}

int occli_sub_build(const char *cmd, const occli_sub *s, proto_subscribe *sub, proto_camera *cam)
{
    oc_subscribe_default(sub);
    proto_codec codec;
    if (proto_codec_parse(s->codec, &codec) != OCEAN_OK) {
        fprintf(stderr, "ocean-client %s: option '--codec': unknown codec '%s'\n", cmd, s->codec);
        return 2;
    }
    sub->codec = (uint8_t)codec;
    unsigned fx = 0;
    char buf[256];
    snprintf(buf, sizeof buf, "%s", s->effects);
    for (char *save = NULL, *t = strtok_r(buf, ",", &save); t; t = strtok_r(NULL, ",", &save)) {
        if (!strcmp(t, "height"))
            fx |= PROTO_FX_HEIGHT;
        else if (!strcmp(t, "displacement"))
            fx |= PROTO_FX_DISPLACEMENT;
        else if (!strcmp(t, "normals"))
            fx |= PROTO_FX_NORMALS;
        else if (!strcmp(t, "foam"))
            fx |= PROTO_FX_FOAM;
        else if (!strcmp(t, "near") || !strcmp(t, "near-field"))
            fx |= PROTO_FX_NEAR_FIELD;
        else if (!strcmp(t, "all"))
            fx |= PROTO_FX_ALL;
        else {
            fprintf(stderr, "ocean-client %s: option '--effects': unknown effect '%s'\n", cmd, t);
            return 2;
        }
    }
    if (!fx) {
        fprintf(stderr, "ocean-client %s: option '--effects': empty\n", cmd);
        return 2;
    }
    sub->effects = (uint8_t)fx;
    static const char *const meshes[] = {"concentric", "chunked", "projected", "none"};
    int mk = -1;
    for (int i = 0; i < 4; i++)
        if (!strcmp(s->mesh, meshes[i]))
            mk = i;
    if (mk < 0) {
        fprintf(stderr, "ocean-client %s: option '--mesh': unknown mesh kind '%s'\n", cmd, s->mesh);
        return 2;
    }
    sub->mesh_kind = (uint8_t)mk;
    static const char *const pol[] = {"none", "seed", "antialias"};
    int pk = -1;
    for (int i = 0; i < 3; i++)
        if (!strcmp(s->policy, pol[i]))
            pk = i;
    if (pk < 0) {
        fprintf(stderr, "ocean-client %s: option '--cutoff-policy': unknown policy '%s'\n", cmd, s->policy);
        return 2;
    }
    sub->cutoff_policy = (uint8_t)pk;
    sub->frame_rate_hz = (float)s->rate;
    sub->accuracy = (float)s->accuracy;
    sub->tile_size = (uint16_t)s->tile_size;
    sub->lod_levels = (uint8_t)s->levels;
    sub->layers = (uint8_t)s->layers;
    sub->base_spacing_m = (float)s->spacing;
    sub->view_range_m = (float)s->range;
    oc_camera_default(cam);
    double v[3];
    if (occli_parse_vec(s->pos, v, 3) != 0) {
        fprintf(stderr, "ocean-client %s: option '--pos': '%s' is not X,Y,Z\n", cmd, s->pos);
        return 2;
    }
    for (int i = 0; i < 3; i++)
        cam->pos[i] = v[i];
    if (occli_parse_vec(s->vel, v, 3) != 0) {
        fprintf(stderr, "ocean-client %s: option '--vel': '%s' is not VX,VY,VZ\n", cmd, s->vel);
        return 2;
    }
    for (int i = 0; i < 3; i++)
        cam->vel[i] = (float)v[i];
    cam->yaw_deg = (float)s->yaw;
    cam->pitch_deg = (float)s->pitch;
    cam->fov_y_deg = (float)s->fov;
    return 0;
}

oc_client *occli_connect(const char *cmd, const char *url, const oc_options *base, int timeout_ms)
{
    oc_options o;
    if (base)
        o = *base;
    else
        oc_options_default(&o);
    o.url = url;
    oc_client *c = NULL;
    char err[512] = "";
    ocean_result r = oc_connect(&o, timeout_ms, &c, err, sizeof err);
    if (r != OCEAN_OK) {
        fprintf(stderr, "ocean-client %s: %s\n", cmd, err[0] ? err : ocean_strerror(r));
        return NULL;
    }
    return c;
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
        {"export", cmd_export}, {"load", cmd_load},   {"sea", cmd_sea},
        {"fidelity", cmd_fidelity},
    };
    for (size_t i = 0; i < sizeof cmds / sizeof cmds[0]; i++)
        if (!strcmp(c, cmds[i].name))
            return cmds[i].fn(argc - 1, argv + 1);
    fprintf(stderr, "ocean-client: unknown command '%s'\n", c);
    usage(stderr);
    return 2;
}
