/*
 * render.c - the reference render of the exact sea (render.h).
 *
 * Threads: render_image's workers take rows from an atomic counter; each
 * reads the immutable render_sea and writes its own rows and counters.
 * OOM policy: as render.h.
 */
#include "render.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "ocean_time.h"
#include "mesh.h"
#include "query.h"
#include "render_shade.h"
#include "slope.h"
#include "spectrum.h"

#define RENDER_LEVELS_MAX 32
#define RENDER_ORDER 6          /* the Butterworth order of the levels (the daemon's default) */
#define RENDER_FAR_M 2e6        /* rays that meet nothing nearer meet the flat sea beyond */

struct render_sea {
    ocean *oc;
    ocean_gerstner *g;
    double t;
    unsigned effects;           /* what each level evaluates */
    double k_top;               /* the shortest wave's wave number, rad/m */
    double near_k_lo;           /* where the near field's band starts (INFINITY: none) */
    double hmin, hmax;          /* bounds of the exact surface's height, m */
    double hs, wind_dir_deg;
    int levels;
    ocean_frame *f[RENDER_LEVELS_MAX];
    ocean_gerstner_view view[RENDER_LEVELS_MAX];
    double kc[RENDER_LEVELS_MAX];
    double lip[RENDER_LEVELS_MAX];          /* bound used on the level's steepest slope */
    ocean_slope_moments carried[RENDER_LEVELS_MAX];
};

/* Level j holds the sea low-passed at kc_j: level 0 unfiltered, level
 * j >= 1 at k_top / 2^(j - 1), down to a quarter of the longest wave's k. */
static double level_kc(double k_top, int j)
{
    return j == 0 ? INFINITY : k_top * ldexp(1.0, 1 - j);
}

/* Continuous level of a footprint s: a sample resolves k < pi / s. */
static double level_of(const render_sea *s, double foot_m)
{
    if (!(foot_m > 0)) return 0;
    double l = log2(2 * s->k_top * foot_m / M_PI);
    return l <= 0 ? 0 : fmin(l, s->levels - 1);
}

static ocean_result sea_level_make(render_sea *s, int j, ocean_slope_table *tab, char *msg, size_t msglen)
{
    s->kc[j] = level_kc(s->k_top, j);
    ocean_result r = ocean_frame_create(s->oc, &s->f[j]);
    if (r != OCEAN_OK) return r;
    ocean_request req;
    ocean_request_all(&req, s->effects);
    req.cutoff_k = s->kc[j];
    req.order = RENDER_ORDER;
    req.foam_map = 0;
    if ((r = ocean_evaluate(s->oc, s->t, &req, s->f[j])) != OCEAN_OK) {
        snprintf(msg, msglen, "evaluating the sea at t = %.9g: %s", s->t, ocean_strerror(r));
        return r;
    }
    ocean_gerstner_view_default(&s->view[j]);
    s->view[j].filter.k = s->kc[j];
    s->view[j].filter.order = RENDER_ORDER;
    s->view[j].filter.low_boost = 1;
    s->view[j].filter.hz = NAN;
    ocean_slope_stats st;
    if ((r = ocean_slope_table_get(tab, s->kc[j], RENDER_ORDER, &st)) != OCEAN_OK) return r;
    s->carried[j] = st.carried;
    /* marching steps by the gap over this bound: four standard deviations
     * of the resolved slope, doubled for the chop's steeper crests */
    s->lip[j] = fmin(fmax(8 * sqrt(0.5 * st.mss_resolved), 0.02), 4.0);
    return OCEAN_OK;
}

/* Bounds of the exact surface's height: the sum of each cascade's extreme
 * grid values plus every near-field amplitude, with a 5 % margin for what
 * the waves reach between grid nodes (a margin, not a proof: a crest top
 * above it would be cut flat where a ray enters the bounds). */
static void sea_bounds(render_sea *s)
{
    const ocean_params *p = ocean_get_params(s->oc);
    double hi = 0, lo = 0;
    for (int c = 0; c < p->cascades; c++) {
        const ocean_field *fd = ocean_frame_field(s->f[0], c);
        double a = 0, b = 0;
        for (long i = 0; fd && fd->height && i < (long)fd->n * fd->n; i++) {
            a = fmax(a, fd->height[i]);
            b = fmin(b, fd->height[i]);
        }
        hi += a;
        lo += b;
    }
    double near = 0;
    ocean_gerstner_wave w;
    for (int i = 0; s->g && i < ocean_gerstner_count(s->g); i++)
        if (ocean_gerstner_get_wave(s->g, i, &w) == OCEAN_OK) near += w.amplitude;
    s->hmax = 1.05 * (hi + near) + 0.01;
    s->hmin = 1.05 * (lo - near) - 0.01;
}

ocean_result render_sea_create(const ocean_params *p, const ocean_gerstner_params *gp, unsigned effects,
                               double t, int threads, render_sea **out, char *msg, size_t msglen)
{
    *out = NULL;
    if (!ocean_time_ok(t)) {
        snprintf(msg, msglen, "time %g s is beyond +-%g s", t, OCEAN_TIME_MAX);
        return OCEAN_EINVAL;
    }
    render_sea *s = calloc(1, sizeof *s);
    if (!s) return OCEAN_ENOMEM;
    ocean_params q = *p;
    q.threads = threads;
    s->t = t;
    s->effects = OCEAN_FX_HEIGHT | OCEAN_FX_NORMALS | (effects & (OCEAN_FX_DISPLACEMENT | OCEAN_FX_FOAM));
    s->hs = ocean_spectrum_hs(&p->sea);
    s->wind_dir_deg = p->sea.wind_dir_deg;
    ocean_slope_table *tab = NULL;
    ocean_result r = ocean_create(&q, &s->oc, msg, msglen);
    if (r == OCEAN_OK && gp) r = ocean_gerstner_create(gp, &s->g, msg, msglen);
    s->near_k_lo = gp ? gp->k_lo : INFINITY;
    if (r == OCEAN_OK) r = ocean_slope_table_create(s->oc, s->g, &tab, msg, msglen);
    if (r == OCEAN_OK) {
        double patch, klo, khi, k_bottom;
        ocean_cascade_band(s->oc, q.cascades - 1, &patch, &klo, &khi);
        /* the shortest wave: the near field's, else the finest cascade's
         * band edge or, with no k_max, the corner of its square of modes */
        s->k_top = gp ? gp->k_hi : isfinite(khi) ? khi : M_PI * q.n * M_SQRT2 / patch;
        ocean_cascade_band(s->oc, 0, &patch, &klo, &khi);
        k_bottom = 2 * M_PI / patch;
        for (int j = 0; r == OCEAN_OK && j < RENDER_LEVELS_MAX; j++) {
            r = sea_level_make(s, j, tab, msg, msglen);
            s->levels = j + 1;
            if (s->kc[j] < k_bottom / 4) break;
        }
    }
    ocean_slope_table_destroy(tab);
    if (r != OCEAN_OK) {
        render_sea_destroy(s);
        return r;
    }
    sea_bounds(s);
    *out = s;
    return OCEAN_OK;
}

void render_sea_destroy(render_sea *s)
{
    if (!s) return;
    for (int j = 0; j < s->levels; j++) ocean_frame_destroy(s->f[j]);
    ocean_gerstner_destroy(s->g);
    ocean_destroy(s->oc);
    free(s);
}

int render_sea_levels(const render_sea *s)
{
    return s->levels;
}

/* The surface of level j over (x, z): a query of that level's fields and
 * near field.  coarse: a reading good to a few centimetres (bilinear,
 * loose inversion, no near field: its waves are millimetres to
 * centimetres high and cost most of an exact reading) for marching; else
 * the accurate one. */
static void level_query(const render_sea *s, int j, double x, double z, int coarse, ocean_query_result *q)
{
    ocean_query_options opt;
    ocean_query_options_default(&opt);
    if (coarse) {
        opt.bilinear = 1;
        opt.max_iterations = 6;
        opt.tolerance = 1e-3;
    }
    double xz[2] = {x, z};
    /* a level filtered far below the near field's band holds none of it */
    const ocean_gerstner *g = coarse || s->kc[j] < 0.25 * s->near_k_lo ? NULL : s->g;
    if (ocean_query_points(s->f[j], g, &s->view[j], s->t, xz, 1, &opt, q, NULL) != OCEAN_OK)
        memset(q, 0, sizeof *q);
}

ocean_result render_sea_point(const render_sea *s, double x, double z, double footprint_m, render_point *out)
{
    memset(out, 0, sizeof *out);
    if (!isfinite(x) || !isfinite(z) || !(footprint_m >= 0)) return OCEAN_EINVAL;
    double l = level_of(s, footprint_m);
    int j0 = (int)l, j1 = j0 + 1 < s->levels ? j0 + 1 : j0;
    double f = l - j0;
    for (int k = 0; k < 2; k++) {
        int j = k ? j1 : j0;
        double w = k ? f : 1 - f;
        if (w == 0) continue;
        ocean_query_result q;
        level_query(s, j, x, z, 0, &q);
        double ny = fmax(q.normal[1], 1e-6);
        out->height += w * q.height;
        out->slope[0] += w * -q.normal[0] / ny;
        out->slope[1] += w * -q.normal[2] / ny;
        out->foam += w * q.foam;
        out->error = fmax(out->error, q.error);
        out->mss[0] += w * s->carried[j].mss_x;
        out->mss[1] += w * s->carried[j].mss_z;
        out->mss[2] += w * s->carried[j].mss_xz;
    }
    return OCEAN_OK;
}

/* ---- ray casting ---------------------------------------------------- */

typedef struct ray {
    double eye[3], v[3];
    double alpha;               /* the sample's angle, rad */
} ray;

static double ray_foot(const ray *r, double t)
{
    return t * r->alpha / sqrt(fmax(fabs(r->v[1]), 0.02));
}

/* Height of the ray over level j's surface at parameter t. */
static double ray_gap(const render_sea *s, const ray *r, int j, double t, long *evals)
{
    ocean_query_result q;
    level_query(s, j, r->eye[0] + r->v[0] * t, r->eye[2] + r->v[2] * t, 1, &q);
    (*evals)++;
    return r->eye[1] + r->v[1] * t - q.height;
}

/* The ray's stretch within the surface's height bounds: [*t0, *t1]; 0
 * when it never enters them. */
static int ray_span(const render_sea *s, const ray *r, double *t0, double *t1)
{
    double y = r->eye[1], vy = r->v[1];
    *t0 = 0;
    if (vy < 0) {
        if (y > s->hmax) *t0 = (y - s->hmax) / -vy;
        *t1 = (y - s->hmin) / -vy;
    } else {
        if (y >= s->hmax) return 0;
        *t1 = vy > 0 ? (s->hmax - y) / vy : RENDER_FAR_M;
    }
    *t1 = fmin(*t1, RENDER_FAR_M);
    return *t0 < *t1;
}

/* Marches the ray to its first crossing of the surface, the step the gap
 * over the level's slope bound allows but at least half the footprint
 * (the level holds no detail finer), then bisects.  Returns 1 with *hit. */
static int ray_march(const render_sea *s, const ray *r, double *hit, long *evals)
{
    double t0, t1;
    if (!ray_span(s, r, &t0, &t1)) return 0;
    double t = fmax(t0, 1e-3), vh = hypot(r->v[0], r->v[2]);
    int j = (int)level_of(s, ray_foot(r, t));
    double g = ray_gap(s, r, j, t, evals);
    if (g <= 0) {
        *hit = t;           /* the eye is under a crest */
        return 1;
    }
    while (t < t1) {
        double foot = ray_foot(r, t);
        j = (int)level_of(s, foot);
        double dt = fmax(0.8 * g / (fabs(r->v[1]) + s->lip[j] * vh), fmax(0.5 * foot, 1e-3));
        double tn = fmin(t + dt, t1), gn = ray_gap(s, r, j, tn, evals);
        if (gn <= 0) {
            for (int i = 0; i < 40 && tn - t > 0.02 * ray_foot(r, tn) + 1e-6; i++) {
                double tm = 0.5 * (t + tn);
                if (ray_gap(s, r, j, tm, evals) > 0) t = tm;
                else tn = tm;
            }
            *hit = 0.5 * (t + tn);
            return 1;
        }
        t = tn;
        g = gn;
    }
    return 0;
}

/* The display value of one sample; returns 1 when it met the sea. */
static int ray_shade(const render_sea *s, const render_sky *sky, const ray *r, double rgb[3], render_stats *st)
{
    int sea = 0;
    double t, lin[3];
    st->rays++;
    if (ray_march(s, r, &t, &st->evaluations)) {
        double x = r->eye[0] + r->v[0] * t, z = r->eye[2] + r->v[2] * t, foot = ray_foot(r, t);
        render_point p;
        render_sea_point(s, x, z, foot, &p);
        render_surface su = {.rel = {x - r->eye[0], p.height - r->eye[1], z - r->eye[2]},
                             .slope = {p.slope[0], p.slope[1]},
                             .mss = {p.mss[0], p.mss[1], p.mss[2]},
                             .foam = p.foam,
                             .crest = p.height / fmax(s->hs * 0.5, 0.2)};
        render_sea_radiance(sky, r->v, &su, r->alpha, lin);
        st->sea_rays++;
        sea = 1;
        st->max_height_error = fmax(st->max_height_error, p.error);
    } else if (r->v[1] < 0) {
        /* beyond RENDER_FAR_M: the flat sea, every slope below the footprint */
        const ocean_slope_moments *m = &s->carried[s->levels - 1];
        double d = -r->eye[1] / r->v[1];
        render_surface su = {.rel = {r->v[0] * d, -r->eye[1], r->v[2] * d}, .mss = {m->mss_x, m->mss_z, m->mss_xz}};
        render_sea_radiance(sky, r->v, &su, r->alpha, lin);
        sea = 1;
    } else {
        render_sky_view(sky, r->v, r->alpha, lin);
    }
    render_tonemap(lin, rgb);
    return sea;
}

/* ---- the image -------------------------------------------------------- */

typedef struct render_job {
    const render_sea *sea;
    const render_sky *sky;
    const render_view *v;
    double fwd[3], right[3], up[3], tan_h;
    float *rgb;
    unsigned char *mask;
    atomic_int next_row;
    pthread_mutex_t lock;
    render_stats st;
} render_job;

static void render_row(render_job *jb, int py, render_stats *st)
{
    const render_view *v = jb->v;
    int ss = v->supersample;
    double aspect = (double)v->width / v->height;
    ray r = {.eye = {v->eye[0], v->eye[1], v->eye[2]}, .alpha = 2 * jb->tan_h / v->height / ss};
    for (int px = 0; px < v->width; px++) {
        double acc[3] = {0, 0, 0};
        int sea = 0;
        for (int sy = 0; sy < ss; sy++)
            for (int sx = 0; sx < ss; sx++) {
                double nx = (px + (sx + 0.5) / ss) / v->width * 2 - 1;
                double ny = 1 - (py + (sy + 0.5) / ss) / v->height * 2;
                double l = 0, rgb[3];
                for (int i = 0; i < 3; i++) {
                    r.v[i] = jb->fwd[i] + nx * jb->tan_h * aspect * jb->right[i] + ny * jb->tan_h * jb->up[i];
                    l += r.v[i] * r.v[i];
                }
                for (int i = 0; i < 3; i++) r.v[i] /= sqrt(l);
                sea += ray_shade(jb->sea, jb->sky, &r, rgb, st);
                for (int i = 0; i < 3; i++) acc[i] += rgb[i];
            }
        size_t at = (size_t)py * v->width + px;
        for (int i = 0; i < 3; i++) jb->rgb[at * 3 + i] = (float)(acc[i] / (ss * ss));
        if (jb->mask) jb->mask[at] = (unsigned char)((255 * sea + ss * ss / 2) / (ss * ss));
    }
}

static void *render_worker(void *arg)
{
    render_job *jb = arg;
    render_stats st = {0};
    int py;
    while ((py = atomic_fetch_add(&jb->next_row, 1)) < jb->v->height) render_row(jb, py, &st);
    pthread_mutex_lock(&jb->lock);
    jb->st.rays += st.rays;
    jb->st.sea_rays += st.sea_rays;
    jb->st.evaluations += st.evaluations;
    jb->st.max_height_error = fmax(jb->st.max_height_error, st.max_height_error);
    pthread_mutex_unlock(&jb->lock);
    return NULL;
}

static ocean_result view_check(const render_view *v, char *msg, size_t msglen)
{
    mesh_camera c = {.pos = {v->eye[0], v->eye[1], v->eye[2]}, .yaw_deg = v->yaw_deg, .pitch_deg = v->pitch_deg,
                     .fov_y_deg = v->fov_deg, .viewport_w = v->width, .viewport_h = v->height};
    if (mesh_camera_validate(&c, msg, msglen) != OCEAN_OK) return OCEAN_EINVAL;
    if (v->width < 1 || v->width > 8192 || v->height < 1 || v->height > 8192 || v->supersample < 1 ||
        v->supersample > 8 || v->threads < 1 || v->threads > 64) {
        snprintf(msg, msglen, "size %dx%d (1..8192 each), supersample %d (1..8) or threads %d (1..64) out of range",
                 v->width, v->height, v->supersample, v->threads);
        return OCEAN_EINVAL;
    }
    return OCEAN_OK;
}

ocean_result render_image(const render_sea *s, const render_view *v, float *rgb, unsigned char *mask,
                          render_stats *st, char *msg, size_t msglen)
{
    memset(st, 0, sizeof *st);
    ocean_result r = view_check(v, msg, msglen);
    if (r != OCEAN_OK) return r;
    render_sky *sky;
    if ((r = render_sky_create(s->wind_dir_deg, s->t, v->eye, v->sun_given ? v->sun_deg : NULL, &sky)) != OCEAN_OK) {
        snprintf(msg, msglen, "sun at %g, %g deg: azimuth finite, elevation within +-90", v->sun_deg[0], v->sun_deg[1]);
        return r;
    }
    render_job jb = {.sea = s, .sky = sky, .v = v, .rgb = rgb, .mask = mask, .tan_h = tan(v->fov_deg * M_PI / 360)};
    mesh_camera c = {.yaw_deg = v->yaw_deg, .pitch_deg = v->pitch_deg, .fov_y_deg = v->fov_deg};
    mesh_camera_basis(&c, jb.fwd, jb.right, jb.up);
    atomic_init(&jb.next_row, 0);
    pthread_mutex_init(&jb.lock, NULL);
    double t0 = cli_now_ms();
    pthread_t th[64];
    int started = 0;
    for (int i = 1; i < v->threads; i++, started++)
        if (pthread_create(&th[started], NULL, render_worker, &jb)) break;
    render_worker(&jb);
    for (int i = 0; i < started; i++) pthread_join(th[i], NULL);
    jb.st.ms = cli_now_ms() - t0;
    *st = jb.st;
    pthread_mutex_destroy(&jb.lock);
    render_sky_destroy(sky);
    return OCEAN_OK;
}
