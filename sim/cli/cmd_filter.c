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

/* What the command line sets beyond the common options. */
typedef struct filter_args {
    const char *policy_name;
    double speed, fps, spacing, v_wave, f_base;
    int order, repeat, redistribute;
} filter_args;

/* Returns cli_parse's 0, 1 (help printed) or 2 (error printed). */
static int filter_args_parse(int argc, char **argv, filter_args *a, cli_common *c)
{
    *a = (filter_args){.policy_name = "seed", .speed = 0.0, .fps = 60.0, .spacing = -1.0,
                       .v_wave = NAN, .order = OCEAN_FILTER_DEFAULT_ORDER, .repeat = 5,
                       .redistribute = 0};
    /* The seed policy's static cutoff as the library sets it (it does not
     * depend on the sea state; the wave speed does, so it stays "not given"). */
    ocean_params dp;
    ocean_params_default(&dp);
    ocean_filter_config dfc;
    ocean_filter_config_default(&dfc, &dp.sea);
    a->f_base = dfc.f_base_hz;
    const cli_opt opts[] = {
        {"policy", CLI_STRING, &a->policy_name, 0, 0, "P     seed | antialias | none", NULL},
        {"speed", CLI_DOUBLE, &a->speed, 0.0, 1e7, "V     camera speed |v|, m/s", NULL},
        {"fps", CLI_DOUBLE, &a->fps, 0.0, 1e4, "F     client frame rate, Hz; 0: no temporal limit", NULL},
        {"spacing", CLI_DOUBLE, &a->spacing, 0.0, 1e6,
         "DX    mesh spacing the client receives, m; 0: no spatial limit "
         "(not given: the finest cascade's grid spacing)", NULL},
        {"order", CLI_INT, &a->order, 1, OCEAN_FILTER_MAX_ORDER, "N     Butterworth order", NULL},
        {"f-base", CLI_DOUBLE, &a->f_base, 0.0, 1e6, "HZ    seed policy: static cutoff frequency", NULL},
        {"v-wave", CLI_DOUBLE, &a->v_wave, 1e-6, 1e6,
         "C     seed policy: fc -> kc speed, m/s (not given: the dominant wave's phase speed)", NULL},
        {"redistribute", CLI_FLAG, &a->redistribute, 0, 0, "      keep the total variance (seed 000's energy guard)", NULL},
        {"repeat", CLI_INT, &a->repeat, 1, 10000, "R     evaluations timed per case, median reported", NULL},
    };
    return cli_parse(argc, argv,
                     "filter [--policy seed|antialias|none] [--speed V] [--fps F] [--spacing DX] [--json]",
                     opts, (int)(sizeof opts / sizeof opts[0]), c, NULL, NULL);
}

/* The filter configuration for the sea with the arguments' overrides.
 * Returns 0, or 2 with the reason printed. */
static int filter_args_config(const filter_args *a, const ocean_sea_state *sea, ocean_filter_config *fc)
{
    ocean_filter_config_default(fc, sea);
    fc->order = a->order;
    if (!isnan(a->f_base))
        fc->f_base_hz = a->f_base;
    if (!isnan(a->v_wave))
        fc->v_wave_mps = a->v_wave;
    char msg[160];
    if (ocean_filter_config_validate(fc, msg, sizeof msg) != OCEAN_OK) {
        fprintf(stderr, "error: %s\n", msg);
        return 2;
    }
    return 0;
}

/* What the command reports. */
typedef struct filter_report {
    ocean_filter_policy policy;
    double speed, fps, spacing;
    ocean_filter_cutoff cut;
    int bucket;
    double bucket_k;
    ocean_frame_info fi, ri;          /* filtered, unfiltered */
    double ms, ms_raw;                /* filtered, unfiltered */
    double var, var_f;                /* the band's variance unfiltered, filtered */
    double kneg;
    const char *limit;                /* what limits the cutoff; NULL: nothing */
    int repeat, n, cascades;
} filter_report;

/* The cutoff the client gets, its bucket, and the filtered evaluation
 * timed beside the unfiltered one.  Returns 0, or the exit status with
 * the reason printed. */
static int filter_measure(const filter_args *a, const cli_common *c, const ocean_filter_config *fc,
                          ocean *o, ocean_frame *f, filter_report *rep)
{
    const ocean_params *p = ocean_get_params(o);
    rep->speed = a->speed;
    rep->fps = a->fps;
    rep->spacing = a->spacing;
    if (rep->spacing < 0.0) {
        double patch;
        ocean_cascade_band(o, p->cascades - 1, &patch, NULL, NULL);
        rep->spacing = patch / p->n;
    }
    ocean_filter_client cl = {rep->speed, rep->fps, rep->spacing};
    ocean_filter_cutoff *cut = &rep->cut;
    if (ocean_filter_cutoff_compute(fc, rep->policy, &cl, cut) != OCEAN_OK) {
        fprintf(stderr, "error: no cutoff for speed %g, fps %g, spacing %g\n", rep->speed, rep->fps,
                rep->spacing);
        return 2;
    }
    ocean_filter_buckets b;
    ocean_filter_buckets_default(&b);
    rep->bucket = 0;
    rep->bucket_k = 0.0;
    ocean_filter_bucket_of(&b, cut->k, &rep->bucket);
    ocean_filter_bucket_cutoff(&b, rep->bucket, &rep->bucket_k);

    ocean_request req, raw;
    ocean_request_all(&raw, c->effects);
    req = raw;
    req.cutoff_k = cut->k;
    req.order = cut->order;
    req.low_boost = cut->low_boost;
    req.redistribute = a->redistribute;
    ocean_result er = timed_pair(o, f, c->time, &raw, &req, a->repeat, &rep->ms_raw, &rep->ms,
                                 &rep->ri, &rep->fi);
    if (er != OCEAN_OK) {
        fprintf(stderr, "error: evaluation failed: %s\n", ocean_strerror(er));
        return 1;
    }
    rep->var = ocean_filtered_variance(o, INFINITY, cut->order);
    rep->var_f = ocean_filtered_variance(o, cut->k, cut->order);
    rep->kneg = ocean_filter_negligible_k(cut->k, cut->order, 1e-4);
    rep->limit = cut->limited_by == 1 ? "spatial" : cut->limited_by == 2 ? "temporal" : NULL;
    rep->repeat = a->repeat;
    rep->n = p->n;
    rep->cascades = p->cascades;
    return 0;
}

static void filter_print_json(const filter_report *rep)
{
    const ocean_filter_cutoff *cut = &rep->cut;
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "policy", ocean_filter_policy_name(rep->policy));
    cJSON_AddNumberToObject(j, "speed", rep->speed);
    cJSON_AddNumberToObject(j, "fps", rep->fps);
    cJSON_AddNumberToObject(j, "spacing", rep->spacing);
    add_num(j, "cutoff_k", cut->k);
    add_num(j, "cutoff_hz", cut->hz);
    add_num(j, "cutoff_wavelength", cut->k > 0.0 ? 2.0 * M_PI / cut->k : INFINITY);
    if (rep->limit)
        cJSON_AddStringToObject(j, "limited_by", rep->limit);
    else
        cJSON_AddNullToObject(j, "limited_by");
    cJSON_AddNumberToObject(j, "order", cut->order);
    cJSON_AddNumberToObject(j, "low_boost", cut->low_boost);
    add_num(j, "negligible_k", rep->kneg);
    cJSON_AddNumberToObject(j, "bucket", rep->bucket);
    add_num(j, "bucket_k", rep->bucket_k);
    cJSON_AddNumberToObject(j, "e_error", rep->fi.e_error);
    cJSON_AddNumberToObject(j, "variance_kept", rep->var > 0.0 ? rep->var_f / rep->var : 1.0);
    cJSON_AddNumberToObject(j, "transforms", rep->fi.transforms);
    cJSON_AddNumberToObject(j, "transforms_unfiltered", rep->ri.transforms);
    cJSON_AddNumberToObject(j, "ms", rep->ms);
    cJSON_AddNumberToObject(j, "ms_unfiltered", rep->ms_raw);
    cJSON_AddNumberToObject(j, "time_ratio", rep->ms_raw > 0.0 ? rep->ms / rep->ms_raw : 1.0);
    cJSON_AddNumberToObject(j, "repeat", rep->repeat);
    cJSON_AddNumberToObject(j, "n", rep->n);
    cJSON_AddNumberToObject(j, "cascades", rep->cascades);
    cli_print_json(j);
}

static void filter_print_text(const filter_report *rep)
{
    const ocean_filter_cutoff *cut = &rep->cut;
    printf("policy %s, speed %g m/s, %g fps, spacing %g m\n", ocean_filter_policy_name(rep->policy),
           rep->speed, rep->fps, rep->spacing);
    if (isinf(cut->k))
        printf("cutoff: none\n");
    else
        printf("cutoff %.6g rad/m (wavelength %.4g m)%s%s, order %d, low boost %.3g\n", cut->k,
               cut->k > 0 ? 2 * M_PI / cut->k : INFINITY, rep->limit ? ", limited by " : "",
               rep->limit ? rep->limit : "", cut->order, cut->low_boost);
    if (isfinite(cut->hz))
        printf("cutoff frequency %.6g Hz\n", cut->hz);
    printf("bucket %d (%.6g rad/m)\n", rep->bucket, rep->bucket_k);
    printf("E_error %.5f, variance kept %.5f\n", rep->fi.e_error,
           rep->var > 0.0 ? rep->var_f / rep->var : 1.0);
    printf("%d transforms in %.3f ms (unfiltered: %d in %.3f ms), ratio %.3f\n",
           rep->fi.transforms, rep->ms, rep->ri.transforms, rep->ms_raw,
           rep->ms_raw > 0 ? rep->ms / rep->ms_raw : 1.0);
}

int cmd_filter(int argc, char **argv)
{
    filter_args a;
    cli_common c;
    int r = filter_args_parse(argc, argv, &a, &c);
    if (r)
        return r == 1 ? 0 : 2;
    filter_report rep;
    if (ocean_filter_policy_parse(a.policy_name, &rep.policy) != OCEAN_OK) {
        fprintf(stderr, "error: --policy '%s': expected seed, antialias or none\n", a.policy_name);
        return 2;
    }
    ocean_filter_config fc;
    if (filter_args_config(&a, &c.params.sea, &fc))
        return 2;
    ocean *o;
    ocean_frame *f;
    if (cli_make_ocean(&c, &o, &f))
        return 1;
    int status = filter_measure(&a, &c, &fc, o, f, &rep);
    if (status == 0) {
        if (c.json)
            filter_print_json(&rep);
        else
            filter_print_text(&rep);
    }
    ocean_frame_destroy(f);
    ocean_destroy(o);
    return status;
}
