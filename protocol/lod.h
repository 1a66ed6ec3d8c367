/*
 * lod.h - "Where each mip is read" (PROTOCOL.md): the spacing a layout-1
 * reader wants at a point and the mips of a cascade it reads there, with
 * their weights.  One rule for the daemon (which plans tiles and e_error
 * by it) and every client (which reads by it); the viewer's shader code
 * follows the same text.
 *
 * Threads: pure functions.
 */
#ifndef PROTO_LOD_H
#define PROTO_LOD_H

/* The mips of one cascade read at spacing s. */
typedef struct proto_lod_read {
    double lambda;      /* continuous level log2(s / sigma_c) */
    int mip[2];         /* the mips read; mip[1] = -1 when only one */
    double weight[2];   /* their weights, the fade included (they sum to fade) */
    double fade;        /* w of a fading cascade beyond its last mip, else 1 */
} proto_lod_read;

/* s_c(x, z) = max(min_spacing, q_c sqrt(dx^2 + dz^2 + max(|cam_y|, 1)^2)),
 * (dx, dz) the point's horizontal offset from the block's camera. */
double proto_lod_spacing(double q_c, double min_spacing, double cam_y, double dx, double dz);

/* The mips of a cascade of native spacing sigma with `mips` mips read at
 * spacing s: mip 0 at or below sigma, two neighbours blended linearly in
 * between, the last beyond, faded out by clamp(mips - lambda, 0, 1) when
 * the cascade fades. */
void proto_lod_read_at(double s, double sigma, int mips, int fades, proto_lod_read *out);

#endif
