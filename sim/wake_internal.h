/*
 * wake_internal.h - what the two halves of a wake share: the series'
 * layout and spectrum, the pattern's fields and its spline reading
 * (wake_pattern.c, no FFT), and the summing that builds them (wake.c,
 * FFTW).  Not part of the library's interface.
 */
#ifndef OCEAN_WAKE_INTERNAL_H
#define OCEAN_WAKE_INTERNAL_H

#include <math.h>

#include "wake.h"

#define WAKE_G 9.81
#define WAKE_PER_WAVE 12       /* grid points per transverse wavelength at most */
#define WAKE_FADE_WAVES 20.0   /* e-folding of the waves' amplitude, in wavelengths */
#define WAKE_FFT_MAX 4096      /* FFT points per side at most */
#define WAKE_LENGTH_PER_BEAM 6.0
#define WAKE_BLOCK 8           /* cells a side of a block of the measured bound */

/* Where a wake's series is summed and sampled: the FFT's periodic domain
 * and the grid cut out of it. */
/* Where a wake's series is summed and sampled: the FFT's periodic domain
 * and the grid cut out of it. */
typedef struct wake_layout {
    double lambda, eps, dx, beam;
    int fx, fz;          /* FFT points along and across the track */
    int ix0, iz0;        /* the grid's first point, in FFT samples from the body */
    int nx, nz;          /* the grid */
} wake_layout;

struct wake_pattern {
    wake_params p;
    wake_layout w;
    wake_grid g;           /* the spline's coefficients */
    double bound;          /* |bicubic reading - series| anywhere */
    float *block_bound;    /* the same per block of WAKE_BLOCK^2 cells */
    int bx, bz;            /* blocks along, across */
    double xend, zmax;     /* the grid's far end behind, its half-width */
    double reach;          /* wake_params_reach, kept: readers ask it per point */
};

/* The wavenumber of FFT index i of n at spacing dx. */
static inline double wake_wavenumber(int i, int n, double dx) { return 2 * M_PI * (i < n / 2 ? i : i - n) / (n * dx); }

/* p's layout for a grid reaching `behind` transverse wavelengths. */
void wake_layout_make(const wake_params *p, double behind, wake_layout *w);
/* The elevation spectrum of p on the layout's FFT grid (FFT order) into
 * buf (fx * fz complex values, re and im). */
void wake_spectrum(const wake_params *p, const wake_layout *w, float (*buf)[2]);
/* A pattern of p (validated) with its layout and its blocks' bounds (all
 * 0), no grid yet.  OCEAN_EINVAL, OCEAN_ENOMEM, with msg. */
ocean_result wake_pattern_alloc(const wake_params *p, wake_pattern **out, char *msg, size_t msglen);
/* Cubic B-spline weights at u in [0, 1), and of the derivative. */
void wake_bspline_weights(double u, double w[4]);
/* The 4 x 4 values of g around cell (ix, iz), 1 <= ix <= nx - 3 (likewise
 * iz), under the weights given. */
double wake_grid_cubic(const wake_grid *g, int ix, int iz, const double ax[4], const double az[4]);
/* The window a pattern is read through, and its gradient. */
double wake_window(const wake_pattern *w, double x, double z, double *wx, double *wz);

#endif
