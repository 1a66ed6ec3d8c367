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
#include "ocean.h"

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

/* Fills planes (proto_tile_planes(PROTO_CH_ALL) * w * h floats) with the
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

#endif
