/*
 * lod.h - "Where each mip is read" (PROTOCOL.md): the spacing a layout-1
 * reader wants at a point, the mips of a cascade it reads there with
 * their weights, and the unresolved slope moments those mips leave to
 * shading.  One rule for the daemon (which plans tiles and e_error by it)
 * and every client (which reads by it); the viewer's shader code follows
 * the same text and is checked against points computed here
 * (tests/vectors/lod.txt, lod_mss.txt).
 *
 * Threads: pure functions.
 */
#ifndef PROTO_LOD_H
#define PROTO_LOD_H

#include "proto.h"

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

/* Adds to mss (x, z, xz) the unresolved slope moments of one cascade read
 * as r says (r from proto_lod_read_at with the same mips): the mip table
 * entries of the mips read with their weights, entry `mips` (the whole
 * cascade) with 1 - fade, and, where two entries are blended with weights
 * a and 1 - a (two mips, or the last mip and entry `mips` in a fade),
 * a (1 - a) (coarser - finer).  tab holds entries 0..mips.  Term by term in
 * that order, so a sum over cascades begun at tail_mss rounds alike for
 * every caller.  A mip outside 0..mips-1 or of weight <= 0 adds nothing. */
void proto_lod_mss_add(const proto_lod_read *r, const proto_mip_entry *tab, int mips, double mss[3]);

/* The share of the breaking index's variance of the mips r reads that a
 * reader interpolating them with `kernel` (PROTO_READ_*) holds between
 * their nodes: the read mips' entries held[kernel] / 32768 with the read
 * weights, over the weights' sum (so a fade does not count twice); 1 for
 * a kernel < 0 (a reader of the waves as they are), a table without them
 * (no READ flag) or nothing read. */
double proto_lod_held(const proto_lod_read *r, const proto_mip_entry *tab, int mips, int kernel);

/* The breaking index's variance a reader holds of one cascade read as r
 * says: the whole cascade's slope variance (entry mips, x + z) less what
 * proto_lod_mss_add leaves unresolved (x + z), >= 0, times
 * proto_lod_held.  Each wave's breaking index is |k| times its height
 * (foam.h), whose variance is the wave's mean-square slope, so the mip
 * table already gives it; an interpolation between nodes damps the waves
 * near each mip's Nyquist, which the read table gives. */
double proto_lod_breaking_var(const proto_lod_read *r, const proto_mip_entry *tab, int mips, int kernel);

/* Whitecap foam in [0, 1] at a point of a layout-1 frame whose block b
 * carries the whitecap table (PROTOCOL.md "Whitecaps in layout 1"): beta
 * and q the cascades' BI and BQ summed as the rule reads them, var the
 * sum of proto_lod_breaking_var over the same reads.  The ramp's foot and
 * the band's frequency are the table's, linear in sigma = sqrt(var)
 * between the rows around it and the end row's beyond them; the foam is
 * ocean_foam_value's (foam.h).  0 for a block without the table. */
double proto_lod_foam(const proto_cascade_block *b, double var, double beta, double q);

#endif
