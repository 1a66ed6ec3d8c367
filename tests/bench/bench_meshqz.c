/*
 * bench_meshqz.c - layout-0 mesh positions as f32 and as qz
 * (MESH_VERTICES_QZ, issue 14), on real server frames.
 *
 * Starts the daemon in-process on config/oceand.conf (the scene `make run`
 * serves) and subscribes as the layout-0 rows of bench_server.sh do (the
 * browser viewer before issue 14: every effect and cascade, concentric
 * mesh, qz tiles, antialias cutoff, 64-sample tiles, min(8, max) levels,
 * level-0 spacing 1 m), in replay mode so the f32 and the qz subscription
 * get the same cameras at the same times: a camera 25 m up (yaw 30, pitch
 * -10, fov 60, 1920x1080) stepping 20 m along x per frame (the "20 m
 * apart" viewers), once with mesh_codec f32 and once with qz, at the
 * accuracy those rows use (1e-3) and at the viewer's qz accuracy (5e-3).
 *
 * Per accuracy: mesh record bytes per frame f32 vs qz (and the ratio), the
 * mesh's share of the f32 frame, the largest |qz - f32| per axis against
 * the stated bound (half the axis step plus f32 rounding: 1.00 = at the
 * bound), and medians over frames of the encode time per mesh (one codec
 * context reused, as a daemon worker does), of the decode time and of the
 * prediction references (made once per topology).  Beside the
 * parallelogram predictor the format uses, the same quantised positions
 * predicted by the previous vertex in vertex order (the stateless
 * alternative; same byte planes and zstd level) show why it was chosen.
 *
 * Prints markdown to stdout and writes tests/bench/out/meshqz.csv.
 * BENCH_QUICK shortens the run.
 */
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <zstd.h>

#include "../lib/bench_util.h"
#include "codec.h"
#include "oceanclient.h"
#include "srv_daemon.h"

#define MAXF 16

typedef struct run {
    oc_frame *f[MAXF];
    int n;
} run;

static int replay(int port, int mesh_codec, double accuracy, int levels, int nframes, run *out)
{
    char url[64], err[256];
    snprintf(url, sizeof url, "ws://127.0.0.1:%d/", port);
    oc_options o;
    oc_options_default(&o);
    o.url = url;
    oc_client *c = NULL;
    if (oc_connect(&o, 10000, &c, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "bench_meshqz: connect: %s\n", err);
        return -1;
    }
    proto_subscribe s;
    oc_subscribe_default(&s);
    s.layout = PROTO_LAYOUT_WORLD;
    s.mode = PROTO_MODE_REPLAY;
    s.effects = PROTO_FX_ALL;
    s.layers = 4;
    s.mesh_kind = PROTO_MESH_CONCENTRIC;
    s.codec = PROTO_CODEC_QZ;
    s.accuracy = (float)accuracy;
    s.cutoff_policy = PROTO_CUTOFF_ANTIALIAS;
    s.tile_size = 64;
    s.lod_levels = (uint8_t)levels;
    s.base_spacing_m = 1;
    s.mesh_codec = (uint8_t)mesh_codec;
    proto_camera cam;
    oc_camera_default(&cam);
    cam.pos[1] = 25;
    cam.yaw_deg = 30;
    cam.pitch_deg = -10;
    cam.fov_y_deg = 60;
    if (oc_client_subscribe(c, &s) != OCEAN_OK) {
        oc_client_destroy(c);
        return -1;
    }
    for (int i = 0; i < nframes; i++) {
        cam.pos[0] = 20.0 * i;
        cam.render_time = 100.0 + i / 30.0;
        oc_client_send_camera(c, &cam, NULL);
    }
    out->n = 0;
    for (int i = 0; i < nframes; i++) {
        oc_frame *f = NULL;
        if (oc_client_next_frame(c, 20000, &f) != OCEAN_OK || !f->info.has_mesh || !f->topology ||
            !f->info.mesh.positions) {
            oc_client_last_error(c, err, sizeof err);
            fprintf(stderr, "bench_meshqz: frame %d without a decoded mesh (%s)\n", i, err);
            oc_frame_free(f);
            oc_client_destroy(c);
            return -1;
        }
        out->f[out->n++] = f;
    }
    oc_client_destroy(c);
    return 0;
}

/* Bytes of the previous-vertex alternative: the format's quantisation,
 * residual q[v] - q[v-1] along the vertex order, byte planes, zstd 3. */
static size_t delta_bytes(const float *xyz, uint32_t n, double accuracy)
{
    float base[3], step[3];
    if (proto_mesh_qz_steps(accuracy, n, xyz, base, step) != OCEAN_OK)
        return 0;
    uint8_t *raw = malloc(12 * (size_t)n + 1);
    size_t len = 0;
    for (int a = 0; a < 3; a++) {
        uint32_t *z = malloc(sizeof *z * n), zmax = 0;
        int64_t prev = 0;
        for (uint32_t v = 0; v < n; v++) {
            int64_t q = llround(((double)xyz[3 * v + a] - base[a]) / step[a]);
            int64_t r = q - prev;
            prev = q;
            z[v] = (uint32_t)((uint64_t)r << 1) ^ (uint32_t)(r >> 63);
            zmax = z[v] > zmax ? z[v] : zmax;
        }
        int nb = zmax == 0 ? 0 : zmax < 0x100u ? 1 : zmax < 0x10000u ? 2 : zmax < 0x1000000u ? 3 : 4;
        for (int b = 0; b < nb; b++)
            for (uint32_t v = 0; v < n; v++)
                raw[len++] = (uint8_t)(z[v] >> (8 * b));
        free(z);
    }
    size_t cap = ZSTD_compressBound(len);
    void *dst = malloc(cap);
    size_t zn = ZSTD_compress(dst, cap, raw, len, 3);
    free(dst);
    free(raw);
    return ZSTD_isError(zn) ? 0 : zn + PROTO_MESH_QZ_HEAD;
}

int main(void)
{
    signal(SIGPIPE, SIG_IGN);
    int quick = bench_quick();
    int nframes = quick ? 4 : 12, reps = quick ? 3 : 7;
    /* admission off: the layout-0 client measured is not what it judges */
    const char *sets[] = {"server.port=0", "server.bind=127.0.0.1", "server.admit_share=0"};
    srv_settings st;
    char err[512];
    if (srv_settings_load("config/oceand.conf", sets, 3, &st, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "bench_meshqz: %s\n", err);
        return 1;
    }
    srv_daemon *d = NULL;
    if (srv_daemon_start(&st, &d, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "bench_meshqz: daemon: %s\n", err);
        return 1;
    }
    int port = srv_daemon_port(d);
    int levels = st.srv.max_lod_levels < 8 ? st.srv.max_lod_levels : 8;
    mkdir("tests/bench/out", 0755);
    FILE *csv = fopen("tests/bench/out/meshqz.csv", "w");
    if (csv)
        fprintf(csv, "accuracy,frames,vertices,f32_record_bytes,qz_record_bytes,ratio,delta_order_bytes,"
                     "mesh_share_of_f32_frame,err_over_bound_x,err_over_bound_y,err_over_bound_z,step_y_m,"
                     "encode_ms,decode_ms,refs_ms\n");
    printf("| accuracy | vertices | f32 mesh bytes/frame | qz mesh bytes/frame | ratio | previous-vertex predictor "
           "(not used) | mesh share of the f32 frame | max error / bound x, y, z | y step (m) | encode ms/mesh | "
           "decode ms/mesh | refs ms/topology |\n");
    printf("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    const double accs[2] = {1e-3, 5e-3};
    int rc = 0;
    for (int ai = 0; ai < 2 && rc == 0; ai++) {
        double acc = (double)(float)accs[ai];
        run a, b;
        if (replay(port, PROTO_MESH_CODEC_F32, acc, levels, nframes, &a) ||
            replay(port, PROTO_MESH_CODEC_QZ, acc, levels, nframes, &b)) {
            rc = 1;
            break;
        }
        double f32b = 0, qzb = 0, deltab = 0, share = 0, worst[3] = {0, 0, 0}, stepy = 0, verts = 0;
        double enc[MAXF], dec[MAXF], refs_ms[MAXF];
        proto_codec_ctx *cx = NULL;
        proto_codec_ctx_create(&cx);
        for (int i = 0; i < a.n; i++) {
            const proto_mesh_vertices *p = &a.f[i]->info.mesh, *q = &b.f[i]->info.mesh;
            uint32_t n = p->vertex_count;
            if (b.f[i]->info.has_mesh != 2 || q->vertex_count != n) {
                fprintf(stderr, "bench_meshqz: frame %d: has_mesh %u, %u vs %u vertices\n", i, b.f[i]->info.has_mesh,
                        q->vertex_count, n);
                rc = 1;
                break;
            }
            verts += n;
            f32b += 32.0 + 12.0 * n;
            qzb += 32.0 + q->qz_len;
            share += (32.0 + 12.0 * n) / (double)a.f[i]->raw_len;
            deltab += 32.0 + (double)delta_bytes(p->positions, n, acc);
            proto_mesh_qz_info in;
            proto_mesh_qz_header(q->qz, q->qz_len, n, &in, NULL, 0);
            stepy += in.step[1];
            for (int k = 0; k < 3; k++) {
                double e = 0, bound = proto_mesh_qz_error_bound(in.base, in.step, n, p->positions, k);
                for (uint32_t v = 0; v < n; v++)
                    e = fmax(e, fabs((double)q->positions[3 * v + k] - (double)p->positions[3 * v + k]));
                worst[k] = fmax(worst[k], e / bound);
            }
            /* timings on the f32 frame's mesh with its topology */
            const oc_topology *t = a.f[i]->topology;
            uint32_t *refs = malloc(3 * sizeof *refs * (size_t)n);
            float *back = malloc(12 * (size_t)n);
            double te[16], td[16], tr[16];
            for (int r = 0; r < reps; r++) {
                double t0 = bench_now_ms();
                proto_mesh_qz_refs(t->indices, t->index_count, n, refs);
                double t1 = bench_now_ms();
                proto_buf out;
                proto_buf_init(&out, 0);
                proto_mesh_qz_encode(cx, acc, n, p->positions, refs, &out, NULL, NULL, 0);
                double t2 = bench_now_ms();
                proto_mesh_qz_decode(proto_buf_data(&out), proto_buf_len(&out), n, refs, back, NULL, 0);
                double t3 = bench_now_ms();
                /* the server's bytes are these bytes */
                if (r == 0 && (proto_buf_len(&out) != q->qz_len || memcmp(proto_buf_data(&out), q->qz, q->qz_len))) {
                    fprintf(stderr, "bench_meshqz: frame %d: encoding differs from the daemon's\n", i);
                    rc = 1;
                }
                proto_buf_free(&out);
                tr[r] = t1 - t0;
                te[r] = t2 - t1;
                td[r] = t3 - t2;
            }
            refs_ms[i] = bench_median(tr, reps);
            enc[i] = bench_median(te, reps);
            dec[i] = bench_median(td, reps);
            free(refs);
            free(back);
        }
        proto_codec_ctx_destroy(cx);
        int n = a.n;
        double me = bench_median(enc, n), md = bench_median(dec, n), mr = bench_median(refs_ms, n);
        printf("| %g | %.0f | %.0f | %.0f | 1/%.2f | %.0f (1/%.2f) | %.0f %% | %.2f, %.2f, %.2f | %.4f | %.3f | %.3f | %.3f |\n",
               accs[ai], verts / n, f32b / n, qzb / n, f32b / qzb, deltab / n, f32b / deltab, 100 * share / n,
               worst[0], worst[1], worst[2], stepy / n, me, md, mr);
        if (csv)
            fprintf(csv, "%g,%d,%.0f,%.0f,%.0f,%.4f,%.0f,%.4f,%.4f,%.4f,%.4f,%.6f,%.4f,%.4f,%.4f\n", accs[ai], n, verts / n,
                    f32b / n, qzb / n, f32b / qzb, deltab / n, share / n, worst[0], worst[1], worst[2], stepy / n, me,
                    md, mr);
        for (int i = 0; i < a.n; i++) {
            oc_frame_free(a.f[i]);
            oc_frame_free(b.f[i]);
        }
    }
    if (csv)
        fclose(csv);
    printf("\n%d frames per accuracy (camera 25 m up, 20 m apart along x, replay mode so f32 and qz frames show the "
           "same meshes), config/oceand.conf, the layout-0 subscription of bench_server.sh's rows \"viewer before issue "
           "14\"; bytes are the FRAME's mesh record body (32-byte head + positions or qz payload); error / bound: the "
           "largest |qz - f32| over every vertex of every frame over the stated bound (half the axis step + f32 "
           "rounding); timings: medians over frames of the median of %d runs, one codec context reused as a daemon "
           "worker does. The previous-vertex column quantises alike and codes q[v] - q[v-1] in vertex order.\n",
           nframes, reps);
    srv_daemon_stop(d);
    return rc;
}
