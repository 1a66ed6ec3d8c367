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
 * Target (issue 2): the full evaluation at N = 512 on 2 threads within
 * 1.15x of FFTW alone.  The verdict line says whether it holds.
 *
 * Prints a markdown table; writes tests/bench/out/core.csv.
 * BENCH_QUICK=1 (or OCEAN_BENCH_QUICK=1) shortens the run.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "../lib/bench_util.h"
#include <fftw3.h>

#include "ocean.h"

typedef struct fxset {
    const char *name;
    unsigned fx;
    int foam_map;
} fxset;

/* The classic trick the issue asks to measure: two real channels packed
 * into one complex field, z = a + i b, cost one c2c transform instead of
 * two c2r.  FFTW alone, same sizes, same threads, interleaved: 8 c2r
 * against 4 c2c.  Returns c2c / c2r. */
static double packing_ratio(int n, int threads, int reps, double *ms_c2r, double *ms_c2c)
{
    int h = n / 2 + 1, dims[2] = {n, n};
    fftwf_complex *in = fftwf_malloc(sizeof(fftwf_complex) * 8 * (size_t)n * h);
    float *out = fftwf_malloc(sizeof(float) * 8 * (size_t)n * n);
    fftwf_complex *cin = fftwf_malloc(sizeof(fftwf_complex) * 4 * (size_t)n * n);
    fftwf_complex *cout = fftwf_malloc(sizeof(fftwf_complex) * 4 * (size_t)n * n);
    double r = NAN;
    if (in && out && cin && cout) {
        fftwf_plan_with_nthreads(threads);
        fftwf_plan pr = fftwf_plan_many_dft_c2r(2, dims, 8, in, NULL, 1, n * h, out, NULL, 1, n * n,
                                                FFTW_ESTIMATE);
        fftwf_plan pc = fftwf_plan_many_dft(2, dims, 4, cin, NULL, 1, n * n, cout, NULL, 1, n * n,
                                            FFTW_BACKWARD, FFTW_ESTIMATE);
        memset(in, 0, sizeof(fftwf_complex) * 8 * (size_t)n * h);
        memset(cin, 0, sizeof(fftwf_complex) * 4 * (size_t)n * n);
        double *a = malloc(sizeof(double) * reps * 2), *b = a + reps;
        for (int i = 0; i < reps; i++) {
            double t0 = bench_now_ms();
            fftwf_execute(pr);
            double t1 = bench_now_ms();
            fftwf_execute(pc);
            a[i] = t1 - t0;
            b[i] = bench_now_ms() - t1;
        }
        *ms_c2r = bench_median(a, reps);
        *ms_c2c = bench_median(b, reps);
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

int main(void)
{
    int quick = bench_quick();
    const int sizes[] = {256, 512, 1024};
    const fxset sets[] = {
        {"height", OCEAN_FX_HEIGHT, 0},
        {"+displacement", OCEAN_FX_HEIGHT | OCEAN_FX_DISPLACEMENT, 0},
        {"+normals", OCEAN_FX_HEIGHT | OCEAN_FX_DISPLACEMENT | OCEAN_FX_NORMALS, 0},
        {"+foam", OCEAN_FX_ALL, 0},
        {"+foam +map", OCEAN_FX_ALL, 1},
    };
    FILE *csv = fopen("tests/bench/out/core.csv", "w");
    if (csv)
        fprintf(csv, "n,effects,threads,transforms,reps,ms,ms_fftw,ratio\n");
    printf("### FFT core: ms per evaluation beside FFTW alone (issue 2)\n\n");
    printf("One cascade, default sea (Pierson-Moskowitz 10 m/s, 1000 m patch), FFTW_ESTIMATE plans. "
           "`ms` is the median ocean_evaluate, `FFTW` the median ocean_transform_only (the same "
           "plans on the same buffers), interleaved in the same run; `ratio` is the median of the "
           "per-repetition ratios.\n\n");
    printf("| N | effects | transforms | 1 thread ms | FFTW ms | ratio | 2 threads ms | FFTW ms | ratio |\n");
    printf("|---:|---|---:|---:|---:|---:|---:|---:|---:|\n");
    double target_ratio = NAN, map_ratio = NAN;
    int failed = 0;
    for (size_t si = 0; si < sizeof sizes / sizeof sizes[0]; si++) {
        int n = sizes[si];
        for (size_t e = 0; e < sizeof sets / sizeof sets[0]; e++) {
            double ms[2], fw[2], ra[2];
            int transforms = 0;
            for (int th = 1; th <= 2; th++) {
                ocean_params p;
                ocean_params_default(&p);
                p.n = n;
                p.threads = th;
                ocean *o = NULL;
                ocean_frame *f = NULL;
                char msg[256];
                if (ocean_create(&p, &o, msg, sizeof msg) != OCEAN_OK || ocean_frame_create(o, &f) != OCEAN_OK) {
                    fprintf(stderr, "bench_core: N=%d: %s\n", n, msg);
                    ocean_destroy(o);
                    failed = 1;
                    ms[th - 1] = fw[th - 1] = ra[th - 1] = NAN;
                    continue;
                }
                ocean_request r;
                ocean_request_all(&r, sets[e].fx);
                r.foam_map = sets[e].foam_map;
                /* Enough repetitions for a stable median, bounded in time. */
                int reps = quick ? 5 : (n >= 1024 ? 15 : n >= 512 ? 31 : 61);
                double *a = malloc(sizeof(double) * reps * 3), *b = a + reps, *q = b + reps;
                ocean_evaluate(o, 0.0, &r, f);
                ocean_transform_only(o, &r, f);
                for (int i = 0; i < reps; i++) {
                    /* Alternate which half goes first so neither always
                     * runs on a warmer cache. */
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
                transforms = info.transforms;
                ms[th - 1] = bench_median(a, reps);
                fw[th - 1] = bench_median(b, reps);
                ra[th - 1] = bench_median(q, reps);
                if (csv)
                    fprintf(csv, "%d,%s,%d,%d,%d,%.4f,%.4f,%.4f\n", n, sets[e].name, th, transforms, reps,
                            ms[th - 1], fw[th - 1], ra[th - 1]);
                if (n == 512 && sets[e].fx == OCEAN_FX_ALL && th == 2)
                    *(sets[e].foam_map ? &map_ratio : &target_ratio) = ra[1];
                free(a);
                ocean_frame_destroy(f);
                ocean_destroy(o);
            }
            printf("| %d | %s | %d | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f |\n", n, sets[e].name, transforms,
                   ms[0], fw[0], ra[0], ms[1], fw[1], ra[1]);
            fflush(stdout);
        }
    }
    if (csv)
        fclose(csv);
    printf("\n`+foam` is the full evaluation as the daemon runs it: all 8 transforms, with J and "
           "foam formed from Dxx, Dzz, Dxz wherever a point is sampled. `+foam +map` also fills "
           "the whole-field J and foam planes (request foam_map: baking, statistics), one more "
           "pass over 5 floats per point.\n\n");
    printf("Target (issue 2): full evaluation at N = 512 on 2 threads within 1.15x of FFTW alone: "
           "measured %.3fx - %s; with the whole-field foam map %.3fx.\n\n", target_ratio,
           isnan(target_ratio) ? "NOT MEASURED" : target_ratio <= 1.15 ? "met" : "NOT met", map_ratio);

    /* Packing two real channels into one complex transform. */
    printf("#### Packing two real channels into one complex transform (FFTW alone)\n\n");
    printf("| N | threads | 8 c2r ms | 4 c2c ms (packed pairs) | c2c / c2r |\n|---:|---:|---:|---:|---:|\n");
    for (int n = 256; n <= 512; n *= 2)
        for (int th = 1; th <= 2; th++) {
            double a = NAN, b = NAN;
            double q = packing_ratio(n, th, quick ? 5 : 31, &a, &b);
            printf("| %d | %d | %.3f | %.3f | %.2f |\n", n, th, a, b, q);
        }
    printf("\nFFTW's real-input transforms already exploit the Hermitian half spectrum, so a packed "
           "pair costs as much as the two real transforms or more, before the unpacking pass: "
           "oceand keeps batched c2r plans.\n\n");
    return failed;
}
