/*
 * wake_field.c - the wakes of the ships at one instant (see wake_field.h).
 */
#include "wake_field.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define WAKE_G 9.81
#define WAKE_FR_FADE 0.05     /* Froude numbers over which a wake fades in above WAKE_FR_MIN */

typedef struct held {
    wake_pattern *p;
    uint64_t used;            /* the read it last served, for the least recently read */
} held;

struct wake_field {
    int max, count;
    uint64_t reads;
    int in_order;             /* evict the pattern that came first, not the least recently read */
    held *h;
};

/* One rung of a ship's ladder: the pattern's parameters, its weight in
 * the blend, and the scale from the ship's frame to the pattern's. */
typedef struct rung {
    wake_params p;
    double weight, scale;
} rung;

/* A ship's place in the sea: its frame and the rungs it reads. */
typedef struct ship {
    double x, z, c, s, vx, vz;   /* position, heading's cos and sin, velocity */
    double amp;                  /* the draught as the pressure head, times the fade-in */
    rung r[2];
} ship;

ocean_result wake_field_create(int max_patterns, wake_field **out)
{
    *out = NULL;
    if (max_patterns < 2) return OCEAN_EINVAL;
    wake_field *f = calloc(1, sizeof *f);
    if (f) f->h = calloc((size_t)max_patterns, sizeof *f->h);
    if (!f || !f->h) {
        free(f);
        return OCEAN_ENOMEM;
    }
    f->max = max_patterns;
    *out = f;
    return OCEAN_OK;
}

void wake_field_destroy(wake_field *f)
{
    if (!f) return;
    for (int i = 0; i < f->count; i++) wake_pattern_destroy(f->h[i].p);
    free(f->h);
    free(f);
}

int wake_field_count(const wake_field *f) { return f->count; }

void wake_field_keep_order(wake_field *f) { f->in_order = 1; }

static int find(const wake_field *f, const wake_params *p)
{
    for (int i = 0; i < f->count; i++)
        if (wake_params_equal(wake_pattern_params(f->h[i].p), p)) return i;
    return -1;
}

static double wavelength(double speed, const ocean_entity_desc *d, double depth)
{
    wake_params p = {speed, d->length_m, depth, 0};
    double l = wake_transverse_wavelength(&p);
    return l > 0 ? l : 2 * M_PI * speed * speed / WAKE_G;
}

/* Ship d in state st over the given depth: 0 when it makes no wake. */
static int ship_make(const ocean_entity_desc *d, const ocean_entity_state *st, double depth, ship *out)
{
    if (d->kind != OCEAN_ENTITY_SHIP || !(st->speed > 0)) return 0;
    double fr = st->speed / sqrt(WAKE_G * d->length_m);
    if (fr <= WAKE_FR_MIN) return 0;
    double u = (fr - WAKE_FR_MIN) / WAKE_FR_FADE, fade = u >= 1 ? 1 : u * u * (3 - 2 * u);
    double heading = st->heading_deg * (M_PI / 180);
    out->x = st->x, out->z = st->z, out->vx = st->vx, out->vz = st->vz;
    out->c = cos(heading), out->s = sin(heading);
    out->amp = d->draught_m * fade;
    double j = WAKE_RUNGS_PER_OCTAVE * log2(st->speed), j0 = floor(j), lam = wavelength(st->speed, d, depth);
    for (int k = 0; k < 2; k++) {
        rung *r = &out->r[k];
        double speed = exp2((j0 + k) / WAKE_RUNGS_PER_OCTAVE);
        r->p = (wake_params){speed, d->length_m, depth, d->beam_m};
        r->weight = k ? j - j0 : 1 - (j - j0);
        r->scale = wavelength(speed, d, depth) / lam;
    }
    return 1;
}

/* Point (x, z) in the frame of ship h: along the track (behind positive)
 * and across it. */
static void ship_frame(const ship *h, double x, double z, double *xb, double *zb)
{
    double rx = x - h->x, rz = z - h->z;
    *xb = -(rx * h->c + rz * h->s);
    *zb = -rx * h->s + rz * h->c;
}

static int rung_reaches(const rung *r, double xb, double zb, double reach)
{
    return r->weight > 0 && hypot(xb, zb) * r->scale <= reach;
}

int wake_field_missing(const wake_field *f, const ocean_entity_desc *d, const ocean_entity_state *s, int n,
                       double depth, const double *xz, size_t np, wake_params *need, int max)
{
    int missing = 0;
    for (int i = 0; i < n; i++) {
        ship h;
        if (!ship_make(&d[i], &s[i], depth, &h)) continue;
        for (int k = 0; k < 2; k++) {
            const rung *r = &h.r[k];
            if (r->weight <= 0 || find(f, &r->p) >= 0) continue;
            int dup = 0;
            for (int m = 0; m < missing && m < max; m++) dup |= wake_params_equal(&need[m], &r->p);
            if (dup) continue;
            double reach = wake_params_reach(&r->p), xb, zb;
            for (size_t q = 0; q < np; q++) {
                ship_frame(&h, xz[2 * q], xz[2 * q + 1], &xb, &zb);
                if (!rung_reaches(r, xb, zb, reach)) continue;
                if (missing < max) need[missing] = r->p;
                missing++;
                break;
            }
        }
    }
    return missing;
}

void wake_field_insert(wake_field *f, wake_pattern *p)
{
    if (!p) return;
    if (find(f, wake_pattern_params(p)) >= 0) {
        wake_pattern_destroy(p);
        return;
    }
    int slot = f->count;
    if (f->count == f->max) {
        slot = 0;
        for (int i = 1; i < f->count; i++)
            if (f->h[i].used < f->h[slot].used) slot = i;
        wake_pattern_destroy(f->h[slot].p);
    } else {
        f->count++;
    }
    f->h[slot].p = p;
    f->h[slot].used = f->in_order ? ++f->reads : f->reads;
}

int wake_field_rungs(const ocean_entity_desc *d, const ocean_entity_state *s, int n, double depth, double x,
                     double z, double radius, wake_params *out, int max)
{
    int count = 0;
    for (int i = 0; i < n; i++) {
        ship h;
        if (!ship_make(&d[i], &s[i], depth, &h)) continue;
        double dist = hypot(x - h.x, z - h.z);
        for (int k = 0; k < 2; k++) {
            const rung *r = &h.r[k];
            if (r->weight <= 0 || dist > radius + wake_params_reach(&r->p) / r->scale) continue;
            int dup = 0;
            for (int m = 0; m < count && m < max; m++) dup |= wake_params_equal(&out[m], &r->p);
            if (dup) continue;
            if (count < max) out[count] = r->p;
            count++;
        }
    }
    return count;
}

/* The patterns of ship h's rungs the field holds (NULL: not held, which
 * wake_field_missing allows only where the rung reaches no point). */
static void ship_patterns(wake_field *f, const ship *h, const wake_pattern *pat[2])
{
    for (int k = 0; k < 2; k++) {
        int i = h->r[k].weight > 0 ? find(f, &h->r[k].p) : -1;
        pat[k] = i >= 0 ? f->h[i].p : NULL;
        if (i >= 0 && !f->in_order) f->h[i].used = f->reads;
    }
}

/* Adds ship h's wake at (x, z) to w. */
static void ship_add(const ship *h, const wake_pattern *const pat[2], double x, double z, wake_sample *w)
{
    double xb, zb, hb = 0, gx = 0, gz = 0, err = 0;
    ship_frame(h, x, z, &xb, &zb);
    for (int k = 0; k < 2; k++) {
        const rung *r = &h->r[k];
        if (!pat[k] || !rung_reaches(r, xb, zb, wake_pattern_reach(pat[k]))) continue;
        double sx, sz, v = wake_pattern_read(pat[k], xb * r->scale, zb * r->scale, &sx, &sz);
        hb += r->weight * v;
        gx += r->weight * r->scale * sx;
        gz += r->weight * r->scale * sz;
        err += r->weight * wake_pattern_bound_at(pat[k], xb * r->scale, zb * r->scale);
    }
    /* back to the world: xb = -(r . heading), zb = r . across */
    double dhdx = h->amp * (-gx * h->c - gz * h->s), dhdz = h->amp * (-gx * h->s + gz * h->c);
    w->height += h->amp * hb;
    w->dhdx += dhdx;
    w->dhdz += dhdz;
    w->dhdt -= h->vx * dhdx + h->vz * dhdz;  /* the pattern travels with the ship */
    w->error += h->amp * err;
}

ocean_result wake_field_sample(wake_field *f, const ocean_entity_desc *d, const ocean_entity_state *s, int n,
                               double depth, const double *xz, size_t np, wake_sample *out)
{
    for (size_t q = 0; q < np; q++)
        if (!isfinite(xz[2 * q]) || !isfinite(xz[2 * q + 1])) return OCEAN_EINVAL;
    if (wake_field_missing(f, d, s, n, depth, xz, np, NULL, 0) > 0) return OCEAN_ESTATE;
    f->reads++;
    memset(out, 0, sizeof *out * np);
    for (int i = 0; i < n; i++) {
        ship h;
        const wake_pattern *pat[2];
        if (!ship_make(&d[i], &s[i], depth, &h)) continue;
        ship_patterns(f, &h, pat);
        for (size_t q = 0; q < np; q++) ship_add(&h, pat, xz[2 * q], xz[2 * q + 1], &out[q]);
    }
    return OCEAN_OK;
}

/* Adds amp times pattern p's exact heights at the points rung r of ship
 * h reaches to heights. */
static ocean_result rung_exact(const ship *h, const rung *r, const wake_pattern *p, const double *xz, size_t np,
                               double *heights)
{
    double *pts = malloc(sizeof(double) * 3 * np), *v = pts + 2 * np, reach = wake_pattern_reach(p), xb, zb;
    size_t *at = malloc(sizeof(size_t) * np), m = 0;
    if (!pts || !at) {
        free(pts);
        free(at);
        return OCEAN_ENOMEM;
    }
    for (size_t q = 0; q < np; q++) {
        ship_frame(h, xz[2 * q], xz[2 * q + 1], &xb, &zb);
        if (!rung_reaches(r, xb, zb, reach)) continue;
        pts[2 * m] = xb * r->scale, pts[2 * m + 1] = zb * r->scale;
        at[m++] = q;
    }
    ocean_result res = m ? wake_pattern_exact(p, pts, m, v) : OCEAN_OK;
    for (size_t i = 0; res == OCEAN_OK && i < m; i++) heights[at[i]] += h->amp * r->weight * v[i];
    free(pts);
    free(at);
    return res;
}

ocean_result wake_field_exact(const wake_field *f, const ocean_entity_desc *d, const ocean_entity_state *s, int n,
                              double depth, const double *xz, size_t np, double *heights)
{
    if (wake_field_missing(f, d, s, n, depth, xz, np, NULL, 0) > 0) return OCEAN_ESTATE;
    memset(heights, 0, sizeof *heights * np);
    for (int i = 0; i < n; i++) {
        ship h;
        if (!ship_make(&d[i], &s[i], depth, &h)) continue;
        for (int k = 0; k < 2; k++) {
            int j = h.r[k].weight > 0 ? find(f, &h.r[k].p) : -1;
            ocean_result r = j >= 0 ? rung_exact(&h, &h.r[k], f->h[j].p, xz, np, heights) : OCEAN_OK;
            if (r != OCEAN_OK) return r;
        }
    }
    return OCEAN_OK;
}

void wake_sample_apply(const wake_sample *w, size_t n, ocean_query_result *q)
{
    for (size_t i = 0; i < n; i++) {
        q[i].height += w[i].height;
        q[i].velocity[1] += w[i].dhdt;
        q[i].error += w[i].error;
        double *nm = q[i].normal;
        if (!(nm[1] > 1e-6) || (w[i].dhdx == 0 && w[i].dhdz == 0)) continue;
        /* a height field's normal is (-hx, 1, -hz) normalised: the slopes add */
        double sx = -nm[0] / nm[1] + w[i].dhdx, sz = -nm[2] / nm[1] + w[i].dhdz, len = sqrt(1 + sx * sx + sz * sz);
        nm[0] = -sx / len, nm[1] = 1 / len, nm[2] = -sz / len;
    }
}
