/*
 * filter.c - the velocity-adaptive low-pass of filter.h: its Butterworth
 * gain, cutoff policies, smoothing, buckets, E_error and the dominant
 * wavelength (see filter.h for the contracts).
 */
#include "filter.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* ---- Butterworth ---------------------------------------------------------- */

static int order_ok(int order)
{
    return order >= 1 && order <= OCEAN_FILTER_MAX_ORDER;
}

double ocean_filter_gain(double k, double kc, int order)
{
    if (!order_ok(order) || isnan(k) || isnan(kc) || k < 0.0 || kc < 0.0)
        return NAN;
    if (isinf(kc))
        return 1.0;
    if (kc == 0.0)
        return 0.0;
    if (k <= kc) {
        /* ratio <= 1: q <= 1, q^2 cannot overflow (it may underflow to 0,
         * which is the right limit). */
        double q = pow(k / kc, order);
        return 1.0 / sqrt(1.0 + q * q);
    }
    /* ratio > 1: work with its inverse so nothing overflows. */
    double q = pow(kc / k, order);
    return q / sqrt(1.0 + q * q);
}

double ocean_filter_negligible_k(double kc, int order, double eps)
{
    if (!order_ok(order) || isnan(kc) || kc < 0.0 || isnan(eps))
        return NAN;
    if (eps >= 1.0)
        return 0.0;
    if (eps <= 0.0 || isinf(kc))
        return INFINITY;
    if (kc == 0.0)
        return 0.0;
    /* H(k) = eps  <=>  (k/kc)^(2n) = (1 - eps^2) / eps^2. */
    double lr = (log1p(-eps * eps) - 2.0 * log(eps)) / (2.0 * order);
    return kc * exp(lr);
}

/* ---- Policies -------------------------------------------------------------- */

static const char *const policy_names[OCEAN_FILTER_POLICY_COUNT_] = {
    [OCEAN_FILTER_NONE] = "none",
    [OCEAN_FILTER_SEED] = "seed",
    [OCEAN_FILTER_ANTIALIAS] = "antialias",
};

const char *ocean_filter_policy_name(ocean_filter_policy p)
{
    if ((unsigned)p >= OCEAN_FILTER_POLICY_COUNT_)
        return "unknown";
    return policy_names[p];
}

ocean_result ocean_filter_policy_parse(const char *name, ocean_filter_policy *out)
{
    if (name == NULL || out == NULL)
        return OCEAN_EINVAL;
    for (int i = 0; i < OCEAN_FILTER_POLICY_COUNT_; i++) {
        if (strcmp(name, policy_names[i]) == 0) {
            *out = (ocean_filter_policy)i;
            return OCEAN_OK;
        }
    }
    return OCEAN_EINVAL;
}

/* Phase speed of the dominant wave; a calm sea has none, so a 10 s
 * deep-water wave (g T / 2 pi = 15.6 m/s) stands in. */
static double dominant_phase_speed(const ocean_sea_state *sea)
{
    double fallback = OCEAN_G * 10.0 / (2.0 * M_PI);
    double wp = ocean_spectrum_peak(sea);
    if (!(wp > 0.0) || !isfinite(wp))
        return fallback;
    double kp = ocean_wavenumber(wp, sea->depth_m);
    if (!(kp > 0.0) || !isfinite(kp))
        return fallback;
    double c = wp / kp;
    return (c > 0.0 && isfinite(c)) ? c : fallback;
}

void ocean_filter_config_default(ocean_filter_config *c, const ocean_sea_state *sea)
{
    ocean_sea_state def;
    if (sea == NULL) {
        ocean_sea_state_default(&def);
        sea = &def;
    }
    c->order = OCEAN_FILTER_DEFAULT_ORDER;
    c->f_base_hz = 3.0;
    c->beta_slow = 0.05;
    c->beta_fast = 0.2;
    c->beta_switch_mps = 5.0;
    c->boost_speed_mps = 10.0;
    c->boost_fraction = 0.03;
    c->v_wave_mps = dominant_phase_speed(sea);
    c->depth_m = sea->depth_m;
    c->alias_gain = M_SQRT1_2;
}

static ocean_result bad_field(char *msg, size_t msglen, const char *field, double v)
{
    if (msg != NULL && msglen > 0)
        snprintf(msg, msglen, "filter config: %s = %g is out of range", field, v);
    return OCEAN_EINVAL;
}

static int in_range(double v, double lo, double hi)
{
    return isfinite(v) && v >= lo && v <= hi;
}

ocean_result ocean_filter_config_validate(const ocean_filter_config *c, char *msg, size_t msglen)
{
    if (c == NULL)
        return OCEAN_EINVAL;
    if (!order_ok(c->order))
        return bad_field(msg, msglen, "order", c->order);
    if (!in_range(c->f_base_hz, 0.0, 1e6))
        return bad_field(msg, msglen, "f_base_hz", c->f_base_hz);
    if (!in_range(c->beta_slow, 0.0, 1e3))
        return bad_field(msg, msglen, "beta_slow", c->beta_slow);
    if (!in_range(c->beta_fast, 0.0, 1e3))
        return bad_field(msg, msglen, "beta_fast", c->beta_fast);
    if (!in_range(c->beta_switch_mps, 0.0, 1e6))
        return bad_field(msg, msglen, "beta_switch_mps", c->beta_switch_mps);
    if (!in_range(c->boost_speed_mps, 0.0, 1e9))
        return bad_field(msg, msglen, "boost_speed_mps", c->boost_speed_mps);
    if (!in_range(c->boost_fraction, 0.0, 1.0))
        return bad_field(msg, msglen, "boost_fraction", c->boost_fraction);
    if (!in_range(c->v_wave_mps, 1e-6, 1e6) )
        return bad_field(msg, msglen, "v_wave_mps", c->v_wave_mps);
    if (!in_range(c->depth_m, 0.01, 12000.0))
        return bad_field(msg, msglen, "depth_m", c->depth_m);
    if (!(c->alias_gain > 0.0 && c->alias_gain <= M_SQRT1_2 + 1e-12))
        return bad_field(msg, msglen, "alias_gain", c->alias_gain);
    return OCEAN_OK;
}

/* The k solving omega(k) + v k = w_ny.  The left side is strictly
 * increasing in k and in v, so the root exists, is unique and falls as v
 * rises.  Bracket by doubling, then bisect to the last bit: the result is
 * a deterministic, monotone function of v. */
static double temporal_limit(double v, double w_ny, double depth)
{
    double lo = 0.0, hi = 1e-9;
    while (ocean_dispersion(hi, depth) + v * hi < w_ny) {
        lo = hi;
        hi *= 2.0;
        if (isinf(hi))
            return INFINITY;
    }
    for (int i = 0; i < 200; i++) {
        double mid = 0.5 * (lo + hi);
        if (mid <= lo || mid >= hi)
            break;
        if (ocean_dispersion(mid, depth) + v * mid < w_ny)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

ocean_result ocean_filter_cutoff_compute(const ocean_filter_config *c, ocean_filter_policy p,
                                         const ocean_filter_client *cl, ocean_filter_cutoff *out)
{
    if (c == NULL || cl == NULL || out == NULL)
        return OCEAN_EINVAL;
    if (ocean_filter_config_validate(c, NULL, 0) != OCEAN_OK)
        return OCEAN_EINVAL;
    if (!isfinite(cl->speed_mps) || cl->speed_mps < 0.0)
        return OCEAN_EINVAL;
    if (!isfinite(cl->fps) || cl->fps < 0.0)
        return OCEAN_EINVAL;
    if (!isfinite(cl->spacing_m) || cl->spacing_m < 0.0)
        return OCEAN_EINVAL;

    double v = cl->speed_mps;
    ocean_filter_cutoff r = {.k = INFINITY, .hz = NAN, .low_boost = 1.0,
                             .order = c->order, .limited_by = 0};
    switch (p) {
    case OCEAN_FILTER_NONE:
        break;
    case OCEAN_FILTER_SEED: {
        double beta = v > c->beta_switch_mps ? c->beta_fast : c->beta_slow;
        double fc = c->f_base_hz + beta * v;
        r.hz = fc;
        r.k = 2.0 * M_PI * fc / c->v_wave_mps;
        if (v > c->boost_speed_mps)
            r.low_boost = 1.0 + c->boost_fraction;
        break;
    }
    case OCEAN_FILTER_ANTIALIAS: {
        double ks = INFINITY, kt = INFINITY;
        if (cl->spacing_m > 0.0)
            ks = 2.0 * M_PI / (4.0 * cl->spacing_m);
        if (cl->fps > 0.0)
            kt = temporal_limit(v, M_PI * cl->fps, c->depth_m);
        double lim = fmin(ks, kt);
        if (isfinite(lim)) {
            r.limited_by = kt < ks ? 2 : 1;
            /* Move kc below the limit so the gain there is alias_gain. */
            r.k = lim;
            if (c->alias_gain < M_SQRT1_2 * (1.0 - 1e-12))
                r.k = lim / ocean_filter_negligible_k(1.0, c->order, c->alias_gain);
            r.hz = (ocean_dispersion(r.k, c->depth_m) + v * r.k) / (2.0 * M_PI);
        }
        break;
    }
    default:
        return OCEAN_EINVAL;
    }
    if (isnan(r.k) || r.k < 0.0)
        return OCEAN_EINVAL;
    *out = r;
    return OCEAN_OK;
}

double ocean_filter_cutoff_gain(const ocean_filter_cutoff *c, double k)
{
    double h = ocean_filter_gain(k, c->k, c->order);
    if (c->low_boost == 1.0)
        return h;
    return h * (1.0 + (c->low_boost - 1.0) * h * h);
}

/* ---- Smoother --------------------------------------------------------------- */

void ocean_filter_smoother_init(ocean_filter_smoother *s)
{
    s->tau_s = 0.25;
    s->max_log_rate = 2.0;
    s->k_floor = 1e-4;
    s->k_ceil = 1e4;
    s->log_k = 0.0;
    s->k = NAN;
    s->primed = 0;
}

#define SNAP_LOG 1e-6

ocean_result ocean_filter_smoother_update(ocean_filter_smoother *s, double target_k, double dt,
                                          double *k_out)
{
    if (s == NULL || k_out == NULL)
        return OCEAN_EINVAL;
    if (isnan(target_k) || target_k < 0.0 || !isfinite(dt) || dt < 0.0)
        return OCEAN_EINVAL;
    if (!(s->tau_s >= 0.0) || !isfinite(s->tau_s) || !(s->max_log_rate > 0.0) ||
        !(s->k_floor > 0.0) || !(s->k_ceil > s->k_floor) || !isfinite(s->k_ceil))
        return OCEAN_EINVAL;

    double lo = log(s->k_floor), hi = log(s->k_ceil);
    double xt = target_k <= s->k_floor ? lo : target_k >= s->k_ceil ? hi : log(target_k);
    double x;
    if (!s->primed || !isfinite(s->log_k)) {
        x = xt;
    } else {
        double x0 = fmin(fmax(s->log_k, lo), hi);
        double d = xt - x0;
        double a = s->tau_s > 0.0 ? -expm1(-dt / s->tau_s) : 1.0;
        double step = d * a;
        double lim = s->max_log_rate * dt;
        if (step > lim)
            step = lim;
        else if (step < -lim)
            step = -lim;
        x = x0 + step;
        /* Snap the exponential tail, but never with a step over the limit. */
        if (fabs(xt - x) < SNAP_LOG && fabs(d) <= lim)
            x = xt;
    }
    s->log_k = x;
    s->primed = 1;
    double k = exp(x);
    if (x == xt && (target_k >= s->k_ceil || target_k <= s->k_floor))
        k = target_k;
    s->k = k;
    *k_out = k;
    return OCEAN_OK;
}

/* ---- Buckets ---------------------------------------------------------------- */

void ocean_filter_buckets_default(ocean_filter_buckets *b)
{
    b->per_octave = 4;
    b->octaves = 20;
    b->k_lo = 1.0 / 1024.0;
}

ocean_result ocean_filter_buckets_validate(const ocean_filter_buckets *b)
{
    if (b == NULL || b->per_octave < 1 || b->per_octave > 64 || b->octaves < 1 ||
        b->octaves > 128 || !(b->k_lo > 0.0) || !isfinite(b->k_lo))
        return OCEAN_EINVAL;
    double top = ldexp(b->k_lo, b->octaves);
    if (!isfinite(top))
        return OCEAN_EINVAL;
    return OCEAN_OK;
}

static int levels(const ocean_filter_buckets *b)
{
    return b->per_octave * b->octaves + 1;
}

int ocean_filter_bucket_count(const ocean_filter_buckets *b)
{
    if (ocean_filter_buckets_validate(b) != OCEAN_OK)
        return 0;
    return levels(b) + 2;
}

/* Level j (0-based) = k_lo 2^(j / per_octave); whole octaves are exact. */
static double level_k(const ocean_filter_buckets *b, int j)
{
    int oct = j / b->per_octave, rem = j % b->per_octave;
    return ldexp(b->k_lo * exp2((double)rem / b->per_octave), oct);
}

ocean_result ocean_filter_bucket_of(const ocean_filter_buckets *b, double kc, int *index)
{
    if (ocean_filter_buckets_validate(b) != OCEAN_OK || index == NULL || isnan(kc) || kc < 0.0)
        return OCEAN_EINVAL;
    int L = levels(b);
    if (isinf(kc)) {
        *index = L + 1;
        return OCEAN_OK;
    }
    if (kc < b->k_lo) {
        *index = 0;
        return OCEAN_OK;
    }
    double f = floor(b->per_octave * log2(kc / b->k_lo));
    int j = f > L - 1 ? L - 1 : (int)f;
    if (j < 0)
        j = 0;
    /* Make level(j) <= kc < level(j+1) hold exactly despite log2 rounding. */
    while (j + 1 <= L - 1 && level_k(b, j + 1) <= kc)
        j++;
    while (j > 0 && level_k(b, j) > kc)
        j--;
    *index = j + 1;
    return OCEAN_OK;
}

ocean_result ocean_filter_bucket_cutoff(const ocean_filter_buckets *b, int index, double *kc)
{
    if (ocean_filter_buckets_validate(b) != OCEAN_OK || kc == NULL)
        return OCEAN_EINVAL;
    int L = levels(b);
    if (index < 0 || index > L + 1)
        return OCEAN_EINVAL;
    if (index == 0)
        *kc = 0.0;
    else if (index == L + 1)
        *kc = INFINITY;
    else
        *kc = level_k(b, index - 1);
    return OCEAN_OK;
}

/* ---- Energy ------------------------------------------------------------------ */

void ocean_filter_energy_init(ocean_filter_energy *e)
{
    memset(e, 0, sizeof *e);
}

void ocean_filter_energy_add(ocean_filter_energy *e, double gain, double p)
{
    if (!(p >= 0.0) || !isfinite(p) || !isfinite(gain))
        return;
    double m = 1.0 - gain;
    e->sum_p += p;
    e->sum_gp += gain * p;
    e->sum_g2p += gain * gain * p;
    e->sum_1mg2p += m * m * p;
}

double ocean_filter_energy_e_error(const ocean_filter_energy *e)
{
    if (!(e->sum_p > 0.0))
        return 0.0;
    return sqrt(e->sum_1mg2p / e->sum_p);
}

double ocean_filter_energy_scale(const ocean_filter_energy *e)
{
    if (!(e->sum_p > 0.0) || !(e->sum_g2p > 0.0))
        return 1.0;
    /* Two square roots: the quotient of the sums could overflow. */
    double s = sqrt(e->sum_p) / sqrt(e->sum_g2p);
    return isfinite(s) ? s : 1.0;
}

double ocean_filter_energy_e_error_redistributed(const ocean_filter_energy *e)
{
    if (!(e->sum_p > 0.0))
        return 0.0;
    double s = ocean_filter_energy_scale(e);
    double r = (e->sum_p - 2.0 * s * e->sum_gp + s * s * e->sum_g2p) / e->sum_p;
    return r > 0.0 ? sqrt(r) : 0.0;
}

ocean_result ocean_filter_energy_modes(const ocean_filter_cutoff *c, const double *k,
                                       const double *p, size_t n, ocean_filter_energy *out)
{
    if (c == NULL || out == NULL || (n > 0 && (k == NULL || p == NULL)))
        return OCEAN_EINVAL;
    ocean_filter_energy e;
    ocean_filter_energy_init(&e);
    for (size_t i = 0; i < n; i++)
        ocean_filter_energy_add(&e, ocean_filter_cutoff_gain(c, k[i]), p[i]);
    *out = e;
    return OCEAN_OK;
}

/* 8-point Gauss-Legendre nodes and weights on [-1, 1]. */
static const double gl8_x[4] = {0.1834346424956498, 0.5255324099163290,
                                0.7966664774136267, 0.9602898564975363};
static const double gl8_w[4] = {0.3626837833783620, 0.3137066458778873,
                                0.2223810344533745, 0.1012285362903763};

ocean_result ocean_filter_energy_integrate(const ocean_filter_cutoff *c,
                                           double (*psi)(double k, void *ctx), void *ctx,
                                           double k_a, double k_b, int panels,
                                           ocean_filter_energy *out)
{
    if (c == NULL || psi == NULL || out == NULL || !(k_a > 0.0) || !(k_b > k_a) ||
        !isfinite(k_b) || panels < 1 || panels > 1000000)
        return OCEAN_EINVAL;
    ocean_filter_energy e;
    ocean_filter_energy_init(&e);
    double ua = log(k_a), du = (log(k_b) - ua) / panels;
    for (int i = 0; i < panels; i++) {
        double mid = ua + (i + 0.5) * du;
        for (int j = 0; j < 8; j++) {
            double u = mid + (j < 4 ? -1.0 : 1.0) * gl8_x[j & 3] * 0.5 * du;
            double k = exp(u);
            double p = psi(k, ctx) * k * gl8_w[j & 3] * 0.5 * du;
            ocean_filter_energy_add(&e, ocean_filter_cutoff_gain(c, k), p);
        }
    }
    *out = e;
    return OCEAN_OK;
}

/* ---- Dominant wavelength ------------------------------------------------------ */

ocean_result ocean_filter_dominant_wavelength(const ocean_sea_state *sea, double *lambda_m)
{
    if (sea == NULL || lambda_m == NULL)
        return OCEAN_EINVAL;
    if (ocean_sea_state_validate(sea, NULL, 0) != OCEAN_OK)
        return OCEAN_EINVAL;
    double wp = ocean_spectrum_peak(sea);
    if (!(wp > 0.0) || !isfinite(wp))
        return OCEAN_EUNSUPPORTED;
    double kp = ocean_wavenumber(wp, sea->depth_m);
    if (!(kp > 0.0) || !isfinite(kp))
        return OCEAN_EUNSUPPORTED;
    *lambda_m = 2.0 * M_PI / kp;
    return OCEAN_OK;
}

ocean_result ocean_filter_mesh_spacing(const ocean_sea_state *sea, double factor, double *dx_m)
{
    if (dx_m == NULL || !(factor >= 0.1 && factor <= 0.5))
        return OCEAN_EINVAL;
    double lambda;
    ocean_result r = ocean_filter_dominant_wavelength(sea, &lambda);
    if (r != OCEAN_OK)
        return r;
    *dx_m = factor * lambda;
    return OCEAN_OK;
}
