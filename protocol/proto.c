/*
 * proto.c - encoder and decoder of the ocean.v1 messages (see PROTOCOL.md).
 *
 * One validation path serves both directions: the decoder first checks the
 * structure of the bytes (lengths, counts, reserved fields) while copying
 * them into a proto_msg, then runs the same per-type validator the encoder
 * runs before writing.  So an encoder can never emit what a decoder refuses,
 * and the tests of one cover the other.
 */
#include "proto.h"
#include "ocean_time.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Wire sizes of the fixed parts (PROTOCOL.md tables). */
#define SEA_SIZE 96
#define HELLO_FIXED (32 + SEA_SIZE)
#define SUBSCRIBE_SIZE 28
#define CAMERA_SIZE 64
#define TILE_FIXED 48
#define FRAME_FIXED 56
#define RECORD_HEAD 8
#define TOPO_FIXED 16
#define VERTS_FIXED 32
#define QUERY_FIXED 24
#define RESULT_FIXED 16
#define SAMPLE_SIZE 36
#define SEASTATE_FIXED (16 + SEA_SIZE)
#define ERROR_FIXED 8
#define BYE_FIXED 4
#define ENTITY_FIXED 56
#define WAKE_FIXED 48

/* Coordinates beyond these are absurd for a sea on this planet. */
#define MAX_WORLD 1e10
#define MAX_LOCAL 1e7
/* What the server derives from a camera within MAX_WORLD (tile, frame,
 * mesh and placement origins) reaches past it by what one frame covers:
 * the view range and the coarsest tile, each at most MAX_LOCAL.  Bounded
 * at MAX_WORLD, they would leave a camera near x = -1e10 without frames. */
#define MAX_ORIGIN (MAX_WORLD + 2 * MAX_LOCAL)

static const char *const type_names[PROTO_TYPE_END_] = {
    "?", "HELLO", "SUBSCRIBE", "CAMERA", "FRAME", "TILE", "MESH_TOPOLOGY", "MESH_VERTICES",
    "QUERY", "QUERY_RESULT", "SEA_STATE", "ERROR", "BYE", "ENTITY", "WAKE"};

const char *proto_type_name(unsigned type)
{
    return (type >= 1 && type < PROTO_TYPE_END_) ? type_names[type] : "?";
}

void proto_limits_default(proto_limits *l)
{
    l->max_message = PROTO_MAX_MESSAGE_DEFAULT;
    l->max_query_points = PROTO_MAX_QUERY_POINTS;
    l->max_frame_tiles = PROTO_MAX_FRAME_TILES;
    l->max_vertices = PROTO_MAX_VERTICES;
    l->max_indices = PROTO_MAX_INDICES;
}

void proto_msg_init(proto_msg *m, proto_type type)
{
    memset(m, 0, sizeof *m);
    m->hdr.version = PROTO_VERSION;
    m->hdr.type = (uint16_t)type;
}

void proto_msg_free(proto_msg *m)
{
    if (!m)
        return;
    free(m->owned_);
    memset(m, 0, sizeof *m);
}

/* ---- shared validation ------------------------------------------------ */

typedef struct ctx {
    char *err;
    size_t errlen;
    const proto_limits *lim;
} ctx;

#define FAIL(c, code, ...) do { ocean_seterr((c)->err, (c)->errlen, __VA_ARGS__); return (code); } while (0)
#define TRY(x) do { ocean_result r_ = (x); if (r_ != OCEAN_OK) return r_; } while (0)

static ocean_result chk_range(ctx *c, const char *what, double v, double lo, double hi)
{
    if (!isfinite(v))
        FAIL(c, OCEAN_EINVAL, "%s is %g; must be finite", what, v);
    if (v < lo || v > hi)
        FAIL(c, OCEAN_EINVAL, "%s = %g outside [%g, %g]", what, v, lo, hi);
    return OCEAN_OK;
}

/* Times: the one limit of ocean_time.h (OCEAN_TIME_MAX), named in the message. */
static ocean_result chk_time(ctx *c, const char *what, double v)
{
    char m[256];
    if (ocean_time_check(v, what, m, sizeof m) != OCEAN_OK)
        FAIL(c, OCEAN_EINVAL, "%s", m);
    return OCEAN_OK;
}

static ocean_result chk_mask(ctx *c, const char *what, uint32_t v, uint32_t allowed)
{
    if (v & ~allowed)
        FAIL(c, OCEAN_ETYPE, "%s 0x%x has unknown bits 0x%x", what, v, v & ~allowed);
    return OCEAN_OK;
}

static ocean_result chk_enum(ctx *c, const char *what, unsigned v, unsigned count)
{
    if (v >= count)
        FAIL(c, OCEAN_ETYPE, "%s %u unknown (valid 0..%u)", what, v, count - 1);
    return OCEAN_OK;
}

/* 1 if s[0..n) is UTF-8 without NUL, overlongs or surrogates. */
static int utf8_ok(const uint8_t *s, size_t n)
{
    size_t i = 0;
    while (i < n) {
        uint8_t b = s[i];
        if (b == 0)
            return 0;
        if (b < 0x80) {
            i++;
            continue;
        }
        int len;
        uint32_t cp;
        if ((b & 0xE0) == 0xC0) len = 2, cp = b & 0x1F;
        else if ((b & 0xF0) == 0xE0) len = 3, cp = b & 0x0F;
        else if ((b & 0xF8) == 0xF0) len = 4, cp = b & 0x07;
        else return 0;
        if (n - i < (size_t)len)
            return 0;
        for (int k = 1; k < len; k++) {
            if ((s[i + k] & 0xC0) != 0x80)
                return 0;
            cp = (cp << 6) | (s[i + k] & 0x3F);
        }
        if ((len == 2 && cp < 0x80) || (len == 3 && cp < 0x800) || (len == 4 && cp < 0x10000) ||
            cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF))
            return 0;
        i += (size_t)len;
    }
    return 1;
}

static ocean_result chk_str(ctx *c, const char *what, const char *s, size_t max)
{
    size_t n = strnlen(s, max + 1);
    if (n > max)
        FAIL(c, OCEAN_ETOOBIG, "%s longer than %zu bytes", what, max);
    if (!utf8_ok((const uint8_t *)s, n))
        FAIL(c, OCEAN_EFORMAT, "%s is not valid UTF-8", what);
    return OCEAN_OK;
}

static ocean_result v_sea(ctx *c, const proto_sea *s)
{
    TRY(chk_enum(c, "sea.spectrum", s->spectrum, 4));
    TRY(chk_enum(c, "sea.spreading", s->spreading, 4));
    TRY(chk_mask(c, "sea.flags", s->flags, PROTO_SEA_FLAGS_ALL));
    TRY(chk_range(c, "sea.wind_u10", s->wind_u10, 0, 100));
    TRY(chk_range(c, "sea.wind_dir_deg", s->wind_dir_deg, -360, 360));
    TRY(chk_range(c, "sea.fetch_m", s->fetch_m, 1, 1e7));
    TRY(chk_range(c, "sea.depth_m", s->depth_m, 0.01, 12000));
    TRY(chk_range(c, "sea.swell", s->swell, 0, 1000));
    TRY(chk_range(c, "sea.phillips_a", s->phillips_a, 0, 1e6));
    TRY(chk_range(c, "sea.small_wave_m", s->small_wave_m, 0, 1e4));
    TRY(chk_range(c, "sea.choppiness", s->choppiness, 0, 10));
    TRY(chk_range(c, "sea.hs", s->hs, 0, 1000));
    TRY(chk_range(c, "sea.tp", s->tp, 0, 1e4));
    return OCEAN_OK;
}

static ocean_result v_hello(ctx *c, const proto_hello *h)
{
    TRY(chk_mask(c, "hello.codecs", h->codecs, (1u << PROTO_CODEC_COUNT_) - 1));
    TRY(chk_mask(c, "hello.mesh_kinds", h->mesh_kinds, (1u << PROTO_MESH_KIND_COUNT_) - 1));
    TRY(chk_mask(c, "hello.effects", h->effects, PROTO_FX_ALL));
    TRY(chk_mask(c, "hello.cutoff_policies", h->cutoff_policies, (1u << PROTO_CUTOFF_POLICY_COUNT_) - 1));
    TRY(chk_mask(c, "hello.modes", h->modes, (1u << PROTO_MODE_COUNT_) - 1));
    if (!h->codecs || !h->modes)
        FAIL(c, OCEAN_EINVAL, "hello announces no codec or no mode");
    if (h->max_message < PROTO_HEADER_SIZE)
        FAIL(c, OCEAN_EINVAL, "hello.max_message %u below the header size", h->max_message);
    TRY(chk_range(c, "hello.max_tile_size", h->max_tile_size, 2, PROTO_TILE_MAX_SIZE));
    TRY(chk_range(c, "hello.max_lod_levels", h->max_lod_levels, 1, PROTO_MAX_LOD_LEVELS));
    TRY(chk_range(c, "hello.max_layers", h->max_layers, 1, PROTO_MAX_LAYERS));
    TRY(chk_range(c, "hello.tick_rate_hz", h->tick_rate_hz, 1e-3, 1000));
    TRY(chk_range(c, "hello.max_frame_rate_hz", h->max_frame_rate_hz, 1e-3, PROTO_MAX_FRAME_RATE));
    TRY(v_sea(c, &h->sea));
    return chk_str(c, "hello.server_version", h->server_version, PROTO_VERSION_STR_MAX);
}

static ocean_result v_subscribe(ctx *c, const proto_subscribe *s)
{
    TRY(chk_mask(c, "subscribe.effects", s->effects, PROTO_FX_ALL));
    if (!s->effects)
        FAIL(c, OCEAN_EINVAL, "subscribe.effects is empty");
    TRY(chk_enum(c, "subscribe.mesh_kind", s->mesh_kind, PROTO_MESH_KIND_COUNT_));
    TRY(chk_enum(c, "subscribe.codec", s->codec, PROTO_CODEC_COUNT_));
    TRY(chk_enum(c, "subscribe.cutoff_policy", s->cutoff_policy, PROTO_CUTOFF_POLICY_COUNT_));
    TRY(chk_enum(c, "subscribe.mode", s->mode, PROTO_MODE_COUNT_));
    TRY(chk_range(c, "subscribe.layers", s->layers, 1, PROTO_MAX_LAYERS));
    TRY(chk_range(c, "subscribe.lod_levels", s->lod_levels, 1, PROTO_MAX_LOD_LEVELS));
    TRY(chk_enum(c, "subscribe.layout", s->layout, PROTO_LAYOUT_COUNT_));
    if (s->mesh_codec != PROTO_MESH_CODEC_F32 && s->mesh_codec != PROTO_MESH_CODEC_QZ)
        FAIL(c, OCEAN_ETYPE, "subscribe.mesh_codec %u unknown (0 f32, 2 qz)", s->mesh_codec);
    if (s->flags & ~(unsigned)PROTO_SUB_FLAGS_ALL)
        FAIL(c, OCEAN_EFORMAT, "subscribe.flags 0x%x has unknown bits (bit 0: full geometry, bit 1: time interpolation)", s->flags);
    TRY(chk_range(c, "subscribe.tile_size", s->tile_size, 2, PROTO_TILE_MAX_SIZE));
    TRY(chk_range(c, "subscribe.frame_rate_hz", s->frame_rate_hz, 0, PROTO_MAX_FRAME_RATE));
    if (s->frame_rate_hz <= 0.0f)
        FAIL(c, OCEAN_EINVAL, "subscribe.frame_rate_hz must be > 0");
    TRY(chk_range(c, "subscribe.accuracy", s->accuracy, (float)PROTO_ACCURACY_MIN, PROTO_ACCURACY_MAX));
    if (s->base_spacing_m != 0.0f)
        TRY(chk_range(c, "subscribe.base_spacing_m", s->base_spacing_m, 1e-3, 1e4));
    if (s->view_range_m != 0.0f)
        TRY(chk_range(c, "subscribe.view_range_m", s->view_range_m, 1, 1e7));
    return OCEAN_OK;
}

static ocean_result v_camera(ctx *c, const proto_camera *k)
{
    TRY(chk_range(c, "camera.pos.x", k->pos[0], -MAX_WORLD, MAX_WORLD));
    TRY(chk_range(c, "camera.pos.y", k->pos[1], -MAX_LOCAL, MAX_LOCAL));
    TRY(chk_range(c, "camera.pos.z", k->pos[2], -MAX_WORLD, MAX_WORLD));
    for (int i = 0; i < 3; i++)
        TRY(chk_range(c, "camera.velocity", k->vel[i], -1e5, 1e5));
    TRY(chk_range(c, "camera.yaw_deg", k->yaw_deg, -360, 360));
    TRY(chk_range(c, "camera.pitch_deg", k->pitch_deg, -90, 90));
    TRY(chk_range(c, "camera.roll_deg", k->roll_deg, -180, 180));
    TRY(chk_range(c, "camera.fov_y_deg", k->fov_y_deg, 0, 180));
    if (k->fov_y_deg <= 0.0f || k->fov_y_deg >= 180.0f)
        FAIL(c, OCEAN_EINVAL, "camera.fov_y_deg = %g outside (0, 180)", (double)k->fov_y_deg);
    TRY(chk_range(c, "camera.viewport_w", k->viewport_w, 1, 16384));
    TRY(chk_range(c, "camera.viewport_h", k->viewport_h, 1, 16384));
    return chk_time(c, "camera.render_time", k->render_time);
}

static ocean_result v_tile(ctx *c, const proto_tile *t)
{
    TRY(chk_range(c, "tile.level", t->level, 0, PROTO_MAX_LEVEL));
    TRY(chk_enum(c, "tile.codec", t->codec, PROTO_CODEC_COUNT_));
    TRY(chk_mask(c, "tile.channels", t->channels, PROTO_CH_ALL));
    if (!t->channels)
        FAIL(c, OCEAN_EINVAL, "tile.channels is empty");
    TRY(chk_range(c, "tile.width", t->width, 1, PROTO_TILE_MAX_SIZE));
    TRY(chk_range(c, "tile.height", t->height, 1, PROTO_TILE_MAX_SIZE));
    TRY(chk_range(c, "tile.origin_x", t->origin_x, -MAX_ORIGIN, MAX_ORIGIN));
    TRY(chk_range(c, "tile.origin_z", t->origin_z, -MAX_ORIGIN, MAX_ORIGIN));
    TRY(chk_range(c, "tile.spacing", t->spacing, 0, PROTO_TILE_SPACING_MAX));
    if (!(t->spacing > 0))
        FAIL(c, OCEAN_EINVAL, "tile.spacing must be > 0");
    TRY(chk_range(c, "tile.error_bound", t->error_bound, 0, 1e30));
    if (t->payload_len && !t->payload)
        FAIL(c, OCEAN_EINVAL, "tile has payload_len %u but no payload", t->payload_len);
    if (t->codec == PROTO_CODEC_F32 || t->codec == PROTO_CODEC_F16) {
        uint64_t want = (uint64_t)proto_tile_planes(t->channels) * t->width * t->height *
                        (t->codec == PROTO_CODEC_F32 ? 4u : 2u);
        if (want != t->payload_len)
            FAIL(c, OCEAN_EFORMAT, "tile %s payload is %u bytes, %ux%u with %d planes needs %llu",
                 proto_codec_name((proto_codec)t->codec), t->payload_len, t->width, t->height,
                 proto_tile_planes(t->channels), (unsigned long long)want);
    } else if (t->payload_len == 0) {
        FAIL(c, OCEAN_EFORMAT, "tile payload is empty");
    }
    return OCEAN_OK;
}

/* A FRAME's has_mesh 2 record: the counts and origin as MESH_VERTICES,
 * then the qz payload's header (the positions need the topology). */
static ocean_result v_vertices_head(ctx *c, const proto_mesh_vertices *v)
{
    if (v->vertex_count == 0)
        FAIL(c, OCEAN_EINVAL, "mesh vertex_count is 0");
    if (v->vertex_count > c->lim->max_vertices)
        FAIL(c, OCEAN_ETOOBIG, "mesh vertex_count %u above the limit %u", v->vertex_count, c->lim->max_vertices);
    for (int i = 0; i < 3; i++)
        TRY(chk_range(c, "mesh.origin", v->origin[i], -MAX_ORIGIN, MAX_ORIGIN));
    return OCEAN_OK;
}

static ocean_result v_vertices_qz(ctx *c, const proto_mesh_vertices *v)
{
    TRY(v_vertices_head(c, v));
    char why[200];
    ocean_result r = proto_mesh_qz_header(v->qz, v->qz_len, v->vertex_count, NULL, why, sizeof why);
    if (r != OCEAN_OK)
        FAIL(c, r, "frame mesh (has_mesh 2): %s", why);
    return OCEAN_OK;
}

static ocean_result v_vertices(ctx *c, const proto_mesh_vertices *v)
{
    TRY(v_vertices_head(c, v));
    if (!v->positions)
        FAIL(c, OCEAN_EINVAL, "mesh has no positions");
    for (size_t i = 0; i < 3 * (size_t)v->vertex_count; i++)
        if (!isfinite(v->positions[i]) || fabsf(v->positions[i]) > (float)MAX_LOCAL)
            FAIL(c, OCEAN_EINVAL, "mesh position component %zu is %g (finite, |v| <= 1e7 required)", i,
                 (double)v->positions[i]);
    return OCEAN_OK;
}

/* The whitecap table: rows with the FOAM flag alone, sigma ascending. */
static ocean_result v_foam_table(ctx *c, const proto_cascade_block *b)
{
    unsigned rows = (b->flags & PROTO_CASCADE_FOAM) ? b->foam_rows : 0;
    if ((b->flags & PROTO_CASCADE_FOAM) && (rows < 1 || rows > PROTO_FOAM_ROWS))
        FAIL(c, OCEAN_EINVAL, "frame.cascades.foam_rows = %u; must be 1..%d", b->foam_rows, PROTO_FOAM_ROWS);
    if (!(b->flags & PROTO_CASCADE_FOAM) && b->foam_rows)
        FAIL(c, OCEAN_EFORMAT, "frame.cascades.foam_rows = %u without the FOAM flag", b->foam_rows);
    for (unsigned i = 0; i < PROTO_FOAM_ROWS; i++) {
        const proto_foam_row *r = &b->foam[i];
        if (i >= rows) {
            if (r->sigma != 0.0f || r->a != 0.0f || r->omega != 0.0f)
                FAIL(c, OCEAN_EFORMAT, "frame.cascades.foam[%u] beyond foam_rows %u must be 0", i, rows);
            continue;
        }
        if (!(r->sigma >= 0.0f && r->sigma <= 1e3f) || (i > 0 && !(r->sigma > b->foam[i - 1].sigma)))
            FAIL(c, OCEAN_EINVAL, "frame.cascades.foam[%u].sigma = %g; must be in [0, 1e3] and ascend", i,
                 (double)r->sigma);
        if (!(r->a >= -1e3f && r->a <= 0.5f))
            FAIL(c, OCEAN_EINVAL, "frame.cascades.foam[%u].a = %g; must be in [-1e3, 0.5]", i, (double)r->a);
        if (!(r->omega >= 0.0f && r->omega <= 1e3f))
            FAIL(c, OCEAN_EINVAL, "frame.cascades.foam[%u].omega = %g; must be in [0, 1e3]", i, (double)r->omega);
    }
    return OCEAN_OK;
}

/* The read table: with READ (and FOAM), every mip that holds waves has a
 * share for each kernel; everything else 0. */
static ocean_result v_read_table(ctx *c, const proto_cascade_block *b)
{
    if ((b->flags & PROTO_CASCADE_READ) && !(b->flags & PROTO_CASCADE_FOAM))
        FAIL(c, OCEAN_EFORMAT, "frame.cascades: the READ flag without FOAM (the read table serves the whitecap ramp)");
    for (unsigned k = 0; k < PROTO_MAX_LAYERS; k++)
        for (int m = 0; m < PROTO_MIP_ENTRIES; m++)
            for (int r = 0; r < PROTO_READ_KERNELS; r++) {
                unsigned v = b->cascade[k].mip[m].held[r];
                int given = (b->flags & PROTO_CASCADE_READ) && k < b->cascade_count && m < b->cascade[k].mips;
                if (given ? v == 0 : v != 0)
                    FAIL(c, given ? OCEAN_EINVAL : OCEAN_EFORMAT,
                         "frame.cascades[%u].mip[%d].held[%d] = %u; must be %s", k, m, r, v,
                         given ? "1..65535" : "0 (no READ flag, or beyond mips)");
            }
    return OCEAN_OK;
}

static ocean_result v_cascades(ctx *c, const proto_cascade_block *b)
{
    TRY(chk_range(c, "frame.cascades.cascade_count", b->cascade_count, 1, PROTO_MAX_LAYERS));
    TRY(chk_range(c, "frame.cascades.order", b->order, 1, 64));
    if (b->flags & ~(PROTO_CASCADE_KEY | PROTO_CASCADE_FOAM | PROTO_CASCADE_READ))
        FAIL(c, OCEAN_EFORMAT, "frame.cascades.flags is %u (bits 0-2 only)", b->flags);
    TRY(v_foam_table(c, b));
    TRY(v_read_table(c, b));
    if (!(b->spacing_per_m > 0.0f) || !isfinite(b->spacing_per_m))
        FAIL(c, OCEAN_EINVAL, "frame.cascades.spacing_per_m = %g; must be finite and > 0",
             (double)b->spacing_per_m);
    for (int i = 0; i < 3; i++)
        TRY(chk_range(c, "frame.cascades.camera", b->camera[i], -MAX_WORLD, MAX_WORLD));
    TRY(chk_range(c, "frame.cascades.min_spacing_m", b->min_spacing_m, 0, 1e6));
    TRY(chk_range(c, "frame.cascades.e_total", b->e_total, 0, 1));
    TRY(chk_range(c, "frame.cascades.tail_mss_x", b->tail_mss[0], 0, 1e3));
    TRY(chk_range(c, "frame.cascades.tail_mss_z", b->tail_mss[1], 0, 1e3));
    TRY(chk_range(c, "frame.cascades.tail_mss_xz", b->tail_mss[2], -1e3, 1e3));
    TRY(chk_range(c, "frame.cascades.geometry_spacing_m", b->geometry_spacing_m, 0, 1e6));
    for (unsigned k = 0; k < b->cascade_count; k++) {
        const proto_cascade_entry *e = &b->cascade[k];
        TRY(chk_range(c, "frame.cascades.patch_m", e->patch_m, 1e-3, 1e7));
        if (e->n < 8 || e->n > 2048 || (e->n & (e->n - 1)))
            FAIL(c, OCEAN_EINVAL, "frame.cascades[%u].n = %u; must be a power of two in 8..2048", k, e->n);
        TRY(chk_range(c, "frame.cascades.mips", e->mips, 1, PROTO_MAX_MIPS));
        if (e->fades > 1)
            FAIL(c, OCEAN_EFORMAT, "frame.cascades[%u].fades is %u (0 or 1)", k, e->fades);
        if ((e->n >> (e->mips - 1)) < 1)
            FAIL(c, OCEAN_EINVAL, "frame.cascades[%u]: %u mips of a %u grid", k, e->mips, e->n);
        if (!(e->spacing_per_m > 0.0f) || !(e->spacing_per_m <= b->spacing_per_m))
            FAIL(c, OCEAN_EINVAL, "frame.cascades[%u].spacing_per_m = %g; must be > 0 and <= the block's %g", k,
                 (double)e->spacing_per_m, (double)b->spacing_per_m);
        for (int m = 0; m < PROTO_MIP_ENTRIES; m++) {
            const proto_mip_entry *q = &b->cascade[k].mip[m];
            if (m > e->mips) {
                if (q->kc != 0.0f || q->mss_x != 0.0f || q->mss_z != 0.0f || q->mss_xz != 0.0f)
                    FAIL(c, OCEAN_EFORMAT, "frame.cascades[%u].mip[%d] beyond mips %u must be 0", k, m, e->mips);
                continue;
            }
            if (m == e->mips ? q->kc != 0.0f : !(q->kc > 0.0f))
                FAIL(c, OCEAN_EINVAL, "frame.cascades[%u].mip[%d].kc = %g (mips %u)", k, m, (double)q->kc,
                     e->mips);
            if (!(q->mss_x >= 0.0f && q->mss_x <= 1e3f) || !(q->mss_z >= 0.0f && q->mss_z <= 1e3f) ||
                !(q->mss_xz >= -1e3f && q->mss_xz <= 1e3f))
                FAIL(c, OCEAN_EINVAL, "frame.cascades[%u].mip[%d] slope moments %g %g %g out of range", k, m,
                     (double)q->mss_x, (double)q->mss_z, (double)q->mss_xz);
        }
        for (int m = 0; m < PROTO_MAX_MIPS; m++) {
            const proto_mip_time *t = &e->time[m];
            if ((m >= e->mips || !t->interval) && (t->tick_a || t->interval || t->phase))
                FAIL(c, OCEAN_EFORMAT, "frame.cascades[%u].time[%d] must be 0 (%s)", k, m,
                     m >= e->mips ? "beyond mips" : "interval 0");
        }
    }
    for (unsigned k = b->cascade_count; k < PROTO_MAX_LAYERS; k++) {
        static const proto_cascade_entry zero;
        if (memcmp(&b->cascade[k], &zero, sizeof zero) != 0)
            FAIL(c, OCEAN_EINVAL, "frame.cascades[%u] beyond cascade_count %u is not empty", k, b->cascade_count);
    }
    return OCEAN_OK;
}

/* A pre-encoded tile record: its own framing (length, tag, padding) and a
 * tag that fits the frame's layout.  Its TILE body was validated when
 * proto_tile_record_encode made it. */
static ocean_result v_record_bytes(ctx *c, const proto_bytes *rec, const proto_frame *f)
{
    if (!rec->p || rec->len < RECORD_HEAD + TILE_FIXED || (rec->len & 7u))
        FAIL(c, OCEAN_EINVAL, "frame tile record of %zu bytes is not a record", rec->len);
    size_t blen = proto_ld32(rec->p);
    uint32_t tag = f->record_tags ? f->record_tags[rec - f->tile_records] : proto_ld32(rec->p + 4);
    if (RECORD_HEAD + blen + ((8u - (blen & 7u)) & 7u) != rec->len)
        FAIL(c, OCEAN_EINVAL, "frame tile record length %zu does not match its %zu bytes", blen, rec->len);
    if (f->layout == PROTO_LAYOUT_CASCADE ? (tag & ~(0xFFu | PROTO_TAG_SLOT_B)) || (tag & 0xFFu) >= f->cascades.cascade_count
                                          : tag != 0)
        FAIL(c, OCEAN_EINVAL, "frame tile record tag %u (layout %u, %u cascades)", tag, f->layout,
             f->cascades.cascade_count);
    if (tag & PROTO_TAG_SLOT_B) {
        unsigned level = rec->p[RECORD_HEAD];
        const proto_cascade_entry *e = &f->cascades.cascade[tag & 0xFFu];
        if (level >= e->mips || !e->time[level].interval)
            FAIL(c, OCEAN_EINVAL, "frame tile record: sample B of mip %u, which has no time interval", level);
    }
    return OCEAN_OK;
}

static ocean_result v_frame(ctx *c, const proto_frame *f)
{
    if (isnan(f->cutoff_k) || f->cutoff_k < 0)
        FAIL(c, OCEAN_EINVAL, "frame.cutoff_k = %g; must be >= 0 (or +inf)", f->cutoff_k);
    TRY(chk_range(c, "frame.e_error", f->e_error, 0, 1));
    for (int i = 0; i < 3; i++)
        TRY(chk_range(c, "frame.origin", f->origin[i], -MAX_ORIGIN, MAX_ORIGIN));
    if (f->tile_count > c->lim->max_frame_tiles)
        FAIL(c, OCEAN_ETOOBIG, "frame.tile_count %u above the limit %u", f->tile_count, c->lim->max_frame_tiles);
    if (f->tile_count && !f->tiles && !f->tile_records)
        FAIL(c, OCEAN_EINVAL, "frame has tile_count %u but no tiles", f->tile_count);
    TRY(chk_enum(c, "frame.layout", f->layout, PROTO_LAYOUT_COUNT_));
    if (f->layout == PROTO_LAYOUT_CASCADE)
        TRY(v_cascades(c, &f->cascades));
    if (f->tile_records) {
        for (unsigned i = 0; i < f->tile_count; i++)
            TRY(v_record_bytes(c, &f->tile_records[i], f));
    } else {
        for (unsigned i = 0; i < f->tile_count; i++) {
            TRY(v_tile(c, &f->tiles[i]));
            if (f->layout == PROTO_LAYOUT_CASCADE ? f->tiles[i].cascade >= f->cascades.cascade_count
                                                  : f->tiles[i].cascade != 0)
                FAIL(c, OCEAN_EINVAL, "frame tile %u: cascade %u (layout %u, %u cascades)", i,
                     f->tiles[i].cascade, f->layout, f->cascades.cascade_count);
            const proto_tile *t = &f->tiles[i];
            if (t->slot && (f->layout != PROTO_LAYOUT_CASCADE || t->slot > 1 ||
                            t->level >= f->cascades.cascade[t->cascade].mips ||
                            !f->cascades.cascade[t->cascade].time[t->level].interval))
                FAIL(c, OCEAN_EINVAL, "frame tile %u: sample B of a mip without a time interval", i);
        }
    }
    if (f->has_mesh > 2 || (f->has_mesh == 2 && f->layout != PROTO_LAYOUT_WORLD))
        FAIL(c, OCEAN_EFORMAT, "frame.has_mesh is %u (0 or 1; 2 in layout 0)", f->has_mesh);
    if (f->has_mesh == 1 && f->layout == PROTO_LAYOUT_WORLD)
        TRY(v_vertices(c, &f->mesh));
    if (f->has_mesh == 2)
        TRY(v_vertices_qz(c, &f->mesh));
    if (f->has_mesh && f->layout == PROTO_LAYOUT_CASCADE)
        for (int i = 0; i < 3; i++)
            TRY(chk_range(c, "frame.placement.origin", f->placement.origin[i], -MAX_ORIGIN, MAX_ORIGIN));
    return OCEAN_OK;
}

static ocean_result v_topology(ctx *c, const proto_mesh_topology *t)
{
    if (t->mesh_kind >= PROTO_MESH_NONE)
        FAIL(c, OCEAN_ETYPE, "mesh_topology.mesh_kind %u unknown (0..2)", t->mesh_kind);
    TRY(chk_range(c, "mesh_topology.lod_levels", t->lod_levels, 1, PROTO_MAX_LOD_LEVELS));
    if (t->vertex_count == 0 || t->index_count == 0)
        FAIL(c, OCEAN_EINVAL, "mesh_topology has %u vertices and %u indices", t->vertex_count, t->index_count);
    if (t->vertex_count > c->lim->max_vertices || t->index_count > c->lim->max_indices)
        FAIL(c, OCEAN_ETOOBIG, "mesh_topology %u vertices / %u indices above the limits %u / %u",
             t->vertex_count, t->index_count, c->lim->max_vertices, c->lim->max_indices);
    if (t->index_count % 3)
        FAIL(c, OCEAN_EFORMAT, "mesh_topology.index_count %u is not a multiple of 3", t->index_count);
    if (!t->indices || !t->morph || !t->level)
        FAIL(c, OCEAN_EINVAL, "mesh_topology arrays missing");
    for (uint32_t i = 0; i < t->index_count; i++)
        if (t->indices[i] >= t->vertex_count)
            FAIL(c, OCEAN_EINVAL, "mesh_topology index %u = %u >= vertex_count %u", i, t->indices[i], t->vertex_count);
    for (uint32_t i = 0; i < t->vertex_count; i++) {
        if (!(t->morph[i] >= 0.0f && t->morph[i] <= 1.0f))
            FAIL(c, OCEAN_EINVAL, "mesh_topology morph[%u] = %g outside [0, 1]", i, (double)t->morph[i]);
        if (t->level[i] >= t->lod_levels)
            FAIL(c, OCEAN_EINVAL, "mesh_topology level[%u] = %u >= lod_levels %u", i, t->level[i], t->lod_levels);
    }
    if (t->flags & ~PROTO_TOPO_FLAT)
        FAIL(c, OCEAN_EFORMAT, "mesh_topology.flags 0x%x has unknown bits", t->flags);
    if (t->flags & PROTO_TOPO_FLAT) {
        if (!t->flat || !t->zones)
            FAIL(c, OCEAN_EINVAL, "mesh_topology FLAT arrays missing");
        for (size_t i = 0; i < 2 * (size_t)t->vertex_count; i++)
            if (!(fabsf(t->flat[i]) <= (float)MAX_LOCAL))
                FAIL(c, OCEAN_EINVAL, "mesh_topology flat[%zu] = %g (finite, |.| <= 1e7)", i, (double)t->flat[i]);
        for (unsigned L = 0; L < t->lod_levels; L++) {
            const float *z = t->zones + 4 * L;
            if (!(z[0] > 0.0f && z[0] <= 1e7f) || !(z[1] >= 0.0f && z[1] <= 1e8f) ||
                !(z[2] >= 0.0f && z[2] <= 1e8f) || z[3] != 0.0f)
                FAIL(c, OCEAN_EINVAL, "mesh_topology zone %u = (%g, %g, %g, %g) out of range", L, (double)z[0],
                     (double)z[1], (double)z[2], (double)z[3]);
            /* the morph rule slides odd vertices half a coarse cell: it
             * holds for lattices that double, and turns triangles over
             * where one is four times the one inside it */
            if (L > 0 && z[0] != 2.0f * z[-4])
                FAIL(c, OCEAN_EINVAL, "mesh_topology zone %u lattice %g is not twice zone %u's %g", L, (double)z[0],
                     L - 1, (double)z[-4]);
        }
    }
    return OCEAN_OK;
}

static ocean_result v_query(ctx *c, const proto_query *q)
{
    if (q->count == 0)
        FAIL(c, OCEAN_EINVAL, "query.count is 0");
    if (q->count > c->lim->max_query_points)
        FAIL(c, OCEAN_ETOOBIG, "query.count %u above the limit %u", q->count, c->lim->max_query_points);
    TRY(chk_enum(c, "query.at_time", q->at_time, 2));
    TRY(chk_time(c, "query.t", q->t));
    if (!q->points)
        FAIL(c, OCEAN_EINVAL, "query has no points");
    for (size_t i = 0; i < 2 * (size_t)q->count; i++)
        if (!isfinite(q->points[i]) || fabs(q->points[i]) > MAX_WORLD)
            FAIL(c, OCEAN_EINVAL, "query point %zu %s = %g (finite, |v| <= 1e10 required)", i / 2,
                 (i & 1) ? "z" : "x", q->points[i]);
    return OCEAN_OK;
}

static ocean_result v_result(ctx *c, const proto_query_result *r)
{
    if (r->count == 0)
        FAIL(c, OCEAN_EINVAL, "query_result.count is 0");
    if (r->count > c->lim->max_query_points)
        FAIL(c, OCEAN_ETOOBIG, "query_result.count %u above the limit %u", r->count, c->lim->max_query_points);
    TRY(chk_time(c, "query_result.t", r->t));
    if (!r->samples)
        FAIL(c, OCEAN_EINVAL, "query_result has no samples");
    for (uint32_t i = 0; i < r->count; i++) {
        const proto_query_sample *s = &r->samples[i];
        float v[9] = {s->height, s->normal[0], s->normal[1], s->normal[2], s->velocity[0],
                      s->velocity[1], s->velocity[2], s->foam, s->error_bound};
        for (int k = 0; k < 9; k++)
            if (!isfinite(v[k]))
                FAIL(c, OCEAN_EINVAL, "query_result sample %u field %d is not finite", i, k);
        if (s->foam < 0.0f || s->foam > 1.0f || s->error_bound < 0.0f)
            FAIL(c, OCEAN_EINVAL, "query_result sample %u: foam %g / error_bound %g out of range", i,
                 (double)s->foam, (double)s->error_bound);
    }
    return OCEAN_OK;
}

static ocean_result v_sea_state(ctx *c, const proto_sea_state *s)
{
    TRY(chk_enum(c, "sea_state.op", s->op, PROTO_SEA_OP_COUNT_));
    TRY(chk_time(c, "sea_state.effective_time", s->effective_time));
    TRY(chk_str(c, "sea_state.token", s->token, PROTO_TOKEN_MAX));
    if (s->op == PROTO_SEA_GET) {
        /* A get carries no state: every field zero, so a future version can
         * give them a meaning without old servers misreading them. */
        const proto_sea *z = &s->sea;
        const double d[11] = {s->effective_time, z->wind_u10, z->wind_dir_deg, z->fetch_m, z->depth_m,
                              z->swell, z->phillips_a, z->small_wave_m, z->choppiness, z->hs, z->tp};
        int nonzero = z->spectrum || z->spreading || z->flags || z->seed;
        for (int i = 0; i < 11; i++) nonzero |= d[i] != 0 || signbit(d[i]);
        if (nonzero)
            FAIL(c, OCEAN_EFORMAT, "sea_state get: effective_time and the sea block must be zero bytes");
        if (s->token[0])
            FAIL(c, OCEAN_EFORMAT, "sea_state get must not carry a token");
        return OCEAN_OK;
    }
    TRY(v_sea(c, &s->sea));
    if (s->op == PROTO_SEA_ANNOUNCE && s->token[0])
        FAIL(c, OCEAN_EFORMAT, "sea_state announce must not carry a token");
    return OCEAN_OK;
}

/* ENTITY: a set or an announce carries a whole sample and shape (the
 * sim's entity table judges their ranges; here only what no entity can
 * have); a remove or gone carries an id alone; a get nothing. */
static ocean_result v_entity(ctx *c, const proto_entity *e)
{
    TRY(chk_enum(c, "entity.op", e->op, PROTO_ENTITY_OP_COUNT_));
    TRY(chk_enum(c, "entity.kind", e->kind, PROTO_ENTITY_KIND_COUNT));
    TRY(chk_str(c, "entity.token", e->token, PROTO_TOKEN_MAX));
    const double f[9] = {e->t, e->x, e->z, e->altitude_m, e->heading_deg, e->speed, e->length_m, e->beam_m,
                         e->draught_m};
    static const char *const names[9] = {"t", "x", "z", "altitude_m", "heading_deg", "speed", "length_m",
                                         "beam_m", "draught_m"};
    if (e->op == PROTO_ENTITY_SET || e->op == PROTO_ENTITY_ANNOUNCE) {
        TRY(chk_time(c, "entity.t", e->t));
        for (int i = 1; i < 9; i++)
            if (!isfinite(f[i]))
                FAIL(c, OCEAN_EINVAL, "entity.%s = %g; must be finite", names[i], f[i]);
    } else {
        int nonzero = e->kind != 0 || (e->op == PROTO_ENTITY_GET && e->id != 0);
        for (int i = 0; i < 9; i++) nonzero |= f[i] != 0 || signbit(f[i]);
        if (nonzero)
            FAIL(c, OCEAN_EFORMAT, "entity %s: every field but %s must be zero bytes",
                 e->op == PROTO_ENTITY_GET ? "get" : e->op == PROTO_ENTITY_REMOVE ? "remove" : "gone",
                 e->op == PROTO_ENTITY_GET ? "op" : "op, id and the token");
    }
    int wants_token = e->op == PROTO_ENTITY_SET || e->op == PROTO_ENTITY_REMOVE;
    if (!wants_token && e->token[0])
        FAIL(c, OCEAN_EFORMAT, "entity %s must not carry a token",
             e->op == PROTO_ENTITY_GET ? "get" : e->op == PROTO_ENTITY_GONE ? "gone" : "announce");
    return OCEAN_OK;
}

/* WAKE: parameters no wake can lack (the reader's wake_pattern judges
 * their ranges), a grid a tile may have, and a codec. */
static ocean_result v_wake(ctx *c, const proto_wake *w)
{
    if (!(isfinite(w->speed) && w->speed > 0 && isfinite(w->length) && w->length > 0))
        FAIL(c, OCEAN_EINVAL, "wake.speed %g and wake.length %g must be finite and > 0", w->speed, w->length);
    if (!(isfinite(w->beam) && w->beam >= 0) || !(w->depth > 0))
        FAIL(c, OCEAN_EINVAL, "wake.beam %g must be finite and >= 0, wake.depth %g > 0 (inf: deep)", w->beam,
             w->depth);
    TRY(chk_range(c, "wake.nx", w->nx, 1, PROTO_PLANE_MAX_SIZE));
    TRY(chk_range(c, "wake.nz", w->nz, 1, PROTO_PLANE_MAX_SIZE));
    TRY(chk_enum(c, "wake.codec", w->codec, PROTO_CODEC_COUNT_));
    return chk_range(c, "wake.error_bound", w->error_bound, 0, 1e30);
}

static ocean_result v_error(ctx *c, const proto_error *e)
{
    if (e->code == 0)
        FAIL(c, OCEAN_EINVAL, "error.code is 0 (OCEAN_OK is not an error)");
    return chk_str(c, "error.message", e->message, PROTO_ERROR_MSG_MAX);
}

static ocean_result v_bye(ctx *c, const proto_bye *b)
{
    TRY(chk_enum(c, "bye.reason", b->reason, PROTO_BYE_REASON_COUNT_));
    return chk_str(c, "bye.message", b->message, PROTO_BYE_MSG_MAX);
}

static ocean_result v_msg(ctx *c, const proto_msg *m)
{
    switch (m->hdr.type) {
    case PROTO_HELLO: return v_hello(c, &m->u.hello);
    case PROTO_SUBSCRIBE: return v_subscribe(c, &m->u.subscribe);
    case PROTO_CAMERA: return v_camera(c, &m->u.camera);
    case PROTO_FRAME: return v_frame(c, &m->u.frame);
    case PROTO_TILE: return v_tile(c, &m->u.tile);
    case PROTO_MESH_TOPOLOGY: return v_topology(c, &m->u.topology);
    case PROTO_MESH_VERTICES: return v_vertices(c, &m->u.vertices);
    case PROTO_QUERY: return v_query(c, &m->u.query);
    case PROTO_QUERY_RESULT: return v_result(c, &m->u.result);
    case PROTO_SEA_STATE: return v_sea_state(c, &m->u.sea_state);
    case PROTO_ERROR: return v_error(c, &m->u.error);
    case PROTO_BYE: return v_bye(c, &m->u.bye);
    case PROTO_ENTITY: return v_entity(c, &m->u.entity);
    case PROTO_WAKE: return v_wake(c, &m->u.wake);
    default: FAIL(c, OCEAN_ETYPE, "message type %u unknown", m->hdr.type);
    }
}

/* ---- header ----------------------------------------------------------- */

ocean_result proto_header_decode(const void *buf, size_t len, const proto_limits *lim,
                                 proto_header *out, char *err, size_t errlen)
{
    proto_limits dl;
    if (!lim) {
        proto_limits_default(&dl);
        lim = &dl;
    }
    memset(out, 0, sizeof *out);
    const uint8_t *p = buf;
    if (!buf || len < PROTO_HEADER_SIZE) {
        ocean_seterr(err, errlen, "message of %zu bytes is shorter than the %d-byte header", len, PROTO_HEADER_SIZE);
        return OCEAN_ETRUNC;
    }
    if (proto_ld32(p) != PROTO_MAGIC) {
        ocean_seterr(err, errlen, "bad magic 0x%08x (expected \"OCNW\")", proto_ld32(p));
        return OCEAN_EFORMAT;
    }
    out->version = proto_ld16(p + 4);
    out->type = proto_ld16(p + 6);
    out->flags = proto_ld32(p + 8);
    out->length = proto_ld32(p + 12);
    out->seq = proto_ld32(p + 16);
    out->sim_time = proto_ldf64(p + 24);
    if (out->version != PROTO_VERSION) {
        ocean_seterr(err, errlen, "protocol version %u not supported (this side speaks %d, subprotocol %s)",
               out->version, PROTO_VERSION, PROTO_SUBPROTOCOL);
        return OCEAN_EVERSION;
    }
    if (out->type < 1 || out->type >= PROTO_TYPE_END_) {
        ocean_seterr(err, errlen, "message type %u unknown (valid 1..%d)", out->type, PROTO_TYPE_END_ - 1);
        return OCEAN_ETYPE;
    }
    if (out->flags != 0 || proto_ld32(p + 20) != 0) {
        ocean_seterr(err, errlen, "%s header: flags 0x%x / reserved 0x%x must be 0 in version 1",
               proto_type_name(out->type), out->flags, proto_ld32(p + 20));
        return OCEAN_EFORMAT;
    }
    if (!ocean_time_ok(out->sim_time)) {
        char m[256];
        ocean_time_check(out->sim_time, "sim_time", m, sizeof m);
        ocean_seterr(err, errlen, "%s header: %s", proto_type_name(out->type), m);
        return OCEAN_EINVAL;
    }
    if ((uint64_t)out->length + PROTO_HEADER_SIZE > lim->max_message) {
        ocean_seterr(err, errlen, "%s of %llu bytes exceeds the %u-byte message limit", proto_type_name(out->type),
               (unsigned long long)out->length + PROTO_HEADER_SIZE, lim->max_message);
        return OCEAN_ETOOBIG;
    }
    if ((uint64_t)out->length + PROTO_HEADER_SIZE > len) {
        ocean_seterr(err, errlen, "%s header declares %u payload bytes, only %zu present", proto_type_name(out->type),
               out->length, len - PROTO_HEADER_SIZE);
        return OCEAN_ETRUNC;
    }
    if ((uint64_t)out->length + PROTO_HEADER_SIZE < len) {
        ocean_seterr(err, errlen, "%s: %zu bytes after the declared %u-byte payload", proto_type_name(out->type),
               len - PROTO_HEADER_SIZE - out->length, out->length);
        return OCEAN_EFORMAT;
    }
    return OCEAN_OK;
}

/* ---- decoding --------------------------------------------------------- */

typedef struct rd {
    const uint8_t *p;   /* whole message */
    size_t end;         /* end of the region being parsed */
    size_t off;         /* absolute offset of the next byte */
    ctx *c;
    const char *what;   /* message/record being parsed, for messages */
    uint8_t *arena;     /* bump allocator for decoded arrays */
    size_t arena_len, arena_used;
} rd;

static ocean_result need(rd *r, size_t k, const char *field)
{
    if (r->end - r->off < k)
        FAIL(r->c, OCEAN_ETRUNC, "%s: %s needs %zu bytes at offset %zu, only %zu left", r->what, field, k,
             r->off, r->end - r->off);
    return OCEAN_OK;
}

static void *arena_take(rd *r, size_t n)
{
    size_t a = (r->arena_used + 7u) & ~(size_t)7u;
    if (a > r->arena_len || r->arena_len - a < n)
        return NULL;   /* cannot happen: the arena is sized from the message */
    r->arena_used = a + n;
    return r->arena + a;
}

static ocean_result zero_bytes(rd *r, size_t at, size_t n, const char *field)
{
    for (size_t i = 0; i < n; i++)
        if (r->p[at + i])
            FAIL(r->c, OCEAN_EFORMAT, "%s: reserved %s byte at offset %zu is 0x%02x, must be 0", r->what, field,
                 at + i, r->p[at + i]);
    return OCEAN_OK;
}

static ocean_result rd_str(rd *r, char *dst, size_t max, const char *field)
{
    TRY(need(r, 2, field));
    size_t n = proto_ld16(r->p + r->off);
    if (n > max)
        FAIL(r->c, OCEAN_ETOOBIG, "%s: %s of %zu bytes longer than %zu", r->what, field, n, max);
    r->off += 2;
    TRY(need(r, n, field));
    if (!utf8_ok(r->p + r->off, n))
        FAIL(r->c, OCEAN_EFORMAT, "%s: %s is not valid UTF-8 (or holds NUL)", r->what, field);
    memcpy(dst, r->p + r->off, n);
    dst[n] = 0;
    r->off += n;
    return OCEAN_OK;
}

static ocean_result rd_end(rd *r)
{
    if (r->off != r->end)
        FAIL(r->c, OCEAN_EFORMAT, "%s: %zu unexpected bytes after the last field (offset %zu)", r->what,
             r->end - r->off, r->off);
    return OCEAN_OK;
}

static void get_sea(const uint8_t *p, proto_sea *s)
{
    s->spectrum = p[0];
    s->spreading = p[1];
    s->flags = p[2];
    s->seed = proto_ld64(p + 8);
    double *d[10] = {&s->wind_u10, &s->wind_dir_deg, &s->fetch_m, &s->depth_m, &s->swell,
                     &s->phillips_a, &s->small_wave_m, &s->choppiness, &s->hs, &s->tp};
    for (int i = 0; i < 10; i++)
        *d[i] = proto_ldf64(p + 16 + 8 * i);
}

static ocean_result d_sea(rd *r, proto_sea *s)
{
    TRY(need(r, SEA_SIZE, "sea state"));
    TRY(zero_bytes(r, r->off + 3, 5, "sea"));
    get_sea(r->p + r->off, s);
    r->off += SEA_SIZE;
    return OCEAN_OK;
}

static ocean_result d_hello(rd *r, proto_hello *h)
{
    TRY(need(r, 32, "fixed fields"));
    const uint8_t *p = r->p + r->off;
    h->codecs = proto_ld32(p);
    h->mesh_kinds = p[4];
    h->effects = p[5];
    h->cutoff_policies = p[6];
    h->modes = p[7];
    h->max_message = proto_ld32(p + 8);
    h->max_query_points = proto_ld32(p + 12);
    h->max_tile_size = proto_ld16(p + 16);
    h->max_lod_levels = p[18];
    h->max_layers = p[19];
    h->tick_rate_hz = proto_ldf32(p + 20);
    h->max_frame_rate_hz = proto_ldf32(p + 24);
    h->client_id = proto_ld32(p + 28);
    r->off += 32;
    TRY(d_sea(r, &h->sea));
    TRY(rd_str(r, h->server_version, PROTO_VERSION_STR_MAX, "server_version"));
    return rd_end(r);
}

static ocean_result d_subscribe(rd *r, proto_subscribe *s)
{
    TRY(need(r, SUBSCRIBE_SIZE, "fixed fields"));
    const uint8_t *p = r->p + r->off;
    s->effects = p[0];
    s->mesh_kind = p[1];
    s->codec = p[2];
    s->cutoff_policy = p[3];
    s->mode = p[4];
    s->layers = p[5];
    s->lod_levels = p[6];
    s->layout = p[7];
    s->tile_size = proto_ld16(p + 8);
    s->mesh_codec = p[10];
    s->flags = p[11];
    s->frame_rate_hz = proto_ldf32(p + 12);
    s->accuracy = proto_ldf32(p + 16);
    s->base_spacing_m = proto_ldf32(p + 20);
    s->view_range_m = proto_ldf32(p + 24);
    r->off += SUBSCRIBE_SIZE;
    return rd_end(r);
}

static ocean_result d_camera(rd *r, proto_camera *k)
{
    TRY(need(r, CAMERA_SIZE, "fixed fields"));
    const uint8_t *p = r->p + r->off;
    for (int i = 0; i < 3; i++) {
        k->pos[i] = proto_ldf64(p + 8 * i);
        k->vel[i] = proto_ldf32(p + 24 + 4 * i);
    }
    k->yaw_deg = proto_ldf32(p + 36);
    k->pitch_deg = proto_ldf32(p + 40);
    k->roll_deg = proto_ldf32(p + 44);
    k->fov_y_deg = proto_ldf32(p + 48);
    k->viewport_w = proto_ld16(p + 52);
    k->viewport_h = proto_ld16(p + 54);
    k->render_time = proto_ldf64(p + 56);
    r->off += CAMERA_SIZE;
    return rd_end(r);
}

/* TILE body; r->end must be the body's end. */
static ocean_result d_tile(rd *r, proto_tile *t)
{
    TRY(need(r, TILE_FIXED, "tile fixed fields"));
    const uint8_t *p = r->p + r->off;
    t->level = p[0];
    t->codec = p[1];
    t->channels = proto_ld16(p + 2);
    t->width = proto_ld16(p + 4);
    t->height = proto_ld16(p + 6);
    t->ix = (int32_t)proto_ld32(p + 8);
    t->iz = (int32_t)proto_ld32(p + 12);
    t->origin_x = proto_ldf64(p + 16);
    t->origin_z = proto_ldf64(p + 24);
    t->spacing = proto_ldf64(p + 32);
    t->error_bound = proto_ldf32(p + 40);
    t->payload_len = proto_ld32(p + 44);
    r->off += TILE_FIXED;
    TRY(need(r, t->payload_len, "tile payload"));
    uint8_t *d = arena_take(r, t->payload_len);
    if (!d)
        FAIL(r->c, OCEAN_ENOMEM, "decoder arena exhausted");
    if (t->payload_len)
        memcpy(d, r->p + r->off, t->payload_len);
    t->payload = d;
    r->off += t->payload_len;
    return rd_end(r);
}

static ocean_result d_floats(rd *r, size_t count, float **out, const char *field)
{
    if (count > SIZE_MAX / 4)
        FAIL(r->c, OCEAN_ETOOBIG, "%s: %s count overflows", r->what, field);
    TRY(need(r, count * 4, field));
    float *f = arena_take(r, count * sizeof *f);
    if (!f && count)
        FAIL(r->c, OCEAN_ENOMEM, "decoder arena exhausted");
    for (size_t i = 0; i < count; i++)
        f[i] = proto_ldf32(r->p + r->off + 4 * i);
    r->off += count * 4;
    *out = f;
    return OCEAN_OK;
}

/* MESH_VERTICES' fixed fields (mesh_id, vertex_count, origin), shared by
 * the f32 and the qz body. */
static ocean_result d_vertices_head(rd *r, proto_mesh_vertices *v)
{
    TRY(need(r, VERTS_FIXED, "mesh vertices fixed fields"));
    const uint8_t *p = r->p + r->off;
    v->mesh_id = proto_ld32(p);
    v->vertex_count = proto_ld32(p + 4);
    for (int i = 0; i < 3; i++)
        v->origin[i] = proto_ldf64(p + 8 + 8 * i);
    r->off += VERTS_FIXED;
    if (v->vertex_count > r->c->lim->max_vertices)
        FAIL(r->c, OCEAN_ETOOBIG, "%s: vertex_count %u above the limit %u", r->what, v->vertex_count,
             r->c->lim->max_vertices);
    return OCEAN_OK;
}

static ocean_result d_vertices(rd *r, proto_mesh_vertices *v)
{
    TRY(d_vertices_head(r, v));
    float *pos;
    TRY(d_floats(r, 3 * (size_t)v->vertex_count, &pos, "positions"));
    v->positions = pos;
    return rd_end(r);
}

/* A has_mesh 2 record: MESH_VERTICES' fixed fields, then the qz payload
 * (kept as bytes: decoding it needs the topology). */
static ocean_result d_vertices_qz(rd *r, proto_mesh_vertices *v)
{
    TRY(d_vertices_head(r, v));
    size_t n = r->end - r->off;
    if (n > UINT32_MAX)
        FAIL(r->c, OCEAN_ETOOBIG, "%s: mesh qz payload of %zu bytes", r->what, n);
    uint8_t *d = arena_take(r, n);
    if (!d)
        FAIL(r->c, OCEAN_ENOMEM, "decoder arena exhausted");
    if (n)
        memcpy(d, r->p + r->off, n);
    v->qz = d;
    v->qz_len = (uint32_t)n;
    v->positions = NULL;
    r->off += n;
    return OCEAN_OK;
}

/* A layout-1 mesh record: the placement. */
static ocean_result d_placement(rd *r, proto_mesh_placement *pl)
{
    TRY(need(r, PROTO_MESH_PLACEMENT_SIZE, "mesh placement"));
    const uint8_t *p = r->p + r->off;
    pl->mesh_id = proto_ld32(p);
    TRY(zero_bytes(r, r->off + 4, 4, "mesh placement"));
    for (int i = 0; i < 3; i++)
        pl->origin[i] = proto_ldf64(p + 8 + 8 * i);
    r->off += PROTO_MESH_PLACEMENT_SIZE;
    return rd_end(r);
}

enum { REC_TILE, REC_VERTICES, REC_PLACEMENT, REC_VERTICES_QZ };

/* Reads one FRAME record (u32 length, u32 tag, body, zero padding to a
 * multiple of 8) and parses the body as `kind`.  Tags above max_tag are
 * refused; *tag gets the tag. */
static ocean_result d_record(rd *r, int kind, void *dst, uint32_t max_tag, uint32_t *tag)
{
    TRY(need(r, RECORD_HEAD, "record header"));
    uint32_t blen = proto_ld32(r->p + r->off);
    *tag = proto_ld32(r->p + r->off + 4);
    if (*tag > max_tag)
        FAIL(r->c, OCEAN_EFORMAT, "%s: record tag %u at offset %zu above %u", r->what, *tag, r->off + 4, max_tag);
    r->off += RECORD_HEAD;
    TRY(need(r, blen, kind == REC_TILE ? "tile record" : "mesh record"));
    size_t pad = (8u - (blen & 7u)) & 7u;
    size_t body_end = r->off + blen;
    size_t outer_end = r->end;
    r->end = body_end;
    ocean_result res = kind == REC_VERTICES ? d_vertices(r, dst)
                     : kind == REC_VERTICES_QZ ? d_vertices_qz(r, dst)
                     : kind == REC_PLACEMENT ? d_placement(r, dst) : d_tile(r, dst);
    r->end = outer_end;
    if (res != OCEAN_OK)
        return res;
    if (r->end - body_end < pad)
        FAIL(r->c, OCEAN_ETRUNC, "%s: record padding of %zu bytes missing at offset %zu", r->what, pad, body_end);
    TRY(zero_bytes(r, body_end, pad, "record padding"));
    r->off = body_end + pad;
    return OCEAN_OK;
}

void proto_frame_fixed_read(const uint8_t *p, proto_frame *f)
{
    f->cutoff_k = proto_ldf64(p);
    f->e_error = proto_ldf64(p + 8);
    for (int i = 0; i < 3; i++)
        f->origin[i] = proto_ldf64(p + 16 + 8 * i);
    f->camera_seq = proto_ld32(p + 40);
    f->tick = proto_ld32(p + 44);
    f->tile_count = proto_ld16(p + 48);
    f->has_mesh = p[50];
    f->layout = p[51];
}

/* Bytes of the cascade block of a FRAME whose block starts at p with
 * `avail` bytes (0 when it cannot be a block). */
static size_t cascade_block_size(const uint8_t *p, size_t avail)
{
    if (avail < PROTO_CASCADE_BLOCK_FIXED || p[0] < 1 || p[0] > PROTO_MAX_LAYERS)
        return 0;
    size_t n = proto_cascade_block_bytes(p[0], p[2]);
    return n <= avail ? n : 0;
}

size_t proto_cascade_block_bytes(unsigned count, unsigned flags)
{
    return PROTO_CASCADE_BLOCK_FIXED + (size_t)count * PROTO_CASCADE_ENTRY_SIZE +
           ((flags & PROTO_CASCADE_FOAM) ? PROTO_FOAM_TABLE_SIZE : 0) +
           ((flags & PROTO_CASCADE_READ) ? (size_t)count * PROTO_READ_ENTRY_SIZE : 0);
}

/* The read table at p (count entries of PROTO_READ_ENTRY_SIZE bytes). */
static void read_table_read(const uint8_t *p, proto_cascade_block *b)
{
    for (unsigned k = 0; k < b->cascade_count && k < PROTO_MAX_LAYERS; k++)
        for (int m = 0; m < PROTO_MAX_MIPS; m++)
            for (int r = 0; r < PROTO_READ_KERNELS; r++)
                b->cascade[k].mip[m].held[r] =
                    proto_ld16(p + (size_t)k * PROTO_READ_ENTRY_SIZE + 2 * (PROTO_READ_KERNELS * m + r));
}

static void read_table_write(uint8_t *p, const proto_cascade_block *b)
{
    for (unsigned k = 0; k < b->cascade_count; k++)
        for (int m = 0; m < PROTO_MAX_MIPS; m++)
            for (int r = 0; r < PROTO_READ_KERNELS; r++)
                proto_st16(p + (size_t)k * PROTO_READ_ENTRY_SIZE + 2 * (PROTO_READ_KERNELS * m + r),
                           b->cascade[k].mip[m].held[r]);
}

/* The whitecap table at p (PROTO_FOAM_TABLE_SIZE bytes). */
static void foam_table_read(const uint8_t *p, proto_cascade_block *b)
{
    b->foam_rows = p[0];
    for (int i = 0; i < PROTO_FOAM_ROWS; i++) {
        const uint8_t *w = p + 8 + 12 * i;
        b->foam[i].sigma = proto_ldf32(w);
        b->foam[i].a = proto_ldf32(w + 4);
        b->foam[i].omega = proto_ldf32(w + 8);
    }
}

static void foam_table_write(uint8_t *p, const proto_cascade_block *b)
{
    memset(p, 0, PROTO_FOAM_TABLE_SIZE);
    p[0] = b->foam_rows;
    for (int i = 0; i < PROTO_FOAM_ROWS; i++) {
        uint8_t *w = p + 8 + 12 * i;
        proto_stf32(w, b->foam[i].sigma);
        proto_stf32(w + 4, b->foam[i].a);
        proto_stf32(w + 8, b->foam[i].omega);
    }
}

static void cascade_block_read(const uint8_t *p, proto_cascade_block *b)
{
    memset(b, 0, sizeof *b);
    b->cascade_count = p[0];
    b->order = p[1];
    b->flags = p[2];
    b->spacing_per_m = proto_ldf32(p + 4);
    for (int i = 0; i < 3; i++)
        b->camera[i] = proto_ldf64(p + 8 + 8 * i);
    b->min_spacing_m = proto_ldf32(p + 32);
    b->e_total = proto_ldf32(p + 36);
    for (int i = 0; i < 3; i++)
        b->tail_mss[i] = proto_ldf32(p + 40 + 4 * i);
    b->geometry_spacing_m = proto_ldf32(p + 52);
    for (unsigned k = 0; k < b->cascade_count && k < PROTO_MAX_LAYERS; k++) {
        const uint8_t *q = p + PROTO_CASCADE_BLOCK_FIXED + (size_t)k * PROTO_CASCADE_ENTRY_SIZE;
        proto_cascade_entry *e = &b->cascade[k];
        e->patch_m = proto_ldf64(q);
        e->n = proto_ld16(q + 8);
        e->mips = q[10];
        e->fades = q[11];
        e->spacing_per_m = proto_ldf32(q + 12);
        for (int m = 0; m < PROTO_MIP_ENTRIES; m++) {
            const uint8_t *w = q + 16 + 16 * m;
            e->mip[m].kc = proto_ldf32(w);
            e->mip[m].mss_x = proto_ldf32(w + 4);
            e->mip[m].mss_z = proto_ldf32(w + 8);
            e->mip[m].mss_xz = proto_ldf32(w + 12);
        }
        for (int m = 0; m < PROTO_MAX_MIPS; m++) {
            const uint8_t *w = q + 16 + 16 * PROTO_MIP_ENTRIES + 8 * m;
            e->time[m].tick_a = proto_ld32(w);
            e->time[m].interval = proto_ld16(w + 4);
            e->time[m].phase = proto_ld16(w + 6);
        }
    }
    if (b->flags & PROTO_CASCADE_FOAM)
        foam_table_read(p + proto_cascade_block_bytes(b->cascade_count, 0), b);
    if (b->flags & PROTO_CASCADE_READ)
        read_table_read(p + proto_cascade_block_bytes(b->cascade_count, b->flags & PROTO_CASCADE_FOAM), b);
}

static void cascade_block_write(uint8_t *p, const proto_cascade_block *b)
{
    p[0] = b->cascade_count;
    p[1] = b->order;
    p[2] = b->flags;
    proto_stf32(p + 4, b->spacing_per_m);
    for (int i = 0; i < 3; i++)
        proto_stf64(p + 8 + 8 * i, b->camera[i]);
    proto_stf32(p + 32, b->min_spacing_m);
    proto_stf32(p + 36, b->e_total);
    for (int i = 0; i < 3; i++)
        proto_stf32(p + 40 + 4 * i, b->tail_mss[i]);
    proto_stf32(p + 52, b->geometry_spacing_m);
    for (unsigned k = 0; k < b->cascade_count; k++) {
        uint8_t *q = p + PROTO_CASCADE_BLOCK_FIXED + (size_t)k * PROTO_CASCADE_ENTRY_SIZE;
        const proto_cascade_entry *e = &b->cascade[k];
        proto_stf64(q, e->patch_m);
        proto_st16(q + 8, e->n);
        q[10] = e->mips;
        q[11] = e->fades;
        proto_stf32(q + 12, e->spacing_per_m);
        for (int m = 0; m < PROTO_MIP_ENTRIES; m++) {
            uint8_t *w = q + 16 + 16 * m;
            proto_stf32(w, e->mip[m].kc);
            proto_stf32(w + 4, e->mip[m].mss_x);
            proto_stf32(w + 8, e->mip[m].mss_z);
            proto_stf32(w + 12, e->mip[m].mss_xz);
        }
        for (int m = 0; m < PROTO_MAX_MIPS; m++) {
            uint8_t *w = q + 16 + 16 * PROTO_MIP_ENTRIES + 8 * m;
            proto_st32(w, e->time[m].tick_a);
            proto_st16(w + 4, e->time[m].interval);
            proto_st16(w + 6, e->time[m].phase);
        }
    }
    if (b->flags & PROTO_CASCADE_FOAM)
        foam_table_write(p + proto_cascade_block_bytes(b->cascade_count, 0), b);
    if (b->flags & PROTO_CASCADE_READ)
        read_table_write(p + proto_cascade_block_bytes(b->cascade_count, b->flags & PROTO_CASCADE_FOAM), b);
}

ocean_result proto_frame_client_fields(const uint8_t *msg, size_t len, size_t *camera_seq_at,
                                       size_t *mesh_id_at)
{
    if (!msg || len < PROTO_HEADER_SIZE + FRAME_FIXED || proto_ld32(msg) != PROTO_MAGIC ||
        proto_ld16(msg + 6) != PROTO_FRAME || proto_ld32(msg + 12) != len - PROTO_HEADER_SIZE)
        return OCEAN_EFORMAT;
    const uint8_t *f = msg + PROTO_HEADER_SIZE;
    unsigned tiles = proto_ld16(f + 48), has_mesh = f[50], layout = f[51];
    size_t off = PROTO_HEADER_SIZE + FRAME_FIXED;
    if (layout > PROTO_LAYOUT_CASCADE)
        return OCEAN_EFORMAT;
    if (layout == PROTO_LAYOUT_CASCADE) {
        size_t bs = cascade_block_size(msg + off, len - off);
        if (!bs)
            return OCEAN_EFORMAT;
        off += bs;
    }
    if (has_mesh > 2 || (has_mesh == 2 && layout != PROTO_LAYOUT_WORLD))
        return OCEAN_EFORMAT;
    size_t mesh_min = layout == PROTO_LAYOUT_CASCADE ? PROTO_MESH_PLACEMENT_SIZE
                    : has_mesh == 2 ? VERTS_FIXED + PROTO_MESH_QZ_HEAD : VERTS_FIXED;
    /* Records as e_record lays them out: u32 length, u32 tag, body, pad to 8. */
    for (unsigned i = 0; i < tiles + (has_mesh != 0); i++) {
        if (len - off < RECORD_HEAD)
            return OCEAN_EFORMAT;
        size_t blen = proto_ld32(msg + off), pad = (8u - (blen & 7u)) & 7u;
        if (i == tiles) {
            if (blen < mesh_min || len - off - RECORD_HEAD != blen + pad)
                return OCEAN_EFORMAT;
            *camera_seq_at = PROTO_HEADER_SIZE + 40;
            *mesh_id_at = off + RECORD_HEAD;
            return OCEAN_OK;
        }
        if (len - off - RECORD_HEAD < blen + pad)
            return OCEAN_EFORMAT;
        off += RECORD_HEAD + blen + pad;
    }
    if (has_mesh || off != len)
        return OCEAN_EFORMAT;
    *camera_seq_at = PROTO_HEADER_SIZE + 40;
    *mesh_id_at = 0;
    return OCEAN_OK;
}

/* A layout-1 tile record's tag: its cascade, and sample B only of a mip
 * with a time interval. */
static ocean_result d_tile_tag(rd *r, const proto_frame *f, proto_tile *t, uint32_t tag)
{
    if (f->layout != PROTO_LAYOUT_CASCADE)
        return OCEAN_OK;
    unsigned c = tag & 0xFFu;
    if ((tag & ~(0xFFu | PROTO_TAG_SLOT_B)) || c >= f->cascades.cascade_count)
        FAIL(r->c, OCEAN_EFORMAT, "%s: record tag %u names no cascade of %u", r->what, tag,
             f->cascades.cascade_count);
    t->cascade = (uint8_t)c;
    t->slot = (tag & PROTO_TAG_SLOT_B) ? 1 : 0;
    const proto_cascade_entry *e = &f->cascades.cascade[c];
    if (t->slot && (t->level >= e->mips || !e->time[t->level].interval))
        FAIL(r->c, OCEAN_EINVAL, "%s: sample B of mip %u of cascade %u, which has no time interval", r->what,
             t->level, c);
    return OCEAN_OK;
}

static ocean_result d_frame(rd *r, proto_frame *f)
{
    TRY(need(r, FRAME_FIXED, "fixed fields"));
    proto_frame_fixed_read(r->p + r->off, f);
    TRY(zero_bytes(r, r->off + 52, 4, "frame"));
    r->off += FRAME_FIXED;
    if (f->layout > PROTO_LAYOUT_CASCADE)
        FAIL(r->c, OCEAN_ETYPE, "FRAME: layout %u unknown (0..1)", f->layout);
    uint32_t max_tag = 0;
    if (f->layout == PROTO_LAYOUT_CASCADE) {
        TRY(need(r, PROTO_CASCADE_BLOCK_FIXED, "cascade block"));
        unsigned cc = r->p[r->off];
        if (cc < 1 || cc > PROTO_MAX_LAYERS)
            FAIL(r->c, OCEAN_EINVAL, "FRAME: cascade_count %u outside 1..%d", cc, PROTO_MAX_LAYERS);
        size_t bytes = proto_cascade_block_bytes(cc, r->p[r->off + 2]);
        TRY(need(r, bytes, "cascade entries"));
        TRY(zero_bytes(r, r->off + 3, 1, "cascade block"));
        if (r->p[r->off + 2] & PROTO_CASCADE_FOAM)
            TRY(zero_bytes(r, r->off + proto_cascade_block_bytes(cc, 0) + 1, 7, "whitecap table"));
        cascade_block_read(r->p + r->off, &f->cascades);
        r->off += bytes;
        max_tag = PROTO_TAG_SLOT_B | 0xFFu;
    }
    if (f->tile_count > r->c->lim->max_frame_tiles)
        FAIL(r->c, OCEAN_ETOOBIG, "FRAME: tile_count %u above the limit %u", f->tile_count, r->c->lim->max_frame_tiles);
    if (f->has_mesh > 2 || (f->has_mesh == 2 && f->layout != PROTO_LAYOUT_WORLD))
        FAIL(r->c, OCEAN_EFORMAT, "FRAME: has_mesh is %u (0 or 1; 2 in layout 0)", f->has_mesh);
    /* Each record needs at least its 8-byte head plus the tile's fixed part. */
    if ((size_t)f->tile_count * (RECORD_HEAD + TILE_FIXED) > r->end - r->off)
        FAIL(r->c, OCEAN_ETRUNC, "FRAME: %u tiles cannot fit in the %zu bytes left", f->tile_count, r->end - r->off);
    proto_tile *tiles = NULL;
    if (f->tile_count) {
        tiles = arena_take(r, f->tile_count * sizeof *tiles);
        if (!tiles)
            FAIL(r->c, OCEAN_ENOMEM, "decoder arena exhausted");
        memset(tiles, 0, f->tile_count * sizeof *tiles);
    }
    f->tiles = tiles;
    uint32_t tag;
    for (unsigned i = 0; i < f->tile_count; i++) {
        TRY(d_record(r, REC_TILE, &tiles[i], max_tag, &tag));
        TRY(d_tile_tag(r, f, &tiles[i], tag));
    }
    if (f->has_mesh)
        TRY(d_record(r, f->layout == PROTO_LAYOUT_CASCADE ? REC_PLACEMENT
                        : f->has_mesh == 2 ? REC_VERTICES_QZ : REC_VERTICES,
                     f->layout == PROTO_LAYOUT_CASCADE ? (void *)&f->placement : (void *)&f->mesh, 0, &tag));
    return rd_end(r);
}

static ocean_result d_topology(rd *r, proto_mesh_topology *t)
{
    TRY(need(r, TOPO_FIXED, "fixed fields"));
    const uint8_t *p = r->p + r->off;
    t->mesh_id = proto_ld32(p);
    t->mesh_kind = p[4];
    t->lod_levels = p[5];
    t->flags = proto_ld16(p + 6);
    if (t->flags & ~PROTO_TOPO_FLAT)
        FAIL(r->c, OCEAN_EFORMAT, "MESH_TOPOLOGY: flags 0x%x has unknown bits", t->flags);
    t->vertex_count = proto_ld32(p + 8);
    t->index_count = proto_ld32(p + 12);
    r->off += TOPO_FIXED;
    if (t->vertex_count > r->c->lim->max_vertices || t->index_count > r->c->lim->max_indices)
        FAIL(r->c, OCEAN_ETOOBIG, "MESH_TOPOLOGY: %u vertices / %u indices above the limits %u / %u",
             t->vertex_count, t->index_count, r->c->lim->max_vertices, r->c->lim->max_indices);
    size_t need_bytes = 4 * (size_t)t->index_count + 5 * (size_t)t->vertex_count;
    TRY(need(r, need_bytes, "indices, morph and level arrays"));
    uint32_t *idx = arena_take(r, 4 * (size_t)t->index_count);
    float *morph = arena_take(r, 4 * (size_t)t->vertex_count);
    uint8_t *lev = arena_take(r, t->vertex_count);
    if ((!idx && t->index_count) || (!morph && t->vertex_count) || (!lev && t->vertex_count))
        FAIL(r->c, OCEAN_ENOMEM, "decoder arena exhausted");
    for (uint32_t i = 0; i < t->index_count; i++)
        idx[i] = proto_ld32(r->p + r->off + 4 * (size_t)i);
    r->off += 4 * (size_t)t->index_count;
    for (uint32_t i = 0; i < t->vertex_count; i++)
        morph[i] = proto_ldf32(r->p + r->off + 4 * (size_t)i);
    r->off += 4 * (size_t)t->vertex_count;
    if (t->vertex_count)
        memcpy(lev, r->p + r->off, t->vertex_count);
    r->off += t->vertex_count;
    t->indices = idx;
    t->morph = morph;
    t->level = lev;
    if (t->flags & PROTO_TOPO_FLAT) {
        size_t pad = (4u - (r->off & 3u)) & 3u;
        TRY(need(r, pad, "flat padding"));
        TRY(zero_bytes(r, r->off, pad, "flat padding"));
        r->off += pad;
        if (t->lod_levels < 1 || t->lod_levels > PROTO_MAX_LOD_LEVELS)
            FAIL(r->c, OCEAN_EINVAL, "MESH_TOPOLOGY: lod_levels %u outside 1..%d", t->lod_levels,
                 PROTO_MAX_LOD_LEVELS);
        float *flat, *zones;
        TRY(d_floats(r, 2 * (size_t)t->vertex_count, &flat, "flat positions"));
        TRY(d_floats(r, 4 * (size_t)t->lod_levels, &zones, "zones"));
        t->flat = flat;
        t->zones = zones;
    }
    return rd_end(r);
}

static ocean_result d_query(rd *r, proto_query *q)
{
    TRY(need(r, QUERY_FIXED, "fixed fields"));
    const uint8_t *p = r->p + r->off;
    q->query_id = proto_ld32(p);
    q->count = proto_ld32(p + 4);
    q->at_time = p[8];
    TRY(zero_bytes(r, r->off + 9, 7, "query"));
    q->t = proto_ldf64(p + 16);
    r->off += QUERY_FIXED;
    if (q->count > r->c->lim->max_query_points)
        FAIL(r->c, OCEAN_ETOOBIG, "QUERY: count %u above the limit %u", q->count, r->c->lim->max_query_points);
    TRY(need(r, 16 * (size_t)q->count, "points"));
    double *pts = arena_take(r, 16 * (size_t)q->count);
    if (!pts && q->count)
        FAIL(r->c, OCEAN_ENOMEM, "decoder arena exhausted");
    for (size_t i = 0; i < 2 * (size_t)q->count; i++)
        pts[i] = proto_ldf64(r->p + r->off + 8 * i);
    r->off += 16 * (size_t)q->count;
    q->points = pts;
    return rd_end(r);
}

static ocean_result d_result(rd *r, proto_query_result *q)
{
    TRY(need(r, RESULT_FIXED, "fixed fields"));
    const uint8_t *p = r->p + r->off;
    q->query_id = proto_ld32(p);
    q->count = proto_ld32(p + 4);
    q->t = proto_ldf64(p + 8);
    r->off += RESULT_FIXED;
    if (q->count > r->c->lim->max_query_points)
        FAIL(r->c, OCEAN_ETOOBIG, "QUERY_RESULT: count %u above the limit %u", q->count, r->c->lim->max_query_points);
    TRY(need(r, SAMPLE_SIZE * (size_t)q->count, "samples"));
    proto_query_sample *s = arena_take(r, sizeof *s * (size_t)q->count);
    if (!s && q->count)
        FAIL(r->c, OCEAN_ENOMEM, "decoder arena exhausted");
    for (uint32_t i = 0; i < q->count; i++) {
        const uint8_t *b = r->p + r->off + SAMPLE_SIZE * (size_t)i;
        s[i].height = proto_ldf32(b);
        for (int k = 0; k < 3; k++) {
            s[i].normal[k] = proto_ldf32(b + 4 + 4 * k);
            s[i].velocity[k] = proto_ldf32(b + 16 + 4 * k);
        }
        s[i].foam = proto_ldf32(b + 28);
        s[i].error_bound = proto_ldf32(b + 32);
    }
    r->off += SAMPLE_SIZE * (size_t)q->count;
    q->samples = s;
    return rd_end(r);
}

static ocean_result d_sea_state(rd *r, proto_sea_state *s)
{
    TRY(need(r, 16, "fixed fields"));
    s->op = r->p[r->off];
    TRY(zero_bytes(r, r->off + 1, 7, "sea_state"));
    s->effective_time = proto_ldf64(r->p + r->off + 8);
    r->off += 16;
    TRY(d_sea(r, &s->sea));
    TRY(rd_str(r, s->token, PROTO_TOKEN_MAX, "token"));
    return rd_end(r);
}

static ocean_result d_entity(rd *r, proto_entity *e)
{
    TRY(need(r, ENTITY_FIXED, "fixed fields"));
    const uint8_t *p = r->p + r->off;
    e->op = p[0];
    e->kind = p[1];
    TRY(zero_bytes(r, r->off + 2, 2, "entity"));
    e->id = proto_ld32(p + 4);
    e->t = proto_ldf64(p + 8);
    e->x = proto_ldf64(p + 16);
    e->z = proto_ldf64(p + 24);
    float *f[6] = {&e->altitude_m, &e->heading_deg, &e->speed, &e->length_m, &e->beam_m, &e->draught_m};
    for (int i = 0; i < 6; i++) *f[i] = proto_ldf32(p + 32 + 4 * i);
    r->off += ENTITY_FIXED;
    TRY(rd_str(r, e->token, PROTO_TOKEN_MAX, "token"));
    return rd_end(r);
}

static ocean_result d_wake(rd *r, proto_wake *w)
{
    TRY(need(r, WAKE_FIXED, "fixed fields"));
    const uint8_t *p = r->p + r->off;
    w->speed = proto_ldf64(p);
    w->length = proto_ldf64(p + 8);
    w->beam = proto_ldf64(p + 16);
    w->depth = proto_ldf64(p + 24);
    w->nx = proto_ld16(p + 32);
    w->nz = proto_ld16(p + 34);
    w->codec = p[36];
    TRY(zero_bytes(r, r->off + 37, 3, "wake"));
    w->error_bound = proto_ldf32(p + 40);
    w->payload_len = proto_ld32(p + 44);
    r->off += WAKE_FIXED;
    TRY(need(r, w->payload_len, "wake payload"));
    uint8_t *d = arena_take(r, w->payload_len);
    if (!d) FAIL(r->c, OCEAN_ENOMEM, "decoder arena exhausted");
    if (w->payload_len) memcpy(d, r->p + r->off, w->payload_len);
    w->payload = d;
    r->off += w->payload_len;
    return rd_end(r);
}

static ocean_result d_error(rd *r, proto_error *e)
{
    TRY(need(r, ERROR_FIXED, "fixed fields"));
    const uint8_t *p = r->p + r->off;
    e->code = proto_ld16(p);
    e->offending_type = proto_ld16(p + 2);
    e->offending_seq = proto_ld32(p + 4);
    r->off += ERROR_FIXED;
    TRY(rd_str(r, e->message, PROTO_ERROR_MSG_MAX, "message"));
    return rd_end(r);
}

static ocean_result d_bye(rd *r, proto_bye *b)
{
    TRY(need(r, BYE_FIXED, "fixed fields"));
    b->reason = proto_ld16(r->p + r->off);
    TRY(zero_bytes(r, r->off + 2, 2, "bye"));
    r->off += BYE_FIXED;
    TRY(rd_str(r, b->message, PROTO_BYE_MSG_MAX, "message"));
    return rd_end(r);
}

ocean_result proto_decode_limited(const void *buf, size_t len, const proto_limits *lim,
                                  proto_msg *msg, char *err, size_t errlen)
{
    proto_limits dl;
    if (!lim) {
        proto_limits_default(&dl);
        lim = &dl;
    }
    memset(msg, 0, sizeof *msg);
    if (err && errlen)
        err[0] = 0;
    ocean_result res = proto_header_decode(buf, len, lim, &msg->hdr, err, errlen);
    if (res != OCEAN_OK)
        return res;
    ctx c = {err, errlen, lim};
    rd r = {buf, len, PROTO_HEADER_SIZE, &c, proto_type_name(msg->hdr.type), NULL, 0, 0};
    /* Decoded arrays never exceed the payload bytes they came from, except
     * for the struct overhead of FRAME tiles and QUERY_RESULT samples. */
    size_t payload = msg->hdr.length;
    size_t extra = 64;
    if (msg->hdr.type == PROTO_FRAME)
        extra += (payload / (RECORD_HEAD + TILE_FIXED) + 1) * (sizeof(proto_tile) + 8);
    r.arena_len = payload + extra;
    switch (msg->hdr.type) {
    case PROTO_FRAME: case PROTO_TILE: case PROTO_MESH_TOPOLOGY: case PROTO_MESH_VERTICES:
    case PROTO_QUERY: case PROTO_QUERY_RESULT: case PROTO_WAKE:
        r.arena = malloc(r.arena_len);
        if (!r.arena) {
            ocean_seterr(err, errlen, "out of memory decoding %s of %zu bytes", r.what, len);
            return OCEAN_ENOMEM;
        }
        break;
    default:
        break;
    }
    switch (msg->hdr.type) {
    case PROTO_HELLO: res = d_hello(&r, &msg->u.hello); break;
    case PROTO_SUBSCRIBE: res = d_subscribe(&r, &msg->u.subscribe); break;
    case PROTO_CAMERA: res = d_camera(&r, &msg->u.camera); break;
    case PROTO_FRAME: res = d_frame(&r, &msg->u.frame); break;
    case PROTO_TILE: res = d_tile(&r, &msg->u.tile); break;
    case PROTO_MESH_TOPOLOGY: res = d_topology(&r, &msg->u.topology); break;
    case PROTO_MESH_VERTICES: res = d_vertices(&r, &msg->u.vertices); break;
    case PROTO_QUERY: res = d_query(&r, &msg->u.query); break;
    case PROTO_QUERY_RESULT: res = d_result(&r, &msg->u.result); break;
    case PROTO_SEA_STATE: res = d_sea_state(&r, &msg->u.sea_state); break;
    case PROTO_ERROR: res = d_error(&r, &msg->u.error); break;
    case PROTO_BYE: res = d_bye(&r, &msg->u.bye); break;
    case PROTO_ENTITY: res = d_entity(&r, &msg->u.entity); break;
    case PROTO_WAKE: res = d_wake(&r, &msg->u.wake); break;
    default: res = OCEAN_ETYPE; break;
    }
    if (res == OCEAN_OK)
        res = v_msg(&c, msg);
    if (res != OCEAN_OK) {
        proto_header h = msg->hdr;
        free(r.arena);
        memset(msg, 0, sizeof *msg);
        msg->hdr = h;
        return res;
    }
    msg->owned_ = r.arena;
    return OCEAN_OK;
}

ocean_result proto_decode(const void *buf, size_t len, proto_msg *msg, char *err, size_t errlen)
{
    return proto_decode_limited(buf, len, NULL, msg, err, errlen);
}

/* ---- encoding --------------------------------------------------------- */

static ocean_result put(proto_buf *b, size_t n, uint8_t **p) { return proto_buf_grow(b, n, p); }

static ocean_result put_str(proto_buf *b, const char *s)
{
    size_t n = strlen(s);
    uint8_t *p;
    TRY(put(b, 2 + n, &p));
    proto_st16(p, (uint16_t)n);
    memcpy(p + 2, s, n);
    return OCEAN_OK;
}

static void set_sea(uint8_t *p, const proto_sea *s)
{
    p[0] = s->spectrum;
    p[1] = s->spreading;
    p[2] = s->flags;
    proto_st64(p + 8, s->seed);
    const double d[10] = {s->wind_u10, s->wind_dir_deg, s->fetch_m, s->depth_m, s->swell,
                          s->phillips_a, s->small_wave_m, s->choppiness, s->hs, s->tp};
    for (int i = 0; i < 10; i++)
        proto_stf64(p + 16 + 8 * i, d[i]);
}

size_t proto_tile_body_size(const proto_tile *t) { return TILE_FIXED + (size_t)t->payload_len; }

static ocean_result e_tile(proto_buf *b, const proto_tile *t)
{
    uint8_t *p;
    TRY(put(b, TILE_FIXED, &p));
    p[0] = t->level;
    p[1] = t->codec;
    proto_st16(p + 2, t->channels);
    proto_st16(p + 4, t->width);
    proto_st16(p + 6, t->height);
    proto_st32(p + 8, (uint32_t)t->ix);
    proto_st32(p + 12, (uint32_t)t->iz);
    proto_stf64(p + 16, t->origin_x);
    proto_stf64(p + 24, t->origin_z);
    proto_stf64(p + 32, t->spacing);
    proto_stf32(p + 40, t->error_bound);
    proto_st32(p + 44, t->payload_len);
    return proto_buf_append(b, t->payload, t->payload_len);
}

static void vertices_head_write(uint8_t *p, const proto_mesh_vertices *v)
{
    proto_st32(p, v->mesh_id);
    proto_st32(p + 4, v->vertex_count);
    for (int i = 0; i < 3; i++)
        proto_stf64(p + 8 + 8 * i, v->origin[i]);
}

static ocean_result e_vertices(proto_buf *b, const proto_mesh_vertices *v)
{
    uint8_t *p;
    TRY(put(b, VERTS_FIXED + 12 * (size_t)v->vertex_count, &p));
    vertices_head_write(p, v);
    for (size_t i = 0; i < 3 * (size_t)v->vertex_count; i++)
        proto_stf32(p + VERTS_FIXED + 4 * i, v->positions[i]);
    return OCEAN_OK;
}

static ocean_result e_vertices_qz(proto_buf *b, const proto_mesh_vertices *v)
{
    uint8_t *p;
    TRY(put(b, VERTS_FIXED, &p));
    vertices_head_write(p, v);
    return proto_buf_append(b, v->qz, v->qz_len);
}

static ocean_result e_placement(proto_buf *b, const proto_mesh_placement *pl)
{
    uint8_t *p;
    TRY(put(b, PROTO_MESH_PLACEMENT_SIZE, &p));
    proto_st32(p, pl->mesh_id);
    for (int i = 0; i < 3; i++)
        proto_stf64(p + 8 + 8 * i, pl->origin[i]);
    return OCEAN_OK;
}

static ocean_result e_record(proto_buf *b, int kind, const void *body, uint32_t tag)
{
    uint8_t *p;
    size_t at = b->len;
    TRY(put(b, RECORD_HEAD, &p));
    proto_st32(p + 4, tag);
    TRY(kind == REC_VERTICES ? e_vertices(b, body) : kind == REC_VERTICES_QZ ? e_vertices_qz(b, body)
        : kind == REC_PLACEMENT ? e_placement(b, body) : e_tile(b, body));
    size_t blen = b->len - at - RECORD_HEAD;
    if (blen > UINT32_MAX)
        return OCEAN_ETOOBIG;
    proto_st32(proto_buf_data(b) + at, (uint32_t)blen);
    size_t pad = (8u - (blen & 7u)) & 7u;
    return put(b, pad, &p);
}

static ocean_result e_hello(proto_buf *b, const proto_msg *m)
{
    uint8_t *p;
    const proto_hello *h = &m->u.hello;
    TRY(put(b, HELLO_FIXED, &p));
    proto_st32(p, h->codecs);
    p[4] = h->mesh_kinds;
    p[5] = h->effects;
    p[6] = h->cutoff_policies;
    p[7] = h->modes;
    proto_st32(p + 8, h->max_message);
    proto_st32(p + 12, h->max_query_points);
    proto_st16(p + 16, h->max_tile_size);
    p[18] = h->max_lod_levels;
    p[19] = h->max_layers;
    proto_stf32(p + 20, h->tick_rate_hz);
    proto_stf32(p + 24, h->max_frame_rate_hz);
    proto_st32(p + 28, h->client_id);
    set_sea(p + 32, &h->sea);
    return put_str(b, h->server_version);
}

static ocean_result e_subscribe(proto_buf *b, const proto_msg *m)
{
    uint8_t *p;
    const proto_subscribe *s = &m->u.subscribe;
    TRY(put(b, SUBSCRIBE_SIZE, &p));
    p[0] = s->effects;
    p[1] = s->mesh_kind;
    p[2] = s->codec;
    p[3] = s->cutoff_policy;
    p[4] = s->mode;
    p[5] = s->layers;
    p[6] = s->lod_levels;
    p[7] = s->layout;
    proto_st16(p + 8, s->tile_size);
    p[10] = s->mesh_codec;
    p[11] = s->flags;
    proto_stf32(p + 12, s->frame_rate_hz);
    proto_stf32(p + 16, s->accuracy);
    proto_stf32(p + 20, s->base_spacing_m);
    proto_stf32(p + 24, s->view_range_m);
    return OCEAN_OK;
}

static ocean_result e_camera(proto_buf *b, const proto_msg *m)
{
    uint8_t *p;
    const proto_camera *k = &m->u.camera;
    TRY(put(b, CAMERA_SIZE, &p));
    for (int i = 0; i < 3; i++) {
        proto_stf64(p + 8 * i, k->pos[i]);
        proto_stf32(p + 24 + 4 * i, k->vel[i]);
    }
    proto_stf32(p + 36, k->yaw_deg);
    proto_stf32(p + 40, k->pitch_deg);
    proto_stf32(p + 44, k->roll_deg);
    proto_stf32(p + 48, k->fov_y_deg);
    proto_st16(p + 52, k->viewport_w);
    proto_st16(p + 54, k->viewport_h);
    proto_stf64(p + 56, k->render_time);
    return OCEAN_OK;
}

static ocean_result e_frame(proto_buf *b, const proto_msg *m)
{
    uint8_t *p;
    const proto_frame *f = &m->u.frame;
    TRY(put(b, FRAME_FIXED, &p));
    proto_stf64(p, f->cutoff_k);
    proto_stf64(p + 8, f->e_error);
    for (int i = 0; i < 3; i++)
        proto_stf64(p + 16 + 8 * i, f->origin[i]);
    proto_st32(p + 40, f->camera_seq);
    proto_st32(p + 44, f->tick);
    proto_st16(p + 48, f->tile_count);
    p[50] = f->has_mesh;
    p[51] = f->layout;
    if (f->layout == PROTO_LAYOUT_CASCADE) {
        TRY(put(b, proto_cascade_block_bytes(f->cascades.cascade_count, f->cascades.flags), &p));
        cascade_block_write(p, &f->cascades);
    }
    if (f->tile_records) {
        /* one allocation for the whole frame: the records are most of it */
        size_t total = RECORD_HEAD + VERTS_FIXED;
        for (unsigned i = 0; i < f->tile_count; i++)
            total += f->tile_records[i].len;
        TRY(proto_buf_reserve(b, total));
    }
    for (unsigned i = 0; i < f->tile_count; i++) {
        if (f->tile_records) {
            size_t at = b->len;
            TRY(proto_buf_append(b, f->tile_records[i].p, f->tile_records[i].len));
            if (f->record_tags) proto_st32(proto_buf_data(b) + at + 4, f->record_tags[i]);
        } else {
            TRY(e_record(b, REC_TILE, &f->tiles[i], f->tiles[i].cascade | (f->tiles[i].slot ? PROTO_TAG_SLOT_B : 0u)));
        }
    }
    if (f->has_mesh && f->layout == PROTO_LAYOUT_CASCADE)
        TRY(e_record(b, REC_PLACEMENT, &f->placement, 0));
    else if (f->has_mesh)
        TRY(e_record(b, f->has_mesh == 2 ? REC_VERTICES_QZ : REC_VERTICES, &f->mesh, 0));
    return OCEAN_OK;
}

static ocean_result e_topology(proto_buf *b, const proto_msg *m)
{
    uint8_t *p;
    const proto_mesh_topology *t = &m->u.topology;
    size_t ic = t->index_count, vc = t->vertex_count;
    size_t at = b->len;
    TRY(put(b, TOPO_FIXED + 4 * ic + 5 * vc, &p));
    proto_st32(p, t->mesh_id);
    p[4] = t->mesh_kind;
    p[5] = t->lod_levels;
    proto_st16(p + 6, t->flags);
    proto_st32(p + 8, t->vertex_count);
    proto_st32(p + 12, t->index_count);
    uint8_t *q = p + TOPO_FIXED;
    for (size_t i = 0; i < ic; i++)
        proto_st32(q + 4 * i, t->indices[i]);
    q += 4 * ic;
    for (size_t i = 0; i < vc; i++)
        proto_stf32(q + 4 * i, t->morph[i]);
    memcpy(q + 4 * vc, t->level, vc);
    if (t->flags & PROTO_TOPO_FLAT) {
        /* flat floats 4-aligned from the message start (the header
         * is 32 bytes, so from the payload start too) */
        size_t pad = (4u - ((b->len - at) & 3u)) & 3u;
        TRY(put(b, pad + 8 * vc + 16 * (size_t)t->lod_levels, &p));
        memset(p, 0, pad);
        p += pad;
        for (size_t i = 0; i < 2 * vc; i++)
            proto_stf32(p + 4 * i, t->flat[i]);
        p += 8 * vc;
        for (size_t i = 0; i < 4 * (size_t)t->lod_levels; i++)
            proto_stf32(p + 4 * i, t->zones[i]);
    }
    return OCEAN_OK;
}

static ocean_result e_query(proto_buf *b, const proto_msg *m)
{
    uint8_t *p;
    const proto_query *q = &m->u.query;
    TRY(put(b, QUERY_FIXED + 16 * (size_t)q->count, &p));
    proto_st32(p, q->query_id);
    proto_st32(p + 4, q->count);
    p[8] = q->at_time;
    proto_stf64(p + 16, q->t);
    for (size_t i = 0; i < 2 * (size_t)q->count; i++)
        proto_stf64(p + QUERY_FIXED + 8 * i, q->points[i]);
    return OCEAN_OK;
}

static ocean_result e_result(proto_buf *b, const proto_msg *m)
{
    uint8_t *p;
    const proto_query_result *q = &m->u.result;
    TRY(put(b, RESULT_FIXED + SAMPLE_SIZE * (size_t)q->count, &p));
    proto_st32(p, q->query_id);
    proto_st32(p + 4, q->count);
    proto_stf64(p + 8, q->t);
    for (uint32_t i = 0; i < q->count; i++) {
        uint8_t *s = p + RESULT_FIXED + SAMPLE_SIZE * (size_t)i;
        const proto_query_sample *x = &q->samples[i];
        proto_stf32(s, x->height);
        for (int k = 0; k < 3; k++) {
            proto_stf32(s + 4 + 4 * k, x->normal[k]);
            proto_stf32(s + 16 + 4 * k, x->velocity[k]);
        }
        proto_stf32(s + 28, x->foam);
        proto_stf32(s + 32, x->error_bound);
    }
    return OCEAN_OK;
}

static ocean_result e_sea_state(proto_buf *b, const proto_msg *m)
{
    uint8_t *p;
    const proto_sea_state *s = &m->u.sea_state;
    TRY(put(b, SEASTATE_FIXED, &p));
    p[0] = s->op;
    proto_stf64(p + 8, s->effective_time);
    set_sea(p + 16, &s->sea);
    return put_str(b, s->token);
}

static ocean_result e_entity(proto_buf *b, const proto_msg *m)
{
    uint8_t *p;
    const proto_entity *e = &m->u.entity;
    TRY(put(b, ENTITY_FIXED, &p));
    p[0] = e->op;
    p[1] = e->kind;
    proto_st32(p + 4, e->id);
    proto_stf64(p + 8, e->t);
    proto_stf64(p + 16, e->x);
    proto_stf64(p + 24, e->z);
    const float f[6] = {e->altitude_m, e->heading_deg, e->speed, e->length_m, e->beam_m, e->draught_m};
    for (int i = 0; i < 6; i++) proto_stf32(p + 32 + 4 * i, f[i]);
    return put_str(b, e->token);
}

static ocean_result e_wake(proto_buf *b, const proto_msg *m)
{
    uint8_t *p;
    const proto_wake *w = &m->u.wake;
    TRY(put(b, WAKE_FIXED, &p));
    proto_stf64(p, w->speed);
    proto_stf64(p + 8, w->length);
    proto_stf64(p + 16, w->beam);
    proto_stf64(p + 24, w->depth);
    proto_st16(p + 32, w->nx);
    proto_st16(p + 34, w->nz);
    p[36] = w->codec;
    p[37] = p[38] = p[39] = 0;
    proto_stf32(p + 40, w->error_bound);
    proto_st32(p + 44, w->payload_len);
    uint8_t *d;
    TRY(put(b, w->payload_len, &d));
    if (w->payload_len) memcpy(d, w->payload, w->payload_len);
    return OCEAN_OK;
}

static ocean_result e_error(proto_buf *b, const proto_msg *m)
{
    uint8_t *p;
    const proto_error *e = &m->u.error;
    TRY(put(b, ERROR_FIXED, &p));
    proto_st16(p, e->code);
    proto_st16(p + 2, e->offending_type);
    proto_st32(p + 4, e->offending_seq);
    return put_str(b, e->message);
}

static ocean_result e_bye(proto_buf *b, const proto_msg *m)
{
    uint8_t *p;
    TRY(put(b, BYE_FIXED, &p));
    proto_st16(p, m->u.bye.reason);
    return put_str(b, m->u.bye.message);
}

static ocean_result e_tile_msg(proto_buf *b, const proto_msg *m) { return e_tile(b, &m->u.tile); }
static ocean_result e_vertices_msg(proto_buf *b, const proto_msg *m) { return e_vertices(b, &m->u.vertices); }

/* The payload encoder of each message type (index: the type). */
static ocean_result (*const e_payloads[])(proto_buf *b, const proto_msg *m) = {
    [PROTO_HELLO] = e_hello,     [PROTO_SUBSCRIBE] = e_subscribe,        [PROTO_CAMERA] = e_camera,
    [PROTO_FRAME] = e_frame,     [PROTO_TILE] = e_tile_msg,              [PROTO_MESH_TOPOLOGY] = e_topology,
    [PROTO_MESH_VERTICES] = e_vertices_msg, [PROTO_QUERY] = e_query,     [PROTO_QUERY_RESULT] = e_result,
    [PROTO_SEA_STATE] = e_sea_state, [PROTO_ERROR] = e_error,           [PROTO_BYE] = e_bye,
    [PROTO_ENTITY] = e_entity,   [PROTO_WAKE] = e_wake,
};

static ocean_result e_payload(proto_buf *b, const proto_msg *m)
{
    unsigned t = m->hdr.type;
    if (t >= sizeof e_payloads / sizeof e_payloads[0] || !e_payloads[t]) return OCEAN_ETYPE;
    return e_payloads[t](b, m);
}

ocean_result proto_encode(proto_buf *out, const proto_msg *msg, char *err, size_t errlen)
{
    proto_limits lim;
    proto_limits_default(&lim);
    ctx c = {err, errlen, &lim};
    if (!out || !msg)
        FAIL(&c, OCEAN_EINVAL, "proto_encode: NULL argument");
    if (msg->hdr.version != PROTO_VERSION)
        FAIL(&c, OCEAN_EVERSION, "cannot encode protocol version %u", msg->hdr.version);
    if (msg->hdr.flags != 0)
        FAIL(&c, OCEAN_EFORMAT, "header flags must be 0 in version 1");
    TRY(chk_time(&c, "header sim_time", msg->hdr.sim_time));
    TRY(v_msg(&c, msg));
    size_t start = out->len;
    uint8_t *h;
    ocean_result r = put(out, PROTO_HEADER_SIZE, &h);
    if (r == OCEAN_OK)
        r = e_payload(out, msg);
    if (r == OCEAN_OK && out->len - start > lim.max_message)
        r = OCEAN_ETOOBIG;
    if (r != OCEAN_OK) {
        proto_buf_truncate(out, start);
        FAIL(&c, r, "encoding %s failed: %s", proto_type_name(msg->hdr.type), ocean_strerror(r));
    }
    h = proto_buf_data(out) + start;
    proto_st32(h, PROTO_MAGIC);
    proto_st16(h + 4, PROTO_VERSION);
    proto_st16(h + 6, msg->hdr.type);
    proto_st32(h + 8, 0);
    proto_st32(h + 12, (uint32_t)(out->len - start - PROTO_HEADER_SIZE));
    proto_st32(h + 16, msg->hdr.seq);
    proto_st32(h + 20, 0);
    proto_stf64(h + 24, msg->hdr.sim_time);
    return OCEAN_OK;
}

ocean_result proto_error_reply(proto_buf *out, const void *bad, size_t badlen, ocean_result code,
                               const char *why, uint32_t seq, double sim_time)
{
    proto_msg m;
    proto_msg_init(&m, PROTO_ERROR);
    m.hdr.seq = seq;
    m.hdr.sim_time = ocean_time_ok(sim_time) ? sim_time : 0.0;
    m.u.error.code = (uint16_t)(code == OCEAN_OK ? OCEAN_EINVAL : code);
    const uint8_t *p = bad;
    if (p && badlen >= 8 && proto_ld32(p) == PROTO_MAGIC)
        m.u.error.offending_type = proto_ld16(p + 6);
    if (p && badlen >= 20 && proto_ld32(p) == PROTO_MAGIC)
        m.u.error.offending_seq = proto_ld32(p + 16);
    /* Copy the text, dropping bytes that would make it invalid UTF-8 on the
     * wire (messages may quote hostile input). */
    const char *s = why ? why : ocean_strerror(code);
    size_t n = 0;
    for (size_t i = 0; s[i] && n < PROTO_ERROR_MSG_MAX; i++) {
        unsigned char ch = (unsigned char)s[i];
        m.u.error.message[n++] = (ch < 0x20 || ch >= 0x7f) ? '?' : (char)ch;
    }
    m.u.error.message[n] = 0;
    return proto_encode(out, &m, NULL, 0);
}

ocean_result proto_tile_record_encode(proto_buf *out, const proto_tile *t, uint32_t tag, char *err,
                                      size_t errlen)
{
    if (err && errlen)
        err[0] = 0;
    proto_limits lim;
    proto_limits_default(&lim);
    ctx c = {err, errlen, &lim};
    if (!out || !t) {
        ocean_seterr(err, errlen, "tile record: NULL argument");
        return OCEAN_EINVAL;
    }
    TRY(v_tile(&c, t));
    if (tag >= PROTO_MAX_LAYERS) {
        ocean_seterr(err, errlen, "tile record: tag %u is not a cascade index (0..%d)", tag, PROTO_MAX_LAYERS - 1);
        return OCEAN_EINVAL;
    }
    size_t at = out->len;
    ocean_result r = e_record(out, REC_TILE, t, tag);
    if (r != OCEAN_OK)
        out->len = at;
    return r;
}

proto_window_step proto_window_next(int valid, uint32_t tick_a, uint16_t interval, const proto_mip_time *t)
{
    if (!t->interval || !valid) return PROTO_WINDOW_DROP;
    if (tick_a == t->tick_a && interval == t->interval) return PROTO_WINDOW_KEEP;
    return (uint32_t)(tick_a + interval) == t->tick_a ? PROTO_WINDOW_SHIFT : PROTO_WINDOW_DROP;
}
