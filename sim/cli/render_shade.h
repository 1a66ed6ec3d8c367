/*
 * render_shade.h - the browser viewer's shading model in double precision,
 * for `ocean-sim render`'s reference images: its sky (gradient, sun halo
 * and disc, clouds from its tiling noise texture), the sea's colour from a
 * mean slope and the slope moments below the sample (Fresnel, sky
 * reflection, the sun's glitter as a Beckmann lobe after Bruneton, Neyret &
 * Holzschuch 2010, foam, subsurface tint, cloud shadow), haze and the
 * tone curve.  Every constant and formula is the viewer's
 * (clients/web/render.js COMMON and SEA_SHADE_GLSL); where the viewer
 * approximates (its sky cube of 128-texel faces blurred through mips, the
 * mean Fresnel fit), this model computes what the approximation stands
 * for: the sky in each direction, and the reflection averaged over the
 * unresolved slopes by Gauss-Hermite quadrature.
 *
 * Threads: a render_sky is immutable once made; any number of threads may
 * shade with one at once.
 */
#ifndef RENDER_SHADE_H
#define RENDER_SHADE_H

#include "ocean_result.h"

/* The light and sky of one view: the viewer's for a sea whose wind blows
 * toward wind_dir_deg, at sim time t, seen from eye (world, m); sun_deg
 * (azimuth from +x toward +z, elevation) places the sun as the viewer's
 * sun=AZ,EL does; NULL: the viewer's default, low over the downwind side
 * (controls.js sunDefaultDeg: (cos(d + 0.5), 0.32, sin(d + 0.5))
 * normalised, d the wind's direction). */
typedef struct render_sky render_sky;

ocean_result render_sky_create(double wind_dir_deg, double t, const double eye[3], const double *sun_deg,
                               render_sky **out);
void render_sky_destroy(render_sky *s);   /* accepts NULL */

/* Radiance of the sky (upper hemisphere; d.y is taken as |d.y|) along
 * unit direction d, clouds included, as the viewer fills its cube map;
 * footprint_rad is the angle a sample covers (the cloud texture is read
 * at the mip that matches it). */
void render_sky_radiance(const render_sky *s, const double d[3], double footprint_rad, double out[3]);

/* What a ray that leaves the sea sees: sky plus the sun's disc. */
void render_sky_view(const render_sky *s, const double d[3], double footprint_rad, double out[3]);

/* The sea at one surface sample. */
typedef struct render_surface {
    double rel[3];       /* the surface point relative to the eye, m */
    double slope[2];     /* resolved mean slope (d eta/dx, d eta/dz) */
    double mss[3];       /* slope moments below the sample: xx, zz, xz */
    double foam;         /* whitecap coverage 0..1 */
    double crest;        /* height over half the significant wave height */
} render_surface;

/* Radiance of the sea at one sample, seen along unit v from the eye,
 * haze included (before the tone curve). */
void render_sea_radiance(const render_sky *s, const double v[3], const render_surface *p,
                         double footprint_rad, double out[3]);

/* The viewer's tone curve: exposure 0.85, Narkowicz's ACES fit, gamma
 * 2.2; out in [0, 1] per channel. */
void render_tonemap(const double in[3], double out[3]);

#endif
