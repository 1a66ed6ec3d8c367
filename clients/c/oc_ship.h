/*
 * oc_ship.h - a floating box hull for the ship example: heave, pitch and
 * roll driven by the sea surface height under 64 hull points.
 *
 * Model (hydrostatic, strip columns): the hull is a box L x B x D floating
 * at draft T, its mass rho L B T, its centre of gravity at the centre of
 * buoyancy at rest (so the metacentric height is the waterplane's BM).  The
 * footprint is cut into nx x nz cells; under each cell's centre the sea's
 * height eta_i gives an immersion d_i = clamp(eta_i - y_bottom_i, 0, D) and
 * an upward force rho g A d_i (A = L B / (nx nz)).  Their sum and moments
 * about the centre of gravity drive
 *     m y''           = sum F_i - m g           - c_h y'
 *     I_p theta''     = sum F_i x_i cos(theta)  - c_p theta'
 *     I_r phi''       = sum F_i z_i cos(phi)    - c_r phi'
 * with box inertias I_p = m (L^2 + D^2) / 12, I_r = m (B^2 + D^2) / 12 and
 * linear damping at the given fractions of critical (standing in for wave
 * radiation damping, which hydrostatics lacks).  Pitch is bow (+x) up,
 * roll is starboard (+z) up.  Integrated with semi-implicit Euler.
 *
 * The caller supplies the heights: oc_ship_points gives the world (x, z) of
 * the hull points for the current state, the caller asks a daemon
 * (oc_client_query) or the simulation (ocean_query_points) for the heights
 * there, then oc_ship_step advances.  oc_ship_run_offline
 * (oc_ship_offline.h, in liboceansim) does the loop on a local sim/ ocean.
 */
#ifndef OC_SHIP_H
#define OC_SHIP_H

#include <stddef.h>

#include "ocean_result.h"

#define OC_SHIP_MAX_POINTS 4096

typedef struct oc_ship_params {
    double length_m, beam_m, draft_m, depth_m;  /* 20, 8, 1.5, 4 */
    double rho;                                 /* 1025 kg/m^3 */
    double g;                                   /* 9.81 m/s^2 */
    double zeta_heave, zeta_pitch, zeta_roll;   /* 0.3, 0.3, 0.2 of critical */
    int nx, nz;                                 /* hull point grid, 8 x 8 */
    double x0, z0;                              /* start position, m */
    double heading_deg;                         /* from +x toward +z */
    double speed;                               /* forward speed, m/s */
} oc_ship_params;

void oc_ship_params_default(oc_ship_params *p);
/* Finite positive sizes, draft < depth, grid 1..64 per side and nx*nz <=
 * OC_SHIP_MAX_POINTS, damping 0..2, |speed| <= 100.  Message names the
 * field. */
ocean_result oc_ship_params_validate(const oc_ship_params *p, char *msg, size_t msglen);

typedef struct oc_ship_state {
    double t;                  /* sim time, s */
    double x, z;               /* horizontal position of the centre, m */
    double heave, heave_rate;  /* m above the rest position, m/s */
    double pitch, pitch_rate;  /* rad, rad/s */
    double roll, roll_rate;    /* rad, rad/s */
    double immersed;           /* fraction of the rest displacement immersed */
} oc_ship_state;

typedef struct oc_ship oc_ship;

ocean_result oc_ship_create(const oc_ship_params *p, double t0, oc_ship **out, char *msg, size_t msglen);
void oc_ship_destroy(oc_ship *s);   /* accepts NULL */

/* Number of hull points (nx * nz). */
size_t oc_ship_point_count(const oc_ship *s);
/* World (x, z) of every hull point for the current state into xz[2n]. */
void oc_ship_points(const oc_ship *s, double *xz);
/* Advances by dt (0 < dt <= 0.5 s) given the sea height under each point
 * (same order as oc_ship_points).  OCEAN_EINVAL for a non-finite height or
 * a bad dt; OCEAN_EDIVERGED if the state becomes non-finite or absurd
 * (|heave| > 100 m, |pitch| or |roll| > 90 deg); the state is then left as
 * it was before the step. */
ocean_result oc_ship_step(oc_ship *s, const double *heights, double dt);
void oc_ship_get_state(const oc_ship *s, oc_ship_state *out);

/* Periodogram of x[0..n) (mean removed, Hann window) into power[0..n/2]
 * (bin k is frequency k / (n dt); power[0] = 0).  OCEAN_EINVAL for n < 8. */
ocean_result oc_ship_power_spectrum(const double *x, size_t n, double *power);
/* Period (s) of the largest peak of power[0..n/2] (a spectrum of n samples
 * every dt, e.g. an average of several oc_ship_power_spectrum), smoothed
 * over 3 bins, searched between min_period and max_period; 0 if none. */
double oc_ship_spectrum_peak(const double *power, size_t n, double dt, double min_period, double max_period);
/* Both in one: the heave (or any) record's dominant period; 0 if n < 8. */
double oc_ship_peak_period(const double *x, size_t n, double dt, double min_period, double max_period);

/* A recorded motion: n samples every dt. */
typedef struct oc_ship_trace {
    size_t n;
    double dt;
    double *t, *heave, *pitch, *roll;
    double *eta;    /* mean sea height under the hull points, m */
} oc_ship_trace;
void oc_ship_trace_free(oc_ship_trace *tr);   /* accepts NULL; zeroes it */

#endif
