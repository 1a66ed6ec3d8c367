/*
 * oc_cascade.c - layout-1 frames on the client: the per-(cascade, mip)
 * tile index of a frame, the lod rule, the point sampler and the mesh
 * displacement declared in oc_cascade.h (see there for the reading rules
 * and their sources).
 */
#include "oc_cascade.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "codec.h"
#include "interp.h"
#include "lod.h"
#include "oceanclient.h"

#define NO_TILE 0xFFFFu
/* a folded crest's slope when a normal is turned into slopes */
#define MAX_SLOPE 100.0f

/* Values a mip read produces, in this order. */
enum { V_H, V_DX, V_DZ, V_SX, V_SZ, V_BI, V_BQ, V_COUNT };
/* What a read wants (bits). */
enum { W_H = 1, W_D = 2, W_S = 4, W_F = 8, W_ALL = 15 };

typedef struct cv_tile {
    const float *data;
    int w, h;
    unsigned channels;
    int off[PROTO_SLOT_COUNT];   /* float offsets of each plane slot; -1 absent */
} cv_tile;

typedef struct cv_mip {
    int n;                       /* samples per side */
    int T;                       /* tile side; 0: no tile of this mip */
    int tps;                     /* tiles per side */
    double spacing;
    uint16_t *grid;              /* tps * tps tile indices (rows = z), NO_TILE */
} cv_mip;

typedef struct cv_cascade {
    double patch, sigma;
    int mips, fades;
    cv_mip mip[PROTO_MAX_MIPS];
} cv_cascade;

struct oc_cascade_view {
    proto_cascade_block block;
    int count;
    cv_cascade c[PROTO_MAX_LAYERS];
    cv_tile *tiles;
    unsigned ntiles;
};

/* ============================================================ the view */

void oc_cascade_view_free(oc_cascade_view *v)
{
    if (!v)
        return;
    for (int c = 0; c < PROTO_MAX_LAYERS; c++)
        for (int m = 0; m < PROTO_MAX_MIPS; m++)
            free(v->c[c].mip[m].grid);
    free(v->tiles);
    free(v);
}

static int near_eq(double a, double b, double tol)
{
    return fabs(a - b) <= tol;
}

/* The cascades' mip grids, from the block (the decoder checked patch > 0,
 * n a power of two 8..2048, mips 1..12 with n >> (mips - 1) >= 1). */
static void view_cascades(oc_cascade_view *v, const proto_cascade_block *b)
{
    v->block = *b;
    v->count = b->cascade_count;
    for (int c = 0; c < v->count; c++) {
        const proto_cascade_entry *e = &b->cascade[c];
        cv_cascade *cc = &v->c[c];
        cc->patch = e->patch_m;
        cc->sigma = e->patch_m / e->n;
        cc->mips = e->mips;
        cc->fades = e->fades;
        for (int m = 0; m < cc->mips; m++) {
            cc->mip[m].n = e->n >> m;
            cc->mip[m].spacing = cc->sigma * ldexp(1.0, m);
        }
    }
}

/* Pass 1: each tile names a mip that exists at its spacing; T per mip. */
static ocean_result view_sizes(oc_cascade_view *v, const proto_frame *info, const float *const *tile_data, char *err,
                               size_t errlen)
{
    for (unsigned i = 0; i < info->tile_count; i++) {
        const proto_tile *t = &info->tiles[i];
        if (!tile_data || !tile_data[i]) {
            ocean_seterr(err, errlen, "tile %u is not decoded", i);
            return OCEAN_ESTATE;
        }
        if (t->cascade >= v->count || t->level >= v->c[t->cascade].mips) {
            ocean_seterr(err, errlen, "tile %u: cascade %u mip %u is not in the cascade block", i, t->cascade,
                         t->level);
            return OCEAN_EFORMAT;
        }
        cv_mip *mp = &v->c[t->cascade].mip[t->level];
        if (!near_eq(t->spacing, mp->spacing, 1e-9 * mp->spacing)) {
            ocean_seterr(err, errlen, "tile %u: spacing %.9g, mip %u of cascade %u has %.9g", i, t->spacing,
                         t->level, t->cascade, mp->spacing);
            return OCEAN_EFORMAT;
        }
        int side = t->width > t->height ? t->width : t->height;
        if (side > mp->T)
            mp->T = side;
    }
    return OCEAN_OK;
}

/* Each mip with tiles: its tile grid, empty (T = min(tile_size, n') with
 * tile_size >= 2). */
static ocean_result view_grids(oc_cascade_view *v, char *err, size_t errlen)
{
    for (int c = 0; c < v->count; c++)
        for (int m = 0; m < v->c[c].mips; m++) {
            cv_mip *mp = &v->c[c].mip[m];
            if (!mp->T)
                continue;
            if (mp->T > mp->n || mp->T < (mp->n < 2 ? mp->n : 2)) {
                ocean_seterr(err, errlen, "cascade %d mip %d: tiles of %d samples on a grid of %d", c, m, mp->T,
                             mp->n);
                return OCEAN_EFORMAT;
            }
            mp->tps = (mp->n + mp->T - 1) / mp->T;
            mp->grid = malloc((size_t)mp->tps * mp->tps * sizeof *mp->grid);
            if (!mp->grid)
                return OCEAN_ENOMEM;
            memset(mp->grid, 0xFF, (size_t)mp->tps * mp->tps * sizeof *mp->grid);
        }
    return OCEAN_OK;
}

/* Pass 2: tile i in its place per the spec, no tile twice. */
static ocean_result view_place(oc_cascade_view *v, const proto_frame *info, const float *const *tile_data, unsigned i,
                               char *err, size_t errlen)
{
    const proto_tile *t = &info->tiles[i];
    cv_mip *mp = &v->c[t->cascade].mip[t->level];
    int T = mp->T;
    if (t->ix < 0 || t->iz < 0 || t->ix >= mp->tps || t->iz >= mp->tps) {
        ocean_seterr(err, errlen, "tile %u: index (%d, %d) outside the %d x %d tiles of cascade %u mip %u", i, t->ix,
                     t->iz, mp->tps, mp->tps, t->cascade, t->level);
        return OCEAN_EFORMAT;
    }
    int ww = mp->n - t->ix * T < T ? mp->n - t->ix * T : T;
    int hh = mp->n - t->iz * T < T ? mp->n - t->iz * T : T;
    if (t->width != ww || t->height != hh) {
        ocean_seterr(err, errlen, "tile %u: %u x %u samples where cascade %u mip %u has %d x %d", i, t->width,
                     t->height, t->cascade, t->level, ww, hh);
        return OCEAN_EFORMAT;
    }
    double ox = (double)t->ix * T * mp->spacing, oz = (double)t->iz * T * mp->spacing;
    if (!near_eq(t->origin_x, ox, 1e-6 * mp->spacing) || !near_eq(t->origin_z, oz, 1e-6 * mp->spacing)) {
        ocean_seterr(err, errlen, "tile %u: origin (%.9g, %.9g), tile (%d, %d) of cascade %u mip %u is at "
                     "(%.9g, %.9g)", i, t->origin_x, t->origin_z, t->ix, t->iz, t->cascade, t->level, ox, oz);
        return OCEAN_EFORMAT;
    }
    uint16_t *g = &mp->grid[(size_t)t->iz * mp->tps + t->ix];
    if (*g != NO_TILE) {
        ocean_seterr(err, errlen, "tile %u: tile (%d, %d) of cascade %u mip %u sent twice (also tile %u)", i, t->ix,
                     t->iz, t->cascade, t->level, *g);
        return OCEAN_EFORMAT;
    }
    *g = (uint16_t)i;
    cv_tile *ct = &v->tiles[i];
    ct->data = tile_data[i];
    ct->w = t->width;
    ct->h = t->height;
    ct->channels = t->channels;
    proto_tile_plane_offsets(t->channels, (size_t)t->width * t->height, ct->off);
    return OCEAN_OK;
}

ocean_result oc_cascade_view_build(const proto_frame *info, const float *const *tile_data,
                                   oc_cascade_view **out, char *err, size_t errlen)
{
    *out = NULL;
    const proto_cascade_block *b = &info->cascades;
    if (info->layout != PROTO_LAYOUT_CASCADE || b->cascade_count < 1 || b->cascade_count > PROTO_MAX_LAYERS) {
        ocean_seterr(err, errlen, "not a layout-1 frame");
        return OCEAN_ESTATE;
    }
    oc_cascade_view *v = calloc(1, sizeof *v);
    if (!v)
        return OCEAN_ENOMEM;
    view_cascades(v, b);
    unsigned n = info->tile_count;
    if (n && !(v->tiles = calloc(n, sizeof *v->tiles))) {
        oc_cascade_view_free(v);
        return OCEAN_ENOMEM;
    }
    v->ntiles = n;
    ocean_result r = view_sizes(v, info, tile_data, err, errlen);
    if (r == OCEAN_OK) r = view_grids(v, err, errlen);
    for (unsigned i = 0; i < n && r == OCEAN_OK; i++) r = view_place(v, info, tile_data, i, err, errlen);
    if (r != OCEAN_OK) {
        oc_cascade_view_free(v);
        return r;
    }
    *out = v;
    return OCEAN_OK;
}

/* ============================================================ lod rule */

static int block_ok(const proto_cascade_block *b)
{
    if (!b || b->cascade_count < 1 || b->cascade_count > PROTO_MAX_LAYERS || !(b->spacing_per_m > 0) ||
        !isfinite(b->spacing_per_m) || !(b->min_spacing_m >= 0) || !isfinite(b->min_spacing_m))
        return 0;
    for (int i = 0; i < 3; i++)
        if (!isfinite(b->camera[i]))
            return 0;
    for (int c = 0; c < b->cascade_count; c++) {
        const proto_cascade_entry *e = &b->cascade[c];
        if (!(e->patch_m > 0) || !isfinite(e->patch_m) || e->n < 1 || e->mips < 1 || e->mips > PROTO_MAX_MIPS ||
            !(e->spacing_per_m > 0) || !(e->spacing_per_m <= b->spacing_per_m))
            return 0;
    }
    return 1;
}

/* The rule itself, on a block already checked: each cascade at its own
 * spacing max(min_spacing_m, q_c * distance), raised to min_spacing. */
static void lod_core(const proto_cascade_block *b, double x, double z, double min_spacing, oc_lod *out)
{
    double dx = x - b->camera[0], dz = z - b->camera[2];
    double floor_s = b->min_spacing_m > min_spacing ? b->min_spacing_m : min_spacing;
    out->s = proto_lod_spacing(b->spacing_per_m, floor_s, b->camera[1], dx, dz);
    out->count = b->cascade_count;
    for (int c = 0; c < b->cascade_count; c++) {
        const proto_cascade_entry *e = &b->cascade[c];
        oc_lod_cascade *L = &out->c[c];
        proto_lod_read r;
        L->s = proto_lod_spacing(e->spacing_per_m, floor_s, b->camera[1], dx, dz);
        proto_lod_read_at(L->s, e->patch_m / e->n, e->mips, e->fades, &r);
        L->lambda = r.lambda;
        L->fade = r.fade;
        for (int k = 0; k < 2; k++) {
            L->mip[k] = r.mip[k];
            L->weight[k] = r.weight[k];
        }
    }
}

ocean_result oc_cascade_lod(const proto_cascade_block *b, double x, double z, double min_spacing, oc_lod *out)
{
    if (!out || !block_ok(b) || !isfinite(x) || !isfinite(z) || !isfinite(min_spacing))
        return OCEAN_EINVAL;
    lod_core(b, x, z, min_spacing, out);
    return OCEAN_OK;
}

/* ============================================================ reading */

/* x mod P in [0, P): fmod is exact in IEEE arithmetic, so a world position
 * of 1e7 m reduces without losing its sub-millimetre part. */
static double wrap(double x, double P)
{
    double u = fmod(x, P);
    if (u < 0) {
        u += P;
        if (u >= P)     /* -tiny + P rounds to P */
            u = 0;
    }
    return u;
}

/* Sample (i, j) (row z, column x; already in [0, n)) of a mip: 0, or -1
 * when the frame has no tile there. */
static inline int fetch(const oc_cascade_view *v, const cv_mip *mp, int i, int j, unsigned want, float *val,
                        unsigned *chan)
{
    int ti = i / mp->T, tj = j / mp->T;
    uint16_t idx = mp->grid[(size_t)ti * mp->tps + tj];
    if (idx == NO_TILE)
        return -1;
    const cv_tile *t = &v->tiles[idx];
    size_t k = (size_t)(i - ti * mp->T) * t->w + (size_t)(j - tj * mp->T);
    const float *d = t->data;
    const int *o = t->off;
    if (want & W_H)
        val[V_H] = o[PROTO_SLOT_H] >= 0 ? d[o[PROTO_SLOT_H] + k] : 0.0f;
    if (want & W_D) {
        val[V_DX] = o[PROTO_SLOT_DX] >= 0 ? d[o[PROTO_SLOT_DX] + k] : 0.0f;
        val[V_DZ] = o[PROTO_SLOT_DZ] >= 0 ? d[o[PROTO_SLOT_DZ] + k] : 0.0f;
    }
    if (want & W_S) {
        if (o[PROTO_SLOT_NU] >= 0)
            proto_normal_oct_slopes(d[o[PROTO_SLOT_NU] + k], d[o[PROTO_SLOT_NV] + k], MAX_SLOPE, &val[V_SX],
                                    &val[V_SZ]);
        else
            val[V_SX] = val[V_SZ] = 0.0f;
    }
    if (want & W_F) {
        val[V_BI] = o[PROTO_SLOT_BI] >= 0 ? d[o[PROTO_SLOT_BI] + k] : 0.0f;
        val[V_BQ] = o[PROTO_SLOT_BQ] >= 0 ? d[o[PROTO_SLOT_BQ] + k] : 0.0f;
    }
    *chan &= t->channels;
    return 0;
}

static inline int imod(long a, int n)
{
    long r = a % n;
    return (int)(r < 0 ? r + n : r);
}

/* The kernel of an interpolation (interp.h). */
static inline ocean_interp kernel_of(oc_interp in)
{
    return in == OC_INTERP_LANCZOS3 ? OCEAN_INTERP_LANCZOS3
           : in == OC_INTERP_CUBIC  ? OCEAN_INTERP_KEYS
                                    : OCEAN_INTERP_BILINEAR;
}

/* The read table's kernel of an interpolation (PROTO_READ_*). */
static inline int read_kernel_of(oc_interp in)
{
    return in == OC_INTERP_LANCZOS3 ? PROTO_READ_LANCZOS3 : in == OC_INTERP_CUBIC ? PROTO_READ_KEYS : PROTO_READ_BILINEAR;
}

/* Taps of an interpolation: weights for offsets 1 - R .. R; returns R. */
static inline int taps(oc_interp in, double t, double *w)
{
    return ocean_interp_weights(kernel_of(in), t, w);
}

/* Reads one mip at cascade-local (u, v) in [0, P): acc[] += weight * value.
 * Where the wider kernels reach beyond the frame's tiles (the edge of the
 * square the spec sends) the next narrower one is used: Lanczos-3, Keys
 * cubic, bilinear.  0, or -1 when not even the 2 x 2 is covered. */
static int read_mip(const oc_cascade_view *v, const cv_mip *mp, double u, double w, unsigned want, oc_interp interp,
                    double weight, double *acc, unsigned *chan)
{
    if (!mp->T)
        return -1;
    double a = u / mp->spacing, b = w / mp->spacing;
    double fa = floor(a), fb = floor(b);
    double tx = a - fa, tz = b - fb;
    long j0 = (long)fa, i0 = (long)fb;
    int n = mp->n;
    float val[V_COUNT] = {0};   /* values not wanted stay 0 */
    for (oc_interp in = interp;; in = in == OC_INTERP_LANCZOS3 ? OC_INTERP_CUBIC : OC_INTERP_LINEAR) {
        double wx[6], wz[6], sum[V_COUNT] = {0};
        int R = taps(in, tx, wx);
        taps(in, tz, wz);
        unsigned ch = *chan;
        int ok = 1;
        for (int di = 0; di < 2 * R && ok; di++) {
            int i = imod(i0 + 1 - R + di, n);
            double rowv[V_COUNT] = {0};
            for (int dj = 0; dj < 2 * R; dj++) {
                if (fetch(v, mp, i, imod(j0 + 1 - R + dj, n), want, val, &ch)) {
                    ok = 0;
                    break;
                }
                for (int k = 0; k < V_COUNT; k++)
                    rowv[k] += wx[dj] * val[k];
            }
            for (int k = 0; k < V_COUNT; k++)
                sum[k] += wz[di] * rowv[k];
        }
        if (ok) {
            for (int k = 0; k < V_COUNT; k++)
                acc[k] += weight * sum[k];
            *chan = ch;
            return 0;
        }
        if (in == OC_INTERP_LINEAR)
            return -1;
    }
}

/* The PROTO_CH_* channels a W_* set reads. */
static unsigned want_channels(unsigned want)
{
    return ((want & W_H) ? PROTO_CH_HEIGHT : 0) | ((want & W_D) ? PROTO_CH_DX | PROTO_CH_DZ : 0) |
           ((want & W_S) ? PROTO_CH_NORMAL : 0) | ((want & W_F) ? PROTO_CH_BREAKING : 0);
}

/* The rule's reading of one cascade, as lod_core stored it. */
static proto_lod_read lod_read_of(const oc_lod_cascade *L)
{
    proto_lod_read r = {L->lambda, {L->mip[0], L->mip[1]}, {L->weight[0], L->weight[1]}, L->fade};
    return r;
}

/* What a read of the cascades gathers besides the sample itself. */
typedef struct read_acc {
    double mss[3];        /* unresolved slope moments (W_S) */
    double beta, q, var;  /* breaking index, its quadrature, the variance read (W_F) */
    unsigned common;      /* channels every tile read had, of those the pass wants */
} read_acc;

/* Adds to out the cascades at (x, z), each read at the levels `lod` names,
 * for the channels in want; with W_S the unresolved slope moments of those
 * levels go to ra->mss, with W_F the breaking index, its quadrature and the
 * variance those levels hold to ra.  0, or -1 when a mip read is not in
 * the frame's tiles. */
static int levels_read(const oc_cascade_view *v, double x, double z, const oc_lod *lod, unsigned want,
                       oc_interp interp, oc_sample *out, read_acc *ra)
{
    const proto_cascade_block *b = &v->block;
    for (int c = 0; c < v->count; c++) {
        const cv_cascade *cc = &v->c[c];
        const proto_cascade_entry *e = &b->cascade[c];
        const oc_lod_cascade *L = &lod->c[c];
        double u = wrap(x, cc->patch), w = wrap(z, cc->patch);
        double acc[V_COUNT] = {0};
        unsigned chan = PROTO_CH_ALL;
        for (int k = 0; k < 2; k++)
            if (L->mip[k] >= 0 && L->weight[k] > 0 &&
                read_mip(v, &cc->mip[L->mip[k]], u, w, want, interp, L->weight[k], acc, &chan))
                return -1;
        proto_lod_read r = lod_read_of(L);
        if (want & W_S)
            proto_lod_mss_add(&r, e->mip, cc->mips, ra->mss);
        if (want & W_F) {
            ra->beta += acc[V_BI];
            ra->q += acc[V_BQ];
            ra->var += proto_lod_breaking_var(&r, e->mip, cc->mips, read_kernel_of(interp));
        }
        out->height += acc[V_H];
        out->dx += acc[V_DX];
        out->dz += acc[V_DZ];
        out->slope_x += acc[V_SX];
        out->slope_z += acc[V_SZ];
        /* only the channels this pass reads: a shading pass at a
         * geometry-free mip (no H there) says nothing of the geometry */
        ra->common &= chan | ~want_channels(want);
    }
    return 0;
}

/* The sum of the cascades at (x, z): height and displacement at the levels
 * `geo` names, slopes, foam and the unresolved moments at those of
 * `shade` (PROTOCOL.md: geometry is read at max(s, G), shading at s; the
 * two are one set when G does not raise s).  0, or -1 when a mip read is
 * not in the frame's tiles. */
static int sample_lod(const oc_cascade_view *v, double x, double z, const oc_lod *geo, const oc_lod *shade,
                      unsigned want, oc_interp interp, oc_sample *out)
{
    const proto_cascade_block *b = &v->block;
    memset(out, 0, sizeof *out);
    out->s = shade->s;
    read_acc ra = {{b->tail_mss[0], b->tail_mss[1], b->tail_mss[2]}, 0, 0, 0, PROTO_CH_ALL};
    const unsigned wg = W_H | W_D;
    if (geo == shade || !(want & wg) || !(want & ~wg)) {
        const oc_lod *lod = (want & ~wg) ? shade : geo;
        if (levels_read(v, x, z, lod, want, interp, out, &ra))
            return -1;
    } else if (levels_read(v, x, z, geo, want & wg, interp, out, &ra) ||
               levels_read(v, x, z, shade, want & ~wg, interp, out, &ra)) {
        return -1;
    }
    double nl = sqrt(out->slope_x * out->slope_x + 1 + out->slope_z * out->slope_z);
    out->normal[0] = -out->slope_x / nl;
    out->normal[1] = 1 / nl;
    out->normal[2] = -out->slope_z / nl;
    for (int i = 0; i < 3; i++)
        out->mss[i] = ra.mss[i];
    if (!(b->flags & PROTO_CASCADE_FOAM))
        ra.common &= ~(unsigned)PROTO_CH_BREAKING;
    out->channels = ra.common & want_channels(want);
    if (out->channels & PROTO_CH_BREAKING)
        out->foam = proto_lod_foam(b, ra.var, ra.beta, ra.q);
    return 0;
}

/* The two level sets of a point: shading at the rule's s (raised to
 * min_spacing), geometry at max(s, G).  *geo points at shade when G does
 * not raise any cascade's spacing. */
static void lods_of(const oc_cascade_view *v, double x, double z, double min_spacing, oc_lod *shade,
                    oc_lod *geo_store, const oc_lod **geo)
{
    lod_core(&v->block, x, z, min_spacing, shade);
    double G = v->block.geometry_spacing_m;
    *geo = shade;
    if (!(G > min_spacing))
        return;
    for (int c = 0; c < shade->count; c++)
        if (shade->c[c].s < G) {
            lod_core(&v->block, x, z, G, geo_store);
            *geo = geo_store;
            return;
        }
}

/* sample_lod at the levels the rule gives (x, z). */
static int sample_core(const oc_cascade_view *v, double x, double z, double min_spacing, unsigned want,
                       oc_interp interp, oc_sample *out)
{
    oc_lod shade, gstore;
    const oc_lod *geo;
    lods_of(v, x, z, min_spacing, &shade, &gstore, &geo);
    return sample_lod(v, x, z, geo, &shade, want, interp, out);
}

static ocean_result frame_view(const oc_frame *f, const oc_cascade_view **v)
{
    if (!f)
        return OCEAN_EINVAL;
    if (!f->view)
        return OCEAN_ESTATE;
    *v = f->view;
    return OCEAN_OK;
}

/* The checks every point reader makes: out cleared, the frame's view, a
 * finite point and spacing, a known kernel. */
static ocean_result point_args(const oc_frame *f, double x, double z, double min_spacing, oc_interp interp,
                               oc_sample *out, const oc_cascade_view **v)
{
    if (!out)
        return OCEAN_EINVAL;
    memset(out, 0, sizeof *out);
    ocean_result r = frame_view(f, v);
    if (r != OCEAN_OK)
        return r;
    if (!isfinite(x) || !isfinite(z) || !isfinite(min_spacing) ||
        (interp != OC_INTERP_CUBIC && interp != OC_INTERP_LINEAR && interp != OC_INTERP_LANCZOS3))
        return OCEAN_EINVAL;
    return OCEAN_OK;
}

ocean_result oc_frame_sample_interp(const oc_frame *f, double x, double z, double min_spacing, oc_interp interp,
                                    oc_sample *out)
{
    const oc_cascade_view *v;
    ocean_result r = point_args(f, x, z, min_spacing, interp, out, &v);
    if (r != OCEAN_OK)
        return r;
    if (sample_core(v, x, z, min_spacing, W_ALL, interp, out)) {
        memset(out, 0, sizeof *out);
        return OCEAN_ENOTFOUND;
    }
    return OCEAN_OK;
}

ocean_result oc_frame_sample(const oc_frame *f, double x, double z, double min_spacing, oc_sample *out)
{
    return oc_frame_sample_interp(f, x, z, min_spacing, OC_INTERP_CUBIC, out);
}

ocean_result oc_frame_surface_interp(const oc_frame *f, double x, double z, double min_spacing, oc_interp interp,
                                     oc_sample *out)
{
    const oc_cascade_view *v;
    ocean_result r = point_args(f, x, z, min_spacing, interp, out, &v);
    if (r != OCEAN_OK)
        return r;
    /* the levels are those of the asked point, held while p moves */
    oc_lod lod, gstore;
    const oc_lod *geo;
    lods_of(v, x, z, min_spacing, &lod, &gstore, &geo);
    double ms = geo->s;   /* the finest spacing read sets the difference step */
    for (int c = 0; c < geo->count; c++)
        ms = fmin(ms, geo->c[c].s);
    double px = x, pz = z, best = INFINITY, bx = x, bz = z;
    const double tol = 1e-5;
    oc_sample s0, sx, sz;
    for (int it = 0; it < 24; it++) {
        if (sample_lod(v, px, pz, geo, &lod, W_D, interp, &s0))
            return OCEAN_ENOTFOUND;
        double rx = px + s0.dx - x, rz = pz + s0.dz - z;
        double res = hypot(rx, rz);
        if (res < best) {
            best = res;
            bx = px;
            bz = pz;
        }
        if (res < tol)
            break;
        /* Newton on p + D(p) = (x, z) with a finite-difference Jacobian */
        double d = 1e-3 > 0.01 * ms ? 1e-3 : 0.01 * ms;
        if (sample_lod(v, px + d, pz, geo, &lod, W_D, interp, &sx) ||
            sample_lod(v, px, pz + d, geo, &lod, W_D, interp, &sz))
            return OCEAN_ENOTFOUND;
        double a = 1 + (sx.dx - s0.dx) / d, bq = (sz.dx - s0.dx) / d;
        double c = (sx.dz - s0.dz) / d, e = 1 + (sz.dz - s0.dz) / d;
        double det = a * e - bq * c;
        if (det > 0.05) {
            px -= (e * rx - bq * rz) / det;
            pz -= (-c * rx + a * rz) / det;
        } else {
            /* near a fold the Jacobian says little: a damped fixed-point step */
            px -= 0.5 * rx;
            pz -= 0.5 * rz;
        }
    }
    if (sample_lod(v, bx, bz, geo, &lod, W_ALL, interp, out)) {
        memset(out, 0, sizeof *out);
        return OCEAN_ENOTFOUND;
    }
    out->residual = best;
    return best <= 1e-4 ? OCEAN_OK : OCEAN_EDIVERGED;
}

ocean_result oc_frame_surface(const oc_frame *f, double x, double z, double min_spacing, oc_sample *out)
{
    return oc_frame_surface_interp(f, x, z, min_spacing, OC_INTERP_CUBIC, out);
}

/* ============================================================ mesh */

double oc_mesh_morph_weight(const float zone[4], double d, int is_coarsest)
{
    if (is_coarsest)
        return 0;
    double R = zone[1], bl = zone[2];
    if (!(bl > 0))
        return d >= R ? 1 : 0;
    double u = (d - (R - bl)) / (2 * bl);
    u = u < 0 ? 0 : u > 1 ? 1 : u;
    return u * u * (3 - 2 * u);
}

ocean_result oc_frame_mesh_positions_ex(const oc_frame *f, const oc_topology *t, oc_interp interp, float *xyz,
                                        size_t *missing)
{
    if (missing)
        *missing = 0;
    if (!f || !t || !xyz ||
        (interp != OC_INTERP_CUBIC && interp != OC_INTERP_LINEAR && interp != OC_INTERP_LANCZOS3))
        return OCEAN_EINVAL;
    const oc_cascade_view *v;
    ocean_result r = frame_view(f, &v);
    if (r != OCEAN_OK)
        return r;
    if (!f->info.has_mesh)
        return OCEAN_ESTATE;
    if (!(t->flags & PROTO_TOPO_FLAT) || !t->flat || !t->zones || !t->level || t->lod_levels < 1 ||
        t->mesh_id != f->info.placement.mesh_id)
        return OCEAN_EINVAL;
    const double *o = f->info.placement.origin;
    const double *cam = v->block.camera;
    size_t miss = 0;
    for (uint32_t i = 0; i < t->vertex_count; i++) {
        unsigned L = t->level[i];
        if (L >= t->lod_levels)
            return OCEAN_EINVAL;
        double px = t->flat[2 * i], pz = t->flat[2 * i + 1];
        int coarsest = L + 1 >= t->lod_levels;
        double w = oc_mesh_morph_weight(t->zones + 4 * L, hypot(o[0] + px - cam[0], o[2] + pz - cam[2]), coarsest);
        if (w > 0) {
            /* slide toward the coarser level's lattice point */
            double g = t->zones[4 * (L + 1)];
            px -= w * (px - g * floor(px / g + 0.5));
            pz -= w * (pz - g * floor(pz / g + 0.5));
        }
        oc_sample s;
        float *q = xyz + 3 * (size_t)i;
        if (sample_core(v, o[0] + px, o[2] + pz, t->zones[4 * L], W_H | W_D, interp, &s)) {
            miss++;
            q[0] = (float)px;
            q[1] = 0.0f;
            q[2] = (float)pz;
            continue;
        }
        q[0] = (float)(px + s.dx);
        q[1] = (float)s.height;
        q[2] = (float)(pz + s.dz);
    }
    if (missing)
        *missing = miss;
    return miss ? OCEAN_ENOTFOUND : OCEAN_OK;
}

ocean_result oc_frame_mesh_positions(const oc_frame *f, const oc_topology *t, float *xyz)
{
    return oc_frame_mesh_positions_ex(f, t, OC_INTERP_CUBIC, xyz, NULL);
}
