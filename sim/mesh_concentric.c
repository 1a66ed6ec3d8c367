/*
 * mesh_concentric.c - seed 001's concentric LOD mesh (see mesh.h).
 *
 * The plan (near spacing, zone radii, levels) depends only on the camera's
 * height octave, field of view and viewport, so the topology is a function
 * of the plan alone and the mesh translates rigidly with the camera in
 * steps of the level-2 cell, 4 near spacings (the "snapping"): levels
 * 0-2 land on a world-fixed lattice, coarser rings slide by under half a
 * cell, and a client re-uses its index buffer until the plan changes.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mesh.h"
#include "mesh_internal.h"

typedef struct plan {
    double s0;                         /* level-0 spacing, m (power of two) */
    double rho;                        /* spacing budget: dx(D) = D / rho */
    int levels;
    int32_t units[MESH_MAX_LEVELS];    /* cell side per level, in s0 */
    double radius[MESH_MAX_LEVELS];    /* outer zone radius, m */
    double blend[MESH_MAX_LEVELS];
    double range;
    double slack;                      /* farthest the camera gets from the snapped
                                          origin, m: half a snapping cell's diagonal */
    int has_sky;                       /* 1: a far skirt from the range to sky */
    double sky;                        /* radius the skirt reaches, m */
} plan;

/* The level whose cells the origin moves by (4 s0).  A cell of level L
 * is split while within R_(L-1) + b_(L-1) + slack of the camera, and its
 * own morph starts at R_L - b_L, 0.2 R_L further out (blend 0.2): the
 * slack, half a snapping cell's diagonal (2.8 s0), stays below that gap
 * (0.2 R_1 = rho s0 >= 4 s0), so the fanned cells at a level's inner edge
 * never morph and their centres never move. */
#define SNAP_LEVEL 2

/* Earth's mean radius, m (IUGG). */
#define EARTH_R 6371008.8

static void make_plan(const mesh_config *cfg, const mesh_camera *cam, plan *p)
{
    memset(p, 0, sizeof *p);
    double f = mesh_camera_px_per_rad(cam);
    p->rho = cfg->roughness * f / cfg->error_px;
    if (p->rho < 4)
        p->rho = 4; /* below this the zones collapse into one another */
    double h = cam->pos[1] > 0 ? cam->pos[1] : 0;
    double want = h / p->rho;
    if (cfg->lambda_dominant_m > 0 && want > cfg->k_lambda * cfg->lambda_dominant_m)
        want = cfg->k_lambda * cfg->lambda_dominant_m;
    if (want < cfg->min_spacing_m)
        want = cfg->min_spacing_m;
    /* a power of two keeps the lattice still while the camera climbs
     * within an octave */
    p->s0 = ldexp(1.0, (int)floor(log2(want)));
    if (p->s0 < cfg->min_spacing_m)
        p->s0 *= 2;
    /* keep lattice coordinates well inside int32 */
    while (cfg->range_m / p->s0 > (double)(1 << 28))
        p->s0 *= 2;
    p->range = cfg->range_m;
    /* A camera near the water with a long range needs more levels than a
     * reader may take (a protocol's 16): each doubling of the near spacing
     * removes one, so the core coarsens, never the range. */
    int most = cfg->max_levels >= 1 && cfg->max_levels <= MESH_MAX_LEVELS ? cfg->max_levels : MESH_MAX_LEVELS;
    for (;;) {
        /* R_L - b_L = rho * s_(L+1): the morph toward the coarser level
         * starts exactly where the coarser spacing meets the error budget */
        double r0 = 2 * p->rho * p->s0 / (1 - cfg->blend_frac);
        int L = 0;
        for (;;) {
            /* every lattice twice the one inside it: the layout-1 morph
             * slides a vertex half a coarse cell onto a coarse vertex that
             * stays put, which no neighbour can overtake (with a four-fold
             * step, vertices a quarter and a half cell along moved by
             * different amounts and triangles turned over) */
            p->units[L] = L == 0 ? 1 : p->units[L - 1] * 2;
            p->radius[L] = L == 0 ? r0 : 2 * p->radius[L - 1];
            p->blend[L] = cfg->blend_frac * p->radius[L];
            /* the next level would start beyond the range: this is the last */
            if (p->radius[L] + p->blend[L] >= p->range || L == MESH_MAX_LEVELS - 1)
                break;
            L++;
        }
        p->levels = L + 1;
        if (p->levels <= most || p->s0 >= p->range)
            break;
        p->s0 *= 2;
    }
    int snapL = p->levels > SNAP_LEVEL ? SNAP_LEVEL : p->levels - 1;
    p->slack = 0.5 * M_SQRT2 * p->units[snapL] * p->s0;
    /* The far skirt: the sea's mean level from the mesh's edge out to the
     * horizon of a camera at the top of its height octave (so it changes
     * with the plan, not every frame), sqrt(2 R h + h^2), as a quadtree
     * of flat cells (add_sky) that the triangulator stitches to the mesh
     * like any coarser level. */
    double hoct = ldexp(1.0, (int)ceil(log2(h > 1 ? h : 1)));
    double sky = sqrt(2 * EARTH_R * hoct + hoct * hoct);
    if (sky > 1e6)
        sky = 1e6;
    if (!cfg->far_skirt)
        sky = 0;
    p->sky = sky;
    p->has_sky = sky > p->range;
    if (p->has_sky == 0)
        p->sky = p->range;
}

static uint64_t plan_key(const mesh_config *cfg, const plan *p)
{
    uint64_t h = mesh_hash(0, "concentric", 10);
    h = mesh_hash(h, &p->s0, sizeof p->s0);
    h = mesh_hash(h, &p->rho, sizeof p->rho);
    h = mesh_hash(h, &p->levels, sizeof p->levels);
    h = mesh_hash(h, &cfg->range_m, sizeof cfg->range_m);
    h = mesh_hash(h, &cfg->blend_frac, sizeof cfg->blend_frac);
    h = mesh_hash(h, &p->slack, sizeof p->slack);
    h = mesh_hash(h, &p->sky, sizeof p->sky);
    h = mesh_hash(h, &p->has_sky, sizeof p->has_sky);
    return h;
}

/* Horizontal distance from the origin to the cell, m. */
static double cell_dmin(int64_t x, int64_t z, int64_t s, double unit)
{
    double dx = x > 0 ? (double)x : (x + s < 0 ? (double)-(x + s) : 0);
    double dz = z > 0 ? (double)z : (z + s < 0 ? (double)-(z + s) : 0);
    return hypot(dx, dz) * unit;
}

/* A cell is split while any of it lies within R + blend of level L - 1 of
 * the camera.  Cells are placed around the snapped origin, which the
 * camera leaves by up to p->slack, so the test adds that: otherwise, with
 * zones not much wider than a snapping cell (a coarse budget clamps rho),
 * finer vertices on a coarser cell's edge sit inside the morph zone and
 * stop short of the coarse edge (morph weight 0 or 0.5 where it must be
 * 1), and the levels disagree along their border. */
static ocean_result add_cell(mesh_bb *bb, const plan *p, int32_t x, int32_t z, int L)
{
    if (L > 0 && cell_dmin(x, z, p->units[L], p->s0) < p->radius[L - 1] + p->blend[L - 1] + p->slack) {
        int32_t c = p->units[L - 1], n = p->units[L] / c;
        for (int32_t j = 0; j < n; j++)
            for (int32_t i = 0; i < n; i++) {
                ocean_result r = add_cell(bb, p, x + i * c, z + j * c, L - 1);
                if (r != OCEAN_OK)
                    return r;
            }
        return OCEAN_OK;
    }
    return mesh_bb_add_leaf(bb, x, z, p->units[L], L);
}

/* The far skirt as a quadtree: a cell wholly beyond the range is one flat
 * skirt leaf (level levels, relabelled later), one beyond the horizon is
 * dropped, one across the range is halved down to the last level's cell,
 * which goes to add_cell as the mesh's own.  Cells so double in size with
 * every step away from the range: a few cells per doubling of distance
 * around the whole circle, whatever the horizon. */
static ocean_result add_sky(mesh_bb *bb, const plan *p, int32_t x, int32_t z, int32_t size)
{
    double d = cell_dmin(x, z, size, p->s0);
    if (d > p->sky)
        return OCEAN_OK;
    if (d > p->range)
        return mesh_bb_add_leaf(bb, x, z, size, p->levels);
    int Ltop = p->levels - 1;
    if (size <= p->units[Ltop])
        return add_cell(bb, p, x, z, Ltop);
    int32_t h = size / 2;
    ocean_result r = OCEAN_OK;
    for (int k = 0; k < 4 && r == OCEAN_OK; k++)
        r = add_sky(bb, p, x + (k & 1) * h, z + (k >> 1) * h, h);
    return r;
}

static void fill_info(mesh *m, const plan *p)
{
    mesh_info *in = &m->info;
    double build_ms = in->build_ms;
    memset(in, 0, sizeof *in);
    in->build_ms = build_ms;
    in->near_spacing_m = p->s0;
    in->rho_err = p->rho;
    in->levels = p->levels;
    for (int L = 0; L < p->levels; L++) {
        in->level_spacing_m[L] = p->units[L] * p->s0;
        in->zone_radius_m[L] = p->radius[L];
        in->blend_m[L] = p->blend[L];
    }
    /* seed 000: rho(d) = rho_max e^(-alpha d) + rho_min through the
     * tessellation factors 8 / 4 / 1 (x b = 1 / (8 s0)) at d = 0, R0, 4 R0:
     * rho_min = 0.7 b solves rho(4 R0) = b (see mesh.h) */
    double b = 1 / (8 * p->s0), m0 = 0.7;
    in->rho_min = m0 * b;
    in->rho_max = (8 - m0) * b;
    in->alpha = log((8 - m0) / (4 - m0)) / p->radius[0];
}

static void update_morph(mesh *m, const plan *p, const mesh_camera *cam)
{
    uint32_t real = m->nv - m->skirt_count;
    for (uint32_t v = real; v < m->nv; v++)
        m->morph[v] = 1.0f;
    for (uint32_t v = 0; v < real; v++) {
        int L = m->level[v];
        float w = 0;
        if (L + 1 < p->levels && p->blend[L] > 0) {
            double x = m->origin[0] + m->base[3 * v] - cam->pos[0];
            double z = m->origin[2] + m->base[3 * v + 2] - cam->pos[2];
            double d = sqrt(x * x + z * z); /* per vertex per frame: no hypot call */
            w = (float)mesh_smoothstep((d - (p->radius[L] - p->blend[L])) / (2 * p->blend[L]));
        } else if (L + 1 < p->levels) {
            double x = m->origin[0] + m->base[3 * v] - cam->pos[0];
            double z = m->origin[2] + m->base[3 * v + 2] - cam->pos[2];
            w = x * x + z * z >= p->radius[L] * p->radius[L] ? 1.0f : 0.0f;
        }
        m->morph[v] = w;
    }
}

/* Vertices the plan's build will make, from zone areas: level L covers the
 * annulus between the previous zone's outer edge and its own, clipped to the
 * range, at one vertex per (units[L] s0)^2; a zone reaches R + b plus the
 * snapping slack (add_cell splits every cell that comes that near).  Cells
 * are square and whole, so the built count runs above this by the cells
 * the circles cut (up to a third of a small mesh; measured 0.81..1.49 x
 * the area count over heights 2..300 m, fov 20..175 degrees, ranges
 * 200..2000 m in tests/test_mesh.c); the factor 1.6 covers it and the
 * seams' extra vertices, so the estimate errs high. */
double mesh_estimate_concentric(const mesh_config *cfg, const mesh_camera *cam)
{
    plan p;
    make_plan(cfg, cam, &p);
    double n = 0, inner = 0;
    for (int L = 0; L < p.levels; L++) {
        double outer = L == p.levels - 1 ? p.range : fmin(p.range, p.radius[L] + p.blend[L] + p.slack);
        if (outer > inner) {
            double s = p.units[L] * p.s0;
            n += M_PI * (outer * outer - inner * inner) / (s * s);
        }
        inner = fmax(inner, outer);
    }
    /* the far skirt: cells that double away from the range, about a ring of
     * the last level's cells per octave out to the horizon */
    if (p.has_sky) {
        double s = p.units[p.levels - 1] * p.s0;
        n += 2.0 * M_PI * p.range / s * fmax(1.0, log2(p.sky / p.range));
    }
    return 1.6 * n + 64;
}

/* Moves the vertices only skirt cells touch (level > Ltop) to the end,
 * relabelled Ltop (the skirt is no LOD level of its own); *nsky gets
 * their count. */
static ocean_result skirt_last(mesh_bb *bb, int Ltop, uint32_t *nsky)
{
    uint32_t nv = bb->nv, *map = malloc((nv ? nv : 1) * sizeof *map);
    int32_t *lat = malloc((size_t)(nv ? nv : 1) * 2 * sizeof *lat);
    uint8_t *lvl = malloc(nv ? nv : 1);
    if (!map || !lat || !lvl) {
        free(map);
        free(lat);
        free(lvl);
        return OCEAN_ENOMEM;
    }
    uint32_t k = 0, n = 0;
    for (int pass = 0; pass < 2; pass++)
        for (uint32_t v = 0; v < nv; v++) {
            int sky = bb->lvl[v] > Ltop;
            if (sky != pass)
                continue;
            map[v] = k;
            lat[2 * k] = bb->lat[2 * v];
            lat[2 * k + 1] = bb->lat[2 * v + 1];
            lvl[k] = sky ? (uint8_t)Ltop : bb->lvl[v];
            n += sky;
            k++;
        }
    for (size_t i = 0; i < bb->ni; i++)
        bb->idx[i] = map[bb->idx[i]];
    memcpy(bb->lat, lat, (size_t)nv * 2 * sizeof *lat);
    memcpy(bb->lvl, lvl, nv);
    free(map);
    free(lat);
    free(lvl);
    *nsky = n;
    return OCEAN_OK;
}

ocean_result mesh_build_concentric(mesh *m, const mesh_camera *cam)
{
    plan p;
    make_plan(&m->cfg, cam, &p);
    uint64_t key = plan_key(&m->cfg, &p);
    /* snap: the origin moves in whole level-2 cells (all finer lattices
     * nest in it); sub-cell camera moves change nothing but morph weights */
    int snapL = p.levels > SNAP_LEVEL ? SNAP_LEVEL : p.levels - 1;
    double g = p.units[snapL] * p.s0;
    double ox = round(cam->pos[0] / g) * g, oz = round(cam->pos[2] / g) * g;
    int rebuilt = 0;
    if (!(m->built && m->key == key)) {
        int Ltop = p.levels - 1;
        int64_t S = p.units[Ltop];
        int64_t K = (int64_t)ceil(p.range / (S * p.s0));
        mesh_bb bb;
        memset(&bb, 0, sizeof bb);
        ocean_result r = OCEAN_OK;
        if (p.has_sky) {
            /* four quadtree roots around the origin reaching the horizon */
            int64_t U = S;
            while ((double)U * p.s0 < p.sky && U < ((int64_t)1 << 29))
                U *= 2;
            for (int k = 0; k < 4 && r == OCEAN_OK; k++)
                r = add_sky(&bb, &p, (int32_t)((k & 1) ? 0 : -U), (int32_t)((k >> 1) ? 0 : -U),
                            (int32_t)U);
        } else {
            for (int64_t j = -K; j < K && r == OCEAN_OK; j++)
                for (int64_t i = -K; i < K && r == OCEAN_OK; i++) {
                    if (cell_dmin(i * S, j * S, S, p.s0) > p.range)
                        continue;
                    r = add_cell(&bb, &p, (int32_t)(i * S), (int32_t)(j * S), Ltop);
                }
        }
        if (r == OCEAN_OK)
            r = mesh_bb_triangulate(&bb);
        uint32_t nsky = 0;
        if (r == OCEAN_OK && p.has_sky)
            r = skirt_last(&bb, Ltop, &nsky);
        if (r == OCEAN_OK)
            r = mesh_adopt(m, &bb, p.s0);
        mesh_bb_free(&bb);
        if (r != OCEAN_OK)
            return r;
        m->skirt_count = nsky;
        m->key = key;
        m->levels = p.levels;
        for (int L = 0; L < p.levels; L++)
            m->lvl_units[L] = p.units[L];
        rebuilt = 1;
    }
    m->origin[0] = ox;
    m->origin[1] = 0;
    m->origin[2] = oz;
    fill_info(m, &p);
    m->info.rebuilt = rebuilt;
    if (m->place_only)
        return OCEAN_OK; /* the client morphs and displaces (mesh_place) */
    memcpy(m->pos, m->base, (size_t)m->nv * 3 * sizeof *m->pos);
    update_morph(m, &p, cam);
    return OCEAN_OK;
}
