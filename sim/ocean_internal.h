/*
 * ocean_internal.h - hooks of ocean.c for oceand's own tests; not
 * installed, not part of the library's API.
 */
#ifndef OCEAN_INTERNAL_H
#define OCEAN_INTERNAL_H

#include "ocean.h"

/* Chooses the spectrum stage's code paths, which must all give the same
 * bits (tests/test_ocean.c compares them):
 *   fused  2: the AVX-512 row pass (AVX-512 F/VL/DQ/BW, AVX2 and FMA),
 *             1: the AVX2+FMA row pass, 0: the plain pass, -1: the
 *             CPU's best; a pass the CPU lacks falls back to the best
 *             below it;
 *   stream 1: write every spectrum with streaming stores (AVX2+FMA and
 *             AVX-512 passes only), 0: never, -1: spectra larger than
 *             twice the last-level cache (the default).
 * ocean_create applies (-1, -1).  Not thread-safe against a running
 * ocean_evaluate on the same ocean.  Returns the row pass now in force
 * (0, 1 or 2); NULL: does nothing, returns -1. */
int ocean_force_paths(ocean *o, int fused, int stream);

/* table 1: the spectrum stage reads every mode's frequency from its table,
 * deep water's too; 0 (ocean_create's): it computes deep water's
 * (k d >= 22) as sqrt(g k) / 2 pi from the mode's integer wave vector.
 * Both give the same bits (the table holds the computed value); the
 * switch is for the tests and benchmarks that compare them.  Same thread
 * rules as ocean_force_paths; NULL: does nothing. */
void ocean_force_frequency_table(ocean *o, int table);

/* Transforms the channels of an evaluation group channels per FFTW call
 * (1 up to the 11 channels an evaluation can hold; 0 or out of range: the
 * default rule, at most 8.5 MB of spectra a call).  Each group size is its own FFTW plan, so results may differ from
 * the default's in the last bits.  Accepts NULL. */
void ocean_force_group(ocean *o, int group);

/* How the spectrum stage splits an FFTW call's pass over the threads:
 * mode 0 by rows, 1 by channel (each thread the channels FFTW's threaded
 * plan transforms on it), -1 (ocean_create's) whichever the ocean has
 * measured faster, with a probe of the other every 16th evaluation.  A
 * call with fewer channels than threads always splits by rows.  Every
 * mode gives the same bits; the switch is for the tests and benchmarks
 * that compare them.  Same thread rules as ocean_force_paths; NULL: does
 * nothing. */
void ocean_force_stage_split(ocean *o, int mode);

/* prune 0: every transform runs FFTW's whole-grid 2-D plan; 1
 * (ocean_create's): a cascade whose waves stop at a quarter of the grid
 * runs the pruned column pass (ocean_counters.fft_calls_pruned).  Both
 * are the same transform; the bits may differ in the last place (other
 * FFTW plans).  For the tests and benchmarks that compare them; also
 * applies to ocean_transform_only.  Same thread rules as
 * ocean_force_paths; NULL: does nothing. */
void ocean_force_pruning(ocean *o, int prune);

/* ocean_transform_only with each FFTW call's spectra first written
 * (zeros, split over the threads as the spectrum stage splits them): the
 * least any stage that writes the spectra FFTW reads can cost, the floor
 * bench_core puts beside the full evaluation.  f's contents are garbage
 * afterwards. */
ocean_result ocean_transform_floor(ocean *o, const ocean_request *r, ocean_frame *f);

#endif
