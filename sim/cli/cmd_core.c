/*
 * cmd_core.c - ocean-sim stats, sample and bench: the FFT core seen from
 * the command line.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cJSON.h>

#include "cli.h"
#include "ocean_reference.h"

int cmd_stats(int argc, char **argv)
{
    cli_common c;
    int r = cli_parse(argc, argv, "stats [options] [--json]", NULL, 0, &c, NULL, NULL);
    if (r)
        return r == 1 ? 0 : 2;
    ocean *o;
    ocean_frame *f;
    if (cli_make_ocean(&c, &o, &f))
        return 1;
    ocean_request req;
    ocean_request_all(&req, c.effects | OCEAN_FX_HEIGHT);
    double t0 = cli_now_ms();
    ocean_result er = ocean_evaluate(o, c.time, &req, f);
    double ms = cli_now_ms() - t0;
    if (er != OCEAN_OK) {
        fprintf(stderr, "error: evaluation failed: %s\n", ocean_strerror(er));
        ocean_frame_destroy(f);
        ocean_destroy(o);
        return 1;
    }
    ocean_spectrum_stats ss;
    ocean_field_stats fs;
    ocean_frame_info info;
    ocean_get_spectrum_stats(o, &ss);
    ocean_frame_get_field_stats(f, &fs);
    ocean_frame_get_info(f, &info);
    const ocean_params *p = &c.params;
    if (c.json) {
        cJSON *j = cJSON_CreateObject();
        cJSON_AddNumberToObject(j, "hs", fs.hs);
        cJSON_AddNumberToObject(j, "hs_spectrum", ss.hs);
        cJSON_AddNumberToObject(j, "hs_analytic", ocean_spectrum_hs(&p->sea));
        cJSON_AddNumberToObject(j, "tp", ss.tp);
        cJSON_AddNumberToObject(j, "lambda_dominant", ss.lambda_dominant);
        cJSON_AddNumberToObject(j, "mean", fs.mean);
        cJSON_AddNumberToObject(j, "min_jacobian", fs.min_jacobian);
        cJSON_AddNumberToObject(j, "folded_fraction", fs.folded_fraction);
        cJSON_AddNumberToObject(j, "foam_coverage", fs.foam_coverage);
        cJSON_AddNumberToObject(j, "transforms", info.transforms);
        cJSON_AddNumberToObject(j, "ms", ms);
        cJSON_AddNumberToObject(j, "time", c.time);
        cJSON_AddNumberToObject(j, "n", p->n);
        cJSON_AddNumberToObject(j, "cascades", p->cascades);
        cJSON_AddStringToObject(j, "spectrum", ocean_spectrum_name(p->sea.spectrum));
        cJSON_AddNumberToObject(j, "wind", p->sea.wind_u10);
        cli_print_json(j);
    } else {
        printf("spectrum %s, wind %.2f m/s, N %d, %d cascade(s), t = %g s\n",
               ocean_spectrum_name(p->sea.spectrum), p->sea.wind_u10, p->n, p->cascades, c.time);
        printf("Hs %.4f m (field), %.4f m (discrete spectrum), %.4f m (analytic)\n",
               fs.hs, ss.hs, ocean_spectrum_hs(&p->sea));
        printf("Tp %.3f s, dominant wavelength %.2f m, mean %.3g m\n", ss.tp, ss.lambda_dominant, fs.mean);
        printf("min Jacobian %.4f, folded %.4f %%, foam %.4f %%\n", fs.min_jacobian,
               100.0 * fs.folded_fraction, 100.0 * fs.foam_coverage);
        printf("%d transforms in %.2f ms\n", info.transforms, ms);
    }
    ocean_frame_destroy(f);
    ocean_destroy(o);
    return 0;
}

int cmd_sample(int argc, char **argv)
{
    cli_common c;
    double x = NAN, z = NAN, t0 = 0.0, dt = 0.1;   /* the point has no default */
    int count = 100, direct = 0;
    double max_terms = 2e9;
    const cli_opt opts[] = {
        {"x", CLI_DOUBLE, &x, -1e9, 1e9, "X     world x of the point, m (required)", NULL},
        {"z", CLI_DOUBLE, &z, -1e9, 1e9, "Z     world z of the point, m (required)", NULL},
        {"t0", CLI_DOUBLE, &t0, -OCEAN_TIME_MAX, OCEAN_TIME_MAX, "T     first time, s", NULL},
        {"dt", CLI_DOUBLE, &dt, 1e-6, 1e6, "D     time step, s", NULL},
        {"count", CLI_INT, &count, 1, 1000000, "C     number of samples", NULL},
        {"direct", CLI_FLAG, &direct, 0, 0, "      sum the waves directly in double instead of FFT fields", NULL},
        {"max-terms", CLI_DOUBLE, &max_terms, 1e3, 1e15,
         "W     refuse a --direct series summing more than W wave terms (count x cascades x n^2;\n"
         "                         the default is about 15 minutes here)", NULL},
    };
    int r = cli_parse(argc, argv, "sample --x X --z Z [--t0 T] [--dt D] [--count C] [--json] [options]",
                      opts, (int)(sizeof opts / sizeof opts[0]), &c, NULL, NULL);
    if (r)
        return r == 1 ? 0 : 2;
    if (isnan(x) || isnan(z)) {
        fprintf(stderr, "error: sample needs the point: --%s is missing (see sample --help)\n", isnan(x) ? "x" : "z");
        return 2;
    }
    /* A direct sum costs every wave of every cascade per sample (~0.4 us a
     * term): priced before it starts, as mesh prices its vertices (an
     * accepted --count 1e6 at n 2048 meant weeks) */
    double terms = (double)count * c.params.cascades * (double)c.params.n * c.params.n;
    if (direct && terms > max_terms) {
        fprintf(stderr, "error: --direct would sum %.3g wave terms (--count %d x %d cascades x n %d^2), more "
                "than --max-terms %.3g (about %.0f s here at 0.4 us a term): lower --count or --n, or raise "
                "--max-terms\n", terms, count, c.params.cascades, c.params.n, max_terms, terms * 4e-7);
        return 2;
    }
    char tmsg[256];
    if (ocean_time_check(t0 + (count - 1) * dt, "last sample time t0 + (count - 1) dt", tmsg,
                         sizeof tmsg) != OCEAN_OK) {
        fprintf(stderr, "error: %s\n", tmsg);
        return 2;
    }
    ocean *o;
    ocean_frame *f;
    if (cli_make_ocean(&c, &o, &f))
        return 1;
    /* Only the height is asked: one transform per cascade per sample. */
    ocean_request req;
    ocean_request_all(&req, OCEAN_FX_HEIGHT | OCEAN_FX_DISPLACEMENT);
    /* --json streams its array: a million samples need no tree in memory */
    if (c.json)
        printf("{\"x\": %.17g, \"z\": %.17g, \"direct\": %s, \"samples\": [\n", x, z,
               direct ? "true" : "false");
    else
        printf("t,height,dx,dz\n");
    int rc = 0;
    for (int i = 0; i < count; i++) {
        double t = t0 + i * dt;
        ocean_point pt;
        ocean_result er = OCEAN_OK;
        if (direct)
            ocean_reference_point(o, t, x, z, INFINITY, 6, &pt); /* void: t checked above */
        else
            er = ocean_evaluate(o, t, &req, f);
        if (er != OCEAN_OK) {
            fprintf(stderr, "error: sample at t = %.9g failed: %s\n", t, ocean_strerror(er));
            rc = 1;
            break;
        }
        if (!direct)
            ocean_frame_sample(f, x, z, &pt);
        if (c.json)
            printf("  {\"t\": %.15g, \"height\": %.9g, \"dx\": %.9g, \"dz\": %.9g}%s\n", t,
                   pt.height, pt.dx, pt.dz, i + 1 < count ? "," : "");
        else
            printf("%.6f,%.6f,%.6f,%.6f\n", t, pt.height, pt.dx, pt.dz);
    }
    if (c.json && rc == 0)
        printf("]}\n");
    ocean_frame_destroy(f);
    ocean_destroy(o);
    return rc;
}

int cmd_bench(int argc, char **argv)
{
    cli_common c;
    int reps = 30;
    const cli_opt opts[] = {
        {"reps", CLI_INT, &reps, 3, 100000, "R     evaluations to time (median reported)", NULL},
    };
    int r = cli_parse(argc, argv, "bench [options] [--reps R] [--json]", opts, 1, &c, NULL, NULL);
    if (r)
        return r == 1 ? 0 : 2;
    ocean *o;
    ocean_frame *f;
    if (cli_make_ocean(&c, &o, &f))
        return 1;
    ocean_request req;
    ocean_request_all(&req, c.effects);
    double *full = malloc(sizeof(double) * reps), *fft = malloc(sizeof(double) * reps);
    if (!full || !fft) {
        fprintf(stderr, "error: out of memory\n");
        return 1;
    }
    /* Warm up caches and FFTW's thread pool, then interleave the two
     * measurements so drift in machine load hits both alike. */
    ocean_evaluate(o, c.time, &req, f);
    ocean_transform_only(o, &req, f);
    for (int i = 0; i < reps; i++) {
        double t0 = cli_now_ms();
        ocean_evaluate(o, c.time + i * 0.033, &req, f);
        double t1 = cli_now_ms();
        ocean_transform_only(o, &req, f);
        double t2 = cli_now_ms();
        full[i] = t1 - t0;
        fft[i] = t2 - t1;
    }
    ocean_frame_info info;
    ocean_frame_get_info(f, &info);
    double ms = cli_median(full, reps), ms_fft = cli_median(fft, reps);
    if (c.json) {
        cJSON *j = cJSON_CreateObject();
        cJSON_AddNumberToObject(j, "n", c.params.n);
        cJSON_AddNumberToObject(j, "cascades", c.params.cascades);
        cJSON_AddNumberToObject(j, "threads", c.params.threads);
        cJSON_AddNumberToObject(j, "effects", c.effects);
        cJSON_AddNumberToObject(j, "transforms", info.transforms);
        cJSON_AddNumberToObject(j, "reps", reps);
        cJSON_AddNumberToObject(j, "ms", ms);
        cJSON_AddNumberToObject(j, "ms_fftw", ms_fft);
        cJSON_AddNumberToObject(j, "ratio", ms / ms_fft);
        cli_print_json(j);
    } else {
        printf("N %d, %d cascade(s), %d thread(s), %d transforms: %.3f ms per evaluation, "
               "FFTW alone %.3f ms (x%.3f), median of %d\n", c.params.n, c.params.cascades,
               c.params.threads, info.transforms, ms, ms_fft, ms / ms_fft, reps);
    }
    free(full);
    free(fft);
    ocean_frame_destroy(f);
    ocean_destroy(o);
    return 0;
}
