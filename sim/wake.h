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
#include "wake_pattern.h"

/* Heights on a grid in the body's frame: heights[iz * nx + ix] at
 * x = x0 + ix * dx (behind the body positive), z = z0 + iz * dx. */
typedef struct wake_grid {
    double x0, z0, dx;
    int nx, nz;
    float *heights;
} wake_grid;

/* The steady wake of p on a grid from 2 transverse wavelengths ahead of
 * the body to WAKE_BEHIND behind, and both sides of the wedge: *out owns
 * its heights (wake_grid_free).  OCEAN_EINVAL (bad parameters),
 * OCEAN_ENOMEM. */
ocean_result wake_steady(const wake_params *p, wake_grid *out, char *msg, size_t msglen);
/* The same to `behind` transverse wavelengths behind, in [1, 100]. */
ocean_result wake_steady_to(const wake_params *p, double behind, wake_grid *out, char *msg, size_t msglen);
/* Frees g's heights.  Accepts NULL. */
void wake_grid_free(wake_grid *g);

/* Summed by one FFT of up to 4096^2 points (0.1-10 s): build it off any
 * thread that serves clients.  OCEAN_EINVAL (bad parameters),
 * OCEAN_ENOMEM, with msg.  Read it through wake_pattern.h. */
ocean_result wake_pattern_create(const wake_params *p, wake_pattern **out, char *msg, size_t msglen);

#endif
