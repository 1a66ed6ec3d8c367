/*
 * srv_client_sim.c - what the simulation thread keeps of each client, and
 * its table (see srv_client_sim.h).  Simulation thread only.
 */
#include "srv_client_sim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Entries sorted by client id (ids are handed out in increasing order, so
 * a new client's entry almost always goes at the end). */
typedef struct entry {
    srv_client *c;          /* one reference */
    srv_client_sim *cs;
} entry;

struct srv_client_table {
    entry *e;
    size_t n, cap;
};

ocean_result srv_client_table_create(srv_client_table **out)
{
    *out = calloc(1, sizeof **out);
    return *out ? OCEAN_OK : OCEAN_ENOMEM;
}

static void sim_free(srv_client_sim *cs)
{
    if (!cs) return;
    mesh_destroy(cs->mesh);
    free(cs->qz_refs);
    for (int i = 0; i < 4; i++) srv_held_destroy(cs->held[i]);
    free(cs);
}

void srv_client_table_destroy(srv_client_table *t)
{
    if (!t) return;
    for (size_t i = 0; i < t->n; i++) {
        sim_free(t->e[i].cs);
        srv_client_unref(t->e[i].c);
    }
    free(t->e);
    free(t);
}

/* The index of id's entry, or where it would go. */
static size_t find(const srv_client_table *t, uint32_t id)
{
    size_t lo = 0, hi = t->n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (t->e[mid].c->id < id) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

srv_client_sim *srv_client_table_get(srv_client_table *t, srv_client *c)
{
    size_t i = find(t, c->id);
    if (i < t->n && t->e[i].c == c) return t->e[i].cs;
    if (t->n == t->cap) {
        size_t nc = t->cap ? 2 * t->cap : 64;
        entry *ne = realloc(t->e, nc * sizeof *ne);
        if (!ne) return NULL;
        t->e = ne;
        t->cap = nc;
    }
    srv_client_sim *cs = calloc(1, sizeof *cs);
    if (!cs) return NULL;
    ocean_filter_smoother_init(&cs->smoother);
    memmove(&t->e[i + 1], &t->e[i], (t->n - i) * sizeof *t->e);
    srv_client_ref(c);
    t->e[i] = (entry){.c = c, .cs = cs};
    t->n++;
    return cs;
}

void srv_client_table_sweep(srv_client_table *t)
{
    size_t k = 0;
    for (size_t i = 0; i < t->n; i++) {
        if (t->e[i].c->closed) {
            sim_free(t->e[i].cs);
            srv_client_unref(t->e[i].c);
        } else {
            t->e[k++] = t->e[i];
        }
    }
    t->n = k;
}

void srv_client_table_reapply(srv_client_table *t)
{
    for (size_t i = 0; i < t->n; i++) t->e[i].cs->sub_gen = 0;
}

srv_msg *srv_client_sim_topology(srv_client_sim *cs, const mesh_view *v, double t, const float *flat,
                                 const float *zones)
{
    cs->mesh_id++;
    cs->topo_key = v->topology_key;
    cs->topo_valid = 1;
    proto_msg tm;
    proto_msg_init(&tm, PROTO_MESH_TOPOLOGY);
    tm.hdr.sim_time = t;
    tm.u.topology.mesh_id = cs->mesh_id;
    tm.u.topology.mesh_kind = (uint8_t)v->kind;
    tm.u.topology.lod_levels = (uint8_t)(v->levels < 1 ? 1 : v->levels);
    tm.u.topology.vertex_count = v->vertex_count;
    tm.u.topology.index_count = v->index_count;
    tm.u.topology.indices = v->indices;
    tm.u.topology.morph = v->morph;
    tm.u.topology.level = v->level;
    if (flat) {
        tm.u.topology.flags = PROTO_TOPO_FLAT;
        tm.u.topology.flat = flat;
        tm.u.topology.zones = zones;
    }
    srv_msg *q = srv_msg_encode(&tm);
    if (!q) cs->topo_valid = 0;
    return q;
}

/* The largest error budget a mesh takes (mesh_config_validate). */
#define MESH_ERROR_PX_MAX 100.0

int srv_client_sim_mesh_fit(srv_client_sim *cs, srv_client *c, const mesh_camera *mc, int max_vertices,
                            uint32_t cam_seq, srv_stats *st)
{
    if (!cs->mesh) /* none subscribed, or it failed: not remade before the next SUBSCRIBE */
        return 0;
    const mesh_config *sub = &cs->mesh_cfg;
    mesh_config cfg = *sub;
    double est = 0, est0 = 0, tried = 0;
    int k = 0;
    for (;; k++) {
        /* doubled, the last step to the largest budget itself (a 2 deg
         * view fits at 100 px, not at 64) */
        cfg.error_px = fmin(sub->error_px * (double)(1 << k), fmax(sub->error_px, MESH_ERROR_PX_MAX));
        if (cfg.error_px <= tried || mesh_estimate_vertices(&cfg, mc, &est) != OCEAN_OK) {
            k = -1;
            break;
        }
        tried = cfg.error_px;
        if (k == 0)
            est0 = est;
        /* a coarser mesh comes back only with room to spare, so a camera
         * hovering at the limit does not flip topologies every frame */
        if (est <= max_vertices && (k >= cs->mesh_coarsen || est <= 0.8 * max_vertices))
            break;
    }
    if (k < 0) {
        if (!cs->mesh_over) {
            char why[320];
            snprintf(why, sizeof why, "camera %u: its %s mesh is estimated at %.4g vertices, above the "
                     "server's limit of %d (server.max_mesh_vertices), even at %g px; frames come "
                     "without a mesh until a camera asks for less (wider fov, smaller viewport or range)",
                     cam_seq, mesh_kind_name(sub->kind), est0, max_vertices,
                     sub->kind == MESH_CONCENTRIC ? MESH_ERROR_PX_MAX : sub->error_px);
            atomic_fetch_add(&st->refused_mesh, 1);
            srv_client_send_error(c, NULL, 0, OCEAN_ETOOBIG, why);
            cs->mesh_over = 1;
        }
        return 0;
    }
    cs->mesh_over = 0;
    if (k == cs->mesh_coarsen)
        return 1;
    mesh *m = NULL;
    ocean_result r = mesh_create(&cfg, &m);
    if (r != OCEAN_OK) {
        char why[200];
        snprintf(why, sizeof why, "mesh %s unavailable, frames come without a mesh: %s",
                 mesh_kind_name(cfg.kind), ocean_strerror(r));
        srv_client_send_error(c, NULL, 0, r, why);
        return 0;
    }
    mesh_destroy(cs->mesh);
    cs->mesh = m;
    cs->topo_valid = 0;
    /* A layout-1 client learns the lattice it got from MESH_TOPOLOGY's
     * zones and displaces it itself: a coarser mesh there is the same kind
     * of adaptation as the byte budget raising q (a narrow field of view, a
     * zoom), not an error to show; a layout-0 client gets positions it did
     * not ask for, and is told. */
    if (k > 0 && cs->sub.layout != PROTO_LAYOUT_CASCADE) {
        char why[320];
        snprintf(why, sizeof why, "camera %u: its %s mesh at %g px (server.mesh_error_px) would be %.4g "
                 "vertices, above the server's limit of %d (server.max_mesh_vertices); it is drawn at "
                 "%g px (%.4g vertices) while the camera needs it", cam_seq, mesh_kind_name(cfg.kind),
                 sub->error_px, est0, max_vertices, cfg.error_px, est);
        srv_client_send_error(c, NULL, 0, OCEAN_ETOOBIG, why);
    }
    if (k > 0) atomic_fetch_add(&st->coarsened_mesh, 1);
    cs->mesh_coarsen = k;
    return 1;
}

