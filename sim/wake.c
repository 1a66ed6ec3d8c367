/*
 * wake.c - the steady wake of a moving pressure distribution summed by FFT
 * (see wake.h); its reading is wake_pattern.c.
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
#include "wake_internal.h"


/* One line of n samples, stride apart, into spline coefficients: the
 * causal and anti-causal passes of the pole sqrt(3) - 2, mirrored ends. */
static void bspline_line(float *c, int n, size_t stride, double *tmp)
{
    const double z = sqrt(3.0) - 2;
    for (int i = 0; i < n; i++) tmp[i] = 6.0 * c[(size_t)i * stride];
    double sum = tmp[0], zk = z;
    for (int k = 1; k < n && k < 40; k++, zk *= z) sum += zk * tmp[k];   /* |z|^40 < 1e-22 */
    tmp[0] = sum;
    for (int i = 1; i < n; i++) tmp[i] += z * tmp[i - 1];
    tmp[n - 1] = z / (z * z - 1) * (tmp[n - 1] + z * tmp[n - 2]);
    for (int i = n - 2; i >= 0; i--) tmp[i] = z * (tmp[i + 1] - tmp[i]);
    for (int i = 0; i < n; i++) c[(size_t)i * stride] = (float)tmp[i];
}

/* g's samples into the coefficients of the cubic spline through them.
 * OCEAN_ENOMEM. */
static ocean_result bspline_prefilter(wake_grid *g)
{
    double *tmp = malloc(sizeof(double) * (size_t)(g->nx > g->nz ? g->nx : g->nz));
    if (!tmp) return OCEAN_ENOMEM;
    for (int iz = 0; iz < g->nz; iz++) bspline_line(g->heights + (size_t)iz * g->nx, g->nx, 1, tmp);
    for (int ix = 0; ix < g->nx; ix++) bspline_line(g->heights + ix, g->nz, (size_t)g->nx, tmp);
    free(tmp);
    return OCEAN_OK;
}


/* The largest |reading - series| in each block of cells, measured where a cubic
 * reading strays most, half-way between the samples (the middles of the
 * cells and of their edges): the series there is the spectrum shifted by
 * half a cell, one more FFT per offset; through the window, as read.
 * spec is the spectrum (kept), buf the plan's buffer.  OCEAN_ENOMEM. */
static ocean_result reading_error(wake_pattern *pat, const fftwf_complex *spec, fftwf_complex *buf, fftwf_plan plan)
{
    const wake_layout *w = &pat->w;
    const wake_grid *g = &pat->g;
    static const double shift[3][2] = {{0.5, 0}, {0, 0.5}, {0.5, 0.5}};
    double norm = 1.0 / ((double)w->fx * w->fz), half[4], whole[4];
    wake_bspline_weights(0.5, half);
    wake_bspline_weights(0, whole);
    /* the shift's phase per mode, e^{i (px + pz)}, from one table a side */
    double *tx = malloc(sizeof *tx * 2 * (size_t)(w->fx + w->fz)), *tz = tx ? tx + 2 * (size_t)w->fx : NULL;
    if (!tx) return OCEAN_ENOMEM;
    for (int s = 0; s < 3; s++) {
        for (int ix = 0; ix < w->fx; ix++) {
            double ph = wake_wavenumber(ix, w->fx, w->dx) * w->dx * shift[s][0];
            tx[2 * ix] = cos(ph), tx[2 * ix + 1] = sin(ph);
        }
        for (int iz = 0; iz < w->fz; iz++) {
            double ph = wake_wavenumber(iz, w->fz, w->dx) * w->dx * shift[s][1];
            tz[2 * iz] = cos(ph), tz[2 * iz + 1] = sin(ph);
        }
        for (int iz = 0; iz < w->fz; iz++)
            for (int ix = 0; ix < w->fx; ix++) {
                double c = tz[2 * iz] * tx[2 * ix] - tz[2 * iz + 1] * tx[2 * ix + 1];
                double sn = tz[2 * iz + 1] * tx[2 * ix] + tz[2 * iz] * tx[2 * ix + 1];
                const float *a = spec[(size_t)iz * w->fx + ix];
                buf[(size_t)iz * w->fx + ix][0] = (float)(a[0] * c - a[1] * sn);
                buf[(size_t)iz * w->fx + ix][1] = (float)(a[0] * sn + a[1] * c);
            }
        fftwf_execute(plan);
        const double *ax = shift[s][0] > 0 ? half : whole, *az = shift[s][1] > 0 ? half : whole;
        for (int iz = 1; iz <= g->nz - 3; iz++)
            for (int ix = 1; ix <= g->nx - 3; ix++) {
                int gx = ((w->ix0 + ix) % w->fx + w->fx) % w->fx, gz = ((w->iz0 + iz) % w->fz + w->fz) % w->fz;
                double exact = buf[(size_t)gz * w->fx + gx][0] * norm, wx, wz;
                double x = g->x0 + (ix + shift[s][0]) * g->dx, z = g->z0 + (iz + shift[s][1]) * g->dx;
                double win = wake_window(pat, x, z, &wx, &wz);
                float *b = &pat->block_bound[(size_t)(iz / WAKE_BLOCK) * pat->bx + ix / WAKE_BLOCK];
                if (win > 0) *b = fmaxf(*b, (float)(win * fabs(wake_grid_cubic(g, ix, iz, ax, az) - exact)));
            }
    }
    free(tx);
    return OCEAN_OK;
}

/* Each block's bound: the largest error measured in it and its eight
 * neighbours (a reading's stencil reaches a cell beyond its own), half
 * again for the points between those measured. */
static void block_bounds(wake_pattern *pat)
{
    size_t n = (size_t)pat->bx * pat->bz;
    float *m = malloc(sizeof *m * n);
    if (!m) {   /* keep the measured, one bound for all */
        for (size_t i = 0; i < n; i++) pat->bound = fmax(pat->bound, pat->block_bound[i]);
        for (size_t i = 0; i < n; i++) pat->block_bound[i] = (float)(1.5 * pat->bound);
        pat->bound *= 1.5;
        return;
    }
    for (int j = 0; j < pat->bz; j++)
        for (int i = 0; i < pat->bx; i++) {
            float v = 0;
            for (int dj = -1; dj <= 1; dj++)
                for (int di = -1; di <= 1; di++) {
                    int a = i + di, b = j + dj;
                    if (a >= 0 && b >= 0 && a < pat->bx && b < pat->bz) v = fmaxf(v, pat->block_bound[b * pat->bx + a]);
                }
            m[(size_t)j * pat->bx + i] = 1.5f * v;
            pat->bound = fmax(pat->bound, 1.5 * v);
        }
    memcpy(pat->block_bound, m, sizeof *m * n);
    free(m);
}


/* The series of p on its layout's grid into *out; with pat (whose p, w
 * and out these are) its bound: the reading's error, measured
 * per block of cells (reading_error, block_bounds). */
static ocean_result wake_sum(const wake_params *p, const wake_layout *w, wake_grid *out, wake_pattern *pat,
                             char *msg, size_t msglen)
{
    int bound = pat != NULL;
    size_t modes = (size_t)w->fx * w->fz;
    fftwf_complex *buf = fftwf_malloc(sizeof *buf * modes), *spec = bound ? fftwf_malloc(sizeof *spec * modes) : NULL;
    out->nx = w->nx;
    out->nz = w->nz;
    out->heights = malloc(sizeof(float) * (size_t)out->nx * out->nz);
    if (!buf || !out->heights || (bound && !spec)) {
        fftwf_free(buf);
        fftwf_free(spec);
        wake_grid_free(out);
        if (msg) snprintf(msg, msglen, "out of memory for a %d x %d wake grid", w->fx, w->fz);
        return OCEAN_ENOMEM;
    }
    ocean_fft_planner_lock();
    fftwf_plan plan = fftwf_plan_dft_2d(w->fz, w->fx, buf, buf, FFTW_BACKWARD, FFTW_ESTIMATE);
    ocean_fft_planner_unlock();
    wake_spectrum(p, w, buf);
    if (spec) memcpy(spec, buf, sizeof *spec * modes);
    fftwf_execute(plan);
    out->dx = w->dx;
    out->x0 = w->ix0 * w->dx;
    out->z0 = w->iz0 * w->dx;
    double norm = 1.0 / (double)modes;
    for (int iz = 0; iz < out->nz; iz++)
        for (int ix = 0; ix < out->nx; ix++) {
            int gx = ((w->ix0 + ix) % w->fx + w->fx) % w->fx, gz = ((w->iz0 + iz) % w->fz + w->fz) % w->fz;
            out->heights[(size_t)iz * out->nx + ix] = (float)(buf[(size_t)gz * w->fx + gx][0] * norm);
        }
    ocean_result r = OCEAN_OK;
    if (bound && (r = bspline_prefilter(out)) == OCEAN_OK && (r = reading_error(pat, spec, buf, plan)) == OCEAN_OK)
        block_bounds(pat);
    ocean_fft_planner_lock();
    fftwf_destroy_plan(plan);
    ocean_fft_planner_unlock();
    fftwf_free(buf);
    fftwf_free(spec);
    if (r != OCEAN_OK) {
        wake_grid_free(out);
        if (msg) snprintf(msg, msglen, "out of memory for a wake pattern");
    }
    return r;
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
    wake_layout w;
    wake_layout_make(p, behind, &w);
    return wake_sum(p, &w, out, NULL, msg, msglen);
}

ocean_result wake_pattern_create(const wake_params *p, wake_pattern **out, char *msg, size_t msglen)
{
    *out = NULL;
    wake_pattern *w;
    ocean_result r = wake_pattern_alloc(p, &w, msg, msglen);
    if (r != OCEAN_OK) return r;
    r = wake_sum(p, &w->w, &w->g, w, msg, msglen);
    if (r != OCEAN_OK) {
        free(w->block_bound);
        free(w);
        return r;
    }
    *out = w;
    return OCEAN_OK;
}

void wake_grid_free(wake_grid *g)
{
    if (!g) return;
    free(g->heights);
    g->heights = NULL;
}
