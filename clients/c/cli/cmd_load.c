/*
 * cmd_load.c - `ocean-client load`: the load generator the daemon's
 * benchmark uses.  One process, one event loop, N WebSocket connections,
 * each subscribed at --rate; reports frames delivered per viewer,
 * tick-to-receipt latency percentiles, frames the server skipped, and
 * bytes per viewer per second.
 *
 * Latency: FRAME carries its tick's sim time but no server wall clock, so
 * the latency of a frame is (receipt wall time - sim_time) minus the
 * smallest such difference seen over every connection in the run (all
 * share one server clock).  The zero point is the fastest delivery seen;
 * the sim clock is assumed to run at wall rate (live mode).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include <cJSON.h>

#include "occli.h"

typedef struct viewer {
    oc_client *c;
    struct load_ctx *ctx;
    uint64_t frames, bytes;
    int closed;
    proto_camera cam;
} viewer;

typedef struct load_ctx {
    int measuring;
    occli_vec delay;          /* recv_wall - sim_time, s, of frames in the window */
    double min_delay;         /* over all frames and connections, whole run */
    uint64_t tiles_bad;
} load_ctx;

static void on_frame(void *user, oc_client *c, const oc_frame *f)
{
    (void)c;
    viewer *v = user;
    load_ctx *L = v->ctx;
    double d = f->recv_wall - f->hdr.sim_time;
    if (d < L->min_delay)
        L->min_delay = d;
    if (!L->measuring)
        return;
    v->frames++;
    v->bytes += f->raw_len;
    occli_vec_push(&L->delay, d);
    for (unsigned i = 0; f->tiles && i < f->info.tile_count; i++)
        L->tiles_bad += f->tiles[i].decode_result != OCEAN_OK;
}

static void on_close(void *user, oc_client *c, int reason, const char *msg)
{
    (void)c;
    (void)reason;
    (void)msg;
    ((viewer *)user)->closed = 1;
}

int cmd_load(int argc, char **argv)
{
    int nclients = 1, json = 0, decode = 0;
    double seconds = 10, ramp = 1.0, spread = 0, speed = 0, warmup = 0.5;
    occli_sub s;
    occli_sub_default(&s);
    const occli_opt opts[] = {
        {"clients", OCCLI_INT, &nclients, 1, 10000, "N  viewers (1)"},
        {"seconds", OCCLI_DOUBLE, &seconds, 0.1, 1e6, "S  measured duration (10)"},
        {"json", OCCLI_FLAG, &json, 0, 0, "print a JSON summary"},
        {"ramp", OCCLI_DOUBLE, &ramp, 0, 600, "S  spread the connects over S seconds (1)"},
        {"warmup", OCCLI_DOUBLE, &warmup, 0, 600, "S  wait after all viewers subscribed before measuring (0.5)"},
        {"spread", OCCLI_DOUBLE, &spread, 0, 1e6, "M  place viewers on a grid with M metres between them (0: co-located)"},
        {"speed", OCCLI_DOUBLE, &speed, 0, 1000, "M/S  viewers fly along +x, reporting 10 times a second (0)"},
        {"decode", OCCLI_FLAG, &decode, 0, 0, "decode every message and tile (costs client CPU; by default only\n"
                                               "                       headers and FRAME fixed fields are read)"},
        OCCLI_SUB_OPTS(&s),
    };
    const char *pos[1];
    int np = 0;
    int pr = occli_parse(argc, argv,
                         "usage: ocean-client load URL --clients N --seconds S --rate HZ [--json] [options]\n"
                         "Connects N viewers from one process on one event loop, subscribes each at --rate and\n"
                         "measures for S seconds: frames per viewer, latency tick-to-receipt p50/p99, frames the\n"
                         "server skipped, bytes per viewer per second.",
                         opts, (int)(sizeof opts / sizeof opts[0]), pos, 1, &np);
    if (pr)
        return pr == 1 ? 0 : 2;
    if (np != 1) {
        fprintf(stderr, "ocean-client load: needs the server URL (see --help)\n");
        return 2;
    }
    proto_subscribe sub;
    proto_camera cam0;
    if (occli_sub_build("load", &s, &sub, &cam0))
        return 2;
    struct rlimit rl;
    if (getrlimit(RLIMIT_NOFILE, &rl) == 0 && rl.rlim_cur < (rlim_t)nclients + 64) {
        rl.rlim_cur = rl.rlim_max < (rlim_t)nclients + 64 ? rl.rlim_max : (rlim_t)nclients + 64;
        setrlimit(RLIMIT_NOFILE, &rl);
    }
    char err[512];
    oc_loop *loop;
    if (oc_loop_create(&loop, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "ocean-client load: %s\n", err);
        return 1;
    }
    load_ctx L;
    memset(&L, 0, sizeof L);
    L.min_delay = INFINITY;
    viewer *vs = calloc((size_t)nclients, sizeof *vs);
    if (!vs) {
        oc_loop_destroy(loop);
        return 1;
    }
    int side = (int)ceil(sqrt((double)nclients));
    int rc = 0, created = 0;
    double t_start = occli_mono();
    for (int i = 0; i < nclients && !occli_stop; i++) {
        double due = t_start + (nclients > 1 ? ramp * i / (nclients - 1) : 0);
        while (occli_mono() < due && !occli_stop)
            oc_loop_service(loop, (int)fmax(1, fmin(20, (due - occli_mono()) * 1e3)));
        viewer *v = &vs[i];
        v->ctx = &L;
        v->cam = cam0;
        v->cam.pos[0] += spread * (i % side);
        v->cam.pos[2] += spread * (i / side);
        v->cam.vel[0] = (float)(v->cam.vel[0] + speed);
        oc_options o;
        oc_options_default(&o);
        o.url = pos[0];
        o.loop = loop;
        o.decode_tiles = decode;
        o.header_only = !decode;   /* the generator's CPU must not be the bottleneck */
        o.cb.user = v;
        o.cb.on_frame = on_frame;
        o.cb.on_close = on_close;
        if (oc_client_create(&o, &v->c, err, sizeof err) != OCEAN_OK) {
            fprintf(stderr, "ocean-client load: viewer %d: %s\n", i, err);
            rc = 1;
            break;
        }
        created++;
        oc_loop_service(loop, 0);
    }
    /* wait for every HELLO, subscribing each viewer as it becomes ready */
    int *subscribed = calloc((size_t)(created > 0 ? created : 1), sizeof *subscribed);
    int ready = 0, failed = 0;
    double deadline = occli_mono() + s.timeout_ms * 1e-3;
    while (!rc && subscribed && ready + failed < created && occli_mono() < deadline && !occli_stop) {
        oc_loop_service(loop, 20);
        for (int i = 0; i < created; i++) {
            if (subscribed[i])
                continue;
            oc_state st = oc_client_state(vs[i].c);
            if (st == OC_READY) {
                oc_client_subscribe(vs[i].c, &sub);
                oc_client_send_camera(vs[i].c, &vs[i].cam, NULL);
                subscribed[i] = 1;
                ready++;
            } else if (st == OC_CLOSED) {
                subscribed[i] = -1;
                failed++;
            }
        }
    }
    if (ready < created)
        fprintf(stderr, "ocean-client load: only %d of %d viewers connected\n", ready, nclients);
    double warm_end = occli_mono() + warmup;
    while (!occli_stop && occli_mono() < warm_end)
        oc_loop_service(loop, 20);
    struct rusage ru0, ru1;
    getrusage(RUSAGE_SELF, &ru0);
    L.measuring = 1;
    double m0 = occli_mono(), m_end = m0 + seconds, last_cam = m0;
    while (!occli_stop && occli_mono() < m_end) {
        oc_loop_service(loop, 20);
        double now = occli_mono();
        if (speed > 0 && now - last_cam >= 0.1) {
            for (int i = 0; i < created; i++)
                if (subscribed[i] == 1) {
                    vs[i].cam.pos[0] += speed * (now - last_cam);
                    oc_client_send_camera(vs[i].c, &vs[i].cam, NULL);
                }
            last_cam = now;
        }
    }
    L.measuring = 0;
    double wall = occli_mono() - m0;
    getrusage(RUSAGE_SELF, &ru1);
    double cpu = (ru1.ru_utime.tv_sec - ru0.ru_utime.tv_sec) + 1e-6 * (ru1.ru_utime.tv_usec - ru0.ru_utime.tv_usec) +
                 (ru1.ru_stime.tv_sec - ru0.ru_stime.tv_sec) + 1e-6 * (ru1.ru_stime.tv_usec - ru0.ru_stime.tv_usec);

    uint64_t frames = 0, bytes = 0, skipped = 0, dropped = 0, errors = 0, dec_err = 0;
    uint64_t fmin_v = UINT64_MAX, fmax_v = 0;
    int closed = 0;
    for (int i = 0; i < created; i++) {
        viewer *v = &vs[i];
        oc_client_stats st;
        oc_client_get_stats(v->c, &st);
        frames += v->frames;
        bytes += v->bytes;
        skipped += st.frames_gap;
        dropped += st.frames_dropped;
        errors += st.errors_rx;
        dec_err += st.decode_errors;
        if (subscribed && subscribed[i] == 1) {
            if (v->frames < fmin_v)
                fmin_v = v->frames;
            if (v->frames > fmax_v)
                fmax_v = v->frames;
        }
        closed += v->closed;
    }
    if (fmin_v == UINT64_MAX)
        fmin_v = 0;
    for (size_t i = 0; i < L.delay.n; i++)
        L.delay.v[i] = 1e3 * (L.delay.v[i] - L.min_delay);
    double p50 = occli_percentile(L.delay.v, L.delay.n, 50);
    double p90 = occli_percentile(L.delay.v, L.delay.n, 90);
    double p99 = occli_percentile(L.delay.v, L.delay.n, 99);
    double pmax = L.delay.n ? L.delay.v[L.delay.n - 1] : NAN;
    int nv = ready > 0 ? ready : 1;
    double fpv = (double)frames / nv;
    double bpvs = wall > 0 ? (double)bytes / nv / wall : 0;
    if (json) {
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "url", pos[0]);
        cJSON_AddNumberToObject(o, "clients", nclients);
        cJSON_AddNumberToObject(o, "connected", ready);
        cJSON_AddNumberToObject(o, "seconds", wall);
        cJSON_AddNumberToObject(o, "rate_hz", s.rate);
        cJSON_AddStringToObject(o, "codec", s.codec);
        cJSON_AddNumberToObject(o, "frames", (double)frames);
        cJSON_AddNumberToObject(o, "frames_per_viewer", fpv);
        cJSON_AddNumberToObject(o, "frames_per_viewer_min", (double)fmin_v);
        cJSON_AddNumberToObject(o, "frames_per_viewer_max", (double)fmax_v);
        cJSON_AddNumberToObject(o, "fps_per_viewer", wall > 0 ? fpv / wall : 0);
        cJSON_AddNumberToObject(o, "frames_expected_per_viewer", s.rate * wall);
        if (L.delay.n) {
            cJSON_AddNumberToObject(o, "latency_p50_ms", p50);
            cJSON_AddNumberToObject(o, "latency_p90_ms", p90);
            cJSON_AddNumberToObject(o, "latency_p99_ms", p99);
            cJSON_AddNumberToObject(o, "latency_max_ms", pmax);
        } else {
            cJSON_AddNullToObject(o, "latency_p50_ms");
            cJSON_AddNullToObject(o, "latency_p99_ms");
        }
        cJSON_AddNumberToObject(o, "frames_skipped", (double)skipped);
        cJSON_AddNumberToObject(o, "frames_skipped_per_viewer", (double)skipped / nv);
        cJSON_AddNumberToObject(o, "frames_dropped_locally", (double)dropped);
        cJSON_AddNumberToObject(o, "bytes", (double)bytes);
        cJSON_AddNumberToObject(o, "bytes_per_viewer_per_s", bpvs);
        cJSON_AddNumberToObject(o, "disconnects", closed);
        cJSON_AddNumberToObject(o, "errors", (double)errors);
        cJSON_AddNumberToObject(o, "decode_errors", (double)(dec_err + L.tiles_bad));
        cJSON_AddNumberToObject(o, "client_cpu_s", cpu);
        cJSON_AddStringToObject(o, "latency_basis",
                                "receipt wall time minus FRAME sim_time, zero at the fastest delivery seen "
                                "over all viewers (sim clock assumed to run at wall rate)");
        char *txt = cJSON_Print(o);
        printf("%s\n", txt);
        free(txt);
        cJSON_Delete(o);
    } else {
        printf("viewers %d/%d, %.2f s at %.1f Hz: %.1f frames/viewer (min %llu, max %llu, %.1f fps), "
               "latency p50 %.2f ms p99 %.2f ms max %.2f ms, skipped %llu, %.0f B/viewer/s, "
               "disconnects %d, errors %llu, client CPU %.2f s\n",
               ready, nclients, wall, s.rate, fpv, (unsigned long long)fmin_v, (unsigned long long)fmax_v,
               wall > 0 ? fpv / wall : 0, p50, p99, pmax, (unsigned long long)skipped, bpvs, closed,
               (unsigned long long)errors, cpu);
    }
    for (int i = 0; i < created; i++)
        oc_client_destroy(vs[i].c);
    oc_loop_destroy(loop);
    occli_vec_free(&L.delay);
    free(subscribed);
    free(vs);
    if (ready == 0 || frames == 0)
        rc = 1;
    return rc;
}
