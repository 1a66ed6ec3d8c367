/*
 * lod.c - "Where each mip is read" (see lod.h).
 */
#include "lod.h"

#include <math.h>

#include "foam.h"

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

double proto_lod_held(const proto_lod_read *r, const proto_mip_entry *tab, int mips, int kernel)
{
    if (kernel < 0 || kernel >= PROTO_READ_KERNELS)
        return 1;
    double sw = 0, sh = 0;
    for (int k = 0; k < 2; k++) {
        if (!mip_read(r, k, mips))
            continue;
        unsigned h = tab[r->mip[k]].held[kernel];
        if (!h)
            return 1; /* a block without the read table */
        sw += r->weight[k];
        sh += r->weight[k] * (h / 32768.0);
    }
    return sw > 0 ? sh / sw : 1;
}

double proto_lod_breaking_var(const proto_lod_read *r, const proto_mip_entry *tab, int mips, int kernel)
{
    double un[3] = {0, 0, 0};
    proto_lod_mss_add(r, tab, mips, un);
    double v = (double)tab[mips].mss_x + tab[mips].mss_z - un[0] - un[1];
    return v > 0 ? v * proto_lod_held(r, tab, mips, kernel) : 0;
}

double proto_lod_foam(const proto_cascade_block *b, double var, double beta, double q)
{
    if (!(b->flags & PROTO_CASCADE_FOAM) || b->foam_rows < 1)
        return 0;
    const proto_foam_row *t = b->foam;
    int n = b->foam_rows > PROTO_FOAM_ROWS ? PROTO_FOAM_ROWS : b->foam_rows;
    double sigma = sqrt(var > 0 ? var : 0), a, omega;
    if (n == 1 || !(sigma > t[0].sigma)) {
        a = t[0].a;
        omega = t[0].omega;
    } else if (sigma >= t[n - 1].sigma) {
        a = t[n - 1].a;
        omega = t[n - 1].omega;
    } else {
        int i = 1;
        while (t[i].sigma < sigma)
            i++;
        double f = (sigma - t[i - 1].sigma) / ((double)t[i].sigma - t[i - 1].sigma);
        a = t[i - 1].a + f * ((double)t[i].a - t[i - 1].a);
        omega = t[i - 1].omega + f * ((double)t[i].omega - t[i - 1].omega);
    }
    ocean_foam_map m = {a, OCEAN_FOAM_BETA_BREAK, -1.0,
                        omega > 0 ? 1.0 / (omega * OCEAN_FOAM_DECAY_S) : INFINITY};
    double f = ocean_foam_value(&m, beta, q);
    return f > 0 ? (f < 1 ? f : 1) : 0;
}
