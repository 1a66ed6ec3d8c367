/*
 * ocean_conf.c - the sea.*, ocean.* and scene.* configuration tables and the
 * loaders built on them.
 *
 * The ranges here are the ones ocean_params_validate enforces, so a value
 * the table accepts is refused later only by a check that spans fields;
 * the table exists to give that refusal a file and a line.  Defaults are
 * written as file text and must equal ocean_params_default (a test
 * compares them field by field).
 */
#include "ocean_conf.h"

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SEA(f) offsetof(ocean_params, sea.f)
#define PAR(f) offsetof(ocean_params, f)
#define SCN(f) offsetof(ocean_scene, f)

/* conf stores CONF_ENUM values as int. */
_Static_assert(sizeof(ocean_spectrum_kind) == sizeof(int), "enum size");
_Static_assert(sizeof(ocean_spreading_kind) == sizeof(int), "enum size");

/* Keys that share this group exclude each other within one source. */
enum { GROUP_WIND = 1 };

static const conf_name spectrum_names[] = {
    {"phillips", OCEAN_SPECTRUM_PHILLIPS},
    {"pierson-moskowitz", OCEAN_SPECTRUM_PM},
    {"jonswap", OCEAN_SPECTRUM_JONSWAP},
    {"tma", OCEAN_SPECTRUM_TMA},
    {"pm", OCEAN_SPECTRUM_PM}, /* the short name ocean_spectrum_parse takes */
    {NULL, 0}};

static const conf_name spreading_names[] = {
    {"tessendorf", OCEAN_SPREAD_TESSENDORF},
    {"mitsuyasu", OCEAN_SPREAD_MITSUYASU},
    {"hasselmann", OCEAN_SPREAD_HASSELMANN},
    {"donelan-banner", OCEAN_SPREAD_DONELAN_BANNER},
    {NULL, 0}};

static const conf_name plan_names[] = {{"estimate", OCEAN_PLAN_ESTIMATE},
                                       {"measure", OCEAN_PLAN_MEASURE},
                                       {"wisdom", OCEAN_PLAN_WISDOM},
                                       {NULL, 0}};

static const conf_name effect_names[] = {
    {"height", OCEAN_FX_HEIGHT},
    {"displacement", OCEAN_FX_DISPLACEMENT},
    {"normals", OCEAN_FX_NORMALS},
    {"foam", OCEAN_FX_FOAM},
    {"near-field", OCEAN_FX_NEAR_FIELD},
    {NULL, 0}};

/* sea.beaufort: not stored; the force sets the wind it stands for. */
static ocean_result beaufort_hook(void *target, const conf_entry *e, const void *value,
                                  char *msg, size_t msglen)
{
    ocean_params *p = target;
    int force = *(const int *)value;
    double u10;
    if (ocean_beaufort_wind(force, &u10) != OCEAN_OK) {
        snprintf(msg, msglen, "%s: no wind for Beaufort force %d", e->name, force);
        return OCEAN_EINVAL;
    }
    p->sea.wind_u10 = u10;
    return OCEAN_OK;
}

static ocean_result pow2_hook(void *target, const conf_entry *e, const void *value,
                              char *msg, size_t msglen)
{
    (void)target;
    int n = *(const int *)value;
    if (n <= 0 || (n & (n - 1)) != 0) {
        snprintf(msg, msglen, "%s: must be a power of two (8, 16, ..., 2048)", e->name);
        return OCEAN_EINVAL;
    }
    return OCEAN_OK;
}

static ocean_result scene_name_hook(void *target, const conf_entry *e, const void *value,
                                    char *msg, size_t msglen)
{
    (void)target;
    const char *s = value;
    bool ok = *s != '\0';
    for (; *s && ok; s++)
        ok = (*s >= 'a' && *s <= 'z') || (*s >= '0' && *s <= '9') || *s == '-' || *s == '_';
    if (!ok) {
        snprintf(msg, msglen, "%s: a scene name is 1-%d characters of a-z, 0-9, '-', '_'",
                 e->name, OCEAN_SCENE_NAME_MAX - 1);
        return OCEAN_EFORMAT;
    }
    return OCEAN_OK;
}

static ocean_result camera_hint_hook(void *target, const conf_entry *e, const void *value,
                                     char *msg, size_t msglen)
{
    (void)target;
    double v[5];
    const char *s = value;
    if (*s && ocean_conf_camera_hint_parse(s, v) != OCEAN_OK) {
        snprintf(msg, msglen, "%s: expected x,y,z[,heading[,pitch]] (finite numbers, m and degrees)",
                 e->name);
        return OCEAN_EFORMAT;
    }
    return OCEAN_OK;
}

static const conf_entry ocean_entries[] = {
    {.name = "sea.spectrum", .type = CONF_ENUM, .offset = SEA(spectrum),
     .def = "pierson-moskowitz", .names = spectrum_names,
     .help = "Wave spectrum. phillips: Tessendorf's Phillips spectrum (uses sea.phillips_a "
             "and sea.small_wave); pierson-moskowitz: fully developed sea; jonswap: fetch-limited "
             "sea (uses sea.fetch); tma: JONSWAP with the shallow-water factor (uses sea.depth)."},
    {.name = "sea.spreading", .type = CONF_ENUM, .offset = SEA(spreading),
     .def = "mitsuyasu", .names = spreading_names,
     .help = "Directional spreading of wave energy around the wind direction: tessendorf "
             "(cos^2, downwind half only), mitsuyasu and hasselmann (cos-2s with their s(w)), "
             "donelan-banner (sech^2)."},
    {.name = "sea.wind", .type = CONF_DOUBLE, .offset = SEA(wind_u10), .min = 0, .max = 100,
     .def = "10", .unit = "m/s", .group = GROUP_WIND,
     .help = "Wind speed U10 (10 m above the sea). Give this or sea.beaufort, not both; "
             "across files and --set the later one wins."},
    {.name = "sea.beaufort", .type = CONF_INT, .min = 0, .max = 12, .def = NULL,
     .flags = CONF_F_NOSTORE, .group = GROUP_WIND, .hook = beaufort_hook,
     .help = "Beaufort force; sets sea.wind to the force's representative U10 (midpoint of "
             "the Met Office band; 12 gives 35 m/s). Optional; excludes sea.wind in the same file."},
    {.name = "sea.direction", .type = CONF_DOUBLE, .offset = SEA(wind_dir_deg), .min = -360,
     .max = 360, .def = "0", .unit = "degrees",
     .help = "Direction the wind blows toward, measured from +x toward +z."},
    {.name = "sea.fetch", .type = CONF_DOUBLE, .offset = SEA(fetch_m), .min = 1, .max = 1e7,
     .def = "100000", .unit = "m",
     .help = "Fetch: distance over which the wind has blown (jonswap and tma); the sea "
             "grows no more past full development, g F / U10^2 = 1.07e4 (109 km at 10 m/s)."},
    {.name = "sea.depth", .type = CONF_DOUBLE, .offset = SEA(depth_m), .min = 0.01,
     .max = 12000, .def = "4000", .unit = "m",
     .help = "Water depth; enters the dispersion relation and the tma spectrum."},
    {.name = "sea.swell", .type = CONF_DOUBLE, .offset = SEA(swell), .min = 0, .max = 10,
     .def = "0",
     .help = "Swell parameter xi: narrows the spreading (s += 16 tanh(wp/w) xi^2; the "
             "mitsuyasu and hasselmann spreadings only); 0 is a pure wind sea."},
    {.name = "sea.phillips_a", .type = CONF_DOUBLE, .offset = SEA(phillips_a), .min = 0,
     .max = 1, .def = "0.00405",
     .help = "Phillips constant A (phillips spectrum only)."},
    {.name = "sea.small_wave", .type = CONF_DOUBLE, .offset = SEA(small_wave_m), .min = 0,
     .max = 100, .def = "0", .unit = "m",
     .help = "Phillips small-wave suppression length l: damps waves shorter than about l "
             "(phillips spectrum only); 0 is off."},
    {.name = "sea.choppiness", .type = CONF_DOUBLE, .offset = SEA(choppiness), .min = 0,
     .max = 10, .def = "1",
     .help = "Choppiness lambda: scale of the horizontal (choppy) displacement; 0 gives "
             "rounded crests and no foam (the wind sets the whitecap coverage, the displacement's "
             "convergence places it), "
             "above about 1.5 crests fold; between 0 and 0.001 refused."},
    {.name = "sea.whitecaps", .type = CONF_BOOL, .offset = SEA(whitecaps), .def = "on",
     .help = "Whitecaps where the waves break, at the wind's coverage (Monahan); off: none "
             "(foam 0 in every tile and answer; a CIGI host's Maritime Surface Conditions "
             "Control sets it)."},
    {.name = "ocean.seed", .type = CONF_U64, .offset = PAR(seed), .min = 0,
     .max = 18446744073709551616.0, .def = "1",
     .help = "Random seed of the wave amplitudes; the same seed and sea state give the same "
             "ocean everywhere. Decimal or 0x hex."},
    {.name = "ocean.n", .type = CONF_INT, .offset = PAR(n), .min = OCEAN_MIN_N,
     .max = OCEAN_MAX_N, .def = "256", .hook = pow2_hook,
     .help = "FFT grid per cascade (n x n), a power of two. Cost grows as n^2 log n."},
    {.name = "ocean.cascades", .type = CONF_INT, .offset = PAR(cascades), .min = 1,
     .max = OCEAN_MAX_CASCADES, .def = "1",
     .help = "Number of cascades (nested patch sizes, each carrying its own band of wave "
             "numbers)."},
    {.name = "ocean.patch", .type = CONF_DOUBLE, .offset = PAR(patch_m), .min = 1, .max = 1e5,
     .def = "1000", .unit = "m",
     .help = "Size of the largest (first) cascade's periodic patch."},
    {.name = "ocean.cascade_ratio", .type = CONF_DOUBLE, .offset = PAR(cascade_ratio),
     .min = 1.5, .max = 100, .def = "4.3",
     .help = "Each cascade's patch is the previous one divided by this; a non-integer ratio "
             "keeps the cascades from tiling in step."},
    {.name = "ocean.k_max", .type = CONF_DOUBLE, .offset = PAR(k_max), .min = 1e-6,
     .max = INFINITY, .def = "inf", .unit = "rad/m", .flags = CONF_F_INF_OK,
     .help = "Waves with |k| >= k_max are left to the Gerstner near field; inf keeps the "
             "finest cascade's full band."},
    {.name = "ocean.threads", .type = CONF_INT, .offset = PAR(threads), .min = 1, .max = 64,
     .def = "2",
     .help = "Worker threads for FFTW and the spectrum stage."},
    {.name = "ocean.drop_gain", .type = CONF_DOUBLE, .offset = PAR(drop_gain), .min = 1e-6,
     .max = 0.70710678118654757, .def = "0.5",
     .help = "A filtered evaluation leaves out every wave whose low-pass gain is below this, "
             "so a low cutoff runs on a smaller FFT grid; 0.7071 drops the whole band above "
             "the cutoff, 0.0156 keeps the filter's tail to 1/64. The dropped waves count in "
             "e_error."},
    {.name = "ocean.plan", .type = CONF_ENUM, .offset = PAR(plan_measure), .def = "estimate",
     .names = plan_names,
     .help = "FFTW planning: estimate starts at once and every process plans alike; measure "
             "times candidate plans at start-up (seconds to minutes) for faster transforms, but "
             "two daemons may then pick different plans and differ in the last bits; wisdom "
             "runs the timed plans recorded in ocean.wisdom, so every replica sharing that file "
             "agrees bit for bit (a transform the file lacks is an error)."},
    {.name = "ocean.wisdom", .type = CONF_STRING, .offset = PAR(wisdom),
     .size = OCEAN_WISDOM_PATH_MAX, .def = "",
     .help = "FFTW wisdom file for ocean.plan = wisdom, written by `ocean-sim wisdom --out FILE` "
             "for the same N, ocean.threads, FFTW build and CPU; replicas that must agree bit "
             "for bit share one file."},
};

static const conf_table ocean_table = {
    .name = "ocean",
    .title = "sea state and simulation (sea.*, ocean.*)",
    .entries = ocean_entries,
    .count = sizeof ocean_entries / sizeof ocean_entries[0],
    .target_size = sizeof(ocean_params),
};

static const conf_entry scene_entries[] = {
    {.name = "scene.name", .type = CONF_STRING, .offset = SCN(name),
     .size = OCEAN_SCENE_NAME_MAX, .flags = CONF_F_REQUIRED, .hook = scene_name_hook,
     .help = "Name clients use to pick the scene: a-z, 0-9, '-', '_'."},
    {.name = "scene.description", .type = CONF_STRING, .offset = SCN(description),
     .size = OCEAN_SCENE_DESC_MAX, .def = "",
     .help = "One line for people: what the scene is for."},
    {.name = "scene.effects", .type = CONF_FLAGS, .offset = SCN(effects), .min = 1,
     .names = effect_names, .flags = CONF_F_REQUIRED,
     .help = "Effects the scene needs; the daemon computes only these (and of them only what "
             "live subscribers ask for). near-field is the Gerstner detail around each camera."},
    {.name = "scene.camera_hint", .type = CONF_STRING, .offset = SCN(camera_hint),
     .size = OCEAN_SCENE_HINT_MAX, .def = "", .hook = camera_hint_hook,
     .help = "Suggested starting camera for viewers, x,y,z[,heading[,pitch]] in metres and "
             "degrees (y up); empty for none."},
};

static const conf_table scene_table = {
    .name = "scene",
    .title = "scene (scene.*)",
    .entries = scene_entries,
    .count = sizeof scene_entries / sizeof scene_entries[0],
    .target_size = sizeof(ocean_scene),
};

const conf_table *ocean_conf_table(void) { return &ocean_table; }
const conf_table *ocean_conf_scene_table(void) { return &scene_table; }

/* Prefixes "name: " to a whole-parameter validation message. */
static ocean_result validate_into(const char *name, const ocean_params *p, char *err, size_t errlen)
{
    char msg[256];
    ocean_result r = ocean_params_validate(p, msg, sizeof msg);
    if (r != OCEAN_OK && err && errlen) snprintf(err, errlen, "%s: %s", name, msg);
    return r;
}

static const char *const skip_for_sim[] = {"server", "scene", NULL};

/* path != NULL: read the file; else parse text. */
static ocean_result load_params(const char *path, const char *name, const char *text, size_t len,
                                ocean_params *p, char *err, size_t errlen)
{
    if (!p) return OCEAN_EINVAL;
    ocean_params tmp;
    ocean_params_default(&tmp);
    const conf_table *tables[] = {&ocean_table};
    void *targets[] = {&tmp};
    conf_set set = {tables, targets, 1};
    conf_load_opts opts = {0, skip_for_sim};
    ocean_result r = path ? conf_load_file(path, &set, &opts, err, errlen)
                          : conf_load_string(name, text, len, &set, &opts, err, errlen);
    if (r == OCEAN_OK) r = validate_into(path ? path : name, &tmp, err, errlen);
    if (r == OCEAN_OK) *p = tmp;
    return r;
}

ocean_result ocean_conf_load(const char *path, ocean_params *p, char *err, size_t errlen)
{
    if (!path) {
        if (err && errlen) snprintf(err, errlen, "(config): no file name given");
        return OCEAN_EINVAL;
    }
    return load_params(path, NULL, NULL, 0, p, err, errlen);
}

ocean_result ocean_conf_load_string(const char *name, const char *text, size_t len,
                                    ocean_params *p, char *err, size_t errlen)
{
    return load_params(NULL, name ? name : "(config)", text, len, p, err, errlen);
}

ocean_result ocean_conf_apply(const char *keyvalue, ocean_params *p, char *err, size_t errlen)
{
    if (!p) return OCEAN_EINVAL;
    ocean_params tmp = *p;
    const conf_table *tables[] = {&ocean_table};
    void *targets[] = {&tmp};
    conf_set set = {tables, targets, 1};
    ocean_result r = conf_apply(keyvalue, &set, err, errlen);
    if (r == OCEAN_OK) r = validate_into("--set", &tmp, err, errlen);
    if (r == OCEAN_OK) *p = tmp;
    return r;
}

static ocean_result load_scene(const char *path, const char *name, const char *text, size_t len,
                               const ocean_params *base, ocean_scene *out, char *err,
                               size_t errlen)
{
    if (!base || !out) return OCEAN_EINVAL;
    ocean_scene *tmp = calloc(1, sizeof *tmp);
    if (!tmp) {
        if (err && errlen) snprintf(err, errlen, "%s: out of memory", path ? path : name);
        return OCEAN_ENOMEM;
    }
    tmp->params = *base;
    const conf_table *tables[] = {&scene_table, &ocean_table};
    void *targets[] = {tmp, &tmp->params};
    conf_set set = {tables, targets, 2};
    /* Only the scene table's defaults: sea and ocean keys start from base. */
    conf_set scene_only = {tables, targets, 1};
    conf_load_opts opts = {CONF_NO_DEFAULTS, NULL};
    ocean_result r = conf_defaults(&scene_only, err, errlen);
    if (r == OCEAN_OK)
        r = path ? conf_load_file(path, &set, &opts, err, errlen)
                 : conf_load_string(name, text, len, &set, &opts, err, errlen);
    if (r == OCEAN_OK) r = validate_into(path ? path : name, &tmp->params, err, errlen);
    if (r == OCEAN_OK) *out = *tmp;
    free(tmp);
    return r;
}

void ocean_conf_scene_path(const char *dir, const char *scene, char *out, size_t len)
{
    size_t n = strlen(scene);
    if (strchr(scene, '/') || (n > 5 && strcmp(scene + n - 5, ".conf") == 0))
        snprintf(out, len, "%s", scene);
    else
        snprintf(out, len, "%s/%s.conf", dir, scene);
}

ocean_result ocean_conf_scene_load(const char *path, const ocean_params *base,
                                   ocean_scene *out, char *err, size_t errlen)
{
    if (!path) {
        if (err && errlen) snprintf(err, errlen, "(scene): no file name given");
        return OCEAN_EINVAL;
    }
    return load_scene(path, NULL, NULL, 0, base, out, err, errlen);
}

ocean_result ocean_conf_scene_load_string(const char *name, const char *text, size_t len,
                                          const ocean_params *base, ocean_scene *out,
                                          char *err, size_t errlen)
{
    return load_scene(NULL, name ? name : "(scene)", text, len, base, out, err, errlen);
}

ocean_result ocean_conf_camera_hint_parse(const char *hint, double v[5])
{
    double tmp[5] = {0, 0, 0, 0, 0};
    int count = 0;
    const char *p = hint;
    if (!hint || !v) return OCEAN_EINVAL;
    for (;;) {
        while (*p == ' ' || *p == '\t') p++;
        /* Decimal numbers only (strtod would take nan, inf, hex). */
        const char *q = p;
        while (*q && strchr("0123456789+-.eE", *q)) q++;
        if (q == p || count == 5) return OCEAN_EINVAL;
        char num[64];
        size_t n = (size_t)(q - p);
        if (n >= sizeof num) return OCEAN_EINVAL;
        memcpy(num, p, n);
        num[n] = '\0';
        char *end;
        double x = strtod(num, &end);
        if (*end || !isfinite(x)) return OCEAN_EINVAL;
        tmp[count++] = x;
        p = q;
        while (*p == ' ' || *p == '\t') p++;
        if (*p == '\0') break;
        if (*p != ',') return OCEAN_EINVAL;
        p++;
    }
    if (count < 3) return OCEAN_EINVAL;
    memcpy(v, tmp, sizeof tmp);
    return OCEAN_OK;
}
