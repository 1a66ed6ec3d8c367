/*
 * foam.c - the whitecap model of foam.h: coverage target, the ramp on the
 * breaking index solved for a Gaussian field with its trails, coverage of
 * sampled foam.
 *
 * Threads: pure functions; ocean_foam_map_solve keeps its last solutions
 * per thread.
 */
#include "foam.h"

#include <math.h>

#include "ocean.h"

#define W_MAX 0.95

double ocean_foam_coverage_target(double u10)
{
    if (!(u10 > 0.0))
        return 0.0;
    if (!isfinite(u10))
        return W_MAX;
    double ustar = sqrt((0.8 + 0.065 * u10) * 1e-3) * u10;
    double w = OCEAN_FOAM_K * ustar * ustar * ustar;
    return w < W_MAX ? w : W_MAX;
}

double ocean_foam_monahan(double u10)
{
    if (!(u10 > 0.0))
        return 0.0;
    return 3.84e-6 * pow(u10, 3.41);
}

/* E[(X - c)+] for X ~ N(0, sigma^2): sigma phi(c/sigma) - c Q(c/sigma). */
static double excess(double c, double sigma)
{
    if (sigma <= 0.0)
        return c < 0.0 ? -c : 0.0;
    double z = c / sigma;
    double phi = exp(-0.5 * z * z) / sqrt(2.0 * M_PI);
    double q = 0.5 * erfc(z / M_SQRT2);
    double e = sigma * phi - c * q;
    return e > 0.0 ? e : 0.0;
}

/* Nodes of the trail quadrature: the envelope u = |Z| / sigma on
 * [0, U_MAX] (Rayleigh; the tail past 9.5 holds e^-45), the phase since
 * the crest on [0, 2 pi); midpoint rules.  Checked against a Monte Carlo
 * of Gaussian (beta, q) pairs in tests/test_foam.c. */
#define U_MAX 9.5
#define U_NODES 320
#define PHASE_NODES 96

/* E[foam] with trails (foam.h): over the envelope e (Rayleigh, std sigma
 * per component) and the phase th since the crest (uniform), independent
 * for a Gaussian field; beta = e cos th. */
static double mean_with_trails(const ocean_foam_map *m, double sigma)
{
    double cs[PHASE_NODES], dec[PHASE_NODES];
    for (int j = 0; j < PHASE_NODES; j++) {
        double ph = (j + 0.5) * (2.0 * M_PI / PHASE_NODES);
        cs[j] = cos(ph);
        dec[j] = exp(-m->decay * ph);
    }
    const double du = U_MAX / U_NODES;
    double s = 0.0;
    for (int i = 0; i < U_NODES; i++) {
        double u = (i + 0.5) * du, e = sigma * u;
        if (e < m->a)
            continue; /* no sample of this envelope reaches the ramp */
        double fe = ocean_foam_ramp(m, e), in = 0.0;
        for (int j = 0; j < PHASE_NODES; j++) {
            double fi = ocean_foam_ramp(m, e * cs[j]), tr = fe * dec[j];
            in += tr > fi ? tr : fi;
        }
        s += u * exp(-0.5 * u * u) * du * in / PHASE_NODES;
    }
    return s;
}

double ocean_foam_map_mean(const ocean_foam_map *m, double sigma)
{
    if (m->uniform >= 0.0)
        return m->uniform;
    if (m->decay < INFINITY && sigma > 0.0)
        return mean_with_trails(m, sigma);
    if (m->b <= m->a)
        return sigma > 0.0 ? 0.5 * erfc(m->b / sigma / M_SQRT2) : (m->b <= 0.0 ? 1.0 : 0.0);
    return (excess(m->a, sigma) - excess(m->b, sigma)) / (m->b - m->a);
}

/* The ramp's start for target w (the map's b, uniform and decay set).
 * The mean falls monotonically as a grows and tends to 1 as a -> -inf:
 * bracket, then regula falsi with the Illinois step (superlinear: a
 * dozen means where bisection took forty, and a mean with trails is a
 * 30 000-node quadrature) to 1e-9 of w. */
static double solve_a(ocean_foam_map t, double sigma, double w)
{
    const double b = OCEAN_FOAM_BETA_BREAK;
    double lo = b - sigma, hi = b, glo = 0.0, ghi;
    t.a = hi;
    ghi = ocean_foam_map_mean(&t, sigma) - w; /* < 0: the caller checked */
    for (int i = 0; i < 200; i++) {
        t.a = lo;
        glo = ocean_foam_map_mean(&t, sigma) - w;
        if (glo >= 0.0)
            break;
        hi = lo;
        ghi = glo;
        lo = b - 2.0 * (b - lo);
    }
    int side = 0;
    for (int i = 0; i < 100 && hi - lo > 1e-12 * sigma; i++) {
        double a = glo == ghi ? 0.5 * (lo + hi) : lo + (hi - lo) * glo / (glo - ghi);
        if (!(a > lo && a < hi))
            a = 0.5 * (lo + hi);
        t.a = a;
        double g = ocean_foam_map_mean(&t, sigma) - w;
        if (fabs(g) <= 1e-9 * w)
            return a;
        if (g > 0.0) {
            lo = a, glo = g;
            if (side == 1) ghi *= 0.5;
            side = 1;
        } else {
            hi = a, ghi = g;
            if (side == -1) glo *= 0.5;
            side = -1;
        }
    }
    return 0.5 * (lo + hi);
}

static ocean_result map_solve(double sigma, double decay, double w, ocean_foam_map *out)
{
    const double b = OCEAN_FOAM_BETA_BREAK;
    *out = (ocean_foam_map){.a = b, .b = b, .uniform = -1.0, .decay = decay};
    if (w == 0.0) {
        /* No whitecaps: not even the criterion's own breakers. */
        out->a = out->b = INFINITY;
        return OCEAN_OK;
    }
    /* sigma = 0 (everything filtered, or no short waves): the unresolved
     * coverage is spread evenly. */
    if (!(sigma > 1e-12 * b)) {
        out->uniform = w;
        return OCEAN_OK;
    }
    /* Active breaking (and its trails) alone already covers w: a step at
     * the criterion. */
    if (ocean_foam_map_mean(out, sigma) >= w)
        return OCEAN_OK;
    out->a = solve_a(*out, sigma, w);
    return OCEAN_OK;
}

/* The last solutions, per thread: the exact sums (ocean_reference) solve
 * their map at every point, and a solve with trails costs a few
 * milliseconds (an ocean memoises its own maps per filter).  Same inputs,
 * same result: a cache, not state. */
#define SOLVED_KEEP 16
typedef struct solved {
    double sigma, omega, w;
    ocean_foam_map m;
    int used;
} solved;
static _Thread_local solved solved_keep[SOLVED_KEEP];
static _Thread_local int solved_next;

ocean_result ocean_foam_map_solve(double sigma, double omega, double w, ocean_foam_map *out)
{
    if (!out || !(sigma >= 0.0) || !isfinite(sigma) || !(omega >= 0.0) || !(w >= 0.0 && w < 1.0))
        return OCEAN_EINVAL;
    for (int i = 0; i < SOLVED_KEEP; i++)
        if (solved_keep[i].used && solved_keep[i].sigma == sigma && solved_keep[i].omega == omega &&
            solved_keep[i].w == w) {
            *out = solved_keep[i].m;
            return OCEAN_OK;
        }
    /* omega = 0: a field that does not move has no crest passing: no trail. */
    double decay = omega > 0.0 ? 1.0 / (omega * OCEAN_FOAM_DECAY_S) : INFINITY;
    ocean_result r = map_solve(sigma, decay, w, out);
    if (r == OCEAN_OK) {
        solved_keep[solved_next] = (solved){sigma, omega, w, *out, 1};
        solved_next = (solved_next + 1) % SOLVED_KEEP;
    }
    return r;
}

double ocean_whitecap_coverage(const float *foam, size_t n)
{
    if (!foam)
        return 0.0;
    double s = 0.0;
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        float f = foam[i];
        if (isnan(f))
            continue;
        s += f < 0.0f ? 0.0 : (f > 1.0f ? 1.0 : f);
        m++;
    }
    return m ? s / (double)m : 0.0;
}

ocean_result ocean_whitecap_coverage_frame(const ocean_frame *f, double x0, double z0,
                                           double size_m, int n, double *out)
{
    if (!f || !out || !isfinite(x0) || !isfinite(z0) || !isfinite(size_m) || !(size_m > 0.0) ||
        n < 1 || n > 4096)
        return OCEAN_EINVAL;
    double h = size_m / n, s = 0.0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            ocean_point p;
            ocean_frame_sample_some(f, x0 + j * h, z0 + i * h, OCEAN_SAMPLE_FOAM, &p);
            s += p.foam;
        }
    *out = s / ((double)n * n);
    return OCEAN_OK;
}
