/*
 * query.h - point queries: height, normal, velocity and foam at world
 * (x, z, t), the same for every client.
 *
 * A query reads the same evaluated fields clients receive (an ocean_frame,
 * at the cutoff the caller chose) plus the Gerstner near field seen without
 * camera fade, so the answer depends on no camera and no LOD.  The fields
 * are read by ocean_frame_sample_accurate (within about a millimetre of
 * the waves they hold), the near field summed exactly.  The surface is a
 * displaced parameter grid: the point whose displaced position is the
 * asked (x, z) is found by Newton's method on the total displacement, and
 * the error bound covers both the reading and what the inversion left.
 */
#ifndef OCEAN_QUERY_H
#define OCEAN_QUERY_H

#include <stddef.h>

#include "gerstner.h"
#include "ocean.h"

/* Farthest an answer's displaced point may lie from the asked (x, z), m,
 * and still carry a finite error bound (the bound is first order in it). */
#define OCEAN_QUERY_MISS_MAX 0.01

typedef struct ocean_query_result {
    double height;        /* surface height above the mean sea level, m */
    double normal[3];     /* unit normal (x, y, z), y up */
    double velocity[3];   /* velocity of the surface particle, m/s */
    double foam;          /* foam coverage 0..1 */
    double error;         /* bound on |height - the exact sum of the same waves|
                             at (x, z), m: the reading's and the inversion's
                             (INFINITY where the surface folds, J <= 0, a
                             derivative channel is missing, or the iteration
                             stopped more than OCEAN_QUERY_MISS_MAX from
                             (x, z): see residual) */
    double residual;      /* horizontal |x0 + D(x0) - x| left, m */
    int iterations;
    int folded;           /* 1: the surface folds here (J <= 0 at the answer
                             or on the iteration's way to it): several
                             undisplaced points map to (x, z); the result is
                             the one the iteration reached */
} ocean_query_result;

typedef struct ocean_query_options {
    int max_iterations;   /* default 24 */
    double tolerance;     /* stop when the residual is below this, m (1e-5) */
    int bilinear;         /* 1: read the fields bilinearly (ocean_frame_sample):
                             smoother than the waves, error then unknown
                             (INFINITY); default 0, the accurate reading */
} ocean_query_options;

void ocean_query_options_default(ocean_query_options *o);

/* Answers n queries at world points xz[2i], xz[2i+1] from frame f (which
 * must hold OCEAN_FX_HEIGHT; displacement, normals, foam and velocity are
 * used when present) and, if g is not NULL, the Gerstner near field at
 * time t viewed through v (NULL: ocean_gerstner_view_default, no fade).
 * Deterministic and independent of n and order.  OCEAN_EINVAL for
 * non-finite coordinates (out[i] is then zeroed and the others still
 * answered; the first bad index is reported through *bad if not NULL). */
ocean_result ocean_query_points(const ocean_frame *f, const ocean_gerstner *g,
                                const ocean_gerstner_view *v, double t,
                                const double *xz, size_t n, const ocean_query_options *opt,
                                ocean_query_result *out, size_t *bad);

/* Effects a frame must have for full query answers. */
#define OCEAN_QUERY_EFFECTS (OCEAN_FX_HEIGHT | OCEAN_FX_DISPLACEMENT | OCEAN_FX_NORMALS | \
                             OCEAN_FX_FOAM | OCEAN_FX_VELOCITY)

#endif
