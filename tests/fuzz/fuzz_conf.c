/*
 * fuzz_conf.c - libFuzzer target for the configuration parser (sim/conf.c,
 * sim/ocean_conf.c).
 *
 * Each input is loaded three ways: as the daemon-style config (ocean table),
 * as a scene file, and against a table holding one entry of every conf type.
 * Beyond "no crash, no sanitizer report" it checks the parser's contract:
 *   - a failed load leaves its target byte for byte as it was, and its
 *     message starts with the source name and holds no control bytes;
 *   - a successful load dumps (conf_dump) to text that loads back to the
 *     identical bytes (the dump is a faithful, loadable configuration);
 *   - a successful ocean load passes ocean_params_validate;
 *   - the first line as a --set override either applies or leaves the
 *     target untouched.
 *
 * tests/test_conf.c includes this file to run the same checks on every seed
 * in tests/fuzz/corpus_conf/ in the ordinary test suite.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "conf.h"
#include "ocean_conf.h"

/* ---- a table with one entry of every type (also used by test_conf.c) ---- */

typedef struct fuzz_kit {
    int i;
    uint64_t u;
    double d;
    double k;        /* INF_OK */
    int b;
    char s[16];
    int e;
    unsigned f;
    int derived;     /* written by the NOSTORE key's hook */
} fuzz_kit;

static const conf_name fuzz_kit_colours[] = {
    {"red", 1}, {"green", 2}, {"blue", 7}, {"crimson", 1}, {NULL, 0}};
static const conf_name fuzz_kit_bits[] = {
    {"a", 1}, {"b", 2}, {"c", 4}, {"d", 64}, {NULL, 0}};

static ocean_result fuzz_kit_twice(void *target, const conf_entry *e, const void *value,
                                   char *msg, size_t msglen)
{
    int v = *(const int *)value;
    if (v == 13) {
        snprintf(msg, msglen, "%s: 13 is refused by the hook", e->name);
        return OCEAN_EINVAL;
    }
    ((fuzz_kit *)target)->derived = 2 * v;
    return OCEAN_OK;
}

static const conf_entry fuzz_kit_entries[] = {
    {.name = "kit.int", .type = CONF_INT, .offset = offsetof(fuzz_kit, i), .min = -100,
     .max = 100, .def = "7", .help = "an int"},
    {.name = "kit.u64", .type = CONF_U64, .offset = offsetof(fuzz_kit, u), .min = 0,
     .max = 18446744073709551616.0, .def = "0x10", .help = "a u64"},
    {.name = "kit.double", .type = CONF_DOUBLE, .offset = offsetof(fuzz_kit, d), .min = -1e3,
     .max = 1e3, .def = "0.1", .unit = "m", .help = "a double"},
    {.name = "kit.k", .type = CONF_DOUBLE, .offset = offsetof(fuzz_kit, k), .min = 0,
     .max = INFINITY, .def = "inf", .flags = CONF_F_INF_OK, .help = "a double or inf"},
    {.name = "kit.bool", .type = CONF_BOOL, .offset = offsetof(fuzz_kit, b), .def = "off",
     .help = "a bool"},
    {.name = "kit.str", .type = CONF_STRING, .offset = offsetof(fuzz_kit, s),
     .size = sizeof(((fuzz_kit *)0)->s), .def = "hi", .help = "a string"},
    {.name = "kit.enum", .type = CONF_ENUM, .offset = offsetof(fuzz_kit, e), .def = "green",
     .names = fuzz_kit_colours, .help = "an enum"},
    {.name = "kit.flags", .type = CONF_FLAGS, .offset = offsetof(fuzz_kit, f), .def = "a,c",
     .names = fuzz_kit_bits, .help = "a flags list"},
    {.name = "kit.twice", .type = CONF_INT, .min = 0, .max = 50, .flags = CONF_F_NOSTORE,
     .group = 1, .hook = fuzz_kit_twice, .help = "sets kit.derived"},
    {.name = "kit.derived", .type = CONF_INT, .offset = offsetof(fuzz_kit, derived), .min = 0,
     .max = 100, .def = "0", .group = 1, .help = "an int a hook also sets"},
};

static const conf_table fuzz_kit_table = {
    .name = "kit",
    .title = "every type",
    .entries = fuzz_kit_entries,
    .count = sizeof fuzz_kit_entries / sizeof fuzz_kit_entries[0],
    .target_size = sizeof(fuzz_kit),
};

/* ---- checks ---------------------------------------------------------------- */

/* Outcome of one input, for test_conf.c. */
typedef struct fuzz_conf_outcome {
    int ocean_ok, scene_ok, kit_ok, set_ok;
    char ocean_err[512], scene_err[512], kit_err[512];
} fuzz_conf_outcome;

static const char *fuzz_check_err(const char *err, const char *name)
{
    size_t n = strlen(name);
    if (strncmp(err, name, n) != 0 || err[n] != ':') return "error message does not start with the source name";
    for (const unsigned char *p = (const unsigned char *)err; *p; p++)
        if (*p < 0x20 || *p == 0x7F) return "error message holds a control byte";
    return NULL;
}

/* Dumps set to a string (caller frees). */
static char *fuzz_dump(const conf_set *set, size_t *len)
{
    char *buf = NULL;
    FILE *f = open_memstream(&buf, len);
    if (!f) return NULL;
    ocean_result r = conf_dump(f, set, CONF_DUMP_HELP);
    if (fclose(f) != 0 || r != OCEAN_OK) {
        free(buf);
        return NULL;
    }
    return buf;
}

/* Runs every check on one input; returns NULL or what went wrong. */
static const char *fuzz_conf_run(const uint8_t *data, size_t size, fuzz_conf_outcome *out)
{
    static fuzz_conf_outcome scratch;
    if (!out) out = &scratch;
    memset(out, 0, sizeof *out);
    const char *text = (const char *)data;
    const char *why;
    char *dump;
    size_t dlen;

    /* 1. The daemon-style config through ocean_conf_load_string. */
    ocean_params p, before, again;
    memset(&p, 0x5A, sizeof p);
    memcpy(&before, &p, sizeof p);
    if (ocean_conf_load_string("in.conf", text, size, &p, out->ocean_err, sizeof out->ocean_err) == OCEAN_OK) {
        out->ocean_ok = 1;
        if (ocean_params_validate(&p, NULL, 0) != OCEAN_OK) return "ocean load accepted invalid params";
        const conf_table *t[] = {ocean_conf_table()};
        void *g[] = {&p};
        conf_set set = {t, g, 1};
        if (!(dump = fuzz_dump(&set, &dlen))) return "ocean dump failed";
        memset(&again, 0x33, sizeof again);
        char err[512];
        ocean_result r = ocean_conf_load_string("dump", dump, dlen, &again, err, sizeof err);
        free(dump);
        if (r != OCEAN_OK) return "ocean dump does not reload";
        if (memcmp(&again, &p, sizeof p) != 0) return "ocean dump reloads to different values";

        /* 4. The first line as a --set override. */
        const char *nl = memchr(text, '\n', size);
        size_t l = nl ? (size_t)(nl - text) : size;
        char *line = malloc(l + 1);
        if (line) {
            memcpy(line, text, l);
            line[l] = '\0';
            ocean_params q;
            memcpy(&q, &p, sizeof p);
            if (ocean_conf_apply(line, &q, err, sizeof err) == OCEAN_OK) {
                out->set_ok = 1;
                if (ocean_params_validate(&q, NULL, 0) != OCEAN_OK) { free(line); return "--set accepted invalid params"; }
            } else if (memcmp(&q, &p, sizeof p) != 0) {
                free(line);
                return "failed --set changed the params";
            } else if ((why = fuzz_check_err(err, "--set"))) {
                free(line);
                return why;
            }
            free(line);
        }
    } else {
        if (memcmp(&p, &before, sizeof p) != 0) return "failed ocean load changed the params";
        if ((why = fuzz_check_err(out->ocean_err, "in.conf"))) return why;
    }

    /* 2. A scene file on top of the defaults. */
    ocean_params base;
    ocean_params_default(&base);
    ocean_scene *sc = malloc(sizeof *sc), *sc0 = malloc(sizeof *sc0), *sc2 = malloc(sizeof *sc2);
    if (!sc || !sc0 || !sc2) {
        free(sc), free(sc0), free(sc2);
        return NULL;
    }
    memset(sc, 0x77, sizeof *sc);
    memcpy(sc0, sc, sizeof *sc);
    why = NULL;
    if (ocean_conf_scene_load_string("scene.conf", text, size, &base, sc, out->scene_err,
                                     sizeof out->scene_err) == OCEAN_OK) {
        out->scene_ok = 1;
        const conf_table *t[] = {ocean_conf_scene_table(), ocean_conf_table()};
        void *g[] = {sc, &sc->params};
        conf_set set = {t, g, 2};
        char err[512];
        if (sc->effects == 0 || sc->name[0] == '\0') why = "scene without name or effects";
        else if (!(dump = fuzz_dump(&set, &dlen))) why = "scene dump failed";
        else {
            memset(sc2, 0x77, sizeof *sc2);
            ocean_result r = ocean_conf_scene_load_string("dump", dump, dlen, &base, sc2, err, sizeof err);
            free(dump);
            /* Compare field by field: the scene's padding is not ours to fix. */
            if (r != OCEAN_OK) why = "scene dump does not reload";
            else if (strcmp(sc2->name, sc->name) || strcmp(sc2->description, sc->description) ||
                     strcmp(sc2->camera_hint, sc->camera_hint) || sc2->effects != sc->effects ||
                     memcmp(&sc2->params, &sc->params, sizeof sc->params) != 0)
                why = "scene dump reloads to different values";
        }
    } else {
        if (memcmp(sc, sc0, sizeof *sc) != 0) why = "failed scene load changed the scene";
        else why = fuzz_check_err(out->scene_err, "scene.conf");
    }
    free(sc), free(sc0), free(sc2);
    if (why) return why;

    /* 3. Every type at once, on top of the kit defaults. */
    fuzz_kit k, k0, k2;
    memset(&k, 0, sizeof k);
    const conf_table *kt[] = {&fuzz_kit_table};
    void *kg[] = {&k};
    conf_set kset = {kt, kg, 1};
    if (conf_defaults(&kset, out->kit_err, sizeof out->kit_err) != OCEAN_OK) return "kit defaults failed";
    memcpy(&k0, &k, sizeof k);
    if (conf_load_string("kit.conf", text, size, &kset, NULL, out->kit_err, sizeof out->kit_err) == OCEAN_OK) {
        out->kit_ok = 1;
        if (!(dump = fuzz_dump(&kset, &dlen))) return "kit dump failed";
        memset(&k2, 0, sizeof k2);
        void *kg2[] = {&k2};
        conf_set kset2 = {kt, kg2, 1};
        char err[512];
        ocean_result r = conf_load_string("dump", dump, dlen, &kset2, NULL, err, sizeof err);
        free(dump);
        if (r != OCEAN_OK) return "kit dump does not reload";
        if (memcmp(&k2, &k, sizeof k) != 0) return "kit dump reloads to different values";
    } else {
        if (memcmp(&k, &k0, sizeof k) != 0) return "failed kit load changed the target";
        if ((why = fuzz_check_err(out->kit_err, "kit.conf"))) return why;
        /* A tiny message buffer must still be NUL-terminated. */
        char tiny[6];
        memset(tiny, 'x', sizeof tiny);
        conf_load_string("kit.conf", text, size, &kset, NULL, tiny, sizeof tiny);
        if (memchr(tiny, '\0', sizeof tiny) == NULL) return "message overflowed a small buffer";
    }
    return NULL;
}

#ifndef FUZZ_CONF_NO_MAIN
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *why = fuzz_conf_run(data, size, NULL);
    if (why) {
        fprintf(stderr, "fuzz_conf: %s\n", why);
        abort();
    }
    return 0;
}
#endif
