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
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

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

/* Common options write into these, then are copied into params. */
typedef struct common_raw {
    const char *spectrum, *spreading, *effects, *plan;
    double wind, direction, fetch, depth, swell, size, choppiness, time, ratio;
    double seed;
    int beaufort, n, cascades, threads;
} common_raw;

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

static void print_opts(const cli_opt *opts, int nopts)
{
    for (int i = 0; i < nopts; i++)
        fprintf(stdout, "  --%-14s %s\n", opts[i].name, opts[i].help);
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
    }
    return -1;
}

int cli_parse(int argc, char **argv, const char *usage,
              const cli_opt *opts, int nopts, cli_common *c,
              const char **pos, int *npos)
{
    memset(c, 0, sizeof *c);
    ocean_params_default(&c->params);
    c->effects = OCEAN_FX_ALL;

    common_raw raw = {NULL, NULL, NULL, NULL, NAN, NAN, NAN, NAN, NAN, NAN, NAN, 0.0,
                      NAN, NAN, -1, -1, -1, -1};
    const char *config = NULL;
    int help = 0;
    const cli_opt common[] = {
        {"spectrum", CLI_STRING, &raw.spectrum, 0, 0,
         "NAME  phillips|pierson-moskowitz|jonswap|tma (default pierson-moskowitz)"},
        {"wind", CLI_DOUBLE, &raw.wind, 0, 100, "U10   wind speed at 10 m, m/s (default 10)"},
        {"direction", CLI_DOUBLE, &raw.direction, -360, 360, "DEG   wind direction from +x toward +z"},
        {"fetch", CLI_DOUBLE, &raw.fetch, 1, 1e7, "M     fetch for jonswap/tma (default 100000)"},
        {"depth", CLI_DOUBLE, &raw.depth, 0.01, 12000, "M     water depth (default 4000)"},
        {"spreading", CLI_STRING, &raw.spreading, 0, 0,
         "NAME  tessendorf|mitsuyasu|hasselmann|donelan-banner (default mitsuyasu)"},
        {"swell", CLI_DOUBLE, &raw.swell, 0, 10, "X     swell parameter xi (default 0)"},
        {"beaufort", CLI_INT, &raw.beaufort, 0, 12, "F     Beaufort force: sets the wind (overrides --wind)"},
        {"size", CLI_DOUBLE, &raw.size, 1, 1e5, "L     largest patch size, m (default 1000)"},
        {"n", CLI_INT, &raw.n, OCEAN_MIN_N, OCEAN_MAX_N, "N     FFT resolution, power of two (default 256)"},
        {"cascades", CLI_INT, &raw.cascades, 1, OCEAN_MAX_CASCADES, "K     cascades 1..4 (default 1)"},
        {"cascade-ratio", CLI_DOUBLE, &raw.ratio, 1.5, 100, "R     patch ratio between cascades (default 4.3)"},
        {"choppiness", CLI_DOUBLE, &raw.choppiness, 0, 10, "L     choppy displacement scale (default 1)"},
        {"seed", CLI_DOUBLE, &raw.seed, 0, 9007199254740992.0, "S     random seed (default 1)"},
        {"time", CLI_DOUBLE, &raw.time, -OCEAN_TIME_MAX, OCEAN_TIME_MAX, "T     simulation time, s (default 0)"},
        {"effects", CLI_STRING, &raw.effects, 0, 0, "LIST  height,displacement,normals,foam (default all)"},
        {"threads", CLI_INT, &raw.threads, 1, 64, "T     worker threads (default 2)"},
        {"plan", CLI_STRING, &raw.plan, 0, 0, "MODE  FFTW planning: estimate (bit-reproducible) | measure"},
        {"config", CLI_STRING, &config, 0, 0, "FILE  read sea.* and ocean.* keys from a config file first"},
        {"json", CLI_FLAG, &c->json, 0, 0, "      machine-readable output"},
        {"help", CLI_FLAG, &help, 0, 0, "      this help"},
    };
    int ncommon = (int)(sizeof common / sizeof common[0]);
    int maxpos = npos ? *npos : 0;
    if (npos)
        *npos = 0;

    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (strncmp(arg, "--", 2) != 0) {
            if (npos && *npos < maxpos) {
                pos[(*npos)++] = arg;
                continue;
            }
            fprintf(stderr, "error: unexpected argument '%s' (see %s --help)\n", arg, argv[0]);
            return 2;
        }
        char name[64];
        const char *eq = strchr(arg + 2, '=');
        size_t len = eq ? (size_t)(eq - arg - 2) : strlen(arg + 2);
        if (len >= sizeof name) {
            fprintf(stderr, "error: unknown option '%s'\n", arg);
            return 2;
        }
        memcpy(name, arg + 2, len);
        name[len] = '\0';
        const cli_opt *o = NULL;
        for (int k = 0; k < nopts && !o; k++)
            if (strcmp(opts[k].name, name) == 0)
                o = &opts[k];
        for (int k = 0; k < ncommon && !o; k++)
            if (strcmp(common[k].name, name) == 0)
                o = &common[k];
        if (!o) {
            fprintf(stderr, "error: unknown option '--%s' (see %s --help)\n", name, argv[0]);
            return 2;
        }
        const char *val = NULL;
        if (o->kind == CLI_FLAG) {
            if (eq) {
                fprintf(stderr, "error: --%s takes no value\n", name);
                return 2;
            }
        } else if (eq) {
            val = eq + 1;
        } else if (i + 1 < argc) {
            val = argv[++i];
        } else {
            fprintf(stderr, "error: --%s needs a value\n", name);
            return 2;
        }
        if (apply_opt(o, val))
            return 2;
    }
    if (help) {
        printf("usage: ocean-sim %s\n\n", usage);
        if (nopts) {
            printf("options of %s:\n", argv[0]);
            print_opts(opts, nopts);
        }
        printf("sea state and simulation options:\n");
        print_opts(common, ncommon);
        return 1;
    }

    ocean_params *p = &c->params;
    char err[512];
    if (config) {
        if (ocean_conf_load(config, p, err, sizeof err) != OCEAN_OK) {
            fprintf(stderr, "error: %s\n", err);
            return 2;
        }
        c->config = config;
    }
    if (raw.spectrum && ocean_spectrum_parse(raw.spectrum, &p->sea.spectrum) != OCEAN_OK) {
        fprintf(stderr, "error: --spectrum: unknown spectrum '%s' "
                "(phillips, pierson-moskowitz, jonswap, tma)\n", raw.spectrum);
        return 2;
    }
    if (raw.spreading && ocean_spreading_parse(raw.spreading, &p->sea.spreading) != OCEAN_OK) {
        fprintf(stderr, "error: --spreading: unknown spreading '%s' "
                "(tessendorf, mitsuyasu, hasselmann, donelan-banner)\n", raw.spreading);
        return 2;
    }
    if (raw.plan) {
        if (strcmp(raw.plan, "estimate") == 0)
            p->plan_measure = 0;
        else if (strcmp(raw.plan, "measure") == 0)
            p->plan_measure = 1;
        else {
            fprintf(stderr, "error: --plan: '%s' is not estimate or measure\n", raw.plan);
            return 2;
        }
    }
    if (raw.effects && cli_parse_effects(raw.effects, &c->effects)) {
        fprintf(stderr, "error: --effects: '%s' is not a list of "
                "height,displacement,normals,foam\n", raw.effects);
        return 2;
    }
    if (!isnan(raw.wind)) p->sea.wind_u10 = raw.wind;
    if (raw.beaufort >= 0) ocean_beaufort_wind(raw.beaufort, &p->sea.wind_u10);
    if (!isnan(raw.direction)) p->sea.wind_dir_deg = raw.direction;
    if (!isnan(raw.fetch)) p->sea.fetch_m = raw.fetch;
    if (!isnan(raw.depth)) p->sea.depth_m = raw.depth;
    if (!isnan(raw.swell)) p->sea.swell = raw.swell;
    if (!isnan(raw.choppiness)) p->sea.choppiness = raw.choppiness;
    if (!isnan(raw.size)) p->patch_m = raw.size;
    if (!isnan(raw.ratio)) p->cascade_ratio = raw.ratio;
    if (!isnan(raw.seed)) {
        if (raw.seed != floor(raw.seed)) {
            fprintf(stderr, "error: --seed: %g must be a whole number\n", raw.seed);
            return 2;
        }
        p->seed = (uint64_t)raw.seed;
    }
    if (raw.n >= 0) p->n = raw.n;
    if (raw.cascades >= 0) p->cascades = raw.cascades;
    if (raw.threads >= 0) p->threads = raw.threads;
    c->time = raw.time;
    if (ocean_params_validate(p, err, sizeof err) != OCEAN_OK) {
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
