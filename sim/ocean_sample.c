/*
 * ocean_sample.c - reading an evaluated frame at world points: the summed
 * cascades read bilinearly on each periodic grid (the daemon's per-vertex
 * path), the frame's foam at a point, and the statistics of its fields.
 * A frame is read-only here: any number of threads may sample one frame
 * at once while no evaluation writes it.
 */
#include "ocean.h"
#include "ocean_internal.h"

#include <math.h>
#include <string.h>

/* The four corners of a cell, located once per cascade and shared by every
 * channel read there; bilinear in double, (a (1-fx) + b fx)(1-fz) + (c (1-fx) + d fx) fz. */
typedef struct corners {
    size_t o00, o01, o10, o11;
    double fx, fz;
} corners;

static inline corners corners_of(const ocean_field *fd, double x, double z)
{
    ocean_cell q = ocean_locate(fd, x, z);
    int n = fd->n, i1 = (q.i0 + 1) & (n - 1), j1 = (q.j0 + 1) & (n - 1);
    size_t r0 = (size_t)q.i0 * n, r1 = (size_t)i1 * n;
    return (corners){r0 + q.j0, r0 + j1, r1 + q.j0, r1 + j1, q.fx, q.fz};
}

static inline double corners_read(const float *g, const corners *k)
{
    double a = g[k->o00], b = g[k->o01], c = g[k->o10], d = g[k->o11];
    return (a * (1.0 - k->fx) + b * k->fx) * (1.0 - k->fz) + (c * (1.0 - k->fx) + d * k->fx) * k->fz;
}

/* The foam of summed foam channels (ocean.h "Whitecap foam") with ramp m. */
static inline double foam_with(const ocean_frame *f, const ocean_foam_map *m, double dxx, double dzz, double bq)
{
    return ocean_foam_value(m, ocean_foam_beta(dxx, dzz, f->foam_inv_lambda),
                            ocean_foam_beta(bq, 0.0, f->foam_inv_lambda));
}

/* Sums go to locals and reach *out once at the end: stores through out
 * (doubles) could alias the field descriptors' doubles, and the compiler
 * would reload every descriptor after every store.  This is the daemon's
 * per-vertex hot path (one call per mesh vertex per client frame). */
void ocean_frame_sample_some(const ocean_frame *f, double x, double z, unsigned want,
                             ocean_point *out)
{
    double h = 0, dx = 0, dz = 0, sx = 0, sz = 0, vx = 0, vy = 0, vz = 0;
    double dxx = 0.0, dzz = 0.0, dxz = 0.0, bq = 0.0;
    int any_foam = 0;
    for (int c = 0; c < f->cascades; c++) {
        const ocean_field *fd = &f->field[c];
        if (!fd->effects)
            continue;
        const corners k = corners_of(fd, x, z);
        /* A group not wanted reads as a channel not evaluated. */
        if ((want & OCEAN_SAMPLE_HEIGHT) && fd->height)
            h += corners_read(fd->height, &k);
        if (want & OCEAN_SAMPLE_DISPLACEMENT) {
            if (fd->dx) dx += corners_read(fd->dx, &k);
            if (fd->dz) dz += corners_read(fd->dz, &k);
        }
        if (want & OCEAN_SAMPLE_SLOPE) {
            if (fd->slope_x) sx += corners_read(fd->slope_x, &k);
            if (fd->slope_z) sz += corners_read(fd->slope_z, &k);
        }
        if (want & OCEAN_SAMPLE_VELOCITY) {
            if (fd->vel_x) vx += corners_read(fd->vel_x, &k);
            if (fd->vel_y) vy += corners_read(fd->vel_y, &k);
            if (fd->vel_z) vz += corners_read(fd->vel_z, &k);
        }
        if ((want & OCEAN_SAMPLE_FOAM) && fd->dxx) {
            any_foam = 1;
            dxx += corners_read(fd->dxx, &k);
            dzz += corners_read(fd->dzz, &k);
            dxz += corners_read(fd->dxz, &k);
            if (fd->bq) bq += corners_read(fd->bq, &k);
        }
    }
    /* J of the summed displacement, not a sum of per-cascade Jacobians. */
    double jac = (1.0 + dxx) * (1.0 + dzz) - dxz * dxz;
    *out = (ocean_point){.height = h, .dx = dx, .dz = dz, .slope_x = sx, .slope_z = sz,
                         .jacobian = jac,
                         .foam = any_foam ? foam_with(f, &f->foam_map[OCEAN_FOAM_BILINEAR], dxx, dzz, bq) : 0.0,
                         .vel_x = vx, .vel_y = vy, .vel_z = vz, .dxx = dxx, .dzz = dzz, .dxz = dxz,
                         .bq = bq};
}

static int frame_has_foam(const ocean_frame *f)
{
    int any = 0;
    for (int c = 0; c < f->cascades; c++)
        any |= f->field[c].dxx != NULL;
    return any;
}

double ocean_frame_foam(const ocean_frame *f, ocean_foam_reading rd, double dxx, double dzz, double bq)
{
    if (!frame_has_foam(f))
        return 0.0;
    return foam_with(f, &f->foam_map[rd], dxx, dzz, bq);
}

double ocean_frame_foam_plus(const ocean_frame *f, ocean_foam_reading rd, double m0, double m1, double dxx,
                             double dzz, double bq)
{
    if (!(m0 > 0.0))
        return ocean_frame_foam(f, rd, dxx, dzz, bq);
    if (!frame_has_foam(f))
        return 0.0;
    double om = f->foam_omega[rd];
    /* the extra waves' moments in beta's units (beta = -(dxx + dzz) / lambda) */
    double il2 = f->foam_inv_lambda * f->foam_inv_lambda, s2 = f->foam_sigma[rd] * f->foam_sigma[rd];
    double e0 = m0 * il2, e1 = m1 * il2, v = s2 + e0;
    ocean_foam_map m;
    if (ocean_foam_map_solve(sqrt(v), (s2 * om + e1) / v, f->info.whitecap_target, &m) != OCEAN_OK)
        return ocean_frame_foam(f, rd, dxx, dzz, bq);
    return foam_with(f, &m, dxx, dzz, bq);
}

void ocean_frame_sample(const ocean_frame *f, double x, double z, ocean_point *out)
{
    ocean_frame_sample_some(f, x, z, OCEAN_SAMPLE_ALL, out);
}

void ocean_frame_sample_displacement(const ocean_frame *f, double x, double z,
                                     double *dx, double *dz)
{
    double sx = 0.0, sz = 0.0;
    for (int c = 0; c < f->cascades; c++) {
        const ocean_field *fd = &f->field[c];
        if (!fd->dx)
            continue;
        const corners k = corners_of(fd, x, z);
        sx += corners_read(fd->dx, &k);
        sz += corners_read(fd->dz, &k);
    }
    *dx = sx;
    *dz = sz;
}

void ocean_frame_get_field_stats(const ocean_frame *f, ocean_field_stats *out)
{
    memset(out, 0, sizeof *out);
    out->min_jacobian = 1.0;
    double var = 0.0;
    int finest = -1;
    for (int c = 0; c < f->cascades; c++) {
        const ocean_field *fd = &f->field[c];
        if (fd->dxx)
            finest = c;
        if (!fd->height)
            continue;
        size_t nn = (size_t)fd->n * fd->n;
        double s = 0.0, s2 = 0.0;
        for (size_t i = 0; i < nn; i++) {
            s += fd->height[i];
            s2 += (double)fd->height[i] * fd->height[i];
        }
        double m = s / nn;
        out->mean += m;
        var += s2 / nn - m * m;
    }
    out->hs = 4.0 * sqrt(var > 0.0 ? var : 0.0);
    if (finest < 0)
        return;
    const ocean_field *fd = &f->field[finest];
    int n = fd->n;
    double h = fd->patch_m / n, folded = 0.0, foam = 0.0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double jac, fm;
            if ((f->cascades == 1 || finest == 0) && fd->jacobian) {
                jac = fd->jacobian[(size_t)i * n + j];
                fm = fd->foam[(size_t)i * n + j];
            } else {
                ocean_point pt;
                ocean_frame_sample_some(f, j * h, i * h, OCEAN_SAMPLE_FOAM, &pt);
                jac = pt.jacobian;
                fm = pt.foam;
            }
            if (jac < out->min_jacobian)
                out->min_jacobian = jac;
            folded += jac < 0.0;
            foam += fm;
        }
    out->folded_fraction = folded / ((double)n * n);
    out->foam_coverage = foam / ((double)n * n);
}
