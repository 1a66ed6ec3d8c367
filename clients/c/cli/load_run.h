/*
 * load_run.h - the two receive paths of `ocean-client load` and the result
 * they both fill, so one report prints either.
 *
 *  - load_direct_run: the default.  Viewers are spread over worker threads,
 *    each with its own epoll loop; every connection is a plain socket read
 *    in bulk and framed by libwslay (a small RFC 6455 library with no
 *    per-byte parsing), after a minimal HTTP Upgrade.  Why not the
 *    client library: libwebsockets 4.1.6's client parser handles a frame's
 *    payload one byte at a time (about 6 ns a byte, measured with perf on
 *    this machine), which at 256 viewers x 3.8 MB/s is several cores - the
 *    generator, not the daemon, would be measured.  Every FRAME's header and
 *    fixed fields (and a layout-1 frame's cascade block) are checked; every
 *    verify_every-th FRAME of each viewer (staggered between viewers) is
 *    decoded in full as the client library would, tiles included.  A
 *    time-interpolating stream (the viewer's; load_timed) has no whole
 *    frames but its KEY frames, so there every verify_every-th viewer
 *    follows its stream instead: every frame decoded in order through an
 *    oc_frame_stream, its view read; the other viewers' frames are
 *    checked as above and counted, never read.
 *  - load_library_run: every viewer is an oc_client on one oc_loop, as a
 *    simulator would connect (--library); header-only unless --decode,
 *    which also follows a time-interpolating stream (the client does).
 *
 * Latency samples are kept raw (receipt wall time - FRAME sim_time) and
 * merged over every thread before percentiles are taken.
 */
#ifndef LOAD_RUN_H
#define LOAD_RUN_H

#include <stddef.h>
#include <stdint.h>

#include "occli.h"
#include "proto.h"

typedef struct load_cfg {
    const char *url;
    int nclients;
    int threads;          /* direct path: worker threads (1..64) */
    int verify_every;     /* direct path: decode every Nth frame in full (1: all) */
    int decode;           /* library path: decode every tile */
    double seconds, ramp, warmup, spread, speed;
    int timeout_ms;
    proto_subscribe sub;
    proto_camera cam0;
} load_cfg;

typedef struct load_result {
    int created, ready;
    double wall;                  /* measured seconds */
    double cpu;                   /* process CPU seconds over the window */
    uint64_t frames, bytes, skipped, dropped, errors, decode_errors, verified;
    uint64_t fmin, fmax;          /* frames of the least / most served viewer */
    uint64_t frames_layout[2];    /* frames by their layout (0 world, 1 cascade) */
    int followed;                 /* viewers whose time-interpolating stream
                                     was followed (every frame decoded) */
    int closed;
    occli_vec delay;              /* raw recv_wall - sim_time, s, in the window */
    double min_delay;             /* smallest such value over the whole run */
    double min_any;               /* same over every message, HELLO included
                                     (direct path; NAN if unknown) */
    char why[320];                /* the first reason a viewer was closed or
                                     refused (a BYE's text), or "" */
} load_result;

/* Whether cfg subscribes to samples in time (layout 1 with
 * PROTO_SUB_TIME_INTERP; layout 0 ignores the flag). */
static inline int load_timed(const load_cfg *cfg)
{
    return (cfg->sub.flags & PROTO_SUB_TIME_INTERP) && cfg->sub.layout == PROTO_LAYOUT_CASCADE;
}

/* What a decoded frame f fails of the checks a verified frame passes
 * (load_direct.c): 0, or the count of problems (a layout-0 f32 mesh
 * without positions; a layout-1 frame with tiles, or of a time-
 * interpolating stream, whose view does not read a finite height at its
 * camera). */
int load_frame_bad(const oc_frame *f);

/* load_frame_bad for a followed time-interpolating stream, *fill its state
 * (0 at the start; NULL: a frame read alone): what the client lacks at
 * first comes over a few frames (each at most twice a frame's byte budget,
 * PROTOCOL.md "Samples in time"), so until the sea is read once, up to
 * LOAD_FILL_FRAMES frames that do not read it yet are not errors. */
#define LOAD_FILL_FRAMES 10
int load_frame_followed_bad(const oc_frame *f, int *fill);

/* Where viewer i of a grid `side` viewers wide starts: cfg->spread metres
 * from its neighbours, flying at cfg->speed along +x on top of the
 * camera's own velocity. */
void load_viewer_place(const load_cfg *cfg, int i, int side, proto_camera *cam);

/* CPU seconds this process has used, user and system. */
double load_cpu_seconds(void);

/* Both return 0 when the run took place (the result says how well, and
 * ready < nclients that some viewers were never served), 1 on a setup
 * failure (message printed). */
int load_direct_run(const load_cfg *cfg, load_result *out);
int load_library_run(const load_cfg *cfg, load_result *out);

#endif
