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
 * its own.  On the ocean `make run` serves, the stages take a point from
 * 8.5 to 6.2 us (5.6 with the accurate reading's loads arranged as in
 * ocean_accurate.c) with the same error against the exact waves, 0.036 mm
 * RMS (bench_filter "Point queries").
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
    double near_m0, near_m1;    /* the near field's breaking-index moments */
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
 * costs a tenth of a query's time. */
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

/* Where the inversion stands: the parameter point (x0, z0), the total
 * displacement there, and what it misses (x, z) by, (ex, ez) and its
 * length res. */
typedef struct inv_state {
    double x0, z0;
    disp d;
    double ex, ez, res;
    /* the smallest J the iteration met: a path from x through J <= 0
     * means the surface folds between x and the answer */
    double jmin;
    int it;
} inv_state;

/* The accurate iteration's start: the predictor's root where the fields
 * have derivatives to predict with, else (x, z) itself.  *pit gets the
 * predictor's steps. */
static void inv_start(const ctx *c, double x, double z, int have_derivs, inv_state *s, int *pit)
{
    s->x0 = x;
    s->z0 = z;
    s->it = 0;
    s->jmin = INFINITY;
    if (have_derivs && !c->bilinear)
        predict(c, x, z, &s->x0, &s->z0, &s->jmin, pit);
    displacement_at(c, s->x0, s->z0, &s->d);
    s->ex = s->x0 + s->d.dx - x;
    s->ez = s->z0 + s->d.dz - z;
    s->res = norm2(s->ex, s->ez);
    double j0 = s->d.jxx * s->d.jzz - s->d.jxz * s->d.jzx;
    if (j0 < s->jmin)
        s->jmin = j0;
}

/* Moves s by the step (sx, sz) if the residual shrinks, halving the step
 * until it does (at most 8 times: far from the root a full Newton step can
 * overshoot a crest), else by a fixed-point step.  Returns 0, s unchanged,
 * where neither descends. */
static int inv_descend(const ctx *c, double x, double z, double sx, double sz, inv_state *s)
{
    double nx0 = s->x0, nz0 = s->z0, nres = INFINITY, nex = s->ex, nez = s->ez;
    disp nd = s->d;
    for (int k = 0; k < 8; k++) {
        nx0 = s->x0 - sx;
        nz0 = s->z0 - sz;
        displacement_at(c, nx0, nz0, &nd);
        nex = nx0 + nd.dx - x;
        nez = nz0 + nd.dz - z;
        nres = norm2(nex, nez);
        if (nres < s->res)
            break;
        sx *= 0.5;
        sz *= 0.5;
    }
    if (!(nres < s->res)) {
        /* no descent along this direction: a fixed-point step instead */
        nx0 = x - s->d.dx;
        nz0 = z - s->d.dz;
        displacement_at(c, nx0, nz0, &nd);
        nex = nx0 + nd.dx - x;
        nez = nz0 + nd.dz - z;
        nres = norm2(nex, nez);
        if (!(nres < s->res))
            return 0;
    }
    s->x0 = nx0;
    s->z0 = nz0;
    s->d = nd;
    s->ex = nex;
    s->ez = nez;
    s->res = nres;
    return 1;
}

/* Newton steps (fixed-point ones where J is near singular or missing)
 * until the tolerance, the iteration limit or no descent.  Returns 1 when
 * the last step, taken from under quad, was not read (see inv_solve). */
static int inv_iterate(const ctx *c, double x, double z, const ocean_query_options *opt,
                       int have_derivs, double quad, inv_state *s)
{
    for (; s->it < opt->max_iterations && s->res > opt->tolerance; s->it++) {
        const disp *d = &s->d;
        double det = d->jxx * d->jzz - d->jxz * d->jzx;
        if (det < s->jmin)
            s->jmin = det;
        double sx, sz;
        int newton = have_derivs && fabs(det) > 1e-3;
        if (newton) {
            /* Newton: solve J step = e */
            sx = (d->jzz * s->ex - d->jxz * s->ez) / det;
            sz = (d->jxx * s->ez - d->jzx * s->ex) / det;
        } else {
            sx = s->ex;
            sz = s->ez;
        }
        if (newton && s->res < quad) {
            s->x0 -= sx;
            s->z0 -= sz;
            s->it++;
            return 1;
        }
        if (!inv_descend(c, x, z, sx, sz, s)) {
            s->it++;
            return 0;
        }
    }
    return 0;
}

/* Both fields read at the answer's parameter point. */
typedef struct inv_reading {
    ocean_point pt, err;
    ocean_gerstner_point gp;
} inv_reading;

/* Inverts x0 + D(x0) = (x, z) from s and reads everything at the final
 * point.  Near the root Newton converges quadratically: a step from a
 * residual under `quad` lands within about res^2 / (a wave's length) of
 * it, far under the tolerance, so that step is taken without reading D
 * there: the final reading, which the answer needs anyway, checks it, and
 * the iteration goes on from it in the rare case it missed. */
static void inv_solve(const ctx *c, double x, double z, const ocean_query_options *opt,
                      int have_derivs, inv_state *s, inv_reading *rd)
{
    double quad = 0.3 * sqrt(opt->tolerance);
    for (;;) {
        int unread = inv_iterate(c, x, z, opt, have_derivs, quad, s);
        read_fields(c, s->x0, s->z0, OCEAN_SAMPLE_ALL, &rd->pt, &rd->err);
        memset(&rd->gp, 0, sizeof rd->gp);
        if (c->gf)
            ocean_gerstner_frame_evaluate(c->gf, &s->x0, &s->z0, 1, &rd->gp);
        const ocean_point *pt = &rd->pt;
        const ocean_gerstner_point *gp = &rd->gp;
        double fex = s->x0 + pt->dx + gp->dx - x, fez = s->z0 + pt->dz + gp->dz - z;
        double fres = norm2(fex, fez);
        if (!unread || fres <= opt->tolerance || s->it >= opt->max_iterations) {
            s->ex = fex;
            s->ez = fez;
            s->res = fres;
            return;
        }
        /* the unread step fell short: on from where it landed */
        s->d = (disp){.dx = pt->dx + gp->dx, .dz = pt->dz + gp->dz, .jxx = 1.0 + pt->dxx + gp->dxx,
                      .jxz = pt->dxz + gp->dxz, .jzx = pt->dxz + gp->dzx,
                      .jzz = 1.0 + pt->dzz + gp->dzz};
        s->ex = fex;
        s->ez = fez;
        s->res = fres;
    }
}

/* Tangents of the displaced surface along x0 (tx*) and z0 (tz*), both
 * fields. */
typedef struct tangents {
    double txx, txy, txz, tzx, tzy, tzz;
} tangents;

/* normal = t_z x t_x, y up; where the surface folds or degenerates, the
 * height field's normal. */
static void surface_normal(const tangents *t, double sx, double sz, double n[3])
{
    double nx = t->tzy * t->txz - t->tzz * t->txy;
    double ny = t->tzz * t->txx - t->tzx * t->txz;
    double nz = t->tzx * t->txy - t->tzy * t->txx;
    double len = sqrt(nx * nx + ny * ny + nz * nz);
    if (!(len > 0.0) || ny <= 0.0) {
        nx = -sx;
        ny = 1.0;
        nz = -sz;
        len = sqrt(nx * nx + ny * ny + nz * nz);
    }
    n[0] = nx / len;
    n[1] = ny / len;
    n[2] = nz / len;
}

/* A horizontal miss m in the world moves the parameter point by J^-1 m
 * and the height by grad(eta) J^-1 m: the world slope g = grad(eta) J^-1
 * times the miss, which is the residual plus what the reading of D may be
 * off by.  Where J is singular (a fold) no bound holds. */
static double error_bound(const tangents *t, double jac, double sx, double sz, double res,
                          const ocean_point *err, const ocean_query_options *opt)
{
    double gx = INFINITY, gz = INFINITY;
    if (jac > 0.0) {
        gx = (sx * t->tzz - sz * t->txz) / jac;
        gz = (sz * t->txx - sx * t->tzx) / jac;
    }
    double miss = res + norm2(err->dx, err->dz);
    double error = err->height + (miss > 0.0 ? norm2(gx, gz) * miss : 0.0);
    /* The slope times the miss is a first-order bound: it holds while the
     * miss is small beside the waves' curvature (a centimetre leaves a
     * second-order term under a tenth of a millimetre for the shortest
     * waves a field holds).  An iteration that stopped farther away (no
     * descent left: at choppiness 6-10 some 0.1-0.7 % of points, 0.4 m
     * away with J > 0 on the way) answers for another point, and the bound
     * it would give (0.14 m against a true 0.35 m) is no bound. */
    if (res > opt->tolerance && res > OCEAN_QUERY_MISS_MAX)
        error = INFINITY;
    return error;
}

static void answer_one(const ctx *c, double x, double z, const ocean_query_options *opt,
                       int have_derivs, ocean_query_result *out)
{
    inv_state s;
    int pit = 0;   /* the predictor's steps (not counted against max_iterations) */
    inv_start(c, x, z, have_derivs, &s, &pit);
    inv_reading rd;
    inv_solve(c, x, z, opt, have_derivs, &s, &rd);
    const ocean_point *pt = &rd.pt;
    const ocean_gerstner_point *gp = &rd.gp;

    double sx = pt->slope_x + gp->slope_x, sz = pt->slope_z + gp->slope_z;
    double dxx = pt->dxx + gp->dxx, dzz = pt->dzz + gp->dzz;
    double dxz = pt->dxz + gp->dxz, dzx = pt->dxz + gp->dzx; /* dDx/dz, dDz/dx */
    tangents t = {1.0 + dxx, sx, dzx, dxz, sz, 1.0 + dzz};
    surface_normal(&t, sx, sz, out->normal);
    out->height = pt->height + gp->dy;
    out->velocity[0] = pt->vel_x + gp->vx;
    out->velocity[1] = pt->vel_y + gp->vy;
    out->velocity[2] = pt->vel_z + gp->vz;
    double jac = t.txx * t.tzz - t.tzx * t.txz;
    /* the whitecaps tiles carry (ocean.h "Whitecap foam"), the near field's
     * divergence and trails included where it is (the legacy Jacobian ramp
     * answered near 0 where a viewer saw the wind's coverage); there the
     * ramp is solved for the band both make, so the near field's short
     * breakers do not add to the wind's coverage (its fade ring takes the
     * full-fade band: a little less foam there) */
    ocean_foam_reading how = c->bilinear ? OCEAN_FOAM_BILINEAR : OCEAN_FOAM_CUBIC;
    out->foam = !have_derivs ? 0.0
              : gp->fade > 0.0 ? ocean_frame_foam_plus(c->f, how, c->near_m0, c->near_m1, dxx, dzz, pt->bq + gp->bq)
                               : ocean_frame_foam(c->f, how, dxx, dzz, pt->bq);
    out->folded = jac <= 0.0 || s.jmin <= 0.0;
    out->residual = s.res;
    out->error = error_bound(&t, jac, sx, sz, s.res, &rd.err, opt);
    out->iterations = s.it + pit;
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
    ctx c = {f, NULL, opt->bilinear != 0, 0.0, 0.0};
    if (g) {
        ocean_gerstner_foam_moments(g, v, &c.near_m0, &c.near_m1);
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
