/*
 * mesh_projected.c - the projected grid (seed 000's title, after Johanson
 * 2004, "Real-time water rendering: introducing the projected grid").
 *
 * As in Johanson, the grid is laid out in the space of a projector that is
 * decoupled from the camera: the projector sits above the camera's ground
 * point, at the camera's height or, when the camera is inside the wave
 * slab |y| <= margin, lifted above it, and the grid spans the range the
 * camera's frustum covers once intersected with that slab (not with the
 * flat plane): a crest or trough at the screen edge therefore always has
 * grid under it.  Our projector's screen is angular - azimuth around the
 * ground point times the angle from the nadir - instead of a planar
 * perspective, so it stays regular for every orientation, nadir views
 * included (a full circle with a centre vertex), and its rows, uniform in
 * the angle from the nadir, are what a screen-space grid's rows are for a
 * camera looking at the horizon.  Horizon handling: rows stop at the
 * range, so no row is ever projected at or above the horizon.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mesh.h"
#include "mesh_internal.h"

#define NS 64  /* frustum rays sampled per screen side */

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

typedef struct ray_ctx {
    double c[3], f[3], r[3], u[3], tx, ty, A, R;
} ray_ctx;

/* The part of the ray through screen point (u, v) inside the slab
 * |y| <= A and within horizontal range R: 1 and t[0..1] if not empty. */
static int ray_slab(const ray_ctx *rc, double u, double v, double t[2], double d[3])
{
    for (int k = 0; k < 3; k++)
        d[k] = rc->f[k] + u * rc->tx * rc->r[k] + v * rc->ty * rc->u[k];
    double hs = hypot(d[0], d[2]);
    double tlo = 0, thi = hs > 1e-12 ? rc->R / hs : INFINITY;
    if (fabs(d[1]) < 1e-15) {
        if (fabs(rc->c[1]) > rc->A)
            return 0;
    } else {
        double t1 = (rc->A - rc->c[1]) / d[1], t2 = (-rc->A - rc->c[1]) / d[1];
        tlo = fmax(tlo, fmin(t1, t2));
        thi = fmin(thi, fmax(t1, t2));
    }
    if (!(thi >= tlo) || !isfinite(thi))
        return 0;
    t[0] = tlo;
    t[1] = thi;
    return 1;
}

typedef struct fp_acc {
    double *ang;
    int na, cap, full, any;
    double rmin, rmax, A;
} fp_acc;

static void fp_add(fp_acc *acc, const double t[2], const double d[3])
{
    acc->any = 1;
    for (int e = 0; e < 2; e++) {
        double x = t[e] * d[0], z = t[e] * d[2], r = hypot(x, z);
        acc->rmin = fmin(acc->rmin, r);
        acc->rmax = fmax(acc->rmax, r);
        if (r <= acc->A) {
            acc->full = 1; /* the dilated footprint holds the ground point */
            continue;
        }
        double phi = atan2(z, x), pad = asin(acc->A / r);
        if (acc->na + 2 <= acc->cap) {
            acc->ang[acc->na++] = phi - pad;
            acc->ang[acc->na++] = phi + pad;
        }
    }
}

/* Bisects between screen points p (hit == hp) and q (the other state) and
 * adds the last hitting ray: the footprint's exact edge. */
static void fp_edge(const ray_ctx *rc, fp_acc *acc, double pu, double pv, double qu,
                    double qv, int hp)
{
    double hu = hp ? pu : qu, hv = hp ? pv : qv, mu = hp ? qu : pu, mv = hp ? qv : pv;
    double t[2], d[3];
    for (int i = 0; i < 48; i++) {
        double cu = 0.5 * (hu + mu), cv = 0.5 * (hv + mv);
        if (ray_slab(rc, cu, cv, t, d)) {
            hu = cu;
            hv = cv;
        } else {
            mu = cu;
            mv = cv;
        }
    }
    if (ray_slab(rc, hu, hv, t, d))
        fp_add(acc, t, d);
}

ocean_result mesh_build_projected(mesh *m, const mesh_camera *cam)
{
    const mesh_config *c = &m->cfg;
    const double A = c->margin_m, R = c->range_m;
    double fw[3], rt[3], up[3];
    mesh_camera_basis(cam, fw, rt, up);
    double ty = tan(0.5 * cam->fov_y_deg * M_PI / 180);
    double tx = ty * cam->viewport_w / cam->viewport_h;
    double hp = cam->pos[1] > A ? cam->pos[1] : A + fmax(1.0, 0.1 * A);

    /* footprint of frustum x slab x range, in polar coordinates around
     * the camera's ground point: sampled rays, plus the exact edge of the
     * footprint (found by bisection) wherever neighbouring rays disagree -
     * that is where the horizon crosses the screen, which a narrow field
     * of view would otherwise miss */
    ray_ctx rc = {{cam->pos[0], cam->pos[1], cam->pos[2]}, {fw[0], fw[1], fw[2]},
                  {rt[0], rt[1], rt[2]}, {up[0], up[1], up[2]}, tx, ty, A, R};
    const int nsamp = (NS + 1) * (NS + 1) + 4 * NS * (NS + 1);
    fp_acc acc = {malloc((size_t)nsamp * 4 * sizeof(double)), 0, 4 * nsamp, 0, 0,
                  INFINITY, 0, A};
    if (!acc.ang)
        return OCEAN_ENOMEM;
    unsigned char *hit = malloc((size_t)(NS + 1) * (NS + 1));
    if (!hit) {
        free(acc.ang);
        return OCEAN_ENOMEM;
    }
    for (int b = 0; b <= NS; b++)
        for (int a = 0; a <= NS; a++) {
            double u = -1 + 2.0 * a / NS, v = -1 + 2.0 * b / NS, t[2], d[3];
            hit[b * (NS + 1) + a] = (unsigned char)ray_slab(&rc, u, v, t, d);
            if (hit[b * (NS + 1) + a])
                fp_add(&acc, t, d);
        }
    for (int b = 0; b <= NS; b++)
        for (int a = 0; a <= NS; a++) {
            int h = hit[b * (NS + 1) + a];
            if (a > 0 && hit[b * (NS + 1) + a - 1] != h)
                fp_edge(&rc, &acc, -1 + 2.0 * (a - 1) / NS, -1 + 2.0 * b / NS,
                        -1 + 2.0 * a / NS, -1 + 2.0 * b / NS, hit[b * (NS + 1) + a - 1]);
            if (b > 0 && hit[(b - 1) * (NS + 1) + a] != h)
                fp_edge(&rc, &acc, -1 + 2.0 * a / NS, -1 + 2.0 * (b - 1) / NS,
                        -1 + 2.0 * a / NS, -1 + 2.0 * b / NS, hit[(b - 1) * (NS + 1) + a]);
        }
    free(hit);
    double *ang = acc.ang;
    int na = acc.na, full = acc.full, any = acc.any;
    double rmin = acc.rmin, rmax = acc.rmax;
    double phi0 = 0, phi1 = 2 * M_PI;
    if (!any) {
        full = 1; /* no sea in view: keep a valid mesh around the camera */
        rmin = 0;
        rmax = R;
    }
    if (!full && na > 0) {
        for (int i = 0; i < na; i++)
            ang[i] = remainder(ang[i], 2 * M_PI);
        qsort(ang, (size_t)na, sizeof *ang, cmp_double);
        /* the covered arc is the complement of the largest empty gap */
        double gap = ang[0] + 2 * M_PI - ang[na - 1];
        int gi = na - 1;
        for (int i = 0; i + 1 < na; i++)
            if (ang[i + 1] - ang[i] > gap) {
                gap = ang[i + 1] - ang[i];
                gi = i;
            }
        if (gap < 0.05) {
            full = 1;
        } else {
            phi0 = ang[(gi + 1) % na];
            phi1 = ang[gi];
            if (phi1 <= phi0)
                phi1 += 2 * M_PI;
            /* half a sampling step more on each side for the rays between */
            double padf = 0.5 * (phi1 - phi0) / NS;
            phi0 -= padf;
            phi1 += padf;
        }
    }
    free(ang);
    if (full) {
        rmin = 0;
        phi0 = 0;
        phi1 = 2 * M_PI;
    } else {
        rmin = fmax(0, rmin - A);
    }
    rmax = fmin(R, rmax + A);
    if (rmax <= rmin)
        rmax = fmin(R, rmin + fmax(1.0, A));
    double psi0 = atan(rmin / hp), psi1 = atan(rmax / hp);

    const int gw = c->grid_w, gh = c->grid_h;
    const int cols = gw;  /* full or not: a full ring's column gw wraps to column 0 */
    const uint32_t nv = full ? (uint32_t)(1 + (gh - 1) * cols) : (uint32_t)(gh * cols);
    const uint32_t nq = full ? (uint32_t)((gh - 2) * gw) : (uint32_t)((gh - 1) * (gw - 1));
    const uint32_t ni = full ? 3u * ((uint32_t)gw + 2 * nq) : 6 * nq;
    uint64_t key = mesh_hash(0, "projected", 9);
    key = mesh_hash(key, &gw, sizeof gw);
    key = mesh_hash(key, &gh, sizeof gh);
    key = mesh_hash(key, &full, sizeof full);

    float *base = malloc((size_t)nv * 3 * sizeof *base);
    uint32_t *idx = NULL;
    int reuse = m->built && m->key == key && m->nv == nv;
    if (!base)
        return OCEAN_ENOMEM;
    if (!reuse) {
        idx = malloc((size_t)ni * sizeof *idx);
        if (!idx) {
            free(base);
            return OCEAN_ENOMEM;
        }
    }
    uint32_t v = 0;
    int row0 = 0;
    if (full) {
        base[0] = base[1] = base[2] = 0;
        v = 1;
        row0 = 1;
    }
    for (int i = row0; i < gh; i++) {
        double psi = psi0 + (psi1 - psi0) * i / (gh - 1);
        double r = i == gh - 1 ? rmax : hp * tan(psi);
        for (int j = 0; j < cols; j++) {
            double phi = full ? phi0 + (phi1 - phi0) * j / gw : phi0 + (phi1 - phi0) * j / (gw - 1);
            base[3 * v] = (float)(r * cos(phi));
            base[3 * v + 1] = 0;
            base[3 * v + 2] = (float)(r * sin(phi));
            v++;
        }
    }
    if (!reuse) {
        uint32_t k = 0;
        if (full) {
            for (int j = 0; j < gw; j++) {
                idx[k++] = 0;
                idx[k++] = 1 + (uint32_t)((j + 1) % gw);
                idx[k++] = 1 + (uint32_t)j;
            }
            for (int i = 0; i < gh - 2; i++)
                for (int j = 0; j < gw; j++) {
                    uint32_t a = 1 + (uint32_t)(i * gw + j);
                    uint32_t b = 1 + (uint32_t)(i * gw + (j + 1) % gw);
                    uint32_t cc = b + (uint32_t)gw, d = a + (uint32_t)gw;
                    idx[k++] = a; idx[k++] = b; idx[k++] = cc;
                    idx[k++] = a; idx[k++] = cc; idx[k++] = d;
                }
        } else {
            for (int i = 0; i < gh - 1; i++)
                for (int j = 0; j < gw - 1; j++) {
                    uint32_t a = (uint32_t)(i * gw + j), b = a + 1;
                    uint32_t cc = b + (uint32_t)gw, d = a + (uint32_t)gw;
                    idx[k++] = a; idx[k++] = b; idx[k++] = cc;
                    idx[k++] = a; idx[k++] = cc; idx[k++] = d;
                }
        }
        ocean_result r = mesh_install(m, nv, ni, base, idx);
        if (r != OCEAN_OK) {
            free(base);
            free(idx);
            return r;
        }
        m->key = key;
    } else {
        free(m->base);
        m->base = base;
        memcpy(m->pos, base, (size_t)nv * 3 * sizeof *m->pos);
    }
    m->levels = 1;
    m->origin[0] = cam->pos[0];
    m->origin[1] = 0;
    m->origin[2] = cam->pos[2];
    double build_ms = m->info.build_ms;
    memset(&m->info, 0, sizeof m->info);
    m->info.build_ms = build_ms;
    m->info.rebuilt = !reuse;
    m->info.levels = 1;
    return OCEAN_OK;
}
