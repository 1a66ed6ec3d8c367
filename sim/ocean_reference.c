/*
 * ocean_reference.c - the double-precision reference of an ocean: every
 * wave of every band summed directly at a point (see ocean_reference.h),
 * the truth the tests and the accuracy benchmark compare the FFT fields
 * with.  Reads the ocean's tables only.
 */
#include "ocean_reference.h"

#include <math.h>
#include <stdlib.h>

#include "ocean_internal.h"

/* x mod 2 pi in [-pi, pi], exact to a few ulp of pi (ocean_time.h); for
 * the spatial phases k.x of the reference sums (x already reduced modulo
 * the patch).  Time phases go through ocean_phase(w, t), which keeps the
 * product w t exact too. */
static inline double reduce_phase(double x)
{
    return ocean_phase(x, 1.0);
}

/* The reference sums (ocean_reference_point, ocean_reference_eval): one
 * wave's h(k, t) and dh/dt with the filter's gain, then its terms at a
 * point given e^{i k.x}.  Both paths use these, so they add the same terms. */
typedef struct ref_wave {
    double hr, hi, tr, ti;   /* g h(k, t), g dh/dt */
    double kw;               /* |k| / w: beta's quadrature from dh/dt (foam.h) */
    int mx, mz;
} ref_wave;

typedef struct ref_sum {
    double h, dx, dz, sx, sz, dxx, dzz, dxz, bq, vx, vy, vz;
} ref_sum;

/* 0 for a wave outside the band or filtered out (nothing to add). */
static int ref_wave_at(const ocean *o, const ocean_cascade *cs, int mx, int mz, double t,
                       double cutoff_k, int order, ref_wave *rw)
{
    const ocean_params *p = &o->p;
    double kx = mx * cs->dk, kz = mz * cs->dk, k = hypot(kx, kz);
    if (!ocean_in_band(cs, k))
        return 0;
    double g = ocean_filter_gain(k, cutoff_k, order);
    if (g == 0.0)
        return 0;
    double hp[2], hm[2];
    ocean_modes_h0(p, cs, mx, mz, hp);
    ocean_modes_h0(p, cs, -mx, -mz, hm);
    double w = ocean_dispersion(k, p->sea.depth_m);
    double ph = ocean_phase(w, t), cp = cos(ph), sp = sin(ph);
    /* h = hp e^{-i ph} + conj(hm) e^{i ph} */
    double hr = hp[0] * cp + hp[1] * sp + hm[0] * cp + hm[1] * sp;
    double hi = hp[1] * cp - hp[0] * sp - hm[1] * cp + hm[0] * sp;
    /* dh/dt = -i w A + i w B, A = hp e^{-i ph}, B = conj(hm) e^{i ph} */
    double ar = hp[0] * cp + hp[1] * sp, ai = hp[1] * cp - hp[0] * sp;
    double br = hm[0] * cp + hm[1] * sp, bi = hm[0] * sp - hm[1] * cp;
    rw->hr = g * hr;
    rw->hi = g * hi;
    rw->tr = g * (w * (ai - bi));
    rw->ti = g * (w * (br - ar));
    rw->kw = k / w;
    rw->mx = mx;
    rw->mz = mz;
    return 1;
}

/* Adds wave rw at a point where e^{i k.x} = ce + i se. */
static inline void ref_add(const ocean_cascade *cs, double lam, const ref_wave *rw, double ce, double se,
                           ref_sum *a)
{
    double kx = rw->mx * cs->dk, kz = rw->mz * cs->dk, k = hypot(kx, kz);
    /* Re(a e^{i ex}) = ar ce - ai se; Re(i a e^{i ex}) = -ai ce - ar se */
    double re_h = rw->hr * ce - rw->hi * se, re_ih = -rw->hi * ce - rw->hr * se;
    double re_t = rw->tr * ce - rw->ti * se, re_it = -rw->ti * ce - rw->tr * se;
    a->h += re_h;
    a->dx += lam * kx / k * re_ih;
    a->dz += lam * kz / k * re_ih;
    a->sx += kx * re_ih;
    a->sz += kz * re_ih;
    a->dxx += -lam * kx * kx / k * re_h;
    a->dzz += -lam * kz * kz / k * re_h;
    a->dxz += -lam * kx * kz / k * re_h;
    a->bq += lam * rw->kw * re_t;
    a->vy += re_t;
    a->vx += lam * kx / k * re_it;
    a->vz += lam * kz / k * re_it;
}

/* The point from its sums; J and the whitecap foam as an evaluation with
 * this filter forms them (foam map m). */
static void ref_finish(const ref_sum *a, double lam, const ocean_foam_map *m, ocean_point *out)
{
    *out = (ocean_point){.height = a->h, .dx = a->dx, .dz = a->dz, .slope_x = a->sx,
                         .slope_z = a->sz, .vel_x = a->vx, .vel_y = a->vy, .vel_z = a->vz,
                         .dxx = a->dxx, .dzz = a->dzz, .dxz = a->dxz, .bq = a->bq};
    out->jacobian = (1.0 + a->dxx) * (1.0 + a->dzz) - a->dxz * a->dxz;
    double il = lam > 0.0 ? 1.0 / lam : 0.0;
    out->foam = ocean_foam_value(m, ocean_foam_beta(a->dxx, a->dzz, il), ocean_foam_beta(a->bq, 0.0, il));
}

static ocean_foam_map ref_foam_map(const ocean *o, double cutoff_k, int order)
{
    double kc = ocean_effective_cutoff(o, cutoff_k, order);
    if (isnan(kc)) /* an invalid filter: the target spread evenly, as sigma 0 gives */
        return (ocean_foam_map){INFINITY, INFINITY, ocean_stats_whitecap_target(o), INFINITY};
    return ocean_stats_foam_sum(o, kc, order, 1.0, 1.0, NULL);
}

void ocean_reference_point(const ocean *o, double t, double x, double z,
                           double cutoff_k, int order, ocean_point *out)
{
    const ocean_params *p = &o->p;
    double lam = p->sea.choppiness;
    int n = p->n;
    ref_sum a = {0};
    for (int c = 0; c < p->cascades; c++) {
        const ocean_cascade *cs = &o->cas[c];
        /* Phases of e^{ik.x} reduced with x mod patch: exact for any x. */
        double xr = x - floor(x / cs->patch) * cs->patch;
        double zr = z - floor(z / cs->patch) * cs->patch;
        for (int mz = -n / 2 + 1; mz < n / 2; mz++)
            for (int mx = -n / 2 + 1; mx < n / 2; mx++) {
                ref_wave rw;
                if (!ref_wave_at(o, cs, mx, mz, t, cutoff_k, order, &rw))
                    continue;
                double ex = reduce_phase(mx * cs->dk * xr + mz * cs->dk * zr);
                ref_add(cs, lam, &rw, cos(ex), sin(ex), &a);
            }
    }
    ocean_foam_map m = ref_foam_map(o, cutoff_k, order);
    ref_finish(&a, lam, &m, out);
}

struct ocean_reference {
    const ocean *o;
    double lam;
    ocean_foam_map foam;
    size_t count[OCEAN_MAX_CASCADES];
    ref_wave *waves[OCEAN_MAX_CASCADES];
};

ocean_result ocean_reference_create(const ocean *o, double t, double cutoff_k, int order,
                                    ocean_reference **out)
{
    if (!out)
        return OCEAN_EINVAL;
    *out = NULL;
    if (!o || !ocean_time_ok(t) || isnan(cutoff_k) || cutoff_k < 0.0 || order < 1)
        return OCEAN_EINVAL;
    ocean_reference *r = calloc(1, sizeof *r);
    if (!r)
        return OCEAN_ENOMEM;
    r->o = o;
    r->lam = o->p.sea.choppiness;
    int n = o->p.n;
    for (int c = 0; c < o->p.cascades; c++) {
        const ocean_cascade *cs = &o->cas[c];
        r->waves[c] = malloc(sizeof(ref_wave) * (size_t)(n - 1) * (size_t)(n - 1));
        if (!r->waves[c]) {
            ocean_reference_destroy(r);
            return OCEAN_ENOMEM;
        }
        /* in ocean_reference_point's order (mz outer), so the sums add alike */
        for (int mz = -n / 2 + 1; mz < n / 2; mz++)
            for (int mx = -n / 2 + 1; mx < n / 2; mx++)
                r->count[c] += ref_wave_at(o, cs, mx, mz, t, cutoff_k, order,
                                           &r->waves[c][r->count[c]]);
    }
    r->foam = ref_foam_map(o, cutoff_k, order);
    *out = r;
    return OCEAN_OK;
}

void ocean_reference_destroy(ocean_reference *r)
{
    if (!r)
        return;
    for (int c = 0; c < OCEAN_MAX_CASCADES; c++)
        free(r->waves[c]);
    free(r);
}

void ocean_reference_eval(const ocean_reference *r, double x, double z, ocean_point *out)
{
    const ocean *o = r->o;
    int n = o->p.n, half = n / 2;
    ref_sum a = {0};
    /* e^{i k.x} = e^{i kx x} e^{i kz z}: 2 (n - 1) sines and cosines a
     * cascade, each of its own reduced phase (no recurrence, so no error
     * grows along the axis), then one complex product a wave. */
    double *ax = malloc(sizeof(double) * 4 * (size_t)n);
    if (!ax) {
        ocean_point nan_pt = {.height = NAN, .dx = NAN, .dz = NAN, .slope_x = NAN, .slope_z = NAN,
                              .jacobian = NAN, .foam = NAN, .vel_x = NAN, .vel_y = NAN,
                              .vel_z = NAN, .dxx = NAN, .dzz = NAN, .dxz = NAN, .bq = NAN};
        *out = nan_pt;
        return;
    }
    double *cx = ax, *sx = ax + n, *cz = ax + 2 * n, *sz = ax + 3 * n;
    for (int c = 0; c < o->p.cascades; c++) {
        const ocean_cascade *cs = &o->cas[c];
        double xr = x - floor(x / cs->patch) * cs->patch;
        double zr = z - floor(z / cs->patch) * cs->patch;
        for (int m = -half + 1; m < half; m++) {
            double px = reduce_phase(m * cs->dk * xr), pz = reduce_phase(m * cs->dk * zr);
            cx[m + half] = cos(px);
            sx[m + half] = sin(px);
            cz[m + half] = cos(pz);
            sz[m + half] = sin(pz);
        }
        const ref_wave *w = r->waves[c];
        for (size_t i = 0; i < r->count[c]; i++) {
            int jx = w[i].mx + half, jz = w[i].mz + half;
            double ce = cx[jx] * cz[jz] - sx[jx] * sz[jz], se = sx[jx] * cz[jz] + cx[jx] * sz[jz];
            ref_add(cs, r->lam, &w[i], ce, se, &a);
        }
    }
    free(ax);
    ref_finish(&a, r->lam, &r->foam, out);
}
