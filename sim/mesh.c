/*
 * mesh.c - what every kind of mesh shares: the mesh object, the
 * triangulator, displacement, the error measure and OBJ output.  The kinds
 * themselves live in mesh_concentric.c, mesh_chunked.c and
 * mesh_projected.c.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "mesh.h"
#include "mesh_internal.h"

static const char *const kind_names[MESH_KIND_COUNT_] = {"concentric", "chunked", "projected"};

const char *mesh_kind_name(mesh_kind k)
{
    return (unsigned)k < MESH_KIND_COUNT_ ? kind_names[k] : "unknown";
}

ocean_result mesh_kind_parse(const char *name, mesh_kind *out)
{
    if (!name || !out)
        return OCEAN_EINVAL;
    for (int k = 0; k < MESH_KIND_COUNT_; k++)
        if (strcmp(name, kind_names[k]) == 0) {
            *out = (mesh_kind)k;
            return OCEAN_OK;
        }
    return OCEAN_EINVAL;
}

double mesh_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

double mesh_smoothstep(double t)
{
    if (!(t > 0))
        return 0;
    if (t >= 1)
        return 1;
    return t * t * (3 - 2 * t);
}

/* FNV-1a, 64 bit. */
uint64_t mesh_hash(uint64_t h, const void *p, size_t n)
{
    const unsigned char *b = p;
    if (!h)
        h = 0xcbf29ce484222325ull;
    for (size_t i = 0; i < n; i++) {
        h ^= b[i];
        h *= 0x100000001b3ull;
    }
    return h;
}

/* ---- camera ---------------------------------------------------------- */

void mesh_camera_default(mesh_camera *c)
{
    memset(c, 0, sizeof *c);
    c->pos[1] = 20;
    c->fov_y_deg = 60;
    c->viewport_w = 1920;
    c->viewport_h = 1080;
}

#define FAIL(...) do { if (msg && msglen) snprintf(msg, msglen, __VA_ARGS__); return OCEAN_EINVAL; } while (0)

ocean_result mesh_camera_validate(const mesh_camera *c, char *msg, size_t msglen)
{
    if (!c)
        FAIL("camera: NULL");
    for (int i = 0; i < 3; i++) {
        double lim = i == 1 ? 1e7 : 1e10;
        if (!isfinite(c->pos[i]) || fabs(c->pos[i]) > lim)
            FAIL("camera position[%d]: %g is not finite or beyond %g m", i, c->pos[i], lim);
    }
    if (!isfinite(c->yaw_deg) || fabs(c->yaw_deg) > 1e6)
        FAIL("camera yaw: %g is not a finite angle", c->yaw_deg);
    if (!isfinite(c->pitch_deg) || fabs(c->pitch_deg) > 90)
        FAIL("camera pitch: %g outside [-90, 90] degrees", c->pitch_deg);
    if (!isfinite(c->roll_deg) || fabs(c->roll_deg) > 1e6)
        FAIL("camera roll: %g is not a finite angle", c->roll_deg);
    /* the protocol's range (PROTOCOL.md, CAMERA): what it allows, the mesh
     * code must take; a narrow fov makes a fine mesh, which
     * mesh_estimate_vertices prices before anything is built */
    if (!isfinite(c->fov_y_deg) || !(c->fov_y_deg > 0) || !(c->fov_y_deg < 180))
        FAIL("camera fov: %g outside (0, 180) degrees", c->fov_y_deg);
    if (c->viewport_w < 1 || c->viewport_w > 65536 || c->viewport_h < 1 || c->viewport_h > 65536)
        FAIL("camera viewport: %dx%d outside 1..65536", c->viewport_w, c->viewport_h);
    return OCEAN_OK;
}

double mesh_camera_px_per_rad(const mesh_camera *c)
{
    return 0.5 * c->viewport_h / tan(0.5 * c->fov_y_deg * M_PI / 180);
}

void mesh_camera_basis(const mesh_camera *c, double f[3], double r[3], double u[3])
{
    double y = c->yaw_deg * M_PI / 180, p = c->pitch_deg * M_PI / 180;
    double ro = c->roll_deg * M_PI / 180;
    f[0] = cos(p) * cos(y);
    f[1] = sin(p);
    f[2] = cos(p) * sin(y);
    /* right = forward x world up (level camera looking along +x: right = +z) */
    double r0[3] = {-f[2], 0, f[0]};
    double rn = hypot(r0[0], r0[2]);
    if (rn < 1e-12) { /* looking straight up or down: right follows yaw */
        r0[0] = -sin(y);
        r0[2] = cos(y);
        rn = 1;
    }
    r0[0] /= rn;
    r0[2] /= rn;
    /* up = right x forward */
    double u0[3] = {r0[1] * f[2] - r0[2] * f[1], r0[2] * f[0] - r0[0] * f[2],
                    r0[0] * f[1] - r0[1] * f[0]};
    double cr = cos(ro), sr = sin(ro);
    for (int i = 0; i < 3; i++) {
        r[i] = cr * r0[i] - sr * u0[i];
        u[i] = sr * r0[i] + cr * u0[i];
    }
}

/* ---- config ---------------------------------------------------------- */

void mesh_config_default(mesh_config *c)
{
    memset(c, 0, sizeof *c);
    c->kind = MESH_CONCENTRIC;
    c->range_m = 90000;
    c->error_px = 1;
    c->roughness = MESH_ROUGHNESS;
    c->lambda_dominant_m = 0;
    c->k_lambda = 0.1;
    c->min_spacing_m = 0.02;
    c->blend_frac = 0.2;
    c->max_levels = MESH_MAX_LEVELS;
    c->far_skirt = 1;
    c->chunk_tiles = 6;
    c->chunk_tile_m = 128;
    c->chunk_quads = 32;
    c->chunk_levels = 4;
    c->grid_w = 256;
    c->grid_h = 256;
    c->margin_m = 6;
}

static int is_pow2(int v) { return v > 0 && (v & (v - 1)) == 0; }

ocean_result mesh_config_validate(const mesh_config *c, char *msg, size_t msglen)
{
    if (!c)
        FAIL("mesh config: NULL");
    if ((unsigned)c->kind >= MESH_KIND_COUNT_)
        FAIL("mesh kind: %d unknown", (int)c->kind);
    if (!isfinite(c->range_m) || c->range_m < 10 || c->range_m > 1e6)
        FAIL("mesh range: %g outside [10, 1e6] m", c->range_m);
    if (!isfinite(c->error_px) || c->error_px < 0.01 || c->error_px > 100)
        FAIL("mesh error_px: %g outside [0.01, 100]", c->error_px);
    if (!isfinite(c->roughness) || c->roughness < 1e-4 || c->roughness > 1)
        FAIL("mesh roughness: %g outside [1e-4, 1]", c->roughness);
    if (!isfinite(c->lambda_dominant_m) || c->lambda_dominant_m < 0 || c->lambda_dominant_m > 1e5)
        FAIL("mesh lambda_dominant: %g outside [0, 1e5] m", c->lambda_dominant_m);
    if (!isfinite(c->k_lambda) || c->k_lambda < 0.1 || c->k_lambda > 0.5)
        FAIL("mesh k_lambda: %g outside [0.1, 0.5]", c->k_lambda);
    if (!isfinite(c->min_spacing_m) || c->min_spacing_m < 0.005 || c->min_spacing_m > 1000)
        FAIL("mesh min_spacing: %g outside [0.005, 1000] m", c->min_spacing_m);
    if (!isfinite(c->blend_frac) || c->blend_frac < 0 || c->blend_frac > 0.45)
        FAIL("mesh blend_frac: %g outside [0, 0.45]", c->blend_frac);
    /* concentric zones double: level L's morph starts (1 - b) R_L out, the
     * level inside it ends (1 + b) R_L / 2 plus the snapping slack, and past
     * 0.24 the two meet at the coarsest budget (the layout-1 morph then moves
     * the centres of fanned cells, mesh_concentric.c SNAP_LEVEL); below 0.15
     * the morph weight changes by most of its range across one cell and
     * neighbours slide far enough apart to turn triangles over (0.1 did at
     * 25 m: tests/test_mesh.c test_layout1_morph_keeps_orientation) */
    if (c->kind == MESH_CONCENTRIC &&
        (c->blend_frac < MESH_CONCENTRIC_BLEND_MIN || c->blend_frac > MESH_CONCENTRIC_BLEND_MAX))
        FAIL("mesh blend_frac: %g outside [%g, %g] for a concentric mesh", c->blend_frac, MESH_CONCENTRIC_BLEND_MIN,
             MESH_CONCENTRIC_BLEND_MAX);
    if (c->max_levels < 1 || c->max_levels > MESH_MAX_LEVELS)
        FAIL("mesh max_levels: %d outside 1..%d", c->max_levels, MESH_MAX_LEVELS);
    if (c->far_skirt != 0 && c->far_skirt != 1)
        FAIL("mesh far_skirt: %d is neither 0 nor 1", c->far_skirt);
    if (c->chunk_tiles < 1 || c->chunk_tiles > 64)
        FAIL("mesh chunk_tiles: %d outside 1..64", c->chunk_tiles);
    if (!isfinite(c->chunk_tile_m) || c->chunk_tile_m < 1 || c->chunk_tile_m > 1e5)
        FAIL("mesh chunk_tile: %g outside [1, 1e5] m", c->chunk_tile_m);
    if (!is_pow2(c->chunk_quads) || c->chunk_quads < 2 || c->chunk_quads > 256)
        FAIL("mesh chunk_quads: %d is not a power of two in 2..256", c->chunk_quads);
    if (c->chunk_levels < 1 || c->chunk_levels > 4 || (c->chunk_quads >> (c->chunk_levels - 1)) < 1)
        FAIL("mesh chunk_levels: %d outside 1..4 or finer than chunk_quads allows", c->chunk_levels);
    if (c->grid_w < 2 || c->grid_w > 4096 || c->grid_h < 2 || c->grid_h > 4096)
        FAIL("mesh grid: %dx%d outside 2..4096", c->grid_w, c->grid_h);
    if (!isfinite(c->margin_m) || c->margin_m < 0 || c->margin_m > 1000)
        FAIL("mesh margin: %g outside [0, 1000] m", c->margin_m);
    return OCEAN_OK;
}

ocean_result mesh_lambda_dominant(const ocean_sea_state *sea, double *out)
{
    if (!sea || !out || ocean_sea_state_validate(sea, NULL, 0) != OCEAN_OK)
        return OCEAN_EINVAL;
    double wp = ocean_spectrum_peak(sea);
    *out = 0;
    if (!(wp > 0) || !isfinite(wp))
        return OCEAN_OK;
    double kp = ocean_wavenumber(wp, sea->depth_m);
    if (kp > 0 && isfinite(kp))
        *out = 2 * M_PI / kp;
    return OCEAN_OK;
}

double mesh_roughness(const ocean_sea_state *sea)
{
    double lam = sea ? sea->choppiness : NAN;
    if (!isfinite(lam) || lam <= MESH_CHOP_VERTICAL)
        return MESH_ROUGHNESS;
    double r = MESH_ROUGHNESS * lam / MESH_CHOP_VERTICAL;
    return r < 1 ? r : 1;
}

/* ---- object ---------------------------------------------------------- */

ocean_result mesh_create(const mesh_config *cfg, mesh **out)
{
    if (!out)
        return OCEAN_EINVAL;
    *out = NULL;
    if (mesh_config_validate(cfg, NULL, 0) != OCEAN_OK)
        return OCEAN_EINVAL;
    mesh *m = calloc(1, sizeof *m);
    if (!m)
        return OCEAN_ENOMEM;
    m->cfg = *cfg;
    *out = m;
    return OCEAN_OK;
}

static void free_arrays(mesh *m)
{
    free(m->base);
    free(m->pos);
    free(m->morph);
    free(m->level);
    free(m->lat);
    free(m->idx);
    free(m->corner);
    m->base = m->pos = m->morph = NULL;
    m->level = NULL;
    m->lat = NULL;
    m->idx = NULL;
    m->corner = NULL;
    m->corner_ok = 0;
}

void mesh_destroy(mesh *m)
{
    if (!m)
        return;
    free_arrays(m);
    free(m->raw);
    free(m);
}

ocean_result mesh_estimate_vertices(const mesh_config *cfg, const mesh_camera *cam, double *out)
{
    if (!cfg || !out || mesh_config_validate(cfg, NULL, 0) != OCEAN_OK ||
        mesh_camera_validate(cam, NULL, 0) != OCEAN_OK)
        return OCEAN_EINVAL;
    switch (cfg->kind) {
    case MESH_CONCENTRIC: *out = mesh_estimate_concentric(cfg, cam); break;
    case MESH_CHUNKED: {
        double q = cfg->chunk_quads + 1.0;
        *out = (double)cfg->chunk_tiles * cfg->chunk_tiles * q * q;
        break;
    }
    case MESH_PROJECTED: *out = (double)cfg->grid_w * cfg->grid_h; break;
    default: return OCEAN_EINVAL;
    }
    return OCEAN_OK;
}

ocean_result mesh_build(mesh *m, const mesh_camera *cam)
{
    if (!m || mesh_camera_validate(cam, NULL, 0) != OCEAN_OK)
        return OCEAN_EINVAL;
    double t0 = mesh_now_ms();
    ocean_result r;
    switch (m->cfg.kind) {
    case MESH_CONCENTRIC: r = mesh_build_concentric(m, cam); break;
    case MESH_CHUNKED: r = mesh_build_chunked(m, cam); break;
    case MESH_PROJECTED: r = mesh_build_projected(m, cam); break;
    default: r = OCEAN_EINVAL;
    }
    if (r == OCEAN_OK) {
        m->built = 1;
        m->info.build_ms = mesh_now_ms() - t0;
    }
    return r;
}

ocean_result mesh_place(mesh *m, const mesh_camera *cam)
{
    if (!m || m->cfg.kind != MESH_CONCENTRIC)
        return mesh_build(m, cam);
    m->place_only = 1;
    ocean_result r = mesh_build(m, cam);
    m->place_only = 0;
    return r;
}

void mesh_get_view(const mesh *m, mesh_view *v)
{
    memset(v, 0, sizeof *v);
    v->kind = m->cfg.kind;
    if (!m->built)
        return;
    memcpy(v->origin, m->origin, sizeof v->origin);
    v->vertex_count = m->nv;
    v->index_count = m->ni;
    v->base = m->base;
    v->positions = m->pos;
    v->indices = m->idx;
    v->level = m->level;
    v->morph = m->morph;
    v->topology_key = m->key;
    v->levels = m->levels;
}

void mesh_get_info(const mesh *m, mesh_info *out)
{
    *out = m->info;
}

double mesh_density_target(const mesh *m, double d)
{
    const mesh_info *in = &m->info;
    if (m->cfg.kind != MESH_CONCENTRIC || !m->built || !(d >= 0))
        return 0;
    double r1 = in->levels > 1 ? in->zone_radius_m[1] : INFINITY;
    if (d < r1)
        return in->rho_max * exp(-in->alpha * d) + in->rho_min;
    return in->rho_err / d;
}

/* ---- shared triangulator --------------------------------------------- */

void mesh_bb_free(mesh_bb *bb)
{
    free(bb->leaves);
    free(bb->lat);
    free(bb->lvl);
    free(bb->idx);
    free(bb->hkeys);
    free(bb->hvals);
    memset(bb, 0, sizeof *bb);
}

static int grow(void **p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap)
        return 1;
    size_t nc = *cap ? *cap : 1024;
    while (nc < need)
        nc *= 2;
    void *q = realloc(*p, nc * elem);
    if (!q)
        return 0;
    *p = q;
    *cap = nc;
    return 1;
}

ocean_result mesh_bb_add_leaf(mesh_bb *bb, int32_t x, int32_t z, int32_t size, int level)
{
    if (!grow((void **)&bb->leaves, &bb->cap_l, bb->nl + 1, sizeof *bb->leaves))
        return OCEAN_ENOMEM;
    bb->leaves[bb->nl++] = (mesh_leaf){x, z, size, (uint8_t)level};
    return OCEAN_OK;
}

static uint64_t lat_key(int32_t x, int32_t z)
{
    return ((uint64_t)(uint32_t)x << 32) | (uint32_t)z;
}

static size_t slot_of(uint64_t k, size_t cap)
{
    k ^= k >> 33;
    k *= 0xff51afd7ed558ccdull;
    k ^= k >> 33;
    k *= 0xc4ceb9fe1a85ec53ull;
    k ^= k >> 33;
    return (size_t)k & (cap - 1);
}

#define NO_VERTEX UINT32_MAX

static uint32_t map_find(const mesh_bb *bb, int32_t x, int32_t z)
{
    uint64_t k = lat_key(x, z);
    for (size_t s = slot_of(k, bb->hcap);; s = (s + 1) & (bb->hcap - 1)) {
        if (bb->hvals[s] == NO_VERTEX)
            return NO_VERTEX;
        if (bb->hkeys[s] == k)
            return bb->hvals[s];
    }
}

static int map_rehash(mesh_bb *bb, size_t ncap)
{
    uint64_t *nk = malloc(ncap * sizeof *nk);
    uint32_t *nv = malloc(ncap * sizeof *nv);
    if (!nk || !nv) {
        free(nk);
        free(nv);
        return 0;
    }
    for (size_t i = 0; i < ncap; i++)
        nv[i] = NO_VERTEX;
    for (size_t i = 0; i < bb->hcap; i++) {
        if (bb->hvals[i] == NO_VERTEX)
            continue;
        size_t s = slot_of(bb->hkeys[i], ncap);
        while (nv[s] != NO_VERTEX)
            s = (s + 1) & (ncap - 1);
        nk[s] = bb->hkeys[i];
        nv[s] = bb->hvals[i];
    }
    free(bb->hkeys);
    free(bb->hvals);
    bb->hkeys = nk;
    bb->hvals = nv;
    bb->hcap = ncap;
    return 1;
}

/* Index of the vertex at (x, z), created with the given level if new; an
 * existing vertex keeps the finest level that touches it. */
static ocean_result map_get(mesh_bb *bb, int32_t x, int32_t z, int level, uint32_t *out)
{
    if ((bb->hcount + 1) * 2 > bb->hcap && !map_rehash(bb, bb->hcap * 2))
        return OCEAN_ENOMEM;
    uint64_t k = lat_key(x, z);
    size_t s = slot_of(k, bb->hcap);
    while (bb->hvals[s] != NO_VERTEX) {
        if (bb->hkeys[s] == k) {
            uint32_t v = bb->hvals[s];
            if (level < bb->lvl[v])
                bb->lvl[v] = (uint8_t)level;
            *out = v;
            return OCEAN_OK;
        }
        s = (s + 1) & (bb->hcap - 1);
    }
    if (bb->nv >= (uint32_t)INT32_MAX)
        return OCEAN_ETOOBIG;
    size_t cap = bb->cap_v, cap2 = bb->cap_v;
    if (!grow((void **)&bb->lat, &cap, 2 * ((size_t)bb->nv + 1), sizeof *bb->lat))
        return OCEAN_ENOMEM;
    if (!grow((void **)&bb->lvl, &cap2, 2 * ((size_t)bb->nv + 1), sizeof *bb->lvl))
        return OCEAN_ENOMEM;
    bb->cap_v = (uint32_t)(cap < cap2 ? cap : cap2);
    uint32_t v = bb->nv++;
    bb->lat[2 * v] = x;
    bb->lat[2 * v + 1] = z;
    bb->lvl[v] = (uint8_t)level;
    bb->hkeys[s] = k;
    bb->hvals[s] = v;
    bb->hcount++;
    *out = v;
    return OCEAN_OK;
}

static ocean_result add_tri(mesh_bb *bb, uint32_t a, uint32_t b, uint32_t c)
{
    if (bb->ni + 3 > (size_t)INT32_MAX)
        return OCEAN_ETOOBIG;
    if (!grow((void **)&bb->idx, &bb->cap_i, bb->ni + 3, sizeof *bb->idx))
        return OCEAN_ENOMEM;
    bb->idx[bb->ni++] = a;
    bb->idx[bb->ni++] = b;
    bb->idx[bb->ni++] = c;
    return OCEAN_OK;
}

/* Appends the vertices strictly inside the edge (ax,az)-(bx,bz) of length
 * len, in order from a to b.  In a lattice of power-of-two aligned cells a
 * finer neighbour always has a corner at the edge's midpoint, so bisection
 * finds every vertex on the edge. */
static int edge_collect(const mesh_bb *bb, int32_t ax, int32_t az, int32_t bx, int32_t bz,
                        int32_t len, uint32_t *out, int n, int max)
{
    if (len < 2 || n >= max)
        return n;
    int32_t mx = ax + (bx - ax) / 2, mz = az + (bz - az) / 2;
    uint32_t v = map_find(bb, mx, mz);
    if (v == NO_VERTEX)
        return n;
    n = edge_collect(bb, ax, az, mx, mz, len / 2, out, n, max);
    if (n < max)
        out[n++] = v;
    return edge_collect(bb, mx, mz, bx, bz, len / 2, out, n, max);
}

#define FAN_MAX 4096

ocean_result mesh_bb_triangulate(mesh_bb *bb)
{
    ocean_result r;
    size_t want = 64;
    while (want < 4 * bb->nl + 64)
        want *= 2;
    free(bb->hkeys);
    free(bb->hvals);
    bb->hkeys = malloc(want * sizeof *bb->hkeys);
    bb->hvals = malloc(want * sizeof *bb->hvals);
    if (!bb->hkeys || !bb->hvals)
        return OCEAN_ENOMEM;
    bb->hcap = want;
    bb->hcount = 0;
    for (size_t i = 0; i < want; i++)
        bb->hvals[i] = NO_VERTEX;
    bb->nv = 0;
    bb->ni = 0;
    /* Pass 1: every leaf corner is a vertex. */
    for (size_t i = 0; i < bb->nl; i++) {
        const mesh_leaf *l = &bb->leaves[i];
        uint32_t v;
        for (int c = 0; c < 4; c++)
            if ((r = map_get(bb, l->x + (c & 1) * l->size, l->z + (c >> 1) * l->size,
                             l->level, &v)) != OCEAN_OK)
                return r;
    }
    /* Pass 2: triangles.  Boundary order (0,0) (0,1) (1,1) (1,0) in (x, z)
     * gives normals toward +y. */
    static const int cx[4] = {0, 0, 1, 1}, cz[4] = {0, 1, 1, 0};
    uint32_t ring[FAN_MAX];
    for (size_t i = 0; i < bb->nl; i++) {
        mesh_leaf l = bb->leaves[i];
        int n = 0;
        for (int c = 0; c < 4; c++) {
            int32_t ax = l.x + cx[c] * l.size, az = l.z + cz[c] * l.size;
            int32_t bx = l.x + cx[(c + 1) & 3] * l.size, bz = l.z + cz[(c + 1) & 3] * l.size;
            ring[n++] = map_find(bb, ax, az);
            n = edge_collect(bb, ax, az, bx, bz, l.size, ring, n, FAN_MAX - 4);
        }
        if (n == 4) {
            if ((r = add_tri(bb, ring[0], ring[1], ring[2])) != OCEAN_OK ||
                (r = add_tri(bb, ring[0], ring[2], ring[3])) != OCEAN_OK)
                return r;
            continue;
        }
        if (l.size < 2)
            return OCEAN_ESTATE; /* cannot happen: nothing is finer than a unit cell */
        uint32_t c;
        if ((r = map_get(bb, l.x + l.size / 2, l.z + l.size / 2, l.level, &c)) != OCEAN_OK)
            return r;
        for (int k = 0; k < n; k++)
            if ((r = add_tri(bb, c, ring[k], ring[(k + 1) % n])) != OCEAN_OK)
                return r;
    }
    return OCEAN_OK;
}

ocean_result mesh_install(mesh *m, uint32_t nv, uint32_t ni, float *base, uint32_t *idx)
{
    float *pos = malloc((size_t)nv * 3 * sizeof *pos);
    float *morph = calloc(nv ? nv : 1, sizeof *morph);
    uint8_t *level = calloc(nv ? nv : 1, 1);
    if (!pos || !morph || !level) {
        free(pos);
        free(morph);
        free(level);
        return OCEAN_ENOMEM;
    }
    memcpy(pos, base, (size_t)nv * 3 * sizeof *pos);
    free_arrays(m);
    m->base = base;
    m->pos = pos;
    m->morph = morph;
    m->level = level;
    m->idx = idx;
    m->nv = nv;
    m->skirt_count = 0;
    m->ni = ni;
    return OCEAN_OK;
}

ocean_result mesh_adopt(mesh *m, mesh_bb *bb, double unit_m)
{
    uint32_t nv = bb->nv;
    float *base = malloc((size_t)nv * 3 * sizeof *base);
    int32_t *lat = malloc((size_t)nv * 2 * sizeof *lat);
    uint32_t *idx = malloc((bb->ni ? bb->ni : 1) * sizeof *idx);
    if (!base || !lat || !idx) {
        free(base);
        free(lat);
        free(idx);
        return OCEAN_ENOMEM;
    }
    for (uint32_t v = 0; v < nv; v++) {
        base[3 * v] = (float)(bb->lat[2 * v] * unit_m);
        base[3 * v + 1] = 0;
        base[3 * v + 2] = (float)(bb->lat[2 * v + 1] * unit_m);
    }
    memcpy(lat, bb->lat, (size_t)nv * 2 * sizeof *lat);
    memcpy(idx, bb->idx, bb->ni * sizeof *idx);
    ocean_result r = mesh_install(m, nv, (uint32_t)bb->ni, base, idx);
    if (r != OCEAN_OK) {
        free(base);
        free(lat);
        free(idx);
        return r;
    }
    memcpy(m->level, bb->lvl, nv);
    m->skirt_count = 0;
    m->lat = lat;
    m->unit_m = unit_m;
    return OCEAN_OK;
}

/* ---- displacement ---------------------------------------------------- */

static int32_t floor_to(int32_t v, int32_t s)
{
    int32_t q = v / s;
    if (v % s != 0 && v < 0)
        q--;
    return q * s;
}

/* The coarse-lattice corners of every vertex that can morph: p00, p11 and
 * the third corner of its cell's triangle (the (0,0)-(1,1) diagonal, as
 * the triangulator splits it), as vertex indices.  Those corners are
 * almost always vertices themselves, so a displacement samples each point
 * once instead of up to four times per morphing vertex. */
static ocean_result morph_corners(mesh *m)
{
    if (m->corner_ok)
        return OCEAN_OK;
    size_t cap = 16;
    while (cap < 2 * (size_t)m->nv)
        cap <<= 1;
    uint64_t *keys = malloc(cap * sizeof *keys);
    uint32_t *vals = malloc(cap * sizeof *vals);
    uint32_t *corner = realloc(m->corner, 3 * (size_t)(m->nv ? m->nv : 1) * sizeof *corner);
    if (corner)
        m->corner = corner;
    if (!keys || !vals || !corner) {
        free(keys);
        free(vals);
        return OCEAN_ENOMEM;
    }
    for (size_t i = 0; i < cap; i++)
        vals[i] = NO_VERTEX;
    for (uint32_t v = 0; v < m->nv; v++) {
        uint64_t k = lat_key(m->lat[2 * v], m->lat[2 * v + 1]);
        size_t s = slot_of(k, cap);
        while (vals[s] != NO_VERTEX)
            s = (s + 1) & (cap - 1);
        keys[s] = k;
        vals[s] = v;
    }
    for (uint32_t v = 0; v < m->nv; v++) {
        uint32_t *c = corner + 3 * (size_t)v;
        c[0] = c[1] = c[2] = NO_VERTEX;
        int L = m->level[v];
        if (L + 1 >= m->levels)
            continue;
        int32_t S = m->lvl_units[L + 1];
        int32_t i = m->lat[2 * v], j = m->lat[2 * v + 1];
        int32_t i0 = floor_to(i, S), j0 = floor_to(j, S);
        int32_t pts[3][2] = {{i0, j0}, {i0 + S, j0 + S},
                             {i - i0 >= j - j0 ? i0 + S : i0, i - i0 >= j - j0 ? j0 : j0 + S}};
        for (int q = 0; q < 3; q++) {
            uint64_t k = lat_key(pts[q][0], pts[q][1]);
            for (size_t s = slot_of(k, cap); vals[s] != NO_VERTEX; s = (s + 1) & (cap - 1))
                if (keys[s] == k) {
                    c[q] = vals[s];
                    break;
                }
        }
    }
    free(keys);
    free(vals);
    m->corner_ok = 1;
    return OCEAN_OK;
}

/* D at corner q of vertex v: the corner vertex's own sample, or sampled
 * here where the corner is no vertex of the mesh. */
static const double *corner_disp(const mesh *m, uint32_t v, int q, int32_t ci, int32_t cj,
                                 mesh_sampler_fn fn, void *ctx, double tmp[3])
{
    uint32_t c = m->corner[3 * (size_t)v + q];
    if (c != NO_VERTEX)
        return m->raw + 3 * (size_t)c;
    fn(ctx, m->origin[0] + ci * m->unit_m, m->origin[2] + cj * m->unit_m, tmp);
    return tmp;
}

ocean_result mesh_displace(mesh *m, mesh_sampler_fn fn, void *ctx)
{
    if (!m || !fn)
        return OCEAN_EINVAL;
    if (!m->built)
        return OCEAN_ESTATE;
    if (m->raw_cap < 3 * (size_t)m->nv) {
        double *raw = realloc(m->raw, 3 * (size_t)m->nv * sizeof *raw);
        if (!raw)
            return OCEAN_ENOMEM;
        m->raw = raw;
        m->raw_cap = 3 * (size_t)m->nv;
    }
    if (m->lat) {
        ocean_result r = morph_corners(m);
        if (r != OCEAN_OK)
            return r;
    }
    const double ox = m->origin[0], oz = m->origin[2];
    /* the far skirt stays flat: it only carries the sea's mean level
     * from the mesh's edge to the horizon */
    uint32_t sampled = m->nv - m->skirt_count;
    for (uint32_t v = 0; v < m->nv; v++) {
        const float *b = m->base + 3 * v;
        double *d = m->raw + 3 * (size_t)v;
        d[0] = d[1] = d[2] = 0;
        if (v < sampled)
            fn(ctx, ox + b[0], oz + b[2], d);
    }
    for (uint32_t v = 0; v < m->nv; v++) {
        const float *b = m->base + 3 * v;
        const double *raw = m->raw + 3 * (size_t)v;
        double d[3] = {raw[0], raw[1], raw[2]};
        double w = m->morph[v];
        int L = m->level[v];
        if (w > 0 && m->lat && L + 1 < m->levels) {
            /* the next level's surface: its cell's triangle with the
             * (0,0)-(1,1) diagonal, as the triangulator splits it */
            int32_t S = m->lvl_units[L + 1];
            int32_t i = m->lat[2 * v], j = m->lat[2 * v + 1];
            int32_t i0 = floor_to(i, S), j0 = floor_to(j, S);
            double fx = (double)(i - i0) / S, fz = (double)(j - j0) / S;
            if (fx > 0 || fz > 0) {
                double t00[3] = {0}, t11[3] = {0}, tm[3] = {0};
                const double *p00 = corner_disp(m, v, 0, i0, j0, fn, ctx, t00);
                const double *p11 = corner_disp(m, v, 1, i0 + S, j0 + S, fn, ctx, t11);
                const double *pm = fx >= fz ? corner_disp(m, v, 2, i0 + S, j0, fn, ctx, tm)
                                            : corner_disp(m, v, 2, i0, j0 + S, fn, ctx, tm);
                double a = fx >= fz ? fx : fz, c = fx >= fz ? fz : fx;
                /* P = p00 + a (pm - p00) + c (p11 - pm) */
                for (int k = 0; k < 3; k++) {
                    double coarse = p00[k] + a * (pm[k] - p00[k]) + c * (p11[k] - pm[k]);
                    d[k] = (1 - w) * d[k] + w * coarse;
                }
            }
        }
        m->pos[3 * v] = (float)(b[0] + d[0]);
        m->pos[3 * v + 1] = (float)(b[1] + d[1]);
        m->pos[3 * v + 2] = (float)(b[2] + d[2]);
    }
    return OCEAN_OK;
}

/* Angle between directions p - c and q - c, radians. */
static double angle_at(const double c[3], const double p[3], const double q[3])
{
    double u[3], v[3];
    for (int k = 0; k < 3; k++) {
        u[k] = p[k] - c[k];
        v[k] = q[k] - c[k];
    }
    double x[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    return atan2(sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]),
                 u[0] * v[0] + u[1] * v[1] + u[2] * v[2]);
}

ocean_result mesh_error_px(const mesh *m, const mesh_camera *cam, mesh_sampler_fn fn,
                           void *ctx, double *max_px)
{
    if (!m || !fn || !max_px || mesh_camera_validate(cam, NULL, 0) != OCEAN_OK)
        return OCEAN_EINVAL;
    if (!m->built)
        return OCEAN_ESTATE;
    static const double bary[4][3] = {
        {1.0 / 3, 1.0 / 3, 1.0 / 3}, {0.5, 0.5, 0}, {0, 0.5, 0.5}, {0.5, 0, 0.5}};
    const double f = mesh_camera_px_per_rad(cam);
    double worst = 0;
    const long ntri = (long)(m->ni / 3);
#pragma omp parallel for schedule(dynamic, 4096) reduction(max : worst)
    for (long ti = 0; ti < ntri; ti++) {
        const uint32_t t = (uint32_t)(3 * ti);
        const uint32_t *tri = m->idx + t;
        /* the far skirt is flat on purpose: not a sampling error */
        uint32_t real = m->nv - m->skirt_count;
        if (tri[0] >= real || tri[1] >= real || tri[2] >= real)
            continue;
        for (int s = 0; s < 4; s++) {
            double mp[3] = {m->origin[0], m->origin[1], m->origin[2]};
            double bp[3] = {m->origin[0], m->origin[1], m->origin[2]};
            for (int k = 0; k < 3; k++)
                for (int c = 0; c < 3; c++) {
                    mp[c] += bary[s][k] * m->pos[3 * tri[k] + c];
                    bp[c] += bary[s][k] * m->base[3 * tri[k] + c];
                }
            double d[3] = {0, 0, 0};
            fn(ctx, bp[0], bp[2], d);
            double ref[3] = {bp[0] + d[0], bp[1] + d[1], bp[2] + d[2]};
            double e = angle_at(cam->pos, mp, ref) * f;
            if (e > worst)
                worst = e;
        }
    }
    *max_px = worst;
    return OCEAN_OK;
}

ocean_result mesh_write_obj(const mesh *m, FILE *f)
{
    if (!m || !f)
        return OCEAN_EINVAL;
    if (!m->built)
        return OCEAN_ESTATE;
    fprintf(f, "# oceand %s mesh: %u vertices, %u triangles, %d levels\n",
            mesh_kind_name(m->cfg.kind), m->nv, m->ni / 3, m->levels);
    fprintf(f, "# positions in metres relative to the world origin %.6f %.6f %.6f (y up)\n",
            m->origin[0], m->origin[1], m->origin[2]);
    fprintf(f, "o ocean_%s\n", mesh_kind_name(m->cfg.kind));
    for (uint32_t v = 0; v < m->nv; v++)
        fprintf(f, "v %.9g %.9g %.9g\n", m->pos[3 * v], m->pos[3 * v + 1], m->pos[3 * v + 2]);
    for (uint32_t t = 0; t + 2 < m->ni; t += 3)
        fprintf(f, "f %u %u %u\n", m->idx[t] + 1, m->idx[t + 1] + 1, m->idx[t + 2] + 1);
    return ferror(f) ? OCEAN_EIO : OCEAN_OK;
}
