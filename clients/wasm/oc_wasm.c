/*
 * oc_wasm.c - the browser viewer's tile decoders: protocol/codec.c's own
 * decoders (f32, f16, qz formats 1 and 2, MESH_VERTICES_QZ) compiled to
 * WebAssembly (clang --target=wasm32-wasi, wasm-ld; Makefile target
 * clients/web/ocean.wasm), with the few exports the viewer's workers call
 * (clients/web/codec.js).  One implementation of every codec: the
 * daemon, the C library and the browser run the same C.
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
#include <zstd.h>

#include "codec.h"

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
 * its heights (one-sided at the edges). */
static void slopes_from_heights(const float *H, int w, int h, double spacing, float *slope)
{
    for (int i = 0; i < h; i++)
        for (int j = 0; j < w; j++) {
            int j0 = j > 0 ? j - 1 : 0, j1 = j < w - 1 ? j + 1 : w - 1;
            int i0 = i > 0 ? i - 1 : 0, i1 = i < h - 1 ? i + 1 : h - 1;
            size_t k = (size_t)i * w + j;
            slope[2 * k] = j1 > j0 ? (float)((H[i * w + j1] - H[i * w + j0]) / ((j1 - j0) * spacing)) : 0.0f;
            slope[2 * k + 1] = i1 > i0 ? (float)((H[i1 * w + j] - H[i0 * w + j]) / ((i1 - i0) * spacing)) : 0.0f;
        }
}

/* Layout 1 (PROTOCOL.md "Cascade mips"): one cascade mip tile decoded into
 * the viewer's texel block: disp = (DX, H, DZ, FOAM) per sample (4 w h
 * floats: a vertex adds disp.xyz to its flat position), slope = (d eta/dx,
 * d eta/dz) (2 w h floats; slopes, not normals, because cascades add and
 * a GL-filtered mip averages slopes) from the octahedral normal at
 * max_slope at most, else from the heights; foam = {sum, max} of FOAM. */
OCW_EXPORT(ocw_cascade_block)
int ocw_cascade_block(int codec, int w, int h, unsigned channels, double spacing, double max_slope,
                      const uint8_t *data, size_t len, float *disp, float *slope, double *foam)
{
    ocw_err[0] = 0;
    int np = proto_tile_planes(channels);
    if (np <= 0 || w < 1 || h < 1 || w > PROTO_TILE_MAX_SIZE || h > PROTO_TILE_MAX_SIZE || !(spacing > 0) ||
        !(max_slope > 0) || !disp || !slope || !foam) {
        ocean_seterr(ocw_err, sizeof ocw_err, "cascade block: bad arguments");
        return OCEAN_EINVAL;
    }
    size_t n = (size_t)w * h;
    float *d = malloc(n * (size_t)np * sizeof *d);
    if (!d)
        return OCEAN_ENOMEM;
    ocean_result r = proto_tile_decode((proto_codec)codec, w, h, channels, data, len, d, ocw_err, sizeof ocw_err);
    if (r != OCEAN_OK) {
        free(d);
        return r;
    }
    int off[6];
    proto_tile_plane_offsets(channels, n, off);
    const float *P[6];
    for (int k = 0; k < 6; k++)
        P[k] = off[k] >= 0 ? d + off[k] : NULL;
    double fsum = 0, fmax = 0;
    for (size_t k = 0; k < n; k++) {
        float fo = P[5] ? P[5][k] : 0.0f;
        disp[4 * k] = P[1] ? P[1][k] : 0.0f;
        disp[4 * k + 1] = P[0] ? P[0][k] : 0.0f;
        disp[4 * k + 2] = P[2] ? P[2][k] : 0.0f;
        disp[4 * k + 3] = fo;
        fsum += fo;
        fmax = fo > fmax ? fo : fmax;
        if (P[3])
            proto_normal_oct_slopes(P[3][k], P[4][k], (float)max_slope, &slope[2 * k], &slope[2 * k + 1]);
        else
            slope[2 * k] = slope[2 * k + 1] = 0.0f;
    }
    if (!P[3] && P[0])
        slopes_from_heights(P[0], w, h, spacing, slope);
    foam[0] = fsum;
    foam[1] = fmax;
    free(d);
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
