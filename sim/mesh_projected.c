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

/* Screen coordinate of sample a of NS + 1 along one side. */
static double fp_screen(int a)
{
    return -1 + 2.0 * a / NS;
}

/* Footprint of frustum x slab x range, in polar coordinates around the
 * camera's ground point: sampled rays, plus the exact edge of the
 * footprint (found by bisection) wherever neighbouring rays disagree -
 * that is where the horizon crosses the screen, which a narrow field of
 * view would otherwise miss. */
static ocean_result fp_trace(const ray_ctx *rc, fp_acc *acc)
{
    unsigned char *hit = malloc((size_t)(NS + 1) * (NS + 1));
    if (!hit)
        return OCEAN_ENOMEM;
    for (int b = 0; b <= NS; b++)
        for (int a = 0; a <= NS; a++) {
            double u = fp_screen(a), v = fp_screen(b), t[2], d[3];
            hit[b * (NS + 1) + a] = (unsigned char)ray_slab(rc, u, v, t, d);
            if (hit[b * (NS + 1) + a])
                fp_add(acc, t, d);
        }
    for (int b = 0; b <= NS; b++)
        for (int a = 0; a <= NS; a++) {
            int h = hit[b * (NS + 1) + a];
            if (a > 0 && hit[b * (NS + 1) + a - 1] != h)
                fp_edge(rc, acc, fp_screen(a - 1), fp_screen(b), fp_screen(a), fp_screen(b),
                        hit[b * (NS + 1) + a - 1]);
            if (b > 0 && hit[(b - 1) * (NS + 1) + a] != h)
                fp_edge(rc, acc, fp_screen(a), fp_screen(b - 1), fp_screen(a), fp_screen(b),
                        hit[(b - 1) * (NS + 1) + a]);
        }
    free(hit);
    return OCEAN_OK;
}

/* The ground the grid covers, in polar coordinates around the camera's
 * ground point. */
typedef struct proj_span {
    int full;  /* the whole disc: a ring of rows around a centre vertex */
    double rmin, rmax, phi0, phi1;
} proj_span;

/* The covered arc is the complement of the largest empty gap between the
 * footprint's angles; a gap too small to matter makes it the full circle. */
static void span_arc(double *ang, int na, proj_span *sp)
{
    for (int i = 0; i < na; i++)
        ang[i] = remainder(ang[i], 2 * M_PI);
    qsort(ang, (size_t)na, sizeof *ang, cmp_double);
    double gap = ang[0] + 2 * M_PI - ang[na - 1];
    int gi = na - 1;
    for (int i = 0; i + 1 < na; i++)
        if (ang[i + 1] - ang[i] > gap) {
            gap = ang[i + 1] - ang[i];
            gi = i;
        }
    if (gap < 0.05) {
        sp->full = 1;
        return;
    }
    sp->phi0 = ang[(gi + 1) % na];
    sp->phi1 = ang[gi];
    if (sp->phi1 <= sp->phi0)
        sp->phi1 += 2 * M_PI;
    /* half a sampling step more on each side for the rays between */
    double padf = 0.5 * (sp->phi1 - sp->phi0) / NS;
    sp->phi0 -= padf;
    sp->phi1 += padf;
}

/* The span of the traced footprint, dilated by the slab's margin A and
 * clipped to the range R. */
static void span_from_footprint(fp_acc *acc, double A, double R, proj_span *sp)
{
    sp->full = acc->full;
    sp->rmin = acc->rmin;
    sp->rmax = acc->rmax;
    sp->phi0 = 0;
    sp->phi1 = 2 * M_PI;
    if (!acc->any) {
        sp->full = 1; /* no sea in view: keep a valid mesh around the camera */
        sp->rmin = 0;
        sp->rmax = R;
    }
    if (!sp->full && acc->na > 0)
        span_arc(acc->ang, acc->na, sp);
    if (sp->full) {
        sp->rmin = 0;
        sp->phi0 = 0;
        sp->phi1 = 2 * M_PI;
    } else {
        sp->rmin = fmax(0, sp->rmin - A);
    }
    sp->rmax = fmin(R, sp->rmax + A);
    if (sp->rmax <= sp->rmin)
        sp->rmax = fmin(R, sp->rmin + fmax(1.0, A));
}

static ocean_result projected_span(const ray_ctx *rc, proj_span *sp)
{
    const int nsamp = (NS + 1) * (NS + 1) + 4 * NS * (NS + 1);
    fp_acc acc = {malloc((size_t)nsamp * 4 * sizeof(double)), 0, 4 * nsamp, 0, 0,
                  INFINITY, 0, rc->A};
    if (!acc.ang)
        return OCEAN_ENOMEM;
    if (fp_trace(rc, &acc) != OCEAN_OK) {
        free(acc.ang);
        return OCEAN_ENOMEM;
    }
    span_from_footprint(&acc, rc->A, rc->R, sp);
    free(acc.ang);
    return OCEAN_OK;
}

/* Rows uniform in the angle from the nadir seen from the projector at
 * height hp; a full ring's column gw would be column 0 again, so it has
 * none. */
static void projected_vertices(float *base, const proj_span *sp, int gw, int gh, double hp)
{
    double psi0 = atan(sp->rmin / hp), psi1 = atan(sp->rmax / hp);
    uint32_t v = 0;
    int row0 = 0;
    if (sp->full) {
        base[0] = base[1] = base[2] = 0;
        v = 1;
        row0 = 1;
    }
    for (int i = row0; i < gh; i++) {
        double psi = psi0 + (psi1 - psi0) * i / (gh - 1);
        double r = i == gh - 1 ? sp->rmax : hp * tan(psi);
        for (int j = 0; j < gw; j++) {
            double phi = sp->full ? sp->phi0 + (sp->phi1 - sp->phi0) * j / gw
                                  : sp->phi0 + (sp->phi1 - sp->phi0) * j / (gw - 1);
            base[3 * v] = (float)(r * cos(phi));
            base[3 * v + 1] = 0;
            base[3 * v + 2] = (float)(r * sin(phi));
            v++;
        }
    }
}

static void projected_indices(uint32_t *idx, int full, int gw, int gh)
{
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
}

/* The grid's vertices, and its triangles unless the mesh already holds
 * this topology (same key and vertex count): then only base changes. */
static ocean_result projected_store(mesh *m, const proj_span *sp, double hp, int *rebuilt)
{
    const int gw = m->cfg.grid_w, gh = m->cfg.grid_h, full = sp->full;
    const uint32_t nv = full ? (uint32_t)(1 + (gh - 1) * gw) : (uint32_t)(gh * gw);
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
    projected_vertices(base, sp, gw, gh, hp);
    if (reuse) {
        free(m->base);
        m->base = base;
        memcpy(m->pos, base, (size_t)nv * 3 * sizeof *m->pos);
        *rebuilt = 0;
        return OCEAN_OK;
    }
    projected_indices(idx, full, gw, gh);
    ocean_result r = mesh_install(m, nv, ni, base, idx);
    if (r != OCEAN_OK) {
        free(base);
        free(idx);
        return r;
    }
    m->key = key;
    *rebuilt = 1;
    return OCEAN_OK;
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
    ray_ctx rc = {{cam->pos[0], cam->pos[1], cam->pos[2]}, {fw[0], fw[1], fw[2]},
                  {rt[0], rt[1], rt[2]}, {up[0], up[1], up[2]}, tx, ty, A, R};
    proj_span sp;
    ocean_result r = projected_span(&rc, &sp);
    if (r != OCEAN_OK)
        return r;
    int rebuilt;
    r = projected_store(m, &sp, hp, &rebuilt);
    if (r != OCEAN_OK)
        return r;
    double build_ms = m->info.build_ms;
    memset(&m->info, 0, sizeof m->info);
    m->info.build_ms = build_ms;
    m->info.rebuilt = rebuilt;
    m->info.levels = 1;
    m->levels = 1;
    m->origin[0] = cam->pos[0];
    m->origin[1] = 0;
    m->origin[2] = cam->pos[2];
    return OCEAN_OK;
}
