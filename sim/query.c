/*
 * query.c - point queries by inverting the choppy displacement.
 *
 * The surface is the image of the parameter plane under
 *   x0 -> x0 + D(x0)   (D: FFT displacement + Gerstner near field).
 * To answer "what is at world (x, z)" we solve x0 + D(x0) = x.  Newton with
 * the displacement's own derivatives (the foam channel's Dxx, Dzz, Dxz)
 * converges quadratically wherever J > 0; without them, or where J is near
 * 0, a fixed-point step x0 <- x - D(x0) is used, which converges while the
 * map is a contraction (no folding).  The residual left is the error bound.
 */
#include "query.h"
#include "ocean_time.h"

#include <math.h>
#include <string.h>

void ocean_query_options_default(ocean_query_options *o)
{
    o->max_iterations = 12;
    o->tolerance = 1e-4;
}

typedef struct disp {
    double dx, dz;              /* total horizontal displacement */
    double jxx, jzz, jxz, jzx;  /* d(x0 + D)/d(x0): Jacobian matrix */
    int have_j;
} disp;

/* Displacement and its Jacobian at parameter point (x0, z0). */
static void displacement_at(const ocean_frame *f, const ocean_gerstner *g,
                            const ocean_gerstner_view *v, double t, double x0, double z0,
                            int with_j, disp *d, ocean_point *pt, ocean_gerstner_point *gp)
{
    memset(d, 0, sizeof *d);
    if (with_j) {
        ocean_frame_sample(f, x0, z0, pt);
        d->dx = pt->dx;
        d->dz = pt->dz;
        d->jxx = 1.0 + pt->dxx;
        d->jzz = 1.0 + pt->dzz;
        d->jxz = d->jzx = pt->dxz;
        d->have_j = pt->dxx != 0.0 || pt->dzz != 0.0 || pt->dxz != 0.0;
    } else {
        ocean_frame_sample_displacement(f, x0, z0, &d->dx, &d->dz);
    }
    if (g) {
        ocean_gerstner_evaluate(g, v, t, &x0, &z0, 1, gp);
        d->dx += gp->dx;
        d->dz += gp->dz;
    } else {
        memset(gp, 0, sizeof *gp);
        gp->jacobian = 1.0;
    }
}

static void answer_one(const ocean_frame *f, const ocean_gerstner *g,
                       const ocean_gerstner_view *v, double t, double x, double z,
                       const ocean_query_options *opt, int have_derivs,
                       ocean_query_result *out)
{
    double x0 = x, z0 = z, res = INFINITY;
    int it = 0;
    disp d;
    ocean_point pt;
    ocean_gerstner_point gp;
    for (; it < opt->max_iterations; it++) {
        displacement_at(f, g, v, t, x0, z0, have_derivs, &d, &pt, &gp);
        double ex = x0 + d.dx - x, ez = z0 + d.dz - z;
        res = hypot(ex, ez);
        if (res <= opt->tolerance)
            break;
        double det = d.jxx * d.jzz - d.jxz * d.jzx;
        if (d.have_j && !g && det > 0.05) {
            /* Newton: solve J * step = e. */
            x0 -= (d.jzz * ex - d.jxz * ez) / det;
            z0 -= (d.jxx * ez - d.jzx * ex) / det;
        } else {
            x0 = x - d.dx;
            z0 = z - d.dz;
        }
    }
    /* Everything at the final parameter point. */
    ocean_frame_sample(f, x0, z0, &pt);
    if (g)
        ocean_gerstner_evaluate(g, v, t, &x0, &z0, 1, &gp);
    double ex = x0 + pt.dx + (g ? gp.dx : 0.0) - x, ez = z0 + pt.dz + (g ? gp.dz : 0.0) - z;
    res = hypot(ex, ez);

    /* Tangents of the displaced surface along x0 and z0 (FFT part), plus
     * the near field's slope; normal = t_z x t_x, y up. */
    double sx = pt.slope_x, sz = pt.slope_z;
    if (g && gp.ny > 0.0) {
        sx += -gp.nx / gp.ny;
        sz += -gp.nz / gp.ny;
    }
    double txx = 1.0 + pt.dxx, txy = sx, txz = pt.dxz;
    double tzx = pt.dxz, tzy = sz, tzz = 1.0 + pt.dzz;
    double nx = tzy * txz - tzz * txy;
    double ny = tzz * txx - tzx * txz;
    double nz = tzx * txy - tzy * txx;
    double len = sqrt(nx * nx + ny * ny + nz * nz);
    if (!(len > 0.0) || ny <= 0.0) {
        /* Folded or degenerate: fall back to the height-field normal. */
        nx = -sx;
        ny = 1.0;
        nz = -sz;
        len = sqrt(nx * nx + ny * ny + nz * nz);
    }
    out->normal[0] = nx / len;
    out->normal[1] = ny / len;
    out->normal[2] = nz / len;
    out->height = pt.height + (g ? gp.dy : 0.0);
    out->velocity[0] = pt.vel_x + (g ? gp.vx : 0.0);
    out->velocity[1] = pt.vel_y + (g ? gp.vy : 0.0);
    out->velocity[2] = pt.vel_z + (g ? gp.vz : 0.0);
    /* The near field's folding adds to the FFT's to first order. */
    double jac = pt.jacobian + (g ? gp.jacobian - 1.0 : 0.0);
    out->foam = ocean_foam_from_jacobian((float)jac);
    if (!have_derivs && !g)
        out->foam = 0.0;
    out->folded = jac <= 0.0;
    out->residual = res;
    /* A horizontal miss of res moves the height by at most |slope| res. */
    out->error = hypot(sx, sz) * res;
    out->iterations = it;
}

ocean_result ocean_query_points(const ocean_frame *f, const ocean_gerstner *g,
                                const ocean_gerstner_view *v, double t,
                                const double *xz, size_t n, const ocean_query_options *opt,
                                ocean_query_result *out, size_t *bad)
{
    if (!f || (n > 0 && (!xz || !out)) || !ocean_time_ok(t))
        return OCEAN_EINVAL;
    ocean_query_options defopt;
    if (!opt) {
        ocean_query_options_default(&defopt);
        opt = &defopt;
    }
    if (opt->max_iterations < 1 || opt->max_iterations > 1000 || !(opt->tolerance > 0.0))
        return OCEAN_EINVAL;
    ocean_gerstner_view defview;
    if (g && !v) {
        ocean_gerstner_view_default(&defview);
        v = &defview;
    }
    int have_derivs = 0;
    ocean_frame_info info;
    ocean_frame_get_info(f, &info);
    for (int c = 0; c < info.cascades; c++) {
        const ocean_field *fd = ocean_frame_field(f, c);
        if (fd && fd->dxx)
            have_derivs = 1;
    }
    ocean_result r = OCEAN_OK;
    for (size_t i = 0; i < n; i++) {
        double x = xz[2 * i], z = xz[2 * i + 1];
        if (!isfinite(x) || !isfinite(z) || fabs(x) > 1e12 || fabs(z) > 1e12) {
            memset(&out[i], 0, sizeof out[i]);
            out[i].error = INFINITY;
            if (r == OCEAN_OK && bad)
                *bad = i;
            r = OCEAN_EINVAL;
            continue;
        }
        answer_one(f, g, v, t, x, z, opt, have_derivs, &out[i]);
    }
    return r;
}
