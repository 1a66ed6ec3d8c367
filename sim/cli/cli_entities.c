/*
 * cli_entities.c - entity entries from a JSON file, and their wakes in
 * point answers (see cli_entities.h).
 */
#include "cli_entities.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cJSON.h>

#include "cli.h"
#include "wake_field.h"
#include "rotor_wash.h"

static const char *const kinds[] = {"ship", "rotorcraft", "aircraft"};

/* Member name of o as a number; absent: dflt; present but not a number:
 * NaN (the table refuses it by name). */
static double num(const cJSON *o, const char *name, double dflt)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, name);
    if (!v) return dflt;
    return cJSON_IsNumber(v) ? v->valuedouble : NAN;
}

static int kind_of(const cJSON *o)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, "kind");
    if (cJSON_IsString(v))
        for (int k = 0; k < (int)(sizeof kinds / sizeof *kinds); k++)
            if (!strcmp(v->valuestring, kinds[k])) return k;
    if (cJSON_IsNumber(v) && v->valuedouble >= 0 && v->valuedouble < OCEAN_ENTITY_KIND_COUNT_)
        return (int)v->valuedouble;
    return -1;
}

/* Enters entry o into e: a removal, or a sample (the entity entered first
 * when no live one has the id).  0, or 2 with the reason printed. */
static int entry_enter(ocean_entities *e, const cJSON *o, int i, const char *path)
{
    char why[400] = "";
    double id = num(o, "id", NAN);
    if (!cJSON_IsObject(o) || !(id >= 0 && id <= UINT32_MAX) || id != floor(id)) {
        fprintf(stderr, "error: %s: entry %d: not an object with an integer \"id\"\n", path, i);
        return 2;
    }
    ocean_result r;
    if (cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(o, "gone"))) {
        r = ocean_entities_remove(e, (uint32_t)id, num(o, "from", NAN));
        if (r != OCEAN_OK)
            snprintf(why, sizeof why, "no live entity %u, or \"from\" missing or before its last entry",
                     (uint32_t)id);
    } else {
        ocean_entity_desc d = {.id = (uint32_t)id, .kind = (ocean_entity_kind)kind_of(o),
                               .length_m = num(o, "length_m", NAN), .beam_m = num(o, "beam_m", 0),
                               .draught_m = num(o, "draught_m", 0)};
        ocean_track_sample s = {.t = num(o, "t", NAN), .x = num(o, "x", NAN), .z = num(o, "z", NAN),
                                .altitude_m = num(o, "altitude_m", 0), .heading_deg = num(o, "heading_deg", NAN),
                                .speed = num(o, "speed", NAN)};
        r = ocean_entities_enter(e, &d, &s, num(o, "from", s.t), why, sizeof why);
    }
    if (r == OCEAN_OK) return 0;
    fprintf(stderr, "error: %s: entry %d: %s\n", path, i, why[0] ? why : ocean_strerror(r));
    return 2;
}

int cli_entities_load(const char *path, ocean_entities **out)
{
    *out = NULL;
    char *text = cli_read_file(path);
    if (!text) return 2;
    cJSON *a = cJSON_Parse(text);
    free(text);
    if (!cJSON_IsArray(a)) {
        fprintf(stderr, "error: %s: not a JSON array of entity entries\n", path);
        cJSON_Delete(a);
        return 2;
    }
    ocean_entities *e;
    char why[200];
    if (ocean_entities_create(OCEAN_ENTITY_MAX, OCEAN_ENTITY_HOLD_S, OCEAN_TRACK_KEEP_MAX, &e, why, sizeof why) !=
        OCEAN_OK) { /* a file's entries, all kept */
        fprintf(stderr, "error: %s\n", why);
        cJSON_Delete(a);
        return 2;
    }
    int i = 0, rc = 0;
    for (const cJSON *o = a->child; o && !rc; o = o->next) rc = entry_enter(e, o, i++, path);
    cJSON_Delete(a);
    if (rc) ocean_entities_destroy(e);
    else *out = e;
    return rc;
}

int cli_wakes_apply(const ocean_entities *e, double t, double depth, const double *xz, size_t n,
                    ocean_query_result *res)
{
    int max = ocean_entities_kept(e);
    ocean_entity_desc *d = malloc(sizeof *d * (size_t)(max ? max : 1));
    ocean_entity_state *st = malloc(sizeof *st * (size_t)(max ? max : 1));
    wake_sample *ws = malloc(sizeof *ws * (n ? n : 1));
    wake_field *f = NULL;
    ocean_result r = d && st && ws ? wake_field_create(64, &f) : OCEAN_ENOMEM;
    int k = r == OCEAN_OK ? ocean_entities_at(e, t, d, st, max) : 0;
    wake_params need[64];
    int missing = r == OCEAN_OK ? wake_field_missing(f, d, st, k, depth, xz, n, need, 64) : 0;
    if (missing > 64) r = OCEAN_ETOOBIG; /* two a ship: 32 ships near the points */
    for (int i = 0; r == OCEAN_OK && i < missing; i++) {
        wake_pattern *p;
        r = wake_pattern_create(&need[i], &p, NULL, 0);
        if (r == OCEAN_OK) wake_field_insert(f, p);
    }
    if (r == OCEAN_OK) r = wake_field_sample(f, d, st, k, depth, xz, n, ws);
    rotor_wash *rw = NULL;
    if (r == OCEAN_OK && ocean_entities_count_kind(e, OCEAN_ENTITY_ROTORCRAFT)) r = rotor_wash_create(&rw);
    if (r == OCEAN_OK && rw) r = rotor_wash_add(rw, e, t, xz, n, ws);
    rotor_wash_destroy(rw);
    if (r == OCEAN_OK) wake_sample_apply(ws, n, res);
    else fprintf(stderr, "error: the ships' wakes at t = %.9g: %s\n", t, ocean_strerror(r));
    wake_field_destroy(f);
    free(ws);
    free(st);
    free(d);
    return r == OCEAN_OK ? 0 : 1;
}
