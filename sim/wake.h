/*
 * wake.h - the steady wake of a body moving at constant velocity over still
 * water of uniform depth: the linear free-surface response to a pressure
 * distribution of the body's size travelling with it (Havelock 1908, Proc.
 * R. Soc. A 81, 398-430; Darmon, Benzaquen & Raphael 2014, J. Fluid Mech.
 * 738, R3).  Its far field is the Kelvin wedge: half-angle arcsin(1/3) =
 * 19.47 deg in deep water whatever the speed, transverse waves of the
 * body's phase speed on the track (wavelength 2 pi U^2 / g), widening as
 * the depth Froude number U / sqrt(g h) nears 1.
 *
 * The pattern is a pure function of (speed, length, depth): computed once
 * by one 2-D FFT in the body's frame, it is what the daemon superposes
 * along entities' tracks (docs/design.md, "Entities").
 *
 * Frame: the body at the origin, moving toward -x; x grows behind it, z
 * across.  Heights are for a pressure head of 1 m (a footprint of peak
 * p0 = rho g * 1 m over an ellipse of the body's length and a sixth of it
 * across, or of the beam given): the response is linear in the head.
 *
 * Threads: any; FFTW plans are made under the library's planner lock.
 */
#ifndef OCEAN_WAKE_H
#define OCEAN_WAKE_H

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

/* Heights on a grid in the body's frame: heights[iz * nx + ix] at
 * x = x0 + ix * dx (behind the body positive), z = z0 + iz * dx. */
typedef struct wake_grid {
    double x0, z0, dx;
    int nx, nz;
    float *heights;
} wake_grid;

/* 1 when a and b name the same wake (every field equal). */
int wake_params_equal(const wake_params *a, const wake_params *b);

/* OCEAN_EINVAL with the reason for a speed, length or depth out of range
 * or not a number. */
ocean_result wake_params_validate(const wake_params *p, char *msg, size_t msglen);

/* The wavelength of the transverse waves on the track: the wave whose phase
 * speed is the body's, (g / k) tanh(k h) = U^2; 0 when the depth Froude
 * number is 1 or more (finite depth has no wave that fast). */
double wake_transverse_wavelength(const wake_params *p);

#define WAKE_BEHIND 22.0        /* transverse wavelengths behind the body wake_steady reaches */

/* The steady wake of p on a grid from 2 transverse wavelengths ahead of
 * the body to WAKE_BEHIND behind, and both sides of the wedge: *out owns
 * its heights (wake_grid_free).  OCEAN_EINVAL (bad parameters),
 * OCEAN_ENOMEM. */
ocean_result wake_steady(const wake_params *p, wake_grid *out, char *msg, size_t msglen);
/* The same to `behind` transverse wavelengths behind, in [1, 100]. */
ocean_result wake_steady_to(const wake_params *p, double behind, wake_grid *out, char *msg, size_t msglen);
/* Frees g's heights.  Accepts NULL. */
void wake_grid_free(wake_grid *g);

/* ---- a wake kept for reading at any point ------------------------------- */

/* The steady wake of one body, summed once and read many times: heights
 * and slopes at any point of its frame, read by the cubic spline through
 * the grid wake_steady returns, through a window that is 0 under the
 * hull (the water there is the hull's own) and fades to 0 toward the
 * grid's edges; 0 beyond them.  Immutable once made: any number of
 * threads may read one.  The exact series it is read from
 * (wake_pattern_exact) is the check of every reading: they differ by at
 * most wake_pattern_bound. */
typedef struct wake_pattern wake_pattern;

/* OCEAN_EINVAL (bad parameters), OCEAN_ENOMEM, with msg.  Costs one FFT
 * of up to WAKE_FFT_MAX^2 points (0.1-10 s): build it off any thread that
 * serves clients. */
ocean_result wake_pattern_create(const wake_params *p, wake_pattern **out, char *msg, size_t msglen);
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

#endif
