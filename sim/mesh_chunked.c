/*
 * mesh_chunked.c - seed 004's chunked tile LOD (see mesh.h).
 *
 * Tiles snap to the tile size around the camera, so the tile grid and its
 * level pattern (chosen by distance from the grid's centre, then relaxed
 * until 4-neighbours differ by at most one level) are the same for every
 * camera position: the topology is fixed per configuration.  Edges between
 * levels are stitched by the shared triangulator (the coarse cell takes
 * the finer tile's edge vertices); a vertex near an edge shared with a
 * coarser tile gets a morph weight rising to 1 at that edge, so the finer
 * tile's border glides onto the coarse edge.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mesh.h"
#include "mesh_internal.h"

static void tile_levels(const mesh_config *c, int *lv)
{
    int n = c->chunk_tiles;
    double half = 0.5 * n;
    for (int b = 0; b < n; b++)
        for (int a = 0; a < n; a++) {
            /* distance in tiles from the grid centre to the tile */
            double dx = fmax(0, fmax(a - half, half - (a + 1)));
            double dz = fmax(0, fmax(b - half, half - (b + 1)));
            /* spread the levels over the grid's radius (in tiles) */
            double scale = (c->chunk_levels - 1) / fmax(1, half - 1);
            int L = (int)floor(hypot(dx, dz) * scale + 1e-9);
            lv[b * n + a] = L < c->chunk_levels - 1 ? L : c->chunk_levels - 1;
        }
    for (int changed = 1; changed;) {
        changed = 0;
        for (int b = 0; b < n; b++)
            for (int a = 0; a < n; a++) {
                int *l = &lv[b * n + a];
                static const int da[4] = {1, -1, 0, 0}, db[4] = {0, 0, 1, -1};
                for (int k = 0; k < 4; k++) {
                    int aa = a + da[k], bb = b + db[k];
                    if (aa < 0 || bb < 0 || aa >= n || bb >= n)
                        continue;
                    if (*l > lv[bb * n + aa] + 1) {
                        *l = lv[bb * n + aa] + 1;
                        changed = 1;
                    }
                }
            }
    }
}

ocean_result mesh_build_chunked(mesh *m, const mesh_camera *cam)
{
    const mesh_config *c = &m->cfg;
    int n = c->chunk_tiles, T = c->chunk_quads;
    double unit = c->chunk_tile_m / T;
    int *lv = malloc((size_t)n * n * sizeof *lv);
    if (!lv)
        return OCEAN_ENOMEM;
    tile_levels(c, lv);
    uint64_t key = mesh_hash(0, "chunked", 7);
    key = mesh_hash(key, &n, sizeof n);
    key = mesh_hash(key, &T, sizeof T);
    key = mesh_hash(key, &c->chunk_tile_m, sizeof c->chunk_tile_m);
    key = mesh_hash(key, lv, (size_t)n * n * sizeof *lv);
    int rebuilt = 0;
    if (!(m->built && m->key == key)) {
        mesh_bb bb;
        memset(&bb, 0, sizeof bb);
        ocean_result r = OCEAN_OK;
        for (int b = 0; b < n && r == OCEAN_OK; b++)
            for (int a = 0; a < n && r == OCEAN_OK; a++) {
                int L = lv[b * n + a], s = 1 << L;
                for (int j = 0; j < T && r == OCEAN_OK; j += s)
                    for (int i = 0; i < T && r == OCEAN_OK; i += s)
                        r = mesh_bb_add_leaf(&bb, a * T + i, b * T + j, s, L);
            }
        if (r == OCEAN_OK)
            r = mesh_bb_triangulate(&bb);
        if (r == OCEAN_OK)
            r = mesh_adopt(m, &bb, unit);
        mesh_bb_free(&bb);
        if (r != OCEAN_OK) {
            free(lv);
            return r;
        }
        m->key = key;
        int maxL = 0;
        for (int t = 0; t < n * n; t++)
            maxL = lv[t] > maxL ? lv[t] : maxL;
        m->levels = maxL + 1;
        for (int L = 0; L < MESH_MAX_LEVELS && L < 31; L++)
            m->lvl_units[L] = L < 8 ? 1 << L : 1 << 8;
        /* morph: rises to 1 toward edges shared with a coarser tile */
        double blend = c->blend_frac > 0 ? 2 * c->blend_frac * T : 0;
        for (uint32_t v = 0; v < m->nv; v++) {
            int i = m->lat[2 * v], j = m->lat[2 * v + 1];
            int L = m->level[v];
            float w = 0;
            for (int b = (j - 1) / T; b <= j / T; b++)
                for (int a = (i - 1) / T; a <= i / T; a++) {
                    if (a < 0 || b < 0 || a >= n || b >= n || i < a * T || j < b * T ||
                        i > (a + 1) * T || j > (b + 1) * T || lv[b * n + a] != L)
                        continue;
                    /* sides: -x, +x, -z, +z */
                    int na[4] = {a - 1, a + 1, a, a}, nb[4] = {b, b, b - 1, b + 1};
                    int dist[4] = {i - a * T, (a + 1) * T - i, j - b * T, (b + 1) * T - j};
                    for (int k = 0; k < 4; k++) {
                        if (na[k] < 0 || nb[k] < 0 || na[k] >= n || nb[k] >= n ||
                            lv[nb[k] * n + na[k]] <= L)
                            continue;
                        double wk = blend > 0 ? 1 - dist[k] / blend : (dist[k] == 0);
                        if (wk > w)
                            w = (float)wk;
                    }
                }
            m->morph[v] = w < 0 ? 0 : w;
        }
        rebuilt = 1;
    }
    free(lv);
    double tile = c->chunk_tile_m;
    m->origin[0] = round(cam->pos[0] / tile - 0.5 * n) * tile;
    m->origin[1] = 0;
    m->origin[2] = round(cam->pos[2] / tile - 0.5 * n) * tile;
    memcpy(m->pos, m->base, (size_t)m->nv * 3 * sizeof *m->pos);
    double build_ms = m->info.build_ms;
    memset(&m->info, 0, sizeof m->info);
    m->info.build_ms = build_ms;
    m->info.rebuilt = rebuilt;
    m->info.near_spacing_m = unit;
    m->info.levels = m->levels;
    for (int L = 0; L < m->levels; L++)
        m->info.level_spacing_m[L] = unit * (1 << L);
    return OCEAN_OK;
}
