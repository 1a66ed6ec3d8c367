/*
 * cmd_fidelity.c - `ocean-client fidelity`: what the sea delivers to a
 * camera, measured from the frames it receives.
 *
 * A camera at height H flies along +x at speed V (or holds still), looking
 * down at --pitch (by default atan(H / range) + fov/4 below the horizon:
 * from 2 m the view reaches the horizon and sees enough sea for slope and
 * whitecap statistics, from 10 km half of it still lands within range),
 * subscribed as the client library does by default (layout 1, the browser
 * viewer's subscription, samples in time included: each
 * frame is read from the samples its connection holds, every frame
 * applied in order by the library on receipt; --time-interp off reads the
 * plain stream, and the report says which).  From each frame made for that
 * camera, a grid of the viewport's pixels is cast onto the mean sea plane
 * (y = 0) and the sea is read where each ray lands, through the spec's lod
 * rule at that point (oc_frame_sample: the pixel footprint decides the
 * mips).  Means are taken per area of sea in view (each pixel weighted by
 * the sea area it covers: whitecap coverage and slope statistics are area
 * statistics, and a pixel-weighted mean from a low camera is a few metres
 * of sea); per-pixel means are reported beside them:
 *   - resolved mean-square slope: <s_x^2 + s_z^2> of the slopes the tiles'
 *     normals give there (summed over cascades);
 *   - unresolved mean-square slope: <mss_x + mss_z> of the moments the
 *     frame carries for what those mips leave out (mip tables) and what no
 *     cascade holds (tail_mss);
 *   - total = resolved + unresolved: the slope variance a renderer that
 *     shades with both draws; per component (x, z and the xz cross moment,
 *     JSON mss_total_x / _z / _xz) it is the slope covariance that shapes
 *     sun glitter and sky reflection (tests/test_fidelity.sh checks that
 *     high cameras get the covariance a low one gets).  Compared with Cox &
 *     Munk (1954), clean sea: sigma^2 = 0.003 + 5.12e-3 U (U in m/s at
 *     12.5 m), U from the scene's U10 by the neutral logarithmic profile
 *     U(z) = (u_* / kappa) ln(z/z0): U12.5 = U10 + (u_* / kappa)
 *     ln(12.5/10), kappa = 0.4, u_* = sqrt(C_D) U10 with Wu's (1982, JGR
 *     87(C12) 9704) C_D = (0.8 + 0.065 U10) 1e-3;
 *   - foam: the whitecap coverage the frames carry (area_foam: the mean
 *     foam the library reads, by the spec's rule, on a square grid of
 *     points around the camera's nadir, a square wide enough to hold many
 *     whitecaps where the sea in view of a low camera holds few; each
 *     sample is a coverage fraction of the sea it stands for, and a mean of
 *     coverages survives the mip filtering that a threshold would not),
 *     compared with Monahan & O'Muircheartaigh (1980), W = 3.84e-6
 *     U10^3.41; the mean foam over the sampled sea and the fraction of
 *     samples with foam >= 0.5 are reported beside it;
 *   - e_error (FRAME) and e_total (cascade block), averaged over frames.
 * Rays above the horizon, or whose point the frame's tiles do not cover,
 * are counted and left out.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cJSON.h>

#include "occli.h"

/* Cox & Munk 1954 reference for U10 (see the top). */
static double u125_from_u10(double u10)
{
    double cd = (0.8 + 0.065 * u10) * 1e-3;
    return u10 + sqrt(cd) * u10 / 0.4 * log(12.5 / 10.0);
}

static double cox_munk_mss(double u10)
{
    return 0.003 + 5.12e-3 * u125_from_u10(u10);
}

static double monahan_whitecap(double u10)
{
    return 3.84e-6 * pow(u10, 3.41);
}

/* Sums over the samples, each weighted (w = 1: per pixel; w = the sea
 * area the pixel covers: per square metre of sea in view). */
typedef struct fid_sums {
    double w, res_x, res_z, res_xz, unres_x, unres_z, unres_xz, foam, foam_half, claimed;
} fid_sums;

typedef struct fid_acc {
    fid_sums px, area;
    double area_foam, area_points;   /* area_foam's sum and its points */
    double e_error, e_total, e_total_max;
    uint64_t samples, above, outside, frames, stale;
    uint64_t rx_frames, rx_bytes;    /* every frame made for the camera */
} fid_acc;

static void sums_add(fid_sums *S, double w, const oc_sample *s, double whole)
{
    S->w += w;
    S->res_x += w * s->slope_x * s->slope_x;
    S->res_z += w * s->slope_z * s->slope_z;
    S->res_xz += w * s->slope_x * s->slope_z;
    S->unres_x += w * s->mss[0];
    S->unres_z += w * s->mss[1];
    S->unres_xz += w * s->mss[2];
    S->foam += w * s->foam;
    S->foam_half += w * (s->foam >= 0.5);
    S->claimed += w * whole;
}

/* The whitecap coverage the frame carries: the mean foam a reader gets
 * (oc_frame_sample, the spec's rule at each point) on a 96 x 96 grid over
 * a square of side max(2 |y|, 1200 m) centred under the camera.  From a
 * low camera the sea in view is a few square metres - far too few
 * whitecaps for an area statistic; the square holds thousands, read near
 * and far as the viewer reads them (every cascade at the nadir, the coarse
 * ones only at its edges).  A 400 m square held few enough of the dominant
 * waves' groups that its coverage swung by 30 % between two instants.
 * Points the frame's tiles do not cover are left out. */
static void area_foam(const oc_frame *f, fid_acc *A)
{
    if (f->info.layout != PROTO_LAYOUT_CASCADE) return;
    const double *c = f->info.cascades.camera;
    double side = fmax(2 * fabs(c[1]), 1200.0);
    for (int i = 0; i < 96; i++)
        for (int j = 0; j < 96; j++) {
            oc_sample s;
            if (oc_frame_sample(f, c[0] + side * ((j + 0.5) / 96 - 0.5), c[2] + side * ((i + 0.5) / 96 - 0.5), 0,
                                &s) != OCEAN_OK || !(s.channels & PROTO_CH_BREAKING))
                continue;
            A->area_foam += s.foam;
            A->area_points += 1;
        }
}

/* Casts grid x grid*9/16 rays of camera `cam` (position from the frame's
 * block) and reads the frame where they land. */
static void measure_frame(const oc_frame *f, const proto_camera *cam, int grid, int verbose, oc_interp interp,
                          fid_acc *A)
{
    const double *cp = f->info.cascades.camera;
    double yaw = cam->yaw_deg * M_PI / 180, pitch = cam->pitch_deg * M_PI / 180;
    /* PROTOCOL.md "Camera orientation": forward (cos p cos y, sin p, cos p sin y); no roll */
    double fw[3] = {cos(pitch) * cos(yaw), sin(pitch), cos(pitch) * sin(yaw)};
    double rt[3] = {-sin(yaw), 0, cos(yaw)};     /* forward x up, horizontal */
    double up[3] = {rt[1] * fw[2] - rt[2] * fw[1], rt[2] * fw[0] - rt[0] * fw[2], rt[0] * fw[1] - rt[1] * fw[0]};
    double ty = tan(cam->fov_y_deg * M_PI / 360);
    double aspect = (double)cam->viewport_w / cam->viewport_h;
    /* what the frame says the whole sea holds: every cascade's entry
     * `mips` (its whole moments) plus the tail no cascade holds */
    const proto_cascade_block *b = &f->info.cascades;
    double whole = (double)b->tail_mss[0] + b->tail_mss[1];
    for (int c = 0; c < b->cascade_count; c++)
        whole += (double)b->cascade[c].mip[b->cascade[c].mips].mss_x + b->cascade[c].mip[b->cascade[c].mips].mss_z;
    int gw = grid, gh = grid * cam->viewport_h / cam->viewport_w;
    if (gh < 2)
        gh = 2;
    for (int i = 0; i < gh; i++)
        for (int j = 0; j < gw; j++) {
            /* pixel centres in normalised device coordinates */
            double sx = ((j + 0.5) / gw * 2 - 1) * ty * aspect, sy = (1 - (i + 0.5) / gh * 2) * ty;
            double d[3];
            for (int k = 0; k < 3; k++)
                d[k] = fw[k] + sx * rt[k] + sy * up[k];
            if (!(d[1] < -1e-9) || cp[1] <= 0) {
                A->above++;
                continue;
            }
            double t = -cp[1] / d[1];
            double x = cp[0] + t * d[0], z = cp[2] + t * d[2];
            oc_sample s;
            if (oc_frame_sample_interp(f, x, z, 0, interp, &s) != OCEAN_OK) {
                A->outside++;
                continue;
            }
            /* a pixel at image-plane point d (unnormalised, forward = 1)
             * spans a solid angle ~ 1/|d|^3 and lands on sea at distance
             * t|d| with incidence cosine |d_y|/|d|: its sea area is
             * ~ t^2 / |d_y| = cy^2 / |d_y|^3 */
            double ay = fabs(d[1]);
            sums_add(&A->px, 1.0, &s, whole);
            sums_add(&A->area, 1.0 / (ay * ay * ay), &s, whole);
            A->samples++;
        }
    if (verbose) {
        oc_lod L;
        oc_cascade_lod(&f->info.cascades, cp[0], cp[2], 0, &L);
        fprintf(stderr, "frame tick %u: %u tiles, q %g, min spacing %g, camera (%g, %g, %g), e_error %g, s %g:",
                f->info.tick, f->info.tile_count, (double)f->info.cascades.spacing_per_m,
                (double)f->info.cascades.min_spacing_m, cp[0], cp[1], cp[2], f->info.e_error, L.s);
        for (int c = 0; c < L.count; c++)
            fprintf(stderr, " c%d lambda %.2f", c, L.c[c].lambda);
        fprintf(stderr, "\n");
    }
    A->e_error += f->info.e_error;
    A->e_total += f->info.cascades.e_total;
    if (f->info.cascades.e_total > A->e_total_max)
        A->e_total_max = f->info.cascades.e_total;
    A->frames++;
}

/* What the command was asked, and the subscription and camera made of it. */
typedef struct fid_cfg {
    double height, speed, pitch, yaw, fov, spacing, range, settle, interval;
    int frames, json, verbose, grid, timeout_ms, vw, vh;
    int settle_frames;        /* -1: the default for the stream */
    int time_interp;          /* index in occli_off_on */
    const char *codec, *interp_name, *url;
    oc_interp interp;
    proto_subscribe sub;
    proto_camera cam;
} fid_cfg;

/* Parses the options into *F (defaults first): 0 go on, 1 help printed, 2
 * refused (said). */
static int fid_parse(int argc, char **argv, fid_cfg *F)
{
    const occli_opt opts[] = {
        {.name = "camera-height", .kind = OCCLI_DOUBLE, .target = &F->height, .min = 0.1, .max = 1e5,
         .help = "M  camera height above the mean sea level"},
        {.name = "speed", .kind = OCCLI_DOUBLE, .target = &F->speed, .min = 0, .max = 1e4,
         .help = "M/S  camera speed along its heading (0: hold still)"},
        {.name = "frames", .kind = OCCLI_INT, .target = &F->frames, .min = 1, .max = 100000,
         .help = "N  frames made for the camera to measure"},
        {.name = "json", .kind = OCCLI_FLAG, .target = &F->json,
         .help = "print the result as one JSON object (the metric lines go to stderr)"},
        {.name = "verbose", .kind = OCCLI_FLAG, .target = &F->verbose,
         .help = "one line per measured frame on stderr: tiles, q, e_error, the levels at the nadir"},
        {.name = "pitch", .kind = OCCLI_DOUBLE, .target = &F->pitch, .min = -90, .max = 1000,
         .help = "DEG  camera pitch (negative looks down); 1000 = auto: the view's centre\n"
                 "                       atan(H / range) + fov/4 below the horizon, so that from any height\n"
                 "                       half the view or more lands on sea within the range"},
        {.name = "yaw", .kind = OCCLI_DOUBLE, .target = &F->yaw, .min = -360, .max = 360,
         .help = "DEG  camera heading (0 = +x); the camera flies along it"},
        {.name = "fov", .kind = OCCLI_DOUBLE, .target = &F->fov, .min = 1, .max = 170,
         .help = "DEG  vertical field of view"},
        {.name = "viewport-width", .kind = OCCLI_INT, .target = &F->vw, .min = 1, .max = 16384,
         .help = "PX  viewport width"},
        {.name = "viewport-height", .kind = OCCLI_INT, .target = &F->vh, .min = 1, .max = 16384,
         .help = "PX  viewport height"},
        {.name = "grid", .kind = OCCLI_INT, .target = &F->grid, .min = 4, .max = 1024,
         .help = "N  rays across the viewport (N x N*height/width in all)"},
        {.name = "spacing", .kind = OCCLI_DOUBLE, .target = &F->spacing, .min = 0, .max = 1e4,
         .help = "M  finest spacing asked (SUBSCRIBE.base_spacing_m; 0 = server default)"},
        {.name = "range", .kind = OCCLI_DOUBLE, .target = &F->range, .min = 0, .max = 1e7,
         .help = "M  view range asked (0 = server default)"},
        {.name = "interp", .kind = OCCLI_STRING, .target = &F->interp_name,
         .help = "NAME  reading within a mip: cubic (Keys), linear, lanczos3"},
        {.name = "codec", .kind = OCCLI_STRING, .target = &F->codec,
         .help = "NAME  tile codec: f32 f16 qz exr-zip exr-piz exr-b44 exr-b44a"},
        {.name = "time-interp", .kind = OCCLI_CHOICE, .target = &F->time_interp, .names = occli_off_on,
         .help = "MODE  samples in time (the viewer's stream): each frame read from the\n"
                 "                       blend of two samples the connection holds, every frame\n"
                 "                       applied in order; off: the plain stream, each frame whole"},
        {.name = "settle", .kind = OCCLI_DOUBLE, .target = &F->settle, .min = 0, .max = 60,
         .help = "S  wait after the first frame made for the camera before measuring (default 0.3;\n"
                 "                       1 with --time-interp on: what the client lacks at first comes over\n"
                 "                       several frames, each at most 4 frames' byte budgets)"},
        {.name = "settle-frames", .kind = OCCLI_INT, .target = &F->settle_frames, .min = 0, .max = 100000,
         .help = "N  frames made for the camera passed over before measuring, besides --settle (default 0;\n"
                 "                       8 with --time-interp on: on a loaded host a second brings a few\n"
                 "                       frames, and it is frames, not seconds, that fill what the client\n"
                 "                       lacks)"},
        {.name = "interval", .kind = OCCLI_DOUBLE, .target = &F->interval, .min = 0, .max = 3600,
         .help = "S  measure one frame per S seconds (0: consecutive frames); a longer span samples more "
                 "sea\n                       (a moving camera) and more wave periods"},
        {.name = "timeout", .kind = OCCLI_INT, .target = &F->timeout_ms, .min = 1, .max = 3600000,
         .help = "MS  connect / frame timeout"},
    };
    const char *pos[1];
    int np = 0;
    int pr = occli_parse(argc, argv,
                         "usage: ocean-client fidelity URL --camera-height H --speed V [--frames N] [--json] [options]\n"
                         "Flies (or holds) a camera at height H and speed V, subscribed as the client library does\n"
                         "(layout 1, samples in time: --time-interp), and measures from the frames it receives\n"
                         "what the sea delivers where the\n"
                         "viewport's pixels land: mean-square slope resolved by the tiles plus the unresolved\n"
                         "moments the frame carries (against Cox & Munk 1954), foam coverage (against Monahan &\n"
                         "O'Muircheartaigh 1980), e_error and e_total.",
                         opts, (int)(sizeof opts / sizeof opts[0]), pos, 1, &np);
    if (pr)
        return pr;
    if (np != 1) {
        fprintf(stderr, "ocean-client fidelity: needs the server URL (see --help)\n");
        return 2;
    }
    F->url = pos[0];
    return 0;
}

static int fid_interp_parse(const char *name, oc_interp *out)
{
    static const struct { const char *name; oc_interp interp; } names[] = {
        {"cubic", OC_INTERP_CUBIC}, {"linear", OC_INTERP_LINEAR}, {"lanczos3", OC_INTERP_LANCZOS3}};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (!strcmp(name, names[i].name)) {
            *out = names[i].interp;
            return 0;
        }
    fprintf(stderr, "ocean-client fidelity: option '--interp': unknown '%s' (cubic linear lanczos3)\n", name);
    return 2;
}

/* Checks the parsed options and makes the subscription and the camera of
 * them: 0, or 2 with the refusal said. */
static int fid_setup(fid_cfg *F)
{
    if (fid_interp_parse(F->interp_name, &F->interp))
        return 2;
    if (F->time_interp == 1)
        F->sub.flags |= PROTO_SUB_TIME_INTERP;
    else
        F->sub.flags &= (uint8_t)~PROTO_SUB_TIME_INTERP;
    if (isnan(F->settle))
        F->settle = F->time_interp == 1 ? 1.0 : 0.3;
    if (F->settle_frames < 0)
        F->settle_frames = F->time_interp == 1 ? 8 : 0;
    proto_codec pc;
    if (proto_codec_parse(F->codec, &pc) != OCEAN_OK) {
        fprintf(stderr, "ocean-client fidelity: option '--codec': unknown codec '%s'\n", F->codec);
        return 2;
    }
    F->sub.codec = (uint8_t)pc;
    F->sub.base_spacing_m = (float)F->spacing;
    F->sub.view_range_m = (float)F->range;
    if (F->spacing > 0 && F->spacing < 0.001) {
        fprintf(stderr, "ocean-client fidelity: option '--spacing': %g below the protocol's 0.001 m\n", F->spacing);
        return 2;
    }
    if (F->range > 0 && F->range < 1) {
        fprintf(stderr, "ocean-client fidelity: option '--range': %g below the protocol's 1 m\n", F->range);
        return 2;
    }
    if (F->pitch > 90) {
        double R = F->range > 0 ? F->range : 10000;   /* the daemon's shipped server.view_range */
        F->pitch = -(atan(F->height / R) * 180 / M_PI + F->fov / 4);
    }
    proto_camera *cam = &F->cam;
    oc_camera_default(cam);
    cam->pos[1] = F->height;
    cam->yaw_deg = (float)F->yaw;
    cam->pitch_deg = (float)F->pitch;
    cam->fov_y_deg = (float)F->fov;
    cam->viewport_w = (uint16_t)F->vw;
    cam->viewport_h = (uint16_t)F->vh;
    cam->vel[0] = (float)(F->speed * cos(F->yaw * M_PI / 180));
    cam->vel[2] = (float)(F->speed * sin(F->yaw * M_PI / 180));
    return 0;
}

/* One measuring run over a connection: the camera flown, the frames
 * taken or passed over, and why the run stopped early. */
typedef struct fid_run {
    const fid_cfg *F;
    oc_client *c;
    proto_camera cam;
    fid_acc A;
    uint32_t first_seq;
    double t0, last_cam, settled_at, last_measured;
    int seen;                 /* frames made for the camera, with a view */
    uint64_t layout0, noview;
    char why[256];
} fid_run;

/* Reports the camera where it is now, 30 times a second. */
static void fid_fly(fid_run *R)
{
    const fid_cfg *F = R->F;
    double now = occli_mono();
    if (F->speed > 0 && now - R->last_cam >= 1.0 / 30) {
        R->cam.pos[0] = F->cam.pos[0] + F->speed * cos(F->yaw * M_PI / 180) * (now - R->t0);
        R->cam.pos[2] = F->cam.pos[2] + F->speed * sin(F->yaw * M_PI / 180) * (now - R->t0);
        oc_client_send_camera(R->c, &R->cam, NULL);
        R->last_cam = now;
    }
}

/* Measures frame f (freed here) or passes over it: only frames made for
 * this camera, of layout 1 with a view, after the settling time and at
 * the interval asked.  0 go on; 1 the run failed (R->why says why). */
static int fid_take(fid_run *R, oc_frame *f)
{
    const fid_cfg *F = R->F;
    fid_acc *A = &R->A;
    /* only frames made for this camera (seq at or after the first CAMERA) */
    if (f->info.camera_seq == PROTO_NO_CAMERA || (int32_t)(f->info.camera_seq - R->first_seq) < 0) {
        A->stale++;
        oc_frame_free(f);
        return 0;
    }
    A->rx_frames++;
    A->rx_bytes += f->raw_len;
    if (f->info.layout != PROTO_LAYOUT_CASCADE) {
        oc_frame_free(f);
        if (++R->layout0 < 5)
            return 0;
        snprintf(R->why, sizeof R->why, "the daemon sends layout-0 frames (it predates layout 1)");
        return 1;
    }
    if (!f->view) {
        snprintf(R->why, sizeof R->why, "layout-1 frame without a view: %s", f->view_error);
        oc_frame_free(f);
        return ++R->noview >= 5;
    }
    if (isnan(R->settled_at))
        R->settled_at = occli_mono();
    if (++R->seen <= F->settle_frames || occli_mono() - R->settled_at < F->settle) {
        A->stale++;
        oc_frame_free(f);
        return 0;
    }
    if (occli_mono() - R->last_measured >= F->interval) {
        R->last_measured = occli_mono();
        area_foam(f, A);
        measure_frame(f, &R->cam, F->grid, F->verbose, F->interp, A);
    }
    oc_frame_free(f);
    return 0;
}

/* Receives and measures frames until F->frames are measured: 0, or 1
 * with R->why said (or empty: interrupted). */
static int fid_receive(fid_run *R)
{
    const fid_cfg *F = R->F;
    while (!occli_stop && R->A.frames < (uint64_t)F->frames) {
        fid_fly(R);
        oc_frame *f = NULL;
        ocean_result r = oc_client_next_frame(R->c, F->speed > 0 ? 20 : F->timeout_ms, &f);
        if (r == OCEAN_ESTATE) {
            if (F->speed > 0 &&
                occli_mono() - R->t0 < F->timeout_ms * 1e-3 * (1 + R->A.frames) + F->interval * F->frames)
                continue;
            snprintf(R->why, sizeof R->why, "no frame within %d ms", F->timeout_ms);
            return 1;
        }
        if (r != OCEAN_OK) {
            oc_client_last_error(R->c, R->why, sizeof R->why);
            return 1;
        }
        if (fid_take(R, f))
            return 1;
    }
    return 0;
}

/* The figures the report prints, from the run's sums. */
typedef struct fid_figures {
    double res, unres, total, res_px, total_px, claimed, claimed_res;
    double u10, cm, foam, foam_half, W, foam_px, foam_tiles, mss_ratio, mss_ratio_px, foam_ratio;
    double bytes_per_frame;
    int foam_applies, foam_offered, mss_ok, foam_ok;
    const char *stream;
} fid_figures;

static void fid_figures_compute(const fid_cfg *F, const fid_acc *A, const proto_hello *hello,
                                const proto_sea *sea, fid_figures *G)
{
    /* the checked figures are per area of sea in view (coverage and slope
     * statistics are area statistics); per pixel beside them */
    const fid_sums *S = &A->area, *P = &A->px;
    G->res = (S->res_x + S->res_z) / S->w;
    G->unres = (S->unres_x + S->unres_z) / S->w;
    G->total = G->res + G->unres;
    G->res_px = (P->res_x + P->res_z) / P->w;
    G->total_px = G->res_px + (P->unres_x + P->unres_z) / P->w;
    G->claimed = S->claimed / S->w;
    G->claimed_res = G->claimed - G->unres;
    G->u10 = sea->wind_u10;
    G->cm = cox_munk_mss(G->u10);
    G->foam = S->foam / S->w;
    G->foam_half = S->foam_half / S->w;
    G->W = monahan_whitecap(G->u10);
    G->foam_px = P->foam / P->w;
    G->foam_tiles = A->area_points > 0 ? A->area_foam / A->area_points : NAN;
    G->foam_applies = G->u10 >= 8 && G->u10 <= 26;
    G->foam_offered = (hello->effects & PROTO_FX_FOAM) != 0;
    /* slopes: both means must hold (per pixel: what the screen shows, near
     * detail included; per area: the sea in view); foam: the coverage the
     * tiles carry (an area fraction needs an area: the sea in view from a
     * low camera is a few square metres, far too few whitecaps to count;
     * its mean is reported beside) */
    G->mss_ratio = G->total / G->cm;
    G->mss_ratio_px = G->total_px / G->cm;
    G->foam_ratio = G->W > 0 && isfinite(G->foam_tiles) ? G->foam_tiles / G->W : NAN;
    G->mss_ok = fabs(G->mss_ratio - 1) <= 0.3 && fabs(G->mss_ratio_px - 1) <= 0.3;
    G->foam_ok = !G->foam_applies || (G->foam_ratio >= 0.5 && G->foam_ratio <= 2);
    G->stream = F->time_interp == 1 ? "time-interpolating" : "plain";
    G->bytes_per_frame = A->rx_frames ? (double)A->rx_bytes / A->rx_frames : 0.0;
}

static void fid_print_lines(FILE *lines, const fid_cfg *F, const fid_acc *A, const fid_figures *G)
{
    const fid_sums *S = &A->area;
    fprintf(lines, "camera: height %g m, speed %g m/s, pitch %g deg; %llu frames, %llu samples (%llu rays above the "
            "horizon, %llu outside the tiles); sea U10 %.2f m/s\n",
            F->height, F->speed, F->pitch, (unsigned long long)A->frames, (unsigned long long)A->samples,
            (unsigned long long)A->above, (unsigned long long)A->outside, G->u10);
    fprintf(lines, "stream: %s (--time-interp %s); %.0f bytes a frame received over the run\n", G->stream,
            occli_off_on[F->time_interp == 1], G->bytes_per_frame);
    fprintf(lines, "(means per area of sea in view; per pixel in brackets where given)\n");
    fprintf(lines, "mss_resolved    %.5f  (x %.5f, z %.5f, xz %.5f; per pixel %.5f)\n", G->res, S->res_x / S->w,
            S->res_z / S->w, S->res_xz / S->w, G->res_px);
    fprintf(lines, "mss_res_claimed %.5f  (what the mip tables say the mips read hold; the measured value differs "
            "by the sampling of a finite patch)\n", G->claimed_res);
    fprintf(lines, "mss_unresolved  %.5f  (x %.5f, z %.5f, xz %.5f; mip tables + tail_mss)\n", G->unres,
            S->unres_x / S->w, S->unres_z / S->w, S->unres_xz / S->w);
    fprintf(lines, "mss_total x/z/xz %.5f %.5f %.5f  (resolved + unresolved: the slope covariance shading draws)\n",
            (S->res_x + S->unres_x) / S->w, (S->res_z + S->unres_z) / S->w, (S->res_xz + S->unres_xz) / S->w);
    fprintf(lines, "mss_sea_claimed %.5f  (the frame's whole sea: every cascade's moments + tail_mss)\n", G->claimed);
    fprintf(lines, "mss_total       %.5f  Cox-Munk %.5f (U12.5 %.2f m/s): ratio %.3f, per pixel %.5f ratio %.3f: %s\n",
            G->total, G->cm, u125_from_u10(G->u10), G->mss_ratio, G->total_px, G->mss_ratio_px,
            G->mss_ok ? "both within 30 %" : "OUTSIDE 30 %");
    fprintf(lines, "foam_coverage   %.5f  (tiles) Monahan-OMuircheartaigh %.5f: ratio %.3f %s%s (sea in view %.5f, "
            "per pixel %.5f)\n", G->foam_tiles, G->W, G->foam_ratio,
            !G->foam_applies ? "(U10 outside 8..26 m/s: not checked)"
            : G->foam_ok     ? "within a factor 2"
                             : "OUTSIDE a factor 2",
            G->foam_offered ? "" : " [the scene offers no foam]", G->foam, G->foam_px);
    fprintf(lines, "foam_ge_half    %.5f  (fraction of samples with foam >= 0.5)\n", G->foam_half);
    fprintf(lines, "foam_tiles      %.5f  (the foam read on a square under the camera: the coverage checked)\n",
            G->foam_tiles);
    fprintf(lines, "e_error         %.5f  (mean over frames)\n", A->e_error / A->frames);
    fprintf(lines, "e_total         %.5f  (mean over frames; max %.5f)\n", A->e_total / A->frames, A->e_total_max);
}

/* A number, or null where it is undefined. */
static void json_number_or_null(cJSON *o, const char *name, double v)
{
    if (isfinite(v))
        cJSON_AddNumberToObject(o, name, v);
    else
        cJSON_AddNullToObject(o, name);
}

/* The slope figures of the JSON object: resolved, unresolved and total,
 * per area of sea in view and per pixel, against Cox & Munk. */
static void fid_json_slopes(cJSON *o, const fid_acc *A, const fid_figures *G)
{
    const fid_sums *S = &A->area, *P = &A->px;
    cJSON_AddNumberToObject(o, "mss_resolved", G->res);
    cJSON_AddNumberToObject(o, "mss_resolved_x", S->res_x / S->w);
    cJSON_AddNumberToObject(o, "mss_resolved_z", S->res_z / S->w);
    cJSON_AddNumberToObject(o, "mss_resolved_xz", S->res_xz / S->w);
    cJSON_AddNumberToObject(o, "mss_unresolved_x", S->unres_x / S->w);
    cJSON_AddNumberToObject(o, "mss_unresolved_z", S->unres_z / S->w);
    cJSON_AddNumberToObject(o, "mss_unresolved_xz", S->unres_xz / S->w);
    /* the slope covariance a renderer that shades with both draws:
     * what sun glitter and sky reflection are made of */
    cJSON_AddNumberToObject(o, "mss_total_x", (S->res_x + S->unres_x) / S->w);
    cJSON_AddNumberToObject(o, "mss_total_z", (S->res_z + S->unres_z) / S->w);
    cJSON_AddNumberToObject(o, "mss_total_xz", (S->res_xz + S->unres_xz) / S->w);
    cJSON_AddNumberToObject(o, "mss_total_x_per_pixel", (P->res_x + P->unres_x) / P->w);
    cJSON_AddNumberToObject(o, "mss_total_z_per_pixel", (P->res_z + P->unres_z) / P->w);
    cJSON_AddNumberToObject(o, "mss_total_xz_per_pixel", (P->res_xz + P->unres_xz) / P->w);
    cJSON_AddNumberToObject(o, "mss_unresolved_per_pixel", (P->unres_x + P->unres_z) / P->w);
    cJSON_AddNumberToObject(o, "mss_resolved_per_pixel", G->res_px);
    cJSON_AddNumberToObject(o, "mss_total_per_pixel", G->total_px);
    cJSON_AddNumberToObject(o, "foam_mean_per_pixel", G->foam_px);
    cJSON_AddStringToObject(o, "weighting", "per area of sea in view (per pixel in *_per_pixel)");
    cJSON_AddNumberToObject(o, "mss_resolved_claimed", G->claimed_res);
    cJSON_AddNumberToObject(o, "mss_unresolved", G->unres);
    cJSON_AddNumberToObject(o, "mss_sea_claimed", G->claimed);
    cJSON_AddNumberToObject(o, "mss_total", G->total);
    cJSON_AddNumberToObject(o, "mss_cox_munk", G->cm);
    cJSON_AddNumberToObject(o, "mss_ratio", G->mss_ratio);
    cJSON_AddNumberToObject(o, "mss_ratio_per_pixel", G->mss_ratio_px);
    cJSON_AddBoolToObject(o, "mss_within_30pct", G->mss_ok);
}

static void fid_print_json(const fid_cfg *F, const fid_acc *A, const fid_figures *G)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "url", F->url);
    /* which stream was read, and what it cost */
    cJSON_AddStringToObject(o, "stream", G->stream);
    cJSON_AddBoolToObject(o, "time_interp", F->time_interp == 1);
    cJSON_AddNumberToObject(o, "bytes_per_frame", G->bytes_per_frame);
    cJSON_AddNumberToObject(o, "camera_height_m", F->height);
    cJSON_AddNumberToObject(o, "speed_m_s", F->speed);
    cJSON_AddNumberToObject(o, "pitch_deg", F->pitch);
    cJSON_AddNumberToObject(o, "frames", (double)A->frames);
    cJSON_AddNumberToObject(o, "samples", (double)A->samples);
    cJSON_AddNumberToObject(o, "rays_above_horizon", (double)A->above);
    cJSON_AddNumberToObject(o, "rays_outside_tiles", (double)A->outside);
    cJSON_AddNumberToObject(o, "u10", G->u10);
    cJSON_AddNumberToObject(o, "u12_5", u125_from_u10(G->u10));
    fid_json_slopes(o, A, G);
    cJSON_AddNumberToObject(o, "foam_mean", G->foam);
    cJSON_AddNumberToObject(o, "foam_fraction_ge_half", G->foam_half);
    json_number_or_null(o, "foam_tiles", G->foam_tiles);
    cJSON_AddStringToObject(o, "foam_coverage_is", "foam_tiles");
    cJSON_AddNumberToObject(o, "whitecap_monahan", G->W);
    json_number_or_null(o, "foam_ratio", G->foam_ratio);
    cJSON_AddBoolToObject(o, "foam_checked", G->foam_applies);
    cJSON_AddBoolToObject(o, "foam_within_factor_2", G->foam_ok);
    cJSON_AddBoolToObject(o, "foam_offered", G->foam_offered);
    cJSON_AddNumberToObject(o, "e_error", A->e_error / A->frames);
    cJSON_AddNumberToObject(o, "e_total", A->e_total / A->frames);
    cJSON_AddNumberToObject(o, "e_total_max", A->e_total_max);
    cJSON_AddStringToObject(o, "mss_reference",
                            "Cox & Munk 1954 clean sea 0.003 + 5.12e-3 U12.5; U12.5 = U10 + u*/0.4 ln(1.25), "
                            "u* = sqrt((0.8 + 0.065 U10) 1e-3) U10 (Wu 1982)");
    cJSON_AddStringToObject(o, "foam_reference", "Monahan & O'Muircheartaigh 1980: W = 3.84e-6 U10^3.41");
    occli_print_json(o);
}

/* Connects, subscribes and measures: 0 with R->A filled, or 1 (said). */
static int fid_measure(const fid_cfg *F, fid_run *R, proto_hello *hello, proto_sea *sea)
{
    R->c = occli_connect("fidelity", F->url, NULL, F->timeout_ms);
    if (!R->c)
        return 1;
    oc_client_hello(R->c, hello);
    oc_client_sea_state(R->c, sea, NULL);
    if (oc_client_subscribe(R->c, &F->sub) != OCEAN_OK ||
        oc_client_send_camera(R->c, &R->cam, &R->first_seq) != OCEAN_OK) {
        char err[512];
        oc_client_last_error(R->c, err, sizeof err);
        fprintf(stderr, "ocean-client fidelity: %s\n", err);
        oc_client_destroy(R->c);
        return 1;
    }
    R->t0 = R->last_cam = occli_mono();
    R->settled_at = NAN;
    R->last_measured = -INFINITY;
    int rc = fid_receive(R);
    oc_client_destroy(R->c);
    if (rc || R->A.samples == 0) {
        fprintf(stderr, "ocean-client fidelity: %s\n",
                R->why[0] ? R->why : R->A.frames ? "no ray landed on sea the frames cover" : "no frame measured");
        return 1;
    }
    return 0;
}

int cmd_fidelity(int argc, char **argv)
{
    fid_cfg F = {.height = 25, .pitch = 1000, .fov = 60, .settle = NAN, .settle_frames = -1, .frames = 10, .grid = 64,
                 .timeout_ms = 5000, .vw = 1920, .vh = 1080, .codec = "qz", .interp_name = "cubic"};
    oc_subscribe_default(&F.sub);
    /* the library's stream (the viewer's: samples in time) unless asked */
    F.time_interp = (F.sub.flags & PROTO_SUB_TIME_INTERP) != 0;
    int pr = fid_parse(argc, argv, &F);
    if (pr)
        return pr == 1 ? 0 : 2;
    if (fid_setup(&F))
        return 2;
    fid_run R;
    memset(&R, 0, sizeof R);
    R.F = &F;
    R.cam = F.cam;
    proto_hello hello;
    proto_sea sea;
    if (fid_measure(&F, &R, &hello, &sea))
        return 1;
    fid_figures G;
    fid_figures_compute(&F, &R.A, &hello, &sea, &G);
    fid_print_lines(F.json ? stderr : stdout, &F, &R.A, &G);
    if (F.json)
        fid_print_json(&F, &R.A, &G);
    return 0;
}
