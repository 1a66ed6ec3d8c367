/*
 * test_proto.c - the ocean.v1 messages: round trip of every type, every
 * test vector in tests/vectors/ (bytes <-> decoded text), and each kind of
 * bad input (truncated, oversized, wrong version, wrong type, bad enum,
 * NaN, lying lengths) giving its specified ocean_result; and "Where each
 * mip is read" (protocol/lod.c) by hand and as its vectors lod.txt and
 * lod_mss.txt.
 *
 * `test_proto --write-vectors DIR` (re)creates the vectors: NAME.bin is one
 * message, NAME.txt its decoded form (or "error = CODE" for the bad ones),
 * in the text format of dump() below, which tests/vectors/README.md
 * describes for implementers in other languages.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "lod.h"
#include "oc_wakes.h"
#include "proto.h"
#include "ocean_time.h"
#include "wake.h"

/* ---- canonical text dump of a decoded message ---------------------------- */

typedef struct sbuf {
    char *s;
    size_t n, cap;
} sbuf;

static void out(sbuf *b, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    if (k < 0)
        fail_msg("out: bad format %s", fmt);
    if (b->n + (size_t)k + 1 > b->cap) {
        b->cap = (b->cap + (size_t)k + 1) * 2;
        b->s = realloc(b->s, b->cap);
        if (!b->s)
            fail_msg("out: no memory");
    }
    va_start(ap, fmt);
    vsnprintf(b->s + b->n, b->cap - b->n, fmt, ap);
    va_end(ap);
    b->n += (size_t)k;
}

static void dump_sea(sbuf *b, const char *p, const proto_sea *s)
{
    out(b, "%s.spectrum = %u\n%s.spreading = %u\n%s.flags = %u\n%s.seed = %llu\n", p, s->spectrum, p, s->spreading,
        p, s->flags, p, (unsigned long long)s->seed);
    out(b, "%s.wind_u10 = %.17g\n%s.wind_dir_deg = %.17g\n%s.fetch_m = %.17g\n%s.depth_m = %.17g\n", p, s->wind_u10, p,
        s->wind_dir_deg, p, s->fetch_m, p, s->depth_m);
    out(b, "%s.swell = %.17g\n%s.phillips_a = %.17g\n%s.small_wave_m = %.17g\n%s.choppiness = %.17g\n", p, s->swell, p,
        s->phillips_a, p, s->small_wave_m, p, s->choppiness);
    out(b, "%s.hs = %.17g\n%s.tp = %.17g\n", p, s->hs, p, s->tp);
}

static void dump_tile(sbuf *b, const char *p, const proto_tile *t)
{
    out(b, "%s.level = %u\n%s.codec = %u\n%s.channels = %u\n%s.width = %u\n%s.height = %u\n", p, t->level, p, t->codec,
        p, t->channels, p, t->width, p, t->height);
    out(b, "%s.ix = %d\n%s.iz = %d\n%s.origin_x = %.17g\n%s.origin_z = %.17g\n%s.spacing = %.17g\n", p, t->ix, p, t->iz,
        p, t->origin_x, p, t->origin_z, p, t->spacing);
    out(b, "%s.error_bound = %.9g\n%s.payload_len = %u\n%s.payload =", p, (double)t->error_bound, p, t->payload_len, p);
    for (uint32_t i = 0; i < t->payload_len; i++)
        out(b, " %02x", t->payload[i]);
    out(b, "\n");
}

static void dump_verts(sbuf *b, const char *p, const proto_mesh_vertices *v)
{
    out(b, "%s.mesh_id = %u\n%s.vertex_count = %u\n%s.origin = %.17g %.17g %.17g\n%s.positions =", p, v->mesh_id, p,
        v->vertex_count, p, v->origin[0], v->origin[1], v->origin[2], p);
    for (size_t i = 0; i < 3 * (size_t)v->vertex_count; i++)
        out(b, " %.9g", (double)v->positions[i]);
    out(b, "\n");
}

static const uint32_t sample_idx[3];

/* A has_mesh 2 record: the fixed fields, the qz header, the payload bytes
 * and the positions decoded with the triangles of the mesh_topology vector
 * (its vertex count is the record's). */
static void dump_verts_qz(sbuf *b, const char *p, const proto_mesh_vertices *v)
{
    out(b, "%s.mesh_id = %u\n%s.vertex_count = %u\n%s.origin = %.17g %.17g %.17g\n", p, v->mesh_id, p,
        v->vertex_count, p, v->origin[0], v->origin[1], v->origin[2]);
    proto_mesh_qz_info in;
    if (proto_mesh_qz_header(v->qz, v->qz_len, v->vertex_count, &in, NULL, 0) == OCEAN_OK) {
        out(b, "%s.qz_header.format = %u\n%s.qz_header.predictor = %u\n", p, in.format, p, in.predictor);
        out(b, "%s.qz_header.base = %.9g %.9g %.9g\n%s.qz_header.step = %.9g %.9g %.9g\n%s.qz_header.nbytes = %u %u %u\n%s.qz_header.raw_len = %u\n",
            p, (double)in.base[0], (double)in.base[1], (double)in.base[2], p, (double)in.step[0], (double)in.step[1],
            (double)in.step[2], p, in.nbytes[0], in.nbytes[1], in.nbytes[2], p, in.raw_len);
    }
    out(b, "%s.qz =", p);
    for (uint32_t i = 0; i < v->qz_len; i++)
        out(b, " %02x", v->qz[i]);
    out(b, "\n");
    if (v->vertex_count == 3) {
        uint32_t refs[9];
        float pos[9];
        if (proto_mesh_qz_refs(sample_idx, 3, 3, refs) == OCEAN_OK &&
            proto_mesh_qz_decode(v->qz, v->qz_len, 3, refs, pos, NULL, 0) == OCEAN_OK) {
            out(b, "%s.positions =", p);
            for (int i = 0; i < 9; i++)
                out(b, " %.9g", (double)pos[i]);
            out(b, "\n");
        }
    }
}

static char *dump(const proto_msg *m)
{
    sbuf b = {0};
    out(&b, "version = %u\ntype = %s\nflags = %u\nseq = %u\nsim_time = %.17g\n", m->hdr.version,
        proto_type_name(m->hdr.type), m->hdr.flags, m->hdr.seq, m->hdr.sim_time);
    switch (m->hdr.type) {
    case PROTO_HELLO: {
        const proto_hello *h = &m->u.hello;
        out(&b, "codecs = %u\nmesh_kinds = %u\neffects = %u\ncutoff_policies = %u\nmodes = %u\n", h->codecs,
            h->mesh_kinds, h->effects, h->cutoff_policies, h->modes);
        out(&b, "max_message = %u\nmax_query_points = %u\nmax_tile_size = %u\nmax_lod_levels = %u\nmax_layers = %u\n",
            h->max_message, h->max_query_points, h->max_tile_size, h->max_lod_levels, h->max_layers);
        out(&b, "tick_rate_hz = %.9g\nmax_frame_rate_hz = %.9g\nclient_id = %u\n", (double)h->tick_rate_hz,
            (double)h->max_frame_rate_hz, h->client_id);
        dump_sea(&b, "sea", &h->sea);
        out(&b, "server_version = %s\n", h->server_version);
        break;
    }
    case PROTO_SUBSCRIBE: {
        const proto_subscribe *s = &m->u.subscribe;
        out(&b, "effects = %u\nmesh_kind = %u\ncodec = %u\ncutoff_policy = %u\nmode = %u\nlayers = %u\nlod_levels = %u\n",
            s->effects, s->mesh_kind, s->codec, s->cutoff_policy, s->mode, s->layers, s->lod_levels);
        out(&b, "layout = %u\ntile_size = %u\nmesh_codec = %u\nflags = %u\n", s->layout, s->tile_size, s->mesh_codec,
            s->flags);
        out(&b, "frame_rate_hz = %.9g\naccuracy = %.9g\nbase_spacing_m = %.9g\nview_range_m = %.9g\n",
            (double)s->frame_rate_hz, (double)s->accuracy, (double)s->base_spacing_m, (double)s->view_range_m);
        break;
    }
    case PROTO_CAMERA: {
        const proto_camera *k = &m->u.camera;
        out(&b, "pos = %.17g %.17g %.17g\nvel = %.9g %.9g %.9g\n", k->pos[0], k->pos[1], k->pos[2], (double)k->vel[0],
            (double)k->vel[1], (double)k->vel[2]);
        out(&b, "yaw_deg = %.9g\npitch_deg = %.9g\nroll_deg = %.9g\nfov_y_deg = %.9g\n", (double)k->yaw_deg,
            (double)k->pitch_deg, (double)k->roll_deg, (double)k->fov_y_deg);
        out(&b, "viewport = %u %u\nrender_time = %.17g\n", k->viewport_w, k->viewport_h, k->render_time);
        break;
    }
    case PROTO_FRAME: {
        const proto_frame *f = &m->u.frame;
        out(&b, "cutoff_k = %.17g\ne_error = %.17g\norigin = %.17g %.17g %.17g\ncamera_seq = %u\ntick = %u\n",
            f->cutoff_k, f->e_error, f->origin[0], f->origin[1], f->origin[2], f->camera_seq, f->tick);
        out(&b, "tile_count = %u\nhas_mesh = %u\nlayout = %u\n", f->tile_count, f->has_mesh, f->layout);
        if (f->layout == PROTO_LAYOUT_CASCADE) {
            const proto_cascade_block *k = &f->cascades;
            out(&b, "cascades.cascade_count = %u\ncascades.order = %u\ncascades.flags = %u\n", k->cascade_count,
                k->order, k->flags);
            out(&b, "cascades.spacing_per_m = %.9g\n", (double)k->spacing_per_m);
            out(&b, "cascades.camera = %.17g %.17g %.17g\ncascades.min_spacing_m = %.9g\ncascades.e_total = %.9g\n",
                k->camera[0], k->camera[1], k->camera[2], (double)k->min_spacing_m, (double)k->e_total);
            out(&b, "cascades.tail_mss = %.9g %.9g %.9g\n", (double)k->tail_mss[0], (double)k->tail_mss[1],
                (double)k->tail_mss[2]);
            out(&b, "cascades.geometry_spacing_m = %.9g\n", (double)k->geometry_spacing_m);
            if (k->flags & PROTO_CASCADE_FOAM) {
                out(&b, "cascades.foam_rows = %u\n", k->foam_rows);
                for (unsigned i = 0; i < k->foam_rows; i++)
                    out(&b, "cascades.foam[%u] = %.9g %.9g %.9g\n", i, (double)k->foam[i].sigma,
                        (double)k->foam[i].a, (double)k->foam[i].omega);
            }
            for (unsigned c = 0; c < k->cascade_count; c++) {
                const proto_cascade_entry *e = &k->cascade[c];
                out(&b, "cascade[%u].patch_m = %.17g\ncascade[%u].n = %u\ncascade[%u].mips = %u\ncascade[%u].fades = %u\n",
                    c, e->patch_m, c, e->n, c, e->mips, c, e->fades);
                out(&b, "cascade[%u].spacing_per_m = %.9g\n", c, (double)e->spacing_per_m);
                for (int q = 0; q <= e->mips; q++)
                    out(&b, "cascade[%u].mip[%d] = %.9g %.9g %.9g %.9g\n", c, q, (double)e->mip[q].kc,
                        (double)e->mip[q].mss_x, (double)e->mip[q].mss_z, (double)e->mip[q].mss_xz);
                for (int q = 0; q < e->mips; q++)
                    out(&b, "cascade[%u].time[%d] = %u %u %u\n", c, q, e->time[q].tick_a, e->time[q].interval,
                        e->time[q].phase);
                for (int q = 0; (k->flags & PROTO_CASCADE_READ) && q < e->mips; q++)
                    out(&b, "cascade[%u].held[%d] = %u %u %u\n", c, q, e->mip[q].held[0], e->mip[q].held[1],
                        e->mip[q].held[2]);
            }
        }
        for (unsigned i = 0; i < f->tile_count; i++) {
            char p[32];
            snprintf(p, sizeof p, "tile[%u]", i);
            /* the record's tag comes before its body */
            if (f->layout == PROTO_LAYOUT_CASCADE)
                out(&b, "%s.cascade = %u\n%s.slot = %u\n", p, f->tiles[i].cascade, p, f->tiles[i].slot);
            dump_tile(&b, p, &f->tiles[i]);
        }
        if (f->has_mesh && f->layout == PROTO_LAYOUT_CASCADE)
            out(&b, "placement.mesh_id = %u\nplacement.origin = %.17g %.17g %.17g\n", f->placement.mesh_id,
                f->placement.origin[0], f->placement.origin[1], f->placement.origin[2]);
        else if (f->has_mesh == 2)
            dump_verts_qz(&b, "mesh", &f->mesh);
        else if (f->has_mesh)
            dump_verts(&b, "mesh", &f->mesh);
        break;
    }
    case PROTO_TILE:
        dump_tile(&b, "tile", &m->u.tile);
        break;
    case PROTO_MESH_TOPOLOGY: {
        const proto_mesh_topology *t = &m->u.topology;
        out(&b, "mesh_id = %u\nmesh_kind = %u\nlod_levels = %u\nflags = %u\nvertex_count = %u\nindex_count = %u\nindices =",
            t->mesh_id, t->mesh_kind, t->lod_levels, t->flags, t->vertex_count, t->index_count);
        for (uint32_t i = 0; i < t->index_count; i++)
            out(&b, " %u", t->indices[i]);
        out(&b, "\nmorph =");
        for (uint32_t i = 0; i < t->vertex_count; i++)
            out(&b, " %.9g", (double)t->morph[i]);
        out(&b, "\nlevel =");
        for (uint32_t i = 0; i < t->vertex_count; i++)
            out(&b, " %u", t->level[i]);
        out(&b, "\n");
        if (t->flags & PROTO_TOPO_FLAT) {
            out(&b, "flat =");
            for (uint32_t i = 0; i < 2 * t->vertex_count; i++)
                out(&b, " %.9g", (double)t->flat[i]);
            out(&b, "\nzones =");
            for (uint32_t i = 0; i < 4u * t->lod_levels; i++)
                out(&b, " %.9g", (double)t->zones[i]);
            out(&b, "\n");
        }
        break;
    }
    case PROTO_MESH_VERTICES:
        dump_verts(&b, "mesh", &m->u.vertices);
        break;
    case PROTO_QUERY: {
        const proto_query *q = &m->u.query;
        out(&b, "query_id = %u\ncount = %u\nat_time = %u\nt = %.17g\npoints =", q->query_id, q->count, q->at_time, q->t);
        for (size_t i = 0; i < 2 * (size_t)q->count; i++)
            out(&b, " %.17g", q->points[i]);
        out(&b, "\n");
        break;
    }
    case PROTO_QUERY_RESULT: {
        const proto_query_result *r = &m->u.result;
        out(&b, "query_id = %u\ncount = %u\nt = %.17g\n", r->query_id, r->count, r->t);
        for (uint32_t i = 0; i < r->count; i++) {
            const proto_query_sample *s = &r->samples[i];
            out(&b, "sample[%u] = %.9g | %.9g %.9g %.9g | %.9g %.9g %.9g | %.9g | %.9g\n", i, (double)s->height,
                (double)s->normal[0], (double)s->normal[1], (double)s->normal[2], (double)s->velocity[0],
                (double)s->velocity[1], (double)s->velocity[2], (double)s->foam, (double)s->error_bound);
        }
        break;
    }
    case PROTO_SEA_STATE: {
        const proto_sea_state *s = &m->u.sea_state;
        out(&b, "op = %u\neffective_time = %.17g\n", s->op, s->effective_time);
        dump_sea(&b, "sea", &s->sea);
        out(&b, "token = %s\n", s->token);
        break;
    }
    case PROTO_ERROR:
        out(&b, "code = %u\noffending_type = %u\noffending_seq = %u\nmessage = %s\n", m->u.error.code,
            m->u.error.offending_type, m->u.error.offending_seq, m->u.error.message);
        break;
    case PROTO_BYE:
        out(&b, "reason = %u\nmessage = %s\n", m->u.bye.reason, m->u.bye.message);
        break;
    case PROTO_ENTITY: {
        const proto_entity *e = &m->u.entity;
        out(&b, "op = %u\nkind = %u\nid = %u\nt = %.17g\nx = %.17g\nz = %.17g\n", e->op, e->kind, e->id, e->t, e->x,
            e->z);
        out(&b, "altitude_m = %.9g\nheading_deg = %.9g\nspeed = %.9g\nlength_m = %.9g\nbeam_m = %.9g\n"
            "draught_m = %.9g\ntoken = %s\n", (double)e->altitude_m, (double)e->heading_deg, (double)e->speed,
            (double)e->length_m, (double)e->beam_m, (double)e->draught_m, e->token);
        break;
    }
    case PROTO_WAKE: {
        const proto_wake *w = &m->u.wake;
        out(&b, "speed = %.17g\nlength = %.17g\nbeam = %.17g\ndepth = %.17g\nnx = %u\nnz = %u\ncodec = %u\n"
            "error_bound = %.9g\npayload_len = %u\n", w->speed, w->length, w->beam, w->depth, w->nx, w->nz, w->codec,
            (double)w->error_bound, w->payload_len);
        break;
    }
    }
    return b.s;
}

/* ---- sample messages -------------------------------------------------------- */

static const uint8_t tile_payload[] = {0x00, 0x00, 0x80, 0x3f, 0x00, 0x00, 0x00, 0xc0,
                                       0x00, 0x00, 0x40, 0x40, 0x00, 0x00, 0x80, 0x3e}; /* f32 1,-2,3,0.25 */
static const proto_tile sample_tiles[2] = {
    {0, PROTO_CODEC_F32, PROTO_CH_HEIGHT, 2, 2, -3, 7, -384.0, 896.0, 2.0, 0.0f, 16, tile_payload, 0, 0},
    {2, PROTO_CODEC_F16, PROTO_CH_HEIGHT, 2, 1, 0, 0, 1e6 + 0.5, -2.5e6, 8.0, 0.00048828125f, 4, tile_payload, 0, 0},
};
/* A WAKE's plane of 2 x 2 coefficients: one block, its byte count, then
 * its f32 tile payload (1, -2, 3, 0.25). */
static const uint8_t wake_payload[] = {0x10, 0x00, 0x00, 0x00, 0x00, 0x00, 0x80, 0x3f, 0x00, 0x00, 0x00, 0xc0,
                                       0x00, 0x00, 0x40, 0x40, 0x00, 0x00, 0x80, 0x3e};
/* Layout-1 tiles: mip 1 of cascade 0 and mip 0 of cascade 1 (cascade-local origins). */
static const proto_tile cascade_tiles[2] = {
    {1, PROTO_CODEC_F32, PROTO_CH_HEIGHT, 2, 2, 3, 1, 46.875, 15.625, 7.8125, 0.0f, 16, tile_payload, 0, 0},
    {0, PROTO_CODEC_F32, PROTO_CH_HEIGHT, 2, 2, 0, 5, 0.0, 9.09375, 0.9093750, 0.0f, 16, tile_payload, 1, 0},
};
/* frame_cascade_time: tile 0 is sample B of cascade 0's mip 1 */
static const proto_tile cascade_time_tiles[2] = {
    {1, PROTO_CODEC_F32, PROTO_CH_HEIGHT, 2, 2, 3, 1, 46.875, 15.625, 7.8125, 0.0f, 16, tile_payload, 0, 1},
    {0, PROTO_CODEC_F32, PROTO_CH_HEIGHT, 2, 2, 0, 5, 0.0, 9.09375, 0.9093750, 0.0f, 16, tile_payload, 1, 0},
};
static const float sample_flat[6] = {-1, 0, 1, 0, 0, 1.5f};
static const float sample_zones[8] = {1, 30, 4.5f, 0, 2, 120, 18, 0};
static const float sample_pos[9] = {0, 0.5f, 0, 10, -0.25f, 0, 0, 0.125f, 10};
static const uint32_t sample_idx[3] = {0, 2, 1};
static const float sample_morph[3] = {0, 0.5f, 1};
static const uint8_t sample_level[3] = {0, 1, 1};
static const double sample_points[6] = {0, 0, 1234567.875, -42.5, -1e9, 3.25};
static const proto_query_sample sample_samples[2] = {
    {0.75f, {0.1f, 0.99f, 0.0f}, {0.5f, 0.25f, -0.125f}, 0.0f, 0.001f},
    {-1.5f, {0.0f, 1.0f, 0.0f}, {0.0f, 0.0f, 0.0f}, 0.875f, 0.0625f},
};

static void sample_sea(proto_sea *s)
{
    s->spectrum = 2;
    s->spreading = 1;
    s->seed = 0x0123456789abcdefull;
    s->wind_u10 = 12.5;
    s->wind_dir_deg = 30;
    s->fetch_m = 1e5;
    s->depth_m = 4000;
    s->swell = 0.25;
    s->phillips_a = 8.1e-3;
    s->small_wave_m = 0.01;
    s->choppiness = 1.2;
    s->hs = 2.75;
    s->tp = 8.5;
}

/* Fills m with the sample message of `type`. */
static void sample(proto_msg *m, proto_type type)
{
    proto_msg_init(m, type);
    m->hdr.seq = 1000u + type;
    m->hdr.sim_time = 12345.678;
    switch (type) {
    case PROTO_HELLO: {
        proto_hello *h = &m->u.hello;
        h->codecs = 0x7f;
        h->mesh_kinds = 0xf;
        h->effects = 31;
        h->cutoff_policies = 7;
        h->modes = 3;
        h->max_message = 1 << 20;
        h->max_query_points = 10000;
        h->max_tile_size = 256;
        h->max_lod_levels = 8;
        h->max_layers = 4;
        h->tick_rate_hz = 30;
        h->max_frame_rate_hz = 60;
        h->client_id = 42;
        sample_sea(&h->sea);
        strcpy(h->server_version, "oceand 0.1.0 \xc3\xa9t\xc3\xa9");
        break;
    }
    case PROTO_SUBSCRIBE:
        m->u.subscribe = (proto_subscribe){PROTO_FX_HEIGHT | PROTO_FX_NORMALS, PROTO_MESH_CONCENTRIC, PROTO_CODEC_QZ,
                                           PROTO_CUTOFF_ANTIALIAS, PROTO_MODE_LIVE, 2, 5, 64, 30.0f, 0.005f, 0.0f, 5000.0f,
                                           PROTO_LAYOUT_WORLD, PROTO_MESH_CODEC_QZ, 0};
        break;
    case PROTO_CAMERA:
        m->u.camera = (proto_camera){{1e7 + 0.125, 150.0, -2.5e6}, {250.0f, 0.0f, -3.5f}, 45.0f, -10.0f, 5.0f, 60.0f,
                                     1920, 1080, 0.0};
        break;
    case PROTO_FRAME:
        m->u.frame = (proto_frame){0.5, 0.03125, {1e7, 0.0, -2.5e6}, 77, 9001, 2, sample_tiles, 1,
                                   {3, 3, {1e7, 0.0, -2.5e6}, sample_pos, NULL, 0}, PROTO_LAYOUT_WORLD, NULL, NULL, {0, {0, 0, 0}},
                                   {0}};
        break;
    case PROTO_TILE:
        m->u.tile = sample_tiles[0];
        break;
    case PROTO_MESH_TOPOLOGY:
        m->u.topology = (proto_mesh_topology){3, PROTO_MESH_CONCENTRIC, 2, 3, 3, sample_idx, sample_morph, sample_level,
                                              0, NULL, NULL};
        break;
    case PROTO_MESH_VERTICES:
        m->u.vertices = (proto_mesh_vertices){3, 3, {-5.5, 0.0, 1e6}, sample_pos, NULL, 0};
        break;
    case PROTO_QUERY:
        m->u.query = (proto_query){7, 3, 1, 600.25, sample_points};
        break;
    case PROTO_QUERY_RESULT:
        m->u.result = (proto_query_result){7, 2, 600.25, sample_samples};
        break;
    case PROTO_SEA_STATE:
        m->u.sea_state.op = PROTO_SEA_SET;
        m->u.sea_state.effective_time = 13000.0;
        sample_sea(&m->u.sea_state.sea);
        strcpy(m->u.sea_state.token, "s3cret-admin-token");
        break;
    case PROTO_ERROR:
        m->u.error.code = OCEAN_ETYPE;
        m->u.error.offending_type = 77;
        m->u.error.offending_seq = 5;
        strcpy(m->u.error.message, "message type 77 unknown (valid 1..12)");
        break;
    case PROTO_BYE:
        m->u.bye.reason = PROTO_BYE_SHUTDOWN;
        strcpy(m->u.bye.message, "server shutting down");
        break;
    case PROTO_ENTITY:
        /* a frigate 1000 km out, at a time with a fraction */
        m->u.entity = (proto_entity){PROTO_ENTITY_SET, 0, 1001, 600.25, 1e6 + 0.5, -2.5e5, 0.0f, 271.5f, 12.5f,
                                     120.0f, 14.5f, 4.25f, "s3cret-entity-token"};
        break;
    case PROTO_WAKE:
        /* a frigate's rung at 8 m/s over 50 m of water */
        m->u.wake = (proto_wake){8.0, 120.0, 15.0, 50.0, 2, 2, PROTO_CODEC_F32, 0.00048828125f,
                                 (uint32_t)sizeof wake_payload, wake_payload};
        break;
    default:
        break;
    }
}

/* The layout-1 variants, named as their vectors. */
static void sample_cascade_block(proto_cascade_block *b)
{
    memset(b, 0, sizeof *b);
    b->cascade_count = 2;
    b->order = 6;
    b->spacing_per_m = 0.046875f;
    b->camera[0] = 1e7 + 0.125;
    b->camera[1] = 25.0;
    b->camera[2] = -2.5e6;
    b->min_spacing_m = 0.0f;
    b->e_total = 0.0078125f;
    b->tail_mss[0] = 0.0125f;
    b->tail_mss[1] = 0.00625f;
    b->tail_mss[2] = -0.0009765625f;
    b->geometry_spacing_m = 2.5f; /* the finest lattice of a mesh 25 m up */
    proto_cascade_entry *e = &b->cascade[0];
    e->patch_m = 1000;
    e->n = 256;
    e->mips = 2;
    e->fades = 0;
    e->mip[0] = (proto_mip_entry){INFINITY, 0.00390625f, 0.001953125f, 0.0f, {0}};
    e->mip[1] = (proto_mip_entry){0.36f, 0.0078125f, 0.00390625f, 0.0001220703125f, {0}};
    e->mip[2] = (proto_mip_entry){0.0f, 0.03125f, 0.015625f, 0.000244140625f, {0}};
    e->spacing_per_m = b->spacing_per_m;
    e = &b->cascade[1];
    e->spacing_per_m = b->spacing_per_m / 4;
    e->patch_m = 232.8;
    e->n = 256;
    e->mips = 1;
    e->fades = 1;
    e->mip[0] = (proto_mip_entry){INFINITY, 0.0f, 0.0f, 0.0f, {0}};
    e->mip[1] = (proto_mip_entry){0.0f, 0.015625f, 0.0078125f, -0.000244140625f, {0}};
}

static int sample_named(proto_msg *m, const char *name)
{
    if (!strcmp(name, "frame_cascade")) {
        sample(m, PROTO_FRAME);
        proto_frame *f = &m->u.frame;
        f->layout = PROTO_LAYOUT_CASCADE;
        f->tiles = cascade_tiles;
        sample_cascade_block(&f->cascades);
        f->placement.mesh_id = 3;
        f->placement.origin[0] = 1e7;
        f->placement.origin[2] = -2.5e6 - 8;
        return 0;
    }
    if (!strcmp(name, "frame_cascade_foam")) {
        /* with the whitecap table (PROTOCOL.md "Whitecaps in layout 1") */
        sample_named(m, "frame_cascade");
        proto_cascade_block *b = &m->u.frame.cascades;
        b->flags = PROTO_CASCADE_FOAM | PROTO_CASCADE_READ;
        b->foam_rows = 3;
        b->foam[0] = (proto_foam_row){0.0625f, -0.015625f, 0.875f};
        b->foam[1] = (proto_foam_row){0.125f, 0.0625f, 1.25f};
        b->foam[2] = (proto_foam_row){0.25f, 0.25f, 1.625f};
        /* and the read table: bilinear, Keys, Lanczos-3 shares / 32768 */
        static const uint16_t held[3][3] = {{29098, 32244, 33063}, {27787, 32014, 33194}, {28672, 31744, 33792}};
        for (int k = 0; k < 3; k++) {
            proto_mip_entry *e = &b->cascade[k < 2 ? 0 : 1].mip[k < 2 ? k : 0];
            memcpy(e->held, held[k], sizeof e->held);
        }
        return 0;
    }
    if (!strcmp(name, "frame_cascade_time")) {
        /* a key frame of a time-interpolating subscription: cascade 0's
         * mip 1 every 4 ticks (a quarter of the way from A to B), cascade
         * 1's mip 0 every 8, with sample A's tick wrapped below 2^32 */
        sample_named(m, "frame_cascade");
        proto_frame *f = &m->u.frame;
        f->tiles = cascade_time_tiles;
        f->cascades.flags = PROTO_CASCADE_KEY;
        f->cascades.cascade[0].time[1] = (proto_mip_time){1000, 4, 16384};
        f->cascades.cascade[1].time[0] = (proto_mip_time){0xFFFFFFFEu, 8, 49152};
        return 0;
    }
    if (!strcmp(name, "frame_mesh_qz")) {
        /* layout 0 with qz positions, for the mesh_topology vector's mesh */
        static proto_buf qz;
        static int made;
        if (!made) {
            uint32_t refs[9];
            proto_codec_ctx *cx = NULL;
            proto_buf_init(&qz, 0);
            if (proto_codec_ctx_create(&cx) != OCEAN_OK || proto_mesh_qz_refs(sample_idx, 3, 3, refs) != OCEAN_OK ||
                proto_mesh_qz_encode(cx, 0.005, 3, sample_pos, refs, &qz, NULL, NULL, 0) != OCEAN_OK)
                return -1;
            proto_codec_ctx_destroy(cx);
            made = 1;
        }
        sample(m, PROTO_FRAME);
        m->u.frame.has_mesh = 2;
        m->u.frame.mesh.positions = NULL;
        m->u.frame.mesh.qz = proto_buf_data(&qz);
        m->u.frame.mesh.qz_len = (uint32_t)proto_buf_len(&qz);
        return 0;
    }
    if (!strcmp(name, "mesh_topology_flat")) {
        sample(m, PROTO_MESH_TOPOLOGY);
        m->u.topology.flags = PROTO_TOPO_FLAT;
        m->u.topology.flat = sample_flat;
        m->u.topology.zones = sample_zones;
        return 0;
    }
    if (!strcmp(name, "sea_state_announce")) {
        sample(m, PROTO_SEA_STATE);
        m->u.sea_state.op = PROTO_SEA_ANNOUNCE;
        m->u.sea_state.token[0] = 0;
        return 0;
    }
    if (!strcmp(name, "sea_state_no_whitecaps")) { /* a CIGI host's Maritime Control turned them off */
        sample(m, PROTO_SEA_STATE);
        m->u.sea_state.op = PROTO_SEA_ANNOUNCE;
        m->u.sea_state.token[0] = 0;
        m->u.sea_state.sea.flags = PROTO_SEA_NO_WHITECAPS;
        return 0;
    }
    if (!strcmp(name, "sea_state_get")) {
        proto_msg_init(m, PROTO_SEA_STATE);
        m->hdr.seq = 9;
        m->hdr.sim_time = 12.5;
        m->u.sea_state.op = PROTO_SEA_GET;
        return 0;
    }
    if (!strcmp(name, "entity_announce")) {
        sample(m, PROTO_ENTITY);
        m->u.entity.op = PROTO_ENTITY_ANNOUNCE;
        m->u.entity.kind = 1;
        m->u.entity.altitude_m = 35.0f;
        m->u.entity.beam_m = m->u.entity.draught_m = 0.0f;
        m->u.entity.length_m = 16.0f;
        m->u.entity.token[0] = 0;
        return 0;
    }
    if (!strcmp(name, "entity_remove") || !strcmp(name, "entity_gone") || !strcmp(name, "entity_get")) {
        proto_msg_init(m, PROTO_ENTITY);
        m->hdr.seq = 11;
        m->hdr.sim_time = 601.5;
        m->u.entity.op = name[7] == 'r' ? PROTO_ENTITY_REMOVE : name[7] == 'g' && name[8] == 'o' ? PROTO_ENTITY_GONE
                                                                                               : PROTO_ENTITY_GET;
        if (m->u.entity.op != PROTO_ENTITY_GET) m->u.entity.id = 1001;
        if (m->u.entity.op == PROTO_ENTITY_REMOVE) strcpy(m->u.entity.token, "s3cret-entity-token");
        return 0;
    }
    if (!strcmp(name, "subscribe_cascade")) {
        sample(m, PROTO_SUBSCRIBE);
        m->u.subscribe.layout = PROTO_LAYOUT_CASCADE;
        m->u.subscribe.layers = 3;
        m->u.subscribe.flags = PROTO_SUB_FULL_GEOMETRY;
        return 0;
    }
    for (int t = 1; t < PROTO_TYPE_END_; t++) {
        char buf[64];
        snprintf(buf, sizeof buf, "%s", proto_type_name((proto_type)t));
        for (char *c = buf; *c; c++)
            *c = (char)(*c >= 'A' && *c <= 'Z' ? *c + 32 : *c);
        if (!strcmp(name, buf)) {
            sample(m, (proto_type)t);
            return 0;
        }
    }
    return -1;
}

static const char *const extra_vectors[] = {"frame_cascade", "frame_cascade_foam", "frame_cascade_time", "mesh_topology_flat", "subscribe_cascade",
                                            "sea_state_announce", "sea_state_no_whitecaps", "sea_state_get",
                                            "frame_mesh_qz", "entity_announce",
                                            "entity_remove", "entity_gone", "entity_get"};
#define N_EXTRA ((int)(sizeof extra_vectors / sizeof extra_vectors[0]))

static uint8_t *encode_sample(proto_type type, size_t *len)
{
    proto_msg m;
    sample(&m, type);
    proto_buf b;
    proto_buf_init(&b, 0);
    char err[256];
    if (proto_encode(&b, &m, err, sizeof err) != OCEAN_OK)
        fail_msg("encode %s: %s", proto_type_name(type), err);
    *len = b.len;
    uint8_t *copy = malloc(b.len);
    memcpy(copy, proto_buf_data(&b), b.len);
    proto_buf_free(&b);
    return copy;
}

/* Decodes an exact-size copy (so ASan catches any overread). */
static ocean_result decode_exact(const uint8_t *p, size_t n, proto_msg *m, char *err, size_t errlen)
{
    uint8_t *c = malloc(n ? n : 1);
    if (n)
        memcpy(c, p, n);
    ocean_result r = proto_decode(c, n, m, err, errlen);
    free(c);
    return r;
}

/* ---- tests ---------------------------------------------------------------- */

/* One time limit (sim/ocean_time.h): every time field of the protocol
 * carries |t| <= OCEAN_TIME_MAX; the decoder and the encoder refuse the
 * next double with a message naming the field and the limit. */
static double *time_field(proto_msg *m, int which)
{
    switch (which) {
    case 0: return &m->hdr.sim_time;
    case 1: return &m->u.camera.render_time;
    case 2: return &m->u.query.t;
    case 3: return &m->u.result.t;
    default: return &m->u.sea_state.effective_time;
    }
}

static void test_time_limit(void **state)
{
    (void)state;
    const proto_type types[5] = {PROTO_BYE, PROTO_CAMERA, PROTO_QUERY, PROTO_QUERY_RESULT,
                                 PROTO_SEA_STATE};
    const char *names[5] = {"sim_time", "camera.render_time", "query.t", "query_result.t",
                            "sea_state.effective_time"};
    for (int w = 0; w < 5; w++) {
        proto_msg m, d;
        sample(&m, types[w]);
        *time_field(&m, w) = 777.25; /* a byte pattern found once in the message */
        proto_buf b;
        proto_buf_init(&b, 0);
        char err[256] = "";
        assert_int_equal(proto_encode(&b, &m, err, sizeof err), OCEAN_OK);
        uint8_t pat[8];
        proto_stf64(pat, 777.25);
        uint8_t *data = proto_buf_data(&b);
        uint8_t *at = memmem(data, b.len, pat, 8);
        assert_non_null(at);
        assert_null(memmem(at + 1, b.len - (size_t)(at + 1 - data), pat, 8));
        double vals[4] = {OCEAN_TIME_MAX, -OCEAN_TIME_MAX, nextafter(OCEAN_TIME_MAX, INFINITY), -1e16};
        for (int v = 0; v < 4; v++) {
            proto_stf64(at, vals[v]);
            ocean_result r = decode_exact(data, b.len, &d, err, sizeof err);
            if (v < 2) {
                if (r != OCEAN_OK)
                    fail_msg("%s = %.17g refused: %s", names[w], vals[v], err);
                assert_true(*time_field(&d, w) == vals[v]);
                proto_msg_free(&d);
            } else {
                assert_int_equal(r, OCEAN_EINVAL);
                if (!strstr(err, names[w]) || !strstr(err, "OCEAN_TIME_MAX"))
                    fail_msg("%s = %.17g: message '%s' names neither field nor limit", names[w],
                             vals[v], err);
            }
        }
        proto_buf_free(&b);
        /* and nothing beyond the limit is encoded */
        *time_field(&m, w) = nextafter(OCEAN_TIME_MAX, INFINITY);
        proto_buf_init(&b, 0);
        assert_int_equal(proto_encode(&b, &m, err, sizeof err), OCEAN_EINVAL);
        assert_non_null(strstr(err, "OCEAN_TIME_MAX"));
        proto_buf_free(&b);
    }
}

static void test_roundtrip_all(void **state)
{
    (void)state;
    for (int t = 1; t < PROTO_TYPE_END_; t++) {
        proto_msg m, d;
        sample(&m, (proto_type)t);
        size_t n;
        uint8_t *bytes = encode_sample((proto_type)t, &n);
        char err[256];
        ocean_result r = decode_exact(bytes, n, &d, err, sizeof err);
        if (r != OCEAN_OK)
            fail_msg("decode %s: %s", proto_type_name(t), err);
        char *a = dump(&m), *b = dump(&d);
        assert_string_equal(a, b);
        /* re-encoding the decoded message gives the same bytes */
        proto_buf pb;
        proto_buf_init(&pb, 16);
        assert_int_equal(proto_encode(&pb, &d, err, sizeof err), OCEAN_OK);
        assert_int_equal(pb.len, n);
        assert_memory_equal(proto_buf_data(&pb), bytes, n);
        /* arrays are 4/8-byte aligned within the message (JS typed arrays) */
        if (t == PROTO_QUERY)
            assert_int_equal((PROTO_HEADER_SIZE + 24) % 8, 0);
        proto_buf_free(&pb);
        proto_msg_free(&d);
        free(a);
        free(b);
        free(bytes);
    }
}

/* proto_frame_client_fields finds camera_seq and the mesh's mesh_id in an
 * encoded FRAME: rewriting them there decodes as a frame carrying the new
 * values and nothing else changed; anything not a whole FRAME is refused. */
static void test_frame_client_fields(void **state)
{
    (void)state;
    for (int with_mesh = 0; with_mesh <= 2; with_mesh++) {
        proto_msg m, d;
        /* 2: the qz mesh record (has_mesh 2) */
        sample_named(&m, with_mesh == 2 ? "frame_mesh_qz" : "frame");
        if (with_mesh < 2)
            m.u.frame.has_mesh = (uint8_t)with_mesh;
        proto_buf pb;
        proto_buf_init(&pb, 0);
        char err[256];
        assert_int_equal(proto_encode(&pb, &m, err, sizeof err), OCEAN_OK);
        uint8_t *b = proto_buf_data(&pb);
        size_t cam_at = 0, mesh_at = 99;
        assert_int_equal(proto_frame_client_fields(b, pb.len, &cam_at, &mesh_at), OCEAN_OK);
        assert_int_equal(proto_ld32(b + cam_at), m.u.frame.camera_seq);
        if (with_mesh) {
            assert_int_equal(proto_ld32(b + mesh_at), m.u.frame.mesh.mesh_id);
            proto_st32(b + mesh_at, 0xABCD1234u);
        } else {
            assert_int_equal(mesh_at, 0);
        }
        proto_st32(b + cam_at, 4242u);
        assert_int_equal(decode_exact(b, pb.len, &d, err, sizeof err), OCEAN_OK);
        assert_int_equal(d.u.frame.camera_seq, 4242u);
        if (with_mesh)
            assert_int_equal(d.u.frame.mesh.mesh_id, 0xABCD1234u);
        assert_int_equal(d.u.frame.tick, m.u.frame.tick);
        assert_int_equal(d.u.frame.tile_count, m.u.frame.tile_count);
        proto_msg_free(&d);
        /* Every truncation is refused, and so is another message type. */
        for (size_t cut = 0; cut < pb.len; cut += 7) {
            size_t a = 1, z = 1;
            if (proto_frame_client_fields(b, cut, &a, &z) == OCEAN_OK)
                fail_msg("a FRAME cut to %zu of %zu bytes was accepted", cut, pb.len);
            assert_true(a == 1 && z == 1);
        }
        proto_buf_free(&pb);
    }
    size_t n, a, z;
    uint8_t *cam = encode_sample(PROTO_CAMERA, &n);
    assert_int_equal(proto_frame_client_fields(cam, n, &a, &z), OCEAN_EFORMAT);
    free(cam);
    assert_int_equal(proto_frame_client_fields(NULL, 100, &a, &z), OCEAN_EFORMAT);
}

static void test_header_errors(void **state)
{
    (void)state;
    size_t n;
    uint8_t *good = encode_sample(PROTO_CAMERA, &n);
    uint8_t *m = malloc(n + 8);
    proto_msg d;
    char err[256];
#define EXPECT(code) do { ocean_result r_ = decode_exact(m, len, &d, err, sizeof err); \
        if (r_ != (code)) fail_msg("line %d: got %d (%s), want %d", __LINE__, r_, err, (code)); \
        assert_true(strlen(err) > 0); } while (0)
    size_t len;
    /* truncated: every length short of the full message */
    for (len = 0; len < n; len++) {
        memcpy(m, good, len);
        ocean_result r = decode_exact(m, len, &d, err, sizeof err);
        assert_int_equal(r, OCEAN_ETRUNC);
    }
    len = n;
    memcpy(m, good, n);
    m[0] = 'X';
    EXPECT(OCEAN_EFORMAT);                          /* magic */
    memcpy(m, good, n);
    proto_st16(m + 4, 2);
    EXPECT(OCEAN_EVERSION);                         /* wrong version */
    assert_non_null(strstr(err, "version 2"));
    memcpy(m, good, n);
    proto_st16(m + 6, 0);
    EXPECT(OCEAN_ETYPE);                            /* type 0 */
    proto_st16(m + 6, PROTO_TYPE_END_);
    EXPECT(OCEAN_ETYPE);                            /* unknown type */
    assert_int_equal(d.hdr.type, PROTO_TYPE_END_); /* header kept for the ERROR reply */
    memcpy(m, good, n);
    proto_st32(m + 8, 1);
    EXPECT(OCEAN_EFORMAT);                          /* flags */
    memcpy(m, good, n);
    proto_st32(m + 20, 1);
    EXPECT(OCEAN_EFORMAT);                          /* reserved */
    memcpy(m, good, n);
    proto_stf64(m + 24, NAN);
    EXPECT(OCEAN_EINVAL);                           /* NaN sim_time */
    proto_stf64(m + 24, -INFINITY);
    EXPECT(OCEAN_EINVAL);
    memcpy(m, good, n);
    proto_st32(m + 12, proto_ld32(good + 12) + 1);
    EXPECT(OCEAN_ETRUNC);                           /* length says more than there is */
    proto_st32(m + 12, proto_ld32(good + 12) - 1);
    EXPECT(OCEAN_EFORMAT);                          /* length says less: trailing byte */
    memcpy(m, good, n);
    m[n] = 0;
    len = n + 1;
    EXPECT(OCEAN_EFORMAT);                          /* extra byte after the message */
    len = n;
    proto_st32(m + 12, 0xFFFFFFF0u);
    EXPECT(OCEAN_ETOOBIG);                          /* oversized */
    /* a lower limit */
    proto_limits lim;
    proto_limits_default(&lim);
    lim.max_message = (uint32_t)n - 1;
    memcpy(m, good, n);
    assert_int_equal(proto_decode_limited(m, n, &lim, &d, err, sizeof err), OCEAN_ETOOBIG);
#undef EXPECT
    free(m);
    free(good);
}

/* Mutates one field of an encoded sample and expects `code`. */
static void expect_field(proto_type t, size_t off, int width, uint64_t value, ocean_result code)
{
    size_t n;
    uint8_t *m = encode_sample(t, &n);
    assert_true(off + (size_t)width <= n);
    if (width == 1)
        m[off] = (uint8_t)value;
    else if (width == 2)
        proto_st16(m + off, (uint16_t)value);
    else if (width == 4)
        proto_st32(m + off, (uint32_t)value);
    else
        proto_st64(m + off, value);
    proto_msg d;
    char err[256] = "";
    ocean_result r = decode_exact(m, n, &d, err, sizeof err);
    if (r != code)
        fail_msg("%s offset %zu = 0x%llx: got %d (%s), want %d", proto_type_name(t), off,
                 (unsigned long long)value, r, err, code);
    assert_true(r == OCEAN_OK || strlen(err) > 0);
    proto_msg_free(&d);
    free(m);
}

static uint64_t f64bits(double v)
{
    uint64_t u;
    memcpy(&u, &v, 8);
    return u;
}

static uint32_t f32bits(float v)
{
    uint32_t u;
    memcpy(&u, &v, 4);
    return u;
}

#define P(x) (PROTO_HEADER_SIZE + (x))

static void test_payload_errors(void **state)
{
    (void)state;
    /* bad enums -> ETYPE */
    expect_field(PROTO_SUBSCRIBE, P(0), 1, 0x20, OCEAN_ETYPE);   /* effects unknown bit */
    expect_field(PROTO_SUBSCRIBE, P(1), 1, 4, OCEAN_ETYPE);      /* mesh kind */
    expect_field(PROTO_SUBSCRIBE, P(2), 1, PROTO_CODEC_COUNT_, OCEAN_ETYPE);
    expect_field(PROTO_SUBSCRIBE, P(3), 1, 3, OCEAN_ETYPE);      /* cutoff policy */
    expect_field(PROTO_SUBSCRIBE, P(4), 1, 2, OCEAN_ETYPE);      /* mode */
    expect_field(PROTO_TILE, P(1), 1, 200, OCEAN_ETYPE);         /* tile codec */
    expect_field(PROTO_TILE, P(2), 2, 0x80, OCEAN_ETYPE);        /* tile channels */
    expect_field(PROTO_MESH_TOPOLOGY, P(4), 1, 3, OCEAN_ETYPE);  /* kind none */
    expect_field(PROTO_QUERY, P(8), 1, 2, OCEAN_ETYPE);          /* at_time */
    expect_field(PROTO_SEA_STATE, P(0), 1, 3, OCEAN_ETYPE);      /* op */
    expect_field(PROTO_SEA_STATE, P(0), 1, 2, OCEAN_EFORMAT);    /* get carrying a sea */
    expect_field(PROTO_SEA_STATE, P(16), 1, 4, OCEAN_ETYPE);     /* spectrum */
    expect_field(PROTO_BYE, P(0), 2, 7, OCEAN_ETYPE);            /* reason */
    expect_field(PROTO_HELLO, P(0), 4, 0x80, OCEAN_ETYPE);       /* codec mask */
    /* NaN / Inf -> EINVAL */
    expect_field(PROTO_CAMERA, P(0), 8, f64bits(NAN), OCEAN_EINVAL);
    expect_field(PROTO_CAMERA, P(8), 8, f64bits(INFINITY), OCEAN_EINVAL);
    expect_field(PROTO_CAMERA, P(24), 4, f32bits(NAN), OCEAN_EINVAL);
    expect_field(PROTO_CAMERA, P(48), 4, f32bits(0.0f), OCEAN_EINVAL);   /* fov 0 */
    expect_field(PROTO_CAMERA, P(52), 2, 0, OCEAN_EINVAL);               /* viewport 0 */
    expect_field(PROTO_CAMERA, P(56), 8, f64bits(NAN), OCEAN_EINVAL);
    expect_field(PROTO_SUBSCRIBE, P(12), 4, f32bits(NAN), OCEAN_EINVAL);
    expect_field(PROTO_SUBSCRIBE, P(12), 4, f32bits(0.0f), OCEAN_EINVAL);
    expect_field(PROTO_SUBSCRIBE, P(16), 4, f32bits(INFINITY), OCEAN_EINVAL);
    expect_field(PROTO_SUBSCRIBE, P(16), 4, f32bits(1e-9f), OCEAN_EINVAL);
    expect_field(PROTO_SUBSCRIBE, P(8), 2, 1, OCEAN_EINVAL);            /* tile size 1 */
    expect_field(PROTO_SUBSCRIBE, P(0), 1, 0, OCEAN_EINVAL);            /* no effects */
    expect_field(PROTO_FRAME, P(0), 8, f64bits(NAN), OCEAN_EINVAL);
    expect_field(PROTO_FRAME, P(0), 8, f64bits(INFINITY), OCEAN_OK);    /* unfiltered */
    expect_field(PROTO_FRAME, P(0), 8, f64bits(-1.0), OCEAN_EINVAL);
    expect_field(PROTO_FRAME, P(8), 8, f64bits(2.0), OCEAN_EINVAL);     /* e_error > 1 */
    expect_field(PROTO_TILE, P(16), 8, f64bits(NAN), OCEAN_EINVAL);
    expect_field(PROTO_TILE, P(32), 8, f64bits(0.0), OCEAN_EINVAL);     /* spacing 0 */
    expect_field(PROTO_TILE, P(48), 4, f32bits(NAN), OCEAN_OK);         /* payload bytes are opaque here */
    expect_field(PROTO_MESH_VERTICES, P(32), 4, f32bits(NAN), OCEAN_EINVAL);
    expect_field(PROTO_QUERY, P(24), 8, f64bits(NAN), OCEAN_EINVAL);
    expect_field(PROTO_QUERY, P(16), 8, f64bits(INFINITY), OCEAN_EINVAL);
    expect_field(PROTO_QUERY_RESULT, P(16), 4, f32bits(NAN), OCEAN_EINVAL);
    expect_field(PROTO_SEA_STATE, P(32), 8, f64bits(NAN), OCEAN_EINVAL); /* wind */
    expect_field(PROTO_SEA_STATE, P(32), 8, f64bits(200.0), OCEAN_EINVAL);
    expect_field(PROTO_SEA_STATE, P(8), 8, f64bits(NAN), OCEAN_EINVAL);  /* effective time */
    expect_field(PROTO_MESH_TOPOLOGY, P(16), 4, 3, OCEAN_EINVAL);       /* index >= vertex_count */
    expect_field(PROTO_MESH_TOPOLOGY, P(28), 4, f32bits(1.5f), OCEAN_EINVAL); /* morph */
    expect_field(PROTO_MESH_TOPOLOGY, P(40), 1, 2, OCEAN_EINVAL);       /* level >= lod_levels */
    expect_field(PROTO_ERROR, P(0), 2, 0, OCEAN_EINVAL);                /* code 0 */
    /* lying counts and lengths -> ETRUNC; limits -> ETOOBIG */
    expect_field(PROTO_QUERY, P(4), 4, 4, OCEAN_ETRUNC);
    expect_field(PROTO_QUERY, P(4), 4, 2, OCEAN_EFORMAT);               /* fewer: trailing point */
    expect_field(PROTO_QUERY, P(4), 4, PROTO_MAX_QUERY_POINTS + 1, OCEAN_ETOOBIG);
    expect_field(PROTO_QUERY, P(4), 4, 0, OCEAN_EFORMAT);               /* 0 points but bytes follow */
    expect_field(PROTO_QUERY_RESULT, P(4), 4, 3, OCEAN_ETRUNC);
    expect_field(PROTO_MESH_VERTICES, P(4), 4, 4, OCEAN_ETRUNC);
    expect_field(PROTO_MESH_VERTICES, P(4), 4, 0xFFFFFFFFu, OCEAN_ETOOBIG);
    expect_field(PROTO_MESH_TOPOLOGY, P(12), 4, 6, OCEAN_ETRUNC);
    expect_field(PROTO_MESH_TOPOLOGY, P(12), 4, 0xFFFFFFFFu, OCEAN_ETOOBIG);
    expect_field(PROTO_TILE, P(44), 4, 17, OCEAN_ETRUNC);               /* payload_len lies */
    expect_field(PROTO_TILE, P(44), 4, 0xFFFFFFFFu, OCEAN_ETRUNC);
    expect_field(PROTO_TILE, P(4), 2, 3, OCEAN_EFORMAT);                /* f32 size mismatch */
    expect_field(PROTO_FRAME, P(48), 2, 3, OCEAN_ETRUNC);               /* tile_count lies */
    expect_field(PROTO_FRAME, P(48), 2, 5000, OCEAN_ETOOBIG);
    expect_field(PROTO_FRAME, P(50), 1, 3, OCEAN_EFORMAT);              /* has_mesh */
    expect_field(PROTO_FRAME, P(50), 1, 2, OCEAN_ECODEC);               /* f32 body read as qz */
    expect_field(PROTO_SUBSCRIBE, P(10), 1, 1, OCEAN_ETYPE);            /* mesh_codec */
    expect_field(PROTO_SUBSCRIBE, P(10), 1, 0, OCEAN_OK);               /* mesh_codec f32 */
    expect_field(PROTO_FRAME, P(56), 4, 1000, OCEAN_ETRUNC);            /* record length lies */
    expect_field(PROTO_FRAME, P(56), 4, 63, OCEAN_ETRUNC);              /* record shorter than its tile */
    expect_field(PROTO_FRAME, P(60), 4, 1, OCEAN_EFORMAT);              /* record reserved */
    expect_field(PROTO_HELLO, P(128), 2, 64, OCEAN_ETOOBIG);            /* string too long */
    expect_field(PROTO_HELLO, P(128), 2, 40, OCEAN_ETRUNC);             /* string longer than message */
    expect_field(PROTO_HELLO, P(130), 1, 0xff, OCEAN_EFORMAT);          /* bad UTF-8 */
    expect_field(PROTO_BYE, P(4), 2, 300, OCEAN_ETOOBIG);
    expect_field(PROTO_BYE, P(6), 1, 0, OCEAN_EFORMAT);                 /* NUL in string */
    /* reserved bytes -> EFORMAT */
    expect_field(PROTO_SUBSCRIBE, P(7), 1, 2, OCEAN_ETYPE);      /* layout */
    expect_field(PROTO_QUERY, P(9), 1, 1, OCEAN_EFORMAT);
    expect_field(PROTO_SEA_STATE, P(19), 1, 1, OCEAN_EFORMAT);
    expect_field(PROTO_SEA_STATE, P(18), 1, 2, OCEAN_ETYPE);     /* sea flags: an unknown bit */
    expect_field(PROTO_MESH_TOPOLOGY, P(6), 2, 2, OCEAN_EFORMAT);
    /* sea state announce with a token */
    proto_msg m;
    sample(&m, PROTO_SEA_STATE);
    m.u.sea_state.op = PROTO_SEA_ANNOUNCE;
    proto_buf b;
    proto_buf_init(&b, 0);
    char err[256];
    assert_int_equal(proto_encode(&b, &m, err, sizeof err), OCEAN_EFORMAT);
    m.u.sea_state.token[0] = 0;
    assert_int_equal(proto_encode(&b, &m, err, sizeof err), OCEAN_OK);
    proto_buf_free(&b);
}

static void test_truncate_every_type(void **state)
{
    (void)state;
    /* Every message cut anywhere, with the header's length fixed up to
     * match (a "consistent" truncation), fails cleanly and never overreads. */
    for (int t = 1; t < PROTO_TYPE_END_; t++) {
        size_t n;
        uint8_t *m = encode_sample((proto_type)t, &n);
        for (size_t cut = PROTO_HEADER_SIZE; cut < n; cut++) {
            uint8_t *c = malloc(cut);
            memcpy(c, m, cut);
            proto_st32(c + 12, (uint32_t)(cut - PROTO_HEADER_SIZE));
            proto_msg d;
            char err[256];
            ocean_result r = proto_decode(c, cut, &d, err, sizeof err);
            if (r == OCEAN_OK)
                fail_msg("%s cut to %zu decoded", proto_type_name(t), cut);
            assert_true(r == OCEAN_ETRUNC || r == OCEAN_EFORMAT || r == OCEAN_EINVAL || r == OCEAN_ETYPE);
            free(c);
        }
        free(m);
    }
}

static void test_encode_refuses(void **state)
{
    (void)state;
    proto_buf b;
    proto_buf_init(&b, 0);
    char err[256];
    proto_msg m;
    sample(&m, PROTO_CAMERA);
    m.u.camera.pos[0] = NAN;
    assert_int_equal(proto_encode(&b, &m, err, sizeof err), OCEAN_EINVAL);
    assert_int_equal(b.len, 0);
    sample(&m, PROTO_SUBSCRIBE);
    m.u.subscribe.codec = 99;
    assert_int_equal(proto_encode(&b, &m, err, sizeof err), OCEAN_ETYPE);
    sample(&m, PROTO_BYE);
    memset(m.u.bye.message, 'a', sizeof m.u.bye.message); /* unterminated */
    assert_int_equal(proto_encode(&b, &m, err, sizeof err), OCEAN_ETOOBIG);
    sample(&m, PROTO_HELLO);
    m.hdr.version = 2;
    assert_int_equal(proto_encode(&b, &m, err, sizeof err), OCEAN_EVERSION);
    sample(&m, PROTO_HELLO);
    m.hdr.type = 99;
    assert_int_equal(proto_encode(&b, &m, err, sizeof err), OCEAN_ETYPE);
    assert_int_equal(b.len, 0);
    /* a large query at the 10000-point scale encodes and decodes */
    double *pts = malloc(2 * 10000 * sizeof *pts);
    for (int i = 0; i < 20000; i++)
        pts[i] = i * 0.5 - 3000;
    proto_msg_init(&m, PROTO_QUERY);
    m.u.query = (proto_query){1, 10000, 0, 0.0, pts};
    assert_int_equal(proto_encode(&b, &m, err, sizeof err), OCEAN_OK);
    proto_msg d;
    assert_int_equal(proto_decode(proto_buf_data(&b), b.len, &d, err, sizeof err), OCEAN_OK);
    assert_int_equal(d.u.query.count, 10000);
    assert_memory_equal(d.u.query.points, pts, 2 * 10000 * sizeof *pts);
    proto_msg_free(&d);
    proto_msg_free(NULL);
    free(pts);
    proto_buf_free(&b);
}

static void test_error_reply(void **state)
{
    (void)state;
    size_t n;
    uint8_t *bad = encode_sample(PROTO_CAMERA, &n);
    proto_st16(bad + 4, 9);
    proto_msg d;
    char err[256];
    ocean_result r = proto_decode(bad, n, &d, err, sizeof err);
    assert_int_equal(r, OCEAN_EVERSION);
    proto_buf b;
    proto_buf_init(&b, 16);
    assert_int_equal(proto_error_reply(&b, bad, n, r, err, 55, 99.5), OCEAN_OK);
    assert_int_equal(b.head, 16);
    proto_msg e;
    assert_int_equal(proto_decode(proto_buf_data(&b), b.len, &e, err, sizeof err), OCEAN_OK);
    assert_int_equal(e.hdr.type, PROTO_ERROR);
    assert_int_equal(e.hdr.seq, 55);
    assert_true(e.hdr.sim_time == 99.5);
    assert_int_equal(e.u.error.code, OCEAN_EVERSION);
    assert_int_equal(e.u.error.offending_type, PROTO_CAMERA);
    assert_int_equal(e.u.error.offending_seq, 1000 + PROTO_CAMERA);
    assert_non_null(strstr(e.u.error.message, "version 9"));
    /* garbage input, hostile text: still a valid ERROR */
    proto_buf_reset(&b);
    assert_int_equal(proto_error_reply(&b, "xy", 2, OCEAN_ETRUNC, "bad \xff\x01 text", 1, NAN), OCEAN_OK);
    assert_int_equal(proto_decode(proto_buf_data(&b), b.len, &e, err, sizeof err), OCEAN_OK);
    assert_int_equal(e.u.error.offending_type, 0);
    assert_string_equal(e.u.error.message, "bad ?? text");
    char longmsg[3000];
    memset(longmsg, 'x', sizeof longmsg - 1);
    longmsg[sizeof longmsg - 1] = 0;
    proto_buf_reset(&b);
    assert_int_equal(proto_error_reply(&b, NULL, 0, OCEAN_EINVAL, longmsg, 1, 0), OCEAN_OK);
    assert_int_equal(proto_decode(proto_buf_data(&b), b.len, &e, err, sizeof err), OCEAN_OK);
    assert_int_equal(strlen(e.u.error.message), PROTO_ERROR_MSG_MAX);
    proto_buf_free(&b);
    free(bad);
}

/* ---- test vectors ----------------------------------------------------------- */

/* The qz payload of frame_mesh_qz: after the frame's fixed fields, its
 * tile records (72 and 64 bytes), the mesh record's head and the 32
 * fixed bytes. */
#define QZ_AT (56 + 72 + 64 + 8 + 32)

/* An offset counted back from the message's end (for the last record). */
#define END_BASE ((size_t)1 << 40)
#define END(x) (END_BASE + (size_t)(x))

typedef struct bad_vector {
    const char *name;
    const char *base;
    size_t off;
    int width;
    uint64_t value;
    ocean_result code;
    long cut; /* >= 0: truncate the message to this many bytes */
} bad_vector;

static const bad_vector bad_vectors[] = {
    {"bad_truncated_header", "bye", 0, 0, 0, OCEAN_ETRUNC, 20},
    {"bad_truncated_payload", "camera", 0, 0, 0, OCEAN_ETRUNC, 60},
    {"bad_magic", "bye", 0, 1, 'X', OCEAN_EFORMAT, -1},
    {"bad_version", "bye", 4, 2, 2, OCEAN_EVERSION, -1},
    {"bad_type", "bye", 6, 2, 99, OCEAN_ETYPE, -1},
    {"bad_oversized", "bye", 12, 4, 0x7FFFFFFF, OCEAN_ETOOBIG, -1},
    {"bad_length_lies", "bye", 12, 4, 200, OCEAN_ETRUNC, -1},
    {"bad_nan_sim_time", "bye", 24, 8, 0x7FF8000000000000ull, OCEAN_EINVAL, -1},
    {"bad_enum_codec", "subscribe", P(2), 1, 50, OCEAN_ETYPE, -1},
    {"bad_sea_flags", "sea_state_announce", P(18), 1, 6, OCEAN_ETYPE, -1},
    {"bad_nan_camera", "camera", P(16), 8, 0x7FF8000000000000ull, OCEAN_EINVAL, -1},
    {"bad_query_count_lies", "query", P(4), 4, 1000, OCEAN_ETRUNC, -1},
    {"bad_frame_record_lies", "frame", P(56), 4, 4096, OCEAN_ETRUNC, -1},
    {"bad_frame_layout", "frame", P(51), 1, 7, OCEAN_ETYPE, -1},
    {"bad_cascade_tag", "frame_cascade", P(56 + 56 + 2 * 320 + 4), 4, 2, OCEAN_EFORMAT, -1},
    {"bad_cascade_nan_spacing", "frame_cascade", P(56 + 4), 4, 0x7FC00000u, OCEAN_EINVAL, -1},
    {"bad_cascade_count", "frame_cascade", P(56), 1, 5, OCEAN_EINVAL, -1},
    /* cascade 1's own q (entry offset 12) twice the block's 0.046875 */
    {"bad_cascade_entry_spacing", "frame_cascade", P(56 + 56 + 320 + 12), 4, 0x3DC00000u, OCEAN_EINVAL, -1},
    /* geometry_spacing_m (block offset 52) -1 */
    {"bad_cascade_geometry_spacing", "frame_cascade", P(56 + 52), 4, 0xBF800000u, OCEAN_EINVAL, -1},
    {"bad_topology_flags", "mesh_topology_flat", P(6), 2, 2, OCEAN_EFORMAT, -1},
    /* zone 1's lattice (after 3 indices, morph, level, 1 padding byte and
     * 3 flat points: offset 84) 4 where zone 0's is 1 */
    {"bad_topology_zone_ratio", "mesh_topology_flat", P(84), 4, 0x40800000u, OCEAN_EINVAL, -1},
    {"bad_subscribe_layout", "subscribe", P(7), 1, 2, OCEAN_ETYPE, -1},
    {"bad_sea_get_with_sea", "sea_state_get", P(32), 8, 0x4024000000000000ull, OCEAN_EFORMAT, -1},
    {"bad_sea_op", "sea_state", P(0), 1, 3, OCEAN_ETYPE, -1},
    {"bad_wake_reserved", "wake", P(37), 1, 1, OCEAN_EFORMAT, -1},
    {"bad_wake_nan_speed", "wake", P(0), 8, 0x7FF8000000000000ull, OCEAN_EINVAL, -1},
    {"bad_wake_nx", "wake", P(32), 2, 0, OCEAN_EINVAL, -1},
    {"bad_wake_codec", "wake", P(36), 1, 50, OCEAN_ETYPE, -1},
    {"bad_wake_payload_lies", "wake", P(44), 4, 4096, OCEAN_ETRUNC, -1},
    {"bad_entity_op", "entity", P(0), 1, 5, OCEAN_ETYPE, -1},
    {"bad_entity_kind", "entity", P(1), 1, 3, OCEAN_ETYPE, -1},
    {"bad_entity_reserved", "entity", P(2), 1, 1, OCEAN_EFORMAT, -1},
    {"bad_entity_nan_x", "entity", P(16), 8, 0x7FF8000000000000ull, OCEAN_EINVAL, -1},
    {"bad_entity_inf_speed", "entity", P(40), 4, 0x7F800000u, OCEAN_EINVAL, -1},
    {"bad_entity_get_id", "entity_get", P(4), 4, 7, OCEAN_EFORMAT, -1},
    {"bad_entity_remove_sample", "entity_remove", P(16), 8, 0x4024000000000000ull, OCEAN_EFORMAT, -1},
    {"bad_subscribe_mesh_codec", "subscribe", P(10), 1, 1, OCEAN_ETYPE, -1},
    /* SUBSCRIBE.flags: bit 2 is not defined */
    {"bad_subscribe_flags", "subscribe", P(11), 1, 4, OCEAN_EFORMAT, -1},
    /* cascade block flags: bit 3 is not defined */
    {"bad_cascade_flags", "frame_cascade", P(56 + 2), 1, 8, OCEAN_EFORMAT, -1},
    /* the read table (after the whitecap table): cascade 0's mip 0 holds
     * no share for the bilinear kernel; cascade 1 (one mip) a share for a
     * mip 1 it does not have */
    {"bad_read_held", "frame_cascade_foam", P(56 + 56 + 2 * 320 + 200), 2, 0, OCEAN_EINVAL, -1},
    {"bad_read_beyond_mips", "frame_cascade_foam", P(56 + 56 + 2 * 320 + 200 + 72 + 6), 2, 1, OCEAN_EFORMAT, -1},
    /* the whitecap table (after the two entries): no rows with the flag */
    {"bad_foam_rows", "frame_cascade_foam", P(56 + 56 + 2 * 320), 1, 0, OCEAN_EINVAL, -1},
    {"bad_foam_reserved", "frame_cascade_foam", P(56 + 56 + 2 * 320 + 1), 1, 1, OCEAN_EFORMAT, -1},
    /* row 1's sigma equal to row 0's 0.0625: rows must ascend */
    {"bad_foam_order", "frame_cascade_foam", P(56 + 56 + 2 * 320 + 8 + 12), 4, 0x3D800000u, OCEAN_EINVAL, -1},
    /* row 0's foot a = 1, above the breaking index 1/2 */
    {"bad_foam_a", "frame_cascade_foam", P(56 + 56 + 2 * 320 + 8 + 4), 4, 0x3F800000u, OCEAN_EINVAL, -1},
    /* cascade 0's time[0] (after its 13 mip entries): a tick with interval 0 */
    {"bad_cascade_time", "frame_cascade", P(56 + 56 + 16 + 16 * 13), 4, 7, OCEAN_EFORMAT, -1},
    /* the first record's tag: sample B of a mip without a time interval */
    {"bad_cascade_slot", "frame_cascade", P(56 + 56 + 2 * 320 + 4), 4, 0x100, OCEAN_EINVAL, -1},
    {"bad_frame_has_mesh", "frame_mesh_qz", P(50), 1, 3, OCEAN_EFORMAT, -1},
    {"bad_frame_cascade_mesh_qz", "frame_cascade", P(50), 1, 2, OCEAN_EFORMAT, -1},
    {"bad_mesh_qz_format", "frame_mesh_qz", P(QZ_AT), 1, 9, OCEAN_ECODEC, -1},
    {"bad_mesh_qz_step", "frame_mesh_qz", P(QZ_AT + 16), 4, 0, OCEAN_ECODEC, -1},
    {"bad_mesh_qz_nan_base", "frame_mesh_qz", P(QZ_AT + 8), 4, 0x7FC00000u, OCEAN_ECODEC, -1},
    {"bad_mesh_qz_raw_len", "frame_mesh_qz", P(QZ_AT + 32), 4, 1, OCEAN_ECODEC, -1},
    {"bad_mesh_qz_vertex_count", "frame_mesh_qz", P(QZ_AT - 28), 4, 4, OCEAN_ECODEC, -1},
    /* the zstd frame (at QZ_AT + 36: magic, descriptor 0x20 = one segment,
     * a 1-byte content size, then one raw last block): a content size
     * other than the header's, and a last block that says it is not */
    {"bad_mesh_qz_zstd_size", "frame_mesh_qz", P(QZ_AT + 41), 1, 16, OCEAN_ECODEC, -1},
    {"bad_mesh_qz_zstd_blocks", "frame_mesh_qz", P(QZ_AT + 42), 1, 0x78, OCEAN_ECODEC, -1},
    /* record tags: a layout-0 tile record's (must be 0), a layout-1 tile
     * record's with a bit above bit 8, a layout-1 mesh record's (must be 0) */
    {"bad_frame_tag", "frame", P(56 + 4), 4, 1, OCEAN_EFORMAT, -1},
    {"bad_cascade_tag_bits", "frame_cascade", P(56 + 56 + 2 * 320 + 4), 4, 0x200, OCEAN_EFORMAT, -1},
    {"bad_cascade_mesh_tag", "frame_cascade", END(PROTO_MESH_PLACEMENT_SIZE + 4), 4, 1, OCEAN_EFORMAT, -1},
    /* an f32 tile 3 samples wide whose payload holds 2 x 2 */
    {"bad_tile_f32_size", "tile", P(4), 2, 3, OCEAN_EFORMAT, -1},
    /* tail_mss x (block offset 40) -1: only the cross moment xz may be negative */
    {"bad_cascade_tail_mss", "frame_cascade", P(56 + 40), 4, 0xBF800000u, OCEAN_EINVAL, -1},
};

static const char *code_name(ocean_result r)
{
    static const char *n[] = {"OCEAN_OK", "OCEAN_EINVAL", "OCEAN_ENOMEM", "OCEAN_EIO", "OCEAN_EFORMAT",
                              "OCEAN_EVERSION", "OCEAN_ETYPE", "OCEAN_ETRUNC", "OCEAN_ETOOBIG",
                              "OCEAN_EUNSUPPORTED", "OCEAN_EAUTH", "OCEAN_ERATE", "OCEAN_ESTATE",
                              "OCEAN_ECODEC", "OCEAN_ENOTFOUND", "OCEAN_EDIVERGED"};
    return (unsigned)r < sizeof n / sizeof n[0] ? n[r] : "?";
}

static int write_file(const char *path, const void *p, size_t n)
{
    FILE *f = fopen(path, "wb");
    if (!f)
        return -1;
    size_t w = fwrite(p, 1, n, f);
    return fclose(f) == 0 && w == n ? 0 : -1;
}

static uint8_t *read_file(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long sz = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *p = malloc((size_t)sz + 1);
    *n = fread(p, 1, (size_t)sz, f);
    p[*n] = 0;
    fclose(f);
    return p;
}

static const char *type_file(proto_type t)
{
    static char buf[64];
    snprintf(buf, sizeof buf, "%s", proto_type_name(t));
    for (char *c = buf; *c; c++)
        *c = (char)(*c >= 'A' && *c <= 'Z' ? *c + 32 : *c);
    return buf;
}

static int write_lod_vectors(const char *dir);
static int wake_read_vectors(const char *dir, int write);

static int write_vectors(const char *dir)
{
    char path[512];
    for (int t = 1; t < PROTO_TYPE_END_ + N_EXTRA; t++) {
        const char *name = t < PROTO_TYPE_END_ ? type_file((proto_type)t) : extra_vectors[t - PROTO_TYPE_END_];
        char nm[64];
        snprintf(nm, sizeof nm, "%s", name);
        proto_msg m;
        sample_named(&m, nm);
        proto_buf b;
        proto_buf_init(&b, 0);
        char err[256];
        if (proto_encode(&b, &m, err, sizeof err) != OCEAN_OK) {
            fprintf(stderr, "%s: %s\n", nm, err);
            return 1;
        }
        snprintf(path, sizeof path, "%s/%s.bin", dir, nm);
        if (write_file(path, proto_buf_data(&b), b.len))
            return 1;
        proto_msg d;
        proto_decode(proto_buf_data(&b), b.len, &d, NULL, 0);
        char *txt = dump(&d);
        snprintf(path, sizeof path, "%s/%s.txt", dir, nm);
        if (write_file(path, txt, strlen(txt)))
            return 1;
        free(txt);
        proto_msg_free(&d);
        proto_buf_free(&b);
    }
    for (size_t k = 0; k < sizeof bad_vectors / sizeof bad_vectors[0]; k++) {
        const bad_vector *v = &bad_vectors[k];
        proto_msg m;
        sample_named(&m, v->base);
        proto_buf b;
        proto_buf_init(&b, 0);
        proto_encode(&b, &m, NULL, 0);
        uint8_t *p = proto_buf_data(&b);
        size_t n = v->cut >= 0 ? (size_t)v->cut : b.len;
        size_t at = v->off >= END_BASE ? b.len - (v->off - END_BASE) : v->off;
        if (v->width == 1) p[at] = (uint8_t)v->value;
        else if (v->width == 2) proto_st16(p + at, (uint16_t)v->value);
        else if (v->width == 4) proto_st32(p + at, (uint32_t)v->value);
        else if (v->width == 8) proto_st64(p + at, v->value);
        proto_msg d;
        char err[256];
        ocean_result r = proto_decode(p, n, &d, err, sizeof err);
        if (r != v->code) {
            fprintf(stderr, "%s: got %d (%s)\n", v->name, r, err);
            return 1;
        }
        snprintf(path, sizeof path, "%s/%s.bin", dir, v->name);
        if (write_file(path, p, n))
            return 1;
        char txt[128];
        snprintf(txt, sizeof txt, "error = %s (%d)\n", code_name(v->code), v->code);
        snprintf(path, sizeof path, "%s/%s.txt", dir, v->name);
        if (write_file(path, txt, strlen(txt)))
            return 1;
        proto_buf_free(&b);
    }
    return write_lod_vectors(dir) || wake_read_vectors(dir, 1) ? 1 : 0;
}

static const char *vector_dir(void)
{
    const char *d = getenv("OCEAN_VECTORS");
    return d ? d : "tests/vectors";
}

static void test_vectors(void **state)
{
    (void)state;
    DIR *dir = opendir(vector_dir());
    if (!dir)
        fail_msg("cannot open %s (run from the repository root)", vector_dir());
    int good = 0, bad = 0;
    struct dirent *e;
    while ((e = readdir(dir))) {
        size_t l = strlen(e->d_name);
        if (l < 5 || strcmp(e->d_name + l - 4, ".bin"))
            continue;
        char path[600], tpath[600];
        snprintf(path, sizeof path, "%s/%s", vector_dir(), e->d_name);
        snprintf(tpath, sizeof tpath, "%s/%.*s.txt", vector_dir(), (int)(l - 4), e->d_name);
        size_t n, tn;
        uint8_t *bin = read_file(path, &n);
        char *want = (char *)read_file(tpath, &tn);
        if (!bin || !want)
            fail_msg("vector %s lacks its expectation %s", path, tpath);
        proto_msg d;
        char err[256];
        ocean_result r = decode_exact(bin, n, &d, err, sizeof err);
        if (strncmp(want, "error = ", 8) == 0) {
            char got[128];
            snprintf(got, sizeof got, "error = %s (%d)\n", code_name(r), r);
            if (strcmp(got, want))
                fail_msg("%s: decoded to %s, expected %s", e->d_name, got, want);
            bad++;
        } else {
            if (r != OCEAN_OK)
                fail_msg("%s: %s", e->d_name, err);
            char *txt = dump(&d);
            if (strcmp(txt, want))
                fail_msg("%s: decoded text differs from %s:\n%s", e->d_name, tpath, txt);
            /* and the encoder reproduces the vector byte for byte */
            proto_buf b;
            proto_buf_init(&b, 0);
            assert_int_equal(proto_encode(&b, &d, err, sizeof err), OCEAN_OK);
            assert_int_equal(b.len, n);
            assert_memory_equal(proto_buf_data(&b), bin, n);
            proto_buf_free(&b);
            free(txt);
            proto_msg_free(&d);
            good++;
        }
        free(bin);
        free(want);
    }
    closedir(dir);
    print_message("%d message vectors, %d error vectors\n", good, bad);
    assert_int_equal(good, PROTO_TYPE_END_ - 1 + N_EXTRA + 2);   /* + wake_read_entity, wake_read_wake */
    assert_int_equal(bad, (int)(sizeof bad_vectors / sizeof bad_vectors[0]));
}

/* Layout 1: pre-encoded tile records give the same bytes as tiles, the
 * per-client fields are found behind the cascade block, and the decoder
 * refuses what the validator refuses. */
static void test_cascade_layout(void **state)
{
    (void)state;
    proto_msg m;
    assert_int_equal(sample_named(&m, "frame_cascade"), 0);
    proto_buf a, recs, b;
    proto_buf_init(&a, 0);
    proto_buf_init(&recs, 0);
    proto_buf_init(&b, 0);
    char err[256];
    assert_int_equal(proto_encode(&a, &m, err, sizeof err), OCEAN_OK);
    size_t at[2];
    for (int i = 0; i < 2; i++) {
        at[i] = recs.len;
        assert_int_equal(proto_tile_record_encode(&recs, &cascade_tiles[i], cascade_tiles[i].cascade, err,
                                                  sizeof err), OCEAN_OK);
    }
    proto_bytes rb[2] = {{proto_buf_data(&recs) + at[0], at[1] - at[0]},
                         {proto_buf_data(&recs) + at[1], recs.len - at[1]}};
    m.u.frame.tiles = NULL;
    m.u.frame.tile_records = rb;
    assert_int_equal(proto_encode(&b, &m, err, sizeof err), OCEAN_OK);
    assert_int_equal(a.len, b.len);
    assert_memory_equal(proto_buf_data(&a), proto_buf_data(&b), a.len);
    /* a record whose tag names a cascade the frame does not have */
    proto_buf bad;
    proto_buf_init(&bad, 0);
    assert_int_equal(proto_tile_record_encode(&bad, &cascade_tiles[1], 2, err, sizeof err), OCEAN_OK);
    proto_bytes bb[2] = {rb[0], {proto_buf_data(&bad), bad.len}};
    m.u.frame.tile_records = bb;
    m.u.frame.cascades.cascade_count = 2;
    proto_buf c;
    proto_buf_init(&c, 0);
    assert_int_equal(proto_encode(&c, &m, err, sizeof err), OCEAN_EINVAL);
    assert_int_equal(c.len, 0);
    assert_int_equal(proto_tile_record_encode(&bad, &cascade_tiles[1], PROTO_MAX_LAYERS, err, sizeof err),
                     OCEAN_EINVAL);
    /* per-client fields */
    size_t cam_at = 0, mesh_at = 0;
    assert_int_equal(proto_frame_client_fields(proto_buf_data(&a), a.len, &cam_at, &mesh_at), OCEAN_OK);
    assert_int_equal(cam_at, PROTO_HEADER_SIZE + 40);
    assert_int_equal(proto_ld32(proto_buf_data(&a) + mesh_at), 3);
    assert_int_equal(mesh_at, a.len - PROTO_MESH_PLACEMENT_SIZE);
    /* decode: tags become tile cascades, the block and placement survive */
    proto_msg d;
    assert_int_equal(proto_decode(proto_buf_data(&a), a.len, &d, err, sizeof err), OCEAN_OK);
    assert_int_equal(d.u.frame.layout, PROTO_LAYOUT_CASCADE);
    assert_int_equal(d.u.frame.tiles[1].cascade, 1);
    assert_int_equal(d.u.frame.cascades.cascade[0].mips, 2);
    assert_true(isinf(d.u.frame.cascades.cascade[0].mip[0].kc));
    assert_true(d.u.frame.placement.origin[2] == -2.5e6 - 8);
    proto_msg_free(&d);
    /* validator: mip entries beyond `mips` must be zero, kc of the last entry 0 */
    sample_named(&m, "frame_cascade");
    m.u.frame.cascades.cascade[1].mip[3].mss_x = 1e-3f;
    proto_buf_init(&c, 0);
    assert_int_equal(proto_encode(&c, &m, err, sizeof err), OCEAN_EFORMAT);
    sample_named(&m, "frame_cascade");
    m.u.frame.cascades.cascade[0].mip[2].kc = 1.0f;
    assert_int_equal(proto_encode(&c, &m, err, sizeof err), OCEAN_EINVAL);
    sample_named(&m, "mesh_topology_flat");
    float zones[8];
    memcpy(zones, sample_zones, sizeof zones);
    zones[4] = 0.0f; /* lattice spacing must be > 0 */
    m.u.topology.zones = zones;
    assert_int_equal(proto_encode(&c, &m, err, sizeof err), OCEAN_EINVAL);
    proto_buf_free(&a);
    proto_buf_free(&b);
    proto_buf_free(&recs);
    proto_buf_free(&bad);
    proto_buf_free(&c);
}

/* ---- lod vectors -------------------------------------------------------------- */

/* tests/vectors/lod.txt: "Where each mip is read" as protocol/lod.c
 * computes it, over cascades like the daemon's (a coarsest one that does
 * not fade, finer ones that do) and points from the nadir to 25 km;
 * lod_mss.txt: the unresolved slope moments at the same points.  The
 * viewer's shader code is checked against the same lines
 * (tests/browser/lod.test.mjs).  Inputs are binary32 values, as the
 * frame carries them. */
typedef struct lod_cascade {
    double patch;
    int n, mips, fades;
} lod_cascade;

typedef struct lod_case {
    double q, min_s, cam_y, dx, dz, floor_s;
    lod_cascade k;
    int j;              /* k's index in lod_cascades */
} lod_case;

static const lod_cascade lod_cascades[] = {
    {1000, 256, 6, 0}, {250, 256, 5, 1}, {12.5, 256, 8, 1}, {64, 64, 4, 1},
};
static const double lod_q[] = {0.046875, 0.01171875};
static const double lod_cam_y[] = {25, -40};
static const double lod_d[][2] = {{0, 0}, {3, -4}, {30, 40}, {-300, 400}, {3000, -4000}, {-15000, 20000}};
static const double lod_floor[][2] = {{0, 0}, {2, 0}, {0, 4}};
/* the boundaries on cascade {64, 64, 4, 1} (sigma 1) at q 1/16 from
 * the nadir: lambda -4 (|cy| < 1, either side of the sea), 0, 1, 3 (the
 * last mip), 3.5, 4 */
static const double lod_edge_y[] = {0.25, -0.5, 16, 32, 128, 181, 256};

#define LOD_GRID ((int)(sizeof lod_cascades / sizeof *lod_cascades * sizeof lod_q / sizeof *lod_q * \
                        sizeof lod_cam_y / sizeof *lod_cam_y * sizeof lod_d / sizeof *lod_d * \
                        sizeof lod_floor / sizeof *lod_floor))
#define LOD_CASES (LOD_GRID + (int)(sizeof lod_edge_y / sizeof *lod_edge_y))

static lod_case lod_case_at(int i)
{
    lod_case k = {0};
    if (i >= LOD_GRID) {
        k.q = 0.0625;
        k.cam_y = lod_edge_y[i - LOD_GRID];
        k.j = 3;
        k.k = lod_cascades[k.j];
        return k;
    }
    int nf = (int)(sizeof lod_floor / sizeof *lod_floor), nd = (int)(sizeof lod_d / sizeof *lod_d);
    int ny = (int)(sizeof lod_cam_y / sizeof *lod_cam_y), nq = (int)(sizeof lod_q / sizeof *lod_q);
    k.min_s = lod_floor[i % nf][0];
    k.floor_s = lod_floor[i % nf][1];
    i /= nf;
    k.dx = lod_d[i % nd][0];
    k.dz = lod_d[i % nd][1];
    i /= nd;
    k.cam_y = lod_cam_y[i % ny];
    i /= ny;
    k.q = lod_q[i % nq];
    k.j = i / nq;
    k.k = lod_cascades[k.j];
    return k;
}

/* Cascade j's mip table moments and the block's tail_mss of the points on
 * it in lod_mss.txt: entry m leaves out more of the cascade's waves as m
 * grows, entry mips holds them all; x, z and xz take different shapes so a
 * reader that swaps them differs, xz of either sign (PROTOCOL.md). */
static void lod_table(int j, int mips, proto_mip_entry tab[PROTO_MIP_ENTRIES], double tail[3])
{
    static const double scale[][3] = {
        {0.004, 0.0025, 0.0007}, {0.011, 0.0075, -0.0021}, {0.0065, 0.009, 0.0013}, {0.0093, 0.0041, -0.0032},
    };
    static const float tails[][3] = {
        {0.0021f, 0.0017f, -0.0004f}, {0.0009f, 0.0012f, 0.0002f}, {0.0004f, 0.0003f, 0}, {0.0031f, 0.0026f, -0.0011f},
    };
    memset(tab, 0, sizeof(proto_mip_entry) * PROTO_MIP_ENTRIES);
    for (int m = 0; m <= mips; m++) {
        int whole = m == mips;
        tab[m].mss_x = (float)(scale[j][0] * (whole ? 1 : 1 - pow(0.55, m + 1)));
        tab[m].mss_z = (float)(scale[j][1] * (whole ? 1 : 1 - pow(0.7, m + 1)));
        tab[m].mss_xz = (float)(scale[j][2] * (whole ? 1 : 1 - pow(0.45, m + 1)));
        /* the read table's shares of one kernel, 0.62..1.05 (/ 32768) */
        if (!whole)
            tab[m].held[0] = (uint16_t)(32768 * (0.62 + 0.043 * ((3 * m + 2 * j) % 11)));
    }
    for (int i = 0; i < 3; i++)
        tail[i] = tails[j][i];
}

/* A point's inputs, as both files list them. */
static void lod_inputs(sbuf *b, const lod_case *k)
{
    out(b, "%.9g %.9g %.9g %.9g %.9g %.9g %.9g %d %d %d", k->q, k->min_s, k->cam_y, k->dx, k->dz, k->floor_s,
        k->k.patch, k->k.n, k->k.mips, k->k.fades);
}

/* lod.txt's line: the inputs, " -> ", what the rule reads. */
static void lod_line(sbuf *b, const lod_case *k)
{
    double s = fmax(proto_lod_spacing(k->q, k->min_s, k->cam_y, k->dx, k->dz), k->floor_s);
    proto_lod_read r;
    proto_lod_read_at(s, k->k.patch / k->k.n, k->k.mips, k->k.fades, &r);
    lod_inputs(b, k);
    out(b, " -> %.17g %.17g %d %.17g %d %.17g %.17g\n", s, r.lambda, r.mip[0], r.weight[0], r.mip[1], r.weight[1],
        r.fade);
}

/* lod_mss.txt's line: the inputs, tail_mss and the mip table, " -> ", the
 * unresolved slope moments there. */
static void lod_mss_line(sbuf *b, const lod_case *k)
{
    double s = fmax(proto_lod_spacing(k->q, k->min_s, k->cam_y, k->dx, k->dz), k->floor_s);
    proto_lod_read r;
    proto_lod_read_at(s, k->k.patch / k->k.n, k->k.mips, k->k.fades, &r);
    proto_mip_entry tab[PROTO_MIP_ENTRIES];
    double mss[3];
    lod_table(k->j, k->k.mips, tab, mss);
    lod_inputs(b, k);
    out(b, " %.9g %.9g %.9g", mss[0], mss[1], mss[2]);
    for (int m = 0; m <= k->k.mips; m++)
        out(b, " %.9g %.9g %.9g", tab[m].mss_x, tab[m].mss_z, tab[m].mss_xz);
    for (int m = 0; m < k->k.mips; m++)
        out(b, " %u", tab[m].held[0]);
    proto_lod_mss_add(&r, tab, k->k.mips, mss);
    out(b, " -> %.17g %.17g %.17g %.17g\n", mss[0], mss[1], mss[2],
        proto_lod_breaking_var(&r, tab, k->k.mips, 0));
}

static const char lod_head[] =
    "# PROTOCOL.md \"Where each mip is read\", computed by protocol/lod.c; one point a line:\n"
    "# q_c min_spacing_m cam_y dx dz floor_m patch_m n mips fades -> s lambda mip0 weight0 mip1 weight1 fade\n"
    "# s = max(min_spacing_m, q_c sqrt(dx^2 + dz^2 + max(|cam_y|, 1)^2), floor_m) (floor_m: a vertex's g_L or G),\n"
    "# sigma = patch_m / n, lambda = log2(s / sigma); mip1 -1 when one mip is read; the weights include the fade.\n";

static const char lod_mss_head[] =
    "# PROTOCOL.md \"Where each mip is read\": the unresolved slope moments, computed by protocol/lod.c; one point "
    "a line:\n"
    "# q_c min_spacing_m cam_y dx dz floor_m patch_m n mips fades tail_x tail_z tail_xz e0_x e0_z e0_xz ... "
    "e<mips>_x e<mips>_z e<mips>_xz h0 ... h<mips-1> -> mss_x mss_z mss_xz var\n"
    "# the point and cascade as in lod.txt (the points are its points); tail: the block's tail_mss; e<m>: the mip\n"
    "# table's entry m (m = mips: the whole cascade); mss = tail + the entries of the mips read with their weights\n"
    "# + entry mips with 1 - fade + a (1 - a) (coarser - finer) where two entries are blended with a, 1 - a;\n"
    "# h<m>: a kernel's share of mip m in the read table (/ 32768); var: the breaking-index variance held,\n"
    "# (e<mips>_x + e<mips>_z - the x + z the read leaves unresolved) times the read mips' shares with their\n"
    "# weights over the weights' sum.\n";

/* The text of lod.txt (mss 0) or lod_mss.txt (mss 1). */
static void lod_text(sbuf *b, int mss)
{
    out(b, "%s", mss ? lod_mss_head : lod_head);
    for (int i = 0; i < LOD_CASES; i++) {
        lod_case k = lod_case_at(i);
        if (mss)
            lod_mss_line(b, &k);
        else
            lod_line(b, &k);
    }
}

/* lod_foam.txt: "Whitecaps in layout 1" as protocol/lod.c computes it
 * (proto_lod_foam), for three whitecap tables (three rows; one; a step
 * row and a row without trails) over a grid of held variance, breaking
 * index and quadrature: below, between and above the rows, on the ramp,
 * on a trail, clamped at 0 and 1. */
static const proto_foam_row foam_tables[3][3] = {
    {{0.02f, -0.03f, 0.8f}, {0.08f, 0.1f, 1.1f}, {0.2f, 0.3f, 1.5f}},
    {{0.1f, 0.05f, 1.0f}},
    {{0.05f, 0.5f, 2.0f}, {0.3f, 0.2f, 0.0f}},
};
static const int foam_table_rows[3] = {3, 1, 2};

static const char lod_foam_head[] =
    "# PROTOCOL.md \"Whitecaps in layout 1\", computed by protocol/lod.c; one point a line:\n"
    "# rows sigma0 a0 omega0 ... sigma<rows-1> a<rows-1> omega<rows-1> var beta q -> foam\n"
    "# the block's whitecap table, the breaking-index variance the reads hold, the summed breaking index and\n"
    "# its quadrature; foam = max(f(beta), f(|beta + i q|) exp(-arg(beta + i q) / (omega 3.85 s))).\n";

static void lod_foam_text(sbuf *b)
{
    static const double vars[] = {0, 0.0009, 0.0064, 0.0144, 0.09};
    static const double betas[] = {-0.3, 0.05, 0.2, 0.45, 0.7};
    static const double qs[] = {-0.4, 0, 0.15};
    out(b, "%s", lod_foam_head);
    for (int t = 0; t < 3; t++) {
        proto_cascade_block blk;
        memset(&blk, 0, sizeof blk);
        blk.flags = PROTO_CASCADE_FOAM;
        blk.foam_rows = (uint8_t)foam_table_rows[t];
        memcpy(blk.foam, foam_tables[t], sizeof foam_tables[t]);
        for (size_t v = 0; v < sizeof vars / sizeof *vars; v++)
            for (size_t i = 0; i < sizeof betas / sizeof *betas; i++)
                for (size_t j = 0; j < sizeof qs / sizeof *qs; j++) {
                    out(b, "%d", blk.foam_rows);
                    for (int r = 0; r < blk.foam_rows; r++)
                        out(b, " %.9g %.9g %.9g", (double)blk.foam[r].sigma, (double)blk.foam[r].a,
                            (double)blk.foam[r].omega);
                    out(b, " %.9g %.9g %.9g -> %.9g\n", vars[v], betas[i], qs[j],
                        proto_lod_foam(&blk, vars[v], betas[i], qs[j]));
                }
    }
}

static const char *const lod_files[] = {"lod.txt", "lod_mss.txt", "lod_foam.txt"};

/* The text of lod_files[k]. */
static void lod_file_text(sbuf *b, int k)
{
    if (k == 2)
        lod_foam_text(b);
    else
        lod_text(b, k);
}

static int write_lod_vectors(const char *dir)
{
    for (int mss = 0; mss < 3; mss++) {
        char path[512];
        snprintf(path, sizeof path, "%s/%s", dir, lod_files[mss]);
        sbuf b = {0};
        lod_file_text(&b, mss);
        int r = write_file(path, b.s, b.n);
        free(b.s);
        if (r)
            return -1;
    }
    return 0;
}

/* ---- a wake read as every reader reads it ------------------------------------ */

/* wake_read_entity.bin (an ENTITY announce of a 10 m boat at 2 m/s, in
 * force from 99.5 s) and wake_read_wake.bin (the WAKE of its one rung:
 * 2 m/s is on the ladder), and wake_read.txt: the wakes they make at
 * t = 103 s over 50 m of water on a 16 x 16 square at 0.75 m behind the
 * boat, as clients/c/oc_wakes.c reads them (height, dh/dx, dh/dz each a
 * line of 256 floats, %.9g).  The viewer's WebAssembly reads the same
 * (tests/browser/protocol.test.mjs). */
#define WR_T 103.0
#define WR_DEPTH 50.0
#define WR_N 16
#define WR_DX 0.75

static int wake_read_messages(proto_buf *ent, proto_buf *wake)
{
    proto_msg m;
    proto_msg_init(&m, PROTO_ENTITY);
    m.hdr.sim_time = 99.5;
    m.u.entity = (proto_entity){PROTO_ENTITY_ANNOUNCE, 0, 9, 100.0, 1000.5, -2000.25, 0.0f, 30.0f, 2.0f, 10.0f, 2.0f,
                                1.0f, ""};
    if (proto_encode(ent, &m, NULL, 0) != OCEAN_OK) return -1;
    wake_params p = {2.0, 10.0, WR_DEPTH, 2.0};
    wake_pattern *pat;
    if (wake_pattern_create(&p, &pat, NULL, 0) != OCEAN_OK) return -1;
    int nx, nz;
    const float *coef = wake_pattern_coefficients(pat, &nx, &nz);
    proto_codec_params cp;
    proto_codec_params_default(&cp);
    cp.accuracy = 1e-4;
    proto_buf pay;
    proto_buf_init(&pay, 0);
    double err = 0;
    ocean_result r = proto_plane_encode(NULL, PROTO_CODEC_QZ, &cp, nx, nz, coef, &pay, &err, NULL, 0);
    proto_msg_init(&m, PROTO_WAKE);
    m.u.wake = (proto_wake){p.speed, p.length, p.beam, p.depth, (uint16_t)nx, (uint16_t)nz, PROTO_CODEC_QZ,
                            (float)(wake_pattern_bound(pat) + err), (uint32_t)pay.len, proto_buf_data(&pay)};
    if (r == OCEAN_OK) r = proto_encode(wake, &m, NULL, 0);
    proto_buf_free(&pay);
    wake_pattern_destroy(pat);
    return r == OCEAN_OK ? 0 : -1;
}

/* The text of wake_read.txt from the two messages' bytes; NULL when a
 * reader refuses them. */
static char *wake_read_text(const uint8_t *ent, size_t nent, const uint8_t *wake, size_t nwake)
{
    oc_wakes *w;
    proto_msg m;
    if (oc_wakes_create(&w) != OCEAN_OK) return NULL;
    int ok = proto_decode(ent, nent, &m, NULL, 0) == OCEAN_OK && oc_wakes_entity(w, &m) == OCEAN_OK;
    if (ok && proto_decode(wake, nwake, &m, NULL, 0) == OCEAN_OK) {
        wake_pattern *p = oc_wakes_decode(&m.u.wake);
        ok = p != NULL;
        oc_wakes_keep(w, p);
        proto_msg_free(&m);
    } else {
        ok = 0;
    }
    /* the square from 10 to 21.25 m behind the boat, across its track */
    double hd = 30.0 * M_PI / 180, bx = 1000.5 + 2.0 * 3.0 * cos(hd), bz = -2000.25 + 6.0 * sin(hd);
    double x0 = bx - 16 * cos(hd) - WR_N * WR_DX / 2, z0 = bz - 16 * sin(hd) - WR_N * WR_DX / 2;
    float g[4 * WR_N * WR_N];   /* as a renderer reads them: oc_wakes_grid */
    ok = ok && oc_wakes_grid(w, WR_T, WR_DEPTH, x0, z0, WR_DX, WR_N, g) == OCEAN_OK;
    oc_wakes_destroy(w);
    if (!ok) return NULL;
    sbuf b = {0};
    out(&b, "# the wakes of wake_read_entity.bin and wake_read_wake.bin on the square: see tests/test_proto.c\n");
    out(&b, "t = %.17g\ndepth = %.17g\nx0 = %.17g\nz0 = %.17g\ndx = %.17g\nn = %d\n", WR_T, WR_DEPTH, x0, z0, WR_DX,
        WR_N);
    static const char *const names[4] = {"height", "dhdx", "dhdz", "mss"};
    for (int c = 0; c < 4; c++) {
        out(&b, "%s =", names[c]);
        for (int k = 0; k < WR_N * WR_N; k++) out(&b, " %.9g", (double)g[4 * k + c]);
        out(&b, "\n");
    }
    return b.s;
}

static int wake_read_vectors(const char *dir, int write)
{
    char pe[512], pw[512], pt[512];
    snprintf(pe, sizeof pe, "%s/wake_read_entity.bin", dir);
    snprintf(pw, sizeof pw, "%s/wake_read_wake.bin", dir);
    snprintf(pt, sizeof pt, "%s/wake_read.txt", dir);
    if (write) {
        proto_buf e, w;
        proto_buf_init(&e, 0);
        proto_buf_init(&w, 0);
        int r = wake_read_messages(&e, &w) || write_file(pe, proto_buf_data(&e), e.len) ||
                write_file(pw, proto_buf_data(&w), w.len);
        for (int k = 0; k < 2 && !r; k++) {
            proto_buf *b = k ? &w : &e;
            proto_msg d;
            proto_decode(proto_buf_data(b), b->len, &d, NULL, 0);
            char *txt = dump(&d), path[520];
            snprintf(path, sizeof path, "%s/wake_read_%s.txt", dir, k ? "wake" : "entity");
            r = write_file(path, txt, strlen(txt));
            free(txt);
            proto_msg_free(&d);
        }
        char *txt = r ? NULL : wake_read_text(proto_buf_data(&e), e.len, proto_buf_data(&w), w.len);
        r = !txt || write_file(pt, txt, strlen(txt));
        free(txt);
        proto_buf_free(&e);
        proto_buf_free(&w);
        return r ? -1 : 0;
    }
    size_t ne, nw, nt;
    uint8_t *e = read_file(pe, &ne), *w = read_file(pw, &nw);
    char *want = (char *)read_file(pt, &nt), *got = e && w ? wake_read_text(e, ne, w, nw) : NULL;
    int same = want && got && strcmp(want, got) == 0;
    free(e);
    free(w);
    free(want);
    free(got);
    return same ? 0 : -1;
}

/* The committed wake vectors still read as the C reader reads them. */
static void test_wake_read_vectors(void **state)
{
    (void)state;
    if (wake_read_vectors(vector_dir(), 0))
        fail_msg("%s/wake_read.txt differs from what clients/c/oc_wakes.c reads of wake_read_entity.bin and "
                 "wake_read_wake.bin (regenerate: test_proto --write-vectors tests/vectors)", vector_dir());
}

/* The committed lod vectors are still what the C rule computes. */
static void test_lod_vectors(void **state)
{
    (void)state;
    for (int mss = 0; mss < 3; mss++) {
        char path[600];
        snprintf(path, sizeof path, "%s/%s", vector_dir(), lod_files[mss]);
        size_t n;
        char *text = (char *)read_file(path, &n);
        if (!text)
            fail_msg("cannot read %s", path);
        sbuf want = {0};
        lod_file_text(&want, mss);
        if (strcmp(want.s, text))
            fail_msg("%s differs from protocol/lod.c's rule (regenerate: test_proto --write-vectors tests/vectors)",
                     path);
        free(want.s);
        free(text);
    }
}

/* "Where each mip is read" (protocol/lod.c): the spacing at a point, and
 * the mips read at a spacing, at the rule's boundaries. */
static void test_lod_rule(void **state)
{
    (void)state;
    /* s = max(min, q sqrt(dx^2 + dz^2 + max(|y|, 1)^2)) */
    assert_true(proto_lod_spacing(0.01, 0, 25, 0, 0) == 0.25);
    assert_true(proto_lod_spacing(0.01, 0, -0.5, 3, 4) == 0.01 * sqrt(26.0));
    assert_true(proto_lod_spacing(0.01, 2, 25, 0, 0) == 2);
    proto_lod_read r;
    /* at or below sigma: mip 0 alone */
    proto_lod_read_at(0.5, 1, 5, 1, &r);
    assert_true(r.mip[0] == 0 && r.mip[1] == -1 && r.weight[0] == 1 && r.fade == 1);
    /* between: two mips, linear */
    proto_lod_read_at(pow(2, 2.25), 1, 5, 1, &r);
    assert_true(r.mip[0] == 2 && r.mip[1] == 3);
    assert_true(fabs(r.weight[0] - 0.75) < 1e-12 && fabs(r.weight[1] - 0.25) < 1e-12);
    /* beyond the last mip: a fading cascade fades by clamp(mips - lambda) */
    proto_lod_read_at(pow(2, 4.5), 1, 5, 1, &r);
    assert_true(r.mip[0] == 4 && r.mip[1] == -1 && fabs(r.fade - 0.5) < 1e-12 && r.weight[0] == r.fade);
    proto_lod_read_at(pow(2, 6), 1, 5, 1, &r);
    assert_true(r.fade == 0 && r.weight[0] == 0);
    /* the coarsest cascade does not fade */
    proto_lod_read_at(pow(2, 6), 1, 5, 0, &r);
    assert_true(r.mip[0] == 4 && r.fade == 1 && r.weight[0] == 1);
}

/* The unresolved slope moments of one cascade (protocol/lod.c), by hand:
 * a table of mips 3 whose entries double, read at each branch of the rule,
 * added to a tail. */
static void test_lod_mss(void **state)
{
    (void)state;
    proto_mip_entry tab[PROTO_MIP_ENTRIES] = {{0}};
    for (int m = 0; m <= 3; m++) {
        tab[m].mss_x = (float)(1 << m);          /* 1 2 4 8 */
        tab[m].mss_z = (float)(3 << m);          /* 3 6 12 24 */
        tab[m].mss_xz = -(float)(1 << m) / 4;    /* -1/4 .. -2 */
    }
    static const struct {
        double lambda;
        int fades;
        double x;   /* mss_x over a tail of 10 */
    } cases[] = {
        {-1, 1, 10 + 1},                                   /* mip 0 */
        {0.25, 1, 10 + 0.75 * 1 + 0.25 * 2 + 0.75 * 0.25 * (2 - 1)},
        {1, 1, 10 + 2},                                    /* mip 1 alone: no cross term */
        {2.5, 1, 10 + 0.5 * 4 + 0.5 * 8 + 0.25 * (8 - 4)},  /* mid-fade */
        {2.75, 1, 10 + 0.25 * 4 + 0.75 * 8 + 0.25 * 0.75 * (8 - 4)},
        {3, 1, 10 + 8},                                    /* faded out: the whole cascade */
        {5, 0, 10 + 4},                                    /* the coarsest cascade keeps its last mip */
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        proto_lod_read r;
        proto_lod_read_at(pow(2, cases[i].lambda), 1, 3, cases[i].fades, &r);
        double mss[3] = {10, 30, -2.5};
        proto_lod_mss_add(&r, tab, 3, mss);
        /* z and xz are x's table scaled by 3 and -1/4, as is the tail */
        if (fabs(mss[0] - cases[i].x) > 1e-12 || fabs(mss[1] - 3 * cases[i].x) > 1e-12 ||
            fabs(mss[2] + cases[i].x / 4) > 1e-12)
            fail_msg("lambda %g: mss %.17g %.17g %.17g, want x %.17g", cases[i].lambda, mss[0], mss[1], mss[2],
                     cases[i].x);
    }
    /* a read outside the table adds nothing */
    proto_lod_read bad = {0, {7, -1}, {1, 0}, 1};
    double mss[3] = {0, 0, 0};
    proto_lod_mss_add(&bad, tab, 3, mss);
    assert_true(mss[0] == 0 && mss[1] == 0 && mss[2] == 0);
}

/* The breaking-index variance a kernel's reading holds (proto_lod_held,
 * proto_lod_breaking_var): the read mips' shares with their weights, over
 * the weights' sum; 1 without the read table or for the waves as they
 * are. */
static void test_lod_held(void **state)
{
    (void)state;
    proto_mip_entry tab[PROTO_MIP_ENTRIES] = {{0}};
    for (int m = 0; m <= 3; m++) {
        tab[m].mss_x = (float)(m == 3 ? 8 : 8 - (4 >> m)); /* unresolved: 4 2 1, whole 8 */
        tab[m].mss_z = 0;
    }
    proto_lod_read r;
    /* no table: the share is 1, and the variance the mip table gives */
    proto_lod_read_at(pow(2, 1.25), 1, 3, 1, &r);
    assert_true(proto_lod_held(&r, tab, 3, PROTO_READ_BILINEAR) == 1);
    double v0 = proto_lod_breaking_var(&r, tab, 3, PROTO_READ_BILINEAR);
    static const uint16_t share[3] = {32768 * 3 / 4, 32768 / 2, 32768 / 4}; /* 0.75 0.5 0.25 */
    for (int m = 0; m < 3; m++)
        tab[m].held[PROTO_READ_KEYS] = share[m];
    /* still none for bilinear, and none for a reader of the waves as they are */
    assert_true(proto_lod_held(&r, tab, 3, PROTO_READ_BILINEAR) == 1);
    assert_true(proto_lod_held(&r, tab, 3, -1) == 1);
    static const struct {
        double lambda;
        double held;
    } cases[] = {
        {-1, 0.75},                     /* mip 0 */
        {1.25, 0.75 * 0.5 + 0.25 * 0.25}, /* mips 1 and 2, 3/4 and 1/4 */
        {2.5, 0.25},                    /* mid-fade: the last mip's share, the fade not counted twice */
        {4, 1},                         /* faded out: nothing read */
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        proto_lod_read_at(pow(2, cases[i].lambda), 1, 3, 1, &r);
        double h = proto_lod_held(&r, tab, 3, PROTO_READ_KEYS);
        if (fabs(h - cases[i].held) > 1e-12)
            fail_msg("lambda %g: held %.17g, want %.17g", cases[i].lambda, h, cases[i].held);
    }
    proto_lod_read_at(pow(2, 1.25), 1, 3, 1, &r);
    assert_true(fabs(proto_lod_breaking_var(&r, tab, 3, PROTO_READ_KEYS) - v0 * (0.75 * 0.5 + 0.25 * 0.25)) < 1e-12);
    /* a table (READ) without the whitecap table (FOAM) is refused */
    proto_msg m;
    sample_named(&m, "frame_cascade_foam");
    m.u.frame.cascades.flags = PROTO_CASCADE_READ;
    m.u.frame.cascades.foam_rows = 0;
    memset(m.u.frame.cascades.foam, 0, sizeof m.u.frame.cascades.foam);
    proto_buf b;
    proto_buf_init(&b, 0);
    char err[256];
    assert_int_equal(proto_encode(&b, &m, err, sizeof err), OCEAN_EFORMAT);
    assert_non_null(strstr(err, "READ flag without FOAM"));
    proto_buf_free(&b);
}

int main(int argc, char **argv)
{
    if (argc == 3 && strcmp(argv[1], "--write-vectors") == 0)
        return write_vectors(argv[2]);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_roundtrip_all),
        cmocka_unit_test(test_lod_rule),
        cmocka_unit_test(test_lod_mss),
        cmocka_unit_test(test_lod_held),
        cmocka_unit_test(test_lod_vectors),
        cmocka_unit_test(test_wake_read_vectors),
        cmocka_unit_test(test_header_errors),
        cmocka_unit_test(test_time_limit),
        cmocka_unit_test(test_frame_client_fields),
        cmocka_unit_test(test_cascade_layout),
        cmocka_unit_test(test_payload_errors),
        cmocka_unit_test(test_truncate_every_type),
        cmocka_unit_test(test_encode_refuses),
        cmocka_unit_test(test_error_reply),
        cmocka_unit_test(test_vectors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
