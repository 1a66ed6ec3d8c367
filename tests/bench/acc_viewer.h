/*
 * acc_viewer.h - the accuracy of what the browser viewer receives
 * (issue 13): layout-1 frames from a real oceand, reconstructed as the
 * client does, against the exact waves.  Included by bench_accuracy.c
 * (every .c file in tests/bench is a program of its own, so this part is a header).
 *
 * What is measured, and why this way:
 *  - the daemon: build/oceand started as `make run` starts it
 *    (--config config/oceand.conf, nothing else but a free --port), so the
 *    scene is server.scene of the shipped config (ship-bridge) and every
 *    server.* key is the shipped one;
 *  - the subscription: oc_subscribe_default, which is the browser viewer's
 *    (clients/web/worker.js chooseSubscription: layout 1, qz, antialias,
 *    30 Hz, lod 8, tile 64, accuracy OC_ACCURACY_DEFAULT = 5e-3, concentric
 *    mesh, samples in time) with layers =
 *    HELLO.max_layers and effects = all & HELLO.effects, as the viewer
 *    computes them; every camera is measured twice, before and after: the
 *    plain stream (the time_interp flag clear, every frame whole) from a
 *    daemon with the byte budget shipped before (AV_BEFORE_BYTES_PER_S),
 *    and the time-interpolating one (each frame read from the blend of two
 *    samples the client holds, every frame applied on receipt) from the
 *    daemon as shipped, so what the viewer gets now sits beside what it
 *    got;
 *  - the cameras: at (0, H, 0), H from 3 m to 1500 m, heading 0, 60 deg
 *    vertical field of view, 1920 x 1080 viewport (a desktop browser's
 *    drawing buffer; the viewer reports its real one), pitch atan(H / 10
 *    km) + fov / 4 below the horizon (ocean-client fidelity's default: half
 *    the view or more lands on sea within the view range from every
 *    height); still, and flying at 60 m/s along the heading (reported 30
 *    times a second: tiles come into view, and on the time-interpolating
 *    stream both their samples travel);
 *  - the reconstruction: a grid of the viewport's pixel centres is cast onto
 *    the mean sea plane and the frame is read there by oc_frame_sample
 *    (clients/c/oc_cascade.c: the spec's lod rule with the pixel footprint,
 *    Keys cubic within a mip, cascades summed), i.e. what the viewer's
 *    fragment shading reads at that pixel (spacing s, no vertex floor), at
 *    the parameter point (x, z);
 *  - the exact waves: the same ocean built in-process from the same config
 *    (srv_settings_load, as the daemon loads it), checked against the
 *    frame's cascade block (patches, grids, every mip's cutoff), every mode
 *    of every cascade summed directly in double at each point at the frame's
 *    sim time (ocean_mode_amplitude; checked against ocean_reference_point).
 *    "Carried" weights each mode with what the frame's mips read at that
 *    point hold of it: sum over the mips the lod rule reads of weight x
 *    Butterworth gain (the block's order and each mip's kc, waves below
 *    ocean.drop_gain left out, as ocean_evaluate does), fade included;
 *    height and displacement by the mips read at max(s, G) (the block's
 *    geometry_spacing_m: finer mips carry normals alone), slopes at s.
 *    "Full" takes every mode at gain 1.  So:
 *      carried error  = reconstruction - exact carried waves (the codec,
 *                       float storage, cubic reading between samples);
 *      left to shading = exact full - exact carried (the waves the frame
 *                       hands to shading as unresolved slope variance;
 *                       e_error is its height-variance fraction at the
 *                       nadir), beside the variance the frame claims for it;
 *      total          = reconstruction - exact full.
 *    The Gerstner near field (ship-bridge has one) travels in layout 1 as
 *    one more cascade, its waves on a lattice: the exact sum takes those
 *    waves from the same lattice ocean the daemon builds
 *    (srv_settings_near_field, ocean_gerstner_cascade_create).  The
 *    short-wave tail beyond the near field is in no figure (tail_mss).
 *  - cost: bytes/s = FRAME bytes received over a window of frames made for
 *    the camera; daemon cores = the daemon's CPU time (utime + stime,
 *    /proc/PID/stat) over the same window, with this one viewer connected;
 *    errors over AV_ERR_FRAMES frames spread over that window.
 */
#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include "oc_cascade.h"
#include "oceanclient.h"
#include "srv_config.h"

/* The cameras: heights from a ship's deck to an aircraft's, each still and
 * flying at 60 m/s along its heading (a fast ship's boat, a slow
 * aircraft), reporting its camera 30 times a second as the viewer does. */
typedef struct av_cam {
    double height, speed;
} av_cam;
static const av_cam av_cams[] = {{3, 0}, {25, 0}, {300, 0}, {1500, 0}, {3, 60}, {25, 60}, {300, 60}, {1500, 60}};
#define AV_CAMS ((int)(sizeof av_cams / sizeof av_cams[0]))
/* Each camera with both streams: 0 the plain one (every frame whole), 1
 * samples in time (SUBSCRIBE flag time_interp, the viewer's). */
#define AV_STREAMS 2
static const char *const av_stream_name[AV_STREAMS] = {"plain", "time-interp"};

/* The budget the plain stream was planned with before samples in time:
 * server.viewer_bytes_per_s as config/oceand.conf shipped it, where a
 * viewer took 3-5 MB/s.  The "before" rows are that stream as it was
 * served; the "after" rows the viewer's stream on today's config. */
#define AV_BEFORE_BYTES_PER_S "3.9e6"
/* Frames whose errors are measured per row, spread over the window: a
 * time-interpolating frame's error depends on where it falls between its
 * mips' samples, so more than one instant is read. */
#define AV_ERR_FRAMES 3

typedef struct av_casc {
    int m;                    /* modes |mx|, |mz| <= m */
    double dk, patch;
    size_t count;
    int *mx, *mz;
    double *kx, *kz, *lkx, *lkz; /* kx, kz, lambda kx / k, lambda kz / k */
    double *hr, *hi;          /* h(k, t) */
    int mips;
    float *gain[PROTO_MAX_MIPS]; /* per mip, per mode */
} av_casc;

typedef struct av_err {       /* sums over points */
    double n, h2, hmax, d2, dmax, a2, amax;
} av_err;

static void av_err_add(av_err *e, double dh, double dd, double ang)
{
    e->n++;
    e->h2 += dh * dh;
    e->d2 += dd * dd;
    e->a2 += ang * ang;
    if (fabs(dh) > e->hmax) e->hmax = fabs(dh);
    if (dd > e->dmax) e->dmax = dd;
    if (ang > e->amax) e->amax = ang;
}

/* The heights a mesh level's vertices take against the exact sea at the
 * same points (sums): how much of the sea's height spread each ring keeps
 * and how well it follows it. */
typedef struct av_level {
    double n, m, m2, e, e2, me, d2, dmin, dmax, g;
} av_level;

static void av_level_add(av_level *l, double mesh_h, double exact_h, double dist, double g)
{
    if (l->n == 0 || dist < l->dmin) l->dmin = dist;
    if (dist > l->dmax) l->dmax = dist;
    l->n++;
    l->m += mesh_h;
    l->m2 += mesh_h * mesh_h;
    l->e += exact_h;
    l->e2 += exact_h * exact_h;
    l->me += mesh_h * exact_h;
    l->d2 += (mesh_h - exact_h) * (mesh_h - exact_h);
    l->g = g;
}

typedef struct av_row {
    double height, speed, pitch, q, e_error, e_total;
    int timed;                   /* the time-interpolating stream */
    int err_frames;              /* frames whose errors were measured */
    double bytes_s, frames_s, kib_frame, tiles_frame, cores;
    double tile_ratio;           /* raw f32 bytes of the tiles' planes over their payload bytes */
    double normals_only;         /* tiles a frame without H (geometry-free mips) */
    double points, above, outside;
    av_err carried, shading, total;
    av_err v_carried, v_geom;   /* the vertex rule: spacing max(s, g_L) */
    double v_points;
    av_level lev[PROTO_MAX_LOD_LEVELS]; /* the vertex rule per mesh level */
    int has_mesh;
    double g0, r0, glast;        /* the mesh's finest ring spacing and radius, coarsest spacing */
    double mss_left_meas, mss_left_claim, mss_res_exact, mss_tail;
    int ok;
    char why[200];
} av_row;

static double av_angle_deg(double sx0, double sz0, double sx1, double sz1)
{
    double a[3], b[3];
    normal_of(sx0, sz0, a);
    normal_of(sx1, sz1, b);
    double c = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    double cx = a[1] * b[2] - a[2] * b[1], cy = a[2] * b[0] - a[0] * b[2], cz = a[0] * b[1] - a[1] * b[0];
    return atan2(sqrt(cx * cx + cy * cy + cz * cz), c) * 180.0 / M_PI;
}

static void av_casc_free(av_casc *C)
{
    free(C->mx);
    free(C->mz);
    free(C->kx);
    free(C->kz);
    free(C->lkx);
    free(C->lkz);
    free(C->hr);
    free(C->hi);
    for (int i = 0; i < PROTO_MAX_MIPS; i++)
        free(C->gain[i]);
    memset(C, 0, sizeof *C);
}

/* Cascade c's modes at time t and, per mip of the frame's block, the gain
 * ocean_evaluate gives each (ocean.c effective_gain: Butterworth below
 * ocean_filter_negligible_k(kc, order, drop_gain), 0 above). */
/* Cascade c of ocean o, read by the frame's cascade entry bk (the
 * near-field lattice is a one-cascade ocean of its own, the block's last
 * entry). */
static void av_casc_build(av_casc *C, const ocean *o, int c, int bk, double t, const proto_cascade_block *b)
{
    memset(C, 0, sizeof *C);
    double patch, klo, khi;
    ocean_cascade_band(o, c, &patch, &klo, &khi);
    const ocean_params *p = ocean_get_params(o);
    C->patch = patch;
    C->dk = 2.0 * M_PI / patch;
    C->m = p->n / 2 - 1;
    size_t cap = (size_t)(C->m + 1) * (2 * C->m + 1);
    C->mx = xcalloc(cap, sizeof(int));
    C->mz = xcalloc(cap, sizeof(int));
    double **arr[] = {&C->kx, &C->kz, &C->lkx, &C->lkz, &C->hr, &C->hi};
    for (size_t i = 0; i < sizeof arr / sizeof arr[0]; i++)
        *arr[i] = xcalloc(cap, sizeof(double));
    double lam = p->sea.choppiness;
    for (int mz = 0; mz <= C->m; mz++)
        for (int mx = mz == 0 ? 1 : -C->m; mx <= C->m; mx++) {
            double h[2];
            ocean_mode_amplitude(o, c, mx, mz, t, h);
            if (h[0] == 0.0 && h[1] == 0.0)
                continue;
            size_t q = C->count++;
            double kx = mx * C->dk, kz = mz * C->dk, k = hypot(kx, kz);
            C->mx[q] = mx;
            C->mz[q] = mz;
            C->kx[q] = kx;
            C->kz[q] = kz;
            C->lkx[q] = lam * kx / k;
            C->lkz[q] = lam * kz / k;
            C->hr[q] = h[0];
            C->hi[q] = h[1];
        }
    const proto_cascade_entry *e = &b->cascade[bk];
    C->mips = e->mips;
    for (int mi = 0; mi < e->mips; mi++) {
        C->gain[mi] = xcalloc(C->count, sizeof(float));
        double kc = e->mip[mi].kc;
        double kneg = isinf(kc) ? INFINITY : ocean_filter_negligible_k(kc, b->order, p->drop_gain);
        for (size_t q = 0; q < C->count; q++) {
            double k = hypot(C->kx[q], C->kz[q]);
            C->gain[mi][q] = isinf(kc) ? 1.0f : k < kneg ? (float)ocean_filter_gain(k, kc, b->order) : 0.0f;
        }
    }
}

/* Exact fields at world (x, z): full[5] = h, dx, dz, sx, sz of every mode
 * of every cascade; car[5] the same with each mode weighted by what the
 * frame's mips read there hold of it (lod L). */
static void av_exact(const av_casc *C, int nc, const oc_lod *L, double x, double z, double full[5], double car[5])
{
    for (int i = 0; i < 5; i++)
        full[i] = car[i] = 0.0;
    for (int c = 0; c < nc; c++) {
        const av_casc *K = &C[c];
        int m = K->m, ncol = 2 * m + 1;
        double *exr = xcalloc((size_t)ncol, sizeof(double)), *exi = xcalloc((size_t)ncol, sizeof(double));
        double *ezr = xcalloc((size_t)m + 1, sizeof(double)), *ezi = xcalloc((size_t)m + 1, sizeof(double));
        double xr = fmod(x, K->patch), zr = fmod(z, K->patch);
        for (int j = -m; j <= m; j++) {
            double ph = fmod(j * K->dk * xr, 2.0 * M_PI);
            exr[j + m] = cos(ph);
            exi[j + m] = sin(ph);
        }
        for (int j = 0; j <= m; j++) {
            double ph = fmod(j * K->dk * zr, 2.0 * M_PI);
            ezr[j] = cos(ph);
            ezi[j] = sin(ph);
        }
        const oc_lod_cascade *lc = &L->c[c];
        const float *g0 = lc->mip[0] >= 0 && lc->weight[0] != 0 ? K->gain[lc->mip[0]] : NULL;
        const float *g1 = lc->mip[1] >= 0 && lc->weight[1] != 0 ? K->gain[lc->mip[1]] : NULL;
        double w0 = lc->weight[0], w1 = lc->weight[1];
        double f[5] = {0}, a[5] = {0};
        for (size_t q = 0; q < K->count; q++) {
            int jx = K->mx[q] + m, jz = K->mz[q];
            double er = exr[jx] * ezr[jz] - exi[jx] * ezi[jz], ei = exr[jx] * ezi[jz] + exi[jx] * ezr[jz];
            double pr = K->hr[q] * er - K->hi[q] * ei, pi = K->hr[q] * ei + K->hi[q] * er;
            double v[5] = {pr, -K->lkx[q] * pi, -K->lkz[q] * pi, -K->kx[q] * pi, -K->kz[q] * pi};
            double g = (g0 ? w0 * g0[q] : 0.0) + (g1 ? w1 * g1[q] : 0.0);
            for (int i = 0; i < 5; i++) {
                f[i] += v[i];
                a[i] += g * v[i];
            }
        }
        for (int i = 0; i < 5; i++) {
            full[i] += 2.0 * f[i];
            car[i] += 2.0 * a[i];
        }
        free(exr);
        free(exi);
        free(ezr);
        free(ezi);
    }
}

static int av_free_port(void)
{
    int s = socket(AF_INET, SOCK_STREAM, 0);
    if (s < 0)
        return -1;
    struct sockaddr_in a;
    memset(&a, 0, sizeof a);
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof a;
    int port = -1;
    if (bind(s, (struct sockaddr *)&a, sizeof a) == 0 && getsockname(s, (struct sockaddr *)&a, &len) == 0)
        port = ntohs(a.sin_port);
    close(s);
    return port;
}

/* CPU seconds the process has used (utime + stime). */
static double av_cpu_s(pid_t pid)
{
    char path[64], buf[2048];
    snprintf(path, sizeof path, "/proc/%d/stat", (int)pid);
    FILE *f = fopen(path, "r");
    if (!f)
        return NAN;
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = 0;
    char *p = strrchr(buf, ')');
    if (!p)
        return NAN;
    unsigned long ut = 0, st = 0;
    /* after ") ": state ppid pgrp session tty tpgid flags minflt cminflt majflt cmajflt utime stime */
    if (sscanf(p + 2, "%*c %*d %*d %*d %*d %*d %*u %*u %*u %*u %*u %lu %lu", &ut, &st) != 2)
        return NAN;
    return (double)(ut + st) / (double)sysconf(_SC_CLK_TCK);
}

static double av_now_s(void) { return bench_now_ms() * 1e-3; }

/* Subscribes as the viewer does (layers and effects from HELLO; flag
 * time_interp as R->timed says) with the camera of R (still at (0, H, 0),
 * heading 0, pitch atan(H / 10 km) + fov / 4 below the horizon, flying
 * R->speed along x), reported 30 times a second when it flies.  NULL on
 * failure (R->why). */
static oc_client *av_subscribe(const char *url, av_row *R, proto_camera *cam, uint32_t *seq)
{
    oc_options o;
    oc_options_default(&o);
    o.url = url;
    oc_client *c = NULL;
    char err[512] = "";
    if (oc_connect(&o, 10000, &c, err, sizeof err) != OCEAN_OK) {
        snprintf(R->why, sizeof R->why, "connect: %.150s", err);
        return NULL;
    }
    proto_hello hello;
    oc_client_hello(c, &hello);
    proto_subscribe sub;
    oc_subscribe_default(&sub);
    sub.layers = hello.max_layers;
    sub.effects = (uint8_t)(PROTO_FX_ALL & (hello.effects ? hello.effects : PROTO_FX_ALL));
    if (R->timed)
        sub.flags |= PROTO_SUB_TIME_INTERP;
    else
        sub.flags &= (uint8_t)~PROTO_SUB_TIME_INTERP;
    oc_camera_default(cam);
    cam->pos[1] = R->height;
    cam->vel[0] = (float)R->speed;
    cam->fov_y_deg = 60.0f;
    cam->viewport_w = 1920;
    cam->viewport_h = 1080;
    cam->yaw_deg = 0.0f;
    R->pitch = -(atan(R->height / 10000.0) * 180.0 / M_PI + 60.0 / 4.0);
    cam->pitch_deg = (float)R->pitch;
    if (oc_client_subscribe(c, &sub) != OCEAN_OK || oc_client_send_camera(c, cam, seq) != OCEAN_OK) {
        oc_client_last_error(c, err, sizeof err);
        snprintf(R->why, sizeof R->why, "subscribe: %.150s", err);
        oc_client_destroy(c);
        return NULL;
    }
    return c;
}

/* What the window's frames cost: sums over them. */
typedef struct av_window {
    double bytes, tiles, nfr, q, ee, et;
    double tpay, traw, tnorm;   /* the tiles: payload and raw f32 bytes, normals-only count */
} av_window;

static void av_window_add(av_window *W, const oc_frame *f)
{
    W->bytes += (double)f->raw_len;
    W->tiles += f->info.tile_count;
    for (int t = 0; t < f->info.tile_count; t++) {
        const proto_tile *ti = &f->tiles[t].info;
        W->tpay += ti->payload_len;
        W->traw += 4.0 * proto_tile_planes(ti->channels) * ti->width * ti->height;
        W->tnorm += !(ti->channels & PROTO_CH_HEIGHT);
    }
    W->q += f->info.cascades.spacing_per_m;
    W->ee += f->info.e_error;
    W->et += f->info.cascades.e_total;
    W->nfr++;
}

/* One row's stream: subscribe, settle 1 s after the first frame made for
 * the camera, then measure bytes, frames and the daemon's CPU over
 * window_s of frames and keep AV_ERR_FRAMES of them, spread over the
 * window (the last at its end), in keep[].  *cam: the camera as last
 * reported.  Returns how many frames it kept (R->why when none). */
static int av_stream(const char *url, pid_t daemon, double window_s, av_row *R, proto_camera *cam,
                     oc_frame *keep[AV_ERR_FRAMES])
{
    uint32_t seq = 0;
    oc_client *c = av_subscribe(url, R, cam, &seq);
    if (!c)
        return 0;
    double t0 = av_now_s(), first = NAN, w0 = NAN, cpu0 = NAN, last_cam = t0;
    av_window W;
    memset(&W, 0, sizeof W);
    int kept = 0;
    char err[512];
    while (av_now_s() - t0 < 30.0 && kept < AV_ERR_FRAMES) {
        double now = av_now_s();
        if (R->speed > 0 && now - last_cam >= 1.0 / 30) {
            cam->pos[0] = R->speed * (now - t0);
            oc_client_send_camera(c, cam, NULL);
            last_cam = now;
        }
        oc_frame *f = NULL;
        ocean_result r = oc_client_next_frame(c, R->speed > 0 ? 20 : 2000, &f);
        if (r == OCEAN_ESTATE)
            continue;
        if (r != OCEAN_OK) {
            oc_client_last_error(c, err, sizeof err);
            snprintf(R->why, sizeof R->why, "frame: %.150s", err);
            break;
        }
        now = av_now_s();
        int mine = f->info.camera_seq != PROTO_NO_CAMERA && (int32_t)(f->info.camera_seq - seq) >= 0 &&
                   f->info.layout == PROTO_LAYOUT_CASCADE;
        if (mine && isnan(first))
            first = now;
        /* the window opens at the first frame after 1 s of settling */
        if (!mine || now - first < 1.0 || isnan(w0)) {
            if (mine && now - first >= 1.0) {
                w0 = now;
                cpu0 = av_cpu_s(daemon);
            }
            oc_frame_free(f);
            continue;
        }
        av_window_add(&W, f);
        if (now - w0 >= (kept + 1) * window_s / AV_ERR_FRAMES) {
            keep[kept++] = f;
            if (kept == AV_ERR_FRAMES) {
                R->bytes_s = W.bytes / (now - w0);
                R->frames_s = W.nfr / (now - w0);
                R->cores = (av_cpu_s(daemon) - cpu0) / (now - w0);
            }
        } else {
            oc_frame_free(f);
        }
    }
    oc_client_destroy(c);
    if (kept < AV_ERR_FRAMES || W.nfr == 0) {
        if (!R->why[0])
            snprintf(R->why, sizeof R->why, "no measurement window of frames made for the camera");
        for (int k = 0; k < kept; k++)
            oc_frame_free(keep[k]);
        return 0;
    }
    R->kib_frame = W.bytes / W.nfr / 1024.0;
    R->tiles_frame = W.tiles / W.nfr;
    R->tile_ratio = W.tpay > 0 ? W.traw / W.tpay : 0.0;
    R->normals_only = W.tnorm / W.nfr;
    R->q = W.q / W.nfr;
    R->e_error = W.ee / W.nfr;
    R->e_total = W.et / W.nfr;
    return kept;
}

/* The ocean each of block b's cascades is (the FFT's, then the near
 * field's lattice, the daemon's from the same settings) in oc_of / c_of,
 * checked against the block: patches, grids, every mip's cutoff.  0 when
 * they agree, else R->why. */
static int av_block_oceans(const proto_cascade_block *b, const ocean *ref, const ocean *nf,
                           const ocean *oc_of[PROTO_MAX_LAYERS], int c_of[PROTO_MAX_LAYERS], av_row *R)
{
    const ocean_params *p = ocean_get_params(ref);
    int want = p->cascades + (nf ? 1 : 0);
    if (b->cascade_count != want) {
        snprintf(R->why, sizeof R->why, "frame has %d cascades, the config %d", b->cascade_count, want);
        return 1;
    }
    for (int k = 0; k < b->cascade_count; k++) {
        oc_of[k] = k < p->cascades ? ref : nf;
        c_of[k] = k < p->cascades ? k : 0;
    }
    for (int k = 0; k < b->cascade_count; k++) {
        double patch, klo, khi, kc[PROTO_MAX_MIPS];
        int mips = 0;
        ocean_cascade_band(oc_of[k], c_of[k], &patch, &klo, &khi);
        ocean_cascade_mips(oc_of[k], c_of[k], b->order, PROTO_MAX_MIPS, &mips, kc);
        int same = fabs(patch - b->cascade[k].patch_m) < 1e-9 * patch && b->cascade[k].n == p->n &&
                   mips == b->cascade[k].mips;
        for (int m = 0; same && m < mips; m++)
            same = isinf(kc[m]) ? isinf(b->cascade[k].mip[m].kc)
                                : fabs((float)kc[m] - b->cascade[k].mip[m].kc) <= 1e-6 * kc[m];
        if (!same) {
            snprintf(R->why, sizeof R->why, "cascade %d of the frame (patch %g, n %d, %d mips) is not the config's "
                     "(patch %g, n %d, %d mips)", k, b->cascade[k].patch_m, b->cascade[k].n, b->cascade[k].mips,
                     patch, p->n, mips);
            return 1;
        }
    }
    return 0;
}

/* Per point of the grid: 0 above the horizon, 1 outside the tiles, 2
 * measured, 3 measured with the vertex rule too; res[32] each:
 * reconstruction (5), exact carried (5), exact full (5), claimed mss,
 * vertex rule's reconstruction (3) and carried (3), its spacing. */
enum { AV_RES = 32 };

/* Reads frame `keep` at ray ij of the grid (camera cam at the block's
 * position) and the exact waves C there; st/o as above. */
static void av_point(const oc_frame *keep, const proto_camera *cam, const av_casc *C, int gw, int gh, int ij,
                     unsigned char *st, double *o)
{
    const proto_cascade_block *b = &keep->info.cascades;
    const double *cp = b->camera;
    double yaw = cam->yaw_deg * M_PI / 180, pitch = cam->pitch_deg * M_PI / 180;
    double fw[3] = {cos(pitch) * cos(yaw), sin(pitch), cos(pitch) * sin(yaw)};
    double rt[3] = {-sin(yaw), 0, cos(yaw)};
    double up[3] = {rt[1] * fw[2] - rt[2] * fw[1], rt[2] * fw[0] - rt[0] * fw[2], rt[0] * fw[1] - rt[1] * fw[0]};
    double ty = tan(cam->fov_y_deg * M_PI / 360), aspect = (double)cam->viewport_w / cam->viewport_h;
    int i = ij / gw, j = ij % gw;
    double sx = ((j + 0.5) / gw * 2 - 1) * ty * aspect, sy = (1 - (i + 0.5) / gh * 2) * ty, d[3];
    for (int k = 0; k < 3; k++)
        d[k] = fw[k] + sx * rt[k] + sy * up[k];
    *st = 0;
    if (!(d[1] < -1e-9))
        return;
    double tt = -cp[1] / d[1], x = cp[0] + tt * d[0], z = cp[2] + tt * d[2];
    oc_sample s;
    oc_lod L;
    *st = 1;
    if (oc_frame_sample_interp(keep, x, z, 0, OC_INTERP_CUBIC, &s) != OCEAN_OK ||
        oc_cascade_lod(b, x, z, 0, &L) != OCEAN_OK)
        return;
    double full[5], car[5];
    av_exact(C, b->cascade_count, &L, x, z, full, car);
    /* height and displacement are read at max(s, G) (PROTOCOL.md: the
     * mips finer than the mesh carry normals alone) */
    oc_lod Lg;
    if (b->geometry_spacing_m > 0 && oc_cascade_lod(b, x, z, b->geometry_spacing_m, &Lg) == OCEAN_OK) {
        double fg[5], cg[5];
        av_exact(C, b->cascade_count, &Lg, x, z, fg, cg);
        for (int k = 0; k < 3; k++)
            car[k] = cg[k];
    }
    double rec[5] = {s.height, s.dx, s.dz, s.slope_x, s.slope_z};
    for (int k = 0; k < 5; k++) {
        o[k] = rec[k];
        o[5 + k] = car[k];
        o[10 + k] = full[k];
    }
    o[15] = s.mss[0] + s.mss[1];
    *st = 2;
    /* the mesh's rings (MESH_TOPOLOGY zones): a vertex of level L reads
     * with spacing max(s, g_L); a point at horizontal distance d from the
     * camera lies in the first level whose zone radius R_L reaches d */
    const oc_topology *topo = keep->topology;
    int nlev = topo && (topo->flags & PROTO_TOPO_FLAT) && topo->zones ? topo->lod_levels : 0;
    if (nlev <= 0)
        return;
    double dist = hypot(x - cp[0], z - cp[2]), g = topo->zones[4 * (nlev - 1)];
    int level = nlev - 1;
    for (int lv = 0; lv < nlev; lv++)
        if (dist <= topo->zones[4 * lv + 1]) {
            g = topo->zones[4 * lv];
            level = lv;
            break;
        }
    oc_sample sv;
    oc_lod Lv;
    if (oc_frame_sample_interp(keep, x, z, g, OC_INTERP_CUBIC, &sv) == OCEAN_OK &&
        oc_cascade_lod(b, x, z, g, &Lv) == OCEAN_OK) {
        double fv[5], cv[5];
        av_exact(C, b->cascade_count, &Lv, x, z, fv, cv);
        double rv[3] = {sv.height, sv.dx, sv.dz};
        for (int k = 0; k < 3; k++) {
            o[16 + k] = rv[k];
            o[19 + k] = cv[k];
        }
        o[22] = g;
        o[23] = level;
        o[24] = dist;
        *st = 3;
    }
}

/* Adds the points of one frame (st, res) to R's sums. */
static void av_add_points(av_row *R, const unsigned char *st, const double *res, int npx)
{
    for (int ij = 0; ij < npx; ij++) {
        if (st[ij] == 0) {
            R->above++;
            continue;
        }
        if (st[ij] == 1) {
            R->outside++;
            continue;
        }
        const double *o = res + (size_t)ij * AV_RES, *rec = o, *car = o + 5, *full = o + 10;
        if (st[ij] == 3) {
            const double *rv = o + 16, *cv = o + 19;
            R->v_points++;
            av_err_add(&R->v_carried, rv[0] - cv[0], hypot(rv[1] - cv[1], rv[2] - cv[2]), 0.0);
            av_err_add(&R->v_geom, full[0] - cv[0], hypot(full[1] - cv[1], full[2] - cv[2]), 0.0);
            av_level_add(&R->lev[(int)o[23]], rv[0], full[0], o[24], o[22]);
        }
        R->points++;
        av_err_add(&R->carried, rec[0] - car[0], hypot(rec[1] - car[1], rec[2] - car[2]),
                   av_angle_deg(rec[3], rec[4], car[3], car[4]));
        av_err_add(&R->shading, full[0] - car[0], hypot(full[1] - car[1], full[2] - car[2]),
                   av_angle_deg(full[3], full[4], car[3], car[4]));
        av_err_add(&R->total, rec[0] - full[0], hypot(rec[1] - full[1], rec[2] - full[2]),
                   av_angle_deg(rec[3], rec[4], full[3], full[4]));
        double ex = full[3] - car[3], ez = full[4] - car[4];
        R->mss_left_meas += ex * ex + ez * ez;
        R->mss_left_claim += o[15] - R->mss_tail;
        R->mss_res_exact += full[3] * full[3] + full[4] * full[4];
    }
}

/* The errors of frame `keep` against the exact waves of its instant, its
 * block checked against the config, added to R.  0, or 1 with R->why. */
static int av_frame_errors(const oc_frame *keep, const proto_camera *cam, const ocean *ref, const ocean *nf,
                           int grid, av_row *R)
{
    if (!keep->view) {
        snprintf(R->why, sizeof R->why, "frame without a layout-1 view: %.150s", keep->view_error);
        return 1;
    }
    const proto_cascade_block *b = &keep->info.cascades;
    const ocean *oc_of[PROTO_MAX_LAYERS];
    int c_of[PROTO_MAX_LAYERS];
    if (av_block_oceans(b, ref, nf, oc_of, c_of, R))
        return 1;
    av_casc C[PROTO_MAX_LAYERS];
    for (int k = 0; k < b->cascade_count; k++)
        av_casc_build(&C[k], oc_of[k], c_of[k], k, keep->hdr.sim_time, b);
    R->mss_tail = (double)b->tail_mss[0] + b->tail_mss[1];
    const oc_topology *topo = keep->topology;
    int nlev = topo && (topo->flags & PROTO_TOPO_FLAT) && topo->zones ? topo->lod_levels : 0;
    R->has_mesh = nlev > 0;
    if (nlev > 0) {
        R->g0 = topo->zones[0];
        R->r0 = topo->zones[1];
        R->glast = topo->zones[4 * (nlev - 1)];
    }
    /* rays through a grid of pixel centres (PROTOCOL.md "Camera orientation") */
    int gw = grid, gh = grid * cam->viewport_h / cam->viewport_w, npx = gw * gh;
    double *res = xcalloc((size_t)npx * AV_RES, sizeof(double));
    unsigned char *st = xcalloc((size_t)npx, 1);
#pragma omp parallel for schedule(dynamic, 4)
    for (int ij = 0; ij < npx; ij++)
        av_point(keep, cam, C, gw, gh, ij, &st[ij], res + (size_t)ij * AV_RES);
    av_add_points(R, st, res, npx);
    R->err_frames++;
    free(res);
    free(st);
    for (int k = 0; k < b->cascade_count; k++)
        av_casc_free(&C[k]);
    return 0;
}

/* One row: its stream's cost over a window, then the errors of
 * AV_ERR_FRAMES of its frames against the exact waves (sums over all
 * their points). */
static void av_measure(const char *url, pid_t daemon, const ocean *ref, const ocean *nf, int grid, double window_s,
                       av_row *R)
{
    proto_camera cam;
    oc_frame *keep[AV_ERR_FRAMES];
    int kept = av_stream(url, daemon, window_s, R, &cam, keep);
    int bad = 0;
    for (int k = 0; k < kept; k++) {
        if (!bad)
            bad = av_frame_errors(keep[k], &cam, ref, nf, grid, R);
        oc_frame_free(keep[k]);
    }
    if (!kept || bad)
        return;
    /* per-point means; the point counts are over every frame measured */
    if (R->points > 0) {
        R->mss_left_meas /= R->points;
        R->mss_left_claim /= R->points;
        R->mss_res_exact /= R->points;
        R->ok = 1;
    } else {
        snprintf(R->why, sizeof R->why, "no ray landed on sea the frames cover");
    }
}

static void av_print_err(const char *what, const av_err *e, double hs)
{
    double n = e->n > 0 ? e->n : 1;
    printf(" %s | %.3g / %.3g | %.3g / %.3g | %.3g / %.3g | %.3g / %.3g |", what, sqrt(e->h2 / n),
           e->hmax, 100.0 * sqrt(e->h2 / n) / hs, 100.0 * e->hmax / hs, sqrt(e->d2 / n), e->dmax,
           sqrt(e->a2 / n), e->amax);
}

/* The section's heading, configuration and method. */
static void av_print_intro(const srv_settings *S, double hs, double chk, int grid, double window_s)
{
    const ocean_params *p = &S->params;
    printf("### What the browser viewer receives: layout-1 frames against the exact waves (issue 13)\n\n");
    printf("**Configuration** (what `make run` serves): `build/oceand --config %s` (port aside), scene %s "
           "(\"%s\"): %s %s, U10 %.3g m/s, choppiness %.3g, %d cascades of N = %d from a %.0f m patch, seed %llu; "
           "Hs of the spectrum %.3f m; server.px_per_sample %g, server.cascade_tile %d, "
           "server.viewer_bytes_per_s %.3g. **Subscription** (the browser viewer's, clients/web/worker.js "
           "chooseSubscription = oc_subscribe_default): layout 1, codec qz, policy antialias, 30 Hz, accuracy "
           "%g, concentric mesh, layers = HELLO.max_layers, every effect the scene offers; each camera twice: "
           "**time-interp** (SUBSCRIBE flag time_interp, the viewer's: each mip's samples travel once per its "
           "update interval and every frame is read from the blend of the two samples the client holds, "
           "PROTOCOL.md \"Samples in time\"; the library applies every frame on receipt) and **plain** (the flag "
           "clear: every frame whole, the viewer's subscription before it). **Cameras**: at (0, H, 0), heading 0, "
           "60 deg vertical fov, 1920 x 1080 viewport, pitch atan(H / 10 km) + 15 deg below the horizon; still, "
           "or flying at 60 m/s along the heading, reported 30 times a second.\n\n",
           CONF_PATH, S->scene.name[0] ? S->scene.name : "(none)", S->scene.description,
           ocean_spectrum_name(p->sea.spectrum), ocean_spreading_name(p->sea.spreading), p->sea.wind_u10,
           p->sea.choppiness, p->cascades, p->n, p->patch_m, (unsigned long long)p->seed, hs, S->srv.px_per_sample,
           S->srv.cascade_tile, S->srv.viewer_bytes_per_s, (double)OC_ACCURACY_DEFAULT);
    printf("**Method.** %d x %d pixel centres of the viewport cast onto the mean sea plane; at each point the "
           "frame is read as the viewer shades it: oc_frame_sample (the spec's lod rule with the pixel footprint, "
           "Keys cubic within a mip, cascades summed) at the parameter point. **Exact waves**: the same ocean "
           "built in-process from the same config (srv_settings_load; the frame's patches, grids and every "
           "mip's cutoff checked equal), every mode of every cascade summed directly in double at the frame's "
           "sim time (self-check against ocean_reference_point: max difference %.1e). *Carried* weights each mode "
           "by what the mips the lod rule reads there hold of it (their weights x Butterworth gain of the "
           "block's order, waves below ocean.drop_gain left out, fade included); *full* takes every mode. "
           "Columns: **carried error** = reconstruction - exact carried waves (codec, storage, cubic reading, "
           "and on the time-interp stream the blend between samples); "
           "**left to shading** = exact full - exact carried (what the frame hands to shading as unresolved "
           "slope variance; e_error is its height-variance fraction at the nadir); **total** = reconstruction - "
           "exact full. *Mesh vertex rule* rows read the same points as a vertex of the mesh ring there reads them "
           "(spacing max(s, g_L), g_L of the first MESH_TOPOLOGY zone whose radius reaches the point's distance; "
           "height and displacement only, the viewer's normals come from the shading read; the interpolation "
           "across a triangle between vertices is not included): what the geometry itself carries. "
           "Each as RMS / max over the points (per pixel, not per sea area) of height (m, and %% of "
           "Hs), horizontal displacement |(dx, dz)| (m) and normal angle (deg; normals from the parameter "
           "surface's slopes, as the tiles carry them). The Gerstner near field is the last cascade: its waves on "
           "their lattice, from the same lattice ocean the daemon builds; the short-wave tail beyond it is in no "
           "figure (tail_mss). Tiles vs f32 = the raw f32 bytes of the received tiles' planes over their qz "
           "payload bytes; normals only = tiles of mips finer than the viewer's mesh, which carry NU NV (and "
           "FOAM) alone (the block's geometry_spacing_m); tiles/frame counts the records a frame brought "
           "(time-interp: the samples due). Bytes/s = FRAME bytes received over %.0f s "
           "of frames made for the camera (after 1 s of settling); daemon cores = its CPU time over the same "
           "window with this one viewer connected. Errors over %d frames per row, spread over the window (the "
           "last at its end): a time-interpolating frame's error depends on where it falls between samples.\n\n",
           grid, grid * 1080 / 1920, chk, window_s, AV_ERR_FRAMES);
}

static double av_rms_h(const av_err *e, double hs) { return e->n > 0 ? 100.0 * sqrt(e->h2 / e->n) / hs : NAN; }
static double av_rms_a(const av_err *e) { return e->n > 0 ? sqrt(e->a2 / e->n) : NAN; }

/* Before and after the time_interp flag, camera by camera: cost and
 * error side by side (plain / time-interp).  1 if a row is missing. */
static int av_print_before_after(const av_row *rows, double hs)
{
    printf("**Before and after samples in time** (before: the plain stream, every tick's tiles, from a daemon "
           "whose server.viewer_bytes_per_s is %s as shipped before; after: the viewer's stream, samples in "
           "time, from the daemon as shipped; same camera; ratio = after over before):\n\n",
           AV_BEFORE_BYTES_PER_S);
    printf("| camera m | speed m/s | MB/s (ratio) | KiB/frame | q | e_error | height RMS %%Hs: carried | height RMS "
           "%%Hs: left to shading | height RMS %%Hs: total | normal RMS deg: carried | normal RMS deg: total | "
           "daemon cores |\n");
    printf("|---:|---:|---|---|---|---|---|---|---|---|---|---|\n");
    int bad = 0;
    for (int c = 0; c < AV_CAMS; c++) {
        const av_row *a = &rows[c * AV_STREAMS], *b = &rows[c * AV_STREAMS + 1];
        if (!a->ok || !b->ok) {
            printf("| %g | %g | not measured: %s | | | | | | | | | |\n", a->height, a->speed, !a->ok ? a->why : b->why);
            bad = 1;
            continue;
        }
        printf("| %g | %g | %.2f / %.2f (%.2f) | %.1f / %.1f | %.3g / %.3g | %.3f / %.3f | %.3g / %.3g | "
               "%.3g / %.3g | %.3g / %.3g | %.3g / %.3g | %.3g / %.3g | %.2f / %.2f |\n",
               a->height, a->speed, a->bytes_s / 1e6, b->bytes_s / 1e6, b->bytes_s / a->bytes_s, a->kib_frame,
               b->kib_frame, a->q, b->q, a->e_error, b->e_error, av_rms_h(&a->carried, hs), av_rms_h(&b->carried, hs),
               av_rms_h(&a->shading, hs), av_rms_h(&b->shading, hs), av_rms_h(&a->total, hs),
               av_rms_h(&b->total, hs), av_rms_a(&a->carried), av_rms_a(&b->carried), av_rms_a(&a->total),
               av_rms_a(&b->total), a->cores, b->cores);
    }
    printf("\n");
    return bad;
}

/* Every row's cost and plan.  1 if a row is missing. */
static int av_print_rows(const av_row *rows)
{
    printf("| camera m | speed m/s | stream | pitch deg | points (above horizon, outside tiles) | q | e_error | "
           "e_total | KiB/frame | tiles/frame (of which normals only) | tiles vs f32 | frames/s | MB/s | daemon "
           "cores |\n");
    printf("|---:|---:|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    int bad = 0;
    for (int i = 0; i < AV_CAMS * AV_STREAMS; i++) {
        const av_row *r = &rows[i];
        if (!r->frames_s) {
            printf("| %g | %g | %s | - | not measured: %s | | | | | | | | | |\n", r->height, r->speed,
                   av_stream_name[r->timed], r->why[0] ? r->why : "daemon did not start");
            bad = 1;
            continue;
        }
        printf("| %g | %g | %s | %.1f | %.0f (%.0f, %.0f) | %.3g | %.4f | %.4f | %.1f | %.0f (%.0f) | 1/%.2f | %.1f "
               "| %.2f | %.2f |\n",
               r->height, r->speed, av_stream_name[r->timed], r->pitch, r->points, r->above, r->outside, r->q,
               r->e_error, r->e_total, r->kib_frame, r->tiles_frame, r->normals_only, r->tile_ratio, r->frames_s,
               r->bytes_s / 1e6, r->cores);
    }
    return bad;
}

/* Every row's errors against the exact waves.  1 if a row is missing. */
/* Per mesh level (the rows' points by ring, read by the vertex rule):
 * the height spread its vertices keep of the exact sea's at the same
 * points (std ratio), their correlation, and the RMS difference. */
static void av_print_levels(const av_row *rows)
{
    printf("\nHeights a mesh level's vertices take (the vertex rule at the points in its ring) against every wave "
           "at the same points: *spread kept* = std(vertex) / std(exact), *corr* = their correlation.\n\n");
    printf("| camera m | speed m/s | stream | level | lattice g m | distance m | points | spread kept | corr | "
           "RMS difference m |\n|---:|---:|---|---:|---:|---|---:|---:|---:|---:|\n");
    for (int i = 0; i < AV_CAMS * AV_STREAMS; i++) {
        const av_row *r = &rows[i];
        for (int L = 0; r->ok && L < PROTO_MAX_LOD_LEVELS; L++) {
            const av_level *l = &r->lev[L];
            if (l->n < 8) continue; /* too few points to call a spread */
            double vm = l->m2 / l->n - (l->m / l->n) * (l->m / l->n);
            double ve = l->e2 / l->n - (l->e / l->n) * (l->e / l->n);
            double cov = l->me / l->n - (l->m / l->n) * (l->e / l->n);
            printf("| %g | %g | %s | %d | %g | %.0f-%.0f | %.0f | %.3f | %.3f | %.3g |\n", r->height, r->speed,
                   av_stream_name[r->timed], L, l->g, l->dmin, l->dmax, l->n, ve > 0 ? sqrt(fmax(vm, 0) / ve) : NAN,
                   vm > 0 && ve > 0 ? cov / sqrt(vm * ve) : NAN, sqrt(l->d2 / l->n));
        }
    }
}

static int av_print_errors(const av_row *rows, double hs)
{
    printf("\n| camera m | speed m/s | stream | error of | height RMS / max m | height RMS / max %%Hs | displacement RMS "
           "/ max m | normal RMS / max deg |\n");
    printf("|---:|---:|---|---|---:|---:|---:|---:|\n");
    int bad = 0;
    for (int i = 0; i < AV_CAMS * AV_STREAMS; i++) {
        const av_row *r = &rows[i];
        const char *sn = av_stream_name[r->timed];
        if (!r->ok) {
            printf("| %g | %g | %s | not measured: %s | | | | |\n", r->height, r->speed, sn, r->why);
            bad = 1;
            continue;
        }
        const char *what[3] = {"the waves the frame carries", "the waves left to shading", "total (against every wave)"};
        const av_err *e[3] = {&r->carried, &r->shading, &r->total};
        for (int k = 0; k < 3; k++) {
            printf("| %g | %g | %s |", r->height, r->speed, sn);
            av_print_err(what[k], e[k], hs);
            printf("\n");
        }
        if (r->v_points > 0) {
            const av_err *v[2] = {&r->v_carried, &r->v_geom};
            const char *vw[2] = {"mesh vertex rule: the waves it carries", "mesh vertex rule: waves not in geometry"};
            for (int k = 0; k < 2; k++) {
                double n = v[k]->n;
                printf("| %g | %g | %s | %s | %.3g / %.3g | %.3g / %.3g | %.3g / %.3g | - |\n", r->height, r->speed,
                       sn, vw[k], sqrt(v[k]->h2 / n), v[k]->hmax, 100 * sqrt(v[k]->h2 / n) / hs,
                       100 * v[k]->hmax / hs, sqrt(v[k]->d2 / n), v[k]->dmax);
            }
        } else {
            printf("| %g | %g | %s | mesh vertex rule | no FLAT topology with the frame: not measured | | | |\n",
                   r->height, r->speed, sn);
        }
    }
    av_print_levels(rows);
    printf("\nMesh rings of the frames measured (MESH_TOPOLOGY zones):");
    for (int i = 0; i < AV_CAMS * AV_STREAMS; i += AV_STREAMS)
        if (rows[i].has_mesh)
            printf(" %g m, %g m/s: g_0 %g m within %.0f m, coarsest g %g m;", rows[i].height, rows[i].speed,
                   rows[i].g0, rows[i].r0, rows[i].glast);
    printf("\n");
    return bad;
}

/* The slope variance left to shading, measured and claimed. */
static void av_print_mss(const av_row *rows, int grid)
{
    printf("\n| camera m | speed m/s | stream | mean-square slope of every mode (exact) | left to shading: measured | "
           "left to shading: the frame's mip tables | tail_mss (the short-wave tail; not in the exact sum) |\n");
    printf("|---:|---:|---|---:|---:|---:|---:|\n");
    for (int i = 0; i < AV_CAMS * AV_STREAMS; i++) {
        const av_row *r = &rows[i];
        if (!r->ok)
            continue;
        printf("| %g | %g | %s | %.5f | %.5f | %.5f | %.5f |\n", r->height, r->speed, av_stream_name[r->timed],
               r->mss_res_exact, r->mss_left_meas, r->mss_left_claim, r->mss_tail);
    }
    printf("\nMean-square slope = <s_x^2 + s_z^2> over the points. *Measured* is the exact slope of the modes the "
           "frame leaves out at each point (full - carried); *mip tables* is what the frame says they hold "
           "(oc_sample mss minus tail_mss): the statistic shading adds, to compare with the measured one over "
           "%d x %d points of %d instants.\n\n", grid, grid * 1080 / 1920, AV_ERR_FRAMES);
}

/* The README's headline: what the viewer gets (its stream, time-interp),
 * with the plain stream's bytes beside. */
static void av_write_headline(const av_row *rows, const srv_settings *S, double hs)
{
    FILE *hf = fopen(OUT_DIR "/headline_viewer.md", "w");
    if (!hf)
        return;
    fprintf(hf, "What the browser viewer receives from `make run` (scene %s, Hs %.2f m; layout 1, the viewer's "
            "subscription with samples in time, 1920 x 1080; errors per pixel against the exact waves; one "
            "viewer; MB/s of the plain stream, every frame whole, beside):\n\n",
            S->scene.name[0] ? S->scene.name : "(none)", hs);
    fprintf(hf, "| camera m | speed m/s | MB/s (plain) | daemon cores | e_error | height RMS %%Hs: carried / left to "
                "shading | normal RMS deg: carried / left to shading | mss left to shading: measured / frame's "
                "tables |\n");
    fprintf(hf, "|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (int c = 0; c < AV_CAMS; c++) {
        const av_row *p = &rows[c * AV_STREAMS], *r = &rows[c * AV_STREAMS + 1];
        if (!r->ok) {
            fprintf(hf, "| %g | %g | not measured: %s | | | | | |\n", r->height, r->speed, r->why);
            continue;
        }
        fprintf(hf, "| %g | %g | %.2f (%.2f) | %.2f | %.3f | %.3g / %.3g | %.3g / %.3g | %.4f / %.4f |\n",
                r->height, r->speed, r->bytes_s / 1e6, p->ok ? p->bytes_s / 1e6 : NAN, r->cores, r->e_error,
                av_rms_h(&r->carried, hs), av_rms_h(&r->shading, hs), av_rms_a(&r->carried), av_rms_a(&r->shading),
                r->mss_left_meas, r->mss_left_claim);
    }
    fprintf(hf, "\n");
    fclose(hf);
}

/* The whole section: returns 0 when every camera was measured on both streams. */
/* One oceand as `make run` starts it (--config CONF_PATH, a free port),
 * for stream k: the plain one with the budget of before, the
 * time-interpolating one as shipped. */
typedef struct av_daemon {
    pid_t pid;
    int up;
    char url[64];
    char log[128];
} av_daemon;

static void av_daemon_start(av_daemon *d, int k)
{
    char exe[4096], od[4200];
    ssize_t el = readlink("/proc/self/exe", exe, sizeof exe - 1);
    exe[el > 0 ? el : 0] = 0;
    char *sl = strrchr(exe, '/');
    if (sl) *sl = 0;
    snprintf(od, sizeof od, "%s/../oceand", exe);
    int port = av_free_port();
    char portarg[16];
    snprintf(portarg, sizeof portarg, "%d", port);
    snprintf(d->url, sizeof d->url, "ws://127.0.0.1:%d/", port);
    snprintf(d->log, sizeof d->log, OUT_DIR "/bench_accuracy_oceand%s.log", k ? "" : "_before");
    d->up = 0;
    fflush(stdout);
    fflush(stderr);
    d->pid = fork();
    if (d->pid == 0) {
        /* only async-signal-safe calls between fork and exec: this process
         * has OpenMP and FFTW threads */
        int fd = open(d->log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd >= 0) {
            dup2(fd, 1);
            dup2(fd, 2);
            close(fd);
        }
        if (k)
            execl(od, "oceand", "--config", CONF_PATH, "--port", portarg, (char *)NULL);
        else
            execl(od, "oceand", "--config", CONF_PATH, "--port", portarg, "--set",
                  "server.viewer_bytes_per_s=" AV_BEFORE_BYTES_PER_S, (char *)NULL);
        _exit(127);
    }
    for (int i = 0; i < 100 && d->pid > 0 && !d->up; i++) {
        oc_options o;
        oc_options_default(&o);
        o.url = d->url;
        oc_client *c = NULL;
        if (oc_connect(&o, 1000, &c, NULL, 0) == OCEAN_OK) {
            d->up = 1;
            oc_client_destroy(c);
        } else {
            usleep(100000);
        }
    }
}

static void av_daemon_stop(av_daemon *d)
{
    if (d->pid > 0) {
        kill(d->pid, SIGTERM);
        waitpid(d->pid, NULL, 0);
    }
    d->pid = 0;
}

static int viewer_section(void)
{
    int q = bench_quick();
    double t_start = bench_now_ms();
    srv_settings S;
    char err[512] = "";
    if (srv_settings_load(CONF_PATH, NULL, 0, &S, err, sizeof err) != OCEAN_OK) {
        printf("### What the browser viewer receives (layout 1)\n\n_Not measured: %s did not load: %s._\n\n",
               CONF_PATH, err);
        return 1;
    }
    ocean *ref = NULL;
    if (ocean_create(&S.params, &ref, err, sizeof err) != OCEAN_OK) {
        printf("### What the browser viewer receives (layout 1)\n\n_Not measured: ocean_create: %s._\n\n", err);
        return 1;
    }
    ocean_spectrum_stats ss;
    ocean_get_spectrum_stats(ref, &ss);
    double hs = ss.hs;
    /* the near field as the daemon serves it in layout 1: its waves on
     * their lattice, one more cascade (srv_settings_near_field is the
     * daemon's own definition; k_lo = the finest cascade's edge) */
    ocean_gerstner *g = NULL;
    ocean *nf = NULL;
    {
        ocean_gerstner_params gp;
        if (srv_settings_near_field(&S, &S.params, &gp)) {
            double patch, klo, khi;
            ocean_cascade_band(ref, S.params.cascades - 1, &patch, &klo, &khi);
            gp.k_lo = khi;
            if (ocean_gerstner_create(&gp, &g, err, sizeof err) != OCEAN_OK ||
                ocean_gerstner_cascade_create(g, &S.params, &nf, err, sizeof err) != OCEAN_OK) {
                printf("### What the browser viewer receives (layout 1)\n\n_Not measured: the near field: %s._\n\n",
                       err);
                ocean_gerstner_destroy(g);
                ocean_destroy(ref);
                return 1;
            }
        }
    }

    /* the exact sum's self-check against ocean_reference_point (every mode
     * of every cascade, unfiltered) at a few points */
    double chk = 0.0;
    {
        proto_cascade_block b0;
        memset(&b0, 0, sizeof b0);
        b0.cascade_count = (uint8_t)S.params.cascades;
        b0.order = 6;
        av_casc C[PROTO_MAX_LAYERS];
        oc_lod L;
        memset(&L, 0, sizeof L);
        for (int k = 0; k < S.params.cascades; k++) {
            av_casc_build(&C[k], ref, k, k, 1234.5, &b0);
            L.c[k].mip[0] = L.c[k].mip[1] = -1;
        }
        for (int i = 0; i < 3; i++) {
            double x = 37.1 + 913.7 * i, z = -211.9 + 377.3 * i, full[5], car[5];
            av_exact(C, S.params.cascades, &L, x, z, full, car);
            ocean_point pt;
            ocean_reference_point(ref, 1234.5, x, z, INFINITY, 6, &pt);
            double d = fmax(fabs(full[0] - pt.height), fmax(fabs(full[1] - pt.dx), fabs(full[2] - pt.dz)));
            d = fmax(d, fmax(fabs(full[3] - pt.slope_x), fabs(full[4] - pt.slope_z)));
            if (d > chk)
                chk = d;
        }
        for (int k = 0; k < S.params.cascades; k++)
            av_casc_free(&C[k]);
    }

    /* row = camera * AV_STREAMS + stream */
    static av_row rows_v[AV_CAMS * AV_STREAMS];
    memset(rows_v, 0, sizeof rows_v);
    av_daemon D[AV_STREAMS];
    for (int k = 0; k < AV_STREAMS; k++) av_daemon_start(&D[k], k);
    for (int r = 0; r < AV_CAMS * AV_STREAMS; r++) {
        rows_v[r].height = av_cams[r / AV_STREAMS].height;
        rows_v[r].speed = av_cams[r / AV_STREAMS].speed;
        rows_v[r].timed = r % AV_STREAMS;
        snprintf(rows_v[r].why, sizeof rows_v[r].why, "the daemon did not start (see %s)", D[r % AV_STREAMS].log);
    }
    int grid = q ? 32 : 64;
    double window_s = q ? 2.0 : 4.0;
    for (int r = 0; r < AV_CAMS * AV_STREAMS; r++) {
        av_row *R = &rows_v[r];
        const av_daemon *d = &D[R->timed];
        if (!d->up) continue;
        R->why[0] = 0;
        av_measure(d->url, d->pid, ref, nf, grid, window_s, R);
        fprintf(stderr, "bench_accuracy: viewer at %g m, %g m/s, %s stream: %s\n", R->height, R->speed,
                av_stream_name[R->timed], R->ok ? "measured" : R->why);
    }
    for (int k = 0; k < AV_STREAMS; k++) av_daemon_stop(&D[k]);
    av_print_intro(&S, hs, chk, grid, window_s);
    int bad = av_print_before_after(rows_v, hs);
    bad |= av_print_rows(rows_v);
    bad |= av_print_errors(rows_v, hs);
    av_print_mss(rows_v, grid);
    av_write_headline(rows_v, &S, hs);
    fprintf(stderr, "bench_accuracy: viewer section in %.1f s\n", (bench_now_ms() - t_start) / 1e3);
    ocean_destroy(nf);
    ocean_gerstner_destroy(g);
    ocean_destroy(ref);
    return bad;
}
