/*
 * cmd_watch.c - `ocean-client watch`: subscribe and print per-frame
 * statistics (sim time, cutoff, E_error, bytes, latency); with --json a
 * final summary object instead.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cJSON.h>

#include "occli.h"

/* The server's first ERROR: a refused SUBSCRIBE, the cause; the refusals
 * of every CAMERA after it follow from it. */
static void keep_error(void *user, oc_client *c, const proto_error *e)
{
    (void)c;
    char *buf = user;
    if (!buf[0]) snprintf(buf, PROTO_ERROR_MSG_MAX + 32, "%s: %s", ocean_strerror((ocean_result)e->code), e->message);
}

/* What the command was asked. */
typedef struct watch_opts {
    double seconds;
    int max_frames, json;
    occli_sub s;
    const char *url;
} watch_opts;

/* Parses the options into *P (defaults first): 0 go on, 1 help printed, 2
 * refused (said). */
static int watch_parse(int argc, char **argv, watch_opts *P)
{
    const occli_opt opts[] = {
        {"seconds", OCCLI_DOUBLE, &P->seconds, 0.001, 1e7, "S  how long to watch", NULL},
        {"frames", OCCLI_INT, &P->max_frames, 0, 1e9, "N  stop after N frames (0: no limit)", NULL},
        {"json", OCCLI_FLAG, &P->json, 0, 0, "print only a JSON summary at the end", NULL},
        OCCLI_SUB_OPTS(&P->s),
    };
    const char *pos[1];
    int np = 0;
    int pr = occli_parse(argc, argv,
                         "usage: ocean-client watch URL [--seconds S] [--frames N] [--json] [subscription options]\n"
                         "Subscribes at the camera given and prints one line per frame: sim time, cutoff (rad/m),\n"
                         "E_error, tiles, bytes and the tick-to-receipt latency estimate.",
                         opts, (int)(sizeof opts / sizeof opts[0]), pos, 1, &np);
    if (pr)
        return pr;
    if (np != 1) {
        fprintf(stderr, "ocean-client watch: needs the server URL (see --help)\n");
        return 2;
    }
    P->url = pos[0];
    return 0;
}

/* What the frames received add up to. */
typedef struct watch_acc {
    occli_vec lat;
    uint64_t frames, bytes, tiles, bad_tiles, frames_layout[2];
    double e_sum, first_t, last_t, last_cut, first_rx, last_rx;
} watch_acc;

/* Counts frame f in, and prints its line unless the summary is JSON. */
static void watch_add(watch_acc *W, const oc_frame *f, int json)
{
    W->frames++;
    W->bytes += f->raw_len;
    W->tiles += f->info.tile_count;
    W->frames_layout[f->info.layout == PROTO_LAYOUT_CASCADE]++;
    for (unsigned i = 0; i < f->info.tile_count; i++)
        W->bad_tiles += f->tiles[i].decode_result != OCEAN_OK;
    W->e_sum += f->info.e_error;
    if (isnan(W->first_t))
        W->first_t = f->hdr.sim_time, W->first_rx = f->recv_wall;
    W->last_t = f->hdr.sim_time;
    W->last_rx = f->recv_wall;
    W->last_cut = f->info.cutoff_k;
    occli_vec_push(&W->lat, f->latency_ms);
    if (!json) {
        printf("frame %6llu  t=%10.4f  cutoff=%-9.4g E_error=%-9.3g tiles=%-3u mesh=%-6u bytes=%-8zu "
               "latency=%.2f ms\n",
               (unsigned long long)f->index, f->hdr.sim_time, f->info.cutoff_k, f->info.e_error,
               f->info.tile_count, f->info.has_mesh ? f->info.mesh.vertex_count : 0, f->raw_len,
               f->latency_ms);
        fflush(stdout);
    }
}

/* Receives frames until P->seconds pass or P->max_frames came, a moving
 * camera reporting itself 10 times a second: 0, or 1 (connection lost,
 * said). */
static int watch_receive(const watch_opts *P, oc_client *c, proto_camera *cam, double t0, watch_acc *W)
{
    double last_cam = t0, end = t0 + P->seconds;
    while (!occli_stop) {
        double now = occli_mono();
        if (now >= end || (P->max_frames && W->frames >= (uint64_t)P->max_frames))
            break;
        if ((cam->vel[0] != 0 || cam->vel[1] != 0 || cam->vel[2] != 0) && now - last_cam >= 0.1) {
            for (int i = 0; i < 3; i++)
                cam->pos[i] += cam->vel[i] * (now - last_cam);
            last_cam = now;
            oc_client_send_camera(c, cam, NULL);
        }
        double left = end - now;
        int wait_ms = (int)fmin(100.0, ceil(left * 1e3));
        oc_frame *f = NULL;
        ocean_result r = oc_client_next_frame(c, wait_ms < 1 ? 1 : wait_ms, &f);
        if (r == OCEAN_EIO) {
            char err[512];
            oc_client_last_error(c, err, sizeof err);
            fprintf(stderr, "ocean-client watch: connection lost: %s\n", err);
            return 1;
        }
        if (r != OCEAN_OK)
            continue;
        watch_add(W, f, P->json);
        oc_frame_free(f);
    }
    return 0;
}

/* The rate frames arrived at: intervals between the first and the last,
 * not frames over the wait (one frame 10 ms after the start is not 100
 * fps).  Undefined below two frames. */
static double watch_fps(const watch_acc *W)
{
    return W->frames >= 2 && W->last_rx > W->first_rx ? (double)(W->frames - 1) / (W->last_rx - W->first_rx)
                                                       : NAN;
}

static void watch_print_json(const char *url, const proto_hello *hello, const watch_acc *W, double wall,
                             const oc_client_stats *st)
{
    double p50 = occli_percentile(W->lat.v, W->lat.n, 50), p99 = occli_percentile(W->lat.v, W->lat.n, 99);
    double fps = watch_fps(W);
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "url", url);
    cJSON_AddStringToObject(o, "server_version", hello->server_version);
    cJSON_AddNumberToObject(o, "seconds", wall);
    cJSON_AddNumberToObject(o, "frames", (double)W->frames);
    cJSON_AddNumberToObject(o, "bytes", (double)W->bytes);
    cJSON_AddNumberToObject(o, "bytes_per_s", wall > 0 ? (double)W->bytes / wall : 0);
    if (isfinite(fps))
        cJSON_AddNumberToObject(o, "fps", fps);
    else
        cJSON_AddNullToObject(o, "fps");
    cJSON_AddNumberToObject(o, "tiles", (double)W->tiles);
    cJSON_AddNumberToObject(o, "frames_layout0", (double)W->frames_layout[0]);
    cJSON_AddNumberToObject(o, "frames_layout1", (double)W->frames_layout[1]);
    cJSON_AddNumberToObject(o, "tile_decode_errors", (double)W->bad_tiles);
    if (W->lat.n) {
        cJSON_AddNumberToObject(o, "latency_p50_ms", p50);
        cJSON_AddNumberToObject(o, "latency_p99_ms", p99);
        cJSON_AddNumberToObject(o, "latency_max_ms", W->lat.v[W->lat.n - 1]);
        cJSON_AddNumberToObject(o, "sim_time_first", W->first_t);
        cJSON_AddNumberToObject(o, "sim_time_last", W->last_t);
        cJSON_AddNumberToObject(o, "e_error_mean", W->e_sum / (double)W->frames);
        if (isfinite(W->last_cut))
            cJSON_AddNumberToObject(o, "cutoff_k_last", W->last_cut);
        else
            cJSON_AddNullToObject(o, "cutoff_k_last");
    } else {
        cJSON_AddNullToObject(o, "latency_p50_ms");
        cJSON_AddNullToObject(o, "latency_p99_ms");
    }
    cJSON_AddNumberToObject(o, "frames_skipped", (double)st->frames_gap);
    cJSON_AddNumberToObject(o, "frames_dropped_locally", (double)st->frames_dropped);
    cJSON_AddNumberToObject(o, "errors", (double)st->errors_rx);
    cJSON_AddNumberToObject(o, "decode_errors", (double)st->decode_errors);
    cJSON_AddStringToObject(o, "latency_basis",
                            "receipt wall time minus FRAME sim_time, offset by the smallest such "
                            "difference seen (sim clock assumed to run at wall rate)");
    occli_print_json(o);
}

static void watch_print_text(const watch_acc *W, double wall, const oc_client_stats *st)
{
    double p50 = occli_percentile(W->lat.v, W->lat.n, 50), p99 = occli_percentile(W->lat.v, W->lat.n, 99);
    double fps = watch_fps(W);
    char rate[32] = "fewer than 2 frames: no rate";
    if (isfinite(fps))
        snprintf(rate, sizeof rate, "%.1f fps", fps);
    printf("# %llu frames in %.2f s (%s), %llu bytes (%.0f B/s), latency p50 %.2f ms p99 %.2f ms, "
           "%llu skipped by the server, %llu decode errors\n",
           (unsigned long long)W->frames, wall, rate, (unsigned long long)W->bytes,
           wall > 0 ? W->bytes / wall : 0, p50, p99, (unsigned long long)st->frames_gap,
           (unsigned long long)st->decode_errors);
}

/* Connects and subscribes, keeping the server's first ERROR in
 * server_error: the client, or NULL (said). */
static oc_client *watch_connect(const watch_opts *P, const proto_subscribe *sub, const proto_camera *cam,
                                char *server_error, proto_hello *hello)
{
    oc_options o;
    oc_options_default(&o);
    o.cb.user = server_error;
    o.cb.on_error = keep_error;
    oc_client *c = occli_connect("watch", P->url, &o, P->s.timeout_ms);
    if (!c)
        return NULL;
    oc_client_hello(c, hello);
    if (oc_client_subscribe(c, sub) != OCEAN_OK || oc_client_send_camera(c, cam, NULL) != OCEAN_OK) {
        char err[512];
        oc_client_last_error(c, err, sizeof err);
        fprintf(stderr, "ocean-client watch: %s\n", err);
        oc_client_destroy(c);
        return NULL;
    }
    return c;
}

int cmd_watch(int argc, char **argv)
{
    watch_opts P = {.seconds = 10};
    occli_sub_default(&P.s);
    int pr = watch_parse(argc, argv, &P);
    if (pr)
        return pr == 1 ? 0 : 2;
    proto_subscribe sub;
    proto_camera cam;
    if (occli_sub_build("watch", &P.s, &sub, &cam))
        return 2;
    /* the server's first ERROR, said if no frame comes (the library's
     * last_error is the latest failure, a poll's timeout by then) */
    char server_error[PROTO_ERROR_MSG_MAX + 32] = "";
    proto_hello hello;
    oc_client *c = watch_connect(&P, &sub, &cam, server_error, &hello);
    if (!c)
        return 1;
    if (!P.json)
        printf("# server %s, tick %.1f Hz, client %u; subscribed codec %s at %.1f Hz\n", hello.server_version,
               (double)hello.tick_rate_hz, hello.client_id, proto_codec_name((proto_codec)sub.codec),
               (double)sub.frame_rate_hz);
    watch_acc W = {.first_t = NAN, .last_t = NAN, .last_cut = NAN, .first_rx = NAN, .last_rx = NAN};
    double t0 = occli_mono();
    int rc = watch_receive(&P, c, &cam, t0, &W);
    double wall = occli_mono() - t0;
    oc_client_stats st;
    oc_client_get_stats(c, &st);
    if (P.json)
        watch_print_json(P.url, &hello, &W, wall, &st);
    else
        watch_print_text(&W, wall, &st);
    occli_vec_free(&W.lat);
    oc_client_destroy(c);
    if (!rc && W.frames == 0) {
        /* a SUBSCRIBE refused with ERROR left only this line on the screen */
        fprintf(stderr, "ocean-client watch: no frame received%s%s\n", server_error[0] ? "; the server said: " : "",
                server_error);
        rc = 1;
    }
    return rc;
}
