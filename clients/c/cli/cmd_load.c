/*
 * cmd_load.c - `ocean-client load`: the load generator the daemon's
 * benchmark uses.  N WebSocket viewers, each subscribed at --rate; reports
 * frames delivered per viewer, tick-to-receipt latency percentiles, frames
 * the server skipped, bytes per viewer per second and the generator's own
 * CPU.  Two receive paths (load_run.h): the direct one (default: worker
 * threads, bulk frame reading, every Nth frame decoded in full, or on the
 * viewer's time-interpolating stream every Nth viewer's stream followed
 * frame by frame) and the client library (--library).  The viewers
 * subscribe as the browser viewer does, --time-interp included.
 *
 * Latency: a frame's sim time is its tick's, and its tick's wall time is
 * the daemon's server.epoch plus that (PROTOCOL.md "Simulation clock"), so
 * with --epoch the latency is each frame's age from its tick (receipt wall
 * time - epoch - sim_time; exact on one host).  Without it, the zero point
 * is the fastest delivery seen over every connection in the run, which
 * hides the time every frame spends being built.
 */
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cJSON.h>

#include "load_run.h"

typedef struct viewer {
    oc_client *c;
    struct load_ctx *ctx;
    uint64_t frames, bytes, frames_layout[2];
    int closed;
    int fill;                 /* load_frame_followed_bad's state */
    proto_camera cam;
} viewer;

typedef struct load_ctx {
    int measuring;
    int decode;               /* frames decoded: read each one's view */
    occli_vec *delay;         /* recv_wall - sim_time, s, of frames in the window */
    double min_delay;         /* over all frames and connections, whole run */
    uint64_t tiles_bad;
    char why[320];          /* the first viewer's closing reason */
} load_ctx;

static void on_frame(void *user, oc_client *c, const oc_frame *f)
{
    (void)c;
    viewer *v = user;
    load_ctx *L = v->ctx;
    double d = f->recv_wall - f->hdr.sim_time;
    if (d < L->min_delay)
        L->min_delay = d;
    /* decoded frames (--decode): the client applied this one to its store
     * on receipt; its view is read as a verified frame's is */
    if (L->decode)
        L->tiles_bad += (uint64_t)load_frame_followed_bad(f, &v->fill);
    if (!L->measuring)
        return;
    v->frames++;
    v->frames_layout[f->info.layout == PROTO_LAYOUT_CASCADE]++;
    v->bytes += f->raw_len;
    occli_vec_push(L->delay, d);
    for (unsigned i = 0; f->tiles && i < f->info.tile_count; i++)
        L->tiles_bad += f->tiles[i].decode_result != OCEAN_OK;
}

static void on_close(void *user, oc_client *c, int reason, const char *msg)
{
    (void)reason;
    viewer *v = user;
    v->closed = 1;
    load_ctx *L = v->ctx;
    /* the client's last error holds a BYE's reason and text */
    if (!L->why[0] && oc_client_last_error(c, L->why, sizeof L->why) == OCEAN_OK && !L->why[0])
        snprintf(L->why, sizeof L->why, "%s", msg && msg[0] ? msg : "connection closed");
}

double load_cpu_seconds(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
           1e-6 * (double)ru.ru_stime.tv_usec;
}

void load_viewer_place(const load_cfg *cfg, int i, int side, proto_camera *cam)
{
    *cam = cfg->cam0;
    cam->pos[0] += cfg->spread * (i % side);
    cam->pos[2] += cfg->spread * (i / side);
    cam->vel[0] = (float)(cam->vel[0] + cfg->speed);
}

/* Creates the viewers on `loop`, their connects spread over cfg->ramp:
 * 0, or 1 (said) with *created those made before the failure. */
static int lib_connect_all(const load_cfg *cfg, oc_loop *loop, viewer *vs, load_ctx *L, int *created)
{
    int nclients = cfg->nclients, side = (int)ceil(sqrt((double)nclients));
    char err[512];
    double t_start = occli_mono();
    for (int i = 0; i < nclients && !occli_stop; i++) {
        double due = t_start + (nclients > 1 ? cfg->ramp * i / (nclients - 1) : 0);
        while (occli_mono() < due && !occli_stop)
            oc_loop_service(loop, (int)fmax(1, fmin(20, (due - occli_mono()) * 1e3)));
        viewer *v = &vs[i];
        v->ctx = L;
        load_viewer_place(cfg, i, side, &v->cam);
        oc_options o;
        oc_options_default(&o);
        o.url = cfg->url;
        o.loop = loop;
        o.decode_tiles = cfg->decode;
        o.header_only = !cfg->decode;
        o.cb.user = v;
        o.cb.on_frame = on_frame;
        o.cb.on_close = on_close;
        if (oc_client_create(&o, &v->c, err, sizeof err) != OCEAN_OK) {
            fprintf(stderr, "ocean-client load: viewer %d: %s\n", i, err);
            return 1;
        }
        ++*created;
        oc_loop_service(loop, 0);
    }
    return 0;
}

/* Waits for every HELLO, subscribing each viewer as it becomes ready
 * (subscribed[i]: 1 subscribed, -1 closed first); returns how many were. */
static int lib_subscribe_all(const load_cfg *cfg, oc_loop *loop, viewer *vs, int created, int *subscribed)
{
    int ready = 0, failed = 0;
    double deadline = occli_mono() + cfg->timeout_ms * 1e-3;
    while (subscribed && ready + failed < created && occli_mono() < deadline && !occli_stop) {
        oc_loop_service(loop, 20);
        for (int i = 0; i < created; i++) {
            if (subscribed[i])
                continue;
            oc_state st = oc_client_state(vs[i].c);
            if (st == OC_READY) {
                oc_client_subscribe(vs[i].c, &cfg->sub);
                oc_client_send_camera(vs[i].c, &vs[i].cam, NULL);
                subscribed[i] = 1;
                ready++;
            } else if (st == OC_CLOSED) {
                subscribed[i] = -1;
                failed++;
            }
        }
    }
    return ready;
}

/* The measured window: the loop serviced for cfg->seconds, subscribed
 * viewers reporting their flight 10 times a second. */
static void lib_measure(const load_cfg *cfg, oc_loop *loop, viewer *vs, int created, const int *subscribed,
                        load_ctx *L, load_result *R)
{
    double c0 = load_cpu_seconds();
    L->measuring = 1;
    double m0 = occli_mono(), m_end = m0 + cfg->seconds, last_cam = m0;
    while (!occli_stop && occli_mono() < m_end) {
        oc_loop_service(loop, 20);
        double now = occli_mono();
        if (cfg->speed > 0 && now - last_cam >= 0.1) {
            for (int i = 0; i < created; i++)
                if (subscribed && subscribed[i] == 1) {
                    vs[i].cam.pos[0] += cfg->speed * (now - last_cam);
                    oc_client_send_camera(vs[i].c, &vs[i].cam, NULL);
                }
            last_cam = now;
        }
    }
    L->measuring = 0;
    R->wall = occli_mono() - m0;
    R->cpu = load_cpu_seconds() - c0;
}

/* Sums the viewers' counts and the clients' statistics into R. */
static void lib_collect(const load_cfg *cfg, viewer *vs, int created, const int *subscribed, load_result *R)
{
    R->fmin = UINT64_MAX;
    for (int i = 0; i < created; i++) {
        viewer *v = &vs[i];
        oc_client_stats st;
        oc_client_get_stats(v->c, &st);
        R->frames += v->frames;
        R->frames_layout[0] += v->frames_layout[0];
        R->frames_layout[1] += v->frames_layout[1];
        R->bytes += v->bytes;
        R->skipped += st.frames_gap;
        R->dropped += st.frames_dropped;
        R->errors += st.errors_rx;
        R->decode_errors += st.decode_errors;
        if (subscribed && subscribed[i] == 1) {
            /* a client that decodes follows its stream by itself */
            R->followed += cfg->decode && load_timed(cfg);
            if (v->frames < R->fmin)
                R->fmin = v->frames;
            if (v->frames > R->fmax)
                R->fmax = v->frames;
        }
        R->closed += v->closed;
    }
    if (R->fmin == UINT64_MAX)
        R->fmin = 0;
}

/* Every viewer an oc_client on one oc_loop (one thread). */
int load_library_run(const load_cfg *cfg, load_result *R)
{
    memset(R, 0, sizeof *R);
    int nclients = cfg->nclients;
    char err[512];
    oc_loop *loop;
    if (oc_loop_create(&loop, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "ocean-client load: %s\n", err);
        return 1;
    }
    load_ctx L;
    memset(&L, 0, sizeof L);
    L.min_delay = INFINITY;
    L.delay = &R->delay;
    L.decode = cfg->decode;
    viewer *vs = calloc((size_t)nclients, sizeof *vs);
    if (!vs) {
        oc_loop_destroy(loop);
        return 1;
    }
    int created = 0;
    int rc = lib_connect_all(cfg, loop, vs, &L, &created);
    int *subscribed = calloc((size_t)(created > 0 ? created : 1), sizeof *subscribed);
    int ready = rc ? 0 : lib_subscribe_all(cfg, loop, vs, created, subscribed);
    if (ready < created)
        fprintf(stderr, "ocean-client load: only %d of %d viewers connected\n", ready, nclients);
    double warm_end = occli_mono() + cfg->warmup;
    while (!occli_stop && occli_mono() < warm_end)
        oc_loop_service(loop, 20);
    lib_measure(cfg, loop, vs, created, subscribed, &L, R);
    R->created = created;
    R->ready = ready;
    snprintf(R->why, sizeof R->why, "%s", L.why);
    lib_collect(cfg, vs, created, subscribed, R);
    R->decode_errors += L.tiles_bad;
    R->verified = cfg->decode ? R->frames : 0;
    R->min_delay = L.min_delay;
    R->min_any = NAN;
    for (int i = 0; i < created; i++)
        oc_client_destroy(vs[i].c);
    oc_loop_destroy(loop);
    free(subscribed);
    free(vs);
    return rc;
}

/* Progress of a load run on a terminal: the run itself (load_direct.c,
 * load_library_run) blocks for ramp + warmup + seconds, so a thread of its
 * own draws elapsed time against that plan. */
typedef struct load_progress {
    atomic_int done;
    double start, planned;
    int nclients;
} load_progress;

static void *load_progress_main(void *arg)
{
    load_progress *lp = arg;
    while (!atomic_load(&lp->done) && !occli_stop) {
        double el = occli_mono() - lp->start;
        occli_progress(fmin(el, lp->planned * 0.999), lp->planned, "load: %d viewers, %.1f/%.1f s", lp->nclients,
                       el, lp->planned);
        occli_sleep(0.2);
    }
    return NULL;
}

/* What the command was asked. */
typedef struct load_opts {
    int nclients, json, decode, library, threads, verify_every;
    double seconds, ramp, spread, speed, warmup, epoch;
    occli_sub s;
    const char *url;
} load_opts;

/* Parses the options into *P (defaults first): 0 go on, 1 help printed, 2
 * refused (said). */
static int load_parse(int argc, char **argv, load_opts *P)
{
    occli_sub *s = &P->s;
    const occli_opt opts[] = {
        {"clients", OCCLI_INT, &P->nclients, 1, 10000, "N  viewers", NULL},
        {"seconds", OCCLI_DOUBLE, &P->seconds, 0.1, 1e6, "S  measured duration", NULL},
        {"json", OCCLI_FLAG, &P->json, 0, 0, "print a JSON summary", NULL},
        {"epoch", OCCLI_DOUBLE, &P->epoch, 0, 1e11, "S  the daemon's server.epoch in Unix seconds: latency becomes each\n"
                                                  "                       frame's age from its tick's wall time (same host or\n"
                                                  "                       synchronised clocks); without it, from the fastest delivery", NULL},
        {"ramp", OCCLI_DOUBLE, &P->ramp, 0, 600, "S  spread the connects over S seconds", NULL},
        {"warmup", OCCLI_DOUBLE, &P->warmup, 0, 600, "S  wait after all viewers subscribed before measuring", NULL},
        {"spread", OCCLI_DOUBLE, &P->spread, 0, 1e6, "M  place viewers on a grid with M metres between them (0: co-located)", NULL},
        {"speed", OCCLI_DOUBLE, &P->speed, 0, 1000, "M/S  viewers fly along +x, reporting 10 times a second", NULL},
        {"threads", OCCLI_INT, &P->threads, 0, 64, "N  worker threads, each its own event loop (0: one per\n"
                                                 "                       online CPU, at most 4)", NULL},
        {"verify-every", OCCLI_INT, &P->verify_every, 1, 1000000,
         "N  decode every Nth frame of each viewer in full, tiles included,\n"
         "                       staggered between viewers (1: every frame); with\n"
         "                       --time-interp on, whose frames are not whole alone, every\n"
         "                       Nth viewer follows its stream instead: all its frames\n"
         "                       decoded in order and read (1: every viewer)", NULL},
        {"decode", OCCLI_FLAG, &P->decode, 0, 0, "decode every frame in full (--verify-every 1; with --library:\n"
                                               "                       decode every tile in the library, which follows\n"
                                               "                       a time-interpolating stream itself)", NULL},
        {"library", OCCLI_FLAG, &P->library, 0, 0, "receive through the C client library, all viewers on one\n"
                                                 "                       oc_loop (one thread; libwebsockets' client parser costs\n"
                                                 "                       ~6 ns a byte, so this path saturates first); reads\n"
                                                 "                       FRAME headers only unless --decode", NULL},
        OCCLI_SUB_OPTS(s),
    };
    const char *pos[1];
    int np = 0;
    int pr = occli_parse(argc, argv,
                         "usage: ocean-client load URL --clients N --seconds S --rate HZ [--json] [options]\n"
                         "Connects N viewers, subscribes each at --rate and measures for S seconds: frames per\n"
                         "viewer, latency tick-to-receipt p50/p99, frames the server skipped, bytes per viewer\n"
                         "per second, the generator's CPU.  Every FRAME's header and fixed fields are checked;\n"
                         "every --verify-every'th is decoded in full.  The viewers subscribe as the browser\n"
                         "viewer does, samples in time included (--time-interp on): each mip's tiles travel once\n"
                         "per its update interval and a frame is read from the samples its connection holds,\n"
                         "so a frame cannot be checked alone: every --verify-every'th viewer follows its\n"
                         "stream (every frame decoded in order); the others' frames are counted, their bytes\n"
                         "and latency measured, not read.  --time-interp off: the plain stream.",
                         opts, (int)(sizeof opts / sizeof opts[0]), pos, 1, &np);
    if (pr)
        return pr;
    if (np != 1) {
        fprintf(stderr, "ocean-client load: needs the server URL (see --help)\n");
        return 2;
    }
    P->url = pos[0];
    return 0;
}

/* The run's configuration from the options: 0, or 2 (said). */
static int load_configure(load_opts *P, load_cfg *cfg)
{
    memset(cfg, 0, sizeof *cfg);
    if (occli_sub_build("load", &P->s, &cfg->sub, &cfg->cam0))
        return 2;
    if (P->threads == 0) {
        long nc = sysconf(_SC_NPROCESSORS_ONLN);
        P->threads = nc < 1 ? 1 : nc > 4 ? 4 : (int)nc;
    }
    if (P->decode)
        P->verify_every = 1;
    cfg->url = P->url;
    cfg->nclients = P->nclients;
    cfg->threads = P->threads;
    cfg->verify_every = P->verify_every;
    cfg->decode = P->decode;
    cfg->seconds = P->seconds;
    cfg->ramp = P->ramp;
    cfg->warmup = P->warmup;
    cfg->spread = P->spread;
    cfg->speed = P->speed;
    cfg->timeout_ms = P->s.timeout_ms;
    return 0;
}

/* One descriptor per viewer, and some to spare. */
static void raise_nofile(int nclients)
{
    struct rlimit rl;
    if (getrlimit(RLIMIT_NOFILE, &rl) == 0 && rl.rlim_cur < (rlim_t)nclients + 64) {
        rl.rlim_cur = rl.rlim_max < (rlim_t)nclients + 64 ? rl.rlim_max : (rlim_t)nclients + 64;
        setrlimit(RLIMIT_NOFILE, &rl);
    }
}

/* Runs the receive path asked, drawing progress on a terminal. */
static int load_run(const load_opts *P, const load_cfg *cfg, load_result *R)
{
    load_progress lp = {.start = occli_mono(), .planned = P->ramp + P->warmup + P->seconds,
                        .nclients = P->nclients};
    atomic_init(&lp.done, 0);
    pthread_t pt;
    int have_pt = isatty(STDERR_FILENO) && pthread_create(&pt, NULL, load_progress_main, &lp) == 0;
    int rc = P->library ? load_library_run(cfg, R) : load_direct_run(cfg, R);
    if (have_pt) {
        atomic_store(&lp.done, 1);
        pthread_join(pt, NULL);
        occli_progress(lp.planned, lp.planned, "load: %d viewers, %.1f s", P->nclients, occli_mono() - lp.start);
    }
    return rc;
}

/* The figures both reports print. */
typedef struct load_summary {
    double p50, p90, p99, pmax, wall, fpv, bpvs;
    int nv, timed;
    const char *path;
} load_summary;

static void load_summarise(const load_opts *P, const load_cfg *cfg, load_result *R, load_summary *M)
{
    /* the zero point: the tick's own wall time (epoch + sim time) when the
     * epoch is known, else the fastest delivery seen */
    double zero = isfinite(P->epoch) ? P->epoch : R->min_delay;
    for (size_t i = 0; i < R->delay.n; i++)
        R->delay.v[i] = 1e3 * (R->delay.v[i] - zero);
    M->p50 = occli_percentile(R->delay.v, R->delay.n, 50);
    M->p90 = occli_percentile(R->delay.v, R->delay.n, 90);
    M->p99 = occli_percentile(R->delay.v, R->delay.n, 99);
    M->pmax = R->delay.n ? R->delay.v[R->delay.n - 1] : NAN;
    M->nv = R->ready > 0 ? R->ready : 1;
    M->wall = R->wall;
    M->fpv = (double)R->frames / M->nv;
    M->bpvs = M->wall > 0 ? (double)R->bytes / M->nv / M->wall : 0;
    M->path = P->library ? "library" : "direct";
    M->timed = load_timed(cfg);
}

/* What was asked and which stream was read. */
static void load_json_request(cJSON *o, const load_opts *P, const load_cfg *cfg, const load_result *R,
                              const load_summary *M)
{
    cJSON_AddStringToObject(o, "url", P->url);
    cJSON_AddNumberToObject(o, "clients", P->nclients);
    cJSON_AddNumberToObject(o, "connected", R->ready);
    cJSON_AddNumberToObject(o, "seconds", M->wall);
    cJSON_AddNumberToObject(o, "rate_hz", P->s.rate);
    cJSON_AddStringToObject(o, "codec", P->s.codec);
    cJSON_AddNumberToObject(o, "layout", cfg->sub.layout);
    /* which stream: samples in time (the viewer's) or plain, and how
     * many viewers decoded theirs in order (the rest read headers) */
    cJSON_AddBoolToObject(o, "time_interp", M->timed);
    cJSON_AddStringToObject(o, "stream", M->timed ? "time-interpolating" : "plain");
    cJSON_AddNumberToObject(o, "streams_followed", R->followed);
    cJSON_AddNumberToObject(o, "effects", cfg->sub.effects);
    cJSON_AddNumberToObject(o, "layers", cfg->sub.layers);
    cJSON_AddNumberToObject(o, "tile_size", cfg->sub.tile_size);
}

static void load_print_json(const load_opts *P, const load_cfg *cfg, const load_result *R, const load_summary *M)
{
    cJSON *o = cJSON_CreateObject();
    load_json_request(o, P, cfg, R, M);
    /* what the daemon answered with: a daemon that predates layout 1
     * sends layout-0 frames whatever was asked */
    cJSON_AddNumberToObject(o, "frames_layout0", (double)R->frames_layout[0]);
    cJSON_AddNumberToObject(o, "frames_layout1", (double)R->frames_layout[1]);
    cJSON_AddNumberToObject(o, "frames", (double)R->frames);
    cJSON_AddNumberToObject(o, "frames_per_viewer", M->fpv);
    cJSON_AddNumberToObject(o, "frames_per_viewer_min", (double)R->fmin);
    cJSON_AddNumberToObject(o, "frames_per_viewer_max", (double)R->fmax);
    cJSON_AddNumberToObject(o, "fps_per_viewer", M->wall > 0 ? M->fpv / M->wall : 0);
    cJSON_AddNumberToObject(o, "frames_expected_per_viewer", P->s.rate * M->wall);
    if (R->delay.n) {
        cJSON_AddNumberToObject(o, "latency_p50_ms", M->p50);
        cJSON_AddNumberToObject(o, "latency_p90_ms", M->p90);
        cJSON_AddNumberToObject(o, "latency_p99_ms", M->p99);
        cJSON_AddNumberToObject(o, "latency_max_ms", M->pmax);
    } else {
        cJSON_AddNullToObject(o, "latency_p50_ms");
        cJSON_AddNullToObject(o, "latency_p99_ms");
    }
    cJSON_AddNumberToObject(o, "frames_skipped", (double)R->skipped);
    cJSON_AddNumberToObject(o, "frames_skipped_per_viewer", (double)R->skipped / M->nv);
    cJSON_AddNumberToObject(o, "frames_dropped_locally", (double)R->dropped);
    cJSON_AddNumberToObject(o, "frames_verified", (double)R->verified);
    cJSON_AddNumberToObject(o, "bytes", (double)R->bytes);
    cJSON_AddNumberToObject(o, "bytes_per_viewer_per_s", M->bpvs);
    cJSON_AddNumberToObject(o, "disconnects", R->closed);
    cJSON_AddNumberToObject(o, "errors", (double)R->errors);
    cJSON_AddNumberToObject(o, "decode_errors", (double)R->decode_errors);
    cJSON_AddNumberToObject(o, "client_cpu_s", R->cpu);
    cJSON_AddNumberToObject(o, "client_cpu_cores", M->wall > 0 ? R->cpu / M->wall : 0);
    /* The zero point above is the fastest FRAME, which hides the time
     * every frame spends being built; HELLO is sent at once, so the
     * fastest FRAME measured against the fastest message says how much. */
    if (isfinite(R->min_any) && isfinite(R->min_delay))
        cJSON_AddNumberToObject(o, "fastest_frame_after_hello_ms", 1e3 * (R->min_delay - R->min_any));
    cJSON_AddStringToObject(o, "receive_path", M->path);
    cJSON_AddNumberToObject(o, "threads", P->library ? 1 : (P->threads < P->nclients ? P->threads : P->nclients));
    cJSON_AddNumberToObject(o, "verify_every", P->library ? (P->decode ? 1 : 0) : P->verify_every);
    cJSON_AddStringToObject(o, "latency_basis",
                            isfinite(P->epoch) ? "receipt wall time minus the tick's wall time (--epoch + FRAME "
                                                 "sim_time): each frame's age from its tick"
                                               : "receipt wall time minus FRAME sim_time, zero at the fastest "
                                                 "delivery seen over all viewers (sim clock assumed to run at "
                                                 "wall rate)");
    occli_print_json(o);
}

static void load_print_text(const load_opts *P, const load_cfg *cfg, const load_result *R, const load_summary *M)
{
    printf("layout %d (frames: %llu layout 0, %llu layout 1), %s\n", cfg->sub.layout,
           (unsigned long long)R->frames_layout[0], (unsigned long long)R->frames_layout[1],
           M->timed ? "time-interpolating stream" : "plain stream");
    if (M->timed)
        printf("streams followed (every frame decoded in order, its view read): %d of %d viewers%s\n",
               R->followed, R->ready, R->followed < R->ready ? "; the others' frames were counted, not read" : "");
    printf("viewers %d/%d, %.2f s at %.1f Hz: %.1f frames/viewer (min %llu, max %llu, %.1f fps), "
           "latency p50 %.2f ms p99 %.2f ms max %.2f ms, skipped %llu, %.0f B/viewer/s, "
           "disconnects %d, errors %llu, decode errors %llu (%llu frames verified), "
           "client CPU %.2f s (%s path)\n",
           R->ready, P->nclients, M->wall, P->s.rate, M->fpv, (unsigned long long)R->fmin,
           (unsigned long long)R->fmax, M->wall > 0 ? M->fpv / M->wall : 0, M->p50, M->p99, M->pmax,
           (unsigned long long)R->skipped, M->bpvs, R->closed, (unsigned long long)R->errors,
           (unsigned long long)R->decode_errors, (unsigned long long)R->verified, R->cpu, M->path);
}

int cmd_load(int argc, char **argv)
{
    load_opts P = {.nclients = 1, .verify_every = 30, .seconds = 10, .ramp = 1.0, .warmup = 0.5, .epoch = NAN};
    /* the library's defaults, which are the browser viewer's subscription
     * (clients/web/worker.js): every effect and every cascade (the daemon
     * clamps both to what the scene has), 64-sample tiles at accuracy 5e-3,
     * 8 levels, layout 1 */
    occli_sub_default(&P.s);
    int pr = load_parse(argc, argv, &P);
    if (pr)
        return pr == 1 ? 0 : 2;
    load_cfg cfg;
    if (load_configure(&P, &cfg))
        return 2;
    raise_nofile(P.nclients);
    load_result R;
    int rc = load_run(&P, &cfg, &R);
    if (rc) {
        occli_vec_free(&R.delay);
        return rc;
    }
    load_summary M;
    load_summarise(&P, &cfg, &R, &M);
    if (P.json)
        load_print_json(&P, &cfg, &R, &M);
    else
        load_print_text(&P, &cfg, &R, &M);
    occli_vec_free(&R.delay);
    /* a run that did not serve every viewer measured something else than
     * was asked: say why, and fail */
    if (R.ready < P.nclients)
        fprintf(stderr, "ocean-client load: %d of %d viewers were not served%s%s\n", P.nclients - R.ready,
                P.nclients, R.why[0] ? ": " : "", R.why);
    if (R.ready < P.nclients || R.frames == 0)
        return 1;
    return 0;
}
