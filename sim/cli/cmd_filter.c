/*
 * cmd_filter.c - `ocean-sim filter`: the Butterworth cutoff a camera speed
 * gets under a policy (seed 000, anti-aliasing, none), and what it costs
 * and saves: E_error of the filtered height spectrum, transforms run and
 * evaluation time, each beside the unfiltered evaluation of the same run.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cJSON.h>

#include "cli.h"
#include "filter.h"

/* A JSON number, or null for NaN/Inf (JSON has neither). */
static void add_num(cJSON *j, const char *name, double v)
{
    if (isfinite(v))
        cJSON_AddNumberToObject(j, name, v);
    else
        cJSON_AddNullToObject(j, name);
}

/* Times the unfiltered request a and the filtered request b alternately
 * (after one warm-up each, so neither pays for first touches and both see
 * the same machine state); medians into *ms_a, *ms_b, facts of the last
 * evaluations into *ia, *ib. */
static ocean_result timed_pair(ocean *o, ocean_frame *f, double t, const ocean_request *a,
                               const ocean_request *b, int repeat, double *ms_a, double *ms_b,
                               ocean_frame_info *ia, ocean_frame_info *ib)
{
    double *ta = malloc(sizeof(double) * 2 * (size_t)repeat);
    if (!ta)
        return OCEAN_ENOMEM;
    double *tb = ta + repeat;
    ocean_result r = ocean_evaluate(o, t, a, f);
    if (r == OCEAN_OK)
        r = ocean_evaluate(o, t, b, f);
    for (int i = 0; i < repeat && r == OCEAN_OK; i++) {
        double t0 = cli_now_ms();
        r = ocean_evaluate(o, t, a, f);
        ta[i] = cli_now_ms() - t0;
        if (r != OCEAN_OK)
            break;
        ocean_frame_get_info(f, ia);
        t0 = cli_now_ms();
        r = ocean_evaluate(o, t, b, f);
        tb[i] = cli_now_ms() - t0;
        ocean_frame_get_info(f, ib);
    }
    if (r == OCEAN_OK) {
        *ms_a = cli_median(ta, repeat);
        *ms_b = cli_median(tb, repeat);
    }
    free(ta);
    return r;
}

int cmd_filter(int argc, char **argv)
{
    cli_common c;
    const char *policy_name = "seed";
    double speed = 0.0, fps = 60.0, spacing = -1.0, v_wave = NAN;
    int order = OCEAN_FILTER_DEFAULT_ORDER, repeat = 5, redistribute = 0;
    /* The seed policy's static cutoff as the library sets it (it does not
     * depend on the sea state; the wave speed does, so it stays "not given"). */
    ocean_params dp;
    ocean_params_default(&dp);
    ocean_filter_config dfc;
    ocean_filter_config_default(&dfc, &dp.sea);
    double f_base = dfc.f_base_hz;
    const cli_opt opts[] = {
        {"policy", CLI_STRING, &policy_name, 0, 0, "P     seed | antialias | none", NULL},
        {"speed", CLI_DOUBLE, &speed, 0.0, 1e7, "V     camera speed |v|, m/s", NULL},
        {"fps", CLI_DOUBLE, &fps, 0.0, 1e4, "F     client frame rate, Hz; 0: no temporal limit", NULL},
        {"spacing", CLI_DOUBLE, &spacing, 0.0, 1e6,
         "DX    mesh spacing the client receives, m; 0: no spatial limit "
         "(not given: the finest cascade's grid spacing)", NULL},
        {"order", CLI_INT, &order, 1, OCEAN_FILTER_MAX_ORDER, "N     Butterworth order", NULL},
        {"f-base", CLI_DOUBLE, &f_base, 0.0, 1e6, "HZ    seed policy: static cutoff frequency", NULL},
        {"v-wave", CLI_DOUBLE, &v_wave, 1e-6, 1e6,
         "C     seed policy: fc -> kc speed, m/s (not given: the dominant wave's phase speed)", NULL},
        {"redistribute", CLI_FLAG, &redistribute, 0, 0, "      keep the total variance (seed 000's energy guard)", NULL},
        {"repeat", CLI_INT, &repeat, 1, 10000, "R     evaluations timed per case, median reported", NULL},
    };
    int r = cli_parse(argc, argv,
                      "filter [--policy seed|antialias|none] [--speed V] [--fps F] [--spacing DX] [--json]",
                      opts, (int)(sizeof opts / sizeof opts[0]), &c, NULL, NULL);
    if (r)
        return r == 1 ? 0 : 2;
    ocean_filter_policy policy;
    if (ocean_filter_policy_parse(policy_name, &policy) != OCEAN_OK) {
        fprintf(stderr, "error: --policy '%s': expected seed, antialias or none\n", policy_name);
        return 2;
    }

    ocean_filter_config fc;
    ocean_filter_config_default(&fc, &c.params.sea);
    fc.order = order;
    if (!isnan(f_base))
        fc.f_base_hz = f_base;
    if (!isnan(v_wave))
        fc.v_wave_mps = v_wave;
    char msg[160];
    if (ocean_filter_config_validate(&fc, msg, sizeof msg) != OCEAN_OK) {
        fprintf(stderr, "error: %s\n", msg);
        return 2;
    }

    ocean *o;
    ocean_frame *f;
    if (cli_make_ocean(&c, &o, &f))
        return 1;
    const ocean_params *p = ocean_get_params(o);
    if (spacing < 0.0) {
        double patch;
        ocean_cascade_band(o, p->cascades - 1, &patch, NULL, NULL);
        spacing = patch / p->n;
    }

    ocean_filter_client cl = {speed, fps, spacing};
    ocean_filter_cutoff cut;
    if (ocean_filter_cutoff_compute(&fc, policy, &cl, &cut) != OCEAN_OK) {
        fprintf(stderr, "error: no cutoff for speed %g, fps %g, spacing %g\n", speed, fps, spacing);
        ocean_frame_destroy(f);
        ocean_destroy(o);
        return 2;
    }
    ocean_filter_buckets b;
    ocean_filter_buckets_default(&b);
    int bucket = 0;
    double bucket_k = 0.0;
    ocean_filter_bucket_of(&b, cut.k, &bucket);
    ocean_filter_bucket_cutoff(&b, bucket, &bucket_k);

    ocean_request req, raw;
    ocean_request_all(&raw, c.effects);
    req = raw;
    req.cutoff_k = cut.k;
    req.order = cut.order;
    req.low_boost = cut.low_boost;
    req.redistribute = redistribute;
    ocean_frame_info fi, ri;
    double ms, ms_raw;
    ocean_result er = timed_pair(o, f, c.time, &raw, &req, repeat, &ms_raw, &ms, &ri, &fi);
    if (er != OCEAN_OK) {
        fprintf(stderr, "error: evaluation failed: %s\n", ocean_strerror(er));
        ocean_frame_destroy(f);
        ocean_destroy(o);
        return 1;
    }
    double var = ocean_filtered_variance(o, INFINITY, cut.order);
    double var_f = ocean_filtered_variance(o, cut.k, cut.order);
    double kneg = ocean_filter_negligible_k(cut.k, cut.order, 1e-4);
    const char *limit = cut.limited_by == 1 ? "spatial" : cut.limited_by == 2 ? "temporal" : NULL;

    if (c.json) {
        cJSON *j = cJSON_CreateObject();
        cJSON_AddStringToObject(j, "policy", ocean_filter_policy_name(policy));
        cJSON_AddNumberToObject(j, "speed", speed);
        cJSON_AddNumberToObject(j, "fps", fps);
        cJSON_AddNumberToObject(j, "spacing", spacing);
        add_num(j, "cutoff_k", cut.k);
        add_num(j, "cutoff_hz", cut.hz);
        add_num(j, "cutoff_wavelength", cut.k > 0.0 ? 2.0 * M_PI / cut.k : INFINITY);
        if (limit)
            cJSON_AddStringToObject(j, "limited_by", limit);
        else
            cJSON_AddNullToObject(j, "limited_by");
        cJSON_AddNumberToObject(j, "order", cut.order);
        cJSON_AddNumberToObject(j, "low_boost", cut.low_boost);
        add_num(j, "negligible_k", kneg);
        cJSON_AddNumberToObject(j, "bucket", bucket);
        add_num(j, "bucket_k", bucket_k);
        cJSON_AddNumberToObject(j, "e_error", fi.e_error);
        cJSON_AddNumberToObject(j, "variance_kept", var > 0.0 ? var_f / var : 1.0);
        cJSON_AddNumberToObject(j, "transforms", fi.transforms);
        cJSON_AddNumberToObject(j, "transforms_unfiltered", ri.transforms);
        cJSON_AddNumberToObject(j, "ms", ms);
        cJSON_AddNumberToObject(j, "ms_unfiltered", ms_raw);
        cJSON_AddNumberToObject(j, "time_ratio", ms_raw > 0.0 ? ms / ms_raw : 1.0);
        cJSON_AddNumberToObject(j, "repeat", repeat);
        cJSON_AddNumberToObject(j, "n", p->n);
        cJSON_AddNumberToObject(j, "cascades", p->cascades);
        cli_print_json(j);
    } else {
        printf("policy %s, speed %g m/s, %g fps, spacing %g m\n", ocean_filter_policy_name(policy),
               speed, fps, spacing);
        if (isinf(cut.k))
            printf("cutoff: none\n");
        else
            printf("cutoff %.6g rad/m (wavelength %.4g m)%s%s, order %d, low boost %.3g\n", cut.k,
                   cut.k > 0 ? 2 * M_PI / cut.k : INFINITY, limit ? ", limited by " : "",
                   limit ? limit : "", cut.order, cut.low_boost);
        if (isfinite(cut.hz))
            printf("cutoff frequency %.6g Hz\n", cut.hz);
        printf("bucket %d (%.6g rad/m)\n", bucket, bucket_k);
        printf("E_error %.5f, variance kept %.5f\n", fi.e_error, var > 0.0 ? var_f / var : 1.0);
        printf("%d transforms in %.3f ms (unfiltered: %d in %.3f ms), ratio %.3f\n",
               fi.transforms, ms, ri.transforms, ms_raw, ms_raw > 0 ? ms / ms_raw : 1.0);
    }
    ocean_frame_destroy(f);
    ocean_destroy(o);
    return 0;
}
