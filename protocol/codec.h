/*
 * codec.h - tile codecs: how a grid of floats becomes the payload of a TILE.
 *
 * A tile is `planes` row-major float grids of w x h samples (row = z index,
 * column = x index), stored plane after plane.  Which planes a tile holds is
 * given by a channel mask (PROTO_CH_*); planes appear in the fixed order
 * H, DX, DZ, NU, NV, FOAM, J, where the normal (PROTO_CH_NORMAL) is two planes
 * NU, NV holding the octahedral encoding of the unit normal.
 *
 * Codecs (ids are on the wire; see PROTOCOL.md for exact byte layouts):
 *   f32       raw IEEE binary32, lossless
 *   f16       IEEE binary16, round to nearest even
 *   qz        quantised with a step from an accuracy target (per plane kind:
 *             see proto_codec_plane_error_bound), least-squares spatial
 *             prediction (DX, DZ, NU, NV also from the decoded H plane),
 *             zstd                                               (the default)
 *   exr-zip   OpenEXR file in memory, FLOAT channels, ZIP (lossless)
 *   exr-piz   OpenEXR file in memory, HALF channels, PIZ (lossless on half)
 *   exr-b44   OpenEXR file in memory, HALF channels, B44 (lossy, fixed rate)
 *   exr-b44a  as exr-b44, flat 4x4 blocks shrink to 3 bytes
 * The EXR payloads are complete .exr files any EXR reader opens.
 *
 * Decoders treat their input as hostile: every size is checked, nothing is
 * read past the end, and non-finite decoded values are refused.
 */
#ifndef PROTO_CODEC_H
#define PROTO_CODEC_H

#include <stddef.h>
#include <stdint.h>

#include "ocean_result.h"
#include "proto_buf.h"

typedef enum proto_codec {
    PROTO_CODEC_F32 = 0,
    PROTO_CODEC_F16 = 1,
    PROTO_CODEC_QZ = 2,
    PROTO_CODEC_EXR_ZIP = 3,
    PROTO_CODEC_EXR_PIZ = 4,
    PROTO_CODEC_EXR_B44 = 5,
    PROTO_CODEC_EXR_B44A = 6,
    PROTO_CODEC_COUNT_
} proto_codec;

#define PROTO_CODEC_DEFAULT PROTO_CODEC_QZ
/* Default accuracy target of qz: max abs error / plane range. */
#define PROTO_ACCURACY_DEFAULT 5e-3
#define PROTO_ACCURACY_MIN 1e-6
#define PROTO_ACCURACY_MAX 0.5

/* Channel mask bits of a tile; the order of the bits is the plane order. */
enum proto_channel {
    PROTO_CH_HEIGHT = 1u << 0,   /* plane "H":    surface height eta, m */
    PROTO_CH_DX = 1u << 1,       /* plane "DX":   choppy displacement x, m */
    PROTO_CH_DZ = 1u << 2,       /* plane "DZ":   choppy displacement z, m */
    PROTO_CH_NORMAL = 1u << 3,   /* planes "NU","NV": octahedral unit normal */
    PROTO_CH_FOAM = 1u << 4,     /* plane "FOAM": foam coverage 0..1 */
    PROTO_CH_JACOBIAN = 1u << 5, /* plane "J":    folding Jacobian */
    PROTO_CH_BREAKING = 1u << 6, /* planes "BI","BQ": breaking index and its
                                    quadrature in time (layout 1's foam) */
    PROTO_CH_ALL = 0x7Fu,
    PROTO_CH_WORLD = 0x3Fu       /* the channels a layout-0 tile may carry (no BI BQ) */
};

/* Plane slots, in the fixed plane order; a tile holds those its channels
 * name (proto_tile_plane_offsets). */
enum proto_plane_slot {
    PROTO_SLOT_H, PROTO_SLOT_DX, PROTO_SLOT_DZ, PROTO_SLOT_NU, PROTO_SLOT_NV, PROTO_SLOT_FOAM, PROTO_SLOT_J,
    PROTO_SLOT_BI, PROTO_SLOT_BQ,
    PROTO_SLOT_COUNT
};

#define PROTO_TILE_MAX_SIZE 1024  /* max width and height of a tile */
#define PROTO_TILE_MAX_PLANES PROTO_SLOT_COUNT

typedef struct proto_codec_params {
    double accuracy;     /* qz: max abs error relative to each plane's range,
                            PROTO_ACCURACY_MIN..MAX */
    int zstd_level;      /* qz: zstd level 1..19 (default 3) */
    int zip_level;       /* exr-zip: deflate level 1..9 (default 4) */
} proto_codec_params;

void proto_codec_params_default(proto_codec_params *p);

/* Short stable name ("f32", "f16", "qz", "exr-zip", ...) or "?" if unknown. */
const char *proto_codec_name(proto_codec c);
/* Name -> codec; OCEAN_ETYPE for an unknown name. */
ocean_result proto_codec_parse(const char *name, proto_codec *out);
/* 1 for codecs whose decoded values equal the input bit for bit. */
int proto_codec_lossless(proto_codec c);

/* Number of planes a channel mask makes (the normal counts twice); 0 if the
 * mask is empty or has unknown bits. */
int proto_tile_planes(unsigned channels);
/* Name of plane i ("H", "DX", "DZ", "NU", "NV", "FOAM", "J", "BI", "BQ") of
 * a tile with the given channels, or NULL if i is out of range. */
const char *proto_tile_plane_name(unsigned channels, int i);
/* Where each plane slot of a tile with `channels` starts, in samples of a
 * decoded tile of wh samples a plane (off[slot] = plane index * wh), -1
 * where the tile has no such plane. */
void proto_tile_plane_offsets(unsigned channels, size_t wh, int off[PROTO_SLOT_COUNT]);

/* A-priori bound on |decoded - input| for one plane whose values lie in
 * [lo, hi], for codec c with params p.  0 for lossless codecs.  For qz
 * this is the relative budget (accuracy x range) of the H and J planes;
 * proto_codec_plane_error_bound gives every plane's.  For exr-b44/
 * b44a the bound is loose (B44 can lose up to half of a block's
 * magnitude when a block straddles zero); proto_tile_encode reports the
 * achieved error, which is what TILE messages carry. */
double proto_codec_error_bound(proto_codec c, const proto_codec_params *p, double lo, double hi);

/* The same bound for plane `plane` of a tile with the given channels, as
 * proto_tile_encode applies it: qz (format 2) gives each plane kind its own
 * budget (PROTOCOL.md "qz": H and J accuracy x range; DX, DZ accuracy x
 * max(h_range, own range), h_range being the tile's H plane range, 0 if
 * none; NU, NV accuracy / 2 in octahedral units; FOAM at most half of
 * 1/255).  Other codecs: as proto_codec_error_bound. */
double proto_codec_plane_error_bound(proto_codec c, const proto_codec_params *p, unsigned channels, int plane,
                                     double lo, double hi, double h_range);

/* Encodes planes (proto_tile_planes(channels) planes of w*h floats, plane
 * after plane) and appends the payload to out.  Input values must be finite
 * (OCEAN_EINVAL otherwise); f16 and the half-based EXR codecs refuse values
 * beyond +-65504 (OCEAN_ECODEC).  If max_err is not NULL it receives the
 * largest |decoded - input| over all samples: for lossless codecs 0, for f16
 * and qz the analytic bound, for B44 the measured error (the payload is
 * decoded once to measure it).  On failure out is unchanged and err (if not
 * NULL) names the reason. */
ocean_result proto_tile_encode(proto_codec c, const proto_codec_params *p, int w, int h,
                               unsigned channels, const float *planes, proto_buf *out,
                               double *max_err, char *err, size_t errlen);

/* Per-worker encoder state: the zstd compression context and the scratch
 * planes qz needs, kept between tiles instead of made and freed per call.
 * Not thread-safe: one per encoding thread, created and destroyed by the
 * caller (protocol/ owns no threads).  destroy accepts NULL. */
typedef struct proto_codec_ctx proto_codec_ctx;
ocean_result proto_codec_ctx_create(proto_codec_ctx **out);
void proto_codec_ctx_destroy(proto_codec_ctx *ctx);

/* proto_tile_encode with a context: same payload bytes, same errors; ctx
 * may be NULL (a temporary context is then made for this call). */
ocean_result proto_tile_encode_ctx(proto_codec_ctx *ctx, proto_codec c, const proto_codec_params *p,
                                   int w, int h, unsigned channels, const float *planes,
                                   proto_buf *out, double *max_err, char *err, size_t errlen);

/* Decodes a payload produced for (c, w, h, channels) into planes (caller's
 * array of proto_tile_planes(channels) * w * h floats).  Any inconsistency
 * (size, header, corrupt zstd/EXR data, non-finite value) gives OCEAN_ECODEC
 * (OCEAN_EINVAL for bad arguments, OCEAN_ETYPE for an unknown codec) and a
 * message in err; planes may then hold partial data. */
ocean_result proto_tile_decode(proto_codec c, int w, int h, unsigned channels,
                               const uint8_t *data, size_t len, float *planes,
                               char *err, size_t errlen);

/* One plane of any size up to PROTO_PLANE_MAX_SIZE a side (a wake
 * pattern's coefficients): the blocks of PROTO_TILE_MAX_SIZE^2 samples
 * that cover it, row of blocks after row, each a u32 byte count and its
 * one-plane (H) tile payload of codec c (PROTOCOL.md "WAKE").  max_err as
 * proto_tile_encode's, over every block.  Errors as proto_tile_encode's;
 * decode: OCEAN_ECODEC for any inconsistency. */
#define PROTO_PLANE_MAX_SIZE 4096
ocean_result proto_plane_encode(proto_codec_ctx *ctx, proto_codec c, const proto_codec_params *p, int w, int h,
                                const float *plane, proto_buf *out, double *max_err, char *err, size_t errlen);
ocean_result proto_plane_decode(proto_codec c, int w, int h, const uint8_t *data, size_t len, float *plane,
                                char *err, size_t errlen);

/* IEEE binary16 conversions (round to nearest even; overflow gives +-inf,
 * NaN stays NaN). */
uint16_t proto_f16_from_f32(float f);
float proto_f32_from_f16(uint16_t h);

/* Octahedral unit-vector packing with y up: (nx, ny, nz) -> (u, v) in
 * [-1, 1]^2 and back.  See PROTOCOL.md "Octahedral normals".  The input need
 * not be normalised; a zero vector encodes as straight up. */
void proto_normal_oct_encode(float nx, float ny, float nz, float *u, float *v);
void proto_normal_oct_decode(float u, float v, float *nx, float *ny, float *nz);
/* The slopes d(eta)/dx, d(eta)/dz of the surface whose octahedral normal
 * is (u, v): the inverse of n = normalise(-sx, 1, -sz).  A facet that
 * overhangs or stands vertical (a folded crest: n_y <= |n| / max_slope) is
 * held at slope max_slope, so no reader divides by a vanishing n_y. */
void proto_normal_oct_slopes(float u, float v, float max_slope, float *sx, float *sz);
/* Unit normals of a height field from its slopes d(eta)/dx, d(eta)/dz
 * (n = normalise(-sx, 1, -sz)), packed into the NU, NV planes. */
void proto_normals_from_slopes(const float *sx, const float *sz, size_t n, float *nu, float *nv);

/* Internal: the OpenEXR codecs (proto_exr.c). */
ocean_result proto_exr_encode(proto_codec c, const proto_codec_params *p, int w, int h,
                              unsigned channels, const float *planes, proto_buf *out,
                              char *err, size_t errlen);
ocean_result proto_exr_decode(int w, int h, unsigned channels, const uint8_t *data,
                              size_t len, float *planes, char *err, size_t errlen);

/* ---- compressed mesh positions (PROTOCOL.md "MESH_VERTICES_QZ") ------
 * A layout-0 mesh record with FRAME.has_mesh 2 carries, after mesh_id,
 * vertex_count and origin, this payload: u8 format (1), u8 predictor (1:
 * parallelogram over the topology's triangles), u16 0, f32 base[3],
 * f32 step[3], u8 nbytes[3], u8 0, u32 R, then one zstd frame of R bytes
 * (byte planes of the zigzagged residuals, axis x, y, z).  Decoding needs
 * the MESH_TOPOLOGY the record's mesh_id names (its triangles say which
 * vertices predict which), through proto_mesh_qz_refs. */
#define PROTO_MESH_QZ_FORMAT 1
#define PROTO_MESH_QZ_HEAD 36
#define PROTO_MESH_QZ_NONE 0xFFFFFFFFu

/* The fields of a payload's header (proto_mesh_qz_header). */
typedef struct proto_mesh_qz_info {
    uint8_t format, predictor;
    float base[3], step[3];   /* per axis x, y, z: value = f32(base + q step) */
    uint8_t nbytes[3];
    uint32_t raw_len;         /* R */
} proto_mesh_qz_info;

/* The prediction references of a topology: refs (3 * vertex_count words)
 * gets, per vertex v, (a, b, c) - the parallelogram a + b - c - or (a, b,
 * NONE) - the floor of their mean - or (NONE, NONE, NONE) - the previous
 * vertex (0 for vertex 0); every reference < v.  The rule (PROTOCOL.md):
 * among the triangles holding v, in index-buffer order, whose two other
 * vertices a, b are both < v, the first for which another triangle (the
 * first in index order) holds edge (a, b) with a third vertex c < v; else
 * the first such triangle's midpoint.  Computed once per topology by both
 * sides.  OCEAN_EINVAL for an index >= vertex_count, OCEAN_ENOMEM. */
ocean_result proto_mesh_qz_refs(const uint32_t *indices, uint32_t index_count, uint32_t vertex_count,
                                uint32_t *refs);

/* The encoder's per-axis base (the minimum) and step for positions xyz
 * (3 per vertex) at qz accuracy a: y's step f32(2a . range_y) (the tiles'
 * height budget; 1 m of range for a sea without relief), x and z the same
 * metres, any axis coarser only where it would need 2^29 levels.
 * OCEAN_EINVAL for a bad accuracy, no vertices or a non-finite value. */
ocean_result proto_mesh_qz_steps(double accuracy, uint32_t vertex_count, const float *xyz, float base[3],
                                 float step[3]);

/* The a-priori bound on |decoded - input| of one axis (0 x, 1 y, 2 z):
 * step/2 plus the f32 rounding of the decoded value. */
double proto_mesh_qz_error_bound(const float base[3], const float step[3], uint32_t vertex_count, const float *xyz,
                                 int axis);

/* Appends the payload (from the format byte on) for positions xyz of
 * vertex_count vertices with the topology's refs, at accuracy, using the
 * worker's ctx (required: a server encodes a mesh per frame).  max_err
 * (may be NULL) gets the largest |decoded - input| per axis.  On failure
 * out is unchanged. */
ocean_result proto_mesh_qz_encode(proto_codec_ctx *ctx, double accuracy, uint32_t vertex_count, const float *xyz,
                                  const uint32_t *refs, proto_buf *out, double max_err[3], char *err,
                                  size_t errlen);

/* Checks a payload's header against vertex_count without decompressing:
 * format, predictor, reserved bytes, finite bases, finite steps > 0,
 * nbytes <= 4, R = sum nbytes . vertex_count, one zstd frame of exactly R
 * bytes and nothing after it.  OCEAN_ECODEC naming the field. */
ocean_result proto_mesh_qz_header(const uint8_t *data, size_t len, uint32_t vertex_count, proto_mesh_qz_info *info,
                                  char *err, size_t errlen);

/* Decodes a payload into xyz (3 * vertex_count floats) with the refs of
 * its topology.  OCEAN_ECODEC for a bad header or stream, a level beyond
 * 2^30, a non-finite or |.| > 1e7 position; OCEAN_EINVAL for refs that
 * point at vertices not yet decoded. */
ocean_result proto_mesh_qz_decode(const uint8_t *data, size_t len, uint32_t vertex_count, const uint32_t *refs,
                                  float *xyz, char *err, size_t errlen);

#endif
