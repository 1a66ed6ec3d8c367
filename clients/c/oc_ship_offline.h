/*
 * oc_ship_offline.h - the ship example's hull (oc_ship.h) floated on a
 * local sim/ ocean instead of a daemon's answers: no network, the same
 * hull model.  Not part of liboceanclient (which holds no simulator): it
 * is in liboceansim, beside the ocean it evaluates (pkg-config oceansim).
 *
 * Threads: a run uses the ocean it is given for its whole length; the
 * caller must not evaluate that ocean from another thread meanwhile.
 */
#ifndef OC_SHIP_OFFLINE_H
#define OC_SHIP_OFFLINE_H

#include "oc_ship.h"
#include "ocean.h"
#include "ocean_result.h"

/* Floats the ship on ocean o for `seconds` of sim time from t0, stepping
 * dt: each step evaluates o at t (height and displacement) into a frame
 * and answers the hull points with ocean_query_points.  Records every step
 * into *out (free with oc_ship_trace_free); on OCEAN_EDIVERGED the trace up
 * to the divergence is kept for inspection.  OCEAN_EINVAL: p, o or out
 * NULL, seconds outside (0, 1e6], dt outside (0, 0.5]. */
ocean_result oc_ship_run_offline(const oc_ship_params *p, ocean *o, double t0, double seconds, double dt,
                                 oc_ship_trace *out, char *msg, size_t msglen);

#endif
