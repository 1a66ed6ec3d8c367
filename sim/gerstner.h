/*
 * gerstner.h - the Gerstner near field: waves shorter than the finest FFT
 * cascade, summed exactly at any world point.
 *
 * A set of M (0..1024) Gerstner waves drawn deterministically from the same
 * directional spectrum and seed as the FFT ocean (wave_rng.h stream
 * OCEAN_RNG_GERSTNER), covering the annulus k_lo <= |k| < k_hi of wave
 * numbers.
 *
 * Partition with the FFT: the ocean keeps |k| < ocean_params.k_max in its
 * cascades and leaves |k| >= k_max to this set, so pass k_lo = k_max (the
 * finest cascade's upper band edge, ocean_cascade_band(...,&k_hi)).  Each
 * wave number belongs to exactly one side of the circle |k| = k_lo: nothing
 * is counted twice, and FFT variance + this set's variance = the spectrum's
 * variance below k_hi.  Variance above k_hi (waves shorter than the
 * shortest wavelength asked for) is left out on purpose.
 *
 * Sampling (stratified, variance-exact): the band is split into R
 * log-spaced annuli; annulus r gets m_r waves (M spread evenly).  Each
 * annulus's variance V_r = int int F k dk dtheta is integrated in double:
 * Gauss-Legendre in ln k on panels that end where the spectra are not
 * smooth (w_p, TMA's w_h = 1, 2, ...), tanh-sinh in theta on the quarters
 * between the spreading functions' kinks and cusps (0, +-90, 180 degrees
 * from the wind); agreement with int S(w) dw is ~1e-14.  Within an annulus
 * the direction marginal m(theta) = int F k dk, tabulated on 1024
 * directions, is cut into m_r sectors of equal variance; each wave
 * carries A = sqrt(2 V_r / m_r), so sum A_i^2 / 2 = sum_r V_r = the
 * integral of F over the band.  Inside its cell a wave's |k| is
 * log-uniform and its direction follows the tabulated marginal; cell
 * (r, s) keys its random numbers, so the same parameters give the same
 * waves on every machine.  (Changing M or R re-cuts the cells and so
 * draws a different set.)
 *
 * Lattice (lattice_m > 0, the layout-1 near-field cascade): after the
 * draw, each wave vector is moved to the nearest point 2 pi (i, j) / L of
 * the lattice of a periodic patch of side L, and w follows the moved |k|.
 * Amplitudes, phases and cells are kept, so the variance stays exactly the
 * band's; a wave moves to the nearest lattice point no earlier wave holds
 * (two waves on one point would be one wave whose variance is not the sum
 * of theirs), so by pi sqrt 2 / L in k unless its point was taken (2.3 %
 * at the band's lower edge for ship-bridge's L = 12.7 m, 15 rad/m), and
 * never beyond |i|, |j| <= k_hi L / 2 pi.  Every user of the set - tiles,
 * meshes, queries - sees the moved waves, so they all agree.
 *
 * Surface (a wave's phase th = k.x0 - w t + phi, w from the finite-depth
 * dispersion relation, phases reduced mod 2 pi in double):
 *   height     eta = f(x0) sum a_i cos th_i
 *   horizontal D   = -f(x0) sum Q a_i (k_i/|k_i|) sin th_i
 * where a_i = g_i A_i (g_i the client's Butterworth gain, optional) and
 * f(x0) the fade around the camera.  Q is the sea state's choppiness,
 * clamped so that sum Q a_i (k_i + max|grad f|) <= steepness_max <= 1:
 * the displacement's Jacobian matrix is then I - S with ||S|| <= 1, so
 * J = det >= 0 everywhere (no loops at any choppiness, with the fade's own
 * gradient included).
 *
 * Cost: creation ~6 ms for 1024 waves (the spectrum quadrature, each
 * radial node's spectrum and spreading computed once: ocean_spectrum_ring;
 * 2-core EPYC); evaluation ~10 ns per wave and point (phases and sin/cos
 * vectorised, 1 ulp).
 *
 * Thread safety: a set is immutable after creation; any number of threads
 * may evaluate it at once (per-call scratch lives on the stack, ~48 KB).
 */
#ifndef OCEAN_GERSTNER_H
#define OCEAN_GERSTNER_H

#include <stddef.h>
#include <stdint.h>

#include "filter.h"
#include "ocean_result.h"
#include "spectrum.h"

#define OCEAN_GERSTNER_MAX_WAVES 1024

typedef struct ocean_gerstner_params {
    ocean_sea_state sea;    /* spectrum, spreading, depth, choppiness */
    uint64_t seed;
    int count;              /* M, 0..1024 */
    int annuli;             /* R, 1..M; 0: round(sqrt(M)/2), at least 1 */
    double k_lo;            /* band's lower edge, rad/m (= ocean k_max) */
    double k_hi;            /* 2 pi / shortest wavelength, rad/m, <= 1e5 */
    double steepness_max;   /* bound on sum Q k a, (0, 1]; default 1 */
    double lattice_m;       /* 0: wave vectors as drawn; > 0: each snapped to
                               the nearest 2 pi (i, j) / lattice_m (integer
                               i, j), so the set is periodic on a lattice_m
                               patch and an FFT of that patch can carry it
                               (ocean_create_lattice); <= 1e5 m */
} ocean_gerstner_params;

/* Defaults: sea = ocean_sea_state_default, seed 1, 256 waves, auto annuli,
 * band 2 pi/8 m .. 2 pi/0.05 m, steepness_max 1, no lattice. */
void ocean_gerstner_params_default(ocean_gerstner_params *p);

/* Checks p; OCEAN_EINVAL with a message naming the field. */
ocean_result ocean_gerstner_params_validate(const ocean_gerstner_params *p, char *msg, size_t msglen);

typedef struct ocean_gerstner ocean_gerstner;

/* Draws the waves of p.  *out is NULL on failure (OCEAN_EINVAL with msg,
 * or OCEAN_ENOMEM). */
ocean_result ocean_gerstner_create(const ocean_gerstner_params *p, ocean_gerstner **out,
                                   char *msg, size_t msglen);
/* Accepts NULL. */
void ocean_gerstner_destroy(ocean_gerstner *g);

/* One wave of the set. */
typedef struct ocean_gerstner_wave {
    double kx, kz, k;     /* wave vector, rad/m */
    double omega;         /* rad/s */
    double amplitude;     /* A, m (before gain and fade) */
    double phase;         /* phi in [0, 2 pi) */
    int annulus, sector;  /* its cell */
    int mx, mz;           /* lattice indices: (kx, kz) = 2 pi (mx, mz) / lattice_m
                             (0, 0 without a lattice) */
} ocean_gerstner_wave;

/* The patch side L the near field of a FFT of n x n samples per side is
 * snapped to so that its shortest wave, 2 pi / k_hi, is held: every
 * lattice index stays within +-(n/2 - 1) (the Nyquist row and column stay
 * empty, as in every cascade), L = (n/2 - 1) 2 pi / k_hi.  NaN for n < 8 or
 * k_hi not positive and finite. */
double ocean_gerstner_lattice_for(int n, double k_hi);

struct ocean_params;

/* The near field a sea of cascades carries, as oceand builds it (and
 * `ocean-sim render` draws it): `count` waves from where the finest
 * cascade stops up to 2 pi / min_wavelength, on the lattice layout 1
 * carries (ocean_gerstner_lattice_for(p->n, k_hi)).
 * ocean_gerstner_near_cut first cuts a sea whose ocean.k_max is infinite
 * at its finest grid's Nyquist circle, pi n / L_finest, so the set can
 * start where the FFT stops without a gap or an overlap (no change for a
 * finite k_max or count <= 0).  ocean_gerstner_near_params then fills *gp
 * for the cut sea and returns 1, or returns 0 (gp defaulted) when there is
 * no near field: count <= 0, k_max infinite, or a band under 1 % wide. */
void ocean_gerstner_near_cut(struct ocean_params *p, int count);
int ocean_gerstner_near_params(const struct ocean_params *p, int count, double min_wavelength,
                               ocean_gerstner_params *gp);

/* The near-field cascade of a snapped set (lattice_m > 0): an ocean of one
 * lattice cascade (ocean_create_lattice) of patch lattice_m on an n x n
 * grid holding exactly g's waves, with lambda = the set's effective Q in
 * the default view (no fade, no filter: the one queries use), so its
 * fields equal ocean_gerstner_evaluate's at the grid points (to float
 * rounding).  n, threads and planning come from p; p's sea must be g's.
 * OCEAN_EINVAL (with msg) for a set without a lattice or one the grid
 * cannot hold. */
struct ocean;
ocean_result ocean_gerstner_cascade_create(const ocean_gerstner *g, const struct ocean_params *p,
                                           struct ocean **out, char *msg, size_t msglen);

int ocean_gerstner_count(const ocean_gerstner *g);
/* OCEAN_EINVAL for i out of range. */
ocean_result ocean_gerstner_get_wave(const ocean_gerstner *g, int i, ocean_gerstner_wave *out);
const ocean_gerstner_params *ocean_gerstner_get_params(const ocean_gerstner *g);

/* Variance of the set, sum (g_i A_i)^2 / 2, with g_i the gain of cutoff c
 * (NULL: unfiltered, equal to the spectrum's variance over the band). */
double ocean_gerstner_variance(const ocean_gerstner *g, const ocean_filter_cutoff *c);

/* How one client (or a camera-free query) sees the set. */
typedef struct ocean_gerstner_view {
    double camera_x, camera_z;  /* world position of the fade's centre */
    double fade_r0, fade_r1;    /* full strength within r0, none beyond r1,
                                   smoothstep between; both INFINITY: no fade */
    ocean_filter_cutoff filter; /* per-wave gains; filter.k = INFINITY: none */
} ocean_gerstner_view;

/* No fade, no filter, camera at the origin: the camera-free view point
 * queries use, the same for every client. */
void ocean_gerstner_view_default(ocean_gerstner_view *v);

/* The choppiness Q actually used with view v (the sea's, clamped as in
 * the header comment) and the resulting sum Q k a (<= steepness_max). */
ocean_result ocean_gerstner_effective_q(const ocean_gerstner *g, const ocean_gerstner_view *v,
                                        double *q, double *steepness);

/* The surface at one parameter point x0 = (x, z) (the undisplaced point;
 * the displaced surface point is (x + dx, dy, z + dz)). */
typedef struct ocean_gerstner_point {
    double dx, dy, dz;    /* displacement; dy is the height */
    double nx, ny, nz;    /* unit normal of the displaced surface, ny > 0 */
    double vx, vy, vz;    /* d(displacement)/dt at fixed x0, m/s */
    double jacobian;      /* det of d(x + dx, z + dz)/d(x, z); >= 0 */
    double fade;          /* f(x0) in [0, 1] */
    double slope_x, slope_z;      /* d(dy)/dx, d(dy)/dz at fixed t (fade included) */
    double dxx, dxz, dzx, dzz;    /* d(dx)/dx, d(dx)/dz, d(dz)/dx, d(dz)/dz: the
                                     displacement's Jacobian matrix minus I, which
                                     query inversion (Newton) adds to the FFT's */
    double bq;                    /* minus the quadrature in time of -(dxx + dzz),
                                     as the FFT's foam channel bq (foam.h trails) */
} ocean_gerstner_point;

/* The breaking-index moments of the set under view v at full fade (the
 * foam of ocean_frame_foam_plus): m0, the variance of its dxx + dzz
 * (sum (Q a k)^2 / 2 over the waves the view keeps), and m1, the same
 * sum weighted by each wave's frequency. */
void ocean_gerstner_foam_moments(const ocean_gerstner *g, const ocean_gerstner_view *v, double *m0, double *m1);

/* Evaluates n points (x[i], z[i]) at time t (|t| <= OCEAN_TIME_MAX, else OCEAN_EINVAL) into
 * out[i].  Results depend only on (set, view, t, point): not on n, the
 * order of the points or the thread.  Points where the fade is 0 cost
 * almost nothing.  OCEAN_EINVAL for NULL arrays with n > 0, non-finite t
 * or coordinates, or an invalid view (fade radii must satisfy
 * 0 <= r0 < r1, or both INFINITY; filter.k >= 0 with a valid order). */
ocean_result ocean_gerstner_evaluate(const ocean_gerstner *g, const ocean_gerstner_view *v,
                                     double t, const double *x, const double *z, size_t n,
                                     ocean_gerstner_point *out);

/* A prepared (view, t) for many single-point calls, e.g. a mesh sampler
 * called once per vertex: ocean_gerstner_evaluate redoes the per-wave
 * work (gains, Q, phi - w t: ~1024 pow and reductions) on every call,
 * a frame does it once in ocean_gerstner_frame_set and then costs only the
 * per-point sum.  Results are bit-identical to ocean_gerstner_evaluate.
 * A frame is used by one thread at a time (it caches per-cell phases); it
 * must not outlive its set.  Create: OCEAN_ENOMEM / OCEAN_EINVAL;
 * evaluate before set: OCEAN_ESTATE. */
typedef struct ocean_gerstner_frame ocean_gerstner_frame;
ocean_result ocean_gerstner_frame_create(const ocean_gerstner *g, ocean_gerstner_frame **out);
void ocean_gerstner_frame_destroy(ocean_gerstner_frame *f); /* accepts NULL */
ocean_result ocean_gerstner_frame_set(ocean_gerstner_frame *f, const ocean_gerstner_view *v,
                                      double t);
ocean_result ocean_gerstner_frame_evaluate(ocean_gerstner_frame *f, const double *x,
                                           const double *z, size_t n, ocean_gerstner_point *out);

/* Only the displacement (dx, dy, dz) of n points into out[3 i .. 3 i + 2],
 * the same values ocean_gerstner_frame_evaluate gives (bit for bit), for
 * a mesh vertex that needs no normal, velocity or Jacobian: three sums
 * instead of eleven.  Errors as ocean_gerstner_frame_evaluate. */
ocean_result ocean_gerstner_frame_displacement(ocean_gerstner_frame *f, const double *x,
                                               const double *z, size_t n, double *out);

/* A regular grid of samples (a level-0 tile, say): sample (i, j) (row i
 * along z, column j along x) sits at world (x0 + j spacing, z0 + i spacing)
 * and goes to plane[i * stride + j].  Planes left NULL are not computed. */
#define OCEAN_GERSTNER_GRID_MAX 4096
typedef struct ocean_gerstner_grid {
    double x0, z0;        /* world position of sample (0, 0), |.| <= 1e12 */
    double spacing;       /* m, > 0 and finite */
    int w, h;             /* samples along x and z, 1..OCEAN_GERSTNER_GRID_MAX */
    size_t stride;        /* floats from one row to the next, >= w */
    int accumulate;       /* 1: add to what the planes hold (FFT tiles), 0: store */
    float *height;        /* dy */
    float *dx, *dz;       /* horizontal displacement */
    float *slope_x, *slope_z; /* d(dy)/dx, d(dy)/dz */
    float *dxx, *dzz, *dxz;   /* displacement derivatives as the FFT's foam
                                 channel holds them (dxz: the mean of d(dx)/dz
                                 and d(dz)/dx, equal without a fade) */
} ocean_gerstner_grid;

/* The near field of frame f (its view and t, see ocean_gerstner_frame_set)
 * on grid g.  Same sums as ocean_gerstner_frame_evaluate (agreement to
 * ~1e-12 of sum |a|, float storage aside) at a fraction of the cost: the
 * phase of wave i at sample (i, j) factors into e^{i k.x0 + ...} times a
 * row factor times a column factor, so each sample costs one complex
 * product per wave instead of a sin and a cos.  Points where the fade is
 * 0 are left untouched (accumulate) or zero.  OCEAN_EINVAL for a bad
 * grid, OCEAN_ESTATE before ocean_gerstner_frame_set, OCEAN_ENOMEM. */
ocean_result ocean_gerstner_frame_sample_grid(ocean_gerstner_frame *f,
                                              const ocean_gerstner_grid *g);

#endif
