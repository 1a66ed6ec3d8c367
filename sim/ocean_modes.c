/*
 * ocean_modes.c - the mode tables of one cascade: its band, and for every
 * mode of the half spectrum the standing-wave coefficients from h0(k) and
 * conj(h0(-k)), the frequency, |k| and the expected variance (the
 * conventions are ocean.c's file comment).  Built once by ocean_create
 * and read-only afterwards, so any thread may read them while no
 * evaluation runs.
 */
#include "ocean.h"
#include "ocean_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <stdio.h>

#include "ocean_time.h"
#include "spectrum.h"
#include "wave_rng.h"

/* Stores the standing-wave coefficients of the mode whose initial
 * amplitudes are hp = h0(k) and hm = h0(-k) at index i of cs->coef:
 * a = h0(k) + conj(h0(-k)), b = i (conj(h0(-k)) - h0(k)), in double and
 * rounded once. */
static void coef_put(ocean_cascade *cs, size_t i, const double hp[2], const double hm[2])
{
    cs->coef[A_RE][i] = (float)(hp[0] + hm[0]);
    cs->coef[A_IM][i] = (float)(hp[1] - hm[1]);
    cs->coef[B_RE][i] = (float)(hp[1] + hm[1]);
    cs->coef[B_IM][i] = (float)(hm[0] - hp[0]);
}

/* Variance per mode P(k) = F(k) dk^2 / 2 (see the file comment). */
static double mode_p(const ocean_params *p, const ocean_cascade *cs, double kx, double kz)
{
    return ocean_spectrum_f(&p->sea, kx, kz) * cs->dk * cs->dk * 0.5;
}

/* h0 of a lattice cascade at (mx, mz): a wave A cos(k.x - w t + phi) is
 * h0(k) = (A / 2) e^{i phi} (h0(-k) = 0), so that h(k) e^{ik.x} + c.c. is
 * the wave (file comment); waves on one point add. */
static void lattice_h0(const ocean_cascade *cs, int mx, int mz, double out[2])
{
    out[0] = out[1] = 0.0;
    for (int i = 0; i < cs->nlw; i++)
        if (cs->lw[i].mx == mx && cs->lw[i].mz == mz) {
            out[0] += 0.5 * cs->lw[i].amplitude * cos(cs->lw[i].phase);
            out[1] += 0.5 * cs->lw[i].amplitude * sin(cs->lw[i].phase);
        }
}

/* h0(k) for the integer wave vector (mx, mz): keyed by (seed, patch, mx, mz). */
void ocean_modes_h0(const ocean_params *p, const ocean_cascade *cs, int mx, int mz, double out[2])
{
    if (cs->lw) {
        lattice_h0(cs, mx, mz, out);
        return;
    }
    double kx = mx * cs->dk, kz = mz * cs->dk;
    double k = hypot(kx, kz);
    if (!ocean_in_band(cs, k)) {
        out[0] = out[1] = 0.0;
        return;
    }
    double xi[2];
    ocean_rng_normal2(p->seed, OCEAN_RNG_FFT, ocean_rng_patch_salt(cs->patch), mx, mz, xi);
    double a = sqrt(mode_p(p, cs, kx, kz)) * M_SQRT1_2;
    out[0] = xi[0] * a;
    out[1] = xi[1] * a;
}

/* The per-mode arrays of a cascade of n x (n/2 + 1) modes, zeroed. */
static ocean_result cascade_alloc(ocean_cascade *cs, int n)
{
    int half = n / 2 + 1;
    size_t nm = (size_t)n * half;
    int ok = (cs->turns_hi = calloc(nm, sizeof(double))) != NULL;
    ok &= (cs->turns_lo = calloc(nm, sizeof(double))) != NULL;
    for (int j = 0; j < 4; j++) {
        ok &= (cs->coef[j] = calloc(nm, sizeof(float))) != NULL;
        ok &= (cs->cache[j] = malloc(nm * sizeof(float))) != NULL;
    }
    ok &= (cs->kx = calloc((size_t)half, sizeof(float))) != NULL;
    ok &= (cs->k = calloc(nm, sizeof(float))) != NULL;
    ok &= (cs->kinv = calloc(nm, sizeof(float))) != NULL;
    ok &= (cs->kw = calloc(nm, sizeof(float))) != NULL;
    ok &= (cs->var = calloc(nm, sizeof(float))) != NULL;
    ok &= (cs->lo = calloc((size_t)half, sizeof(int))) != NULL;
    ok &= (cs->hi = calloc((size_t)half, sizeof(int))) != NULL;
    ok &= (cs->deep = calloc((size_t)half, sizeof(int))) != NULL;
    cs->cache_n = 0;
    if (!ok)
        return OCEAN_ENOMEM;
    for (int m = 0; m < half; m++)
        cs->deep[m] = half;
    for (int ix = 0; ix < half; ix++)
        cs->kx[ix] = (float)(ix * cs->dk);
    return OCEAN_OK;
}

/* The columns of each row pair (mz, -mz) that hold a wave: cs->lo, cs->hi
 * from the coefficients just stored.  Any of the pair nonzero counts, so a
 * range covers both rows (the stage takes them together). */
static void cascade_ranges(ocean_cascade *cs, int n)
{
    int half = n / 2 + 1;
    for (int m = 0; m <= n / 2; m++) {
        size_t up = ocean_pair_row(m, n) * half, down = ocean_pair_row(-m, n) * half;
        int lo = half, hi = 0;
        for (int ix = 0; ix < half; ix++) {
            int any = 0;
            for (int j = 0; j < 4; j++)
                any |= cs->coef[j][up + ix] != 0.0f || cs->coef[j][down + ix] != 0.0f;
            if (any) {
                lo = lo < ix ? lo : ix;
                hi = ix + 1;
            }
        }
        cs->lo[m] = lo < hi ? lo : 0;
        cs->hi[m] = lo < hi ? hi : 0;
    }
}

ocean_result ocean_modes_build(ocean *o, int c)
{
    ocean_cascade *cs = &o->cas[c];
    const ocean_params *p = &o->p;
    int n = p->n, half = n / 2 + 1;
    cs->patch = p->patch_m / pow(p->cascade_ratio, c);
    cs->dk = 2.0 * M_PI / cs->patch;
    /* Coarser cascades stop at half their Nyquist: at least 4 samples per
     * wavelength (Crest PR #903); the next cascade takes over from there. */
    cs->k_lo = c == 0 ? 0.0 : o->cas[c - 1].k_hi;
    cs->k_hi = c == p->cascades - 1 ? p->k_max : M_PI * n / (2.0 * cs->patch);
    ocean_result r = cascade_alloc(cs, n);
    if (r != OCEAN_OK)
        return r;
    cs->cf = sqrt(OCEAN_G * cs->dk) / OCEAN_TWO_PI_C1;
    /* k grows along a row: deep water is a tail of each row pair. */
    for (int m = 0; m < half; m++) {
        int x = 0;
        while (x < half && !(hypot(x * cs->dk, m * cs->dk) * p->sea.depth_m >= DEEP_KD))
            x++;
        cs->deep[m] = x;
    }
    double var = 0.0;
    for (int iz = 0; iz < n; iz++) {
        int mz = iz < n / 2 ? iz : iz - n;
        for (int ix = 0; ix < half; ix++) {
            size_t i = (size_t)iz * half + ix;
            int mx = ix;
            /* Nyquist row and column stay zero. */
            if (mz == -n / 2 || mx == n / 2)
                continue;
            double kx = mx * cs->dk, kz = mz * cs->dk, k = hypot(kx, kz);
            if (!ocean_in_band(cs, k))
                continue;
            double hp[2], hm[2];
            ocean_modes_h0(p, cs, mx, mz, hp);
            ocean_modes_h0(p, cs, -mx, -mz, hm);
            if (ix >= cs->deep[abs(mz)]) {
                cs->turns_hi[i] = ocean_deep_turns(cs->cf, (double)mx * mx + (double)mz * mz);
                cs->turns_lo[i] = 0.0;
            } else {
                ocean_turns_of(ocean_dispersion(k, p->sea.depth_m), &cs->turns_hi[i],
                               &cs->turns_lo[i]);
            }
            coef_put(cs, ocean_pair_row(mz, n) * half + ix, hp, hm);
            cs->k[i] = (float)k;
            cs->kinv[i] = (float)(1.0 / k);
            cs->kw[i] = (float)(k / ocean_dispersion(k, p->sea.depth_m));
            double v = mode_p(p, cs, kx, kz) + mode_p(p, cs, -kx, -kz);
            cs->var[i] = (float)v;
            /* Column 0 holds both k and -k; other columns stand for their mirror too. */
            var += ix == 0 ? v : 2.0 * v;
        }
    }
    cs->variance = var;
    cascade_ranges(cs, n);
    return OCEAN_OK;
}

/* The band [k_lo, k_hi) of a lattice cascade: the waves' |k| range, so
 * mip levels that hold none of them are empty.  OCEAN_EINVAL (msg names
 * the wave) for a wave off the grid or with a non-finite term. */
static ocean_result lattice_band(ocean_cascade *cs, int n, const ocean_lattice_wave *w, int count,
                                 char *msg, size_t msglen)
{
    cs->k_lo = INFINITY;
    cs->k_hi = 0.0;
    for (int i = 0; i < count; i++) {
        /* the Nyquist row and column stay empty, as in every cascade */
        if (w[i].mx <= -n / 2 || w[i].mx >= n / 2 || w[i].mz <= -n / 2 || w[i].mz >= n / 2 ||
            (w[i].mx == 0 && w[i].mz == 0) || !isfinite(w[i].amplitude) || w[i].amplitude < 0.0 ||
            !isfinite(w[i].phase)) {
            if (msg) snprintf(msg, msglen, "lattice wave %d: (mx, mz) = (%d, %d), amplitude %g, phase %g: "
                              "indices must be within +-%d and not both 0, amplitude finite and >= 0",
                              i, w[i].mx, w[i].mz, w[i].amplitude, w[i].phase, n / 2 - 1);
            return OCEAN_EINVAL;
        }
        double k = hypot(w[i].mx * cs->dk, w[i].mz * cs->dk);
        cs->k_lo = fmin(cs->k_lo, k);
        cs->k_hi = fmax(cs->k_hi, k);
    }
    if (count == 0)
        cs->k_lo = cs->k_hi = 0.0;
    else
        cs->k_hi = nextafter(cs->k_hi, INFINITY);
    return OCEAN_OK;
}

/* Fills the half spectrum's entry of the lattice point (mx, mz), mx >= 0,
 * unless another wave on the same point did; returns the variance it adds
 * (column 0 counts once, the others for their mirror too). */
static double lattice_mode_put(ocean_cascade *cs, const ocean_params *p, int mx, int mz)
{
    int n = p->n, half = n / 2 + 1;
    size_t at = (size_t)ocean_wrap_index(mz, n) * half + mx;
    if (cs->k[at] != 0.0f)
        return 0.0;
    double hp[2], hm[2];
    ocean_modes_h0(p, cs, mx, mz, hp);
    ocean_modes_h0(p, cs, -mx, -mz, hm);
    double kx = mx * cs->dk, kz = mz * cs->dk, k = hypot(kx, kz);
    ocean_turns_of(ocean_dispersion(k, p->sea.depth_m), &cs->turns_hi[at], &cs->turns_lo[at]);
    /* The stage takes one phase for rows mz and -mz (same |k|): the row
     * mirror carries the same w whether or not a wave sits there. */
    size_t mir = (size_t)ocean_wrap_index(-mz, n) * half + mx;
    cs->turns_hi[mir] = cs->turns_hi[at];
    cs->turns_lo[mir] = cs->turns_lo[at];
    coef_put(cs, ocean_pair_row(mz, n) * half + mx, hp, hm);
    cs->k[at] = (float)k;
    cs->kinv[at] = (float)(1.0 / k);
    cs->kw[at] = (float)(k / ocean_dispersion(k, p->sea.depth_m));
    /* E|h(k,t)|^2 over time: the two terms' cross product averages out */
    double v = hp[0] * hp[0] + hp[1] * hp[1] + hm[0] * hm[0] + hm[1] * hm[1];
    cs->var[at] = (float)v;
    return mx == 0 ? v : 2.0 * v;
}

/* The lattice cascade of ocean_create_lattice: h0 from the waves (sparse:
 * only their lattice points are non-zero), every other per-mode array as
 * a spectrum cascade fills it, so ocean_evaluate, the mips and the
 * moments treat it like any cascade. */
ocean_result ocean_modes_build_lattice(ocean *o, const ocean_lattice_wave *w, int count,
                                       char *msg, size_t msglen)
{
    ocean_cascade *cs = &o->cas[0];
    const ocean_params *p = &o->p;
    int n = p->n, half = n / 2 + 1;
    cs->patch = p->patch_m;
    cs->dk = 2.0 * M_PI / cs->patch;
    ocean_result r = lattice_band(cs, n, w, count, msg, msglen);
    if (r == OCEAN_OK)
        r = cascade_alloc(cs, n);
    if (r != OCEAN_OK)
        return r;
    cs->lw = malloc(sizeof *cs->lw * (size_t)(count > 0 ? count : 1));
    if (!cs->lw)
        return OCEAN_ENOMEM;
    memcpy(cs->lw, w, sizeof *cs->lw * (size_t)count);
    cs->nlw = count;
    /* the half spectrum's entries a wave at (mx, mz) touches: (mx, mz)
     * itself when mx >= 0, the mirror (-mx, -mz) otherwise, and both in
     * column 0 (which holds k and -k as separate entries) */
    double var = 0.0;
    for (int i = 0; i < count; i++) {
        if (w[i].mx >= 0)
            var += lattice_mode_put(cs, p, w[i].mx, w[i].mz);
        if (-w[i].mx >= 0)
            var += lattice_mode_put(cs, p, -w[i].mx, -w[i].mz);
    }
    /* The stage reads |k| and 1/|k| of row |mz| for rows mz and -mz (kz
     * enters squared): a wave on row -mz alone gets them on row mz too. */
    for (int mz = 1; mz < n / 2; mz++) {
        size_t up = (size_t)mz * half, down = (size_t)ocean_wrap_index(-mz, n) * half;
        for (int mx = 0; mx < half; mx++)
            if (cs->k[up + mx] == 0.0f && cs->k[down + mx] != 0.0f) {
                cs->k[up + mx] = cs->k[down + mx];
                cs->kinv[up + mx] = cs->kinv[down + mx];
                cs->kw[up + mx] = cs->kw[down + mx];
            }
    }
    cs->variance = var;
    cascade_ranges(cs, n);
    return OCEAN_OK;
}

void ocean_mode_amplitude(const ocean *o, int c, int mx, int mz, double t, double out[2])
{
    int n = o->p.n;
    out[0] = out[1] = 0.0;
    if (c < 0 || c >= o->p.cascades || mx <= -n / 2 || mx >= n / 2 || mz <= -n / 2 || mz >= n / 2)
        return;
    const ocean_cascade *cs = &o->cas[c];
    double hp[2], hm[2];
    ocean_modes_h0(&o->p, cs, mx, mz, hp);
    ocean_modes_h0(&o->p, cs, -mx, -mz, hm);
    double w = ocean_dispersion(hypot(mx * cs->dk, mz * cs->dk), o->p.sea.depth_m);
    double ph = ocean_phase(w, t), cp = cos(ph), sp = sin(ph);
    out[0] = hp[0] * cp + hp[1] * sp + hm[0] * cp + hm[1] * sp;
    out[1] = hp[1] * cp - hp[0] * sp + hm[0] * sp - hm[1] * cp;
}

void ocean_modes_free(ocean_cascade *cs)
{
    free(cs->turns_hi);
    free(cs->turns_lo);
    for (int j = 0; j < 4; j++) {
        free(cs->coef[j]);
        free(cs->cache[j]);
    }
    free(cs->kx);
    free(cs->k);
    free(cs->kinv);
    free(cs->kw);
    free(cs->var);
    free(cs->lo);
    free(cs->hi);
    free(cs->deep);
    free(cs->lw);
}
