/*
 * mesh_internal.h - what the mesh_*.c files share; not a public header.
 *
 * Concentric and chunked meshes are both sets of square leaf cells on an
 * integer lattice (unit = the finest spacing), so they share one
 * triangulator: every leaf is split in two along its (0,0)-(1,1) diagonal,
 * or, when finer neighbours put vertices inside its edges, fanned from its
 * centre through all of them.  That is what makes every mesh free of
 * cracks and T-junctions, whatever the level pattern.
 */
#ifndef OCEAN_MESH_INTERNAL_H
#define OCEAN_MESH_INTERNAL_H

#include <stdint.h>

#include "mesh.h"

typedef struct mesh_leaf {
    int32_t x, z;     /* lower corner, lattice units */
    int32_t size;     /* side, lattice units (power of two) */
    uint8_t level;
} mesh_leaf;

/* Topology under construction. */
typedef struct mesh_bb {
    mesh_leaf *leaves;
    size_t nl, cap_l;
    int32_t *lat;       /* 2 per vertex */
    uint8_t *lvl;
    uint32_t nv, cap_v;
    uint32_t *idx;
    size_t ni, cap_i;
    uint64_t *hkeys;    /* open addressing: lattice point -> vertex */
    uint32_t *hvals;
    size_t hcap, hcount;
} mesh_bb;

struct mesh {
    mesh_config cfg;
    int built;
    uint64_t key;
    double origin[3];
    double unit_m;                     /* lattice unit (concentric, chunked) */
    uint32_t nv, ni;
    float *base, *pos, *morph;
    uint8_t *level;
    int32_t *lat;                      /* 2 per vertex, NULL for projected */
    uint32_t *idx;
    int levels;
    int32_t lvl_units[MESH_MAX_LEVELS];/* cell side of each level, units */
    int place_only;                    /* mesh_place: skip per-vertex positions and morph */
    mesh_info info;
    /* Displacement scratch: each vertex's own sample, and the vertices at
     * the three coarse corners a morphing vertex interpolates (3 per
     * vertex, UINT32_MAX where a corner is no vertex), rebuilt lazily
     * after every topology change (corner_ok = 0). */
    double *raw;
    size_t raw_cap;
    uint32_t *corner;
    int corner_ok;
};

void mesh_bb_free(mesh_bb *bb);
ocean_result mesh_bb_add_leaf(mesh_bb *bb, int32_t x, int32_t z, int32_t size, int level);
/* Vertices and triangles of every leaf (see the file comment). */
ocean_result mesh_bb_triangulate(mesh_bb *bb);

/* Moves bb's topology into m (allocating base/pos/morph), base = lat *
 * unit.  On failure m is unchanged and bb still owns its arrays. */
ocean_result mesh_adopt(mesh *m, mesh_bb *bb, double unit_m);

/* Installs fully built arrays into m (projected grid); takes ownership on
 * success only. */
ocean_result mesh_install(mesh *m, uint32_t nv, uint32_t ni, float *base, uint32_t *idx);

uint64_t mesh_hash(uint64_t h, const void *p, size_t n);
double mesh_smoothstep(double t);
double mesh_now_ms(void);

ocean_result mesh_build_concentric(mesh *m, const mesh_camera *cam);
ocean_result mesh_build_chunked(mesh *m, const mesh_camera *cam);
ocean_result mesh_build_projected(mesh *m, const mesh_camera *cam);

#endif
