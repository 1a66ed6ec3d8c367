/*
 * gen_vectors.c - the C side of the web viewer's protocol cross-check.
 *
 * The browser viewer carries its own JavaScript decoder (clients/web/
 * protocol.js, codec.js).  This helper ties it to the C implementation in
 * protocol/: tests/test_browser.sh builds it against the current
 * libocean_proto.a on every run, so the two can never drift apart silently.
 *
 *   gen_vectors gen DIR     writes messages encoded by proto_encode (HELLO,
 *                           FRAME with qz/f16/f32 tiles and a mesh,
 *                           a layout-1 FRAME with cascade tiles, a cascade
 *                           block and a mesh placement, MESH_TOPOLOGY plain
 *                           and FLAT, QUERY_RESULT, SEA_STATE, ERROR, BYE) as DIR/NAME.bin, and DIR/expected.json with
 *                           what the C decoders make of them (tile samples
 *                           as decoded by proto_tile_decode).
 *   gen_vectors decode FILE...   decodes each file with proto_decode and
 *                           prints one JSON line per file: the result code,
 *                           and for SUBSCRIBE/CAMERA/QUERY/BYE the fields.
 *
 * Build: cc -std=c11 -Isim -Iprotocol tests/browser/gen_vectors.c
 *        BUILD/libocean_proto.a BUILD/libocean_sim.a -lzstd -lOpenEXRCore-3_1 -lm
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <zstd.h>

#include "codec.h"
#include "proto.h"
#include "../bench/qz_before.h"

static int write_msg(const char *dir, const char *name, proto_msg *m)
{
    proto_buf b;
    proto_buf_init(&b, 0);
    char err[256];
    if (proto_encode(&b, m, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "encode %s: %s\n", name, err);
        return -1;
    }
    char path[1024];
    snprintf(path, sizeof path, "%s/%s.bin", dir, name);
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(proto_buf_data(&b), 1, proto_buf_len(&b), f) != proto_buf_len(&b)) {
        fprintf(stderr, "cannot write %s\n", path);
        if (f) fclose(f);
        return -1;
    }
    fclose(f);
    proto_buf_free(&b);
    return 0;
}

/* A MESH_TOPOLOGY message with these fields (not FLAT unless the caller
 * sets flags, flat and zones afterwards). */
static void topology_msg(proto_msg *m, uint32_t seq, uint32_t mesh_id, uint8_t lod_levels, uint32_t vertex_count,
                         uint32_t index_count, const uint32_t *indices, const float *morph, const uint8_t *level)
{
    proto_msg_init(m, PROTO_MESH_TOPOLOGY);
    m->hdr.seq = seq;
    m->u.topology.mesh_id = mesh_id;
    m->u.topology.mesh_kind = PROTO_MESH_CONCENTRIC;
    m->u.topology.lod_levels = lod_levels;
    m->u.topology.vertex_count = vertex_count;
    m->u.topology.index_count = index_count;
    m->u.topology.indices = indices;
    m->u.topology.morph = morph;
    m->u.topology.level = level;
}

static void print_floats(FILE *o, const float *v, size_t n)
{
    fputc('[', o);
    for (size_t i = 0; i < n; i++)
        fprintf(o, "%s%.9g", i ? "," : "", (double)v[i]);
    fputc(']', o);
}

/* A smooth but irregular test field so prediction and quantisation both
 * have work to do. */
static float field(int plane, int i, int j)
{
    double x = j * 0.37, z = i * 0.29;
    switch (plane) {
    case 0: return (float)(1.7 * sin(x + 0.3 * z) + 0.4 * cos(2.1 * z - 0.7 * x));
    case 1: return (float)(0.6 * cos(x - z));
    case 2: return (float)(-0.5 * sin(0.8 * x + 1.3 * z));
    case 5: return (float)fmax(0.0, sin(x * 1.9) * cos(z * 1.1));
    default: return 0.0f;
    }
}

static int gen(const char *dir)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/expected.json", dir);
    FILE *o = fopen(path, "w");
    if (!o)
        return 1;
    fprintf(o, "{\n");

    /* HELLO */
    proto_msg m;
    proto_msg_init(&m, PROTO_HELLO);
    m.hdr.seq = 1;
    m.hdr.sim_time = 12.5;
    proto_hello *h = &m.u.hello;
    h->codecs = 0x7f;
    h->mesh_kinds = 0x7;
    h->effects = PROTO_FX_ALL;
    h->cutoff_policies = 0x7;
    h->modes = 0x3;
    h->max_message = 1u << 20;
    h->max_query_points = 4096;
    h->max_tile_size = 256;
    h->max_lod_levels = 8;
    h->max_layers = 4;
    h->tick_rate_hz = 30.0f;
    h->max_frame_rate_hz = 60.0f;
    h->client_id = 77;
    h->sea.spectrum = 2;
    h->sea.spreading = 1;
    h->sea.seed = 0x0123456789abcdefULL;
    h->sea.wind_u10 = 12.3;
    h->sea.wind_dir_deg = 35;
    h->sea.fetch_m = 1e5;
    h->sea.depth_m = 4000;
    h->sea.swell = 0.5;
    h->sea.phillips_a = 0.00405;
    h->sea.small_wave_m = 0.01;
    h->sea.choppiness = 1.2;
    h->sea.hs = 3.1;
    h->sea.tp = 8.2;
    snprintf(h->server_version, sizeof h->server_version, "oceand 0.1 \xc3\xa9t\xc3\xa9");
    if (write_msg(dir, "hello", &m))
        return 1;
    const proto_sea sea = h->sea;
    fprintf(o, "\"hello\": {\"codecs\":127,\"clientId\":77,\"seed\":\"%llu\",\"windU10\":12.3,\"tp\":8.2,"
               "\"tickRateHz\":30,\"serverVersion\":\"%s\",\"simTime\":12.5,\"seq\":1},\n",
            (unsigned long long)sea.seed, h->server_version);

    /* FRAME: four tiles (qz format 2, f16, f32, and a qz format 1 payload as
     * recordings made before format 2 hold: tests/bench/qz_before.h),
     * different shapes/channels, and a mesh */
    enum { NT = 4 };
    const proto_codec codecs[NT] = {PROTO_CODEC_QZ, PROTO_CODEC_F16, PROTO_CODEC_F32, PROTO_CODEC_QZ};
    const unsigned chans[NT] = {PROTO_CH_HEIGHT | PROTO_CH_DX | PROTO_CH_DZ | PROTO_CH_NORMAL | PROTO_CH_FOAM,
                                PROTO_CH_HEIGHT | PROTO_CH_NORMAL, PROTO_CH_HEIGHT | PROTO_CH_FOAM,
                                PROTO_CH_HEIGHT | PROTO_CH_DX | PROTO_CH_NORMAL};
    const int ws[NT] = {17, 8, 5, 11}, hs[NT] = {13, 8, 3, 9};
    proto_tile tiles[NT];
    proto_buf pay[NT];
    float *dec[NT];
    for (int t = 0; t < NT; t++) {
        int np = proto_tile_planes(chans[t]), w = ws[t], hh = hs[t];
        size_t n = (size_t)w * hh;
        float *pl = calloc(n * np, sizeof *pl);
        int k = 0;
        static const int slot_bit[7] = {0, 1, 2, 3, 3, 4, 5};
        for (int s = 0; s < 7; s++) {
            if (!(chans[t] & (1u << slot_bit[s])))
                continue;
            for (int i = 0; i < hh; i++)
                for (int j = 0; j < w; j++) {
                    float v = field(s, i, j);
                    if (s == 3 || s == 4) {
                        float u, vv;
                        proto_normal_oct_encode(-0.3f * field(0, i, j), 1.0f, 0.2f * field(1, i, j), &u, &vv);
                        v = s == 3 ? u : vv;
                    }
                    pl[(size_t)k * n + (size_t)i * w + j] = v;
                }
            k++;
        }
        proto_codec_params p;
        proto_codec_params_default(&p);
        p.accuracy = 1e-3;
        proto_buf_init(&pay[t], 0);
        double merr;
        char err[256];
        if ((t == 3 ? qzb_encode(&p, w, hh, np, pl, &pay[t], &merr, err, sizeof err)
                    : proto_tile_encode(codecs[t], &p, w, hh, chans[t], pl, &pay[t], &merr, err, sizeof err)) != OCEAN_OK) {
            fprintf(stderr, "tile encode: %s\n", err);
            return 1;
        }
        dec[t] = calloc(n * np, sizeof(float));
        if (proto_tile_decode(codecs[t], w, hh, chans[t], proto_buf_data(&pay[t]), proto_buf_len(&pay[t]), dec[t],
                              err, sizeof err) != OCEAN_OK) {
            fprintf(stderr, "tile decode: %s\n", err);
            return 1;
        }
        memset(&tiles[t], 0, sizeof tiles[t]);
        tiles[t].level = (uint8_t)t;
        tiles[t].codec = (uint8_t)codecs[t];
        tiles[t].channels = (uint16_t)chans[t];
        tiles[t].width = (uint16_t)w;
        tiles[t].height = (uint16_t)hh;
        tiles[t].ix = -3 + t;
        tiles[t].iz = 2 - t;
        tiles[t].spacing = 0.5 * (1 << t);
        tiles[t].origin_x = tiles[t].ix * w * tiles[t].spacing + 1e6;
        tiles[t].origin_z = tiles[t].iz * hh * tiles[t].spacing;
        tiles[t].error_bound = (float)merr;
        tiles[t].payload_len = (uint32_t)proto_buf_len(&pay[t]);
        tiles[t].payload = proto_buf_data(&pay[t]);
        free(pl);
    }
    float pos[3 * 4] = {0, 0.25f, 0, 1, 0, 0, 0, 0, 1, 1.5f, -0.125f, 1.5f};
    proto_msg_init(&m, PROTO_FRAME);
    m.hdr.seq = 2;
    m.hdr.sim_time = 1234567.0625;
    proto_frame *f = &m.u.frame;
    f->cutoff_k = INFINITY;
    f->e_error = 0.0123;
    f->origin[0] = 1000000.5;
    f->origin[1] = 0;
    f->origin[2] = -250.25;
    f->camera_seq = 41;
    f->tick = 9001;
    f->tile_count = NT;
    f->tiles = tiles;
    f->has_mesh = 1;
    f->mesh.mesh_id = 5;
    f->mesh.vertex_count = 4;
    f->mesh.origin[0] = 1000000.5;
    f->mesh.origin[1] = 0;
    f->mesh.origin[2] = -250.25;
    f->mesh.positions = pos;
    if (write_msg(dir, "frame", &m))
        return 1;
    fprintf(o, "\"frame\": {\"cutoffK\":\"inf\",\"eError\":0.0123,\"cameraSeq\":41,\"tick\":9001,\"simTime\":1234567.0625,"
               "\"meshId\":5,\"positions\":");
    print_floats(o, pos, 12);
    fprintf(o, ",\"tiles\":[");
    for (int t = 0; t < NT; t++) {
        size_t n = (size_t)ws[t] * hs[t] * proto_tile_planes(chans[t]);
        fprintf(o, "%s{\"codec\":%d,\"channels\":%u,\"width\":%d,\"height\":%d,\"ix\":%d,\"iz\":%d,"
                   "\"originX\":%.17g,\"originZ\":%.17g,\"spacing\":%.17g,\"errorBound\":%.9g,\"payloadLen\":%u,\"decoded\":",
                t ? "," : "", codecs[t], chans[t], ws[t], hs[t], tiles[t].ix, tiles[t].iz, tiles[t].origin_x,
                tiles[t].origin_z, tiles[t].spacing, (double)tiles[t].error_bound, tiles[t].payload_len);
        print_floats(o, dec[t], n);
        fputc('}', o);
    }
    fprintf(o, "]},\n");

    /* FRAME, layout 1 (cascade tiles): two cascades' mip tiles (tags 0
     * and 1, qz and f16), a full cascade block and a mesh placement */
    {
        proto_tile ct[NT];
        for (int t = 0; t < NT; t++) {
            ct[t] = tiles[t];
            ct[t].cascade = (uint8_t)(t == 1);          /* tags 0, 1, 0 */
            ct[t].level = (uint8_t)(t == 2 ? 3 : t);    /* mips */
            ct[t].ix = t;
            ct[t].iz = 2 - t;
            ct[t].spacing = (t == 1 ? 0.90625 : 3.90625) * (1 << ct[t].level);
            ct[t].origin_x = ct[t].ix * ws[t] * ct[t].spacing;   /* cascade-local */
            ct[t].origin_z = ct[t].iz * hs[t] * ct[t].spacing;
        }
        proto_msg_init(&m, PROTO_FRAME);
        m.hdr.seq = 4;
        m.hdr.sim_time = 98765.4375;
        f = &m.u.frame;
        f->cutoff_k = INFINITY;
        f->e_error = 0;
        f->origin[0] = -7654321.25;
        f->origin[2] = 1234.5;
        f->camera_seq = 43;
        f->tick = 9002;
        f->tile_count = NT;
        f->tiles = ct;
        f->layout = PROTO_LAYOUT_CASCADE;
        f->has_mesh = 1;
        f->placement.mesh_id = 6;
        f->placement.origin[0] = -7654320;
        f->placement.origin[1] = 0;
        f->placement.origin[2] = 1232;
        proto_cascade_block *cb = &f->cascades;
        cb->cascade_count = 2;
        cb->order = 8;
        cb->spacing_per_m = 0.00390625f;
        cb->camera[0] = -7654321.25;
        cb->camera[1] = 300.5;
        cb->camera[2] = 1234.5;
        cb->min_spacing_m = 0.125f;
        cb->e_total = 0.015625f;
        cb->tail_mss[0] = 0.0123f;
        cb->tail_mss[1] = 0.0071f;
        cb->tail_mss[2] = -0.0007f;
        cb->geometry_spacing_m = 18.75f;
        const double patch[2] = {1000, 232.5};
        const int mips[2] = {6, 4};
        for (int c = 0; c < 2; c++) {
            proto_cascade_entry *e = &cb->cascade[c];
            e->patch_m = patch[c];
            e->n = 256;
            e->mips = (uint8_t)mips[c];
            e->fades = (uint8_t)c;
            e->spacing_per_m = cb->spacing_per_m / (float)(1 << c);   /* each cascade its own q */
            for (int k = 0; k <= mips[c]; k++) {
                e->mip[k].kc = k == 0 ? INFINITY : k == mips[c] ? 0.0f : (float)(3.14159265358979323846 * 256 / patch[c] / (1 << k));
                e->mip[k].mss_x = 0.001f * (float)(k * k) * (c + 1);
                e->mip[k].mss_z = 0.0006f * (float)(k * k) * (c + 1);
                e->mip[k].mss_xz = k ? -0.0001f * (float)k : 0.0f;
            }
        }
        if (write_msg(dir, "frame_cascade", &m))
            return 1;
        fprintf(o, "\"frame_cascade\": {\"layout\":1,\"cameraSeq\":43,\"meshId\":6,\"placement\":[-7654320,0,1232],"
                   "\"cascadeCount\":2,\"order\":8,\"spacingPerM\":%.9g,\"camera\":[-7654321.25,300.5,1234.5],"
                   "\"minSpacingM\":%.9g,\"eTotal\":%.9g,\"tailMss\":[%.9g,%.9g,%.9g],\"geometrySpacingM\":%.9g,"
                   "\"cascades\":[",
                (double)cb->spacing_per_m, (double)cb->min_spacing_m, (double)cb->e_total, (double)cb->tail_mss[0],
                (double)cb->tail_mss[1], (double)cb->tail_mss[2], (double)cb->geometry_spacing_m);
        for (int c = 0; c < 2; c++) {
            const proto_cascade_entry *e = &cb->cascade[c];
            fprintf(o, "%s{\"patchM\":%.17g,\"n\":%u,\"mips\":%u,\"fades\":%u,\"spacingPerM\":%.9g,\"mip\":[",
                    c ? "," : "", e->patch_m, e->n, e->mips, e->fades, (double)e->spacing_per_m);
            for (int k = 0; k < PROTO_MIP_ENTRIES; k++) {
                fprintf(o, "%s", k ? "," : "");
                if (isinf(e->mip[k].kc))
                    fprintf(o, "\"inf\"");
                else
                    fprintf(o, "%.9g", (double)e->mip[k].kc);
                fprintf(o, ",%.9g,%.9g,%.9g", (double)e->mip[k].mss_x, (double)e->mip[k].mss_z, (double)e->mip[k].mss_xz);
            }
            fprintf(o, "]}");
        }
        fprintf(o, "],\"tiles\":[");
        for (int t = 0; t < NT; t++) {
            size_t n = (size_t)ws[t] * hs[t] * proto_tile_planes(chans[t]);
            fprintf(o, "%s{\"cascade\":%u,\"level\":%u,\"ix\":%d,\"iz\":%d,\"originX\":%.17g,\"originZ\":%.17g,"
                       "\"spacing\":%.17g,\"decoded\":",
                    t ? "," : "", ct[t].cascade, ct[t].level, ct[t].ix, ct[t].iz, ct[t].origin_x, ct[t].origin_z,
                    ct[t].spacing);
            print_floats(o, dec[t], n);
            fputc('}', o);
        }
        fprintf(o, "]},\n");
    }

    /* MESH_TOPOLOGY, FLAT (layout 1): flat positions and zones */
    {
        uint32_t fidx[6] = {0, 2, 1, 1, 2, 3};
        float fmorph[4] = {0, 0, 0, 0};
        uint8_t flev[3 + 1] = {0, 0, 1, 2};
        float flat[8] = {-1.5f, 0, 1.5f, 0, 0, 3, 12, -12};
        float zones[12] = {1.5f, 40, 6, 0, 3, 80, 12, 0, 6, 160, 0, 0};
        topology_msg(&m, 5, 6, 3, 4, 6, fidx, fmorph, flev);
        m.u.topology.flags = PROTO_TOPO_FLAT;
        m.u.topology.flat = flat;
        m.u.topology.zones = zones;
        if (write_msg(dir, "topology_flat", &m))
            return 1;
        fprintf(o, "\"topology_flat\": {\"meshId\":6,\"flags\":1,\"lodLevels\":3,\"level\":[0,0,1,2],\"flat\":");
        print_floats(o, flat, 8);
        fprintf(o, ",\"zones\":");
        print_floats(o, zones, 12);
        fprintf(o, "},\n");
    }

    /* MESH_TOPOLOGY */
    uint32_t idx[6] = {0, 2, 1, 1, 2, 3};
    float morph[4] = {0, 0.25f, 0.5f, 1};
    uint8_t lev[4] = {0, 0, 1, 1};
    topology_msg(&m, 3, 5, 2, 4, 6, idx, morph, lev);
    if (write_msg(dir, "topology", &m))
        return 1;
    fprintf(o, "\"topology\": {\"meshId\":5,\"indices\":[0,2,1,1,2,3],\"morph\":[0,0.25,0.5,1],\"level\":[0,0,1,1]},\n");

    /* Layout 0 with qz mesh positions (has_mesh 2) and the MESH_TOPOLOGY
     * they are predicted over: a G x G lattice (1 m, row-major, two
     * triangles a cell) far from the origin, displaced by a few smooth
     * waves, so the parallelogram, midpoint and previous-vertex rules all
     * occur; expected: the C refs and the C-decoded positions */
    {
        enum { G = 24, V = G * G, I = 6 * (G - 1) * (G - 1) };
        static uint32_t gi[I];
        static float gm[V], gp[3 * V], back[3 * V];
        static uint8_t gl[V];
        static uint32_t refs[3 * V];
        int k = 0;
        for (int i = 0; i + 1 < G; i++)
            for (int j = 0; j + 1 < G; j++) {
                uint32_t a = (uint32_t)(i * G + j), b = a + 1, c = a + G, d = c + 1;
                gi[k++] = a; gi[k++] = c; gi[k++] = b;
                gi[k++] = b; gi[k++] = c; gi[k++] = d;
            }
        for (int i = 0; i < G; i++)
            for (int j = 0; j < G; j++) {
                float *q = gp + 3 * (i * G + j);
                double x = j - 11.5, z = i - 11.5;
                q[0] = (float)(x + 0.4 * sin(0.7 * x + 0.3 * z));
                q[1] = (float)(1.5 * sin(0.45 * x - 0.2 * z) + 0.3 * cos(1.3 * z + 0.5 * x));
                q[2] = (float)(z - 0.35 * cos(0.5 * z - 0.6 * x));
            }
        topology_msg(&m, 6, 11, 1, V, I, gi, gm, gl);
        if (write_msg(dir, "topology_mesh_qz", &m))
            return 1;
        proto_codec_ctx *cx = NULL;
        proto_buf qz;
        proto_buf_init(&qz, 0);
        char err[256];
        if (proto_mesh_qz_refs(gi, I, V, refs) != OCEAN_OK || proto_codec_ctx_create(&cx) != OCEAN_OK ||
            proto_mesh_qz_encode(cx, 2e-3, V, gp, refs, &qz, NULL, err, sizeof err) != OCEAN_OK ||
            proto_mesh_qz_decode(proto_buf_data(&qz), proto_buf_len(&qz), V, refs, back, err, sizeof err) != OCEAN_OK) {
            fprintf(stderr, "mesh qz: %s\n", err);
            return 1;
        }
        proto_codec_ctx_destroy(cx);
        proto_msg_init(&m, PROTO_FRAME);
        m.hdr.seq = 7;
        m.hdr.sim_time = 321.5;
        f = &m.u.frame;
        f->cutoff_k = INFINITY;
        f->origin[0] = -3e6 + 0.5;
        f->origin[2] = 7e5;
        f->camera_seq = 44;
        f->tick = 9003;
        f->has_mesh = 2;
        f->mesh.mesh_id = 11;
        f->mesh.vertex_count = V;
        f->mesh.origin[0] = -3e6 + 0.5;
        f->mesh.origin[2] = 7e5;
        f->mesh.qz = proto_buf_data(&qz);
        f->mesh.qz_len = (uint32_t)proto_buf_len(&qz);
        if (write_msg(dir, "frame_mesh_qz", &m))
            return 1;
        int kinds[3] = {0, 0, 0};
        for (int v = 0; v < V; v++)
            kinds[refs[3 * v + 2] != PROTO_MESH_QZ_NONE ? 0 : refs[3 * v] != PROTO_MESH_QZ_NONE ? 1 : 2]++;
        fprintf(o, "\"frame_mesh_qz\": {\"meshId\":11,\"vertexCount\":%d,\"qzLen\":%u,\"refKinds\":[%d,%d,%d],\"refs\":[",
                V, f->mesh.qz_len, kinds[0], kinds[1], kinds[2]);
        for (int i = 0; i < 3 * V; i++)
            fprintf(o, "%s%u", i ? "," : "", refs[i]);
        fprintf(o, "],\"input\":");
        print_floats(o, gp, 3 * V);
        fprintf(o, ",\"positions\":");
        print_floats(o, back, 3 * V);
        fprintf(o, "},\n");
        proto_buf_free(&qz);
    }

    /* QUERY_RESULT */
    proto_query_sample qs[2] = {{0.5f, {0, 1, 0}, {0.1f, 0.2f, 0.3f}, 0.25f, 0.001f},
                                {-1.25f, {0.6f, 0.8f, 0}, {0, 0, 0}, 0, 0}};
    proto_msg_init(&m, PROTO_QUERY_RESULT);
    m.u.result.query_id = 9;
    m.u.result.count = 2;
    m.u.result.t = 99.5;
    m.u.result.samples = qs;
    if (write_msg(dir, "result", &m))
        return 1;
    fprintf(o, "\"result\": {\"queryId\":9,\"count\":2,\"t\":99.5,\"height1\":-1.25,\"foam0\":0.25},\n");

    /* SEA_STATE announce */
    proto_msg_init(&m, PROTO_SEA_STATE);
    m.u.sea_state.op = PROTO_SEA_ANNOUNCE;
    m.u.sea_state.effective_time = 60;
    m.u.sea_state.sea = sea;
    if (write_msg(dir, "sea", &m))
        return 1;
    fprintf(o, "\"sea\": {\"effectiveTime\":60,\"windDirDeg\":35},\n");

    /* zstd frames as libzstd makes them with every header form the JS
     * frame walk (zstdFrameSizes) must read: 1-, 2- and 4-byte content
     * sizes (2 bytes store size - 256), a checksum, a window descriptor
     * (not single-segment: a 1 KB window under 300 KB), several blocks, RLE
     * blocks (300 KB of zeros: libzstd never makes the first block RLE);
     * expected: ZSTD_getFrameContentSize and
     * ZSTD_findFrameCompressedSize */
    fprintf(o, "\"zstd_frames\": [");
    static const struct { size_t len; int checksum, window_log, pattern; } zf[] = {
        {15, 0, 0, 0}, {300, 1, 0, 0}, {70000, 0, 0, 1}, {300000, 1, 10, 1}, {300000, 0, 0, 2}};
    ZSTD_CCtx *zc = ZSTD_createCCtx();
    for (size_t z = 0; z < sizeof zf / sizeof zf[0]; z++) {
        uint8_t *src = malloc(zf[z].len), *dst = malloc(ZSTD_compressBound(zf[z].len));
        uint32_t st = 12345u + (uint32_t)z;
        for (size_t i = 0; i < zf[z].len; i++) {
            st = st * 1664525u + 1013904223u;
            /* 0: noise, 1: a repeating ramp with noise in one byte of 8 (compressible), 2: zeros */
            src[i] = zf[z].pattern == 0 ? (uint8_t)(st >> 24)
                   : zf[z].pattern == 1 ? (uint8_t)(i % 8 ? i % 251 : st >> 24) : 0;
        }
        ZSTD_CCtx_reset(zc, ZSTD_reset_session_and_parameters);
        ZSTD_CCtx_setParameter(zc, ZSTD_c_contentSizeFlag, 1);
        ZSTD_CCtx_setParameter(zc, ZSTD_c_checksumFlag, zf[z].checksum);
        if (zf[z].window_log)
            ZSTD_CCtx_setParameter(zc, ZSTD_c_windowLog, zf[z].window_log);
        size_t n = ZSTD_compress2(zc, dst, ZSTD_compressBound(zf[z].len), src, zf[z].len);
        if (ZSTD_isError(n) || ZSTD_getFrameContentSize(dst, n) != zf[z].len ||
            ZSTD_findFrameCompressedSize(dst, n) != n) {
            fprintf(stderr, "gen_vectors: zstd frame %zu: %s\n", z, ZSTD_isError(n) ? ZSTD_getErrorName(n) : "sizes");
            return 1;
        }
        fprintf(o, "%s{\"contentSize\":%zu,\"frameLength\":%zu,\"descriptor\":%u,\"hex\":\"", z ? "," : "",
                zf[z].len, n, dst[4]);
        for (size_t i = 0; i < n; i++)
            fprintf(o, "%02x", dst[i]);
        fprintf(o, "\"}");
        free(src);
        free(dst);
    }
    ZSTD_freeCCtx(zc);
    fprintf(o, "],\n");

    /* ERROR and BYE */
    proto_buf eb;
    proto_buf_init(&eb, 0);
    uint8_t bad[32] = {0x4f, 0x43, 0x4e, 0x57, 1, 0, 3, 0};
    bad[16] = 42;
    proto_error_reply(&eb, bad, sizeof bad, OCEAN_EINVAL, "camera.fov_y_deg = 0 outside (0, 180)", 4, 2.5);
    snprintf(path, sizeof path, "%s/error.bin", dir);
    FILE *ef = fopen(path, "wb");
    fwrite(proto_buf_data(&eb), 1, proto_buf_len(&eb), ef);
    fclose(ef);
    proto_buf_free(&eb);
    fprintf(o, "\"error\": {\"code\":1,\"offendingType\":3,\"offendingSeq\":42,\"message\":\"camera.fov_y_deg = 0 outside (0, 180)\"},\n");
    proto_msg_init(&m, PROTO_BYE);
    m.u.bye.reason = PROTO_BYE_SLOW_CONSUMER;
    snprintf(m.u.bye.message, sizeof m.u.bye.message, "output buffer over 64 MB");
    if (write_msg(dir, "bye", &m))
        return 1;
    fprintf(o, "\"bye\": {\"reason\":2,\"message\":\"output buffer over 64 MB\"}\n}\n");
    fclose(o);
    for (int t = 0; t < NT; t++) {
        proto_buf_free(&pay[t]);
        free(dec[t]);
    }
    return 0;
}

static void json_str(const char *s)
{
    putchar('"');
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\') printf("\\%c", c);
        else if (c < 0x20) printf("\\u%04x", c);
        else putchar(c);
    }
    putchar('"');
}

static int decode_files(int n, char **files)
{
    for (int i = 0; i < n; i++) {
        FILE *f = fopen(files[i], "rb");
        if (!f) {
            printf("{\"file\":\"%s\",\"code\":-1}\n", files[i]);
            continue;
        }
        fseek(f, 0, SEEK_END);
        long len = ftell(f);
        fseek(f, 0, SEEK_SET);
        uint8_t *buf = malloc(len > 0 ? (size_t)len : 1);
        size_t got = fread(buf, 1, (size_t)len, f);
        fclose(f);
        proto_msg m;
        char err[512];
        ocean_result r = proto_decode(buf, got, &m, err, sizeof err);
        printf("{\"file\":\"%s\",\"code\":%d", files[i], (int)r);
        if (r != OCEAN_OK) {
            printf(",\"err\":");
            json_str(err);
        } else {
            printf(",\"type\":%u,\"seq\":%u,\"simTime\":%.17g", m.hdr.type, m.hdr.seq, m.hdr.sim_time);
            switch (m.hdr.type) {
            case PROTO_SUBSCRIBE: {
                proto_subscribe *s = &m.u.subscribe;
                printf(",\"effects\":%u,\"meshKind\":%u,\"codec\":%u,\"cutoffPolicy\":%u,\"mode\":%u,\"layers\":%u,"
                       "\"lodLevels\":%u,\"tileSize\":%u,\"frameRateHz\":%.9g,\"accuracy\":%.9g,\"baseSpacingM\":%.9g,"
                       "\"viewRangeM\":%.9g,\"layout\":%u,\"meshCodec\":%u,\"flags\":%u",
                       s->effects, s->mesh_kind, s->codec, s->cutoff_policy, s->mode, s->layers, s->lod_levels,
                       s->tile_size, (double)s->frame_rate_hz, (double)s->accuracy, (double)s->base_spacing_m,
                       (double)s->view_range_m, s->layout, s->mesh_codec, s->flags);
                break;
            }
            case PROTO_CAMERA: {
                proto_camera *k = &m.u.camera;
                printf(",\"pos\":[%.17g,%.17g,%.17g],\"vel\":[%.9g,%.9g,%.9g],\"yawDeg\":%.9g,\"pitchDeg\":%.9g,"
                       "\"rollDeg\":%.9g,\"fovYDeg\":%.9g,\"viewportW\":%u,\"viewportH\":%u,\"renderTime\":%.17g",
                       k->pos[0], k->pos[1], k->pos[2], (double)k->vel[0], (double)k->vel[1], (double)k->vel[2],
                       (double)k->yaw_deg, (double)k->pitch_deg, (double)k->roll_deg, (double)k->fov_y_deg,
                       k->viewport_w, k->viewport_h, k->render_time);
                break;
            }
            case PROTO_QUERY: {
                proto_query *q = &m.u.query;
                printf(",\"queryId\":%u,\"count\":%u,\"atTime\":%u,\"t\":%.17g,\"points\":[", q->query_id, q->count,
                       q->at_time, q->t);
                for (uint32_t k = 0; k < 2 * q->count; k++)
                    printf("%s%.17g", k ? "," : "", q->points[k]);
                printf("]");
                break;
            }
            case PROTO_BYE:
                printf(",\"reason\":%u,\"message\":", m.u.bye.reason);
                json_str(m.u.bye.message);
                break;
            default:
                break;
            }
            proto_msg_free(&m);
        }
        printf("}\n");
        free(buf);
    }
    return 0;
}

int main(int argc, char **argv)
{
    if (argc >= 3 && strcmp(argv[1], "gen") == 0)
        return gen(argv[2]);
    if (argc >= 2 && strcmp(argv[1], "decode") == 0)
        return decode_files(argc - 2, argv + 2);
    fprintf(stderr, "usage: gen_vectors gen DIR | decode FILE...\n");
    return 2;
}
