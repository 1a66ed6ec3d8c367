/*
 * rotor_wash.c - the water under a rotorcraft's downwash (see rotor_wash.h).
 *
 * The ring integral C(rho, s) is tabulated where the stationary-phase form
 * does not hold (near the footprint, rho <= TAB_RHO, and early, s <=
 * TAB_S; later there the integrand's Gaussian has cut every wave that
 * could still be there): Simpson's rule in q = sqrt(k), where the
 * integrand is q^3 exp(-q^4 / 4) cos(q s) J0(q^2 rho), with the Bessel and
 * cosine factors computed once a row and a column.
 *
 * OOM policy: rotor_wash_create and rotor_wash_add fail with OCEAN_ENOMEM,
 * nothing kept.
 */
#include "rotor_wash.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define G 9.81
#define TAB_RHO 10.0
#define TAB_S 60.0
#define TAB_DRHO 0.05
#define TAB_DS 0.1
#define TAB_NR 201             /* TAB_RHO / TAB_DRHO + 1 */
#define TAB_NS 601             /* TAB_S / TAB_DS + 1 */
#define QUAD_Q 3.4             /* exp(-q^4 / 4) < 1e-14 beyond */
#define QUAD_N 680             /* even: Simpson panels of 0.005 */
#define PHASE_K_MAX 14.0       /* beyond, the stationary wave's amplitude is below 1e-21 */

struct rotor_wash {
    float *tab;                /* C at rho = i * TAB_DRHO, s = j * TAB_DS: tab[i * TAB_NS + j] */
};

static double smooth01(double x) { return x <= 0 ? 0 : x >= 1 ? 1 : x * x * (3 - 2 * x); }

void rotor_wash_footprint(double diameter, double height, double speed, double *head, double *radius)
{
    double thrust = ROTOR_DISK_LOADING * M_PI * diameter * diameter / 4;
    double r0 = diameter / (2 * M_SQRT2);                        /* the contracted slipstream */
    double c2 = r0 * r0 + height * height / 114.0;                /* Beltaos & Rajaratnam's spread */
    double vh = sqrt(ROTOR_DISK_LOADING / (2 * ROTOR_RHO_AIR)); /* the hover's induced velocity */
    double reach = (1 - smooth01((height - 3 * diameter) / diameter)) * (1 - smooth01((speed - vh) / vh));
    *radius = sqrt(c2);
    *head = reach * thrust / (ROTOR_RHO_WATER * G * M_PI * c2);
}

/* Simpson weights over [0, QUAD_Q] in n panels (n even), node i at i * h. */
static double simpson_w(int i, int n) { return i == 0 || i == n ? 1.0 : (i & 1) ? 4.0 : 2.0; }

ocean_result rotor_wash_create(rotor_wash **out)
{
    *out = NULL;
    rotor_wash *w = calloc(1, sizeof *w);
    /* the Bessel factor with the weights, a row per rho; the cosines of a column */
    double *jr = malloc(sizeof(double) * (QUAD_N + 1) * (TAB_NR + 1)), *cs = jr ? jr + (size_t)(QUAD_N + 1) * TAB_NR : NULL;
    if (w) w->tab = malloc(sizeof(float) * TAB_NR * TAB_NS);
    if (!w || !w->tab || !jr) {
        free(jr);
        rotor_wash_destroy(w);
        return OCEAN_ENOMEM;
    }
    const double h = QUAD_Q / QUAD_N;
    for (int i = 0; i < TAB_NR; i++)
        for (int k = 0; k <= QUAD_N; k++) {
            double q = k * h;
            jr[(size_t)i * (QUAD_N + 1) + k] =
                simpson_w(k, QUAD_N) * h / 3 * q * q * q * exp(-q * q * q * q / 4) * j0(q * q * i * TAB_DRHO);
        }
    for (int j = 0; j < TAB_NS; j++) {
        for (int k = 0; k <= QUAD_N; k++) cs[k] = cos(k * h * j * TAB_DS);
        for (int i = 0; i < TAB_NR; i++) {
            const double *row = jr + (size_t)i * (QUAD_N + 1);
            double sum = 0;
            for (int k = 0; k <= QUAD_N; k++) sum += row[k] * cs[k];
            w->tab[i * TAB_NS + j] = (float)sum;
        }
    }
    free(jr);
    *out = w;
    return OCEAN_OK;
}

void rotor_wash_destroy(rotor_wash *w)
{
    if (!w) return;
    free(w->tab);
    free(w);
}

/* The table's bilinear reading and its gradient. */
static double ring_table(const rotor_wash *w, double rho, double s, double *d_rho, double *d_s)
{
    double fr = rho / TAB_DRHO, fs = s / TAB_DS;
    int i = (int)fr, j = (int)fs;
    if (i > TAB_NR - 2) i = TAB_NR - 2;
    if (j > TAB_NS - 2) j = TAB_NS - 2;
    double u = fr - i, v = fs - j;
    const float *a = &w->tab[i * TAB_NS + j], *b = a + TAB_NS;
    double c00 = a[0], c01 = a[1], c10 = b[0], c11 = b[1];
    *d_rho = ((1 - v) * (c10 - c00) + v * (c11 - c01)) / TAB_DRHO;
    *d_s = ((1 - u) * (c01 - c00) + u * (c11 - c10)) / TAB_DS;
    return (1 - u) * ((1 - v) * c00 + v * c01) + u * ((1 - v) * c10 + v * c11);
}

/* The stationary-phase form: the wave of wavenumber k* = s^2 / (4 rho^2)
 * (the one whose group has come rho in s), amplitude sqrt(2) / rho k*
 * Phi(k*), Phi(k) = exp(-k^2 / 4) / 2, phase s^2 / (4 rho); the
 * derivatives of the phase alone (the amplitude's are smaller by the
 * phase's size). */
static double ring_far(double rho, double s, double *d_rho, double *d_s)
{
    double k = s * s / (4 * rho * rho);
    *d_rho = *d_s = 0;
    if (k > PHASE_K_MAX) return 0;
    double amp = M_SQRT2 / rho * k * 0.5 * exp(-k * k / 4), ph = s * s / (4 * rho);
    double sn = sin(ph);
    *d_rho = amp * sn * k;
    *d_s = -amp * sn * s / (2 * rho);
    return amp * cos(ph);
}

double rotor_wash_ring(const rotor_wash *w, double rho, double s, double *d_rho, double *d_s)
{
    double dr, ds, c;
    if (rho <= TAB_RHO) c = s <= TAB_S ? ring_table(w, rho, s, &dr, &ds) : (dr = ds = 0, 0);
    else c = ring_far(rho, s, &dr, &ds);
    if (d_rho) *d_rho = dr;
    if (d_s) *d_s = ds;
    return c;
}

double rotor_wash_ring_exact(double rho, double s)
{
    /* panels short enough for the fastest phase here, q s + q^2 rho */
    double fast = s + 2 * QUAD_Q * rho;
    int n = 2 * (int)ceil(QUAD_Q * fast / (2 * M_PI) * 16 / 2) + 400;
    double h = QUAD_Q / n, sum = 0;
    for (int k = 0; k <= n; k++) {
        double q = k * h;
        sum += simpson_w(k, n) * q * q * q * exp(-q * q * q * q / 4) * cos(q * s) * j0(q * q * rho);
    }
    return sum * h / 3;
}

/* ---- the rotorcraft of a table on the forcing's lattice ---------------- */

typedef struct foot {
    uint32_t id;
    double x, z, head, c;
    double vx, vz;             /* the rotor's velocity (the dent's) */
} foot;

/* The footprints of the rotorcraft in the sea at tk (increasing id) into
 * out; returns how many. */
static int lattice_feet(const ocean_entities *e, double tk, ocean_entity_desc *d, ocean_entity_state *s, int max,
                        foot *out)
{
    int n = ocean_entities_at(e, tk, d, s, max), m = 0;
    for (int i = 0; i < n; i++) {
        if (d[i].kind != OCEAN_ENTITY_ROTORCRAFT) continue;
        foot f = {.id = d[i].id, .x = s[i].x, .z = s[i].z};
        rotor_wash_footprint(d[i].length_m, s[i].altitude_m, s[i].speed, &f.head, &f.c);
        if (f.head > 0) out[m++] = f;
    }
    return m;
}

/* The rotorcraft in the sea at t (increasing id), their positions (head
 * and radius unused). */
static int rotors_now(const ocean_entities *e, double t, ocean_entity_desc *d, ocean_entity_state *s, int max,
                      foot *out)
{
    int n = ocean_entities_at(e, t, d, s, max), m = 0;
    for (int i = 0; i < n; i++)
        if (d[i].kind == OCEAN_ENTITY_ROTORCRAFT)
            out[m++] = (foot){.id = d[i].id, .x = s[i].x, .z = s[i].z, .vx = s[i].vx, .vz = s[i].vz};
    return m;
}

/* Whether b's pressure differs from a's enough to send rings: by
 * ROTOR_STEP_MIN_M of head, or the same measure of the footprint's spread. */
static int foot_changed(const foot *a, const foot *b)
{
    return fabs(a->head - b->head) + b->head * fabs(a->c - b->c) / b->c >= ROTOR_STEP_MIN_M;
}

/* Adds sign * weight * head * C of footprint f, tau seconds after its step,
 * to the n points (and the bound). */
static void add_ring(const rotor_wash *w, const foot *f, double sign, double weight, double tau, const double *xz,
                     size_t n, wake_sample *out)
{
    double a = sign * weight * f->head, rate = sqrt(G / f->c), s = tau * rate;
    for (size_t q = 0; q < n; q++) {
        double dx = xz[2 * q] - f->x, dz = xz[2 * q + 1] - f->z, r = sqrt(dx * dx + dz * dz), dr, ds;
        double c = rotor_wash_ring(w, r / f->c, s, &dr, &ds);
        out[q].height += a * c;
        out[q].dhdt += a * ds * rate;
        out[q].error += weight * f->head * ROTOR_RING_ERROR;
        if (r > 1e-9) {
            out[q].dhdx += a * dr / f->c * dx / r;
            out[q].dhdz += a * dr / f->c * dz / r;
        }
    }
}

/* The dent of footprint f (the newest lattice state) at the n points,
 * moving at f's velocity. */
static void add_dent(const foot *f, const double *xz, size_t n, wake_sample *out)
{
    for (size_t q = 0; q < n; q++) {
        double dx = (xz[2 * q] - f->x) / f->c, dz = (xz[2 * q + 1] - f->z) / f->c;
        double e = f->head * exp(-(dx * dx + dz * dz)), sx = 2 * dx / f->c * e, sz = 2 * dz / f->c * e;
        out[q].height -= e;
        out[q].dhdx += sx;
        out[q].dhdz += sz;
        out[q].dhdt -= f->vx * sx + f->vz * sz;   /* carried with the rotor */
    }
}

/* The rings of the step at lattice time tk: footprints a (before) to b
 * (after), both in increasing id; a pressure that changed sends its rings
 * from where the rotor is at tk. */
static void add_step(const rotor_wash *w, const foot *a, int na, const foot *b, int nb, double t, double tk,
                     const double *xz, size_t n, wake_sample *out)
{
    double tau = t - tk, weight = fmin(1.0, (ROTOR_HISTORY_S - tau) / ROTOR_FADE_S);
    if (weight <= 0) return;
    int i = 0, j = 0;
    while (i < na || j < nb) {
        if (i < na && j < nb && a[i].id == b[j].id) {
            if (foot_changed(&a[i], &b[j])) {
                foot was = a[i];
                was.x = b[j].x, was.z = b[j].z;
                add_ring(w, &b[j], 1, weight, tau, xz, n, out);
                add_ring(w, &was, -1, weight, tau, xz, n, out);
            }
            i++, j++;
        } else if (j >= nb || (i < na && a[i].id < b[j].id)) {
            add_ring(w, &a[i++], -1, weight, tau, xz, n, out);   /* gone, or out of reach */
        } else {
            add_ring(w, &b[j++], 1, weight, tau, xz, n, out);    /* come */
        }
    }
}

/* The dents of the newest lattice footprints f (n of them), each where
 * its rotor is at t (now, nf of them, increasing id; where it was at the
 * lattice time if it has left since). */
static void add_dents(const foot *f, int n, const foot *now, int nf, const double *xz, size_t np, wake_sample *out)
{
    for (int i = 0, j = 0; i < n; i++) {
        foot d = f[i];
        while (j < nf && now[j].id < d.id) j++;
        d.vx = d.vz = 0;
        if (j < nf && now[j].id == d.id) d.x = now[j].x, d.z = now[j].z, d.vx = now[j].vx, d.vz = now[j].vz;
        add_dent(&d, xz, np, out);
    }
}

ocean_result rotor_wash_add(const rotor_wash *w, const ocean_entities *e, double t, const double *xz, size_t n,
                            wake_sample *out)
{
    if (!isfinite(t)) return OCEAN_EINVAL;
    for (size_t q = 0; q < n; q++)
        if (!isfinite(xz[2 * q]) || !isfinite(xz[2 * q + 1])) return OCEAN_EINVAL;
    if (!ocean_entities_count_kind(e, OCEAN_ENTITY_ROTORCRAFT)) return OCEAN_OK;
    int max = ocean_entities_kept(e), steps = (int)ceil(ROTOR_HISTORY_S / ROTOR_STEP_S);
    int64_t last = (int64_t)floor(t / ROTOR_STEP_S);
    ocean_entity_desc *d = malloc(sizeof *d * (size_t)max);
    ocean_entity_state *s = malloc(sizeof *s * (size_t)max);
    foot *feet = malloc(sizeof *feet * (size_t)max * 3);
    if (!d || !s || !feet) {
        free(d);
        free(s);
        free(feet);
        return OCEAN_ENOMEM;
    }
    foot *prev = feet, *cur = feet + max;
    int np = lattice_feet(e, (double)(last - steps) * ROTOR_STEP_S, d, s, max, prev);
    for (int64_t k = last - steps + 1; k <= last; k++) {
        double tk = (double)k * ROTOR_STEP_S;
        int nc = lattice_feet(e, tk, d, s, max, cur);
        add_step(w, prev, np, cur, nc, t, tk, xz, n, out);
        foot *sw = prev;
        prev = cur, cur = sw, np = nc;
    }
    int nn = rotors_now(e, t, d, s, max, feet + 2 * max);
    add_dents(prev, np, feet + 2 * max, nn, xz, n, out);
    free(d);
    free(s);
    free(feet);
    return OCEAN_OK;
}
