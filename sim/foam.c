/*
 * foam.c - the whitecap model of foam.h: coverage target, the ramp on the
 * breaking index solved for a Gaussian field, coverage of sampled foam.
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

double ocean_foam_map_mean(const ocean_foam_map *m, double sigma)
{
    if (m->uniform >= 0.0)
        return m->uniform;
    if (m->b <= m->a)
        return sigma > 0.0 ? 0.5 * erfc(m->b / sigma / M_SQRT2) : (m->b <= 0.0 ? 1.0 : 0.0);
    return (excess(m->a, sigma) - excess(m->b, sigma)) / (m->b - m->a);
}

ocean_result ocean_foam_map_solve(double sigma, double w, ocean_foam_map *out)
{
    if (!out || !(sigma >= 0.0) || !isfinite(sigma) || !(w >= 0.0 && w < 1.0))
        return OCEAN_EINVAL;
    const double b = OCEAN_FOAM_BETA_BREAK;
    *out = (ocean_foam_map){.a = b, .b = b, .uniform = -1.0};
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
    /* Active breaking alone already covers w: a step at the criterion. */
    if (ocean_foam_map_mean(out, sigma) >= w)
        return OCEAN_OK;
    /* The mean grows monotonically as a falls; it tends to 1 as a -> -inf.
     * Bracket, then bisect (60 halvings: a to ~1e-18 of the bracket). */
    double lo = b - sigma, hi = b;
    ocean_foam_map t = *out;
    for (int i = 0; i < 200; i++) {
        t.a = lo;
        if (ocean_foam_map_mean(&t, sigma) >= w)
            break;
        hi = lo;
        lo = b - 2.0 * (b - lo);
    }
    for (int i = 0; i < 80; i++) {
        t.a = 0.5 * (lo + hi);
        if (ocean_foam_map_mean(&t, sigma) >= w)
            lo = t.a;
        else
            hi = t.a;
    }
    out->a = 0.5 * (lo + hi);
    return OCEAN_OK;
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
