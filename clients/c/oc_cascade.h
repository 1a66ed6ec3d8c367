/*
 * oc_cascade.h - layout-1 frames on the client: per-cascade periodic mip
 * grids, the spec's "where each mip is read" rule, a point sampler and the
 * client-side displacement of the flat concentric mesh
 * (PROTOCOL.md "Layouts: what travels per camera").
 *
 * A layout-1 FRAME carries, for each cascade c and mip m, the tiles its
 * camera needs of a grid of n_c/2^m samples that is periodic on the
 * cascade's patch P_c.  The library indexes those tiles per (c, m) into a
 * view (oc_cascade_view) when the frame is received.  Without the
 * subscription's time_interp flag every FRAME is self-contained (it carries
 * all tiles its camera needs) and its view reads only its own tiles; with
 * it, the connection holds each mip's two samples in time (oc_held.h) and
 * the view reads their blend at the frame's instant.  Either way a point
 * outside what the frame's instant covers is reported (OCEAN_ENOTFOUND),
 * never filled from an older instant.
 *
 * Reading (oc_frame_sample):
 *  - level: per cascade s_c = max(min_spacing_m, q_c * sqrt(dx^2 + dz^2 +
 *    max(|cy|, 1)^2)) from the frame's cascade block (each cascade entry
 *    has its own q_c), raised to the caller's min_spacing (the vertex rule
 *    max(s, g_L)); lambda_c = log2(s_c / sigma_c); mip 0
 *    at lambda <= 0, the two mips around lambda blended linearly
 *    (trilinear), the last mip beyond, times the fade
 *    w = clamp(mips - lambda, 0, 1) for a cascade that fades.  Exactly the
 *    spec's rule; oc_cascade_lod exposes the weights.  Height and
 *    displacement are read at the levels of max(s_c, G), G the block's
 *    geometry_spacing_m (the mesh's finest lattice when the frame has a
 *    mesh and normals; 0 otherwise): the server sends mips finer than the
 *    mesh can show with normals only.  A simulator that wants heights
 *    finer than its mesh sets SUBSCRIBE.flags PROTO_SUB_FULL_GEOMETRY or
 *    subscribes without a mesh (G is then 0), or asks QUERY.
 *  - position: world x, z reduced mod P_c with fmod (exact in IEEE double,
 *    so |x| = 1e7 m loses nothing), then a mip's periodic grid.
 *  - within a mip: Keys' cubic convolution (Keys 1981, "Cubic convolution
 *    interpolation for digital image processing", IEEE Trans. ASSP 29(6),
 *    a = -1/2; third-order accurate where bilinear is second-order) on a
 *    4 x 4 neighbourhood; OC_INTERP_LANCZOS3 (6 x 6 windowed sinc, 2.25x
 *    the reads) keeps more of the waves near a mip's two-samples-a-
 *    wavelength limit but ripples in its passband (a wave 18 samples long
 *    is read ~0.9 % off, against ~0.05 % for Keys: tests/test_oc_cascade.c); OC_INTERP_LINEAR is what a GPU's GL_LINEAR + REPEAT
 *    does.  Measured on the daemon's ship-bridge frames carrying every wave
 *    (2000 points within 30 m of a camera 10 m up, against accurate
 *    queries): height RMS error cubic 6.2 mm (max 2.3 cm), Lanczos-3 4.6 mm
 *    (1.5 cm), bilinear 2.7 cm (9.9 cm); mean-square slope read between the
 *    samples, of 0.0278 the tiles hold at their nodes: cubic 0.0274,
 *    Lanczos-3 0.0288, bilinear 0.0239.  Where a kernel reaches beyond the
 *    frame's tiles (the edge of the square the spec sends) the next
 *    narrower one is used, down to bilinear on the inner 2 x 2.
 *  - cascades are summed: height and displacement add; slopes add (each
 *    cascade's normal n is turned into slopes -n_x/n_y, -n_z/n_y with n_y
 *    held >= 0.01 so a folded crest cannot give an infinite slope) and the
 *    normal is normalise(-s_x, 1, -s_z) (PROTOCOL.md "From slopes"), i.e.
 *    the slopes of the parameter surface, as the tiles carry them; the
 *    breaking index (BI) and its quadrature (BQ) add too, and foam is the
 *    block's whitecap table applied to them at the breaking-index variance
 *    the reads hold with the interpolation used, by the frame's read table
 *    (proto_lod_foam, proto_lod_breaking_var: PROTOCOL.md "Whitecaps in
 *    layout 1"), so a point near the camera, which reads every cascade,
 *    gets the whitecaps of the whole sea, a far one the same coverage
 *    spread over the waves it still reads, and every interpolation the
 *    same coverage (400 m of ship-bridge: cubic 0.0218, Lanczos-3 0.0209,
 *    bilinear 0.0225, against the wind's 0.0202).  Where a kernel falls
 *    back to a narrower one at the frame's edge, the variance is still
 *    the asked kernel's.
 *  - unresolved slope moments: the mip table entries of the mips read with
 *    the same weights, entry `mips` in proportion 1 - w for a faded
 *    cascade, summed over cascades, plus the block's tail_mss.
 *
 * Threading: a view is immutable once built; any number of threads may
 * sample one frame at once.
 */
#ifndef OC_CASCADE_H
#define OC_CASCADE_H

#include <stddef.h>
#include <stdint.h>

#include "ocean_result.h"
#include "proto.h"

typedef struct oc_frame oc_frame;
typedef struct oc_topology oc_topology;
typedef struct oc_cascade_view oc_cascade_view;

/* How a mip is read between its samples. */
typedef enum oc_interp {
    OC_INTERP_CUBIC = 0,   /* Keys cubic convolution, 4 x 4 (default) */
    OC_INTERP_LINEAR = 1,  /* bilinear, 2 x 2 */
    OC_INTERP_LANCZOS3 = 2 /* Lanczos windowed sinc a = 3, 6 x 6 */
} oc_interp;

/* Which mips of each cascade a point reads, and with what weight. */
typedef struct oc_lod_cascade {
    double s;             /* spacing this cascade is read at, m: its own q_c */
    double lambda;        /* continuous level log2(s / sigma_c) */
    int mip[2];           /* mips read; mip[1] = -1 when only one */
    double weight[2];     /* their weights, the fade included (sum = fade) */
    double fade;          /* w of a fading cascade beyond its last mip, else 1 */
} oc_lod_cascade;

typedef struct oc_lod {
    double s;             /* spacing wanted at the point at the block's q (the
                             coarsest cascade's), m; each cascade's is in c[] */
    int count;            /* cascades */
    oc_lod_cascade c[PROTO_MAX_LAYERS];
} oc_lod;

/* What a point of a layout-1 frame holds. */
typedef struct oc_sample {
    double height;        /* surface height of the parameter point (x, z), m */
    double dx, dz;        /* its horizontal (choppy) displacement, m: the
                             surface point is (x + dx, height, z + dz) */
    double slope_x, slope_z; /* resolved d(eta)/dx, d(eta)/dz from the normals */
    double normal[3];     /* normalise(-slope_x, 1, -slope_z) */
    double foam;          /* [0, 1] */
    double mss[3];        /* unresolved slope moments x, z, xz at this point:
                             what shading must add to the resolved slopes */
    double s;             /* spacing the levels were chosen for, m */
    unsigned channels;    /* PROTO_CH_* present in every tile read (H, DX, DZ,
                             NORMAL, BREAKING: the latter with the block's
                             whitecap table); absent ones read as 0 (normal
                             up, no foam) */
    double residual;      /* oc_frame_surface only: |p + D(p) - (x, z)| left, m */
} oc_sample;

/* The lod rule of PROTOCOL.md for block b at world (x, z), with the
 * spacing raised to min_spacing (0: the rule's own s; a vertex of lattice
 * spacing g_L passes g_L).  Pure; OCEAN_EINVAL for non-finite input or a
 * block that breaks the protocol's ranges. */
ocean_result oc_cascade_lod(const proto_cascade_block *b, double x, double z, double min_spacing,
                            oc_lod *out);

/* Samples frame f (layout 1, tiles decoded) at world (x, z): the sum of
 * its cascades read per the lod rule with the spacing raised to
 * min_spacing (0 for shading, g_L for mesh vertices), Keys cubic within a
 * mip.  OCEAN_ESTATE if f is not a decoded layout-1 frame (its view failed
 * to build: f->view_result says why), OCEAN_ENOTFOUND if a mip the rule
 * reads has no tile at the point in this frame (out zeroed),
 * OCEAN_EINVAL for non-finite input. */
ocean_result oc_frame_sample(const oc_frame *f, double x, double z, double min_spacing, oc_sample *out);
/* As oc_frame_sample with the interpolation within a mip chosen. */
ocean_result oc_frame_sample_interp(const oc_frame *f, double x, double z, double min_spacing,
                                    oc_interp interp, oc_sample *out);

/* The surface at world (x, z): finds the parameter point p whose displaced
 * position p + (dx, dz) is (x, z) (Newton iteration on the sampled field,
 * as QUERY does on the server) and returns its sample with height the
 * surface height above (x, z) and out->residual what is left of the
 * inversion.  Where the surface folds the iteration may stop short:
 * OCEAN_EDIVERGED with the best point found.  Other results as
 * oc_frame_sample. */
ocean_result oc_frame_surface(const oc_frame *f, double x, double z, double min_spacing, oc_sample *out);
ocean_result oc_frame_surface_interp(const oc_frame *f, double x, double z, double min_spacing, oc_interp interp,
                                     oc_sample *out);

/* Geomorph weight of a vertex of level L at horizontal distance d from the
 * frame's camera, given that level's zone (g_L, R_L, b_L, 0) from
 * MESH_TOPOLOGY: smoothstep over [R_L - b_L, R_L + b_L], a step at R_L when
 * b_L = 0 (PROTOCOL.md "Mesh in layout 1", step 1).  The coarsest level's
 * weight is 0: callers pass is_coarsest. */
double oc_mesh_morph_weight(const float zone[4], double d, int is_coarsest);

/* Displaces the flat topology t (FLAT set, t->mesh_id = the frame's
 * placement mesh_id) for frame f (layout 1 with a mesh placement):
 * morph, snap toward the coarser lattice, then add (DX, H, DZ) summed over
 * cascades at world origin + p', read with max(s, g_L).  xyz gets 3 floats
 * per vertex relative to the placement origin (world = origin + xyz).
 * Every vertex is written; one whose point lies outside the frame's tiles
 * keeps its morphed flat position at y = 0 and the call then returns
 * OCEAN_ENOTFOUND (*missing, if not NULL, counts them).  OCEAN_EINVAL for a
 * topology that is not FLAT or not the placement's, OCEAN_ESTATE for a
 * frame without a layout-1 view or placement. */
ocean_result oc_frame_mesh_positions(const oc_frame *f, const oc_topology *t, float *xyz);
ocean_result oc_frame_mesh_positions_ex(const oc_frame *f, const oc_topology *t, oc_interp interp,
                                        float *xyz, size_t *missing);

/* ---- used by oceanclient.c when a frame is received ---------------------- */

/* Builds the view of a layout-1 frame whose tiles are decoded: checks that
 * every tile record fits the cascade block (tag < cascade_count, level <
 * mips, spacing sigma_c 2^m, square tiles of one side T per mip laid out as
 * the spec says, no tile twice) and indexes them.  tile_data[i] is tile i's
 * decoded planes (proto_tile_planes(channels) * width * height floats).
 * OCEAN_EFORMAT naming the tile for a misplaced one, OCEAN_ESTATE when a
 * tile is not decoded, OCEAN_ENOMEM. */
ocean_result oc_cascade_view_build(const proto_frame *info, const float *const *tile_data,
                                   oc_cascade_view **out, char *err, size_t errlen);
void oc_cascade_view_free(oc_cascade_view *v);

#endif
