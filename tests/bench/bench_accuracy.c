/*
 * bench_accuracy.c - what accuracy costs in time (issue 8).
 *
 * Sweeps every accuracy axis of the server - FFT resolution, cascade count,
 * Gerstner near-field wave count, cutoff policy and level, storage
 * precision, tile codec and quantisation step, mesh kind and density - and
 * for each setting measures the median time per tick (ocean_evaluate) and
 * per client frame (the per-client work: the client's tiles, laid out as
 * the daemon's defaults ask and encoded with its codec, plus the near
 * field; the mesh axis costs mesh update + displacement), beside the error
 * against a reference sea: height RMS (% of Hs) and max abs, normal angle
 * (RMS and max, degrees), foam coverage, E_error (ocean_frame_info), PSNR
 * of the height (peak = the reference's range) and of the normal map, and
 * SSIM of the normal map (Wang et al. 2004: 11x11 Gaussian window,
 * sigma 1.5, K1 = 0.01, K2 = 0.03, L = 1, normals as RGB = (n + 1) / 2).
 *
 * Reference.  The same sea (same seed, same spectrum, same patch) at
 * N = 2048, summed directly in double at S x S sample points (0.5 m apart,
 * offset from every FFT grid, so the bilinear reading between grid points
 * is part of what is measured).  Direct summation rather than the N = 2048
 * FFT field: the FFT field is float on a 0.49 m grid and reading it between
 * grid points adds bilinear error of the size being measured; the sum is
 * exact at any point.  It is separable (rows, then columns), so S x S
 * points cost O(modes x S), not O(modes x S^2).  Waves are keyed by wave
 * vector, so a single-cascade setting on the same patch carries a subset of
 * exactly these waves.  A setting with more cascades carries waves of other
 * patches (another draw of the same spectrum); its reference is then that
 * setting's own waves, summed exactly, completed with every wave of the
 * N = 2048 sea that falls outside the setting's bands - the same sea at the
 * reference resolution.  The Gerstner near field is an independent draw
 * (M waves standing for a whole band), so in its rows the reference keeps
 * the dense N = 2048 waves in that band; the slope-variance ratio column
 * shows what the near field restores statistically.  A self-check compares
 * the separable sum with ocean_reference_point.
 *
 * Outputs (paths relative to the repository root, where make runs it):
 *   stdout                              markdown sections for REPORT.md
 *   tests/bench/out/accuracy.csv        every setting, every metric
 *   tests/bench/out/acc_<axis>.dat      gnuplot data: index 0 all points,
 *                                       1 height front, 2 normal front,
 *                                       3 the shipped default
 *   tests/bench/out/scenes.csv          effects sets and scenes
 *   tests/bench/out/headline.md         the README's headline table
 * BENCH_QUICK=1 (or OCEAN_BENCH_QUICK=1) shrinks every sweep.
 */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "../lib/bench_util.h"
#include "codec.h"
#include "filter.h"
#include "gerstner.h"
#include "mesh.h"
#include "ocean.h"
#include "ocean_conf.h"
#include "ocean_reference.h"
#include "proto_buf.h"

#define OUT_DIR "tests/bench/out"
#define CONF_PATH "config/oceand.conf"
#define SCENE_DIR "config/scenes"
#define T0 137.25           /* the instant every error is measured at, s */
#define N_REF 2048
#define TILE 64
#define NCH 8               /* reference channels */

/* The daemon's per-client defaults (server/srv_config.c); a server.* key of
 * the same name in config/oceand.conf overrides each (read_server_keys). */
static double srv_mesh_error_px = 4.0;      /* server.mesh_error_px */
static double srv_view_range = 10000.0;     /* server.view_range, m */
static int srv_near_waves = 64;             /* server.near_field_waves */
static double srv_near_radius = 60.0;       /* server.near_field_radius, m */
static double srv_near_min_wl = 0.1;        /* server.near_field_min_wavelength, m */
static int srv_tiles_per_side = 2;          /* server.tiles_per_side */
static double srv_base_spacing = 2.0;       /* server.base_spacing, m */
#define FADE_R0 (0.5 * srv_near_radius)     /* near field full within, m */
#define FADE_R1 (srv_near_radius)           /* none beyond, m */

enum { C_H, C_DX, C_DZ, C_SX, C_SZ, C_DXX, C_DZZ, C_DXZ };

static int quick;
static int reps_tick, reps_frame;

/* ---- small helpers -------------------------------------------------------- */

static void *xcalloc(size_t n, size_t sz)
{
    void *p = calloc(n ? n : 1, sz);
    if (!p) {
        fprintf(stderr, "bench_accuracy: out of memory\n");
        exit(1);
    }
    return p;
}

/* ---- the sample window ------------------------------------------------------ */

typedef struct window {
    int s;            /* s x s points */
    double x0, z0, d; /* first point and spacing, m */
} window;

static window W;

static double win_x(int j) { return W.x0 + j * W.d; }
static double win_z(int i) { return W.z0 + i * W.d; }

/* A field sampled at the window's points: what a setting delivers or what
 * the reference says.  The Jacobian gives the foam. */
typedef struct sset {
    double *h, *dx, *dz, *sx, *sz, *jac;
    unsigned char *valid;   /* 0 where a mesh does not cover the point */
} sset;

static void sset_init(sset *s)
{
    size_t m = (size_t)W.s * W.s;
    double *b = xcalloc(6 * m, sizeof *b);
    s->h = b; s->dx = b + m; s->dz = b + 2 * m; s->sx = b + 3 * m; s->sz = b + 4 * m; s->jac = b + 5 * m;
    s->valid = xcalloc(m, 1);
    memset(s->valid, 1, m);
    for (size_t i = 0; i < m; i++)
        s->jac[i] = 1.0;
}

static void sset_free(sset *s)
{
    free(s->h);
    free(s->valid);
}

/* ---- reference: separable direct summation in double ---------------------- */

/* The half plane (mz > 0, or mz == 0 and mx > 0) of one wave-vector lattice,
 * |mx|, |mz| <= m, with h(k, t) in double; each mode stands for itself and
 * its Hermitian mirror. */
typedef struct lattice {
    double dk, patch;
    int m;
    double *h;   /* complex, (m + 1) rows x (2m + 1) columns */
} lattice;

static double *lat_at(const lattice *L, int mx, int mz)
{
    return L->h + 2 * ((size_t)mz * (2 * L->m + 1) + (size_t)(mx + L->m));
}

static void lattice_from_ocean(lattice *L, const ocean *o, int c, double t)
{
    double patch, klo, khi;
    ocean_cascade_band(o, c, &patch, &klo, &khi);
    L->patch = patch;
    L->dk = 2.0 * M_PI / patch;
    L->m = ocean_get_params(o)->n / 2 - 1;
    L->h = xcalloc(2 * (size_t)(L->m + 1) * (2 * L->m + 1), sizeof(double));
    int m = L->m;
#pragma omp parallel for schedule(dynamic, 8)
    for (int mz = 0; mz <= m; mz++)
        for (int mx = mz == 0 ? 1 : -m; mx <= m; mx++)
            ocean_mode_amplitude(o, c, mx, mz, t, lat_at(L, mx, mz));
}

/* out[ch][i][j] += sum over the lattice's modes of the channel's value at
 * window point (i, j).  Channel factors as in ocean_reference_point:
 * h; i lam kx/k h; i lam kz/k h; i kx h; i kz h; -lam kx^2/k h; ... */
static void dft_add(const lattice *L, double lam, double *out)
{
    const int s = W.s, m = L->m, ncol = 2 * m + 1;
    size_t ss = (size_t)s * s;
    double *ere = xcalloc((size_t)ncol * s, sizeof *ere), *eim = xcalloc((size_t)ncol * s, sizeof *eim);
    double *zr = xcalloc((size_t)s, sizeof *zr);
    for (int j = 0; j < s; j++) {
        double x = win_x(j), xr = x - floor(x / L->patch) * L->patch;
        for (int mx = -m; mx <= m; mx++) {
            double ph = fmod(mx * L->dk * xr, 2.0 * M_PI);
            ere[(size_t)(mx + m) * s + j] = cos(ph);
            eim[(size_t)(mx + m) * s + j] = sin(ph);
        }
    }
    for (int i = 0; i < s; i++) {
        double z = win_z(i);
        zr[i] = z - floor(z / L->patch) * L->patch;
    }
#pragma omp parallel
    {
        double *acc = xcalloc(NCH * ss, sizeof *acc);
        double *are = xcalloc(NCH * (size_t)s, sizeof *are), *aim = xcalloc(NCH * (size_t)s, sizeof *aim);
#pragma omp for schedule(dynamic, 4)
        for (int mz = 0; mz <= m; mz++) {
            memset(are, 0, sizeof(double) * NCH * s);
            memset(aim, 0, sizeof(double) * NCH * s);
            int any = 0;
            double kz = mz * L->dk;
            for (int mx = mz == 0 ? 1 : -m; mx <= m; mx++) {
                const double *hv = lat_at(L, mx, mz);
                if (hv[0] == 0.0 && hv[1] == 0.0)
                    continue;
                any = 1;
                double kx = mx * L->dk, k = hypot(kx, kz);
                /* real-type factors multiply h, i-type multiply i h */
                double r_h = 1.0, r_dxx = -lam * kx * kx / k, r_dzz = -lam * kz * kz / k, r_dxz = -lam * kx * kz / k;
                double r_dx = lam * kx / k, r_dz = lam * kz / k, r_sx = kx, r_sz = kz;
                const double *er = ere + (size_t)(mx + m) * s, *ei = eim + (size_t)(mx + m) * s;
                double hr = hv[0], hi = hv[1];
                for (int j = 0; j < s; j++) {
                    double pr = hr * er[j] - hi * ei[j], pi = hr * ei[j] + hi * er[j];
                    are[C_H * s + j] += r_h * pr;     aim[C_H * s + j] += r_h * pi;
                    are[C_DXX * s + j] += r_dxx * pr; aim[C_DXX * s + j] += r_dxx * pi;
                    are[C_DZZ * s + j] += r_dzz * pr; aim[C_DZZ * s + j] += r_dzz * pi;
                    are[C_DXZ * s + j] += r_dxz * pr; aim[C_DXZ * s + j] += r_dxz * pi;
                    are[C_DX * s + j] -= r_dx * pi;   aim[C_DX * s + j] += r_dx * pr;
                    are[C_DZ * s + j] -= r_dz * pi;   aim[C_DZ * s + j] += r_dz * pr;
                    are[C_SX * s + j] -= r_sx * pi;   aim[C_SX * s + j] += r_sx * pr;
                    are[C_SZ * s + j] -= r_sz * pi;   aim[C_SZ * s + j] += r_sz * pr;
                }
            }
            if (!any)
                continue;
            for (int i = 0; i < s; i++) {
                double ph = fmod(mz * L->dk * zr[i], 2.0 * M_PI), cr = cos(ph), ci = sin(ph);
                for (int ch = 0; ch < NCH; ch++) {
                    double *o = acc + ch * ss + (size_t)i * s;
                    const double *ar = are + ch * s, *ai = aim + ch * s;
                    for (int j = 0; j < s; j++)
                        o[j] += 2.0 * (ar[j] * cr - ai[j] * ci);
                }
            }
        }
#pragma omp critical
        for (size_t q = 0; q < NCH * ss; q++)
            out[q] += acc[q];
        free(acc);
        free(are);
        free(aim);
    }
    free(ere);
    free(eim);
    free(zr);
}

static void sset_from_channels(sset *r, const double *ch)
{
    size_t ss = (size_t)W.s * W.s;
    for (size_t q = 0; q < ss; q++) {
        r->h[q] = ch[C_H * ss + q];
        r->dx[q] = ch[C_DX * ss + q];
        r->dz[q] = ch[C_DZ * ss + q];
        r->sx[q] = ch[C_SX * ss + q];
        r->sz[q] = ch[C_SZ * ss + q];
        double a = ch[C_DXX * ss + q], b = ch[C_DZZ * ss + q], c = ch[C_DXZ * ss + q];
        r->jac[q] = (1.0 + a) * (1.0 + b) - c * c;
    }
}

/* The reference sea: the N = 2048 ocean on the base patch. */
static ocean *ref_ocean;
static lattice ref_lat;
static double *ref_full;   /* NCH x s x s channels of the whole N = 2048 sea */
static sset ref_set;
static double ref_hs;

/* Does a setting (ocean o) carry a wave at (kx, kz)?  Cascade c < K-1
 * holds the annulus [k_lo, k_hi); the last one [k_lo, k_max) inside its
 * square grid (|m| <= n/2 - 1, each mode standing for a cell dk wide). */
static int setting_covers(const ocean *o, double kx, double kz)
{
    const ocean_params *p = ocean_get_params(o);
    double k = hypot(kx, kz);
    for (int c = 0; c < p->cascades; c++) {
        double patch, lo, hi;
        ocean_cascade_band(o, c, &patch, &lo, &hi);
        if (k < lo || k >= hi)
            continue;
        if (c < p->cascades - 1)
            return 1;
        double edge = (p->n / 2 - 0.5) * 2.0 * M_PI / patch;
        if (fabs(kx) < edge && fabs(kz) < edge)
            return 1;
    }
    return 0;
}

/* Reference for a setting whose waves are not a subset of the N = 2048
 * sea's: its own waves plus the reference's waves it lacks.  lam is the
 * choppiness. */
static void reference_for(const ocean *o, double lam, sset *out)
{
    size_t ss = (size_t)W.s * W.s;
    double *ch = xcalloc(NCH * ss, sizeof *ch);
    lattice rest = ref_lat;
    size_t cnt = 2 * (size_t)(ref_lat.m + 1) * (2 * ref_lat.m + 1);
    rest.h = xcalloc(cnt, sizeof(double));
    memcpy(rest.h, ref_lat.h, cnt * sizeof(double));
    int m = ref_lat.m;
    for (int mz = 0; mz <= m; mz++)
        for (int mx = -m; mx <= m; mx++)
            if (setting_covers(o, mx * ref_lat.dk, mz * ref_lat.dk)) {
                double *h = lat_at(&rest, mx, mz);
                h[0] = h[1] = 0.0;
            }
    dft_add(&rest, lam, ch);
    free(rest.h);
    for (int c = 0; c < ocean_get_params(o)->cascades; c++) {
        lattice L;
        lattice_from_ocean(&L, o, c, T0);
        dft_add(&L, lam, ch);
        free(L.h);
    }
    sset_from_channels(out, ch);
    free(ch);
}

/* ---- metrics -------------------------------------------------------------------- */

typedef struct metrics {
    double h_rms_pct, h_max, n_rms_deg, n_max_deg;
    double foam_ref, foam_set;   /* mean coverage over the window, % */
    double e_error, psnr_h, psnr_n, ssim_n, slope_ratio, covered;
} metrics;

static void normal_of(double sx, double sz, double n[3])
{
    double l = sqrt(sx * sx + 1.0 + sz * sz);
    n[0] = -sx / l;
    n[1] = 1.0 / l;
    n[2] = -sz / l;
}

/* Mean SSIM of two s x s images in [0, 1] (Wang et al. 2004): Gaussian
 * window 11 x 11, sigma 1.5, over every position where it fits. */
static double ssim(const double *a, const double *b, int s)
{
    double g[11], gs = 0.0;
    for (int i = 0; i < 11; i++) {
        g[i] = exp(-((i - 5) * (i - 5)) / (2.0 * 1.5 * 1.5));
        gs += g[i];
    }
    for (int i = 0; i < 11; i++)
        g[i] /= gs;
    const double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;
    double sum = 0.0;
    int cnt = 0;
    for (int i = 0; i + 11 <= s; i++)
        for (int j = 0; j + 11 <= s; j++) {
            double ma = 0, mb = 0, aa = 0, bb = 0, ab = 0;
            for (int u = 0; u < 11; u++)
                for (int v = 0; v < 11; v++) {
                    double w = g[u] * g[v], x = a[(size_t)(i + u) * s + j + v], y = b[(size_t)(i + u) * s + j + v];
                    ma += w * x; mb += w * y; aa += w * x * x; bb += w * y * y; ab += w * x * y;
                }
            double va = aa - ma * ma, vb = bb - mb * mb, cv = ab - ma * mb;
            sum += ((2 * ma * mb + c1) * (2 * cv + c2)) / ((ma * ma + mb * mb + c1) * (va + vb + c2));
            cnt++;
        }
    return cnt ? sum / cnt : NAN;
}

static metrics compare(const sset *set, const sset *ref, double e_error)
{
    metrics mt;
    memset(&mt, 0, sizeof mt);
    int s = W.s;
    size_t ss = (size_t)s * s;
    double se = 0, mx = 0, lo = INFINITY, hi = -INFINITY, ang2 = 0, angmax = 0, nse = 0;
    double fr = 0, fs = 0, svs = 0, svr = 0;
    size_t cnt = 0;
    double *img_s = xcalloc(3 * ss, sizeof *img_s), *img_r = xcalloc(3 * ss, sizeof *img_r);
    for (size_t q = 0; q < ss; q++) {
        double nr[3], ns[3];
        normal_of(ref->sx[q], ref->sz[q], nr);
        normal_of(set->sx[q], set->sz[q], ns);
        if (!set->valid[q])
            memcpy(ns, nr, sizeof ns);   /* uncovered: neutral for the image */
        for (int c = 0; c < 3; c++) {
            img_r[c * ss + q] = 0.5 + 0.5 * nr[c];
            img_s[c * ss + q] = 0.5 + 0.5 * ns[c];
        }
        if (!set->valid[q])
            continue;
        cnt++;
        double e = set->h[q] - ref->h[q];
        se += e * e;
        if (fabs(e) > mx) mx = fabs(e);
        if (ref->h[q] < lo) lo = ref->h[q];
        if (ref->h[q] > hi) hi = ref->h[q];
        double d = ns[0] * nr[0] + ns[1] * nr[1] + ns[2] * nr[2];
        double a = acos(d > 1.0 ? 1.0 : d < -1.0 ? -1.0 : d) * 180.0 / M_PI;
        ang2 += a * a;
        if (a > angmax) angmax = a;
        for (int c = 0; c < 3; c++) {
            double dn = 0.5 * (ns[c] - nr[c]);
            nse += dn * dn;
        }
        fr += ocean_foam_from_jacobian((float)ref->jac[q]);
        fs += ocean_foam_from_jacobian((float)set->jac[q]);
        svs += set->sx[q] * set->sx[q] + set->sz[q] * set->sz[q];
        svr += ref->sx[q] * ref->sx[q] + ref->sz[q] * ref->sz[q];
    }
    double rms = cnt ? sqrt(se / cnt) : NAN;
    mt.covered = (double)cnt / ss;
    mt.h_rms_pct = 100.0 * rms / ref_hs;
    mt.h_max = mx;
    mt.n_rms_deg = cnt ? sqrt(ang2 / cnt) : NAN;
    mt.n_max_deg = angmax;
    mt.foam_ref = cnt ? 100.0 * fr / cnt : NAN;
    mt.foam_set = cnt ? 100.0 * fs / cnt : NAN;
    mt.e_error = e_error;
    mt.psnr_h = rms > 0 ? 20.0 * log10((hi - lo) / rms) : INFINITY;
    double nrms = cnt ? sqrt(nse / (3.0 * cnt)) : NAN;
    mt.psnr_n = nrms > 0 ? 20.0 * log10(1.0 / nrms) : INFINITY;
    mt.ssim_n = (ssim(img_s, img_r, s) + ssim(img_s + ss, img_r + ss, s) + ssim(img_s + 2 * ss, img_r + 2 * ss, s)) / 3.0;
    mt.slope_ratio = svr > 0 ? svs / svr : NAN;
    free(img_s);
    free(img_r);
    return mt;
}

/* ---- rows of the report ----------------------------------------------------- */

typedef struct row {
    char axis[16];
    char label[64];
    double tick_ms, frame_ms, bytes;   /* bytes per client frame (tiles) */
    double extra;                      /* axis-specific: kc, vertices, decode ms ... */
    metrics m;
    int is_default, front_h, front_n;
} row;

static row *rows;
static int nrows, cap_rows;

static row *row_add(const char *axis, const char *label)
{
    if (nrows == cap_rows) {
        cap_rows = cap_rows ? 2 * cap_rows : 64;
        rows = realloc(rows, sizeof(row) * cap_rows);
        if (!rows) {
            fprintf(stderr, "bench_accuracy: out of memory\n");
            exit(1);
        }
    }
    row *r = &rows[nrows++];
    memset(r, 0, sizeof *r);
    snprintf(r->axis, sizeof r->axis, "%s", axis);
    snprintf(r->label, sizeof r->label, "%s", label);
    r->extra = NAN;
    return r;
}

/* The cost a table's Pareto front weighs against error: time per client
 * frame (tick + frame) on every axis but the codec's, whose cost is the
 * bytes it sends (KiB per frame); its times are in the table beside. */
static double row_time(const row *r)
{
    if (!strcmp(r->axis, "codec"))
        return r->bytes / 1024.0;
    return r->tick_ms + r->frame_ms;
}

/* Pareto fronts within one axis: minimise (tick + frame time, error). */
static void mark_fronts(const char *axis)
{
    for (int a = 0; a < nrows; a++) {
        if (strcmp(rows[a].axis, axis))
            continue;
        int dom_h = 0, dom_n = 0;
        for (int b = 0; b < nrows; b++) {
            if (b == a || strcmp(rows[b].axis, axis))
                continue;
            double ta = row_time(&rows[a]), tb = row_time(&rows[b]);
            double ha = rows[a].m.h_rms_pct, hb = rows[b].m.h_rms_pct;
            double na = rows[a].m.n_rms_deg, nb = rows[b].m.n_rms_deg;
            if (tb <= ta && hb <= ha && (tb < ta || hb < ha))
                dom_h = 1;
            if (tb <= ta && nb <= na && (tb < ta || nb < na))
                dom_n = 1;
        }
        rows[a].front_h = !dom_h;
        rows[a].front_n = !dom_n;
    }
}

static int cmp_row_time(const void *a, const void *b)
{
    double x = row_time(*(row *const *)a), y = row_time(*(row *const *)b);
    return (x > y) - (x < y);
}

/* gnuplot data for one axis: index 0 all, 1 height front, 2 normal front,
 * 3 default.  Columns: cost (row_time) tick frame h_rms n_rms ssim "label". */
static void write_dat(const char *axis)
{
    char path[256];
    snprintf(path, sizeof path, OUT_DIR "/acc_%s.dat", axis);
    FILE *f = fopen(path, "w");
    if (!f)
        return;
    row *sel[512];
    int n = 0;
    for (int i = 0; i < nrows && n < 512; i++)
        if (!strcmp(rows[i].axis, axis))
            sel[n++] = &rows[i];
    qsort(sel, (size_t)n, sizeof sel[0], cmp_row_time);
    for (int blk = 0; blk < 4; blk++) {
        fprintf(f, "# %s\n", blk == 0 ? "all" : blk == 1 ? "front_height" : blk == 2 ? "front_normal" : "default");
        for (int i = 0; i < n; i++) {
            row *r = sel[i];
            if ((blk == 1 && !r->front_h) || (blk == 2 && !r->front_n) || (blk == 3 && !r->is_default))
                continue;
            fprintf(f, "%.6g %.6g %.6g %.6g %.6g %.6g \"%s\"\n", row_time(r), r->tick_ms, r->frame_ms,
                    fmax(r->m.h_rms_pct, 1e-9), fmax(r->m.n_rms_deg, 1e-9), r->m.ssim_n, r->label);
        }
        /* gnuplot needs a point in every index */
        fprintf(f, "\n\n");
    }
    fclose(f);
}

static void print_table(const char *axis, const char *title, const char *extra_name, const char *note)
{
    printf("#### %s\n\n", title);
    if (note)
        printf("%s\n\n", note);
    printf("| setting | tick ms | frame ms | KiB/frame |%s height RMS %%Hs | height max m | normal RMS deg | "
           "normal max deg | foam %% (ref) | E_error | PSNR h dB | PSNR n dB | SSIM n | slope var | front h/n |\n",
           extra_name ? extra_name : "");
    printf("|---|---:|---:|---:|%s---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|:---:|\n", extra_name ? "---:|" : "");
    for (int i = 0; i < nrows; i++) {
        row *r = &rows[i];
        if (strcmp(r->axis, axis))
            continue;
        char extra[32] = "";
        if (extra_name)
            snprintf(extra, sizeof extra, " %.4g |", r->extra);
        printf("| %s%s | %.3f | %.3f | %.1f |%s %.4g | %.4g | %.3g | %.3g | %.3g (%.3g) | %.3g | %.1f | %.1f | %.4f | %.3f | %s/%s |\n",
               r->label, r->is_default ? " **(default)**" : "", r->tick_ms, r->frame_ms, r->bytes / 1024.0, extra,
               r->m.h_rms_pct, r->m.h_max, r->m.n_rms_deg, r->m.n_max_deg, r->m.foam_set, r->m.foam_ref,
               r->m.e_error, r->m.psnr_h, r->m.psnr_n, r->m.ssim_n, r->m.slope_ratio,
               r->front_h ? "*" : "-", r->front_n ? "*" : "-");
    }
    printf("\n");
    fflush(stdout);
}

/* ---- settings: build, time, sample ------------------------------------------ */

static ocean_params base;        /* ocean_params_default + config/oceand.conf */
static metrics field_vs_ref, mesh_vs_ref;   /* the references of the codec and mesh axes */
static char base_note[1024];

typedef struct sim {
    ocean *o;
    ocean_frame *f;
    ocean_request req;
} sim;

static int sim_open(sim *s, const ocean_params *p, const ocean_request *r)
{
    char msg[256];
    memset(s, 0, sizeof *s);
    if (ocean_create(p, &s->o, msg, sizeof msg) != OCEAN_OK || ocean_frame_create(s->o, &s->f) != OCEAN_OK) {
        fprintf(stderr, "bench_accuracy: ocean_create: %s\n", msg);
        ocean_destroy(s->o);
        return -1;
    }
    s->req = *r;
    return 0;
}

static void sim_close(sim *s)
{
    ocean_frame_destroy(s->f);
    ocean_destroy(s->o);
}

/* Median ms of ocean_evaluate over reps ticks (1/30 s apart), then the
 * evaluation at T0 the errors are measured on. */
static double sim_tick(sim *s)
{
    double *v = xcalloc((size_t)reps_tick, sizeof *v);
    ocean_evaluate(s->o, T0, &s->req, s->f);
    for (int i = 0; i < reps_tick; i++) {
        double t0 = bench_now_ms();
        ocean_evaluate(s->o, T0 + (i + 1) / 30.0, &s->req, s->f);
        v[i] = bench_now_ms() - t0;
    }
    double m = bench_median(v, reps_tick);
    free(v);
    ocean_evaluate(s->o, T0, &s->req, s->f);
    return m;
}

static void sample_frame(const ocean_frame *f, sset *out)
{
    int s = W.s;
    for (int i = 0; i < s; i++)
        for (int j = 0; j < s; j++) {
            ocean_point pt;
            ocean_frame_sample(f, win_x(j), win_z(i), &pt);
            size_t q = (size_t)i * s + j;
            out->h[q] = pt.height;
            out->dx[q] = pt.dx;
            out->dz[q] = pt.dz;
            out->sx[q] = pt.slope_x;
            out->sz[q] = pt.slope_z;
            out->jac[q] = pt.jacobian;
        }
}

/* One cascade's fields as a protocol tile window (planes H DX DZ NU NV FOAM J;
 * channels the frame lacks read as 0, J as 1). */
static void cut_tile(const ocean_field *fd, int i0, int j0, int w, int h, float *planes)
{
    int n = fd->n;
    size_t m = (size_t)w * h;
    for (int i = 0; i < h; i++)
        for (int j = 0; j < w; j++) {
            size_t g = (size_t)((i0 + i) % n) * n + (size_t)((j0 + j) % n), k = (size_t)i * w + j;
            planes[k] = fd->height ? fd->height[g] : 0.0f;
            planes[m + k] = fd->dx ? fd->dx[g] : 0.0f;
            planes[2 * m + k] = fd->dz ? fd->dz[g] : 0.0f;
            float sx = fd->slope_x ? fd->slope_x[g] : 0.0f, sz = fd->slope_z ? fd->slope_z[g] : 0.0f;
            proto_normal_oct_encode(-sx, 1.0f, -sz, &planes[3 * m + k], &planes[4 * m + k]);
            planes[5 * m + k] = fd->foam ? fd->foam[g] : 0.0f;
            planes[6 * m + k] = fd->jacobian ? fd->jacobian[g] : 1.0f;
        }
}

/* The per-client frame: the client's mesh, its near field and its codec. */
typedef struct client {
    mesh *m;
    mesh_camera cam;
    const ocean_gerstner *g;   /* NULL: no near field */
    ocean_gerstner_view view;
    proto_codec codec;
    proto_codec_params cp;
    double *near_x, *near_z;   /* mesh vertices within the fade radius */
    size_t near_n;
    ocean_gerstner_point *near_out;
} client;

/* The sea's displacement at a mesh vertex: the summed cascades' dx,
 * height, dz read bilinearly, the lean path a server takes per vertex. */
static void sea_sampler(void *vctx, double x, double z, double out[3])
{
    const ocean_frame *f = vctx;
    out[0] = out[1] = out[2] = 0.0;
    for (int c = 0; c < OCEAN_MAX_CASCADES; c++) {
        const ocean_field *fd = ocean_frame_field(f, c);
        if (!fd)
            break;
        if (!fd->height)
            continue;
        int n = fd->n;
        double u = x / fd->patch_m, v = z / fd->patch_m;
        u = (u - floor(u)) * n;
        v = (v - floor(v)) * n;
        int j0 = (int)u, i0 = (int)v;
        if (j0 >= n) j0 = n - 1;
        if (i0 >= n) i0 = n - 1;
        double fx = u - j0, fz = v - i0;
        size_t a = (size_t)i0 * n + j0, b = (size_t)i0 * n + ((j0 + 1) & (n - 1));
        size_t cc = (size_t)((i0 + 1) & (n - 1)) * n + j0, d = (size_t)((i0 + 1) & (n - 1)) * n + ((j0 + 1) & (n - 1));
        double w00 = (1 - fx) * (1 - fz), w01 = fx * (1 - fz), w10 = (1 - fx) * fz, w11 = fx * fz;
        out[1] += w00 * fd->height[a] + w01 * fd->height[b] + w10 * fd->height[cc] + w11 * fd->height[d];
        if (fd->dx) {
            out[0] += w00 * fd->dx[a] + w01 * fd->dx[b] + w10 * fd->dx[cc] + w11 * fd->dx[d];
            out[2] += w00 * fd->dz[a] + w01 * fd->dz[b] + w10 * fd->dz[cc] + w11 * fd->dz[d];
        }
    }
}

/* The tiles one client receives, as the daemon's defaults lay them out:
 * CLIENT_LEVELS levels, level l at srv_base_spacing * 2^l, each
 * srv_tiles_per_side^2 tiles of TILE x TILE samples world-aligned around
 * the camera, every sample read from the summed cascades, all planes,
 * encoded with the client's codec.  Returns the bytes. */
#define CLIENT_LEVELS 4
static double client_tiles(const ocean_frame *f, const client *cl)
{
    int nt = srv_tiles_per_side;
    size_t m = (size_t)TILE * TILE;
    float *planes = xcalloc(7 * m, sizeof *planes);
    proto_buf b;
    proto_buf_init(&b, 0);
    char err[256];
    double total = 0.0;
    for (int l = 0; l < CLIENT_LEVELS; l++) {
        double dxs = srv_base_spacing * (double)(1 << l), side = dxs * TILE;
        double ox = floor(cl->cam.pos[0] / side - 0.5 * nt + 0.5) * side;
        double oz = floor(cl->cam.pos[2] / side - 0.5 * nt + 0.5) * side;
        for (int ti = 0; ti < nt; ti++)
            for (int tj = 0; tj < nt; tj++) {
                for (int i = 0; i < TILE; i++)
                    for (int j = 0; j < TILE; j++) {
                        ocean_point pt;
                        ocean_frame_sample(f, ox + tj * side + j * dxs, oz + ti * side + i * dxs, &pt);
                        size_t k = (size_t)i * TILE + j;
                        planes[k] = (float)pt.height;
                        planes[m + k] = (float)pt.dx;
                        planes[2 * m + k] = (float)pt.dz;
                        proto_normal_oct_encode((float)-pt.slope_x, 1.0f, (float)-pt.slope_z, &planes[3 * m + k],
                                                &planes[4 * m + k]);
                        planes[5 * m + k] = (float)pt.foam;
                        planes[6 * m + k] = (float)pt.jacobian;
                    }
                proto_buf_reset(&b);
                if (proto_tile_encode(cl->codec, &cl->cp, TILE, TILE, PROTO_CH_WORLD, planes, &b, NULL, err,
                                      sizeof err) == OCEAN_OK)
                    total += (double)proto_buf_len(&b);
                else
                    fprintf(stderr, "bench_accuracy: encode: %s\n", err);
            }
    }
    proto_buf_free(&b);
    free(planes);
    return total;
}

/* Median ms of one client frame: the client's tiles (client_tiles), plus
 * the near field (if any) summed at the client's mesh vertices within the
 * fade radius.  The mesh itself is costed on the mesh axis. */
static double client_frame(const ocean_frame *f, int cascades, client *cl, double *bytes)
{
    (void)cascades;
    double *v = xcalloc((size_t)reps_frame, sizeof *v);
    for (int i = 0; i < reps_frame; i++) {
        double t0 = bench_now_ms();
        *bytes = client_tiles(f, cl);
        if (cl->g && cl->near_n)
            ocean_gerstner_evaluate(cl->g, &cl->view, T0 + i / 30.0, cl->near_x, cl->near_z, cl->near_n,
                                    cl->near_out);
        v[i] = bench_now_ms() - t0;
    }
    double m = bench_median(v, reps_frame);
    free(v);
    return m;
}

static client default_client;

static int client_init(client *cl)
{
    memset(cl, 0, sizeof *cl);
    mesh_config mc;
    mesh_config_default(&mc);
    mesh_lambda_dominant(&base.sea, &mc.lambda_dominant_m);
    mc.error_px = srv_mesh_error_px;
    mc.range_m = srv_view_range;
    if (mesh_create(&mc, &cl->m) != OCEAN_OK)
        return -1;
    mesh_camera_default(&cl->cam);
    cl->cam.pos[0] = W.x0 + 0.5 * W.s * W.d;
    cl->cam.pos[2] = W.z0 + 0.5 * W.s * W.d;
    if (mesh_build(cl->m, &cl->cam) != OCEAN_OK)
        return -1;
    ocean_gerstner_view_default(&cl->view);
    cl->view.camera_x = cl->cam.pos[0];
    cl->view.camera_z = cl->cam.pos[2];
    cl->view.fade_r0 = FADE_R0;
    cl->view.fade_r1 = FADE_R1;
    cl->codec = PROTO_CODEC_DEFAULT;
    proto_codec_params_default(&cl->cp);
    mesh_view v;
    mesh_get_view(cl->m, &v);
    cl->near_x = xcalloc(v.vertex_count, sizeof(double));
    cl->near_z = xcalloc(v.vertex_count, sizeof(double));
    for (uint32_t i = 0; i < v.vertex_count; i++) {
        double x = v.origin[0] + v.base[3 * i], z = v.origin[2] + v.base[3 * i + 2];
        double ex = x - cl->view.camera_x, ez = z - cl->view.camera_z;
        if (ex * ex + ez * ez < FADE_R1 * FADE_R1) {
            cl->near_x[cl->near_n] = x;
            cl->near_z[cl->near_n] = z;
            cl->near_n++;
        }
    }
    cl->near_out = xcalloc(cl->near_n, sizeof(ocean_gerstner_point));
    return 0;
}

/* ---- axis: resolution x cascades -------------------------------------------- */

static void run_grid(void)
{
    const int ns_full[] = {64, 128, 256, 512, 1024}, ns_quick[] = {64, 256, 1024};
    const int ks_full[] = {1, 2, 3, 4}, ks_quick[] = {1, 2, 4};
    const int *ns = quick ? ns_quick : ns_full, *ks = quick ? ks_quick : ks_full;
    int nn = quick ? 3 : 5, nk = quick ? 3 : 4;
    sset set, ref;
    sset_init(&set);
    sset_init(&ref);
    for (int a = 0; a < nn; a++)
        for (int b = 0; b < nk; b++) {
            ocean_params p = base;
            p.n = ns[a];
            p.cascades = ks[b];
            ocean_request r;
            ocean_request_all(&r, OCEAN_FX_ALL);
            sim s;
            if (sim_open(&s, &p, &r))
                continue;
            char label[64];
            snprintf(label, sizeof label, "N=%d K=%d", p.n, p.cascades);
            row *rw = row_add("grid", label);
            rw->is_default = p.n == base.n && p.cascades == base.cascades;
            rw->tick_ms = sim_tick(&s);
            rw->frame_ms = client_frame(s.f, p.cascades, &default_client, &rw->bytes);
            sample_frame(s.f, &set);
            const sset *rf = &ref_set;
            int same_patch = p.cascades == 1;
            if (!same_patch) {
                reference_for(s.o, p.sea.choppiness, &ref);
                rf = &ref;
            }
            ocean_frame_info info;
            ocean_frame_get_info(s.f, &info);
            rw->m = compare(&set, rf, info.e_error);
            double patch, lo, hi;
            ocean_cascade_band(s.o, p.cascades - 1, &patch, &lo, &hi);
            rw->extra = 2.0 * patch / p.n;   /* shortest wavelength carried, m */
            sim_close(&s);
            fprintf(stderr, "  grid %s: tick %.2f ms, h %.3g %%, n %.3g deg\n", label, rw->tick_ms,
                    rw->m.h_rms_pct, rw->m.n_rms_deg);
        }
    /* The N = 2048 FFT itself against its own direct sum: what float and
     * bilinear reading leave. */
    if (!quick) {
        ocean_params p = base;
        p.n = N_REF;
        p.cascades = 1;
        ocean_request r;
        ocean_request_all(&r, OCEAN_FX_ALL);
        sim s;
        if (!sim_open(&s, &p, &r)) {
            row *rw = row_add("check", "N=2048 K=1 (FFT vs its own direct sum)");
            int keep = reps_tick;
            reps_tick = 3;
            rw->tick_ms = sim_tick(&s);
            reps_tick = keep;
            sample_frame(s.f, &set);
            rw->m = compare(&set, &ref_set, 0.0);
            rw->extra = 2.0 * p.patch_m / p.n;
            sim_close(&s);
        }
    }
    sset_free(&set);
    sset_free(&ref);
    mark_fronts("grid");
    write_dat("grid");
}

/* ---- axis: cutoff policy and level --------------------------------------- */

static void run_cutoff(void)
{
    ocean_filter_config fc;
    ocean_filter_config_default(&fc, &base.sea);
    ocean_filter_buckets bk;
    ocean_filter_buckets_default(&bk);
    double spacing = 0.0;
    mesh_info mi;
    mesh_get_info(default_client.m, &mi);
    spacing = mi.near_spacing_m;
    struct { ocean_filter_policy pol; double v; } cases_full[] = {
        {OCEAN_FILTER_NONE, 0}, {OCEAN_FILTER_SEED, 0}, {OCEAN_FILTER_SEED, 10}, {OCEAN_FILTER_SEED, 50},
        {OCEAN_FILTER_SEED, 300}, {OCEAN_FILTER_ANTIALIAS, 0}, {OCEAN_FILTER_ANTIALIAS, 50},
        {OCEAN_FILTER_ANTIALIAS, 150}, {OCEAN_FILTER_ANTIALIAS, 300}, {OCEAN_FILTER_ANTIALIAS, 1000},
    };
    int ncase = (int)(sizeof cases_full / sizeof cases_full[0]);
    sset set;
    sset_init(&set);
    for (int i = 0; i < ncase; i++) {
        if (quick && (i == 2 || i == 6 || i == 7))
            continue;
        ocean_filter_client cl = {cases_full[i].v, 60.0, spacing};
        ocean_filter_cutoff cut;
        if (ocean_filter_cutoff_compute(&fc, cases_full[i].pol, &cl, &cut) != OCEAN_OK)
            continue;
        double kc = cut.k;
        if (isfinite(kc)) {
            int bi;
            if (ocean_filter_bucket_of(&bk, kc, &bi) == OCEAN_OK)
                ocean_filter_bucket_cutoff(&bk, bi, &kc);
        }
        ocean_request r;
        ocean_request_all(&r, OCEAN_FX_ALL);
        r.cutoff_k = kc;
        r.order = cut.order;
        r.low_boost = cut.low_boost;
        sim s;
        if (sim_open(&s, &base, &r))
            continue;
        char label[64];
        snprintf(label, sizeof label, "%s %g m/s", ocean_filter_policy_name(cases_full[i].pol), cases_full[i].v);
        row *rw = row_add("cutoff", label);
        rw->is_default = cases_full[i].pol == OCEAN_FILTER_NONE;
        rw->tick_ms = sim_tick(&s);
        rw->frame_ms = client_frame(s.f, base.cascades, &default_client, &rw->bytes);
        sample_frame(s.f, &set);
        ocean_frame_info info;
        ocean_frame_get_info(s.f, &info);
        rw->m = compare(&set, &ref_set, info.e_error);
        rw->extra = kc;
        sim_close(&s);
    }
    sset_free(&set);
    mark_fronts("cutoff");
    write_dat("cutoff");
}

/* ---- axis: Gerstner near-field wave count ---------------------------------- */

static void run_gerstner(void)
{
    const int ms_full[] = {0, 16, 64, 256, 1024}, ms_quick[] = {0, 64, 1024};
    const int *ms = quick ? ms_quick : ms_full;
    int nm = quick ? 3 : 5;
    ocean_params p = base;
    /* The FFT keeps the disc inside its grid; the near field takes the
     * annulus from there up to the reference's shortest wave. */
    double dk = 2.0 * M_PI / p.patch_m;
    p.k_max = (p.n / 2 - 1) * dk;
    double k_hi = (N_REF / 2 - 1) * dk;
    sset set;
    sset_init(&set);
    for (int a = 0; a < nm; a++) {
        ocean_request r;
        ocean_request_all(&r, OCEAN_FX_ALL);
        sim s;
        if (sim_open(&s, &p, &r))
            continue;
        ocean_gerstner *g = NULL;
        if (ms[a] > 0) {
            ocean_gerstner_params gp;
            ocean_gerstner_params_default(&gp);
            gp.sea = p.sea;
            gp.seed = p.seed;
            gp.count = ms[a];
            gp.k_lo = p.k_max;
            gp.k_hi = k_hi;
            char msg[256];
            if (ocean_gerstner_create(&gp, &g, msg, sizeof msg) != OCEAN_OK) {
                fprintf(stderr, "bench_accuracy: gerstner: %s\n", msg);
                sim_close(&s);
                continue;
            }
        }
        char label[64];
        snprintf(label, sizeof label, "M=%d", ms[a]);
        row *rw = row_add("gerstner", label);
        rw->is_default = ms[a] == 0;   /* the base sea has no near field */
        rw->tick_ms = sim_tick(&s);
        client cl = default_client;
        cl.g = g;
        rw->frame_ms = client_frame(s.f, p.cascades, &cl, &rw->bytes);
        sample_frame(s.f, &set);
        if (g) {
            int n = W.s;
            size_t ss = (size_t)n * n;
            double *xs = xcalloc(ss, sizeof *xs), *zs = xcalloc(ss, sizeof *zs);
            ocean_gerstner_point *gp = xcalloc(ss, sizeof *gp);
            for (int i = 0; i < n; i++)
                for (int j = 0; j < n; j++) {
                    xs[(size_t)i * n + j] = win_x(j);
                    zs[(size_t)i * n + j] = win_z(i);
                }
            ocean_gerstner_view v;
            ocean_gerstner_view_default(&v);
            if (ocean_gerstner_evaluate(g, &v, T0, xs, zs, ss, gp) == OCEAN_OK)
                for (size_t q = 0; q < ss; q++) {
                    set.h[q] += gp[q].dy;
                    set.dx[q] += gp[q].dx;
                    set.dz[q] += gp[q].dz;
                    set.sx[q] += -gp[q].nx / gp[q].ny;
                    set.sz[q] += -gp[q].nz / gp[q].ny;
                }
            free(xs);
            free(zs);
            free(gp);
        }
        ocean_frame_info info;
        ocean_frame_get_info(s.f, &info);
        rw->m = compare(&set, &ref_set, info.e_error);
        rw->extra = ms[a];
        ocean_gerstner_destroy(g);
        sim_close(&s);
    }
    sset_free(&set);
    mark_fronts("gerstner");
    write_dat("gerstner");
}

/* ---- axes: storage precision and tile codec --------------------------------- */

/* Single-cascade grids sampled bilinearly at the window points, as
 * ocean_frame_sample reads a field. */
typedef struct grids {
    int n;
    double patch;
    float *h, *dx, *dz, *sx, *sz, *jac;
} grids;

static double bil(const float *g, int n, double u, double v)
{
    u = (u - floor(u)) * n;
    v = (v - floor(v)) * n;
    int j0 = (int)u, i0 = (int)v;
    if (j0 >= n) j0 = n - 1;
    if (i0 >= n) i0 = n - 1;
    double fx = u - j0, fz = v - i0;
    int i1 = (i0 + 1) & (n - 1), j1 = (j0 + 1) & (n - 1);
    double a = g[(size_t)i0 * n + j0], b = g[(size_t)i0 * n + j1], c = g[(size_t)i1 * n + j0], d = g[(size_t)i1 * n + j1];
    return (a * (1 - fx) + b * fx) * (1 - fz) + (c * (1 - fx) + d * fx) * fz;
}

static void sample_grids(const grids *g, sset *out)
{
    int s = W.s;
    for (int i = 0; i < s; i++)
        for (int j = 0; j < s; j++) {
            double u = win_x(j) / g->patch, v = win_z(i) / g->patch;
            size_t q = (size_t)i * s + j;
            out->h[q] = bil(g->h, g->n, u, v);
            out->dx[q] = bil(g->dx, g->n, u, v);
            out->dz[q] = bil(g->dz, g->n, u, v);
            out->sx[q] = bil(g->sx, g->n, u, v);
            out->sz[q] = bil(g->sz, g->n, u, v);
            out->jac[q] = bil(g->jac, g->n, u, v);
        }
}

static void grids_alloc(grids *g, int n, double patch)
{
    g->n = n;
    g->patch = patch;
    size_t nn = (size_t)n * n;
    float *b = xcalloc(6 * nn, sizeof *b);
    g->h = b; g->dx = b + nn; g->dz = b + 2 * nn; g->sx = b + 3 * nn; g->sz = b + 4 * nn; g->jac = b + 5 * nn;
}

static void grids_from_field(grids *g, const ocean_field *fd)
{
    size_t nn = (size_t)fd->n * fd->n;
    memcpy(g->h, fd->height, nn * sizeof(float));
    memcpy(g->dx, fd->dx, nn * sizeof(float));
    memcpy(g->dz, fd->dz, nn * sizeof(float));
    memcpy(g->sx, fd->slope_x, nn * sizeof(float));
    memcpy(g->sz, fd->slope_z, nn * sizeof(float));
    memcpy(g->jac, fd->jacobian, nn * sizeof(float));
}

static void run_precision_codec(void)
{
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_ALL);
    ocean_params p = base;
    p.cascades = 1;   /* tiles of one cascade: the codec's own error */
    sim s;
    if (sim_open(&s, &p, &r))
        return;
    double tick = sim_tick(&s);
    const ocean_field *fd = ocean_frame_field(s.f, 0);
    int n = fd->n;
    grids g;
    grids_alloc(&g, n, fd->patch_m);
    sset set;
    sset_init(&set);
    ocean_frame_info info;
    ocean_frame_get_info(s.f, &info);
    /* The uncompressed f32 field is the reference of these two axes: the
     * error a precision or a codec adds.  Its own error against the N = 2048
     * sea is kept for the notes. */
    sset own;
    sset_init(&own);
    grids_from_field(&g, fd);
    sample_grids(&g, &own);
    field_vs_ref = compare(&own, &ref_set, 0.0);

    /* storage precision: the evaluated fields kept as f32 or f16 */
    for (int prec = 0; prec < 2; prec++) {
        row *rw = row_add("precision", prec ? "f16 storage" : "f32 storage");
        rw->is_default = prec == 0;
        double conv = 0.0;
        grids_from_field(&g, fd);
        if (prec) {
            size_t nn = (size_t)n * n;
            float *all[6] = {g.h, g.dx, g.dz, g.sx, g.sz, g.jac};
            uint16_t *tmp = xcalloc(6 * nn, sizeof *tmp);
            double *v = xcalloc((size_t)reps_frame, sizeof *v);
            for (int k = 0; k < reps_frame; k++) {
                double t0 = bench_now_ms();
                for (int c = 0; c < 6; c++)
                    for (size_t q = 0; q < nn; q++)
                        tmp[c * nn + q] = proto_f16_from_f32(all[c][q]);
                v[k] = bench_now_ms() - t0;
            }
            conv = bench_median(v, reps_frame);
            for (int c = 0; c < 6; c++)
                for (size_t q = 0; q < nn; q++)
                    all[c][q] = proto_f32_from_f16(tmp[c * nn + q]);
            free(tmp);
            free(v);
        }
        rw->tick_ms = tick + conv;
        rw->frame_ms = client_frame(s.f, 1, &default_client, &rw->bytes);
        rw->extra = (double)n * n * 6 * (prec ? 2 : 4) / 1024.0;   /* held per tick */
        sample_grids(&g, &set);
        rw->m = compare(&set, &own, info.e_error);
    }
    mark_fronts("precision");

    /* tile codecs and the quantisation step */
    struct { proto_codec c; double acc; } cs[] = {
        {PROTO_CODEC_F32, 0}, {PROTO_CODEC_F16, 0}, {PROTO_CODEC_QZ, 3e-2}, {PROTO_CODEC_QZ, 1e-2},
        {PROTO_CODEC_QZ, 3e-3}, {PROTO_CODEC_QZ, 1e-3}, {PROTO_CODEC_QZ, 1e-4}, {PROTO_CODEC_QZ, 1e-5},
        {PROTO_CODEC_EXR_ZIP, 0}, {PROTO_CODEC_EXR_PIZ, 0}, {PROTO_CODEC_EXR_B44, 0}, {PROTO_CODEC_EXR_B44A, 0},
        {PROTO_CODEC_QZ, PROTO_ACCURACY_DEFAULT},   /* the shipped default, always measured */
    };
    int ncs = (int)(sizeof cs / sizeof cs[0]);
    for (int ci = 0; ci < ncs - 1; ci++)
        if (cs[ci].c == PROTO_CODEC_QZ && cs[ci].acc == PROTO_ACCURACY_DEFAULT)
            ncs--;   /* already in the list */
    int t = n < TILE ? n : TILE, planes_n = proto_tile_planes(PROTO_CH_WORLD);
    size_t tm = (size_t)t * t;
    float *planes = xcalloc(planes_n * tm, sizeof *planes), *back = xcalloc(planes_n * tm, sizeof *back);
    proto_buf b;
    proto_buf_init(&b, 0);
    char err[256];
    for (int ci = 0; ci < ncs; ci++) {
        if (quick && (ci == 2 || ci == 4 || ci == 7 || ci == 9))
            continue;
        client cl = default_client;
        cl.codec = cs[ci].c;
        proto_codec_params_default(&cl.cp);
        if (cs[ci].acc > 0)
            cl.cp.accuracy = cs[ci].acc;
        char label[64];
        if (cs[ci].acc > 0)
            snprintf(label, sizeof label, "%s %g", proto_codec_name(cs[ci].c), cs[ci].acc);
        else
            snprintf(label, sizeof label, "%s", proto_codec_name(cs[ci].c));
        row *rw = row_add("codec", label);
        rw->is_default = cs[ci].c == PROTO_CODEC_DEFAULT && cs[ci].acc == PROTO_ACCURACY_DEFAULT;
        rw->tick_ms = tick;
        /* encode + decode every tile once, reassembling the decoded grids */
        double *ve = xcalloc((size_t)reps_frame, sizeof *ve), *vd = xcalloc((size_t)reps_frame, sizeof *vd);
        int fail = 0;
        for (int k = 0; k < reps_frame && !fail; k++) {
            double enc = 0.0, dec = 0.0, bytes = 0.0;
            for (int i0 = 0; i0 < n && !fail; i0 += t)
                for (int j0 = 0; j0 < n && !fail; j0 += t) {
                    cut_tile(fd, i0, j0, t, t, planes);
                    proto_buf_reset(&b);
                    double t0 = bench_now_ms();
                    if (proto_tile_encode(cl.codec, &cl.cp, t, t, PROTO_CH_WORLD, planes, &b, NULL, err, sizeof err)
                        != OCEAN_OK) {
                        fprintf(stderr, "bench_accuracy: %s: encode: %s\n", label, err);
                        fail = 1;
                        break;
                    }
                    double t1 = bench_now_ms();
                    if (proto_tile_decode(cl.codec, t, t, PROTO_CH_WORLD, proto_buf_data(&b), proto_buf_len(&b), back,
                                          err, sizeof err) != OCEAN_OK) {
                        fprintf(stderr, "bench_accuracy: %s: decode: %s\n", label, err);
                        fail = 1;
                        break;
                    }
                    dec += bench_now_ms() - t1;
                    enc += t1 - t0;
                    bytes += (double)proto_buf_len(&b);
                    if (k == 0)
                        for (int i = 0; i < t; i++)
                            for (int j = 0; j < t; j++) {
                                size_t gq = (size_t)(i0 + i) * n + (size_t)(j0 + j), q = (size_t)i * t + j;
                                float nx, ny, nz;
                                g.h[gq] = back[q];
                                g.dx[gq] = back[tm + q];
                                g.dz[gq] = back[2 * tm + q];
                                proto_normal_oct_decode(back[3 * tm + q], back[4 * tm + q], &nx, &ny, &nz);
                                g.sx[gq] = ny > 1e-6f ? -nx / ny : 0.0f;
                                g.sz[gq] = ny > 1e-6f ? -nz / ny : 0.0f;
                                g.jac[gq] = back[6 * tm + q];
                            }
                }
            ve[k] = enc;
            vd[k] = dec;
            rw->bytes = bytes;
        }
        if (fail) {
            nrows--;
            free(ve);
            free(vd);
            continue;
        }
        rw->frame_ms = bench_median(ve, reps_frame);
        rw->extra = bench_median(vd, reps_frame);   /* client's decode ms */
        free(ve);
        free(vd);
        sample_grids(&g, &set);
        rw->m = compare(&set, &own, info.e_error);
    }
    proto_buf_free(&b);
    free(planes);
    free(back);
    free(g.h);
    sset_free(&set);
    sset_free(&own);
    sim_close(&s);
    mark_fronts("codec");
    write_dat("precision");
    write_dat("codec");
}

/* ---- axis: mesh kind and density -------------------------------------------- */

/* Heights and slopes of the displaced mesh at the window points: each base
 * triangle covering a point interpolates its vertices' displaced heights
 * over the undisplaced (parameter) plane; its slope is that plane's
 * gradient.  Points no triangle covers are marked invalid. */
static void sample_mesh(const mesh *m, sset *out)
{
    mesh_view v;
    mesh_get_view(m, &v);
    int s = W.s;
    memset(out->valid, 0, (size_t)s * s);
    for (uint32_t t = 0; t + 2 < v.index_count; t += 3) {
        double px[3], pz[3], py[3], dxv[3], dzv[3];
        for (int c = 0; c < 3; c++) {
            uint32_t id = v.indices[t + c];
            px[c] = v.origin[0] + v.base[3 * id];
            pz[c] = v.origin[2] + v.base[3 * id + 2];
            py[c] = v.positions[3 * id + 1];
            dxv[c] = v.positions[3 * id] - v.base[3 * id];
            dzv[c] = v.positions[3 * id + 2] - v.base[3 * id + 2];
        }
        double xmin = fmin(px[0], fmin(px[1], px[2])), xmax = fmax(px[0], fmax(px[1], px[2]));
        double zmin = fmin(pz[0], fmin(pz[1], pz[2])), zmax = fmax(pz[0], fmax(pz[1], pz[2]));
        int j0 = (int)ceil((xmin - W.x0) / W.d), j1 = (int)floor((xmax - W.x0) / W.d);
        int i0 = (int)ceil((zmin - W.z0) / W.d), i1 = (int)floor((zmax - W.z0) / W.d);
        if (j1 < 0 || i1 < 0 || j0 >= s || i0 >= s)
            continue;
        if (j0 < 0) j0 = 0;
        if (i0 < 0) i0 = 0;
        if (j1 >= s) j1 = s - 1;
        if (i1 >= s) i1 = s - 1;
        double det = (px[1] - px[0]) * (pz[2] - pz[0]) - (px[2] - px[0]) * (pz[1] - pz[0]);
        if (fabs(det) < 1e-12)
            continue;
        /* plane gradient of the height over (x, z) */
        double gx = ((py[1] - py[0]) * (pz[2] - pz[0]) - (py[2] - py[0]) * (pz[1] - pz[0])) / det;
        double gz = ((px[1] - px[0]) * (py[2] - py[0]) - (px[2] - px[0]) * (py[1] - py[0])) / det;
        for (int i = i0; i <= i1; i++)
            for (int j = j0; j <= j1; j++) {
                double x = win_x(j), z = win_z(i);
                double l1 = ((x - px[0]) * (pz[2] - pz[0]) - (px[2] - px[0]) * (z - pz[0])) / det;
                double l2 = ((px[1] - px[0]) * (z - pz[0]) - (x - px[0]) * (pz[1] - pz[0])) / det;
                double l0 = 1.0 - l1 - l2;
                const double e = -1e-9;
                if (l0 < e || l1 < e || l2 < e)
                    continue;
                size_t q = (size_t)i * s + j;
                out->valid[q] = 1;
                out->h[q] = l0 * py[0] + l1 * py[1] + l2 * py[2];
                out->dx[q] = l0 * dxv[0] + l1 * dxv[1] + l2 * dxv[2];
                out->dz[q] = l0 * dzv[0] + l1 * dzv[1] + l2 * dzv[2];
                out->sx[q] = gx;
                out->sz[q] = gz;
                out->jac[q] = 1.0;
            }
    }
}

static void run_mesh(void)
{
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_ALL);
    sim s;
    if (sim_open(&s, &base, &r))
        return;
    double tick = sim_tick(&s);
    ocean_frame_info info;
    ocean_frame_get_info(s.f, &info);
    double lambda_dom = 0.0;
    mesh_lambda_dominant(&base.sea, &lambda_dom);
    /* A camera 40 m up, 80 m behind the window, looking at it. */
    mesh_camera cam;
    mesh_camera_default(&cam);
    cam.pos[0] = W.x0 - 80.0;
    cam.pos[1] = 40.0;
    cam.pos[2] = W.z0 + 0.5 * W.s * W.d;
    cam.yaw_deg = 0.0;
    cam.pitch_deg = -25.0;
    struct { mesh_kind k; double v; } cases[] = {
        {MESH_CONCENTRIC, 16}, {MESH_CONCENTRIC, 8}, {MESH_CONCENTRIC, 4}, {MESH_CONCENTRIC, 2}, {MESH_CONCENTRIC, 1},
        {MESH_CHUNKED, 8}, {MESH_CHUNKED, 16}, {MESH_CHUNKED, 32}, {MESH_CHUNKED, 64}, {MESH_CHUNKED, 128},
        {MESH_PROJECTED, 128}, {MESH_PROJECTED, 256}, {MESH_PROJECTED, 512}, {MESH_PROJECTED, 1024},
    };
    int nc = (int)(sizeof cases / sizeof cases[0]);
    sset set, own;
    sset_init(&set);
    sset_init(&own);
    sample_frame(s.f, &own);   /* the mesh's reference: the sea it displaces by */
    mesh_vs_ref = compare(&own, &ref_set, 0.0);
    void *sc = s.f;
    for (int i = 0; i < nc; i++) {
        if (quick && (i == 0 || i == 4 || i == 5 || i == 9 || i == 13))
            continue;
        mesh_config mc;
        mesh_config_default(&mc);
        mc.kind = cases[i].k;
        mc.lambda_dominant_m = lambda_dom;
        mc.range_m = srv_view_range;
        mc.error_px = srv_mesh_error_px;
        char label[64];
        if (mc.kind == MESH_CONCENTRIC) {
            mc.error_px = cases[i].v;
            snprintf(label, sizeof label, "concentric %gpx", cases[i].v);
        } else if (mc.kind == MESH_CHUNKED) {
            mc.chunk_quads = (int)cases[i].v;
            snprintf(label, sizeof label, "chunked %dq", (int)cases[i].v);
        } else {
            mc.grid_w = mc.grid_h = (int)cases[i].v;
            snprintf(label, sizeof label, "projected %d^2", (int)cases[i].v);
        }
        mesh *m = NULL;
        if (mesh_create(&mc, &m) != OCEAN_OK || mesh_build(m, &cam) != OCEAN_OK) {
            fprintf(stderr, "bench_accuracy: mesh %s failed\n", label);
            mesh_destroy(m);
            continue;
        }
        row *rw = row_add("mesh", label);
        mesh_config dflt;
        mesh_config_default(&dflt);
        rw->is_default = mc.kind == dflt.kind && mc.error_px == srv_mesh_error_px;
        rw->tick_ms = tick;
        /* per frame: the camera moves on (0.5 m per frame) and the mesh is
         * rebuilt or updated, then displaced */
        double *v = xcalloc((size_t)reps_frame, sizeof *v);
        mesh_camera c2 = cam;
        for (int k = 0; k < reps_frame; k++) {
            c2.pos[0] += 0.5;
            double t0 = bench_now_ms();
            mesh_build(m, &c2);
            mesh_displace(m, sea_sampler, sc);
            v[k] = bench_now_ms() - t0;
        }
        rw->frame_ms = bench_median(v, reps_frame);
        free(v);
        mesh_build(m, &cam);
        mesh_displace(m, sea_sampler, sc);
        double px = NAN;
        mesh_error_px(m, &cam, sea_sampler, sc, &px);
        mesh_view mv;
        mesh_get_view(m, &mv);
        rw->bytes = (double)mv.vertex_count * 12.0;   /* positions per frame */
        rw->extra = px;
        sample_mesh(m, &set);
        rw->m = compare(&set, &own, info.e_error);
        mesh_destroy(m);
    }
    sset_free(&set);
    sset_free(&own);
    sim_close(&s);
    mark_fronts("mesh");
    write_dat("mesh");
}

/* ---- effects sets and scenes ------------------------------------------------ */

static const char *fx_name(unsigned fx, char *buf, size_t len)
{
    buf[0] = 0;
    const char *names[] = {"height", "displacement", "normals", "foam", "near-field"};
    for (int i = 0; i < 5; i++)
        if (fx & (1u << i)) {
            size_t l = strlen(buf);
            snprintf(buf + l, len - l, "%s%s", l ? "," : "", names[i]);
        }
    return buf;
}

/* Median near-field ms per client frame: the Gerstner set summed at the
 * client's mesh vertices within the fade radius. */
static double near_field_ms(const ocean_params *p, const client *cl0)
{
    ocean_gerstner_params gp;
    ocean_gerstner_params_default(&gp);
    gp.sea = p->sea;
    gp.seed = p->seed;
    gp.count = srv_near_waves;
    /* above the finest cascade's square band, down to the daemon's
     * shortest near-field wavelength */
    double dk = 2.0 * M_PI / (p->patch_m / pow(p->cascade_ratio, p->cascades - 1));
    gp.k_lo = isfinite(p->k_max) ? p->k_max : M_SQRT2 * (p->n / 2) * dk;
    gp.k_hi = 2.0 * M_PI / srv_near_min_wl;
    if (gp.k_hi <= gp.k_lo * 1.5)
        gp.k_hi = gp.k_lo * 8.0;
    ocean_gerstner *g = NULL;
    char msg[256];
    if (ocean_gerstner_create(&gp, &g, msg, sizeof msg) != OCEAN_OK) {
        fprintf(stderr, "bench_accuracy: near field: %s\n", msg);
        return NAN;
    }
    /* the default client's vertices within the fade radius of its camera
     * (the sea differs per scene; the mesh and the radius do not) */
    size_t cnt = cl0->near_n;
    const double *xs = cl0->near_x, *zs = cl0->near_z;
    ocean_gerstner_point *out = xcalloc(cnt, sizeof *out);
    double *t = xcalloc((size_t)reps_frame, sizeof *t);
    for (int k = 0; k < reps_frame; k++) {
        double t0 = bench_now_ms();
        ocean_gerstner_evaluate(g, &cl0->view, T0 + k / 30.0, xs, zs, cnt, out);
        t[k] = bench_now_ms() - t0;
    }
    double m = bench_median(t, reps_frame);
    free(t);
    free(out);
    ocean_gerstner_destroy(g);
    return m;
}

static double tick_for(const ocean_params *p, unsigned fx, int *transforms)
{
    ocean_request r;
    ocean_request_all(&r, fx & OCEAN_FX_ALL);
    sim s;
    if (sim_open(&s, p, &r))
        return NAN;
    double ms = sim_tick(&s);
    ocean_frame_info info;
    ocean_frame_get_info(s.f, &info);
    if (transforms)
        *transforms = info.transforms;
    sim_close(&s);
    return ms;
}

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static void run_scenes(void)
{
    FILE *csv = fopen(OUT_DIR "/scenes.csv", "w");
    if (csv)
        fprintf(csv, "kind,name,effects,n,cascades,transforms,tick_ms,tick_all_ms,ratio_vs_all,near_field_ms\n");
    printf("### Simulate only what a scene calls for\n\n");
    printf("Median ms per tick (ocean_evaluate, %d threads) for each effects set on the shipped default sea, "
           "and for each scene in `config/scenes/` with the effects it names beside all four FFT effects on "
           "the same sea (ratio measured in the same run). The near field is per client: the Gerstner set "
           "(%d waves) summed at the client's mesh vertices within %g m of the camera, ms per client frame (%zu vertices of the default client's mesh).\n\n",
           base.threads, srv_near_waves, FADE_R1, default_client.near_n);
    printf("| effects (default sea) | transforms | tick ms | vs all | near field ms/frame |\n|---|---:|---:|---:|---:|\n");
    unsigned sets[] = {OCEAN_FX_HEIGHT, OCEAN_FX_HEIGHT | OCEAN_FX_DISPLACEMENT,
                       OCEAN_FX_HEIGHT | OCEAN_FX_DISPLACEMENT | OCEAN_FX_NORMALS, OCEAN_FX_ALL,
                       OCEAN_FX_ALL | OCEAN_FX_NEAR_FIELD};
    double all_ms = tick_for(&base, OCEAN_FX_ALL, NULL);
    char buf[128];
    for (int i = 0; i < 5; i++) {
        int tr = 0;
        double ms = tick_for(&base, sets[i], &tr);
        double nf = (sets[i] & OCEAN_FX_NEAR_FIELD) ? near_field_ms(&base, &default_client) : 0.0;
        char nf_s[32] = "-";
        if (sets[i] & OCEAN_FX_NEAR_FIELD)
            snprintf(nf_s, sizeof nf_s, "%.3f", nf);
        printf("| %s | %d | %.3f | %.2f | %s |\n", fx_name(sets[i], buf, sizeof buf), tr, ms, ms / all_ms, nf_s);
        if (csv)
            fprintf(csv, "effects,default,\"%s\",%d,%d,%d,%.4f,%.4f,%.4f,%.4f\n", fx_name(sets[i], buf, sizeof buf),
                    base.n, base.cascades, tr, ms, all_ms, ms / all_ms, nf);
    }
    printf("\n| scene | effects | N x cascades | transforms | tick ms | all effects ms | ratio | near field ms/frame |\n");
    printf("|---|---|---|---:|---:|---:|---:|---:|\n");
    DIR *d = opendir(SCENE_DIR);
    char *names[64];
    int nn = 0;
    if (d) {
        struct dirent *e;
        while ((e = readdir(d)) && nn < 64) {
            size_t l = strlen(e->d_name);
            if (l > 5 && !strcmp(e->d_name + l - 5, ".conf"))
                names[nn++] = strdup(e->d_name);
        }
        closedir(d);
    }
    qsort(names, (size_t)nn, sizeof names[0], cmp_str);
    for (int i = 0; i < nn; i++) {
        char path[512], err[512];
        snprintf(path, sizeof path, SCENE_DIR "/%s", names[i]);
        ocean_scene sc;
        if (ocean_conf_scene_load(path, &base, &sc, err, sizeof err) != OCEAN_OK) {
            printf("| %s | (failed to load: %s) | | | | | | |\n", names[i], err);
            free(names[i]);
            continue;
        }
        int tr = 0, tra = 0;
        double ms = tick_for(&sc.params, sc.effects, &tr);
        double ma = tick_for(&sc.params, OCEAN_FX_ALL, &tra);
        double nf = 0.0;
        if (sc.effects & OCEAN_FX_NEAR_FIELD) {
            nf = near_field_ms(&sc.params, &default_client);
        }
        char nf_s[32] = "-";
        if (nf > 0)
            snprintf(nf_s, sizeof nf_s, "%.3f", nf);
        printf("| %s | %s | %d x %d | %d | %.3f | %.3f | %.2f | %s |\n", sc.name, fx_name(sc.effects, buf, sizeof buf),
               sc.params.n, sc.params.cascades, tr, ms, ma, ms / ma, nf_s);
        if (csv)
            fprintf(csv, "scene,%s,\"%s\",%d,%d,%d,%.4f,%.4f,%.4f,%.4f\n", sc.name, fx_name(sc.effects, buf, sizeof buf),
                    sc.params.n, sc.params.cascades, tr, ms, ma, ms / ma, nf);
        free(names[i]);
    }
    if (nn == 0)
        printf("| (no scenes found in %s) | | | | | | | |\n", SCENE_DIR);
    printf("\n");
    if (csv)
        fclose(csv);
    fflush(stdout);
}

/* ---- self-check of the reference ----------------------------------------- */

/* The separable sum against ocean_reference_point (which sums every wave
 * one by one) at a few window points: on a small multi-cascade ocean, and
 * (full run) on the N = 2048 reference itself. */
static double self_check(double *err_ref)
{
    ocean_params p = base;
    p.n = 64;
    p.cascades = 2;
    ocean *o = NULL;
    char msg[256];
    *err_ref = NAN;
    if (ocean_create(&p, &o, msg, sizeof msg) != OCEAN_OK)
        return NAN;
    size_t ss = (size_t)W.s * W.s;
    double *ch = xcalloc(NCH * ss, sizeof *ch);
    for (int c = 0; c < p.cascades; c++) {
        lattice L;
        lattice_from_ocean(&L, o, c, T0);
        dft_add(&L, p.sea.choppiness, ch);
        free(L.h);
    }
    double worst = 0.0;
    int pts[3][2] = {{0, 0}, {W.s / 2, W.s / 3}, {W.s - 1, W.s - 1}};
    for (int k = 0; k < 3; k++) {
        int i = pts[k][0], j = pts[k][1];
        ocean_point pt;
        ocean_reference_point(o, T0, win_x(j), win_z(i), INFINITY, 6, &pt);
        size_t q = (size_t)i * W.s + j;
        worst = fmax(worst, fabs(pt.height - ch[C_H * ss + q]));
        worst = fmax(worst, fabs(pt.slope_x - ch[C_SX * ss + q]));
        worst = fmax(worst, fabs(pt.dx - ch[C_DX * ss + q]));
        worst = fmax(worst, fabs(pt.dxz - ch[C_DXZ * ss + q]));
    }
    free(ch);
    ocean_destroy(o);
    if (!quick) {
        ocean_point pt;
        int i = W.s / 2, j = W.s / 3;
        ocean_reference_point(ref_ocean, T0, win_x(j), win_z(i), INFINITY, 6, &pt);
        size_t q = (size_t)i * W.s + j;
        *err_ref = fmax(fabs(pt.height - ref_set.h[q]), fabs(pt.slope_x - ref_set.sx[q]));
    }
    return worst;
}

/* ---- headline ------------------------------------------------------------------ */

static const row *find_row(const char *axis, const char *label)
{
    for (int i = 0; i < nrows; i++)
        if (!strcmp(rows[i].axis, axis) && !strcmp(rows[i].label, label))
            return &rows[i];
    return NULL;
}

static void write_headline(void)
{
    FILE *f = fopen(OUT_DIR "/headline.md", "w");
    if (!f)
        return;
    fprintf(f, "Per-client layout-0 sweep on the base sea (%s without its scene; not what the browser viewer "
               "receives, see above):\n\n", CONF_PATH);
    fprintf(f, "| axis | setting | tick ms | client frame ms | height RMS %%Hs | normal RMS deg | SSIM normals | "
               "on front h/n |\n");
    fprintf(f, "|---|---|---:|---:|---:|---:|---:|:---:|\n");
    const char *picks[][2] = {
        {"grid", "N=64 K=1"}, {"grid", "N=256 K=1"}, {"grid", "N=1024 K=1"}, {"grid", "N=64 K=2"},
        {"grid", "N=256 K=2"}, {"grid", "N=64 K=4"}, {"grid", "N=256 K=4"}, {"grid", "N=1024 K=2"},
        {"cutoff", "antialias 300 m/s"}, {"cutoff", "antialias 1000 m/s"}, {"gerstner", "M=64"},
    };
    for (size_t i = 0; i < sizeof picks / sizeof picks[0]; i++) {
        const row *r = find_row(picks[i][0], picks[i][1]);
        if (!r)
            continue;
        const char *what = !strcmp(r->axis, "grid") ? "resolution x cascades" : r->axis;
        fprintf(f, "| %s | %s%s | %.2f | %.2f | %.3g | %.2f | %.3f | %s/%s |\n", what, r->label,
                r->is_default ? " **(default)**" : "", r->tick_ms, r->frame_ms, r->m.h_rms_pct, r->m.n_rms_deg,
                r->m.ssim_n, r->front_h ? "yes" : "no", r->front_n ? "yes" : "no");
    }
    fprintf(f, "\nErrors against the same sea at N = %d summed directly in double (height RMS as %% of Hs = "
               "%.2f m). Tick: ocean_evaluate with height, displacement, normals and foam; client frame: that "
               "client's tiles, qz-encoded.\n", N_REF, ref_hs);
    fclose(f);
}

/* The few server.* keys this benchmark mirrors, if the shipped config sets
 * them: "server.KEY = VALUE" lines, comments stripped. */
static void read_server_keys(const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return;
    char line[512];
    while (fgets(line, sizeof line, f)) {
        char *h = strchr(line, '#');
        if (h)
            *h = 0;
        char key[128];
        double v;
        if (sscanf(line, " server.%127[a-z_] = %lf", key, &v) != 2 || !isfinite(v))
            continue;
        if (!strcmp(key, "mesh_error_px")) srv_mesh_error_px = v;
        else if (!strcmp(key, "view_range")) srv_view_range = v;
        else if (!strcmp(key, "near_field_waves")) srv_near_waves = (int)v;
        else if (!strcmp(key, "near_field_radius")) srv_near_radius = v;
        else if (!strcmp(key, "near_field_min_wavelength")) srv_near_min_wl = v;
        else if (!strcmp(key, "tiles_per_side")) srv_tiles_per_side = (int)v;
        else if (!strcmp(key, "base_spacing")) srv_base_spacing = v;
    }
    fclose(f);
}

/* ---- layout 1: what the browser viewer receives ------------------------------------ */

#include "acc_viewer.h"

/* ---- main ------------------------------------------------------------------------ */

int main(void)
{
    /* The layout-1 section first: it is what users get.  BENCH_ACCURACY_PART
     * = viewer runs only it, = layout0 only the per-client sweep below. */
    const char *part = getenv("BENCH_ACCURACY_PART");
    int viewer_bad = 0;
    if (!part || !strcmp(part, "viewer")) {
        viewer_bad = viewer_section();
        fflush(stdout);
        if (part)
            return viewer_bad;
    }

    quick = bench_quick();
    reps_tick = quick ? 5 : 11;
    reps_frame = quick ? 3 : 7;
    W.s = quick ? 64 : 128;
    W.d = 0.5;
    W.x0 = 123.456789;
    W.z0 = 345.678901;

    ocean_params_default(&base);
    read_server_keys(CONF_PATH);
    char err[512];
    if (ocean_conf_load(CONF_PATH, &base, err, sizeof err) == OCEAN_OK)
        snprintf(base_note, sizeof base_note, "ocean_params_default + %s", CONF_PATH);
    else
        snprintf(base_note, sizeof base_note, "ocean_params_default (%s did not load: %s)", CONF_PATH, err);

    double t_start = bench_now_ms();
    /* the reference sea */
    ocean_params rp = base;
    rp.n = N_REF;
    rp.cascades = 1;
    rp.k_max = INFINITY;
    char msg[256];
    if (ocean_create(&rp, &ref_ocean, msg, sizeof msg) != OCEAN_OK) {
        fprintf(stderr, "bench_accuracy: reference ocean: %s\n", msg);
        return 1;
    }
    ocean_spectrum_stats st;
    ocean_get_spectrum_stats(ref_ocean, &st);
    ref_hs = st.hs;
    lattice_from_ocean(&ref_lat, ref_ocean, 0, T0);
    fprintf(stderr, "bench_accuracy: reference amplitudes in %.1f s\n", (bench_now_ms() - t_start) / 1e3);
    ref_full = xcalloc(NCH * (size_t)W.s * W.s, sizeof *ref_full);
    dft_add(&ref_lat, rp.sea.choppiness, ref_full);
    sset_init(&ref_set);
    sset_from_channels(&ref_set, ref_full);
    double t_ref = bench_now_ms() - t_start;
    fprintf(stderr, "bench_accuracy: reference in %.1f s\n", t_ref / 1e3);

    if (client_init(&default_client)) {
        fprintf(stderr, "bench_accuracy: default client mesh failed\n");
        return 1;
    }
    mesh_view mv;
    mesh_get_view(default_client.m, &mv);
    fprintf(stderr, "bench_accuracy: default client mesh %u vertices, %zu within %g m\n", mv.vertex_count,
            default_client.near_n, FADE_R1);

    double err_ref;
    double err_small = self_check(&err_ref);
    char ref_check[128];
    if (quick)
        snprintf(ref_check, sizeof ref_check, "N = 2048 check skipped in the quick run");
    else
        snprintf(ref_check, sizeof ref_check, "%.2e on the N = 2048 reference itself", err_ref);

    printf("### Accuracy against cost (issue 8): the per-client layout-0 path on the base sea\n\n");
    printf("**Label: not what the browser viewer receives.** This sweep measures the layout-0 path (world tiles "
           "summed and filtered per camera by the server), which only clients asking for layout 0 get, on the "
           "base sea of %s without its server.scene; the viewer subscribes layout 1 to the scene `make run` "
           "serves (the section above). The sweep compares settings of the simulation against each other.\n\n",
           CONF_PATH);
    printf("Base configuration: %s: %s %s, U10 %.3g m/s, choppiness %.3g, N = %d, "
           "%d cascade(s), patch %.0f m, seed %llu, %d threads; client (the daemon's defaults): codec %s %g, "
           "concentric mesh at %g px over %g m (camera 20 m: %u vertices), no cutoff, near field (where a "
           "setting has one) %d waves fading out at %g m, shortest %g m. The daemon itself serves "
           "server.scene (ship-bridge unless configured), whose own sea is timed in the scene table.\n\n",
           base_note, ocean_spectrum_name(base.sea.spectrum), ocean_spreading_name(base.sea.spreading),
           base.sea.wind_u10, base.sea.choppiness, base.n, base.cascades, base.patch_m,
           (unsigned long long)base.seed, base.threads, proto_codec_name(PROTO_CODEC_DEFAULT),
           PROTO_ACCURACY_DEFAULT, srv_mesh_error_px, srv_view_range, mv.vertex_count, srv_near_waves,
           srv_near_radius, srv_near_min_wl);
    printf("**Reference.** The same sea (same seed and spectrum, waves keyed by wave vector) at N = %d on the "
           "%.0f m patch (waves down to %.2f m), summed directly in double at %d x %d points %.2f m apart "
           "(a %.0f m window at (%.3f, %.3f), off every FFT grid), t = %g s; Hs of the reference spectrum "
           "%.3f m. Direct summation, not the N = 2048 FFT field, because that field is float on a %.2f m grid "
           "and reading it between grid points adds bilinear error of the size measured here; the sum is exact "
           "at every point and, being separable, costs O(modes x %d). Settings with more cascades carry waves "
           "of other patches; their reference is their own waves summed exactly plus the N = %d waves outside "
           "their bands. Self-check of the separable sum against ocean_reference_point: max difference "
           "%.2e (N = 64, 2 cascades), %s. Reference built in %.1f s.\n\n",
           N_REF, base.patch_m, 2.0 * base.patch_m / N_REF, W.s, W.s, W.d, W.s * W.d, W.x0, W.z0, T0, ref_hs,
           base.patch_m / N_REF, W.s, N_REF, err_small, ref_check, t_ref / 1e3);
    printf("**Columns.** tick = median ocean_evaluate (all four effects unless noted, %d runs); frame = median "
           "per-client work (%d runs): the client's tiles as the daemon lays them out (%d levels, %d x %d tiles "
           "of 64 x 64 samples per level at %g m x 2^level, read from the summed cascades; H DX DZ normal foam "
           "J) encoded with the client's codec, plus the near field where the setting has one (the mesh is "
           "costed on its own axis); KiB/frame = tile bytes. Ratios between rows are measured in the same run. Height RMS in %% of Hs; normal angle between the setting's and the reference's normals "
           "(from the slopes); foam = mean coverage over the window, setting (reference); E_error from "
           "ocean_frame_info; PSNR h with peak = the reference's height range in the window; PSNR n and SSIM "
           "n on the normal map as RGB; slope var = the setting's slope variance over the reference's (1 = all "
           "the roughness); front h/n = on the Pareto front of (tick + frame time, height error) / (time, "
           "normal error) within the table (for codecs: of (bytes, error)).\n\n", reps_tick, reps_frame,
           CLIENT_LEVELS, srv_tiles_per_side, srv_tiles_per_side, srv_base_spacing);
    fflush(stdout);

    run_grid();
    /* the default on the fronts? */
    const row *def = NULL;
    for (int i = 0; i < nrows; i++)
        if (!strcmp(rows[i].axis, "grid") && rows[i].is_default)
            def = &rows[i];
    print_table("grid", "FFT resolution x cascade count",
                " shortest wave m |", "Every setting evaluates height, displacement, normals and foam on every cascade.");
    if (!quick)
        print_table("check", "Check: the N = 2048 FFT against its own direct sum", " shortest wave m |",
                    "What float storage and bilinear reading alone leave (not a setting on offer). At the grid "
                    "points themselves the FFT equals the direct sum to float precision; between them, "
                    "bilinear reading of the finest waves (2 samples per wavelength at the Nyquist edge) "
                    "costs this much, and every setting carries the same kind of floor from its own finest "
                    "band.");
    if (def) {
        char verdict[2048];
        size_t vl = 0;
        vl += (size_t)snprintf(verdict + vl, sizeof verdict - vl,
                               "**Shipped default (%s, %.2f ms tick + client frame, height %.3g %%Hs, normals %.3g deg) "
                               "on the Pareto front:** height %s, normals %s.", def->label, row_time(def),
                               def->m.h_rms_pct, def->m.n_rms_deg, def->front_h ? "yes" : "NO",
                               def->front_n ? "yes" : "NO");
        for (int k = 0; k < 2; k++) {
            int on = k == 0 ? def->front_h : def->front_n;
            if (on)
                continue;
            vl += (size_t)snprintf(verdict + vl, sizeof verdict - vl, " Dominated on %s by:", k == 0 ? "height" : "normals");
            for (int i = 0; i < nrows && vl < sizeof verdict - 128; i++) {
                const row *r = &rows[i];
                if (strcmp(r->axis, "grid") || r == def)
                    continue;
                double e = k == 0 ? r->m.h_rms_pct : r->m.n_rms_deg, ed = k == 0 ? def->m.h_rms_pct : def->m.n_rms_deg;
                if (row_time(r) <= row_time(def) && e <= ed)
                    vl += (size_t)snprintf(verdict + vl, sizeof verdict - vl, " %s (%.2f ms, %.3g)", r->label,
                                           row_time(r), e);
            }
            vl += (size_t)snprintf(verdict + vl, sizeof verdict - vl, ".");
        }
        /* The shared work alone: with many clients the tick is paid once,
         * so the front on tick time says which sea to simulate. */
        for (int k = 0; k < 2; k++) {
            int first = 1;
            for (int i = 0; i < nrows && vl < sizeof verdict - 160; i++) {
                const row *r = &rows[i];
                if (strcmp(r->axis, "grid") || r == def)
                    continue;
                double e = k == 0 ? r->m.h_rms_pct : r->m.n_rms_deg, ed = k == 0 ? def->m.h_rms_pct : def->m.n_rms_deg;
                if (r->tick_ms <= def->tick_ms && e <= ed) {
                    vl += (size_t)snprintf(verdict + vl, sizeof verdict - vl, "%s %s (%.2f ms, %.3g)",
                                           first ? (k == 0 ? " On tick time alone the default is dominated on height by:"
                                                           : " On tick time alone, on normals by:") : ",",
                                           r->label, r->tick_ms, e);
                    first = 0;
                }
            }
            if (!first)
                vl += (size_t)snprintf(verdict + vl, sizeof verdict - vl, ".");
        }
        printf("%s\n\n", verdict);
        FILE *vf = fopen(OUT_DIR "/default_verdict.md", "w");
        if (vf) {
            fprintf(vf, "%s\n", verdict);
            fclose(vf);
        }
    }
    run_cutoff();
    print_table("cutoff", "Cutoff policy and level (N = default, cutoff bucketed as the server does)",
                " cutoff rad/m |", "Error against the unfiltered reference: what a filtered client does not see. "
                "Antialias clients at 60 fps receiving the default mesh's near spacing.");
    run_gerstner();
    print_table("gerstner", "Gerstner near-field wave count",
                " waves |", "FFT band cut to the disc inside its grid (k_max = (N/2 - 1) dk); the near field "
                "covers the annulus from there to the reference's shortest wave; frame includes the near field "
                "summed at the mesh vertices within the fade radius. The near field is an independent draw of "
                "its band, so pointwise it cannot match the reference's waves there (its error adds); what it "
                "restores is the band's roughness, shown by the slope-variance ratio.");
    run_precision_codec();
    char note[1024];
    snprintf(note, sizeof note, "Errors here are what the storage or codec **adds**: against the same field kept "
             "in f32 (one cascade, N = %d), read at the same points. That field's own error against the "
             "N = %d reference is %.3g %%Hs height RMS, %.3g deg normal RMS, SSIM %.4f; ",
             base.n, N_REF, field_vs_ref.h_rms_pct, field_vs_ref.n_rms_deg, field_vs_ref.ssim_n);
    char note2[1400];
    snprintf(note2, sizeof note2, "%stick includes the conversion; errors after the f16 round trip of every "
             "channel; KiB/frame = the client's tiles (default codec).", note);
    print_table("precision", "Storage precision of the evaluated fields", " KiB held |", note2);
    snprintf(note2, sizeof note2, "%serrors after encoding and decoding every 64 x 64 tile of the field "
             "(normals octahedral); frame = encoding all tiles; decode ms = the client's cost for them.", note);
    print_table("codec", "Tile codec and quantisation step", " decode ms |", note2);
    run_mesh();
    snprintf(note2, sizeof note2, "Range %g m; camera 40 m up, 80 m behind the window, pitch -25 deg, 1920 x "
             "1080, 60 deg fov. Errors are the mesh's own: its displaced surface interpolated over each "
             "triangle at the window points (normals from the triangle's plane) against the sea it displaces by "
             "(default field, read at the same points; that field's own error against the N = %d reference is "
             "%.3g %%Hs, %.3g deg). Frame = mesh update for a camera moving 0.5 m per frame + displacement; "
             "KiB/frame = vertex positions; max error px = mesh_error_px over the whole mesh. Coverage differs "
             "by kind, so compare within a kind: concentric reaches the range, chunked only its tile grid "
             "(6 x 128 m by default), projected the view frustum.",
             srv_view_range, N_REF, mesh_vs_ref.h_rms_pct, mesh_vs_ref.n_rms_deg);
    print_table("mesh", "Mesh kind and density", " max error px |", note2);
    run_scenes();

    FILE *csv = fopen(OUT_DIR "/accuracy.csv", "w");
    if (csv) {
        fprintf(csv, "axis,setting,default,tick_ms,frame_ms,bytes_per_frame,extra,height_rms_pct_hs,height_max_m,"
                     "normal_rms_deg,normal_max_deg,foam_pct,foam_ref_pct,e_error,psnr_h_db,psnr_n_db,ssim_n,"
                     "slope_var_ratio,covered,front_height,front_normal\n");
        for (int i = 0; i < nrows; i++) {
            const row *r = &rows[i];
            fprintf(csv, "%s,\"%s\",%d,%.5g,%.5g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.5g,%.5g,%.5g,%.4g,%.4g,%.6f,%.5g,%.4g,%d,%d\n",
                    r->axis, r->label, r->is_default, r->tick_ms, r->frame_ms, r->bytes, r->extra, r->m.h_rms_pct,
                    r->m.h_max, r->m.n_rms_deg, r->m.n_max_deg, r->m.foam_set, r->m.foam_ref, r->m.e_error,
                    r->m.psnr_h, r->m.psnr_n, r->m.ssim_n, r->m.slope_ratio, r->m.covered, r->front_h, r->front_n);
        }
        fclose(csv);
    }
    write_headline();
    fprintf(stderr, "bench_accuracy: done in %.1f s\n", (bench_now_ms() - t_start) / 1e3);
    mesh_destroy(default_client.m);
    free(default_client.near_x);
    free(default_client.near_z);
    free(default_client.near_out);
    sset_free(&ref_set);
    free(ref_full);
    free(ref_lat.h);
    ocean_destroy(ref_ocean);
    free(rows);
    return viewer_bad;
}
