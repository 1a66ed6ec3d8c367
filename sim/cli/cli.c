/*
 * cli.c - the one option parser behind every ocean-sim subcommand.
 *
 * Options are "--name value" or "--name=value".  The common sea-state
 * options are a table like the subcommand's own, so both are checked the
 * same way: a value that is not a number, is NaN/Inf or lies outside its
 * range is refused with the option's name and the allowed range.
 */
#include "cli.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cJSON.h>

#include "ocean_conf.h"
#include "ocean_plan.h"

double cli_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double cli_median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

int cli_parse_effects(const char *s, unsigned *out)
{
    static const struct { const char *name; unsigned bit; } names[] = {
        {"height", OCEAN_FX_HEIGHT}, {"displacement", OCEAN_FX_DISPLACEMENT},
        {"normals", OCEAN_FX_NORMALS}, {"foam", OCEAN_FX_FOAM},
        {"velocity", OCEAN_FX_VELOCITY}, {"near-field", OCEAN_FX_NEAR_FIELD},
        {"all", OCEAN_FX_ALL}};
    unsigned mask = 0;
    const char *p = s;
    while (*p) {
        size_t len = strcspn(p, ",");
        int found = 0;
        for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
            if (strlen(names[i].name) == len && strncmp(p, names[i].name, len) == 0) {
                mask |= names[i].bit;
                found = 1;
            }
        if (!found)
            return -1;
        p += len;
        if (*p == ',')
            p++;
    }
    if (!mask)
        return -1;
    *out = mask;
    return 0;
}

static int parse_number(const char *opt, const char *val, double lo, double hi, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(val, &end);
    if (end == val || *end != '\0' || errno == ERANGE) {
        fprintf(stderr, "error: --%s: '%s' is not a number\n", opt, val);
        return -1;
    }
    if (!isfinite(v)) {
        fprintf(stderr, "error: --%s: '%s' must be finite\n", opt, val);
        return -1;
    }
    if (hi == OCEAN_TIME_MAX && !ocean_time_ok(v)) {
        char m[256];
        ocean_time_check(v, opt, m, sizeof m);
        fprintf(stderr, "error: --%s\n", m);
        return -1;
    }
    if (v < lo || v > hi) {
        fprintf(stderr, "error: --%s: %s is out of range [%g, %g]\n", opt, val, lo, hi);
        return -1;
    }
    *out = v;
    return 0;
}

/* An effects mask as --effects spells it. */
static void format_effects(unsigned mask, char *buf, size_t len)
{
    static const struct { const char *name; unsigned bit; } names[] = {
        {"height", OCEAN_FX_HEIGHT}, {"displacement", OCEAN_FX_DISPLACEMENT},
        {"normals", OCEAN_FX_NORMALS}, {"foam", OCEAN_FX_FOAM},
        {"velocity", OCEAN_FX_VELOCITY}, {"near-field", OCEAN_FX_NEAR_FIELD}};
    buf[0] = '\0';
    if (mask == OCEAN_FX_ALL) {
        snprintf(buf, len, "all");
        return;
    }
    size_t n = 0;
    for (size_t i = 0; i < sizeof names / sizeof names[0] && n < len; i++)
        if (mask & names[i].bit)
            n += (size_t)snprintf(buf + n, len - n, "%s%s", n ? "," : "", names[i].name);
}

/* The value *o->target holds, as the command line spells it; "" when it
 * means "not given" (NaN, NULL, outside the option's range). */
static void format_value(const cli_opt *o, char *buf, size_t len)
{
    buf[0] = '\0';
    switch (o->kind) {
    case CLI_DOUBLE: {
        double v = *(const double *)o->target;
        if (!isnan(v) && v >= o->min && v <= o->max)
            snprintf(buf, len, "%.15g", v);
        break;
    }
    case CLI_INT: {
        int v = *(const int *)o->target;
        if (v >= o->min && v <= o->max)
            snprintf(buf, len, "%d", v);
        break;
    }
    case CLI_U64:
        snprintf(buf, len, "%llu", (unsigned long long)*(const uint64_t *)o->target);
        break;
    case CLI_STRING: {
        const char *v = *(const char *const *)o->target;
        if (v)
            snprintf(buf, len, "%s", v);
        break;
    }
    case CLI_FLAG:
        snprintf(buf, len, "%d", *(const int *)o->target);
        break;
    case CLI_CHOICE: {
        int v = *(const int *)o->target, n = 0;
        while (o->names[n])
            n++;
        if (v >= 0 && v < n)
            snprintf(buf, len, "%s", o->names[v]);
        break;
    }
    case CLI_EFFECTS:
        format_effects(*(const unsigned *)o->target, buf, len);
        break;
    }
}

static void print_opts(const cli_opt *opts, int nopts, char (*defs)[96])
{
    for (int i = 0; i < nopts; i++) {
        char text[512];
        snprintf(text, sizeof text, "%s", opts[i].help);
        if (opts[i].kind == CLI_CHOICE) {
            size_t n = strlen(text);
            for (int k = 0; opts[i].names[k] && n < sizeof text; k++)
                n += (size_t)snprintf(text + n, sizeof text - n, "%s%s", k ? "|" : ": ", opts[i].names[k]);
        }
        if (opts[i].kind != CLI_FLAG && defs[i][0])
            fprintf(stdout, "  --%-14s %s (default %s)\n", opts[i].name, text, defs[i]);
        else
            fprintf(stdout, "  --%-14s %s\n", opts[i].name, text);
    }
}

static int apply_opt(const cli_opt *o, const char *val)
{
    double v;
    switch (o->kind) {
    case CLI_DOUBLE:
        if (parse_number(o->name, val, o->min, o->max, &v))
            return -1;
        *(double *)o->target = v;
        return 0;
    case CLI_U64: {
        /* Read as an integer, never through a double: seeds past 2^53
         * would round to a neighbour's and give its sea (min and max are
         * taken as 0 and 2^64 - 1). */
        char *end;
        errno = 0;
        const char *d = val;
        while (*d == ' ')
            d++;
        unsigned long long u = *d >= '0' && *d <= '9' ? strtoull(d, &end, 10) : 0;
        if (!(*d >= '0' && *d <= '9') || *end != '\0' || errno == ERANGE) {
            fprintf(stderr, "error: --%s: '%s' is not a whole number in [0, %llu]\n", o->name, val,
                    (unsigned long long)UINT64_MAX);
            return -1;
        }
        *(uint64_t *)o->target = (uint64_t)u;
        return 0;
    }
    case CLI_INT:
        if (parse_number(o->name, val, o->min, o->max, &v))
            return -1;
        if (v != floor(v)) {
            fprintf(stderr, "error: --%s: '%s' must be a whole number\n", o->name, val);
            return -1;
        }
        *(int *)o->target = (int)v;
        return 0;
    case CLI_STRING:
        *(const char **)o->target = val;
        return 0;
    case CLI_FLAG:
        *(int *)o->target = 1;
        return 0;
    case CLI_CHOICE:
        for (int k = 0; o->names[k]; k++)
            if (strcmp(o->names[k], val) == 0) {
                *(int *)o->target = k;
                return 0;
            }
        fprintf(stderr, "error: --%s: unknown value '%s' (", o->name, val);
        for (int k = 0; o->names[k]; k++)
            fprintf(stderr, "%s%s", k ? ", " : "", o->names[k]);
        fprintf(stderr, ")\n");
        return -1;
    case CLI_EFFECTS:
        if (cli_parse_effects(val, (unsigned *)o->target)) {
            fprintf(stderr, "error: --%s: '%s' is not a list of "
                    "height,displacement,normals,foam,velocity (or all)\n", o->name, val);
            return -1;
        }
        /* The near field is the daemon's (its Gerstner set comes from the
         * server.near_field_* keys); taken here, it would be ignored in
         * silence. */
        if (*(unsigned *)o->target & OCEAN_FX_NEAR_FIELD) {
            fprintf(stderr, "error: --%s: near-field is oceand's (server.near_field_*): ocean-sim "
                    "evaluates the FFT cascades alone\n", o->name);
            return -1;
        }
        return 0;
    }
    return -1;
}

/* Finds the option named by "--name" or "--name=value" in arg. */
static const cli_opt *find_opt(const char *arg, const cli_opt *const *tabs, const int *ns, int ntabs)
{
    const char *eq = strchr(arg + 2, '=');
    size_t len = eq ? (size_t)(eq - arg - 2) : strlen(arg + 2);
    for (int t = 0; t < ntabs; t++)
        for (int k = 0; k < ns[t]; k++)
            if (strlen(tabs[t][k].name) == len && strncmp(tabs[t][k].name, arg + 2, len) == 0)
                return &tabs[t][k];
    return NULL;
}

/* What cli_parse works with beside cli_common. */
typedef struct parse_state {
    /* the common options' values that are not cli_common's own fields */
    int spectrum, spreading, beaufort, help, show;
    const char *config;
    /* names of the sea-state enums, as the config file spells them */
    const char *spectra[OCEAN_SPECTRUM_COUNT_ + 1];
    const char *spreads[OCEAN_SPREAD_COUNT_ + 1];
    /* the subcommand's table and the common one */
    const cli_opt *tabs[2];
    int ns[2];
    /* positional arguments go to pos[], at most maxpos, *npos counting */
    const char **pos;
    int *npos, maxpos;
} parse_state;

/* The common options' table into out[]; returns its length.  They write
 * straight into the parameters, so what --help shows as a default is what
 * the simulation gets. */
static int common_opts(cli_common *c, parse_state *s, cli_opt *out)
{
    ocean_params *p = &c->params;
    for (int k = 0; k <= OCEAN_SPECTRUM_COUNT_; k++)
        s->spectra[k] = k < OCEAN_SPECTRUM_COUNT_ ? ocean_spectrum_name((ocean_spectrum_kind)k) : NULL;
    for (int k = 0; k <= OCEAN_SPREAD_COUNT_; k++)
        s->spreads[k] = k < OCEAN_SPREAD_COUNT_ ? ocean_spreading_name((ocean_spreading_kind)k) : NULL;
    static const char *const plans[] = {"estimate", "measure", NULL};
    s->spectrum = (int)p->sea.spectrum;
    s->spreading = (int)p->sea.spreading;
    s->beaufort = -1;
    s->help = 0;
    s->show = 0;
    s->config = NULL;
    const cli_opt common[] = {
        {"spectrum", CLI_CHOICE, &s->spectrum, 0, 0, "NAME  wave spectrum", s->spectra},
        {"wind", CLI_DOUBLE, &p->sea.wind_u10, 0, 100, "U10   wind speed at 10 m, m/s", NULL},
        {"direction", CLI_DOUBLE, &p->sea.wind_dir_deg, -360, 360, "DEG   wind direction from +x toward +z", NULL},
        {"fetch", CLI_DOUBLE, &p->sea.fetch_m, 1, 1e7, "M     fetch for jonswap/tma", NULL},
        {"depth", CLI_DOUBLE, &p->sea.depth_m, 0.01, 12000, "M     water depth", NULL},
        {"spreading", CLI_CHOICE, &s->spreading, 0, 0, "NAME  directional spreading", s->spreads},
        {"swell", CLI_DOUBLE, &p->sea.swell, 0, 10, "X     swell parameter xi", NULL},
        {"beaufort", CLI_INT, &s->beaufort, 0, 12, "F     Beaufort force: sets the wind (overrides --wind)", NULL},
        {"size", CLI_DOUBLE, &p->patch_m, 1, 1e5, "L     largest patch size, m", NULL},
        {"n", CLI_INT, &p->n, OCEAN_MIN_N, OCEAN_MAX_N, "N     FFT resolution, power of two", NULL},
        {"cascades", CLI_INT, &p->cascades, 1, OCEAN_MAX_CASCADES, "K     cascades", NULL},
        {"cascade-ratio", CLI_DOUBLE, &p->cascade_ratio, 1.5, 100, "R     patch ratio between cascades", NULL},
        {"choppiness", CLI_DOUBLE, &p->sea.choppiness, 0, 10, "L     choppy displacement scale", NULL},
        {"seed", CLI_U64, &p->seed, 0, 0, "S     random seed, 0 .. 2^64 - 1", NULL},
        {"time", CLI_DOUBLE, &c->time, -OCEAN_TIME_MAX, OCEAN_TIME_MAX, "T     simulation time, s", NULL},
        {"effects", CLI_EFFECTS, &c->effects, 0, 0, "LIST  height,displacement,normals,foam,velocity or all", NULL},
        {"threads", CLI_INT, &p->threads, 1, 64, "T     worker threads", NULL},
        {"plan", CLI_CHOICE, &p->plan_measure, 0, 0, "MODE  FFTW planning (estimate is bit-reproducible)", plans},
        {"config", CLI_STRING, &s->config, 0, 0, "FILE  read sea.* and ocean.* keys from a config file first", NULL},
        {"json", CLI_FLAG, &c->json, 0, 0, "      machine-readable output", NULL},
        {"show-options", CLI_FLAG, &s->show, 0, 0, "      print every option's value after parsing, and exit", NULL},
        {"help", CLI_FLAG, &s->help, 0, 0, "      this help", NULL},
    };
    _Static_assert(sizeof common / sizeof common[0] <= CLI_MAX_OPTS, "common options fit");
    memcpy(out, common, sizeof common);
    return (int)(sizeof common / sizeof common[0]);
}

/* The value of option o, named by arg = argv[*i]: after its '=' or the
 * next argument (then *i advances); NULL for a flag.  Returns 0, or 2
 * with the reason printed. */
static int option_value(const cli_opt *o, const char *arg, int argc, char **argv, int *i,
                        const char **val)
{
    const char *eq = strchr(arg + 2, '=');
    *val = NULL;
    if (o->kind == CLI_FLAG) {
        if (eq) {
            fprintf(stderr, "error: --%s takes no value\n", o->name);
            return 2;
        }
    } else if (eq) {
        *val = eq + 1;
    } else if (*i + 1 < argc) {
        *val = argv[++*i];
    } else {
        fprintf(stderr, "error: --%s needs a value\n", o->name);
        return 2;
    }
    return 0;
}

/* One pass over the arguments: pass 0 checks every option and applies
 * --config and --help, pass 1 applies the others.  Returns 0, or 2 with
 * the reason printed. */
static int scan_args(int argc, char **argv, int pass, parse_state *s)
{
    if (s->npos)
        *s->npos = 0;
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (strncmp(arg, "--", 2) != 0) {
            if (s->npos && *s->npos < s->maxpos) {
                s->pos[(*s->npos)++] = arg;
                continue;
            }
            fprintf(stderr, "error: unexpected argument '%s' (see %s --help)\n", arg, argv[0]);
            return 2;
        }
        const cli_opt *o = find_opt(arg, s->tabs, s->ns, 2);
        if (!o) {
            const char *eq = strchr(arg + 2, '=');
            fprintf(stderr, "error: unknown option '--%.*s' (see %s --help)\n",
                    eq ? (int)(eq - arg - 2) : (int)strlen(arg + 2), arg + 2, argv[0]);
            return 2;
        }
        const char *val;
        if (option_value(o, arg, argc, argv, &i, &val))
            return 2;
        int first = o->target == (void *)&s->config || o->target == (void *)&s->help;
        if (pass == 0 && first && apply_opt(o, val))
            return 2;
        if (pass == 1 && !first && apply_opt(o, val))
            return 2;
    }
    return 0;
}

static void print_help(const char *usage, const char *cmd, const parse_state *s,
                       char (*defs)[96])
{
    printf("usage: ocean-sim %s\n\n", usage);
    if (s->ns[0]) {
        printf("options of %s:\n", cmd);
        print_opts(s->tabs[0], s->ns[0], defs);
    }
    printf(s->ns[1] > 2 ? "sea state and simulation options:\n" : "and:\n");
    print_opts(s->tabs[1], s->ns[1], defs + s->ns[0]);
}

/* --config FILE under the options; the enums' options read what it set.
 * Returns 0, or 2 with the reason printed. */
static int load_config(cli_common *c, parse_state *s)
{
    char err[512];
    if (ocean_conf_load(s->config, &c->params, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "error: %s\n", err);
        return 2;
    }
    c->config = s->config;
    s->spectrum = (int)c->params.sea.spectrum;
    s->spreading = (int)c->params.sea.spreading;
    return 0;
}

static void show_options(const parse_state *s)
{
    for (int t = 0; t < 2; t++)
        for (int k = 0; k < s->ns[t]; k++) {
            const cli_opt *o = &s->tabs[t][k];
            if (o->target == (const void *)&s->show || o->target == (const void *)&s->help)
                continue;
            char v[512];
            format_value(o, v, sizeof v);
            printf("--%s=%s\n", o->name, v);
        }
}

int cli_parse(int argc, char **argv, const char *usage,
              const cli_opt *opts, int nopts, cli_common *c,
              const char **pos, int *npos)
{
    cli_common own;
    int own_only = !c;   /* a command that takes no sea: its table alone */
    if (own_only) c = &own;
    memset(c, 0, sizeof *c);
    ocean_params *p = &c->params;
    ocean_params_default(p);
    c->effects = OCEAN_FX_ALL;
    c->time = 0.0;
    parse_state s;
    cli_opt common[CLI_MAX_OPTS];
    int ncommon = common_opts(c, &s, common);
    s.tabs[0] = opts;
    /* the last two common options are --show-options and --help */
    s.tabs[1] = own_only ? common + ncommon - 2 : common;
    s.ns[0] = nopts;
    s.ns[1] = own_only ? 2 : ncommon;
    if (nopts + ncommon > CLI_MAX_OPTS) {
        fprintf(stderr, "error: internal: %d options (max %d)\n", nopts + ncommon, CLI_MAX_OPTS);
        return 2;
    }
    /* The defaults, before a config file or an option changes them. */
    char defs[CLI_MAX_OPTS][96];
    for (int t = 0, d = 0; t < 2; t++)
        for (int k = 0; k < s.ns[t]; k++)
            format_value(&s.tabs[t][k], defs[d++], sizeof defs[0]);
    s.pos = pos;
    s.npos = npos;
    s.maxpos = npos ? *npos : 0;
    if (npos)
        *npos = 0;

    /* Two passes: the first checks every option and finds --config and
     * --help, the second applies the options over the config file. */
    for (int pass = 0; pass < 2; pass++) {
        if (scan_args(argc, argv, pass, &s))
            return 2;
        if (pass == 0 && s.help) {
            print_help(usage, argv[0], &s, defs);
            return 1;
        }
        if (pass == 0 && s.config && load_config(c, &s))
            return 2;
    }
    p->sea.spectrum = (ocean_spectrum_kind)s.spectrum;
    p->sea.spreading = (ocean_spreading_kind)s.spreading;
    if (s.beaufort >= 0)
        ocean_beaufort_wind(s.beaufort, &p->sea.wind_u10);
    if (s.show) {
        show_options(&s);
        return 1;
    }
    char err[512];
    if (!own_only && ocean_params_validate(p, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "error: %s\n", err);
        return 2;
    }
    return 0;
}

int cli_make_ocean(const cli_common *c, ocean **o, ocean_frame **f)
{
    char err[512];
    *f = NULL;
    ocean_result r = ocean_create(&c->params, o, err, sizeof err);
    if (r != OCEAN_OK) {
        fprintf(stderr, "error: cannot create the ocean: %s (%s)\n", err, ocean_strerror(r));
        return 1;
    }
    /* The scene plan's warnings (its refusals stopped ocean_create). */
    ocean_plan plan;
    ocean_plan_init(&plan);
    ocean_plan_params(&c->params, &plan);
    ocean_plan_ocean(*o, NULL, &plan);
    ocean_plan_print(&plan, stderr, "ocean-sim: scene plan");
    if ((r = ocean_frame_create(*o, f)) != OCEAN_OK) {
        fprintf(stderr, "error: cannot allocate the frame: %s\n", ocean_strerror(r));
        ocean_destroy(*o);
        *o = NULL;
        return 1;
    }
    return 0;
}

void cli_print_json(cJSON *o)
{
    char *s = cJSON_Print(o);
    if (s)
        puts(s);
    free(s);
    cJSON_Delete(o);
}

char *cli_read_file(const char *path)
{
    FILE *fp = strcmp(path, "-") == 0 ? stdin : fopen(path, "rb");
    if (!fp) {
        fprintf(stderr, "error: cannot open %s: %s\n", path, strerror(errno));
        return NULL;
    }
    size_t cap = 1 << 16, len = 0;
    char *buf = malloc(cap);
    while (buf) {
        size_t got = fread(buf + len, 1, cap - len - 1, fp);
        len += got;
        if (got == 0)
            break;
        if (len + 1 == cap) {
            char *g = realloc(buf, cap * 2);
            if (!g) {
                free(buf);
                buf = NULL;
                break;
            }
            buf = g;
            cap *= 2;
        }
    }
    if (fp != stdin)
        fclose(fp);
    if (buf)
        buf[len] = '\0';
    return buf;
}
