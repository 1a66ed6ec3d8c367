/*
 * cmd_sea.c - `ocean-client sea`: the sea state in force, shown, or with
 * the admin token changed for every client from a sim time on.
 */
#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include <cJSON.h>

#include "conf.h"
#include "occli.h"
#include "ocean_conf.h"
#include "ocean_time.h"
#include "spectrum.h"

static cJSON *sea_json(const proto_sea *s, double eff)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "effective_time", eff);
    /* Names, as --spectrum and --spreading take them. */
    /* An id this build does not know (a newer server) stays a number. */
    const char *sn = s->spectrum < OCEAN_SPECTRUM_COUNT_ ? ocean_spectrum_name((ocean_spectrum_kind)s->spectrum) : NULL;
    const char *pn = s->spreading < OCEAN_SPREAD_COUNT_ ? ocean_spreading_name((ocean_spreading_kind)s->spreading) : NULL;
    if (sn)
        cJSON_AddStringToObject(o, "spectrum", sn);
    else
        cJSON_AddNumberToObject(o, "spectrum", s->spectrum);
    if (pn)
        cJSON_AddStringToObject(o, "spreading", pn);
    else
        cJSON_AddNumberToObject(o, "spreading", s->spreading);
    /* the seed's every digit: a double would round seeds past 2^53 */
    char seed[24];
    snprintf(seed, sizeof seed, "%llu", (unsigned long long)s->seed);
    cJSON_AddRawToObject(o, "seed", seed);
    cJSON_AddNumberToObject(o, "wind_u10", s->wind_u10);
    cJSON_AddNumberToObject(o, "wind_dir_deg", s->wind_dir_deg);
    cJSON_AddNumberToObject(o, "fetch_m", s->fetch_m);
    cJSON_AddNumberToObject(o, "depth_m", s->depth_m);
    cJSON_AddNumberToObject(o, "swell", s->swell);
    cJSON_AddNumberToObject(o, "phillips_a", s->phillips_a);
    cJSON_AddNumberToObject(o, "small_wave_m", s->small_wave_m);
    cJSON_AddNumberToObject(o, "choppiness", s->choppiness);
    cJSON_AddBoolToObject(o, "whitecaps", !(s->flags & PROTO_SEA_NO_WHITECAPS));
    cJSON_AddNumberToObject(o, "hs", s->hs);
    cJSON_AddNumberToObject(o, "tp", s->tp);
    return o;
}

/* The range the daemon's config table gives sea key `key` (sim/ocean_conf.c):
 * one source, so this tool never refuses what oceand accepts or sends what
 * it refuses. */
static void sea_range(const char *key, double *lo, double *hi)
{
    const conf_table *t[] = {ocean_conf_table()};
    void *tg[] = {NULL};
    conf_set set = {t, tg, 1};
    const conf_entry *e = conf_find(&set, key, NULL);
    if (e) {
        *lo = e->min;
        *hi = e->max;
    }
}

/* The sea state's numeric fields --set changes: each option's range is
 * its config key's. */
static const struct sea_field {
    const char *opt, *key, *help;
    size_t offset;            /* in proto_sea */
} sea_fields[] = {
    {"wind", "sea.wind", "U  wind speed at 10 m, m/s", offsetof(proto_sea, wind_u10)},
    {"wind-dir", "sea.direction", "DEG  wind direction", offsetof(proto_sea, wind_dir_deg)},
    {"fetch", "sea.fetch", "M  fetch", offsetof(proto_sea, fetch_m)},
    {"depth", "sea.depth", "M  water depth", offsetof(proto_sea, depth_m)},
    {"swell", "sea.swell", "S  swell", offsetof(proto_sea, swell)},
    {"choppiness", "sea.choppiness", "L  choppiness", offsetof(proto_sea, choppiness)},
    {"phillips-a", "sea.phillips_a", "A  Phillips constant", offsetof(proto_sea, phillips_a)},
    {"small-wave", "sea.small_wave", "M  small-wave suppression length", offsetof(proto_sea, small_wave_m)},
};
#define SEA_FIELDS (sizeof sea_fields / sizeof sea_fields[0])

/* What `sea` was asked; NaN, -1 or NULL: not given. */
typedef struct sea_opts {
    int set, timeout_ms, spectrum, spreading, whitecaps;
    const char *token, *seed_s, *url;
    double at;
    double field[SEA_FIELDS];   /* sea_fields' values */
    unsigned long long seed;    /* seed_s read */
} sea_opts;

/* Parses the options into *P (defaults first): 0 go on, 1 help printed, 2
 * refused (said). */
static int sea_parse(int argc, char **argv, sea_opts *P)
{
    /* Spectrum and spreading by name, in sim/spectrum.h's order (the wire
     * carries the index). */
    const char *spectra[OCEAN_SPECTRUM_COUNT_ + 1] = {NULL}, *spreads[OCEAN_SPREAD_COUNT_ + 1] = {NULL};
    for (int k = 0; k < OCEAN_SPECTRUM_COUNT_; k++)
        spectra[k] = ocean_spectrum_name((ocean_spectrum_kind)k);
    for (int k = 0; k < OCEAN_SPREAD_COUNT_; k++)
        spreads[k] = ocean_spreading_name((ocean_spreading_kind)k);
    static const char *const on_off[] = {"off", "on", NULL};
    occli_opt opts[SEA_FIELDS + 8] = {
        {"set", OCCLI_FLAG, &P->set, 0, 0, "send SEA_STATE SET (needs --token)", NULL},
        {"token", OCCLI_STRING, &P->token, 0, 0, "TOKEN  the admin token from the server's config", NULL},
        {"at", OCCLI_DOUBLE, &P->at, -OCEAN_TIME_MAX, OCEAN_TIME_MAX, "T  sim time the change takes effect (not given: now)", NULL},
    };
    int n = 3;
    for (size_t i = 0; i < SEA_FIELDS; i++, n++) {
        opts[n] = (occli_opt){sea_fields[i].opt, OCCLI_DOUBLE, &P->field[i], 0, 0, sea_fields[i].help, NULL};
        sea_range(sea_fields[i].key, &opts[n].min, &opts[n].max);
    }
    opts[n++] = (occli_opt){"spectrum", OCCLI_CHOICE, &P->spectrum, 0, 0, "NAME  spectrum", spectra};
    opts[n++] = (occli_opt){"spreading", OCCLI_CHOICE, &P->spreading, 0, 0, "NAME  directional spreading", spreads};
    opts[n++] = (occli_opt){"whitecaps", OCCLI_CHOICE, &P->whitecaps, 0, 0, "on|off  whitecaps where waves break",
                            on_off};
    opts[n++] = (occli_opt){"seed", OCCLI_STRING, &P->seed_s, 0, 0, "N  random seed, 0 .. 2^64 - 1", NULL};
    opts[n++] = (occli_opt){"timeout", OCCLI_INT, &P->timeout_ms, 1, 3600000, "MS  connect / answer timeout", NULL};
    const char *pos[1];
    int np = 0;
    int pr = occli_parse(argc, argv,
                         "usage: ocean-client sea URL [--set --token T [--at T] [--wind U] ...]\n"
                         "Prints the sea state in force (JSON).  With --set, changes the given fields and asks\n"
                         "the server to apply them for every client at sim time --at.",
                         opts, n, pos, 1, &np);
    if (pr)
        return pr;
    if (np != 1) {
        fprintf(stderr, "ocean-client sea: needs the server URL (see --help)\n");
        return 2;
    }
    P->url = pos[0];
    return 0;
}

/* The first option given that changes the sea state, or NULL. */
static const char *sea_change_given(const sea_opts *P)
{
    for (size_t i = 0; i < SEA_FIELDS; i++)
        if (!isnan(P->field[i]))
            return sea_fields[i].opt;
    return P->spectrum >= 0 ? "spectrum" : P->spreading >= 0 ? "spreading" : P->whitecaps >= 0 ? "whitecaps"
           : P->seed_s ? "seed" : NULL;
}

/* Refuses what would be ignored or cannot be sent, and reads the seed:
 * 0, or 2 (said). */
static int sea_check(sea_opts *P)
{
    if (P->set && !P->token) {
        fprintf(stderr, "ocean-client sea: option '--set' needs '--token'\n");
        return 2;
    }
    const char *change = sea_change_given(P);
    /* A change asked without --set would be ignored: say so instead. */
    if (!P->set) {
        const char *given = change ? change : !isnan(P->at) ? "at" : P->token ? "token" : NULL;
        if (given) {
            fprintf(stderr, "ocean-client sea: option '--%s' changes the sea state only with '--set' "
                    "(and '--token'); without --set the command only prints the state in force\n", given);
            return 2;
        }
    }
    if (P->set && !change) {
        fprintf(stderr, "ocean-client sea: '--set' with nothing to change: give one of --wind, "
                "--wind-dir, --fetch, --depth, --swell, --choppiness, --phillips-a, --small-wave, "
                "--spectrum, --spreading, --seed\n");
        return 2;
    }
    /* read as an integer, never through a double (seeds past 2^53) */
    const char *s = P->seed_s;
    if (s) {
        char *end;
        errno = 0;
        P->seed = *s >= '0' && *s <= '9' ? strtoull(s, &end, 10) : 0;
        if (!(*s >= '0' && *s <= '9') || *end || errno == ERANGE) {
            fprintf(stderr, "ocean-client sea: option '--seed': '%s' is not a whole number in [0, %llu]\n", s,
                    (unsigned long long)UINT64_MAX);
            return 2;
        }
    }
    return 0;
}

/* Sends the changes given on top of the state in force (*sea, effective
 * at *eff), then reads the state back: 0, or 1 (refused, said). */
static int sea_set(const sea_opts *P, oc_client *c, proto_sea *sea, double *eff)
{
    for (size_t i = 0; i < SEA_FIELDS; i++)
        if (!isnan(P->field[i]))
            *(double *)((char *)sea + sea_fields[i].offset) = P->field[i];
    if (P->spectrum >= 0) sea->spectrum = (uint8_t)P->spectrum;
    if (P->spreading >= 0) sea->spreading = (uint8_t)P->spreading;
    if (P->whitecaps >= 0)
        sea->flags = (uint8_t)(P->whitecaps ? sea->flags & ~PROTO_SEA_NO_WHITECAPS : sea->flags | PROTO_SEA_NO_WHITECAPS);
    if (P->seed_s) sea->seed = (uint64_t)P->seed;
    sea->hs = 0;
    sea->tp = 0;
    /* default "now": the state's current effective time; the server
     * applies a time already past at its next tick */
    double when = isnan(P->at) ? *eff : P->at;
    int rc = 0;
    ocean_result r = oc_client_sea_state_set(c, sea, when, P->token, P->timeout_ms);
    if (r != OCEAN_OK) {
        char err[512];
        oc_client_last_error(c, err, sizeof err);
        fprintf(stderr, "ocean-client sea: %s\n", err[0] ? err : ocean_strerror(r));
        rc = 1;
    }
    oc_client_sea_state(c, sea, eff);
    /* the server enters a change at max(asked, its clock): the past is not
     * rewritten, and the asker hears when it did take effect */
    if (rc == 0 && !isnan(P->at) && *eff > P->at)
        fprintf(stderr, "ocean-client sea: asked for t = %.3f s, in force from t = %.3f s (a change takes effect no "
                "earlier than the server's clock)\n", P->at, *eff);
    return rc;
}

int cmd_sea(int argc, char **argv)
{
    sea_opts P = {.timeout_ms = 5000, .spectrum = -1, .spreading = -1, .whitecaps = -1, .at = NAN};
    for (size_t i = 0; i < SEA_FIELDS; i++)
        P.field[i] = NAN;
    int pr = sea_parse(argc, argv, &P);
    if (pr)
        return pr == 1 ? 0 : 2;
    if (sea_check(&P))
        return 2;
    oc_client *c = occli_connect("sea", P.url, NULL, P.timeout_ms);
    if (!c)
        return 1;
    proto_sea sea;
    double eff = 0;
    /* the state in force and when it took effect (HELLO's sea has no time) */
    if (oc_client_sea_state_fetch(c, P.timeout_ms, &sea, &eff) != OCEAN_OK) {
        char err[512];
        oc_client_last_error(c, err, sizeof err);
        fprintf(stderr, "ocean-client sea: %s\n", err);
        oc_client_destroy(c);
        return 1;
    }
    int rc = P.set ? sea_set(&P, c, &sea, &eff) : 0;
    /* a refused --set prints only its error: the state in force on stdout
     * read as the change having been made */
    if (rc == 0) {
        cJSON *o = sea_json(&sea, eff);
        occli_print_json(o);
    }
    oc_client_destroy(c);
    return rc;
}
