/*
 * lod.c - "Where each mip is read" (see lod.h).
 */
#include "lod.h"

#include <math.h>

double proto_lod_spacing(double q_c, double min_spacing, double cam_y, double dx, double dz)
{
    double h = fmax(fabs(cam_y), 1.0);
    return fmax(min_spacing, q_c * sqrt(dx * dx + dz * dz + h * h));
}

void proto_lod_read_at(double s, double sigma, int mips, int fades, proto_lod_read *out)
{
    double lam = log2(s / sigma);
    out->lambda = lam;
    out->fade = 1;
    out->mip[1] = -1;
    out->weight[1] = 0;
    if (lam <= 0) {
        out->mip[0] = 0;
        out->weight[0] = 1;
    } else if (lam < mips - 1) {
        int m0 = (int)floor(lam);
        double f = lam - m0;
        out->mip[0] = m0;
        out->weight[0] = 1 - f;
        out->mip[1] = m0 + 1;
        out->weight[1] = f;
    } else {
        out->mip[0] = mips - 1;
        if (fades) {
            double w = mips - lam;
            out->fade = w < 0 ? 0 : w > 1 ? 1 : w;
        }
        out->weight[0] = out->fade;
    }
}
