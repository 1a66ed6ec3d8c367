/*
 * bench_link.c - a viewer on a slow link (issue 41, item 3): the daemon on
 * the configuration `make run` serves (config/oceand.conf, ship-bridge),
 * one viewer with the browser viewer's subscription (layout 1, every
 * effect and cascade, qz at 5e-3, 30 Hz) and the bridge camera (25 m up,
 * 1920 x 1080), reading its socket through a shaped link: a 32 KB receive
 * buffer and a token bucket of the link's rate with a tenth of a second of
 * burst, reporting its camera at 30 Hz with the sim time of the last frame
 * it received (PROTOCOL.md "Pacing").  For each link rate, and unshaped:
 * frames a second, each frame's age from its tick (the daemon's sim clock
 * at receipt minus the frame's sim time; one process, one clock), the
 * bytes of a frame, and what the frame gives up for its bytes: its
 * spacing per metre q (the block's; larger is coarser) and its tiles.
 * Each link twice: the viewer's stream, samples in time (SUBSCRIBE flag
 * time_interp: each mip's samples travel once per its update interval, a
 * frame that replaces one still unsent is planned from what the client
 * held before it), and the plain stream (the flag clear, every frame
 * whole), the viewer's before it.  The reader follows its stream as the
 * viewer does: every frame decoded in order through one oc_frame_stream
 * (the samples it holds) and read 30 m ahead of the camera; a frame that
 * does not read there (a sample missed, a frame misapplied) is counted.
 * Markdown on stdout, CSV in tests/bench/out/link.csv.  The first 4 s of
 * each row are the link's settling, not measured.
 */
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "../lib/bench_util.h"
#include "../lib/test_ws.h"
#include "oceanclient.h"
#include "proto_buf.h"
#include "srv_client.h"
#include "srv_daemon.h"

#define MAX_FRAMES 4096

typedef struct row {
    double bps;                   /* the link; 0: unshaped */
    int timed;                    /* the time-interpolating stream */
    int unread;                   /* frames whose view did not read the sea ahead */
    char why[160];                /* the first one's reason */
    int n;
    double at[MAX_FRAMES], age[MAX_FRAMES], bytes[MAX_FRAMES], q[MAX_FRAMES], tiles[MAX_FRAMES];
} row;

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* The p-th percentile of v[i] over frames received at or after `from`. */
static double pct(const row *r, const double *v, double from, double p)
{
    static double tmp[MAX_FRAMES];
    int k = 0;
    for (int i = 0; i < r->n; i++)
        if (r->at[i] >= from) tmp[k++] = v[i];
    if (!k) return NAN;
    qsort(tmp, (size_t)k, sizeof *tmp, cmp_double);
    int idx = (int)ceil(p / 100.0 * k) - 1;
    return tmp[idx < 0 ? 0 : idx];
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* m, encoded, as one binary message. */
static int send_msg(test_ws *w, proto_msg *m)
{
    proto_buf b;
    proto_buf_init(&b, 0);
    int rc = proto_encode(&b, m, NULL, 0) != OCEAN_OK || test_ws_send(w, 2, proto_buf_data(&b), b.len) != 0;
    proto_buf_free(&b);
    return rc;
}

static void send_camera(test_ws *w, const proto_camera *cam, double last_t)
{
    proto_msg m;
    proto_msg_init(&m, PROTO_CAMERA);
    m.u.camera = *cam;
    m.hdr.sim_time = last_t;
    send_msg(w, &m);
}

/* Frame msg of the stream fs, decoded as the viewer does on receipt (in
 * order, into the samples it holds) and read 30 m ahead of camera cam;
 * counted in r when either fails. */
static void follow_frame(oc_frame_stream *fs, const proto_camera *cam, row *r, const uint8_t *msg, size_t len)
{
    oc_frame *f = NULL;
    char err[160] = "";
    ocean_result res = oc_frame_stream_decode(fs, msg, len, &f, err, sizeof err);
    double yaw = cam->yaw_deg * M_PI / 180;
    oc_sample sm;
    if (res == OCEAN_OK) res = oc_frame_sample(f, cam->pos[0] + 30 * cos(yaw), cam->pos[2] + 30 * sin(yaw), 0, &sm);
    if (res != OCEAN_OK && !r->unread++)
        snprintf(r->why, sizeof r->why, "%s %s", ocean_strerror(res), err);
    oc_frame_free(f);
}

/* One FRAME received: its age, bytes, q and tile count. */
static void take_frame(srv_hub *h, row *r, const uint8_t *msg, size_t len, double at, double *last_t)
{
    proto_frame f;
    char err[200];
    *last_t = proto_ldf64(msg + 24);
    if (r->n >= MAX_FRAMES || oc_frame_peek(msg, len, len, &f, NULL, err, sizeof err) != OCEAN_OK) return;
    r->at[r->n] = at;
    r->age[r->n] = srv_hub_sim_time(h) - *last_t;
    r->bytes[r->n] = (double)len;
    r->q[r->n] = f.cascades.spacing_per_m;
    r->tiles[r->n] = f.tile_count;
    r->n++;
}

/* A viewer behind a link of r->bps (0: unshaped) for secs. */
static int shaped_viewer(srv_daemon *d, double secs, row *r)
{
    srv_hub *h = srv_daemon_hub(d);
    test_ws w;
    if (test_ws_connect(&w, srv_daemon_port(d), "/", PROTO_SUBPROTOCOL) != 0) return 1;
    if (r->bps > 0) test_ws_small_rcvbuf(&w, 32768);
    proto_msg m;
    proto_msg_init(&m, PROTO_SUBSCRIBE);
    oc_subscribe_default(&m.u.subscribe);
    if (r->timed)
        m.u.subscribe.flags |= PROTO_SUB_TIME_INTERP;
    else
        m.u.subscribe.flags &= (uint8_t)~PROTO_SUB_TIME_INTERP;
    oc_frame_stream *fs = NULL;
    if (send_msg(&w, &m) || oc_frame_stream_create(&fs) != OCEAN_OK) {
        test_ws_close(&w);
        return 1;
    }
    proto_camera cam;
    oc_camera_default(&cam);
    cam.pos[1] = 25;
    cam.pitch_deg = -10;
    cam.yaw_deg = 30;
    cam.fov_y_deg = 60;
    cam.viewport_w = 1920;
    cam.viewport_h = 1080;
    double t0 = now_s(), next_cam = t0, last_t = 0, tokens = 0, tokens_t = t0;
    while (now_s() - t0 < secs) {
        double now = now_s();
        if (now >= next_cam) {
            send_camera(&w, &cam, last_t);
            next_cam += 1.0 / 30;
        }
        if (r->bps > 0) {
            tokens = fmin(tokens + r->bps * (now - tokens_t), 0.1 * r->bps);
            tokens_t = now;
            if (tokens <= 0) {
                usleep(2000);
                continue;
            }
        }
        uint8_t *msg = NULL;
        size_t n = 0;
        int op = test_ws_recv(&w, 5, &msg, &n);
        if (op < 0) {
            oc_frame_stream_destroy(fs);
            test_ws_close(&w);
            return 1;
        }
        if (op == 2 && n >= PROTO_HEADER_SIZE) {
            tokens -= (double)n;
            if (proto_ld16(msg + 6) == PROTO_FRAME) {
                take_frame(h, r, msg, n, now_s() - t0, &last_t);
                follow_frame(fs, &cam, r, msg, n);
            }
        }
        free(msg);
    }
    oc_frame_stream_destroy(fs);
    test_ws_close(&w);
    return 0;
}

int main(void)
{
    signal(SIGPIPE, SIG_IGN);
    double secs = bench_quick() ? 8 : 16, settle = 4;
    const char *sets[] = {"server.port=0", "server.bind=127.0.0.1"};
    srv_settings st;
    char err[512];
    if (srv_settings_load("config/oceand.conf", sets, 2, &st, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "bench_link: %s\n", err);
        return 1;
    }
    srv_daemon *d = NULL;
    if (srv_daemon_start(&st, &d, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "bench_link: daemon: %s\n", err);
        return 1;
    }
    mkdir("tests/bench/out", 0755);
    FILE *csv = fopen("tests/bench/out/link.csv", "w");
    if (csv)
        fprintf(csv, "link_bytes_per_s,stream,fps,age_p50_ms,age_p99_ms,frame_bytes_p50,frame_bytes_mean,q_p50,"
                     "tiles_p50,frames_unread\n");
    printf("| link | stream | frames/s | age p50 ms | age p99 ms | bytes a frame (p50 / mean) | q: spacing per metre "
           "(p50) | tiles a frame (p50) | frames not read |\n|---|---|---:|---:|---:|---:|---:|---:|---:|\n");
    const double links[] = {0, 3e6, 2e6, 1e6};
    static row r;
    int rc = 0;
    for (size_t k = 0; k < 2 * sizeof links / sizeof links[0] && !rc; k++) {
        memset(&r, 0, sizeof r);
        r.bps = links[k / 2];
        r.timed = k % 2 == 0;
        rc = shaped_viewer(d, secs, &r);
        int measured = 0;
        double bsum = 0;
        for (int i = 0; i < r.n; i++)
            if (r.at[i] >= settle) {
                measured++;
                bsum += r.bytes[i];
            }
        double fps = measured / (secs - settle), bmean = measured ? bsum / measured : NAN;
        double a50 = 1e3 * pct(&r, r.age, settle, 50), a99 = 1e3 * pct(&r, r.age, settle, 99);
        double b50 = pct(&r, r.bytes, settle, 50), q50 = pct(&r, r.q, settle, 50), t50 = pct(&r, r.tiles, settle, 50);
        char name[32];
        if (r.bps > 0) snprintf(name, sizeof name, "%.0f MB/s", r.bps / 1e6);
        else snprintf(name, sizeof name, "unshaped");
        const char *stream = r.timed ? "time-interp" : "plain";
        printf("| %s | %s | %.1f | %.1f | %.1f | %.0f / %.0f | %.4g | %.0f | %d%s%s |\n", name, stream, fps, a50, a99,
               b50, bmean, q50, t50, r.unread, r.unread ? ": " : "", r.why);
        if (csv)
            fprintf(csv, "%.0f,%s,%.2f,%.2f,%.2f,%.0f,%.0f,%.6g,%.0f,%d\n", r.bps, stream, fps, a50, a99, b50, bmean,
                    q50, t50, r.unread);
        /* a stream the viewer cannot follow is a failure, not a figure */
        if (r.unread) rc = 1;
    }
    if (csv) fclose(csv);
    printf("\nThe daemon on config/oceand.conf (ship-bridge) in this process; one viewer at a time with the browser "
           "viewer's subscription and camera (25 m, 1920 x 1080), %.0f s a row of which the first %.0f s are not "
           "measured; each link with the viewer's stream (time-interp: samples in time) and the plain one (every "
           "frame whole, the viewer's before it).  Age: the daemon's sim clock at receipt minus the frame's sim "
           "time.  A coarser q is what a slow link's frames give up for their bytes (PROTOCOL.md \"Pacing\").  "
           "Every frame is decoded in order as the viewer does and read 30 m ahead of the camera: frames not read "
           "counts those whose view missed the sea there (a sample missed or misapplied; any fails the bench).\n",
           secs, settle);
    srv_daemon_stop(d);
    return rc;
}
