/*
 * cmd_record.c - camera paths flown against the daemon and saved as frame
 * stores (clients/c/oc_store.h): `ocean-client record` flies one in live
 * mode and saves every message that came back; `ocean-client replay` flies
 * it in replay mode, where each CAMERA names the sim time to render, so the
 * saved FRAMEs must be identical on every run (--check compares).
 */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "oc_path.h"
#include "oc_store.h"
#include "occli.h"

typedef struct rec_ctx {
    oc_store_writer *w;
    double t0;
    int write_failed;
    uint64_t frames;          /* FRAMEs received */
    uint32_t last_answered;   /* camera_seq of the last FRAME */
    int have_answer;
    uint64_t bytes;
} rec_ctx;

static void on_msg(void *user, oc_client *c, const uint8_t *raw, size_t len, const proto_msg *m,
                   ocean_result res)
{
    (void)c;
    (void)res;
    rec_ctx *r = user;
    r->bytes += len;
    if (len >= PROTO_HEADER_SIZE && oc_store_writer_append(r->w, occli_mono() - r->t0, raw, len) != OCEAN_OK)
        r->write_failed = 1;
    if (m && m->hdr.type == PROTO_FRAME) {
        r->frames++;
        if (m->u.frame.camera_seq != PROTO_NO_CAMERA) {
            r->last_answered = m->u.frame.camera_seq;
            r->have_answer = 1;
        }
    }
}

static void on_frame_drop(void *user, oc_client *c, const oc_frame *f)
{
    (void)user;
    (void)c;
    (void)f;   /* stored by on_msg; nothing else to do */
}

static int finish_store(const char *cmd, rec_ctx *r, const char *out)
{
    ocean_result cr = oc_store_writer_close(r->w);
    r->w = NULL;
    if (cr != OCEAN_OK || r->write_failed) {
        fprintf(stderr, "ocean-client %s: writing %s failed\n", cmd, out);
        return 1;
    }
    return 0;
}

/* Opens the frame store `out` for r: 0, or 1 (said). */
static int rec_store_open(const char *cmd, const char *out, rec_ctx *r)
{
    char err[512];
    memset(r, 0, sizeof *r);
    if (oc_store_writer_open(out, &r->w, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "ocean-client %s: %s\n", cmd, err);
        return 1;
    }
    r->t0 = occli_mono();
    return 0;
}

/* Connects with every message received going into r's store, tiles not
 * decoded: the client, or NULL (said). */
static oc_client *rec_connect(const char *cmd, const char *url, int timeout_ms, rec_ctx *r)
{
    oc_options o;
    oc_options_default(&o);
    o.cb.user = r;
    o.cb.on_message = on_msg;
    o.cb.on_frame = on_frame_drop;
    o.decode_tiles = 0;
    return occli_connect(cmd, url, &o, timeout_ms);
}

/* What `record` was asked. */
typedef struct record_opts {
    const char *path, *out, *url;
    double tail, speed;
    occli_sub s;
} record_opts;

static int record_parse(int argc, char **argv, record_opts *P)
{
    const occli_opt opts[] = {
        {"path", OCCLI_STRING, &P->path, 0, 0, "FILE  camera path (oceand camera path v1 CSV; - for stdin)", NULL},
        {"out", OCCLI_STRING, &P->out, 0, 0, "FRAMES  frame store to write", NULL},
        {"tail", OCCLI_DOUBLE, &P->tail, 0, 3600, "S  keep receiving after the last report", NULL},
        {"speed", OCCLI_DOUBLE, &P->speed, 0.01, 100, "X  fly the path X times faster than its t column", NULL},
        OCCLI_SUB_OPTS(&P->s),
    };
    const char *pos[1];
    int np = 0;
    int pr = occli_parse(argc, argv,
                         "usage: ocean-client record URL --path PATH.csv --out FRAMES [options]\n"
                         "Flies the camera path in live mode (report i is sent at (t_i - t_0) / speed seconds)\n"
                         "and saves every message received to the frame store FRAMES.",
                         opts, (int)(sizeof opts / sizeof opts[0]), pos, 1, &np);
    if (pr)
        return pr;
    if (np != 1 || !P->path || !P->out) {
        fprintf(stderr, "ocean-client record: needs URL, --path and --out (see --help)\n");
        return 2;
    }
    P->url = pos[0];
    return 0;
}

/* The camera path, which live mode paces by t: NULL (said) if it cannot
 * be read or goes back in time. */
static oc_path *record_path_load(const char *path)
{
    char err[512];
    oc_path *p;
    if (oc_path_load(path, &p, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "ocean-client record: %s\n", err);
        return NULL;
    }
    if (!p->monotonic) {
        fprintf(stderr, "ocean-client record: %s:%u: t goes back in time (a replay-mode recording that "
                "scrubs): `ocean-client replay` sends it as recorded; record paces reports by t\n", path,
                p->back_line);
        oc_path_destroy(p);
        return NULL;
    }
    return p;
}

/* Sends each report of p at its time, then receives for P->tail seconds:
 * 0, or 1 (a send failed or the connection closed). */
static int record_fly(const record_opts *P, oc_client *c, const oc_path *p, proto_camera *cam, const rec_ctx *r,
                      double start)
{
    int rc = 0;
    for (size_t i = 0; i < p->count && !rc && !occli_stop; i++) {
        double due = start + (p->pts[i].t - p->pts[0].t) / P->speed;
        while (!occli_stop) {
            double now = occli_mono();
            if (now >= due)
                break;
            oc_service(c, (int)fmax(1, fmin(50, (due - now) * 1e3)));
        }
        oc_path_camera(&p->pts[i], cam);
        cam->render_time = 0;
        if (oc_client_send_camera(c, cam, NULL) != OCEAN_OK)
            rc = 1;
        if (oc_client_state(c) == OC_CLOSED)
            rc = 1;
        occli_progress((double)(i + 1), (double)p->count + (P->tail > 0),
                       "%zu/%zu camera reports, %.1f/%.1f s, %llu frames", i + 1, p->count, occli_mono() - start,
                       (p->pts[p->count - 1].t - p->pts[0].t) / P->speed + P->tail, (unsigned long long)r->frames);
    }
    double end = occli_mono() + P->tail;
    while (!rc && !occli_stop && occli_mono() < end && oc_client_state(c) != OC_CLOSED) {
        oc_service(c, 50);
        occli_progress((double)p->count, (double)p->count + 1, "%zu/%zu camera reports, tail %.1f/%.1f s, %llu frames",
                       p->count, p->count, P->tail - (end - occli_mono()), P->tail, (unsigned long long)r->frames);
    }
    occli_progress_end();
    return rc;
}

int cmd_record(int argc, char **argv)
{
    record_opts P = {.tail = 1.0, .speed = 1.0};
    occli_sub_default(&P.s);
    int pr = record_parse(argc, argv, &P);
    if (pr)
        return pr == 1 ? 0 : 2;
    proto_subscribe sub;
    proto_camera cam;
    if (occli_sub_build("record", &P.s, &sub, &cam))
        return 2;
    oc_path *p = record_path_load(P.path);
    if (!p)
        return 2;
    rec_ctx r;
    if (rec_store_open("record", P.out, &r)) {
        oc_path_destroy(p);
        return 1;
    }
    oc_client *c = rec_connect("record", P.url, P.s.timeout_ms, &r);
    if (!c) {
        oc_store_writer_close(r.w);
        oc_path_destroy(p);
        return 1;
    }
    sub.mode = PROTO_MODE_LIVE;
    int rc = oc_client_subscribe(c, &sub) != OCEAN_OK;
    double start = occli_mono();
    if (!rc)
        rc = record_fly(&P, c, p, &cam, &r, start);
    if (oc_client_state(c) == OC_CLOSED) {
        char err[512];
        oc_client_last_error(c, err, sizeof err);
        fprintf(stderr, "ocean-client record: connection lost: %s\n", err);
        rc = 1;
    }
    oc_client_destroy(c);
    rc |= finish_store("record", &r, P.out);
    fprintf(stderr, "ocean-client record: %zu camera reports over %.2f s, %llu frames, %llu bytes -> %s\n",
            p->count, occli_mono() - start, (unsigned long long)r.frames, (unsigned long long)r.bytes, P.out);
    if (!rc && r.frames == 0) {
        fprintf(stderr, "ocean-client record: no frame received\n");
        rc = 1;
    }
    oc_path_destroy(p);
    return rc;
}

/* What `replay` was asked. */
typedef struct replay_opts {
    const char *out, *check, *url, *path;
    int window;
    occli_sub s;
} replay_opts;

static int replay_parse(int argc, char **argv, replay_opts *P)
{
    const occli_opt opts[] = {
        {"out", OCCLI_STRING, &P->out, 0, 0, "FRAMES  frame store to write (a temporary file if only --check)", NULL},
        {"check", OCCLI_STRING, &P->check, 0, 0, "FRAMES  compare with an earlier run byte for byte; exit 1 on any difference", NULL},
        {"window", OCCLI_INT, &P->window, 1, 256, "N  CAMERA reports in flight", NULL},
        OCCLI_SUB_OPTS(&P->s),
    };
    const char *pos[2];
    int np = 0;
    int pr = occli_parse(argc, argv,
                         "usage: ocean-client replay URL PATH.csv --out FRAMES [--check FRAMES] [options]\n"
                         "Subscribes in replay mode and sends each camera report with its t as the sim time to\n"
                         "render; saves every message received.  --check compares the FRAME, MESH_TOPOLOGY and\n"
                         "QUERY_RESULT messages with an earlier store byte for byte (header seq excepted).",
                         opts, (int)(sizeof opts / sizeof opts[0]), pos, 2, &np);
    if (pr)
        return pr;
    if (np != 2 || (!P->out && !P->check)) {
        fprintf(stderr, "ocean-client replay: needs URL, PATH.csv and --out (see --help)\n");
        return 2;
    }
    P->url = pos[0];
    P->path = pos[1];
    return 0;
}

/* The store to compare with must be readable before a replay that can
 * take minutes: 0, or 2 (said). */
static int replay_check_readable(const char *check)
{
    char err[512];
    oc_store_reader *cr;
    if (oc_store_reader_open(check, &cr, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "ocean-client replay: option '--check': %s\n", err);
        return 2;
    }
    oc_store_reader_close(cr);
    return 0;
}

/* A temporary file's name in tmp (64 bytes): 0, or 1 (said). */
static int replay_temp_out(char *tmp)
{
    snprintf(tmp, 64, "/tmp/ocean-replay.XXXXXX");
    int fd = mkstemp(tmp);
    if (fd < 0) {
        fprintf(stderr, "ocean-client replay: cannot make a temporary file: %s\n", strerror(errno));
        return 1;
    }
    close(fd);
    return 0;
}

/* Sends the path's reports, P->window in flight, until each is answered
 * by a FRAME; *answered counts them.  0, or 1 (said). */
static int replay_send(const replay_opts *P, oc_client *c, const oc_path *p, proto_camera *cam, const rec_ctx *r,
                       uint32_t *seqs, size_t *answered)
{
    size_t sent = 0;
    int rc = 0;
    double last_progress = occli_mono();
    while (!rc && !occli_stop && *answered < p->count) {
        while (sent < p->count && sent - *answered < (size_t)P->window) {
            oc_path_camera(&p->pts[sent], cam);
            if (oc_client_send_camera(c, cam, &seqs[sent]) != OCEAN_OK) {
                rc = 1;
                break;
            }
            sent++;
        }
        oc_service(c, 50);
        /* a FRAME answering camera k answers every earlier one too */
        if (r->have_answer) {
            while (*answered < sent && (int32_t)(r->last_answered - seqs[*answered]) >= 0) {
                ++*answered;
                last_progress = occli_mono();
            }
        }
        occli_progress((double)*answered, (double)p->count, "%zu/%zu camera reports answered, %llu frames",
                       *answered, p->count, (unsigned long long)r->frames);
        if (oc_client_state(c) == OC_CLOSED) {
            char err[512];
            oc_client_last_error(c, err, sizeof err);
            fprintf(stderr, "ocean-client replay: connection lost: %s\n", err);
            rc = 1;
        } else if (occli_mono() - last_progress > P->s.timeout_ms * 1e-3) {
            fprintf(stderr, "ocean-client replay: no FRAME for camera report %zu (t = %.9g) within %d ms\n",
                    *answered, p->pts[*answered].t, P->s.timeout_ms);
            rc = 1;
        }
    }
    return rc;
}

/* Connects in replay mode and replays the path, *start the time it began
 * once connected: 0, or 1 (said). */
static int replay_run(const replay_opts *P, proto_subscribe *sub, proto_camera *cam, const oc_path *p, rec_ctx *r,
                      size_t *answered, double *start)
{
    oc_client *c = rec_connect("replay", P->url, P->s.timeout_ms, r);
    *start = occli_mono();
    if (!c)
        return 1;
    sub->mode = PROTO_MODE_REPLAY;
    int rc = oc_client_subscribe(c, sub) != OCEAN_OK;
    uint32_t *seqs = calloc(p->count, sizeof *seqs);
    if (!seqs)
        rc = 1;
    if (!rc)
        rc = replay_send(P, c, p, cam, r, seqs, answered);
    occli_progress_end();
    free(seqs);
    oc_client_stats st;
    oc_client_get_stats(c, &st);
    if (st.errors_rx) {
        char err[512];
        oc_client_last_error(c, err, sizeof err);
        fprintf(stderr, "ocean-client replay: the server sent %llu ERROR(s), last: %s\n",
                (unsigned long long)st.errors_rx, err);
        rc = 1;
    }
    oc_client_destroy(c);
    return rc;
}

/* --check: the store written against the earlier one: 0 identical, or 1
 * (said). */
static int replay_compare(const char *check, const char *out)
{
    char err[512];
    oc_store_diff d;
    ocean_result cr = oc_store_compare(check, out, 0, &d, err, sizeof err);
    if (cr != OCEAN_OK) {
        fprintf(stderr, "ocean-client replay: --check: %s\n", err);
        return 1;
    }
    if (!d.identical) {
        fprintf(stderr, "ocean-client replay: --check: DIFFERENT from %s: %s\n", check, d.what);
        return 1;
    }
    fprintf(stderr, "ocean-client replay: --check: identical to %s (%llu messages compared)\n", check,
            (unsigned long long)d.compared);
    return 0;
}

int cmd_replay(int argc, char **argv)
{
    replay_opts P = {.window = 4};
    occli_sub_default(&P.s);
    int pr = replay_parse(argc, argv, &P);
    if (pr)
        return pr == 1 ? 0 : 2;
    proto_subscribe sub;
    proto_camera cam;
    if (occli_sub_build("replay", &P.s, &sub, &cam))
        return 2;
    if (P.check && replay_check_readable(P.check))
        return 2;
    char err[512];
    oc_path *p;
    if (oc_path_load(P.path, &p, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "ocean-client replay: %s\n", err);
        return 2;
    }
    char tmp[64] = "";
    const char *out = P.out;
    if (!out && replay_temp_out(tmp)) {
        oc_path_destroy(p);
        return 1;
    }
    if (!out)
        out = tmp;
    rec_ctx r;
    if (rec_store_open("replay", out, &r)) {
        oc_path_destroy(p);
        return 1;
    }
    size_t answered = 0;
    double start;
    int rc = replay_run(&P, &sub, &cam, p, &r, &answered, &start);
    rc |= finish_store("replay", &r, out);
    fprintf(stderr, "ocean-client replay: %zu/%zu camera reports answered in %.2f s, %llu frames, %llu bytes -> %s\n",
            answered, p->count, occli_mono() - start, (unsigned long long)r.frames, (unsigned long long)r.bytes,
            tmp[0] ? "(temporary)" : out);
    oc_path_destroy(p);
    if (!rc && P.check)
        rc = replay_compare(P.check, out);
    if (tmp[0])
        unlink(tmp);
    return rc;
}
