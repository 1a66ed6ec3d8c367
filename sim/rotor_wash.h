/*
 * rotor_wash.h - the water under a rotorcraft's downwash: the dent its
 * slipstream presses into the sea and the ring waves every change of it
 * sends out, as a pure function of the rotorcraft's track.
 *
 * Forcing.  Momentum theory: a rotor of diameter D holding a rotorcraft in
 * hover drives a slipstream whose momentum flux is the thrust T, here
 * T = w pi D^2 / 4 at a disk loading w of ROTOR_DISK_LOADING (Leishman
 * 2006, Principles of Helicopter Aerodynamics, 2nd ed., ch. 2: helicopters
 * 5-10 lb/ft^2); the slipstream contracts to D / (2 sqrt 2) and, as a round
 * jet impinging on the water, presses on it with the pressure of a
 * turbulent impinging jet: Gaussian, p = p0 exp(-r^2 / c^2), spreading
 * with the height H as exp(-114 (r / H)^2) (Beltaos & Rajaratnam 1974,
 * "Impinging circular turbulent jets", J. Hydraulics Div. ASCE 100(10)),
 * i.e. c = H / sqrt(114) far up, c^2 = (D / (2 sqrt 2))^2 + H^2 / 114 here,
 * and integrating to the jet's momentum flux: p0 pi c^2 = T.  As a
 * pressure head A = T / (rho_w g pi c^2) (a 16 m rotor at 10 m: 7 cm).
 * The model's reach: full up to 3 D of height and at speeds up to the
 * hover's induced velocity v_h = sqrt(w / (2 rho_air)) (12 m/s), faded to
 * nothing at 4 D and at 2 v_h (a faster rotor's wake is swept behind it,
 * which the model does not follow).
 *
 * Response (linear, deep water, Lamb 1932, Hydrodynamics, art. 255, the
 * Cauchy-Poisson problem in two dimensions): a head A held on still water
 * from time t0 on raises, at distance r,
 *
 *   eta = -A [f(rho) - C(rho, s)],  rho = r / c,  s = (t - t0) sqrt(g / c),
 *   f(rho) = exp(-rho^2),
 *   C(rho, s) = int_0^inf (1/2) exp(-k^2 / 4) cos(sqrt(k) s) J0(k rho) k dk:
 *
 * the hydrostatic dent f (the displaced water weighs T) and the rings
 * that leave it, whose crests at r after a time tau follow the local
 * wavenumber g tau^2 / (4 r^2).  The pressure is sampled on the lattice of
 * sim times k * ROTOR_STEP_S (so any instant is computed alike): the dent
 * of the newest lattice state, carried where the rotor is at t (a moving
 * rotor's dent moves with it, quasi-steady, as a ship's wake does), and
 * each change of the pressure between two lattice states in the last
 * ROTOR_HISTORY_S seconds (the oldest fading out over ROTOR_FADE_S) as the
 * step it is, its rings sent from where the rotor was then.  A change of
 * less than ROTOR_STEP_MIN_M of head in one lattice step (a slow climb, a
 * host's jitter) sends none: the dent follows it (by at most that much at
 * a lattice time).  A rotor hovering or cruising level costs one dent;
 * its coming, and a fast climb or descent, a ring each step.  C is read from a table computed once
 * (rotor_wash_create) near the footprint and early, and by its
 * stationary-phase form, sqrt(2) s^2 / (4 rho^3) Phi(k*) cos(s^2 / (4
 * rho)), k* = s^2 / (4 rho^2), beyond; rotor_wash_ring_exact sums the
 * integral itself (the check of the reading).
 *
 * Threads: a rotor_wash is immutable once made: any number of threads may
 * read it, each with its own table of entities (or under its lock).
 * OOM: rotor_wash_create and rotor_wash_add return OCEAN_ENOMEM.
 */
#ifndef OCEAN_ROTOR_WASH_H
#define OCEAN_ROTOR_WASH_H

#include <stddef.h>

#include "entity.h"
#include "ocean_result.h"
#include "wake_field.h"

#define ROTOR_DISK_LOADING 360.0   /* N/m^2, 7.5 lb/ft^2 */
#define ROTOR_RHO_AIR 1.225        /* kg/m^3, sea level */
#define ROTOR_RHO_WATER 1025.0     /* kg/m^3, sea water */
#define ROTOR_STEP_S 0.2           /* the forcing's lattice, s */
#define ROTOR_HISTORY_S 60.0       /* changes older than this send no more rings */
#define ROTOR_FADE_S 10.0          /* over which the oldest fade */
#define ROTOR_STEP_MIN_M 1e-3      /* m of head a lattice step must change by to send rings */
/* Bound on |rotor_wash_ring - rotor_wash_ring_exact| anywhere, for a head
 * of 1 m (measured by test_rotor_wash over the table and the
 * stationary-phase region, with a margin). */
#define ROTOR_RING_ERROR 1.2e-2

typedef struct rotor_wash rotor_wash;

ocean_result rotor_wash_create(rotor_wash **out);
void rotor_wash_destroy(rotor_wash *w); /* accepts NULL */

/* The footprint of a rotor of diameter D (m) at height H (m) moving at U
 * (m/s): its head A (m) and radius c (m).  A is 0 beyond the model's
 * reach. */
void rotor_wash_footprint(double diameter, double height, double speed, double *head, double *radius);

/* Adds the downwash of every rotorcraft of table e at sim time t to the n
 * points xz (height, slopes, rate of change, error bound into out, which
 * holds the other wakes already).  OCEAN_EINVAL (t or a point not
 * finite), OCEAN_ENOMEM. */
ocean_result rotor_wash_add(const rotor_wash *w, const ocean_entities *e, double t, const double *xz, size_t n,
                            wake_sample *out);

/* C(rho, s) as rotor_wash_add reads it, and its derivatives in rho and s
 * (either may be NULL). */
double rotor_wash_ring(const rotor_wash *w, double rho, double s, double *d_rho, double *d_s);
/* C(rho, s) summed by quadrature (slow: for checking). */
double rotor_wash_ring_exact(double rho, double s);

#endif
