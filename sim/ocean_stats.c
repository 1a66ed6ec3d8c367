/*
 * ocean_stats.c - expected statistics of an ocean's discretised spectrum,
 * whole or under a filter: sums over every mode of its variance, with the
 * gains an evaluation applies (E_error, the redistribution scale, the
 * breaking index's std for the foam map, the moments and mips of each
 * cascade).  They do not depend on t, so the ones a tick asks for again
 * and again are memoised in the ocean (same thread rules as the ocean).
 */
#include "ocean.h"
#include "ocean_internal.h"

#include <math.h>
#include <string.h>

#include "interp.h"
#include "spectrum.h"

/* Index of (kc, order, scale, boost) in a memo table, or -1. */
static int memo_find(const ocean_memo *m, double kc, int order, double scale, double boost)
{
    for (int i = 0; i < FILTER_MEMO; i++)
        if (m[i].used && m[i].kc == kc && m[i].order == order && m[i].scale == scale &&
            m[i].boost == boost)
            return i;
    return -1;
}

/* Stores a value, replacing the oldest entry (round robin). */
static void memo_put(ocean_memo *m, int *next, double kc, int order, double scale,
                     double boost, double value)
{
    m[*next] = (ocean_memo){1, order, kc, scale, boost, value, 0.0};
    *next = (*next + 1) % FILTER_MEMO;
}

/* The gain a wave of wave number k actually gets: waves above kneg are not
 * transformed at all. */
static inline double effective_gain(double k, double kc, int order, double kneg)
{
    return k < kneg ? ocean_filter_gain(k, kc, order) : 0.0;
}

/* Sum over every mode of var * fn(gain), with the half-spectrum weights. */
static void filter_sums(const ocean *o, double kc, int order, double scale, double boost,
                        double *total, double *kept, double *err)
{
    double kneg = ocean_negligible_k(o, kc, order);
    int n = o->p.n, half = n / 2 + 1;
    *total = *kept = *err = 0.0;
    for (int c = 0; c < o->p.cascades; c++)
        for (size_t i = 0; i < (size_t)n * half; i++) {
            const ocean_cascade *cs = &o->cas[c];
            if (cs->var[i] == 0.0f)
                continue;
            double w = ((i % half) == 0 ? 1.0 : 2.0) * cs->var[i];
            double g = effective_gain(cs->k[i], kc, order, kneg);
            double ge = g * scale * (1.0 + (boost - 1.0) * g * g);
            *total += w;
            *kept += w * g * g;
            *err += w * (1.0 - ge) * (1.0 - ge);
        }
}

/* Each reading's share of a wave's power per |column| and |row| index m
 * (phase step m dk h between nodes of spacing h), m < count. */
static void reading_powers(ocean_foam_reading rd, double dkh, int count, double *out)
{
    if (rd == OCEAN_FOAM_EXACT) {
        for (int m = 0; m < count; m++)
            out[m] = 1.0;
        return;
    }
    ocean_interp_powers(rd == OCEAN_FOAM_BILINEAR ? OCEAN_INTERP_BILINEAR : OCEAN_INTERP_LAGRANGE, dkh, count, out);
}

/* Std of the breaking index beta = sum k eta_k (foam.h) as each reading
 * holds it, and its mean frequency: over the modes an evaluation with this
 * filter transforms, m0 = sum var k^2 ge^2 A(kx h) A(kz h), with A the
 * reading's power (interp.h) on a grid of spacing h, and m1 the same
 * sum weighted by each wave's frequency.  Without A the finest cascade's
 * near-Nyquist waves, which bilinear reading damps, would count fully and
 * tiles would show ~half the intended coverage at light winds; with the
 * bilinear A on an accurate reading, queries covered 1.5 times the wind's
 * share. */
typedef struct foam_band {
    double sigma[OCEAN_FOAM_READINGS], omega[OCEAN_FOAM_READINGS]; /* sqrt(m0), m1 / m0 (0 without waves) */
} foam_band;

static foam_band foam_band_of(const ocean *o, double kc, int order, double scale, double boost)
{
    double kneg = ocean_negligible_k(o, kc, order), m0[OCEAN_FOAM_READINGS] = {0}, m1[OCEAN_FOAM_READINGS] = {0};
    int n = o->p.n, half = n / 2 + 1;
    for (int c = 0; c < o->p.cascades; c++) {
        const ocean_cascade *cs = &o->cas[c];
        if (cs->k_lo >= kneg)
            continue;
        double h = cs->patch / ocean_pick_size(cs, n, kneg);
        /* A per column and per row: |mx|, |mz| < n/2. */
        double a[OCEAN_FOAM_READINGS][OCEAN_MAX_N / 2];
        for (int r = 0; r < OCEAN_FOAM_READINGS; r++)
            reading_powers((ocean_foam_reading)r, cs->dk * h, n / 2, a[r]);
        for (size_t i = 0; i < (size_t)n * half; i++) {
            if (cs->var[i] == 0.0f)
                continue;
            int ix = (int)(i % half), iz = (int)(i / half), mz = iz < n / 2 ? iz : n - iz;
            int jx = ix < n / 2 ? ix : n / 2 - 1, jz = mz < n / 2 ? mz : n / 2 - 1;
            double w = (ix == 0 ? 1.0 : 2.0) * cs->var[i];
            double g = isinf(kc) ? 1.0 : effective_gain(cs->k[i], kc, order, kneg);
            double ge = g * scale * (1.0 + (boost - 1.0) * g * g);
            double k = cs->k[i], vb = w * k * k * ge * ge, wk = ocean_dispersion(k, o->p.sea.depth_m);
            for (int r = 0; r < OCEAN_FOAM_READINGS; r++) {
                double v = vb * a[r][jx] * a[r][jz];
                m0[r] += v;
                m1[r] += v * wk;
            }
        }
    }
    foam_band b;
    for (int r = 0; r < OCEAN_FOAM_READINGS; r++) {
        b.sigma[r] = sqrt(m0[r]);
        b.omega[r] = m0[r] > 0.0 ? m1[r] / m0[r] : 0.0;
    }
    return b;
}

/* The map of a band (foam.h): its target coverage at its sigma and omega. */
static ocean_foam_map foam_map_of(const ocean *o, double sigma, double omega)
{
    ocean_foam_map m;
    if (ocean_foam_map_solve(sigma, omega, ocean_stats_whitecap_target(o), &m) != OCEAN_OK)
        m = (ocean_foam_map){INFINITY, INFINITY, -1.0, INFINITY};
    return m;
}

/* The band and its solved maps, memoised: a solve with trails integrates
 * numerically (a few ms), and the ticks ask for the same filters again. */
static int foam_memo(ocean *o, double kc, int order, double scale, double boost)
{
    int i = memo_find(o->foam_memo, kc, order, scale, boost);
    if (i >= 0)
        return i;
    foam_band b = foam_band_of(o, kc, order, scale, boost);
    i = o->foam_next;
    memo_put(o->foam_memo, &o->foam_next, kc, order, scale, boost, 0.0);
    for (int r = 0; r < OCEAN_FOAM_READINGS; r++) {
        o->foam_read[i][r][0] = b.sigma[r];
        o->foam_read[i][r][1] = b.omega[r];
        o->foam_maps[i][r] = foam_map_of(o, b.sigma[r], b.omega[r]);
    }
    return i;
}

ocean_foam_map ocean_stats_foam_sum(const ocean *o, double kc, int order, double scale, double boost,
                                    double *sigma)
{
    foam_band b = foam_band_of(o, kc, order, scale, boost);
    if (sigma) *sigma = b.sigma[OCEAN_FOAM_EXACT];
    return foam_map_of(o, b.sigma[OCEAN_FOAM_EXACT], b.omega[OCEAN_FOAM_EXACT]);
}

ocean_foam_map ocean_stats_foam(ocean *o, ocean_foam_reading rd, double kc, int order, double scale, double boost,
                                double *sigma, double *omega)
{
    int i = foam_memo(o, kc, order, scale, boost);
    if (sigma) *sigma = o->foam_read[i][rd][0];
    if (omega) *omega = o->foam_read[i][rd][1];
    return o->foam_maps[i][rd];
}

ocean_result ocean_foam_table(const ocean *o, const ocean *more, int order, const double *kc, int n,
                              ocean_foam_row *rows, int *count)
{
    if (!o || !kc || !rows || !count || n < 1 || order < 1)
        return OCEAN_EINVAL;
    *count = 0;
    double w = ocean_stats_whitecap_target(o);
    if (!(w > 0.0))
        return OCEAN_OK; /* no whitecaps (whitecaps off, or no waves): no ramp at all */
    for (int j = 0; j < n; j++) {
        if (!(kc[j] >= 0.0))
            return OCEAN_EINVAL;
        /* the band itself: a reader of tiles sums the bands' indices */
        const int e = OCEAN_FOAM_EXACT;
        foam_band b = foam_band_of(o, kc[j], order, 1.0, 1.0);
        double m0 = b.sigma[e] * b.sigma[e], m1 = m0 * b.omega[e];
        if (more) {
            foam_band c = foam_band_of(more, kc[j], order, 1.0, 1.0);
            m0 += c.sigma[e] * c.sigma[e];
            m1 += c.sigma[e] * c.sigma[e] * c.omega[e];
        }
        double sigma = sqrt(m0), omega = m0 > 0.0 ? m1 / m0 : 0.0;
        if (*count && !(sigma > rows[*count - 1].sigma))
            continue; /* no wave between the two cutoffs */
        ocean_foam_map m;
        ocean_result r = ocean_foam_map_solve(sigma, omega, w, &m);
        if (r != OCEAN_OK)
            return r;
        /* a field of no waves is uniformly W: the ramp's limit, whose foot
         * puts beta = 0 at W (foam.h) */
        double a = m.uniform >= 0.0 ? -OCEAN_FOAM_BETA_BREAK * w / (1.0 - w) : m.a;
        rows[(*count)++] = (ocean_foam_row){sigma, a, omega};
    }
    return OCEAN_OK;
}

/* The whitecap coverage of o's sea: the wind's, but none when the grid
 * holds no wave at all (Phillips A = 0, or k_max below every mode: no
 * breakers, whatever the wind says; it gave 0.93 % of foam on a flat sea).
 * A filter that removes every wave still leaves the sea's coverage, spread
 * evenly (foam.h). */
double ocean_stats_whitecap_target(const ocean *o)
{
    double energy = 0.0;
    for (int c = 0; c < o->p.cascades; c++)
        energy += o->cas[c].variance;
    /* whitecaps off (the sea state's): no foam anywhere, every place foam
     * is read (tiles, queries, statistics) following this one target */
    return energy > 0.0 && o->p.sea.whitecaps ? ocean_foam_coverage_target(o->p.sea.wind_u10) : 0.0;
}


/* Scale on the passed band that restores the unfiltered variance;
 * depends only on (cutoff, order). */
double ocean_stats_redistribution(ocean *o, double kc, int order)
{
    int i = memo_find(o->redis_memo, kc, order, 1.0, 1.0);
    if (i >= 0)
        return o->redis_memo[i].value;
    double total, kept, err;
    filter_sums(o, kc, order, 1.0, 1.0, &total, &kept, &err);
    double v = kept > 0.0 ? sqrt(total / kept) : 1.0;
    memo_put(o->redis_memo, &o->redis_next, kc, order, 1.0, 1.0, v);
    return v;
}

/* E_error = ||H - H_f||_2 / ||H||_2 over the height spectrum, in
 * expectation (E|h(k,t)|^2 = var(k)), so it does not flicker with t and
 * counts the waves a smaller transform dropped. */
double ocean_stats_error(ocean *o, double kc, int order, double scale, double boost)
{
    if (isinf(kc) && scale == 1.0 && boost == 1.0)
        return 0.0;
    int i = memo_find(o->err_memo, kc, order, scale, boost);
    if (i >= 0)
        return o->err_memo[i].value;
    double total, kept, err;
    filter_sums(o, kc, order, scale, boost, &total, &kept, &err);
    double v = total > 0.0 ? sqrt(err / total) : 0.0;
    memo_put(o->err_memo, &o->err_next, kc, order, scale, boost, v);
    return v;
}

ocean_result ocean_cascade_mips(const ocean *o, int c, int order, int max_mips, int *mips, double *kc)
{
    if (!o || c < 0 || c >= o->p.cascades || order < 1 || order > OCEAN_FILTER_MAX_ORDER || max_mips < 1 ||
        !mips || !kc)
        return OCEAN_EINVAL;
    const ocean_cascade *cs = &o->cas[c];
    int m = 0;
    kc[m++] = INFINITY;
    for (int n = o->p.n / 2; n >= OCEAN_MIN_N && m < max_mips; n /= 2) {
        double k = (double)(n / 4) * cs->dk;
        /* no wave of the band survives: this mip and all coarser are empty */
        if (cs->k_lo >= ocean_negligible_k(o, k, order))
            break;
        kc[m++] = k;
    }
    *mips = m;
    return OCEAN_OK;
}

ocean_result ocean_cascade_moments(const ocean *o, int c, double kc, int order, ocean_moments *out)
{
    if (!o || !out || c < 0 || c >= o->p.cascades || isnan(kc) || kc < 0.0 || order < 1 ||
        order > OCEAN_FILTER_MAX_ORDER)
        return OCEAN_EINVAL;
    const ocean_cascade *cs = &o->cas[c];
    double kneg = ocean_negligible_k(o, kc, order);
    int n = o->p.n, half = n / 2 + 1;
    double vh = 0, sx = 0, sz = 0, sxz = 0, total = 0, kh = 0, khtt = 0, ks = 0, kstt = 0;
    /* each reading's power per |column| and |row| on the grid this cutoff
     * runs on (ocean_evaluate's) */
    double h = cs->patch / ocean_pick_size(cs, n, kneg), ap[OCEAN_INTERP_KERNELS][OCEAN_MAX_N / 2 + 1];
    for (int k = 0; k < OCEAN_INTERP_KERNELS; k++)
        ocean_interp_powers((ocean_interp)k, cs->dk * h, half, ap[k]);
    double kp[OCEAN_INTERP_KERNELS] = {0};
    for (int row = 0; row < n; row++) {
        double kz = (row < n / 2 ? row : row - n) * cs->dk;
        int mz = row < n / 2 ? row : n - row;
        for (int ix = 0; ix < half; ix++) {
            size_t i = (size_t)row * half + ix;
            if (cs->var[i] == 0.0f)
                continue;
            double w = (ix == 0 ? 1.0 : 2.0) * cs->var[i];
            double g = isinf(kc) ? 1.0 : effective_gain(cs->k[i], kc, order, kneg);
            double rem = w * (1.0 - g * g);
            double kx = cs->kx[ix];
            total += w;
            vh += rem;
            sx += rem * kx * kx;
            sz += rem * kz * kz;
            sxz += rem * kx * kz;
            double w2 = 2.0 * M_PI * (cs->turns_hi[i] + cs->turns_lo[i]), k2 = kx * kx + kz * kz;
            w2 *= w2;
            double kept = w * g * g;
            kh += kept;
            khtt += kept * w2 * w2;
            ks += kept * k2;
            kstt += kept * k2 * w2 * w2;
            for (int k = 0; k < OCEAN_INTERP_KERNELS; k++)
                kp[k] += kept * k2 * ap[k][ix] * ap[k][mz];
        }
    }
    for (int k = 0; k < OCEAN_INTERP_KERNELS; k++)
        out->kept_mss_read[k] = kp[k];
    out->kept_var_h = kh;
    out->kept_var_h_tt = khtt;
    out->kept_mss = ks;
    out->kept_mss_tt = kstt;
    out->var_h = vh;
    out->mss_x = sx;
    out->mss_z = sz;
    out->mss_xz = sxz;
    out->total_var_h = total;
    return OCEAN_OK;
}

double ocean_filtered_variance(const ocean *o, double cutoff_k, int order)
{
    double total, kept, err;
    filter_sums(o, cutoff_k, order, 1.0, 1.0, &total, &kept, &err);
    return kept;
}

void ocean_get_spectrum_stats(const ocean *o, ocean_spectrum_stats *out)
{
    memset(out, 0, sizeof *out);
    for (int c = 0; c < o->p.cascades; c++) {
        out->cascade_variance[c] = o->cas[c].variance;
        out->variance += o->cas[c].variance;
    }
    out->hs = 4.0 * sqrt(out->variance);
    out->wp = ocean_spectrum_peak(&o->p.sea);
    if (out->wp > 0.0) {
        out->tp = 2.0 * M_PI / out->wp;
        out->kp = ocean_wavenumber(out->wp, o->p.sea.depth_m);
        out->lambda_dominant = 2.0 * M_PI / out->kp;
    }
}
