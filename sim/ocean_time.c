/*
 * ocean_time.c - the time limit's check and the exact phase (see
 * ocean_time.h for why the limit is 2^27 s and how the phase stays exact).
 */
#include "ocean_time.h"

#include <math.h>

ocean_result ocean_time_check(double t, const char *field, char *msg, size_t msglen)
{
    if (ocean_time_ok(t))
        return OCEAN_OK;
    ocean_seterr(msg, msglen,
                 "%s = %.17g s is beyond the time limit +-%.0f s (OCEAN_TIME_MAX = 2^27 s, "
                 "where double precision keeps wave phases within 1e-6 rad)",
                 field ? field : "t", t, OCEAN_TIME_MAX);
    return OCEAN_EINVAL;
}

double ocean_phase(double w, double t)
{
    /* The bounds keep Veltkamp's 2^27 + 1 multiple finite. */
    if (!(fabs(w) < 1e300) || !(fabs(t) < 1e300))
        return NAN;
    double fh, fl, th, tl;
    ocean_turns_of(w, &fh, &fl);
    /* Beyond 2^51 turns the rounding trick and Dekker's split stop being exact. */
    if (!(fabs(fh * t) < 2251799813685248.0))
        return NAN;
    ocean_split(t, &th, &tl);
    return ocean_phase_turns(fh, fl, t, th, tl);
}
