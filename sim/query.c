/*
 * query.c - point queries by inverting the choppy displacement.
 *
 * The surface is the image of the parameter plane under
 *   x0 -> x0 + D(x0)   (D: FFT displacement + Gerstner near field).
 * To answer "what is at world (x, z)" we solve x0 + D(x0) = x by Newton's
 * method with the Jacobian of the total displacement (the FFT's Dxx, Dxz,
 * Dzz plus the near field's own derivatives), damped by halving the step
 * while the residual does not shrink, and a fixed-point step x0 <- x -
 * D(x0) where the Jacobian is (near) singular.  Where the surface folds
 * several x0 map to x; the one reached is returned and flagged.
 *
 * Three stages keep the costly reading for the last steps: a predictor
 * (Newton on the FFT fields read bilinearly, no near field: an eighth of an
 * accurate step) gets within the bilinear reading's centimetres; the
 * accurate iteration takes a step or two from there; and its last step,
 * taken from under 0.3 sqrt(tolerance) where Newton converges
 * quadratically, is checked by the final reading instead of a reading of
 * its own.  On the ocean `make run` serves that took a point from 8.5 to
 * 6.2 us (5.6 with the accurate reading's loads restructured, ocean.c),
 * with the same error against the exact waves, 0.036 mm RMS (bench_filter
 * "Point queries").
 *
 * The FFT fields are read with ocean_frame_sample_accurate (Hermite on the
 * spectral derivatives, about a millimetre from the waves themselves in a
 * Beaufort 10 sea), not bilinearly, and the near field is summed exactly
 * (an ocean_gerstner_frame prepared once per call).  The error bound is
 * against the exact sum of the same waves: the reading's own bound on the
 * height, plus the world slope times what is left horizontally (the
 * residual and the reading's bound on the displacement).
 */
#include "query.h"
#include "ocean_time.h"

#include <math.h>
#include <string.h>

void ocean_query_options_default(ocean_query_options *o)
{
    o->max_iterations = 24;
    o->tolerance = 1e-5;
    o->bilinear = 0;
}

typedef struct ctx {
    const ocean_frame *f;
    ocean_gerstner_frame *gf;   /* NULL: no near field */
    int bilinear;
} ctx;

static void read_fields(const ctx *c, double x0, double z0, unsigned want, ocean_point *pt,
                        ocean_point *err)
{
    if (c->bilinear) {
        ocean_frame_sample_some(c->f, x0, z0, want, pt);
        if (err)
            *err = (ocean_point){.height = INFINITY, .dx = INFINITY, .dz = INFINITY};
    } else {
        ocean_frame_sample_accurate(c->f, x0, z0, want, pt, err);
    }
}

/* |(a, b)|.  Points are refused beyond 1e12 m and displacements, slopes
 * and bounds are far smaller, so the squares cannot overflow (an infinite
 * bound stays infinite): libm's hypot, which rescales to be safe anywhere,
 * was a tenth of a query's time. */
static inline double norm2(double a, double b)
{
    return sqrt(a * a + b * b);
}

typedef struct disp {
    double dx, dz;               /* total horizontal displacement */
    double jxx, jxz, jzx, jzz;   /* d(x0 + D)/d(x0): jxz = d(x + Dx)/dz */
} disp;

static void displacement_at(const ctx *c, double x0, double z0, disp *d)
{
    ocean_point pt;
    read_fields(c, x0, z0, OCEAN_SAMPLE_DISPLACEMENT | OCEAN_SAMPLE_FOAM, &pt, NULL);
    d->dx = pt.dx;
    d->dz = pt.dz;
    d->jxx = 1.0 + pt.dxx;
    d->jzz = 1.0 + pt.dzz;
    d->jxz = d->jzx = pt.dxz;
    if (c->gf) {
        ocean_gerstner_point gp;
        if (ocean_gerstner_frame_evaluate(c->gf, &x0, &z0, 1, &gp) == OCEAN_OK) {
            d->dx += gp.dx;
            d->dz += gp.dz;
            d->jxx += gp.dxx;
            d->jxz += gp.dxz;
            d->jzx += gp.dzx;
            d->jzz += gp.dzz;
        }
    }
}

/* Where the predictor stops: a few times the bilinear reading's own error
 * in D, beyond which its root is no better than its reading. */
#define PREDICT_TOL 5e-3
#define PREDICT_MAX 12

/* The predictor: Newton on the FFT fields read bilinearly, without the near
 * field (an eighth of an accurate step's cost, and the near field moves
 * the root by millimetres), from (x, z) to its own root, which lies within
 * the reading's centimetres of the true one; the accurate iteration then
 * needs a step or two where it needed four.  *jmin gets the smallest J
 * met on the way (the path from x counts for folds); *its the steps taken.
 * Stops where J is near singular, leaving the careful iteration there. */
static void predict(const ctx *c, double x, double z, double *px, double *pz, double *jmin, int *its)
{
    double x0 = x, z0 = z;
    ocean_point pt;
    ocean_frame_sample_some(c->f, x0, z0, OCEAN_SAMPLE_DISPLACEMENT | OCEAN_SAMPLE_FOAM, &pt);
    double ex = x0 + pt.dx - x, ez = z0 + pt.dz - z, res = norm2(ex, ez);
    for (int k = 0; k < PREDICT_MAX && res > PREDICT_TOL; k++) {
        double jxx = 1.0 + pt.dxx, jzz = 1.0 + pt.dzz, jxz = pt.dxz;
        double det = jxx * jzz - jxz * jxz;
        if (det < *jmin)
            *jmin = det;
        if (!(det > 0.05))
            break;
        double nx0 = x0 - (jzz * ex - jxz * ez) / det, nz0 = z0 - (jxx * ez - jxz * ex) / det;
        ocean_point np;
        ocean_frame_sample_some(c->f, nx0, nz0, OCEAN_SAMPLE_DISPLACEMENT | OCEAN_SAMPLE_FOAM, &np);
        double nex = nx0 + np.dx - x, nez = nz0 + np.dz - z, nres = norm2(nex, nez);
        if (!(nres < res))
            break;
        x0 = nx0, z0 = nz0, pt = np, ex = nex, ez = nez, res = nres;
        ++*its;
    }
    *px = x0;
    *pz = z0;
}

static void answer_one(const ctx *c, double x, double z, const ocean_query_options *opt,
                       int have_derivs, ocean_query_result *out)
{
    double x0 = x, z0 = z;
    int it = 0;
    /* the smallest J the iteration met: a path from x through J <= 0 means
     * the surface folds between x and the answer */
    double jmin = INFINITY;
    int pit = 0;   /* the predictor's steps (not counted against max_iterations) */
    if (have_derivs && !c->bilinear)
        predict(c, x, z, &x0, &z0, &jmin, &pit);
    disp d;
    displacement_at(c, x0, z0, &d);
    double ex = x0 + d.dx - x, ez = z0 + d.dz - z, res = norm2(ex, ez);
    double j0 = d.jxx * d.jzz - d.jxz * d.jzx;
    if (j0 < jmin)
        jmin = j0;
    /* Near the root Newton converges quadratically: a step from a residual
     * under `quad` lands within about res^2 / (a wave's length) of it, far
     * under the tolerance, so that step is taken without reading D there:
     * the final reading, which the answer needs anyway, checks it, and the
     * iteration goes on from it in the rare case it missed. */
    double quad = 0.3 * sqrt(opt->tolerance);
    ocean_point pt, err;
    ocean_gerstner_point gp;
    for (;;) {
        int unread = 0;
        for (; it < opt->max_iterations && res > opt->tolerance; it++) {
            double det = d.jxx * d.jzz - d.jxz * d.jzx;
            if (det < jmin)
                jmin = det;
            double sx, sz;
            int newton = have_derivs && fabs(det) > 1e-3;
            if (newton) {
                /* Newton: solve J step = e */
                sx = (d.jzz * ex - d.jxz * ez) / det;
                sz = (d.jxx * ez - d.jzx * ex) / det;
            } else {
                sx = ex;
                sz = ez;
            }
            if (newton && res < quad) {
                x0 -= sx;
                z0 -= sz;
                it++;
                unread = 1;
                break;
            }
            /* Halve the step until the residual shrinks (at most 8 times: far
             * from the root a full Newton step can overshoot a crest). */
            double nx0 = x0, nz0 = z0, nres = INFINITY, nex = ex, nez = ez;
            disp nd = d;
            for (int k = 0; k < 8; k++) {
                nx0 = x0 - sx;
                nz0 = z0 - sz;
                displacement_at(c, nx0, nz0, &nd);
                nex = nx0 + nd.dx - x;
                nez = nz0 + nd.dz - z;
                nres = norm2(nex, nez);
                if (nres < res)
                    break;
                sx *= 0.5;
                sz *= 0.5;
            }
            if (!(nres < res)) {
                /* no descent along this direction: a fixed-point step instead */
                nx0 = x - d.dx;
                nz0 = z - d.dz;
                displacement_at(c, nx0, nz0, &nd);
                nex = nx0 + nd.dx - x;
                nez = nz0 + nd.dz - z;
                nres = norm2(nex, nez);
                if (!(nres < res)) {
                    it++;
                    break;
                }
            }
            x0 = nx0;
            z0 = nz0;
            d = nd;
            ex = nex;
            ez = nez;
            res = nres;
        }
        /* Everything at the final parameter point. */
        read_fields(c, x0, z0, OCEAN_SAMPLE_ALL, &pt, &err);
        memset(&gp, 0, sizeof gp);
        if (c->gf)
            ocean_gerstner_frame_evaluate(c->gf, &x0, &z0, 1, &gp);
        double fex = x0 + pt.dx + gp.dx - x, fez = z0 + pt.dz + gp.dz - z, fres = norm2(fex, fez);
        if (!unread || fres <= opt->tolerance || it >= opt->max_iterations) {
            ex = fex;
            ez = fez;
            res = fres;
            break;
        }
        /* the unread step fell short: on from where it landed */
        d = (disp){.dx = pt.dx + gp.dx, .dz = pt.dz + gp.dz, .jxx = 1.0 + pt.dxx + gp.dxx,
                   .jxz = pt.dxz + gp.dxz, .jzx = pt.dxz + gp.dzx, .jzz = 1.0 + pt.dzz + gp.dzz};
        ex = fex;
        ez = fez;
        res = fres;
    }

    /* Tangents of the displaced surface along x0 and z0, both fields;
     * normal = t_z x t_x, y up. */
    double sx = pt.slope_x + gp.slope_x, sz = pt.slope_z + gp.slope_z;
    double dxx = pt.dxx + gp.dxx, dzz = pt.dzz + gp.dzz;
    double dxz = pt.dxz + gp.dxz, dzx = pt.dxz + gp.dzx; /* dDx/dz, dDz/dx */
    double txx = 1.0 + dxx, txy = sx, txz = dzx;
    double tzx = dxz, tzy = sz, tzz = 1.0 + dzz;
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
    out->height = pt.height + gp.dy;
    out->velocity[0] = pt.vel_x + gp.vx;
    out->velocity[1] = pt.vel_y + gp.vy;
    out->velocity[2] = pt.vel_z + gp.vz;
    double jac = txx * tzz - tzx * txz;
    /* the whitecaps tiles carry (ocean.h "Whitecap foam"), the near field's
     * divergence included: the legacy Jacobian ramp answered near 0 where
     * a viewer saw the wind's coverage */
    out->foam = have_derivs ? ocean_frame_foam(c->f, dxx, dzz) : 0.0;
    out->folded = jac <= 0.0 || jmin <= 0.0;
    out->residual = res;
    /* A horizontal miss m in the world moves the parameter point by J^-1 m
     * and the height by grad(eta) J^-1 m: the world slope g = grad(eta)
     * J^-1 times the miss, which is the residual plus what the reading of
     * D may be off by.  Where J is singular (a fold) no bound holds. */
    double gx = INFINITY, gz = INFINITY;
    if (jac > 0.0) {
        gx = (sx * tzz - sz * txz) / jac;
        gz = (sz * txx - sx * tzx) / jac;
    }
    double miss = res + norm2(err.dx, err.dz);
    out->error = err.height + (miss > 0.0 ? norm2(gx, gz) * miss : 0.0);
    /* The slope times the miss is a first-order bound: it holds while the
     * miss is small beside the waves' curvature (a centimetre leaves a
     * second-order term under a tenth of a millimetre for the shortest
     * waves a field holds).  An iteration that stopped farther away (no
     * descent left: at choppiness 6-10 some 0.1-0.7 % of points, 0.4 m
     * away with J > 0 on the way) answers for another point, and the bound
     * it would give (0.14 m against a true 0.35 m) is no bound. */
    if (res > opt->tolerance && res > OCEAN_QUERY_MISS_MAX)
        out->error = INFINITY;
    out->iterations = it + pit;
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
    ctx c = {f, NULL, opt->bilinear != 0};
    if (g) {
        ocean_result gr = ocean_gerstner_frame_create(g, &c.gf);
        if (gr == OCEAN_OK)
            gr = ocean_gerstner_frame_set(c.gf, v, t);
        if (gr != OCEAN_OK) {
            ocean_gerstner_frame_destroy(c.gf);
            return gr;
        }
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
        answer_one(&c, x, z, opt, have_derivs, &out[i]);
    }
    ocean_gerstner_frame_destroy(c.gf);
    return r;
}
