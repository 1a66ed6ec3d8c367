/*
 * oc_wasm.c - the browser viewer's decoders: protocol/codec.c's own
 * decoders (f32, f16, qz formats 1 and 2, MESH_VERTICES_QZ), the message
 * decoder (protocol/proto.c) and the C library's store of a
 * time-interpolating stream (clients/c/oc_held.c) compiled to WebAssembly
 * (clang --target=wasm32-wasi, wasm-ld; Makefile target
 * clients/web/ocean.wasm), with the few exports the viewer's workers call
 * (clients/web/codec.js).  One implementation of every codec and of the
 * samples-in-time rules: the daemon, the C library and the browser run
 * the same C.
 *
 * zstd: the residual streams are decompressed by zstd's own decoder, a
 * separate WebAssembly module (the npm package zstddec, pinned in
 * tests/browser/package.json and vendored as clients/web/vendor/zstd.wasm);
 * this file adapts the four libzstd calls codec.c makes to the two
 * functions that module exports, through the imports "zstd.content_size"
 * and "zstd.decompress" that codec.js provides.  zstddec exports no
 * frame-length function, so ZSTD_findFrameCompressedSize here answers "the
 * whole input" whenever the input parses as zstd frames: a payload of two
 * frames whose sizes add up to R decodes to the same residuals here and is
 * refused as malformed by the native decoder.  Every other check is the
 * native one.
 *
 * Threads: none; each decode worker instantiates its own module.  Memory:
 * JavaScript allocates inputs and outputs with ocw_alloc / ocw_free; a
 * failed allocation is OCEAN_ENOMEM like everywhere else.  The message of
 * the last failure is read with ocw_error().
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <zstd.h>

#include "codec.h"
#include "oc_held.h"
#include "oc_wakes.h"
#include "proto.h"

#define OCW_EXPORT(name) __attribute__((export_name(#name)))
#define OCW_IMPORT(mod, name) __attribute__((import_module(#mod), import_name(#name)))

/* Content size of the zstd frames in src (zstddec's ZSTD_findDecompressedSize),
 * or -1 when they do not parse or one lacks its content size. */
OCW_IMPORT(zstd, content_size) double ocw_zstd_content_size(const void *src, size_t len);
/* Decompresses src into dst (at most cap bytes): the byte count, or -1. */
OCW_IMPORT(zstd, decompress) double ocw_zstd_decompress(void *dst, size_t cap, const void *src, size_t len);

/* ---- libzstd's decoding calls, on the imported decoder ----------------- */

#define OCW_ZSTD_CORRUPT ((size_t)-20) /* ZSTD_error_corruption_detected */

unsigned ZSTD_isError(size_t code) { return code > (size_t)-120; /* ZSTD_error_maxCode */ }

const char *ZSTD_getErrorName(size_t code)
{
    return ZSTD_isError(code) ? "corrupted or truncated zstd data" : "no error";
}

size_t ZSTD_findFrameCompressedSize(const void *src, size_t len)
{
    return ocw_zstd_content_size(src, len) >= 0 ? len : OCW_ZSTD_CORRUPT;
}

unsigned long long ZSTD_getFrameContentSize(const void *src, size_t len)
{
    double n = ocw_zstd_content_size(src, len);
    return n >= 0 ? (unsigned long long)n : ZSTD_CONTENTSIZE_ERROR;
}

size_t ZSTD_decompress(void *dst, size_t cap, const void *src, size_t len)
{
    double n = ocw_zstd_decompress(dst, cap, src, len);
    return n >= 0 && n <= (double)cap ? (size_t)n : OCW_ZSTD_CORRUPT;
}

/* The EXR codecs need OpenEXRCore, which the browser build does not
 * carry; the viewer never subscribes with them. */
ocean_result proto_exr_decode(int w, int h, unsigned channels, const uint8_t *data, size_t len, float *planes,
                              char *err, size_t errlen)
{
    (void)w, (void)h, (void)channels, (void)data, (void)len, (void)planes;
    ocean_seterr(err, errlen, "the EXR codecs are not decoded in the browser");
    return OCEAN_EUNSUPPORTED;
}

/* ---- exports ---------------------------------------------------------- */

static char ocw_err[256];

OCW_EXPORT(ocw_alloc) void *ocw_alloc(size_t n) { return malloc(n ? n : 1); }
OCW_EXPORT(ocw_free) void ocw_free(void *p) { free(p); }
OCW_EXPORT(ocw_error) const char *ocw_error(void) { return ocw_err; }

/* proto_tile_decode: planes gets proto_tile_planes(channels) * w * h floats. */
OCW_EXPORT(ocw_tile_decode)
int ocw_tile_decode(int codec, int w, int h, unsigned channels, const uint8_t *data, size_t len, float *planes)
{
    ocw_err[0] = 0;
    return proto_tile_decode((proto_codec)codec, w, h, channels, data, len, planes, ocw_err, sizeof ocw_err);
}

/* The slopes of a tile without normal planes, from central differences of
 * its heights (one-sided at the edges), into the first two of each
 * sample's four slope texels. */
static void slopes_from_heights(const float *H, int w, int h, double spacing, float *slope)
{
    for (int i = 0; i < h; i++)
        for (int j = 0; j < w; j++) {
            int j0 = j > 0 ? j - 1 : 0, j1 = j < w - 1 ? j + 1 : w - 1;
            int i0 = i > 0 ? i - 1 : 0, i1 = i < h - 1 ? i + 1 : h - 1;
            size_t k = (size_t)i * w + j;
            slope[4 * k] = j1 > j0 ? (float)((H[i * w + j1] - H[i * w + j0]) / ((j1 - j0) * spacing)) : 0.0f;
            slope[4 * k + 1] = i1 > i0 ? (float)((H[i1 * w + j] - H[i0 * w + j]) / ((i1 - i0) * spacing)) : 0.0f;
        }
}

/* Layout 1 (PROTOCOL.md "Cascade mips"): a cascade mip tile's decoded
 * planes d (of channels) as the viewer's texel block: disp = (DX, H, DZ,
 * 0) per sample (4 w h floats: a vertex adds disp.xyz to its flat
 * position), slope = (d eta/dx, d eta/dz, BI, BQ) (4 w h floats; slopes,
 * not normals, because cascades add and a GL-filtered mip averages slopes;
 * the breaking index and its quadrature add too, and the shader applies
 * the frame's whitecap table to their sum: PROTOCOL.md "Whitecaps in
 * layout 1") from the octahedral normal at max_slope at most, else from
 * the heights. */
static void texel_block(const float *d, unsigned channels, int w, int h, double spacing, double max_slope,
                        float *disp, float *slope)
{
    size_t n = (size_t)w * h;
    int off[PROTO_SLOT_COUNT];
    proto_tile_plane_offsets(channels, n, off);
    const float *P[PROTO_SLOT_COUNT];
    for (int k = 0; k < PROTO_SLOT_COUNT; k++)
        P[k] = off[k] >= 0 ? d + off[k] : NULL;
    const float *pH = P[PROTO_SLOT_H], *pX = P[PROTO_SLOT_DX], *pZ = P[PROTO_SLOT_DZ];
    const float *pU = P[PROTO_SLOT_NU], *pV = P[PROTO_SLOT_NV], *pB = P[PROTO_SLOT_BI], *pQ = P[PROTO_SLOT_BQ];
    for (size_t k = 0; k < n; k++) {
        disp[4 * k] = pX ? pX[k] : 0.0f;
        disp[4 * k + 1] = pH ? pH[k] : 0.0f;
        disp[4 * k + 2] = pZ ? pZ[k] : 0.0f;
        disp[4 * k + 3] = 0.0f;
        if (pU)
            proto_normal_oct_slopes(pU[k], pV[k], (float)max_slope, &slope[4 * k], &slope[4 * k + 1]);
        else
            slope[4 * k] = slope[4 * k + 1] = 0.0f;
        slope[4 * k + 2] = pB ? pB[k] : 0.0f;
        slope[4 * k + 3] = pQ ? pQ[k] : 0.0f;
    }
    if (!pU && pH)
        slopes_from_heights(pH, w, h, spacing, slope);
}

static int block_args_ok(int w, int h, double spacing, double max_slope, const void *disp, const void *slope)
{
    if (w < 1 || h < 1 || w > PROTO_TILE_MAX_SIZE || h > PROTO_TILE_MAX_SIZE || !(spacing > 0) ||
        !(max_slope > 0) || !disp || !slope) {
        ocean_seterr(ocw_err, sizeof ocw_err, "cascade block: bad arguments");
        return 0;
    }
    return 1;
}

/* One cascade mip tile's payload decoded into its texel block (texel_block). */
OCW_EXPORT(ocw_cascade_block)
int ocw_cascade_block(int codec, int w, int h, unsigned channels, double spacing, double max_slope,
                      const uint8_t *data, size_t len, float *disp, float *slope)
{
    ocw_err[0] = 0;
    int np = proto_tile_planes(channels);
    if (np <= 0 || !block_args_ok(w, h, spacing, max_slope, disp, slope)) {
        ocean_seterr(ocw_err, sizeof ocw_err, "cascade block: bad arguments");
        return OCEAN_EINVAL;
    }
    float *d = malloc((size_t)w * h * (size_t)np * sizeof *d);
    if (!d)
        return OCEAN_ENOMEM;
    ocean_result r = proto_tile_decode((proto_codec)codec, w, h, channels, data, len, d, ocw_err, sizeof ocw_err);
    if (r == OCEAN_OK)
        texel_block(d, channels, w, h, spacing, max_slope, disp, slope);
    free(d);
    return r;
}

/* ---- layout 1 samples in time (PROTOCOL.md "Samples in time") ---------- */

/* A time-interpolating stream's store, clients/c/oc_held.c as the C
 * library runs it, sharded: a viewer with several decode workers gives
 * each one store that keeps the tiles of its shard (every FRAME goes to
 * every worker, in order), so they decode and blend in parallel and each
 * tile is decoded once, by one of them, when it is first blended. */
typedef struct ocw_held {
    oc_held *store;
    proto_frame at;          /* the last frame applied, without tiles: the instant blended */
    int have_frame;
    proto_tile *tiles;       /* the last blend */
    float **data;
    unsigned n;
} ocw_held;

OCW_EXPORT(ocw_held_create) ocw_held *ocw_held_create(void)
{
    ocw_held *h = calloc(1, sizeof *h);
    if (h && oc_held_create(&h->store) != OCEAN_OK) {
        free(h);
        h = NULL;
    }
    return h;
}

static void held_blend_drop(ocw_held *h)
{
    oc_held_blend_free(h->tiles, h->data, h->n);
    h->tiles = NULL;
    h->data = NULL;
    h->n = 0;
}

OCW_EXPORT(ocw_held_destroy) void ocw_held_destroy(ocw_held *h)
{
    if (!h) return;
    held_blend_drop(h);
    oc_held_destroy(h->store);
    free(h);
}

/* The shard of a tile: a hash of its place, the same in every worker. */
static unsigned tile_shard(const proto_tile *t, unsigned shards)
{
    uint32_t k = (uint32_t)t->ix * 73856093u ^ (uint32_t)t->iz * 19349663u ^
                 (uint32_t)(t->cascade * PROTO_MAX_MIPS + t->level) * 83492791u;
    return k % shards;
}

/* Applies one whole FRAME message (layout 1) to the store, keeping the
 * tiles of shard `shard` of `shards` as payloads (decoded when blended). */
OCW_EXPORT(ocw_held_apply)
int ocw_held_apply(ocw_held *h, const uint8_t *msg, size_t len, unsigned shard, unsigned shards)
{
    ocw_err[0] = 0;
    if (!h || !shards || shard >= shards) {
        ocean_seterr(ocw_err, sizeof ocw_err, "held store: bad arguments");
        return OCEAN_EINVAL;
    }
    proto_msg m;
    ocean_result r = proto_decode(msg, len, &m, ocw_err, sizeof ocw_err);
    if (r != OCEAN_OK) return r;
    proto_frame *f = &m.u.frame;
    if (m.hdr.type != PROTO_FRAME || f->layout != PROTO_LAYOUT_CASCADE) {
        proto_msg_free(&m);
        ocean_seterr(ocw_err, sizeof ocw_err, "held store: not a layout-1 FRAME");
        return OCEAN_ESTATE;
    }
    proto_tile *mine = malloc((f->tile_count ? f->tile_count : 1) * sizeof *mine);
    if (!mine) {
        proto_msg_free(&m);
        return OCEAN_ENOMEM;
    }
    uint16_t k = 0;
    for (unsigned i = 0; i < f->tile_count; i++)
        if (tile_shard(&f->tiles[i], shards) == shard) mine[k++] = f->tiles[i];
    proto_frame sub = *f;
    sub.tiles = mine;
    sub.tile_count = k;
    r = oc_held_apply(h->store, &sub, NULL, ocw_err, sizeof ocw_err);
    memset(&h->at, 0, sizeof h->at);
    h->at.layout = f->layout;
    h->at.tick = f->tick;
    h->at.cascades = f->cascades;
    h->have_frame = 1;
    free(mine);
    proto_msg_free(&m);
    return r;
}

/* Decodes what the store has not decoded yet and blends the tiles of the
 * last frame's instant; the count is ocw_held_count().  A tile that does
 * not decode is left out and named in ocw_error (the result is then its
 * decoder's), the rest blended all the same. */
OCW_EXPORT(ocw_held_blend) int ocw_held_blend(ocw_held *h)
{
    ocw_err[0] = 0;
    if (!h || !h->have_frame) {
        ocean_seterr(ocw_err, sizeof ocw_err, "held store: no frame applied");
        return OCEAN_ESTATE;
    }
    held_blend_drop(h);
    char e[256] = "";
    ocean_result dr = oc_held_decode(h->store, e, sizeof e);
    ocean_result r = oc_held_blend(h->store, &h->at, &h->tiles, &h->data, &h->n);
    if (r == OCEAN_OK && dr != OCEAN_OK) {
        ocean_seterr(ocw_err, sizeof ocw_err, "%s", e);
        r = dr;
    }
    return r;
}

OCW_EXPORT(ocw_held_count) unsigned ocw_held_count(const ocw_held *h) { return h ? h->n : 0; }

/* Blended tile i: out = cascade, mip, ix, iz, width, height, channels,
 * spacing, error_bound; the planes (proto_tile_planes(channels) w h
 * floats, plane after plane) are at ocw_held_planes(h, i). */
OCW_EXPORT(ocw_held_tile) int ocw_held_tile(const ocw_held *h, unsigned i, double *out)
{
    if (!h || i >= h->n || !out) return OCEAN_EINVAL;
    const proto_tile *t = &h->tiles[i];
    double v[9] = {t->cascade, t->level, t->ix, t->iz, t->width, t->height, t->channels, t->spacing,
                   t->error_bound};
    memcpy(out, v, sizeof v);
    return OCEAN_OK;
}

OCW_EXPORT(ocw_held_planes) const float *ocw_held_planes(const ocw_held *h, unsigned i)
{
    return h && i < h->n ? h->data[i] : NULL;
}

/* Blended tile i as its texel block (texel_block). */
OCW_EXPORT(ocw_held_texels)
int ocw_held_texels(const ocw_held *h, unsigned i, double max_slope, float *disp, float *slope)
{
    ocw_err[0] = 0;
    if (!h || i >= h->n) return OCEAN_EINVAL;
    const proto_tile *t = &h->tiles[i];
    if (!block_args_ok(t->width, t->height, t->spacing, max_slope, disp, slope)) return OCEAN_EINVAL;
    texel_block(h->data[i], t->channels, t->width, t->height, t->spacing, max_slope, disp, slope);
    return OCEAN_OK;
}

/* Layout 0: unit normals (x, y, z, 1) per sample from a tile's NU, NV
 * planes, into a 4-float stride (the viewer's normal texture). */
OCW_EXPORT(ocw_normals)
void ocw_normals(const float *nu, const float *nv, size_t n, float *xyzw)
{
    for (size_t k = 0; k < n; k++) {
        proto_normal_oct_decode(nu[k], nv[k], &xyzw[4 * k], &xyzw[4 * k + 1], &xyzw[4 * k + 2]);
        xyzw[4 * k + 3] = 1.0f;
    }
}

OCW_EXPORT(ocw_mesh_qz_refs)
int ocw_mesh_qz_refs(const uint32_t *indices, uint32_t index_count, uint32_t vertex_count, uint32_t *refs)
{
    ocw_err[0] = 0;
    ocean_result r = proto_mesh_qz_refs(indices, index_count, vertex_count, refs);
    if (r != OCEAN_OK)
        ocean_seterr(ocw_err, sizeof ocw_err, "mesh qz: topology of %u vertices is not a triangle list over them",
                     vertex_count);
    return r;
}

OCW_EXPORT(ocw_mesh_qz_decode)
int ocw_mesh_qz_decode(const uint8_t *data, size_t len, uint32_t vertex_count, const uint32_t *refs, float *xyz)
{
    ocw_err[0] = 0;
    return proto_mesh_qz_decode(data, len, vertex_count, refs, xyz, ocw_err, sizeof ocw_err);
}

/* ---- the ships' wakes (clients/c/oc_wakes.c) ---------------------------- */

OCW_EXPORT(ocw_wakes_create) oc_wakes *ocw_wakes_create(void)
{
    oc_wakes *w = NULL;
    oc_wakes_create(&w);
    return w;
}

OCW_EXPORT(ocw_wakes_destroy) void ocw_wakes_destroy(oc_wakes *w) { oc_wakes_destroy(w); }

/* An ENTITY or WAKE message (whole, header included) into the store. */
OCW_EXPORT(ocw_wakes_message) int ocw_wakes_message(oc_wakes *w, const uint8_t *msg, size_t len)
{
    ocw_err[0] = 0;
    if (!w) return OCEAN_EINVAL;
    proto_msg m;
    ocean_result r = proto_decode(msg, len, &m, ocw_err, sizeof ocw_err);
    if (r != OCEAN_OK) return r;
    if (m.hdr.type == PROTO_ENTITY) {
        r = oc_wakes_entity(w, &m);
        if (r != OCEAN_OK) ocean_seterr(ocw_err, sizeof ocw_err, "entity %u: entry refused", m.u.entity.id);
    } else if (m.hdr.type == PROTO_WAKE) {
        wake_pattern *p = oc_wakes_decode(&m.u.wake);
        if (p) oc_wakes_keep(w, p);
        else ocean_seterr(ocw_err, sizeof ocw_err, "WAKE of %g m/s, %g m: pattern unreadable", m.u.wake.speed,
                          m.u.wake.length);
        r = p ? OCEAN_OK : OCEAN_ECODEC;
    } else {
        ocean_seterr(ocw_err, sizeof ocw_err, "wakes: not an ENTITY or WAKE message");
        r = OCEAN_EINVAL;
    }
    proto_msg_free(&m);
    return r;
}

/* The wakes at sim time t over the given depth on the n x n points
 * (x0 + i dx, z0 + j dx) into out (4 floats each, row j after row: height,
 * dh/dx, dh/dz, the slope variance a side the grid does not hold:
 * oc_wakes_grid).  OCEAN_ESTATE: a pattern a ship there needs has not
 * come. */
OCW_EXPORT(ocw_wakes_grid) int ocw_wakes_grid(oc_wakes *w, double t, double depth, double x0, double z0, double dx,
                                              int n, float *out)
{
    ocw_err[0] = 0;
    return oc_wakes_grid(w, t, depth, x0, z0, dx, n, out);
}
