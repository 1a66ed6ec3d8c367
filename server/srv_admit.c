/*
 * srv_admit.c - admission for the daemon as a whole (see srv_admit.h).
 *
 * Rates are smoothed over a few seconds (each sample weighs SMOOTH): a
 * burst of other work on the host lowers the capacity for a while, not for
 * one sample's second only, and a quiet second does not reopen it at once.
 */
#include "srv_admit.h"

#include <math.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include "srv_tiles.h"

#define SMOOTH 0.3
#define SAMPLE_S 1.0   /* seconds between samples */
/* plane-samples a codec's cost is re-measured from at least (a 64^2 tile's
 * worth of one plane): fewer say more about the clock than the codec */
#define MIN_SAMPLES 4096.0

struct srv_admit {
    int workers;
    int ncpu;
    double clk_tck;
    atomic_uint_fast64_t tile_ns[PROTO_CODEC_COUNT_];      /* [any] running totals */
    atomic_uint_fast64_t tile_samples[PROTO_CODEC_COUNT_]; /* [any] */
    uint64_t seen_ns[PROTO_CODEC_COUNT_], seen_samples[PROTO_CODEC_COUNT_]; /* [svc] */
    double cost[PROTO_CODEC_COUNT_]; /* [svc] seconds per plane-sample */
    int sampled;                     /* [svc] a first sample was taken */
    double last_now, last_tiles_s, last_busy_s, last_self_s; /* [svc] */
    double shared, others;           /* [svc] cores, smoothed */
    double priced;                   /* [svc] */
    int admitted;                    /* [svc] */
};

static int cpus_usable(void)
{
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0) return CPU_COUNT(&set);
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? (int)n : 1;
}

double srv_admit_thread_cpu(void)
{
    struct timespec ts;
    if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts) != 0) return 0;
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

ocean_result srv_admit_create(int workers, srv_admit **out)
{
    srv_admit *a = calloc(1, sizeof *a);
    if (!a) return OCEAN_ENOMEM;
    a->workers = workers > 0 ? workers : 1;
    a->ncpu = cpus_usable();
    long t = sysconf(_SC_CLK_TCK);
    a->clk_tck = t > 0 ? (double)t : 100.0;
    *out = a;
    return OCEAN_OK;
}

void srv_admit_destroy(srv_admit *a) { free(a); }

void srv_admit_tiles(srv_admit *a, unsigned codec, double cpu_s, double plane_samples)
{
    if (!a || codec >= PROTO_CODEC_COUNT_ || !(cpu_s >= 0) || !(plane_samples > 0)) return;
    atomic_fetch_add(&a->tile_ns[codec], (uint64_t)(cpu_s * 1e9));
    atomic_fetch_add(&a->tile_samples[codec], (uint64_t)plane_samples);
}

/* Busy seconds of every CPU of the host (all but idle and iowait: another
 * VM's steal is capacity this one does not get), from /proc/stat's first
 * line; -1 if it cannot be read. */
static double host_busy_s(const srv_admit *a)
{
    FILE *f = fopen("/proc/stat", "r");
    if (!f) return -1;
    unsigned long long v[8] = {0};
    int got = fscanf(f, "cpu %llu %llu %llu %llu %llu %llu %llu %llu", &v[0], &v[1], &v[2], &v[3], &v[4],
                     &v[5], &v[6], &v[7]);
    fclose(f);
    if (got < 4) return -1;
    unsigned long long busy = v[0] + v[1] + v[2] + v[5] + v[6] + v[7];
    return (double)busy / a->clk_tck;
}

static double self_s(void)
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0) return -1;
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
           1e-6 * (double)ru.ru_stime.tv_usec;
}

static double smooth(double old, double now, int first) { return first ? now : (1 - SMOOTH) * old + SMOOTH * now; }

/* Each codec's cost per plane-sample from what its tiles took since the
 * last sample (the calibration's tiles included). */
static void sample_codecs(srv_admit *a)
{
    for (int c = 0; c < PROTO_CODEC_COUNT_; c++) {
        uint64_t ns = atomic_load(&a->tile_ns[c]), n = atomic_load(&a->tile_samples[c]);
        double dn = (double)(n - a->seen_samples[c]);
        if (dn < MIN_SAMPLES) continue;
        double cost = 1e-9 * (double)(ns - a->seen_ns[c]) / dn;
        a->cost[c] = smooth(a->cost[c], cost, a->cost[c] == 0);
        a->seen_ns[c] = ns;
        a->seen_samples[c] = n;
    }
}

void srv_admit_sample(srv_admit *a, double now)
{
    if (!a) return;
    double dt = now - a->last_now;
    if (a->sampled && dt < SAMPLE_S) return;
    sample_codecs(a);
    double tiles = 0;
    for (int c = 0; c < PROTO_CODEC_COUNT_; c++) tiles += 1e-9 * (double)atomic_load(&a->tile_ns[c]);
    double busy = host_busy_s(a), self = self_s();
    if (a->sampled && self >= 0 && a->last_self_s >= 0) {
        double shared = fmax(0, ((self - a->last_self_s) - (tiles - a->last_tiles_s)) / dt);
        a->shared = smooth(a->shared, shared, 0);
        if (busy >= 0 && a->last_busy_s >= 0) {
            double others = fmax(0, ((busy - a->last_busy_s) - (self - a->last_self_s)) / dt);
            a->others = smooth(a->others, fmin(others, (double)a->ncpu), 0);
        }
    }
    a->sampled = 1;
    a->last_now = now;
    a->last_tiles_s = tiles;
    a->last_busy_s = busy;
    a->last_self_s = self;
}

/* The cost of a plane-sample in codec c: measured, else the dearest
 * measured (a codec none of whose tiles was made yet is not free). */
static double cost_of(const srv_admit *a, unsigned c)
{
    if (c < PROTO_CODEC_COUNT_ && a->cost[c] > 0) return a->cost[c];
    double most = 0;
    for (int i = 0; i < PROTO_CODEC_COUNT_; i++) most = fmax(most, a->cost[i]);
    return most;
}

/* Plane-samples a live layout-0 frame of sub makes, all its tiles new. */
static double frame_samples(const srv_config *cfg, const proto_subscribe *sub)
{
    double per = cfg->tiles_per_side, n = sub->tile_size;
    return per * per * sub->lod_levels * n * n * proto_tile_planes(srv_tiles_channels(sub->effects));
}

double srv_admit_price(const srv_admit *a, const srv_config *cfg, const proto_subscribe *sub)
{
    if (!a || sub->layout == PROTO_LAYOUT_CASCADE || sub->mode == PROTO_MODE_REPLAY) return 0;
    return frame_samples(cfg, sub) * sub->frame_rate_hz * cost_of(a, sub->codec);
}

void srv_admit_get_view(const srv_admit *a, const srv_config *cfg, srv_admit_view *v)
{
    memset(v, 0, sizeof *v);
    v->others = a->others;
    /* what other processes use is not all lost: the scheduler shares the
     * cores with them, so half of what the daemon could use stays usable */
    double most = fmin((double)a->workers, (double)a->ncpu);
    v->usable = fmax(0.5 * most, most - a->others);
    v->capacity = cfg->admit_share * v->usable;
    v->shared = a->shared;
    v->priced = a->priced;
    v->admitted = a->admitted;
}

static void refusal(const srv_admit *a, const srv_config *cfg, const proto_subscribe *sub, double price,
                    char *why, size_t n)
{
    srv_admit_view v;
    srv_admit_get_view(a, cfg, &v);
    int planes = proto_tile_planes(srv_tiles_channels(sub->effects));
    snprintf(why, n, "subscribe: over the daemon's capacity: this subscription's tiles would take %.3g "
             "cores (%.4g tile samples x %d planes x %g Hz x %.3g us a plane-sample in %s, measured here) "
             "beside the %.3g cores admitted work takes (%.3g shared, %.3g for %d layout-0 subscription%s), "
             "above the %.3g it may take (server.admit_share %g x %.3g cores usable: %d of server.workers, "
             "%.2g busy with other processes); ask for fewer or smaller tiles, a lower frame rate, a cheaper "
             "codec, or layout 1 (tiles every viewer shares)",
             price, frame_samples(cfg, sub) / planes, planes, (double)sub->frame_rate_hz,
             cost_of(a, sub->codec) * 1e6, proto_codec_name((proto_codec)sub->codec), v.shared + v.priced,
             v.shared, v.priced, v.admitted, v.admitted == 1 ? "" : "s", v.capacity, cfg->admit_share,
             v.usable, a->workers, v.others);
}

ocean_result srv_admit_take(srv_admit *a, const srv_config *cfg, const proto_subscribe *sub, double old,
                            double price, char *why, size_t n)
{
    if (!a) return OCEAN_OK;
    if (price > old && cfg->admit_share > 0) {
        srv_admit_view v;
        srv_admit_get_view(a, cfg, &v);
        if (v.shared + v.priced - old + price > v.capacity) {
            refusal(a, cfg, sub, price, why, n);
            return OCEAN_ETOOBIG;
        }
    }
    srv_admit_release(a, old);
    if (price > 0) {
        a->priced += price;
        a->admitted++;
    }
    return OCEAN_OK;
}

void srv_admit_release(srv_admit *a, double price)
{
    if (!a || !(price > 0)) return;
    a->priced = a->admitted > 1 ? fmax(0, a->priced - price) : 0;
    a->admitted--;
}
