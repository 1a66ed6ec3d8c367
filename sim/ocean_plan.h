/*
 * ocean_plan.h - the scene plan: checks that a sea state, its grid and the
 * way it is served make physical and numerical sense, run at load
 * (config and scene files, --set, SEA_STATE set, ocean_create).
 *
 * Each check refuses or warns, with the numbers:
 *
 *   peak      REFUSE when the dominant wavelength 2 pi / k_p exceeds the
 *             largest patch: the peak is below the grid's first wave
 *             number and the grid holds a small part of the sea (wind
 *             100 m/s on a 1 km patch: Hs 33 m of the analytic 224 m).
 *             WARN when the built grid holds less than 90 % of the
 *             analytic Hs for another reason (peak poorly sampled).
 *   breaking  REFUSE when Hs exceeds the depth-limited breaking height
 *             H_b = min(0.78 d, 0.142 L_p tanh(k_p d)): McCowan (1894)
 *             H/d = 0.78 for the solitary wave, Miche (1944) for periodic
 *             waves (0.142 L deep, 0.89 d shallow), L_p the peak wavelength
 *             at depth d.  TMA at 1 cm depth gives 0.6 m waves: refused.
 *             WARN when the largest of ~1000 waves, 1.86 Hs (Longuet-
 *             Higgins 1952, Rayleigh heights), exceeds H_b: those waves
 *             would break and a linear sea does not break them.
 *   near      WARN (the daemon) when the near-field band is empty (it is
 *             then silently not built).  A spacing too coarse for the near
 *             field's longest wave is one client's choice, not the scene's:
 *             the daemon says so when such a client subscribes.
 * Not here: e_total, the energy missing from geometry and shading together
 * (seed 000's 5 % guard), depends on each client's camera, cutoffs and
 * whether it takes normals, not on the scene; every layout-1 frame states
 * its own (PROTOCOL.md, the cascade block's e_total).
 *
 * Refusals are part of ocean_params_validate, so every entry point refuses
 * the same way; warnings are collected by ocean_plan_params and
 * ocean_plan_ocean and printed by the daemon (stderr log) and ocean-sim.
 */
#ifndef OCEAN_PLAN_H
#define OCEAN_PLAN_H

#include <stdio.h>

#include "ocean.h"

/* Published constants of the checks (see the file comment). */
#define OCEAN_PLAN_MCCOWAN 0.78    /* H_b / d, McCowan 1894 */
#define OCEAN_PLAN_MICHE 0.142     /* H_b / L, Miche 1944 */
#define OCEAN_PLAN_HMAX_HS 1.86    /* H_max / Hs for ~1000 Rayleigh waves */
#define OCEAN_PLAN_GRID_HS_MIN 0.9 /* grid Hs / analytic Hs below this warns */

typedef enum { OCEAN_PLAN_WARN = 1, OCEAN_PLAN_REFUSE = 2 } ocean_plan_level;

#define OCEAN_PLAN_MAX 8
typedef struct ocean_plan_item {
    ocean_plan_level level;
    const char *check;      /* "peak", "breaking", "near" ... (the checks above) */
    char text[320];         /* what and the numbers */
} ocean_plan_item;

typedef struct ocean_plan {
    int count;
    ocean_plan_item item[OCEAN_PLAN_MAX];
} ocean_plan;

/* Empties plan. */
void ocean_plan_init(ocean_plan *plan);

/* Number of items of plan at `level`. */
int ocean_plan_count(const ocean_plan *plan, ocean_plan_level level);

/* The checks on parameters alone (peak vs patch, breaking), appended to
 * plan.  p must have passed the field checks of ocean_params_validate
 * (which calls this and refuses on the first REFUSE item). */
void ocean_plan_params(const ocean_params *p, ocean_plan *plan);

/* The checks on the sea state alone (breaking), appended to plan: part of
 * ocean_plan_params, and of ocean_gerstner_params_validate, so a near field
 * on its own refuses the sea the FFT ocean refuses. */
void ocean_plan_sea(const ocean_sea_state *s, ocean_plan *plan);

/* How a scene is served, for the checks that depend on it. */
typedef struct ocean_plan_serving {
    int near_field;          /* 1: the scene asks for the Gerstner near field */
    double near_k_lo, near_k_hi; /* its band, rad/m (k_lo = the FFT's k_max) */
} ocean_plan_serving;

/* The checks on a built ocean (grid Hs vs analytic) and, if sv != NULL,
 * on how it is served (a near field with an empty band), appended to plan.
 * Whether a client's sample spacing carries the near field is the
 * server's to say when that client subscribes. */
void ocean_plan_ocean(const ocean *o, const ocean_plan_serving *sv, ocean_plan *plan);

/* Writes each item as "<prefix>: warning|refused (check): text\n" to f. */
void ocean_plan_print(const ocean_plan *plan, FILE *f, const char *prefix);

#endif
