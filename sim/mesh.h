/*
 * mesh.h - camera-relative LOD meshes for the sea surface (no sockets).
 *
 * Three kinds, all watertight (no cracks, no T-junctions), all with float
 * positions relative to a per-frame origin whose world position is double,
 * uint32 indices, and per-vertex LOD level and morph weight:
 *
 *  - MESH_CONCENTRIC (seed 001, the default): nested levels centred under
 *    the camera.  Level 0 (spacing dx) is the core; then rings of doubling
 *    radius R_i = 2 R_(i-1) whose spacing doubles with them (dx, 2 dx,
 *    4 dx, 8 dx, ...: seed 000's tessellation factors 8 / 4 / 1 at 0, R0
 *    and 4 R0) out to the range (90 km and beyond), so every direction gets
 *    the same vertex count.  Every lattice is twice the one inside it: the
 *    layout-1 morph (PROTOCOL.md "Mesh in layout 1") slides an odd vertex
 *    onto a coarse vertex that stays put, which turns no triangle over.
 *    The whole mesh moves with the camera in steps of the level-2 spacing
 *    (4 dx), so level 0-2 vertices stay on a world-fixed lattice and the
 *    topology never changes while the near spacing is unchanged: a client
 *    gets indices once, then positions.
 *    Cells bordering a finer level are fanned from their centre through
 *    every finer vertex on their edges, so no vertex lies inside an edge.
 *    Beyond the range a flat far skirt (mesh_config.far_skirt) reaches the
 *    camera's horizon, so no mesh edge shows from high up; its vertices
 *    come last, carry the last level and morph 1, and are never sampled.
 *  - MESH_CHUNKED (seed 004): a grid of square tiles (default 6x6 of
 *    128 m, 32x32 quads) snapped to the tile size, up to 4 levels by
 *    distance, neighbours at most one level apart, edges stitched.
 *  - MESH_PROJECTED (seed 000's title, after Johanson 2004): a grid laid in
 *    a projector's angular screen space (azimuth x angle from the nadir)
 *    over the view frustum's footprint on the sea, with the frustum first
 *    widened by the wave displacement margin (so crests and troughs at the
 *    screen edge never open holes) and clamped to the range (the horizon).
 *
 * Near spacing (concentric): the pixel footprint rule dx = h / rho_err,
 * with rho_err = roughness * f / error_px (f = pixels per radian), capped
 * at k * lambda_dominant (k in [0.1, 0.5]) and floored at min_spacing,
 * then rounded down to a power of two metres so the lattice is stable
 * while the camera climbs within an octave.  The zones follow from the
 * same rule: each level's morph zone R_i +- blend_frac R_i (50 m +- 10 m
 * in the defaults' proportions) starts where the next level's spacing
 * meets the error budget, R_i (1 - blend_frac) = rho_err dx_(i+1); so
 * R0 = 2 rho_err dx / (1 - blend_frac), then R_i = 2 R_(i-1) (seed 000's
 * 50 m / 200 m are R0 and R2 for a camera ~20 m up).  A camera at 3 000 m
 * gets a coarser core than one at 2 m, a narrow field of view a finer one,
 * and every camera the same error budget in pixels.
 *
 * Threads: a mesh object is used by one thread at a time; distinct meshes
 * are independent.
 */
#ifndef OCEAN_MESH_H
#define OCEAN_MESH_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "ocean_result.h"
#include "spectrum.h"

#define MESH_MAX_LEVELS 32
#define MESH_CONCENTRIC_BLEND_MIN 0.15 /* blend_frac a concentric mesh takes (mesh.c) */
#define MESH_CONCENTRIC_BLEND_MAX 0.24

typedef enum mesh_kind {
    MESH_CONCENTRIC = 0,
    MESH_CHUNKED = 1,
    MESH_PROJECTED = 2,
    MESH_KIND_COUNT_
} mesh_kind;

/* "concentric", "chunked", "projected"; parse returns OCEAN_EINVAL for
 * anything else. */
const char *mesh_kind_name(mesh_kind k);
ocean_result mesh_kind_parse(const char *name, mesh_kind *out);

/* A viewer.  Yaw is measured from +x toward +z (as the wind direction),
 * pitch positive up, roll positive clockwise as seen by the viewer. */
typedef struct mesh_camera {
    double pos[3];        /* world x, y (height above mean sea level), z */
    double yaw_deg, pitch_deg, roll_deg;
    double fov_y_deg;     /* vertical field of view, (0, 180) */
    int viewport_w, viewport_h;
} mesh_camera;

/* Camera at (0, 20, 0), level, 60 degree fov, 1920x1080. */
void mesh_camera_default(mesh_camera *c);
/* Finite position (|x|,|z| <= 1e10, |y| <= 1e7), angles finite, fov in
 * (0, 180) and viewport in range: the ranges ocean.v1 allows.  Message names the field. */
ocean_result mesh_camera_validate(const mesh_camera *c, char *msg, size_t msglen);
/* Pixels per radian at the screen centre: (h/2) / tan(fov/2). */
double mesh_camera_px_per_rad(const mesh_camera *c);
/* Unit forward, right and up vectors of the camera. */
void mesh_camera_basis(const mesh_camera *c, double fwd[3], double right[3], double up[3]);

typedef struct mesh_config {
    mesh_kind kind;
    double range_m;          /* radius the mesh must cover, 10 m .. 1e6 m (90 km) */
    /* concentric */
    double error_px;         /* screen-space error budget, px (1) */
    double roughness;        /* largest geometric error per metre of spacing of
                                the sea drawn (m/m); with error_px sets rho_err.
                                MESH_ROUGHNESS; for a given sea,
                                mesh_roughness() */
    double lambda_dominant_m;/* dominant wavelength, m; 0 = unknown (no cap) */
    double k_lambda;         /* near spacing <= k * lambda_dominant, 0.1 .. 0.5 */
    double min_spacing_m;    /* finest near spacing (the sea's finest detail) */
    double blend_frac;       /* morph zone half-width / zone radius, 0..0.45 (0.2);
                                concentric: MESH_CONCENTRIC_BLEND_MIN..MAX */
    int max_levels;          /* most levels, 1..MESH_MAX_LEVELS (MESH_MAX_LEVELS): a
                                camera near the water with a long range that would
                                need more gets a coarser near spacing (one
                                doubling per level saved) */
    int far_skirt;           /* 1 (default): rings of flat triangles (morph 1, never
                                sampled, the sea's mean level) from the range out to
                                the horizon of the camera's height octave,
                                sqrt(2 R h + h^2), so no mesh edge shows from high up;
                                0: the mesh stops at the range */
    /* chunked */
    int chunk_tiles;         /* tiles per side, 1..64 (6) */
    double chunk_tile_m;     /* tile size, m (128) */
    int chunk_quads;         /* quads per tile side at level 0, power of two 2..256 (32) */
    int chunk_levels;        /* 1..4; level L has chunk_quads >> L quads per side */
    /* projected */
    int grid_w, grid_h;      /* grid columns x rows, 2..4096 (256 x 256) */
    double margin_m;         /* largest wave displacement, m (vertical and
                                horizontal), so waves never open holes (6) */
} mesh_config;

/* The default mesh_config.roughness, 0.075 m/m: a saturated wind-sea tail
 * (PM alpha) puts rms sqrt(alpha)/(2 pi) s = 0.014 s in the band a spacing
 * s cannot carry; the maximum over a frame's samples is ~4.5 sigma, and
 * choppy displacement at choppiness 1 adds as much sideways (bench_mesh
 * calibrates it: <= 1 px at 2..2000 m). */
#define MESH_ROUGHNESS 0.075
#define MESH_CHOP_VERTICAL 1.3

void mesh_config_default(mesh_config *c);

/* The roughness of a sea drawn with its choppy displacement: the vertical
 * and horizontal errors a spacing leaves are orthogonal, the horizontal one
 * choppiness lambda times the calibration's, so the error grows as
 * sqrt((1 + lambda^2) / 2); MESH_ROUGHNESS up to lambda = 1 (calm seas keep
 * the calibrated mesh), at most 1.  With MESH_ROUGHNESS alone the error
 * outgrew the budget from lambda ~3 on (ocean-sim mesh, camera at 25 m,
 * 16 px: 16.2 px at 3, 54 px at 10).  An invalid sea gets MESH_ROUGHNESS. */
double mesh_roughness(const ocean_sea_state *sea);
ocean_result mesh_config_validate(const mesh_config *c, char *msg, size_t msglen);

/* Dominant wavelength of a sea state: 2 pi / k_p with k_p the wave number
 * of the spectrum's peak at the sea's depth.  OCEAN_EINVAL for an invalid
 * sea; *out = 0 for no wind (no dominant wave). */
ocean_result mesh_lambda_dominant(const ocean_sea_state *sea, double *out);

typedef struct mesh mesh;

/* Validates cfg and makes an empty mesh.  *out is NULL on failure. */
ocean_result mesh_create(const mesh_config *cfg, mesh **out);
void mesh_destroy(mesh *m);   /* accepts NULL */

/* An upper estimate of the vertex count mesh_build would make for cfg and
 * cam, computed from the plan alone (no allocation, microseconds), so a
 * server can refuse a mesh before building it: concentric meshes grow as
 * (px per radian / error_px)^2, a 1-degree 1080p camera asks for ~10^7.
 * OCEAN_EINVAL for an invalid config or camera. */
ocean_result mesh_estimate_vertices(const mesh_config *cfg, const mesh_camera *cam, double *out);

/* Builds (or updates) the mesh for a camera.  When the topology the camera
 * calls for equals the current one (same key), only the origin, morph
 * weights and (projected grid) positions are refreshed, which is O(vertices)
 * with no allocation.  Positions are left undisplaced (see mesh_displace).
 * On failure (OCEAN_EINVAL for a bad camera, OCEAN_ENOMEM, OCEAN_ETOOBIG
 * past 2^31 indices) the previous mesh is unchanged. */
ocean_result mesh_build(mesh *m, const mesh_camera *cam);

/* What a built mesh holds.  Pointers stay valid until the next mesh_build
 * or mesh_destroy. */
typedef struct mesh_view {
    mesh_kind kind;
    double origin[3];          /* world position of the frame origin (y = 0) */
    uint32_t vertex_count;
    uint32_t index_count;      /* 3 per triangle; triangles face +y */
    const float *base;         /* xyz per vertex relative to origin, flat (y = 0) */
    const float *positions;    /* xyz relative to origin after mesh_displace
                                  (equal to base until then) */
    const uint32_t *indices;
    const uint8_t *level;      /* LOD level per vertex (0 = finest) */
    const float *morph;        /* morph weight per vertex 0..1 toward level + 1 */
    uint64_t topology_key;     /* equal keys <=> identical indices and base */
    int levels;                /* number of LOD levels present */
} mesh_view;
/* mesh_build for clients that morph and displace the flat mesh themselves
 * (the cascade tile layout): the topology (rebuilt only when the plan
 * changes), origin and info, without the per-vertex positions and morph
 * weights of mesh_build, which are left as they were.  Concentric meshes
 * only; other kinds are built in full. */
ocean_result mesh_place(mesh *m, const mesh_camera *cam);
void mesh_get_view(const mesh *m, mesh_view *out);

/* The plan behind the last build. */
typedef struct mesh_info {
    double near_spacing_m;            /* level 0 spacing (projected: 0) */
    double rho_err;                   /* spacing/distance budget: dx(D) = D / rho_err */
    int levels;
    double level_spacing_m[MESH_MAX_LEVELS];
    double zone_radius_m[MESH_MAX_LEVELS];  /* outer radius of each level's zone */
    double blend_m[MESH_MAX_LEVELS];        /* morph zone half-width at that radius */
    /* seed 000's density rho(d) = rho_max exp(-alpha d) + rho_min (vertices
     * per metre) fitted to the tessellation factors 8/4/1 at 0, R0, R2 */
    double rho_max, alpha, rho_min;
    double build_ms;                  /* wall time of the last mesh_build */
    int rebuilt;                      /* 1 if the last build made new topology */
} mesh_info;
void mesh_get_info(const mesh *m, mesh_info *out);

/* Target linear vertex density (vertices per metre) at horizontal
 * distance d from the camera: seed 000's rho(d) inside the core (d < R1),
 * rho_err / d beyond (the rings).  Concentric meshes only (0 otherwise).
 * The built mesh never falls below it; the levels' power-of-two spacing
 * puts it up to 2x above (4x just inside R1, seed 000's step from factor
 * 4 to 1). */
double mesh_density_target(const mesh *m, double d);

/* Displacement of the sea at world (x, z): out = (dx, dy, dz), metres. */
typedef void (*mesh_sampler_fn)(void *ctx, double x, double z, double out_disp[3]);

/* positions = base + displacement sampled at each vertex's world position
 * (origin + base, in double).  A vertex with morph weight w > 0 gets
 * (1 - w) D(p) + w D_coarse(p), D_coarse interpolating D on the next
 * level's lattice, so vertices glide into the coarser level.  OCEAN_ESTATE
 * before the first build. */
ocean_result mesh_displace(mesh *m, mesh_sampler_fn fn, void *ctx);

/* Largest screen-space geometric error, px, of the displaced mesh against
 * the surface itself.  fn is called from several OpenMP threads at once,
 * so it must be reentrant (ocean_frame_sample is).  Measured
 * as the sampler evaluated at each point (an
 * infinitely dense reference): at the centroid and edge midpoints of
 * every triangle, the angle at the camera between the mesh's interpolated
 * point and the true displaced point, times mesh_camera_px_per_rad.  The
 * angle is orientation independent (the worst over all view directions).
 * Call after mesh_displace with the same sampler. */
ocean_result mesh_error_px(const mesh *m, const mesh_camera *cam, mesh_sampler_fn fn,
                           void *ctx, double *max_px);

/* Writes the displaced mesh as Wavefront OBJ, positions relative to the
 * origin (stated in a comment), one face per triangle. */
ocean_result mesh_write_obj(const mesh *m, FILE *f);

#endif
