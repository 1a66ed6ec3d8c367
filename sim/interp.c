/*
 * interp.c - the share of a wave's power each kernel keeps (interp.h).
 */
#include "interp.h"

/* c[d] = int_0^1 sum_j w_j(u) w_(j-d)(u) du by Gauss-Legendre on 16
 * panels of 4 points: exact for the polynomial kernels (degree 6 in u),
 * and for Lanczos' smooth weights within 1e-12. */
static void kernel_gram(ocean_interp kernel, double c[OCEAN_INTERP_MAX_TAPS])
{
    static const double gx[4] = {0.0694318442029737, 0.3300094782075719, 0.6699905217924281, 0.9305681557970263};
    static const double gw[4] = {0.1739274225687269, 0.3260725774312731, 0.3260725774312731, 0.1739274225687269};
    enum { PANELS = 16 };
    for (int d = 0; d < OCEAN_INTERP_MAX_TAPS; d++)
        c[d] = 0.0;
    for (int p = 0; p < PANELS; p++)
        for (int q = 0; q < 4; q++) {
            double w[OCEAN_INTERP_MAX_TAPS];
            int taps = 2 * ocean_interp_weights(kernel, (p + gx[q]) / PANELS, w);
            for (int j = 0; j < taps; j++)
                for (int l = 0; l <= j; l++)
                    c[j - l] += gw[q] / PANELS * w[j] * w[l];
        }
}

void ocean_interp_powers(ocean_interp kernel, double dth, int count, double *out)
{
    double c[OCEAN_INTERP_MAX_TAPS];
    kernel_gram(kernel, c);
    for (int m = 0; m < count; m++) {
        double p = c[0];
        for (int d = 1; d < OCEAN_INTERP_MAX_TAPS; d++)
            p += 2.0 * c[d] * cos(d * m * dth);
        out[m] = p;
    }
}
