/*
 * ocean_internal.h - hooks of ocean.c for oceand's own tests; not
 * installed, not part of the library's API.
 */
#ifndef OCEAN_INTERNAL_H
#define OCEAN_INTERNAL_H

#include "ocean.h"

/* Chooses the spectrum stage's code paths, which must all give the same
 * bits (tests/test_ocean.c compares them):
 *   fused  1: the AVX2+FMA row pass (only where the CPU has both; else
 *             the plain pass), 0: the plain pass, -1: the CPU's best;
 *   stream 1: write every spectrum with streaming stores (AVX2+FMA pass
 *             only), 0: never, -1: spectra larger than twice the
 *             last-level cache (the default).
 * ocean_create applies (-1, -1).  Not thread-safe against a running
 * ocean_evaluate on the same ocean.  Accepts NULL (does nothing). */
void ocean_force_paths(ocean *o, int fused, int stream);

/* Transforms the channels of an evaluation group channels per FFTW call
 * (1 up to the 11 channels an evaluation can hold; 0 or out of range: the
 * default rule, at most 8.5 MB of spectra a call).  Each group size is its own FFTW plan, so results may differ from
 * the default's in the last bits.  Accepts NULL. */
void ocean_force_group(ocean *o, int group);

#endif
