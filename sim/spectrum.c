/*
 * spectrum.c - spectra, spreading, dispersion and Beaufort presets.
 *
 * All arithmetic in double.  Every function guards the places where the
 * textbook formula produces inf * 0 (w -> 0 in w^-5 exp(-w^-4)), overflows
 * (cosh(kh), Gamma(2s+1)) or divides by zero (no wind), so any finite sea
 * state gives finite, non-negative densities.
 */
#include "spectrum.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* Pierson-Moskowitz constants (Stewart 2008, eq. 16.30). */
#define PM_ALPHA 8.1e-3
#define PM_BETA 0.74
/* U19.5 ~ 1.026 U10 (Stewart 2008). */
#define PM_U195_PER_U10 1.026
/* exp() of anything below this is 0 in double; skip the w^-5 factor. */
#define EXP_UNDERFLOW (-745.0)

static const char *const spectrum_names[OCEAN_SPECTRUM_COUNT_] = {
    "phillips", "pierson-moskowitz", "jonswap", "tma"};
static const char *const spreading_names[OCEAN_SPREAD_COUNT_] = {
    "tessendorf", "mitsuyasu", "hasselmann", "donelan-banner"};

void ocean_sea_state_default(ocean_sea_state *s)
{
    memset(s, 0, sizeof *s);
    s->spectrum = OCEAN_SPECTRUM_PM;
    s->spreading = OCEAN_SPREAD_MITSUYASU;
    s->wind_u10 = 10.0;
    s->wind_dir_deg = 0.0;
    s->fetch_m = 1e5;
    s->depth_m = 4000.0;
    s->swell = 0.0;
    s->phillips_a = PM_ALPHA / 2.0;
    s->small_wave_m = 0.0;
    s->choppiness = 1.0;
    s->whitecaps = 1;
}

static int check_range(const char *name, double v, double lo, double hi,
                       char *msg, size_t msglen)
{
    if (isfinite(v) && v >= lo && v <= hi)
        return 1;
    if (msg)
        snprintf(msg, msglen, "%s = %g is out of range [%g, %g]", name, v, lo, hi);
    return 0;
}

ocean_result ocean_sea_state_validate(const ocean_sea_state *s, char *msg, size_t msglen)
{
    if (!s) {
        if (msg) snprintf(msg, msglen, "sea state is NULL");
        return OCEAN_EINVAL;
    }
    if ((unsigned)s->spectrum >= OCEAN_SPECTRUM_COUNT_) {
        if (msg) snprintf(msg, msglen, "spectrum = %d is not a known spectrum", (int)s->spectrum);
        return OCEAN_EINVAL;
    }
    if ((unsigned)s->spreading >= OCEAN_SPREAD_COUNT_) {
        if (msg) snprintf(msg, msglen, "spreading = %d is not a known spreading function", (int)s->spreading);
        return OCEAN_EINVAL;
    }
    if (!check_range("wind", s->wind_u10, 0.0, 100.0, msg, msglen) ||
        !check_range("direction", s->wind_dir_deg, -360.0, 360.0, msg, msglen) ||
        !check_range("fetch", s->fetch_m, 1.0, 1e7, msg, msglen) ||
        !check_range("depth", s->depth_m, 0.01, 12000.0, msg, msglen) ||
        !check_range("swell", s->swell, 0.0, 10.0, msg, msglen) ||
        !check_range("phillips_a", s->phillips_a, 0.0, 1.0, msg, msglen) ||
        !check_range("small_wave", s->small_wave_m, 0.0, 100.0, msg, msglen) ||
        !check_range("choppiness", s->choppiness, 0.0, 10.0, msg, msglen))
        return OCEAN_EINVAL;
    if (s->whitecaps != 0 && s->whitecaps != 1) {
        if (msg) snprintf(msg, msglen, "whitecaps = %d: 1 (on) or 0 (off)", s->whitecaps);
        return OCEAN_EINVAL;
    }
    /* The displacement channels hold lambda D in float and foam reads them
     * back divided by lambda: below 1e-3 the displacement is under a
     * millimetre per metre of slope (nothing to see), and near 1e-38 the
     * channels leave float's normal range and foam becomes NaN. */
    if (s->choppiness > 0.0 && s->choppiness < OCEAN_CHOPPINESS_MIN) {
        if (msg)
            snprintf(msg, msglen, "choppiness = %g: use 0 (no choppy displacement, no foam) or "
                     "%g .. 10", s->choppiness, OCEAN_CHOPPINESS_MIN);
        return OCEAN_EINVAL;
    }
    /* The swell term raises s of the cos-2s family, narrowing it (Horvath
     * 2015: s += 16 tanh(wp/w) xi^2); the cos^2 and sech^2 spreadings have
     * no s to raise, and a swell silently ignored there reads as a sea
     * that does not respond. */
    if (s->swell > 0.0 && s->spreading != OCEAN_SPREAD_MITSUYASU && s->spreading != OCEAN_SPREAD_HASSELMANN) {
        if (msg)
            snprintf(msg, msglen, "swell = %g applies to the cos-2s spreadings (mitsuyasu, hasselmann); "
                     "spreading %s has none: use swell = 0 or one of those",
                     s->swell, ocean_spreading_name(s->spreading));
        return OCEAN_EINVAL;
    }
    return OCEAN_OK;
}

const char *ocean_spectrum_name(ocean_spectrum_kind k)
{
    return (unsigned)k < OCEAN_SPECTRUM_COUNT_ ? spectrum_names[k] : "unknown";
}

const char *ocean_spreading_name(ocean_spreading_kind k)
{
    return (unsigned)k < OCEAN_SPREAD_COUNT_ ? spreading_names[k] : "unknown";
}

ocean_result ocean_spectrum_parse(const char *name, ocean_spectrum_kind *out)
{
    for (int i = 0; name && i < OCEAN_SPECTRUM_COUNT_; i++)
        if (strcmp(name, spectrum_names[i]) == 0) {
            *out = (ocean_spectrum_kind)i;
            return OCEAN_OK;
        }
    if (name && strcmp(name, "pm") == 0) {
        *out = OCEAN_SPECTRUM_PM;
        return OCEAN_OK;
    }
    return OCEAN_EINVAL;
}

ocean_result ocean_spreading_parse(const char *name, ocean_spreading_kind *out)
{
    for (int i = 0; name && i < OCEAN_SPREAD_COUNT_; i++)
        if (strcmp(name, spreading_names[i]) == 0) {
            *out = (ocean_spreading_kind)i;
            return OCEAN_OK;
        }
    return OCEAN_EINVAL;
}

double ocean_dispersion(double k, double depth)
{
    if (!(k > 0.0))
        return 0.0;
    return sqrt(OCEAN_G * k * tanh(k * depth));
}

double ocean_dispersion_dk(double k, double depth)
{
    if (!(k > 0.0))
        return sqrt(OCEAN_G * depth);
    double kh = k * depth;
    double th = tanh(kh);
    double w = sqrt(OCEAN_G * k * th);
    /* sech^2 = 1 - tanh^2: cosh(kh) would overflow for kh > 710. */
    return OCEAN_G * (th + kh * (1.0 - th * th)) / (2.0 * w);
}

double ocean_wavenumber(double w, double depth)
{
    if (!(w > 0.0))
        return 0.0;
    double k0 = w * w / OCEAN_G;
    /* Eckart's approximation, then Newton on w(k) - w. */
    double k = k0 / sqrt(tanh(k0 * depth));
    if (!isfinite(k) || k <= 0.0)
        k = w / sqrt(OCEAN_G * depth);
    for (int i = 0; i < 50; i++) {
        double f = ocean_dispersion(k, depth) - w;
        double d = ocean_dispersion_dk(k, depth);
        double step = f / d;
        k -= step;
        if (k <= 0.0)
            k = 1e-12;
        if (fabs(step) <= 1e-15 * k)
            break;
    }
    return k;
}

static double u195(const ocean_sea_state *s)
{
    return PM_U195_PER_U10 * s->wind_u10;
}

/* JONSWAP fetch laws (Hasselmann et al. 1973) in the dimensionless fetch
 * x = g F / U10^2: alpha = 0.076 x^-0.22, wp = 22 (g / U10) x^(-1/3) (the
 * form 22 (g^2 / (U10 F))^(1/3); the other published form differs ~3 %).
 * Growth stops at full development, where the sea holds the energy of the
 * fully developed Pierson-Moskowitz sea of the same wind (1964: Hs =
 * 0.20925 U19.5^2 / g, U19.5 = 1.026 U10).  JONSWAP's m0 is
 * alpha g^2 wp^-4 R / 5, R = m0(gamma 3.3) / m0(gamma 1) = 1.525; PM's is
 * a g^2 (g / U19.5)^-4 / (4 b), a = 0.0081, b = 0.74; equal where
 *   x^(4/3 - 0.22) = 5 22^4 1.026^4 a / (4 b 0.076 R),  x = 1.0707e4
 * (independent of the wind; the constant below is that root, solved with
 * the integrals themselves).  There the peak is 1.004 g / U10, 17 % above
 * PM's 0.855 g / U10: JONSWAP's peak is narrower, so the same energy sits
 * higher.  Capped at PM's peak instead (x = 1.7e4) the sea grew to 1.30 x
 * PM's Hs, more than the wind can hold. */
#define JONSWAP_X_FULL 10707.25

static double jonswap_x(const ocean_sea_state *s)
{
    double x = OCEAN_G * s->fetch_m / (s->wind_u10 * s->wind_u10);
    return x < JONSWAP_X_FULL ? x : JONSWAP_X_FULL;
}

static double jonswap_alpha(const ocean_sea_state *s)
{
    return 0.076 * pow(jonswap_x(s), -0.22);
}

static double jonswap_wp(const ocean_sea_state *s)
{
    return 22.0 * OCEAN_G / s->wind_u10 * cbrt(1.0 / jonswap_x(s));
}

/* Phillips' outer length L = V^2 / g (Tessendorf 2001). */
static double phillips_l(const ocean_sea_state *s)
{
    return s->wind_u10 * s->wind_u10 / OCEAN_G;
}

double ocean_spectrum_peak(const ocean_sea_state *s)
{
    if (!(s->wind_u10 > 1e-6))
        return 0.0;
    switch (s->spectrum) {
    case OCEAN_SPECTRUM_PM:
        return pow(0.8 * PM_BETA, 0.25) * OCEAN_G / u195(s);
    case OCEAN_SPECTRUM_JONSWAP:
    case OCEAN_SPECTRUM_TMA:
        return jonswap_wp(s);
    case OCEAN_SPECTRUM_PHILLIPS: {
        /* Peak of the 1-D density k^-3 exp(-1/(kL)^2): k = sqrt(2/3) / L. */
        double kp = sqrt(2.0 / 3.0) / phillips_l(s);
        return ocean_dispersion(kp, s->depth_m);
    }
    default:
        return 0.0;
    }
}

double ocean_tma_phi(double w, double depth)
{
    double wh = w * sqrt(depth / OCEAN_G);
    if (wh <= 1.0)
        return 0.5 * wh * wh;
    if (wh < 2.0)
        return 1.0 - 0.5 * (2.0 - wh) * (2.0 - wh);
    return 1.0;
}

static double pm_s(double alpha, double w, double w0)
{
    double r = w0 / w;
    double e = -PM_BETA * r * r * r * r;
    if (e < EXP_UNDERFLOW)
        return 0.0;
    return alpha * OCEAN_G * OCEAN_G * pow(w, -5.0) * exp(e);
}

static double jonswap_s(const ocean_sea_state *s, double w)
{
    double wp = jonswap_wp(s);
    double r = wp / w;
    double e = -1.25 * r * r * r * r;
    if (e < EXP_UNDERFLOW)
        return 0.0;
    double sigma = w <= wp ? 0.07 : 0.09;
    double d = (w - wp) / (sigma * wp);
    double peak = pow(3.3, exp(-0.5 * d * d));
    return jonswap_alpha(s) * OCEAN_G * OCEAN_G * pow(w, -5.0) * exp(e) * peak;
}

/* Phillips density in k, integrated over direction: A exp(-1/(kL)^2)
 * exp(-k^2 l^2) / k^3 (the 2-D form divided by D(theta), times k). */
static double phillips_sk(const ocean_sea_state *s, double k)
{
    double L = phillips_l(s);
    double x = 1.0 / (k * L);
    double e = -x * x - k * k * s->small_wave_m * s->small_wave_m;
    if (e < EXP_UNDERFLOW)
        return 0.0;
    return s->phillips_a * exp(e) / (k * k * k);
}

double ocean_spectrum_s(const ocean_sea_state *s, double w)
{
    if (!(w > 0.0) || !isfinite(w) || !(s->wind_u10 > 1e-6))
        return 0.0;
    switch (s->spectrum) {
    case OCEAN_SPECTRUM_PM:
        return pm_s(PM_ALPHA, w, OCEAN_G / u195(s));
    case OCEAN_SPECTRUM_JONSWAP:
        return jonswap_s(s, w);
    case OCEAN_SPECTRUM_TMA:
        return ocean_tma_phi(w, s->depth_m) * jonswap_s(s, w);
    case OCEAN_SPECTRUM_PHILLIPS: {
        double k = ocean_wavenumber(w, s->depth_m);
        return phillips_sk(s, k) / ocean_dispersion_dk(k, s->depth_m);
    }
    default:
        return 0.0;
    }
}

double ocean_cos2s_norm(double s)
{
    if (s < 0.0)
        s = 0.0;
    double lq = (2.0 * s - 1.0) * M_LN2 + 2.0 * lgamma(s + 1.0) - lgamma(2.0 * s + 1.0) - log(M_PI);
    return exp(lq);
}

/* Spreading exponent s(w) of the cos-2s family, with the swell term. */
static double cos2s_exponent(const ocean_sea_state *s, double w, double wp)
{
    double r = w / wp, sv;
    if (s->spreading == OCEAN_SPREAD_MITSUYASU) {
        double sp = 11.5 * pow(wp * s->wind_u10 / OCEAN_G, -2.5);
        sv = r <= 1.0 ? sp * pow(r, 5.0) : sp * pow(r, -2.5);
    } else {
        sv = r <= 1.0 ? 6.97 * pow(r, 4.06)
                      : 9.77 * pow(r, -2.33 - 1.45 * (s->wind_u10 * wp / OCEAN_G - 1.17));
    }
    sv += 16.0 * tanh(wp / w) * s->swell * s->swell;
    /* Beyond 1e6 the lobe is narrower than any grid resolves. */
    return fmin(fmax(sv, 0.0), 1e6);
}

void ocean_spreading_at(const ocean_sea_state *s, double w, ocean_spreading *out)
{
    memset(out, 0, sizeof *out);
    out->kind = s->spreading;
    if (s->spreading == OCEAN_SPREAD_TESSENDORF)
        return;
    double wp = ocean_spectrum_peak(s);
    if (!(wp > 0.0) || !(w > 0.0)) {
        out->uniform = 1;
        return;
    }
    switch (s->spreading) {
    case OCEAN_SPREAD_MITSUYASU:
    case OCEAN_SPREAD_HASSELMANN:
        out->sv = cos2s_exponent(s, w, wp);
        out->lnorm = log(ocean_cos2s_norm(out->sv));
        break;
    case OCEAN_SPREAD_DONELAN_BANNER: {
        double r = w / wp, b;
        if (r < 0.95)
            b = 2.61 * pow(r, 1.3);
        else if (r < 1.6)
            b = 2.28 * pow(r, -1.3);
        else
            b = pow(10.0, -0.4 + 0.8393 * exp(-0.567 * log(r * r)));
        /* b -> 0 (r -> 0) tends to the uniform 1/(2 pi). */
        if (b < 1e-8) {
            out->uniform = 1;
            break;
        }
        out->b = b;
        out->pre = b / (2.0 * tanh(b * M_PI));
        break;
    }
    default:
        break;
    }
}

void ocean_spreading_dir_at(ocean_spreading_kind kind, double theta, ocean_spreading_dir *out)
{
    memset(out, 0, sizeof *out);
    out->theta = remainder(theta, 2.0 * M_PI); /* [-pi, pi] */
    if (kind == OCEAN_SPREAD_TESSENDORF) {
        out->cos_theta = cos(out->theta);
    } else if (kind == OCEAN_SPREAD_MITSUYASU || kind == OCEAN_SPREAD_HASSELMANN) {
        out->c_half = fabs(cos(out->theta / 2.0));
        if (out->c_half != 0.0)
            out->ln_c_half = log(out->c_half);
    }
}

double ocean_spreading_eval(const ocean_spreading *d, const ocean_spreading_dir *dir)
{
    switch (d->kind) {
    case OCEAN_SPREAD_TESSENDORF: {
        if (fabs(dir->theta) >= M_PI / 2)
            return 0.0;
        double c = dir->cos_theta;
        return (2.0 / M_PI) * c * c;
    }
    case OCEAN_SPREAD_MITSUYASU:
    case OCEAN_SPREAD_HASSELMANN: {
        if (d->uniform)
            return 1.0 / (2.0 * M_PI);
        if (dir->c_half == 0.0)
            return d->sv == 0.0 ? ocean_cos2s_norm(0.0) : 0.0;
        double ld = d->lnorm + 2.0 * d->sv * dir->ln_c_half;
        return ld < EXP_UNDERFLOW ? 0.0 : exp(ld);
    }
    case OCEAN_SPREAD_DONELAN_BANNER: {
        if (d->uniform)
            return 1.0 / (2.0 * M_PI);
        double ch = cosh(d->b * dir->theta); /* inf for huge b*theta: 1/inf^2 = 0 */
        return d->pre / (ch * ch);
    }
    default:
        return 0.0;
    }
}

double ocean_spreading_d(const ocean_sea_state *s, double theta, double w)
{
    ocean_spreading d;
    ocean_spreading_dir dir;
    ocean_spreading_at(s, w, &d);
    ocean_spreading_dir_at(s->spreading, theta, &dir);
    return ocean_spreading_eval(&d, &dir);
}

/* S(w) dw/dk at k (Phillips: its density in k), w = w(k). */
static double ring_radial(const ocean_sea_state *s, double k, double w)
{
    if (s->spectrum == OCEAN_SPECTRUM_PHILLIPS)
        return phillips_sk(s, k);
    return ocean_spectrum_s(s, w) * ocean_dispersion_dk(k, s->depth_m);
}

void ocean_spectrum_ring_at(const ocean_sea_state *s, double k, ocean_spectrum_ring *out)
{
    memset(out, 0, sizeof *out);
    if (!(k > 0.0) || !isfinite(k) || !(s->wind_u10 > 1e-6))
        return;
    out->k = k;
    double w = ocean_dispersion(k, s->depth_m);
    ocean_spreading_at(s, w, &out->d);
    out->radial = ring_radial(s, k, w);
}

double ocean_spectrum_ring_f(const ocean_spectrum_ring *r, const ocean_spreading_dir *dir)
{
    if (!(r->k > 0.0))
        return 0.0;
    double d = ocean_spreading_eval(&r->d, dir);
    if (d == 0.0)
        return 0.0;
    return r->radial * d / r->k;
}

/* One point: the spreading first, so a direction it leaves empty (half the
 * plane for Tessendorf's) costs no spectrum; then ocean_spectrum_ring_f's
 * product, in its order (the same bits). */
double ocean_spectrum_f(const ocean_sea_state *s, double kx, double kz)
{
    double k = hypot(kx, kz);
    if (!(k > 0.0) || !isfinite(k) || !(s->wind_u10 > 1e-6))
        return 0.0;
    double w = ocean_dispersion(k, s->depth_m);
    ocean_spreading sp;
    ocean_spreading_dir dir;
    ocean_spreading_at(s, w, &sp);
    ocean_spreading_dir_at(s->spreading, atan2(kz, kx) - s->wind_dir_deg * (M_PI / 180.0), &dir);
    double d = ocean_spreading_eval(&sp, &dir);
    if (d == 0.0)
        return 0.0;
    return ring_radial(s, k, w) * d / k;
}

ocean_result ocean_beaufort_wind(int force, double *u10)
{
    /* Midpoints of the Met Office bands (m/s at 10 m); force 12 is open-ended. */
    static const double mid[13] = {0.1, 0.9, 2.45, 4.4, 6.7, 9.35, 12.3,
                                   15.5, 18.95, 22.6, 26.45, 30.55, 35.0};
    if (force < 0 || force > 12)
        return OCEAN_EINVAL;
    *u10 = mid[force];
    return OCEAN_OK;
}

double ocean_spectrum_hs(const ocean_sea_state *s)
{
    double wp = ocean_spectrum_peak(s);
    if (!(wp > 0.0))
        return 0.0;
    /* Simpson in ln w over [wp/100, wp*1000]: the spectrum is negligible
     * below, and the tail above holds < 1e-12 of m0 for w^-5 spectra. */
    const int n = 20000;
    double a = log(wp / 100.0), b = log(wp * 1000.0), h = (b - a) / n, sum = 0.0;
    for (int i = 0; i <= n; i++) {
        double w = exp(a + i * h);
        double f = ocean_spectrum_s(s, w) * w;
        sum += f * (i == 0 || i == n ? 1.0 : (i % 2 ? 4.0 : 2.0));
    }
    return 4.0 * sqrt(sum * h / 3.0);
}
