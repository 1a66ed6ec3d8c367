/*
 * srv_work.c - query work in bounded slices (see srv_work.h).
 */
#include "srv_work.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "query.h"
#include "srv_wakes.h"

typedef struct item {
    struct item *next;
    srv_client *c;              /* one reference held */
    srv_query *q;
    double t;                   /* time the query is answered at */
    ocean_query_result *res;    /* q->count, filled slice by slice */
    uint32_t done;
} item;

struct srv_work {
    item *head, *tail;          /* the rotation: one query per client */
    double sec_per_point;       /* measured cost of a point (EWMA) */
};

ocean_result srv_work_create(srv_work **out)
{
    srv_work *w = calloc(1, sizeof *w);
    if (!w) return OCEAN_ENOMEM;
    w->sec_per_point = 20e-6; /* until measured: 65 532 points take 1.2-1.9 s */
    *out = w;
    return OCEAN_OK;
}

/* Ends an item: the client's active count drops (under hub.lock). */
static void finish(srv_hub *h, item *it)
{
    pthread_mutex_lock(&h->lock);
    if (it->c->n_queries_active > 0) it->c->n_queries_active--;
    pthread_mutex_unlock(&h->lock);
    srv_client_unref(it->c);
    free(it->q->points);
    free(it->q);
    free(it->res);
    free(it);
}

void srv_work_destroy(srv_work *w)
{
    if (!w) return;
    while (w->head) {
        item *it = w->head;
        w->head = it->next;
        srv_client_unref(it->c);
        free(it->q->points);
        free(it->q);
        free(it->res);
        free(it);
    }
    free(w);
}

int srv_work_busy(const srv_work *w) { return w->head != NULL; }

int srv_work_next_time(const srv_work *w, double *t)
{
    if (!w->head) return 0;
    *t = w->head->t;
    return 1;
}

void srv_work_take(srv_work *w, srv_client *c, double t_now)
{
    if (!srv_inbox_queries(c->in) || c->n_queries_active > 0) return;
    item *it = calloc(1, sizeof *it);
    if (!it) return; /* stays pending; taken on a later tick */
    srv_query *q = srv_inbox_take_query(c->in);
    c->n_queries_active++;
    srv_client_ref(c);
    it->c = c;
    it->q = q;
    it->t = q->at_time ? q->t : t_now;
    if (w->tail) w->tail->next = it;
    else w->head = it;
    w->tail = it;
}

static void answer(srv_hub *h, item *it)
{
    srv_query *q = it->q;
    proto_query_sample *smp = calloc(q->count ? q->count : 1, sizeof *smp);
    if (!smp) {
        srv_client_send_error(it->c, NULL, 0, OCEAN_ENOMEM, "query could not be answered: out of memory");
        return;
    }
    for (uint32_t i = 0; i < q->count; i++) {
        const ocean_query_result *a = &it->res[i];
        proto_query_sample *o = &smp[i];
        o->height = (float)a->height;
        for (int k = 0; k < 3; k++) {
            o->normal[k] = (float)a->normal[k];
            o->velocity[k] = (float)a->velocity[k];
        }
        o->foam = (float)(a->foam < 0 ? 0 : a->foam > 1 ? 1 : a->foam);
        /* no bound (a fold, or a point the iteration did not reach) is
         * sent as the largest float, never as 0, which would claim an
         * exact answer */
        o->error_bound = a->error >= 0 && a->error < FLT_MAX ? (float)a->error : FLT_MAX;
    }
    proto_msg m;
    proto_msg_init(&m, PROTO_QUERY_RESULT);
    /* the header is the server's clock when sending (PROTOCOL.md "Header"),
     * which clients fold into their clock and latency estimates; the time
     * the answer describes is the body's t */
    m.hdr.sim_time = srv_hub_sim_time(h);
    m.u.result.query_id = q->query_id;
    m.u.result.count = q->count;
    m.u.result.t = it->t;
    m.u.result.samples = smp;
    srv_msg *out = srv_msg_new();
    char err[256];
    if (out && proto_encode(&out->buf, &m, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "oceand: cannot encode QUERY_RESULT: %s\n", err);
        srv_msg_free(out);
        out = NULL;
    }
    if (out) srv_client_queue(it->c, out);
    atomic_fetch_add(&h->stats.queries, 1);
    atomic_fetch_add(&h->stats.query_points, q->count);
    free(smp);
}

/* Puts it first in the rotation again: its turn is over until the next
 * tick. */
static void put_back(srv_work *w, item *it)
{
    it->next = w->head;
    w->head = it;
    if (!w->tail) w->tail = it;
}

void srv_work_queries(srv_work *w, srv_hub *h, srv_work_eval_fn eval, void *ctx,
                      const ocean_gerstner *g, double depth, double budget_s)
{
    double t0 = srv_now(), now = t0;
    int slices = 0;
    while (w->head && (slices == 0 || now - t0 < budget_s)) {
        item *it = w->head;
        w->head = it->next;
        if (!w->head) w->tail = NULL;
        it->next = NULL;
        if (it->c->closed) {
            finish(h, it);
            continue;
        }
        double s0 = now;
        srv_query *q = it->q;
        ocean_result r = OCEAN_OK;
        size_t bad = 0;
        /* A query at a time no evaluation holds costs an ocean evaluation
         * first: at most one such per turn, and only as a turn's first
         * slice, so a turn stays near its budget. */
        if (slices > 0 && !eval(ctx, it->t, 1)) {
            put_back(w, it);  /* first in the next turn (at the back it could wait forever) */
            break;
        }
        if (!it->res) it->res = calloc(q->count ? q->count : 1, sizeof *it->res);
        int evaluated = slices == 0 && it->res && !eval(ctx, it->t, 1);
        const ocean_frame *f = it->res ? eval(ctx, it->t, 0) : NULL;
        if (!f) r = OCEAN_ENOMEM;
        /* the turn's one evaluation is priced by the caller (budget_s is
         * what is left for points): answering its query's points after it
         * costs little, where a budget that counted it answered a
         * 128-point query a tick later */
        if (evaluated) t0 = srv_now();
        /* slices of a quarter of the budget at the measured cost, so a
         * misjudged cost per point overruns by a quarter budget, not four */
        now = srv_now();
        double left = budget_s - (now - t0);
        double want = fmin(left, 0.25 * budget_s) / w->sec_per_point;
        uint32_t k = want < 16 ? 16 : want > 8192 ? 8192 : (uint32_t)want;
        if (k > q->count - it->done) k = q->count - it->done;
        double p0 = srv_now();
        const double *pts = q->points + 2 * (size_t)it->done;
        wake_sample *ws = r == OCEAN_OK && k > 0 ? malloc(sizeof *ws * k) : NULL;
        ocean_result wr = ws ? srv_wakes_sample(h->wakes, h->entities, it->t, depth, pts, k, ws) : OCEAN_ENOMEM;
        if (wr == OCEAN_ESTATE) {
            /* a wake pattern its points need is being built: no answer
             * without it (srv_wakes.h) */
            free(ws);
            put_back(w, it);
            break;
        }
        if (r == OCEAN_OK && k > 0 && wr == OCEAN_ENOMEM) r = OCEAN_ENOMEM;
        ocean_query_options opt;
        ocean_query_options_default(&opt);
        if (r == OCEAN_OK && k > 0)
            r = ocean_query_points(f, g, NULL, it->t, pts, k, &opt, it->res + it->done, &bad);
        if (r == OCEAN_OK && wr == OCEAN_OK) wake_sample_apply(ws, k, it->res + it->done);
        free(ws);
        now = srv_now();
        if (r == OCEAN_OK && k >= 16)
            w->sec_per_point = 0.7 * w->sec_per_point + 0.3 * (now - p0) / k;
        atomic_fetch_add(&it->c->cpu_ns, (uint64_t)((now - s0) * 1e9));
        atomic_fetch_add(&h->stats.query_slices, 1);
        slices++;
        if (r != OCEAN_OK) {
            char why[200];
            if (r == OCEAN_ENOMEM)
                snprintf(why, sizeof why, "query %u could not be answered: out of memory", q->query_id);
            else
                snprintf(why, sizeof why, "query %u: point %zu refused (%s)", q->query_id,
                         (size_t)it->done + bad, ocean_strerror(r));
            srv_client_send_error(it->c, NULL, 0, r, why);
            finish(h, it);
            continue;
        }
        it->done += k;
        if (it->done >= q->count) {
            answer(h, it);
            finish(h, it);
            continue;
        }
        /* not done: back of the rotation, the next client's turn */
        if (w->tail) w->tail->next = it;
        else w->head = it;
        w->tail = it;
    }
    if (slices) srv_hub_wake_net(h);

}
