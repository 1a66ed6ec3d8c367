/*
 * wake_field.h - the wakes of the ships in the sea at one instant, as the
 * point answers (queries, CIGI HAT/HOT) add them to the wind sea.
 *
 * The model is quasi-steady: at sim time t each ship (ocean_entity_state
 * at t) carries the steady wake of its speed, length, beam and the sea's
 * depth (wake.h), laid in its frame (heading) and scaled by its draught:
 * the hull as a surface pressure of head equal to its draught, the
 * pressure a floating body in hydrostatic balance puts on the water under
 * it (the linear response scales with the head).  Wakes add linearly to
 * the wind sea and to each other, so a ship in another's wake feels it.
 * A pure function of the ships' states at t: nothing accumulates.  Its
 * limit: a turning ship's wake turns with it, rigidly, instead of staying
 * on the water where each stretch of track laid it; a ship slower than
 * hull Froude number WAKE_FR_MIN makes none (its waves are exponentially
 * small: the footprint's spectrum at the wavenumber g / U^2), fading in
 * over the next 0.05.  Rotorcraft press the water otherwise
 * (rotor_wash.h); aircraft make none.
 *
 * Speed varies continuously along a track, and a pattern costs an FFT, so
 * patterns are kept on a ladder of speeds 2^(j/16) m/s, 4.4 % apart: a
 * ship between two rungs reads both, each with its coordinates scaled by
 * the ratio of the rung's transverse wavelength to the ship's (so the
 * waves line up), blended linearly in log speed.  The heights are
 * continuous in speed, and a ship at steady speed needs two patterns.
 *
 * The field holds patterns and builds none: whoever owns the time builds
 * the ones wake_field_missing names (wake_pattern_create) and inserts
 * them; until then wake_field_sample refuses (OCEAN_ESTATE) rather than
 * answer without a wake.
 *
 * Threads: one thread at a time (the owner's lock).
 * OOM: wake_field_create returns OCEAN_ENOMEM; nothing else allocates.
 */
#ifndef OCEAN_WAKE_FIELD_H
#define OCEAN_WAKE_FIELD_H

#include <stddef.h>

#include "entity.h"
#include "ocean_result.h"
#include "query.h"
#include "wake.h"

#define WAKE_FR_MIN 0.1        /* hull Froude number U / sqrt(g L) below which a ship makes no wake */
#define WAKE_RUNGS_PER_OCTAVE 16

/* The wakes at one point: height, its slopes, its rate of change, and the
 * bound on |height - the exact sum of the same waves|, m. */
typedef struct wake_sample {
    double height, dhdx, dhdz, dhdt, error;
} wake_sample;

typedef struct wake_field wake_field;

/* A field that keeps at most max_patterns (>= 2) patterns, the least
 * recently read going first. */
ocean_result wake_field_create(int max_patterns, wake_field **out);
void wake_field_destroy(wake_field *f); /* accepts NULL */

/* The patterns that the n ships (d[i], s[i]) over water of the given
 * depth (m; INFINITY: deep) need to answer the np points xz but the field
 * does not hold: their parameters into need (at most max, each once).
 * Returns how many are missing (may exceed max). */
int wake_field_missing(const wake_field *f, const ocean_entity_desc *d, const ocean_entity_state *s, int n,
                       double depth, const double *xz, size_t np, wake_params *need, int max);

/* Takes p into the field (a pattern with the same parameters already held
 * is kept and p destroyed). */
void wake_field_insert(wake_field *f, wake_pattern *p);
int wake_field_count(const wake_field *f);
/* A full field then makes room by dropping the pattern that came first,
 * not the least recently read: a reader whose sender models what it
 * holds (PROTOCOL.md "WAKE"). */
void wake_field_keep_order(wake_field *f);

/* The patterns (each once, at most max into out) of the n ships whose
 * wakes reach within radius of (x, z): what a viewer there draws.
 * Returns how many (may exceed max). */
int wake_field_rungs(const ocean_entity_desc *d, const ocean_entity_state *s, int n, double depth, double x,
                     double z, double radius, wake_params *out, int max);

/* The wakes of the n ships at the np points into out.  OCEAN_ESTATE when
 * a pattern they need is missing (out untouched); OCEAN_EINVAL for a point
 * not finite. */
ocean_result wake_field_sample(wake_field *f, const ocean_entity_desc *d, const ocean_entity_state *s, int n,
                               double depth, const double *xz, size_t np, wake_sample *out);

/* The same heights with every pattern's waves summed exactly
 * (wake_pattern_exact): the check of wake_field_sample.  OCEAN_ESTATE,
 * OCEAN_ENOMEM. */
ocean_result wake_field_exact(const wake_field *f, const ocean_entity_desc *d, const ocean_entity_state *s, int n,
                              double depth, const double *xz, size_t np, double *heights);

/* Adds n wake samples to query answers: height, normal (the slopes add),
 * vertical velocity, error bound. */
void wake_sample_apply(const wake_sample *w, size_t n, ocean_query_result *q);

#endif
