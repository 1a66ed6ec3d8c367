/*
 * tile_source.h - real ocean tiles for the codec tests and benchmark.
 *
 * Cuts a w x h window out of cascade 0 of an evaluated FFT ocean (sim/ocean.h)
 * and lays it out as a protocol tile: planes H, DX, DZ, NU, NV, FOAM, J
 * (normals octahedral from the slopes).  Header-only so that test_codec.c and
 * bench_codec.c share it without a library of their own.
 */
#ifndef TILE_SOURCE_H
#define TILE_SOURCE_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "codec.h"
#include "filter.h"
#include "ocean.h"
#include "ocean_conf.h"

typedef struct tile_source {
    ocean *o;
    ocean_frame *f;
    int n;
} tile_source;

/* Builds and evaluates an ocean at time t with wind u10 (m/s), resolution n
 * and patch size patch_m.  Returns 0 on success. */
static inline int tile_source_open(tile_source *s, double u10, int n, double patch_m, double t)
{
    ocean_params p;
    char msg[256];
    memset(s, 0, sizeof *s);
    ocean_params_default(&p);
    p.sea.wind_u10 = u10;
    p.n = n;
    p.patch_m = patch_m;
    p.threads = 1;
    if (ocean_create(&p, &s->o, msg, sizeof msg) != OCEAN_OK) {
        fprintf(stderr, "tile_source: ocean_create: %s\n", msg);
        return -1;
    }
    if (ocean_frame_create(s->o, &s->f) != OCEAN_OK)
        return -1;
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_ALL);
    if (ocean_evaluate(s->o, t, &r, s->f) != OCEAN_OK)
        return -1;
    s->n = ocean_frame_field(s->f, 0)->n;
    return 0;
}

static inline void tile_source_close(tile_source *s)
{
    ocean_frame_destroy(s->f);
    ocean_destroy(s->o);
    memset(s, 0, sizeof *s);
}

/* Fills planes (proto_tile_planes(PROTO_CH_WORLD) * w * h floats) with the
 * window whose first sample is grid (i0, j0); the grid is periodic. */
static inline void tile_source_cut(const tile_source *s, int i0, int j0, int w, int h, float *planes)
{
    const ocean_field *fd = ocean_frame_field(s->f, 0);
    int n = fd->n;
    size_t m = (size_t)w * h;
    for (int i = 0; i < h; i++)
        for (int j = 0; j < w; j++) {
            size_t g = (size_t)((i0 + i) % n) * n + (size_t)((j0 + j) % n), k = (size_t)i * w + j;
            planes[k] = fd->height[g];
            planes[m + k] = fd->dx[g];
            planes[2 * m + k] = fd->dz[g];
            proto_normal_oct_encode(-fd->slope_x[g], 1.0f, -fd->slope_z[g], &planes[3 * m + k], &planes[4 * m + k]);
            planes[5 * m + k] = fd->foam[g];
            planes[6 * m + k] = fd->jacobian[g];
        }
}

/* ---- layout-1 tiles, as the daemon sends them to the browser viewer ------ */

/* Every mip of every cascade of one scene at time t, evaluated as
 * server/srv_cascade.c's eval_mips does (one ocean_evaluate per mip level,
 * cascade c filtered at ocean_cascade_mips' cutoff kc[c][m] with the
 * filter's default Butterworth order, per_cascade = 1, foam map on). */
#define TILE_L1_MIPS 8
typedef struct tile_l1 {
    ocean *o;
    ocean_frame *f[TILE_L1_MIPS];
    int cascades, n, mips[OCEAN_MAX_CASCADES];
} tile_l1;

/* Loads conf_path (the daemon's file) and the scene file scene_path over
 * it, builds the ocean and evaluates every mip at time t with the effects
 * the browser viewer asks for (height, displacement, normals, foam).
 * Returns 0 on success. */
static inline int tile_l1_open(tile_l1 *s, const char *conf_path, const char *scene_path, double t)
{
    char msg[512];
    memset(s, 0, sizeof *s);
    ocean_params base;
    ocean_scene *sc = calloc(1, sizeof *sc);
    if (!sc)
        return -1;
    if (ocean_conf_load(conf_path, &base, msg, sizeof msg) != OCEAN_OK ||
        ocean_conf_scene_load(scene_path, &base, sc, msg, sizeof msg) != OCEAN_OK) {
        fprintf(stderr, "tile_l1: %s\n", msg);
        free(sc);
        return -1;
    }
    ocean_params p = sc->params;
    free(sc);
    p.threads = 1;
    if (ocean_create(&p, &s->o, msg, sizeof msg) != OCEAN_OK) {
        fprintf(stderr, "tile_l1: ocean_create: %s\n", msg);
        return -1;
    }
    ocean_filter_config fc;
    ocean_filter_config_default(&fc, &p.sea);
    s->cascades = ocean_get_params(s->o)->cascades;
    s->n = ocean_get_params(s->o)->n;
    double kc[OCEAN_MAX_CASCADES][TILE_L1_MIPS];
    for (int c = 0; c < s->cascades; c++)
        if (ocean_cascade_mips(s->o, c, fc.order, TILE_L1_MIPS, &s->mips[c], kc[c]) != OCEAN_OK)
            return -1;
    for (int m = 0; m < TILE_L1_MIPS; m++) {
        ocean_request rq;
        memset(&rq, 0, sizeof rq);
        int any = 0;
        for (int c = 0; c < s->cascades; c++)
            if (m < s->mips[c]) {
                rq.effects[c] = OCEAN_FX_ALL;
                rq.cascade_cutoff_k[c] = kc[c][m];
                any = 1;
            }
        if (!any)
            break;
        rq.cutoff_k = INFINITY;
        rq.order = fc.order;
        rq.low_boost = 1.0;
        rq.per_cascade = 1;
        if (ocean_frame_create(s->o, &s->f[m]) != OCEAN_OK || ocean_evaluate(s->o, t, &rq, s->f[m]) != OCEAN_OK)
            return -1;
    }
    return 0;
}

static inline void tile_l1_close(tile_l1 *s)
{
    for (int m = 0; m < TILE_L1_MIPS; m++)
        ocean_frame_destroy(s->f[m]);
    ocean_destroy(s->o);
    memset(s, 0, sizeof *s);
}

/* Tiles of side T per side of mip m (0 if cascade c has no mip m). */
static inline int tile_l1_count(const tile_l1 *s, int c, int m, int T)
{
    return m < s->mips[c] && s->f[m] ? (s->n >> m) / T : 0;
}

/* The viewer's channels for cascade c: H DX DZ NU NV BI BQ on every
 * cascade (server/srv_cascade.c chan_of). */
static inline unsigned tile_l1_channels(int c)
{
    (void)c;
    return PROTO_CH_HEIGHT | PROTO_CH_DX | PROTO_CH_DZ | PROTO_CH_NORMAL | PROTO_CH_BREAKING;
}

/* Fills planes with tile (ix, iz) of side T of mip m of cascade c, exactly
 * as srv_cascade.c's tile_build samples it (grid points of the mip, every
 * stride-th sample of the evaluated grid; normals octahedral from the
 * slopes), with tile_l1_channels(c).  Returns 0 on success. */
static inline int tile_l1_cut(const tile_l1 *s, int c, int m, int ix, int iz, int T, float *planes)
{
    const ocean_field *fd = ocean_frame_field(s->f[m], c);
    int np = s->n >> m;
    if (!fd || fd->n < np || fd->n % np || !fd->height || !fd->dx || !fd->slope_x || !fd->dxx || !fd->bq)
        return -1;
    int stride = fd->n / np;
    double lam = ocean_get_params(s->o)->sea.choppiness;
    float il = lam > 0 ? (float)(1.0 / lam) : 0.0f;
    size_t ns = (size_t)T * T;
    for (int i = 0; i < T; i++)
        for (int j = 0; j < T; j++) {
            size_t g = (size_t)((iz * T + i) * stride) * (size_t)fd->n + (size_t)((ix * T + j) * stride);
            size_t k = (size_t)i * T + j;
            planes[k] = fd->height[g];
            planes[ns + k] = fd->dx[g];
            planes[2 * ns + k] = fd->dz[g];
            proto_normal_oct_encode(-fd->slope_x[g], 1.0f, -fd->slope_z[g], &planes[3 * ns + k], &planes[4 * ns + k]);
            planes[5 * ns + k] = -(fd->dxx[g] + fd->dzz[g]) * il;   /* BI, BQ (foam.h) */
            planes[6 * ns + k] = -fd->bq[g] * il;
        }
    return 0;
}

#endif
