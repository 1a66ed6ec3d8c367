/*
 * cmd_entity.c - `ocean-client entity`: the ships and aircraft in the sea
 * (PROTOCOL.md "ENTITY"), listed, or with the entity token one placed
 * (a track sample) or taken out.
 */
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include <cJSON.h>

#include "entity.h"
#include "occli.h"
#include "ocean_time.h"

/* What the server said: the entities in force (newest sample each, by id)
 * and the ERROR about an ENTITY, if one came. */
typedef struct entity_seen {
    proto_entity *e;
    int n, cap;
    int refused;
    char why[PROTO_ERROR_MSG_MAX + 64];
    uint32_t want_id;          /* the set or remove sent: its announce or gone is its answer */
    int want_op;
    atomic_int answered;       /* that answer, or an ERROR, came */
} entity_seen;

static void on_entity(void *user, oc_client *c, const proto_entity *e)
{
    (void)c;
    entity_seen *s = user;
    if (e->id == s->want_id && e->op == s->want_op) atomic_store(&s->answered, 1);
    int i = 0;
    while (i < s->n && s->e[i].id != e->id) i++;
    if (e->op == PROTO_ENTITY_GONE) {
        if (i < s->n) s->e[i] = s->e[--s->n];
        return;
    }
    if (e->op != PROTO_ENTITY_ANNOUNCE) return;
    if (i == s->n) {
        if (s->n == s->cap) {
            int cap = s->cap ? 2 * s->cap : 16;
            proto_entity *g = realloc(s->e, sizeof *g * (size_t)cap);
            if (!g) return; /* listed without it; the tool prints what it holds */
            s->e = g;
            s->cap = cap;
        }
        s->n++;
    }
    s->e[i] = *e;
}

static void on_error(void *user, oc_client *c, const proto_error *e)
{
    (void)c;
    entity_seen *s = user;
    if (e->offending_type != PROTO_ENTITY || s->refused) return;
    s->refused = 1;
    snprintf(s->why, sizeof s->why, "%s: %s", ocean_strerror((ocean_result)e->code), e->message);
    atomic_store(&s->answered, 1);
}

static const char *const kinds[] = {"ship", "rotorcraft", "aircraft", NULL};

static int by_id(const void *a, const void *b)
{
    uint32_t x = ((const proto_entity *)a)->id, y = ((const proto_entity *)b)->id;
    return x < y ? -1 : x > y;
}

static cJSON *entities_json(entity_seen *s)
{
    qsort(s->e, (size_t)s->n, sizeof *s->e, by_id);
    cJSON *a = cJSON_CreateArray();
    for (int i = 0; i < s->n; i++) {
        const proto_entity *e = &s->e[i];
        cJSON *o = cJSON_CreateObject();
        cJSON_AddNumberToObject(o, "id", e->id);
        if (e->kind < PROTO_ENTITY_KIND_COUNT) cJSON_AddStringToObject(o, "kind", kinds[e->kind]);
        else cJSON_AddNumberToObject(o, "kind", e->kind);
        cJSON_AddNumberToObject(o, "t", e->t);
        cJSON_AddNumberToObject(o, "x", e->x);
        cJSON_AddNumberToObject(o, "z", e->z);
        cJSON_AddNumberToObject(o, "altitude_m", e->altitude_m);
        cJSON_AddNumberToObject(o, "heading_deg", e->heading_deg);
        cJSON_AddNumberToObject(o, "speed", e->speed);
        cJSON_AddNumberToObject(o, "length_m", e->length_m);
        cJSON_AddNumberToObject(o, "beam_m", e->beam_m);
        cJSON_AddNumberToObject(o, "draught_m", e->draught_m);
        cJSON_AddItemToArray(a, o);
    }
    return a;
}

/* What `entity` was asked; NaN, -1 or NULL: not given. */
typedef struct entity_opts {
    int set, remove, timeout_ms, id, kind;
    const char *token, *url;
    double t, x, z, altitude, heading, speed, length, beam, draught;
} entity_opts;

/* Parses the options into *P: 0 go on, 1 help printed, 2 refused (said). */
static int entity_parse(int argc, char **argv, entity_opts *P)
{
    const double pos = OCEAN_ENTITY_POS_MAX;
    occli_opt opts[] = {
        {"set", OCCLI_FLAG, &P->set, 0, 0, "send ENTITY set: a track sample (needs --token, --id and the sample)", NULL},
        {"remove", OCCLI_FLAG, &P->remove, 0, 0, "send ENTITY remove (needs --token and --id)", NULL},
        {"token", OCCLI_STRING, &P->token, 0, 0, "TOKEN  the entity token from the server's config", NULL},
        {"id", OCCLI_INT, &P->id, 0, 2147483647, "N  the entity", NULL},
        {"kind", OCCLI_CHOICE, &P->kind, 0, 0, "NAME  what it is", kinds},
        {"t", OCCLI_DOUBLE, &P->t, -OCEAN_TIME_MAX, OCEAN_TIME_MAX, "T  sim time of the sample (not given: the server's clock)", NULL},
        {"x", OCCLI_DOUBLE, &P->x, -pos, pos, "M  position", NULL},
        {"z", OCCLI_DOUBLE, &P->z, -pos, pos, "M  position", NULL},
        {"altitude", OCCLI_DOUBLE, &P->altitude, 0, OCEAN_AIRCRAFT_ALTITUDE_MAX, "M  above mean sea level (ship: 0)", NULL},
        {"heading", OCCLI_DOUBLE, &P->heading, -3600, 3600, "DEG  direction of travel, from +x toward +z", NULL},
        {"speed", OCCLI_DOUBLE, &P->speed, 0, OCEAN_AIRCRAFT_SPEED_MAX, "M/S  along the heading", NULL},
        {"length", OCCLI_DOUBLE, &P->length, 0, 500, "M  ship: waterline length; rotorcraft: rotor diameter; aircraft: span", NULL},
        {"beam", OCCLI_DOUBLE, &P->beam, 0, 100, "M  ship's beam (others 0)", NULL},
        {"draught", OCCLI_DOUBLE, &P->draught, 0, 30, "M  ship's draught (others 0)", NULL},
        {"timeout", OCCLI_INT, &P->timeout_ms, 1, 3600000, "MS  connect / answer timeout", NULL},
    };
    const char *pos_args[1];
    int np = 0;
    int pr = occli_parse(argc, argv,
                         "usage: ocean-client entity URL [--set --token T --id N --kind K --x M --z M ... | --remove --token T --id N]\n"
                         "Prints the entities in the sea (JSON, newest sample each).  With --set, first enters a\n"
                         "track sample of entity --id (entering it with --kind and its size if new); with --remove,\n"
                         "takes it out.",
                         opts, (int)(sizeof opts / sizeof opts[0]), pos_args, 1, &np);
    if (pr) return pr;
    if (np != 1) {
        fprintf(stderr, "ocean-client entity: needs the server URL (see --help)\n");
        return 2;
    }
    P->url = pos_args[0];
    return 0;
}

/* Refuses what would be ignored or is missing: 0, or 2 (said). */
static int entity_check(const entity_opts *P)
{
    const char *sample = !isnan(P->x) ? "x" : !isnan(P->z) ? "z" : !isnan(P->t) ? "t" : !isnan(P->speed) ? "speed"
                       : !isnan(P->heading) ? "heading" : !isnan(P->altitude) ? "altitude" : !isnan(P->length) ? "length"
                       : !isnan(P->beam) ? "beam" : !isnan(P->draught) ? "draught" : P->kind >= 0 ? "kind" : NULL;
    if (P->set && P->remove) {
        fprintf(stderr, "ocean-client entity: '--set' and '--remove' together: give one\n");
        return 2;
    }
    if ((P->set || P->remove) && (!P->token || P->id < 0)) {
        fprintf(stderr, "ocean-client entity: '--%s' needs '--%s'\n", P->set ? "set" : "remove", !P->token ? "token" : "id");
        return 2;
    }
    if (!P->set && (sample || (!P->remove && (P->token || P->id >= 0)))) {
        fprintf(stderr, "ocean-client entity: option '--%s' is used only with '--set'%s; without it the command "
                "only prints the entities in the sea\n", sample ? sample : P->token ? "token" : "id",
                sample ? "" : " or '--remove'");
        return 2;
    }
    if (P->set && (P->kind < 0 || isnan(P->x) || isnan(P->z) || isnan(P->length))) {
        fprintf(stderr, "ocean-client entity: '--set' needs --kind, --x, --z and --length (and a ship --beam and "
                "--draught)\n");
        return 2;
    }
    return 0;
}

/* The ENTITY of the options (set or remove). */
static proto_entity entity_of(const entity_opts *P, double now)
{
    proto_entity e = {.op = (uint8_t)(P->set ? PROTO_ENTITY_SET : PROTO_ENTITY_REMOVE), .id = (uint32_t)P->id};
    snprintf(e.token, sizeof e.token, "%s", P->token);
    if (!P->set) return e;
    e.kind = (uint8_t)P->kind;
    e.t = isnan(P->t) ? now : P->t;
    e.x = P->x;
    e.z = P->z;
    const double v[6] = {P->altitude, P->heading, P->speed, P->length, P->beam, P->draught};
    float *f[6] = {&e.altitude_m, &e.heading_deg, &e.speed, &e.length_m, &e.beam_m, &e.draught_m};
    for (int i = 0; i < 6; i++) *f[i] = isnan(v[i]) ? 0.0f : (float)v[i];
    return e;
}

int cmd_entity(int argc, char **argv)
{
    entity_opts P = {.timeout_ms = 5000, .id = -1, .kind = -1, .t = NAN, .x = NAN, .z = NAN, .altitude = NAN,
                     .heading = NAN, .speed = NAN, .length = NAN, .beam = NAN, .draught = NAN};
    int pr = entity_parse(argc, argv, &P);
    if (pr) return pr == 1 ? 0 : 2;
    if (entity_check(&P)) return 2;
    entity_seen seen = {0};
    oc_options o;
    oc_options_default(&o);
    o.cb.user = &seen;
    o.cb.on_entity = on_entity;
    o.cb.on_error = on_error;
    oc_client *c = occli_connect("entity", P.url, &o, P.timeout_ms);
    if (!c) return 1;
    int rc = 0;
    char err[512] = "";
    ocean_result r = OCEAN_OK;
    proto_sea sea;
    double eff;
    /* the entities' timeline comes after HELLO, before the answer to what
     * is sent next: a round trip first, so that an entry of an earlier
     * life of the id is not taken for the answer */
    if (P.set || P.remove) r = oc_client_sea_state_fetch(c, P.timeout_ms, &sea, &eff);
    if (r == OCEAN_OK && (P.set || P.remove)) {
        atomic_store(&seen.answered, 0);
        proto_entity e = entity_of(&P, oc_client_sim_time(c));
        seen.want_id = e.id;
        seen.want_op = P.set ? PROTO_ENTITY_ANNOUNCE : PROTO_ENTITY_GONE;
        r = oc_client_send_entity(c, &e);
        /* replicated, the answer comes back through the shared stream,
         * after the answers to what is sent next: wait for it */
        for (int ms = 0; r == OCEAN_OK && !atomic_load(&seen.answered) && ms < P.timeout_ms; ms += 5)
            oc_service(c, 5);
        if (r == OCEAN_OK && !atomic_load(&seen.answered)) {
            snprintf(err, sizeof err, "no answer to the %s of entity %u within %d ms", P.set ? "set" : "remove",
                     e.id, P.timeout_ms);
            r = OCEAN_ESTATE;
        }
    }
    /* the server answers in order: once the sea state asked after them
     * comes back, every answer to the ENTITYs before it has come */
    proto_entity get = {.op = PROTO_ENTITY_GET};
    if (r == OCEAN_OK) r = oc_client_send_entity(c, &get);
    if (r == OCEAN_OK) r = oc_client_sea_state_fetch(c, P.timeout_ms, &sea, &eff);
    if (r != OCEAN_OK && !err[0]) oc_client_last_error(c, err, sizeof err);
    if (r != OCEAN_OK || seen.refused) {
        fprintf(stderr, "ocean-client entity: %s\n", seen.refused ? seen.why : err[0] ? err : ocean_strerror(r));
        rc = 1;
    } else {
        occli_print_json(entities_json(&seen));
    }
    oc_client_destroy(c);
    free(seen.e);
    return rc;
}
