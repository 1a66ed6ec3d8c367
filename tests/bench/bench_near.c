/*
 * bench_near.c - what the Gerstner near field costs per point (issue 13
 * item 4), three ways the daemon can ask for it:
 *
 *   one-shot   ocean_gerstner_evaluate for one point per call: what the
 *              daemon's mesh sampler did per vertex until issue 13 (every
 *              call redoes the per-wave gains, Q and phases at t)
 *   frame      ocean_gerstner_frame_set once, then
 *              ocean_gerstner_frame_evaluate for one point per call
 *   frame disp the same with ocean_gerstner_frame_displacement (dx, dy,
 *              dz only): the mesh sampler now
 *   grid       ocean_gerstner_frame_sample_grid over a 64 x 64 tile: the
 *              near field in level-0 tiles
 *
 * for the daemon's 64 waves and for 256 and 1024, with the antialias
 * filter's per-wave gains on (the mesh path's view) and a 60 m fade whose
 * points all lie inside it.  Median over repetitions, ns per point; the
 * speed-up columns are one-shot / frame and one-shot / grid, measured in
 * the same run.  Writes tests/bench/out/near.csv beside the table.
 *
 * Then queries in the storm scene (config/scenes/storm.conf over
 * config/oceand.conf, with the daemon's 64-wave near field): the cost of
 * one field reading (bilinear, accurate) and of one query (inversion
 * included), and the height error of each reading at 200 points against
 * the direct sum of every FFT mode in double (ocean_reference_point).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "../lib/bench_util.h"
#include "gerstner.h"
#include "ocean.h"
#include "ocean_conf.h"
#include "ocean_reference.h"
#include "query.h"

#define PTS 4096
#define SIDE 64

static double per_point_ns(double ms, int n)
{
    return ms * 1e6 / n;
}

static int storm_queries(int quick)
{
    ocean_params base;
    ocean_scene sc;
    char err[300];
    if (ocean_conf_load("config/oceand.conf", &base, err, sizeof err) != OCEAN_OK ||
        ocean_conf_scene_load("config/scenes/storm.conf", &base, &sc, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "bench_near: %s\n", err);
        return 1;
    }
    ocean_params p = sc.params;
    p.k_max = M_PI * p.n / (p.patch_m / pow(p.cascade_ratio, p.cascades - 1));
    p.threads = 1;
    ocean *o = NULL;
    ocean_frame *f = NULL;
    ocean_gerstner *g = NULL;
    if (ocean_create(&p, &o, err, sizeof err) != OCEAN_OK || ocean_frame_create(o, &f) != OCEAN_OK) {
        fprintf(stderr, "bench_near: %s\n", err);
        return 1;
    }
    double t = 137.25, klo, khi;
    ocean_request r;
    ocean_request_all(&r, OCEAN_QUERY_EFFECTS);
    r.foam_map = 0;
    ocean_evaluate(o, t, &r, f);
    ocean_cascade_band(o, p.cascades - 1, NULL, &klo, &khi);
    ocean_gerstner_params gp;
    ocean_gerstner_params_default(&gp);
    gp.sea = p.sea;
    gp.seed = p.seed;
    gp.count = 64;
    gp.k_lo = khi;
    gp.k_hi = 2 * M_PI / 0.1;
    if (ocean_gerstner_create(&gp, &g, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "bench_near: %s\n", err);
        return 1;
    }
    enum { NQ = 2000 };
    static double xz[2 * NQ];
    static ocean_query_result res[NQ];
    uint64_t st = 99;
    for (int i = 0; i < 2 * NQ; i++) {
        st = st * 6364136223846793005ULL + 1442695040888963407ULL;
        xz[i] = ((double)(st >> 11) * 0x1p-53 - 0.5) * 4000.0;
    }
    int reps = quick ? 3 : 7;
    double tb[8], ta[8], tq[8], sink = 0;
    for (int k = 0; k < reps; k++) {
        ocean_point pt;
        double t0 = bench_now_ms();
        for (int i = 0; i < NQ; i++) {
            ocean_frame_sample(f, xz[2 * i], xz[2 * i + 1], &pt);
            sink += pt.height;
        }
        double t1 = bench_now_ms();
        for (int i = 0; i < NQ; i++) {
            ocean_frame_sample_accurate(f, xz[2 * i], xz[2 * i + 1], OCEAN_SAMPLE_ALL, &pt, NULL);
            sink += pt.height;
        }
        double t2 = bench_now_ms();
        ocean_query_points(f, g, NULL, t, xz, NQ, NULL, res, NULL);
        double t3 = bench_now_ms();
        tb[k] = (t1 - t0) * 1e6 / NQ;
        ta[k] = (t2 - t1) * 1e6 / NQ;
        tq[k] = (t3 - t2) * 1e6 / NQ;
    }
    int ne = quick ? 40 : 200;
    double sb = 0, sa = 0, mb = 0, ma = 0;
    ocean_reference *exact = NULL;
    if (ocean_reference_create(o, t, INFINITY, 6, &exact) != OCEAN_OK) {
        fprintf(stderr, "bench_near: the exact reference: out of memory\n");
        return 1;
    }
    for (int i = 0; i < ne; i++) {
        ocean_point ref, b, a;
        ocean_reference_eval(exact, xz[2 * i], xz[2 * i + 1], &ref);
        ocean_frame_sample(f, xz[2 * i], xz[2 * i + 1], &b);
        ocean_frame_sample_accurate(f, xz[2 * i], xz[2 * i + 1], OCEAN_SAMPLE_HEIGHT, &a, NULL);
        double eb = fabs(b.height - ref.height), ea = fabs(a.height - ref.height);
        sb += eb * eb;
        sa += ea * ea;
        mb = fmax(mb, eb);
        ma = fmax(ma, ea);
    }
    ocean_reference_destroy(exact);
    printf("\nStorm scene (N = %d, %d cascades, choppiness %.1f, 64-wave near field): field reading\n"
           "per point and height error against the direct sum of every mode (%d points)\n\n",
           p.n, p.cascades, p.sea.choppiness, ne);
    printf("| reading | ns per point | height error RMS (mm) | worst (mm) |\n|---|---:|---:|---:|\n");
    printf("| bilinear (ocean_frame_sample) | %.0f | %.2f | %.2f |\n", bench_median(tb, reps),
           1e3 * sqrt(sb / ne), 1e3 * mb);
    printf("| accurate (ocean_frame_sample_accurate) | %.0f | %.3f | %.3f |\n", bench_median(ta, reps),
           1e3 * sqrt(sa / ne), 1e3 * ma);
    printf("\nOne query (ocean_query_points: Newton on FFT + near field, accurate reading, bound): "
           "%.1f us per point.\n", bench_median(tq, reps) / 1e3);
    if (!isfinite(sink))
        fprintf(stderr, "bench_near: non-finite output\n");
    ocean_gerstner_destroy(g);
    ocean_frame_destroy(f);
    ocean_destroy(o);
    return 0;
}

int main(void)
{
    int quick = bench_quick();
    int reps = quick ? 3 : 9;
    const int counts[] = {64, 256, 1024};
    FILE *csv = fopen("tests/bench/out/near.csv", "w");
    if (csv)
        fprintf(csv, "waves,oneshot_ns,frame_ns,frame_disp_ns,grid_ns,disp_speedup,grid_speedup\n");
    printf("Near field per point (ns, median of %d), 60 m fade, antialias filter on\n\n", reps);
    printf("| waves | one-shot per vertex (before) | frame, full point | frame, displacement (mesh now) | grid 64x64 (tiles) | mesh speed-up | grid speed-up |\n");
    printf("|---:|---:|---:|---:|---:|---:|---:|\n");
    static double xs[PTS], zs[PTS];
    static ocean_gerstner_point out[PTS];
    static float planes[5][SIDE * SIDE];
    for (int i = 0; i < PTS; i++) {
        /* a mesh-like spiral of vertices inside the fade's full-strength disc */
        double r = 29.0 * sqrt((i + 0.5) / PTS), a = i * 2.399963;
        xs[i] = 1000.0 + r * cos(a);
        zs[i] = -500.0 + r * sin(a);
    }
    for (unsigned c = 0; c < sizeof counts / sizeof counts[0]; c++) {
        ocean_gerstner_params p;
        ocean_gerstner_params_default(&p);
        p.count = counts[c];
        p.k_lo = 2 * M_PI / 0.42;
        p.k_hi = 2 * M_PI / 0.1;
        ocean_gerstner *g = NULL;
        char msg[200];
        if (ocean_gerstner_create(&p, &g, msg, sizeof msg) != OCEAN_OK) {
            fprintf(stderr, "bench_near: %s\n", msg);
            return 1;
        }
        ocean_gerstner_view v;
        ocean_gerstner_view_default(&v);
        v.camera_x = 1000.0;
        v.camera_z = -500.0;
        v.fade_r0 = 30.0;
        v.fade_r1 = 60.0;
        v.filter = (ocean_filter_cutoff){.k = 40.0, .hz = NAN, .low_boost = 1.0, .order = 6};
        ocean_gerstner_frame *fr = NULL;
        ocean_gerstner_frame_create(g, &fr);
        int n1 = quick ? PTS / 8 : PTS;
        double a[16], b[16], dsp[16], gt[16];
        static double d3[3 * PTS];
        double sink = 0.0;
        for (int r = 0; r < reps; r++) {
            double t = 100.0 + r * 0.033;
            double t0 = bench_now_ms();
            for (int i = 0; i < n1; i++)
                ocean_gerstner_evaluate(g, &v, t, &xs[i], &zs[i], 1, &out[i]);
            double t1 = bench_now_ms();
            ocean_gerstner_frame_set(fr, &v, t);
            for (int i = 0; i < n1; i++)
                ocean_gerstner_frame_evaluate(fr, &xs[i], &zs[i], 1, &out[i]);
            double t2a = bench_now_ms();
            ocean_gerstner_frame_displacement(fr, xs, zs, 1, d3); /* warm the frame's cells */
            for (int i = 0; i < n1; i++)
                ocean_gerstner_frame_displacement(fr, &xs[i], &zs[i], 1, &d3[3 * i]);
            double t2 = bench_now_ms();
            ocean_gerstner_grid gr = {.x0 = 990.0, .z0 = -510.0, .spacing = 20.0 / SIDE, .w = SIDE,
                                      .h = SIDE, .stride = SIDE, .height = planes[0], .dx = planes[1],
                                      .dz = planes[2], .slope_x = planes[3], .slope_z = planes[4]};
            ocean_gerstner_frame_sample_grid(fr, &gr);
            double t3 = bench_now_ms();
            a[r] = per_point_ns(t1 - t0, n1);
            b[r] = per_point_ns(t2a - t1, n1);
            dsp[r] = per_point_ns(t2 - t2a, n1);
            gt[r] = per_point_ns(t3 - t2, SIDE * SIDE);
            sink += out[n1 / 2].dy + planes[0][SIDE] + d3[3 * (n1 / 2) + 1];
        }
        double ma = bench_median(a, reps), mb = bench_median(b, reps), md = bench_median(dsp, reps);
        double mg = bench_median(gt, reps);
        printf("| %d | %.0f | %.0f | %.0f | %.0f | %.1fx | %.1fx |\n", counts[c], ma, mb, md, mg, ma / md,
               ma / mg);
        if (csv)
            fprintf(csv, "%d,%.1f,%.1f,%.1f,%.1f,%.2f,%.2f\n", counts[c], ma, mb, md, mg, ma / md, ma / mg);
        if (!isfinite(sink))
            fprintf(stderr, "bench_near: non-finite output\n");
        ocean_gerstner_frame_destroy(fr);
        ocean_gerstner_destroy(g);
    }
    printf("\nThe daemon's mesh sampler uses the frame's displacement path (one ocean_gerstner_frame per mesh);\n"
           "level-0 tiles can take the grid path.\n");
    if (csv)
        fclose(csv);
    return storm_queries(quick);
}
