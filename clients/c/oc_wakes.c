/*
 * oc_wakes.c - a reader's wakes of the ships (see oc_wakes.h).
 */
#include "oc_wakes.h"

#include <math.h>
#include <stdlib.h>

#include "codec.h"
#include "entity.h"
#include "rotor_wash.h"

struct oc_wakes {
    ocean_entities *entities;
    wake_field *patterns;
    rotor_wash *rotors;      /* made at the first rotorcraft */
};

ocean_result oc_wakes_create(oc_wakes **out)
{
    *out = NULL;
    oc_wakes *w = calloc(1, sizeof *w);
    if (!w) return OCEAN_ENOMEM;
    if (ocean_entities_create(OCEAN_ENTITY_MAX, PROTO_ENTITY_HOLD_S, OC_WAKES_TRACK_KEEP, &w->entities, NULL, 0) !=
            OCEAN_OK ||
        wake_field_create(PROTO_WAKE_HELD, &w->patterns) != OCEAN_OK) {
        oc_wakes_destroy(w);
        return OCEAN_ENOMEM;
    }
    wake_field_keep_order(w->patterns);
    *out = w;
    return OCEAN_OK;
}

void oc_wakes_destroy(oc_wakes *w)
{
    if (!w) return;
    ocean_entities_destroy(w->entities);
    wake_field_destroy(w->patterns);
    rotor_wash_destroy(w->rotors);
    free(w);
}

ocean_result oc_wakes_entity(oc_wakes *w, const proto_msg *m)
{
    const proto_entity *e = &m->u.entity;
    double from = m->hdr.sim_time;
    if (m->hdr.type != PROTO_ENTITY || (e->op != PROTO_ENTITY_ANNOUNCE && e->op != PROTO_ENTITY_GONE))
        return OCEAN_EINVAL;
    ocean_entity_desc d = {.id = e->id, .kind = (ocean_entity_kind)e->kind, .length_m = e->length_m,
                           .beam_m = e->beam_m, .draught_m = e->draught_m}, known;
    ocean_track_sample s = {.t = e->t, .x = e->x, .z = e->z, .altitude_m = e->altitude_m,
                            .heading_deg = e->heading_deg, .speed = e->speed};
    ocean_result r = OCEAN_OK;
    /* gone, or entered anew with another shape (the server removed it first) */
    if (ocean_entities_desc(w->entities, e->id, &known) == OCEAN_OK &&
        (e->op == PROTO_ENTITY_GONE || !ocean_entity_desc_same(&known, &d)))
        r = ocean_entities_remove(w->entities, e->id, from);
    if (r == OCEAN_OK && e->op == PROTO_ENTITY_ANNOUNCE) r = ocean_entities_enter(w->entities, &d, &s, from, NULL, 0);
    ocean_entities_prune(w->entities, from - PROTO_ENTITY_PAST_S);
    return r == OCEAN_OK ? OCEAN_OK : OCEAN_EINVAL;
}

wake_pattern *oc_wakes_decode(const proto_wake *p)
{
    size_t n = (size_t)p->nx * p->nz;
    float *coef = malloc(sizeof *coef * (n ? n : 1));
    wake_pattern *pat = NULL;
    wake_params wp = {p->speed, p->length, p->depth, p->beam};
    if (coef && proto_plane_decode((proto_codec)p->codec, p->nx, p->nz, p->payload, p->payload_len, coef, NULL, 0) ==
                    OCEAN_OK)
        wake_pattern_from_coefficients(&wp, coef, p->nx, p->nz, p->error_bound, &pat, NULL, 0);
    free(coef);
    return pat;
}

void oc_wakes_keep(oc_wakes *w, wake_pattern *p) { wake_field_insert(w->patterns, p); }

int oc_wakes_patterns(const oc_wakes *w) { return wake_field_count(w->patterns); }

ocean_result oc_wakes_sample(oc_wakes *w, double t, double depth, const double *xz, size_t n, wake_sample *out)
{
    int max = ocean_entities_kept(w->entities);
    ocean_entity_desc *d = malloc(sizeof *d * (size_t)(max ? max : 1));
    ocean_entity_state *st = malloc(sizeof *st * (size_t)(max ? max : 1));
    ocean_result r = d && st ? OCEAN_OK : OCEAN_ENOMEM;
    if (r == OCEAN_OK) {
        int k = ocean_entities_at(w->entities, t, d, st, max);
        r = wake_field_sample(w->patterns, d, st, k, depth, xz, n, out);
    }
    if (r == OCEAN_OK && !w->rotors && ocean_entities_count_kind(w->entities, OCEAN_ENTITY_ROTORCRAFT))
        r = rotor_wash_create(&w->rotors);
    if (r == OCEAN_OK && w->rotors) r = rotor_wash_add(w->rotors, w->entities, t, xz, n, out);
    free(d);
    free(st);
    return r;
}

/* The point's slopes low-passed over its stencil (itself weighing 1/2,
 * the four points around it 1/8 each, the grid's edge clamped: the tent
 * filter whose response falls from 1 to 0 at the grid's Nyquist
 * wavelength, 2 dx) into o[1], o[2], and the weighted variance about them
 * a side into o[3]. */
static void grid_stencil(const wake_sample *s, int n, int i, int j, float *o)
{
    static const int di[5] = {0, 1, -1, 0, 0}, dj[5] = {0, 0, 0, 1, -1};
    static const double wt[5] = {0.5, 0.125, 0.125, 0.125, 0.125};
    double mx = 0, mz = 0, vx = 0, vz = 0;
    for (int k = 0; k < 5; k++) {
        int a = i + di[k], b = j + dj[k];
        a = a < 0 ? 0 : a >= n ? n - 1 : a;
        b = b < 0 ? 0 : b >= n ? n - 1 : b;
        const wake_sample *p = &s[(size_t)b * n + a];
        mx += wt[k] * p->dhdx, mz += wt[k] * p->dhdz;
        vx += wt[k] * p->dhdx * p->dhdx, vz += wt[k] * p->dhdz * p->dhdz;
    }
    o[1] = (float)mx;
    o[2] = (float)mz;
    o[3] = (float)fmax(0.0, 0.5 * (vx - mx * mx + vz - mz * mz));
}

ocean_result oc_wakes_grid(oc_wakes *w, double t, double depth, double x0, double z0, double dx, int n, float *out)
{
    if (!w || !out || n < 3 || n > 1024 || !(dx > 0) || !isfinite(x0) || !isfinite(z0)) return OCEAN_EINVAL;
    size_t np = (size_t)n * n;
    double *xz = malloc(sizeof *xz * 2 * np);
    wake_sample *s = malloc(sizeof *s * np);
    ocean_result r = xz && s ? OCEAN_OK : OCEAN_ENOMEM;
    for (size_t k = 0; r == OCEAN_OK && k < np; k++) {
        xz[2 * k] = x0 + (double)(k % (size_t)n) * dx;
        xz[2 * k + 1] = z0 + (double)(k / (size_t)n) * dx;
    }
    if (r == OCEAN_OK) r = oc_wakes_sample(w, t, depth, xz, np, s);
    for (size_t k = 0; r == OCEAN_OK && k < np; k++) {
        out[4 * k] = (float)s[k].height;
        grid_stencil(s, n, (int)(k % (size_t)n), (int)(k / (size_t)n), out + 4 * k);
    }
    free(xz);
    free(s);
    return r;
}
