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

int cmd_watch(int argc, char **argv)
{
    double seconds = 10;
    int max_frames = 0, json = 0;
    occli_sub s;
    occli_sub_default(&s);
    const occli_opt opts[] = {
        {"seconds", OCCLI_DOUBLE, &seconds, 0.001, 1e7, "S  how long to watch", NULL},
        {"frames", OCCLI_INT, &max_frames, 0, 1e9, "N  stop after N frames (0: no limit)", NULL},
        {"json", OCCLI_FLAG, &json, 0, 0, "print only a JSON summary at the end", NULL},
        OCCLI_SUB_OPTS(&s),
    };
    const char *pos[1];
    int np = 0;
    int pr = occli_parse(argc, argv,
                         "usage: ocean-client watch URL [--seconds S] [--frames N] [--json] [subscription options]\n"
                         "Subscribes at the camera given and prints one line per frame: sim time, cutoff (rad/m),\n"
                         "E_error, tiles, bytes and the tick-to-receipt latency estimate.",
                         opts, (int)(sizeof opts / sizeof opts[0]), pos, 1, &np);
    if (pr)
        return pr == 1 ? 0 : 2;
    if (np != 1) {
        fprintf(stderr, "ocean-client watch: needs the server URL (see --help)\n");
        return 2;
    }
    proto_subscribe sub;
    proto_camera cam;
    if (occli_sub_build("watch", &s, &sub, &cam))
        return 2;
    /* the server's first ERROR, said if no frame comes (the library's
     * last_error is the latest failure, a poll's timeout by then) */
    char server_error[PROTO_ERROR_MSG_MAX + 32] = "";
    oc_options o;
    oc_options_default(&o);
    o.cb.user = server_error;
    o.cb.on_error = keep_error;
    oc_client *c = occli_connect("watch", pos[0], &o, s.timeout_ms);
    if (!c)
        return 1;
    proto_hello hello;
    oc_client_hello(c, &hello);
    if (oc_client_subscribe(c, &sub) != OCEAN_OK || oc_client_send_camera(c, &cam, NULL) != OCEAN_OK) {
        char err[512];
        oc_client_last_error(c, err, sizeof err);
        fprintf(stderr, "ocean-client watch: %s\n", err);
        oc_client_destroy(c);
        return 1;
    }
    if (!json)
        printf("# server %s, tick %.1f Hz, client %u; subscribed codec %s at %.1f Hz\n", hello.server_version,
               (double)hello.tick_rate_hz, hello.client_id, proto_codec_name((proto_codec)sub.codec),
               (double)sub.frame_rate_hz);
    occli_vec lat = {0};
    uint64_t frames = 0, bytes = 0, tiles = 0, bad_tiles = 0, frames_layout[2] = {0, 0};
    double e_sum = 0, first_t = NAN, last_t = NAN, last_cut = NAN, first_rx = NAN, last_rx = NAN;
    double t0 = occli_mono(), last_cam = t0;
    double end = t0 + seconds;
    int rc = 0;
    while (!occli_stop) {
        double now = occli_mono();
        if (now >= end || (max_frames && frames >= (uint64_t)max_frames))
            break;
        /* a moving camera reports itself 10 times a second */
        if ((cam.vel[0] != 0 || cam.vel[1] != 0 || cam.vel[2] != 0) && now - last_cam >= 0.1) {
            for (int i = 0; i < 3; i++)
                cam.pos[i] += cam.vel[i] * (now - last_cam);
            last_cam = now;
            oc_client_send_camera(c, &cam, NULL);
        }
        double left = end - now;
        int wait_ms = (int)fmin(100.0, ceil(left * 1e3));
        oc_frame *f = NULL;
        ocean_result r = oc_client_next_frame(c, wait_ms < 1 ? 1 : wait_ms, &f);
        if (r == OCEAN_EIO) {
            char err[512];
            oc_client_last_error(c, err, sizeof err);
            fprintf(stderr, "ocean-client watch: connection lost: %s\n", err);
            rc = 1;
            break;
        }
        if (r != OCEAN_OK)
            continue;
        frames++;
        bytes += f->raw_len;
        tiles += f->info.tile_count;
        frames_layout[f->info.layout == PROTO_LAYOUT_CASCADE]++;
        for (unsigned i = 0; i < f->info.tile_count; i++)
            bad_tiles += f->tiles[i].decode_result != OCEAN_OK;
        e_sum += f->info.e_error;
        if (isnan(first_t))
            first_t = f->hdr.sim_time, first_rx = f->recv_wall;
        last_t = f->hdr.sim_time;
        last_rx = f->recv_wall;
        last_cut = f->info.cutoff_k;
        occli_vec_push(&lat, f->latency_ms);
        if (!json) {
            printf("frame %6llu  t=%10.4f  cutoff=%-9.4g E_error=%-9.3g tiles=%-3u mesh=%-6u bytes=%-8zu "
                   "latency=%.2f ms\n",
                   (unsigned long long)f->index, f->hdr.sim_time, f->info.cutoff_k, f->info.e_error,
                   f->info.tile_count, f->info.has_mesh ? f->info.mesh.vertex_count : 0, f->raw_len,
                   f->latency_ms);
            fflush(stdout);
        }
        oc_frame_free(f);
    }
    double wall = occli_mono() - t0;
    oc_client_stats st;
    oc_client_get_stats(c, &st);
    double p50 = occli_percentile(lat.v, lat.n, 50), p99 = occli_percentile(lat.v, lat.n, 99);
    double pmax = lat.n ? lat.v[lat.n - 1] : NAN;
    /* The rate frames arrived at: intervals between the first and the
     * last, not frames over the wait (one frame 10 ms after the start is
     * not 100 fps).  Undefined below two frames. */
    double fps = frames >= 2 && last_rx > first_rx ? (double)(frames - 1) / (last_rx - first_rx) : NAN;
    if (json) {
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "url", pos[0]);
        cJSON_AddStringToObject(o, "server_version", hello.server_version);
        cJSON_AddNumberToObject(o, "seconds", wall);
        cJSON_AddNumberToObject(o, "frames", (double)frames);
        cJSON_AddNumberToObject(o, "bytes", (double)bytes);
        cJSON_AddNumberToObject(o, "bytes_per_s", wall > 0 ? (double)bytes / wall : 0);
        if (isfinite(fps))
            cJSON_AddNumberToObject(o, "fps", fps);
        else
            cJSON_AddNullToObject(o, "fps");
        cJSON_AddNumberToObject(o, "tiles", (double)tiles);
        cJSON_AddNumberToObject(o, "frames_layout0", (double)frames_layout[0]);
        cJSON_AddNumberToObject(o, "frames_layout1", (double)frames_layout[1]);
        cJSON_AddNumberToObject(o, "tile_decode_errors", (double)bad_tiles);
        if (lat.n) {
            cJSON_AddNumberToObject(o, "latency_p50_ms", p50);
            cJSON_AddNumberToObject(o, "latency_p99_ms", p99);
            cJSON_AddNumberToObject(o, "latency_max_ms", pmax);
            cJSON_AddNumberToObject(o, "sim_time_first", first_t);
            cJSON_AddNumberToObject(o, "sim_time_last", last_t);
            cJSON_AddNumberToObject(o, "e_error_mean", e_sum / (double)frames);
            if (isfinite(last_cut))
                cJSON_AddNumberToObject(o, "cutoff_k_last", last_cut);
            else
                cJSON_AddNullToObject(o, "cutoff_k_last");
        } else {
            cJSON_AddNullToObject(o, "latency_p50_ms");
            cJSON_AddNullToObject(o, "latency_p99_ms");
        }
        cJSON_AddNumberToObject(o, "frames_skipped", (double)st.frames_gap);
        cJSON_AddNumberToObject(o, "frames_dropped_locally", (double)st.frames_dropped);
        cJSON_AddNumberToObject(o, "errors", (double)st.errors_rx);
        cJSON_AddNumberToObject(o, "decode_errors", (double)st.decode_errors);
        cJSON_AddStringToObject(o, "latency_basis",
                                "receipt wall time minus FRAME sim_time, offset by the smallest such "
                                "difference seen (sim clock assumed to run at wall rate)");
        occli_print_json(o);
    } else {
        char rate[32] = "fewer than 2 frames: no rate";
        if (isfinite(fps))
            snprintf(rate, sizeof rate, "%.1f fps", fps);
        printf("# %llu frames in %.2f s (%s), %llu bytes (%.0f B/s), latency p50 %.2f ms p99 %.2f ms, "
               "%llu skipped by the server, %llu decode errors\n",
               (unsigned long long)frames, wall, rate, (unsigned long long)bytes,
               wall > 0 ? bytes / wall : 0, p50, p99, (unsigned long long)st.frames_gap,
               (unsigned long long)st.decode_errors);
    }
    occli_vec_free(&lat);
    oc_client_destroy(c);
    if (!rc && frames == 0) {
        /* a SUBSCRIBE refused with ERROR left only this line on the screen */
        fprintf(stderr, "ocean-client watch: no frame received%s%s\n", server_error[0] ? "; the server said: " : "",
                server_error);
        rc = 1;
    }
    return rc;
}
