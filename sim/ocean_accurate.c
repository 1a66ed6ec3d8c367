/*
 * ocean_accurate.c - the accurate reading of an evaluated frame at a
 * world point (ocean_frame_sample_accurate): Hermite interpolation of the
 * height and the displacement from their FFT derivatives, cubic Lagrange
 * for the other channels, and a bound on the reading's error.  Read-only
 * on the frame: any number of threads may read one frame at once.
 */
#include "ocean.h"
#include "ocean_internal.h"

#include <math.h>
#include <string.h>

/* Bilinear reading of a grid that holds waves up to half its Nyquist rate
 * (coarse cascades) or up to it (the finest) leaves centimetres between
 * grid points: the error is ~ (k h)^2 / 8 of each wave's amplitude, and
 * the coarse cascades put metres of amplitude near k h = pi / 2.  The FFT
 * already gives each field's exact first derivatives at the grid points
 * (slopes for the height, the foam channel's Dxx, Dxz, Dzz for the
 * displacement), so the height and the displacement are read by Hermite
 * interpolation: value and first derivatives at every node, tensor product
 * of the 1-D Hermite interpolant on the 4 nodes -1..2 (degree 7),
 * H_k = (1 - 2 l_k'(x_k)(t - x_k)) l_k^2, K_k = (t - x_k) l_k^2 with l_k
 * the Lagrange basis (Hildebrand, Introduction to Numerical Analysis,
 * 1974, sec. 8.2).  Its 1-D error on a wave of k h = 1, pi/2, pi is 7e-6,
 * 2.5e-4, 4e-2 of the amplitude, against 0.12, 0.29, 1 for bilinear (six
 * nodes would give 2e-8, 5e-6, 9e-3, but cost four times as much for a
 * third less error on the storm scene).  The tensor product needs the cross
 * derivative f_xz at the nodes, which no channel holds: the mean of the
 * differences of f_x along z and of f_z along x, sixth-order central on
 * the coarse cascades (k h <= pi / 2), a 21-point least-squares stencil on
 * the finest, whose diagonal waves reach k h = 2.2 where the sixth-order
 * difference is 30 % off (wide_w).  Channels without derivatives
 * (slopes, velocity, Dxx...) are read by 4 x 4 cubic Lagrange.
 *
 * Measured on the storm scene (Beaufort 10, 3 cascades of N = 256, the
 * finest to its Nyquist rate) against the direct sum of every mode in
 * double: height 0.07 mm RMS, 0.24 mm worst; bilinear 6 cm, 18 cm (1.2 us
 * against 0.15 us per reading of every channel, bench_near).
 *
 * Error bound: per wave, the interpolation error divided by the response
 * of the fourth difference (2 sin(k h / 2))^4 grows with k h, so over a
 * band that stops at k h = pi / 2 (coarse cascades) or pi (the finest) it
 * is at most its value there; the fourth differences of the nodes around
 * the point, along x and along z, measure the local amplitude of exactly
 * the waves that matter (hermite_read). */

#define ACC_REACH 11                  /* nodes -11 .. 12 around the cell */
#define ACC_SPAN (2 * ACC_REACH + 2)
#define ACC_MAXN 4

typedef struct stencil {
    size_t row[ACC_SPAN];             /* offsets of rows i0 - 11 .. i0 + 12 */
    int col[ACC_SPAN];                /* columns j0 - 11 .. j0 + 12 */
    int nodes, first;                 /* Hermite nodes first .. first + nodes - 1 */
    double hu[ACC_MAXN], ku[ACC_MAXN];/* Hermite value and slope bases along x */
    double hv[ACC_MAXN], kv[ACC_MAXN];/* and along z */
    double lu[4], lv[4];              /* cubic Lagrange, nodes -1..2 */
    double h;                         /* grid spacing, m */
    /* The cross-derivative term folded into one weight per row (wz, for
     * f_x differenced along z) and per column (wx, f_z along x), offsets
     * -11 .. 12 by index + ACC_REACH, nonzero in [lo, hi] (stencil_of). */
    double wz[ACC_SPAN], wx[ACC_SPAN];
    int lo, hi;
    int contig;                       /* columns lo .. hi do not wrap */
    size_t off[ACC_MAXN * ACC_MAXN];  /* the 4 x 4 nodes' offsets, row-major */
} stencil;

static void lagrange4(double t, double w[4])
{
    double all[OCEAN_INTERP_MAX_TAPS];
    ocean_interp_weights(OCEAN_INTERP_LAGRANGE, t, all);
    for (int k = 0; k < 4; k++)
        w[k] = all[k];
}

/* Hermite bases on the nodes -1..2 at t, from their Lagrange basis l
 * (lagrange4): H_k = (1 - 2 l_k'(x_k)(t - x_k)) l_k^2, K_k = (t - x_k) l_k^2,
 * where l_k'(x_k) = sum over m != k of 1 / (x_k - x_m). */
static void hermite4(double t, const double l[4], double *hv, double *kv)
{
    static const double lp[4] = {-11.0 / 6.0, -0.5, 0.5, 11.0 / 6.0};
    for (int k = 0; k < 4; k++) {
        double d = t - (k - 1), l2 = l[k] * l[k];
        hv[k] = (1.0 - 2.0 * lp[k] * d) * l2;
        kv[k] = d * l2;
    }
}

/* h times the derivative along one axis at a node, as differences of the
 * nodes m = 1 .. reach away: weights of (node + m) - (node - m).  Sixth-
 * order central for the coarse cascades (k h <= pi / 2). */
static const double cdiff6_w[3] = {45.0 / 60.0, -9.0 / 60.0, 1.0 / 60.0};

/* The same for a grid whose waves reach its Nyquist rate: 21 points,
 * weights fitted by least squares to the exact derivative (relative error
 * of the modified wave number) over k h in (0, 2.3], which holds the whole
 * band |k| h <= pi in the diagonal directions, where a cross derivative
 * matters; relative error <= 3.2e-4 there (the sixth-order difference is
 * 30 % off at k h = 2.2). */
static const double wide_w[10] = {
    0.96149997793578101, -0.42688812746433052, 0.23261704731444471, -0.13048081462293556,
    0.070745166958478364, -0.035655135414171368, 0.016085410075560996, -0.0061669823723281957,
    0.0018241301461298877, -0.00031443106493215573};

/* Fills *sp for reading fd at (x, z) (by pointer: the struct is 700 bytes). */
static void stencil_of(const ocean_field *fd, double x, double z, int finest, stencil *sp)
{
    const int nodes = ACC_MAXN;
    ocean_cell q = ocean_locate(fd, x, z);
    int n = fd->n, m = n - 1;
    for (int k = 0; k < ACC_SPAN; k++) {
        sp->row[k] = (size_t)((q.i0 + k - ACC_REACH + 4 * n) & m) * n;
        sp->col[k] = (q.j0 + k - ACC_REACH + 4 * n) & m;
    }
    sp->nodes = nodes;
    sp->first = 1 - nodes / 2;
    lagrange4(q.fx, sp->lu);
    lagrange4(q.fz, sp->lv);
    hermite4(q.fx, sp->lu, sp->hu, sp->ku);
    hermite4(q.fz, sp->lv, sp->hv, sp->kv);
    sp->h = fd->patch_m / n;
    /* The tensor product's cross term sums f_xz ku[a] kv[b] over the
     * nodes, and f_xz at a node is a difference of its neighbours: the sum
     * regroups as one weight per row of the f_x plane (per column of f_z)
     * that a node's difference reaches, so a reading costs one pass over
     * those rows instead of one difference per node (4x fewer loads on the
     * finest cascade's 21-point stencil). */
    int reach = finest ? 10 : 3;
    const double *w = finest ? wide_w : cdiff6_w;
    memset(sp->wz, 0, sizeof sp->wz);
    memset(sp->wx, 0, sizeof sp->wx);
    for (int b = 0; b < nodes; b++)
        for (int d = 1; d <= reach; d++) {
            int at = b + sp->first + ACC_REACH; /* node b's index, rows and columns alike */
            sp->wz[at + d] += sp->kv[b] * w[d - 1];
            sp->wz[at - d] -= sp->kv[b] * w[d - 1];
            sp->wx[at + d] += sp->ku[b] * w[d - 1];
            sp->wx[at - d] -= sp->ku[b] * w[d - 1];
        }
    sp->lo = sp->first - reach;
    sp->hi = sp->first + nodes - 1 + reach;
    sp->contig = sp->col[sp->hi + ACC_REACH] - sp->col[sp->lo + ACC_REACH] == sp->hi - sp->lo;
    for (int b = 0; b < nodes; b++)
        for (int a = 0; a < nodes; a++)
            sp->off[b * nodes + a] = sp->row[b + sp->first + ACC_REACH] + (size_t)sp->col[a + sp->first + ACC_REACH];
}

/* Node (r, c) relative to the cell's corner, r and c in -11..12. */
static inline double node(const float *g, const stencil *s, int r, int c)
{
    return g[s->row[r + ACC_REACH] + s->col[c + ACC_REACH]];
}

static double lagrange_read(const float *g, const stencil *s)
{
    /* nodes -1 .. 2 are the Hermite nodes (first = -1): their offsets */
    double acc = 0.0;
    for (int r = 0; r < 4; r++) {
        double rowv = 0.0;
        for (int c = 0; c < 4; c++)
            rowv += s->lu[c] * g[s->off[4 * r + c]];
        acc += s->lv[r] * rowv;
    }
    return acc;
}

/* The larger of two finite values, inlined (libm's fmax is a call). */
static inline double max2(double a, double b)
{
    return a > b ? a : b;
}

/* The envelope terms of hermite_read's bound (see there): *hx, *hz and
 * *hxz from the 8 x 8 nodes around the cell.  Always inlined, so each
 * call with a constant `finest` gets its own copy; a coarse cascade's
 * copy loads and differences no slopes, and gives the terms the general
 * code gave with them zero, bit for bit. */
static inline __attribute__((always_inline)) void envelope(const float *g, const float *gx,
                                                           const float *gz, const stencil *s,
                                                           int finest, double *hx_out,
                                                           double *hz_out, double *hxz_out)
{
    enum { B = ACC_MAXN + 4 };
    double h = s->h, hx = 0.0, hz = 0.0, hxz = 0.0;
    /* The nodes the fourth differences reach (two beyond the 4 x 4 on each
     * side) are loaded once into blk (values), bx (h f_x) and bz (h f_z),
     * not five times each.  The slopes only on the finest cascade: a
     * coarse one stops at k h = pi / 2, where any four consecutive node
     * values hold 0.71 of a wave's amplitude (the bound's factor 2 covers
     * that), so its values alone bound it. */
    float blk[B][B], bx[B][B], bz[B][B];
    for (int i = 0; i < B; i++)
        for (int k = 0; k < B; k++) {
            int r = s->first - 2 + i, c = s->first - 2 + k;
            blk[i][k] = (float)node(g, s, r, c);
            if (finest) {
                bx[i][k] = (float)(h * node(gx, s, r, c));
                bz[i][k] = (float)(h * node(gz, s, r, c));
            }
        }
    /* A wave near the band's top, k h = th_top, beats against the nodes:
     * its node values follow an envelope |cos| that passes through 0 where
     * the wave between them still has its full amplitude (at th = pi - e,
     * A cos(th j + phi) = (-1)^j A cos(e j - phi)).  Its slopes at the
     * nodes then hold that amplitude (h f_x = -th A sin(...)), so the
     * envelope is taken from both: the fourth difference of the values,
     * and that of h times the derivative over th_top.  For one wave of any
     * k h <= th_top the larger of the two is within a factor th_top / th
     * of its amplitude times the difference's response, and where that
     * factor matters (low k h) the values alone hold it. */
    /* Second differences first, each once: along x of the values (vx)
     * and of h f_x (sx), along z of the values (vz) and of h f_z (sz).
     * At the 4 x 4 nodes (block rows and columns 2..5) the fourth
     * differences along x and z (a wave's response (2 sin(th / 2))^4, 16
     * at the Nyquist rate) and the mixed one, second along x and along z
     * ((2 sin(th_x / 2))^2 (2 sin(th_z / 2))^2, large only where both
     * components are), are second differences of those.  The slopes'
     * terms are divided by th_top = pi, the finest cascade's band top. */
    float vx[B][B], vz[B][B], sx[B][B], sz[B][B];
    for (int i = 0; i < B; i++)
        for (int k = 1; k < B - 1; k++) {
            vx[i][k] = blk[i][k - 1] - 2.0f * blk[i][k] + blk[i][k + 1];
            vz[k][i] = blk[k - 1][i] - 2.0f * blk[k][i] + blk[k + 1][i];
            if (finest) {
                sx[i][k] = bx[i][k - 1] - 2.0f * bx[i][k] + bx[i][k + 1];
                sz[k][i] = bz[k - 1][i] - 2.0f * bz[k][i] + bz[k + 1][i];
            }
        }
    for (int i = 2; i < B - 2; i++)
        for (int k = 2; k < B - 2; k++) {
            double d4x = fabs(vx[i][k - 1] - 2.0 * vx[i][k] + vx[i][k + 1]);
            double d4z = fabs(vz[i - 1][k] - 2.0 * vz[i][k] + vz[i + 1][k]);
            double dm = fabs(vx[i - 1][k] - 2.0 * vx[i][k] + vx[i + 1][k]);
            if (finest) {
                d4x = max2(d4x, fabs(sx[i][k - 1] - 2.0 * sx[i][k] + sx[i][k + 1]) / M_PI);
                d4z = max2(d4z, fabs(sz[i - 1][k] - 2.0 * sz[i][k] + sz[i + 1][k]) / M_PI);
                dm = max2(dm, max2(fabs(sx[i - 1][k] - 2.0 * sx[i][k] + sx[i + 1][k]),
                                   fabs(sz[i][k - 1] - 2.0 * sz[i][k] + sz[i][k + 1])) / M_PI);
            }
            if (d4x > hx) hx = d4x;
            if (d4z > hz) hz = d4z;
            if (dm > hxz) hxz = dm;
        }
    *hx_out = hx;
    *hz_out = hz;
    *hxz_out = hxz;
}

/* Hermite reading of value plane g with derivative planes gx (d/dx) and
 * gz (d/dz); *bound (unless NULL) receives its error bound (see the
 * section comment). */
static double hermite_read(const float *g, const float *gx, const float *gz, const stencil *s,
                           int finest, double *bound)
{
    double h = s->h, acc = 0.0, big = 0.0, hx = 0.0, hz = 0.0, hxz = 0.0;
    /* The cross term: h^2 f_xz at the nodes (the mean of f_x differenced
     * along z and f_z along x) times ku kv, by the stencil's folded
     * weights; az[a] sums node column a along z, ax[a] node row a along x,
     * all advanced together: eight independent chains of adds, not one. */
    double az[ACC_MAXN] = {0}, ax[ACC_MAXN] = {0}, cross = 0.0;
    if (s->contig) {
        /* the columns lo .. hi do not wrap: plain pointers, the same sums */
        const int c0 = s->col[s->first + ACC_REACH], cl = s->col[s->lo + ACC_REACH];
        const float *ra[ACC_MAXN];
        for (int a = 0; a < ACC_MAXN; a++)
            ra[a] = gz + s->row[a + s->first + ACC_REACH] + cl - s->lo;
        for (int j = s->lo; j <= s->hi; j++) {
            double wz = s->wz[j + ACC_REACH], wx = s->wx[j + ACC_REACH];
            const float *rj = gx + s->row[j + ACC_REACH] + c0;
            for (int a = 0; a < ACC_MAXN; a++) {
                az[a] += wz * rj[a];
                ax[a] += wx * ra[a][j];
            }
        }
    } else {
        for (int j = s->lo; j <= s->hi; j++) {
            double wz = s->wz[j + ACC_REACH], wx = s->wx[j + ACC_REACH];
            for (int a = 0; a < ACC_MAXN; a++) {
                az[a] += wz * node(gx, s, j, a + s->first);
                ax[a] += wx * node(gz, s, a + s->first, j);
            }
        }
    }
    for (int a = 0; a < ACC_MAXN; a++)
        cross += s->ku[a] * az[a] + s->kv[a] * ax[a];
    acc += 0.5 * cross * h;
    for (int b = 0; b < s->nodes; b++) {          /* row node r (z) */
        for (int a = 0; a < s->nodes; a++) {      /* column node c (x) */
            size_t o = s->off[b * ACC_MAXN + a];
            double fv = g[o], fx = gx[o] * h, fz = gz[o] * h;
            acc += fv * s->hu[a] * s->hv[b] + fx * s->ku[a] * s->hv[b] + fz * s->hu[a] * s->kv[b];
            if (bound && fabs(fv) > big)
                big = fabs(fv);
        }
    }
    if (bound) {
        if (finest)
            envelope(g, gx, gz, s, 1, &hx, &hz, &hxz);
        else
            envelope(g, gx, gz, s, 0, &hx, &hz, &hxz);
    }
    /* Per wave, the 1-D error over the fourth difference's response peaks
     * at the band's top: 6.3e-5 at k h = pi / 2 (coarse cascades' edge),
     * 2.7e-3 at pi (the finest; 1.3e-3 at k h = 2.8: 1.5e-3 is taken,
     * which the factor 2 below lifts above the value at pi).  Along each
     * axis the error is at most that ratio times the high-passed field,
     * whose local envelope the nodes (values and slopes, above) sample; a
     * factor 2 covers the envelope between nodes.  On the finest cascade
     * the cross derivative's 21-point stencil is fitted up to k h = 2.3: a
     * wave with both components high (past it in one, or a band that
     * fills the square grid to its corners, ocean.k_max = inf) is read
     * with a cross term the fourth differences along the axes do not see,
     * so the mixed difference adds its own term, 5e-3 of it.  Scanned wave
     * by wave over every lattice wave of a 64-point grid (400 points
     * each), error over bound is at most 0.95 inside the Nyquist circle
     * (the slopes' envelope covers k h = 3.04 along an axis, where the
     * values' envelope passes through 0), but 2.7 for a lone wave at the
     * square's corner, k h = (3.04, 3.04): a band that fills the square
     * relies on its corner waves carrying little beside the rest, as in
     * the default sea (0 of 400 query points over their bound).  Float
     * storage adds 2^-22 of the nodes' magnitude. */
    double ratio = finest ? 1.5e-3 : 6.3e-5, ratio_xz = finest ? 5e-3 : 0.0;
    if (bound)
        *bound = 2.0 * ratio * (hx + hz) + 2.0 * ratio_xz * hxz + big * 0x1p-22;
    return acc;
}

void ocean_frame_sample_accurate(const ocean_frame *f, double x, double z, unsigned want,
                                 ocean_point *out, ocean_point *err)
{
    enum { H, DX, DZ, SX, SZ, VX, VY, VZ, DXX, DZZ, DXZ, BQ, NV };
    double v[NV] = {0}, e[3] = {0};
    int any_foam = 0, blind[3] = {0};
    for (int c = 0; c < f->cascades; c++) {
        const ocean_field *fd = &f->field[c];
        if (!fd->effects)
            continue;
        int finest = c == f->cascades - 1;
        stencil s;
        stencil_of(fd, x, z, finest, &s);
        double b = 0.0, *bp = err ? &b : NULL;
        if ((want & OCEAN_SAMPLE_HEIGHT) && fd->height) {
            if (fd->slope_x) {
                v[H] += hermite_read(fd->height, fd->slope_x, fd->slope_z, &s, finest, bp);
                e[0] += b;
            } else {
                v[H] += lagrange_read(fd->height, &s);
                blind[0] = 1;
            }
        }
        if ((want & OCEAN_SAMPLE_DISPLACEMENT) && fd->dx) {
            if (fd->dxx) {
                v[DX] += hermite_read(fd->dx, fd->dxx, fd->dxz, &s, finest, bp);
                e[1] += b;
                v[DZ] += hermite_read(fd->dz, fd->dxz, fd->dzz, &s, finest, bp);
                e[2] += b;
            } else {
                v[DX] += lagrange_read(fd->dx, &s);
                v[DZ] += lagrange_read(fd->dz, &s);
                blind[1] = blind[2] = 1;
            }
        }
        if (want & OCEAN_SAMPLE_SLOPE) {
            if (fd->slope_x) v[SX] += lagrange_read(fd->slope_x, &s);
            if (fd->slope_z) v[SZ] += lagrange_read(fd->slope_z, &s);
        }
        if (want & OCEAN_SAMPLE_VELOCITY) {
            if (fd->vel_x) v[VX] += lagrange_read(fd->vel_x, &s);
            if (fd->vel_y) v[VY] += lagrange_read(fd->vel_y, &s);
            if (fd->vel_z) v[VZ] += lagrange_read(fd->vel_z, &s);
        }
        if ((want & OCEAN_SAMPLE_FOAM) && fd->dxx) {
            any_foam = 1;
            v[DXX] += lagrange_read(fd->dxx, &s);
            v[DZZ] += lagrange_read(fd->dzz, &s);
            v[DXZ] += lagrange_read(fd->dxz, &s);
            if (fd->bq) v[BQ] += lagrange_read(fd->bq, &s);
        }
    }
    double jac = (1.0 + v[DXX]) * (1.0 + v[DZZ]) - v[DXZ] * v[DXZ];
    *out = (ocean_point){.height = v[H], .dx = v[DX], .dz = v[DZ], .slope_x = v[SX],
                         .slope_z = v[SZ], .jacobian = jac,
                         /* the frame's whitecap foam, with the ramp of an
                          * accurate reading (ocean_foam_reading) */
                         .foam = any_foam ? ocean_frame_foam(f, OCEAN_FOAM_CUBIC, v[DXX], v[DZZ], v[BQ]) : 0.0,
                         .vel_x = v[VX], .vel_y = v[VY], .vel_z = v[VZ], .dxx = v[DXX],
                         .dzz = v[DZZ], .dxz = v[DXZ], .bq = v[BQ]};
    if (err)
        *err = (ocean_point){.height = blind[0] ? INFINITY : e[0],
                             .dx = blind[1] ? INFINITY : e[1],
                             .dz = blind[2] ? INFINITY : e[2]};
}
