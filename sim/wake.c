/*
 * wake.c - the steady wake of a moving pressure distribution (see wake.h).
 *
 * In the body's frame the water streams past at U along +x.  A surface
 * pressure p = rho g A f(x, z) moving at -U x drives each Fourier mode k at
 * the frequency w = -U kx, and linear theory (the kinematic and dynamic
 * surface conditions over depth h) gives the mode's elevation
 *
 *   eta(k) = A w0^2 f(k) / ((w + i eps)^2 - w0^2),  w0^2 = g |k| tanh(|k| h),
 *
 * the small eps being the radiation condition (the motion started long
 * ago, Rayleigh's device): waves only behind the body.  eps sets how far
 * the waves reach before they fade: a transverse wave's amplitude falls as
 * exp(-2 eps x / U) (the pole moves to kx = g/U^2 + 2 i eps / U), here by
 * e over 20 transverse wavelengths, so the periodic FFT domain (85
 * wavelengths along the track) holds the pattern without its wrapped tail
 * reaching the grid returned.  f is a hull's footprint: (1 - r^2)^2 over
 * the ellipse of the body's length L and beam B = L / 6 (r = 1 on its
 * edge), whose transform is 4 pi L B J3(q) / q^3 with q^2 = (kx L/2)^2 +
 * (kz B/2)^2.  Its edges are sharp enough to raise the short divergent
 * waves that make the cusp, as a bow does (a Gaussian of the hull's size
 * keeps only the transverse waves at low Froude numbers: its spectrum
 * falls as exp(-k^2)).
 *
 * OOM policy: a buffer that cannot be allocated fails the call with
 * OCEAN_ENOMEM, nothing kept.
 */
#include "wake.h"

#include <fftw3.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ocean_internal.h"

#define WAKE_G 9.81
#define WAKE_PER_WAVE 12       /* grid points per transverse wavelength at most */
#define WAKE_FADE_WAVES 20.0   /* e-folding of the waves' amplitude, in wavelengths */
#define WAKE_FFT_MAX 4096      /* FFT points per side at most */
#define WAKE_LENGTH_PER_BEAM 6.0

ocean_result wake_params_validate(const wake_params *p, char *msg, size_t msglen)
{
    const char *bad = NULL;
    if (!(p->speed > 0 && p->speed <= WAKE_SPEED_MAX)) bad = "speed";
    else if (!(p->length >= WAKE_LENGTH_MIN && p->length <= WAKE_LENGTH_MAX)) bad = "length";
    else if (!(p->depth > 0)) bad = "depth";
    if (!bad) return OCEAN_OK;
    if (msg)
        snprintf(msg, msglen, "wake %s %g out of range (speed (0, %g] m/s, length [%g, %g] m, depth > 0 m or inf)",
                 bad, !strcmp(bad, "speed") ? p->speed : !strcmp(bad, "length") ? p->length : p->depth,
                 WAKE_SPEED_MAX, WAKE_LENGTH_MIN, WAKE_LENGTH_MAX);
    return OCEAN_EINVAL;
}

double wake_transverse_wavelength(const wake_params *p)
{
    double U2 = p->speed * p->speed;
    if (isinf(p->depth)) return 2 * M_PI * U2 / WAKE_G;
    if (U2 >= WAKE_G * p->depth) return 0;
    /* (g / k) tanh(k h) = U^2: the left side falls from g h (k -> 0) to 0,
     * so bisection on k between the deep-water root and 0 */
    double lo = 0, hi = WAKE_G / U2;
    for (int i = 0; i < 200; i++) {
        double k = 0.5 * (lo + hi);
        if (WAKE_G / k * tanh(k * p->depth) > U2) lo = k;
        else hi = k;
    }
    return 2 * M_PI / (0.5 * (lo + hi));
}

static int pow2_at_least(double n)
{
    int m = 64;
    while (m < n && m < WAKE_FFT_MAX) m *= 2;
    return m;
}

/* The elevation spectrum of p on an nz x nx grid of spacing dx (FFT order)
 * into buf. */
static void wake_spectrum(const wake_params *p, double lambda, int nx, int nz, double dx, fftwf_complex *buf)
{
    double U = p->speed, eps = U / (2 * WAKE_FADE_WAVES * lambda);
    double L = p->length, B = L / WAKE_LENGTH_PER_BEAM;
    double f0 = 4 * M_PI * L * B / (dx * dx);   /* the footprint's DFT over J3(q) / q^3 */
    for (int iz = 0; iz < nz; iz++) {
        double kz = 2 * M_PI * (iz < nz / 2 ? iz : iz - nz) / (nz * dx);
        for (int ix = 0; ix < nx; ix++) {
            double kx = 2 * M_PI * (ix < nx / 2 ? ix : ix - nx) / (nx * dx);
            double k = hypot(kx, kz);
            double w02 = WAKE_G * k * (isinf(p->depth) ? 1.0 : tanh(k * p->depth));
            double q = hypot(0.5 * kx * L, 0.5 * kz * B);
            double f = f0 * (q < 1e-3 ? (1 - q * q / 16) / 48 : jn(3, q) / (q * q * q));
            double a = -U * kx, re = a * a - eps * eps - w02, im = 2 * a * eps, d = re * re + im * im;
            fftwf_complex *c = &buf[(size_t)iz * nx + ix];
            (*c)[0] = d > 0 ? (float)(w02 * f * re / d) : 0.0f;
            (*c)[1] = d > 0 ? (float)(-w02 * f * im / d) : 0.0f;
        }
    }
}

ocean_result wake_steady(const wake_params *p, wake_grid *out, char *msg, size_t msglen)
{
    return wake_steady_to(p, WAKE_BEHIND, out, msg, msglen);
}

ocean_result wake_steady_to(const wake_params *p, double behind, wake_grid *out, char *msg, size_t msglen)
{
    memset(out, 0, sizeof *out);
    if (!(behind >= 1 && behind <= 100)) {
        if (msg) snprintf(msg, msglen, "wake grid %g transverse wavelengths behind the body: not in [1, 100]", behind);
        return OCEAN_EINVAL;
    }
    ocean_result r = wake_params_validate(p, msg, msglen);
    if (r != OCEAN_OK) return r;
    double lambda = wake_transverse_wavelength(p);
    if (lambda <= 0) lambda = 2 * M_PI * p->speed * p->speed / WAKE_G;  /* no transverse waves: the deep scale */
    double fh = isinf(p->depth) ? 0 : p->speed / sqrt(WAKE_G * p->depth);
    double dx = fmin(lambda / WAKE_PER_WAVE, p->length / 8);
    /* the wedge widens toward 90 deg as the depth Froude number nears 1 */
    double half = (fh > 0.5 ? 1.1 : 0.55) * behind * lambda;
    int nx = pow2_at_least(fmax(85, 1.5 * behind + 40) * lambda / dx), nz = pow2_at_least(4 * half / dx);
    fftwf_complex *buf = fftwf_malloc(sizeof *buf * (size_t)nx * nz);
    out->nx = (int)lround((behind + 2) * lambda / dx) + 1;
    out->nz = 2 * (int)lround(half / dx) + 1;
    if (out->nx > nx / 2) out->nx = nx / 2;
    if (out->nz > nz / 2) out->nz = nz / 2 | 1;
    out->heights = malloc(sizeof(float) * (size_t)out->nx * out->nz);
    if (!buf || !out->heights) {
        fftwf_free(buf);
        wake_grid_free(out);
        if (msg) snprintf(msg, msglen, "out of memory for a %d x %d wake grid", nx, nz);
        return OCEAN_ENOMEM;
    }
    ocean_fft_planner_lock();
    fftwf_plan plan = fftwf_plan_dft_2d(nz, nx, buf, buf, FFTW_BACKWARD, FFTW_ESTIMATE);
    ocean_fft_planner_unlock();
    wake_spectrum(p, lambda, nx, nz, dx, buf);
    fftwf_execute(plan);
    ocean_fft_planner_lock();
    fftwf_destroy_plan(plan);
    ocean_fft_planner_unlock();
    int ix0 = -(int)lround(2 * lambda / dx), iz0 = -(out->nz / 2);
    out->dx = dx;
    out->x0 = ix0 * dx;
    out->z0 = iz0 * dx;
    double norm = 1.0 / ((double)nx * nz);
    for (int iz = 0; iz < out->nz; iz++)
        for (int ix = 0; ix < out->nx; ix++) {
            int gx = ((ix0 + ix) % nx + nx) % nx, gz = ((iz0 + iz) % nz + nz) % nz;
            out->heights[(size_t)iz * out->nx + ix] = (float)(buf[(size_t)gz * nx + gx][0] * norm);
        }
    fftwf_free(buf);
    return OCEAN_OK;
}

void wake_grid_free(wake_grid *g)
{
    if (!g) return;
    free(g->heights);
    g->heights = NULL;
}
