/*
 * interp.h - the kernels that read a sampled field between its nodes, and
 * the share of a wave's power each keeps.
 *
 * A field sampled on a grid and read between nodes by a kernel keeps, of
 * a wave whose phase advances th between nodes along an axis, on average
 * over the point read, a share of its power: 1 at th = 0, less towards
 * the grid's Nyquist th = pi (and a little more than 1 in between for
 * Lanczos' overshoot).  A reader that turns a field's variance into
 * something - the whitecap ramp (foam.h) turns the breaking index's std
 * into a coverage - needs the variance its own kernel holds, not the
 * field's.
 *
 * Threads: pure functions.
 */
#ifndef OCEAN_INTERP_H
#define OCEAN_INTERP_H

#include <math.h>

typedef enum ocean_interp {
    OCEAN_INTERP_BILINEAR = 0, /* 2 taps a side: GL_LINEAR */
    OCEAN_INTERP_LAGRANGE = 1, /* 4: cubic Lagrange on nodes -1..2 */
    OCEAN_INTERP_KEYS = 2,     /* 4: Keys (1981) cubic convolution, a = -1/2 (Catmull-Rom) */
    OCEAN_INTERP_LANCZOS3 = 3, /* 6: Lanczos windowed sinc, a = 3, normalised to sum 1
                                  (Duchon 1979, J. Appl. Meteor. 18(8) 1016) */
    OCEAN_INTERP_KERNELS
} ocean_interp;

/* The most taps of any kernel. */
#define OCEAN_INTERP_MAX_TAPS 6

/* Weights of `kernel` at t in [0, 1) between nodes 0 and 1, for the
 * nodes 1 - R .. R in w[0 .. 2R - 1]; returns R.  Inline: the readers'
 * inner loops call it with a constant kernel. */
static inline int ocean_interp_weights(ocean_interp kernel, double t, double w[OCEAN_INTERP_MAX_TAPS])
{
    double t2 = t * t, t3 = t2 * t;
    switch (kernel) {
    case OCEAN_INTERP_LAGRANGE:
        w[0] = -t * (t - 1.0) * (t - 2.0) / 6.0;
        w[1] = (t + 1.0) * (t - 1.0) * (t - 2.0) / 2.0;
        w[2] = -(t + 1.0) * t * (t - 2.0) / 2.0;
        w[3] = (t + 1.0) * t * (t - 1.0) / 6.0;
        return 2;
    case OCEAN_INTERP_KEYS:
        w[0] = 0.5 * (-t3 + 2.0 * t2 - t);
        w[1] = 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0);
        w[2] = 0.5 * (-3.0 * t3 + 4.0 * t2 + t);
        w[3] = 0.5 * (t3 - t2);
        return 2;
    case OCEAN_INTERP_LANCZOS3: {
        double sum = 0.0;
        for (int k = 0; k < 6; k++) {
            double x = t - (k - 2);
            if (fabs(x) < 1e-12) {
                w[k] = 1.0;
            } else {
                double px = M_PI * x;
                w[k] = 3.0 * sin(px) * sin(px / 3.0) / (px * px);
            }
            sum += w[k];
        }
        for (int k = 0; k < 6; k++)
            w[k] /= sum;
        return 3;
    }
    default:
        w[0] = 1.0 - t;
        w[1] = t;
        return 1;
    }
}

/* out[m], m = 0 .. count - 1: the mean share of a wave's power that
 * `kernel` keeps along one axis, for a wave whose phase advances m * dth
 * between nodes, read at a uniformly random point between two nodes:
 * E_u |sum_j w_j(u) e^{i j th}|^2 = c_0 + 2 sum_d c_d cos(d th), c_d the
 * integrals over u of sum_j w_j w_(j-d) (bilinear: (2 + cos th) / 3).  A
 * wave (kx, kz) keeps out[|mx|] out[|mz|] of its power: the kernels are
 * separable. */
void ocean_interp_powers(ocean_interp kernel, double dth, int count, double *out);

#endif
