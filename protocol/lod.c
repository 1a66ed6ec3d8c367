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

/* mss += k * e's moments */
static void mss_add_scaled(double mss[3], double k, const proto_mip_entry *e)
{
    mss[0] += k * e->mss_x;
    mss[1] += k * e->mss_z;
    mss[2] += k * e->mss_xz;
}

/* Whether r reads a mip of the cascade at its k-th place, with a weight. */
static int mip_read(const proto_lod_read *r, int k, int mips)
{
    return r->mip[k] >= 0 && r->mip[k] < mips && r->weight[k] > 0;
}

void proto_lod_mss_add(const proto_lod_read *r, const proto_mip_entry *tab, int mips, double mss[3])
{
    for (int k = 0; k < 2; k++)
        if (mip_read(r, k, mips))
            mss_add_scaled(mss, r->weight[k], &tab[r->mip[k]]);
    if (r->fade < 1)
        mss_add_scaled(mss, 1 - r->fade, &tab[mips]);
    /* PROTOCOL.md: the linear blend of two band-limited fields holds
     * (a g0 + (1 - a) g1)^2 of a wave's variance, not a g0^2 + (1 - a) g1^2;
     * the difference is a (1 - a) (coarser - finer) of the moments (24.6 %
     * of the near field's slope variance at its mid-fade, without it) */
    const proto_mip_entry *fine, *coarse;
    double a;
    if (mip_read(r, 0, mips) && mip_read(r, 1, mips)) {
        fine = &tab[r->mip[0]];
        coarse = &tab[r->mip[1]];
        a = r->weight[0];
    } else if (mip_read(r, 0, mips) && r->fade < 1) {
        fine = &tab[r->mip[0]];   /* the last mip, of weight fade */
        coarse = &tab[mips];
        a = r->fade;
    } else {
        return;
    }
    double k = a * (1 - a);
    mss[0] += k * ((double)coarse->mss_x - fine->mss_x);
    mss[1] += k * ((double)coarse->mss_z - fine->mss_z);
    mss[2] += k * ((double)coarse->mss_xz - fine->mss_xz);
}
