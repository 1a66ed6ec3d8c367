/*
 * bench_core.c - the FFT core table of issue 2: what one evaluation costs
 * beside FFTW alone doing the same transforms.
 *
 * For N = 256, 512, 1024, the cumulative effect sets height; +displacement;
 * +normals; +foam, on 1 and 2 threads: the median ms of ocean_evaluate (the
 * spectrum stage h(k,t) and its channels, the batched inverse FFTs, the
 * Jacobian/foam pass) and, interleaved with it in the same run, the median
 * ms of ocean_transform_only (the very same FFTW plans on the same buffers:
 * FFTW alone).  The ratio is the median of the per-repetition ratios, so a
 * burst of machine load hits both halves of a pair alike.
 *
 * The table is made twice: with FFTW_ESTIMATE plans (the default) and with
 * FFTW_MEASURE plans (what ocean.plan = wisdom runs), N = 512 and 1024.
 *
 * Targets: issue 2, the full evaluation at N = 512 on 2 threads within
 * 1.15x of FFTW alone (ESTIMATE); issue 14, the same at N = 512 and 1024
 * with MEASURE plans, and the evaluation under a competing busy process no
 * worse than 1.5x its quiet time.  Verdict lines say whether each holds.
 * The floor table measures two oceans: the one-cascade default sea of the
 * main tables and the ocean `make run` serves (config/oceand.conf and its
 * scene through srv_settings_load, ocean.n set to 512 and 1024), and puts
 * each beside FFTW's whole-grid 2-D transform of the same spectra as well
 * as FFTW on the calls the evaluation makes (whose coarse cascades leave
 * out the column transforms of columns no wave reaches).
 * Also: packing two real channels into one complex transform, FFTW alone,
 * with both planners.
 *
 * Runs with OMP_WAIT_POLICY=passive unless the environment sets a policy,
 * as oceand does (server/main.c): it re-executes itself to set it, since
 * libgomp reads the variable once, when it loads.
 *
 * Prints markdown tables; writes tests/bench/out/core.csv.
 * BENCH_QUICK=1 (or OCEAN_BENCH_QUICK=1) shortens the run.
 */
#include <math.h>
#include <sched.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "../lib/bench_util.h"
#include <fftw3.h>

#include "ocean.h"
#include "ocean_internal.h"
#include "srv_config.h"

#define CONF_PATH "config/oceand.conf"

typedef struct fxset {
    const char *name;
    unsigned fx;
    int foam_map;
} fxset;

static const fxset sets[] = {
    {"height", OCEAN_FX_HEIGHT, 0},
    {"+displacement", OCEAN_FX_HEIGHT | OCEAN_FX_DISPLACEMENT, 0},
    {"+normals", OCEAN_FX_HEIGHT | OCEAN_FX_DISPLACEMENT | OCEAN_FX_NORMALS, 0},
    {"+foam", OCEAN_FX_ALL, 0},
    {"+foam +map", OCEAN_FX_ALL, 1},
};
#define NSETS ((int)(sizeof sets / sizeof sets[0]))
#define SET_FULL 3 /* "+foam": the evaluation as the daemon runs it */

/* The classic trick the issue asks to measure: two real channels packed
 * into one complex field, z = a + i b, cost one c2c transform instead of
 * two c2r.  FFTW alone, same sizes, same threads, same planner, interleaved:
 * 8 c2r against 4 c2c, and against 4 c2c followed by the pass that splits
 * each interleaved (a, b) output into the two planes a field is made of
 * (ocean_field channels are planar).  Returns c2c / c2r. */
static double packing_ratio(int n, int threads, int reps, unsigned flags, double *ms_c2r,
                            double *ms_c2c, double *ms_split)
{
    int h = n / 2 + 1, dims[2] = {n, n};
    size_t nn = (size_t)n * n;
    fftwf_complex *in = fftwf_malloc(sizeof(fftwf_complex) * 8 * (size_t)n * h);
    float *out = fftwf_malloc(sizeof(float) * 8 * nn);
    fftwf_complex *cin = fftwf_malloc(sizeof(fftwf_complex) * 4 * nn);
    fftwf_complex *cout = fftwf_malloc(sizeof(fftwf_complex) * 4 * nn);
    double r = NAN;
    if (in && out && cin && cout) {
        fftwf_plan_with_nthreads(threads);
        fftwf_plan pr = fftwf_plan_many_dft_c2r(2, dims, 8, in, NULL, 1, n * h, out, NULL, 1, n * n, flags);
        fftwf_plan pc = fftwf_plan_many_dft(2, dims, 4, cin, NULL, 1, n * n, cout, NULL, 1, n * n,
                                            FFTW_BACKWARD, flags);
        memset(in, 0, sizeof(fftwf_complex) * 8 * (size_t)n * h);
        memset(cin, 0, sizeof(fftwf_complex) * 4 * nn);
        double *a = malloc(sizeof(double) * reps * 3), *b = a + reps, *c = b + reps;
        for (int i = 0; i < reps; i++) {
            double t0 = bench_now_ms();
            fftwf_execute(pr);
            double t1 = bench_now_ms();
            fftwf_execute(pc);
            double t2 = bench_now_ms();
#pragma omp parallel for num_threads(threads) schedule(static)
            for (int k = 0; k < 4; k++) {
                const float *z = (const float *)cout[(size_t)k * nn];
                float *pa = out + (size_t)(2 * k) * nn, *pb = pa + nn;
                for (size_t j = 0; j < nn; j++) {
                    pa[j] = z[2 * j];
                    pb[j] = z[2 * j + 1];
                }
            }
            a[i] = t1 - t0;
            b[i] = t2 - t1;
            c[i] = bench_now_ms() - t1;
        }
        *ms_c2r = bench_median(a, reps);
        *ms_c2c = bench_median(b, reps);
        *ms_split = bench_median(c, reps);
        r = *ms_c2c / *ms_c2r;
        free(a);
        fftwf_destroy_plan(pr);
        fftwf_destroy_plan(pc);
    }
    fftwf_free(in);
    fftwf_free(out);
    fftwf_free(cin);
    fftwf_free(cout);
    return r;
}

typedef struct cell {
    double ms, fw, ratio;
    int transforms;
} cell;

/* The default sea at N = n on 2 threads with MEASURE plans, and a frame
 * for it: 0, or 1 (after saying why on stderr, `what` naming the table)
 * with *o and *f NULL. */
static int measure_default_sea(int n, const char *what, ocean **o, ocean_frame **f, char *msg,
                               size_t msglen)
{
    ocean_params p;
    ocean_params_default(&p);
    p.n = n;
    p.threads = 2;
    p.plan_measure = OCEAN_PLAN_MEASURE;
    *o = NULL;
    *f = NULL;
    if (ocean_create(&p, o, msg, msglen) != OCEAN_OK || ocean_frame_create(*o, f) != OCEAN_OK) {
        fprintf(stderr, "bench_core: %s, N=%d: %s\n", what, n, msg);
        ocean_destroy(*o);
        *o = NULL;
        return 1;
    }
    return 0;
}

/* One ocean per (N, threads, planner), every effects set on it: ms of
 * ocean_evaluate and of ocean_transform_only interleaved. */
static int measure_ocean(int n, int th, int plan, int quick, FILE *csv, cell out[NSETS])
{
    ocean_params p;
    ocean_params_default(&p);
    p.n = n;
    p.threads = th;
    p.plan_measure = plan;
    ocean *o = NULL;
    ocean_frame *f = NULL;
    char msg[600] = "";
    for (int e = 0; e < NSETS; e++)
        out[e] = (cell){NAN, NAN, NAN, 0};
    if (ocean_create(&p, &o, msg, sizeof msg) != OCEAN_OK || ocean_frame_create(o, &f) != OCEAN_OK) {
        fprintf(stderr, "bench_core: N=%d: %s\n", n, msg);
        ocean_destroy(o);
        return 1;
    }
    for (int e = 0; e < NSETS; e++) {
        ocean_request r;
        ocean_request_all(&r, sets[e].fx);
        r.foam_map = sets[e].foam_map;
        /* Enough repetitions for a stable median, bounded in time. */
        int reps = quick ? 5 : (n >= 1024 ? 15 : n >= 512 ? 31 : 61);
        double *a = malloc(sizeof(double) * reps * 3), *b = a + reps, *q = b + reps;
        ocean_evaluate(o, 0.0, &r, f);
        ocean_transform_only(o, &r, f);
        for (int i = 0; i < reps; i++) {
            /* Alternate which half goes first so neither always runs on a
             * warmer cache. */
            double t0 = bench_now_ms(), t1, t2;
            if (i % 2 == 0) {
                ocean_evaluate(o, 10.0 + i / 30.0, &r, f);
                t1 = bench_now_ms();
                ocean_transform_only(o, &r, f);
                t2 = bench_now_ms();
                a[i] = t1 - t0;
                b[i] = t2 - t1;
            } else {
                ocean_transform_only(o, &r, f);
                t1 = bench_now_ms();
                ocean_evaluate(o, 10.0 + i / 30.0, &r, f);
                t2 = bench_now_ms();
                b[i] = t1 - t0;
                a[i] = t2 - t1;
            }
            q[i] = a[i] / b[i];
        }
        ocean_frame_info info;
        ocean_frame_get_info(f, &info);
        out[e] = (cell){bench_median(a, reps), bench_median(b, reps), bench_median(q, reps), info.transforms};
        if (csv)
            fprintf(csv, "%d,%s,%d,%s,%d,%d,%.4f,%.4f,%.4f\n", n, sets[e].name, th,
                    plan == OCEAN_PLAN_MEASURE ? "measure" : "estimate", out[e].transforms, reps,
                    out[e].ms, out[e].fw, out[e].ratio);
        free(a);
    }
    ocean_frame_destroy(f);
    ocean_destroy(o);
    return 0;
}

/* The FFT table for one planner; ratios[si] gets the 2-thread "+foam" and
 * map_ratios[si] the "+foam +map" ratio of sizes[si]. */
static int core_table(const int *sizes, int nsizes, int plan, int quick, FILE *csv, double *ratios,
                      double *map_ratios)
{
    int failed = 0;
    printf("| N | effects | transforms | 1 thread ms | FFTW ms | ratio | 2 threads ms | FFTW ms | ratio |\n");
    printf("|---:|---|---:|---:|---:|---:|---:|---:|---:|\n");
    for (int si = 0; si < nsizes; si++) {
        cell c[2][NSETS];
        for (int th = 1; th <= 2; th++)
            failed |= measure_ocean(sizes[si], th, plan, quick, csv, c[th - 1]);
        for (int e = 0; e < NSETS; e++)
            printf("| %d | %s | %d | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f |\n", sizes[si], sets[e].name,
                   c[1][e].transforms, c[0][e].ms, c[0][e].fw, c[0][e].ratio, c[1][e].ms, c[1][e].fw,
                   c[1][e].ratio);
        ratios[si] = c[1][SET_FULL].ratio;
        map_ratios[si] = c[1][SET_FULL + 1].ratio;
        fflush(stdout);
    }
    return failed;
}

/* What each spectrum-stage path contributes (issue 14): the full
 * evaluation (+foam, 2 threads, MEASURE plans) with the plain row pass,
 * the AVX2+FMA pass, the AVX-512 pass, the widest pass with streaming
 * stores, and the widest pass reading every frequency from memory (deep
 * water's too: ocean_force_frequency_table), each interleaved with FFTW
 * alone on one ocean (ocean_force_paths; all give the same bits,
 * tests/test_ocean.c); a
 * pass the CPU lacks is labelled with the one that ran.  Every path already takes one
 * phase per mirror-row pair.  Returns 0, or 1 when the ocean could not be
 * made. */
static int stage_paths(int n, int quick)
{
    ocean *o;
    ocean_frame *f;
    char msg[600] = "";
    if (measure_default_sea(n, "stage paths", &o, &f, msg, sizeof msg))
        return 1;
    enum { PATHS = 5 };
    /* table: every frequency read from memory, deep water's too (the
     * stage before it computed deep water's). */
    static const struct { int fused, stream, table; } path[PATHS] = {
        {0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {2, 1, 0}, {2, 0, 1}};
    static const char *const pass_name[] = {"plain row pass", "AVX2+FMA", "AVX-512"};
    int ran[PATHS];
    for (int k = 0; k < PATHS; k++)
        ran[k] = ocean_force_paths(o, path[k].fused, path[k].stream);
    int best = ocean_force_paths(o, -1, -1);
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_ALL);
    r.foam_map = 0;
    int reps = quick ? 5 : (n >= 1024 ? 15 : 41);
    double *ms = malloc(sizeof(double) * reps * (PATHS + 2)), *fw = ms + PATHS * reps, *q = fw + reps;
    for (int i = 0; i < reps; i++) {
        double t0 = bench_now_ms();
        ocean_transform_only(o, &r, f);
        fw[i] = bench_now_ms() - t0;
        for (int k = 0; k < PATHS; k++) {
            int pk = (i + k) % PATHS; /* rotate which path goes first */
            ocean_force_paths(o, path[pk].fused, path[pk].stream);
            ocean_force_frequency_table(o, path[pk].table);
            t0 = bench_now_ms();
            ocean_evaluate(o, 10.0 + i / 30.0 + pk, &r, f);
            ms[pk * reps + i] = bench_now_ms() - t0;
        }
    }
    for (int k = 0; k < PATHS; k++) {
        for (int i = 0; i < reps; i++)
            q[i] = ms[k * reps + i] / fw[i];
        printf("| %d | %s%s%s%s%s | %.3f | %.3f | %.3f |\n", n, pass_name[ran[k]],
               ran[k] != path[k].fused ? " (the CPU lacks the wider pass)" : "",
               path[k].stream ? ", streaming stores" : "",
               path[k].table ? ", every frequency read from memory (deep water's too)" : "",
               ran[k] == best && !path[k].stream && !path[k].table ? " **(default)**" : "",
               bench_median(ms + k * reps, reps), bench_median(fw, reps), bench_median(q, reps));
    }
    ocean_force_paths(o, -1, -1);
    ocean_force_frequency_table(o, 0);
    free(ms);
    ocean_frame_destroy(f);
    ocean_destroy(o);
    return 0;
}

/* The floor under the target (issue 14): the full evaluation (+foam, 2
 * threads, MEASURE plans) of the ocean *p0 at N = n, FFTW alone, and FFTW
 * alone with each call's spectra first written (ocean_transform_floor:
 * zeros, split as the stage splits them; the least a stage that writes what FFTW
 * reads can cost), the three interleaved, the first of each repetition
 * rotating.  Prints a row labelled `label`; *ratio gets evaluation / FFTW.
 * Returns 0, or 1 when the ocean could not be made. */
/* Where one row of the floor table's evaluation time went (medians over
 * its repetitions, ms; ocean_counters' ns_* deltas). */
typedef struct split_row {
    char label[96];
    int n;
    double eval, fftw_alone, fft_in_eval, evolve, channels, rest;
    /* pruning (ocean_force_pruning): FFTW alone and the evaluation on the
     * whole-grid 2-D plans, the evaluation over that FFTW, and the FFTW
     * calls per evaluation that pruned, of all */
    double fftw_whole, eval_whole, ratio_whole, ratio_whole_whole;
    int calls, pruned;
} split_row;

static int floor_table(const ocean_params *p0, const char *label, int n, int quick, double *ratio,
                       split_row *sp)
{
    ocean_params p = *p0;
    p.n = n;
    p.threads = 2;
    p.plan_measure = OCEAN_PLAN_MEASURE;
    ocean *o = NULL;
    ocean_frame *f = NULL;
    char msg[600] = "";
    *ratio = NAN;
    if (ocean_create(&p, &o, msg, sizeof msg) != OCEAN_OK || ocean_frame_create(o, &f) != OCEAN_OK) {
        fprintf(stderr, "bench_core: %s, N=%d: %s\n", label, n, msg);
        printf("| %s | %d | %d | (not measured: %s) | | | | | | |\n", label, n, p.cascades, msg);
        ocean_destroy(o);
        return 1;
    }
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_ALL);
    r.foam_map = 0;
    int reps = quick ? 6 : (n * p.cascades >= 1024 ? 30 : 60);
    enum { W = 5 }; /* evaluation, FFTW alone, floor, both on the whole-grid plans */
    double *m = malloc(sizeof(double) * reps * (2 * W + 4)), *q = m + W * reps, *ev = q + W * reps,
           *ch = ev + reps, *ff = ch + reps, *rest = ff + reps;
    ocean_counters k0, k1;
    ocean_get_counters(o, &k0);
    ocean_evaluate(o, 1.0, &r, f);
    ocean_get_counters(o, &k1);
    int calls = (int)(k1.fft_calls - k0.fft_calls), pruned = (int)(k1.fft_calls_pruned - k0.fft_calls_pruned);
    ocean_transform_floor(o, &r, f);
    ocean_transform_only(o, &r, f);
    ocean_force_pruning(o, 0);
    ocean_evaluate(o, 2.0, &r, f);
    ocean_transform_only(o, &r, f);
    ocean_force_pruning(o, 1);
    for (int i = 0; i < reps; i++)
        for (int k = 0; k < W; k++) {
            int w = (i + k) % W;
            ocean_counters c0, c1;
            ocean_get_counters(o, &c0);
            ocean_force_pruning(o, w < 3);
            double t0 = bench_now_ms();
            if (w == 0 || w == 4)
                ocean_evaluate(o, 10.0 + i / 30.0 + (w == 4 ? 0.5 / 30.0 : 0.0), &r, f);
            else if (w == 1 || w == 3)
                ocean_transform_only(o, &r, f);
            else
                ocean_transform_floor(o, &r, f);
            m[w * reps + i] = bench_now_ms() - t0;
            ocean_force_pruning(o, 1);
            if (w == 0) {
                ocean_get_counters(o, &c1);
                ev[i] = (double)(c1.ns_evolve - c0.ns_evolve) * 1e-6;
                ch[i] = (double)(c1.ns_channels - c0.ns_channels) * 1e-6;
                ff[i] = (double)(c1.ns_fft - c0.ns_fft) * 1e-6;
                rest[i] = m[i] - ev[i] - ch[i] - ff[i];
            }
        }
    double med[W], rat[5];
    for (int w = 0; w < W; w++)
        med[w] = bench_median(m + w * reps, reps);
    /* per-repetition ratios: floor / FFTW, evaluation / FFTW, evaluation /
     * floor, evaluation / whole-grid FFTW, whole-grid evaluation / it */
    static const int num[5] = {2, 0, 0, 0, 4}, den[5] = {1, 1, 2, 3, 3};
    for (int k = 0; k < 5; k++) {
        for (int i = 0; i < reps; i++)
            q[i] = m[num[k] * reps + i] / m[den[k] * reps + i];
        rat[k] = bench_median(q, reps);
    }
    ocean_frame_info info;
    ocean_frame_get_info(f, &info);
    printf("| %s | %d | %d | %d | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f |\n", label, n, p.cascades,
           info.transforms, med[1], med[2], rat[0], med[0], rat[1], rat[2], med[0] - med[2]);
    *ratio = rat[1];
    *sp = (split_row){"", n, med[0], med[1], bench_median(ff, reps), bench_median(ev, reps),
                      bench_median(ch, reps), bench_median(rest, reps), med[3], med[4], rat[3], rat[4],
                      calls, pruned};
    snprintf(sp->label, sizeof sp->label, "%s", label);
    free(m);
    ocean_frame_destroy(f);
    ocean_destroy(o);
    return 0;
}

/* How the stage splits a call over the threads (ocean_force_stage_split),
 * one cascade of the default sea at N = n (+foam, 2 threads, MEASURE
 * plans): the evaluation split by rows, by channel, and as oceand runs it
 * (the split measured faster), and the floor (zero writes) split each
 * way, all interleaved with FFTW alone, the first of each repetition
 * rotating.  *ratio gets the default's evaluation / FFTW alone.  Returns 0,
 * or 1 when the ocean could not be made. */
#define SPLITS 5
static int split_table(int n, int quick, double *ratio)
{
    ocean *o;
    ocean_frame *f;
    char msg[600] = "";
    *ratio = NAN;
    if (measure_default_sea(n, "split table", &o, &f, msg, sizeof msg)) {
        printf("| %d | (not measured: %s) | | | |\n", n, msg);
        return 1;
    }
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_ALL);
    r.foam_map = 0;
    static const char *const names[SPLITS] = {
        "evaluation, by rows", "evaluation, by channel", "evaluation, the split measured faster **(default)**",
        "FFTW + writes (zeros), by rows", "FFTW + writes (zeros), by channel"};
    static const int mode[SPLITS] = {0, 1, -1, 0, 1};
    int reps = quick ? 6 : (n >= 1024 ? 30 : 60);
    double *m = malloc(sizeof(double) * reps * SPLITS * 3), *fw = m + SPLITS * reps, *q = fw + SPLITS * reps;
    ocean_evaluate(o, 1.0, &r, f);
    ocean_transform_only(o, &r, f);
    /* Each run right after its own FFTW alone, so every one follows the
     * same kind of work (an evaluation right after another finds some of
     * its inputs still cached). */
    for (int i = 0; i < reps; i++)
        for (int k = 0; k < SPLITS; k++) {
            int w = (i + k) % SPLITS;
            double t0 = bench_now_ms();
            ocean_transform_only(o, &r, f);
            double t1 = bench_now_ms();
            ocean_force_stage_split(o, mode[w]);
            if (w < 3)
                ocean_evaluate(o, 10.0 + i / 30.0 + w * 1e-3, &r, f);
            else
                ocean_transform_floor(o, &r, f);
            double t2 = bench_now_ms();
            fw[w * reps + i] = t1 - t0;
            m[w * reps + i] = t2 - t1;
        }
    ocean_force_stage_split(o, -1);
    for (int w = 0; w < SPLITS; w++) {
        for (int i = 0; i < reps; i++)
            q[i] = m[w * reps + i] / fw[w * reps + i];
        double rq = bench_median(q, reps);
        if (w == 2)
            *ratio = rq;
        printf("| %d | %s | %.3f | %.3f | %.3f |\n", n, names[w], bench_median(m + w * reps, reps),
               bench_median(fw + w * reps, reps), rq);
    }
    free(m);
    ocean_frame_destroy(f);
    ocean_destroy(o);
    return 0;
}

/* Channels per FFTW call (ocean_force_group): the full evaluation (+foam, 8
 * transforms, MEASURE plans, 2 threads) with the default rule (at most
 * 8.5 MB of spectra a call) and with 8, 4, 2 and 1 channels a call, each
 * interleaved with FFTW alone on the same grouping, and beside FFTW alone
 * in one call of 8 (the plan oceand used before).  Prints rows; *ratio_def
 * gets the default's ratio to FFTW alone on its own grouping and
 * *ratio_one its ratio to FFTW alone in one call.  Returns 0, or 1 when
 * the ocean could not be made. */
static int group_table(int n, int quick, double *ratio_def, double *ratio_one)
{
    ocean *o;
    ocean_frame *f;
    char msg[600] = "";
    *ratio_def = *ratio_one = NAN;
    if (measure_default_sea(n, "channels per call", &o, &f, msg, sizeof msg))
        return 1;
    enum { NG = 5 };
    static const int gs[NG] = {0, 8, 4, 2, 1};
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_ALL);
    r.foam_map = 0;
    int reps = quick ? 5 : (n >= 1024 ? 15 : 41);
    double *ms = malloc(sizeof(double) * reps * NG * 4), *fw = ms + reps * NG, *q = fw + reps * NG,
           *q1 = q + reps * NG;
    uint64_t calls[NG] = {0};
    for (int i = 0; i < reps; i++) {
        for (int k = 0; k < NG; k++) {
            int g = (i + k) % NG; /* rotate which grouping goes first */
            ocean_force_group(o, gs[g]);
            /* One untimed round on this grouping first, so the timed one
             * finds the caches as its own previous round left them, not as
             * another grouping's did. */
            ocean_evaluate(o, 5.0 + i / 30.0 + g, &r, f);
            ocean_transform_only(o, &r, f);
            ocean_counters c0, c1;
            ocean_get_counters(o, &c0);
            double t0 = bench_now_ms();
            ocean_evaluate(o, 10.0 + i / 30.0 + g, &r, f);
            double t1 = bench_now_ms();
            ocean_get_counters(o, &c1);
            ocean_transform_only(o, &r, f);
            double t2 = bench_now_ms();
            ms[g * reps + i] = t1 - t0;
            fw[g * reps + i] = t2 - t1;
            calls[g] = c1.fft_calls - c0.fft_calls;
        }
        for (int g = 0; g < NG; g++) {
            q[g * reps + i] = ms[g * reps + i] / fw[g * reps + i];
            q1[g * reps + i] = ms[g * reps + i] / fw[1 * reps + i];
        }
    }
    for (int g = 0; g < NG; g++) {
        char name[48];
        if (gs[g] == 0)
            snprintf(name, sizeof name, "**default: %d**", 8 / (int)(calls[g] ? calls[g] : 1));
        else
            snprintf(name, sizeof name, "%d", gs[g]);
        double rq = bench_median(q + g * reps, reps), r1 = bench_median(q1 + g * reps, reps);
        printf("| %d | %s | %llu | %.3f | %.3f | %.3f | %.3f |\n", n, name, (unsigned long long)calls[g],
               bench_median(ms + g * reps, reps), bench_median(fw + g * reps, reps), rq, r1);
        if (gs[g] == 0) {
            *ratio_def = rq;
            *ratio_one = r1;
        }
    }
    ocean_force_group(o, 0);
    free(ms);
    ocean_frame_destroy(f);
    ocean_destroy(o);
    return 0;
}

/* The child of policy_table: median ms of the full evaluation and of FFTW
 * alone at N (MEASURE, 2 threads), printed as "ms fftw ratio". */
static int policy_child(int n, int quick)
{
    ocean *o;
    ocean_frame *f;
    char msg[600] = "";
    if (measure_default_sea(n, "wait policy", &o, &f, msg, sizeof msg))
        return 1;
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_ALL);
    r.foam_map = 0;
    int reps = quick ? 5 : (n >= 1024 ? 21 : 61);
    double *a = malloc(sizeof(double) * reps * 3), *b = a + reps, *q = b + reps;
    ocean_evaluate(o, 0.0, &r, f);
    for (int i = 0; i < reps; i++) {
        double t0 = bench_now_ms();
        ocean_evaluate(o, 10.0 + i / 30.0, &r, f);
        double t1 = bench_now_ms();
        ocean_transform_only(o, &r, f);
        double t2 = bench_now_ms();
        a[i] = t1 - t0;
        b[i] = t2 - t1;
        q[i] = a[i] / b[i];
    }
    printf("%.4f %.4f %.4f\n", bench_median(a, reps), bench_median(b, reps), bench_median(q, reps));
    free(a);
    ocean_frame_destroy(f);
    ocean_destroy(o);
    return 0;
}

/* Runs this program again as "bench_core ARGS..." in a fresh process
 * (libgomp reads the policy when it loads) with OMP_WAIT_POLICY=passive
 * and GOMP_SPINCOUNT=spin, its standard output read into buf.  Returns 0
 * when it exited with 0, else -1. */
static int child_run(const char *spin, const char *a1, const char *a2, const char *a3, char *buf,
                     size_t size)
{
    int fd[2];
    buf[0] = 0;
    if (pipe(fd) != 0)
        return -1;
    fflush(stdout);
    pid_t pid = fork();
    if (pid == 0) {
        dup2(fd[1], 1);
        close(fd[0]);
        close(fd[1]);
        setenv("OMP_WAIT_POLICY", "passive", 1);
        setenv("GOMP_SPINCOUNT", spin, 1);
        execl("/proc/self/exe", "bench_core", a1, a2, a3, (char *)NULL);
        _exit(127);
    }
    close(fd[1]);
    if (pid < 0) {
        close(fd[0]);
        return -1;
    }
    size_t got = 0;
    ssize_t k;
    while (got < size - 1 && (k = read(fd[0], buf + got, size - 1 - got)) > 0)
        got += (size_t)k;
    buf[got] = 0;
    close(fd[0]);
    int st = 0;
    waitpid(pid, &st, 0);
    return WIFEXITED(st) && WEXITSTATUS(st) == 0 ? 0 : -1;
}

/* policy_child at N in a fresh process with GOMP_SPINCOUNT=spin: 0 and
 * out[3] = ms, FFTW ms, ratio; or -1. */
static int policy_run(int n, const char *spin, int quick, double out[3])
{
    char ns[16], buf[256];
    snprintf(ns, sizeof ns, "%d", n);
    if (child_run(spin, "--policy-child", ns, quick ? "1" : "0", buf, sizeof buf) != 0 ||
        sscanf(buf, "%lf %lf %lf", &out[0], &out[1], &out[2]) != 3)
        return -1;
    return 0;
}

/* A process that only burns CPU, optionally pinned to one CPU.  Started
 * stopped; the caller toggles it with SIGCONT / SIGSTOP. */
static pid_t spinner(int cpu)
{
    pid_t pid = fork();
    if (pid == 0) {
        if (cpu >= 0) {
            cpu_set_t set;
            CPU_ZERO(&set);
            CPU_SET(cpu, &set);
            sched_setaffinity(0, sizeof set, &set);
        }
        raise(SIGSTOP);
        volatile unsigned long x = 0;
        for (;;)
            x++;
    }
    if (pid > 0) {
        int st;
        waitpid(pid, &st, WUNTRACED);
    }
    return pid;
}

/* Median ms of the full evaluation at N on 2 threads, quiet and while a
 * busy process holds a core, interleaved rep by rep (the spinner is
 * stopped and continued) so a slow spell of the machine hits both. */
static double contention(int n, int cpu, int reps, double *quiet_ms, double *busy_ms)
{
    ocean_params p;
    ocean_params_default(&p);
    p.n = n;
    p.threads = 2;
    ocean *o = NULL;
    ocean_frame *f = NULL;
    char msg[600];
    *quiet_ms = *busy_ms = NAN;
    if (ocean_create(&p, &o, msg, sizeof msg) != OCEAN_OK || ocean_frame_create(o, &f) != OCEAN_OK) {
        ocean_destroy(o);
        return NAN;
    }
    pid_t sp = spinner(cpu);
    if (sp < 0) {
        ocean_frame_destroy(f);
        ocean_destroy(o);
        return NAN;
    }
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_ALL);
    r.foam_map = 0;
    double *a = malloc(sizeof(double) * reps * 2), *b = a + reps;
    ocean_evaluate(o, 0.0, &r, f);
    for (int i = 0; i < reps; i++) {
        double t0 = bench_now_ms();
        ocean_evaluate(o, 10.0 + i / 30.0, &r, f);
        a[i] = bench_now_ms() - t0;
        kill(sp, SIGCONT);
        /* Let it take its core: a few scheduler ticks. */
        struct timespec ts = {0, 20 * 1000 * 1000};
        nanosleep(&ts, NULL);
        t0 = bench_now_ms();
        ocean_evaluate(o, 20.0 + i / 30.0, &r, f);
        b[i] = bench_now_ms() - t0;
        kill(sp, SIGSTOP);
    }
    kill(sp, SIGKILL);
    waitpid(sp, NULL, 0);
    *quiet_ms = bench_median(a, reps);
    *busy_ms = bench_median(b, reps);
    free(a);
    ocean_frame_destroy(f);
    ocean_destroy(o);
    return *busy_ms / *quiet_ms;
}

static int contention_child(int quick, const char *label);

int main(int argc, char **argv)
{
    /* As oceand: a spinning OpenMP barrier waits out a whole time slice
     * whenever another process holds the core a team member needs. */
    if (argc == 4 && strcmp(argv[1], "--policy-child") == 0)
        return policy_child(atoi(argv[2]), atoi(argv[3]));
    if (argc == 4 && strcmp(argv[1], "--contention-child") == 0)
        return contention_child(atoi(argv[2]), strcmp(argv[3], "oceand") == 0 ?
                                "passive (oceand)" : "passive + spin " OCEAN_GOMP_SPINCOUNT);
    if (ocean_wait_policy_setenv(1))
        execv("/proc/self/exe", argv);
    char policy[96];
    snprintf(policy, sizeof policy, "%s%s%s", getenv("OMP_WAIT_POLICY"),
             getenv("GOMP_SPINCOUNT") ? ", GOMP_SPINCOUNT=" : "",
             getenv("GOMP_SPINCOUNT") ? getenv("GOMP_SPINCOUNT") : "");
    int quick = bench_quick();
    const int est_sizes[] = {256, 512, 1024}, mea_sizes[] = {512, 1024};
    /* The ocean `make run` serves, loaded as oceand loads it with ocean.n
     * set to each size (so the near field's edge, k_max = pi n / L_finest,
     * follows N as it would in the daemon). */
    ocean_params served[2];
    char served_name[160] = "served scene", served_err[512] = "";
    int served_ok = 1;
    for (int i = 0; i < 2 && served_ok; i++) {
        srv_settings S;
        char set[32];
        snprintf(set, sizeof set, "ocean.n=%d", mea_sizes[i]);
        const char *sets[1] = {set};
        served_ok = srv_settings_load(CONF_PATH, sets, 1, &S, served_err, sizeof served_err) == OCEAN_OK;
        if (served_ok) {
            served[i] = S.params;
            snprintf(served_name, sizeof served_name, "served: %s", S.scene.name[0] ? S.scene.name : "no scene");
        }
    }
    FILE *csv = fopen("tests/bench/out/core.csv", "w");
    if (csv)
        fprintf(csv, "n,effects,threads,plan,transforms,reps,ms,ms_fftw,ratio\n");
    printf("### FFT core: ms per evaluation beside FFTW alone (issues 2 and 14)\n\n");
    printf("One cascade, default sea (Pierson-Moskowitz 10 m/s, 1000 m patch), OMP_WAIT_POLICY=%s. "
           "`ms` is the median ocean_evaluate, `FFTW` the median ocean_transform_only (the same "
           "plans on the same buffers), interleaved in the same run; `ratio` is the median of the "
           "per-repetition ratios.\n\n", policy);
    printf("#### FFTW_ESTIMATE plans (ocean.plan = estimate, the default)\n\n");
    double est[3], est_map[3], mea[2], mea_map[2];
    int failed = core_table(est_sizes, 3, OCEAN_PLAN_ESTIMATE, quick, csv, est, est_map);
    printf("\n#### FFTW_MEASURE plans (ocean.plan = measure, or wisdom written by `ocean-sim wisdom`)\n\n");
    failed |= core_table(mea_sizes, 2, OCEAN_PLAN_MEASURE, quick, csv, mea, mea_map);
    if (csv)
        fclose(csv);
    printf("\n`+foam` is the full evaluation as the daemon runs it: all 8 transforms, with J and "
           "foam formed from Dxx, Dzz, Dxz wherever a point is sampled. `+foam +map` also fills "
           "the whole-field J and foam planes (request foam_map: baking, statistics), one more "
           "pass over 5 floats per point.\n\n");
    printf("Target (issue 2): full evaluation at N = 512 on 2 threads within 1.15x of FFTW alone "
           "(ESTIMATE plans): measured %.3fx - %s; with the whole-field foam map %.3fx.\n\n", est[1],
           isnan(est[1]) ? "NOT MEASURED" : est[1] <= 1.15 ? "met" : "NOT met", est_map[1]);
    for (int i = 0; i < 2; i++)
        printf("Target (issue 14): full evaluation at N = %d on 2 threads within 1.15x of FFTW alone "
               "with MEASURE plans: measured %.3fx - %s; with the whole-field foam map %.3fx.\n\n",
               mea_sizes[i], mea[i], isnan(mea[i]) ? "NOT MEASURED" : mea[i] <= 1.15 ? "met" : "NOT met",
               mea_map[i]);

    printf("#### The floor under the target, and the ocean `make run` serves (MEASURE plans, "
           "2 threads, +foam)\n\n");
    printf("An evaluation has to write the spectra FFTW reads: 8 x N x (N/2+1) complex floats a "
           "cascade, 34 MB at N = 1024 (in calls of 2 channels) and 8.4 MB at N = 512. `FFTW + "
           "writes` is FFTW alone with each call's spectra first overwritten with zeros, split "
           "over the threads as the stage splits them (the split it has measured faster, next table "
           "but one): no arithmetic, no inputs read, so no stage "
           "that writes what FFTW reads can cost less. The stage also reads the inputs of "
           "each mode that holds a wave (its standing-wave coefficients a and b, 16 bytes; and, "
           "where k d < 22, w/2pi in two doubles shared by rows mz and -mz: deep water's it "
           "computes) and keeps h(k,t) for the later calls. The three are interleaved; ratios are "
           "medians of per-repetition ratios. Two oceans: the one-cascade default sea of the tables "
           "above, every mode of its grid a wave; and the ocean of the scene `make run` serves "
           "(%s: config/oceand.conf and its scene, as oceand loads them, ocean.n raised to N), "
           "whose coarse cascades stop at half their Nyquist and whose finest stops at its Nyquist "
           "circle (the near field takes over there), so the stage touches 38.5 %% of its modes.\n\n", served_name);
    printf("| ocean | N | cascades | transforms | FFTW alone ms | FFTW + writes ms | floor / FFTW | "
           "evaluation ms | evaluation / FFTW | evaluation / floor | evaluation - floor ms |\n"
           "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    double served_ratio[2] = {NAN, NAN}, one_ratio[2];
    split_row split[4];
    int nsplit = 0;
    {
        ocean_params dp;
        ocean_params_default(&dp);
        for (int i = 0; i < 2; i++)
            if (floor_table(&dp, "one cascade, default sea", mea_sizes[i], quick, &one_ratio[i],
                            &split[nsplit]) == 0)
                nsplit++;
            else
                failed = 1;
        for (int i = 0; i < 2 && served_ok; i++)
            if (floor_table(&served[i], served_name, mea_sizes[i], quick, &served_ratio[i],
                            &split[nsplit]) == 0)
                nsplit++;
            else
                failed = 1;
    }
    printf("\n");
    printf("Where each evaluation of that table went (medians over its repetitions, ms). `FFTW in "
           "the evaluation` is the time inside its FFTW calls, beside the same calls alone; the "
           "stage's passes are timed as the ocean counts them (ocean_counters: ns_evolve, the pass "
           "of each cascade's first call, which evolves h(k,t) and writes that call's spectra; "
           "ns_channels, the later calls' passes, which read h(k,t) back from the tick's cache); "
           "`other` is the rest of ocean_evaluate (request checks, filter memos).\n\n");
    printf("| ocean | N | evaluation ms | FFTW alone ms | FFTW in the evaluation ms | evolving pass ms | "
           "later passes ms | other ms | stage / FFTW alone |\n"
           "|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (int i = 0; i < nsplit; i++)
        printf("| %s | %d | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f |\n", split[i].label,
               split[i].n, split[i].eval, split[i].fftw_alone, split[i].fft_in_eval, split[i].evolve,
               split[i].channels, split[i].rest,
               (split[i].evolve + split[i].channels) / split[i].fftw_alone);
    printf("\n");
    printf("The column pass a band leaves out (same table's runs): a 2-D c2r is a c2c down each of "
           "the N/2+1 columns of the half spectrum, then a c2r along each row. A coarse cascade's "
           "waves (a half disc of radius N/4) lie in the first N/4 columns; the others are zero "
           "and stay zero through the first pass, so the ocean runs it on those N/4 columns only "
           "(ocean_counters.fft_calls_pruned; the same transform, checked against the whole-grid "
           "plans by test_ocean's pruned_column_pass). `FFTW alone` above is FFTW on the calls the "
           "evaluation makes; here beside FFTW's whole-grid 2-D c2r of the same spectra (what "
           "FFTW alone costs when nothing is known of the band, as every row above measured before) "
           "and the evaluation run on those whole-grid plans (ocean_force_pruning(o, 0)), all "
           "interleaved with the table's runs.\n\n");
    printf("| ocean | N | FFTW calls pruned | FFTW alone, whole-grid 2-D ms | FFTW alone, the calls made ms | "
           "evaluation, whole-grid plans ms | evaluation ms | whole-grid evaluation / whole-grid FFTW | "
           "evaluation / whole-grid FFTW |\n"
           "|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (int i = 0; i < nsplit; i++)
        printf("| %s | %d | %d of %d | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f |\n", split[i].label,
               split[i].n, split[i].pruned, split[i].calls, split[i].fftw_whole, split[i].fftw_alone,
               split[i].eval_whole, split[i].eval, split[i].ratio_whole_whole, split[i].ratio_whole);
    printf("\n");
    if (!served_ok)
        printf("_The served ocean was not measured: %s._\n\n", served_err);
    for (int i = 0; i < 2; i++) {
        double whole = NAN;
        for (int j = 0; j < nsplit; j++)
            if (split[j].n == mea_sizes[i] && strcmp(split[j].label, served_name) == 0)
                whole = split[j].ratio_whole;
        printf("Target (issue 14), this table: full evaluation at N = %d within 1.15x of FFTW alone with "
               "MEASURE plans: the served ocean %.3fx of FFTW on the calls it makes - %s, %.3fx of "
               "FFTW's whole-grid 2-D transform of its spectra - %s; one full-band cascade %.3fx - %s.\n\n",
               mea_sizes[i], served_ratio[i],
               isnan(served_ratio[i]) ? "NOT MEASURED" : served_ratio[i] <= 1.15 ? "met" : "NOT met",
               whole, isnan(whole) ? "NOT MEASURED" : whole <= 1.15 ? "met" : "NOT met",
               one_ratio[i], isnan(one_ratio[i]) ? "NOT MEASURED" : one_ratio[i] <= 1.15 ? "met" : "NOT met");
    }

    printf("#### How the stage splits a call over the threads (same bits, MEASURE plans, 2 threads, "
           "+foam)\n\n");
    printf("FFTW's threaded plan for a call of several channels gives each thread whole channels (a "
           "block of the batch). A stage pass split by rows makes every thread write part of every "
           "channel, so each FFTW thread then reads half its spectra from the core that wrote them; "
           "split by channel, each thread writes the channels its FFTW thread will transform, but "
           "every thread reads all of h(k,t) and an evolving pass takes two steps (its own rows "
           "from h in L1, then, after a barrier, the other rows from the cache). Which costs less "
           "depends on how busy the shared caches are: on this VM the row split's cross-core reads "
           "cost FFTW 10-20 %% in some minutes and nothing in others. So oceand measures both per "
           "cascade and grid (ns per channel of the passes and FFTW calls together, the least of "
           "each split's last 8), runs the faster and tries the other every 16th evaluation. One "
           "cascade of the default sea; each run right after its own FFTW alone on the same plans "
           "and buffers, the rows rotating; ratios the medians of per-repetition ratios.\n\n");
    printf("| N | stage split | ms | FFTW ms | ratio |\n|---:|---|---:|---:|---:|\n");
    double split_ratio[2] = {NAN, NAN};
    for (int i = 0; i < 2; i++)
        failed |= split_table(mea_sizes[i], quick, &split_ratio[i]);
    printf("\n");
    for (int i = 0; i < 2; i++)
        printf("Target (issue 14), this table: full evaluation at N = %d within 1.15x of FFTW alone with "
               "MEASURE plans (oceand's split): %.3fx - %s.\n\n", mea_sizes[i], split_ratio[i],
               isnan(split_ratio[i]) ? "NOT MEASURED" : split_ratio[i] <= 1.15 ? "met" : "NOT met");

    printf("#### The spectrum stage's paths (same bits, MEASURE plans, 2 threads, +foam)\n\n");
    printf("One ocean, its paths forced in turn and interleaved with FFTW alone on the same plans "
           "and buffers; every path takes one phase and sin/cos per pair of rows mz, -mz (same "
           "|k|, same w). The AVX2+FMA pass forms the phase product's error with one fused "
           "multiply-add (exact, as the plain pass's Dekker product is); the AVX-512 pass is the "
           "same source 16 floats wide, with registers enough to keep the sin/cos coefficients "
           "(AVX2 reloads them from the stack); streaming stores write the spectra without first "
           "reading the lines, forced here at both sizes (oceand streams only spectra over twice "
           "the last-level cache: none at N <= 1024 on this machine). The last row reads every "
           "mode's frequency from its table, as the stage did before it computed deep water's "
           "(k d >= 22: sqrt(g k) / 2 pi from the integer wave vector; same bits). **(default)** "
           "marks the pass oceand runs on this CPU.\n\n");
    printf("| N | path | ms | FFTW ms | ratio |\n|---:|---|---:|---:|---:|\n");
    for (int i = 0; i < 2; i++)
        failed |= stage_paths(mea_sizes[i], quick);
    printf("\n");

    printf("#### Channels per FFTW call (MEASURE plans, 2 threads, +foam)\n\n");
    printf("oceand hands FFTW the channels in groups of at most 8.5 MB of spectra (a constant, so "
           "every replica runs the same plans): at N = 1024 the 8 spectra are 34 MB, more than the "
           "last-level cache, and one call of 8 read them back from memory. Each grouping is "
           "interleaved with FFTW alone on the same calls; the last column divides by FFTW alone "
           "in one call of 8, the plan oceand used before.\n\n");
    printf("| N | channels a call | FFTW calls | ms | FFTW ms (same calls) | ratio | ms / FFTW in one call |\n"
           "|---:|---|---:|---:|---:|---:|---:|\n");
    double g_def[2], g_one[2];
    for (int i = 0; i < 2; i++)
        failed |= group_table(mea_sizes[i], quick, &g_def[i], &g_one[i]);
    printf("\n");
    for (int i = 0; i < 2; i++)
        printf("Target (issue 14), this table: full evaluation at N = %d within 1.15x of FFTW alone "
               "with MEASURE plans: %.3fx of FFTW alone on the same calls - %s; %.3fx of FFTW alone "
               "in one call of 8.\n\n", mea_sizes[i], g_def[i],
               isnan(g_def[i]) ? "NOT MEASURED" : g_def[i] <= 1.15 ? "met" : "NOT met", g_one[i]);

    printf("#### OpenMP wait policy (MEASURE plans, 2 threads, +foam)\n\n");
    printf("An evaluation is a chain of parallel regions (the spectrum stage, FFTW's passes) a few "
           "microseconds apart. Passive alone puts a team member to sleep at once, so each region "
           "first waits for it to be woken; ocean_wait_policy_setenv(1) lets it spin about 30 us first "
           "(GOMP_SPINCOUNT=" OCEAN_GOMP_SPINCOUNT ", ocean_wait_policy_setenv(1): ocean-sim and this "
           "benchmark) and still sleeps between ticks and under contention (next table). oceand "
           "itself stays fully passive: on 2 cores the spinning team took time from its service "
           "thread and 256 viewers' frames came later. Each row is its own process (libgomp "
           "reads the policy when it loads), run twice in alternation; the medians of the two "
           "runs are averaged.\n\n");
    printf("| N | policy | ms | FFTW ms | ratio |\n|---:|---|---:|---:|---:|\n");
    for (int i = 0; i < 2; i++) {
        static const char *spins[2] = {"0", OCEAN_GOMP_SPINCOUNT};
        double acc[2][3] = {{0}};
        int ok[2] = {0, 0};
        for (int round = 0; round < 2; round++)
            for (int k = 0; k < 2; k++) {
                double v[3];
                if (policy_run(mea_sizes[i], spins[k], quick, v) == 0) {
                    for (int j = 0; j < 3; j++)
                        acc[k][j] += v[j];
                    ok[k]++;
                }
            }
        for (int k = 0; k < 2; k++) {
            if (!ok[k]) {
                printf("| %d | passive, GOMP_SPINCOUNT=%s | failed | | |\n", mea_sizes[i], spins[k]);
                failed = 1;
                continue;
            }
            printf("| %d | passive, GOMP_SPINCOUNT=%s%s | %.3f | %.3f | %.3f |\n", mea_sizes[i], spins[k],
                   k ? " (ocean-sim, this table's others)" : " (oceand)", acc[k][0] / ok[k], acc[k][1] / ok[k], acc[k][2] / ok[k]);
        }
        fflush(stdout);
    }
    printf("\n");

    /* Packing two real channels into one complex transform. */
    printf("#### Packing two real channels into one complex transform (FFTW alone)\n\n");
    printf("8 c2r against 4 c2c of packed pairs z = a + i b, same sizes, threads and planner, "
           "interleaved; `+ split` adds the pass that splits each interleaved complex output into "
           "the two planar channels a field holds.\n\n");
    printf("| planner | N | threads | 8 c2r ms | 4 c2c ms | c2c / c2r | 4 c2c + split ms | (c2c + split) / c2r |\n"
           "|---|---:|---:|---:|---:|---:|---:|---:|\n");
    double best = INFINITY;
    for (int pl = 0; pl < 2; pl++)
        for (int n = 256; n <= 1024; n *= 2)
            for (int th = 1; th <= 2; th++) {
                double a = NAN, b = NAN, c = NAN;
                int reps = quick ? 5 : n >= 1024 ? 11 : 31;
                double q = packing_ratio(n, th, reps, pl ? FFTW_MEASURE : FFTW_ESTIMATE, &a, &b, &c);
                printf("| %s | %d | %d | %.3f | %.3f | %.2f | %.3f | %.2f |\n", pl ? "measure" : "estimate", n,
                       th, a, b, q, c, c / a);
                if (pl && c / a < best)
                    best = c / a;
                fflush(stdout);
            }
    printf("\nBest packed cost with MEASURE plans, split included: %.2fx of the real batch (its best row; "
           "the others are above). Packing also needs the spectrum stage to write whole complex "
           "spectra z(k) and z(-k) instead of half spectra, and a pair of channels shares one "
           "transform, so a request for an odd number of channels pays for an idle half. oceand keeps "
           "batched c2r plans%s.\n\n", best,
           best < 0.85 ? "; this run says packing would pay off: worth redoing the stage" :
                         ": a gain under 15 % on the transforms alone, lost on 2 threads at N = 512, "
                         "does not pay for a second spectrum layout");
    /* Contention, under oceand's policy and under the spinning one. */
    printf("#### Under contention: a busy process holding a core\n\n");
    printf("Full evaluation (+foam) on 2 threads, ESTIMATE plans, OMP_WAIT_POLICY=passive, each "
           "policy in its own process: oceand's (no spin) and ocean_wait_policy_setenv(1)'s "
           "(GOMP_SPINCOUNT=" OCEAN_GOMP_SPINCOUNT "). Each repetition times one evaluation quiet, "
           "then one while a spinning process runs (continued 20 ms before, stopped after), so "
           "both medians come from the same minutes.\n\n");
    printf("| policy | N | spinner | quiet ms | busy ms | busy / quiet |\n|---|---:|---|---:|---:|---:|\n");
    double worst[2] = {NAN, NAN};
    static const char *cspin[2] = {"0", OCEAN_GOMP_SPINCOUNT};
    for (int k = 0; k < 2; k++) {
        char buf[4096];
        if (child_run(cspin[k], "--contention-child", quick ? "1" : "0", k ? "spin" : "oceand", buf,
                      sizeof buf) != 0) {
            printf("| %s | contention run failed | | | | |\n", cspin[k]);
            failed = 1;
            continue;
        }
        char *w = strstr(buf, "worst256 ");
        if (w) {
            worst[k] = atof(w + 9);
            *w = 0;
        }
        fputs(buf, stdout);
        fflush(stdout);
    }
    printf("\nTarget (issue 14, its case: the daemon's N = 256 on 2 threads, oceand's policy): under "
           "a competing busy process no worse than 1.5x the quiet time: worst %.2fx - %s (with the "
           "spin: %.2fx). N = 512 is shown for scale: there the two threads are busy for the whole "
           "evaluation, so a third runnable process on 2 cores leaves them 4/3 of a core and 1.5x "
           "is the fair-share floor.\n\n", worst[0],
           isnan(worst[0]) ? "NOT MEASURED" : worst[0] <= 1.5 ? "met" : "NOT met", worst[1]);
    return failed;
}

/* The contention rows under this process's policy (label), then
 * "worst256 X": the worst busy / quiet at N = 256. */
static int contention_child(int quick, const char *label)
{
    double worst = 0;
    for (int n = 256; n <= 512; n *= 2)
        for (int cpu = -1; cpu <= 0; cpu++) {
            double qm, bm;
            double q = contention(n, cpu, quick ? 9 : n >= 512 ? 41 : 81, &qm, &bm);
            printf("| %s | %d | %s | %.3f | %.3f | %.2f |\n", label, n,
                   cpu < 0 ? "not pinned" : "pinned to CPU 0", qm, bm, q);
            if (n == 256 && !(q <= worst))
                worst = q;
        }
    printf("worst256 %.4f\n", worst);
    return isnan(worst) ? 1 : 0;
}
