/*
 * slope.c - slope second moments split into resolved / carried / tail
 * (contract in slope.h).
 *
 * The FFT modes are collected once, with their expected variances, sorted
 * by |k|: a Butterworth weight depends on |k| only, so for a cutoff the
 * modes far below it (weight 1 to double precision) and above the drop
 * wave number (weight 0) are prefix sums, and only the band in between is
 * summed mode by mode.  The tail does not depend on the cutoff and is
 * integrated once.
 */
#include "slope.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "filter.h"
#include "spectrum.h"

/* Elfouhaily et al. 1997 constants (eqs. 40-44, 57-59). */
#define ELF_CM 0.23      /* m/s, minimum phase speed */
#define ELF_KM 370.0     /* rad/m, wave number of the minimum */
#define VON_KARMAN 0.4

#define MEMO_SIZE 64
#define TAIL_DIRECTIONS 512
#define TAIL_PANEL 0.2   /* ln k width of one Gauss-Legendre panel */

typedef struct mode {
    double k;                 /* |k| as the ocean holds it (float), for the gain */
    double c[4];              /* a^2/2 * (kx^2, kz^2, kx kz, 1) */
} mode;

typedef struct memo {
    int used, order;
    double kc;
    ocean_slope_stats s;
} memo;

struct ocean_slope_table {
    size_t nm;
    mode *m;                  /* sorted by k */
    double (*prefix)[4];      /* prefix[i] = sum of c over m[0..i) */
    double k_top;             /* the ocean's largest |k| (ocean_effective_cutoff) */
    double drop_gain;
    int nw;
    double *wk;               /* near-field |k| and moments */
    double (*wc)[4];
    ocean_slope_moments tail_sea, tail_short;
    double k_sim_top, k_short;
    memo memo[MEMO_SIZE];
    int memo_next;
};

double ocean_slope_u125(double u10)
{
    if (!(u10 >= 0.0))
        return NAN;
    double ustar = sqrt((0.8 + 0.065 * u10) * 1e-3) * u10;
    return u10 + ustar / VON_KARMAN * log(12.5 / 10.0);
}

double ocean_slope_cox_munk_mss(double u10)
{
    double u = ocean_slope_u125(u10);
    return isnan(u) ? NAN : 0.003 + 5.12e-3 * u;
}

static double friction_velocity(double u10)
{
    return sqrt((0.8 + 0.065 * u10) * 1e-3) * u10;
}

static double elf_alpha_m(double ustar)
{
    if (!(ustar > 0.0))
        return 0.0;
    double a = ustar <= ELF_CM ? 0.01 * (1.0 + log(ustar / ELF_CM))
                               : 0.01 * (1.0 + 3.0 * log(ustar / ELF_CM));
    return a > 0.0 ? a : 0.0;
}

/* Gravity-capillary phase speed, deep water (Elfouhaily eq. 39's c). */
static double elf_c(double k)
{
    return sqrt(OCEAN_G / k * (1.0 + (k / ELF_KM) * (k / ELF_KM)));
}

double ocean_slope_elfouhaily_bh(double k, double u10)
{
    if (!(k > 0.0) || !isfinite(k) || !(u10 > 0.0))
        return 0.0;
    double am = elf_alpha_m(friction_velocity(u10));
    double d = k / ELF_KM - 1.0;
    return 0.5 * am * (ELF_CM / elf_c(k)) * exp(-0.25 * d * d);
}

/* Elfouhaily's spreading Delta(k) (eqs. 57-59): the directional function
 * is (1 + Delta cos 2 phi) / (2 pi), phi from the wind. */
static double elf_delta(double k, double ustar, double cp)
{
    double c = elf_c(k);
    double a0 = M_LN2 / 4.0, ap = 4.0, am = 0.13 * ustar / ELF_CM;
    double x = a0 + am * pow(ELF_CM / c, 2.5);
    if (cp > 0.0)
        x += ap * pow(c / cp, 2.5);
    return tanh(x);
}

/* 8-point Gauss-Legendre on [-1, 1]. */
static const double GL_X[8] = {-0.9602898564975363, -0.7966664774136267, -0.5255324099163290,
                               -0.1834346424956498, 0.1834346424956498, 0.5255324099163290,
                               0.7966664774136267, 0.9602898564975363};
static const double GL_W[8] = {0.1012285362903763, 0.2223810344533745, 0.3137066458778873,
                               0.3626837833783620, 0.3626837833783620, 0.3137066458778873,
                               0.2223810344533745, 0.1012285362903763};

static void mom_add(ocean_slope_moments *m, const double c[4], double w)
{
    m->mss_x += w * c[0];
    m->mss_z += w * c[1];
    m->mss_xz += w * c[2];
    m->energy += w * c[3];
}

static ocean_slope_moments mom_sum(ocean_slope_moments a, ocean_slope_moments b)
{
    return (ocean_slope_moments){a.mss_x + b.mss_x, a.mss_z + b.mss_z, a.mss_xz + b.mss_xz,
                                 a.energy + b.energy};
}

/* The sea state's spectrum over ln k in [a, b) along world direction
 * (ct, st), weight dtheta: int F k^2 (kx^2, kz^2, kx kz, 1)/k^2... in
 * polar form dkx dkz = k^2 dln k dtheta. */
static void sea_ray(const ocean_sea_state *sea, double ct, double st, double a, double b,
                    double dtheta, ocean_slope_moments *m)
{
    if (!(b > a))
        return;
    double la = log(a), lb = log(b);
    int panels = (int)ceil((lb - la) / TAIL_PANEL);
    if (panels < 1)
        panels = 1;
    double h = (lb - la) / panels;
    for (int p = 0; p < panels; p++)
        for (int i = 0; i < 8; i++) {
            double lk = la + h * (p + 0.5 + 0.5 * GL_X[i]);
            double k = exp(lk), kx = k * ct, kz = k * st;
            double w = 0.5 * h * GL_W[i] * dtheta * k * k * ocean_spectrum_f(sea, kx, kz);
            double c[4] = {kx * kx, kz * kz, kx * kz, 1.0};
            mom_add(m, c, w);
        }
}

/* Elfouhaily's B_h over [a, b) with its spreading, wind toward wdir. */
static void short_tail(const ocean_sea_state *sea, double a, double b, ocean_slope_moments *m)
{
    memset(m, 0, sizeof *m);
    if (!(b > a) || !(sea->wind_u10 > 1e-6))
        return;
    double ustar = friction_velocity(sea->wind_u10);
    double wp = ocean_spectrum_peak(sea), cp = 0.0;
    if (wp > 0.0)
        cp = wp / ocean_wavenumber(wp, sea->depth_m);
    double th = sea->wind_dir_deg * (M_PI / 180.0), c2 = cos(2.0 * th), s2 = sin(2.0 * th);
    double la = log(a), lb = log(b);
    int panels = (int)ceil((lb - la) / TAIL_PANEL);
    double h = (lb - la) / panels;
    for (int p = 0; p < panels; p++)
        for (int i = 0; i < 8; i++) {
            double k = exp(la + h * (p + 0.5 + 0.5 * GL_X[i]));
            double w = 0.5 * h * GL_W[i] * ocean_slope_elfouhaily_bh(k, sea->wind_u10);
            double d = elf_delta(k, ustar, cp);
            /* int cos^2(theta) (1 + D cos 2(theta - th)) / 2 pi dtheta = 1/2 + D/4 cos 2 th */
            double c[4] = {0.5 + 0.25 * d * c2, 0.5 - 0.25 * d * c2, 0.25 * d * s2, 1.0 / (k * k)};
            mom_add(m, c, w);
        }
}

static int mode_cmp(const void *a, const void *b)
{
    double x = ((const mode *)a)->k, y = ((const mode *)b)->k;
    return (x > y) - (x < y);
}

/* Every FFT mode of oc, sorted by |k|, with the prefix sums of their
 * moments. */
static ocean_result table_modes(ocean_slope_table *t, const ocean *oc)
{
    const ocean_params *p = ocean_get_params(oc);
    const ocean_sea_state *sea = &p->sea;
    int n = p->n, nc = p->cascades;
    /* Half plane (mz > 0, or mz = 0 and mx > 0): each mode stands for
     * itself and its mirror -k, E|h(k)|^2 + E|h(-k)|^2 = (F(k) + F(-k)) dk^2
     * (ocean.c: P(k) = F dk^2 / 2 per draw, two draws per mode). */
    size_t cap = (size_t)nc * n * (n / 2 + 1);
    t->m = malloc(cap * sizeof *t->m);
    if (!t->m)
        return OCEAN_ENOMEM;
    for (int c = 0; c < nc; c++) {
        double patch, klo, khi;
        ocean_cascade_band(oc, c, &patch, &klo, &khi);
        double dk = 2.0 * M_PI / patch;
        /* The same band test and Nyquist exclusion as ocean_modes.c's ocean_modes_h0. */
        for (int mz = 0; mz < n / 2; mz++)
            for (int mx = -n / 2 + 1; mx < n / 2; mx++) {
                if (mz == 0 && mx <= 0)
                    continue;
                double kx = mx * dk, kz = mz * dk, k = hypot(kx, kz);
                if (!(k >= klo && k < khi && k > 0.0))
                    continue;
                double v = (ocean_spectrum_f(sea, kx, kz) + ocean_spectrum_f(sea, -kx, -kz)) * dk * dk;
                if (!(v > 0.0))
                    continue;
                mode *md = &t->m[t->nm++];
                md->k = (float)k; /* the ocean compares the float |k| */
                md->c[0] = v * kx * kx;
                md->c[1] = v * kz * kz;
                md->c[2] = v * kx * kz;
                md->c[3] = v;
            }
    }
    qsort(t->m, t->nm, sizeof *t->m, mode_cmp);
    t->prefix = malloc((t->nm + 1) * sizeof *t->prefix);
    if (!t->prefix)
        return OCEAN_ENOMEM;
    memset(t->prefix[0], 0, sizeof t->prefix[0]);
    for (size_t i = 0; i < t->nm; i++)
        for (int j = 0; j < 4; j++)
            t->prefix[i + 1][j] = t->prefix[i][j] + t->m[i].c[j];
    return OCEAN_OK;
}

/* Every wave of the near field nf with its moments. */
static ocean_result table_near_field(ocean_slope_table *t, const ocean_gerstner *nf)
{
    t->nw = ocean_gerstner_count(nf);
    t->wk = malloc(((size_t)t->nw + 1) * sizeof *t->wk);
    t->wc = malloc(((size_t)t->nw + 1) * sizeof *t->wc);
    if (!t->wk || !t->wc)
        return OCEAN_ENOMEM;
    for (int i = 0; i < t->nw; i++) {
        ocean_gerstner_wave w;
        ocean_gerstner_get_wave(nf, i, &w);
        double v = 0.5 * w.amplitude * w.amplitude;
        t->wk[i] = w.k;
        t->wc[i][0] = v * w.kx * w.kx;
        t->wc[i][1] = v * w.kz * w.kz;
        t->wc[i][2] = v * w.kx * w.kz;
        t->wc[i][3] = v;
    }
    return OCEAN_OK;
}

/* The tail: the sea state's spectrum beyond what the FFT (finest grid n
 * points, fdk apart, band top fkhi) and the near field nf hold, up to
 * k_short, then Elfouhaily's B_h up to the capillary cutoff. */
static void table_tail(ocean_slope_table *t, const ocean_sea_state *sea, const ocean_gerstner *nf,
                       int n, double fdk, double fkhi)
{
    double nf_lo = INFINITY, nf_hi = INFINITY;
    if (nf) {
        const ocean_gerstner_params *gp = ocean_gerstner_get_params(nf);
        nf_lo = gp->k_lo;
        nf_hi = gp->k_hi;
    }
    /* The FFT's edge along a direction: its band's top, or the square of
     * the finest grid's cells (modes |m| <= n/2 - 1, each a cell of width
     * dk), whichever comes first. */
    double half = (n / 2 - 0.5) * fdk;
    double fft_top = fkhi < M_SQRT2 * half ? fkhi : M_SQRT2 * half;
    t->k_sim_top = nf ? fmax(nf_hi, fft_top) : fft_top;
    t->k_short = fmax(OCEAN_SLOPE_K_GRAVITY, t->k_sim_top);
    double dth = 2.0 * M_PI / TAIL_DIRECTIONS;
    for (int i = 0; i < TAIL_DIRECTIONS; i++) {
        double th = -M_PI + (i + 0.5) * dth, ct = cos(th), st = sin(th);
        double m = fmax(fabs(ct), fabs(st));
        double e = fmin(fkhi, half / m);
        if (nf) {
            sea_ray(sea, ct, st, e, fmin(nf_lo, t->k_short), dth, &t->tail_sea);
            sea_ray(sea, ct, st, fmax(e, nf_hi), t->k_short, dth, &t->tail_sea);
        } else {
            sea_ray(sea, ct, st, e, t->k_short, dth, &t->tail_sea);
        }
    }
    short_tail(sea, t->k_short, OCEAN_SLOPE_K_CAPILLARY, &t->tail_short);
}

ocean_result ocean_slope_table_create(const ocean *oc, const ocean_gerstner *nf,
                                      ocean_slope_table **out, char *msg, size_t msglen)
{
    if (out)
        *out = NULL;
    if (!oc || !out) {
        if (msg) snprintf(msg, msglen, "ocean or output is NULL");
        return OCEAN_EINVAL;
    }
    const ocean_params *p = ocean_get_params(oc);
    ocean_slope_table *t = calloc(1, sizeof *t);
    if (!t)
        goto nomem;
    t->drop_gain = p->drop_gain;
    if (table_modes(t, oc) != OCEAN_OK || (nf && table_near_field(t, nf) != OCEAN_OK))
        goto nomem;
    /* ocean.c's k_top: the finest cascade's k_hi or its corner. */
    double fpatch, fklo, fkhi;
    ocean_cascade_band(oc, p->cascades - 1, &fpatch, &fklo, &fkhi);
    double fdk = 2.0 * M_PI / fpatch;
    double corner = M_SQRT2 * (p->n / 2 - 1) * fdk;
    t->k_top = fkhi < corner ? fkhi : corner;
    table_tail(t, &p->sea, nf, p->n, fdk, fkhi);
    *out = t;
    return OCEAN_OK;
nomem:
    ocean_slope_table_destroy(t);
    if (msg) snprintf(msg, msglen, "out of memory for the slope table");
    return OCEAN_ENOMEM;
}

void ocean_slope_table_destroy(ocean_slope_table *t)
{
    if (!t)
        return;
    free(t->m);
    free(t->prefix);
    free(t->wk);
    free(t->wc);
    free(t);
}

/* H^2 and 1 - H^2 of the order-n Butterworth at k without cancellation:
 * r = (k/kc)^(2n) by squaring, H^2 = 1/(1 + r), 1 - H^2 = r/(1 + r). */
static inline void bw2(double k, double kc, int order, double *h2, double *l2)
{
    double x = k / kc, r = 1.0, b = x * x;
    for (int e = order; e; e >>= 1, b *= b)
        if (e & 1)
            r *= b;
    if (isinf(r)) {
        *h2 = 0.0;
        *l2 = 1.0;
        return;
    }
    *h2 = 1.0 / (1.0 + r);
    *l2 = r / (1.0 + r);
}

/* First index with m[i].k >= k. */
static size_t lower_bound(const ocean_slope_table *t, double k)
{
    size_t lo = 0, hi = t->nm;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (t->m[mid].k < k)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

static void prefix_range(const ocean_slope_table *t, size_t a, size_t b, ocean_slope_moments *m)
{
    double d[4];
    for (int j = 0; j < 4; j++)
        d[j] = t->prefix[b][j] - t->prefix[a][j];
    mom_add(m, d, 1.0);
}

static void compute(const ocean_slope_table *t, double kc_in, int order, ocean_slope_stats *s)
{
    memset(s, 0, sizeof *s);
    /* ocean_effective_cutoff's rule, with the ocean's own k_top. */
    double kc = kc_in;
    if (isinf(kc) || ocean_filter_gain(t->k_top, kc, order) >= 1.0 - 1e-6)
        kc = INFINITY;
    s->k_cut = kc;
    s->order = order;
    if (isinf(kc)) {
        prefix_range(t, 0, t->nm, &s->fft_resolved);
    } else if (kc == 0.0) {
        prefix_range(t, 0, t->nm, &s->fft_carried);
    } else {
        /* Below k_flat the weight 1 - H^2 < 1e-17: a prefix sum.  At and
         * above the drop wave number the ocean transforms nothing. */
        double kneg = ocean_filter_negligible_k(kc, order, t->drop_gain);
        double k_flat = kc * pow(1e-17, 1.0 / (2.0 * order));
        size_t i_lo = lower_bound(t, k_flat), i_hi = lower_bound(t, kneg);
        if (i_hi < i_lo)
            i_hi = i_lo;
        prefix_range(t, 0, i_lo, &s->fft_resolved);
        double r[4] = {0}, c[4] = {0};
        for (size_t i = i_lo; i < i_hi; i++) {
            double h2, l2;
            bw2(t->m[i].k, kc, order, &h2, &l2);
            for (int j = 0; j < 4; j++) {
                r[j] += h2 * t->m[i].c[j];
                c[j] += l2 * t->m[i].c[j];
            }
        }
        mom_add(&s->fft_resolved, r, 1.0);
        mom_add(&s->fft_carried, c, 1.0);
        prefix_range(t, i_hi, t->nm, &s->fft_carried);
    }
    for (int i = 0; i < t->nw; i++) {
        double h2 = 1.0, l2 = 0.0;
        if (kc == 0.0) {
            h2 = 0.0;
            l2 = 1.0;
        } else if (!isinf(kc)) {
            bw2(t->wk[i], kc, order, &h2, &l2);
        }
        mom_add(&s->near_resolved, t->wc[i], h2);
        mom_add(&s->near_carried, t->wc[i], l2);
    }
    s->tail_sea = t->tail_sea;
    s->tail_short = t->tail_short;
    s->tail = mom_sum(t->tail_sea, t->tail_short);
    s->resolved = mom_sum(s->fft_resolved, s->near_resolved);
    s->carried = mom_sum(mom_sum(s->fft_carried, s->near_carried), s->tail);
    s->total = mom_sum(s->resolved, s->carried);
    s->mss_resolved = s->resolved.mss_x + s->resolved.mss_z;
    s->mss_carried = s->carried.mss_x + s->carried.mss_z;
    s->mss_total = s->total.mss_x + s->total.mss_z;
    s->k_sim_top = t->k_sim_top;
    s->k_short = t->k_short;
    s->k_capillary = OCEAN_SLOPE_K_CAPILLARY;
}

ocean_result ocean_slope_table_get(ocean_slope_table *t, double k_cut, int order,
                                   ocean_slope_stats *out)
{
    if (!t || !out || isnan(k_cut) || k_cut < 0.0 || order < 1 || order > OCEAN_FILTER_MAX_ORDER)
        return OCEAN_EINVAL;
    for (int i = 0; i < MEMO_SIZE; i++)
        if (t->memo[i].used && t->memo[i].kc == k_cut && t->memo[i].order == order) {
            *out = t->memo[i].s;
            return OCEAN_OK;
        }
    memo *m = &t->memo[t->memo_next];
    t->memo_next = (t->memo_next + 1) % MEMO_SIZE;
    compute(t, k_cut, order, &m->s);
    m->used = 1;
    m->kc = k_cut;
    m->order = order;
    *out = m->s;
    return OCEAN_OK;
}

ocean_result ocean_slope_variance(const ocean *oc, const ocean_gerstner *nf, double k_cut,
                                  int order, ocean_slope_stats *out)
{
    if (!oc || !out || isnan(k_cut) || k_cut < 0.0 || order < 1 || order > OCEAN_FILTER_MAX_ORDER)
        return OCEAN_EINVAL;
    ocean_slope_table *t;
    ocean_result r = ocean_slope_table_create(oc, nf, &t, NULL, 0);
    if (r != OCEAN_OK)
        return r;
    r = ocean_slope_table_get(t, k_cut, order, out);
    ocean_slope_table_destroy(t);
    return r;
}
