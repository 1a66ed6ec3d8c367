/*
 * render.h - the reference render of the exact sea: what `ocean-sim render`
 * draws and the viewer's screenshots are judged against.
 *
 * The sea of one instant is every wave of every FFT cascade (the fields of
 * a full-resolution, unfiltered evaluation: the exact sums at the grid
 * nodes, read between them by the library's accurate reading, within about
 * a millimetre of the direct sum) plus the Gerstner near field summed
 * exactly, with the choppy displacement inverted at each point (query.h).
 * Each ray is cast against that surface from the camera and shaded with
 * the viewer's model (render_shade.h).  What a sample cannot resolve is
 * handed to shading as Bruneton, Neyret & Holzschuch's (2010) geometry-to-
 * BRDF transition prescribes: a sample whose footprint on the sea is s
 * reads the surface low-passed at k = pi / s (Nyquist; a Butterworth
 * filter of the ocean's own, evaluated as a second frame per octave) and
 * takes the slope variance of every shorter wave (slope.h: the cascades'
 * modes, the near field and the unsimulated tail) as Beckmann roughness.
 * So near the camera the exact waves are the geometry, and far away their
 * average look is kept, as the viewer intends, without aliasing.  Each
 * pixel averages ss x ss samples in display values (after the tone curve,
 * as a framebuffer's multisample resolve does).
 *
 * Threads: a render_sea is immutable once made and may be shared by the
 * threads of one render_image call; render_image runs `threads` workers.
 * OOM policy: create returns OCEAN_ENOMEM with nothing kept; render_image
 * returns OCEAN_ENOMEM having written nothing useful.
 */
#ifndef RENDER_H
#define RENDER_H

#include "gerstner.h"
#include "ocean.h"

/* The sea of one instant, at every footprint level a view may need. */
typedef struct render_sea render_sea;

/* p: the sea; gp: its near field (NULL: none; ocean_gerstner_near_params
 * gives oceand's); effects: the OCEAN_FX_* channels the scene serves
 * (height and normals are always drawn; without displacement the sea has
 * no chop, without foam no whitecaps); t: sim time, s. */
ocean_result render_sea_create(const ocean_params *p, const ocean_gerstner_params *gp, unsigned effects,
                               double t, int threads, render_sea **out, char *msg, size_t msglen);
void render_sea_destroy(render_sea *s);   /* accepts NULL */
/* How many footprint levels (frames low-passed an octave apart) it holds. */
int render_sea_levels(const render_sea *s);

/* The surface at world (x, z): height and the other fields a sample needs,
 * read at footprint s (m; 0: the exact unfiltered sea).  For tests. */
typedef struct render_point {
    double height;       /* m, the displaced surface's height over (x, z) */
    double slope[2];     /* the surface's resolved slope */
    double mss[3];       /* slope moments below the footprint (xx, zz, xz) */
    double foam;
    double error;        /* the query's bound on |height - exact|, m */
} render_point;
ocean_result render_sea_point(const render_sea *s, double x, double z, double footprint_m, render_point *out);

/* One view, in the viewer's conventions (camera.js: yaw from +x toward +z,
 * pitch up, vertical field of view). */
typedef struct render_view {
    double eye[3];
    double yaw_deg, pitch_deg, fov_deg;
    int width, height;   /* pixels, 1..8192 */
    int supersample;     /* samples per pixel along each axis, 1..8 */
    int threads;         /* 1..64 */
    int sun_given;       /* 1: the sun at (sun_deg[0] azimuth, [1] elevation), as the viewer's
                            sun=AZ,EL; 0: the viewer's default sun for the sea's wind */
    double sun_deg[2];
} render_view;

typedef struct render_stats {
    double ms;                 /* wall time of the render */
    long rays, sea_rays;       /* samples cast, those that met the sea */
    long evaluations;          /* surface readings during marching and refinement */
    double max_height_error;   /* largest query bound at a hit, m */
} render_stats;

/* Renders the view into rgb (width * height * 3 display values in [0, 1],
 * row 0 at the top) and, if mask is not NULL, the fraction of each
 * pixel's samples that met the sea into mask (width * height, 0..255).
 * OCEAN_EINVAL for a bad view (message in msg). */
ocean_result render_image(const render_sea *s, const render_view *v, float *rgb, unsigned char *mask,
                          render_stats *st, char *msg, size_t msglen);

#endif
