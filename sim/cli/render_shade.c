/*
 * render_shade.c - the viewer's shading model in double (render_shade.h).
 *
 * Threads: a render_sky is written by render_sky_create only.
 * OOM policy: render_sky_create returns OCEAN_ENOMEM with nothing kept.
 */
#include "render_shade.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

/* clients/web/render.js's constants */
#define CLOUD_TEX 512                 /* cloud texture size, texels */
#define CLOUD_UV 32                   /* noise lattice units the texture spans */
#define CLOUD_SCALE (1.0 / 2500.0)    /* noise units per metre */
#define CLOUD_K (CLOUD_SCALE / CLOUD_UV)
#define CLOUD_ALT 2000.0
#define CLOUD_MIPS 10                 /* 512 .. 1 */
#define SUN_E 6.0
#define SUN_MSS 1e-5
#define HAZE_M 42000.0

static const double WATER_DEEP[3] = {0.004, 0.028, 0.058};
static const double WATER_SCATTER[3] = {0.02, 0.21, 0.22};
static const double SUN_COLOR[3] = {1.0, 0.92, 0.80};

struct render_sky {
    double sun[3];
    double eye[3];
    double cloud_off[2];              /* the viewer's u_cloudOff */
    float *mip[CLOUD_MIPS];           /* the cloud texture and its box-filtered mips */
};

/* ---- the cloud texture: render.js makeCloudTexture, the same bytes ---- */

static double cloud_hash(uint32_t x, uint32_t y, uint32_t o)
{
    uint32_t h = x * 374761393u + y * 668265263u + o * 2147483647u;
    h = (h ^ (h >> 13)) * 1274126177u;
    return (double)(h ^ (h >> 16)) / 4294967296.0;
}

static double cloud_texel(int x, int y)
{
    double s = 0, a = 0.5, norm = 0;
    for (int o = 0; o < 5; o++) {
        int per = CLOUD_UV << o;
        double fx = (double)x / CLOUD_TEX * per, fy = (double)y / CLOUD_TEX * per;
        int ix = (int)floor(fx), iy = (int)floor(fy);
        double tx = fx - ix, ty = fy - iy;
        double ux = tx * tx * (3 - 2 * tx), uy = ty * ty * (3 - 2 * ty);
        uint32_t x0 = (uint32_t)(ix % per), y0 = (uint32_t)(iy % per);
        uint32_t x1 = (uint32_t)((ix + 1) % per), y1 = (uint32_t)((iy + 1) % per);
        double v = (cloud_hash(x0, y0, (uint32_t)o) * (1 - ux) + cloud_hash(x1, y0, (uint32_t)o) * ux) * (1 - uy) +
                   (cloud_hash(x0, y1, (uint32_t)o) * (1 - ux) + cloud_hash(x1, y1, (uint32_t)o) * ux) * uy;
        s += a * v;
        norm += a;
        a *= 0.5;
    }
    return floor(255 * s / norm + 0.5) / 255.0;
}

static int cloud_build(render_sky *s)
{
    for (int m = 0, n = CLOUD_TEX; m < CLOUD_MIPS; m++, n /= 2) {
        s->mip[m] = malloc(sizeof(float) * (size_t)n * (size_t)n);
        if (!s->mip[m]) return -1;
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++) {
                if (m == 0) {
                    s->mip[0][y * n + x] = (float)cloud_texel(x, y);
                    continue;
                }
                const float *p = s->mip[m - 1];
                int w = 2 * n;
                s->mip[m][y * n + x] = 0.25f * (p[2 * y * w + 2 * x] + p[2 * y * w + 2 * x + 1] +
                                                p[(2 * y + 1) * w + 2 * x] + p[(2 * y + 1) * w + 2 * x + 1]);
            }
    }
    return 0;
}

/* GL LINEAR with REPEAT on mip m at texture coordinates (u, v). */
static double cloud_bilinear(const render_sky *s, int m, double u, double v)
{
    int n = CLOUD_TEX >> m;
    double x = (u - floor(u)) * n - 0.5, y = (v - floor(v)) * n - 0.5;
    double fx = floor(x), fy = floor(y), tx = x - fx, ty = y - fy;
    int x0 = ((int)fx % n + n) % n, y0 = ((int)fy % n + n) % n;
    int x1 = (x0 + 1) % n, y1 = (y0 + 1) % n;
    const float *t = s->mip[m];
    return (t[y0 * n + x0] * (1 - tx) + t[y0 * n + x1] * tx) * (1 - ty) +
           (t[y1 * n + x0] * (1 - tx) + t[y1 * n + x1] * tx) * ty;
}

/* The cloud texture read trilinearly for a footprint of foot_m metres. */
static double cloud_read(const render_sky *s, double u, double v, double foot_m)
{
    double lod = log2(fmax(foot_m * CLOUD_K * CLOUD_TEX, 1.0));
    if (!(lod < CLOUD_MIPS - 1)) lod = CLOUD_MIPS - 1;
    int m = (int)lod;
    double f = lod - m;
    double c = cloud_bilinear(s, m, u, v);
    return f > 0 ? c * (1 - f) + cloud_bilinear(s, m + 1, u, v) * f : c;
}

static double smoothstep(double a, double b, double x)
{
    double t = fmin(fmax((x - a) / (b - a), 0.0), 1.0);
    return t * t * (3 - 2 * t);
}

/* cloud cover 0..1 at world (x, z) given relative to the eye */
static double clouds(const render_sky *s, double rx, double rz, double foot_m)
{
    return smoothstep(0.48, 0.75, cloud_read(s, rx * CLOUD_K + s->cloud_off[0], rz * CLOUD_K + s->cloud_off[1], foot_m));
}

ocean_result render_sky_create(double wind_dir_deg, double t, const double eye[3], const double *sun_deg,
                               render_sky **out)
{
    *out = NULL;
    if (!isfinite(wind_dir_deg) || !isfinite(t) || !isfinite(eye[0]) || !isfinite(eye[1]) || !isfinite(eye[2]) ||
        (sun_deg && (!isfinite(sun_deg[0]) || !(fabs(sun_deg[1]) <= 90))))
        return OCEAN_EINVAL;
    render_sky *s = calloc(1, sizeof *s);
    if (!s) return OCEAN_ENOMEM;
    if (cloud_build(s)) {
        render_sky_destroy(s);
        return OCEAN_ENOMEM;
    }
    double d = wind_dir_deg * M_PI / 180, sun[3] = {cos(d + 0.5), 0.32, sin(d + 0.5)};
    if (sun_deg) {
        double a = sun_deg[0] * M_PI / 180, e = sun_deg[1] * M_PI / 180;
        sun[0] = cos(e) * cos(a);
        sun[1] = sin(e);
        sun[2] = cos(e) * sin(a);
    }
    double l = sqrt(sun[0] * sun[0] + sun[1] * sun[1] + sun[2] * sun[2]);
    for (int i = 0; i < 3; i++) {
        s->sun[i] = sun[i] / l;
        s->eye[i] = eye[i];
    }
    /* render.js common(): offsets of the eye reduced in double, clouds
     * drifting with the wind */
    double drift = 0.004 * t, wind[2] = {cos(d), sin(d)};
    for (int i = 0; i < 2; i++) {
        double a = eye[2 * i] * CLOUD_K + wind[i] * drift / CLOUD_UV;
        s->cloud_off[i] = a - floor(a);
    }
    *out = s;
    return OCEAN_OK;
}

void render_sky_destroy(render_sky *s)
{
    if (!s) return;
    for (int m = 0; m < CLOUD_MIPS; m++) free(s->mip[m]);
    free(s);
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void sky_halo(double sd, double out[3])
{
    double k = 0.25 * pow(sd, 8.0) + 0.45 * pow(sd, 64.0);
    for (int i = 0; i < 3; i++) out[i] = SUN_COLOR[i] * k;
}

static void sky_gradient(double y, double out[3])
{
    static const double lo[3] = {0.55, 0.68, 0.82}, hi[3] = {0.09, 0.25, 0.60};
    double f = pow(fmax(y, 0.0), 0.45);
    for (int i = 0; i < 3; i++) out[i] = lo[i] + (hi[i] - lo[i]) * f;
}

/* gradient + halo (render.js skyBase) */
static void sky_base(const render_sky *s, const double d[3], double out[3])
{
    double h[3];
    sky_gradient(d[1], out);
    sky_halo(fmax(dot3(d, s->sun), 0.0), h);
    for (int i = 0; i < 3; i++) out[i] += h[i];
}

void render_sky_radiance(const render_sky *s, const double d_in[3], double footprint_rad, double out[3])
{
    double d[3] = {d_in[0], fabs(d_in[1]), d_in[2]};
    sky_base(s, d, out);
    if (d[1] <= 0.01) return;
    double t = (CLOUD_ALT - s->eye[1]) / d[1];
    if (t <= 0) return;
    /* the footprint on the cloud deck along the view, as a GPU's
     * isotropic trilinear read takes the larger derivative */
    double cl = clouds(s, d[0] * t, d[2] * t, t * footprint_rad / d[1]);
    double lit = 0.78 + 0.3 * pow(fmax(dot3(d, s->sun), 0.0), 4.0);
    double a = cl * smoothstep(0.01, 0.2, d[1]) * 0.85;
    static const double cloud_col[3] = {0.92, 0.93, 0.95};
    for (int i = 0; i < 3; i++) out[i] += (cloud_col[i] * lit - out[i]) * a;
}

void render_sky_view(const render_sky *s, const double d[3], double footprint_rad, double out[3])
{
    render_sky_radiance(s, d, footprint_rad, out);
    double disc = 40.0 * smoothstep(0.99985, 0.99995, dot3(d, s->sun));
    for (int i = 0; i < 3; i++) out[i] += SUN_COLOR[i] * disc;
}

/* render.js cloudShadow (its rel.y is the point's height over the eye) */
static double cloud_shadow(const render_sky *s, const double rel[3], double foot_m)
{
    double k = (CLOUD_ALT - rel[1]) / fmax(s->sun[1], 0.05);
    return 1.0 - 0.5 * clouds(s, rel[0] + s->sun[0] * k, rel[2] + s->sun[2] * k, foot_m);
}

/* Bruneton et al.'s approximation of Smith's Lambda (render.js lambdaSmith) */
static double lambda_smith(double c, double s2)
{
    double v = c / sqrt(fmax((1 - c * c) * 2 * s2, 1e-12));
    return v > 4 ? 0 : exp(-v * v) / (2 * v * 1.7724539);
}

/* Slope variance along the horizontal direction of a (x, z). */
static double mss_along(const double a[3], double sxx, double szz, double sxz)
{
    double l = hypot(a[0] + 1e-7, a[2]), x = (a[0] + 1e-7) / l, z = a[2] / l;
    return fmax(x * x * sxx + 2 * x * z * sxz + z * z * szz, 1e-7);
}

/* The sun's glitter: the Gaussian density of the facet slopes that mirror
 * the sun to the eye, as render.js seaShade computes it. */
static double sun_glitter(const render_sky *s, const double v[3], const double n[3], const render_surface *p)
{
    double e[3] = {-v[0], -v[1], -v[2]}, h[3];
    for (int i = 0; i < 3; i++) h[i] = s->sun[i] + e[i];
    double hl = sqrt(dot3(h, h));
    for (int i = 0; i < 3; i++) h[i] /= hl;
    if (!(h[1] > 0 && s->sun[1] > 0)) return 0;
    double sxx = p->mss[0] + SUN_MSS, szz = p->mss[1] + SUN_MSS, sxz = p->mss[2];
    double det = fmax(sxx * szz - sxz * sxz, 1e-12);
    double zx = -h[0] / h[1] - p->slope[0], zz = -h[2] / h[1] - p->slope[1];
    double q = (szz * zx * zx - 2 * sxz * zx * zz + sxx * zz * zz) / det;
    double dens = exp(-0.5 * q) / (2 * M_PI * sqrt(det));
    double zv = fmax(dot3(e, n), 0.01), zh = fmax(dot3(h, n), 0.01), zl = fmax(dot3(s->sun, n), 0.01);
    double fh = 0.02 + 0.98 * pow(1 - fmax(dot3(e, h), 0.0), 5.0);
    double g = 1 + lambda_smith(zl, mss_along(s->sun, sxx, szz, sxz)) + lambda_smith(zv, mss_along(v, sxx, szz, sxz));
    return SUN_E * fh * dens / (4 * zv * zh * zh * zh * zh * g);
}

static void facet_normal(double sx, double sz, double n[3])
{
    double l = sqrt(sx * sx + 1 + sz * sz);
    n[0] = -sx / l;
    n[1] = 1 / l;
    n[2] = -sz / l;
}

/* The sky reflected by the facets below the sample, each mixed with the
 * water's own colour by its Fresnel factor: the slopes' Gaussian
 * (mean slope, moments mss) integrated by 4 x 4 Gauss-Hermite nodes,
 * facets weighted by their area seen from the eye.  This is what the
 * viewer's mean Fresnel fit and blurred sky cube approximate. */
static void reflect_mix(const render_sky *s, const double v[3], const render_surface *p, const double water[3],
                        double footprint_rad, double out[3])
{
    static const double node[4] = {-2.3344142183389773, -0.7419637843027259, 0.7419637843027259, 2.3344142183389773};
    static const double wt[4] = {0.04587585476806849, 0.4541241452319315, 0.4541241452319315, 0.04587585476806849};
    double a = fmax(p->mss[0], 0.0), b = fmax(p->mss[1], 0.0);
    double l11 = sqrt(a), l21 = l11 > 0 ? p->mss[2] / l11 : 0, l22 = sqrt(fmax(b - l21 * l21, 0.0));
    int nq = a + b > 1e-10 ? 4 : 1;
    double acc[3] = {0, 0, 0}, wsum = 0;
    for (int i = 0; i < nq; i++)
        for (int j = 0; j < nq; j++) {
            double u = nq > 1 ? node[i] : 0, w = nq > 1 ? node[j] : 0;
            double n[3];
            facet_normal(p->slope[0] + l11 * u, p->slope[1] + l21 * u + l22 * w, n);
            double en = -dot3(v, n);
            if (en <= 0) continue;
            double weight = (nq > 1 ? wt[i] * wt[j] : 1) * en / n[1];
            double r[3], sky[3];
            for (int k = 0; k < 3; k++) r[k] = v[k] + 2 * en * n[k];
            render_sky_radiance(s, r, footprint_rad, sky);
            double f = 0.02 + 0.98 * pow(1 - en, 5.0);
            for (int k = 0; k < 3; k++) acc[k] += weight * (water[k] + (sky[k] - water[k]) * f);
            wsum += weight;
        }
    for (int k = 0; k < 3; k++) out[k] = wsum > 0 ? acc[k] / wsum : water[k];
}

void render_sea_radiance(const render_sky *s, const double v[3], const render_surface *p, double footprint_rad,
                         double out[3])
{
    double n[3];
    facet_normal(p->slope[0], p->slope[1], n);
    double dist = sqrt(dot3(p->rel, p->rel));
    double shadow = cloud_shadow(s, p->rel, dist * footprint_rad);
    double sun_up = fmin(fmax(s->sun[1] * 2, 0.05), 1.0);
    double sss = pow(fmax(dot3(v, s->sun) * 0.5 + 0.5, 0.0), 3.0) * fmin(fmax(p->crest, 0.0), 1.0);
    double water[3], col[3];
    for (int i = 0; i < 3; i++)
        water[i] = WATER_DEEP[i] * sun_up + WATER_SCATTER[i] * sss * sun_up * 0.6 +
                   WATER_SCATTER[i] * 0.06 * fmax(dot3(n, s->sun), 0.0);
    reflect_mix(s, v, p, water, footprint_rad, col);
    double glit = sun_glitter(s, v, n, p) * shadow;
    static const double up[3] = {0, 1, 0};
    double zenith[3];
    sky_base(s, up, zenith);
    double lit = (0.35 + 0.65 * fmax(dot3(n, s->sun), 0.0) * shadow) * sun_up;
    static const double foam_col[3] = {0.90, 0.94, 0.96};
    double foam = fmin(fmax(p->foam, 0.0), 1.0), hz = 1 - exp(-dist / HAZE_M), halo[3], haze[3];
    sky_gradient(0.03, haze);
    sky_halo(fmax(dot3(v, s->sun), 0.0), halo);
    for (int i = 0; i < 3; i++) {
        double c = col[i] + SUN_COLOR[i] * glit;
        c += (foam_col[i] * lit + zenith[i] * 0.25 - c) * foam;
        c *= 0.62 + 0.38 * shadow;
        out[i] = c + (haze[i] + halo[i] - c) * hz;
    }
}

void render_tonemap(const double in[3], double out[3])
{
    for (int i = 0; i < 3; i++) {
        double c = in[i] * 0.85;
        double x = (c * (2.51 * c + 0.03)) / (c * (2.43 * c + 0.59) + 0.14);
        out[i] = pow(fmin(fmax(x, 0.0), 1.0), 1 / 2.2);
    }
}
