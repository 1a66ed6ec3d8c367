/*
 * ocean.c - the FFT ocean (see ocean.h for the contract).
 *
 * Per cascade we keep, for every mode of the half spectrum (kz rows, kx >= 0
 * columns, as FFTW's c2r wants it), the mode's two standing-wave
 * coefficients a and b (from the initial amplitudes h0(k) and conj(h0(-k))
 * below), the angular frequency in double and the wave vector.  An
 * evaluation then runs one pass over the modes (the "spectrum stage") that
 * writes every asked channel's spectrum, and one batched c2r transform per
 * cascade (per group of channels at large N).  The stage touches only the
 * columns of each row that hold a wave (cascade.lo, hi) and writes zeros
 * past them: a coarse cascade's band (a half disc of radius n/4) fills
 * about 20 % of its half spectrum, and its waves lie in the first n/4 of
 * the n/2 + 1 columns, so its transform runs the 2-D c2r's column pass on
 * those columns only (ocean_fft_run).  A low cutoff picks a smaller
 * transform: the modes it keeps are the same waves, only fewer of them.
 *
 * Conventions: eta(x) = sum_k h(k,t) e^{i k.x},
 *   h(k,t) = h0(k) e^{-i w t} + conj(h0(-k)) e^{+i w t},   E|h0(k)|^2 = P(k),
 *   P(k) = F(k) dk^2 / 2 so that E[var eta] = sum_k F(k) dk^2 -> m0.
 * The stage evaluates the same h(k,t) as a cos(w t) + b sin(w t), with
 *   a = h0(k) + conj(h0(-k)),   b = i (conj(h0(-k)) - h0(k)),
 * formed in double once: 4 multiplies a mode instead of 8.
 * Choppy displacement D = sum i (k/|k|) h e^{ik.x} times lambda, so a
 * point moves toward the crest as in Gerstner's waves and
 * J = (1 + Dxx)(1 + Dzz) - Dxz^2 < 1 on crests.  The Nyquist row and column
 * are zero in every channel (S. G. Johnson 2011), so the band is symmetric.
 */
#include "ocean.h"
#include "ocean_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ocean_plan.h"
#include "ocean_time.h"

void ocean_params_default(ocean_params *p)
{
    memset(p, 0, sizeof *p);
    ocean_sea_state_default(&p->sea);
    p->seed = 1;
    p->n = 256;
    p->cascades = 1;
    p->patch_m = 1000.0;
    p->cascade_ratio = 4.3;
    p->k_max = INFINITY;
    p->threads = 2;
    p->plan_measure = OCEAN_PLAN_ESTIMATE;
    p->drop_gain = OCEAN_DROP_GAIN_DEFAULT;
}

int ocean_wait_policy_setenv(int spin)
{
    if (getenv("OMP_WAIT_POLICY"))
        return 0;
    setenv("OMP_WAIT_POLICY", "passive", 1);
    if (spin)
        setenv("GOMP_SPINCOUNT", OCEAN_GOMP_SPINCOUNT, 0);
    return 1;
}

/* The waves p would hold: the shortest within the time limit's
 * OCEAN_OMEGA_MAX, and none of the scene plan's refusals. */
static ocean_result params_check_waves(const ocean_params *p, char *msg, size_t msglen)
{
    /* The one time limit (ocean_time.h) holds for waves up to
     * OCEAN_OMEGA_MAX: the shortest wave held is the finest cascade's band
     * corner, or k_max below it. */
    double fine = p->patch_m / pow(p->cascade_ratio, p->cascades - 1);
    double k_top = fmin(M_SQRT2 * (p->n / 2 - 1) * 2.0 * M_PI / fine, p->k_max);
    double w_top = ocean_dispersion(k_top, p->sea.depth_m);
    if (w_top > OCEAN_OMEGA_MAX) {
        if (msg) snprintf(msg, msglen,
                          "the shortest wave held, %.3g m (k = %.4g rad/m, w = %.4g rad/s, finest "
                          "patch %g m at n = %d), is beyond w = %g rad/s (OCEAN_OMEGA_MAX, the "
                          "%.3g m wave the time limit is built on): use ocean.k_max <= %.4g rad/m, a "
                          "smaller n or a larger finest patch",
                          2.0 * M_PI / k_top, k_top, w_top, fine, p->n, OCEAN_OMEGA_MAX,
                          2.0 * M_PI / ocean_wavenumber(OCEAN_OMEGA_MAX, p->sea.depth_m),
                          ocean_wavenumber(OCEAN_OMEGA_MAX, p->sea.depth_m));
        return OCEAN_EINVAL;
    }
    /* The scene plan's refusals (ocean_plan.h): peak beyond the patch,
     * Hs beyond the breaking height. */
    ocean_plan plan;
    ocean_plan_init(&plan);
    ocean_plan_params(p, &plan);
    for (int i = 0; i < plan.count; i++)
        if (plan.item[i].level == OCEAN_PLAN_REFUSE) {
            if (msg) snprintf(msg, msglen, "%s", plan.item[i].text);
            return OCEAN_EINVAL;
        }
    return OCEAN_OK;
}

ocean_result ocean_params_validate(const ocean_params *p, char *msg, size_t msglen)
{
    if (!p) {
        if (msg) snprintf(msg, msglen, "parameters are NULL");
        return OCEAN_EINVAL;
    }
    ocean_result r = ocean_sea_state_validate(&p->sea, msg, msglen);
    if (r != OCEAN_OK)
        return r;
    if (p->n < OCEAN_MIN_N || p->n > OCEAN_MAX_N || (p->n & (p->n - 1)) != 0) {
        if (msg) snprintf(msg, msglen, "n = %d must be a power of two in [%d, %d]",
                          p->n, OCEAN_MIN_N, OCEAN_MAX_N);
        return OCEAN_EINVAL;
    }
    if (p->cascades < 1 || p->cascades > OCEAN_MAX_CASCADES) {
        if (msg) snprintf(msg, msglen, "cascades = %d is out of range [1, %d]",
                          p->cascades, OCEAN_MAX_CASCADES);
        return OCEAN_EINVAL;
    }
    if (!isfinite(p->patch_m) || p->patch_m < 1.0 || p->patch_m > 1e5) {
        if (msg) snprintf(msg, msglen, "patch = %g m is out of range [1, 100000]", p->patch_m);
        return OCEAN_EINVAL;
    }
    if (!isfinite(p->cascade_ratio) || p->cascade_ratio < 1.5 || p->cascade_ratio > 100.0) {
        if (msg) snprintf(msg, msglen, "cascade_ratio = %g is out of range [1.5, 100]",
                          p->cascade_ratio);
        return OCEAN_EINVAL;
    }
    if (isnan(p->k_max) || p->k_max <= 0.0) {
        if (msg) snprintf(msg, msglen, "k_max = %g must be > 0 (INFINITY for none)", p->k_max);
        return OCEAN_EINVAL;
    }
    if (!(p->drop_gain > 0.0 && p->drop_gain <= M_SQRT1_2 + 1e-12)) {
        if (msg) snprintf(msg, msglen, "drop_gain = %g is out of range (0, 0.7071]", p->drop_gain);
        return OCEAN_EINVAL;
    }
    if (p->threads < 1 || p->threads > 64) {
        if (msg) snprintf(msg, msglen, "threads = %d is out of range [1, 64]", p->threads);
        return OCEAN_EINVAL;
    }
    r = params_check_waves(p, msg, msglen);
    if (r != OCEAN_OK)
        return r;
    if (p->plan_measure < OCEAN_PLAN_ESTIMATE || p->plan_measure > OCEAN_PLAN_WISDOM) {
        if (msg) snprintf(msg, msglen, "plan = %d is not estimate, measure or wisdom", p->plan_measure);
        return OCEAN_EINVAL;
    }
    if (memchr(p->wisdom, '\0', sizeof p->wisdom) == NULL) {
        if (msg) snprintf(msg, msglen, "wisdom: path not terminated within %d bytes", OCEAN_WISDOM_PATH_MAX);
        return OCEAN_EINVAL;
    }
    if (p->plan_measure == OCEAN_PLAN_WISDOM && p->wisdom[0] == '\0') {
        if (msg) snprintf(msg, msglen, "plan = wisdom needs a wisdom file (ocean.wisdom = PATH; "
                          "`ocean-sim wisdom --out PATH` writes one)");
        return OCEAN_EINVAL;
    }
    return OCEAN_OK;
}

const ocean_params *ocean_get_params(const ocean *o)
{
    return &o->p;
}

void ocean_cascade_band(const ocean *o, int c, double *patch_m, double *k_lo, double *k_hi)
{
    const ocean_cascade *cs = &o->cas[c];
    if (patch_m) *patch_m = cs->patch;
    if (k_lo) *k_lo = cs->k_lo;
    if (k_hi) *k_hi = cs->k_hi;
}

static ocean_result ocean_build(const ocean_params *p, int lattice, const ocean_lattice_wave *lw,
                                int nlw, ocean **out, char *msg, size_t msglen);

ocean_result ocean_create(const ocean_params *p, ocean **out, char *msg, size_t msglen)
{
    *out = NULL;
    ocean_result r = ocean_params_validate(p, msg, msglen);
    if (r != OCEAN_OK)
        return r;
    return ocean_build(p, 0, NULL, 0, out, msg, msglen);
}

ocean_result ocean_create_lattice(const ocean_params *p, double patch_m, const ocean_lattice_wave *w,
                                  int count, ocean **out, char *msg, size_t msglen)
{
    if (!out)
        return OCEAN_EINVAL;
    *out = NULL;
    if (!p || (count > 0 && !w) || count < 0 || count > OCEAN_LATTICE_MAX_WAVES) {
        if (msg) snprintf(msg, msglen, "lattice: parameters or waves missing, or count = %d "
                          "outside [0, %d]", count, OCEAN_LATTICE_MAX_WAVES);
        return OCEAN_EINVAL;
    }
    if (!isfinite(patch_m) || patch_m < 1e-3 || patch_m > 1e5) {
        if (msg) snprintf(msg, msglen, "lattice: patch = %g m is out of range [0.001, 100000]", patch_m);
        return OCEAN_EINVAL;
    }
    /* The spectrum checks of ocean_params_validate (peak within the patch,
     * breaking height) are about a spectrum cascade; a lattice carries
     * given waves.  What the evaluation relies on is checked: the grid,
     * threads, planning, the sea (depth, choppiness) and the time limit. */
    ocean_params q = *p;
    q.cascades = 1;
    q.patch_m = patch_m;
    q.k_max = INFINITY;
    ocean_result r = ocean_sea_state_validate(&q.sea, msg, msglen);
    if (r != OCEAN_OK)
        return r;
    if (q.n < OCEAN_MIN_N || q.n > OCEAN_MAX_N || (q.n & (q.n - 1)) != 0 || q.threads < 1 ||
        q.threads > 64 || !(q.drop_gain > 0.0 && q.drop_gain <= M_SQRT1_2 + 1e-12) ||
        q.plan_measure < OCEAN_PLAN_ESTIMATE || q.plan_measure > OCEAN_PLAN_WISDOM ||
        memchr(q.wisdom, '\0', sizeof q.wisdom) == NULL ||
        (q.plan_measure == OCEAN_PLAN_WISDOM && q.wisdom[0] == '\0')) {
        if (msg) snprintf(msg, msglen, "lattice: n = %d, threads = %d, drop_gain = %g or the plan "
                          "mode is invalid (see ocean_params_validate)", q.n, q.threads, q.drop_gain);
        return OCEAN_EINVAL;
    }
    double dk = 2.0 * M_PI / patch_m;
    for (int i = 0; i < count; i++) {
        double w_i = ocean_dispersion(hypot(w[i].mx * dk, w[i].mz * dk), q.sea.depth_m);
        if (!(w_i <= OCEAN_OMEGA_MAX)) {
            if (msg) snprintf(msg, msglen, "lattice wave %d: w = %g rad/s is beyond OCEAN_OMEGA_MAX = %g",
                              i, w_i, OCEAN_OMEGA_MAX);
            return OCEAN_EINVAL;
        }
    }
    return ocean_build(&q, 1, w, count, out, msg, msglen);
}

/* Every cascade's waves: from the spectrum, or the given lattice waves. */
static ocean_result build_cascades(ocean *o, int lattice, const ocean_lattice_wave *lw, int nlw,
                                   char *msg, size_t msglen)
{
    for (int c = 0; c < o->p.cascades; c++) {
        char why[256] = "";
        ocean_result r = lattice ? ocean_modes_build_lattice(o, lw, nlw, why, sizeof why) : ocean_modes_build(o, c);
        if (r != OCEAN_OK) {
            if (msg) {
                if (why[0]) snprintf(msg, msglen, "%s", why);
                else snprintf(msg, msglen, "out of memory for cascade %d", c);
            }
            return r;
        }
    }
    return OCEAN_OK;
}

static ocean_result ocean_build(const ocean_params *p, int lattice, const ocean_lattice_wave *lw,
                                int nlw, ocean **out, char *msg, size_t msglen)
{
    *out = NULL;
    ocean_fft_init();
    ocean *o = calloc(1, sizeof *o);
    if (!o) {
        if (msg) snprintf(msg, msglen, "out of memory");
        return OCEAN_ENOMEM;
    }
    o->p = *p;
    ocean_force_paths(o, -1, -1);
    o->split_mode = -1;
    o->prune = 1;
    ocean_result r = build_cascades(o, lattice, lw, nlw, msg, msglen);
    if (r != OCEAN_OK) {
        ocean_destroy(o);
        return r;
    }
    int n = p->n;
    const ocean_cascade *fin = &o->cas[p->cascades - 1];
    double corner = M_SQRT2 * (n / 2 - 1) * fin->dk;
    o->k_top = fin->k_hi < corner ? fin->k_hi : corner;
    o->spec = fftwf_malloc(sizeof(fftwf_complex) * CH_COUNT * (size_t)n * (n / 2 + 1));
    r = o->spec ? ocean_fft_plan(o, msg, msglen) : OCEAN_ENOMEM;
    if (!o->spec && msg)
        snprintf(msg, msglen, "out of memory for %d-point spectra", n);
    if (r != OCEAN_OK) {
        ocean_destroy(o);
        return r;
    }
    *out = o;
    return OCEAN_OK;
}

void ocean_destroy(ocean *o)
{
    if (!o)
        return;
    ocean_fft_free(o);
    fftwf_free(o->spec);
    for (int c = 0; c < OCEAN_MAX_CASCADES; c++)
        ocean_modes_free(&o->cas[c]);
    for (int i = 0; i < GAIN_PLANES; i++)
        free(o->gains[i].g);
    free(o);
}

void ocean_request_all(ocean_request *r, unsigned effects)
{
    memset(r, 0, sizeof *r);
    for (int c = 0; c < OCEAN_MAX_CASCADES; c++)
        r->effects[c] = effects;
    r->cutoff_k = INFINITY;
    r->order = 6;
    r->low_boost = 1.0;
    r->foam_map = 1;
}

/* Float arithmetic only, so the field pass below vectorises. */
static inline float foam_from_jacobian(float j)
{
    float f = 1.0f - j * (float)(1.0 / OCEAN_FOAM_J_CLEAR);
    return f < 0.0f ? 0.0f : (f > 1.0f ? 1.0f : f);
}

float ocean_foam_from_jacobian(float j)
{
    return foam_from_jacobian(j);
}

ocean_result ocean_frame_create(const ocean *o, ocean_frame **out)
{
    ocean_frame *f = calloc(1, sizeof *f);
    *out = NULL;
    if (!f)
        return OCEAN_ENOMEM;
    f->cascades = o->p.cascades;
    f->n_max = o->p.n;
    for (int c = 0; c < f->cascades; c++) {
        size_t nn = (size_t)o->p.n * o->p.n;
        f->block[c] = fftwf_malloc(sizeof(float) * CH_COUNT * nn);
        f->derived[c] = fftwf_malloc(sizeof(float) * 2 * nn);
        if (!f->block[c] || !f->derived[c]) {
            ocean_frame_destroy(f);
            return OCEAN_ENOMEM;
        }
        f->patch[c] = o->cas[c].patch;
    }
    *out = f;
    return OCEAN_OK;
}

void ocean_frame_destroy(ocean_frame *f)
{
    if (!f)
        return;
    for (int c = 0; c < OCEAN_MAX_CASCADES; c++) {
        fftwf_free(f->block[c]);
        fftwf_free(f->derived[c]);
    }
    free(f);
}

/* A filter whose gain over the whole band stays above 1 - 1e-6 changes
 * no float: the evaluation is the unfiltered one. */
#define NOOP_LOSS 1e-6

/* Which channels an effect mask needs, in block order; returns the count. */
static int channel_list(unsigned effects, int ch[CH_COUNT])
{
    int m = 0;
    if (effects & OCEAN_FX_HEIGHT) ch[m++] = CH_H;
    if (effects & OCEAN_FX_DISPLACEMENT) { ch[m++] = CH_DX; ch[m++] = CH_DZ; }
    if (effects & OCEAN_FX_NORMALS) { ch[m++] = CH_SX; ch[m++] = CH_SZ; }
    if (effects & OCEAN_FX_FOAM) { ch[m++] = CH_DXX; ch[m++] = CH_DZZ; ch[m++] = CH_DXZ; ch[m++] = CH_BQ; }
    if (effects & OCEAN_FX_VELOCITY) { ch[m++] = CH_VX; ch[m++] = CH_VY; ch[m++] = CH_VZ; }
    return m;
}

/* Jacobian J = (1 + Dxx)(1 + Dzz) - Dxz^2 and foam for rows [r0, r1) of an
 * n-point field; cloned for AVX2 like spectrum_row.  The active ramp
 * vectorises in float; the trails (foam.h) are then added where the
 * envelope reaches the ramp, a minority of the points. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
static void jacobian_rows(ocean_field *fd, long i0, long i1, const ocean_foam_map *m,
                          double inv_lambda)
{
    const float *restrict xx = fd->dxx, *restrict zz = fd->dzz, *restrict xz = fd->dxz;
    const float *restrict bq = fd->bq;
    float *restrict jac = fd->jacobian, *restrict foam = fd->foam;
    for (long i = i0; i < i1; i++)
        jac[i] = (1.0f + xx[i]) * (1.0f + zz[i]) - xz[i] * xz[i];
    /* foam = clamp((beta - a) / (b - a)) as ocean_foam_ramp, in float so
     * the pass vectorises; a constant field, or a step, otherwise. */
    if (m->uniform >= 0.0 || !(m->b > m->a)) {
        for (long i = i0; i < i1; i++)
            foam[i] = (float)ocean_foam_value(m, ocean_foam_beta(xx[i], zz[i], inv_lambda),
                                              ocean_foam_beta(bq[i], 0.0, inv_lambda));
        return;
    }
    float s = (float)(-inv_lambda / (m->b - m->a)), off = (float)(-m->a / (m->b - m->a));
#pragma omp simd
    for (long i = i0; i < i1; i++) {
        float f = (xx[i] + zz[i]) * s + off;
        foam[i] = f < 0.0f ? 0.0f : (f > 1.0f ? 1.0f : f);
    }
    if (!(m->decay < INFINITY))
        return;
    /* The trails (foam.h): the crest's foam, the ramp at the envelope,
     * times ocean_foam_fade; select, no branch, so the pass vectorises. */
    float il = (float)inv_lambda, fa = (float)m->a, fb = 1.0f / (float)(m->b - m->a), dk = (float)m->decay;
#pragma omp simd
    for (long i = i0; i < i1; i++) {
        float beta = -(xx[i] + zz[i]) * il, q = -bq[i] * il;
        float fe = (sqrtf(beta * beta + q * q) - fa) * fb;
        fe = fe > 1.0f ? 1.0f : fe;
        float tr = fe * ocean_foam_fade(beta, q, dk);
        foam[i] = tr > foam[i] ? tr : foam[i]; /* fe <= 0: tr <= 0, no trail */
    }
}

static void set_field_pointers(ocean_frame *f, int c, int n, unsigned effects,
                               const int *ch, int nch, int foam_map)
{
    ocean_field *fd = &f->field[c];
    memset(fd, 0, sizeof *fd);
    fd->n = n;
    fd->patch_m = f->patch[c];
    fd->effects = effects;
    size_t nn = (size_t)n * n;
    for (int j = 0; j < nch; j++) {
        float *p = f->block[c] + (size_t)j * nn;
        switch (ch[j]) {
        case CH_H: fd->height = p; break;
        case CH_DX: fd->dx = p; break;
        case CH_DZ: fd->dz = p; break;
        case CH_SX: fd->slope_x = p; break;
        case CH_SZ: fd->slope_z = p; break;
        case CH_DXX: fd->dxx = p; break;
        case CH_DZZ: fd->dzz = p; break;
        case CH_DXZ: fd->dxz = p; break;
        case CH_BQ: fd->bq = p; break;
        case CH_VX: fd->vel_x = p; break;
        case CH_VY: fd->vel_y = p; break;
        case CH_VZ: fd->vel_z = p; break;
        }
    }
    if ((effects & OCEAN_FX_FOAM) && foam_map) {
        fd->jacobian = f->derived[c];
        fd->foam = f->derived[c] + nn;
    }
}

/* The gain plane of (cascade, n, filter), found or claimed (least recently
 * used).  *ready says whether it already holds the gains.  NULL when
 * memory runs out: the rows then compute their gains as they go, so an
 * allocation failure costs time, never a wrong field. */
static float *gain_plane_get(ocean *o, int c, int n, double kc, int order, double scale,
                             double boost, int *ready)
{
    ocean_gain_plane *victim = &o->gains[0];
    uint64_t now = ++o->gain_clock;
    for (int i = 0; i < GAIN_PLANES; i++) {
        ocean_gain_plane *gp = &o->gains[i];
        if (gp->used && gp->cascade == c && gp->n == n && gp->kc == kc && gp->order == order &&
            gp->scale == scale && gp->boost == boost) {
            gp->used = now;
            *ready = 1;
            return gp->g;
        }
        if (gp->used < victim->used)
            victim = gp;
    }
    size_t need = (size_t)n * (n / 2 + 1);
    if (victim->cap < need) {
        float *g = realloc(victim->g, sizeof(float) * need);
        if (!g) {
            *ready = 0;
            return NULL;
        }
        victim->g = g;
        victim->cap = need;
    }
    *victim = (ocean_gain_plane){c, n, order, kc, scale, boost, now, victim->cap, victim->g};
    *ready = 0;
    return victim->g;
}

/* Channels per FFTW call on the n-point grid.  Eight spectra at N = 1024
 * are 34 MB, more than a last-level cache holds, so one batched transform
 * found what the row pass wrote already evicted and ran from memory; in
 * groups of at most GROUP_BYTES of spectra, each group's row pass writes
 * into the same region of o->spec and its transform reads it from the cache
 * (bench_core, "Channels per FFTW call").  A constant rather than the
 * machine's cache size: the plans a group uses, and so the bits, must not
 * depend on the host (replicas agree bit for bit). */
#define GROUP_BYTES 8.5e6

static int group_size(const ocean *o, int n, int nch)
{
    if (o->group > 0)
        return o->group < nch ? o->group : nch;
    double per = (double)n * (n / 2 + 1) * sizeof(fftwf_complex);
    int g = (int)(GROUP_BYTES / per);
    return g < 1 ? 1 : g < nch ? g : nch;
}

void ocean_force_group(ocean *o, int group)
{
    if (o)
        o->group = group > 0 && group <= CH_COUNT ? group : 0;
}

double ocean_effective_cutoff(const ocean *o, double cutoff_k, int order)
{
    if (isnan(cutoff_k) || cutoff_k < 0.0 || order < 1 || order > OCEAN_FILTER_MAX_ORDER)
        return NAN;
    if (isinf(cutoff_k) || ocean_filter_gain(o->k_top, cutoff_k, order) >= 1.0 - NOOP_LOSS)
        return INFINITY;
    return cutoff_k;
}

static ocean_result request_check(const ocean *o, double t, const ocean_request *r,
                                  const ocean_frame *f)
{
    if (!o || !r || !f || f->cascades != o->p.cascades || f->n_max != o->p.n)
        return OCEAN_EINVAL;
    if (!ocean_time_ok(t) || isnan(r->cutoff_k) || r->cutoff_k < 0.0 || r->order < 1 ||
        r->order > OCEAN_FILTER_MAX_ORDER || !isfinite(r->low_boost) || r->low_boost < 0.0 || r->low_boost > 2.0)
        return OCEAN_EINVAL;
    if (r->per_cascade) {
        /* a per-cascade frame holds each cascade's breaking index, which a
         * reader sums before any ramp (PROTOCOL.md "Whitecaps in layout
         * 1"): no cascade has a foam of its own */
        if (r->redistribute || (r->low_boost != 0.0 && r->low_boost != 1.0) || r->foam_map)
            return OCEAN_EINVAL;
        for (int c = 0; c < o->p.cascades; c++)
            if (isnan(r->cascade_cutoff_k[c]) || r->cascade_cutoff_k[c] < 0.0)
                return OCEAN_EINVAL;
    }
    return OCEAN_OK;
}

/* The filter of one evaluation, as every cascade applies it unless the
 * request gives each its own cutoff. */
typedef struct eval_filter {
    double kc, kneg, scale, boost;
} eval_filter;

/* The frame's foam mapping.  The whitecap ramp depends on the filter, not
 * on t: memoised. */
static void frame_foam_setup(ocean *o, const ocean_request *r, const eval_filter *ef, ocean_frame *f)
{
    int any_foam = 0;
    for (int c = 0; c < o->p.cascades; c++)
        any_foam |= (r->effects[c] & OCEAN_FX_FOAM) != 0;
    double lam = o->p.sea.choppiness;
    f->foam_inv_lambda = lam > 0.0 ? 1.0 / lam : 0.0;
    f->info.whitecap_target = ocean_stats_whitecap_target(o);
    for (int rd = 0; rd < OCEAN_FOAM_READINGS; rd++) {
        f->foam_sigma[rd] = f->foam_omega[rd] = 0.0;
        f->foam_map[rd] = any_foam ? ocean_stats_foam(o, (ocean_foam_reading)rd, ef->kc, r->order, ef->scale,
                                                      ef->boost, &f->foam_sigma[rd], &f->foam_omega[rd])
                                   /* read by nothing (no foam channel), but defined */
                                   : (ocean_foam_map){INFINITY, INFINITY, -1.0, INFINITY};
    }
    f->info.foam_sigma = f->foam_sigma[OCEAN_FOAM_BILINEAR];
    f->info.foam_omega = f->foam_omega[OCEAN_FOAM_BILINEAR];
}

/* Modes of the n-point grid an evolving pass computed, and of those the
 * deep-water ones (ocean_counters). */
static void count_evolved(ocean *o, const ocean_cascade *cs, int n)
{
    for (int p = 0; p <= n / 2; p++) {
        int lo, hi;
        ocean_pair_range(cs, n, p, &lo, &hi);
        int rows = p == 0 || p == n / 2 ? 1 : 2, d = o->deep_table ? hi : cs->deep[p];
        o->counters.modes_evolved += (uint64_t)(hi - lo) * rows;
        o->counters.modes_deep += (uint64_t)(hi - (d > lo ? (d < hi ? d : hi) : lo)) * rows;
    }
}

/* One FFTW call's a->nch channels: the stage pass writes their spectra
 * (the first call of the tick evolving h(k,t) into the cache, the others
 * reading it back), then FFTW transforms them into out. */
static void stage_and_transform(ocean *o, ocean_stage_args *a, int nt, const int *split, size_t plane,
                                int by_channel, float *out)
{
    ocean_cascade *cs = a->cs;
    int n = a->n, gn = a->nch;
    uint64_t t0 = ocean_now_ns();
#pragma omp parallel num_threads(nt) if (nt > 1)
    ocean_stage_pass(a, nt, split, plane, by_channel && gn >= nt);
    uint64_t t1 = ocean_now_ns();
    *(a->cached ? &o->counters.ns_channels : &o->counters.ns_evolve) += t1 - t0;
    if (!a->cached) {
        count_evolved(o, cs, n);
        cs->cache_t = a->t;
        cs->cache_n = n;
        cs->cache_dt = a->need_dt;
        a->cached = 1;
    }
    a->gain_ready = a->gain != NULL;
    uint64_t t2 = ocean_now_ns();
    o->counters.fft_calls_pruned += ocean_fft_run(o, cs, n, gn, out);
    o->counters.ns_fft += ocean_now_ns() - t2;
    o->counters.fft_calls++;
    o->counters.fft_calls_by_channel += by_channel && gn >= nt;
}

/* Every channel a->ch[0 .. a->nch) of cascade c into the frame's block,
 * in FFTW calls of group_size channels. */
static void cascade_transform(ocean *o, int c, ocean_stage_args *a, ocean_frame *f)
{
    const ocean_cascade *cs = a->cs;
    int n = a->n, nch = a->nch;
    const int *ch = a->ch;
    /* Claimed here, where every row fills it, never for a cascade wholly
     * above the cutoff: a claimed plane is trusted from then on. */
    if (!(isinf(a->kc) && a->scale == 1.0 && a->boost == 1.0 && n == a->n_full))
        a->gain = gain_plane_get(o, c, n, a->kc, a->order, a->scale, a->boost, &a->gain_ready);
    int g = group_size(o, n, nch);
    int nt = n >= PARALLEL_MIN_N ? o->p.threads : 1, split[STAGE_MAX_THREADS + 1];
    size_t plane = (size_t)n * (n / 2 + 1);
    ocean_stage_split(cs, n, nt, split);
    /* Split by channel or by rows: the same bits, but which is faster
     * depends on how busy this machine's caches are (ocean_stage_channels), so
     * the ocean measures both and runs the faster.  Only where a call has
     * a channel for every thread. */
    ocean_split_stat *st = &o->split[c][ocean_level_of(n)][a->cached];
    int by_channel = nt > 1 && (g < nch ? g : nch) >= nt ? ocean_stage_split_pick(o, st) : 0;
    uint64_t c_start = ocean_now_ns();
    for (int j0 = 0; j0 < nch; j0 += g) {
        int gn = nch - j0 < g ? nch - j0 : g;
        a->ch = ch + j0;
        a->nch = gn;
        a->stream = (double)gn * n * (n / 2 + 1) * sizeof(fftwf_complex) > o->stream_bytes;
        stage_and_transform(o, a, nt, split, plane, by_channel, f->block[c] + (size_t)j0 * n * n);
    }
    if (nt > 1 && (g < nch ? g : nch) >= nt)
        ocean_stage_split_note(st, by_channel, (double)(ocean_now_ns() - c_start) / nch);
    for (int j = 0; j < nch; j++) {
        int e = ch[j] == CH_H ? 0 : ch[j] <= CH_DZ ? 1 : ch[j] <= CH_SZ ? 2
              : ch[j] <= CH_BQ ? 3 : 4;
        o->counters.transforms_by_effect[e]++;
    }
}

/* Cascade c's fields for request r; returns the transforms run. */
static int evaluate_cascade(ocean *o, int c, double t, const ocean_request *r,
                            const eval_filter *ef, ocean_frame *f)
{
    ocean_cascade *cs = &o->cas[c];
    int n_full = o->p.n;
    double kc = ef->kc, kneg = ef->kneg;
    if (r->per_cascade) {
        kc = r->cascade_cutoff_k[c];
        kneg = ocean_negligible_k(o, kc, r->order);
    }
    unsigned fx = r->effects[c] & (OCEAN_FX_ALL | OCEAN_FX_VELOCITY);
    int ch[CH_COUNT];
    int nch = channel_list(fx, ch);
    /* A cascade wholly above the cutoff contributes zero fields at the
     * smallest size: nothing to transform. */
    int n = cs->k_lo >= kneg ? OCEAN_MIN_N : ocean_pick_size(cs, n_full, kneg);
    set_field_pointers(f, c, n, fx, ch, nch, r->foam_map);
    if (nch == 0)
        return 0;
    int transforms = 0;
    if (cs->k_lo >= kneg) {
        memset(f->block[c], 0, sizeof(float) * nch * (size_t)n * n);
    } else {
        /* The row pass caches every mode of the grid it covers, so any
         * later request of the same tick on a grid no larger reuses it. */
        int need_dt = (fx & (OCEAN_FX_VELOCITY | OCEAN_FX_FOAM)) != 0; /* foam: its quadrature */
        int cached = cs->cache_n >= n && cs->cache_t == t && (cs->cache_dt || !need_dt);
        ocean_stage_args a = {cs, cached, need_dt, n_full, n, nch, ch, t, kc, kneg, ef->scale, ef->boost,
                        o->p.sea.choppiness, r->order, o->spec, NULL, 0, o->fused,
                        (double)nch * n * (n / 2 + 1) * sizeof(fftwf_complex) > o->stream_bytes,
                        o->deep_table};
        cascade_transform(o, c, &a, f);
        transforms = nch;
    }
    if ((fx & OCEAN_FX_FOAM) && r->foam_map) {
        ocean_field *fd = &f->field[c];
        long nn = (long)n * n, step = (long)n * 8;
#pragma omp parallel for num_threads(o->p.threads) schedule(static) if (n >= PARALLEL_MIN_N)
        for (long i = 0; i < nn; i += step)
            jacobian_rows(fd, i, i + step < nn ? i + step : nn, &f->foam_map[OCEAN_FOAM_BILINEAR],
                          f->foam_inv_lambda);
    }
    return transforms;
}

ocean_result ocean_evaluate(ocean *o, double t, const ocean_request *r, ocean_frame *f)
{
    ocean_result res = request_check(o, t, r, f);
    if (res != OCEAN_OK)
        return res;
    eval_filter ef;
    ef.kc = ocean_effective_cutoff(o, r->cutoff_k, r->order);
    ef.kneg = ocean_negligible_k(o, ef.kc, r->order);
    ef.scale = r->redistribute && !isinf(ef.kc) ? ocean_stats_redistribution(o, ef.kc, r->order) : 1.0;
    ef.boost = r->low_boost > 0.0 ? r->low_boost : 1.0;
    frame_foam_setup(o, r, &ef, f);
    int transforms = 0;
    for (int c = 0; c < o->p.cascades; c++)
        transforms += evaluate_cascade(o, c, t, r, &ef, f);
    f->info.t = t;
    f->info.cutoff_k = r->per_cascade ? NAN : ef.kc;
    f->info.transforms = transforms;
    f->info.cascades = o->p.cascades;
    f->info.e_error = r->per_cascade ? 0.0 : ocean_stats_error(o, ef.kc, r->order, ef.scale, ef.boost);
    o->counters.evaluations++;
    o->counters.transforms += (uint64_t)transforms;
    return OCEAN_OK;
}

/* The FFTW calls of ocean_evaluate(o, ., r, f); with write_spectra, each
 * call's spectra are first overwritten with zeros, split over the threads
 * as the stage would split an evolving pass now (ocean_stage_split_best: by channel,
 * or by row pairs). */
static ocean_result transform_groups(ocean *o, const ocean_request *r, ocean_frame *f, int write_spectra)
{
    if (!o || !r || !f || f->cascades != o->p.cascades || isnan(r->cutoff_k) ||
        r->cutoff_k < 0.0 || r->order < 1 || r->order > OCEAN_FILTER_MAX_ORDER)
        return OCEAN_EINVAL;
    double kneg = ocean_negligible_k(o, ocean_effective_cutoff(o, r->cutoff_k, r->order), r->order);
    for (int c = 0; c < o->p.cascades; c++) {
        const ocean_cascade *cs = &o->cas[c];
        int ch[CH_COUNT];
        int nch = channel_list(r->effects[c] & (OCEAN_FX_ALL | OCEAN_FX_VELOCITY), ch);
        if (nch == 0 || cs->k_lo >= kneg)
            continue;
        int n = ocean_pick_size(cs, o->p.n, kneg), half = n / 2 + 1;
        size_t plane = (size_t)n * half;
        int g = group_size(o, n, nch);
        int nt = n >= PARALLEL_MIN_N ? o->p.threads : 1, split[STAGE_MAX_THREADS + 1];
        ocean_stage_split(cs, n, nt, split);
        for (int j0 = 0; j0 < nch; j0 += g) {
            int gn = nch - j0 < g ? nch - j0 : g;
            if (write_spectra && nt > 1 && gn >= nt && ocean_stage_split_best(o, &o->split[c][ocean_level_of(n)][0])) {
#pragma omp parallel num_threads(nt)
                {
                    int c0, c1;
                    ocean_stage_channels(gn, &c0, &c1);
                    memset(o->spec + (size_t)c0 * plane, 0, sizeof(fftwf_complex) * plane * (size_t)(c1 - c0));
                }
            } else if (write_spectra) {
#pragma omp parallel num_threads(nt) if (nt > 1)
                {
                    int r0, r1;
                    ocean_stage_rows(cs, n, nt, split, &r0, &r1);
                    for (int p = r0; p < r1; p++)
                        for (int j = 0; j < gn; j++) {
                            fftwf_complex *row = o->spec + (size_t)j * plane;
                            memset(row + (size_t)p * half, 0, sizeof(fftwf_complex) * half);
                            if (p != 0 && p != n / 2)
                                memset(row + (size_t)(n - p) * half, 0, sizeof(fftwf_complex) * half);
                        }
                }
            }
            ocean_fft_run(o, cs, n, gn, f->block[c] + (size_t)j0 * n * n);
        }
    }
    return OCEAN_OK;
}

ocean_result ocean_transform_only(ocean *o, const ocean_request *r, ocean_frame *f)
{
    return transform_groups(o, r, f, 0);
}

ocean_result ocean_transform_floor(ocean *o, const ocean_request *r, ocean_frame *f)
{
    return transform_groups(o, r, f, 1);
}

const ocean_field *ocean_frame_field(const ocean_frame *f, int cascade)
{
    if (!f || cascade < 0 || cascade >= f->cascades)
        return NULL;
    return &f->field[cascade];
}

void ocean_frame_get_info(const ocean_frame *f, ocean_frame_info *out)
{
    *out = f->info;
}

void ocean_get_counters(const ocean *o, ocean_counters *out)
{
    *out = o->counters;
}
