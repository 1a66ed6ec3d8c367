/*
 * occli.c - what the ocean-client subcommands share (occli.h): the
 * table-driven option parser, the subscription options and the requests
 * built of them, the connection, progress on a terminal and the small
 * helpers (clocks, percentiles, growable arrays).
 *
 * Threads: occli_stop is set by main.c's signal handler and read by any
 * thread.  occli_progress and occli_sub_default keep state in statics, so
 * one thread at a time calls them (the command's; load's progress thread
 * draws while the run blocks the command's thread).
 */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <cJSON.h>

#include "occli.h"
#include "ocean_time.h"

volatile sig_atomic_t occli_stop;

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

/* The value *o->target holds, as the command line would spell it; "" for
 * an option not given and without a default (NaN, NULL, a choice < 0). */
static void format_value(const occli_opt *o, char *buf, size_t len)
{
    buf[0] = 0;
    switch (o->kind) {
    case OCCLI_DOUBLE: {
        double v = *(const double *)o->target;
        if (!isnan(v))
            snprintf(buf, len, "%.15g", v);
        break;
    }
    case OCCLI_INT: snprintf(buf, len, "%d", *(const int *)o->target); break;
    case OCCLI_STRING: {
        const char *v = *(const char *const *)o->target;
        if (v)
            snprintf(buf, len, "%s", v);
        break;
    }
    case OCCLI_FLAG: snprintf(buf, len, "%d", *(const int *)o->target); break;
    case OCCLI_CHOICE: {
        int v = *(const int *)o->target;
        if (v >= 0)
            snprintf(buf, len, "%s", o->names[v]);
        break;
    }
    }
}

static void print_usage(FILE *f, const char *usage, const occli_opt *opts, int nopts, char (*defs)[64])
{
    fprintf(f, "%s\n\nOptions:\n", usage);
    for (int i = 0; i < nopts; i++) {
        const char *h = opts[i].help;
        const char *sp = strstr(h, "  ");
        char arg[64], text[512];
        /* A flag takes no argument, so its help has no "ARG  " prefix to
         * strip (its continuation lines are indented with spaces). */
        if (opts[i].kind == OCCLI_FLAG || !sp) {
            snprintf(arg, sizeof arg, "%s", opts[i].name);
            snprintf(text, sizeof text, "%s", h);
        } else {
            snprintf(arg, sizeof arg, "%s %.*s", opts[i].name, (int)(sp - h), h);
            snprintf(text, sizeof text, "%s", sp + 2);
        }
        if (opts[i].kind == OCCLI_CHOICE) {
            size_t n = strlen(text);
            for (int k = 0; opts[i].names[k] && n < sizeof text; k++)
                n += (size_t)snprintf(text + n, sizeof text - n, "%s%s", k ? " " : ": ", opts[i].names[k]);
        }
        if (opts[i].kind != OCCLI_FLAG && defs[i][0])
            fprintf(f, "  --%-18s %s (default %s)\n", arg, text, defs[i]);
        else
            fprintf(f, "  --%-18s %s\n", arg, text);
    }
    fprintf(f, "  --%-18s %s\n", "show-options", "print every option's value after parsing, and exit");
    fprintf(f, "  --%-18s %s\n", "help", "this text");
}

static const occli_opt *find_opt(const occli_opt *opts, int nopts, const char *name, size_t nl)
{
    for (int k = 0; k < nopts; k++)
        if (strlen(opts[k].name) == nl && !strncmp(opts[k].name, name, nl))
            return &opts[k];
    return NULL;
}

/* Sets an OCCLI_CHOICE target to the index of val among its names. */
static int set_choice(const char *cmd, const occli_opt *o, const char *val)
{
    int found = -1;
    for (int k = 0; o->names[k]; k++)
        if (!strcmp(o->names[k], val))
            found = k;
    if (found < 0) {
        char list[256] = "";
        size_t n = 0;
        for (int k = 0; o->names[k] && n < sizeof list; k++)
            n += (size_t)snprintf(list + n, sizeof list - n, "%s%s", k ? ", " : "", o->names[k]);
        fprintf(stderr, "ocean-client %s: option '--%s': unknown value '%s' (one of %s)\n", cmd, o->name, val,
                list);
        return 2;
    }
    *(int *)o->target = found;
    return 0;
}

/* Sets an OCCLI_DOUBLE or OCCLI_INT target: a finite number within the
 * option's range (and the time limit, for a time), whole for an int. */
static int set_number(const char *cmd, const occli_opt *o, const char *val)
{
    char *end;
    errno = 0;
    double v = strtod(val, &end);
    if (end == val || *end || errno == ERANGE || !isfinite(v)) {
        fprintf(stderr, "ocean-client %s: option '--%s': '%s' is not a number\n", cmd, o->name, val);
        return 2;
    }
    if (o->max == OCEAN_TIME_MAX && !ocean_time_ok(v)) {
        char m[256];
        ocean_time_check(v, o->name, m, sizeof m);
        fprintf(stderr, "ocean-client %s: option '--%s': %s\n", cmd, o->name, m);
        return 2;
    }
    if (v < o->min || v > o->max) {
        fprintf(stderr, "ocean-client %s: option '--%s': %s outside [%g, %g]\n", cmd, o->name, val, o->min,
                o->max);
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
    return 0;
}

/* One "--name[=value]" at argv[*i] (its value may be argv[*i + 1], which
 * then is consumed): 0 set, 2 refused (said). */
static int parse_option(int argc, char **argv, int *i, const occli_opt *opts, int nopts)
{
    const char *cmd = argv[0], *name = argv[*i] + 2;
    const char *eq = strchr(name, '=');
    size_t nl = eq ? (size_t)(eq - name) : strlen(name);
    const occli_opt *o = find_opt(opts, nopts, name, nl);
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
        return 0;
    }
    const char *val = eq ? eq + 1 : NULL;
    if (!val) {
        if (*i + 1 >= argc) {
            fprintf(stderr, "ocean-client %s: option '--%s' needs a value\n", cmd, o->name);
            return 2;
        }
        val = argv[++*i];
    }
    if (o->kind == OCCLI_STRING) {
        *(const char **)o->target = val;
        return 0;
    }
    if (o->kind == OCCLI_CHOICE)
        return set_choice(cmd, o, val);
    return set_number(cmd, o, val);
}

/* A word that is not "--name": a positional argument, or a refused
 * single-dash option or one argument too many. */
static int take_positional(const char *cmd, const char *a, const char **pos, int max_pos, int *np)
{
    if (a[0] == '-' && a[1] && strcmp(a, "-") != 0) {
        fprintf(stderr, "ocean-client %s: unknown option '%s' (see --help)\n", cmd, a);
        return 2;
    }
    if (*np >= max_pos) {
        fprintf(stderr, "ocean-client %s: unexpected argument '%s' (see --help)\n", cmd, a);
        return 2;
    }
    pos[(*np)++] = a;
    return 0;
}

static void print_options(const occli_opt *opts, int nopts)
{
    for (int i = 0; i < nopts; i++) {
        char v[512];
        format_value(&opts[i], v, sizeof v);
        printf("--%s=%s\n", opts[i].name, v);
    }
}

int occli_parse(int argc, char **argv, const char *usage, const occli_opt *opts, int nopts,
                const char **pos, int max_pos, int *npos)
{
    const char *cmd = argv[0];
    int np = 0, show = 0;
    char defs[OCCLI_MAX_OPTS][64];
    if (nopts > OCCLI_MAX_OPTS) {
        fprintf(stderr, "ocean-client %s: internal error: %d options (max %d)\n", cmd, nopts, OCCLI_MAX_OPTS);
        return 2;
    }
    /* The defaults, before any option changes a target. */
    for (int i = 0; i < nopts; i++)
        format_value(&opts[i], defs[i], sizeof defs[i]);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int r = 0;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            print_usage(stdout, usage, opts, nopts, defs);
            return 1;
        }
        if (strcmp(a, "--show-options") == 0)
            show = 1;
        else if (strncmp(a, "--", 2) != 0 || a[2] == 0)
            r = take_positional(cmd, a, pos, max_pos, &np);
        else
            r = parse_option(argc, argv, &i, opts, nopts);
        if (r)
            return r;
    }
    if (show) {
        print_options(opts, nopts);
        return 1;
    }
    if (npos)
        *npos = np;
    return 0;
}

void occli_print_json(cJSON *o)
{
    char *txt = cJSON_Print(o);
    if (txt)
        puts(txt);
    free(txt);
    cJSON_Delete(o);
}

static int progress_open;   /* a progress line is on the terminal */

void occli_progress(double done, double total, const char *fmt, ...)
{
    static int tty = -1;
    static double last;
    if (tty < 0)
        tty = isatty(STDERR_FILENO);
    if (!tty)
        return;
    int final = total > 0 && done >= total;
    double now = occli_mono();
    if (!final && progress_open && now - last < 0.1)
        return;
    last = now;
    int width = 40, fill = total > 0 ? (int)fmin(width, done * width / total) : 0;
    char detail[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(detail, sizeof detail, fmt, ap);
    va_end(ap);
    fprintf(stderr, "\r[%.*s%*s] %s\033[K", fill, "########################################", width - fill, "",
            detail);
    progress_open = 1;
    if (final)
        occli_progress_end();
    fflush(stderr);
}

void occli_progress_end(void)
{
    if (progress_open) {
        fputc('\n', stderr);
        progress_open = 0;
    }
}

const char *const occli_off_on[] = {"off", "on", NULL};

/* Names of the subscription enums, in their wire order (protocol/proto.h). */
static const char *const mesh_names[] = {"concentric", "chunked", "projected", "none"};
static const char *const policy_names[] = {"none", "seed", "antialias"};

/* The effect names as --effects spells them, in bit order (the first
 * EFFECT_NAMES_CANONICAL), then the other spellings it takes. */
static const struct { unsigned bit; const char *name; } effect_names[] = {
    {PROTO_FX_HEIGHT, "height"}, {PROTO_FX_DISPLACEMENT, "displacement"}, {PROTO_FX_NORMALS, "normals"},
    {PROTO_FX_FOAM, "foam"},     {PROTO_FX_NEAR_FIELD, "near"},           {PROTO_FX_NEAR_FIELD, "near-field"},
    {PROTO_FX_ALL, "all"}};
#define EFFECT_NAMES_CANONICAL 5

void occli_sub_default(occli_sub *s)
{
    memset(s, 0, sizeof *s);
    proto_subscribe d;
    oc_subscribe_default(&d);
    proto_camera cam;
    oc_camera_default(&cam);
    s->codec = proto_codec_name((proto_codec)d.codec);
    static char fx[96];
    fx[0] = 0;
    for (size_t i = 0; i < EFFECT_NAMES_CANONICAL; i++)
        if (d.effects & effect_names[i].bit)
            snprintf(fx + strlen(fx), sizeof fx - strlen(fx), "%s%s", fx[0] ? "," : "", effect_names[i].name);
    s->effects = fx;
    s->mesh = d.mesh_kind < 4 ? mesh_names[d.mesh_kind] : "concentric";
    s->layout = d.layout;
    s->time_interp = (d.flags & PROTO_SUB_TIME_INTERP) != 0;
    s->mesh_codec = d.mesh_codec == PROTO_MESH_CODEC_QZ ? "qz" : "f32";
    s->policy = d.cutoff_policy < 3 ? policy_names[d.cutoff_policy] : "antialias";
    s->rate = d.frame_rate_hz;
    /* The wire carries accuracy as float32; the double the library starts
     * from is the one to show. */
    s->accuracy = OC_ACCURACY_DEFAULT;
    s->tile_size = d.tile_size;
    s->levels = d.lod_levels;
    s->layers = d.layers;
    s->spacing = d.base_spacing_m;
    s->range = d.view_range_m;
    static char posbuf[96], velbuf[96];
    snprintf(posbuf, sizeof posbuf, "%g,%g,%g", cam.pos[0], cam.pos[1], cam.pos[2]);
    snprintf(velbuf, sizeof velbuf, "%g,%g,%g", (double)cam.vel[0], (double)cam.vel[1], (double)cam.vel[2]);
    s->pos = posbuf;
    s->vel = velbuf;
    s->yaw = cam.yaw_deg;
    s->pitch = cam.pitch_deg;
    s->fov = cam.fov_y_deg;
    s->timeout_ms = 5000;
}

/* --effects LIST as a PROTO_FX_* mask: 0, or 2 (said). */
static int effects_parse(const char *cmd, const char *list, unsigned *out)
{
    unsigned fx = 0;
    char buf[256];
    snprintf(buf, sizeof buf, "%s", list);
    for (char *save = NULL, *t = strtok_r(buf, ",", &save); t; t = strtok_r(NULL, ",", &save)) {
        size_t i = 0, n = sizeof effect_names / sizeof effect_names[0];
        while (i < n && strcmp(t, effect_names[i].name))
            i++;
        if (i == n) {
            fprintf(stderr, "ocean-client %s: option '--effects': unknown effect '%s'\n", cmd, t);
            return 2;
        }
        fx |= effect_names[i].bit;
    }
    if (!fx) {
        fprintf(stderr, "ocean-client %s: option '--effects': empty\n", cmd);
        return 2;
    }
    *out = fx;
    return 0;
}

/* The index of name in names[0..n), or -1. */
static int name_index(const char *name, const char *const *names, int n)
{
    int k = -1;
    for (int i = 0; i < n; i++)
        if (!strcmp(name, names[i]))
            k = i;
    return k;
}

/* CAMERA from the camera options: 0, or 2 (said). */
static int camera_build(const char *cmd, const occli_sub *s, proto_camera *cam)
{
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

int occli_sub_build(const char *cmd, const occli_sub *s, proto_subscribe *sub, proto_camera *cam)
{
    oc_subscribe_default(sub);
    proto_codec codec;
    if (proto_codec_parse(s->codec, &codec) != OCEAN_OK) {
        fprintf(stderr, "ocean-client %s: option '--codec': unknown codec '%s'\n", cmd, s->codec);
        return 2;
    }
    sub->codec = (uint8_t)codec;
    sub->layout = (uint8_t)s->layout;
    unsigned fx;
    if (effects_parse(cmd, s->effects, &fx))
        return 2;
    sub->effects = (uint8_t)fx;
    int mk = name_index(s->mesh, mesh_names, 4);
    if (mk < 0) {
        fprintf(stderr, "ocean-client %s: option '--mesh': unknown mesh kind '%s'\n", cmd, s->mesh);
        return 2;
    }
    sub->mesh_kind = (uint8_t)mk;
    if (!strcmp(s->mesh_codec, "f32"))
        sub->mesh_codec = PROTO_MESH_CODEC_F32;
    else if (!strcmp(s->mesh_codec, "qz"))
        sub->mesh_codec = PROTO_MESH_CODEC_QZ;
    else {
        fprintf(stderr, "ocean-client %s: option '--mesh-codec': unknown mesh codec '%s' (f32 or qz)\n", cmd,
                s->mesh_codec);
        return 2;
    }
    int pk = name_index(s->policy, policy_names, 3);
    if (pk < 0) {
        fprintf(stderr, "ocean-client %s: option '--cutoff-policy': unknown policy '%s'\n", cmd, s->policy);
        return 2;
    }
    sub->cutoff_policy = (uint8_t)pk;
    sub->flags = (uint8_t)((s->full_geometry ? PROTO_SUB_FULL_GEOMETRY : 0) |
                           (s->time_interp == 1 ? PROTO_SUB_TIME_INTERP : 0));
    sub->frame_rate_hz = (float)s->rate;
    sub->accuracy = (float)s->accuracy;
    sub->tile_size = (uint16_t)s->tile_size;
    sub->lod_levels = (uint8_t)s->levels;
    sub->layers = (uint8_t)s->layers;
    sub->base_spacing_m = (float)s->spacing;
    sub->view_range_m = (float)s->range;
    return camera_build(cmd, s, cam);
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
