/*
 * ocean_plan.c - the scene plan checks (see ocean_plan.h for what each
 * check does, refuse or warn, and its published source).
 */
#include "ocean_plan.h"

#include <math.h>
#include <stdarg.h>
#include <string.h>

#include "spectrum.h"

void ocean_plan_init(ocean_plan *plan)
{
    memset(plan, 0, sizeof *plan);
}

int ocean_plan_count(const ocean_plan *plan, ocean_plan_level level)
{
    int n = 0;
    for (int i = 0; i < plan->count; i++)
        n += plan->item[i].level == level;
    return n;
}

__attribute__((format(printf, 4, 5)))
static void add(ocean_plan *plan, ocean_plan_level level, const char *check, const char *fmt, ...)
{
    if (plan->count >= OCEAN_PLAN_MAX)
        return;
    ocean_plan_item *it = &plan->item[plan->count++];
    it->level = level;
    it->check = check;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(it->text, sizeof it->text, fmt, ap);
    va_end(ap);
}

/* Depth-limited breaking height at depth d for sea s: min(McCowan, Miche),
 * *which naming the one that binds. */
static double breaking_height(const ocean_sea_state *s, double d, const char **which)
{
    double wp = ocean_spectrum_peak(s);
    double kp = ocean_wavenumber(wp, d), lp = 2.0 * M_PI / kp;
    double hb_mc = OCEAN_PLAN_MCCOWAN * d, hb_mi = OCEAN_PLAN_MICHE * lp * tanh(kp * d);
    if (which) *which = hb_mc <= hb_mi ? "McCowan 1894: 0.78 d" : "Miche 1944: 0.142 L tanh(k d)";
    return fmin(hb_mc, hb_mi);
}

/* The least depth at which s's Hs is within its breaking height.  Hs moves
 * with the depth too (TMA's depth factor; the peak wavelength everywhere):
 * Hs / 0.78 at the refused depth can itself be refused for a TMA sea
 * (0.01 m would suggest 0.0803 m, that 0.227 m, ...), so the boundary is
 * bisected.
 * 0 when even the deepest accepted water (12000 m) breaks it. */
static double least_depth(const ocean_sea_state *s)
{
    ocean_sea_state t = *s;
    double lo = s->depth_m, hi = 12000.0;
    t.depth_m = hi;
    if (ocean_spectrum_hs(&t) > breaking_height(&t, hi, NULL))
        return 0.0;
    for (int i = 0; i < 60 && hi - lo > 1e-4 * hi; i++) {
        t.depth_m = 0.5 * (lo + hi);
        if (ocean_spectrum_hs(&t) > breaking_height(&t, t.depth_m, NULL))
            lo = t.depth_m;
        else
            hi = t.depth_m;
    }
    return hi;
}

void ocean_plan_params(const ocean_params *p, ocean_plan *plan)
{
    const ocean_sea_state *s = &p->sea;
    double wp = ocean_spectrum_peak(s);
    if (!(wp > 0.0))
        return; /* no wind, no sea: nothing to check */
    double kp = ocean_wavenumber(wp, s->depth_m), lp = 2.0 * M_PI / kp;
    if (lp > p->patch_m)
        add(plan, OCEAN_PLAN_REFUSE, "peak",
            "the dominant wavelength %.4g m (peak period %.3g s) exceeds the %.4g m patch: the "
            "grid starts above the peak and would hold a small part of the sea's Hs %.3g m; "
            "use ocean.patch >= %.4g m or less wind",
            lp, 2.0 * M_PI / wp, p->patch_m, ocean_spectrum_hs(s), lp);
    ocean_plan_sea(s, plan);
}

void ocean_plan_sea(const ocean_sea_state *s, ocean_plan *plan)
{
    double wp = ocean_spectrum_peak(s);
    if (!(wp > 0.0))
        return; /* no wind, no sea: nothing to check */
    double d = s->depth_m;
    double kp = ocean_wavenumber(wp, d), lp = 2.0 * M_PI / kp;
    double hs = ocean_spectrum_hs(s);
    const char *which;
    double hb = breaking_height(s, d, &which);
    if (hs > hb) {
        double dmin = least_depth(s);
        char way[96];
        if (dmin > 0.0) {
            /* rounded up to the 3 digits printed: the depth typed back is
             * accepted */
            double q = pow(10.0, floor(log10(dmin)) - 2.0);
            snprintf(way, sizeof way, "use sea.depth >= %.3g m or less wind or fetch", ceil(dmin / q) * q);
        } else {
            snprintf(way, sizeof way, "no depth holds it: use less wind or fetch");
        }
        add(plan, OCEAN_PLAN_REFUSE, "breaking",
            "Hs %.3g m exceeds the depth-limited breaking height %.3g m at depth %.4g m (%s, "
            "peak wavelength %.4g m): a sea of such waves cannot exist; %s",
            hs, hb, d, which, lp, way);
    }
    else if (OCEAN_PLAN_HMAX_HS * hs > hb)
        add(plan, OCEAN_PLAN_WARN, "breaking",
            "the largest waves (1.86 Hs = %.3g m, 1000 waves of a Rayleigh sea) exceed the "
            "breaking height %.3g m at depth %.4g m (%s): they would break, and this linear sea "
            "does not break them",
            OCEAN_PLAN_HMAX_HS * hs, hb, d, which);
}

void ocean_plan_ocean(const ocean *o, const ocean_plan_serving *sv, ocean_plan *plan)
{
    const ocean_params *p = ocean_get_params(o);
    ocean_spectrum_stats ss;
    ocean_get_spectrum_stats(o, &ss);
    double hs = ocean_spectrum_hs(&p->sea);
    /* The grid's Hs leaves out what lies beyond k_max by design (the near
     * field or nothing): compare with the analytic Hs below it. */
    /* The grid spans 2 pi / patch .. the finest cascade's Nyquist. */
    double fine = p->patch_m / pow(p->cascade_ratio, p->cascades - 1);
    double lmin = 2.0 * fine / p->n;
    /* ocean.k_max may stop the grid sooner than its Nyquist rate */
    int by_kmax = isfinite(p->k_max) && 2.0 * M_PI / p->k_max > 1.0001 * lmin;
    char down[160];
    if (by_kmax)
        snprintf(down, sizeof down, "%.3g m (ocean.k_max %.3g rad/m)", 2.0 * M_PI / p->k_max, p->k_max);
    else
        snprintf(down, sizeof down, "%.3g m (finest patch %.4g m / n %d x 2)", lmin, fine, p->n);
    if (by_kmax) lmin = 2.0 * M_PI / p->k_max;
    if (hs > 0.0 && ss.hs < OCEAN_PLAN_GRID_HS_MIN * hs)
        add(plan, OCEAN_PLAN_WARN, "peak",
            "the grid holds Hs %.3g m of the sea's analytic %.3g m (%.0f %%): its waves run "
            "from %.4g m (the patch) down to %s, the peak is %.4g m%s",
            ss.hs, hs, 100.0 * ss.hs / hs, p->patch_m, down, ss.lambda_dominant,
            ss.lambda_dominant < 4.0 * lmin
                ? (by_kmax ? ", too short for the grid: raise ocean.k_max"
                           : ", too short for the grid: raise ocean.n or add cascades")
                : ", sampled by too few modes: a larger patch");
    if (sv && sv->near_field) {
        double klo = sv->near_k_lo, khi = sv->near_k_hi;
        if (!(isfinite(klo) && khi > 1.01 * klo))
            add(plan, OCEAN_PLAN_WARN, "near",
                "the near field is asked for but its band is empty (%.3g to %.3g rad/m, i.e. "
                "%.3g m to %.3g m): the FFT already reaches its shortest wave, no near field "
                "is built",
                klo, khi, 2.0 * M_PI / khi, 2.0 * M_PI / klo);
    }
}

void ocean_plan_print(const ocean_plan *plan, FILE *f, const char *prefix)
{
    for (int i = 0; i < plan->count; i++)
        fprintf(f, "%s: %s (%s): %s\n", prefix,
                plan->item[i].level == OCEAN_PLAN_REFUSE ? "refused" : "warning",
                plan->item[i].check, plan->item[i].text);
}
