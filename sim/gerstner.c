/*
 * gerstner.c - the Gerstner near field (see gerstner.h for the model, the
 * sampling and the partition with the FFT bands).
 */
#include "gerstner.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ocean.h"
#include "ocean_plan.h"
#include "ocean_time.h"
#include "wave_rng.h"

#define TWO_PI 6.283185307179586
/* 2 pi = TWO_PI_HI + TWO_PI_LO to about 1e-32 (Cody-Waite split). */
#define TWO_PI_HI 6.283185307179586232
#define TWO_PI_LO 2.4492935982947064e-16
#define THETA_BINS 1024
/* Points are evaluated relative to a 256 m cell corner: x - corner is
 * exact in double, and k.corner is reduced once per cell and wave. */
#define CELL_M 256.0

struct ocean_gerstner {
    ocean_gerstner_params p;
    int count;
    /* structure of arrays, count entries each */
    double *kx, *kz, *k, *hx, *hz, *omega, *amp, *phase;
    int *annulus, *sector, *mx, *mz;
};

void ocean_gerstner_params_default(ocean_gerstner_params *p)
{
    memset(p, 0, sizeof *p);
    ocean_sea_state_default(&p->sea);
    p->seed = 1;
    p->count = 256;
    p->annuli = 0;
    p->k_lo = TWO_PI / 8.0;
    p->k_hi = TWO_PI / 0.05;
    p->steepness_max = 1.0;
}

static ocean_result bad(char *msg, size_t msglen, const char *field, double v)
{
    if (msg != NULL && msglen > 0)
        snprintf(msg, msglen, "gerstner: %s = %g is out of range", field, v);
    return OCEAN_EINVAL;
}

ocean_result ocean_gerstner_params_validate(const ocean_gerstner_params *p, char *msg, size_t msglen)
{
    if (p == NULL)
        return OCEAN_EINVAL;
    ocean_result r = ocean_sea_state_validate(&p->sea, msg, msglen);
    if (r != OCEAN_OK)
        return r;
    /* the sea the FFT ocean refuses (ocean_plan.h: Hs beyond the breaking
     * height) is refused here too: 1 cm of water held a 2.2 m near field */
    ocean_plan plan;
    ocean_plan_init(&plan);
    ocean_plan_sea(&p->sea, &plan);
    for (int i = 0; i < plan.count; i++)
        if (plan.item[i].level == OCEAN_PLAN_REFUSE) {
            if (msg != NULL && msglen > 0) snprintf(msg, msglen, "gerstner: %s", plan.item[i].text);
            return OCEAN_EINVAL;
        }
    if (p->count < 0 || p->count > OCEAN_GERSTNER_MAX_WAVES)
        return bad(msg, msglen, "count", p->count);
    if (p->annuli < 0 || (p->count > 0 && p->annuli > p->count))
        return bad(msg, msglen, "annuli", p->annuli);
    if (!(p->steepness_max > 0.0 && p->steepness_max <= 1.0))
        return bad(msg, msglen, "steepness_max", p->steepness_max);
    if (!(p->lattice_m >= 0.0 && p->lattice_m <= 1e5))
        return bad(msg, msglen, "lattice_m", p->lattice_m);
    if (p->count > 0) {
        if (!(p->k_lo > 0.0) || !isfinite(p->k_lo))
            return bad(msg, msglen, "k_lo", p->k_lo);
        /* no wave faster than OCEAN_OMEGA_MAX: the time limit's phase bound */
        if (!(p->k_hi > p->k_lo))
            return bad(msg, msglen, "k_hi", p->k_hi);
        /* a snapped wave may lie up to half a lattice cell's diagonal above k_hi */
        double k_top = p->k_hi + (p->lattice_m > 0.0 ? M_SQRT2 * M_PI / p->lattice_m : 0.0);
        if (!(ocean_dispersion(k_top, p->sea.depth_m) <= OCEAN_OMEGA_MAX)) {
            if (msg != NULL && msglen > 0)
                snprintf(msg, msglen, "gerstner: k_hi = %g rad/m (%.3g m waves) is faster than "
                         "OCEAN_OMEGA_MAX = %g rad/s, the frequency the time limit is built on",
                         k_top, 2.0 * M_PI / k_top, OCEAN_OMEGA_MAX);
            return OCEAN_EINVAL;
        }
    }
    return OCEAN_OK;
}

void ocean_gerstner_destroy(ocean_gerstner *g)
{
    if (g == NULL)
        return;
    free(g->kx);
    free(g->annulus);
    free(g);
}

static const double gl8_x[4] = {0.1834346424956498, 0.5255324099163290,
                                0.7966664774136267, 0.9602898564975363};
static const double gl8_w[4] = {0.3626837833783620, 0.3137066458778873,
                                0.2223810344533745, 0.1012285362903763};

/* Radial Gauss-Legendre nodes of annulus [ka, kb] in u = ln k; returns
 * the count.  The area element k dk dtheta = k^2 du dtheta, so the weight
 * returned already holds k^2 du.  Panels end at the frequencies where the
 * spectra or spreading functions of spectrum.h are not smooth (w_p for
 * JONSWAP's sigma and the cos-2s exponents, 0.95 and 1.6 w_p for
 * Donelan-Banner, w_h = 1 and 2 for TMA), so Gauss-Legendre keeps its
 * order; elsewhere panels are at most 0.25 wide in ln k. */
#define MAX_RADIAL 1024
static int radial_nodes(const ocean_sea_state *sea, double ka, double kb, double *k, double *w)
{
    double cuts[8];
    int nc = 0;
    cuts[nc++] = log(ka);
    double wp = ocean_spectrum_peak(sea);
    double wbreak[5] = {wp, 0.95 * wp, 1.6 * wp, sqrt(OCEAN_G / sea->depth_m),
                        2.0 * sqrt(OCEAN_G / sea->depth_m)};
    for (int i = 0; i < 5; i++) {
        if (!(wbreak[i] > 0.0) || !isfinite(wbreak[i]))
            continue;
        double kbk = ocean_wavenumber(wbreak[i], sea->depth_m);
        if (kbk > ka && kbk < kb)
            cuts[nc++] = log(kbk);
    }
    cuts[nc++] = log(kb);
    /* sort the (few) interior cuts */
    for (int i = 1; i < nc - 1; i++)
        for (int j = i + 1; j < nc - 1; j++)
            if (cuts[j] < cuts[i]) {
                double tmp = cuts[i];
                cuts[i] = cuts[j];
                cuts[j] = tmp;
            }
    int n = 0;
    for (int c = 0; c + 1 < nc; c++) {
        double span = cuts[c + 1] - cuts[c];
        if (!(span > 0.0))
            continue;
        int panels = (int)ceil(span / 0.25);
        if (panels < 1)
            panels = 1;
        if (panels > (MAX_RADIAL - n) / 8 / (nc - 1 - c))
            panels = (MAX_RADIAL - n) / 8 / (nc - 1 - c);
        double du = span / panels;
        for (int pi = 0; pi < panels; pi++) {
            double mid = cuts[c] + (pi + 0.5) * du;
            for (int q = 0; q < 8; q++, n++) {
                double u = mid + (q < 4 ? -1.0 : 1.0) * gl8_x[q & 3] * 0.5 * du;
                k[n] = exp(u);
                w[n] = k[n] * k[n] * gl8_w[q & 3] * 0.5 * du;
            }
        }
    }
    return n;
}

/* The radial sum at direction th (world radians) over the annulus's rings
 * (the k nodes' spectrum and spreading, computed once per annulus). */
static double radial_sum(const ocean_sea_state *sea, double th, int n, const ocean_spectrum_ring *ring,
                         const double *w)
{
    ocean_spreading_dir dir;
    ocean_spreading_dir_at(sea->spreading, th - sea->wind_dir_deg * (M_PI / 180.0), &dir);
    double acc = 0.0;
    for (int i = 0; i < n; i++) {
        double f = ocean_spectrum_ring_f(&ring[i], &dir);
        if (f > 0.0 && isfinite(f))
            acc += f * w[i];
    }
    return acc;
}

/* Direction marginal of annulus [ka, kb] for the sampling: m[j] = the
 * variance in theta bin j (width 2 pi / THETA_BINS, midpoint rule).  Its
 * sum is only approximate (spreading functions have kinks and cusps: the
 * cos-2s cusp behind the wind, Tessendorf's edge at +-90 degrees); the
 * variance itself comes from annulus_variance. */
static void annulus_marginal(const ocean_sea_state *sea, int nr, const ocean_spectrum_ring *ring,
                             const double *w, double *m)
{
    double dth = TWO_PI / THETA_BINS;
    for (int j = 0; j < THETA_BINS; j++)
        m[j] = radial_sum(sea, -M_PI + (j + 0.5) * dth, nr, ring, w) * dth;
}

/* The annulus variance int int F k dk dtheta: tanh-sinh (double
 * exponential) quadrature in theta on the four quarters between the
 * directions where spreading functions are not smooth (0, +-90, 180
 * degrees from the wind), which is exact to ~1e-13 despite the cusps;
 * Gauss-Legendre in ln k. */
static double annulus_variance(const ocean_sea_state *sea, int nr, const ocean_spectrum_ring *ring,
                               const double *w)
{
    const double h = 1.0 / 16.0, tmax = 3.5;
    double wind = sea->wind_dir_deg * (M_PI / 180.0), total = 0.0;
    for (int q = 0; q < 4; q++) {
        double a = wind - M_PI + q * (M_PI / 2), half = M_PI / 4, mid = a + half;
        double acc = 0.0;
        for (double t = -tmax; t <= tmax + 1e-9; t += h) {
            double sh = M_PI_2 * sinh(t), ch = cosh(sh);
            double x = tanh(sh);
            double wt = M_PI_2 * cosh(t) / (ch * ch);
            if (wt < 1e-300)
                continue;
            acc += wt * radial_sum(sea, mid + half * x, nr, ring, w);
        }
        total += acc * half * h;
    }
    return total;
}

/* Moves wave w onto the lattice 2 pi (i, j) / L (gerstner.h "Lattice"):
 * the nearest lattice point to its drawn wave vector that no earlier wave
 * holds, within max(|i|, |j|) <= top.  Two waves on one point would be one
 * wave of amplitude |a1 + a2| (its variance is not a1^2/2 + a2^2/2), so a
 * taken point sends the wave to the nearest free one.  The wave vector is
 * rebuilt from the integer indices, so an FFT of the L patch holds exactly
 * this wave. */
static void snap(ocean_gerstner *g, int w, double L, long top)
{
    double dk = TWO_PI / L, ux = g->kx[w] / dk, uz = g->kz[w] / dk;
    long cx = lround(ux), cz = lround(uz), bx = cx, bz = cz;
    for (long r = 0; r <= 16; r++) {
        double best = INFINITY;
        for (long i = cx - r; i <= cx + r; i++)
            for (long j = cz - r; j <= cz + r; j++) {
                if (labs(i - cx) != r && labs(j - cz) != r)
                    continue; /* inside: seen at a smaller r */
                if ((i == 0 && j == 0) || labs(i) > top || labs(j) > top)
                    continue;
                int taken = 0;
                for (int q = 0; q < w && !taken; q++)
                    taken = g->mx[q] == i && g->mz[q] == j;
                double d = (i - ux) * (i - ux) + (j - uz) * (j - uz);
                if (!taken && d < best) {
                    best = d;
                    bx = i;
                    bz = j;
                }
            }
        if (best < INFINITY)
            break;
    }
    g->mx[w] = (int)bx;
    g->mz[w] = (int)bz;
    g->kx[w] = (double)bx * dk;
    g->kz[w] = (double)bz * dk;
    g->k[w] = hypot(g->kx[w], g->kz[w]);
    g->hx[w] = g->kx[w] / g->k[w];
    g->hz[w] = g->kz[w] / g->k[w];
}

double ocean_gerstner_lattice_for(int n, double k_hi)
{
    if (n < 8 || !(k_hi > 0.0) || !isfinite(k_hi))
        return NAN;
    return (n / 2 - 1) * TWO_PI / k_hi;
}

void ocean_gerstner_near_cut(struct ocean_params *p, int count)
{
    if (count <= 0 || isfinite(p->k_max))
        return;
    double finest = p->patch_m / pow(p->cascade_ratio, p->cascades - 1);
    p->k_max = M_PI * p->n / finest;
}

int ocean_gerstner_near_params(const struct ocean_params *p, int count, double min_wavelength,
                               ocean_gerstner_params *gp)
{
    ocean_gerstner_params_default(gp);
    double k_hi = TWO_PI / min_wavelength;
    if (count <= 0 || !isfinite(p->k_max) || !(k_hi > p->k_max * 1.01))
        return 0;
    gp->sea = p->sea;
    gp->seed = p->seed;
    gp->count = count;
    gp->k_lo = p->k_max;
    gp->k_hi = k_hi;
    /* snapped to the lattice of a periodic patch whose n-point grid holds
     * the shortest wave, so layout 1 carries the set as one more cascade
     * (see "Lattice" above); meshes and queries use the same snapped waves */
    gp->lattice_m = ocean_gerstner_lattice_for(p->n, k_hi);
    return 1;
}

/* Inverse of the tabulated direction CDF (piecewise linear in theta):
 * the theta at which the cumulative variance reaches target. */
static double invert_cdf(const double *cdf, double target)
{
    /* cdf[0] = 0 .. cdf[THETA_BINS] = total, non-decreasing */
    int lo = 0, hi = THETA_BINS;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (cdf[mid] <= target)
            lo = mid;
        else
            hi = mid;
    }
    double w = cdf[lo + 1] - cdf[lo];
    double frac = w > 0.0 ? (target - cdf[lo]) / w : 0.5;
    frac = fmin(fmax(frac, 0.0), 1.0);
    return -M_PI + (lo + frac) * (TWO_PI / THETA_BINS);
}

ocean_result ocean_gerstner_create(const ocean_gerstner_params *p, ocean_gerstner **out,
                                   char *msg, size_t msglen)
{
    if (out == NULL)
        return OCEAN_EINVAL;
    *out = NULL;
    ocean_result r = ocean_gerstner_params_validate(p, msg, msglen);
    if (r != OCEAN_OK)
        return r;

    ocean_gerstner *g = calloc(1, sizeof *g);
    if (g == NULL)
        return OCEAN_ENOMEM;
    g->p = *p;
    int M = p->count;
    g->count = M;
    size_t n = M > 0 ? (size_t)M : 1;
    g->kx = malloc(8 * n * sizeof(double));
    g->annulus = calloc(4 * n, sizeof(int));
    double *m = malloc((2 * THETA_BINS + 1) * sizeof(double));
    ocean_spectrum_ring *ring = malloc(MAX_RADIAL * sizeof *ring);
    if (g->kx == NULL || g->annulus == NULL || m == NULL || ring == NULL) {
        free(m);
        free(ring);
        ocean_gerstner_destroy(g);
        return OCEAN_ENOMEM;
    }
    g->kz = g->kx + n;
    g->k = g->kz + n;
    g->hx = g->k + n;
    g->hz = g->hx + n;
    g->omega = g->hz + n;
    g->amp = g->omega + n;
    g->phase = g->amp + n;
    g->sector = g->annulus + n;
    g->mx = g->sector + n;
    g->mz = g->mx + n;
    double *cdf = m + THETA_BINS;

    if (M > 0) {
        int R = p->annuli;
        if (R == 0) {
            R = (int)lround(sqrt((double)M) / 2.0);
            if (R < 1)
                R = 1;
        }
        g->p.annuli = R;
        double lspan = log(p->k_hi / p->k_lo);
        /* lattice indices stay within the band's top (|i| dk <= k_hi):
         * with ocean_gerstner_lattice_for's L that is n/2 - 1 */
        long top = p->lattice_m > 0.0 ? (long)floor(p->k_hi * p->lattice_m / TWO_PI + 1e-9) : 0;
        int w = 0;
        for (int a = 0; a < R; a++) {
            double ka = a == 0 ? p->k_lo : p->k_lo * exp(lspan * a / R);
            double kb = a == R - 1 ? p->k_hi : p->k_lo * exp(lspan * (a + 1) / R);
            int ma = M / R + (a < M % R ? 1 : 0);
            double rk[MAX_RADIAL], rw[MAX_RADIAL];
            int nr = radial_nodes(&p->sea, ka, kb, rk, rw);
            for (int i = 0; i < nr; i++)
                ocean_spectrum_ring_at(&p->sea, rk[i], &ring[i]);
            annulus_marginal(&p->sea, nr, ring, rw, m);
            cdf[0] = 0.0;
            for (int j = 0; j < THETA_BINS; j++)
                cdf[j + 1] = cdf[j] + m[j];
            double v = annulus_variance(&p->sea, nr, ring, rw);
            double vt = cdf[THETA_BINS];
            double amp = sqrt(2.0 * v / ma);
            for (int s = 0; s < ma; s++, w++) {
                double u[2], ph[2];
                ocean_rng_uniform2(p->seed, OCEAN_RNG_GERSTNER, 0, a, s, u);
                ocean_rng_uniform2(p->seed, OCEAN_RNG_GERSTNER, 1, a, s, ph);
                double k = ka * exp(u[0] * log(kb / ka));
                if (k >= kb) /* rounding must not leave the half-open cell */
                    k = nextafter(kb, 0.0);
                if (k < ka)
                    k = ka;
                double th;
                if (vt > 0.0)
                    th = invert_cdf(cdf, vt * ((s + u[1]) / ma));
                else
                    th = -M_PI + TWO_PI * (s + u[1]) / ma;
                g->k[w] = k;
                g->hx[w] = cos(th);
                g->hz[w] = sin(th);
                g->kx[w] = k * g->hx[w];
                g->kz[w] = k * g->hz[w];
                if (p->lattice_m > 0.0)
                    snap(g, w, p->lattice_m, top);
                k = g->k[w];
                g->omega[w] = ocean_dispersion(k, p->sea.depth_m);
                g->amp[w] = amp;
                g->phase[w] = TWO_PI * ph[0];
                g->annulus[w] = a;
                g->sector[w] = s;
            }
        }
    }
    free(m);
    free(ring);
    *out = g;
    return OCEAN_OK;
}

ocean_result ocean_gerstner_cascade_create(const ocean_gerstner *g, const ocean_params *p,
                                           ocean **out, char *msg, size_t msglen)
{
    if (out)
        *out = NULL;
    if (!g || !p || !out || !(g->p.lattice_m > 0.0)) {
        if (msg && msglen > 0)
            snprintf(msg, msglen, "gerstner: the near-field cascade needs a set snapped to a lattice "
                     "(lattice_m > 0)");
        return OCEAN_EINVAL;
    }
    ocean_gerstner_view v;
    ocean_gerstner_view_default(&v);
    double q;
    ocean_result r = ocean_gerstner_effective_q(g, &v, &q, NULL);
    if (r != OCEAN_OK)
        return r;
    ocean_lattice_wave *w = malloc(sizeof *w * (size_t)(g->count > 0 ? g->count : 1));
    if (!w)
        return OCEAN_ENOMEM;
    for (int i = 0; i < g->count; i++)
        w[i] = (ocean_lattice_wave){g->mx[i], g->mz[i], g->amp[i], g->phase[i]};
    ocean_params lp = *p;
    lp.sea = g->p.sea;
    lp.sea.choppiness = q;
    r = ocean_create_lattice(&lp, g->p.lattice_m, w, g->count, out, msg, msglen);
    free(w);
    return r;
}

int ocean_gerstner_count(const ocean_gerstner *g)
{
    return g ? g->count : 0;
}

const ocean_gerstner_params *ocean_gerstner_get_params(const ocean_gerstner *g)
{
    return &g->p;
}

ocean_result ocean_gerstner_get_wave(const ocean_gerstner *g, int i, ocean_gerstner_wave *out)
{
    if (g == NULL || out == NULL || i < 0 || i >= g->count)
        return OCEAN_EINVAL;
    out->kx = g->kx[i];
    out->kz = g->kz[i];
    out->k = g->k[i];
    out->omega = g->omega[i];
    out->amplitude = g->amp[i];
    out->phase = g->phase[i];
    out->annulus = g->annulus[i];
    out->sector = g->sector[i];
    out->mx = g->mx[i];
    out->mz = g->mz[i];
    return OCEAN_OK;
}

static double wave_gain(const ocean_filter_cutoff *c, double k)
{
    if (c == NULL || isinf(c->k))
        return 1.0;
    return ocean_filter_cutoff_gain(c, k);
}

double ocean_gerstner_variance(const ocean_gerstner *g, const ocean_filter_cutoff *c)
{
    double v = 0.0;
    for (int i = 0; i < g->count; i++) {
        double a = wave_gain(c, g->k[i]) * g->amp[i];
        v += 0.5 * a * a;
    }
    return v;
}

void ocean_gerstner_view_default(ocean_gerstner_view *v)
{
    memset(v, 0, sizeof *v);
    v->fade_r0 = INFINITY;
    v->fade_r1 = INFINITY;
    v->filter.k = INFINITY;
    v->filter.hz = NAN;
    v->filter.low_boost = 1.0;
    v->filter.order = OCEAN_FILTER_DEFAULT_ORDER;
}

static int view_ok(const ocean_gerstner_view *v)
{
    if (!isfinite(v->camera_x) || !isfinite(v->camera_z))
        return 0;
    int nofade = isinf(v->fade_r0) && v->fade_r0 > 0 && isinf(v->fade_r1) && v->fade_r1 > 0;
    if (!nofade && !(v->fade_r0 >= 0.0 && v->fade_r1 > v->fade_r0 && isfinite(v->fade_r1)))
        return 0;
    if (isnan(v->filter.k) || v->filter.k < 0.0)
        return 0;
    if (!isinf(v->filter.k)) {
        if (v->filter.order < 1 || v->filter.order > OCEAN_FILTER_MAX_ORDER)
            return 0;
        if (!(v->filter.low_boost >= 0.0 && v->filter.low_boost <= 2.0))
            return 0;
    }
    return 1;
}

/* Largest |grad f| of the fade: smoothstep over width w peaks at 1.5 / w. */
static double fade_grad_max(const ocean_gerstner_view *v)
{
    return isinf(v->fade_r1) ? 0.0 : 1.5 / (v->fade_r1 - v->fade_r0);
}

/* Effective amplitudes a_i = g_i A_i and the clamped Q. */
static void prepare(const ocean_gerstner *g, const ocean_gerstner_view *v, double *a,
                    double *q_out, double *steep_out)
{
    double gf = fade_grad_max(v), bound = 0.0, steep1 = 0.0;
    for (int i = 0; i < g->count; i++) {
        a[i] = wave_gain(&v->filter, g->k[i]) * g->amp[i];
        bound += a[i] * (g->k[i] + gf);
        steep1 += a[i] * g->k[i];
    }
    double q = g->p.sea.choppiness;
    if (q * bound > g->p.steepness_max)
        q = g->p.steepness_max / bound;
    *q_out = q;
    if (steep_out)
        *steep_out = q * steep1;
}

ocean_result ocean_gerstner_effective_q(const ocean_gerstner *g, const ocean_gerstner_view *v,
                                        double *q, double *steepness)
{
    if (g == NULL || v == NULL || q == NULL || !view_ok(v))
        return OCEAN_EINVAL;
    double a[OCEAN_GERSTNER_MAX_WAVES];
    double s;
    prepare(g, v, a, q, &s);
    if (steepness)
        *steepness = s;
    return OCEAN_OK;
}

/* (a * b) mod 2 pi, accurate to a few ulp of pi for |a b| up to ~1e15:
 * the product's rounding error is recovered with fma, and the reduction
 * uses the two-part 2 pi. */
static double mulmod_2pi(double a, double b)
{
    double p = a * b;
    double e = fma(a, b, -p);
    double q = nearbyint(p * (1.0 / TWO_PI_HI));
    double r = fma(-q, TWO_PI_HI, p);
    r = fma(-q, TWO_PI_LO, r);
    return r + e;
}

static double wrap_2pi(double x)
{
    double q = nearbyint(x * (1.0 / TWO_PI_HI));
    return fma(-q, TWO_PI_HI, x) - q * TWO_PI_LO;
}

/* sin and cos of many phases at once, vectorisable (libm's sincos is a
 * call per wave and dominated the evaluation).  Reduction by pi/2 in four
 * parts, the first three with 27 significant bits so q * P1..P3 are exact
 * for |q| < 2^26 (|th| < 1e8 rad, far beyond the 2e7 a 256 m cell and
 * k <= 1e5 rad/m can reach); then fdlibm's kernel polynomials on
 * [-pi/4, pi/4] (error < 1e-16) and the quadrant's swap/sign. */
#define PIO2_1 1.570796325802803
#define PIO2_2 9.920935739593517e-10
#define PIO2_3 5.721188709663575e-18
#define PIO2_4 1.6446256936324258e-26
static void sincos_many(const double *th, double *sn, double *cs, int n)
{
#pragma omp simd
    for (int i = 0; i < n; i++) {
        /* round to nearest by the 1.5 * 2^52 trick: vectorises without SSE4.1 */
        double q = (th[i] * M_2_PI + 6755399441055744.0) - 6755399441055744.0;
        double r = th[i] - q * PIO2_1;
        r -= q * PIO2_2;
        r -= q * PIO2_3;
        r -= q * PIO2_4;
        double z = r * r;
        double ps = r + r * z * (-1.66666666666666324348e-01 + z * (8.33333333332248946124e-03 +
                    z * (-1.98412698298579493134e-04 + z * (2.75573137070700676789e-06 +
                    z * (-2.50507602534068634195e-08 + z * 1.58969099521155010221e-10)))));
        double pc = 1.0 - 0.5 * z + z * z * (4.16666666666666019037e-02 +
                    z * (-1.38888888888741095749e-03 + z * (2.48015872894767294178e-05 +
                    z * (-2.75573143513906633035e-07 + z * (2.08757232129817482790e-09 +
                    z * -1.13596475577881948265e-11)))));
        int qi = (int)q;
        int swap = qi & 1;
        double s = swap ? pc : ps, c = swap ? ps : pc;
        sn[i] = (qi & 2) ? -s : s;
        cs[i] = ((qi + 1) & 2) ? -c : c;
    }
}

/* Fade and its gradient at (x, z). */
static double fade_at(const ocean_gerstner_view *v, double x, double z, double *fx, double *fz)
{
    *fx = *fz = 0.0;
    if (isinf(v->fade_r1))
        return 1.0;
    double ex = x - v->camera_x, ez = z - v->camera_z;
    double r = hypot(ex, ez);
    if (r <= v->fade_r0)
        return 1.0;
    if (r >= v->fade_r1)
        return 0.0;
    double w = v->fade_r1 - v->fade_r0;
    double s = (v->fade_r1 - r) / w;
    double dfdr = -6.0 * s * (1.0 - s) / w;
    *fx = dfdr * ex / r;
    *fz = dfdr * ez / r;
    return s * s * (3.0 - 2.0 * s);
}

/* Everything a (view, t) pair fixes: gains, Q, phi - w t, and the
 * phases of k . corner for the last few 256 m cells (2 x 2 slots indexed
 * by the cells' parities, so points around a camera near a cell corner do
 * not thrash).  The one-shot evaluate keeps it on the stack with one
 * slot; an ocean_gerstner_frame keeps it on the heap. */
#define CELL_SLOTS 4
typedef struct eval_state {
    const ocean_gerstner *g;
    ocean_gerstner_view view;
    double t, q;
    int slots;
    double cell_x[CELL_SLOTS], cell_z[CELL_SLOTS];
    double a[OCEAN_GERSTNER_MAX_WAVES];
    double tphase[OCEAN_GERSTNER_MAX_WAVES];
    double *base; /* slots x OCEAN_GERSTNER_MAX_WAVES */
} eval_state;

void ocean_gerstner_foam_moments(const ocean_gerstner *g, const ocean_gerstner_view *v, double *m0, double *m1)
{
    double a[OCEAN_GERSTNER_MAX_WAVES], q = 0.0, s0 = 0.0, s1 = 0.0;
    prepare(g, v, a, &q, NULL);
    for (int i = 0; i < g->count; i++) {
        double c = q * a[i] * g->k[i], var = 0.5 * c * c;
        s0 += var;
        s1 += var * g->omega[i];
    }
    *m0 = s0;
    *m1 = s1;
}

/* slots: 1 or CELL_SLOTS, st->base must hold that many arrays. */
static void state_set(eval_state *st, const ocean_gerstner *g, const ocean_gerstner_view *v,
                      double t, int slots)
{
    st->g = g;
    st->view = *v;
    st->t = t;
    st->slots = slots;
    for (int i = 0; i < CELL_SLOTS; i++)
        st->cell_x[i] = st->cell_z[i] = NAN;
    prepare(g, v, st->a, &st->q, NULL);
    for (int i = 0; i < g->count; i++)
        st->tphase[i] = wrap_2pi(g->phase[i] - mulmod_2pi(g->omega[i], t));
}

static const double *cell_base(eval_state *st, double cx, double cz)
{
    int slot = 0;
    if (st->slots > 1) {
        long ix = (long)(cx / CELL_M), iz = (long)(cz / CELL_M);
        slot = (int)((ix & 1) | ((iz & 1) << 1));
    }
    double *base = st->base + (size_t)slot * OCEAN_GERSTNER_MAX_WAVES;
    if (st->cell_x[slot] != cx || st->cell_z[slot] != cz) {
        const ocean_gerstner *g = st->g;
        for (int i = 0; i < g->count; i++)
            base[i] = st->tphase[i] + mulmod_2pi(g->kx[i], cx) + mulmod_2pi(g->kz[i], cz);
        st->cell_x[slot] = cx;
        st->cell_z[slot] = cz;
    }
    return base;
}

static int points_ok(const double *x, const double *z, size_t n, const void *out)
{
    if (n > 0 && (x == NULL || z == NULL || out == NULL))
        return 0;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(x[i]) || !isfinite(z[i]) || fabs(x[i]) > 1e12 || fabs(z[i]) > 1e12)
            return 0;
    return 1;
}

/* The eleven sums over the waves at one point, the fade not yet
 * applied: eta, grad eta, D, grad D, dD/dt and d eta/dt. */
typedef struct wave_sums {
    double C, Sx, Sz, Dx, Dz, Dxx, Dxz, Dzz, Vx, Vy, Vz, Bq;
} wave_sums;

/* The sums at offset (ux, uz) from the cell whose phases are base.
 * Phases, then sin/cos of all of them, then the sums; each stage is a
 * simple loop the compiler vectorises. */
static void point_sums(const eval_state *st, const double *base, double ux, double uz, wave_sums *s)
{
    const ocean_gerstner *g = st->g;
    int M = g->count;
    const double *a = st->a;
    double q = st->q;
    double th[OCEAN_GERSTNER_MAX_WAVES], sn[OCEAN_GERSTNER_MAX_WAVES];
    double cs[OCEAN_GERSTNER_MAX_WAVES];
    for (int i = 0; i < M; i++)
        th[i] = base[i] + g->kx[i] * ux + g->kz[i] * uz;
    sincos_many(th, sn, cs, M);
    /* Twelve sums in two interleaved lanes (even/odd waves), which the
     * compiler packs into one SSE2 register each. */
    double acc[12][2] = {{0}};
    int m2 = M & ~1;
    for (int i = 0; i < m2; i += 2) {
        for (int l = 0; l < 2; l++) {
            int j = i + l;
            double ai = a[j], as = ai * sn[j], qc = q * ai * cs[j], qs = q * ai * sn[j];
            double w = g->omega[j];
            acc[0][l] += ai * cs[j];
            acc[1][l] += as * g->kx[j];
            acc[2][l] += as * g->kz[j];
            acc[3][l] += qs * g->hx[j];
            acc[4][l] += qs * g->hz[j];
            acc[5][l] += qc * (g->hx[j] * g->kx[j]);
            acc[6][l] += qc * (g->hx[j] * g->kz[j]);
            acc[7][l] += qc * (g->hz[j] * g->kz[j]);
            acc[8][l] += as * w;
            acc[9][l] += qc * w * g->hx[j];
            acc[10][l] += qc * w * g->hz[j];
            acc[11][l] += qs * g->k[j];
        }
    }
    for (int j = m2; j < M; j++) {
        double ai = a[j], as = ai * sn[j], qc = q * ai * cs[j], qs = q * ai * sn[j];
        double w = g->omega[j];
        acc[0][0] += ai * cs[j];
        acc[1][0] += as * g->kx[j];
        acc[2][0] += as * g->kz[j];
        acc[3][0] += qs * g->hx[j];
        acc[4][0] += qs * g->hz[j];
        acc[5][0] += qc * (g->hx[j] * g->kx[j]);
        acc[6][0] += qc * (g->hx[j] * g->kz[j]);
        acc[7][0] += qc * (g->hz[j] * g->kz[j]);
        acc[8][0] += as * w;
        acc[9][0] += qc * w * g->hx[j];
        acc[10][0] += qc * w * g->hz[j];
        acc[11][0] += qs * g->k[j];
    }
    /* Signs: eta = sum a cos; grad eta = -sum a k sin; D = -sum Q a h
     * sin; grad D = -sum Q a h k cos (hx kz = hz kx); dD/dt = +sum Q a
     * h w cos; d eta/dt = +sum a w sin.  Bq: with the phase falling in
     * time, cos's quadrature (foam.h) is -sin, so -(Dxx + Dzz) = sum Q a k
     * cos has the quadrature -sum Q a k sin, and bq (its negative) is
     * +sum Q a k sin. */
    s->C = acc[0][0] + acc[0][1];
    s->Sx = -(acc[1][0] + acc[1][1]);
    s->Sz = -(acc[2][0] + acc[2][1]);
    s->Dx = -(acc[3][0] + acc[3][1]);
    s->Dz = -(acc[4][0] + acc[4][1]);
    s->Dxx = -(acc[5][0] + acc[5][1]);
    s->Dxz = -(acc[6][0] + acc[6][1]);
    s->Dzz = -(acc[7][0] + acc[7][1]);
    s->Vy = acc[8][0] + acc[8][1];
    s->Vx = acc[9][0] + acc[9][1];
    s->Vz = acc[10][0] + acc[10][1];
    s->Bq = acc[11][0] + acc[11][1];
}

/* The point from its sums and the fade f (gradient fx, fz), whose own
 * slope enters every derivative. */
static void point_set(ocean_gerstner_point *o, double f, double fx, double fz, const wave_sums *s)
{
    o->dy = f * s->C;
    o->dx = f * s->Dx;
    o->dz = f * s->Dz;
    o->vx = f * s->Vx;
    o->vy = f * s->Vy;
    o->vz = f * s->Vz;
    double ex = f * s->Sx + fx * s->C, ez = f * s->Sz + fz * s->C; /* d eta/dx, d eta/dz */
    double dxx = f * s->Dxx + fx * s->Dx, dxz = f * s->Dxz + fz * s->Dx; /* dDx/dx, dDx/dz */
    double dzx = f * s->Dxz + fx * s->Dz, dzz = f * s->Dzz + fz * s->Dz; /* dDz/dx, dDz/dz */
    double J = (1.0 + dxx) * (1.0 + dzz) - dxz * dzx;
    o->jacobian = J;
    o->slope_x = ex;
    o->slope_z = ez;
    o->dxx = dxx;
    o->dxz = dxz;
    o->dzx = dzx;
    o->dzz = dzz;
    /* the fade's own gradient terms of dxx + dzz are left out of the
     * quadrature: under 1 / (k times the fade's width) of it */
    o->bq = f * s->Bq;
    /* N = T_z x T_x with T_x = (1+dxx, ex, dzx), T_z = (dxz, ez, 1+dzz). */
    double nx = ez * dzx - (1.0 + dzz) * ex;
    double ny = J;
    double nz = dxz * ex - ez * (1.0 + dxx);
    double len = sqrt(nx * nx + ny * ny + nz * nz);
    if (len > 0.0 && isfinite(len)) {
        o->nx = nx / len;
        o->ny = ny / len;
        o->nz = nz / len;
    }
}

static void evaluate_points(eval_state *st, const double *x, const double *z, size_t n,
                            ocean_gerstner_point *out)
{
    int M = st->g->count;
    for (size_t p = 0; p < n; p++) {
        ocean_gerstner_point *o = &out[p];
        double fx, fz;
        double f = fade_at(&st->view, x[p], z[p], &fx, &fz);
        memset(o, 0, sizeof *o);
        o->ny = 1.0;
        o->jacobian = 1.0;
        o->fade = f;
        if (f == 0.0 || M == 0)
            continue;
        double cx = CELL_M * nearbyint(x[p] / CELL_M), cz = CELL_M * nearbyint(z[p] / CELL_M);
        const double *base = cell_base(st, cx, cz);
        wave_sums s;
        point_sums(st, base, x[p] - cx, z[p] - cz, &s); /* offsets exact */
        point_set(o, f, fx, fz, &s);
    }
}

ocean_result ocean_gerstner_evaluate(const ocean_gerstner *g, const ocean_gerstner_view *v,
                                     double t, const double *x, const double *z, size_t n,
                                     ocean_gerstner_point *out)
{
    if (g == NULL || v == NULL || !view_ok(v) || !ocean_time_ok(t) || !points_ok(x, z, n, out))
        return OCEAN_EINVAL;
    eval_state st;
    double base[OCEAN_GERSTNER_MAX_WAVES];
    st.base = base;
    state_set(&st, g, v, t, 1);
    evaluate_points(&st, x, z, n, out);
    return OCEAN_OK;
}

struct ocean_gerstner_frame {
    eval_state st;
    int ready;
};

ocean_result ocean_gerstner_frame_create(const ocean_gerstner *g, ocean_gerstner_frame **out)
{
    if (out == NULL)
        return OCEAN_EINVAL;
    *out = NULL;
    if (g == NULL)
        return OCEAN_EINVAL;
    ocean_gerstner_frame *f = calloc(1, sizeof *f);
    double *base = malloc(sizeof(double) * CELL_SLOTS * OCEAN_GERSTNER_MAX_WAVES);
    if (f == NULL || base == NULL) {
        free(f);
        free(base);
        return OCEAN_ENOMEM;
    }
    f->st.g = g;
    f->st.base = base;
    *out = f;
    return OCEAN_OK;
}

void ocean_gerstner_frame_destroy(ocean_gerstner_frame *f)
{
    if (f == NULL)
        return;
    free(f->st.base);
    free(f);
}

ocean_result ocean_gerstner_frame_set(ocean_gerstner_frame *f, const ocean_gerstner_view *v,
                                      double t)
{
    if (f == NULL || v == NULL || !view_ok(v) || !ocean_time_ok(t))
        return OCEAN_EINVAL;
    state_set(&f->st, f->st.g, v, t, CELL_SLOTS);
    f->ready = 1;
    return OCEAN_OK;
}

ocean_result ocean_gerstner_frame_evaluate(ocean_gerstner_frame *f, const double *x,
                                           const double *z, size_t n, ocean_gerstner_point *out)
{
    if (f == NULL || !points_ok(x, z, n, out))
        return OCEAN_EINVAL;
    if (!f->ready)
        return OCEAN_ESTATE;
    evaluate_points(&f->st, x, z, n, out);
    return OCEAN_OK;
}

ocean_result ocean_gerstner_frame_displacement(ocean_gerstner_frame *f, const double *x,
                                               const double *z, size_t n, double *out)
{
    if (f == NULL || !points_ok(x, z, n, out))
        return OCEAN_EINVAL;
    if (!f->ready)
        return OCEAN_ESTATE;
    eval_state *st = &f->st;
    const ocean_gerstner *g = st->g;
    int M = g->count;
    const double *a = st->a;
    double q = st->q;
    for (size_t p = 0; p < n; p++) {
        double fx, fz;
        double fv = fade_at(&st->view, x[p], z[p], &fx, &fz);
        out[3 * p] = out[3 * p + 1] = out[3 * p + 2] = 0.0;
        if (fv == 0.0 || M == 0)
            continue;
        double cx = CELL_M * nearbyint(x[p] / CELL_M), cz = CELL_M * nearbyint(z[p] / CELL_M);
        const double *base = cell_base(st, cx, cz);
        double ux = x[p] - cx, uz = z[p] - cz;
        double th[OCEAN_GERSTNER_MAX_WAVES], sn[OCEAN_GERSTNER_MAX_WAVES];
        double cs[OCEAN_GERSTNER_MAX_WAVES];
        for (int i = 0; i < M; i++)
            th[i] = base[i] + g->kx[i] * ux + g->kz[i] * uz;
        sincos_many(th, sn, cs, M);
        /* the same two interleaved lanes as evaluate_points, so the sums
         * round alike */
        double acc[3][2] = {{0}};
        int m2 = M & ~1;
        for (int i = 0; i < m2; i += 2)
            for (int l = 0; l < 2; l++) {
                int j = i + l;
                double ai = a[j], qs = q * ai * sn[j];
                acc[0][l] += ai * cs[j];
                acc[1][l] += qs * g->hx[j];
                acc[2][l] += qs * g->hz[j];
            }
        for (int j = m2; j < M; j++) {
            double ai = a[j], qs = q * ai * sn[j];
            acc[0][0] += ai * cs[j];
            acc[1][0] += qs * g->hx[j];
            acc[2][0] += qs * g->hz[j];
        }
        out[3 * p] = fv * -(acc[1][0] + acc[1][1]);
        out[3 * p + 1] = fv * (acc[0][0] + acc[0][1]);
        out[3 * p + 2] = fv * -(acc[2][0] + acc[2][1]);
    }
    return OCEAN_OK;
}

/* ---- grids -------------------------------------------------------------- */

static int grid_ok(const ocean_gerstner_grid *g)
{
    if (g == NULL || !isfinite(g->x0) || !isfinite(g->z0) || fabs(g->x0) > 1e12 ||
        fabs(g->z0) > 1e12 || !(g->spacing > 0.0) || !isfinite(g->spacing))
        return 0;
    if (g->w < 1 || g->h < 1 || g->w > OCEAN_GERSTNER_GRID_MAX || g->h > OCEAN_GERSTNER_GRID_MAX ||
        g->stride < (size_t)g->w)
        return 0;
    /* the far corner must stay in range too */
    double span = g->spacing * (g->w > g->h ? g->w : g->h);
    return isfinite(span) && fabs(g->x0) + span <= 1e12 && fabs(g->z0) + span <= 1e12;
}

static void grid_store(float *plane, size_t at, double v, int acc)
{
    if (plane == NULL)
        return;
    plane[at] = acc ? (float)(plane[at] + v) : (float)v;
}

/* Row r of every plane to zero (planes a grid does not accumulate into). */
static void grid_clear_row(const ocean_gerstner_grid *g, int r)
{
    for (int j = 0; j < g->w; j++) {
        size_t at = (size_t)r * g->stride + j;
        grid_store(g->height, at, 0, 0); grid_store(g->dx, at, 0, 0);
        grid_store(g->dz, at, 0, 0); grid_store(g->slope_x, at, 0, 0);
        grid_store(g->slope_z, at, 0, 0); grid_store(g->dxx, at, 0, 0);
        grid_store(g->dzz, at, 0, 0); grid_store(g->dxz, at, 0, 0);
    }
}

/* The waves a grid evaluation sums (those the filter left), packed: each
 * one's coefficient in every plane, its wave vector and its phase at
 * sample (0, 0); with the row factor and the w column factors
 * e^{i k.x}. */
typedef struct grid_work {
    int M;
    size_t mm;
    double *ca, *cdx, *cdz, *csx, *csz, *cxx, *cxz, *czz;   /* coefficients */
    double *rc, *rs;        /* the row's factor, cos and sin */
    double *colc, *cols;    /* column j's factor at [mm * j] */
    double *th, *kx, *kz;   /* phase scratch, wave vectors */
    double *row0;           /* phase at sample (0, 0) */
    double *buf;
} grid_work;

static ocean_result grid_work_alloc(grid_work *gw, int M, int w)
{
    size_t mm = (size_t)M;
    gw->M = M;
    gw->mm = mm;
    /* coefficient planes (8), row factor (2), column factors (2 w) */
    gw->buf = malloc(sizeof(double) * mm * (8 + 2 + 2 * (size_t)w + 3));
    gw->row0 = malloc(sizeof(double) * mm);
    if (gw->buf == NULL || gw->row0 == NULL) {
        free(gw->buf);
        free(gw->row0);
        return OCEAN_ENOMEM;
    }
    gw->ca = gw->buf;
    gw->cdx = gw->ca + mm;
    gw->cdz = gw->cdx + mm;
    gw->csx = gw->cdz + mm;
    gw->csz = gw->csx + mm;
    gw->cxx = gw->csz + mm;
    gw->cxz = gw->cxx + mm;
    gw->czz = gw->cxz + mm;
    gw->rc = gw->czz + mm;
    gw->rs = gw->rc + mm;
    gw->colc = gw->rs + mm;
    gw->cols = gw->colc + mm * w;
    gw->th = gw->cols + mm * w;
    gw->kx = gw->th + mm;
    gw->kz = gw->kx + mm;
    return OCEAN_OK;
}

static void grid_work_free(grid_work *gw)
{
    free(gw->row0);
    free(gw->buf);
}

/* The waves the filter left, packed into gw, and their column factors,
 * each from its own reduced phase (no recurrence, so no error growth along
 * the row). */
static void grid_pack(grid_work *gw, const eval_state *st, const ocean_gerstner_grid *g)
{
    const ocean_gerstner *gs = st->g;
    double q = st->q;
    int m = 0;
    for (int i = 0; i < gs->count; i++) {
        double a = st->a[i];
        if (a == 0.0)
            continue;
        gw->ca[m] = a;
        gw->cdx[m] = -q * a * gs->hx[i];
        gw->cdz[m] = -q * a * gs->hz[i];
        gw->csx[m] = -a * gs->kx[i];
        gw->csz[m] = -a * gs->kz[i];
        gw->cxx[m] = -q * a * gs->hx[i] * gs->kx[i];
        gw->cxz[m] = -q * a * gs->hx[i] * gs->kz[i];
        gw->czz[m] = -q * a * gs->hz[i] * gs->kz[i];
        gw->kx[m] = gs->kx[i];
        gw->kz[m] = gs->kz[i];
        /* phase at sample (0, 0), reduced exactly as the one-point path */
        gw->th[m] = wrap_2pi(st->tphase[i] + mulmod_2pi(gs->kx[i], g->x0) +
                             mulmod_2pi(gs->kz[i], g->z0));
        m++;
    }
    memcpy(gw->row0, gw->th, sizeof(double) * gw->mm);
    for (int j = 0; j < g->w; j++) {
        double js = j * g->spacing;
        for (int i = 0; i < gw->M; i++)
            gw->th[i] = mulmod_2pi(gw->kx[i], js);
        sincos_many(gw->th, gw->cols + gw->mm * j, gw->colc + gw->mm * j, gw->M);
    }
}

/* The sums of the planes at column j of the current row (fade not yet
 * applied); the phase of each wave is the row factor times the column's. */
typedef struct grid_sums {
    double C, Dx, Dz, Sx, Sz, Dxx, Dxz, Dzz;
} grid_sums;

static void grid_sum(const grid_work *gw, int j, grid_sums *out)
{
    const double *rc = gw->rc, *rs = gw->rs;
    const double *cc = gw->colc + gw->mm * j, *cs = gw->cols + gw->mm * j;
    const double *ca = gw->ca, *cdx = gw->cdx, *cdz = gw->cdz, *csx = gw->csx, *csz = gw->csz;
    const double *cxx = gw->cxx, *cxz = gw->cxz, *czz = gw->czz;
    double C = 0, Dx = 0, Dz = 0, Sx = 0, Sz = 0, Dxx = 0, Dxz = 0, Dzz = 0;
    int M = gw->M;
#pragma omp simd reduction(+ : C, Dx, Dz, Sx, Sz, Dxx, Dxz, Dzz)
    for (int i = 0; i < M; i++) {
        double c = rc[i] * cc[i] - rs[i] * cs[i];
        double s = rs[i] * cc[i] + rc[i] * cs[i];
        C += ca[i] * c;
        Dx += cdx[i] * s;
        Dz += cdz[i] * s;
        Sx += csx[i] * s;
        Sz += csz[i] * s;
        Dxx += cxx[i] * c;
        Dxz += cxz[i] * c;
        Dzz += czz[i] * c;
    }
    *out = (grid_sums){C, Dx, Dz, Sx, Sz, Dxx, Dxz, Dzz};
}

/* Row r of the grid: rows wholly outside the fade are skipped. */
static void grid_row(grid_work *gw, const eval_state *st, const ocean_gerstner_grid *g, int r)
{
    int fade = !isinf(st->view.fade_r1);
    double z = g->z0 + r * g->spacing, rsp = r * g->spacing;
    if (fade && fabs(z - st->view.camera_z) >= st->view.fade_r1) {
        if (!g->accumulate)
            grid_clear_row(g, r);
        return;
    }
    for (int i = 0; i < gw->M; i++)
        gw->th[i] = gw->row0[i] + mulmod_2pi(gw->kz[i], rsp);
    sincos_many(gw->th, gw->rs, gw->rc, gw->M);
    for (int j = 0; j < g->w; j++) {
        double x = g->x0 + j * g->spacing;
        double fx = 0.0, fz = 0.0, fv = 1.0;
        if (fade)
            fv = fade_at(&st->view, x, z, &fx, &fz);
        size_t at = (size_t)r * g->stride + j;
        grid_sums s = {0, 0, 0, 0, 0, 0, 0, 0};
        if (fv != 0.0)
            grid_sum(gw, j, &s);
        int acc = g->accumulate;
        if (fv == 0.0 && acc)
            continue;
        grid_store(g->height, at, fv * s.C, acc);
        grid_store(g->dx, at, fv * s.Dx, acc);
        grid_store(g->dz, at, fv * s.Dz, acc);
        grid_store(g->slope_x, at, fv * s.Sx + fx * s.C, acc);
        grid_store(g->slope_z, at, fv * s.Sz + fz * s.C, acc);
        grid_store(g->dxx, at, fv * s.Dxx + fx * s.Dx, acc);
        grid_store(g->dzz, at, fv * s.Dzz + fz * s.Dz, acc);
        grid_store(g->dxz, at, fv * s.Dxz + 0.5 * (fz * s.Dx + fx * s.Dz), acc);
    }
}

ocean_result ocean_gerstner_frame_sample_grid(ocean_gerstner_frame *f,
                                              const ocean_gerstner_grid *g)
{
    if (f == NULL || !grid_ok(g))
        return OCEAN_EINVAL;
    if (!f->ready)
        return OCEAN_ESTATE;
    const eval_state *st = &f->st;
    /* Waves the filter silenced cost nothing: keep the others, packed. */
    int M = 0;
    for (int i = 0; i < st->g->count; i++)
        M += st->a[i] != 0.0;
    if (M == 0) {
        if (!g->accumulate)
            for (int r = 0; r < g->h; r++)
                grid_clear_row(g, r);
        return OCEAN_OK;
    }
    grid_work gw;
    if (grid_work_alloc(&gw, M, g->w) != OCEAN_OK)
        return OCEAN_ENOMEM;
    grid_pack(&gw, st, g);
    for (int r = 0; r < g->h; r++)
        grid_row(&gw, st, g, r);
    grid_work_free(&gw);
    return OCEAN_OK;
}
