/*
 * srv_sim.c - the simulation thread (see srv_sim.h).
 *
 * A batch is a set of frame jobs (client, time, camera).  Running a batch:
 *   1. evaluate each distinct (time, group) once, serially (the ocean is
 *      single-threaded; FFTW uses ocean.threads inside);
 *   2. look every job's tiles up in the tile cache and encode the missing
 *      ones in parallel (server.workers threads);
 *   3. per client, in parallel: mesh build + displacement + FRAME encoding;
 *   4. hand the bytes to the clients and wake the service thread.
 */
#include "srv_sim.h"
#include "ocean_time.h"

#include <errno.h>
#include <float.h>
#include <malloc.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "gerstner.h"
#include "ocean_plan.h"
#include "query.h"
#include "srv_admit.h"
#include "srv_cascade.h"
#include "srv_seabuild.h"
#include "srv_tiles.h"
#include "srv_wakes.h"
#include "srv_work.h"

#define EVAL_MAX 8
#define MAX_TILES_PER_JOB (PROTO_MAX_LOD_LEVELS * 64)

typedef struct group {
    int32_t bucket;   /* -1: unfiltered query group */
    int32_t layers;
    float boost;
} group;

typedef struct eval_entry {
    int used;
    double t;
    group g;
    unsigned effects;
    ocean_frame *f;
    ocean_frame_info info;
    uint64_t last_use;
} eval_entry;

typedef struct job {
    srv_client *c;
    srv_client_sim *cs;     /* the client's entry in the simulation thread's table */
    double t;
    proto_camera cam;
    uint32_t cam_seq;
    int replay;
    uint32_t tick;
    int64_t tick_no;        /* live: the tick, unwrapped */
    group g;
    double cutoff_k;
    ocean_filter_cutoff cut;
    unsigned need;          /* ocean effects needed */
    eval_entry *ev;
    srv_tile **tiles;
    int ntiles;
    srv_msg *topo, *frame;
    int sub_changed;
    int leader;             /* live: index of the job whose mesh this one shares */
    int mesh_ok;
    mesh_view mv;           /* the displaced mesh (valid when mesh_ok) */
    int fshare;             /* live: index of the job whose FRAME bytes this one shares */
    int has_mesh;           /* the FRAME carries a mesh */
    int no_share;           /* its FRAME bytes cannot be shared */
    uint8_t *mesh_qz;       /* mesh_codec qz: the MESH_VERTICES_QZ payload of
                               the displaced mesh (malloc'd, freed at hand-over);
                               NULL: positions travel as f32 */
    uint32_t mesh_qz_len;
} job;

struct srv_sim {
    srv_hub *hub;
    pthread_t thread;
    int running;
    int stop;                   /* [hub.lock] */
    /* everything below: [sim] */
    srv_settings set;           /* copy of the hub's settings */
    uint64_t set_gen;
    ocean *oc;
    ocean_gerstner *g;
    ocean *nf;                  /* the near field as a lattice cascade (layout 1), or NULL */
    ocean_filter_config fcfg;
    ocean_filter_buckets buckets;
    double lambda_dom;
    double roughness;           /* mesh_roughness of the sea in force */
    srv_seabuild *build;        /* the next sea change's ocean, built ahead */
    uint64_t sea_gen;           /* hub.sea_gen last seen */
    eval_entry ev[EVAL_MAX];
    uint64_t use;
    srv_tile_cache *tiles;
    srv_cascade *casc;          /* layout-1 products shared by every camera */
    uint64_t gen;
    uint64_t tick_no;
    double camera_hint[5];
    srv_work *work;             /* queries in slices (srv_work.c) */
    srv_client_table *table;    /* what this thread keeps of each client */
    double work_due;            /* monotonic: background work's next turn */
    int query_deferred;         /* ticks in a row with no slack for query work */
    double eval_s;              /* measured seconds of one ocean evaluation (EWMA) */
    double replay_s[2];         /* measured seconds of one replay frame, by layout (EWMA; 0: none yet) */
    uint32_t replay_last;       /* the replay client first in the last turn (its id) */
    int holding;                /* caches may hold tiles or evaluations */
    double turn_wall;           /* monotonic: the last turn's start */
};

/* ---- ocean construction ----------------------------------------------------- */

ocean_result srv_sim_sea_check(const srv_settings *s, const ocean_params *p, char *msg, size_t msglen)
{
    srv_sea_ocean o;
    ocean_result r = srv_sea_ocean_build(s, p, 0, &o, msg, msglen);
    srv_sea_ocean_free(&o);
    return r;
}

static void eval_clear(srv_sim *s)
{
    for (int i = 0; i < EVAL_MAX; i++) {
        ocean_frame_destroy(s->ev[i].f);
        memset(&s->ev[i], 0, sizeof s->ev[i]);
    }
}

static void adopt_sea(srv_sim *s, const ocean_params *p)
{
    s->set.params = *p;
    ocean_filter_config_default(&s->fcfg, &p->sea);
    double lam = 0;
    if (mesh_lambda_dominant(&p->sea, &lam) != OCEAN_OK) lam = 0;
    s->lambda_dom = lam;
    s->roughness = mesh_roughness(&p->sea);
}

static eval_entry *evaluate(srv_sim *s, double t, const group *g, unsigned effects);
static void tile_cost(srv_sim *s, const srv_tile *t, double cpu_s);

/* Admission's first prices (srv_admit.h): a 64^2 tile of the scene's
 * channels in each codec the server offers, sampled from an evaluation at
 * t = 0, before any client can ask; the live tiles' costs refine them. */
static void calibrate(srv_sim *s)
{
    group g = {.bucket = -1, .layers = ocean_get_params(s->oc)->cascades, .boost = 1.0f};
    unsigned fx = s->set.effects & OCEAN_FX_ALL, ch = srv_tiles_channels(fx);
    eval_entry *ev = ch ? evaluate(s, 0.0, &g, fx) : NULL;
    for (int c = 0; ev && c < PROTO_CODEC_COUNT_; c++) {
        if (!(s->set.srv.codecs & (1u << c))) continue;
        srv_tile t;
        memset(&t, 0, sizeof t);
        srv_tile_key_init(&t.key);
        t.key.spacing = s->set.srv.base_spacing;
        t.key.bucket = g.bucket;
        t.key.boost = g.boost;
        t.key.accuracy = (float)PROTO_ACCURACY_DEFAULT;
        t.key.channels = (uint16_t)ch;
        t.key.size = 64;
        t.key.codec = (uint8_t)c;
        t.key.layers = (uint8_t)g.layers;
        /* the second build is timed: the first makes the thread's codec
         * context and warms the caches, which no live tile pays for */
        for (int pass = 0; pass < 2; pass++) {
            double c0 = srv_admit_thread_cpu();
            srv_tile_build(&t, ev->f);
            if (pass == 1 && t.result == OCEAN_OK) tile_cost(s, &t, srv_admit_thread_cpu() - c0);
            free(t.payload);
            t.payload = NULL;
        }
    }
    eval_clear(s);
}

ocean_result srv_sim_create(srv_hub *h, srv_sim **out, char *msg, size_t msglen)
{
    srv_sim *s = calloc(1, sizeof *s);
    if (!s) return OCEAN_ENOMEM;
    s->hub = h;
    pthread_mutex_lock(&h->lock);
    s->set = h->settings;
    s->set_gen = h->settings_gen;
    pthread_mutex_unlock(&h->lock);
    srv_sea_ocean o;
    double b0 = srv_now();
    ocean_result r = srv_sea_ocean_build(&s->set, &s->set.params, 1, &o, msg, msglen);
    pthread_mutex_lock(&h->lock);
    h->sea_build_s = srv_now() - b0; /* the first lead (srv_hub_sea_lead) */
    pthread_mutex_unlock(&h->lock);
    s->oc = o.oc;
    s->g = o.g;
    s->nf = o.nf;
    if (r == OCEAN_OK) r = srv_seabuild_create(&s->build);
    if (r == OCEAN_OK) r = srv_tiles_create(&s->tiles);
    if (r == OCEAN_OK) r = srv_cascade_create(&s->casc);
    if (r == OCEAN_OK) r = srv_work_create(&s->work);
    if (r == OCEAN_OK) r = srv_client_table_create(&s->table);
    if (r != OCEAN_OK) {
        srv_sim_destroy(s);
        return r;
    }
    adopt_sea(s, &s->set.params);
    ocean_filter_buckets_default(&s->buckets);
    double v[5] = {0, 20, 0, 0, 0};
    if (s->set.scene.camera_hint[0]) ocean_conf_camera_hint_parse(s->set.scene.camera_hint, v);
    memcpy(s->camera_hint, v, sizeof v);
    calibrate(s);
    *out = s;
    return OCEAN_OK;
}

void srv_sim_destroy(srv_sim *s)
{
    if (!s) return;
    srv_sim_stop(s);
    srv_work_destroy(s->work);
    srv_client_table_destroy(s->table);
    eval_clear(s);
    srv_tiles_destroy(s->tiles);
    srv_cascade_destroy(s->casc);
    ocean_gerstner_destroy(s->g);
    ocean_destroy(s->nf);
    ocean_destroy(s->oc);
    srv_seabuild_destroy(s->build);
    free(s);
}

/* ---- evaluation cache ------------------------------------------------------- */

static int group_eq(const group *a, const group *b)
{
    return a->bucket == b->bucket && a->layers == b->layers && a->boost == b->boost;
}

static double group_cutoff(const srv_sim *s, const group *g)
{
    if (g->bucket < 0) return INFINITY;
    double k = INFINITY;
    ocean_filter_bucket_cutoff(&s->buckets, g->bucket, &k);
    return k;
}

/* Returns an entry holding an evaluation at (t, g) with at least `effects`. */
static eval_entry *evaluate(srv_sim *s, double t, const group *g, unsigned effects)
{
    eval_entry *hit = NULL, *victim = NULL;
    for (int i = 0; i < EVAL_MAX; i++) {
        eval_entry *e = &s->ev[i];
        if (e->used && e->t == t && group_eq(&e->g, g)) { hit = e; break; }
    }
    if (hit && (hit->effects & effects) == effects) {
        hit->last_use = ++s->use;
        return hit;
    }
    if (hit) {
        effects |= hit->effects;
        victim = hit;
    } else {
        for (int i = 0; i < EVAL_MAX; i++) {
            eval_entry *e = &s->ev[i];
            if (!victim || !e->used || (victim->used && e->last_use < victim->last_use)) victim = e;
            if (!e->used) break;
        }
    }
    if (!victim->f && ocean_frame_create(s->oc, &victim->f) != OCEAN_OK) return NULL;
    ocean_request rq;
    memset(&rq, 0, sizeof rq);
    int cascades = ocean_get_params(s->oc)->cascades;
    for (int c = 0; c < cascades && c < g->layers; c++) rq.effects[c] = effects & ~OCEAN_FX_NEAR_FIELD;
    rq.cutoff_k = group_cutoff(s, g);
    rq.order = s->fcfg.order;
    rq.redistribute = 0;
    rq.low_boost = g->boost;
    victim->used = 0;
    double e0 = srv_now();
    if (ocean_evaluate(s->oc, t, &rq, victim->f) != OCEAN_OK) return NULL;
    s->eval_s = s->eval_s > 0 ? 0.8 * s->eval_s + 0.2 * (srv_now() - e0) : srv_now() - e0;
    victim->used = 1;
    victim->t = t;
    victim->g = *g;
    victim->effects = effects;
    victim->last_use = ++s->use;
    ocean_frame_get_info(victim->f, &victim->info);
    srv_stats *st = &s->hub->stats;
    atomic_fetch_add(&st->evaluations, 1);
    return victim;
}

static void publish_counters(srv_sim *s)
{
    ocean_counters oc;
    ocean_get_counters(s->oc, &oc);
    /* Counters restart with each new ocean; keep the totals monotone. */
    static __thread uint64_t base[SRV_FX_CHANNELS + 1], last[SRV_FX_CHANNELS + 1];
    static __thread const ocean *seen;
    if (seen != s->oc) {
        for (int i = 0; i <= SRV_FX_CHANNELS; i++) base[i] += last[i];
        memset(last, 0, sizeof last);
        seen = s->oc;
    }
    srv_stats *st = &s->hub->stats;
    for (int i = 0; i < SRV_FX_CHANNELS; i++) {
        last[i] = oc.transforms_by_effect[i];
        atomic_store(&st->transforms_by_effect[i], base[i] + last[i]);
    }
    last[SRV_FX_CHANNELS] = oc.transforms;
    atomic_store(&st->transforms, base[SRV_FX_CHANNELS] + oc.transforms);
}

/* ---- per-client pieces ------------------------------------------------------ */

static void default_camera(const srv_sim *s, proto_camera *c)
{
    memset(c, 0, sizeof *c);
    c->pos[0] = s->camera_hint[0];
    c->pos[1] = s->camera_hint[1];
    c->pos[2] = s->camera_hint[2];
    c->yaw_deg = (float)s->camera_hint[3];
    c->pitch_deg = (float)s->camera_hint[4];
    c->fov_y_deg = 60;
    c->viewport_w = 1280;
    c->viewport_h = 720;
}

static double base_spacing(const srv_sim *s, const proto_subscribe *sub)
{
    return sub->base_spacing_m > 0 ? sub->base_spacing_m : s->set.srv.base_spacing;
}

/* Chooses the client's cutoff for this frame and its evaluation group. */
static void choose_cutoff(srv_sim *s, job *j)
{
    srv_client_sim *cs = j->cs;
    const proto_subscribe *sub = &cs->sub;
    ocean_filter_client cl;
    cl.speed_mps = sqrt((double)j->cam.vel[0] * j->cam.vel[0] + (double)j->cam.vel[1] * j->cam.vel[1] +
                        (double)j->cam.vel[2] * j->cam.vel[2]);
    cl.fps = sub->frame_rate_hz;
    cl.spacing_m = base_spacing(s, sub);
    ocean_filter_cutoff cut;
    if (ocean_filter_cutoff_compute(&s->fcfg, (ocean_filter_policy)sub->cutoff_policy, &cl, &cut) !=
        OCEAN_OK) {
        cut.k = INFINITY;
        cut.low_boost = 1;
        cut.order = s->fcfg.order;
    }
    double dt = cs->primed ? j->t - cs->last_t : 0;
    if (!(dt >= 0) || !isfinite(dt)) dt = 0; /* replay may jump back: no smoothing step */
    double k = cut.k;
    if (ocean_filter_smoother_update(&cs->smoother, cut.k, dt, &k) != OCEAN_OK) k = cut.k;
    cs->primed = 1;
    cs->last_t = j->t;
    cs->cutoff_k = k;
    int b = 0;
    if (ocean_filter_bucket_of(&s->buckets, k, &b) != OCEAN_OK) b = ocean_filter_bucket_count(&s->buckets) - 1;
    j->g.bucket = b;
    j->g.layers = sub->layers;
    j->g.boost = (float)(cut.low_boost > 0 ? cut.low_boost : 1.0);
    /* The frame reports the bucket's cutoff; but a bucket above every wave
     * the ocean holds filters nothing, so its group is the unfiltered one:
     * it shares that evaluation (and its tiles) instead of repeating it. */
    j->cutoff_k = group_cutoff(s, &j->g);
    if (isinf(ocean_effective_cutoff(s->oc, j->cutoff_k, s->fcfg.order)))
        ocean_filter_bucket_of(&s->buckets, INFINITY, &j->g.bucket);
    j->cut = cut;
    j->cut.k = j->cutoff_k;
    j->cut.low_boost = j->g.boost;
    j->need = sub->effects & OCEAN_FX_ALL;
    if (sub->mesh_kind != PROTO_MESH_NONE)
        j->need |= OCEAN_FX_HEIGHT | (sub->effects & OCEAN_FX_DISPLACEMENT);
    if (!(j->need & OCEAN_FX_ALL)) j->need |= OCEAN_FX_HEIGHT;
}

/* The velocity policy's cutoff for a layout-1 frame.  Tiles of that layout
 * are world-fixed samples: a sample that does not move does not see the
 * camera's motion, so the antialias policy's temporal limit
 * (omega + |v| k < pi fps) does not apply to them and only the level's own
 * spacing limits what it carries (PROTOCOL.md "Layouts").  The seed policy
 * (f_c = f_base + beta |v|, as seed 000 writes it) still chooses a cutoff;
 * what it removes is carried as unresolved slope variance. */
static double layout1_policy(srv_sim *s, const proto_subscribe *sub, const proto_camera *cam)
{
    if (sub->cutoff_policy != PROTO_CUTOFF_SEED) return INFINITY;
    ocean_filter_client cl;
    cl.speed_mps = sqrt((double)cam->vel[0] * cam->vel[0] + (double)cam->vel[1] * cam->vel[1] +
                        (double)cam->vel[2] * cam->vel[2]);
    cl.fps = sub->frame_rate_hz;
    cl.spacing_m = base_spacing(s, sub);
    ocean_filter_cutoff cut;
    if (ocean_filter_cutoff_compute(&s->fcfg, OCEAN_FILTER_SEED, &cl, &cut) != OCEAN_OK) return INFINITY;
    return cut.k > 0 ? cut.k : INFINITY;
}

/* Builds the layout-1 frames of a batch and hands them to their clients. */
static void run_cascade(srv_sim *s, srv_cascade_job *cj, int n, double tick_wall)
{
    if (n <= 0) return;
    srv_stats *st = &s->hub->stats;
    s->gen++;
    double p0 = srv_now();
    srv_cascade_run(s->casc, s->oc, s->g, s->nf, s->fcfg.order, &s->set.srv, st, cj, n, s->gen);
    static int prof = -1;
    if (prof < 0) prof = getenv("OCEAND_PROFILE") != NULL;
    if (prof) fprintf(stderr, "cascade batch %d jobs: %.2f ms\n", n, (srv_now() - p0) * 1e3);
    for (int i = 0; i < n; i++) {
        srv_cascade_job *j = &cj[i];
        int published = j->frame != NULL;
        int replaced = srv_client_hand_over(j->c, st, j->topo, j->frame, j->replay, tick_wall);
        srv_cascade_handed_over(j, published, replaced);
        j->topo = j->frame = NULL;
    }
    srv_hub_wake_net(s->hub);
}

/* Rebuilds the client's mesh object after a new subscription. */
static void apply_subscription(srv_sim *s, srv_client *c, srv_client_sim *cs)
{
    mesh_destroy(cs->mesh);
    cs->mesh = NULL;
    cs->topo_valid = 0;
    cs->mesh_coarsen = 0;
    cs->primed = 0;
    /* the client drops what it holds on the next frame (a KEY frame) */
    for (int i = 0; i < 4; i++) srv_held_clear(cs->held[i]);
    cs->held_pending = 0;
    /* a new subscription keeps the stream's schedule at its own rate: a
     * client cannot buy frames by re-subscribing */
    cs->next_frame_t = cs->framed ? cs->last_frame_t + 1.0 / cs->sub.frame_rate_hz : -INFINITY;
    ocean_filter_smoother_init(&cs->smoother);
    if (cs->sub.mesh_kind == PROTO_MESH_NONE) return;
    mesh_config mc;
    mesh_config_default(&mc);
    mc.kind = (mesh_kind)cs->sub.mesh_kind;
    mc.range_m = cs->sub.view_range_m > 0 ? cs->sub.view_range_m : s->set.srv.view_range;
    if (mc.range_m < 10) mc.range_m = 10;
    if (mc.range_m > 1e6) mc.range_m = 1e6;
    mc.error_px = cs->sub.layout == PROTO_LAYOUT_CASCADE ? s->set.srv.flat_mesh_error_px : s->set.srv.mesh_error_px;
    mc.lambda_dominant_m = s->lambda_dom;
    mc.roughness = s->roughness;
    /* what MESH_TOPOLOGY can carry: a camera near the water with a long
     * range gets a coarser core, not a mesh the frame cannot hold (which
     * would be built, refused, and leave the client without a mesh until
     * its next SUBSCRIBE) */
    mc.max_levels = PROTO_MAX_LOD_LEVELS;
    char msg[256];
    ocean_result r = mesh_config_validate(&mc, msg, sizeof msg);
    if (r == OCEAN_OK) r = mesh_create(&mc, &cs->mesh);
    if (r != OCEAN_OK) {
        char why[400];
        snprintf(why, sizeof why, "mesh %s unavailable, frames come without a mesh: %s",
                 mesh_kind_name(mc.kind), r == OCEAN_EINVAL ? msg : ocean_strerror(r));
        srv_client_send_error(c, NULL, 0, r, why);
        cs->mesh = NULL;
    }
    cs->mesh_cfg = mc;
}

typedef struct sampler_ctx {
    const ocean_frame *f;
    ocean_gerstner_frame *gf;   /* near field prepared once per mesh, or NULL */
    ocean_gerstner_view view;
    int disp;
} sampler_ctx;

static void sample_disp(void *ctx, double x, double z, double out[3])
{
    const sampler_ctx *sc = ctx;
    ocean_point p;
    ocean_frame_sample_some(sc->f, x, z, OCEAN_SAMPLE_HEIGHT | (sc->disp ? OCEAN_SAMPLE_DISPLACEMENT : 0),
                            &p);
    out[0] = sc->disp ? p.dx : 0;
    out[1] = p.height;
    out[2] = sc->disp ? p.dz : 0;
    if (sc->gf) {
        double dx = x - sc->view.camera_x, dz = z - sc->view.camera_z;
        if (dx * dx + dz * dz < sc->view.fade_r1 * sc->view.fade_r1) {
            double gd[3];
            if (ocean_gerstner_frame_displacement(sc->gf, &x, &z, 1, gd) == OCEAN_OK) {
                if (sc->disp) {
                    out[0] += gd[0];
                    out[2] += gd[2];
                }
                out[1] += gd[1];
            }
        }
    }
}


/* Encodes job j's displaced mesh as MESH_VERTICES_QZ at the subscription's
 * accuracy, once for every viewer that shares the mesh (same_mesh asks
 * them for the same mesh codec and accuracy), with the worker's codec
 * context.  The topology's prediction references are kept per client
 * until its topology changes.  On failure j->mesh_qz stays NULL and the
 * frame carries f32 positions, which every client decodes [worker thread
 * owning the client]. */
static void mesh_qz_stage(srv_client_sim *cs, job *j)
{
    const mesh_view *v = &j->mv;
    if (!cs->qz_refs || cs->qz_refs_key != v->topology_key || cs->qz_refs_n != v->vertex_count) {
        uint32_t *refs = realloc(cs->qz_refs, 3 * sizeof *refs * (size_t)v->vertex_count);
        if (!refs) return;
        cs->qz_refs = refs;
        cs->qz_refs_n = 0;
        if (proto_mesh_qz_refs(v->indices, v->index_count, v->vertex_count, refs) != OCEAN_OK) return;
        cs->qz_refs_key = v->topology_key;
        cs->qz_refs_n = v->vertex_count;
    }
    proto_buf b;
    proto_buf_init(&b, 0);
    if (proto_mesh_qz_encode(srv_tiles_codec_ctx(), cs->sub.accuracy, v->vertex_count, v->positions, cs->qz_refs,
                             &b, NULL, NULL, 0) == OCEAN_OK && proto_buf_len(&b) <= UINT32_MAX) {
        j->mesh_qz = b.mem;   /* no headroom: the payload starts at mem */
        j->mesh_qz_len = (uint32_t)proto_buf_len(&b);
        return;
    }
    proto_buf_free(&b);
}

/* Builds and displaces the client's mesh for job j [worker thread; the
 * client's sim state is only touched by the one worker that owns it]. */
static void mesh_stage(srv_sim *s, job *j)
{
    srv_client *c = j->c;
    srv_client_sim *cs = j->cs;
    j->mesh_ok = 0;
    if (!cs->mesh) return;
    mesh_camera mc;
    srv_mesh_camera(&j->cam, &mc);
    /* Priced before it is built: a camera the protocol allows may ask for
     * a mesh no server should build (a 1-degree 1080p camera: 10^7
     * vertices).  Steep chop asks for a finer mesh than its budget alone,
     * and gets a coarser budget up to the mesh's largest; beyond that its
     * frames come without a mesh, with one ERROR naming the limit, until a
     * camera asks for less (srv_client_sim_mesh_fit). */
    if (!srv_client_sim_mesh_fit(cs, c, &mc, s->set.srv.max_mesh_vertices, j->cam_seq, &s->hub->stats)) return;
    double m0 = srv_now();
    ocean_result r = mesh_build(cs->mesh, &mc);
    if (r == OCEAN_OK) {
        sampler_ctx sc;
        memset(&sc, 0, sizeof sc);
        sc.f = j->ev->f;
        sc.disp = (cs->sub.effects & OCEAN_FX_DISPLACEMENT) != 0;
        if (s->g && (cs->sub.effects & OCEAN_FX_NEAR_FIELD)) {
            sc.view.camera_x = j->cam.pos[0];
            sc.view.camera_z = j->cam.pos[2];
            sc.view.fade_r1 = s->set.srv.near_field_radius;
            sc.view.fade_r0 = 0.5 * sc.view.fade_r1;
            sc.view.filter = j->cut;
            /* The per-wave work (gains, Q, phases at t) once per mesh, not
             * once per vertex; without memory the mesh goes without it. */
            if (ocean_gerstner_frame_create(s->g, &sc.gf) == OCEAN_OK &&
                ocean_gerstner_frame_set(sc.gf, &sc.view, j->t) != OCEAN_OK) {
                ocean_gerstner_frame_destroy(sc.gf);
                sc.gf = NULL;
            }
        }
        r = mesh_displace(cs->mesh, sample_disp, &sc);
        ocean_gerstner_frame_destroy(sc.gf);
    }
    if (r == OCEAN_OK) {
        mesh_get_view(cs->mesh, &j->mv);
        if (j->mv.levels > PROTO_MAX_LOD_LEVELS || j->mv.vertex_count == 0) r = OCEAN_ETOOBIG;
    }
    if (r == OCEAN_OK && cs->sub.mesh_codec == PROTO_MESH_CODEC_QZ) mesh_qz_stage(cs, j);
    atomic_fetch_add(&c->cpu_ns, (uint64_t)((srv_now() - m0) * 1e9));
    if (r != OCEAN_OK) {
        char why[256];
        snprintf(why, sizeof why, "mesh build failed (%s); frames come without a mesh until "
                 "the next SUBSCRIBE", ocean_strerror(r));
        srv_client_send_error(c, NULL, 0, r, why);
        mesh_destroy(cs->mesh);
        cs->mesh = NULL;
        return;
    }
    j->mesh_ok = 1;
}

/* The client's side of a frame with the mesh of job src: a new
 * MESH_TOPOLOGY (j->topo) when the client has not seen this topology.
 * Returns 1 if the frame carries a mesh [worker thread owning the client]. */
static int topo_stage(job *j, const job *src)
{
    srv_client_sim *cs = j->cs;
    if (!src->mesh_ok || cs->sub.mesh_kind == PROTO_MESH_NONE) return 0;
    const mesh_view *v = &src->mv;
    if (!cs->topo_valid || v->topology_key != cs->topo_key)
        j->topo = srv_client_sim_topology(cs, v, j->t, NULL, NULL);
    return 1;
}

/* Encodes the FRAME (and a MESH_TOPOLOGY when the client has not seen this
 * topology) of job j, with the mesh of job src (j itself, or a job with the
 * same camera, time and cutoff whose mesh is identical).  With shared set
 * the bytes go into a blob that other jobs' frames may refer to
 * (share_stage). */
static void frame_stage(srv_sim *s, job *j, const job *src, int shared)
{
    (void)s;
    srv_client_sim *cs = j->cs;
    proto_msg m;
    proto_msg_init(&m, PROTO_FRAME);
    m.hdr.sim_time = j->t;
    proto_frame *fr = &m.u.frame;
    fr->cutoff_k = j->cutoff_k;
    fr->e_error = j->ev->info.e_error;
    if (!(fr->e_error >= 0)) fr->e_error = 0;
    if (fr->e_error > 1) fr->e_error = 1;
    fr->camera_seq = j->cam_seq;
    fr->tick = j->tick;
    fr->origin[0] = j->cam.pos[0];
    fr->origin[2] = j->cam.pos[2];
    proto_tile pt[MAX_TILES_PER_JOB];
    int nt = 0;
    for (int i = 0; i < j->ntiles; i++)
        if (j->tiles[i] && j->tiles[i]->result == OCEAN_OK) srv_tile_to_proto(j->tiles[i], &pt[nt++]);
    fr->tile_count = (uint16_t)nt;
    fr->tiles = pt;
    j->has_mesh = topo_stage(j, src);
    if (j->has_mesh) {
        const mesh_view *v = &src->mv;
        fr->has_mesh = 1;
        fr->mesh.mesh_id = cs->mesh_id;
        fr->mesh.vertex_count = v->vertex_count;
        memcpy(fr->mesh.origin, v->origin, sizeof v->origin);
        fr->mesh.positions = v->positions;
        if (src->mesh_qz && cs->sub.mesh_codec == PROTO_MESH_CODEC_QZ) {
            fr->has_mesh = 2;
            fr->mesh.qz = src->mesh_qz;
            fr->mesh.qz_len = src->mesh_qz_len;
        }
        memcpy(fr->origin, v->origin, sizeof v->origin);
    }
    j->frame = srv_msg_encode(&m);
    if (!shared || !j->frame || srv_msg_make_shared(j->frame) != OCEAN_OK) return;
    srv_msg *q = j->frame;
    size_t cam_at, mesh_at;
    if (proto_frame_client_fields(proto_buf_data(&q->blob->buf), proto_buf_len(&q->blob->buf), &cam_at,
                                  &mesh_at) != OCEAN_OK || cam_at != SRV_FRAME_CAMERA_SEQ_AT ||
        (j->has_mesh && (mesh_at == 0 || mesh_at > UINT32_MAX))) {
        j->no_share = 1;   /* not laid out as expected: nobody borrows these bytes */
        return;
    }
    q->camera_seq = j->cam_seq;
    if (j->has_mesh) {
        q->mesh_id = cs->mesh_id;
        q->mesh_id_at = (uint32_t)mesh_at;
    }
}

/* Job j's FRAME as a reference to the bytes of job lead's, whose frame is
 * identical but for camera_seq and mesh_id (frames_equal); src is the job
 * whose mesh both carry.  Falls back to encoding its own.  Runs after
 * frame_stage(lead) [worker thread owning j's client]. */
static void share_stage(srv_sim *s, job *j, const job *lead, const job *src)
{
    if (lead->frame && lead->frame->blob && !lead->no_share) {
        j->has_mesh = topo_stage(j, src);
        if (j->has_mesh == lead->has_mesh) {
            j->frame = srv_msg_share(lead->frame);
            if (j->frame) {
                j->frame->camera_seq = j->cam_seq;
                j->frame->mesh_id = j->cs->mesh_id;
                atomic_fetch_add(&s->hub->stats.frames_shared, 1);
                return;
            }
        }
        /* topology bookkeeping is done; encode our own */
        srv_msg_free(j->topo);
        j->topo = NULL;
        j->cs->topo_valid = 0;
    }
    frame_stage(s, j, src, 0);
}

/* Two live jobs whose FRAMEs are byte for byte the same except camera_seq,
 * mesh_id (per client) and the header's seq (stamped when sent): same time,
 * evaluation, cutoff, tick, origin, tile entries, and the same mesh build
 * or none at all. */
static int frames_equal(const job *a, const job *b, int a_mesh, int b_mesh)
{
    if (a->t != b->t || a->ev != b->ev || a->cutoff_k != b->cutoff_k || a->tick != b->tick ||
        a->cam.pos[0] != b->cam.pos[0] || a->cam.pos[2] != b->cam.pos[2] || a->ntiles != b->ntiles ||
        a_mesh != b_mesh || (a_mesh && a->leader != b->leader))
        return 0;
    return a->ntiles == 0 || memcmp(a->tiles, b->tiles, sizeof *a->tiles * (size_t)a->ntiles) == 0;
}

/* Two live jobs whose meshes are bit for bit the same. */
static int same_mesh(const job *a, const job *b)
{
    const srv_client_sim *x = a->cs, *y = b->cs;
    if (!x->mesh || !y->mesh || a->t != b->t || !group_eq(&a->g, &b->g)) return 0;
    const unsigned fx = OCEAN_FX_DISPLACEMENT | OCEAN_FX_NEAR_FIELD;
    if ((x->sub.effects & fx) != (y->sub.effects & fx)) return 0;
    /* the shared mesh is encoded once, for one mesh codec and accuracy */
    if (x->sub.mesh_codec != y->sub.mesh_codec ||
        (x->sub.mesh_codec == PROTO_MESH_CODEC_QZ && x->sub.accuracy != y->sub.accuracy))
        return 0;
    const mesh_config *p = &x->mesh_cfg, *q = &y->mesh_cfg;
    if (p->kind != q->kind || p->range_m != q->range_m || p->error_px != q->error_px ||
        p->lambda_dominant_m != q->lambda_dominant_m || p->roughness != q->roughness)
        return 0;
    const proto_camera *k = &a->cam, *l = &b->cam;
    return k->pos[0] == l->pos[0] && k->pos[1] == l->pos[1] && k->pos[2] == l->pos[2] &&
           k->yaw_deg == l->yaw_deg && k->pitch_deg == l->pitch_deg && k->roll_deg == l->roll_deg &&
           k->fov_y_deg == l->fov_y_deg && k->viewport_w == l->viewport_w &&
           k->viewport_h == l->viewport_h && a->cut.order == b->cut.order;
}

/* ---- batches ----------------------------------------------------------------- */

static int cmp_job(const void *a, const void *b)
{
    const job *x = a, *y = b;
    if (x->c != y->c) return x->c->id < y->c->id ? -1 : 1;
    return 0;
}

/* Batch stage 1: one evaluation per (t, group), with the channels every
 * job sharing it needs (jobs sharing (t, group) reuse the entry; EVAL_MAX
 * bounds a batch). */
static void batch_evaluate(srv_sim *s, job *jobs, int n)
{
    for (int i = 0; i < n; i++) {
        unsigned need = jobs[i].need;
        for (int k = i + 1; k < n; k++)
            if (jobs[k].t == jobs[i].t && group_eq(&jobs[k].g, &jobs[i].g)) need |= jobs[k].need;
        jobs[i].ev = NULL;
        jobs[i].need = need;
    }
    for (int i = 0; i < n; i++) jobs[i].ev = evaluate(s, jobs[i].t, &jobs[i].g, jobs[i].need);
}

/* Job j's world tiles from the cache; those not there yet (fresh) are
 * appended to missing[*nmiss] to be built. */
static void job_tiles(srv_sim *s, job *j, srv_tile **missing, int *nmiss)
{
    srv_stats *st = &s->hub->stats;
    const proto_subscribe *sub = &j->cs->sub;
    int per = s->set.srv.tiles_per_side, levels = sub->lod_levels;
    unsigned ch = srv_tiles_channels(sub->effects);
    j->ntiles = 0;
    j->tiles = NULL;
    if (!j->ev || !ch || levels * per * per > MAX_TILES_PER_JOB) return;
    j->tiles = calloc((size_t)levels * per * per, sizeof(srv_tile *));
    if (!j->tiles) return;
    double base = base_spacing(s, sub);
    for (int L = 0; L < levels; L++) {
        double sp = base * ldexp(1.0, L), w = sp * sub->tile_size;
        int32_t x0 = srv_tiles_first(j->cam.pos[0], w, per), z0 = srv_tiles_first(j->cam.pos[2], w, per);
        for (int a = 0; a < per; a++)
            for (int b = 0; b < per; b++) {
                srv_tile_key k;
                srv_tile_key_init(&k);
                k.t = j->t;
                k.spacing = sp;
                k.bucket = j->g.bucket;
                k.boost = j->g.boost;
                k.accuracy = sub->accuracy;
                k.ix = x0 + b;
                k.iz = z0 + a;
                k.channels = (uint16_t)ch;
                k.size = sub->tile_size;
                k.level = (uint8_t)L;
                k.codec = sub->codec;
                k.layers = (uint8_t)j->g.layers;
                int fresh = 0;
                srv_tile *t = srv_tiles_get(s->tiles, &k, s->gen, &fresh);
                if (!t) continue;
                if (fresh) {
                    missing[(*nmiss)++] = t;
                    t->ready = 0;
                    atomic_fetch_add(&st->tile_cache_misses, 1);
                } else {
                    atomic_fetch_add(&st->tile_cache_hits, 1);
                }
                j->tiles[j->ntiles++] = t;
            }
    }
}

/* Tile t took cpu_s of its thread's CPU: admission's unit cost. */
static void tile_cost(srv_sim *s, const srv_tile *t, double cpu_s)
{
    double samples = (double)t->key.size * t->key.size * proto_tile_planes(t->key.channels);
    srv_admit_tiles(s->hub->admit, t->key.codec, cpu_s, samples);
}

/* Each missing tile samples the evaluation of the first job that asked for
 * it, found by key (t, group); built on the workers.  live: what the tiles
 * took goes to admission's prices. */
static void build_missing(srv_sim *s, srv_tile **missing, int nmiss, int live)
{
    const ocean_frame **src = malloc(sizeof(*src) * (size_t)nmiss);
    if (!src) return;
    for (int m = 0; m < nmiss; m++) {
        src[m] = NULL;
        for (int e = 0; e < EVAL_MAX; e++) {
            eval_entry *ev = &s->ev[e];
            if (ev->used && ev->t == missing[m]->key.t && ev->g.bucket == missing[m]->key.bucket &&
                ev->g.layers == missing[m]->key.layers && ev->g.boost == missing[m]->key.boost) {
                src[m] = ev->f;
                break;
            }
        }
    }
    double *cpu = calloc((size_t)nmiss, sizeof *cpu);
#pragma omp parallel for schedule(dynamic, 1) num_threads(s->set.srv.workers)
    for (int m = 0; m < nmiss; m++) {
        if (src[m]) {
            double c0 = srv_admit_thread_cpu();
            srv_tile_build(missing[m], src[m]);
            if (cpu) cpu[m] = srv_admit_thread_cpu() - c0;
        } else {
            missing[m]->ready = 1;
            missing[m]->result = OCEAN_ESTATE;
        }
    }
    /* what each codec's live tiles cost: admission's prices (srv_admit.h) */
    for (int m = 0; m < nmiss && cpu && live; m++)
        if (src[m] && missing[m]->result == OCEAN_OK) tile_cost(s, missing[m], cpu[m]);
    free(cpu);
    free(src);
    atomic_fetch_add(&s->hub->stats.tiles_encoded, (uint64_t)nmiss);
}

/* Batch stage 2: every job's tiles, the missing ones built; returns how
 * many were built. */
static int batch_tiles(srv_sim *s, job *jobs, int n)
{
    /* a replay's tiles are not priced (srv_admit.h): their cost stays in
     * the shared work admission measures */
    int live = 1;
    for (int i = 0; i < n; i++) live &= !jobs[i].replay;
    srv_tile **missing = malloc(sizeof(srv_tile *) * (size_t)n * MAX_TILES_PER_JOB);
    int nmiss = 0;
    for (int i = 0; i < n && missing; i++) job_tiles(s, &jobs[i], missing, &nmiss);
    if (missing && nmiss) build_missing(s, missing, nmiss, live);
    free(missing);
    return nmiss;
}

/* Live jobs with identical cameras, time and cutoff share one mesh build
 * (co-located viewers): their leaders into leaders[]; replay jobs of one
 * client form a run (runs[]: its first job) kept in order. */
static void group_meshes(job *jobs, int n, int *runs, int *nruns, int *leaders, int *nlead)
{
    for (int i = 0; i < n; i++) {
        jobs[i].leader = i;
        if (!jobs[i].ev) continue;
        if (jobs[i].replay) {
            if (i == 0 || jobs[i].c != jobs[i - 1].c || !jobs[i - 1].replay) runs[(*nruns)++] = i;
            continue;
        }
        for (int k = 0; k < *nlead; k++)
            if (same_mesh(&jobs[leaders[k]], &jobs[i])) {
                jobs[i].leader = leaders[k];
                break;
            }
        if (jobs[i].leader == i) leaders[(*nlead)++] = i;
    }
}

/* Live jobs whose FRAMEs would be identical but for the per-client fields
 * share one encoding: it is built once (frame leaders, fl[]), the others
 * refer to its bytes (fl NULL: no sharing). */
static void group_frames(job *jobs, int n, int *fl)
{
    int nfl = 0;
    for (int i = 0; i < n; i++) {
        job *j = &jobs[i];
        j->fshare = i;
        j->no_share = 0;
        if (!j->ev || j->replay || !fl) continue;
        int jm = jobs[j->leader].mesh_ok && j->cs->sub.mesh_kind != PROTO_MESH_NONE;
        for (int k = 0; k < nfl; k++) {
            const job *o = &jobs[fl[k]];
            int om = jobs[o->leader].mesh_ok && o->cs->sub.mesh_kind != PROTO_MESH_NONE;
            if (frames_equal(o, j, om, jm)) {
                j->fshare = fl[k];
                break;
            }
        }
        if (j->fshare == i) fl[nfl++] = i;
    }
}

/* Batch stage 3: meshes and frames, on the workers. */
static void batch_frames(srv_sim *s, job *jobs, int n)
{
    int workers = s->set.srv.workers;
    qsort(jobs, (size_t)n, sizeof *jobs, cmp_job);
    int *runs = malloc(sizeof(int) * (size_t)(n + 1)), *leaders = malloc(sizeof(int) * (size_t)(n + 1));
    int *fl = malloc(sizeof(int) * (size_t)(n + 1));
    int nruns = 0, nlead = 0;
    if (runs && leaders) {
        group_meshes(jobs, n, runs, &nruns, leaders, &nlead);
#pragma omp parallel for schedule(dynamic, 1) num_threads(workers)
        for (int k = 0; k < nlead; k++) mesh_stage(s, &jobs[leaders[k]]);
        group_frames(jobs, n, fl);
#pragma omp parallel for schedule(dynamic, 1) num_threads(workers)
        for (int i = 0; i < n; i++)
            if (jobs[i].ev && !jobs[i].replay && jobs[i].fshare == i)
                frame_stage(s, &jobs[i], &jobs[jobs[i].leader], fl != NULL);
#pragma omp parallel for schedule(dynamic, 8) num_threads(workers)
        for (int i = 0; i < n; i++)
            if (jobs[i].ev && !jobs[i].replay && jobs[i].fshare != i)
                share_stage(s, &jobs[i], &jobs[jobs[i].fshare], &jobs[jobs[i].leader]);
#pragma omp parallel for schedule(dynamic, 1) num_threads(workers)
        for (int r = 0; r < nruns; r++)
            for (int i = runs[r]; i < n && jobs[i].c == jobs[runs[r]].c && jobs[i].replay; i++) {
                if (!jobs[i].ev) continue;
                mesh_stage(s, &jobs[i]);
                frame_stage(s, &jobs[i], &jobs[i], 0);
            }
    }
    free(fl);
    free(runs);
    free(leaders);
}

/* Layout 0: a batch of jobs evaluated, tiled, meshed, framed and handed
 * over to their clients' queues. */
static void run_batch(srv_sim *s, job *jobs, int n, double tick_wall)
{
    if (n <= 0) return;
    srv_stats *st = &s->hub->stats;
    s->gen++;
    static int prof = -1;
    if (prof < 0) prof = getenv("OCEAND_PROFILE") != NULL;
    double p0 = srv_now();
    batch_evaluate(s, jobs, n);
    double p1 = srv_now();
    int nmiss = batch_tiles(s, jobs, n);
    double p2 = srv_now();
    batch_frames(s, jobs, n);
    double p3 = srv_now();
    if (prof)
        fprintf(stderr, "batch %d jobs: eval %.2f ms, tiles %.2f ms (%d new), frames %.2f ms\n", n,
                (p1 - p0) * 1e3, (p2 - p1) * 1e3, nmiss, (p3 - p2) * 1e3);
    for (int i = 0; i < n; i++) {
        job *j = &jobs[i];
        free(j->tiles);
        j->tiles = NULL;
        free(j->mesh_qz);
        j->mesh_qz = NULL;
        srv_client_hand_over(j->c, st, j->topo, j->frame, j->replay, tick_wall);
        j->topo = j->frame = NULL;
    }
    srv_hub_wake_net(s->hub);
}

/* ---- queries (answered in slices by srv_work.c) ---------------------------------- */

static const ocean_frame *query_eval(void *ctx, double t, int cached_only)
{
    srv_sim *s = ctx;
    group g = {-1, ocean_get_params(s->oc)->cascades, 1.0f};
    if (cached_only) {
        for (int i = 0; i < EVAL_MAX; i++) {
            eval_entry *e = &s->ev[i];
            if (e->used && e->t == t && group_eq(&e->g, &g) &&
                (e->effects & OCEAN_QUERY_EFFECTS) == OCEAN_QUERY_EFFECTS)
                return e->f;
        }
        return NULL;
    }
    eval_entry *e = evaluate(s, t, &g, OCEAN_QUERY_EFFECTS);
    return e ? e->f : NULL;
}

/* ---- sea changes ------------------------------------------------------------ */

/* The hub holds the timeline (srv_hub.h); the simulation thread follows
 * it: the ocean of a tick at sim time t is that of the last change with
 * effective_time <= t.  The earliest pending change's ocean is built ahead
 * by srv_seabuild's thread, and taken when the change falls due. */

/* The change the tick at which the earliest pending one falls due will
 * take: the last one due by then (those before it are never served, and
 * building them would only delay its build). */
static void want_next_sea(srv_sim *s)
{
    srv_hub *h = s->hub;
    pthread_mutex_lock(&h->lock);
    int have = h->n_sea_pending > 0;
    srv_sea_change c;
    if (have) {
        double rate = h->settings.srv.tick_rate;
        double tick = ceil(h->sea_pending[0].effective_time * rate) / rate;
        int k = 0;
        while (k + 1 < h->n_sea_pending && h->sea_pending[k + 1].effective_time <= tick) k++;
        c = h->sea_pending[k];
    }
    pthread_mutex_unlock(&h->lock);
    if (have) srv_seabuild_want(s->build, &s->set, s->set_gen, &c.params, c.effective_time);
}

/* Applies the changes due at tick time t before the tick's frames are made. */
static void follow_sea(srv_sim *s, double t)
{
    srv_hub *h = s->hub;
    srv_sea_change c;
    pthread_mutex_lock(&h->lock);
    int due = srv_hub_sea_take_due(h, t, &c);
    if (due) {
        h->sea_applying = 1; /* until its ocean is in force and counted, below */
        /* meshes follow the new dominant wavelength */
        srv_client_table_reapply(s->table);
    }
    pthread_mutex_unlock(&h->lock);
    if (due) {
        srv_sea_ocean o;
        char msg[256];
        int ahead = 0;
        double took = 0;
        ocean_result r = srv_seabuild_take(s->build, &s->set, s->set_gen, &c.params, c.effective_time, &o, &ahead,
                                           &took, msg, sizeof msg);
        pthread_mutex_lock(&h->lock);
        h->sea_build_s = 0.5 * h->sea_build_s + 0.5 * took; /* the lead of the changes set next */
        pthread_mutex_unlock(&h->lock);
        if (r != OCEAN_OK) {
            /* checked when scheduled (srv_sim_sea_check, or the
             * validation of SEA_STATE set): only memory fails here */
            fprintf(stderr, "oceand: the sea due at t = %.3f s cannot be built (%s); "
                    "clients are told a sea this daemon does not serve\n", c.effective_time, msg);
        } else {
            eval_clear(s);
            srv_tiles_clear(s->tiles);
            srv_cascade_reset(s->casc);
            srv_sea_ocean old = {s->oc, s->g, s->nf};
            srv_seabuild_discard(s->build, &old);
            s->oc = o.oc;
            s->g = o.g;
            s->nf = o.nf;
            adopt_sea(s, &c.params);
            atomic_fetch_add(&h->stats.sea_changes, 1);
            atomic_fetch_add(ahead ? &h->stats.sea_built_ahead : &h->stats.sea_built_due, 1);
        }
        pthread_mutex_lock(&h->lock);
        h->sea_applying = 0;
        pthread_mutex_unlock(&h->lock);
    }
    want_next_sea(s);
}

/* ---- the loop ------------------------------------------------------------------ */

/* Ticks in a row a query turn may be put off for want of slack; then one
 * turn runs whatever the tick left, so a query always progresses. */
#define QUERY_DEFER_MAX 8
/* Seconds with nothing to do before the caches go (release_idle). */
#define IDLE_GRACE_S 1.0
/* What a turn leaves before the next tick is due (a frame's hand-over). */
#define QUERY_MARGIN_S 2e-3

/* Query work for one tick: server.query_ms at most, and no more than the
 * tick left before the next one is due, so the frames of every client go
 * first; a turn whose first query needs an evaluation of its own waits for
 * a tick that leaves one's measured time.  On a host whose other core is
 * busy a tick takes longer and leaves less; a turn put off QUERY_DEFER_MAX
 * ticks runs anyway, at a quarter of its budget. */
static void query_turn(srv_sim *s, double next_tick_wall, int live)
{
    double budget = 1e-3 * s->set.srv.query_ms;
    if (live) {
        double slack = next_tick_wall - srv_now() - QUERY_MARGIN_S, t;
        double need = srv_work_next_time(s->work, &t) && !query_eval(s, t, 1) ? s->eval_s : 0;
        if ((slack <= 0 || slack < need) && s->query_deferred < QUERY_DEFER_MAX) {
            s->query_deferred++;
            return;
        }
        budget = slack > need ? fmin(budget, slack - need) : 0.25 * budget;
    }
    s->query_deferred = 0;
    srv_work_queries(s->work, s->hub, query_eval, s, s->g, ocean_get_params(s->oc)->sea.depth_m, budget);
}

static void ts_from(double secs, struct timespec *ts)
{
    ts->tv_sec = (time_t)floor(secs);
    ts->tv_nsec = (long)((secs - floor(secs)) * 1e9);
    if (ts->tv_nsec >= 1000000000L) { ts->tv_sec++; ts->tv_nsec -= 1000000000L; }
}

typedef struct work {
    srv_client **cl;     /* referenced clients */
    int ncl, capcl;
    job *jobs;
    int njobs, capjobs;
    srv_cascade_job *cjobs;   /* layout 1 */
    int ncjobs, capcjobs;
} work;

static int grow(void **p, int *cap, int need, size_t el)
{
    if (need <= *cap) return 1;
    int nc = *cap ? *cap * 2 : 64;
    while (nc < need) nc *= 2;
    void *np = realloc(*p, (size_t)nc * el);
    if (!np) return 0;
    *p = np;
    *cap = nc;
    return 1;
}

/* What the tile caches hold, for /metrics and /status. */
static void publish_cache_size(srv_sim *s)
{
    size_t n, b;
    srv_cascade_cache_size(s->casc, &n, &b);
    srv_stats *st = &s->hub->stats;
    atomic_store(&st->tile_cache_entries, (uint64_t)(n + srv_tiles_count(s->tiles)));
    atomic_store(&st->tile_cache_bytes, (uint64_t)(b + srv_tiles_bytes(s->tiles)));
}

/* The last subscriber left and no query or replay work has come for
 * IDLE_GRACE_S: the caches hold the last ticks' tiles and evaluations, which
 * no later tick can use (their keys hold their sim time), until the next
 * tick sweeps them, however long that takes. Drop them now and hand the
 * freed memory back to the system (the daemon otherwise keeps up to
 * M_TRIM_THRESHOLD free, main.c): after 256 layout-0 viewers 2 km apart
 * left, 660 MB stayed resident, 320 MB of it in these caches; now 21 MB. The
 * mip tables and frames the next tick reuses stay. */
static void release_idle(srv_sim *s)
{
    srv_tiles_sweep(s->tiles, UINT64_MAX);
    srv_cascade_sweep(s->casc, UINT64_MAX);
    eval_clear(s);
    malloc_trim(0);
    s->holding = 0;
    publish_cache_size(s);
}

/* Waits (hub.lock held, and still held on return) until a tick is due:
 * a live frame (*live_due), background work, a settings or sea change, or
 * a sea change's effective time; *idle when nobody is subscribed and no
 * work is queued (the caches can go).  0 when the thread is to stop. */
static int wait_for_work(srv_sim *s, double next_tick_wall, int *live_due, int *idle)
{
    srv_hub *h = s->hub;
    double rate_w = s->set.srv.tick_rate;
    *live_due = *idle = 0;
    while (!s->stop) {
        double now = srv_now();
        double simt = srv_hub_sim_time(h);
        int pending = h->sea_gen != s->sea_gen || h->settings_gen != s->set_gen;
        /* queries and replay frames run in bounded slices, at most one
         * turn per tick period (srv_work.c, server.replay_per_tick); but a
         * query that comes when none is being answered is taken at once:
         * a simulator's host asks once a frame and needs the answer within
         * it (its turn still leaves the next tick its time: query_turn) */
        int busy = srv_work_busy(s->work), bg = busy, fresh = 0;
        for (srv_client *c = h->clients; c; c = c->next) {
            if (c->closed) continue;
            int q = srv_inbox_queries(c->in) > 0;
            fresh |= q && !busy;
            bg |= q || srv_inbox_replays(c->in);
        }
        if ((bg && now >= s->work_due) || fresh) pending = 1;
        if (h->n_subscribed > 0 && now >= next_tick_wall) *live_due = 1;
        /* a change is due at the first tick at or after its effective time */
        double due_t = h->n_sea_pending ? ceil(h->sea_pending[0].effective_time * rate_w) / rate_w : INFINITY;
        if (*live_due || pending || simt >= due_t) return 1;
        /* the caches go after IDLE_GRACE_S with nothing to do: a
         * simulator's host that asks once a frame finds its tick's
         * evaluation still there, not freed and trimmed between frames */
        int quiet = h->n_subscribed == 0 && !bg && s->holding;
        if (quiet && now >= s->turn_wall + IDLE_GRACE_S) {
            *idle = 1;
            return 1;
        }
        struct timespec ts;
        double until = h->n_subscribed > 0 ? next_tick_wall : now + 1.0;
        if (quiet && s->turn_wall + IDLE_GRACE_S < until) until = s->turn_wall + IDLE_GRACE_S;
        if (bg && s->work_due < until) until = s->work_due;
        if (now + (due_t - simt) < until) until = now + (due_t - simt);
        if (h->n_subscribed == 0) atomic_fetch_add(&h->stats.idle_ticks, 1);
        ts_from(until, &ts);
        pthread_cond_timedwait(&h->wake, &h->lock, &ts);
    }
    return 0;
}

/* One more job in w for client c (NULL when memory ran out). */
static job *add_job(work *w, srv_client *c, srv_client_sim *cs)
{
    if (!grow((void **)&w->jobs, &w->capjobs, w->njobs + 1, sizeof *w->jobs)) return NULL;
    job *j = &w->jobs[w->njobs++];
    memset(j, 0, sizeof *j);
    j->c = c;
    j->cs = cs;
    return j;
}

/* Under hub.lock: every subscribed client's requests of tick t, copied
 * into w (its subscription when changed, its camera, its replay
 * cameras). */
static void snapshot_jobs(srv_sim *s, work *w, double t, int64_t tick_no, int live_due)
{
    w->ncl = w->njobs = 0;
    srv_client_table_sweep(s->table);
    for (srv_client *c = s->hub->clients; c; c = c->next) {
        if (c->closed) continue;
        srv_work_take(s->work, c, t);
        if (!c->subscribed) continue;
        srv_client_sim *cs = srv_client_table_get(s->table, c);
        if (!cs || !grow((void **)&w->cl, &w->capcl, w->ncl + 1, sizeof *w->cl)) break;
        srv_client_ref(c);
        w->cl[w->ncl++] = c;
        /* A changed subscription is taken with the job that applies it
         * (filter_jobs).  A turn without a live tick (a query's, between
         * ticks) leaves it for the next tick: taken without a job it would
         * never be applied, and the client would get frames without the
         * mesh it asked for, and no ERROR, for as long as it stayed. */
        int changed = cs->sub_gen != c->sub_gen;
        job *j = NULL;
        if (c->sub.mode == PROTO_MODE_REPLAY) {
            /* its frames come in the replay turn (replay_turn); a changed
             * subscription rebuilds the mesh now */
            if (changed && (j = add_job(w, c, cs))) j->replay = -1;
        } else if (live_due) {
            if (!(j = add_job(w, c, cs))) break;
            j->t = t;
            j->tick = (uint32_t)tick_no;
            j->tick_no = tick_no;
            if (c->has_camera) {
                j->cam = c->cam;
                j->cam_seq = c->cam_seq;
            } else {
                j->cam_seq = PROTO_NO_CAMERA;
                j->replay = -2; /* camera filled below */
            }
        }
        if (j && changed) {
            cs->sub = c->sub;
            cs->sub_gen = c->sub_gen;
            j->sub_changed = 1;
        }
    }
}

/* The wake patterns the client c (either layout), its camera at cam, needs
 * at sim time t and does not hold, queued as WAKE messages: those of the
 * ships whose wakes reach its view range. Only built ones: the others go to
 * the builder, and the wake shows once built (a frame never waits for one).
 * cs models what the client holds: the last PROTO_WAKE_HELD sent. */
static void wakes_send(srv_sim *s, srv_client *c, srv_client_sim *cs, double t, const proto_camera *cam)
{
    srv_hub *h = s->hub;
    int max = srv_entities_kept(h->entities);
    if (max == 0) return;
    ocean_entity_desc *d = malloc(sizeof *d * (size_t)max);
    ocean_entity_state *st = malloc(sizeof *st * (size_t)max);
    wake_params need[PROTO_WAKE_HELD];
    int n = d && st ? srv_entities_at(h->entities, t, d, st, max) : 0;
    double range = cs->sub.view_range_m > 0 ? cs->sub.view_range_m : s->set.srv.view_range;
    int k = wake_field_rungs(d, st, n, ocean_get_params(s->oc)->sea.depth_m, cam->pos[0], cam->pos[2], range, need,
                             PROTO_WAKE_HELD);
    free(d);
    free(st);
    for (int i = 0; i < k && i < PROTO_WAKE_HELD; i++) {
        int held = 0;
        for (int j = 0; j < cs->n_wakes && !held; j++) held = wake_params_equal(&cs->wakes[j], &need[i]);
        if (held) continue;
        srv_msg *q = srv_wakes_message(h->wakes, &need[i]);
        if (!q) continue;
        srv_client_queue(c, q);
        if (cs->n_wakes == PROTO_WAKE_HELD)
            memmove(&cs->wakes[0], &cs->wakes[1], sizeof cs->wakes[0] * (size_t)--cs->n_wakes);
        cs->wakes[cs->n_wakes++] = need[i];
    }
}

/* Applies changed subscriptions, keeps the live jobs whose frame is due
 * (the client's frame rate on the nearest tick), sends layout-1 jobs to
 * the shared cascade products (w->cjobs) and chooses the layout-0 jobs'
 * cutoffs; returns how many layout-0 jobs are left at the front of
 * w->jobs. */
static int filter_jobs(srv_sim *s, work *w, double t, double rate)
{
    int n = 0;
    w->ncjobs = 0;
    for (int i = 0; i < w->njobs; i++) {
        job j = w->jobs[i];
        srv_client_sim *cs = j.cs;
        if (j.sub_changed || cs->sub_gen == 0) apply_subscription(s, j.c, cs);
        if (j.replay == -1) continue;
        if (j.replay != 1) {
            double period = 1.0 / cs->sub.frame_rate_hz;
            if (t + 0.5 / rate < cs->next_frame_t) continue;
            cs->next_frame_t = fmax(cs->next_frame_t + period, t + period - 0.5 / rate);
            cs->last_frame_t = t;
            cs->framed = 1;
            if (j.replay == -2) default_camera(s, &j.cam);
            j.replay = 0;
        } else {
            j.tick = (uint32_t)(int64_t)llround(j.t * rate);
        }
        wakes_send(s, j.c, cs, j.t, &j.cam);
        if (cs->sub.layout == PROTO_LAYOUT_CASCADE) {
            if (!grow((void **)&w->cjobs, &w->capcjobs, w->ncjobs + 1, sizeof *w->cjobs)) continue;
            srv_cascade_job *q = &w->cjobs[w->ncjobs++];
            memset(q, 0, sizeof *q);
            q->c = j.c;
            q->cs = cs;
            q->t = j.t;
            q->cam = j.cam;
            q->cam_seq = j.cam_seq;
            q->tick = j.tick;
            q->tick_pos = j.replay == 1 ? j.t * rate : (double)j.tick_no;
            q->replay = j.replay == 1;
            q->policy_k = layout1_policy(s, &cs->sub, &j.cam);
            continue;
        }
        choose_cutoff(s, &j);
        w->jobs[n++] = j;
    }
    return n;
}

/* Layout-0 jobs in batches of at most EVAL_MAX / 2 distinct evaluations. */
static void run_batches(srv_sim *s, job *jobs, int n, double tick_wall)
{
    int start = 0;
    while (start < n) {
        int end = start, distinct = 0;
        while (end < n) {
            int seen = 0;
            for (int k = start; k < end && !seen; k++)
                seen = jobs[k].t == jobs[end].t && group_eq(&jobs[k].g, &jobs[end].g);
            if (!seen && distinct >= EVAL_MAX / 2) break;
            distinct += !seen;
            end++;
        }
        run_batch(s, jobs + start, end - start, tick_wall);
        start = end;
    }
}

/* After a live tick: the caches swept of the generations before, the
 * next tick's wall time, the tick's cost counted. */
static void end_live_tick(srv_sim *s, double t0, int64_t tick_no, double rate, double sim0, double *next_tick_wall)
{
    srv_hub *h = s->hub;
    srv_tiles_sweep(s->tiles, s->gen > 1 ? s->gen - 1 : 0);
    srv_cascade_sweep(s->casc, s->gen > 1 ? s->gen - 1 : 0);
    publish_cache_size(s);
    *next_tick_wall = t0 + ((double)(tick_no + 1) / rate - sim0);
    double dt = srv_now() - t0;
    atomic_fetch_add(&h->stats.ticks, 1);
    atomic_fetch_add(&h->stats.tick_ns_total, (uint64_t)(dt * 1e9));
    atomic_store(&h->stats.tick_ns_last, (uint64_t)(dt * 1e9));
}

#define REPLAY_HEADROOM 0.25  /* of a tick period, left to the live work's jitter */
#define REPLAY_FLOOR 0.0625   /* of a tick period: replays' room however busy the live work */

static void replay_cost(srv_sim *s, int layout1, double seconds, int frames)
{
    if (frames <= 0) return;
    double *c = &s->replay_s[layout1], per = seconds / frames;
    *c = *c > 0 ? 0.7 * *c + 0.3 * per : per;
}

/* Client c's replay frames into w: quantum seconds more in its deficit,
 * then frames while their measured cost fits both it and the tick's room
 * left (*room, which they spend; the tick's first frame needs only the
 * deficit), at most server.replay_per_tick.  A layout whose cost is not
 * measured yet costs all the room: one frame, measured.  What is left of
 * the deficit stays banked, up to a frame's cost and a quantum; nothing
 * once the queue is empty [hub.lock held].  Returns how many. */
static int take_replay(srv_sim *s, work *w, srv_client *c, double quantum, double *room)
{
    srv_client_sim *cs = srv_client_table_get(s->table, c);
    if (!cs) return 0;
    double cost = s->replay_s[c->sub.layout == PROTO_LAYOUT_CASCADE];
    if (cost <= 0) cost = fmax(*room, 1e-9);
    cs->replay_deficit = fmin(cs->replay_deficit + quantum, cost + quantum);
    int taken = 0;
    while (taken < s->set.srv.replay_per_tick && srv_inbox_replays(c->in) && w->njobs < 4096 &&
           cs->replay_deficit >= cost && (cost <= *room || w->njobs == 0)) {
        job *j = add_job(w, c, cs);
        if (!j) break;
        srv_replay_cam *rc = srv_inbox_take_replay(c->in);
        j->t = rc->cam.render_time;
        j->cam = rc->cam;
        j->cam_seq = rc->seq;
        j->replay = 1;
        free(rc);
        cs->replay_deficit -= cost;
        *room -= cost;
        taken++;
    }
    if (!srv_inbox_replays(c->in)) cs->replay_deficit = 0;
    return taken;
}

/* Client c has replay cameras waiting [hub.lock held]. */
static int replay_waiting(const srv_client *c)
{
    return !c->closed && c->sub.mode == PROTO_MODE_REPLAY && srv_inbox_replays(c->in);
}

/* Replay frames take what the live work leaves of the tick (the time
 * before the next one less REPLAY_HEADROOM of a period, and REPLAY_FLOOR
 * of a period at least), shared by the replaying clients by deficit round
 * robin (M. Shreedhar and G. Varghese, "Efficient fair queuing using
 * deficit round robin", SIGCOMM 1995): each gets an equal quantum of it a
 * tick and spends it on frames at its layout's measured cost, banking the
 * rest, so a client whose frames cost more than a tick leaves still gets
 * one every few ticks and the cheap ones are not held behind it; clients
 * whose banks fill in the same tick take turns, the tick's room being
 * spent.  (Eight replay clients at two frames a tick each asked for more
 * than the daemon makes in a tick, and every live viewer lost frames.) */
static void replay_turn(srv_sim *s, work *w, double tick_wall, double rate)
{
    srv_hub *h = s->hub;
    w->njobs = 0;
    double room = fmax(tick_wall + (1.0 - REPLAY_HEADROOM) / rate - srv_now(), REPLAY_FLOOR / rate);
    double quantum = 0;
    int taken = 0, start = 0, active = 0, first = 1;
    pthread_mutex_lock(&h->lock);
    for (int i = 0; i < w->ncl; i++) {
        srv_client *c = w->cl[i];
        if (c->id == s->replay_last) start = i + 1;
        active += replay_waiting(c);
    }
    if (active) quantum = room / active;
    for (int k = 0; k < w->ncl && active; k++) {
        srv_client *c = w->cl[(start + k) % w->ncl];
        if (!replay_waiting(c)) continue;
        if (first) s->replay_last = c->id; /* the next tick starts after it */
        first = 0;
        taken += take_replay(s, w, c, quantum, &room);
    }
    pthread_mutex_unlock(&h->lock);
    if (!taken) return;
    int n = filter_jobs(s, w, 0, rate);
    double r0 = srv_now();
    run_cascade(s, w->cjobs, w->ncjobs, tick_wall);
    double r1 = srv_now();
    run_batches(s, w->jobs, n, tick_wall);
    replay_cost(s, 1, r1 - r0, w->ncjobs);
    replay_cost(s, 0, srv_now() - r1, n);
}

static void *sim_main(void *arg)
{
    srv_sim *s = arg;
    srv_hub *h = s->hub;
    work w = {0};
    double next_tick_wall = 0;
    for (;;) {
        int live_due, idle;
        pthread_mutex_lock(&h->lock);
        if (!wait_for_work(s, next_tick_wall, &live_due, &idle)) {
            pthread_mutex_unlock(&h->lock);
            break;
        }
        if (idle) {
            pthread_mutex_unlock(&h->lock);
            release_idle(s);
            continue;
        }
        s->holding = 1;
        double t0 = srv_now();
        s->turn_wall = t0;
        if (h->settings_gen != s->set_gen) {
            ocean_params keep = s->set.params;
            s->set = h->settings;
            s->set.params = keep;
            s->set_gen = h->settings_gen;
        }
        double rate = s->set.srv.tick_rate;
        s->sea_gen = h->sea_gen;
        double sim0 = srv_hub_sim_time(h);
        /* tick k shows sim time k / rate; ticks before the epoch are negative */
        int64_t tick_no = (int64_t)floor(sim0 * rate);
        double t = (double)tick_no / rate;
        double tick_wall = t0 - (sim0 - t);      /* monotonic time of the tick */
        snapshot_jobs(s, &w, t, tick_no, live_due);
        int viewers = h->n_subscribed > 0;
        pthread_mutex_unlock(&h->lock);
        /* the sea of tick t (a reload's changed sea entered the timeline) */
        follow_sea(s, t);
        int n = filter_jobs(s, &w, t, rate);
        run_cascade(s, w.cjobs, w.ncjobs, tick_wall);
        run_batches(s, w.jobs, n, tick_wall);
        replay_turn(s, &w, tick_wall, rate);
        /* a turn between ticks leaves the next one its time as a tick's
         * turn does */
        if (srv_work_busy(s->work)) query_turn(s, tick_wall + 1.0 / rate, live_due || viewers);
        s->work_due = t0 + 1.0 / rate;
        for (int i = 0; i < w.ncl; i++) srv_client_unref(w.cl[i]);
        if (live_due) end_live_tick(s, t0, tick_no, rate, sim0, &next_tick_wall);
        publish_counters(s);
    }
    free(w.cl);
    free(w.jobs);
    free(w.cjobs);
    return NULL;
}

ocean_result srv_sim_start(srv_sim *s)
{
    if (s->running) return OCEAN_ESTATE;
    s->stop = 0;
    if (pthread_create(&s->thread, NULL, sim_main, s) != 0) return OCEAN_ENOMEM;
    s->running = 1;
    return OCEAN_OK;
}

void srv_sim_stop(srv_sim *s)
{
    if (!s || !s->running) return;
    pthread_mutex_lock(&s->hub->lock);
    s->stop = 1;
    pthread_cond_broadcast(&s->hub->wake);
    pthread_mutex_unlock(&s->hub->lock);
    pthread_join(s->thread, NULL);
    s->running = 0;
}
