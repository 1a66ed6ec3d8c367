/*
 * srv_cascade.c - the cascade tile layout (see srv_cascade.h).
 *
 * Per batch:
 *   1. plan every job: from its camera, the (cascade, mip) pairs it reads
 *      and the tile index ranges of each (PROTOCOL.md "Where each mip is
 *      read"; the daemon and every client apply the same rule);
 *   2. per distinct time: evaluate each needed mip level once (all FFT
 *      cascades in one ocean_evaluate, each at its own cutoff; the near
 *      field's lattice cascade, the last, in its own, only when a tile of
 *      it is missing), then encode the
 *      tiles no earlier job of this tick asked for, in parallel, straight
 *      into FRAME records (proto_tile_record_encode);
 *   3. per job: the cascade block, the records, the mesh placement (and a
 *      MESH_TOPOLOGY when the client's mesh plan changed); jobs whose
 *      frames would be byte-identical but for the per-client fields share
 *      one encoding.
 */
#include "srv_cascade.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gerstner.h"
#include "lod.h"
#include "mesh.h"
#include "slope.h"
#include "srv_held.h"
#include "srv_tiles.h"

#define MAX_MIPS PROTO_MAX_MIPS


/* Time-independent facts of the current ocean (per filter order).  The
 * layout-1 cascades are the FFT's (0 .. fft - 1) and, when the sea has a
 * near field, its lattice cascade (index fft, the finest): a periodic
 * patch like any other, so the same mips, moments, planning and tiles
 * serve it. */
typedef struct tables {
    const ocean *oc;
    const ocean *nf;       /* the near field's lattice cascade, or NULL */
    int order;
    int cascades, n;       /* cascades = fft + (nf != NULL) */
    int fft;               /* FFT cascades */
    double patch[PROTO_MAX_LAYERS];
    int mips[PROTO_MAX_LAYERS];
    double kc[PROTO_MAX_LAYERS][MAX_MIPS];
    /* mip table entries: [m] for m < mips = what mip m lacks; [mips] = all */
    proto_mip_entry entry[PROTO_MAX_LAYERS][PROTO_MIP_ENTRIES];
    double var_removed[PROTO_MAX_LAYERS][PROTO_MIP_ENTRIES];
    /* How fast each mip's kept band changes: RMS of the second time
     * derivative over RMS, of the heights and of the slopes, 1/s^2. */
    double tt_h[PROTO_MAX_LAYERS][MAX_MIPS], tt_s[PROTO_MAX_LAYERS][MAX_MIPS];
    double total_var;      /* the FFT cascades, m^2 */
    double nf_var;         /* the near-field cascade, m^2 */
    const ocean_gerstner *g;
    double near_mss[3];    /* the Gerstner near field's slope moments (shading
                              only when there is no near-field cascade) */
    double tail_mss[3];    /* the short-wave tail beyond the shortest simulated wave */
    double inv_lambda[PROTO_MAX_LAYERS]; /* 1 / choppiness of each cascade's ocean (0: none) */
    /* the whitecap table (PROTOCOL.md "Whitecaps in layout 1"), over the
     * FFT cascades' and the near-field cascade's waves: its rows are found
     * by the std a reader holds, so a reader of fewer cascades uses the
     * rows below */
    proto_foam_row foam[PROTO_FOAM_ROWS];
    int foam_rows;
} tables;


struct srv_cascade {
    tables tab;
    int tab_valid;
    uint64_t tab_gen;      /* bumps with every new set of tables: what a client
                              holds from older ones is of another sea */
    ocean_frame *mipf[MAX_MIPS];  /* mip level m of every FFT cascade, this batch */
    ocean_frame *nff[MAX_MIPS];   /* mip level m of the near-field cascade */
    srv_tile_cache *cache; /* the encoded records, key layout 1 */
    const ocean *nf_in;    /* the near-field ocean the tables were made with */
};

/* A job's plan: which tiles of which mips. */
typedef struct range {
    int32_t x0, nx, z0, nz;  /* first index and count, wrapping mod ntile */
} range;

typedef struct plan {
    int ok;
    int ncas;              /* cascades this subscription may have: the FFT's, and the
                              near field's when it asks for that effect */
    int layers;            /* those it gets (its SUBSCRIBE.layers) */
    double q, min_spacing; /* q: the coarsest cascade's (the block's spacing_per_m) */
    double qc[PROTO_MAX_LAYERS];     /* each cascade's q (its entry's spacing_per_m), <= q */
    double cbytes[PROTO_MAX_LAYERS]; /* estimated bytes of each cascade's tiles */
    int ctiles[PROTO_MAX_LAYERS];
    unsigned channels;
    int need[PROTO_MAX_LAYERS][MAX_MIPS];
    range r[PROTO_MAX_LAYERS][MAX_MIPS];
    int tiles;
    srv_tile **list;       /* the records, in frame order */
    double geo;            /* G, the block's geometry_spacing_m: g_0 of the mesh
                              when the frame has one and normals, else 0 */
    int has_mesh;
    mesh_view mv;
    mesh_info mi;
    int share_with;        /* index of the job whose bytes this one shares, or itself */
    /* Samples in time (PROTOCOL.md): each mip's window and the times of
     * its samples A and B (interval 0: A at the frame's time). */
    proto_mip_time time[PROTO_MAX_LAYERS][MAX_MIPS];
    double t_ab[PROTO_MAX_LAYERS][MAX_MIPS][2];
    int ticks_per_frame;
    srv_held *held;        /* time-interpolating client: what it holds, moved
                              to this frame's windows; NULL otherwise */
    int key;               /* the frame carries PROTO_CASCADE_KEY */
    uint32_t *tags;        /* each record's tag, in frame order */
    double budget;         /* the frame's byte budget (plan_job) */
    double burst;          /* held samples this frame carries so far (estimated bytes) */
} plan;

ocean_result srv_cascade_create(srv_cascade **out)
{
    srv_cascade *k = calloc(1, sizeof *k);
    if (!k || srv_tiles_create(&k->cache) != OCEAN_OK) {
        free(k);
        *out = NULL;
        return OCEAN_ENOMEM;
    }
    *out = k;
    return OCEAN_OK;
}

void srv_cascade_reset(srv_cascade *k)
{
    if (!k)
        return;
    srv_tiles_clear(k->cache);
    k->tab_valid = 0;
}

void srv_cascade_destroy(srv_cascade *k)
{
    if (!k)
        return;
    srv_tiles_destroy(k->cache);
    for (int m = 0; m < MAX_MIPS; m++) {
        ocean_frame_destroy(k->mipf[m]);
        ocean_frame_destroy(k->nff[m]);
    }
    free(k);
}

void srv_cascade_sweep(srv_cascade *k, uint64_t keep_from)
{
    srv_tiles_sweep(k->cache, keep_from);
}

void srv_cascade_cache_size(const srv_cascade *k, size_t *entries, size_t *bytes)
{
    *entries = srv_tiles_count(k->cache);
    *bytes = srv_tiles_bytes(k->cache);
}


static unsigned ocean_fx_of(unsigned ch)
{
    unsigned fx = 0;
    if (ch & PROTO_CH_HEIGHT) fx |= OCEAN_FX_HEIGHT;
    if (ch & (PROTO_CH_DX | PROTO_CH_DZ)) fx |= OCEAN_FX_DISPLACEMENT;
    if (ch & PROTO_CH_NORMAL) fx |= OCEAN_FX_NORMALS;
    if (ch & (PROTO_CH_FOAM | PROTO_CH_BREAKING)) fx |= OCEAN_FX_FOAM;
    return fx;
}

uint32_t srv_cascade_max_tiles(const ocean_params *p, int layers, int tile_size)
{
    uint64_t total = 0;
    int cascades = layers < p->cascades ? layers : p->cascades;
    for (int m = 0; m < MAX_MIPS && (p->n >> m) >= OCEAN_MIN_N; m++) {
        int np = p->n >> m, t = tile_size < np ? tile_size : np;
        uint64_t per = (uint64_t)(np / t) * (uint64_t)(np / t);
        total += per * (uint64_t)cascades;
    }
    return total > UINT32_MAX ? UINT32_MAX : (uint32_t)total;
}

/* ---- tables -------------------------------------------------------------- */

/* The read table's entry of a mip (PROTOCOL.md "Whitecaps in layout 1"):
 * the share of its breaking-index variance each kernel holds between its
 * nodes, / 32768, at least 1 (a mip that keeps no slope: all of it). */
static void held_shares(const ocean_moments *mo, proto_mip_entry *e)
{
    static const ocean_interp kernel[PROTO_READ_KERNELS] = {
        [PROTO_READ_BILINEAR] = OCEAN_INTERP_BILINEAR,
        [PROTO_READ_KEYS] = OCEAN_INTERP_KEYS,
        [PROTO_READ_LANCZOS3] = OCEAN_INTERP_LANCZOS3,
    };
    for (int r = 0; r < PROTO_READ_KERNELS; r++) {
        double share = mo->kept_mss > 0.0 ? mo->kept_mss_read[kernel[r]] / mo->kept_mss : 1.0;
        long v = lround(share * 32768.0);
        e->held[r] = (uint16_t)(v < 1 ? 1 : v > 65535 ? 65535 : v);
    }
}

/* The whitecap table: the ramps of the sea's bands below cutoffs spread
 * evenly in log k from the lowest mip cutoff of any cascade to the highest,
 * and the whole sea: a reader's std falls between two of them wherever it
 * stands.  Once per ocean (each row solves a ramp, ~2 ms). */
static ocean_result foam_table_make(tables *tb)
{
    double lo = INFINITY, hi = 0.0, kc[PROTO_FOAM_ROWS];
    for (int c = 0; c < tb->cascades; c++)
        for (int m = 1; m < tb->mips[c]; m++) {
            lo = fmin(lo, tb->kc[c][m]);
            hi = fmax(hi, tb->kc[c][m]);
        }
    int n = 0;
    if (hi > lo)
        for (; n < PROTO_FOAM_ROWS - 1; n++)
            kc[n] = lo * pow(hi / lo, (double)n / (PROTO_FOAM_ROWS - 2));
    kc[n++] = INFINITY;
    ocean_foam_row rows[PROTO_FOAM_ROWS];
    int count = 0;
    ocean_result r = ocean_foam_table(tb->oc, tb->nf, tb->order, kc, n, rows, &count);
    if (r != OCEAN_OK)
        return r;
    tb->foam_rows = 0;
    for (int i = 0; i < count; i++) {
        proto_foam_row *f = &tb->foam[tb->foam_rows];
        f->sigma = (float)rows[i].sigma;
        f->a = (float)fmin(rows[i].a, 0.5);
        f->omega = (float)rows[i].omega;
        /* rows the f32 rounding makes equal, or out of the spec's ranges
         * (a sea whose breaking index exceeds them), are left out */
        if ((tb->foam_rows && !(f->sigma > tb->foam[tb->foam_rows - 1].sigma)) || !(f->sigma <= 1e3f) ||
            !(f->a >= -1e3f) || !(f->omega <= 1e3f))
            continue;
        tb->foam_rows++;
    }
    memset(&tb->foam[tb->foam_rows], 0, sizeof tb->foam[0] * (size_t)(PROTO_FOAM_ROWS - tb->foam_rows));
    return OCEAN_OK;
}

static ocean_result tables_make(tables *tb, const ocean *oc, const ocean_gerstner *g, const ocean *nf,
                                int order)
{
    memset(tb, 0, sizeof *tb);
    tb->g = g;
    /* A Gerstner wave A cos(k.x - w t + phi) has mean-square slopes
     * A^2 kx^2 / 2, A^2 kz^2 / 2 and cross moment A^2 kx kz / 2: what
     * shading carries of a near field that has no cascade. */
    for (int i = 0; g && i < ocean_gerstner_count(g); i++) {
        ocean_gerstner_wave w;
        if (ocean_gerstner_get_wave(g, i, &w) != OCEAN_OK) continue;
        double a2 = 0.5 * w.amplitude * w.amplitude;
        tb->near_mss[0] += a2 * w.kx * w.kx;
        tb->near_mss[1] += a2 * w.kz * w.kz;
        tb->near_mss[2] += a2 * w.kx * w.kz;
    }
    const ocean_params *p = ocean_get_params(oc);
    tb->oc = oc;
    tb->order = order;
    tb->fft = p->cascades;
    /* the near-field cascade needs a slot in the protocol's cascade block
     * (srv_settings_load refuses a scene without one) and the same grid */
    tb->nf = nf && p->cascades < PROTO_MAX_LAYERS && ocean_get_params(nf)->n == p->n ? nf : NULL;
    tb->cascades = p->cascades + (tb->nf != NULL);
    tb->n = p->n;
    /* The waves shorter than any the simulation holds (the sea state's
     * spectrum to 10 cm, then Elfouhaily et al. 1997's B_h to 1 mm;
     * slope.h): no tile ever carries them, shading always does. */
    ocean_slope_table *st = NULL;
    ocean_slope_stats ss;
    if (ocean_slope_table_create(oc, g, &st, NULL, 0) == OCEAN_OK &&
        ocean_slope_table_get(st, INFINITY, order, &ss) == OCEAN_OK) {
        tb->tail_mss[0] = ss.tail.mss_x;
        tb->tail_mss[1] = ss.tail.mss_z;
        tb->tail_mss[2] = ss.tail.mss_xz;
    }
    ocean_slope_table_destroy(st);
    for (int c = 0; c < tb->cascades; c++) {
        double klo, khi;
        /* the near-field cascade is cascade 0 of its own ocean */
        const ocean *src = c < tb->fft ? oc : tb->nf;
        int sc = c < tb->fft ? c : 0;
        ocean_cascade_band(src, sc, &tb->patch[c], &klo, &khi);
        ocean_result r = ocean_cascade_mips(src, sc, order, MAX_MIPS, &tb->mips[c], tb->kc[c]);
        if (r != OCEAN_OK)
            return r;
        for (int m = 0; m <= tb->mips[c]; m++) {
            ocean_moments mo;
            r = ocean_cascade_moments(src, sc, m < tb->mips[c] ? tb->kc[c][m] : 0.0, order, &mo);
            if (r != OCEAN_OK)
                return r;
            proto_mip_entry *e = &tb->entry[c][m];
            e->kc = m < tb->mips[c] ? (float)tb->kc[c][m] : 0.0f;
            e->mss_x = (float)mo.mss_x;
            e->mss_z = (float)mo.mss_z;
            e->mss_xz = (float)mo.mss_xz;
            if (m < tb->mips[c])
                held_shares(&mo, e);
            tb->var_removed[c][m] = mo.var_h;
            if (m < tb->mips[c]) {
                tb->tt_h[c][m] = mo.kept_var_h > 0 ? sqrt(mo.kept_var_h_tt / mo.kept_var_h) : 0.0;
                tb->tt_s[c][m] = mo.kept_mss > 0 ? sqrt(mo.kept_mss_tt / mo.kept_mss) : 0.0;
            }
            if (m == tb->mips[c]) {
                if (c < tb->fft) tb->total_var += mo.total_var_h;
                else tb->nf_var = mo.total_var_h;
            }
        }
        double lam = ocean_get_params(src)->sea.choppiness;
        tb->inv_lambda[c] = lam > 0 ? 1.0 / lam : 0.0;
    }
    return foam_table_make(tb);
}

/* ---- planning -------------------------------------------------------------- */

/* Tile index range [first, first + count) of the tiles of side w (m) that
 * meet [x - half, x + half], wrapped to a period of ntile tiles. */
static void span(double lo, double hi, double w, int ntile, int32_t *first, int32_t *count)
{
    double a = floor(lo / w), b = floor(hi / w);
    double cnt = b - a + 1;
    if (!(cnt < ntile)) {
        *first = 0;
        *count = ntile;
        return;
    }
    double f = fmod(a, (double)ntile);
    if (f < 0)
        f += ntile;
    *first = (int32_t)f;
    *count = (int32_t)cnt;
}

/* Channels of the tiles of mip m of cascade c: every cascade carries its
 * breaking index for foam (the reader sums them and applies the frame's
 * whitecap table; PROTOCOL.md "Whitecaps in layout 1"); and a mip finer
 * than the mesh can show (2^(m+1) sigma_c <= G) is geometry-free: every
 * reader reads height and displacement at max(s, G), so that mip's H, DX
 * and DZ would travel unread, and only its normals and breaking index go. */
static unsigned chan_of(const tables *tb, const plan *pl, int c, int m)
{
    unsigned ch = pl->channels;
    if (pl->geo > 0 && ldexp(tb->patch[c] / tb->n, m + 1) <= pl->geo)
        ch &= PROTO_CH_NORMAL | PROTO_CH_BREAKING;
    return ch;
}

/* ---- samples in time ------------------------------------------------------ */

/* The update interval of mip m of cascade c, in ticks, for subscription
 * sub (PROTOCOL.md "Samples in time").  Linear interpolation between
 * samples d apart misses a field f by -s(1-s) d^2 f''/2 at the fraction s
 * of the way; over the interval its RMS is d^2 RMS(f'') / (2 sqrt 30).  A
 * mip's interval is the longest power of two of ticks at which that, for
 * its heights (with H or displacement) and its slopes (with normals or
 * foam) relative to their own RMS, stays within the quantiser's RMS error
 * for the subscription's accuracy a on a tile whose range is 6 RMS
 * (2 sqrt 3 a): time costs no more error than the codec.  An interval
 * shorter than two ticks, or than the subscription's frame period, would
 * send as many samples as frames: 0, each frame's own time. */
static int mip_interval(const tables *tb, const srv_config *cfg, const proto_subscribe *sub, int c, int m,
                        int ticks_per_frame)
{
    if (!(sub->flags & PROTO_SUB_TIME_INTERP)) return 0;
    double r = 0.0;
    if (sub->effects & (PROTO_FX_HEIGHT | PROTO_FX_DISPLACEMENT)) r = tb->tt_h[c][m];
    if (sub->effects & (PROTO_FX_NORMALS | PROTO_FX_FOAM)) r = fmax(r, tb->tt_s[c][m]);
    double eps = 2.0 * sqrt(3.0) * sub->accuracy;
    int K = 0;
    for (int k = 2; k <= SRV_CASCADE_MAX_INTERVAL; k *= 2) {
        double d = k / cfg->tick_rate;
        if (d * d * r / (2.0 * sqrt(30.0)) > eps) break;
        K = k;
    }
    return K >= ticks_per_frame ? K : 0;
}

/* Job j's time table: each mip's window [tick_a, tick_a + K] around the
 * frame's tick position p, with tick_a = K floor((p - phi) / K) + phi; the
 * offset phi = (5c + 3m) mod K staggers the mips' refreshes over the ticks
 * (whole mips of several cascades would otherwise all refresh on the same
 * tick: one frame K times the mean). */
static void time_table(const tables *tb, const srv_config *cfg, const srv_cascade_job *j, plan *pl)
{
    const proto_subscribe *sub = &j->cs->sub;
    double fr = sub->frame_rate_hz > 0 ? sub->frame_rate_hz : cfg->tick_rate;
    pl->ticks_per_frame = (int)fmax(1.0, floor(cfg->tick_rate / fr + 0.5));
    memset(pl->time, 0, sizeof pl->time);
    for (int c = 0; c < tb->cascades; c++)
        for (int m = 0; m < tb->mips[c]; m++) {
            int K = mip_interval(tb, cfg, sub, c, m, pl->ticks_per_frame);
            pl->t_ab[c][m][0] = pl->t_ab[c][m][1] = j->t;
            if (!K) continue;
            int phi = (5 * c + 3 * m) % K;
            double a = K * floor((j->tick_pos - phi) / K) + phi;
            double w = (j->tick_pos - a) / K;
            int64_t ka = (int64_t)a;
            pl->time[c][m].tick_a = (uint32_t)(uint64_t)ka;
            pl->time[c][m].interval = (uint16_t)K;
            pl->time[c][m].phase = (uint16_t)fmin(65535.0, fmax(0.0, floor(w * 65536.0)));
            pl->t_ab[c][m][0] = (double)ka / cfg->tick_rate;
            pl->t_ab[c][m][1] = (double)(ka + K) / cfg->tick_rate;
        }
}

/* What one frame of the plan costs of mip (c, m)'s tiles on average: a mip
 * refreshed every K ticks sends each tile once every K / ticks_per_frame
 * frames. */
static double refresh_share(const plan *pl, int c, int m)
{
    int K = pl->time[c][m].interval;
    return K ? fmin(1.0, (double)pl->ticks_per_frame / K) : 1.0;
}

/* Encoded bytes of one tile of side T, from a fixed model of each codec -
 * never from what this daemon happened to encode before, so that two
 * replicas plan every frame alike (the ocean and what travels are pure
 * functions of the sea, t and the camera).
 * qz (format 2): residual bytes per sample and plane measured on the
 * default scene's layout-1 mip tiles (bench_codec, "as the viewer receives
 * them": 32 x 32, H DX DZ NU NV BI BQ, every mip of every cascade; with
 * BI BQ the model is within 2 % of the bytes) at
 * accuracies 2^k x 5e-3, k = 2 .. -4, linear in log2(accuracy) between
 * them (5e-3: 0.430, i.e. 1/8.5 of f32 with the headers), 0.14 more per
 * halving below and 0.05 less per doubling above the table; plus the
 * payload header, 8 + ~40 bytes a plane (weights of the LSX predictor).
 * f16 and the half-float EXR codecs 2; f32 and exr-zip 4 a sample. */
double srv_cascade_tile_bytes(const proto_subscribe *sub, unsigned channels, int T)
{
    static const double qz_res[7] = {0.311, 0.361, 0.430, 0.524, 0.635, 0.764, 0.905}; /* L = -2 .. 4 */
    int planes = proto_tile_planes(channels);
    double per, head = 0.0;
    switch (sub->codec) {
    case PROTO_CODEC_QZ: {
        double L = log2(5e-3 / fmax((double)sub->accuracy, 1e-6));
        if (L <= -2)
            per = qz_res[0] + 0.05 * (L + 2);
        else if (L >= 4)
            per = qz_res[6] + 0.14 * (L - 4);
        else {
            int i = (int)floor(L + 2);
            double f = L + 2 - i;
            per = i >= 6 ? qz_res[6] : qz_res[i] + f * (qz_res[i + 1] - qz_res[i]);
        }
        per = fmin(fmax(per, 0.05), 4.0);
        head = 8.0 + 40.0 * planes;
        break;
    }
    case PROTO_CODEC_F32:
    case PROTO_CODEC_EXR_ZIP:
        per = 4.0;
        break;
    default:
        per = 2.0;
        break;
    }
    return per * planes * T * T + head + 64; /* + record and TILE headers */
}

/* The bounding box [x0, x1] x [z0, z1] of the sea a camera may draw from
 * this frame's tiles within distance R (PROTOCOL.md "Where each mip is
 * read"): the disc's sector around the view direction, widened by
 * SECTOR_MARGIN on each side for the turn the camera may make before the
 * next frame, plus the disc of radius max(|y|, 1) under the camera (the
 * nadir a camera looking down sees), all grown by `grow` (the reading
 * stencil). */
#define SECTOR_MARGIN_DEG 30.0
typedef struct sector {
    double ext[4];  /* min and max of cos, min and max of sin over the sector's directions */
} sector;

static void sector_of(const proto_camera *cam, sector *sc)
{
    double vfov = cam->fov_y_deg * M_PI / 180.0;
    double aspect = cam->viewport_h ? (double)cam->viewport_w / cam->viewport_h : 1.0;
    double half = atan(tan(0.5 * vfov) * aspect) + SECTOR_MARGIN_DEG * M_PI / 180.0;
    if (!(half < M_PI)) {
        *sc = (sector){{-1, 1, -1, 1}};
        return;
    }
    double yaw = cam->yaw_deg * M_PI / 180.0;
    /* the arc's ends and the compass points the arc passes */
    double a[6] = {yaw - half, yaw + half, 0, 0.5 * M_PI, M_PI, 1.5 * M_PI};
    *sc = (sector){{INFINITY, -INFINITY, INFINITY, -INFINITY}};
    for (int i = 0; i < 6; i++) {
        if (i >= 2 && fabs(remainder(a[i] - yaw, 2 * M_PI)) > half) continue;
        double c = cos(a[i]), s = sin(a[i]);
        sc->ext[0] = fmin(sc->ext[0], c), sc->ext[1] = fmax(sc->ext[1], c);
        sc->ext[2] = fmin(sc->ext[2], s), sc->ext[3] = fmax(sc->ext[3], s);
    }
    /* the apex itself */
    sc->ext[0] = fmin(sc->ext[0], 0), sc->ext[1] = fmax(sc->ext[1], 0);
    sc->ext[2] = fmin(sc->ext[2], 0), sc->ext[3] = fmax(sc->ext[3], 0);
}

static void view_box(const srv_cascade_job *j, const sector *sc, double R, double grow, double box[4])
{
    const proto_camera *cam = &j->cam;
    double cx = cam->pos[0], cz = cam->pos[2];
    double r0 = fmin(R, fmax(fabs(cam->pos[1]), 1.0));
    box[0] = fmin(cx - r0, cx + R * sc->ext[0]) - grow;
    box[1] = fmax(cx + r0, cx + R * sc->ext[1]) + grow;
    box[2] = fmin(cz - r0, cz + R * sc->ext[2]) - grow;
    box[3] = fmax(cz + r0, cz + R * sc->ext[3]) + grow;
}

static double nadir_error(const tables *tb, const plan *pl, const proto_camera *cam);
static double lost_var(const tables *tb, int c, double s);
static void plan_relief(const tables *tb, const srv_config *cfg, const srv_cascade_job *j, const sector *sc,
                        double q, double ppr, double budget, plan *pl);

/* The plan for spacing factor q at every cascade; returns the estimated
 * bytes of its tiles. */
static double plan_at(const tables *tb, const srv_config *cfg, const srv_cascade_job *j,
                      const sector *sc, double q, plan *pl);
/* Cascade c of plan pl at spacing factor q (pl's other cascades stay);
 * returns the estimated bytes of that cascade's tiles. */
static double plan_cascade(const tables *tb, const srv_config *cfg, const srv_cascade_job *j,
                           const sector *sc, int c, double q, plan *pl);

#define QUARTER_OCTAVE 1.189207115002721 /* 2^(1/4) */

static double plan_bytes(const plan *pl)
{
    double b = 0;
    for (int c = 0; c < pl->layers; c++) b += pl->cbytes[c];
    return b;
}

/* A job's plan at the server's quality target (server.px_per_sample),
 * coarsened (q raised by steps of 2^(1/4)) until the frame's tiles fit the
 * viewer's byte budget (server.viewer_bytes_per_s over its frame rate,
 * estimated with srv_cascade_tile_bytes' model): a
 * large viewport or a low camera gets a little less geometry and a little
 * more unresolved roughness, never more bytes than the budget.
 *
 * A subscription with normals and a mesh then puts relief first
 * (plan_relief): the cascades whose left-out heights a camera near the
 * water would see in the mesh's silhouettes get the bytes first.  (A
 * client without a mesh, an export, a sampler, keeps the texture.)
 *
 * Then each cascade spends what that left of the budget on its own q.
 * Bytes grow with q in steps of whole tiles, and a step of one coarse
 * cascade (tiles 125 m wide at ship-bridge) can cost more than all the
 * fine cascades' mips together: with one q for every cascade, a camera
 * 25 m up with the viewer's subscription stopped at 111 of its 130 KB (at
 * qz accuracy 1e-3: at 105 KB, with no tile of the finest FFT cascade).
 * So, finest cascade first, a quarter octave per cascade
 * per round, every cascade refines while its next step fits and its q is
 * above the target; a cascade whose step does not fit stops (its bytes
 * only grow as its q falls).  The fine cascades' patches are small, so
 * their mips come whole and cheap, and they carry the slopes the near
 * sea shows. */
static void plan_job(const tables *tb, const srv_config *cfg, const srv_cascade_job *j, plan *pl)
{
    mesh_camera mc;
    srv_mesh_camera(&j->cam, &mc);
    double ppr = mesh_camera_px_per_rad(&mc);
    /* A camera's q has no use below SRV_CASCADE_Q_MIN (a degenerate field
     * of view, 1e-45 deg, asks for 1e-37): the plan starts there, so the
     * octave search below reaches a plan that fits in its 64 steps. */
    double q = fmax(cfg->px_per_sample / (ppr > 0 ? ppr : 1.0), SRV_CASCADE_Q_MIN);
    double rate_hz = j->cs->sub.frame_rate_hz > 0 ? j->cs->sub.frame_rate_hz : 30.0;
    /* live frames at the rate the client's link carries (srv_link.h), up to
     * server.viewer_bytes_per_s; a replay plans from the recording alone */
    double bps = cfg->viewer_bytes_per_s, link = (double)atomic_load(&j->c->link_bps);
    if (!j->replay && link > 0 && link < bps) bps = link;
    double budget = bps / rate_hz;
    pl->budget = budget;
    sector sc;
    sector_of(&j->cam, &sc);
    double hi = q;
    if (plan_at(tb, cfg, j, &sc, q, pl) > budget) {
        /* octaves first, then quarter octaves back down to the finest that fits */
        for (int it = 0; it < 64; it++) {
            hi *= 2;
            if (plan_at(tb, cfg, j, &sc, hi, pl) <= budget)
                break;
        }
        for (int it = 0; it < 3; it++) {
            double t = hi / QUARTER_OCTAVE;
            if (t <= q || plan_at(tb, cfg, j, &sc, t, pl) > budget)
                break;
            hi = t;
        }
        plan_at(tb, cfg, j, &sc, hi, pl);
    }
    /* Seed 000's energy guard, E <= 5 %: a subscription without normals
     * has no shading to carry what the tiles drop (its e_total is its
     * e_error), so its plan is refined - past server.px_per_sample if
     * need be - until the tiles carry 95 % of the height variance at the
     * nadir, spending up to twice the byte budget;
     * past that the frame reports what is missing in e_total. */
    if (!(j->cs->sub.effects & PROTO_FX_NORMALS)) {
        while (hi > q / 64 && nadir_error(tb, pl, &j->cam) > SRV_CASCADE_E_GUARD) {
            double t = hi / QUARTER_OCTAVE;
            if (plan_at(tb, cfg, j, &sc, t, pl) > 2.0 * budget) {
                plan_at(tb, cfg, j, &sc, hi, pl);
                break;
            }
            hi = t;
        }
    } else if (pl->has_mesh) {
        plan_relief(tb, cfg, j, &sc, q, ppr, budget, pl);
    }
    /* each cascade its own q, within what is left (see above) */
    double bytes = plan_bytes(pl);
    int open = 0;
    for (int c = 0; c < pl->layers; c++)
        if (pl->qc[c] / QUARTER_OCTAVE >= q * 0.999999) open |= 1 << c;
    while (open) {
        for (int c = pl->layers - 1; c >= 0; c--) {
            if (!(open & (1 << c))) continue;
            double was_q = pl->qc[c], was_b = pl->cbytes[c], t = was_q / QUARTER_OCTAVE;
            double nb = bytes - was_b + plan_cascade(tb, cfg, j, &sc, c, t, pl);
            if (nb > budget) {
                plan_cascade(tb, cfg, j, &sc, c, was_q, pl);
                open &= ~(1 << c);
                continue;
            }
            bytes = nb;
            if (t / QUARTER_OCTAVE < q * 0.999999) open &= ~(1 << c);
        }
    }
    pl->tiles = 0;
    for (int c = 0; c < pl->layers; c++) pl->tiles += pl->ctiles[c];
}

/* The relief cascade c's reads leave out, in pixels: the RMS height
 * they lack at slant distance r, seen from r (sqrt(lost) f / r, f the
 * camera's pixels per radian), where it is largest along the sea the
 * camera sees (from the nearest point its frustum reaches, by its pitch
 * and field of view, out to the view range).  A crest the tiles leave out
 * is a silhouette that much too low: a camera near the water sees far
 * crests edge on, by their height, however small their footprint.  (The
 * mesh's lattice has its own error budget, so G is left out here.) */
#define RELIEF_STEPS 32
static double relief_px(const tables *tb, const plan *pl, const srv_cascade_job *j, int c, double ppr,
                        double range_m)
{
    const proto_camera *cam = &j->cam;
    double h = fmax(fabs(cam->pos[1]), 1.0);
    double down = (0.5 * cam->fov_y_deg - cam->pitch_deg) * M_PI / 180.0;
    if (!(down > 0))
        return 0.0; /* no sea in view */
    double near = down < 0.5 * M_PI ? h / sin(down) : h, far = sqrt(range_m * range_m + h * h);
    if (!(near < far))
        return 0.0;
    double worst = 0, step = pow(far / near, 1.0 / RELIEF_STEPS), r = near;
    for (int i = 0; i <= RELIEF_STEPS; i++, r *= step) {
        double lost = lost_var(tb, c, fmax(pl->qc[c] * r, pl->min_spacing));
        worst = fmax(worst, sqrt(fmax(lost, 0.0)) * ppr / r);
    }
    return worst;
}

/* Relief before texture.  Where the plan that fits leaves out heights that
 * would show more than RELIEF_PX (relief_px), it starts again RELIEF_START
 * times coarser and takes, a quarter octave of one cascade at a time, the
 * step that removes the most relief error (the sum over cascades of its
 * square) per byte, while it fits the budget, until every cascade's is
 * within RELIEF_PX; plan_job's refinement then spends what is left finest
 * first.  The slopes the coarser mips leave out reach the shading as
 * unresolved roughness (the mip tables); lost heights reach nothing.
 * From 5 m over the storm sea in a 10 deg view, one q for every cascade
 * read the 240 m waves of cascade 0 no farther than 1.7 km, and the crests
 * that rise over the horizon (0.7-2.9 km out) were flat; three octaves
 * give the marginal choice room to move the finer cascades' bytes there
 * (a single octave still left cascade 0 at 2.7 px for a 30 Hz viewer). */
#define RELIEF_PX 1.0
#define RELIEF_START 8.0
static void plan_relief(const tables *tb, const srv_config *cfg, const srv_cascade_job *j, const sector *sc,
                        double q, double ppr, double budget, plan *pl)
{
    const proto_subscribe *sub = &j->cs->sub;
    double range_m = sub->view_range_m > 0 ? sub->view_range_m : cfg->view_range;
    double worst[PROTO_MAX_LAYERS] = {0}, most = 0;
    for (int c = 0; c < pl->layers; c++) most = fmax(most, relief_px(tb, pl, j, c, ppr, range_m));
    if (!(most > RELIEF_PX))
        return;
    double bytes = plan_at(tb, cfg, j, sc, RELIEF_START * pl->q, pl);
    int open = 0;
    for (int c = 0; c < pl->layers; c++) {
        worst[c] = relief_px(tb, pl, j, c, ppr, range_m);
        if (pl->qc[c] / QUARTER_OCTAVE >= q * 0.999999 && worst[c] > RELIEF_PX) open |= 1 << c;
    }
    while (open) {
        /* every open cascade's next step, priced; the best kept */
        int best = -1;
        double best_gain = 0, best_w = 0;
        for (int c = 0; c < pl->layers; c++) {
            if (!(open & (1 << c))) continue;
            double was_q = pl->qc[c], was_b = pl->cbytes[c];
            double nb = bytes - was_b + plan_cascade(tb, cfg, j, sc, c, was_q / QUARTER_OCTAVE, pl);
            double w = relief_px(tb, pl, j, c, ppr, range_m);
            plan_cascade(tb, cfg, j, sc, c, was_q, pl);
            if (nb > budget) {
                open &= ~(1 << c);
                continue;
            }
            double gain = (worst[c] * worst[c] - w * w) / fmax(nb - bytes, 1.0);
            if (best < 0 || gain > best_gain) best = c, best_gain = gain, best_w = w;
        }
        if (best < 0)
            break;
        double t = pl->qc[best] / QUARTER_OCTAVE;
        plan_cascade(tb, cfg, j, sc, best, t, pl);
        bytes = plan_bytes(pl);
        worst[best] = best_w;
        if (t / QUARTER_OCTAVE < q * 0.999999 || !(best_w > RELIEF_PX)) open &= ~(1 << best);
    }
}

static double plan_at(const tables *tb, const srv_config *cfg, const srv_cascade_job *j,
                      const sector *sc, double q, plan *pl)
{
    const proto_subscribe *sub = &j->cs->sub;
    /* only the fields a plan computes: the mesh parts stay */
    memset(pl->need, 0, sizeof pl->need);
    memset(pl->cbytes, 0, sizeof pl->cbytes);
    memset(pl->ctiles, 0, sizeof pl->ctiles);
    pl->ncas = tb->fft + (tb->nf && (sub->effects & PROTO_FX_NEAR_FIELD) ? 1 : 0);
    pl->layers = sub->layers < pl->ncas ? sub->layers : pl->ncas;
    pl->q = q;
    /* The velocity policy's cutoff as a floor on the spacing read: a mip
     * whose cutoff lies above it is not needed (kc of mip m is pi / (2 sigma_m)). */
    double pol = isfinite(j->policy_k) && j->policy_k > 0 ? M_PI / (2.0 * j->policy_k) : 0.0;
    pl->min_spacing = fmax(sub->base_spacing_m > 0 ? sub->base_spacing_m : 0.0, pol);
    pl->channels = srv_tiles_channels(sub->effects);
    /* layout 1's foam is the breaking index the reader sums; a sea without
     * whitecaps has no table and sends none (PROTOCOL.md "Whitecaps in
     * layout 1": no table, no foam) */
    if (pl->channels & PROTO_CH_FOAM)
        pl->channels = (pl->channels & ~(unsigned)PROTO_CH_FOAM) | (tb->foam_rows ? PROTO_CH_BREAKING : 0u);
    double bytes = 0;
    pl->tiles = 0;
    for (int c = 0; c < pl->layers; c++) {
        bytes += plan_cascade(tb, cfg, j, sc, c, q, pl);
        pl->tiles += pl->ctiles[c];
    }
    pl->ok = 1;
    return bytes;
}

static double plan_cascade(const tables *tb, const srv_config *cfg, const srv_cascade_job *j,
                           const sector *sc, int c, double q, plan *pl)
{
    const proto_subscribe *sub = &j->cs->sub;
    double range_m = sub->view_range_m > 0 ? sub->view_range_m : cfg->view_range;
    double cy = fmax(fabs(j->cam.pos[1]), 1.0);
    pl->qc[c] = q;
    pl->cbytes[c] = 0;
    pl->ctiles[c] = 0;
    memset(pl->need[c], 0, sizeof pl->need[c]);
    double sigma = tb->patch[c] / tb->n;
    int fades = c > 0;
    for (int m = 0; m < tb->mips[c]; m++) {
        unsigned ch = chan_of(tb, pl, c, m);
        if (!ch) continue;
        int np = tb->n >> m, t = cfg->cascade_tile < np ? cfg->cascade_tile : np, ntile = np / t;
        double sp = sigma * ldexp(1.0, m), lim = 2.0 * sp;
        int last = m == tb->mips[c] - 1;
        double R;
        if (last && !fades) {
            R = range_m;
        } else {
            if (pl->min_spacing >= lim)
                continue;
            double r2 = (lim / q) * (lim / q) - cy * cy;
            if (!(r2 > 0))
                continue;
            R = fmin(sqrt(r2), range_m);
        }
        double box[4], w = t * sp;
        view_box(j, sc, R, 2.0 * sp, box);
        range *g = &pl->r[c][m];
        span(box[0], box[1], w, ntile, &g->x0, &g->nx);
        span(box[2], box[3], w, ntile, &g->z0, &g->nz);
        pl->need[c][m] = 1;
        pl->ctiles[c] += g->nx * g->nz;
        pl->cbytes[c] += (double)g->nx * g->nz * srv_cascade_tile_bytes(sub, ch, t) * refresh_share(pl, c, m);
    }
    return pl->cbytes[c];
}

/* ---- tiles ------------------------------------------------------------------ */

/* Copies tile t's samples from mip m of its cascade (grid points: no
 * interpolation), encodes them and wraps them in a FRAME record.  Thread
 * safe for distinct t. */
static void tile_build(srv_tile *t, const ocean_frame *f, const tables *tb)
{
    const srv_tile_key *k = &t->key;
    t->ready = 1;
    /* the near-field cascade is cascade 0 of its own frame */
    const ocean_field *fd = ocean_frame_field(f, k->cascade < tb->fft ? k->cascade : 0);
    int np = tb->n >> k->level, T = k->size;
    if (!fd || fd->n < np || fd->n % np) {
        t->result = OCEAN_ESTATE;
        return;
    }
    int stride = fd->n / np;
    size_t ns = (size_t)T * T;
    int planes = proto_tile_planes(k->channels);
    float *buf = malloc(sizeof(float) * ns * ((size_t)planes + 2));
    if (!buf) {
        t->result = OCEAN_ENOMEM;
        return;
    }
    float *sx = buf + ns * (size_t)planes, *sz = sx + ns;
    int off[PROTO_SLOT_COUNT];
    proto_tile_plane_offsets(k->channels, ns, off);
    float *P[PROTO_SLOT_COUNT];
    for (int q = 0; q < PROTO_SLOT_COUNT; q++) P[q] = off[q] >= 0 ? buf + off[q] : NULL;
    float *ph = P[PROTO_SLOT_H], *pdx = P[PROTO_SLOT_DX], *pdz = P[PROTO_SLOT_DZ], *pnu = P[PROTO_SLOT_NU];
    float *pbi = P[PROTO_SLOT_BI], *pbq = P[PROTO_SLOT_BQ];
    if ((ph && !fd->height) || ((pdx || pdz) && !fd->dx) || (pnu && !fd->slope_x) || P[PROTO_SLOT_FOAM] ||
        P[PROTO_SLOT_J] || (pbi && (!fd->dxx || !fd->bq))) {
        free(buf);
        t->result = OCEAN_ESTATE;
        return;
    }
    /* the breaking index and its quadrature (foam.h): beta = -(Dxx + Dzz)
     * / lambda, q = -bq / lambda */
    float il = (float)tb->inv_lambda[k->cascade];
    for (int i = 0; i < T; i++) {
        size_t row = (size_t)((k->iz * T + i) * stride) * (size_t)fd->n;
        for (int j = 0; j < T; j++) {
            size_t g = row + (size_t)((k->ix * T + j) * stride), s = (size_t)i * T + j;
            if (ph) ph[s] = fd->height[g];
            if (pdx) pdx[s] = fd->dx[g];
            if (pdz) pdz[s] = fd->dz[g];
            if (pnu) {
                sx[s] = fd->slope_x[g];
                sz[s] = fd->slope_z[g];
            }
            if (pbi) {
                pbi[s] = -(fd->dxx[g] + fd->dzz[g]) * il;
                pbq[s] = -fd->bq[g] * il;
            }
        }
    }
    if (pnu) proto_normals_from_slopes(sx, sz, ns, pnu, P[PROTO_SLOT_NV]);
    proto_buf pb;
    double max_err = 0;
    t->result = srv_tiles_encode(k, T, buf, &pb, &max_err);
    free(buf);
    if (t->result != OCEAN_OK)
        return;
    double sp = tb->patch[k->cascade] / tb->n * ldexp(1.0, k->level);
    proto_tile pt;
    memset(&pt, 0, sizeof pt);
    pt.level = k->level;
    pt.codec = k->codec;
    pt.channels = k->channels;
    pt.width = pt.height = (uint16_t)T;
    pt.ix = k->ix;
    pt.iz = k->iz;
    pt.origin_x = (double)k->ix * T * sp;
    pt.origin_z = (double)k->iz * T * sp;
    pt.spacing = sp;
    pt.error_bound = isfinite(max_err) && max_err >= 0 ? (float)max_err : 0.0f;
    pt.payload_len = (uint32_t)pb.len;
    pt.payload = proto_buf_data(&pb);
    pt.cascade = k->cascade;
    proto_buf rec;
    proto_buf_init(&rec, 0);
    t->result = proto_tile_record_encode(&rec, &pt, k->cascade, NULL, 0);
    proto_buf_free(&pb);
    if (t->result != OCEAN_OK) {
        proto_buf_free(&rec);
        return;
    }
    t->result = srv_tile_take_payload(t, &rec);
}

/* ---- frames ----------------------------------------------------------------- */


/* The height variance of cascade c that a read at spacing s leaves out
 * (PROTOCOL.md "Where each mip is read"): what the mips read lack, with
 * their weights, and all of it beyond a fading cascade's fade. */
static double lost_var(const tables *tb, int c, double s)
{
    int M = tb->mips[c];
    proto_lod_read r;
    proto_lod_read_at(s, tb->patch[c] / tb->n, M, c > 0, &r);
    double v = (1 - r.fade) * tb->var_removed[c][M];
    for (int k = 0; k < 2; k++)
        if (r.mip[k] >= 0) v += r.weight[k] * tb->var_removed[c][r.mip[k]];
    return v;
}

/* Height variance the tiles do not carry at the camera's nadir, as a
 * fraction of the sea's: each cascade at the level the lod rule reads
 * there (PROTOCOL.md), blended between mips as a client blends them. */
static double nadir_error(const tables *tb, const plan *pl, const proto_camera *cam)
{
    /* the sea this subscription is served: the near field's variance
     * counts when it asks for that effect */
    double total = tb->total_var + (pl->ncas > tb->fft ? tb->nf_var : 0.0);
    if (!(total > 0))
        return 0.0;
    double miss = 0.0;
    for (int c = 0; c < pl->ncas; c++) {
        if (c >= pl->layers) {
            miss += tb->var_removed[c][tb->mips[c]];
            continue;
        }
        /* height is read at max(s, G) (PROTOCOL.md), s at the nadir */
        miss += lost_var(tb, c, fmax(proto_lod_spacing(pl->qc[c], pl->min_spacing, cam->pos[1], 0, 0), pl->geo));
    }
    double e = miss / total;
    return e < 0 ? 0 : e > 1 ? 1 : e;
}

/* The client's mesh for job j and, when its plan changed, the FLAT
 * MESH_TOPOLOGY to send first. */
static void mesh_part(const srv_config *cfg, srv_stats *st, srv_cascade_job *j, plan *pl)
{
    srv_client_sim *cs = j->cs;
    if (!cs->mesh || cs->sub.mesh_kind == PROTO_MESH_NONE) return;
    mesh_camera mc;
    srv_mesh_camera(&j->cam, &mc);
    /* Priced before it is placed, as for layout 0: a camera the protocol
     * allows may ask for a topology no server should build. */
    if (!srv_client_sim_mesh_fit(j->cs, j->c, &mc, cfg->max_mesh_vertices, j->cam_seq, st)) return;
    ocean_result r = mesh_place(cs->mesh, &mc);
    if (r == OCEAN_OK) {
        mesh_get_view(cs->mesh, &pl->mv);
        mesh_get_info(cs->mesh, &pl->mi);
        if (pl->mv.levels < 1 || pl->mv.levels > PROTO_MAX_LOD_LEVELS || pl->mv.vertex_count == 0)
            r = OCEAN_ETOOBIG;
    }
    if (r != OCEAN_OK) {
        char why[256];
        snprintf(why, sizeof why, "mesh build failed (%s); frames come without a mesh until the next SUBSCRIBE",
                 ocean_strerror(r));
        srv_client_send_error(j->c, NULL, 0, r, why);
        mesh_destroy(cs->mesh);
        cs->mesh = NULL;
        return;
    }
    pl->has_mesh = 1;
    const mesh_view *v = &pl->mv;
    if (cs->topo_valid && v->topology_key == cs->topo_key) return;
    float *flat = malloc(sizeof(float) * 2 * (size_t)v->vertex_count);
    float zones[4 * PROTO_MAX_LOD_LEVELS];
    if (!flat) {
        pl->has_mesh = 0;
        return;
    }
    for (uint32_t i = 0; i < v->vertex_count; i++) {
        flat[2 * i] = v->base[3 * i];
        flat[2 * i + 1] = v->base[3 * i + 2];
    }
    for (int L = 0; L < v->levels; L++) {
        zones[4 * L] = (float)pl->mi.level_spacing_m[L];
        zones[4 * L + 1] = (float)pl->mi.zone_radius_m[L];
        zones[4 * L + 2] = (float)pl->mi.blend_m[L];
        zones[4 * L + 3] = 0.0f;
    }
    j->topo = srv_client_sim_topology(cs, v, j->t, flat, zones);
    free(flat);
    if (!j->topo)
        pl->has_mesh = 0;
}

static void frame_build(const tables *tb, srv_cascade_job *j, plan *pl, int shared)
{
    const proto_subscribe *sub = &j->cs->sub;
    proto_bytes *recs = malloc(sizeof *recs * (size_t)(pl->tiles ? pl->tiles : 1));
    uint32_t *tags = malloc(sizeof *tags * (size_t)(pl->tiles ? pl->tiles : 1));
    if (!recs || !tags) {
        free(recs);
        free(tags);
        return;
    }
    int nt = 0;
    for (int i = 0; i < pl->tiles; i++)
        if (pl->list[i] && pl->list[i]->result == OCEAN_OK && pl->list[i]->payload) {
            tags[nt] = pl->tags[i];
            recs[nt++] = (proto_bytes){pl->list[i]->payload, pl->list[i]->payload_len};
        }
    proto_msg m;
    proto_msg_init(&m, PROTO_FRAME);
    m.hdr.sim_time = j->t;
    proto_frame *fr = &m.u.frame;
    fr->cutoff_k = isfinite(j->policy_k) && j->policy_k > 0 ? j->policy_k : INFINITY;
    fr->e_error = nadir_error(tb, pl, &j->cam);
    fr->origin[0] = pl->has_mesh ? pl->mv.origin[0] : j->cam.pos[0];
    fr->origin[2] = pl->has_mesh ? pl->mv.origin[2] : j->cam.pos[2];
    fr->camera_seq = j->cam_seq;
    fr->tick = j->tick;
    fr->tile_count = (uint16_t)nt;
    fr->tile_records = recs;
    fr->record_tags = tags;
    fr->layout = PROTO_LAYOUT_CASCADE;
    proto_cascade_block *b = &fr->cascades;
    b->cascade_count = (uint8_t)pl->layers;
    b->order = (uint8_t)tb->order;
    b->flags = pl->key ? PROTO_CASCADE_KEY : 0;
    if ((pl->channels & PROTO_CH_BREAKING) && tb->foam_rows) {
        b->flags |= PROTO_CASCADE_FOAM | PROTO_CASCADE_READ;
        b->foam_rows = (uint8_t)tb->foam_rows;
        memcpy(b->foam, tb->foam, sizeof b->foam);
    }
    b->spacing_per_m = (float)pl->q;
    for (int i = 0; i < 3; i++) b->camera[i] = j->cam.pos[i];
    b->min_spacing_m = (float)pl->min_spacing;
    b->geometry_spacing_m = (float)pl->geo;
    /* Without normals the client has nothing to shade what geometry
     * drops; with them every simulated wave is carried by one or the
     * other. */
    b->e_total = (sub->effects & PROTO_FX_NORMALS) ? 0.0f : (float)fr->e_error;
    for (int c = 0; c < pl->layers; c++) {
        proto_cascade_entry *e = &b->cascade[c];
        e->patch_m = tb->patch[c];
        e->n = (uint16_t)tb->n;
        e->mips = (uint8_t)tb->mips[c];
        e->fades = c > 0;
        e->spacing_per_m = (float)pl->qc[c];
        for (int q = 0; q <= tb->mips[c]; q++) {
            e->mip[q] = tb->entry[c][q];
            if (!(b->flags & PROTO_CASCADE_READ)) memset(e->mip[q].held, 0, sizeof e->mip[q].held);
        }
        for (int q = 0; q < tb->mips[c]; q++) e->time[q] = pl->time[c][q];
    }
    /* The near field is the last cascade when the sea has one and the
     * subscription asks for it: its moments are in its mip table (where
     * geometry does not resolve it, the lod rule reads them there), never
     * again in the tail.  Without such a cascade - no near-field cascade,
     * or a subscription without the effect - its waves are still the
     * sea's (the tail starts above them), so they shade, in the tail
     * (left out, they would be a gap in the spectrum: 13 % of
     * ship-bridge's slope variance). */
    int near_in_frame = tb->nf && (sub->effects & PROTO_FX_NEAR_FIELD);
    for (int i = 0; i < 3; i++) {
        b->tail_mss[i] = (float)tb->tail_mss[i];
        if (!near_in_frame) b->tail_mss[i] += (float)tb->near_mss[i];
    }
    /* cascades the subscription leaves out: their slopes only shade */
    for (int c = pl->layers; c < pl->ncas; c++) {
        const proto_mip_entry *all = &tb->entry[c][tb->mips[c]];
        b->tail_mss[0] += all->mss_x;
        b->tail_mss[1] += all->mss_z;
        b->tail_mss[2] += all->mss_xz;
    }
    if (pl->has_mesh) {
        fr->has_mesh = 1;
        fr->placement.mesh_id = j->cs->mesh_id;
        memcpy(fr->placement.origin, pl->mv.origin, sizeof pl->mv.origin);
    }
    j->frame = srv_msg_encode(&m);
    free(recs);
    free(tags);
    if (!shared || !j->frame || srv_msg_make_shared(j->frame) != OCEAN_OK) return;
    srv_msg *q = j->frame;
    size_t cam_at, mesh_at;
    if (proto_frame_client_fields(proto_buf_data(&q->blob->buf), proto_buf_len(&q->blob->buf), &cam_at,
                                  &mesh_at) != OCEAN_OK || cam_at != SRV_FRAME_CAMERA_SEQ_AT ||
        (pl->has_mesh && (mesh_at == 0 || mesh_at > UINT32_MAX))) {
        pl->share_with = -1;   /* not laid out as expected: nobody borrows these bytes */
        return;
    }
    q->camera_seq = j->cam_seq;
    if (pl->has_mesh) {
        q->mesh_id = j->cs->mesh_id;
        q->mesh_id_at = (uint32_t)mesh_at;
    }
}

/* Two live jobs whose FRAMEs are the same bytes but for camera_seq,
 * mesh_id and the header seq. */
static int same_frame(const srv_cascade_job *a, const plan *pa, const srv_cascade_job *b, const plan *pb)
{
    const proto_subscribe *x = &a->cs->sub, *y = &b->cs->sub;
    if (a->t != b->t || a->tick != b->tick || a->policy_k != b->policy_k || pa->tiles != pb->tiles ||
        pa->has_mesh != pb->has_mesh || pa->layers != pb->layers || pa->ncas != pb->ncas || pa->q != pb->q ||
        pa->min_spacing != pb->min_spacing || pa->geo != pb->geo || x->effects != y->effects || memcmp(a->cam.pos, b->cam.pos, sizeof a->cam.pos) ||
        pa->key != pb->key || memcmp(pa->time, pb->time, sizeof pa->time))
        return 0;
    for (int c = 0; c < pa->layers; c++)
        if (pa->qc[c] != pb->qc[c]) return 0;
    if (pa->has_mesh && (pa->mv.topology_key != pb->mv.topology_key ||
                         memcmp(pa->mv.origin, pb->mv.origin, sizeof pa->mv.origin)))
        return 0;
    return pa->tiles == 0 || (memcmp(pa->list, pb->list, sizeof *pa->list * (size_t)pa->tiles) == 0 &&
                              memcmp(pa->tags, pb->tags, sizeof *pa->tags * (size_t)pa->tiles) == 0);
}

/* One mip level m of the near-field cascade, when a tile of it is
 * missing: the near field is simulated only for a live layout-1 viewer
 * whose camera resolves it. */
static ocean_result eval_near_mip(srv_cascade *k, ocean *nf, const tables *tb, double t, int m,
                                  unsigned fx, srv_stats *st)
{
    int c = tb->fft;
    if (!k->nff[m]) {
        ocean_result r = ocean_frame_create(nf, &k->nff[m]);
        if (r != OCEAN_OK) return r;
    }
    ocean_request rq;
    memset(&rq, 0, sizeof rq);
    rq.effects[0] = fx;
    rq.cascade_cutoff_k[0] = m < tb->mips[c] ? tb->kc[c][m] : 0.0;
    rq.cutoff_k = INFINITY;
    rq.order = tb->order;
    rq.low_boost = 1.0;
    rq.per_cascade = 1;
    ocean_result r = ocean_evaluate(nf, t, &rq, k->nff[m]);
    if (r == OCEAN_OK) atomic_fetch_add(&st->evaluations, 1);
    return r;
}

/* Evaluates the mips needed at time t (need_fx[c][m]: ocean effects). */
static ocean_result eval_mips(srv_cascade *k, ocean *oc, ocean *nf, const tables *tb, double t,
                              unsigned need_fx[PROTO_MAX_LAYERS][MAX_MIPS], srv_stats *st)
{
    for (int m = 0; m < MAX_MIPS; m++) {
        if (tb->nf && need_fx[tb->fft][m]) {
            ocean_result r = eval_near_mip(k, nf, tb, t, m, need_fx[tb->fft][m], st);
            if (r != OCEAN_OK) return r;
        }
        ocean_request rq;
        memset(&rq, 0, sizeof rq);
        int any = 0;
        for (int c = 0; c < tb->fft; c++) {
            rq.effects[c] = need_fx[c][m];
            rq.cascade_cutoff_k[c] = m < tb->mips[c] ? tb->kc[c][m] : 0.0;
            if (need_fx[c][m]) any = 1;
        }
        if (!any) continue;
        if (!k->mipf[m]) {
            ocean_result r = ocean_frame_create(oc, &k->mipf[m]);
            if (r != OCEAN_OK) return r;
        }
        rq.cutoff_k = INFINITY;
        rq.order = tb->order;
        rq.low_boost = 1.0;
        rq.per_cascade = 1;
        ocean_result r = ocean_evaluate(oc, t, &rq, k->mipf[m]);
        if (r != OCEAN_OK) return r;
        atomic_fetch_add(&st->evaluations, 1);
    }
    return OCEAN_OK;
}

/* The cascade tables of this ocean (made anew for a new ocean, whose
 * frames have other grids and tiles other bytes); 0, every job told, when
 * they cannot be made. */
static int tables_current(srv_cascade *k, ocean *oc, const ocean_gerstner *g, ocean *nf, int order,
                          srv_cascade_job *jobs, int n)
{
    if (k->tab_valid && k->tab.oc == oc && k->tab.g == g && k->nf_in == nf && k->tab.order == order) return 1;
    for (int m = 0; m < MAX_MIPS; m++) {
        ocean_frame_destroy(k->mipf[m]);
        k->mipf[m] = NULL;
        ocean_frame_destroy(k->nff[m]);
        k->nff[m] = NULL;
    }
    srv_tiles_clear(k->cache);
    k->tab_gen++;
    k->nf_in = nf;
    k->tab_valid = tables_make(&k->tab, oc, g, nf, order) == OCEAN_OK;
    if (!k->tab_valid)
        for (int i = 0; i < n; i++)
            srv_client_send_error(jobs[i].c, NULL, 0, OCEAN_ESTATE, "cascade tables unavailable");
    return k->tab_valid;
}

/* Stage 1: each job's mesh, then its plan (the mesh's finest lattice
 * decides which mips travel without geometry). */
static void plan_jobs(const tables *tb, const srv_config *cfg, srv_stats *st, srv_cascade_job *jobs, plan *pl,
                      int n)
{
    for (int i = 0; i < n; i++) {
        mesh_part(cfg, st, &jobs[i], &pl[i]);
        const proto_subscribe *sub = &jobs[i].cs->sub;
        int geo = pl[i].has_mesh && (sub->effects & PROTO_FX_NORMALS) && !(sub->flags & PROTO_SUB_FULL_GEOMETRY) &&
                  pl[i].mi.levels > 0;
        pl[i].geo = geo ? pl[i].mi.level_spacing_m[0] : 0.0;
        time_table(tb, cfg, &jobs[i], &pl[i]);
        plan_job(tb, cfg, &jobs[i], &pl[i]);
        pl[i].share_with = i;
        if (pl[i].tiles > (int)PROTO_MAX_FRAME_TILES) {
            char why[200];
            snprintf(why, sizeof why, "frame would need %d tiles, above the protocol's %u: subscribe a larger "
                     "tile_size", pl[i].tiles, PROTO_MAX_FRAME_TILES);
            srv_client_send_error(jobs[i].c, NULL, 0, OCEAN_ETOOBIG, why);
            pl[i].ok = 0;
            continue;
        }
        /* a time-interpolating client may need both samples of a tile */
        size_t cap = 2 * (size_t)(pl[i].tiles ? pl[i].tiles : 1);
        pl[i].list = calloc(cap, sizeof *pl[i].list);
        pl[i].tags = calloc(cap, sizeof *pl[i].tags);
        if (!pl[i].list || !pl[i].tags) pl[i].ok = 0;
    }
}

/* The tiles missing this batch, at their sample times. */
typedef struct missing_set {
    srv_tile **tile;
    size_t n, cap;
} missing_set;

/* One tile of plan p looked up in the cache (p->list); a fresh one joins ms. */
static void lookup_tile(srv_cascade *k, srv_stats *st, plan *p, int at, srv_tile_key *key, uint64_t gen,
                        missing_set *ms)
{
    int fresh = 0;
    srv_tile *tl = srv_tiles_get(k->cache, key, gen, &fresh);
    p->list[at] = tl;
    if (!tl) return;
    if (!fresh) {
        atomic_fetch_add(&st->tile_cache_hits, 1);
        return;
    }
    if (ms->n == ms->cap) {
        size_t nc = ms->cap ? 2 * ms->cap : 256;
        srv_tile **nm = realloc(ms->tile, nc * sizeof *nm);
        if (!nm) {
            tl->result = OCEAN_ENOMEM;
            return;
        }
        ms->tile = nm;
        ms->cap = nc;
    }
    ms->tile[ms->n++] = tl;
    atomic_fetch_add(&st->tile_cache_misses, 1);
}

/* Tiles per side of mip m. */
static int mip_tiles(const tables *tb, const srv_config *cfg, int m)
{
    int np = tb->n >> m, T = cfg->cascade_tile < np ? cfg->cascade_tile : np;
    return np / T;
}

/* Moves model h to plan pl's windows, as the client moves what it holds on
 * reading the frame. */
static void held_advance(const tables *tb, const srv_config *cfg, const plan *pl, srv_held *h)
{
    for (int c = 0; c < PROTO_MAX_LAYERS; c++) {
        int mips = c < pl->layers ? tb->mips[c] : 0;
        for (int m = 0; m < mips; m++) {
            int nt = mip_tiles(tb, cfg, m);
            if (srv_held_advance(h, c, m, &pl->time[c][m], nt * nt) != OCEAN_OK) srv_held_clear(h);
        }
        srv_held_drop(h, c, mips);
    }
}

/* A time-interpolating job's model of what its client holds (srv_held.h),
 * moved to this frame's windows as the client will move it.  Live, it is
 * built on what the client holds for sure: while its last frame may still
 * wait in the latest-wins slot (this frame would replace it) on what the
 * client holds with that frame and without it (srv_client_sim.h); a
 * frame the service thread has taken since is what it holds.  Building on
 * the state before the waiting frame alone would, whenever every frame is
 * planned while the one before waits (a writer slower than the tick),
 * start every frame from the same model, and a KEY frame capped at
 * SRV_CASCADE_BURST_A budgets would never make the sea whole.  A model
 * from other tables (a new sea), another tile side or the other mode
 * starts empty, and so the frame is a KEY frame. */
static void held_begin(srv_cascade *k, const srv_config *cfg, srv_cascade_job *j, plan *pl)
{
    srv_client_sim *cs = j->cs;
    const tables *tb = &k->tab;
    pl->held = NULL;
    pl->key = 0;
    if (!(cs->sub.flags & PROTO_SUB_TIME_INTERP)) return;
    for (int i = 0; i < 4; i++)
        if (!cs->held[i] && srv_held_create(&cs->held[i]) != OCEAN_OK) return;
    if (cs->held_gen != k->tab_gen || cs->held_tile != cfg->cascade_tile || cs->held_replay != j->replay) {
        for (int i = 0; i < 4; i++) srv_held_clear(cs->held[i]);
        cs->held_pending = 0;
        cs->held_gen = k->tab_gen;
        cs->held_tile = cfg->cascade_tile;
        cs->held_replay = j->replay;
    }
    srv_held *h = cs->held[SRV_HELD_AFTER];
    if (!j->replay) {
        if (cs->held_pending && !srv_outbox_frame_waiting(j->c->out)) {
            srv_held_copy(cs->held[SRV_HELD_KNOWN], cs->held[SRV_HELD_AFTER]);
            cs->held_pending = 0;
        }
        h = cs->held[SRV_HELD_NEXT];
        srv_held_copy(h, cs->held[SRV_HELD_KNOWN]);
    }
    held_advance(tb, cfg, pl, h);
    if (!j->replay && cs->held_pending) {
        srv_held *other = cs->held[SRV_HELD_SCRATCH];
        srv_held_copy(other, cs->held[SRV_HELD_AFTER]);
        held_advance(tb, cfg, pl, other);
        srv_held_meet(h, other);
    }
    /* keyed now, not when the batch ends: a replay client's next frame in
     * this batch continues from this one, as it does in the next batch */
    pl->key = srv_held_key(h);
    if (pl->key) srv_held_keyed(h);
    pl->held = h;
}

void srv_cascade_handed_over(const srv_cascade_job *j, int published, int replaced)
{
    srv_client_sim *cs = j->cs;
    if (j->replay || !published || !(cs->sub.flags & PROTO_SUB_TIME_INTERP) || !cs->held[SRV_HELD_NEXT]) return;
    /* the frame before was taken, not replaced: the client holds it */
    if (cs->held_pending && !replaced) srv_held_copy(cs->held[SRV_HELD_KNOWN], cs->held[SRV_HELD_AFTER]);
    srv_held *t = cs->held[SRV_HELD_AFTER];
    cs->held[SRV_HELD_AFTER] = cs->held[SRV_HELD_NEXT];
    cs->held[SRV_HELD_NEXT] = t;
    cs->held_pending = 1;
}

/* One needed tile (c, m, ix, iz) of job j in pass `pass`: pass 0 the tile
 * at the frame's time, or its window's sample A if the client lacks it;
 * pass 1 its sample B if the client lacks it.  The plan prices a held mip
 * at its share per frame (refresh_share), but what a client lacks can
 * come at once: a KEY frame holds every sample, a frame that replaces an
 * unsent one what both carry, a window's start the B of all the mip's
 * tiles.  So the held samples a frame carries stop at a cap: every A
 * first, coarse mips and cascades first, up to SRV_CASCADE_BURST_A frame
 * budgets, so the client's sea is whole at once (a camera moving fast
 * needs both samples of every tile coming into view), then the B samples
 * up to SRV_CASCADE_BURST budgets in all, the windows ending soonest first
 * (the client reads A alone until a tile's B comes: PROTOCOL.md "Samples
 * in time"); the rest stay lacking in the model and go with the next
 * frames.  One sample always goes, whatever its size, so the stream always
 * progresses. */
static void lookup_needed(srv_cascade *k, srv_stats *st, const srv_cascade_job *j, plan *p, srv_tile_key *key,
                          int ntile, int pass, uint64_t gen, missing_set *ms, int *at)
{
    int c = key->cascade, m = key->level, i = key->iz * ntile + key->ix;
    if (!p->time[c][m].interval || !p->held) {
        if (pass) return;
        key->t = j->t;
        p->tags[*at] = (uint32_t)c;
        lookup_tile(k, st, p, (*at)++, key, gen, ms);
        return;
    }
    if (srv_held_has(p->held, c, m, pass, i, key->channels)) return;
    double cost = srv_cascade_tile_bytes(&j->cs->sub, key->channels, key->size);
    double cap = (pass ? SRV_CASCADE_BURST : SRV_CASCADE_BURST_A) * p->budget;
    if (p->burst > 0 && p->burst + cost > cap) return;
    p->burst += cost;
    key->t = p->t_ab[c][m][pass];
    p->tags[*at] = (uint32_t)c | (pass ? PROTO_TAG_SLOT_B : 0u);
    lookup_tile(k, st, p, (*at)++, key, gen, ms);
    srv_held_add(p->held, c, m, pass, i, key->channels);
}

/* The mips of plan p in the order lookup_job visits them in `pass`: coarse
 * mips and cascades first; pass 1 (B samples) by the ticks left in their
 * windows first (earliest deadline first: a B not come by its window's end
 * is a tile lost at the shift), then coarse first.  Returns the count. */
static int mip_order(const tables *tb, const plan *p, int pass, int order[][2])
{
    int n = 0;
    for (int c = 0; c < p->layers; c++)
        for (int m = tb->mips[c] - 1; m >= 0; m--)
            if (p->need[c][m]) order[n][0] = c, order[n++][1] = m;
    for (int i = 1; pass && i < n; i++)   /* insertion sort: stable, a few dozen mips */
        for (int k = i; k > 0; k--) {
            const proto_mip_time *x = &p->time[order[k][0]][order[k][1]];
            const proto_mip_time *y = &p->time[order[k - 1][0]][order[k - 1][1]];
            double lx = x->interval * (65536.0 - x->phase), ly = y->interval * (65536.0 - y->phase);
            if (lx >= ly) break;
            int t0 = order[k][0], t1 = order[k][1];
            order[k][0] = order[k - 1][0], order[k][1] = order[k - 1][1];
            order[k - 1][0] = t0, order[k - 1][1] = t1;
        }
    return n;
}

/* Every tile job j's plan p needs, from the cache or into ms: the tiles
 * at the frame's time and the A samples, then the B samples (see
 * lookup_needed and mip_order). */
static void lookup_job(srv_cascade *k, const srv_config *cfg, srv_stats *st, const srv_cascade_job *j, plan *p,
                       uint64_t gen, missing_set *ms)
{
    const tables *tb = &k->tab;
    const proto_subscribe *sub = &j->cs->sub;
    int at = 0, order[PROTO_MAX_LAYERS * MAX_MIPS][2];
    for (int pass = 0; pass < (p->held ? 2 : 1); pass++) {
        int n = mip_order(tb, p, pass, order);
        for (int o = 0; o < n; o++) {
            int c = order[o][0], m = order[o][1];
            int np = tb->n >> m, T = cfg->cascade_tile < np ? cfg->cascade_tile : np, ntile = np / T;
            const range *rg = &p->r[c][m];
            for (int a = 0; a < rg->nz; a++)
                for (int b = 0; b < rg->nx; b++) {
                    srv_tile_key key;
                    srv_tile_key_init(&key);
                    key.accuracy = sub->accuracy;
                    key.ix = (rg->x0 + b) % ntile;
                    key.iz = (rg->z0 + a) % ntile;
                    key.channels = (uint16_t)chan_of(tb, p, c, m);
                    key.size = (uint16_t)T;
                    key.layout = PROTO_LAYOUT_CASCADE;
                    key.cascade = (uint8_t)c;
                    key.level = (uint8_t)m;
                    key.codec = sub->codec;
                    lookup_needed(k, st, j, p, &key, ntile, pass, gen, ms, &at);
                }
        }
    }
    p->tiles = at;
}

/* Stage 2: every job's tiles looked up in job order (a client's model of
 * what it holds moves frame by frame), then, per distinct sample time,
 * the mips the missing tiles need evaluated (a tile cached under another
 * channel set is a distinct key, so every missing tile's mip is evaluated
 * with its channels) and the missing tiles encoded on the workers. */
static void tiles_by_time(srv_cascade *k, ocean *oc, ocean *nf, const srv_config *cfg, srv_stats *st,
                          srv_cascade_job *jobs, plan *pl, int n, uint64_t gen)
{
    const tables *tb = &k->tab;
    missing_set ms = {0};
    for (int i = 0; i < n; i++) {
        if (!pl[i].ok) continue;
        held_begin(k, cfg, &jobs[i], &pl[i]);
        lookup_job(k, cfg, st, &jobs[i], &pl[i], gen, &ms);
    }
    srv_tile **at_t = ms.n ? malloc(ms.n * sizeof *at_t) : NULL;
    char *done = ms.n ? calloc(ms.n, 1) : NULL;
    for (size_t q0 = 0; q0 < ms.n && at_t && done; q0++) {
        if (done[q0]) continue;
        double t = ms.tile[q0]->key.t;
        unsigned need_fx[PROTO_MAX_LAYERS][MAX_MIPS];
        memset(need_fx, 0, sizeof need_fx);
        size_t nt = 0;
        for (size_t q = q0; q < ms.n; q++) {
            if (done[q] || ms.tile[q]->key.t != t) continue;
            done[q] = 1;
            at_t[nt++] = ms.tile[q];
            need_fx[ms.tile[q]->key.cascade][ms.tile[q]->key.level] |= ocean_fx_of(ms.tile[q]->key.channels);
        }
        ocean_result r = eval_mips(k, oc, nf, tb, t, need_fx, st);
        if (r != OCEAN_OK) {
            for (size_t q = 0; q < nt; q++) at_t[q]->result = r;
            continue;
        }
#pragma omp parallel for schedule(dynamic, 1) num_threads(cfg->workers)
        for (size_t q = 0; q < nt; q++)
            tile_build(at_t[q], at_t[q]->key.cascade < tb->fft ? k->mipf[at_t[q]->key.level]
                                                               : k->nff[at_t[q]->key.level], tb);
        atomic_fetch_add(&st->tiles_encoded, (uint64_t)nt);
    }
    if (ms.n && (!at_t || !done))
        for (size_t q = 0; q < ms.n; q++) ms.tile[q]->result = OCEAN_ENOMEM;
    free(at_t);
    free(done);
    free(ms.tile);
}

/* Stage 3: frames; live jobs with the same frame share one encoding. */
static void frames_of(const tables *tb, const srv_config *cfg, srv_stats *st, srv_cascade_job *jobs, plan *pl,
                      int n)
{
    for (int i = 0; i < n; i++) {
        if (!pl[i].ok || jobs[i].replay) continue;
        for (int l = 0; l < i; l++)
            if (pl[l].ok && !jobs[l].replay && pl[l].share_with == l &&
                same_frame(&jobs[l], &pl[l], &jobs[i], &pl[i])) {
                pl[i].share_with = l;
                break;
            }
    }
#pragma omp parallel for schedule(dynamic, 1) num_threads(cfg->workers)
    for (int i = 0; i < n; i++)
        if (pl[i].ok && pl[i].share_with == i) frame_build(tb, &jobs[i], &pl[i], !jobs[i].replay);
    for (int i = 0; i < n; i++) {
        int l = pl[i].share_with;
        if (!pl[i].ok || l == i) continue;
        if (l >= 0 && jobs[l].frame && jobs[l].frame->blob && pl[l].share_with == l) {
            jobs[i].frame = srv_msg_share(jobs[l].frame);
            if (jobs[i].frame) {
                jobs[i].frame->camera_seq = jobs[i].cam_seq;
                jobs[i].frame->mesh_id = jobs[i].cs->mesh_id;
                atomic_fetch_add(&st->frames_shared, 1);
                continue;
            }
        }
        frame_build(tb, &jobs[i], &pl[i], 0);
    }
}

/* The model of a time-interpolating client after its frame: when the
 * frame or one of its tiles could not be made, the client's holdings are
 * no longer known: the next frame is a KEY frame. */
static void held_end(const srv_cascade_job *j, plan *pl)
{
    if (!pl->held) return;
    int whole = pl->ok && j->frame;
    for (int i = 0; whole && i < pl->tiles; i++)
        whole = pl->list[i] && pl->list[i]->result == OCEAN_OK && pl->list[i]->payload;
    if (!whole) srv_held_clear(pl->held);
}

void srv_cascade_run(srv_cascade *k, ocean *oc, const ocean_gerstner *g, ocean *nf, int order,
                     const srv_config *cfg, srv_stats *st, srv_cascade_job *jobs, int n, uint64_t gen)
{
    if (n <= 0 || !tables_current(k, oc, g, nf, order, jobs, n)) return;
    plan *pl = calloc((size_t)n, sizeof *pl);
    if (!pl) return;
    plan_jobs(&k->tab, cfg, st, jobs, pl, n);
    tiles_by_time(k, oc, nf, cfg, st, jobs, pl, n, gen);
    frames_of(&k->tab, cfg, st, jobs, pl, n);
    for (int i = 0; i < n; i++) {
        held_end(&jobs[i], &pl[i]);
        free(pl[i].list);
        free(pl[i].tags);
    }
    free(pl);
}
