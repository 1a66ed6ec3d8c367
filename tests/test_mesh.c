/*
 * test_mesh.c - the LOD meshes (sim/mesh.h): watertight, no T-junctions,
 * no degenerate or flipped triangles, counts, density, stitching, frustum
 * coverage, snapping, far-from-origin precision, displacement and morph,
 * topology keys, OBJ output, hostile input.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "mesh.h"

static int sanitized(void)
{
    const char *s = getenv("OCEAN_TEST_SANITIZED");
    return s && *s == '1';
}

/* ---- helpers --------------------------------------------------------- */

static mesh *make(mesh_kind kind, double range, double error_px)
{
    mesh_config c;
    mesh_config_default(&c);
    c.kind = kind;
    c.range_m = range;
    c.error_px = error_px;
    mesh *m = NULL;
    assert_int_equal(mesh_create(&c, &m), OCEAN_OK);
    assert_non_null(m);
    return m;
}

static mesh_camera cam_at(double x, double y, double z)
{
    mesh_camera c;
    mesh_camera_default(&c);
    c.pos[0] = x;
    c.pos[1] = y;
    c.pos[2] = z;
    return c;
}

typedef struct edge_rec {
    uint64_t key;   /* min << 32 | max */
    int fwd, bwd;   /* uses as min->max, max->min */
} edge_rec;

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* Checks indices in range, every triangle non-degenerate and facing +y
 * (flat base positions), every edge used at most twice and then in
 * opposite directions (a consistently oriented 2-manifold), and
 * V - E + F == 1 (a disc: one boundary loop, no hole, no crack - a
 * T-junction would leave an unmatched triangle of edges and lower it).
 * Returns the number of boundary edges; *min_boundary_r gets the smallest
 * horizontal distance of a boundary edge's midpoint from (cx, cz). */
static long check_topology(const mesh_view *v, double cx, double cz, double *min_boundary_r)
{
    uint32_t nt = v->index_count / 3;
    assert_true(v->index_count % 3 == 0);
    assert_true(nt > 0);
    uint64_t *e = malloc((size_t)nt * 3 * sizeof *e);
    assert_non_null(e);
    double min_area = INFINITY;
    for (uint32_t t = 0; t < nt; t++) {
        const uint32_t *tri = v->indices + 3 * t;
        for (int k = 0; k < 3; k++)
            assert_true(tri[k] < v->vertex_count);
        const float *a = v->base + 3 * tri[0], *b = v->base + 3 * tri[1], *c = v->base + 3 * tri[2];
        double ux = b[0] - a[0], uz = b[2] - a[2], wx = c[0] - a[0], wz = c[2] - a[2];
        double cross_y = uz * wx - ux * wz; /* y of (b-a) x (c-a) */
        double l2 = fmax(ux * ux + uz * uz, wx * wx + wz * wz);
        if (!(cross_y > 1e-9 * l2)) {
            print_error("triangle %u degenerate or flipped: cross %g (edge^2 %g)\n", t, cross_y, l2);
            fail();
        }
        min_area = fmin(min_area, cross_y);
        for (int k = 0; k < 3; k++) {
            uint32_t p = tri[k], q = tri[(k + 1) % 3];
            uint64_t lo = p < q ? p : q, hi = p < q ? q : p;
            /* bit 0 of the low word: direction; edge key in the rest */
            e[3 * t + k] = (lo << 32 | hi) << 1 | (p > q);
        }
    }
    qsort(e, (size_t)nt * 3, sizeof *e, cmp_u64);
    long edges = 0, boundary = 0;
    double minr = INFINITY;
    for (size_t i = 0; i < (size_t)nt * 3;) {
        size_t j = i;
        int fwd = 0, bwd = 0;
        while (j < (size_t)nt * 3 && (e[j] >> 1) == (e[i] >> 1)) {
            if (e[j] & 1)
                bwd++;
            else
                fwd++;
            j++;
        }
        edges++;
        if (fwd > 1 || bwd > 1) {
            print_error("edge used %d/%d times in one direction\n", fwd, bwd);
            fail();
        }
        if (fwd + bwd == 1) {
            boundary++;
            uint64_t k = e[i] >> 1;
            uint32_t p = (uint32_t)(k >> 32), q = (uint32_t)k;
            double mx = 0.5 * (v->base[3 * p] + v->base[3 * q]) + v->origin[0] - cx;
            double mz = 0.5 * (v->base[3 * p + 2] + v->base[3 * q + 2]) + v->origin[2] - cz;
            minr = fmin(minr, hypot(mx, mz));
        }
        i = j;
    }
    free(e);
    long euler = (long)v->vertex_count - edges + (long)nt;
    if (euler != 1) {
        print_error("V - E + F = %ld (want 1 for a disc)\n", euler);
        fail();
    }
    if (min_boundary_r)
        *min_boundary_r = minr;
    return boundary;
}

/* Brute T-junction check with a bucket grid: no vertex lies strictly
 * inside any triangle edge. */
static void check_no_tjunction(const mesh_view *v, double bucket)
{
    float minx = INFINITY, minz = INFINITY, maxx = -INFINITY, maxz = -INFINITY;
    for (uint32_t i = 0; i < v->vertex_count; i++) {
        minx = fminf(minx, v->base[3 * i]);
        maxx = fmaxf(maxx, v->base[3 * i]);
        minz = fminf(minz, v->base[3 * i + 2]);
        maxz = fmaxf(maxz, v->base[3 * i + 2]);
    }
    bucket = fmax(bucket, fmax(maxx - minx, maxz - minz) / 2000);
    long nx = (long)((maxx - minx) / bucket) + 1, nz = (long)((maxz - minz) / bucket) + 1;
    assert_true(nx * nz < 50000000);
    long *head = malloc((size_t)(nx * nz) * sizeof *head), *next = malloc(v->vertex_count * sizeof *next);
    assert_non_null(head);
    assert_non_null(next);
    for (long i = 0; i < nx * nz; i++)
        head[i] = -1;
    for (uint32_t i = 0; i < v->vertex_count; i++) {
        long bx = (long)((v->base[3 * i] - minx) / bucket), bz = (long)((v->base[3 * i + 2] - minz) / bucket);
        next[i] = head[bz * nx + bx];
        head[bz * nx + bx] = i;
    }
    long found = 0;
    for (uint32_t t = 0; t < v->index_count; t += 3)
        for (int k = 0; k < 3; k++) {
            uint32_t p = v->indices[t + k], q = v->indices[t + (k + 1) % 3];
            if (p > q)
                continue; /* each interior edge once */
            double ax = v->base[3 * p], az = v->base[3 * p + 2];
            double bx = v->base[3 * q], bz = v->base[3 * q + 2];
            double len = hypot(bx - ax, bz - az);
            long x0 = (long)((fmin(ax, bx) - minx) / bucket), x1 = (long)((fmax(ax, bx) - minx) / bucket);
            long z0 = (long)((fmin(az, bz) - minz) / bucket), z1 = (long)((fmax(az, bz) - minz) / bucket);
            for (long gz = z0; gz <= z1; gz++)
                for (long gx = x0; gx <= x1; gx++)
                    for (long i = head[gz * nx + gx]; i >= 0; i = next[i]) {
                        if ((uint32_t)i == p || (uint32_t)i == q)
                            continue;
                        double px = v->base[3 * i] - ax, pz = v->base[3 * i + 2] - az;
                        double ex = (bx - ax) / len, ez = (bz - az) / len;
                        double along = px * ex + pz * ez, off = fabs(px * ez - pz * ex);
                        if (along > 1e-6 * len && along < len * (1 - 1e-6) && off < 1e-6 * len)
                            found++;
                    }
        }
    free(head);
    free(next);
    if (found) {
        print_error("%ld vertices lie inside another triangle's edge\n", found);
        fail();
    }
}

/* ---- config and camera ------------------------------------------------ */

static void test_config_and_camera(void **state)
{
    (void)state;
    mesh_config c;
    mesh_config_default(&c);
    char msg[128];
    assert_int_equal(mesh_config_validate(&c, msg, sizeof msg), OCEAN_OK);
    mesh_config b = c;
    b.range_m = NAN;
    assert_int_equal(mesh_config_validate(&b, msg, sizeof msg), OCEAN_EINVAL);
    assert_non_null(strstr(msg, "range"));
    b = c;
    b.k_lambda = 0.6;
    assert_int_equal(mesh_config_validate(&b, msg, sizeof msg), OCEAN_EINVAL);
    assert_non_null(strstr(msg, "k_lambda"));
    b = c;
    b.chunk_quads = 24;
    assert_int_equal(mesh_config_validate(&b, msg, sizeof msg), OCEAN_EINVAL);
    b = c;
    b.kind = (mesh_kind)7;
    mesh *m = (mesh *)&b;
    assert_int_equal(mesh_create(&b, &m), OCEAN_EINVAL);
    assert_null(m);

    mesh_kind k;
    assert_int_equal(mesh_kind_parse("chunked", &k), OCEAN_OK);
    assert_int_equal(k, MESH_CHUNKED);
    assert_int_equal(mesh_kind_parse("cone", &k), OCEAN_EINVAL);
    assert_string_equal(mesh_kind_name(MESH_PROJECTED), "projected");

    mesh_camera cam = cam_at(0, 10, 0);
    assert_int_equal(mesh_camera_validate(&cam, msg, sizeof msg), OCEAN_OK);
    cam.pos[2] = INFINITY;
    assert_int_equal(mesh_camera_validate(&cam, msg, sizeof msg), OCEAN_EINVAL);
    assert_non_null(strstr(msg, "position"));
    cam = cam_at(0, 10, 0);
    cam.fov_y_deg = 0;
    assert_int_equal(mesh_camera_validate(&cam, msg, sizeof msg), OCEAN_EINVAL);
    cam = cam_at(0, 10, 0);
    cam.viewport_h = 0;
    assert_int_equal(mesh_camera_validate(&cam, msg, sizeof msg), OCEAN_EINVAL);
    /* 1080 px over 60 degrees: 540 / tan 30 */
    cam = cam_at(0, 10, 0);
    assert_float_equal(mesh_camera_px_per_rad(&cam), 540 / tan(M_PI / 6), 1e-9);
}

static void test_lambda_dominant(void **state)
{
    (void)state;
    ocean_sea_state sea;
    ocean_sea_state_default(&sea);
    double lam = 0;
    assert_int_equal(mesh_lambda_dominant(&sea, &lam), OCEAN_OK);
    /* deep water: lambda = 2 pi g / wp^2 */
    double wp = ocean_spectrum_peak(&sea);
    assert_true(wp > 0);
    assert_float_equal(lam, 2 * M_PI * OCEAN_G / (wp * wp), 1e-3 * lam);
    assert_true(lam > 30 && lam < 300); /* a 10 m/s wind sea */
    sea.wind_u10 = 0;
    assert_int_equal(mesh_lambda_dominant(&sea, &lam), OCEAN_OK);
    assert_true(lam == 0);
    sea.wind_u10 = NAN;
    assert_int_equal(mesh_lambda_dominant(&sea, &lam), OCEAN_EINVAL);
}

/* The roughness a sea's mesh is built with: the calibrated one up to
 * choppiness MESH_CHOP_VERTICAL, then growing as the choppiness (the
 * sideways error), at most 1; a sea without a valid choppiness keeps the
 * calibration.  And it densifies the mesh: more vertices at choppiness 5
 * than at 1, none more at 1.3. */
static void test_roughness_follows_choppiness(void **state)
{
    (void)state;
    ocean_sea_state sea;
    ocean_sea_state_default(&sea);
    const double lam[] = {0, 0.5, 1, 1.3, 2.6, 5, 10};
    const double want[] = {0.075, 0.075, 0.075, 0.075, 0.15, 0.075 * 5 / 1.3, 0.075 * 10 / 1.3};
    for (int i = 0; i < 7; i++) {
        sea.choppiness = lam[i];
        assert_float_equal(mesh_roughness(&sea), want[i], 1e-12);
    }
    sea.choppiness = 1e3; /* beyond the config's range: the cap */
    assert_true(mesh_roughness(&sea) == 1.0);
    sea.choppiness = NAN;
    assert_true(mesh_roughness(&sea) == MESH_ROUGHNESS);
    assert_true(mesh_roughness(NULL) == MESH_ROUGHNESS);
    mesh_camera cam;
    mesh_camera_default(&cam);
    size_t count[3];
    const double chop[3] = {1, 1.3, 5};
    for (int i = 0; i < 3; i++) {
        mesh_config cfg;
        mesh_config_default(&cfg);
        cfg.error_px = 16;
        cfg.range_m = 2000;
        sea.choppiness = chop[i];
        cfg.roughness = mesh_roughness(&sea);
        mesh *m = NULL;
        assert_int_equal(mesh_create(&cfg, &m), OCEAN_OK);
        assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
        mesh_view v;
        mesh_get_view(m, &v);
        count[i] = v.vertex_count;
        mesh_destroy(m);
    }
    assert_true(count[1] == count[0]);
    assert_true(count[2] > 4 * count[0]);
}

/* A camera at the water with a long range needs more levels than a
 * reader may take: with max_levels the near spacing coarsens until it
 * fits, and the mesh still reaches the range (a camera at 0.5 m with a
 * 200 km range had 20 levels; the daemon, whose frames hold 16, refused it
 * and dropped the mesh). */
static void world_of(const mesh_view *v, uint32_t i, double out[2]);

static void test_concentric_max_levels(void **state)
{
    (void)state;
    mesh_camera cam;
    mesh_camera_default(&cam);
    cam.pos[1] = 0.5;
    mesh_config cfg;
    mesh_config_default(&cfg);
    cfg.error_px = 16;
    cfg.range_m = 2e5;
    cfg.far_skirt = 0; /* the mesh itself must reach the range */
    mesh *m = NULL;
    assert_int_equal(mesh_create(&cfg, &m), OCEAN_OK);
    assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
    mesh_view v;
    mesh_get_view(m, &v);
    int free_levels = v.levels;
    mesh_destroy(m);
    assert_true(free_levels > 16);
    cfg.max_levels = 16;
    assert_int_equal(mesh_create(&cfg, &m), OCEAN_OK);
    assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
    mesh_get_view(m, &v);
    assert_true(v.levels <= 16 && v.levels >= 2);
    /* it still covers the range: a vertex at least that far out */
    double far = 0;
    for (uint32_t i = 0; i < v.vertex_count; i++) {
        double w[2];
        world_of(&v, i, w);
        double d = hypot(w[0] - cam.pos[0], w[1] - cam.pos[2]);
        far = d > far ? d : far;
    }
    assert_true(far >= cfg.range_m);
    mesh_destroy(m);
    cfg.max_levels = 0;
    char msg[200];
    assert_int_equal(mesh_config_validate(&cfg, msg, sizeof msg), OCEAN_EINVAL);
    assert_non_null(strstr(msg, "max_levels"));
}

/* ---- concentric ------------------------------------------------------- */

static void test_concentric_watertight_full_range(void **state)
{
    (void)state;
    /* the real 90 km configuration (coarser budget under ASan) */
    double heights[3] = {2, 200, 3000};
    for (int i = 0; i < 3; i++) {
        mesh *m = make(MESH_CONCENTRIC, 90000, sanitized() ? 6 : 2);
        mesh_camera cam = cam_at(12.3, heights[i], -45.6);
        assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
        mesh_view v;
        mesh_get_view(m, &v);
        double minr;
        long nb = check_topology(&v, v.origin[0], v.origin[2], &minr);
        assert_true(nb > 0);
        /* the only boundary is the outer one, at or beyond the range */
        assert_true(minr >= 90000 * 0.999);
        assert_true(v.levels >= 3);
        mesh_destroy(m);
    }
}

static void test_concentric_no_tjunctions(void **state)
{
    (void)state;
    /* small range so the brute-force check stays quick; every level
     * border type (0|1, 1|2 at ratio 4, ring|ring) is present */
    mesh *m = make(MESH_CONCENTRIC, 2000, 3);
    mesh_camera cam = cam_at(3.1, 5, 7.7);
    assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
    mesh_view v;
    mesh_get_view(m, &v);
    mesh_info in;
    mesh_get_info(m, &in);
    assert_true(v.levels >= 4);
    check_topology(&v, v.origin[0], v.origin[2], NULL);
    check_no_tjunction(&v, 4 * in.near_spacing_m);
    /* every level is present among the vertices */
    int seen[MESH_MAX_LEVELS] = {0};
    for (uint32_t i = 0; i < v.vertex_count; i++)
        seen[v.level[i]]++;
    for (int L = 0; L < v.levels; L++)
        assert_true(seen[L] > 0);
    mesh_destroy(m);
}

static void test_concentric_counts_and_symmetry(void **state)
{
    (void)state;
    mesh *m = make(MESH_CONCENTRIC, 20000, 2);
    mesh_camera cam = cam_at(0, 20, 0);
    assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
    mesh_view v;
    mesh_get_view(m, &v);
    mesh_info in;
    mesh_get_info(m, &in);
    /* the same vertex count in every direction: the four quadrants (and
     * the 8 octants) around the snapped centre hold equal counts */
    long q[4] = {0}, oct[8] = {0};
    for (uint32_t i = 0; i < v.vertex_count; i++) {
        float x = v.base[3 * i], z = v.base[3 * i + 2];
        if (x > 0 && z >= 0) q[0]++;
        else if (x <= 0 && z > 0) q[1]++;
        else if (x < 0 && z <= 0) q[2]++;
        else if (x >= 0 && z < 0) q[3]++;
        if (x > 0 && z > 0 && x != z)
            oct[(x > z) + 2 * 0]++;
        if (x < 0 && z < 0 && x != z)
            oct[(-x > -z) + 2 * 1]++;
    }
    assert_int_equal(q[0], q[1]);
    assert_int_equal(q[1], q[2]);
    assert_int_equal(q[2], q[3]);
    assert_int_equal(oct[0], oct[1]); /* mirror about the diagonal */
    assert_int_equal(oct[2], oct[3]);
    /* count per configuration: the integral of the realised density over
     * the disc - sum over levels of annulus area / spacing^2 - bounds it */
    double est = 0, prev = 0;
    for (int L = 0; L < in.levels; L++) {
        double outer = fmin(in.zone_radius_m[L] + in.blend_m[L], 20000);
        double sp = in.level_spacing_m[L];
        est += M_PI * (outer * outer - prev * prev) / (sp * sp);
        prev = outer;
    }
    assert_true(v.vertex_count > 0.6 * est);
    assert_true(v.vertex_count < 1.6 * est);
    /* triangles ~ 2 per vertex */
    assert_true(v.index_count / 3 > 1.9 * v.vertex_count);
    assert_true(v.index_count / 3 < 2.1 * v.vertex_count);
    /* levels: R0 = 2 rho dx / (1 - blend), then doubling to the range */
    assert_float_equal(in.zone_radius_m[0], 2 * in.rho_err * in.near_spacing_m / 0.8, 1e-9);
    for (int L = 1; L < in.levels; L++)
        assert_float_equal(in.zone_radius_m[L], 2 * in.zone_radius_m[L - 1], 1e-9);
    assert_true(in.zone_radius_m[in.levels - 1] + in.blend_m[in.levels - 1] >= 20000);
    assert_true(in.zone_radius_m[in.levels - 2] + in.blend_m[in.levels - 2] < 20000);
    /* spacings: dx, then doubling, each lattice twice the one inside it
     * (the layout-1 morph rule's assumption) */
    for (int L = 1; L < in.levels; L++)
        assert_float_equal(in.level_spacing_m[L], 2 * in.level_spacing_m[L - 1], 0);
    /* blend zone: R0 +- blend_frac R0 (50 m +- 10 m in proportion) */
    assert_float_equal(in.blend_m[0], 0.2 * in.zone_radius_m[0], 1e-9);
    mesh_destroy(m);
}

static double near_spacing(double h, double fov, double lambda, int vh)
{
    mesh_config c;
    mesh_config_default(&c);
    c.range_m = 300;
    c.error_px = 16; /* keeps the narrow-fov meshes small */
    c.lambda_dominant_m = lambda;
    mesh *m = NULL;
    assert_int_equal(mesh_create(&c, &m), OCEAN_OK);
    mesh_camera cam = cam_at(0, h, 0);
    cam.fov_y_deg = fov;
    cam.viewport_h = vh;
    assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
    mesh_info in;
    mesh_get_info(m, &in);
    mesh_destroy(m);
    return in.near_spacing_m;
}

static void test_concentric_scales_with_camera(void **state)
{
    (void)state;
    double s2 = near_spacing(2, 60, 0, 1080), s3000 = near_spacing(3000, 60, 0, 1080);
    assert_true(s3000 > 100 * s2);
    /* binoculars (5 degrees) get a finer core than 60 degrees */
    double s_narrow = near_spacing(200, 5, 0, 1080), s_wide = near_spacing(200, 60, 0, 1080);
    assert_true(s_narrow * 4 <= s_wide);
    /* a bigger viewport (more pixels) gets a finer core too */
    assert_true(near_spacing(200, 60, 0, 4320) < s_wide);
    /* dominant wavelength caps the near spacing: dx <= k lambda */
    double capped = near_spacing(3000, 60, 100, 1080);
    assert_true(capped <= 0.1 * 100);
    assert_true(capped > 0.1 * 100 / 2); /* power of two just below */
    /* power of two, stable within an octave of height */
    assert_true(near_spacing(20, 60, 0, 1080) == near_spacing(21, 60, 0, 1080));
    double l2 = log2(s2);
    assert_true(l2 == floor(l2));
    /* the sea's finest detail floors it */
    assert_true(near_spacing(0.01, 60, 0, 1080) >= 0.02);
}

static void test_concentric_density_follows_rho(void **state)
{
    (void)state;
    mesh *m = make(MESH_CONCENTRIC, 5000, 2);
    mesh_camera cam = cam_at(0, 10, 0);
    assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
    mesh_view v;
    mesh_get_view(m, &v);
    mesh_info in;
    mesh_get_info(m, &in);
    /* seed 000: rho(d) = rho_max e^(-alpha d) + rho_min hits the
     * tessellation factors 8 / 4 / 1 at 0, R0 and R2 = 4 R0 (where the
     * level of spacing 8 dx starts) */
    double b = 1 / (8 * in.near_spacing_m);
    assert_float_equal(mesh_density_target(m, 0), 8 * b, 1e-9 * b);
    assert_float_equal(mesh_density_target(m, in.zone_radius_m[0]), 4 * b, 1e-9 * b);
    assert_float_equal(in.zone_radius_m[2], 4 * in.zone_radius_m[0], 1e-9 * in.zone_radius_m[0]);
    assert_float_equal(in.rho_max * exp(-in.alpha * in.zone_radius_m[2]) + in.rho_min, b, 0.01 * b);
    /* monotone non-increasing */
    for (double d = 0; d < 4000; d += 7.3)
        assert_true(mesh_density_target(m, d + 7.3) <= mesh_density_target(m, d) * (1 + 1e-12));
    /* realised linear density in annuli (sqrt of vertices per area) never
     * below the target and at most the levels' quantisation above it */
    double r_in = 0.5 * in.near_spacing_m;
    int checked = 0;
    while (r_in < 4000) {
        double r_out = r_in * 1.25 + 4 * in.near_spacing_m;
        long n = 0;
        for (uint32_t i = 0; i < v.vertex_count; i++) {
            double d = hypot(v.base[3 * i] + v.origin[0] - cam.pos[0], v.base[3 * i + 2] + v.origin[2] - cam.pos[2]);
            n += d >= r_in && d < r_out;
        }
        double area = M_PI * (r_out * r_out - r_in * r_in);
        double real = sqrt(n / area);
        /* target over the annulus: its value at the outer radius is the
         * lowest, at the inner the highest */
        double t_lo = mesh_density_target(m, r_out), t_hi = mesh_density_target(m, r_in);
        /* at most 4x (seed 000's step from factor 4 to 1 at R1) carried
         * on through R1's blend zone (x 1 + blend_frac), plus counting noise */
        if (real < 0.9 * t_lo || real > 4 * 1.2 * 1.05 * t_hi) {
            print_error("annulus %g..%g m: realised %g /m, target %g..%g\n", r_in, r_out, real, t_lo, t_hi);
            fail();
        }
        checked++;
        r_in = r_out;
    }
    assert_true(checked > 10);
    mesh_destroy(m);
}

static void world_of(const mesh_view *v, uint32_t i, double out[2])
{
    out[0] = v->origin[0] + v->base[3 * i];
    out[1] = v->origin[2] + v->base[3 * i + 2];
}

static void test_concentric_snapping(void **state)
{
    (void)state;
    mesh *m = make(MESH_CONCENTRIC, 3000, 2);
    mesh_camera cam = cam_at(100.01, 20, -50.01);
    assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
    mesh_view a;
    mesh_get_view(m, &a);
    /* start near the middle of the snap cell so the moves below stay in it */
    cam.pos[0] = a.origin[0] + 0.01;
    cam.pos[2] = a.origin[2] - 0.01;
    assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
    mesh_get_view(m, &a);
    mesh_info in;
    mesh_get_info(m, &in);
    double dx = in.near_spacing_m;
    uint32_t nv = a.vertex_count;
    double *wa = malloc(nv * 2 * sizeof *wa);
    assert_non_null(wa);
    for (uint32_t i = 0; i < nv; i++)
        world_of(&a, i, wa + 2 * i);
    double oa[3];
    memcpy(oa, a.origin, sizeof oa);
    uint64_t key = a.topology_key;
    /* sub-spacing moves: identical world positions, same topology */
    double moves[4][2] = {{0.3, 0}, {0, -0.45}, {-0.2, 0.2}, {0.49, 0.49}};
    for (int k = 0; k < 4; k++) {
        mesh_camera c2 = cam;
        c2.pos[0] += moves[k][0] * dx;
        c2.pos[2] += moves[k][1] * dx;
        assert_int_equal(mesh_build(m, &c2), OCEAN_OK);
        mesh_view b;
        mesh_get_view(m, &b);
        mesh_info bi;
        mesh_get_info(m, &bi);
        assert_int_equal(bi.rebuilt, 0);
        assert_true(b.topology_key == key);
        assert_int_equal(b.vertex_count, nv);
        for (uint32_t i = 0; i < nv; i++) {
            double w[2];
            world_of(&b, i, w);
            assert_true(w[0] == wa[2 * i] && w[1] == wa[2 * i + 1]);
        }
    }
    /* a long move: the mesh follows in whole snap steps, the topology
     * stays, and every level-0 vertex lands on a point of the same
     * world-fixed lattice (multiples of dx): vertices never swim */
    mesh_camera c3 = cam;
    c3.pos[0] += 37.77;
    c3.pos[2] -= 12.34;
    assert_int_equal(mesh_build(m, &c3), OCEAN_OK);
    mesh_view b;
    mesh_get_view(m, &b);
    assert_true(b.topology_key == key);
    assert_true(fabs(b.origin[0] - c3.pos[0]) <= 4 * dx + 1e-9);
    assert_true(fabs(b.origin[2] - c3.pos[2]) <= 4 * dx + 1e-9);
    assert_true(b.origin[0] != oa[0]);
    for (uint32_t i = 0; i < nv; i++) {
        if (b.level[i] > 2)
            continue;
        double w[2];
        world_of(&b, i, w);
        double sp = dx;
        assert_true(fabs(w[0] / sp - round(w[0] / sp)) < 1e-9);
        assert_true(fabs(w[1] / sp - round(w[1] / sp)) < 1e-9);
    }
    /* a new height octave changes the plan, hence the key */
    mesh_camera c4 = cam;
    c4.pos[1] = 200;
    assert_int_equal(mesh_build(m, &c4), OCEAN_OK);
    mesh_get_view(m, &b);
    assert_true(b.topology_key != key);
    free(wa);
    mesh_destroy(m);
}

static void sampler_plane(void *ctx, double x, double z, double d[3])
{
    const double *o = ctx; /* reference point: keeps the numbers small */
    d[0] = 0.01 * (z - o[1]);
    d[1] = 0.5 + 0.03 * (x - o[0]) - 0.02 * (z - o[1]);
    d[2] = -0.01 * (x - o[0]);
}

static void sampler_waves(void *ctx, double x, double z, double d[3])
{
    const double *o = ctx;
    double px = x - o[0], pz = z - o[1];
    d[1] = 0.7 * cos(0.05 * px + 0.02 * pz) + 0.2 * sin(0.31 * px - 0.17 * pz + 1);
    d[0] = -0.3 * sin(0.05 * px + 0.02 * pz);
    d[2] = -0.12 * sin(0.05 * px + 0.02 * pz);
}

typedef struct counting {
    const double *ref;
    long calls;
} counting;

static void sampler_counted(void *ctx, double x, double z, double d[3])
{
    counting *c = ctx;
    c->calls++;
    sampler_plane((void *)c->ref, x, z, d);
}

static void test_displace_and_morph(void **state)
{
    (void)state;
    mesh_config mcfg;
    mesh_config_default(&mcfg);
    mcfg.range_m = 2000;
    mcfg.error_px = 4;
    mcfg.far_skirt = 0; /* every vertex sampled (the skirt has its own test) */
    mesh *m = NULL;
    assert_int_equal(mesh_create(&mcfg, &m), OCEAN_OK);
    mesh_camera cam = cam_at(40.5, 10, 20.25);
    assert_int_equal(mesh_displace(m, sampler_plane, NULL), OCEAN_ESTATE);
    assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
    mesh_view v;
    mesh_get_view(m, &v);
    mesh_info in;
    mesh_get_info(m, &in);
    /* morph weights: 0 inside the blend zone, 1 beyond it, in between
     * inside it, by distance from the (true) camera */
    int inside = 0;
    for (uint32_t i = 0; i < v.vertex_count; i++) {
        int L = v.level[i];
        double d = hypot(v.base[3 * i] + v.origin[0] - cam.pos[0], v.base[3 * i + 2] + v.origin[2] - cam.pos[2]);
        float w = v.morph[i];
        assert_true(w >= 0 && w <= 1);
        if (L + 1 >= v.levels) {
            /* the last level does not morph; the far skirt beyond the
             * range is flat with weight 1 */
            assert_true(w == 0 || (w == 1 && d > 2000.0));
            continue;
        }
        double r = in.zone_radius_m[L], b = in.blend_m[L];
        if (d <= r - b)
            assert_true(w == 0);
        else if (d >= r + b)
            assert_true(w == 1);
        else {
            inside++;
            assert_true(fabs(w - 0.5) <= 0.5);
        }
    }
    assert_true(inside > 0);
    /* a linear surface is reproduced exactly, morphing or not: the mesh
     * error is zero (up to float positions) */
    double ref[2] = {cam.pos[0], cam.pos[2]};
    assert_int_equal(mesh_displace(m, sampler_plane, ref), OCEAN_OK);
    mesh_get_view(m, &v);
    for (uint32_t i = 0; i < v.vertex_count; i++) {
        double d[3];
        sampler_plane(ref, v.origin[0] + v.base[3 * i], v.origin[2] + v.base[3 * i + 2], d);
        for (int k = 0; k < 3; k++)
            assert_true(fabs(v.positions[3 * i + k] - (v.base[3 * i + k] + d[k])) <= 1e-3 + 1e-6 * fabs(v.base[3 * i + k]));
    }
    double err = -1;
    assert_int_equal(mesh_error_px(m, &cam, sampler_plane, ref, &err), OCEAN_OK);
    assert_true(err >= 0 && err < 0.05);
    /* A morphing vertex's coarse corners are vertices already sampled:
     * one sample per vertex (plus the rare corner that is no vertex), not
     * up to four, and the same again once the corners are known. */
    counting cnt = {ref, 0};
    assert_int_equal(mesh_displace(m, sampler_counted, &cnt), OCEAN_OK);
    long first = cnt.calls;
    cnt.calls = 0;
    assert_int_equal(mesh_displace(m, sampler_counted, &cnt), OCEAN_OK);
    if (!(first >= (long)v.vertex_count && first <= (long)(1.02 * v.vertex_count) && cnt.calls == first))
        fail_msg("samples per displacement %ld then %ld for %u vertices", first, cnt.calls, v.vertex_count);
    /* a fully morphed vertex sits on the coarser level's surface; an
     * unmorphed one on the true surface */
    assert_int_equal(mesh_displace(m, sampler_waves, ref), OCEAN_OK);
    mesh_get_view(m, &v);
    int odd_full = 0;
    for (uint32_t i = 0; i < v.vertex_count; i++) {
        double d[3];
        double wx = v.origin[0] + v.base[3 * i], wz = v.origin[2] + v.base[3 * i + 2];
        sampler_waves(ref, wx, wz, d);
        double dev = fabs(v.positions[3 * i + 1] - d[1]);
        if (v.morph[i] == 0)
            assert_true(dev < 1e-4);
        if (v.morph[i] == 1 && v.level[i] + 1 < v.levels) {
            double S = in.level_spacing_m[v.level[i] + 1];
            double lx = v.base[3 * i] / S, lz = v.base[3 * i + 2] / S;
            if (lx != floor(lx) && lz == floor(lz)) {
                /* on a coarse x edge: the coarse value is linear along it */
                double x0 = floor(lx) * S, fx = lx - floor(lx), a[3], b[3];
                sampler_waves(ref, v.origin[0] + x0, wz, a);
                sampler_waves(ref, v.origin[0] + x0 + S, wz, b);
                assert_true(fabs(v.positions[3 * i + 1] - (a[1] + fx * (b[1] - a[1]))) < 1e-4);
                odd_full++;
            }
        }
    }
    assert_true(odd_full > 0);
    /* a wavy surface has a real, finite error, and a tighter budget
     * lowers it */
    assert_int_equal(mesh_error_px(m, &cam, sampler_waves, ref, &err), OCEAN_OK);
    assert_true(err > 0 && isfinite(err));
    mesh *fine = make(MESH_CONCENTRIC, 2000, 2);
    assert_int_equal(mesh_build(fine, &cam), OCEAN_OK);
    assert_int_equal(mesh_displace(fine, sampler_waves, ref), OCEAN_OK);
    double err_fine = -1;
    assert_int_equal(mesh_error_px(fine, &cam, sampler_waves, ref, &err_fine), OCEAN_OK);
    assert_true(err_fine < err);
    mesh_destroy(fine);
    mesh_destroy(m);
}

/* phase reference in the sampler keeps the test's own arithmetic exact */
static void sampler_far(void *ctx, double x, double z, double d[3])
{
    const double *o = ctx;
    double px = x - o[0], pz = z - o[1];
    d[0] = 0.1 * sin(0.9 * px);
    d[1] = 0.25 * cos(1.3 * px + 0.7 * pz);
    d[2] = 0.1 * sin(1.1 * pz);
}

static void test_far_from_origin_precision(void **state)
{
    (void)state;
    const double far = 1e7;
    mesh *near_m = make(MESH_CONCENTRIC, 500, 2), *far_m = make(MESH_CONCENTRIC, 500, 2);
    mesh_camera cn = cam_at(1.3, 8, -2.6), cf = cam_at(far + 1.3, 8, -far - 2.6);
    assert_int_equal(mesh_build(near_m, &cn), OCEAN_OK);
    assert_int_equal(mesh_build(far_m, &cf), OCEAN_OK);
    mesh_view a, b;
    mesh_get_view(near_m, &a);
    mesh_get_view(far_m, &b);
    /* the origin carries the offset in double; floats are identical */
    assert_int_equal(a.vertex_count, b.vertex_count);
    assert_true(b.origin[0] - a.origin[0] == far);
    assert_true(a.origin[2] - b.origin[2] == far);
    assert_memory_equal(a.base, b.base, a.vertex_count * 3 * sizeof(float));
    assert_true(a.topology_key == b.topology_key);
    /* displaced positions keep sub-millimetre precision 1e7 m out: the
     * same surface, shifted, gives the same floats */
    double rn[2] = {0, 0}, rf[2] = {far, -far};
    assert_int_equal(mesh_displace(near_m, sampler_far, rn), OCEAN_OK);
    assert_int_equal(mesh_displace(far_m, sampler_far, rf), OCEAN_OK);
    mesh_get_view(near_m, &a);
    mesh_get_view(far_m, &b);
    double worst = 0;
    for (uint32_t i = 0; i < 3 * a.vertex_count; i++)
        worst = fmax(worst, fabs(a.positions[i] - b.positions[i]));
    assert_true(worst < 1e-4);
    /* and they match the exact double evaluation */
    for (uint32_t i = 0; i < b.vertex_count; i += 7) {
        if (b.morph[i] != 0)
            continue;
        double d[3];
        sampler_far(rf, b.origin[0] + b.base[3 * i], b.origin[2] + b.base[3 * i + 2], d);
        assert_true(fabs(b.positions[3 * i + 1] - d[1]) < 1e-5);
    }
    mesh_destroy(near_m);
    mesh_destroy(far_m);
}

static void test_topology_key(void **state)
{
    (void)state;
    mesh *m1 = make(MESH_CONCENTRIC, 3000, 2), *m2 = make(MESH_CONCENTRIC, 3000, 2);
    mesh_camera c1 = cam_at(0, 20, 0), c2 = cam_at(5555.5, 22, -777.7);
    c2.yaw_deg = 123;
    assert_int_equal(mesh_build(m1, &c1), OCEAN_OK);
    assert_int_equal(mesh_build(m2, &c2), OCEAN_OK);
    mesh_view a, b;
    mesh_get_view(m1, &a);
    mesh_get_view(m2, &b);
    /* equal keys: identical indices and base, so a client keeps its buffers */
    assert_true(a.topology_key == b.topology_key);
    assert_int_equal(a.index_count, b.index_count);
    assert_memory_equal(a.indices, b.indices, a.index_count * sizeof(uint32_t));
    assert_memory_equal(a.base, b.base, a.vertex_count * 3 * sizeof(float));
    /* different plan, different key; different kinds differ too */
    mesh *m3 = make(MESH_CONCENTRIC, 3000, 4);
    assert_int_equal(mesh_build(m3, &c1), OCEAN_OK);
    mesh_view c;
    mesh_get_view(m3, &c);
    assert_true(c.topology_key != a.topology_key);
    mesh *m4 = make(MESH_CHUNKED, 3000, 2);
    assert_int_equal(mesh_build(m4, &c1), OCEAN_OK);
    mesh_view d;
    mesh_get_view(m4, &d);
    assert_true(d.topology_key != a.topology_key);
    mesh_destroy(m1);
    mesh_destroy(m2);
    mesh_destroy(m3);
    mesh_destroy(m4);
}

static void test_hostile_camera_keeps_mesh(void **state)
{
    (void)state;
    mesh *m = make(MESH_CONCENTRIC, 1000, 2);
    mesh_camera cam = cam_at(0, 10, 0);
    assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
    mesh_view a;
    mesh_get_view(m, &a);
    uint32_t nv = a.vertex_count;
    uint64_t key = a.topology_key;
    mesh_camera bad = cam;
    bad.pos[1] = NAN;
    assert_int_equal(mesh_build(m, &bad), OCEAN_EINVAL);
    bad = cam;
    bad.fov_y_deg = 180;
    assert_int_equal(mesh_build(m, &bad), OCEAN_EINVAL);
    bad = cam;
    bad.pos[0] = 1e300;
    assert_int_equal(mesh_build(m, &bad), OCEAN_EINVAL);
    mesh_view b;
    mesh_get_view(m, &b);
    assert_int_equal(b.vertex_count, nv);
    assert_true(b.topology_key == key);
    assert_int_equal(mesh_build(NULL, &cam), OCEAN_EINVAL);
    assert_int_equal(mesh_displace(m, NULL, NULL), OCEAN_EINVAL);
    /* camera below the sea surface or exactly on it still gets a mesh */
    cam.pos[1] = -5;
    assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
    mesh_get_view(m, &b);
    check_topology(&b, b.origin[0], b.origin[2], NULL);
    mesh_destroy(m);
    mesh_destroy(NULL);
}

/* ---- chunked ---------------------------------------------------------- */

static int tile_level_at(const mesh_view *v, double tile, double quads, double x, double z)
{
    /* the level of a tile = the level of the vertex at its centre */
    (void)quads;
    for (uint32_t i = 0; i < v->vertex_count; i++)
        if (fabs(v->base[3 * i] - x) < 1e-3 && fabs(v->base[3 * i + 2] - z) < 1e-3)
            return v->level[i];
    (void)tile;
    return -1;
}

static void test_chunked(void **state)
{
    (void)state;
    mesh *m = make(MESH_CHUNKED, 90000, 1);
    mesh_camera cam = cam_at(70.0, 30, -10.0);
    assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
    mesh_view v;
    mesh_get_view(m, &v);
    check_topology(&v, 0, 0, NULL);
    check_no_tjunction(&v, 8);
    /* 6 x 6 tiles of 128 m, up to 4 levels, 4-neighbours at most one apart */
    int lv[6][6];
    int maxl = 0, minl = 9;
    for (int b = 0; b < 6; b++)
        for (int a = 0; a < 6; a++) {
            lv[b][a] = tile_level_at(&v, 128, 32, a * 128 + 64, b * 128 + 64);
            assert_true(lv[b][a] >= 0 && lv[b][a] < 4);
            maxl = lv[b][a] > maxl ? lv[b][a] : maxl;
            minl = lv[b][a] < minl ? lv[b][a] : minl;
        }
    assert_int_equal(minl, 0);
    assert_int_equal(maxl, 3);
    assert_int_equal(v.levels, 4);
    for (int b = 0; b < 6; b++)
        for (int a = 0; a < 6; a++) {
            if (a + 1 < 6)
                assert_true(abs(lv[b][a] - lv[b][a + 1]) <= 1);
            if (b + 1 < 6)
                assert_true(abs(lv[b][a] - lv[b + 1][a]) <= 1);
        }
    /* the four tiles round the camera are finest: 32 x 32 quads each */
    assert_int_equal(lv[2][2], 0);
    assert_int_equal(lv[3][3], 0);
    /* vertex count: sum over tiles of (quads_L + 1)^2, less shared edges,
     * plus one centre per stitched coarse cell; bounded by the parts */
    long sum = 0, inner = 0;
    for (int b = 0; b < 6; b++)
        for (int a = 0; a < 6; a++) {
            long q = 32 >> lv[b][a];
            sum += (q + 1) * (q + 1);
            inner += (q - 1) * (q - 1);
        }
    assert_true(v.vertex_count < sum);
    assert_true(v.vertex_count > inner);
    /* grid covers 768 m around the camera and snaps to the tile */
    assert_true(v.origin[0] == -384 + 128 && v.origin[2] == -384);
    /* stitching: along every edge between levels the fine vertices are
     * shared by the coarse tile's triangles (checked by the topology and
     * T-junction checks above) and fully morphed onto the coarse edge */
    int stitched = 0;
    for (uint32_t i = 0; i < v.vertex_count; i++) {
        double x = v.base[3 * i], z = v.base[3 * i + 2];
        double fx = x / 128, fz = z / 128;
        int on_x = fabs(fx - round(fx)) < 1e-9, on_z = fabs(fz - round(fz)) < 1e-9;
        if (!(on_x || on_z) || (on_x && on_z))
            continue;
        int a0, b0, a1, b1;
        if (on_x) {
            a0 = (int)round(fx) - 1; a1 = a0 + 1; b0 = b1 = (int)floor(fz);
        } else {
            b0 = (int)round(fz) - 1; b1 = b0 + 1; a0 = a1 = (int)floor(fx);
        }
        if (a0 < 0 || b0 < 0 || a1 > 5 || b1 > 5 || lv[b0][a0] == lv[b1][a1])
            continue;
        int fine = lv[b0][a0] < lv[b1][a1] ? lv[b0][a0] : lv[b1][a1];
        assert_int_equal(v.level[i], fine);
        assert_true(v.morph[i] == 1.0f);
        stitched++;
    }
    assert_true(stitched > 0);
    /* sub-tile moves: same world positions */
    uint64_t key = v.topology_key;
    double o0 = v.origin[0], o2 = v.origin[2];
    mesh_camera c2 = cam;
    c2.pos[0] += 40;
    c2.pos[2] -= 30;
    assert_int_equal(mesh_build(m, &c2), OCEAN_OK);
    mesh_get_view(m, &v);
    assert_true(v.origin[0] == o0 && v.origin[2] == o2 && v.topology_key == key);
    /* a whole tile further: grid moves one tile, topology kept */
    c2.pos[0] += 128;
    assert_int_equal(mesh_build(m, &c2), OCEAN_OK);
    mesh_get_view(m, &v);
    assert_true(v.origin[0] == o0 + 128 && v.topology_key == key);
    mesh_destroy(m);

    /* other shapes: 1 level, odd tile counts */
    mesh_config c;
    mesh_config_default(&c);
    c.kind = MESH_CHUNKED;
    c.chunk_tiles = 5;
    c.chunk_quads = 8;
    c.chunk_levels = 1;
    assert_int_equal(mesh_create(&c, &m), OCEAN_OK);
    assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
    mesh_get_view(m, &v);
    assert_int_equal(v.vertex_count, 41 * 41);
    assert_int_equal(v.index_count, 40 * 40 * 6);
    check_topology(&v, 0, 0, NULL);
    mesh_destroy(m);
}

/* ---- projected -------------------------------------------------------- */

typedef struct tri_grid {
    const mesh_view *v;
    double minx, minz, cell;
    long nx, nz;
    long *head, *next; /* triangle buckets (a triangle in every bucket of its box) */
    long *item;
    long nitems;
} tri_grid;

static int point_in_mesh(const mesh_view *v, double x, double z)
{
    /* brute force over triangles: coverage tests use few points */
    for (uint32_t t = 0; t < v->index_count; t += 3) {
        const float *a = v->base + 3 * v->indices[t], *b = v->base + 3 * v->indices[t + 1],
                    *c = v->base + 3 * v->indices[t + 2];
        double d1 = (z - a[2]) * (b[0] - a[0]) - (x - a[0]) * (b[2] - a[2]);
        double d2 = (z - b[2]) * (c[0] - b[0]) - (x - b[0]) * (c[2] - b[2]);
        double d3 = (z - c[2]) * (a[0] - c[0]) - (x - c[0]) * (a[2] - c[2]);
        /* up-facing triangles: the point is inside when all three agree */
        double eps = 1e-6;
        if ((d1 <= eps && d2 <= eps && d3 <= eps) || (d1 >= -eps && d2 >= -eps && d3 >= -eps))
            return 1;
    }
    return 0;
}

static void check_projected_covers(mesh_camera cam, double margin, double range)
{
    mesh_config c;
    mesh_config_default(&c);
    c.kind = MESH_PROJECTED;
    c.grid_w = 48;
    c.grid_h = 64;
    c.margin_m = margin;
    c.range_m = range;
    mesh *m = NULL;
    assert_int_equal(mesh_create(&c, &m), OCEAN_OK);
    assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
    mesh_view v;
    mesh_get_view(m, &v);
    check_topology(&v, cam.pos[0], cam.pos[2], NULL);
    /* horizon handling: nothing beyond the range */
    for (uint32_t i = 0; i < v.vertex_count; i++)
        assert_true(hypot(v.base[3 * i], v.base[3 * i + 2]) <= range * (1 + 1e-5));
    double f[3], r[3], u[3];
    mesh_camera_basis(&cam, f, r, u);
    double ty = tan(0.5 * cam.fov_y_deg * M_PI / 180), tx = ty * cam.viewport_w / cam.viewport_h;
    int hits = 0;
    const int n = 23;
    for (int b = 0; b <= n; b++)
        for (int a = 0; a <= n; a++) {
            double sx = -1 + 2.0 * a / n, sy = -1 + 2.0 * b / n, d[3];
            for (int k = 0; k < 3; k++)
                d[k] = f[k] + sx * tx * r[k] + sy * ty * u[k];
            /* the sea the pixel sees lies between the planes y = -margin
             * and y = +margin; every base point there must be meshed */
            double planes[3] = {-margin, 0, margin};
            for (int p = 0; p < 3; p++) {
                if (fabs(d[1]) < 1e-12)
                    continue;
                double t = (planes[p] - cam.pos[1]) / d[1];
                if (t <= 0)
                    continue;
                double x = t * d[0], z = t * d[2];
                if (hypot(x, z) > range * 0.999)
                    continue;
                hits++;
                if (!point_in_mesh(&v, x, z)) {
                    print_error("screen (%g, %g) plane %g: sea at (%g, %g) not covered\n", sx, sy, planes[p], x, z);
                    fail();
                }
            }
        }
    assert_true(hits > 0);
    mesh_destroy(m);
}

static void test_projected(void **state)
{
    (void)state;
    /* level at 20 m, looking slightly down; the horizon is on screen */
    mesh_camera cam = cam_at(100, 20, 200);
    cam.pitch_deg = -10;
    cam.yaw_deg = 30;
    check_projected_covers(cam, 3, 20000);
    /* steep, rolled */
    cam.pitch_deg = -50;
    cam.roll_deg = 25;
    check_projected_covers(cam, 3, 20000);
    /* nadir from 2 000 m: a full circle round the ground point */
    cam = cam_at(0, 2000, 0);
    cam.pitch_deg = -90;
    check_projected_covers(cam, 5, 90000);
    /* bridge camera inside the wave slab (2 m up, 6 m margin) */
    cam = cam_at(5, 2, 5);
    cam.pitch_deg = -5;
    check_projected_covers(cam, 6, 5000);
    /* narrow fov toward the horizon */
    cam = cam_at(0, 50, 0);
    cam.fov_y_deg = 4;
    cam.pitch_deg = -1;
    check_projected_covers(cam, 2, 90000);
    /* looking at the sky: a valid mesh still */
    cam = cam_at(0, 50, 0);
    cam.pitch_deg = 60;
    mesh *m = make(MESH_PROJECTED, 10000, 1);
    assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
    mesh_view v;
    mesh_get_view(m, &v);
    check_topology(&v, 0, 0, NULL);
    /* moving the camera keeps the topology (positions only) */
    cam.pitch_deg = -10;
    assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
    mesh_get_view(m, &v);
    uint64_t key = v.topology_key;
    cam.pos[0] += 17;
    cam.yaw_deg += 10;
    assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
    mesh_get_view(m, &v);
    assert_true(v.topology_key == key);
    assert_int_equal(v.vertex_count, 256 * 256);
    mesh_destroy(m);
}

static void test_obj_output(void **state)
{
    (void)state;
    mesh *m = make(MESH_CHUNKED, 1000, 1);
    mesh_camera cam = cam_at(0, 10, 0);
    FILE *f = tmpfile();
    assert_non_null(f);
    assert_int_equal(mesh_write_obj(m, f), OCEAN_ESTATE);
    assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
    double ref[2] = {0, 0};
    assert_int_equal(mesh_displace(m, sampler_waves, ref), OCEAN_OK);
    assert_int_equal(mesh_write_obj(m, f), OCEAN_OK);
    rewind(f);
    char line[256];
    long nvl = 0, nfl = 0;
    uint32_t maxi = 0;
    while (fgets(line, sizeof line, f)) {
        if (line[0] == 'v' && line[1] == ' ')
            nvl++;
        if (line[0] == 'f' && line[1] == ' ') {
            unsigned a, b, c;
            assert_int_equal(sscanf(line + 2, "%u %u %u", &a, &b, &c), 3);
            assert_true(a >= 1 && b >= 1 && c >= 1);
            maxi = a > maxi ? a : maxi;
            nfl++;
        }
    }
    fclose(f);
    mesh_view v;
    mesh_get_view(m, &v);
    assert_int_equal(nvl, v.vertex_count);
    assert_int_equal(nfl, v.index_count / 3);
    assert_true(maxi <= v.vertex_count);
    mesh_destroy(m);
}

/* mesh_estimate_vertices (issue 15, the mesh bomb): the estimate must bound
 * the count the build really makes (a server refuses on it before any
 * allocation) without overstating it by more than 2x (or ordinary cameras
 * would be refused), for concentric meshes over heights, fovs and ranges;
 * and the 1-degree 1080p camera at 25 m of the report must price in the
 * millions (it built 21 M vertices), for an estimate alone. */
static void test_estimate_vertices(void **state)
{
    (void)state;
    const double hs[] = {2, 25, 300}, fovs[] = {20, 60, 120, 175}, ranges[] = {200, 2000};
    for (size_t a = 0; a < 3; a++)
        for (size_t b = 0; b < 4; b++)
            for (size_t r = 0; r < 2; r++) {
                mesh_config c;
                mesh_config_default(&c);
                c.range_m = ranges[r];
                c.error_px = 16;
                mesh_camera cam = cam_at(0, hs[a], 0);
                cam.fov_y_deg = fovs[b];
                double est = 0;
                assert_int_equal(mesh_estimate_vertices(&c, &cam, &est), OCEAN_OK);
                mesh *m = NULL;
                assert_int_equal(mesh_create(&c, &m), OCEAN_OK);
                assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
                mesh_view v;
                mesh_get_view(m, &v);

                if (!(est >= v.vertex_count && est <= 2.0 * v.vertex_count + 128))
                    fail_msg("h %g fov %g range %g: estimate %g for %u built", hs[a], fovs[b],
                             ranges[r], est, v.vertex_count);
                mesh_destroy(m);
            }
    mesh_config c;
    mesh_config_default(&c);
    c.range_m = 10000;
    c.error_px = 16;
    mesh_camera bomb = cam_at(0, 25, 0);
    bomb.fov_y_deg = 1;
    double est = 0;
    assert_int_equal(mesh_estimate_vertices(&c, &bomb, &est), OCEAN_OK);
    assert_true(est > 1e6);
    /* the protocol's extremes are valid cameras (PROTOCOL.md, CAMERA) */
    bomb.fov_y_deg = 0.005f;
    assert_int_equal(mesh_estimate_vertices(&c, &bomb, &est), OCEAN_OK);
    assert_true(est > 1e9);
    mesh_camera far = cam_at(5e9, 5e6, -5e9);
    far.fov_y_deg = 175;
    assert_int_equal(mesh_camera_validate(&far, NULL, 0), OCEAN_OK);
    assert_int_equal(mesh_estimate_vertices(&c, &far, &est), OCEAN_OK);
    far.fov_y_deg = 180;
    assert_int_equal(mesh_estimate_vertices(&c, &far, &est), OCEAN_EINVAL);
    assert_int_equal(mesh_estimate_vertices(NULL, &far, &est), OCEAN_EINVAL);
}

/* A vertex of level L on the edge of a coarser cell (it shares a triangle
 * with a vertex of a coarser level) must sit on that cell's coarse edge:
 * morph weight 1, or the two levels disagree there and the surface pops
 * or cracks.  Over error budgets (the daemon's 16 px included: there rho
 * is clamped and the zones are barely wider than the snapping offset)
 * and camera positions anywhere in a snapping cell. */
static void test_concentric_boundary_fully_morphed(void **state)
{
    (void)state;
    const double budgets[] = {1, 2, 4, 8, 16, 32};
    const double heights[] = {2, 25, 300};
    int checked = 0;
    for (int b = 0; b < 6; b++)
        for (int hi = 0; hi < 3; hi++)
            /* Nine camera offsets; three spread over the same cell (0, 4,
             * 8) under the sanitizers and at 1 px, whose meshes of 0.7-1.5
             * M vertices (six times the daemon's server.max_mesh_vertices)
             * took 14 of this test's 17 s at nine. */
            for (int k = 0; k < 9; k += sanitized() || budgets[b] < 2 ? 4 : 1) {
                if (budgets[b] < 4 && heights[hi] < 25 && sanitized())
                    continue;
                mesh *m = make(MESH_CONCENTRIC, sanitized() ? 2000 : 5000, budgets[b]);
                /* offsets spread over a snapping cell (8 level-0 spacings) */
                mesh_camera cam = cam_at(1000.0 + 3.7 * k * k, heights[hi], -200.0 + 5.3 * k);
                assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
                mesh_view v;
                mesh_get_view(m, &v);
                for (uint32_t t = 0; t < v.index_count; t += 3) {
                    const uint32_t *tri = v.indices + t;
                    int lmax = 0;
                    for (int q = 0; q < 3; q++)
                        lmax = v.level[tri[q]] > lmax ? v.level[tri[q]] : lmax;
                    for (int q = 0; q < 3; q++) {
                        uint32_t i = tri[q];
                        if (v.level[i] < lmax) {
                            checked++;
                            if (v.morph[i] != 1.0f)
                                fail_msg("budget %g px, height %g m, camera %d: level-%d vertex at "
                                         "(%.2f, %.2f) on a level-%d cell has morph %g", budgets[b],
                                         heights[hi], k, v.level[i], v.base[3 * i] + v.origin[0],
                                         v.base[3 * i + 2] + v.origin[2], lmax, v.morph[i]);
                        }
                    }
                }
                mesh_destroy(m);
            }
    assert_true(checked > 1000);
}

/* The flat mesh morphed as PROTOCOL.md "Mesh in layout 1" says (written
 * here from the spec's text: weight by smoothstep over R_L +- b_L, the
 * flat position slid onto the coarser lattice, p - w (p - g floor(p/g +
 * 1/2))) turns no triangle over, at any camera: heights from 1 m to 10 km,
 * the camera anywhere in its snapping cell, the daemon's 16 px budget and
 * a finer one.  With a lattice four times the one inside it (the plan
 * before), vertices a quarter and a half coarse cell along slid different
 * distances and one overtook the other. */
static double morph_flat(const mesh_view *v, const mesh_info *in, const double cam[3], uint32_t i, int axis)
{
    int L = v->level[i];
    double p = v->base[3 * i + axis];
    if (L + 1 >= in->levels)
        return p;
    double d = hypot(v->origin[0] + v->base[3 * i] - cam[0], v->origin[2] + v->base[3 * i + 2] - cam[2]);
    double R = in->zone_radius_m[L], b = in->blend_m[L], w;
    if (b > 0) {
        double u = fmin(fmax((d - (R - b)) / (2 * b), 0), 1);
        w = u * u * (3 - 2 * u);
    } else {
        w = d >= R;
    }
    double g = in->level_spacing_m[L + 1];
    return p - w * (p - g * floor(p / g + 0.5));
}

static void test_layout1_morph_keeps_orientation(void **state)
{
    (void)state;
    const double heights[] = {1, 3, 10, 25, 80, 300, 1500, 10000};
    /* budget px, blend_frac: the daemon's, a finer budget, the widest and
     * the narrowest blend a concentric mesh takes */
    const double cfgs[][2] = {{16, 0.2}, {4, 0.2}, {16, MESH_CONCENTRIC_BLEND_MAX}, {16, MESH_CONCENTRIC_BLEND_MIN}};
    long checked = 0, turned = 0;
    for (int b = 0; b < 4; b++)
        for (int hi = 0; hi < 8; hi++)
            for (int k = 0; k < 6; k += sanitized() ? 2 : 1) {
                mesh_config c;
                mesh_config_default(&c);
                c.range_m = 10000;
                c.error_px = cfgs[b][0];
                c.blend_frac = cfgs[b][1];
                mesh *m = NULL;
                assert_int_equal(mesh_create(&c, &m), OCEAN_OK);
                mesh_camera cam = cam_at(311.0 + 1.37 * k * k, heights[hi], -57.0 + 2.9 * k);
                assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
                mesh_view v;
                mesh_get_view(m, &v);
                mesh_info in;
                mesh_get_info(m, &in);
                for (int L = 1; L < in.levels; L++)
                    assert_true(in.level_spacing_m[L] <= 2 * in.level_spacing_m[L - 1]);
                for (uint32_t t = 0; t < v.index_count; t += 3) {
                    const uint32_t *tri = v.indices + t;
                    double a[3][2], f[3][2];
                    for (int q = 0; q < 3; q++) {
                        f[q][0] = v.base[3 * tri[q]];
                        f[q][1] = v.base[3 * tri[q] + 2];
                        a[q][0] = morph_flat(&v, &in, cam.pos, tri[q], 0);
                        a[q][1] = morph_flat(&v, &in, cam.pos, tri[q], 2);
                    }
                    double c0 = (f[1][0] - f[0][0]) * (f[2][1] - f[0][1]) - (f[1][1] - f[0][1]) * (f[2][0] - f[0][0]);
                    double c1 = (a[1][0] - a[0][0]) * (a[2][1] - a[0][1]) - (a[1][1] - a[0][1]) * (a[2][0] - a[0][0]);
                    checked++;
                    /* collapsing to a line where a vertex lands on its coarse
                     * neighbour is the morph's purpose; turning over is not */
                    if (c0 * c1 < -1e-9 * c0 * c0 && turned++ < 3)
                        print_error("budget %g px, blend %g, height %g m, camera %d: triangle %u turned over "
                                    "(area %g -> %g)\n", cfgs[b][0], cfgs[b][1], heights[hi], k, t / 3, 0.5 * c0,
                                    0.5 * c1);
                }
                mesh_destroy(m);
            }
    print_message("%ld triangles morphed, %ld turned over\n", checked, turned);
    assert_true(checked > 100000);
    assert_int_equal(turned, 0);
    /* blends outside them turn triangles over (0.1 did at 25 m; 0.25 and
     * up reach the fanned cells at a level's inner edge): refused for
     * concentric meshes, not for chunked ones (their blend is their own) */
    const double refused[] = {0, 0.1, MESH_CONCENTRIC_BLEND_MAX + 0.01, 0.45};
    for (int i = 0; i < 4; i++) {
        mesh_config c;
        mesh_config_default(&c);
        c.blend_frac = refused[i];
        char why[200];
        assert_int_equal(mesh_config_validate(&c, why, sizeof why), OCEAN_EINVAL);
        assert_non_null(strstr(why, "blend_frac"));
        c.kind = MESH_CHUNKED;
        assert_int_equal(mesh_config_validate(&c, why, sizeof why), OCEAN_OK);
    }
}

/* From 1500 m (the flight scene's camera) the horizon is 138 km away
 * (sqrt(2 R h), R = 6371 km) and the 10 km mesh edge would show: the far
 * skirt carries the surface out past it, still one watertight disc with
 * no T-junction, flat and fully morphed beyond the range. */
static void test_concentric_far_skirt(void **state)
{
    (void)state;
    const double hs[] = {300, 1500, 10000};
    for (int i = 0; i < 3; i++) {
        mesh *m = make(MESH_CONCENTRIC, 10000, 4);
        mesh_camera cam = cam_at(123.4, hs[i], -56.7);
        assert_int_equal(mesh_build(m, &cam), OCEAN_OK);
        mesh_view v;
        mesh_get_view(m, &v);
        double minr;
        long nb = check_topology(&v, v.origin[0], v.origin[2], &minr);
        assert_true(nb > 0);
        check_no_tjunction(&v, 1.0);
        double horizon = sqrt(2 * 6371008.8 * hs[i]);
        if (!(minr >= horizon))
            fail_msg("camera at %g m: mesh edge at %.0f m, horizon %.0f m", hs[i], minr, horizon);
        assert_true(v.levels <= 16);
        double ref[2] = {0, 0};
        assert_int_equal(mesh_displace(m, sampler_waves, ref), OCEAN_OK);
        mesh_get_view(m, &v);
        int far = 0;
        for (uint32_t k = 0; k < v.vertex_count; k++) {
            double r = hypot(v.base[3 * k], v.base[3 * k + 2]);
            /* the last level's cells reach past the range (up to its zone
             * radius, < 3 x the range); beyond that only the skirt */
            if (r > 3 * 10000) {
                far++;
                assert_true(v.morph[k] == 1.0f && v.positions[3 * k + 1] == 0.0f);
            }
        }
        assert_true(far > 0);
        mesh_destroy(m);
    }
    mesh_config c;
    mesh_config_default(&c);
    c.far_skirt = 2;
    mesh *bad = NULL;
    assert_int_equal(mesh_create(&c, &bad), OCEAN_EINVAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_config_and_camera),
        cmocka_unit_test(test_lambda_dominant),
        cmocka_unit_test(test_roughness_follows_choppiness),
        cmocka_unit_test(test_concentric_max_levels),
        cmocka_unit_test(test_concentric_watertight_full_range),
        cmocka_unit_test(test_concentric_no_tjunctions),
        cmocka_unit_test(test_concentric_counts_and_symmetry),
        cmocka_unit_test(test_concentric_scales_with_camera),
        cmocka_unit_test(test_concentric_density_follows_rho),
        cmocka_unit_test(test_concentric_snapping),
        cmocka_unit_test(test_displace_and_morph),
        cmocka_unit_test(test_concentric_boundary_fully_morphed),
        cmocka_unit_test(test_layout1_morph_keeps_orientation),
        cmocka_unit_test(test_concentric_far_skirt),
        cmocka_unit_test(test_far_from_origin_precision),
        cmocka_unit_test(test_topology_key),
        cmocka_unit_test(test_hostile_camera_keeps_mesh),
        cmocka_unit_test(test_chunked),
        cmocka_unit_test(test_estimate_vertices),
        cmocka_unit_test(test_projected),
        cmocka_unit_test(test_obj_output),
    };
    const char *filter = getenv("MESH_TEST_FILTER"); /* run one test while debugging */
    if (filter && *filter)
        cmocka_set_test_filter(filter);
    return cmocka_run_group_tests(tests, NULL, NULL);
}
