/*
 * oc_ship.c - the floating box hull of the ship example (see oc_ship.h).
 */
#include "oc_ship.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void setmsg(char *msg, size_t n, const char *fmt, ...)
{
    if (!msg || !n)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, n, fmt, ap);
    va_end(ap);
}

struct oc_ship {
    oc_ship_params p;
    oc_ship_state st;
    size_t n;
    double *bx, *bz;         /* body-frame point offsets (x forward, z starboard) */
    double mass, ip, ir;     /* kg, kg m^2 */
    double ch, cp, cr;       /* damping coefficients */
    double area;             /* per column, m^2 */
};

void oc_ship_params_default(oc_ship_params *p)
{
    memset(p, 0, sizeof *p);
    p->length_m = 20;
    p->beam_m = 8;
    p->draft_m = 1.5;
    p->depth_m = 4;
    p->rho = 1025;
    p->g = 9.81;
    p->zeta_heave = 0.3;
    p->zeta_pitch = 0.3;
    p->zeta_roll = 0.2;
    p->nx = 8;
    p->nz = 8;
}

ocean_result oc_ship_params_validate(const oc_ship_params *p, char *msg, size_t msglen)
{
    if (!p)
        return OCEAN_EINVAL;
    struct {
        const char *name;
        double v, lo, hi;
    } f[] = {
        {"length_m", p->length_m, 0.1, 1e4}, {"beam_m", p->beam_m, 0.1, 1e4},
        {"draft_m", p->draft_m, 0.01, 1e3},  {"depth_m", p->depth_m, 0.02, 1e3},
        {"rho", p->rho, 1, 1e5},             {"g", p->g, 0.01, 100},
        {"zeta_heave", p->zeta_heave, 0, 2}, {"zeta_pitch", p->zeta_pitch, 0, 2},
        {"zeta_roll", p->zeta_roll, 0, 2},   {"x0", p->x0, -1e9, 1e9},
        {"z0", p->z0, -1e9, 1e9},            {"heading_deg", p->heading_deg, -3600, 3600},
        {"speed", p->speed, -100, 100},
    };
    for (size_t i = 0; i < sizeof f / sizeof f[0]; i++)
        if (!(f[i].v >= f[i].lo && f[i].v <= f[i].hi)) {
            setmsg(msg, msglen, "ship %s = %g outside [%g, %g]", f[i].name, f[i].v, f[i].lo, f[i].hi);
            return OCEAN_EINVAL;
        }
    if (p->draft_m >= p->depth_m) {
        setmsg(msg, msglen, "ship draft_m %g must be below depth_m %g", p->draft_m, p->depth_m);
        return OCEAN_EINVAL;
    }
    if (p->nx < 1 || p->nx > 64 || p->nz < 1 || p->nz > 64 || p->nx * p->nz > OC_SHIP_MAX_POINTS) {
        setmsg(msg, msglen, "ship point grid %d x %d outside 1..64 per side", p->nx, p->nz);
        return OCEAN_EINVAL;
    }
    return OCEAN_OK;
}

ocean_result oc_ship_create(const oc_ship_params *p, double t0, oc_ship **out, char *msg, size_t msglen)
{
    if (!out)
        return OCEAN_EINVAL;
    *out = NULL;
    ocean_result r = oc_ship_params_validate(p, msg, msglen);
    if (r != OCEAN_OK)
        return r;
    if (!isfinite(t0)) {
        setmsg(msg, msglen, "start time is not finite");
        return OCEAN_EINVAL;
    }
    oc_ship *s = calloc(1, sizeof *s);
    if (!s)
        return OCEAN_ENOMEM;
    s->p = *p;
    s->n = (size_t)p->nx * (size_t)p->nz;
    s->bx = malloc(s->n * sizeof *s->bx);
    s->bz = malloc(s->n * sizeof *s->bz);
    if (!s->bx || !s->bz) {
        oc_ship_destroy(s);
        return OCEAN_ENOMEM;
    }
    for (int i = 0; i < p->nx; i++)
        for (int k = 0; k < p->nz; k++) {
            size_t j = (size_t)i * (size_t)p->nz + (size_t)k;
            s->bx[j] = p->length_m * ((i + 0.5) / p->nx - 0.5);
            s->bz[j] = p->beam_m * ((k + 0.5) / p->nz - 0.5);
        }
    double L = p->length_m, B = p->beam_m, D = p->depth_m;
    s->area = L * B / (double)s->n;
    s->mass = p->rho * L * B * p->draft_m;
    s->ip = s->mass * (L * L + D * D) / 12.0;
    s->ir = s->mass * (B * B + D * D) / 12.0;
    /* restoring stiffnesses of the discretised waterplane, for critical damping */
    double kh = p->rho * p->g * s->area * (double)s->n, kp = 0, kr = 0;
    for (size_t j = 0; j < s->n; j++) {
        kp += p->rho * p->g * s->area * s->bx[j] * s->bx[j];
        kr += p->rho * p->g * s->area * s->bz[j] * s->bz[j];
    }
    s->ch = 2 * p->zeta_heave * sqrt(kh * s->mass);
    s->cp = 2 * p->zeta_pitch * sqrt(kp * s->ip);
    s->cr = 2 * p->zeta_roll * sqrt(kr * s->ir);
    s->st.t = t0;
    s->st.x = p->x0;
    s->st.z = p->z0;
    s->st.immersed = 1;
    *out = s;
    return OCEAN_OK;
}

void oc_ship_destroy(oc_ship *s)
{
    if (!s)
        return;
    free(s->bx);
    free(s->bz);
    free(s);
}

size_t oc_ship_point_count(const oc_ship *s) { return s ? s->n : 0; }

void oc_ship_points(const oc_ship *s, double *xz)
{
    double h = s->p.heading_deg * M_PI / 180.0;
    double ch = cos(h), sh = sin(h);
    double cp = cos(s->st.pitch), cr = cos(s->st.roll);
    for (size_t j = 0; j < s->n; j++) {
        double bx = s->bx[j] * cp, bz = s->bz[j] * cr;
        /* heading rotates body x (forward) toward +z, body z (starboard) toward -x */
        xz[2 * j] = s->st.x + ch * bx - sh * bz;
        xz[2 * j + 1] = s->st.z + sh * bx + ch * bz;
    }
}

ocean_result oc_ship_step(oc_ship *s, const double *heights, double dt)
{
    if (!s || !heights || !(dt > 0 && dt <= 0.5))
        return OCEAN_EINVAL;
    for (size_t j = 0; j < s->n; j++)
        if (!isfinite(heights[j]))
            return OCEAN_EINVAL;
    const oc_ship_params *p = &s->p;
    oc_ship_state st = s->st;
    double sp = sin(st.pitch), cp = cos(st.pitch), sr = sin(st.roll), cr = cos(st.roll);
    double F = 0, Mp = 0, Mr = 0, vol = 0;
    for (size_t j = 0; j < s->n; j++) {
        double ybot = st.heave - p->draft_m + s->bx[j] * sp + s->bz[j] * sr;
        double d = heights[j] - ybot;
        if (d < 0)
            d = 0;
        if (d > p->depth_m)
            d = p->depth_m;
        double f = p->rho * p->g * s->area * d;
        F += f;
        Mp += f * s->bx[j] * cp;
        Mr += f * s->bz[j] * cr;
        vol += s->area * d;
    }
    double ah = (F - s->mass * p->g - s->ch * st.heave_rate) / s->mass;
    double ap = (Mp - s->cp * st.pitch_rate) / s->ip;
    double ar = (Mr - s->cr * st.roll_rate) / s->ir;
    st.heave_rate += ah * dt;
    st.pitch_rate += ap * dt;
    st.roll_rate += ar * dt;
    st.heave += st.heave_rate * dt;
    st.pitch += st.pitch_rate * dt;
    st.roll += st.roll_rate * dt;
    double h = p->heading_deg * M_PI / 180.0;
    st.x += p->speed * cos(h) * dt;
    st.z += p->speed * sin(h) * dt;
    st.t += dt;
    st.immersed = vol / (p->length_m * p->beam_m * p->draft_m);
    if (!isfinite(st.heave) || !isfinite(st.pitch) || !isfinite(st.roll) || !isfinite(st.heave_rate) ||
        !isfinite(st.pitch_rate) || !isfinite(st.roll_rate) || fabs(st.heave) > 100 ||
        fabs(st.pitch) > M_PI / 2 || fabs(st.roll) > M_PI / 2)
        return OCEAN_EDIVERGED;
    s->st = st;
    return OCEAN_OK;
}

void oc_ship_get_state(const oc_ship *s, oc_ship_state *out)
{
    if (s && out)
        *out = s->st;
}

ocean_result oc_ship_power_spectrum(const double *x, size_t n, double *power)
{
    if (!x || !power || n < 8)
        return OCEAN_EINVAL;
    double mean = 0;
    for (size_t i = 0; i < n; i++)
        mean += x[i];
    mean /= (double)n;
    size_t nf = n / 2;
    power[0] = 0;
    /* direct DFT: records are a few thousand samples, and it keeps the
     * library free of an FFT dependency for one spectrum */
    for (size_t k = 1; k <= nf; k++) {
        double re = 0, im = 0;
        for (size_t i = 0; i < n; i++) {
            double w = 0.5 - 0.5 * cos(2 * M_PI * (double)i / (double)(n - 1));
            double v = (x[i] - mean) * w;
            double a = 2 * M_PI * (double)((k * i) % n) / (double)n;
            re += v * cos(a);
            im -= v * sin(a);
        }
        power[k] = re * re + im * im;
    }
    return OCEAN_OK;
}

double oc_ship_spectrum_peak(const double *power, size_t n, double dt, double min_period, double max_period)
{
    if (!power || n < 8 || !(dt > 0))
        return 0;
    size_t nf = n / 2;
    double best = -1, best_period = 0;
    for (size_t k = 1; k <= nf; k++) {
        double period = (double)n * dt / (double)k;
        if (period < min_period || period > max_period)
            continue;
        double sm = power[k] + (k > 1 ? power[k - 1] : 0) + (k < nf ? power[k + 1] : 0);
        if (sm > best) {
            best = sm;
            best_period = period;
        }
    }
    return best_period;
}

double oc_ship_peak_period(const double *x, size_t n, double dt, double min_period, double max_period)
{
    if (!x || n < 8 || !(dt > 0))
        return 0;
    double *pw = malloc((n / 2 + 1) * sizeof *pw);
    if (!pw)
        return 0;
    double r = 0;
    if (oc_ship_power_spectrum(x, n, pw) == OCEAN_OK)
        r = oc_ship_spectrum_peak(pw, n, dt, min_period, max_period);
    free(pw);
    return r;
}

void oc_ship_trace_free(oc_ship_trace *tr)
{
    if (!tr)
        return;
    free(tr->t);
    free(tr->heave);
    free(tr->pitch);
    free(tr->roll);
    free(tr->eta);
    memset(tr, 0, sizeof *tr);
}
