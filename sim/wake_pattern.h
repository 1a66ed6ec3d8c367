/*
 * wake_pattern.h - the steady wake of one body kept for reading at any
 * point: its parameters (what names a wake), the cubic spline through its
 * grid and the window it is read through.  A pattern is summed by FFT
 * where it is built (wake.h: wake_pattern_create) and read here, by the
 * daemon and by any reader that received its grid (wake_pattern_from_grid,
 * no FFT: a client of the daemon reads the same pattern with the same code).
 *
 * Frame: the body at the origin, moving toward -x; x grows behind it, z
 * across.  Heights are for a pressure head of 1 m (wake.h).
 *
 * Threads: a pattern is immutable once made: any number of threads may
 * read one.
 */
#ifndef OCEAN_WAKE_PATTERN_H
#define OCEAN_WAKE_PATTERN_H

#include <stddef.h>

#include "ocean_result.h"

#define WAKE_SPEED_MAX 60.0     /* m/s: a fast boat is 25; beyond, not a displacement hull */
#define WAKE_LENGTH_MIN 0.5     /* m */
#define WAKE_LENGTH_MAX 500.0   /* m: the largest ships */
#define WAKE_BEAM_MIN 0.1       /* m */

typedef struct wake_params {
    double speed;    /* U, m/s, in (0, WAKE_SPEED_MAX] */
    double length;   /* L, m, the pressure footprint's length */
    double depth;    /* h, m, > 0; INFINITY: deep water */
    double beam;     /* B, m, the footprint's width, [WAKE_BEAM_MIN, length]; 0: a sixth of the length */
} wake_params;

/* 1 when a and b name the same wake (every field equal). */
int wake_params_equal(const wake_params *a, const wake_params *b);

/* OCEAN_EINVAL with the reason for a speed, length or depth out of range
 * or not a number. */
ocean_result wake_params_validate(const wake_params *p, char *msg, size_t msglen);

/* The wavelength of the transverse waves on the track: the wave whose phase
 * speed is the body's, (g / k) tanh(k h) = U^2; 0 when the depth Froude
 * number is 1 or more (finite depth has no wave that fast). */
double wake_transverse_wavelength(const wake_params *p);

#define WAKE_BEHIND 22.0        /* transverse wavelengths behind the body a pattern reaches */

/* The steady wake of one body, summed once and read many times: heights
 * and slopes at any point of its frame, read by the cubic spline through
 * the grid of the series (wake.h), through a window that is 0 under the
 * hull (the water there is the hull's own) and fades to 0 toward the
 * grid's edges; 0 beyond them.  Immutable once made: any number of
 * threads may read one.  The exact series it is read from
 * (wake_pattern_exact) is the check of every reading: they differ by at
 * most wake_pattern_bound. */
typedef struct wake_pattern wake_pattern;

/* Built by wake_pattern_create (wake.h), or wake_pattern_from_coefficients. */
void wake_pattern_destroy(wake_pattern *w); /* accepts NULL */

const wake_params *wake_pattern_params(const wake_pattern *w);
/* The transverse wavelength the pattern is laid out on, m. */
double wake_pattern_wavelength(const wake_pattern *w);
/* The distance from the body beyond which the pattern is 0, m. */
double wake_pattern_reach(const wake_pattern *w);
/* The reach of p's pattern before it is built (p valid). */
double wake_params_reach(const wake_params *p);
/* Bound on |wake_pattern_read - wake_pattern_exact| anywhere, m (for a
 * pressure head of 1 m).  Measured when the pattern is made: the series
 * is summed again half-way between the grid's samples (the cells' and
 * their edges' middles, where a cubic reading strays most), the largest
 * error of each block of cells and its neighbours kept, half again for
 * the points between. */
double wake_pattern_bound(const wake_pattern *w);

/* The bound where the reading at (x, z) lies: the error measured in the
 * block of 8 x 8 cells around it (0 where the window is 0). */
double wake_pattern_bound_at(const wake_pattern *w, double x, double z);

/* The height at (x, z) of the body's frame, and its slopes through
 * dhdx, dhdz. */
double wake_pattern_read(const wake_pattern *w, double x, double z, double *dhdx, double *dhdz);

/* The exact heights at n points xz[2i], xz[2i+1] of the body's frame: the
 * same waves summed one by one in double through the same window (the
 * whole spectrum per point: for checking, not serving).  OCEAN_ENOMEM. */
ocean_result wake_pattern_exact(const wake_pattern *w, const double *xz, size_t n, double *out);

/* The spline's coefficient grid of w (nx * nz floats, rows along x), and
 * its size through *nx, *nz: what a pattern's reader needs besides its
 * parameters. */
const float *wake_pattern_coefficients(const wake_pattern *w, int *nx, int *nz);

/* The pattern of p read from coefficients received (nx * nz, as
 * wake_pattern_coefficients gives them), its error bound `bound`
 * everywhere (a reader's own share beyond the builder's: the codec's).
 * OCEAN_EINVAL (bad parameters, a size other than p's layout, a value not
 * finite, a bound not finite or negative), OCEAN_ENOMEM, with msg. */
ocean_result wake_pattern_from_coefficients(const wake_params *p, const float *coef, int nx, int nz, double bound,
                                            wake_pattern **out, char *msg, size_t msglen);

#endif
